//! The owned element tree both stages share: an XML element with its attributes substituted ([`Elem`]),
//! where it starts ([`Loc`]), and Mitsuba's search path that was in force there ([`Resolver`]). Its own
//! file so that the reader (xml.rs), the upgrade of older files (upgrade.rs) and the typed properties
//! (properties.rs) all use it without using each other.

use std::fmt;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use anyhow::Result;

use crate::error::{truncated, Error};

/// Longest quotation of a value in a message.
pub(super) const QUOTED: usize = 60;

/// Longest message about an element, in characters: whatever a substituted value holds, an error stays
/// a line (at six levels of repeated `<default>`s one was 10 MB).
const MAX_MESSAGE: usize = 400;

/// Mitsuba's `FileResolver`: folders searched in order for a relative file name (src/core/fresolver.cpp).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Resolver(Rc<Vec<PathBuf>>);

impl Resolver {
    /// The search path of a file read on its own: its folder.
    pub(super) fn of_folder(dir: PathBuf) -> Resolver {
        Resolver(Rc::new(vec![dir]))
    }
}

impl Resolver {
    /// The first folder in which `name` exists, joined to it; an absolute name, or one found nowhere, as
    /// it is (Mitsuba's `resolve`), here joined to the first folder so that a message names a real place.
    pub(super) fn resolve(&self, name: &str) -> PathBuf {
        let p = Path::new(name);
        if p.is_absolute() {
            return p.to_path_buf();
        }
        self.0
            .iter()
            .map(|d| d.join(p))
            .find(|c| c.exists())
            .unwrap_or_else(|| self.0[0].join(p))
    }

    /// Whether `name` is found by the search path.
    pub(super) fn finds(&self, name: &str) -> bool {
        Path::new(name).is_absolute() || self.0.iter().any(|d| d.join(name).exists())
    }

    /// This search path with `dir` first.
    pub(super) fn prepend(&self, dir: PathBuf) -> Resolver {
        let mut dirs = vec![dir];
        dirs.extend(self.0.iter().cloned());
        Resolver(Rc::new(dirs))
    }
}

/// Where an element starts.
#[derive(Clone, Debug)]
pub(super) struct Loc {
    pub(super) file: Rc<str>,
    pub(super) line: u32,
    pub(super) col: u32,
    /// The search path in force where the element was read (a spectrum file resolves by it, as Mitsuba's
    /// parser resolves one while it reads).
    pub(super) resolver: Resolver,
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file, self.line, self.col)
    }
}

/// An XML element with its attributes substituted.
#[derive(Clone, Debug)]
pub(super) struct Elem {
    pub(super) tag: String,
    pub(super) attrs: Vec<(String, String)>,
    pub(super) children: Vec<Elem>,
    pub(super) loc: Loc,
}

impl Elem {
    pub(super) fn attr(&self, name: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| k == name).map(|(_, v)| v.as_str())
    }

    pub(super) fn kind(&self) -> &str {
        self.attr("type").unwrap_or("")
    }

    /// The element as messages name it: `<shape type="rectangle" id="floor">`, `<float name="fov">`.
    pub(super) fn what(&self) -> String {
        let mut s = format!("<{}", self.tag);
        for key in ["type", "id", "name"] {
            if let Some(v) = self.attr(key) {
                s += &format!(" {key}=\"{}\"", truncated(v, QUOTED));
            }
        }
        s + ">"
    }

    /// A located [`Error::Scene`] (inside anyhow; `Scene::load_with` takes it out): the element is its
    /// field.
    pub(super) fn err(&self, msg: impl fmt::Display) -> anyhow::Error {
        let Loc { file, line, col, .. } = &self.loc;
        anyhow::Error::from(Error::scene(
            file.to_string(),
            *line as usize,
            *col as usize,
            self.what(),
            truncated(&msg.to_string(), MAX_MESSAGE),
        ))
    }

    pub(super) fn warning(&self, msg: impl fmt::Display) -> String {
        format!(
            "{}: {}: {}",
            self.loc,
            self.what(),
            truncated(&msg.to_string(), MAX_MESSAGE)
        )
    }

    pub(super) fn required(&self, name: &str) -> Result<&str> {
        self.attr(name)
            .ok_or_else(|| self.err(format!("needs the attribute {name}")))
    }
}

//! ppm-vk's one error type, for the scene readers and the engine alike (the engine re-exports it).
//! Each case carries what an embedding program needs to act on it: a
//! scene error its file, line, column and field; a device limit what was too large and what to lower;
//! an I/O error its path. The `ppm-vk` binary wraps it in `anyhow` for its messages.
//!
//! A new error site builds its case with a constructor ([`Error::scene`], [`Error::limit`],
//! [`Error::io`], [`Error::device`]) rather than converting an `anyhow::Error` wholesale: there is no
//! `From<anyhow::Error>`, so a device failure never passes itself off as a scene error or the reverse.
//!
//! Every message is one line and complete in itself (`{}` says it all), so the underlying error is a
//! field (`error`) rather than a `source()`: a caller that prints the chain (anyhow's `{:#}`) would
//! otherwise print it twice.

use std::fmt;
use std::path::{Path, PathBuf};

/// `Result<T, ppm_vk_engine::Error>`.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A boxed error from below the engine (the Vulkan wrapper, the driver, an image codec).
pub type Source = Box<dyn std::error::Error + Send + Sync + 'static>;

#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A scene that cannot be rendered: malformed or out-of-range in its file (then `line` and
    /// `column`, 1-based, say where), or built in code and refused by [`crate::Scene::validate`] (then
    /// `file` is the scene's name and `line` and `column` are 0). `field` is the path of the field
    /// (`sphere[1].radius`, `materials.white.diffuse`; empty for the scene as a whole).
    #[error("{}", Located { file, line: *line, column: *column, field, message })]
    Scene {
        file: String,
        line: usize,
        column: usize,
        field: String,
        message: String,
    },

    /// A render setting out of its range (`field` names it, as in the engine's `Settings`).
    #[error("settings: {field}: {message}")]
    Settings { field: &'static str, message: String },

    /// Something this device cannot hold or run: `what` needs `value` (unknown when the device only
    /// reports that a limit was reached) where the device allows `limit`; `lower` says what to lower.
    #[error("{what}: {} than this device's limit of {limit}; lower {lower}", match value {
        Some(v) => format!("needs {v}, more"),
        None => "reached no more".to_string(),
    })]
    Limit {
        what: String,
        value: Option<u64>,
        limit: u64,
        lower: String,
    },

    /// A Vulkan or driver failure while `context`; `error` is the wrapper's own error (the message
    /// shows its whole chain on one line).
    #[error("{context}: {}", chain(error.as_ref()))]
    Device { context: String, error: Source },

    /// A file that could not be read or written, or whose content could not be decoded (an EXR, a
    /// report): the decoder's message is then an `InvalidData` error.
    #[error("{}: {error}", path.display())]
    Io { path: PathBuf, error: std::io::Error },

    /// A checkpoint that cannot be resumed: damaged, or of another scene, setting or build (`message`
    /// says which).
    #[error("{message}")]
    Checkpoint { message: String },

    /// The engine's `Renderer::pass` saw its `CancelToken` set and stopped between dispatches; the
    /// renderer keeps the passes completed before it.
    #[error("cancelled")]
    Cancelled,
}

impl Error {
    /// A located scene error: `file:line:column: field: message` (line and column 1-based; 0 when the
    /// scene has no file, see [`Error::Scene`]).
    pub fn scene(
        file: impl Into<String>,
        line: usize,
        column: usize,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> Error {
        Error::Scene {
            file: file.into(),
            line,
            column,
            field: field.into(),
            message: message.into(),
        }
    }

    /// A device limit: `what` needs `value` where the device allows `limit`; `lower` is the advice.
    pub fn limit(what: impl Into<String>, value: Option<u64>, limit: u64, lower: impl Into<String>) -> Error {
        Error::Limit {
            what: what.into(),
            value,
            limit,
            lower: lower.into(),
        }
    }

    /// An I/O failure on `path`.
    pub fn io(path: impl AsRef<Path>, source: std::io::Error) -> Error {
        Error::Io {
            path: path.as_ref().to_path_buf(),
            error: source,
        }
    }

    /// A file whose content could not be decoded (`source`: the decoder's error).
    pub fn decode(path: impl AsRef<Path>, source: impl Into<Source>) -> Error {
        Error::io(
            path,
            std::io::Error::new(std::io::ErrorKind::InvalidData, source.into()),
        )
    }

    /// A device failure while `context`; for `map_err`: `.map_err(Error::device("reading the image"))`.
    pub fn device<E: Into<Source>>(context: impl Into<String>) -> impl FnOnce(E) -> Error {
        let context = context.into();
        move |e| Error::Device {
            context,
            error: e.into(),
        }
    }
}

/// `file:line:column: field: message`, leaving out what is unknown.
struct Located<'a> {
    file: &'a str,
    line: usize,
    column: usize,
    field: &'a str,
    message: &'a str,
}

impl fmt::Display for Located<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            0 if self.file.is_empty() => {}
            0 => write!(f, "scene {}: ", self.file)?,
            _ => write!(f, "{}:{}:{}: ", self.file, self.line, self.column)?,
        }
        if !self.field.is_empty() {
            write!(f, "{}: ", self.field)?;
        }
        write!(f, "{}", self.message)
    }
}

/// An error and its causes on one line, `a: b: c` (as anyhow's `{:#}`).
fn chain(e: &(dyn std::error::Error + 'static)) -> String {
    let mut s = e.to_string();
    let mut next = e.source();
    while let Some(c) = next {
        s.push_str(": ");
        s.push_str(&c.to_string());
        next = c.source();
    }
    s
}

/// A vector as messages show it: `[x, y, z]`.
pub(crate) fn fmt_vec(v: [f32; 3]) -> String {
    // Very large and very small numbers in exponent form: 1e30 written out is 31 digits.
    let f = |x: f32| match x.abs() {
        a if a != 0.0 && !(1e-6..1e9).contains(&a) => format!("{x:e}"),
        _ => format!("{x}"),
    };
    format!("[{}, {}, {}]", f(v[0]), f(v[1]), f(v[2]))
}

/// `text` cut to at most `max` characters, `...` marking a cut: quoted values stay short in messages
/// whatever a file holds.
pub(crate) fn truncated(text: &str, max: usize) -> String {
    match text.char_indices().nth(max) {
        Some((at, _)) => format!("{}...", &text[..at]),
        None => text.to_string(),
    }
}

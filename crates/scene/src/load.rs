//! Reading a scene: the file's format chooses the reader (Mitsuba XML for `.xml`, else TOML), and OBJ
//! meshes are imported into a scene built in code.

use std::path::Path;

use crate::error::{Error, Result};
use crate::files::{read_bounded, MAX_SCENE_BYTES};
use crate::model::{Scene, MAX_TRIANGLES};
use crate::obj::{self, ObjImport};
use crate::{mitsuba, toml};

impl Scene {
    /// Reads and parses a scene file: Mitsuba 3 XML for a `.xml` file (see `docs/mitsuba.md`), else
    /// the TOML format. A file that cannot be read is [`Error::Io`]; anything wrong in it is
    /// [`Error::Scene`] with its line, column and field. Mesh files are found relative to the scene
    /// file's directory.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene> {
        Scene::load_with(path, &[])
    }

    /// [`Scene::load`] with `defines` (`name`, `value`) overriding a Mitsuba scene's `<default>`
    /// parameters, as Mitsuba's `-D name=value` (a name the scene never uses is an error). A TOML
    /// scene has no parameters: `defines` must be empty for it.
    pub fn load_with(path: impl AsRef<Path>, defines: &[(String, String)]) -> Result<Scene> {
        let path = path.as_ref();
        let shown = path.display().to_string();
        let is_xml = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("xml"));
        if is_xml {
            // The reader's located errors are `Error`s inside anyhow; anything else names the file.
            return mitsuba::load(path, defines).map_err(|e| match e.downcast::<Error>() {
                Ok(located) => located,
                Err(e) => Error::scene(shown, 0, 0, "", format!("{e:#}")),
            });
        }
        if let Some((name, value)) = defines.first() {
            let message = format!("-D {name}={value}: parameters are for Mitsuba scenes (.xml); a TOML scene has none");
            return Err(Error::scene(shown, 0, 0, "", message));
        }
        let text = read_bounded(path, MAX_SCENE_BYTES, "scene file")?;
        Scene::parse(&text, &path.display().to_string())
    }

    /// Parses scene text; `origin` (usually the file name) is the `file` of every error, and mesh files
    /// are found relative to its directory.
    pub fn parse(text: &str, origin: &str) -> Result<Scene> {
        toml::parse(text, origin)
    }

    /// Imports an OBJ file (and its MTL unless `import.material` is set) as a new mesh; returns its
    /// index in `meshes`. Its MTL materials are appended to `materials` (named `<path>:<MTL name>`),
    /// what was approximated to `warnings`. Call [`Scene::validate`] when the scene is complete. The
    /// error is [`Error::Scene`] with no file of its own: its message starts with the OBJ or MTL file
    /// and the line there.
    pub fn import_obj(&mut self, path: impl AsRef<Path>, import: &ObjImport) -> Result<usize> {
        obj::import(self, path.as_ref(), import, MAX_TRIANGLES, true)
            .map_err(|e| Error::scene("", 0, 0, "", format!("{e:#}")))
    }
}

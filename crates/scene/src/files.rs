//! Reading files within bounds: what a scene or mesh file may weigh, and the one reader that refuses a
//! device, a FIFO or a directory before reading a byte.

use std::path::Path;

use crate::error::{Error, Result};

/// Largest scene file read: 16 MiB, well above 2^16 shapes written out (about 6 MiB). Parsing allocates
/// in proportion to the text, so this bounds what a hostile file can make the parser take.
pub const MAX_SCENE_BYTES: u64 = 16 << 20;

/// Most bytes an OBJ file may have: 2 GiB, room for [`MAX_TRIANGLES`](crate::MAX_TRIANGLES) triangles written out.
pub const MAX_MESH_BYTES: u64 = 2 << 30;

/// Reads a regular file of at most `max` bytes as text; anything else (a device such as /dev/zero, a
/// directory, a larger file) is an error naming the path, before reading a byte.
pub(crate) fn read_bounded(path: &Path, max: u64, what: &str) -> Result<String> {
    let refuse = |kind: std::io::ErrorKind, why: String| Error::io(path, std::io::Error::new(kind, why));
    let cannot = |e: std::io::Error| refuse(e.kind(), format!("cannot read {what}: {e}"));
    let meta = std::fs::metadata(path).map_err(cannot)?;
    if !meta.is_file() {
        return Err(refuse(
            std::io::ErrorKind::InvalidInput,
            format!("cannot read {what}: not a regular file"),
        ));
    }
    if meta.len() > max {
        return Err(refuse(
            std::io::ErrorKind::InvalidData,
            format!("{} bytes, more than a {what} may have ({max})", meta.len()),
        ));
    }
    std::fs::read_to_string(path).map_err(cannot)
}

/// A fresh directory under the system temp dir for a test's files, removed on drop.
#[cfg(test)]
pub(crate) struct TempDir(pub std::path::PathBuf);

#[cfg(test)]
impl TempDir {
    pub fn new(tag: &str) -> TempDir {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static NEXT: AtomicUsize = AtomicUsize::new(0);
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("ppm-vk-{tag}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("creating a temp dir");
        TempDir(dir)
    }

    /// Writes `text` to `name` in the directory; returns its path.
    pub fn write(&self, name: &str, text: &str) -> std::path::PathBuf {
        let path = self.0.join(name);
        std::fs::write(&path, text).expect("writing a temp file");
        path
    }
}

#[cfg(test)]
impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

//! Reading files within bounds: what a scene or mesh file may weigh, and the one reader that refuses a
//! device, a FIFO or a directory before reading a byte.

use std::path::Path;

use crate::error::{Error, Result};

/// Largest scene file read: 16 MiB, well above 2^16 shapes written out (about 6 MiB). Parsing allocates
/// in proportion to the text, so this bounds what a hostile file can make the parser take.
pub const MAX_SCENE_BYTES: u64 = 16 << 20;

/// Most bytes an OBJ file may have: 2 GiB, room for [`MAX_TRIANGLES`](crate::MAX_TRIANGLES) triangles written out.
pub const MAX_MESH_BYTES: u64 = 2 << 30;

/// Most bytes a texture image may have: 2 GiB. An image within [`MAX_TEXTURE_PIXELS`](crate::texture::MAX_TEXTURE_PIXELS)
/// is at most 1 GiB uncompressed (2^26 pixels of four 32-bit floats); the decoder streams the file, so
/// this only refuses what cannot be an image we would read.
pub const MAX_IMAGE_BYTES: u64 = 2 << 30;

/// Opens a regular file of at most `max` bytes for reading and returns it with its length; anything else
/// (a FIFO, a device such as /dev/zero, a directory, a larger file) is an error naming the path, before
/// a byte is read. The open itself never blocks: it is non-blocking (a FIFO without a writer would
/// otherwise wait in `open` forever, where no signal ends it), and the type and size are then taken
/// from the open file, so a file swapped after a check cannot slip past it.
pub fn open_bounded(path: &Path, max: u64, what: &str) -> Result<(std::fs::File, u64)> {
    let refuse = |kind: std::io::ErrorKind, why: String| Error::io(path, std::io::Error::new(kind, why));
    let cannot = |e: std::io::Error| refuse(e.kind(), format!("cannot read {what}: {e}"));
    let not_regular = || {
        refuse(
            std::io::ErrorKind::InvalidInput,
            format!("cannot read {what}: not a regular file"),
        )
    };
    // The cheap refusal first: nothing is opened that is not a regular file now.
    if !std::fs::metadata(path).map_err(cannot)?.is_file() {
        return Err(not_regular());
    }
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt as _;
        // Regular files ignore O_NONBLOCK; a FIFO put in the file's place after the check does not.
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path).map_err(cannot)?;
    let meta = file.metadata().map_err(cannot)?;
    if !meta.is_file() {
        return Err(not_regular());
    }
    if meta.len() > max {
        return Err(refuse(
            std::io::ErrorKind::InvalidData,
            format!("{} bytes, more than a {what} may have ({max})", meta.len()),
        ));
    }
    Ok((file, meta.len()))
}

/// The bytes of a regular file of at most `max` bytes (see [`open_bounded`]); a file that grows while it
/// is read is cut at `max` + 1 bytes and refused.
pub fn read_bounded_bytes(path: &Path, max: u64, what: &str) -> Result<Vec<u8>> {
    use std::io::Read as _;
    let (file, len) = open_bounded(path, max, what)?;
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(max.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, std::io::Error::new(e.kind(), format!("cannot read {what}: {e}"))))?;
    if bytes.len() as u64 > max {
        let why = format!("it grew past {max} bytes while read, more than a {what} may have");
        return Err(Error::io(
            path,
            std::io::Error::new(std::io::ErrorKind::InvalidData, why),
        ));
    }
    Ok(bytes)
}

/// Reads a regular file of at most `max` bytes as text (see [`read_bounded_bytes`]).
pub(crate) fn read_bounded(path: &Path, max: u64, what: &str) -> Result<String> {
    let bytes = read_bounded_bytes(path, max, what)?;
    String::from_utf8(bytes).map_err(|e| {
        let why = format!(
            "cannot read {what}: not UTF-8 text (byte {})",
            e.utf8_error().valid_up_to()
        );
        Error::io(path, std::io::Error::new(std::io::ErrorKind::InvalidData, why))
    })
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

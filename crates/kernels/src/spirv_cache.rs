//! The SPIR-V of kernels compiled at run time (specialize.rs), kept on disk between runs, so a scene
//! rendered before does not wait for shaderc again (seconds per scene on a CPU: docs/performance.md,
//! "Set-up").
//!
//! One file per compiled kernel, `spirv/<key>.spv` in the context's cache directory, named by the SHA-256
//! of everything the compile reads ([`key`]): the kernel, the defines, the scene constants, every
//! embedded shader source and this build's own compiled kernels (which change with the compiler), and
//! the compile options' version. The file:
//!
//! | bytes | what                                              |
//! |-------|---------------------------------------------------|
//! | 8     | magic `PPMVKSPV`                                  |
//! | 32    | the key (as in the name: a file copied over another is refused) |
//! | 8     | length of the SPIR-V that follows, LE             |
//! | 32    | SHA-256 of that SPIR-V                            |
//! | ...   | the SPIR-V words, little-endian                   |
//!
//! A file that fails any check (short, padded, damaged, another compile's, not SPIR-V) is never used: the
//! kernel is compiled again and the file replaced. Writes go through a temporary file and a rename, so
//! concurrent runs leave whole files. Past [`MAX_FILES`] files the least recently used are deleted (a read
//! marks a file used).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use sha2::{Digest, Sha256};

use crate::reflected::{KernelInfo, ALL, SOURCES};

const MAGIC: &[u8; 8] = b"PPMVKSPV";
/// Compiled kernels kept: past this many files, the least recently used are deleted (a file is 15-60 KB,
/// so the folder stays under about 15 MB; a scene has at most four, so this is 64 scenes or more).
pub const MAX_FILES: usize = 256;
/// Bumped when the compile options in specialize.rs change (they are not in the key otherwise).
const OPTIONS_VERSION: &str = "ppm-vk spirv cache 1: vulkan1.2, performance";
const HEADER_LEN: usize = 8 + 32 + 8 + 32;
/// The first word of every SPIR-V module.
const SPIRV_MAGIC: u32 = 0x0723_0203;

/// The hash naming a compile: `kernel` with `defines` and `constants`, by this build's sources and
/// compiler.
pub fn key(kernel: &KernelInfo, defines: &[(&str, &str)], constants: &str) -> Key {
    let mut h = Sha256::new();
    // Each field with its length, so no two different inputs concatenate alike.
    let mut field = |bytes: &[u8]| {
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(bytes);
    };
    field(OPTIONS_VERSION.as_bytes());
    for (path, text) in SOURCES {
        field(path.as_bytes());
        field(text.as_bytes());
    }
    // The build-time SPIR-V: a different shaderc (or glslang inside it) compiles it differently.
    for k in ALL {
        field(k.spirv);
    }
    field(kernel.name.as_bytes());
    field(kernel.source.as_bytes());
    for (name, value) in defines {
        field(name.as_bytes());
        field(value.as_bytes());
    }
    field(constants.as_bytes());
    Key(h.finalize().into())
}

/// The SHA-256 naming one compile ([`key`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Key(pub [u8; 32]);

/// The file in `dir` that holds the compile named `key`.
pub fn file_in(dir: &Path, key: &Key) -> PathBuf {
    let hex: String = key.0.iter().map(|b| format!("{b:02x}")).collect();
    dir.join("spirv").join(format!("{hex}.spv"))
}

/// The SPIR-V words in a cache file's `bytes`, if the file is whole and holds the compile `key`; else why
/// not, in a few words.
pub fn unwrap(bytes: &[u8], key: &Key) -> Result<Vec<u32>, String> {
    if bytes.len() < HEADER_LEN || &bytes[..8] != MAGIC {
        return Err("not a ppm-vk SPIR-V cache file".into());
    }
    if bytes[8..40] != key.0 {
        return Err("holds another compile (its key differs)".into());
    }
    let len = u64::from_le_bytes(bytes[40..48].try_into().expect("8 bytes"));
    let data = &bytes[HEADER_LEN..];
    if data.len() as u64 != len {
        return Err(format!(
            "truncated or padded ({} bytes of SPIR-V, the header says {len})",
            data.len()
        ));
    }
    if Sha256::digest(data)[..] != bytes[48..80] {
        return Err("damaged (checksum mismatch)".into());
    }
    if data.len() < 20 || !data.len().is_multiple_of(4) {
        return Err(format!("{} bytes is not a SPIR-V module", data.len()));
    }
    let words: Vec<u32> = data
        .chunks_exact(4)
        .map(|w| u32::from_le_bytes(w.try_into().expect("4 bytes")))
        .collect();
    if words[0] != SPIRV_MAGIC {
        return Err("not SPIR-V (magic number)".into());
    }
    Ok(words)
}

/// A cache file holding `words`, the compile `key`.
pub fn wrap(words: &[u32], key: &Key) -> Vec<u8> {
    let data: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let mut out = Vec::with_capacity(HEADER_LEN + data.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&key.0);
    out.extend_from_slice(&(data.len() as u64).to_le_bytes());
    out.extend_from_slice(&Sha256::digest(&data));
    out.extend_from_slice(&data);
    out
}

/// The cached SPIR-V of the compile `key` in `dir`: `Ok(None)` when there is none, `Err` saying why a file
/// there was not used.
pub fn read(dir: &Path, key: &Key) -> Result<Option<Vec<u32>>, String> {
    let path = &file_in(dir, key);
    // Only a regular file is read: a FIFO put there would block the set-up for ever.
    match std::fs::metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(format!("{}: {e}", path.display())),
        Ok(m) if !m.is_file() => return Err(format!("{}: not a regular file", path.display())),
        Ok(_) => {}
    }
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let words = unwrap(&bytes, key).map_err(|why| format!("{}: {why}", path.display()))?;
    // Used now: the pruning keeps the recently used. Best effort (a read-only cache still serves).
    let _ = std::fs::File::options()
        .write(true)
        .open(path)
        .and_then(|f| f.set_modified(std::time::SystemTime::now()));
    Ok(Some(words))
}

/// Deletes the least recently used `.spv` files of `dir`'s cache beyond the newest `keep`; returns how many
/// it deleted. Files that vanish meanwhile (another run pruning) are no error.
pub fn prune(dir: &Path, keep: usize) -> Result<usize> {
    let folder = dir.join("spirv");
    let listing = std::fs::read_dir(&folder).with_context(|| format!("listing {}", folder.display()))?;
    let mut files: Vec<(std::time::SystemTime, PathBuf)> = listing
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "spv"))
        .filter_map(|p| Some((std::fs::metadata(&p).ok()?.modified().ok()?, p)))
        .collect();
    if files.len() <= keep {
        return Ok(0);
    }
    files.sort(); // oldest first
    let excess = files.len() - keep;
    for (_, path) in &files[..excess] {
        match std::fs::remove_file(path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(e).with_context(|| format!("deleting {}", path.display()))
            }
            _ => {}
        }
    }
    Ok(excess)
}

/// Writes `words`, the compile `key`, to its file in `dir` through a temporary file (named by this process
/// and thread, so concurrent writers do not share it) renamed into place.
pub fn write(dir: &Path, key: &Key, words: &[u32]) -> Result<()> {
    let path = &file_in(dir, key);
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let thread = format!("{:?}", std::thread::current().id());
    let tag: String = thread.chars().filter(char::is_ascii_digit).collect();
    let tmp = path.with_extension(format!("tmp.{}.{tag}", std::process::id()));
    let written = std::fs::File::create(&tmp)
        .and_then(|mut f| f.write_all(&wrap(words, key)))
        .and_then(|_| std::fs::rename(&tmp, path));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp); // best effort: the write's error is the one to report
    }
    written.with_context(|| format!("writing {} and renaming it into place", tmp.display()))?;
    prune(dir, MAX_FILES).map(|_| ())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words() -> Vec<u32> {
        vec![SPIRV_MAGIC, 0x0001_0500, 0, 42, 0, 7]
    }

    const KEY: Key = Key([7; 32]);

    #[test]
    fn a_wrapped_module_unwraps_to_its_words() {
        assert_eq!(unwrap(&wrap(&words(), &KEY), &KEY), Ok(words()));
    }

    #[test]
    fn damaged_files_are_refused_saying_why() {
        let file = wrap(&words(), &KEY);
        let refused = |bytes: &[u8], why: &str| {
            let e = unwrap(bytes, &KEY).expect_err(why);
            assert!(e.contains(why), "{e:?} does not say {why:?}");
        };
        refused(&[], "not a ppm-vk SPIR-V cache file");
        refused(&file[..HEADER_LEN - 1], "not a ppm-vk SPIR-V cache file");
        refused(&wrap(&words(), &Key([8; 32])), "another compile");
        refused(&file[..file.len() - 1], "truncated");
        refused(&[&file[..], &[0]].concat(), "padded");
        let mut flipped = file.clone();
        *flipped.last_mut().unwrap() ^= 1;
        refused(&flipped, "checksum");
        let mut not_spirv = words();
        not_spirv[0] = 0;
        refused(&wrap(&not_spirv, &KEY), "magic number");
        refused(&wrap(&words()[..3], &KEY), "not a SPIR-V module");
    }

    #[test]
    fn the_key_names_every_input() {
        let k = &crate::reflected::RAY;
        let base = key(k, &[("A", "1")], "const uint N = 1u;");
        assert_eq!(base, key(k, &[("A", "1")], "const uint N = 1u;"), "not deterministic");
        assert_ne!(
            base,
            key(&crate::reflected::PHOTON, &[("A", "1")], "const uint N = 1u;")
        );
        assert_ne!(base, key(k, &[("A", "0")], "const uint N = 1u;"));
        assert_ne!(base, key(k, &[], "const uint N = 1u;"));
        assert_ne!(base, key(k, &[("A", "1")], "const uint N = 2u;"));
        // A define's name and value run together differently.
        assert_ne!(key(k, &[("AB", "1")], ""), key(k, &[("A", "B1")], ""));
    }

    /// At MAX_FILES files nothing is deleted; one more deletes exactly the least recently used, and a
    /// file read is used (kept over older unread ones).
    #[test]
    fn the_folder_keeps_the_most_recently_used_max_files() {
        let dir = std::env::temp_dir().join(format!("ppm-vk-spirv-cache-prune-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let key = |i: usize| {
            let mut k = [0u8; 32];
            k[..8].copy_from_slice(&(i as u64).to_le_bytes());
            Key(k)
        };
        let base = std::time::SystemTime::UNIX_EPOCH + std::time::Duration::from_secs(1_700_000_000);
        let age = |i: usize, secs: u64| {
            let f = std::fs::File::options()
                .write(true)
                .open(file_in(&dir, &key(i)))
                .unwrap();
            f.set_modified(base + std::time::Duration::from_secs(secs)).unwrap();
        };
        for i in 0..MAX_FILES {
            write(&dir, &key(i), &words()).unwrap();
            age(i, i as u64); // file 0 the oldest
        }
        assert_eq!(prune(&dir, MAX_FILES).unwrap(), 0, "at the bound");
        assert_eq!(read(&dir, &key(0)), Ok(Some(words())), "reading marks file 0 used now");
        write(&dir, &key(MAX_FILES), &words()).unwrap(); // one over: prunes
        let count = std::fs::read_dir(dir.join("spirv")).unwrap().count();
        assert_eq!(count, MAX_FILES);
        assert_eq!(read(&dir, &key(1)), Ok(None), "the least recently used was kept");
        assert!(read(&dir, &key(0)).unwrap().is_some(), "the file just read was deleted");
        assert!(read(&dir, &key(MAX_FILES)).unwrap().is_some());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn reads_what_it_wrote_and_refuses_damaged_files() {
        let dir = std::env::temp_dir().join(format!("ppm-vk-spirv-cache-unit-{}", std::process::id()));
        assert_eq!(read(&dir, &KEY), Ok(None), "an absent file is no entry, not an error");
        write(&dir, &KEY, &words()).unwrap();
        assert_eq!(read(&dir, &KEY), Ok(Some(words())));
        let path = file_in(&dir, &KEY);
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() - 4]).unwrap();
        let e = read(&dir, &KEY).expect_err("a truncated file is used");
        assert!(
            e.contains("truncated") && e.contains(&path.display().to_string()),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

//! The pipeline cache kept on disk between runs, so a second run does not compile every kernel again.
//!
//! One file per device in the cache directory, `pipelines-<vendor>-<device>.bin`:
//!
//! | bytes | what                                                                  |
//! |-------|-----------------------------------------------------------------------|
//! | 8     | magic `PPMVKPC\0`                                                     |
//! | 4     | this wrapper's format version (1), little-endian                      |
//! | 4     | the driver version that wrote it (`VkPhysicalDeviceProperties`)       |
//! | 8     | length of the Vulkan data that follows                                |
//! | 4     | CRC-32 of that data                                                   |
//! | ...   | `vkGetPipelineCacheData`'s bytes, which start with Vulkan's own header |
//!
//! Vulkan's `VkPipelineCacheHeaderVersionOne` names the vendor, the device and the driver build
//! (`pipelineCacheUUID`); the wrapper adds the driver version and a length and checksum, because a driver
//! handed a truncated or damaged blob may crash rather than refuse it. A file that fails any check is
//! ignored (the context starts with an empty cache and says why in [`Context::pipeline_cache_note`]) and
//! replaced on the next save. Saves go through a temporary file and a rename, so concurrent runs leave
//! one whole file.
//!
//! [`Context::pipeline_cache_note`]: crate::Context::pipeline_cache_note

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{anyhow, Context as _, Result};
use ash::vk;

const MAGIC: &[u8; 8] = b"PPMVKPC\0";
const FORMAT: u32 = 1;
/// The wrapper's header: magic, format, driver version, data length, CRC.
const WRAPPER_LEN: usize = 8 + 4 + 4 + 8 + 4;
/// `VkPipelineCacheHeaderVersionOne`: header size, header version, vendor id, device id, cache UUID.
const VK_HEADER_LEN: usize = 4 + 4 + 4 + 4 + vk::UUID_SIZE;

/// What a cache file must match to be used: the device and the driver build that wrote it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct CacheKey {
    pub vendor_id: u32,
    pub device_id: u32,
    pub driver_version: u32,
    pub uuid: [u8; vk::UUID_SIZE],
}

impl CacheKey {
    pub fn of(props: &vk::PhysicalDeviceProperties) -> CacheKey {
        CacheKey {
            vendor_id: props.vendor_id,
            device_id: props.device_id,
            driver_version: props.driver_version,
            uuid: props.pipeline_cache_uuid,
        }
    }

    /// The file in `dir` that holds this device's cache.
    pub fn file_in(&self, dir: &Path) -> PathBuf {
        dir.join(format!("pipelines-{:04x}-{:04x}.bin", self.vendor_id, self.device_id))
    }
}

fn u32_at(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"))
}

/// The Vulkan data inside a cache file's `bytes`, if the file is whole and was written for `key`; else
/// why not, in a few words.
pub(crate) fn unwrap<'a>(bytes: &'a [u8], key: &CacheKey) -> Result<&'a [u8], String> {
    if bytes.len() < WRAPPER_LEN || &bytes[..8] != MAGIC {
        return Err("not a ppm-vk pipeline cache".into());
    }
    if u32_at(bytes, 8) != FORMAT {
        return Err(format!("format {} (this build reads {FORMAT})", u32_at(bytes, 8)));
    }
    if u32_at(bytes, 12) != key.driver_version {
        return Err("written by another driver version".into());
    }
    let len = u64::from_le_bytes(bytes[16..24].try_into().expect("8 bytes"));
    let data = &bytes[WRAPPER_LEN..];
    if data.len() as u64 != len {
        return Err(format!(
            "truncated or padded ({} bytes of data, the header says {len})",
            data.len()
        ));
    }
    if crc32fast::hash(data) != u32_at(bytes, 24) {
        return Err("damaged (checksum mismatch)".into());
    }
    // Vulkan's header, read as the spec lays it out (little-endian on every platform ppm-vk runs on).
    if data.len() < VK_HEADER_LEN {
        return Err("too short for Vulkan's header".into());
    }
    let header_size = u32_at(data, 0) as usize;
    if header_size < VK_HEADER_LEN || header_size > data.len() {
        return Err(format!("Vulkan header size {header_size} is invalid"));
    }
    if u32_at(data, 4) != vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32 {
        return Err(format!("Vulkan header version {}", u32_at(data, 4)));
    }
    if (u32_at(data, 8), u32_at(data, 12)) != (key.vendor_id, key.device_id) {
        return Err("written for another device".into());
    }
    if data[16..VK_HEADER_LEN] != key.uuid {
        return Err("written by another driver build (pipelineCacheUUID differs)".into());
    }
    Ok(data)
}

/// A cache file holding Vulkan's `data` for `key`.
pub(crate) fn wrap(data: &[u8], key: &CacheKey) -> Vec<u8> {
    let mut out = Vec::with_capacity(WRAPPER_LEN + data.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT.to_le_bytes());
    out.extend_from_slice(&key.driver_version.to_le_bytes());
    out.extend_from_slice(&(data.len() as u64).to_le_bytes());
    out.extend_from_slice(&crc32fast::hash(data).to_le_bytes());
    out.extend_from_slice(data);
    out
}

/// A device's pipeline cache and the file it came from and goes back to.
pub(crate) struct DiskCache {
    pub raw: vk::PipelineCache,
    path: PathBuf,
    key: CacheKey,
    /// CRC of the data as last read or written: a save with nothing new writes nothing.
    saved_crc: Mutex<Option<u32>>,
    /// Why the file was not used, when it existed and was not.
    pub note: Option<String>,
    /// Bytes of Vulkan data the cache was seeded with (0: none, or the file was not used).
    pub loaded: usize,
}

impl DiskCache {
    /// Creates the pipeline cache, seeded from `dir`'s file for this device when that file checks out.
    pub fn open(device: &ash::Device, dir: &Path, key: CacheKey) -> Result<DiskCache> {
        let path = key.file_in(dir);
        // Only a regular file is read: a FIFO put there would block the start for ever.
        let regular = std::fs::metadata(&path).map(|m| m.is_file());
        let read = match regular {
            Ok(false) => Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "not a regular file",
            )),
            _ => std::fs::read(&path),
        };
        let (initial, note) = match read {
            Ok(bytes) => match unwrap(&bytes, &key) {
                Ok(data) => (data.to_vec(), None),
                Err(why) => (
                    Vec::new(),
                    Some(format!("pipeline cache {} ignored: {why}", path.display())),
                ),
            },
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => (Vec::new(), None),
            Err(e) => (
                Vec::new(),
                Some(format!("pipeline cache {} ignored: {e}", path.display())),
            ),
        };
        let info = vk::PipelineCacheCreateInfo::default().initial_data(&initial);
        let raw = unsafe { device.create_pipeline_cache(&info, None) }.context("creating the pipeline cache")?;
        let saved_crc = Mutex::new((!initial.is_empty()).then(|| crc32fast::hash(&initial)));
        Ok(DiskCache {
            raw,
            path,
            key,
            saved_crc,
            note,
            loaded: initial.len(),
        })
    }

    /// Writes the cache back if it holds anything new; returns the file written, if any.
    pub fn save(&self, device: &ash::Device) -> Result<Option<&Path>> {
        let data = unsafe { device.get_pipeline_cache_data(self.raw) }.context("reading the pipeline cache")?;
        let crc = crc32fast::hash(&data);
        let mut saved = self
            .saved_crc
            .lock()
            .map_err(|_| anyhow!("pipeline cache lock poisoned"))?;
        if data.is_empty() || *saved == Some(crc) {
            return Ok(None);
        }
        write_replacing(&self.path, &wrap(&data, &self.key))
            .with_context(|| format!("saving the pipeline cache to {}", self.path.display()))?;
        *saved = Some(crc);
        Ok(Some(&self.path))
    }
}

/// Writes `bytes` to a temporary file beside `path` (named by this process, so concurrent runs do not
/// share it) and renames it over `path`.
fn write_replacing(path: &Path, bytes: &[u8]) -> Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let tmp = path.with_extension(format!("tmp.{}", std::process::id()));
    let written = std::fs::File::create(&tmp)
        .and_then(|mut f| f.write_all(bytes).and_then(|_| f.sync_all()))
        .and_then(|_| std::fs::rename(&tmp, path));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp); // best effort: the write's error is the one to report
    }
    written.with_context(|| format!("writing {} and renaming it into place", tmp.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key() -> CacheKey {
        CacheKey {
            vendor_id: 0x10005,
            device_id: 0,
            driver_version: 42,
            uuid: *b"0123456789abcdef",
        }
    }

    /// Vulkan data as a driver would write it for `key`: its header, then a payload.
    fn vulkan_data(key: &CacheKey, payload: &[u8]) -> Vec<u8> {
        let mut d = Vec::new();
        d.extend_from_slice(&(VK_HEADER_LEN as u32).to_le_bytes());
        d.extend_from_slice(&(vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32).to_le_bytes());
        d.extend_from_slice(&key.vendor_id.to_le_bytes());
        d.extend_from_slice(&key.device_id.to_le_bytes());
        d.extend_from_slice(&key.uuid);
        d.extend_from_slice(payload);
        d
    }

    #[test]
    fn a_wrapped_cache_unwraps_to_its_data() {
        let data = vulkan_data(&key(), b"compiled kernels");
        assert_eq!(unwrap(&wrap(&data, &key()), &key()), Ok(&data[..]));
    }

    #[test]
    fn damaged_or_foreign_files_are_refused_saying_why() {
        let k = key();
        let file = wrap(&vulkan_data(&k, b"compiled kernels"), &k);
        let refused = |bytes: &[u8], key: &CacheKey, why: &str| {
            let e = unwrap(bytes, key).expect_err(why);
            assert!(e.contains(why), "{e:?} does not say {why:?}");
        };
        refused(&[], &k, "not a ppm-vk pipeline cache");
        refused(&file[..WRAPPER_LEN - 1], &k, "not a ppm-vk pipeline cache");
        refused(&file[..file.len() - 1], &k, "truncated");
        let mut flipped = file.clone();
        *flipped.last_mut().unwrap() ^= 1;
        refused(&flipped, &k, "checksum");
        refused(
            &file,
            &CacheKey {
                driver_version: 43,
                ..k
            },
            "driver version",
        );
        refused(&file, &CacheKey { device_id: 1, ..k }, "another device");
        refused(&file, &CacheKey { uuid: [0; 16], ..k }, "pipelineCacheUUID");
        // A whole wrapper around a bad Vulkan header (as a buggy writer might leave).
        let mut bad = vulkan_data(&k, b"");
        bad[0] = 8;
        refused(&wrap(&bad, &k), &k, "header size");
        refused(&wrap(b"short", &k), &k, "too short");
    }
}

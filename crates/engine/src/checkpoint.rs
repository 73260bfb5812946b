//! Checkpoints: the whole state of a progressive render, so a render of hours survives the process.
//!
//! A file is `MAGIC`, the format version (u32 LE), the header's length (u32 LE), the header as JSON
//! ([`Header`]: build, scene, settings, counters), the raw device buffers it lists, in order, and the
//! SHA-256 of all the bytes before it, header included. It is written through a temporary file and a
//! rename, so it is either the old checkpoint or the new one. A reader checks the magic bytes, the
//! header and the length the header gives before it reads the buffers: a device file or a FIFO is
//! refused before it is opened for reading, a file of another length before it is read.
//! [`Renderer::checkpoint`](crate::Renderer::checkpoint) takes one and
//! [`Renderer::resume`](crate::Renderer::resume) continues from it, bit for bit as if never stopped.

use std::path::Path;

use anyhow::{bail, ensure, Context as _, Result};
use ppm_vk_kernels::layout::{HitPoint, HitStats, PathCounters};
use serde::{Deserialize, Serialize};
use sha2::Digest;

use crate::scene::Scene;
use crate::settings::Settings;
use crate::stats::ProbeReport;

const MAGIC: &[u8; 8] = b"PPMVKCKP";
/// Raised whenever the layout of the file or of a buffer in it changes.
pub const FORMAT: u32 = 3;
/// A header is a few KiB; anything larger is not a checkpoint.
const MAX_HEADER: u32 = 1 << 20;
/// Bytes of the file's checksum, after the buffers.
const TRAILER: usize = 32;
/// Most passes a checkpoint may count: eye passes index their random streams by the pass as a u32.
pub const MAX_PASSES: u64 = u32::MAX as u64;

/// What a checkpoint is of, and the renderer's counters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// The build that wrote it (the binary's git revision): kernels of another build may differ.
    pub build: String,
    pub scene_name: String,
    /// [`Scene::content_sha256`] of the scene as rendered (resolution included).
    pub scene_sha256: String,
    pub settings: Settings,
    /// Photon passes done and photons emitted: the random streams continue from these.
    pub passes: u64,
    pub emitted: u64,
    /// Photons per batch (halved on overflow; results do not depend on it, time does).
    pub batch: u32,
    /// The photon grid's cell edge for the next pass (`Renderer::fit_grid`; results do not depend on it).
    pub grid_cell: f32,
    pub probe: Option<ProbeReport>,
    /// Bytes of each buffer after the header, in the order of [`Checkpoint`]'s fields.
    pub sections: Vec<u64>,
}

/// A render's state: the header and the device buffers that carry it from pass to pass.
#[derive(Clone, Debug, PartialEq)]
pub struct Checkpoint {
    pub header: Header,
    /// Per hit point: N, R^2, tau and the probe's lambda / r^2.
    pub stats: Vec<HitStats>,
    /// PPM's hit points (fixed for the render); empty for SPPM, which traces them anew every pass.
    pub hit_points: Vec<HitPoint>,
    /// Per pixel: the emission samples' sum and count.
    pub direct: Vec<[f64; 4]>,
    /// Per pixel: the pilot eye pass's mark.
    pub busy: Vec<u32>,
    pub cut: PathCounters,
}

impl Checkpoint {
    fn payload(&self) -> [&[u8]; 5] {
        [
            bytemuck::cast_slice(&self.stats),
            bytemuck::cast_slice(&self.hit_points),
            bytemuck::cast_slice(&self.direct),
            bytemuck::cast_slice(&self.busy),
            bytemuck::bytes_of(&self.cut),
        ]
    }

    /// Fills in the header's section sizes (called by `Renderer::checkpoint`).
    pub(crate) fn seal(mut self) -> Checkpoint {
        self.header.sections = self.payload().iter().map(|p| p.len() as u64).collect();
        self
    }

    /// Writes the checkpoint atomically (a temporary file in the same directory, then a rename).
    pub fn save(&self, path: &Path) -> Result<()> {
        let header = serde_json::to_vec(&self.header).context("encoding the checkpoint header")?;
        crate::image_io::write_atomically(path, "ckpt", |w| {
            use std::io::Write as _;
            let mut sha = sha2::Sha256::new();
            let prefix = [
                &MAGIC[..],
                &FORMAT.to_le_bytes(),
                &(header.len() as u32).to_le_bytes(),
                &header,
            ];
            for p in prefix.into_iter().chain(self.payload()) {
                w.write_all(p)?;
                sha.update(p);
            }
            w.write_all(&sha.finalize())?;
            Ok(())
        })
    }

    /// Reads a checkpoint, refusing another format version or a damaged file.
    pub fn load(path: &Path) -> Result<Checkpoint> {
        Checkpoint::read(path, None).with_context(|| format!("checkpoint {}", path.display()))
    }

    /// [`Checkpoint::load`] for a render of `scene` with `settings` by `build`: the header is checked
    /// against them ([`Checkpoint::check`]) and its buffers' sizes against the render's, before the
    /// buffers are read.
    pub fn load_for(path: &Path, scene: &Scene, settings: &Settings, build: &str) -> Result<Checkpoint> {
        Checkpoint::read(path, Some((scene, settings, build)))
            .with_context(|| format!("cannot resume from {}", path.display()))
    }

    fn read(path: &Path, render: Option<(&Scene, &Settings, &str)>) -> Result<Checkpoint> {
        use std::io::Read as _;
        // A regular file only, opened without blocking: a FIFO would wait in open() for a writer.
        let (file, len) = ppm_vk_scene::open_bounded(path, u64::MAX, "checkpoint")?;
        let mut file = std::io::BufReader::new(file);
        let mut prefix = vec![0u8; 16];
        ensure!(len >= 16, "not a ppm-vk checkpoint ({len} bytes)");
        file.read_exact(&mut prefix).context("reading the checkpoint")?;
        let header_len = check_prefix(&prefix, len)?;
        prefix.resize(16 + header_len, 0);
        file.read_exact(&mut prefix[16..]).context("reading the checkpoint")?;
        let header = parse_header(&prefix)?;
        header.check_counters()?;
        if let Some((scene, settings, build)) = render {
            header.check(scene, settings, build)?;
            header.check_sections(scene)?;
        }
        // The length the header gives, before the rest is read: what is read is what it says.
        let total = expected_len(&header, header_len)?;
        ensure!(
            total == len,
            "{len} bytes, the header lists {total} (truncated or damaged)"
        );
        let mut bytes = prefix;
        bytes.reserve_exact((len as usize).saturating_sub(bytes.len()));
        file.take(len - bytes.len() as u64)
            .read_to_end(&mut bytes)
            .context("reading the checkpoint")?;
        Checkpoint::parse(&bytes)
    }

    fn parse(bytes: &[u8]) -> Result<Checkpoint> {
        let len = check_prefix(bytes, bytes.len() as u64)?;
        let header = parse_header(&bytes[..(16 + len).min(bytes.len())])?;
        let total = expected_len(&header, len)?;
        ensure!(
            total == bytes.len() as u64,
            "{} bytes, the header lists {total} (truncated?)",
            bytes.len()
        );
        let (body, trailer) = bytes.split_at(bytes.len() - TRAILER);
        ensure!(
            sha2::Sha256::digest(body)[..] == trailer[..],
            "the file does not match its checksum (damaged or edited)"
        );
        header.check_counters()?;
        let mut rest = &body[16 + len..];
        let mut take = |n: u64| {
            let (a, b) = rest.split_at(n as usize);
            rest = b;
            a
        };
        // pod_collect_to_vec copies, so the file's bytes need no alignment.
        let stats = section(take(header.sections[0]), "hit statistics")?;
        let hit_points = section(take(header.sections[1]), "hit points")?;
        let direct = section(take(header.sections[2]), "direct emission")?;
        let busy = section(take(header.sections[3]), "pilot marks")?;
        let cut: Vec<PathCounters> = section(take(header.sections[4]), "path counters")?;
        ensure!(cut.len() == 1, "path counters: {} entries, expected 1", cut.len());
        let c = Checkpoint {
            header,
            stats,
            hit_points,
            direct,
            busy,
            cut: cut[0],
        };
        Ok(c)
    }

    /// Fails, saying what differs, unless this checkpoint is of `scene` rendered with `settings` by the
    /// build `build`.
    pub fn check(&self, scene: &Scene, settings: &Settings, build: &str) -> Result<()> {
        self.header.check(scene, settings, build)
    }
}

/// The header's length, after checking the magic bytes and the format version in the first 16 bytes of
/// a file of `len` bytes.
fn check_prefix(bytes: &[u8], len: u64) -> Result<usize> {
    ensure!(bytes.len() >= 16 && &bytes[..8] == MAGIC, "not a ppm-vk checkpoint");
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    let format = word(8);
    ensure!(
        format == FORMAT,
        "format version {format}, this build reads version {FORMAT}"
    );
    let header = word(12);
    ensure!(
        header <= MAX_HEADER && 16 + header as u64 + TRAILER as u64 <= len,
        "truncated header ({header} bytes)"
    );
    Ok(header as usize)
}

/// The header in `bytes` (the file's first 16 + its length); its counters are not checked yet.
fn parse_header(bytes: &[u8]) -> Result<Header> {
    let header: Header = serde_json::from_slice(&bytes[16..]).context("parsing the header")?;
    ensure!(
        header.sections.len() == 5,
        "{} sections, expected 5",
        header.sections.len()
    );
    Ok(header)
}

/// The file's length as `header` (of `header_len` bytes) gives it.
fn expected_len(header: &Header, header_len: usize) -> Result<u64> {
    let sizes = header.sections.iter().try_fold(0u64, |sum, &n| sum.checked_add(n));
    sizes
        .and_then(|n| n.checked_add((16 + header_len + TRAILER) as u64))
        .ok_or_else(|| anyhow::anyhow!("buffer sizes {:?} overflow", header.sections))
}

impl Header {
    /// The counters within what a render of its settings can reach: passes at most [`MAX_PASSES`],
    /// photons emitted the passes times the photons per pass, a batch within a pass, a usable grid cell.
    fn check_counters(&self) -> Result<()> {
        self.settings.validate().context("its settings")?;
        let per_pass = self.settings.photons_per_pass as u64;
        ensure!(
            self.passes <= MAX_PASSES,
            "passes {} is more than a render may have ({MAX_PASSES})",
            self.passes
        );
        ensure!(
            self.passes.checked_mul(per_pass) == Some(self.emitted),
            "emitted {} photons in {} passes of {per_pass}: the counters disagree",
            self.emitted,
            self.passes
        );
        ensure!(
            (1..=per_pass).contains(&(self.batch as u64)),
            "batch {} is outside 1..={per_pass} (the photons per pass)",
            self.batch
        );
        ensure!(
            self.grid_cell.is_finite() && self.grid_cell > 0.0,
            "grid cell {} is not a positive size",
            self.grid_cell
        );
        Ok(())
    }

    /// The buffers' sizes are those a render of `scene` with these settings has.
    fn check_sections(&self, scene: &Scene) -> Result<()> {
        let pixels = scene.camera.width as u64 * scene.camera.height as u64;
        let slots = pixels * self.settings.slots(scene) as u64;
        let ppm_hits = match self.settings.mode {
            crate::settings::Mode::Ppm => slots,
            crate::settings::Mode::Sppm => 0,
        };
        let size = |n: u64, one: usize| n * one as u64;
        let want = [
            size(slots, std::mem::size_of::<HitStats>()),
            size(ppm_hits, std::mem::size_of::<HitPoint>()),
            size(pixels, std::mem::size_of::<[f64; 4]>()),
            size(pixels, std::mem::size_of::<u32>()),
            size(1, std::mem::size_of::<PathCounters>()),
        ];
        ensure!(
            self.sections == want,
            "its buffers are {:?} bytes, a render of {}x{} pixels has {want:?}",
            self.sections,
            scene.camera.width,
            scene.camera.height
        );
        Ok(())
    }

    /// Fails, saying what differs, unless this header is of `scene` rendered with `settings` by `build`.
    fn check(&self, scene: &Scene, settings: &Settings, build: &str) -> Result<()> {
        let h = self;
        if h.build != build {
            bail!(
                "it was written by build {}, this is build {build}: resume it with that build",
                h.build
            );
        }
        let sha = scene.content_sha256();
        if h.scene_sha256 != sha {
            bail!(
                "it is of another scene: {} (content sha256 {}), this render is of {} at {}x{} (sha256 {sha})",
                h.scene_name,
                h.scene_sha256,
                scene.name,
                scene.camera.width,
                scene.camera.height
            );
        }
        if &h.settings != settings {
            let diff = settings_diff(&h.settings, settings, "in the checkpoint", "now")?;
            bail!("it was rendered with other settings ({})", diff.join("; "));
        }
        Ok(())
    }
}

/// The settings that differ between `a` and `b`, each as `name: value <a_is>, value <b_is>`.
pub(crate) fn settings_diff(a: &Settings, b: &Settings, a_is: &str, b_is: &str) -> Result<Vec<String>> {
    let (a, b) = (serde_json::to_value(a)?, serde_json::to_value(b)?);
    Ok(match (a, b) {
        (serde_json::Value::Object(a), serde_json::Value::Object(b)) => a
            .iter()
            .filter(|(k, v)| b.get(*k) != Some(v))
            .map(|(k, v)| {
                format!(
                    "{k}: {} {a_is}, {} {b_is}",
                    show(v),
                    b.get(k).map_or("none".into(), show)
                )
            })
            .collect(),
        _ => vec![],
    })
}

/// A setting's value as the user wrote it: the settings' floats are f32, which JSON values widen.
fn show(v: &serde_json::Value) -> String {
    match v.as_f64() {
        Some(x) if v.is_f64() => format!("{}", x as f32),
        _ => v.to_string(),
    }
}

/// One buffer of the file as `T`s; its size must be a whole number of them.
pub(crate) fn section<T: bytemuck::Pod>(bytes: &[u8], what: &str) -> Result<Vec<T>> {
    let size = std::mem::size_of::<T>();
    // is_multiple_of is Rust 1.87, newer than the workspace's rust-version
    ensure!(
        bytes.len().is_multiple_of(size),
        "{what}: {} bytes, not a multiple of {size}",
        bytes.len()
    );
    Ok(bytemuck::pod_collect_to_vec(bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Checkpoint {
        Checkpoint {
            header: Header {
                build: "b1".into(),
                scene_name: "s".into(),
                scene_sha256: "00".into(),
                settings: Settings::default(),
                passes: 3,
                emitted: 3_000_000,
                batch: 100,
                grid_cell: 0.25,
                probe: None,
                sections: vec![],
            },
            stats: vec![
                HitStats {
                    n: 1.5,
                    r2: 0.01,
                    tau_r: 2.0,
                    ..Default::default()
                };
                3
            ],
            hit_points: vec![],
            direct: vec![[1.0, 2.0, 3.0, 4.0]; 2],
            busy: vec![1, 0],
            cut: PathCounters {
                photon_paths: 7,
                ..Default::default()
            },
        }
        .seal()
    }

    /// `name`: one file per test, as tests run in parallel.
    fn bytes(c: &Checkpoint, name: &str) -> Vec<u8> {
        let dir = std::env::temp_dir().join(format!("ppm-vk-ckpt-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        c.save(&path).unwrap();
        std::fs::read(&path).unwrap()
    }

    #[test]
    fn round_trip_is_exact() {
        let c = sample();
        assert_eq!(Checkpoint::parse(&bytes(&c, "round-trip.ckpt")).unwrap(), c);
    }

    #[test]
    fn damaged_files_are_refused_with_the_reason() {
        let good = bytes(&sample(), "damaged.ckpt");
        let err = |b: &[u8]| format!("{:#}", Checkpoint::parse(b).unwrap_err());
        assert!(err(&good[..good.len() - 1]).contains("truncated"));
        assert!(err(b"PNG\x89 not at all").contains("not a ppm-vk checkpoint"));
        let mut v1 = good.clone();
        v1[8] = 1;
        assert!(err(&v1).contains("format version 1"), "{}", err(&v1));
        let mut flipped = good.clone();
        *flipped.last_mut().unwrap() ^= 1;
        assert!(err(&flipped).contains("checksum"));
        let mut huge = good.clone();
        huge[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(err(&huge).contains("truncated header"));
        // The header is under the checksum: passes edited from 3 to 4 is a damaged file.
        let at = good.windows(9).position(|w| w == b"passes\":3").unwrap();
        let mut edited = good.clone();
        edited[at + 8] = b'4';
        assert!(err(&edited).contains("checksum"), "{}", err(&edited));
    }

    /// Counters a render of the header's settings cannot reach are refused even under a good checksum.
    #[test]
    fn counters_are_checked_against_the_settings() {
        let err = |edit: fn(&mut Header), name: &str| {
            let mut c = sample();
            edit(&mut c.header);
            format!("{:#}", Checkpoint::parse(&bytes(&c, name)).unwrap_err())
        };
        let e = err(|h| h.passes = u64::MAX, "passes.ckpt");
        assert!(e.contains("passes 18446744073709551615 is more than"), "{e}");
        let e = err(|h| h.emitted += 1, "emitted.ckpt");
        assert!(e.contains("the counters disagree"), "{e}");
        let e = err(|h| h.batch = 0, "batch.ckpt");
        assert!(e.contains("batch 0 is outside"), "{e}");
        let e = err(|h| h.grid_cell = -1.0, "cell.ckpt");
        assert!(e.contains("grid cell -1 is not a positive size"), "{e}");
    }

    /// `load` refuses a FIFO (without blocking on it) and a device file, and a file whose length is not
    /// the header's, before reading the buffers.
    #[test]
    fn only_a_regular_file_of_the_stated_length_is_read() {
        let e = format!("{:#}", Checkpoint::load(Path::new("/dev/zero")).unwrap_err());
        assert!(e.contains("not a regular file"), "{e}");
        let dir = std::env::temp_dir().join(format!("ppm-vk-ckpt-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("long.ckpt");
        let mut good = bytes(&sample(), "long.ckpt");
        good.extend_from_slice(&[0; 100]);
        std::fs::write(&path, &good).unwrap();
        let e = format!("{:#}", Checkpoint::load(&path).unwrap_err());
        assert!(e.contains("the header lists"), "{e}");
    }
}

//! Checkpoints: the whole state of a progressive render, so a render of hours survives the process.
//!
//! A file is `MAGIC`, the format version (u32 LE), the header's length (u32 LE), the header as JSON
//! ([`Header`]: build, scene, settings, counters) and the raw device buffers it lists, in order. It is
//! written through a temporary file and a rename, so it is either the old checkpoint or the new one.
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
pub const FORMAT: u32 = 1;
/// A header is a few KiB; anything larger is not a checkpoint.
const MAX_HEADER: u32 = 1 << 20;

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
    /// SHA-256 of those bytes, so a damaged file is refused rather than resumed.
    pub payload_sha256: String,
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

    /// Fills in the header's section sizes and checksum (called by `Renderer::checkpoint`).
    pub(crate) fn seal(mut self) -> Checkpoint {
        let payload = self.payload();
        let (sections, sha) = (payload.iter().map(|p| p.len() as u64).collect(), sha256(&payload));
        (self.header.sections, self.header.payload_sha256) = (sections, sha);
        self
    }

    /// Writes the checkpoint atomically (a temporary file in the same directory, then a rename).
    pub fn save(&self, path: &Path) -> Result<()> {
        let header = serde_json::to_vec(&self.header).context("encoding the checkpoint header")?;
        crate::image_io::write_atomically(path, "ckpt", |w| {
            use std::io::Write as _;
            w.write_all(MAGIC)?;
            w.write_all(&FORMAT.to_le_bytes())?;
            w.write_all(&(header.len() as u32).to_le_bytes())?;
            w.write_all(&header)?;
            for p in self.payload() {
                w.write_all(p)?;
            }
            Ok(())
        })
    }

    /// Reads a checkpoint, refusing another format version or a damaged file.
    pub fn load(path: &Path) -> Result<Checkpoint> {
        let bytes = std::fs::read(path).with_context(|| format!("reading checkpoint {}", path.display()))?;
        Checkpoint::parse(&bytes).with_context(|| format!("checkpoint {}", path.display()))
    }

    fn parse(bytes: &[u8]) -> Result<Checkpoint> {
        ensure!(bytes.len() >= 16 && &bytes[..8] == MAGIC, "not a ppm-vk checkpoint");
        let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
        let format = word(8);
        ensure!(
            format == FORMAT,
            "format version {format}, this build reads version {FORMAT}"
        );
        let len = word(12);
        ensure!(
            len <= MAX_HEADER && 16 + len as usize <= bytes.len(),
            "truncated header ({len} bytes)"
        );
        let header: Header = serde_json::from_slice(&bytes[16..16 + len as usize]).context("parsing the header")?;
        let mut rest = &bytes[16 + len as usize..];
        ensure!(
            header.sections.len() == 5,
            "{} sections, expected 5",
            header.sections.len()
        );
        let total = header.sections.iter().try_fold(0u64, |sum, &n| sum.checked_add(n));
        ensure!(
            total == Some(rest.len() as u64),
            "{} bytes of buffers, the header lists {:?} (truncated?)",
            rest.len(),
            header.sections
        );
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
        ensure!(
            sha256(&c.payload()) == c.header.payload_sha256,
            "the buffers do not match their checksum (damaged file)"
        );
        Ok(c)
    }

    /// Fails, saying what differs, unless this checkpoint is of `scene` rendered with `settings` by the
    /// build `build`.
    pub fn check(&self, scene: &Scene, settings: &Settings, build: &str) -> Result<()> {
        let h = &self.header;
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
            let (a, b) = (serde_json::to_value(&h.settings)?, serde_json::to_value(settings)?);
            let diff: Vec<String> = match (a, b) {
                (serde_json::Value::Object(a), serde_json::Value::Object(b)) => a
                    .iter()
                    .filter(|(k, v)| b.get(*k) != Some(v))
                    .map(|(k, v)| {
                        format!(
                            "{k}: {} in the checkpoint, {} now",
                            show(v),
                            b.get(k).map_or("none".into(), show)
                        )
                    })
                    .collect(),
                _ => vec![],
            };
            bail!("it was rendered with other settings ({})", diff.join("; "));
        }
        Ok(())
    }
}

/// A setting's value as the user wrote it: the settings' floats are f32, which JSON values widen.
fn show(v: &serde_json::Value) -> String {
    match v.as_f64() {
        Some(x) if v.is_f64() => format!("{}", x as f32),
        _ => v.to_string(),
    }
}

/// One buffer of the file as `T`s; its size must be a whole number of them.
fn section<T: bytemuck::Pod>(bytes: &[u8], what: &str) -> Result<Vec<T>> {
    let size = std::mem::size_of::<T>();
    // is_multiple_of is Rust 1.87, newer than the workspace's rust-version
    ensure!(
        bytes.len().is_multiple_of(size),
        "{what}: {} bytes, not a multiple of {size}",
        bytes.len()
    );
    Ok(bytemuck::pod_collect_to_vec(bytes))
}

fn sha256(parts: &[&[u8]]) -> String {
    let mut h = sha2::Sha256::new();
    for p in parts {
        h.update(p);
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
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
                emitted: 300,
                batch: 100,
                grid_cell: 0.25,
                probe: None,
                sections: vec![],
                payload_sha256: String::new(),
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
        let mut v2 = good.clone();
        v2[8] = 2;
        assert!(err(&v2).contains("format version 2"), "{}", err(&v2));
        let mut flipped = good.clone();
        *flipped.last_mut().unwrap() ^= 1;
        assert!(err(&flipped).contains("checksum"));
        let mut huge = good.clone();
        huge[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(err(&huge).contains("truncated header"));
    }
}

//! One image from many machines: workers that never talk to each other each render a [`Part`] of the same
//! render, and [`merge`] combines any set of parts into the image one machine would have made.
//!
//! Two methods ([`Method`]):
//! - [`Method::Probabilistic`], probabilistic PPM (Knaus and Zwicker 2011): pass `i` (from 0) searches
//!   with the fixed radius `R_i^2 = R_0^2 prod_{j=1..i} (j + alpha) / (j + 1)` (their eq. 17, squared
//!   radii) and is an estimate of its own; the image is the mean of the passes' estimates. Worker `k` of
//!   `n` renders passes `k, k + n, k + 2n, ...` with the random streams those passes have in a render of
//!   all of them, so `n` workers of `p` passes each give, merged, one worker's `n p` passes bit for bit.
//! - [`Method::Independent`]: worker `k` renders an ordinary progressive render (the settings' mode) with
//!   its own seed; the merge averages the images. Each part's radii shrank over its own passes only.
//!
//! A part holds per pixel the sums the merge needs in fixed point ([`FIXED_ONE`] units per unit of
//! radiance, in i128), so sums are exact and the merge is the same in any order. The file is the
//! checkpoint's framing ([`crate::checkpoint`]): magic bytes, format version, a JSON header (what the part
//! is of: build, scene hash, settings, method, worker k of n, passes), the sums, and the SHA-256 of all
//! the bytes before it. The merge refuses parts of another scene, settings, build, method, worker count or
//! pass count, and a worker given twice, saying which.
//!
//! ```no_run
//! # fn main() -> anyhow::Result<()> {
//! use ppm_vk_engine::distributed::{merge, render_part, Job, Method};
//! use ppm_vk_engine::{open_device, ContextOptions, Scene, Settings};
//! let ctx = open_device(&ContextOptions::default())?;
//! let scene = Scene::load("scenes/cornell-spheres.toml")?;
//! let settings = Settings::default();
//! let mut parts = Vec::new();
//! for worker in 0..2 {
//!     // On a farm each worker runs on its own machine and saves its part (`Part::save`).
//!     let job = Job { method: Method::Probabilistic, worker, of: 2, passes: 10 };
//!     parts.push(render_part(&ctx, &scene, &settings, &job, "my-build", None, |_| {})?);
//! }
//! let (image, info) = merge(&parts)?;
//! image.save("cornell.exr")?;
//! println!("{} passes from {} workers", info.passes, info.workers.len());
//! # Ok(())
//! # }
//! ```

use std::path::Path;

use anyhow::{bail, ensure, Context as _};
use serde::{Deserialize, Serialize};
use sha2::Digest;

use crate::checkpoint::{section, settings_diff, MAX_PASSES};
use crate::error::{Error, Result};
use crate::image_io::RgbImage;
use crate::scene::Scene;
use crate::settings::Settings;
use crate::stats::PassStats;
use crate::{CancelToken, Context, Renderer};

const MAGIC: &[u8; 8] = b"PPMVKPRT";
/// Raised whenever the layout of a part file changes.
pub const FORMAT: u32 = 1;
/// A header is a few KiB; anything larger is not a part.
const MAX_HEADER: u32 = 1 << 20;
/// Bytes of the file's checksum, after the sums.
const TRAILER: usize = 32;
/// Most workers one render may be split between.
pub const MAX_WORKERS: u32 = 1 << 16;
/// Fixed-point units per unit of radiance in a part's sums: 2^40 (radiance to within 1e-12).
pub const FIXED_ONE: f64 = (1u64 << 40) as f64;
/// Largest value one pass may give a pixel's sum (2^48, 2.8e14): far past any real scene's radiance, and
/// small enough that the sums of [`MAX_PASSES`] such passes stay within i128 with [`FIXED_ONE`]
/// (2^48 * 2^40 * 2^32 = 2^120).
pub const MAX_PIXEL_VALUE: f64 = 281_474_976_710_656.0;

/// How the workers split a render (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Probabilistic PPM: worker k renders passes k, k + n, ...; merged, one machine's image bit for bit.
    Probabilistic,
    /// Independent progressive renders with their own seeds, averaged.
    Independent,
}

/// One worker's share of a render: worker `worker` (from 0) of `of`, `passes` passes of its own.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Job {
    pub method: Method,
    pub worker: u32,
    pub of: u32,
    pub passes: u64,
}

impl Job {
    /// Workers in 1..=[`MAX_WORKERS`], this one among them, at least one pass, and all workers' passes
    /// within what a render may have ([`MAX_PASSES`]: the passes index the random streams as u32).
    pub fn validate(&self) -> Result<()> {
        let bad = |field: &'static str, message: String| Err(Error::Settings { field, message });
        if !(1..=MAX_WORKERS).contains(&self.of) {
            return bad(
                "of",
                format!("the workers must be in 1..={MAX_WORKERS}, got {}", self.of),
            );
        }
        if self.worker >= self.of {
            return bad(
                "worker",
                format!(
                    "worker {} of {}: workers count from 0 to {}",
                    self.worker,
                    self.of,
                    self.of - 1
                ),
            );
        }
        let total = (self.of as u64).checked_mul(self.passes);
        if self.passes == 0 || total.is_none_or(|t| t > MAX_PASSES) {
            return bad(
                "passes",
                format!(
                    "{} passes for each of {} workers: must be at least 1 and at most {MAX_PASSES} in all",
                    self.passes, self.of
                ),
            );
        }
        Ok(())
    }

    /// The passes of a whole render this worker renders, in order.
    pub fn pass_indices(&self) -> impl Iterator<Item = u64> + '_ {
        (0..self.passes).map(|j| j * self.of as u64 + self.worker as u64)
    }

    /// The seed of an independent worker's render: the settings' seed mixed with the worker's index, so
    /// workers (and the runs of nearby seeds) draw different streams.
    pub fn seed(&self, seed: u32) -> u32 {
        match self.method {
            Method::Probabilistic => seed,
            Method::Independent => seed ^ self.worker.wrapping_mul(0x9E37_79B9).rotate_left(16),
        }
    }
}

/// What a part is of, and which share of the render it holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartHeader {
    /// The build that wrote it (the binary's git revision): kernels of another build may differ.
    pub build: String,
    pub scene_name: String,
    /// [`Scene::content_sha256`] of the scene as rendered (resolution included).
    pub scene_sha256: String,
    pub width: u32,
    pub height: u32,
    /// The render's settings (an independent worker's seed is [`Job::seed`] of them).
    pub settings: Settings,
    pub job: Job,
    /// Bytes of each section after the header, in the order of [`Part`]'s fields.
    pub sections: Vec<u64>,
}

/// One worker's partial result: per pixel, sums in fixed point ([`FIXED_ONE`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    pub header: PartHeader,
    /// Probabilistic: the sum over this worker's passes of each pass's photon estimate. Independent: the
    /// worker's whole image.
    pub radiance: Vec<[i128; 3]>,
    /// Probabilistic: the emission samples' radiance summed over this worker's passes (eye paths that see
    /// lights directly or through specular chains); zero for independent parts.
    pub emission: Vec<[i128; 3]>,
    /// The count of those emission samples.
    pub samples: Vec<u64>,
}

/// What [`merge`] combined.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MergeInfo {
    pub scene_name: String,
    pub method: Method,
    /// Workers of the render.
    pub of: u32,
    /// The workers merged, in order, and those not given (a merge of some of them is an image of fewer
    /// passes, still unbiased in the same way).
    pub workers: Vec<u32>,
    pub missing: Vec<u32>,
    /// Photon passes in the merged image, and the photons they emitted.
    pub passes: u64,
    pub photons: u64,
}

/// Radiance `v` in fixed point; `what` names it in the error.
fn fixed(v: f64, what: impl FnOnce() -> String) -> anyhow::Result<i128> {
    ensure!(
        v.is_finite() && v.abs() < MAX_PIXEL_VALUE,
        "{}: {v} is not a finite radiance below {MAX_PIXEL_VALUE:e}",
        what()
    );
    Ok((v * FIXED_ONE).round() as i128)
}

fn add3(sum: &mut [i128; 3], v: [i128; 3]) -> anyhow::Result<()> {
    for (s, v) in sum.iter_mut().zip(v) {
        *s = s.checked_add(v).context("a pixel's sum overflows i128")?;
    }
    Ok(())
}

/// Renders worker `job.worker`'s share of `scene` with `settings` and returns its part; `build` names the
/// build (parts of other builds are refused by [`merge`]). `cancel`, when given, ends the pass in flight
/// ([`Error::Cancelled`]); `on_pass` sees each pass's statistics.
pub fn render_part(
    ctx: &Context,
    scene: &Scene,
    settings: &Settings,
    job: &Job,
    build: &str,
    cancel: Option<CancelToken>,
    mut on_pass: impl FnMut(&PassStats),
) -> Result<Part> {
    job.validate()?;
    let settings_used = Settings {
        seed: job.seed(settings.seed),
        ..settings.clone()
    };
    let mut renderer = Renderer::new(ctx, scene, settings_used)?;
    if let Some(c) = cancel {
        renderer.set_cancel(c);
    }
    let pixels = scene.camera.width as usize * scene.camera.height as usize;
    let mut radiance = vec![[0i128; 3]; pixels];
    let mut emission = vec![[0i128; 3]; pixels];
    let mut samples = vec![0u64; pixels];
    let sums = |e: anyhow::Error| Error::Device {
        context: "summing a pass's estimate".into(),
        error: e.into(),
    };
    match job.method {
        Method::Probabilistic => {
            let (start, pilot) = renderer.start_state()?;
            let alpha = settings.alpha as f64;
            // The schedule's product for pass `at`, multiplied in the same order whichever passes a worker
            // renders: the same f64 as a render of every pass.
            let (mut at, mut scale) = (0u64, 1.0f64);
            for index in job.pass_indices() {
                while at < index {
                    at += 1;
                    scale *= (at as f64 + alpha) / (at as f64 + 1.0);
                }
                let (stats, mut estimate) = renderer.probabilistic_pass(index, &start, scale)?;
                if index == 0 {
                    // The pilot eye pass's emission samples are pass 0's, as in a render.
                    for (d, p) in estimate.direct.iter_mut().zip(&pilot) {
                        for c in 0..4 {
                            d[c] += p[c];
                        }
                    }
                }
                let pixel = |i: usize| move || format!("pass {index}, pixel {i}");
                let mut add = || -> anyhow::Result<()> {
                    for i in 0..pixels {
                        let p = estimate.photons[i];
                        let d = estimate.direct[i];
                        add3(
                            &mut radiance[i],
                            [fixed(p[0], pixel(i))?, fixed(p[1], pixel(i))?, fixed(p[2], pixel(i))?],
                        )?;
                        add3(
                            &mut emission[i],
                            [fixed(d[0], pixel(i))?, fixed(d[1], pixel(i))?, fixed(d[2], pixel(i))?],
                        )?;
                        samples[i] += d[3] as u64;
                    }
                    Ok(())
                };
                add().map_err(sums)?;
                on_pass(&stats);
            }
        }
        Method::Independent => {
            for _ in 0..job.passes {
                on_pass(&renderer.pass()?);
            }
            let image = renderer.image()?;
            let mut add = || -> anyhow::Result<()> {
                for (i, (sum, px)) in radiance.iter_mut().zip(&image.pixels).enumerate() {
                    let what = || format!("pixel {i}");
                    *sum = [
                        fixed(px[0] as f64, what)?,
                        fixed(px[1] as f64, what)?,
                        fixed(px[2] as f64, what)?,
                    ];
                }
                Ok(())
            };
            add().map_err(sums)?;
        }
    }
    Ok(Part {
        header: PartHeader {
            build: build.into(),
            scene_name: scene.name.clone(),
            scene_sha256: scene.content_sha256(),
            width: scene.camera.width,
            height: scene.camera.height,
            settings: settings.clone(),
            job: *job,
            sections: vec![],
        },
        radiance,
        emission,
        samples,
    }
    .seal())
}

impl Part {
    fn payload(&self) -> [&[u8]; 3] {
        [
            bytemuck::cast_slice(&self.radiance),
            bytemuck::cast_slice(&self.emission),
            bytemuck::cast_slice(&self.samples),
        ]
    }

    /// Fills in the header's section sizes.
    fn seal(mut self) -> Part {
        self.header.sections = self.payload().iter().map(|p| p.len() as u64).collect();
        self
    }

    /// Writes the part atomically (a temporary file in the same directory, then a rename).
    pub fn save(&self, path: &Path) -> anyhow::Result<()> {
        crate::image_io::write_atomically(path, "part", |w| self.write_to(w))
    }

    /// The part as the bytes of its file (what [`Part::parse`] reads): for a part sent over a network
    /// rather than through a file.
    pub fn to_bytes(&self) -> anyhow::Result<Vec<u8>> {
        let mut bytes = Vec::new();
        self.write_to(&mut bytes)?;
        Ok(bytes)
    }

    fn write_to(&self, w: &mut impl std::io::Write) -> anyhow::Result<()> {
        let header = serde_json::to_vec(&self.header).context("encoding the part's header")?;
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
    }

    /// Reads a part, refusing another format version, a damaged or truncated file, or a header whose
    /// share or sizes no render has. Only a regular file is opened, and its length is checked against
    /// the header's before the sums are read.
    pub fn load(path: &Path) -> anyhow::Result<Part> {
        Part::read(path).with_context(|| format!("part {}", path.display()))
    }

    fn read(path: &Path) -> anyhow::Result<Part> {
        use std::io::Read as _;
        let (file, len) = ppm_vk_scene::open_bounded(path, u64::MAX, "a part")?;
        let mut file = std::io::BufReader::new(file);
        ensure!(len >= 16, "not a ppm-vk part ({len} bytes)");
        let mut prefix = vec![0u8; 16];
        file.read_exact(&mut prefix).context("reading the part")?;
        let header_len = check_prefix(&prefix, len)?;
        prefix.resize(16 + header_len, 0);
        file.read_exact(&mut prefix[16..]).context("reading the part")?;
        let header = parse_header(&prefix)?;
        let total = expected_len(&header, header_len)?;
        ensure!(
            total == len,
            "{len} bytes, the header lists {total} (truncated or damaged)"
        );
        let mut bytes = prefix;
        bytes.reserve_exact((len as usize).saturating_sub(bytes.len()));
        file.take(len - bytes.len() as u64)
            .read_to_end(&mut bytes)
            .context("reading the part")?;
        Part::parse(&bytes)
    }

    /// A part from a file's bytes (public for the hostile-input tests; [`Part::load`] reads a file).
    pub fn parse(bytes: &[u8]) -> anyhow::Result<Part> {
        let len = check_prefix(bytes, bytes.len() as u64)?;
        let header = parse_header(&bytes[..16 + len])?;
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
        let mut rest = &body[16 + len..];
        let mut take = |n: u64| {
            let (a, b) = rest.split_at(n as usize);
            rest = b;
            a
        };
        Ok(Part {
            radiance: section(take(header.sections[0]), "radiance sums")?,
            emission: section(take(header.sections[1]), "emission sums")?,
            samples: section(take(header.sections[2]), "emission sample counts")?,
            header,
        })
    }
}

/// The header's length, after checking the magic bytes and the format version in the first 16 bytes of
/// a file of `len` bytes.
fn check_prefix(bytes: &[u8], len: u64) -> anyhow::Result<usize> {
    ensure!(bytes.len() >= 16 && &bytes[..8] == MAGIC, "not a ppm-vk part");
    let word = |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
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

/// The header in `bytes` (the file's first 16 + its length), checked: a share of a render its settings
/// allow, an image size a scene may have, and the sections a part of that size has.
fn parse_header(bytes: &[u8]) -> anyhow::Result<PartHeader> {
    let h: PartHeader = serde_json::from_slice(&bytes[16..]).context("parsing the header")?;
    h.settings.validate().context("its settings")?;
    h.job.validate().context("its share of the render")?;
    let max = crate::scene::MAX_RESOLUTION;
    ensure!(
        (1..=max).contains(&h.width) && (1..=max).contains(&h.height),
        "image size {}x{}: each side must be in 1..={max}",
        h.width,
        h.height
    );
    let pixels = h.width as u64 * h.height as u64;
    let want = vec![pixels * 48, pixels * 48, pixels * 8];
    ensure!(
        h.sections == want,
        "its sections are {:?} bytes, a part of {}x{} pixels has {want:?}",
        h.sections,
        h.width,
        h.height
    );
    Ok(h)
}

/// The file's length as `header` (of `header_len` bytes) gives it (sizes already checked).
fn expected_len(header: &PartHeader, header_len: usize) -> anyhow::Result<u64> {
    let sizes: u64 = header.sections.iter().sum();
    Ok(sizes + (16 + header_len + TRAILER) as u64)
}

/// Merges parts of one render, in any order, into its image: for probabilistic parts, the mean of every
/// pass's photon estimate plus the emission samples' mean; for independent parts, the mean image.
/// Refuses, saying which, parts of different builds, scenes, settings, methods, worker counts or pass
/// counts, and a worker given twice. Missing workers are allowed (the image then has fewer passes) and
/// listed in [`MergeInfo::missing`].
pub fn merge(parts: &[Part]) -> anyhow::Result<(RgbImage, MergeInfo)> {
    let Some(first) = parts.first() else {
        bail!("no parts to merge");
    };
    let a = &first.header;
    let name = |h: &PartHeader| format!("worker {} of {}", h.job.worker, h.job.of);
    for p in &parts[1..] {
        let b = &p.header;
        let (x, y) = (name(a), name(b));
        if b.build != a.build {
            bail!(
                "{y}'s part was written by build {}, {x}'s by build {}: merge parts of one build",
                b.build,
                a.build
            );
        }
        if b.scene_sha256 != a.scene_sha256 {
            bail!(
                "{y}'s part is of another scene: {} at {}x{} (sha256 {}), {x}'s of {} at {}x{} (sha256 {})",
                b.scene_name,
                b.width,
                b.height,
                b.scene_sha256,
                a.scene_name,
                a.width,
                a.height,
                a.scene_sha256
            );
        }
        if b.settings != a.settings {
            let diff = settings_diff(&b.settings, &a.settings, &format!("for {y}"), &format!("for {x}"))?;
            bail!("{y}'s part was rendered with other settings ({})", diff.join("; "));
        }
        ensure!(
            b.job.method == a.job.method,
            "{y}'s part is of method {:?}, {x}'s of {:?}",
            b.job.method,
            a.job.method
        );
        ensure!(
            b.job.of == a.job.of,
            "{y}'s part is of a render split between {} workers, {x}'s between {}",
            b.job.of,
            a.job.of
        );
        ensure!(
            b.job.passes == a.job.passes,
            "{y}'s part has {} passes, {x}'s {}: every worker renders as many",
            b.job.passes,
            a.job.passes
        );
        // Sizes equal through the scene hash; checked all the same, as the sums are indexed by them.
        ensure!(
            (b.width, b.height) == (a.width, a.height),
            "{y}'s image size differs from {x}'s"
        );
    }
    let mut order: Vec<&Part> = parts.iter().collect();
    order.sort_by_key(|p| p.header.job.worker);
    if let Some(w) = order
        .windows(2)
        .find(|w| w[0].header.job.worker == w[1].header.job.worker)
    {
        bail!("worker {} of {} is given twice", w[0].header.job.worker, a.job.of);
    }
    let pixels = a.width as usize * a.height as usize;
    // `Part::load` checks these; a part built in code may not have come through it.
    for p in parts {
        ensure!(
            [p.radiance.len(), p.emission.len(), p.samples.len()] == [pixels; 3],
            "{}'s part does not hold {pixels} pixels of each sum",
            name(&p.header)
        );
    }
    let (mut radiance, mut emission, mut samples) =
        (vec![[0i128; 3]; pixels], vec![[0i128; 3]; pixels], vec![0u64; pixels]);
    for p in &order {
        for i in 0..pixels {
            add3(&mut radiance[i], p.radiance[i])?;
            add3(&mut emission[i], p.emission[i])?;
            samples[i] = samples[i]
                .checked_add(p.samples[i])
                .context("an emission sample count overflows")?;
        }
    }
    let workers: Vec<u32> = order.iter().map(|p| p.header.job.worker).collect();
    let passes = a.job.passes * parts.len() as u64;
    let divisor = match a.job.method {
        Method::Probabilistic => passes as f64,
        Method::Independent => parts.len() as f64,
    } * FIXED_ONE;
    let mut image = RgbImage::new(a.width, a.height);
    for (i, px) in image.pixels.iter_mut().enumerate() {
        let seen = FIXED_ONE * samples[i].max(1) as f64;
        for c in 0..3 {
            px[c] = (radiance[i][c] as f64 / divisor + emission[i][c] as f64 / seen) as f32;
        }
    }
    let info = MergeInfo {
        scene_name: a.scene_name.clone(),
        method: a.job.method,
        of: a.job.of,
        missing: (0..a.job.of).filter(|w| workers.binary_search(w).is_err()).collect(),
        workers,
        passes,
        photons: passes * a.settings.photons_per_pass as u64,
    };
    Ok((image, info))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2x1 part of worker `worker` of `of`, its sums distinct per worker.
    fn part(worker: u32, of: u32) -> Part {
        let w = worker as i128;
        Part {
            header: PartHeader {
                build: "b1".into(),
                scene_name: "s".into(),
                scene_sha256: "00".into(),
                width: 2,
                height: 1,
                settings: Settings::default(),
                job: Job {
                    method: Method::Probabilistic,
                    worker,
                    of,
                    passes: 3,
                },
                sections: vec![],
            },
            radiance: vec![[(1 + w) << 40, 2 << 40, 3], [4, 5 + w, 6]],
            emission: vec![[7 << 40, 0, 0], [0, 0, 1 << 40]],
            samples: vec![2, 0],
        }
        .seal()
    }

    /// A file's bytes with `header` (JSON as given) and `payload`, under a correct checksum: what a
    /// hostile writer would make.
    fn file(header: &[u8], payload: &[u8]) -> Vec<u8> {
        let mut bytes = [
            &MAGIC[..],
            &FORMAT.to_le_bytes(),
            &(header.len() as u32).to_le_bytes(),
            header,
            payload,
        ]
        .concat();
        let sha = sha2::Sha256::digest(&bytes);
        bytes.extend_from_slice(&sha);
        bytes
    }

    fn scratch(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("ppm-vk-part-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join(name)
    }

    #[test]
    fn round_trip_is_exact() {
        let p = part(1, 2);
        let path = scratch("round-trip.part");
        p.save(&path).unwrap();
        assert_eq!(Part::load(&path).unwrap(), p);
        let bytes = p.to_bytes().unwrap();
        assert_eq!(bytes, std::fs::read(&path).unwrap());
        assert_eq!(Part::parse(&bytes).unwrap(), p);
    }

    /// The merge divides the radiance sums by the passes and the emission sums by their samples, in any
    /// order of the parts.
    #[test]
    fn merge_is_the_mean_in_any_order() {
        let (a, b) = (part(0, 2), part(1, 2));
        let (image, info) = merge(&[b.clone(), a.clone()]).unwrap();
        assert_eq!(merge(&[a, b]).unwrap(), (image.clone(), info.clone()));
        assert_eq!((info.passes, info.workers, info.missing), (6, vec![0, 1], vec![]));
        // Pixel 0: radiance (1 + 2) / 6 passes, plus emission 14 / 4 samples.
        assert_eq!(image.pixels[0][0], (3.0 / 6.0 + 14.0 / 4.0) as f32);
        assert_eq!(image.pixels[0][1], (4.0 / 6.0) as f32);
        // Pixel 1: no samples, so the emission sum is divided by 1.
        assert_eq!(image.pixels[1][2], (12.0 / 6.0 / FIXED_ONE + 2.0) as f32);
        let (_, info) = merge(&[part(2, 4)]).unwrap();
        assert_eq!(info.missing, vec![0, 1, 3]);
    }

    #[test]
    fn mismatched_parts_are_refused_saying_which() {
        let err = |parts: &[Part]| format!("{:#}", merge(parts).unwrap_err());
        let a = part(0, 2);
        let edit = |f: fn(&mut PartHeader)| {
            let mut b = part(1, 2);
            f(&mut b.header);
            err(&[a.clone(), b])
        };
        let e = edit(|h| h.build = "b2".into());
        assert!(
            e.contains("worker 1 of 2's part was written by build b2, worker 0 of 2's by build b1"),
            "{e}"
        );
        let e = edit(|h| h.scene_sha256 = "11".into());
        assert!(e.contains("is of another scene"), "{e}");
        let e = edit(|h| h.settings.alpha = 0.5);
        assert!(
            e.contains("other settings (alpha: 0.5 for worker 1 of 2, 0.7 for worker 0 of 2)"),
            "{e}"
        );
        let e = edit(|h| h.job.method = Method::Independent);
        assert!(e.contains("is of method Independent"), "{e}");
        let e = edit(|h| h.job.passes = 4);
        assert!(e.contains("has 4 passes, worker 0 of 2's 3"), "{e}");
        let e = err(&[a.clone(), part(1, 3)]);
        assert!(e.contains("split between 3 workers, worker 0 of 2's between 2"), "{e}");
        let mut short = part(1, 2);
        short.samples.pop();
        let e = err(&[a.clone(), short]);
        assert!(
            e.contains("worker 1 of 2's part does not hold 2 pixels of each sum"),
            "{e}"
        );
        let e = err(&[a.clone(), part(1, 2), a.clone()]);
        assert!(e.contains("worker 0 of 2 is given twice"), "{e}");
        assert!(err(&[]).contains("no parts"));
    }

    #[test]
    fn damaged_files_are_refused_with_the_reason() {
        let path = scratch("damaged.part");
        part(0, 1).save(&path).unwrap();
        let good = std::fs::read(&path).unwrap();
        let err = |b: &[u8]| format!("{:#}", Part::parse(b).unwrap_err());
        // Every truncation is an error, never a panic.
        for n in 0..good.len() {
            let e = err(&good[..n]);
            assert!(
                e.contains("truncated") || e.contains("not a ppm-vk part"),
                "{n} bytes: {e}"
            );
        }
        assert!(err(b"PPMVKCKP a checkpoint, not a part").contains("not a ppm-vk part"));
        let mut v2 = good.clone();
        v2[8] = 2;
        assert!(err(&v2).contains("format version 2"));
        for at in [20, good.len() / 2, good.len() - 1] {
            let mut flipped = good.clone();
            flipped[at] ^= 1;
            let e = err(&flipped);
            assert!(
                e.contains("checksum") || e.contains("parsing the header"),
                "byte {at}: {e}"
            );
        }
        let e = format!("{:#}", Part::load(Path::new("/dev/zero")).unwrap_err());
        assert!(e.contains("not a regular file"), "{e}");
    }

    /// Headers under a correct checksum that no render writes: refused from the header alone, before any
    /// sum is read or allocated.
    #[test]
    fn hostile_headers_are_refused() {
        let good = part(0, 2).header;
        let with = |f: fn(&mut PartHeader)| {
            let mut h = good.clone();
            f(&mut h);
            let bytes = file(&serde_json::to_vec(&h).unwrap(), &[]);
            format!("{:#}", Part::parse(&bytes).unwrap_err())
        };
        let e = with(|h| h.job.worker = 2);
        assert!(e.contains("worker 2 of 2: workers count from 0 to 1"), "{e}");
        let e = with(|h| h.job.of = 0);
        assert!(e.contains("the workers must be in 1..=65536, got 0"), "{e}");
        let e = with(|h| h.width = u32::MAX);
        assert!(e.contains("image size 4294967295x1"), "{e}");
        let e = with(|h| h.sections = vec![u64::MAX, u64::MAX, 16]);
        assert!(e.contains("its sections are"), "{e}");
        let e = with(|h| h.settings.photons_per_pass = 0);
        assert!(e.contains("photons_per_pass"), "{e}");
        let e = with(|h| h.job.passes = 0);
        assert!(e.contains("must be at least 1"), "{e}");
        // A correct header whose sums are missing is a short file.
        let e = with(|_| ());
        assert!(e.contains("the header lists"), "{e}");
        let e = format!("{:#}", Part::parse(&file(b"{\"build\": [", &[])).unwrap_err());
        assert!(e.contains("parsing the header"), "{e}");
    }

    /// Every byte of a good header replaced by each of a few characters that change numbers, strings and
    /// structure, the checksum made right again: each file parses or is refused, never a panic, and what
    /// parses is a part whose sums fit its header.
    #[test]
    fn edited_headers_never_panic() {
        let p = part(1, 2);
        let header = serde_json::to_vec(&p.header).unwrap();
        let payload: Vec<u8> = p.payload().concat();
        let (mut parsed, mut refused) = (0, 0);
        for at in 0..header.len() {
            for c in *b"9-0\"{}e:," {
                let mut h = header.clone();
                h[at] = c;
                match Part::parse(&file(&h, &payload)) {
                    Ok(q) => {
                        let pixels = (q.header.width * q.header.height) as usize;
                        assert_eq!([q.radiance.len(), q.emission.len(), q.samples.len()], [pixels; 3]);
                        parsed += 1;
                    }
                    Err(_) => refused += 1,
                }
            }
        }
        // Both outcomes happen: the edits reach the checks, not only the JSON parser.
        assert!(parsed > 0 && refused > 0, "{parsed} parsed, {refused} refused");
    }

    #[test]
    fn job_limits_hold_at_their_bounds() {
        let job = |worker, of, passes| Job {
            method: Method::Probabilistic,
            worker,
            of,
            passes,
        };
        assert!(job(MAX_WORKERS - 1, MAX_WORKERS, 1).validate().is_ok());
        assert!(job(0, MAX_WORKERS + 1, 1).validate().is_err());
        assert!(job(0, 1, MAX_PASSES).validate().is_ok());
        assert!(job(0, 1, MAX_PASSES + 1).validate().is_err());
        assert!(job(0, 2, MAX_PASSES / 2 + 1).validate().is_err());
        assert!(job(0, MAX_WORKERS, u64::MAX).validate().is_err());
        let passes: Vec<u64> = job(1, 3, 4).pass_indices().collect();
        assert_eq!(passes, [1, 4, 7, 10]);
    }

    #[test]
    fn pixel_values_hold_at_their_bound() {
        let below = MAX_PIXEL_VALUE * (1.0 - f64::EPSILON);
        assert_eq!(fixed(below, String::new).unwrap(), (below * FIXED_ONE) as i128);
        let e = format!("{:#}", fixed(MAX_PIXEL_VALUE, || "pixel 3".into()).unwrap_err());
        assert!(e.contains("pixel 3: 281474976710656 is not a finite radiance"), "{e}");
        assert!(fixed(f64::NAN, String::new).is_err());
        // MAX_PASSES passes at the bound still sum within i128.
        let most = (MAX_PIXEL_VALUE * FIXED_ONE) as i128;
        assert!(most.checked_mul(MAX_PASSES as i128).is_some());
    }
}

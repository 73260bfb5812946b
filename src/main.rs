//! The `ppm-vk` command: render a scene, list devices, benchmark.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{bail, Context as _, Result};
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use ppm_vk_engine::metrics::{compare, Reference, Region};
use ppm_vk_engine::report::{PassRecord, RunHeader, RunReport, SCHEMA};
use ppm_vk_engine::{
    open_device, CancelToken, Checkpoint, Context, ContextOptions, Mode, PassStats, ProbeMode, Renderer, Scene,
    Settings,
};

mod bench;
mod check;
mod compare;
mod distributed;
mod plot;
mod view;

#[derive(Parser)]
#[command(name = "ppm-vk", version = concat!(env!("CARGO_PKG_VERSION"), " (", env!("PPM_VK_GIT_REV"), ")"))]
#[command(about = "Progressive photon mapping with photon probing and a cone filter, on Vulkan compute")]
#[command(propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene progressively and write the image.
    Render(RenderArgs),
    /// Show a scene in a window as it renders; move the camera with the mouse (needs a display).
    View(view::ViewArgs),
    /// List the Vulkan devices and whether each can run ppm-vk.
    Devices,
    /// Time each stage on a fixed set of cases; prints a table and writes JSON.
    Bench(bench::BenchArgs),
    /// Render variants for equal wall time each and score them against a reference.
    Compare(compare::CompareArgs),
    /// Read scene files as `render` would and say what each holds and approximated (no device needed).
    Check(check::CheckArgs),
    /// Merge the parts `render --worker K --of N` wrote into one image (docs/distributed.md).
    Merge(distributed::MergeArgs),
}

#[derive(Args, Clone)]
pub struct DeviceArgs {
    /// Device index or name substring (see `ppm-vk devices`); default: a discrete GPU, else an integrated
    /// one, else any (lavapipe).
    #[arg(long, env = "PPM_VK_DEVICE")]
    pub device: Option<String>,
    /// Enable the Vulkan validation layer and fail on any message it reports.
    #[arg(long)]
    pub validate: bool,
    /// Directory of the pipeline cache and of the SPIR-V of the kernels compiled for each scene, which
    /// spare a run compiling again the kernels an earlier run compiled [default: $XDG_CACHE_HOME/ppm-vk,
    /// else ~/.cache/ppm-vk].
    #[arg(long, value_name = "DIR", env = "PPM_VK_CACHE_DIR")]
    pub pipeline_cache: Option<PathBuf>,
    /// Keep no pipeline cache and no compiled SPIR-V: compile every kernel afresh (wins over
    /// --pipeline-cache).
    #[arg(long)]
    pub no_pipeline_cache: bool,
}

impl DeviceArgs {
    /// Opens the device, with the pipeline cache unless it is off; says so when a cache file was ignored.
    pub fn open(&self) -> Result<Context> {
        self.open_for(None)
    }

    /// [`DeviceArgs::open`], also for presenting to windows of `present`'s display.
    pub fn open_for(&self, present: Option<ppm_vk_engine::raw_window_handle::RawDisplayHandle>) -> Result<Context> {
        let pipeline_cache = match self.no_pipeline_cache {
            true => None,
            false => self
                .pipeline_cache
                .clone()
                .or_else(ContextOptions::default_pipeline_cache),
        };
        let ctx = open_device(&ContextOptions {
            validation: self.validate,
            device: self.device.clone(),
            pipeline_cache,
            present,
        })?;
        if let Some(note) = ctx.pipeline_cache_note() {
            eprintln!("note: {note}; it will be rewritten");
        }
        Ok(ctx)
    }
}

/// The set-up's stages, one line, then each kernel's compile and pipeline (`render --profile`, and `bench`
/// for each scene's first case).
fn print_setup(load_s: f64, t: &ppm_vk_engine::SetupTimes) {
    eprintln!(
        "set-up {:.2} s: scene read {load_s:.2}, lowered {:.2} (BVH {:.2}), GLSL {:.3}, kernels {:.2}, \
         buffers {:.2}, pilot eye pass {:.2}, probe {:.2}",
        load_s + t.total_s(),
        t.lower_s,
        t.bvh_s,
        t.glsl_s,
        t.kernels_s,
        t.buffers_s,
        t.start_s,
        t.probe_s
    );
    for k in &t.kernels {
        let source = match k.spirv_cached {
            None => "built in",
            Some(true) => "SPIR-V cached",
            Some(false) => "compiled",
        };
        eprintln!(
            "  kernel {:<20} {source:<13} compile {:.2} s, pipeline {:.2} s",
            k.name, k.compile_s, k.pipeline_s
        );
    }
}

/// Saves the pipeline cache now (the context saves it when dropped too, but silently): a failure is a
/// warning, never the run's error.
pub fn save_pipeline_cache(ctx: &Context) {
    if let Err(e) = ctx.save_pipeline_cache() {
        eprintln!("warning: {e:#}");
    }
}

/// The regions scored on their own against a reference.
#[derive(Args, Clone)]
pub struct RegionArgs {
    /// A region to score on its own against --reference, NAME:X0,Y0,W,H in the reference's pixels
    /// (origin top left); repeatable. Replaces the scene file's `[[region]]`s (see
    /// docs/scene-format.md), which are scored when none is given.
    #[arg(long = "region", value_parser = parse_region)]
    regions: Vec<Region>,
}

impl RegionArgs {
    /// `--region`s if any, else the scene's regions in the reference's pixels.
    pub fn resolve(&self, scene: &Scene, reference: &Reference) -> Vec<Region> {
        if !self.regions.is_empty() {
            return self.regions.clone();
        }
        let (w, h) = (reference.image.width, reference.image.height);
        scene.regions.iter().map(|r| r.pixels(w, h)).collect()
    }
}

/// How to render: the flags `render` and `view` share.
#[derive(Args, Clone)]
pub(crate) struct SettingsArgs {
    /// `sppm`: stochastic PPM, new hit points every pass at a random point of each pixel (anti-aliased, box
    /// filter; the lower error at equal time from 10 s on); `ppm`: hit points fixed at pixel centres.
    #[arg(long, value_enum, default_value_t = ModeArg::Sppm)]
    mode: ModeArg,
    /// Photons emitted per pass, at most 16777216 (2^24; more photons: more passes) [default: 1000000;
    /// `view`: 100000, so a frame comes every few tenths of a second on a CPU device].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=ppm_vk_engine::settings::MAX_PHOTONS_PER_PASS as i64))]
    photons_per_pass: Option<u32>,
    /// Fraction of new photons kept per pass (eq. 3, 6), in (0, 1).
    #[arg(long, default_value_t = 0.7, value_parser = parse_fraction)]
    alpha: f32,
    /// Seed of all random streams.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Starting search radius in scene units (default: the paper's eq. 8).
    #[arg(long, value_parser = parse_positive)]
    radius: Option<f32>,
    /// Override the scene's resolution, e.g. 256x256 (each side 1..=16384).
    #[arg(long, value_parser = parse_resolution)]
    resolution: Option<(u32, u32)>,
    /// Hit points per pixel in PPM (glass splits an eye path into both Fresnel branches up to this many).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=8))]
    hit_slots: u32,
    /// SPPM: the lobe directions (hit points) an eye path's first rough vertex splits it into, on rough
    /// glass and rough metal below --glossy-hits: the light seen through a glossy lobe gets this many
    /// samples a pass (1: one direction).
    #[arg(long, default_value_t = Settings::default().rough_splits, value_parser = clap::value_parser!(u32).range(1..=8))]
    rough_splits: u32,
    /// SPPM: the hit points an eye path may split into at smooth glass and thin panes, both Fresnel
    /// branches while it has slots (1: one branch drawn by Fresnel), in scenes without a rough split.
    #[arg(long, default_value_t = Settings::default().glass_splits, value_parser = clap::value_parser!(u32).range(1..=8))]
    glass_splits: u32,
    /// Eye paths per pixel and pass that only collect the emission seen directly or through mirrors and
    /// glass: the light's edges and its images converge this many times faster (0: the hit-point path's
    /// own sample only).
    #[arg(long, default_value_t = Settings::default().emission_samples,
          value_parser = clap::value_parser!(u32).range(0..=ppm_vk_engine::settings::MAX_EMISSION_SAMPLES as i64))]
    emission_samples: u32,
    /// Emission paths per pixel of the pilot eye pass, which only marks the pixels that take
    /// --emission-samples: fewer start the render sooner and miss more of a light's smallest images (their
    /// pixels then take --light-samples; no bias either way).
    #[arg(long, default_value_t = Settings::default().pilot_samples,
          value_parser = clap::value_parser!(u32).range(1..=ppm_vk_engine::settings::MAX_EMISSION_SAMPLES as i64))]
    pilot_samples: u32,
    /// Eye paths per pixel and pass where the pilot sampled through a rough lobe (rough metal, rough glass):
    /// the light such a vertex reflects is the noisiest term there (at least --emission-samples).
    #[arg(long, default_value_t = Settings::default().rough_samples,
          value_parser = clap::value_parser!(u32).range(0..=ppm_vk_engine::settings::MAX_EMISSION_SAMPLES as i64))]
    rough_samples: u32,
    /// Direct light: `sample` sends a shadow ray to a light at each emission sample's first diffuse point
    /// (light sampling; photons then leave no record where they first land), `photons` leaves it to the
    /// photons (the paper's estimator).
    #[arg(long, value_enum, default_value_t = DirectArg::Sample)]
    direct: DirectArg,
    /// With `--direct sample`: light-sampling paths per pixel and pass where the pilot saw no emitter
    /// (pixels that see one take --emission-samples).
    #[arg(long, default_value_t = Settings::default().light_samples,
          value_parser = clap::value_parser!(u32).range(1..=ppm_vk_engine::settings::MAX_EMISSION_SAMPLES as i64))]
    light_samples: u32,
    /// Glossy hit points: eye paths end with a hit point on rough conductors of at least this roughness
    /// (alpha), where the photons leave records and the gather evaluates the BRDF per photon; smoother
    /// ones, and rough glass, are sampled through. `off`: every rough lobe is sampled through
    /// (docs/accuracy.md compares the two).
    #[arg(long, value_name = "ALPHA", default_value = GLOSSY_DEFAULT, value_parser = parse_glossy)]
    glossy_hits: Glossy,
    /// The light rough surfaces that eye paths sample through reflect straight from a light: `mis` by a
    /// shadow ray and the lobe's direction weighed by multiple importance sampling, `bsdf` by the lobe's
    /// direction alone (points, spots and the sun still by shadow rays), `lights` by shadow rays alone
    /// (glowing spheres still by the lobe).
    #[arg(long, value_enum, default_value_t = GlossyLightArg::Mis)]
    glossy_light: GlossyLightArg,
    /// Photon probing (eq. 7-9): `off` starts every radius at eq. 8's r, `paper` is eq. 9 as printed,
    /// `scale-free` is r' = r (1 + lambda / r^2), `nearest` the radius that holds --probe-k probe photons
    /// (r' = r sqrt(k / N), at most 2 r), `curvature` (the default) the radius of least bias^2 + variance
    /// from the density and its curvature (r / 8 to --probe-grow times r; by default it only shrinks).
    #[arg(long, value_enum, default_value_t = ProbeArg::Curvature)]
    probe: ProbeArg,
    /// beta of eq. 9 as a fraction of r in (0, 1) (the paper's best: 0.2 = r/5).
    #[arg(long, default_value_t = 0.2, value_parser = parse_fraction)]
    beta: f32,
    /// Photons the probe pass emits (default: --photons-per-pass, as in the paper).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=ppm_vk_engine::settings::MAX_PHOTONS_PER_PASS as i64))]
    probe_photons: Option<u32>,
    /// With `--probe nearest`: the probe photons each starting radius is to hold (r' = r sqrt(k / N),
    /// at most 2 r), at least 1.
    #[arg(long, default_value_t = ppm_vk_engine::settings::DEFAULT_PROBE_K)]
    probe_k: f32,
    /// With `--probe curvature`: the most a starting radius may grow, r' / r in [1, 2] (1, the default: only
    /// shrink).
    #[arg(long, default_value_t = ppm_vk_engine::settings::DEFAULT_PROBE_GROW)]
    probe_grow: f32,
    /// The adaptive shrink after every pass: where the photons a hit point has gathered show a curvature
    /// beyond this many standard deviations of its noise (a narrow caustic, a sharp shadow), its radius
    /// shrinks to the one of least bias^2 + variance; 0 turns it off (eq. 3's shrink alone).
    #[arg(long, default_value_t = ppm_vk_engine::settings::DEFAULT_SHRINK_Z)]
    shrink_z: f32,
    /// The share of every area light's photons aimed at what casts caustics (the mirrors, glass and rough
    /// lobes sampled through), weighed so that the image stays unbiased; 0 (the default): none.
    #[arg(long, default_value_t = ppm_vk_engine::settings::DEFAULT_CAUSTIC_PHOTONS)]
    caustic_photons: f32,
    /// Cone filter (eq. 10-14): its constant k >= 1, or `off`.
    #[arg(long, default_value = "off", value_parser = parse_cone)]
    cone: Cone,
}

impl SettingsArgs {
    /// The settings these flags give, checked; `photons_per_pass` where --photons-per-pass is not given.
    pub fn settings(&self, photons_per_pass: u32) -> Result<Settings> {
        let settings = Settings {
            mode: self.mode.into(),
            photons_per_pass: self.photons_per_pass.unwrap_or(photons_per_pass),
            alpha: self.alpha,
            seed: self.seed,
            initial_radius: self.radius,
            hit_slots: self.hit_slots,
            rough_splits: self.rough_splits,
            glass_splits: self.glass_splits,
            probe: self.probe.into(),
            probe_beta: self.beta,
            probe_photons: self.probe_photons,
            probe_k: self.probe_k,
            probe_grow: self.probe_grow,
            shrink_z: self.shrink_z,
            caustic_photons: self.caustic_photons,
            cone_k: self.cone.0,
            emission_samples: self.emission_samples,
            pilot_samples: self.pilot_samples,
            rough_samples: self.rough_samples,
            direct: self.direct.into(),
            light_samples: self.light_samples,
            glossy_hits: self.glossy_hits.0,
            glossy_light: self.glossy_light.into(),
            ..Settings::default()
        };
        settings.validate()?;
        Ok(settings)
    }

    /// The scene file (with `-D` defines) at --resolution, if given.
    pub fn load_scene(&self, path: &std::path::Path, defines: &[(String, String)]) -> Result<Scene> {
        let scene = load_scene(path, defines)?;
        Ok(match self.resolution {
            Some((w, h)) => scene.with_resolution(w, h),
            None => scene,
        })
    }
}

#[derive(Args)]
struct RenderArgs {
    /// Scene file: TOML (see docs/scene-format.md) or Mitsuba 3 XML (.xml, see docs/mitsuba.md).
    scene: PathBuf,
    /// Override a Mitsuba scene's parameter: `-D name=value` sets what `$name` stands for (repeatable).
    #[arg(short = 'D', long = "define", value_name = "NAME=VALUE", value_parser = ppm_vk_engine::scene::parse_define)]
    pub defines: Vec<(String, String)>,
    /// Photon passes the render has when done (default 100 unless --time is given); a resumed render
    /// counts the passes of its checkpoint.
    #[arg(long, conflicts_with = "time", value_parser = clap::value_parser!(u64).range(1..))]
    passes: Option<u64>,
    /// Render for this many seconds instead of a pass count: the passes' wall time, set-up (kernel
    /// compilation, the BVH, the probe pass) excluded, as for `compare --time`. The last pass started in
    /// time finishes.
    #[arg(long, value_parser = parse_seconds)]
    time: Option<f64>,
    #[command(flatten)]
    settings: SettingsArgs,
    /// Output image: .exr (linear HDR) or .png (tone-mapped sRGB). Default: `<scene name>.exr` and a
    /// `<scene name>.png` preview in the working directory.
    #[arg(long, short)]
    out: Option<PathBuf>,
    /// Overwrite output images that already exist (without it, render refuses before it starts).
    #[arg(long, short)]
    force: bool,
    /// Print the per-pass stage timing table.
    #[arg(long)]
    profile: bool,
    /// Reference image (EXR) to measure error against at the end.
    #[arg(long)]
    reference: Option<PathBuf>,
    #[command(flatten)]
    regions: RegionArgs,
    /// Evaluate the error against --reference after every N passes (it reads the image back; the
    /// overhead is printed).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    error_every: u64,
    /// Write a run report: per pass wall time, GPU time per stage, photons, errors (.json or .csv).
    #[arg(long)]
    report: Option<PathBuf>,
    /// Write the per-pass stage timeline as a Chrome trace (opens in Perfetto or chrome://tracing).
    #[arg(long)]
    trace: Option<PathBuf>,
    /// Save the whole state of the render to FILE (at the end, when interrupted, and every
    /// --checkpoint-every seconds), so `--resume FILE` can continue it.
    #[arg(long, value_name = "FILE", value_parser = parse_checkpoint_path)]
    checkpoint: Option<PathBuf>,
    /// Also write the image (and the --checkpoint) every this many seconds while rendering [default:
    /// 300 with --checkpoint, else only at the end].
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
    checkpoint_every: Option<f64>,
    /// Continue the render saved in FILE by --checkpoint. Give the scene and settings it was made with (it
    /// refuses others, saying which); --passes counts its passes too.
    #[arg(long, value_name = "FILE")]
    resume: Option<PathBuf>,
    /// Render only worker K's share (K from 0) of a render split between --of N workers that never talk
    /// to each other, and write it as a part (--out, default `<scene name>.worker-K-of-N.part`) for
    /// `ppm-vk merge`; --passes counts this worker's passes (docs/distributed.md).
    #[arg(long, value_name = "K", requires = "of",
          conflicts_with_all = ["time", "checkpoint", "resume", "report", "trace", "reference"])]
    worker: Option<u32>,
    /// The number of workers the render is split between (with --worker).
    #[arg(long, value_name = "N", requires = "worker")]
    of: Option<u32>,
    /// With --worker: `probabilistic` (the default) renders passes K, K+N, ... of probabilistic PPM, which
    /// merge into one machine's image bit for bit; `independent` renders the mode's progressive render
    /// with the worker's own seed, and the merge averages the images.
    #[arg(long, value_enum, requires = "worker")]
    method: Option<distributed::MethodArg>,
    #[command(flatten)]
    device: DeviceArgs,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum ModeArg {
    Ppm,
    Sppm,
}

/// A value's name on the command line (kebab-case, as serde writes the engine's enums in JSON).
pub(crate) fn cli_name(v: impl clap::ValueEnum) -> String {
    v.to_possible_value()
        .map_or_else(String::new, |p| p.get_name().to_string())
}

impl From<ModeArg> for Mode {
    fn from(m: ModeArg) -> Mode {
        match m {
            ModeArg::Ppm => Mode::Ppm,
            ModeArg::Sppm => Mode::Sppm,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum GlossyLightArg {
    Mis,
    Bsdf,
    Lights,
}

impl From<GlossyLightArg> for ppm_vk_engine::GlossyLight {
    fn from(g: GlossyLightArg) -> ppm_vk_engine::GlossyLight {
        match g {
            GlossyLightArg::Mis => ppm_vk_engine::GlossyLight::Mis,
            GlossyLightArg::Bsdf => ppm_vk_engine::GlossyLight::Bsdf,
            GlossyLightArg::Lights => ppm_vk_engine::GlossyLight::Lights,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum DirectArg {
    Sample,
    Photons,
}

impl From<DirectArg> for ppm_vk_engine::DirectLight {
    fn from(d: DirectArg) -> ppm_vk_engine::DirectLight {
        match d {
            DirectArg::Sample => ppm_vk_engine::DirectLight::Sample,
            DirectArg::Photons => ppm_vk_engine::DirectLight::Photons,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum ProbeArg {
    Off,
    Paper,
    ScaleFree,
    Nearest,
    Curvature,
}

impl From<ProbeArg> for ProbeMode {
    fn from(p: ProbeArg) -> ProbeMode {
        match p {
            ProbeArg::Off => ProbeMode::Off,
            ProbeArg::Paper => ProbeMode::Paper,
            ProbeArg::ScaleFree => ProbeMode::ScaleFree,
            ProbeArg::Nearest => ProbeMode::Nearest,
            ProbeArg::Curvature => ProbeMode::Curvature,
        }
    }
}

/// A number that `ok` accepts; `range` says which in the error.
fn parse_in<T: std::str::FromStr + std::fmt::Display + Copy>(
    s: &str,
    ok: fn(T) -> bool,
    range: &str,
) -> Result<T, String>
where
    T::Err: std::fmt::Display,
{
    match s.parse::<T>() {
        Ok(v) if ok(v) => Ok(v),
        Ok(v) => Err(format!("must be {range}, got {v}")),
        Err(e) => Err(format!("{s:?}: {e}")),
    }
}

fn parse_seconds(s: &str) -> Result<f64, String> {
    parse_in(s, |t: f64| t.is_finite() && t > 0.0, "a positive number of seconds")
}

fn parse_fraction(s: &str) -> Result<f32, String> {
    parse_in(s, |f: f32| f > 0.0 && f < 1.0, "in (0, 1)")
}

/// `--glossy-hits`'s default, as `Settings::default().glossy_hits` has it.
const GLOSSY_DEFAULT: &str = "0.15";

/// `--glossy-hits`: a roughness, or `off`.
fn parse_glossy(s: &str) -> Result<Glossy, String> {
    if s.eq_ignore_ascii_case("off") {
        return Ok(Glossy(None));
    }
    parse_in(s, |f: f32| f.is_finite() && f >= 0.0, "finite and >= 0 (or `off`)").map(|a| Glossy(Some(a)))
}

/// What `--glossy-hits` gives: the least roughness of a glossy hit point, or none.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Glossy(Option<f32>);

fn parse_positive(s: &str) -> Result<f32, String> {
    parse_in(s, |f: f32| f.is_finite() && f > 0.0, "positive and finite")
}

/// `--checkpoint` took seconds before it took a file: a number is that old use, and says what replaced it.
fn parse_checkpoint_path(s: &str) -> Result<PathBuf, String> {
    if s.parse::<f64>().is_ok() {
        return Err(format!(
            "--checkpoint now names the file to save the render's state to; to write the image every {s} s, \
             use --checkpoint-every {s} (with --checkpoint FILE it saves the state too)"
        ));
    }
    Ok(PathBuf::from(s))
}

fn parse_region(s: &str) -> Result<Region, String> {
    let (name, rect) = s
        .split_once(':')
        .ok_or_else(|| format!("{s:?}: expected NAME:X0,Y0,W,H"))?;
    let v: Vec<u32> = rect
        .split(',')
        .map(|x| x.trim().parse::<u32>().map_err(|e| format!("{s:?}: {x:?}: {e}")))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [x0, y0, w, h] if w > 0 && h > 0 && !name.is_empty() => Ok(Region {
            name: name.to_string(),
            x0,
            y0,
            w,
            h,
        }),
        _ => Err(format!("{s:?}: expected NAME:X0,Y0,W,H with W, H > 0")),
    }
}

/// `--cone`: a filter constant, or none.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cone(pub(crate) Option<f32>);

pub(crate) fn parse_cone(s: &str) -> Result<Cone, String> {
    if s.eq_ignore_ascii_case("off") {
        return Ok(Cone(None));
    }
    let k: f32 = s
        .parse()
        .map_err(|e| format!("{s:?}: {e} (expected a number k >= 1, or `off`)"))?;
    if !(k.is_finite() && k >= 1.0) {
        return Err(format!("the cone filter constant must be >= 1, got {s}"));
    }
    Ok(Cone(Some(k)))
}

/// `WIDTHxHEIGHT`, each side in 1..=[`MAX_RESOLUTION`](ppm_vk_engine::scene::MAX_RESOLUTION).
pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, got {s:?}"))?;
    let parse = |v: &str| v.trim().parse::<u32>().map_err(|e| format!("{v:?}: {e}"));
    let (w, h) = (parse(w)?, parse(h)?);
    let max = ppm_vk_engine::scene::MAX_RESOLUTION;
    if w == 0 || h == 0 || w > max || h > max {
        return Err(format!(
            "resolution {w}x{h} out of range: width and height must be in 1..={max}"
        ));
    }
    Ok((w, h))
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => match render(args) {
            Ok(Ended::Signal(sig)) => std::process::exit(128 + sig),
            other => other.map(|_| ()),
        },
        Command::View(args) => match view::run(args) {
            Ok(view::Ended::Signal(sig)) => std::process::exit(128 + sig),
            Ok(view::Ended::NoDisplay(why)) => {
                eprintln!("error: {why}");
                std::process::exit(view::EXIT_NO_DISPLAY);
            }
            other => other.map(|_| ()),
        },
        Command::Devices => devices(),
        Command::Bench(args) => bench::run(args),
        Command::Compare(args) => compare::run(args),
        Command::Check(args) => check::run(args),
        Command::Merge(args) => distributed::run(args),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn devices() -> Result<()> {
    let list = Context::list_devices()?;
    if list.is_empty() {
        println!("no Vulkan devices found");
    }
    for d in list {
        let status = if d.missing.is_empty() {
            "usable".to_string()
        } else {
            format!("lacks {}", d.missing.join(", "))
        };
        println!(
            "[{}] {} ({}, Vulkan {}, {}, {} MiB): {}",
            d.index,
            d.name,
            d.kind,
            d.api_version,
            d.driver,
            d.memory_bytes >> 20,
            status
        );
    }
    Ok(())
}

/// Loads a scene (with a Mitsuba scene's `-D` overrides) and writes what loading approximated (MTL
/// features, dropped triangles, Mitsuba features) to stderr.
pub fn load_scene(path: &std::path::Path, defines: &[(String, String)]) -> Result<Scene> {
    let scene = Scene::load_with(path, defines)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}

/// Fails if the validation layer said anything (only when it is on).
pub fn check_validation(ctx: &Context) -> Result<()> {
    let msgs = ctx.validation_messages();
    if !msgs.is_empty() {
        bail!(
            "the validation layer reported {} message(s):\n{}",
            msgs.len(),
            msgs.join("\n")
        );
    }
    Ok(())
}

/// The build a checkpoint names: its kernels and engine must be the ones that continue it.
const BUILD: &str = env!("PPM_VK_GIT_REV");

/// How a render ended.
enum Ended {
    Done,
    /// By this signal (SIGINT, SIGTERM) after writing what it had: exit 128 + signal.
    Signal(i32),
}

/// The first SIGINT or SIGTERM is stored (its number) for the render loop to stop, and cancels `cancel`
/// (if given) so the pass in flight ends at its next submission; a second one exits at once, with 128 +
/// its number.
pub(crate) fn watch_signals(cancel: Option<CancelToken>) -> Result<Arc<AtomicUsize>> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let first = Arc::new(AtomicUsize::new(0));
    let seen = Arc::new(AtomicBool::new(false));
    for sig in [SIGINT, SIGTERM] {
        // Registered first, so it runs before `seen` is set: exits only when a signal came before.
        signal_hook::flag::register_conditional_shutdown(sig, 128 + sig, seen.clone())
            .context("installing the signal handlers")?;
        signal_hook::flag::register(sig, seen.clone()).context("installing the signal handlers")?;
        // compare_exchange keeps the first signal's number (a plain store would keep the last).
        let (first, cancel) = (first.clone(), cancel.clone());
        // SAFETY: the action only does an atomic compare-exchange and an atomic store (the cancel), which
        // are async-signal-safe.
        unsafe {
            signal_hook::low_level::register(sig, move || {
                let _ = first.compare_exchange(0, sig as usize, Ordering::SeqCst, Ordering::SeqCst);
                if let Some(c) = &cancel {
                    c.cancel();
                }
            })
        }
        .context("installing the signal handlers")?;
    }
    Ok(first)
}

/// The images `render` writes: `--out`, else `<scene name>.exr` plus a `<scene name>.png` preview.
/// Existing files are refused unless `--force`, before any work is done.
pub(crate) fn outputs(out: &Option<PathBuf>, scene_name: &str, force: bool) -> Result<Vec<PathBuf>> {
    let paths = match out {
        Some(out) => {
            let ext = out.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
            if !matches!(ext.as_deref(), Some("exr") | Some("png")) {
                bail!("--out {}: the extension must be .exr or .png", out.display());
            }
            vec![out.clone()]
        }
        None => vec![
            PathBuf::from(format!("{scene_name}.exr")),
            PathBuf::from(format!("{scene_name}.png")),
        ],
    };
    if !force {
        if let Some(p) = paths.iter().find(|p| p.exists()) {
            bail!(
                "{} exists: not overwritten (pass --force to overwrite, or --out to choose another file)",
                p.display()
            );
        }
    }
    Ok(paths)
}

fn save_all(image: &ppm_vk_engine::RgbImage, paths: &[PathBuf]) -> Result<()> {
    for p in paths {
        image.save(p)?;
    }
    Ok(())
}

fn render(args: RenderArgs) -> Result<Ended> {
    if let (Some(worker), Some(of)) = (args.worker, args.of) {
        return distributed::render_worker(args, worker, of);
    }
    // The renderer's token: a signal ends the pass in flight between its submissions, not after it.
    let cancel = CancelToken::new();
    let signal = watch_signals(Some(cancel.clone()))?;
    let interrupted = || match signal.load(Ordering::SeqCst) {
        0 => None,
        s => Some(s as i32),
    };
    if let Some(out) = &args.out {
        outputs(&Some(out.clone()), "", true)?; // the extension, before the scene is read
    }
    if let Some(report) = &args.report {
        let ext = report
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        if !matches!(ext.as_deref(), Some("json") | Some("csv")) {
            bail!("--report {}: the extension must be .json or .csv", report.display());
        }
    }
    let loading = Instant::now();
    let scene = args.settings.load_scene(&args.scene, &args.defines)?;
    let load_s = loading.elapsed().as_secs_f64();
    // A resumed render continues the image it wrote before: it may overwrite it.
    let out = outputs(&args.out, &scene.name, args.force || args.resume.is_some())?;
    let reference = match &args.reference {
        Some(p) => Some(Reference::load(p)?),
        None => None,
    };
    let settings = args.settings.settings(1_000_000)?;
    // A checkpoint that does not fit is refused here, before the device opens.
    let resumed = match &args.resume {
        Some(path) => Some(Checkpoint::load_for(path, &scene, &settings, BUILD)?),
        None => None,
    };
    let set_up_interrupted = |sig: i32| {
        eprintln!("interrupted during set-up: no pass done, nothing written");
        Ok(Ended::Signal(sig))
    };
    if let Some(sig) = interrupted() {
        return set_up_interrupted(sig);
    }

    let ctx = args.device.open()?;
    let info = ctx.info().clone();
    eprintln!("device: {} ({}, {})", info.name, info.kind, info.driver);
    let started = Instant::now();
    let mut renderer = match &resumed {
        Some(c) => Renderer::resume(&ctx, &scene, settings, c, BUILD)?,
        None => Renderer::new(&ctx, &scene, settings)?,
    };
    renderer.set_cancel(cancel);
    let setup_s = started.elapsed().as_secs_f64();
    // Every kernel is compiled by now: keep them for the next run even if this one is killed.
    save_pipeline_cache(&ctx);
    for note in renderer.setup_times().notes() {
        eprintln!("note: {note}");
    }
    if args.profile {
        print_setup(load_s, renderer.setup_times());
    }
    eprintln!(
        "scene {}: {}x{}, {} hit-point slots, initial radius {:.5}, {} photons/pass; ray pass {:.1} ms GPU",
        scene.name,
        scene.camera.width,
        scene.camera.height,
        renderer.hit_point_slots(),
        renderer.initial_radius(),
        renderer.settings().photons_per_pass,
        renderer.ray_ms()
    );
    if resumed.is_some() {
        eprintln!(
            "resumed after pass {} ({} photons)",
            renderer.passes(),
            renderer.emitted()
        );
    }

    if args.profile {
        let m = renderer.pilot_marks()?;
        let pct = |n: u32| 100.0 * n as f64 / m.pixels.max(1) as f64;
        eprintln!(
            "pilot marks: emission {:.1}%, near a light {:.1}%, rough {:.1}%, lit {:.1}% of {} pixels; all emission \
             samples in {:.1}% (in the pilot: {:.1}%)",
            pct(m.emission),
            pct(m.near),
            pct(m.rough),
            pct(m.lit),
            m.pixels,
            pct(m.all_samples),
            pct(m.pilot_all)
        );
    }
    if let Some(p) = renderer.probe_report() {
        let q = p.lambda_ratio_quantiles;
        eprintln!(
            "probe: {} photons, {} of {} hit points enlarged ({} reached by none), lambda/r^2 min {:.3} q1 {:.3} median {:.3} q3 {:.3} max {:.3}, mean radius {:.3} r, {:.1} ms GPU",
            p.photons, p.enlarged, p.hit_points, p.empty, q[0], q[1], q[2], q[3], q[4], p.mean_radius_ratio, p.gpu_ms
        );
    }
    if let Some(sig) = interrupted() {
        return set_up_interrupted(sig);
    }
    let mut report = RunReport::new(RunHeader {
        schema: SCHEMA.into(),
        git_revision: BUILD.into(),
        device: info.name.clone(),
        device_kind: info.kind.clone(),
        driver: info.driver.clone(),
        scene_path: args.scene.display().to_string(),
        scene_name: scene.name.clone(),
        scene_sha256: scene.content_sha256(),
        width: scene.camera.width,
        height: scene.camera.height,
        settings: renderer.settings().clone(),
        ray_ms: renderer.ray_ms(),
        probe: renderer.probe_report().cloned(),
    });
    let regions = match &reference {
        Some(reference) => args.regions.resolve(&scene, reference),
        None => Vec::new(),
    };
    let (mut gpu_origin, mut eval_s, mut evals) = (None, 0f64, 0u32);
    let budget = args.time.map(Duration::from_secs_f64);
    let passes = args.passes.unwrap_or(if budget.is_some() { u64::MAX } else { 100 });
    let bar = if budget.is_some() {
        ProgressBar::new(1000)
    } else {
        ProgressBar::new(passes)
    };
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:30} {msg} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    // What is saved when: the image (and the state, with --checkpoint) every `save_every`, and at the end.
    let save_every = args.checkpoint_every.or(args.checkpoint.as_ref().map(|_| 300.0));
    let save = |renderer: &mut Renderer| -> Result<()> {
        save_all(&renderer.image()?, &out)?;
        match &args.checkpoint {
            Some(path) => renderer.checkpoint(BUILD)?.save(path),
            None => Ok(()),
        }
    };
    let loop_start = Instant::now();
    let mut history: Vec<PassStats> = Vec::new();
    let mut last_save = Instant::now();
    let mut ended = Ended::Done;
    while renderer.passes() < passes {
        if let Some(sig) = interrupted() {
            bar.println("interrupted: writing the image of the passes done so far");
            ended = Ended::Signal(sig);
            break;
        }
        if let Some(b) = budget {
            if loop_start.elapsed() >= b {
                break;
            }
        }
        let s = match renderer.pass() {
            Ok(s) => s,
            // A signal cancelled the pass in flight: the state is the passes before it.
            Err(ppm_vk_engine::Error::Cancelled) if interrupted().is_some() => {
                bar.println("interrupted during a pass: writing the image of the passes done before it");
                ended = Ended::Signal(interrupted().unwrap_or_default());
                break;
            }
            Err(e) => return Err(save_after_failure(&mut renderer, &out, e.into())),
        };
        let elapsed = loop_start.elapsed().as_secs_f64();
        let rate = (s.photons * (history.len() as u64 + 1)) as f64 / elapsed / 1e6;
        match budget {
            Some(b) => bar.set_position((elapsed / b.as_secs_f64() * 1000.0).min(1000.0) as u64),
            None => bar.set_position(s.index),
        }
        bar.set_message(format!(
            "pass {} | {:.2} M photons/s | {:.1} ms/pass",
            s.index, rate, s.wall_ms
        ));
        let origin = *gpu_origin.get_or_insert(s.stages.first().map(|t| t.start_ms).unwrap_or(0.0));
        let mut record = PassRecord::new(&s, started.elapsed().as_secs_f64(), origin);
        if let Some(reference) = &reference {
            if s.index % args.error_every == 0 {
                let t = Instant::now();
                let image = renderer.image()?;
                record.error = Some(compare(&image, reference, None, true)?);
                for r in &regions {
                    record
                        .region_errors
                        .insert(r.name.clone(), compare(&image, reference, Some(r), true)?);
                }
                eval_s += t.elapsed().as_secs_f64();
                evals += 1;
            }
        }
        report.passes.push(record);
        history.push(s);
        if save_every.is_some_and(|t| last_save.elapsed().as_secs_f64() >= t) {
            save(&mut renderer)?;
            last_save = Instant::now();
        }
    }
    bar.finish_and_clear();
    save_pipeline_cache(&ctx); // what later passes compiled (none today; cheap when nothing is new)
    if history.is_empty() && matches!(ended, Ended::Signal(_)) && resumed.is_none() {
        eprintln!("interrupted before the first pass ended: nothing written");
        return Ok(ended);
    }
    let loop_s = loop_start.elapsed().as_secs_f64();
    let image = renderer.image()?;
    let bad = image.count_non_finite();
    if bad > 0 {
        bail!("the image has {bad} non-finite pixels: not written (this is a bug; please report it)");
    }
    save(&mut renderer)?;
    check_validation(&ctx)?;
    // Written all the same (it is what the scene gives), but a black image is rarely what was meant.
    if image.mean() == [0.0; 3] {
        eprintln!(
            "warning: every pixel is 0 after {} passes: the camera sees nothing lit (is it looking away \
             from the scene or from inside a shape, or do the lights face away from what it sees?)",
            renderer.passes()
        );
    }

    let emitted = renderer.emitted();
    println!(
        "{} passes, {} photons in {:.2} s ({:.2} M photons/s; setup {:.2} s) -> {}",
        history.len(),
        emitted,
        loop_s,
        history.iter().map(|s| s.photons).sum::<u64>() as f64 / loop_s.max(1e-9) / 1e6,
        setup_s,
        out.iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    if let Some(path) = &args.checkpoint {
        println!("checkpoint after pass {}: {}", renderer.passes(), path.display());
    }
    print_stage_summary(&history, args.profile);
    // Paths ended at a depth backstop are counted in every report; a share above 1e-4 of the paths traced
    // is worth a warning (a glass sphere strands about 2e-5 of them by rounding, which is not).
    if let Some(last) = history.last() {
        let pixels = scene.camera.width as f64 * scene.camera.height as f64;
        let eye_paths = pixels
            * (renderer.settings().slots(&scene) + renderer.settings().most_samples()).max(1) as f64
            * (renderer.passes() as f64 + 1.0);
        let photon_share = last.photon_paths_cut as f64 / last.emitted_total.max(1) as f64;
        let eye_share = last.eye_paths_cut as f64 / eye_paths;
        if photon_share > 1e-4 || eye_share > 1e-4 {
            let l = renderer.path_limits();
            eprintln!(
                "warning: {} photon paths reached {} surface interactions and {} eye paths {} specular bounces, \
                 and were ended there: the scene traps light (glass by internal reflection, facing mirrors, \
                 albedo near 1); the energy they still carried is missing from the image",
                last.photon_paths_cut, l.photon_depth, last.eye_paths_cut, l.eye_depth
            );
        }
        if last.photons_capped > 0 {
            eprintln!(
                "warning: {} time(s) a photon's flux was held at 2^16 times a light's, where the correction for \
                 smooth shading (light grazing a smooth-shaded mesh) would have raised it further: a loss of \
                 at most the flux beyond that (docs/design.md, smooth shading)",
                last.photons_capped
            );
        }
    }
    if let Some(reference) = reference {
        report_error(&image, &reference, &regions)?;
        if evals > 0 {
            println!(
                "error evaluated after {evals} passes: {:.1} ms each, {:.1}% of the render's wall time",
                eval_s / evals as f64 * 1e3,
                eval_s / loop_s.max(1e-9) * 100.0
            );
        }
    }
    if let Some(path) = &args.report {
        report.save(path)?;
        println!("report: {}", path.display());
    }
    if let Some(path) = &args.trace {
        report.save_chrome_trace(path)?;
        println!("trace: {}", path.display());
    }
    if let Ended::Signal(sig) = ended {
        eprintln!(
            "interrupted by signal {sig} after pass {}: image, report and checkpoint written",
            renderer.passes()
        );
    }
    Ok(ended)
}

/// A pass failed (the device lost, out of memory): saves the image of the passes before it if the device
/// still answers, and returns the pass's error saying what was kept. The checkpoint is not rewritten: a
/// failed pass may have left part of its work in the state; the last one saved stays valid.
fn save_after_failure(renderer: &mut Renderer, out: &[PathBuf], error: anyhow::Error) -> anyhow::Error {
    let pass = renderer.passes() + 1;
    let saved = renderer
        .image()
        .map_err(anyhow::Error::from)
        .and_then(|image| save_all(&image, out));
    match saved {
        Ok(()) => {
            let files: Vec<String> = out.iter().map(|p| p.display().to_string()).collect();
            error.context(format!(
                "pass {pass} failed; the image of the {} passes before it is in {}",
                pass - 1,
                files.join(", ")
            ))
        }
        Err(e) => error.context(format!(
            "pass {pass} failed, and the image could not be saved either ({e:#})"
        )),
    }
}

fn print_stage_summary(history: &[PassStats], full: bool) {
    if history.is_empty() {
        return;
    }
    let names = ["photon", "lookup", "gather", "update"];
    let n = history.len() as f64;
    let mean = |name: &str| history.iter().map(|s| s.stage_ms(name)).sum::<f64>() / n;
    let wall = history.iter().map(|s| s.wall_ms).sum::<f64>() / n;
    let parts: Vec<String> = names.iter().map(|k| format!("{k} {:.2}", mean(k))).collect();
    println!("mean GPU ms per pass: {} | wall {:.2}", parts.join(", "), wall);
    if full {
        let cols = [
            "ray",
            "photon",
            "lookup/count",
            "lookup/scan",
            "lookup/split",
            "lookup/scatter",
            "gather",
            "update",
        ];
        let head: Vec<String> = cols.iter().map(|c| format!("{:>15}", c)).collect();
        println!("{:>6} {:>10} {} {:>9}", "pass", "records", head.join(""), "wall");
        for s in history {
            let row: Vec<String> = cols.iter().map(|c| format!("{:>15.2}", s.stage_ms(c))).collect();
            println!("{:>6} {:>10} {} {:>9.2}", s.index, s.records, row.join(""), s.wall_ms);
        }
    }
}

fn report_error(image: &ppm_vk_engine::RgbImage, reference: &Reference, regions: &[Region]) -> Result<()> {
    let whole = compare(image, reference, None, true)?;
    println!(
        "error vs reference (its own noise removed): RMSE {:.4}, relMSE {:.5}, bias {:+.4}",
        whole.rmse, whole.rel_mse, whole.mean_bias
    );
    for r in regions {
        let e = compare(image, reference, Some(r), true)?;
        println!(
            "  {:<12} RMSE {:.4}, relMSE {:.5}, bias {:+.4}",
            r.name, e.rmse, e.rel_mse, e.mean_bias
        );
    }
    Ok(())
}

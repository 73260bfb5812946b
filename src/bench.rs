//! `ppm-vk bench`: a fixed, documented set of cases, each rendered for a few warm-up passes (excluded:
//! they include the pipelines' first-dispatch compile) and then timed over measured passes. Reports the
//! median per stage (GPU timestamps) and of the wall time per pass, the peak device memory and host
//! resident memory of each case, and whether either grew over the measured passes; prints a table and
//! writes JSON.

use std::path::{Path, PathBuf};

use std::collections::BTreeMap;

use anyhow::{Context as _, Result};
use clap::Args;
use ppm_vk_engine::{Context, Mode, PassStats, ProbeMode, Renderer, Scene, Settings};
use serde::Serialize;

use crate::{Cone, DeviceArgs, ModeArg, ProbeArg};

/// The matrix: 0.1M, 1M and 4M photons per pass at 256^2, 512^2 and 1024^2.
const DEFAULT_CASES: &str = "100k@256x256,1M@256x256,4M@256x256,100k@512x512,1M@512x512,4M@512x512,\
                             100k@1024x1024,1M@1024x1024,4M@1024x1024";

#[derive(Args)]
pub struct BenchArgs {
    /// Scene to benchmark; repeat it for a ladder of scenes, each case run on every one, and each scene's
    /// photon stage per photon and eye pass per hit point printed as a ratio to the first scene's.
    #[arg(long, default_value = "scenes/cornell-spheres.toml")]
    scene: Vec<PathBuf>,
    /// Override a Mitsuba scene's parameter: `-D name=value` sets what `$name` stands for (repeatable).
    #[arg(short = 'D', long = "define", value_name = "NAME=VALUE", value_parser = ppm_vk_engine::scene::parse_define)]
    pub defines: Vec<(String, String)>,
    /// Cases as PHOTONS@WIDTHxHEIGHT, comma-separated (photon counts accept k and M suffixes; width and
    /// height 1..=16384); PHOTONS alone renders at the scene's own resolution.
    #[arg(long, default_value = DEFAULT_CASES, value_parser = parse_cases)]
    cases: Cases,
    /// Passes run before timing starts.
    #[arg(long, default_value_t = 2)]
    warmup: u32,
    /// Passes timed per case (the median is reported).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
    passes: u32,
    /// `ppm` or `sppm` (SPPM adds an eye pass to every pass).
    #[arg(long, value_enum, default_value_t = ModeArg::Sppm)]
    mode: ModeArg,
    /// Photon probing (eq. 7-9), as for `render`.
    #[arg(long, value_enum, default_value_t = ProbeArg::Curvature)]
    probe: ProbeArg,
    /// Cone filter constant k >= 1, or `off`, as for `render`.
    #[arg(long, default_value = "off", value_parser = crate::parse_cone)]
    cone: Cone,
    /// Direct light by light sampling or by the photons, as for `render`.
    #[arg(long, value_enum, default_value_t = crate::DirectArg::Sample)]
    direct: crate::DirectArg,
    /// Also time the photon kernel against variants of itself with parts removed, down to tracing only
    /// (its ceiling in this design), on each case's first batch.
    #[arg(long)]
    breakdown: bool,
    /// Where to write the JSON results.
    #[arg(long, default_value = "bench.json")]
    json: PathBuf,
    #[command(flatten)]
    device: DeviceArgs,
}

#[derive(Clone)]
struct Case {
    photons: u32,
    /// `None`: the scene's own resolution.
    resolution: Option<(u32, u32)>,
}

#[derive(Clone)]
struct Cases(Vec<Case>);

fn parse_count(s: &str) -> Result<u32, String> {
    let s = s.trim();
    let (num, mul) = match s.chars().last() {
        Some('k') | Some('K') => (&s[..s.len() - 1], 1e3),
        Some('m') | Some('M') => (&s[..s.len() - 1], 1e6),
        _ => (s, 1.0),
    };
    let v: f64 = num.parse().map_err(|e| format!("photon count {s:?}: {e}"))?;
    let v = v * mul;
    if !(v >= 1.0 && v <= u32::MAX as f64) {
        return Err(format!("photon count {s:?} out of range 1..={}", u32::MAX));
    }
    Ok(v as u32)
}

fn parse_cases(s: &str) -> Result<Cases, String> {
    let cases = s
        .split(',')
        .map(|c| {
            let (p, r) = match c.split_once('@') {
                Some((p, r)) => (p, Some(r)),
                None => (c, None),
            };
            let resolution = r
                .map(crate::parse_resolution)
                .transpose()
                .map_err(|e| format!("case {c:?}: {e}"))?;
            Ok(Case {
                photons: parse_count(p).map_err(|e| format!("case {c:?}: expected PHOTONS[@WIDTHxHEIGHT]: {e}"))?,
                resolution,
            })
        })
        .collect::<Result<_, String>>()?;
    Ok(Cases(cases))
}

/// bench.json (schema ppm-vk-bench/2).
#[derive(Serialize)]
struct BenchDoc {
    schema: &'static str,
    device: DeviceDoc,
    git_revision: &'static str,
    scenes: Vec<String>,
    mode: Mode,
    probe: ProbeMode,
    cone_k: Option<f32>,
    direct: ppm_vk_engine::DirectLight,
    warmup_passes: u32,
    measured_passes: u32,
    cases: Vec<CaseResult>,
}

#[derive(Serialize)]
struct DeviceDoc {
    name: String,
    kind: String,
    driver: String,
    api: String,
}

#[derive(Serialize)]
struct CaseResult {
    scene: String,
    photons_per_pass: u32,
    width: u32,
    height: u32,
    hit_points: u32,
    records_per_pass: f64,
    batches_per_pass: u32,
    ray_ms: f64,
    /// Where the renderer's set-up went, in seconds (the first case of a scene pays the kernels'
    /// compiles; later cases find most of them cached).
    setup: ppm_vk_engine::SetupTimes,
    /// The first warm-up pass's wall time: with the set-up, what the first image of a new scene costs
    /// (on lavapipe it compiles the photon-stage kernels at their first dispatch).
    first_pass_wall_ms: Option<f64>,
    /// What the pilot eye pass marked: pixels of each mark, and those where the pilot took all its samples.
    pilot_marks: ppm_vk_engine::PilotMarks,
    stage_ms_median: BTreeMap<&'static str, f64>,
    pass_wall_ms_median: f64,
    pass_wall_ms_all: Vec<f64>,
    resolve_ms_median: f64,
    photons_per_second: f64,
    photon_stage_ns_per_photon: f64,
    /// The eye pass (stage `ray`) per hit point; PPM's passes after the first trace emission samples only.
    eye_ns_per_hit_point: f64,
    /// This case against the same case of the first scene (a ladder of scenes only).
    vs_first_scene: Option<Ratios>,
    photon_breakdown: Vec<BreakdownResult>,
    bvh: BvhResult,
    device_memory: DeviceMemoryResult,
    host_rss: HostRssResult,
}

#[derive(Clone, Copy, Serialize)]
struct Ratios {
    photon_stage_per_photon: f64,
    eye_pass_per_hit_point: f64,
}

#[derive(Serialize)]
struct BreakdownResult {
    variant: &'static str,
    photons: u32,
    gpu_ms: f64,
    intersections: u64,
    intersections_per_second: f64,
}

#[derive(Serialize)]
struct BvhResult {
    triangles: usize,
    nodes: usize,
    depth: u32,
    build_seconds: f64,
    bytes: usize,
}

#[derive(Serialize)]
struct DeviceMemoryResult {
    peak_reserved_bytes: u64,
    in_use_bytes_after_warmup: u64,
    in_use_bytes_after_measured: u64,
}

/// Linux only: `None` (null) elsewhere.
#[derive(Serialize)]
struct HostRssResult {
    peak_bytes: Option<u64>,
    bytes_after_warmup: Option<u64>,
    bytes_after_measured: Option<u64>,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n == 0 {
        return 0.0;
    }
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

const STAGES: [&str; 5] = ["ray", "photon", "lookup", "gather", "update"];

/// This process's resident memory now and its peak since the last [`reset_peak_rss`], in bytes (Linux's
/// /proc/self/status VmRSS and VmHWM; `None` elsewhere).
fn host_rss() -> Option<(u64, u64)> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let field = |name: &str| -> Option<u64> {
        let line = status.lines().find(|l| l.starts_with(name))?;
        Some(
            line[name.len()..]
                .trim()
                .trim_end_matches("kB")
                .trim()
                .parse::<u64>()
                .ok()?
                * 1024,
        )
    };
    Some((field("VmRSS:")?, field("VmHWM:")?))
}

/// Restarts the peak resident set (VmHWM) from the current one (Linux: `5` into /proc/self/clear_refs).
fn reset_peak_rss() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1u64 << 20) as f64
}

/// The photon kernel's variants, each as a fraction of the trace-only ceiling (intersections per second).
fn print_breakdown(variants: &[BreakdownResult]) {
    let Some(ceiling) = variants
        .iter()
        .find(|v| v.variant == "trace only")
        .map(|v| v.intersections_per_second)
    else {
        return;
    };
    for v in variants {
        println!(
            "    photon kernel, {:<16} {:>8.1} ms for {} photons, {:>6.2} M intersections, {:>6.1} M/s, {:>5.1}% of trace only",
            v.variant,
            v.gpu_ms,
            v.photons,
            v.intersections as f64 / 1e6,
            v.intersections_per_second / 1e6,
            100.0 * v.intersections_per_second / ceiling
        );
    }
}

fn print_header(ladder: bool) {
    print!(
        "{:>10} {:>11} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>11} {:>9} {:>9} {:>9}",
        "photons",
        "resolution",
        "first ray",
        "ray",
        "photon",
        "lookup",
        "gather",
        "update",
        "pass ms",
        "M photons/s",
        "resolve",
        "dev MiB",
        "RSS MiB"
    );
    if ladder {
        print!(" {:>14} {:>12}", "photon/photon", "eye/hit pt");
    }
    println!();
}

fn print_row(r: &CaseResult) {
    let stage = |s: &str| r.stage_ms_median.get(s).copied().unwrap_or(0.0);
    print!(
        "{:>10} {:>11} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>11.3} {:>9.1} {:>9.0} {:>9}",
        r.photons_per_pass,
        format!("{}x{}", r.width, r.height),
        r.ray_ms,
        stage("ray"),
        stage("photon"),
        stage("lookup"),
        stage("gather"),
        stage("update"),
        r.pass_wall_ms_median,
        r.photons_per_second / 1e6,
        r.resolve_ms_median,
        mib(r.device_memory.peak_reserved_bytes),
        r.host_rss
            .peak_bytes
            .map_or("-".to_string(), |b| format!("{:.0}", mib(b)))
    );
    if let Some(v) = r.vs_first_scene {
        print!(
            " {:>13.2}x {:>11.2}x",
            v.photon_stage_per_photon, v.eye_pass_per_hit_point
        );
    }
    println!();
}

/// Renders one case of one scene: warm-up, measured passes, resolves and (with --breakdown) the photon
/// kernel's variants.
fn measure(args: &BenchArgs, ctx: &Context, scene_path: &Path, scene: &Scene, photons: u32) -> Result<CaseResult> {
    let settings = Settings {
        photons_per_pass: photons,
        mode: Mode::from(args.mode),
        probe: args.probe.into(),
        cone_k: args.cone.0,
        direct: args.direct.into(),
        ..Settings::default()
    };
    ctx.reset_memory_peak();
    reset_peak_rss();
    let mut renderer = Renderer::new(ctx, scene, settings)?;
    let mut first_pass_wall_ms = None;
    for _ in 0..args.warmup {
        let pass = renderer.pass()?;
        first_pass_wall_ms.get_or_insert(pass.wall_ms);
    }
    // Memory after the warm-up and after the measured passes: nothing should grow with passes.
    let (dev_before, rss_before) = (ctx.memory_usage(), host_rss());
    let measured: Vec<PassStats> = (0..args.passes).map(|_| renderer.pass()).collect::<Result<_, _>>()?;
    let (dev_after, rss_after) = (ctx.memory_usage(), host_rss());
    renderer.resolve()?; // the first resolve compiles its pipeline
    let resolve_ms = median((0..3).map(|_| renderer.resolve()).collect::<Result<Vec<_>, _>>()?);
    let breakdown = match args.breakdown {
        true => renderer.photon_breakdown(photons)?,
        false => Vec::new(),
    };
    let stage: BTreeMap<&'static str, f64> = STAGES
        .iter()
        .map(|&s| (s, median(measured.iter().map(|p| p.stage_ms(s)).collect())))
        .collect();
    let wall = median(measured.iter().map(|p| p.wall_ms).collect());
    let bvh = renderer.bvh_stats();
    let hit_points = renderer.active_hit_points();
    Ok(CaseResult {
        scene: scene_path.display().to_string(),
        photons_per_pass: photons,
        width: scene.camera.width,
        height: scene.camera.height,
        hit_points,
        records_per_pass: median(measured.iter().map(|p| p.records as f64).collect()),
        batches_per_pass: measured.last().map_or(0, |p| p.batches),
        ray_ms: renderer.ray_ms(),
        setup: renderer.setup_times().clone(),
        first_pass_wall_ms,
        pilot_marks: renderer.pilot_marks()?,
        pass_wall_ms_median: wall,
        pass_wall_ms_all: measured.iter().map(|p| p.wall_ms).collect(),
        resolve_ms_median: resolve_ms,
        photons_per_second: photons as f64 / (wall * 1e-3),
        photon_stage_ns_per_photon: stage["photon"] * 1e6 / photons as f64,
        eye_ns_per_hit_point: stage["ray"] * 1e6 / hit_points.max(1) as f64,
        vs_first_scene: None,
        stage_ms_median: stage,
        photon_breakdown: breakdown
            .iter()
            .map(|v| BreakdownResult {
                variant: v.name,
                photons: v.photons,
                gpu_ms: v.gpu_ms,
                intersections: v.steps,
                intersections_per_second: v.steps_per_second(),
            })
            .collect(),
        bvh: BvhResult {
            triangles: bvh.triangles,
            nodes: bvh.nodes,
            depth: bvh.depth,
            build_seconds: bvh.build_seconds,
            bytes: renderer.bvh_bytes(),
        },
        device_memory: DeviceMemoryResult {
            peak_reserved_bytes: dev_after.peak_reserved_bytes,
            in_use_bytes_after_warmup: dev_before.in_use_bytes,
            in_use_bytes_after_measured: dev_after.in_use_bytes,
        },
        host_rss: HostRssResult {
            peak_bytes: rss_after.map(|r| r.1),
            bytes_after_warmup: rss_before.map(|r| r.0),
            bytes_after_measured: rss_after.map(|r| r.0),
        },
    })
}

pub fn run(args: BenchArgs) -> Result<()> {
    let ctx = args.device.open()?;
    let info = ctx.info().clone();
    println!("device: {} ({}, {})", info.name, info.kind, info.driver);
    println!(
        "mode {}, probe {}, cone {}; {} warm-up passes, median of {}",
        crate::cli_name(args.mode),
        crate::cli_name(args.probe),
        args.cone.0.map_or("off".to_string(), |k| k.to_string()),
        args.warmup,
        args.passes
    );
    let ladder = args.scene.len() > 1;
    let mut results: Vec<CaseResult> = Vec::new();
    for path in &args.scene {
        let loading = std::time::Instant::now();
        let base = crate::load_scene(path, &args.defines)?;
        let load_s = loading.elapsed().as_secs_f64();
        if ladder {
            println!("scene {}", path.display());
        }
        for (index, case) in args.cases.0.iter().enumerate() {
            let (width, height) = case.resolution.unwrap_or((base.camera.width, base.camera.height));
            let mut r = measure(&args, &ctx, path, &base.with_resolution(width, height), case.photons)?;
            if index == 0 {
                // The scene's first case pays its kernels' compiles (the later ones find them cached).
                crate::print_setup(load_s, &r.setup);
                if r.bvh.triangles > 0 {
                    println!(
                        "{} triangles loaded in {:.2} s; BVH built in {:.2} s ({:.2} M triangles/s), {} nodes, depth {}, {:.1} MiB",
                        r.bvh.triangles,
                        load_s,
                        r.bvh.build_seconds,
                        r.bvh.triangles as f64 / r.bvh.build_seconds.max(1e-9) / 1e6,
                        r.bvh.nodes,
                        r.bvh.depth,
                        mib(r.bvh.bytes as u64)
                    );
                }
                print_header(ladder);
            }
            // The same case of the first scene (cases run in order, the first scene first).
            if let Some(first) = results.get(index).filter(|_| ladder) {
                r.vs_first_scene = Some(Ratios {
                    photon_stage_per_photon: r.photon_stage_ns_per_photon / first.photon_stage_ns_per_photon,
                    eye_pass_per_hit_point: r.eye_ns_per_hit_point / first.eye_ns_per_hit_point,
                });
            }
            print_row(&r);
            print_breakdown(&r.photon_breakdown);
            results.push(r);
            crate::check_validation(&ctx)?;
        }
    }
    let doc = BenchDoc {
        schema: "ppm-vk-bench/2",
        device: DeviceDoc {
            name: info.name,
            kind: info.kind,
            driver: info.driver,
            api: info.api_version,
        },
        git_revision: env!("PPM_VK_GIT_REV"),
        scenes: args.scene.iter().map(|p| p.display().to_string()).collect(),
        mode: Mode::from(args.mode),
        probe: args.probe.into(),
        cone_k: args.cone.0,
        direct: args.direct.into(),
        warmup_passes: args.warmup,
        measured_passes: args.passes,
        cases: results,
    };
    std::fs::write(&args.json, serde_json::to_string_pretty(&doc)?)
        .with_context(|| format!("writing {}", args.json.display()))?;
    println!("wrote {}", args.json.display());
    Ok(())
}

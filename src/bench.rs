//! `ppm-vk bench`: a fixed, documented set of cases, each rendered for a few warm-up passes (excluded:
//! they include the pipelines' first-dispatch compile) and then timed over measured passes. Reports the
//! median per stage (GPU timestamps) and of the wall time per pass, the peak device memory and host
//! resident memory of each case, and whether either grew over the measured passes; prints a table and
//! writes JSON.

use std::path::PathBuf;

use std::collections::BTreeMap;

use anyhow::{Context as _, Result};
use clap::Args;
use ppm_vk_engine::{Mode, PassStats, ProbeMode, Renderer, Settings};
use serde::Serialize;

use crate::{Cone, DeviceArgs, ModeArg, ProbeArg};

/// The matrix: 0.1M, 1M and 4M photons per pass at 256^2, 512^2 and 1024^2.
const DEFAULT_CASES: &str = "100k@256x256,1M@256x256,4M@256x256,100k@512x512,1M@512x512,4M@512x512,\
                             100k@1024x1024,1M@1024x1024,4M@1024x1024";

#[derive(Args)]
pub struct BenchArgs {
    /// Scene to benchmark.
    #[arg(long, default_value = "scenes/cornell-spheres.toml")]
    scene: PathBuf,
    /// Override a Mitsuba scene's parameter: `-D name=value` sets what `$name` stands for (repeatable).
    #[arg(short = 'D', long = "define", value_name = "NAME=VALUE", value_parser = ppm_vk_engine::scene::parse_define)]
    pub defines: Vec<(String, String)>,
    /// Cases as PHOTONS@WIDTHxHEIGHT, comma-separated (photon counts accept k and M suffixes; width and
    /// height 1..=16384).
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
    #[arg(long, value_enum, default_value_t = ProbeArg::Off)]
    probe: ProbeArg,
    /// Cone filter constant k >= 1, or `off`, as for `render`.
    #[arg(long, default_value = "off", value_parser = crate::parse_cone)]
    cone: Cone,
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
    width: u32,
    height: u32,
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
            let (p, r) = c
                .split_once('@')
                .ok_or_else(|| format!("case {c:?}: expected PHOTONS@WIDTHxHEIGHT"))?;
            let (width, height) = crate::parse_resolution(r).map_err(|e| format!("case {c:?}: {e}"))?;
            Ok(Case {
                photons: parse_count(p).map_err(|e| format!("case {c:?}: {e}"))?,
                width,
                height,
            })
        })
        .collect::<Result<_, String>>()?;
    Ok(Cases(cases))
}

/// bench.json (schema ppm-vk-bench/1).
#[derive(Serialize)]
struct BenchDoc {
    schema: &'static str,
    device: DeviceDoc,
    git_revision: &'static str,
    scene: String,
    mode: Mode,
    probe: ProbeMode,
    cone_k: Option<f32>,
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
    photons_per_pass: u32,
    width: u32,
    height: u32,
    hit_points: u32,
    records_per_pass: f64,
    batches_per_pass: u32,
    ray_ms: f64,
    stage_ms_median: BTreeMap<&'static str, f64>,
    pass_wall_ms_median: f64,
    pass_wall_ms_all: Vec<f64>,
    resolve_ms_median: f64,
    photons_per_second: f64,
    photon_stage_ns_per_photon: f64,
    photon_breakdown: Vec<BreakdownResult>,
    bvh: BvhResult,
    device_memory: DeviceMemoryResult,
    host_rss: HostRssResult,
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
fn print_breakdown(variants: &[ppm_vk_engine::PhotonVariant]) {
    let Some(ceiling) = variants
        .iter()
        .find(|v| v.name == "trace only")
        .map(|v| v.steps_per_second())
    else {
        return;
    };
    for v in variants {
        println!(
            "    photon kernel, {:<16} {:>8.1} ms for {} photons, {:>6.2} M intersections, {:>6.1} M/s, {:>5.1}% of trace only",
            v.name,
            v.gpu_ms,
            v.photons,
            v.steps as f64 / 1e6,
            v.steps_per_second() / 1e6,
            100.0 * v.steps_per_second() / ceiling
        );
    }
}

pub fn run(args: BenchArgs) -> Result<()> {
    let cases = &args.cases.0;
    let mode = Mode::from(args.mode);
    let loading = std::time::Instant::now();
    let base = crate::load_scene(&args.scene, &args.defines)?;
    let load_s = loading.elapsed().as_secs_f64();
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
    println!(
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
    let mut results = Vec::new();
    for case in cases {
        let scene = base.with_resolution(case.width, case.height);
        let settings = Settings {
            photons_per_pass: case.photons,
            mode,
            probe: args.probe.into(),
            cone_k: args.cone.0,
            ..Settings::default()
        };
        ctx.reset_memory_peak();
        reset_peak_rss();
        let mut renderer = Renderer::new(&ctx, &scene, settings)?;
        let bvh = renderer.bvh_stats().clone();
        if bvh.triangles > 0 && results.is_empty() {
            println!(
                "scene: {} triangles loaded in {:.2} s; BVH built in {:.2} s ({:.2} M triangles/s), {} nodes, depth {}, {:.1} MiB",
                bvh.triangles,
                load_s,
                bvh.build_seconds,
                bvh.triangles as f64 / bvh.build_seconds.max(1e-9) / 1e6,
                bvh.nodes,
                bvh.depth,
                mib((bvh.nodes * 32 + bvh.triangles * 48) as u64)
            );
        }
        for _ in 0..args.warmup {
            renderer.pass()?;
        }
        // Memory after the warm-up and after the measured passes: nothing should grow with passes.
        let (dev_before, rss_before) = (ctx.memory_usage(), host_rss());
        let measured: Vec<PassStats> = (0..args.passes).map(|_| renderer.pass()).collect::<Result<_, _>>()?;
        let (dev_after, rss_after) = (ctx.memory_usage(), host_rss());
        renderer.resolve()?; // the first resolve compiles its pipeline
        let resolve_ms = median((0..3).map(|_| renderer.resolve()).collect::<Result<Vec<_>, _>>()?);
        let breakdown = match args.breakdown {
            true => renderer.photon_breakdown(case.photons)?,
            false => Vec::new(),
        };
        let stage: Vec<f64> = STAGES
            .iter()
            .map(|s| median(measured.iter().map(|p| p.stage_ms(s)).collect()))
            .collect();
        let wall = median(measured.iter().map(|p| p.wall_ms).collect());
        let rate = case.photons as f64 / (wall * 1e-3) / 1e6;
        let records = median(measured.iter().map(|p| p.records as f64).collect());
        let rss_peak = rss_after.map(|r| r.1);
        println!(
            "{:>10} {:>11} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>11.3} {:>9.1} {:>9.0} {:>9}",
            case.photons,
            format!("{}x{}", case.width, case.height),
            renderer.ray_ms(),
            stage[0],
            stage[1],
            stage[2],
            stage[3],
            stage[4],
            wall,
            rate,
            resolve_ms,
            mib(dev_after.peak_reserved_bytes),
            rss_peak.map_or("-".to_string(), |b| format!("{:.0}", mib(b)))
        );
        print_breakdown(&breakdown);
        results.push(CaseResult {
            photons_per_pass: case.photons,
            width: case.width,
            height: case.height,
            hit_points: renderer.active_hit_points(),
            records_per_pass: records,
            batches_per_pass: measured.last().map_or(0, |p| p.batches),
            ray_ms: renderer.ray_ms(),
            stage_ms_median: STAGES.iter().copied().zip(stage.iter().copied()).collect(),
            pass_wall_ms_median: wall,
            pass_wall_ms_all: measured.iter().map(|p| p.wall_ms).collect(),
            resolve_ms_median: resolve_ms,
            photons_per_second: rate * 1e6,
            photon_stage_ns_per_photon: stage[1] * 1e6 / case.photons as f64,
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
                bytes: bvh.nodes * 32 + bvh.triangles * 48,
            },
            device_memory: DeviceMemoryResult {
                peak_reserved_bytes: dev_after.peak_reserved_bytes,
                in_use_bytes_after_warmup: dev_before.in_use_bytes,
                in_use_bytes_after_measured: dev_after.in_use_bytes,
            },
            host_rss: HostRssResult {
                peak_bytes: rss_peak,
                bytes_after_warmup: rss_before.map(|r| r.0),
                bytes_after_measured: rss_after.map(|r| r.0),
            },
        });
        crate::check_validation(&ctx)?;
    }
    let doc = BenchDoc {
        schema: "ppm-vk-bench/1",
        device: DeviceDoc {
            name: info.name,
            kind: info.kind,
            driver: info.driver,
            api: info.api_version,
        },
        git_revision: env!("PPM_VK_GIT_REV"),
        scene: args.scene.display().to_string(),
        mode,
        probe: args.probe.into(),
        cone_k: args.cone.0,
        warmup_passes: args.warmup,
        measured_passes: args.passes,
        cases: results,
    };
    std::fs::write(&args.json, serde_json::to_string_pretty(&doc)?)
        .with_context(|| format!("writing {}", args.json.display()))?;
    println!("wrote {}", args.json.display());
    Ok(())
}

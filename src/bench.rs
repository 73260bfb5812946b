//! `ppm-vk bench`: a fixed, documented set of cases, each rendered for a few warm-up passes (excluded:
//! they include the pipelines' first-dispatch compile) and then timed over measured passes. Reports the
//! median per stage (GPU timestamps) and of the wall time per pass, prints a table and writes JSON.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;
use ppm_vk_engine::{Mode, PassStats, Renderer, Scene, Settings};
use serde_json::json;

use crate::DeviceArgs;

#[derive(Args)]
pub struct BenchArgs {
    /// Scene to benchmark.
    #[arg(long, default_value = "scenes/cornell-spheres.toml")]
    scene: PathBuf,
    /// Cases as PHOTONS@WIDTHxHEIGHT, comma-separated (photon counts accept k and M suffixes).
    #[arg(long, default_value = "100k@512x512,1M@512x512")]
    cases: String,
    /// Passes run before timing starts.
    #[arg(long, default_value_t = 2)]
    warmup: u32,
    /// Passes timed per case (the median is reported).
    #[arg(long, default_value_t = 5)]
    passes: u32,
    /// `ppm` or `sppm` (SPPM adds an eye pass to every pass).
    #[arg(long, default_value = "sppm")]
    mode: String,
    /// Where to write the JSON results.
    #[arg(long, default_value = "bench.json")]
    json: PathBuf,
    #[command(flatten)]
    device: DeviceArgs,
}

struct Case {
    photons: u32,
    width: u32,
    height: u32,
}

fn parse_count(s: &str) -> Result<u32> {
    let s = s.trim();
    let (num, mul) = match s.chars().last() {
        Some('k') | Some('K') => (&s[..s.len() - 1], 1e3),
        Some('m') | Some('M') => (&s[..s.len() - 1], 1e6),
        _ => (s, 1.0),
    };
    let v: f64 = num.parse().map_err(|e| anyhow::anyhow!("photon count {s:?}: {e}"))?;
    let v = v * mul;
    if !(v >= 1.0 && v <= u32::MAX as f64) {
        bail!("photon count {s:?} out of range");
    }
    Ok(v as u32)
}

fn parse_cases(s: &str) -> Result<Vec<Case>> {
    s.split(',')
        .map(|c| {
            let (p, r) = c.split_once('@').ok_or_else(|| anyhow::anyhow!("case {c:?}: expected PHOTONS@WxH"))?;
            let (w, h) = r.split_once('x').ok_or_else(|| anyhow::anyhow!("case {c:?}: expected PHOTONS@WxH"))?;
            Ok(Case { photons: parse_count(p)?, width: w.trim().parse()?, height: h.trim().parse()? })
        })
        .collect()
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

pub fn run(args: BenchArgs) -> Result<()> {
    if args.passes == 0 {
        bail!("--passes must be at least 1");
    }
    let cases = parse_cases(&args.cases)?;
    let mode = match args.mode.as_str() {
        "ppm" => Mode::Ppm,
        "sppm" => Mode::Sppm,
        other => bail!("--mode {other:?}: expected ppm or sppm"),
    };
    let base = Scene::load(&args.scene)?;
    let ctx = args.device.open()?;
    let info = ctx.info().clone();
    println!("device: {} ({}, {})", info.name, info.kind, info.driver);
    println!(
        "{:>10} {:>11} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>11} {:>9}",
        "photons", "resolution", "first ray", "ray", "photon", "lookup", "gather", "update", "pass ms", "M photons/s", "resolve"
    );
    let mut results = Vec::new();
    for case in &cases {
        let scene = base.with_resolution(case.width, case.height);
        let settings = Settings { photons_per_pass: case.photons, mode, ..Settings::default() };
        let mut renderer = Renderer::new(&ctx, &scene, settings)?;
        for _ in 0..args.warmup {
            renderer.pass()?;
        }
        let measured: Vec<PassStats> = (0..args.passes).map(|_| renderer.pass()).collect::<Result<_>>()?;
        renderer.resolve()?; // the first resolve compiles its pipeline
        let resolve_ms = median((0..3).map(|_| renderer.resolve()).collect::<Result<Vec<_>>>()?);
        let stage: Vec<f64> = STAGES.iter().map(|s| median(measured.iter().map(|p| p.stage_ms(s)).collect())).collect();
        let wall = median(measured.iter().map(|p| p.wall_ms).collect());
        let rate = case.photons as f64 / (wall * 1e-3) / 1e6;
        let records = median(measured.iter().map(|p| p.records as f64).collect());
        println!(
            "{:>10} {:>11} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>11.3} {:>9.1}",
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
            resolve_ms
        );
        results.push(json!({
            "photons_per_pass": case.photons,
            "width": case.width,
            "height": case.height,
            "hit_points": renderer.active_hit_points(),
            "records_per_pass": records,
            "batches_per_pass": measured.last().map(|p| p.batches).unwrap_or(0),
            "ray_ms": renderer.ray_ms(),
            "stage_ms_median": STAGES.iter().zip(&stage).map(|(k, v)| (k.to_string(), json!(v))).collect::<serde_json::Map<_, _>>(),
            "pass_wall_ms_median": wall,
            "pass_wall_ms_all": measured.iter().map(|p| p.wall_ms).collect::<Vec<_>>(),
            "resolve_ms_median": resolve_ms,
            "photons_per_second": rate * 1e6,
        }));
        crate::check_validation(&ctx)?;
    }
    let doc = json!({
        "schema": "ppm-vk-bench/1",
        "device": { "name": info.name, "kind": info.kind, "driver": info.driver, "api": info.api_version },
        "git_revision": env!("PPM_VK_GIT_REV"),
        "scene": args.scene.display().to_string(),
        "mode": args.mode,
        "warmup_passes": args.warmup,
        "measured_passes": args.passes,
        "cases": results,
    });
    std::fs::write(&args.json, serde_json::to_string_pretty(&doc)?)
        .map_err(|e| anyhow::anyhow!("writing {}: {e}", args.json.display()))?;
    println!("wrote {}", args.json.display());
    Ok(())
}

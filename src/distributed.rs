//! `render --worker K --of N` (one worker's part of a render) and `merge` (parts into the image):
//! docs/distributed.md.

use std::path::PathBuf;
use std::sync::atomic::Ordering;

use anyhow::{bail, Context as _, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use ppm_vk_engine::distributed::{merge, render_part, Job, Method, Part};
use ppm_vk_engine::metrics::{compare, ErrorStats, Reference, Region};
use ppm_vk_engine::CancelToken;

use crate::{outputs, save_pipeline_cache, watch_signals, Ended, RenderArgs, BUILD};

/// `--method`: how the workers split the render.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum MethodArg {
    /// Probabilistic PPM: worker K renders passes K, K+N, ...; merged, one machine's image bit for bit.
    Probabilistic,
    /// Independent progressive renders with their own seeds, averaged.
    Independent,
}

impl From<MethodArg> for Method {
    fn from(m: MethodArg) -> Method {
        match m {
            MethodArg::Probabilistic => Method::Probabilistic,
            MethodArg::Independent => Method::Independent,
        }
    }
}

/// `--out` of a worker: a part file, never an image (`merge` makes the image).
fn part_path(args: &RenderArgs, scene_name: &str, job: &Job) -> Result<PathBuf> {
    let path = match &args.out {
        Some(p) => p.clone(),
        None => PathBuf::from(format!("{scene_name}.worker-{}-of-{}.part", job.worker, job.of)),
    };
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    if matches!(ext.as_deref(), Some("exr") | Some("png")) {
        bail!(
            "--out {}: a worker writes a part for `ppm-vk merge`, not an image (name it .part)",
            path.display()
        );
    }
    if !args.force && path.exists() {
        bail!("{} exists: not overwritten (pass --force to overwrite)", path.display());
    }
    Ok(path)
}

/// `render --worker K --of N`: renders worker K's passes and writes its part.
pub(crate) fn render_worker(args: RenderArgs, worker: u32, of: u32) -> Result<Ended> {
    let cancel = CancelToken::new();
    let signal = watch_signals(Some(cancel.clone()))?;
    let scene = args.settings.load_scene(&args.scene, &args.defines)?;
    let settings = args.settings.settings(1_000_000)?;
    let job = Job {
        method: args.method.unwrap_or(MethodArg::Probabilistic).into(),
        worker,
        of,
        passes: args.passes.unwrap_or(100),
    };
    job.validate()?;
    let out = part_path(&args, &scene.name, &job)?;
    let ctx = args.device.open()?;
    let info = ctx.info().clone();
    eprintln!("device: {} ({}, {})", info.name, info.kind, info.driver);
    let bar = ProgressBar::new(job.passes);
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} passes {msg} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let started = std::time::Instant::now();
    let part = render_part(&ctx, &scene, &settings, &job, BUILD, Some(cancel), |s| {
        bar.inc(1);
        bar.set_message(format!("(pass {} of the render, {:.1} ms)", s.index - 1, s.wall_ms));
    });
    bar.finish_and_clear();
    save_pipeline_cache(&ctx);
    let part = match part {
        Err(ppm_vk_engine::Error::Cancelled) if signal.load(Ordering::SeqCst) != 0 => {
            eprintln!("interrupted: a part holds all of a worker's passes or none; nothing written");
            return Ok(Ended::Signal(signal.load(Ordering::SeqCst) as i32));
        }
        other => other?,
    };
    part.save(&out)?;
    crate::check_validation(&ctx)?;
    println!(
        "worker {worker} of {of} ({:?}): {} passes of {} photons in {:.2} s -> {}",
        job.method,
        job.passes,
        settings.photons_per_pass,
        started.elapsed().as_secs_f64(),
        out.display()
    );
    Ok(Ended::Done)
}

#[derive(Args)]
pub struct MergeArgs {
    /// Part files written by `ppm-vk render --worker K --of N` (any order; each worker at most once).
    #[arg(required = true)]
    parts: Vec<PathBuf>,
    /// Output image: .exr (linear HDR) or .png (tone-mapped sRGB).
    #[arg(long, short)]
    out: PathBuf,
    /// Overwrite the output image if it exists.
    #[arg(long, short)]
    force: bool,
    /// Reference image (EXR) to measure the merged image's error against.
    #[arg(long)]
    reference: Option<PathBuf>,
    /// A region to score on its own against --reference, NAME:X0,Y0,W,H in the reference's pixels
    /// (origin top left); repeatable.
    #[arg(long = "region", value_parser = crate::parse_region, requires = "reference")]
    regions: Vec<Region>,
    /// Write what was merged (and the error, with --reference) as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// What `merge --json` writes.
#[derive(serde::Serialize)]
struct MergeRecord {
    parts: Vec<String>,
    info: ppm_vk_engine::distributed::MergeInfo,
    out: String,
    error: Option<ErrorStats>,
    region_errors: std::collections::BTreeMap<String, ErrorStats>,
}

/// `merge`: the parts into one image.
pub fn run(args: MergeArgs) -> Result<()> {
    let out = outputs(&Some(args.out.clone()), "", args.force)?.remove(0);
    let reference = match &args.reference {
        Some(p) => Some(Reference::load(p)?),
        None => None,
    };
    let parts: Vec<Part> = args.parts.iter().map(|p| Part::load(p)).collect::<Result<_>>()?;
    let (image, info) = merge(&parts).with_context(|| {
        let names: Vec<String> = args.parts.iter().map(|p| p.display().to_string()).collect();
        format!("cannot merge {}", names.join(", "))
    })?;
    image.save(&out)?;
    println!(
        "merged workers {:?} of {} ({:?}): {} passes, {} photons -> {}",
        info.workers,
        info.of,
        info.method,
        info.passes,
        info.photons,
        out.display()
    );
    if !info.missing.is_empty() {
        eprintln!(
            "warning: workers {:?} of {} were not given: the image has {} of the render's passes",
            info.missing, info.of, info.passes
        );
    }
    let error = match &reference {
        Some(r) => {
            let e = compare(&image, r, None, true)?;
            println!(
                "error vs reference (its own noise removed): RMSE {:.4}, relMSE {:.5}, bias {:+.4}",
                e.rmse, e.rel_mse, e.mean_bias
            );
            Some(e)
        }
        None => None,
    };
    let mut region_errors = std::collections::BTreeMap::new();
    if let Some(r) = &reference {
        for region in &args.regions {
            let e = compare(&image, r, Some(region), true)?;
            println!(
                "  {:<12} RMSE {:.4}, relMSE {:.5}, bias {:+.4}",
                region.name, e.rmse, e.rel_mse, e.mean_bias
            );
            region_errors.insert(region.name.clone(), e);
        }
    }
    if let Some(path) = &args.json {
        let record = MergeRecord {
            parts: args.parts.iter().map(|p| p.display().to_string()).collect(),
            info,
            out: out.display().to_string(),
            error,
            region_errors,
        };
        let text = serde_json::to_string_pretty(&record).context("encoding the merge record")?;
        std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

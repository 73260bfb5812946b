//! `ppm-vk compare`: renders variants of one scene for the same wall time each, one after another on the
//! same device, and scores each against a reference image. Writes a Markdown table, JSON, every image and
//! side-by-side crops of the regions that tell the variants apart.
//!
//! A variant is `+`-joined words: `ppm` (plain) or `sppm` (stochastic), `probe` (eq. 9 as printed), `probe-sf` (scale-free),
//! `cone` (k = 1.1) or `cone=K`, `beta=F` (fraction of r), `alpha=A`. The clock of a variant starts before
//! its renderer is made, so the probe pass and kernel compilation count against it. The error is also
//! sampled at roughly logarithmic times for the error-against-time plot; those evaluations (an image
//! read back and compared) are timed and left out of the variant's clock.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{bail, Context as _, Result};
use clap::Args;
use ppm_vk_engine::metrics::{compare, cornell_regions, ErrorStats, Reference, Region};
use ppm_vk_engine::{Mode, ProbeMode, Renderer, RgbImage, Settings};
use serde_json::json;

use crate::DeviceArgs;

#[derive(Args)]
pub struct CompareArgs {
    /// Scene file.
    scene: PathBuf,
    /// Override a Mitsuba scene's parameter: `-D name=value` sets what `$name` stands for (repeatable).
    #[arg(short = 'D', long = "define", value_name = "NAME=VALUE", value_parser = ppm_vk_engine::scene::parse_define)]
    pub defines: Vec<(String, String)>,
    /// Reference image (EXR, full resolution; a `_var.exr` beside it is used to remove its noise).
    #[arg(long)]
    reference: PathBuf,
    /// Wall-clock seconds per variant, setup included.
    #[arg(long, default_value_t = 10.0)]
    time: f64,
    /// Variants separated by `;` or `,`, e.g. "ppm; ppm+probe; ppm+cone; ppm+probe-sf+cone". Words joined by
    /// `+`: ppm, sppm, probe, probe-sf, cone[=K], beta=F, alpha=A, es=N (emission samples per pixel and pass).
    #[arg(long, default_value = "ppm; ppm+probe; ppm+probe-sf; ppm+cone; ppm+probe+cone; ppm+probe-sf+cone")]
    variants: String,
    /// Photons per pass.
    #[arg(long, default_value_t = 1_000_000)]
    photons_per_pass: u32,
    /// Override the scene's resolution, e.g. 256x256.
    #[arg(long, value_parser = crate::parse_resolution)]
    resolution: Option<(u32, u32)>,
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Folder for the table, JSON, images and crops.
    #[arg(long, default_value = "compare-out")]
    out: PathBuf,
    #[command(flatten)]
    device: DeviceArgs,
}

struct Variant {
    name: String,
    settings: Settings,
}

fn parse_variant(text: &str, base: &Settings) -> Result<Variant> {
    let name = text.trim().to_string();
    let mut s = base.clone();
    for word in name.split('+').map(str::trim) {
        let (key, value) = match word.split_once('=') {
            Some((k, v)) => (k, Some(v)),
            None => (word, None),
        };
        let number = |what: &str| -> Result<f32> {
            value
                .ok_or_else(|| anyhow::anyhow!("variant {name:?}: {what} needs a value ({what}=...)"))?
                .parse::<f32>()
                .with_context(|| format!("variant {name:?}: {word}"))
        };
        match key {
            "ppm" => s.mode = Mode::Ppm,
            "sppm" => s.mode = Mode::Sppm,
            "probe" => s.probe = ProbeMode::Paper,
            "probe-sf" => s.probe = ProbeMode::ScaleFree,
            "cone" => s.cone_k = Some(if value.is_some() { number("cone")? } else { 1.1 }),
            "beta" => s.probe_beta = number("beta")?,
            "alpha" => s.alpha = number("alpha")?,
            "es" => {
                let e = number("es")?;
                if !(e >= 0.0 && e.fract() == 0.0) {
                    bail!("variant {name:?}: es (emission samples) must be a whole number, got {e}");
                }
                s.emission_samples = e as u32;
            }
            other => bail!(
                "variant {name:?}: unknown word {other:?} (ppm, sppm, probe, probe-sf, cone[=K], beta=F, alpha=A, es=N)"
            ),
        }
    }
    s.validate().with_context(|| format!("variant {name:?}"))?;
    Ok(Variant { name, settings: s })
}

fn file_name(variant: &str) -> String {
    variant.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '.' { c } else { '_' }).collect()
}

pub fn run(args: CompareArgs) -> Result<()> {
    if !(args.time.is_finite() && args.time > 0.0) {
        bail!("--time must be a positive number of seconds");
    }
    let mut scene = crate::load_scene(&args.scene, &args.defines)?;
    if let Some((w, h)) = args.resolution {
        scene = scene.with_resolution(w, h);
    }
    let reference = Reference::load(&args.reference)?;
    let base = Settings { photons_per_pass: args.photons_per_pass, seed: args.seed, ..Settings::default() };
    let variants: Vec<Variant> =
        args.variants.split([';', ',']).filter(|v| !v.trim().is_empty()).map(|v| parse_variant(v, &base)).collect::<Result<_>>()?;
    if variants.is_empty() {
        bail!("--variants names no variant");
    }
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let regions: Vec<Region> = if scene.name == "cornell-spheres" { cornell_regions() } else { Vec::new() };
    let ctx = args.device.open()?;
    let info = ctx.info().clone();
    eprintln!("device: {} ({}); {} s per variant", info.name, info.driver, args.time);

    let budget = Duration::from_secs_f64(args.time);
    let mut rows = Vec::new();
    let mut images: Vec<(String, RgbImage)> = Vec::new();
    let mut curves = Vec::new();
    for v in &variants {
        let start = Instant::now();
        let mut renderer = Renderer::new(&ctx, &scene, v.settings.clone())?;
        let setup_s = start.elapsed().as_secs_f64();
        // The variant's clock: wall time less the time spent measuring its error along the way.
        let mut excluded = Duration::ZERO;
        let clock = |excluded: Duration| start.elapsed().saturating_sub(excluded);
        let mut next_sample = 0.5f64;
        let mut curve = Vec::new();
        while clock(excluded) < budget {
            renderer.pass()?;
            let t = clock(excluded).as_secs_f64();
            if t >= next_sample && clock(excluded) < budget {
                let t0 = Instant::now();
                curve.push((t, compare(&renderer.image()?, &reference, None, true)?.rel_mse));
                excluded += t0.elapsed();
                next_sample = t * 1.25;
            }
        }
        let image = renderer.image()?;
        let wall = clock(excluded).as_secs_f64();
        curve.push((wall, compare(&image, &reference, None, true)?.rel_mse));
        let stem = args.out.join(file_name(&v.name));
        image.save(&stem.with_extension("exr"))?;
        image.save(&stem.with_extension("png"))?;
        let whole = compare(&image, &reference, None, true)?;
        let per_region: Vec<(String, ErrorStats)> =
            regions.iter().map(|r| Ok((r.name.clone(), compare(&image, &reference, Some(r), true)?))).collect::<Result<_>>()?;
        eprintln!("{:<24} {:>4} passes, RMSE {:.4}, relMSE {:.5}", v.name, renderer.passes(), whole.rmse, whole.rel_mse);
        rows.push(json!({
            "variant": v.name,
            "settings": v.settings,
            "wall_s": wall,
            "setup_s": setup_s,
            "passes": renderer.passes(),
            "photons": renderer.emitted(),
            "whole": whole,
            "regions": per_region.iter().map(|(n, e)| (n.clone(), json!(e))).collect::<serde_json::Map<_, _>>(),
            "probe": renderer.probe_report(),
            "rel_mse_curve": curve,
        }));
        curves.push(crate::plot::Series { name: v.name.clone(), points: curve });
        images.push((v.name.clone(), image));
        crate::check_validation(&ctx)?;
    }

    // The table: whole image and each region, RMSE / relMSE.
    let mut md = format!(
        "{} at {}x{}, {} s per variant (setup included), {} photons/pass, on {}; error against {} with its own noise removed.\n\n",
        scene.name,
        scene.camera.width,
        scene.camera.height,
        args.time,
        args.photons_per_pass,
        info.name,
        args.reference.display()
    );
    md += "| variant | passes | RMSE | relMSE |";
    for r in &regions {
        md += &format!(" {} RMSE | {} relMSE |", r.name, r.name);
    }
    md += "\n|---|---|---|---|";
    md += &"---|---|".repeat(regions.len());
    md += "\n";
    for row in &rows {
        md += &format!(
            "| {} | {} | {:.4} | {:.5} |",
            row["variant"].as_str().unwrap_or(""),
            row["passes"],
            row["whole"]["rmse"].as_f64().unwrap_or(f64::NAN),
            row["whole"]["rel_mse"].as_f64().unwrap_or(f64::NAN)
        );
        for r in &regions {
            let e = &row["regions"][&r.name];
            md += &format!(" {:.4} | {:.5} |", e["rmse"].as_f64().unwrap_or(f64::NAN), e["rel_mse"].as_f64().unwrap_or(f64::NAN));
        }
        md += "\n";
    }
    std::fs::write(args.out.join("compare.md"), &md)?;
    std::fs::write(
        args.out.join("compare.json"),
        serde_json::to_string_pretty(&json!({
            "schema": "ppm-vk-compare/1",
            "scene": args.scene.display().to_string(),
            "device": { "name": info.name, "driver": info.driver },
            "git_revision": env!("PPM_VK_GIT_REV"),
            "time_s": args.time,
            "photons_per_pass": args.photons_per_pass,
            "variants": rows,
        }))?,
    )?;
    // Crops: each region of each variant side by side, the reference last (at the image's resolution).
    let (w, h) = (images[0].1.width, images[0].1.height);
    let reference_image = reference.at_resolution(w, h)?.image;
    let scale = reference.image.width / w.max(1);
    for r in regions.iter().filter(|r| r.name == "caustic" || r.name == "shadow_edge") {
        let (x0, y0, cw, ch) = (r.x0 / scale, r.y0 / scale, (r.w / scale).max(1), (r.h / scale).max(1));
        let mut crops: Vec<RgbImage> = images.iter().map(|(_, im)| im.crop(x0, y0, cw, ch)).collect::<Result<_>>()?;
        crops.push(reference_image.crop(x0, y0, cw, ch)?);
        let refs: Vec<&RgbImage> = crops.iter().collect();
        // Enlarged 4x and 2 stops darker, so the caustic's structure is not clipped away.
        RgbImage::hstack(&refs)?.upscale(4)?.save_png(&args.out.join(format!("crops-{}.png", r.name)), -2.0)?;
    }
    let title = format!("{} {}x{}, {} photons/pass, {}", scene.name, scene.camera.width, scene.camera.height, args.photons_per_pass, info.name);
    match crate::plot::error_plot(&args.out.join("error-vs-time.png"), &title, "relMSE vs reference", &curves) {
        Ok(()) => {}
        Err(e) => eprintln!("warning: no plot: {e:#} (the table, JSON and images are written)"),
    }
    println!("{md}");
    println!(
        "crops (left to right: {}, reference) and images in {}",
        images.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>().join(", "),
        args.out.display()
    );
    Ok(())
}

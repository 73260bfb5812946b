//! `ppm-vk compare`: renders variants of one scene for the same wall time each, one after another on the
//! same device, and scores each against a reference image. Writes a Markdown table, JSON, every image and
//! side-by-side crops of the regions that tell the variants apart.
//!
//! A variant is `+`-joined words over the default settings (whose probe is the curvature rule):
//! `ppm` or `sppm` (stochastic), `noprobe` (eq. 8's radius), `probe` (eq. 9 as printed), `probe-sf` (scale-free),
//! `cone` (k = 1.1) or `cone=K`, `beta=F` (fraction of r), `alpha=A`. `--time` means what it means for
//! `render`: the passes' wall time, set-up excluded (kernel compilation, the BVH and the probe pass,
//! reported apart as `setup_s`), so each variant gets the same time to render in. The error is also
//! sampled at roughly logarithmic times for the error-against-time plot; those evaluations (an image
//! read back and compared) are timed and left out of the variant's clock.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{bail, Context as _, Result};
use clap::Args;
use ppm_vk_engine::metrics::{compare, ErrorStats, Reference};
use ppm_vk_engine::{Mode, ProbeMode, ProbeReport, Renderer, RgbImage, Settings};
use serde::Serialize;

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
    /// Seconds each variant renders for: the passes' wall time, as for `render --time` (set-up, i.e.
    /// kernel compilation, the BVH and the probe pass, is excluded and reported apart; the error
    /// evaluations for the plot are excluded too). The last pass started in time finishes.
    #[arg(long, default_value_t = 10.0, value_parser = crate::parse_seconds)]
    time: f64,
    /// Variants separated by `;` or `,`, e.g. "ppm; ppm+probe; ppm+cone; ppm+probe-sf+cone". Words joined by
    /// `+`: ppm, sppm, noprobe (every radius eq. 8's; the default is the curvature probe, probe-curv=1), probe, probe-sf, probe-nn[=K] (the k-nearest probe), probe-curv[=G] (the curvature probe, growing radii at most G times), pp=N (photons of the probe pass), cone[=K], beta=F, alpha=A, shrink=Z (the adaptive shrink's significance; noshrink: off), aim=S (the share of photons aimed at caustics), es=N (emission samples per pixel and pass), ps=N (the pilot's), rsp=N (where a rough lobe is seen),
    /// rs=N (SPPM: lobe directions at the first rough vertex), gs=N (SPPM: Fresnel splits at smooth glass), gh=A (glossy hit points on rough conductors of alpha >= A), nogh (none), photons (direct light by the photons) or
    /// sample (by light sampling, the default), ls=N (light samples), gl=mis|bsdf|lights (the light rough
    /// vertices reflect straight from a light: both strategies, the default, or one of them).
    #[arg(
        long,
        default_value = "ppm+noprobe; ppm+probe; ppm+probe-sf; ppm+noprobe+cone; ppm+probe+cone; ppm+probe-sf+cone"
    )]
    variants: String,
    /// Photons per pass.
    #[arg(long, default_value_t = 1_000_000, value_parser = clap::value_parser!(u32).range(1..))]
    photons_per_pass: u32,
    /// Override the scene's resolution, e.g. 256x256 (each side 1..=16384; the reference's must be a
    /// whole multiple of it).
    #[arg(long, value_parser = crate::parse_resolution)]
    resolution: Option<(u32, u32)>,
    /// Seed of all random streams (the same for every variant).
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Folder for the table (compare.md), JSON (compare.json), images, crops and the plot
    /// (error-vs-time.svg).
    #[arg(long, default_value = "compare-out")]
    out: PathBuf,
    /// Another renderer's errors, drawn as points on the plot for scale: a CSV file with one
    /// `seconds,rel_mse[,label]` line per point (relMSE against the same reference, its noise removed;
    /// the label, default "peer", names it in the legend). Lines starting with `#` are comments. Example:
    /// docs/peers/mitsuba-path-cornell-spheres.csv.
    #[arg(long, value_name = "FILE")]
    peer: Option<PathBuf>,
    #[command(flatten)]
    regions: crate::RegionArgs,
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
            "noprobe" => s.probe = ProbeMode::Off,
            "probe" => s.probe = ProbeMode::Paper,
            "probe-sf" => s.probe = ProbeMode::ScaleFree,
            "probe-nn" => {
                s.probe = ProbeMode::Nearest;
                if value.is_some() {
                    s.probe_k = number("probe-nn")?;
                }
            }
            "probe-curv" => {
                s.probe = ProbeMode::Curvature;
                if value.is_some() {
                    s.probe_grow = number("probe-curv")?;
                }
            }
            "pp" => {
                let text = value.ok_or_else(|| anyhow::anyhow!("variant {name:?}: pp needs a value (pp=...)"))?;
                let n = text
                    .parse::<u32>()
                    .with_context(|| format!("variant {name:?}: {word} (probe photons, a whole number)"))?;
                s.probe_photons = Some(n);
            }
            "cone" => s.cone_k = Some(if value.is_some() { number("cone")? } else { 1.1 }),
            "beta" => s.probe_beta = number("beta")?,
            "alpha" => s.alpha = number("alpha")?,
            "shrink" => s.shrink_z = number("shrink")?,
            "noshrink" => s.shrink_z = 0.0,
            "aim" => s.caustic_photons = number("aim")?,
            "es" | "ls" | "ps" | "rsp" => {
                let e = number(key)?;
                if !(e >= 0.0 && e.fract() == 0.0) {
                    bail!("variant {name:?}: {key} (emission, light, pilot or rough-pixel samples) must be a whole number, got {e}");
                }
                match key {
                    "es" => s.emission_samples = e as u32,
                    "ps" => s.pilot_samples = e as u32,
                    "rsp" => s.rough_samples = e as u32,
                    _ => s.light_samples = e as u32,
                }
            }
            "rs" => {
                let k = number("rs")?;
                if !(k >= 1.0 && k.fract() == 0.0) {
                    bail!("variant {name:?}: rs (rough splits) must be a whole number, got {k}");
                }
                s.rough_splits = k as u32;
            }
            "gs" => {
                let k = number("gs")?;
                if !(k >= 1.0 && k.fract() == 0.0) {
                    bail!("variant {name:?}: gs (glass splits) must be a whole number, got {k}");
                }
                s.glass_splits = k as u32;
            }
            "gh" => s.glossy_hits = Some(number("gh")?),
            "nogh" => s.glossy_hits = None,
            "photons" => s.direct = ppm_vk_engine::DirectLight::Photons,
            "sample" => s.direct = ppm_vk_engine::DirectLight::Sample,
            "gl" => {
                s.glossy_light = match value {
                    Some("mis") => ppm_vk_engine::GlossyLight::Mis,
                    Some("bsdf") => ppm_vk_engine::GlossyLight::Bsdf,
                    Some("lights") => ppm_vk_engine::GlossyLight::Lights,
                    _ => bail!("variant {name:?}: gl takes mis, bsdf or lights"),
                }
            }
            other => bail!(
                "variant {name:?}: unknown word {other:?} (ppm, sppm, noprobe, probe, probe-sf, probe-nn[=K], probe-curv[=G], pp=N, cone[=K], beta=F, alpha=A, \
                 shrink=Z, noshrink, aim=S, es=N, ps=N, rsp=N, ls=N, rs=N, gs=N, gh=A, nogh, photons, sample, gl=mis|bsdf|lights)"
            ),
        }
    }
    s.validate().with_context(|| format!("variant {name:?}"))?;
    Ok(Variant { name, settings: s })
}

fn file_name(variant: &str) -> String {
    variant
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// One variant's result, as compare.json writes it (schema ppm-vk-compare/1).
#[derive(Serialize)]
struct VariantResult {
    variant: String,
    settings: Settings,
    /// Seconds of passes (the variant's clock), and of set-up before them.
    wall_s: f64,
    setup_s: f64,
    passes: u64,
    photons: u64,
    whole: ErrorStats,
    regions: BTreeMap<String, ErrorStats>,
    probe: Option<ProbeReport>,
    /// (seconds, relMSE) along the way.
    rel_mse_curve: Vec<(f64, f64)>,
}

#[derive(Serialize)]
struct DeviceName {
    name: String,
    driver: String,
}

/// compare.json.
#[derive(Serialize)]
struct CompareDoc {
    schema: &'static str,
    scene: String,
    device: DeviceName,
    git_revision: &'static str,
    time_s: f64,
    photons_per_pass: u32,
    variants: Vec<VariantResult>,
}

pub fn run(args: CompareArgs) -> Result<()> {
    // A bad peer file is refused before any rendering.
    let peer = args.peer.as_deref().map(crate::plot::read_peer).transpose()?;
    let mut scene = crate::load_scene(&args.scene, &args.defines)?;
    if let Some((w, h)) = args.resolution {
        scene = scene.with_resolution(w, h);
    }
    let reference = Reference::load(&args.reference)?;
    let base = Settings {
        photons_per_pass: args.photons_per_pass,
        seed: args.seed,
        ..Settings::default()
    };
    let variants: Vec<Variant> = args
        .variants
        .split([';', ','])
        .filter(|v| !v.trim().is_empty())
        .map(|v| parse_variant(v, &base))
        .collect::<Result<_>>()?;
    if variants.is_empty() {
        bail!("--variants names no variant");
    }
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let regions = args.regions.resolve(&scene, &reference);
    let ctx = args.device.open()?;
    let info = ctx.info().clone();
    eprintln!("device: {} ({}); {} s per variant", info.name, info.driver, args.time);

    let budget = Duration::from_secs_f64(args.time);
    let mut rows = Vec::new();
    let mut images: Vec<(String, RgbImage)> = Vec::new();
    let mut curves = Vec::new();
    for v in &variants {
        let setup = Instant::now();
        let mut renderer = Renderer::new(&ctx, &scene, v.settings.clone())?;
        let setup_s = setup.elapsed().as_secs_f64();
        let start = Instant::now();
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
        // The extension appended, not set: `with_extension` would cut a name such as aim=0.25 at its dot.
        let stem = file_name(&v.name);
        image.save(args.out.join(format!("{stem}.exr")))?;
        image.save(args.out.join(format!("{stem}.png")))?;
        let whole = compare(&image, &reference, None, true)?;
        let per_region: Vec<(String, ErrorStats)> = regions
            .iter()
            .map(|r| Ok((r.name.clone(), compare(&image, &reference, Some(r), true)?)))
            .collect::<Result<_>>()?;
        eprintln!(
            "{:<24} {:>4} passes, RMSE {:.4}, relMSE {:.5}",
            v.name,
            renderer.passes(),
            whole.rmse,
            whole.rel_mse
        );
        curves.push(crate::plot::Series {
            name: v.name.clone(),
            points: curve.clone(),
        });
        rows.push(VariantResult {
            variant: v.name.clone(),
            settings: v.settings.clone(),
            wall_s: wall,
            setup_s,
            passes: renderer.passes(),
            photons: renderer.emitted(),
            whole,
            regions: per_region.into_iter().collect(),
            probe: renderer.probe_report().cloned(),
            rel_mse_curve: curve,
        });
        images.push((v.name.clone(), image));
        crate::check_validation(&ctx)?;
    }

    // The table: whole image and each region, RMSE / relMSE.
    let mut md = format!(
        "{} at {}x{}, {} s of passes per variant (set-up excluded), {} photons/pass, on {}; error against {} with its own noise removed.\n\n",
        scene.name,
        scene.camera.width,
        scene.camera.height,
        args.time,
        args.photons_per_pass,
        info.name,
        args.reference.display()
    );
    md += "| variant | set-up s | passes | RMSE | relMSE |";
    for r in &regions {
        md += &format!(" {} RMSE | {} relMSE |", r.name, r.name);
    }
    md += "\n|---|---|---|---|---|";
    md += &"---|---|".repeat(regions.len());
    md += "\n";
    for row in &rows {
        md += &format!(
            "| {} | {:.2} | {} | {:.4} | {:.5} |",
            row.variant, row.setup_s, row.passes, row.whole.rmse, row.whole.rel_mse
        );
        for e in regions.iter().filter_map(|r| row.regions.get(&r.name)) {
            md += &format!(" {:.4} | {:.5} |", e.rmse, e.rel_mse);
        }
        md += "\n";
    }
    let write = |name: &str, text: &str| {
        let path = args.out.join(name);
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))
    };
    write("compare.md", &md)?;
    let doc = CompareDoc {
        schema: "ppm-vk-compare/1",
        scene: args.scene.display().to_string(),
        device: DeviceName {
            name: info.name.clone(),
            driver: info.driver.clone(),
        },
        git_revision: env!("PPM_VK_GIT_REV"),
        time_s: args.time,
        photons_per_pass: args.photons_per_pass,
        variants: rows,
    };
    write("compare.json", &serde_json::to_string_pretty(&doc)?)?;
    // Crops: each region of each variant side by side, the reference last (at the image's resolution).
    let (w, h) = (images[0].1.width, images[0].1.height);
    let reference_image = reference.at_resolution(w, h)?.image;
    let scale = reference.image.width / w.max(1);
    for r in regions
        .iter()
        .filter(|r| r.name == "caustic" || r.name == "shadow_edge")
    {
        let (x0, y0, cw, ch) = (r.x0 / scale, r.y0 / scale, (r.w / scale).max(1), (r.h / scale).max(1));
        let mut crops: Vec<RgbImage> = images
            .iter()
            .map(|(_, im)| im.crop(x0, y0, cw, ch))
            .collect::<Result<_>>()?;
        crops.push(reference_image.crop(x0, y0, cw, ch)?);
        let refs: Vec<&RgbImage> = crops.iter().collect();
        // Enlarged 4x and 2 stops darker, so the caustic's structure is not clipped away.
        RgbImage::hstack(&refs)?
            .upscale(4)?
            .save_png(args.out.join(format!("crops-{}.png", r.name)), -2.0)?;
    }
    let title = format!(
        "{} {}x{}, {} photons/pass, {}",
        scene.name, scene.camera.width, scene.camera.height, args.photons_per_pass, info.name
    );
    let plot = args.out.join("error-vs-time.svg");
    crate::plot::error_plot(
        &plot,
        &title,
        "relMSE vs reference",
        &curves,
        peer.as_deref().unwrap_or_default(),
    )?;
    println!("{md}");
    println!(
        "crops (left to right: {}, reference) and images in {}",
        images.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>().join(", "),
        args.out.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variant_words_set_their_fields() {
        let base = Settings::default();
        let v = parse_variant("sppm+noprobe+es=2", &base).unwrap();
        assert_eq!((v.settings.mode, v.settings.probe), (Mode::Sppm, ProbeMode::Off));
        assert_eq!(v.settings.emission_samples, 2);
        let v = parse_variant("probe-curv=1.5+pp=4000000", &base).unwrap();
        assert_eq!(v.settings.probe, ProbeMode::Curvature);
        assert_eq!(
            (v.settings.probe_grow, v.settings.probe_photons),
            (1.5, Some(4_000_000))
        );
    }

    #[test]
    fn bad_variant_words_say_which() {
        let base = Settings::default();
        for (text, says) in [
            ("sppm+pp", "pp needs a value"),
            ("sppm+pp=2.5", "probe photons, a whole number"),
            ("sppm+pp=0", "probe_photons"),
            ("sppm+nope", "unknown word \"nope\""),
        ] {
            let e = format!("{:#}", parse_variant(text, &base).err().unwrap());
            assert!(e.contains(says), "{text}: {e}");
        }
    }
}

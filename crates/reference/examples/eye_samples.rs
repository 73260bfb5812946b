//! What the eye pass's per-pixel sample counts cost lavapipe: after a scene's pilot, each pixel's count of
//! emission and light-sampling paths (`samples_for_mark` of its mark, ray.comp's rule) summed, against what
//! SIMD groups of 8 neighbouring pixels pay for them (each group runs its largest count in every lane), and
//! what they would pay sorted by count. Prints a line per scene: the counts' histogram, the two sums and
//! their ratio (docs/performance.md, "Issue 39: the interior and the mesh ladder, before and after").
//!
//! cargo run --release -p ppm-vk-reference --example eye_samples -- [--resolution WxH] SCENE...

use anyhow::{Context as _, Result};
use ppm_vk_engine::{open_device, ContextOptions, DirectLight, Renderer, Scene, Settings};
use ppm_vk_reference::samples_for_mark;

/// Lanes of a SIMD group on lavapipe with 256-bit vectors (ray.comp's pixels run a row's neighbours in one).
const LANES: usize = 8;

fn main() -> Result<()> {
    let (mut resolution, mut scenes) = ((512u32, 512u32), Vec::new());
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--resolution" => {
                let v = args.next().context("--resolution needs WxH")?;
                let (w, h) = v
                    .split_once('x')
                    .with_context(|| format!("--resolution {v}: expected WxH"))?;
                resolution = (w.parse()?, h.parse()?);
            }
            _ => scenes.push(a),
        }
    }
    let ctx = open_device(&ContextOptions::default())?;
    for path in &scenes {
        let scene = Scene::load(path)?.with_resolution(resolution.0, resolution.1);
        let settings = Settings {
            photons_per_pass: 100_000,
            ..Settings::default()
        };
        let renderer = Renderer::new(&ctx, &scene, settings.clone())?;
        let direct = settings.direct == DirectLight::Sample;
        // As the renderer pushes them (ray_pushes): the unmarked pixels' count is light_samples, or one
        // where the photons take direct light.
        let (e, r, l) = (
            settings.emission_samples,
            settings.rough_pixel_samples(),
            settings.unmarked_samples(),
        );
        let counts: Vec<u64> = (renderer.marks()?.iter())
            .map(|&m| samples_for_mark(direct, e, r, l, m) as u64)
            .collect();
        let paid = |c: &[u64]| -> u64 { c.chunks(LANES).map(|g| LANES as u64 * g.iter().max().unwrap()).sum() };
        let own: u64 = counts.iter().sum();
        let mut sorted = counts.clone();
        sorted.sort_unstable();
        let mut histogram = std::collections::BTreeMap::new();
        for &c in &counts {
            *histogram.entry(c).or_insert(0u32) += 1;
        }
        println!(
            "{path} at {}x{}: pixels by samples {histogram:?}; the pixels' own {own}, SIMD groups pay {} ({:.3}x), sorted {}",
            resolution.0,
            resolution.1,
            paid(&counts),
            paid(&counts) as f64 / own as f64,
            paid(&sorted)
        );
    }
    Ok(())
}

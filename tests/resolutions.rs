//! Any resolution renders (issue 39): at a few dozen pixels wide eq. 8's radius is a tenth of the scene, so
//! with a million photons a pass every hit point's lookup reads thousands of photons, far past lavapipe's
//! loop budget per subgroup; the renderer splits such a pass into smaller batches (the same photons) rather
//! than failing. Each image is finite and its mean agrees with the same scene rendered at 128 x 128 (a box
//! filter conserves the light; the wider radius moves a little of it across edges) at the same aspect.

mod common;

use common::*;
use ppm_vk_engine::{Renderer, Settings};

/// The image's mean after `passes` passes at w x h, and the most batches a pass took.
fn mean(scene: &ppm_vk_engine::Scene, w: u32, h: u32, passes: u32) -> ([f64; 3], u32) {
    let ctx = ctx();
    let settings = Settings {
        photons_per_pass: 1_000_000,
        seed: 3,
        ..Settings::default()
    };
    let mut r = Renderer::new(&ctx, &scene.clone().with_resolution(w, h), settings).unwrap_or_else(|e| panic!("{e:#}"));
    let mut batches = 0;
    for _ in 0..passes {
        batches = batches.max(r.pass().unwrap_or_else(|e| panic!("{w}x{h}: {e:#}")).batches);
    }
    let image = r.image().unwrap();
    assert_eq!(image.count_non_finite(), 0, "{w}x{h}: non-finite pixels");
    drop(r);
    assert_clean(&ctx);
    (image.mean(), batches)
}

#[test]
fn tiny_images_render_without_a_limit_error() {
    for path in ["scenes/cornell-spheres.toml", "scenes/glass-on-table.toml"] {
        let scene = load(&format!("{}/{path}", env!("CARGO_MANIFEST_DIR")));
        for (w, h) in [(32, 32), (64, 36)] {
            // The same view (the field of view is vertical: the aspect ratio decides what is seen).
            let (want, _) = mean(&scene, 128, 128 * h / w, 2);
            let (got, batches) = mean(&scene, w, h, 2);
            println!("{path} at {w}x{h}: mean {got:.4?} ({batches} batches a pass), at 128 wide {want:.4?}");
            for c in 0..3 {
                // 5%: two passes' noise in a few hundred pixels, and the light a radius a tenth of the
                // scene moves across the image's edges.
                assert!(
                    (got[c] / want[c] - 1.0).abs() < 0.05,
                    "{path} at {w}x{h}, channel {c}: {got:?} vs {want:?}"
                );
            }
        }
    }
}

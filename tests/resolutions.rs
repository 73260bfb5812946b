//! Any resolution renders (issue 39): at a few dozen pixels wide eq. 8's radius is a tenth of the scene, so
//! with a million photons a pass every hit point's lookup reads thousands of photons, far past lavapipe's
//! loop budget per subgroup; the renderer splits such a pass into smaller batches (the same photons) rather
//! than failing. Each image is finite and its mean agrees with the same scene rendered at 128 x 128 (a box
//! filter conserves the light; the wider radius moves a little of it across edges) at the same aspect.

mod common;

use common::*;
use ppm_vk_engine::layout::{HitPoint, HitStats, PassAccum};
use ppm_vk_engine::{Renderer, Settings};

/// Bytes of the largest per-slot record, which sets the tiles (the statistics' 64).
fn slot_bytes() -> u64 {
    [
        std::mem::size_of::<HitPoint>(),
        std::mem::size_of::<HitStats>(),
        std::mem::size_of::<PassAccum>(),
    ]
    .into_iter()
    .max()
    .unwrap() as u64
}

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

/// 2048 x 2048 SPPM: 192 MiB of hit points and 256 MiB of their statistics, past lavapipe's largest storage
/// binding (128 MiB), which the renderer binds in tiles. It renders; every tile's pixels were traced,
/// gathered and resolved (each band of rows it covers is lit, the box's walls and floor); the tiles are
/// as many as the device's binding asks; the validation layer saw no binding past the limit.
#[test]
fn renders_at_2048_squared_without_a_limit_error() {
    let ctx = ctx();
    let (w, h) = (2048u32, 2048u32);
    let settings = Settings {
        photons_per_pass: 20_000,
        ..Settings::default()
    };
    let mut r = Renderer::new(&ctx, &cornell(w, h), settings).unwrap_or_else(|e| panic!("{e:#}"));
    r.pass().unwrap_or_else(|e| panic!("{e:#}"));
    let image = r.image().unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(image.count_non_finite(), 0);
    // The tiles the device's largest binding asks for: the largest per-slot record, in runs of 64 pixels.
    let range = ctx.limits().max_storage_buffer_range as u64;
    let per_tile = (range / slot_bytes() / 64 * 64).min((w * h) as u64);
    let tiles = (w as u64 * h as u64).div_ceil(per_tile);
    assert_eq!(r.tile_count() as u64, tiles);
    if range < 192 << 20 {
        assert!(tiles > 1, "lavapipe's 128 MiB must split 2048x2048");
    }
    // Each tile's rows (whole rows or not) have light in them: a tile bound at the wrong offset, or
    // never dispatched, would leave its pixels black.
    for t in 0..tiles {
        let (first, last) = (t * per_tile, ((t + 1) * per_tile).min((w * h) as u64) - 1);
        let (y0, y1) = ((first / w as u64) as u32, (last / w as u64) as u32);
        let band = image.crop(0, y0, w, y1 - y0 + 1).unwrap();
        let m = band.mean();
        assert!(m.iter().all(|&c| c > 0.01), "tile {t} (rows {y0}..={y1}): mean {m:?}");
    }
    drop(r);
    assert_clean(&ctx);
}

/// Tiling is exact: the same renders with the tiles forced small (`Settings::max_tile_bytes`: 64 x 64
/// in three tiles of 1536, 1536 and 1024 pixels, the cap not a whole number of runs) give the same image
/// bit for bit as in one tile: SPPM with the probe pass, PPM with four hit points a pixel (glass splits
/// its eye paths), and a PPM render resumed from a checkpoint.
#[test]
fn small_tiles_render_the_same_bits_as_one() {
    let ctx = ctx();
    let scene = cornell(64, 64);
    let cases = [
        (
            "sppm, probe",
            Settings {
                photons_per_pass: 20_000,
                probe: ppm_vk_engine::ProbeMode::ScaleFree,
                seed: 5,
                ..Settings::default()
            },
        ),
        (
            "ppm, 4 slots",
            Settings {
                mode: ppm_vk_engine::Mode::Ppm,
                photons_per_pass: 20_000,
                hit_slots: 4,
                seed: 6,
                ..Settings::default()
            },
        ),
    ];
    for (what, settings) in cases {
        let per_pixel = slot_bytes() * settings.slots(&scene) as u64;
        let small = Settings {
            max_tile_bytes: Some(1536 * per_pixel + 63 * per_pixel),
            ..settings.clone()
        };
        let run = |s: &Settings| {
            let mut r = Renderer::new(&ctx, &scene, s.clone()).unwrap_or_else(|e| panic!("{what}: {e:#}"));
            for _ in 0..2 {
                r.pass().unwrap_or_else(|e| panic!("{what}: {e:#}"));
            }
            (r.tile_count(), r.active_hit_points(), r.image().unwrap())
        };
        let (one_tiles, one_active, one) = run(&settings);
        let (tiles, active, split) = run(&small);
        assert_eq!((one_tiles, tiles), (1, 3), "{what}");
        assert_eq!(active, one_active, "{what}: the tiles' hit points");
        assert!(one.mean()[0] > 0.01, "{what}: a black image proves nothing");
        assert_eq!(
            pixels_sha256(&split),
            pixels_sha256(&one),
            "{what}: tiled image differs"
        );
        // Resumed in tiles from a tiled checkpoint after one pass: the uninterrupted tiled render's bits.
        let mut first = Renderer::new(&ctx, &scene, small.clone()).unwrap();
        first.pass().unwrap();
        let checkpoint = first.checkpoint("test").unwrap();
        drop(first);
        let mut resumed = Renderer::resume(&ctx, &scene, small.clone(), &checkpoint, "test")
            .unwrap_or_else(|e| panic!("{what}: {e:#}"));
        resumed.pass().unwrap();
        assert_eq!(
            pixels_sha256(&resumed.image().unwrap()),
            pixels_sha256(&one),
            "{what}: resumed"
        );
    }
    assert_clean(&ctx);
}

/// A cap below one run of `TILE_ALIGN_PIXELS` pixels is a settings error naming the field; exactly one
/// run renders.
#[test]
fn a_tile_cap_below_one_run_is_a_settings_error() {
    let ctx = ctx();
    let scene = cornell(16, 16);
    // cornell-spheres' glass splits: 4 slots a pixel.
    let slots = ppm_vk_engine::settings::DEFAULT_GLASS_SPLITS as u64;
    let run = ppm_vk_engine::TILE_ALIGN_PIXELS as u64 * slot_bytes() * slots;
    let at = |cap: u64| {
        let s = Settings {
            photons_per_pass: 1000,
            max_tile_bytes: Some(cap),
            ..Settings::default()
        };
        Renderer::new(&ctx, &scene, s).map(|r| r.tile_count())
    };
    assert_eq!(at(run).unwrap_or_else(|e| panic!("{e:#}")), 4);
    match at(run - 1) {
        Err(ppm_vk_engine::Error::Settings { field, message }) => {
            assert_eq!(field, "max_tile_bytes", "{message}");
        }
        other => panic!("expected a settings error, got {:?}", other.map(|_| ())),
    }
    assert_clean(&ctx);
}

//! Photon probing (eq. 7-9) on the GPU against the CPU reference, and how both probe rules behave when the
//! scene's units change.

mod common;

use common::{assert_clean, cornell, ctx};
use ppm_vk_engine::layout::{HitPoint, HitStats};
use ppm_vk_engine::{ProbeMode, Renderer, Settings};
use ppm_vk_kernels::photon::SALT_PROBE;
use ppm_vk_reference as reference;

const RES: u32 = 32;
const PROBE_PHOTONS: u32 = 20_000;

/// The probe's constant for `settings`' rule: k for the nearest rule, beta otherwise.
fn param(settings: &Settings) -> f32 {
    match settings.probe {
        ProbeMode::Nearest => settings.probe_k,
        ProbeMode::Curvature => settings.probe_grow,
        _ => settings.probe_beta,
    }
}

fn settings(probe: ProbeMode) -> Settings {
    Settings {
        mode: ppm_vk_engine::Mode::Ppm,
        photons_per_pass: 20_000,
        probe,
        probe_photons: Some(PROBE_PHOTONS),
        ..Settings::default()
    }
}

/// The renderer's hit points and probed statistics, the CPU probe of the same hit points, and eq. 8's r:
/// the CPU traces the same probe photons (same streams) and probes every hit point by brute force.
/// What gpu_and_cpu_probe returns: the hit points, the GPU's statistics, the CPU's (lambda / r^2, R^2) per
/// hit point, and eq. 8's r.
type ProbeResults = (Vec<HitPoint>, Vec<HitStats>, Vec<(f64, f64)>, f64);

fn gpu_and_cpu_probe(r: &Renderer) -> ProbeResults {
    let g = r.gpu_scene();
    let hits = r.read_hit_points().unwrap();
    let gpu = r.read_stats().unwrap();
    let photons = reference::photon_pass(g, 0, PROBE_PHOTONS, SALT_PROBE);
    let r0 = g.initial_radius as f64;
    let start = vec![
        HitStats {
            r2: r0 * r0,
            ..Default::default()
        };
        hits.len()
    ];
    let cpu = reference::probe(&hits, &start, &photons, r.settings().probe, param(r.settings()));
    (hits, gpu, cpu, r0)
}

fn probe_case(mode: ProbeMode) {
    let ctx = ctx();
    let scene = cornell(RES, RES);
    let r = Renderer::new(&ctx, &scene, settings(mode)).unwrap();
    let (hits, gpu, cpu, r0) = gpu_and_cpu_probe(&r);
    let (mut live, mut agree, mut enlarged, mut worst) = (0usize, 0usize, 0usize, 0f64);
    for (i, (h, (s, (ratio, r2)))) in hits.iter().zip(gpu.iter().zip(&cpu)).enumerate() {
        if h.is_empty() {
            continue;
        }
        live += 1;
        enlarged += (s.r2 > r0 * r0 * (1.0 + 1e-9)) as usize;
        // lambda / r^2 is a mean of d^2 / r^2 over the photons in the sphere (hundreds here: r is eq. 8's
        // 0.17 m at 32 pixels wide). Positions differ between GPU and CPU by f32 rounding (~1e-7 m, so
        // d^2 / r^2 by ~1e-6 per photon), and ~0.2% of records belong to paths that diverged at a
        // threshold, each moving a mean of N values in [0, 1] by at most 1/N: 1e-4 absolute covers the
        // first; the second touches a hit point whenever one of its hundreds of photons came from a diverged
        // path: measured 95.5% and 94.1% of hit points agreeing (ray offsets 2^-14 and 2^-16), so 90%. The
        // probe on identical photons is checked exactly in probe_kernel_matches_reference_on_identical_photons.
        // r'^2 = r^2 (1 + lambda / r^2)^2 (scale-free) turns a difference of lambda / r^2 into up to twice
        // that, relative.
        let same = (s.probe - ratio).abs() <= 1e-4 && (s.r2 - r2).abs() <= 2e-4 * r2;
        agree += same as usize;
        worst = worst.max((s.probe - ratio).abs());
        assert!(
            s.probe.is_finite() && (0.0..=1.0).contains(&s.probe),
            "slot {i}: lambda/r^2 {}",
            s.probe
        );
        assert!(s.r2 >= r0 * r0 * (1.0 - 1e-12), "slot {i}: the probe shrank a radius");
    }
    println!("{mode:?}: {agree} of {live} hit points agree with the CPU probe (worst |d lambda/r^2| {worst:.2e}), {enlarged} enlarged");
    assert!(
        agree * 100 >= live * 90,
        "{mode:?}: only {agree} of {live} hit points agree"
    );
    // A diverged record moves one mean by at most 1/N with N in the hundreds: never by 0.02.
    assert!(worst < 0.02, "{mode:?}: a hit point's lambda/r^2 differs by {worst}");
    assert!(enlarged > 0, "{mode:?}: the probe enlarged nothing");
    let report = r.probe_report().expect("a probe report");
    assert_eq!(report.hit_points as usize, live);
    assert_eq!(report.enlarged as usize, enlarged);
    let q = report.lambda_ratio_quantiles;
    assert!(q.windows(2).all(|w| w[0] <= w[1]), "quantiles not ordered: {q:?}");
    // Over flat walls photons are uniform in the disc: the median lambda / r^2 is near 1/2 (eq. 7's closed
    // form for a uniform disc), the spread coming from the ~20 photons each estimate averages.
    assert!((q[2] - 0.5).abs() < 0.1, "median lambda/r^2 {} is not near 1/2", q[2]);
    assert_clean(&ctx);
}

/// The probe kernel on the very records the GPU traced (no diverged path can differ): M per hit point
/// exactly, lambda / r^2 and the new radius to rounding.
fn probe_identical_photons(mode: ProbeMode) {
    let ctx = ctx();
    let mut r = Renderer::new(&ctx, &cornell(RES, RES), settings(mode)).unwrap();
    let g = r.gpu_scene().clone();
    let r0 = g.initial_radius as f64;
    let start = vec![
        ppm_vk_engine::layout::HitStats {
            r2: r0 * r0,
            ..Default::default()
        };
        g.slots() as usize
    ];
    r.write_stats(&start).unwrap(); // undo the probe Renderer::new ran
    let records = r.trace_and_probe(0, PROBE_PHOTONS).unwrap();
    let accum = r.read_accum().unwrap();
    let hits = r.read_hit_points().unwrap();
    r.finish_probe().unwrap();
    let after = r.read_stats().unwrap();
    let cpu = reference::probe(&hits, &start, &records, mode, param(r.settings()));
    let mut live = 0;
    for (i, h) in hits.iter().enumerate() {
        if h.is_empty() {
            continue;
        }
        live += 1;
        // The same distance and front-side tests in f32 on the same records: the same photons, exactly.
        let m = reference::gather_one(h, start[i].r2, &records, 0.0, &r.gpu_scene().materials).m;
        assert_eq!(accum[i].m, m, "{mode:?} slot {i}: M");
        // d^2 / r^2 per photon in f32 rounded to 2.30 fixed point against f64: 1e-6 covers both.
        let (ratio, r2) = cpu[i];
        assert!(
            (after[i].probe - ratio).abs() <= 1e-6,
            "{mode:?} slot {i}: lambda/r^2 GPU {} CPU {ratio}",
            after[i].probe
        );
        assert!(
            (after[i].r2 - r2).abs() <= 2e-6 * r2,
            "{mode:?} slot {i}: r'^2 GPU {} CPU {r2}",
            after[i].r2
        );
    }
    assert!(live > 1000, "only {live} hit points");
    assert_clean(&ctx);
}

#[test]
fn probe_kernel_matches_reference_on_identical_photons() {
    probe_identical_photons(ProbeMode::Paper);
    probe_identical_photons(ProbeMode::ScaleFree);
    probe_identical_photons(ProbeMode::Nearest);
    probe_identical_photons(ProbeMode::Curvature);
}

/// The nearest rule (r' = r min(sqrt(k / N), 2)) on the GPU against the CPU probe (which counts each
/// hit point's probe photons by brute force), and what it does with the density: where the probe photons
/// crowd (more than k within r: the glass sphere's caustic, the walls by the light) it shrinks the radius,
/// where few arrive it grows it, to at most 2 r.
#[test]
fn nearest_probe_matches_reference_and_follows_the_photons() {
    let ctx = ctx();
    let s = Settings {
        probe_k: 200.0,
        ..settings(ProbeMode::Nearest)
    };
    let r = Renderer::new(&ctx, &cornell(RES, RES), s).unwrap();
    let (hits, gpu, cpu, r0) = gpu_and_cpu_probe(&r);
    let (mut live, mut agree, mut shrunk, mut grown) = (0usize, 0usize, 0usize, 0usize);
    for (i, h) in hits.iter().enumerate() {
        if h.is_empty() {
            continue;
        }
        live += 1;
        let (g, c) = (gpu[i].r2, cpu[i].1);
        // As probe_case: paths that diverged at a threshold move a few hit points' counts.
        agree += ((g - c).abs() <= 2e-4 * c) as usize;
        assert!(g <= 4.0 * r0 * r0 * (1.0 + 1e-9), "slot {i}: r'^2 {g} beyond (2 r)^2");
        shrunk += (g < r0 * r0 * (1.0 - 1e-9)) as usize;
        grown += (g > r0 * r0 * (1.0 + 1e-9)) as usize;
    }
    println!("nearest: {agree} of {live} agree with the CPU probe; {shrunk} shrunk, {grown} grown");
    assert!(agree * 100 >= live * 90, "only {agree} of {live} hit points agree");
    assert!(shrunk > 0 && grown > 0, "{shrunk} shrunk, {grown} grown");
    drop(r);
    assert_clean(&ctx);
}

/// The curvature rule on the GPU against the CPU probe, and what it does: in cornell-spheres at 32 pixels
/// wide (eq. 8's r a tenth of the box) the glass sphere's caustic and the light's falloff on the walls curve
/// the density enough to shrink radii, the flat rest grows them.
#[test]
fn curvature_probe_matches_reference_and_follows_the_photons() {
    let ctx = ctx();
    // Growth up to 2 r (the default only shrinks).
    let s = Settings {
        probe_grow: 2.0,
        ..settings(ProbeMode::Curvature)
    };
    let r = Renderer::new(&ctx, &cornell(RES, RES), s).unwrap();
    let shrunk = curvature_case(&r, 2.0);
    drop(r);
    // Growth capped at 1 (`probe_grow`): the same radii where they shrank, none grown.
    let s = Settings {
        probe_grow: 1.0,
        ..settings(ProbeMode::Curvature)
    };
    let r = Renderer::new(&ctx, &cornell(RES, RES), s).unwrap();
    assert_eq!(curvature_case(&r, 1.0), shrunk);
    drop(r);
    assert_clean(&ctx);
}

/// The GPU's curvature radii against the CPU probe's, within r / 8 and `grow` r; returns how many shrank.
fn curvature_case(r: &Renderer, grow: f64) -> usize {
    let (hits, gpu, cpu, r0) = gpu_and_cpu_probe(r);
    let (mut live, mut agree, mut shrunk, mut grown) = (0usize, 0usize, 0usize, 0usize);
    for (i, h) in hits.iter().enumerate() {
        if h.is_empty() {
            continue;
        }
        live += 1;
        let (g, c) = (gpu[i].r2, cpu[i].1);
        // As probe_case: paths that diverged at a threshold move a few hit points' counts.
        agree += ((g - c).abs() <= 2e-4 * c) as usize;
        assert!(
            g <= grow * grow * r0 * r0 * (1.0 + 1e-6),
            "slot {i}: r'^2 {g} beyond ({grow} r)^2"
        );
        assert!(g >= r0 * r0 / 64.0 * (1.0 - 1e-6), "slot {i}: r'^2 {g} below (r / 8)^2");
        shrunk += (g < r0 * r0 * (1.0 - 1e-6)) as usize;
        grown += (g > r0 * r0 * (1.0 + 1e-6)) as usize;
    }
    println!(
        "curvature, growth at most {grow}: {agree} of {live} agree with the CPU probe; {shrunk} shrunk, {grown} grown"
    );
    assert!(agree * 100 >= live * 90, "only {agree} of {live} hit points agree");
    assert!(shrunk > 0, "none shrunk");
    assert_eq!(grown > 0, grow > 1.0, "{grown} grown");
    shrunk
}

#[test]
fn curvature_probe_renders_the_same_at_any_scale() {
    // Counts within r and r / 2: the same radii, relative to the scene, at every scale.
    let (base, g1) = render_scaled(1.0, ProbeMode::Curvature, 4);
    for s in [1e-3f32, 1e3] {
        let (m, g) = render_scaled(s, ProbeMode::Curvature, 4);
        for c in 0..3 {
            assert!((m[c] / base[c] - 1.0).abs() < 0.01, "scale {s}: mean {m:?} vs {base:?}");
        }
        assert!((g / g1 - 1.0).abs() < 0.01, "scale {s}: radius change {g} vs {g1}");
    }
}

#[test]
fn probe_paper_matches_reference() {
    probe_case(ProbeMode::Paper);
}

#[test]
fn probe_scale_free_matches_reference() {
    probe_case(ProbeMode::ScaleFree);
}

/// The mean radiance of `passes` passes of cornell-spheres scaled by `s`, and the probe's mean radius growth.
/// (At 32 pixels wide eq. 8's radius is a tenth of the box, so every lookup reads thousands of photons:
/// 20k photons per pass keeps a subgroup's lookups inside lavapipe's loop budget.)
fn render_scaled(s: f32, probe: ProbeMode, passes: u32) -> ([f64; 3], f64) {
    let ctx = ctx();
    let scene = cornell(RES, RES).scaled(s);
    let mut r = Renderer::new(
        &ctx,
        &scene,
        Settings {
            photons_per_pass: 20_000,
            ..settings(probe)
        },
    )
    .unwrap();
    for _ in 0..passes {
        r.pass().unwrap();
    }
    let image = r.image().unwrap();
    assert_eq!(image.count_non_finite(), 0);
    let growth = r.probe_report().map(|p| p.mean_radius_ratio).unwrap_or(1.0);
    assert_clean(&ctx);
    (image.mean(), growth)
}

#[test]
fn scale_free_probe_renders_the_same_at_any_scale() {
    // Radiance does not depend on units: every ray offset, radius and grid cell is relative to the scene,
    // and the scale-free rule enlarges by the same factor at every scale.
    let (base, g1) = render_scaled(1.0, ProbeMode::ScaleFree, 4);
    for s in [1e-3f32, 1e3] {
        let (m, g) = render_scaled(s, ProbeMode::ScaleFree, 4);
        // 1%: the same photons at every scale, up to f32 rounding that moves a few paths.
        for c in 0..3 {
            assert!((m[c] / base[c] - 1.0).abs() < 0.01, "scale {s}: mean {m:?} vs {base:?}");
        }
        assert!((g / g1 - 1.0).abs() < 0.01, "scale {s}: radius growth {g} vs {g1}");
    }
}

#[test]
fn nearest_probe_renders_the_same_at_any_scale() {
    // A ratio of photon counts: the same radii, relative to the scene, at every scale.
    let (base, g1) = render_scaled(1.0, ProbeMode::Nearest, 4);
    for s in [1e-3f32, 1e3] {
        let (m, g) = render_scaled(s, ProbeMode::Nearest, 4);
        for c in 0..3 {
            assert!((m[c] / base[c] - 1.0).abs() < 0.01, "scale {s}: mean {m:?} vs {base:?}");
        }
        assert!((g / g1 - 1.0).abs() < 0.01, "scale {s}: radius change {g} vs {g1}");
    }
}

#[test]
fn paper_probe_depends_on_the_scene_units() {
    // Eq. 9 as printed enlarges r to r (1 + lambda / r) = r + lambda: with lambda ~ r^2 / 2 the growth
    // is ~1 + r / 2, so it follows the units. At 32 pixels wide eq. 8 gives r = 0.17 in metres (growth
    // ~1.08) and 167 in millimetres (growth ~80). Documented, not fixed: that is what --probe paper means.
    // Only the probe runs: with radii 80 times the start every lookup reads the whole photon map, past
    // lavapipe's loop budget (the renderer would split such a pass into smaller batches; a_lookup_past_the_loop_budget_is_split_across_batches).
    let (_, g1) = render_scaled(1.0, ProbeMode::Paper, 0);
    let (_, g1000) = render_scaled(1e3, ProbeMode::Paper, 0);
    println!("paper probe: mean radius growth {g1:.4} in metres, {g1000:.3} in millimetres");
    assert!(
        (1.02..1.2).contains(&g1),
        "in metres: growth {g1}, expected ~1 + r/2 = 1.08"
    );
    assert!(
        g1000 > 20.0,
        "in millimetres the paper's rule should enlarge r tens of times: {g1000}"
    );
}

/// SPPM with the probe: a pixel whose first eye path left no hit point (it saw the light, or its glass
/// path died) has no density to probe and keeps r, on the GPU as in the CPU reference. (The GPU used to
/// treat such pixels as sparse and double their radius, blurring every later sample there.) Pixels with a
/// hit point follow the CPU probe as in PPM.
#[test]
fn sppm_probe_leaves_pixels_without_a_hit_point_at_r() {
    let ctx = ctx();
    let scene = cornell(RES, RES);
    let settings = Settings {
        mode: ppm_vk_engine::Mode::Sppm,
        ..settings(ProbeMode::ScaleFree)
    };
    let r = Renderer::new(&ctx, &scene, settings).unwrap();
    let (hits, gpu, cpu, r0) = gpu_and_cpu_probe(&r);
    let empty: Vec<usize> = (0..hits.len()).filter(|&i| hits[i].is_empty()).collect();
    println!("{} of {} pixels have no hit point", empty.len(), hits.len());
    assert!(
        !empty.is_empty(),
        "the test needs pixels without a hit point (the light is in view)"
    );
    for &i in &empty {
        assert_eq!(gpu[i].r2, r0 * r0, "pixel {i}: no hit point, yet its radius changed");
        assert_eq!(cpu[i].1, r0 * r0);
    }
    let live = hits.len() - empty.len();
    let agree = (0..hits.len())
        .filter(|&i| !hits[i].is_empty() && (gpu[i].r2 - cpu[i].1).abs() <= 2e-4 * cpu[i].1)
        .count();
    // As in PPM (probe_case): paths that diverged at a threshold move some hit points' means; 90%.
    assert!(
        agree * 100 >= live * 90,
        "only {agree} of {live} hit points agree with the CPU probe"
    );
    drop(r);
    assert_clean(&ctx);
}

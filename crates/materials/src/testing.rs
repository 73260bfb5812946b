//! What the tests of the BSDFs share, here and in the engine's CPU twin (the `test-support` feature):
//! values read from the JSON files Mitsuba's scripts wrote (scenes/references/), the distributions and
//! directions they sweep, quadrature over the hemisphere, and a chi-square test of a sampler against its
//! density.

use glam::{Vec2, Vec3};

use crate::math::PI;
use crate::Microfacet;

/// A colour as the tests' JSON files (made with Mitsuba) write it: a number, an [r, g, b] array, or
/// Mitsuba's {"type": "rgb", "value": ..}.
pub fn json_rgb(v: &serde_json::Value) -> Vec3 {
    match v {
        serde_json::Value::Number(n) => Vec3::splat(n.as_f64().unwrap() as f32),
        serde_json::Value::Array(a) => {
            Vec3::from_slice(&a.iter().map(|x| x.as_f64().unwrap() as f32).collect::<Vec<_>>())
        }
        serde_json::Value::Object(o) => json_rgb(&o["value"]),
        other => panic!("not a colour: {other}"),
    }
}

/// A vector as the tests' JSON files write it, [x, y, z].
pub fn v(x: &serde_json::Value) -> Vec3 {
    let a = x.as_array().unwrap();
    Vec3::new(
        a[0].as_f64().unwrap() as f32,
        a[1].as_f64().unwrap() as f32,
        a[2].as_f64().unwrap() as f32,
    )
}

/// Distributions the tests sweep: both kinds, isotropic and anisotropic, smooth to very rough.
pub fn distributions() -> Vec<Microfacet> {
    let mut v = Vec::new();
    for ggx in [false, true] {
        for (alpha, alpha_v) in [(0.05, 0.05), (0.2, 0.2), (0.6, 0.6), (1.0, 1.0), (0.1, 0.5)] {
            v.push(Microfacet { ggx, alpha, alpha_v });
        }
    }
    v
}

/// A unit direction at polar cosine `c` and azimuth `phi`.
pub fn dir(c: f32, phi: f32) -> Vec3 {
    let s = (1.0 - c * c).max(0.0).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), c)
}

/// The integral of f over the upper hemisphere, by the midpoint rule in (cos theta, phi) on an n x 4n
/// grid refined towards the pole, where narrow lobes live (cos theta = 1 - t^2).
pub fn hemisphere(n: usize, f: impl Fn(Vec3) -> f64) -> f64 {
    let mut sum = 0.0;
    for i in 0..n {
        let t = (i as f64 + 0.5) / n as f64;
        let c = 1.0 - t * t; // dc = 2 t dt
        for j in 0..4 * n {
            let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / (4 * n) as f64;
            let w = 2.0 * t / n as f64 * 2.0 * std::f64::consts::PI / (4 * n) as f64;
            sum += w * f(dir(c as f32, phi as f32));
        }
    }
    sum
}

/// Pearson's chi-square test of `sample` against the density `pdf` over the upper hemisphere (and,
/// for `lower`, the lower one too), on a (cos theta, phi) grid with the expected counts integrated
/// per cell; cells expecting fewer than 5 samples are pooled. Returns (statistic, degrees of freedom)
/// and fails if the statistic exceeds the 1e-4 tail of its distribution (Wilson-Hilferty), or if the
/// sampler misses the density's mass by more than its noise.
pub fn chi_square(
    label: &str,
    samples: usize,
    lower: bool,
    mut sample: impl FnMut(Vec2) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f64,
) -> (f64, usize) {
    let (nt, np) = (20usize, 40usize);
    let halves = if lower { 2 } else { 1 };
    let cell = |v: Vec3| -> usize {
        let h = usize::from(v.z < 0.0);
        let c = v.z.abs().min(1.0);
        let t = ((1.0 - c).max(0.0).sqrt() * nt as f32).min(nt as f32 - 1.0) as usize;
        let phi = v.y.atan2(v.x).rem_euclid(2.0 * PI);
        let p = (phi / (2.0 * PI) * np as f32).min(np as f32 - 1.0) as usize;
        (h * nt + t) * np + p
    };
    let mut observed = vec![0f64; halves * nt * np];
    let mut rng = crate::rng::Rng::new(12345, 678);
    for _ in 0..samples {
        if let Some(v) = sample(Vec2::new(rng.float(), rng.float())) {
            observed[cell(v)] += 1.0;
        }
    }
    // Expected counts: the density integrated over each cell by a midpoint rule in (t, phi), refined
    // (8x8, 16x16, ... up to 512x512) until two refinements agree within 1e-4 of the cell or of
    // a tenth of a sample: a narrow lobe near the horizon needs hundreds of points across a cell (a
    // fixed 24x24 rule missed 8% of a Beckmann lobe of alpha 0.05 there, which an integral over
    // slope space and the sampler agreed on).
    let integrate = |h: usize, t: usize, p: usize, sub: usize| -> f64 {
        let mut sum = 0.0;
        for a in 0..sub {
            let tt = (t as f64 + (a as f64 + 0.5) / sub as f64) / nt as f64;
            let c = 1.0 - tt * tt;
            for b in 0..sub {
                let phi = 2.0 * std::f64::consts::PI * (p as f64 + (b as f64 + 0.5) / sub as f64) / np as f64;
                let mut v = dir(c as f32, phi as f32);
                if h == 1 {
                    v.z = -v.z;
                }
                let w = 2.0 * tt / (nt * sub) as f64 * 2.0 * std::f64::consts::PI / (np * sub) as f64;
                sum += w * pdf(v);
            }
        }
        sum * samples as f64
    };
    let mut expected = vec![0f64; observed.len()];
    for h in 0..halves {
        for t in 0..nt {
            for p in 0..np {
                let (mut sub, mut e) = (8, integrate(h, t, p, 8));
                while sub < 512 {
                    let finer = integrate(h, t, p, 2 * sub);
                    let done = (finer - e).abs() <= 1e-4 * finer.abs() + 0.1;
                    (sub, e) = (2 * sub, finer);
                    if done {
                        break;
                    }
                }
                expected[(h * nt + t) * np + p] = e;
            }
        }
    }
    let total_expected: f64 = expected.iter().sum();
    let total_observed: f64 = observed.iter().sum();
    let noise = total_expected.sqrt();
    assert!(
        (total_observed - total_expected).abs() < 5.0 * noise + 2e-3 * samples as f64,
        "{label}: {total_observed} samples landed where the density expects {total_expected}"
    );
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].partial_cmp(&expected[b]).unwrap());
    let (mut stat, mut dof) = (0.0, 0usize);
    let (mut pool_e, mut pool_o) = (0.0, 0.0);
    for i in order {
        if expected[i] < 5.0 || pool_e > 0.0 && pool_e < 5.0 {
            pool_e += expected[i];
            pool_o += observed[i];
            continue;
        }
        stat += (observed[i] - expected[i]).powi(2) / expected[i];
        if std::env::var("CHI_DEBUG").is_ok() && (observed[i] - expected[i]).powi(2) / expected[i] > 4.0 {
            println!(
                "cell t{} p{}: observed {} expected {:.1}",
                (i / np) % nt,
                i % np,
                observed[i],
                expected[i]
            );
        }
        dof += 1;
    }
    if pool_e > 0.0 {
        stat += (pool_o - pool_e).powi(2) / pool_e.max(1e-9);
        dof += 1;
    }
    let dof = dof.max(2) - 1;
    // Wilson-Hilferty: (X/k)^(1/3) is normal with mean 1 - 2/(9k), variance 2/(9k); z = 3.719 is the
    // 1e-4 upper tail.
    let k = dof as f64;
    let limit = k * (1.0 - 2.0 / (9.0 * k) + 3.719 * (2.0 / (9.0 * k)).sqrt()).powi(3);
    assert!(
        stat < limit,
        "{label}: chi-square {stat:.1} above {limit:.1} at {dof} degrees of freedom"
    );
    (stat, dof)
}

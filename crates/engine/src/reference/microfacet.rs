//! CPU twin of shaders/common/microfacet.glsl: Mitsuba 3's microfacet distributions (Beckmann and GGX,
//! roughness `au` along the tangent and `av` along the bitangent), Smith's masking G1 and the sampling of
//! the normals visible from a direction (Heitz 2018 for GGX; Jakob 2014's slope inversion for Beckmann).
//! Directions are in the local frame: z the normal on the incoming side, x the tangent. Checked in the
//! tests below against integrals that do not use it (each visible-normal density integrates to 1, and
//! the sampler's histogram against the density, by a chi-square test), and through the BSDFs built on it
//! (rough_conductor.rs, rough_dielectric.rs) against Mitsuba's own.

use glam::{Vec2, Vec3};
use ppm_vk_kernels::layout::{Material, MICROFACET_GGX};

use super::trace::PI;

#[derive(Clone, Copy, Debug)]
pub struct Microfacet {
    pub ggx: bool,
    pub au: f32,
    pub av: f32,
}

impl Microfacet {
    /// The distribution of material `m` (its fifth texel).
    pub fn of(m: &Material) -> Microfacet {
        Microfacet {
            ggx: m.distribution == MICROFACET_GGX,
            au: m.alpha_u,
            av: m.alpha_v,
        }
    }

    /// The distribution of normals D(m).
    pub fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let (x, y, z2) = (m.x / self.au, m.y / self.av, m.z * m.z);
        let r = if self.ggx {
            let t = x * x + y * y + z2;
            1.0 / (PI * self.au * self.av * t * t)
        } else {
            (-(x * x + y * y) / z2).exp() / (PI * self.au * self.av * z2 * z2)
        };
        if r * m.z > 1e-20 {
            r
        } else {
            0.0
        }
    }

    /// Smith's masking G1(v, m).
    pub fn g1(&self, v: Vec3, m: Vec3) -> f32 {
        if v.dot(m) * v.z <= 0.0 {
            return 0.0;
        }
        let xy = (self.au * v.x) * (self.au * v.x) + (self.av * v.y) * (self.av * v.y);
        if xy <= 0.0 {
            return 1.0;
        }
        let tan2 = xy / (v.z * v.z);
        if self.ggx {
            return 2.0 / (1.0 + (1.0 + tan2).sqrt());
        }
        let a = 1.0 / tan2.sqrt();
        // Mitsuba's rational fit, held at 1 where it rises to 1.00006 (just below a = 1.6).
        if a >= 1.6 {
            1.0
        } else {
            ((3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)).min(1.0)
        }
    }

    /// A normal drawn from the normals visible from `wi` (wi.z > 0), of density [`Self::visible_pdf`].
    pub fn sample_visible(&self, wi: Vec3, u: Vec2) -> Vec3 {
        let v = Vec3::new(self.au * wi.x, self.av * wi.y, wi.z).normalize();
        if self.ggx {
            let len2 = v.x * v.x + v.y * v.y;
            let t1 = if len2 > 0.0 {
                Vec3::new(-v.y, v.x, 0.0) / len2.sqrt()
            } else {
                Vec3::X
            };
            let t2 = v.cross(t1);
            let r = u.x.sqrt();
            let phi = 2.0 * PI * u.y;
            let p1 = r * phi.cos();
            let mut p2 = r * phi.sin();
            let s = 0.5 * (1.0 + v.z);
            p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
            let n = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * v;
            return Vec3::new(self.au * n.x, self.av * n.y, n.z.max(0.0)).normalize();
        }
        let sin_theta = (1.0 - v.z * v.z).max(0.0).sqrt();
        let (cos_phi, sin_phi) = if sin_theta > 0.0 {
            (v.x / sin_theta, v.y / sin_theta)
        } else {
            (1.0, 0.0)
        };
        let s = beckmann_slopes(v.z, u);
        let s = Vec2::new(cos_phi * s.x - sin_phi * s.y, sin_phi * s.x + cos_phi * s.y) * Vec2::new(self.au, self.av);
        Vec3::new(-s.x, -s.y, 1.0).normalize()
    }

    /// D_wi(m) = G1(wi, m) max(0, wi.m) D(m) / wi.z.
    pub fn visible_pdf(&self, wi: Vec3, m: Vec3) -> f32 {
        self.g1(wi, m) * wi.dot(m).max(0.0) * self.d(m) / wi.z
    }
}

/// erf, Abramowitz and Stegun 7.1.26 (the published constants, as microfacet.glsl writes them).
#[allow(clippy::excessive_precision)]
pub fn erf(x: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.3275911 * x.abs());
    let p = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    let y = 1.0 - p * (-x * x).exp();
    if x < 0.0 {
        -y
    } else {
        y
    }
}

/// Its inverse on (-1, 1) (M. Giles 2011).
#[allow(clippy::excessive_precision)]
pub fn erfinv(x: f32) -> f32 {
    let mut w = -((1.0 - x) * (1.0 + x)).max(1e-30).ln();
    let mut p;
    if w < 5.0 {
        w -= 2.5;
        p = 2.81022636e-08;
        p = 3.43273939e-07 + p * w;
        p = -3.5233877e-06 + p * w;
        p = -4.39150654e-06 + p * w;
        p = 0.00021858087 + p * w;
        p = -0.00125372503 + p * w;
        p = -0.00417768164 + p * w;
        p = 0.246640727 + p * w;
        p = 1.50140941 + p * w;
    } else {
        w = w.sqrt() - 3.0;
        p = -0.000200214257;
        p = 0.000100950558 + p * w;
        p = 0.00134934322 + p * w;
        p = -0.00367342844 + p * w;
        p = 0.00573950773 + p * w;
        p = -0.0076224613 + p * w;
        p = 0.00943887047 + p * w;
        p = 1.00167406 + p * w;
        p = 2.83297682 + p * w;
    }
    p * x
}

/// The visible slopes of the unit-roughness Beckmann distribution seen at `cos_theta` (Jakob 2014).
fn beckmann_slopes(cos_theta: f32, u: Vec2) -> Vec2 {
    let u = u.clamp(Vec2::splat(1e-6), Vec2::splat(1.0 - 1e-6));
    let tan_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt() / cos_theta;
    let cot_theta = 1.0 / tan_theta.max(1e-7);
    const INV_SQRT_PI: f32 = 0.564_189_6;
    let top = erf(cot_theta);
    let mut x = top - (top + 1.0) * erf((-u.x.ln()).sqrt());
    let target = u.x * (1.0 + top + INV_SQRT_PI * tan_theta * (-cot_theta * cot_theta).exp());
    for _ in 0..3 {
        let slope = erfinv(x);
        let value = 1.0 + x + INV_SQRT_PI * tan_theta * (-slope * slope).exp() - target;
        x -= value / (1.0 - slope * tan_theta);
    }
    Vec2::new(erfinv(x.clamp(-1.0 + 1e-7, 1.0 - 1e-7)), erfinv(2.0 * u.y - 1.0))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Distributions the tests sweep: both kinds, isotropic and anisotropic, smooth to very rough.
    pub(crate) fn distributions() -> Vec<Microfacet> {
        let mut v = Vec::new();
        for ggx in [false, true] {
            for (au, av) in [(0.05, 0.05), (0.2, 0.2), (0.6, 0.6), (1.0, 1.0), (0.1, 0.5)] {
                v.push(Microfacet { ggx, au, av });
            }
        }
        v
    }

    /// A unit direction at polar cosine `c` and azimuth `phi`.
    pub(crate) fn dir(c: f32, phi: f32) -> Vec3 {
        let s = (1.0 - c * c).max(0.0).sqrt();
        Vec3::new(s * phi.cos(), s * phi.sin(), c)
    }

    /// The integral of f over the upper hemisphere, by the midpoint rule in (cos theta, phi) on an n x 4n
    /// grid refined towards the pole, where narrow lobes live (cos theta = 1 - t^2).
    pub(crate) fn hemisphere(n: usize, f: impl Fn(Vec3) -> f64) -> f64 {
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

    /// Independent of the sampler: the projected area of the microfacets is the macro-surface's,
    /// int D(m) m.z dm = 1, and the visible normals' density integrates to 1 from every direction (which
    /// checks G1 against D: Smith's G1 is exactly what makes it so).
    #[test]
    fn densities_integrate_to_one() {
        for mf in distributions() {
            let n = if mf.au.min(mf.av) < 0.1 { 1200 } else { 400 };
            let proj = hemisphere(n, |m| mf.d(m) as f64 * m.z as f64);
            assert!((proj - 1.0).abs() < 2e-3, "{mf:?}: int D cos = {proj}");
            for c in [0.95, 0.6, 0.2] {
                let wi = dir(c, 0.7);
                let vis = hemisphere(n, |m| mf.visible_pdf(wi, m) as f64);
                // Beckmann's G1 is Mitsuba's rational fit (within ~0.2%), GGX's exact.
                let tol = if mf.ggx { 3e-3 } else { 6e-3 };
                assert!((vis - 1.0).abs() < tol, "{mf:?} at cos {c}: int D_wi = {vis}");
            }
        }
    }

    /// G1 never exceeds 1 (the photons' weights rely on it), over the whole range of the fit.
    #[test]
    fn masking_is_at_most_one() {
        for mf in distributions() {
            for k in 1..=2000 {
                let v = dir(k as f32 / 2000.0, 0.4);
                let g = mf.g1(v, Vec3::Z);
                assert!((0.0..=1.0).contains(&g), "{mf:?}: G1 {g} at cos {}", v.z);
            }
        }
    }

    #[test]
    fn erf_and_erfinv_are_inverse() {
        for k in -99..=99 {
            let x = k as f32 / 100.0;
            let y = erf(erfinv(x));
            assert!((y - x).abs() < 2e-6, "erf(erfinv({x})) = {y}");
        }
        assert!((erf(1.0) - 0.842_700_8).abs() < 2e-7);
    }

    /// Pearson's chi-square test of `sample` against the density `pdf` over the upper hemisphere (and,
    /// for `lower`, the lower one too), on a (cos theta, phi) grid with the expected counts integrated
    /// per cell; cells expecting fewer than 5 samples are pooled. Returns (statistic, degrees of freedom)
    /// and fails if the statistic exceeds the 1e-4 tail of its distribution (Wilson-Hilferty), or if the
    /// sampler misses the density's mass by more than its noise.
    pub(crate) fn chi_square(
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
        let mut rng = super::super::rng::Rng::new(12345, 678);
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

    #[test]
    fn visible_normals_follow_their_density() {
        for mf in distributions() {
            for c in [0.98, 0.5, 0.1] {
                let wi = dir(c, 0.7);
                let label = format!("{mf:?} at cos {c}");
                let (stat, dof) = chi_square(
                    &label,
                    400_000,
                    false,
                    |u| Some(mf.sample_visible(wi, u)),
                    |m| mf.visible_pdf(wi, m) as f64,
                );
                println!("{label}: chi-square {stat:.1} on {dof} degrees of freedom");
            }
        }
    }
}

//! Mitsuba 3's microfacet distributions (Beckmann and GGX, roughness `alpha` along the tangent and
//! `alpha_v` along the bitangent), Smith's masking G1 and the sampling of the normals visible from a
//! direction (Heitz 2018 for GGX; Jakob 2014's slope inversion for Beckmann), as
//! shaders/materials/microfacet.glsl computes them. Directions are in the local frame: z the normal on the
//! incoming side, x the tangent. Checked in the tests below against integrals that do not use it (each
//! visible-normal density integrates to 1, and the sampler's histogram against the density, by a chi-square
//! test), and through the BSDFs built on it (rough_conductor.rs, rough_dielectric.rs) against Mitsuba's own.

use glam::{Vec2, Vec3};

use crate::math::PI;

/// A microfacet distribution: Mitsuba's `distribution` and its roughness (the scene's, and the CPU twin's
/// from a material record). `Debug` is part of a scene's content hash: keep its name and fields.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microfacet {
    pub ggx: bool,
    /// Roughness along the surface's tangent (Mitsuba's alpha_u; its alpha when isotropic).
    pub alpha: f32,
    /// Roughness along the bitangent (alpha_v): equal to `alpha` but on anisotropic surfaces, whose
    /// tangent is Mitsuba's dp/du (docs/mitsuba.md).
    pub alpha_v: f32,
}

impl Microfacet {
    /// The same roughness in every direction.
    pub fn isotropic(ggx: bool, alpha: f32) -> Microfacet {
        Microfacet {
            ggx,
            alpha,
            alpha_v: alpha,
        }
    }

    pub fn is_anisotropic(&self) -> bool {
        self.alpha != self.alpha_v
    }

    /// Mitsuba's floor on alpha (its MicrofacetDistribution clamps to it): below it the lobe is narrower
    /// than f32 directions resolve.
    pub const MIN_ALPHA: f32 = 1e-4;

    /// The distribution of normals D(m).
    pub fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let (x, y, z2) = (m.x / self.alpha, m.y / self.alpha_v, m.z * m.z);
        let r = if self.ggx {
            let t = x * x + y * y + z2;
            1.0 / (PI * self.alpha * self.alpha_v * t * t)
        } else {
            (-(x * x + y * y) / z2).exp() / (PI * self.alpha * self.alpha_v * z2 * z2)
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
        let xy = (self.alpha * v.x) * (self.alpha * v.x) + (self.alpha_v * v.y) * (self.alpha_v * v.y);
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
        let v = Vec3::new(self.alpha * wi.x, self.alpha_v * wi.y, wi.z).normalize();
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
            return Vec3::new(self.alpha * n.x, self.alpha_v * n.y, n.z.max(0.0)).normalize();
        }
        let sin_theta = (1.0 - v.z * v.z).max(0.0).sqrt();
        let (cos_phi, sin_phi) = if sin_theta > 0.0 {
            (v.x / sin_theta, v.y / sin_theta)
        } else {
            (1.0, 0.0)
        };
        let s = beckmann_slopes(v.z, u);
        let s = Vec2::new(cos_phi * s.x - sin_phi * s.y, sin_phi * s.x + cos_phi * s.y)
            * Vec2::new(self.alpha, self.alpha_v);
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
mod tests {
    use super::*;
    use crate::testing::{chi_square, dir, distributions, hemisphere};

    /// Independent of the sampler: the projected area of the microfacets is the macro-surface's,
    /// int D(m) m.z dm = 1, and the visible normals' density integrates to 1 from every direction (which
    /// checks G1 against D: Smith's G1 is exactly what makes it so).
    #[test]
    fn densities_integrate_to_one() {
        for mf in distributions() {
            let n = if mf.alpha.min(mf.alpha_v) < 0.1 { 1200 } else { 400 };
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

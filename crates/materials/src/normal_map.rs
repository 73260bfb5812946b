//! Bump and normal maps on the host (their kernel code is `shaders/materials/normal_map.glsl`): the
//! perturbed normal each gives, as Mitsuba 3's src/bsdfs/bumpmap.cpp and normalmap.cpp compute it, and the
//! shadowing term a perturbed normal gives the BSDF (Estevez et al. 2019, Mitsuba's
//! `use_shadowing_function`). The texture lookups that feed them are the twin's (crates/reference).

use glam::{Vec2, Vec3};

/// Mitsuba's Frame3f::tan_theta_2 of `w` about `n`.
fn tan_theta_2(w: Vec3, n: Vec3) -> f32 {
    let c = w.dot(n);
    (1.0 - c * c).max(0.0) / (c * c)
}

/// The shadowing term of a hit's map: alpha^2 about the unperturbed normal `n0`; alpha^2 = 0 where there is
/// no map (or it left the normal as it was).
#[derive(Clone, Copy, Debug, Default)]
pub struct Bump {
    pub alpha2: f32,
    pub n0: Vec3,
}

impl Bump {
    /// The term of perturbed normal `n` about the unperturbed `n0`: alpha^2 = min(tan^2(theta) / 8, 1).
    pub fn of(n: Vec3, n0: Vec3) -> Bump {
        Bump {
            alpha2: (0.125 * tan_theta_2(n, n0)).min(1.0),
            n0,
        }
    }

    /// normal_map.glsl's `bump_shadowing`: the term for light-side direction `w`.
    pub fn shadowing(&self, w: Vec3) -> f32 {
        if self.alpha2 == 0.0 {
            return 1.0;
        }
        2.0 / (1.0 + (1.0 + self.alpha2 * tan_theta_2(w, self.n0)).sqrt())
    }
}

/// A bump map's normal: dp/du and dp/dv moved along the unperturbed normal `n0` by the height's gradient
/// `grad` (its scale applied), crossed, and turned to the side of `front`.
pub fn bumped(dpdu: Vec3, dpdv: Vec3, n0: Vec3, grad: Vec2, front: Vec3) -> Vec3 {
    let du = dpdu + n0 * (grad.x - n0.dot(dpdu));
    let dv = dpdv + n0 * (grad.y - n0.dot(dpdv));
    let n = du.cross(dv).normalize();
    if front.dot(n) < 0.0 {
        -n
    } else {
        n
    }
}

/// A normal map's normal: `c` (the texture's 2 rgb - 1) in the frame of `n0` whose s is dp/du made
/// orthogonal to it and t = n0 x s.
pub fn mapped(dpdu: Vec3, n0: Vec3, c: Vec3) -> Vec3 {
    let s = (dpdu - n0 * n0.dot(dpdu)).normalize();
    let t = n0.cross(s);
    (c.x * s + c.y * t + c.z * n0).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bump map's height h = s u on a unit square (dp/du = x, dp/dv = y, n = z) tilts the normal to
    /// normalize(-s, 0, 1), the closed form of cross(x + s z, y); the identity normal map leaves z.
    #[test]
    fn the_maps_give_their_closed_forms() {
        let s = 0.7;
        let n = bumped(Vec3::X, Vec3::Y, Vec3::Z, Vec2::new(s, 0.0), Vec3::Z);
        assert!((n - Vec3::new(-s, 0.0, 1.0).normalize()).length() < 1e-6, "{n}");
        let n = mapped(Vec3::X, Vec3::Z, Vec3::Z);
        assert!((n - Vec3::Z).length() < 1e-7, "{n}");
        let n = mapped(2.0 * Vec3::X + Vec3::Z, Vec3::Z, Vec3::new(1.0, 0.0, 1.0));
        assert!((n - Vec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-6, "{n}");
        assert_eq!(Bump::of(Vec3::Z, Vec3::Z).shadowing(Vec3::X), 1.0);
    }

    /// The shadowing term is 1 without tilt, and Mitsuba's closed form otherwise: tilt 45 degrees
    /// (tan^2 = 1, alpha^2 = 1/8) and a direction at 60 degrees (tan^2 = 3): 2 / (1 + sqrt(1 + 3/8)).
    #[test]
    fn shadowing_term_is_estevez_closed_form() {
        assert_eq!(Bump::default().shadowing(Vec3::new(0.3, 0.1, 0.9).normalize()), 1.0);
        let b = Bump {
            alpha2: 0.125,
            n0: Vec3::Z,
        };
        let w = Vec3::new(60f32.to_radians().sin(), 0.0, 60f32.to_radians().cos());
        let want = 2.0 / (1.0 + (1.0f32 + 3.0 / 8.0).sqrt());
        assert!(
            (b.shadowing(w) - want).abs() < 1e-6,
            "{} against {want}",
            b.shadowing(w)
        );
    }
}

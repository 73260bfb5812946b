//! photon/targets.glsl: emitted photons aimed at the spheres around what casts caustics
//! (`RenderParams::targets`, from crates/engine/src/lower/targets.rs), each weighted by the cosine density
//! over the mixture's. The same f32 operations and random numbers as the kernel.

use glam::Vec3;
use ppm_vk_kernels::layout::RenderParams;
use ppm_vk_materials::math::{cosine_direction, onb, PI};

use crate::rng::Rng;

/// targets.glsl's `target_cone`: target k's axis from o, cos a, 1 - cos a, and whether o is outside it.
fn target_cone(p: &RenderParams, k: usize, o: Vec3) -> (Vec3, f32, f32, bool) {
    let t = p.targets[k];
    let to = Vec3::new(t[0], t[1], t[2]) - o;
    let dist2 = to.dot(to);
    let sin2 = t[3] * t[3] / dist2;
    let axis = to * (1.0 / dist2.sqrt());
    let cos_a = (1.0 - sin2).max(0.0).sqrt();
    (axis, cos_a, sin2 / (1.0 + cos_a), sin2 < 1.0)
}

/// The direction an emitted photon leaves o along about the light's normal n, and the weight its flux
/// takes (0: it leaves below the light and ends), drawing u1 and u2, and the choice where the scene has
/// targets (photon.comp's pending draw with `aim`).
pub fn emit(p: &RenderParams, o: Vec3, n: Vec3, rng: &mut Rng) -> (Vec3, f32) {
    let u1 = rng.float();
    let u2 = rng.float();
    let count = p.num_targets;
    if count == 0 {
        return (cosine_direction(n, u1, u2), 1.0);
    }
    let c = rng.float();
    let s = p.target_share;
    let mut d = cosine_direction(n, u1, u2);
    if c < s {
        let j = ((c / s * count as f32) as u32).min(count - 1) as usize;
        let (axis, _, one_minus, outside) = target_cone(p, j, o);
        if outside {
            let cos_t = 1.0 - u1 * one_minus;
            let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
            let (t, b) = onb(axis);
            let phi = 2.0 * PI * u2;
            d = (sin_t * phi.cos() * t + sin_t * phi.sin() * b + cos_t * axis).normalize();
        }
    }
    let cos_n = d.dot(n);
    if !(cos_n > 0.0) {
        return (d, 0.0);
    }
    let mut cosine = 1.0 - s;
    let mut cones = 0.0f32;
    for k in 0..count as usize {
        let (axis, cos_a, one_minus, outside) = target_cone(p, k, o);
        if !outside {
            cosine += s / count as f32;
        } else if d.dot(axis) >= cos_a {
            cones += 1.0 / (2.0 * PI * one_minus);
        }
    }
    (d, cos_n / (cosine * cos_n + PI * s / count as f32 * cones))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A light facing down at o, two targets below it (one partly behind the light's plane is not: both
    /// below), half the photons aimed.
    fn params() -> RenderParams {
        let mut p = RenderParams {
            num_targets: 2,
            target_share: 0.5,
            ..Default::default()
        };
        p.targets[0] = [0.3, 0.5, 0.1, 0.1];
        p.targets[1] = [-0.5, 0.2, 0.3, 0.3];
        p
    }

    /// The weight is the cosine density over the mixture's, so under the mixture its mean is the cosine
    /// density's integral over the hemisphere, 1, and its mean over a target's cone the cosine
    /// probability of that cone (estimated by plain cosine draws); while the mixture puts at least half
    /// the share into each cone, many times what the cosine does.
    #[test]
    fn the_weight_keeps_the_cosine_expectation_and_the_share_goes_to_the_cones() {
        let p = params();
        let (o, n) = (Vec3::new(0.0, 1.5, 0.0), Vec3::new(0.0, -1.0, 0.0));
        let samples = 1_000_000;
        let mut rng = Rng::new(7, 1);
        let (mut sum, mut sum2, mut in_cone, mut weighted_cone) = (0f64, 0f64, 0u32, 0f64);
        let (axis, cos_a, _, _) = target_cone(&p, 0, o);
        for _ in 0..samples {
            let (d, w) = emit(&p, o, n, &mut rng);
            let (w, inside) = (w as f64, d.dot(axis) >= cos_a);
            sum += w;
            sum2 += w * w;
            in_cone += inside as u32;
            weighted_cone += if inside { w } else { 0.0 };
        }
        let mean = sum / samples as f64;
        let sigma = ((sum2 / samples as f64 - mean * mean) / samples as f64).sqrt();
        assert!((mean - 1.0).abs() < 4.0 * sigma + 1e-6, "mean weight {mean} +- {sigma}");
        let mut plain = 0u32;
        let mut rng = Rng::new(8, 1);
        for _ in 0..4 * samples {
            let d = cosine_direction(n, rng.float(), rng.float());
            plain += (d.dot(axis) >= cos_a) as u32;
        }
        let q = plain as f64 / (4 * samples) as f64;
        let q_sigma = (q * (1.0 - q) / (4 * samples) as f64).sqrt();
        let aimed = weighted_cone / samples as f64;
        assert!(
            (aimed - q).abs() < 5.0 * q_sigma + 4.0 * q / (in_cone as f64).sqrt(),
            "the cone's weighted share {aimed} against the cosine's {q} +- {q_sigma}"
        );
        let share = in_cone as f64 / samples as f64;
        assert!(
            share > 0.25 && share > 10.0 * q,
            "{share} of the photons in the cone, cosine {q}"
        );
    }

    /// Without targets the draw is the cosine's, two numbers, weight 1; a light inside a target's sphere
    /// is never aimed at it.
    #[test]
    fn no_targets_or_a_light_inside_one_is_the_cosine() {
        let (o, n) = (Vec3::new(0.0, 1.5, 0.0), Vec3::new(0.0, -1.0, 0.0));
        let (mut a, mut b) = (Rng::new(3, 3), Rng::new(3, 3));
        let none = RenderParams::default();
        let (d, w) = emit(&none, o, n, &mut a);
        assert_eq!((d, w), (cosine_direction(n, b.float(), b.float()), 1.0));
        assert_eq!(a.float(), b.float(), "the same numbers drawn");
        let mut p = params();
        p.num_targets = 1;
        p.targets[0] = [0.0, 1.4, 0.0, 0.5];
        let mut rng = Rng::new(5, 5);
        for _ in 0..1000 {
            let (_, w) = emit(&p, o, n, &mut rng);
            assert!((w - 1.0).abs() < 1e-6, "weight {w} with the light inside the target");
        }
    }
}

//! Mitsuba's `blendbsdf` on the host (its kernel code is `shaders/materials/blend.glsl`): f = (1 - w) f_0 +
//! w f_1 with w a weight in [0, 1], a constant or a texture's luminance (Mitsuba 3's src/bsdfs/blendbsdf.cpp
//! reads `weight` with `eval_1`, which for an RGB bitmap is `luminance(interpolate_3(..))`,
//! src/textures/bitmap.cpp). The kernels pick one component per surface interaction, component 1 with
//! probability w, as Mitsuba's `sample` does; the chosen one then is the surface at that vertex.

use glam::Vec3;

/// Most blends nested in one another along any chain of a material (a blend of two plain surfaces is 1
/// deep). The kernels resolve a hit's material in at most this many steps (blend.glsl's loop), so a
/// deeper one would be left a blend; `Scene::validate` refuses it.
pub const MAX_BLEND_DEPTH: u32 = 4;

/// Mitsuba's `luminance` of linear RGB (src/core/spectrum.h, its RGB variants): a float texture's value
/// read from an RGB bitmap or colour.
pub fn luminance(rgb: Vec3) -> f32 {
    rgb.dot(Vec3::new(0.212671, 0.715160, 0.072169))
}

/// Whether choosing between the components needs a random number: only for 0 < w < 1. At 0 and 1 the
/// choice is certain and no number is drawn, so that such a blend renders bit for bit as the component it
/// is (the path's later random numbers unchanged).
pub fn needs_sample(weight: f32) -> bool {
    weight > 0.0 && weight < 1.0
}

/// The component a blend of weight `weight` picks: false the first, true the second; `u` (uniform in
/// [0, 1), drawn only where [`needs_sample`]) picks the second with probability w: P(u < w) = w.
pub fn second(weight: f32, u: impl FnOnce() -> f32) -> bool {
    if needs_sample(weight) {
        u() < weight
    } else {
        weight >= 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn luminance_weights_sum_to_one() {
        assert!((luminance(Vec3::ONE) - 1.0).abs() < 1e-6);
        assert_eq!(luminance(Vec3::ZERO), 0.0);
        assert!((luminance(Vec3::Y) - 0.715160).abs() < 1e-7);
    }

    /// The extremes draw nothing and pick their component; between them the second component's frequency
    /// is w (binomial, 6 sigma).
    #[test]
    fn second_is_picked_with_probability_w() {
        assert!(!second(0.0, || panic!("no draw at w = 0")));
        assert!(second(1.0, || panic!("no draw at w = 1")));
        let mut rng = Rng::new(7, 3);
        for w in [0.1f32, 0.5, 0.93] {
            let n = 200_000;
            let hits = (0..n).filter(|_| second(w, || rng.float())).count() as f64;
            let p = w as f64;
            let sigma = (n as f64 * p * (1.0 - p)).sqrt();
            assert!((hits - n as f64 * p).abs() < 6.0 * sigma, "w {w}: {hits} of {n}");
        }
    }
}

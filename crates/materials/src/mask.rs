//! Mitsuba's `mask` (shaders/materials/mask.glsl): a surface there with probability `opacity`, passed
//! through otherwise. The choice is made where a ray meets the surface, by a hash of the ray, the primitive
//! and the render's seed (why a hash and not the path's random stream: mask.glsl); this is that hash, the
//! same integer arithmetic as the kernels, and what the CPU twin decides with.

use glam::Vec3;

/// mask.glsl's primitive keys: a quad's and a sphere's side (0 near, 1 far) above the triangles' indices.
pub const PRIM_QUAD: u32 = 0x8000_0000;
pub const PRIM_SPHERE: u32 = 0x4000_0000;

/// The PCG hash of Jarzynski and Olano ("Hash Functions for GPU Rendering", JCGT 2020): `mask_pcg`.
pub fn pcg(v: u32) -> u32 {
    let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

/// `mask_uniform`: uniform in [0, 1) for the ray of key `key` (drawn from its path's stream) meeting
/// primitive `prim`: the top 24 bits.
pub fn uniform(key: u32, prim: u32) -> f32 {
    let h = pcg(pcg(key) ^ prim);
    (h >> 8) as f32 * (1.0 / 16777216.0)
}

/// Mitsuba's luminance of a linear sRGB colour, 0.212671 r + 0.715160 g + 0.072169 b (its `eval_1` of an
/// RGB texture, which a mask's opacity is; texture.glsl's `luminance`), written so that a grey is its own
/// value exactly (the weights sum to 1): opacity 1 given as a colour stops every ray.
pub fn luminance(c: Vec3) -> f32 {
    c.y + 0.212671 * (c.x - c.y) + 0.072169 * (c.z - c.y)
}

/// Whether a ray meeting a surface of `opacity` stops there (`mask_keeps`, given its uniform number).
pub fn keeps(opacity: f32, u: f32) -> bool {
    u < opacity.clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The decisions are what the estimator needs: a fraction `opacity` of rays (keys drawn from a stream)
    /// stops, the primitives one ray meets decide independently (the two sides of a sphere too), and
    /// opacity 1 and 0 are exact.
    #[test]
    fn a_fraction_opacity_of_rays_stops_and_primitives_decide_independently() {
        let n = 200_000u32;
        let mut rng = crate::rng::Rng::new(3, 9);
        for opacity in [0.1f32, 0.5, 0.9] {
            let (mut stops, mut both) = (0u32, 0u32);
            for _ in 0..n {
                let key = rng.next_u32();
                stops += keeps(opacity, uniform(key, 12)) as u32;
                // Sphere 3's far side against its near side, and two neighbouring triangles.
                let sides =
                    keeps(opacity, uniform(key, PRIM_SPHERE | 7)) && keeps(opacity, uniform(key, PRIM_SPHERE | 6));
                let tris = keeps(opacity, uniform(key, 40)) && keeps(opacity, uniform(key, 41));
                both += sides as u32 + tris as u32;
            }
            let p = opacity as f64;
            let sd = (p * (1.0 - p) / n as f64).sqrt();
            let got = stops as f64 / n as f64;
            assert!((got - p).abs() < 5.0 * sd, "opacity {opacity}: {got}");
            let got2 = both as f64 / (2 * n) as f64;
            assert!(
                (got2 - p * p).abs() < 5.0 * sd,
                "opacity {opacity}: both {got2} vs {}",
                p * p
            );
        }
        for k in 0..100_000u32 {
            let u = uniform(k, k.wrapping_mul(2654435761));
            assert!((0.0..1.0).contains(&u));
            assert!(keeps(1.0, u) && !keeps(0.0, u));
        }
    }

    #[test]
    fn luminance_is_mitsubas_and_exact_on_greys() {
        for v in [0.0f32, 0.3, 0.5, 1.0, 7.25] {
            assert_eq!(luminance(Vec3::splat(v)), v);
        }
        let c = Vec3::new(0.9, 0.2, 0.4);
        let want = 0.212671 * 0.9 + 0.715160 * 0.2 + 0.072169 * 0.4;
        assert!((luminance(c) - want).abs() < 1e-7);
    }
}

//! The light table (lights.glsl): emitting quads and triangles chosen in proportion to their power, and
//! the fixed-point scale of the photon flux sums, which the lights' power bounds.

use glam::Vec3;
use ppm_vk_kernels::layout::{Light, Triangle, LIGHT_QUAD, LIGHT_TRIANGLE};

use crate::error::{Error, Result};
use crate::scene::Scene;

/// The lights of `scene` (`triangles`: its BVH's, in leaf order) and their total emitted power per channel.
pub fn lights(scene: &Scene, triangles: &[Triangle]) -> Result<(Vec<Light>, [f64; 3])> {
    // Lights: emitting quads and triangles, chosen in proportion to their power (summed over RGB).
    // A Lambertian emitter of radiance L and area A emits L A pi.
    let mut lights = Vec::new();
    let mut total_power = [0f64; 3];
    let mut add = |index: u32, kind: u32, emission: Vec3, area: f32| {
        let power = emission * area * std::f32::consts::PI;
        for c in 0..3 {
            total_power[c] += power[c] as f64;
        }
        lights.push(Light {
            index,
            kind,
            power: power.to_array(),
            ..Default::default()
        });
    };
    for qi in scene.lights() {
        let q = &scene.quads[qi as usize];
        add(qi, LIGHT_QUAD, scene.materials[q.material as usize].emission, q.area());
    }
    for (ti, t) in triangles.iter().enumerate() {
        let e = scene.materials[t.material as usize].emission;
        if e.max_element() > 0.0 {
            let (v0, v1, v2) = (Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2));
            add(ti as u32, LIGHT_TRIANGLE, e, 0.5 * (v1 - v0).cross(v2 - v0).length());
        }
    }
    let sum: f64 = lights
        .iter()
        .map(|l| l.power.iter().map(|&p| p as f64).sum::<f64>())
        .sum();
    if lights.is_empty() || sum <= 0.0 {
        let what = "no light emits power: every emitter's emission x area x pi rounds to 0 in 32-bit floats \
                    (raise the emission or the emitters' size)";
        return Err(Error::scene(&scene.name, 0, 0, "", what));
    }
    let mut run = 0f64;
    for l in &mut lights {
        run += l.power.iter().map(|&p| p as f64).sum::<f64>() / sum;
        l.cdf = run as f32;
    }
    if let Some(last) = lights.last_mut() {
        last.cdf = 1.0; // no photon may fall past the last light through rounding
    }
    // Each light's probability is the share of [0, 1) its f32 cdf gives it, so that power / prob stays
    // unbiased where 100k lights make the rounding of the running sum matter.
    let mut previous = 0f64;
    for l in &mut lights {
        l.prob = (l.cdf as f64 - previous) as f32;
        previous = l.cdf as f64;
    }
    if let Some(i) = lights.iter().position(|l| l.prob.is_nan() || l.prob <= 0.0) {
        let message = format!(
            "light {i} of {} has too small a share of the total power to be chosen in an f32 light table \
             (split the scene's lights more evenly)",
            lights.len()
        );
        return Err(Error::scene(&scene.name, 0, 0, "", message));
    }
    Ok((lights, total_power))
}

/// The fixed-point scale of the photon flux sums (`RenderParams::flux_fixed`): a power of two that keeps
/// the most flux one photon carries under 2^30.
pub fn flux_fixed(scene: &Scene, lights: &[Light]) -> Result<f32> {
    // No photon carries more flux than it leaves its light with (roulette divides by the largest
    // albedo, mirrors, glass and thin panes never amplify, a plastic's branches weigh at most 1:
    // plastic.glsl), so this bounds one photon's share of a fixed-point sum.
    let max_flux = lights
        .iter()
        .flat_map(|l| l.power.map(|p| p as f64 / l.prob as f64))
        .fold(0f64, f64::max);
    let flux_fixed = 2f64.powi((2f64.powi(30) / max_flux).log2().floor() as i32) as f32;
    if !(flux_fixed.is_finite() && flux_fixed > 0.0) {
        return Err(Error::scene(
            &scene.name,
            0,
            0,
            "",
            format!("light power {max_flux} W is out of the representable range"),
        ));
    }
    Ok(flux_fixed)
}

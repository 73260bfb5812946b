//! Lights that are not emitting surfaces: points, spots, the sun (directional) and environments (a
//! constant radiance, or a latitude-longitude map), as Mitsuba 3 defines them. Emitting quads, triangles
//! and spheres are materials with `emission` (model.rs); these are the rest. The engine lowers both into
//! one light table (crates/engine/src/lower/lights.rs) and shaders/common/lights.glsl samples it.

use glam::{Mat3, Vec3};

/// A light with no surface of its own (`Scene::emitters`).
#[derive(Clone, Debug, PartialEq)]
pub enum Emitter {
    /// Mitsuba's `point`: radiant intensity `intensity` (W/sr) in every direction from `position`.
    Point { position: Vec3, intensity: Vec3 },
    /// Mitsuba's `spot`: intensity `intensity` along `direction` (unit), full out to `beam` (radians from the
    /// axis), falling linearly in angle to 0 at `cutoff` (radians, `beam <= cutoff <= pi / 2`).
    Spot {
        position: Vec3,
        direction: Vec3,
        intensity: Vec3,
        cutoff: f32,
        beam: f32,
    },
    /// Mitsuba's `directional` (the sun): irradiance `irradiance` (W/m^2, on a plane facing it) arriving
    /// along `direction` (unit, the way the light travels).
    Directional { direction: Vec3, irradiance: Vec3 },
    /// Mitsuba's `constant` (no map) and `envmap`: radiance arriving from every direction, at infinity.
    Environment(Environment),
}

/// An environment: `scale` times the map's radiance in a direction (or `scale` itself without a map).
#[derive(Clone, Debug, PartialEq)]
pub struct Environment {
    /// The constant's radiance, or the map's scale (linear RGB).
    pub scale: Vec3,
    pub map: Option<EnvMap>,
    /// Local to world (a rotation): the map's up is local +y, its u = 0 column local -z, u = 0.5 local +z (Mitsuba's
    /// convention: u = atan2(x, -z) / 2 pi, v = acos(y) / pi of the local direction).
    pub to_world: Mat3,
}

/// A latitude-longitude map of linear RGB radiance, row by row from the top (v = 0, local +y).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvMap {
    /// The file it came from (for messages; not hashed).
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec3>,
}

/// The most pixels an environment map may have (a 16k x 8k map; its sampling tables are as large again).
pub const MAX_ENVMAP_PIXELS: u64 = 1 << 27;

impl Emitter {
    /// The element's name in Mitsuba's terms, for messages.
    pub fn kind(&self) -> &'static str {
        match self {
            Emitter::Point { .. } => "point",
            Emitter::Spot { .. } => "spot",
            Emitter::Directional { .. } => "directional",
            Emitter::Environment(Environment { map: None, .. }) => "constant",
            Emitter::Environment(_) => "envmap",
        }
    }

    /// Moves the light with a uniform scale `s` about the origin (`Scene::scaled`): positions scale;
    /// intensities scale by s^2 so that the irradiance they give the scaled scene is unchanged.
    pub fn scaled(&self, s: f32) -> Emitter {
        match self.clone() {
            Emitter::Point { position, intensity } => Emitter::Point {
                position: position * s,
                intensity: intensity * (s * s),
            },
            Emitter::Spot {
                position,
                direction,
                intensity,
                cutoff,
                beam,
            } => Emitter::Spot {
                position: position * s,
                direction,
                intensity: intensity * (s * s),
                cutoff,
                beam,
            },
            other => other,
        }
    }

    /// Checks the values (`path`: the field path of messages, `emitter[i]`).
    pub(crate) fn check(&self, path: &str) -> Result<(), (String, String)> {
        let bad = |field: &str, message: String| Err((format!("{path}.{field}"), message));
        let colour = |field: &str, v: Vec3| -> Result<(), (String, String)> {
            if !v.is_finite() || v.cmplt(Vec3::ZERO).any() {
                return bad(field, format!("every component must be finite and >= 0, got {v}"));
            }
            Ok(())
        };
        let unit = |field: &str, v: Vec3| -> Result<(), (String, String)> {
            if !v.is_finite() || (v.length() - 1.0).abs() > 1e-3 {
                return bad(field, format!("must be a finite unit vector, got {v}"));
            }
            Ok(())
        };
        let point = |field: &str, v: Vec3| -> Result<(), (String, String)> {
            if !v.is_finite() {
                return bad(field, format!("must be finite, got {v}"));
            }
            Ok(())
        };
        match self {
            Emitter::Point { position, intensity } => {
                point("position", *position)?;
                colour("intensity", *intensity)
            }
            Emitter::Spot {
                position,
                direction,
                intensity,
                cutoff,
                beam,
            } => {
                point("position", *position)?;
                unit("direction", *direction)?;
                colour("intensity", *intensity)?;
                if !(cutoff.is_finite() && *cutoff > 0.0 && *cutoff <= std::f32::consts::FRAC_PI_2) {
                    return bad(
                        "cutoff_angle",
                        format!("must be in (0, 90] degrees, got {}", cutoff.to_degrees()),
                    );
                }
                if !(beam.is_finite() && *beam > 0.0 && beam <= cutoff) {
                    return bad(
                        "beam_width",
                        format!(
                            "must be in (0, cutoff_angle = {}] degrees, got {}",
                            cutoff.to_degrees(),
                            beam.to_degrees()
                        ),
                    );
                }
                Ok(())
            }
            Emitter::Directional { direction, irradiance } => {
                unit("direction", *direction)?;
                colour("irradiance", *irradiance)
            }
            Emitter::Environment(env) => {
                colour(if env.map.is_some() { "scale" } else { "radiance" }, env.scale)?;
                let m = env.to_world;
                let orthonormal = (m.transpose() * m - Mat3::IDENTITY)
                    .to_cols_array()
                    .iter()
                    .all(|x| x.abs() < 1e-3);
                if !m.is_finite() || !orthonormal {
                    return bad(
                        "to_world",
                        "must be a rotation (no scale or shear for an environment)".into(),
                    );
                }
                if let Some(map) = &env.map {
                    let n = u64::from(map.width) * u64::from(map.height);
                    if map.width < 2 || map.height < 2 || n != map.pixels.len() as u64 {
                        return bad(
                            "filename",
                            format!(
                                "{}: {} x {} with {} pixels: an environment map needs at least 2 x 2",
                                map.name,
                                map.width,
                                map.height,
                                map.pixels.len()
                            ),
                        );
                    }
                    if n > MAX_ENVMAP_PIXELS {
                        return bad(
                            "filename",
                            format!(
                                "{}: {n} pixels, more than MAX_ENVMAP_PIXELS = {MAX_ENVMAP_PIXELS}",
                                map.name
                            ),
                        );
                    }
                    if let Some(p) = map.pixels.iter().find(|p| !p.is_finite() || p.cmplt(Vec3::ZERO).any()) {
                        return bad(
                            "filename",
                            format!("{}: a pixel is {p}: radiance must be finite and >= 0", map.name),
                        );
                    }
                }
                Ok(())
            }
        }
    }

    /// Whether it gives any light (a light of zero power is allowed, but is not a scene's light).
    pub fn emits(&self) -> bool {
        let positive = |v: &Vec3| v.max_element() > 0.0;
        match self {
            Emitter::Point { intensity, .. } | Emitter::Spot { intensity, .. } => positive(intensity),
            Emitter::Directional { irradiance, .. } => positive(irradiance),
            Emitter::Environment(env) => {
                positive(&env.scale) && env.map.as_ref().is_none_or(|m| m.pixels.iter().any(positive))
            }
        }
    }
}

/// Mitsuba's latitude-longitude direction of texture coordinates (u, v): local y up, u = 0 towards -z, u = 0.25 towards +x.
pub fn envmap_direction(u: f32, v: f32) -> Vec3 {
    let phi = u * 2.0 * std::f32::consts::PI;
    let theta = v * std::f32::consts::PI;
    Vec3::new(phi.sin() * theta.sin(), theta.cos(), -phi.cos() * theta.sin())
}

/// The texture coordinates of local direction d (unit): the inverse of [`envmap_direction`].
pub fn envmap_uv(d: Vec3) -> (f32, f32) {
    let mut u = d.x.atan2(-d.z) * (0.5 / std::f32::consts::PI);
    if u < 0.0 {
        u += 1.0;
    }
    (u, d.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn envmap_coordinates_round_trip() {
        for (u, v) in [(0.1f32, 0.2f32), (0.5, 0.5), (0.9, 0.7), (0.25, 0.99)] {
            let (u2, v2) = envmap_uv(envmap_direction(u, v));
            assert!((u - u2).abs() < 1e-5 && (v - v2).abs() < 1e-5, "{u},{v} -> {u2},{v2}");
        }
        let d = envmap_direction(0.5, 0.5);
        assert!((d - Vec3::Z).length() < 1e-6, "{d}");
        assert!((envmap_direction(0.0, 0.5) + Vec3::Z).length() < 1e-6);
        assert!((envmap_direction(0.3, 0.0) - Vec3::Y).length() < 1e-6);
    }
}

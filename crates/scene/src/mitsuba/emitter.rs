//! The `<emitter>` element: Mitsuba's area emitter inside a shape (its radiance). Other lights (point,
//! spot, directional, constant, environment) are refused at the top level.

use anyhow::Result;
use glam::Vec3;

use super::properties::Props;
use super::xml::Elem;
use super::Builder;

impl Builder {
    /// A top-level `<emitter>`: none is read (ppm-vk's lights are emitting quads and triangles).
    pub(super) fn emitter(&mut self, e: &Elem) -> Result<()> {
        Err(e.err(
            "only area emitters inside a shape are supported (no point, spot, directional, \
             constant or environment lights)",
        ))
    }
}

/// The radiance of an `<emitter>` inside a shape (Mitsuba's default 1).
pub(super) fn area(o: &Elem) -> Result<Vec3> {
    if o.kind() != "area" {
        return Err(o.err("only area emitters are supported on shapes"));
    }
    let (ep, rest) = Props::of(o);
    if let Some(r) = rest.first() {
        return Err(r.err(format!("not expected inside {}", o.what())));
    }
    let radiance = ep.color("radiance")?.unwrap_or(Vec3::ONE);
    ep.finish()?;
    Ok(radiance)
}

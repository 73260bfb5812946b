//! The interior of `scenes/interior.xml` (issue 39): a staircase hall of about 30k triangles, one OBJ per
//! material, since a Mitsuba `obj` shape carries one BSDF. Units: metres, +y up.
//!
//! The hall is x in [-4, 4], y in [0, 6], z in [-5, 3]. A straight flight of 16 steps along the left wall
//! (x in [-3.9, -2.3]) rises from z = 2 to a landing (a slab, top at y = 3) across the back (z in
//! [-5, -2]). A glass balustrade (closed panels 2 cm thick) runs up the open side of the flight and
//! along the landing's edge, held by metal posts under a metal handrail; a metal ring stands on a
//! pedestal in the hall. The scene file places the 13 lights (disks and rectangles).

use glam::DVec3;

use super::{icosphere, torus_model, Model, NO_NORMAL};

/// The hall's extent.
const LO: DVec3 = DVec3::new(-4.0, 0.0, -5.0);
const HI: DVec3 = DVec3::new(4.0, 6.0, 3.0);
/// Steps of the flight, their rise (16 x 0.1875 = 3 m) and run (16 x 0.25 = 4 m).
pub const STEPS: u32 = 16;
const RISE: f64 = 3.0 / STEPS as f64;
const RUN: f64 = 4.0 / STEPS as f64;
/// The flight's sides and where it starts (its foot, z) and ends (the landing's edge).
const STAIR_X: (f64, f64) = (-3.9, -2.3);
const STAIR_FOOT: f64 = 2.0;
const LANDING_EDGE: f64 = -2.0;
const LANDING_TOP: f64 = 3.0;
/// The balustrade's line on the flight (x) and on the landing (z); its rail height above the nosing.
const RAIL_X: f64 = -2.26;
const RAIL_Z: f64 = -2.1;
const RAIL_HEIGHT: f64 = 1.0;
/// Glass panels on the flight and on the landing, and the pedestal's box.
pub const STAIR_PANELS: u32 = 4;
pub const LANDING_PANELS: u32 = 6;
const PEDESTAL: (DVec3, DVec3) = (DVec3::new(1.1, 0.0, 0.1), DVec3::new(1.9, 0.8, 0.9));
/// Texture repeats per metre on the wood (the 512 x 256 wood.png spans 1 x 0.5 m).
const WOOD_UV_PER_M: [f64; 2] = [1.0, 2.0];

/// Height of the flight's nosing line at `z` (the stair's slope).
fn nosing(z: f64) -> f64 {
    ((STAIR_FOOT - z) / (STAIR_FOOT - LANDING_EDGE)).clamp(0.0, 1.0) * LANDING_TOP
}

/// A hexahedron from its 8 corners, indexed by bits (x: 1, y: 2, z: 4) as [`super::box_model`]'s, front
/// sides out; flat (a normal per side), with texture coordinates projected on each side's own axes when `uv` is set.
fn hexa(m: &mut Model, corner: [DVec3; 8], uv: bool) {
    let centre = corner.iter().sum::<DVec3>() / 8.0;
    let c = corner.map(|p| m.vertex(p));
    for axis in 0..3 {
        for side in 0..2u32 {
            let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
            let ring = [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(x, y)| ((side << axis) | (x << a) | (y << b)) as usize);
            let mid = ring.iter().map(|&i| corner[i]).sum::<DVec3>() / 4.0;
            let out = mid - centre;
            let t = match uv {
                // The side's two in-plane axes (the world axes other than its normal's largest).
                true => {
                    let (ua, va) = match out.abs().max_element() {
                        x if x == out.x.abs() => (DVec3::Z, DVec3::Y),
                        y if y == out.y.abs() => (DVec3::X, DVec3::Z),
                        _ => (DVec3::X, DVec3::Y),
                    };
                    ring.map(|i| {
                        m.vt.push([
                            corner[i].dot(ua) * WOOD_UV_PER_M[0],
                            corner[i].dot(va) * WOOD_UV_PER_M[1],
                        ]);
                        m.vt.len() as u32 - 1
                    })
                }
                false => [NO_NORMAL; 4],
            };
            // A flat normal per side (without one, Mitsuba's OBJ loader would smooth across the corners).
            let p = ring.map(|i| corner[i]);
            let normal = (p[1] - p[0]).cross(p[3] - p[0]);
            let n = m.normal(if normal.dot(out) < 0.0 { -normal } else { normal });
            let r = ring.map(|i| c[i]);
            m.face_uv([r[0], r[1], r[2]], [n; 3], [t[0], t[1], t[2]], out);
            m.face_uv([r[0], r[2], r[3]], [n; 3], [t[0], t[2], t[3]], out);
        }
    }
}

fn aabb(lo: DVec3, hi: DVec3) -> [DVec3; 8] {
    std::array::from_fn(|i| {
        DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

/// A closed cylinder from `a` to `b` of radius `r`: `around` segments, `along` bands, flat caps; smooth
/// normals on the side.
fn cylinder(m: &mut Model, a: DVec3, b: DVec3, r: f64, around: u32, along: u32) {
    use std::f64::consts::TAU;
    let axis = (b - a).normalize();
    let (e1, e2) = axis.any_orthonormal_pair();
    let dir = |k: u32| {
        let t = TAU * (k % around) as f64 / around as f64;
        e1 * t.cos() + e2 * t.sin()
    };
    let first = m.v.len() as u32;
    let first_n = m.vn.len() as u32;
    for k in 0..around {
        m.normal(dir(k));
    }
    for j in 0..=along {
        let p = a.lerp(b, j as f64 / along as f64);
        for k in 0..around {
            m.vertex(p + r * dir(k));
        }
    }
    let at = |j: u32, k: u32| first + j * around + k % around;
    for j in 0..along {
        for k in 0..around {
            let q = [at(j, k), at(j, k + 1), at(j + 1, k + 1), at(j + 1, k)];
            let n = [k, k + 1, k + 1, k].map(|k| first_n + k % around);
            let out = dir(k) + dir(k + 1);
            m.face([q[0], q[1], q[2]], [n[0], n[1], n[2]], out);
            m.face([q[0], q[2], q[3]], [n[0], n[2], n[3]], out);
        }
    }
    // Caps: a fan about each end's centre, facing along the axis.
    for (j, centre, out) in [(0, a, -axis), (along, b, axis)] {
        let c = m.vertex(centre);
        let n = m.normal(out);
        for k in 0..around {
            m.face([c, at(j, k), at(j, k + 1)], [n; 3], out);
        }
    }
}

/// A sphere of radius `r` at `centre` (icosphere `level`), with its normals.
fn ball(m: &mut Model, centre: DVec3, r: f64, level: u32) {
    let (v, f) = icosphere(level);
    let (first, first_n) = (m.v.len() as u32, m.vn.len() as u32);
    for p in &v {
        m.vertex(centre + r * *p);
        m.normal(*p);
    }
    for t in f {
        let out = t.iter().map(|&i| v[i as usize]).sum::<DVec3>();
        m.face(t.map(|i| first + i), t.map(|i| first_n + i), out);
    }
}

/// Walls, floor and ceiling (facing in) and the pedestal: plain diffuse.
pub fn shell_obj() -> String {
    let mut m = Model::default();
    m.group("hall", None);
    let c = aabb(LO, HI);
    let centre = (LO + HI) * 0.5;
    let cv = c.map(|p| m.vertex(p));
    for axis in 0..3 {
        for side in 0..2u32 {
            let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
            let r = [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(x, y)| cv[((side << axis) | (x << a) | (y << b)) as usize]);
            let mid = [(0, 0), (1, 1)]
                .map(|(x, y)| c[((side << axis) | (x << a) | (y << b)) as usize])
                .iter()
                .sum::<DVec3>()
                / 2.0;
            // Facing into the hall, flat.
            let n = m.normal(centre - mid);
            m.face([r[0], r[1], r[2]], [n; 3], centre - mid);
            m.face([r[0], r[2], r[3]], [n; 3], centre - mid);
        }
    }
    m.group("pedestal", None);
    hexa(&mut m, aabb(PEDESTAL.0, PEDESTAL.1), false);
    m.write(None)
}

/// The steps, the landing slab and the hall's wooden floor boards (a slab 2 cm thick on the floor
/// would double the floor; the floor instead is a thin deck over the shell's floor): textured.
pub fn wood_obj() -> String {
    let mut m = Model::default();
    m.group("steps", None);
    for i in 0..STEPS {
        let z1 = STAIR_FOOT - i as f64 * RUN;
        let lo = DVec3::new(STAIR_X.0, 0.0, z1 - RUN);
        let hi = DVec3::new(STAIR_X.1, (i + 1) as f64 * RISE, z1);
        hexa(&mut m, aabb(lo, hi), true);
    }
    m.group("landing", None);
    hexa(
        &mut m,
        aabb(
            DVec3::new(LO.x, LANDING_TOP - 0.2, LO.z),
            DVec3::new(HI.x, LANDING_TOP, LANDING_EDGE),
        ),
        true,
    );
    m.group("deck", None);
    hexa(
        &mut m,
        aabb(
            DVec3::new(STAIR_X.1 + 0.3, 0.0, LANDING_EDGE + 0.3),
            DVec3::new(HI.x - 0.3, 0.01, HI.z - 0.3),
        ),
        true,
    );
    m.write(None)
}

/// The glass panels: parallelepipeds 2 cm thick, 5 cm clear of the posts at each end.
pub fn glass_obj() -> String {
    let mut m = Model::default();
    m.group("balustrade", None);
    let (gap, t, low, high) = (0.05, 0.01, 0.08, RAIL_HEIGHT - 0.08);
    // The flight: bottom and top follow the slope.
    let step = (STAIR_FOOT - LANDING_EDGE) / STAIR_PANELS as f64;
    for k in 0..STAIR_PANELS {
        let (z0, z1) = (
            STAIR_FOOT - k as f64 * step - gap,
            STAIR_FOOT - (k + 1) as f64 * step + gap,
        );
        let corner = std::array::from_fn(|i| {
            let x = RAIL_X + if i & 1 == 0 { -t } else { t };
            let z = if i & 4 == 0 { z1 } else { z0 };
            let y = nosing(z) + if i & 2 == 0 { low } else { high };
            DVec3::new(x, y, z)
        });
        hexa(&mut m, corner, false);
    }
    // The landing's edge.
    let (x0, x1) = (RAIL_X, HI.x - 0.1);
    let step = (x1 - x0) / LANDING_PANELS as f64;
    for k in 0..LANDING_PANELS {
        let lo = DVec3::new(x0 + k as f64 * step + gap, LANDING_TOP + low, RAIL_Z - t);
        let hi = DVec3::new(x0 + (k + 1) as f64 * step - gap, LANDING_TOP + high, RAIL_Z + t);
        hexa(&mut m, aabb(lo, hi), false);
    }
    m.write(None)
}

/// Posts, handrails, newel balls and the ring on the pedestal: rough metal. Most of the hall's triangles
/// are here, in round things, as in a modelled interior.
pub fn metal_obj() -> String {
    let mut m = Model::default();
    m.group("posts", None);
    let post = |m: &mut Model, base: DVec3| cylinder(m, base, base + DVec3::Y * RAIL_HEIGHT, 0.02, 48, 6);
    let step = (STAIR_FOOT - LANDING_EDGE) / STAIR_PANELS as f64;
    for k in 0..=STAIR_PANELS {
        let z = STAIR_FOOT - k as f64 * step;
        post(&mut m, DVec3::new(RAIL_X, nosing(z), z));
    }
    let (x0, x1) = (RAIL_X, HI.x - 0.1);
    let step = (x1 - x0) / LANDING_PANELS as f64;
    for k in 1..=LANDING_PANELS {
        post(&mut m, DVec3::new(x0 + k as f64 * step, LANDING_TOP, RAIL_Z));
    }
    m.group("rails", None);
    let top = |z: f64| DVec3::new(RAIL_X, nosing(z) + RAIL_HEIGHT, z);
    cylinder(&mut m, top(STAIR_FOOT), top(LANDING_EDGE), 0.03, 48, 48);
    cylinder(
        &mut m,
        DVec3::new(RAIL_X, LANDING_TOP + RAIL_HEIGHT, RAIL_Z),
        DVec3::new(x1, LANDING_TOP + RAIL_HEIGHT, RAIL_Z),
        0.03,
        48,
        48,
    );
    m.group("newels", None);
    for p in [
        top(STAIR_FOOT),
        top(LANDING_EDGE),
        DVec3::new(x1, LANDING_TOP + RAIL_HEIGHT, RAIL_Z),
    ] {
        ball(&mut m, p + DVec3::Y * 0.04, 0.06, 3);
    }
    m.group("ring", None);
    let (r, tube) = (0.32, 0.07);
    let centre = DVec3::new(
        (PEDESTAL.0.x + PEDESTAL.1.x) / 2.0,
        PEDESTAL.1.y + tube + 0.0005,
        (PEDESTAL.0.z + PEDESTAL.1.z) / 2.0,
    );
    torus_model(&mut m, centre, r, tube, 96, 48);
    m.write(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn faces(text: &str) -> usize {
        text.lines().filter(|l| l.starts_with("f ")).count()
    }

    #[test]
    fn the_hall_has_about_30k_triangles_and_uv_on_the_wood() {
        let counts = [shell_obj(), wood_obj(), glass_obj(), metal_obj()].map(|t| faces(&t));
        assert_eq!(counts[0], 12 + 12, "the shell's 6 sides and the pedestal");
        assert_eq!(counts[1], 12 * (STEPS as usize + 2), "steps, landing, deck");
        assert_eq!(counts[2], 12 * (STAIR_PANELS + LANDING_PANELS) as usize);
        let total: usize = counts.iter().sum();
        assert!((25_000..=35_000).contains(&total), "{total} triangles");
        let wood = wood_obj();
        // Every corner of the wood has a texture coordinate and a normal (v/vt/vn); the others a normal.
        assert!(wood
            .lines()
            .filter(|l| l.starts_with("f "))
            .all(|l| l
                .split(' ')
                .skip(1)
                .all(|c| c.split('/').count() == 3 && !c.contains("//"))));
        for t in [shell_obj(), glass_obj(), metal_obj()] {
            assert!(t
                .lines()
                .filter(|l| l.starts_with("f "))
                .all(|l| l.split(' ').skip(1).all(|c| c.contains("//"))));
        }
    }
}

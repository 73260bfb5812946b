//! `shaders/common/bvh.glsl` in Rust, operation for operation, over the same flattened nodes: the BVH
//! traversal and the watertight ray/triangle test (Woop, Benthin and Wald 2013). Rust never fuses a
//! multiply-add, and the GLSL marks those operations `precise`, so both compute the same bits. Also a
//! brute-force intersector over all triangles, the independent check of the traversal.

use glam::{Vec2, Vec3};
use ppm_vk_kernels::layout::{BvhNode, Triangle, BVH_EMPTY, BVH_LEAF};
use ppm_vk_materials::math::v3;

/// `BVH_ROBUST`: 1 + 2 gamma(3), the slab test's far distance widened by its rounding error bound (the
/// same literal as bvh.glsl).
#[allow(clippy::excessive_precision)]
pub const ROBUST: f32 = 1.0000003576;
/// `BVH_TINY`: a direction component below this makes the ray parallel to that axis's slab.
const TINY: f32 = 1e-30;
/// `BVH_HUGE`: an infinite distance in the slab test.
const HUGE: f32 = 3e38;

/// A ray prepared for the box and triangle tests (`BvhRay` of bvh.glsl).
#[derive(Clone, Copy, Debug)]
pub struct BvhRay {
    pub o: Vec3,
    pub d: Vec3,
    /// 1 / d, 0 on the parallel axes.
    pub inv_d: Vec3,
    /// |d| < TINY per axis.
    pub parallel: [bool; 3],
    /// kx, ky, kz: kz the axis of the largest |d|; kx, ky swapped when d[kz] < 0.
    pub k: [usize; 3],
    /// d[kx] / d[kz], d[ky] / d[kz], 1 / d[kz].
    pub s: Vec3,
}

impl BvhRay {
    pub fn new(o: Vec3, d: Vec3) -> BvhRay {
        let ad = d.abs();
        let parallel = [ad.x < TINY, ad.y < TINY, ad.z < TINY];
        let inv = |x: f32, p: bool| if p { 0.0 } else { 1.0 / x };
        let inv_d = Vec3::new(inv(d.x, parallel[0]), inv(d.y, parallel[1]), inv(d.z, parallel[2]));
        let mut kz = 0;
        if ad.y > ad[kz] {
            kz = 1;
        }
        if ad.z > ad[kz] {
            kz = 2;
        }
        let mut kx = if kz == 2 { 0 } else { kz + 1 };
        let mut ky = if kx == 2 { 0 } else { kx + 1 };
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let sz = 1.0 / d[kz];
        BvhRay {
            o,
            d,
            inv_d,
            parallel,
            k: [kx, ky, kz],
            s: Vec3::new(d[kx] * sz, d[ky] * sz, sz),
        }
    }
}

/// One slab of a child's box along axis `k` (`bvh_slab`): entry and exit distances; a ray parallel to the
/// slab is inside it for every t (its origin within the slab, faces included) or none.
fn slab(r: &BvhRay, k: usize, lo: f32, hi: f32) -> (f32, f32) {
    let t0 = (lo - r.o[k]) * r.inv_d[k];
    let t1 = (hi - r.o[k]) * r.inv_d[k];
    if r.parallel[k] {
        let near = if lo <= r.o[k] && r.o[k] <= hi { -HUGE } else { HUGE };
        return (near, -near);
    }
    (t0.min(t1), t0.max(t1))
}

/// The watertight test (`bvh_triangle_test`): (t, barycentric weights of v1 and v2) for a hit with t in
/// (tmin, tmax). Two-sided; an edge function of exactly 0 counts as inside.
pub fn triangle_test(r: &BvhRay, v0: Vec3, v1: Vec3, v2: Vec3, tmin: f32, tmax: f32) -> Option<(f32, Vec2)> {
    let [kx, ky, kz] = r.k;
    let (a0, b0, c0) = (v0 - r.o, v1 - r.o, v2 - r.o);
    let a = Vec3::new(a0[kx], a0[ky], a0[kz]);
    let b = Vec3::new(b0[kx], b0[ky], b0[kz]);
    let c = Vec3::new(c0[kx], c0[ky], c0[kz]);
    let ax = a.x - r.s.x * a.z;
    let ay = a.y - r.s.y * a.z;
    let bx = b.x - r.s.x * b.z;
    let by = b.y - r.s.y * b.z;
    let cx = c.x - r.s.x * c.z;
    let cy = c.y - r.s.y * c.z;
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 {
        return None;
    }
    let az = r.s.z * a.z;
    let bz = r.s.z * b.z;
    let cz = r.s.z * c.z;
    let tt = u * az + v * bz + w * cz;
    let rcp = 1.0 / det;
    let t = tt * rcp;
    if !(t > tmin && t < tmax) {
        return None;
    }
    Some((t, Vec2::new(v, w) * rcp))
}

/// A hit of [`intersect`] or [`brute_force`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BvhHit {
    pub t: f32,
    /// Index into the leaf-ordered triangles.
    pub triangle: u32,
    /// Barycentric weights of v1 and v2.
    pub bary: Vec2,
}

/// What one traversal did (`BvhHit` of bvh.glsl).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Traversal {
    pub hit: Option<BvhHit>,
    /// Node visits plus triangle tests.
    pub steps: u32,
    /// Stopped after `budget` steps with work left: `hit` is not final.
    pub cut: bool,
    /// Most entries the stack held (not reported by the GPU).
    pub stack_peak: u32,
}

/// `bvh_intersect`: the nearest hit of o + t d, t in (tmin, tmax), through the 4-wide BVH, taking at most
/// `budget` steps, step for step as bvh.glsl (each step: a pop, a node visit, a leaf taken, a triangle
/// tested, whichever this ray has to do). Panics if the stack overflows (`Bvh::validate_wide` refuses
/// such a tree).
pub fn intersect(
    nodes: &[BvhNode],
    tris: &[Triangle],
    o: Vec3,
    d: Vec3,
    tmin: f32,
    tmax: f32,
    budget: u32,
) -> Traversal {
    traverse(nodes, tris, o, d, tmin, tmax, budget, false, |_, _| true)
}

/// [`intersect`] with bvh.glsl's `bvh_filter`: `keep(i, b)` says whether a hit on triangle i at
/// barycentric weights b stops the ray (false: a masked surface it passes).
#[allow(clippy::too_many_arguments)]
pub fn intersect_filtered(
    nodes: &[BvhNode],
    tris: &[Triangle],
    o: Vec3,
    d: Vec3,
    tmin: f32,
    tmax: f32,
    budget: u32,
    keep: impl Fn(u32, Vec2) -> bool,
) -> Traversal {
    traverse(nodes, tris, o, d, tmin, tmax, budget, false, keep)
}

/// `bvh_intersect` with `any_hit`: a shadow ray, ended by the first hit the traversal finds.
pub fn intersect_any(
    nodes: &[BvhNode],
    tris: &[Triangle],
    o: Vec3,
    d: Vec3,
    tmin: f32,
    tmax: f32,
    budget: u32,
) -> Traversal {
    traverse(nodes, tris, o, d, tmin, tmax, budget, true, |_, _| true)
}

// Mirrors bvh.glsl's bvh_intersect argument for argument, so the twin reads line by line against it.
#[allow(clippy::too_many_arguments)]
fn traverse(
    nodes: &[BvhNode],
    tris: &[Triangle],
    o: Vec3,
    d: Vec3,
    tmin: f32,
    tmax: f32,
    budget: u32,
    any_hit: bool,
    keep: impl Fn(u32, Vec2) -> bool,
) -> Traversal {
    let r = BvhRay::new(o, d);
    let mut best = tmax;
    let mut hit = None;
    let mut steps = 0u32;
    let mut cut = false;
    let mut stack = [(0u32, 0f32); ppm_vk_engine::bvh::STACK as usize];
    let mut sp = 0usize;
    let mut stack_peak = 0;
    let mut next = 0u32;
    let (mut tri, mut tri_end) = (0u32, 0u32);
    loop {
        if next == BVH_EMPTY && tri == tri_end && sp == 0 {
            break;
        }
        if steps == budget {
            cut = true;
            break;
        }
        steps += 1;
        if next == BVH_EMPTY && sp > 0 {
            sp -= 1;
            if stack[sp].1 <= best {
                next = stack[sp].0;
            }
        }
        if next & BVH_LEAF == 0 {
            let n = &nodes[next as usize];
            let boxes = n.child_boxes();
            let mut key = [0f32; 4];
            let mut refs = n.child;
            let mut entered = 0;
            for i in 0..4 {
                let (lo, hi) = boxes[i];
                let (nx, fx) = slab(&r, 0, lo[0], hi[0]);
                let (ny, fy) = slab(&r, 1, lo[1], hi[1]);
                let (nz, fz) = slab(&r, 2, lo[2], hi[2]);
                let near = nx.max(ny).max(nz.max(tmin));
                let far = fx.min(fy).min(fz) * ROBUST;
                let enter = near <= far.min(best) && n.child[i] != BVH_EMPTY;
                key[i] = if enter { near } else { HUGE };
                entered += enter as usize;
            }
            // bvh_order's network: entered children first, nearest first, ties in slot order.
            for (i, j) in [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)] {
                if key[j] < key[i] {
                    key.swap(i, j);
                    refs.swap(i, j);
                }
            }
            for i in (1..entered).rev() {
                stack[sp] = (refs[i], key[i]);
                sp += 1;
            }
            next = if entered > 0 { refs[0] } else { BVH_EMPTY };
            stack_peak = stack_peak.max(sp as u32);
        }
        if let (Some((first, count)), true) = (BvhNode::leaf_range(next), tri == tri_end) {
            (tri, tri_end) = (first, first + count);
            next = BVH_EMPTY;
        }
        if tri != tri_end {
            let tr = &tris[tri as usize];
            let found = triangle_test(&r, v3(tr.v0), v3(tr.v1), v3(tr.v2), tmin, best);
            if let Some((t, bary)) = found.filter(|&(_, bary)| keep(tri, bary)) {
                best = t;
                hit = Some(BvhHit { t, triangle: tri, bary });
                if any_hit {
                    (next, sp, tri_end) = (BVH_EMPTY, 0, tri + 1);
                }
            }
            tri += 1;
        }
    }
    Traversal {
        hit,
        steps,
        cut,
        stack_peak,
    }
}

/// The nearest hit by testing every triangle in order (the first of equal t wins): the check of
/// [`intersect`].
pub fn brute_force(tris: &[Triangle], o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> Option<BvhHit> {
    let r = BvhRay::new(o, d);
    let mut best = tmax;
    let mut hit = None;
    for (i, tr) in tris.iter().enumerate() {
        let found = triangle_test(&r, v3(tr.v0), v3(tr.v1), v3(tr.v2), tmin, best);
        if let Some((t, bary)) = found {
            best = t;
            hit = Some(BvhHit {
                t,
                triangle: i as u32,
                bary,
            });
        }
    }
    hit
}

/// `bvh_normal`: the geometric normal, on the side the vertices wind counter-clockwise.
pub fn normal(tr: &Triangle) -> Vec3 {
    (v3(tr.v1) - v3(tr.v0)).cross(v3(tr.v2) - v3(tr.v0)).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_the_inside_and_reports_barycentrics() {
        let t = Triangle::through([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        for d in [Vec3::Z, -Vec3::Z] {
            let o = Vec3::new(0.25, 0.5, 0.0) - 2.0 * d;
            let r = BvhRay::new(o, d);
            let (th, b) = triangle_test(&r, v3(t.v0), v3(t.v1), v3(t.v2), 0.0, 10.0).expect("two-sided hit");
            assert_eq!(th, 2.0);
            assert!((b - Vec2::new(0.25, 0.5)).abs().max_element() < 1e-7, "{b}");
        }
        assert_eq!(normal(&t), Vec3::Z);
        // Outside, behind the origin, beyond tmax, in the plane: no hit.
        let r = BvhRay::new(Vec3::new(0.75, 0.75, -1.0), Vec3::Z);
        assert!(triangle_test(&r, v3(t.v0), v3(t.v1), v3(t.v2), 0.0, 10.0).is_none());
        let r = BvhRay::new(Vec3::new(0.25, 0.25, 1.0), Vec3::Z);
        assert!(triangle_test(&r, v3(t.v0), v3(t.v1), v3(t.v2), 0.0, 10.0).is_none());
        let r = BvhRay::new(Vec3::new(0.25, 0.25, -1.0), Vec3::Z);
        assert!(triangle_test(&r, v3(t.v0), v3(t.v1), v3(t.v2), 0.0, 0.5).is_none());
        let r = BvhRay::new(Vec3::new(-1.0, 0.25, 0.0), Vec3::X);
        assert!(triangle_test(&r, v3(t.v0), v3(t.v1), v3(t.v2), 0.0, 10.0).is_none());
    }

    /// The constants this file shares with bvh.glsl have the same values there.
    #[test]
    fn constants_match_the_glsl() {
        let glsl = ppm_vk_kernels::reflected::SOURCES
            .iter()
            .find(|(p, _)| *p == "common/bvh.glsl")
            .unwrap()
            .1;
        let value = |name: &str| -> f32 {
            let line = glsl
                .lines()
                .find(|l| l.starts_with(&format!("const float {name} = ")))
                .unwrap();
            line.split('=')
                .nth(1)
                .unwrap()
                .trim()
                .trim_end_matches(';')
                .parse()
                .unwrap()
        };
        assert_eq!(value("BVH_ROBUST"), ROBUST);
        assert_eq!(value("BVH_TINY"), TINY);
        assert_eq!(value("BVH_HUGE"), HUGE);
        // The stack: lavapipe does not bound private arrays, so a GLSL stack smaller than the builder's
        // bound would not show as a wrong hit there; it would on another device.
        let line = |prefix: &str| glsl.lines().find(|l| l.starts_with(prefix)).unwrap();
        assert_eq!(
            line("const uint BVH_MAX_DEPTH = "),
            format!("const uint BVH_MAX_DEPTH = {}u;", ppm_vk_engine::bvh::MAX_DEPTH)
        );
        assert_eq!(
            line("const uint BVH_STACK = "),
            "const uint BVH_STACK = 3u * BVH_MAX_DEPTH;"
        );
        assert_eq!(ppm_vk_engine::bvh::STACK, 3 * ppm_vk_engine::bvh::MAX_DEPTH);
        for (name, v) in [
            ("BVH_EMPTY", ppm_vk_kernels::layout::BVH_EMPTY),
            ("BVH_LEAF", ppm_vk_kernels::layout::BVH_LEAF),
            ("BVH_COUNT_SHIFT", ppm_vk_kernels::layout::BVH_COUNT_SHIFT),
            ("BVH_FIRST_MASK", ppm_vk_kernels::layout::BVH_FIRST_MASK),
        ] {
            let text = line(&format!("const uint {name} = "));
            let lit = text
                .split('=')
                .nth(1)
                .unwrap()
                .trim()
                .trim_end_matches(';')
                .trim_end_matches('u');
            let parsed = match lit.strip_prefix("0x") {
                Some(hex) => u32::from_str_radix(hex, 16).unwrap(),
                None => lit.parse().unwrap(),
            };
            assert_eq!(parsed, v, "{name}");
        }
    }

    #[test]
    fn a_shared_edge_is_hit_by_exactly_one_side_or_both() {
        // Two triangles sharing the diagonal (0,0)-(1,1); rays exactly through points of it.
        let a = Triangle::through([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]);
        let b = Triangle::through([0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]);
        // The square's corners (0,0) and (1,1) are on its outline, where a ray may pass outside.
        for k in 1..64 {
            let s = k as f32 / 64.0;
            for o in [
                Vec3::new(0.3, -0.2, -1.0),
                Vec3::new(-5.0, 7.0, 3.0),
                Vec3::new(0.1, 0.9, 0.001),
            ] {
                let target = Vec3::new(s, s, 0.0);
                let r = BvhRay::new(o, target - o);
                let ha = triangle_test(&r, v3(a.v0), v3(a.v1), v3(a.v2), 0.0, 10.0);
                let hb = triangle_test(&r, v3(b.v0), v3(b.v1), v3(b.v2), 0.0, 10.0);
                assert!(
                    ha.is_some() || hb.is_some(),
                    "ray from {o} through {target} passes between the triangles"
                );
            }
        }
    }
}

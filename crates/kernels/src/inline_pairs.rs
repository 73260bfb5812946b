//! The triangles of a small mesh written into the kernels (specialize.rs) that pair into parallelograms:
//! two triangles sharing an edge, the one's far corner where the other's mirrors through that edge, as a
//! quad split in two (a wall, a box's face). geometry.glsl tests such a pair by its plane once, as a quad
//! (`inline_pair_test`), and then knows which of the two the ray met by which side of the shared diagonal
//! the point lies on: one test where there were two. CPU twin: reference::trace.
//!
//! The corners: the first triangle is (A, B, C) in some order, the second (A, C, D); the diagonal is A-C.
//! The pair is the parallelogram spanned from B by `edge_u = A - B` and `edge_v = C - B`; a point
//! `B + a edge_u + b edge_v` lies in the first triangle where `a + b <= 1` (weights A a, B 1 - a - b, C b)
//! and in the second otherwise (A 1 - b, C 1 - a, D a + b - 1, since D = A + C - B).

use crate::layout::Triangle;

/// A corner's role in its pair (the module's A, B, C, D).
pub const CORNER_A: u32 = 0;
pub const CORNER_B: u32 = 1;
pub const CORNER_C: u32 = 2;
pub const CORNER_D: u32 = 3;

/// How far the second triangle's far corner may lie from `A + C - B`, relative to the pair's size: a few
/// rounding errors of the vertices' own transforms. Where it lies that far, the pair's test covers a sliver
/// that wide more or less than the two triangles do.
pub const PARALLELOGRAM_TOLERANCE: f32 = 1e-6;

/// Two written-out triangles tested as one parallelogram.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InlinePair {
    /// B, the first triangle's corner off the diagonal.
    pub origin: [f32; 3],
    /// A - B and C - B.
    pub edge_u: [f32; 3],
    pub edge_v: [f32; 3],
    /// The two triangles' indices (leaf order, as `Light::index` and the hit's primitive).
    pub first: u32,
    pub second: u32,
    /// The corners (CORNER_*) of each triangle's v1 and v2, whose weights are a hit's barycentric
    /// coordinates.
    pub first_corners: [u32; 2],
    pub second_corners: [u32; 2],
}

/// The pairs among `triangles` and the triangles left single, in index order: each triangle pairs with
/// the first later one that shares an edge with it (the same two vertices, bit for bit) and completes the
/// parallelogram (within [`PARALLELOGRAM_TOLERANCE`]); degenerate triangles stay single.
pub fn pairs(triangles: &[Triangle]) -> (Vec<InlinePair>, Vec<u32>) {
    let mut taken = vec![false; triangles.len()];
    let mut pairs = Vec::new();
    for i in 0..triangles.len() {
        if taken[i] {
            continue;
        }
        for j in i + 1..triangles.len() {
            if taken[j] {
                continue;
            }
            if let Some(p) = pair(&triangles[i], &triangles[j], i as u32, j as u32) {
                taken[i] = true;
                taken[j] = true;
                pairs.push(p);
                break;
            }
        }
    }
    let singles = (0..triangles.len() as u32).filter(|&i| !taken[i as usize]).collect();
    (pairs, singles)
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn length(a: [f32; 3]) -> f32 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// `t` and `u` as a pair, if they make one (see [`pairs`]).
fn pair(t: &Triangle, u: &Triangle, ti: u32, ui: u32) -> Option<InlinePair> {
    let tv = [t.v0, t.v1, t.v2];
    let uv = [u.v0, u.v1, u.v2];
    // The shared edge: vertices of t found in u, bit for bit (positions compared as bits: -0.0 is not 0.0
    // there, which at worst leaves a pair single).
    let bits = |v: [f32; 3]| v.map(f32::to_bits);
    let in_u = |v: [f32; 3]| uv.iter().position(|w| bits(*w) == bits(v));
    let shared: Vec<(usize, usize)> = (0..3).filter_map(|k| in_u(tv[k]).map(|m| (k, m))).collect();
    let [(ka, ma), (kc, mc)] = shared[..] else {
        return None; // no edge shared, or the same triangle twice
    };
    let kb = 3 - ka - kc;
    let md = 3 - ma - mc;
    let (a, b, c, d) = (tv[ka], tv[kb], tv[kc], uv[md]);
    let (edge_u, edge_v) = (sub(a, b), sub(c, b));
    let n = [
        edge_u[1] * edge_v[2] - edge_u[2] * edge_v[1],
        edge_u[2] * edge_v[0] - edge_u[0] * edge_v[2],
        edge_u[0] * edge_v[1] - edge_u[1] * edge_v[0],
    ];
    let size = length(edge_u) + length(edge_v);
    // Degenerate: no area, or not finite (NaN compares false).
    let has_area = length(n) > 0.0 && size.is_finite();
    if !has_area {
        return None;
    }
    // D against the parallelogram's fourth corner A + C - B.
    let off = sub(d, [a[0] + edge_v[0], a[1] + edge_v[1], a[2] + edge_v[2]]);
    let on_corner = length(off) <= PARALLELOGRAM_TOLERANCE * size;
    if !on_corner {
        return None;
    }
    let corner = |k: usize, roles: [(usize, u32); 3]| roles.iter().find(|r| r.0 == k).expect("a corner").1;
    let t_roles = [(ka, CORNER_A), (kb, CORNER_B), (kc, CORNER_C)];
    let u_roles = [(ma, CORNER_A), (mc, CORNER_C), (md, CORNER_D)];
    Some(InlinePair {
        origin: b,
        edge_u,
        edge_v,
        first: ti,
        second: ui,
        first_corners: [corner(1, t_roles), corner(2, t_roles)],
        second_corners: [corner(1, u_roles), corner(2, u_roles)],
    })
}

/// The weights of the four corners at planar coordinates (a, b) in the pair's first triangle
/// (`first`) or its second, in CORNER_* order (geometry.glsl's `pair_weights`).
pub fn weights(first: bool, a: f32, b: f32) -> [f32; 4] {
    if first {
        [a, 1.0 - a - b, b, 0.0]
    } else {
        [1.0 - b, 0.0, 1.0 - a, a + b - 1.0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point's barycentric coordinates in its triangle, from its pair's planar coordinates, give back
    /// the point: for a square split either way, with the triangles' vertices in every rotation.
    #[test]
    fn a_pairs_weights_give_back_the_point_in_either_triangle() {
        let (p, q, r, s) = ([0.0, 0.0, 1.0], [2.0, 0.0, 1.0], [2.0, 3.0, 1.0], [0.0, 3.0, 1.0]);
        let rot = |t: [[f32; 3]; 3], k: usize| Triangle::through(t[k % 3], t[(k + 1) % 3], t[(k + 2) % 3]);
        for (t1, t2) in [([p, q, r], [p, r, s]), ([q, r, s], [q, s, p])] {
            for k1 in 0..3 {
                for k2 in 0..3 {
                    let ts = [rot(t1, k1), rot(t2, k2)];
                    let (pairs, singles) = pairs(&ts);
                    assert_eq!((pairs.len(), singles.len()), (1, 0), "{ts:?}");
                    let pr = pairs[0];
                    for (a, b) in [(0.2f32, 0.3f32), (0.7, 0.9), (0.5, 0.5), (0.0, 1.0), (1.0, 1.0)] {
                        let point: Vec<f32> = (0..3)
                            .map(|i| pr.origin[i] + a * pr.edge_u[i] + b * pr.edge_v[i])
                            .collect();
                        let first = a + b <= 1.0;
                        let w = weights(first, a, b);
                        let (t, corners) = if first {
                            (&ts[pr.first as usize], pr.first_corners)
                        } else {
                            (&ts[pr.second as usize], pr.second_corners)
                        };
                        let (b1, b2) = (w[corners[0] as usize], w[corners[1] as usize]);
                        for (i, want) in point.iter().enumerate() {
                            let back = (1.0 - b1 - b2) * t.v0[i] + b1 * t.v1[i] + b2 * t.v2[i];
                            assert!((back - want).abs() < 1e-5, "({a}, {b}) in {t:?}: {back} against {want}");
                        }
                        assert!(b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0 + 1e-6);
                    }
                }
            }
        }
    }

    /// The tolerance's bound: the far corner off the parallelogram's by half of it pairs, by twice it
    /// does not.
    #[test]
    fn the_far_corner_pairs_within_the_tolerance_only() {
        let lone = Triangle::through([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let size = 2.0; // |A - B| + |C - B|: A and C end the shared edge, B is the origin
        let near = |k: f32| {
            Triangle::through(
                [1.0, 0.0, 0.0],
                [1.0, 1.0 + k * PARALLELOGRAM_TOLERANCE * size, 0.0],
                [0.0, 1.0, 0.0],
            )
        };
        assert_eq!(pairs(&[lone, near(0.0)]).0.len(), 1);
        assert_eq!(pairs(&[lone, near(0.5)]).0.len(), 1, "within the tolerance");
        assert_eq!(pairs(&[lone, near(2.0)]).0.len(), 0, "beyond it");
    }

    /// What does not pair: no shared edge, a kite (the far corner off the parallelogram), a degenerate
    /// triangle; and a strip of three squares' six triangles pairs into three.
    #[test]
    fn only_parallelograms_pair() {
        let lone = Triangle::through([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let apart = Triangle::through([5.0, 0.0, 0.0], [6.0, 0.0, 0.0], [5.0, 1.0, 0.0]);
        assert_eq!(pairs(&[lone, apart]), (vec![], vec![0, 1]));
        let kite = Triangle::through([1.0, 0.0, 0.0], [1.2, 1.1, 0.0], [0.0, 1.0, 0.0]);
        assert_eq!(pairs(&[lone, kite]).0, vec![]);
        let bent = Triangle::through([1.0, 0.0, 0.0], [1.0, 1.0, 1e-3], [0.0, 1.0, 0.0]);
        assert_eq!(pairs(&[lone, bent]).0, vec![], "out of the plane");
        let flat = Triangle::through([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]);
        let flat2 = Triangle::through([0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0]);
        assert_eq!(pairs(&[flat, flat2]).0, vec![], "degenerate");
        let mut strip = Vec::new();
        for k in 0..3 {
            let x = k as f32;
            strip.push(Triangle::through(
                [x, 0.0, 0.0],
                [x + 1.0, 0.0, 0.0],
                [x + 1.0, 1.0, 0.0],
            ));
            strip.push(Triangle::through([x, 0.0, 0.0], [x + 1.0, 1.0, 0.0], [x, 1.0, 0.0]));
        }
        let (p, s) = pairs(&strip);
        assert_eq!((p.len(), s.len()), (3, 0));
        assert!(p.iter().all(|p| p.second == p.first + 1), "{p:?}");
    }
}

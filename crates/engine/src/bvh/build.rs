//! The binned SAH builder (see the module above for the method): triangle bounds in parallel chunks, the
//! top levels of the tree forked onto threads, the binary tree flattened depth first.

use std::time::Instant;

use anyhow::{bail, ensure, Result};
use glam::{Vec3, Vec3A};
use ppm_vk_kernels::layout::Triangle;

use super::{
    stack_bound, widen, Aabb, BinaryNode, Bvh, BvhOptions, BvhStats, TriangleInput, BINARY_LEAF, MAX_DEPTH, MAX_LEAF,
    MAX_TRIANGLES, PARALLEL_MIN, TRAVERSAL_COST, TRIANGLE_COST,
};

/// A triangle's bounds during the build.
#[derive(Clone, Copy, Debug)]
struct PrimRef {
    lo: Vec3A,
    hi: Vec3A,
    index: u32,
}

impl PrimRef {
    /// Twice the centroid (the halving cancels out of the binning).
    fn c2(&self) -> Vec3A {
        self.lo + self.hi
    }
}

/// Bounds and centroid (times 2) bounds of some triangles.
fn bounds_of(refs: &[PrimRef]) -> (Aabb, Aabb) {
    let (mut b, mut c) = (Aabb::EMPTY, Aabb::EMPTY);
    for r in refs {
        b.grow(r.lo, r.hi);
        let c2 = r.c2();
        c.grow(c2, c2);
    }
    (b, c)
}

fn is_degenerate(v: &[Vec3; 3]) -> bool {
    if !v.iter().all(|p| p.is_finite()) {
        return true;
    }
    // In f64 the cross product of f32 differences is exact up to its final rounding, so it is 0 only for
    // truly collinear vertices, never for a tiny but valid triangle.
    let (a, b, c) = (v[0].as_dvec3(), v[1].as_dvec3(), v[2].as_dvec3());
    (b - a).cross(c - a) == glam::DVec3::ZERO
}

/// Levels of a balanced tree over `n` triangles with leaves of `max_leaf`: ceil(log2(ceil(n / max_leaf))).
fn levels_needed(n: usize, max_leaf: usize) -> u32 {
    let leaves = n.div_ceil(max_leaf).max(1);
    usize::BITS - (leaves - 1).leading_zeros()
}

#[derive(Default)]
struct Counters {
    median_splits: usize,
}

struct Builder {
    max_leaf: usize,
    bins: usize,
    max_depth: u32,
}

#[derive(Clone, Copy)]
struct Bin {
    b: Aabb,
    count: u32,
}

/// A chosen split: the first `mid` triangles go left; its cost relative to a leaf's triangle tests; each
/// side's bounds and centroid (times 2) bounds.
struct Split {
    axis: usize,
    mid: usize,
    cost: f64,
    sides: [(Aabb, Aabb); 2],
}

/// Per-axis bins, reused down a thread's recursion.
type Bins = [[Bin; 64]; 3];

fn new_bins() -> Box<Bins> {
    Box::new(
        [[Bin {
            b: Aabb::EMPTY,
            count: 0,
        }; 64]; 3],
    )
}

impl Builder {
    fn leaf(&self, out: &mut Vec<BinaryNode>, b: Aabb, first: usize, n: usize) {
        out.push(BinaryNode {
            lo: b.lo.to_array(),
            offset: first as u32,
            hi: b.hi.to_array(),
            count_axis: (n as u32) << 2 | BINARY_LEAF,
        });
    }

    /// Builds the subtree over `refs` (at `first` in the whole array), depth first into `out`; a second
    /// child's offset counts from the start of `out`. `spawn`: levels below this one that may still fork.
    // The recursion's state (slices, offsets, the fork budget), each read at every level.
    #[allow(clippy::too_many_arguments)]
    fn build(
        &self,
        refs: &mut [PrimRef],
        first: usize,
        depth: u32,
        b: Aabb,
        cb: Aabb,
        spawn: u32,
        out: &mut Vec<BinaryNode>,
        counters: &mut Counters,
        scratch: &mut Bins,
    ) {
        let n = refs.len();
        if n == 1 {
            return self.leaf(out, b, first, n);
        }
        let extent = cb.hi - cb.lo;
        // At the depth limit only a balanced split still fits below; with all centroids at one point no
        // plane separates them. Either way: a leaf if it may be one, else the median.
        let median = depth + levels_needed(n, self.max_leaf) >= self.max_depth || extent.max_element() <= 0.0;
        let sah = if median {
            None
        } else {
            self.sah_split(refs, b, cb, scratch)
        };
        let (axis, mid, [(lb, lcb), (rb, rcb)]) = match sah {
            Some(s) if n > self.max_leaf || s.cost < n as f64 * TRIANGLE_COST => (s.axis, s.mid, s.sides),
            _ if n <= self.max_leaf => return self.leaf(out, b, first, n),
            _ => {
                counters.median_splits += 1;
                let axis = extent.max_position();
                let mid = n / 2;
                refs.select_nth_unstable_by(mid, |p, q| p.c2()[axis].total_cmp(&q.c2()[axis]));
                (axis, mid, [bounds_of(&refs[..mid]), bounds_of(&refs[mid..])])
            }
        };
        let (left, right) = refs.split_at_mut(mid);
        let me = out.len();
        out.push(BinaryNode {
            lo: b.lo.to_array(),
            offset: 0,
            hi: b.hi.to_array(),
            count_axis: axis as u32,
        });
        if spawn > 0 && n >= PARALLEL_MIN {
            // The left subtree on another thread; its nodes follow this one, the right subtree's theirs.
            let (left_nodes, right_nodes, right_counters) = std::thread::scope(|s| {
                let handle = s.spawn(|| {
                    let mut nodes = Vec::with_capacity(2 * left.len() / self.max_leaf);
                    let mut c = Counters::default();
                    let mut scratch = new_bins();
                    self.build(
                        left,
                        first,
                        depth + 1,
                        lb,
                        lcb,
                        spawn - 1,
                        &mut nodes,
                        &mut c,
                        &mut scratch,
                    );
                    (nodes, c)
                });
                let mut nodes = Vec::with_capacity(2 * right.len() / self.max_leaf);
                let mut c = Counters::default();
                self.build(
                    right,
                    first + mid,
                    depth + 1,
                    rb,
                    rcb,
                    spawn - 1,
                    &mut nodes,
                    &mut c,
                    scratch,
                );
                let (left_nodes, lc) = handle.join().expect("a BVH build thread panicked");
                c.median_splits += lc.median_splits;
                (left_nodes, nodes, c)
            });
            counters.median_splits += right_counters.median_splits;
            append_rebased(out, &left_nodes);
            out[me].offset = out.len() as u32;
            append_rebased(out, &right_nodes);
        } else {
            self.build(left, first, depth + 1, lb, lcb, 0, out, counters, scratch);
            out[me].offset = out.len() as u32;
            self.build(right, first + mid, depth + 1, rb, rcb, 0, out, counters, scratch);
        }
    }

    /// The cheapest binned SAH split, `refs` partitioned by it, or None if no bin boundary separates the
    /// centroids.
    fn sah_split(&self, refs: &mut [PrimRef], b: Aabb, cb: Aabb, bins: &mut Bins) -> Option<Split> {
        // No more bins than triangles: a small node's sweep would mostly cross empty bins.
        let nb = self.bins.min(refs.len().max(2));
        let extent = cb.hi - cb.lo;
        // (1 - 1e-6) keeps the largest centroid in the last bin; a flat axis puts everything in bin 0.
        let scale = Vec3A::select(
            extent.cmpgt(Vec3A::ZERO),
            (nb as f32 * (1.0 - 1e-6)) / extent,
            Vec3A::ZERO,
        );
        let max_bin = glam::UVec3::splat(nb as u32 - 1);
        let bin_of = |r: &PrimRef| ((r.c2() - cb.lo) * scale).as_uvec3().min(max_bin);
        for axis_bins in bins.iter_mut() {
            axis_bins[..nb].fill(Bin {
                b: Aabb::EMPTY,
                count: 0,
            });
        }
        for r in refs.iter() {
            let k = bin_of(r);
            for axis in 0..3 {
                let bin = &mut bins[axis][k[axis] as usize];
                bin.b.grow(r.lo, r.hi);
                bin.count += 1;
            }
        }
        let mut best: Option<(usize, usize, f64)> = None; // (axis, last bin on the left, cost)
        let mut right_cost = [0f64; 64];
        for (axis, bins) in bins.iter().enumerate() {
            // Sweep from the right: the cost of bins k.. on the right side, then from the left.
            let (mut acc, mut count) = (Aabb::EMPTY, 0u32);
            for k in (1..nb).rev() {
                acc = acc.union(bins[k].b);
                count += bins[k].count;
                right_cost[k] = if count > 0 {
                    acc.half_area() * count as f64
                } else {
                    f64::INFINITY
                };
            }
            let (mut acc, mut count) = (Aabb::EMPTY, 0u32);
            for k in 0..nb - 1 {
                acc = acc.union(bins[k].b);
                count += bins[k].count;
                if count == 0 || !right_cost[k + 1].is_finite() {
                    continue;
                }
                let cost = acc.half_area() * count as f64 + right_cost[k + 1];
                if !matches!(best, Some((_, _, c)) if c <= cost) {
                    best = Some((axis, k, cost));
                }
            }
        }
        let (axis, split, cost) = best?;
        let area = b.half_area().max(f64::MIN_POSITIVE);
        let cost = TRAVERSAL_COST + TRIANGLE_COST * cost / area;
        // Partition (bins 0..=split to the left), taking each side's bounds and centroid bounds as each
        // triangle finds its side: no second pass over them.
        let mut sides = [(Aabb::EMPTY, Aabb::EMPTY); 2];
        let mut i = 0;
        let mut j = refs.len();
        while i < j {
            let r = refs[i];
            let c2 = r.c2();
            if bin_of(&r)[axis] as usize <= split {
                sides[0].0.grow(r.lo, r.hi);
                sides[0].1.grow(c2, c2);
                i += 1;
            } else {
                sides[1].0.grow(r.lo, r.hi);
                sides[1].1.grow(c2, c2);
                j -= 1;
                refs.swap(i, j);
            }
        }
        Some(Split {
            axis,
            mid: i,
            cost,
            sides,
        })
    }
}

/// `f` over `0..n` cut into one contiguous range per thread, the results in order.
fn parallel_chunks<T: Send>(n: usize, threads: usize, f: impl Fn(std::ops::Range<usize>) -> T + Sync) -> Vec<T> {
    let per = n.div_ceil(threads.max(1)).max(PARALLEL_MIN);
    let ranges: Vec<_> = (0..n.div_ceil(per).max(1))
        .map(|k| k * per..((k + 1) * per).min(n))
        .collect();
    if ranges.len() == 1 {
        return vec![f(ranges[0].clone())];
    }
    std::thread::scope(|s| {
        let handles: Vec<_> = ranges.iter().map(|r| s.spawn(|| f(r.clone()))).collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a BVH build thread panicked"))
            .collect()
    })
}

/// Appends a subtree built into its own vector, moving its second-child offsets along.
fn append_rebased(out: &mut Vec<BinaryNode>, nodes: &[BinaryNode]) {
    let base = out.len() as u32;
    out.extend(nodes.iter().map(|n| {
        let mut n = *n;
        if !n.is_leaf() {
            n.offset += base;
        }
        n
    }));
}

/// Builds a BVH over `input`. Degenerate triangles are dropped and listed in [`Bvh::dropped`].
pub fn build(input: &[TriangleInput], options: &BvhOptions) -> Result<Bvh> {
    let start = Instant::now();
    ensure!(
        (1..=MAX_LEAF).contains(&options.max_leaf),
        "BVH: max_leaf must be 1..={MAX_LEAF}, got {}",
        options.max_leaf
    );
    ensure!(
        (2..=64).contains(&options.bins),
        "BVH: bins must be 2..=64, got {}",
        options.bins
    );
    ensure!(
        (1..=MAX_DEPTH).contains(&options.max_depth),
        "BVH: max_depth must be 1..={MAX_DEPTH} (the GPU traversal's stack), got {}",
        options.max_depth
    );
    if input.len() > MAX_TRIANGLES {
        bail!(
            "BVH: {} triangles are more than one BVH holds ({MAX_TRIANGLES})",
            input.len()
        );
    }
    let threads = match options.threads {
        0 => std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
        t => t,
    };

    // Bounds of each triangle, in chunks on all threads (concatenated in input order).
    let chunks = parallel_chunks(input.len(), threads, |range| {
        let mut refs = Vec::with_capacity(range.len());
        let mut dropped = Vec::new();
        for i in range {
            let t = &input[i];
            if is_degenerate(&t.v) {
                dropped.push(i as u32);
                continue;
            }
            let lo = Vec3A::from(t.v[0].min(t.v[1]).min(t.v[2]));
            let hi = Vec3A::from(t.v[0].max(t.v[1]).max(t.v[2]));
            refs.push(PrimRef {
                lo,
                hi,
                index: i as u32,
            });
        }
        (refs, dropped)
    });
    let mut refs = Vec::with_capacity(input.len());
    let mut dropped = Vec::new();
    for (r, d) in chunks {
        refs.extend_from_slice(&r);
        dropped.extend_from_slice(&d);
    }
    let n = refs.len();
    let max_leaf = options.max_leaf as usize;
    let need = levels_needed(n, max_leaf);
    if need > options.max_depth {
        bail!(
            "BVH: {n} triangles need a tree {need} levels deep with {max_leaf} per leaf, more than the limit of {}",
            options.max_depth
        );
    }

    let mut nodes = Vec::with_capacity(2 * n.div_ceil(max_leaf));
    let mut counters = Counters::default();
    if n == 0 {
        nodes.push(BinaryNode {
            count_axis: BINARY_LEAF,
            ..Default::default()
        });
    } else {
        let builder = Builder {
            max_leaf,
            bins: options.bins as usize,
            max_depth: options.max_depth,
        };
        let (b, cb) = bounds_of(&refs);
        // Fork the top levels: about four subtrees per thread, so an uneven split still keeps all busy.
        let spawn = if threads > 1 {
            usize::BITS - (threads - 1).leading_zeros() + 2
        } else {
            0
        };
        builder.build(
            &mut refs,
            0,
            0,
            b,
            cb,
            spawn,
            &mut nodes,
            &mut counters,
            &mut new_bins(),
        );
    }
    // The triangles in leaf order, and the 4-wide tree beside them on another thread.
    let (triangles, wide) = std::thread::scope(|s| {
        let wide = s.spawn(|| widen(&nodes, threads));
        let triangles: Vec<Triangle> = parallel_chunks(refs.len(), threads, |range| {
            refs[range]
                .iter()
                .map(|r| {
                    let t = &input[r.index as usize];
                    Triangle {
                        v0: t.v[0].to_array(),
                        material: t.material,
                        v1: t.v[1].to_array(),
                        source: r.index,
                        v2: t.v[2].to_array(),
                        pad0: 0,
                    }
                })
                .collect::<Vec<_>>()
        })
        .concat();
        (triangles, wide.join().expect("a BVH widening thread panicked"))
    });
    let mut bvh = Bvh {
        wide,
        nodes,
        triangles,
        dropped,
        stats: BvhStats::default(),
    };
    let (depth, leaves, sah_cost) = bvh.shape();
    if depth > options.max_depth {
        bail!(
            "BVH: built {depth} levels deep, past the limit of {} (a bug in the builder)",
            options.max_depth
        );
    }
    bvh.stats = BvhStats {
        input: input.len(),
        triangles: bvh.triangles.len(),
        dropped: bvh.dropped.len(),
        nodes: bvh.nodes.len(),
        leaves,
        depth,
        wide_nodes: bvh.wide.len(),
        stack_bound: stack_bound(&bvh.wide),
        sah_cost,
        median_splits: counters.median_splits,
        build_seconds: start.elapsed().as_secs_f64(),
    };
    Ok(bvh)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::bvh::meshes::*;
    use crate::reference::bvh::{brute_force, intersect, triangle_test, BvhRay};
    use crate::reference::rng::Rng;
    use crate::reference::trace::v3;

    const NO_BUDGET: u32 = u32::MAX;

    fn built(input: &[TriangleInput]) -> Bvh {
        let bvh = build(input, &BvhOptions::default()).unwrap();
        bvh.validate(MAX_LEAF, MAX_DEPTH).unwrap();
        bvh.validate_wide().unwrap();
        bvh
    }

    fn random_unit(rng: &mut Rng) -> Vec3 {
        loop {
            let v = Vec3::new(rng.float(), rng.float(), rng.float()) * 2.0 - 1.0;
            if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }

    /// Traces (o, d) through the BVH and by brute force; panics unless both find the same nearest hit.
    /// Returns the hit and whether its t is bit-identical to brute force's.
    ///
    /// Where several triangles meet the ray at one point (a shared vertex or edge), each one's t is that
    /// distance rounded its own way, a few ulps apart, and a box is culled by a distance that rounded the
    /// way of none of them; so there the BVH may report one of them a few ulps farther than the nearest of
    /// the rounded values. Never nearer: brute force tests everything.
    fn same_as_brute_force(bvh: &Bvh, o: Vec3, d: Vec3, what: &str) -> Option<(reference::bvh::BvhHit, bool)> {
        let got = intersect(&bvh.wide, &bvh.triangles, o, d, 0.0, f32::INFINITY, NO_BUDGET);
        assert!(!got.cut);
        let want = brute_force(&bvh.triangles, o, d, 0.0, f32::INFINITY);
        match (got.hit, want) {
            (None, None) => None,
            (Some(g), Some(w)) => {
                let r = BvhRay::new(o, d);
                let test = |i: u32| {
                    let t = &bvh.triangles[i as usize];
                    triangle_test(&r, v3(t.v0), v3(t.v1), v3(t.v2), 0.0, f32::INFINITY).map(|h| h.0)
                };
                let exact = g.t == w.t;
                assert!(
                    g.t >= w.t && g.t - w.t <= 2e-6 * g.t,
                    "{what}: ray {o} {d}: BVH t {} (triangle {}), brute force {} ({})",
                    g.t,
                    g.triangle,
                    w.t,
                    w.triangle
                );
                assert_eq!(
                    test(g.triangle),
                    Some(g.t),
                    "{what}: the BVH's hit is not its triangle's"
                );
                // Independent of the test's arithmetic: the barycentric point is the ray's point.
                let t = &bvh.triangles[g.triangle as usize];
                let p = (1.0 - g.bary.x - g.bary.y) * v3(t.v0) + g.bary.x * v3(t.v1) + g.bary.y * v3(t.v2);
                let q = o + g.t * d;
                let scale = o.abs().max_element().max(q.abs().max_element()).max(1.0);
                assert!(
                    (p - q).length() <= 1e-4 * scale,
                    "{what}: barycentric point {p} is not the ray's {q}"
                );
                assert!(
                    g.bary.min_element() >= -1e-5 && g.bary.x + g.bary.y <= 1.0 + 1e-5,
                    "{what}: bary {}",
                    g.bary
                );
                Some((g, exact))
            }
            (g, w) => panic!("{what}: ray {o} {d}: BVH {g:?}, brute force {w:?}"),
        }
    }

    use crate::reference;

    #[test]
    fn bvh_matches_brute_force_on_random_soups() {
        for (seed, n, size) in [
            (1, 1, 0.3),
            (2, 2, 0.3),
            (3, 7, 0.2),
            (4, 100, 0.1),
            (5, 3000, 0.05),
            (6, 3000, 0.5),
        ] {
            let input = random_soup(seed, n, 1.0, size);
            let bvh = built(&input);
            assert_eq!(bvh.stats.triangles, n);
            let mut rng = Rng::new(seed, 99);
            let (mut hits, mut inexact) = (0, 0);
            let rays = 2000;
            for k in 0..rays {
                let o = Vec3::new(rng.float(), rng.float(), rng.float()) * 1.6 - 0.3;
                let mut d = random_unit(&mut rng);
                match k % 10 {
                    // Axis-parallel rays: direction components exactly 0 (the slab test's reciprocal).
                    0 => d = Vec3::new(0.0, 0.0, d.z.signum()),
                    1 => d = Vec3::new(d.x, 0.0, -0.0).normalize(),
                    // Not unit: t is in units of |d|.
                    2 => d *= 7.5,
                    // Aimed at a vertex or an edge point of a random triangle.
                    3 | 4 => {
                        let t = &input[rng.next_u32() as usize % n];
                        let target = if k % 10 == 3 {
                            t.v[0]
                        } else {
                            t.v[1].lerp(t.v[2], rng.float())
                        };
                        d = target - o;
                    }
                    _ => {}
                }
                if let Some((_, exact)) = same_as_brute_force(&bvh, o, d, &format!("soup {seed}, ray {k}")) {
                    hits += 1;
                    inexact += !exact as usize;
                }
            }
            println!(
                "soup {seed}: {n} triangles, {} nodes, depth {}, SAH {:.2}: {hits} of {rays} rays hit, {inexact} a few ulps off",
                bvh.stats.nodes, bvh.stats.depth, bvh.stats.sah_cost
            );
            // Only rays aimed at a vertex or an edge point can meet several triangles at one point.
            assert!(inexact * 50 <= rays, "soup {seed}: {inexact} hits not bit-identical");
            assert!(hits > rays / 10, "soup {seed}: only {hits} hits: the rays test little");
        }
    }

    /// From inside a closed mesh every ray hits, including those exactly through vertices and shared
    /// edges, and the hit is the brute-force one.
    fn watertight_from_inside(mesh: &[TriangleInput], inside: &[Vec3], what: &str) -> (usize, usize) {
        let bvh = built(mesh);
        let (mut rays, mut inexact) = (0, 0);
        let mut rng = Rng::new(7, 7);
        for &o in inside {
            for t in mesh {
                // Through each vertex, the middle of each edge and a random point on it.
                let targets = [
                    t.v[0],
                    t.v[1],
                    t.v[2],
                    (t.v[0] + t.v[1]) * 0.5,
                    (t.v[1] + t.v[2]) * 0.5,
                    (t.v[2] + t.v[0]) * 0.5,
                    t.v[0].lerp(t.v[1], rng.float()),
                    t.v[1].lerp(t.v[2], rng.float()),
                ];
                for target in targets {
                    let d = target - o;
                    let hit = same_as_brute_force(&bvh, o, d, what);
                    let (_, exact) =
                        hit.unwrap_or_else(|| panic!("{what}: ray from {o} through {target} left the closed mesh"));
                    rays += 1;
                    inexact += !exact as usize;
                }
            }
        }
        (rays, inexact)
    }

    #[test]
    fn bvh_closed_sphere_is_watertight() {
        let mesh = uv_sphere(Vec3::ZERO, 1.0, 24, 32, 0);
        assert_eq!(mesh.len(), 2 * 32 * 23);
        // The centre makes the ray through a vertex exactly the vertex's own coordinates.
        let inside = [
            Vec3::ZERO,
            Vec3::new(0.3, -0.2, 0.1),
            Vec3::new(0.0, 0.0, 0.9),
            Vec3::new(-0.5, 0.5, -0.6),
        ];
        let (rays, inexact) = watertight_from_inside(&mesh, &inside, "sphere");
        println!(
            "sphere: {rays} rays through vertices and edges, none missed; {inexact} hits a few ulps off brute force's"
        );
    }

    #[test]
    fn bvh_closed_box_is_watertight() {
        // Coordinates on a 1/4 grid and origins on a 1/8 one: the rays pass exactly through the vertices and
        // the points of the shared (and diagonal) edges they aim at.
        let mesh = box_grid(Vec3::splat(-1.0), Vec3::splat(1.0), 8, 0);
        assert_eq!(mesh.len(), 12 * 64);
        let inside = [
            Vec3::ZERO,
            Vec3::new(0.25, -0.125, 0.5),
            Vec3::new(0.875, 0.875, -0.875),
        ];
        let (rays, inexact) = watertight_from_inside(&mesh, &inside, "box");
        println!(
            "box: {rays} rays through vertices and edges, none missed; {inexact} hits a few ulps off brute force's"
        );
        // Along an edge of the box from outside: in the planes of two faces (no hit there), through the
        // corner vertex of the third: the hit is that corner.
        let bvh = built(&mesh);
        for (o, d, corner) in [
            (Vec3::new(-3.0, -1.0, -1.0), Vec3::X, Vec3::new(-1.0, -1.0, -1.0)),
            (Vec3::new(1.0, 5.0, -1.0), -Vec3::Y, Vec3::new(1.0, 1.0, -1.0)),
            (Vec3::new(1.0, 1.0, 2.0), -Vec3::Z, Vec3::new(1.0, 1.0, 1.0)),
            // Along a shared edge inside the face z = 1, onto the edge between two faces.
            (Vec3::new(-3.0, 0.25, 1.0), Vec3::X, Vec3::new(-1.0, 0.25, 1.0)),
        ] {
            let (hit, _) = same_as_brute_force(&bvh, o, d, "along an edge")
                .expect("a ray along an edge hits the face it runs into");
            assert_eq!(o + hit.t * d, corner, "ray {o} {d}");
        }
        // From outside, aimed at every vertex and edge middle of the face x = 1 off its outline (a ray
        // through the silhouette may pass outside): a hit at that very point (the box is convex).
        let o = Vec3::new(3.0, -2.5, 1.75);
        let mut aimed = 0;
        for t in &mesh {
            for (a, b) in [(t.v[0], t.v[1]), (t.v[1], t.v[2]), (t.v[2], t.v[0])] {
                for target in [a, (a + b) * 0.5] {
                    if target.x != 1.0 || target.y.abs() == 1.0 || target.z.abs() == 1.0 {
                        continue;
                    }
                    let (hit, _) =
                        same_as_brute_force(&bvh, o, target - o, "from outside").expect("ray at a vertex missed");
                    assert!((hit.t - 1.0).abs() <= 1e-6, "ray at {target} hit at t {}", hit.t);
                    aimed += 1;
                }
            }
        }
        assert!(aimed > 100);
    }

    #[test]
    fn bvh_drops_and_counts_degenerate_triangles() {
        let good = random_soup(11, 20, 1.0, 0.2);
        let p = Vec3::new(0.5, 0.5, 0.5);
        let mut input = good.clone();
        let bad = [
            [p, p, p],
            [p, p, Vec3::ONE],
            [Vec3::ZERO, Vec3::ONE, Vec3::splat(2.0)],
            [Vec3::new(f32::NAN, 0.0, 0.0), Vec3::X, Vec3::Y],
            [Vec3::new(0.0, f32::INFINITY, 0.0), Vec3::X, Vec3::Y],
        ];
        let mut bad_at = Vec::new();
        for (k, v) in bad.iter().enumerate() {
            let at = 3 * k + 1;
            input.insert(at, TriangleInput { v: *v, material: 0 });
            bad_at.push(at as u32);
        }
        // A tiny triangle is not degenerate: its f32 cross product would underflow, its area is not 0.
        let q = Vec3::new(0.0, 0.0, 0.5);
        let tiny = TriangleInput {
            v: [q, q + Vec3::X * 1e-25, q + Vec3::Y * 1e-25],
            material: 0,
        };
        input.push(tiny);
        let bvh = built(&input);
        assert_eq!(bvh.dropped, bad_at);
        assert_eq!(bvh.stats.dropped, bad.len());
        assert_eq!(bvh.stats.input, input.len());
        assert_eq!(bvh.stats.triangles, good.len() + 1);
        // Every kept triangle is its input, by `source`.
        for t in &bvh.triangles {
            let src = &input[t.source as usize];
            assert_eq!([t.v0, t.v1, t.v2], src.v.map(|v| v.to_array()));
            assert_eq!(t.material, src.material);
        }
    }

    #[test]
    fn bvh_empty_and_single() {
        let empty = built(&[]);
        assert_eq!((empty.stats.nodes, empty.stats.triangles, empty.stats.depth), (1, 0, 0));
        let miss = intersect(
            &empty.wide,
            &empty.triangles,
            Vec3::ZERO,
            Vec3::X,
            0.0,
            f32::INFINITY,
            NO_BUDGET,
        );
        assert_eq!((miss.hit, miss.steps, miss.cut), (None, 1, false));
        let one = [TriangleInput {
            v: [Vec3::X, Vec3::Y, Vec3::Z],
            material: 3,
        }];
        let bvh = built(&one);
        assert_eq!((bvh.stats.nodes, bvh.stats.leaves, bvh.stats.depth), (1, 1, 0));
        let (hit, _) = same_as_brute_force(&bvh, Vec3::ZERO, Vec3::ONE, "single").unwrap();
        assert!((hit.t - 1.0 / 3.0).abs() < 1e-7);
    }

    /// The depth limit holds exactly where SAH alone would go deeper, and the tree is still right. (SAH
    /// itself never nears MAX_DEPTH in f32: it takes sizes shrinking by about the triangle count at each
    /// level. The GPU's stack at MAX_DEPTH is tested on a tree made by hand, tests/bvh.rs.)
    #[test]
    fn bvh_depth_limit_at_the_bound() {
        let chain = growing_chain(150, 1.25);
        let free = built(&chain);
        let limit = 12;
        assert!(free.stats.depth > limit, "SAH alone: depth {}", free.stats.depth);
        let opts = BvhOptions {
            max_depth: limit,
            ..BvhOptions::default()
        };
        let bvh = build(&chain, &opts).unwrap();
        bvh.validate(MAX_LEAF, limit).unwrap();
        println!(
            "chain of {}: depth {} by SAH, {} with the limit ({} median splits)",
            chain.len(),
            free.stats.depth,
            bvh.stats.depth,
            bvh.stats.median_splits
        );
        assert_eq!(bvh.stats.depth, limit);
        assert!(bvh.stats.median_splits > 0);
        // Rays onto every triangle, the deepest leaves included.
        for t in &chain {
            let target = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
            let o = target + Vec3::new(0.1, -1.0, 0.3) * (t.v[1].x - t.v[0].x);
            assert!(same_as_brute_force(&bvh, o, target - o, "chain").is_some());
        }
        // The tightest limit: 4000 triangles in leaves of 4 need 10 levels.
        let soup = random_soup(3, 4000, 1.0, 0.05);
        let opts = BvhOptions {
            max_depth: 10,
            ..BvhOptions::default()
        };
        let bvh = build(&soup, &opts).unwrap();
        bvh.validate(MAX_LEAF, 10).unwrap();
        assert_eq!(bvh.stats.depth, 10);
        let err = build(&soup, &BvhOptions { max_depth: 9, ..opts }).unwrap_err();
        assert!(err.to_string().contains("10 levels deep"), "{err}");
        assert!(build(
            &soup,
            &BvhOptions {
                max_depth: MAX_DEPTH + 1,
                ..opts
            }
        )
        .is_err());
    }

    /// Thousands of identical triangles: no plane separates them; median splits, and every one is tested.
    #[test]
    fn bvh_identical_triangles() {
        let t = TriangleInput {
            v: [Vec3::ZERO, Vec3::X, Vec3::Y],
            material: 0,
        };
        let bvh = built(&vec![t; 5000]);
        assert_eq!(bvh.stats.depth, levels_needed(5000, MAX_LEAF as usize));
        assert!(bvh.stats.median_splits > 0);
        let o = Vec3::new(0.25, 0.25, 1.0);
        let (hit, _) = same_as_brute_force(&bvh, o, -Vec3::Z, "stack").unwrap();
        assert_eq!(hit.t, 1.0);
        // Every box holds the hit point, so every triangle is tested, one a step, the node visits beside
        // them in the same steps or in steps of their own.
        let r = intersect(&bvh.wide, &bvh.triangles, o, -Vec3::Z, 0.0, f32::INFINITY, NO_BUDGET);
        assert!(
            (5000..=5000 + bvh.wide.len()).contains(&(r.steps as usize)),
            "{} steps, {} wide nodes",
            r.steps,
            bvh.wide.len()
        );
    }

    /// A traversal that needs S steps finishes with a budget of S and is cut with S - 1.
    #[test]
    fn bvh_step_budget_at_the_bound() {
        let bvh = built(&uv_sphere(Vec3::ZERO, 1.0, 16, 16, 0));
        let mut rng = Rng::new(5, 5);
        for _ in 0..200 {
            let o = Vec3::new(rng.float(), rng.float(), rng.float()) * 0.5;
            let d = random_unit(&mut rng);
            let full = intersect(&bvh.wide, &bvh.triangles, o, d, 0.0, f32::INFINITY, NO_BUDGET);
            assert!(full.hit.is_some() && !full.cut);
            let exact = intersect(&bvh.wide, &bvh.triangles, o, d, 0.0, f32::INFINITY, full.steps);
            assert_eq!(exact, full);
            let short = intersect(&bvh.wide, &bvh.triangles, o, d, 0.0, f32::INFINITY, full.steps - 1);
            assert!(short.cut && short.steps == full.steps - 1);
        }
    }

    /// The parallel build makes the very tree the single-threaded one does.
    #[test]
    fn bvh_build_is_deterministic_across_threads() {
        let soup = random_soup(8, 50_000, 10.0, 0.1);
        let one = build(
            &soup,
            &BvhOptions {
                threads: 1,
                ..BvhOptions::default()
            },
        )
        .unwrap();
        let many = build(
            &soup,
            &BvhOptions {
                threads: 4,
                ..BvhOptions::default()
            },
        )
        .unwrap();
        many.validate(MAX_LEAF, MAX_DEPTH).unwrap();
        assert_eq!(one.nodes, many.nodes);
        assert_eq!(one.triangles, many.triangles);
        assert_eq!(one.stats.sah_cost, many.stats.sah_cost);
    }

    #[test]
    fn bvh_stats_of_a_sphere() {
        let mesh = uv_sphere(Vec3::ZERO, 1.0, 101, 100, 0);
        let bvh = built(&mesh);
        let s = &bvh.stats;
        println!("{s:?}");
        assert_eq!((s.input, s.triangles, s.dropped), (mesh.len(), mesh.len(), 0));
        assert_eq!(s.nodes, 2 * s.leaves - 1);
        assert!(s.leaves >= mesh.len().div_ceil(MAX_LEAF as usize));
        // A ray that meets the root tests a handful of nodes and triangles, not 20000: the SAH cost of a
        // good tree over a closed surface is a few tens (one leaf of everything would cost 20000).
        assert!(s.sah_cost > 1.0 && s.sah_cost < 100.0, "SAH cost {}", s.sah_cost);
        assert!(
            s.depth >= levels_needed(mesh.len(), MAX_LEAF as usize) && s.depth < 40,
            "depth {}",
            s.depth
        );
        // The 4-wide nodes: 64 bytes each, about a third as many as the binary tree's (at most 4 children
        // where the binary has 2): fewer node bytes per triangle than the binary tree's 32-byte nodes.
        assert_eq!(bvh.node_bytes(), 64 * s.wide_nodes);
        assert!(
            s.wide_nodes * 3 <= s.nodes + 3 && bvh.node_bytes() < 32 * s.nodes,
            "{s:?}"
        );
        assert_eq!(bvh.triangle_bytes(), 48 * s.triangles);
    }

    #[test]
    fn levels() {
        assert_eq!(levels_needed(1, 4), 0);
        assert_eq!(levels_needed(4, 4), 0);
        assert_eq!(levels_needed(5, 4), 1);
        assert_eq!(levels_needed(8, 4), 1);
        assert_eq!(levels_needed(9, 4), 2);
        assert_eq!(levels_needed(1 << 20, 1), 20);
        assert_eq!(levels_needed((1 << 20) + 1, 1), 21);
    }
}

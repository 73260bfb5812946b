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
pub fn levels_needed(n: usize, max_leaf: usize) -> u32 {
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
    // The builder against brute force and the CPU twin's traversal: crates/reference/tests/bvh_build.rs.
    use super::*;

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

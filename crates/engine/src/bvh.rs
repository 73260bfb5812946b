//! A bounding volume hierarchy over triangles, built on the host and flattened for the GPU.
//!
//! Binned SAH (Wald 2007, "On fast Construction of SAH-based Bounding Volume Hierarchies"): at every node
//! the triangles' centroids are binned along all three axes and the split with the lowest surface area
//! heuristic cost is taken; a node becomes a leaf when it holds at most `max_leaf` triangles and splitting
//! would cost more. The top levels build in parallel (scoped threads). The binary tree is flattened depth
//! first like pbrt-v4's `LinearBVHNode` ([`BinaryNode`]: bounds, second child or first triangle, count and
//! split axis), with the triangles reordered into leaf order, and then collapsed into the 4-wide tree the
//! kernels traverse ([`Bvh::wide`], [`BvhNode`]): each wide node takes a binary node's children and opens
//! the largest interior one among them (by surface area) until it has four, so one node fetch and one run
//! of vector arithmetic test four boxes. `shaders/common/bvh.glsl` traverses it on the GPU and
//! [`crate::reference::bvh`] on the CPU.
//!
//! Depth is bounded by [`MAX_DEPTH`]: a node that could only just fit a balanced subtree below it in the
//! depth left is split at its median instead, which halves it. The wide tree is no deeper, and its
//! traversal stack holds three children per level ([`STACK`]).

use std::time::Instant;

use anyhow::{bail, ensure, Context as _, Result};
use glam::{Vec3, Vec3A};
use ppm_vk_device::{Buffer, ComputePipeline, Context};
use ppm_vk_kernels::bvh_trace::{self, TraceHit, TracePush, TraceRay};
use ppm_vk_kernels::layout::{BvhNode, Triangle, BVH_EMPTY};

/// The deepest leaf of a built tree (`BVH_MAX_DEPTH` in bvh.glsl).
pub const MAX_DEPTH: u32 = bvh_trace::MAX_DEPTH;
/// Entries of the traversal stack (`BVH_STACK` in bvh.glsl): three children of each of [`MAX_DEPTH`] levels.
pub const STACK: u32 = 3 * MAX_DEPTH;
/// Most triangles a leaf may hold.
pub const MAX_LEAF: u32 = 4;
/// Most triangles one BVH takes (node indices and leaf offsets are 32-bit, the count 30 bits).
pub const MAX_TRIANGLES: usize = 1 << 30;
/// SAH costs of a node visit and a triangle test. On lavapipe both are one step of the traversal loop
/// and of about the same work.
pub const TRAVERSAL_COST: f64 = 1.0;
pub const TRIANGLE_COST: f64 = 1.0;
/// Subtrees smaller than this are built on the thread that reached them.
const PARALLEL_MIN: usize = 4096;

/// `BinaryNode::count_axis & 3` of a leaf; 0-2 is an interior node's split axis.
pub const BINARY_LEAF: u32 = 3;

/// A node of the binary tree the builder makes, flattened depth first: an interior node's first child is
/// the next node, its second is at `offset`; a leaf holds the triangles `offset .. offset + count`. The
/// kernels traverse the 4-wide tree collapsed from it ([`Bvh::wide`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BinaryNode {
    pub lo: [f32; 3],
    /// Interior: index of the second child; leaf: first triangle.
    pub offset: u32,
    pub hi: [f32; 3],
    /// `count << 2 | axis`, axis [`BINARY_LEAF`] for a leaf.
    pub count_axis: u32,
}

impl BinaryNode {
    pub fn is_leaf(&self) -> bool {
        self.count_axis & 3 == BINARY_LEAF
    }

    /// Triangles of a leaf (0 for an interior node).
    pub fn count(&self) -> u32 {
        if self.is_leaf() {
            self.count_axis >> 2
        } else {
            0
        }
    }

    /// Split axis of an interior node.
    pub fn axis(&self) -> usize {
        (self.count_axis & 3) as usize
    }

    fn half_area(&self) -> f64 {
        Aabb {
            lo: Vec3A::from_array(self.lo),
            hi: Vec3A::from_array(self.hi),
        }
        .half_area()
    }
}

/// A triangle to build over: its vertices (counter-clockwise seen from the front) and material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleInput {
    pub v: [Vec3; 3],
    pub material: u32,
}

impl TriangleInput {
    /// Every mesh triangle of `scene`, in mesh order (the meshes are already in world space): what the
    /// scene's one BVH is built over.
    pub fn of_scene(scene: &crate::scene::Scene) -> Vec<TriangleInput> {
        scene
            .meshes
            .iter()
            .flat_map(|m| {
                m.triangles().map(|t| TriangleInput {
                    v: t.p,
                    material: t.material,
                })
            })
            .collect()
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BvhOptions {
    /// Most triangles per leaf, 1..=[`MAX_LEAF`].
    pub max_leaf: u32,
    /// SAH bins per axis, 2..=64.
    pub bins: u32,
    /// Deepest leaf allowed, 1..=[`MAX_DEPTH`] (lower only to test the depth limit).
    pub max_depth: u32,
    /// Threads to build with; 0: as many as the machine has.
    pub threads: usize,
}

impl Default for BvhOptions {
    fn default() -> BvhOptions {
        BvhOptions {
            max_leaf: MAX_LEAF,
            bins: 32,
            max_depth: MAX_DEPTH,
            threads: 0,
        }
    }
}

/// What a build made.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BvhStats {
    /// Triangles given.
    pub input: usize,
    /// Triangles in the tree.
    pub triangles: usize,
    /// Triangles dropped as degenerate (see [`Bvh::dropped`]).
    pub dropped: usize,
    /// Nodes of the binary tree.
    pub nodes: usize,
    pub leaves: usize,
    /// Edges from the root to the deepest leaf (a lone leaf: 0).
    pub depth: u32,
    /// Nodes of the 4-wide tree the kernels traverse, and the most entries its traversal's stack can hold
    /// (three children of every node on the path to the deepest leaf at most; at most [`STACK`]).
    pub wide_nodes: usize,
    pub stack_bound: u32,
    /// Expected cost of a ray that meets the root box: sum over nodes of area / root area times
    /// [`TRAVERSAL_COST`] (interior) or [`TRIANGLE_COST`] per triangle (leaves).
    pub sah_cost: f64,
    /// Nodes split at the median instead of by SAH: at the depth limit, or with coincident centroids.
    pub median_splits: usize,
    pub build_seconds: f64,
}

/// A flattened BVH: the binary tree and the 4-wide one collapsed from it, which the kernels read.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// Depth first from the root (index 0). A tree over no triangles is one empty leaf.
    pub nodes: Vec<BinaryNode>,
    /// The 4-wide tree ([`widen`]), its root first: a root with no children when there are no triangles.
    pub wide: Vec<BvhNode>,
    /// In leaf order; `Triangle::source` is the index in the input.
    pub triangles: Vec<Triangle>,
    /// Input indices of the triangles dropped: a coordinate NaN or infinite, or zero area (collinear or
    /// repeated vertices; no ray can hit one).
    pub dropped: Vec<u32>,
    pub stats: BvhStats,
}

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

#[derive(Clone, Copy, Debug)]
struct Aabb {
    lo: Vec3A,
    hi: Vec3A,
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        lo: Vec3A::splat(f32::INFINITY),
        hi: Vec3A::splat(f32::NEG_INFINITY),
    };

    fn grow(&mut self, lo: Vec3A, hi: Vec3A) {
        self.lo = self.lo.min(lo);
        self.hi = self.hi.max(hi);
    }

    fn union(self, o: Aabb) -> Aabb {
        Aabb {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
        }
    }

    /// Half the surface area, in f64 (large scenes overflow f32 products).
    fn half_area(&self) -> f64 {
        let e = (self.hi - self.lo).max(Vec3A::ZERO).as_dvec3();
        e.x * e.y + e.y * e.z + e.z * e.x
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

/// The 4-wide tree of a binary one: each wide node holds its binary node's children, the largest interior
/// one (by surface area) replaced by its own two while there are fewer than four. Depth first from the
/// root; a leaf keeps its binary leaf's triangles. The root's interior children's subtrees are made on
/// their own threads (up to `threads`) and appended in order.
pub fn widen(nodes: &[BinaryNode], threads: usize) -> Vec<BvhNode> {
    let root = &nodes[0];
    if root.is_leaf() {
        let mut n = BvhNode::default();
        if root.count() > 0 {
            n = BvhNode::new(&[(root.lo, root.hi, BvhNode::leaf(root.offset, root.count()))]);
        }
        return vec![n];
    }
    let kids = open_children(nodes, 0);
    let subtrees: Vec<Option<Vec<BvhNode>>> = std::thread::scope(|s| {
        let handles: Vec<_> = kids
            .iter()
            .map(|&c| {
                let interior = !nodes[c].is_leaf();
                let big = nodes.len() >= PARALLEL_MIN && threads > 1;
                (interior && big).then(|| s.spawn(move || widen_from(nodes, c)))
            })
            .collect();
        kids.iter()
            .zip(handles)
            .map(|(&c, h)| match h {
                Some(h) => Some(h.join().expect("a BVH widening thread panicked")),
                None => (!nodes[c].is_leaf()).then(|| widen_from(nodes, c)),
            })
            .collect()
    });
    let mut wide = vec![BvhNode::default()];
    let mut children = [([0f32; 3], [0f32; 3], 0u32); 4];
    for (slot, (&c, sub)) in kids.iter().zip(subtrees).enumerate() {
        let node = &nodes[c];
        let child = match sub {
            None => BvhNode::leaf(node.offset, node.count()),
            Some(sub) => {
                let base = wide.len() as u32;
                wide.extend(sub.into_iter().map(|mut n| {
                    for r in n
                        .child
                        .iter_mut()
                        .filter(|r| **r != BVH_EMPTY && BvhNode::leaf_range(**r).is_none())
                    {
                        *r += base;
                    }
                    n
                }));
                base
            }
        };
        children[slot] = (node.lo, node.hi, child);
    }
    wide[0] = BvhNode::new(&children[..kids.len()]);
    wide
}

/// The binary children of interior node `b` that one wide node takes: its two, the largest interior one
/// (by surface area; the last of equal ones) opened into its own two while there are fewer than four.
fn open_children(nodes: &[BinaryNode], b: usize) -> Kids {
    let mut kids = Kids::new(b + 1, nodes[b].offset as usize);
    while kids.len() < 4 {
        let open = (0..kids.len())
            .filter(|&k| !nodes[kids[k]].is_leaf())
            .max_by(|&p, &q| nodes[kids[p]].half_area().total_cmp(&nodes[kids[q]].half_area()));
        let Some(k) = open else { break };
        let c = kids[k];
        kids.replace_with_two(k, c + 1, nodes[c].offset as usize);
    }
    kids
}

/// The wide subtree whose root takes the children of binary interior node `b`, its root at index 0.
fn widen_from(nodes: &[BinaryNode], b: usize) -> Vec<BvhNode> {
    let mut wide = vec![BvhNode::default()];
    // (binary node whose children the wide node takes, wide node)
    let mut work = vec![(b, 0usize)];
    while let Some((b, w)) = work.pop() {
        let kids = open_children(nodes, b);
        let mut children = [([0f32; 3], [0f32; 3], 0u32); 4];
        for (slot, &c) in kids.iter().enumerate() {
            let node = &nodes[c];
            let child = if node.is_leaf() {
                BvhNode::leaf(node.offset, node.count())
            } else {
                wide.push(BvhNode::default());
                work.push((c, wide.len() - 1));
                (wide.len() - 1) as u32
            };
            children[slot] = (node.lo, node.hi, child);
        }
        wide[w] = BvhNode::new(&children[..kids.len()]);
    }
    wide
}

/// Up to four child indices, without allocating.
#[derive(Clone, Copy)]
struct Kids {
    items: [usize; 4],
    len: usize,
}

impl Kids {
    fn new(a: usize, b: usize) -> Kids {
        Kids {
            items: [a, b, 0, 0],
            len: 2,
        }
    }

    fn len(&self) -> usize {
        self.len
    }

    /// Replaces item `k` by `a` and `b`, in its place.
    fn replace_with_two(&mut self, k: usize, a: usize, b: usize) {
        self.items.copy_within(k + 1..self.len, k + 2);
        (self.items[k], self.items[k + 1]) = (a, b);
        self.len += 1;
    }

    fn iter(&self) -> std::slice::Iter<'_, usize> {
        self.items[..self.len].iter()
    }
}

impl std::ops::Index<usize> for Kids {
    type Output = usize;
    fn index(&self, k: usize) -> &usize {
        &self.items[..self.len][k]
    }
}

/// The most entries bvh.glsl's traversal of `wide` can have on its stack: over the paths from the root, the
/// sum of each node's children less the one visited.
pub fn stack_bound(wide: &[BvhNode]) -> u32 {
    // Children follow their parents (depth-first order), so a backward pass sees every child first.
    let mut need = vec![0u32; wide.len()];
    for i in (0..wide.len()).rev() {
        let n = &wide[i];
        let children = n.child.iter().filter(|&&c| c != BVH_EMPTY).count() as u32;
        let deepest = n
            .child
            .iter()
            .filter(|&&c| c != BVH_EMPTY && BvhNode::leaf_range(c).is_none())
            .map(|&c| need[c as usize])
            .max()
            .unwrap_or(0);
        need[i] = children.saturating_sub(1) + deepest;
    }
    need[0]
}

impl Bvh {
    /// (depth, leaves, SAH cost) of the flattened tree.
    fn shape(&self) -> (u32, usize, f64) {
        let root = Aabb {
            lo: Vec3A::from_array(self.nodes[0].lo),
            hi: Vec3A::from_array(self.nodes[0].hi),
        };
        let root_area = root.half_area();
        // Children follow their parent in depth-first order, so one forward pass sets every depth.
        let mut depths = vec![0u32; self.nodes.len()];
        let (mut max_depth, mut leaves, mut cost) = (0, 0, 0.0);
        for (i, n) in self.nodes.iter().enumerate() {
            let area = Aabb {
                lo: Vec3A::from_array(n.lo),
                hi: Vec3A::from_array(n.hi),
            }
            .half_area();
            let rel = if root_area > 0.0 { area / root_area } else { 1.0 };
            max_depth = max_depth.max(depths[i]);
            if n.is_leaf() {
                leaves += 1;
                cost += rel * TRIANGLE_COST * n.count() as f64;
            } else {
                cost += rel * TRAVERSAL_COST;
                depths[i + 1] = depths[i] + 1;
                depths[n.offset as usize] = depths[i] + 1;
            }
        }
        (max_depth, leaves, cost)
    }

    /// Bytes of the node buffer.
    /// (the kernels' 4-wide nodes).
    pub fn node_bytes(&self) -> usize {
        std::mem::size_of_val(self.wide.as_slice())
    }

    /// Bytes of the triangle buffer.
    pub fn triangle_bytes(&self) -> usize {
        std::mem::size_of_val(self.triangles.as_slice())
    }

    /// Checks the tree's invariants: every triangle in exactly one leaf, leaves of 1..=max_leaf (one
    /// empty leaf for an empty tree), children inside their parent's box, triangles inside their leaf's,
    /// children after their parent, depth within `max_depth`. The tests call it; a build never needs it.
    pub fn validate(&self, max_leaf: u32, max_depth: u32) -> Result<()> {
        ensure!(!self.nodes.is_empty(), "no root node");
        if self.triangles.is_empty() {
            ensure!(
                self.nodes.len() == 1 && self.nodes[0].is_leaf() && self.nodes[0].count() == 0,
                "empty tree"
            );
            return Ok(());
        }
        let inside = |lo: [f32; 3], hi: [f32; 3], p: [f32; 3]| (0..3).all(|k| lo[k] <= p[k] && p[k] <= hi[k]);
        let mut seen = vec![false; self.triangles.len()];
        // (node, depth)
        let mut stack = vec![(0usize, 0u32)];
        let mut visited = 0;
        while let Some((i, depth)) = stack.pop() {
            visited += 1;
            let n = self
                .nodes
                .get(i)
                .with_context(|| format!("node index {i} out of range"))?;
            ensure!(depth <= max_depth, "node {i} at depth {depth}, past {max_depth}");
            if n.is_leaf() {
                let (first, count) = (n.offset as usize, n.count() as usize);
                ensure!(
                    (1..=max_leaf as usize).contains(&count),
                    "leaf {i} holds {count} triangles"
                );
                ensure!(first + count <= self.triangles.len(), "leaf {i} past the triangles");
                for (k, t) in self.triangles[first..first + count].iter().enumerate() {
                    ensure!(
                        !std::mem::replace(&mut seen[first + k], true),
                        "triangle {} in two leaves",
                        first + k
                    );
                    for v in [t.v0, t.v1, t.v2] {
                        ensure!(inside(n.lo, n.hi, v), "triangle {} outside leaf {i}", first + k);
                    }
                }
            } else {
                let second = n.offset as usize;
                ensure!(n.axis() < 3, "node {i}: axis {}", n.axis());
                ensure!(
                    second > i + 1 && second < self.nodes.len(),
                    "node {i}: second child {second}"
                );
                for c in [i + 1, second] {
                    let child = &self.nodes[c];
                    ensure!(
                        inside(n.lo, n.hi, child.lo) && inside(n.lo, n.hi, child.hi),
                        "node {c} outside its parent {i}"
                    );
                    stack.push((c, depth + 1));
                }
            }
        }
        ensure!(
            visited == self.nodes.len(),
            "{} nodes unreachable",
            self.nodes.len() - visited
        );
        ensure!(seen.iter().all(|&s| s), "a triangle in no leaf");
        Ok(())
    }

    /// Checks the 4-wide tree the kernels read: child indices in range and after their parent (no cycles,
    /// every node reached once), leaves of 1..=[`MAX_LEAF`] triangles within the buffer, every triangle in
    /// exactly one leaf, every child's box (as the kernels decode it) holding all the triangles below it,
    /// and a stack bound within [`STACK`]. `DeviceBvh::new` calls it: a bad index would read out of bounds
    /// on the GPU. (Decoded boxes need not nest: each is rounded outwards from its own content.)
    pub fn validate_wide(&self) -> Result<()> {
        ensure!(!self.wide.is_empty(), "no root node");
        let mut seen = vec![false; self.triangles.len()];
        let mut reached = vec![false; self.wide.len()];
        reached[0] = true;
        for (i, n) in self.wide.iter().enumerate() {
            ensure!(reached[i], "wide node {i} unreachable");
            for &c in n.child.iter().filter(|&&c| c != BVH_EMPTY) {
                if let Some((first, count)) = BvhNode::leaf_range(c) {
                    let (first, count) = (first as usize, count as usize);
                    ensure!(count <= MAX_LEAF as usize, "wide node {i}: a leaf of {count} triangles");
                    ensure!(
                        first + count <= self.triangles.len(),
                        "wide node {i}: a leaf past the triangles"
                    );
                    for (k, s) in seen.iter_mut().enumerate().skip(first).take(count) {
                        ensure!(!std::mem::replace(s, true), "triangle {k} in two leaves");
                    }
                } else {
                    let c = c as usize;
                    ensure!(c > i && c < self.wide.len(), "wide node {i}: child {c}");
                    ensure!(!std::mem::replace(&mut reached[c], true), "wide node {c} reached twice");
                }
            }
        }
        ensure!(seen.iter().all(|&s| s), "a triangle in no leaf");
        // The triangles' bounds below each node, children first (they follow their parents), against the
        // decoded boxes.
        let mut content = vec![Aabb::EMPTY; self.wide.len()];
        for i in (0..self.wide.len()).rev() {
            let n = &self.wide[i];
            let boxes = n.child_boxes();
            for (slot, &c) in n.child.iter().enumerate().filter(|(_, &c)| c != BVH_EMPTY) {
                let mut below = Aabb::EMPTY;
                match BvhNode::leaf_range(c) {
                    Some((first, count)) => {
                        for t in &self.triangles[first as usize..(first + count) as usize] {
                            for v in [t.v0, t.v1, t.v2] {
                                let p = Vec3A::from_array(v);
                                below.grow(p, p);
                            }
                        }
                    }
                    None => below = content[c as usize],
                }
                let (lo, hi) = boxes[slot];
                ensure!(
                    Vec3A::from_array(lo).cmple(below.lo).all() && Vec3A::from_array(hi).cmpge(below.hi).all(),
                    "wide node {i}: child {slot}'s box {lo:?}..{hi:?} does not hold {:?}..{:?}",
                    below.lo,
                    below.hi
                );
                content[i] = content[i].union(below);
            }
        }
        let bound = stack_bound(&self.wide);
        ensure!(
            bound <= STACK,
            "the traversal could need {bound} stack entries, more than its {STACK} (the tree is too deep)"
        );
        Ok(())
    }
}

/// A BVH in device buffers, for a kernel that includes `shaders/common/bvh.glsl`: bind `nodes` (the 4-wide
/// tree) to its `BvhNode bvh_nodes[]` and `triangles` to its `Triangle bvh_triangles[]`.
pub struct DeviceBvh {
    pub nodes: Buffer,
    pub triangles: Buffer,
}

impl DeviceBvh {
    pub fn new(ctx: &Context, bvh: &Bvh) -> Result<DeviceBvh> {
        // build() never makes a tree the GPU cannot walk (its stack holds three children of MAX_DEPTH
        // levels), but a Bvh may have been put together or changed by hand, and a bad index would read out
        // of bounds there.
        bvh.validate_wide()
            .context("uploading a BVH the GPU traversal cannot take")?;
        Ok(DeviceBvh {
            nodes: ctx
                .buffer_from("bvh nodes", &bvh.wide)
                .context("uploading the BVH's nodes")?,
            triangles: ctx
                .buffer_from("bvh triangles", &bvh.triangles)
                .context("uploading the BVH's triangles")?,
        })
    }
}

/// The test kernel `bvh_trace.comp`: nearest hits of a batch of rays on the GPU.
pub struct BvhTracer {
    pipeline: ComputePipeline,
}

impl BvhTracer {
    pub fn new(ctx: &Context) -> Result<BvhTracer> {
        Ok(BvhTracer {
            pipeline: ppm_vk_kernels::pipeline(ctx, &ppm_vk_kernels::reflected::BVH_TRACE)?,
        })
    }

    /// The nearest hit of each ray, each traversal taking at most `budget` steps (at most
    /// [`bvh_trace::MAX_BUDGET`]); records of cut traversals keep `cut = 1`. See [`BvhTracer::trace`].
    pub fn trace_unchecked(
        &self,
        ctx: &Context,
        bvh: &DeviceBvh,
        rays: &[TraceRay],
        budget: u32,
    ) -> Result<Vec<TraceHit>> {
        self.dispatch(ctx, bvh, rays, budget, false)
    }

    /// Shadow rays: each traversal ends at the first hit it finds (any hit in (tmin, tmax), not the
    /// nearest); records as [`BvhTracer::trace_unchecked`]'s.
    pub fn trace_any_unchecked(
        &self,
        ctx: &Context,
        bvh: &DeviceBvh,
        rays: &[TraceRay],
        budget: u32,
    ) -> Result<Vec<TraceHit>> {
        self.dispatch(ctx, bvh, rays, budget, true)
    }

    fn dispatch(
        &self,
        ctx: &Context,
        bvh: &DeviceBvh,
        rays: &[TraceRay],
        budget: u32,
        any_hit: bool,
    ) -> Result<Vec<TraceHit>> {
        if rays.is_empty() {
            return Ok(Vec::new());
        }
        let ray_buf = ctx.buffer_from("bvh trace rays", rays).context("uploading the rays")?;
        let hit_buf = Buffer::new(
            ctx,
            "bvh trace hits",
            std::mem::size_of_val(rays) as u64 / std::mem::size_of::<TraceRay>() as u64
                * std::mem::size_of::<TraceHit>() as u64,
            ppm_vk_device::BufferKind::Storage,
        )?;
        let push = TracePush {
            count: rays.len() as u32,
            budget,
            any_hit: any_hit as u32,
        };
        ctx.run(|cmd| {
            bvh_trace::record(
                &self.pipeline,
                cmd,
                &bvh.nodes,
                &bvh.triangles,
                &ray_buf,
                &hit_buf,
                &push,
            )
        })
        .context("tracing rays through the BVH")?;
        ctx.download_prefix(&hit_buf, rays.len())
            .context("reading the BVH hits back")
    }

    /// [`BvhTracer::trace_unchecked`] that fails if any traversal was cut at the budget: its hit would be
    /// wrong without a word (on lavapipe the device's own loop limit cuts the same way, silently).
    pub fn trace(&self, ctx: &Context, bvh: &DeviceBvh, rays: &[TraceRay], budget: u32) -> Result<Vec<TraceHit>> {
        let hits = self.trace_unchecked(ctx, bvh, rays, budget)?;
        let cut: Vec<usize> = hits
            .iter()
            .enumerate()
            .filter(|(_, h)| h.cut != 0)
            .map(|(i, _)| i)
            .collect();
        if let Some(&first) = cut.first() {
            bail!(
                "{} of {} BVH traversals were cut at the budget of {budget} loop steps (node visits + triangle \
                 tests; lavapipe ends a SIMD group's loops after {} iterations), first ray {first}: too many \
                 overlapping triangles along the ray",
                cut.len(),
                hits.len(),
                bvh_trace::LOOP_LIMIT
            );
        }
        Ok(hits)
    }
}

/// Generated meshes: the tests' closed shapes and triangle soups, and the build benchmark's input. Shared
/// vertices are computed once per grid point, so the triangles around them see them bit for bit.
#[cfg(any(test, feature = "test-hooks"))]
pub mod meshes {
    use std::f32::consts::PI;

    use glam::Vec3;

    use super::TriangleInput;
    use crate::reference::rng::Rng;

    fn tri(a: Vec3, b: Vec3, c: Vec3, material: u32) -> TriangleInput {
        TriangleInput { v: [a, b, c], material }
    }

    /// A closed UV sphere: `rings` bands from pole to pole, `segments` around, fans at the poles;
    /// counter-clockwise seen from outside. 2 segments (rings - 1) triangles.
    pub fn uv_sphere(center: Vec3, radius: f32, rings: u32, segments: u32, material: u32) -> Vec<TriangleInput> {
        assert!(rings >= 2 && segments >= 3);
        let vertex = |ring: u32, seg: u32| -> Vec3 {
            match ring {
                0 => center + radius * Vec3::Z,
                r if r == rings => center - radius * Vec3::Z,
                r => {
                    let theta = PI * r as f32 / rings as f32;
                    let phi = 2.0 * PI * (seg % segments) as f32 / segments as f32;
                    center + radius * Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
                }
            }
        };
        let mut out = Vec::with_capacity(2 * (segments * (rings - 1)) as usize);
        for r in 0..rings {
            for s in 0..segments {
                let (a, b, c, d) = (vertex(r, s), vertex(r + 1, s), vertex(r + 1, s + 1), vertex(r, s + 1));
                if r + 1 < rings {
                    out.push(tri(a, b, c, material));
                }
                if r > 0 {
                    out.push(tri(a, c, d, material));
                }
            }
        }
        out
    }

    /// The closed box [lo, hi], each face an n x n grid of cells cut along a diagonal: 12 n^2 triangles,
    /// counter-clockwise seen from outside.
    pub fn box_grid(lo: Vec3, hi: Vec3, n: u32, material: u32) -> Vec<TriangleInput> {
        let point = |g: [u32; 3]| lo + (hi - lo) * (Vec3::new(g[0] as f32, g[1] as f32, g[2] as f32) / n as f32);
        let mut out = Vec::with_capacity(12 * (n * n) as usize);
        for axis in 0..3 {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for side in [0, n] {
                for i in 0..n {
                    for j in 0..n {
                        let corner = |di: u32, dj: u32| {
                            let mut g = [0; 3];
                            g[axis] = side;
                            g[u] = i + di;
                            g[v] = j + dj;
                            point(g)
                        };
                        let (p00, p10, p11, p01) = (corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1));
                        // cross(u, v) is +axis: the far face winds u then v, the near one the other way.
                        if side == n {
                            out.push(tri(p00, p10, p11, material));
                            out.push(tri(p00, p11, p01, material));
                        } else {
                            out.push(tri(p00, p11, p10, material));
                            out.push(tri(p00, p01, p11, material));
                        }
                    }
                }
            }
        }
        out
    }

    /// `n` random triangles: centres uniform in [0, extent]^3, vertices within `size` of them per axis.
    pub fn random_soup(seed: u64, n: usize, extent: f32, size: f32) -> Vec<TriangleInput> {
        let mut rng = Rng::new(seed, 0x5005);
        let mut v3 = |s: f32, off: f32| Vec3::new(rng.float(), rng.float(), rng.float()) * s + Vec3::splat(off);
        (0..n)
            .map(|i| {
                let c = v3(extent, 0.0);
                let (a, b, d) = (v3(2.0 * size, -size), v3(2.0 * size, -size), v3(2.0 * size, -size));
                tri(c + a, c + b, c + d, i as u32 % 7)
            })
            .collect()
    }

    /// `n` triangles side by side along x, each `ratio` times the size of the one before: SAH peels the
    /// largest off at every level, so without the depth limit the tree would be about n deep.
    pub fn growing_chain(n: u32, ratio: f32) -> Vec<TriangleInput> {
        let mut out = Vec::new();
        let (mut x, mut s) = (0.0f32, 1.0f32);
        for _ in 0..n {
            out.push(tri(
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + s, 0.0, 0.0),
                Vec3::new(x, s, s),
                0,
            ));
            x += s;
            s *= ratio;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::meshes::*;
    use super::*;
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

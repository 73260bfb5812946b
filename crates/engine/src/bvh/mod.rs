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
//!
//! `build.rs` is the binned SAH builder, `widen.rs` the collapse into the 4-wide tree, `device.rs` the
//! Vulkan side (the tree in device buffers, the test kernel that traces it); this file holds the types,
//! the options, the statistics and the checks of a built tree.

use anyhow::{ensure, Context as _, Result};
use glam::{Vec3, Vec3A};
use ppm_vk_kernels::bvh_trace;
use ppm_vk_kernels::layout::{BvhNode, Triangle, BVH_EMPTY};

mod build;
// A BVH uploaded and traced alone, by the traversal's test kernel (the tests and the examples).
mod device;
mod widen;

pub use build::{build, levels_needed};
pub use device::{BvhTracer, DeviceBvh};
pub use widen::{stack_bound, widen};

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

//! The binary tree collapsed into the 4-wide one the kernels traverse, and the stack its traversal needs.

use ppm_vk_kernels::layout::{BvhNode, BVH_EMPTY};

use super::{BinaryNode, PARALLEL_MIN};

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

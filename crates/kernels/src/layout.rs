//! The records kernels share with the host: `#[repr(C)]` twins of `shaders/common/types.glsl`, each
//! checked at compile time against the std430 layout glslang produced (see `gpu_struct!`).

use bytemuck::{Pod, Zeroable};

use crate::gpu_struct;

pub const SURFACE_DIFFUSE: u32 = 0;
pub const SURFACE_MIRROR: u32 = 1;
pub const SURFACE_GLASS: u32 = 2;
/// `HitPoint::pixel` of an empty slot.
pub const EMPTY_SLOT: u32 = u32::MAX;
/// The probe pass's fixed-point scale for d^2 / r^2 (2^30).
pub const PROBE_FIXED: f64 = 1073741824.0;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Material {
    pub color: [f32; 3],
    pub surface: u32,
    pub emission: [f32; 3],
    pub ior: f32,
}
gpu_struct!(Material {
    color,
    surface,
    emission,
    ior
});

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Sphere {
    pub center: [f32; 3],
    pub radius: f32,
    pub material: u32,
    pub pad0: u32,
    pub pad1: u32,
    pub pad2: u32,
}
gpu_struct!(Sphere {
    center,
    radius,
    material,
    pad0,
    pad1,
    pad2
});

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Quad {
    pub origin: [f32; 3],
    pub material: u32,
    pub edge_u: [f32; 3],
    pub area: f32,
    pub edge_v: [f32; 3],
    pub plane_d: f32,
    pub normal: [f32; 3],
    pub pad0: f32,
    pub w: [f32; 3],
    pub pad1: f32,
}
gpu_struct!(Quad {
    origin,
    material,
    edge_u,
    area,
    edge_v,
    plane_d,
    normal,
    pad0,
    w,
    pad1
});

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Light {
    /// Into the quads ([`LIGHT_QUAD`]) or the BVH's leaf-ordered triangles ([`LIGHT_TRIANGLE`]).
    pub index: u32,
    pub cdf: f32,
    pub prob: f32,
    pub kind: u32,
    pub power: [f32; 3],
    pub pad1: f32,
}
gpu_struct!(Light {
    index,
    cdf,
    prob,
    kind,
    power,
    pad1
});
pub const LIGHT_QUAD: u32 = 0;
pub const LIGHT_TRIANGLE: u32 = 1;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RenderParams {
    pub eye: [f32; 3],
    pub tan_half_fov: f32,
    pub right: [f32; 3],
    pub aspect: f32,
    pub up: [f32; 3],
    pub width: u32,
    pub forward: [f32; 3],
    pub height: u32,
    pub grid_min: [f32; 3],
    pub cell_size: f32,
    pub grid_mask: u32,
    pub num_spheres: u32,
    pub num_quads: u32,
    pub num_lights: u32,
    pub eps: f32,
    pub max_photon_depth: u32,
    pub max_eye_depth: u32,
    pub hit_slots: u32,
    pub photon_capacity: u32,
    pub seed: u32,
    /// Fixed-point units per unit of flux in [`PassAccum`] (a power of two).
    pub flux_fixed: f32,
    /// Ray offset per unit of the point's largest coordinate.
    pub eps_rel: f32,
    /// Triangles in the BVH (0: the kernels do not traverse it).
    pub num_triangles: u32,
    /// BVH traversal steps one photon thread / one eye thread may take in all (`PathLimits`).
    pub photon_bvh_budget: u32,
    pub eye_bvh_budget: u32,
    /// Loop steps a subgroup's photon lookups may take before one may have been cut short by the
    /// device's loop budget (`lookup_limit`); `u32::MAX` where the device has none.
    pub lookup_limit: u32,
}
gpu_struct!(RenderParams {
    eye,
    tan_half_fov,
    right,
    aspect,
    up,
    width,
    forward,
    height,
    grid_min,
    cell_size,
    grid_mask,
    num_spheres,
    num_quads,
    num_lights,
    eps,
    max_photon_depth,
    max_eye_depth,
    hit_slots,
    photon_capacity,
    seed,
    flux_fixed,
    eps_rel,
    num_triangles,
    photon_bvh_budget,
    eye_bvh_budget,
    lookup_limit
});

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct HitPoint {
    pub pos: [f32; 3],
    pub pixel: u32,
    pub normal: [f32; 3],
    pub pad0: u32,
    pub weight: [f32; 3],
    pub pad1: u32,
}
gpu_struct!(HitPoint {
    pos,
    pixel,
    normal,
    pad0,
    weight,
    pad1
});

impl HitPoint {
    pub fn is_empty(&self) -> bool {
        self.pixel == EMPTY_SLOT
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct HitStats {
    pub n: f64,
    pub r2: f64,
    pub tau_r: f64,
    pub tau_g: f64,
    pub tau_b: f64,
    /// lambda / r^2 from the probe pass (eq. 7), or 0 without probing.
    pub probe: f64,
}
gpu_struct!(HitStats {
    n,
    r2,
    tau_r,
    tau_g,
    tau_b,
    probe
});

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct PassAccum {
    pub flux_r: i64,
    pub flux_g: i64,
    pub flux_b: i64,
    pub m: u32,
    pub pad0: u32,
}
gpu_struct!(PassAccum {
    flux_r,
    flux_g,
    flux_b,
    m,
    pad0
});

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Photon {
    pub pos: [f32; 3],
    pub cell: u32,
    pub flux: [f32; 3],
    pub dir: u32,
}
gpu_struct!(Photon { pos, cell, flux, dir });
// grid_scatter.comp copies a Photon as four 64-bit words and reads `cell` as the high half of the second.
const _: () = assert!(std::mem::offset_of!(Photon, cell) == 12 && std::mem::size_of::<Photon>() == 32);

/// Paths the tracing kernels ended at their depth backstops (`PathLimits`), cumulative over a render.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct PathCounters {
    pub photon_paths: u32,
    pub eye_paths: u32,
    /// Paths whose BVH traversal ran out of the loop budget: the renderer stops with an error.
    pub traversal_cut: u32,
    pub pad0: u32,
}
gpu_struct!(PathCounters {
    photon_paths,
    eye_paths,
    traversal_cut,
    pad0
});

/// A photon batch's work counters in a BVH scene (photon.comp, photon_resume.comp).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct PhotonWork {
    /// Photons of the batch the threads have taken (may pass the batch's count).
    pub started: u32,
    /// Photons suspended for the resume round.
    pub suspended: u32,
    pub pad0: u32,
    pub pad1: u32,
    /// The resume round's workgroups: a `VkDispatchIndirectCommand` at [`PhotonWork::GROUPS_OFFSET`].
    pub groups: [u32; 3],
    pub pad2: u32,
}
gpu_struct!(PhotonWork {
    started,
    suspended,
    pad0,
    pad1,
    groups,
    pad2
});

impl PhotonWork {
    pub const GROUPS_OFFSET: u64 = std::mem::offset_of!(PhotonWork, groups) as u64;
}

/// A photon suspended where its thread's loop budget ran out (photon.comp).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PhotonState {
    pub state: u64,
    pub inc: u64,
    pub o: [f32; 3],
    pub depth: u32,
    pub d: [f32; 3],
    pub pad0: u32,
    pub flux: [f32; 3],
    pub pad1: u32,
}
gpu_struct!(PhotonState {
    state,
    inc,
    o,
    depth,
    d,
    pad0,
    flux,
    pad1
});

/// `BvhNode::child` of a slot without a child.
pub const BVH_EMPTY: u32 = u32::MAX;
/// `BvhNode::child` of a leaf: this bit, its triangle count less one from [`BVH_COUNT_SHIFT`] and its first
/// triangle below (bvh.glsl's constants of the same names).
pub const BVH_LEAF: u32 = 1 << 31;
pub const BVH_COUNT_SHIFT: u32 = 29;
pub const BVH_FIRST_MASK: u32 = (1 << BVH_COUNT_SHIFT) - 1;

/// A node of the 4-wide BVH the kernels traverse (shaders/common/bvh.glsl): the boxes of up to four
/// children, axis by axis with one child per vector component, and each child's reference
/// ([`BVH_EMPTY`], an interior node's index, or a leaf, [`BvhNode::leaf`]). crates/engine/src/bvh.rs
/// collapses the binary SAH tree into it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    pub lo_x: [f32; 4],
    pub hi_x: [f32; 4],
    pub lo_y: [f32; 4],
    pub hi_y: [f32; 4],
    pub lo_z: [f32; 4],
    pub hi_z: [f32; 4],
    pub child: [u32; 4],
}
gpu_struct!(BvhNode {
    lo_x,
    hi_x,
    lo_y,
    hi_y,
    lo_z,
    hi_z,
    child
});

impl Default for BvhNode {
    /// A node without children.
    fn default() -> BvhNode {
        BvhNode {
            lo_x: [0.0; 4],
            hi_x: [0.0; 4],
            lo_y: [0.0; 4],
            hi_y: [0.0; 4],
            lo_z: [0.0; 4],
            hi_z: [0.0; 4],
            child: [BVH_EMPTY; 4],
        }
    }
}

impl BvhNode {
    /// The reference to a leaf of `count` (1..=4) triangles from `first` (below 2^29).
    pub fn leaf(first: u32, count: u32) -> u32 {
        debug_assert!((1..=4).contains(&count) && first <= BVH_FIRST_MASK);
        BVH_LEAF | (count - 1) << BVH_COUNT_SHIFT | first
    }

    /// A leaf reference's (first triangle, count); `None` for an interior node or an empty slot.
    pub fn leaf_range(child: u32) -> Option<(u32, u32)> {
        (child != BVH_EMPTY && child & BVH_LEAF != 0)
            .then(|| (child & BVH_FIRST_MASK, (child >> BVH_COUNT_SHIFT & 3) + 1))
    }

    /// Child `i`'s box.
    pub fn child_box(&self, i: usize) -> ([f32; 3], [f32; 3]) {
        (
            [self.lo_x[i], self.lo_y[i], self.lo_z[i]],
            [self.hi_x[i], self.hi_y[i], self.hi_z[i]],
        )
    }

    /// Sets child `i`: its box and its reference.
    pub fn set_child(&mut self, i: usize, lo: [f32; 3], hi: [f32; 3], child: u32) {
        (self.lo_x[i], self.lo_y[i], self.lo_z[i]) = (lo[0], lo[1], lo[2]);
        (self.hi_x[i], self.hi_y[i], self.hi_z[i]) = (hi[0], hi[1], hi[2]);
        self.child[i] = child;
    }
}

/// A triangle of the BVH in leaf order: its vertices as given (the watertight test needs shared vertices
/// bit-identical), its material and its index in the builder's input.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Triangle {
    pub v0: [f32; 3],
    pub material: u32,
    pub v1: [f32; 3],
    pub source: u32,
    pub v2: [f32; 3],
    pub pad0: u32,
}
gpu_struct!(Triangle {
    v0,
    material,
    v1,
    source,
    v2,
    pad0
});

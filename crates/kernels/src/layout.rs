//! The records kernels share with the host: `#[repr(C)]` twins of `shaders/common/types.glsl`, each
//! checked at compile time against the std430 layout glslang produced (see `gpu_struct!`).

use bytemuck::{Pod, Zeroable};

use crate::gpu_struct;

/// How many blends deep blend.glsl resolves a hit's material (ppm_vk_materials::blend::MAX_BLEND_DEPTH,
/// checked equal where the engine lowers blends).
pub use crate::reflected::constants::MAX_BLEND_DEPTH;
/// `RenderParams::glossy_light` (ray/glossy_light.glsl).
pub use crate::reflected::constants::{GLOSSY_LIGHT_BSDF, GLOSSY_LIGHT_LIGHTS, GLOSSY_LIGHT_MIS};
/// `Material::distribution` of a rough surface (microfacet.glsl).
pub use crate::reflected::constants::{MICROFACET_BECKMANN, MICROFACET_GGX};
/// `Material::surface`: which BSDF (types.glsl).
pub use crate::reflected::constants::{
    SURFACE_BLEND, SURFACE_CONDUCTOR, SURFACE_DIFFUSE, SURFACE_GLASS, SURFACE_MIRROR, SURFACE_PLASTIC,
    SURFACE_ROUGH_CONDUCTOR, SURFACE_ROUGH_GLASS, SURFACE_THIN,
};
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
    /// The terms only some surfaces read (types.glsl says which): a conductor's complex index of
    /// refraction eta + i k (`lobe_a`, `lobe_b`), a plastic's specular_reflectance (`lobe_a`) and the
    /// bound of its diffuse weight (`lobe_b[0]`), a thin dielectric's specular_transmittance (`lobe_a`).
    /// Zero for other surfaces.
    pub lobe_a: [f32; 3],
    /// 0: no texture; else 1 + the texel of its texture's header in the texture buffer (texture.glsl).
    pub texture: u32,
    /// See `lobe_a`; a plastic's `lobe_b[1]` and `lobe_b[2]` hold its fdr_int and 1 if nonlinear, which
    /// turn a texture's diffuse_reflectance into its diffuse factor.
    pub lobe_b: [f32; 3],
    /// 0: no bump or normal map; else 1 + the texel of its record in the texture buffer (normal_map.glsl:
    /// kind, its texture's header, a bump map's scale).
    pub normal_map: u32,
    /// A rough surface's microfacet roughness along the tangent and the bitangent, and its
    /// `MICROFACET_*` distribution; zero for other surfaces.
    pub alpha_u: f32,
    pub alpha_v: f32,
    pub distribution: u32,
    /// A rough plastic's coat: 1 + the texel of its transmittance table in the texture buffer (64 values,
    /// four a texel); 0 for every other surface.
    pub table: u32,
    /// Mitsuba's `mask`: 0 opaque; else 1 + the texel of its opacity texture's header.
    pub opacity: u32,
    /// 0: none; else 1 + the texel of the header of the texture on `specular_reflectance`.
    pub specular_texture: u32,
    /// 0: none; else 1 + the texel of the header of the texture on a rough surface's `alpha`.
    pub alpha_texture: u32,
    /// 0: none; else 1 + the texel of the header of the texture on an area light's `radiance`.
    pub emission_texture: u32,
}
gpu_struct!(Material {
    color,
    surface,
    emission,
    ior,
    lobe_a,
    texture,
    lobe_b,
    normal_map,
    alpha_u,
    alpha_v,
    distribution,
    table,
    opacity,
    specular_texture,
    alpha_texture,
    emission_texture
});

/// Texels of a texture's header, before a bitmap's pixels.
pub use crate::reflected::constants::TEXTURE_HEADER;
/// Texels per triangle in the triangles' shading buffer: texture coordinates (two), vertex normals (one).
pub use crate::reflected::constants::TRIANGLE_TEXELS;
/// A texture's kind, filter and wrap mode in its header (texture.glsl).
pub use crate::reflected::constants::{
    FILTER_BILINEAR, FILTER_NEAREST, TEXTURE_BITMAP, TEXTURE_CHECKERBOARD, WRAP_CLAMP, WRAP_MIRROR, WRAP_REPEAT,
};
/// A bump or normal map's kind in its record (normal_map.glsl).
pub use crate::reflected::constants::{NORMAL_MAP_BUMP, NORMAL_MAP_NORMAL};
/// The most a photon may carry at a smooth-shaded surface, in fixed-point units of the gather's sums
/// (2^46, `RenderParams::flux_fixed` per unit of flux: 2^16 times the most any light gives a photon).
/// Veach's correction for shading normals can raise a photon's flux without bound (shading.glsl); the
/// rare photon past this is held at it and counted (`PathCounters::capped`).
pub const FLUX_CAP_FIXED: f64 = 70368744177664.0;

impl Material {
    /// Whether its lobe is a microfacet distribution's (`distribution` then names it): a rough conductor,
    /// rough glass, or a plastic with a rough coat.
    pub fn is_rough(&self) -> bool {
        self.surface == SURFACE_ROUGH_CONDUCTOR
            || self.surface == SURFACE_ROUGH_GLASS
            || (self.surface == SURFACE_PLASTIC && self.table != 0)
    }
}

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
    /// [`QUAD_PARALLELOGRAM`], or [`QUAD_DISK`]: only the ellipse inscribed in it.
    pub shape: u32,
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
    shape,
    w,
    pad1
});

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Light {
    /// Into the quads ([`LIGHT_QUAD`]), the BVH's leaf-ordered triangles ([`LIGHT_TRIANGLE`]) or the spheres
    /// ([`LIGHT_SPHERE`]); an environment map's first texel in the texture texels ([`LIGHT_ENVIRONMENT`]).
    pub index: u32,
    pub cdf: f32,
    pub prob: f32,
    pub kind: u32,
    /// What the light emits: a photon's flux is `power / prob` (but a spot's, `flux`).
    pub power: [f32; 3],
    /// A sphere's radius; the scene's bounding sphere's (directional lights and environments).
    pub radius: f32,
    /// A point's or spot's position; the bounding sphere's centre; a sphere's centre.
    pub origin: [f32; 3],
    pub cos_cutoff: f32,
    /// A spot's axis; the direction a directional light travels; an environment's local +y in the world.
    pub normal: [f32; 3],
    pub cos_beam: f32,
    /// A unit vector perpendicular to `normal` (an environment's local +x); the third axis is
    /// `edge_u x normal` (types.glsl's Emitter: edge_v).
    pub edge_u: [f32; 3],
    pub cutoff: f32,
    /// Radiance, intensity or irradiance (types.glsl's Emitter::value), not yet divided by `prob`; a quad's
    /// or triangle's radiance, never divided (1 where a texture gives it).
    pub value: [f32; 3],
    pub inv_width: f32,
    /// A spot's photon flux before its falloff; a quad with a radiance texture's per unit of radiance,
    /// area pi (zero for the other kinds: power / prob).
    pub flux: [f32; 3],
    /// A quad's or triangle's radiance texture: 0 for none, else 1 + the texel of its header.
    pub texture: u32,
}
gpu_struct!(Light {
    index,
    cdf,
    prob,
    kind,
    power,
    radius,
    origin,
    cos_cutoff,
    normal,
    cos_beam,
    edge_u,
    cutoff,
    value,
    inv_width,
    flux,
    texture
});
/// `Light::kind` (types.glsl).
pub use crate::reflected::constants::{
    LIGHT_DIRECTIONAL, LIGHT_ENVIRONMENT, LIGHT_POINT, LIGHT_QUAD, LIGHT_SPHERE, LIGHT_SPOT, LIGHT_TRIANGLE,
};
/// `Quad::shape` (types.glsl).
pub use crate::reflected::constants::{QUAD_DISK, QUAD_PARALLELOGRAM};

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
    /// 1: direct light by light sampling at the eye paths, the photons leaving no record where they first
    /// land straight from a light; 0: all light through the photons (the paper's estimator).
    pub direct_light: u32,
    /// Rough conductors of at least this roughness hold hit points and photon records, their BRDF
    /// evaluated per photon by the gather ("glossy hit points", rough_conductor.glsl); `f32::MAX`: none.
    pub glossy_alpha: f32,
    /// 1: some mask's opacity is not 0 or 1 throughout, and every ray the kernels trace draws a key from
    /// its path's random stream for the masks' choices (materials/mask.glsl); 0: no ray draws one.
    pub masks: u32,
    /// The lights' power, channels summed (the light table's total): an area light's samples are weighed
    /// by pi Le / light_power per unit area at rough vertices (ray/glossy_light.glsl).
    pub light_power: f32,
    /// `GLOSSY_LIGHT_*`: how eye paths take the light their rough vertices reflect straight from an emitter.
    pub glossy_light: u32,
    /// 1 (SPPM): the hit slots are for the lobe directions an eye path's first rough vertex splits it into,
    /// and glass, panes and plastics take one branch (ray.comp); 0 (PPM): those split while slots last.
    pub rough_split: u32,
    /// Spheres around what casts caustics, which emitted photons are aimed at (photon/targets.glsl): the
    /// first `num_targets` of `targets`, centre and radius each; 0 where none or `target_share` is 0.
    pub num_targets: u32,
    /// The share of an area light's photons aimed at them (`Settings::caustic_photons`).
    pub target_share: f32,
    pub targets: [[f32; 4]; MAX_TARGETS],
}
/// The most spheres photons are aimed at (`RenderParams::targets`; more casting materials share one).
/// types.glsl sizes the array and photon/targets.glsl writes the density's term out once for each.
pub const MAX_TARGETS: usize = 8;
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
    lookup_limit,
    direct_light,
    glossy_alpha,
    masks,
    light_power,
    glossy_light,
    rough_split,
    num_targets,
    target_share,
    targets
});

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct HitPoint {
    pub pos: [f32; 3],
    pub pixel: u32,
    pub normal: [f32; 3],
    /// 0: `weight` holds the BRDF; else 1 + the rough conductor whose BRDF the gather evaluates per photon.
    pub brdf: u32,
    pub weight: [f32; 3],
    /// Where `brdf` != 0: the direction towards the eye, octahedral snorm 2x16.
    pub wo: u32,
}
gpu_struct!(HitPoint {
    pos,
    pixel,
    normal,
    brdf,
    weight,
    wo
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
    /// The curvature statistic D = M - 4 M_half (photons within R against 4x those within R / 2), summed
    /// over passes and scaled as R shrinks (update.comp's adaptive shrink).
    pub curv: f64,
    /// Its variance under Poisson counts, M + 8 M_half, summed and scaled the same way.
    pub curv_var: f64,
}
gpu_struct!(HitStats {
    n,
    r2,
    tau_r,
    tau_g,
    tau_b,
    probe,
    curv,
    curv_var
});

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct PassAccum {
    pub flux_r: i64,
    pub flux_g: i64,
    pub flux_b: i64,
    pub m: u32,
    /// Of the `m` photons, those within R / 2 (the update's curvature statistic).
    pub m_half: u32,
}
gpu_struct!(PassAccum {
    flux_r,
    flux_g,
    flux_b,
    m,
    m_half
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
    /// Photons whose flux reached `FLUX_CAP_FIXED` at a smooth-shaded surface (held there: a loss the
    /// renderer reports). The bench's step-counting build of photon.comp counts intersections here instead.
    pub capped: u32,
}
gpu_struct!(PathCounters {
    photon_paths,
    eye_paths,
    traversal_cut,
    capped
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

/// The photon grid build's dispatches, sized from the batch's records (grid_dispatch.comp).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GridDispatch {
    /// The count's and the split's workgroups: a `VkDispatchIndirectCommand` at [`GridDispatch::CHUNKS_OFFSET`].
    pub chunks: [u32; 3],
    pub pad0: u32,
    /// The placing's workgroups, at [`GridDispatch::RECORDS_OFFSET`].
    pub records: [u32; 3],
    pub pad1: u32,
}
gpu_struct!(GridDispatch {
    chunks,
    pad0,
    records,
    pad1
});

impl GridDispatch {
    pub const CHUNKS_OFFSET: u64 = std::mem::offset_of!(GridDispatch, chunks) as u64;
    pub const RECORDS_OFFSET: u64 = std::mem::offset_of!(GridDispatch, records) as u64;
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
pub use crate::reflected::constants::BVH_EMPTY;
/// `BvhNode::child` of a leaf: this bit, its triangle count less one from [`BVH_COUNT_SHIFT`] and its first
/// triangle below (bvh.glsl's constants of the same names).
pub use crate::reflected::constants::{BVH_COUNT_SHIFT, BVH_FIRST_MASK, BVH_LEAF};

/// A node of the 4-wide BVH the kernels traverse (shaders/common/bvh.glsl), 64 bytes: the boxes of up to
/// four children, quantized to a byte per bound on a power-of-two step per axis, and each child's reference
/// ([`BVH_EMPTY`], an interior node's index, or a leaf, [`BvhNode::leaf`]). crates/engine/src/bvh/widen.rs
/// collapses the binary SAH tree into it; [`BvhNode::new`] quantizes, [`BvhNode::child_boxes`] decodes as
/// the kernels do.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    pub origin_x: f32,
    pub origin_y: f32,
    pub origin_z: f32,
    /// Biased f32 exponents of the three axes' steps: x | y << 8 | z << 16.
    pub exponents: u32,
    /// The children's lower bounds on x in steps above `origin_x`, a byte each (child 0 lowest), then the
    /// upper bounds.
    pub qx: [u32; 2],
    pub qy: [u32; 2],
    pub qz: [u32; 2],
    pub child: [u32; 4],
    /// To 64 bytes: the kernels read a node in two 32-byte loads.
    pub pad: [u32; 2],
}
gpu_struct!(BvhNode {
    origin_x,
    origin_y,
    origin_z,
    exponents,
    qx,
    qy,
    qz,
    child,
    pad
});

impl Default for BvhNode {
    /// A node without children.
    fn default() -> BvhNode {
        BvhNode {
            origin_x: 0.0,
            origin_y: 0.0,
            origin_z: 0.0,
            exponents: 0,
            qx: [0; 2],
            qy: [0; 2],
            qz: [0; 2],
            child: [BVH_EMPTY; 4],
            pad: [0; 2],
        }
    }
}

/// A bound decoded as bvh.glsl's `bvh_axis` computes it: origin + q 2^(exponent - 127), in f32.
fn decode(origin: f32, exponent: u32, q: u32) -> f32 {
    origin + q as f32 * f32::from_bits(exponent << 23)
}

/// One axis of a node: the exponent and the bytes of its children's bounds, each lower bound decoding to
/// at most the true one and each upper bound to at least it, checked as the kernels decode them.
fn quantize_axis(origin: f32, top: f32, bounds: impl Iterator<Item = (f32, f32)> + Clone) -> (u32, [u32; 2]) {
    // The smallest step that spans the node in 255 steps (f32 exponents 1..=254: normal, no overflow),
    // from the extent's own exponent: 2^e >= extent / 255.
    let extent = top as f64 - origin as f64;
    let mut exponent = if extent > 0.0 {
        let need = extent / 255.0;
        let e = ((need.to_bits() >> 52) & 0x7ff) as i32 - 1023; // floor(log2(need))
        let e = if need > f64::from_bits(((e + 1023) as u64) << 52) {
            e + 1
        } else {
            e
        };
        (e + 127).clamp(1, 254) as u32
    } else {
        1
    };
    'grow: loop {
        let step = f32::from_bits(exponent << 23) as f64;
        let mut q = [0u32; 2];
        for (k, (lo, hi)) in bounds.clone().enumerate() {
            let mut l = (((lo as f64 - origin as f64) / step).floor().max(0.0) as u32).min(255);
            while l > 0 && decode(origin, exponent, l) > lo {
                l -= 1;
            }
            let mut h = (((hi as f64 - origin as f64) / step).ceil().max(0.0) as u32).clamp(l, 255);
            while decode(origin, exponent, h) < hi {
                if h == 255 {
                    exponent += 1;
                    continue 'grow;
                }
                h += 1;
            }
            q[0] |= l << (8 * k);
            q[1] |= h << (8 * k);
        }
        return (exponent, q);
    }
}

impl BvhNode {
    /// The node of up to four children, each its box (lo, hi) and its reference; their boxes quantized
    /// so that each decoded box holds the given one.
    pub fn new(children: &[([f32; 3], [f32; 3], u32)]) -> BvhNode {
        assert!(children.len() <= 4, "a BVH node has at most four children");
        let mut n = BvhNode::default();
        if children.is_empty() {
            return n;
        }
        let mut origin = [f32::INFINITY; 3];
        let mut top = [f32::NEG_INFINITY; 3];
        for (lo, hi, _) in children {
            for a in 0..3 {
                origin[a] = origin[a].min(lo[a]);
                top[a] = top[a].max(hi[a]);
            }
        }
        (n.origin_x, n.origin_y, n.origin_z) = (origin[0], origin[1], origin[2]);
        let mut q = [[0u32; 2]; 3];
        for a in 0..3 {
            let bounds = children.iter().map(|(lo, hi, _)| (lo[a], hi[a]));
            let (e, qa) = quantize_axis(origin[a], top[a], bounds);
            n.exponents |= e << (8 * a);
            q[a] = qa;
        }
        (n.qx, n.qy, n.qz) = (q[0], q[1], q[2]);
        for (k, c) in children.iter().enumerate() {
            n.child[k] = c.2;
        }
        n
    }

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

    /// The children's boxes (lo, hi) as the kernels decode them (bvh.glsl's `bvh_axis`); an empty slot's
    /// is meaningless.
    pub fn child_boxes(&self) -> [([f32; 3], [f32; 3]); 4] {
        let origin = [self.origin_x, self.origin_y, self.origin_z];
        let q = [self.qx, self.qy, self.qz];
        let mut out = [([0f32; 3], [0f32; 3]); 4];
        for (k, b) in out.iter_mut().enumerate() {
            for a in 0..3 {
                let e = self.exponents >> (8 * a) & 0xff;
                b.0[a] = decode(origin[a], e, q[a][0] >> (8 * k) & 0xff);
                b.1[a] = decode(origin[a], e, q[a][1] >> (8 * k) & 0xff);
            }
        }
        out
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

impl Triangle {
    /// A triangle of material 0 and source 0 through three vertices (the tests' shapes).
    pub fn through(v0: [f32; 3], v1: [f32; 3], v2: [f32; 3]) -> Triangle {
        Triangle {
            v0,
            v1,
            v2,
            ..Triangle::default()
        }
    }
}

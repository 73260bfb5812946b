//! The scene as the kernels see it: flat records (crates/kernels/src/layout.rs) and the per-render
//! constants. Both the GPU renderer and the CPU reference start from this one conversion ("lowering"):
//! [`GpuScene::new`] calls `textures.rs` (texture and triangle texels), `materials.rs` (the material
//! table), the BVH builder, `lights.rs` (the light table and the flux sums' fixed-point scale) and
//! `grid.rs` (starting radius, grid cell and buckets) in turn.

use glam::Vec3;
use ppm_vk_kernels::layout::{
    self, BvhNode, Light, Material, Quad, RenderParams, Sphere, Triangle, GLOSSY_LIGHT_BSDF, GLOSSY_LIGHT_LIGHTS,
    GLOSSY_LIGHT_MIS, QUAD_DISK, QUAD_PARALLELOGRAM,
};
use ppm_vk_kernels::specialize::MAX_INLINE_PRIMITIVES;

use crate::bvh::{self, Bvh, BvhOptions, BvhStats, TriangleInput};
use crate::error::{Error, Result};
use crate::scene::Scene;
use crate::settings::{GlossyLight, Settings};

mod grid;
mod lights;
mod materials;
mod targets;
mod textures;

pub use grid::{default_radius, grid_buckets, CELL_PER_RADIUS};
pub use textures::texture_texels;

/// Flattened scene plus the constants of one render.
#[derive(Clone, Debug)]
pub struct GpuScene {
    pub params: RenderParams,
    pub materials: Vec<Material>,
    pub spheres: Vec<Sphere>,
    pub quads: Vec<Quad>,
    pub lights: Vec<Light>,
    /// The triangles of all meshes in a BVH: one empty leaf and no triangles without meshes.
    pub bvh_nodes: Vec<BvhNode>,
    pub bvh_triangles: Vec<Triangle>,
    pub bvh_stats: BvhStats,
    /// The textures as texels (texture.glsl): one zeroed texel without textures.
    pub textures: Vec<[u32; 4]>,
    /// What shading reads of `bvh_triangles`, `layout::TRIANGLE_TEXELS` texels each (texture.glsl,
    /// shading.glsl, geometry.glsl's surface_tangent): texture coordinates (u0 v0 u1 v1 | u2 v2, f32 bits)
    /// with dp/du from them (octahedral, then 1; 0 0 where the mesh has none or they are degenerate),
    /// then the vertex normals (octahedral n0 n1 n2, and 1 for a smooth triangle, 0 for a flat one); one
    /// zeroed texel where no mesh has texture coordinates or vertex normals and no surface is anisotropic.
    pub triangle_texels: Vec<[u32; 4]>,
    /// The kernels test `bvh_triangles` one by one, written into them as constants (a small mesh:
    /// `specialize::MAX_INLINE_TRIANGLES`), and never traverse the BVH.
    pub triangles_inline: bool,
    /// Where `triangles_inline`: those of them that pair into parallelograms, each pair tested as one, and
    /// the rest (ppm_vk_kernels::inline_pairs); else empty.
    pub inline_pairs: Vec<ppm_vk_kernels::inline_pairs::InlinePair>,
    pub inline_singles: Vec<u32>,
    /// The starting search radius of every hit point (eq. 8, or the setting).
    pub initial_radius: f32,
    /// Total emitted power of all lights, per channel (W, un-normalised photon flux sums to this).
    pub total_power: [f64; 3],
    /// The kinds of light the scene has, as bits `1 << LIGHT_*` (specialize.rs leaves the others' code out).
    pub light_kinds: u32,
    /// Whether light 0 is an environment (lights.glsl's first_emitter).
    pub has_environment: bool,
    /// Lower corner of the scene's bounds.
    pub lo: [f32; 3],
    /// Area of all surfaces (photons land only on them): sizes the grid's hash table.
    pub surface_area: f64,
    /// The photon grid's bucket count set by `Settings::grid_buckets`; `None`: sized from the cell.
    pub fixed_buckets: Option<u32>,
}

/// Writes the camera's basis and image size into `params` (ray.comp's camera_ray reads them).
pub fn set_camera(params: &mut RenderParams, cam: &crate::scene::Camera) {
    let forward = (cam.look_at - cam.eye).normalize();
    let right = forward.cross(cam.up).normalize();
    let up = right.cross(forward);
    params.eye = cam.eye.to_array();
    params.tan_half_fov = (cam.vfov_deg.to_radians() * 0.5).tan();
    params.right = right.to_array();
    params.aspect = cam.width as f32 / cam.height as f32;
    params.up = up.to_array();
    params.width = cam.width;
    params.forward = forward.to_array();
    params.height = cam.height;
}

impl GpuScene {
    /// `photon_capacity` sizes the photon batch buffers (see `Renderer`).
    pub fn new(scene: &Scene, settings: &Settings, photon_capacity: u32) -> Result<GpuScene> {
        let (mut textures, texture_at) = texture_texels(&scene.textures);
        let materials = materials::materials(scene, &texture_at, &mut textures);
        let spheres = spheres(scene);
        let quads = quads(scene);
        let built = triangles(scene)?;
        let triangle_texels = textures::triangle_texels(scene, &built.triangles);
        let table = lights::lights(scene, &built.triangles, &triangle_texels, &texture_at, &mut textures)?;
        let glossy_alpha = settings.glossy_hits.unwrap_or(f32::MAX);
        // Photons aimed at what casts caustics (targets.rs) leave with up to 1 / (1 - share) of their
        // light's flux (photon/targets.glsl).
        let aim = match settings.caustic_photons {
            s if s > 0.0 => targets::targets(&materials, &spheres, &quads, &built.triangles, glossy_alpha),
            _ => Vec::new(),
        };
        let share = if aim.is_empty() { 0.0 } else { settings.caustic_photons };
        let flux_fixed = lights::flux_fixed(scene, table.max_flux / (1.0 - share as f64))?;
        let (lights, total_power, light_kinds) = (table.lights, table.total_power, table.kinds);
        let (lo, hi) = scene.bounds();
        let extent = (hi - lo).max_element();
        let initial_radius = grid::initial_radius(scene, settings)?;
        let cell_size = grid::cell_size(settings, initial_radius)?;
        let surface_area = grid::surface_area(scene);
        let mut params = RenderParams {
            num_spheres: spheres.len() as u32,
            num_quads: quads.len() as u32,
            num_lights: lights.len() as u32,
            num_triangles: built.triangles.len() as u32,
            photon_bvh_budget: u32::MAX,
            eye_bvh_budget: u32::MAX,
            // Ray offsets (offset_ray in geometry.glsl): 2^-14 of the point's largest coordinate, ~512 f32
            // ulps, plus 1e-7 of the scene's size for points near the origin. Both scale with the scene.
            // Measured: smaller offsets let eye paths split at glass re-hit the surface they left (2^-16:
            // speckles at the glass sphere's silhouette, caustic-box relMSE 0.0097 against 0.0017; 2^-18:
            // GPU and CPU paths split on 8 of 4096 pixels). The cost: 6 cm offsets 1 km from the origin,
            // where a 2 m furnace comes out 3.9% bright.
            eps: 1e-7 * extent,
            eps_rel: 1.0 / 16384.0,
            max_photon_depth: settings.max_photon_depth,
            max_eye_depth: settings.max_eye_depth,
            hit_slots: settings.slots(scene),
            rough_split: settings.splits_rough(scene) as u32,
            photon_capacity,
            seed: settings.seed,
            flux_fixed,
            direct_light: (settings.direct == crate::settings::DirectLight::Sample) as u32,
            glossy_alpha,
            masks: draws_mask_keys(scene) as u32,
            light_power: total_power.iter().sum::<f64>() as f32,
            glossy_light: match settings.glossy_light {
                GlossyLight::Mis => GLOSSY_LIGHT_MIS,
                GlossyLight::Bsdf => GLOSSY_LIGHT_BSDF,
                GlossyLight::Lights => GLOSSY_LIGHT_LIGHTS,
            },
            num_targets: aim.len() as u32,
            target_share: share,
            ..Default::default()
        };
        params.targets[..aim.len()].copy_from_slice(&aim);
        set_camera(&mut params, &scene.camera);
        // Small meshes are compiled into the tracing kernels with the spheres and quads (specialize.rs).
        let triangles_inline = settings.specialize
            && !built.triangles.is_empty()
            && built.triangles.len() <= settings.max_inline_triangles as usize
            && spheres.len() + quads.len() <= MAX_INLINE_PRIMITIVES;
        let (inline_pairs, inline_singles) = match triangles_inline {
            true => ppm_vk_kernels::inline_pairs::pairs(&built.triangles),
            false => (Vec::new(), Vec::new()),
        };
        let mut g = GpuScene {
            textures,
            triangle_texels,
            triangles_inline,
            inline_pairs,
            inline_singles,
            params,
            materials,
            spheres,
            quads,
            lights,
            bvh_nodes: built.wide,
            bvh_triangles: built.triangles,
            bvh_stats: built.stats,
            initial_radius,
            total_power,
            light_kinds,
            has_environment: light_kinds & (1 << layout::LIGHT_ENVIRONMENT) != 0,
            lo: lo.to_array(),
            surface_area,
            fixed_buckets: settings.grid_buckets,
        };
        g.set_grid_cell(cell_size, photon_capacity);
        Ok(g)
    }

    /// Sets the photon grid's cell size (and with it the grid's origin and the hash
    /// table's buckets, `params.grid_mask + 1`). Lookups read at most 3x3x3 cells where the cells are
    /// [`CELL_PER_RADIUS`] times the largest search radius; any size gives the same photons.
    pub fn set_grid_cell(&mut self, cell_size: f32, photon_capacity: u32) {
        self.params.cell_size = cell_size;
        self.params.grid_min = (Vec3::from(self.lo) - Vec3::splat(cell_size)).to_array();
        let buckets = self
            .fixed_buckets
            .unwrap_or_else(|| grid_buckets(self.surface_area, cell_size, photon_capacity));
        self.params.grid_mask = buckets - 1;
    }

    /// The most buckets the grid's table can be given (all cell sizes): allocated once, so memory never
    /// grows with the passes as the cells shrink and want more buckets (`grid_buckets`).
    pub fn max_buckets(&self) -> u32 {
        self.fixed_buckets
            .unwrap_or_else(|| grid_buckets(f64::INFINITY, 1.0, self.params.photon_capacity))
    }

    /// Whether the tracing kernels traverse the BVH (the scene has triangles, not written out).
    pub fn traverses_bvh(&self) -> bool {
        self.params.num_triangles > 0 && !self.triangles_inline
    }

    /// Whether any triangle is smooth-shaded (has vertex normals): the kernels then read shading normals
    /// and weigh photons by Veach's correction (shading.glsl).
    pub fn smooth_shading(&self) -> bool {
        let stride = layout::TRIANGLE_TEXELS as usize;
        self.triangle_texels.len() >= stride && self.triangle_texels.chunks_exact(stride).any(|t| t[2][3] != 0)
    }

    /// Device bytes of the BVH's nodes and triangles.
    pub fn bvh_bytes(&self) -> usize {
        self.bvh_nodes.len() * std::mem::size_of::<BvhNode>()
            + self.bvh_triangles.len() * std::mem::size_of::<Triangle>()
    }

    pub fn pixels(&self) -> u32 {
        self.params.width * self.params.height
    }

    pub fn slots(&self) -> u32 {
        self.pixels() * self.params.hit_slots
    }
}

fn spheres(scene: &Scene) -> Vec<Sphere> {
    scene
        .spheres
        .iter()
        .map(|s| Sphere {
            center: s.center.to_array(),
            radius: s.radius,
            material: s.material,
            ..Default::default()
        })
        .collect()
}

fn quads(scene: &Scene) -> Vec<Quad> {
    scene
        .quads
        .iter()
        .map(|q| {
            let c = q.edge_u.cross(q.edge_v);
            let n = c.normalize();
            Quad {
                origin: q.origin.to_array(),
                material: q.material,
                edge_u: q.edge_u.to_array(),
                area: q.area(),
                shape: if q.disk { QUAD_DISK } else { QUAD_PARALLELOGRAM },
                edge_v: q.edge_v.to_array(),
                plane_d: n.dot(q.origin),
                normal: n.to_array(),
                w: (c / c.dot(c)).to_array(),
                ..Default::default()
            }
        })
        .collect()
}

/// Triangles: every mesh's, in one BVH (the meshes are already in world space).
fn triangles(scene: &Scene) -> Result<Bvh> {
    let input = TriangleInput::of_scene(scene);
    let built = bvh::build(&input, &BvhOptions::default())
        .map_err(|e| Error::scene(&scene.name, 0, 0, "", format!("building the BVH: {e:#}")))?;
    if !built.dropped.is_empty() {
        // Scene validation drops degenerate triangles first, so this is a NaN or an area that rounds to 0.
        return Err(Error::scene(
            &scene.name,
            0,
            0,
            "",
            format!(
                "{} triangles are degenerate (zero area or not finite), e.g. input triangle {}",
                built.dropped.len(),
                built.dropped[0]
            ),
        ));
    }
    Ok(built)
}

/// Whether the kernels' rays must draw mask keys (materials/mask.glsl): some masked material's opacity is
/// not decided by its value alone. An opacity of exactly 0 everywhere (a `null` bsdf, a mask of 0: every
/// ray passes) or a constant of at least 1 (every ray stops) decides without a random number, so such a
/// scene draws the same numbers as the scene without the surface (opacity 0) or without the mask
/// (opacity 1): its image is theirs bit for bit. A bitmap of ones is not taken as decided: its bilinear
/// interpolation may round just below 1.
fn draws_mask_keys(scene: &Scene) -> bool {
    use crate::scene::texture::Pattern;
    let decided = |t: &crate::scene::texture::Texture| {
        let y = |c: glam::Vec3| ppm_vk_materials::mask::luminance(c).clamp(0.0, 1.0);
        match &t.pattern {
            Pattern::Checkerboard { color0, color1 } => {
                let (a, b) = (y(*color0), y(*color1));
                (a == 0.0 && b == 0.0) || (a == 1.0 && b == 1.0)
            }
            Pattern::Bitmap { pixels, .. } => pixels.iter().all(|&p| y(p) == 0.0),
        }
    };
    scene
        .materials
        .iter()
        .filter_map(|m| m.opacity)
        .any(|t| !decided(&scene.textures[t as usize]))
}

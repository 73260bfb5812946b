//! The scene as the kernels see it: flat records (crates/kernels/src/layout.rs) and the per-render
//! constants. Both the GPU renderer and the CPU reference start from this one conversion.

use glam::Vec3;
use ppm_vk_kernels::layout::{
    self, BvhNode, Light, Material, Quad, RenderParams, Sphere, Triangle, LIGHT_QUAD, LIGHT_TRIANGLE,
};
use ppm_vk_kernels::lookup::SCAN_BLOCK;
use ppm_vk_kernels::specialize::MAX_INLINE_PRIMITIVES;
use ppm_vk_materials::plastic;

use crate::bvh::{self, BvhOptions, BvhStats, TriangleInput};
use crate::error::{Error, Result};
use crate::scene::{Scene, Surface};
use crate::settings::Settings;

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
    /// The starting search radius of every hit point (eq. 8, or the setting).
    pub initial_radius: f32,
    /// Total emitted power of all lights, per channel (W, un-normalised photon flux sums to this).
    pub total_power: [f64; 3],
    /// Lower corner of the scene's bounds.
    pub lo: [f32; 3],
    /// Area of all surfaces (photons land only on them): sizes the grid's hash table.
    pub surface_area: f64,
    /// The photon grid's bucket count set by `Settings::grid_buckets`; `None`: sized from the cell.
    pub fixed_buckets: Option<u32>,
}

fn arr(v: Vec3) -> [f32; 3] {
    v.to_array()
}

/// Writes the camera's basis and image size into `params` (ray.comp's camera_ray reads them).
pub fn set_camera(params: &mut RenderParams, cam: &crate::scene::Camera) {
    let forward = (cam.look_at - cam.eye).normalize();
    let right = forward.cross(cam.up).normalize();
    let up = right.cross(forward);
    params.eye = arr(cam.eye);
    params.tan_half_fov = (cam.vfov_deg.to_radians() * 0.5).tan();
    params.right = arr(right);
    params.aspect = cam.width as f32 / cam.height as f32;
    params.up = arr(up);
    params.width = cam.width;
    params.forward = arr(forward);
    params.height = cam.height;
}

/// `textures` as texels (texture.glsl's layout) and the texel of each one's header.
pub fn texture_texels(textures: &[crate::scene::texture::Texture]) -> (Vec<[u32; 4]>, Vec<u32>) {
    use crate::scene::texture::{Filter, Pattern, Wrap};
    let bits = |v: Vec3| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits(), 0];
    let mut texels = Vec::new();
    let mut at = Vec::new();
    for t in textures {
        let h = texels.len() as u32;
        at.push(h);
        let filter = match t.filter {
            Filter::Bilinear => layout::FILTER_BILINEAR,
            Filter::Nearest => layout::FILTER_NEAREST,
        };
        let wrap = match t.wrap {
            Wrap::Repeat => layout::WRAP_REPEAT,
            Wrap::Mirror => layout::WRAP_MIRROR,
            Wrap::Clamp => layout::WRAP_CLAMP,
        };
        let m = t.to_uv;
        let rows = [bits(Vec3::new(m[0], m[1], m[2])), bits(Vec3::new(m[3], m[4], m[5]))];
        match &t.pattern {
            Pattern::Bitmap { width, height, pixels } => {
                let first = h + layout::TEXTURE_HEADER;
                texels.push([layout::TEXTURE_BITMAP | filter << 4 | wrap << 8, *width, *height, first]);
                texels.extend(rows);
                texels.extend([[0; 4], [0; 4]]);
                texels.extend(pixels.iter().map(|p| bits(*p)));
            }
            Pattern::Checkerboard { color0, color1 } => {
                texels.push([layout::TEXTURE_CHECKERBOARD | filter << 4 | wrap << 8, 0, 0, 0]);
                texels.extend(rows);
                texels.extend([bits(*color0), bits(*color1)]);
            }
        }
    }
    if texels.is_empty() {
        texels.push([0; 4]);
    }
    (texels, at)
}

/// The shading attributes of `triangles` (leaf order; `source` indexes the scene's triangles in mesh
/// order), `layout::TRIANGLE_TEXELS` texels each: texture coordinates and dp/du where a mesh has them
/// (zero where not), and vertex normals where it has them (flagged flat where not); one zeroed texel if no
/// mesh has either and no surface is anisotropic (which reads the dp/du flag of every triangle).
fn triangle_texels(scene: &Scene, triangles: &[Triangle]) -> Vec<[u32; 4]> {
    let anisotropic = scene
        .materials
        .iter()
        .any(|m| m.surface.rough().is_some_and(|r| r.is_anisotropic()));
    let triangles_read = scene.meshes.iter().any(|m| m.uvs.is_some() || m.normals.is_some()) || anisotropic;
    if triangles.is_empty() || !triangles_read {
        return vec![[0; 4]];
    }
    // Per triangle of the scene: texture coordinates, dp/du from them, vertex normals.
    type Attributes = ([glam::Vec2; 3], Option<Vec3>, Option<[Vec3; 3]>);
    let by_source: Vec<Attributes> = scene
        .meshes
        .iter()
        .flat_map(|m| {
            m.indices.iter().map(move |t| {
                let uv = m.uvs.as_ref().map(|uv| t.map(|i| uv[i as usize]));
                let dpdu = uv.and_then(|uv| dp_du(t.map(|i| m.positions[i as usize]), uv));
                let normals = m.normals.as_ref().map(|n| t.map(|i| n[i as usize]));
                (uv.unwrap_or([glam::Vec2::ZERO; 3]), dpdu, normals)
            })
        })
        .collect();
    let bits = |x: f32| x.to_bits();
    let oct = ppm_vk_materials::math::oct_encode;
    triangles
        .iter()
        .flat_map(|t| {
            let ([a, b, c], dpdu, normals) = by_source[t.source as usize];
            let n = match normals {
                Some(n) => [oct(n[0]), oct(n[1]), oct(n[2]), 1],
                None => [0; 4],
            };
            let (tangent, has) = dpdu.map_or((0, 0), |d| (oct(d), 1));
            [
                [bits(a.x), bits(a.y), bits(b.x), bits(b.y)],
                [bits(c.x), bits(c.y), tangent, has],
                n,
            ]
        })
        .collect()
}

/// Mitsuba's dp/du of a triangle with corners `p` and texture coordinates `uv` (its Mesh's
/// compute_surface_interaction), as a unit vector; None where the coordinates are degenerate
/// (geometry.glsl's surface_tangent then takes the triangle's first edge, as without coordinates).
fn dp_du(p: [Vec3; 3], uv: [glam::Vec2; 3]) -> Option<Vec3> {
    let (duv0, duv1) = ((uv[1] - uv[0]).as_dvec2(), (uv[2] - uv[0]).as_dvec2());
    let (dp0, dp1) = ((p[1] - p[0]).as_dvec3(), (p[2] - p[0]).as_dvec3());
    let det = duv0.x * duv1.y - duv0.y * duv1.x;
    let d = (duv1.y * dp0 - duv0.y * dp1) / det;
    (det != 0.0)
        .then_some(d)
        .and_then(|d| d.try_normalize())
        .map(|d| d.as_vec3())
}

/// Eq. 8: r = 2 (X + Y + Z) / (3 s), X, Y, Z the extents of the scene's bounding box, s the image size
/// along one axis (the width).
pub fn default_radius(scene: &Scene) -> f32 {
    let (lo, hi) = scene.bounds();
    let e = hi - lo;
    2.0 * (e.x + e.y + e.z) / (3.0 * scene.camera.width as f32)
}

impl GpuScene {
    /// `photon_capacity` sizes the photon batch buffers (see `Renderer`).
    pub fn new(scene: &Scene, settings: &Settings, photon_capacity: u32) -> Result<GpuScene> {
        let (mut textures, texture_at) = texture_texels(&scene.textures);
        let materials: Vec<Material> = scene
            .materials
            .iter()
            .map(|m| {
                // A plastic's coat (scene/plastic.rs): a rough one's transmittance table goes after the
                // textures, four values a texel (plastic.glsl's coat_transmittance reads it).
                let coat = match m.surface {
                    Surface::Plastic { ior, rough, .. } => Some(plastic::coat(ior, rough)),
                    _ => None,
                };
                let table = match coat.as_ref().and_then(|c| c.table.as_ref()) {
                    Some(t) => {
                        let at = textures.len() as u32 + 1;
                        textures.extend(t.chunks(4).map(|c| {
                            let mut texel = [0u32; 4];
                            for (k, v) in c.iter().enumerate() {
                                texel[k] = v.to_bits();
                            }
                            texel
                        }));
                        at
                    }
                    None => 0,
                };
                let (color, surface, ior) = match m.surface {
                    Surface::Diffuse { albedo } => (albedo, layout::SURFACE_DIFFUSE, 1.0),
                    Surface::Mirror { reflectance } => (reflectance, layout::SURFACE_MIRROR, 1.0),
                    Surface::Conductor { reflectance, .. } => (reflectance, layout::SURFACE_CONDUCTOR, 1.0),
                    Surface::Glass { ior } => (Vec3::ONE, layout::SURFACE_GLASS, ior),
                    Surface::Plastic {
                        diffuse,
                        ior,
                        nonlinear,
                        ..
                    } => (
                        plastic::diffuse_factor(diffuse, ior, nonlinear, coat.as_ref().expect("a coat").internal),
                        layout::SURFACE_PLASTIC,
                        ior,
                    ),
                    Surface::ThinDielectric { ior, reflectance, .. } => (reflectance, layout::SURFACE_THIN, ior),
                    Surface::RoughConductor { reflectance, .. } => (reflectance, layout::SURFACE_ROUGH_CONDUCTOR, 1.0),
                    Surface::RoughGlass { ior, .. } => (Vec3::ONE, layout::SURFACE_ROUGH_GLASS, ior),
                };
                let rough = match m.surface {
                    Surface::RoughConductor { rough, .. } | Surface::RoughGlass { rough, .. } => Some(rough),
                    Surface::Plastic { rough, .. } => rough,
                    _ => None,
                };
                let (lobe_a, lobe_b) = match m.surface {
                    Surface::Conductor { eta, k, .. } | Surface::RoughConductor { eta, k, .. } => (arr(eta), arr(k)),
                    Surface::Plastic {
                        diffuse,
                        specular,
                        ior,
                        nonlinear,
                        ..
                    } => {
                        let coat = coat.as_ref().expect("a coat");
                        (
                            arr(specular),
                            [
                                plastic::diffuse_bound(diffuse, ior, nonlinear, coat),
                                coat.internal,
                                nonlinear as u32 as f32,
                            ],
                        )
                    }
                    Surface::ThinDielectric { transmittance, .. } => (arr(transmittance), [0.0; 3]),
                    _ => ([0.0; 3], [0.0; 3]),
                };
                Material {
                    color: arr(color),
                    surface,
                    emission: arr(m.emission),
                    ior,
                    lobe_a,
                    lobe_b,
                    texture: m.texture.map_or(0, |t| texture_at[t as usize] + 1),
                    alpha_u: rough.map_or(0.0, |r| r.alpha),
                    alpha_v: rough.map_or(0.0, |r| r.alpha_v),
                    distribution: rough.map_or(0, |r| match r.ggx {
                        true => layout::MICROFACET_GGX,
                        false => layout::MICROFACET_BECKMANN,
                    }),
                    table,
                    ..Default::default()
                }
            })
            .collect();
        let spheres: Vec<Sphere> = scene
            .spheres
            .iter()
            .map(|s| Sphere {
                center: arr(s.center),
                radius: s.radius,
                material: s.material,
                ..Default::default()
            })
            .collect();
        let quads: Vec<Quad> = scene
            .quads
            .iter()
            .map(|q| {
                let c = q.edge_u.cross(q.edge_v);
                let n = c.normalize();
                Quad {
                    origin: arr(q.origin),
                    material: q.material,
                    edge_u: arr(q.edge_u),
                    area: c.length(),
                    edge_v: arr(q.edge_v),
                    plane_d: n.dot(q.origin),
                    normal: arr(n),
                    w: arr(c / c.dot(c)),
                    ..Default::default()
                }
            })
            .collect();

        // Triangles: every mesh's, in one BVH (the meshes are already in world space).
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

        // Lights: emitting quads and triangles, chosen in proportion to their power (summed over RGB).
        // A Lambertian emitter of radiance L and area A emits L A pi.
        let mut lights = Vec::new();
        let mut total_power = [0f64; 3];
        let mut add = |index: u32, kind: u32, emission: Vec3, area: f32| {
            let power = emission * area * std::f32::consts::PI;
            for c in 0..3 {
                total_power[c] += power[c] as f64;
            }
            lights.push(Light {
                index,
                kind,
                power: arr(power),
                ..Default::default()
            });
        };
        for qi in scene.lights() {
            let q = &scene.quads[qi as usize];
            add(qi, LIGHT_QUAD, scene.materials[q.material as usize].emission, q.area());
        }
        for (ti, t) in built.triangles.iter().enumerate() {
            let e = scene.materials[t.material as usize].emission;
            if e.max_element() > 0.0 {
                let (v0, v1, v2) = (Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2));
                add(ti as u32, LIGHT_TRIANGLE, e, 0.5 * (v1 - v0).cross(v2 - v0).length());
            }
        }
        let sum: f64 = lights
            .iter()
            .map(|l| l.power.iter().map(|&p| p as f64).sum::<f64>())
            .sum();
        if lights.is_empty() || sum <= 0.0 {
            return Err(Error::scene(&scene.name, 0, 0, "", "no light emits power"));
        }
        let mut run = 0f64;
        for l in &mut lights {
            run += l.power.iter().map(|&p| p as f64).sum::<f64>() / sum;
            l.cdf = run as f32;
        }
        if let Some(last) = lights.last_mut() {
            last.cdf = 1.0; // no photon may fall past the last light through rounding
        }
        // Each light's probability is the share of [0, 1) its f32 cdf gives it, so that power / prob stays
        // unbiased where 100k lights make the rounding of the running sum matter.
        let mut previous = 0f64;
        for l in &mut lights {
            l.prob = (l.cdf as f64 - previous) as f32;
            previous = l.cdf as f64;
        }
        if let Some(i) = lights.iter().position(|l| l.prob.is_nan() || l.prob <= 0.0) {
            let message = format!(
                "light {i} of {} has too small a share of the total power to be chosen in an f32 light table \
                 (split the scene's lights more evenly)",
                lights.len()
            );
            return Err(Error::scene(&scene.name, 0, 0, "", message));
        }

        // No photon carries more flux than it leaves its light with (roulette divides by the largest
        // albedo, mirrors, glass and thin panes never amplify, a plastic's branches weigh at most 1:
        // plastic.glsl), so this bounds one photon's share of a fixed-point sum.
        let max_flux = lights
            .iter()
            .flat_map(|l| l.power.map(|p| p as f64 / l.prob as f64))
            .fold(0f64, f64::max);
        let flux_fixed = 2f64.powi((2f64.powi(30) / max_flux).log2().floor() as i32) as f32;
        if !(flux_fixed.is_finite() && flux_fixed > 0.0) {
            return Err(Error::scene(
                &scene.name,
                0,
                0,
                "",
                format!("light power {max_flux} W is out of the representable range"),
            ));
        }
        let (lo, hi) = scene.bounds();
        let extent = (hi - lo).max_element();
        let initial_radius = settings.initial_radius.unwrap_or_else(|| default_radius(scene));
        if !(initial_radius.is_finite() && initial_radius > 0.0) {
            return Err(Error::Settings {
                field: "initial_radius",
                message: format!("must be positive and finite, got {initial_radius}"),
            });
        }
        // Cells of CELL_PER_RADIUS starting radii. The probe may enlarge radii; the renderer then sizes
        // the cells for the largest (Renderer::fit_grid).
        let cell_size = CELL_PER_RADIUS * initial_radius;
        // A lookup window must stay under 1024 cells a side (grid_key in grid.glsl).
        let cell_size = match settings.grid_cell {
            Some(c) if !(c.is_finite() && c > 0.0 && c * 256.0 >= cell_size) => {
                return Err(Error::Settings {
                    field: "grid_cell",
                    message: format!("{c} must be positive and at least 1/256 of {cell_size} (the starting cell)"),
                })
            }
            Some(c) => c,
            None => cell_size,
        };
        let surface_area = scene_surface_area(scene);
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
            hit_slots: settings.slots(),
            photon_capacity,
            seed: settings.seed,
            flux_fixed,
            direct_light: (settings.direct == crate::settings::DirectLight::Sample) as u32,
            glossy_alpha: settings.glossy_hits.unwrap_or(f32::MAX),
            ..Default::default()
        };
        set_camera(&mut params, &scene.camera);
        // Small meshes are compiled into the tracing kernels with the spheres and quads (specialize.rs).
        let triangles_inline = settings.specialize
            && !built.triangles.is_empty()
            && built.triangles.len() <= settings.max_inline_triangles as usize
            && spheres.len() + quads.len() <= MAX_INLINE_PRIMITIVES;
        let triangle_texels = triangle_texels(scene, &built.triangles);
        let mut g = GpuScene {
            textures,
            triangle_texels,
            triangles_inline,
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
            lo: arr(lo),
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
        self.params.grid_min = arr(Vec3::from(self.lo) - Vec3::splat(cell_size));
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

fn scene_surface_area(scene: &Scene) -> f64 {
    scene.quads.iter().map(|q| q.area() as f64).sum::<f64>()
        + scene
            .spheres
            .iter()
            .map(|s| 4.0 * std::f64::consts::PI * (s.radius as f64).powi(2))
            .sum::<f64>()
        + scene
            .meshes
            .iter()
            .flat_map(|m| m.triangles())
            .map(|t| t.area() as f64)
            .sum::<f64>()
}

/// A photon-grid cell's edge in search radii (of the largest radius live in the pass). The trade: smaller
/// cells read fewer photons outside each sphere (a lookup spans 2-3 cells a side, against 2 at twice the
/// radius) but want a larger hash table, which the grid build's scattered writes pay for. Measured on
/// lavapipe (docs/performance.md, "Issue 14, second session"): 1.4-1.7 fastest per pass; 2 and 1.2 about
/// 5-10% slower, 0.7 about 20%.
pub const CELL_PER_RADIUS: f32 = 1.5;

/// Buckets of the photon grid's hash table. Photons lie on surfaces, so the cells that ever hold one
/// are about (surface area / cell^2) times a small factor for cells a surface cuts at a slant; two
/// buckets per such cell keeps collisions rare while the table stays small enough to be cached (a table
/// sized by the photon count was 40x larger and its scan and atomics cost more than its collisions saved).
pub fn grid_buckets(surface_area: f64, cell_size: f32, photon_capacity: u32) -> u32 {
    let cells = 1.5 * surface_area / (cell_size as f64).powi(2);
    let wanted = (2.0 * cells).min(2.0 * photon_capacity as f64).max(1.0);
    (wanted as u64)
        .next_power_of_two()
        .clamp(SCAN_BLOCK as u64, SCAN_BLOCK as u64 * 65536) as u32
}

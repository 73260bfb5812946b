//! The scene itself, format-neutral: camera, materials and their surfaces, spheres, quads, meshes, image
//! regions; its bounds, lights and content hashes; and every value check, once ([`Scene::validate`]), so a
//! scene built in code, read from TOML or Mitsuba XML or imported is checked the same way. The readers
//! (toml.rs, mitsuba/, obj.rs, ply.rs) build it; load.rs chooses the reader for a file.

use std::fmt;

use glam::{DVec3, Vec3};

use crate::emitter::{Emitter, Environment};
use crate::error::fmt_vec;
use crate::error::{Error, Result};
use crate::texture;
use crate::Microfacet;
use ppm_vk_materials::conductor as conductors;
use ppm_vk_materials::plastic;

/// Largest accepted image side; larger is almost certainly a typo and would
/// exhaust GPU memory long before rendering anything useful.
pub const MAX_RESOLUTION: u32 = 16384;

/// Most triangles a scene (and so one OBJ file) may hold: 2^24 = 16,777,216. A sanity limit, not a
/// format one: that many triangles already need over 1 GiB of vertex and BVH buffers, and an OBJ that
/// large is far more likely a mistake than a scene meant for this renderer.
pub const MAX_TRIANGLES: usize = 1 << 24;

/// Most spheres and quads a scene may hold together: 2^16. Every ray tests each of them in turn (only
/// triangles have a BVH), so a pass over more would take hours; lavapipe's loop budget already stops far
/// below this (`PathLimits`).
pub const MAX_SHAPES: usize = 1 << 16;

/// Farthest a sphere may reach from the origin (its centre's largest coordinate plus its radius): 2^60.
/// Its intersection squares distances in 32-bit floats, which overflow at 2^128.
pub const MAX_SPHERE_REACH: f32 = (1u64 << 60) as f32;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub look_at: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees, in (0, 180).
    pub vfov_deg: f32,
    pub width: u32,
    pub height: u32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Surface {
    /// Lambertian reflector; albedo components in [0, 1].
    Diffuse { albedo: Vec3 },
    /// Perfect specular reflector; reflectance components in [0, 1].
    Mirror { reflectance: Vec3 },
    /// Smooth conductor (Mitsuba's `conductor`): a specular reflector whose reflectance is `reflectance`
    /// times the unpolarised Fresnel term of a metal of complex index `eta + i k` per RGB channel
    /// (shaders/materials/conductor.glsl, ppm_vk_materials::conductor).
    Conductor { reflectance: Vec3, eta: Vec3, k: Vec3 },
    /// Smooth dielectric; `ior` is the index inside, the outside is 1.
    Glass { ior: f32 },
    /// Mitsuba's `plastic` (ppm_vk_materials::plastic): a diffuse base of reflectance `diffuse` under a smooth
    /// dielectric coat of relative index `ior` (inside over outside) whose mirror reflection is `specular`
    /// times its Fresnel term; `nonlinear` darkens and saturates the base as light bounces between it and
    /// the coat. Its diffuse reflectance is bounded by [`plastic::max_diffuse_reflectance`].
    Plastic {
        diffuse: Vec3,
        specular: Vec3,
        ior: f32,
        nonlinear: bool,
        /// Mitsuba's `roughplastic`: the coat a microfacet distribution (ppm_vk_materials::rough_plastic).
        rough: Option<Microfacet>,
    },
    /// Mitsuba's `roughconductor` (ppm_vk_materials::rough_conductor): the conductor's facets, oriented by a
    /// microfacet distribution.
    RoughConductor {
        reflectance: Vec3,
        eta: Vec3,
        k: Vec3,
        rough: Microfacet,
    },
    /// Mitsuba's `roughdielectric` (ppm_vk_materials::rough_dielectric): the glass's facets, oriented by a
    /// microfacet distribution; `ior` is the index inside over the index outside.
    RoughGlass { ior: f32, rough: Microfacet },
    /// Mitsuba's `thindielectric` (ppm_vk_materials::thin_dielectric): a pane of relative index `ior` that
    /// reflects (times `reflectance`) or lets light through without bending it (times `transmittance`).
    ThinDielectric {
        ior: f32,
        reflectance: Vec3,
        transmittance: Vec3,
    },
    /// Mitsuba's `blendbsdf` (ppm_vk_materials::blend): (1 - w) times material `first`'s BSDF plus w times
    /// material `second`'s (indices into `Scene::materials`, themselves blends at most
    /// [`MAX_BLEND_DEPTH`] deep). w is `weight`, or, where the material has a `texture`, that texture's
    /// luminance at each point (the weight's texture lives in `Material::texture`, which a blend reads
    /// for nothing else). The kernels pick one of the two at each surface interaction (blend.glsl).
    Blend { weight: f32, first: u32, second: u32 },
}

pub use ppm_vk_materials::blend::MAX_BLEND_DEPTH;

impl Surface {
    /// Its microfacet distribution, where it is rough.
    pub fn rough(&self) -> Option<Microfacet> {
        match *self {
            Surface::RoughConductor { rough, .. } | Surface::RoughGlass { rough, .. } => Some(rough),
            Surface::Plastic { rough, .. } => rough,
            _ => None,
        }
    }

    /// A conductor of complex index `eta + i k`, or, for Mitsuba's default "none" (eta 0, k 1: a Fresnel
    /// term of exactly 1 at every angle), the mirror it equals, which the kernels trace without the Fresnel
    /// term.
    pub fn conductor(reflectance: Vec3, eta: Vec3, k: Vec3) -> Surface {
        match (eta, k) == conductors::named("none").expect("the default conductor") {
            true => Surface::Mirror { reflectance },
            false => Surface::Conductor { reflectance, eta, k },
        }
    }

    /// A plastic, its diffuse reflectance lowered where a channel exceeds what a photon can scatter
    /// without gaining flux ([`plastic::max_diffuse_reflectance`], 0.93-0.95 for common coats); the
    /// message says so, for the loader to warn with.
    pub fn plastic(
        diffuse: Vec3,
        specular: Vec3,
        ior: f32,
        nonlinear: bool,
        rough: Option<Microfacet>,
    ) -> (Surface, Option<String>) {
        Surface::plastic_in(diffuse, specular, ior, nonlinear, rough, &mut plastic::Coats::default())
    }

    /// [`Surface::plastic`] with its coat taken from `coats`: a reader keeps one for the whole file.
    pub(crate) fn plastic_in(
        diffuse: Vec3,
        specular: Vec3,
        ior: f32,
        nonlinear: bool,
        rough: Option<Microfacet>,
        coats: &mut plastic::Coats,
    ) -> (Surface, Option<String>) {
        let most = plastic::max_diffuse_reflectance(ior, nonlinear, coats.coat(ior, rough));
        let kept = diffuse.min(Vec3::splat(most));
        let warning = (kept != diffuse).then(|| {
            format!(
                "diffuse_reflectance {} lowered to at most {most:.4} per channel: above it a photon's \
                 diffuse bounce off this coat (index {ior}) would gain flux (docs/scene-format.md, plastic)",
                fmt_vec(diffuse.to_array())
            )
        });
        let surface = Surface::Plastic {
            diffuse: kept,
            specular,
            ior,
            nonlinear,
            rough,
        };
        (surface, warning)
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Unique within a scene. Materials imported from an MTL are named `<OBJ path>:<MTL name>`.
    pub name: String,
    pub surface: Surface,
    /// Emitted radiance (linear RGB); zero means the material is not a light.
    pub emission: Vec3,
    /// Index into `Scene::textures`: the texture the diffuse reflectance (a diffuse surface's albedo, a
    /// plastic's base) is read from at each point, instead of the surface's constant.
    pub texture: Option<u32>,
    /// Mitsuba's `bumpmap` or `normalmap` around the surface: the normal its BSDF works about, perturbed
    /// at each point by a texture (shaders/materials/normal_map.glsl).
    pub normal_map: Option<NormalMap>,
    /// Mitsuba's `mask`: index into `Scene::textures` of its opacity (1 opaque, 0 not there; a constant
    /// opacity is a 1 x 1 texture). Rays pass the surface with probability 1 - opacity.
    pub opacity: Option<u32>,
    /// Index into `Scene::textures`: the texture `specular_reflectance` is read from (conductors,
    /// plastics, thin dielectrics), instead of the surface's constant.
    pub specular_texture: Option<u32>,
    /// Index into `Scene::textures`: the texture a rough surface's `alpha` is read from.
    pub alpha_texture: Option<u32>,
    /// Index into `Scene::textures`: the texture an area light's `radiance` is read from.
    pub emission_texture: Option<u32>,
}

/// A texture that perturbs a material's shading normal, as Mitsuba 3's src/bsdfs/bumpmap.cpp and
/// normalmap.cpp do, with their shadowing term (Estevez et al. 2019) on the perturbed BSDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NormalMap {
    /// `bumpmap`: a height field, the luminance of texture `texture` (index into `Scene::textures`) times
    /// `scale`, whose gradient in (u, v) moves the surface along its normal.
    Bump { texture: u32, scale: f32 },
    /// `normalmap`: texture `texture`'s RGB as 2 x - 1, a normal in the shading frame (dp/du, its cross,
    /// the normal).
    Normal { texture: u32 },
}

impl NormalMap {
    pub fn texture(&self) -> u32 {
        match *self {
            NormalMap::Bump { texture, .. } | NormalMap::Normal { texture } => texture,
        }
    }
}

impl Material {
    pub fn is_light(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
    /// Index into `Scene::materials`.
    pub material: u32,
}

/// Parallelogram `origin + s*edge_u + t*edge_v`, `s, t` in [0, 1], or with `disk` the ellipse inscribed
/// in it, `(2s - 1)^2 + (2t - 1)^2 <= 1` (Mitsuba's `disk` under any affine `to_world`: one analytic
/// shape and one light, not a fan of triangles).
/// Front normal is `normalize(edge_u x edge_v)`; emission leaves the front side only.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quad {
    pub origin: Vec3,
    pub edge_u: Vec3,
    pub edge_v: Vec3,
    /// Index into `Scene::materials`.
    pub material: u32,
    /// Only the inscribed ellipse (a disk), not the whole parallelogram.
    pub disk: bool,
}

impl Quad {
    pub fn normal(&self) -> Vec3 {
        self.edge_u.cross(self.edge_v).normalize()
    }

    /// The parallelogram's area, or pi / 4 of it for the ellipse inscribed in it.
    pub fn area(&self) -> f32 {
        let a = self.edge_u.cross(self.edge_v).length();
        if self.disk {
            a * std::f32::consts::FRAC_PI_4
        } else {
            a
        }
    }
}

/// An indexed triangle mesh in world space (the scene file's transform already applied).
///
/// A triangle `[a, b, c]` is counter-clockwise seen from its front side, as in OBJ: its front normal is
/// `normalize((p[b] - p[a]) x (p[c] - p[a]))`. Triangles reflect from both sides, emission leaves the
/// front side only (as for quads), and a closed glass mesh has its front side outside.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// Where it came from: the OBJ path as opened, or any label for a mesh built in code.
    pub name: String,
    pub positions: Vec<Vec3>,
    /// Unit shading normals, one per position, when the OBJ gives one for every vertex. Only shading:
    /// the front side is always the winding's.
    pub normals: Option<Vec<Vec3>>,
    /// Texture coordinates, one per position, when the file gives them for every vertex (Mitsuba's
    /// convention: v grows downwards in the image, so an OBJ's `vt` is flipped).
    pub uvs: Option<Vec<glam::Vec2>>,
    /// Triangles as indices into `positions`.
    pub indices: Vec<[u32; 3]>,
    /// Material of each triangle (index into `Scene::materials`); as long as `indices`.
    pub materials: Vec<u32>,
}

/// One triangle of a mesh, positions resolved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    pub p: [Vec3; 3],
    /// Index into `Scene::materials`.
    pub material: u32,
}

impl Triangle {
    /// `(p1 - p0) x (p2 - p0)`: along the front normal, twice the area long.
    pub fn cross(&self) -> Vec3 {
        (self.p[1] - self.p[0]).cross(self.p[2] - self.p[0])
    }

    /// Front normal (counter-clockwise winding).
    pub fn normal(&self) -> Vec3 {
        self.cross().normalize()
    }

    pub fn area(&self) -> f32 {
        0.5 * self.cross().length()
    }

    /// Zero area at f32 precision: no direction can be taken for its normal. The loader drops these;
    /// `Scene::validate` refuses them.
    pub fn is_degenerate(&self) -> bool {
        self.cross().normalize_or_zero() == Vec3::ZERO
    }
}

impl Mesh {
    /// Vertex normals where the file gave none, as Mitsuba 3 makes them (`Mesh::recompute_vertex_normals`):
    /// each triangle's normal, weighted by its angle at the vertex (Thuermer and Wuethrich 1998), summed
    /// and normalised. Degenerate triangles add nothing; a vertex whose sum vanishes takes the normal of
    /// the first triangle at it that has one.
    pub fn compute_vertex_normals(&mut self) {
        let mut sum = vec![glam::DVec3::ZERO; self.positions.len()];
        let mut first = vec![None; self.positions.len()];
        for t in &self.indices {
            let p = t.map(|i| self.positions[i as usize].as_dvec3());
            let Some(n) = (p[1] - p[0]).cross(p[2] - p[0]).try_normalize() else {
                continue;
            };
            for k in 0..3 {
                let (Some(a), Some(b)) = (
                    (p[(k + 1) % 3] - p[k]).try_normalize(),
                    (p[(k + 2) % 3] - p[k]).try_normalize(),
                ) else {
                    continue;
                };
                let v = t[k] as usize;
                sum[v] += n * a.dot(b).clamp(-1.0, 1.0).acos();
                first[v].get_or_insert(n);
            }
        }
        let normals = sum
            .iter()
            .zip(&first)
            .map(|(s, f)| s.try_normalize().or(*f).unwrap_or(glam::DVec3::Z).as_vec3())
            .collect();
        self.normals = Some(normals);
    }

    /// A mesh whose triangles all have one material.
    pub fn with_material(name: impl Into<String>, positions: Vec<Vec3>, indices: Vec<[u32; 3]>, material: u32) -> Mesh {
        let materials = vec![material; indices.len()];
        Mesh {
            name: name.into(),
            positions,
            normals: None,
            uvs: None,
            indices,
            materials,
        }
    }

    /// Triangle `i`. Panics when `i` or one of its vertex indices is out of range (a validated scene
    /// has none out of range).
    pub fn triangle(&self, i: usize) -> Triangle {
        let [a, b, c] = self.indices[i];
        Triangle {
            p: [
                self.positions[a as usize],
                self.positions[b as usize],
                self.positions[c as usize],
            ],
            material: self.materials[i],
        }
    }

    pub fn triangles(&self) -> impl Iterator<Item = Triangle> + '_ {
        (0..self.indices.len()).map(|i| self.triangle(i))
    }
}

/// Names one triangle of a scene: `scene.meshes[mesh].triangle(triangle)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TriangleRef {
    pub mesh: u32,
    pub triangle: u32,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub name: String,
    pub camera: Camera,
    /// In file order (TOML materials first, then those imported with each mesh).
    pub materials: Vec<Material>,
    pub spheres: Vec<Sphere>,
    pub quads: Vec<Quad>,
    /// Triangle meshes, in world space.
    pub meshes: Vec<Mesh>,
    /// The textures materials read (`Material::texture`).
    pub textures: Vec<texture::Texture>,
    /// Lights with no surface of their own: points, spots, the sun, environments (emitter.rs). Emitting
    /// quads, triangles and spheres are materials with `emission`.
    pub emitters: Vec<Emitter>,
    /// Parts of the image scored on their own against a reference (`[[region]]` in a TOML scene); a
    /// Mitsuba scene has none.
    pub regions: Vec<ImageRegion>,
    /// What loading approximated or dropped, one line each (an MTL feature the engine does not model,
    /// once per material; degenerate triangles dropped, with their count). The library never prints
    /// them: the CLI writes them to stderr.
    pub warnings: Vec<String>,
}

/// A named rectangle of pixels (origin top left), in the reference's full resolution.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Region {
    pub name: String,
    pub x0: u32,
    pub y0: u32,
    pub w: u32,
    pub h: u32,
}

impl Region {
    pub fn new(name: &str, x0: u32, y0: u32, w: u32, h: u32) -> Self {
        Self {
            name: name.to_owned(),
            x0,
            y0,
            w,
            h,
        }
    }
}

/// A named part of the image, scored on its own against a reference image: its edges as fractions of
/// the image's width and height (origin top left; x0 < x1, y0 < y1, all in [0, 1]), so it names the
/// same part of the picture at any resolution.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageRegion {
    pub name: String,
    pub x0: f64,
    pub y0: f64,
    pub x1: f64,
    pub y1: f64,
}

impl ImageRegion {
    /// The pixels it covers in a `width` x `height` image (a reference's), its edges rounded outward to
    /// whole pixels: exactly its edges where they fall on pixel edges (k / 512 at 512 x 512).
    pub fn pixels(&self, width: u32, height: u32) -> Region {
        // A millionth of a pixel of slack, so that a fraction such as 1/3 at 300 pixels, not exactly
        // 100 in floating point, is not widened by one.
        let low = |f: f64, n: u32| ((f * f64::from(n) + 1e-6).floor().max(0.0) as u32).min(n);
        let high = |f: f64, n: u32| ((f * f64::from(n) - 1e-6).ceil().max(0.0) as u32).min(n);
        let (x0, y0) = (low(self.x0, width), low(self.y0, height));
        let (x1, y1) = (high(self.x1, width).max(x0 + 1), high(self.y1, height).max(y0 + 1));
        Region::new(&self.name, x0, y0, x1 - x0, y1 - y0)
    }

    fn check(&self, path: &str) -> Result<(), Invalid> {
        if self.name.is_empty() {
            return Err(invalid(format!("{path}.name"), "must not be empty"));
        }
        for (lo, hi, a, b) in [(self.x0, self.x1, "x0", "x1"), (self.y0, self.y1, "y0", "y1")] {
            if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo < hi && hi <= 1.0) {
                return Err(invalid(
                    format!("{path}.{a}"),
                    format!(
                        "{a} and {b} are fractions of the image with 0 <= {a} < {b} <= 1, got {a} = {lo}, {b} = {hi}"
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// A failed check of [`Scene::validate`]: the field it concerns, as a path (`sphere[1].radius`,
/// `materials.white.diffuse`, `mesh[0]`; empty for the scene as a whole), and what is wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct Invalid {
    pub path: String,
    pub message: String,
}

impl fmt::Display for Invalid {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.path.is_empty() {
            write!(f, "{}", self.message)
        } else {
            write!(f, "{}: {}", self.path, self.message)
        }
    }
}

impl std::error::Error for Invalid {}

fn invalid(path: impl Into<String>, message: impl Into<String>) -> Invalid {
    Invalid {
        path: path.into(),
        message: message.into(),
    }
}

impl Scene {
    /// Axis-aligned bounds `(min, max)` of all spheres, quads and mesh vertices; `(0, 0)` for an
    /// empty scene (a validated scene is never empty: it has a light).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for s in &self.spheres {
            lo = lo.min(s.center - Vec3::splat(s.radius));
            hi = hi.max(s.center + Vec3::splat(s.radius));
        }
        for q in &self.quads {
            for p in [
                q.origin,
                q.origin + q.edge_u,
                q.origin + q.edge_v,
                q.origin + q.edge_u + q.edge_v,
            ] {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        for p in self.meshes.iter().flat_map(|m| &m.positions) {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        if lo.cmple(hi).all() {
            (lo, hi)
        } else {
            (Vec3::ZERO, Vec3::ZERO)
        }
    }

    /// Indices (into `quads`) of the quads whose material emits.
    pub fn lights(&self) -> Vec<u32> {
        self.quads
            .iter()
            .enumerate()
            .filter(|(_, q)| self.emits(q.material))
            .map(|(i, _)| i as u32)
            .collect()
    }

    /// The mesh triangles whose material emits, in mesh and triangle order (the triangle half of the
    /// light list; [`Scene::lights`] is the quad half).
    pub fn emitting_triangles(&self) -> Vec<TriangleRef> {
        let mut out = Vec::new();
        for (mi, m) in self.meshes.iter().enumerate() {
            for (ti, &mat) in m.materials.iter().enumerate() {
                if self.emits(mat) {
                    out.push(TriangleRef {
                        mesh: mi as u32,
                        triangle: ti as u32,
                    });
                }
            }
        }
        out
    }

    /// SHA-256 (hex) of everything that shapes the image: camera and resolution, the materials' surfaces
    /// and emission, spheres, quads and every mesh's vertices, normals, indices and materials. Names
    /// (the scene's, materials', mesh paths) are left out: moving a scene's directory keeps its hash.
    /// Checkpoints use it to refuse resuming a render of another scene.
    pub fn content_sha256(&self) -> String {
        camera_sha256(&self.camera, &self.geometry_sha256())
    }

    /// SHA-256 (hex) of everything [`Scene::content_sha256`] covers except the camera: what a renderer
    /// keeps when only the camera moves (the engine's `Renderer::set_camera`).
    pub fn geometry_sha256(&self) -> String {
        use sha2::Digest;
        use std::fmt::Write as _;
        let mut h = sha2::Sha256::new();
        let floats =
            |v: &[Vec3]| -> Vec<u8> { v.iter().flat_map(|p| p.to_array()).flat_map(f32::to_le_bytes).collect() };
        let surfaces: Vec<(Surface, Vec3, Option<u32>)> = self
            .materials
            .iter()
            .map(|m| (m.surface, m.emission, m.texture))
            .collect();
        // Writing into a hash cannot fail.
        let _ = write!(Feed(&mut h), "{:?}", (&surfaces, &self.spheres, &self.quads));
        // Only materials with a normal map (or a texture on a parameter beyond the diffuse reflectance)
        // hash it, so that every other scene keeps its hash.
        for (i, m) in self.materials.iter().enumerate() {
            if let Some(n) = m.normal_map {
                let _ = write!(Feed(&mut h), "normal_map{i}{n:?}");
            }
            let more = [m.opacity, m.specular_texture, m.alpha_texture, m.emission_texture];
            if more.iter().any(Option::is_some) {
                let _ = write!(Feed(&mut h), "textures{i}{more:?}");
            }
        }
        for t in &self.textures {
            let _ = write!(Feed(&mut h), "{:?}", (t.filter, t.wrap, t.to_uv));
            match &t.pattern {
                texture::Pattern::Bitmap { width, height, pixels } => {
                    h.update([width.to_le_bytes(), height.to_le_bytes()].concat());
                    h.update(floats(pixels));
                }
                texture::Pattern::Checkerboard { color0, color1 } => h.update(floats(&[*color0, *color1])),
            }
        }
        for m in &self.meshes {
            h.update((m.positions.len() as u64).to_le_bytes());
            h.update(floats(&m.positions));
            h.update(floats(m.normals.as_deref().unwrap_or(&[])));
            let uvs = m.uvs.as_deref().unwrap_or(&[]);
            h.update((uvs.len() as u64).to_le_bytes());
            h.update(
                uvs.iter()
                    .flat_map(|p| p.to_array())
                    .flat_map(f32::to_le_bytes)
                    .collect::<Vec<u8>>(),
            );
            h.update((m.indices.len() as u64).to_le_bytes());
            h.update(
                m.indices
                    .iter()
                    .flatten()
                    .flat_map(|i| i.to_le_bytes())
                    .collect::<Vec<u8>>(),
            );
            h.update(m.materials.iter().flat_map(|i| i.to_le_bytes()).collect::<Vec<u8>>());
        }
        // Only scenes with such lights hash them, so that every other scene keeps its hash.
        for e in &self.emitters {
            match e {
                Emitter::Environment(Environment {
                    scale,
                    map: Some(map),
                    to_world,
                }) => {
                    let _ = write!(Feed(&mut h), "envmap{:?}", (scale, to_world, map.width, map.height));
                    h.update(floats(&map.pixels));
                }
                other => {
                    let _ = write!(Feed(&mut h), "{other:?}");
                }
            }
        }
        hex(h)
    }

    /// Triangles in all meshes.
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.indices.len()).sum()
    }

    fn emits(&self, material: u32) -> bool {
        self.materials.get(material as usize).is_some_and(Material::is_light)
    }

    /// Uniform scale about the world origin of all geometry and the camera
    /// position/target; `s` must be positive and finite. Radiance (emission) is
    /// unchanged, so a correct renderer produces the same image.
    pub fn scaled(&self, s: f32) -> Scene {
        debug_assert!(s.is_finite() && s > 0.0, "scale must be positive and finite, got {s}");
        let mut out = self.clone();
        out.camera.eye *= s;
        out.camera.look_at *= s;
        for sp in &mut out.spheres {
            sp.center *= s;
            sp.radius *= s;
        }
        for q in &mut out.quads {
            q.origin *= s;
            q.edge_u *= s;
            q.edge_v *= s;
        }
        // Normals are unchanged by a uniform positive scale.
        for p in out.meshes.iter_mut().flat_map(|m| &mut m.positions) {
            *p *= s;
        }
        out.emitters = self.emitters.iter().map(|e| e.scaled(s)).collect();
        out
    }

    /// Same scene at another image size (both at least 1).
    pub fn with_resolution(&self, w: u32, h: u32) -> Scene {
        debug_assert!(w >= 1 && h >= 1, "resolution must be at least 1x1, got {w}x{h}");
        let mut out = self.clone();
        out.camera.width = w;
        out.camera.height = h;
        out
    }

    /// Checks everything the renderer relies on: finite values, camera, material ranges (emission only
    /// on diffuse surfaces), textures (values in [0, 1], read by diffuse and plastic surfaces only, on
    /// meshes only with texture coordinates), sphere radii, non-degenerate quads and triangles, indices
    /// in range, at most [`MAX_TRIANGLES`], the lights' values, and at least one light (an emitting quad,
    /// sphere or mesh triangle, or an [`Emitter`] that emits). The error is [`Error::Scene`] with the field's path, the scene's name as its `file`
    /// and no line (a loader that knows where the field was written locates it instead).
    pub fn validate(&self) -> Result<()> {
        self.check()
            .map_err(|e| Error::scene(&self.name, 0, 0, e.path, e.message))
    }

    /// Textures: each material's in range, on a diffuse or plastic surface whose constant is at least the
    /// texture's largest value in each channel (loaders set it to [`texture::Texture::max`], the bound the
    /// photons use), and every texture's values reflectances (`materials.NAME.texture` names the first
    /// material reading a bad one, `textures[i]` one that none reads).
    fn check_textures(&self) -> Result<(), Invalid> {
        for (i, t) in self.textures.iter().enumerate() {
            let this = Some(i as u32);
            // A texture that nothing reads as a reflectance (an area light's radiance, or nothing) holds
            // radiances: unbounded.
            let radiance = !self.materials.iter().any(|m| {
                m.texture == this
                    || m.normal_map.is_some_and(|n| Some(n.texture()) == this)
                    || m.opacity == this
                    || m.specular_texture == this
                    || m.alpha_texture == this
            });
            let checked = if radiance { t.check_radiance() } else { t.check() };
            if let Err(message) = checked {
                let path = self
                    .materials
                    .iter()
                    .find(|m| m.texture == this)
                    .map(|m| format!("materials.{}.texture", m.name))
                    .or_else(|| {
                        let m = self.materials.iter().find(|m| m.emission_texture == this)?;
                        Some(format!("materials.{}.emission_texture", m.name))
                    })
                    .unwrap_or_else(|| format!("textures[{i}]"));
                return Err(invalid(path, format!("texture \"{}\": {message}", t.name)));
            }
        }
        for m in &self.materials {
            let Some(n) = m.normal_map else { continue };
            let p = format!("materials.{}.normal_map", m.name);
            if n.texture() as usize >= self.textures.len() {
                return Err(invalid(
                    p,
                    format!(
                        "texture index {} out of range ({} textures)",
                        n.texture(),
                        self.textures.len()
                    ),
                ));
            }
            if let NormalMap::Bump { scale, .. } = n {
                if !scale.is_finite() {
                    return Err(invalid(p, format!("the bump map's scale must be finite, got {scale}")));
                }
            }
        }
        // specular_reflectance and alpha textures: in range, on a surface that reads them (specular: one
        // whose constant reflectance bounds the texture, as the diffuse one's; alpha: an isotropic rough
        // conductor or glass, its texture's luminance at each point the alpha).
        for m in &self.materials {
            for (field, t) in [
                ("specular_texture", m.specular_texture),
                ("alpha_texture", m.alpha_texture),
            ] {
                let Some(t) = t else { continue };
                let p = format!("materials.{}.{field}", m.name);
                let Some(texture) = self.textures.get(t as usize) else {
                    return Err(invalid(
                        p,
                        format!("texture index {t} out of range ({} textures)", self.textures.len()),
                    ));
                };
                let bound = match (field, m.surface) {
                    (
                        "specular_texture",
                        Surface::Mirror { reflectance }
                        | Surface::Conductor { reflectance, .. }
                        | Surface::RoughConductor { reflectance, .. }
                        | Surface::ThinDielectric { reflectance, .. },
                    ) => Some(reflectance),
                    ("alpha_texture", Surface::RoughConductor { rough, .. } | Surface::RoughGlass { rough, .. })
                        if !rough.is_anisotropic() =>
                    {
                        None
                    }
                    _ => {
                        return Err(invalid(
                            p,
                            "not read on this surface (specular_texture: (rough) conductors, mirrors and thin \
                             dielectrics; alpha_texture: isotropic rough conductors and glass)",
                        ))
                    }
                };
                if let Some(constant) = bound.filter(|c| texture.max().cmpgt(*c).any()) {
                    return Err(invalid(
                        p,
                        format!(
                            "the surface's constant reflectance {} is below the largest value of texture \"{}\" \
                             (it must bound the texture: set it to Texture::max())",
                            fmt_vec(constant.to_array()),
                            texture.name
                        ),
                    ));
                }
            }
        }
        for m in &self.materials {
            let Some(t) = m.opacity else { continue };
            if t as usize >= self.textures.len() {
                return Err(invalid(
                    format!("materials.{}.opacity", m.name),
                    format!("texture index {t} out of range ({} textures)", self.textures.len()),
                ));
            }
        }
        for m in &self.materials {
            let Some(t) = m.emission_texture else { continue };
            let p = format!("materials.{}.emission_texture", m.name);
            let Some(texture) = self.textures.get(t as usize) else {
                return Err(invalid(
                    p,
                    format!("texture index {t} out of range ({} textures)", self.textures.len()),
                ));
            };
            // Material::emission is the texture's largest value (what makes the material a light).
            if texture.max() != m.emission {
                return Err(invalid(
                    p,
                    format!(
                        "the emission {} is not the largest value of radiance texture \"{}\", {} (set it to \
                         Texture::max())",
                        fmt_vec(m.emission.to_array()),
                        texture.name,
                        fmt_vec(texture.max().to_array())
                    ),
                ));
            }
        }
        for m in &self.materials {
            let Some(t) = m.texture else { continue };
            let p = format!("materials.{}.texture", m.name);
            let Some(texture) = self.textures.get(t as usize) else {
                return Err(invalid(
                    p,
                    format!("texture index {t} out of range ({} textures)", self.textures.len()),
                ));
            };
            let constant = match m.surface {
                Surface::Diffuse { albedo } => albedo,
                Surface::Plastic { diffuse, .. } => diffuse,
                // A blend's weight: the texture's luminance, in [0, 1] as its values are (checked above).
                Surface::Blend { .. } => continue,
                _ => {
                    return Err(invalid(
                        p,
                        "a texture gives a diffuse reflectance: only diffuse and plastic surfaces read one (and \
                     blends, as their weight)",
                    ))
                }
            };
            let most = texture.max();
            if most.cmpgt(constant).any() {
                return Err(invalid(
                    p,
                    format!(
                        "the surface's constant reflectance {} is below the largest value of texture \"{}\", {} \
                         (it must bound the texture: set it to Texture::max())",
                        fmt_vec(constant.to_array()),
                        texture.name,
                        fmt_vec(most.to_array())
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Material `i` and, where it is a blend, every material its components reach (`i` first). Only for
    /// a scene whose blends [`Scene::check_blends`] accepted.
    pub fn blend_components(&self, i: u32) -> Vec<u32> {
        let mut out = vec![i];
        let mut k = 0;
        while k < out.len() {
            if let Some(Surface::Blend { first, second, .. }) = self.materials.get(out[k] as usize).map(|m| m.surface) {
                out.extend([first, second]);
            }
            k += 1;
        }
        out
    }

    /// Blends: their components in range, no blend reaching itself, none more than [`MAX_BLEND_DEPTH`]
    /// deep, and none with a bump or normal map of its own (a reader gives it to the components: the
    /// kernels apply the chosen component's).
    fn check_blends(&self) -> Result<(), Invalid> {
        // The blend depth of material `i`; `path`: the blends above it.
        fn depth(s: &Scene, i: u32, path: &mut Vec<u32>) -> Result<u32, Invalid> {
            let m = &s.materials[i as usize];
            let Surface::Blend { first, second, .. } = m.surface else {
                return Ok(0);
            };
            let p = format!("materials.{}.blend", m.name);
            for c in [first, second] {
                if c as usize >= s.materials.len() {
                    return Err(invalid(
                        p,
                        format!("material index {c} out of range ({} materials)", s.materials.len()),
                    ));
                }
            }
            if path.contains(&i) {
                return Err(invalid(
                    p,
                    "a blend that contains itself (its components lead back to it)",
                ));
            }
            if path.len() as u32 >= MAX_BLEND_DEPTH {
                return Err(invalid(
                    p,
                    format!("blends nested more than MAX_BLEND_DEPTH = {MAX_BLEND_DEPTH} deep"),
                ));
            }
            path.push(i);
            let d = depth(s, first, path)?.max(depth(s, second, path)?);
            path.pop();
            Ok(1 + d)
        }
        for (i, m) in self.materials.iter().enumerate() {
            if let Surface::Blend { .. } = m.surface {
                if m.normal_map.is_some() {
                    return Err(invalid(
                        format!("materials.{}.normal_map", m.name),
                        "a bump or normal map on a blend: give it to each of its components",
                    ));
                }
                depth(self, i as u32, &mut Vec::new())?;
            }
        }
        Ok(())
    }

    /// [`Scene::validate`] with the field path kept apart, for loaders that can locate it.
    pub(crate) fn check(&self) -> Result<(), Invalid> {
        self.check_with(&mut plastic::Coats::default())
    }

    /// [`Scene::check`] taking the plastics' coats from `coats`, one per distinct coat however many
    /// materials share it: a reader that made them already passes its own.
    pub(crate) fn check_with(&self, coats: &mut plastic::Coats) -> Result<(), Invalid> {
        check_camera(&self.camera)?;
        // Textures first: a bad pixel is named rather than the constant it made.
        self.check_textures()?;
        for m in &self.materials {
            check_material(m, coats)?;
        }
        self.check_blends()?;
        let material = |path: &str, i: u32| -> Result<&Material, Invalid> {
            self.materials.get(i as usize).ok_or_else(|| {
                invalid(
                    path,
                    format!("material index {i} out of range ({} materials)", self.materials.len()),
                )
            })
        };
        for (i, s) in self.spheres.iter().enumerate() {
            let p = format!("sphere[{i}]");
            finite_vec(s.center, &format!("{p}.center"))?;
            if !(s.radius.is_finite() && s.radius > 0.0) {
                return Err(invalid(
                    format!("{p}.radius"),
                    format!("must be positive and finite, got {}", s.radius),
                ));
            }
            // The intersection squares distances from the centre in f32: beyond 2^60 they overflow
            // (2^128) and every ray misses or hits NaN, a silently black image.
            let reach = s.center.abs().max_element() + s.radius;
            if reach > MAX_SPHERE_REACH {
                return Err(invalid(
                    format!("{p}.radius"),
                    format!(
                        "a sphere of radius {:e} at {} reaches {reach:e} from the origin, beyond {MAX_SPHERE_REACH:e} \
                         (2^60), where its intersection's squares overflow 32-bit floats",
                        s.radius,
                        fmt_vec(s.center.to_array())
                    ),
                ));
            }
            if material(&format!("{p}.material"), s.material)?
                .emission_texture
                .is_some()
            {
                return Err(invalid(
                    format!("{p}.material"),
                    "a radiance texture (emission_texture) is read on quads and triangles only",
                ));
            }
        }
        for (i, q) in self.quads.iter().enumerate() {
            check_quad(q, &format!("quad[{i}]"))?;
            material(&format!("quad[{i}].material"), q.material)?;
        }
        for (i, m) in self.meshes.iter().enumerate() {
            let p = format!("mesh[{i}]");
            check_mesh(m, &p, self.materials.len())?;
            if m.uvs.is_none() {
                // A blend's components are read at its points too.
                let textured = m
                    .materials
                    .iter()
                    .flat_map(|&k| self.blend_components(k))
                    .map(|k| &self.materials[k as usize]);
                if let Some(t) = textured.clone().find(|t| t.normal_map.is_some()) {
                    return Err(invalid(
                        p,
                        format!(
                            "{}: material \"{}\" has a bump or normal map, which needs texture coordinates (one \
                             per vertex), and the mesh has none",
                            m.name, t.name
                        ),
                    ));
                }
                let patterned = |t: Option<u32>| {
                    let t = t.and_then(|t| self.textures.get(t as usize));
                    t.is_some_and(|t| matches!(t.pattern, texture::Pattern::Bitmap { .. }))
                };
                if let Some(t) = textured.clone().find(|t| patterned(t.opacity)) {
                    return Err(invalid(
                        p,
                        format!(
                            "{}: material \"{}\" is masked by an image, which needs texture coordinates (one \
                             per vertex), and the mesh has none",
                            m.name, t.name
                        ),
                    ));
                }
                if let Some(t) = textured
                    .clone()
                    .find(|t| t.texture.is_some() || t.emission_texture.is_some())
                {
                    return Err(invalid(
                        p,
                        format!(
                            "{}: material \"{}\" reads a texture, but the mesh has no texture coordinates \
                             (one per vertex)",
                            m.name, t.name
                        ),
                    ));
                }
            }
        }
        for (i, r) in self.regions.iter().enumerate() {
            r.check(&format!("region[{i}]"))?;
            if self.regions[..i].iter().any(|other| other.name == r.name) {
                return Err(invalid(
                    format!("region[{i}].name"),
                    format!("region {:?} is named twice", r.name),
                ));
            }
        }
        let shapes = self.spheres.len() + self.quads.len();
        if shapes > MAX_SHAPES {
            return Err(invalid(
                "",
                format!(
                    "{shapes} spheres and quads, more than MAX_SHAPES = {MAX_SHAPES} (every ray tests each \
                     one; put large geometry in a mesh, which has a BVH)"
                ),
            ));
        }
        let triangles = self.triangle_count();
        if triangles > MAX_TRIANGLES {
            return Err(invalid(
                "",
                format!("{triangles} triangles, more than MAX_TRIANGLES = {MAX_TRIANGLES}"),
            ));
        }
        for (i, e) in self.emitters.iter().enumerate() {
            e.check(&format!("emitter[{i}]"))
                .map_err(|(path, message)| invalid(path, message))?;
        }
        let emitting_triangle = self.meshes.iter().any(|m| m.materials.iter().any(|&k| self.emits(k)));
        let emitting_sphere = self.spheres.iter().any(|s| self.emits(s.material));
        if self.lights().is_empty()
            && !emitting_triangle
            && !emitting_sphere
            && !self.emitters.iter().any(Emitter::emits)
        {
            return Err(invalid(
                "",
                "no light: nothing to render (give a quad, sphere or mesh a material with positive \
                 `emission`, or Ke in its MTL, or add a light)",
            ));
        }
        Ok(())
    }
}

fn finite_vec(v: Vec3, path: &str) -> Result<(), Invalid> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(invalid(
            path,
            format!("every component must be finite, got {}", fmt_vec(v.to_array())),
        ))
    }
}

/// A finite vector with every component in [0, 1] (albedo, reflectance).
fn unit_vec(v: Vec3, path: &str) -> Result<(), Invalid> {
    finite_vec(v, path)?;
    if v.cmpge(Vec3::ZERO).all() && v.cmple(Vec3::ONE).all() {
        Ok(())
    } else {
        Err(invalid(
            path,
            format!("every component must be in [0, 1], got {}", fmt_vec(v.to_array())),
        ))
    }
}

/// Feeds `Debug` text straight into a hash (exact: floats print as their shortest round trip).
struct Feed<'a>(&'a mut sha2::Sha256);

impl fmt::Write for Feed<'_> {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        sha2::Digest::update(self.0, s.as_bytes());
        Ok(())
    }
}

fn hex(h: sha2::Sha256) -> String {
    sha2::Digest::finalize(h).iter().map(|b| format!("{b:02x}")).collect()
}

/// [`Scene::content_sha256`] from its camera and [`Scene::geometry_sha256`].
pub fn camera_sha256(camera: &Camera, geometry_sha256: &str) -> String {
    use std::fmt::Write as _;
    let mut h = <sha2::Sha256 as sha2::Digest>::new();
    let _ = write!(Feed(&mut h), "{camera:?}{geometry_sha256}");
    hex(h)
}

impl Camera {
    /// Checks the camera as [`Scene::validate`] does; the error is [`Error::Scene`] naming the field
    /// (`camera.up`, ...), with `what` as its file.
    pub fn validate(&self, what: &str) -> Result<()> {
        check_camera(self).map_err(|e| Error::scene(what, 0, 0, e.path, e.message))
    }
}

fn check_camera(c: &Camera) -> Result<(), Invalid> {
    finite_vec(c.eye, "camera.eye")?;
    finite_vec(c.look_at, "camera.look_at")?;
    finite_vec(c.up, "camera.up")?;
    let vfov = c.vfov_deg;
    if !(vfov.is_finite() && vfov > 0.0 && vfov < 180.0) {
        return Err(invalid(
            "camera.vfov",
            format!("must be in (0, 180) degrees, got {vfov}"),
        ));
    }
    let (width, height) = (c.width, c.height);
    if !(1..=MAX_RESOLUTION).contains(&width) || !(1..=MAX_RESOLUTION).contains(&height) {
        return Err(invalid(
            "camera.resolution",
            format!("width and height must each be in 1..={MAX_RESOLUTION}, got [{width}, {height}]"),
        ));
    }
    // In f64 so that far-apart finite points cannot overflow; zero length gives zero.
    let view = c.look_at.as_dvec3() - c.eye.as_dvec3();
    let dir = view.normalize_or_zero();
    if dir == DVec3::ZERO {
        return Err(invalid(
            "camera.look_at",
            format!("must differ from camera.eye, both are {}", fmt_vec(c.eye.to_array())),
        ));
    }
    let up_n = c.up.as_dvec3().normalize_or_zero();
    if up_n == DVec3::ZERO {
        return Err(invalid("camera.up", "must be a non-zero vector"));
    }
    // ~0.006 degrees: closer than that the camera basis is numerically meaningless.
    if dir.cross(up_n).length() < 1e-4 {
        return Err(invalid(
            "camera.up",
            format!(
                "is parallel to the view direction (look_at - eye = {}); \
                 choose an up vector not along it",
                fmt_vec(view.as_vec3().to_array())
            ),
        ));
    }
    Ok(())
}

fn positive_ior(ior: f32, path: &str) -> Result<(), Invalid> {
    match ior.is_finite() && ior > 0.0 {
        true => Ok(()),
        false => Err(invalid(
            path.to_string(),
            format!("relative index of refraction must be finite and > 0, got {ior}"),
        )),
    }
}

/// A conductor's specular_reflectance and complex index (smooth or rough).
fn conductor_terms(p: &str, reflectance: Vec3, eta: Vec3, k: Vec3) -> Result<(), Invalid> {
    unit_vec(reflectance, &format!("{p}.reflectance"))?;
    for (name, v) in [("eta", eta), ("k", k)] {
        let path = format!("{p}.conductor.{name}");
        finite_vec(v, &path)?;
        if v.cmplt(Vec3::ZERO).any() {
            let got = fmt_vec(v.to_array());
            return Err(invalid(path, format!("every component must be >= 0, got {got}")));
        }
    }
    if (eta + k).cmple(Vec3::ZERO).any() {
        let message = "eta and k are both 0 in a channel: no such metal (Mitsuba's default is eta 0, k 1)";
        return Err(invalid(format!("{p}.conductor"), message.to_string()));
    }
    Ok(())
}

/// A microfacet roughness: finite, at least Mitsuba's floor (the readers raise smaller values to it).
fn roughness(rough: Microfacet, path: &str) -> Result<(), Invalid> {
    for a in [rough.alpha, rough.alpha_v] {
        if !(a.is_finite() && a >= Microfacet::MIN_ALPHA) {
            return Err(invalid(
                path.to_string(),
                format!("must be finite and >= {}, got {a}", Microfacet::MIN_ALPHA),
            ));
        }
    }
    Ok(())
}

fn check_material(m: &Material, coats: &mut plastic::Coats) -> Result<(), Invalid> {
    let p = format!("materials.{}", m.name);
    let ep = format!("{p}.emission");
    finite_vec(m.emission, &ep)?;
    if m.emission.cmplt(Vec3::ZERO).any() {
        return Err(invalid(
            ep,
            format!("every component must be >= 0, got {}", fmt_vec(m.emission.to_array())),
        ));
    }
    // A subnormal emission's power (emission x area x pi) rounds to 0: a light that sends no photon.
    if m.emission.to_array().iter().any(|&e| e > 0.0 && e < f32::MIN_POSITIVE) {
        return Err(invalid(
            ep,
            format!(
                "{} has a component above 0 but below {:e}, the smallest normal 32-bit float: its power \
                 would round to 0 (use 0 for no light)",
                fmt_vec(m.emission.to_array()),
                f32::MIN_POSITIVE
            ),
        ));
    }
    match m.surface {
        Surface::Diffuse { albedo } => unit_vec(albedo, &format!("{p}.diffuse"))?,
        Surface::Mirror { reflectance } => unit_vec(reflectance, &format!("{p}.mirror"))?,
        Surface::Conductor { reflectance, eta, k } => conductor_terms(&p, reflectance, eta, k)?,
        Surface::Glass { ior } => {
            if !(ior.is_finite() && ior >= 1.0) {
                return Err(invalid(
                    format!("{p}.glass"),
                    format!("index of refraction must be finite and >= 1, got {ior}"),
                ));
            }
        }
        Surface::Plastic {
            diffuse,
            specular,
            ior,
            nonlinear,
            rough,
        } => {
            positive_ior(ior, &format!("{p}.plastic.ior"))?;
            unit_vec(specular, &format!("{p}.plastic.specular"))?;
            if let Some(rough) = rough {
                roughness(rough, &format!("{p}.plastic.alpha"))?;
            }
            let path = format!("{p}.plastic.diffuse");
            unit_vec(diffuse, &path)?;
            let most = plastic::max_diffuse_reflectance(ior, nonlinear, coats.coat(ior, rough));
            if diffuse.max_element() > most {
                return Err(invalid(
                    path,
                    format!(
                        "at most {most:.4} per channel for a coat of index {ior} (above it a photon's diffuse \
                         bounce would gain flux), got {}",
                        fmt_vec(diffuse.to_array())
                    ),
                ));
            }
        }
        Surface::RoughConductor {
            reflectance,
            eta,
            k,
            rough,
        } => {
            conductor_terms(&p, reflectance, eta, k)?;
            roughness(rough, &format!("{p}.conductor.alpha"))?;
        }
        Surface::RoughGlass { ior, rough } => {
            if !(ior.is_finite() && ior >= 1.0) {
                return Err(invalid(
                    format!("{p}.rough_glass.ior"),
                    format!("index of refraction must be finite and >= 1, got {ior}"),
                ));
            }
            roughness(rough, &format!("{p}.rough_glass.alpha"))?;
        }
        Surface::ThinDielectric {
            ior,
            reflectance,
            transmittance,
        } => {
            positive_ior(ior, &format!("{p}.thin.ior"))?;
            unit_vec(reflectance, &format!("{p}.thin.reflectance"))?;
            unit_vec(transmittance, &format!("{p}.thin.transmittance"))?;
        }
        Surface::Blend { weight, .. } => {
            // Mitsuba clips the weight to [0, 1]; outside it is a mistake in the file, refused here.
            if !(0.0..=1.0).contains(&weight) {
                return Err(invalid(
                    format!("{p}.blend.weight"),
                    format!("must be in [0, 1], got {weight}"),
                ));
            }
        }
    }
    if m.is_light() && !matches!(m.surface, Surface::Diffuse { .. }) {
        return Err(invalid(
            ep,
            "emission can only be combined with diffuse (or stand alone), not with mirror or glass",
        ));
    }
    Ok(())
}

fn check_quad(q: &Quad, p: &str) -> Result<(), Invalid> {
    finite_vec(q.origin, &format!("{p}.origin"))?;
    finite_vec(q.edge_u, &format!("{p}.edge_u"))?;
    finite_vec(q.edge_v, &format!("{p}.edge_v"))?;
    // f64 so that huge (but finite) f32 edges cannot overflow the tests below.
    let (u, v) = (q.edge_u.as_dvec3(), q.edge_v.as_dvec3());
    for (len, field) in [(u.length(), "edge_u"), (v.length(), "edge_v")] {
        // Checked separately so the message can say which edge is at fault.
        if len == 0.0 {
            return Err(invalid(
                format!("{p}.{field}"),
                "edge has zero length (degenerate quad)",
            ));
        }
    }
    // Relative test: sin(angle between edges) below 1e-6 is parallel at f32 precision.
    if u.cross(v).length() <= 1e-6 * u.length() * v.length() {
        return Err(invalid(
            format!("{p}.edge_v"),
            format!(
                "parallel to edge_u {} (zero-area, degenerate quad)",
                fmt_vec(q.edge_u.to_array())
            ),
        ));
    }
    Ok(())
}

fn check_mesh(m: &Mesh, p: &str, num_materials: usize) -> Result<(), Invalid> {
    let fail = |msg: String| Err(invalid(p, format!("{}: {msg}", m.name)));
    if m.indices.is_empty() {
        return fail("has no triangles".into());
    }
    if m.materials.len() != m.indices.len() {
        return fail(format!(
            "{} triangle materials for {} triangles",
            m.materials.len(),
            m.indices.len()
        ));
    }
    if let Some(k) = m.positions.iter().position(|v| !v.is_finite()) {
        return fail(format!(
            "vertex {k} is not finite: {}",
            fmt_vec(m.positions[k].to_array())
        ));
    }
    if let Some(n) = &m.normals {
        if n.len() != m.positions.len() {
            return fail(format!("{} normals for {} vertices", n.len(), m.positions.len()));
        }
        if let Some(k) = n.iter().position(|v| v.normalize_or_zero() == Vec3::ZERO) {
            return fail(format!(
                "normal {k} is zero or not finite: {}",
                fmt_vec(n[k].to_array())
            ));
        }
    }
    if let Some(uv) = &m.uvs {
        if uv.len() != m.positions.len() {
            return fail(format!(
                "{} texture coordinates for {} vertices",
                uv.len(),
                m.positions.len()
            ));
        }
        if let Some(k) = uv.iter().position(|v| !v.is_finite()) {
            return fail(format!("texture coordinate {k} is not finite: {}", uv[k]));
        }
    }
    let nv = m.positions.len();
    for (t, (tri, &mat)) in m.indices.iter().zip(&m.materials).enumerate() {
        if let Some(&i) = tri.iter().find(|&&i| i as usize >= nv) {
            return fail(format!(
                "triangle {t} has vertex index {i}, out of range ({nv} vertices)"
            ));
        }
        if mat as usize >= num_materials {
            return fail(format!(
                "triangle {t} has material index {mat}, out of range ({num_materials} materials)"
            ));
        }
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] || m.triangle(t).is_degenerate() {
            return fail(format!("triangle {t} is degenerate (zero area or a repeated vertex)"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit square light (two triangles facing -y at y = 1) over a diffuse floor quad.
    fn small_scene() -> Scene {
        Scene {
            name: "code".into(),
            camera: Camera {
                eye: Vec3::new(0.0, 0.5, 3.0),
                look_at: Vec3::new(0.0, 0.5, 0.0),
                up: Vec3::Y,
                vfov_deg: 40.0,
                width: 8,
                height: 8,
            },
            materials: vec![
                Material {
                    name: "white".into(),
                    surface: Surface::Diffuse {
                        albedo: Vec3::splat(0.5),
                    },
                    emission: Vec3::ZERO,
                    texture: None,
                    normal_map: None,
                    opacity: None,
                    specular_texture: None,
                    alpha_texture: None,
                    emission_texture: None,
                },
                Material {
                    name: "lamp".into(),
                    surface: Surface::Diffuse { albedo: Vec3::ZERO },
                    emission: Vec3::splat(5.0),
                    texture: None,
                    normal_map: None,
                    opacity: None,
                    specular_texture: None,
                    alpha_texture: None,
                    emission_texture: None,
                },
            ],
            spheres: vec![],
            quads: vec![Quad {
                origin: Vec3::new(-1.0, 0.0, -1.0),
                edge_u: Vec3::new(0.0, 0.0, 2.0),
                edge_v: Vec3::new(2.0, 0.0, 0.0),
                material: 0,
                disk: false,
            }],
            meshes: vec![Mesh::with_material(
                "lamp",
                vec![
                    Vec3::new(0.0, 1.0, 0.0),
                    Vec3::new(1.0, 1.0, 0.0),
                    Vec3::new(1.0, 1.0, 1.0),
                    Vec3::new(0.0, 1.0, 1.0),
                ],
                // Counter-clockwise seen from below: front normal -y.
                vec![[0, 1, 2], [0, 2, 3]],
                1,
            )],
            textures: vec![],
            regions: vec![],
            emitters: vec![],
            warnings: vec![],
        }
    }

    fn check_err(s: &Scene) -> Invalid {
        match s.check() {
            Ok(()) => panic!("expected the scene to be refused: {s:?}"),
            Err(e) => e,
        }
    }

    #[test]
    fn scene_built_in_code_validates() {
        let s = small_scene();
        s.validate().expect("valid");
        assert_eq!(s.triangle_count(), 2);
        assert!(s.lights().is_empty(), "no emitting quad");
        assert_eq!(
            s.emitting_triangles(),
            [
                TriangleRef { mesh: 0, triangle: 0 },
                TriangleRef { mesh: 0, triangle: 1 }
            ]
        );
        for t in s.meshes[0].triangles() {
            assert_eq!(t.normal(), Vec3::NEG_Y);
            assert!((t.area() - 0.5).abs() < 1e-6);
        }
        assert_eq!(s.bounds(), (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 1.0, 1.0)));
        let t = s.scaled(3.0);
        assert_eq!(t.bounds(), (s.bounds().0 * 3.0, s.bounds().1 * 3.0));
        assert!((t.meshes[0].triangle(1).area() - 4.5).abs() < 1e-5);
        t.validate().expect("scaled scene valid");
    }

    #[test]
    fn validate_refuses_bad_meshes() {
        type Edit = fn(&mut Scene);
        let cases: Vec<(Edit, &str)> = vec![
            (
                |s| s.meshes[0].indices[1][2] = 4,
                "triangle 1 has vertex index 4, out of range (4 vertices)",
            ),
            (
                |s| s.meshes[0].materials[0] = 7,
                "triangle 0 has material index 7, out of range (2 materials)",
            ),
            (
                |s| {
                    s.meshes[0].materials.pop();
                },
                "1 triangle materials for 2 triangles",
            ),
            (|s| s.meshes[0].positions[2].x = f32::NAN, "vertex 2 is not finite"),
            (|s| s.meshes[0].positions[2].z = f32::INFINITY, "vertex 2 is not finite"),
            (|s| s.meshes[0].indices[0] = [0, 1, 1], "triangle 0 is degenerate"),
            // Collinear: zero area though the indices differ.
            (
                |s| s.meshes[0].positions[2] = Vec3::new(2.0, 1.0, 0.0),
                "triangle 0 is degenerate",
            ),
            (|s| s.meshes[0].indices.clear(), "has no triangles"),
            (
                |s| s.meshes[0].normals = Some(vec![Vec3::Y; 3]),
                "3 normals for 4 vertices",
            ),
            (
                |s| s.meshes[0].normals = Some(vec![Vec3::Y, Vec3::ZERO, Vec3::Y, Vec3::Y]),
                "normal 1 is zero",
            ),
        ];
        for (edit, needle) in cases {
            let mut s = small_scene();
            edit(&mut s);
            let e = check_err(&s);
            assert_eq!(e.path, "mesh[0]", "{e}");
            assert!(e.message.starts_with("lamp: "), "{e}");
            assert!(e.message.contains(needle), "{e} should contain {needle:?}");
            let full = format!("{:#}", s.validate().unwrap_err());
            assert!(full.starts_with("scene code: mesh[0]: lamp: "), "{full}");
        }
    }

    /// [`small_scene`] with a 2 x 1 texture on "white" (the floor quad) and texture coordinates on the
    /// lamp mesh.
    fn textured_scene() -> Scene {
        let mut s = small_scene();
        s.textures.push(texture::Texture {
            name: "t.png".into(),
            pattern: texture::Pattern::Bitmap {
                width: 2,
                height: 1,
                pixels: vec![Vec3::splat(0.25), Vec3::new(0.5, 0.75, 0.5)],
            },
            filter: texture::Filter::Bilinear,
            wrap: texture::Wrap::Repeat,
            to_uv: texture::IDENTITY_UV,
        });
        s.materials[0].texture = Some(0);
        s.materials[0].surface = Surface::Diffuse {
            albedo: s.textures[0].max(),
        };
        s.meshes[0].uvs = Some(vec![glam::Vec2::ZERO; 4]);
        s
    }

    #[test]
    fn validate_checks_textures_and_texture_coordinates() {
        textured_scene().validate().expect("valid");
        type Edit = fn(&mut Scene);
        let cases: Vec<(Edit, &str, &str)> = vec![
            (
                |s| s.materials[0].texture = Some(3),
                "materials.white.texture",
                "texture index 3 out of range (1 textures)",
            ),
            (
                |s| {
                    s.materials[0].surface = Surface::Mirror {
                        reflectance: Vec3::ONE,
                    }
                },
                "materials.white.texture",
                "only diffuse and plastic surfaces read one",
            ),
            (
                |s| {
                    s.materials[0].surface = Surface::Diffuse {
                        albedo: Vec3::splat(0.5),
                    }
                },
                "materials.white.texture",
                "the surface's constant reflectance [0.5, 0.5, 0.5] is below the largest value of texture \"t.png\", [0.5, 0.75, 0.5]",
            ),
            (
                |s| {
                    if let texture::Pattern::Bitmap { pixels, .. } = &mut s.textures[0].pattern {
                        pixels[1].y = f32::NAN;
                    }
                },
                "materials.white.texture",
                "texture \"t.png\": pixel (1, 0) (column, row from the top) is [0.5, NaN, 0.5]",
            ),
            (
                |s| {
                    if let texture::Pattern::Bitmap { pixels, .. } = &mut s.textures[0].pattern {
                        pixels[0] = Vec3::splat(1.5);
                    }
                    s.materials[0].surface = Surface::Diffuse { albedo: Vec3::splat(1.5) };
                },
                "materials.white.texture",
                "pixel (0, 0) (column, row from the top) is [1.5, 1.5, 1.5]: a reflectance must be finite and in [0, 1]",
            ),
            (
                |s| {
                    s.materials[0].texture = None;
                    s.textures[0].to_uv[2] = f32::INFINITY;
                },
                "textures[0]",
                "to_uv [1.0, 0.0, inf, 0.0, 1.0, 0.0] is not finite",
            ),
            (
                |s| s.meshes[0].uvs = Some(vec![glam::Vec2::ZERO; 3]),
                "mesh[0]",
                "lamp: 3 texture coordinates for 4 vertices",
            ),
            (
                |s| s.meshes[0].uvs.as_mut().unwrap()[2].x = f32::NAN,
                "mesh[0]",
                "lamp: texture coordinate 2 is not finite",
            ),
            (
                |s| {
                    s.meshes[0].uvs = None;
                    s.materials[1].texture = Some(0);
                    s.materials[1].surface = s.materials[0].surface;
                },
                "mesh[0]",
                "lamp: material \"lamp\" reads a texture, but the mesh has no texture coordinates",
            ),
        ];
        for (edit, path, needle) in cases {
            let mut s = textured_scene();
            edit(&mut s);
            let e = check_err(&s);
            assert_eq!(e.path, path, "{e}");
            assert!(e.message.contains(needle), "{e} should contain {needle:?}");
        }
        // A plastic reads one too, within its bound.
        let mut s = textured_scene();
        let (surface, _) = Surface::plastic(s.textures[0].max(), Vec3::ONE, 1.5, false, None);
        s.materials[0].surface = surface;
        s.validate().expect("a textured plastic");
    }

    #[test]
    fn validate_needs_a_light_quad_or_triangle() {
        let mut s = small_scene();
        s.materials[1].emission = Vec3::ZERO;
        let e = check_err(&s);
        assert_eq!(e.path, "");
        assert!(e.message.starts_with("no light: nothing to render"), "{e}");
        // An emitting quad alone is enough, as before meshes.
        s.meshes.clear();
        s.quads[0].material = 1;
        s.materials[1].emission = Vec3::ONE;
        s.validate().expect("emitting quad");
        assert!(s.emitting_triangles().is_empty());
    }

    #[test]
    fn validate_checks_every_kind_of_value() {
        let mut s = small_scene();
        s.camera.vfov_deg = 180.0;
        assert_eq!(check_err(&s).path, "camera.vfov");
        let mut s = small_scene();
        s.materials[0].surface = Surface::Mirror {
            reflectance: Vec3::new(0.5, 1.5, 0.5),
        };
        let e = check_err(&s);
        assert_eq!(
            (e.path.as_str(), e.message.as_str()),
            (
                "materials.white.mirror",
                "every component must be in [0, 1], got [0.5, 1.5, 0.5]"
            )
        );
        let mut s = small_scene();
        s.materials[1].surface = Surface::Glass { ior: 1.5 };
        assert_eq!(check_err(&s).path, "materials.lamp.emission");
        let mut s = small_scene();
        s.spheres.push(Sphere {
            center: Vec3::ZERO,
            radius: 0.5,
            material: 1,
        });
        // A glowing sphere is a light like any other.
        s.validate().unwrap();
        s.spheres[0].material = 2;
        assert!(check_err(&s).message.contains("material index 2 out of range"));
        let mut s = small_scene();
        s.quads[0].edge_v = s.quads[0].edge_u * 2.0;
        assert_eq!(check_err(&s).path, "quad[0].edge_v");
    }
}

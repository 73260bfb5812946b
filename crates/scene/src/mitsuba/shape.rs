//! The `<shape>` element: its bsdf and area emitter, the material they make, then one reader per
//! Mitsuba shape type (rectangle, cube, disk, sphere, obj, ply), called from the dispatch in
//! [`Builder::shape`], which place the scene's quads, spheres and meshes.

use std::collections::HashMap;
use std::rc::Rc;

use anyhow::Result;
use glam::{DAffine3, DMat3, DVec3, Vec3};

use super::bsdf::Bsdf;
use super::elem::Elem;
use super::properties::Props;
use super::texture::Tex;
use super::Builder;
use crate::obj::{self, RawMesh};
use crate::texture::{self, Texture};
use crate::{ply, serialized, Mesh, ObjImport, Quad, Sphere, Surface, MAX_TRIANGLES};

/// Triangles in the fan a `disk` becomes. The polygon's radius is enlarged so that its area is the
/// disk's exactly (an emitting disk keeps its power); its outline then lies between 2.6e-5 of the
/// radius inside the circle (edge midpoints) and 5.1e-5 outside (corners).
pub const DISK_SEGMENTS: u32 = 256;

/// Sides of the prism a `cylinder` becomes. Its circumradius is enlarged so that its lateral area is
/// the cylinder's exactly (pi / n / sin(pi / n) times the radius); its outline then lies between 5.0e-5
/// of the radius inside the circle (the middles of its faces) and 2.5e-5 outside (its edges).
pub const CYLINDER_SEGMENTS: u32 = 256;

/// Shapes whose back side can be seen (a one-sided BSDF on them renders differently here).
#[derive(Clone, Copy, PartialEq)]
enum Closed {
    Yes,
    No,
}

/// What each shape type's reader gets: the shape's element and properties, and what [`Builder::shape`]
/// read for every type.
struct Common<'a> {
    e: &'a Elem,
    props: &'a Props<'a>,
    to_world: DAffine3,
    flip: bool,
    material: u32,
    /// The surface of its bsdf, and the element that bsdf came from (the shape's, without one).
    surface: Surface,
    bsdf_at: &'a Elem,
    emission: Vec3,
    /// The emitter's element (the shape's, without one).
    emitter_at: &'a Elem,
    textured: bool,
    anisotropic: bool,
}

/// An area emitter's radiance: a colour, or a texture (its largest value taken later).
type Radiance = (Vec3, Option<Rc<Tex>>);

impl Builder {
    /// A `<shape>`: its bsdf and emitter, its material, then its type's reader; every property must have
    /// been read by then.
    pub(super) fn shape(&mut self, e: &Elem) -> Result<()> {
        if e.kind() == "instance" {
            return self.instance(e);
        }
        let index = self.shapes;
        self.shapes += 1;
        let (props, objects) = Props::of(e);
        let mut bsdf: Option<(Bsdf, &Elem)> = None;
        let mut emission: Option<(Radiance, &Elem)> = None;
        for o in objects {
            match o.tag.as_str() {
                "bsdf" | "ref" => {
                    if bsdf.is_some() {
                        return Err(o.err("a second bsdf: a shape has one (as in Mitsuba)"));
                    }
                    let b = if o.tag == "bsdf" {
                        self.bsdf(o)?
                    } else {
                        self.bsdf_ref(o)?
                    };
                    bsdf = Some((b, o));
                }
                "emitter" => {
                    if emission.is_some() {
                        return Err(o.err("a second emitter: a shape has one (as in Mitsuba)"));
                    }
                    emission = Some((self.area(o)?, o));
                }
                "medium" => return Err(o.err("participating media are not supported")),
                _ => return Err(o.err(format!("not expected inside {}", e.what()))),
            }
        }
        // Mitsuba gives a shape without a bsdf a diffuse one of reflectance 0.5.
        let (bsdf, bsdf_at) = bsdf.unwrap_or((
            Bsdf {
                surface: Surface::Diffuse {
                    albedo: Vec3::splat(0.5),
                },
                two_sided: false,
                id: None,
                texture: None,
                normal_map: None,
                blend: None,
                opacity: None,
                specular: None,
                alpha: None,
            },
            e,
        ));
        let shape_name = e.attr("id").map_or_else(|| format!("shape[{index}]"), str::to_string);
        let ((emission, radiance_texture), emitter_at) = emission.unwrap_or(((Vec3::ZERO, None), e));
        // A textured radiance: Material::emission holds the texture's largest value in each channel (what
        // makes the material a light; the light's power and photon bound come from the texture itself).
        let emission = radiance_texture.as_ref().map_or(emission, |t| t.texture.max());
        if let Some(t) = &radiance_texture {
            if e.kind() == "sphere" {
                return Err(t.at.err(
                    "a texture on an area emitter's radiance on a sphere is not supported yet (read on rectangles \
                     and meshes: obj, ply, serialized, cube, disk, cylinder)",
                ));
            }
            if emission.max_element() <= 0.0 {
                return Err(t
                    .at
                    .err("the radiance texture is black everywhere: the emitter emits nothing"));
            }
        }
        if emission.max_element() > 0.0 && !matches!(bsdf.surface, Surface::Diffuse { .. }) {
            return Err(emitter_at.err(format!(
                "an area emitter on a {} surface: ppm-vk lights are diffuse (or black) only",
                match bsdf.surface {
                    Surface::Blend { .. } => "blendbsdf",
                    Surface::Glass { .. } | Surface::RoughGlass { .. } => "dielectric",
                    Surface::Plastic { .. } => "plastic",
                    Surface::ThinDielectric { .. } => "thin dielectric",
                    _ => "conductor",
                }
            )));
        }
        if emission.max_element() > 0.0 && bsdf.opacity.is_some() {
            return Err(emitter_at.err(
                "an area emitter on a mask or null bsdf is not supported (ppm-vk's lights emit from all of \
                 their surface)",
            ));
        }
        let name = match (&bsdf.id, emission.max_element() > 0.0) {
            (Some(id), false) => id.clone(),
            _ => shape_name,
        };
        let to_world = props.transform("to_world")?;
        let flip = props.boolean("flip_normals")?;
        // A bump or normal map reads texture coordinates too (modifiers.rs).
        let textured = bsdf.textured() || radiance_texture.is_some();
        // An anisotropic lobe lies along Mitsuba's dp/du: a rectangle's x axis (edge_u below), a sphere's
        // longitude, a mesh's texture coordinates (or the frame of its face normal without them).
        let anisotropic = (bsdf.leaves().iter()).any(|l| l.surface.rough().is_some_and(|r| r.is_anisotropic()));
        if anisotropic && matches!(e.kind(), "cube" | "disk") {
            return Err(bsdf_at.err(format!(
                "anisotropic roughness on a {} is not supported yet (read on rectangles, spheres and OBJ and \
                 PLY meshes)",
                e.kind()
            )));
        }
        // A rectangle's quad has Mitsuba's uv as its coordinates along edge_u and edge_v. A mirroring
        // to_world or flip_normals turns its front side around by swapping the edges, which would swap
        // u and v: a textured one instead runs its first edge backwards from the corner (1, -1), so that
        // its coordinates are (1 - u, v), and its texture's to_uv takes them back to (u, v) first.
        // An anisotropic one does the same, so that edge_u stays along (minus) Mitsuba's x axis.
        let turned = (to_world.matrix3.determinant() < 0.0) != flip;
        let backwards = e.kind() == "rectangle" && turned && (textured || anisotropic);
        if backwards && bsdf.blend.is_some() {
            return Err(bsdf_at.err(
                "a blendbsdf with a texture or anisotropic roughness on a rectangle turned by flip_normals or a \
                 mirroring to_world is not supported yet",
            ));
        }
        if backwards && bsdf.normal_map.is_some() {
            return Err(bsdf_at.err(
                "a bump or normal map on a rectangle turned by flip_normals or a mirroring to_world is not \
                 supported yet",
            ));
        }
        // The textures read at (1 - u, v) on a backwards rectangle: to_uv takes them back to (u, v) first.
        let mirrored = |t: &Texture| Texture {
            to_uv: texture::compose_uv(t.to_uv, [-1.0, 0.0, 1.0, 0.0, 1.0, 0.0]),
            ..t.clone()
        };
        let radiance_texture = radiance_texture.map(|t| {
            let texture = if backwards {
                mirrored(&t.texture)
            } else {
                t.texture.clone()
            };
            (texture, t.at.clone())
        });
        let radiance_texture = radiance_texture.as_ref();
        let material = if backwards {
            let turned_bsdf = bsdf.map_textures(|t| Tex {
                texture: mirrored(&t.texture),
                at: t.at.clone(),
            });
            self.material(&name, &turned_bsdf, emission, radiance_texture, bsdf_at)
        } else {
            self.material(&name, &bsdf, emission, radiance_texture, bsdf_at)
        };
        let common = Common {
            e,
            props: &props,
            to_world,
            flip,
            material,
            surface: bsdf.surface,
            bsdf_at,
            emission,
            emitter_at,
            textured,
            anisotropic,
        };
        let closed = match e.kind() {
            "rectangle" => self.rectangle(&common, backwards),
            "cube" => self.cube(&common)?,
            "disk" => self.disk(&common)?,
            "cylinder" => self.cylinder(&common)?,
            "sphere" => self.sphere(&common)?,
            "obj" => self.obj(&common)?,
            "ply" => self.ply(&common)?,
            "serialized" => self.serialized(&common)?,
            _ => {
                return Err(
                    e.err("unsupported shape (read: rectangle, cube, disk, cylinder, sphere, obj, ply, serialized)")
                )
            }
        };
        props.finish()?;
        self.warn_one_sided(e, &bsdf, bsdf_at, closed);
        Ok(())
    }

    /// The bsdf a `<ref id="..">` names (a top-level one defined before it).
    pub(super) fn bsdf_ref(&self, o: &Elem) -> Result<Bsdf> {
        let id = o.required("id")?;
        self.bsdfs.get(id).cloned().ok_or_else(|| {
            let mut known: Vec<&str> = self.bsdfs.keys().map(String::as_str).collect();
            known.sort();
            o.err(format!(
                "no bsdf with id \"{id}\" defined before it (known: {})",
                if known.is_empty() {
                    "none".to_string()
                } else {
                    known.join(", ")
                }
            ))
        })
    }

    /// Warns about an open shape whose bsdf Mitsuba renders one-sided.
    fn warn_one_sided(&mut self, e: &Elem, bsdf: &Bsdf, bsdf_at: &Elem, closed: Closed) {
        let one_sided = match bsdf.surface {
            Surface::Diffuse { albedo } => albedo != Vec3::ZERO,
            Surface::Mirror { .. }
            | Surface::Conductor { .. }
            | Surface::RoughConductor { .. }
            | Surface::Plastic { .. } => true,
            Surface::Glass { .. } | Surface::RoughGlass { .. } | Surface::ThinDielectric { .. } => false,
            // Both components two-sided make it two-sided (blend.rs).
            Surface::Blend { .. } => true,
        };
        if closed == Closed::No && one_sided && !bsdf.two_sided {
            self.warn(
                bsdf_at,
                format!(
                    "one-sided in Mitsuba (black seen from behind) on {}, which ppm-vk renders \
                     reflecting on both sides: wrap it in a twosided bsdf to say so",
                    e.what()
                ),
            );
        }
    }

    /// Mitsuba's `rectangle`: [-1, 1]^2 at z = 0, facing +z.
    fn rectangle(&mut self, c: &Common, backwards: bool) -> Closed {
        let Common {
            e,
            to_world,
            flip,
            material,
            ..
        } = *c;
        if backwards {
            // quad() swaps the edges of a turned quad: edge_u = -x, edge_v = +y from (1, -1).
            self.quad(
                e,
                &to_world,
                flip,
                [1.0, -1.0, 0.0],
                [0.0, 2.0, 0.0],
                [-2.0, 0.0, 0.0],
                material,
            );
            Closed::No
        } else {
            self.quad(
                e,
                &to_world,
                flip,
                [-1.0, -1.0, 0.0],
                [2.0, 0.0, 0.0],
                [0.0, 2.0, 0.0],
                material,
            );
            Closed::No
        }
    }

    /// Mitsuba's `cube`: [-1, 1]^3, its six faces facing out: six quads, or with a texture the mesh of
    /// twelve triangles Mitsuba makes of it (src/shapes/cube.cpp), with its texture coordinates.
    fn cube(&mut self, c: &Common) -> Result<Closed> {
        let Common {
            e,
            to_world,
            flip,
            material,
            textured,
            ..
        } = *c;
        if textured {
            // Each face's corners, counter-clockwise seen from outside, at uv (0, 1), (1, 1), (1, 0), (0, 0)
            // (Mitsuba's table, face by face: -y, +y, +x, +z, -x, -z).
            let faces: [[[f64; 3]; 4]; 6] = [
                [[1., -1., -1.], [1., -1., 1.], [-1., -1., 1.], [-1., -1., -1.]],
                [[1., 1., -1.], [-1., 1., -1.], [-1., 1., 1.], [1., 1., 1.]],
                [[1., -1., -1.], [1., 1., -1.], [1., 1., 1.], [1., -1., 1.]],
                [[1., -1., 1.], [1., 1., 1.], [-1., 1., 1.], [-1., -1., 1.]],
                [[-1., -1., 1.], [-1., 1., 1.], [-1., 1., -1.], [-1., -1., -1.]],
                [[1., 1., -1.], [1., -1., -1.], [-1., -1., -1.], [-1., 1., -1.]],
            ];
            let corner_uv = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
            let positions = faces.iter().flatten().map(|&p| DVec3::from(p)).collect();
            let uvs = (0..6).flat_map(|_| corner_uv.map(glam::Vec2::from)).collect();
            let triangles = (0..6u32)
                .flat_map(|f| [[0, 1, 2], [3, 0, 2]].map(|t| (t.map(|k| 4 * f + k), material)))
                .collect();
            let raw = RawMesh {
                name: format!("{} cube", e.loc),
                positions,
                normals: None,
                partial_normals: false,
                uvs: Some(uvs),
                triangles,
            };
            self.mesh(e, raw, &to_world, flip)?;
            return Ok(Closed::Yes);
        }
        // Each face of [-1, 1]^3 with its normal outward: edges u x v along +axis, swapped
        // for the face on the negative side.
        for axis in 0..3 {
            let unit = |k: usize| DVec3::AXES[k % 3];
            for side in [1.0, -1.0] {
                let (mut u, mut v) = (2.0 * unit(axis + 1), 2.0 * unit(axis + 2));
                let origin = side * unit(axis) - 0.5 * (u + v);
                if side < 0.0 {
                    std::mem::swap(&mut u, &mut v);
                }
                self.quad(
                    e,
                    &to_world,
                    flip,
                    origin.to_array(),
                    u.to_array(),
                    v.to_array(),
                    material,
                );
            }
        }
        Ok(Closed::Yes)
    }

    /// Mitsuba's `disk`: the unit disk at z = 0, facing +z. An area light without textures is one
    /// analytic disk (a [`Quad`] with `disk`, the ellipse inscribed in [-1, 1]^2 under `to_world`): one
    /// light sampled uniformly in its area, as Mitsuba samples it, and tested by every ray as the quads
    /// are. Any other disk is a fan of [`DISK_SEGMENTS`] triangles in the BVH, with Mitsuba's uv (a fan as
    /// a light was 256 light-table entries whose slivers all meet at its centre: 10-30% of the interior's
    /// eye pass, docs/performance.md).
    fn disk(&mut self, c: &Common) -> Result<Closed> {
        let Common {
            e,
            to_world,
            flip,
            material,
            emission,
            textured,
            ..
        } = *c;
        if emission.max_element() > 0.0 && !textured {
            self.quad(
                e,
                &to_world,
                flip,
                [-1.0, -1.0, 0.0],
                [2.0, 0.0, 0.0],
                [0.0, 2.0, 0.0],
                material,
            );
            if let Some(q) = self.scene.quads.last_mut() {
                q.disk = true;
            }
            return Ok(Closed::No);
        }
        let n = DISK_SEGMENTS;
        let step = std::f64::consts::TAU / f64::from(n);
        // The regular n-gon of area pi: radius sqrt(2 pi / (n sin(2 pi / n))).
        let r = (std::f64::consts::TAU / (f64::from(n) * step.sin())).sqrt();
        // Mitsuba's uv (src/shapes/disk.cpp): (r, phi / 2 pi). The rim's n + 1 vertices (the last at v = 1,
        // the seam), then a centre per triangle, at the v of the triangle's middle: one shared centre
        // would bend every triangle's v towards its own.
        let mut positions: Vec<DVec3> = (0..=n)
            .map(|i| {
                let a = step * f64::from(i % n);
                DVec3::new(r * a.cos(), r * a.sin(), 0.0)
            })
            .collect();
        let mut uvs: Vec<glam::Vec2> = (0..=n).map(|i| glam::Vec2::new(1.0, i as f32 / n as f32)).collect();
        positions.extend((0..n).map(|_| DVec3::ZERO));
        uvs.extend((0..n).map(|i| glam::Vec2::new(0.0, (i as f32 + 0.5) / n as f32)));
        let triangles = (0..n).map(|i| ([n + 1 + i, i, i + 1], material)).collect();
        let raw = RawMesh {
            name: format!("{} disk", e.loc),
            positions,
            normals: None,
            partial_normals: false,
            uvs: Some(uvs),
            triangles,
        };
        self.mesh(e, raw, &to_world, flip)?;
        Ok(Closed::No)
    }

    /// Mitsuba's `cylinder` (src/shapes/cylinder.cpp): an open tube of radius 1 from z = 0 to 1, placed by
    /// `to_world * translate(p0) * to_frame(p1 - p0) * scale(radius, radius, |p1 - p0|)`, as a prism of
    /// [`CYLINDER_SEGMENTS`] sides whose lateral area is exact, shaded smooth by the true cylinder's normals,
    /// with Mitsuba's uv: u = phi / 2 pi about the axis (from the frame's s axis), v = z.
    fn cylinder(&mut self, c: &Common) -> Result<Closed> {
        let Common {
            e,
            props,
            to_world,
            flip,
            material,
            ..
        } = *c;
        let p0 = props.point("p0")?.unwrap_or(DVec3::ZERO);
        let p1 = props.point("p1")?.unwrap_or(DVec3::Z);
        let radius = props.float("radius")?.unwrap_or(1.0);
        let d = p1 - p0;
        let length = d.length();
        if !(length > 0.0 && length.is_finite()) {
            return Err(e.err("p0 and p1 coincide: the cylinder has no length"));
        }
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(e.err(format!("radius {radius}: must be positive")));
        }
        let n = d / length;
        // Mitsuba's Frame3f(n): coordinate_system (Duff et al. 2017), as include/mitsuba/core/vector.h.
        let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = DVec3::new(sign * n.x * n.x * a + 1.0, sign * b, -sign * n.x);
        let t = DVec3::new(b, sign + n.y * n.y * a, -n.y);
        let m = to_world
            * DAffine3::from_translation(p0)
            * DAffine3::from_mat3(DMat3::from_cols(s, t, n))
            * DAffine3::from_scale(DVec3::new(radius, radius, length));
        // Mitsuba intersects a circular cylinder whatever to_world says (it only warns): refused here.
        let (x, y, z) = (m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis);
        let r2 = x.length_squared();
        let round = (y.length_squared() - r2).abs() <= 1e-6 * r2
            && [x.dot(y), x.dot(z), y.dot(z)]
                .iter()
                .all(|p| p.abs() <= 1e-6 * r2.max(z.length_squared()));
        if !round {
            return Err(e.err(
                "to_world shears the cylinder or scales it unevenly across its axis (an elliptic \
                 cylinder): not supported (Mitsuba only warns, and intersects a round one)",
            ));
        }
        if m.matrix3.determinant() < 0.0 {
            return Err(e.err("a mirroring to_world on a cylinder is not supported"));
        }
        let segments = CYLINDER_SEGMENTS;
        let step = std::f64::consts::TAU / f64::from(segments);
        let half = step / 2.0;
        let enlarged = half / half.sin();
        // Two rings of segments + 1 vertices (the last at u = 1, where the texture's seam is).
        let mut positions = Vec::new();
        let mut normals = Vec::new();
        let mut uvs = Vec::new();
        for z in [0.0, 1.0] {
            for i in 0..=segments {
                let phi = step * f64::from(i % segments);
                let (sin, cos) = phi.sin_cos();
                positions.push(DVec3::new(enlarged * cos, enlarged * sin, z));
                normals.push(DVec3::new(cos, sin, 0.0));
                uvs.push(glam::Vec2::new(i as f32 / segments as f32, z as f32));
            }
        }
        let ring = segments + 1;
        let mut triangles = Vec::new();
        for i in 0..segments {
            // Counter-clockwise seen from outside: along phi, then up.
            triangles.push(([i, i + 1, ring + i + 1], material));
            triangles.push(([i, ring + i + 1, ring + i], material));
        }
        let raw = RawMesh {
            name: format!("{} cylinder", e.loc),
            positions,
            normals: Some(normals),
            partial_normals: false,
            uvs: Some(uvs),
            triangles,
        };
        self.mesh(e, raw, &m, flip)?;
        Ok(Closed::No)
    }

    /// Mitsuba's `sphere`: its center and radius, then to_world (which must keep it a sphere).
    fn sphere(&mut self, c: &Common) -> Result<Closed> {
        let Common {
            e,
            props,
            to_world,
            flip,
            material,
            surface,
            emission,
            emitter_at,
            textured,
            anisotropic,
            ..
        } = *c;
        let center = props.point("center")?.unwrap_or(DVec3::ZERO);
        let radius = props.float("radius")?.unwrap_or(1.0);
        let m = to_world * DAffine3::from_translation(center) * DAffine3::from_scale(DVec3::splat(radius));
        let gram = m.matrix3.transpose() * m.matrix3;
        let s2 = gram.x_axis.x;
        let off = (gram - DMat3::from_diagonal(DVec3::splat(s2))).to_cols_array();
        if off.iter().any(|x| x.abs() > 1e-6 * s2) {
            return Err(e.err("to_world scales the sphere non-uniformly (an ellipsoid): not supported"));
        }
        // Mitsuba's flipped sphere lights only its inside; ppm-vk's emitting spheres light outwards.
        if flip && emission.max_element() > 0.0 {
            return Err(emitter_at.err("flip_normals on an emitting sphere (lighting its inside) is not supported"));
        }
        if flip && matches!(surface, Surface::Glass { .. }) {
            return Err(e.err("flip_normals on a dielectric sphere (its inside outside) is not supported"));
        }
        // Mitsuba's sphere uv is taken in its object axes, the engine's along the world's.
        let axes = m.matrix3 * (1.0 / s2.sqrt()) - DMat3::IDENTITY;
        if textured && axes.to_cols_array().iter().any(|x| x.abs() > 1e-6) {
            return Err(e.err(
                "a textured sphere whose to_world rotates or mirrors it is not supported (its texture \
                 coordinates are taken along the world's axes)",
            ));
        }
        if anisotropic && axes.to_cols_array().iter().any(|x| x.abs() > 1e-6) {
            return Err(e.err(
                "an anisotropic sphere whose to_world rotates or mirrors it is not supported (its \
                 tangents are taken along the world's axes)",
            ));
        }
        self.origins
            .insert(format!("sphere[{}]", self.scene.spheres.len()), e.clone());
        self.scene.spheres.push(Sphere {
            center: m.translation.as_vec3(),
            radius: s2.sqrt() as f32,
            material,
        });
        Ok(Closed::Yes)
    }

    /// Mitsuba's `obj`: an OBJ mesh (its materials not read: the shape's bsdf is its material).
    fn obj(&mut self, c: &Common) -> Result<Closed> {
        let Common {
            e,
            props,
            to_world,
            flip,
            material,
            bsdf_at,
            textured,
            ..
        } = *c;
        let path = self.file(e, props)?;
        let flip_tex_coords = props.boolean_or("flip_tex_coords", true)?;
        let i = obj::import(
            &mut self.scene,
            &path,
            &ObjImport {
                transform: to_world,
                material: Some(material),
            },
            MAX_TRIANGLES,
            flip_tex_coords,
        )
        .map_err(|err| e.err(format!("{err:#}")))?;
        if textured && self.scene.meshes[i].uvs.is_none() {
            return Err(e.err(format!(
                "{}: no texture coordinates (a vt on every face corner), which the texture of {} needs",
                path.display(),
                bsdf_at.what()
            )));
        }
        self.origins.insert(format!("mesh[{i}]"), e.clone());
        let m = &mut self.scene.meshes[i];
        if flip {
            m.indices.iter_mut().for_each(|t| t.swap(1, 2));
            m.normals.iter_mut().flatten().for_each(|n| *n = -*n);
        }
        // As Mitsuba: flat where asked, else the file's vertex normals or its own.
        match props.boolean("face_normals")? {
            true => m.normals = None,
            false if m.normals.is_none() => m.compute_vertex_normals(),
            false => {}
        }
        Ok(closed(m))
    }

    /// Mitsuba's `ply`: a PLY mesh (read by `scene/ply.rs`).
    fn ply(&mut self, c: &Common) -> Result<Closed> {
        let Common {
            e,
            props,
            to_world,
            flip,
            material,
            bsdf_at,
            textured,
            ..
        } = *c;
        let path = self.file(e, props)?;
        let face_normals = props.boolean("face_normals")?;
        let raw = ply::read(&path, material).map_err(|err| e.err(format!("{err:#}")))?;
        let uvs = || {
            format!(
                "{}: no texture coordinates (float or double vertex properties u and v, texture_u and \
                 texture_v, or s and t), which the texture of {} needs",
                path.display(),
                bsdf_at.what()
            )
        };
        self.mesh_file(e, raw, face_normals, &to_world, flip, textured, uvs)
    }

    /// Mitsuba's `serialized`: shape `shape_index` of a .serialized file (read by `scene/serialized.rs`),
    /// with the file's normals unless `face_normals`, else Mitsuba's computed ones.
    fn serialized(&mut self, c: &Common) -> Result<Closed> {
        let Common {
            e,
            props,
            to_world,
            flip,
            material,
            bsdf_at,
            textured,
            ..
        } = *c;
        let path = self.file(e, props)?;
        let face_normals = props.boolean("face_normals")?;
        let index = match props.get("shape_index") {
            None => 0,
            Some(p) => {
                let v = p.required("value")?;
                if p.tag != "integer" {
                    return Err(p.err("expected an <integer> here"));
                }
                v.trim()
                    .parse::<u32>()
                    .map_err(|_| p.err(format!("expected a non-negative integer, got \"{v}\"")))?
            }
        };
        let raw = serialized::read(&path, index, material).map_err(|err| e.err(format!("{err:#}")))?;
        let uvs = || {
            format!(
                "{}: shape {index} has no texture coordinates, which the texture of {} needs",
                path.display(),
                bsdf_at.what()
            )
        };
        self.mesh_file(e, raw, face_normals, &to_world, flip, textured, uvs)
    }

    /// A mesh read from a file (PLY, serialized) placed in the scene as Mitsuba does: flat where
    /// `face_normals` asks, else with the file's vertex normals or Mitsuba's own; refused with `no_uvs`'s
    /// message where a texture needs coordinates the file lacks.
    // The element, the mesh and how to shade it, its placement, and what a texture needs: a struct would
    // only name them again.
    #[allow(clippy::too_many_arguments)]
    fn mesh_file(
        &mut self,
        e: &Elem,
        mut raw: RawMesh,
        face_normals: bool,
        to_world: &DAffine3,
        flip: bool,
        textured: bool,
        no_uvs: impl FnOnce() -> String,
    ) -> Result<Closed> {
        if face_normals {
            raw.normals = None;
        }
        if textured && raw.uvs.is_none() {
            return Err(e.err(no_uvs()));
        }
        let i = self.mesh(e, raw, to_world, flip)?;
        let m = &mut self.scene.meshes[i];
        if !face_normals && m.normals.is_none() {
            m.compute_vertex_normals();
        }
        Ok(closed(m))
    }

    /// The quad `origin + s u + t v` (object space) placed by `m`; its front normal is `u x v` turned
    /// as Mitsuba turns normals (the inverse transpose), and flipped with `flip`.
    // The element, its transform, its flip and the quad's corner, edges and material: a struct would
    // only name them again.
    #[allow(clippy::too_many_arguments)]
    fn quad(&mut self, e: &Elem, m: &DAffine3, flip: bool, origin: [f64; 3], u: [f64; 3], v: [f64; 3], material: u32) {
        let (mut u, mut v) = (m.transform_vector3(u.into()), m.transform_vector3(v.into()));
        // A mirroring transform turns u x v against the inverse-transposed normal.
        if (m.matrix3.determinant() < 0.0) != flip {
            std::mem::swap(&mut u, &mut v);
        }
        self.origins
            .insert(format!("quad[{}]", self.scene.quads.len()), e.clone());
        self.scene.quads.push(Quad {
            origin: m.transform_point3(origin.into()).as_vec3(),
            edge_u: u.as_vec3(),
            edge_v: v.as_vec3(),
            material,
            disk: false,
        });
    }

    fn mesh(&mut self, e: &Elem, raw: RawMesh, m: &DAffine3, flip: bool) -> Result<usize> {
        let i = obj::add_mesh(&mut self.scene, raw, m, flip).map_err(|err| e.err(format!("{err:#}")))?;
        self.origins.insert(format!("mesh[{i}]"), e.clone());
        Ok(i)
    }
}

/// Whether every edge of `m` (by vertex position) is shared by exactly two triangles.
fn closed(m: &Mesh) -> Closed {
    let mut edges: HashMap<[[u32; 3]; 2], u32> = HashMap::new();
    let key = |i: u32| m.positions[i as usize].to_array().map(f32::to_bits);
    for t in &m.indices {
        for k in 0..3 {
            let (a, b) = (key(t[k]), key(t[(k + 1) % 3]));
            *edges.entry(if a < b { [a, b] } else { [b, a] }).or_default() += 1;
        }
    }
    if edges.values().all(|&n| n == 2) {
        Closed::Yes
    } else {
        Closed::No
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec2;

    use super::super::tests::{error, load_body, load_in, write_texture};
    use super::*;
    use crate::{Scene, TempDir};

    /// The TOML quads of `quads` (inline tables) after the same camera and light as `HEAD`.
    fn toml_quads(quads: &str) -> Vec<Quad> {
        let text = format!(
            "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\nvfov = 40\nresolution = [8, 8]\n\
             [materials.m]\ndiffuse = [0.5, 0.5, 0.5]\n[materials.light]\nemission = [1, 1, 1]\n\
             [[quad]]\norigin = [-1, 3, 1]\nedge_u = [2, 0, 0]\nedge_v = [0, 0, -2]\nmaterial = \"light\"\n{quads}"
        );
        let s = Scene::parse(&text, "test.toml").expect("TOML equivalent");
        s.quads[1..].to_vec()
    }

    /// The corners of a quad, as a sorted list (so that corner order does not matter).
    fn corners(q: &Quad) -> Vec<[i64; 3]> {
        let mut c: Vec<[i64; 3]> = [
            q.origin,
            q.origin + q.edge_u,
            q.origin + q.edge_v,
            q.origin + q.edge_u + q.edge_v,
        ]
        .iter()
        .map(|p| p.to_array().map(|x| (x * 1e4).round() as i64))
        .collect();
        c.sort();
        c
    }

    /// Same corners and same front normal.
    fn assert_same_quads(got: &[Quad], want: &[Quad]) {
        assert_eq!(got.len(), want.len(), "{got:?}\nvs\n{want:?}");
        for w in want {
            assert!(
                got.iter()
                    .any(|g| corners(g) == corners(w) && g.normal().distance(w.normal()) < 1e-5),
                "no quad like {w:?} (normal {}) among {got:?}",
                w.normal()
            );
        }
    }

    fn rectangle(transform: &str, extra: &str) -> Vec<Quad> {
        let s = load_body(&format!(
            r#"<shape type="rectangle"><transform name="to_world">{transform}</transform>{extra}
               <bsdf type="twosided"><bsdf type="diffuse"/></bsdf></shape>"#
        ))
        .unwrap_or_else(|e| panic!("{e:#}"));
        s.quads[1..].to_vec()
    }

    #[test]
    fn each_transform_of_a_rectangle_matches_its_toml_quad() {
        let cases: &[(&str, &str)] = &[
            // [-1, 1]^2 at z = 0, normal +z.
            ("", "origin = [-1, -1, 0]\nedge_u = [2, 0, 0]\nedge_v = [0, 2, 0]"),
            (
                r#"<translate x="1" y="2" z="3"/>"#,
                "origin = [0, 1, 3]\nedge_u = [2, 0, 0]\nedge_v = [0, 2, 0]",
            ),
            (
                r#"<translate value="1 2 3"/>"#,
                "origin = [0, 1, 3]\nedge_u = [2, 0, 0]\nedge_v = [0, 2, 0]",
            ),
            (
                r#"<scale x="2" y="3"/>"#,
                "origin = [-2, -3, 0]\nedge_u = [4, 0, 0]\nedge_v = [0, 6, 0]",
            ),
            (
                r#"<scale value="0.5"/>"#,
                "origin = [-0.5, -0.5, 0]\nedge_u = [1, 0, 0]\nedge_v = [0, 1, 0]",
            ),
            // Right-handed: +90 degrees about y takes +z to +x.
            (
                r#"<rotate y="1" angle="90"/>"#,
                "origin = [0, -1, 1]\nedge_u = [0, 0, -2]\nedge_v = [0, 2, 0]",
            ),
            // -90 degrees about x takes +z to +y (the reference's floor).
            (
                r#"<rotate value="1, 0, 0" angle="-90"/>"#,
                "origin = [-1, 0, 1]\nedge_u = [2, 0, 0]\nedge_v = [0, 0, -2]",
            ),
            // Document order: scale first, then translate (the centre moves by 1)...
            (
                r#"<scale value="2"/><translate x="1"/>"#,
                "origin = [-1, -2, 0]\nedge_u = [4, 0, 0]\nedge_v = [0, 4, 0]",
            ),
            // ...against translate first, then scale (the translation is scaled too).
            (
                r#"<translate x="1"/><scale value="2"/>"#,
                "origin = [0, -2, 0]\nedge_u = [4, 0, 0]\nedge_v = [0, 4, 0]",
            ),
            (
                r#"<matrix value="2 0 0 1  0 2 0 0  0 0 2 0  0 0 0 1"/>"#,
                "origin = [-1, -2, 0]\nedge_u = [4, 0, 0]\nedge_v = [0, 4, 0]",
            ),
            // lookat: z to the target direction (+x), y up, x = up x dir = -z.
            (
                r#"<lookat origin="0, 0, 0" target="1, 0, 0" up="0, 1, 0"/>"#,
                "origin = [0, -1, 1]\nedge_u = [0, 0, -2]\nedge_v = [0, 2, 0]",
            ),
            // A mirror keeps the normal Mitsuba computes with the inverse transpose: +z.
            (
                r#"<scale x="-1"/>"#,
                "origin = [-1, -1, 0]\nedge_u = [2, 0, 0]\nedge_v = [0, 2, 0]",
            ),
            (
                r#"<scale z="-1"/>"#,
                "origin = [-1, -1, 0]\nedge_u = [0, 2, 0]\nedge_v = [2, 0, 0]",
            ),
        ];
        for (transform, quad) in cases {
            let want = toml_quads(&format!("[[quad]]\n{quad}\nmaterial = \"m\"\n"));
            assert_same_quads(&rectangle(transform, ""), &want);
        }
        // flip_normals turns the normal to -z.
        let want =
            toml_quads("[[quad]]\norigin = [-1, -1, 0]\nedge_u = [0, 2, 0]\nedge_v = [2, 0, 0]\nmaterial = \"m\"\n");
        assert_same_quads(&rectangle("", r#"<boolean name="flip_normals" value="true"/>"#), &want);
    }

    #[test]
    fn cube_is_six_outward_quads() {
        let box_toml = |inward: bool| {
            let mut s = String::new();
            for (o, u, v) in [
                ("[1, -1, -1]", "[0, 2, 0]", "[0, 0, 2]"),
                ("[-1, -1, -1]", "[0, 0, 2]", "[0, 2, 0]"),
                ("[-1, 1, -1]", "[0, 0, 2]", "[2, 0, 0]"),
                ("[-1, -1, -1]", "[2, 0, 0]", "[0, 0, 2]"),
                ("[-1, -1, 1]", "[2, 0, 0]", "[0, 2, 0]"),
                ("[-1, -1, -1]", "[0, 2, 0]", "[2, 0, 0]"),
            ] {
                let (u, v) = if inward { (v, u) } else { (u, v) };
                s += &format!("[[quad]]\norigin = {o}\nedge_u = {u}\nedge_v = {v}\nmaterial = \"m\"\n");
            }
            toml_quads(&s)
        };
        let cube = |extra: &str| {
            load_body(&format!(r#"<shape type="cube">{extra}<bsdf type="diffuse"/></shape>"#))
                .unwrap()
                .quads[1..]
                .to_vec()
        };
        let outward = cube("");
        assert_same_quads(&outward, &box_toml(false));
        for q in &outward {
            // Outward: the normal points away from the centre.
            assert!(q.normal().dot(q.origin + 0.5 * (q.edge_u + q.edge_v)) > 0.99);
        }
        assert_same_quads(&cube(r#"<boolean name="flip_normals" value="true"/>"#), &box_toml(true));
        // A mirroring transform keeps them outward (Mitsuba flips the winding of a mirrored mesh).
        let mirrored = cube(r#"<transform name="to_world"><scale x="-1"/></transform>"#);
        assert_same_quads(&mirrored, &box_toml(false));
    }

    #[test]
    fn disk_is_an_area_exact_fan_facing_z() {
        let s = load_body(
            r#"<shape type="disk"><transform name="to_world"><scale value="0.5"/><translate z="1"/></transform>
               <bsdf type="diffuse"><rgb name="reflectance" value="0.3"/></bsdf></shape>"#,
        )
        .unwrap();
        let m = &s.meshes[0];
        assert_eq!(m.indices.len(), DISK_SEGMENTS as usize);
        let area: f64 = m.triangles().map(|t| f64::from(t.area())).sum();
        let exact = std::f64::consts::PI * 0.25;
        assert!((area / exact - 1.0).abs() < 1e-6, "area {area} vs {exact}");
        for t in m.triangles() {
            assert!(t.normal().distance(Vec3::Z) < 1e-5);
            assert!(t.p.iter().all(|p| (p.z - 1.0).abs() < 1e-6));
        }
        // Every rim vertex 5.0e-5 outside the radius 0.5 (relative: (2 pi / n)^2 / 12), the centre
        // at the centre.
        for p in &m.positions {
            let r = p.truncate().length();
            assert!(r < 1e-6 || (r / 0.5 - 1.0 - 5.02e-5).abs() < 1e-6, "{p}");
        }
        let flipped = load_body(
            r#"<shape type="disk"><boolean name="flip_normals" value="true"/><bsdf type="diffuse"/></shape>"#,
        )
        .unwrap();
        assert!(flipped.meshes[0]
            .triangles()
            .all(|t| t.normal().distance(Vec3::NEG_Z) < 1e-5));
    }

    /// An area light on a disk is one analytic disk: the ellipse inscribed in a quad (a circle here, and
    /// an ellipse under a non-uniform scale), its area exact, its normal turned by flip_normals; no fan.
    #[test]
    fn an_emitting_disk_is_one_analytic_disk() {
        let s = load_body(
            r#"<shape type="disk"><transform name="to_world"><scale x="0.5" y="0.25"/><translate z="1"/></transform>
               <bsdf type="diffuse"/><emitter type="area"><rgb name="radiance" value="2"/></emitter></shape>
               <shape type="disk"><boolean name="flip_normals" value="true"/>
               <emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>"#,
        )
        .unwrap();
        assert!(s.meshes.is_empty() && s.emitting_triangles().is_empty());
        let (d, f) = (&s.quads[s.quads.len() - 2], &s.quads[s.quads.len() - 1]);
        assert!(d.disk && f.disk);
        let pi = std::f32::consts::PI;
        assert!((d.area() - pi * 0.5 * 0.25).abs() < 1e-6, "{}", d.area());
        assert!(d.normal().distance(Vec3::Z) < 1e-6 && f.normal().distance(Vec3::NEG_Z) < 1e-6);
        // The centre, and the ends of its axes, on the ellipse.
        let centre = d.origin + 0.5 * (d.edge_u + d.edge_v);
        assert!(centre.distance(Vec3::new(0.0, 0.0, 1.0)) < 1e-6);
        assert!((0.5 * d.edge_u).length() == 0.5 && (0.5 * d.edge_v).length() == 0.25);
        assert!((f.area() - pi).abs() < 1e-6);
        assert_eq!(s.lights().len(), s.quads.len());
    }

    /// A cylinder from p0 to p1 (then turned, scaled and moved by to_world): its lateral area is the
    /// cylinder's, 2 pi r L, to 1e-6; every vertex lies 2.5e-5 of the radius outside the true cylinder
    /// ((pi / n)^2 / 6) between its end circles, and its normal is the cylinder's there (radial, unit).
    #[test]
    fn cylinder_is_an_area_exact_prism_with_the_cylinders_normals() {
        let s = load_body(
            r#"<shape type="cylinder"><point name="p0" value="1, -0.5, 0.25"/><point name="p1" value="-0.5, 2, 1"/>
               <float name="radius" value="0.3"/><transform name="to_world"><scale value="2"/>
               <rotate x="0.6" y="0.8" angle="70"/><translate x="1" y="2" z="3"/></transform>
               <bsdf type="twosided"><bsdf type="diffuse"/></bsdf><emitter type="area"/></shape>"#,
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        let m = &s.meshes[0];
        assert_eq!(m.indices.len(), 2 * CYLINDER_SEGMENTS as usize);
        let place = DAffine3::from_scale(DVec3::splat(2.0));
        let place = DAffine3::from_axis_angle(DVec3::new(0.6, 0.8, 0.0), 70f64.to_radians()) * place;
        let place = DAffine3::from_translation(DVec3::new(1.0, 2.0, 3.0)) * place;
        let (p0, p1) = (
            place.transform_point3(DVec3::new(1.0, -0.5, 0.25)),
            place.transform_point3(DVec3::new(-0.5, 2.0, 1.0)),
        );
        let (r, length, axis) = (0.6, p0.distance(p1), (p1 - p0).normalize());
        let area: f64 = m.triangles().map(|t| f64::from(t.area())).sum();
        let exact = std::f64::consts::TAU * r * length;
        assert!((area / exact - 1.0).abs() < 1e-6, "area {area} vs {exact}");
        let outside = (std::f64::consts::PI / f64::from(CYLINDER_SEGMENTS)).powi(2) / 6.0;
        let normals = m.normals.as_ref().expect("smooth");
        for (p, n) in m.positions.iter().zip(normals) {
            let d = p.as_dvec3() - p0;
            let along = d.dot(axis);
            let radial = d - along * axis;
            assert!(
                along.abs() < 1e-5 || (along - length).abs() < 1e-5,
                "{p}: {along} along the axis"
            );
            assert!(
                (radial.length() / r - 1.0 - outside).abs() < 1e-5,
                "{p}: {} from the axis",
                radial.length()
            );
            assert!(n.as_dvec3().distance(radial.normalize()) < 1e-5, "{p}: normal {n}");
        }
        // Every triangle faces out (its winding), and the emitter lights outwards.
        for t in m.triangles() {
            let c = (t.p[0] + t.p[1] + t.p[2]).as_dvec3() / 3.0 - p0;
            assert!(t.normal().as_dvec3().dot(c - c.dot(axis) * axis) > 0.0);
        }
        assert_eq!(s.emitting_triangles().len(), 2 * CYLINDER_SEGMENTS as usize);
        let flipped = load_body(
            r#"<shape type="cylinder"><boolean name="flip_normals" value="true"/><bsdf type="diffuse"/></shape>"#,
        )
        .unwrap();
        let m = &flipped.meshes[0];
        for (t, idx) in m.triangles().zip(&m.indices) {
            let c = (t.p[0] + t.p[1] + t.p[2]) / 3.0;
            assert!(t.normal().dot(c.with_z(0.0)) < 0.0, "flipped: faces in");
            let n = m.normals.as_ref().unwrap()[idx[0] as usize];
            assert!(n.dot(c.with_z(0.0)) < 0.0, "flipped: its normals in");
        }
        for (body, says) in [
            (r#"<point name="p1" value="0, 0, 0"/>"#, "no length"),
            (r#"<float name="radius" value="0"/>"#, "must be positive"),
            (r#"<transform name="to_world"><scale x="2"/></transform>"#, "elliptic"),
            (r#"<transform name="to_world"><scale z="-1"/></transform>"#, "mirroring"),
        ] {
            let e = error(&format!(r#"<shape type="cylinder">{body}</shape>"#));
            assert!(e.contains("<shape type=\"cylinder\">") && e.contains(says), "{e}");
        }
    }

    #[test]
    fn sphere_from_center_radius_or_to_world_matches_toml() {
        let want = Sphere {
            center: Vec3::new(1.0, 2.0, 3.0),
            radius: 0.5,
            material: 1,
        };
        for body in [
            r#"<point name="center" x="1" y="2" z="3"/><float name="radius" value="0.5"/>"#,
            r#"<point name="center" value="1, 2, 3"/><float name="radius" value="0.5"/>"#,
            r#"<transform name="to_world"><scale value="0.5"/><translate x="1" y="2" z="3"/></transform>"#,
            // Both: centre and radius first, then to_world.
            r#"<float name="radius" value="0.25"/><transform name="to_world"><scale value="2"/><translate x="1" y="2" z="3"/></transform>"#,
        ] {
            let s = load_body(&format!(r#"<shape type="sphere">{body}<bsdf type="diffuse"/></shape>"#)).unwrap();
            let got = s.spheres[0];
            assert!(
                got.center.distance(want.center) < 1e-6 && (got.radius - want.radius).abs() < 1e-6,
                "{body}: {got:?}"
            );
        }
        let e = error(r#"<shape type="sphere"><transform name="to_world"><scale x="2"/></transform></shape>"#);
        assert!(
            e.contains("<shape type=\"sphere\">") && e.contains("non-uniformly"),
            "{e}"
        );
    }

    /// A unit square at z = 0 as two triangles facing +z, as an OBJ and an ASCII PLY (one quad face).
    fn write_square_meshes(dir: &TempDir) {
        dir.write(
            "sq.obj",
            "mtllib ignored.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nusemtl nothing\nf 1 2 3 4\n",
        );
        dir.write(
            "sq.ply",
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
             element face 1\nproperty list uchar int vertex_indices\nend_header\n-1 -1 0\n1 -1 0\n1 1 0\n-1 1 0\n4 0 1 2 3\n",
        );
    }

    /// Most published meshes are binary PLY: both byte orders, double positions, float normals, texture
    /// coordinates (read past, not used yet) and an int index list give the mesh the ASCII file gives.
    #[test]
    fn binary_ply_in_both_byte_orders_reads_as_ascii() {
        let dir = TempDir::new("mitsuba-ply");
        let corners = [
            [-1.0f64, -1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
        ];
        let header = |format: &str| {
            format!(
                "ply\nformat {format} 1.0\ncomment written by a test\nelement vertex 4\nproperty double x\n\
                 property double y\nproperty double z\nproperty float nx\nproperty float ny\nproperty float nz\n\
                 property float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
            )
        };
        for (format, big) in [("binary_little_endian", false), ("binary_big_endian", true)] {
            let mut bytes = header(format).into_bytes();
            let mut put = |b: &[u8]| {
                let mut b = b.to_vec();
                if big {
                    b.reverse();
                }
                bytes.extend_from_slice(&b);
            };
            for (i, c) in corners.iter().enumerate() {
                for x in c {
                    put(&x.to_le_bytes());
                }
                for n in [0.0f32, 0.0, 1.0] {
                    put(&n.to_le_bytes());
                }
                for t in [(i % 2) as f32, (i / 2) as f32] {
                    put(&t.to_le_bytes());
                }
            }
            put(&[4u8]); // the list's length (one byte: the same in either order)
            for i in 0..4i32 {
                put(&i.to_le_bytes());
            }
            std::fs::write(dir.0.join(format!("{format}.ply")), &bytes).unwrap();
        }
        write_square_meshes(&dir);
        let mesh = |file: &str| {
            let body = format!(r#"<shape type="ply"><string name="filename" value="{file}"/></shape>"#);
            let s = load_in(&dir, &body, &[]).unwrap_or_else(|e| panic!("{file}: {e:#}"));
            s.meshes[0].clone()
        };
        let ascii = mesh("sq.ply");
        for format in ["binary_little_endian", "binary_big_endian"] {
            let m = mesh(&format!("{format}.ply"));
            assert_eq!(m.positions, ascii.positions, "{format}");
            assert_eq!(m.indices, ascii.indices, "{format}");
            assert_eq!(
                m.normals.as_deref(),
                Some(&[Vec3::Z; 4][..]),
                "{format}: the normals are read"
            );
        }
    }

    /// A mesh without normals gets Mitsuba's own (angle-weighted: its `recompute_vertex_normals`), unless
    /// `face_normals` asks for flat shading. The expected normals are Mitsuba 3.9's for this file
    /// (`mi.load_dict({'type': 'obj', ...}).vertex_normal(i)`, scalar_rgb).
    #[test]
    fn meshes_without_normals_get_mitsubas_vertex_normals() {
        let dir = TempDir::new("mitsuba-normals");
        dir.write("fold.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0.5\nf 1 2 3\nf 2 4 3\n");
        let shape = |face_normals: &str| {
            format!(
                r#"<shape type="obj"><string name="filename" value="fold.obj"/>
                   <boolean name="face_normals" value="{face_normals}"/><bsdf type="diffuse"/></shape>"#
            )
        };
        let s = load_in(&dir, &shape("false"), &[]).unwrap();
        let normals = s.meshes[0].normals.as_ref().expect("computed normals");
        let mitsuba = [
            Vec3::Z,
            Vec3::new(-0.227046, -0.227046, 0.947048),
            Vec3::new(-0.227046, -0.227046, 0.947048),
            Vec3::new(-0.408248, -0.408248, 0.816497),
        ];
        // Our loader keeps the file's vertex order for a mesh of positions only.
        for (i, (n, want)) in normals.iter().zip(mitsuba).enumerate() {
            assert!(n.distance(want) < 1e-5, "vertex {i}: {n} against Mitsuba's {want}");
        }
        assert!(load_in(&dir, &shape("true"), &[]).unwrap().meshes[0].normals.is_none());
    }

    #[test]
    fn obj_and_ply_match_the_rectangle_with_to_world_and_flip() {
        let dir = TempDir::new("mitsuba-mesh");
        write_square_meshes(&dir);
        for kind in ["obj", "ply"] {
            for (flip, normal) in [("false", Vec3::Y), ("true", Vec3::NEG_Y)] {
                let s = load_in(
                    &dir,
                    &format!(
                        r#"<shape type="{kind}"><string name="filename" value="sq.{kind}"/>
                           <boolean name="flip_normals" value="{flip}"/>
                           <transform name="to_world"><rotate x="1" angle="-90"/><translate y="1"/></transform>
                           <bsdf type="twosided"><bsdf type="diffuse"/></bsdf></shape>"#
                    ),
                    &[],
                )
                .unwrap_or_else(|e| panic!("{kind}: {e:#}"));
                let m = &s.meshes[0];
                assert_eq!(m.indices.len(), 2, "{kind}");
                let area: f32 = m.triangles().map(|t| t.area()).sum();
                assert!((area - 4.0).abs() < 1e-5, "{kind}: area {area}");
                for t in m.triangles() {
                    assert!(t.normal().distance(normal) < 1e-5, "{kind} flip {flip}: {}", t.normal());
                    assert!(t.p.iter().all(|p| (p.y - 1.0).abs() < 1e-6));
                }
                // The bsdf is the XML's: the MTL is never read.
                assert_eq!(
                    s.materials[m.materials[0] as usize].surface,
                    Surface::Diffuse {
                        albedo: Vec3::splat(0.5)
                    }
                );
            }
        }
        let e = format!(
            "{:#}",
            load_in(
                &dir,
                r#"<shape type="ply"><string name="filename" value="none.ply"/></shape>"#,
                &[]
            )
            .unwrap_err()
        );
        assert!(
            e.contains("<shape type=\"ply\">") && e.contains("none.ply: cannot read PLY file"),
            "{e}"
        );
    }

    /// The texture coordinates a quad gives world point `p`: its coordinates along edge_u and edge_v,
    /// through its material's texture's to_uv.
    fn quad_uv(s: &Scene, q: &Quad, p: Vec3) -> Vec2 {
        let (u, v, d) = (q.edge_u, q.edge_v, p - q.origin);
        // The dual basis of (u, v) in their plane.
        let n = u.cross(v);
        let (a, b) = (
            d.dot(v.cross(n)) / u.dot(v.cross(n)),
            d.dot(u.cross(n)) / v.dot(u.cross(n)),
        );
        let m = s.textures[s.materials[q.material as usize].texture.unwrap() as usize].to_uv;
        Vec2::new(m[0] * a + m[1] * b + m[2], m[3] * a + m[4] * b + m[5])
    }

    #[test]
    fn a_textured_rectangle_has_mitsubas_uv_turned_or_not() {
        let dir = TempDir::new("mitsuba-tex-rect");
        write_texture(&dir, "t.png");
        // Mitsuba 3.9.1: the local point (0.3, -0.6, 0) of a rectangle has uv (0.65, 0.2) whatever to_world
        // and flip_normals do; its world position, and the side its area emitter lights, for each.
        let cases: &[(&str, &str, Vec3, Vec3)] = &[
            ("", "false", Vec3::new(0.3, -0.6, 0.0), Vec3::Z),
            ("", "true", Vec3::new(0.3, -0.6, 0.0), Vec3::NEG_Z),
            (r#"<scale x="-1"/>"#, "false", Vec3::new(-0.3, -0.6, 0.0), Vec3::Z),
            (r#"<scale x="-1"/>"#, "true", Vec3::new(-0.3, -0.6, 0.0), Vec3::NEG_Z),
            (
                r#"<scale x="2" y="-3"/><rotate x="1" angle="-90"/><translate y="1"/>"#,
                "false",
                Vec3::new(0.6, 1.0, -1.8),
                Vec3::Y,
            ),
        ];
        for (transform, flip, p, normal) in cases {
            let s = load_in(
                &dir,
                &format!(
                    r#"<shape type="rectangle"><transform name="to_world">{transform}</transform>
                       <boolean name="flip_normals" value="{flip}"/>
                       <bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="t.png"/>
                         <transform name="to_uv"><scale x="2"/><translate y="0.25"/></transform></texture></bsdf></shape>"#
                ),
                &[],
            )
            .unwrap_or_else(|e| panic!("{e:#}"));
            let q = s.quads[1];
            let uv = quad_uv(&s, &q, *p);
            // Mitsuba's uv through the texture's own to_uv: (2 u, v + 0.25).
            let want = Vec2::new(2.0 * 0.65, 0.2 + 0.25);
            assert!(
                uv.distance(want) < 1e-5,
                "{transform} flip {flip}: uv {uv}, want {want}"
            );
            assert!(
                q.normal().distance(*normal) < 1e-5,
                "{transform} flip {flip}: normal {}",
                q.normal()
            );
            s.validate().unwrap();
        }
    }

    #[test]
    fn textured_meshes_need_texture_coordinates() {
        let dir = TempDir::new("mitsuba-tex-mesh");
        write_texture(&dir, "t.png");
        let tex = r#"<bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="t.png"/></texture></bsdf>"#;
        dir.write(
            "uv.obj",
            "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nvt 0.1 0.2\nvt 0.9 0.2\nvt 0.9 0.8\nf 1/1 2/2 3/3\n",
        );
        // Mitsuba flips an OBJ's v unless flip_tex_coords is false.
        for (flag, want) in [
            ("", [Vec2::new(0.1, 0.8), Vec2::new(0.9, 0.8), Vec2::new(0.9, 0.2)]),
            (
                r#"<boolean name="flip_tex_coords" value="true"/>"#,
                [Vec2::new(0.1, 0.8), Vec2::new(0.9, 0.8), Vec2::new(0.9, 0.2)],
            ),
            (
                r#"<boolean name="flip_tex_coords" value="false"/>"#,
                [Vec2::new(0.1, 0.2), Vec2::new(0.9, 0.2), Vec2::new(0.9, 0.8)],
            ),
        ] {
            let s = load_in(
                &dir,
                &format!(r#"<shape type="obj"><string name="filename" value="uv.obj"/>{flag}{tex}</shape>"#),
                &[],
            )
            .unwrap_or_else(|e| panic!("{e:#}"));
            let m = &s.meshes[0];
            let got: Vec<Vec2> = m.indices[0]
                .iter()
                .map(|&i| m.uvs.as_ref().unwrap()[i as usize])
                .collect();
            assert!(
                got.iter().zip(want).all(|(g, w)| g.distance(w) < 1e-6),
                "{flag}: {got:?}"
            );
            assert!(s.materials[m.materials[0] as usize].texture.is_some());
        }
        // PLY: s and t, not flipped (Mitsuba's ply reader does not).
        dir.write(
            "st.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
             property float s\nproperty float t\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
             -1 -1 0 0.1 0.2\n1 -1 0 0.9 0.2\n1 1 0 0.9 0.8\n3 0 1 2\n",
        );
        let s = load_in(
            &dir,
            &format!(r#"<shape type="ply"><string name="filename" value="st.ply"/>{tex}</shape>"#),
            &[],
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        assert_eq!(
            s.meshes[0].uvs.as_deref(),
            Some(&[Vec2::new(0.1, 0.2), Vec2::new(0.9, 0.2), Vec2::new(0.9, 0.8)][..])
        );
        // Without texture coordinates: refused, the file named.
        write_square_meshes(&dir);
        for kind in ["obj", "ply"] {
            let e = format!(
                "{:#}",
                load_in(
                    &dir,
                    &format!(r#"<shape type="{kind}"><string name="filename" value="sq.{kind}"/>{tex}</shape>"#),
                    &[]
                )
                .unwrap_err()
            );
            assert!(
                e.contains(&format!("scene.xml:12:1: <shape type=\"{kind}\">: "))
                    && e.contains(&format!("sq.{kind}: no texture coordinates")),
                "{e}"
            );
        }
    }

    #[test]
    fn ply_texture_coordinates_under_each_name_and_type() {
        let dir = TempDir::new("mitsuba-ply-uv");
        let uv = [[0.1f64, 0.2], [0.9, 0.2], [0.9, 0.8]];
        let want: Vec<Vec2> = uv.iter().map(|t| Vec2::new(t[0] as f32, t[1] as f32)).collect();
        let body = |file: &str| format!(r#"<shape type="ply"><string name="filename" value="{file}"/></shape>"#);
        // ASCII, each name Mitsuba reads; texture_s/texture_t Mitsuba 3.9 ignores ("can't start with postfix").
        for (a, b, read) in [
            ("u", "v", true),
            ("texture_u", "texture_v", true),
            ("s", "t", true),
            ("texture_s", "texture_t", false),
        ] {
            let mut text = format!(
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                 property float {a}\nproperty float {b}\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
            );
            for (p, t) in [[-1, -1], [1, -1], [1, 1]].iter().zip(uv) {
                text += &format!("{} {} 0 {} {}\n", p[0], p[1], t[0], t[1]);
            }
            text += "3 0 1 2\n";
            dir.write("a.ply", &text);
            let s = load_in(&dir, &body("a.ply"), &[]).unwrap_or_else(|e| panic!("{a}: {e:#}"));
            assert_eq!(s.meshes[0].uvs.as_deref(), read.then_some(&want[..]), "{a} {b}");
        }
        // Binary, both byte orders, float and double; integer ones are not read (Mitsuba rescales them).
        for (format, big) in [("binary_little_endian", false), ("binary_big_endian", true)] {
            for kind in ["float", "double", "uchar"] {
                let mut bytes = format!(
                    "ply\nformat {format} 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                     property {kind} u\nproperty {kind} v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                )
                .into_bytes();
                let mut put = |b: &[u8]| {
                    let mut b = b.to_vec();
                    if big {
                        b.reverse();
                    }
                    bytes.extend_from_slice(&b);
                };
                for (p, t) in [[-1.0f32, -1.0], [1.0, -1.0], [1.0, 1.0]].iter().zip(uv) {
                    for x in [p[0], p[1], 0.0] {
                        put(&x.to_le_bytes());
                    }
                    for x in t {
                        match kind {
                            "float" => put(&(x as f32).to_le_bytes()),
                            "double" => put(&x.to_le_bytes()),
                            _ => put(&[(x * 255.0) as u8]),
                        }
                    }
                }
                put(&[3u8]);
                for i in 0..3i32 {
                    put(&i.to_le_bytes());
                }
                std::fs::write(dir.0.join("b.ply"), &bytes).unwrap();
                let s = load_in(&dir, &body("b.ply"), &[]).unwrap_or_else(|e| panic!("{format} {kind}: {e:#}"));
                let expected = (kind != "uchar").then_some(&want[..]);
                assert_eq!(s.meshes[0].uvs.as_deref(), expected, "{format} {kind}");
            }
        }
    }
}

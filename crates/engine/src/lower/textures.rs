//! Texels: the textures in texture.glsl's layout, and per BVH triangle what shading reads of it (texture
//! coordinates, dp/du from them, vertex normals).

use glam::Vec3;
use ppm_vk_kernels::layout::{self, Triangle};

use crate::scene::Scene;

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
pub fn triangle_texels(scene: &Scene, triangles: &[Triangle]) -> Vec<[u32; 4]> {
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

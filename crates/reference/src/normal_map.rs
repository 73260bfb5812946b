//! Bump and normal maps, as `shaders/materials/normal_map.glsl` (Mitsuba 3's src/bsdfs/bumpmap.cpp and
//! normalmap.cpp): the perturbed shading normal at a hit and the shadowing term it gives the BSDF.

use glam::{IVec2, Vec2, Vec3};
use ppm_vk_kernels::layout::{FILTER_NEAREST, NORMAL_MAP_BUMP, TEXTURE_BITMAP};
pub use ppm_vk_materials::normal_map::Bump;
use ppm_vk_materials::normal_map::{bumped, mapped};

use super::texture::{pixel, texel_rgb, value};
use super::trace::Hit;
use ppm_vk_engine::lower::GpuScene;

/// normal_map.glsl's `texture_gradient` (Mitsuba's bitmap eval_1_grad).
pub fn texture_gradient(texels: &[[u32; 4]], at: u32, uv: Vec2) -> Vec2 {
    let head = texels[at as usize];
    if head[0] & 15 != TEXTURE_BITMAP || (head[0] >> 4) & 15 == FILTER_NEAREST {
        return Vec2::ZERO;
    }
    let r0 = texel_rgb(texels[at as usize + 1]);
    let r1 = texel_rgb(texels[at as usize + 2]);
    let st = Vec2::new(r0.x * uv.x + r0.y * uv.y + r0.z, r1.x * uv.x + r1.y * uv.y + r1.z);
    let wrap = (head[0] >> 8) & 15;
    let size = IVec2::new(head[1] as i32, head[2] as i32);
    let p = st * size.as_vec2() - Vec2::splat(0.5);
    let i = p.floor().as_ivec2();
    let w1 = p - i.as_vec2();
    let w0 = Vec2::ONE - w1;
    let y = Vec3::new(0.212671, 0.715160, 0.072169);
    let f = |dx: i32, dy: i32| y.dot(pixel(texels, head[3], size, i + IVec2::new(dx, dy), wrap));
    let (f00, f10, f01, f11) = (f(0, 0), f(1, 0), f(0, 1), f(1, 1));
    let df = Vec2::new(
        w0.y * (f10 - f00) + w1.y * (f11 - f01),
        w0.x * (f01 - f00) + w1.x * (f11 - f10),
    );
    size.as_vec2() * Vec2::new(r0.x * df.x + r1.x * df.y, r0.y * df.x + r1.y * df.y)
}

/// normal_map.glsl's `mapped_normal`: the shading normal at `h` with its material's map applied, on the
/// side of `ng` (`ns`: the unperturbed one, on that side), and its shadowing term.
pub fn perturb(g: &GpuScene, h: &Hit, ng: Vec3, ns: Vec3) -> (Vec3, Bump) {
    let record = g.materials[h.material as usize].normal_map;
    if record == 0 {
        return (ns, Bump::default());
    }
    let r = g.textures[record as usize - 1];
    let front = h.normal;
    let n0 = if ns.dot(front) < 0.0 { -ns } else { ns };
    let [dpdu, dpdv] = h.dp;
    let n = if r[0] == NORMAL_MAP_BUMP {
        let grad = f32::from_bits(r[2]) * texture_gradient(&g.textures, r[1], h.uv);
        if grad == Vec2::ZERO {
            return (ns, Bump::default());
        }
        bumped(dpdu, dpdv, n0, grad, front)
    } else {
        let c = 2.0 * value(&g.textures, r[1], h.uv) - Vec3::ONE;
        if c.x == 0.0 && c.y == 0.0 && c.z > 0.0 {
            return (ns, Bump::default());
        }
        mapped(dpdu, n0, c)
    };
    let bump = Bump::of(n, n0);
    (if n.dot(ng) < 0.0 { -n } else { n }, bump)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::{sphere_derivatives, triangle_derivatives};

    /// A sphere's derivatives are Mitsuba's: at the equator on +x, dp/du = 2 pi r y and dp/dv = -pi r z.
    #[test]
    fn sphere_derivatives_at_the_equator() {
        let [du, dv] = sphere_derivatives(Vec3::X, 2.0);
        let pi = ppm_vk_materials::math::PI;
        assert!((du - Vec3::new(0.0, 4.0 * pi, 0.0)).length() < 1e-5, "{du}");
        assert!((dv - Vec3::new(0.0, 0.0, -2.0 * pi)).length() < 1e-5, "{dv}");
    }

    /// A triangle's uv derivatives: corners (0,0,0), (2,0,0), (0,3,0) with uv (0,0), (1,0), (0,1) give
    /// dp/du = (2,0,0) and dp/dv = (0,3,0).
    #[test]
    fn triangle_derivatives_follow_the_texture_coordinates() {
        let [du, dv] = triangle_derivatives(
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 3.0, 0.0),
            [Vec2::ZERO, Vec2::X, Vec2::Y],
        );
        assert_eq!((du, dv), (Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.0)));
    }
}

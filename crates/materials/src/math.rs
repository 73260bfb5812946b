//! The leaf math the BSDFs, the host and the CPU twin share: the same f32 operations as
//! `shaders/common/geometry.glsl`, `sampling.glsl` and microfacet.glsl's frames, and the octahedral
//! encoding of unit vectors the kernels' records hold.

use glam::{Vec2, Vec3};

pub const PI: f32 = std::f32::consts::PI;

pub fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
}

/// GLSL's reflect(d, n) = d - 2 dot(n, d) n.
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * n.dot(d) * n
}

/// microfacet.glsl's `frame`: the tangent along `dpdu` made orthogonal to `nf`, or `onb(nf)` where
/// `dpdu` is 0 or along `nf`.
pub fn frame(nf: Vec3, dpdu: Vec3) -> (Vec3, Vec3) {
    let s = dpdu - nf * nf.dot(dpdu);
    let l = s.dot(s);
    if l > 1e-12 * dpdu.dot(dpdu) {
        let t = s * (1.0 / l.sqrt());
        (t, nf.cross(t))
    } else {
        onb(nf)
    }
}

/// `d` in the local frame (t, b, nf).
pub fn to_local(d: Vec3, t: Vec3, b: Vec3, nf: Vec3) -> Vec3 {
    Vec3::new(d.dot(t), d.dot(b), d.dot(nf))
}

pub fn onb(n: Vec3) -> (Vec3, Vec3) {
    let s = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (s + n.z);
    let c = n.x * n.y * a;
    (
        Vec3::new(1.0 + s * n.x * n.x * a, s * c, -s * n.x),
        Vec3::new(c, s + n.y * n.y * a, -n.y),
    )
}

pub fn cosine_direction(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let (t, b) = onb(n);
    (r * phi.cos() * t + r * phi.sin() * b + (1.0 - u1).max(0.0).sqrt() * n).normalize()
}

/// (reflectance, transmitted cosine); reflectance 1 on total internal reflection.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> (f32, f32) {
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (0.5 * (rs * rs + rp * rp), cos_t)
}

fn sign_not_zero(x: f32) -> f32 {
    if x >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

/// GLSL packSnorm2x16.
fn pack_snorm2x16(p: Vec2) -> u32 {
    let q = |x: f32| ((x.clamp(-1.0, 1.0) * 32767.0).round() as i16) as u16 as u32;
    q(p.x) | (q(p.y) << 16)
}

fn unpack_snorm2x16(e: u32) -> Vec2 {
    let f = |b: u32| ((b as u16 as i16) as f32 / 32767.0).clamp(-1.0, 1.0);
    Vec2::new(f(e & 0xffff), f(e >> 16))
}

pub fn oct_encode(v: Vec3) -> u32 {
    let mut p = Vec2::new(v.x, v.y) / (v.x.abs() + v.y.abs() + v.z.abs());
    if v.z < 0.0 {
        p = (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs())) * Vec2::new(sign_not_zero(p.x), sign_not_zero(p.y));
    }
    pack_snorm2x16(p)
}

pub fn oct_decode(e: u32) -> Vec3 {
    let p = unpack_snorm2x16(e);
    let mut v = Vec3::new(p.x, p.y, 1.0 - p.x.abs() - p.y.abs());
    if v.z < 0.0 {
        let xy = (Vec2::ONE - Vec2::new(v.y.abs(), v.x.abs())) * Vec2::new(sign_not_zero(v.x), sign_not_zero(v.y));
        v.x = xy.x;
        v.y = xy.y;
    }
    v.normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn octahedral_round_trip() {
        for (i, v) in [
            Vec3::X,
            -Vec3::Y,
            Vec3::new(0.3, -0.5, -0.8),
            Vec3::new(-0.1, 0.2, 0.97),
        ]
        .iter()
        .enumerate()
        {
            let v = v.normalize();
            let back = oct_decode(oct_encode(v));
            assert!((back - v).length() < 1e-4, "case {i}: {v} -> {back}");
        }
    }

    #[test]
    fn fresnel_limits() {
        // Normal incidence on n = 1.5: ((1 - 1.5) / (1 + 1.5))^2 = 0.04.
        let (f, cos_t) = fresnel_dielectric(1.0, 1.0 / 1.5);
        assert!((f - 0.04).abs() < 1e-6 && (cos_t - 1.0).abs() < 1e-6);
        // Past the critical angle from inside (sin > 1/1.5): total internal reflection.
        assert_eq!(fresnel_dielectric(0.5, 1.5).0, 1.0);
    }

    #[test]
    fn cosine_directions_are_in_the_hemisphere() {
        let n = Vec3::new(0.0, -1.0, 0.0);
        let mut rng = crate::rng::Rng::new(7, 1);
        let mut mean_cos = 0.0;
        for _ in 0..20_000 {
            let d = cosine_direction(n, rng.float(), rng.float());
            assert!(d.dot(n) >= 0.0 && (d.length() - 1.0).abs() < 1e-5);
            mean_cos += d.dot(n) as f64;
        }
        // E[cos] under a cosine-weighted hemisphere is 2/3.
        assert!((mean_cos / 20_000.0 - 2.0 / 3.0).abs() < 0.01);
    }
}

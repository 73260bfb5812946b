//! Generated meshes: the tests' closed shapes and triangle soups, and the build benchmark's input. Shared
//! vertices are computed once per grid point, so the triangles around them see them bit for bit.

use std::f32::consts::PI;

use glam::Vec3;

use crate::rng::Rng;
use ppm_vk_engine::bvh::TriangleInput;

fn tri(a: Vec3, b: Vec3, c: Vec3, material: u32) -> TriangleInput {
    TriangleInput { v: [a, b, c], material }
}

/// A closed UV sphere: `rings` bands from pole to pole, `segments` around, fans at the poles;
/// counter-clockwise seen from outside. 2 segments (rings - 1) triangles.
pub fn uv_sphere(center: Vec3, radius: f32, rings: u32, segments: u32, material: u32) -> Vec<TriangleInput> {
    assert!(rings >= 2 && segments >= 3);
    let vertex = |ring: u32, seg: u32| -> Vec3 {
        match ring {
            0 => center + radius * Vec3::Z,
            r if r == rings => center - radius * Vec3::Z,
            r => {
                let theta = PI * r as f32 / rings as f32;
                let phi = 2.0 * PI * (seg % segments) as f32 / segments as f32;
                center + radius * Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
            }
        }
    };
    let mut out = Vec::with_capacity(2 * (segments * (rings - 1)) as usize);
    for r in 0..rings {
        for s in 0..segments {
            let (a, b, c, d) = (vertex(r, s), vertex(r + 1, s), vertex(r + 1, s + 1), vertex(r, s + 1));
            if r + 1 < rings {
                out.push(tri(a, b, c, material));
            }
            if r > 0 {
                out.push(tri(a, c, d, material));
            }
        }
    }
    out
}

/// The closed box [lo, hi], each face an n x n grid of cells cut along a diagonal: 12 n^2 triangles,
/// counter-clockwise seen from outside.
pub fn box_grid(lo: Vec3, hi: Vec3, n: u32, material: u32) -> Vec<TriangleInput> {
    let point = |g: [u32; 3]| lo + (hi - lo) * (Vec3::new(g[0] as f32, g[1] as f32, g[2] as f32) / n as f32);
    let mut out = Vec::with_capacity(12 * (n * n) as usize);
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in [0, n] {
            for i in 0..n {
                for j in 0..n {
                    let corner = |di: u32, dj: u32| {
                        let mut g = [0; 3];
                        g[axis] = side;
                        g[u] = i + di;
                        g[v] = j + dj;
                        point(g)
                    };
                    let (p00, p10, p11, p01) = (corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1));
                    // cross(u, v) is +axis: the far face winds u then v, the near one the other way.
                    if side == n {
                        out.push(tri(p00, p10, p11, material));
                        out.push(tri(p00, p11, p01, material));
                    } else {
                        out.push(tri(p00, p11, p10, material));
                        out.push(tri(p00, p01, p11, material));
                    }
                }
            }
        }
    }
    out
}

/// `n` random triangles: centres uniform in [0, extent]^3, vertices within `size` of them per axis.
pub fn random_soup(seed: u64, n: usize, extent: f32, size: f32) -> Vec<TriangleInput> {
    let mut rng = Rng::new(seed, 0x5005);
    let mut v3 = |s: f32, off: f32| Vec3::new(rng.float(), rng.float(), rng.float()) * s + Vec3::splat(off);
    (0..n)
        .map(|i| {
            let c = v3(extent, 0.0);
            let (a, b, d) = (v3(2.0 * size, -size), v3(2.0 * size, -size), v3(2.0 * size, -size));
            tri(c + a, c + b, c + d, i as u32 % 7)
        })
        .collect()
}

/// `n` triangles side by side along x, each `ratio` times the size of the one before: SAH peels the
/// largest off at every level, so without the depth limit the tree would be about n deep.
pub fn growing_chain(n: u32, ratio: f32) -> Vec<TriangleInput> {
    let mut out = Vec::new();
    let (mut x, mut s) = (0.0f32, 1.0f32);
    for _ in 0..n {
        out.push(tri(
            Vec3::new(x, 0.0, 0.0),
            Vec3::new(x + s, 0.0, 0.0),
            Vec3::new(x, s, s),
            0,
        ));
        x += s;
        s *= ratio;
    }
    out
}

//! Geometry over a lowered scene, the same f32 operations as `shaders/common/geometry.glsl` and
//! `grid.glsl`; the leaf math it shares with the host (reflection, frames, Fresnel, octahedral codes) is
//! ppm_vk_materials::math.

use glam::{Vec2, Vec3};
use ppm_vk_kernels::inline_pairs::{self, InlinePair};
use ppm_vk_kernels::layout::QUAD_DISK;
use ppm_vk_materials::mask;
use ppm_vk_materials::math::{fresnel_dielectric, oct_decode, reflect, PI};

use ppm_vk_engine::lower::GpuScene;

/// Also here for the BVH's tests and the bvh_trace example, which import them by this path.
pub use ppm_vk_materials::math::{cosine_direction, v3};

pub struct Hit {
    pub pos: Vec3,
    pub normal: Vec3,
    pub material: u32,
    /// Texture coordinates (texture.glsl's `surface_uv`).
    pub uv: Vec2,
    /// A smooth-shaded triangle's interpolated vertex normal, not yet turned to any side and `None` where
    /// the vertex normals cancel (shading.glsl's `shading_normal`; `super::shading::normal` turns it).
    pub smooth: Option<Vec3>,
    /// Mitsuba's dp/du, not unit (geometry.glsl's `surface_tangent`).
    pub dpdu: Vec3,
    /// A sphere's (geometry.glsl's HIT_SPHERE): glossy_light.glsl weighs their emission apart.
    pub sphere: bool,
    /// Mitsuba's dp/du and dp/dv, not unit, as a bump or normal map reads them (normal_map.glsl's
    /// `surface_derivatives`).
    pub dp: [Vec3; 2],
}

/// `key`: the ray's mask key (mask::key).
pub fn intersect_scene(g: &GpuScene, o: Vec3, d: Vec3, tmin: f32, tmax: f32, key: u32) -> Option<Hit> {
    let mut best = tmax;
    let mut found: Option<(u32, usize)> = None;
    // A quad's planar coordinates, a triangle's barycentric weights of v1 and v2.
    let mut local = Vec2::ZERO;
    for (i, s) in g.spheres.iter().enumerate() {
        // geometry.glsl: the discriminant without cancellation, the near root as c / q.
        let oc = o - v3(s.center);
        let b = oc.dot(d);
        let f = oc - b * d;
        let r2 = s.radius * s.radius;
        let disc = r2 - f.dot(f);
        if disc < 0.0 {
            continue;
        }
        let q = -(b + if b >= 0.0 { disc.sqrt() } else { -disc.sqrt() });
        if q == 0.0 {
            continue;
        }
        let t0 = (oc.dot(oc) - r2) / q;
        let mut t = t0.min(q);
        // geometry.glsl's sphere_stops: a masked sphere passed at its near side may stop the ray at its far.
        let stops = |far: bool, t: f32| {
            let normal = (o + t * d - v3(s.center)) * (1.0 / s.radius);
            super::mask::keeps(
                g,
                s.material,
                key,
                mask::PRIM_SPHERE | (2 * i as u32 + far as u32),
                || sphere_uv(normal),
            )
        };
        let mut far = t <= tmin;
        if !far && t < best && !stops(false, t) {
            far = true;
        }
        if far {
            t = t0.max(q);
        }
        if t > tmin && t < best && (!far || stops(true, t)) {
            best = t;
            found = Some((0, i));
        }
    }
    for (i, q) in g.quads.iter().enumerate() {
        let n = v3(q.normal);
        let denom = n.dot(d);
        if denom.abs() < 1e-12 {
            continue;
        }
        let t = (q.plane_d - n.dot(o)) / denom;
        if t <= tmin || t >= best {
            continue;
        }
        let rel = o + t * d - v3(q.origin);
        let a = v3(q.w).dot(rel.cross(v3(q.edge_v)));
        let b = v3(q.w).dot(v3(q.edge_u).cross(rel));
        if !(0.0..=1.0).contains(&a) || !(0.0..=1.0).contains(&b) {
            continue;
        }
        // A disk: only the ellipse inscribed in the parallelogram.
        if q.shape == QUAD_DISK && (2.0 * a - 1.0) * (2.0 * a - 1.0) + (2.0 * b - 1.0) * (2.0 * b - 1.0) > 1.0 {
            continue;
        }
        if !super::mask::keeps(g, q.material, key, mask::PRIM_QUAD | i as u32, || Vec2::new(a, b)) {
            continue;
        }
        best = t;
        found = Some((1, i));
        local = Vec2::new(a, b);
    }
    // geometry.glsl's bvh_filter: a masked triangle may let the ray pass.
    let keep = |tri: u32, bary: Vec2| {
        let m = g.bvh_triangles[tri as usize].material;
        super::mask::keeps(g, m, key, tri, || triangle_uv(g, tri as usize, bary))
    };
    if g.triangles_inline {
        // Written into the kernels: the pairs, then the triangles left single, in order, each by its plane,
        // the first of equal t winning, as geometry.glsl.
        for p in &g.inline_pairs {
            let hit = inline_pair_test(o, d, p, tmin, best).filter(|&(i, _, bary)| keep(i, bary));
            if let Some((i, t, bary)) = hit {
                best = t;
                found = Some((2, i as usize));
                local = bary;
            }
        }
        for &i in &g.inline_singles {
            let tr = &g.bvh_triangles[i as usize];
            let hit = inline_triangle_test(o, d, tr, tmin, best).filter(|&(_, bary)| keep(i, bary));
            if let Some((t, bary)) = hit {
                best = t;
                found = Some((2, i as usize));
                local = bary;
            }
        }
    } else if !g.bvh_triangles.is_empty() {
        // Unlimited budget: where the GPU's traversal is cut, the renderer fails instead.
        let tr = super::bvh::intersect_filtered(&g.bvh_nodes, &g.bvh_triangles, o, d, tmin, best, u32::MAX, keep);
        if let Some(h) = tr.hit {
            best = h.t;
            found = Some((2, h.triangle as usize));
            local = h.bary;
        }
    }
    let (kind, i) = found?;
    let pos = o + best * d;
    Some(match kind {
        0 => {
            let s = &g.spheres[i];
            let normal = (pos - v3(s.center)) * (1.0 / s.radius);
            Hit {
                pos,
                normal,
                material: s.material,
                uv: sphere_uv(normal),
                smooth: None,
                dpdu: Vec3::new(-normal.y, normal.x, 0.0),
                sphere: true,
                dp: sphere_derivatives(normal, 1.0 / (1.0 / s.radius)),
            }
        }
        1 => Hit {
            pos,
            normal: v3(g.quads[i].normal),
            material: g.quads[i].material,
            uv: local,
            smooth: None,
            dpdu: v3(g.quads[i].edge_u),
            sphere: false,
            dp: [v3(g.quads[i].edge_u), v3(g.quads[i].edge_v)],
        },
        _ => {
            let t = &g.bvh_triangles[i];
            // Interpolated from the vertices' (texture.glsl's surface_uv); zero where no mesh has them.
            let stride = ppm_vk_kernels::layout::TRIANGLE_TEXELS as usize;
            let texels = g.triangle_texels.get(stride * i..stride * (i + 1));
            let f = |b: u32| f32::from_bits(b);
            let w = [1.0 - local.x - local.y, local.x, local.y];
            let uv = triangle_uv(g, i, local);
            // The vertex normals interpolated (shading.glsl's shading_normal).
            let smooth = texels.filter(|t| t[2][3] != 0).and_then(|t| {
                let n = w[0] * oct_decode(t[2][0]) + w[1] * oct_decode(t[2][1]) + w[2] * oct_decode(t[2][2]);
                let l = n.dot(n);
                (l > 0.0).then(|| n * (1.0 / l.sqrt()))
            });
            let normal = super::bvh::normal(t);
            let dpdu = match texels {
                Some(t) if t[1][3] != 0 => oct_decode(t[1][2]),
                _ => v3(t.v1) - v3(t.v0),
            };
            let (e1, e2) = (v3(t.v1) - v3(t.v0), v3(t.v2) - v3(t.v0));
            let dp = match texels {
                Some(t) => triangle_derivatives(
                    e1,
                    e2,
                    [
                        Vec2::new(f(t[0][0]), f(t[0][1])),
                        Vec2::new(f(t[0][2]), f(t[0][3])),
                        Vec2::new(f(t[1][0]), f(t[1][1])),
                    ],
                ),
                None => [e1, e2],
            };
            Hit {
                pos,
                normal,
                material: t.material,
                uv,
                smooth,
                dpdu,
                sphere: false,
                dp,
            }
        }
    })
}

/// geometry.glsl's `inline_triangle_test`: a triangle of a small mesh tested by its plane, as a quad is
/// (not watertight, unlike the BVH's test). Its hit's distance and weights of v1 and v2.
pub fn inline_triangle_test(
    o: Vec3,
    d: Vec3,
    tr: &ppm_vk_kernels::layout::Triangle,
    tmin: f32,
    tmax: f32,
) -> Option<(f32, Vec2)> {
    let v0 = v3(tr.v0);
    // bary: rel = bary.x e1 + bary.y e2
    let (t, bary) = plane_hit(o, d, v0, v3(tr.v1) - v0, v3(tr.v2) - v0, tmin, tmax)?;
    (bary.x >= 0.0 && bary.y >= 0.0 && bary.x + bary.y <= 1.0).then_some((t, bary))
}

/// geometry.glsl's `plane_hit`: where o + t d meets the plane through `origin` spanned by e1 and e2, for t
/// in (tmin, tmax): t and the point's coordinates (a, b), point = origin + a e1 + b e2.
fn plane_hit(o: Vec3, d: Vec3, origin: Vec3, e1: Vec3, e2: Vec3, tmin: f32, tmax: f32) -> Option<(f32, Vec2)> {
    let n = e1.cross(e2);
    let t = n.dot(origin - o) / n.dot(d);
    if !(t > tmin && t < tmax) {
        return None;
    }
    let rel = o + t * d - origin;
    let w = n / n.dot(n);
    Some((t, Vec2::new(w.dot(rel.cross(e2)), w.dot(e1.cross(rel)))))
}

/// geometry.glsl's `inline_pair_test`: two written-out triangles that make a parallelogram
/// (ppm_vk_kernels::inline_pairs), tested as one by its plane. The triangle met, the hit's distance and
/// its weights of that triangle's v1 and v2.
pub fn inline_pair_test(o: Vec3, d: Vec3, p: &InlinePair, tmin: f32, tmax: f32) -> Option<(u32, f32, Vec2)> {
    let (t, ab) = plane_hit(o, d, v3(p.origin), v3(p.edge_u), v3(p.edge_v), tmin, tmax)?;
    let (a, b) = (ab.x, ab.y);
    if !((0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b)) {
        return None;
    }
    let first = a + b <= 1.0;
    let weights = inline_pairs::weights(first, a, b);
    let (i, [c1, c2]) = match first {
        true => (p.first, p.first_corners),
        false => (p.second, p.second_corners),
    };
    Some((i, t, Vec2::new(weights[c1 as usize], weights[c2 as usize])))
}

/// texture.glsl's `surface_uv` of a sphere at unit normal `normal`: longitude and colatitude about the
/// world's axes.
pub fn sphere_uv(normal: Vec3) -> Vec2 {
    let mut phi = normal.y.atan2(normal.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    Vec2::new(phi * (0.5 / PI), normal.z.clamp(-1.0, 1.0).acos() * (1.0 / PI))
}

/// texture.glsl's `surface_uv` of triangle `i` (leaf order) at barycentric weights `bary` of v1 and v2:
/// interpolated from its vertices'; zero where no mesh has them.
pub fn triangle_uv(g: &GpuScene, i: usize, bary: Vec2) -> Vec2 {
    let stride = ppm_vk_kernels::layout::TRIANGLE_TEXELS as usize;
    let f = |b: u32| f32::from_bits(b);
    match g.triangle_texels.get(stride * i..stride * (i + 1)) {
        Some(t) => {
            (1.0 - bary.x - bary.y) * Vec2::new(f(t[0][0]), f(t[0][1]))
                + bary.x * Vec2::new(f(t[0][2]), f(t[0][3]))
                + bary.y * Vec2::new(f(t[1][0]), f(t[1][1]))
        }
        None => Vec2::ZERO,
    }
}

/// `offset_ray` of geometry.glsl.
pub fn offset_ray(g: &GpuScene, p: Vec3, n: Vec3) -> Vec3 {
    p + (g.params.eps_rel * p.abs().max_element() + g.params.eps) * n
}

/// geometry.glsl's `glass_branch`: reflection with probability f (Fresnel), else refraction, for the
/// uniform number `u`; `nf` faces the incoming direction `d`. Returns the new (origin, direction).
pub fn glass_branch(g: &GpuScene, pos: Vec3, nf: Vec3, front: bool, ior: f32, u: f32, d: Vec3) -> (Vec3, Vec3) {
    let eta = if front { 1.0 / ior } else { ior };
    let cos_i = -d.dot(nf);
    let (f, cos_t) = fresnel_dielectric(cos_i, eta);
    if u < f {
        (offset_ray(g, pos, nf), reflect(d, nf))
    } else {
        (
            offset_ray(g, pos, -nf),
            (eta * d + (eta * cos_i - cos_t) * nf).normalize(),
        )
    }
}

/// `grid_key(grid_cell(p))` of grid.glsl: the cell's coordinates modulo 1024, packed 10 bits each.
pub fn grid_key(g: &GpuScene, p: Vec3) -> u32 {
    let c = ((p - v3(g.params.grid_min)) / g.params.cell_size).floor();
    let (x, y, z) = (
        c.x as i32 as u32 & 1023,
        c.y as i32 as u32 & 1023,
        c.z as i32 as u32 & 1023,
    );
    x | (y << 10) | (z << 20)
}

/// `grid_bucket(key)` of grid.glsl: the hash-table bucket of a cell key.
pub fn grid_bucket(g: &GpuScene, key: u32) -> u32 {
    let (x, y, z) = (key & 1023, (key >> 10) & 1023, key >> 20);
    (x.wrapping_mul(73856093) ^ y.wrapping_mul(19349663) ^ z.wrapping_mul(83492791)) & g.params.grid_mask
}

/// geometry.glsl's `sphere_derivatives` (what bump and normal maps perturb, normal_map.rs): Mitsuba's dp/du and dp/dv of a sphere of radius `r` at unit
/// normal `n`.
pub fn sphere_derivatives(n: Vec3, r: f32) -> [Vec3; 2] {
    let pi = ppm_vk_materials::math::PI;
    let rd = (n.x * n.x + n.y * n.y).sqrt();
    let dpdu = (2.0 * pi * r) * Vec3::new(-n.y, n.x, 0.0);
    let dpdv = if rd > 0.0 {
        (pi * r) * Vec3::new(n.z * n.x / rd, n.z * n.y / rd, -rd)
    } else {
        (pi * r) * Vec3::X
    };
    [dpdu, dpdv]
}

/// normal_map.glsl's `surface_derivatives` for a triangle of edges `e1`, `e2` and texture coordinates
/// `uv`: Mitsuba's dp/du and dp/dv, the edges where the coordinates are degenerate.
pub fn triangle_derivatives(e1: Vec3, e2: Vec3, uv: [Vec2; 3]) -> [Vec3; 2] {
    let duv0 = uv[1] - uv[0];
    let duv1 = uv[2] - uv[0];
    let det = duv0.x * duv1.y - duv0.y * duv1.x;
    if det == 0.0 {
        return [e1, e2];
    }
    let inv = 1.0 / det;
    [(duv1.y * e1 - duv0.y * e2) * inv, (duv0.x * e2 - duv1.x * e1) * inv]
}

#[cfg(test)]
mod tests {
    use super::*;
    use ppm_vk_materials::math::frame;

    /// The written-out triangles' plane test against the BVH's watertight test (bvh::triangle_test), an
    /// independent formulation: on rays at random triangles of every orientation and of sizes 1e-3 to 1e3,
    /// from origins up to 30 triangle sizes away, both find the same hits (but where the point lies within
    /// rounding of an edge, where rounding decides), at the same t and weights to rounding (which grows as
    /// the incidence grazes). A degenerate triangle and a ray in or along the plane give no hit.
    #[test]
    fn the_plane_test_finds_what_the_watertight_test_finds() {
        let mut rng = ppm_vk_materials::rng::Rng::new(7, 0);
        let mut u = move || rng.float();
        let tri =
            |v: [Vec3; 3]| ppm_vk_kernels::layout::Triangle::through(v[0].to_array(), v[1].to_array(), v[2].to_array());
        let (mut hits, mut near_edge) = (0, 0);
        for _ in 0..200_000 {
            let scale = 10f32.powf(6.0 * u() - 3.0);
            let mut p = || scale * Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5);
            let v = [p(), p(), p()];
            // Well-shaped triangles only: a sliver's weights are ill-conditioned in either test.
            let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
            let longest = e1.length().max(e2.length()).max((v[2] - v[1]).length());
            if e1.cross(e2).length() < 0.1 * longest * longest {
                continue;
            }
            let t = tri(v);
            // Aim at a point of the triangle's plane near it (weights in [-0.2, 1.2]), from afar.
            let (a, b) = (1.4 * u() - 0.2, 1.4 * u() - 0.2);
            let target = v[0] + a * (v[1] - v[0]) + b * (v[2] - v[0]);
            let o = target + 30.0 * scale * (Vec3::new(u(), u(), u()) - 0.5);
            let d = (target - o).normalize();
            let want = super::super::bvh::triangle_test(
                &super::super::bvh::BvhRay::new(o, d),
                v[0],
                v[1],
                v[2],
                0.0,
                f32::MAX,
            );
            let got = inline_triangle_test(o, d, &t, 0.0, f32::MAX);
            // Rounding moves a point found from `far` triangle sizes away at incidence cos by about
            // ulp * far / cos in the weights: the tolerance, and the band about the edges where the two
            // tests may disagree.
            let cos = e1.cross(e2).normalize().dot(d).abs();
            let far = (o - target).length() / scale;
            let tol = 1e-5 + 2e-6 * far / cos;
            let edge = a.min(b).min(1.0 - a - b).abs() < tol;
            match (want, got) {
                (Some((tw, bw)), Some((tg, bg))) => {
                    hits += 1;
                    assert!((tw - tg).abs() <= 1e-5 * tw / cos, "t {tg} against {tw}, cos {cos}");
                    let off = (bw - bg).abs().max_element();
                    assert!(off <= tol, "weights {bg} against {bw}, cos {cos}, {far} sizes away");
                }
                (None, None) => {}
                _ if edge => near_edge += 1,
                (w, g) => panic!("watertight {w:?}, plane {g:?}: weights ({a}, {b}) of {v:?} from {o}"),
            }
        }
        assert!(hits > 40_000, "{hits} hits");
        println!("{hits} hits, {near_edge} disagreements within rounding of an edge");
        let o = Vec3::new(0.2, 0.2, 1.0);
        let flat = tri([Vec3::ZERO, Vec3::X, Vec3::Y]);
        assert_eq!(inline_triangle_test(o, Vec3::X, &flat, 0.0, f32::MAX), None, "parallel");
        assert_eq!(
            inline_triangle_test(Vec3::new(0.2, 0.2, 0.0), Vec3::X, &flat, 0.0, f32::MAX),
            None,
            "in the plane"
        );
        let degenerate = tri([Vec3::ZERO, Vec3::X, 2.0 * Vec3::X]);
        assert_eq!(
            inline_triangle_test(o, -Vec3::Z, &degenerate, 0.0, f32::MAX),
            None,
            "degenerate"
        );
        assert!(
            inline_triangle_test(o, -Vec3::Z, &flat, 0.0, f32::MAX).is_some(),
            "the plain case"
        );
    }

    /// The frame an anisotropic lobe lies in, against Mitsuba's: on each shape of tangents.xml (a sphere,
    /// a turned and stretched rectangle, one with flip_normals, a mirrored one, a mesh with texture
    /// coordinates and a smooth-shaded one without), where Mitsuba's rays hit it (tangents.json, made by
    /// tangents.py beside it), the tangent of microfacet.glsl's `frame` about the shading normal, from the
    /// hit's dp/du, is Mitsuba's sh_frame.s up to its sign (D and G1 are even in it): within 1e-3 (the
    /// meshes' are stored as 16-bit octahedral codes, about 5e-5 rad).
    #[test]
    fn anisotropic_frames_are_mitsubas() {
        let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/references/");
        let scene = ppm_vk_engine::Scene::load(format!("{root}tangents.xml")).unwrap_or_else(|e| panic!("{e:#}"));
        let g = GpuScene::new(&scene, &ppm_vk_engine::Settings::default(), 1 << 10).unwrap();
        let text = include_str!("../../../scenes/references/tangents.json");
        let doc: serde_json::Value = serde_json::from_str(text).unwrap();
        let vec = |v: &serde_json::Value| {
            let a: Vec<f32> = v
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap() as f32)
                .collect();
            Vec3::new(a[0], a[1], a[2])
        };
        for shape in doc["shapes"].as_array().unwrap() {
            let name = shape["shape"].as_str().unwrap();
            let hits = shape["hits"].as_array().unwrap();
            assert!(hits.len() >= 10, "{name}: {} hits", hits.len());
            for (k, hit) in hits.iter().enumerate() {
                let (o, d) = (vec(&hit["o"]), vec(&hit["d"]));
                let h = intersect_scene(&g, o, d, 0.0, 1e30, 0).expect("a hit");
                assert!(
                    h.pos.distance(vec(&hit["p"])) < 1e-4,
                    "{name} {k}: hit {} against {}",
                    h.pos,
                    vec(&hit["p"])
                );
                let ng = if d.dot(h.normal) < 0.0 { h.normal } else { -h.normal };
                let ns = super::super::shading::normal(&h, ng);
                assert!(ns.dot(vec(&hit["n"])).abs() > 1.0 - 1e-4, "{name} {k}: normal {ns}");
                let (t, _) = frame(ns, h.dpdu);
                let s = vec(&hit["s"]);
                assert!(
                    t.dot(s).abs() > 1.0 - 1e-3,
                    "{name} {k}: tangent {t} against Mitsuba's {s}"
                );
            }
        }
    }
}

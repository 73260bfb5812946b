//! shaders/common/lights.glsl in plain Rust: choosing a light, sampling it for shadow rays, starting
//! photons from it, and the environment's radiance, density and sampling (its table in `g.textures`).

use glam::Vec3;
use ppm_vk_kernels::layout::{
    Light, LIGHT_DIRECTIONAL, LIGHT_ENVIRONMENT, LIGHT_POINT, LIGHT_QUAD, LIGHT_SPHERE, LIGHT_SPOT, LIGHT_TRIANGLE,
    QUAD_DISK,
};
use ppm_vk_materials::math::{onb, v3, PI};

use crate::rng::Rng;
use crate::trace::offset_ray;
use crate::{bvh, GpuScene};

/// A light as lights.glsl's `Emitter` (see types.glsl for what each field holds per kind).
pub struct Emitter {
    pub origin: Vec3,
    pub edge_u: Vec3,
    pub edge_v: Vec3,
    pub normal: Vec3,
    pub flux: Vec3,
    pub cdf: f32,
    pub kind: u32,
    pub value: Vec3,
    pub radius: f32,
    pub cos_cutoff: f32,
    pub cos_beam: f32,
    pub cutoff: f32,
    pub inv_width: f32,
    pub table: u32,
}

/// lights.glsl's `emitter_of`.
pub fn emitter_of(g: &GpuScene, light: &Light) -> Emitter {
    let flux = v3(if light.kind == LIGHT_SPOT || light.texture != 0 {
        light.flux
    } else {
        light.power
    }) / light.prob;
    let mut e = Emitter {
        origin: Vec3::ZERO,
        edge_u: Vec3::ZERO,
        edge_v: Vec3::ZERO,
        normal: Vec3::ZERO,
        flux,
        cdf: light.cdf,
        kind: light.kind,
        value: Vec3::ZERO,
        radius: 0.0,
        cos_cutoff: 0.0,
        cos_beam: 0.0,
        cutoff: 0.0,
        inv_width: 0.0,
        table: 0,
    };
    if light.kind == LIGHT_TRIANGLE {
        let t = &g.bvh_triangles[light.index as usize];
        (e.origin, e.edge_u, e.edge_v) = (v3(t.v0), v3(t.v1) - v3(t.v0), v3(t.v2) - v3(t.v0));
        e.normal = bvh::normal(t);
        e.value = v3(light.value);
        e.table = if light.texture != 0 { light.index + 1 } else { 0 };
        return e;
    }
    if light.kind == LIGHT_QUAD {
        let q = &g.quads[light.index as usize];
        (e.origin, e.edge_u, e.edge_v, e.normal) = (v3(q.origin), v3(q.edge_u), v3(q.edge_v), v3(q.normal));
        e.radius = if q.shape == QUAD_DISK { 1.0 } else { 0.0 };
        e.value = v3(light.value);
        e.table = light.texture;
        return e;
    }
    e.origin = v3(light.origin);
    e.edge_u = v3(light.edge_u);
    e.normal = v3(light.normal);
    e.edge_v = e.edge_u.cross(e.normal);
    e.value = if light.kind == LIGHT_ENVIRONMENT {
        v3(light.value)
    } else {
        v3(light.value) / light.prob
    };
    e.radius = light.radius;
    e.cos_cutoff = light.cos_cutoff;
    e.cos_beam = light.cos_beam;
    e.cutoff = light.cutoff;
    e.inv_width = light.inv_width;
    e.table = light.index;
    e
}

/// lights.glsl's `choose_emitter`: the first light whose running cdf exceeds u.
pub fn choose_emitter(g: &GpuScene, u: f32) -> Emitter {
    let mut li = 0usize;
    while li + 1 < g.lights.len() && u >= g.lights[li].cdf {
        li += 1;
    }
    emitter_of(g, &g.lights[li])
}

/// lights.glsl's `first_emitter`: light 0, the environment when there is one.
pub fn first_emitter(g: &GpuScene) -> Emitter {
    emitter_of(g, &g.lights[0])
}

/// lights.glsl's `emitter_radiance`: what multiplies `e.flux` at `emitter_point(e, a, b)` (a quad's
/// radiance texture at the point's planar coordinates, a textured triangle's at its interpolated uv,
/// else 1).
pub fn emitter_radiance(g: &GpuScene, e: &Emitter, mut a: f32, mut b: f32) -> Vec3 {
    if e.table == 0 || e.kind > LIGHT_TRIANGLE {
        return Vec3::ONE;
    }
    if e.kind == LIGHT_QUAD {
        let uv = if e.radius != 0.0 {
            disk_point(a, b)
        } else {
            glam::Vec2::new(a, b)
        };
        return crate::texture::value(&g.textures, e.table - 1, uv);
    }
    if a + b > 1.0 {
        (a, b) = (1.0 - a, 1.0 - b);
    }
    let prim = (e.table - 1) as usize;
    let m = &g.materials[g.bvh_triangles[prim].material as usize];
    let f = |x: u32| f32::from_bits(x);
    let (t, t2) = (g.triangle_texels[3 * prim], g.triangle_texels[3 * prim + 1]);
    let uv = (1.0 - a - b) * glam::Vec2::new(f(t[0]), f(t[1]))
        + a * glam::Vec2::new(f(t[2]), f(t[3]))
        + b * glam::Vec2::new(f(t2[0]), f(t2[1]));
    crate::texture::value(&g.textures, m.emission_texture - 1, uv)
}

/// lights.glsl's `is_area`.
pub fn is_area(e: &Emitter) -> bool {
    e.kind <= LIGHT_TRIANGLE
}

/// lights.glsl's `disk_point`: a disk's planar coordinates for uniform (a, b), by the polar map
/// (sqrt(a), 2 pi b) of the unit disk onto the ellipse inscribed in the unit square.
pub fn disk_point(a: f32, b: f32) -> glam::Vec2 {
    let r = 0.5 * a.sqrt();
    let phi = 2.0 * PI * b;
    glam::Vec2::new(0.5 + r * phi.cos(), 0.5 + r * phi.sin())
}

/// lights.glsl's `emitter_point`: uniform in the emitter's area for uniform (a, b).
pub fn emitter_point(e: &Emitter, mut a: f32, mut b: f32) -> Vec3 {
    if e.kind == LIGHT_TRIANGLE && a + b > 1.0 {
        (a, b) = (1.0 - a, 1.0 - b);
    }
    if e.kind == LIGHT_QUAD && e.radius != 0.0 {
        let p = disk_point(a, b);
        (a, b) = (p.x, p.y);
    }
    e.origin + a * e.edge_u + b * e.edge_v
}

pub fn uniform_sphere(a: f32, b: f32) -> Vec3 {
    let z = 1.0 - 2.0 * a;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * b;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn about(t: Vec3, b: Vec3, n: Vec3, cos_theta: f32, sin_theta: f32, phi: f32) -> Vec3 {
    sin_theta * phi.cos() * t + sin_theta * phi.sin() * b + cos_theta * n
}

/// lights.glsl's `spot_falloff`.
pub fn spot_falloff(e: &Emitter, cos_theta: f32) -> f32 {
    if !(cos_theta > e.cos_cutoff) {
        return 0.0;
    }
    if cos_theta >= e.cos_beam {
        return 1.0;
    }
    ((e.cutoff - cos_theta.acos()) * e.inv_width).max(0.0)
}

fn table_float(g: &GpuScene, at: u32) -> f32 {
    f32::from_bits(g.textures[at as usize][0])
}

fn env_pixel(g: &GpuScene, first: u32, w: u32, row: u32, col: u32) -> Vec3 {
    let t = g.textures[(first + row * w + col) as usize];
    Vec3::new(f32::from_bits(t[0]), f32::from_bits(t[1]), f32::from_bits(t[2]))
}

/// lights.glsl's `cdf_search`: (index, t, p).
fn cdf_search(g: &GpuScene, first: u32, n: u32, u: f32) -> (u32, f32, f32) {
    let (mut lo, mut hi) = (0u32, n - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if u >= table_float(g, first + mid) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    let before = if lo > 0 { table_float(g, first + lo - 1) } else { 0.0 };
    let p = table_float(g, first + lo) - before;
    (lo, ((u - before) / p).clamp(0.0, 0.99999994), p)
}

/// lights.glsl's `cdf_share`.
fn cdf_share(g: &GpuScene, first: u32, i: u32) -> f32 {
    table_float(g, first + i) - if i > 0 { table_float(g, first + i - 1) } else { 0.0 }
}

/// lights.glsl's `cell_density`.
fn cell_density((w, h): (u32, u32), p_cell: f32, sin_theta: f32) -> f32 {
    if sin_theta > 0.0 {
        p_cell * (w * (h - 1)) as f32 / (2.0 * PI * PI * sin_theta)
    } else {
        0.0
    }
}

/// lights.glsl's `infinite_reach`: how far a shadow ray from o towards the sun or the sky goes.
pub fn infinite_reach(e: &Emitter, o: Vec3) -> f32 {
    2.0 * (e.radius + (o - e.origin).length())
}

/// lights.glsl's `emitter_bounds`: the centre and radius of the sphere around an emitter with an area;
/// `None` for a point, a spot, the sun and the environment.
pub fn emitter_bounds(e: &Emitter) -> Option<(Vec3, f32)> {
    match e.kind {
        LIGHT_QUAD => Some((
            e.origin + 0.5 * (e.edge_u + e.edge_v),
            0.5 * (e.edge_u + e.edge_v).length().max((e.edge_u - e.edge_v).length()),
        )),
        LIGHT_TRIANGLE => {
            let centre = e.origin + (e.edge_u + e.edge_v) * (1.0 / 3.0);
            let a = e.origin - centre;
            Some((
                centre,
                a.length().max((a + e.edge_u).length().max((a + e.edge_v).length())),
            ))
        }
        LIGHT_SPHERE => Some((e.origin, e.radius)),
        _ => None,
    }
}

fn env_size(g: &GpuScene, e: &Emitter) -> (u32, u32) {
    let t = g.textures[e.table as usize];
    (t[0], t[1])
}

fn env_local(e: &Emitter, d: Vec3) -> Vec3 {
    Vec3::new(e.edge_u.dot(d), e.normal.dot(d), e.edge_v.dot(d))
}

/// lights.glsl's `env_cell`: (band, column, where in the pixel grid).
fn env_cell(w: u32, h: u32, d: Vec3) -> (u32, u32, [f32; 2]) {
    let u = d.x.atan2(-d.z) * (0.5 / PI);
    let v = d.y.clamp(-1.0, 1.0).acos() * (1.0 / PI);
    let mut x = u * w as f32 - 0.5;
    x -= w as f32 * (x / w as f32).floor();
    let y = v * (h - 1) as f32;
    let col = (x as u32).min(w - 1);
    let band = (y as u32).min(h - 2);
    (band, col, [x - col as f32, y - band as f32])
}

/// lights.glsl's `env_bilinear`.
fn env_bilinear(g: &GpuScene, e: &Emitter, w: u32, band: u32, col: u32, f: [f32; 2]) -> Vec3 {
    let first = e.table + 1;
    let next = if col + 1 == w { 0 } else { col + 1 };
    let c00 = env_pixel(g, first, w, band, col);
    let c01 = env_pixel(g, first, w, band, next);
    let c10 = env_pixel(g, first, w, band + 1, col);
    let c11 = env_pixel(g, first, w, band + 1, next);
    e.value * ((1.0 - f[1]) * ((1.0 - f[0]) * c00 + f[0] * c01) + f[1] * ((1.0 - f[0]) * c10 + f[0] * c11))
}

/// lights.glsl's `environment_radiance`.
pub fn environment_radiance(g: &GpuScene, e: &Emitter, d: Vec3) -> Vec3 {
    if e.table == u32::MAX {
        return e.value;
    }
    let (w, h) = env_size(g, e);
    let (band, col, f) = env_cell(w, h, env_local(e, d));
    env_bilinear(g, e, w, band, col, f)
}

/// lights.glsl's `environment_pdf`.
pub fn environment_pdf(g: &GpuScene, e: &Emitter, d: Vec3) -> f32 {
    if e.table == u32::MAX {
        return 1.0 / (4.0 * PI);
    }
    let (w, h) = env_size(g, e);
    let l = env_local(e, d);
    let (band, col, _) = env_cell(w, h, l);
    let rows = e.table + 1 + w * h;
    let cols = rows + h - 1 + band * w;
    let p_cell = cdf_share(g, rows, band) * cdf_share(g, cols, col);
    cell_density((w, h), p_cell, (1.0 - l.y * l.y).max(0.0).sqrt())
}

/// lights.glsl's `env_sample`: (world direction, solid-angle density, radiance).
pub fn env_sample(g: &GpuScene, e: &Emitter, a: f32, b: f32) -> (Vec3, f32, Vec3) {
    if e.table == u32::MAX {
        return (uniform_sphere(a, b), 1.0 / (4.0 * PI), e.value);
    }
    let (w, h) = env_size(g, e);
    let rows = e.table + 1 + w * h;
    let (band, ty, p_band) = cdf_search(g, rows, h - 1, a);
    let (col, tx, p_col) = cdf_search(g, rows + h - 1 + band * w, w, b);
    let u = (col as f32 + tx + 0.5) / w as f32;
    let v = (band as f32 + ty) / (h - 1) as f32;
    let l = ppm_vk_engine::scene::emitter::envmap_direction(u - u.floor(), v);
    let pdf = cell_density((w, h), p_band * p_col, (PI * v).sin());
    let radiance = env_bilinear(g, e, w, band, col, [tx, ty]);
    (l.x * e.edge_u + l.y * e.normal + l.z * e.edge_v, pdf, radiance)
}

/// A shadow-ray sample of a light other than a quad or triangle (lights.glsl's `light_sample`): the
/// direction, how far the ray goes, li, and the density times prob for an environment (0 otherwise).
pub struct LightSample {
    pub w: Vec3,
    pub dist: f32,
    pub li: Vec3,
    pub pdf: f32,
}

/// lights.glsl's `light_sample` from ray origin o.
pub fn light_sample(g: &GpuScene, e: &Emitter, o: Vec3, a: f32, b: f32) -> Option<LightSample> {
    match e.kind {
        LIGHT_SPHERE => {
            let dc = e.origin - o;
            let dist2 = dc.dot(dc);
            let r2 = e.radius * e.radius;
            if !(dist2 > r2) {
                return None;
            }
            let dc_len = dist2.sqrt();
            let sin2_max = r2 / dist2;
            let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
            let cap = sin2_max / (1.0 + cos_max);
            let one_minus = a * cap;
            let cos_theta = 1.0 - one_minus;
            let sin_theta = (one_minus * (2.0 - one_minus)).max(0.0).sqrt();
            let n = dc / dc_len;
            let (t, bt) = onb(n);
            let w = about(t, bt, n, cos_theta, sin_theta, 2.0 * PI * b);
            let near = dc_len * cos_theta - (r2 - dist2 * sin_theta * sin_theta).max(0.0).sqrt();
            let y = o + near * w;
            let y_off = offset_ray(g, y, (y - e.origin).normalize());
            let dist = (y_off - o).dot(w);
            (dist > 0.0).then(|| LightSample {
                w,
                dist,
                li: e.value * (2.0 * PI * cap),
                pdf: 0.0,
            })
        }
        LIGHT_POINT | LIGHT_SPOT => {
            let to = e.origin - o;
            let d2 = to.dot(to);
            let dist = d2.sqrt();
            let w = to / dist;
            let mut li = e.value / d2;
            if e.kind == LIGHT_SPOT {
                li *= spot_falloff(e, -w.dot(e.normal));
            }
            (d2 > 0.0).then_some(LightSample { w, dist, li, pdf: 0.0 })
        }
        LIGHT_DIRECTIONAL => Some(LightSample {
            w: -e.normal,
            dist: infinite_reach(e, o),
            li: e.value,
            pdf: 0.0,
        }),
        LIGHT_ENVIRONMENT => {
            let (w, p, radiance) = env_sample(g, e, a, b);
            if !(p > 0.0) {
                return None;
            }
            let pdf = p * e.cdf;
            Some(LightSample {
                w,
                dist: infinite_reach(e, o),
                li: radiance / pdf,
                pdf,
            })
        }
        _ => None,
    }
}

/// A photon from a light other than a quad or triangle (lights.glsl's `emit_photon`): origin, direction
/// (a sphere's: its normal, about which the caller draws the direction), flux, and whether the direction
/// is final (false for a sphere).
pub fn emit_photon(g: &GpuScene, e: &Emitter, a: f32, b: f32, rng: &mut Rng) -> (Vec3, Vec3, Vec3, bool) {
    let mut flux = e.flux;
    match e.kind {
        LIGHT_SPHERE => {
            let n = uniform_sphere(a, b);
            return (offset_ray(g, e.origin + e.radius * n, n), n, flux, false);
        }
        LIGHT_POINT => return (e.origin, uniform_sphere(a, b), flux, true),
        LIGHT_SPOT => {
            let cos_theta = 1.0 - a * (1.0 - e.cos_cutoff);
            let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
            let d = about(e.edge_u, e.edge_v, e.normal, cos_theta, sin_theta, 2.0 * PI * b);
            flux *= spot_falloff(e, cos_theta);
            return (e.origin, d, flux, true);
        }
        _ => {}
    }
    let r = e.radius * rng.float().sqrt();
    let phi = 2.0 * PI * rng.float();
    let d = if e.kind == LIGHT_ENVIRONMENT {
        let (towards, p, radiance) = env_sample(g, e, a, b);
        flux = if p > 0.0 {
            radiance * (PI * e.radius * e.radius / (p * e.cdf))
        } else {
            Vec3::ZERO
        };
        -towards
    } else {
        e.normal
    };
    let (t, bt) = onb(d);
    (
        e.origin - e.radius * d + r * phi.cos() * t + r * phi.sin() * bt,
        d,
        flux,
        true,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat3;
    use ppm_vk_engine::scene::emitter::envmap_uv;
    use ppm_vk_engine::scene::{Emitter as SceneEmitter, EnvMap, Environment, Scene};
    use ppm_vk_engine::settings::Settings;

    fn emitter(kind: u32, origin: Vec3, edge_u: Vec3, edge_v: Vec3, radius: f32) -> Emitter {
        Emitter {
            origin,
            edge_u,
            edge_v,
            normal: edge_u.cross(edge_v).normalize_or_zero(),
            flux: Vec3::ONE,
            cdf: 1.0,
            kind,
            value: Vec3::ONE,
            radius,
            cos_cutoff: 0.0,
            cos_beam: 0.0,
            cutoff: 0.0,
            inv_width: 0.0,
            table: 0,
        }
    }

    /// The sphere around a quad (a skewed one too), a triangle and a sphere holds every corner, and for a
    /// quad and a triangle touches the farthest: the smallest sphere about that centre. Point lights and
    /// the sun have none.
    #[test]
    fn emitter_bounds_hold_the_emitter() {
        let o = Vec3::new(0.3, -1.0, 2.0);
        for (u, v) in [
            (Vec3::new(0.15, 0.0, 0.0), Vec3::new(0.0, 0.0, 0.15)),
            (Vec3::new(2.0, 0.0, 0.0), Vec3::new(1.5, 0.5, 0.0)),
        ] {
            // The bounds of `kind` on (o, u, v), whose farthest corner must lie on the sphere.
            let touches = |kind: u32, corners: &[Vec3]| {
                let (c, r) = emitter_bounds(&emitter(kind, o, u, v, 0.0)).unwrap();
                let far = corners.iter().map(|p| (*p - c).length()).fold(0f32, f32::max);
                assert!(
                    (far - r).abs() <= 1e-6 * r.max(1.0),
                    "kind {kind}: farthest corner {far}, radius {r}"
                );
                c
            };
            touches(LIGHT_QUAD, &[o, o + u, o + v, o + u + v]);
            let c = touches(LIGHT_TRIANGLE, &[o, o + u, o + v]);
            assert!((c - (o + (u + v) / 3.0)).length() < 1e-6);
        }
        assert_eq!(
            emitter_bounds(&emitter(LIGHT_SPHERE, o, Vec3::X, Vec3::Z, 0.25)),
            Some((o, 0.25))
        );
        for kind in [LIGHT_POINT, LIGHT_SPOT, LIGHT_DIRECTIONAL, LIGHT_ENVIRONMENT] {
            assert_eq!(emitter_bounds(&emitter(kind, o, Vec3::X, Vec3::Z, 0.25)), None);
        }
    }

    /// A scene whose only light is an environment map of w x h pixels given by `f(row, col)`, lowered.
    fn lowered(w: u32, h: u32, f: impl Fn(u32, u32) -> Vec3) -> GpuScene {
        let text = r#"name = "env"
[camera]
eye = [0.0, 0.0, 3.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
vfov = 40.0
resolution = [8, 8]
[materials.white]
diffuse = [0.5, 0.5, 0.5]
[materials.lamp]
emission = [1.0, 1.0, 1.0]
[[sphere]]
center = [0.0, 0.0, 0.0]
radius = 1.0
material = "white"
[[quad]]
origin = [100.0, 100.0, 100.0]
edge_u = [0.1, 0.0, 0.0]
edge_v = [0.0, 0.0, 0.1]
material = "lamp"
"#;
        let mut scene = Scene::parse(text, "env.toml").unwrap();
        scene.quads.pop();
        let pixels = (0..h)
            .flat_map(|r| (0..w).map(move |c| (r, c)))
            .map(|(r, c)| f(r, c))
            .collect();
        scene.emitters.push(SceneEmitter::Environment(Environment {
            scale: Vec3::ONE,
            map: Some(EnvMap {
                name: "test".into(),
                width: w,
                height: h,
                pixels,
            }),
            // Turned, so that the frame's columns are exercised.
            to_world: Mat3::from_rotation_y(0.7) * Mat3::from_rotation_x(0.3),
        }));
        scene.validate().unwrap();
        GpuScene::new(&scene, &Settings::default(), 1024).unwrap()
    }

    fn pattern(r: u32, c: u32) -> Vec3 {
        // Smooth variation, a bright spot, and a black region (whose cells must still be sampled where a
        // neighbouring pixel is lit: bilinear radiance reaches into them).
        let base = 0.2 + 0.1 * ((c as f32 * 0.7).sin() + (r as f32 * 0.9).cos());
        let spot = if (r, c) == (3, 11) { 40.0 } else { 0.0 };
        if c < 3 {
            Vec3::ZERO
        } else {
            Vec3::new(base + spot, 0.5 * base, 2.0 * base)
        }
    }

    /// The cells are drawn in proportion to their weight (the largest channel of their four pixels times
    /// the largest sin theta of their band, computed here from the pixels), by a chi-square test; the
    /// density env_sample returns is environment_pdf's; and L / pdf averages to the integral of the bilinear
    /// radiance over the sphere, by quadrature.
    #[test]
    fn environment_sampling_follows_the_maps_distribution_and_is_unbiased() {
        let (w, h) = (16u32, 9u32);
        let g = lowered(w, h, pattern);
        let e = first_emitter(&g);
        assert_eq!(e.kind, LIGHT_ENVIRONMENT);
        let px = |r: u32, c: u32| pattern(r, c % w);
        let bands = h - 1;
        let mut weights = vec![0f64; (bands * w) as usize];
        for i in 0..bands {
            let (t0, t1) = (
                PI as f64 * i as f64 / bands as f64,
                PI as f64 * (i + 1) as f64 / bands as f64,
            );
            let s = if t0 <= std::f64::consts::FRAC_PI_2 && std::f64::consts::FRAC_PI_2 <= t1 {
                1.0
            } else {
                t0.sin().max(t1.sin())
            };
            for j in 0..w {
                let m = [px(i, j), px(i, j + 1), px(i + 1, j), px(i + 1, j + 1)]
                    .iter()
                    .fold(0f32, |m, p| m.max(p.max_element()));
                weights[(i * w + j) as usize] = m as f64 * s;
            }
        }
        let total: f64 = weights.iter().sum();
        let n = 400_000u32;
        let mut counts = vec![0u32; weights.len()];
        let mut rng = Rng::new(7, 0);
        let mut sum = glam::DVec3::ZERO;
        let mut mismatched = 0;
        let inverse = Mat3::from_cols(e.edge_u, e.normal, e.edge_v).transpose();
        for _ in 0..n {
            let (a, b) = (rng.float(), rng.float());
            let (d, pdf, radiance) = env_sample(&g, &e, a, b);
            let (u, v) = envmap_uv(inverse * d);
            let mut x = u * w as f32 - 0.5;
            x -= w as f32 * (x / w as f32).floor();
            let (col, band) = ((x as u32).min(w - 1), ((v * bands as f32) as u32).min(bands - 1));
            counts[(band * w + col) as usize] += 1;
            let again = environment_pdf(&g, &e, d);
            if (again / pdf - 1.0).abs() > 1e-3 {
                mismatched += 1;
            }
            // The radiance of the cell drawn is the map's in that direction (up to the f32 round trip of
            // the direction through its coordinates, times the map's steepest change: 1e-3 absolute).
            let again_l = environment_radiance(&g, &e, d);
            assert!(
                (again_l - radiance).abs().max_element() <= 1e-3 * (1.0 + radiance.max_element()),
                "{again_l} {radiance}"
            );
            sum += (radiance / pdf).as_dvec3();
        }
        let mut chi2 = 0f64;
        let mut dof = 0;
        for (k, &c) in counts.iter().enumerate() {
            let expected = n as f64 * weights[k] / total;
            if weights[k] == 0.0 {
                assert_eq!(c, 0, "cell {k} has no weight but was drawn");
                continue;
            }
            chi2 += (c as f64 - expected).powi(2) / expected;
            dof += 1;
        }
        let bound = dof as f64 + 5.0 * (2.0 * dof as f64).sqrt();
        assert!(chi2 < bound, "chi-square {chi2:.1} over {dof} cells (bound {bound:.1})");
        // A direction at a cell's edge may round into its neighbour.
        assert!(
            mismatched < n / 1000,
            "{mismatched} densities differ from environment_pdf's"
        );
        // The integral by quadrature: bilinear radiance on a fine grid of (u, v), times 2 pi^2 sin theta.
        let k = 2048u32;
        let mut integral = glam::DVec3::ZERO;
        for iv in 0..k {
            let v = (iv as f64 + 0.5) / k as f64;
            let y = v * bands as f64;
            let (r0, fy) = ((y as u32).min(bands - 1), y - (y as u32).min(bands - 1) as f64);
            for iu in 0..k {
                let u = (iu as f64 + 0.5) / k as f64;
                let mut x = u * w as f64 - 0.5;
                x -= w as f64 * (x / w as f64).floor();
                let (c0, fx) = ((x as u32).min(w - 1), x - (x as u32).min(w - 1) as f64);
                let l = (1.0 - fy) * ((1.0 - fx) * px(r0, c0).as_dvec3() + fx * px(r0, c0 + 1).as_dvec3())
                    + fy * ((1.0 - fx) * px(r0 + 1, c0).as_dvec3() + fx * px(r0 + 1, c0 + 1).as_dvec3());
                integral += l * (std::f64::consts::PI * v).sin();
            }
        }
        integral *= 2.0 * std::f64::consts::PI.powi(2) / (k as f64 * k as f64);
        let mean = sum / n as f64;
        for c in 0..3 {
            assert!(
                (mean[c] / integral[c] - 1.0).abs() < 0.01,
                "channel {c}: mean L / pdf {} against the integral {}",
                mean[c],
                integral[c]
            );
        }
    }
}

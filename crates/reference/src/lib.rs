//! The CPU reference of every kernel, in plain Rust. Tracing follows the GLSL operation for operation in
//! f32 and draws the same random numbers, so both produce the same paths (up to the last bit of a fused
//! multiply-add); sums and the progressive update are in f64. The tests run both on identical inputs.
//!
//! A crate of its own, `publish = false`, that only tests and examples depend on: no production build
//! compiles it (`cargo tree -e normal -p ppm-vk` does not list it). It reads the engine's lowered scene
//! (`ppm_vk_engine::lower::GpuScene`) and takes the BSDFs' math from `ppm_vk_materials`, as the kernels do.

// The kernels test `!(x > y)` so that a NaN ends a path; the twin mirrors them as written.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod blend;
pub mod bvh;
pub mod conductor;
pub mod glossy_light;
pub mod lights;
pub mod mask;
/// Generated meshes for the BVH's tests and benchmarks.
pub mod meshes;
pub mod microfacet;
pub mod normal_map;
pub mod plastic;
/// The kernels' random numbers (rng.glsl), a leaf of the materials crate, whose samplers' tests use them too.
pub use ppm_vk_materials::rng;
pub mod rough_conductor;
pub mod rough_dielectric;
pub mod shading;
pub mod targets;
pub mod texture;
pub mod thin_dielectric;
pub mod trace;

use glam::{DVec3, Vec2, Vec3};
use ppm_vk_kernels::layout::{
    HitPoint, HitStats, Material, PassAccum, Photon, EMPTY_SLOT, LIGHT_ENVIRONMENT, SURFACE_DIFFUSE, SURFACE_PLASTIC,
    SURFACE_ROUGH_CONDUCTOR, SURFACE_ROUGH_GLASS, SURFACE_THIN,
};
use ppm_vk_kernels::photon::{SALT_EMISSION, SALT_STRATA};
use ppm_vk_kernels::ray::RayPush;
use ppm_vk_materials::math::{cosine_direction, fresnel_dielectric, oct_decode, oct_encode, reflect, v3, PI};

use lights::{choose_emitter, emitter_point, emitter_radiance, first_emitter, is_area, light_sample, LightSample};
use normal_map::Bump;
use ppm_vk_engine::lower::GpuScene;
use ppm_vk_engine::settings::ProbeMode;
use rng::Rng;
use rough_conductor::glossy_hit;
use trace::{glass_branch, intersect_scene, offset_ray};

/// The camera ray through point `jitter` of pixel (px, py), as ray.comp's `camera_ray`.
fn camera_ray(g: &GpuScene, px: u32, py: u32, j: [f32; 2]) -> Vec3 {
    let p = &g.params;
    let sx = (2.0 * (px as f32 + j[0]) / p.width as f32 - 1.0) * p.aspect * p.tan_half_fov;
    let sy = (1.0 - 2.0 * (py as f32 + j[1]) / p.height as f32) * p.tan_half_fov;
    (v3(p.forward) + sx * v3(p.right) + sy * v3(p.up)).normalize()
}

/// ray.comp's `direct_light_ray`, traced at once: term (d) at diffuse point p, one light sample with its
/// shadow ray;
/// `coat`: p is that plastic's base under its coat.
/// `rough`: p is a glossy hit point on that rough conductor, seen from the direction given (albedo: its
/// specular_reflectance). `nf` is the shading normal, `ng` the true surface's on its side.
#[allow(clippy::too_many_arguments)]
fn direct_light(
    g: &GpuScene,
    p: Vec3,
    nf: Vec3,
    ng: Vec3,
    albedo: Vec3,
    coat: Option<&Material>,
    rough: Option<(&Material, Vec3)>,
    bump: &Bump,
    rng: &mut Rng,
) -> Vec3 {
    let e = choose_emitter(g, rng.float());
    let a = rng.float();
    let b = rng.float();
    let o = offset_ray(g, p, nf);
    // The light reaching p along w from as far as d: the estimate is f_r lflux s (ray.comp).
    let (w, d, lflux, s, cos_p);
    let mut weight = 1.0;
    if !is_area(&e) {
        let Some(LightSample { w: w2, dist, li, pdf }) = light_sample(g, &e, o, a, b) else {
            return Vec3::ZERO;
        };
        (w, d, lflux) = (w2, dist, li);
        cos_p = nf.dot(w);
        if !(cos_p > 0.0) {
            return Vec3::ZERO;
        }
        s = cos_p;
        if pdf > 0.0 && rough.is_none() {
            let pb = cos_p / PI;
            weight = pdf * pdf / (pdf * pdf + pb * pb);
        }
    } else {
        let y = offset_ray(g, emitter_point(&e, a, b), e.normal);
        let mut w2 = y - o;
        let d2 = w2.dot(w2);
        d = d2.sqrt();
        w2 /= d;
        w = w2;
        cos_p = nf.dot(w);
        let cos_y = -e.normal.dot(w);
        if cos_p <= 0.0 || cos_y <= 0.0 || d2 <= 0.0 {
            return Vec3::ZERO;
        }
        lflux = e.flux * emitter_radiance(g, &e, a, b);
        s = cos_p * cos_y / (PI * d2);
    }
    if !shading::valid(w, ng, nf) {
        return Vec3::ZERO;
    }
    if intersect_scene(g, o, w, 0.0, d, mask::key(g, rng)).is_some() {
        return Vec3::ZERO;
    }
    let fr = match rough {
        Some((m, wo)) => {
            let (sr, f) = rough_conductor::terms(m, w, wo, nf);
            albedo * f * (sr / (4.0 * wo.dot(nf)))
        }
        None => albedo / PI,
    };
    let l = fr * lflux * s;
    let l = match coat {
        Some(m) => l * plastic::coat_transmittance(g, m.table, cos_p, m.ior),
        None => l,
    };
    l * weight * bump.shadowing(w)
}

/// ray.comp's `environment_ray` traced: the environment's light at diffuse point p by a cosine-weighted
/// direction, weighted against direct_light's environment samples (power heuristic).
#[allow(clippy::too_many_arguments)]
fn environment_by_bsdf(
    g: &GpuScene,
    p: Vec3,
    nf: Vec3,
    ng: Vec3,
    albedo: Vec3,
    coat: Option<&Material>,
    bump: &Bump,
    rng: &mut Rng,
) -> Vec3 {
    let e = first_emitter(g);
    if e.kind != LIGHT_ENVIRONMENT {
        return Vec3::ZERO;
    }
    let u1 = rng.float();
    let u2 = rng.float();
    let w = cosine_direction(nf, u1, u2);
    let cos_p = nf.dot(w);
    if !(cos_p > 0.0) || !shading::valid(w, ng, nf) {
        return Vec3::ZERO;
    }
    let o = offset_ray(g, p, nf);
    if intersect_scene(g, o, w, 0.0, lights::infinite_reach(&e, o), mask::key(g, rng)).is_some() {
        return Vec3::ZERO;
    }
    let pb = cos_p / PI;
    let pl = lights::environment_pdf(g, &e, w) * e.cdf;
    let l = albedo * lights::environment_radiance(g, &e, w) * (pb * pb / (pb * pb + pl * pl));
    let l = match coat {
        Some(m) => l * plastic::coat_transmittance(g, m.table, cos_p, m.ior),
        None => l,
    };
    l * bump.shadowing(w)
}

/// ray.comp's term (d) at a diffuse point or plastic base (`direct_light_ray`, and with an environment
/// `environment_ray`), traced at once and summed (`trace_diffuse`).
#[allow(clippy::too_many_arguments)]
fn direct_diffuse(
    g: &GpuScene,
    p: Vec3,
    nf: Vec3,
    ng: Vec3,
    albedo: Vec3,
    coat: Option<&Material>,
    bump: &Bump,
    rng: &mut Rng,
) -> Vec3 {
    let l = direct_light(g, p, nf, ng, albedo, coat, None, bump, rng);
    if g.has_environment {
        l + environment_by_bsdf(g, p, nf, ng, albedo, coat, bump, rng)
    } else {
        l
    }
}

/// ray.comp's `escaped`: the environment seen along d where an eye path leaves the scene.
fn escaped(g: &GpuScene, d: Vec3) -> Vec3 {
    if !g.has_environment {
        return Vec3::ZERO;
    }
    let e = first_emitter(g);
    lights::environment_radiance(g, &e, d)
}

/// rough_dielectric.glsl's `rough_bounce` at hit `h`: for a rough conductor or rough glass, the new origin,
/// direction and weight (zero: the path ends), its numbers drawn from `rng` in the kernel's order; None
/// for every other surface. An anisotropic lobe lies along the hit's dp/du (`rough_tangent`).
fn rough_bounce(
    g: &GpuScene,
    m: &Material,
    h: &trace::Hit,
    nf: Vec3,
    front: bool,
    rng: &mut Rng,
    d: Vec3,
) -> Option<(Vec3, Vec3, Vec3)> {
    let (pos, dpdu) = (h.pos, if m.alpha_u != m.alpha_v { h.dpdu } else { Vec3::ZERO });
    match m.surface {
        SURFACE_ROUGH_CONDUCTOR => {
            let u = Vec2::new(rng.float(), rng.float());
            Some(rough_conductor::bounce(g, m, pos, nf, dpdu, u, d))
        }
        SURFACE_ROUGH_GLASS => {
            let u = rng.float();
            let u2 = Vec2::new(rng.float(), rng.float());
            let (o, d, w) = rough_dielectric::bounce(g, m, pos, nf, dpdu, front, u, u2, d);
            Some((o, d, Vec3::splat(w)))
        }
        _ => None,
    }
}

/// The probability ray.comp gives a plastic's coat (specular lobe `spec`) over its base (`diff`) when it
/// takes one of them; `None` when both are black.
fn coat_probability(spec: Vec3, diff: Vec3) -> Option<f32> {
    let total = spec.max_element() + diff.max_element();
    (total > 0.0).then(|| spec.max_element() / total)
}

/// An eye vertex as ray.comp's eye paths find it: the hit, its material with the texture applied, the
/// side the ray arrives on (`front`), and the true normal `ng` and shading normal `nf` on that side.
struct EyeVertex {
    h: trace::Hit,
    m: Material,
    front: bool,
    ng: Vec3,
    nf: Vec3,
    /// Its bump or normal map's shadowing term (normal_map.rs).
    bump: Bump,
}

/// The start of every eye vertex on both of ray.comp's eye paths (which write it out twice: as one GLSL
/// function with out-parameters it cost lavapipe 5-8% of the eye pass on glass-on-table,
/// docs/performance.md, "Crates"): the ray o + t d of a path
/// `depth` bounces long must leave the last vertex on the side of both its normals `vng`, `vns`
/// (shading.glsl), be within the depth backstop and hit something, and d must lie on the same side of the
/// hit's normals too, which then become `vng`, `vns`. `None`: the path ends here; `cut` counts a path
/// ended at the backstop (checked second: past it, a direction the last vertex refuses ends the path
/// uncounted); `escaped` is set where the ray leaves the scene (its environment is term (a)).
#[allow(clippy::too_many_arguments)]
fn eye_vertex(
    g: &GpuScene,
    o: Vec3,
    d: Vec3,
    depth: u32,
    vng: &mut Vec3,
    vns: &mut Vec3,
    thr: &mut Vec3,
    bump: &mut Bump,
    rng: &mut Rng,
    cut: &mut u32,
    escaped: &mut bool,
) -> Option<EyeVertex> {
    if !shading::valid(d, *vng, *vns) {
        return None;
    }
    // The last vertex's bump or normal map term for the direction the path leaves it along.
    *thr *= bump.shadowing(d);
    *bump = Bump::default();
    if depth >= g.params.max_eye_depth {
        *cut += 1;
        return None;
    }
    let Some(mut h) = intersect_scene(g, o, d, 0.0, 1e30, mask::key(g, rng)) else {
        *escaped = true;
        return None;
    };
    blend::resolve(g, &mut h, rng);
    let m = texture::apply(g, &g.materials[h.material as usize], h.uv);
    let front = d.dot(h.normal) < 0.0;
    let ng = if front { h.normal } else { -h.normal };
    let (nf, here) = normal_map::perturb(g, &h, ng, shading::normal(&h, ng));
    if !shading::valid(d, ng, nf) {
        return None;
    }
    (*vng, *vns) = (ng, nf);
    *bump = here;
    Some(EyeVertex {
        h,
        m,
        front,
        ng,
        nf,
        bump: here,
    })
}

/// What ray.comp's emission samples saw, which the pilot marks a pixel by: `seen`, a path met an emitter's
/// front that no shadow ray takes; `lit`, a shadow ray reached a light; `rough`, a path sampled through a
/// rough conductor or rough glass; `chain`, a path left a mirror, smooth glass or a smooth coat; `near`,
/// in the pilot, such a chain passed near a light after a curved vertex (ray.comp's MARK_NEAR); `curved`,
/// in the pilot, such a chain followed a curved vertex (MARK_CURVED).
#[derive(Clone, Copy, Debug, Default)]
struct SampleMarks {
    seen: bool,
    lit: bool,
    rough: bool,
    chain: bool,
    near: bool,
    curved: bool,
}

/// ray.comp's `NEAR_REACH`: how near a chain passes a light to mark its pixel (MARK_NEAR), in radii of the
/// sphere around the light.
pub const NEAR_REACH: f32 = 2.0;
/// ray.comp's `NEAR_LIGHTS_MAX`: the lights the pilot's near test looks at, the first in the table.
pub const NEAR_LIGHTS_MAX: usize = 64;

/// ray.comp's `passes_near_light`: whether the ray (o, d) passes within NEAR_REACH times the radius of the
/// sphere around one of the first NEAR_LIGHTS_MAX lights (`lights::emitter_bounds`), ahead of o.
fn passes_near_light(g: &GpuScene, o: Vec3, d: Vec3) -> bool {
    g.lights.iter().take(NEAR_LIGHTS_MAX).any(|light| {
        lights::emitter_bounds(&lights::emitter_of(g, light)).is_some_and(|(c, rb)| {
            let v = c - o;
            let t = v.dot(d);
            let reach = NEAR_REACH * rb;
            (if t > 0.0 { v.dot(v) - t * t } else { v.dot(v) }) < reach * reach
        })
    })
}

/// ray.comp's stratified positions of a pixel's emission samples in one pass (`strata_grid`,
/// `stratum_point`): `count` samples in the cells of an m x n grid (m = floor(sqrt(count)), n = ceil(count /
/// m)), taken in raster order from cell `shift` on, each at a uniform point of its cell.
pub struct Strata {
    pub grid: [u32; 2],
    pub shift: u32,
}

impl Strata {
    /// The grid for `count` samples, its first cell from the uniform number `u`.
    pub fn new(count: u32, u: f32) -> Strata {
        let m = ((count as f32).sqrt() as u32).max(1);
        let grid = [m, count.div_ceil(m)];
        let cells = grid[0] * grid[1];
        Strata {
            grid,
            shift: ((u * cells as f32) as u32).min(cells - 1),
        }
    }

    /// Sample `index`'s position in the pixel, `u` uniform in the unit square.
    pub fn point(&self, index: u32, u: [f32; 2]) -> [f32; 2] {
        let cell = (index + self.shift) % (self.grid[0] * self.grid[1]);
        let c = [cell % self.grid[0], cell / self.grid[0]];
        [0, 1].map(|k| (c[k] as f32 + u[k]) * (1.0 / self.grid[k] as f32))
    }
}

/// One emission eye sample of ray.comp's `emission_sample`: the emission met along the specular chain
/// through sample `index`'s point of the pixel (`strata`), one Fresnel branch chosen with probability f,
/// and with direct light sampled (`RenderParams::direct_light`) term (d) at its diffuse end. `cut` counts
/// a path ended at the depth backstop; `marks` gathers what the pilot marks by (`SampleMarks`).
/// `pilot`: the pilot's sample, which takes each smooth dielectric branch with probability 1/2
/// (`branch_u`).
// The path's state and its marks, each read and set along it.
#[allow(clippy::too_many_arguments)]
fn emission_sample(
    g: &GpuScene,
    px: u32,
    py: u32,
    (strata, index): (&Strata, u32),
    rng: &mut Rng,
    cut: &mut u32,
    marks: &mut SampleMarks,
    pilot: bool,
) -> Vec3 {
    let u = [rng.float(), rng.float()];
    let j = strata.point(index, u);
    let mut o = v3(g.params.eye);
    let mut d = camera_ray(g, px, py, j);
    let mut thr = Vec3::ONE;
    // Term (d) at the plastics passed on the way.
    let mut sum = Vec3::ZERO;
    // The last vertex's normals, which d must lie on the same side of (shading.glsl).
    let (mut vng, mut vns) = (d, d);
    let mut last = Bump::default();
    // Where d left a rough vertex: its lobe's density of d and the vertex (glossy_light.glsl); 0 else.
    let (mut lobe_pdf, mut lobe_from) = (0f32, Vec3::ZERO);
    // The path met a curved vertex (MARK_NEAR).
    let mut bent = false;
    for depth in 0.. {
        // Past the first vertex without a lobe's density: the path left a mirror, glass or a smooth coat.
        if depth > 0 && !(lobe_pdf > 0.0) {
            marks.chain = true;
            if pilot && bent {
                marks.curved = true;
                if !marks.near {
                    marks.near = passes_near_light(g, o, d);
                }
            }
        }
        let mut out = false;
        let Some(EyeVertex {
            h,
            m,
            front,
            ng,
            nf,
            bump,
        }) = eye_vertex(
            g, o, d, depth, &mut vng, &mut vns, &mut thr, &mut last, rng, cut, &mut out,
        )
        else {
            if out {
                let e = thr * escaped(g, d) * glossy_light::escape_weight(g, lobe_pdf, d);
                marks.seen |= e.max_element() > 0.0 && !(lobe_pdf > 0.0);
                sum += e;
            }
            break;
        };
        // Curved: a sphere, or a shading normal more than 0.8 degrees off the face (ray.comp).
        bent |= h.sphere || nf.dot(ng) < 0.9999;
        let m = &m;
        let lobe_in = std::mem::take(&mut lobe_pdf);
        if m.surface == SURFACE_DIFFUSE {
            let mut e = if front {
                thr * v3(m.emission) * glossy_light::lobe_weight(g, lobe_in, lobe_from, &h, v3(m.emission))
            } else {
                Vec3::ZERO
            };
            marks.seen |= e.max_element() > 0.0 && !(lobe_in > 0.0);
            if g.params.direct_light != 0 {
                let l = direct_diffuse(g, h.pos, nf, ng, v3(m.color), None, &bump, rng);
                marks.lit |= l.max_element() > 0.0;
                e += thr * l;
            }
            return sum + e;
        }
        if glossy_hit(g, m) {
            // A glossy hit point's vertex: its term (d), and the path ends.
            let mut e = Vec3::ZERO;
            if g.params.direct_light != 0 {
                let l = direct_light(g, h.pos, nf, ng, v3(m.color), None, Some((m, -d)), &bump, rng);
                marks.lit |= l.max_element() > 0.0;
                e = thr * l;
            }
            return sum + e;
        }
        if conductor::is_reflector(m.surface) {
            thr *= conductor::reflector_weight(m, -d.dot(nf));
            d = reflect(d, nf);
            o = offset_ray(g, h.pos, nf);
            continue;
        }
        if m.surface == SURFACE_PLASTIC {
            // Both lobes: the base's term (d) here, the path on along the coat.
            let (coat_d, spec, diff) = plastic::plastic_lobes(g, m, nf, rng, d);
            if g.params.direct_light != 0 {
                let l = direct_diffuse(g, h.pos, nf, ng, diff, Some(m), &bump, rng);
                marks.lit |= l.max_element() > 0.0;
                sum += thr * l;
            }
            // A rough coat is a rough vertex: its shadow ray, then the lobe's (glossy_light.glsl).
            let wo = -d;
            let rough = glossy_light::rough_coat(m);
            if rough {
                sum += thr * glossy_light::rough_light(g, m, &h, nf, ng, front, wo, &bump, rng, &mut marks.lit);
            }
            thr *= spec;
            d = coat_d;
            o = offset_ray(g, h.pos, nf);
            if rough {
                lobe_pdf = glossy_light::lobe_density(g, m, &h, nf, front, wo, d);
                lobe_from = h.pos;
            }
            continue;
        }
        if m.surface == SURFACE_THIN {
            let w;
            (o, d, w) = thin_dielectric::branch(g, m, h.pos, nf, branch_u(rng, pilot), d);
            thr *= w;
            continue;
        }
        if glossy_light::rough_vertex(g, m) {
            // The light this vertex reflects straight from an emitter by a shadow ray, then the lobe.
            let wo = -d;
            marks.rough = true;
            sum += thr * glossy_light::rough_light(g, m, &h, nf, ng, front, wo, &bump, rng, &mut marks.lit);
            let (o2, d2, w) = rough_bounce(g, m, &h, nf, front, rng, d).expect("a rough surface");
            (o, d) = (o2, d2);
            thr *= w;
            if thr.max_element() <= 0.0 {
                return sum;
            }
            lobe_pdf = glossy_light::lobe_density(g, m, &h, nf, front, wo, d);
            lobe_from = h.pos;
            continue;
        }
        (o, d) = glass_branch(g, h.pos, nf, front, m.ior, branch_u(rng, pilot), d);
    }
    sum
}

/// ray.comp's `branch_u`: the uniform number that picks a smooth dielectric's branch (reflection below the
/// reflectance). Counted samples draw it uniformly (each branch with its Fresnel probability); the pilot,
/// which only marks, takes each branch with probability 1/2, so that it finds a light reflected in glass as
/// readily as one seen through it.
fn branch_u(rng: &mut Rng, pilot: bool) -> f32 {
    let u = rng.float();
    match pilot {
        false => u,
        true if u < 0.5 => 0.0,
        // The largest float below 1: refraction unless totally reflected.
        true => 1.0 - f32::EPSILON / 2.0,
    }
}

/// What one eye pass of `ray.comp` makes.
pub struct EyePass {
    /// `hit_slots` per pixel (empty when the pass traced no hit points).
    pub hits: Vec<HitPoint>,
    /// Per pixel: the sum of this pass's emission samples (rgb) and their count (w).
    pub direct: Vec<[f64; 4]>,
    /// Eye paths ended at the depth backstop.
    pub cut: u32,
}

/// The pilot's marks (ray.comp's `busy`), as the kernel's binding defines them.
pub use ppm_vk_kernels::ray::{MARK_CHAIN, MARK_CURVED, MARK_EMISSION, MARK_LIT, MARK_NEAR, MARK_ROUGH, MARK_SPLIT};

/// ray.comp's count of emission-sample paths a pixel takes per eye pass after the pilot, from its marks:
/// `rough` where the pilot sampled through a rough lobe (the renderer passes
/// `Settings::rough_pixel_samples`, at least `emission`), `emission` where it saw emission or a curved
/// chain passed near a light (MARK_NEAR); with direct
/// light sampled, `light` where a pilot shadow ray reached a light and one where none did (if the pilot
/// took samples at all); else `light` (the renderer passes `Settings::unmarked_samples` there).
pub fn samples_for_mark(direct_light: bool, emission: u32, rough: u32, light: u32, mark: u32) -> u32 {
    if mark & MARK_ROUGH != 0 {
        rough
    } else if mark & (MARK_EMISSION | MARK_NEAR) != 0 {
        emission
    } else if direct_light && emission > 0 && mark & MARK_LIT == 0 {
        light.min(1)
    } else {
        light
    }
}

/// A whole eye pass: the ray kernel's dispatches `pushes` (`Renderer::ray_pushes`), hit points from the
/// one that traces them, emission samples summed over all.
/// `busy`: per pixel, whether the pilot marked it (ray.comp); the pilot pass (push.pilot) sets it.
pub fn eye_pass(g: &GpuScene, pushes: &[RayPush], busy: &mut [u32]) -> EyePass {
    let mut out = EyePass {
        hits: Vec::new(),
        direct: vec![[0f64; 4]; g.pixels() as usize],
        cut: 0,
    };
    for push in pushes {
        let one = ray_pass(g, push, busy);
        if push.trace_hits != 0 {
            out.hits = one.hits;
        }
        for (d, e) in out.direct.iter_mut().zip(&one.direct) {
            for c in 0..4 {
                d[c] += e[c];
            }
        }
        out.cut += one.cut;
    }
    out
}

/// One dispatch of eye pass `push.pass` as `ray.comp` runs it: hit points (with `push.trace_hits`; a negative `jitter`
/// draws a random position in each pixel) and the emission samples.
pub fn ray_pass(g: &GpuScene, push: &RayPush, busy: &mut [u32]) -> EyePass {
    let p = &g.params;
    let slots = p.hit_slots as usize;
    let trace_hits = push.trace_hits != 0;
    let mut out = EyePass {
        hits: if trace_hits {
            vec![HitPoint::default(); g.slots() as usize]
        } else {
            Vec::new()
        },
        direct: vec![[0f64; 4]; g.pixels() as usize],
        cut: 0,
    };
    for pixel in 0..g.pixels() {
        let px = pixel % p.width;
        let py = pixel / p.width;
        let stream = push.pass as u64 * g.pixels() as u64 + pixel as u64;
        let mut emitted = glam::DVec3::ZERO;
        let mut samples = 0u32;
        if trace_hits {
            let mut rng = Rng::new(p.seed as u64 | ((push.salt as u64) << 32), stream);
            let mut j = push.jitter;
            if j[0] < 0.0 {
                j[0] = rng.float();
                j[1] = rng.float();
            }
            // (origin, direction, throughput, depth, and where it left a rough vertex its lobe's density
            // and the vertex: ray.comp's Pending)
            type Pending = (Vec3, Vec3, Vec3, u32, f32, Vec3);
            let first: Pending = (v3(p.eye), camera_ray(g, px, py, j), Vec3::ONE, 0, 0.0, Vec3::ZERO);
            let mut stack: Vec<Pending> = vec![first];
            let mut slot = 0usize;
            let mut hit_emitted = Vec3::ZERO;
            let base = pixel as usize * slots;
            // SPPM's split happens once, at the first rough vertex (ray.comp).
            let mut may_split = p.rough_split != 0;
            // The slots glass, panes and plastics may split into both branches (ray.comp); SPPM's only in
            // the pixels marked MARK_SPLIT.
            let branch_slots = if may_split || (push.jitter[0] < 0.0 && busy[pixel as usize] & MARK_SPLIT == 0) {
                1
            } else {
                slots
            };
            // A fixed point of the pixel counts only when no random sample does (ray.comp).
            let hit_is_sample = push.jitter[0] < 0.0 || push.emission_samples == 0;
            while let Some((mut o, mut d, mut thr, mut depth, mut lobe_pdf, mut lobe_from)) = stack.pop() {
                // The last vertex's normals (shading.glsl); a branch is stacked only where d suits them.
                let (mut vng, mut vns) = (d, d);
                let mut out_of_scene = false;
                // A stacked branch took its vertex's term when stacked.
                let mut last = Bump::default();
                while let Some(EyeVertex {
                    h,
                    m,
                    front,
                    ng,
                    nf,
                    bump,
                }) = eye_vertex(
                    g,
                    o,
                    d,
                    depth,
                    &mut vng,
                    &mut vns,
                    &mut thr,
                    &mut last,
                    &mut rng,
                    &mut out.cut,
                    &mut out_of_scene,
                ) {
                    let m = &m;
                    let lobe_in = std::mem::take(&mut lobe_pdf);
                    let diffuse = m.surface == SURFACE_DIFFUSE;
                    if diffuse || m.surface == SURFACE_PLASTIC {
                        // ray.comp: a diffuse surface, or a plastic's base and coat (both lobes while
                        // there are slots, else one).
                        let (mut diff, mut spec) = (v3(m.color), Vec3::ZERO);
                        let (mut on_base, mut coat) = (true, false);
                        let mut coat_d = d;
                        // 1 / the coat's probability where one lobe is chosen.
                        let mut coat_scale = 1.0;
                        if diffuse {
                            if front {
                                let le = v3(m.emission);
                                hit_emitted += thr * le * glossy_light::lobe_weight(g, lobe_in, lobe_from, &h, le);
                            }
                        } else {
                            (coat_d, spec, diff) = plastic::plastic_lobes(g, m, nf, &mut rng, d);
                            coat = true;
                            if slot + stack.len() + 1 >= branch_slots {
                                let Some(ps) = coat_probability(spec, diff) else {
                                    break;
                                };
                                coat = rng.float() < ps;
                                on_base = !coat;
                                if coat {
                                    spec /= ps;
                                    coat_scale = 1.0 / ps;
                                } else {
                                    diff /= 1.0 - ps;
                                }
                            }
                        }
                        if on_base {
                            if p.direct_light != 0 && hit_is_sample {
                                let coat = (!diffuse).then_some(m);
                                hit_emitted += thr * direct_diffuse(g, h.pos, nf, ng, diff, coat, &bump, &mut rng);
                            }
                            if diff.max_element() > 0.0 && slot < slots {
                                out.hits[base + slot] = HitPoint {
                                    pos: h.pos.to_array(),
                                    pixel,
                                    normal: nf.to_array(),
                                    weight: (thr * diff / PI).to_array(),
                                    ..Default::default()
                                };
                                slot += 1;
                            }
                            if !coat {
                                break;
                            }
                        }
                        // A rough coat followed is a rough vertex: its shadow ray where this path is a
                        // sample, weighed as the coat's lobe is, then the lobe's direction.
                        let wo = -d;
                        let rough = !diffuse && glossy_light::rough_coat(m) && hit_is_sample;
                        if rough {
                            let mut unused = false;
                            hit_emitted += thr
                                * coat_scale
                                * glossy_light::rough_light(g, m, &h, nf, ng, front, wo, &bump, &mut rng, &mut unused);
                        }
                        depth += 1;
                        thr *= spec;
                        d = coat_d;
                        o = offset_ray(g, h.pos, nf);
                        if rough {
                            lobe_pdf = glossy_light::lobe_density(g, m, &h, nf, front, wo, d);
                        }
                        lobe_from = h.pos;
                        continue;
                    }
                    if glossy_hit(g, m) {
                        // ray.comp: a glossy hit point, its term (d) by the BRDF; the path ends.
                        let wo = -d;
                        let cos_o = wo.dot(nf);
                        if cos_o.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                            break;
                        }
                        if p.direct_light != 0 && hit_is_sample {
                            hit_emitted +=
                                thr * direct_light(g, h.pos, nf, ng, v3(m.color), None, Some((m, wo)), &bump, &mut rng);
                        }
                        if slot < slots {
                            out.hits[base + slot] = HitPoint {
                                pos: h.pos.to_array(),
                                pixel,
                                normal: nf.to_array(),
                                brdf: h.material + 1,
                                weight: rough_conductor::hit_weight(m, thr, cos_o).to_array(),
                                wo: oct_encode(wo),
                            };
                            slot += 1;
                        }
                        break;
                    }
                    depth += 1;
                    if glossy_light::rough_vertex(g, m) {
                        // As the emission samples: a shadow ray where this path is one of them, the lobe.
                        let wo = -d;
                        if hit_is_sample {
                            let mut unused = false;
                            hit_emitted += thr
                                * glossy_light::rough_light(g, m, &h, nf, ng, front, wo, &bump, &mut rng, &mut unused);
                        }
                        // SPPM's split (ray.comp): a lobe direction for every slot, each weighted 1 / k.
                        let k = if std::mem::take(&mut may_split) { slots } else { 1 };
                        thr /= k as f32;
                        for _ in 1..k {
                            let (bo, bd, w) = rough_bounce(g, m, &h, nf, front, &mut rng, d).expect("a rough surface");
                            let bt = thr * w;
                            if !(bt.max_element() > 0.0) || !shading::valid(bd, ng, nf) {
                                continue;
                            }
                            let pdf = match hit_is_sample {
                                true => glossy_light::lobe_density(g, m, &h, nf, front, wo, bd),
                                false => 0.0,
                            };
                            stack.push((bo, bd, bt * bump.shadowing(bd), depth, pdf, h.pos));
                        }
                        let (o2, d2, w) = rough_bounce(g, m, &h, nf, front, &mut rng, d).expect("a rough surface");
                        (o, d) = (o2, d2);
                        thr *= w;
                        if thr.max_element() <= 0.0 {
                            break;
                        }
                        if hit_is_sample {
                            lobe_pdf = glossy_light::lobe_density(g, m, &h, nf, front, wo, d);
                        }
                        lobe_from = h.pos;
                        continue;
                    }
                    if m.surface == SURFACE_THIN {
                        let rr = thin_dielectric::reflectance(-d.dot(nf), m.ior);
                        if rr < 1.0 && slot + stack.len() + 1 < branch_slots {
                            let refl = reflect(d, nf);
                            if shading::valid(refl, ng, nf) {
                                let w = thr * (rr * v3(m.color)) * bump.shadowing(refl);
                                stack.push((offset_ray(g, h.pos, nf), refl, w, depth, 0.0, Vec3::ZERO));
                            }
                            thr *= (1.0 - rr) * v3(m.lobe_a);
                            o = offset_ray(g, h.pos, -nf);
                        } else {
                            let w;
                            (o, d, w) = thin_dielectric::branch(g, m, h.pos, nf, rng.float(), d);
                            thr *= w;
                        }
                        continue;
                    }
                    if conductor::is_reflector(m.surface) {
                        thr *= conductor::reflector_weight(m, -d.dot(nf));
                        d = reflect(d, nf);
                        o = offset_ray(g, h.pos, nf);
                        continue;
                    }
                    let eta = if front { 1.0 / m.ior } else { m.ior };
                    let cos_i = -d.dot(nf);
                    let (f, cos_t) = fresnel_dielectric(cos_i, eta);
                    let refl = reflect(d, nf);
                    let refr = (eta * d + (eta * cos_i - cos_t) * nf).normalize();
                    if f >= 1.0 {
                        d = refl;
                        o = offset_ray(g, h.pos, nf);
                    } else if slot + stack.len() + 1 < branch_slots {
                        if shading::valid(refl, ng, nf) {
                            let w = thr * f * bump.shadowing(refl);
                            stack.push((offset_ray(g, h.pos, nf), refl, w, depth, 0.0, Vec3::ZERO));
                        }
                        thr *= 1.0 - f;
                        d = refr;
                        o = offset_ray(g, h.pos, -nf);
                    } else if rng.float() < f {
                        d = refl;
                        o = offset_ray(g, h.pos, nf);
                    } else {
                        d = refr;
                        o = offset_ray(g, h.pos, -nf);
                    }
                }
                if out_of_scene {
                    hit_emitted += thr * escaped(g, d) * glossy_light::escape_weight(g, lobe_pdf, d);
                    // term (a)
                }
            }
            for s in slot..slots {
                out.hits[base + s] = HitPoint {
                    pixel: EMPTY_SLOT,
                    ..Default::default()
                };
            }
            if hit_is_sample {
                emitted += hit_emitted.as_dvec3();
                samples += 1;
            }
        }
        let mut rng = Rng::new(
            p.seed as u64 | ((SALT_EMISSION as u64) << 32),
            ((push.chunk as u64) << 48) | stream,
        );
        let pilot = push.pilot != 0;
        let total = if pilot {
            push.emission_samples
        } else {
            samples_for_mark(
                p.direct_light != 0,
                push.emission_samples,
                push.rough_samples,
                push.light_samples,
                busy[pixel as usize],
            )
        };
        let first = push.chunk * push.per_dispatch;
        let want = total.saturating_sub(first).min(push.per_dispatch);
        // The pilot: `pilot_samples` in every pixel, the rest only where a path left a mirror or glass.
        let mut marks = SampleMarks {
            chain: pilot && busy[pixel as usize] & MARK_CHAIN != 0,
            ..Default::default()
        };
        // The positions of the pass's samples, stratified; the pilot's (marks only) uniform (ray.comp).
        let mut srng = Rng::new(p.seed as u64 | ((SALT_STRATA as u64) << 32), stream);
        let strata = Strata::new(if pilot { 1 } else { total.max(1) }, srng.float());
        for s in 0..want {
            if pilot && first + s >= push.pilot_samples && !marks.chain {
                break;
            }
            let e = emission_sample(
                g,
                px,
                py,
                (&strata, first + s),
                &mut rng,
                &mut out.cut,
                &mut marks,
                pilot,
            );
            if !pilot {
                emitted += e.as_dvec3();
                samples += 1;
            }
        }
        if pilot {
            let bit = |on: bool, mark: u32| on as u32 * mark;
            busy[pixel as usize] |= bit(marks.seen, MARK_EMISSION)
                | bit(marks.lit, MARK_LIT)
                | bit(marks.rough, MARK_ROUGH)
                | bit(marks.chain, MARK_CHAIN)
                | bit(marks.near, MARK_NEAR)
                | bit(marks.curved, MARK_CURVED);
        }
        if samples > 0 {
            out.direct[pixel as usize] = [emitted.x, emitted.y, emitted.z, samples as f64];
        }
    }
    out
}

/// The records of photon `index` (global), as `photon.comp` leaves them; returns false if the path was
/// ended at the depth backstop (`RenderParams::max_photon_depth`) rather than by roulette or escape.
pub fn trace_photon(g: &GpuScene, index: u64, salt: u32, out: &mut Vec<Photon>) -> bool {
    let p = &g.params;
    let mut rng = Rng::new(p.seed as u64 | ((salt as u64) << 32), index);
    let e = choose_emitter(g, rng.float());
    let a = rng.float();
    let b = rng.float();
    let (mut o, mut d, mut flux);
    let mut w = 1.0f32;
    if !is_area(&e) {
        // lights.glsl's emit_photon: a sphere gives its point and normal, for the cosine draw below.
        let (o2, dir, f, direction_given) = lights::emit_photon(g, &e, a, b, &mut rng);
        (o, flux) = (o2, f);
        d = dir;
        if !direction_given {
            (d, w) = targets::emit(&g.params, o, dir, &mut rng);
            flux *= w;
        }
    } else {
        o = offset_ray(g, emitter_point(&e, a, b), e.normal);
        (d, w) = targets::emit(&g.params, o, e.normal, &mut rng);
        flux = e.flux * emitter_radiance(g, &e, a, b) * w;
    }
    // photon.comp: a photon aimed below its light carries nothing and ends.
    if !(w > 0.0) {
        return true;
    }
    // photon.comp's `capped`, without its count.
    let cap = |f: Vec3| shading::capped(f, p.flux_fixed).0;
    for depth in 1..=p.max_photon_depth {
        let Some(mut h) = intersect_scene(g, o, d, 0.0, 1e30, mask::key(g, &mut rng)) else {
            return true;
        };
        blend::resolve(g, &mut h, &mut rng);
        let m = &texture::apply(g, &g.materials[h.material as usize], h.uv);
        let front = d.dot(h.normal) < 0.0;
        let ng = if front { h.normal } else { -h.normal };
        let (nf, bump) = normal_map::perturb(g, &h, ng, shading::normal(&h, ng));
        // Veach's correction (shading.glsl): shading_in here, shading_out on leaving but after a diffuse
        // bounce (drawn about ng); exactly 1 on a flat surface.
        if !shading::valid(d, ng, nf) {
            return true;
        }
        flux = cap(flux * shading::factor_in(-d, ng, nf));
        // A bump or normal map's term, for the direction the photon arrived from (normal_map.rs).
        flux *= bump.shadowing(-d);
        let mut leave = true;
        if (p.direct_light == 0 || depth > 1) && glossy_hit(g, m) {
            // photon.comp: a record on a glossy hit point's surface; its lobe sampled below.
            out.push(Photon {
                pos: h.pos.to_array(),
                cell: trace::grid_key(g, h.pos),
                flux: flux.to_array(),
                dir: oct_encode(d),
            });
        }
        if m.surface == SURFACE_DIFFUSE {
            let c = v3(m.color);
            let pr = c.max_element();
            if pr <= 0.0 {
                return true;
            }
            // photon.comp: with direct light sampled, no record where the photon first lands.
            if p.direct_light == 0 || depth > 1 {
                out.push(Photon {
                    pos: h.pos.to_array(),
                    cell: trace::grid_key(g, h.pos),
                    flux: flux.to_array(),
                    dir: oct_encode(d),
                });
            }
            if rng.float() >= pr {
                return true;
            }
            flux *= c / pr;
            let v1 = rng.float();
            let v2 = rng.float();
            d = cosine_direction(ng, v1, v2);
            o = offset_ray(g, h.pos, ng);
            leave = false;
        } else if conductor::is_reflector(m.surface) {
            flux *= conductor::reflector_weight(m, -d.dot(nf));
            d = reflect(d, nf);
            o = offset_ray(g, h.pos, nf);
        } else if m.surface == SURFACE_PLASTIC {
            // photon.comp samples the plastics, rough conductors and rough glass in one routine
            // (lobe_bounce.glsl); here each keeps its own, as the eye paths' twins do.
            if (p.direct_light == 0 || depth > 1) && v3(m.color).max_element() > 0.0 {
                let t = plastic::coat_transmittance(g, m.table, -d.dot(nf), m.ior);
                out.push(Photon {
                    pos: h.pos.to_array(),
                    cell: trace::grid_key(g, h.pos),
                    flux: (flux * t).to_array(),
                    dir: oct_encode(d),
                });
            }
            let u = [rng.float(), rng.float(), rng.float()];
            let Some((o2, d2, w)) = plastic::scatter(g, m, h.pos, nf, u, &mut rng, d) else {
                return true;
            };
            (o, d) = (o2, d2);
            flux *= w;
        } else if m.surface == SURFACE_THIN {
            let w;
            (o, d, w) = thin_dielectric::branch(g, m, h.pos, nf, rng.float(), d);
            flux *= w;
        } else if let Some((o2, d2, w)) = rough_bounce(g, m, &h, nf, front, &mut rng, d) {
            (o, d) = (o2, d2);
            flux *= w;
            if flux.max_element() <= 0.0 {
                return true;
            }
        } else {
            (o, d) = glass_branch(g, h.pos, nf, front, m.ior, rng.float(), d);
        }
        if !shading::valid(d, ng, nf) {
            return true;
        }
        if leave {
            flux = cap(flux * shading::factor_out(d, ng, nf));
        }
    }
    false
}

/// All records of photons `first..first+count`, in photon order.
pub fn photon_pass(g: &GpuScene, first: u64, count: u32, salt: u32) -> Vec<Photon> {
    let mut out = Vec::new();
    for i in 0..count as u64 {
        trace_photon(g, first + i, salt, &mut out);
    }
    out
}

/// What one hit point gathered (`gather_one`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Gathered {
    /// M: the photons inside the sphere.
    pub m: u32,
    /// Of those, the ones within R / 2 (the update's curvature statistic).
    pub m_half: u32,
    /// Their flux sum in f64 (with the cone weight of eq. 10 when `cone_k` > 0).
    pub flux: DVec3,
}

/// What one hit point gathers from `photons`, by brute force over every photon (an independent check
/// of the grid). `materials`: the scene's (`GpuScene::materials`), for the BRDFs of glossy hit points.
pub fn gather_one(hp: &HitPoint, r2: f64, photons: &[Photon], cone_k: f32, materials: &[Material]) -> Gathered {
    let mut g = Gathered::default();
    if hp.pixel == EMPTY_SLOT {
        return g;
    }
    let r2f = r2 as f32;
    let r = r2f.sqrt();
    let pos = v3(hp.pos);
    let n = v3(hp.normal);
    let glossy = (hp.brdf != 0).then(|| (&materials[hp.brdf as usize - 1], oct_decode(hp.wo).normalize()));
    for p in photons {
        let dv = v3(p.pos) - pos;
        let d2 = dv.dot(dv);
        if d2 > r2f || oct_decode(p.dir).dot(n) >= 0.0 {
            continue;
        }
        let ratio = match glossy {
            Some((m, wo)) => rough_conductor::ratio(m, -oct_decode(p.dir).normalize(), wo, n),
            None => Vec3::ONE,
        };
        let w = if cone_k > 0.0 {
            1.0 - d2.sqrt() / (cone_k * r)
        } else {
            1.0
        }; // eq. 10
        g.m += 1;
        g.m_half += (d2 <= 0.25 * r2f) as u32;
        g.flux += (v3(p.flux) * ratio).as_dvec3() * w as f64;
    }
    g
}

/// `gather_one` for every slot.
pub fn gather(
    hits: &[HitPoint],
    stats: &[HitStats],
    photons: &[Photon],
    cone_k: f32,
    materials: &[Material],
) -> Vec<Gathered> {
    hits.iter()
        .zip(stats)
        .map(|(h, s)| gather_one(h, s.r2, photons, cone_k, materials))
        .collect()
}

/// The progressive update of one hit point (eq. 3, 6; eq. 14 with the cone filter's sums), in f64;
/// `flux_fixed` is the accumulator's fixed-point scale (`RenderParams::flux_fixed`). tau takes the new
/// flux times the hit point's `weight` (w f_r). Then the adaptive shrink (`shrunk`) where `shrink_z` > 0.
pub fn update(
    s: &HitStats,
    a: &PassAccum,
    weight: [f32; 3],
    alpha: f32,
    flux_fixed: f32,
    shrink_z: f32,
    r2_floor: f32,
) -> HitStats {
    if a.m == 0 {
        return *s;
    }
    let m = a.m as f64;
    let m_half = a.m_half as f64;
    let alpha = alpha as f64;
    let ratio = (s.n + alpha * m) / (s.n + m);
    let w = v3(weight).as_dvec3() / flux_fixed as f64;
    let s = HitStats {
        n: s.n + alpha * m,
        r2: s.r2 * ratio,                                 // eq. 3, squared
        tau_r: (s.tau_r + a.flux_r as f64 * w.x) * ratio, // eq. 6
        tau_g: (s.tau_g + a.flux_g as f64 * w.y) * ratio,
        tau_b: (s.tau_b + a.flux_b as f64 * w.z) * ratio,
        probe: s.probe,
        // The curvature statistic: D = M - 4 M_half ~ R^4, Var D = M + 8 M_half ~ R^2.
        curv: (s.curv + (m - 4.0 * m_half)) * ratio * ratio,
        curv_var: (s.curv_var + (m + 8.0 * m_half)) * ratio,
    };
    if shrink_z > 0.0 {
        shrunk(s, shrink_z as f64, r2_floor as f64)
    } else {
        s
    }
}

/// The least factor on R^2 the adaptive shrink applies in one pass (update.comp's SHRINK_MIN).
pub const SHRINK_MIN: f64 = 0.25;

/// The adaptive shrink (update.comp): probe.comp's curvature fit (p / R)^6 = 9 N / (32 D^2) over the
/// accumulated counts, with only the part of |D| beyond `z` standard deviations; where p < R, R^2 takes
/// (p / R)^2 (at least `SHRINK_MIN`, and R^2 at least `r2_floor`), D scales as R^4, and N, tau and D's
/// variance keep the share of them the fit's density puts within p.
pub fn shrunk(s: HitStats, z: f64, r2_floor: f64) -> HitStats {
    let d = (s.curv.abs() - z * s.curv_var.sqrt()).max(0.0);
    if !(9.0 * s.n < 32.0 * d * d) {
        return s;
    }
    let x = 9.0 * s.n / (32.0 * d * d); // (p / R)^6, in (0, 1)
    let t = if x > SHRINK_MIN * SHRINK_MIN * SHRINK_MIN {
        cbrt_f64(x)
    } else {
        SHRINK_MIN
    } // (p / R)^2
    .max(r2_floor / s.r2);
    if !(t < 1.0) {
        return s;
    }
    // The share of the statistics within p under the fit's density (update.comp): t (1 - k (1 - t)), with
    // D whole.
    let k = if s.n > 0.0 { 4.0 * s.curv / (3.0 * s.n) } else { 0.0 };
    let kept = (t * (1.0 - k * (1.0 - t))).clamp(0.0, 1.0);
    HitStats {
        n: s.n * kept,
        r2: s.r2 * t,
        tau_r: s.tau_r * kept,
        tau_g: s.tau_g * kept,
        tau_b: s.tau_b * kept,
        probe: s.probe,
        curv: s.curv * (t * t),
        curv_var: s.curv_var * kept,
    }
}

/// The kernel's cube root: f32's, then two Newton steps in f64.
fn cbrt_f64(x: f64) -> f64 {
    let mut y = (x as f32).powf(1.0 / 3.0) as f64;
    y -= (y * y * y - x) / (3.0 * y * y);
    y -= (y * y * y - x) / (3.0 * y * y);
    y
}

/// Pixel radiance from the statistics (eq. 1-2; eq. 11's normalisation `norm`); `direct` holds the
/// emission samples summed over eye passes (rgb) and their count (w).
pub fn resolve(g: &GpuScene, stats: &[HitStats], direct: &[[f64; 4]], emitted: f64, norm: f32) -> Vec<[f64; 3]> {
    let slots = g.params.hit_slots as usize;
    (0..g.pixels() as usize)
        .map(|pixel| {
            let mut sum = DVec3::ZERO;
            if emitted > 0.0 {
                for st in &stats[pixel * slots..(pixel + 1) * slots] {
                    let area = norm as f64 * std::f64::consts::PI * st.r2;
                    sum += DVec3::new(st.tau_r, st.tau_g, st.tau_b) / (area * emitted);
                }
            }
            let d = direct[pixel];
            let samples = d[3].max(1.0);
            [sum.x + d[0] / samples, sum.y + d[1] / samples, sum.z + d[2] / samples]
        })
        .collect()
}

/// Eq. 7 in units of r^2: lambda / r^2 = (1/N) sum |t_p - g|^2 / r^2 over the `d2` (squared distances) of
/// the photons inside the sphere; 1 (sparse) when there is none (shared/paper/ALGORITHM.md).
pub fn lambda_ratio(d2: &[f64], r2: f64) -> f64 {
    if d2.is_empty() {
        return 1.0;
    }
    d2.iter().sum::<f64>() / d2.len() as f64 / r2
}

/// Eq. 9: the starting radius from r and lambda / r^2, with beta = `beta_frac` r. The test lambda / r <=
/// beta is lambda / r^2 <= beta_frac in both modes; above it the paper enlarges to r (1 + lambda / r), the
/// scale-free variant to r (1 + lambda / r^2).
/// Nearest (`count` probe photons within r, `param` k): r min(sqrt(k / count), 2), 2 r without one.
/// Curvature (`counts` within r / 2, r and 2 r, `param` the largest r' / r): [`curvature_growth`].
pub fn probe_radius(r: f64, ratio: f64, counts: [usize; 3], mode: ProbeMode, param: f64) -> f64 {
    let count = counts[1];
    if mode == ProbeMode::Curvature {
        return r * curvature_growth(counts.map(|c| c as f64)).min(param);
    }
    if mode == ProbeMode::Nearest {
        return r * if count > 0 {
            (param / count as f64).sqrt().min(2.0)
        } else {
            2.0
        };
    }
    let beta_frac = param;
    if mode == ProbeMode::Off || ratio <= beta_frac {
        return r;
    }
    match mode {
        ProbeMode::Paper => r * (1.0 + ratio * r), // lambda / r = ratio * r
        _ => r * (1.0 + ratio),
    }
}

/// The radius p / R of least error of a density estimate from Na photons within R and Nb within R / 2,
/// written from the closed forms rather than probe.comp's text: N(p) = pi p^2 f + pi p^4 L / 8 over a disc
/// (f the density, L its Laplacian) gives f and L from the two counts; the estimate at radius p has bias
/// p^2 L / 8 and variance f / (pi p^2), least in sum at p^6 = 32 f / (pi L^2). |Na - 4 Nb| counts only
/// beyond `CURVATURE_Z` standard deviations of its noise (sqrt(Na + 8 Nb)). At most 2 (2 where flat).
pub fn curvature_fit(na: f64, nb: f64) -> f64 {
    const CURVATURE_Z: f64 = 2.0;
    let big_r = 1.0; // a unit radius: the result is a ratio
    let area = std::f64::consts::PI * big_r * big_r;
    let laplacian_abs =
        ((na - 4.0 * nb).abs() - CURVATURE_Z * (na + 8.0 * nb).sqrt()).max(0.0) * 32.0 / (3.0 * area * big_r * big_r);
    if laplacian_abs == 0.0 {
        return 2.0;
    }
    let density = na / area;
    let p6 = 32.0 * density / (std::f64::consts::PI * laplacian_abs * laplacian_abs);
    p6.powf(1.0 / 6.0).min(2.0)
}

/// The curvature probe's r' / r from the probe photons within r / 2, r and 2 r: the smaller of the fits at
/// R = r and at R = 2 r, so that a radius grows only where the density is flat out to 2 r; r / 8 to 2 r.
pub fn curvature_growth([half, n1, two]: [f64; 3]) -> f64 {
    curvature_fit(n1, half)
        .min(2.0 * curvature_fit(two, n1))
        .clamp(0.125, 2.0)
}

/// The probe pass over `photons` for every slot, as probe.comp computes it: (lambda / r^2, new r^2).
pub fn probe(
    hits: &[HitPoint],
    stats: &[HitStats],
    photons: &[Photon],
    mode: ProbeMode,
    param: f32,
) -> Vec<(f64, f64)> {
    hits.iter()
        .zip(stats)
        .map(|(hp, st)| {
            if hp.pixel == EMPTY_SLOT {
                return (0.0, st.r2);
            }
            let r2f = st.r2 as f32;
            let pos = v3(hp.pos);
            let n = v3(hp.normal);
            // The curvature rule looks up to 2 r; within r / 2 by probe.comp's test in f32 (d^2 / r^2).
            let reach = if mode == ProbeMode::Curvature { 4.0 * r2f } else { r2f };
            let near: Vec<f32> = photons
                .iter()
                .filter_map(|p| {
                    let dv = v3(p.pos) - pos;
                    let d2 = dv.dot(dv);
                    (d2 <= reach && oct_decode(p.dir).dot(n) < 0.0).then_some(d2)
                })
                .collect();
            let d2: Vec<f64> = near.iter().filter(|&&d| d <= r2f).map(|&d| d as f64).collect();
            let half = near.iter().filter(|&&d| d <= r2f && d * (1.0 / r2f) <= 0.25).count();
            let ratio = lambda_ratio(&d2, st.r2);
            let counts = [half, d2.len(), near.len()];
            let r = probe_radius(st.r2.sqrt(), ratio, counts, mode, param as f64);
            (ratio, r * r)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic points uniform on a disc of radius r (a Fibonacci spiral: equal area per point).
    fn disc(r: f64, n: usize) -> Vec<f64> {
        (0..n).map(|i| r * r * (i as f64 + 0.5) / n as f64).collect() // squared radii, uniform in area
    }

    /// Exact counts of the density f(y) = a + b |y|^2 (Laplacian 4 b) within p: pi p^2 a + pi b p^4 / 2.
    fn quadratic_counts(a: f64, b: f64) -> (f64, f64) {
        let n = |p: f64| std::f64::consts::PI * (a * p * p + b * p.powi(4) / 2.0);
        (n(1.0), n(0.5))
    }

    /// Counts within r / 2, r and 2 r of a disc of light of radius `spot` (as a fraction of r) holding
    /// `inside` photons over a flat floor of `per_r` photons per disc of radius r.
    fn spot_counts(spot: f64, inside: f64, per_r: f64) -> [f64; 3] {
        [0.5, 1.0, 2.0].map(|p: f64| inside * (p / spot).min(1.0).powi(2) + per_r * p * p)
    }

    #[test]
    fn curvature_probe_finds_the_radius_of_least_error() {
        // Counts so large that the noise margin is negligible: r'^6 = 32 f / (pi L^2), with f the
        // density the disc holds on average (N1 / pi) and L = 4 b, as computed here from the density.
        for (a, b) in [(1e12, 1e11), (1e12, -3e11), (5e12, 4e12)] {
            let (n1, n2) = quadratic_counts(a, b);
            let want = (32.0 * (n1 / std::f64::consts::PI) / (std::f64::consts::PI * 16.0 * b * b)).powf(1.0 / 6.0);
            let got = curvature_fit(n1, n2);
            assert!((got / want.min(2.0) - 1.0).abs() < 1e-3, "a {a} b {b}: {got} vs {want}");
        }
        // A flat density (doubling the radius takes in 4 times the photons), or none, reads as flat: the
        // largest radius.
        assert_eq!(curvature_growth([100.0, 400.0, 1600.0]), 2.0);
        assert_eq!(curvature_growth([0.0; 3]), 2.0);
        // A difference within twice its noise does not count: 40 photons, 12 of them within r / 2
        // (D = -8, noise sqrt(136) ~ 11.7).
        assert_eq!(curvature_growth([12.0, 40.0, 160.0]), 2.0);
        // A spot much narrower than r shrinks r, the more the more photons it holds.
        let few = curvature_growth(spot_counts(0.2, 100.0, 20.0));
        let many = curvature_growth(spot_counts(0.2, 10_000.0, 20.0));
        assert!(many < few && few < 1.0, "{few} {many}");
        assert_eq!(curvature_growth([1e12, 1e12, 1e12]), 0.125);
        // A caustic 100 times brighter than the floor just past r (a ring from 1.2 r out): flat within r,
        // so the fit at r alone would grow r to 2 r, into it; the fit at 2 r keeps r' below 1.2 r.
        let ring = |p: f64| 100.0 * 20.0 * (p * p - 1.44).max(0.0);
        let counts = [0.5, 1.0, 2.0].map(|p: f64| 20.0 * p * p + ring(p));
        assert_eq!(curvature_fit(counts[1], counts[0]), 2.0);
        let g = curvature_growth(counts);
        assert!(g < 1.2, "grew into the caustic: {g}");
    }

    #[test]
    fn lambda_of_a_uniform_disc_is_half_r_squared() {
        // E|t - g|^2 over a uniform disc of radius r is r^2 / 2 (eq. 7's closed form).
        let r = 0.37;
        assert!((lambda_ratio(&disc(r, 100_000), r * r) - 0.5).abs() < 1e-9);
    }

    #[test]
    fn lambda_of_photons_at_the_centre_is_zero_and_of_none_is_sparse() {
        assert_eq!(lambda_ratio(&[0.0; 10], 0.01), 0.0);
        assert_eq!(lambda_ratio(&[], 0.01), 1.0);
    }

    #[test]
    fn eq9_branches_at_the_boundary() {
        let r = 0.5;
        for mode in [ProbeMode::Paper, ProbeMode::ScaleFree] {
            // lambda / r <= beta keeps r, exactly at the boundary too.
            assert_eq!(probe_radius(r, 0.2, [0; 3], mode, 0.2), r);
            assert_eq!(probe_radius(r, 0.0, [0; 3], mode, 0.2), r);
        }
        // Just above: the paper adds lambda (an area) to r: r (1 + lambda / r) = r + lambda.
        let ratio = 0.2 + 1e-12;
        assert!((probe_radius(r, ratio, [0; 3], ProbeMode::Paper, 0.2) - (r + ratio * r * r)).abs() < 1e-15);
        assert!((probe_radius(r, ratio, [0; 3], ProbeMode::ScaleFree, 0.2) - r * (1.0 + ratio)).abs() < 1e-15);
        // The scale-free rule does not depend on units; the paper's does.
        let (a, b) = (
            probe_radius(1.0, 0.5, [0; 3], ProbeMode::ScaleFree, 0.2),
            probe_radius(1000.0, 0.5, [0; 3], ProbeMode::ScaleFree, 0.2),
        );
        assert!((b / a - 1000.0).abs() < 1e-9);
        let (a, b) = (
            probe_radius(1.0, 0.5, [0; 3], ProbeMode::Paper, 0.2),
            probe_radius(1000.0, 0.5, [0; 3], ProbeMode::Paper, 0.2),
        );
        assert!((b / a - 1000.0).abs() > 100.0, "paper rule: {a} vs {b}");
        assert_eq!(probe_radius(r, 0.9, [0; 3], ProbeMode::Off, 0.2), r);
    }

    #[test]
    fn cone_filter_normalisation_is_unbiased_for_a_uniform_density() {
        // The mean of w = 1 - d / (k r) over a uniform disc is 1 - 2 / (3k) (eq. 11): E[d] = 2r/3.
        for k in [1.0f64, 1.1, 2.0] {
            let d2 = disc(1.0, 200_000);
            let mean_w = d2.iter().map(|d2| 1.0 - d2.sqrt() / k).sum::<f64>() / d2.len() as f64;
            assert!((mean_w - (1.0 - 2.0 / (3.0 * k))).abs() < 1e-5, "k {k}: {mean_w}");
        }
    }

    #[test]
    fn adaptive_shrink_finds_the_closed_form_optimum() {
        // A density f(rho) = f0 + c rho^2 about the hit point (Laplacian L = 4c) holds
        // N(p) = pi p^2 f0 + pi c p^4 / 2 photons within p. The estimate N(p) / (pi p^2) has bias
        // c p^2 / 2 and variance f0 / (pi p^2) (Poisson), least in sum at p^6 = 2 f0 / (pi c^2): derived
        // here from the density, not from the fit's counts. One pass of exactly the expected counts, no
        // significance test (z = 0): the update's eq. 3 and then the shrink must land on that p, up to the
        // c R^2 / f0 the counts hold beyond the quadratic's leading term.
        let pi = std::f64::consts::PI;
        let count = |f0: f64, c: f64, p: f64| pi * p * p * f0 + pi * c * p.powi(4) / 2.0;
        for (f0, c, r) in [(4.0e5, -4.0e4, 0.3), (4.0e5, 4.0e4, 0.3), (1.0e9, -9.0e11, 0.004)] {
            let optimum = (2.0 * f0 / (pi * c * c)).powf(1.0 / 6.0);
            let s = HitStats {
                r2: r * r,
                ..Default::default()
            };
            let a = PassAccum {
                m: count(f0, c, r).round() as u32,
                m_half: count(f0, c, r / 2.0).round() as u32,
                ..Default::default()
            };
            let alpha = 0.7f32;
            let plain = update(&s, &a, [1.0; 3], alpha, 1.0, 0.0, 0.0);
            let shrunk = update(&s, &a, [1.0; 3], alpha, 1.0, 1e-30, 0.0);
            let (r_eq3, r_new) = (plain.r2.sqrt(), shrunk.r2.sqrt());
            assert!(
                optimum < r_eq3 && optimum > 0.5 * r_eq3,
                "the case must be in the fit's range"
            );
            let drift = (c * r * r / f0).abs(); // the quadratic's next term, relative
            assert!(
                (r_new / optimum - 1.0).abs() < drift,
                "f0 {f0}, c {c}: R {r_new} against the optimum {optimum} (eq. 3's {r_eq3})"
            );
            // What the statistics keep within the new radius: adaptive_shrink_keeps_what_the_density_holds.
        }
    }

    #[test]
    fn adaptive_shrink_keeps_what_the_density_holds() {
        // Statistics of exactly the counts a density f(rho) = f0 + c rho^2 puts within R and R / 2, at a
        // peak much narrower than R (f(R) a fifth of f0) and at a dip: the shrink to p must keep the
        // closed form's N(p) of them (and as much of tau), not the area's share (p / R)^2 of N(R), which
        // would spread the peak's photons over the disc.
        let pi = std::f64::consts::PI;
        let count = |f0: f64, c: f64, p: f64| pi * p * p * f0 + pi * c * p.powi(4) / 2.0;
        for (f0, c, r) in [
            (1.0e6, -0.8e6 / 0.09, 0.3),
            (1.0e6, -0.5e6 / 0.09, 0.3),
            (1.0e6, 2.0e6 / 0.09, 0.3),
        ] {
            let (n, half) = (count(f0, c, r), count(f0, c, r / 2.0));
            let s = HitStats {
                r2: r * r,
                n,
                tau_r: n,
                tau_g: 2.0 * n,
                tau_b: 0.5 * n,
                curv: n - 4.0 * half,
                curv_var: n + 8.0 * half,
                ..Default::default()
            };
            // With or without the significance test: it decides whether to shrink, not what is kept.
            for z in [0.0, 2.0] {
                let shrunk = shrunk(s, z, 0.0);
                let p = shrunk.r2.sqrt();
                assert!(p < 0.9 * r, "f0 {f0}, c {c}: the case must shrink ({p} of {r})");
                let want = count(f0, c, p);
                assert!(
                    (shrunk.n / want - 1.0).abs() < 1e-9,
                    "c {c}, z {z}: N(p) {} against {want}",
                    shrunk.n
                );
                assert!((shrunk.tau_g / (2.0 * want) - 1.0).abs() < 1e-9);
                let area = n * (p / r).powi(2);
                println!(
                    "c {c:e}, z {z}: p / R {:.3}, kept {:.4} of N, the area's share {:.4}",
                    p / r,
                    want / n,
                    area / n
                );
            }
        }
    }

    #[test]
    fn cone_filter_progressive_estimate_is_unbiased() {
        // Photons of flux 1 uniform on a plane at density rho per unit area; the filtered progressive
        // estimate tau / ((1 - 2/(3k)) pi R^2 N_emitted / M_per_unit) must converge to rho over many
        // passes (eq. 12-14), with R shrinking by eq. 3.
        let (k, alpha, rho) = (1.1f64, 0.7f64, 4000.0f64);
        let norm = 1.0 - 2.0 / (3.0 * k);
        let mut rng = rng::Rng::new(3, 9);
        let mut s = HitStats {
            r2: 0.01,
            ..Default::default()
        };
        let mut emitted = 0f64;
        for _ in 0..400 {
            // One pass: photons uniform on a 1x1 square around the hit point (Poisson count ~ rho).
            let count = rho as usize;
            emitted += count as f64;
            let r = s.r2.sqrt();
            let (mut m, mut tau_m) = (0u32, 0f64);
            for _ in 0..count {
                let (x, y) = (rng.float() as f64 - 0.5, rng.float() as f64 - 0.5);
                let d = (x * x + y * y).sqrt();
                if d * d <= s.r2 {
                    m += 1;
                    tau_m += 1.0 - d / (k * r); // eq. 10
                }
            }
            let acc = PassAccum {
                flux_r: (tau_m * 65536.0).round() as i64,
                m,
                ..Default::default()
            };
            s = update(&s, &acc, [1.0; 3], alpha as f32, 65536.0, 0.0, 0.0);
        }
        // Radiance-like estimate of the density: tau / (norm pi R^2) per emitted photon, times the
        // photons per pass per unit area (rho photons over an area of 1).
        let estimate = s.tau_r / (norm * std::f64::consts::PI * s.r2 * emitted) * rho;
        assert!((estimate / rho - 1.0).abs() < 0.03, "estimate {estimate} vs {rho}");
    }
}

#[cfg(test)]
mod strata_tests {
    use super::Strata;

    /// ray.comp's stratified positions: for every count a pixel may take and every first cell, the samples
    /// fall in distinct cells (all of them when the count fills the grid), each position inside its own
    /// cell and the pixel; and each sample's cell, over the first cells, is every cell once, so a uniform
    /// first cell makes each position uniform over the pixel (each sample unbiased).
    #[test]
    fn strata_cover_the_pixel_once_and_each_sample_is_uniform() {
        for count in 1..=40u32 {
            let grid = Strata::new(count, 0.0).grid;
            let cells = grid[0] * grid[1];
            assert!(
                cells >= count && cells < count + grid[0],
                "count {count}: grid {grid:?}"
            );
            assert!(
                grid[0] <= grid[1] && grid[1] <= grid[0] + 2,
                "count {count}: grid {grid:?} not near square"
            );
            if let Some(m) = (1..=6).find(|m| m * m == count) {
                assert_eq!(grid, [m, m], "a square count is a square grid");
            }
            for shift in 0..cells {
                let u = (shift as f32 + 0.5) / cells as f32;
                let s = Strata::new(count, u);
                assert_eq!(s.shift, shift, "count {count}: u {u}");
                let mut seen = vec![false; cells as usize];
                for index in 0..count {
                    for corner in [[0.0, 0.0], [0.999_999, 0.999_999], [0.3, 0.7]] {
                        let p = s.point(index, corner);
                        assert!(p.iter().all(|&x| (0.0..1.0).contains(&x)), "count {count}: {p:?}");
                        let cell = (p[1] * grid[1] as f32) as u32 * grid[0] + (p[0] * grid[0] as f32) as u32;
                        assert_eq!(cell, (index + shift) % cells, "count {count}, index {index}: {p:?}");
                    }
                    let cell = ((index + shift) % cells) as usize;
                    assert!(
                        !std::mem::replace(&mut seen[cell], true),
                        "count {count}: cell {cell} twice"
                    );
                }
                assert_eq!(seen.iter().filter(|&&s| s).count() as u32, count);
            }
            // Over the first cells, each sample takes every cell once.
            for index in 0..count {
                let mut hits = vec![0u32; cells as usize];
                for shift in 0..cells {
                    hits[((index + shift) % cells) as usize] += 1;
                }
                assert!(hits.iter().all(|&h| h == 1), "count {count}, index {index}: {hits:?}");
            }
        }
        // The last first cell for u just below 1.
        assert_eq!(Strata::new(16, 0.999_999_94).shift, 15);
    }
}

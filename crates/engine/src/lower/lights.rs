//! The light table (lights.glsl): every light, chosen in proportion to its power, for photons and shadow
//! rays alike; an environment map's sampling tables (written after the textures); and the fixed-point
//! scale of the photon flux sums, which the most flux one photon can carry bounds.

use std::f64::consts::PI;

use glam::{DVec3, Vec3};
use ppm_vk_kernels::layout::{
    Light, Triangle, LIGHT_DIRECTIONAL, LIGHT_ENVIRONMENT, LIGHT_POINT, LIGHT_QUAD, LIGHT_SPHERE, LIGHT_SPOT,
    LIGHT_TRIANGLE,
};

use crate::error::{Error, Result};
use crate::scene::texture::{Filter, Pattern, Texture, Wrap};
use crate::scene::{Emitter, EnvMap, Environment, Scene};

/// What [`lights`] builds.
pub struct LightTable {
    pub lights: Vec<Light>,
    /// Total emitted power per channel (W; an environment's: what crosses the scene's bounding disk).
    pub total_power: [f64; 3],
    /// The most flux one photon can leave a light with (any channel): bounds the fixed-point sums.
    pub max_flux: f64,
    /// The kinds present, as bits `1 << LIGHT_*` (the kernels leave out the code of the others).
    pub kinds: u32,
}

/// A light before the table's probabilities: its record (power, kind, geometry) and, per unit of
/// 1 / prob, the most flux one of its photons carries.
struct Entry {
    light: Light,
    flux_bound: f64,
}

fn max3(v: [f32; 3]) -> f64 {
    v.iter().fold(0f64, |m, &x| m.max(x as f64))
}

/// The lights of `scene` (`triangles`: its BVH's, in leaf order), in this order: the environment (light 0,
/// which lights.glsl's first_emitter reads), emitting quads, triangles, spheres, then the other emitters.
/// An environment map's tables are appended to `textures` (lights.glsl reads them there); `texture_at` is
/// the texel of each scene texture's header there (a radiance texture), `triangle_texels` the triangles'
/// texture coordinates (textures::triangle_texels).
pub fn lights(
    scene: &Scene,
    triangles: &[Triangle],
    triangle_texels: &[[u32; 4]],
    texture_at: &[u32],
    textures: &mut Vec<[u32; 4]>,
) -> Result<LightTable> {
    let (lo, hi) = scene.bounds();
    // The scene's bounding sphere, a little larger (Mitsuba's, for the same reason: photons from the sun
    // and the sky start outside it).
    let centre = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length() * (1.0 + 1e-3))
        .max(1e-6 * centre.abs().max_element())
        .max(1e-20);
    let mut entries = Vec::new();
    // Lambertian emitters of radiance L and area A emit L A pi.
    let area_light = |index: u32, kind: u32, emission: Vec3, area: f32| {
        let power = emission * area * std::f32::consts::PI;
        Entry {
            light: Light {
                index,
                kind,
                power: power.to_array(),
                // Le, which shadow rays at rough vertices weigh against the lobe (ray/glossy_light.glsl).
                value: emission.to_array(),
                ..Default::default()
            },
            flux_bound: max3(power.to_array()),
        }
    };
    let environment = scene.emitters.iter().find_map(|e| match e {
        Emitter::Environment(env) => Some(env),
        _ => None,
    });
    if let Some(env) = environment {
        entries.push(environment_light(env, centre, radius, textures)?);
    }
    for qi in scene.lights() {
        let q = &scene.quads[qi as usize];
        let m = &scene.materials[q.material as usize];
        let Some(t) = m.emission_texture else {
            entries.push(area_light(qi, LIGHT_QUAD, m.emission, q.area()));
            continue;
        };
        // A radiance texture (Mitsuba's area emitter with a textured `radiance`): photons leave uniformly
        // in area with flux Le(uv) A pi / prob, unbiased for any prob; the power that sets prob is the
        // texture's mean over the quad's uv square times A pi, and the bound its largest value's.
        let texture = &scene.textures[t as usize];
        let per_radiance = q.area() as f64 * PI;
        let mut entry = area_light(qi, LIGHT_QUAD, Vec3::ZERO, q.area());
        entry.light.power = (texture_mean(texture) * per_radiance).as_vec3().to_array();
        entry.light.flux = [per_radiance as f32; 3];
        entry.light.value = [1.0; 3]; // the texture gives Le
        entry.light.texture = texture_at[t as usize] + 1;
        entry.flux_bound = texture.max().max_element() as f64 * per_radiance;
        entries.push(entry);
    }
    for (ti, t) in triangles.iter().enumerate() {
        let m = &scene.materials[t.material as usize];
        let e = m.emission;
        if e.max_element() > 0.0 {
            let (v0, v1, v2) = (Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2));
            let area = 0.5 * (v1 - v0).cross(v2 - v0).length();
            let Some(k) = m.emission_texture else {
                entries.push(area_light(ti as u32, LIGHT_TRIANGLE, e, area));
                continue;
            };
            // A radiance texture: photons leave uniformly in area with flux Le(uv) A pi / prob (unbiased
            // for any prob); the power that sets prob is the texture's largest value over the triangle's
            // texels times A pi (a bound: prob > 0 wherever Le > 0, and no photon carries more than
            // power / prob), lights.glsl's emitter_radiance reading its material's texture there.
            let texture = &scene.textures[k as usize];
            let at = 3 * ti;
            let f = |x: u32| f32::from_bits(x);
            let (a, c) = (triangle_texels[at], triangle_texels[at + 1]);
            let uv = [[f(a[0]), f(a[1])], [f(a[2]), f(a[3])], [f(c[0]), f(c[1])]];
            let most = texture_max_over(texture, uv).as_dvec3();
            let per_radiance = area as f64 * PI;
            let mut entry = area_light(ti as u32, LIGHT_TRIANGLE, Vec3::ZERO, area);
            entry.light.power = (most * per_radiance).as_vec3().to_array();
            entry.light.flux = [per_radiance as f32; 3];
            entry.light.value = [1.0; 3]; // the texture gives Le
            entry.light.texture = texture_at[k as usize] + 1;
            entry.flux_bound = most.max_element() * per_radiance;
            entries.push(entry);
        }
    }
    for (si, s) in scene.spheres.iter().enumerate() {
        let e = scene.materials[s.material as usize].emission;
        if e.max_element() > 0.0 {
            let area = 4.0 * std::f32::consts::PI * s.radius * s.radius;
            let mut entry = area_light(si as u32, LIGHT_SPHERE, e, area);
            entry.light.origin = s.center.to_array();
            entry.light.radius = s.radius;
            entry.light.value = e.to_array();
            entries.push(entry);
        }
    }
    for e in &scene.emitters {
        if let Some(entry) = delta_light(e, centre, radius) {
            entries.push(entry);
        }
    }
    entries.retain(|e| e.light.power.iter().any(|&p| p > 0.0));
    let sum: f64 = entries
        .iter()
        .map(|e| e.light.power.iter().map(|&p| p as f64).sum::<f64>())
        .sum();
    if entries.is_empty() || sum.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        let what = "no light emits power: every light's power (an emitter's emission x area x pi, a point's or \
                    spot's intensity over its solid angle, the sun's or the sky's flux through the scene) rounds \
                    to 0 in 32-bit floats (raise the emission or the lights' size)";
        return Err(Error::scene(&scene.name, 0, 0, "", what));
    }
    let mut run = 0f64;
    for e in &mut entries {
        run += e.light.power.iter().map(|&p| p as f64).sum::<f64>() / sum;
        e.light.cdf = run as f32;
    }
    if let Some(last) = entries.last_mut() {
        last.light.cdf = 1.0; // no photon may fall past the last light through rounding
    }
    // Each light's probability is the share of [0, 1) its f32 cdf gives it, so that power / prob stays
    // unbiased where 100k lights make the rounding of the running sum matter.
    let mut previous = 0f64;
    for e in &mut entries {
        e.light.prob = (e.light.cdf as f64 - previous) as f32;
        previous = e.light.cdf as f64;
    }
    if let Some(i) = entries
        .iter()
        .position(|e| e.light.prob.is_nan() || e.light.prob <= 0.0)
    {
        let message = format!(
            "light {i} of {} has too small a share of the total power to be chosen in an f32 light table \
             (split the scene's lights more evenly)",
            entries.len()
        );
        return Err(Error::scene(&scene.name, 0, 0, "", message));
    }
    let mut total_power = [0f64; 3];
    for e in &entries {
        for (total, &p) in total_power.iter_mut().zip(&e.light.power) {
            *total += p as f64;
        }
    }
    let max_flux = entries
        .iter()
        .map(|e| e.flux_bound / e.light.prob as f64)
        .fold(0f64, f64::max);
    let kinds = entries.iter().fold(0, |k, e| k | 1 << e.light.kind);
    Ok(LightTable {
        lights: entries.into_iter().map(|e| e.light).collect(),
        total_power,
        max_flux,
        kinds,
    })
}

/// Pixel index i of a side of n, wrapped (texture.glsl's wrap_pixel).
fn wrap_index(wrap: Wrap, i: i64, n: i64) -> i64 {
    match wrap {
        Wrap::Clamp => i.clamp(0, n - 1),
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::Mirror => {
            let m = i.rem_euclid(n);
            if i.div_euclid(n) & 1 != 0 {
                n - 1 - m
            } else {
                m
            }
        }
    }
}

/// Texture `t`'s value at its coordinates `st` (after to_uv), in f64: texture.glsl's texture_value.
fn texture_at_st(t: &Texture, s: f64, u: f64) -> DVec3 {
    let (width, height, pixels) = match &t.pattern {
        Pattern::Checkerboard { color0, color1 } => {
            let upper = (s - s.floor() > 0.5, u - u.floor() > 0.5);
            return if upper.0 == upper.1 { color0 } else { color1 }.as_dvec3();
        }
        Pattern::Bitmap { width, height, pixels } => (*width as i64, *height as i64, pixels),
    };
    let wrap = |i: i64, n: i64| wrap_index(t.wrap, i, n);
    let px = |x: i64, y: i64| pixels[(wrap(y, height) * width + wrap(x, width)) as usize].as_dvec3();
    let (x, y) = (s * width as f64, u * height as f64);
    if t.filter == Filter::Nearest {
        return px(x.floor() as i64, y.floor() as i64);
    }
    let (x, y) = (x - 0.5, y - 0.5);
    let (i, j) = (x.floor(), y.floor());
    let (fx, fy) = (x - i, y - j);
    let (i, j) = (i as i64, j as i64);
    (1.0 - fy) * ((1.0 - fx) * px(i, j) + fx * px(i + 1, j)) + fy * ((1.0 - fx) * px(i, j + 1) + fx * px(i + 1, j + 1))
}

/// Most pixels [`texture_max_over`] scans for one triangle; beyond, the whole image's largest value.
const MAX_SCANNED_PIXELS: i64 = 1 << 16;

/// The largest value per channel texture `t` takes on the triangle of surface coordinates `uv`: the
/// largest of the pixels (wrapped) that its coordinates' bounding box, widened by a pixel each way,
/// reaches (bilinear and nearest lookups mix no others); a checkerboard's larger colour.
fn texture_max_over(t: &Texture, uv: [[f32; 2]; 3]) -> Vec3 {
    let Pattern::Bitmap { width, height, pixels } = &t.pattern else {
        return t.max();
    };
    let [a, b, c, d, e, f] = t.to_uv.map(f64::from);
    let st = uv.map(|[u, v]| (a * u as f64 + b * v as f64 + c, d * u as f64 + e * v as f64 + f));
    let (w, h) = (*width as i64, *height as i64);
    let range = |lo: f64, hi: f64, n: i64| {
        let (i0, i1) = ((lo * n as f64).floor() - 1.0, (hi * n as f64).floor() + 1.0);
        if !(i0.is_finite() && i1.is_finite()) || i1 - i0 + 1.0 >= n as f64 {
            (0, n - 1)
        } else {
            (i0 as i64, i1 as i64)
        }
    };
    let fold = |g: fn(f64, f64) -> f64, pick: fn(&(f64, f64)) -> f64| st.iter().map(pick).fold(pick(&st[0]), g);
    let (x0, x1) = range(fold(f64::min, |p| p.0), fold(f64::max, |p| p.0), w);
    let (y0, y1) = range(fold(f64::min, |p| p.1), fold(f64::max, |p| p.1), h);
    if (x1 - x0 + 1) * (y1 - y0 + 1) > MAX_SCANNED_PIXELS {
        return t.max();
    }
    let wrap = |i: i64, n: i64| wrap_index(t.wrap, i, n);
    let mut most = Vec3::ZERO;
    for y in y0..=y1 {
        for x in x0..=x1 {
            most = most.max(pixels[(wrap(y, h) * w + wrap(x, w)) as usize]);
        }
    }
    most
}

/// Most patches [`texture_mean`] sums exactly; beyond (a to_uv that repeats a large image many times),
/// and for a to_uv that turns the image, a midpoint rule of `MEAN_QUADRATURE`^2 points instead.
const MAX_MEAN_PATCHES: f64 = (1u64 << 24) as f64;
const MEAN_QUADRATURE: usize = 1024;

/// The mean of texture `t` over the unit square of surface coordinates (a quad's uv): exact (to f64
/// rounding) where to_uv neither turns nor shears it. The texture is bilinear (or constant) on each patch
/// of the grid of step 1 / (2 width) by 1 / (2 height) in its coordinates (pixel edges and centres; a
/// checkerboard's halves), and a bilinear function's integral over a rectangle is its area times its
/// value at the centre: the sum over the patches that the image of the square cuts. Otherwise a midpoint
/// rule: its error only moves photons between lights (prob), never the image's expectation, as each
/// photon's flux is Le(uv) A pi / prob.
fn texture_mean(t: &Texture) -> DVec3 {
    let [a, b, c, d, e, f] = t.to_uv.map(f64::from);
    let (w, h) = match t.pattern {
        Pattern::Bitmap { width, height, .. } => (width as f64, height as f64),
        Pattern::Checkerboard { .. } => (1.0, 1.0),
    };
    let (ds, dt) = (0.5 / w, 0.5 / h);
    let patches = (a.abs() / ds + 2.0) * (e.abs() / dt + 2.0);
    if b == 0.0 && d == 0.0 && a != 0.0 && e != 0.0 && patches <= MAX_MEAN_PATCHES {
        let (s0, s1) = (c.min(a + c), c.max(a + c));
        let (t0, t1) = (f.min(e + f), f.max(e + f));
        let cuts = |lo: f64, hi: f64, step: f64| {
            let mut v = vec![lo];
            let mut k = (lo / step).floor() + 1.0;
            while k * step < hi {
                v.push(k * step);
                k += 1.0;
            }
            v.push(hi);
            v
        };
        let (xs, ys) = (cuts(s0, s1, ds), cuts(t0, t1, dt));
        let mut sum = DVec3::ZERO;
        for y in ys.windows(2) {
            for x in xs.windows(2) {
                let centre = texture_at_st(t, 0.5 * (x[0] + x[1]), 0.5 * (y[0] + y[1]));
                sum += centre * ((x[1] - x[0]) * (y[1] - y[0]));
            }
        }
        return sum / ((s1 - s0) * (t1 - t0));
    }
    let n = MEAN_QUADRATURE;
    let mut sum = DVec3::ZERO;
    for j in 0..n {
        for i in 0..n {
            let (u, v) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
            sum += texture_at_st(t, a * u + b * v + c, d * u + e * v + f);
        }
    }
    sum / (n * n) as f64
}

/// A unit vector perpendicular to unit n (any one: the frames lights.glsl draws directions in).
fn perpendicular(n: Vec3) -> Vec3 {
    let a = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    n.cross(a).normalize()
}

/// A point, spot or directional light's entry (None for an environment, which is light 0).
fn delta_light(e: &Emitter, centre: Vec3, radius: f32) -> Option<Entry> {
    let four_pi = 4.0 * std::f32::consts::PI;
    let (light, flux_bound) = match *e {
        Emitter::Point { position, intensity } => {
            let power = intensity * four_pi;
            let light = Light {
                kind: LIGHT_POINT,
                power: power.to_array(),
                origin: position.to_array(),
                value: intensity.to_array(),
                ..Default::default()
            };
            (light, max3(power.to_array()))
        }
        Emitter::Spot {
            position,
            direction,
            intensity,
            cutoff,
            beam,
        } => {
            // Power: I times the falloff's integral over the sphere, 2 pi [(1 - cos b) + the linear ramp's
            // part] = 2 pi (1 + (sin b - sin c) / (c - b)) (1 - cos c where b = c). Photons leave uniform
            // in the cone, each with I 2 pi (1 - cos c) times the falloff in its direction.
            let (b, c) = (beam as f64, cutoff as f64);
            let solid = if c - b > 1e-6 {
                2.0 * PI * (1.0 + (b.sin() - c.sin()) / (c - b))
            } else {
                2.0 * PI * (1.0 - c.cos())
            };
            let cone = 2.0 * PI * (1.0 - c.cos());
            let i = intensity.as_dvec3();
            let light = Light {
                kind: LIGHT_SPOT,
                power: (i * solid).as_vec3().to_array(),
                origin: position.to_array(),
                normal: direction.to_array(),
                edge_u: perpendicular(direction).to_array(),
                value: intensity.to_array(),
                flux: (i * cone).as_vec3().to_array(),
                cos_cutoff: cutoff.cos(),
                cos_beam: beam.cos(),
                cutoff,
                inv_width: if cutoff > beam { 1.0 / (cutoff - beam) } else { 0.0 },
                ..Default::default()
            };
            (light, i.max_element() * cone)
        }
        Emitter::Directional { direction, irradiance } => {
            // The flux through the bounding sphere's disk facing it.
            let power = irradiance * (std::f32::consts::PI * radius * radius);
            let light = Light {
                kind: LIGHT_DIRECTIONAL,
                power: power.to_array(),
                origin: centre.to_array(),
                radius,
                normal: direction.to_array(),
                edge_u: perpendicular(direction).to_array(),
                value: irradiance.to_array(),
                ..Default::default()
            };
            (light, max3(power.to_array()))
        }
        Emitter::Environment(_) => return None,
    };
    Some(Entry { light, flux_bound })
}

/// The environment's entry, its map's sampling tables appended to `textures` (lights.glsl's layout).
fn environment_light(env: &Environment, centre: Vec3, radius: f32, textures: &mut Vec<[u32; 4]>) -> Result<Entry> {
    let disk = PI * radius as f64 * radius as f64;
    let to_world = env.to_world;
    let mut light = Light {
        kind: LIGHT_ENVIRONMENT,
        index: u32::MAX,
        origin: centre.to_array(),
        radius,
        normal: to_world.y_axis.to_array(),
        edge_u: to_world.x_axis.to_array(),
        value: env.scale.to_array(),
        ..Default::default()
    };
    let scale = env.scale.as_dvec3();
    let Some(map) = &env.map else {
        // Uniform directions: L 4 pi through the disk of area pi R^2.
        let power = scale * (4.0 * PI * disk);
        light.power = power.as_vec3().to_array();
        return Ok(Entry {
            light,
            flux_bound: power.max_element(),
        });
    };
    light.index = u32::try_from(textures.len()).map_err(|_| limit_error(map))?;
    let (table, integral, bound) = envmap_table(map);
    if textures.len() + table.len() > i32::MAX as usize {
        return Err(limit_error(map));
    }
    textures.extend(table);
    // Power: pi R^2 times the integral of L over the sphere; a photon's flux L pi R^2 / pdf is at most
    // pi R^2 times `bound` (per unit of scale).
    light.power = (scale * integral * disk).as_vec3().to_array();
    Ok(Entry {
        light,
        flux_bound: scale.max_element() * bound * disk,
    })
}

fn limit_error(map: &EnvMap) -> Error {
    Error::scene(
        &map.name,
        0,
        0,
        "filename",
        "the environment map and the textures together exceed the texel buffer's 2^31 texels",
    )
}

/// An environment map's texels (lights.glsl's table), the integral of its radiance over the sphere (per
/// channel; bilinear pixels, by the midpoint of each cell), and the largest L / pdf a sample can have
/// (any channel), from the f32 cdfs the kernels read.
fn envmap_table(map: &EnvMap) -> (Vec<[u32; 4]>, DVec3, f64) {
    let (w, h) = (map.width as usize, map.height as usize);
    let px = |row: usize, col: usize| map.pixels[row * w + col % w];
    let bands = h - 1;
    let band_angle = PI / bands as f64;
    // A cell (band i, column j) is the patch between pixels (i, j), (i, j + 1), (i + 1, j), (i + 1, j + 1);
    // its radiance, bilinear, is at most the largest of their channels, and sin theta at most s_i, so a
    // weight m s_i bounds L sin theta everywhere in it: pdf > 0 wherever L > 0, and L / pdf stays bounded.
    let mut weights = vec![0f64; bands * w];
    let mut integral = DVec3::ZERO;
    for i in 0..bands {
        let (t0, t1) = (i as f64 * band_angle, (i + 1) as f64 * band_angle);
        let s_max = if t0 <= PI / 2.0 && PI / 2.0 <= t1 {
            1.0
        } else {
            t0.sin().max(t1.sin())
        };
        let s_mid = (0.5 * (t0 + t1)).sin();
        for j in 0..w {
            let corners = [px(i, j), px(i, j + 1), px(i + 1, j), px(i + 1, j + 1)];
            let m = corners.iter().fold(0f32, |m, c| m.max(c.max_element())) as f64;
            weights[i * w + j] = m * s_max;
            let mean = corners.iter().fold(DVec3::ZERO, |s, c| s + c.as_dvec3()) / 4.0;
            integral += mean * s_mid * band_angle * (2.0 * PI / w as f64);
        }
    }
    let mut out = Vec::with_capacity(1 + w * h + bands + bands * w);
    out.push([w as u32, h as u32, 0, 0]);
    out.extend(map.pixels.iter().map(|p| {
        let [r, g, b] = p.to_array().map(f32::to_bits);
        [r, g, b, 0]
    }));
    let band_sums: Vec<f64> = weights.chunks(w).map(|row| row.iter().sum()).collect();
    let band_cdf = inclusive_cdf(&band_sums);
    out.extend(band_cdf.iter().map(|&c| [c.to_bits(), 0, 0, 0]));
    let mut bound = 0f64;
    for i in 0..bands {
        let row = &weights[i * w..(i + 1) * w];
        let col_cdf = inclusive_cdf(row);
        out.extend(col_cdf.iter().map(|&c| [c.to_bits(), 0, 0, 0]));
        let p_band = band_cdf[i] - if i > 0 { band_cdf[i - 1] } else { 0.0 };
        for j in 0..w {
            let p_col = col_cdf[j] - if j > 0 { col_cdf[j - 1] } else { 0.0 };
            if row[j] > 0.0 && p_band > 0.0 && p_col > 0.0 {
                // L / pdf <= m 2 pi^2 sin theta / (p_band p_col w (h - 1)) <= weight 2 pi^2 / (...).
                let pdf_uv = p_band as f64 * p_col as f64 * (w * bands) as f64;
                bound = bound.max(row[j] * 2.0 * PI * PI / pdf_uv);
            }
        }
    }
    (out, integral, bound)
}

/// Inclusive f32 running sums of `weights` divided by their total, the last exactly 1 (uniform where the
/// total is 0: such a band is never chosen).
fn inclusive_cdf(weights: &[f64]) -> Vec<f32> {
    let total: f64 = weights.iter().sum();
    let n = weights.len();
    let mut run = 0f64;
    let mut out: Vec<f32> = weights
        .iter()
        .enumerate()
        .map(|(k, &x)| {
            run += x;
            if total > 0.0 {
                (run / total) as f32
            } else {
                (k + 1) as f32 / n as f32
            }
        })
        .collect();
    if let Some(last) = out.last_mut() {
        *last = 1.0;
    }
    out
}

/// The fixed-point scale of the photon flux sums (`RenderParams::flux_fixed`): a power of two that keeps
/// the most flux one photon carries under 2^30.
pub fn flux_fixed(scene: &Scene, max_flux: f64) -> Result<f32> {
    // No photon carries more flux than it leaves its light with (roulette divides by the largest
    // albedo, mirrors, glass and thin panes never amplify, a plastic's branches weigh at most 1:
    // plastic.glsl), so this bounds one photon's share of a fixed-point sum.
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
    Ok(flux_fixed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::texture::IDENTITY_UV;

    fn bitmap(w: u32, h: u32, filter: Filter, wrap: Wrap, to_uv: [f32; 6]) -> Texture {
        Texture {
            name: "t".into(),
            pattern: Pattern::Bitmap {
                width: w,
                height: h,
                pixels: (0..w * h)
                    .map(|i| Vec3::new((i % 7) as f32, (i * i % 5) as f32 * 0.5, 1.0 + (i % w) as f32))
                    .collect(),
            },
            filter,
            wrap,
            to_uv,
        }
    }

    /// The midpoint rule on an n x n grid of the unit square of surface coordinates.
    fn midpoint(t: &Texture, n: usize) -> DVec3 {
        let [a, b, c, d, e, f] = t.to_uv.map(f64::from);
        let mut sum = DVec3::ZERO;
        for j in 0..n {
            for i in 0..n {
                let (u, v) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                sum += texture_at_st(t, a * u + b * v + c, d * u + e * v + f);
            }
        }
        sum / (n * n) as f64
    }

    /// texture_mean is exact: a repeating bitmap's mean over one period is its pixels' mean (each
    /// pixel's tent or box integrates to 1 / (w h)), a checkerboard's over whole periods its colours';
    /// a clamped, mirrored or offset one agrees with a dense midpoint rule as the rule converges.
    #[test]
    fn texture_means_are_exact() {
        for filter in [Filter::Bilinear, Filter::Nearest] {
            let t = bitmap(5, 3, filter, Wrap::Repeat, IDENTITY_UV);
            let Pattern::Bitmap { pixels, .. } = &t.pattern else {
                unreachable!()
            };
            let mean = pixels.iter().map(|p| p.as_dvec3()).sum::<DVec3>() / pixels.len() as f64;
            assert!((texture_mean(&t) - mean).abs().max_element() < 1e-12, "{filter:?}");
        }
        let checker = Texture {
            name: "c".into(),
            pattern: Pattern::Checkerboard {
                color0: Vec3::new(1.0, 2.0, 3.0),
                color1: Vec3::new(5.0, 0.0, 1.0),
            },
            filter: Filter::Bilinear,
            wrap: Wrap::Repeat,
            to_uv: [2.0, 0.0, 0.0, 0.0, 3.0, 0.0],
        };
        assert!((texture_mean(&checker) - DVec3::new(3.0, 1.0, 2.0)).abs().max_element() < 1e-12);
        for (wrap, to_uv) in [
            (Wrap::Clamp, [1.3, 0.0, -0.2, 0.0, 0.7, 0.1]),
            (Wrap::Mirror, [-2.5, 0.0, 0.3, 0.0, 1.5, -0.4]),
        ] {
            let t = bitmap(4, 6, Filter::Bilinear, wrap, to_uv);
            let (exact, dense) = (texture_mean(&t), midpoint(&t, 4000));
            // The midpoint rule's error here: at most ~1e-4 (its cells that straddle a patch's edge).
            assert!(
                (exact - dense).abs().max_element() < 1e-3,
                "{wrap:?}: {exact} against {dense}"
            );
        }
    }

    /// texture_max_over bounds the texture everywhere on the triangle (dense samples of it never exceed
    /// it) under each filter and wrap mode, a turning to_uv, and triangles from tiny to many periods wide
    /// (where it falls back to the image's largest value).
    #[test]
    fn the_triangle_bound_holds_over_the_triangle() {
        let cases = [
            (Filter::Bilinear, Wrap::Repeat, [1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
            (Filter::Nearest, Wrap::Clamp, [0.8, 0.3, 0.1, -0.2, 1.1, 0.05]),
            (Filter::Bilinear, Wrap::Mirror, [-2.5, 0.4, 0.3, 0.1, 1.5, -0.4]),
        ];
        let triangles = [
            [[0.1, 0.1], [0.15, 0.1], [0.1, 0.17]],
            [[0.3, 0.6], [0.9, 0.2], [0.5, 0.95]],
            [[-0.7, 0.2], [0.4, -0.3], [0.05, 1.3]],
            [[0.0, 0.0], [40.0, 0.0], [0.0, 30.0]],
        ];
        for (filter, wrap, to_uv) in cases {
            let t = bitmap(9, 7, filter, wrap, to_uv);
            let [a, b, c, d, e, f] = to_uv.map(f64::from);
            for uv in triangles {
                let bound = texture_max_over(&t, uv).as_dvec3();
                let n = 60;
                for i in 0..=n {
                    for j in 0..=n - i {
                        let (p, q) = (i as f64 / n as f64, j as f64 / n as f64);
                        let at = |k: usize| (1.0 - p - q) * uv[0][k] as f64 + p * uv[1][k] as f64 + q * uv[2][k] as f64;
                        let (u, v) = (at(0), at(1));
                        let value = texture_at_st(&t, a * u + b * v + c, d * u + e * v + f);
                        assert!(
                            value.cmple(bound + 1e-12).all(),
                            "{filter:?} {wrap:?} {uv:?}: {value} over {bound}"
                        );
                    }
                }
            }
        }
    }

    /// A textured quad light's power is its texture's mean times A pi, its photons' flux per unit of
    /// radiance A pi / prob, and the bound on one photon's flux the texture's largest value times A pi.
    #[test]
    fn a_textured_lights_power_and_bound_come_from_its_texture() {
        let mut scene = Scene::parse(
            r#"name = "t"
[camera]
eye = [0.0, 1.0, 3.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
vfov = 40.0
resolution = [8, 8]
[materials.glow]
emission = [1.0, 1.0, 1.0]
[[quad]]
origin = [0.0, 1.0, 0.0]
edge_u = [2.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 1.5]
material = "glow"
"#,
            "t.toml",
        )
        .unwrap();
        let t = bitmap(5, 3, Filter::Bilinear, Wrap::Repeat, IDENTITY_UV);
        let (mean, most) = (texture_mean(&t), t.max());
        scene.textures.push(t);
        scene.materials[0].emission_texture = Some(0);
        scene.materials[0].emission = most;
        scene.validate().unwrap();
        let table = lights(&scene, &[], &[], &[7], &mut Vec::new()).unwrap();
        let l = &table.lights[0];
        let a_pi = 3.0 * PI;
        assert_eq!((l.kind, l.texture, l.prob), (LIGHT_QUAD, 8, 1.0));
        assert_eq!(l.flux, [a_pi as f32; 3]);
        for c in 0..3 {
            assert!((l.power[c] as f64 / (mean[c] * a_pi) - 1.0).abs() < 1e-6);
        }
        assert!((table.max_flux / (most.max_element() as f64 * a_pi) - 1.0).abs() < 1e-12);
    }
}

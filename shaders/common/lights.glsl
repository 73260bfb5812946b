// The lights: emitting quads, triangles and spheres, points, spots, the sun (directional) and an
// environment, chosen in proportion to their power (crates/engine/src/lower/lights.rs builds the table).
// photon.comp starts photons from them (emit_photon); ray.comp samples them for the direct light at its
// eye paths' diffuse points (light_sample) and looks the environment up where an eye path leaves the
// scene (environment_radiance). The including kernel declares, before this file,
//   layout(std430, binding = N) readonly buffer Lights { Light lights[]; };
// (read only where the lights are not compiled in, SCENE_INLINE_LIGHTS). An environment, if any, is light 0.
// CPU twin: crates/reference/src/lights.rs.
#ifndef LIGHTS_GLSL
#define LIGHTS_GLSL
#include "bvh.glsl"

// The Emitter of a light record (its quad or triangle read from the scene).
Emitter emitter_of(Light light) {
    vec3 flux = (light.kind == LIGHT_SPOT || light.texture != 0u ? light.flux : light.power) / light.prob;
    if (light.kind == LIGHT_TRIANGLE) {
        Triangle tr = bvh_triangle(light.index);
        return Emitter(tr.v0, tr.v1 - tr.v0, tr.v2 - tr.v0, bvh_normal(tr), flux, light.cdf, LIGHT_TRIANGLE,
                       light.value, 0.0, 0.0, 0.0, 0.0, 0.0, light.texture != 0u ? light.index + 1u : 0u);
    }
    if (light.kind == LIGHT_QUAD) {
        Quad q = quads[light.index];
        float disk = q.shape == QUAD_DISK ? 1.0 : 0.0; // Emitter::radius
        return Emitter(q.origin, q.edge_u, q.edge_v, q.normal, flux, light.cdf, LIGHT_QUAD, light.value, disk, 0.0,
                       0.0, 0.0, 0.0, light.texture);
    }
    vec3 value = light.kind == LIGHT_ENVIRONMENT ? light.value : light.value / light.prob;
    return Emitter(light.origin, light.edge_u, cross(light.edge_u, light.normal), light.normal, flux, light.cdf,
                   light.kind, value, light.radius, light.cos_cutoff, light.cos_beam,
                   light.cutoff, light.inv_width, light.index);
}

// The light for the uniform number u: the first whose running cdf exceeds u.
#ifdef SCENE_INLINE_LIGHTS
// The lights are constants: a chain of selects, unrolled, reads no memory (a dynamically indexed constant
// array would be copied per invocation). A triangle's normal is computed from its edges as the buffer
// path below computes it (bvh_normal), so both start from the same bits.
Emitter choose_emitter(float u) {
    Emitter e = SCENE_EMITTERS[0];
    [[unroll]] for (uint i = 1u; i < NUM_LIGHTS; i++) {
        if (u >= SCENE_EMITTERS[i - 1u].cdf) e = SCENE_EMITTERS[i];
    }
    if (e.kind == LIGHT_TRIANGLE) e.normal = triangle_normal(e.edge_u, e.edge_v);
    return e;
}

// Light 0, which is the environment when the scene has one.
Emitter first_emitter() { return SCENE_EMITTERS[0]; }
#else
// Binary search for the first light whose cdf exceeds u (the same light as a linear scan: cdfs never
// decrease), in ceil(log2 n) steps: scenes may have 100k emitting triangles.
Emitter choose_emitter(float u) {
    uint lo = 0u;
    uint hi = params.num_lights - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (u >= lights[mid].cdf) lo = mid + 1u; else hi = mid;
    }
    return emitter_of(lights[lo]);
}

Emitter first_emitter() { return emitter_of(lights[0]); }
#endif

// A disk's (a quad with radius 1: the ellipse inscribed in it) planar coordinates for uniform (a, b): the
// polar map (sqrt(a), 2 pi b) of the unit disk, uniform in area (and an affine map keeps it so).
vec2 disk_point(float a, float b) {
    float r = 0.5 * sqrt(a);
    float phi = 2.0 * PI * b;
    return vec2(0.5 + r * cos(phi), 0.5 + r * sin(phi));
}

// The point of emitter e at uniform numbers (a, b), uniform in its area: a triangle folds the unit square
// onto the half below its diagonal, a disk takes disk_point.
vec3 emitter_point(Emitter e, float a, float b) {
    if (e.kind == LIGHT_TRIANGLE && a + b > 1.0) {
        a = 1.0 - a;
        b = 1.0 - b;
    }
    if (e.kind == LIGHT_QUAD && e.radius != 0.0) {
        vec2 p = disk_point(a, b);
        a = p.x;
        b = p.y;
    }
    return e.origin + a * e.edge_u + b * e.edge_v;
}

// What multiplies e.flux at emitter_point(e, a, b): a quad's radiance texture there (its uv is the point's
// planar coordinates, as a hit's: (a, b), a disk's disk_point), a textured triangle's (e.table - 1 is the triangle: its material's texture
// at its interpolated uv, as surface_uv), else 1 (e.flux is then the whole flux). As Mitsuba 3's area
// emitter with a textured radiance, sampled uniformly in area: the flux Le(uv) A pi / prob is unbiased for
// any prob.
vec3 emitter_radiance(Emitter e, float a, float b) {
    if (!HAS_TEXTURES || e.table == 0u || e.kind > LIGHT_TRIANGLE) return vec3(1.0);
    if (e.kind == LIGHT_QUAD) return texture_value(e.table - 1u, e.radius != 0.0 ? disk_point(a, b) : vec2(a, b));
    if (a + b > 1.0) { // emitter_point's fold
        a = 1.0 - a;
        b = 1.0 - b;
    }
    uint prim = e.table - 1u;
    uint m = bvh_triangle(prim).material;
    uint radiance = texelFetch(material_texels, int(MATERIAL_TEXELS * m + 5u)).w;
    vec4 t = uintBitsToFloat(texelFetch(triangle_texels, int(TRIANGLE_TEXELS * prim)));
    vec2 t2 = uintBitsToFloat(texelFetch(triangle_texels, int(TRIANGLE_TEXELS * prim + 1u)).xy);
    return texture_value(radiance - 1u, (1.0 - a - b) * t.xy + a * t.zw + b * t2);
}

// A quad or triangle: sampled by emitter_point and the cosine about its normal (the code every scene had
// before the other kinds, kept apart so that scenes with only these compile to what they did).
bool is_area(Emitter e) { return e.kind <= LIGHT_TRIANGLE; }

// Uniform on the unit sphere.
vec3 uniform_sphere(float a, float b) {
    float z = 1.0 - 2.0 * a;
    float r = sqrt(max(0.0, 1.0 - z * z));
    float phi = 2.0 * PI * b;
    return vec3(r * cos(phi), r * sin(phi), z);
}

// Direction at (cos_theta, phi) about unit axis n, in the frame (t, b, n).
vec3 about(vec3 t, vec3 b, vec3 n, float cos_theta, float sin_theta, float phi) {
    return sin_theta * cos(phi) * t + sin_theta * sin(phi) * b + cos_theta * n;
}

// A spot's intensity profile at cos_theta from its axis (Mitsuba's spot): 1 inside the beam, falling
// linearly in the angle to 0 at the cutoff.
float spot_falloff(Emitter e, float cos_theta) {
    if (!(cos_theta > e.cos_cutoff)) return 0.0;
    if (cos_theta >= e.cos_beam) return 1.0;
    return max(0.0, (e.cutoff - acos(cos_theta)) * e.inv_width); // acos rounds: never below 0
}

// --- The environment: a constant, or a latitude-longitude map of w x h pixels (Mitsuba's envmap).
// Table (texture_texels, from texel e.table; lower/lights.rs writes it): texel 0 (w, h); then the pixels
// (rgb), row by row from the top (v = 0, local +y); then the inclusive cdf of the h - 1 row bands (x);
// then per band the inclusive cdf of its w cells (x). Pixel (i, j) sits at u = (j + 0.5) / w, v = i / (h - 1)
// and radiance is bilinear between them (u wraps), as Mitsuba's envmap evaluates it; a cell is the patch
// between four pixels, and sampling picks a band, a cell in it, and a point uniform in the cell's (u, v).

float table_float(uint at) { return uintBitsToFloat(texelFetch(texture_texels, int(at)).x); }

vec3 env_pixel(uint first, uint w, uint row, uint col) {
    return uintBitsToFloat(texelFetch(texture_texels, int(first + row * w + col)).xyz);
}

// The first of the n inclusive cdf entries from `first` that exceeds u, and u's place in its interval.
uint cdf_search(uint first, uint n, float u, out float t, out float p) {
    uint lo = 0u;
    uint hi = n - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (u >= table_float(first + mid)) lo = mid + 1u; else hi = mid;
    }
    float before = lo > 0u ? table_float(first + lo - 1u) : 0.0;
    p = table_float(first + lo) - before;
    t = clamp((u - before) / p, 0.0, 0.99999994);
    return lo;
}

// The probability cdf_search gives entry i of the inclusive cdf from `first`: its share of [0, 1).
float cdf_share(uint first, uint i) {
    return table_float(first + i) - (i > 0u ? table_float(first + i - 1u) : 0.0);
}

// The solid-angle density of a direction drawn uniformly in the (u, v) of a cell of the map's w x h pixels
// chosen with probability p_cell: a density of cells = w (h - 1) over the unit square, and du dv =
// dw / (2 pi^2 sin theta).
float cell_density(uvec2 size, float p_cell, float sin_theta) {
    return sin_theta > 0.0 ? p_cell * float(size.x * (size.y - 1u)) / (2.0 * PI * PI * sin_theta) : 0.0;
}

// Local direction of map coordinates (u, v): Mitsuba's (local y up, u = 0 towards -z).
vec3 envmap_direction(float u, float v) {
    float phi = 2.0 * PI * u;
    float theta = PI * v;
    return vec3(sin(phi) * sin(theta), cos(theta), -cos(phi) * sin(theta));
}

// World to the environment's local frame (its rotation's transpose).
vec3 env_local(Emitter e, vec3 d) { return vec3(dot(e.edge_u, d), dot(e.normal, d), dot(e.edge_v, d)); }

// The map's cell under local direction d: its band and column, and where in the pixel grid d falls.
void env_cell(uint w, uint h, vec3 d, out uint band, out uint col, out vec2 f) {
    float u = atan(d.x, -d.z) * (0.5 / PI);
    float v = acos(clamp(d.y, -1.0, 1.0)) * (1.0 / PI);
    float x = u * float(w) - 0.5;
    x -= float(w) * floor(x / float(w)); // in [0, w)
    float y = v * float(h - 1u);
    col = min(uint(x), w - 1u);
    band = min(uint(y), h - 2u);
    f = vec2(x - float(col), y - float(band));
}

// The bilinear radiance of cell (band, col) at f in it, times the scale.
vec3 env_bilinear(Emitter e, uint w, uint band, uint col, vec2 f) {
    uint first = e.table + 1u;
    uint next = col + 1u == w ? 0u : col + 1u;
    vec3 c00 = env_pixel(first, w, band, col);
    vec3 c01 = env_pixel(first, w, band, next);
    vec3 c10 = env_pixel(first, w, band + 1u, col);
    vec3 c11 = env_pixel(first, w, band + 1u, next);
    return e.value * ((1.0 - f.y) * ((1.0 - f.x) * c00 + f.x * c01) + f.y * ((1.0 - f.x) * c10 + f.x * c11));
}

// The radiance arriving from world direction d.
vec3 environment_radiance(Emitter e, vec3 d) {
    if (e.table == 0xffffffffu) return e.value;
    uvec2 size = texelFetch(texture_texels, int(e.table)).xy;
    uint band, col;
    vec2 f;
    env_cell(size.x, size.y, env_local(e, d), band, col, f);
    return env_bilinear(e, size.x, band, col, f);
}

// The solid-angle density with which env_sample draws world direction d.
float environment_pdf(Emitter e, vec3 d) {
    if (e.table == 0xffffffffu) return 1.0 / (4.0 * PI);
    uvec2 size = texelFetch(texture_texels, int(e.table)).xy;
    uint band, col;
    vec2 f;
    vec3 l = env_local(e, d);
    env_cell(size.x, size.y, l, band, col, f);
    uint rows = e.table + 1u + size.x * size.y;
    uint cols = rows + size.y - 1u + band * size.x;
    return cell_density(size, cdf_share(rows, band) * cdf_share(cols, col), sqrt(max(0.0, 1.0 - l.y * l.y)));
}

// A world direction towards the environment for uniform (a, b), its solid-angle density, and the radiance
// from it (read from the cell drawn, not looked up again from the direction).
vec3 env_sample(Emitter e, float a, float b, out float pdf, out vec3 radiance) {
    if (e.table == 0xffffffffu) {
        pdf = 1.0 / (4.0 * PI);
        radiance = e.value;
        return uniform_sphere(a, b);
    }
    uvec2 size = texelFetch(texture_texels, int(e.table)).xy;
    uint rows = e.table + 1u + size.x * size.y;
    float ty, tx, p_band, p_col;
    uint band = cdf_search(rows, size.y - 1u, a, ty, p_band);
    uint col = cdf_search(rows + size.y - 1u + band * size.x, size.x, b, tx, p_col);
    float u = (float(col) + tx + 0.5) / float(size.x);
    float v = (float(band) + ty) / float(size.y - 1u);
    vec3 l = envmap_direction(u - floor(u), v);
    pdf = cell_density(size, p_band * p_col, sin(PI * v));
    radiance = env_bilinear(e, size.x, band, col, vec2(tx, ty));
    return l.x * e.edge_u + l.y * e.normal + l.z * e.edge_v;
}

// How far a shadow ray from o towards an infinite light (the sun, the environment) goes: past the scene's
// bounding sphere.
float infinite_reach(Emitter e, vec3 o) { return 2.0 * (e.radius + length(o - e.origin)); }

// The sphere around an emitter with an area (a quad, a disk, a triangle, a sphere): its centre and radius.
// False for a point, a spot, the sun and the environment, which have none (ray.comp's pilot: a chain
// passing near a light).
bool emitter_bounds(Emitter e, out vec3 centre, out float radius) {
    if (e.kind == LIGHT_QUAD) {
        centre = e.origin + 0.5 * (e.edge_u + e.edge_v);
        radius = 0.5 * max(length(e.edge_u + e.edge_v), length(e.edge_u - e.edge_v));
        return true;
    }
    if (e.kind == LIGHT_TRIANGLE) {
        centre = e.origin + (e.edge_u + e.edge_v) * (1.0 / 3.0);
        vec3 a = e.origin - centre;
        radius = max(length(a), max(length(a + e.edge_u), length(a + e.edge_v)));
        return true;
    }
    centre = e.origin;
    radius = e.radius;
    return e.kind == LIGHT_SPHERE;
}

// --- Shadow rays: light other than a quad's or triangle's reaching the ray origin o (offset from its
// surface), for uniform (a, b): the unit direction w towards it, how far the shadow ray goes, and li, the
// radiance (or intensity / d^2, or irradiance) divided by the density of w and by prob, so that the
// estimate of the reflected light is f_r li cos_p. pdf: w's solid-angle density times prob, for an
// environment's multiple importance sampling (0 for a delta light). False: nothing arrives.
bool light_sample(Emitter e, vec3 o, float a, float b, out vec3 w, out float dist, out vec3 li, out float pdf) {
    pdf = 0.0;
    if (HAS_SPHERE_LIGHTS && e.kind == LIGHT_SPHERE) {
        // Uniform in the solid angle of the cap the sphere covers seen from o (emission leaves the outside
        // only: from inside nothing arrives).
        vec3 dc = e.origin - o;
        float dist2 = dot(dc, dc);
        float r2 = e.radius * e.radius;
        if (!(dist2 > r2)) return false;
        float dc_len = sqrt(dist2);
        float sin2_max = r2 / dist2;
        float cos_max = sqrt(max(0.0, 1.0 - sin2_max));
        float cap = sin2_max / (1.0 + cos_max); // 1 - cos_max, without cancellation
        float one_minus = a * cap;               // 1 - cos_theta
        float cos_theta = 1.0 - one_minus;
        float sin_theta = sqrt(max(0.0, one_minus * (2.0 - one_minus)));
        vec3 n = dc / dc_len;
        vec3 t, bt;
        onb(n, t, bt);
        w = about(t, bt, n, cos_theta, sin_theta, 2.0 * PI * b);
        float near = dc_len * cos_theta - sqrt(max(0.0, r2 - dist2 * sin_theta * sin_theta));
        vec3 y = o + near * w;
        vec3 y_off = offset_ray(y, normalize(y - e.origin)); // short of the sphere, which the ray must not hit
        dist = dot(y_off - o, w);
        li = e.value * (2.0 * PI * cap);
        return dist > 0.0;
    }
    if (HAS_DELTA_LIGHTS && (e.kind == LIGHT_POINT || e.kind == LIGHT_SPOT)) {
        vec3 to = e.origin - o;
        float d2 = dot(to, to);
        dist = sqrt(d2);
        w = to / dist;
        li = e.value / d2;
        if (e.kind == LIGHT_SPOT) li *= spot_falloff(e, -dot(w, e.normal));
        return d2 > 0.0;
    }
    dist = infinite_reach(e, o);
    if (HAS_DELTA_LIGHTS && e.kind == LIGHT_DIRECTIONAL) {
        w = -e.normal;
        li = e.value;
        return true;
    }
    if (HAS_ENVIRONMENT && e.kind == LIGHT_ENVIRONMENT) {
        float p;
        vec3 radiance;
        w = env_sample(e, a, b, p, radiance);
        if (!(p > 0.0)) return false;
        pdf = p * e.cdf; // the environment is light 0: its prob is its cdf
        li = radiance / pdf;
        return true;
    }
    return false;
}

// --- Photons from a light other than a quad or triangle: origin o, direction d and flux, from uniform
// (a, b) and, for the infinite lights, two more numbers of rng. A sphere returns its surface point and
// normal instead (false), for the caller's cosine draw, as a quad's.
bool emit_photon(Emitter e, float a, float b, inout Rng rng, out vec3 o, out vec3 d, out vec3 flux) {
    flux = e.flux;
    if (HAS_SPHERE_LIGHTS && e.kind == LIGHT_SPHERE) {
        d = uniform_sphere(a, b); // the normal, about which the caller draws the direction
        o = offset_ray(e.origin + e.radius * d, d);
        return false;
    }
    if (HAS_DELTA_LIGHTS && e.kind == LIGHT_POINT) {
        o = e.origin;
        d = uniform_sphere(a, b);
        return true;
    }
    if (HAS_DELTA_LIGHTS && e.kind == LIGHT_SPOT) {
        // Uniform in the cone to the cutoff; the flux carries the falloff (flux = I 2 pi (1 - cos_cutoff)).
        float cos_theta = 1.0 - a * (1.0 - e.cos_cutoff);
        float sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
        o = e.origin;
        d = about(e.edge_u, e.edge_v, e.normal, cos_theta, sin_theta, 2.0 * PI * b);
        flux *= spot_falloff(e, cos_theta);
        return true;
    }
    // Infinite lights: from a disk of the bounding sphere's radius facing the direction of travel, outside
    // the sphere (the flux through it: E pi R^2 for the sun, L pi R^2 / pdf for a direction of the sky).
    float r = e.radius * sqrt(rng_float(rng));
    float phi = 2.0 * PI * rng_float(rng);
    if (HAS_ENVIRONMENT && e.kind == LIGHT_ENVIRONMENT) {
        float p;
        vec3 radiance;
        vec3 towards = env_sample(e, a, b, p, radiance);
        d = -towards;
        flux = p > 0.0 ? radiance * (PI * e.radius * e.radius / (p * e.cdf)) : vec3(0.0);
    } else {
        d = e.normal;
    }
    vec3 t, bt;
    onb(d, t, bt);
    o = e.origin - e.radius * d + r * cos(phi) * t + r * sin(phi) * bt;
    return true;
}
#endif

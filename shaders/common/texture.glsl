// Textures (Mitsuba's bitmap and checkerboard): the diffuse reflectance of a material with one, at the
// texture coordinates of the hit. CPU twin: crates/reference/src/texture.rs; what each texture
// holds: crates/scene/src/texture.rs, laid out by crates/engine/src/lower/.
//
// A texture in texture_texels: a header of TEXTURE_HEADER texels,
//   0: kind | filter << 4 | wrap << 8, width, height, the texel of its first pixel (a bitmap)
//   1: to_uv's first row (a, b, c): u' = a u + b v + c     2: its second row (d, e, f)
//   3: a checkerboard's color0                           4: its color1
// then a bitmap's pixels, one texel each (linear RGB), row by row from the image's top row.
#ifndef TEXTURE_GLSL
#define TEXTURE_GLSL

const uint TEXTURE_HEADER = 5u;

// Mitsuba's luminance of a linear sRGB colour, 0.212671 r + 0.715160 g + 0.072169 b (its eval_1 of an RGB
// texture: a mask's opacity), written so that a grey is its own value exactly (the weights sum to 1).
float luminance(vec3 c) {
    precise float y = c.g + 0.212671 * (c.r - c.g) + 0.072169 * (c.b - c.g);
    return y;
}

// The texture coordinates of hit h, as Mitsuba gives them: a quad's planar coordinates (a rectangle's
// local x, y from [-1, 1] to [0, 1]), a sphere's longitude and colatitude about the world's axes, a
// triangle's interpolated from its vertices'.
vec2 surface_uv(Hit h) {
    // (No sphere, no sphere code: lavapipe would run its atan and acos at every call, a branch's both
    // sides being run.)
    if (NUM_SPHERES > 0u && h.kind == HIT_SPHERE) {
        float phi = atan(h.normal.y, h.normal.x);
        if (phi < 0.0) phi += 2.0 * PI;
        return vec2(phi * (0.5 / PI), acos(clamp(h.normal.z, -1.0, 1.0)) * (1.0 / PI));
    }
    if (h.kind == HIT_TRIANGLE) {
        vec4 a = uintBitsToFloat(texelFetch(triangle_texels, int(TRIANGLE_TEXELS * h.prim)));
        vec2 c = uintBitsToFloat(texelFetch(triangle_texels, int(TRIANGLE_TEXELS * h.prim + 1u)).xy);
        return (1.0 - h.local.x - h.local.y) * a.xy + h.local.x * a.zw + h.local.y * c;
    }
    return h.local;
}

// Pixel coordinate i of a side of n pixels, wrapped (Mitsuba's wrap modes).
int wrap_pixel(int i, int n, uint wrap) {
    if (wrap == WRAP_CLAMP) return clamp(i, 0, n - 1);
    int k = int(floor(float(i) / float(n))); // which copy of the image i lies in
    int m = i - n * k;
    if (wrap == WRAP_MIRROR && (k & 1) != 0) m = n - 1 - m;
    return m;
}

// The pixel at wrapped coordinates (x, y) of the bitmap whose first pixel is texel `first`.
vec3 texture_pixel(uint first, int width, int x, int y) {
    return uintBitsToFloat(texelFetch(texture_texels, int(first) + y * width + x).xyz);
}

// The value of the texture whose header is at texel `at`, at texture coordinates uv.
vec3 texture_value(uint at, vec2 uv) {
    uvec4 head = texelFetch(texture_texels, int(at));
    vec3 r0 = uintBitsToFloat(texelFetch(texture_texels, int(at + 1u)).xyz);
    vec3 r1 = uintBitsToFloat(texelFetch(texture_texels, int(at + 2u)).xyz);
    vec2 st = vec2(r0.x * uv.x + r0.y * uv.y + r0.z, r1.x * uv.x + r1.y * uv.y + r1.z);
    uint kind = head.x & 15u;
    if (kind == TEXTURE_CHECKERBOARD) {
        // Mitsuba's checkerboard: color0 where the fractional parts of u and v are on the same side of 1/2.
        bvec2 upper = greaterThan(st - floor(st), vec2(0.5));
        return uintBitsToFloat(texelFetch(texture_texels, int(at + (upper.x == upper.y ? 3u : 4u))).xyz);
    }
    uint filter_type = (head.x >> 4) & 15u;
    uint wrap = (head.x >> 8) & 15u;
    ivec2 size = ivec2(head.yz);
    vec2 p = st * vec2(size);
    // Bilinear between the four pixel centres around p; nearest: the pixel p lies in, which is the
    // bilinear's first fetch (i = floor(p) without the half-pixel shift), so that lavapipe, which runs both
    // sides of every branch, pays for no fetch of its own. Each coordinate is wrapped once.
    bool nearest = filter_type == FILTER_NEAREST;
    if (!nearest) p -= 0.5;
    ivec2 i = ivec2(floor(p));
    int x0 = wrap_pixel(i.x, size.x, wrap), y0 = wrap_pixel(i.y, size.y, wrap);
    vec3 c00 = texture_pixel(head.w, size.x, x0, y0);
    if (nearest) return c00;
    vec2 w = p - vec2(i);
    int x1 = wrap_pixel(i.x + 1, size.x, wrap), y1 = wrap_pixel(i.y + 1, size.y, wrap);
    vec3 c10 = texture_pixel(head.w, size.x, x1, y0);
    vec3 c01 = texture_pixel(head.w, size.x, x0, y1);
    vec3 c11 = texture_pixel(head.w, size.x, x1, y1);
    return (1.0 - w.y) * ((1.0 - w.x) * c00 + w.x * c10) + w.y * ((1.0 - w.x) * c01 + w.x * c11);
}

// Material m's textures on other parameters than the diffuse reflectance (its sixth texel) at hit h:
// specular_reflectance becomes m.color ((rough) conductors, mirrors, thin dielectrics: their constant
// there); alpha, the luminance of its texture's value (Mitsuba's eval_1 of an RGB texture, its
// src/textures/bitmap.cpp) floored at 1e-4 (its MicrofacetDistribution), becomes m.alpha_u and
// m.alpha_v, which hit_microfacet (microfacet.glsl) reads in place of the material's. `t`: that texel;
// uv: the hit's texture coordinates.
void apply_parameter_textures(inout Material m, vec2 uv, uvec4 t) {
    m.specular_texture = t.y;
    m.alpha_texture = t.z;
    if (!HAS_PARAMETER_TEXTURES || (t.y == 0u && t.z == 0u)) return;
    if (t.y != 0u) m.color = texture_value(t.y - 1u, uv);
    if (t.z != 0u) {
        const vec3 Y = vec3(0.212671, 0.715160, 0.072169); // Mitsuba's luminance
        m.alpha_u = max(dot(texture_value(t.z - 1u, uv), Y), 1e-4);
        m.alpha_v = m.alpha_u;
    }
}

// Material m (material() read it) at hit h with its textures applied: a diffuse surface's albedo, or a
// plastic's diffuse factor from the texture's diffuse_reflectance (as the host makes Material.color for
// a constant one: crates/materials/src/plastic.rs), and apply_parameter_textures'.
// An emitter's radiance texture (the sixth texel's w, read only where it emits) gives its emission there.
// The texture coordinates are taken once, and a kind of texture no material has is left out
// (HAS_PARAMETER_TEXTURES, HAS_EMISSION_TEXTURES): lavapipe runs every branch's code, taken or not.
void apply_texture(inout Material m, Hit h) {
    if (!HAS_TEXTURES) return;
    // The sixth texel, read once: opacity, specular_reflectance, alpha, radiance (types.glsl).
    uvec4 slots = texelFetch(material_texels, int(MATERIAL_TEXELS * h.material + 5u));
    vec2 uv = surface_uv(h);
    apply_parameter_textures(m, uv, slots);
    if (HAS_EMISSION_TEXTURES && slots.w != 0u && max(m.emission.r, max(m.emission.g, m.emission.b)) > 0.0) {
        m.emission = texture_value(slots.w - 1u, uv);
    }
    if (m.texture == 0u) return;
    vec3 value = texture_value(m.texture - 1u, uv);
    if (m.surface == SURFACE_PLASTIC) {
        vec3 terms, bound;
        material_terms(h.material, terms, bound);
        vec3 inner = bound.z != 0.0 ? 1.0 - value * bound.y : vec3(1.0 - bound.y);
        value = value / inner / (m.ior * m.ior);
    }
    m.color = value;
}
#endif

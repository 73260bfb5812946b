// Bump and normal maps (Mitsuba 3's src/bsdfs/bumpmap.cpp and normalmap.cpp): a material whose
// Material.normal_map names a record in texture_texels has its shading normal perturbed at each point, and
// its BSDF takes Estevez et al.'s shadowing term (normalmap_helpers.h, "A Microfacet-Based Shadowing
// Function to Solve the Bump Terminator Problem", Ray Tracing Gems 2019). CPU twin:
// crates/reference/src/normal_map.rs. Included by shading.glsl, after texture.glsl.
//
// The record, one texel: kind (NORMAL_MAP_*), the texel of its texture's header, a bump map's scale.
// The perturbed normal then goes through smooth shading's path (shading.glsl): a direction on different
// sides of it and of the true surface takes no part, and photons take Veach's correction.
#ifndef NORMAL_MAP_GLSL
#define NORMAL_MAP_GLSL

const uint NORMAL_MAP_BUMP = 1u;
const uint NORMAL_MAP_NORMAL = 2u;

// The shadowing term of the last hit shaded (bump_shadowing): alpha^2 = min(tan^2 / 8, 1) of the angle
// between its perturbed and unperturbed normals, and the unperturbed normal n0; alpha^2 = 0: no term.
// A kernel sets them through shading_normal at each hit and reads them before its next one.
float bump_alpha2 = 0.0;
vec3 bump_n0 = vec3(0.0);

// Mitsuba's Frame3f::tan_theta_2 of w about n (unit both).
float tan_theta_2(vec3 w, vec3 n) {
    float c = dot(w, n);
    return max(1.0 - c * c, 0.0) / (c * c);
}

// The shadowing term of the last hit for the light-side direction w (the direction a photon arrived from,
// or the one an eye path leaves along or casts its shadow ray along): 2 / (1 + sqrt(1 + alpha^2 tan^2)),
// as Mitsuba's eval_shadow_terminator. 1 where the hit had no map.
float bump_shadowing(vec3 w) {
    if (!HAS_NORMAL_MAPS || bump_alpha2 == 0.0) return 1.0;
    return 2.0 / (1.0 + sqrt(1.0 + bump_alpha2 * tan_theta_2(w, bump_n0)));
}

// Mitsuba's bitmap eval_1_grad: the gradient in (u, v) of the bilinear interpolation of the texture's
// luminance, its partials in the pixel grid taken back through to_uv's linear part (transposed) and then
// times the resolution, in Mitsuba's order. Nearest filtering gives 0, as in Mitsuba.
vec2 texture_gradient(uint at, vec2 uv) {
    uvec4 head = texelFetch(texture_texels, int(at));
    if ((head.x & 15u) != TEXTURE_BITMAP || ((head.x >> 4) & 15u) == FILTER_NEAREST) return vec2(0.0);
    vec3 r0 = uintBitsToFloat(texelFetch(texture_texels, int(at + 1u)).xyz);
    vec3 r1 = uintBitsToFloat(texelFetch(texture_texels, int(at + 2u)).xyz);
    vec2 st = vec2(r0.x * uv.x + r0.y * uv.y + r0.z, r1.x * uv.x + r1.y * uv.y + r1.z);
    uint wrap = (head.x >> 8) & 15u;
    ivec2 size = ivec2(head.yz);
    vec2 p = st * vec2(size) - 0.5;
    ivec2 i = ivec2(floor(p));
    vec2 w1 = p - vec2(i);
    vec2 w0 = 1.0 - w1;
    const vec3 Y = vec3(0.212671, 0.715160, 0.072169); // Mitsuba's luminance
    int x0 = wrap_pixel(i.x, size.x, wrap), x1 = wrap_pixel(i.x + 1, size.x, wrap);
    int y0 = wrap_pixel(i.y, size.y, wrap), y1 = wrap_pixel(i.y + 1, size.y, wrap);
    float f00 = dot(Y, texture_pixel(head.w, size.x, x0, y0));
    float f10 = dot(Y, texture_pixel(head.w, size.x, x1, y0));
    float f01 = dot(Y, texture_pixel(head.w, size.x, x0, y1));
    float f11 = dot(Y, texture_pixel(head.w, size.x, x1, y1));
    vec2 df = vec2(w0.y * (f10 - f00) + w1.y * (f11 - f01), w0.x * (f01 - f00) + w1.x * (f11 - f10));
    return vec2(size) * vec2(r0.x * df.x + r1.x * df.y, r0.y * df.x + r1.y * df.y);
}

// Mitsuba's dp/du and dp/dv at hit h: a quad's edges, a sphere's (trace_scene), a triangle's from its
// texture coordinates (Mesh::compute_surface_interaction; its edges where they are degenerate).
void surface_derivatives(Hit h, out vec3 dpdu, out vec3 dpdv) {
    dpdu = h.dpdu;
    dpdv = h.dpdv;
    if (h.kind == HIT_TRIANGLE) {
        vec4 a = uintBitsToFloat(texelFetch(triangle_texels, int(TRIANGLE_TEXELS * h.prim)));
        vec2 c = uintBitsToFloat(texelFetch(triangle_texels, int(TRIANGLE_TEXELS * h.prim + 1u)).xy);
        vec2 duv0 = a.zw - a.xy;
        vec2 duv1 = c - a.xy;
        float det = duv0.x * duv1.y - duv0.y * duv1.x;
        if (det != 0.0) {
            float inv = 1.0 / det;
            dpdu = (duv1.y * h.dpdu - duv0.y * h.dpdv) * inv;
            dpdv = (duv0.x * h.dpdv - duv1.x * h.dpdu) * inv;
        }
    }
}

// The shading normal at hit h with its material's map applied, on the side of ng (ns: the unperturbed
// one, on that side). Sets bump_alpha2 and bump_n0. A map that leaves the normal as it is (a flat height
// field's zero gradient, a normal map's (0, 0, 1)) returns ns itself, bit for bit: the perturbed frame is
// then the unperturbed one, which its arithmetic would only reproduce up to rounding.
vec3 mapped_normal(Hit h, vec3 ng, vec3 ns) {
    bump_alpha2 = 0.0;
    uint record = texelFetch(material_texels, int(MATERIAL_TEXELS * h.material + 3u)).w;
    if (record == 0u) return ns;
    uvec4 r = texelFetch(texture_texels, int(record - 1u));
    // The unperturbed frame on the surface's front side (Mitsuba's frames do not turn towards the ray).
    vec3 front = h.normal;
    vec3 n0 = dot(ns, front) < 0.0 ? -ns : ns;
    vec2 uv = surface_uv(h);
    vec3 dpdu, dpdv;
    surface_derivatives(h, dpdu, dpdv);
    vec3 n;
    if (r.x == NORMAL_MAP_BUMP) {
        vec2 g = uintBitsToFloat(r.z) * texture_gradient(r.y, uv);
        if (g == vec2(0.0)) return ns;
        vec3 du = dpdu + n0 * (g.x - dot(n0, dpdu));
        vec3 dv = dpdv + n0 * (g.y - dot(n0, dpdv));
        n = normalize(cross(du, dv));
        if (dot(front, n) < 0.0) n = -n;
    } else {
        vec3 c = 2.0 * texture_value(r.y, uv) - 1.0;
        if (c.x == 0.0 && c.y == 0.0 && c.z > 0.0) return ns;
        vec3 s = normalize(dpdu - n0 * dot(n0, dpdu));
        vec3 t = cross(n0, s);
        n = normalize(c.x * s + c.y * t + c.z * n0);
    }
    bump_alpha2 = min(0.125 * tan_theta_2(n, n0), 1.0);
    bump_n0 = n0;
    return dot(n, ng) < 0.0 ? -n : n;
}
#endif

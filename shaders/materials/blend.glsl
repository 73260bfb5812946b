// Mitsuba's `blendbsdf` (src/bsdfs/blendbsdf.cpp): f = (1 - w) f_0 + w f_1, w a constant or the luminance
// of a texture (Mitsuba's eval_1 of an RGB bitmap, src/textures/bitmap.cpp). Host side, with the
// choice's math: crates/materials/src/blend.rs; CPU twin: crates/reference/src/blend.rs.
//
// A blend is resolved at each surface interaction, right after the intersection and before anything reads
// the hit's material: one component is chosen, the second with probability w (as Mitsuba's `sample`
// chooses), and the hit's material becomes it, so that the chosen component is the surface for everything
// at that vertex (hit point, shadow ray, next direction; a photon's record and bounce). This is unbiased
// for every estimator: each one is linear in the BSDF at the vertex (a path's weight, a photon's flux, a
// hit point's BRDF are products in which f appears once), and E[f_chosen] = (1 - w) f_0 + w f_1 = f.
// At w = 0 or 1 no random number is drawn, so such a blend is its component bit for bit.
//
// The record (types.glsl): surface SURFACE_BLEND, ior the constant weight, texture the weight's texture
// (0: none), lobe_a's bits the two components' material indices.
#ifndef BLEND_GLSL
#define BLEND_GLSL

// The deepest blends nest (ppm_vk_materials::blend::MAX_BLEND_DEPTH, which Scene::validate holds them to).
const uint MAX_BLEND_DEPTH = 4u;

#ifdef SCENE_CONSTANTS
#define HAS_BLENDS SCENE_BLENDS
#else
#define HAS_BLENDS true
#endif

// Hit h's material with its blends resolved: a component chosen per blend, drawing from the path's rng.
void resolve_blend(inout Hit h, inout Rng rng) {
    if (!HAS_BLENDS) return;
    for (uint level = 0u; level < MAX_BLEND_DEPTH; level++) {
        uint at = MATERIAL_TEXELS * h.material;
        if (texelFetch(material_texels, int(at)).w != SURFACE_BLEND) return;
        float w = uintBitsToFloat(texelFetch(material_texels, int(at + 1u)).w);
        uvec4 c = texelFetch(material_texels, int(at + 2u)); // xy: the components, w: the weight's texture
        if (c.w != 0u) {
            const vec3 Y = vec3(0.212671, 0.715160, 0.072169); // Mitsuba's luminance
            w = dot(Y, texture_value(c.w - 1u, surface_uv(h)));
        }
        bool second = w >= 1.0;
        if (w > 0.0 && w < 1.0) second = rng_float(rng) < w;
        h.material = second ? c.y : c.x;
    }
}
#endif

// Mitsuba's mask (src/bsdfs/mask.cpp): a surface that is there with probability `opacity` and passes the
// ray on unchanged otherwise. Mitsuba samples that as a null lobe (straight through, weight 1) chosen with
// probability 1 - opacity and weights the nested bsdf's value by opacity; here the choice is made where
// the ray meets the surface, inside the intersection loops and the BVH's traversal (geometry.glsl): a
// surface a ray passes is, for that ray, not there. Every ray (eye rays, photons, shadow rays) then sees
// a surface of opacity a with probability a, an unbiased estimate of Mitsuba's mixture, and a shadow
// ray's expected visibility is the product of (1 - a) over the surfaces it crosses (Mitsuba's null
// transmission, eval_null_transmission). Opacity 1 never passes (u < 1) and 0 always does, exactly.
//
// The choice is a hash of a key the ray drew from its path's random stream before it was traced
// (mask_key) and of the primitive, not a draw inside the traversal: the traversal visits primitives in an
// order that depends on the tree, and a hash gives the same answer whatever the order (and for the same
// primitive met twice by one ray); two primitives, or two rays, decide independently. Scenes without masks,
// or whose masks are all 0 or 1 (RenderParams.masks), draw no key, so their paths draw the same numbers as
// without them; the CPU twin (crates/materials/src/mask.rs) is the same integer arithmetic. The two sides
// of a sphere are two primitives.
#ifndef MASK_GLSL
#define MASK_GLSL

// Material m's opacity texture: 0 for an opaque surface, else 1 + the texel of its header.
uint material_opacity(uint m) {
    return texelFetch(material_texels, int(MATERIAL_TEXELS * m + 5u)).x;
}

// The PCG hash of Jarzynski and Olano ("Hash Functions for GPU Rendering", JCGT 2020).
uint mask_pcg(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The key a ray about to be traced draws from its path's stream `rng` (0, drawing nothing, in a scene
// without masks).
uint mask_key(inout Rng rng) {
    return HAS_MASKS && params.masks != 0u ? rng_next(rng) : 0u;
}

// Uniform in [0, 1) for the ray of key `key` meeting primitive `prim` (geometry.glsl's MASK_PRIM_*): the
// top 24 bits.
float mask_uniform(uint key, uint prim) {
    uint h = mask_pcg(mask_pcg(key) ^ prim);
    return float(h >> 8u) * (1.0 / 16777216.0);
}

// Whether the ray of key `key` stops where it meets material m's surface at h (a hit being built: h.kind
// and what surface_uv reads of it), as primitive `prim`. Mitsuba's opacity is the texture's eval_1 (for
// RGB the luminance) clamped to [0, 1].
bool mask_keeps(uint m, uint key, uint prim, Hit h) {
    uint at = material_opacity(m);
    if (at == 0u) return true;
    float opacity = clamp(luminance(texture_value(at - 1u, surface_uv(h))), 0.0, 1.0);
    return mask_uniform(key, prim) < opacity;
}
#endif

// The material table's accessors: Material i (types.glsl) from `material_texels`, MATERIAL_TEXELS 16-byte texels each,
// which the including kernel declares (bindings.glsl for the tracing kernels, gather.comp for the BRDFs it
// evaluates per photon). HAS_TEXTURES as bindings.glsl sets it (true where undefined).
#ifndef MATERIALS_GLSL
#define MATERIALS_GLSL
#ifndef HAS_TEXTURES
#define HAS_TEXTURES true
#endif
// Material i without its lobe terms (left zero: material_terms reads them where a surface needs them).
Material material(uint i) {
    uvec4 a = texelFetch(material_texels, int(MATERIAL_TEXELS * i));
    uvec4 b = texelFetch(material_texels, int(MATERIAL_TEXELS * i + 1u));
    uint texture = HAS_TEXTURES ? texelFetch(material_texels, int(MATERIAL_TEXELS * i + 2u)).w : 0u;
    return Material(uintBitsToFloat(a.xyz), a.w, uintBitsToFloat(b.xyz), uintBitsToFloat(b.w), vec3(0.0),
                    texture, vec3(0.0), 0u, 0.0, 0.0, 0u, 0u, 0u, 0u, 0u, 0u);
}
// Material i's lobe terms (Material.lobe_a, lobe_b: what they hold depends on the surface).
void material_terms(uint i, out vec3 a, out vec3 b) {
    a = uintBitsToFloat(texelFetch(material_texels, int(MATERIAL_TEXELS * i + 2u)).xyz);
    b = uintBitsToFloat(texelFetch(material_texels, int(MATERIAL_TEXELS * i + 3u)).xyz);
}
// Only lobe_a.
vec3 material_term_a(uint i) {
    return uintBitsToFloat(texelFetch(material_texels, int(MATERIAL_TEXELS * i + 2u)).xyz);
}

#endif

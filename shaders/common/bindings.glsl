// Scene bindings shared by the kernels that trace rays (ray, photon): always bindings 0-7, in this order
// (4 and 5: the triangle BVH, crates/engine/src/bvh/; one empty leaf in scenes without meshes).
// The intersection loops read the scene through SPHERE(i), QUAD(i), INLINE_TRIANGLE(i), INLINE_PAIR(k),
// INLINE_SINGLE(k), NUM_SPHERES, NUM_QUADS, NUM_INLINE_TRIANGLES, NUM_INLINE_PAIRS and
// NUM_INLINE_SINGLES, and traverse the BVH when NUM_TRIANGLES > 0. Built as shipped, they read the
// buffers; the renderer recompiles the tracing kernels with SCENE_CONSTANTS defined and the spheres and
// quads written out as constants (crates/kernels/src/specialize.rs), so the unrolled loops need no loads at
// all; the triangles of a small mesh are written out too (by parallelograms where they pair), and then no
// BVH is traversed.
// Only loop indices may index the constants: a dynamic index into a constant array makes lavapipe copy it
// per invocation, so materials are read from their buffer (a chain of selects over constants measured no
// faster).
#ifndef BINDINGS_GLSL
#define BINDINGS_GLSL
#include "params.glsl"
layout(std430, binding = 1) readonly buffer Spheres { Sphere spheres[]; };
layout(std430, binding = 2) readonly buffer Quads { Quad quads[]; };
// The materials as 16-byte texels, MATERIAL_TEXELS each (color, surface | emission, ior | ...): material() reads them. Texel fetches
// are vector gathers on lavapipe, where a storage-buffer load is a loop over the lanes (bvh.glsl).
layout(binding = 3) uniform usamplerBuffer material_texels;
// The BVH's nodes (BvhNode) and triangles (Triangle) as 16-byte texels: bvh_node() and bvh_triangle()
// in bvh.glsl read them.
layout(binding = 4) uniform usamplerBuffer bvh_node_texels;
layout(binding = 5) uniform usamplerBuffer bvh_triangle_texels;
// The textures (texture.glsl: each a header of TEXTURE_HEADER texels, then a bitmap's pixels), and what
// shading reads of the BVH's triangles in leaf order, TRIANGLE_TEXELS texels each: texture coordinates
// (u0 v0 u1 v1 | u2 v2, texture.glsl) and vertex normals (shading.glsl): one zeroed texel each in a scene
// without them.
layout(binding = 6) uniform usamplerBuffer texture_texels;
layout(binding = 7) uniform usamplerBuffer triangle_texels;

// Two triangles of a small mesh written out that make a parallelogram (crates/kernels/src/inline_pairs.rs):
// the corner B off their shared diagonal, A - B and C - B, the two triangles' indices, and the corners
// (0-3: A, B, C, D) of the first's v1 and v2 and the second's, 2 bits each from the lowest.
struct InlinePair {
    vec3 origin;
    uint first;
    vec3 edge_u;
    uint second;
    vec3 edge_v;
    uint corners;
};

// A kernel compiled for one scene knows whether any material has a texture (without one, the texture index is
// not even read), on its specular reflectance or roughness, or on its emission, whether any mesh is
// smooth-shaded (shading.glsl) and whether any rough surface is anisotropic (geometry.glsl's
// surface_tangent), whether any has a bump or normal map (normal_map.glsl), whether any is masked
// (materials/mask.glsl: the intersection loops test opacity), and which kinds of light it has beyond quads
// and triangles (lights.glsl): glowing spheres, delta lights (point, spot, directional), an environment.
#ifdef SCENE_CONSTANTS
#include "scene_constants.glsl"
#define HAS_TEXTURES SCENE_TEXTURES
#define HAS_PARAMETER_TEXTURES SCENE_PARAMETER_TEXTURES
#define HAS_EMISSION_TEXTURES SCENE_EMISSION_TEXTURES
#define HAS_VERTEX_NORMALS SCENE_SHADING_NORMALS
#define HAS_NORMAL_MAPS SCENE_NORMAL_MAPS
#define HAS_MASKS SCENE_MASKS
// A bump or normal map's normal goes through smooth shading's path (shading.glsl).
#define HAS_SHADING_NORMALS (SCENE_SHADING_NORMALS || SCENE_NORMAL_MAPS)
#define HAS_ANISOTROPY SCENE_ANISOTROPIC
#define HAS_SPHERE_LIGHTS SCENE_SPHERE_LIGHTS
#define HAS_DELTA_LIGHTS SCENE_DELTA_LIGHTS
#define HAS_ENVIRONMENT SCENE_ENVIRONMENT
#else
#define HAS_TEXTURES true
#define HAS_PARAMETER_TEXTURES true
#define HAS_EMISSION_TEXTURES true
#define HAS_VERTEX_NORMALS true
#define HAS_NORMAL_MAPS true
#define HAS_MASKS true
#define HAS_SHADING_NORMALS true
#define HAS_ANISOTROPY true
#define HAS_SPHERE_LIGHTS true
#define HAS_DELTA_LIGHTS true
#define HAS_ENVIRONMENT true
#endif
#define HAS_OTHER_LIGHTS (HAS_SPHERE_LIGHTS || HAS_DELTA_LIGHTS || HAS_ENVIRONMENT)
#include "materials.glsl"

#ifdef SCENE_CONSTANTS
#define SPHERE(i) SCENE_SPHERES[i]
#define QUAD(i) SCENE_QUADS[i]
#define INLINE_TRIANGLE(i) SCENE_TRIANGLES[i]
#define INLINE_PAIR(k) SCENE_PAIRS[k]
#define INLINE_SINGLE(k) SCENE_SINGLES[k]
// SCENE_BVH: the scene's triangles are in the BVH, not written out.
#define NUM_TRIANGLES (SCENE_BVH ? params.num_triangles : 0u)
#else
#define NUM_TRIANGLES params.num_triangles
#define NUM_SPHERES params.num_spheres
#define NUM_QUADS params.num_quads
#define NUM_INLINE_TRIANGLES 0u
#define NUM_INLINE_PAIRS 0u
#define NUM_INLINE_SINGLES 0u
#define INLINE_PAIR(k) InlinePair(vec3(0.0), 0u, vec3(0.0), 0u, vec3(0.0), 0u)
#define INLINE_SINGLE(k) 0u
#define SPHERE(i) spheres[i]
#define QUAD(i) quads[i]
#define INLINE_TRIANGLE(i) bvh_triangle(i)
#endif
#endif

// GPU records shared by the kernels. Each struct here has a #[repr(C)] twin in crates/kernels/src/layout.rs,
// checked at compile time against the std430 offsets glslang gives these declarations (build.rs reflects them).
#ifndef TYPES_GLSL
#define TYPES_GLSL
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

const uint SURFACE_DIFFUSE = 0u;
const uint SURFACE_MIRROR = 1u;
const uint SURFACE_GLASS = 2u;
const uint SURFACE_CONDUCTOR = 3u;
const uint SURFACE_PLASTIC = 4u;  // Mitsuba's plastic: plastic.glsl
const uint SURFACE_THIN = 5u;     // Mitsuba's thindielectric: thin_dielectric.glsl
const uint SURFACE_ROUGH_CONDUCTOR = 6u; // Mitsuba's roughconductor: rough_conductor.glsl
const uint SURFACE_ROUGH_GLASS = 7u;     // Mitsuba's roughdielectric: rough_dielectric.glsl
const uint SURFACE_BLEND = 8u;           // Mitsuba's blendbsdf: blend.glsl (resolved at each hit)

// MATERIAL_TEXELS 16-byte texels; material() reads the first two, material_terms() the next two (only
// conductors, plastics and thin dielectrics need them, so every other surface costs two fetches),
// material_microfacet() the fifth (only rough surfaces) and the sixth holds the textures on parameters
// other than the diffuse reflectance (each 0: none; else 1 + the texel of the texture's header).
const uint MATERIAL_TEXELS = 6u;
struct Material {
    vec3 color;      // diffuse albedo, mirror reflectance, a (rough) conductor's or thin dielectric's
                     // specular_reflectance, or a plastic's diffuse factor (plastic.glsl)
    uint surface;    // SURFACE_*
    vec3 emission;   // radiance leaving the front side (quads only)
    float ior;       // (rough) glass, plastic coat, thin dielectric: index inside over index outside; blend:
                     // its constant weight
    vec3 lobe_a;     // (rough) conductor: real part eta of the complex index, per channel; plastic: the coat's
                     // specular_reflectance; thin dielectric: specular_transmittance; blend: the bits of x
                     // and y are its two components' material indices (blend.glsl)
    uint texture;    // 0: none; else 1 + the texel of its texture's header (texture.glsl), whose value is
                     // the diffuse albedo (diffuse) or diffuse_reflectance (plastic) at each point, or whose
                     // luminance is a blend's weight
    vec3 lobe_b;     // conductor: imaginary part k (extinction), per channel; plastic: x, the largest
                     // weight its diffuse lobe gives (plastic.glsl), y its coat's internal diffuse
                     // reflectance (fdr_int when smooth) and z 1 if nonlinear
                     // (what turns a texture's diffuse_reflectance into its diffuse factor)
    uint normal_map; // 0: none; else 1 + the texel of its bump or normal map's record in texture_texels
                     // (normal_map.glsl)
    float alpha_u;   // rough surfaces: the microfacet roughness along the tangent (microfacet.glsl)
    float alpha_v;   // and along the bitangent
    uint distribution; // MICROFACET_*
    uint table;      // a rough plastic: 1 + the texel of its coat's transmittance table in texture_texels
                     // (64 values over the cosine, four a texel: plastic.glsl); else 0
    uint opacity;    // Mitsuba's mask: the texture of its opacity (a constant one is a 1 x 1 bitmap)
    uint specular_texture; // specular_reflectance (conductors, plastics, thin dielectrics)
    uint alpha_texture;    // a rough surface's alpha
    uint emission_texture; // an area light's radiance
};

const uint TEXTURE_BITMAP = 0u;
const uint TEXTURE_CHECKERBOARD = 1u;
const uint FILTER_BILINEAR = 0u;
const uint FILTER_NEAREST = 1u;
const uint WRAP_REPEAT = 0u;
const uint WRAP_MIRROR = 1u;
const uint WRAP_CLAMP = 2u;

struct Sphere {
    vec3 center;
    float radius;
    uint material;
    uint pad0;
    uint pad1;
    uint pad2;
};

// Parallelogram origin + a*edge_u + b*edge_v, a,b in [0,1]; front normal = normalize(cross(edge_u, edge_v)).
struct Quad {
    vec3 origin;
    uint material;
    vec3 edge_u;
    float area;
    vec3 edge_v;
    float plane_d;   // dot(normal, origin)
    vec3 normal;
    uint shape;      // QUAD_PARALLELOGRAM, or QUAD_DISK: only the ellipse inscribed in it (Mitsuba's disk)
    vec3 w;          // cross(u, v) / |cross(u, v)|^2: planar coordinates of a hit (Shirley's trick)
    float pad1;
};

const uint QUAD_PARALLELOGRAM = 0u;
const uint QUAD_DISK = 1u;

// A light as the kernels sample it (lights.glsl), made from its Light (and its quad, triangle or sphere).
// Never stored in a buffer: the scene-specialised kernels hold their lights as constants of this type.
// What each field holds depends on the kind:
//   quad, triangle: the parallelogram origin + a edge_u + b edge_v (a triangle: a + b <= 1), its normal;
//   sphere: its centre (origin) and radius;
//   point: its position (origin); spot: its position, axis (normal) and a frame about it (edge_u, edge_v);
//   directional: the scene's bounding sphere (origin, radius), the direction the light travels (normal) and
//     a frame about it;
//   environment: the bounding sphere, and to_world's columns x, y, z (edge_u, normal, edge_v).
struct Emitter {
    vec3 origin;
    vec3 edge_u;
    vec3 edge_v;
    vec3 normal;
    vec3 flux;       // the flux a photon leaves with (power / prob); a spot's before its falloff
    float cdf;
    uint kind;       // LIGHT_*
    vec3 value;      // a sphere's radiance, a point's or spot's intensity, a directional light's irradiance,
                     // each divided by prob; an environment's radiance or scale (its prob is its cdf: light 0);
                     // a quad's or triangle's radiance, not divided (1 where a texture gives it)
    float radius;
    float cos_cutoff; // a spot's: where its falloff reaches 0, and where it starts (cos_beam), the cutoff
    float cos_beam;   // angle in radians, and 1 / (cutoff - beam) (falloff linear in the angle, as Mitsuba's)
    float cutoff;
    float inv_width;
    uint table;      // an environment map's first texel in texture_texels (lights.glsl); 0xffffffff: constant;
                     // a quad's radiance texture (0: none, else 1 + its header's texel), a textured
                     // triangle's 1 + its index (flux is then per unit of radiance: lights.glsl's
                     // emitter_radiance)
};

const uint LIGHT_QUAD = 0u;
const uint LIGHT_TRIANGLE = 1u;
const uint LIGHT_SPHERE = 2u;
const uint LIGHT_POINT = 3u;
const uint LIGHT_SPOT = 4u;
const uint LIGHT_DIRECTIONAL = 5u;
const uint LIGHT_ENVIRONMENT = 6u;

// A light to emit photons from, chosen with probability `prob` (proportional to power). The fields after
// `power` are the Emitter's of the same names (zero for quads and triangles).
struct Light {
    uint index;      // into the quads (LIGHT_QUAD), the BVH's leaf-ordered triangles (LIGHT_TRIANGLE) or the
                     // spheres (LIGHT_SPHERE); an environment map's table (Emitter::table)
    float cdf;       // inclusive running sum of prob
    float prob;      // the probability the f32 cdf gives it: cdf - the previous cdf
    uint kind;       // LIGHT_*
    vec3 power;      // what the light emits (an area light's emission * area * pi): the flux a photon carries
                     // is power / prob (Emitter::flux)
    float radius;
    vec3 origin;
    float cos_cutoff;
    vec3 normal;
    float cos_beam;
    vec3 edge_u;
    float cutoff;
    vec3 value;      // not yet divided by prob; a quad's or triangle's radiance (1 where a texture gives it)
    float inv_width;
    vec3 flux;       // Emitter::flux, when it is not power / prob (a spot's; a textured quad's per unit
                     // radiance, area pi: its photons carry flux * Le(uv) / prob)
    uint texture;    // a quad's or triangle's radiance texture: 0 none, else 1 + the texel of its header
};

// Constants of one render, written once by the host.
struct RenderParams {
    vec3 eye;
    float tan_half_fov;
    vec3 right;      // camera basis, unit vectors
    float aspect;    // width / height
    vec3 up;
    uint width;
    vec3 forward;
    uint height;
    vec3 grid_min;   // origin of the photon grid's cells
    float cell_size; // edge of a grid cell: set per pass from the search radii (Renderer::pass)
    uint grid_mask;  // hash table size - 1 (a power of two)
    uint num_spheres;
    uint num_quads;
    uint num_lights;
    float eps;       // ray offset floor, relative to the scene's size (see offset_ray)
    uint max_photon_depth;
    uint max_eye_depth;
    uint hit_slots;  // hit points per pixel (glass splits the eye path into both Fresnel branches, or with
                     // rough_split the first rough vertex into lobe directions)
    uint photon_capacity; // photon records one batch can hold
    uint seed;
    float flux_fixed; // fixed-point units per unit of flux in PassAccum: a power of two, 2^30 / (largest
                      // flux a photon can carry) rounded down, so one photon's contribution fits an int32
    float eps_rel;   // ray offset per unit of the point's largest coordinate (see offset_ray)
    uint num_triangles; // triangles in the BVH (0: no meshes, the BVH is not traversed)
    uint photon_bvh_budget; // BVH traversal steps one photon thread may take in all (PathLimits)
    uint eye_bvh_budget;    // the same for one eye thread
    uint lookup_limit;      // loop steps a subgroup's lookups may take (neighbours.glsl); 0xffffffff: no limit
    uint direct_light;      // 1: direct light by light sampling at the eye paths (ray.comp), the photons
                            // skipping their first diffuse record (photon.comp); 0: all by photons
    float glossy_alpha;     // rough conductors of at least this roughness hold hit points and photon
                            // records (rough_conductor.glsl, "glossy hit points"); above every alpha: none
    uint masks;             // 1: some mask's opacity is not 0 or 1 throughout: each traced ray draws its key
                            // (materials/mask.glsl)
    float light_power;      // the lights' power, channels summed (the light table's total): the density
                            // ray/glossy_light.glsl weighs an area light's samples by
    uint glossy_light;      // GLOSSY_LIGHT_*: how eye paths take the light their rough vertices reflect
    uint rough_split;       // 1 (SPPM): the hit slots are for the first rough vertex's lobe directions, and
                            // glass, panes and plastics take one branch; 0 (PPM): those split while slots last
    uint num_targets;       // spheres around what casts caustics, which emitted photons are aimed at
                            // (photon/targets.glsl); 0: none, every photon leaves by the cosine
    float target_share;     // the share of an area light's photons aimed at them
    vec4 targets[8];        // MAX_TARGETS of them: centre, radius
};

// RenderParams.glossy_light (ray/glossy_light.glsl): the light a rough vertex reflects straight from an
// emitter by both strategies weighed by the power heuristic, by its lobe's sampled direction alone (delta
// lights still by shadow rays), or by shadow rays alone (glowing spheres still by the lobe).
const uint GLOSSY_LIGHT_BSDF = 0u;
const uint GLOSSY_LIGHT_MIS = 1u;
const uint GLOSSY_LIGHT_LIGHTS = 2u;

// A diffuse (or glossy) point seen from a pixel (PPM pass 1). Fixed for the whole render.
struct HitPoint {
    vec3 pos;
    uint pixel;      // 0xffffffff: empty slot
    vec3 normal;     // facing the eye ray
    uint brdf;       // 0: `weight` holds the BRDF (diffuse, a plastic's base); else 1 + the index of the rough
                     // conductor it lies on, whose BRDF the gather evaluates per photon (rough_conductor.glsl)
    vec3 weight;     // eye-path throughput * f_r (albedo / pi), or on a rough conductor throughput times
                     // the bound of its BRDF (rough_conductor_hit_weight)
    uint wo;         // brdf != 0: the direction towards the eye, octahedral snorm 2x16 (oct_encode)
};

// Per-hit-point progressive statistics (eq. 3, 6), in double: N and tau must not lose increments over
// billions of photons.
struct HitStats {
    double n;        // accumulated (alpha-scaled) photon count N
    double r2;       // squared search radius R^2
    double tau_r;    // accumulated un-normalised flux tau (times the cone filter's weights when on)
    double tau_g;
    double tau_b;
    double probe;    // lambda / r^2 from the probe pass (eq. 7), or 0 without probing
    double curv;     // the curvature statistic D = M - 4 M_half summed over passes, scaled as R shrinks
    double curv_var; // its variance, M + 8 M_half summed the same way (update.comp's adaptive shrink)
};

// What this pass's photons gave a hit point: M and tau_M, flux in fixed point (RenderParams.flux_fixed
// units per unit) so the sum is exact and independent of the order photons are visited in. Each photon
// converts to int32 (a vector instruction; float to int64 is not one on AVX2) and sums into int64.
struct PassAccum {
    int64_t flux_r;
    int64_t flux_g;
    int64_t flux_b;
    uint m;
    uint m_half;     // of the m, those within R / 2 (the update's curvature statistic)
};

// A photon deposited on a diffuse surface.
struct Photon {
    vec3 pos;
    uint cell;       // key of the grid cell holding pos (grid_key in grid.glsl)
    vec3 flux;       // un-normalised: light power * path throughput / light choice probability
    uint dir;        // direction of travel, octahedral snorm 2x16
};

// A Photon as the four 64-bit words of its std430 layout (layout.rs asserts the offsets), low half first.
// lavapipe loads and stores a vector one component per lane: four words are half the scattered stores
// and gathered loads of eight fields (photon.comp's append, the grid build's copies, the lookups'
// reads in neighbours.glsl: 25-30% of the gather's time, measured in docs/performance.md).
u64vec4 photon_words(Photon p) {
    return u64vec4(packUint2x32(uvec2(floatBitsToUint(p.pos.x), floatBitsToUint(p.pos.y))),
                   packUint2x32(uvec2(floatBitsToUint(p.pos.z), p.cell)),
                   packUint2x32(uvec2(floatBitsToUint(p.flux.r), floatBitsToUint(p.flux.g))),
                   packUint2x32(uvec2(floatBitsToUint(p.flux.b), p.dir)));
}

// A Photon read as its two 16-byte texels (position, cell | flux, dir), back as its four words.
u64vec4 texels_words(uvec4 a, uvec4 b) {
    return u64vec4(packUint2x32(a.xy), packUint2x32(a.zw), packUint2x32(b.xy), packUint2x32(b.zw));
}

// The first two words: position and cell key.
vec3 words_pos(u64vec4 w, out uint cell) {
    uvec2 a = unpackUint2x32(w.x), b = unpackUint2x32(w.y);
    cell = b.y;
    return uintBitsToFloat(uvec3(a, b.x));
}

// The last two: flux and the octahedral direction.
vec3 words_flux(u64vec4 w, out uint dir) {
    uvec2 c = unpackUint2x32(w.z), d = unpackUint2x32(w.w);
    dir = d.y;
    return uintBitsToFloat(uvec3(c, d.x));
}

// Paths the tracing kernels ended at their depth backstop (RenderParams.max_photon_depth, max_eye_depth)
// rather than by roulette, absorption or escape: each such path is a (bounded) loss the renderer reports.
struct PathCounters {
    uint photon_paths;
    uint eye_paths;
    uint traversal_cut; // paths whose BVH traversal ran out of the loop budget (an error: the renderer stops)
    uint capped;     // photons held at FLUX_CAP_FIXED at a smooth-shaded surface (shading.glsl); the bench's
                     // PHOTON_COUNT_STEPS build counts intersections here instead
};

// A batch's photon work in a BVH scene (photon.comp): photons taken from the counter, photons suspended
// for the resume round, and the resume round's dispatch (a VkDispatchIndirectCommand, photon_resume.comp).
struct PhotonWork {
    uint started;    // photons of the batch threads have taken (may pass the batch's count)
    uint suspended;  // entries of the suspended photons' buffer
    uint pad0;
    uint pad1;
    uvec3 groups;    // workgroups of the resume round
    uint pad2;
};

// The photon grid build's dispatches (VkDispatchIndirectCommand each), sized from the batch's records by
// grid_dispatch.comp: the count's and the split's workgroups (one per CHUNK records), and the placing's
// (one thread per record, spread over y by invocation.glsl's spread_groups).
struct GridDispatch {
    uvec3 chunks;
    uint pad0;
    uvec3 records;
    uint pad1;
};

// A photon suspended where its thread's loop budget ran out, to go on from the same intersection.
struct PhotonState {
    uint64_t state;  // its random stream (Rng)
    uint64_t inc;
    vec3 o;          // the ray still to trace
    uint depth;      // surface interactions so far
    vec3 d;
    uint pad0;
    vec3 flux;
    uint pad1;
};

// A node of the 4-wide BVH (crates/engine/src/bvh/widen.rs collapses the binary SAH tree into it), 64 bytes:
// the boxes of its (up to) four children quantized to 8 bits per bound (Ylitie, Karras and Laine 2017), and
// each child's reference: BVH_EMPTY, an interior node's index, or BVH_LEAF | (count - 1) << BVH_COUNT_SHIFT
// | its first triangle in the leaf-ordered triangle buffer. On each axis a bound is origin + q 2^e with q
// a byte and e the axis's exponent: the product is exact and the host rounds q down for a lower bound and
// up for an upper one, checking the sum as the kernels compute it, so a child's box always holds it.
struct BvhNode {
    float origin_x;
    float origin_y;
    float origin_z;
    uint exponents;  // biased f32 exponents of the three axes' steps: x | y << 8 | z << 16
    uvec2 qx;        // the children's lower bounds on x in steps, one byte each (child 0 lowest), then upper
    uvec2 qy;
    uvec2 qz;
    uint child[4];
    uvec2 pad;       // to 64 bytes: two 32-byte loads (bvh_node in bvh.glsl)
};

// A triangle of the BVH, in leaf order. Its vertices as given, not a vertex and two edges: the watertight
// test needs the two triangles sharing an edge to see bit-identical vertices (v0 + e1 rounds).
struct Triangle {
    vec3 v0;
    uint material;
    vec3 v1;
    uint source;     // index of the triangle in the builder's input
    vec3 v2;
    uint pad0;
};

const float PROBE_FIXED = 1073741824.0; // 2^30: the probe's fixed-point scale for d^2 / r^2 in [0, 1]
const uint TRIANGLE_TEXELS = 3u;         // texels per triangle in triangle_texels (bindings.glsl)
const float FLUX_CAP_FIXED = 70368744177664.0; // 2^46: the most a photon may carry at a smooth-shaded
                                               // surface, in fixed-point units (shading.glsl)
#endif

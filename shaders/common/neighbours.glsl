// Visits the photons of this batch within sqrt(r2) of a hit point that arrive from the side it is seen
// from, calling the including kernel's `visit(flux, d2)` for each. Needs `sorted` (records grouped by
// bucket), `cell_start` and `params` declared before it.
#ifndef NEIGHBOURS_GLSL
#define NEIGHBOURS_GLSL
#include "grid.glsl"
#include "sampling.glsl"

void visit(vec3 flux, float d2);

// Whether a photon travelling along `dir` (octahedral-encoded) arrives at a surface of normal n from
// its front: only the sign matters, so the direction needs no normalising.
bool arrives_from_front(uint dir, vec3 n) {
    return dot(oct_decode_unnormalized(dir), n) < 0.0;
}

// Each field is read only when needed: most photons of a bucket fail the distance test, and every read
// from a storage buffer is a gather per lane on lavapipe.
void visit_bucket(uint h, vec3 pos, vec3 normal, float r2) {
    uint end = cell_start[h + 1u];
    for (uint k = cell_start[h]; k < end; k++) {
        vec3 dv = sorted[k].pos - pos;
        float d2 = dot(dv, dv);
        if (d2 > r2) continue;
        // The BRDF is zero for light arriving from behind the surface (ALGORITHM.md).
        if (!arrives_from_front(sorted[k].dir, normal)) continue;
        visit(sorted[k].flux, d2);
    }
}

// Cells are at least twice the largest radius wide (GpuScene), so the sphere overlaps at most 2x2x2 of
// them. Their 8 buckets are visited once each: a cell outside the sphere's range takes the hash of the
// first, and a bucket two cells share is skipped the second time (written out, not as an array: lavapipe
// keeps indexed private arrays in memory).
void for_each_photon_near(vec3 pos, vec3 normal, float r2) {
    float r = sqrt(r2);
    ivec3 lo = grid_cell(pos - vec3(r));
    bvec3 two = greaterThan(grid_cell(pos + vec3(r)), lo);
    uint h0 = grid_hash(lo);
    uint h1 = two.x ? grid_hash(lo + ivec3(1, 0, 0)) : h0;
    uint h2 = two.y ? grid_hash(lo + ivec3(0, 1, 0)) : h0;
    uint h3 = two.x && two.y ? grid_hash(lo + ivec3(1, 1, 0)) : h0;
    uint h4 = two.z ? grid_hash(lo + ivec3(0, 0, 1)) : h0;
    uint h5 = two.x && two.z ? grid_hash(lo + ivec3(1, 0, 1)) : h0;
    uint h6 = two.y && two.z ? grid_hash(lo + ivec3(0, 1, 1)) : h0;
    uint h7 = all(two) ? grid_hash(lo + ivec3(1, 1, 1)) : h0;
    visit_bucket(h0, pos, normal, r2);
    if (h1 != h0) visit_bucket(h1, pos, normal, r2);
    if (h2 != h0 && h2 != h1) visit_bucket(h2, pos, normal, r2);
    if (h3 != h0 && h3 != h1 && h3 != h2) visit_bucket(h3, pos, normal, r2);
    uvec3 a = uvec3(h0, h1, h2);
    if (!any(equal(a, uvec3(h4))) && h4 != h3) visit_bucket(h4, pos, normal, r2);
    if (!any(equal(a, uvec3(h5))) && h5 != h3 && h5 != h4) visit_bucket(h5, pos, normal, r2);
    if (!any(equal(a, uvec3(h6))) && !any(equal(uvec3(h3, h4, h5), uvec3(h6)))) visit_bucket(h6, pos, normal, r2);
    if (!any(equal(a, uvec3(h7))) && !any(equal(uvec4(h3, h4, h5, h6), uvec4(h7)))) visit_bucket(h7, pos, normal, r2);
}
#endif

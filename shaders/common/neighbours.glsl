// Visits the photons of this batch within sqrt(r2) of a hit point that arrive from the side it is seen
// from, calling the including kernel's `visit(photon, d2)` for each. Needs `sorted` (records grouped by
// bucket), `cell_start` and `params` declared before it.
#ifndef NEIGHBOURS_GLSL
#define NEIGHBOURS_GLSL
#include "grid.glsl"

void visit(Photon p, float d2);

// Sign of dot(direction, n) for an octahedral-encoded direction: the vector needs no normalising.
bool arrives_from_front(uint dir, vec3 n) {
    vec2 e = unpackSnorm2x16(dir);
    vec3 d = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (d.z < 0.0) d.xy = (1.0 - abs(d.yx)) * vec2(d.x >= 0.0 ? 1.0 : -1.0, d.y >= 0.0 ? 1.0 : -1.0);
    return dot(d, n) < 0.0;
}

void for_each_photon_near(vec3 pos, vec3 normal, float r2) {
    float r = sqrt(r2);
    ivec3 lo = grid_cell(pos - vec3(r));
    ivec3 hi = grid_cell(pos + vec3(r));
    for (int z = lo.z; z <= hi.z; z++)
    for (int y = lo.y; y <= hi.y; y++)
    for (int x = lo.x; x <= hi.x; x++) {
        ivec3 c = ivec3(x, y, z);
        uint h = grid_hash(c);
        for (uint k = cell_start[h]; k < cell_start[h + 1u]; k++) {
            Photon p = sorted[k];
            vec3 dv = p.pos - pos;
            float d2 = dot(dv, dv);
            if (d2 > r2) continue;
            // Two cells may share a bucket: take a photon only from its own cell.
            if (grid_cell(p.pos) != c) continue;
            // The BRDF is zero for light arriving from behind the surface (ALGORITHM.md).
            if (!arrives_from_front(p.dir, normal)) continue;
            visit(p, d2);
        }
    }
}
#endif

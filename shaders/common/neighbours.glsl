// The photons of this batch near a group of hit points. A thread gathers for GROUP hit points at once
// (consecutive entries of the spatially sorted order, so usually neighbours on one surface) and tests each
// photon it reads against all of them: on lavapipe every read from a storage buffer is a gather per lane,
// and the group shares its reads. Calls the including kernel's `visit(j, flux, dir, d2)` for each photon within
// sqrt(q_r2[j]) of hit point j that arrives from the side it is seen from (dir: its direction of travel,
// not normalised). Needs `sorted_texels` (records
// grouped by bucket, two 16-byte texels each: position and cell key, flux and direction), `cell_start` and
// `params` declared before it. The records are read as texels: a texel fetch is a vector gather on
// lavapipe, where a storage-buffer load is a loop over the lanes (bvh.glsl).
#ifndef NEIGHBOURS_GLSL
#define NEIGHBOURS_GLSL
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_EXT_control_flow_attributes : require
#include "grid.glsl"
#include "sampling.glsl"

// Hit points per thread: 2 as built (gather::GROUP), 1 where the renderer compiles it so. Measured per
// 1M-photon pass at 512^2 with the scale-free probe and the cone filter, since records are read as
// whole 64-bit words: SPPM 282-320 ms with two, 339-357 with four, 331-342 with one; PPM 395-421 with
// two, 454-457 with four. Without the probe (smaller radii, fewer photons per lookup) one is fastest:
// PPM 221-230 ms against 303-307 with two, SPPM 170-179 against 187-213 (Renderer::new picks by that).
#ifndef GROUP_SIZE
#define GROUP_SIZE 2
#endif
const uint GROUP = GROUP_SIZE;

// Loop steps this subgroup's lookups took, each counted by one lane. lavapipe ends every loop of a SIMD
// group (its subgroup) once they have taken 65535 steps in all (LP_MAX_TGSI_LOOP_ITERATIONS), an exit
// the compiler cannot see, so a loop cannot tell it was cut. Counting the steps can: a loop runs as
// many steps as its longest active lane, which subgroupMax gives. lookup_may_be_cut() compares the
// total with the limit, so a cut lookup is an error, never a silently darker image.
uint lookup_steps = 0u;

void count_steps(uint n) {
    if (subgroupElect()) lookup_steps += n;
}

// The group, set by the including kernel; q_r2[j] < 0 marks an unused member.
vec3 q_pos[GROUP];
vec3 q_normal[GROUP];
float q_r2[GROUP];

void visit(uint j, vec3 flux, vec3 dir, float d2);

// The photons of cell `key` (its bucket may hold other cells' too) for the members in bit set `select`.
// Fields are read only when needed: most photons of a bucket are outside every sphere.
void visit_cell(uint key, uint select) {
    uint h = grid_bucket(key);
    uint end = cell_start[h + 1u];
    uint k = cell_start[h];
    count_steps(subgroupMax(end - k) + 1u);
    for (; k < end; k++) {
        uvec4 a = texelFetch(sorted_texels, int(2u * k));
        uint cell = a.w;
        vec3 p = uintBitsToFloat(a.xyz);
        float d2[GROUP];
        bool inside[GROUP];
        bool any_inside = false;
        [[unroll]] for (uint j = 0u; j < GROUP; j++) {
            vec3 dv = p - q_pos[j];
            d2[j] = dot(dv, dv);
            inside[j] = (select & (1u << j)) != 0u && d2[j] <= q_r2[j];
            any_inside = any_inside || inside[j];
        }
        if (!any_inside) continue;
        // Another cell's photon in a shared bucket: it is counted when its own cell is visited.
        if (cell != key) continue;
        // The BRDF is zero for light arriving from behind the surface (../shared/paper/ALGORITHM.md); only the sign of
        // the dot product matters, so the direction needs no normalising.
        uvec4 b = texelFetch(sorted_texels, int(2u * k + 1u));
        vec3 flux = uintBitsToFloat(b.xyz);
        vec3 dir = oct_decode_unnormalized(b.w);
        [[unroll]] for (uint j = 0u; j < GROUP; j++) {
            if (inside[j] && dot(dir, q_normal[j]) < 0.0) visit(j, flux, dir, d2[j]);
        }
    }
}

int window_cells(ivec3 lo, ivec3 hi) {
    ivec3 e = min(hi - lo + 1, ivec3(1024)); // saturates (members far apart) instead of overflowing
    return e.x * e.y * e.z;
}

// Visits the cells lo..hi that the sphere of at least one selected member touches.
void visit_window(ivec3 lo, ivec3 hi, uint select) {
    vec3 rel[GROUP];    // members in cell units
    float r2c[GROUP];   // their r^2 in cell units
    float inv = 1.0 / params.cell_size;
    [[unroll]] for (uint j = 0u; j < GROUP; j++) {
        rel[j] = (q_pos[j] - params.grid_min) * inv;
        r2c[j] = q_r2[j] * inv * inv;
    }
    for (int z = lo.z; z <= hi.z; z++) {
        count_steps(1u);
        for (int y = lo.y; y <= hi.y; y++) {
            count_steps(1u);
            for (int x = lo.x; x <= hi.x; x++) {
                count_steps(1u);
                vec3 c = vec3(x, y, z);
                bool touched = false;
                [[unroll]] for (uint j = 0u; j < GROUP; j++) {
                    vec3 out_of_cell = max(max(c - rel[j], rel[j] - (c + 1.0)), 0.0); // distance to the cell
                    touched = touched || ((select & (1u << j)) != 0u && dot(out_of_cell, out_of_cell) <= r2c[j]);
                }
                if (touched) visit_cell(grid_key(ivec3(x, y, z)), select);
            }
        }
    }
}

// Each member's window is the cells its sphere's bounding box overlaps (3x3x3 at most: cells are 1.5
// times the largest radius wide, lower/grid.rs: CELL_PER_RADIUS). Members close together share one
// window, the union of theirs; where the union is larger than their windows together (members on
// different surfaces), each gets its own.
void for_each_photon_near_group() {
    ivec3 lo[GROUP], hi[GROUP];
    ivec3 ulo = ivec3(0x7fffffff), uhi = ivec3(-0x7fffffff);
    uint live = 0u;
    int separate = 0;
    [[unroll]] for (uint j = 0u; j < GROUP; j++) {
        float r = sqrt(max(q_r2[j], 0.0));
        lo[j] = grid_cell(q_pos[j] - vec3(r));
        hi[j] = grid_cell(q_pos[j] + vec3(r));
        if (q_r2[j] < 0.0) continue;
        live |= 1u << j;
        ulo = min(ulo, lo[j]);
        uhi = max(uhi, hi[j]);
        separate += window_cells(lo[j], hi[j]);
    }
    if (live == 0u) return;
    if (window_cells(ulo, uhi) <= separate) {
        visit_window(ulo, uhi, live);
        return;
    }
    [[unroll]] for (uint j = 0u; j < GROUP; j++) {
        if ((live & (1u << j)) != 0u) visit_window(lo[j], hi[j], 1u << j);
    }
}

// Whether this subgroup's lookups may have run into the device's loop limit (params.lookup_limit: the
// budget less a margin for the kernel's other loops; never on a device without one).
bool lookup_may_be_cut() {
    return subgroupAdd(lookup_steps) >= params.lookup_limit;
}
#endif

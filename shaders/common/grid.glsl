// The photon grid: a hashed uniform grid of cell size params.cell_size, rebuilt for every batch of photons.
#ifndef GRID_GLSL
#define GRID_GLSL
ivec3 grid_cell(vec3 p) {
    return ivec3(floor((p - params.grid_min) / params.cell_size));
}

uint grid_hash(ivec3 c) {
    // Teschner et al. 2003's primes; the mask keeps it in the table.
    return (uint(c.x) * 73856093u ^ uint(c.y) * 19349663u ^ uint(c.z) * 83492791u) & params.grid_mask;
}
#endif

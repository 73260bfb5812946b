// The photon grid: a hashed uniform grid of cell size params.cell_size, rebuilt for every batch of photons.
// The cell size follows the search radii as they shrink (Renderer::pass), so a lookup's window of cells
// stays close to its sphere.
#ifndef GRID_GLSL
#define GRID_GLSL
ivec3 grid_cell(vec3 p) {
    return ivec3(floor((p - params.grid_min) / params.cell_size));
}

// A cell's key: its coordinates modulo 1024, packed 10 bits each. Every record carries its cell's key. A
// lookup window is far narrower than 1024 cells, so inside it a key names one cell: a photon is counted
// only while its own cell is visited, even where two cells of the window share a hash bucket.
uint grid_key(ivec3 c) {
    uvec3 u = uvec3(c) & 1023u;
    return u.x | (u.y << 10u) | (u.z << 20u);
}

uint grid_bucket(uint key) {
    // Teschner et al. 2003's primes; the mask keeps it in the table.
    uint x = key & 1023u, y = (key >> 10u) & 1023u, z = key >> 20u;
    return (x * 73856093u ^ y * 19349663u ^ z * 83492791u) & params.grid_mask;
}
#endif

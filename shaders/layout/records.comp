// Not a stage, never dispatched: it declares, in storage blocks, the records that the kernels read as
// texels (uniform texel buffers), so that build.rs reflects their std430 layouts and crates/kernels/src/
// layout.rs checks its Rust twins against them, as for every other record.
#version 460
layout(local_size_x = 1) in;
#include "types.glsl"

layout(std430, binding = 0) buffer Materials { Material materials[]; };
layout(std430, binding = 1) buffer BvhNodes { BvhNode bvh_nodes[]; };
layout(std430, binding = 2) buffer BvhTriangles { Triangle bvh_triangles[]; };
layout(std430, binding = 3) buffer Photons { Photon photons[]; };

void main() {
    // Statically used, so that the compiler keeps the blocks and their layouts.
    materials[0].surface = bvh_nodes[0].child[0] + bvh_triangles[0].material + photons[0].cell;
}

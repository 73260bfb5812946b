// Scene bindings shared by the kernels that trace rays (ray, photon): always bindings 0-3, in this order.
#ifndef BINDINGS_GLSL
#define BINDINGS_GLSL
layout(std430, binding = 0) readonly buffer Params { RenderParams params; };
layout(std430, binding = 1) readonly buffer Spheres { Sphere spheres[]; };
layout(std430, binding = 2) readonly buffer Quads { Quad quads[]; };
layout(std430, binding = 3) readonly buffer Materials { Material materials[]; };
#endif

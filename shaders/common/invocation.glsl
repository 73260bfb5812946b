#ifndef INVOCATION_GLSL
#define INVOCATION_GLSL
// Large dispatches spread over y (65535 workgroups per dimension): this linearises them.
uint invocation_index() {
    return gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
}

// An indirect dispatch's workgroups for `groups` of them, spread over y past the 65535 one dimension may
// hold, as ComputePipeline::dispatch spreads a direct one (invocation_index linearises them): x * y covers
// `groups` with less than a row past it. Zero groups: (0, 1, 1), which runs nothing.
uvec3 spread_groups(uint groups) {
    uint x = min(groups, 65535u);
    return uvec3(x, x == 0u ? 1u : (groups + x - 1u) / x, 1u);
}
#endif

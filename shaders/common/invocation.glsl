#ifndef INVOCATION_GLSL
#define INVOCATION_GLSL
// Large dispatches spread over y (65535 workgroups per dimension): this linearises them.
uint invocation_index() {
    return gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
}
#endif

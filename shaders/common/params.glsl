// The render's constants (binding 0 of every kernel that reads them), and a private copy: kernels call
// load_params() first and read `params` from then on. On lavapipe every read of a storage buffer is a
// bounds-checked gather per lane, and reads inside loops are not hoisted, so the copy is much cheaper.
#ifndef PARAMS_GLSL
#define PARAMS_GLSL
layout(std430, binding = 0) readonly buffer Params { RenderParams params_buffer; };
RenderParams params;

void load_params() {
    params = params_buffer;
}
#endif

// Pass 3, between the two rounds of a BVH scene's photon batch (photon.comp): the resume round's
// workgroups, one thread for each suspended photon and each photon of the batch no thread started.
#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 1) in;

#include "types.glsl"
#include "invocation.glsl"
layout(std430, binding = 0) buffer Work { PhotonWork work; };
layout(push_constant) uniform PhotonResumePush {
    uint count;      // photons in the batch
    uint local_size; // photon.comp's workgroup size
} pc;

void main() {
    uint n = work.suspended + pc.count - min(work.started, pc.count);
    work.groups = spread_groups((n + pc.local_size - 1u) / pc.local_size);
}

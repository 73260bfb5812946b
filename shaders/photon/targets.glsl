// Photons aimed at what casts caustics (crates/engine/src/lower/targets.rs finds the spheres around the
// mirrors, glass and lobes sampled through; CPU twin: crates/reference/src/targets.rs). An area light's
// photon leaves along a cosine direction about its normal n, or with probability params.target_share
// along a direction uniform in the cone that target j (one of params.num_targets, each as likely) subtends
// from o; a target that holds o gives the cosine direction instead. The photon's flux is multiplied by the
// cosine density over the mixture's, so its expectation is the light's whatever is aimed at:
//   p(d) = (1 - s + s m / N) cos(d, n) / pi + (s / N) sum over the targets k not holding o of [d in C_k] / W_k
// with s the share, N the targets, m those that hold o, C_k the cone and W_k = 2 pi (1 - cos a_k) its solid
// angle (sin a_k = r_k / |c_k - o|). The weight is at most 1 / (1 - s) (lower.rs scales the flux's
// fixed point by it); 0 where d leaves below the light (the photon then carries nothing and ends).
#ifndef TARGETS_GLSL
#define TARGETS_GLSL

#ifdef SCENE_CONSTANTS
#define HAS_TARGETS SCENE_TARGETS
#else
#define HAS_TARGETS true
#endif

// Target k's cone from o: its axis, cos a and 1 - cos a (from sin^2 a, exact for the narrow cones that
// matter, where 1 - cos a would cancel); false where o is inside it.
bool target_cone(uint k, vec3 o, out vec3 axis, out float cos_a, out float one_minus) {
    vec4 t = params.targets[k];
    vec3 to = t.xyz - o;
    float dist2 = dot(to, to);
    float sin2 = t.w * t.w / dist2;
    axis = to * inversesqrt(dist2);
    cos_a = sqrt(max(0.0, 1.0 - sin2));
    one_minus = sin2 / (1.0 + cos_a);
    return sin2 < 1.0;
}

// Target k's term of the mixture's density at d (none past params.num_targets): its share of the choice
// goes to the cosine where it holds o, else the cone's density 1 / W_k where d is in its cone.
void target_density(uint k, vec3 o, vec3 d, inout float cosine, inout float cones) {
    if (k >= params.num_targets) return;
    vec3 axis;
    float cos_a, one_minus;
    if (!target_cone(k, o, axis, cos_a, one_minus)) cosine += params.target_share / float(params.num_targets);
    else if (dot(d, axis) >= cos_a) cones += 1.0 / (2.0 * PI * one_minus);
}

// The direction an emitted photon leaves o along (n: the light's normal there), from the uniform numbers
// u1, u2 (the direction) and c (the choice); `w` the weight its flux takes.
vec3 aimed_direction(vec3 o, vec3 n, float u1, float u2, float c, out float w) {
    float s = params.target_share;
    uint count = params.num_targets;
    vec3 d = cosine_direction(n, u1, u2);
    if (c < s) {
        uint j = min(uint(c / s * float(count)), count - 1u);
        vec3 axis;
        float cos_a, one_minus;
        if (target_cone(j, o, axis, cos_a, one_minus)) {
            float cos_t = 1.0 - u1 * one_minus;
            float sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
            vec3 t, b;
            onb(axis, t, b);
            float phi = 2.0 * PI * u2;
            d = normalize(sin_t * cos(phi) * t + sin_t * sin(phi) * b + cos_t * axis);
        }
    }
    float cos_n = dot(d, n);
    if (!(cos_n > 0.0)) { w = 0.0; return d; }
    float cosine = 1.0 - s;
    float cones = 0.0;
    // Written out for each of the MAX_TARGETS, not a loop: lavapipe counts every loop's iterations against
    // the SIMD group's budget, which photon.comp's PATH_STEP_LOOPS accounts for (and runs this on every
    // step of the path, under an empty mask where no lane emits).
    target_density(0u, o, d, cosine, cones);
    target_density(1u, o, d, cosine, cones);
    target_density(2u, o, d, cosine, cones);
    target_density(3u, o, d, cosine, cones);
    target_density(4u, o, d, cosine, cones);
    target_density(5u, o, d, cosine, cones);
    target_density(6u, o, d, cosine, cones);
    target_density(7u, o, d, cosine, cones);
    // (cos / pi) / p(d)
    w = cos_n / (cosine * cos_n + PI * s / float(count) * cones);
    return d;
}
#endif

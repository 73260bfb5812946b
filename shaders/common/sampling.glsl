// Directions, bases and the dielectric Fresnel term, shared by the ray and photon kernels.
#ifndef SAMPLING_GLSL
#define SAMPLING_GLSL
const float PI = 3.14159265358979323846;

// Orthonormal basis around unit n (Duff et al. 2017, branchless).
void onb(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

// Cosine-weighted direction about n from two uniform numbers.
vec3 cosine_direction(vec3 n, float u1, float u2) {
    float r = sqrt(u1);
    float phi = 2.0 * PI * u2;
    vec3 t, b;
    onb(n, t, b);
    return normalize(r * cos(phi) * t + r * sin(phi) * b + sqrt(max(0.0, 1.0 - u1)) * n);
}

// Exact unpolarised Fresnel reflectance of a smooth dielectric. cos_i > 0 is the cosine on the incident
// side, eta = n_incident / n_transmitted. Returns 1 on total internal reflection; cos_t gets the
// transmitted cosine.
float fresnel_dielectric(float cos_i, float eta, out float cos_t) {
    float sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0) { cos_t = 0.0; return 1.0; }
    cos_t = sqrt(1.0 - sin2_t);
    float rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    float rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

// Octahedral encoding of a unit vector into two snorm16 (for photon directions).
uint oct_encode(vec3 v) {
    vec2 p = v.xy / (abs(v.x) + abs(v.y) + abs(v.z));
    if (v.z < 0.0) {
        p = (1.0 - abs(p.yx)) * vec2(p.x >= 0.0 ? 1.0 : -1.0, p.y >= 0.0 ? 1.0 : -1.0);
    }
    return packSnorm2x16(p);
}

// The inverse, not normalised: the direction's length is between 1/sqrt(3) and 1, and the one use (the
// sign of a dot product in neighbours.glsl) needs no more.
vec3 oct_decode_unnormalized(uint e) {
    vec2 p = unpackSnorm2x16(e);
    vec3 v = vec3(p, 1.0 - abs(p.x) - abs(p.y));
    if (v.z < 0.0) {
        v.xy = (1.0 - abs(v.yx)) * vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0);
    }
    return v;
}
#endif

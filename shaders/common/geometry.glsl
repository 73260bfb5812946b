// Ray intersection with the scene (analytic spheres and parallelograms). Needs the buffers `spheres`,
// `quads` and `params` declared by the including kernel.
#ifndef GEOMETRY_GLSL
#define GEOMETRY_GLSL

struct Hit {
    float t;
    vec3 pos;
    vec3 normal;     // geometric normal: outward for spheres, the front normal for quads
    uint material;
    uint kind;       // 0 sphere, 1 quad
    uint index;
};

// Nearest hit with t in (tmin, tmax); false if none.
bool intersect_scene(vec3 o, vec3 d, float tmin, float tmax, out Hit hit) {
    hit.t = tmax;
    bool found = false;
    for (uint i = 0u; i < params.num_spheres; i++) {
        Sphere s = spheres[i];
        vec3 oc = o - s.center;
        float b = dot(oc, d);
        float c = dot(oc, oc) - s.radius * s.radius;
        float disc = b * b - c;
        if (disc < 0.0) continue;
        float sq = sqrt(disc);
        float t = -b - sq;
        if (t <= tmin) t = -b + sq;
        if (t > tmin && t < hit.t) {
            hit.t = t; hit.kind = 0u; hit.index = i; found = true;
        }
    }
    for (uint i = 0u; i < params.num_quads; i++) {
        Quad q = quads[i];
        float denom = dot(q.normal, d);
        if (abs(denom) < 1e-12) continue;
        float t = (q.plane_d - dot(q.normal, o)) / denom;
        if (t <= tmin || t >= hit.t) continue;
        vec3 rel = o + t * d - q.origin;
        float a = dot(q.w, cross(rel, q.edge_v));
        float b = dot(q.w, cross(q.edge_u, rel));
        if (a < 0.0 || a > 1.0 || b < 0.0 || b > 1.0) continue;
        hit.t = t; hit.kind = 1u; hit.index = i; found = true;
    }
    if (found) {
        hit.pos = o + hit.t * d;
        if (hit.kind == 0u) {
            Sphere s = spheres[hit.index];
            hit.normal = (hit.pos - s.center) / s.radius;
            hit.material = s.material;
        } else {
            hit.normal = quads[hit.index].normal;
            hit.material = quads[hit.index].material;
        }
    }
    return found;
}
#endif

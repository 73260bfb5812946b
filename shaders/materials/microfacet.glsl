// Microfacet distributions as Mitsuba 3 defines them (its MicrofacetDistribution): Beckmann and GGX, with
// roughness alpha_u along the tangent and alpha_v along the bitangent, Smith's separable shadowing-masking,
// and sampling of the normals visible from a direction (Heitz 2018, "Sampling the GGX Distribution of
// Visible Normals"; for Beckmann the slope inversion of Jakob 2014, "An Improved Visible Normal Sampling
// Routine for the Beckmann Distribution"). Directions are in the local frame: z the macro-surface normal
// on the side of the incoming direction, x the tangent. CPU twin: crates/materials/src/microfacet.rs.
#ifndef MICROFACET_GLSL
#define MICROFACET_GLSL

const uint MICROFACET_BECKMANN = 0u;
const uint MICROFACET_GGX = 1u;

// A kernel compiled for one scene (SCENE_CONSTANTS) knows which distributions its rough surfaces use, and
// leaves out the other's code: Beckmann's sampling (erf, erfinv, Newton's steps) is long, and lavapipe
// runs both sides of a branch, so a GGX-only scene would pay for it at every rough vertex.
#ifdef SCENE_CONSTANTS
#define HAS_BECKMANN SCENE_BECKMANN
#define HAS_GGX SCENE_GGX
#else
#define HAS_BECKMANN true
#define HAS_GGX true
#endif

struct Microfacet {
    uint kind;       // MICROFACET_*
    float au;        // alpha along the tangent
    float av;        // alpha along the bitangent
};

// Whether mf is GGX (else Beckmann), settled at compile time where the scene has one kind.
bool mf_is_ggx(Microfacet mf) {
    return !HAS_BECKMANN || (HAS_GGX && mf.kind == MICROFACET_GGX);
}

// Direction d in the local frame (t, b, nf).
vec3 to_local(vec3 d, vec3 t, vec3 b, vec3 nf) {
    return vec3(dot(d, t), dot(d, b), dot(d, nf));
}

// The local frame about nf: its tangent t along dpdu (made orthogonal to nf, as Mitsuba's shading frame
// is) where a lobe is anisotropic, and the frame of nf alone (onb) where dpdu is 0 (isotropic: any tangent
// serves) or along nf. On a surface's back side b is Mitsuba's bitangent reversed, which no lobe tells
// apart (D and G1 are even in y).
void frame(vec3 nf, vec3 dpdu, out vec3 t, out vec3 b) {
    vec3 s = dpdu - nf * dot(nf, dpdu);
    float l = dot(s, s);
    if (l > 1e-12 * dot(dpdu, dpdu)) {
        t = s * inversesqrt(l);
        b = cross(nf, t);
    } else {
        onb(nf, t, b);
    }
}

// Material i's distribution (the material's fifth texel; bindings.glsl's material_texels).
Microfacet material_microfacet(uint i) {
    uvec4 t = texelFetch(material_texels, int(MATERIAL_TEXELS * i + 4u));
    return Microfacet(t.z, uintBitsToFloat(t.x), uintBitsToFloat(t.y));
}

// The distribution of material i at a hit, m as apply_texture left it: its alpha textured there, if it
// has an alpha texture (texture.glsl's apply_parameter_textures).
Microfacet hit_microfacet(uint i, Material m) {
    Microfacet mf = material_microfacet(i);
    if (m.alpha_texture != 0u) {
        mf.au = m.alpha_u;
        mf.av = m.alpha_v;
    }
    return mf;
}

// Material i's table (Material.table: a rough plastic's coat).
uint material_table(uint i) {
    return texelFetch(material_texels, int(MATERIAL_TEXELS * i + 4u)).w;
}

// The distribution of normals D(m).
float mf_d(Microfacet mf, vec3 m) {
    if (m.z <= 0.0) return 0.0;
    float x = m.x / mf.au, y = m.y / mf.av, z2 = m.z * m.z;
    float r;
    if (mf_is_ggx(mf)) {
        float t = x * x + y * y + z2;
        r = 1.0 / (PI * mf.au * mf.av * t * t);
    } else {
        r = exp(-(x * x + y * y) / z2) / (PI * mf.au * mf.av * z2 * z2);
    }
    return r * m.z > 1e-20 ? r : 0.0; // as Mitsuba: no denormal tails
}

// Smith's masking G1(v, m): the fraction of microfacets of normal m that direction v sees.
float mf_g1(Microfacet mf, vec3 v, vec3 m) {
    if (dot(v, m) * v.z <= 0.0) return 0.0;
    float xy = (mf.au * v.x) * (mf.au * v.x) + (mf.av * v.y) * (mf.av * v.y);
    if (xy <= 0.0) return 1.0;
    float tan2 = xy / (v.z * v.z); // tan^2 theta times the projected alpha^2
    if (mf_is_ggx(mf)) return 2.0 / (1.0 + sqrt(1.0 + tan2));
    float a = inversesqrt(tan2);
    // Mitsuba's rational fit (Walter et al. 2007), which rises to 1.00006 just below a = 1.6: held at 1,
    // so that no bounce gains flux.
    return a >= 1.6 ? 1.0 : min((3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a), 1.0);
}

// erf, Abramowitz and Stegun 7.1.26 (absolute error below 1.5e-7).
float mf_erf(float x) {
    float t = 1.0 / (1.0 + 0.3275911 * abs(x));
    float p = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    float y = 1.0 - p * exp(-x * x);
    return x < 0.0 ? -y : y;
}

// Its inverse on (-1, 1), M. Giles, "Approximating the erfinv function" (GPU Computing Gems, 2011).
float mf_erfinv(float x) {
    float w = -log(max((1.0 - x) * (1.0 + x), 1e-30));
    float p;
    if (w < 5.0) {
        w -= 2.5;
        p = 2.81022636e-08;
        p = 3.43273939e-07 + p * w;
        p = -3.5233877e-06 + p * w;
        p = -4.39150654e-06 + p * w;
        p = 0.00021858087 + p * w;
        p = -0.00125372503 + p * w;
        p = -0.00417768164 + p * w;
        p = 0.246640727 + p * w;
        p = 1.50140941 + p * w;
    } else {
        w = sqrt(w) - 3.0;
        p = -0.000200214257;
        p = 0.000100950558 + p * w;
        p = 0.00134934322 + p * w;
        p = -0.00367342844 + p * w;
        p = 0.00573950773 + p * w;
        p = -0.0076224613 + p * w;
        p = 0.00943887047 + p * w;
        p = 1.00167406 + p * w;
        p = 2.83297682 + p * w;
    }
    return p * x;
}

// Beckmann: the slopes of the visible normals of the unit-roughness distribution seen at cos_theta (Jakob
// 2014): the x slope by Newton's method on its CDF in the erf domain, the y slope a Gaussian.
vec2 mf_beckmann_slopes(float cos_theta, vec2 u) {
    u = clamp(u, vec2(1e-6), vec2(1.0 - 1e-6));
    float tan_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0)) / cos_theta;
    float cot_theta = 1.0 / max(tan_theta, 1e-7);
    const float INV_SQRT_PI = 0.56418958354775628;
    float top = mf_erf(cot_theta);
    float x = top - (top + 1.0) * mf_erf(sqrt(-log(u.x))); // initial guess
    float target = u.x * (1.0 + top + INV_SQRT_PI * tan_theta * exp(-cot_theta * cot_theta));
    [[unroll]] for (uint k = 0u; k < 3u; k++) {
        float slope = mf_erfinv(x);
        float value = 1.0 + x + INV_SQRT_PI * tan_theta * exp(-slope * slope) - target;
        x -= value / (1.0 - slope * tan_theta);
    }
    return vec2(mf_erfinv(clamp(x, -1.0 + 1e-7, 1.0 - 1e-7)), mf_erfinv(2.0 * u.y - 1.0));
}

// A normal m drawn from the distribution of normals visible from wi (wi.z > 0), whose density is
// D_wi(m) = G1(wi, m) max(0, wi.m) D(m) / wi.z.
vec3 mf_sample_visible(Microfacet mf, vec3 wi, vec2 u) {
    vec3 v = normalize(vec3(mf.au * wi.x, mf.av * wi.y, wi.z)); // stretched to unit roughness
    if (mf_is_ggx(mf)) {
        // Heitz 2018: a point on the projected hemisphere, seen from v.
        float len2 = v.x * v.x + v.y * v.y;
        vec3 t1 = len2 > 0.0 ? vec3(-v.y, v.x, 0.0) * inversesqrt(len2) : vec3(1.0, 0.0, 0.0);
        vec3 t2 = cross(v, t1);
        float r = sqrt(u.x);
        float phi = 2.0 * PI * u.y;
        float p1 = r * cos(phi);
        float p2 = r * sin(phi);
        float s = 0.5 * (1.0 + v.z);
        p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * p2;
        vec3 n = p1 * t1 + p2 * t2 + sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0)) * v;
        return normalize(vec3(mf.au * n.x, mf.av * n.y, max(n.z, 0.0)));
    }
    float sin_theta = sqrt(max(1.0 - v.z * v.z, 0.0));
    float cos_phi = sin_theta > 0.0 ? v.x / sin_theta : 1.0;
    float sin_phi = sin_theta > 0.0 ? v.y / sin_theta : 0.0;
    vec2 s = mf_beckmann_slopes(v.z, u);
    s = vec2(cos_phi * s.x - sin_phi * s.y, sin_phi * s.x + cos_phi * s.y) * vec2(mf.au, mf.av); // rotate, unstretch
    return normalize(vec3(-s.x, -s.y, 1.0));
}

// The density of mf_sample_visible's normal m seen from wi.
float mf_visible_pdf(Microfacet mf, vec3 wi, vec3 m) {
    return mf_g1(mf, wi, m) * max(dot(wi, m), 0.0) * mf_d(mf, m) / wi.z;
}
#endif

// PCG32 (O'Neill), one independent stream per photon or pixel. The CPU reference (crates/materials/src/
// rng.rs) is the same integer arithmetic, so both see identical random numbers.
#ifndef RNG_GLSL
#define RNG_GLSL
struct Rng { uint64_t state; uint64_t inc; };

uint rng_next(inout Rng r) {
    uint64_t old = r.state;
    r.state = old * 6364136223846793005UL + r.inc;
    uint xorshifted = uint(((old >> 18u) ^ old) >> 27u);
    uint rot = uint(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
}

Rng rng_new(uint64_t seed, uint64_t stream) {
    Rng r;
    r.state = 0UL;
    r.inc = (stream << 1u) | 1UL;
    rng_next(r);
    r.state += seed;
    rng_next(r);
    return r;
}

// Uniform in [0, 1): the top 24 bits, exactly representable.
float rng_float(inout Rng r) {
    return float(rng_next(r) >> 8u) * (1.0 / 16777216.0);
}
#endif

/* rng.h: PCG32 (O'Neill 2014), one stream per pixel, so images do not depend on the
 * thread count or tile order. */
#ifndef EX_RNG_H
#define EX_RNG_H

#include <stdint.h>

typedef struct rng {
    uint64_t state, inc;
} rng;

static inline uint32_t rng_u32(rng *r)
{
    const uint64_t old = r->state;
    r->state = old * 6364136223846793005ULL + r->inc;
    const uint32_t xorshifted = (uint32_t)(((old >> 18u) ^ old) >> 27u);
    const uint32_t rot = (uint32_t)(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
}

static inline uint64_t mix64(uint64_t z) /* splitmix64 finalizer */
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

static inline rng rng_seed(uint64_t seed, uint64_t stream)
{
    rng r;
    r.state = 0;
    r.inc = (mix64(stream ^ 0x9e3779b97f4a7c15ULL) << 1u) | 1u;
    rng_u32(&r);
    r.state += mix64(seed + 0x632be59bd9b4e019ULL);
    rng_u32(&r);
    return r;
}

/* A float in [0, 1): 24 random bits. */
static inline float rng_float(rng *r) { return (float)(rng_u32(r) >> 8) * 0x1p-24f; }

#endif

/* mk_rng.h: the seeded RNG of the tests, without Check, so the shared case
 * generators (cases.c) and the demos that link them use the same sequences. */
#ifndef MK_RNG_H
#define MK_RNG_H

#include <math.h>
#include <stdint.h>

#include "minko/math3d.h"

/* splitmix64: tiny, seedable, the same sequence on every platform. */
typedef struct mk_rng { uint64_t s; } mk_rng;
static inline uint64_t mk_rng_u64(mk_rng *r)
{
    uint64_t z = (r->s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
/* Uniform in [0, 1). */
static inline double mk_rng_unit(mk_rng *r) { return (double)(mk_rng_u64(r) >> 11) * (1.0 / 9007199254740992.0); }
static inline double mk_rng_range(mk_rng *r, double lo, double hi) { return lo + (hi - lo) * mk_rng_unit(r); }
static inline mk_vec3 mk_rng_v3(mk_rng *r, double lo, double hi)
{
    return mk_v3((mk_real)mk_rng_range(r, lo, hi), (mk_real)mk_rng_range(r, lo, hi), (mk_real)mk_rng_range(r, lo, hi));
}
/* Uniformly distributed unit quaternion (Shoemake). */
static inline mk_quat mk_rng_quat(mk_rng *r)
{
    double u1 = mk_rng_unit(r), u2 = 6.283185307179586 * mk_rng_unit(r), u3 = 6.283185307179586 * mk_rng_unit(r);
    double a = sqrt(1 - u1), b = sqrt(u1);
    return mk_quat_normalize(mk_quat_make((mk_real)(a * sin(u2)), (mk_real)(a * cos(u2)), (mk_real)(b * sin(u3)), (mk_real)(b * cos(u3))));
}
static inline mk_vec3 mk_rng_dir(mk_rng *r)
{
    for (;;) {
        mk_vec3 v = mk_rng_v3(r, -1, 1);
        mk_real l2 = mk_v3_len2(v);
        if (l2 > 1e-4 && l2 <= 1) return mk_v3_scale(v, 1 / mk_sqrt_(l2));
    }
}

#endif

/* bench_toi_bilateral.h: a prototype of bilateral advancement, for bench_toi only.
 *
 * The issue asks for conservative advancement (what mk_toi does) and bilateral
 * advancement (Catto's root finder of Box2D's b2TimeOfImpact) to be measured
 * against each other. The library keeps one implementation, so the other lives
 * here, built on the same internals as mk_toi (GJK on the cores, warm-started;
 * no GJK for sphere and plane pairs; the same tolerance floor; the
 * narrowphase's polished answer at a hit), so that the two differ only in how
 * they advance. Same inputs, same result struct, no input checks (the bench
 * passes valid sweeps). Not a proof of anything: see the .c file. */
#ifndef BENCH_TOI_BILATERAL_H
#define BENCH_TOI_BILATERAL_H

#include "minko/toi.h"

#ifdef __cplusplus
extern "C" {
#endif

mk_status bench_toi_bilateral(const mk_shape *a, const mk_sweep *sa, const mk_shape *b, const mk_sweep *sb, mk_real target,
                              mk_real tolerance, mk_toi_result *out);

#ifdef __cplusplus
}
#endif

#endif

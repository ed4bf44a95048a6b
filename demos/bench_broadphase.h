/* bench_broadphase.h: the C side of demos/bench_broadphase (Minko's part,
 * and the memory-bound floor), called from the C++ driver that also runs
 * Bullet, ODE and FCL. Boxes are 6 doubles each: lo x y z, hi x y z. Pairs
 * are object indices packed as (low << 32 | high). */
#ifndef BENCH_BROADPHASE_H
#define BENCH_BROADPHASE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bb_minko bb_minko;

/* kind: MK_BP_SAP, MK_BP_HGRID or MK_BP_AUTO; pairs_only as in mk_bp_def.
 * NULL on failure. */
bb_minko *bb_minko_create(int kind, int pairs_only, int n, const double *box, const unsigned char *is_static);
/* One frame: new boxes for `moved`, destroy + create for `respawned`,
 * update; returns the pair count, or -1 on a Minko error (printed). */
long bb_minko_frame(bb_minko *m, const double *box, const int *moved, int n_moved, const int *respawned, int n_respawned);
/* The pair set of the last frame as object indices (room for its count). */
void bb_minko_pairs(const bb_minko *m, uint64_t *out);
size_t bb_minko_bytes(const bb_minko *m);
const char *bb_minko_kind(const bb_minko *m);
/* Pairs the structure holds (the grid: candidates sharing a cell). */
long bb_minko_candidates(const bb_minko *m);
void bb_minko_destroy(bb_minko *m);

/* The floor: read every box once and write the true pairs once; returns a
 * value that depends on every input so the compiler cannot drop the work. */
double bb_floor(const double *box, int n, const uint64_t *pairs, long n_pairs, uint64_t *out);

#ifdef __cplusplus
}
#endif

#endif

/* bench_broadphase_minko.c: Minko's side of demos/bench_broadphase, in C as
 * an embedded user would write it: one mk_bp, ids kept per object, and an
 * array from proxy slot to object. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "minko/broadphase.h"
#include "bench_broadphase.h"

static mk_aabb box_of(const double *b)
{
    return mk_aabb_make(mk_v3((mk_real)b[0], (mk_real)b[1], (mk_real)b[2]), mk_v3((mk_real)b[3], (mk_real)b[4], (mk_real)b[5]));
}

static int report(const char *what, mk_status st)
{
    if (st == MK_OK) return 0;
    fprintf(stderr, "bench_broadphase: %s: %s\n", what, mk_status_str(st));
    return 1;
}

/* obj[slot]: the object of each proxy slot (MK_BP_SLOT), so the pair loop
 * needs no call per pair. */
struct bb_minko { mk_bp *bp; mk_bp_id *id; int *obj; int n, cap; const unsigned char *is_static; };

static int add(bb_minko *m, const double *box, int o)
{
    mk_status st = mk_bp_create_proxy(m->bp, box_of(box + 6 * o), NULL, 1, 1, m->is_static[o], &m->id[o]);
    if (report("create proxy", st)) return 1;
    m->obj[MK_BP_SLOT(m->id[o])] = o;
    return 0;
}

bb_minko *bb_minko_create(int kind, int pairs_only, int n, const double *box, const unsigned char *is_static)
{
    bb_minko *m = (bb_minko *)calloc(1, sizeof *m);
    mk_bp_def d = mk_bp_default_def();
    int i;
    if (!m) return NULL;
    m->n = n;
    /* churn destroys and creates within one frame: room for that too */
    m->cap = n + n / 8 + 64;
    m->is_static = is_static;
    m->id = (mk_bp_id *)calloc((size_t)n, sizeof *m->id);
    m->obj = (int *)calloc((size_t)m->cap, sizeof *m->obj);
    if (!m->id || !m->obj) { bb_minko_destroy(m); return NULL; }
    d.kind = (mk_bp_kind)kind;
    d.pairs_only = pairs_only;
    d.proxy_capacity = m->cap;
    if (report("create", mk_bp_create(&d, NULL, &m->bp))) { bb_minko_destroy(m); return NULL; }
    for (i = 0; i < n; ++i)
        if (add(m, box, i)) { bb_minko_destroy(m); return NULL; }
    return m;
}

long bb_minko_frame(bb_minko *m, const double *box, const int *moved, int n_moved, const int *respawned, int n_respawned)
{
    int i, np;
    for (i = 0; i < n_moved; ++i)
        if (report("move", mk_bp_move_proxy(m->bp, m->id[moved[i]], box_of(box + 6 * moved[i])))) return -1;
    for (i = 0; i < n_respawned; ++i) {
        int o = respawned[i];
        if (report("destroy", mk_bp_destroy_proxy(m->bp, m->id[o])) || add(m, box, o)) return -1;
    }
    if (report("update", mk_bp_update(m->bp))) return -1;
    mk_bp_pairs(m->bp, &np);
    return np;
}

void bb_minko_pairs(const bb_minko *m, uint64_t *out)
{
    int i, np;
    const mk_bp_pair *p = mk_bp_pairs(m->bp, &np);
    for (i = 0; i < np; ++i) {
        uint64_t a = (uint64_t)m->obj[MK_BP_SLOT(p[i].a)], b = (uint64_t)m->obj[MK_BP_SLOT(p[i].b)];
        out[i] = a < b ? a << 32 | b : b << 32 | a;
    }
}

size_t bb_minko_bytes(const bb_minko *m)
{
    mk_bp_stats st;
    return mk_bp_get_stats(m->bp, &st) == MK_OK ? st.bytes : 0;
}

const char *bb_minko_kind(const bb_minko *m)
{
    mk_bp_stats st;
    return mk_bp_get_stats(m->bp, &st) == MK_OK ? mk_bp_kind_name(st.kind) : "?";
}

long bb_minko_candidates(const bb_minko *m)
{
    mk_bp_stats st;
    return mk_bp_get_stats(m->bp, &st) == MK_OK ? st.candidates : -1;
}

void bb_minko_destroy(bb_minko *m)
{
    if (!m) return;
    mk_bp_destroy(m->bp);
    free(m->id);
    free(m->obj);
    free(m);
}

double bb_floor(const double *box, int n, const uint64_t *pairs, long n_pairs, uint64_t *out)
{
    double acc = 0;
    int i;
    for (i = 0; i < 6 * n; ++i) acc += box[i];
    memcpy(out, pairs, (size_t)n_pairs * sizeof *pairs);
    return acc + (double)(n_pairs ? out[n_pairs - 1] : 0);
}

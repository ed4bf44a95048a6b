/* bp_sweep.c: every overlapping pair from scratch, with no state kept between
 * calls: a sort and sweep in rows.
 *
 * Why rows: a plain sort and sweep on one axis tests every pair that
 * overlaps on that axis, and on a scene spread over a plane (ODE's exploded
 * heap: 10 000 spheres, 600 pairs) that is 500 000 tests. Cutting the second
 * axis into rows one box tall leaves a box only its own row and the two next
 * to it to sweep against, which divides those tests by the number of rows.
 *
 * How: the sweep axis is the one where box centres spread most, the row axis
 * the next one. Row height H is the largest box extent on the row axis (a
 * little more, so rounding cannot hide a pair), so a box's partners start in
 * its own row or the next one up or down. Each box becomes one 64-bit key
 * (row, its lower end on the sweep axis quantised to 16 bits, slot) and one
 * radix sort orders them; each row is swept alone and then merged with the
 * row above. The quantisation is monotone, so comparing quantised values
 * never stops a sweep before a box it should have met; the exact closed
 * test on the AABBs decides. Boxes infinite on the row axis (ground planes)
 * do not fit a row: they are tested against every box, O(n) each.
 *
 * Cost: O(n) keys, one radix sort of n keys (a few byte passes), and for
 * each box the boxes of its three rows that overlap it on the sweep axis. */
#include <math.h>
#include <string.h>

#include "broadphase_internal.h"

/* 16-bit quantised positions: with the row in the next byte, the radix sort
 * takes three passes over the keys (the slot is payload, never sorted on). */
#define MK_SWEEP_Q_MAX_ 0xFFFFu
#define MK_SWEEP_ROWS_ 0xFFFFu     /* 16-bit row numbers */

/* The frame of one sweep: axes, quantisation of the sweep axis, rows. */
typedef struct frame_ {
    int ax, ay;           /* sweep axis, row axis */
    double x0, xscale;    /* q(x) = floor((x - x0) * xscale), clamped */
    double y0, inv_h;     /* row(y) = floor((y - y0) * inv_h), clamped */
    double h;             /* row height: at least every box's extent on ay */
} frame_;

struct mk_sweep {
    uint64_t *key, *tmp;  /* sort keys: row << 40 | q(lo) << 24 | slot */
    uint32_t *qhi;        /* per sorted box: q(hi) on the sweep axis */
    mk_aabb *box;         /* per sorted box: its AABB (sequential reads in the sweep) */
    uint32_t *big;        /* slots of boxes infinite on the row axis */
    int cap;
    frame_ f;             /* of the last sweep, with its n sorted and nbig big boxes: */
    int n, nbig;          /* region queries after a stateless update read them */
};

static size_t sweep_bytes_per_proxy(void)
{
    return 2 * sizeof(uint64_t) + sizeof(uint32_t) + sizeof(mk_aabb) + sizeof(uint32_t);
}

static mk_status sweep_create(mk_bp *bp)
{
    struct mk_sweep *w;
    size_t n = (size_t)bp->cap;
    char *p;
    if (!(w = (struct mk_sweep *)mk_bp_alloc_(bp, sizeof *w))) return MK_ERR_OUT_OF_MEMORY;
    /* One block; the AABBs first for their alignment. */
    if (!(p = (char *)mk_bp_alloc_(bp, n * sweep_bytes_per_proxy()))) {
        mk_bp_free_(bp, w, sizeof *w);
        return MK_ERR_OUT_OF_MEMORY;
    }
    w->box = (mk_aabb *)p; p += n * sizeof(mk_aabb);
    w->key = (uint64_t *)p; p += n * sizeof(uint64_t);
    w->tmp = (uint64_t *)p; p += n * sizeof(uint64_t);
    w->qhi = (uint32_t *)p; p += n * sizeof(uint32_t);
    w->big = (uint32_t *)p;
    w->cap = bp->cap;
    bp->sweep = w;
    return MK_OK;
}

void mk_sweep_destroy_(mk_bp *bp)
{
    struct mk_sweep *w = bp->sweep;
    if (!w) return;
    mk_bp_free_(bp, w->box, (size_t)w->cap * sweep_bytes_per_proxy());
    mk_bp_free_(bp, w, sizeof *w);
    bp->sweep = NULL;
}


static int in_structure(const mk_bp *bp, uint32_t s)
{
    return (bp->flags[s] & (MK_PF_ALIVE | MK_PF_DYING)) == MK_PF_ALIVE;
}

static double lo_of(const mk_aabb *b, int axis) { return (double)(&b->lo.x)[axis]; }
static double hi_of(const mk_aabb *b, int axis) { return (double)(&b->hi.x)[axis]; }

/* Monotone in x, so q(lo_b) > q(hi_a) implies lo_b > hi_a. */
static uint32_t quantise(const frame_ *f, double x)
{
    double t = (x - f->x0) * f->xscale;
    if (!(t > 0)) return 0;
    return t >= (double)MK_SWEEP_Q_MAX_ ? MK_SWEEP_Q_MAX_ : (uint32_t)t;
}

static uint32_t row_of(const frame_ *f, double y)
{
    double t = (y - f->y0) * f->inv_h;
    if (!(t > 0)) return 0;
    return t >= (double)MK_SWEEP_ROWS_ ? MK_SWEEP_ROWS_ : (uint32_t)t;
}

/* Axes and ranges only steer the speed (any monotone quantisation and any
 * row origin are correct), so they come from a sample of at most about 1024
 * boxes; the row height must bound every box and takes a full pass. */
#define MK_SWEEP_SAMPLE_ 1024

typedef struct spread_ {
    double sum[3], sum2[3];
    int cnt[3];
    double lo[3], hi[3];  /* range of the sampled boxes finite on that axis */
} spread_;

static void measure(const mk_bp *bp, spread_ *p)
{
    uint32_t s, stride = (uint32_t)(bp->hi_slot / MK_SWEEP_SAMPLE_ + 1);
    int k;
    memset(p, 0, sizeof *p);
    for (k = 0; k < 3; ++k) { p->lo[k] = HUGE_VAL; p->hi[k] = -HUGE_VAL; }
    for (s = 0; s < (uint32_t)bp->hi_slot; s += stride) {
        const mk_aabb *b = &bp->box[s];
        if (!in_structure(bp, s)) continue;
        for (k = 0; k < 3; ++k) {
            double l = lo_of(b, k), h = hi_of(b, k), c = 0.5 * (l + h);
            if (!(h - l <= MK_REAL_MAX)) continue; /* infinite: says nothing about spread */
            p->sum[k] += c; p->sum2[k] += c * c; p->cnt[k]++;
            if (l < p->lo[k]) p->lo[k] = l;
            if (h > p->hi[k]) p->hi[k] = h;
        }
    }
}

/* The largest finite extent on `axis`, over every box. */
static double largest_extent(const mk_bp *bp, int axis)
{
    double m = 0;
    uint32_t s;
    for (s = 0; s < (uint32_t)bp->hi_slot; ++s) {
        double e = hi_of(&bp->box[s], axis) - lo_of(&bp->box[s], axis);
        if (in_structure(bp, s) && e > m && e <= MK_REAL_MAX) m = e;
    }
    return m;
}

static void plan(const mk_bp *bp, frame_ *f)
{
    spread_ p;
    double var[3], xlo, xhi, ylo, yhi, hmax;
    int k;
    measure(bp, &p);
    for (k = 0; k < 3; ++k) var[k] = p.cnt[k] ? p.sum2[k] / p.cnt[k] - (p.sum[k] / p.cnt[k]) * (p.sum[k] / p.cnt[k]) : 0;
    f->ax = 0;
    for (k = 1; k < 3; ++k) if (var[k] > var[f->ax]) f->ax = k;
    f->ay = f->ax == 0 ? 1 : 0;
    for (k = 0; k < 3; ++k) if (k != f->ax && var[k] > var[f->ay]) f->ay = k;
    xlo = p.lo[f->ax]; xhi = p.hi[f->ax];
    ylo = p.lo[f->ay]; yhi = p.hi[f->ay];
    hmax = largest_extent(bp, f->ay);
    f->x0 = xlo <= xhi ? xlo : 0;
    f->xscale = xhi > xlo ? (double)(MK_SWEEP_Q_MAX_ - 1) / (xhi - xlo) : 0;
    if (!(f->xscale <= 1e300)) f->xscale = 0;
    /* H a little above the largest extent: row numbers are computed in
     * double, so two rows apart must stay provably farther than any box.
     * At most MK_SWEEP_ROWS_ rows; rows beyond it merge into the last. */
    hmax *= 1.0 + 1.0 / 1024;
    if (hmax < (yhi - ylo) / (MK_SWEEP_ROWS_ - 1)) hmax = (yhi - ylo) / (MK_SWEEP_ROWS_ - 1);
    f->y0 = ylo <= yhi ? ylo : 0;
    f->h = hmax;
    f->inv_h = hmax > 0 ? 1.0 / hmax : 0;
    if (!(f->inv_h <= 1e300)) f->inv_h = 0; /* a subnormal height: one row */
}

typedef mk_status (*report_fn)(mk_bp *bp, uint32_t a, uint32_t b);

typedef struct sweep_ctx_ {
    mk_bp *bp;
    const struct mk_sweep *w;
    report_fn report;
} sweep_ctx_;

static uint32_t slot_at(const struct mk_sweep *w, int i) { return (uint32_t)(w->key[i] & 0xFFFFFFu); }
static uint32_t qlo_at(const struct mk_sweep *w, int i) { return (uint32_t)(w->key[i] >> 24) & MK_SWEEP_Q_MAX_; }

static inline mk_status test(const sweep_ctx_ *c, int i, int j)
{
    uint32_t a, b;
    if (!mk_bp_overlap_(&c->w->box[i], &c->w->box[j])) return MK_OK;
    a = slot_at(c->w, i);
    b = slot_at(c->w, j);
    if (mk_bp_both_static_(c->bp, a, b)) return MK_OK;
    return c->report(c->bp, a, b);
}

/* Pairs inside one row [s, e). */
static mk_status sweep_row(const sweep_ctx_ *c, int s, int e)
{
    int i, j;
    mk_status st;
    for (i = s; i < e; ++i) {
        uint32_t hi = c->w->qhi[i];
        for (j = i + 1; j < e && qlo_at(c->w, j) <= hi; ++j)
            if ((st = test(c, i, j)) != MK_OK) return st;
    }
    return MK_OK;
}

/* Pairs between rows [s, e) and [t, u): a merge of the two sorted runs;
 * whichever box starts first scans the other run for the boxes starting
 * before it ends. */
static mk_status sweep_rows(const sweep_ctx_ *c, int s, int e, int t, int u)
{
    const struct mk_sweep *w = c->w;
    mk_status st;
    int j;
    while (s < e && t < u) {
        if (qlo_at(w, s) <= qlo_at(w, t)) {
            uint32_t hi = w->qhi[s];
            for (j = t; j < u && qlo_at(w, j) <= hi; ++j)
                if ((st = test(c, s, j)) != MK_OK) return st;
            ++s;
        } else {
            uint32_t hi = w->qhi[t];
            for (j = s; j < e && qlo_at(w, j) <= hi; ++j)
                if ((st = test(c, j, t)) != MK_OK) return st;
            ++t;
        }
    }
    return MK_OK;
}

/* Boxes infinite on the row axis against everything: O(n) each. */
static mk_status sweep_big(const sweep_ctx_ *c, int n, int nbig)
{
    mk_bp *bp = c->bp;
    int i, j;
    mk_status st;
    for (i = 0; i < nbig; ++i) {
        uint32_t a = c->w->big[i];
        const mk_aabb *ba = &bp->box[a];
        for (j = 0; j < n; ++j) {
            uint32_t b = slot_at(c->w, j);
            if (!mk_bp_overlap_(ba, &c->w->box[j]) || mk_bp_both_static_(bp, a, b)) continue;
            if ((st = c->report(bp, a, b)) != MK_OK) return st;
        }
        for (j = i + 1; j < nbig; ++j) {
            uint32_t b = c->w->big[j];
            if (!mk_bp_overlap_(ba, &bp->box[b]) || mk_bp_both_static_(bp, a, b)) continue;
            if ((st = c->report(bp, a, b)) != MK_OK) return st;
        }
    }
    return MK_OK;
}

/* Keys of the boxes that fit a row, sorted; the big ones listed apart. */
static int sort_keys(mk_bp *bp, const frame_ *f, int *nbig)
{
    struct mk_sweep *w = bp->sweep;
    int n = 0, i;
    uint32_t s;
    *nbig = 0;
    for (s = 0; s < (uint32_t)bp->hi_slot; ++s) {
        const mk_aabb *b = &bp->box[s];
        if (!in_structure(bp, s)) continue;
        if (!(hi_of(b, f->ay) - lo_of(b, f->ay) <= MK_REAL_MAX)) { w->big[(*nbig)++] = s; continue; }
        w->key[n++] = (uint64_t)row_of(f, lo_of(b, f->ay)) << 40 | (uint64_t)quantise(f, lo_of(b, f->ax)) << 24 | s;
    }
    mk_sort_u64_by_(w->key, w->tmp, n, 3); /* the slot is payload: slot order breaks ties */
    for (i = 0; i < n; ++i) {
        const mk_aabb *b = &bp->box[slot_at(w, i)];
        w->box[i] = *b;
        w->qhi[i] = quantise(f, hi_of(b, f->ax));
    }
    return n;
}

mk_status mk_sweep_pairs_(mk_bp *bp, mk_status (*report)(mk_bp *bp, uint32_t a, uint32_t b))
{
    frame_ f;
    sweep_ctx_ c;
    int n, nbig, s, e;
    mk_status st;
    if (!bp->sweep && (st = sweep_create(bp)) != MK_OK) return st;
    plan(bp, &f);
    n = sort_keys(bp, &f, &nbig);
    bp->sweep->f = f;
    bp->sweep->n = n;
    bp->sweep->nbig = nbig;
    c.bp = bp; c.w = bp->sweep; c.report = report;
    for (s = 0; s < n; s = e) {
        uint64_t row = c.w->key[s] >> 40;
        int u;
        for (e = s + 1; e < n && c.w->key[e] >> 40 == row; ++e) {}
        if ((st = sweep_row(&c, s, e)) != MK_OK) return st;
        if (e == n || c.w->key[e] >> 40 != row + 1) continue;
        for (u = e + 1; u < n && c.w->key[u] >> 40 == row + 1; ++u) {}
        if ((st = sweep_rows(&c, s, e, e, u)) != MK_OK) return st;
    }
    return sweep_big(&c, n, nbig);
}

/* First index in [i, e) whose quantised lower end is above q (or, with
 * strict = 0, at least q): the sorted run [i, e) of one row. */
static int first_above(const struct mk_sweep *w, int i, int e, uint32_t q, int strict)
{
    while (i < e) {
        int mid = i + (e - i) / 2;
        uint32_t v = qlo_at(w, mid);
        if (strict ? v <= q : v < q) i = mid + 1;
        else e = mid;
    }
    return i;
}

/* The AABB tests a sweep of the current boxes would make, counted without
 * making them: one sort, then per box a binary search in its own row and in
 * the next one (the merge of two rows tests about the boxes of the next row
 * that start inside it, and vice versa). O(n log n), no pair is touched. */
mk_status mk_sweep_count_(mk_bp *bp, double *tests)
{
    frame_ f;
    struct mk_sweep *w;
    int n, nbig, s, e, u, i;
    double t = 0;
    mk_status st;
    if (!bp->sweep && (st = sweep_create(bp)) != MK_OK) return st;
    w = bp->sweep;
    plan(bp, &f);
    n = sort_keys(bp, &f, &nbig);
    w->n = 0; /* the arrays no longer describe a finished sweep */
    w->nbig = 0;
    for (s = 0; s < n; s = e) {
        uint64_t row = w->key[s] >> 40;
        for (e = s + 1; e < n && w->key[e] >> 40 == row; ++e) {}
        for (u = e; u < n && w->key[u] >> 40 == row + 1; ++u) {}
        for (i = s; i < e; ++i) {
            t += first_above(w, i + 1, e, w->qhi[i], 1) - (i + 1);
            if (u > e) t += first_above(w, e, u, w->qhi[i], 1) - first_above(w, e, u, qlo_at(w, i), 0);
        }
        for (i = e; i < u; ++i) t += first_above(w, s, e, w->qhi[i], 1) - first_above(w, s, e, qlo_at(w, i), 1);
    }
    *tests = t + (double)nbig * n;
    return MK_OK;
}

/* First sorted index in [i, n) whose row is at least `row`. */
static int row_start(const struct mk_sweep *w, int i, uint64_t row)
{
    int hi = w->n;
    while (i < hi) {
        int mid = i + (hi - i) / 2;
        if (w->key[mid] >> 40 < row) i = mid + 1;
        else hi = mid;
    }
    return i;
}

/* The rows that can hold a box overlapping q (a box starts at most h below
 * q.lo on the row axis), each scanned from its start while its boxes start
 * before q ends on the swept axis; then the big boxes. */
void mk_sweep_query_(const mk_bp *bp, mk_aabb q, mk_bp_query_fn fn, void *ctx)
{
    const struct mk_sweep *w = bp->sweep;
    const frame_ *f = &w->f;
    uint64_t row = row_of(f, lo_of(&q, f->ay) - f->h), last = row_of(f, hi_of(&q, f->ay));
    uint32_t qx = quantise(f, hi_of(&q, f->ax));
    int i = row_start(w, 0, row), j;
    while (i < w->n && w->key[i] >> 40 <= last) {
        row = w->key[i] >> 40;
        for (; i < w->n && w->key[i] >> 40 == row && qlo_at(w, i) <= qx; ++i) {
            uint32_t s = slot_at(w, i);
            if (mk_bp_overlap_(&w->box[i], &q) && !fn(ctx, mk_bp_id_of_(bp, s), bp->user[s])) return;
        }
        i = row_start(w, i, row + 1);
    }
    for (j = 0; j < w->nbig; ++j) {
        uint32_t s = w->big[j];
        if (mk_bp_overlap_(&bp->box[s], &q) && !fn(ctx, mk_bp_id_of_(bp, s), bp->user[s])) return;
    }
}

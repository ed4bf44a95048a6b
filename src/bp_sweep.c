/* bp_sweep.c: every overlapping pair from scratch, with no pairs kept between
 * calls: a sort and sweep in rows. It serves a pairs_only SAP's busy updates
 * (the proxies' boxes, statics among them, pairs reported to the pair
 * table, or kept as found for the set alone) and mk_bp_sweep_boxes (a
 * caller's array of boxes, the pairs handed out as found, with no proxies,
 * pair table or per-pair call at all).
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
 * radix sort orders them. Each box then scans the rest of its row, and the
 * row above from the first box starting at most wq before it (wq: the
 * widest box on the sweep axis, from a sample, unless that is over twice
 * the mean); the few boxes wider than wq scan the row below themselves
 * (sweep_rows, sweep_wide). The inner loops read row << 16 | q, so one
 * compare ends a scan at the box's end or at its row's end. The
 * quantisation is monotone, so comparing quantised values never stops a
 * sweep before a box it should have met; the exact closed test on the
 * AABBs decides. Boxes infinite on the row axis (ground planes) do not
 * fit a row: they are tested against every box, O(n) each.
 *
 * Without a branch on the test: in a dense heap about a third of the
 * tested pairs overlap, at random, and a branch per axis mispredicted on
 * most pairs kept. Into the pair array (no report, no statics) each tested
 * pair is written and kept by moving the end past it (test & 1). ODE's
 * stress heap replayed (ode_scenes --scene stress_space --backend minko,
 * session 10, alternated runs, load 6-8): frames 0-11 mean 20.4-24.0 ->
 * 13.9-17.2 ms per frame (3 runs); frames 30-99 (sparse, ~2 600 pairs)
 * median 0.81-0.98 -> 0.80-0.86 ms (5 runs), though callgrind counts 10 %
 * more instructions there (frames 60-64: 22.96 -> 25.43 M).
 * Not kept (session 10): the test as four SSE2 packed compares (lanes
 * {x, y} and {y, z} of each end): 17 % fewer sweep instructions in the
 * densest frames (821 -> 679 M over frames 0-2) and frames 0-11 about
 * 10 % faster, but the sparse frames 30-99 no faster (median 0.84-0.96
 * against 0.83-0.92 ms, 3 alternated runs, load 7), for a second,
 * platform-specific form of the test.
 * Not kept (session 11, ODE's running stress scene from a snapshot of step
 * 25, steps 25-99, rdtsc per phase, 4-5 alternated runs, load 8-14): the
 * merge of two rows picking the run that moves with masks instead of a
 * branch (callgrind's branch model: 1.03 M -> 0.74 M mispredicts over
 * steps 25-54, with the big boxes' test below also branch-free) measured
 * no faster (sweep 932-1214 against 964-1145 kcycles per step); the big
 * boxes' test without a branch adds ~13 instructions per box and saved
 * little: its branch mispredicted ~1 k times per step.
 * Session 12 (the same steps 25-99, the boxes of each mk_bp_sweep_boxes
 * call recorded and replayed alone, 5 repetitions, medians over 7
 * alternated runs, load 6-11): the look back instead of merging two rows
 * (the merge's choice mispredicted about every other box), the first box
 * of each scan tested without asking, and a half-space (ODE's ground
 * plane, one finite side) tested on that side alone without a branch
 * (with broadphase.c's cheaper box check) took the median call from
 * ~600-640 to ~550 us, though callgrind counts ~4 % more instructions
 * (3.61 -> 3.76 M per call) for 2.4 times fewer mispredicts in its branch
 * model (27.2 k -> 11.2 k per call). bench_broadphase's 10k scenes, SAP
 * sets (callgrind per update): uniform 14.4 -> 13.1 M, mixed 23.3 ->
 * 22.0 M, corridor 4.67 -> 4.57 M, wall 4.44 -> 4.40 M, teleport 14.5 ->
 * 13.2 M.
 * Not kept (session 12, same replay): the merge kept with the first box
 * tested without asking (328 M instructions over the 75 calls against
 * 286 M, no faster than the merge); a second box tested without asking,
 * or a third unasked step of the look back's start (no faster).
 * Why the insertion sort below is never taken there: the heap spreads
 * outwards ~0.25 m a step on each axis with rows 0.6 m tall, so ~40 % of
 * the boxes change rows every step (only ~255 inversions within rows).
 * Letting it run up to two movers per stayer (their radix sort merged in)
 * measured worse: 300 M against 292 M instructions over the 75 calls,
 * 1.21 M against 0.84 M mispredicts, median 682 against 593 us.
 *
 * Sweeps in a row (a pairs_only caller's busy frames) keep the plan (axes,
 * quantisation, rows; made with headroom) and start from the last sweep's
 * order, so a coherent scene needs an insertion sort, O(n), instead of the
 * radix sort (boxes that changed rows are sorted apart and merged in); a
 * plan is remade when it is old, when boxes crowd the ends of its ranges,
 * or when a box is taller than its rows (the one thing that would make it
 * wrong).
 *
 * Cost: O(n) keys, one insertion sort bounded to 4 moves per box (plus a
 * radix sort of the boxes that changed rows, at most about n / 8) or one
 * radix sort of n keys (counted as they are made, two or three scatter
 * passes), one pass placing the sorted boxes, and for each box the boxes
 * of its own row that start within it and of the row above that start
 * within it or up to wq before it; for each box wider than wq, a binary
 * search and the boxes of the row below that start within it. */
#include <math.h>
#include <string.h>

#include "broadphase_internal.h"

/* 16-bit quantised positions and row numbers, so that row << 16 | q fits
 * 32 bits; the last row is 0xFFFE, so that no such value reaches the
 * sentinel 0xFFFFFFFF that ends the last row's scans. */
#define MK_SWEEP_Q_MAX_ 0xFFFFu
#define MK_SWEEP_ROWS_ 0xFFFEu
#define MK_SWEEP_ROW_ 0x10000u     /* one row up, in row << 16 | q */
#define MK_SWEEP_END_ 0xFFFFFFFFu  /* rlo[n]: above every box's rhi */

/* The keys' 32 sort bits (row << 16 | q(lo), above 24 bits of slot) are
 * radix-sorted in three digits of 12, 12 and 8 bits, the first two counted
 * as the keys are made; a digit that every key shares costs nothing (a
 * scene spread over fewer than 256 rows: two passes). */
#define MK_SWEEP_HIST_ (4096 + 4096 + 256)

/* The frame of one sweep: axes, quantisation of the sweep axis, rows. */
typedef struct frame_ {
    int ax, ay, az;       /* sweep axis, row axis, the third one */
    double x0, xscale;    /* q(x) = floor((x - x0) * xscale), clamped */
    double y0, inv_h;     /* row(y) = floor((y - y0) * inv_h), clamped */
    double h;             /* row height: at least every box's extent on ay */
    uint32_t wq;          /* a box starts at most wq before the boxes of the row above it scans (in q) */
} frame_;

struct mk_sweep {
    uint64_t *key, *tmp;  /* sort keys: row << 40 | q(lo) << 24 | slot (scratch once sorted) */
    uint32_t *rlo, *rhi;  /* per sorted box: row << 16 | q(lo), row << 16 | q(hi) on the sweep axis (the
                             inner loops' reads: one compare ends a scan at q or at its row's end); rlo[n] = END */
    uint32_t *slot;       /* per sorted box: its slot */
    mk_aabb *box;         /* per sorted box: its AABB (sequential reads in the sweep) */
    uint32_t *big;        /* slots of boxes infinite on the row axis */
    uint32_t *wide;       /* sorted indices of the boxes wider than f.wq on the sweep axis */
    int cap;
    frame_ f;             /* of the last sweep, with its n sorted and nbig big boxes: */
    int n, nbig;          /* region queries after a stateless update read them */
    int kept;             /* f and key[0, n) may seed the next sweep of the same kind (KEPT_*; see sort_keys) */
    uint32_t src_n;       /* boxes of the caller's array in the last box sweep: later ones are new */
    mk_bp_pair *out;      /* overlapping pairs as found (slots or box indices, a < b) */
    int nout, outcap;
    int age;              /* sweeps since f was planned */
    int crowded;          /* the last sweep clamped many boxes to the ends of f's ranges */
    int sort_wait;        /* sweeps left before an insertion sort is tried again */
    int sort_backoff;     /* the next wait, doubled each time one gives up */
    uint32_t hist[MK_SWEEP_HIST_]; /* the radix sort's three histograms */
};

enum { KEPT_NONE = 0, KEPT_PROXIES, KEPT_BOXES };

/* The first size of the array of pairs a box sweep hands out. */
#define MK_SWEEP_OUT_ 1024

/* The per-box arrays of a sweep of capacity n (box, slot and wide have one
 * entry more, rlo two: sentinels for scans that test a box unasked). */
static size_t sweep_bytes(size_t n)
{
    return n * (2 * sizeof(uint64_t) + 5 * sizeof(uint32_t) + sizeof(mk_aabb)) + 4 * sizeof(uint32_t) + sizeof(mk_aabb);
}

static mk_status sweep_create(mk_bp *bp)
{
    struct mk_sweep *w;
    size_t n = (size_t)bp->cap;
    char *p;
    if (!(w = (struct mk_sweep *)mk_bp_alloc_(bp, sizeof *w))) return MK_ERR_OUT_OF_MEMORY;
    /* One block; the AABBs first for their alignment. */
    if (!(p = (char *)mk_bp_alloc_(bp, sweep_bytes(n)))) {
        mk_bp_free_(bp, w, sizeof *w);
        return MK_ERR_OUT_OF_MEMORY;
    }
    w->box = (mk_aabb *)p; p += (n + 1) * sizeof(mk_aabb);
    w->key = (uint64_t *)p; p += n * sizeof(uint64_t);
    w->tmp = (uint64_t *)p; p += n * sizeof(uint64_t);
    w->rlo = (uint32_t *)p; p += (n + 2) * sizeof(uint32_t);
    w->rhi = (uint32_t *)p; p += n * sizeof(uint32_t);
    w->slot = (uint32_t *)p; p += (n + 1) * sizeof(uint32_t);
    w->wide = (uint32_t *)p; p += (n + 1) * sizeof(uint32_t);
    w->big = (uint32_t *)p;
    w->cap = bp->cap;
    w->n = w->nbig = w->kept = w->age = w->crowded = w->sort_wait = w->sort_backoff = 0;
    w->src_n = 0;
    w->nout = 0;
    w->outcap = MK_SWEEP_OUT_;
    if (!(w->out = (mk_bp_pair *)mk_bp_alloc_(bp, (size_t)w->outcap * sizeof *w->out))) {
        mk_bp_free_(bp, w->box, sweep_bytes(n));
        mk_bp_free_(bp, w, sizeof *w);
        return MK_ERR_OUT_OF_MEMORY;
    }
    bp->sweep = w;
    return MK_OK;
}

void mk_sweep_destroy_(mk_bp *bp)
{
    struct mk_sweep *w = bp->sweep;
    if (!w) return;
    mk_bp_free_(bp, w->box, sweep_bytes((size_t)w->cap));
    mk_bp_free_(bp, w->out, (size_t)w->outcap * sizeof *w->out);
    mk_bp_free_(bp, w, sizeof *w);
    bp->sweep = NULL;
}


static int in_structure(const mk_bp *bp, uint32_t s)
{
    return (bp->flags[s] & (MK_PF_ALIVE | MK_PF_DYING)) == MK_PF_ALIVE;
}

/* Where one sweep reads its boxes: the proxies (box[] of the slots in the
 * structure, statics among them) or a caller's array (every box, none
 * static). Everything but the keys' order and the reporting is shared. */
typedef struct src_ {
    mk_bp *bp;
    int proxies;          /* 1: bp's proxies; 0: the caller's boxes */
    const char *base;     /* box of slot s at base + s * stride */
    size_t stride;
    uint32_t n;           /* slots [0, n) */
} src_;

static inline const mk_aabb *src_box(const src_ *v, uint32_t s)
{
    return (const mk_aabb *)(const void *)(v->base + s * v->stride);
}

static inline int src_in(const src_ *v, uint32_t s)
{
    return v->proxies ? in_structure(v->bp, s) : s < v->n;
}

static double lo_of(const mk_aabb *b, int axis) { return (double)(&b->lo.x)[axis]; }
static double hi_of(const mk_aabb *b, int axis) { return (double)(&b->hi.x)[axis]; }

/* The box with its axes in the order row, third, sweep: the sweep's copies
 * are kept so, and boxes tested against them are put so, since overlap
 * does not depend on the order of the axes while the test's cost does: it
 * stops at the first axis that separates, and the sweep axis, which the
 * scans have already matched (but for rounding), comes last. */
static inline mk_aabb permuted(const frame_ *f, const mk_aabb *b)
{
    const mk_real *lo = &b->lo.x, *hi = &b->hi.x;
    mk_aabb r;
    r.lo = mk_v3(lo[f->ay], lo[f->az], lo[f->ax]);
    r.hi = mk_v3(hi[f->ay], hi[f->az], hi[f->ax]);
    return r;
}

/* Infinite on the row axis: in no row. */
static int is_big(const frame_ *f, const mk_aabb *b) { return !(hi_of(b, f->ay) - lo_of(b, f->ay) <= MK_REAL_MAX); }

/* Monotone in x, so q(lo_b) > q(hi_a) implies lo_b > hi_a. */
static uint32_t quantise(const frame_ *f, double x)
{
    double t = (x - f->x0) * f->xscale;
    if (!(t > 0)) return 0;
    return t >= (double)MK_SWEEP_Q_MAX_ ? MK_SWEEP_Q_MAX_ : (uint32_t)t;
}

/* Rows beyond either end merge into the end row: slower, never wrong (a
 * box starts at most H below any box it overlaps, whatever row it is in). */
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

static void measure(const src_ *v, spread_ *p)
{
    uint32_t s, stride = v->n / MK_SWEEP_SAMPLE_ + 1;
    int k;
    memset(p, 0, sizeof *p);
    for (k = 0; k < 3; ++k) { p->lo[k] = HUGE_VAL; p->hi[k] = -HUGE_VAL; }
    for (s = 0; s < v->n; s += stride) {
        const mk_aabb *b = src_box(v, s);
        if (!src_in(v, s)) continue;
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
static double largest_extent(const src_ *v, int axis)
{
    double m = 0;
    uint32_t s;
    for (s = 0; s < v->n; ++s) {
        const mk_aabb *b = src_box(v, s);
        double e = hi_of(b, axis) - lo_of(b, axis);
        if (src_in(v, s) && e > m && e <= MK_REAL_MAX) m = e;
    }
    return m;
}

/* Ranges get a quarter of their width as headroom on each side, so that a
 * plan kept across sweeps (sort_keys) still spreads boxes that drift out
 * of the range it was made for (ODE's heap spreads over the plane). */
static void widen(double *lo, double *hi)
{
    double m = 0.25 * (*hi - *lo);
    if (!(m <= 1e300)) return; /* empty or overflowing: used as it is */
    *lo -= m;
    *hi += m;
}

/* The rows' look back, wq (see sweep_rows), from the quantised widths of
 * a sample of the boxes: each box pays about per_q * (wq - its width) tests
 * of boxes that start within wq before it but end before it (per_q boxes
 * per unit of q in a row), and each box wider than wq a scan of its own,
 * counted as 4 tests (2 let ODE's denser early heap make a fifth of its
 * boxes wide: +0.6 % instructions, +6 % mispredicts in callgrind); wq is
 * the sampled width with the least expected
 * cost. Boxes of one size: the widest (no waste, no wide box); ODE's
 * spread heap (sizes 1:6, sparse rows): the widest; sizes 1:100 in crowded
 * rows: smaller (wq = 0 would test the merge's pairs). O(m) (a radix
 * sort) for m <= ~1024 sampled boxes, once per plan. */
static uint32_t look_back(const src_ *v, const frame_ *f, double per_q, uint64_t *wbuf, uint64_t *scratch)
{
    uint32_t s, stride = v->n / MK_SWEEP_SAMPLE_ + 1, best = 0;
    double sum = 0, cost, least = HUGE_VAL;
    int m = 0, i;
    for (s = 0; s < v->n; s += stride) {
        const mk_aabb *b = src_box(v, s);
        if (src_in(v, s) && !is_big(f, b)) wbuf[m++] = quantise(f, hi_of(b, f->ax)) - quantise(f, lo_of(b, f->ax));
    }
    mk_sort_u64_by_(wbuf, scratch, m, 0);
    for (i = 0; i < m; ++i) {
        sum += (double)wbuf[i];
        cost = per_q * ((double)(i + 1) * (double)wbuf[i] - sum) + 4.0 * (m - 1 - i);
        if (cost < least) { least = cost; best = (uint32_t)wbuf[i]; }
    }
    return best;
}

static void plan(const src_ *v, frame_ *f, uint64_t *wbuf, uint64_t *scratch)
{
    spread_ p;
    double var[3], xlo, xhi, ylo, yhi, hmax;
    int k;
    measure(v, &p);
    for (k = 0; k < 3; ++k) var[k] = p.cnt[k] ? p.sum2[k] / p.cnt[k] - (p.sum[k] / p.cnt[k]) * (p.sum[k] / p.cnt[k]) : 0;
    f->ax = 0;
    for (k = 1; k < 3; ++k) if (var[k] > var[f->ax]) f->ax = k;
    f->ay = f->ax == 0 ? 1 : 0;
    for (k = 0; k < 3; ++k) if (k != f->ax && var[k] > var[f->ay]) f->ay = k;
    f->az = 3 - f->ax - f->ay;
    xlo = p.lo[f->ax]; xhi = p.hi[f->ax];
    ylo = p.lo[f->ay]; yhi = p.hi[f->ay];
    widen(&xlo, &xhi);
    widen(&ylo, &yhi);
    hmax = largest_extent(v, f->ay);
    f->x0 = xlo <= xhi ? xlo : 0;
    f->xscale = xhi > xlo ? (double)(MK_SWEEP_Q_MAX_ - 1) / (xhi - xlo) : 0;
    if (!(f->xscale <= 1e300)) f->xscale = 0;
    /* H a little above the largest extent: row numbers are computed in
     * double, so two rows apart must stay provably farther than any box.
     * At most MK_SWEEP_ROWS_ rows; rows beyond it merge into the last. */
    hmax *= 1.0 + 1.0 / 1024;
    if (hmax < (yhi - ylo) / (MK_SWEEP_ROWS_ - 2)) hmax = (yhi - ylo) / (MK_SWEEP_ROWS_ - 2);
    f->y0 = ylo <= yhi ? ylo - hmax : 0; /* row 0 is left to boxes below the range */
    f->h = hmax;
    f->inv_h = hmax > 0 ? 1.0 / hmax : 0;
    if (!(f->inv_h <= 1e300)) f->inv_h = 0; /* a subnormal height: one row */
    /* boxes per unit of q in one row, from the sampled ranges */
    {
        double area = (p.hi[f->ay] - p.lo[f->ay] + hmax) * (p.hi[f->ax] - p.lo[f->ax]) * f->xscale;
        double per_q = area > 0 && area <= 1e300 ? (double)v->n * hmax / area : 0;
        f->wq = look_back(v, f, per_q, wbuf, scratch);
    }
}

typedef mk_status (*report_fn)(mk_bp *bp, uint32_t a, uint32_t b);

typedef struct sweep_ctx_ {
    mk_bp *bp;
    const src_ *v;
    struct mk_sweep *w;
    report_fn report;     /* each pair goes there; NULL: pairs go to w->out, */
    mk_bp_pair *at, *end; /* at `at`, w->out's end at `end` (pointers: the pairs' stores cannot alias them) */
    int statics;          /* proxies, statics among them: static-static pairs are left out */
} sweep_ctx_;

/* w->out is full: double it, unless the caller fixed the capacity. */
static mk_status grow_out(sweep_ctx_ *c)
{
    struct mk_sweep *w = c->w;
    mk_bp *bp = c->bp;
    int cap;
    mk_status st;
    cap = w->outcap > INT32_MAX / 2 / (int)sizeof *w->out ? INT32_MAX : 2 * w->outcap;
    if (bp->def.fixed_capacity && cap > bp->pairs.cap) cap = bp->pairs.cap; /* the caller's bound */
    if (cap <= w->outcap) return MK_ERR_CAPACITY;
    if ((st = mk_bp_grow_(bp, (void **)&w->out, sizeof *w->out, (size_t)w->outcap, (size_t)cap)) != MK_OK) return st;
    c->at = w->out + w->outcap;
    c->end = w->out + cap;
    w->outcap = cap;
    return MK_OK;
}

/* An overlapping pair (no static-static pair): to the report, or into
 * w->out, with no call (a pairs_only SAP's set comes from there). */
static inline mk_status emit(sweep_ctx_ *c, uint32_t a, uint32_t b)
{
    mk_status st;
    if (c->statics && mk_bp_both_static_(c->bp, a, b)) return MK_OK;
    if (c->report) return c->report(c->bp, a, b);
    if (c->at == c->end && (st = grow_out(c)) != MK_OK) return st;
    c->at->a = a < b ? a : b;
    c->at->b = a < b ? b : a;
    c->at++;
    return MK_OK;
}

/* The sorted arrays the inner loops read, in locals: emit may call out,
 * and its stores could alias them, so nothing is reloaded through c. */
typedef struct rows_ { const uint32_t *rlo, *rhi, *slot; const mk_aabb *box; } rows_;

static rows_ rows_of(const struct mk_sweep *w)
{
    rows_ r;
    r.rlo = w->rlo; r.rhi = w->rhi; r.slot = w->slot; r.box = w->box;
    return r;
}

/* mk_bp_overlap_ without a branch (see the header): 10.7 M tests for
 * 3.3 M pairs in the densest frame of ODE's stress heap. */
static inline int overlaps(const mk_aabb *a, const mk_aabb *b)
{
    return (a->lo.x <= b->hi.x) & (b->lo.x <= a->hi.x) & (a->lo.y <= b->hi.y) & (b->lo.y <= a->hi.y) &
           (a->lo.z <= b->hi.z) & (b->lo.z <= a->hi.z);
}

/* One tested pair into w->out at *at, kept (*at moved past it) if hit:
 * no branch on the test. The array grows, at its end, only for a pair
 * kept. */
static MK_INLINE mk_status put(sweep_ctx_ *c, mk_bp_pair **at, mk_bp_pair **end, uint32_t sa, uint32_t sb, int hit)
{
    mk_status st;
    if (*at == *end) {
        if (!hit) return MK_OK;
        c->at = *at;
        if ((st = grow_out(c)) != MK_OK) return st;
        *at = c->at;
        *end = c->end;
    }
    (*at)->a = sa < sb ? sa : sb;
    (*at)->b = sa < sb ? sb : sa;
    *at += hit;
    return MK_OK;
}

/* Box a (slot sa) against the sorted boxes from j on while their rlo is
 * at most hi (a's end on the sweep axis, moved to the row scanned; a row's
 * end or the sentinel stops it). With `fast` (no report, no statics: the
 * pairs go to w->out at *at) the first box is tested without asking (most
 * scans of a sparse scene meet none or one, and asking mispredicts), the
 * others in a loop; rlo[j + 1] >= rlo[j] (the second sentinel) ends it. */
static MK_INLINE mk_status scan(sweep_ctx_ *c, const rows_ r, const mk_aabb *a, uint32_t sa, int j, uint32_t hi,
                                mk_bp_pair **at, mk_bp_pair **end, int fast)
{
    mk_status st;
    if (!fast) {
        for (; r.rlo[j] <= hi; ++j)
            if (mk_bp_overlap_(a, &r.box[j]) && (st = emit(c, sa, r.slot[j])) != MK_OK) return st;
        return MK_OK;
    }
    if ((st = put(c, at, end, sa, r.slot[j], (r.rlo[j] <= hi) & overlaps(a, &r.box[j]))) != MK_OK) return st;
    for (++j; r.rlo[j] <= hi; ++j)
        if ((st = put(c, at, end, sa, r.slot[j], overlaps(a, &r.box[j]))) != MK_OK) return st;
    return MK_OK;
}

/* Pairs inside row [s, e) and between it and the row above, [e, u) (none
 * when u == e): each box scans the rest of its row, and the row above from
 * the first box starting at most wq before it; then each box of the row
 * above wider than wq (w->wide from *wi on) scans this row from the first
 * box starting over wq after it. A pair across the rows is tested once:
 * by the lower box if the upper one starts at most wq before it, else by
 * the upper one, which then reaches over wq. Both starts only move
 * forward, the look back's mostly by 0 to 2 boxes: two steps without a
 * branch. With wq = 0 the tests are the merge's of the two rows; a larger
 * wq spares the wide boxes' scans for tests of boxes that start within wq
 * but end before (see look_back).
 * Not a merge of the two rows any more (session 12): choosing the run that
 * moves mispredicted about every other box (see the header). */
static MK_INLINE mk_status sweep_rows(sweep_ctx_ *c, int s, int e, int u, int *wi, int fast)
{
    const rows_ r = rows_of(c->w);
    const uint32_t wq = c->w->f.wq, back = MK_SWEEP_ROW_ - wq, *wide = c->w->wide;
    mk_bp_pair *at = c->at, *end = c->end;
    int i, p = e, q = s;
    mk_status st = MK_OK;
    for (i = s; i < e; ++i) {
        const uint32_t from = r.rlo[i] + back, hi = r.rhi[i], sa = r.slot[i];
        const mk_aabb a = r.box[i];
        if ((st = scan(c, r, &a, sa, i + 1, hi, &at, &end, fast)) != MK_OK) goto out;
        if (u == e) continue;
        p += r.rlo[p] < from;
        p += r.rlo[p] < from;
        while (r.rlo[p] < from) ++p;
        if ((st = scan(c, r, &a, sa, p, hi + MK_SWEEP_ROW_, &at, &end, fast)) != MK_OK) goto out;
    }
    while ((int)wide[*wi] < e) ++*wi; /* wide boxes with no row below, or of this row */
    for (; (int)wide[*wi] < u; ++*wi) {
        const int k = (int)wide[*wi];
        /* the row below's boxes starting at most wq after k (q(lo) + wq past the row: all of them) */
        const uint32_t lo = r.rlo[k] - MK_SWEEP_ROW_, last = (r.rlo[k] & MK_SWEEP_Q_MAX_) + wq > MK_SWEEP_Q_MAX_ ? lo | MK_SWEEP_Q_MAX_ : lo + wq;
        const mk_aabb a = r.box[k];
        while (r.rlo[q] <= last) ++q;
        if ((st = scan(c, r, &a, r.slot[k], q, r.rhi[k] - MK_SWEEP_ROW_, &at, &end, fast)) != MK_OK) goto out;
    }
out:
    if (fast) c->at = at; /* else emit moved c->at */
    return st;
}

/* Sorted boxes [0, n) against one big box pa (slot a): into w->out (no
 * report, no statics) without a branch on the test, each box's pair
 * written and kept by moving the end past it, as in scan: a ground plane
 * of ODE's heap overlaps a third of the boxes, in no order a branch could
 * learn. Only the big box's finite sides can fail, and a half-space (one
 * finite side: an axis-aligned plane) is tested on that side alone, as
 * s * (the box's coordinate) <= bound, s = -1 for a lower side. */
static mk_status big_all(sweep_ctx_ *c, const mk_aabb *pa, uint32_t a, int n)
{
    const mk_aabb *box = c->w->box;
    const uint32_t *slot = c->w->slot;
    const mk_real *plo = &pa->lo.x, *phi = &pa->hi.x;
    mk_bp_pair *at = c->at, *end = c->end;
    mk_real s = 1, bound = 0;
    int j, k, off = 0, sides = 0;
    mk_status st;
    for (k = 0; k < 3; ++k) {
        if (plo[k] >= -MK_REAL_MAX) { sides++; off = 3 + k; s = -1; bound = -plo[k]; } /* the box's hi[k] */
        if (phi[k] <= MK_REAL_MAX) { sides++; off = k; s = 1; bound = phi[k]; }       /* the box's lo[k] */
    }
    for (j = 0; j < n; ++j) {
        const uint32_t sb = slot[j];
        const int hit = sides == 1 ? s * (&box[j].lo.x)[off] <= bound : overlaps(pa, &box[j]);
        if (at == end) { /* full: grown only for a pair that overlaps */
            if (!hit) continue;
            c->at = at;
            if ((st = grow_out(c)) != MK_OK) return st;
            at = c->at;
            end = c->end;
        }
        at->a = a < sb ? a : sb;
        at->b = a < sb ? sb : a;
        at += hit;
    }
    c->at = at;
    return MK_OK;
}

/* Boxes infinite on the row axis against everything: O(n) each. */
static mk_status sweep_big(sweep_ctx_ *c, int n, int nbig)
{
    const struct mk_sweep *w = c->w;
    int i, j;
    mk_status st;
    for (i = 0; i < nbig; ++i) {
        uint32_t a = w->big[i];
        const mk_aabb *ba = src_box(c->v, a);
        const mk_aabb pa = permuted(&w->f, ba);
        if (!c->report && !c->statics) {
            if ((st = big_all(c, &pa, a, n)) != MK_OK) return st;
        } else {
            for (j = 0; j < n; ++j)
                if (mk_bp_overlap_(&pa, &w->box[j]) && (st = emit(c, a, w->slot[j])) != MK_OK) return st;
        }
        for (j = i + 1; j < nbig; ++j)
            if (mk_bp_overlap_(ba, src_box(c->v, w->big[j])) && (st = emit(c, a, w->big[j])) != MK_OK) return st;
    }
    return MK_OK;
}

/* ---- keys ---- */


/* The digits of the radix sort: shift in the key, size, offset in hist. */
static const struct { int shift; uint32_t size, off; } DIGIT_[3] = {{24, 4096, 0}, {36, 4096, 4096}, {48, 256, 8192}};

static inline uint32_t digit(uint64_t k, int d) { return (uint32_t)(k >> DIGIT_[d].shift) & (DIGIT_[d].size - 1); }

/* What one sort of keys learnt about the plan it used, and what the key
 * pass in slot order (keys_by_slot) counts for the radix sort as it goes. */
typedef struct keying_ {
    int tall;     /* a box taller than the rows: the plan is wrong, not just slow */
    int counted;  /* hist holds digits 0 and 1 of the keys, */
    uint64_t any, all; /* and these their OR and AND (digit 2 differs only where any ^ all does) */
} keying_;

static inline uint64_t key_of(const frame_ *f, const mk_aabb *b, uint32_t slot, keying_ *k)
{
    double ylo = lo_of(b, f->ay);
    uint32_t row = row_of(f, ylo), q = quantise(f, lo_of(b, f->ax));
    k->tall |= !((hi_of(b, f->ay) - ylo) * (1.0 + 1.0 / 1024) <= f->h);
    return (uint64_t)row << 40 | (uint64_t)q << 24 | slot;
}

/* Slot s in key order (`key`) or in the big list, with its key made now. */
static inline void file_box(struct mk_sweep *w, const src_ *v, uint32_t s, uint64_t *key, int *n, int *nb, keying_ *k)
{
    const mk_aabb *b = src_box(v, s);
    if (is_big(&w->f, b)) w->big[(*nb)++] = s;
    else key[(*n)++] = key_of(&w->f, b, s, k);
}

/* Every box in the source, in slot order: keys (counted for the radix
 * sort), and the big ones apart. */
static int keys_by_slot(struct mk_sweep *w, const src_ *v, int *nbig, keying_ *k)
{
    /* Locals: the stores to key[] could alias anything read through pointers. */
    const frame_ f = w->f;
    const src_ src = *v;
    uint64_t *key = w->key;
    uint32_t *big = w->big, s;
    uint32_t *h = w->hist;
    uint64_t any = 0, all = ~(uint64_t)0;
    keying_ kk = *k;
    int n = 0, nb = 0;
    memset(h, 0, DIGIT_[2].off * sizeof *h);
    for (s = 0; s < src.n; ++s) {
        const mk_aabb *b = src_box(&src, s);
        uint64_t kb;
        if (!src_in(&src, s)) continue;
        if (is_big(&f, b)) {
            big[nb++] = s;
            continue;
        }
        key[n++] = kb = key_of(&f, b, s, &kk);
        h[digit(kb, 0)]++;
        h[DIGIT_[1].off + digit(kb, 1)]++;
        any |= kb;
        all &= kb;
    }
    kk.counted = 1;
    kk.any = any;
    kk.all = all;
    *k = kk;
    *nbig = nb;
    return n;
}

/* The same keys in the order of the last sweep (slot[0, w->n) and the big
 * list of the last sweep): with a coherent scene and the same plan they
 * come out nearly sorted, into key[0, returned count). The last sweep's
 * boxes are the ones in the source now but for those added since: proxies
 * created since the last update (flag NEW in the dirty list), or the
 * caller's boxes past the last count. Those, any that stopped being big,
 * and the boxes that changed rows go to tmp[0, *extra) instead: a box that
 * changed rows is a row's length away from its place in the order (boxes
 * lined up in a corridor cross the row line every frame), so sorting it
 * apart and merging it in is cheaper than moving it there one place at a
 * time. */
static int keys_in_last_order(struct mk_sweep *w, const src_ *v, int *nbig, int *extra_out, keying_ *k)
{
    mk_bp *bp = v->bp;
    int n = 0, extra = 0, i, nb = 0;
    uint32_t s;
    for (i = 0; i < w->nbig; ++i)
        if (src_in(v, w->big[i])) file_box(w, v, w->big[i], w->tmp, &extra, &nb, k);
    if (v->proxies) {
        for (i = 0; i < bp->dirty_count; ++i)
            if ((bp->flags[bp->dirty[i]] & MK_PF_NEW) && src_in(v, bp->dirty[i])) file_box(w, v, bp->dirty[i], w->tmp, &extra, &nb, k);
    } else {
        for (s = w->src_n; s < v->n; ++s) file_box(w, v, s, w->tmp, &extra, &nb, k);
    }
    for (i = 0; i < w->n; ++i) {
        const mk_aabb *b;
        uint64_t key;
        s = w->slot[i];
        if (!src_in(v, s)) continue;
        b = src_box(v, s);
        if (is_big(&w->f, b)) { w->big[nb++] = s; continue; }
        key = key_of(&w->f, b, s, k);
        if ((uint32_t)(key >> 40) != w->rlo[i] >> 16) w->tmp[extra++] = key; /* another row */
        else w->key[n++] = key;
    }
    *nbig = nb;
    *extra_out = extra;
    return n;
}

/* key[0, n) sorted, tmp[0, m) not, n + m keys of room in key: all of them
 * sorted into key. The radix sort of tmp borrows key[n, n + m) as scratch;
 * the merge runs from the back, so it never overwrites a key not yet read. */
static void merge_in(uint64_t *key, int n, uint64_t *tmp, int m)
{
    int i = n - 1, j = m - 1, o = n + m - 1;
    mk_sort_u64_by_(tmp, key + n, m, 3);
    while (j >= 0) key[o--] = i >= 0 && key[i] > tmp[j] ? key[i--] : tmp[j--];
}

/* Insertion sort that gives up once it has moved keys `budget` places
 * (the keys are then still all there, in some order): O(n + inversions). */
static int insertion_sort(uint64_t *key, int n, long budget)
{
    int i, j;
    for (i = 1; i < n; ++i) {
        uint64_t v = key[i];
        if (key[i - 1] <= v) continue;
        for (j = i; j > 0 && key[j - 1] > v; --j) key[j] = key[j - 1];
        key[j] = v;
        if ((budget -= i - j) < 0) return 0;
    }
    return 1;
}

/* Plans older than this are remade: the axis of largest spread may have changed. */
#define MK_SWEEP_PLAN_AGE_ 64
/* Longest wait between insertion sorts that gave up (boxes changing rows
 * every frame, as in ODE's exploding heap, make the order incoherent). */
#define MK_SWEEP_MAX_SORT_WAIT_ 32

/* After an insertion sort gave up, the next ones wait (doubling waits). */
static void insertion_gave_up(struct mk_sweep *w)
{
    w->sort_backoff = w->sort_backoff ? 2 * w->sort_backoff : 1;
    if (w->sort_backoff > MK_SWEEP_MAX_SORT_WAIT_) w->sort_backoff = MK_SWEEP_MAX_SORT_WAIT_;
    w->sort_wait = w->sort_backoff;
}

/* The arrays the sweep reads, with the frame and the source in locals:
 * the stores to the arrays could alias them, and make every box reload
 * them. */
typedef struct placing_ {
    frame_ f;
    src_ v;
    mk_aabb *box;
    uint32_t *slot, *rlo, *rhi;
} placing_;

static placing_ placing_of(const struct mk_sweep *w, const src_ *v)
{
    placing_ pl;
    pl.f = w->f;
    pl.v = *v;
    pl.box = w->box; pl.slot = w->slot; pl.rlo = w->rlo; pl.rhi = w->rhi;
    return pl;
}

/* Sorted box p is the box of key k. */
static inline void place(const placing_ *pl, int p, uint64_t k)
{
    uint32_t s = (uint32_t)(k & 0xFFFFFFu), lo = (uint32_t)(k >> 24);
    const mk_aabb *b = src_box(&pl->v, s);
    pl->box[p] = permuted(&pl->f, b);
    pl->slot[p] = s;
    pl->rlo[p] = lo;
    pl->rhi[p] = (lo & ~MK_SWEEP_Q_MAX_) | quantise(&pl->f, hi_of(b, pl->f.ax));
}

/* Histograms of digits 0 and 1 (unless the key pass counted them) and of
 * digit 2 when keys differ in it (rows 256 and up, rare); returns the
 * digits some keys differ in (in `need`, lowest first), each histogram
 * turned into bucket starts. */
static int radix_plan(uint32_t *h, const uint64_t *key, int n, keying_ k, int *need)
{
    int i, d, m = 0;
    if (n == 0) return 0;
    if (!k.counted) {
        memset(h, 0, DIGIT_[2].off * sizeof *h);
        for (i = 0; i < n; ++i) {
            h[digit(key[i], 0)]++;
            h[DIGIT_[1].off + digit(key[i], 1)]++;
            k.any |= key[i];
            k.all &= key[i];
        }
    }
    if (digit(k.any ^ k.all, 2)) {
        memset(h + DIGIT_[2].off, 0, DIGIT_[2].size * sizeof *h);
        for (i = 0; i < n; ++i) h[DIGIT_[2].off + digit(key[i], 2)]++;
    }
    for (d = 0; d < 3; ++d) {
        uint32_t *c = h + DIGIT_[d].off, sum = 0, b;
        if (!digit(k.any ^ k.all, d)) continue; /* the same in every key */
        for (b = 0; b < DIGIT_[d].size; ++b) { uint32_t t = c[b]; c[b] = sum; sum += t; }
        need[m++] = d;
    }
    return m;
}

/* Stable LSD radix sort of key[0, n) by their sort bits; returns where
 * the sorted keys are (key or tmp). The boxes are placed by a pass of
 * their own, in order: a last scatter pass writing the sweep's arrays
 * directly (a permuted box, slot, rlo and rhi per key, each store to
 * another of up to 4096 buckets) missed the cache on every store: in
 * ODE's running stress scene (steps 25-99, rdtsc, 5 alternated runs, load
 * 9-11) keys, sort and placing took 747-1154 kcycles per step that way and
 * 423-597 with the placing pass in order. */
static const uint64_t *radix_sort(struct mk_sweep *w, int n, keying_ k)
{
    uint64_t *src = w->key, *dst = w->tmp, *sw;
    int need[3], m = radix_plan(w->hist, w->key, n, k, need), p, i;
    for (p = 0; p < m; ++p) {
        int d = need[p];
        uint32_t *c = w->hist + DIGIT_[d].off;
        for (i = 0; i < n; ++i) dst[c[digit(src[i], d)]++] = src[i];
        sw = src; src = dst; dst = sw;
    }
    return src;
}

/* Boxes beyond the plan's ranges land in row 0 or the last row, at q = 0
 * or the largest q (the plan's headroom keeps the others off them): too
 * many there (over 1/16) and the plan is remade. Only a hint, so a sample
 * of at most about 1024 of the sorted boxes decides. */
static int crowded(const struct mk_sweep *w, int n)
{
    int i, stride = n / MK_SWEEP_SAMPLE_ + 1, c = 0;
    for (i = 0; i < n; i += stride) {
        uint32_t row = w->rlo[i] >> 16, q = w->rlo[i] & MK_SWEEP_Q_MAX_;
        c += (row - 1u >= MK_SWEEP_ROWS_ - 1u) | (q - 1u >= MK_SWEEP_Q_MAX_ - 1u);
    }
    return c * stride > n / 16 + 16;
}

/* Sorted keys of the boxes that fit a row, the big ones listed apart, and
 * the per-box arrays the sweep reads. A sweep right after another one of
 * the same source (`reuse`) keeps its plan, unless it is old or boxes
 * crowded the ends of its ranges, and starts from its order: an insertion
 * sort, O(n) on a coherent scene, with a radix sort past 4 moves per box
 * (and for a while after one gave up). Any plan is correct as long as no
 * box is taller than its rows; one that meets such a box is remade. */
static int sort_keys(struct mk_sweep *w, const src_ *v, int reuse, int *nbig)
{
    frame_ *f = &w->f;
    keying_ k = {0, 0, 0, ~(uint64_t)0};
    int n = 0, i, sorted = 0, keep = reuse && !w->crowded && w->age < MK_SWEEP_PLAN_AGE_;
    if (keep && w->sort_wait == 0) {
        int m;
        n = keys_in_last_order(w, v, nbig, &m, &k);
        /* past an eighth of the boxes apart, the scene is not coherent */
        if (!k.tall && !(sorted = m <= n / 8 + 64 && insertion_sort(w->key, n, 4L * n + 64))) insertion_gave_up(w);
        if (sorted) {
            merge_in(w->key, n, w->tmp, m);
            w->sort_backoff = 0;
        } else {
            memcpy(w->key + n, w->tmp, (size_t)m * sizeof *w->key);
        }
        n += m;
    } else if (keep) { /* the plan without the order: keys in slot order, sequential reads */
        w->sort_wait--;
        n = keys_by_slot(w, v, nbig, &k);
    }
    if (!keep || k.tall) {
        plan(v, f, w->tmp, w->key); /* both free until the keys are made */
        k.tall = 0;
        n = keys_by_slot(w, v, nbig, &k);
        w->age = 0;
    }
    w->age++;
    {
        /* the slot is payload: input order breaks ties */
        const uint64_t *key = sorted ? w->key : radix_sort(w, n, k);
        const placing_ pl = placing_of(w, v);
        uint32_t *wide = w->wide, wq = f->wq;
        int nw = 0;
        for (i = 0; i < n; ++i) {
            place(&pl, i, key[i]);
            wide[nw] = (uint32_t)i;
            nw += pl.rhi[i] - pl.rlo[i] > wq;
        }
        wide[nw] = (uint32_t)n + 1; /* ends the walks over them */
    }
    /* what scans read past the last box: never a pair */
    w->rlo[n] = w->rlo[n + 1] = MK_SWEEP_END_;
    memset(&w->box[n], 0, sizeof w->box[n]);
    w->slot[n] = 0;
    w->crowded = crowded(w, n);
    return n;
}

static uint32_t row_at(const struct mk_sweep *w, int i) { return w->rlo[i] >> 16; }

/* The end of the row that starts at i (n when i == n: the sentinel's row
 * is no box's). */
static int row_end(const struct mk_sweep *w, int i, int n)
{
    uint32_t row;
    if (i == n) return n;
    row = row_at(w, i);
    for (++i; row_at(w, i) == row; ++i) {}
    return i;
}

/* First index in [i, e) whose rlo is above q (or, with strict = 0, at
 * least q): the sorted run [i, e) of one row, q in that row. */
static int first_above(const struct mk_sweep *w, int i, int e, uint32_t q, int strict)
{
    while (i < e) {
        int mid = i + (e - i) / 2;
        uint32_t v = w->rlo[mid];
        if (strict ? v <= q : v < q) i = mid + 1;
        else e = mid;
    }
    return i;
}

/* First sorted index in [i, n) whose row is at least `row`. */
static int row_start(const struct mk_sweep *w, int i, uint32_t row)
{
    int hi = w->n;
    while (i < hi) {
        int mid = i + (hi - i) / 2;
        if (row_at(w, mid) < row) i = mid + 1;
        else hi = mid;
    }
    return i;
}

/* Each row alone and with the next one. */
static MK_INLINE mk_status sweep_grid(sweep_ctx_ *c, int n, int fast)
{
    const struct mk_sweep *w = c->w;
    int s, e, u, wi = 0;
    mk_status st;
    for (s = 0, e = row_end(w, 0, n); s < n; s = e, e = u) {
        u = row_end(w, e, n);
        if ((st = sweep_rows(c, s, e, e < n && row_at(w, e) == row_at(w, s) + 1 ? u : e, &wi, fast)) != MK_OK) return st;
    }
    return MK_OK;
}

/* The pairs of the sorted boxes, then the big boxes. */
static mk_status sweep_all(sweep_ctx_ *c, int n, int nbig)
{
    mk_status st = !c->report && !c->statics ? sweep_grid(c, n, 1) : sweep_grid(c, n, 0);
    return st != MK_OK ? st : sweep_big(c, n, nbig);
}

/* One sweep of the source's boxes, kept (KEPT_*) for the next sweep of the
 * same kind; the pairs go to c->report or stay in w->out. */
static mk_status run(sweep_ctx_ *c, int kind, int reuse)
{
    struct mk_sweep *w = c->w;
    int n, nbig;
    mk_status st;
    n = sort_keys(w, c->v, reuse && w->kept == kind, &nbig);
    w->n = n;
    w->nbig = nbig;
    w->src_n = c->v->n;
    c->at = w->out;
    c->end = w->out + w->outcap;
    st = sweep_all(c, n, nbig);
    w->nout = (int)(c->at - w->out);
    w->kept = st == MK_OK ? kind : KEPT_NONE;
    return st;
}

static mk_status ensure(mk_bp *bp)
{
    return bp->sweep ? MK_OK : sweep_create(bp);
}

static src_ proxies_of(mk_bp *bp)
{
    src_ v;
    v.bp = bp;
    v.proxies = 1;
    v.base = (const char *)bp->box;
    v.stride = sizeof *bp->box;
    v.n = (uint32_t)bp->hi_slot;
    return v;
}

mk_status mk_sweep_pairs_(mk_bp *bp, mk_status (*report)(mk_bp *bp, uint32_t a, uint32_t b))
{
    sweep_ctx_ c;
    src_ v;
    mk_status st;
    if ((st = ensure(bp)) != MK_OK) return st;
    v = proxies_of(bp);
    c.bp = bp; c.v = &v; c.w = bp->sweep; c.report = report; c.statics = bp->statics > 0;
    /* The arrays describe the last sweep only if the last update was one. */
    return run(&c, KEPT_PROXIES, bp->swept);
}

const mk_bp_pair *mk_sweep_found_(const mk_bp *bp, int *count)
{
    *count = bp->sweep->nout;
    return bp->sweep->out;
}

mk_status mk_sweep_boxes_(mk_bp *bp, const mk_aabb *boxes, size_t stride, int n, const mk_bp_pair **pairs, int *count)
{
    sweep_ctx_ c;
    src_ v;
    mk_status st;
    *pairs = NULL;
    *count = 0;
    if ((st = ensure(bp)) != MK_OK) return st;
    v.bp = bp;
    v.proxies = 0;
    v.base = (const char *)boxes;
    v.stride = stride;
    v.n = (uint32_t)n;
    c.bp = bp; c.v = &v; c.w = bp->sweep; c.report = NULL; c.statics = 0;
    if ((st = run(&c, KEPT_BOXES, 1)) != MK_OK) return st;
    *pairs = c.w->out;
    *count = c.w->nout;
    return MK_OK;
}

/* The AABB tests a sweep of the current boxes would make, counted without
 * making them: one sort, then per box a binary search in its own row and in
 * the next one (its look back and the wide boxes' scans down, as in
 * sweep_rows and sweep_wide). O(n log n), no pair is touched. */
mk_status mk_sweep_count_(mk_bp *bp, double *tests)
{
    struct mk_sweep *w;
    int n, nbig, s, e, u, i;
    double t = 0;
    src_ v;
    mk_status st;
    if ((st = ensure(bp)) != MK_OK) return st;
    w = bp->sweep;
    v = proxies_of(bp);
    n = sort_keys(w, &v, 0, &nbig);
    w->n = 0; /* the arrays no longer describe a finished sweep */
    w->nbig = 0;
    w->kept = KEPT_NONE;
    for (s = 0; s < n; s = e) {
        e = row_end(w, s, n);
        for (u = e; u < n && row_at(w, u) == row_at(w, s) + 1; ++u) {}
        for (i = s; i < e; ++i) {
            t += first_above(w, i + 1, e, w->rhi[i], 1) - (i + 1);
            if (u > e)
                t += first_above(w, e, u, w->rhi[i] + MK_SWEEP_ROW_, 1) -
                     first_above(w, e, u, w->rlo[i] + MK_SWEEP_ROW_ - w->f.wq, 0);
        }
        for (i = e; i < u; ++i)
            if (w->rhi[i] - w->rlo[i] > w->f.wq)
                t += first_above(w, s, e, w->rhi[i] - MK_SWEEP_ROW_, 1) -
                     first_above(w, s, e, w->rlo[i] - MK_SWEEP_ROW_ + w->f.wq, 1);
    }
    *tests = t + (double)nbig * n;
    return MK_OK;
}

/* The rows that can hold a box overlapping q (a box starts at most h below
 * q.lo on the row axis), each scanned from its start while its boxes start
 * before q ends on the swept axis; then the big boxes. */
void mk_sweep_query_(const mk_bp *bp, mk_aabb q, mk_bp_query_fn fn, void *ctx)
{
    const struct mk_sweep *w = bp->sweep;
    const frame_ *f = &w->f;
    uint32_t row = row_of(f, lo_of(&q, f->ay) - f->h), last = row_of(f, hi_of(&q, f->ay));
    uint32_t qx = quantise(f, hi_of(&q, f->ax));
    const mk_aabb pq = permuted(f, &q);
    int i = row_start(w, 0, row), j;
    while (i < w->n && row_at(w, i) <= last) {
        row = row_at(w, i);
        for (; w->rlo[i] <= (row << 16 | qx); ++i) { /* the row's end or the sentinel stops it */
            uint32_t s = w->slot[i];
            if (mk_bp_overlap_(&w->box[i], &pq) && !fn(ctx, mk_bp_id_of_(bp, s), bp->user[s])) return;
        }
        i = row_start(w, i, row + 1);
    }
    for (j = 0; j < w->nbig; ++j) {
        uint32_t s = w->big[j];
        if (mk_bp_overlap_(&bp->box[s], &q) && !fn(ctx, mk_bp_id_of_(bp, s), bp->user[s])) return;
    }
}

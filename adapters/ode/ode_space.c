/* ode_space.c: mk_ode_space_collide and mk_ode_space_collide2 (minko_ode.h).
 *
 * ODE has no public interface for custom spaces, so the adapter replaces the
 * *call*: it reads the space's geoms through the public API, keeps one
 * record per geom (keyed by dGeomID) and one Minko broadphase per space, and
 * reproduces the filter of ODE's collideAABBs (collision_space_internal.h)
 * on each pair the broadphase finds. With mk_real = dReal the sweep's boxes
 * are ODE's AABBs, copied once, and its closed test is ODE's; otherwise (a
 * float build, or a box the sweep refuses) its boxes are ODE's rounded
 * outwards, it only proposes pairs, and the final overlap test runs on
 * ODE's own dReal AABBs: the reported set is ODE's exactly either way.
 *
 * Why the per-geom work is so small:
 *  - every call reads every geom's AABB anyway (ODE has no move notice), so
 *    the broadphase is Minko's set-only sweep of the records' boxes
 *    (mk_bp_sweep_boxes): no proxies to move, no pair set to keep, each
 *    pair written once, and the sweep starts from the last call's order;
 *  - records are dense, the i-th record's box is the sweep's box i, so a
 *    pair is two record indices, with no call per pair;
 *  - ODE keeps a space's list order unless a clean geom is dirtied, and geoms
 *    in a space only the adapter collides stay dirty, so the order of the
 *    previous call usually finds each geom's record without hashing;
 *  - the filter fields (enabled, zero size, body, category and collide bits)
 *    are read in the same walk, right after the AABB: dGeomGetAABB has just
 *    brought the geom's cache lines in, so the six getters cost
 *    instructions, not misses, and the pair loop then reads records, not
 *    geoms. A geom that is disabled or zero-sized gets category and collide
 *    bits 0 in its record, which no filter passes: it stays in the
 *    broadphase and is filtered out of its pairs, the same set as skipping
 *    it. (Until session 11 they were read lazily in the pair loop, for the
 *    ~27 % of geoms in a candidate pair: fewer instructions, but each was a
 *    miss the prefetch did not hide. Moved here, the running stress heap's
 *    pair loop went from 0.35-0.69 to 0.10-0.22 ms per call and the walk
 *    did not slow down (0.58-0.66 -> 0.44-0.60 ms; steps 25-99, per-call
 *    timers, 7 and 19 runs, load 8-12), although the call runs 8 % more
 *    instructions: 5.66 -> 6.14 M per call, callgrind.)
 *
 * Why not a persistent incremental structure (fat boxes in an mk_bp, moved
 * only when a geom leaves its box; session 9 built one, measured it and
 * did not keep it): in ODE's stress heap, the scene the target is set on,
 * the spheres roll apart for the whole run and move more than their own
 * size per step (median 0.36-0.51 m per 0.05 s step; 96-100 % of them over
 * 3 cm, frames 5-98). Nearly every geom left its fat box every call, so
 * SAP kept answering with its own stateless sweep, with the proxy moves
 * and a pair table on top: 7.25 M instructions per frame against 4.49 M
 * for this sweep (callgrind, frames 60-64 of the replay).
 *
 * Not kept (session 10): the pair loop with its two prefetch bounds
 * folded into one test, the filter's flags ANDed and the first-seen order
 * picked without a branch: 63 -> 53 instructions per pair (callgrind,
 * replay frames 0-2, 5.3 M pairs) but 4-10 % slower on the replay's
 * frames 0-11 and 30-99 (3 alternated runs, load 6-8): the loop waits on
 * memory (records, geoms, the callback's stores), not on instructions.
 * Not kept (session 11): prefetching each body's position with the walk
 * (dxSphere::computeAABB waits on it: ~11-16 % of the space collide's
 * samples in the running stress scene, perf) measured no faster under
 * load 8-14 (sync 949-1393 against 941-1573 kcycles per step, 3-6
 * alternated runs), nor did longer prefetch distances (walk 16, records
 * 48, geoms 24 pairs ahead).
 *
 * Not kept (session 12, running stress heap, steps 25-99, load ~10,
 * per-call timers in alternated runs): prefetching each body's position
 * again, now from the record's body pointer (no read of the geom ahead):
 * walk 0.54-0.59 against 0.48-0.56 ms; prefetching the second cache line
 * of each 40-byte record (a third of them straddle two): pair loop
 * 0.10-0.15 against 0.11-0.18 ms in one set of 5 runs, no difference in
 * the next 5. Without the walk's geom prefetch the walk takes 0.88-1.08
 * ms instead of 0.51-0.59: it is what keeps the walk fast.
 *
 * Pair order: the sweep's, fixed by the calls made so far; within a pair,
 * the geom this space's records met first comes first (a first-seen index
 * per record), so neither addresses nor removals (which move records)
 * change which geom a near callback gets as o1.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "minko/broadphase.h"
#include "ode_internal.h"
#include "ode_map.h"

/* What a candidate pair reads, and no more (40 bytes): the pair loop
 * touches two entries and, only when the boxes are not exact, two raw AABBs. */
typedef struct entry {
    dGeomID geom;
    dBodyID body;
    unsigned long cat, col; /* ODE's bits, or 0 and 0 when the geom is disabled or zero-sized */
    uint32_t seen;          /* sync epoch that last found the geom in the space (marked only when some left) */
    uint32_t seq;           /* first-seen index: of a pair, the geom with the lower one is passed first */
} entry;

/* ODE's interleaved AABB {minx, maxx, miny, maxy, minz, maxz}. */
typedef dReal ode_aabb[6];

typedef struct space_state {
    dSpaceID space;
    mk_bp *bp;        /* set-only sweeps of boxes[0, n) */
    int capacity;     /* box capacity of bp */
    entry *entries;   /* records [0, n), dense: a removed one's place takes the last */
    mk_aabb *boxes;   /* boxes[i]: record i's ODE AABB, rounded outwards to mk_real */
    ode_aabb *raw;    /* raw[i]: record i's ODE AABB, kept only when !exact */
    int exact;        /* boxes[] hold ODE's AABBs exactly (mk_real = dReal, none refused) */
    int n;
    size_t cap;       /* of entries and boxes */
    mk_ode_map index; /* dGeomID -> record */
    int *order;       /* record of the i-th geom of the previous enumeration */
    size_t norder, caporder;
    uint32_t epoch;
    uint32_t next_seq; /* first-seen index of the next new record */
    int busy;         /* its pairs are being reported: the records must stay as they are */
} space_state;

static mk_ode_map state_index; /* dSpaceID -> index into states */
static space_state **states;
static int nstates, capstates;

/* Pairs waiting for the near callback (collide2's). Callers append, report
 * their range and truncate back, so a callback may re-enter (nested spaces)
 * safely. */
typedef struct geom_pair { dGeomID a, b; } geom_pair;
static geom_pair *report;
static size_t nreport, capreport;

static int grow_array(void **p, size_t *cap, size_t need, size_t elem)
{
    size_t n = *cap ? *cap : 64;
    void *q;
    if (need <= *cap) return 0;
    while (n < need) n *= 2;
    q = realloc(*p, n * elem);
    if (!q) return -1;
    *p = q;
    *cap = n;
    return 0;
}

static void note_error(mk_status st)
{
    mk_ode_stats_.errors++;
    mk_ode_stats_.last_error = st;
}

/* ---- geoms as ODE's spaces see them ---- */

/* GEOM_ZERO_SIZED is internal; these are the public readings of the cases that set it. */
static int zero_sized(dGeomID g)
{
    dReal r, len;
    dVector3 l;
    switch (dGeomGetClass(g)) {
    case dSphereClass:
        return dGeomSphereGetRadius(g) == 0;
    case dBoxClass:
        dGeomBoxGetLengths(g, l);
        return l[0] == 0 || l[1] == 0 || l[2] == 0;
    case dCapsuleClass:
        dGeomCapsuleGetParams(g, &r, &len);
        return r == 0; /* ODE: a zero-length capsule is a sphere, not zero-sized */
    case dCylinderClass:
        dGeomCylinderGetParams(g, &r, &len);
        return r == 0 || len == 0;
    default:
        return 0;
    }
}

/* The filter's fields of e's geom, read by every sync (ODE sends no notice
 * when they change). */
static void read_filter(entry *e)
{
    dGeomID g = e->geom;
    e->body = dGeomGetBody(g);
    if (dGeomIsEnabled(g) && !zero_sized(g)) {
        e->cat = dGeomGetCategoryBits(g);
        e->col = dGeomGetCollideBits(g);
    } else {
        e->cat = e->col = 0;
    }
}

#if defined(__GNUC__)
#  define MK_PREFETCH(p) __builtin_prefetch(p)
#else
#  define MK_PREFETCH(p) ((void)0)
#endif

/* The pair loop meets records and geoms in the sweep's order, which is
 * spatial, while they lie in memory in creation order: each first visit is
 * a miss, and each waits for the one before. Fetching them ahead lets the
 * misses overlap. Records this many pairs ahead, */
#define RECORD_AHEAD 16
/* and the first cache line of the geoms of records fetched earlier, which
 * any near callback reads (ODE's own spaces read the geoms just before they
 * call back, so theirs come warm). */
#define GEOM_AHEAD 8

/* The three cache lines of a dxGeom that ODE's list walk, its AABB and
 * read_filter touch. */
static void prefetch_lines(const void *geom)
{
    const char *g = (const char *)geom;
    MK_PREFETCH(g);
    MK_PREFETCH(g + 64);
    MK_PREFETCH(g + 128);
}

/* ODE's list walk follows each geom's next pointer and dGeomGetAABB reads
 * the geom: after a world step they are cold, and each miss waits for the
 * one before. The previous call's order names the geoms to come (ODE keeps
 * the list's order while they stay dirty): fetched this many ahead. */
#define WALK_AHEAD 8

/* Closed overlap of ODE's interleaved AABBs (a NaN bound compares false and
 * so never separates, as in ODE). */
static int aabbs_overlap(const dReal *a1, const dReal *a2)
{
    return !(a1[0] > a2[1] || a1[1] < a2[0] || a1[2] > a2[3] || a1[3] < a2[2] || a1[4] > a2[5] || a1[5] < a2[4]);
}

/* collideAABBs' tests in its order but for the AABBs' (the caller's); the
 * geoms' enabled and zero-size tests are in cat and col (read_filter). */
static int ode_filter(dBodyID b1, unsigned long cat1, unsigned long col1, dBodyID b2, unsigned long cat2,
                      unsigned long col2)
{
    if (b1 && b1 == b2) return 0;
    return (cat1 & col2) || (cat2 & col1);
}

/* ---- dReal AABB -> mk_aabb, rounded outwards ---- */

#if defined(MK_SINGLE)
#  define mk_nextafter_ nextafterf
#else
#  define mk_nextafter_ nextafter
#endif

static mk_real round_down(dReal x)
{
    mk_real f = (mk_real)x;
    if ((dReal)f > x) f = mk_nextafter_(f, -(mk_real)HUGE_VAL);
    return f;
}
static mk_real round_up(dReal x)
{
    mk_real f = (mk_real)x;
    if ((dReal)f < x) f = mk_nextafter_(f, (mk_real)HUGE_VAL);
    return f;
}

/* The broadphase refuses NaN and inverted boxes; ODE never separates a NaN
 * bound, so such an axis is treated as filling all space. The result
 * contains the dReal box. A side at +inf (or -inf) on both ends becomes the
 * largest finite value to infinity, since the broadphase refuses lo = +inf
 * and hi = -inf. */
static mk_aabb to_mk_aabb_rounded(const dReal *b)
{
    mk_aabb box;
    mk_real inf = (mk_real)HUGE_VAL, *lo = &box.lo.x, *hi = &box.hi.x;
    int k;
    for (k = 0; k < 3; k++) {
        dReal l = b[2 * k], h = b[2 * k + 1];
        if (!(l <= h)) {
            lo[k] = -inf;
            hi[k] = inf;
        } else if (l == (dReal)HUGE_VAL) {
            lo[k] = MK_REAL_MAX;
            hi[k] = inf;
        } else if (h == -(dReal)HUGE_VAL) {
            lo[k] = -inf;
            hi[k] = -MK_REAL_MAX;
        } else {
            lo[k] = round_down(l);
            hi[k] = round_up(h);
        }
    }
    return box;
}

/* Reads geom g's AABB, once, into record i: with mk_real = dReal a plain
 * copy into the box the sweep reads, which is then the only copy (exact:
 * the sweep's closed test is ODE's, and a box it refuses -- a NaN bound, a
 * side at +inf on both ends; planes are fine -- sends the call to the
 * rounded conversion in sweep_records, so valid boxes are checked once);
 * otherwise the raw AABB is kept for the exact test and rounded outwards. */
static inline void read_aabb(space_state *st, int i, dGeomID g)
{
#if defined(MK_SINGLE)
    dGeomGetAABB(g, st->raw[i]);
    st->boxes[i] = to_mk_aabb_rounded(st->raw[i]);
#else
    ode_aabb b;
    dGeomGetAABB(g, b);
    st->boxes[i].lo = mk_v3(b[0], b[2], b[4]);
    st->boxes[i].hi = mk_v3(b[1], b[3], b[5]);
#endif
}

/* Record i's ODE AABB (collide2's scans). */
static const dReal *record_aabb(const space_state *st, int i, ode_aabb tmp)
{
    const mk_aabb *b = &st->boxes[i];
    if (!st->exact) return st->raw[i];
    tmp[0] = b->lo.x; tmp[1] = b->hi.x;
    tmp[2] = b->lo.y; tmp[3] = b->hi.y;
    tmp[4] = b->lo.z; tmp[5] = b->hi.z;
    return tmp;
}

/* ---- per-space state ---- */

/* The broadphase's box capacity is fixed at creation: make a new one twice
 * as large when the space outgrows it (it holds no proxies, only the sweep's
 * scratch, so nothing is copied; not a steady-state event). */
static mk_status reserve(space_state *st, int n)
{
    int cap = st->capacity;
    mk_bp_def def = mk_bp_default_def();
    mk_bp *bp;
    mk_status s;
    if (n <= cap && st->bp) return MK_OK;
    while (cap < n) cap = cap ? 2 * cap : 256;
    def.proxy_capacity = cap;
    /* mk_bp_sweep_boxes writes its own pair array and never touches the pair
     * table: keep that table at its minimum (2 * cap entries would be ~1.4 MB
     * at 10 000 geoms, never used). */
    def.pair_capacity = 16;
    if ((s = mk_bp_create(&def, NULL, &bp)) != MK_OK) return s;
    if (st->bp) mk_bp_destroy(st->bp);
    st->bp = bp;
    st->capacity = cap;
    return MK_OK;
}

/* The state of `space`; NULL when out of memory (*err MK_ERR_OUT_OF_MEMORY)
 * or while that space's own pairs are being reported, i.e. from inside its
 * own near callback (*err MK_ERR_BAD_ARGUMENT: its records and pairs are in
 * use, and ODE's own SAP space cannot do this either). */
static space_state *state_for(dSpaceID space, mk_status *err)
{
    long i = mk_ode_map_get(&state_index, space, NULL);
    space_state *st;
    *err = MK_ERR_OUT_OF_MEMORY;
    if (i >= 0) {
        if (!states[i]->busy) return states[i];
        *err = MK_ERR_BAD_ARGUMENT;
        return NULL;
    }
    if (nstates == capstates) {
        size_t cap = (size_t)capstates;
        if (grow_array((void **)&states, &cap, (size_t)nstates + 1, sizeof *states) != 0) return NULL;
        capstates = (int)cap;
    }
    st = calloc(1, sizeof *st);
    if (!st) return NULL;
    st->space = space;
    if (mk_ode_map_put(&state_index, space, NULL, (uint32_t)nstates) != 0) {
        free(st);
        return NULL;
    }
    states[nstates++] = st;
    return st;
}

static void free_state(space_state *st)
{
    if (st->bp) mk_bp_destroy(st->bp);
    free(st->entries);
    free(st->boxes);
    free(st->raw);
    free(st->order);
    mk_ode_map_free(&st->index);
    free(st);
}

/* Room for n records in entries, boxes and raw (grown together; raw is
 * address space only while the boxes are exact). */
static int reserve_records(space_state *st, size_t n)
{
    size_t cap = st->cap;
    if (n <= cap) return 0;
    if (grow_array((void **)&st->entries, &cap, n, sizeof *st->entries) != 0) return -1;
    cap = st->cap;
    if (grow_array((void **)&st->boxes, &cap, n, sizeof *st->boxes) != 0) return -1;
    cap = st->cap;
    if (grow_array((void **)&st->raw, &cap, n, sizeof *st->raw) != 0) return -1;
    st->cap = cap;
    return 0;
}

static mk_status add_entry(space_state *st, dGeomID g, long *out)
{
    int i = st->n;
    if (mk_ode_map_put(&st->index, g, NULL, (uint32_t)i) != 0) return MK_ERR_OUT_OF_MEMORY;
    memset(&st->entries[i], 0, sizeof st->entries[i]);
    st->entries[i].geom = g;
    st->entries[i].seq = st->next_seq++;
    st->n++;
    *out = i;
    return MK_OK;
}

/* The last record takes the place of record i. */
static void remove_entry(space_state *st, int i)
{
    int last = --st->n;
    mk_ode_map_remove(&st->index, st->entries[i].geom, NULL);
    if (i == last) return;
    st->entries[i] = st->entries[last];
    st->boxes[i] = st->boxes[last];
    memcpy(st->raw[i], st->raw[last], sizeof st->raw[i]);
    mk_ode_map_put(&st->index, st->entries[i].geom, NULL, (uint32_t)i); /* overwrite: cannot allocate */
}

/* Brings the records of `st` up to date with its space: O(n) reads of
 * ODE's AABBs (computed lazily by ODE, as its own spaces do), records for
 * new geoms, and removal of geoms that left the space or were destroyed
 * (ODE sends no notice: they are simply not enumerated any more). A
 * destroyed geom whose address comes back as a new geom just looks moved,
 * which is right: nothing else is cached across calls. */
static mk_status sync(space_state *st)
{
    int n = dSpaceGetNumGeoms(st->space), i;
    mk_status s = reserve(st, n);
    if (s != MK_OK) return s;
    if (grow_array((void **)&st->order, &st->caporder, (size_t)n, sizeof *st->order) != 0 ||
        reserve_records(st, (size_t)st->n + (size_t)n) != 0)
        return MK_ERR_OUT_OF_MEMORY;
    st->epoch++;
    {
        /* Locals, kept in registers across ODE's calls (st's fields would
         * be reloaded after each); add_entry does not move the arrays
         * (reserve_records above). */
        dSpaceID space = st->space;
        entry *entries = st->entries;
        int *order = st->order;
        int hinted = st->norder < (size_t)n ? (int)st->norder : n;
        for (i = 0; i < n; i++) {
            /* order[] is a hint (records move when one is removed): checked */
            int k = i < hinted ? order[i] : -1;
            dGeomID g;
            long slot;
            if (i + WALK_AHEAD < hinted && order[i + WALK_AHEAD] < st->n)
                prefetch_lines(entries[order[i + WALK_AHEAD]].geom); /* a stale hint's address is harmless */
            g = dSpaceGetGeom(space, i); /* sequential access is O(1) in ODE */
            slot = k >= 0 && k < st->n && entries[k].geom == g ? k : mk_ode_map_get(&st->index, g, NULL);
            if (slot < 0 && (s = add_entry(st, g, &slot)) != MK_OK) return s;
            read_aabb(st, (int)slot, g);
            read_filter(&entries[slot]);
            order[i] = (int)slot;
        }
    }
    st->norder = (size_t)n;
#if !defined(MK_SINGLE)
    st->exact = 1; /* every box was just copied from ODE */
#endif
    /* Every enumerated geom has a record, so more records than geoms means
     * some geoms left: the ones order[] does not list. */
    if (st->n > n) {
        for (i = 0; i < n; i++) st->entries[st->order[i]].seen = st->epoch;
        for (i = 0; i < st->n;)
            if (st->entries[i].seen != st->epoch) remove_entry(st, i);
            else i++;
    }
    return MK_OK;
}

/* The pairs of records whose boxes overlap: ODE's AABB pairs exactly when
 * st->exact, else a candidate set for ODE's own test on raw[], since boxes
 * that ODE never separates (NaN) or the broadphase refuses are widened to
 * all space by the rounded conversion. */
static mk_status sweep_records(space_state *st, const mk_bp_pair **pairs, int *np)
{
    int i;
    mk_status s = mk_bp_sweep_boxes(st->bp, st->boxes, 0, st->n, pairs, np);
    if (s != MK_ERR_BAD_AABB) return s;
    st->exact = 0;
    for (i = 0; i < st->n; i++) { /* ODE keeps the AABB it computed: a copy */
        dGeomGetAABB(st->entries[i].geom, st->raw[i]);
        st->boxes[i] = to_mk_aabb_rounded(st->raw[i]);
    }
    return mk_bp_sweep_boxes(st->bp, st->boxes, 0, st->n, pairs, np);
}

/* ---- reporting ---- */

static int push_pair(dGeomID a, dGeomID b)
{
    if (grow_array((void **)&report, &capreport, nreport + 1, sizeof *report) != 0) return -1;
    report[nreport].a = a;
    report[nreport].b = b;
    nreport++;
    return 0;
}

/* Calls back for report[from..] and truncates the list back to `from`. */
static void flush(size_t from, void *data, dNearCallback *callback)
{
    size_t i;
    mk_ode_stats_.pairs_reported += (long long)(nreport - from);
    /* report may be reallocated by a re-entrant call: index, never hold pointers */
    for (i = from; i < nreport; i++) {
        geom_pair p = report[i];
        callback(data, p.a, p.b);
    }
    nreport = from;
}

void mk_ode_space_collide(dSpaceID space, void *data, dNearCallback *callback)
{
    space_state *st;
    const mk_bp_pair *pairs;
    int np, i;
    long long reported = 0;
    mk_status s;
    if (!space || !callback || !dGeomIsSpace((dGeomID)space)) {
        note_error(MK_ERR_NULL);
        return;
    }
    mk_ode_stats_.space_calls++;
    st = state_for(space, &s);
    if (!st) {
        note_error(s);
        return;
    }
    s = sync(st);
    if (s == MK_OK) s = sweep_records(st, &pairs, &np);
    if (s != MK_OK) {
        note_error(s);
        return;
    }
    /* The callback straight from the pair loop, as ODE's spaces do (no
     * list of pairs written and read again: at 3 million pairs that is
     * 100 MB of memory traffic). It may collide other spaces; this one's
     * records and pairs stay as they are while busy (state_for). */
    st->busy = 1;
    for (i = 0; i < np; i++) {
        entry *a = &st->entries[pairs[i].a];
        entry *b = &st->entries[pairs[i].b];
        if (i + RECORD_AHEAD < np) {
            MK_PREFETCH(&st->entries[pairs[i + RECORD_AHEAD].a]);
            MK_PREFETCH(&st->entries[pairs[i + RECORD_AHEAD].b]);
        }
        if (i + GEOM_AHEAD < np) {
            MK_PREFETCH(st->entries[pairs[i + GEOM_AHEAD].a].geom);
            MK_PREFETCH(st->entries[pairs[i + GEOM_AHEAD].b].geom);
        }
        if (ode_filter(a->body, a->cat, a->col, b->body, b->cat, b->col) &&
            (st->exact || aabbs_overlap(st->raw[pairs[i].a], st->raw[pairs[i].b]))) {
            reported++;
            if (a->seq < b->seq) callback(data, a->geom, b->geom);
            else callback(data, b->geom, a->geom);
        }
    }
    st->busy = 0;
    mk_ode_stats_.pairs_reported += reported;
}

/* ODE's collide2(space, geom): every enabled geom of the (synced) space
 * against `g`, which itself is not checked for being enabled, as in ODE;
 * a scan of the records, O(n) like ODE's own spaces' collide2, in record
 * order (deterministic). `g_first` puts g first in the callback
 * (dSpaceCollide2's swap_callback). */
static mk_status collect_vs_geom(space_state *st, dGeomID g, int g_first)
{
    dReal box[6];
    dBodyID body = dGeomGetBody(g);
    unsigned long cat = dGeomGetCategoryBits(g), col = dGeomGetCollideBits(g);
    int i;
    dGeomGetAABB(g, box);
    for (i = 0; i < st->n; i++) {
        entry *e = &st->entries[i];
        ode_aabb tmp;
        if (!aabbs_overlap(record_aabb(st, i, tmp), box)) continue;
        if (!ode_filter(e->body, e->cat, e->col, body, cat, col)) continue;
        if ((g_first ? push_pair(g, e->geom) : push_pair(e->geom, g)) != 0) return MK_ERR_OUT_OF_MEMORY;
    }
    return MK_OK;
}

void mk_ode_space_collide2(dGeomID o1, dGeomID o2, void *data, dNearCallback *callback)
{
    dSpaceID s1, s2;
    size_t from = nreport;
    mk_status s = MK_OK;
    if (!o1 || !o2 || !callback) {
        note_error(MK_ERR_NULL);
        return;
    }
    mk_ode_stats_.space_calls++;
    s1 = dGeomIsSpace(o1) ? (dSpaceID)o1 : NULL;
    s2 = dGeomIsSpace(o2) ? (dSpaceID)o2 : NULL;
    if (s1 && s2) { /* different sublevels: the lower one is treated as a plain geom */
        int l1 = dSpaceGetSublevel(s1), l2 = dSpaceGetSublevel(s2);
        if (l1 > l2) s2 = NULL;
        if (l1 < l2) s1 = NULL;
    }
    if (s1 && s2 && s1 == s2) {
        mk_ode_space_collide(s1, data, callback);
        return;
    }
    if (!s1 && !s2) { /* two geoms: collideAABBs alone, enabled or not, as in ODE */
        dReal b1[6], b2[6];
        dGeomGetAABB(o1, b1);
        dGeomGetAABB(o2, b2);
        if (ode_filter(dGeomGetBody(o1), dGeomGetCategoryBits(o1), dGeomGetCollideBits(o1), dGeomGetBody(o2),
                       dGeomGetCategoryBits(o2), dGeomGetCollideBits(o2)) &&
            aabbs_overlap(b1, b2)) {
            mk_ode_stats_.pairs_reported++;
            callback(data, o1, o2);
        }
        return;
    }
    {
        /* One space is queried with the geoms of the other side: the other
         * space's geoms (all of them, in list order, as ODE iterates the
         * space with fewer geoms) or the single geom. */
        int iterate_s1 = s1 && s2 && dSpaceGetNumGeoms(s1) < dSpaceGetNumGeoms(s2);
        dSpaceID queried = s1 && !iterate_s1 ? s1 : s2;
        dGeomID other = queried == s1 ? o2 : o1;
        dSpaceID other_space = queried == s1 ? s2 : s1;
        int other_first = queried == s2; /* the o1 side always comes first */
        space_state *st = state_for(queried, &s);
        if (st) s = sync(st);
        if (s == MK_OK && other_space) {
            int n = dSpaceGetNumGeoms(other_space), i;
            for (i = 0; i < n && s == MK_OK; i++) s = collect_vs_geom(st, dSpaceGetGeom(other_space, i), other_first);
        } else if (s == MK_OK) {
            s = collect_vs_geom(st, other, other_first);
        }
    }
    if (s != MK_OK) note_error(s);
    flush(from, data, callback);
}

void mk_ode_space_forget(dSpaceID space)
{
    long i = mk_ode_map_get(&state_index, space, NULL);
    if (i < 0) return;
    if (states[i]->busy) { /* from inside its own near callback: its records are in use */
        note_error(MK_ERR_BAD_ARGUMENT);
        return;
    }
    free_state(states[i]);
    mk_ode_map_remove(&state_index, space, NULL);
    if (i != nstates - 1) { /* swap-remove, keep the index map in step */
        states[i] = states[nstates - 1];
        mk_ode_map_put(&state_index, states[i]->space, NULL, (uint32_t)i); /* overwrite: cannot allocate */
    }
    nstates--;
}

void mk_ode_space_free_all(void)
{
    int i;
    for (i = 0; i < nstates; i++) free_state(states[i]);
    free(states);
    states = NULL;
    nstates = capstates = 0;
    mk_ode_map_free(&state_index);
    free(report);
    report = NULL;
    nreport = capreport = 0;
}

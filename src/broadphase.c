/* broadphase.c: the common API in front of brute force, SAP and the grid:
 * proxies and their ids, input checks, the update driver, AUTO's choice,
 * queries and ray casts. See minko/broadphase.h for the contract. */
#include <stddef.h>
#include <string.h>

#include "alloc.h"
#include "broadphase_internal.h"

/* ---- memory ---- */

void *mk_bp_alloc_(mk_bp *bp, size_t size)
{
    void *p = bp->alloc.alloc(bp->alloc.ctx, size, 16);
    if (p) bp->bytes += size;
    return p;
}

void mk_bp_free_(mk_bp *bp, void *p, size_t size)
{
    if (!p) return;
    bp->bytes -= size;
    bp->alloc.free(bp->alloc.ctx, p, size);
}

mk_status mk_bp_grow_(mk_bp *bp, void **p, size_t elem, size_t old_n, size_t new_n)
{
    void *q = mk_bp_alloc_(bp, elem * new_n);
    if (!q) return MK_ERR_OUT_OF_MEMORY;
    if (*p) {
        memcpy(q, *p, elem * old_n);
        mk_bp_free_(bp, *p, elem * old_n);
    }
    *p = q;
    return MK_OK;
}

/* ---- creation ---- */

mk_bp_def mk_bp_default_def(void)
{
    mk_bp_def d;
    memset(&d, 0, sizeof d);
    d.kind = MK_BP_AUTO;
    d.proxy_capacity = 1024;
    d.filter_mode = MK_BP_FILTER_NONE;
    return d;
}

const char *mk_bp_kind_name(mk_bp_kind kind)
{
    switch (kind) {
    case MK_BP_AUTO: return "auto";
    case MK_BP_BRUTE: return "brute";
    case MK_BP_SAP: return "sap";
    case MK_BP_HGRID: return "hgrid";
    default: return "unknown";
    }
}

static int kind_available(mk_bp_kind k)
{
#if defined(MK_WITHOUT_SAP)
    if (k == MK_BP_SAP) return 0;
#endif
#if defined(MK_WITHOUT_HGRID)
    if (k == MK_BP_HGRID) return 0;
#endif
    return k >= MK_BP_AUTO && k < MK_BP_KIND_COUNT;
}

/* Per-proxy arrays, listed once so create and destroy agree. */
typedef struct proxy_array_ { void **p; size_t elem; } proxy_array_;
static int proxy_arrays(mk_bp *bp, proxy_array_ *a)
{
    int n = 0;
    a[n].p = (void **)&bp->box; a[n++].elem = sizeof *bp->box;
    a[n].p = (void **)&bp->next; a[n++].elem = sizeof *bp->next;
    a[n].p = (void **)&bp->user; a[n++].elem = sizeof *bp->user;
    a[n].p = (void **)&bp->cat; a[n++].elem = sizeof *bp->cat;
    a[n].p = (void **)&bp->mask; a[n++].elem = sizeof *bp->mask;
    a[n].p = (void **)&bp->gen; a[n++].elem = sizeof *bp->gen;
    a[n].p = (void **)&bp->flags; a[n++].elem = sizeof *bp->flags;
    a[n].p = (void **)&bp->free_slots; a[n++].elem = sizeof *bp->free_slots;
    a[n].p = (void **)&bp->dirty; a[n++].elem = sizeof *bp->dirty;
    a[n].p = (void **)&bp->bucket; a[n++].elem = sizeof *bp->bucket;
    return n;
}

static void destroy_structures(mk_bp *bp)
{
#if !defined(MK_WITHOUT_SAP)
    mk_sap_destroy_(bp);
#endif
#if !defined(MK_WITHOUT_HGRID)
    mk_hgrid_destroy_(bp);
#endif
}

void mk_bp_destroy(mk_bp *bp)
{
    proxy_array_ a[10];
    int n, i;
    mk_allocator al;
    if (!bp) return;
    destroy_structures(bp);
    mk_sweep_destroy_(bp);
    mk_pairs_fini_(bp);
    n = proxy_arrays(bp, a);
    for (i = 0; i < n; ++i) mk_bp_free_(bp, *a[i].p, a[i].elem * (size_t)bp->cap);
    al = bp->alloc;
    al.free(al.ctx, bp, sizeof *bp);
}

static mk_status check_def(const mk_bp_def *d)
{
    if (!kind_available(d->kind)) return d->kind >= 0 && d->kind < MK_BP_KIND_COUNT ? MK_ERR_UNSUPPORTED : MK_ERR_BAD_ARGUMENT;
    if (d->proxy_capacity < 1 || d->proxy_capacity > MK_BP_MAX_PROXIES) return MK_ERR_BAD_SIZE;
    if (d->pair_capacity < 0 || d->pair_capacity > INT32_MAX / 4) return MK_ERR_BAD_SIZE;
    if (d->filter_mode < MK_BP_FILTER_NONE || d->filter_mode > MK_BP_FILTER_OR) return MK_ERR_BAD_ARGUMENT;
    return MK_OK;
}

#define MK_BP_FIRST_PAIRS_ 1024
mk_status mk_bp_create(const mk_bp_def *def, const mk_allocator *alloc, mk_bp **out)
{
    mk_bp_def d = def ? *def : mk_bp_default_def();
    mk_allocator al;
    mk_bp *bp;
    proxy_array_ a[10];
    int n, i, pair_cap;
    mk_status st;
    if (!out) return MK_ERR_NULL;
    *out = NULL;
    if (mk_alloc_resolve_(alloc, &al) != MK_OK) return MK_ERR_NULL;
    if ((st = check_def(&d)) != MK_OK) return st;
    bp = (mk_bp *)al.alloc(al.ctx, sizeof *bp, 16);
    if (!bp) return MK_ERR_OUT_OF_MEMORY;
    memset(bp, 0, sizeof *bp);
    bp->alloc = al;
    bp->def = d;
    bp->cap = d.proxy_capacity;
    bp->kind = d.kind == MK_BP_AUTO ? MK_BP_SAP : d.kind;
    if (!kind_available(bp->kind)) bp->kind = kind_available(MK_BP_HGRID) ? MK_BP_HGRID : MK_BP_BRUTE;
    n = proxy_arrays(bp, a);
    for (i = 0; i < n; ++i)
        if (!(*a[i].p = mk_bp_alloc_(bp, a[i].elem * (size_t)bp->cap))) { mk_bp_destroy(bp); return MK_ERR_OUT_OF_MEMORY; }
    memset(bp->flags, 0, (size_t)bp->cap);
    memset(bp->gen, 0, (size_t)bp->cap);
    /* A table that may grow starts small and doubles as the first update
     * finds the pairs (candidates, for the grid): sized for 2 per proxy it
     * held 2 MB of index at 100k proxies, mostly empty, and every look-up
     * in a sparse index is a cache miss. */
    if (d.pair_capacity) pair_cap = d.pair_capacity;
    else if (d.fixed_capacity) pair_cap = bp->cap > INT32_MAX / 4 ? INT32_MAX / 4 : 2 * bp->cap;
    else pair_cap = MK_BP_FIRST_PAIRS_;
    if ((st = mk_pairs_init_(bp, pair_cap)) != MK_OK) { mk_bp_destroy(bp); return st; }
    bp->rebuild = 1;
    *out = bp;
    return MK_OK;
}

/* ---- proxies ---- */

/* No NaN, lo <= hi, and no side that is infinite the wrong way (an AABB
 * starting at +inf or ending at -inf is empty, not a plane): on each axis
 * hi - lo >= 0, which IEEE arithmetic makes exactly that (a NaN fails the
 * compare; hi - lo < 0 exactly when hi < lo, subnormals included; +inf -
 * +inf and -inf - -inf are NaN; a finite side against the wrong infinity
 * gives -inf). Three subtractions and compares instead of nine compares:
 * this runs for every move of every proxy and every box of
 * mk_bp_sweep_boxes (ODE's 10 000 geoms: 36 -> ~14 instructions a box). */
static inline int box_ok(const mk_aabb *b)
{
    return (b->hi.x - b->lo.x >= 0) & (b->hi.y - b->lo.y >= 0) & (b->hi.z - b->lo.z >= 0);
}

static inline mk_status check_box(const mk_aabb *b)
{
    return box_ok(b) ? MK_OK : MK_ERR_BAD_AABB;
}

/* && on purpose: a moved box differs in its first coordinate, almost always. */
static inline int same_box(const mk_aabb *a, const mk_aabb *b)
{
    return a->lo.x == b->lo.x && a->lo.y == b->lo.y && a->lo.z == b->lo.z && a->hi.x == b->hi.x &&
           a->hi.y == b->hi.y && a->hi.z == b->hi.z;
}

/* The slot of a live, not destroyed id, or -1. */
static inline int slot_of(const mk_bp *bp, mk_bp_id id)
{
    uint32_t slot = id >> 8;
    if (!bp || slot >= (uint32_t)bp->hi_slot) return -1;
    if ((bp->flags[slot] & (MK_PF_ALIVE | MK_PF_DYING)) != MK_PF_ALIVE) return -1;
    if (bp->gen[slot] != (id & 0xff)) return -1;
    return (int)slot;
}

static inline void mark_dirty(mk_bp *bp, uint32_t slot, uint8_t flag)
{
    if (!(bp->flags[slot] & MK_PF_DIRTY)) {
        bp->flags[slot] |= MK_PF_DIRTY;
        bp->dirty[bp->dirty_count++] = slot;
    }
    bp->flags[slot] |= flag;
}

mk_status mk_bp_create_proxy(mk_bp *bp, mk_aabb box, void *user, uint64_t cat, uint64_t mask, int is_static, mk_bp_id *out)
{
    uint32_t slot;
    mk_status st;
    if (!bp || !out) return MK_ERR_NULL;
    *out = MK_BP_NULL_ID;
    if ((st = check_box(&box)) != MK_OK) return st;
    /* Slots of proxies destroyed since the last update are freed by it; until
     * then they still count against the capacity. */
    if (bp->free_count > 0) slot = bp->free_slots[--bp->free_count];
    else if (bp->hi_slot < bp->cap) slot = (uint32_t)bp->hi_slot++;
    else return MK_ERR_CAPACITY;
    if (bp->gen[slot] == 0) bp->gen[slot] = 1;
    bp->flags[slot] = MK_PF_ALIVE | (is_static ? MK_PF_STATIC : 0);
    bp->box[slot] = box;
    bp->next[slot] = box;
    bp->user[slot] = user;
    bp->cat[slot] = cat;
    bp->mask[slot] = mask;
    mark_dirty(bp, slot, MK_PF_NEW);
    bp->live++;
    if (is_static) bp->statics++;
    *out = mk_bp_id_of_(bp, slot);
    return MK_OK;
}

mk_status mk_bp_destroy_proxy(mk_bp *bp, mk_bp_id id)
{
    int s;
    if (!bp) return MK_ERR_NULL;
    if ((s = slot_of(bp, id)) < 0) return MK_ERR_UNKNOWN_ID;
    mark_dirty(bp, (uint32_t)s, MK_PF_DYING);
    bp->live--;
    if (bp->flags[s] & MK_PF_STATIC) bp->statics--;
    return MK_OK;
}

/* One move, shared by the single and the batch call (bp is not NULL). */
static inline mk_status move_one(mk_bp *bp, mk_bp_id id, const mk_aabb *box)
{
    int s;
    mk_status st;
    if ((s = slot_of(bp, id)) < 0) return MK_ERR_UNKNOWN_ID;
    /* a resting body is not a mover; next[] passed check_box, so the same box would too */
    if (same_box(&bp->next[s], box)) return MK_OK;
    if ((st = check_box(box)) != MK_OK) return st;
    bp->next[s] = *box;
    if (bp->flags[s] & MK_PF_NEW) bp->box[s] = *box;
    else mark_dirty(bp, (uint32_t)s, MK_PF_MOVED);
    return MK_OK;
}

mk_status mk_bp_move_proxy(mk_bp *bp, mk_bp_id id, mk_aabb box)
{
    if (!bp) return MK_ERR_NULL;
    return move_one(bp, id, &box);
}

/* Alignments of the batch's element types, in C99 (no alignof). */
struct align_id_ { char c; mk_bp_id t; };
struct align_box_ { char c; mk_aabb t; };
#define ALIGN_ID_ offsetof(struct align_id_, t)
#define ALIGN_BOX_ offsetof(struct align_box_, t)

mk_status mk_bp_move_proxies(mk_bp *bp, const mk_bp_id *ids, size_t id_stride, const mk_aabb *boxes, size_t box_stride,
                             int n, int *done)
{
    const char *pi = (const char *)ids, *pb = (const char *)boxes;
    mk_status st = MK_OK;
    int i;
    if (done) *done = 0;
    if (!bp) return MK_ERR_NULL;
    if (n < 0) return MK_ERR_BAD_SIZE;
    if (n == 0) return MK_OK;
    if (!ids || !boxes) return MK_ERR_NULL;
    if (!id_stride) id_stride = sizeof *ids;
    if (!box_stride) box_stride = sizeof *boxes;
    /* Every element read must be aligned for its type (a misaligned read is
     * undefined behaviour, and a trap on some embedded targets). */
    if ((uintptr_t)ids % ALIGN_ID_ || id_stride % ALIGN_ID_ || (uintptr_t)boxes % ALIGN_BOX_ || box_stride % ALIGN_BOX_)
        return MK_ERR_BAD_ARGUMENT;
    for (i = 0; i < n; ++i, pi += id_stride, pb += box_stride) {
        mk_bp_id id = *(const mk_bp_id *)(const void *)pi;
        if (id == MK_BP_NULL_ID) continue; /* a free slot of the host's array */
        if ((st = move_one(bp, id, (const mk_aabb *)(const void *)pb)) != MK_OK) break;
    }
    if (done) *done = i;
    return st;
}

mk_status mk_bp_sweep_boxes(mk_bp *bp, const mk_aabb *boxes, size_t box_stride, int n, const mk_bp_pair **pairs, int *count)
{
    const char *pb = (const char *)boxes;
    int i, ok = 1;
    if (pairs) *pairs = NULL;
    if (count) *count = 0;
    if (!bp || !pairs || !count) return MK_ERR_NULL;
    if (n < 0) return MK_ERR_BAD_SIZE;
    if (n > bp->cap) return MK_ERR_CAPACITY;
    if (bp->hi_slot) return MK_ERR_BAD_ARGUMENT; /* a broadphase of proxies: their sweep is mk_bp_update's */
    if (n == 0) return MK_OK;
    if (!boxes) return MK_ERR_NULL;
    if (!box_stride) box_stride = sizeof *boxes;
    if ((uintptr_t)boxes % ALIGN_BOX_ || box_stride % ALIGN_BOX_) return MK_ERR_BAD_ARGUMENT;
    /* one branch for the whole array: a bad box is the rare case */
    for (i = 0; i < n; ++i, pb += box_stride) ok &= box_ok((const mk_aabb *)(const void *)pb);
    if (!ok) return MK_ERR_BAD_AABB;
    return mk_sweep_boxes_(bp, boxes, box_stride, n, pairs, count);
}

mk_status mk_bp_set_filter(mk_bp *bp, mk_bp_id id, uint64_t cat, uint64_t mask)
{
    int s;
    if (!bp) return MK_ERR_NULL;
    if ((s = slot_of(bp, id)) < 0) return MK_ERR_UNKNOWN_ID;
    bp->cat[s] = cat;
    bp->mask[s] = mask;
    mark_dirty(bp, (uint32_t)s, MK_PF_REFILTER);
    return MK_OK;
}

mk_status mk_bp_get_proxy(const mk_bp *bp, mk_bp_id id, mk_aabb *box, void **user)
{
    int s;
    if (!bp) return MK_ERR_NULL;
    if ((s = slot_of(bp, id)) < 0) return MK_ERR_UNKNOWN_ID;
    if (box) *box = bp->next[s];
    if (user) *user = bp->user[s];
    return MK_OK;
}

void *mk_bp_user(const mk_bp *bp, mk_bp_id id)
{
    int s = slot_of(bp, id);
    return s < 0 ? NULL : bp->user[s];
}

int mk_bp_filter_pass_(const mk_bp *bp, uint32_t a, uint32_t b)
{
    uint64_t ab, ba;
    if (bp->def.filter_mode != MK_BP_FILTER_NONE) { /* the words are read only when they matter */
        ab = bp->cat[a] & bp->mask[b];
        ba = bp->cat[b] & bp->mask[a];
        if (bp->def.filter_mode == MK_BP_FILTER_AND && !(ab && ba)) return 0;
        if (bp->def.filter_mode == MK_BP_FILTER_OR && !(ab || ba)) return 0;
    }
    if (bp->def.filter)
        return bp->def.filter(bp->def.filter_ctx, mk_bp_id_of_(bp, a), bp->user[a], mk_bp_id_of_(bp, b), bp->user[b]) != 0;
    return 1;
}

void mk_bp_commit_(mk_bp *bp)
{
    int i;
    for (i = 0; i < bp->dirty_count; ++i) {
        uint32_t s = bp->dirty[i];
        bp->box[s] = bp->next[s];
    }
}

/* ---- AUTO ---- */

/* Motion statistics from the dirty list, smoothed over frames: the share of
 * proxies that moved, and the share that moved farther than their own size
 * (teleports, which break the insertion sort's coherence). */
static void observe_motion(mk_bp *bp)
{
    int i, moved = 0, far = 0;
    double n = bp->live > 0 ? (double)bp->live : 1.0;
    for (i = 0; i < bp->dirty_count; ++i) {
        uint32_t s = bp->dirty[i];
        mk_vec3 d, e;
        if ((bp->flags[s] & (MK_PF_MOVED | MK_PF_NEW | MK_PF_DYING)) == 0) continue;
        ++moved;
        if (bp->flags[s] & (MK_PF_NEW | MK_PF_DYING)) continue; /* churn, not incoherence */
        d = mk_v3_abs(mk_v3_sub(mk_aabb_center(bp->next[s]), mk_aabb_center(bp->box[s])));
        e = mk_v3_sub(bp->box[s].hi, bp->box[s].lo);
        if (d.x > e.x || d.y > e.y || d.z > e.z) ++far;
    }
    if (bp->frames_since_choice == 0) { /* the first sample: nothing to smooth with */
        bp->moved_share = moved / n;
        bp->far_share = far / n;
        return;
    }
    bp->moved_share = 0.5 * bp->moved_share + 0.5 * (moved / n);
    bp->far_share = 0.5 * bp->far_share + 0.5 * (far / n);
}

/* The choice, from what was measured on this scene (shares of movers, of
 * teleports and of statics, SAP's swap counts) against what was measured on
 * the benchmarks (demos/bench_broadphase, 10k proxies; bullet_scenes,
 * ode_scenes):
 *  - incoherent motion (over 2% of the proxies jump farther than their size
 *    in an update, or SAP's swaps ran over budget since the last choice):
 *    the grid, whose cost does not grow with it (teleport: 5.2 ms against
 *    SAP's 12.6) -- but for a caller that wants the set only (pairs_only)
 *    SAP, whose stateless sweep does not care how far things moved
 *    (teleport: 2.9 ms; ODE's 10 000-sphere heap: the grid is 14x slower),
 *    unless most proxies are static (the grid's static index costs nothing
 *    per update; a sweep sorts the statics every time);
 *  - few movers (under ~100, or under 5% with few statics): SAP, which
 *    costs nothing when nothing moved (Bullet's 1000-box stack at rest:
 *    0.036 ms a step against the grid's 0.072);
 *  - many movers (over 20%), or over ~100 among mostly statics: the grid
 *    (uniform, mixed, wall, churn: 1.1 to 2.5 ms against SAP's 3.1 to 7.0;
 *    static: 0.4 ms against 4.2) -- but for a pairs_only caller with few
 *    statics SAP, i.e. its stateless sweep, when the boxes are lined up so
 *    that the sweep tests few boxes per proxy (sweep_is_cheap);
 *  - in between, the structure in use stays: a switch costs a rebuild. */
/* Crowding, for a pairs_only caller: does a stateless sweep test few boxes
 * per proxy? Measured (bench_broadphase, 10k): about 3 tests per proxy on
 * boxes lined up in a corridor or a wall, where the sweep beats the grid
 * (0.77 and 0.85 ms against 1.0 and 1.05), 26-49 on boxes filling a volume,
 * where the grid wins by 1.9x. The count is exact and costs a sort, O(n log
 * n): about 7 M instructions at 10k proxies, more than a frame of either
 * structure. So its answer is kept for MK_BP_CROWD_KEEP_ updates (8
 * choices) unless the number of proxies changes by a quarter: how boxes
 * crowd an axis changes with the layout of the scene, slowly. */
#define MK_BP_SWEEP_TESTS_PER_PROXY_ 6.0
#define MK_BP_CROWD_KEEP_ 256
static int sweep_is_cheap(mk_bp *bp)
{
    double tests;
    int drift = bp->live > bp->crowd_live ? bp->live - bp->crowd_live : bp->crowd_live - bp->live;
    if (bp->crowd_live > 0 && bp->frames_since_choice - bp->crowd_at < MK_BP_CROWD_KEEP_ && 4 * drift <= bp->crowd_live)
        return bp->crowd_cheap;
    if (mk_sweep_count_(bp, &tests) != MK_OK) return 0;
    bp->crowd_live = bp->live;
    bp->crowd_at = bp->frames_since_choice;
    bp->crowd_cheap = tests <= MK_BP_SWEEP_TESTS_PER_PROXY_ * bp->live;
    return bp->crowd_cheap;
}

/* SAP or the grid, for a caller with events and a scene of many movers and
 * few statics: which costs less per update? Estimated on a sample of this
 * update's movers, each against every proxy, from their boxes before and
 * after the moves (O(n) per sampled mover, at a choice only):
 *  - SAP pays for swaps: an endpoint of a mover passing an endpoint of
 *    another proxy, on each of its three axes;
 *  - the grid pays for its candidates (about: pairs of boxes nearer than
 *    the larger one's size on every axis, since cells are 1-2 sizes wide),
 *    each scanned every update, and for the re-tests of those whose gap or
 *    overlap is thinner than their travel (taken as twice the mover's).
 * The weights are fitted so that the estimate ranks the two as measured:
 * bench_broadphase with events at 10k (uniform, mixed, churn: the grid
 * 1.6-2.8x faster, estimate 3-5x) and Bullet's 3000 falling boxes (SAP
 * 2.9x fewer instructions in mk_bp_update over 300 steps; estimate 1-6x
 * cheaper, until the pile spreads and SAP's swaps run over budget). Costs
 * 32 movers x at most 2048 proxies, each proxy read once for its movers:
 * ~80 instructions a (mover, proxy) pair, ~5 M per choice at 10k proxies
 * (bench_broadphase uniform with events; it was ~10 M). */
#define MK_BP_COST_MOVERS_ 32
#define MK_BP_COST_AGAINST_ 2048
#define MK_BP_COST_MARGIN_ 2.0
#define MK_BP_COST_SWAP_ 25.0
#define MK_BP_COST_CANDIDATE_ 12.0
#define MK_BP_COST_RETEST_ 100.0
typedef struct move_cost_ { long swaps[2], near[2], woken[2]; } move_cost_; /* [the other one moved] */

/* Endpoint pairs of the mover (old o, new n) and b (old bo, new bn) on one
 * axis whose order flips: each is one swap of SAP's insertion sort. */
static int flips(mk_real o, mk_real n, mk_real bo, mk_real bn)
{
    return (o < bo) != (n < bn);
}

/* A sampled mover or proxy as cost_against reads it: its boxes before (o)
 * and after (n) the move, the span both cover on each axis, its size. */
typedef struct sample_ { mk_real ol[3], oh[3], nl[3], nh[3], lo[3], hi[3], size[3]; } sample_;

static void sample_of(const mk_aabb *o, const mk_aabb *n, sample_ *m)
{
    int k;
    for (k = 0; k < 3; ++k) {
        m->ol[k] = (&o->lo.x)[k]; m->oh[k] = (&o->hi.x)[k];
        m->nl[k] = (&n->lo.x)[k]; m->nh[k] = (&n->hi.x)[k];
        m->lo[k] = mk_min(m->ol[k], m->nl[k]);
        m->hi[k] = mk_max(m->oh[k], m->nh[k]);
        m->size[k] = m->oh[k] - m->ol[k];
    }
}

/* Do the spans of m and b (before and after the move) meet on axis k? */
static int spans_meet(const sample_ *m, const sample_ *b, int k)
{
    return (b->lo[k] <= m->hi[k]) & (m->lo[k] <= b->hi[k]);
}

/* The four endpoint pairs of m and b on axis k whose order flips. */
static int axis_flips(const sample_ *m, const sample_ *b, int k)
{
    return flips(m->ol[k], m->nl[k], b->ol[k], b->nl[k]) + flips(m->ol[k], m->nl[k], b->oh[k], b->nh[k]) +
           flips(m->oh[k], m->nh[k], b->ol[k], b->nl[k]) + flips(m->oh[k], m->nh[k], b->oh[k], b->nh[k]);
}

/* The gap between m and b on axis k (negative: their overlap), before the move. */
static mk_real axis_gap(const sample_ *m, const sample_ *b, int k)
{
    return mk_max(b->ol[k] - m->oh[k], m->ol[k] - b->oh[k]);
}

/* Runs for every sampled (mover, proxy) pair, so the common case -- spans
 * apart on every axis, not near -- is a few compares without a branch on
 * each axis: flips are counted only where the spans meet, and the gap only
 * once the pair is near on every axis. travel: the mover's. */
static void cost_against(const sample_ *m, mk_real travel, const sample_ *b, int moved, move_cost_ *c)
{
    mk_real d0 = axis_gap(m, b, 0), d1, d2, gap, depth;
    int meet0 = spans_meet(m, b, 0), meet1 = spans_meet(m, b, 1), meet2 = spans_meet(m, b, 2);
    /* no endpoint order can flip on an axis where the two boxes' spans
     * before and after the move do not meet (most proxies, most axes) */
    if (meet0 | meet1 | meet2)
        c->swaps[moved] += (meet0 ? axis_flips(m, b, 0) : 0) + (meet1 ? axis_flips(m, b, 1) : 0) + (meet2 ? axis_flips(m, b, 2) : 0);
    if (!(d0 < mk_max(m->size[0], b->size[0]))) return; /* not near */
    d1 = axis_gap(m, b, 1);
    d2 = axis_gap(m, b, 2);
    if (!(d1 < mk_max(m->size[1], b->size[1])) || !(d2 < mk_max(m->size[2], b->size[2]))) return;
    gap = mk_max(d0, mk_max(d1, d2));
    depth = mk_min(-d0, mk_min(-d1, -d2));
    c->near[moved]++;
    c->woken[moved] += (gap > 0 ? gap : depth) <= 2 * travel;
}

static int is_mover(const mk_bp *bp, uint32_t s)
{
    return (bp->flags[s] & (MK_PF_MOVED | MK_PF_NEW | MK_PF_DYING)) == MK_PF_MOVED;
}

/* Both sides are weighed on the same sample (movers against every stride-th
 * proxy), so their ratio needs no scaling. */
static int sap_is_cheaper(const mk_bp *bp)
{
    move_cost_ c = {{0, 0}, {0, 0}, {0, 0}};
    sample_ mv[MK_BP_COST_MOVERS_], pb;
    mk_real travel[MK_BP_COST_MOVERS_];
    uint32_t slot[MK_BP_COST_MOVERS_], s;
    double sap, grid;
    int i, t = 0, movers = 0, sampled = 0, stride, jstride;
    for (i = 0; i < bp->dirty_count; ++i) movers += is_mover(bp, bp->dirty[i]);
    if (movers == 0) return bp->kind == MK_BP_SAP; /* nothing to weigh: stay */
    stride = movers > MK_BP_COST_MOVERS_ ? movers / MK_BP_COST_MOVERS_ : 1;
    jstride = (bp->hi_slot + MK_BP_COST_AGAINST_ - 1) / MK_BP_COST_AGAINST_;
    for (i = 0; i < bp->dirty_count && sampled < MK_BP_COST_MOVERS_; ++i) {
        uint32_t m = bp->dirty[i];
        const mk_aabb *o = &bp->box[m], *n = &bp->next[m];
        if (!is_mover(bp, m) || t++ % stride) continue;
        sample_of(o, n, &mv[sampled]);
        travel[sampled] = mk_max(mk_v3_max_abs(mk_v3_sub(n->lo, o->lo)), mk_v3_max_abs(mk_v3_sub(n->hi, o->hi)));
        slot[sampled++] = m;
    }
    /* Mover j is weighed against the proxies s = j (mod jstride): each such
     * proxy is read once for all its movers. */
    for (s = 0; s < (uint32_t)bp->hi_slot; ++s) {
        int j = (int)(s % (uint32_t)jstride), moved;
        if (j >= sampled || (bp->flags[s] & (MK_PF_ALIVE | MK_PF_NEW | MK_PF_DYING)) != MK_PF_ALIVE) continue;
        sample_of(&bp->box[s], &bp->next[s], &pb);
        moved = (bp->flags[s] & MK_PF_MOVED) != 0;
        for (; j < sampled; j += jstride)
            if (slot[j] != s) cost_against(&mv[j], travel[j], &pb, moved, &c);
    }
    /* a pair of movers is met from both sides: half each */
    sap = MK_BP_COST_SWAP_ * (c.swaps[0] + 0.5 * c.swaps[1]);
    grid = MK_BP_COST_CANDIDATE_ * (c.near[0] + 0.5 * c.near[1]) + MK_BP_COST_RETEST_ * (c.woken[0] + 0.5 * c.woken[1]);
    /* a switch costs a rebuild, and the sample is noisy: the other must win clearly */
    return bp->kind == MK_BP_SAP ? sap <= MK_BP_COST_MARGIN_ * grid : MK_BP_COST_MARGIN_ * sap < grid;
}

static mk_bp_kind auto_choice(mk_bp *bp, int sap_lost_coherence)
{
    double movers = bp->moved_share * bp->live;
    int dynamic = bp->live - bp->statics, few_statics = 2 * bp->statics < bp->live;
    if (!kind_available(MK_BP_SAP)) return kind_available(MK_BP_HGRID) ? MK_BP_HGRID : MK_BP_BRUTE;
    if (!kind_available(MK_BP_HGRID)) return MK_BP_SAP;
    if (bp->far_share >= 0.02 || sap_lost_coherence)
        return bp->def.pairs_only && few_statics ? MK_BP_SAP : MK_BP_HGRID;
    if (dynamic <= 96 || movers <= 96 || (bp->moved_share < 0.05 && few_statics)) return MK_BP_SAP;
    if (bp->moved_share > 0.2 || !few_statics) {
        if (!few_statics) return MK_BP_HGRID;
        if (bp->def.pairs_only) return sweep_is_cheap(bp) ? MK_BP_SAP : MK_BP_HGRID;
        return sap_is_cheaper(bp) ? MK_BP_SAP : MK_BP_HGRID;
    }
    return bp->kind == MK_BP_BRUTE ? MK_BP_SAP : bp->kind;
}

static void auto_choose(mk_bp *bp)
{
    mk_bp_kind want;
    if (bp->def.kind != MK_BP_AUTO) return;
    /* Sample the motion every 8th update and decide every 32nd (the first
     * included): a switch costs a rebuild, and the sampling is not free. The
     * second update is sampled and decided too: it is the first to see
     * motion rather than creation, and waiting longer costs a scene of few
     * frames most of its run (teleport, 100k proxies, 8 frames: 7 of them
     * on the grid, 97 ms a frame against the sweep's 36). */
    if (bp->frames_since_choice % 8 == 0 || bp->frames_since_choice == 1) observe_motion(bp);
    if (bp->frames_since_choice % 32 != 0 && bp->frames_since_choice != 1) {
        bp->frames_since_choice++;
        return;
    }
    bp->frames_since_choice++;
    want = auto_choice(bp, bp->kind == MK_BP_SAP && bp->sap_losses > bp->losses_at_choice);
    bp->losses_at_choice = bp->sap_losses;
    if (want == bp->kind) return;
    destroy_structures(bp);
    bp->kind = want;
    bp->rebuild = 1;
    bp->switches++;
}

/* ---- update ---- */

static mk_status run_structure(mk_bp *bp)
{
    switch (bp->kind) {
#if !defined(MK_WITHOUT_SAP)
    case MK_BP_SAP: return mk_sap_update_(bp);
#endif
#if !defined(MK_WITHOUT_HGRID)
    case MK_BP_HGRID: return mk_hgrid_update_(bp);
#endif
    default: return mk_brute_update_(bp);
    }
}

static void retire_dirty(mk_bp *bp)
{
    int i;
    for (i = 0; i < bp->dirty_count; ++i) {
        uint32_t s = bp->dirty[i];
        if (bp->flags[s] & MK_PF_DYING) {
            bp->flags[s] = 0;
            bp->gen[s] = (uint8_t)(bp->gen[s] == 255 ? 1 : bp->gen[s] + 1);
            bp->free_slots[bp->free_count++] = s;
        } else {
            bp->flags[s] &= (uint8_t)(MK_PF_ALIVE | MK_PF_STATIC);
        }
    }
    bp->dirty_count = 0;
}

mk_status mk_bp_update(mk_bp *bp)
{
    mk_status st;
    int rebuild, sweeps;
    if (!bp) return MK_ERR_NULL;
    auto_choose(bp);
    rebuild = bp->rebuild;
    sweeps = bp->sweeps;
    st = run_structure(bp);
    if (rebuild && sweeps == bp->sweeps) bp->full_rebuilds++;
    bp->swept = st == MK_OK && sweeps != bp->sweeps;
    if (st != MK_OK) {
        /* Whatever was missed is recounted next time; the pairs of destroyed
         * proxies go now, since their slots are about to be reused. */
        mk_pairs_drop_flagged_(bp, MK_PF_DYING);
        bp->rebuild = 1;
    }
    mk_pairs_finish_(bp);
    retire_dirty(bp);
    return st;
}

const mk_bp_pair *mk_bp_pairs(const mk_bp *bp, int *count)
{
    if (count) *count = bp ? bp->pairs.set_count : 0;
    return bp ? bp->pairs.set : NULL;
}

/* pairs_only: no events, even after updates that made them internally. */
const mk_bp_pair *mk_bp_added(const mk_bp *bp, int *count)
{
    if (count) *count = bp && !bp->def.pairs_only ? bp->pairs.added_count : 0;
    return bp ? bp->pairs.added : NULL;
}

const mk_bp_pair *mk_bp_removed(const mk_bp *bp, int *count)
{
    if (count) *count = bp && !bp->def.pairs_only ? bp->pairs.removed_count : 0;
    return bp ? bp->pairs.removed : NULL;
}

/* ---- queries ---- */

typedef struct query_ctx_ { const mk_bp *bp; mk_bp_query_fn fn; void *ctx; } query_ctx_;

/* Proxies destroyed since the last update are still in the structures: hide them. */
static int skip_dying(void *c, mk_bp_id id, void *user)
{
    query_ctx_ *q = (query_ctx_ *)c;
    if (q->bp->flags[id >> 8] & MK_PF_DYING) return 1;
    return q->fn(q->ctx, id, user);
}

static void brute_query(const mk_bp *bp, mk_aabb box, mk_bp_query_fn fn, void *ctx)
{
    int s;
    for (s = 0; s < bp->hi_slot; ++s) {
        if ((bp->flags[s] & (MK_PF_ALIVE | MK_PF_NEW)) != MK_PF_ALIVE) continue;
        if (mk_bp_overlap_(&bp->box[s], &box) && !fn(ctx, mk_bp_id_of_(bp, (uint32_t)s), bp->user[s])) return;
    }
}

static void query(const mk_bp *bp, mk_aabb box, mk_bp_query_fn fn, void *ctx)
{
    query_ctx_ q;
    q.bp = bp; q.fn = fn; q.ctx = ctx;
    if (bp->swept) { mk_sweep_query_(bp, box, skip_dying, &q); return; }
    if (bp->rebuild || bp->kind == MK_BP_BRUTE) { brute_query(bp, box, skip_dying, &q); return; }
#if !defined(MK_WITHOUT_SAP)
    if (bp->kind == MK_BP_SAP) { mk_sap_query_(bp, box, skip_dying, &q); return; }
#endif
#if !defined(MK_WITHOUT_HGRID)
    if (bp->kind == MK_BP_HGRID) { mk_hgrid_query_(bp, box, skip_dying, &q); return; }
#endif
}

mk_status mk_bp_query_aabb(const mk_bp *bp, mk_aabb box, mk_bp_query_fn fn, void *ctx)
{
    mk_status st;
    if (!bp || !fn) return MK_ERR_NULL;
    if ((st = check_box(&box)) != MK_OK) return st;
    query(bp, box, fn, ctx);
    return MK_OK;
}

typedef struct ray_ctx_ {
    const mk_bp *bp;
    mk_bp_ray ray;
    mk_vec3 d;
    mk_real max;
    mk_bp_ray_fn fn;
    void *ctx;
} ray_ctx_;

/* Entry fraction of the segment into [lo, hi] on one axis, clipping [*t0, *t1]. */
static int slab(mk_real from, mk_real d, mk_real lo, mk_real hi, mk_real *t0, mk_real *t1)
{
    mk_real a, b;
    if (d == 0) return from >= lo && from <= hi;
    a = (lo - from) / d;
    b = (hi - from) / d;
    if (a > b) { mk_real t = a; a = b; b = t; }
    if (a > *t0) *t0 = a;
    if (b < *t1) *t1 = b;
    return *t0 <= *t1;
}

static int ray_visit(void *c, mk_bp_id id, void *user)
{
    ray_ctx_ *r = (ray_ctx_ *)c;
    const mk_aabb *b = &r->bp->box[id >> 8];
    mk_real t0 = 0, t1 = r->max;
    /* The swept box [box_lo, box_hi] touches b iff the segment touches b grown by it. */
    if (!slab(r->ray.from.x, r->d.x, b->lo.x - r->ray.box_hi.x, b->hi.x - r->ray.box_lo.x, &t0, &t1)) return 1;
    if (!slab(r->ray.from.y, r->d.y, b->lo.y - r->ray.box_hi.y, b->hi.y - r->ray.box_lo.y, &t0, &t1)) return 1;
    if (!slab(r->ray.from.z, r->d.z, b->lo.z - r->ray.box_hi.z, b->hi.z - r->ray.box_lo.z, &t0, &t1)) return 1;
    r->max = r->fn(r->ctx, id, user, t0, r->max);
    return r->max >= 0;
}

mk_status mk_bp_raycast(const mk_bp *bp, const mk_bp_ray *ray, mk_bp_ray_fn fn, void *ctx)
{
    ray_ctx_ r;
    mk_aabb sweep;
    if (!bp || !ray || !fn) return MK_ERR_NULL;
    if (!mk_v3_is_valid(ray->from) || !mk_v3_is_valid(ray->to) || !mk_v3_is_valid(ray->box_lo) || !mk_v3_is_valid(ray->box_hi))
        return MK_ERR_NOT_FINITE;
    if (ray->box_lo.x > 0 || ray->box_lo.y > 0 || ray->box_lo.z > 0 || ray->box_hi.x < 0 || ray->box_hi.y < 0 || ray->box_hi.z < 0)
        return MK_ERR_BAD_AABB;
    r.bp = bp; r.ray = *ray; r.fn = fn; r.ctx = ctx; r.max = 1;
    r.d = mk_v3_sub(ray->to, ray->from);
    sweep = mk_aabb_make(mk_v3_add(mk_v3_min(ray->from, ray->to), ray->box_lo), mk_v3_add(mk_v3_max(ray->from, ray->to), ray->box_hi));
    if (!mk_v3_is_valid(sweep.lo) || !mk_v3_is_valid(sweep.hi)) return MK_ERR_NOT_FINITE;
    query(bp, sweep, ray_visit, &r);
    return MK_OK;
}

mk_status mk_bp_get_stats(const mk_bp *bp, mk_bp_stats *out)
{
    if (!bp || !out) return MK_ERR_NULL;
    memset(out, 0, sizeof *out);
    out->kind = bp->kind;
    out->requested = bp->def.kind;
    out->proxies = bp->live;
    out->static_proxies = bp->statics;
    out->pairs = bp->pairs.set_count;
    out->candidates = bp->pairs.count;
    mk_bp_added(bp, &out->added);
    mk_bp_removed(bp, &out->removed);
    out->full_rebuilds = bp->full_rebuilds;
    out->sweeps = bp->sweeps;
    out->switches = bp->switches;
    out->bytes = bp->bytes + sizeof *bp;
#if !defined(MK_WITHOUT_SAP)
    if (bp->kind == MK_BP_SAP) out->swaps = mk_sap_swaps_(bp);
#endif
#if !defined(MK_WITHOUT_HGRID)
    if (bp->kind == MK_BP_HGRID) mk_hgrid_counts_(bp, &out->levels, &out->cells);
#endif
    return MK_OK;
}

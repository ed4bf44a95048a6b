/* sap.c: incremental sweep and prune (seeds 000/004).
 *
 * Three arrays of endpoints, one per axis, kept sorted by (value, min before
 * max): the tie rule makes touching boxes overlap. Each array has sentinels at
 * -inf and +inf so the insertion sort needs no bounds checks. An update writes
 * the moved proxies' new values in place and insertion-sorts each array once
 * (batch update); a min endpoint passing a max endpoint leftwards may start a
 * pair (added if the boxes now overlap on all axes), a max passing a min
 * leftwards ends one. Swaps are counted: when they exceed the cost of sorting
 * from scratch (crowded axes, teleports), the update stops and rebuilds with
 * full sorts and one stateless sweep (bp_sweep.c) for the pairs; a pairs_only
 * caller gets the sweep's set alone, without a rebuild. Inserted proxies
 * are merged in as a sorted batch and paired by one sweep; removed ones are
 * compacted out in one pass.
 *
 * Cost of an incremental update: one pass over each axis's 2n endpoints
 * plus one shift per swap (some 14 instructions) plus, per crossing of a
 * min and a max, two AABB tests; the pair table is looked up only for the
 * crossings that change a pair. The moved proxies' old boxes (box[]) are
 * kept until the sorts are done for that: a crossing that ends an overlap
 * can only end a live pair if the old boxes overlapped. On Bullet's 3000
 * falling boxes (300 steps, ~53k swaps an update, 15 % of them crossings
 * that end an overlap on a crowded axis and almost none a pair; callgrind,
 * demos/bullet_split.sh) mk_bp_update went from 874 to 627 M instructions:
 * 805 M with the old-box test alone, the rest from a shift loop per
 * endpoint kind and positions indexed by the endpoint itself. Not kept:
 * carrying ep[i - 1] in a register across the scan (628 M). */
#include <string.h>

#include "broadphase_internal.h"

typedef struct mk_ep { mk_real v; uint32_t d; } mk_ep; /* d = slot << 1 | is_max */

#define MK_SENTINEL_LO_ 0xFFFFFFFEu /* a "min" at -inf: nothing sorts before it */
#define MK_SENTINEL_HI_ 0xFFFFFFFFu /* a "max" at +inf: nothing sorts after it */

struct mk_sap {
    mk_ep *ep[3];
    int count;              /* endpoints per axis, sentinels included */
    int ep_cap;             /* 2 * proxy capacity + 2 */
    uint32_t *pos;          /* pos[axis * pos_stride + d] = index of endpoint d in ep[axis] */
    size_t pos_stride;      /* 2 * proxy capacity */
    uint8_t *in;            /* slot is in the arrays */
    mk_ep *tmp;             /* sorting and batch insertion: 2 * ep_cap */
    uint32_t *active[2], *active_pos; /* sweep: [0] dynamic, [1] static */
    int active_count[2];
    long long swaps;        /* last update */
    int sweep_wait;         /* pairs_only: stateless updates left before insertion sorts may be tried again */
    int sweep_backoff;      /* pairs_only: the next wait, doubled each time they fail */
    int sweep_overdue;      /* pairs_only: stateless updates since the wait ran out (the scene stayed busy) */
    mk_real maxw;           /* >= every finite x width among proxies with finite lo.x */
};

static int ep_less(mk_ep a, mk_ep b)
{
    return a.v < b.v || (a.v == b.v && !(a.d & 1) && (b.d & 1));
}

static int is_sentinel(mk_ep e) { return e.d >= MK_SENTINEL_LO_; }
static uint32_t ep_slot(mk_ep e) { return e.d >> 1; }

static mk_real axis_lo(const mk_aabb *b, int axis) { return (&b->lo.x)[axis]; }
static mk_real axis_hi(const mk_aabb *b, int axis) { return (&b->hi.x)[axis]; }

static int in_structure(const mk_bp *bp, uint32_t s)
{
    return (bp->flags[s] & (MK_PF_ALIVE | MK_PF_DYING)) == MK_PF_ALIVE;
}

/* ---- lifetime ---- */

mk_status mk_sap_create_(mk_bp *bp)
{
    struct mk_sap *s;
    size_t n = (size_t)bp->cap, ne = 2 * n + 2;
    int k;
    if (!(s = (struct mk_sap *)mk_bp_alloc_(bp, sizeof *s))) return MK_ERR_OUT_OF_MEMORY;
    memset(s, 0, sizeof *s);
    bp->sap = s;
    s->ep_cap = (int)ne;
    s->pos_stride = 2 * n;
    for (k = 0; k < 3; ++k)
        if (!(s->ep[k] = (mk_ep *)mk_bp_alloc_(bp, ne * sizeof(mk_ep)))) goto fail;
    if (!(s->tmp = (mk_ep *)mk_bp_alloc_(bp, 2 * ne * sizeof(mk_ep)))) goto fail;
    if (!(s->pos = (uint32_t *)mk_bp_alloc_(bp, 6 * n * sizeof(uint32_t)))) goto fail;
    if (!(s->in = (uint8_t *)mk_bp_alloc_(bp, n))) goto fail;
    if (!(s->active[0] = (uint32_t *)mk_bp_alloc_(bp, n * sizeof(uint32_t)))) goto fail;
    if (!(s->active[1] = (uint32_t *)mk_bp_alloc_(bp, n * sizeof(uint32_t)))) goto fail;
    if (!(s->active_pos = (uint32_t *)mk_bp_alloc_(bp, n * sizeof(uint32_t)))) goto fail;
    return MK_OK;
fail:
    mk_sap_destroy_(bp);
    return MK_ERR_OUT_OF_MEMORY;
}

void mk_sap_destroy_(mk_bp *bp)
{
    struct mk_sap *s = bp->sap;
    size_t n = (size_t)bp->cap, ne = 2 * n + 2;
    int k;
    if (!s) return;
    for (k = 0; k < 3; ++k) mk_bp_free_(bp, s->ep[k], ne * sizeof(mk_ep));
    mk_bp_free_(bp, s->tmp, 2 * ne * sizeof(mk_ep));
    mk_bp_free_(bp, s->pos, 6 * n * sizeof(uint32_t));
    mk_bp_free_(bp, s->in, n);
    mk_bp_free_(bp, s->active[0], n * sizeof(uint32_t));
    mk_bp_free_(bp, s->active[1], n * sizeof(uint32_t));
    mk_bp_free_(bp, s->active_pos, n * sizeof(uint32_t));
    mk_bp_free_(bp, s, sizeof *s);
    bp->sap = NULL;
}

long long mk_sap_swaps_(const mk_bp *bp) { return bp->sap ? bp->sap->swaps : 0; }

/* ---- helpers ---- */

static void set_pos(struct mk_sap *s, int axis, int i)
{
    mk_ep e = s->ep[axis][i];
    if (!is_sentinel(e)) s->pos[(size_t)axis * s->pos_stride + e.d] = (uint32_t)i;
}

static void fix_pos(struct mk_sap *s, int axis, int from)
{
    int i;
    for (i = from; i < s->count; ++i) set_pos(s, axis, i);
}

/* Bottom-up merge sort of a[0, n) using tmp; stable. */
static void sort_eps(mk_ep *a, mk_ep *tmp, int n)
{
    int w, i;
    mk_ep *src = a, *dst = tmp, *sw;
    for (w = 1; w < n; w *= 2) {
        for (i = 0; i < n; i += 2 * w) {
            int l = i, m = i + w < n ? i + w : n, r = i + 2 * w < n ? i + 2 * w : n, o = i, p = m;
            while (l < m && p < r) dst[o++] = ep_less(src[p], src[l]) ? src[p++] : src[l++];
            while (l < m) dst[o++] = src[l++];
            while (p < r) dst[o++] = src[p++];
        }
        sw = src; src = dst; dst = sw;
    }
    if (src != a) memcpy(a, src, (size_t)n * sizeof *a);
}

static void widen(struct mk_sap *s, const mk_aabb *b)
{
    if (b->lo.x >= -MK_REAL_MAX && b->hi.x - b->lo.x > s->maxw) s->maxw = b->hi.x - b->lo.x;
}

static void put_endpoints(const mk_bp *bp, mk_ep *out, uint32_t slot, int axis)
{
    out[0].v = axis_lo(&bp->box[slot], axis); out[0].d = slot << 1;
    out[1].v = axis_hi(&bp->box[slot], axis); out[1].d = (slot << 1) | 1;
}

/* ---- full rebuild: sort everything, sweep the axis of largest spread ---- */

static void active_add(struct mk_sap *s, int list, uint32_t slot)
{
    s->active_pos[slot] = (uint32_t)s->active_count[list];
    s->active[list][s->active_count[list]++] = slot;
}

static void active_remove(struct mk_sap *s, int list, uint32_t slot)
{
    uint32_t p = s->active_pos[slot], last = s->active[list][--s->active_count[list]];
    s->active[list][p] = last;
    s->active_pos[last] = p;
}

/* One sweep along `axis`: every proxy meets the ones whose interval is open
 * when it starts. Only pairs with `needs(slot)` on at least one side are
 * tested (all of them for a rebuild, new ones after an insertion). */
typedef int (*needs_fn)(const mk_bp *bp, uint32_t slot);

static mk_status sweep(mk_bp *bp, int axis, needs_fn needs, mk_status (*report)(mk_bp *, uint32_t, uint32_t))
{
    struct mk_sap *s = bp->sap;
    const mk_ep *ep = s->ep[axis];
    int i, l;
    s->active_count[0] = s->active_count[1] = 0;
    for (i = 1; i < s->count - 1; ++i) {
        uint32_t a = ep_slot(ep[i]);
        int a_static = (bp->flags[a] & MK_PF_STATIC) != 0, a_needs = needs(bp, a);
        if (ep[i].d & 1) { active_remove(s, a_static, a); continue; }
        for (l = 0; l < 2; ++l) {
            int j;
            if (l == 1 && a_static) break; /* static never meets static */
            for (j = 0; j < s->active_count[l]; ++j) {
                uint32_t b = s->active[l][j];
                mk_status st;
                if (!a_needs && !needs(bp, b)) continue;
                if (!mk_bp_overlap_(&bp->box[a], &bp->box[b])) continue;
                if ((st = report(bp, a, b)) != MK_OK) return st;
            }
        }
        active_add(s, a_static, a);
    }
    return MK_OK;
}

static mk_status rebuild(mk_bp *bp)
{
    struct mk_sap *s = bp->sap;
    int axis, n = 1;
    uint32_t i;
    mk_status st;
    memset(s->in, 0, (size_t)bp->cap);
    s->maxw = 0;
    for (i = 0; i < (uint32_t)bp->hi_slot; ++i) {
        if (!in_structure(bp, i)) continue;
        s->in[i] = 1;
        widen(s, &bp->box[i]);
        for (axis = 0; axis < 3; ++axis) put_endpoints(bp, &s->ep[axis][n], i, axis);
        n += 2;
    }
    s->count = n + 1;
    for (axis = 0; axis < 3; ++axis) {
        mk_ep *ep = s->ep[axis];
        ep[0].v = -(mk_real)INFINITY; ep[0].d = MK_SENTINEL_LO_;
        ep[n].v = (mk_real)INFINITY; ep[n].d = MK_SENTINEL_HI_;
        sort_eps(ep + 1, s->tmp, n - 1);
        fix_pos(s, axis, 0);
    }
    mk_pairs_full_begin_(bp);
    if ((st = mk_sweep_pairs_(bp, mk_pairs_full_add_)) != MK_OK) { bp->pairs.full = 0; return st; }
    mk_pairs_full_end_(bp);
    bp->rebuild = 0;
    return MK_OK;
}

/* pairs_only: the set straight from a stateless sweep. The endpoint arrays
 * and the pair table are left stale (bp->rebuild), so the next update that
 * goes back to insertion sorts starts with a rebuild. */
static mk_status sweep_set(mk_bp *bp)
{
    const mk_bp_pair *found;
    int n;
    mk_status st;
    if ((st = mk_sweep_pairs_(bp, NULL)) != MK_OK) return st;
    found = mk_sweep_found_(bp, &n);
    if ((st = mk_pairs_set_from_(bp, found, n)) != MK_OK) return st;
    bp->rebuild = 1;
    bp->sweeps++;
    return MK_OK;
}

/* ---- incremental steps ---- */

static int leaving(const mk_bp *bp, uint32_t slot)
{
    return bp->sap->in[slot] && (bp->flags[slot] & (MK_PF_DYING | MK_PF_REFILTER));
}

static void remove_leaving(mk_bp *bp, int n_leaving)
{
    struct mk_sap *s = bp->sap;
    int axis, r, w = 0;
    if (n_leaving == 0) return;
    mk_pairs_drop_flagged_(bp, MK_PF_DYING | MK_PF_REFILTER);
    for (axis = 0; axis < 3; ++axis) {
        mk_ep *ep = s->ep[axis];
        for (r = 0, w = 0; r < s->count; ++r) {
            if (!is_sentinel(ep[r]) && leaving(bp, ep_slot(ep[r]))) continue;
            ep[w] = ep[r];
            set_pos(s, axis, w++);
        }
    }
    s->count = w;
    for (r = 0; r < bp->dirty_count; ++r)
        if (leaving(bp, bp->dirty[r])) s->in[bp->dirty[r]] = 0;
}

/* a's max passed b's min leftwards: they stop overlapping on this axis. A
 * pair can only be live if the boxes overlapped when the last update ended
 * (box[], not committed yet) or overlap now (next[]: only then can this
 * update have added it), and it must go only if they no longer overlap now:
 * if they still do, the crossing that makes them overlap again on this axis
 * comes later in the sort. The two box tests skip the table look-up for
 * almost every crossing of a crowded axis (boxes that only meet on it). */
static void crossed_apart(mk_bp *bp, uint32_t a, uint32_t b)
{
    if (mk_bp_overlap_(&bp->box[a], &bp->box[b]) && !mk_bp_overlap_(&bp->next[a], &bp->next[b])) mk_pairs_remove_(bp, a, b);
}

/* a's min passed b's max leftwards: they may overlap now. */
static mk_status crossed_into(mk_bp *bp, uint32_t a, uint32_t b)
{
    if (!mk_bp_overlap_(&bp->next[a], &bp->next[b]) || mk_bp_both_static_(bp, a, b)) return MK_OK;
    return mk_pairs_add_(bp, a, b);
}

/* Insertion sort of one axis; a crossing of a min and a max endpoint may
 * start or end a pair. Returns 1 when the swap budget ran out. A max moving
 * left can only end overlaps and a min only start them, so each has its
 * own shift loop, and a shift past an endpoint of the same kind is a move
 * and a position update (pos is indexed by the endpoint's own d). */
static int sift_axis(mk_bp *bp, int axis, long long budget, mk_status *st)
{
    struct mk_sap *s = bp->sap;
    mk_ep *ep = s->ep[axis];
    uint32_t *pos = s->pos + (size_t)axis * s->pos_stride;
    long long swaps = s->swaps;
    int i, n = s->count - 1;
    for (i = 2; i < n; ++i) {
        mk_ep x = ep[i], y = ep[i - 1];
        int j = i;
        if (!ep_less(x, y)) continue;
        if (x.d & 1) { /* ep_less for a max: a max sorts after everything of its value */
            do {
                if (!(y.d & 1)) crossed_apart(bp, ep_slot(x), ep_slot(y));
                ep[j] = y;
                pos[y.d] = (uint32_t)j;
                y = ep[--j - 1];
            } while (x.v < y.v);
        } else { /* ...and a min before the maxes of its value */
            do {
                if ((y.d & 1) && (*st = crossed_into(bp, ep_slot(x), ep_slot(y))) != MK_OK) return 0;
                ep[j] = y;
                pos[y.d] = (uint32_t)j;
                y = ep[--j - 1];
            } while (x.v < y.v || (x.v == y.v && (y.d & 1)));
        }
        ep[j] = x;
        pos[x.d] = (uint32_t)j;
        swaps += i - j;
        if (swaps > budget) break;
    }
    s->swaps = swaps;
    return swaps > budget;
}

static int staying_moved(const mk_bp *bp, uint32_t slot)
{
    return bp->sap->in[slot] && (bp->flags[slot] & (MK_PF_MOVED | MK_PF_DYING | MK_PF_REFILTER)) == MK_PF_MOVED;
}

static int entering(const mk_bp *bp, uint32_t slot)
{
    return !bp->sap->in[slot] && in_structure(bp, slot);
}

/* Merge the sorted batch tmp[0, k) into ep[axis] from the back (in place). */
static void merge_in(struct mk_sap *s, int axis, int k)
{
    mk_ep *ep = s->ep[axis];
    int i = s->count - 2, j = k - 1, o = s->count + k - 1;
    ep[o--] = ep[s->count - 1]; /* the +inf sentinel stays last */
    while (j >= 0) {
        if (i > 0 && ep_less(s->tmp[j], ep[i])) ep[o--] = ep[i--];
        else ep[o--] = s->tmp[j--];
    }
}

static int is_newcomer(const mk_bp *bp, uint32_t slot)
{
    return (bp->flags[slot] & (MK_PF_NEW | MK_PF_REFILTER)) != 0;
}

static mk_status insert_entering(mk_bp *bp, int n_entering)
{
    struct mk_sap *s = bp->sap;
    int axis, r, k = 0;
    if (n_entering == 0) return MK_OK;
    for (axis = 0; axis < 3; ++axis) {
        for (r = 0, k = 0; r < bp->dirty_count; ++r) {
            uint32_t slot = bp->dirty[r];
            if (!entering(bp, slot)) continue;
            put_endpoints(bp, &s->tmp[k], slot, axis);
            k += 2;
        }
        sort_eps(s->tmp, s->tmp + k, k);
        merge_in(s, axis, k);
        s->count += k;
        fix_pos(s, axis, 0);
        s->count -= k;
    }
    s->count += k;
    for (r = 0; r < bp->dirty_count; ++r) {
        uint32_t slot = bp->dirty[r];
        if (!entering(bp, slot)) continue;
        s->in[slot] = 1;
        widen(s, &bp->box[slot]);
    }
    /* Pairs of the newcomers: one sweep, testing only pairs with a newcomer. */
    return sweep(bp, 0, is_newcomer, mk_pairs_add_);
}

/* Writes the moved proxies' new values into their endpoints. */
static void write_moved(mk_bp *bp)
{
    struct mk_sap *s = bp->sap;
    int r, axis;
    for (r = 0; r < bp->dirty_count; ++r) {
        uint32_t slot = bp->dirty[r];
        if (!staying_moved(bp, slot)) continue;
        widen(s, &bp->next[slot]);
        for (axis = 0; axis < 3; ++axis) {
            const uint32_t *pos = s->pos + (size_t)axis * s->pos_stride + 2 * slot;
            s->ep[axis][pos[0]].v = axis_lo(&bp->next[slot], axis);
            s->ep[axis][pos[1]].v = axis_hi(&bp->next[slot], axis);
        }
    }
}

/* Sorting from scratch costs about n log n moves per axis plus a sweep;
 * past that many swaps, insertion sort has lost. With pairs_only the
 * alternative is a stateless sweep, a few passes over the boxes: a few
 * swaps per endpoint are its price. */
static long long swap_budget(const mk_bp *bp)
{
    long long n = bp->sap->count, lg = 1;
    if (bp->def.pairs_only) return 4 * n + 1024;
    while ((1LL << lg) < n) ++lg;
    return 3 * n * lg + 1024;
}

#define MK_SAP_MAX_WAIT_ 64

/* pairs_only, with stale arrays: go on with stateless sweeps, or rebuild
 * and try insertion sorts? Once the wait after a loss is over and the scene
 * is calm (fewer than half the proxies changed): rebuild. A rebuild costs a
 * few sweeps (it fills the pair table), and a busy scene would only lose
 * again; the first updates count as busy too (every proxy is new: ODE's
 * 10 000-sphere heap, 3.3 M pairs at frame 0, took 2.1 s to rebuild against
 * 0.24 s for the sweep of frame 1). A scene that stays busy is retried every
 * 4 * MK_SAP_MAX_WAIT_ updates. */
static int keep_sweeping(mk_bp *bp)
{
    struct mk_sap *s = bp->sap;
    if (s->sweep_wait > 0) {
        s->sweep_wait--;
        return 1;
    }
    if (2 * bp->dirty_count >= bp->live && ++s->sweep_overdue < 4 * MK_SAP_MAX_WAIT_) return 1;
    s->sweep_overdue = 0;
    return 0;
}

/* Insertion sorts lost to incoherent motion: with pairs_only, answer by
 * stateless sweeps for a while (longer after each loss), else rebuild. */
static mk_status lost_coherence(mk_bp *bp)
{
    struct mk_sap *s = bp->sap;
    bp->sap_losses++;
    if (!bp->def.pairs_only) {
        bp->full_rebuilds++;
        return rebuild(bp);
    }
    if (s->sweep_backoff < 4) s->sweep_backoff = 4;
    s->sweep_wait = s->sweep_backoff;
    if (s->sweep_backoff < MK_SAP_MAX_WAIT_) s->sweep_backoff *= 2;
    return sweep_set(bp);
}

mk_status mk_sap_update_(mk_bp *bp)
{
    struct mk_sap *s;
    mk_status st = MK_OK;
    int r, n_leaving = 0, n_moved = 0, n_entering = 0, axis;
    if (!bp->sap && (st = mk_sap_create_(bp)) != MK_OK) return st;
    s = bp->sap;
    s->swaps = 0;
    if (bp->rebuild) {
        mk_bp_commit_(bp);
        if (bp->def.pairs_only && keep_sweeping(bp)) return sweep_set(bp);
        return rebuild(bp);
    }
    for (r = 0; r < bp->dirty_count; ++r) {
        uint32_t slot = bp->dirty[r];
        n_leaving += leaving(bp, slot);
        n_moved += staying_moved(bp, slot);
    }
    remove_leaving(bp, n_leaving);
    for (r = 0; r < bp->dirty_count; ++r) n_entering += entering(bp, bp->dirty[r]);
    if (n_moved) {
        long long budget = swap_budget(bp);
        write_moved(bp);
        for (axis = 0; axis < 3; ++axis) {
            if (sift_axis(bp, axis, budget, &st)) {
                mk_bp_commit_(bp);
                return lost_coherence(bp);
            }
            if (st != MK_OK) {
                mk_bp_commit_(bp);
                return st;
            }
        }
        if (s->sweep_backoff > 4) s->sweep_backoff /= 2; /* coherent again */
    }
    mk_bp_commit_(bp);
    return insert_entering(bp, n_entering);
}

/* ---- region query: the x slab that can hold an overlapping min endpoint ---- */

static int first_at_least(const mk_ep *ep, int n, mk_real v)
{
    int lo = 1, hi = n - 1; /* answer in [1, n-1]; ep[n-1] is the +inf sentinel */
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (ep[mid].v < v) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

static int visit_range(const mk_bp *bp, const mk_ep *ep, int i, int end, mk_real stop, mk_aabb q, mk_bp_query_fn fn, void *ctx)
{
    for (; i < end && ep[i].v <= stop; ++i) {
        uint32_t slot;
        if (ep[i].d & 1) continue;
        slot = ep_slot(ep[i]);
        if (mk_bp_overlap_(&bp->box[slot], &q) && !fn(ctx, mk_bp_id_of_(bp, slot), bp->user[slot])) return 0;
    }
    return 1;
}

void mk_sap_query_(const mk_bp *bp, mk_aabb q, mk_bp_query_fn fn, void *ctx)
{
    const struct mk_sap *s = bp->sap;
    const mk_ep *ep;
    mk_real start;
    int i;
    if (!s) return;
    ep = s->ep[0];
    start = q.lo.x - s->maxw;
    if (!(start > -MK_REAL_MAX)) { visit_range(bp, ep, 1, s->count - 1, q.hi.x, q, fn, ctx); return; }
    /* Proxies reaching to -inf start before any window: visit them first. */
    for (i = 1; i < s->count - 1 && ep[i].v < -MK_REAL_MAX; ++i) {}
    if (!visit_range(bp, ep, 1, i, q.hi.x, q, fn, ctx)) return;
    i = first_at_least(ep, s->count, start);
    visit_range(bp, ep, i, s->count - 1, q.hi.x, q, fn, ctx);
}

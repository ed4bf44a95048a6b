/* ode_space.c: mk_ode_space_collide and mk_ode_space_collide2 (minko_ode.h).
 *
 * ODE has no public interface for custom spaces, so the adapter replaces the
 * *call*: it reads the space's geoms through the public API, keeps one
 * persistent Minko broadphase per space keyed by dGeomID, and reproduces the
 * filter of ODE's collideAABBs (collision_space_internal.h) on each pair the
 * broadphase finds. The broadphase only proposes pairs (its AABBs are the
 * dReal ones rounded outwards to mk_real); the final overlap test runs on
 * ODE's own dReal AABBs, so the reported set is ODE's exactly in a float
 * build too.
 *
 * Why the per-geom work is so small:
 *  - proxies carry a fattened AABB (the geom's grown by FAT_MARGIN of its
 *    size) and move only when the geom's AABB leaves it, so geoms that rest
 *    or creep cost the broadphase nothing; the exact dReal test removes the
 *    extra candidate pairs this brings; the moves go in one batch;
 *  - pairs map to records through an array indexed by the proxies' slots,
 *    with no call per pair;
 *  - ODE keeps a space's list order unless a clean geom is dirtied, and geoms
 *    in a space only the adapter collides stay dirty, so the order of the
 *    previous call usually finds each geom's record without hashing;
 *  - the filter fields (enabled, zero size, body, category and collide bits)
 *    are read lazily, once per call and only for geoms in a candidate pair,
 *    because everything they decide is per pair. Disabled geoms therefore
 *    stay in the broadphase and are filtered out of its pairs, which gives
 *    the same set as skipping them.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "minko/broadphase.h"
#include "ode_internal.h"
#include "ode_map.h"

/* The fields a candidate pair reads come first: with the slot map below,
 * the pair loop touches two entries and nothing else. */
typedef struct entry {
    dGeomID geom;     /* NULL: free slot */
    uint32_t checked; /* sync epoch of the filter fields below */
    int ok;           /* enabled and not zero-sized */
    dBodyID body;
    unsigned long cat, col;
    dReal aabb[6];    /* ODE's interleaved AABB {minx, maxx, miny, maxy, minz, maxz} */
    mk_bp_id proxy;
    uint32_t seen;    /* sync epoch that last found the geom in the space */
    mk_aabb fat;      /* the proxy's AABB: contains aabb, rounded outwards */
} entry;

/* Growth of a proxy's AABB on each side, relative to the geom's largest
 * finite extent (measured on the stress scene: see ode_scenes). */
#define FAT_MARGIN MK_REAL(0.1)

typedef struct space_state {
    dSpaceID space;
    mk_bp *bp;
    int capacity;     /* proxy capacity of bp */
    entry *entries;   /* slots; a proxy's user pointer is its slot + 1 */
    int *of_proxy;    /* MK_BP_SLOT(proxy) -> slot, so pairs need no call per proxy */
    int nslots, capslots, live;
    int *free_slots;
    int nfree;
    mk_ode_map index; /* dGeomID -> slot */
    int *order;       /* slot of the i-th geom of the previous enumeration */
    size_t norder, caporder;
    struct move { mk_bp_id proxy; int slot; mk_aabb box; } *moves; /* one call's proxy moves, made in one batch */
    size_t capmoves;
    uint32_t epoch;
} space_state;

static mk_ode_map state_index; /* dSpaceID -> index into states */
static space_state **states;
static int nstates, capstates;

/* Pairs waiting for the near callback. Callers append, report their range and
 * truncate back, so a callback may re-enter (nested spaces) safely. */
typedef struct geom_pair { dGeomID a, b; } geom_pair;
static geom_pair *report;
static size_t nreport, capreport;
/* Slots found by one region query. */
static int *hits;
static size_t nhits, caphits;

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

static void read_filter(const space_state *st, entry *e)
{
    e->checked = st->epoch;
    e->ok = dGeomIsEnabled(e->geom) && !zero_sized(e->geom);
    e->body = dGeomGetBody(e->geom);
    e->cat = dGeomGetCategoryBits(e->geom);
    e->col = dGeomGetCollideBits(e->geom);
}

static void check_entry(const space_state *st, entry *e)
{
    if (e->checked != st->epoch) read_filter(st, e);
}

/* collideAABBs' tests in its order, on exact dReal AABBs (a NaN bound
 * compares false and so never separates, as in ODE). */
static int ode_filter(dBodyID b1, unsigned long cat1, unsigned long col1, const dReal *a1, dBodyID b2,
                      unsigned long cat2, unsigned long col2, const dReal *a2)
{
    if (b1 && b1 == b2) return 0;
    if (!((cat1 & col2) || (cat2 & col1))) return 0;
    return !(a1[0] > a2[1] || a1[1] < a2[0] || a1[2] > a2[3] || a1[3] < a2[2] || a1[4] > a2[5] || a1[5] < a2[4]);
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
 * bound, so such an axis is treated as filling all space. `grow` (>= 0)
 * widens each side (0 for the exact box); the result contains the dReal
 * box. A side at +inf (or -inf) on both ends becomes the largest finite
 * value to infinity, since the broadphase refuses lo = +inf and hi = -inf. */
static mk_aabb to_mk_aabb_rounded(const dReal *b, dReal grow)
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
            lo[k] = round_down(l - grow);
            hi[k] = round_up(h + grow);
        }
    }
    return box;
}

/* The same; inline, since every moving geom's box comes through here. */
static inline mk_aabb to_mk_aabb_grown(const dReal *b, dReal grow)
{
#if !defined(MK_SINGLE)
    /* mk_real is dReal: a box with ordered, finite bounds (every geom but
     * planes) converts without rounding or special cases. */
    if ((b[0] <= b[1]) & (b[2] <= b[3]) & (b[4] <= b[5]) & (b[0] <= DBL_MAX) & (b[2] <= DBL_MAX) & (b[4] <= DBL_MAX) &
        (b[1] >= -DBL_MAX) & (b[3] >= -DBL_MAX) & (b[5] >= -DBL_MAX)) {
        mk_aabb box;
        box.lo = mk_v3(b[0] - grow, b[2] - grow, b[4] - grow);
        box.hi = mk_v3(b[1] + grow, b[3] + grow, b[5] + grow);
        return box;
    }
#endif
    return to_mk_aabb_rounded(b, grow);
}

static mk_aabb to_mk_aabb(const dReal *b) { return to_mk_aabb_grown(b, 0); }

/* The dReal box inside the proxy's box, compared exactly (a float mk_real
 * widens to dReal without rounding); NaN bounds are never inside. */
static int inside_fat(const dReal *b, const mk_aabb *fat)
{
    return (dReal)fat->lo.x <= b[0] && b[1] <= (dReal)fat->hi.x && (dReal)fat->lo.y <= b[2] && b[3] <= (dReal)fat->hi.y &&
           (dReal)fat->lo.z <= b[4] && b[5] <= (dReal)fat->hi.z;
}

/* The proxy's box: the geom's grown by FAT_MARGIN of its largest finite
 * extent (0 if none). A moving geom leaves its box most frames (ODE's
 * exploding heap: 97% of the geoms every frame), so the finite case comes
 * first, without a loop. */
static mk_aabb fat_box(const dReal *b)
{
    dReal ex = b[1] - b[0], ey = b[3] - b[2], ez = b[5] - b[4], size = ex > ey ? ex : ey, e;
    int k;
    if (ez > size) size = ez;
    if (!(size >= 0 && size <= DBL_MAX)) { /* an infinite or NaN extent: the largest finite one */
        size = 0;
        for (k = 0; k < 3; k++)
            if ((e = b[2 * k + 1] - b[2 * k]) > size && e <= DBL_MAX) size = e;
    }
    return to_mk_aabb_grown(b, FAT_MARGIN * size);
}

/* ---- per-space state ---- */

static void *slot_user(int slot) { return (void *)(uintptr_t)(slot + 1); }
static int user_slot(void *user) { return (int)(uintptr_t)user - 1; }

/* A broadphase of `capacity` proxies holding every entry's proxy box; the
 * new ids go to ids[slot] and the slot map to of_proxy, so that a failure
 * leaves `st` as it was. */
static mk_status new_bp(const space_state *st, int capacity, mk_bp **out, mk_bp_id *ids, int *of_proxy)
{
    mk_bp_def def = mk_bp_default_def();
    int i;
    mk_status s;
    def.proxy_capacity = capacity;
    /* Sweep and prune, not AUTO: on ODE's stress heap (radii 0.05 to 0.3)
     * AUTO moves to the hash grid, whose candidate pairs outnumber the pairs
     * ten to one there; space collide took 14 ms a step instead of SAP's
     * 1.0 ms at 1000 spheres (ode_scenes --quick --scene stress). */
    def.kind = MK_BP_SAP;
    /* The near callback gets the whole set each call, never the changes:
     * lets incoherent frames (the heap exploding) skip the pair table. */
    def.pairs_only = 1;
    s = mk_bp_create(&def, NULL, out);
    if (s == MK_ERR_UNSUPPORTED) { /* a build without SAP (MK_WITHOUT) */
        def.kind = MK_BP_AUTO;
        s = mk_bp_create(&def, NULL, out);
    }
    for (i = 0; s == MK_OK && i < st->nslots; i++) {
        const entry *e = &st->entries[i];
        if (!e->geom) continue;
        s = mk_bp_create_proxy(*out, e->fat, slot_user(i), ~(uint64_t)0, ~(uint64_t)0, 0, &ids[i]);
        if (s == MK_OK) of_proxy[MK_BP_SLOT(ids[i])] = i;
    }
    return s;
}

/* The broadphase's proxy capacity is fixed at creation: rebuild it twice as
 * large when the space outgrows it (not a steady-state event). */
static mk_status reserve(space_state *st, int n)
{
    int cap = st->capacity, i, *of_proxy;
    mk_bp *bp = NULL;
    mk_bp_id *ids;
    mk_status s;
    if (n <= cap && st->bp) return MK_OK;
    while (cap < n) cap = cap ? 2 * cap : 256;
    ids = malloc(((size_t)st->nslots + 1) * sizeof *ids);
    of_proxy = malloc((size_t)cap * sizeof *of_proxy);
    s = ids && of_proxy ? new_bp(st, cap, &bp, ids, of_proxy) : MK_ERR_OUT_OF_MEMORY;
    if (s == MK_OK) {
        for (i = 0; i < st->nslots; i++)
            if (st->entries[i].geom) st->entries[i].proxy = ids[i];
        if (st->bp) mk_bp_destroy(st->bp);
        free(st->of_proxy);
        st->bp = bp;
        st->of_proxy = of_proxy;
        st->capacity = cap;
    } else {
        if (bp) mk_bp_destroy(bp);
        free(of_proxy);
    }
    free(ids);
    return s;
}

static space_state *state_for(dSpaceID space)
{
    long i = mk_ode_map_get(&state_index, space, NULL);
    space_state *st;
    if (i >= 0) return states[i];
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
    free(st->of_proxy);
    free(st->free_slots);
    free(st->order);
    free(st->moves);
    mk_ode_map_free(&st->index);
    free(st);
}

static int new_slot(space_state *st)
{
    if (st->nfree) return st->free_slots[--st->nfree];
    if (st->nslots == st->capslots) {
        size_t cap = (size_t)st->capslots, fcap = (size_t)st->capslots;
        if (grow_array((void **)&st->entries, &cap, (size_t)st->nslots + 1, sizeof *st->entries) != 0) return -1;
        if (grow_array((void **)&st->free_slots, &fcap, cap, sizeof *st->free_slots) != 0) return -1;
        st->capslots = (int)cap;
    }
    return st->nslots++;
}

static mk_status add_entry(space_state *st, dGeomID g, const dReal *box, long *out)
{
    int slot = new_slot(st);
    entry *e;
    mk_status s;
    if (slot < 0) return MK_ERR_OUT_OF_MEMORY;
    e = &st->entries[slot];
    memset(e, 0, sizeof *e);
    e->geom = g;
    memcpy(e->aabb, box, sizeof e->aabb);
    e->fat = fat_box(box);
    s = mk_bp_create_proxy(st->bp, e->fat, slot_user(slot), ~(uint64_t)0, ~(uint64_t)0, 0, &e->proxy);
    if (s == MK_OK && mk_ode_map_put(&st->index, g, NULL, (uint32_t)slot) != 0) {
        mk_bp_destroy_proxy(st->bp, e->proxy);
        s = MK_ERR_OUT_OF_MEMORY;
    }
    if (s != MK_OK) {
        e->geom = NULL;
        st->free_slots[st->nfree++] = slot;
        return s;
    }
    st->of_proxy[MK_BP_SLOT(e->proxy)] = slot;
    st->live++;
    *out = slot;
    return MK_OK;
}

static void remove_entry(space_state *st, int slot)
{
    entry *e = &st->entries[slot];
    mk_bp_destroy_proxy(st->bp, e->proxy);
    mk_ode_map_remove(&st->index, e->geom, NULL);
    e->geom = NULL;
    st->free_slots[st->nfree++] = slot;
    st->live--;
}

/* Brings the broadphase of `st` up to date with its space: O(n) reads of
 * ODE's AABBs (computed lazily by ODE, as its own spaces do), moves for the
 * geoms whose AABB changed, proxies for new geoms, and removal of geoms that
 * left the space or were destroyed (ODE sends no notice: they are simply not
 * enumerated any more). A destroyed geom whose address comes back as a new
 * geom just looks moved, which is right: nothing else is cached across calls. */
static mk_status sync(space_state *st)
{
    int n = dSpaceGetNumGeoms(st->space), i, k, nmoves = 0, done;
    mk_status sm, s = reserve(st, n);
    if (s != MK_OK) return s;
    if (grow_array((void **)&st->order, &st->caporder, (size_t)n, sizeof *st->order) != 0 ||
        grow_array((void **)&st->moves, &st->capmoves, (size_t)n, sizeof *st->moves) != 0)
        return MK_ERR_OUT_OF_MEMORY;
    st->epoch++;
    for (i = 0; i < n; i++) {
        dGeomID g = dSpaceGetGeom(st->space, i); /* sequential access is O(1) in ODE */
        dReal box[6];
        entry *e;
        long slot = (size_t)i < st->norder && st->entries[st->order[i]].geom == g ? st->order[i]
                                                                                  : mk_ode_map_get(&st->index, g, NULL);
        dGeomGetAABB(g, box);
        if (slot < 0) {
            s = add_entry(st, g, box, &slot);
            if (s != MK_OK) break;
        } else {
            e = &st->entries[slot];
            if (!inside_fat(box, &e->fat)) {
                e->fat = fat_box(box);
                st->moves[nmoves].proxy = e->proxy;
                st->moves[nmoves].slot = (int)slot;
                st->moves[nmoves].box = e->fat;
                nmoves++;
            }
            memcpy(e->aabb, box, sizeof box);
        }
        st->entries[slot].seen = st->epoch;
        st->order[i] = (int)slot;
    }
    sm = mk_bp_move_proxies(st->bp, &st->moves[0].proxy, sizeof *st->moves, &st->moves[0].box, sizeof *st->moves, nmoves,
                            &done);
    /* Proxies left behind by a failure keep their box: the records say so,
     * and the next call moves them. */
    for (k = done; k < nmoves; k++) mk_bp_get_proxy(st->bp, st->moves[k].proxy, &st->entries[st->moves[k].slot].fat, NULL);
    if (s != MK_OK) return s;
    if (sm != MK_OK) return sm;
    st->norder = (size_t)n;
    /* Every enumerated geom is live and seen, so live > n means some were not. */
    for (i = 0; st->live > n && i < st->nslots; i++)
        if (st->entries[i].geom && st->entries[i].seen != st->epoch) remove_entry(st, i);
    return mk_bp_update(st->bp);
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
    size_t from = nreport;
    mk_status s;
    if (!space || !callback || !dGeomIsSpace((dGeomID)space)) {
        note_error(MK_ERR_NULL);
        return;
    }
    mk_ode_stats_.space_calls++;
    st = state_for(space);
    if (!st) {
        note_error(MK_ERR_OUT_OF_MEMORY);
        return;
    }
    s = sync(st);
    if (s != MK_OK) {
        note_error(s);
        return;
    }
    pairs = mk_bp_pairs(st->bp, &np);
    /* Room for every candidate up front: the loop below only stores. */
    if (grow_array((void **)&report, &capreport, nreport + (size_t)np, sizeof *report) != 0) {
        note_error(MK_ERR_OUT_OF_MEMORY);
        return;
    }
    for (i = 0; i < np; i++) {
        entry *a = &st->entries[st->of_proxy[MK_BP_SLOT(pairs[i].a)]];
        entry *b = &st->entries[st->of_proxy[MK_BP_SLOT(pairs[i].b)]];
        check_entry(st, a);
        check_entry(st, b);
        if (a->ok && b->ok && ode_filter(a->body, a->cat, a->col, a->aabb, b->body, b->cat, b->col, b->aabb)) {
            report[nreport].a = a->geom;
            report[nreport].b = b->geom;
            nreport++;
        }
    }
    flush(from, data, callback);
}

static int hit_cb(void *ctx, mk_bp_id id, void *user)
{
    (void)ctx;
    (void)id;
    if (grow_array((void **)&hits, &caphits, nhits + 1, sizeof *hits) != 0) return 0;
    hits[nhits++] = user_slot(user);
    return 1;
}

static int cmp_int(const void *x, const void *y)
{
    int a = *(const int *)x, b = *(const int *)y;
    return (a > b) - (a < b);
}

/* ODE's collide2(space, geom): every enabled geom of the (synced) space
 * against `g`, which itself is not checked for being enabled, as in ODE.
 * `g_first` puts g first in the callback (dSpaceCollide2's swap_callback). */
static mk_status collect_vs_geom(space_state *st, dGeomID g, int g_first)
{
    dReal box[6];
    dBodyID body = dGeomGetBody(g);
    unsigned long cat = dGeomGetCategoryBits(g), col = dGeomGetCollideBits(g);
    size_t i;
    mk_status s;
    dGeomGetAABB(g, box);
    nhits = 0;
    s = mk_bp_query_aabb(st->bp, to_mk_aabb(box), hit_cb, NULL);
    if (s != MK_OK) return s;
    qsort(hits, nhits, sizeof *hits, cmp_int); /* slot order: deterministic */
    for (i = 0; i < nhits; i++) {
        entry *e = &st->entries[hits[i]];
        check_entry(st, e);
        if (!e->ok || !ode_filter(e->body, e->cat, e->col, e->aabb, body, cat, col, box)) continue;
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
        if (ode_filter(dGeomGetBody(o1), dGeomGetCategoryBits(o1), dGeomGetCollideBits(o1), b1, dGeomGetBody(o2),
                       dGeomGetCategoryBits(o2), dGeomGetCollideBits(o2), b2)) {
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
        space_state *st = state_for(queried);
        if (!st) s = MK_ERR_OUT_OF_MEMORY;
        if (s == MK_OK) s = sync(st);
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
    free(hits);
    hits = NULL;
    nhits = caphits = 0;
}

/* minko/broadphase.h: which AABBs overlap, kept up to date frame after frame.
 *
 * Contract. A broadphase (mk_bp) owns a set of proxies: an AABB, a user
 * pointer, two filter words and a static flag each, named by a
 * generation-checked mk_bp_id (a destroyed proxy's id is refused; a slot's
 * ids repeat only after 255 reuses of that slot). Callers create, move and destroy proxies, then call
 * mk_bp_update(), which makes the pair set exactly the set of proxy pairs
 * whose closed AABBs overlap (touching boxes overlap), minus static-static
 * pairs and pairs the filter rejects. After an update, mk_bp_pairs() gives the
 * whole set sorted by (a, b) with a < b, and mk_bp_added()/mk_bp_removed()
 * give the changes since the previous update, also sorted: replaying them on
 * the previous set gives the new one. A caller that reads only the set says
 * so (mk_bp_def.pairs_only): it gets no events (their counts stay 0), and SAP
 * may then answer an incoherent update with a stateless sort and sweep that
 * writes the set directly, skipping its pair table; the set is the same
 * exact, sorted set either way. Three structures sit behind one API and
 * give identical sets: brute force (the oracle), incremental sweep and prune,
 * and a hierarchical hash grid; MK_BP_AUTO picks one from scene statistics and
 * mk_bp_stats() says which (for a caller with events and many movers: SAP's
 * swaps against the grid's candidates, estimated on a sample of movers every
 * 32 updates). AABBs may have infinite sides (ground planes) but
 * no NaN, no lo > hi, and no lo = +inf or hi = -inf. Memory comes only from
 * the mk_allocator given at creation: the proxy capacity is fixed then, and
 * the pair set and the grid's cell pool grow by doubling inside mk_bp_update()
 * only when they overflow (never in a steady state; a fixed-size mode refuses
 * with MK_ERR_CAPACITY instead), and AUTO allocates the structure it switches
 * to (stats.switches counts that) and, for a pairs_only caller, the sweep's
 * scratch (about 80 B per proxy, and 8 B per pair its stateless updates
 * find, grown by doubling like the pair set) with which it measures
 * crowding. An update that fails leaves the broadphase
 * valid: the next successful update rebuilds what was missed. Queries (region,
 * ray, stats) never allocate and never change the broadphase, so several
 * threads may query at once; no other call is thread-safe.
 *
 * Complexity, n proxies, d of them moving, s static, p pairs, k changes per
 * update; and where each structure loses:
 *   brute force  update O(d n); queries O(n). Loses beyond a few hundred proxies.
 *   SAP          update O(n + swaps + k) for coherent motion: each endpoint
 *                moves past the endpoints between its old and new place. Loses
 *                when many endpoints crowd one axis (large n, boxes lined up,
 *                every box crossing thousands of others per frame) or motion
 *                is incoherent; past a swap budget it falls back to a full
 *                sort of its axes and a stateless sweep for the pairs. With
 *                pairs_only it answers such updates, and its first ones,
 *                by the sweep alone (no pair table, no events) until the
 *                scene is calm (fewer than half the proxies changed), then
 *                rebuilds. The sweep (no pairs kept): the axis of largest
 *                spread is swept, the next one cut into rows as tall as the
 *                tallest box, one sort of n keys (radix, or insertion from
 *                the last sweep's order when sweeps follow each and the
 *                scene is coherent: O(n), the boxes that changed rows
 *                sorted apart and merged in), and each box meets
 *                the boxes of its own and the next row that overlap it on
 *                the swept axis: O(n + those meetings + p) (the pairs are
 *                bucketed by their lower slot to sort them); a box
 *                infinite across the rows (a plane) meets every box, O(n);
 *                statics are sorted every time too. Crowding, as AUTO
 *                reads it: the tests a sweep would make, counted in O(n log
 *                n) without making them (at a choice; the answer is kept
 *                for 256 updates unless the proxy count changes by a
 *                quarter); few per proxy (boxes lined up in a
 *                corridor or a wall: about 3) and the sweep beats the grid,
 *                many (boxes filling a volume: 26-49) and it loses by about
 *                2x. Statics sit in SAP's axes like everyone else. Region query O(log n + proxies in
 *                the x slab); after a stateless update, O(log n + the boxes
 *                of the rows the query spans that start before it ends).
 *   hash grid    update O(d + candidates with a moved member + cell changes
 *                + static look-ups): candidates are pairs of non-static
 *                proxies sharing a cell, kept across frames; a candidate's
 *                AABBs are re-read only once its two proxies have travelled as
 *                far as its gap (or overlap) was thick, and cells are
 *                revisited only when a proxy crosses a cell wall. Statics that
 *                stay put sit in a static index built in O(s log s) (a dense
 *                array of cells per size level when that fits in ~8 cells per
 *                static, hashed cells otherwise) and cost nothing per update:
 *                a moving proxy looks up the statics around it, O(cells + the
 *                statics near it), only once its travel may have closed the
 *                smallest gap it saw (every update for a fast mover). Memory
 *                O(n) cells, not world volume (about 0.7-2 kB per proxy with
 *                its pair table). Loses when sizes spread over many octaves
 *                (a proxy is also filed in every coarser level in use, and
 *                candidates outnumber pairs ~6x on sizes 1..100 even with
 *                the coarsest size level filed one level finer, which it
 *                is while finer proxies outnumber it 4 to 1; boxes of one
 *                size lined up in a thin cluster, whose candidates overlap on
 *                two axes anyway, are filed one level coarser), when one cell holds
 *                many proxies (candidates grow with its square), on fast
 *                motion (every crossing re-files cells, a fast mover looks up
 *                statics every update; a level where most proxies are fast is
 *                filed one level coarser to halve the crossings), on teleports (each one re-files
 *                all its cells and rebuilds its candidates), and on statics
 *                that keep moving (a moved static leaves the index for the
 *                cells; the index is rebuilt, O(n), once a quarter of it
 *                has). Proxies with an infinite side are candidates of every
 *                proxy. Region query O(cells in the box's range), or O(n)
 *                when that is more.
 *
 * Memory per proxy is fixed at creation for SAP (about 0.5 kB); the pair
 * table, the grid's cells and its static index grow on demand. With
 * fixed_capacity the grid needs pair_capacity for its candidates, not just
 * the pairs, and has no static index (statics are filed in cells).
 */
#ifndef MINKO_BROADPHASE_H
#define MINKO_BROADPHASE_H

#include "minko/math3d.h"

#ifdef __cplusplus
extern "C" {
#endif

/* (slot << 8) | generation, generation in 1..255; 0 is never a live id.
 * Ordering ids orders proxies by slot, so sorted pair sets are deterministic. */
typedef uint32_t mk_bp_id;
#define MK_BP_NULL_ID 0u
/* The slot of an id: below proxy_capacity, unique among live proxies, so
 * callers can index their own arrays by it (e.g. to map pairs to objects
 * without a call per pair). */
#define MK_BP_SLOT(id) ((id) >> 8)
/* Most proxies one broadphase can hold (slot numbers fit in 24 bits). */
#define MK_BP_MAX_PROXIES (1 << 24)

typedef enum mk_bp_kind {
    MK_BP_AUTO = 0, /* choose from scene statistics; re-evaluated as the scene changes */
    MK_BP_BRUTE,    /* O(n^2) reference */
    MK_BP_SAP,      /* incremental sweep and prune */
    MK_BP_HGRID,    /* hierarchical hash grid */
    MK_BP_KIND_COUNT
} mk_bp_kind;

/* Built-in filters on the two words of each proxy (cat = what I am, mask =
 * what I collide with). A pair filter callback, if set, runs after them. */
typedef enum mk_bp_filter_mode {
    MK_BP_FILTER_NONE = 0, /* every pair passes */
    MK_BP_FILTER_AND,      /* Bullet: (cat_a & mask_b) && (cat_b & mask_a) */
    MK_BP_FILTER_OR        /* ODE:    (cat_a & mask_b) || (cat_b & mask_a) */
} mk_bp_filter_mode;

/* Return nonzero to keep the pair. Called when a pair starts to overlap (not
 * every frame), when a proxy's filter words change, and again for every pair
 * after a structure rebuild (AUTO switch, recovery from a failed update);
 * brute force, the plain oracle, and SAP's stateless updates (pairs_only)
 * ask again for every overlapping pair they meet. Called from inside
 * mk_bp_update(), so it must not call back into bp; a filter that changes its
 * mind must say so through mk_bp_set_filter(). */
typedef int (*mk_bp_pair_filter)(void *ctx, mk_bp_id a, void *user_a, mk_bp_id b, void *user_b);

typedef struct mk_bp_def {
    mk_bp_kind kind;              /* default MK_BP_AUTO */
    int proxy_capacity;           /* most live proxies, 1..MK_BP_MAX_PROXIES; default 1024 */
    int pair_capacity;            /* initial pair capacity; 0 = grown from 1024 on demand (fixed: 2 * proxy_capacity) */
    int fixed_capacity;           /* nonzero: never grow; overflow returns MK_ERR_CAPACITY */
    mk_bp_filter_mode filter_mode;/* default MK_BP_FILTER_NONE */
    mk_bp_pair_filter filter;     /* optional */
    void *filter_ctx;
    int pairs_only;               /* nonzero: the caller reads mk_bp_pairs() only (no events) */
} mk_bp_def;

typedef struct mk_bp_pair { mk_bp_id a, b; } mk_bp_pair; /* a < b */

typedef struct mk_bp_stats {
    mk_bp_kind kind;        /* the structure in use (never MK_BP_AUTO) */
    mk_bp_kind requested;   /* what the def asked for */
    int proxies, static_proxies, pairs;
    int added, removed;     /* events of the last update */
    long long swaps;        /* SAP: endpoint swaps in the last update */
    int full_rebuilds;      /* SAP: full sorts so far; any kind: rebuilds after a switch or failure */
    int switches;           /* AUTO: changes of structure so far */
    int levels;             /* grid: occupied levels */
    int cells;              /* grid: occupied cells */
    int candidates;         /* grid: candidate pairs held (pairs sharing a cell); others: pairs held */
    size_t bytes;           /* memory held, all blocks */
    int sweeps;             /* SAP with pairs_only: updates answered by a stateless sweep so far */
} mk_bp_stats;

typedef struct mk_bp mk_bp;

MK_API mk_bp_def mk_bp_default_def(void);
/* def may be NULL (defaults); alloc may be NULL (malloc/free). */
MK_API mk_status mk_bp_create(const mk_bp_def *def, const mk_allocator *alloc, mk_bp **out);
MK_API void mk_bp_destroy(mk_bp *bp);

/* A static proxy never pairs with another static proxy and costs nothing per
 * update unless it is moved. The new proxy's pairs appear at the next update.
 * The slots of proxies destroyed since the last update are freed by it:
 * until then they count against proxy_capacity (size it for the live
 * proxies plus one frame's worth of destroy-and-create). */
MK_API mk_status mk_bp_create_proxy(mk_bp *bp, mk_aabb box, void *user, uint64_t cat, uint64_t mask,
                                    int is_static, mk_bp_id *out);
/* Its pairs disappear at the next update (reported in mk_bp_removed()). */
MK_API mk_status mk_bp_destroy_proxy(mk_bp *bp, mk_bp_id id);
/* New AABB; O(1), the structure catches up in mk_bp_update(). The same AABB
 * as the last one given is not a move (resting bodies cost nothing). */
MK_API mk_status mk_bp_move_proxy(mk_bp *bp, mk_bp_id id, mk_aabb box);
/* n moves in one call, for a host that keeps its proxies' ids and AABBs in
 * its own arrays: entry i moves the proxy whose id is at (char *)ids + i *
 * id_stride to the AABB at (char *)boxes + i * box_stride (strides in bytes,
 * 0 = packed arrays; ids and boxes may point into the same array of host
 * structs). Entries whose id is MK_BP_NULL_ID are skipped (free slots of the
 * host's array). Same semantics as n calls of mk_bp_move_proxy() in order: an
 * unchanged AABB is a no-op, each AABB is checked. The batch stops at the
 * first entry that fails: the entries before it are moved, it and the ones
 * after it are not, *done (if not NULL) gets its index (n when all
 * succeeded) and its status is returned. MK_ERR_BAD_SIZE for n < 0,
 * MK_ERR_NULL for a NULL array with n > 0, MK_ERR_BAD_ARGUMENT for a pointer
 * or stride not aligned for its element type (*done = 0 for these). O(n),
 * no allocation. */
MK_API mk_status mk_bp_move_proxies(mk_bp *bp, const mk_bp_id *ids, size_t id_stride, const mk_aabb *boxes,
                                    size_t box_stride, int n, int *done);
/* A set-only sweep of the caller's own boxes, for a host that reads every
 * AABB again each frame (ODE's spaces): no proxies, ids, events, statics,
 * filter or pair table, and nothing to move. Box i is at (char *)boxes + i *
 * box_stride (0 = packed); *pairs gets every pair (a, b) of indices, a < b,
 * whose closed boxes overlap (touching boxes overlap), each once, *count
 * their number. Their order is the sweep's (rows, then lower ends), fixed by
 * the boxes of this call and of the calls before it: the same calls give the
 * same order. The array is bp's, valid until the next call on bp. Calls in a
 * row keep the sweep's plan and start from the last call's order, so box i
 * should be the same object from call to call (an insertion sort, O(n), on a
 * coherent scene; correct whatever the boxes). Cost: the stateless sweep of
 * mk_bp_update's pairs_only SAP (see above), O(n + boxes met + pairs), one
 * sort of n keys. For a bp that never held a proxy (MK_ERR_BAD_ARGUMENT
 * otherwise); n <= proxy_capacity (MK_ERR_CAPACITY). Each box is checked as
 * a proxy's is (MK_ERR_BAD_AABB); MK_ERR_NULL, MK_ERR_BAD_SIZE (n < 0) and
 * MK_ERR_BAD_ARGUMENT (misaligned) as mk_bp_move_proxies. Allocates the
 * sweep's scratch (about 84 B per proxy of capacity and 34 KB of radix
 * histograms) on the first call and
 * doubles the pair array (first 1024 pairs) when it overflows (with
 * fixed_capacity, not past pair_capacity: MK_ERR_CAPACITY); on any error
 * *pairs is NULL and *count 0. */
MK_API mk_status mk_bp_sweep_boxes(mk_bp *bp, const mk_aabb *boxes, size_t box_stride, int n, const mk_bp_pair **pairs,
                                   int *count);
/* New filter words: the proxy's pairs are re-filtered at the next update. */
MK_API mk_status mk_bp_set_filter(mk_bp *bp, mk_bp_id id, uint64_t cat, uint64_t mask);
MK_API mk_status mk_bp_get_proxy(const mk_bp *bp, mk_bp_id id, mk_aabb *box, void **user);
/* The user pointer of a live id, NULL otherwise (fast path for pair loops). */
MK_API void *mk_bp_user(const mk_bp *bp, mk_bp_id id);

/* Brings the pair set and the events up to date. */
MK_API mk_status mk_bp_update(mk_bp *bp);
/* Views valid until the next mutating call; counts via *count. */
MK_API const mk_bp_pair *mk_bp_pairs(const mk_bp *bp, int *count);
MK_API const mk_bp_pair *mk_bp_added(const mk_bp *bp, int *count);
MK_API const mk_bp_pair *mk_bp_removed(const mk_bp *bp, int *count);

/* Calls fn for every proxy whose AABB overlaps box (closed), each once, in no
 * set order, with the AABBs of the last mk_bp_update() (proxies created since
 * are not seen yet, destroyed ones are skipped). fn returns 0 to stop early. */
typedef int (*mk_bp_query_fn)(void *ctx, mk_bp_id id, void *user);
MK_API mk_status mk_bp_query_aabb(const mk_bp *bp, mk_aabb box, mk_bp_query_fn fn, void *ctx);

/* Segment from `from` to `to` sweeping the box [box_lo, box_hi] (zero for a
 * thin ray; box_lo <= 0 <= box_hi): fn gets every proxy whose AABB the swept
 * box touches, with t in [0, max] the entry fraction along the segment, and
 * returns the new max fraction (return max to go on, t to clip, < 0 to stop). */
typedef struct mk_bp_ray { mk_vec3 from, to, box_lo, box_hi; } mk_bp_ray;
typedef mk_real (*mk_bp_ray_fn)(void *ctx, mk_bp_id id, void *user, mk_real t, mk_real max);
MK_API mk_status mk_bp_raycast(const mk_bp *bp, const mk_bp_ray *ray, mk_bp_ray_fn fn, void *ctx);

MK_API mk_status mk_bp_get_stats(const mk_bp *bp, mk_bp_stats *out);
MK_API const char *mk_bp_kind_name(mk_bp_kind kind);

#ifdef __cplusplus
}
#endif

#endif

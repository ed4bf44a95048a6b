/* broadphase_internal.h: what broadphase.c shares with its structures
 * (bp_brute.c, sap.c, hgrid.c) and the pair table (bp_pairs.c).
 *
 * Data flow of one mk_bp_update(): the API records changes per proxy (flags
 * below, each changed slot once in bp->dirty); the structure's update reads
 * them, commits next[] into box[] (mk_bp_commit_) when it no longer needs the
 * old boxes, and reports overlap changes to the pair table; mk_pairs_finish_
 * turns the changes into sorted added/removed events and the sorted set. */
#ifndef MK_BROADPHASE_INTERNAL_H
#define MK_BROADPHASE_INTERNAL_H

#include "minko/broadphase.h"

/* Proxy flags. */
enum {
    MK_PF_ALIVE = 1,     /* slot in use (possibly DYING) */
    MK_PF_STATIC = 2,
    MK_PF_DIRTY = 4,     /* listed in bp->dirty */
    MK_PF_NEW = 8,       /* created since the last update: not in the structure yet */
    MK_PF_DYING = 16,    /* destroyed since the last update: still in the structure */
    MK_PF_MOVED = 32,    /* next[] differs from box[] */
    MK_PF_REFILTER = 64  /* filter words changed: re-run the filter on its pairs */
};

/* Pair table entry states. */
enum {
    MK_PS_LIVE = 1,      /* overlapping and accepted by the filter, as of now */
    MK_PS_REPORTED = 2,  /* in the set given out by the last update */
    MK_PS_TOUCHED = 4,   /* in pairs.touched */
    MK_PS_CAND = 16,     /* grid: the two proxies share a cell */
    MK_PS_REJECTED = 32, /* grid: overlapping but the filter said no */
    MK_PS_STATIC = 64,   /* grid: overlapping, found through the static index */
    MK_PS_FOUND = 128,   /* grid: ...by a look-up of this update (cleared by its re-test) */
    MK_PS_KEEP = MK_PS_LIVE | MK_PS_CAND | MK_PS_STATIC /* entries without these go */
};

/* wake: the grid's re-test threshold on the two proxies' summed travel (0 = test). */
typedef struct mk_pair_entry { uint64_t key; uint32_t state; float wake; } mk_pair_entry;

/* Open-addressing pair table: dense entries, a linear-probing index of
 * entry numbers (backward-shift deletion, no tombstones) keyed by
 * (low slot << 32 | high slot), plus the sorted output and event arrays. */
typedef struct mk_pair_table {
    mk_pair_entry *e;
    int count, cap;           /* entries; cap is also the size of every array below */
    uint32_t *index;          /* 2 * cap rounded up to a power of two, UINT32_MAX = empty */
    uint32_t index_mask;
    uint32_t *touched; int touched_count;
    uint64_t *scratch, *scratch2;  /* sorting */
    mk_bp_pair *set, *set_next; int set_count;
    mk_bp_pair *added, *removed; int added_count, removed_count;
    int full;                 /* 1 inside a full recount, 2 after its end, 3 after a forget */
    int full_count;           /* keys collected in scratch by a full recount */
} mk_pair_table;

struct mk_sap;
struct mk_hgrid;
struct mk_sweep;

struct mk_bp {
    mk_allocator alloc;
    size_t bytes;             /* held, for stats */
    mk_bp_def def;
    mk_bp_kind kind;          /* in use */
    int cap;                  /* proxy capacity */
    int live, statics;        /* live proxies (not DYING), static ones among them */
    int hi_slot;              /* slots [0, hi_slot) have ever been used */
    mk_aabb *box;             /* as of the last update (what the structures hold) */
    mk_aabb *next;            /* latest AABB given by the caller */
    void **user;
    uint64_t *cat, *mask;
    uint8_t *gen, *flags;
    uint32_t *free_slots; int free_count;
    uint32_t *dirty; int dirty_count;
    uint32_t *bucket;         /* per slot: scratch of mk_sort_pairs_ */
    mk_pair_table pairs;
    mk_status broken;         /* a failed update: rebuild the structure next time */
    int rebuild;              /* the structure must be rebuilt from scratch */
    int switches, full_rebuilds;
    int sweeps;               /* updates answered by the stateless sweep */
    int swept;                /* the last update was one of them: queries read the sweep */
    int frames_since_choice;
    int sap_losses;           /* SAP: updates whose swaps ran over budget (lost coherence) */
    int losses_at_choice;     /* AUTO: sap_losses when it last chose */
    double moved_share, far_share;  /* AUTO: smoothed motion statistics */
    int crowd_live;           /* AUTO: live proxies at the last crowding count (0: none yet) */
    int crowd_at, crowd_cheap;/* ...its update (frames_since_choice) and its answer */
    struct mk_sap *sap;
    struct mk_hgrid *grid;
    struct mk_sweep *sweep;   /* scratch of mk_sweep_pairs_, made on first use */
};

/* ---- memory (the caller's allocator; NULL means malloc) ---- */
void *mk_bp_alloc_(mk_bp *bp, size_t size);
void mk_bp_free_(mk_bp *bp, void *p, size_t size);
/* Grow *p from old_n to new_n elements of size elem (copying); MK_ERR_* on failure, *p untouched. */
mk_status mk_bp_grow_(mk_bp *bp, void **p, size_t elem, size_t old_n, size_t new_n);

static inline mk_bp_id mk_bp_id_of_(const mk_bp *bp, uint32_t slot) { return (slot << 8) | bp->gen[slot]; }
static inline uint64_t mk_pair_key_(uint32_t a, uint32_t b)
{
    return a < b ? ((uint64_t)a << 32) | b : ((uint64_t)b << 32) | a;
}
/* Closed-interval overlap on all three axes. */
static inline int mk_bp_overlap_(const mk_aabb *a, const mk_aabb *b)
{
    return a->lo.x <= b->hi.x && b->lo.x <= a->hi.x && a->lo.y <= b->hi.y && b->lo.y <= a->hi.y &&
           a->lo.z <= b->hi.z && b->lo.z <= a->hi.z;
}
static inline int mk_bp_both_static_(const mk_bp *bp, uint32_t a, uint32_t b)
{
    return (bp->flags[a] & bp->flags[b] & MK_PF_STATIC) != 0;
}
/* Copies next[] into box[] for every dirty slot. */
void mk_bp_commit_(mk_bp *bp);
/* The built-in filter words and the user callback; 1 = keep. */
int mk_bp_filter_pass_(const mk_bp *bp, uint32_t a, uint32_t b);
/* The same, without a call when there is no filter at all. */
static inline int mk_bp_filter_keeps_(const mk_bp *bp, uint32_t a, uint32_t b)
{
    return (bp->def.filter_mode == MK_BP_FILTER_NONE && !bp->def.filter) || mk_bp_filter_pass_(bp, a, b);
}

/* ---- pair table (bp_pairs.c) ---- */
mk_status mk_pairs_init_(mk_bp *bp, int cap);
void mk_pairs_fini_(mk_bp *bp);
/* Incremental: the pair starts / stops overlapping. add runs the filter for pairs not yet live. */
mk_status mk_pairs_add_(mk_bp *bp, uint32_t a, uint32_t b);
void mk_pairs_remove_(mk_bp *bp, uint32_t a, uint32_t b);
/* Drops LIVE from every pair with a DYING or REFILTER proxy (a scan of all pairs). */
void mk_pairs_drop_flagged_(mk_bp *bp, uint8_t flags);
/* Full recount: begin, add every overlapping pair once, end (which makes the events
 * and refills the table; grid candidates are dropped). A failed add needs no end. */
void mk_pairs_full_begin_(mk_bp *bp);
mk_status mk_pairs_full_add_(mk_bp *bp, uint32_t a, uint32_t b);
void mk_pairs_full_end_(mk_bp *bp);
/* The set alone, without events or entries (pairs_only's stateless updates),
 * from every overlapping pair found once (slots, a < b; the filter runs on
 * each). MK_ERR_CAPACITY / OUT_OF_MEMORY leave the table as it was. */
mk_status mk_pairs_set_from_(mk_bp *bp, const mk_bp_pair *found, int n);
/* Empties the table but keeps the set the caller last saw: the next finish
 * diffs the live entries against it as a whole (the grid's rebuild). */
void mk_pairs_forget_(mk_bp *bp);
/* Entry lookup for the grid: find or insert (state 0); NULL on growth failure (status in *st). */
mk_pair_entry *mk_pairs_get_(mk_bp *bp, uint32_t a, uint32_t b, mk_status *st);
void mk_pairs_touch_(mk_bp *bp, mk_pair_entry *e);
/* Events, set, deletion of dead entries. */
mk_status mk_pairs_finish_(mk_bp *bp);
/* Sort n pair keys ascending; tmp has room for n. A counting sort on the
 * lower slot when the keys outnumber the slots enough, else radix. */
void mk_sort_pairs_(mk_bp *bp, uint64_t *keys, uint64_t *tmp, int n);
/* Sort n keys ascending (LSD radix); tmp has room for n. */
void mk_sort_u64_(uint64_t *keys, uint64_t *tmp, int n);
/* The same on the bytes from from_byte up only; ties keep their order. */
void mk_sort_u64_by_(uint64_t *keys, uint64_t *tmp, int n, int from_byte);

/* ---- stateless sort and sweep (bp_sweep.c) ---- */
/* Reports every overlapping pair of live proxies (no static-static pair)
 * once, in no set order, from the boxes in box[] (report NULL: the pairs
 * of slots, a < b, stay in the sweep's array, mk_sweep_found_, grown by
 * doubling); allocates its scratch on first use. O(n) + one sort + the boxes met in the sweep; right after an
 * update answered by a sweep (bp->swept), the sort starts from that
 * sweep's order (an insertion sort, O(n) on a coherent scene). */
mk_status mk_sweep_pairs_(mk_bp *bp, mk_status (*report)(mk_bp *bp, uint32_t a, uint32_t b));
/* The pairs the last mk_sweep_pairs_ without a report found. */
const mk_bp_pair *mk_sweep_found_(const mk_bp *bp, int *count);
/* The same over a caller's boxes (mk_bp_sweep_boxes, checked there): the
 * pairs of indices, a < b, in the sweep's scratch (grown by doubling). */
mk_status mk_sweep_boxes_(mk_bp *bp, const mk_aabb *boxes, size_t stride, int n, const mk_bp_pair **pairs, int *count);
void mk_sweep_destroy_(mk_bp *bp);
/* The AABB tests mk_sweep_pairs_ would make on the boxes in box[], counted
 * in O(n log n) without making them (AUTO's crowding statistic). Leaves no
 * sweep for mk_sweep_query_ to read. */
mk_status mk_sweep_count_(mk_bp *bp, double *tests);
/* Region query on the boxes of the last mk_sweep_pairs_ (after a stateless
 * update): O(log n + boxes in the rows q spans that start before q ends). */
void mk_sweep_query_(const mk_bp *bp, mk_aabb q, mk_bp_query_fn fn, void *ctx);

/* ---- structures ---- */
mk_status mk_brute_update_(mk_bp *bp);

mk_status mk_sap_create_(mk_bp *bp);
void mk_sap_destroy_(mk_bp *bp);
mk_status mk_sap_update_(mk_bp *bp);   /* incremental, or a full rebuild when bp->rebuild */
void mk_sap_query_(const mk_bp *bp, mk_aabb q, mk_bp_query_fn fn, void *ctx);
long long mk_sap_swaps_(const mk_bp *bp);

mk_status mk_hgrid_create_(mk_bp *bp);
void mk_hgrid_destroy_(mk_bp *bp);
mk_status mk_hgrid_update_(mk_bp *bp); /* incremental, or a full rebuild when bp->rebuild */
void mk_hgrid_query_(const mk_bp *bp, mk_aabb q, mk_bp_query_fn fn, void *ctx);
void mk_hgrid_counts_(const mk_bp *bp, int *levels, int *cells);

#endif

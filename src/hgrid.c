/* hgrid.c: hierarchical hash grid (seed 004) with persistent candidates.
 *
 * Levels have cells of size 2^L. A proxy lives ("native") in the cells its
 * AABB covers on the finest level whose cells are at least its size (the
 * seed's 0.5 <= size/cell <= 1), and is also filed as a "guest" in the cells
 * it covers on every coarser level in use, so any two proxies meet in the
 * cells of the coarser one's level. Cells are stored sparsely in an
 * open-addressing hash of (level, i, j, k), so memory follows the proxies, not
 * the world. Two proxies sharing a cell are a *candidate* pair, kept in the
 * pair table across frames: an update re-files only proxies whose cell range
 * changed (rare under coherent motion), and re-tests the AABBs of candidate
 * pairs with a moved member. Each pair sits in the table once, so it is
 * reported once however many cells the two share. Proxies with an infinite
 * side (planes, slabs) go to an oversized list and are candidates of every
 * proxy. A level stays in use until the next rebuild once it had a proxy.
 * Statics that stay put are not in the cells at all but in a read-only
 * static index (below), which dynamic proxies look up.
 *
 * Re-testing a candidate is skipped while it cannot have changed: each proxy
 * sums how far its faces have moved (travel), and a tested pair stores the
 * summed travel at which its closest gap (or thinnest overlap) could first
 * close. That bound is exact, so the set stays exact; it makes a frame of
 * slow motion cost a few loads per candidate instead of two AABB reads.
 *
 * Cell coordinates are computed in double with exact power-of-two scaling;
 * the level is also kept coarse enough that |coordinate / cell| < 2^41, so
 * far-away specks cannot overflow a cell index. */
#include <math.h>
#include <string.h>

#include "broadphase_internal.h"

#define MK_NONE_ UINT32_MAX
#define MK_GUEST_ 0x80000000u /* in a cell entry: filed there as a guest */
#define MK_BUMP_ 0x80000000u  /* in todo: file one level coarser */
#define MK_LEVEL_MIN_ (-100)
#define MK_LEVEL_MAX_ 1100
#define MK_LEVELS_ (MK_LEVEL_MAX_ - MK_LEVEL_MIN_ + 1)

/* Per-proxy state bits: how it is filed, and what this update did to it. */
enum {
    REG_NONE = 0, REG_CELLS = 1, REG_OVERSIZED = 2,
    REG_INDEXED = 3,  /* a static in the static index (not in any cell) */
    REG_MASK = 3,
    ST_REFILED = 4,   /* filing changed in this update: candidacy must be re-checked */
    ST_DIRTY = 8,     /* moved, created or refiltered in this update */
    ST_REFILTER = 16, /* filter words changed */
    ST_GONE = 32,     /* unfiled in this update */
    ST_SLOW = ST_REFILED | ST_REFILTER | ST_GONE, /* its candidates need the full re-test */
    ST_QUERY = 64,    /* a dynamic proxy that must look for statics in this update */
    ST_TIGHT = 128    /* ...moving fast: look without a margin, it will look again soon */
};

typedef struct mk_cell {
    int64_t c[3];
    int32_t level;
    uint32_t head;      /* first entry, MK_NONE_ if none */
    uint32_t count;
    uint32_t pad_;
} mk_cell;

typedef struct mk_centry { uint32_t who; uint32_t next; } mk_centry; /* who = slot | MK_GUEST_ */
/* The static index: a cell's run of entries (count 0: an empty table slot). */
typedef struct mk_ixcell { uint64_t h; uint32_t start, count; } mk_ixcell;

typedef struct mk_range { int64_t lo[3], hi[3]; } mk_range;

/* The per-proxy fields of the every-update re-test loop, together so that
 * a candidate's re-test touches one cache line per proxy, not two, in 16
 * bytes (a shift to index, 4 records a line). */
typedef struct mk_gproxy {
    double travel;     /* sum over updates of the largest move of any face */
    uint8_t st;        /* REG_* | ST_* */
    uint8_t fast;      /* filed in cells, and fast when it last left its cells (counted in fast[]) */
    int16_t sized_at;  /* filed in cells: the level of its size (level_of) when counted in sized[] */
} mk_gproxy;

/* ...a static's entry: a copy of its box, so a cell is read in one sweep... */
typedef struct mk_ixent { mk_aabb box; uint32_t slot; int32_t level; } mk_ixent; /* slot MK_NONE_: gone */

/* ...and a level: a dense array of cells over the box of its statics'
 * centre cells when that holds at most ~8 cells per static, hashed cells
 * otherwise (statics in far-apart clusters). */
#define MK_IX_LEVELS_ 32 /* statics on yet finer levels stay in the cells */
typedef struct mk_ixlevel {
    int level;
    int first, end;          /* its entries */
    double half;             /* largest half size of its statics */
    int64_t lo[3], hi[3];    /* box of the centre cells */
    int64_t n[3];            /* dense: cells per axis (n[0] = 0: hashed) */
    uint32_t base;           /* dense: its cells in ix_dense */
} mk_ixlevel;

struct mk_hgrid {
    /* per proxy slot */
    int32_t *level;
    mk_range *range;        /* native cell range */
    mk_gproxy *px;          /* what the re-test loop reads, one record per slot */
    double *refile_at;      /* travel at which a face may first reach a cell wall */
    uint32_t *ov_pos;       /* index in oversized[] */
    uint32_t *todo; int todo_count; /* proxies to file in this update (| MK_BUMP_) */
    int updates;            /* since travel was last reset to 0 */
    uint32_t *oversized; int ov_count;
    /* levels */
    int32_t natives[MK_LEVELS_]; /* natives per level */
    int32_t fast[MK_LEVELS_];    /* natives per level that are fast (gproxy.fast) */
    int32_t sized[MK_LEVELS_];   /* proxies in cells per level of their size (gproxy.sized_at) */
    int sized_total, sized_changed;
    int down_level;              /* the size level filed one level finer (MK_LEVEL_MIN_ - 1: none) */
    int up;                      /* every proxy filed one level coarser (choose_up) */
    int up_clock;                /* updates since the grid was made, for choose_up */
    uint8_t used[MK_LEVELS_];    /* level in use since the last rebuild */
    int32_t used_list[MK_LEVELS_]; int used_count; /* ascending */
    /* cells */
    mk_cell *cells; int cell_count, cell_cap, empty_cells;
    uint32_t *index; uint32_t index_cap, index_mask; /* the part in use follows the cells, for locality */
    mk_centry *ent; uint32_t ent_free; int ent_cap, ent_used;
    /* static index: statics as of its last build, in a read-only grid */
    mk_ixent *ix_ent; uint32_t ix_cap;   /* entries: by level, then cell */
    uint64_t *ix_tmp; uint32_t ix_tmp_cap; /* sort keys, twice the entries */
    uint32_t *ix_dense; uint32_t ix_dense_cap; /* dense levels: first entry of each cell, + end */
    mk_ixcell *ix_tab; uint32_t ix_tab_cap, ix_tab_size; /* hashed levels' cells, open addressing */
    uint32_t *ix_pos;        /* per slot: its entry */
    double *swake;           /* per dynamic slot: travel at which a face may first reach an indexed static */
    mk_ixlevel ix_lv[MK_IX_LEVELS_]; int ix_level_count; /* ascending */
    int32_t ix_rank[MK_LEVELS_]; /* build scratch: a level's rank + 1, 0 = not indexed */
    int ix_statics;          /* indexed at the last build */
    int ix_changes;          /* statics created or gone from the index since */
    int ix_off;              /* the last build had no room (fixed capacity): statics are in cells */
    mk_status fail;          /* first growth failure in this update */
};

/* ---- levels and ranges ---- */

/* Exponent arithmetic on the bits of a double: these run for every moved
 * proxy every update, where frexp/ilogb/ldexp/floor calls into libm cost
 * more than the rest of the bookkeeping. */
static int exponent_of(double x) /* ilogb for normal x > 0 */
{
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return (int)((u >> 52) & 0x7ff) - 1023;
}

static int level_of_size(double size)
{
    uint64_t u;
    if (!(size >= 0x1p-100)) return MK_LEVEL_MIN_;
    memcpy(&u, &size, sizeof u);
    /* smallest L with 2^L >= size: the exponent, plus one unless size is a power of two */
    return exponent_of(size) + ((u & 0xfffffffffffffull) != 0);
}

static int is_oversized(const mk_aabb *b)
{
    const mk_real *lo = &b->lo.x, *hi = &b->hi.x;
    int k;
    for (k = 0; k < 3; ++k)
        if (!((double)hi[k] - (double)lo[k] <= 1e300)) return 1; /* an infinite side */
    return 0;
}

/* The two lower bounds on a proxy's level: its size (cells at least as big
 * as the box) and its distance from the origin (cell indices below 2^41). */
static void level_bounds(const mk_aabb *b, int *by_size, int *by_coord)
{
    const mk_real *lo = &b->lo.x, *hi = &b->hi.x;
    double size = 0, far = 0;
    int k;
    for (k = 0; k < 3; ++k) {
        double s = (double)hi[k] - (double)lo[k], a = fabs((double)lo[k]), c = fabs((double)hi[k]);
        if (s > size) size = s;
        if (a > far) far = a;
        if (c > far) far = c;
    }
    /* A box one ulp over a power of two still counts as that power: unit
     * cubes should share one level, not split between two by rounding. */
    *by_size = level_of_size(size * (1 - 0x1p-30));
    *by_coord = far >= 0x1p-60 ? exponent_of(far) - 40 : MK_LEVEL_MIN_;
}

/* 2^-level, exact: the scaling in cell_coord is then an exact product. */
static double inv_cell(int level)
{
    uint64_t u = (uint64_t)(1023 - level) << 52;
    double d;
    memcpy(&d, &u, sizeof d);
    return d;
}

static int level_of(const mk_aabb *b)
{
    int l, lc;
    level_bounds(b, &l, &lc);
    return lc > l ? lc : l;
}

/* A filed proxy keeps its level while its size stays within a factor of two
 * of the ideal: rounding makes a unit cube measure 1 - ulp or 1 + ulp from
 * frame to frame, and every level change re-files all its cells. Any level
 * is correct (cell ranges come from the boxes); the choice only sets cost. */
static int keeps_level(const mk_aabb *b, int own, int *native)
{
    int l, lc;
    level_bounds(b, &l, &lc);
    *native = lc > l ? lc : l;
    return lc <= own && l >= own - 1 && l <= own + 1;
}

/* A move of a quarter of a cell or more per update (but less than a jump of
 * several cells, which is a teleport, not speed) is fast. */
static int is_fast(double moved, int level)
{
    double speed = moved * inv_cell(level);
    return speed >= 0.25 && speed < 4;
}

/* Fast movers cross a cell wall nearly every update, and re-filing is what
 * their updates cost: they are filed one level coarser (half the walls,
 * fewer cells) while most natives of their size level are fast too. Only
 * then: opening a coarser level makes every finer proxy its guest, which
 * a level of slow proxies would pay for on every re-filing. */
static int wants_bump(const struct mk_hgrid *g, int native, double moved)
{
    return native < MK_LEVEL_MAX_ && is_fast(moved, native) && 2 * g->fast[native - MK_LEVEL_MIN_] > g->natives[native - MK_LEVEL_MIN_];
}


/* The coarsest size level is filed one level finer while the proxies of
 * finer sizes outnumber it more than MK_DOWN_RATIO_ to 1. Every finer proxy
 * is its guest, and a guest meets every native whose cells hold its own:
 * with cells 1-2 times a native's size that is (size + cell)^3 / size^3 =
 * 8-27 times the volume the two could overlap in (mixed sizes 1..100, 10k:
 * 113k of 120k candidates had a native of the top level, 8% of them
 * overlapping). Cells half as big cut that to 3-8 times, for about 2.5
 * times the cells per native; finer levels have fewer guests, and there
 * the cells cost more than they save (measured: mk_bp_update 8.9 M
 * instructions a frame, 7.0 M with the top level one finer, 7.5 M with the
 * top two). */
#define MK_DOWN_RATIO_ 4
static void choose_down_level(struct mk_hgrid *g)
{
    int i = MK_LEVELS_ - 1, top;
    g->down_level = MK_LEVEL_MIN_ - 1;
    g->sized_changed = 0;
    while (i > 0 && g->sized[i] == 0) --i;
    top = g->sized[i];
    if (i > 0 && g->sized_total - top > MK_DOWN_RATIO_ * top) g->down_level = i + MK_LEVEL_MIN_;
}

/* Boxes of one size lined up in a thin cluster (a corridor: 90% of them in
 * a tube two sizes wide) share their cells on the tube's two thin axes
 * anyway: there, cells twice as big add candidates only along the tube
 * (4/3 as many: 10k boxes, 32k -> 46k) while halving the cell-wall
 * crossings and the cells per box (8 -> 3.4), and the grid is 15-20%
 * faster (bench_broadphase corridor 10k, same runs: grid / sweep 1.32-1.46
 * -> 1.05-1.10). In a volume or a slab (at most one such axis) the
 * candidates grow 1.8-2.4x and it is slower. So, with a single size in
 * use: every 32 updates, up to 256 candidates are sampled; when on two
 * axes nearly all of them (90%, 85% to stay) overlap, everything is filed
 * one level coarser: the grid is rebuilt when that changes (at most every
 * 32 updates, the first time at the second update). */
#define MK_UP_SAMPLE_ 256
static void choose_up(const mk_bp *bp, struct mk_hgrid *g)
{
    const mk_pair_entry *e = bp->pairs.e;
    int i, k, n = 0, sat = 0, stride = bp->pairs.count / MK_UP_SAMPLE_ + 1, hit[3] = {0, 0, 0};
    int top = MK_LEVELS_ - 1;
    while (top > 0 && g->sized[top] == 0) --top;
    /* one size (two neighbouring levels: a float box of size 1 measures
     * 1 +- a few ulps of its coordinates) */
    if (g->sized_total == 0 || g->sized[top] + (top > 0 ? g->sized[top - 1] : 0) != g->sized_total) { g->up = 0; return; }
    for (i = 0; i < bp->pairs.count; i += stride) {
        uint32_t a = (uint32_t)(e[i].key >> 32), b = (uint32_t)e[i].key;
        const mk_real *al = &bp->box[a].lo.x, *ah = &bp->box[a].hi.x, *bl = &bp->box[b].lo.x, *bh = &bp->box[b].hi.x;
        if (!(e[i].state & MK_PS_CAND) || (g->px[a].st & REG_MASK) != REG_CELLS || (g->px[b].st & REG_MASK) != REG_CELLS) continue;
        for (k = 0; k < 3; ++k) hit[k] += al[k] <= bh[k] && bl[k] <= ah[k];
        ++n;
    }
    if (n < MK_UP_SAMPLE_ / 4) return; /* too few to judge: as it is */
    for (k = 0; k < 3; ++k) sat += hit[k] * 100 >= n * (g->up ? 85 : 90);
    g->up = sat >= 2;
}

static void count_sized(struct mk_hgrid *g, uint32_t slot, int size_level, int add)
{
    if (add) g->px[slot].sized_at = (int16_t)size_level;
    g->sized[g->px[slot].sized_at - MK_LEVEL_MIN_] += add ? 1 : -1;
    g->sized_total += add ? 1 : -1;
    g->sized_changed = 1;
}

/* floor(x) for |x| < 2^41, without a call into libm (these run several
 * times per moved proxy per update). */
static int64_t floor_small(double x)
{
    int64_t i = (int64_t)x;
    return i - (x < (double)i);
}

/* floor(v * inv) for |v * inv| < 2^41 (guaranteed by level_of). */
static int64_t cell_coord(mk_real v, double inv) { return floor_small((double)v * inv); }

/* The cells of box b grown by `margin` cells on every side. Re-filings of
 * slow boxes use 1/16 (fat_range), so a box jittering across a cell wall is
 * not re-filed every frame; any superset of the box's own cells is correct.
 * Returns 0 when a coordinate is infinite or beyond the 2^41 index bound:
 * the proxy then needs a new level or the oversized list. */
static int range_with_margin(const mk_aabb *b, int level, double margin, mk_range *r)
{
    double inv = inv_cell(level);
    int k;
    for (k = 0; k < 3; ++k) {
        double lo = (double)(&b->lo.x)[k] * inv - margin, hi = (double)(&b->hi.x)[k] * inv + margin;
        if (!(lo > -0x1p41 && hi < 0x1p41)) return 0;
        r->lo[k] = floor_small(lo);
        r->hi[k] = floor_small(hi);
    }
    return 1;
}

static int fat_range(const mk_aabb *b, int level, mk_range *r) { return range_with_margin(b, level, 0.0625, r); }
static int range_fits(const mk_aabb *b, int level, mk_range *r) { return range_with_margin(b, level, 0, r); }

static void range_at(const mk_aabb *b, int level, mk_range *r)
{
    double inv = inv_cell(level);
    int k;
    for (k = 0; k < 3; ++k) {
        r->lo[k] = cell_coord((&b->lo.x)[k], inv);
        r->hi[k] = cell_coord((&b->hi.x)[k], inv);
    }
}

/* floor(x / 2^d), portable for negative x. */
static int64_t floor_shift(int64_t x, int d)
{
    if (d >= 62) return x < 0 ? -1 : 0;
    return x >= 0 ? x >> d : -((-(x + 1)) >> d) - 1;
}

/* A proxy's cells on a coarser level are its native cells scaled down: its
 * guest filing is a function of the native range alone, so filing and
 * unfiling can never disagree. */
static void coarser(const mk_range *native, int d, mk_range *out)
{
    int k;
    for (k = 0; k < 3; ++k) {
        out->lo[k] = floor_shift(native->lo[k], d);
        out->hi[k] = floor_shift(native->hi[k], d);
    }
}

/* How far box b's faces may move before leaving r, the cells it is filed in
 * at level (negative once they have left). */
static double wall_room(const mk_aabb *b, const mk_range *r, int level)
{
    double c = 1 / inv_cell(level), room = HUGE_VAL;
    int k;
    for (k = 0; k < 3; ++k) {
        /* inside means wall_lo <= lo and hi < wall_hi: a face on the upper
         * wall is already in the next cell */
        double d0 = (double)(&b->lo.x)[k] - (double)r->lo[k] * c, d1 = (double)(r->hi[k] + 1) * c - (double)(&b->hi.x)[k];
        if (!(d0 >= 0 && d1 > 0)) return -1; /* NaN (infinite sides) too */
        if (d0 < room) room = d0;
        if (d1 < room) room = d1;
    }
    return room;
}

/* The travel at which a proxy with that much room must be looked at again;
 * shrunk like the wakes, so rounding can only make it come early. */
static double room_until(double travel, double room)
{
    return travel + room * (1 - 0x1p-20) - travel * 0x1p-36;
}

static int range_eq(const mk_range *a, const mk_range *b) { return memcmp(a, b, sizeof *a) == 0; }

static int ranges_meet(const mk_range *a, const mk_range *b)
{
    return a->lo[0] <= b->hi[0] && b->lo[0] <= a->hi[0] && a->lo[1] <= b->hi[1] && b->lo[1] <= a->hi[1] &&
           a->lo[2] <= b->hi[2] && b->lo[2] <= a->hi[2];
}

static void use_level_list(struct mk_hgrid *g, int level)
{
    int i = g->used_count++;
    while (i > 0 && g->used_list[i - 1] > level) { g->used_list[i] = g->used_list[i - 1]; --i; }
    g->used_list[i] = level;
    g->used[level - MK_LEVEL_MIN_] = 1;
}

/* ---- cells ---- */

static uint32_t cell_hash(int level, const int64_t *c, uint32_t mask)
{
    uint64_t h = (uint64_t)c[0] * 0x9E3779B97F4A7C15ull;
    h ^= (uint64_t)c[1] * 0xC2B2AE3D27D4EB4Full;
    h ^= (uint64_t)c[2] * 0x165667B19E3779F9ull;
    h ^= (uint64_t)(uint32_t)level * 0x27D4EB2F165667C5ull;
    h ^= h >> 29;
    h *= 0xBF58476D1CE4E5B9ull;
    return (uint32_t)(h >> 32) & mask;
}

static int cell_is(const mk_cell *cell, int level, const int64_t *c)
{
    return cell->c[0] == c[0] && cell->c[1] == c[1] && cell->c[2] == c[2] && cell->level == level;
}

static uint32_t *cell_slot(const struct mk_hgrid *g, int level, const int64_t *c)
{
    uint32_t h = cell_hash(level, c, g->index_mask);
    for (;;) {
        uint32_t i = g->index[h];
        if (i == MK_NONE_ || cell_is(&g->cells[i], level, c)) return &g->index[h];
        h = (h + 1) & g->index_mask;
    }
}

static void index_rebuild(struct mk_hgrid *g)
{
    int i;
    memset(g->index, 0xff, (size_t)(g->index_mask + 1) * sizeof *g->index);
    for (i = 0; i < g->cell_count; ++i) *cell_slot(g, g->cells[i].level, g->cells[i].c) = (uint32_t)i;
}

/* Empty cells stay where they are until they outnumber the others: a
 * fast mover leaves a trail of them, and deleting each at once (a
 * backward shift in the index, a cell moved into its place) costs several
 * cache misses; re-entering one costs none. Then all go in one pass. */
static void compact_cells(struct mk_hgrid *g)
{
    int i, n = 0;
    for (i = 0; i < g->cell_count; ++i)
        if (g->cells[i].count) g->cells[n++] = g->cells[i];
    g->cell_count = n;
    g->empty_cells = 0;
    index_rebuild(g);
}

static mk_status grow_cells(mk_bp *bp, struct mk_hgrid *g)
{
    int cap = g->cell_cap * 2;
    uint32_t isize = g->index_cap * 2;
    void *cells = g->cells, *index = NULL;
    mk_status st;
    if (bp->def.fixed_capacity || cap > INT32_MAX / 4) return MK_ERR_CAPACITY;
    if (!(index = mk_bp_alloc_(bp, isize * sizeof(uint32_t)))) return MK_ERR_OUT_OF_MEMORY;
    if ((st = mk_bp_grow_(bp, &cells, sizeof(mk_cell), (size_t)g->cell_cap, (size_t)cap)) != MK_OK) {
        mk_bp_free_(bp, index, isize * sizeof(uint32_t));
        return st;
    }
    mk_bp_free_(bp, g->index, (size_t)g->index_cap * sizeof(uint32_t));
    g->cells = (mk_cell *)cells;
    g->cell_cap = cap;
    g->index = (uint32_t *)index;
    g->index_cap = isize;
    g->index_mask = isize - 1;
    index_rebuild(g);
    return MK_OK;
}

static mk_status grow_entries(mk_bp *bp, struct mk_hgrid *g)
{
    int cap = g->ent_cap * 2, i;
    void *p = g->ent;
    mk_status st;
    if (bp->def.fixed_capacity || cap > INT32_MAX / 4) return MK_ERR_CAPACITY;
    if ((st = mk_bp_grow_(bp, &p, sizeof(mk_centry), (size_t)g->ent_cap, (size_t)cap)) != MK_OK) return st;
    g->ent = (mk_centry *)p;
    for (i = g->ent_cap; i < cap; ++i) g->ent[i].next = i + 1 < cap ? (uint32_t)i + 1 : g->ent_free;
    g->ent_free = (uint32_t)g->ent_cap;
    g->ent_cap = cap;
    return MK_OK;
}

/* The cell, created empty if needed; NULL when it could not grow. */
static mk_cell *cell_get(mk_bp *bp, struct mk_hgrid *g, int level, const int64_t *c)
{
    uint32_t *s = cell_slot(g, level, c);
    mk_cell *cell;
    if (*s != MK_NONE_) return &g->cells[*s];
    if (2 * (uint32_t)g->cell_count >= g->index_mask && g->index_mask + 1 < g->index_cap) {
        g->index_mask = g->index_mask * 2 + 1; /* more of the allocated index, at most half full */
        index_rebuild(g);
        s = cell_slot(g, level, c);
    }
    /* Full: compact when that frees a quarter of the pool (compacting for a
     * few empty cells would repeat a pass over every cell every few new
     * ones; mixed 10k: -2.5 % instructions a frame), or any room when the
     * pool may not grow. */
    if (g->cell_count == g->cell_cap && g->empty_cells > (bp->def.fixed_capacity ? 0 : g->cell_cap / 4)) {
        compact_cells(g);
        s = cell_slot(g, level, c);
    }
    if (g->cell_count == g->cell_cap) {
        mk_status st = grow_cells(bp, g);
        if (st != MK_OK) { if (g->fail == MK_OK) g->fail = st; return NULL; }
        s = cell_slot(g, level, c);
    }
    *s = (uint32_t)g->cell_count;
    cell = &g->cells[g->cell_count++];
    cell->c[0] = c[0]; cell->c[1] = c[1]; cell->c[2] = c[2];
    cell->level = level;
    cell->head = MK_NONE_;
    cell->count = 0;
    g->empty_cells++; /* until cell_add */
    return cell;
}

static int cell_add(mk_bp *bp, struct mk_hgrid *g, mk_cell *cell, uint32_t who)
{
    uint32_t e;
    if (g->ent_free == MK_NONE_) {
        mk_status st = grow_entries(bp, g);
        if (st != MK_OK) { if (g->fail == MK_OK) g->fail = st; return 0; }
    }
    e = g->ent_free;
    g->ent_free = g->ent[e].next;
    g->ent[e].who = who;
    g->ent[e].next = cell->head;
    cell->head = e;
    if (cell->count++ == 0) g->empty_cells--;
    g->ent_used++;
    return 1;
}

static void cell_remove(struct mk_hgrid *g, int level, const int64_t *c, uint32_t who)
{
    uint32_t i = *cell_slot(g, level, c), *link, e;
    mk_cell *cell;
    if (i == MK_NONE_) return; /* only after a failed filing; the rebuild that follows cleans up */
    cell = &g->cells[i];
    for (link = &cell->head; (e = *link) != MK_NONE_; link = &g->ent[e].next) {
        if (g->ent[e].who != who) continue;
        *link = g->ent[e].next;
        g->ent[e].next = g->ent_free;
        g->ent_free = e;
        g->ent_used--;
        if (--cell->count == 0) g->empty_cells++;
        return;
    }
}

/* ---- filing ---- */

static void candidate(mk_bp *bp, struct mk_hgrid *g, uint32_t a, uint32_t b)
{
    mk_status st = MK_OK;
    mk_pair_entry *e;
    if (a == b || mk_bp_both_static_(bp, a, b)) return;
    if (!(e = mk_pairs_get_(bp, a, b, &st))) { if (g->fail == MK_OK) g->fail = st; return; }
    if (!(e->state & MK_PS_CAND)) {
        e->state |= MK_PS_CAND;
        mk_pairs_touch_(bp, e);
    }
}

static int in_range(const mk_range *r, const int64_t *c)
{
    return r && c[0] >= r->lo[0] && c[0] <= r->hi[0] && c[1] >= r->lo[1] && c[1] <= r->hi[1] && c[2] >= r->lo[2] && c[2] <= r->hi[2];
}

/* Is c the first cell (lowest on every axis) where ranges a and b meet? */
static int first_shared(const mk_range *a, const mk_range *b, const int64_t *c)
{
    int k;
    for (k = 0; k < 3; ++k)
        if (c[k] != (a->lo[k] > b->lo[k] ? a->lo[k] : b->lo[k])) return 0;
    return 1;
}

/* Files `slot` into every cell of r at `level` outside `skip` (the cells it
 * is already in), and meets the proxies there: all of them on its own level,
 * only natives on coarser levels (guests there are finer than their natives
 * and meet `slot` on their own level). A native of this level sharing
 * several cells is met only in the first: a hash lookup saved per extra
 * cell. If that cell is in `skip`, the two already share it: a candidate. */
static void file_range(mk_bp *bp, struct mk_hgrid *g, uint32_t slot, int level, const mk_range *r, const mk_range *skip, int guest)
{
    int64_t c[3];
    for (c[0] = r->lo[0]; c[0] <= r->hi[0]; ++c[0])
        for (c[1] = r->lo[1]; c[1] <= r->hi[1]; ++c[1])
            for (c[2] = r->lo[2]; c[2] <= r->hi[2]; ++c[2]) {
                mk_cell *cell;
                uint32_t e;
                if (in_range(skip, c)) continue;
                if (!(cell = cell_get(bp, g, level, c))) return;
                for (e = cell->head; e != MK_NONE_; e = g->ent[e].next) {
                    uint32_t who = g->ent[e].who;
                    if (who & MK_GUEST_) { if (!guest) candidate(bp, g, slot, who & ~MK_GUEST_); }
                    else if (first_shared(r, &g->range[who], c)) candidate(bp, g, slot, who);
                }
                /* cell_add may move cells (growth): do it last, cell not used after */
                if (!cell_add(bp, g, cell, slot | (guest ? MK_GUEST_ : 0))) return;
            }
}

/* Takes `slot` out of every cell of r at `level` outside `keep`. */
static void unfile_range(struct mk_hgrid *g, uint32_t slot, int level, const mk_range *r, const mk_range *keep, int guest)
{
    int64_t c[3];
    for (c[0] = r->lo[0]; c[0] <= r->hi[0]; ++c[0])
        for (c[1] = r->lo[1]; c[1] <= r->hi[1]; ++c[1])
            for (c[2] = r->lo[2]; c[2] <= r->hi[2]; ++c[2])
                if (!in_range(keep, c)) cell_remove(g, level, c, slot | (guest ? MK_GUEST_ : 0));
}

static int range_within(const mk_range *a, const mk_range *b)
{
    return a->lo[0] >= b->lo[0] && a->hi[0] <= b->hi[0] && a->lo[1] >= b->lo[1] && a->hi[1] <= b->hi[1] &&
           a->lo[2] >= b->lo[2] && a->hi[2] <= b->hi[2];
}

/* Moves slot's filing on one level from range o to range n, touching only
 * the cells that differ. Only a range that lost cells can lose candidates:
 * one that just grew leaves its old candidates alone (new ones come with
 * wake 0, so they are tested anyway). */
static void refile_range(mk_bp *bp, struct mk_hgrid *g, uint32_t slot, int level, const mk_range *o, const mk_range *n, int guest)
{
    unfile_range(g, slot, level, o, n, guest);
    file_range(bp, g, slot, level, n, o, guest);
    if (!range_within(o, n)) g->px[slot].st |= ST_REFILED;
}

static void ov_add(struct mk_hgrid *g, uint32_t slot)
{
    g->ov_pos[slot] = (uint32_t)g->ov_count;
    g->oversized[g->ov_count++] = slot;
}

static void ov_remove(struct mk_hgrid *g, uint32_t slot)
{
    uint32_t p = g->ov_pos[slot], last = g->oversized[--g->ov_count];
    g->oversized[p] = last;
    g->ov_pos[last] = p;
}

/* Removes slot from every cell it is filed in. */
static void unfile(struct mk_hgrid *g, uint32_t slot)
{
    int i;
    if ((g->px[slot].st & REG_MASK) == REG_OVERSIZED) ov_remove(g, slot);
    if ((g->px[slot].st & REG_MASK) == REG_CELLS) {
        int own = g->level[slot];
        unfile_range(g, slot, own, &g->range[slot], NULL, 0);
        for (i = 0; i < g->used_count; ++i) {
            mk_range r;
            if (g->used_list[i] <= own) continue;
            coarser(&g->range[slot], g->used_list[i] - own, &r);
            unfile_range(g, slot, g->used_list[i], &r, NULL, 1);
        }
        g->natives[own - MK_LEVEL_MIN_]--;
        count_sized(g, slot, 0, 0);
        g->fast[own - MK_LEVEL_MIN_] -= g->px[slot].fast;
        g->px[slot].fast = 0;
    }
    g->px[slot].st = (uint8_t)((g->px[slot].st & ~REG_MASK) | ST_GONE);
}

/* A level comes into use: every finer proxy already filed becomes its guest. */
static void open_level(mk_bp *bp, struct mk_hgrid *g, int level)
{
    uint32_t s;
    use_level_list(g, level);
    for (s = 0; s < (uint32_t)bp->hi_slot && g->fail == MK_OK; ++s) {
        mk_range r;
        if ((g->px[s].st & REG_MASK) != REG_CELLS || g->level[s] >= level) continue;
        coarser(&g->range[s], level - g->level[s], &r);
        file_range(bp, g, s, level, &r, NULL, 1);
    }
}

/* The level to file box b at: its size's (*size), one coarser if bump (a
 * fast mover), one finer if that is the down level (choose_down_level) and
 * cell indices stay in bounds. */
static int filing_level(const struct mk_hgrid *g, const mk_aabb *b, int bump, int *size)
{
    int l, lc;
    level_bounds(b, &l, &lc);
    *size = lc > l ? lc : l;
    if (bump || g->up) return *size < MK_LEVEL_MAX_ ? *size + 1 : *size;
    return *size == g->down_level && *size - 1 >= lc ? *size - 1 : *size;
}

/* Files slot at filing_level. */
static void file(mk_bp *bp, struct mk_hgrid *g, uint32_t slot, int bump)
{
    const mk_aabb *b = &bp->box[slot];
    int i, own, size;
    uint32_t s;
    g->px[slot].st |= ST_REFILED;
    if (is_oversized(b)) {
        /* Everything is its candidate, filed or oversized. */
        for (s = 0; s < (uint32_t)bp->hi_slot; ++s)
            if (g->px[s].st & REG_MASK) candidate(bp, g, slot, s);
        g->px[slot].st = (uint8_t)((g->px[slot].st & ~REG_MASK) | REG_OVERSIZED);
        g->refile_at[slot] = 0;
        ov_add(g, slot);
        return;
    }
    own = filing_level(g, b, bump, &size);
    if (!g->used[own - MK_LEVEL_MIN_]) open_level(bp, g, own);
    g->level[slot] = own;
    g->natives[own - MK_LEVEL_MIN_]++;
    count_sized(g, slot, size, 1);
    g->px[slot].st = (uint8_t)((g->px[slot].st & ~REG_MASK) | REG_CELLS);
    range_at(b, own, &g->range[slot]); /* first filing: tight; re-filings add the margin */
    g->refile_at[slot] = room_until(g->px[slot].travel, wall_room(b, &g->range[slot], own));
    file_range(bp, g, slot, own, &g->range[slot], NULL, 0);
    for (i = 0; i < g->used_count; ++i) {
        mk_range r;
        if (g->used_list[i] <= own) continue;
        coarser(&g->range[slot], g->used_list[i] - own, &r);
        file_range(bp, g, slot, g->used_list[i], &r, NULL, 1);
    }
    for (i = 0; i < g->ov_count; ++i) candidate(bp, g, slot, g->oversized[i]);
}

/* A moved proxy that keeps its level is re-filed in place, cell by cell;
 * returns 0 when it must be unfiled and filed again (new level, oversized),
 * one level coarser if *bump. */
static int refile_in_place(mk_bp *bp, struct mk_hgrid *g, uint32_t slot, const mk_aabb *nb, double moved, int *bump)
{
    int own = g->level[slot], i, native;
    mk_range r, o, old = g->range[slot];
    double room;
    if ((g->px[slot].st & REG_MASK) == REG_OVERSIZED && is_oversized(nb)) return 1; /* still everyone's candidate */
    if ((g->px[slot].st & REG_MASK) != REG_CELLS) return 0;
    room = wall_room(nb, &old, own);
    if (room >= 0) { g->refile_at[slot] = room_until(g->px[slot].travel, room); return 1; }
    /* Left its cells. The level is only reconsidered now: while the box
     * stays within them its size cannot be far off. */
    if (is_fast(moved, own) != g->px[slot].fast) { /* speed as of its last wall crossing */
        g->px[slot].fast ^= 1;
        g->fast[own - MK_LEVEL_MIN_] += g->px[slot].fast ? 1 : -1;
    }
    if (!keeps_level(nb, own, &native)) return 0;
    *bump = wants_bump(g, native, moved);
    if (g->up) { if (own != native + 1 && native < MK_LEVEL_MAX_) return 0; } /* file chooses */
    else if (*bump ? own != native + 1 : own > native && moved * inv_cell(native) < 0.0625) return 0;
    /* in or out of the down level: filed again (file chooses) */
    else if (!*bump && (native == g->down_level) != (own == native - 1)) return 0;
    if (native != g->px[slot].sized_at) { count_sized(g, slot, 0, 0); count_sized(g, slot, native, 1); }
    /* The margin pays for slow or jittering boxes; a box moving more than
     * the margin per update would leave it anyway, and gets its bare cells. */
    if (moved * inv_cell(own) < 0.0625) { if (!fat_range(nb, own, &r)) return 0; }
    else if (!range_fits(nb, own, &r)) return 0;
    g->refile_at[slot] = room_until(g->px[slot].travel, wall_room(nb, &r, own));
    refile_range(bp, g, slot, own, &old, &r, 0);
    g->range[slot] = r;
    /* Cell walls of coarser levels are walls of this one too. */
    for (i = g->used_count - 1; i >= 0 && g->used_list[i] > own; --i) {
        mk_range n;
        coarser(&r, g->used_list[i] - own, &n);
        coarser(&old, g->used_list[i] - own, &o);
        if (!range_eq(&n, &o)) refile_range(bp, g, slot, g->used_list[i], &o, &n, 1);
    }
    return 1;
}

/* ---- the per-update re-test of candidates ---- */

/* Do a and b (both filed) still share a cell? */
static int still_candidates(const struct mk_hgrid *g, uint32_t a, uint32_t b)
{
    mk_range r;
    int ra = g->px[a].st & REG_MASK, rb = g->px[b].st & REG_MASK;
    if (ra == REG_OVERSIZED || rb == REG_OVERSIZED) return 1;
    if (ra != REG_CELLS || rb != REG_CELLS) return 0; /* an indexed static is in no cell */
    if (g->level[a] == g->level[b]) return ranges_meet(&g->range[a], &g->range[b]);
    if (g->level[a] < g->level[b]) { coarser(&g->range[a], g->level[b] - g->level[a], &r); return ranges_meet(&r, &g->range[b]); }
    coarser(&g->range[b], g->level[a] - g->level[b], &r);
    return ranges_meet(&r, &g->range[a]);
}

/* How far apart (> 0) or how deep in each other (>= 0) two boxes are: the
 * largest gap over the axes, or the thinnest overlap. Either can change by
 * at most the two boxes' travel. */
static double margin(const mk_aabb *a, const mk_aabb *b, int overlapping)
{
    const mk_real *al = &a->lo.x, *ah = &a->hi.x, *bl = &b->lo.x, *bh = &b->hi.x;
    double m = overlapping ? HUGE_VAL : 0;
    int k;
    for (k = 0; k < 3; ++k) {
        double x = (double)bl[k] - (double)ah[k], y = (double)al[k] - (double)bh[k];
        if (overlapping) { if (-x < m) m = -x; if (-y < m) m = -y; }
        else { if (x > m) m = x; if (y > m) m = y; }
    }
    return m;
}

/* The travel sum at which the pair must be tested again, rounded down to a
 * float: slightly early is safe, late is not. The shrink factors cover the
 * rounding of the gap and of the travel sums. */
static float wake_at(double sum, double m)
{
    double w = sum + m * (1 - 0x1p-20) - sum * 0x1p-36;
    if (!(w > 0)) return 0;
    if (w > 3e38) return 3e38f;
    return (float)(w * (1 - 0x1p-22));
}

/* One member in cells, the other in the static index: the pairs the static
 * queries keep. */
static int index_pair(uint8_t sa, uint8_t sb)
{
    int ra = sa & REG_MASK, rb = sb & REG_MASK;
    return (ra == REG_INDEXED && rb == REG_CELLS) || (ra == REG_CELLS && rb == REG_INDEXED);
}

static uint32_t next_state(const mk_bp *bp, struct mk_hgrid *g, uint32_t a, uint32_t b, mk_pair_entry *e)
{
    const uint32_t pair_bits = MK_PS_CAND | MK_PS_STATIC | MK_PS_LIVE | MK_PS_REJECTED;
    uint32_t s = e->state;
    uint8_t sa = g->px[a].st, sb = g->px[b].st;
    int overlap;
    double m;
    /* A static that left the index meets its partners in cells again. */
    if ((s & MK_PS_STATIC) && !index_pair(sa, sb)) { s &= ~(uint32_t)MK_PS_STATIC; e->wake = 0; }
    if (!(sa & REG_MASK) || !(sb & REG_MASK) || !(s & (MK_PS_CAND | MK_PS_STATIC))) return s & ~pair_bits;
    if (!(s & MK_PS_STATIC) && ((sa | sb) & ST_REFILED) && !still_candidates(g, a, b)) return s & ~pair_bits;
    if ((sa | sb) & ST_REFILTER) s &= ~(uint32_t)(MK_PS_LIVE | MK_PS_REJECTED);
    else if (g->px[a].travel + g->px[b].travel < (double)e->wake) return s;
    overlap = mk_bp_overlap_(&bp->box[a], &bp->box[b]);
    m = margin(&bp->box[a], &bp->box[b], overlap);
    e->wake = wake_at(g->px[a].travel + g->px[b].travel, m);
    if (!overlap) {
        /* An index pair lives only while it overlaps: the queries find it
         * again. The dynamic member's last query saw this static overlapping,
         * so its static wake does not cover the gap that just opened: it
         * must look again once it may have closed it (a box bouncing on the
         * ground would be missed otherwise). */
        if (s & MK_PS_STATIC) {
            uint32_t d = (sa & REG_MASK) == REG_CELLS ? a : b;
            double w = room_until(g->px[d].travel, m);
            if (w < g->swake[d]) g->swake[d] = w;
        }
        return s & ~(uint32_t)(MK_PS_LIVE | MK_PS_REJECTED | MK_PS_STATIC);
    }
    if (s & (MK_PS_LIVE | MK_PS_REJECTED)) return s;
    return s | (mk_bp_filter_keeps_(bp, a, b) ? MK_PS_LIVE : MK_PS_REJECTED);
}

/* An index pair whose dynamic member looked up its statics in this update
 * (and neither member changed its filter words): it overlaps if and only
 * if the look-up found it (FOUND), and the look-up's swake already covers
 * the gap of one it did not find. */
#define MK_INDEX_BITS_ (MK_PS_STATIC | MK_PS_FOUND | MK_PS_LIVE | MK_PS_REJECTED)
static int looked_up(uint32_t state, uint8_t sa, uint8_t sb)
{
    return (state & MK_PS_STATIC) && ((sa | sb) & (ST_QUERY | ST_REFILTER)) == ST_QUERY && index_pair(sa, sb);
}

static void retest(mk_bp *bp, struct mk_hgrid *g, int all)
{
    /* locals: the loop's common path reads only these, and the compiler
     * cannot keep them in registers across the rare calls below */
    mk_pair_entry *ent = bp->pairs.e;
    const mk_gproxy *px = g->px;
    const int count = bp->pairs.count;
    int i;
    for (i = 0; i < count; ++i) {
        mk_pair_entry *e = &ent[i];
        uint32_t a = (uint32_t)(e->key >> 32), b = (uint32_t)e->key, s, old;
        const mk_gproxy *pa = &px[a], *pb = &px[b];
        uint8_t sab = pa->st | pb->st;
        /* the common case: both filed as before, too little travel to matter
         * (every entry here has CAND: the grid sets it on insertion) */
        if (!all && !(sab & ST_DIRTY)) continue;
        old = e->state;
        if (looked_up(old, pa->st, pb->st)) s = old & MK_PS_FOUND ? old & ~(uint32_t)MK_PS_FOUND : old & ~(uint32_t)MK_INDEX_BITS_;
        else if (!(sab & ST_SLOW) && pa->travel + pb->travel < (double)e->wake) continue;
        else s = next_state(bp, g, a, b, e) & ~(uint32_t)MK_PS_FOUND;
        e->state = s;
        if ((s ^ old) & MK_PS_KEEP) mk_pairs_touch_(bp, e);
    }
}

/* Every 256 updates travel restarts from 0, with every wake, so the sums
 * stay small enough for the float wakes to keep their precision. */
static void restart_travel(mk_bp *bp, struct mk_hgrid *g)
{
    int i;
    if (++g->updates < 256) return;
    g->updates = 0;
    for (i = 0; i < bp->hi_slot; ++i) g->px[i].travel = g->refile_at[i] = g->swake[i] = 0;
    for (i = 0; i < bp->pairs.count; ++i) bp->pairs.e[i].wake = 0;
}

/* The largest move of any face from box o to box n (NaN when a side is
 * infinite). Runs for every mover every update: maxima without branches,
 * and the NaN (inf - inf) caught once by the sum of the moves, which a
 * NaN makes NaN (a NaN travel fails every "cannot have changed" test, so
 * the proxy is always looked at). */
static double face_travel(const mk_aabb *o, const mk_aabb *n)
{
    double a = fabs((double)n->lo.x - (double)o->lo.x), b = fabs((double)n->lo.y - (double)o->lo.y);
    double c = fabs((double)n->lo.z - (double)o->lo.z), d = fabs((double)n->hi.x - (double)o->hi.x);
    double e = fabs((double)n->hi.y - (double)o->hi.y), f = fabs((double)n->hi.z - (double)o->hi.z);
    double sum = ((a + b) + (c + d)) + (e + f);
    a = a > b ? a : b;
    c = c > d ? c : d;
    e = e > f ? e : f;
    a = a > c ? a : c;
    a = a > e ? a : e;
    return sum == sum ? a : sum;
}

/* ---- the static index ----
 *
 * Statics that have not moved since the index was built sit in a read-only
 * grid instead of the cells. Each is listed once, with a copy of its box, in
 * the cell holding its centre one level above its own (cells 2-4 times its
 * size: the measured best trade between cells looked up and boxes tested);
 * a query widens its box by the largest half size on that level. The lists
 * are packed in one array sorted by cell, so a cell's statics are read in
 * one sweep. Nothing there changes from frame to frame, so statics cost
 * nothing per update; a dynamic proxy looks up the statics around it only
 * when its travel may have closed the smallest gap it saw last time (swake).
 * Pairs found that way carry MK_PS_STATIC and live while they overlap. A
 * static that is created, moved or destroyed leaves the index (its entry is
 * blanked) for the cells; the index is rebuilt with the whole grid once such
 * changes reach a quarter of it. */

/* A 64-bit hash of an index cell; the table slot keeps all of it, and a
 * match is confirmed against the first entry of the run. */
static uint64_t ix_hash(int level, const int64_t *c)
{
    uint64_t h = (uint64_t)(uint32_t)level * 0x27D4EB2F165667C5ull;
    int k;
    for (k = 0; k < 3; ++k) {
        h ^= (uint64_t)c[k] * 0x9E3779B97F4A7C15ull;
        h = (h ^ (h >> 31)) * 0xBF58476D1CE4E5B9ull;
    }
    return h ^ (h >> 29);
}

static int is_indexable(const mk_bp *bp, uint32_t s)
{
    return (bp->flags[s] & (MK_PF_ALIVE | MK_PF_DYING | MK_PF_STATIC)) == (MK_PF_ALIVE | MK_PF_STATIC) && !is_oversized(&bp->box[s]);
}

/* Grows *p (elem bytes each) to at least n, without keeping the contents. */
static int ix_room(mk_bp *bp, void **p, size_t elem, uint32_t *cap, uint32_t n)
{
    uint32_t c = n + n / 4 + 64;
    void *q;
    if (n <= *cap) return 1;
    if (bp->def.fixed_capacity || !(q = mk_bp_alloc_(bp, elem * c))) return 0;
    mk_bp_free_(bp, *p, elem * *cap);
    *p = q;
    *cap = c;
    return 1;
}

/* The index level of a static is its own plus MK_IX_UP_: cells 2 to 4
 * times its size (measured best between cells looked up and boxes tested). */
#define MK_IX_UP_ 1
static void centre_cell(const mk_aabb *b, int level, int64_t *c)
{
    double inv = inv_cell(level);
    int k;
    for (k = 0; k < 3; ++k) c[k] = floor_small(0.5 * ((double)(&b->lo.x)[k] + (double)(&b->hi.x)[k]) * inv);
}

static int entry_in(const mk_ixent *e, int level, const int64_t *c)
{
    int64_t ec[3];
    if (e->level != level) return 0;
    centre_cell(&e->box, level, ec);
    return ec[0] == c[0] && ec[1] == c[1] && ec[2] == c[2];
}

/* The run of cell (level, c) of a hashed level, or NULL. */
static const mk_ixcell *ix_find(const struct mk_hgrid *g, int level, const int64_t *c)
{
    uint64_t h = ix_hash(level, c);
    uint32_t mask = g->ix_tab_size - 1, i = (uint32_t)h & mask;
    for (;; i = (i + 1) & mask) {
        const mk_ixcell *x = &g->ix_tab[i];
        if (x->count == 0) return NULL;
        if (x->h == h && entry_in(&g->ix_ent[x->start], level, c)) return x;
    }
}

/* Cell number within a dense level's box (row-major, x fastest). */
static uint64_t dense_index(const mk_ixlevel *lv, const int64_t *c)
{
    return (uint64_t)(c[0] - lv->lo[0]) + (uint64_t)lv->n[0] * ((uint64_t)(c[1] - lv->lo[1]) + (uint64_t)lv->n[1] * (uint64_t)(c[2] - lv->lo[2]));
}

/* Sort key: the level's rank, then the cell number (dense levels) or 11
 * bits of each coordinate interleaved (hashed levels, where cells sharing a
 * key are split apart by group_runs), then the slot. */
static uint64_t ix_sort_key(const struct mk_hgrid *g, int rank, const int64_t *c, uint32_t slot)
{
    const mk_ixlevel *lv = &g->ix_lv[rank];
    uint64_t m = 0;
    int b, k;
    if (lv->n[0]) m = dense_index(lv, c);
    else
        for (b = 0; b < 11; ++b)
            for (k = 0; k < 3; ++k) m |= (((uint64_t)c[k] >> b) & 1) << (3 * b + k);
    return ((uint64_t)rank << 35 | m) << 24 | slot;
}

static int same_cell(const struct mk_hgrid *g, uint64_t a, uint64_t b)
{
    uint32_t sa = (uint32_t)(a & 0xffffff), sb = (uint32_t)(b & 0xffffff);
    return g->level[sa] == g->level[sb] && memcmp(g->range[sa].lo, g->range[sb].lo, sizeof g->range[sa].lo) == 0;
}

/* keys sorted: makes the statics of each cell adjacent where cells share a
 * key (hashed levels only, rare; quadratic in such a run, which is short). */
static void group_runs(const struct mk_hgrid *g, uint64_t *keys, int n)
{
    int i, j;
    for (i = 1; i < n; ++i) {
        uint64_t t;
        if ((keys[i] >> 24) != (keys[i - 1] >> 24) || same_cell(g, keys[i], keys[i - 1])) continue;
        /* keys[i] starts another cell: pull the rest of the previous cell's run forward */
        for (j = i + 1; j < n && (keys[j] >> 24) == (keys[i] >> 24); ++j)
            if (same_cell(g, keys[j], keys[i - 1])) break;
        if (j == n || (keys[j] >> 24) != (keys[i] >> 24)) continue;
        t = keys[j];
        memmove(keys + i + 1, keys + i, (size_t)(j - i) * sizeof *keys);
        keys[i] = t;
    }
}

static void ix_add_run(struct mk_hgrid *g, uint32_t start, uint32_t count)
{
    const mk_ixent *e = &g->ix_ent[start];
    uint32_t mask = g->ix_tab_size - 1;
    uint64_t h = ix_hash(e->level, g->range[e->slot].lo);
    uint32_t i = (uint32_t)h & mask;
    while (g->ix_tab[i].count) i = (i + 1) & mask;
    g->ix_tab[i].h = h; g->ix_tab[i].start = start; g->ix_tab[i].count = count;
}

/* Levels of the statics, ranked in ascending order (the first
 * MK_IX_LEVELS_ are indexed, finer ones stay in the cells), with the box
 * of their centre cells and whether a dense array of cells fits in about
 * 8 per static; returns the statics indexed and sets *cells and *hashed. */
static int ix_levels(mk_bp *bp, struct mk_hgrid *g, uint32_t *cells, uint32_t *hashed)
{
    int32_t *rank = g->ix_rank; /* per level: count, then rank + 1 */
    uint32_t s;
    int l, n = 0, k;
    memset(rank, 0, sizeof g->ix_rank);
    for (s = 0; s < (uint32_t)bp->hi_slot; ++s)
        if (is_indexable(bp, s)) rank[(g->level[s] = level_of(&bp->box[s]) + MK_IX_UP_) - MK_LEVEL_MIN_]++;
    g->ix_level_count = 0;
    for (l = 0; l < MK_LEVELS_; ++l) {
        mk_ixlevel *lv = &g->ix_lv[g->ix_level_count];
        if (!rank[l] || g->ix_level_count == MK_IX_LEVELS_) { rank[l] = 0; continue; }
        memset(lv, 0, sizeof *lv);
        lv->level = l + MK_LEVEL_MIN_;
        for (k = 0; k < 3; ++k) { lv->lo[k] = INT64_MAX; lv->hi[k] = INT64_MIN; }
        rank[l] = ++g->ix_level_count;
    }
    for (s = 0; s < (uint32_t)bp->hi_slot; ++s) {
        mk_ixlevel *lv;
        if (!is_indexable(bp, s) || !rank[g->level[s] - MK_LEVEL_MIN_]) continue;
        lv = &g->ix_lv[rank[g->level[s] - MK_LEVEL_MIN_] - 1];
        centre_cell(&bp->box[s], g->level[s], g->range[s].lo);
        for (k = 0; k < 3; ++k) {
            double h = 0.5 * ((double)(&bp->box[s].hi.x)[k] - (double)(&bp->box[s].lo.x)[k]);
            if (g->range[s].lo[k] < lv->lo[k]) lv->lo[k] = g->range[s].lo[k];
            if (g->range[s].lo[k] > lv->hi[k]) lv->hi[k] = g->range[s].lo[k];
            if (h > lv->half) lv->half = h;
        }
        lv->end++; /* a count for now */
        ++n;
    }
    *cells = *hashed = 0;
    for (l = 0; l < g->ix_level_count; ++l) {
        mk_ixlevel *lv = &g->ix_lv[l];
        double c = 1;
        for (k = 0; k < 3; ++k) c *= (double)lv->hi[k] - (double)lv->lo[k] + 1;
        if (c <= 8.0 * lv->end + 64) {
            for (k = 0; k < 3; ++k) lv->n[k] = lv->hi[k] - lv->lo[k] + 1;
            lv->base = *cells;
            *cells += (uint32_t)c + 1;
        } else {
            *hashed += (uint32_t)lv->end;
        }
    }
    return n;
}

/* Fills the index from the finite statics (after reset_cells). For an
 * indexed static, g->level[s] is its index level and g->range[s].lo its
 * centre cell there. */
static void ix_build(mk_bp *bp, struct mk_hgrid *g)
{
    uint32_t s, cells, hashed, tab = 16, i0;
    int i, n, l;
    uint64_t *keys;
    g->ix_statics = g->ix_changes = 0;
    n = ix_levels(bp, g, &cells, &hashed);
    while (tab < 2 * hashed) tab *= 2;
    g->ix_off = n > 0 && !(ix_room(bp, (void **)&g->ix_ent, sizeof *g->ix_ent, &g->ix_cap, (uint32_t)n) &&
                           ix_room(bp, (void **)&g->ix_tmp, 2 * sizeof *g->ix_tmp, &g->ix_tmp_cap, (uint32_t)n) &&
                           ix_room(bp, (void **)&g->ix_dense, sizeof *g->ix_dense, &g->ix_dense_cap, cells) &&
                           (!hashed || ix_room(bp, (void **)&g->ix_tab, sizeof *g->ix_tab, &g->ix_tab_cap, tab)));
    if (n == 0 || g->ix_off) { g->ix_level_count = 0; return; }
    if (hashed) {
        g->ix_tab_size = tab; /* a power of two, within the room */
        memset(g->ix_tab, 0, (size_t)tab * sizeof *g->ix_tab);
    }
    keys = g->ix_tmp;
    for (s = 0, n = 0; s < (uint32_t)bp->hi_slot; ++s) {
        int r;
        if (!is_indexable(bp, s) || !(r = g->ix_rank[g->level[s] - MK_LEVEL_MIN_])) continue;
        g->px[s].st = REG_INDEXED;
        g->refile_at[s] = 0; /* any move takes it out */
        keys[n++] = ix_sort_key(g, r - 1, g->range[s].lo, s);
    }
    g->ix_statics = n;
    mk_sort_u64_(keys, keys + n, n);
    group_runs(g, keys, n);
    for (i = 0; i < n; ++i) {
        uint32_t slot = (uint32_t)(keys[i] & 0xffffff);
        g->ix_ent[i].box = bp->box[slot];
        g->ix_ent[i].slot = slot;
        g->ix_ent[i].level = g->level[slot];
        g->ix_pos[slot] = (uint32_t)i;
    }
    /* each level's entries are one block; cells are runs within it */
    for (l = 0, i = 0; l < g->ix_level_count; ++l) {
        mk_ixlevel *lv = &g->ix_lv[l];
        int end = i + lv->end;
        lv->first = i;
        lv->end = end;
        if (lv->n[0]) {
            uint64_t c, nc = (uint64_t)lv->n[0] * (uint64_t)lv->n[1] * (uint64_t)lv->n[2];
            for (c = 0; c <= nc; ++c) {
                while (i < end && dense_index(lv, g->range[g->ix_ent[i].slot].lo) < c) ++i;
                g->ix_dense[lv->base + c] = (uint32_t)i;
            }
            i = end;
            continue;
        }
        for (i0 = (uint32_t)i; i < end; ++i)
            if (i + 1 == end || !same_cell(g, g->ix_ent[i].slot, g->ix_ent[i + 1].slot)) {
                ix_add_run(g, i0, (uint32_t)i + 1 - i0);
                i0 = (uint32_t)i + 1;
            }
    }
}

/* Takes a static out of the index (it moved or went). */
static void ix_remove(struct mk_hgrid *g, uint32_t s)
{
    g->ix_ent[g->ix_pos[s]].slot = MK_NONE_;
    g->ix_changes++;
}

/* The cells of q widened by `grow` at level, if there are at most `most`
 * of them and they are within the index bound of cell coordinates. The
 * widening carries a relative slack so rounding of centres and sizes cannot
 * leave out a cell. */
static int query_range(const mk_aabb *q, int level, double grow, double most, mk_range *r)
{
    double inv = inv_cell(level), cells = 1;
    int k;
    for (k = 0; k < 3; ++k) {
        double a = (double)(&q->lo.x)[k], b = (double)(&q->hi.x)[k];
        double lo = (a - grow - fabs(a) * 0x1p-40 - grow * 0x1p-30) * inv;
        double hi = (b + grow + fabs(b) * 0x1p-40 + grow * 0x1p-30) * inv;
        if (!(lo > -0x1p41 && hi < 0x1p41)) return 0;
        r->lo[k] = floor_small(lo);
        r->hi[k] = floor_small(hi);
        cells *= (double)(r->hi[k] - r->lo[k] + 1);
    }
    return cells <= most;
}

typedef int (*ix_fn)(void *ctx, uint32_t slot, const mk_aabb *box);

/* fn for the indexed statics among entries [from, to) whose box meets q. */
static int visit_run(const struct mk_hgrid *g, uint32_t from, uint32_t to, const mk_aabb *q, ix_fn fn, void *ctx)
{
    const mk_ixent *e = g->ix_ent + from, *end = g->ix_ent + to;
    for (; e < end; ++e)
        if (e->slot != MK_NONE_ && mk_bp_overlap_(&e->box, q) && !fn(ctx, e->slot, &e->box)) return 0;
    return 1;
}

/* The cells r of a dense level (clipped to it), row by row: a row of cells
 * along x is one run of entries, and the rows are a fixed stride apart in
 * the level's array of cells. */
static int visit_dense(const struct mk_hgrid *g, const mk_ixlevel *lv, const mk_range *r, const mk_aabb *q, ix_fn fn, void *ctx)
{
    size_t plane = lv->base + (size_t)dense_index(lv, r->lo), nx = (size_t)(r->hi[0] - r->lo[0] + 1);
    size_t sy = (size_t)lv->n[0], sz = (size_t)lv->n[0] * (size_t)lv->n[1];
    int64_t y, z;
    for (z = r->lo[2]; z <= r->hi[2]; ++z, plane += sz) {
        size_t row = plane;
        for (y = r->lo[1]; y <= r->hi[1]; ++y, row += sy)
            if (!visit_run(g, g->ix_dense[row], g->ix_dense[row + nx], q, fn, ctx)) return 0;
    }
    return 1;
}

/* Calls fn once for every indexed static whose box meets q; stops when fn
 * returns 0. */
static int ix_visit(const struct mk_hgrid *g, const mk_aabb *q, ix_fn fn, void *ctx)
{
    int i, k;
    for (i = 0; i < g->ix_level_count; ++i) {
        const mk_ixlevel *lv = &g->ix_lv[i];
        mk_range r;
        int64_t c[3];
        if (!query_range(q, lv->level, lv->half, (double)(lv->end - lv->first), &r)) {
            if (!visit_run(g, (uint32_t)lv->first, (uint32_t)lv->end, q, fn, ctx)) return 0;
            continue;
        }
        if (lv->n[0]) {
            for (k = 0; k < 3; ++k) { /* clipped to the level's cells */
                if (r.lo[k] < lv->lo[k]) r.lo[k] = lv->lo[k];
                if (r.hi[k] > lv->hi[k]) r.hi[k] = lv->hi[k];
                if (r.lo[k] > r.hi[k]) break;
            }
            if (k < 3) continue;
            if (!visit_dense(g, lv, &r, q, fn, ctx)) return 0;
            continue;
        }
        for (c[0] = r.lo[0]; c[0] <= r.hi[0]; ++c[0])
            for (c[1] = r.lo[1]; c[1] <= r.hi[1]; ++c[1])
                for (c[2] = r.lo[2]; c[2] <= r.hi[2]; ++c[2]) {
                    const mk_ixcell *cell = ix_find(g, lv->level, c);
                    if (cell && !visit_run(g, cell->start, cell->start + cell->count, q, fn, ctx)) return 0;
                }
    }
    return 1;
}

typedef struct static_query_ { mk_bp *bp; struct mk_hgrid *g; uint32_t d; mk_aabb q; double room; } static_query_;

/* An overlapping static becomes (or stays) an index pair; a separate one
 * bounds how far d may travel before it must look again. */
static int meet_static(void *c, uint32_t t, const mk_aabb *box)
{
    static_query_ *q = (static_query_ *)c;
    mk_bp *bp = q->bp;
    const mk_aabb *b = &bp->box[q->d];
    mk_pair_entry *e;
    mk_status st = MK_OK;
    uint32_t old;
    if (!mk_bp_overlap_(b, box)) {
        double m = margin(b, box, 0);
        if (m < q->room) q->room = m;
        return 1;
    }
    if (!(e = mk_pairs_get_(bp, q->d, t, &st))) { if (q->g->fail == MK_OK) q->g->fail = st; return 0; }
    old = e->state;
    /* FOUND tells the re-test of this update that the pair overlaps, so it
     * need not read the boxes again; wake 0: the first re-test of an update
     * without a look-up reads them. */
    e->wake = 0;
    e->state |= MK_PS_STATIC | MK_PS_FOUND;
    if (!(old & (MK_PS_LIVE | MK_PS_REJECTED))) e->state |= mk_bp_filter_keeps_(bp, q->d, t) ? MK_PS_LIVE : MK_PS_REJECTED;
    if ((e->state ^ old) & MK_PS_LIVE) mk_pairs_touch_(bp, e);
    return 1;
}

/* The statics around dynamic proxy d (filed in cells, box committed): within
 * a margin of an eighth of its cell, or none for a fast mover, which will be
 * back next update anyway. */
static void query_statics(mk_bp *bp, struct mk_hgrid *g, uint32_t d, int tight)
{
    const mk_aabb *b = &bp->box[d];
    mk_real m = tight ? 0 : (mk_real)(0.125 / inv_cell(g->level[d]));
    static_query_ sq;
    int k;
    sq.q.lo = mk_v3_sub(b->lo, mk_v3(m, m, m));
    sq.q.hi = mk_v3_add(b->hi, mk_v3(m, m, m));
    sq.bp = bp; sq.g = g; sq.d = d; sq.room = m;
    for (k = 0; k < 3; ++k) { /* the margin as rounded */
        double lo = (double)(&b->lo.x)[k] - (double)(&sq.q.lo.x)[k], hi = (double)(&sq.q.hi.x)[k] - (double)(&b->hi.x)[k];
        if (lo < sq.room) sq.room = lo;
        if (hi < sq.room) sq.room = hi;
    }
    if (ix_visit(g, &sq.q, meet_static, &sq)) g->swake[d] = room_until(g->px[d].travel, sq.room > 0 ? sq.room : 0);
    else g->swake[d] = 0;
}

static void query_all_statics(mk_bp *bp, struct mk_hgrid *g, int all)
{
    int i, n = all ? bp->hi_slot : bp->dirty_count;
    if (g->ix_statics == 0) return;
    for (i = 0; i < n && g->fail == MK_OK; ++i) {
        uint32_t s = all ? (uint32_t)i : bp->dirty[i];
        uint8_t st = g->px[s].st;
        if ((st & REG_MASK) != REG_CELLS || (bp->flags[s] & MK_PF_STATIC) || (!all && !(st & ST_QUERY))) continue;
        query_statics(bp, g, s, !all && (st & ST_TIGHT));
    }
}

/* ---- lifetime ---- */

typedef struct grid_array_ { void **p; size_t elem; } grid_array_;
static int grid_arrays(struct mk_hgrid *g, grid_array_ *a)
{
    int n = 0;
    a[n].p = (void **)&g->level; a[n++].elem = sizeof *g->level;
    a[n].p = (void **)&g->range; a[n++].elem = sizeof *g->range;
    a[n].p = (void **)&g->px; a[n++].elem = sizeof *g->px;
    a[n].p = (void **)&g->refile_at; a[n++].elem = sizeof *g->refile_at;
    a[n].p = (void **)&g->ov_pos; a[n++].elem = sizeof *g->ov_pos;
    a[n].p = (void **)&g->todo; a[n++].elem = sizeof *g->todo;
    a[n].p = (void **)&g->oversized; a[n++].elem = sizeof *g->oversized;
    a[n].p = (void **)&g->ix_pos; a[n++].elem = sizeof *g->ix_pos;
    a[n].p = (void **)&g->swake; a[n++].elem = sizeof *g->swake;
    return n;
}

/* Empties the cells, with the part of the index in use sized for about
 * `expect` cells: a sparse index spread over the allocation would cost a
 * cache miss per lookup. */
static void reset_cells(struct mk_hgrid *g, int proxies, int expect)
{
    int i;
    g->cell_count = g->empty_cells = 0;
    for (g->index_mask = 63; g->index_mask + 1 < g->index_cap && g->index_mask < 2u * (uint32_t)expect; g->index_mask = g->index_mask * 2 + 1) {}
    memset(g->index, 0xff, (size_t)(g->index_mask + 1) * sizeof *g->index);
    for (i = 0; i < g->ent_cap; ++i) g->ent[i].next = i + 1 < g->ent_cap ? (uint32_t)i + 1 : MK_NONE_;
    g->ent_free = 0;
    g->ent_used = 0;
    for (i = 0; i < proxies; ++i) g->px[i].st = g->px[i].fast = 0;
    memset(g->natives, 0, sizeof g->natives);
    memset(g->fast, 0, sizeof g->fast);
    memset(g->sized, 0, sizeof g->sized);
    g->sized_total = g->sized_changed = 0;
    g->down_level = MK_LEVEL_MIN_ - 1;
    memset(g->used, 0, sizeof g->used);
    g->used_count = 0;
    g->ov_count = 0;
}

mk_status mk_hgrid_create_(mk_bp *bp)
{
    struct mk_hgrid *g;
    grid_array_ a[9];
    int n, i;
    if (!(g = (struct mk_hgrid *)mk_bp_alloc_(bp, sizeof *g))) return MK_ERR_OUT_OF_MEMORY;
    memset(g, 0, sizeof *g);
    bp->grid = g;
    n = grid_arrays(g, a);
    for (i = 0; i < n; ++i)
        if (!(*a[i].p = mk_bp_alloc_(bp, a[i].elem * (size_t)bp->cap))) goto fail;
    /* A proxy covers 8 cells of its own level at most, 27 once re-filed with
     * a margin, plus a guest cell or two per coarser level. Growing pools
     * start at the typical need; fixed ones get room for 27 cells and 32
     * filings per proxy, which a wide spread of sizes can still exceed. */
    g->cell_cap = (bp->def.fixed_capacity ? 27 : 2) * bp->cap + 64;
    g->ent_cap = (bp->def.fixed_capacity ? 32 : 4) * bp->cap + 64;
    g->index_cap = 64;
    while (g->index_cap < (uint32_t)g->cell_cap * 2) g->index_cap *= 2;
    if (!(g->cells = (mk_cell *)mk_bp_alloc_(bp, sizeof(mk_cell) * (size_t)g->cell_cap))) goto fail;
    if (!(g->ent = (mk_centry *)mk_bp_alloc_(bp, sizeof(mk_centry) * (size_t)g->ent_cap))) goto fail;
    if (!(g->index = (uint32_t *)mk_bp_alloc_(bp, sizeof(uint32_t) * (size_t)g->index_cap))) goto fail;
    memset(g->px, 0, sizeof *g->px * (size_t)bp->cap);
    memset(g->refile_at, 0, sizeof *g->refile_at * (size_t)bp->cap);
    memset(g->swake, 0, sizeof *g->swake * (size_t)bp->cap);
    reset_cells(g, bp->cap, 0);
    return MK_OK;
fail:
    mk_hgrid_destroy_(bp);
    return MK_ERR_OUT_OF_MEMORY;
}

void mk_hgrid_destroy_(mk_bp *bp)
{
    struct mk_hgrid *g = bp->grid;
    grid_array_ a[9];
    int n, i;
    if (!g) return;
    n = grid_arrays(g, a);
    for (i = 0; i < n; ++i) mk_bp_free_(bp, *a[i].p, a[i].elem * (size_t)bp->cap);
    mk_bp_free_(bp, g->cells, sizeof(mk_cell) * (size_t)g->cell_cap);
    mk_bp_free_(bp, g->ent, sizeof(mk_centry) * (size_t)g->ent_cap);
    if (g->index) mk_bp_free_(bp, g->index, sizeof(uint32_t) * (size_t)g->index_cap);
    mk_bp_free_(bp, g->ix_ent, sizeof *g->ix_ent * (size_t)g->ix_cap);
    mk_bp_free_(bp, g->ix_tmp, sizeof *g->ix_tmp * 2 * (size_t)g->ix_tmp_cap);
    mk_bp_free_(bp, g->ix_dense, sizeof *g->ix_dense * (size_t)g->ix_dense_cap);
    mk_bp_free_(bp, g->ix_tab, sizeof *g->ix_tab * (size_t)g->ix_tab_cap);
    mk_bp_free_(bp, g, sizeof *g);
    bp->grid = NULL;
}

void mk_hgrid_counts_(const mk_bp *bp, int *levels, int *cells)
{
    *levels = bp->grid ? bp->grid->used_count : 0;
    *cells = bp->grid ? bp->grid->cell_count - bp->grid->empty_cells : 0;
}

/* ---- update ---- */

static int in_structure(const mk_bp *bp, uint32_t s)
{
    return (bp->flags[s] & (MK_PF_ALIVE | MK_PF_DYING)) == MK_PF_ALIVE;
}

static void rebuild(mk_bp *bp, struct mk_hgrid *g)
{
    uint32_t s;
    reset_cells(g, bp->cap, 4 * (bp->live - bp->statics) + 64);
    mk_pairs_forget_(bp);
    mk_bp_commit_(bp);
    ix_build(bp, g);
    /* Choose the down level from all sizes, then open every level, so
     * nobody is filed as a guest one level at a time. */
    for (s = 0; s < (uint32_t)bp->hi_slot; ++s)
        if (in_structure(bp, s) && !is_oversized(&bp->box[s]) && g->px[s].st != REG_INDEXED)
            g->sized[level_of(&bp->box[s]) - MK_LEVEL_MIN_]++, g->sized_total++;
    choose_down_level(g);
    memset(g->sized, 0, sizeof g->sized); /* file() counts them again */
    g->sized_total = 0;
    for (s = 0; s < (uint32_t)bp->hi_slot; ++s) {
        int l, size;
        if (!in_structure(bp, s) || is_oversized(&bp->box[s]) || g->px[s].st == REG_INDEXED) continue;
        l = filing_level(g, &bp->box[s], 0, &size);
        if (!g->used[l - MK_LEVEL_MIN_]) use_level_list(g, l);
    }
    for (s = 0; s < (uint32_t)bp->hi_slot && g->fail == MK_OK; ++s)
        if (in_structure(bp, s) && g->px[s].st != REG_INDEXED) file(bp, g, s, 0);
    query_all_statics(bp, g, 1);
}

/* Statics created or moved out of the index cost like dynamic proxies (and
 * meet each other's cells): rebuild once they are a quarter of it. */
static int index_stale(const struct mk_hgrid *g)
{
    return !g->ix_off && g->ix_changes > g->ix_statics / 4 + 64;
}

/* A changed proxy, with its old box still in place: mark it, add up its
 * travel, re-file it if it crossed a cell wall... */
static void take_change(mk_bp *bp, struct mk_hgrid *g, uint32_t s)
{
    uint8_t f = bp->flags[s];
    double moved;
    int reg = g->px[s].st & REG_MASK, bump = 0;
    g->px[s].st |= (uint8_t)(ST_DIRTY | ((f & MK_PF_REFILTER) ? ST_REFILTER : 0));
    if (reg == REG_INDEXED && (f & (MK_PF_DYING | MK_PF_MOVED))) ix_remove(g, s);
    if (f & MK_PF_DYING) { unfile(g, s); return; }
    if (f & MK_PF_NEW) {
        g->todo[g->todo_count++] = s;
        if (f & MK_PF_STATIC) g->ix_changes++;
        else g->px[s].st |= ST_QUERY;
        return;
    }
    if (!(f & MK_PF_MOVED)) return;
    moved = face_travel(&bp->box[s], &bp->next[s]);
    g->px[s].travel += moved;
    if (g->ix_statics && !(g->px[s].travel < g->swake[s])) /* a gap to a static may have closed */
        g->px[s].st |= (uint8_t)(ST_QUERY | (reg == REG_CELLS && moved * inv_cell(g->level[s]) >= 0.0625 ? ST_TIGHT : 0));
    if (g->px[s].travel < g->refile_at[s]) return; /* no face can have reached a wall */
    if (!refile_in_place(bp, g, s, &bp->next[s], moved, &bump)) {
        unfile(g, s);
        g->todo[g->todo_count++] = s | (bump ? MK_BUMP_ : 0);
        g->px[s].st |= ST_QUERY;
    }
}

/* ...and commits each new box once its old one is no longer needed (the
 * commit of mk_bp_commit_, without a second pass over the dirty list). */
static void take_changes(mk_bp *bp, struct mk_hgrid *g)
{
    int i;
    for (i = 0; i < bp->dirty_count; ++i) {
        uint32_t s = bp->dirty[i];
        take_change(bp, g, s);
        bp->box[s] = bp->next[s];
    }
}

mk_status mk_hgrid_update_(mk_bp *bp)
{
    struct mk_hgrid *g;
    mk_status st;
    int i, all = bp->rebuild;
    if (!bp->grid && (st = mk_hgrid_create_(bp)) != MK_OK) return st;
    g = bp->grid;
    g->fail = MK_OK;
    g->todo_count = 0;
    if (!all && index_stale(g)) {
        all = 1;
        bp->full_rebuilds++;
    }
    if (!all && g->up_clock++ % 32 == 1) {
        int was = g->up;
        choose_up(bp, g);
        if (g->up != was) {
            all = 1;
            bp->full_rebuilds++;
        }
    }
    if (all) {
        rebuild(bp, g);
    } else {
        if (g->empty_cells > g->cell_count / 2) compact_cells(g);
        if (g->sized_changed) choose_down_level(g);
        restart_travel(bp, g);
        take_changes(bp, g);
        for (i = 0; i < g->todo_count && g->fail == MK_OK; ++i) file(bp, g, g->todo[i] & ~MK_BUMP_, g->todo[i] >= MK_BUMP_);
        query_all_statics(bp, g, 0);
    }
    if (g->fail == MK_OK) retest(bp, g, all);
    if (all) {
        for (i = 0; i < bp->hi_slot; ++i) g->px[i].st &= REG_MASK;
    } else {
        for (i = 0; i < bp->dirty_count; ++i) g->px[bp->dirty[i]].st &= REG_MASK;
    }
    if (g->fail != MK_OK) return g->fail;
    bp->rebuild = 0;
    return MK_OK;
}

/* ---- region query ---- */

static void linear_query(const mk_bp *bp, const struct mk_hgrid *g, mk_aabb q, mk_bp_query_fn fn, void *ctx)
{
    uint32_t s;
    for (s = 0; s < (uint32_t)bp->hi_slot; ++s)
        if ((g->px[s].st & REG_MASK) && mk_bp_overlap_(&bp->box[s], &q) && !fn(ctx, mk_bp_id_of_(bp, s), bp->user[s])) return;
}

/* Cells the query covers over all levels, or -1 if that is beyond reason
 * (or beyond int64): then a linear scan is cheaper. */
static double cells_covered(const struct mk_hgrid *g, const mk_aabb *q)
{
    double total = 0;
    int i, k;
    for (i = 0; i < g->used_count; ++i) {
        double n = 1;
        for (k = 0; k < 3; ++k) {
            double lo = floor((double)(&q->lo.x)[k] * inv_cell(g->used_list[i]));
            double hi = floor((double)(&q->hi.x)[k] * inv_cell(g->used_list[i]));
            if (!(hi - lo < 4e18) || !(fabs(lo) < 4e18) || !(fabs(hi) < 4e18)) return -1;
            n *= hi - lo + 1;
        }
        total += n;
    }
    return total;
}

typedef struct region_query_ { const mk_bp *bp; const mk_aabb *q; mk_bp_query_fn fn; void *ctx; } region_query_;

static int region_visit(void *c, uint32_t s, const mk_aabb *box)
{
    region_query_ *r = (region_query_ *)c;
    return !mk_bp_overlap_(box, r->q) || r->fn(r->ctx, mk_bp_id_of_(r->bp, s), r->bp->user[s]);
}

void mk_hgrid_query_(const mk_bp *bp, mk_aabb q, mk_bp_query_fn fn, void *ctx)
{
    const struct mk_hgrid *g = bp->grid;
    region_query_ rq;
    double covered;
    int i;
    if (!g) return;
    covered = cells_covered(g, &q);
    if (covered < 0 || covered > (double)(g->cell_count + 16)) { linear_query(bp, g, q, fn, ctx); return; }
    for (i = 0; i < g->ov_count; ++i) {
        uint32_t s = g->oversized[i];
        if (mk_bp_overlap_(&bp->box[s], &q) && !fn(ctx, mk_bp_id_of_(bp, s), bp->user[s])) return;
    }
    rq.bp = bp; rq.q = &q; rq.fn = fn; rq.ctx = ctx;
    if (!ix_visit(g, &q, region_visit, &rq)) return;
    for (i = 0; i < g->used_count; ++i) {
        int level = g->used_list[i], k;
        mk_range r;
        int64_t c[3];
        range_at(&q, level, &r);
        for (c[0] = r.lo[0]; c[0] <= r.hi[0]; ++c[0])
            for (c[1] = r.lo[1]; c[1] <= r.hi[1]; ++c[1])
                for (c[2] = r.lo[2]; c[2] <= r.hi[2]; ++c[2]) {
                    uint32_t ci = *cell_slot(g, level, c), e;
                    if (ci == MK_NONE_) continue;
                    for (e = g->cells[ci].head; e != MK_NONE_; e = g->ent[e].next) {
                        uint32_t s = g->ent[e].who;
                        const mk_range *pr;
                        if (s & MK_GUEST_) continue;
                        pr = &g->range[s];
                        /* Report s only in the first cell it shares with the query. */
                        for (k = 0; k < 3; ++k)
                            if (c[k] != (pr->lo[k] > r.lo[k] ? pr->lo[k] : r.lo[k])) break;
                        if (k < 3 || !mk_bp_overlap_(&bp->box[s], &q)) continue;
                        if (!fn(ctx, mk_bp_id_of_(bp, s), bp->user[s])) return;
                    }
                }
    }
}

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
#define MK_GUEST_ 0x80000000u
#define MK_LEVEL_MIN_ (-100)
#define MK_LEVEL_MAX_ 1100
#define MK_LEVELS_ (MK_LEVEL_MAX_ - MK_LEVEL_MIN_ + 1)

/* Per-proxy state bits: how it is filed, and what this update did to it. */
enum {
    REG_NONE = 0, REG_CELLS = 1, REG_OVERSIZED = 2, REG_MASK = 3,
    ST_REFILED = 4,   /* filing changed in this update: candidacy must be re-checked */
    ST_DIRTY = 8,     /* moved, created or refiltered in this update */
    ST_REFILTER = 16, /* filter words changed */
    ST_GONE = 32,     /* unfiled in this update */
    ST_SLOW = ST_REFILED | ST_REFILTER | ST_GONE /* its candidates need the full re-test */
};

typedef struct mk_cell {
    int64_t c[3];
    int32_t level;
    uint32_t head;      /* first entry, MK_NONE_ if none */
    uint32_t count;
    uint32_t pad_;
} mk_cell;

typedef struct mk_centry { uint32_t who; uint32_t next; } mk_centry; /* who = slot | MK_GUEST_ */

typedef struct mk_range { int64_t lo[3], hi[3]; } mk_range;

/* The per-proxy fields of the every-update loops, together so that a
 * candidate's re-test touches one cache line per proxy, not three. */
typedef struct mk_gproxy {
    double travel;     /* sum over updates of the largest move of any face */
    double refile_at;  /* travel at which a face may first reach a cell wall */
    uint8_t st;        /* REG_* | ST_* */
} mk_gproxy;

struct mk_hgrid {
    /* per proxy slot */
    int32_t *level;
    mk_range *range;        /* native cell range */
    mk_gproxy *px;          /* what the per-update loops read, one record per slot */
    uint32_t *ov_pos;       /* index in oversized[] */
    uint32_t *todo; int todo_count; /* proxies to file in this update */
    int updates;            /* since travel was last reset to 0 */
    uint32_t *oversized; int ov_count;
    /* levels */
    int32_t natives[MK_LEVELS_]; /* natives per level */
    uint8_t used[MK_LEVELS_];    /* level in use since the last rebuild */
    int32_t used_list[MK_LEVELS_]; int used_count; /* ascending */
    /* cells */
    mk_cell *cells; int cell_count, cell_cap;
    uint32_t *index; uint32_t index_mask;
    mk_centry *ent; uint32_t ent_free; int ent_cap, ent_used;
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
static int keeps_level(const mk_aabb *b, int own)
{
    int l, lc;
    level_bounds(b, &l, &lc);
    return lc <= own && l >= own - 1 && l <= own + 1;
}

/* 2^-level, exact: the scaling in cell_coord is then an exact product. */
static double inv_cell(int level)
{
    uint64_t u = (uint64_t)(1023 - level) << 52;
    double d;
    memcpy(&d, &u, sizeof d);
    return d;
}

/* floor(v * inv) for |v * inv| < 2^41 (guaranteed by level_of). */
static int64_t cell_coord(mk_real v, double inv)
{
    double x = (double)v * inv;
    int64_t i = (int64_t)x;
    return i - (x < (double)i);
}

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
        int64_t i;
        if (!(lo > -0x1p41 && hi < 0x1p41)) return 0;
        i = (int64_t)lo; r->lo[k] = i - (lo < (double)i);
        i = (int64_t)hi; r->hi[k] = i - (hi < (double)i);
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

static mk_status grow_cells(mk_bp *bp, struct mk_hgrid *g)
{
    int cap = g->cell_cap * 2;
    uint32_t isize = (g->index_mask + 1) * 2;
    void *cells = g->cells, *index = NULL;
    mk_status st;
    if (bp->def.fixed_capacity || cap > INT32_MAX / 4) return MK_ERR_CAPACITY;
    if (!(index = mk_bp_alloc_(bp, isize * sizeof(uint32_t)))) return MK_ERR_OUT_OF_MEMORY;
    if ((st = mk_bp_grow_(bp, &cells, sizeof(mk_cell), (size_t)g->cell_cap, (size_t)cap)) != MK_OK) {
        mk_bp_free_(bp, index, isize * sizeof(uint32_t));
        return st;
    }
    mk_bp_free_(bp, g->index, (size_t)(g->index_mask + 1) * sizeof(uint32_t));
    g->cells = (mk_cell *)cells;
    g->cell_cap = cap;
    g->index = (uint32_t *)index;
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
    return cell;
}

/* Backward-shift deletion of the index slot, then swap-remove of the cell. */
static void cell_free(struct mk_hgrid *g, mk_cell *cell)
{
    uint32_t *s = cell_slot(g, cell->level, cell->c), hole = (uint32_t)(s - g->index), j = hole, idx = *s, last;
    for (;;) {
        uint32_t k, home;
        j = (j + 1) & g->index_mask;
        k = g->index[j];
        if (k == MK_NONE_) break;
        home = cell_hash(g->cells[k].level, g->cells[k].c, g->index_mask);
        if (((j - home) & g->index_mask) >= ((j - hole) & g->index_mask)) { g->index[hole] = k; hole = j; }
    }
    g->index[hole] = MK_NONE_;
    last = (uint32_t)--g->cell_count;
    if (idx != last) {
        g->cells[idx] = g->cells[last];
        *cell_slot(g, g->cells[idx].level, g->cells[idx].c) = idx;
    }
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
    cell->count++;
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
        if (--cell->count == 0) cell_free(g, cell);
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

/* Files `slot` into every cell of r at `level` outside `skip` (the cells it
 * is already in), and meets the proxies there: all of them on its own level,
 * only natives on coarser levels (guests there are finer than their natives
 * and meet `slot` on their own level). */
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
                    if (!guest || !(who & MK_GUEST_)) candidate(bp, g, slot, who & ~MK_GUEST_);
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

/* Moves slot's filing on one level from range o to range n, touching only
 * the cells that differ. */
static void refile_range(mk_bp *bp, struct mk_hgrid *g, uint32_t slot, int level, const mk_range *o, const mk_range *n, int guest)
{
    unfile_range(g, slot, level, o, n, guest);
    file_range(bp, g, slot, level, n, o, guest);
    g->px[slot].st |= ST_REFILED;
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

static void file(mk_bp *bp, struct mk_hgrid *g, uint32_t slot)
{
    const mk_aabb *b = &bp->box[slot];
    int i, own;
    uint32_t s;
    g->px[slot].st |= ST_REFILED;
    if (is_oversized(b)) {
        /* Everything is its candidate, filed or oversized. */
        for (s = 0; s < (uint32_t)bp->hi_slot; ++s)
            if (g->px[s].st & REG_MASK) candidate(bp, g, slot, s);
        g->px[slot].st = (uint8_t)((g->px[slot].st & ~REG_MASK) | REG_OVERSIZED);
        g->px[slot].refile_at = 0;
        ov_add(g, slot);
        return;
    }
    own = level_of(b);
    if (!g->used[own - MK_LEVEL_MIN_]) open_level(bp, g, own);
    g->level[slot] = own;
    g->natives[own - MK_LEVEL_MIN_]++;
    g->px[slot].st = (uint8_t)((g->px[slot].st & ~REG_MASK) | REG_CELLS);
    range_at(b, own, &g->range[slot]); /* first filing: tight; re-filings add the margin */
    g->px[slot].refile_at = room_until(g->px[slot].travel, wall_room(b, &g->range[slot], own));
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
 * returns 0 when it must be unfiled and filed again (new level, oversized). */
static int refile_in_place(mk_bp *bp, struct mk_hgrid *g, uint32_t slot, const mk_aabb *nb, double moved)
{
    int own = g->level[slot], i;
    mk_range r, o, old = g->range[slot];
    double room;
    if ((g->px[slot].st & REG_MASK) == REG_OVERSIZED && is_oversized(nb)) return 1; /* still everyone's candidate */
    if ((g->px[slot].st & REG_MASK) != REG_CELLS) return 0;
    room = wall_room(nb, &old, own);
    if (room >= 0) { g->px[slot].refile_at = room_until(g->px[slot].travel, room); return 1; }
    /* Left its cells. The level is only reconsidered now: while the box
     * stays within them its size cannot be far off. */
    if (!keeps_level(nb, own)) return 0;
    /* The margin pays for slow or jittering boxes; a box moving more than
     * the margin per update would leave it anyway, and gets its bare cells. */
    if (moved * inv_cell(own) < 0.0625) { if (!fat_range(nb, own, &r)) return 0; }
    else if (!range_fits(nb, own, &r)) return 0;
    g->px[slot].refile_at = room_until(g->px[slot].travel, wall_room(nb, &r, own));
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
    if ((g->px[a].st | g->px[b].st) & REG_OVERSIZED) return 1;
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

static uint32_t next_state(const mk_bp *bp, const struct mk_hgrid *g, uint32_t a, uint32_t b, mk_pair_entry *e)
{
    const uint32_t pair_bits = MK_PS_CAND | MK_PS_LIVE | MK_PS_REJECTED;
    uint32_t s = e->state;
    uint8_t sa = g->px[a].st, sb = g->px[b].st;
    int overlap;
    if (!(sa & REG_MASK) || !(sb & REG_MASK) || !(s & MK_PS_CAND)) return s & ~pair_bits;
    if (((sa | sb) & ST_REFILED) && !still_candidates(g, a, b)) return s & ~pair_bits;
    if ((sa | sb) & ST_REFILTER) s &= ~(uint32_t)(MK_PS_LIVE | MK_PS_REJECTED);
    else if (g->px[a].travel + g->px[b].travel < (double)e->wake) return s;
    overlap = mk_bp_overlap_(&bp->box[a], &bp->box[b]);
    e->wake = wake_at(g->px[a].travel + g->px[b].travel, margin(&bp->box[a], &bp->box[b], overlap));
    if (!overlap) return s & ~(uint32_t)(MK_PS_LIVE | MK_PS_REJECTED);
    if (s & (MK_PS_LIVE | MK_PS_REJECTED)) return s;
    return s | (mk_bp_filter_pass_(bp, a, b) ? MK_PS_LIVE : MK_PS_REJECTED);
}

static void retest(mk_bp *bp, struct mk_hgrid *g, int all)
{
    mk_pair_table *t = &bp->pairs;
    int i;
    for (i = 0; i < t->count; ++i) {
        mk_pair_entry *e = &t->e[i];
        uint32_t a = (uint32_t)(e->key >> 32), b = (uint32_t)e->key, s, old = e->state;
        uint8_t sa = g->px[a].st, sb = g->px[b].st;
        if (!all && !((sa | sb) & ST_DIRTY)) continue;
        /* the common case: both filed as before, too little travel to matter
         * (every entry here has CAND: the grid sets it on insertion) */
        if (!((sa | sb) & ST_SLOW) && g->px[a].travel + g->px[b].travel < (double)e->wake) continue;
        s = next_state(bp, g, a, b, e);
        e->state = s;
        if ((s ^ old) & (MK_PS_LIVE | MK_PS_CAND)) mk_pairs_touch_(bp, e);
    }
}

/* Every 256 updates travel restarts from 0, with every wake, so the sums
 * stay small enough for the float wakes to keep their precision. */
static void restart_travel(mk_bp *bp, struct mk_hgrid *g)
{
    int i;
    if (++g->updates < 256) return;
    g->updates = 0;
    for (i = 0; i < bp->hi_slot; ++i) g->px[i].travel = g->px[i].refile_at = 0;
    for (i = 0; i < bp->pairs.count; ++i) bp->pairs.e[i].wake = 0;
}

/* The largest move of any face from box o to box n (NaN when a side is infinite). */
static double face_travel(const mk_aabb *o, const mk_aabb *n)
{
    const mk_real *ol = &o->lo.x, *oh = &o->hi.x, *nl = &n->lo.x, *nh = &n->hi.x;
    double d = 0;
    int k;
    for (k = 0; k < 3; ++k) {
        double dl = fabs((double)nl[k] - (double)ol[k]), dh = fabs((double)nh[k] - (double)oh[k]);
        /* written so that a NaN (inf - inf) wins: NaN travel fails every
         * "cannot have changed" test, so the proxy is always looked at */
        if (!(dl <= d)) d = dl;
        if (!(dh <= d)) d = dh;
    }
    return d;
}

/* ---- lifetime ---- */

typedef struct grid_array_ { void **p; size_t elem; } grid_array_;
static int grid_arrays(struct mk_hgrid *g, grid_array_ *a)
{
    int n = 0;
    a[n].p = (void **)&g->level; a[n++].elem = sizeof *g->level;
    a[n].p = (void **)&g->range; a[n++].elem = sizeof *g->range;
    a[n].p = (void **)&g->px; a[n++].elem = sizeof *g->px;
    a[n].p = (void **)&g->ov_pos; a[n++].elem = sizeof *g->ov_pos;
    a[n].p = (void **)&g->todo; a[n++].elem = sizeof *g->todo;
    a[n].p = (void **)&g->oversized; a[n++].elem = sizeof *g->oversized;
    return n;
}

static void reset_cells(struct mk_hgrid *g, int proxies)
{
    int i;
    g->cell_count = 0;
    memset(g->index, 0xff, (size_t)(g->index_mask + 1) * sizeof *g->index);
    for (i = 0; i < g->ent_cap; ++i) g->ent[i].next = i + 1 < g->ent_cap ? (uint32_t)i + 1 : MK_NONE_;
    g->ent_free = 0;
    g->ent_used = 0;
    for (i = 0; i < proxies; ++i) g->px[i].st = 0;
    memset(g->natives, 0, sizeof g->natives);
    memset(g->used, 0, sizeof g->used);
    g->used_count = 0;
    g->ov_count = 0;
}

mk_status mk_hgrid_create_(mk_bp *bp)
{
    struct mk_hgrid *g;
    grid_array_ a[6];
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
    g->index_mask = 1;
    while (g->index_mask + 1 < (uint32_t)g->cell_cap * 2) g->index_mask = g->index_mask * 2 + 1;
    if (!(g->cells = (mk_cell *)mk_bp_alloc_(bp, sizeof(mk_cell) * (size_t)g->cell_cap))) goto fail;
    if (!(g->ent = (mk_centry *)mk_bp_alloc_(bp, sizeof(mk_centry) * (size_t)g->ent_cap))) goto fail;
    if (!(g->index = (uint32_t *)mk_bp_alloc_(bp, sizeof(uint32_t) * (size_t)(g->index_mask + 1)))) goto fail;
    memset(g->px, 0, sizeof *g->px * (size_t)bp->cap);
    reset_cells(g, bp->cap);
    return MK_OK;
fail:
    mk_hgrid_destroy_(bp);
    return MK_ERR_OUT_OF_MEMORY;
}

void mk_hgrid_destroy_(mk_bp *bp)
{
    struct mk_hgrid *g = bp->grid;
    grid_array_ a[6];
    int n, i;
    if (!g) return;
    n = grid_arrays(g, a);
    for (i = 0; i < n; ++i) mk_bp_free_(bp, *a[i].p, a[i].elem * (size_t)bp->cap);
    mk_bp_free_(bp, g->cells, sizeof(mk_cell) * (size_t)g->cell_cap);
    mk_bp_free_(bp, g->ent, sizeof(mk_centry) * (size_t)g->ent_cap);
    if (g->index) mk_bp_free_(bp, g->index, sizeof(uint32_t) * (size_t)(g->index_mask + 1));
    mk_bp_free_(bp, g, sizeof *g);
    bp->grid = NULL;
}

void mk_hgrid_counts_(const mk_bp *bp, int *levels, int *cells)
{
    *levels = bp->grid ? bp->grid->used_count : 0;
    *cells = bp->grid ? bp->grid->cell_count : 0;
}

/* ---- update ---- */

static int in_structure(const mk_bp *bp, uint32_t s)
{
    return (bp->flags[s] & (MK_PF_ALIVE | MK_PF_DYING)) == MK_PF_ALIVE;
}

static void rebuild(mk_bp *bp, struct mk_hgrid *g)
{
    uint32_t s;
    reset_cells(g, bp->cap);
    mk_pairs_forget_(bp);
    mk_bp_commit_(bp);
    /* Open every level first, so nobody is filed as a guest one level at a time. */
    for (s = 0; s < (uint32_t)bp->hi_slot; ++s) {
        int l;
        if (!in_structure(bp, s) || is_oversized(&bp->box[s])) continue;
        l = level_of(&bp->box[s]);
        if (!g->used[l - MK_LEVEL_MIN_]) use_level_list(g, l);
    }
    for (s = 0; s < (uint32_t)bp->hi_slot && g->fail == MK_OK; ++s)
        if (in_structure(bp, s)) file(bp, g, s);
}

/* One pass over the changed proxies, with the old boxes still in place:
 * mark them, add up their travel, re-file what crossed a cell wall. */
static void take_changes(mk_bp *bp, struct mk_hgrid *g)
{
    int i;
    for (i = 0; i < bp->dirty_count; ++i) {
        uint32_t s = bp->dirty[i];
        uint8_t f = bp->flags[s];
        double moved;
        g->px[s].st |= (uint8_t)(ST_DIRTY | ((f & MK_PF_REFILTER) ? ST_REFILTER : 0));
        if (f & MK_PF_DYING) { unfile(g, s); continue; }
        if (f & MK_PF_NEW) { g->todo[g->todo_count++] = s; continue; }
        if (!(f & MK_PF_MOVED)) continue;
        moved = face_travel(&bp->box[s], &bp->next[s]);
        g->px[s].travel += moved;
        if (g->px[s].travel < g->px[s].refile_at) continue; /* no face can have reached a wall */
        if (!refile_in_place(bp, g, s, &bp->next[s], moved)) {
            unfile(g, s);
            g->todo[g->todo_count++] = s;
        }
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
    if (all) {
        rebuild(bp, g);
    } else {
        restart_travel(bp, g);
        take_changes(bp, g);
        mk_bp_commit_(bp);
        for (i = 0; i < g->todo_count && g->fail == MK_OK; ++i) file(bp, g, g->todo[i]);
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

void mk_hgrid_query_(const mk_bp *bp, mk_aabb q, mk_bp_query_fn fn, void *ctx)
{
    const struct mk_hgrid *g = bp->grid;
    double covered;
    int i;
    if (!g) return;
    covered = cells_covered(g, &q);
    if (covered < 0 || covered > (double)(g->cell_count + 16)) { linear_query(bp, g, q, fn, ctx); return; }
    for (i = 0; i < g->ov_count; ++i) {
        uint32_t s = g->oversized[i];
        if (mk_bp_overlap_(&bp->box[s], &q) && !fn(ctx, mk_bp_id_of_(bp, s), bp->user[s])) return;
    }
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

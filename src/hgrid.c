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

enum { REG_NONE = 0, REG_CELLS = 1, REG_OVERSIZED = 2 };

typedef struct mk_cell {
    int64_t c[3];
    int32_t level;
    uint32_t head;      /* first entry, MK_NONE_ if none */
    uint32_t count;
    uint32_t pad_;
} mk_cell;

typedef struct mk_centry { uint32_t who; uint32_t next; } mk_centry; /* who = slot | MK_GUEST_ */

typedef struct mk_range { int64_t lo[3], hi[3]; } mk_range;

struct mk_hgrid {
    /* per proxy slot */
    int32_t *level;
    mk_range *range;        /* native cell range */
    uint8_t *reg;           /* REG_* */
    uint8_t *refiled;       /* re-filed in this update: candidates must be re-checked */
    uint32_t *ov_pos;       /* index in oversized[] */
    uint32_t *todo; int todo_count; /* proxies to file in this update */
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

static int level_of_size(double size)
{
    int e;
    double m;
    if (!(size > 0)) return MK_LEVEL_MIN_;
    m = frexp(size, &e);       /* size = m 2^e, m in [0.5, 1) */
    return m == 0.5 ? e - 1 : e; /* smallest L with 2^L >= size */
}

static int is_oversized(const mk_aabb *b)
{
    const mk_real *lo = &b->lo.x, *hi = &b->hi.x;
    int k;
    for (k = 0; k < 3; ++k)
        if (!((double)hi[k] - (double)lo[k] <= 1e300)) return 1; /* an infinite side */
    return 0;
}

static int level_of(const mk_aabb *b)
{
    const mk_real *lo = &b->lo.x, *hi = &b->hi.x;
    double size = 0, far = 0;
    int k, l, lc;
    for (k = 0; k < 3; ++k) {
        double s = (double)hi[k] - (double)lo[k];
        if (s > size) size = s;
        if (fabs((double)lo[k]) > far) far = fabs((double)lo[k]);
        if (fabs((double)hi[k]) > far) far = fabs((double)hi[k]);
    }
    l = level_of_size(size);
    lc = far > 0 ? ilogb(far) - 40 : MK_LEVEL_MIN_; /* keeps |coordinate / cell| < 2^41 */
    if (lc > l) l = lc;
    if (l < MK_LEVEL_MIN_) l = MK_LEVEL_MIN_;
    return l;
}

static int64_t cell_coord(mk_real v, int level) { return (int64_t)floor(ldexp((double)v, -level)); }

static void range_at(const mk_aabb *b, int level, mk_range *r)
{
    int k;
    for (k = 0; k < 3; ++k) {
        r->lo[k] = cell_coord((&b->lo.x)[k], level);
        r->hi[k] = cell_coord((&b->hi.x)[k], level);
    }
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

/* Files `who` into every cell of r at `level`; meets the proxies there:
 * all of them on its own level, only natives on coarser levels (guests
 * there are finer than their natives and meet `slot` on their own level). */
static void file_range(mk_bp *bp, struct mk_hgrid *g, uint32_t slot, int level, const mk_range *r, int guest)
{
    int64_t c[3];
    for (c[0] = r->lo[0]; c[0] <= r->hi[0]; ++c[0])
        for (c[1] = r->lo[1]; c[1] <= r->hi[1]; ++c[1])
            for (c[2] = r->lo[2]; c[2] <= r->hi[2]; ++c[2]) {
                mk_cell *cell = cell_get(bp, g, level, c);
                uint32_t e;
                if (!cell) return;
                for (e = cell->head; e != MK_NONE_; e = g->ent[e].next) {
                    uint32_t who = g->ent[e].who;
                    if (!guest || !(who & MK_GUEST_)) candidate(bp, g, slot, who & ~MK_GUEST_);
                }
                /* cell_add may move cells (growth): do it last, cell not used after */
                if (!cell_add(bp, g, cell, slot | (guest ? MK_GUEST_ : 0))) return;
            }
}

static void unfile_range(struct mk_hgrid *g, uint32_t slot, int level, const mk_range *r, int guest)
{
    int64_t c[3];
    for (c[0] = r->lo[0]; c[0] <= r->hi[0]; ++c[0])
        for (c[1] = r->lo[1]; c[1] <= r->hi[1]; ++c[1])
            for (c[2] = r->lo[2]; c[2] <= r->hi[2]; ++c[2]) cell_remove(g, level, c, slot | (guest ? MK_GUEST_ : 0));
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

/* Removes slot from every cell it is filed in, as filed from box b. */
static void unfile(struct mk_hgrid *g, uint32_t slot, const mk_aabb *b)
{
    int i;
    if (g->reg[slot] == REG_OVERSIZED) ov_remove(g, slot);
    if (g->reg[slot] == REG_CELLS) {
        int own = g->level[slot];
        unfile_range(g, slot, own, &g->range[slot], 0);
        for (i = 0; i < g->used_count; ++i) {
            mk_range r;
            if (g->used_list[i] <= own) continue;
            range_at(b, g->used_list[i], &r);
            unfile_range(g, slot, g->used_list[i], &r, 1);
        }
        g->natives[own - MK_LEVEL_MIN_]--;
    }
    g->reg[slot] = REG_NONE;
}

/* A level comes into use: every finer proxy already filed becomes its guest. */
static void open_level(mk_bp *bp, struct mk_hgrid *g, int level)
{
    uint32_t s;
    use_level_list(g, level);
    for (s = 0; s < (uint32_t)bp->hi_slot && g->fail == MK_OK; ++s) {
        mk_range r;
        if (g->reg[s] != REG_CELLS || g->level[s] >= level) continue;
        range_at(&bp->box[s], level, &r);
        file_range(bp, g, s, level, &r, 1);
    }
}

static void file(mk_bp *bp, struct mk_hgrid *g, uint32_t slot)
{
    const mk_aabb *b = &bp->box[slot];
    int i, own;
    uint32_t s;
    g->refiled[slot] = 1;
    if (is_oversized(b)) {
        /* Everything is its candidate, filed or oversized. */
        for (s = 0; s < (uint32_t)bp->hi_slot; ++s)
            if (g->reg[s] != REG_NONE) candidate(bp, g, slot, s);
        g->reg[slot] = REG_OVERSIZED;
        ov_add(g, slot);
        return;
    }
    own = level_of(b);
    if (!g->used[own - MK_LEVEL_MIN_]) open_level(bp, g, own);
    g->level[slot] = own;
    g->natives[own - MK_LEVEL_MIN_]++;
    g->reg[slot] = REG_CELLS;
    range_at(b, own, &g->range[slot]);
    file_range(bp, g, slot, own, &g->range[slot], 0);
    for (i = 0; i < g->used_count; ++i) {
        mk_range r;
        if (g->used_list[i] <= own) continue;
        range_at(b, g->used_list[i], &r);
        file_range(bp, g, slot, g->used_list[i], &r, 1);
    }
    for (i = 0; i < g->ov_count; ++i) candidate(bp, g, slot, g->oversized[i]);
}

/* Would slot be filed differently with box nb than it is with box ob? */
static int filing_changes(const struct mk_hgrid *g, uint32_t slot, const mk_aabb *ob, const mk_aabb *nb)
{
    int own, i;
    mk_range r, o;
    if (g->reg[slot] == REG_OVERSIZED || is_oversized(nb)) return 1;
    own = level_of(nb);
    if (own != g->level[slot]) return 1;
    range_at(nb, own, &r);
    if (!range_eq(&r, &g->range[slot])) return 1;
    for (i = g->used_count - 1; i >= 0 && g->used_list[i] > own; --i) {
        range_at(nb, g->used_list[i], &r);
        range_at(ob, g->used_list[i], &o);
        if (!range_eq(&r, &o)) return 1;
    }
    return 0;
}

/* ---- the per-update re-test of candidates ---- */

/* Do a and b (both filed) still share a cell? */
static int still_candidates(const mk_bp *bp, const struct mk_hgrid *g, uint32_t a, uint32_t b)
{
    mk_range r;
    if (g->reg[a] == REG_OVERSIZED || g->reg[b] == REG_OVERSIZED) return 1;
    if (g->level[a] == g->level[b]) return ranges_meet(&g->range[a], &g->range[b]);
    if (g->level[a] < g->level[b]) { range_at(&bp->box[a], g->level[b], &r); return ranges_meet(&r, &g->range[b]); }
    range_at(&bp->box[b], g->level[a], &r);
    return ranges_meet(&r, &g->range[a]);
}

static uint32_t next_state(const mk_bp *bp, const struct mk_hgrid *g, uint32_t a, uint32_t b, uint32_t s)
{
    const uint32_t pair_bits = MK_PS_CAND | MK_PS_LIVE | MK_PS_REJECTED;
    if (g->reg[a] == REG_NONE || g->reg[b] == REG_NONE || !(s & MK_PS_CAND)) return s & ~pair_bits;
    if ((g->refiled[a] || g->refiled[b]) && !still_candidates(bp, g, a, b)) return s & ~pair_bits;
    if ((bp->flags[a] | bp->flags[b]) & MK_PF_REFILTER) s &= ~(uint32_t)(MK_PS_LIVE | MK_PS_REJECTED);
    if (!mk_bp_overlap_(&bp->box[a], &bp->box[b])) return s & ~(uint32_t)(MK_PS_LIVE | MK_PS_REJECTED);
    if (s & (MK_PS_LIVE | MK_PS_REJECTED)) return s;
    return s | (mk_bp_filter_pass_(bp, a, b) ? MK_PS_LIVE : MK_PS_REJECTED);
}

static void retest(mk_bp *bp, struct mk_hgrid *g, int all)
{
    mk_pair_table *t = &bp->pairs;
    int i;
    for (i = 0; i < t->count; ++i) {
        mk_pair_entry *e = &t->e[i];
        uint32_t a = (uint32_t)(e->key >> 32), b = (uint32_t)e->key, s;
        if (!all && !((bp->flags[a] | bp->flags[b]) & MK_PF_DIRTY)) continue;
        s = next_state(bp, g, a, b, e->state);
        if ((s ^ e->state) & (MK_PS_LIVE | MK_PS_CAND)) { e->state = s; mk_pairs_touch_(bp, e); }
        else e->state = s;
    }
}

/* ---- lifetime ---- */

typedef struct grid_array_ { void **p; size_t elem; } grid_array_;
static int grid_arrays(struct mk_hgrid *g, grid_array_ *a)
{
    int n = 0;
    a[n].p = (void **)&g->level; a[n++].elem = sizeof *g->level;
    a[n].p = (void **)&g->range; a[n++].elem = sizeof *g->range;
    a[n].p = (void **)&g->reg; a[n++].elem = sizeof *g->reg;
    a[n].p = (void **)&g->refiled; a[n++].elem = sizeof *g->refiled;
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
    memset(g->reg, 0, (size_t)proxies);
    memset(g->natives, 0, sizeof g->natives);
    memset(g->used, 0, sizeof g->used);
    g->used_count = 0;
    g->ov_count = 0;
}

mk_status mk_hgrid_create_(mk_bp *bp)
{
    struct mk_hgrid *g;
    grid_array_ a[7];
    int n, i;
    if (!(g = (struct mk_hgrid *)mk_bp_alloc_(bp, sizeof *g))) return MK_ERR_OUT_OF_MEMORY;
    memset(g, 0, sizeof *g);
    bp->grid = g;
    n = grid_arrays(g, a);
    for (i = 0; i < n; ++i)
        if (!(*a[i].p = mk_bp_alloc_(bp, a[i].elem * (size_t)bp->cap))) goto fail;
    /* A proxy covers at most 8 cells of its own level, plus a guest cell or
     * two per coarser level. Growing pools start at the typical need; fixed
     * ones get room for 8 cells and 16 filings per proxy. */
    g->cell_cap = (bp->def.fixed_capacity ? 8 : 2) * bp->cap + 64;
    g->ent_cap = (bp->def.fixed_capacity ? 16 : 4) * bp->cap + 64;
    g->index_mask = 1;
    while (g->index_mask + 1 < (uint32_t)g->cell_cap * 2) g->index_mask = g->index_mask * 2 + 1;
    if (!(g->cells = (mk_cell *)mk_bp_alloc_(bp, sizeof(mk_cell) * (size_t)g->cell_cap))) goto fail;
    if (!(g->ent = (mk_centry *)mk_bp_alloc_(bp, sizeof(mk_centry) * (size_t)g->ent_cap))) goto fail;
    if (!(g->index = (uint32_t *)mk_bp_alloc_(bp, sizeof(uint32_t) * (size_t)(g->index_mask + 1)))) goto fail;
    memset(g->refiled, 0, (size_t)bp->cap);
    reset_cells(g, bp->cap);
    return MK_OK;
fail:
    mk_hgrid_destroy_(bp);
    return MK_ERR_OUT_OF_MEMORY;
}

void mk_hgrid_destroy_(mk_bp *bp)
{
    struct mk_hgrid *g = bp->grid;
    grid_array_ a[7];
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
        /* Unfile what changes, with the old boxes; then commit; then file. */
        for (i = 0; i < bp->dirty_count; ++i) {
            uint32_t s = bp->dirty[i];
            uint8_t f = bp->flags[s];
            if (f & MK_PF_DYING) { unfile(g, s, &bp->box[s]); continue; }
            if (f & MK_PF_NEW) { g->todo[g->todo_count++] = s; continue; }
            if ((f & MK_PF_MOVED) && filing_changes(g, s, &bp->box[s], &bp->next[s])) {
                unfile(g, s, &bp->box[s]);
                g->todo[g->todo_count++] = s;
            }
        }
        mk_bp_commit_(bp);
        for (i = 0; i < g->todo_count && g->fail == MK_OK; ++i) file(bp, g, g->todo[i]);
    }
    if (g->fail == MK_OK) retest(bp, g, all);
    if (all) memset(g->refiled, 0, (size_t)bp->hi_slot);
    else for (i = 0; i < g->todo_count; ++i) g->refiled[g->todo[i]] = 0;
    if (g->fail != MK_OK) return g->fail;
    bp->rebuild = 0;
    return MK_OK;
}

/* ---- region query ---- */

static void linear_query(const mk_bp *bp, const struct mk_hgrid *g, mk_aabb q, mk_bp_query_fn fn, void *ctx)
{
    uint32_t s;
    for (s = 0; s < (uint32_t)bp->hi_slot; ++s)
        if (g->reg[s] != REG_NONE && mk_bp_overlap_(&bp->box[s], &q) && !fn(ctx, mk_bp_id_of_(bp, s), bp->user[s])) return;
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
            double lo = floor(ldexp((double)(&q->lo.x)[k], -g->used_list[i]));
            double hi = floor(ldexp((double)(&q->hi.x)[k], -g->used_list[i]));
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

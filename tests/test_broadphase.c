/* test_broadphase.c: every broadphase structure against an O(n^2) oracle
 * computed here, frame by frame, under seeded random scenes; events replay to
 * the set; queries, filters, capacities and bad input. */
#include <stdlib.h>
#include <string.h>

#include "minko/broadphase.h"
#include "support/mk_test.h"

#define MAXN 600
#define NKIND 5
/* The last one is SAP for a caller that wants the set only (pairs_only):
 * incoherent frames are answered by a stateless sweep, without events. */
static const mk_bp_kind kinds[NKIND] = {MK_BP_BRUTE, MK_BP_SAP, MK_BP_HGRID, MK_BP_AUTO, MK_BP_SAP};
static const int only_pairs[NKIND] = {0, 0, 0, 0, 1};
#define K_SAP_SET 4

static const char *name_of(int k) { return only_pairs[k] ? "sap pairs_only" : mk_bp_kind_name(kinds[k]); }

typedef struct obj { int alive, is_static; mk_aabb box; mk_vec3 vel; mk_bp_id id[NKIND]; } obj;

typedef struct world {
    obj o[MAXN];
    int n;                      /* objects ever made (alive or not) */
    mk_bp *bp[NKIND];
    mk_bp_pair *prev[NKIND];    /* last set, for event replay */
    int prev_count[NKIND];
    mk_rng rng;
    int filter;                 /* use the test filter */
} world;

static int pair_cmp(const void *a, const void *b)
{
    const mk_bp_pair *x = (const mk_bp_pair *)a, *y = (const mk_bp_pair *)b;
    if (x->a != y->a) return x->a < y->a ? -1 : 1;
    return x->b < y->b ? -1 : (x->b > y->b);
}

/* Objects with index % 7 == 3 refuse partners with index % 5 == 1 (a user rule). */
static int test_filter(void *ctx, mk_bp_id a, void *ua, mk_bp_id b, void *ub)
{
    long ia = (long)(intptr_t)ua - 1, ib = (long)(intptr_t)ub - 1;
    (void)ctx; (void)a; (void)b;
    return !((ia % 7 == 3 && ib % 5 == 1) || (ib % 7 == 3 && ia % 5 == 1));
}

static int world_init(world *w, uint64_t seed, int cap, int filter)
{
    int k, made = 0;
    memset(w, 0, sizeof *w);
    w->rng.s = seed;
    w->filter = filter;
    for (k = 0; k < NKIND; ++k) {
        mk_bp_def d = mk_bp_default_def();
        mk_status st;
        d.kind = kinds[k];
        d.pairs_only = only_pairs[k];
        d.proxy_capacity = cap;
        if (filter) { d.filter = test_filter; }
        st = mk_bp_create(&d, NULL, &w->bp[k]);
        if (st == MK_ERR_UNSUPPORTED) { w->bp[k] = NULL; continue; }
        MK_ASSERT_STATUS(st, MK_OK);
        w->prev[k] = (mk_bp_pair *)malloc(sizeof(mk_bp_pair) * MAXN * MAXN / 2);
        ++made;
    }
    return made;
}

static void world_fini(world *w)
{
    int k;
    for (k = 0; k < NKIND; ++k) { mk_bp_destroy(w->bp[k]); free(w->prev[k]); }
}

static void add_obj(world *w, mk_aabb box, int is_static)
{
    int k, i = w->n++;
    ck_assert_int_lt(i, MAXN);
    w->o[i].alive = 1;
    w->o[i].is_static = is_static;
    w->o[i].box = box;
    for (k = 0; k < NKIND; ++k)
        if (w->bp[k]) MK_ASSERT_STATUS(mk_bp_create_proxy(w->bp[k], box, (void *)(intptr_t)(i + 1), ~0ull, ~0ull, is_static, &w->o[i].id[k]), MK_OK);
}

static void move_obj(world *w, int i, mk_aabb box)
{
    int k;
    w->o[i].box = box;
    for (k = 0; k < NKIND; ++k)
        if (w->bp[k]) MK_ASSERT_STATUS(mk_bp_move_proxy(w->bp[k], w->o[i].id[k], box), MK_OK);
}

static void kill_obj(world *w, int i)
{
    int k;
    w->o[i].alive = 0;
    for (k = 0; k < NKIND; ++k)
        if (w->bp[k]) {
            MK_ASSERT_STATUS(mk_bp_destroy_proxy(w->bp[k], w->o[i].id[k]), MK_OK);
            MK_ASSERT_STATUS(mk_bp_destroy_proxy(w->bp[k], w->o[i].id[k]), MK_ERR_UNKNOWN_ID);
        }
}

/* The truth, as object-index pairs (i < j), sorted. */
static int oracle(const world *w, mk_bp_pair *out)
{
    int i, j, n = 0;
    for (i = 0; i < w->n; ++i) {
        if (!w->o[i].alive) continue;
        for (j = i + 1; j < w->n; ++j) {
            if (!w->o[j].alive || (w->o[i].is_static && w->o[j].is_static)) continue;
            if (!mk_aabb_overlap(w->o[i].box, w->o[j].box)) continue;
            if (w->filter && !test_filter(NULL, 0, (void *)(intptr_t)(i + 1), 0, (void *)(intptr_t)(j + 1))) continue;
            out[n].a = (mk_bp_id)i; out[n].b = (mk_bp_id)j; ++n;
        }
    }
    return n;
}

static int sorted_strictly(const mk_bp_pair *p, int n)
{
    int i;
    for (i = 0; i < n; ++i) {
        if (p[i].a >= p[i].b) return 0;
        if (i > 0 && pair_cmp(&p[i - 1], &p[i]) >= 0) return 0;
    }
    return 1;
}

/* Checks one structure: sorted set, replayed events, and the truth. */
static void check_kind(world *w, int k, const mk_bp_pair *truth, int nt, int frame)
{
    static mk_bp_pair buf[MAXN * MAXN / 2], replay[MAXN * MAXN / 2];
    int np, na, nr, i, r = 0, a = 0, o = 0, p = 0;
    const mk_bp_pair *set = mk_bp_pairs(w->bp[k], &np), *add = mk_bp_added(w->bp[k], &na), *rem = mk_bp_removed(w->bp[k], &nr);
    ck_assert_msg(sorted_strictly(set, np) && sorted_strictly(add, na) && sorted_strictly(rem, nr),
                  "%s: unsorted output at frame %d", name_of(k), frame);
    if (only_pairs[k]) ck_assert_msg(na == 0 && nr == 0, "%s: events at frame %d", name_of(k), frame);
    /* replay: prev - removed + added == set */
    while (!only_pairs[k] && (p < w->prev_count[k] || a < na)) {
        if (p < w->prev_count[k] && r < nr && pair_cmp(&w->prev[k][p], &rem[r]) == 0) { ++p; ++r; continue; }
        if (a >= na || (p < w->prev_count[k] && pair_cmp(&w->prev[k][p], &add[a]) < 0)) replay[o++] = w->prev[k][p++];
        else replay[o++] = add[a++];
    }
    ck_assert_msg(r == nr, "%s: removed a pair that was not there (frame %d)", name_of(k), frame);
    ck_assert_msg(only_pairs[k] || (o == np && memcmp(replay, set, sizeof *set * (size_t)np) == 0), "%s: events do not replay (frame %d)",
                  name_of(k), frame);
    memcpy(w->prev[k], set, sizeof *set * (size_t)np);
    w->prev_count[k] = np;
    /* map ids to object indices and compare with the truth */
    for (i = 0; i < np; ++i) {
        long ia = (long)(intptr_t)mk_bp_user(w->bp[k], set[i].a) - 1, ib = (long)(intptr_t)mk_bp_user(w->bp[k], set[i].b) - 1;
        ck_assert_msg(ia >= 0 && ib >= 0, "%s: pair with a dead id (frame %d)", name_of(k), frame);
        buf[i].a = (mk_bp_id)(ia < ib ? ia : ib);
        buf[i].b = (mk_bp_id)(ia < ib ? ib : ia);
    }
    qsort(buf, (size_t)np, sizeof *buf, pair_cmp);
    if (np != nt || memcmp(buf, truth, sizeof *buf * (size_t)np) != 0) {
        int missing = 0, extra = 0, x = 0, y = 0;
        while (x < nt || y < np) {
            if (y >= np || (x < nt && pair_cmp(&truth[x], &buf[y]) < 0)) { ++missing; ++x; }
            else if (x >= nt || pair_cmp(&buf[y], &truth[x]) < 0) { ++extra; ++y; }
            else { ++x; ++y; }
        }
        ck_abort_msg("%s: frame %d: %d pairs, truth %d: %d missing, %d extra", name_of(k), frame, np, nt, missing, extra);
    }
}

static void step(world *w, int frame)
{
    static mk_bp_pair truth[MAXN * MAXN / 2];
    int nt = oracle(w, truth), k;
    for (k = 0; k < NKIND; ++k) {
        if (!w->bp[k]) continue;
        MK_ASSERT_STATUS(mk_bp_update(w->bp[k]), MK_OK);
        check_kind(w, k, truth, nt, frame);
    }
}

static mk_aabb box_at(mk_vec3 c, mk_vec3 half) { return mk_aabb_make(mk_v3_sub(c, half), mk_v3_add(c, half)); }

static mk_aabb random_box(mk_rng *r, double world_size, double size_lo, double size_hi)
{
    double s = size_lo * pow(size_hi / size_lo, mk_rng_unit(r)); /* log-uniform */
    mk_vec3 half = mk_v3((mk_real)(s * mk_rng_range(r, 0.3, 0.5)), (mk_real)(s * mk_rng_range(r, 0.3, 0.5)), (mk_real)(s * mk_rng_range(r, 0.3, 0.5)));
    return box_at(mk_rng_v3(r, 0, world_size), half);
}

static void drift(world *w, int i, double speed)
{
    obj *o = &w->o[i];
    mk_vec3 d = mk_v3_scale(o->vel, (mk_real)speed);
    move_obj(w, i, mk_aabb_make(mk_v3_add(o->box.lo, d), mk_v3_add(o->box.hi, d)));
}

/* ---- scenes ---- */

static void run_motion(uint64_t seed, int n, double world_size, double size_lo, double size_hi, double static_share,
                       double teleport_share, double churn_share, int frames)
{
    static world w;
    int i, f;
    if (!world_init(&w, seed, MAXN, 0)) return;
    for (i = 0; i < n; ++i) {
        add_obj(&w, random_box(&w.rng, world_size, size_lo, size_hi), mk_rng_unit(&w.rng) < static_share);
        w.o[i].vel = mk_v3_scale(mk_rng_dir(&w.rng), (mk_real)(size_lo * 0.2));
    }
    for (f = 0; f < frames; ++f) {
        for (i = 0; i < w.n; ++i) {
            if (!w.o[i].alive || w.o[i].is_static) continue;
            if (mk_rng_unit(&w.rng) < teleport_share) {
                mk_vec3 half = mk_aabb_extents(w.o[i].box);
                move_obj(&w, i, box_at(mk_rng_v3(&w.rng, 0, world_size), half));
            } else {
                drift(&w, i, 1);
            }
        }
        for (i = 0; i < w.n && churn_share > 0; ++i)
            if (w.o[i].alive && mk_rng_unit(&w.rng) < churn_share) kill_obj(&w, i);
        while (churn_share > 0 && w.n < MAXN && mk_rng_unit(&w.rng) < churn_share * n) {
            add_obj(&w, random_box(&w.rng, world_size, size_lo, size_hi), mk_rng_unit(&w.rng) < static_share);
            w.o[w.n - 1].vel = mk_v3_scale(mk_rng_dir(&w.rng), (mk_real)(size_lo * 0.2));
        }
        step(&w, f);
    }
    if (w.bp[1]) { /* SAP: coherent scenes stay incremental after the first build */
        mk_bp_stats st;
        MK_ASSERT_STATUS(mk_bp_get_stats(w.bp[1], &st), MK_OK);
        ck_assert_int_eq(st.kind, MK_BP_SAP);
        if (teleport_share == 0) ck_assert_int_eq(st.full_rebuilds, 1);
        if (teleport_share >= 0.1) ck_assert_int_gt(st.full_rebuilds, 1);
    }
    if (w.bp[K_SAP_SET] && teleport_share >= 0.1) { /* teleports: answered by stateless sweeps */
        mk_bp_stats st;
        MK_ASSERT_STATUS(mk_bp_get_stats(w.bp[K_SAP_SET], &st), MK_OK);
        ck_assert_int_gt(st.sweeps, 0);
    }
    world_fini(&w);
}

/* pairs_only: bursts of teleports (stateless sweeps) between calm stretches
 * where a fifth of the boxes drift (insertion sorts again), with churn,
 * statics and a ground plane; the set must be exact on every frame,
 * whichever path answered it. */
START_TEST(pairs_only_switches_paths)
{
    static world w;
    const mk_real inf = (mk_real)INFINITY;
    int i, f, sweeps_seen = 0, back_to_sorts = 0;
    mk_bp_stats st;
    if (!world_init(&w, 31, MAXN, 0)) return;
    add_obj(&w, mk_aabb_make(mk_v3(-inf, -inf, -inf), mk_v3(inf, inf, (mk_real)0.5)), 1);
    for (i = 0; i < 320; ++i) {
        add_obj(&w, random_box(&w.rng, 14, 0.5, 2), i % 6 == 0);
        w.o[w.n - 1].vel = mk_v3_scale(mk_rng_dir(&w.rng), (mk_real)0.05);
    }
    for (f = 0; f < 240; ++f) {
        int burst = (f / 20) % 3 == 1;
        int sweeps_before, rebuilds_before;
        MK_ASSERT_STATUS(mk_bp_get_stats(w.bp[K_SAP_SET], &st), MK_OK);
        sweeps_before = st.sweeps;
        rebuilds_before = st.full_rebuilds;
        for (i = 1; i < w.n; ++i) {
            if (!w.o[i].alive || w.o[i].is_static) continue;
            if (burst && mk_rng_unit(&w.rng) < 0.5) move_obj(&w, i, box_at(mk_rng_v3(&w.rng, 0, 14), mk_aabb_extents(w.o[i].box)));
            else if (burst || i % 5 == 0) drift(&w, i, 1);
        }
        if (f % 7 == 3) {
            for (i = 1; i < w.n; ++i)
                if (w.o[i].alive && mk_rng_unit(&w.rng) < 0.02) kill_obj(&w, i);
            while (w.n < MAXN && mk_rng_unit(&w.rng) < 0.8) add_obj(&w, random_box(&w.rng, 14, 0.5, 2), 0);
        }
        step(&w, f);
        MK_ASSERT_STATUS(mk_bp_get_stats(w.bp[K_SAP_SET], &st), MK_OK);
        sweeps_seen += st.sweeps > sweeps_before;
        back_to_sorts += st.full_rebuilds > rebuilds_before && sweeps_seen > 0;
    }
    ck_assert_int_gt(sweeps_seen, 10);
    ck_assert_int_gt(back_to_sorts, 0);
    ck_assert_int_lt(sweeps_seen, 240);
    world_fini(&w);
}
END_TEST

START_TEST(coherent_motion) { run_motion(1, 300, 12, 1, 2, 0, 0, 0, 200); }
END_TEST
START_TEST(teleports) { run_motion(2, 300, 12, 1, 2, 0, 0.1, 0, 150); }
END_TEST
START_TEST(churn) { run_motion(3, 250, 12, 1, 2, 0, 0, 0.01, 300); }
END_TEST
START_TEST(mixed_sizes_1_to_1000) { run_motion(4, 300, 40, 0.02, 20, 0, 0.01, 0.005, 150); }
END_TEST
START_TEST(static_dynamic_mix) { run_motion(5, 400, 14, 0.5, 2, 0.8, 0.02, 0.005, 150); }
END_TEST

/* The grid files its coarsest size level one level finer while the finer
 * boxes outnumber it 4 to 1 (their guest candidates with it are what the
 * scene pays for): big boxes come (20 among 240 small: filed finer), more
 * come (100: filed at their own level again, re-filed as they cross cell
 * walls) and all go (the small ones' level is the coarsest again); the set
 * stays exact through every change of the rule. */
START_TEST(top_level_filed_finer)
{
    static world w;
    int i, f, first_big = 0;
    if (!world_init(&w, 41, MAXN, 0)) return;
    for (i = 0; i < 240; ++i) {
        add_obj(&w, random_box(&w.rng, 30, 0.5, 2), 0);
        w.o[i].vel = mk_v3_scale(mk_rng_dir(&w.rng), (mk_real)0.1);
    }
    for (f = 0; f < 120; ++f) {
        int add = f == 0 ? 20 : f == 40 ? 80 : 0;
        if (f == 0) first_big = w.n;
        for (i = 0; i < add && w.n < MAXN; ++i) {
            add_obj(&w, random_box(&w.rng, 30, 6, 8), 0);
            w.o[w.n - 1].vel = mk_v3_scale(mk_rng_dir(&w.rng), (mk_real)0.4);
        }
        if (f == 80)
            for (i = first_big; i < w.n; ++i)
                if (w.o[i].alive) kill_obj(&w, i);
        for (i = 0; i < w.n; ++i)
            if (w.o[i].alive) drift(&w, i, 1);
        step(&w, f);
    }
    world_fini(&w);
}
END_TEST

/* AUTO starts small and coherent (SAP), then the scene grows past what SAP
 * is good at (hundreds of boxes each passing several others a frame) and
 * AUTO switches to the grid: the set stays exact and the events replay
 * across the switch. */
START_TEST(auto_switches_structure)
{
    static world w;
    mk_bp_stats st;
    int i, f;
    if (!world_init(&w, 12, MAXN, 0)) return;
    for (i = 0; i < 40; ++i) {
        add_obj(&w, random_box(&w.rng, 6, 1, 2), 0);
        w.o[i].vel = mk_v3_scale(mk_rng_dir(&w.rng), (mk_real)0.05);
    }
    for (f = 0; f < 100; ++f) {
        if (f == 20)
            for (i = 0; i < 260; ++i) {
                add_obj(&w, random_box(&w.rng, 14, 1, 2), 0);
                w.o[w.n - 1].vel = mk_v3_scale(mk_rng_dir(&w.rng), (mk_real)0.3);
            }
        for (i = 0; i < w.n; ++i) drift(&w, i, 1);
        step(&w, f);
        if (f == 10 && w.bp[3]) {
            MK_ASSERT_STATUS(mk_bp_get_stats(w.bp[3], &st), MK_OK);
            ck_assert_int_eq(st.kind, MK_BP_SAP);
        }
    }
    if (w.bp[3]) {
        MK_ASSERT_STATUS(mk_bp_get_stats(w.bp[3], &st), MK_OK);
        ck_assert_int_eq(st.kind, MK_BP_HGRID);
        ck_assert_int_ge(st.switches, 1);
    }
    /* The scene comes to rest: the host still moves every proxy, but to the
     * box it already has (no move at all), and only 5 keep drifting: SAP. */
    for (f = 100; f < 200; ++f) {
        for (i = 0; i < w.n; ++i) {
            if (i % 60 == 0) drift(&w, i, 1);
            else move_obj(&w, i, w.o[i].box);
        }
        step(&w, f);
    }
    if (w.bp[3]) {
        MK_ASSERT_STATUS(mk_bp_get_stats(w.bp[3], &st), MK_OK);
        ck_assert_int_eq(st.kind, MK_BP_SAP);
        ck_assert_int_ge(st.switches, 2);
    }
    world_fini(&w);
}
END_TEST

/* AUTO for a caller with events, many movers, few statics: a block of
 * touching cubes falling as one keeps every endpoint's order (SAP swaps
 * nothing, while the grid would re-test every touching pair): SAP. The block
 * then bursts, every cube flying off its own way past hundreds of
 * endpoints: the grid. Exact sets and replayed events all along. */
START_TEST(auto_weighs_swaps_against_candidates)
{
    static world w;
    mk_bp_stats st;
    int i, f;
    if (!world_init(&w, 41, MAXN, 0) || !w.bp[3]) return;
    for (i = 0; i < 6 * 6 * 8; ++i) {
        mk_vec3 c = mk_v3((mk_real)(i % 6), (mk_real)((i / 6) % 6), (mk_real)(i / 36));
        add_obj(&w, box_at(c, mk_v3(MK_REAL(0.5), MK_REAL(0.5), MK_REAL(0.5))), 0);
        w.o[i].vel = mk_v3(0, 0, MK_REAL(-0.02));
    }
    for (f = 0; f < 200; ++f) {
        if (f == 70)
            for (i = 0; i < w.n; ++i) w.o[i].vel = mk_v3_scale(mk_rng_dir(&w.rng), MK_REAL(0.4));
        for (i = 0; i < w.n; ++i) drift(&w, i, 1);
        step(&w, f);
        if (f == 66 || f == 199) {
            MK_ASSERT_STATUS(mk_bp_get_stats(w.bp[3], &st), MK_OK);
            ck_assert_int_eq(st.kind, f == 66 ? MK_BP_SAP : MK_BP_HGRID);
        }
    }
    world_fini(&w);
}
END_TEST

/* Unit cubes on an integer lattice: neighbours touch exactly (closed intervals). */
START_TEST(touching_lattice)
{
    static world w;
    int x, y, z, f, i;
    if (!world_init(&w, 6, MAXN, 0)) return;
    for (x = 0; x < 6; ++x)
        for (y = 0; y < 6; ++y)
            for (z = 0; z < 6; ++z)
                add_obj(&w, mk_aabb_make(mk_v3((mk_real)x, (mk_real)y, (mk_real)z), mk_v3((mk_real)x + 1, (mk_real)y + 1, (mk_real)z + 1)), 0);
    step(&w, 0);
    /* Each cube touches its 26 neighbours: ((5 + 6 + 5)^3 - 6^3) / 2 pairs. */
    ck_assert_int_eq(w.prev_count[0], 1940);
    /* Slide every other row by exact unit steps: contacts appear and vanish exactly at touching. */
    for (f = 1; f < 40; ++f) {
        for (i = 0; i < w.n; ++i) {
            mk_real dx = (mk_real)((i % 2) ? 0.5 : -0.5) * (mk_real)((f / 4) % 2 ? 1 : -1);
            mk_aabb b = w.o[i].box;
            if (w.o[i].is_static) continue;
            b.lo.x += dx; b.hi.x += dx;
            move_obj(&w, i, b);
        }
        step(&w, f);
    }
    world_fini(&w);
}
END_TEST

/* Points, specks, a huge box, infinite planes and slabs, far-away coordinates. */
START_TEST(tiny_huge_infinite)
{
    static world w;
    const mk_real inf = (mk_real)INFINITY;
    int i, f;
    if (!world_init(&w, 7, MAXN, 0)) return;
    add_obj(&w, mk_aabb_make(mk_v3(-inf, -inf, -inf), mk_v3(inf, inf, 0)), 1);      /* ground plane z <= 0 */
    add_obj(&w, mk_aabb_make(mk_v3(-inf, 3, -inf), mk_v3(inf, 3.5, inf)), 0);        /* slab, dynamic */
    add_obj(&w, mk_aabb_make(mk_v3(-500, -500, -500), mk_v3(500, 500, 2)), 0);      /* huge */
    add_obj(&w, mk_aabb_make(mk_v3(5, -inf, 1), mk_v3(inf, inf, 1)), 1);              /* half-infinite sheet */
    for (i = 0; i < 200; ++i) {
        mk_vec3 c = mk_rng_v3(&w.rng, -6, 6);
        mk_real h = (mk_real)(i % 3 == 0 ? 0 : 1e-6 * (i % 7));
        add_obj(&w, box_at(c, mk_v3(h, h, h)), i % 5 == 0);
        w.o[w.n - 1].vel = mk_v3_scale(mk_rng_dir(&w.rng), (mk_real)0.05);
    }
    for (i = 0; i < 40; ++i) {
        mk_vec3 c = mk_v3_add(mk_v3(1e6, -1e6, 1e5), mk_rng_v3(&w.rng, -2, 2));
        add_obj(&w, box_at(c, mk_v3(0.5, 0.5, 0.5)), 0);
        w.o[w.n - 1].vel = mk_v3_scale(mk_rng_dir(&w.rng), (mk_real)0.1);
    }
    for (f = 0; f < 120; ++f) {
        for (i = 4; i < w.n; ++i) if (!w.o[i].is_static) drift(&w, i, 1);
        if (f % 10 == 0) {
            mk_aabb s = w.o[1].box;
            s.lo.y = (mk_real)mk_rng_range(&w.rng, -6, 6); s.hi.y = s.lo.y + (mk_real)0.5;
            move_obj(&w, 1, s);
        }
        if (f == 60) kill_obj(&w, 0);
        if (f == 80) add_obj(&w, mk_aabb_make(mk_v3(-inf, -inf, -inf), mk_v3(inf, inf, 0)), 1);
        step(&w, f);
    }
    world_fini(&w);
}
END_TEST

START_TEST(filters_and_refilter)
{
    static world w;
    int i, f, k;
    if (!world_init(&w, 8, MAXN, 1)) return;
    for (i = 0; i < 250; ++i) {
        add_obj(&w, random_box(&w.rng, 10, 1, 2), 0);
        w.o[i].vel = mk_v3_scale(mk_rng_dir(&w.rng), (mk_real)0.1);
    }
    for (f = 0; f < 60; ++f) {
        for (i = 0; i < w.n; ++i) drift(&w, i, 1);
        step(&w, f);
    }
    /* Refilter: a zero mask under no built-in mode changes nothing, the
     * callback still decides; the pair set must stay exact. */
    for (k = 0; k < NKIND; ++k)
        if (w.bp[k]) MK_ASSERT_STATUS(mk_bp_set_filter(w.bp[k], w.o[3].id[k], 0, 0), MK_OK);
    step(&w, 60);
    world_fini(&w);
}
END_TEST

/* Bullet's AND and ODE's OR on the filter words, and changing them later. */
START_TEST(filter_modes)
{
    int mode, k;
    for (mode = MK_BP_FILTER_AND; mode <= MK_BP_FILTER_OR; ++mode)
        for (k = 0; k < NKIND; ++k) {
            mk_bp_def d = mk_bp_default_def();
            mk_bp *bp;
            mk_bp_id a, b, c;
            int n;
            mk_aabb box = mk_aabb_make(mk_v3(0, 0, 0), mk_v3(1, 1, 1));
            d.kind = kinds[k];
            d.pairs_only = only_pairs[k];
            d.filter_mode = (mk_bp_filter_mode)mode;
            if (mk_bp_create(&d, NULL, &bp) == MK_ERR_UNSUPPORTED) continue;
            /* a: cat 1 mask 2; b: cat 2 mask 0; c: cat 2 mask 1 */
            MK_ASSERT_STATUS(mk_bp_create_proxy(bp, box, NULL, 1, 2, 0, &a), MK_OK);
            MK_ASSERT_STATUS(mk_bp_create_proxy(bp, box, NULL, 2, 0, 0, &b), MK_OK);
            MK_ASSERT_STATUS(mk_bp_create_proxy(bp, box, NULL, 2, 1, 0, &c), MK_OK);
            MK_ASSERT_STATUS(mk_bp_update(bp), MK_OK);
            mk_bp_pairs(bp, &n);
            /* a-b: (1&0)=0, (2&2)!=0 -> AND no, OR yes. a-c: both -> yes. b-c: (2&1)=0,(2&0)=0 -> no. */
            ck_assert_int_eq(n, mode == MK_BP_FILTER_AND ? 1 : 2);
            MK_ASSERT_STATUS(mk_bp_set_filter(bp, b, 2, 1), MK_OK); /* now a-b passes AND too */
            MK_ASSERT_STATUS(mk_bp_update(bp), MK_OK);
            mk_bp_pairs(bp, &n);
            ck_assert_int_eq(n, 2);
            MK_ASSERT_STATUS(mk_bp_set_filter(bp, a, 0, 0), MK_OK);
            MK_ASSERT_STATUS(mk_bp_update(bp), MK_OK);
            mk_bp_pairs(bp, &n);
            ck_assert_int_eq(n, 0);
            mk_bp_removed(bp, &n);
            ck_assert_int_eq(n, only_pairs[k] ? 0 : 2);
            (void)c;
            mk_bp_destroy(bp);
        }
}
END_TEST

/* ---- queries ---- */

typedef struct hits { int n; int seen[MAXN]; } hits;
static int on_hit(void *ctx, mk_bp_id id, void *user)
{
    hits *h = (hits *)ctx;
    (void)id;
    h->seen[h->n++] = (int)(intptr_t)user - 1;
    return 1;
}
typedef struct ray_hits { int n; int seen[MAXN]; mk_real t[MAXN]; } ray_hits;
static mk_real on_ray(void *ctx, mk_bp_id id, void *user, mk_real t, mk_real max)
{
    ray_hits *h = (ray_hits *)ctx;
    (void)id;
    h->t[h->n] = t;
    h->seen[h->n++] = (int)(intptr_t)user - 1;
    return max;
}
static int int_cmp(const void *a, const void *b) { return *(const int *)a - *(const int *)b; }

/* Exact segment-vs-box entry fraction in double, or -1. */
static double ray_entry(mk_vec3 from, mk_vec3 to, mk_aabb b)
{
    double t0 = 0, t1 = 1;
    const mk_real *f = &from.x, *e = &to.x, *lo = &b.lo.x, *hi = &b.hi.x;
    int k;
    for (k = 0; k < 3; ++k) {
        double d = (double)e[k] - (double)f[k], a, c;
        if (d == 0) { if (f[k] < lo[k] || f[k] > hi[k]) return -1; continue; }
        a = ((double)lo[k] - f[k]) / d; c = ((double)hi[k] - f[k]) / d;
        if (a > c) { double t = a; a = c; c = t; }
        if (a > t0) t0 = a;
        if (c < t1) t1 = c;
        if (t0 > t1) return -1;
    }
    return t0;
}

START_TEST(region_and_ray_queries)
{
    static world w;
    static hits h;
    static ray_hits rh;
    int i, f, k, q;
    if (!world_init(&w, 9, MAXN, 0)) return;
    for (i = 0; i < 300; ++i) {
        add_obj(&w, random_box(&w.rng, 20, 0.05, 5), i % 4 == 0);
        w.o[i].vel = mk_v3_scale(mk_rng_dir(&w.rng), (mk_real)0.1);
    }
    add_obj(&w, mk_aabb_make(mk_v3(-(mk_real)INFINITY, -(mk_real)INFINITY, -(mk_real)INFINITY), mk_v3((mk_real)INFINITY, (mk_real)INFINITY, -1)), 1);
    for (f = 0; f < 16; ++f) {
        for (i = 0; i < 300; ++i) {
            if (!w.o[i].alive || w.o[i].is_static) continue;
            /* from frame 8 on, teleports: pairs_only SAP answers by stateless sweeps */
            if (f >= 8 && mk_rng_unit(&w.rng) < 0.3) move_obj(&w, i, box_at(mk_rng_v3(&w.rng, 0, 20), mk_aabb_extents(w.o[i].box)));
            else drift(&w, i, 1);
        }
        if (f == 5) kill_obj(&w, 7);
        if (f == 12) kill_obj(&w, 9);
        step(&w, f);
        for (q = 0; q < 20; ++q) {
            mk_aabb box = q == 0 ? mk_aabb_make(mk_v3(-1e9, -1e9, -1e9), mk_v3(1e9, 1e9, 1e9)) : random_box(&w.rng, 20, 0.1, 8);
            mk_bp_ray ray;
            int want[MAXN], nw = 0;
            memset(&ray, 0, sizeof ray);
            ray.from = mk_rng_v3(&w.rng, -2, 22);
            ray.to = mk_rng_v3(&w.rng, -2, 22);
            for (i = 0; i < w.n; ++i) if (w.o[i].alive && mk_aabb_overlap(w.o[i].box, box)) want[nw++] = i;
            for (k = 0; k < NKIND; ++k) {
                if (!w.bp[k]) continue;
                h.n = 0;
                MK_ASSERT_STATUS(mk_bp_query_aabb(w.bp[k], box, on_hit, &h), MK_OK);
                qsort(h.seen, (size_t)h.n, sizeof(int), int_cmp);
                ck_assert_msg(h.n == nw && memcmp(h.seen, want, sizeof(int) * (size_t)nw) == 0,
                              "%s: region query %d found %d, truth %d", name_of(k), q, h.n, nw);
                rh.n = 0;
                MK_ASSERT_STATUS(mk_bp_raycast(w.bp[k], &ray, on_ray, &rh), MK_OK);
                for (i = 0; i < rh.n; ++i) {
                    double t = ray_entry(ray.from, ray.to, w.o[rh.seen[i]].box);
                    ck_assert_msg(t >= 0, "%s: ray reported a box it misses", name_of(k));
                    MK_ASSERT_NEAR(rh.t[i], t, 1e-5 * (1 + fabs(t)));
                }
                {   /* every box the exact test hits must be reported */
                    int hit = 0, j;
                    for (i = 0; i < w.n; ++i) {
                        if (!w.o[i].alive || ray_entry(ray.from, ray.to, w.o[i].box) < 0) continue;
                        ++hit;
                        for (j = 0; j < rh.n && rh.seen[j] != i; ++j) {}
                        ck_assert_msg(j < rh.n, "%s: ray missed object %d", name_of(k), i);
                    }
                    ck_assert_int_eq(hit, rh.n);
                }
            }
        }
    }
    if (w.bp[K_SAP_SET]) {
        mk_bp_stats st;
        MK_ASSERT_STATUS(mk_bp_get_stats(w.bp[K_SAP_SET], &st), MK_OK);
        ck_assert_int_gt(st.sweeps, 0);
    }
    world_fini(&w);
}
END_TEST

/* The grid's static index: mostly statics in two far-apart clusters (the
 * index hashes its cells then) or one (a dense array of cells), slow and
 * fast movers among them (every one fast: the grid files them a level
 * coarser); now and then a static moves (it leaves the index) or one goes
 * and another comes (enough of that rebuilds the index); the filter refuses
 * some pairs; region queries see indexed statics. */
static void run_statics(uint64_t seed, double apart, int fast_every)
{
    static world w;
    static hits h;
    int i, f, k, q;
    if (!world_init(&w, seed, MAXN, 1)) return;
    for (i = 0; i < 400; ++i) {
        mk_aabb b = random_box(&w.rng, 12, 0.3, 3);
        mk_vec3 off = mk_v3((mk_real)(i % 2 ? apart : 0), 0, 0);
        add_obj(&w, mk_aabb_make(mk_v3_add(b.lo, off), mk_v3_add(b.hi, off)), i % 5 != 0);
        w.o[i].vel = mk_v3_scale(mk_rng_dir(&w.rng), (mk_real)(i % fast_every == 0 ? 0.4 : 0.03));
    }
    for (f = 0; f < 160; ++f) {
        for (i = 0; i < w.n; ++i) {
            if (!w.o[i].alive) continue;
            if (!w.o[i].is_static) drift(&w, i, 1);
            else if (mk_rng_unit(&w.rng) < 0.003) drift(&w, i, 3);
        }
        if (f % 2 == 0 && w.n < MAXN) { /* a static goes, another comes */
            for (i = (int)(mk_rng_unit(&w.rng) * w.n); !w.o[i].alive || !w.o[i].is_static; i = (i + 1) % w.n) {}
            kill_obj(&w, i);
            add_obj(&w, w.o[i].box, 1);
        }
        step(&w, f);
        for (q = 0; q < 4; ++q) {
            mk_aabb box = random_box(&w.rng, 14, 0.5, 6);
            int want[MAXN], nw = 0;
            for (i = 0; i < w.n; ++i) if (w.o[i].alive && mk_aabb_overlap(w.o[i].box, box)) want[nw++] = i;
            for (k = 0; k < NKIND; ++k) {
                if (!w.bp[k]) continue;
                h.n = 0;
                MK_ASSERT_STATUS(mk_bp_query_aabb(w.bp[k], box, on_hit, &h), MK_OK);
                qsort(h.seen, (size_t)h.n, sizeof(int), int_cmp);
                ck_assert_msg(h.n == nw && memcmp(h.seen, want, sizeof(int) * (size_t)nw) == 0,
                              "%s: region query found %d, truth %d (frame %d)", name_of(k), h.n, nw, f);
            }
        }
    }
    if (w.bp[2]) { /* the index was rebuilt: the grid rebuilt itself at least once */
        mk_bp_stats st;
        MK_ASSERT_STATUS(mk_bp_get_stats(w.bp[2], &st), MK_OK);
        ck_assert_int_gt(st.full_rebuilds, 1);
    }
    world_fini(&w);
}

START_TEST(static_index_dense) { run_statics(21, 0, 3); }
END_TEST

START_TEST(static_index_hashed) { run_statics(22, 5000, 3); }
END_TEST

START_TEST(static_index_fast_movers) { run_statics(23, 0, 1); }
END_TEST

/* A swept box and early clipping. */
static mk_real clip_first(void *ctx, mk_bp_id id, void *user, mk_real t, mk_real max)
{
    (void)id; (void)user; (void)max;
    ++*(int *)ctx;
    return t;
}
START_TEST(swept_box_and_clipping)
{
    int k;
    for (k = 0; k < NKIND; ++k) {
        mk_bp_def d = mk_bp_default_def();
        mk_bp *bp;
        mk_bp_id id;
        mk_bp_ray ray;
        int calls = 0, x;
        d.kind = kinds[k];
        d.pairs_only = only_pairs[k];
        if (mk_bp_create(&d, NULL, &bp) == MK_ERR_UNSUPPORTED) continue;
        for (x = 0; x < 10; ++x)
            MK_ASSERT_STATUS(mk_bp_create_proxy(bp, mk_aabb_make(mk_v3((mk_real)(10 * x + 5), 2, -1), mk_v3((mk_real)(10 * x + 6), 3, 1)), NULL, 1, 1, 1, &id), MK_OK);
        MK_ASSERT_STATUS(mk_bp_update(bp), MK_OK);
        memset(&ray, 0, sizeof ray);
        ray.to = mk_v3(200, 0, 0);
        MK_ASSERT_STATUS(mk_bp_raycast(bp, &ray, clip_first, &calls), MK_OK);
        ck_assert_int_eq(calls, 0); /* thin ray at y = 0 misses boxes at y in [2, 3] */
        ray.box_lo = mk_v3(-1, -2, -1); ray.box_hi = mk_v3(1, 2, 1); /* swept box reaches y = 2 exactly */
        MK_ASSERT_STATUS(mk_bp_raycast(bp, &ray, clip_first, &calls), MK_OK);
        ck_assert_int_ge(calls, 1);
        ck_assert_int_le(calls, 10);
        mk_bp_destroy(bp);
    }
}
END_TEST

/* ---- capacities, memory, bad input ---- */

typedef struct counting { long allocs, frees; size_t live; } counting;
static void *c_alloc(void *ctx, size_t size, size_t align) { counting *c = (counting *)ctx; (void)align; c->allocs++; c->live += size; return malloc(size); }
static void c_free(void *ctx, void *p, size_t size) { counting *c = (counting *)ctx; c->frees++; c->live -= size; free(p); }

START_TEST(steady_state_does_not_allocate)
{
    int k;
    for (k = 0; k < NKIND; ++k) {
        counting c = {0, 0, 0};
        mk_allocator al;
        mk_bp_def d = mk_bp_default_def();
        mk_bp *bp;
        mk_bp_id ids[200];
        mk_rng r = {11};
        int i, f;
        long before;
        al.alloc = c_alloc; al.free = c_free; al.ctx = &c;
        d.kind = kinds[k];
        d.pairs_only = only_pairs[k];
        d.proxy_capacity = 200;
        d.pair_capacity = 16; /* deliberately small: the pair set must grow */
        if (mk_bp_create(&d, &al, &bp) == MK_ERR_UNSUPPORTED) continue;
        for (i = 0; i < 200; ++i) MK_ASSERT_STATUS(mk_bp_create_proxy(bp, random_box(&r, 8, 1, 2), NULL, 1, 1, 0, &ids[i]), MK_OK);
        for (f = 0; f < 10; ++f) MK_ASSERT_STATUS(mk_bp_update(bp), MK_OK);
        before = c.allocs;
        for (f = 0; f < 50; ++f) {
            for (i = 0; i < 200; ++i) {
                mk_aabb b;
                MK_ASSERT_STATUS(mk_bp_get_proxy(bp, ids[i], &b, NULL), MK_OK);
                b.lo.x += (mk_real)(f % 2 ? 0.01 : -0.01); b.hi.x += (mk_real)(f % 2 ? 0.01 : -0.01);
                MK_ASSERT_STATUS(mk_bp_move_proxy(bp, ids[i], b), MK_OK);
            }
            MK_ASSERT_STATUS(mk_bp_update(bp), MK_OK);
        }
        ck_assert_msg(c.allocs == before, "%s allocated %ld times in the steady state", name_of(k), c.allocs - before);
        mk_bp_destroy(bp);
        ck_assert_int_eq((int)c.live, 0);
        ck_assert_int_eq((int)c.allocs, (int)c.frees);
    }
}
END_TEST

START_TEST(fixed_capacity_overflow_recovers)
{
    int k;
    for (k = 0; k < NKIND; ++k) {
        mk_bp_def d = mk_bp_default_def();
        mk_bp *bp;
        mk_bp_id ids[40], extra;
        int i, n;
        d.kind = kinds[k];
        d.pairs_only = only_pairs[k];
        d.proxy_capacity = 40;
        d.pair_capacity = 20;
        d.fixed_capacity = 1;
        if (mk_bp_create(&d, NULL, &bp) == MK_ERR_UNSUPPORTED) continue;
        /* 40 boxes all overlapping: 780 pairs do not fit in 20 */
        for (i = 0; i < 40; ++i) MK_ASSERT_STATUS(mk_bp_create_proxy(bp, mk_aabb_make(mk_v3(0, 0, 0), mk_v3(1, 1, 1)), NULL, 1, 1, 0, &ids[i]), MK_OK);
        MK_ASSERT_STATUS(mk_bp_create_proxy(bp, mk_aabb_make(mk_v3(0, 0, 0), mk_v3(1, 1, 1)), NULL, 1, 1, 0, &extra), MK_ERR_CAPACITY);
        MK_ASSERT_STATUS(mk_bp_update(bp), MK_ERR_CAPACITY);
        mk_bp_pairs(bp, &n);
        ck_assert_int_le(n, 20);
        /* move all but 6 far apart: 15 pairs fit; the next update is exact again */
        for (i = 6; i < 40; ++i) {
            mk_real x = (mk_real)(10 * i);
            MK_ASSERT_STATUS(mk_bp_move_proxy(bp, ids[i], mk_aabb_make(mk_v3(x, 0, 0), mk_v3(x + 1, 1, 1))), MK_OK);
        }
        ck_assert_msg(mk_bp_update(bp) == MK_OK, "%s did not recover", name_of(k));
        mk_bp_pairs(bp, &n);
        ck_assert_int_eq(n, 15);
        MK_ASSERT_STATUS(mk_bp_update(bp), MK_OK);
        mk_bp_pairs(bp, &n);
        ck_assert_int_eq(n, 15);
        mk_bp_destroy(bp);
    }
}
END_TEST

START_TEST(bad_input)
{
    mk_bp_def d = mk_bp_default_def();
    mk_bp *bp;
    mk_bp_id id, old;
    mk_aabb ok = mk_aabb_make(mk_v3(0, 0, 0), mk_v3(1, 1, 1)), bad;
    mk_bp_ray ray;
    const mk_real inf = (mk_real)INFINITY, nan = (mk_real)NAN;
    int k;
    MK_ASSERT_STATUS(mk_bp_create(NULL, NULL, NULL), MK_ERR_NULL);
    d.proxy_capacity = 0;
    MK_ASSERT_STATUS(mk_bp_create(&d, NULL, &bp), MK_ERR_BAD_SIZE);
    ck_assert_ptr_null(bp);
    d = mk_bp_default_def();
    d.kind = (mk_bp_kind)42;
    MK_ASSERT_STATUS(mk_bp_create(&d, NULL, &bp), MK_ERR_BAD_ARGUMENT);
    d = mk_bp_default_def();
    d.filter_mode = (mk_bp_filter_mode)9;
    MK_ASSERT_STATUS(mk_bp_create(&d, NULL, &bp), MK_ERR_BAD_ARGUMENT);
    for (k = 0; k < NKIND; ++k) {
        d = mk_bp_default_def();
        d.kind = kinds[k];
        d.pairs_only = only_pairs[k];
        d.proxy_capacity = 2;
        if (mk_bp_create(&d, NULL, &bp) == MK_ERR_UNSUPPORTED) continue;
        bad = ok; bad.lo.y = nan;
        MK_ASSERT_STATUS(mk_bp_create_proxy(bp, bad, NULL, 1, 1, 0, &id), MK_ERR_BAD_AABB);
        ck_assert_uint_eq(id, MK_BP_NULL_ID);
        bad = ok; bad.lo.x = 2;
        MK_ASSERT_STATUS(mk_bp_create_proxy(bp, bad, NULL, 1, 1, 0, &id), MK_ERR_BAD_AABB);
        bad = ok; bad.lo.z = inf; bad.hi.z = inf;
        MK_ASSERT_STATUS(mk_bp_create_proxy(bp, bad, NULL, 1, 1, 0, &id), MK_ERR_BAD_AABB);
        bad = ok; bad.lo.z = -inf; bad.hi.z = -inf;
        MK_ASSERT_STATUS(mk_bp_create_proxy(bp, bad, NULL, 1, 1, 0, &id), MK_ERR_BAD_AABB);
        MK_ASSERT_STATUS(mk_bp_create_proxy(NULL, ok, NULL, 1, 1, 0, &id), MK_ERR_NULL);
        MK_ASSERT_STATUS(mk_bp_create_proxy(bp, ok, NULL, 1, 1, 0, NULL), MK_ERR_NULL);
        MK_ASSERT_STATUS(mk_bp_create_proxy(bp, ok, NULL, 1, 1, 0, &old), MK_OK);
        MK_ASSERT_STATUS(mk_bp_create_proxy(bp, ok, NULL, 1, 1, 0, &id), MK_OK);
        MK_ASSERT_STATUS(mk_bp_create_proxy(bp, ok, NULL, 1, 1, 0, &id), MK_ERR_CAPACITY);
        bad = ok; bad.hi.x = nan;
        MK_ASSERT_STATUS(mk_bp_move_proxy(bp, old, bad), MK_ERR_BAD_AABB);
        MK_ASSERT_STATUS(mk_bp_move_proxy(bp, MK_BP_NULL_ID, ok), MK_ERR_UNKNOWN_ID);
        MK_ASSERT_STATUS(mk_bp_move_proxy(bp, 0xFFFFFF01u, ok), MK_ERR_UNKNOWN_ID);
        MK_ASSERT_STATUS(mk_bp_update(bp), MK_OK);
        MK_ASSERT_STATUS(mk_bp_destroy_proxy(bp, old), MK_OK);
        /* stale: destroyed, and after its slot is reused */
        MK_ASSERT_STATUS(mk_bp_move_proxy(bp, old, ok), MK_ERR_UNKNOWN_ID);
        MK_ASSERT_STATUS(mk_bp_update(bp), MK_OK);
        MK_ASSERT_STATUS(mk_bp_create_proxy(bp, ok, NULL, 1, 1, 0, &id), MK_OK);
        ck_assert_uint_ne(id, old);
        MK_ASSERT_STATUS(mk_bp_move_proxy(bp, old, ok), MK_ERR_UNKNOWN_ID);
        MK_ASSERT_STATUS(mk_bp_set_filter(bp, old, 1, 1), MK_ERR_UNKNOWN_ID);
        MK_ASSERT_STATUS(mk_bp_get_proxy(bp, old, NULL, NULL), MK_ERR_UNKNOWN_ID);
        ck_assert_ptr_null(mk_bp_user(bp, old));
        MK_ASSERT_STATUS(mk_bp_destroy_proxy(bp, old), MK_ERR_UNKNOWN_ID);
        MK_ASSERT_STATUS(mk_bp_query_aabb(bp, ok, NULL, NULL), MK_ERR_NULL);
        bad = ok; bad.lo.x = nan;
        MK_ASSERT_STATUS(mk_bp_query_aabb(bp, bad, on_hit, NULL), MK_ERR_BAD_AABB);
        memset(&ray, 0, sizeof ray);
        ray.to.x = nan;
        MK_ASSERT_STATUS(mk_bp_raycast(bp, &ray, on_ray, NULL), MK_ERR_NOT_FINITE);
        ray.to.x = 1; ray.box_lo.x = 1;
        MK_ASSERT_STATUS(mk_bp_raycast(bp, &ray, on_ray, NULL), MK_ERR_BAD_AABB);
        MK_ASSERT_STATUS(mk_bp_update(NULL), MK_ERR_NULL);
        MK_ASSERT_STATUS(mk_bp_get_stats(bp, NULL), MK_ERR_NULL);
        mk_bp_destroy(bp);
    }
    mk_bp_destroy(NULL);
}
END_TEST

START_TEST(ids_and_stats)
{
    mk_bp_def d = mk_bp_default_def();
    mk_bp *bp;
    mk_bp_id a, b;
    mk_bp_stats st;
    int n;
    const mk_bp_pair *p;
    d.proxy_capacity = 8;
    MK_ASSERT_STATUS(mk_bp_create(&d, NULL, &bp), MK_OK);
    MK_ASSERT_STATUS(mk_bp_create_proxy(bp, mk_aabb_make(mk_v3(0, 0, 0), mk_v3(1, 1, 1)), (void *)&d, 1, 1, 0, &a), MK_OK);
    MK_ASSERT_STATUS(mk_bp_create_proxy(bp, mk_aabb_make(mk_v3(1, 1, 1), mk_v3(2, 2, 2)), NULL, 1, 1, 1, &b), MK_OK);
    ck_assert_ptr_eq(mk_bp_user(bp, a), &d);
    MK_ASSERT_STATUS(mk_bp_update(bp), MK_OK);
    p = mk_bp_pairs(bp, &n);
    ck_assert_int_eq(n, 1); /* corner to corner: closed boxes touch */
    ck_assert_uint_eq(p[0].a, a < b ? a : b);
    MK_ASSERT_STATUS(mk_bp_get_stats(bp, &st), MK_OK);
    ck_assert_int_eq(st.requested, MK_BP_AUTO);
    ck_assert_int_ne(st.kind, MK_BP_AUTO);
    ck_assert_int_eq(st.proxies, 2);
    ck_assert_int_eq(st.static_proxies, 1);
    ck_assert_int_eq(st.pairs, 1);
    ck_assert_int_gt((int)st.bytes, 0);
    ck_assert_str_ne(mk_bp_kind_name(st.kind), "unknown");
    ck_assert_str_ne(mk_bp_kind_name(st.kind), "auto");
    mk_bp_destroy(bp);
}
END_TEST

/* A host's own array of bodies: the batch reads ids and boxes out of it. */
typedef struct host_body { double mass; mk_bp_id id; mk_aabb box; char tag; } host_body;

static void same_output(mk_bp *x, mk_bp *y, int frame)
{
    int nx, ny;
    const mk_bp_pair *px = mk_bp_pairs(x, &nx), *py = mk_bp_pairs(y, &ny);
    ck_assert_msg(nx == ny, "frame %d: batch %d pairs, single moves %d", frame, nx, ny);
    ck_assert_msg(nx == 0 || memcmp(px, py, sizeof *px * (size_t)nx) == 0, "frame %d: sets differ", frame);
    px = mk_bp_added(x, &nx); py = mk_bp_added(y, &ny);
    ck_assert_msg(nx == ny && (nx == 0 || memcmp(px, py, sizeof *px * (size_t)nx) == 0), "frame %d: added differ", frame);
    px = mk_bp_removed(x, &nx); py = mk_bp_removed(y, &ny);
    ck_assert_msg(nx == ny && (nx == 0 || memcmp(px, py, sizeof *px * (size_t)nx) == 0), "frame %d: removed differ", frame);
}

/* mk_bp_move_proxies from a strided host array (with free slots, resting
 * bodies and teleports) gives the same sets and events as single moves, for
 * every kind; the two broadphases get the same ids since they see the same
 * creations. */
START_TEST(batch_moves_match_single_moves)
{
    enum { N = 300, FRAMES = 60 };
    static host_body body[N];
    int k, i, f;
    for (k = 0; k < NKIND; ++k) {
        mk_rng rng;
        mk_bp *single, *batch;
        mk_bp_def d = mk_bp_default_def();
        d.kind = kinds[k];
        d.pairs_only = only_pairs[k];
        d.proxy_capacity = N;
        if (mk_bp_create(&d, NULL, &single) == MK_ERR_UNSUPPORTED) continue;
        MK_ASSERT_STATUS(mk_bp_create(&d, NULL, &batch), MK_OK);
        rng.s = 31 + (uint64_t)k;
        for (i = 0; i < N; ++i) {
            mk_vec3 c = mk_rng_v3(&rng, 0, 20);
            mk_bp_id other;
            body[i].box = mk_aabb_make(c, mk_v3_add(c, mk_v3(1, 1, 1)));
            MK_ASSERT_STATUS(mk_bp_create_proxy(batch, body[i].box, NULL, 1, 1, i % 10 == 0, &body[i].id), MK_OK);
            MK_ASSERT_STATUS(mk_bp_create_proxy(single, body[i].box, NULL, 1, 1, i % 10 == 0, &other), MK_OK);
            ck_assert_uint_eq(other, body[i].id);
        }
        for (f = 0; f < FRAMES; ++f) {
            int done = -1;
            for (i = 0; i < N; ++i) {
                double r = mk_rng_unit(&rng);
                if (body[i].id == MK_BP_NULL_ID || r < 0.3) continue; /* resting */
                if (r < 0.32) { /* teleport */
                    mk_vec3 c = mk_rng_v3(&rng, 0, 20);
                    body[i].box = mk_aabb_make(c, mk_v3_add(c, mk_v3(1, 1, 1)));
                } else {
                    mk_vec3 v = mk_rng_v3(&rng, -0.1, 0.1);
                    body[i].box = mk_aabb_make(mk_v3_add(body[i].box.lo, v), mk_v3_add(body[i].box.hi, v));
                }
                MK_ASSERT_STATUS(mk_bp_move_proxy(single, body[i].id, body[i].box), MK_OK);
            }
            if (f == 20) /* a host slot freed: its id goes NULL and the batch skips it */
                for (i = 0; i < N; i += 37) {
                    MK_ASSERT_STATUS(mk_bp_destroy_proxy(single, body[i].id), MK_OK);
                    MK_ASSERT_STATUS(mk_bp_destroy_proxy(batch, body[i].id), MK_OK);
                    body[i].id = MK_BP_NULL_ID;
                }
            MK_ASSERT_STATUS(mk_bp_move_proxies(batch, &body[0].id, sizeof *body, &body[0].box, sizeof *body, N, &done), MK_OK);
            ck_assert_int_eq(done, N);
            MK_ASSERT_STATUS(mk_bp_update(single), MK_OK);
            MK_ASSERT_STATUS(mk_bp_update(batch), MK_OK);
            same_output(batch, single, f);
        }
        mk_bp_destroy(single);
        mk_bp_destroy(batch);
    }
}
END_TEST

/* The batch stops at the first bad entry: the ones before it moved, it and
 * the ones after it did not; argument checks move nothing. */
START_TEST(batch_moves_bad_input)
{
    mk_bp *bp;
    mk_bp_id ids[4];
    mk_aabb boxes[4], got;
    char raw[sizeof(mk_aabb) * 2 + 16];
    int i, done = -1;
    MK_ASSERT_STATUS(mk_bp_create(NULL, NULL, &bp), MK_OK);
    for (i = 0; i < 4; ++i) {
        boxes[i] = mk_aabb_make(mk_v3(3 * i, 0, 0), mk_v3(3 * i + 1, 1, 1));
        MK_ASSERT_STATUS(mk_bp_create_proxy(bp, boxes[i], NULL, 1, 1, 0, &ids[i]), MK_OK);
    }
    MK_ASSERT_STATUS(mk_bp_update(bp), MK_OK);
    for (i = 0; i < 4; ++i) { boxes[i].lo.y += 5; boxes[i].hi.y += 5; }
    boxes[2].lo.x = (mk_real)NAN;
    MK_ASSERT_STATUS(mk_bp_move_proxies(bp, ids, 0, boxes, 0, 4, &done), MK_ERR_BAD_AABB);
    ck_assert_int_eq(done, 2);
    for (i = 0; i < 4; ++i) {
        MK_ASSERT_STATUS(mk_bp_get_proxy(bp, ids[i], &got, NULL), MK_OK);
        MK_ASSERT_NEAR(got.lo.y, i < 2 ? 5 : 0, 0);
    }
    boxes[2].lo.x = 6;
    ids[1] = 0xFFFFFF01u;
    MK_ASSERT_STATUS(mk_bp_move_proxies(bp, ids, 0, boxes, 0, 4, &done), MK_ERR_UNKNOWN_ID);
    ck_assert_int_eq(done, 1);
    MK_ASSERT_STATUS(mk_bp_move_proxies(bp, ids + 2, 0, boxes + 2, 0, 2, NULL), MK_OK);
    MK_ASSERT_STATUS(mk_bp_get_proxy(bp, ids[3], &got, NULL), MK_OK);
    MK_ASSERT_NEAR(got.lo.y, 5, 0);
    MK_ASSERT_STATUS(mk_bp_move_proxies(bp, ids, 0, boxes, 0, -1, &done), MK_ERR_BAD_SIZE);
    ck_assert_int_eq(done, 0);
    MK_ASSERT_STATUS(mk_bp_move_proxies(bp, NULL, 0, boxes, 0, 1, &done), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_bp_move_proxies(bp, ids, 0, NULL, 0, 1, &done), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_bp_move_proxies(NULL, ids, 0, boxes, 0, 1, &done), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_bp_move_proxies(bp, NULL, 0, NULL, 0, 0, &done), MK_OK);
    ck_assert_int_eq(done, 0);
    MK_ASSERT_STATUS(mk_bp_move_proxies(bp, ids, 3, boxes, 0, 1, &done), MK_ERR_BAD_ARGUMENT);
    MK_ASSERT_STATUS(mk_bp_move_proxies(bp, ids, 0, boxes, sizeof(mk_real) + 1, 1, &done), MK_ERR_BAD_ARGUMENT);
    MK_ASSERT_STATUS(mk_bp_move_proxies(bp, ids, 0, (const mk_aabb *)(const void *)(raw + 1), 0, 1, &done), MK_ERR_BAD_ARGUMENT);
    ck_assert_int_eq(done, 0);
    MK_ASSERT_STATUS(mk_bp_update(bp), MK_OK);
    mk_bp_destroy(bp);
}
END_TEST

/* A box resting on a static ground bounces by less than the grid's query
 * margin: the pair must come back every time the boxes touch again (the
 * grid once dropped an index pair on separation and did not look again). */
START_TEST(bounce_on_static_ground)
{
    static const mk_real lift[] = {MK_REAL(0.03), MK_REAL(-0.01), MK_REAL(0.03), MK_REAL(-0.01), MK_REAL(0.005),
                                   MK_REAL(-0.02), MK_REAL(0.02), MK_REAL(0.0), MK_REAL(0.01), MK_REAL(-0.01)};
    mk_aabb ground = mk_aabb_make(mk_v3(-250, -100, -250), mk_v3(250, MK_REAL(0.02), 250));
    int k, f;
    for (k = 0; k < NKIND; ++k) {
        mk_bp_def d = mk_bp_default_def();
        mk_bp *bp;
        mk_bp_id g, b, other;
        d.kind = kinds[k];
        d.pairs_only = only_pairs[k];
        if (mk_bp_create(&d, NULL, &bp) == MK_ERR_UNSUPPORTED) continue;
        MK_ASSERT_STATUS(mk_bp_create_proxy(bp, ground, NULL, 1, 1, 1, &g), MK_OK);
        /* a second dynamic box far away, so the scene is not a single pair */
        MK_ASSERT_STATUS(mk_bp_create_proxy(bp, mk_aabb_make(mk_v3(100, 5, 100), mk_v3(101, 6, 101)), NULL, 1, 1, 0, &other), MK_OK);
        MK_ASSERT_STATUS(mk_bp_create_proxy(bp, mk_aabb_make(mk_v3(0, lift[0], 0), mk_v3(1, lift[0] + 1, 1)), NULL, 1, 1, 0, &b), MK_OK);
        for (f = 0; f < 40; ++f) {
            mk_real y = lift[f % 10];
            mk_aabb box = mk_aabb_make(mk_v3(0, y, 0), mk_v3(1, y + 1, 1));
            int np, want = y <= MK_REAL(0.02);
            MK_ASSERT_STATUS(mk_bp_move_proxy(bp, b, box), MK_OK);
            MK_ASSERT_STATUS(mk_bp_update(bp), MK_OK);
            mk_bp_pairs(bp, &np);
            ck_assert_msg(np == want, "%s: frame %d, box at y %g: %d pairs, want %d", name_of(k), f, (double)y, np, want);
        }
        mk_bp_destroy(bp);
    }
}
END_TEST

static Suite *broadphase_suite(void)
{
    Suite *s = suite_create("broadphase");
    TCase *tc = tcase_create("core");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, ids_and_stats);
    tcase_add_test(tc, bad_input);
    tcase_add_test(tc, coherent_motion);
    tcase_add_test(tc, pairs_only_switches_paths);
    tcase_add_test(tc, teleports);
    tcase_add_test(tc, churn);
    tcase_add_test(tc, mixed_sizes_1_to_1000);
    tcase_add_test(tc, top_level_filed_finer);
    tcase_add_test(tc, static_dynamic_mix);
    tcase_add_test(tc, auto_switches_structure);
    tcase_add_test(tc, auto_weighs_swaps_against_candidates);
    tcase_add_test(tc, touching_lattice);
    tcase_add_test(tc, tiny_huge_infinite);
    tcase_add_test(tc, filters_and_refilter);
    tcase_add_test(tc, filter_modes);
    tcase_add_test(tc, region_and_ray_queries);
    tcase_add_test(tc, static_index_dense);
    tcase_add_test(tc, static_index_hashed);
    tcase_add_test(tc, static_index_fast_movers);
    tcase_add_test(tc, swept_box_and_clipping);
    tcase_add_test(tc, steady_state_does_not_allocate);
    tcase_add_test(tc, fixed_capacity_overflow_recovers);
    tcase_add_test(tc, batch_moves_match_single_moves);
    tcase_add_test(tc, batch_moves_bad_input);
    tcase_add_test(tc, bounce_on_static_ground);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return mk_test_run(broadphase_suite()); }

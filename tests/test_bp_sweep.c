/* test_bp_sweep.c: the stateless sort and sweep (bp_sweep.c) against an
 * O(n^2) oracle computed here. A pairs_only SAP answers every busy update
 * (at least half the proxies changed) with the sweep, so each scene below
 * moves most of its boxes every frame and checks, frame by frame, that the
 * set is exactly the brute-force set and that the sweep answered. Touching
 * boxes (closed intervals: a shared face, edge or corner is an overlap) are
 * built on exact binary lattices, where any rounding in the sweep's
 * quantised keys or rows would lose a pair. Every frame also goes through
 * mk_bp_sweep_boxes (the same sweep over the scene's own box array, no
 * proxies, no statics) on a second broadphase, against the same oracle. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "minko/broadphase.h"
#include "support/mk_test.h"

#define MAXN 700

typedef struct scene {
    int n;
    mk_aabb box[MAXN];
    int is_static[MAXN];
    mk_bp_id id[MAXN];
    mk_bp *bp, *boxes_bp; /* proxies; mk_bp_sweep_boxes over box[] */
    int frames, sweeps_before;
    mk_bp_pair got[1 << 16], want[1 << 16];
} scene;

static int pair_cmp(const void *a, const void *b)
{
    const mk_bp_pair *x = (const mk_bp_pair *)a, *y = (const mk_bp_pair *)b;
    if (x->a != y->a) return x->a < y->a ? -1 : 1;
    return x->b < y->b ? -1 : (x->b > y->b);
}

static void scene_init(scene *s)
{
    mk_bp_def d = mk_bp_default_def();
    memset(s, 0, sizeof *s);
    d.kind = MK_BP_SAP;
    d.pairs_only = 1;
    d.proxy_capacity = MAXN;
    MK_ASSERT_STATUS(mk_bp_create(&d, NULL, &s->bp), MK_OK);
    d = mk_bp_default_def();
    d.proxy_capacity = MAXN;
    MK_ASSERT_STATUS(mk_bp_create(&d, NULL, &s->boxes_bp), MK_OK);
}

static void scene_free(scene *s)
{
    mk_bp_destroy(s->bp);
    mk_bp_destroy(s->boxes_bp);
}

static void add(scene *s, mk_aabb b, int is_static)
{
    int i = s->n++;
    ck_assert_int_lt(i, MAXN);
    s->box[i] = b;
    s->is_static[i] = is_static;
    MK_ASSERT_STATUS(mk_bp_create_proxy(s->bp, b, (void *)(intptr_t)(i + 1), ~0ull, ~0ull, is_static, &s->id[i]), MK_OK);
}

static void kill(scene *s, int i)
{
    MK_ASSERT_STATUS(mk_bp_destroy_proxy(s->bp, s->id[i]), MK_OK);
    s->n--;
    if (i == s->n) return;
    s->box[i] = s->box[s->n]; /* the scene's indices stay dense; user pointers follow */
    s->is_static[i] = s->is_static[s->n];
    s->id[i] = s->id[s->n];
    MK_ASSERT_STATUS(mk_bp_destroy_proxy(s->bp, s->id[i]), MK_OK);
    MK_ASSERT_STATUS(mk_bp_create_proxy(s->bp, s->box[i], (void *)(intptr_t)(i + 1), ~0ull, ~0ull, s->is_static[i], &s->id[i]), MK_OK);
}

static void move(scene *s, int i, mk_aabb b)
{
    s->box[i] = b;
    MK_ASSERT_STATUS(mk_bp_move_proxy(s->bp, s->id[i], b), MK_OK);
}

/* Brute force over the scene's boxes, as object-index pairs (static-static
 * pairs too, unless `statics` says they are left out). */
static int oracle(scene *s, int statics)
{
    int i, j, n = 0;
    for (i = 0; i < s->n; ++i)
        for (j = i + 1; j < s->n; ++j) {
            if ((statics && s->is_static[i] && s->is_static[j]) || !mk_aabb_overlap(s->box[i], s->box[j])) continue;
            ck_assert_int_lt(n, 1 << 16);
            s->want[n].a = (mk_bp_id)i;
            s->want[n].b = (mk_bp_id)j;
            ++n;
        }
    return n;
}

static int query_count_cb(void *ctx, mk_bp_id id, void *user)
{
    (void)id; (void)user;
    ++*(int *)ctx;
    return 1;
}

/* got[0, n) sorted against the oracle's want[0, nw). */
static void same_as_oracle(const scene *s, int n, int nw, const char *what)
{
    int i;
    for (i = 0; i < n && i < nw; ++i)
        ck_assert_msg(s->got[i].a == s->want[i].a && s->got[i].b == s->want[i].b,
                      "%s, frame %d: pair %d is (%u, %u), brute force has (%u, %u)", what, s->frames, i, s->got[i].a,
                      s->got[i].b, s->want[i].a, s->want[i].b);
    ck_assert_msg(n == nw, "%s, frame %d: %d pairs, brute force %d", what, s->frames, n, nw);
}

/* mk_bp_sweep_boxes over the scene's array: each pair once, a < b, every
 * overlapping pair (statics are plain boxes there). */
static void check_boxes(scene *s)
{
    const mk_bp_pair *p;
    int np, i;
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(s->boxes_bp, s->box, 0, s->n, &p, &np), MK_OK);
    ck_assert_int_le(np, 1 << 16);
    for (i = 0; i < np; ++i) {
        ck_assert_msg(p[i].a < p[i].b && p[i].b < (mk_bp_id)s->n, "pair %d is (%u, %u)", i, p[i].a, p[i].b);
        s->got[i] = p[i];
    }
    qsort(s->got, (size_t)np, sizeof *s->got, pair_cmp);
    same_as_oracle(s, np, oracle(s, 0), "mk_bp_sweep_boxes");
}

/* One update: the set equals the oracle's, the update was a sweep, and a
 * region query (read from the sweep's rows) finds what brute force finds;
 * then the same boxes through mk_bp_sweep_boxes. */
static void check_frame(scene *s, mk_aabb q)
{
    const mk_bp_pair *p;
    mk_bp_stats st;
    int np, nw, i, found = 0, truth = 0;
    MK_ASSERT_STATUS(mk_bp_update(s->bp), MK_OK);
    MK_ASSERT_STATUS(mk_bp_get_stats(s->bp, &st), MK_OK);
    ck_assert_int_eq(st.sweeps, s->sweeps_before + 1); /* the sweep answered this update */
    s->sweeps_before = st.sweeps;
    p = mk_bp_pairs(s->bp, &np);
    ck_assert_int_le(np, 1 << 16);
    for (i = 0; i < np; ++i) {
        mk_bp_id a = (mk_bp_id)((intptr_t)mk_bp_user(s->bp, p[i].a) - 1), b = (mk_bp_id)((intptr_t)mk_bp_user(s->bp, p[i].b) - 1);
        ck_assert_msg(p[i].a < p[i].b && (i == 0 || pair_cmp(&p[i - 1], &p[i]) < 0), "set not sorted at %d", i);
        s->got[i].a = a < b ? a : b;
        s->got[i].b = a < b ? b : a;
    }
    qsort(s->got, (size_t)np, sizeof *s->got, pair_cmp);
    nw = oracle(s, 1);
    same_as_oracle(s, np, nw, "pairs_only update");
    MK_ASSERT_STATUS(mk_bp_query_aabb(s->bp, q, query_count_cb, &found), MK_OK);
    for (i = 0; i < s->n; ++i) truth += mk_aabb_overlap(s->box[i], q);
    ck_assert_int_eq(found, truth);
    check_boxes(s);
    s->frames++;
}

static mk_aabb box_at(mk_vec3 c, mk_vec3 half) { return mk_aabb_make(mk_v3_sub(c, half), mk_v3_add(c, half)); }

static mk_aabb random_box(mk_rng *r, double world, double lo, double hi)
{
    mk_vec3 half = mk_v3((mk_real)(0.5 * mk_rng_range(r, lo, hi)), (mk_real)(0.5 * mk_rng_range(r, lo, hi)),
                         (mk_real)(0.5 * mk_rng_range(r, lo, hi)));
    return box_at(mk_rng_v3(r, 0, world), half);
}

static mk_aabb shifted(mk_aabb b, mk_vec3 d) { return mk_aabb_make(mk_v3_add(b.lo, d), mk_v3_add(b.hi, d)); }

/* Boxes drifting a little each frame (every one moves: the sweep answers),
 * spread mostly along one axis so that rows form, with a ground plane. */
START_TEST(coherent)
{
    static scene s;
    mk_rng r = {11};
    const mk_real inf = (mk_real)INFINITY;
    mk_vec3 vel[MAXN];
    int i, f;
    scene_init(&s);
    add(&s, mk_aabb_make(mk_v3(-inf, -inf, -inf), mk_v3(inf, inf, (mk_real)0.3)), 1);
    for (i = 1; i < 500; ++i) {
        mk_vec3 c = mk_v3((mk_real)mk_rng_range(&r, 0, 30), (mk_real)mk_rng_range(&r, 0, 6), (mk_real)mk_rng_unit(&r));
        add(&s, box_at(c, mk_aabb_extents(random_box(&r, 1, 0.1, 1.5))), i % 9 == 0);
        vel[i] = mk_v3_scale(mk_rng_dir(&r), (mk_real)0.05);
    }
    for (f = 0; f < 40; ++f) {
        for (i = 1; i < s.n; ++i)
            if (!s.is_static[i]) move(&s, i, shifted(s.box[i], vel[i]));
        check_frame(&s, random_box(&r, 20, 1, 4));
    }
    scene_free(&s);
}
END_TEST

/* A third of the boxes jump anywhere each frame; the others drift. */
START_TEST(teleporting)
{
    static scene s;
    mk_rng r = {12};
    int i, f;
    scene_init(&s);
    for (i = 0; i < 600; ++i) add(&s, random_box(&r, 16, 0.2, 2.5), 0);
    for (f = 0; f < 30; ++f) {
        for (i = 0; i < s.n; ++i) {
            if (mk_rng_unit(&r) < 0.33) move(&s, i, box_at(mk_rng_v3(&r, 0, 16), mk_aabb_extents(s.box[i])));
            else move(&s, i, shifted(s.box[i], mk_v3_scale(mk_rng_dir(&r), (mk_real)0.1)));
        }
        check_frame(&s, random_box(&r, 16, 1, 5));
    }
    scene_free(&s);
}
END_TEST

/* Unit cubes on an integer lattice, some of them exactly face to face,
 * edge to edge or corner to corner (lo of one == hi of the other, exactly
 * representable), shifted each frame by a multiple of 1/4 so they keep
 * touching; a far box stretches the sweep's range so that its quantised
 * keys are coarse (many boxes share a key) and another one 2^-20 wide sits
 * on a lattice face. Rows are one cube tall: touching across a row boundary
 * is exercised too. */
START_TEST(touching)
{
    static scene s;
    mk_rng r = {13};
    int i, f, x, y, z;
    scene_init(&s);
    for (x = 0; x < 9; ++x)
        for (y = 0; y < 9; ++y)
            for (z = 0; z < 4; ++z) {
                mk_vec3 lo;
                if (mk_rng_unit(&r) < 0.25) continue; /* holes: not every box has every neighbour */
                lo = mk_v3((mk_real)x, (mk_real)y, (mk_real)z);
                add(&s, mk_aabb_make(lo, mk_v3_add(lo, mk_v3(1, 1, 1))), 0);
            }
    add(&s, mk_aabb_make(mk_v3(3, 3, 4), mk_v3((mk_real)3 + (mk_real)ldexp(1, -20), 3, 5)), 0); /* flat, on a top face */
    add(&s, mk_aabb_make(mk_v3(4, 4, 4), mk_v3(4, 4, 4)), 0);  /* a point on a corner */
    add(&s, mk_aabb_make(mk_v3(4096, 0, 0), mk_v3(4097, 1, 1)), 0); /* far: coarse keys */
    for (f = 0; f < 24; ++f) {
        mk_vec3 d = mk_v3((mk_real)(0.25 * (f % 3)), (mk_real)(-0.25 * (f % 2)), (mk_real)0.5);
        if (f % 4 == 3) d = mk_v3(-d.x, -d.y, -d.z);
        for (i = 0; i < s.n; ++i) move(&s, i, shifted(s.box[i], d));
        check_frame(&s, mk_aabb_make(mk_v3(2, 2, 1), mk_v3(3, 3, 2)));
    }
    scene_free(&s);
}
END_TEST

/* Sweeps in a row with proxies created and destroyed between them (each
 * sweep starts from the last one's order), a box that turns infinite
 * across the rows and back (a plane), and one that grows taller than the
 * rows the plan was made for. */
START_TEST(churn)
{
    static scene s;
    mk_rng r = {14};
    const mk_real inf = (mk_real)INFINITY;
    int i, f;
    scene_init(&s);
    add(&s, mk_aabb_make(mk_v3(1, 1, 1), mk_v3(3, 3, 3)), 1); /* the largest box: a plan outlives frames */
    for (i = 1; i < 400; ++i) add(&s, random_box(&r, 20, 0.2, 1.5), i % 17 == 0);
    for (f = 0; f < 40; ++f) {
        for (i = 0; i < s.n; ++i)
            if (!s.is_static[i]) move(&s, i, shifted(s.box[i], mk_v3_scale(mk_rng_dir(&r), (mk_real)0.2)));
        for (i = 0; i < 12; ++i) kill(&s, (int)(mk_rng_unit(&r) * s.n));
        for (i = 0; i < 12; ++i) add(&s, random_box(&r, 20, 0.2, 1.5), 0);
        if (f % 5 == 2) move(&s, 7, mk_aabb_make(mk_v3(-inf, -inf, 3), mk_v3(inf, inf, 4)));
        if (f % 5 == 4) move(&s, 7, s.box[8]); /* finite again, on top of another box */
        if (f == 20) move(&s, 9, mk_aabb_make(mk_v3(4, 4, 4), mk_v3(12, 12, 12))); /* taller than the rows */
        check_frame(&s, random_box(&r, 20, 2, 6));
    }
    scene_free(&s);
}
END_TEST

/* Thin boxes over a tall row axis: tens of thousands of rows (the radix
 * sort's third digit), then, with the plan kept, clusters of overlapping
 * boxes moved far past every end of its ranges, where they share the
 * first or the last row (0xFFFE, next to the sentinel that ends the last
 * row's scans) and the ends of the quantised sweep axis. */
START_TEST(far_rows)
{
    static scene s;
    mk_rng r = {15};
    int i, f;
    scene_init(&s);
    for (i = 0; i < 600; ++i) {
        mk_vec3 c = mk_v3((mk_real)mk_rng_range(&r, 0, 2000), (mk_real)mk_rng_range(&r, 0, 1000), (mk_real)mk_rng_unit(&r));
        add(&s, box_at(c, mk_v3((mk_real)mk_rng_range(&r, 0.5, 8), (mk_real)mk_rng_range(&r, 0.001, 0.01), (mk_real)0.5)), 0);
    }
    for (f = 0; f < 6; ++f) {
        for (i = 0; i < s.n; ++i) {
            mk_vec3 d = mk_v3_scale(mk_rng_dir(&r), (mk_real)0.004);
            if (f >= 2 && i % 3 == 0) { /* far out: +-1e6 on both axes, in four clusters of overlapping boxes */
                mk_real fx = (mk_real)(i % 2 ? 1e6 : -1e6), fy = (mk_real)(i % 4 < 2 ? 1e6 : -1e6);
                d = mk_v3_sub(mk_v3(fx + (mk_real)(i % 7), fy + (mk_real)(0.001 * (i % 5)), 0), mk_aabb_center(s.box[i]));
                d.z = 0;
            }
            move(&s, i, shifted(s.box[i], d));
        }
        check_frame(&s, random_box(&r, 1000, 1, 50));
    }
    scene_free(&s);
}
END_TEST

/* Every box the same, then every box a point at the same place: all keys
 * tie, every pair overlaps (static ones aside). */
START_TEST(all_equal)
{
    static scene s;
    int i, f;
    scene_init(&s);
    for (i = 0; i < 120; ++i) add(&s, mk_aabb_make(mk_v3(1, 2, 3), mk_v3(2, 3, 4)), i % 10 == 0);
    for (f = 0; f < 4; ++f) {
        mk_vec3 p = mk_v3((mk_real)f, (mk_real)-f, (mk_real)(2 * f));
        for (i = 0; i < s.n; ++i)
            if (!s.is_static[i]) move(&s, i, f % 2 ? mk_aabb_make(p, p) : mk_aabb_make(p, mk_v3_add(p, mk_v3(1, 1, 1))));
        check_frame(&s, mk_aabb_make(p, p));
    }
    scene_free(&s);
}
END_TEST

/* Cubes of edges 1 to 100 (log-uniform, ~2 overlaps per cube, as
 * bench_broadphase's mixed scene) on an integer lattice, each moved by -1,
 * 0 or 1 per axis every frame, so that many touch exactly: the widest
 * boxes start further back than the rows look (sweep_rows) and find the
 * boxes of the row below themselves (sweep_wide). With half-spaces whose
 * one finite side is an upper and a lower end, and a box infinite but on
 * one lower end. */
START_TEST(mixed_sizes)
{
    static scene s;
    mk_rng r = {16};
    const mk_real inf = (mk_real)INFINITY;
    int i, k, f;
    scene_init(&s);
    add(&s, mk_aabb_make(mk_v3(-inf, -inf, -inf), mk_v3(inf, inf, 20)), 0);
    add(&s, mk_aabb_make(mk_v3(-inf, -inf, 300), mk_v3(inf, inf, inf)), 0);
    add(&s, mk_aabb_make(mk_v3(350, -inf, -inf), mk_v3(inf, inf, inf)), 1);
    for (i = 0; i < 400; ++i) {
        mk_real e = (mk_real)floor(pow(100, mk_rng_unit(&r)) + 0.5), lo[3];
        for (k = 0; k < 3; ++k) lo[k] = (mk_real)floor(mk_rng_range(&r, 0, 384));
        add(&s, mk_aabb_make(mk_v3(lo[0], lo[1], lo[2]), mk_v3(lo[0] + e, lo[1] + e, lo[2] + e)), i % 7 == 0);
    }
    for (f = 0; f < 20; ++f) {
        for (i = 3; i < s.n; ++i) {
            mk_vec3 d = mk_v3((mk_real)(mk_rng_u64(&r) % 3) - 1, (mk_real)(mk_rng_u64(&r) % 3) - 1, (mk_real)(mk_rng_u64(&r) % 3) - 1);
            if (!s.is_static[i]) move(&s, i, shifted(s.box[i], d));
        }
        check_frame(&s, random_box(&r, 384, 10, 60));
    }
    scene_free(&s);
}
END_TEST

/* mk_bp_sweep_boxes reads boxes through a stride (here inside host
 * records), follows the array as it grows and shrinks between calls, and
 * gives the same pairs in the same order for the same calls. */
typedef struct host_rec { int tag; mk_aabb box; double pad; } host_rec;

START_TEST(boxes_stride_and_order)
{
    static host_rec rec[300];
    mk_bp *a, *b;
    mk_bp_def d = mk_bp_default_def();
    const mk_bp_pair *p, *q;
    mk_rng r = {15};
    int i, f, n = 200, np, nq;
    d.proxy_capacity = 300;
    MK_ASSERT_STATUS(mk_bp_create(&d, NULL, &a), MK_OK);
    MK_ASSERT_STATUS(mk_bp_create(&d, NULL, &b), MK_OK);
    for (i = 0; i < 300; ++i) rec[i].box = random_box(&r, 12, 0.3, 2.0);
    for (f = 0; f < 12; ++f) {
        int brute = 0, j;
        n = f % 3 == 2 ? n - 37 : n + 11;
        for (i = 0; i < n; ++i) rec[i].box = shifted(rec[i].box, mk_v3_scale(mk_rng_dir(&r), (mk_real)0.3));
        MK_ASSERT_STATUS(mk_bp_sweep_boxes(a, &rec[0].box, sizeof *rec, n, &p, &np), MK_OK);
        MK_ASSERT_STATUS(mk_bp_sweep_boxes(b, &rec[0].box, sizeof *rec, n, &q, &nq), MK_OK);
        ck_assert_int_eq(np, nq);
        ck_assert_msg(np == 0 || !memcmp(p, q, (size_t)np * sizeof *p), "frame %d: same calls, other order", f);
        for (i = 0; i < n; ++i)
            for (j = i + 1; j < n; ++j) brute += mk_aabb_overlap(rec[i].box, rec[j].box);
        ck_assert_int_eq(np, brute);
        for (i = 0; i < np; ++i) ck_assert(p[i].a < p[i].b && p[i].b < (mk_bp_id)n && mk_aabb_overlap(rec[p[i].a].box, rec[p[i].b].box));
    }
    mk_bp_destroy(a);
    mk_bp_destroy(b);
}
END_TEST

/* Bad input: a clear status, *pairs NULL and *count 0, nothing changed. */
START_TEST(boxes_errors)
{
    mk_bp *bp, *px, *fixed;
    mk_bp_def d = mk_bp_default_def();
    mk_aabb box[50];
    const mk_bp_pair *p = (const mk_bp_pair *)box;
    int i, np = 7;
    mk_bp_id id;
    d.proxy_capacity = 50;
    MK_ASSERT_STATUS(mk_bp_create(&d, NULL, &bp), MK_OK);
    for (i = 0; i < 50; ++i) box[i] = mk_aabb_make(mk_v3(0, 0, 0), mk_v3(1, 1, 1)); /* all overlap */
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(NULL, box, 0, 4, &p, &np), MK_ERR_NULL);
    ck_assert(p == NULL && np == 0);
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, NULL, 0, 4, &p, &np), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 4, NULL, &np), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 4, &p, NULL), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, -1, &p, &np), MK_ERR_BAD_SIZE);
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 51, &p, &np), MK_ERR_CAPACITY);
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 3, 4, &p, &np), MK_ERR_BAD_ARGUMENT); /* misaligned stride */
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, (const mk_aabb *)(const void *)((const char *)box + 1), 0, 4, &p, &np),
                     MK_ERR_BAD_ARGUMENT);
    box[3].lo.y = (mk_real)NAN;
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 4, &p, &np), MK_ERR_BAD_AABB);
    box[3] = mk_aabb_make(mk_v3(0, 2, 0), mk_v3(1, 1, 1)); /* lo > hi */
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 4, &p, &np), MK_ERR_BAD_AABB);
    box[3] = mk_aabb_make(mk_v3((mk_real)INFINITY, 0, 0), mk_v3((mk_real)INFINITY, 1, 1)); /* lo = +inf */
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 4, &p, &np), MK_ERR_BAD_AABB);
    ck_assert(p == NULL && np == 0);
    /* the check is hi - lo >= 0 per axis: the cases where a difference
     * could mislead (infinities, overflow, a subnormal gap) */
    box[3] = mk_aabb_make(mk_v3(0, (mk_real)INFINITY, 0), mk_v3(1, 1, 1)); /* lo = +inf, hi finite */
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 4, &p, &np), MK_ERR_BAD_AABB);
    box[3] = mk_aabb_make(mk_v3(0, 0, 0), mk_v3(1, 1, -(mk_real)INFINITY)); /* hi = -inf, lo finite */
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 4, &p, &np), MK_ERR_BAD_AABB);
    box[3] = mk_aabb_make(mk_v3(0, 0, (mk_real)ldexp(1, sizeof(mk_real) == 4 ? -140 : -1060)), mk_v3(1, 1, 0)); /* lo > hi by a subnormal */
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 4, &p, &np), MK_ERR_BAD_AABB);
    box[3] = mk_aabb_make(mk_v3(-MK_REAL_MAX, 0, -(mk_real)INFINITY), mk_v3(MK_REAL_MAX, 1, (mk_real)INFINITY)); /* hi - lo overflows: fine */
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 4, &p, &np), MK_OK);
    ck_assert_int_eq(np, 6);
    box[3] = mk_aabb_make(mk_v3(0, 0, 0), mk_v3(1, 1, 1));
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 0, &p, &np), MK_OK);
    ck_assert_int_eq(np, 0);
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 50, &p, &np), MK_OK); /* 1225 pairs: the array grows */
    ck_assert_int_eq(np, 1225);
    /* A broadphase of proxies refuses: its sweep is mk_bp_update's. */
    MK_ASSERT_STATUS(mk_bp_create(&d, NULL, &px), MK_OK);
    MK_ASSERT_STATUS(mk_bp_create_proxy(px, box[0], NULL, ~0ull, ~0ull, 0, &id), MK_OK);
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(px, box, 0, 4, &p, &np), MK_ERR_BAD_ARGUMENT);
    /* fixed_capacity: the pair array does not grow past pair_capacity (it
     * starts at 1024 pairs); then MK_ERR_CAPACITY. */
    d.fixed_capacity = 1;
    d.pair_capacity = 2000;
    MK_ASSERT_STATUS(mk_bp_create(&d, NULL, &fixed), MK_OK);
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(fixed, box, 0, 50, &p, &np), MK_OK);
    ck_assert_int_eq(np, 1225);
    mk_bp_destroy(fixed);
    d.pair_capacity = 1000;
    MK_ASSERT_STATUS(mk_bp_create(&d, NULL, &fixed), MK_OK);
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(fixed, box, 0, 45, &p, &np), MK_OK); /* 990 */
    ck_assert_int_eq(np, 990);
    MK_ASSERT_STATUS(mk_bp_sweep_boxes(fixed, box, 0, 50, &p, &np), MK_ERR_CAPACITY);
    ck_assert(p == NULL && np == 0);
    mk_bp_destroy(fixed);
    mk_bp_destroy(px);
    mk_bp_destroy(bp);
}
END_TEST

static int brute_count(const mk_aabb *b, int n)
{
    int i, j, c = 0;
    for (i = 0; i < n; ++i)
        for (j = i + 1; j < n; ++j) c += mk_aabb_overlap(b[i], b[j]);
    return c;
}

/* The sweep writes every tested pair into its array and keeps only those
 * that overlap: a full array must still take as many pairs as the caller
 * allowed, and grow only for a pair that overlaps. Dense random boxes
 * (about a third of the tested pairs overlap, so tests that fail follow
 * the last pair) with pair_capacity exactly their pair count pass; one
 * less is MK_ERR_CAPACITY. */
START_TEST(boxes_exact_capacity)
{
    static mk_aabb box[300];
    mk_bp_def d = mk_bp_default_def();
    mk_rng r = {21};
    const mk_bp_pair *p;
    mk_bp *bp;
    int i, np, want, k;
    for (k = 0; k < 4; ++k) {
        for (i = 0; i < 300; ++i) box[i] = random_box(&r, 6, 0.5, 2.0);
        want = brute_count(box, 300);
        ck_assert_int_gt(want, 1024); /* past the first array: it grew to the bound */
        d.proxy_capacity = 300;
        d.fixed_capacity = 1;
        d.pair_capacity = want;
        MK_ASSERT_STATUS(mk_bp_create(&d, NULL, &bp), MK_OK);
        MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 300, &p, &np), MK_OK);
        ck_assert_int_eq(np, want);
        mk_bp_destroy(bp);
        d.pair_capacity = want - 1;
        MK_ASSERT_STATUS(mk_bp_create(&d, NULL, &bp), MK_OK);
        MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 300, &p, &np), MK_ERR_CAPACITY);
        ck_assert(p == NULL && np == 0);
        mk_bp_destroy(bp);
    }
}
END_TEST

/* Each box is checked as the sweep reads it, so a bad one is refused on
 * every path: calls that keep the plan and start from the last call's
 * order, new boxes past the last call's count, a NaN on the row axis (a
 * box that would be filed as infinite), hi = -inf; and the call after a
 * refused one is exact again. */
START_TEST(boxes_bad_on_kept_plan)
{
    mk_bp *bp;
    mk_bp_def d = mk_bp_default_def();
    mk_aabb box[50];
    const mk_bp_pair *p;
    const mk_real inf = (mk_real)INFINITY;
    static const int at[4] = {7, 45, 0, 49};
    int i, np;
    d.proxy_capacity = 50;
    MK_ASSERT_STATUS(mk_bp_create(&d, NULL, &bp), MK_OK);
    for (i = 0; i < 50; ++i) { /* a 10 x 5 grid of unit boxes half a box apart */
        mk_vec3 lo = mk_v3((mk_real)(0.5 * (i % 10)), (mk_real)(0.75 * (i / 10)), 0);
        box[i] = mk_aabb_make(lo, mk_v3_add(lo, mk_v3(1, 1, 1)));
    }
    for (i = 0; i < 4; ++i) {
        mk_aabb keep = box[at[i]];
        MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 40, &p, &np), MK_OK);
        MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 40, &p, &np), MK_OK);
        ck_assert_int_eq(np, brute_count(box, 40));
        if (i == 0) box[at[i]].lo.x = (mk_real)NAN;
        if (i == 1) box[at[i]] = mk_aabb_make(mk_v3(0, 2, 0), mk_v3(1, 1, 1));
        if (i == 2) box[at[i]].lo.y = box[at[i]].hi.y = (mk_real)NAN;
        if (i == 3) box[at[i]].lo.z = box[at[i]].hi.z = -inf;
        MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 50, &p, &np), MK_ERR_BAD_AABB);
        ck_assert(p == NULL && np == 0);
        box[at[i]] = keep;
        MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 50, &p, &np), MK_OK);
        ck_assert_int_eq(np, brute_count(box, 50));
        MK_ASSERT_STATUS(mk_bp_sweep_boxes(bp, box, 0, 50, &p, &np), MK_OK);
        ck_assert_int_eq(np, brute_count(box, 50));
    }
    mk_bp_destroy(bp);
}
END_TEST

int main(void)
{
    Suite *su = suite_create("bp_sweep");
    TCase *tc = tcase_create("sweep");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, coherent);
    tcase_add_test(tc, teleporting);
    tcase_add_test(tc, touching);
    tcase_add_test(tc, churn);
    tcase_add_test(tc, all_equal);
    tcase_add_test(tc, far_rows);
    tcase_add_test(tc, mixed_sizes);
    tcase_add_test(tc, boxes_stride_and_order);
    tcase_add_test(tc, boxes_errors);
    tcase_add_test(tc, boxes_exact_capacity);
    tcase_add_test(tc, boxes_bad_on_kept_plan);
    suite_add_tcase(su, tc);
    return mk_test_run(su);
}

/* test_manifold_points.c: mk_collide_pose_points, the unreduced candidates:
 * they contain mk_collide_pose's reduced points bit for bit, an octagon
 * face on a turned octagon gives its whole 16-gon, box pairs stay reduced,
 * a short buffer is a status, and bad input is refused. */
#include <string.h>

#include "minko/manifold.h"
#include "support/mk_test.h"

#define MAXC MK_COLLIDE_MAX_CANDIDATES
#define PI 3.14159265358979323846

/* Coordinates are O(1): "exact" means a few ulps of that. */
#if defined(MK_SINGLE)
#  define TOL 2e-5
#else
#  define TOL 1e-12
#endif

static mk_pose pose_of(mk_vec3 p, mk_quat q)
{
    mk_pose x;
    MK_ASSERT_STATUS(mk_pose_from_transform(mk_transform_make(p, q), &x), MK_OK);
    return x;
}

/* A regular octagonal prism of circumradius r and half height h. */
static mk_hull *octagon_prism(mk_real r, mk_real h)
{
    mk_vec3 p[16];
    mk_hull *hull = NULL;
    int i;
    for (i = 0; i < 8; ++i) {
        double t = PI / 4 * i;
        p[2 * i] = mk_v3(r * (mk_real)cos(t), r * (mk_real)sin(t), -h);
        p[2 * i + 1] = mk_v3(r * (mk_real)cos(t), r * (mk_real)sin(t), h);
    }
    MK_ASSERT_STATUS(mk_hull_create(p, 16, NULL, &hull), MK_OK);
    return hull;
}

static mk_vec3 pose_point(const mk_pose *x, mk_vec3 l) { return mk_v3_add(mk_mat3_mul_v3(x->r, l), x->p); }

static int same_point(const mk_contact_point *p, const mk_contact_point *q)
{
    return memcmp(&p->point_a, &q->point_a, sizeof p->point_a) == 0 && memcmp(&p->point_b, &q->point_b, sizeof p->point_b) == 0 &&
           memcmp(&p->local_a, &q->local_a, sizeof p->local_a) == 0 && memcmp(&p->local_b, &q->local_b, sizeof p->local_b) == 0 &&
           memcmp(&p->depth, &q->depth, sizeof p->depth) == 0 && p->features == q->features && p->flags == q->flags;
}

/* Both entries from equal cache states: the candidates contain every
 * reduced point bit for bit, share its normal, and follow the contract's
 * relations. Returns the number of candidates. */
static int check_superset(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin,
                          const mk_manifold_cache *cache, mk_contact_point *pts)
{
    mk_manifold_cache c1, c2;
    mk_manifold m;
    mk_vec3 n;
    int count = -1, i, j;
    if (cache) c1 = c2 = *cache;
    MK_ASSERT_STATUS(mk_collide_pose(a, xa, b, xb, margin, cache ? &c1 : NULL, &m), MK_OK);
    MK_ASSERT_STATUS(mk_collide_pose_points(a, xa, b, xb, margin, cache ? &c2 : NULL, &n, pts, MAXC, &count), MK_OK);
    if (cache) ck_assert(memcmp(&c1, &c2, sizeof c1) == 0);
    ck_assert_int_ge(count, m.count);
    ck_assert_int_le(count, MAXC);
    if (count <= MK_MANIFOLD_MAX_POINTS) ck_assert_int_eq(count, m.count);
    if (m.count > 0) ck_assert(memcmp(&n, &m.normal, sizeof n) == 0);
    for (i = 0; i < m.count; ++i) {
        for (j = 0; j < count && !same_point(&m.points[i], &pts[j]); ++j) continue;
        ck_assert_msg(j < count, "reduced point %d (features %08x) is not a candidate", i, m.points[i].features);
    }
    for (i = 0; i < count; ++i) {
        const mk_contact_point *c = &pts[i];
        MK_ASSERT_V3_NEAR(c->point_b, mk_v3_mad(c->point_a, -c->depth, n), 64 * TOL);
        MK_ASSERT_V3_NEAR(pose_point(xa, c->local_a), c->point_a, 64 * TOL);
        MK_ASSERT_V3_NEAR(pose_point(xb, c->local_b), c->point_b, 64 * TOL);
        ck_assert(c->depth >= -margin);
        ck_assert_int_eq((int)c->flags, c->depth < 0 ? (int)MK_CONTACT_SPECULATIVE : 0);
        for (j = 0; j < i; ++j) ck_assert_msg(pts[j].features != c->features, "duplicate feature pair %08x", c->features);
    }
    return count;
}

/* Octagon B turned by 22.5 degrees, resting 0.01 deep on octagon A: the
 * faces overlap in a regular 16-gon (B's corners lie outside A's sides by
 * 7.6 % of the radius, far beyond the clip's slop), every corner at depth
 * 0.01 under the normal +z; mk_collide_pose keeps four of them. */
START_TEST(octagon_face_gives_sixteen)
{
    mk_hull *h = octagon_prism(1, MK_REAL(0.25));
    mk_shape a, b;
    mk_pose xa = pose_of(mk_v3(0, 0, 0), mk_quat_identity());
    mk_pose xb = pose_of(mk_v3(0, 0, MK_REAL(0.49)), mk_quat_from_axis_angle(mk_v3(0, 0, 1), (mk_real)(PI / 8)));
    mk_contact_point pts[MAXC];
    mk_manifold_cache cache;
    mk_real inner = (mk_real)cos(PI / 8);
    int count, i, pass;
    MK_ASSERT_STATUS(mk_shape_hull(h, 0, &a), MK_OK);
    MK_ASSERT_STATUS(mk_shape_hull(h, 0, &b), MK_OK);
    memset(&cache, 0, sizeof cache);
    for (pass = 0; pass < 3; ++pass) { /* cold without a cache, then cold and warm with one */
        mk_manifold m;
        count = check_superset(&a, &xa, &b, &xb, 0, pass ? &cache : NULL, pts);
        ck_assert_int_eq(count, 16);
        for (i = 0; i < count; ++i) {
            mk_real r = mk_sqrt_(pts[i].point_a.x * pts[i].point_a.x + pts[i].point_a.y * pts[i].point_a.y);
            MK_ASSERT_NEAR(pts[i].depth, 0.01, 64 * TOL);
            /* Corners of the 16-gon: inside both octagons, on the rim of one. */
            ck_assert(r <= 1 + 64 * TOL);
            ck_assert(r >= inner - 64 * TOL);
        }
        if (pass) MK_ASSERT_STATUS(mk_collide_pose(&a, &xa, &b, &xb, 0, &cache, &m), MK_OK);
        else {
            MK_ASSERT_STATUS(mk_collide_pose(&a, &xa, &b, &xb, 0, NULL, &m), MK_OK);
            ck_assert_int_eq(m.count, 4);
            MK_ASSERT_V3_NEAR(m.normal, mk_v3(0, 0, 1), 64 * TOL);
        }
    }
    mk_hull_destroy(h);
}
END_TEST

/* The same pair in the other order: the mirror image (normal negated,
 * witnesses and features exchanged), point for point. */
START_TEST(swapped_order_mirrors)
{
    mk_hull *h = octagon_prism(1, MK_REAL(0.25));
    mk_shape a, b;
    mk_pose xa = pose_of(mk_v3(0, 0, 0), mk_quat_identity());
    mk_pose xb = pose_of(mk_v3(MK_REAL(0.1), 0, MK_REAL(0.45)), mk_quat_from_axis_angle(mk_v3(0, 0, 1), MK_REAL(0.3)));
    mk_contact_point p[MAXC], q[MAXC];
    int n1, n2, i, j;
    MK_ASSERT_STATUS(mk_shape_hull(h, 0, &a), MK_OK);
    MK_ASSERT_STATUS(mk_shape_hull(h, 0, &b), MK_OK);
    n1 = check_superset(&a, &xa, &b, &xb, 0, NULL, p);
    n2 = check_superset(&b, &xb, &a, &xa, 0, NULL, q);
    ck_assert_int_gt(n1, 4);
    ck_assert_int_eq(n1, n2);
    for (i = 0; i < n1; ++i) {
        uint32_t f = MK_FEATURE_PAIR(MK_FEATURE_PAIR_B(p[i].features), MK_FEATURE_PAIR_A(p[i].features));
        for (j = 0; j < n2 && q[j].features != f; ++j) continue;
        ck_assert_msg(j < n2, "no mirror of %08x", p[i].features);
        MK_ASSERT_V3_NEAR(q[j].point_a, p[i].point_b, 64 * TOL);
        MK_ASSERT_V3_NEAR(q[j].point_b, p[i].point_a, 64 * TOL);
        MK_ASSERT_NEAR(q[j].depth, p[i].depth, 64 * TOL);
    }
    mk_hull_destroy(h);
}
END_TEST

/* A cylinder standing on a box (GJK + clip): its cap's octagon, all eight
 * corners at the analytic depth; mk_collide_pose keeps four. */
START_TEST(cylinder_cap_gives_octagon)
{
    mk_shape box, cyl;
    mk_pose xa = pose_of(mk_v3(0, 0, 0), mk_quat_identity());
    mk_pose xb = pose_of(mk_v3(MK_REAL(0.2), MK_REAL(-0.1), MK_REAL(1.45)), mk_quat_identity());
    mk_contact_point pts[MAXC];
    int count, i;
    MK_ASSERT_STATUS(mk_shape_box(mk_v3(2, 2, 1), 0, &box), MK_OK);
    MK_ASSERT_STATUS(mk_shape_cylinder(MK_REAL(0.5), MK_REAL(0.5), 0, &cyl), MK_OK);
    count = check_superset(&box, &xa, &cyl, &xb, 0, NULL, pts);
    ck_assert_int_eq(count, 8);
    for (i = 0; i < count; ++i) {
        MK_ASSERT_NEAR(pts[i].depth, 0.05, 1e3 * TOL);
        MK_ASSERT_NEAR(pts[i].point_a.z, 1, 1e3 * TOL);
    }
}
END_TEST

/* Random hull pairs (ellipsoid point clouds) in contact, cold and warm:
 * the superset property whatever the contact (vertex, edge, face). */
START_TEST(random_hulls_superset)
{
    mk_rng r = {0x5eed0006u};
    int trial, bigger = 0;
    for (trial = 0; trial < 200; ++trial) {
        mk_vec3 pa[24], pb[24];
        mk_hull *ha = NULL, *hb = NULL;
        mk_shape a, b;
        mk_contact_point pts[MAXC];
        mk_manifold_cache cache;
        mk_pose xa, xb;
        mk_quat qb;
        mk_vec3 tb;
        int i, n = 8 + trial % 16;
        for (i = 0; i < n; ++i) {
            pa[i] = mk_v3_mul(mk_rng_dir(&r), mk_v3(1, MK_REAL(0.7), MK_REAL(0.4)));
            pb[i] = mk_v3_mul(mk_rng_dir(&r), mk_v3(MK_REAL(0.8), MK_REAL(0.8), MK_REAL(0.3)));
        }
        MK_ASSERT_STATUS(mk_hull_create(pa, n, NULL, &ha), MK_OK);
        MK_ASSERT_STATUS(mk_hull_create(pb, n, NULL, &hb), MK_OK);
        MK_ASSERT_STATUS(mk_shape_hull(ha, trial % 3 == 0 ? MK_REAL(0.05) : 0, &a), MK_OK);
        MK_ASSERT_STATUS(mk_shape_hull(hb, 0, &b), MK_OK);
        xa = pose_of(mk_v3(0, 0, 0), trial % 2 ? mk_rng_quat(&r) : mk_quat_identity());
        tb = mk_v3_add(mk_rng_v3(&r, -0.4, 0.4), mk_v3(0, 0, MK_REAL(0.55)));
        qb = trial % 2 ? mk_rng_quat(&r) : mk_quat_identity();
        xb = pose_of(tb, qb);
        memset(&cache, 0, sizeof cache);
        cache.mode = trial % 4 == 1 ? MK_MANIFOLD_BEST_FACE : MK_MANIFOLD_STABLE_IDS;
        bigger += check_superset(&a, &xa, &b, &xb, MK_REAL(0.02), NULL, pts) > 4;
        check_superset(&a, &xa, &b, &xb, MK_REAL(0.02), &cache, pts);
        xb = pose_of(mk_v3_add(tb, mk_v3(MK_REAL(0.001), 0, 0)), qb);
        check_superset(&a, &xa, &b, &xb, MK_REAL(0.02), &cache, pts);
        mk_hull_destroy(ha);
        mk_hull_destroy(hb);
    }
    ck_assert_int_ge(bigger, 3); /* some of them where it matters (random clouds have small faces) */
}
END_TEST

/* Two boxes come reduced from box_box.c: the same points as mk_collide_pose. */
START_TEST(boxes_stay_reduced)
{
    mk_shape a, b;
    mk_pose xa = pose_of(mk_v3(0, 0, 0), mk_quat_identity());
    mk_pose xb = pose_of(mk_v3(MK_REAL(0.1), 0, MK_REAL(1.98)), mk_quat_from_axis_angle(mk_v3(0, 0, 1), MK_REAL(0.4)));
    mk_contact_point pts[MAXC];
    mk_manifold m;
    int count, i;
    MK_ASSERT_STATUS(mk_shape_box(mk_v3(1, 1, 1), 0, &a), MK_OK);
    MK_ASSERT_STATUS(mk_shape_box(mk_v3(1, 1, 1), 0, &b), MK_OK);
    count = check_superset(&a, &xa, &b, &xb, 0, NULL, pts);
    MK_ASSERT_STATUS(mk_collide_pose(&a, &xa, &b, &xb, 0, NULL, &m), MK_OK);
    ck_assert_int_eq(count, 4);
    ck_assert_int_eq(m.count, 4);
    for (i = 0; i < count; ++i) ck_assert(same_point(&pts[i], &m.points[i]));
}
END_TEST

/* A buffer too small for the candidates: MK_ERR_CAPACITY with the count
 * needed, buffer and normal untouched; exactly enough room is fine. */
START_TEST(short_buffer_is_a_status)
{
    mk_hull *h = octagon_prism(1, MK_REAL(0.25));
    mk_shape a, b, ba, bb;
    mk_pose xa = pose_of(mk_v3(0, 0, 0), mk_quat_identity());
    mk_pose xb = pose_of(mk_v3(0, 0, MK_REAL(0.49)), mk_quat_from_axis_angle(mk_v3(0, 0, 1), (mk_real)(PI / 8)));
    mk_pose xbox = pose_of(mk_v3(0, 0, MK_REAL(1.99)), mk_quat_identity());
    mk_contact_point pts[MAXC], sentinel[MAXC];
    mk_vec3 n = mk_v3(7, 7, 7);
    int count = -1;
    MK_ASSERT_STATUS(mk_shape_hull(h, 0, &a), MK_OK);
    MK_ASSERT_STATUS(mk_shape_hull(h, 0, &b), MK_OK);
    memset(pts, 0xAB, sizeof pts);
    memcpy(sentinel, pts, sizeof pts);
    MK_ASSERT_STATUS(mk_collide_pose_points(&a, &xa, &b, &xb, 0, NULL, &n, pts, 15, &count), MK_ERR_CAPACITY);
    ck_assert_int_eq(count, 16);
    ck_assert(memcmp(pts, sentinel, sizeof pts) == 0);
    ck_assert(n.x == 7 && n.y == 7 && n.z == 7);
    MK_ASSERT_STATUS(mk_collide_pose_points(&a, &xa, &b, &xb, 0, NULL, &n, pts, 0, &count), MK_ERR_CAPACITY);
    ck_assert_int_eq(count, 16);
    MK_ASSERT_STATUS(mk_collide_pose_points(&a, &xa, &b, &xb, 0, NULL, &n, pts, 16, &count), MK_OK);
    ck_assert_int_eq(count, 16);
    /* Boxes too: four face points do not fit in three. */
    MK_ASSERT_STATUS(mk_shape_box(mk_v3(1, 1, 1), 0, &ba), MK_OK);
    MK_ASSERT_STATUS(mk_shape_box(mk_v3(1, 1, 1), 0, &bb), MK_OK);
    memcpy(pts, sentinel, sizeof pts);
    n = mk_v3(7, 7, 7);
    MK_ASSERT_STATUS(mk_collide_pose_points(&ba, &xa, &bb, &xbox, 0, NULL, &n, pts, 3, &count), MK_ERR_CAPACITY);
    ck_assert_int_eq(count, 4);
    ck_assert(memcmp(pts, sentinel, sizeof pts) == 0);
    ck_assert(n.x == 7 && n.y == 7 && n.z == 7);
    /* Apart: nothing is needed, so no buffer is too small. */
    xbox = pose_of(mk_v3(0, 0, 5), mk_quat_identity());
    MK_ASSERT_STATUS(mk_collide_pose_points(&a, &xa, &b, &xbox, 0, NULL, &n, pts, 0, &count), MK_OK);
    ck_assert_int_eq(count, 0);
    mk_hull_destroy(h);
}
END_TEST

START_TEST(bad_input)
{
    mk_hull *h = octagon_prism(1, MK_REAL(0.25));
    mk_shape a, b, bad, p1, p2;
    mk_pose xa = pose_of(mk_v3(0, 0, 0), mk_quat_identity());
    mk_pose xb = pose_of(mk_v3(0, 0, MK_REAL(0.49)), mk_quat_identity()), raw;
    mk_contact_point pts[MAXC], sentinel[MAXC];
    mk_manifold_cache cache;
    mk_vec3 n = mk_v3(7, 7, 7);
    int count = -1;
    MK_ASSERT_STATUS(mk_shape_hull(h, 0, &a), MK_OK);
    MK_ASSERT_STATUS(mk_shape_hull(h, 0, &b), MK_OK);
    memset(pts, 0xAB, sizeof pts);
    memcpy(sentinel, pts, sizeof pts);
    MK_ASSERT_STATUS(mk_collide_pose_points(NULL, &xa, &b, &xb, 0, NULL, &n, pts, MAXC, &count), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_collide_pose_points(&a, NULL, &b, &xb, 0, NULL, &n, pts, MAXC, &count), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_collide_pose_points(&a, &xa, NULL, &xb, 0, NULL, &n, pts, MAXC, &count), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_collide_pose_points(&a, &xa, &b, NULL, 0, NULL, &n, pts, MAXC, &count), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_collide_pose_points(&a, &xa, &b, &xb, 0, NULL, NULL, pts, MAXC, &count), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_collide_pose_points(&a, &xa, &b, &xb, 0, NULL, &n, NULL, MAXC, &count), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_collide_pose_points(&a, &xa, &b, &xb, 0, NULL, &n, pts, MAXC, NULL), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_collide_pose_points(&a, &xa, &b, &xb, 0, NULL, &n, pts, -1, &count), MK_ERR_BAD_ARGUMENT);
    MK_ASSERT_STATUS(mk_collide_pose_points(&a, &xa, &b, &xb, (mk_real)NAN, NULL, &n, pts, MAXC, &count), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_collide_pose_points(&a, &xa, &b, &xb, (mk_real)INFINITY, NULL, &n, pts, MAXC, &count), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_collide_pose_points(&a, &xa, &b, &xb, -1, NULL, &n, pts, MAXC, &count), MK_ERR_BAD_ARGUMENT);
    memset(&cache, 0, sizeof cache);
    cache.mode = (mk_manifold_mode)7;
    MK_ASSERT_STATUS(mk_collide_pose_points(&a, &xa, &b, &xb, 0, &cache, &n, pts, MAXC, &count), MK_ERR_BAD_ARGUMENT);
    /* A pose not made by mk_pose_from_transform. */
    memset(&raw, 0, sizeof raw);
    raw.r = mk_mat3_identity();
    MK_ASSERT_STATUS(mk_collide_pose_points(&a, &raw, &b, &xb, 0, NULL, &n, pts, MAXC, &count), MK_ERR_UNCHECKED_POSE);
    /* An invalid shape, in either place and for boxes too. */
    bad = a;
    bad.radius = -1;
    ck_assert(mk_collide_pose_points(&bad, &xa, &b, &xb, 0, NULL, &n, pts, MAXC, &count) != MK_OK);
    ck_assert(mk_collide_pose_points(&a, &xa, &bad, &xb, 0, NULL, &n, pts, MAXC, &count) != MK_OK);
    MK_ASSERT_STATUS(mk_shape_box(mk_v3(1, 1, 1), 0, &bad), MK_OK);
    bad.u.half_extents.y = (mk_real)NAN;
    ck_assert(mk_collide_pose_points(&bad, &xa, &bad, &xb, 0, NULL, &n, pts, MAXC, &count) != MK_OK);
    /* Two planes have no manifold. */
    MK_ASSERT_STATUS(mk_shape_plane(mk_v3(0, 0, 1), 0, &p1), MK_OK);
    MK_ASSERT_STATUS(mk_shape_plane(mk_v3(0, 0, 1), 0, &p2), MK_OK);
    MK_ASSERT_STATUS(mk_collide_pose_points(&p1, &xa, &p2, &xb, 0, NULL, &n, pts, MAXC, &count), MK_ERR_UNSUPPORTED);
    /* None of it wrote anything. */
    ck_assert_int_eq(count, -1);
    ck_assert(n.x == 7 && n.y == 7 && n.z == 7);
    ck_assert(memcmp(pts, sentinel, sizeof pts) == 0);
    mk_hull_destroy(h);
}
END_TEST

static Suite *suite(void)
{
    Suite *s = suite_create("manifold_points");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, octagon_face_gives_sixteen);
    tcase_add_test(tc, swapped_order_mirrors);
    tcase_add_test(tc, cylinder_cap_gives_octagon);
    tcase_add_test(tc, random_hulls_superset);
    tcase_add_test(tc, boxes_stay_reduced);
    tcase_add_test(tc, short_buffer_is_a_status);
    tcase_add_test(tc, bad_input);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return mk_test_run(suite()); }

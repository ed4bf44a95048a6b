/* test_manifold_touching.c: MK_MANIFOLD_TOUCHING_ONLY (minko/manifold.h).
 * Along moving trajectories of box, rounded box, hull, sphere, capsule and
 * cylinder pairs in and out of the margin, a cache with the flag gives, frame
 * after frame, exactly the manifold of a cache without it less its
 * speculative points: so the flag drops points and nothing else, and the
 * warm state (the preferred axis) carries over as without it. Unknown flag
 * bits are refused. */
#include <string.h>

#include "minko/manifold.h"
#include "support/mk_test.h"

/* Coordinates are O(1): a point the plain call reports touching by less
 * than round-off may be missing where SAT finds the solids apart. */
#define REQUIRE(cond, ...) do { if (!(cond)) ck_abort_msg(__VA_ARGS__); } while (0)

#if defined(MK_SINGLE)
#  define TOL 2e-5
#else
#  define TOL 1e-12
#endif

static int same_point(const mk_contact_point *p, const mk_contact_point *q)
{
    return memcmp(&p->point_a, &q->point_a, sizeof p->point_a) == 0 && memcmp(&p->point_b, &q->point_b, sizeof p->point_b) == 0 &&
           memcmp(&p->local_a, &q->local_a, sizeof p->local_a) == 0 && memcmp(&p->local_b, &q->local_b, sizeof p->local_b) == 0 &&
           memcmp(&p->depth, &q->depth, sizeof p->depth) == 0 && p->features == q->features && p->flags == q->flags;
}

/* One shape of kind k (0 box, 1 rounded box, 2 hull, 3 sphere, 4 capsule,
 * 5 cylinder), about unit size. */
static void make_shape(mk_rng *r, int k, mk_hull **hull, mk_shape *s)
{
    switch (k) {
    case 0: MK_ASSERT_STATUS(mk_shape_box(mk_rng_v3(r, 0.2, 1), 0, s), MK_OK); break;
    case 1: MK_ASSERT_STATUS(mk_shape_box(mk_rng_v3(r, 0.2, 1), MK_REAL(0.04), s), MK_OK); break;
    case 2: {
        mk_vec3 p[12];
        int i;
        for (i = 0; i < 12; ++i) p[i] = mk_v3_mul(mk_rng_dir(r), mk_rng_v3(r, 0.4, 1));
        MK_ASSERT_STATUS(mk_hull_create(p, 12, NULL, hull), MK_OK);
        MK_ASSERT_STATUS(mk_shape_hull(*hull, 0, s), MK_OK);
        break;
    }
    case 3: MK_ASSERT_STATUS(mk_shape_sphere((mk_real)mk_rng_range(r, 0.2, 1), s), MK_OK); break;
    case 4: MK_ASSERT_STATUS(mk_shape_capsule((mk_real)mk_rng_range(r, 0.1, 0.5), (mk_real)mk_rng_range(r, 0.2, 1), s), MK_OK); break;
    default: MK_ASSERT_STATUS(mk_shape_cylinder((mk_real)mk_rng_range(r, 0.2, 1), (mk_real)mk_rng_range(r, 0.2, 1), 0, s), MK_OK); break;
    }
}

/* Moving pairs, half of them two boxes (stacked or side by side, gaps
 * around the margin, slightly tilted, the pair the flag's shortcut serves),
 * the rest random pairs of every kind above near contact. */
START_TEST(touching_only_is_the_manifold_less_speculative)
{
    mk_rng r = {777};
    int c, f, dropped = 0, apart_within = 0, touching = 0;
    for (c = 0; c < 1200; ++c) {
        mk_hull *ha = NULL, *hb = NULL;
        mk_shape a, b;
        mk_transform xa, xb;
        mk_manifold_cache plain, flagged;
        mk_vec3 vel;
        mk_quat spin;
        mk_real margin = MK_REAL(0.05);
        if (c % 2 == 0) {
            /* Boxes resting on or beside each other along axis k of A,
             * a gap around the margin, slightly tilted and offset. */
            int k = (c / 2) % 3, rounded = (c / 6) % 5 == 0;
            mk_real gap = (mk_real)mk_rng_range(&r, -0.01, 0.06);
            mk_vec3 d = mk_rng_v3(&r, -0.3, 0.3), ea, eb;
            mk_quat tilt = mk_quat_from_axis_angle(mk_rng_dir(&r), (mk_real)mk_rng_range(&r, 0, 0.05));
            make_shape(&r, rounded, &ha, &a);
            make_shape(&r, rounded, &hb, &b);
            ea = a.u.half_extents;
            eb = b.u.half_extents;
            gap += a.radius + b.radius;
            if (k == 0) d.x = ea.x + eb.x + gap;
            if (k == 1) d.y = ea.y + eb.y + gap;
            if (k == 2) d.z = ea.z + eb.z + gap;
            xa = mk_transform_make(mk_rng_v3(&r, -2, 2), mk_rng_quat(&r));
            xb = mk_transform_make(mk_transform_point(xa, d), mk_quat_mul(xa.q, tilt));
        } else {
            mk_real reach;
            make_shape(&r, (int)(mk_rng_u64(&r) % 6), &ha, &a);
            make_shape(&r, (int)(mk_rng_u64(&r) % 6), &hb, &b);
            reach = (mk_real)mk_rng_range(&r, 0.3, 1.6);
            xa = mk_transform_make(mk_rng_v3(&r, -2, 2), mk_rng_quat(&r));
            xb = mk_transform_make(mk_v3_mad(xa.p, reach, mk_rng_dir(&r)), mk_rng_quat(&r));
        }
        memset(&plain, 0, sizeof plain);
        plain.mode = (c / 2) % 2 ? MK_MANIFOLD_BEST_FACE : MK_MANIFOLD_STABLE_IDS;
        flagged = plain;
        flagged.flags = MK_MANIFOLD_TOUCHING_ONLY;
        vel = mk_rng_v3(&r, -0.004, 0.004);
        spin = mk_quat_from_axis_angle(mk_rng_dir(&r), (mk_real)mk_rng_range(&r, 0, 0.01));
        for (f = 0; f < 12; ++f) {
            mk_pose pa, pb;
            mk_manifold want, got;
            int i, n = 0, small = 1;
            MK_ASSERT_STATUS(mk_pose_from_transform(xa, &pa), MK_OK);
            MK_ASSERT_STATUS(mk_pose_from_transform(xb, &pb), MK_OK);
            MK_ASSERT_STATUS(mk_collide_pose(&a, &pa, &b, &pb, margin, &plain, &want), MK_OK);
            MK_ASSERT_STATUS(mk_collide_pose(&a, &pa, &b, &pb, margin, &flagged, &got), MK_OK);
            ck_assert_uint_eq(flagged.flags, MK_MANIFOLD_TOUCHING_ONLY); /* the host's, never written */
            for (i = 0; i < want.count; ++i) {
                if (want.points[i].depth < 0) continue;
                small = small && want.points[i].depth <= TOL;
                if (n < got.count && !same_point(&got.points[n], &want.points[i]))
                    REQUIRE(0, "case %d frame %d: point %d differs from the plain call's point %d", c, f, n, i);
                n++;
            }
            if (got.count != n && !(got.count == 0 && small))
                REQUIRE(0, "case %d frame %d: %d points with the flag, %d touching without", c, f, got.count, n);
            if (got.count > 0) ck_assert(memcmp(&got.normal, &want.normal, sizeof got.normal) == 0);
            dropped += want.count > n;
            apart_within += want.count > 0 && n == 0;
            touching += n > 0;
            xb.p = mk_v3_add(xb.p, vel);
            xb.q = mk_quat_normalize(mk_quat_mul(spin, xb.q));
        }
        if (ha) mk_hull_destroy(ha);
        if (hb) mk_hull_destroy(hb);
    }
    /* Every case was met many times. */
    ck_assert_int_gt(dropped, 1000);
    ck_assert_int_gt(apart_within, 500);
    ck_assert_int_gt(touching, 2000);
}
END_TEST

START_TEST(unknown_flags_refused)
{
    mk_shape a, s;
    mk_pose x0, x1;
    mk_manifold m;
    mk_manifold_cache cache;
    mk_vec3 n;
    mk_contact_point pts[MK_COLLIDE_MAX_CANDIDATES];
    int count;
    MK_ASSERT_STATUS(mk_shape_box(mk_v3(1, 1, 1), 0, &a), MK_OK);
    MK_ASSERT_STATUS(mk_shape_sphere(1, &s), MK_OK);
    MK_ASSERT_STATUS(mk_pose_from_transform(mk_transform_identity(), &x0), MK_OK);
    MK_ASSERT_STATUS(mk_pose_from_transform(mk_transform_make(mk_v3(0, 0, MK_REAL(1.9)), mk_quat_identity()), &x1), MK_OK);
    memset(&cache, 0, sizeof cache);
    cache.flags = 2;
    MK_ASSERT_STATUS(mk_collide_pose(&a, &x0, &a, &x1, 0, &cache, &m), MK_ERR_BAD_ARGUMENT);
    MK_ASSERT_STATUS(mk_collide_pose(&a, &x0, &s, &x1, 0, &cache, &m), MK_ERR_BAD_ARGUMENT);
    MK_ASSERT_STATUS(mk_collide_pose_points(&a, &x0, &s, &x1, 0, &cache, &n, pts, MK_COLLIDE_MAX_CANDIDATES, &count), MK_ERR_BAD_ARGUMENT);
    cache.flags = MK_MANIFOLD_TOUCHING_ONLY;
    MK_ASSERT_STATUS(mk_collide_pose(&a, &x0, &a, &x1, 0, &cache, &m), MK_OK);
    ck_assert_int_eq(m.count, 4);
    MK_ASSERT_STATUS(mk_collide_pose(&a, &x0, &s, &x1, 0, &cache, &m), MK_OK);
    ck_assert_int_eq(m.count, 1);
}
END_TEST

static Suite *suite(void)
{
    Suite *s = suite_create("manifold_touching");
    TCase *tc = tcase_create("core");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, touching_only_is_the_manifold_less_speculative);
    tcase_add_test(tc, unknown_flags_refused);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return mk_test_run(suite()); }

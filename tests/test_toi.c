/* test_toi.c: sweeps, swept bounds. */
#include <string.h>

#include "minko/toi.h"
#include "support/mk_test.h"

#if defined(MK_SINGLE)
#  define POSE_TOL 2e-5
#else
#  define POSE_TOL 1e-12
#endif

static mk_transform pose_at(const mk_sweep *sw, double t)
{
    mk_transform x;
    MK_ASSERT_STATUS(mk_sweep_transform(sw, (mk_real)t, &x), MK_OK);
    return x;
}

/* Same rotation: q and -q are the same; compare through a rotated vector pair. */
static void assert_same_pose(mk_transform a, mk_transform b, double tol)
{
    MK_ASSERT_V3_NEAR(a.p, b.p, tol);
    MK_ASSERT_V3_NEAR(mk_quat_rotate(a.q, mk_v3(1, 0, 0)), mk_quat_rotate(b.q, mk_v3(1, 0, 0)), tol);
    MK_ASSERT_V3_NEAR(mk_quat_rotate(a.q, mk_v3(0, 1, 0)), mk_quat_rotate(b.q, mk_v3(0, 1, 0)), tol);
}

START_TEST(sweep_from_transforms_interpolates)
{
    mk_rng r = {11};
    int i;
    for (i = 0; i < 200; ++i) {
        mk_transform x0 = mk_transform_make(mk_rng_v3(&r, -10, 10), mk_rng_quat(&r));
        mk_transform x1 = mk_transform_make(mk_rng_v3(&r, -10, 10), mk_rng_quat(&r));
        mk_vec3 lc = mk_rng_v3(&r, -1, 1), w0, w1, wm, axis;
        mk_sweep sw;
        double angle, a0, a1;
        MK_ASSERT_STATUS(mk_sweep_from_transforms(x0, x1, lc, &sw), MK_OK);
        assert_same_pose(pose_at(&sw, 0), x0, 10 * POSE_TOL);
        assert_same_pose(pose_at(&sw, 1), x1, 10 * POSE_TOL);
        angle = (double)mk_v3_len(sw.rotation);
        ck_assert(angle <= 3.14159265358979323846 * (1 + 1e-6));
        /* The rotation centre moves on the segment; a body point turns at a constant rate about the axis. */
        MK_ASSERT_V3_NEAR(mk_transform_point(pose_at(&sw, 0.3), lc), mk_v3_lerp(sw.c0, sw.c1, (mk_real)0.3), 10 * POSE_TOL);
        axis = mk_v3_normalize(sw.rotation);
        w0 = mk_quat_rotate(pose_at(&sw, 0).q, mk_v3(0.3, -0.2, 0.9));
        wm = mk_quat_rotate(pose_at(&sw, 0.25).q, mk_v3(0.3, -0.2, 0.9));
        w1 = mk_quat_rotate(pose_at(&sw, 0.5).q, mk_v3(0.3, -0.2, 0.9));
        w0 = mk_v3_mad(w0, -mk_v3_dot(w0, axis), axis);
        wm = mk_v3_mad(wm, -mk_v3_dot(wm, axis), axis);
        w1 = mk_v3_mad(w1, -mk_v3_dot(w1, axis), axis);
        a0 = atan2((double)mk_v3_dot(mk_v3_cross(w0, wm), axis), (double)mk_v3_dot(w0, wm));
        a1 = atan2((double)mk_v3_dot(mk_v3_cross(wm, w1), axis), (double)mk_v3_dot(wm, w1));
        MK_ASSERT_NEAR(a0, 0.25 * angle, 1e3 * POSE_TOL);
        MK_ASSERT_NEAR(a1, 0.25 * angle, 1e3 * POSE_TOL);
    }
}
END_TEST

START_TEST(sweep_from_velocity_integrates)
{
    mk_transform x0 = mk_transform_make(mk_v3(1, 2, 3), mk_quat_from_axis_angle(mk_v3(0, 1, 0), 0.4));
    mk_vec3 lc = mk_v3(0.5, 0, 0);
    mk_sweep sw;
    mk_transform x;
    MK_ASSERT_STATUS(mk_sweep_from_velocity(x0, mk_v3(10, 0, -2), mk_v3(0, 0, 30), 0.05, lc, &sw), MK_OK);
    MK_ASSERT_V3_NEAR(sw.c1, mk_v3_add(sw.c0, mk_v3(0.5, 0, -0.1)), 10 * POSE_TOL);
    x = pose_at(&sw, 1);
    MK_ASSERT_V3_NEAR(mk_transform_point(x, lc), sw.c1, 10 * POSE_TOL);
    assert_same_pose(mk_transform_make(mk_v3_zero(), x.q),
                     mk_transform_make(mk_v3_zero(), mk_quat_mul(mk_quat_from_axis_angle(mk_v3(0, 0, 1), 1.5), x0.q)), 10 * POSE_TOL);
    /* 1.5 turns in one step cannot be a sweep: substep. */
    MK_ASSERT_STATUS(mk_sweep_from_velocity(x0, mk_v3_zero(), mk_v3(0, 0, 60), 0.05, lc, &sw), MK_OK);
    MK_ASSERT_STATUS(mk_sweep_from_velocity(x0, mk_v3_zero(), mk_v3(0, 0, 63), 0.05, lc, &sw), MK_ERR_BAD_ARGUMENT);
}
END_TEST

START_TEST(sweep_bad_input)
{
    mk_transform x0 = mk_transform_identity(), bad = mk_transform_make(mk_v3_zero(), mk_quat_make(0, 0, 0.5, 0.5));
    mk_sweep sw, good;
    mk_transform x;
    mk_shape plane, sphere;
    mk_aabb box;
    memset(&sw, 0, sizeof sw);
    MK_ASSERT_STATUS(mk_sweep_from_transforms(x0, x0, mk_v3_zero(), NULL), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_sweep_from_transforms(x0, bad, mk_v3_zero(), &sw), MK_ERR_BAD_ROTATION);
    MK_ASSERT_STATUS(mk_sweep_from_transforms(x0, x0, mk_v3((mk_real)NAN, 0, 0), &sw), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_sweep_from_velocity(x0, mk_v3((mk_real)INFINITY, 0, 0), mk_v3_zero(), 1, mk_v3_zero(), &sw), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_sweep_from_velocity(x0, mk_v3_zero(), mk_v3_zero(), -1, mk_v3_zero(), &sw), MK_ERR_BAD_ARGUMENT);
    MK_ASSERT_STATUS(mk_sweep_from_velocity(bad, mk_v3_zero(), mk_v3_zero(), 1, mk_v3_zero(), &sw), MK_ERR_BAD_ROTATION);
    ck_assert(sw.q0.w == 0); /* untouched by every refusal */
    MK_ASSERT_STATUS(mk_sweep_from_transforms(x0, x0, mk_v3_zero(), &good), MK_OK);
    sw = good;
    sw.q0 = mk_quat_make(0, 0, 0, 1.1);
    MK_ASSERT_STATUS(mk_sweep_validate(&sw), MK_ERR_BAD_ROTATION);
    sw = good;
    sw.rotation = mk_v3(4, 0, 0);
    MK_ASSERT_STATUS(mk_sweep_validate(&sw), MK_ERR_BAD_ARGUMENT);
    sw = good;
    sw.c1.y = (mk_real)NAN;
    MK_ASSERT_STATUS(mk_sweep_validate(&sw), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_sweep_transform(&good, (mk_real)1.5, &x), MK_ERR_BAD_ARGUMENT);
    MK_ASSERT_STATUS(mk_sweep_transform(&good, (mk_real)NAN, &x), MK_ERR_NOT_FINITE);
    mk_shape_plane(mk_v3(0, 0, 1), 0, &plane);
    mk_shape_sphere(1, &sphere);
    MK_ASSERT_STATUS(mk_swept_aabb(&plane, &good, &box), MK_ERR_UNSUPPORTED);
    MK_ASSERT_STATUS(mk_swept_aabb(&sphere, &sw, &box), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_swept_aabb(&sphere, NULL, &box), MK_ERR_NULL);
}
END_TEST

/* Every shape, random sweeps (fast turns included): the swept box holds the
 * shape's box at 2000 sampled times, and is exact for pure translation. */
START_TEST(swept_aabb_contains_motion)
{
    mk_rng r = {12};
    mk_shape shapes[6];
    int i, k;
    mk_shape_sphere(0.5, &shapes[0]);
    mk_shape_box(mk_v3(1, 0.2, 0.4), 0.05, &shapes[1]);
    mk_shape_capsule(0.2, 1, &shapes[2]);
    mk_shape_cylinder(0.5, 0.3, 0, &shapes[3]);
    mk_shape_cone(0.4, 0.8, 0.1, &shapes[4]);
    mk_shape_box(mk_v3(2, 0.05, 0.05), 0, &shapes[5]);
    for (i = 0; i < 120; ++i) {
        const mk_shape *s = &shapes[i % 6];
        mk_transform x0 = mk_transform_make(mk_rng_v3(&r, -5, 5), mk_rng_quat(&r));
        mk_vec3 v = mk_rng_v3(&r, -20, 20), w = mk_v3_scale(mk_rng_dir(&r), (mk_real)mk_rng_range(&r, 0, 3.14));
        mk_vec3 lc = i % 3 == 0 ? mk_v3_zero() : mk_rng_v3(&r, -0.5, 0.5);
        mk_sweep sw;
        mk_aabb swept, a0, a1;
        if (i % 4 == 0) w = mk_v3_zero();
        MK_ASSERT_STATUS(mk_sweep_from_velocity(x0, v, w, 1, lc, &sw), MK_OK);
        MK_ASSERT_STATUS(mk_swept_aabb(s, &sw, &swept), MK_OK);
        for (k = 0; k <= 2000; ++k) {
            mk_aabb b;
            MK_ASSERT_STATUS(mk_shape_aabb(s, pose_at(&sw, k / 2000.0), &b), MK_OK);
            ck_assert_msg(mk_aabb_contains(swept, b), "case %d (%s), t = %g: the shape leaves its swept box", i,
                          mk_shape_type_name(s->type), k / 2000.0);
        }
        mk_shape_aabb(s, pose_at(&sw, 0), &a0);
        mk_shape_aabb(s, pose_at(&sw, 1), &a1);
        if (i % 4 == 0) {
            a0 = mk_aabb_union(a0, a1);
            MK_ASSERT_V3_NEAR(swept.lo, a0.lo, 100 * POSE_TOL);
            MK_ASSERT_V3_NEAR(swept.hi, a0.hi, 100 * POSE_TOL);
        }
    }
}
END_TEST

static Suite *toi_suite(void)
{
    Suite *s = suite_create("toi");
    TCase *tc = tcase_create("sweep");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, sweep_from_transforms_interpolates);
    tcase_add_test(tc, sweep_from_velocity_integrates);
    tcase_add_test(tc, sweep_bad_input);
    tcase_add_test(tc, swept_aabb_contains_motion);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return mk_test_run(toi_suite()); }

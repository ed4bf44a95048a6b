/* test_shape.c: shape constructors, validation, support functions, AABBs. */
#include <string.h>

#include "minko/shape.h"
#include "support/mk_test.h"

START_TEST(constructors_reject_bad_sizes)
{
    mk_shape s;
    memset(&s, 0, sizeof s);
    s.type = MK_SHAPE_TYPE_COUNT; /* must stay untouched by refused calls */
    MK_ASSERT_STATUS(mk_shape_sphere(0, &s), MK_ERR_BAD_SIZE);
    MK_ASSERT_STATUS(mk_shape_sphere(-1, &s), MK_ERR_BAD_SIZE);
    MK_ASSERT_STATUS(mk_shape_sphere((mk_real)NAN, &s), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_shape_sphere((mk_real)INFINITY, &s), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_shape_box(mk_v3(1, 0, 1), 0, &s), MK_ERR_BAD_SIZE);
    MK_ASSERT_STATUS(mk_shape_box(mk_v3(1, 1, 1), -0.1, &s), MK_ERR_BAD_SIZE);
    MK_ASSERT_STATUS(mk_shape_box(mk_v3(1, 1, (mk_real)NAN), 0, &s), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_shape_capsule(1, 0, &s), MK_ERR_BAD_SIZE);
    MK_ASSERT_STATUS(mk_shape_cylinder(-1, 1, 0, &s), MK_ERR_BAD_SIZE);
    MK_ASSERT_STATUS(mk_shape_cone(1, -1, 0, &s), MK_ERR_BAD_SIZE);
    MK_ASSERT_STATUS(mk_shape_hull(NULL, 0, &s), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_shape_plane(mk_v3(0, 0, 2), 0, &s), MK_ERR_BAD_NORMAL);
    MK_ASSERT_STATUS(mk_shape_plane(mk_v3(0, 0, 0), 0, &s), MK_ERR_BAD_NORMAL);
    MK_ASSERT_STATUS(mk_shape_plane(mk_v3(0, 0, 1), (mk_real)NAN, &s), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_shape_plane(mk_v3(0, 0, 1), 2 * MK_MAX_COORD, &s), MK_ERR_OUT_OF_RANGE);
    MK_ASSERT_STATUS(mk_shape_plane(mk_v3(0, 0, 1), -2 * MK_MAX_COORD, &s), MK_ERR_OUT_OF_RANGE);
    MK_ASSERT_STATUS(mk_shape_sphere(1, NULL), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_shape_validate(NULL), MK_ERR_NULL);
    ck_assert_int_eq(s.type, MK_SHAPE_TYPE_COUNT);
    MK_ASSERT_STATUS(mk_shape_validate(&s), MK_ERR_BAD_SHAPE);
    MK_ASSERT_STATUS(mk_shape_box(mk_v3(1, 2, 3), 0.1, &s), MK_OK);
    ck_assert_int_eq(s.type, MK_SHAPE_BOX);
    ck_assert_str_eq(mk_shape_type_name(MK_SHAPE_CONE), "cone");
    ck_assert_str_eq(mk_shape_type_name(MK_SHAPE_TYPE_COUNT), "unknown");
}
END_TEST

START_TEST(support_primitives_analytic)
{
    mk_shape s;
    mk_vec3 d = mk_v3(1, -2, 2); /* |d| = 3 */
    mk_shape_sphere(2, &s);
    MK_ASSERT_V3_NEAR(mk_shape_support(&s, d), mk_v3(2.0 / 3, -4.0 / 3, 4.0 / 3), 4 * MK_REAL_EPSILON);
    mk_shape_box(mk_v3(1, 2, 3), 0, &s);
    MK_ASSERT_V3_NEAR(mk_shape_support(&s, d), mk_v3(1, -2, 3), 0);
    mk_shape_box(mk_v3(1, 2, 3), 0.3, &s);
    MK_ASSERT_V3_NEAR(mk_shape_support(&s, d), mk_v3(1 + 0.1, -2 - 0.2, 3 + 0.2), 8 * MK_REAL_EPSILON);
    mk_shape_capsule(0.5, 2, &s);
    MK_ASSERT_V3_NEAR(mk_shape_support(&s, mk_v3(0, 0, -1)), mk_v3(0, 0, -2.5), 0);
    mk_shape_cylinder(2, 1, 0, &s);
    MK_ASSERT_V3_NEAR(mk_shape_support(&s, mk_v3(3, 4, 1)), mk_v3(1.2, 1.6, 1), 4 * MK_REAL_EPSILON);
    MK_ASSERT_V3_NEAR(mk_shape_support(&s, mk_v3(0, 0, -1)), mk_v3(0, 0, -1), 0);
    mk_shape_cone(1, 1, 0, &s);
    MK_ASSERT_V3_NEAR(mk_shape_support(&s, mk_v3(0, 0, 1)), mk_v3(0, 0, 1), 0);
    MK_ASSERT_V3_NEAR(mk_shape_support(&s, mk_v3(1, 0, 0)), mk_v3(1, 0, -1), 0);
    mk_shape_plane(mk_v3(0, 0, 1), 2, &s);
    MK_ASSERT_V3_NEAR(mk_shape_support(&s, mk_v3(0, 0, 5)), mk_v3(0, 0, 2), 0);
    ck_assert(!mk_v3_is_valid(mk_v3_scale(mk_shape_support(&s, mk_v3(1, 0, 0)), 10)));
}
END_TEST

/* The support function is the ground truth: the world AABB must touch the
 * solid on all six sides, i.e. equal the world support along +-x, +-y, +-z. */
static void check_aabb_tight(const mk_shape *s, mk_transform xf, double tol)
{
    mk_aabb b;
    int i;
    mk_mat3 R = mk_mat3_from_quat(xf.q);
    MK_ASSERT_STATUS(mk_shape_aabb(s, xf, &b), MK_OK);
    for (i = 0; i < 3; ++i) {
        mk_vec3 e = mk_v3(i == 0, i == 1, i == 2);
        mk_real hi = mk_v3_dot(e, mk_v3_add(mk_mat3_mul_v3(R, mk_shape_support(s, mk_mat3_tmul_v3(R, e))), xf.p));
        mk_real lo = mk_v3_dot(e, mk_v3_add(mk_mat3_mul_v3(R, mk_shape_support(s, mk_mat3_tmul_v3(R, mk_v3_neg(e)))), xf.p));
        MK_ASSERT_NEAR(i == 0 ? b.hi.x : i == 1 ? b.hi.y : b.hi.z, hi, tol);
        MK_ASSERT_NEAR(i == 0 ? b.lo.x : i == 1 ? b.lo.y : b.lo.z, lo, tol);
    }
}

START_TEST(aabb_is_tight)
{
    mk_rng r = {3};
    mk_shape shapes[6];
    int i, k;
    mk_shape_sphere(0.7, &shapes[0]);
    mk_shape_box(mk_v3(1, 0.2, 3), 0.05, &shapes[1]);
    mk_shape_capsule(0.3, 1.5, &shapes[2]);
    mk_shape_cylinder(0.8, 0.4, 0.02, &shapes[3]);
    mk_shape_cone(0.6, 1.1, 0, &shapes[4]);
    mk_shape_cone(0.6, 1.1, 0.1, &shapes[5]);
    for (k = 0; k < 6; ++k)
        for (i = 0; i < 200; ++i)
            check_aabb_tight(&shapes[k], mk_transform_make(mk_rng_v3(&r, -50, 50), mk_rng_quat(&r)), 1e-5);
}
END_TEST

START_TEST(aabb_plane_and_bad_transform)
{
    mk_shape s;
    mk_aabb b;
    mk_shape_plane(mk_v3(0, 0, 1), 1, &s);
    MK_ASSERT_STATUS(mk_shape_aabb(&s, mk_transform_make(mk_v3(0, 0, 2), mk_quat_identity()), &b), MK_OK);
    MK_ASSERT_NEAR(b.hi.z, 3, 0);
    ck_assert(isinf((double)b.lo.z) && b.lo.z < 0);
    ck_assert(isinf((double)b.hi.x) && isinf((double)b.lo.y));
    mk_shape_sphere(1, &s);
    MK_ASSERT_STATUS(mk_shape_aabb(&s, mk_transform_make(mk_v3(0, 0, 0), mk_quat_make(0, 0, 0, 3)), &b), MK_ERR_BAD_ROTATION);
    MK_ASSERT_STATUS(mk_shape_aabb(&s, mk_transform_make(mk_v3((mk_real)NAN, 0, 0), mk_quat_identity()), &b), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_shape_aabb(&s, mk_transform_identity(), NULL), MK_ERR_NULL);
}
END_TEST

static Suite *shape_suite(void)
{
    Suite *s = suite_create("shape");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, constructors_reject_bad_sizes);
    tcase_add_test(tc, support_primitives_analytic);
    tcase_add_test(tc, aabb_is_tight);
    tcase_add_test(tc, aabb_plane_and_bad_transform);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return mk_test_run(shape_suite()); }

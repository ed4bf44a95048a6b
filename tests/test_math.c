/* test_math.c: math3d, status strings, version. */
#include <math.h>
#include <string.h>

#include "minko/math3d.h"
#include "support/mk_test.h"

START_TEST(status_strings)
{
    int i;
    for (i = 0; i < MK_STATUS_COUNT_; ++i) {
        ck_assert_ptr_nonnull(mk_status_str((mk_status)i));
        ck_assert_int_gt((int)strlen(mk_status_str((mk_status)i)), 1);
        ck_assert_str_ne(mk_status_name((mk_status)i), "MK_STATUS_UNKNOWN");
    }
    ck_assert_str_eq(mk_status_str(MK_OK), "ok");
    ck_assert_str_eq(mk_status_name(MK_ERR_NOT_FINITE), "MK_ERR_NOT_FINITE");
    ck_assert_str_eq(mk_status_str((mk_status)999), "unknown mk_status value");
    ck_assert_str_eq(mk_status_name((mk_status)-1), "MK_STATUS_UNKNOWN");
}
END_TEST

START_TEST(version_and_precision)
{
    ck_assert_int_eq(mk_version(), MK_VERSION_NUMBER);
#if defined(MK_SINGLE)
    ck_assert_int_eq(mk_is_double_precision(), 0);
    ck_assert_int_eq((int)sizeof(mk_real), 4);
#else
    ck_assert_int_eq(mk_is_double_precision(), 1);
    ck_assert_int_eq((int)sizeof(mk_real), 8);
#endif
}
END_TEST

START_TEST(vector_ops)
{
    mk_vec3 a = mk_v3(1, 2, 3), b = mk_v3(-4, 5, 0.5);
    MK_ASSERT_V3_NEAR(mk_v3_cross(a, b), mk_v3(2 * 0.5 - 3 * 5, 3 * -4 - 1 * 0.5, 1 * 5 - 2 * -4), 0);
    MK_ASSERT_NEAR(mk_v3_dot(a, b), -4 + 10 + 1.5, 0);
    MK_ASSERT_NEAR(mk_v3_len(mk_v3(3, 4, 12)), 13, 0);
    MK_ASSERT_V3_NEAR(mk_v3_normalize(mk_v3(0, 0, 0)), mk_v3(0, 0, 0), 0);
    MK_ASSERT_V3_NEAR(mk_v3_normalize(mk_v3(0, 0, -5)), mk_v3(0, 0, -1), 0);
    MK_ASSERT_V3_NEAR(mk_v3_mad(a, 2, b), mk_v3(-7, 12, 4), 0);
    ck_assert(!mk_v3_is_valid(mk_v3(0, (mk_real)NAN, 0)));
    ck_assert(!mk_v3_is_valid(mk_v3((mk_real)INFINITY, 0, 0)));
    ck_assert(mk_v3_is_valid(a));
}
END_TEST

START_TEST(perp_is_perpendicular_unit)
{
    mk_rng r = {1};
    int i;
    for (i = 0; i < 1000; ++i) {
        mk_vec3 n = mk_rng_dir(&r), p = mk_v3_perp(n);
        MK_ASSERT_NEAR(mk_v3_dot(n, p), 0, 10 * MK_REAL_EPSILON);
        MK_ASSERT_NEAR(mk_v3_len(p), 1, 10 * MK_REAL_EPSILON);
    }
}
END_TEST

START_TEST(quaternion_matrix_agree)
{
    mk_rng r = {7};
    int i;
    for (i = 0; i < 1000; ++i) {
        mk_quat q = mk_rng_quat(&r);
        mk_vec3 v = mk_rng_v3(&r, -10, 10);
        mk_mat3 m = mk_mat3_from_quat(q);
        mk_quat q2 = mk_quat_from_mat3(m);
        MK_ASSERT_V3_NEAR(mk_quat_rotate(q, v), mk_mat3_mul_v3(m, v), 1000 * MK_REAL_EPSILON);
        MK_ASSERT_V3_NEAR(mk_quat_inv_rotate(q, mk_quat_rotate(q, v)), v, 1000 * MK_REAL_EPSILON);
        MK_ASSERT_V3_NEAR(mk_quat_rotate(q2, v), mk_quat_rotate(q, v), 2000 * MK_REAL_EPSILON);
        MK_ASSERT_V3_NEAR(mk_mat3_tmul_v3(m, mk_mat3_mul_v3(m, v)), v, 1000 * MK_REAL_EPSILON);
        ck_assert(mk_quat_is_valid(q));
    }
}
END_TEST

START_TEST(axis_angle)
{
    mk_quat q = mk_quat_from_axis_angle(mk_v3(0, 0, 2), (mk_real)(3.14159265358979323846 / 2));
    MK_ASSERT_V3_NEAR(mk_quat_rotate(q, mk_v3(1, 0, 0)), mk_v3(0, 1, 0), 10 * MK_REAL_EPSILON);
    q = mk_quat_from_axis_angle(mk_v3(0, 0, 0), 1);
    MK_ASSERT_NEAR(q.w, 1, 0);
}
END_TEST

START_TEST(quaternion_validation)
{
    ck_assert(!mk_quat_is_valid(mk_quat_make(0, 0, 0, 2)));
    ck_assert(!mk_quat_is_valid(mk_quat_make(0, 0, 0, 0)));
    ck_assert(!mk_quat_is_valid(mk_quat_make(0, 0, (mk_real)NAN, 1)));
    ck_assert(mk_quat_is_valid(mk_quat_make(0, 0, 0, 1 + MK_QUAT_TOLERANCE / 4)));
    MK_ASSERT_NEAR(mk_quat_normalize(mk_quat_make(0, 0, 0, 0)).w, 1, 0);
}
END_TEST

START_TEST(transforms_compose)
{
    mk_rng r = {11};
    int i;
    for (i = 0; i < 500; ++i) {
        mk_transform a = mk_transform_make(mk_rng_v3(&r, -100, 100), mk_rng_quat(&r));
        mk_transform b = mk_transform_make(mk_rng_v3(&r, -100, 100), mk_rng_quat(&r));
        mk_vec3 v = mk_rng_v3(&r, -10, 10);
        mk_transform ab = mk_transform_mul(a, b), rel = mk_transform_inv_mul(a, b);
        MK_ASSERT_V3_NEAR(mk_transform_point(ab, v), mk_transform_point(a, mk_transform_point(b, v)), 1e4 * MK_REAL_EPSILON);
        /* a * (a^-1 b) = b */
        MK_ASSERT_V3_NEAR(mk_transform_point(a, mk_transform_point(rel, v)), mk_transform_point(b, v), 1e4 * MK_REAL_EPSILON);
        MK_ASSERT_V3_NEAR(mk_transform_inv_point(a, mk_transform_point(a, v)), v, 1e4 * MK_REAL_EPSILON);
    }
}
END_TEST

START_TEST(aabb_closed_intervals)
{
    mk_aabb a = mk_aabb_make(mk_v3(0, 0, 0), mk_v3(1, 1, 1));
    mk_aabb touch = mk_aabb_make(mk_v3(1, 0, 0), mk_v3(2, 1, 1));
    mk_aabb apart = mk_aabb_make(mk_v3(1 + 1e-3, 0, 0), mk_v3(2, 1, 1));
    ck_assert(mk_aabb_overlap(a, touch));
    ck_assert(mk_aabb_overlap(touch, a));
    ck_assert(!mk_aabb_overlap(a, apart));
    ck_assert(mk_aabb_contains(mk_aabb_union(a, touch), a));
    ck_assert(!mk_aabb_is_valid(mk_aabb_make(mk_v3(1, 0, 0), mk_v3(0, 1, 1))));
    ck_assert(!mk_aabb_is_valid(mk_aabb_make(mk_v3((mk_real)NAN, 0, 0), mk_v3(0, 1, 1))));
    ck_assert(mk_aabb_is_valid(mk_aabb_make(mk_v3(-(mk_real)INFINITY, 0, 0), mk_v3(0, 1, 1))));
}
END_TEST

/* Largest |r^T r - I| entry. */
static double orthonormality_error(mk_mat3 r)
{
    double e = fabs((double)mk_v3_len2(r.c0) - 1);
    e = fmax(e, fabs((double)mk_v3_len2(r.c1) - 1));
    e = fmax(e, fabs((double)mk_v3_len2(r.c2) - 1));
    e = fmax(e, fabs((double)mk_v3_dot(r.c0, r.c1)));
    e = fmax(e, fabs((double)mk_v3_dot(r.c0, r.c2)));
    return fmax(e, fabs((double)mk_v3_dot(r.c1, r.c2)));
}

START_TEST(pose_from_transform)
{
    mk_rng r = {21};
    mk_pose p, before;
    int i;
    for (i = 0; i < 1000; ++i) {
        mk_quat q = mk_rng_quat(&r);
        mk_real g = (mk_real)mk_rng_range(&r, 1 - MK_QUAT_TOLERANCE / 3, 1 + MK_QUAT_TOLERANCE / 3); /* drifted, accepted */
        mk_vec3 x = mk_rng_v3(&r, -100, 100), v = mk_rng_v3(&r, -1, 1);
        MK_ASSERT_STATUS(mk_pose_from_transform(mk_transform_make(x, mk_quat_make(q.x * g, q.y * g, q.z * g, q.w * g)), &p), MK_OK);
        /* The exact rotation of q / |q|: orthonormal to rounding whatever the drift. */
        ck_assert(orthonormality_error(p.r) <= 16 * MK_REAL_EPSILON);
        MK_ASSERT_V3_NEAR(mk_mat3_mul_v3(p.r, v), mk_quat_rotate(q, v), 64 * MK_REAL_EPSILON);
        ck_assert(p.p.x == x.x && p.p.y == x.y && p.p.z == x.z);
    }
    memset(&p, 0x5a, sizeof p);
    before = p;
    MK_ASSERT_STATUS(mk_pose_from_transform(mk_transform_identity(), NULL), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_pose_from_transform(mk_transform_make(mk_v3(0, (mk_real)NAN, 0), mk_quat_identity()), &p), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_pose_from_transform(mk_transform_make(mk_v3_zero(), mk_quat_make(0, (mk_real)INFINITY, 0, 1)), &p),
                     MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_pose_from_transform(mk_transform_make(mk_v3_zero(), mk_quat_make(0, 0, 0, 1 + 2 * MK_QUAT_TOLERANCE)), &p),
                     MK_ERR_BAD_ROTATION);
    MK_ASSERT_STATUS(mk_pose_from_transform(mk_transform_make(mk_v3(0, 0, -2 * MK_MAX_COORD), mk_quat_identity()), &p),
                     MK_ERR_OUT_OF_RANGE);
    ck_assert(memcmp(&p, &before, sizeof p) == 0); /* untouched on error */
}
END_TEST

START_TEST(pose_from_matrix)
{
    mk_rng r = {22};
    mk_pose p, before;
    mk_mat3 m;
    int i;
    for (i = 0; i < 1000; ++i) {
        mk_quat q = mk_rng_quat(&r);
        mk_vec3 x = mk_rng_v3(&r, -100, 100), v = mk_rng_v3(&r, -1, 1);
        m = mk_mat3_from_quat(q);
        /* A host's matrix, orthonormal to rounding: kept exactly. */
        MK_ASSERT_STATUS(mk_pose_from_matrix(m, x, &p), MK_OK);
        ck_assert(memcmp(&p.r, &m, sizeof m) == 0);
        /* Drifted by a quarter of the tolerance in every entry (what a float
         * host widened to double, or a long-integrated matrix, looks like):
         * accepted, and replaced by an exact rotation close to it. */
        m.c0 = mk_v3_add(m.c0, mk_v3_scale(mk_rng_v3(&r, -1, 1), MK_ROTATION_TOLERANCE / 8));
        m.c1 = mk_v3_add(m.c1, mk_v3_scale(mk_rng_v3(&r, -1, 1), MK_ROTATION_TOLERANCE / 8));
        m.c2 = mk_v3_add(m.c2, mk_v3_scale(mk_rng_v3(&r, -1, 1), MK_ROTATION_TOLERANCE / 8));
        MK_ASSERT_STATUS(mk_pose_from_matrix(m, x, &p), MK_OK);
        ck_assert_msg(orthonormality_error(p.r) <= 16 * MK_REAL_EPSILON, "orthonormality %g", orthonormality_error(p.r));
        ck_assert(mk_v3_dot(p.r.c2, mk_v3_cross(p.r.c0, p.r.c1)) > 0);
        MK_ASSERT_V3_NEAR(mk_mat3_mul_v3(p.r, v), mk_quat_rotate(q, v), 4 * MK_ROTATION_TOLERANCE);
    }
    memset(&p, 0x5a, sizeof p);
    before = p;
    m = mk_mat3_identity();
    MK_ASSERT_STATUS(mk_pose_from_matrix(m, mk_v3_zero(), NULL), MK_ERR_NULL);
    m.c1.z = (mk_real)NAN;
    MK_ASSERT_STATUS(mk_pose_from_matrix(m, mk_v3_zero(), &p), MK_ERR_NOT_FINITE);
    m = mk_mat3_identity();
    MK_ASSERT_STATUS(mk_pose_from_matrix(m, mk_v3((mk_real)INFINITY, 0, 0), &p), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_pose_from_matrix(m, mk_v3(0, 2 * MK_MAX_COORD, 0), &p), MK_ERR_OUT_OF_RANGE);
    m.c2 = mk_v3(0, 0, -1); /* a reflection: orthonormal, det -1 */
    MK_ASSERT_STATUS(mk_pose_from_matrix(m, mk_v3_zero(), &p), MK_ERR_BAD_ROTATION);
    m = mk_mat3_identity();
    m.c0.x = 1 + 2 * MK_ROTATION_TOLERANCE; /* scaled */
    MK_ASSERT_STATUS(mk_pose_from_matrix(m, mk_v3_zero(), &p), MK_ERR_BAD_ROTATION);
    m = mk_mat3_identity();
    m.c1.x = 2 * MK_ROTATION_TOLERANCE; /* sheared */
    MK_ASSERT_STATUS(mk_pose_from_matrix(m, mk_v3_zero(), &p), MK_ERR_BAD_ROTATION);
    m = mk_mat3_cols(mk_v3_zero(), mk_v3_zero(), mk_v3_zero());
    MK_ASSERT_STATUS(mk_pose_from_matrix(m, mk_v3_zero(), &p), MK_ERR_BAD_ROTATION);
    /* The accepting test has no finiteness check of its own: a NaN or an
     * infinity in any entry of r, alone or with a bad position, must still
     * be named MK_ERR_NOT_FINITE (a NaN would slip through the max of the
     * orthonormality errors; the determinant stops it). */
    for (i = 0; i < 9; ++i) {
        const mk_real bad[3] = {(mk_real)NAN, (mk_real)INFINITY, -(mk_real)INFINITY};
        int k;
        for (k = 0; k < 3; ++k) {
            m = mk_mat3_from_quat(mk_rng_quat(&r));
            (&m.c0.x)[i] = bad[k];
            MK_ASSERT_STATUS(mk_pose_from_matrix(m, mk_v3_zero(), &p), MK_ERR_NOT_FINITE);
            MK_ASSERT_STATUS(mk_pose_from_matrix(m, mk_v3(0, 2 * MK_MAX_COORD, 0), &p), MK_ERR_NOT_FINITE);
        }
    }
    /* Finite but so large that r^T r overflows: a bad rotation, not a crash. */
    m = mk_mat3_identity();
    m.c2.z = MK_REAL_MAX;
    MK_ASSERT_STATUS(mk_pose_from_matrix(m, mk_v3_zero(), &p), MK_ERR_BAD_ROTATION);
    ck_assert(memcmp(&p, &before, sizeof p) == 0); /* untouched on error */
}
END_TEST

/* mk_pose_set_position moves a checked pose and keeps its rotation bits;
 * the position gets the constructors' checks, a raw pose is refused, and a
 * refusal leaves the pose as it was. */
START_TEST(pose_set_position)
{
    mk_rng r = {23};
    mk_pose p, q, before, raw;
    mk_quat rot = mk_rng_quat(&r);
    mk_vec3 x = mk_rng_v3(&r, -100, 100);
    MK_ASSERT_STATUS(mk_pose_from_transform(mk_transform_make(mk_rng_v3(&r, -100, 100), rot), &p), MK_OK);
    MK_ASSERT_STATUS(mk_pose_from_transform(mk_transform_make(x, rot), &q), MK_OK);
    MK_ASSERT_STATUS(mk_pose_set_position(&p, x), MK_OK);
    /* The same pose as made afresh (fields compared: the struct has padding). */
    ck_assert(memcmp(&p.r, &q.r, sizeof p.r) == 0 && memcmp(&p.p, &q.p, sizeof p.p) == 0 && p.checked == q.checked);
    before = p;
    MK_ASSERT_STATUS(mk_pose_set_position(NULL, x), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_pose_set_position(&p, mk_v3(0, (mk_real)NAN, 0)), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_pose_set_position(&p, mk_v3(0, 0, -(mk_real)INFINITY)), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_pose_set_position(&p, mk_v3(2 * MK_MAX_COORD, 0, 0)), MK_ERR_OUT_OF_RANGE);
    ck_assert(memcmp(&p.r, &before.r, sizeof p.r) == 0 && memcmp(&p.p, &before.p, sizeof p.p) == 0 && p.checked == before.checked);
    MK_ASSERT_STATUS(mk_pose_set_position(&p, mk_v3(MK_MAX_COORD, -MK_MAX_COORD, 0)), MK_OK); /* the bound is inclusive */
    ck_assert(p.p.x == MK_MAX_COORD && memcmp(&p.r, &before.r, sizeof p.r) == 0);
    memset(&raw, 0, sizeof raw);
    raw.r = mk_mat3_identity();
    MK_ASSERT_STATUS(mk_pose_set_position(&raw, x), MK_ERR_UNCHECKED_POSE);
    ck_assert(raw.checked == 0 && raw.p.x == 0);
}
END_TEST

/* The coordinate bound is inclusive and exact in both precisions: +-MK_MAX_COORD
 * passes, the next representable number beyond it does not. */
START_TEST(coordinate_bound)
{
    const mk_real b = MK_MAX_COORD;
#if defined(MK_SINGLE)
    const mk_real beyond = nextafterf(b, (mk_real)INFINITY);
#else
    const mk_real beyond = nextafter(b, (mk_real)INFINITY);
#endif
    mk_pose p;
    ck_assert(mk_position_is_valid(mk_v3(b, -b, b)));
    ck_assert(!mk_position_is_valid(mk_v3(beyond, 0, 0)));
    ck_assert(!mk_position_is_valid(mk_v3(0, -beyond, 0)));
    ck_assert(!mk_position_is_valid(mk_v3(0, 0, (mk_real)NAN)));
    ck_assert(mk_transform_is_valid(mk_transform_make(mk_v3(-b, b, -b), mk_quat_identity())));
    ck_assert(!mk_transform_is_valid(mk_transform_make(mk_v3(0, 0, beyond), mk_quat_identity())));
    MK_ASSERT_STATUS(mk_pose_from_transform(mk_transform_make(mk_v3(b, b, -b), mk_quat_identity()), &p), MK_OK);
    MK_ASSERT_STATUS(mk_pose_from_matrix(mk_mat3_identity(), mk_v3(-b, b, b), &p), MK_OK);
    MK_ASSERT_STATUS(mk_pose_from_transform(mk_transform_make(mk_v3(b, -beyond, b), mk_quat_identity()), &p), MK_ERR_OUT_OF_RANGE);
    MK_ASSERT_STATUS(mk_pose_from_matrix(mk_mat3_identity(), mk_v3(-beyond, 0, 0), &p), MK_ERR_OUT_OF_RANGE);
}
END_TEST

static Suite *math_suite(void)
{
    Suite *s = suite_create("math");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, status_strings);
    tcase_add_test(tc, version_and_precision);
    tcase_add_test(tc, vector_ops);
    tcase_add_test(tc, perp_is_perpendicular_unit);
    tcase_add_test(tc, quaternion_matrix_agree);
    tcase_add_test(tc, axis_angle);
    tcase_add_test(tc, quaternion_validation);
    tcase_add_test(tc, transforms_compose);
    tcase_add_test(tc, aabb_closed_intervals);
    tcase_add_test(tc, pose_from_transform);
    tcase_add_test(tc, pose_from_matrix);
    tcase_add_test(tc, pose_set_position);
    tcase_add_test(tc, coordinate_bound);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return mk_test_run(math_suite()); }

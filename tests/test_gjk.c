/* test_gjk.c: GJK on cores: smooth shapes against analytic answers, rounded
 * shapes, the warm-start cache, boolean queries, and the internal solver's
 * explicit states. */
#include <string.h>

#include "gjk.h"
#include "minko/distance.h"
#include "pose.h"
#include "support/mk_test.h"

/* Smooth cores converge to GJK's relative tolerance (1e4 eps). Near the
 * optimum the distance is flat to second order in the normal, so a curved
 * feature's normal is known only to about the square root of that. */
#if defined(MK_SINGLE)
#  define TOL 2e-5
#  define NTOL 1e-2
#else
#  define TOL 1e-10
#  define NTOL 1e-5
#endif

static mk_transform xf(mk_real x, mk_real y, mk_real z) { return mk_transform_make(mk_v3(x, y, z), mk_quat_identity()); }
static mk_transform xfq(mk_vec3 p, mk_quat q) { return mk_transform_make(p, q); }

static mk_distance_result dist_ok(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb)
{
    mk_distance_result r;
    MK_ASSERT_STATUS(mk_distance(a, xa, b, xb, NULL, &r), MK_OK);
    MK_ASSERT_NEAR(mk_v3_len(r.normal), 1, 8 * MK_REAL_EPSILON);
    MK_ASSERT_V3_NEAR(r.point_b, mk_v3_mad(r.point_a, r.distance, r.normal), 1e3 * MK_REAL_EPSILON * 10);
    return r;
}

START_TEST(cylinder_cone_against_sphere)
{
    mk_shape cyl, cone, s;
    mk_distance_result r;
    mk_shape_cylinder(1, 2, 0, &cyl);
    mk_shape_cone(1, 1, 0, &cone); /* apex (0,0,1), base disc radius 1 at z = -1 */
    mk_shape_sphere(0.5, &s);
    r = dist_ok(&cyl, xf(0, 0, 0), &s, xf(3, 0, 0.5)); /* side */
    MK_ASSERT_NEAR(r.distance, 1.5, TOL);
    MK_ASSERT_V3_NEAR(r.normal, mk_v3(1, 0, 0), TOL);
    ck_assert_int_eq(r.method, MK_METHOD_GJK);
    r = dist_ok(&cyl, xf(0, 0, 0), &s, xf(0.3, 0.2, 4)); /* cap */
    MK_ASSERT_NEAR(r.distance, 1.5, TOL);
    MK_ASSERT_V3_NEAR(r.normal, mk_v3(0, 0, 1), TOL);
    r = dist_ok(&cyl, xf(0, 0, 0), &s, xf(0, 2, 3)); /* rim: nearest (0,1,2), offset (0,1,1) */
    MK_ASSERT_NEAR(r.distance, sqrt(2.0) - 0.5, TOL);
    r = dist_ok(&s, xf(0, 2, 3), &cyl, xf(0, 0, 0));
    MK_ASSERT_NEAR(r.distance, sqrt(2.0) - 0.5, TOL);
    MK_ASSERT_V3_NEAR(r.normal, mk_v3(0, -sqrt(0.5), -sqrt(0.5)), NTOL);
    r = dist_ok(&cone, xf(0, 0, 0), &s, xf(0, 0, 3)); /* above the apex */
    MK_ASSERT_NEAR(r.distance, 1.5, TOL);
    /* beside the slant: the side line from (1,0,-1) to the apex has unit
     * normal (2,0,1)/sqrt5; the centre (1,0,1) is 2/sqrt5 from it */
    r = dist_ok(&cone, xf(0, 0, 0), &s, xf(1, 0, 1));
    MK_ASSERT_NEAR(r.distance, 2 / sqrt(5.0) - 0.5, TOL);
    MK_ASSERT_V3_NEAR(r.normal, mk_v3(2 / sqrt(5.0), 0, 1 / sqrt(5.0)), NTOL);
    /* overlapping: the sphere centre 0.2 inside the cylinder's side */
    r = dist_ok(&cyl, xf(0, 0, 0), &s, xf(0.8, 0, 0));
    MK_ASSERT_NEAR(r.distance, -0.7, TOL);
    MK_ASSERT_V3_NEAR(r.normal, mk_v3(1, 0, 0), NTOL);
}
END_TEST

/* Rounded cores: the answer is the core distance minus both radii, in every
 * region (face, edge, corner), and never a margin approximation. */
START_TEST(rounded_shapes_are_exact)
{
    mk_shape a, b;
    mk_distance_result r;
    mk_shape_box(mk_v3(1, 1, 1), 0.2, &a);
    mk_shape_box(mk_v3(0.5, 0.5, 0.5), 0.1, &b);
    r = dist_ok(&a, xf(0, 0, 0), &b, xf(0, 0, 3)); /* face to face: 3 - 1 - 0.5 - 0.3 */
    MK_ASSERT_NEAR(r.distance, 1.2, TOL);
    MK_ASSERT_V3_NEAR(r.normal, mk_v3(0, 0, 1), TOL);
    r = dist_ok(&a, xf(0, 0, 0), &b, xf(3, 3.5, 4)); /* corner to corner: offset (1.5, 2, 2.5) */
    MK_ASSERT_NEAR(r.distance, sqrt(1.5 * 1.5 + 4 + 6.25) - 0.3, TOL);
    r = dist_ok(&a, xf(0, 0, 0), &b, xf(0, 0, 1.6)); /* cores apart by 0.1, shapes overlap by 0.2 */
    MK_ASSERT_NEAR(r.distance, -0.2, TOL);
    ck_assert_int_eq(r.method, MK_METHOD_SAT); /* face-face: SAT's bound is certified, no GJK */
    r = dist_ok(&a, xf(0, 0, 0), &b, xf(0, 0, 1.2)); /* cores overlap by 0.3: depth 0.6 */
    MK_ASSERT_NEAR(r.distance, -0.6, TOL);
    MK_ASSERT_V3_NEAR(r.normal, mk_v3(0, 0, 1), TOL);
    ck_assert_int_eq(r.method, MK_METHOD_SAT); /* overlapping box cores: SAT's 15 axes */
    {
        /* the same rounded cores as hulls go through EPA */
        static const mk_vec3 ca[8] = {{-1, -1, -1}, {1, -1, -1}, {-1, 1, -1}, {1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {-1, 1, 1}, {1, 1, 1}};
        mk_vec3 cb[8];
        mk_hull *hullA = NULL, *hullB = NULL;
        mk_shape ra, rb;
        int k;
        for (k = 0; k < 8; ++k) cb[k] = mk_v3_scale(ca[k], 0.5);
        MK_ASSERT_STATUS(mk_hull_create(ca, 8, NULL, &hullA), MK_OK);
        MK_ASSERT_STATUS(mk_hull_create(cb, 8, NULL, &hullB), MK_OK);
        mk_shape_hull(hullA, 0.2, &ra);
        mk_shape_hull(hullB, 0.1, &rb);
        r = dist_ok(&ra, xf(0, 0, 0), &rb, xf(0, 0, 1.6));
        MK_ASSERT_NEAR(r.distance, -0.2, TOL);
        ck_assert_int_eq(r.method, MK_METHOD_GJK);
        r = dist_ok(&ra, xf(0, 0, 0), &rb, xf(0, 0, 1.2));
        MK_ASSERT_NEAR(r.distance, -0.6, TOL);
        MK_ASSERT_V3_NEAR(r.normal, mk_v3(0, 0, 1), TOL);
        ck_assert_int_eq(r.method, MK_METHOD_EPA);
        mk_hull_destroy(hullA);
        mk_hull_destroy(hullB);
    }
}
END_TEST

/* Jolt #2103: a cylinder cast starting just touching a capsule reported
 * 7.25 m of penetration: GJK on the shrunk cores ended at a separation equal
 * to the sum of the convex radii, and the contact points taken from that
 * simplex were pushed apart by the full radii. Here the capsule's radius
 * (7.197 m) is 15x the cylinder's, the touching features are the cylinder's
 * flat side and the capsule's cylindrical part (parallel lines: a degenerate
 * GJK simplex), and the answer is analytic: rho - r_cyl - r_capsule. Jolt's
 * y-up poses map to our z axes by the rotation (x, y, z) -> (z, x, y). */
START_TEST(regression_capsule_touching_cylinder)
{
    mk_shape cap, cyl;
    double x = -7.63574218, y = -0.951660156, z = -2.09155273, rho = sqrt(x * x + y * y);
    double gap[3] = {0, 1e-6, -1e-6};
    int k, ov;
    mk_shape_capsule((mk_real)7.19732189, (mk_real)2.03114343, &cap);
    mk_shape_cylinder((mk_real)0.4975, (mk_real)0.3, 0, &cyl);
    for (k = 0; k < 3; ++k) {
        /* move the cylinder radially so the gap is gap[k] (k = 0: Jolt's pose) */
        double f = k == 0 ? 1 : ((double)cyl.u.cylinder.radius + (double)cap.radius + gap[k]) / rho;
        mk_transform xc = xf((mk_real)(x * f), (mk_real)(y * f), (mk_real)z);
        double rr = sqrt((double)xc.p.x * xc.p.x + (double)xc.p.y * xc.p.y);
        double want = rr - (double)cyl.u.cylinder.radius - (double)cap.radius;
        mk_distance_result r = dist_ok(&cap, xf(0, 0, 0), &cyl, xc);
        MK_ASSERT_NEAR(r.distance, want, 1e2 * TOL);
        MK_ASSERT_V3_NEAR(r.normal, mk_v3((mk_real)(xc.p.x / rr), (mk_real)(xc.p.y / rr), 0), NTOL);
#if !defined(MK_SINGLE)
        if (k > 0) {
            ck_assert(gap[k] > 0 ? r.distance > 0 : r.distance < 0);
            MK_ASSERT_STATUS(mk_overlap(&cap, xf(0, 0, 0), &cyl, xc, NULL, &ov), MK_OK);
            ck_assert_int_eq(ov, gap[k] < 0);
        }
#else
        (void)ov;
#endif
        r = dist_ok(&cyl, xc, &cap, xf(0, 0, 0));
        MK_ASSERT_NEAR(r.distance, want, 1e2 * TOL);
    }
}
END_TEST

/* A cache warm-started from the previous frame gives the same answer and
 * needs no more iterations; a cache holding garbage is ignored, not trusted. */
START_TEST(warm_start_cache)
{
    mk_shape a, b, c;
    mk_rng rng = {21};
    int i, cold_it = 0, warm_it = 0;
    mk_shape_box(mk_v3(1, 0.5, 0.25), 0, &a);
    mk_shape_box(mk_v3(0.3, 1, 0.7), 0.05, &b);
    mk_shape_cylinder(0.5, 1, 0, &c);
    for (i = 0; i < 100; ++i) {
        mk_gjk_cache cache;
        mk_transform xa = xfq(mk_rng_v3(&rng, -1, 1), mk_rng_quat(&rng));
        mk_transform xb = xfq(mk_rng_v3(&rng, -3, 3), mk_rng_quat(&rng));
        mk_quat dq = mk_quat_from_axis_angle(mk_rng_dir(&rng), MK_REAL(0.01));
        mk_distance_result r0, r1, cold;
        const mk_shape *sb = (i & 1) ? &b : &c;
        memset(&cache, 0, sizeof cache);
        MK_ASSERT_STATUS(mk_distance(&a, xa, sb, xb, &cache, &r0), MK_OK);
        /* next frame: a small motion */
        xb = xfq(mk_v3_add(xb.p, mk_v3(0.003, -0.002, 0.001)), mk_quat_normalize(mk_quat_mul(dq, xb.q)));
        MK_ASSERT_STATUS(mk_distance(&a, xa, sb, xb, &cache, &r1), MK_OK);
        MK_ASSERT_STATUS(mk_distance(&a, xa, sb, xb, NULL, &cold), MK_OK);
        MK_ASSERT_NEAR(r1.distance, cold.distance, sb == &b ? 1e2 * MK_REAL_EPSILON * 4 : 4 * TOL);
        warm_it += r1.iterations;
        cold_it += cold.iterations;
    }
    ck_assert_msg(warm_it <= cold_it, "warm %d > cold %d iterations", warm_it, cold_it);
    {
        mk_gjk_cache junk;
        mk_distance_result r, cold;
        memset(&junk, 0xff, sizeof junk); /* NaN direction, negative indices */
        MK_ASSERT_STATUS(mk_distance(&a, xf(0, 0, 0), &b, xf(0, 0, 3), &junk, &r), MK_OK);
        junk.count = 3;
        junk.ia[0] = 1000; /* out of range for a box */
        MK_ASSERT_STATUS(mk_distance(&a, xf(0, 0, 0), &b, xf(0, 0, 3), &junk, &r), MK_OK);
        MK_ASSERT_STATUS(mk_distance(&a, xf(0, 0, 0), &b, xf(0, 0, 3), NULL, &cold), MK_OK);
        MK_ASSERT_NEAR(r.distance, cold.distance, 0);
    }
}
END_TEST

/* The boolean query agrees with the sign of the distance away from zero. */
START_TEST(overlap_agrees_with_distance)
{
    mk_shape s[5];
    mk_rng rng = {33};
    int i, j, k;
    mk_shape_box(mk_v3(1, 0.5, 0.25), 0, &s[0]);
    mk_shape_cylinder(0.5, 1, 0.1, &s[1]);
    mk_shape_cone(0.7, 0.6, 0, &s[2]);
    mk_shape_capsule(0.3, 0.8, &s[3]);
    mk_shape_sphere(0.6, &s[4]);
    for (k = 0; k < 300; ++k) {
        mk_transform xa = xfq(mk_rng_v3(&rng, -1, 1), mk_rng_quat(&rng));
        mk_transform xb = xfq(mk_rng_v3(&rng, -2.5, 2.5), mk_rng_quat(&rng));
        mk_distance_result r;
        int ov;
        i = k % 5;
        j = (k / 5) % 5;
        MK_ASSERT_STATUS(mk_distance(&s[i], xa, &s[j], xb, NULL, &r), MK_OK);
        MK_ASSERT_STATUS(mk_overlap(&s[i], xa, &s[j], xb, NULL, &ov), MK_OK);
        if (fabs((double)r.distance) > 1e-6) ck_assert_int_eq(ov, r.distance < 0);
    }
}
END_TEST

/* The solver's own bookkeeping: bounds bracket the answer, and the state is
 * explicit (a smooth pair converges on the tolerance well under the cap). */
START_TEST(solver_bounds_and_state)
{
    mk_shape a, b;
    mk_gjk_result g;
    mk_pair p;
    mk_shape_cylinder(1, 1, 0, &a);
    mk_shape_cone(1, 1, 0, &b);
    p = mk_pair_make(&a, xf(0, 0, 0), &b, xfq(mk_v3(2.5, 0.3, 0.2), mk_quat_from_axis_angle(mk_v3(1, 1, 0), 1)));
    mk_gjk(&p, NULL, 0, 0, &g);
    ck_assert_int_eq(g.overlap, 0);
    ck_assert_int_eq(g.state, MK_SOLVE_CONVERGED);
    ck_assert(g.iterations < MK_GJK_MAX_ITERATIONS);
    ck_assert(g.lower <= g.upper);
    ck_assert(g.upper - g.lower <= MK_GJK_REL_TOL * g.upper + MK_GJK_ABS_TOL * g.scale);
    p = mk_pair_make(&a, xf(0, 0, 0), &b, xf(0.5, 0, 0));
    mk_gjk(&p, NULL, 0, 0, &g);
    ck_assert_int_eq(g.overlap, 1);
    ck_assert_int_eq(g.upper == 0, 1);
}
END_TEST

static Suite *gjk_suite(void)
{
    Suite *s = suite_create("gjk");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, cylinder_cone_against_sphere);
    tcase_add_test(tc, rounded_shapes_are_exact);
    tcase_add_test(tc, regression_capsule_touching_cylinder);
    tcase_add_test(tc, warm_start_cache);
    tcase_add_test(tc, overlap_agrees_with_distance);
    tcase_add_test(tc, solver_bounds_and_state);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return mk_test_run(gjk_suite()); }

/* test_toi.c: sweeps, swept bounds, time of impact, shape casts. */
#include <stdio.h>
#include <string.h>

#include "minko/distance.h"
#include "minko/toi.h"
#include "support/mk_test.h"

/* TOI_TOL: times and distances that should be exact (the issue asks 1e-9 in
 * double); in float the distance queries resolve ~1e2 eps of the scene size. */
#if defined(MK_SINGLE)
#  define POSE_TOL 2e-5
#  define TOI_TOL 5e-4
#else
#  define POSE_TOL 1e-12
#  define TOI_TOL 1e-9
#endif

/* A hull of 24 random points in an ellipsoid-ish cloud, off-centre. */
static mk_hull *random_hull(unsigned seed)
{
    mk_rng r;
    mk_vec3 p[24];
    mk_hull *h = NULL;
    int i;
    r.s = seed;
    for (i = 0; i < 24; ++i) p[i] = mk_v3_add(mk_v3_mul(mk_rng_dir(&r), mk_v3(0.6, 0.4, 0.3)), mk_v3(0.1, -0.05, 0.02));
    MK_ASSERT_STATUS(mk_hull_create(p, 24, NULL, &h), MK_OK);
    return h;
}

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
    mk_shape shapes[7];
    mk_hull *hull = random_hull(7);
    int i, k;
    mk_shape_sphere(0.5, &shapes[0]);
    mk_shape_box(mk_v3(1, 0.2, 0.4), 0.05, &shapes[1]);
    mk_shape_capsule(0.2, 1, &shapes[2]);
    mk_shape_cylinder(0.5, 0.3, 0, &shapes[3]);
    mk_shape_cone(0.4, 0.8, 0.1, &shapes[4]);
    mk_shape_box(mk_v3(2, 0.05, 0.05), 0, &shapes[5]);
    mk_shape_hull(hull, 0.02, &shapes[6]);
    for (i = 0; i < 140; ++i) {
        const mk_shape *s = &shapes[i % 7];
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
    mk_hull_destroy(hull);
}
END_TEST


/* ---- time of impact ---- */

static mk_sweep linear_sweep(mk_vec3 p0, mk_vec3 p1)
{
    mk_sweep sw;
    MK_ASSERT_STATUS(mk_sweep_from_transforms(mk_transform_make(p0, mk_quat_identity()), mk_transform_make(p1, mk_quat_identity()),
                                              mk_v3_zero(), &sw),
                     MK_OK);
    return sw;
}

static mk_toi_result toi(const mk_shape *a, const mk_sweep *sa, const mk_shape *b, const mk_sweep *sb, double target, double tol)
{
    mk_toi_result r;
    MK_ASSERT_STATUS(mk_toi(a, sa, b, sb, (mk_real)target, (mk_real)tol, &r), MK_OK);
    return r;
}

static double dist_at(const mk_shape *a, const mk_sweep *sa, const mk_shape *b, const mk_sweep *sb, double t)
{
    mk_distance_result d;
    MK_ASSERT_STATUS(mk_distance(a, pose_at(sa, t), b, pose_at(sb, t), NULL, &d), MK_OK);
    return (double)d.distance;
}

/* Brute force: the first of n samples at or below the target, refined by
 * bisection; -1 when no sample gets there. */
static double reference_toi(const mk_shape *a, const mk_sweep *sa, const mk_shape *b, const mk_sweep *sb, double target, int n)
{
    double lo = 0, hi = -1;
    int i;
    if (dist_at(a, sa, b, sb, 0) <= target) return 0;
    for (i = 1; i <= n; ++i)
        if (dist_at(a, sa, b, sb, (double)i / n) <= target) {
            lo = (double)(i - 1) / n;
            hi = (double)i / n;
            break;
        }
    if (hi < 0) return -1;
    for (i = 0; i < 60; ++i) {
        double m = 0.5 * (lo + hi);
        if (dist_at(a, sa, b, sb, m) <= target) hi = m;
        else lo = m;
    }
    return lo;
}

/* The contract, checked against brute force: a hit is never later than the
 * first sampled contact, and at the reported time the distance is within
 * [target - eps, target + tol]; SEPARATED only if no sample reaches target. */
static void check_against_reference(const mk_shape *a, const mk_sweep *sa, const mk_shape *b, const mk_sweep *sb, double target,
                                    double tol, int samples, const char *what)
{
    mk_toi_result r = toi(a, sa, b, sb, target, tol);
    double ref = reference_toi(a, sa, b, sb, target, samples);
    double eps = TOI_TOL;
    ck_assert_msg(r.state != MK_TOI_FAILED, "%s: failed after %d iterations", what, r.iterations);
    if (ref >= 0) {
        ck_assert_msg(r.state == MK_TOI_HIT || r.state == MK_TOI_OVERLAPPED, "%s: missed a contact at t = %.17g (state %d)", what, ref,
                      (int)r.state);
        ck_assert_msg((double)r.t <= ref + eps, "%s: hit at %.17g, after the contact at %.17g", what, (double)r.t, ref);
    }
    if (r.state == MK_TOI_HIT) {
        double d = dist_at(a, sa, b, sb, (double)r.t);
        /* Starting within target is a hit at 0 at whatever distance the shapes start. */
        ck_assert_msg(d <= target + tol + eps && (d >= target - eps || r.t == 0), "%s: distance %.17g at the hit, target %g", what, d,
                      target);
        MK_ASSERT_NEAR(r.distance, d, eps);
    }
    if (r.state == MK_TOI_SEPARATED) ck_assert_msg(ref < 0, "%s: separated, but brute force touches at %.17g", what, ref);
}

/* |p0 + t v| = R: the smaller root. */
static double sphere_root(mk_vec3 p0, mk_vec3 v, double R)
{
    double a = (double)mk_v3_len2(v), b = (double)mk_v3_dot(p0, v), c = (double)mk_v3_len2(p0) - R * R;
    double disc = b * b - a * c;
    return disc < 0 ? -1 : c / (-b + sqrt(disc));
}

START_TEST(sphere_sphere_linear_analytic)
{
    mk_rng r = {21};
    int i, hits = 0;
    for (i = 0; i < 300; ++i) {
        mk_shape a, b;
        mk_vec3 pa = mk_rng_v3(&r, -5, 5), pb = mk_rng_v3(&r, -5, 5);
        mk_vec3 qa = mk_rng_v3(&r, -5, 5), qb = mk_rng_v3(&r, -5, 5);
        mk_sweep sa = linear_sweep(pa, qa), sb = linear_sweep(pb, qb);
        double ra = mk_rng_range(&r, 0.1, 1.5), rb = mk_rng_range(&r, 0.1, 1.5), target = (i % 3) * 0.01;
        double t_ref = sphere_root(mk_v3_sub(pb, pa), mk_v3_sub(mk_v3_sub(qb, qa), mk_v3_sub(pb, pa)), ra + rb + target);
        mk_toi_result res;
        mk_shape_sphere((mk_real)ra, &a);
        mk_shape_sphere((mk_real)rb, &b);
        res = toi(&a, &sa, &b, &sb, target, 0);
        if (mk_v3_dist(pa, pb) < ra + rb) {
            ck_assert_int_eq(res.state, MK_TOI_OVERLAPPED);
        } else if (t_ref >= 0 && t_ref <= 1) {
            ck_assert_msg(res.state == MK_TOI_HIT, "case %d: state %d", i, (int)res.state);
            MK_ASSERT_NEAR(res.t, t_ref, TOI_TOL);
            MK_ASSERT_NEAR(res.distance, target, 10 * TOI_TOL);
            ++hits;
        } else {
            ck_assert_msg(res.state == MK_TOI_SEPARATED, "case %d: state %d, root %g", i, (int)res.state, t_ref);
        }
    }
    ck_assert(hits > 30);
}
END_TEST

START_TEST(sphere_plane_linear_analytic)
{
    mk_rng r = {22};
    mk_shape ground, ball;
    int i;
    mk_shape_plane(mk_v3(0, 0, 1), 0, &ground);
    for (i = 0; i < 200; ++i) {
        double rad = mk_rng_range(&r, 0.05, 1), z0 = mk_rng_range(&r, rad + 0.01, 5), z1 = mk_rng_range(&r, -5, 5);
        double target = (i % 2) * 0.005;
        mk_sweep sb = linear_sweep(mk_rng_v3(&r, -1, 1), mk_rng_v3(&r, -1, 1));
        mk_sweep sg = linear_sweep(mk_v3_zero(), mk_v3_zero());
        mk_toi_result res;
        sb.c0.z = (mk_real)z0;
        sb.c1.z = (mk_real)z1;
        mk_shape_sphere((mk_real)rad, &ball);
        res = toi(&ground, &sg, &ball, &sb, target, 0);
        if (z1 - rad > target) {
            ck_assert_int_eq(res.state, MK_TOI_SEPARATED);
        } else {
            double t_ref = (z0 - rad - target) / (z0 - z1);
            ck_assert_int_eq(res.state, MK_TOI_HIT);
            MK_ASSERT_NEAR(res.t, t_ref, TOI_TOL);
            MK_ASSERT_V3_NEAR(res.normal, mk_v3(0, 0, 1), 0);
            ck_assert(res.rate < 0);
        }
        /* The same with the plane as B. */
        res = toi(&ball, &sb, &ground, &sg, target, 0);
        if (z1 - rad <= target) MK_ASSERT_NEAR(res.t, (z0 - rad - target) / (z0 - z1), TOI_TOL);
    }
}
END_TEST

/* A 5 cm ball at 10 to 1000 m/s against a 10 cm wall, from 8 start offsets
 * across one 1/60 s step: whenever the step's motion crosses the wall, the
 * TOI stops the ball in front of it. */
START_TEST(bullet_never_tunnels)
{
    static const double speeds[5] = {10, 50, 100, 300, 1000};
    mk_shape ball, wall;
    mk_sweep sw = linear_sweep(mk_v3_zero(), mk_v3_zero());
    int i, k, hits = 0;
    mk_shape_sphere(0.05, &ball);
    mk_shape_box(mk_v3(0.05, 2, 2), 0, &wall);
    for (i = 0; i < 5; ++i) {
        double step = speeds[i] / 60;
        for (k = 0; k < 8; ++k) {
            /* Front face at x = -0.05; the ball starts between 0 and one step's travel in front of it. */
            double x0 = -0.05 - 0.05 - 0.001 - step * (k + 0.5) / 8;
            mk_sweep sb = linear_sweep(mk_v3((mk_real)x0, 0.3, -0.2), mk_v3((mk_real)(x0 + step), 0.3, -0.2));
            mk_toi_result res = toi(&wall, &sw, &ball, &sb, 0, 1e-6);
            double x_hit = x0 + step * (double)res.t;
            ck_assert_msg(res.state == MK_TOI_HIT, "%g m/s, offset %d: state %d", speeds[i], k, (int)res.state);
            ck_assert_msg(x_hit <= -0.1 + TOI_TOL && x_hit >= -0.1 - 2e-6 - 10 * TOI_TOL * speeds[i], "%g m/s, offset %d: ball centre at %.17g", speeds[i], k, x_hit);
            ++hits;
        }
    }
    ck_assert_int_eq(hits, 40);
}
END_TEST

START_TEST(toi_bad_input)
{
    mk_shape s, plane;
    mk_sweep good = linear_sweep(mk_v3_zero(), mk_v3(1, 0, 0)), bad;
    mk_toi_result r;
    mk_ray_hit h;
    mk_shape_sphere(1, &s);
    mk_shape_plane(mk_v3(0, 0, 1), 0, &plane);
    r.iterations = 77;
    MK_ASSERT_STATUS(mk_toi(NULL, &good, &s, &good, 0, 0, &r), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_toi(&s, &good, &s, NULL, 0, 0, &r), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_toi(&s, &good, &s, &good, 0, 0, NULL), MK_ERR_NULL);
    bad = good;
    bad.c1.x = (mk_real)NAN;
    MK_ASSERT_STATUS(mk_toi(&s, &bad, &s, &good, 0, 0, &r), MK_ERR_NOT_FINITE);
    bad = good;
    bad.q0 = mk_quat_make(0.1, 0, 0, 0.8);
    MK_ASSERT_STATUS(mk_toi(&s, &good, &s, &bad, 0, 0, &r), MK_ERR_BAD_ROTATION);
    bad = good;
    bad.rotation = mk_v3(0, 0, 3.5);
    MK_ASSERT_STATUS(mk_toi(&s, &bad, &s, &good, 0, 0, &r), MK_ERR_BAD_ARGUMENT);
    MK_ASSERT_STATUS(mk_toi(&s, &good, &s, &good, -1, 0, &r), MK_ERR_BAD_ARGUMENT);
    MK_ASSERT_STATUS(mk_toi(&s, &good, &s, &good, 0, (mk_real)INFINITY, &r), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_toi(&plane, &good, &plane, &good, 0, 0, &r), MK_ERR_UNSUPPORTED);
    bad = good;
    bad.rotation = mk_v3(0, 0.5, 0);
    MK_ASSERT_STATUS(mk_toi(&plane, &bad, &s, &good, 0, 0, &r), MK_ERR_UNSUPPORTED);
    ck_assert_int_eq(r.iterations, 77);
    MK_ASSERT_STATUS(mk_shape_cast(&s, mk_transform_identity(), mk_v3((mk_real)NAN, 0, 0), &s, mk_transform_identity(), &h), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_shape_cast(&s, mk_transform_make(mk_v3_zero(), mk_quat_make(0, 0, 0, 3)), mk_v3(1, 0, 0), &s,
                                   mk_transform_identity(), &h),
                     MK_ERR_BAD_ROTATION);
}
END_TEST

static mk_sweep spin_sweep(mk_vec3 p0, mk_vec3 p1, mk_quat q0, mk_vec3 rotation)
{
    mk_sweep sw;
    MK_ASSERT_STATUS(mk_sweep_from_velocity(mk_transform_make(p0, q0), mk_v3_sub(p1, p0), rotation, 1, mk_v3_zero(), &sw), MK_OK);
    return sw;
}

/* A 2 m rod, 2 cm thick, spinning at up to pi per step about its middle:
 * past the edge of a plate (no contact; a swept-sphere test would say yes),
 * and into it (the tip arrives long before the centre would). */
START_TEST(spinning_rod_past_and_into_plate)
{
    mk_shape rod, plate, capsule;
    mk_sweep still = linear_sweep(mk_v3_zero(), mk_v3_zero());
    int i;
    mk_shape_box(mk_v3(1, 0.01, 0.01), 0, &rod);
    mk_shape_capsule(0.01, 1, &capsule);
    mk_shape_box(mk_v3(0.5, 0.5, 0.01), 0, &plate);
    for (i = 0; i < 12; ++i) {
        double spin = 0.5 + 0.2 * i; /* rad per step, up to 2.7 */
        char what[64];
        /* Past: the centre stays 1.2 m from the plate's edge, the tip reaches 1 m. */
        mk_sweep past = spin_sweep(mk_v3(1.7, 0, 0.5), mk_v3(1.7, 0, -0.5), mk_quat_identity(), mk_v3(0, 0, (mk_real)spin));
        /* Into: the rod sweeps down in the xz-plane onto the plate, tip first. */
        mk_sweep into = spin_sweep(mk_v3(0, 0.1 * (i % 3), 1.3), mk_v3(0.1, 0, 0.9), mk_quat_from_axis_angle(mk_v3(0, 1, 0), -0.9),
                                   mk_v3(0, (mk_real)spin, 0));
        sprintf(what, "rod past, spin %g", spin);
        check_against_reference(&rod, &past, &plate, &still, 0.001, 1e-6, 2000, what);
        ck_assert_int_eq(toi(&rod, &past, &plate, &still, 0.001, 1e-6).state, MK_TOI_SEPARATED);
        sprintf(what, "rod into, spin %g", spin);
        check_against_reference(&rod, &into, &plate, &still, 0.001, 1e-6, 2000, what);
        sprintf(what, "capsule into, spin %g", spin);
        check_against_reference(&capsule, &into, &plate, &still, 0, 1e-6, 2000, what);
    }
}
END_TEST

/* A box tipping over onto the ground: a corner lands first. Against a plane
 * (the plane path) and against a thick ground box (the GJK path). */
START_TEST(box_rotating_onto_ground)
{
    mk_shape box, ground_plane, ground_box;
    mk_sweep still = linear_sweep(mk_v3_zero(), mk_v3_zero());
    int i;
    mk_shape_box(mk_v3(0.5, 0.3, 0.2), 0.02, &box);
    mk_shape_plane(mk_v3(0, 0, 1), 0, &ground_plane);
    mk_shape_box(mk_v3(5, 5, 1), 0, &ground_box);
    for (i = 0; i < 16; ++i) {
        double fall = 0.1 + 0.05 * i, turn = 0.18 * (i + 1);
        mk_sweep sw = spin_sweep(mk_v3(0.2, 0.1, 0.7), mk_v3(0.2, 0.1, (mk_real)(0.7 - fall)),
                                 mk_quat_from_axis_angle(mk_v3(1, 1, 0), 0.3), mk_v3((mk_real)turn, 0, 0.3));
        mk_sweep below = linear_sweep(mk_v3(0, 0, -1), mk_v3(0, 0, -1));
        char what[64];
        sprintf(what, "box onto plane, case %d", i);
        check_against_reference(&ground_plane, &still, &box, &sw, 0, 1e-7, 2000, what);
        sprintf(what, "box onto ground box, case %d", i);
        check_against_reference(&ground_box, &below, &box, &sw, 0.002, 1e-7, 2000, what);
    }
}
END_TEST

/* Grazing: two spheres whose closest approach is exactly target + g. */
START_TEST(glancing_contacts)
{
    mk_shape a, b, box;
    mk_sweep sa = linear_sweep(mk_v3_zero(), mk_v3_zero());
    mk_toi_result r;
    double gaps[6] = {1e-3, 1e-6, 0, -1e-6, -1e-3, -0.05};
    int i;
    mk_shape_sphere(1, &a);
    mk_shape_sphere(0.5, &b);
    mk_shape_box(mk_v3(1, 1, 1), 0, &box);
    for (i = 0; i < 6; ++i) {
        double g = gaps[i], y = 1.5 + 0.01 + g;
        mk_sweep sb = linear_sweep(mk_v3(-3, (mk_real)y, 0), mk_v3(3, (mk_real)y, 0));
        mk_sweep sc = spin_sweep(mk_v3(-3, (mk_real)(y + 0.2), 0), mk_v3(3, (mk_real)(y + 0.2), 0), mk_quat_identity(), mk_v3(0, 0, 1));
        char what[64];
        r = toi(&a, &sa, &b, &sb, 0.01, 1e-9);
        if (g > TOI_TOL) ck_assert_msg(r.state == MK_TOI_SEPARATED, "gap %g: state %d", g, (int)r.state);
        else if (g <= 0) ck_assert_msg(r.state == MK_TOI_HIT, "gap %g: state %d", g, (int)r.state);
        sprintf(what, "grazing spheres, gap %g", g);
        check_against_reference(&a, &sa, &b, &sb, 0.01, 1e-9, 2000, what);
        sprintf(what, "grazing box over sphere, gap %g", g);
        check_against_reference(&b, &sb, &box, &sc, 0.01, 1e-7, 2000, what);
    }
}
END_TEST

START_TEST(overlapping_and_touching_at_start)
{
    mk_shape a, b;
    mk_sweep sa = linear_sweep(mk_v3_zero(), mk_v3(1, 0, 0)), sb = linear_sweep(mk_v3(1.4, 0, 0), mk_v3(3, 0, 0));
    mk_toi_result r;
    mk_shape_sphere(1, &a);
    mk_shape_box(mk_v3(0.5, 0.5, 0.5), 0, &b);
    r = toi(&a, &sa, &b, &sb, 0, 0);
    ck_assert_int_eq(r.state, MK_TOI_OVERLAPPED);
    MK_ASSERT_NEAR(r.t, 0, 0);
    ck_assert(r.distance < 0);
    sb = linear_sweep(mk_v3(1.505, 0, 0), mk_v3(3, 0, 0)); /* 5 mm apart, target 1 cm: already in range */
    r = toi(&a, &sa, &b, &sb, 0.01, 0);
    ck_assert_int_eq(r.state, MK_TOI_HIT);
    MK_ASSERT_NEAR(r.t, 0, 0);
    MK_ASSERT_NEAR(r.distance, 0.005, 10 * TOI_TOL);
    ck_assert(r.rate > 0); /* B runs away faster than A follows */
}
END_TEST

/* Random convex pairs, random motions with turns up to pi, against brute force. */
START_TEST(random_motions_against_brute_force)
{
    mk_rng r = {23};
    mk_shape shapes[8];
    mk_hull *hull = random_hull(8);
    int i;
    mk_shape_sphere(0.4, &shapes[0]);
    mk_shape_box(mk_v3(0.6, 0.3, 0.2), 0, &shapes[1]);
    mk_shape_box(mk_v3(0.4, 0.4, 0.1), 0.05, &shapes[2]);
    mk_shape_capsule(0.15, 0.5, &shapes[3]);
    mk_shape_cylinder(0.3, 0.4, 0, &shapes[4]);
    mk_shape_cone(0.35, 0.45, 0.02, &shapes[5]);
    mk_shape_box(mk_v3(1.5, 0.05, 0.05), 0, &shapes[6]);
    mk_shape_hull(hull, 0, &shapes[7]);
    for (i = 0; i < 64; ++i) {
        const mk_shape *a = &shapes[i % 8], *b = &shapes[(i * 3 + 1) % 8];
        mk_vec3 ca = mk_rng_v3(&r, -2, 2), cb = mk_rng_v3(&r, -2, 2);
        mk_sweep sa = spin_sweep(ca, mk_v3_mad(cb, (mk_real)0.3, mk_rng_v3(&r, -1, 1)), mk_rng_quat(&r),
                                 mk_v3_scale(mk_rng_dir(&r), (mk_real)mk_rng_range(&r, 0, 3.1)));
        mk_sweep sb = spin_sweep(cb, mk_v3_mad(ca, (mk_real)0.3, mk_rng_v3(&r, -1, 1)), mk_rng_quat(&r),
                                 mk_v3_scale(mk_rng_dir(&r), (mk_real)mk_rng_range(&r, 0, 3.1)));
        char what[96];
        sprintf(what, "random %d: %s / %s", i, mk_shape_type_name(a->type), mk_shape_type_name(b->type));
        check_against_reference(a, &sa, b, &sb, 0.005, 1e-7, 1000, what);
    }
    mk_hull_destroy(hull);
}
END_TEST

START_TEST(shape_cast_analytic)
{
    mk_shape ball, box, cap;
    mk_ray_hit h;
    mk_transform at = mk_transform_make(mk_v3(5, 0.3, -0.2), mk_quat_identity());
    mk_shape_sphere(0.5, &ball);
    mk_shape_box(mk_v3(1, 2, 3), 0, &box);
    mk_shape_capsule(0.25, 1, &cap);
    /* A ball cast along +x onto the box face x = 4. */
    MK_ASSERT_STATUS(mk_shape_cast(&ball, mk_transform_make(mk_v3(0, 0.5, 0.5), mk_quat_identity()), mk_v3(10, 0, 0), &box, at, &h), MK_OK);
    ck_assert(h.hit);
    MK_ASSERT_NEAR(h.fraction, 0.35, TOI_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(-1, 0, 0), TOI_TOL);
    MK_ASSERT_NEAR(h.point.x, 4, 10 * TOI_TOL);
    /* A box cast onto a ball: the box's corner region. */
    MK_ASSERT_STATUS(mk_shape_cast(&box, mk_transform_identity(), mk_v3(0, 0, 10), &ball, mk_transform_make(mk_v3(0, 0, 5), mk_quat_identity()), &h),
                     MK_OK);
    MK_ASSERT_NEAR(h.fraction, (5 - 3.5) / 10, TOI_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(0, 0, -1), TOI_TOL);
    /* A lying capsule dropped onto a rotated box edge. */
    MK_ASSERT_STATUS(mk_shape_cast(&cap, mk_transform_make(mk_v3(0, 0, 5), mk_quat_from_axis_angle(mk_v3(0, 1, 0), 1.5707963267948966)),
                                   mk_v3(0, 0, -10), &box, mk_transform_make(mk_v3_zero(), mk_quat_from_axis_angle(mk_v3(1, 0, 0), 0.7853981633974483)), &h),
                     MK_OK);
    /* After a 45-degree turn about x the face y = 2 faces (0, 1, 1) / sqrt 2: the capsule's axis stops 0.25 from it. */
    MK_ASSERT_NEAR(h.fraction, (5 - 2.25 * sqrt(2.0)) / 10, TOI_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(0, 1 / sqrt(2.0), 1 / sqrt(2.0)), 10 * TOI_TOL);
    /* Misses, and a start in contact. */
    MK_ASSERT_STATUS(mk_shape_cast(&ball, mk_transform_make(mk_v3(0, 5, 0), mk_quat_identity()), mk_v3(10, 0, 0), &box, at, &h), MK_OK);
    ck_assert(!h.hit);
    MK_ASSERT_V3_NEAR(h.point, mk_v3(10, 5, 0), 0);
    MK_ASSERT_STATUS(mk_shape_cast(&ball, mk_transform_make(mk_v3(4.2, 0, 0), mk_quat_identity()), mk_v3(10, 0, 0), &box, at, &h), MK_OK);
    ck_assert(h.hit && h.fraction == 0);
}
END_TEST

START_TEST(sweep_advance_restarts)
{
    mk_sweep sw, rest;
    int k;
    MK_ASSERT_STATUS(mk_sweep_from_velocity(mk_transform_make(mk_v3(1, 2, 3), mk_quat_from_axis_angle(mk_v3(1, 0, 1), 0.3)), mk_v3(3, -1, 2),
                                            mk_v3(0.5, 1.5, -1), 1, mk_v3(0.1, 0.2, 0), &sw),
                     MK_OK);
    rest = sw;
    MK_ASSERT_STATUS(mk_sweep_advance(&rest, (mk_real)0.4), MK_OK);
    for (k = 0; k <= 10; ++k) assert_same_pose(pose_at(&rest, k / 10.0), pose_at(&sw, 0.4 + 0.6 * k / 10.0), 100 * POSE_TOL);
    MK_ASSERT_STATUS(mk_sweep_advance(&rest, (mk_real)1.2), MK_ERR_BAD_ARGUMENT);
    MK_ASSERT_STATUS(mk_sweep_advance(NULL, 0), MK_ERR_NULL);
}
END_TEST

START_TEST(earliest_over_pairs)
{
    mk_shape ball, wall;
    mk_toi_body bodies[4];
    mk_toi_pair pairs[4] = {{1, 0}, {2, 0}, {0, 3}, {3, 2}};
    mk_toi_event ev;
    mk_shape_sphere(0.1, &ball);
    mk_shape_box(mk_v3(0.05, 5, 5), 0, &wall);
    bodies[0].shape = &wall;
    bodies[0].sweep = linear_sweep(mk_v3_zero(), mk_v3_zero());
    bodies[1].shape = &ball; /* reaches the wall at t = 0.5 */
    bodies[1].sweep = linear_sweep(mk_v3(-1.15, 0, 0), mk_v3(0.85, 0, 0));
    bodies[2].shape = &ball; /* at t = 0.25 */
    bodies[2].sweep = linear_sweep(mk_v3(-0.65, 1, 0), mk_v3(1.35, 1, 0));
    bodies[3].shape = &ball; /* inside the wall from the start */
    bodies[3].sweep = linear_sweep(mk_v3(0, -1, 0), mk_v3(1, -1, 0));
    MK_ASSERT_STATUS(mk_toi_earliest(bodies, 4, pairs, 4, 0, 1e-9, &ev), MK_OK);
    ck_assert_int_eq(ev.pair, 1);
    MK_ASSERT_NEAR(ev.result.t, 0.25, TOI_TOL);
    ck_assert_int_eq(ev.overlapped, 1);
    MK_ASSERT_STATUS(mk_toi_earliest(bodies, 4, pairs, 1, 0, 1e-9, &ev), MK_OK);
    MK_ASSERT_NEAR(ev.result.t, 0.5, TOI_TOL);
    MK_ASSERT_STATUS(mk_toi_earliest(bodies, 4, pairs, 0, 0, 1e-9, &ev), MK_OK);
    ck_assert_int_eq(ev.pair, -1);
    pairs[3].b = 3;
    MK_ASSERT_STATUS(mk_toi_earliest(bodies, 4, pairs, 4, 0, 1e-9, &ev), MK_ERR_BAD_ARGUMENT);
    pairs[3].b = 4;
    MK_ASSERT_STATUS(mk_toi_earliest(bodies, 4, pairs, 4, 0, 1e-9, &ev), MK_ERR_BAD_ARGUMENT);
    MK_ASSERT_STATUS(mk_toi_earliest(NULL, 4, pairs, 4, 0, 1e-9, &ev), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_toi_earliest(bodies, -1, pairs, 0, 0, 1e-9, &ev), MK_ERR_BAD_SIZE);
}
END_TEST

/* Seed 000's adaptive step: a ball crossing a 2 m gap between two walls ten
 * times over in one step bounces off each wall in turn, never through. */
static int reflect_ball(void *user, mk_toi_body *bodies, int body_count, int pair, const mk_toi_result *hit, mk_real time)
{
    mk_sweep *sw = &bodies[0].sweep;
    mk_vec3 d = mk_v3_sub(sw->c1, sw->c0);
    double *last = (double *)user;
    (void)body_count;
    (void)pair;
    ck_assert_msg((double)time > *last, "time goes forward");
    *last = (double)time;
    sw->c1 = mk_v3_add(sw->c0, mk_v3_mad(d, -2 * mk_v3_dot(d, hit->normal), hit->normal));
    return 0;
}

START_TEST(substep_bouncing_ball)
{
    mk_shape ball, wall;
    mk_toi_body bodies[3];
    mk_toi_pair pairs[2] = {{0, 1}, {0, 2}};
    mk_toi_step_stats stats;
    mk_transform end;
    double last = 0;
    mk_shape_sphere(0.1, &ball);
    mk_shape_box(mk_v3(0.5, 5, 5), 0, &wall);
    bodies[0].shape = &ball;
    bodies[0].sweep = linear_sweep(mk_v3(0, 0, 0), mk_v3(10, 0, 0));
    bodies[1].shape = &wall;
    bodies[1].sweep = linear_sweep(mk_v3(1.5, 0, 0), mk_v3(1.5, 0, 0));
    bodies[2].shape = &wall;
    bodies[2].sweep = linear_sweep(mk_v3(-1.5, 0, 0), mk_v3(-1.5, 0, 0));
    MK_ASSERT_STATUS(mk_toi_substep(bodies, 3, pairs, 2, 0, 1e-9, 20, reflect_ball, &last, &stats), MK_OK);
    /* 0.9 to the first wall, then 1.8 per crossing: six bounces, 0.1 to go after the last. */
    ck_assert_int_eq(stats.hits, 6);
    ck_assert_int_eq(stats.failed, 0);
    MK_ASSERT_NEAR(stats.time, 1, 0);
    end = pose_at(&bodies[0].sweep, 1);
    MK_ASSERT_NEAR(end.p.x, -0.8, 1e3 * TOI_TOL);
    /* With too few rounds the loop stops part-way and says so. */
    bodies[0].sweep = linear_sweep(mk_v3(0, 0, 0), mk_v3(10, 0, 0));
    last = 0;
    MK_ASSERT_STATUS(mk_toi_substep(bodies, 3, pairs, 2, 0, 1e-9, 3, reflect_ball, &last, &stats), MK_OK);
    ck_assert_int_eq(stats.hits, 3);
    MK_ASSERT_NEAR(stats.time, (0.9 + 3.6) / 10, 1e3 * TOI_TOL);
    MK_ASSERT_NEAR(pose_at(&bodies[0].sweep, 0).p.x, 0.9, 1e3 * TOI_TOL);
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
    tc = tcase_create("toi");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, sphere_sphere_linear_analytic);
    tcase_add_test(tc, sphere_plane_linear_analytic);
    tcase_add_test(tc, bullet_never_tunnels);
    tcase_add_test(tc, toi_bad_input);
    tcase_add_test(tc, spinning_rod_past_and_into_plate);
    tcase_add_test(tc, box_rotating_onto_ground);
    tcase_add_test(tc, glancing_contacts);
    tcase_add_test(tc, overlapping_and_touching_at_start);
    tcase_add_test(tc, random_motions_against_brute_force);
    tcase_add_test(tc, shape_cast_analytic);
    tcase_add_test(tc, sweep_advance_restarts);
    tcase_add_test(tc, earliest_over_pairs);
    tcase_add_test(tc, substep_bouncing_ball);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return mk_test_run(toi_suite()); }

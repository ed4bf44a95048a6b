/* test_raycast.c: ray casts against analytic answers, support-plane
 * certificates and a brute-force march + bisection oracle. */
#include <string.h>

#include "minko/raycast.h"
#include "support/mk_test.h"

#if defined(MK_SINGLE)
#  define RAY_TOL 2e-5
#else
#  define RAY_TOL 1e-12
#endif

/* An irregular octahedron: 6 vertices, 8 triangles. */
static mk_hull *make_octahedron(void)
{
    mk_vec3 v[6];
    mk_hull *h = NULL;
    v[0] = mk_v3(1.2, 0.1, 0);
    v[1] = mk_v3(-0.9, -0.1, 0.05);
    v[2] = mk_v3(0.05, 0.8, -0.1);
    v[3] = mk_v3(0, -1.1, 0);
    v[4] = mk_v3(0.1, 0, 1.3);
    v[5] = mk_v3(-0.1, 0.05, -0.7);
    MK_ASSERT_STATUS(mk_hull_create(v, 6, NULL, &h), MK_OK);
    ck_assert_int_eq(h->face_count, 8);
    return h;
}

/* ---- the oracle: inside tests written from each solid's definition ---- */
static double seg_dist(mk_vec3 a, mk_vec3 b, mk_vec3 p)
{
    mk_vec3 e = mk_v3_sub(b, a);
    double u = (double)mk_v3_dot(mk_v3_sub(p, a), e) / (double)mk_v3_len2(e);
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    return (double)mk_v3_dist(p, mk_v3_mad(a, (mk_real)u, e));
}

static double hull_core_dist(const mk_hull *h, mk_vec3 p)
{
    double best = 1e300;
    int f, inside = 1;
    for (f = 0; f < h->face_count; ++f) {
        mk_vec3 n = h->planes[f].normal;
        double s = (double)mk_v3_dot(n, p) - (double)h->planes[f].offset;
        int e0 = h->face_edge[f], e = e0, in_poly = 1;
        if (s > 0) inside = 0;
        do {
            mk_vec3 a = h->vertices[h->edges[e].origin], b = h->vertices[h->edges[h->edges[e].next].origin];
            double d = seg_dist(a, b, p);
            if (d < best) best = d;
            if (mk_v3_dot(mk_v3_cross(mk_v3_sub(b, a), mk_v3_sub(p, a)), n) < 0) in_poly = 0;
            e = h->edges[e].next;
        } while (e != e0);
        if (in_poly && s >= 0 && s < best) best = s;
    }
    return inside ? 0 : best;
}

/* Distance from p (local frame) to the core, 0 inside. */
static double core_dist(const mk_shape *s, mk_vec3 p)
{
    switch (s->type) {
    case MK_SHAPE_SPHERE: return (double)mk_v3_len(p);
    case MK_SHAPE_BOX: {
        double qx = fabs((double)p.x) - (double)s->u.half_extents.x, qy = fabs((double)p.y) - (double)s->u.half_extents.y;
        double qz = fabs((double)p.z) - (double)s->u.half_extents.z;
        qx = qx > 0 ? qx : 0;
        qy = qy > 0 ? qy : 0;
        qz = qz > 0 ? qz : 0;
        return sqrt(qx * qx + qy * qy + qz * qz);
    }
    case MK_SHAPE_CAPSULE:
        return seg_dist(mk_v3(0, 0, -s->u.capsule.half_height), mk_v3(0, 0, s->u.capsule.half_height), p);
    case MK_SHAPE_CYLINDER: {
        double dr = sqrt((double)(p.x * p.x + p.y * p.y)) - (double)s->u.cylinder.radius;
        double dz = fabs((double)p.z) - (double)s->u.cylinder.half_height;
        dr = dr > 0 ? dr : 0;
        dz = dz > 0 ? dz : 0;
        return sqrt(dr * dr + dz * dz);
    }
    case MK_SHAPE_CONE: {
        double R = (double)s->u.cone.radius, h = (double)s->u.cone.half_height;
        double rho = sqrt((double)(p.x * p.x + p.y * p.y)), z = (double)p.z;
        mk_vec3 q = mk_v3((mk_real)rho, (mk_real)z, 0);
        double d1, d2;
        if (z >= -h && rho / R + (z + h) / (2 * h) <= 1) return 0;
        d1 = seg_dist(mk_v3(0, (mk_real)-h, 0), mk_v3((mk_real)R, (mk_real)-h, 0), q);
        d2 = seg_dist(mk_v3((mk_real)R, (mk_real)-h, 0), mk_v3(0, (mk_real)h, 0), q);
        return d1 < d2 ? d1 : d2;
    }
    case MK_SHAPE_HULL: return hull_core_dist(s->u.hull, p);
    default: return 0;
    }
}

static int oracle_inside(const mk_shape *s, mk_transform xf, mk_vec3 w)
{
    mk_vec3 p = mk_transform_inv_point(xf, w);
    if (s->type == MK_SHAPE_PLANE) return mk_v3_dot(s->u.plane.normal, p) <= s->u.plane.offset;
    return core_dist(s, p) <= (double)s->radius;
}

/* First fraction at which the segment is inside: march, then bisect. -1 if no sample is inside. */
static double oracle_ray(const mk_shape *s, mk_transform xf, mk_vec3 o, mk_vec3 d, int steps)
{
    double lo = 0, hi = -1;
    int i;
    if (oracle_inside(s, xf, o)) return 0;
    for (i = 1; i <= steps; ++i) {
        double t = (double)i / steps;
        if (oracle_inside(s, xf, mk_v3_mad(o, (mk_real)t, d))) {
            hi = t;
            lo = (double)(i - 1) / steps;
            break;
        }
    }
    if (hi < 0) return -1;
    for (i = 0; i < 80; ++i) {
        double m = 0.5 * (lo + hi);
        if (oracle_inside(s, xf, mk_v3_mad(o, (mk_real)m, d))) hi = m;
        else lo = m;
    }
    return hi;
}

/* Certificate for a hit at t > 0: the point lies on the supporting plane of
 * the solid with the reported normal, and the ray enters against the normal
 * (so every earlier point is strictly outside that plane). */
static void check_certificate(const mk_shape *s, mk_transform xf, mk_vec3 d, const mk_ray_hit *h, double tol)
{
    mk_vec3 nl = mk_quat_inv_rotate(xf.q, h->normal), ql = mk_transform_inv_point(xf, h->point);
    double support = (double)mk_v3_dot(nl, mk_shape_support(s, nl));
    MK_ASSERT_NEAR(mk_v3_len(h->normal), 1, 1e3 * MK_REAL_EPSILON);
    ck_assert_msg(mk_v3_dot(h->normal, d) <= tol * (double)mk_v3_len(d), "ray leaves through its hit normal");
    MK_ASSERT_NEAR(mk_v3_dot(nl, ql), support, tol);
}

static mk_ray_hit cast(const mk_shape *s, mk_transform xf, mk_vec3 o, mk_vec3 d)
{
    mk_ray_hit h;
    MK_ASSERT_STATUS(mk_raycast(s, xf, o, d, &h), MK_OK);
    return h;
}

START_TEST(sphere_analytic)
{
    mk_shape s;
    mk_transform xf = mk_transform_make(mk_v3(10, 0, 0), mk_quat_from_axis_angle(mk_v3(1, 2, 3), 0.7));
    mk_ray_hit h;
    double far = sizeof(mk_real) == 4 ? 1e3 : 1e6;
    mk_shape_sphere(2, &s);
    h = cast(&s, xf, mk_v3(0, 1, 0), mk_v3(20, 0, 0));
    ck_assert(h.hit);
    MK_ASSERT_NEAR(h.fraction, (10 - sqrt(3.0)) / 20, RAY_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(-sqrt(3.0) / 2, 0.5, 0), RAY_TOL * 10);
    MK_ASSERT_V3_NEAR(h.point, mk_v3(10 - sqrt(3.0), 1, 0), RAY_TOL * 20);
    /* Far from the origin: the answer is relative to the ray, not to the coordinates. */
    xf.p = mk_v3((mk_real)far, (mk_real)far, 0);
    h = cast(&s, xf, mk_v3((mk_real)(far - 10), (mk_real)far, 0), mk_v3(20, 0, 0));
    MK_ASSERT_NEAR(h.fraction, 8.0 / 20, RAY_TOL * far);
    /* Misses: pointing away, passing beside, too short. */
    xf.p = mk_v3(10, 0, 0);
    ck_assert(!cast(&s, xf, mk_v3(0, 0, 0), mk_v3(-20, 0, 0)).hit);
    ck_assert(!cast(&s, xf, mk_v3(0, 2.001, 0), mk_v3(20, 0, 0)).hit);
    ck_assert(!cast(&s, xf, mk_v3(0, 0, 0), mk_v3(7.99, 0, 0)).hit);
    ck_assert(cast(&s, xf, mk_v3(0, 0, 0), mk_v3(8.01, 0, 0)).hit);
}
END_TEST

START_TEST(box_analytic)
{
    mk_shape s;
    mk_transform id = mk_transform_identity();
    mk_ray_hit h;
    mk_shape_box(mk_v3(1, 2, 3), 0, &s);
    h = cast(&s, id, mk_v3(-5, 0.5, 0.5), mk_v3(10, 0, 0));
    ck_assert(h.hit);
    MK_ASSERT_NEAR(h.fraction, 0.4, RAY_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(-1, 0, 0), 0);
    h = cast(&s, id, mk_v3(0.5, 0.5, 10), mk_v3(0, 0, -10));
    MK_ASSERT_NEAR(h.fraction, 0.7, RAY_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(0, 0, 1), 0);
    /* Rounded box: a face, an edge (a cylinder of radius 0.5 about it) and a corner (a ball). */
    mk_shape_box(mk_v3(1, 1, 1), 0.5, &s);
    h = cast(&s, id, mk_v3(0.2, 0.1, 5), mk_v3(0, 0, -5));
    MK_ASSERT_NEAR(h.fraction, (5 - 1.5) / 5, RAY_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(0, 0, 1), RAY_TOL);
    h = cast(&s, id, mk_v3(1.3, 0, 5), mk_v3(0, 0, -5));
    MK_ASSERT_NEAR(h.fraction, (5 - 1.4) / 5, RAY_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(0.6, 0, 0.8), 10 * RAY_TOL);
    h = cast(&s, id, mk_v3(1.3, 1.3, 5), mk_v3(0, 0, -5));
    MK_ASSERT_NEAR(h.fraction, (4 - sqrt(0.07)) / 5, RAY_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(0.6, 0.6, 2 * sqrt(0.07)), 10 * RAY_TOL);
    ck_assert(!cast(&s, id, mk_v3(1.36, 1.36, 5), mk_v3(0, 0, -5)).hit); /* outside the corner ball */
}
END_TEST

START_TEST(capsule_cylinder_cone_analytic)
{
    mk_shape s;
    mk_transform id = mk_transform_identity();
    mk_ray_hit h;
    mk_shape_capsule(0.5, 1, &s);
    h = cast(&s, id, mk_v3(-4, 0, 0.7), mk_v3(8, 0, 0)); /* side */
    MK_ASSERT_NEAR(h.fraction, 3.5 / 8, RAY_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(-1, 0, 0), RAY_TOL);
    h = cast(&s, id, mk_v3(0.3, 0, 4), mk_v3(0, 0, -8)); /* cap ball */
    MK_ASSERT_NEAR(h.fraction, (3 - 0.4) / 8, RAY_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(0.6, 0, 0.8), 10 * RAY_TOL);

    mk_shape_cylinder(1, 1, 0, &s);
    h = cast(&s, id, mk_v3(0.5, 0.2, 3), mk_v3(0, 0, -6)); /* flat cap */
    MK_ASSERT_NEAR(h.fraction, 2.0 / 6, RAY_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(0, 0, 1), RAY_TOL);
    h = cast(&s, id, mk_v3(-3, 0.6, 0.2), mk_v3(6, 0, 0)); /* side */
    MK_ASSERT_NEAR(h.fraction, (3 - 0.8) / 6, RAY_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(-0.8, 0.6, 0), 10 * RAY_TOL);
    mk_shape_cylinder(1, 1, 0.25, &s);
    h = cast(&s, id, mk_v3(1.1, 0, 3), mk_v3(0, 0, -6)); /* the rounded rim: a torus */
    MK_ASSERT_NEAR(h.fraction, (2 - sqrt(0.0525)) / 6, RAY_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(0.4, 0, 4 * sqrt(0.0525)), 10 * RAY_TOL);

    mk_shape_cone(1, 1, 0, &s);
    h = cast(&s, id, mk_v3(5, 0, 0), mk_v3(-10, 0, 0)); /* slant, at z = 0 the radius is 0.5 */
    MK_ASSERT_NEAR(h.fraction, 4.5 / 10, RAY_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(2 / sqrt(5.0), 0, 1 / sqrt(5.0)), 10 * RAY_TOL);
    h = cast(&s, id, mk_v3(0.3, 0.1, -4), mk_v3(0, 0, 8)); /* base */
    MK_ASSERT_NEAR(h.fraction, 3.0 / 8, RAY_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(0, 0, -1), RAY_TOL);
    h = cast(&s, id, mk_v3(0, 0, 4), mk_v3(0, 0, -8)); /* apex: any normal of its normal cone */
    MK_ASSERT_NEAR(h.fraction, 3.0 / 8, RAY_TOL);
    check_certificate(&s, id, mk_v3(0, 0, -8), &h, 10 * RAY_TOL);
}
END_TEST

START_TEST(plane_and_hull_analytic)
{
    mk_shape s;
    mk_hull *hull = make_octahedron();
    mk_transform xf = mk_transform_make(mk_v3(0, 0, 1), mk_quat_identity());
    mk_ray_hit h;
    mk_shape_plane(mk_v3(0, 0, 1), 0.5, &s); /* solid below z = 1.5 in the world */
    h = cast(&s, xf, mk_v3(3, 4, 5.5), mk_v3(0, 0, -8));
    MK_ASSERT_NEAR(h.fraction, 0.5, RAY_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(0, 0, 1), 0);
    ck_assert(!cast(&s, xf, mk_v3(3, 4, 5.5), mk_v3(1, 0, 0)).hit);
    ck_assert(!cast(&s, xf, mk_v3(3, 4, 5.5), mk_v3(0, 0, -3.99)).hit);

    mk_shape_hull(hull, 0, &s);
    /* Straight down the z axis onto the top vertex (0.1, 0, 1.3)'s faces. */
    h = cast(&s, mk_transform_identity(), mk_v3(0.1, 0, 5), mk_v3(0, 0, -10));
    MK_ASSERT_NEAR(h.fraction, 3.7 / 10, RAY_TOL);
    check_certificate(&s, mk_transform_identity(), mk_v3(0, 0, -10), &h, 10 * RAY_TOL);
    mk_shape_hull(hull, 0.2, &s); /* rounded: the vertex becomes a ball */
    h = cast(&s, mk_transform_identity(), mk_v3(0.1, 0, 5), mk_v3(0, 0, -10));
    MK_ASSERT_NEAR(h.fraction, 3.5 / 10, RAY_TOL);
    MK_ASSERT_V3_NEAR(h.normal, mk_v3(0, 0, 1), 10 * RAY_TOL);
    mk_hull_destroy(hull);
}
END_TEST

START_TEST(inside_start_and_degenerate_rays)
{
    mk_shape s;
    mk_transform id = mk_transform_identity();
    mk_ray_hit h;
    int type;
    mk_hull *hull = make_octahedron();
    for (type = 0; type < MK_SHAPE_TYPE_COUNT; ++type) {
        switch (type) {
        case MK_SHAPE_SPHERE: mk_shape_sphere(1, &s); break;
        case MK_SHAPE_BOX: mk_shape_box(mk_v3(1, 1, 1), 0, &s); break;
        case MK_SHAPE_CAPSULE: mk_shape_capsule(0.5, 1, &s); break;
        case MK_SHAPE_CYLINDER: mk_shape_cylinder(1, 1, 0, &s); break;
        case MK_SHAPE_CONE: mk_shape_cone(1, 1, 0.1, &s); break;
        case MK_SHAPE_HULL: mk_shape_hull(hull, 0, &s); break;
        default: mk_shape_plane(mk_v3(0, 0, 1), 0.5, &s); break;
        }
        h = cast(&s, id, mk_v3(0, 0, 0.1), mk_v3(0, 0, 4));
        ck_assert_msg(h.hit && h.fraction == 0, "%s: a ray from inside hits at 0", mk_shape_type_name(s.type));
        MK_ASSERT_V3_NEAR(h.normal, mk_v3(0, 0, -1), 0);
        h = cast(&s, id, mk_v3(0, 0, 0.1), mk_v3_zero());
        ck_assert(h.hit && h.fraction == 0);
        MK_ASSERT_V3_NEAR(h.normal, mk_v3_zero(), 0);
        h = cast(&s, id, mk_v3(7, 0, 5), mk_v3_zero());
        ck_assert_msg(!h.hit, "%s: a zero-length ray outside misses", mk_shape_type_name(s.type));
        MK_ASSERT_V3_NEAR(h.point, mk_v3(7, 0, 5), 0);
    }
    mk_hull_destroy(hull);
}
END_TEST

START_TEST(bad_input)
{
    mk_shape s, bad;
    mk_ray_hit h;
    mk_transform id = mk_transform_identity();
    mk_shape_sphere(1, &s);
    memset(&bad, 0, sizeof bad);
    bad.type = MK_SHAPE_BOX;
    h.hit = 42;
    MK_ASSERT_STATUS(mk_raycast(NULL, id, mk_v3_zero(), mk_v3(1, 0, 0), &h), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_raycast(&s, id, mk_v3_zero(), mk_v3(1, 0, 0), NULL), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_raycast(&bad, id, mk_v3_zero(), mk_v3(1, 0, 0), &h), MK_ERR_BAD_SIZE);
    MK_ASSERT_STATUS(mk_raycast(&s, id, mk_v3((mk_real)NAN, 0, 0), mk_v3(1, 0, 0), &h), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_raycast(&s, id, mk_v3_zero(), mk_v3(0, (mk_real)INFINITY, 0), &h), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_raycast(&s, mk_transform_make(mk_v3((mk_real)NAN, 0, 0), mk_quat_identity()), mk_v3_zero(), mk_v3(1, 0, 0), &h),
                     MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_raycast(&s, mk_transform_make(mk_v3_zero(), mk_quat_make(0, 0, 0, 2)), mk_v3_zero(), mk_v3(1, 0, 0), &h),
                     MK_ERR_BAD_ROTATION);
    ck_assert_int_eq(h.hit, 42);
}
END_TEST

/* Random rays aimed at random points of each shape's bounding box, from
 * outside it, against the oracle; hits also carry the support certificate. */
static void random_rays(const mk_shape *s, unsigned seed, int count)
{
    mk_rng r;
    int i, hits = 0;
    r.s = seed;
    for (i = 0; i < count; ++i) {
        mk_transform xf = mk_transform_make(mk_rng_v3(&r, -3, 3), mk_rng_quat(&r));
        mk_aabb box;
        mk_vec3 target, o, d;
        mk_ray_hit h;
        double t_ref, scale;
        mk_shape_aabb(s, xf, &box);
        target = mk_v3(box.lo.x + (box.hi.x - box.lo.x) * (mk_real)mk_rng_unit(&r),
                       box.lo.y + (box.hi.y - box.lo.y) * (mk_real)mk_rng_unit(&r),
                       box.lo.z + (box.hi.z - box.lo.z) * (mk_real)mk_rng_unit(&r));
        o = mk_v3_mad(target, (mk_real)mk_rng_range(&r, 2, 5), mk_rng_dir(&r));
        d = mk_v3_scale(mk_v3_sub(target, o), (mk_real)mk_rng_range(&r, 1.0, 3.0));
        h = cast(s, xf, o, d);
        t_ref = oracle_ray(s, xf, o, d, 1500);
        scale = (double)mk_v3_len(d);
        if (t_ref >= 0) {
            double cosine;
            ck_assert_msg(h.hit, "seed %u ray %d: %s missed, oracle hit at %.17g", seed, i, mk_shape_type_name(s->type), t_ref);
            /* The hit fraction's conditioning is 1 / |n.d|: compare distances along the normal. */
            cosine = fabs((double)mk_v3_dot(h.normal, d)) / scale;
            ck_assert_msg(fabs((double)h.fraction - t_ref) * scale * (cosine > 1e-3 ? cosine : 1e-3) <= 1e3 * RAY_TOL * scale,
                          "seed %u ray %d %s: fraction %.17g, oracle %.17g", seed, i, mk_shape_type_name(s->type), (double)h.fraction, t_ref);
            ++hits;
        }
        if (h.hit && h.fraction > 0) check_certificate(s, xf, d, &h, 1e2 * RAY_TOL * (scale + 10));
        if (h.hit && t_ref >= 0 && fabs((double)mk_v3_dot(h.normal, d)) > 0.1 * scale)
            ck_assert_msg(oracle_inside(s, xf, mk_v3_mad(h.point, (mk_real)1e-4, d)), "seed %u ray %d: a little past the hit is inside", seed, i);
    }
    ck_assert_msg(hits > count / 5, "%s: only %d of %d rays hit; the test aims badly", mk_shape_type_name(s->type), hits, count);
}

START_TEST(random_against_oracle)
{
    mk_shape s;
    mk_hull *hull = make_octahedron();
    mk_shape_sphere(0.7, &s);
    random_rays(&s, 1, 60);
    mk_shape_box(mk_v3(1, 0.5, 0.25), 0, &s);
    random_rays(&s, 2, 60);
    mk_shape_box(mk_v3(1, 0.5, 0.25), 0.2, &s);
    random_rays(&s, 3, 60);
    mk_shape_capsule(0.3, 0.8, &s);
    random_rays(&s, 4, 60);
    mk_shape_cylinder(0.6, 0.9, 0, &s);
    random_rays(&s, 5, 60);
    mk_shape_cylinder(0.6, 0.9, 0.15, &s);
    random_rays(&s, 6, 60);
    mk_shape_cone(0.7, 0.8, 0, &s);
    random_rays(&s, 7, 60);
    mk_shape_cone(0.7, 0.8, 0.2, &s);
    random_rays(&s, 8, 60);
    mk_shape_hull(hull, 0, &s);
    random_rays(&s, 9, 60);
    mk_shape_hull(hull, 0.25, &s);
    random_rays(&s, 10, 60);
    mk_hull_destroy(hull);
}
END_TEST

static Suite *raycast_suite(void)
{
    Suite *s = suite_create("raycast");
    TCase *tc = tcase_create("core");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, sphere_analytic);
    tcase_add_test(tc, box_analytic);
    tcase_add_test(tc, capsule_cylinder_cone_analytic);
    tcase_add_test(tc, plane_and_hull_analytic);
    tcase_add_test(tc, inside_start_and_degenerate_rays);
    tcase_add_test(tc, bad_input);
    tcase_add_test(tc, random_against_oracle);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return mk_test_run(raycast_suite()); }

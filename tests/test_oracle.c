/* test_oracle.c: the judge is judged. The brute-force oracle (support/oracle.h)
 * must reproduce hand-derived answers, agree with its own exhaustive mode, and
 * satisfy the defining property of a penetration depth: moving B by the depth
 * along the normal makes the shapes touch. */
#include <stdlib.h>
#include <string.h>

#include "minko/shape.h"
#include "support/mk_test.h"
#include "support/cases.h"
#include "support/oracle.h"

#define SQRT2 1.41421356237309504880L
#define SQRT3 1.73205080756887729353L

/* The oracle works in long double whatever mk_real is, but its inputs are
 * mk_real: in the float build a value like 1.9 is rounded before it arrives.
 * Expected answers below are computed from the same rounded numbers. */
#define TOL 1e-15L

static mk_transform pose(long double x, long double y, long double z, mk_quat q)
{
    return mk_transform_make(mk_v3((mk_real)x, (mk_real)y, (mk_real)z), q);
}

static mk_transform at(long double x, long double y, long double z) { return pose(x, y, z, mk_quat_identity()); }

static mk_oracle_result query(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb)
{
    mk_oracle_result r;
    memset(&r, 0, sizeof r);
    ck_assert_int_eq(mk_oracle_distance(a, xa, b, xb, &r), 0);
    return r;
}

static void assert_normal(mk_oracle_result r, long double x, long double y, long double z)
{
    mk_lvec3 n;
    n.x = x, n.y = y, n.z = z;
    ck_assert_msg(mk_oracle_angle_deg(n, r.normal.x, r.normal.y, r.normal.z) < 1e-12L,
                  "normal (%.17Lg %.17Lg %.17Lg), expected (%.17Lg %.17Lg %.17Lg)", r.normal.x, r.normal.y, r.normal.z, x, y,
                  z);
}

START_TEST(axis_aligned_boxes)
{
    mk_shape a, b;
    mk_oracle_result r;
    mk_shape_box(mk_v3(1, 2, 3), 0, &a);
    mk_shape_box(mk_v3(0.5, 0.5, 0.5), 0, &b);
    /* face gap along x */
    r = query(&a, at(0, 0, 0), &b, at(2, 0.25, -1));
    MK_ASSERT_NEAR(r.distance, 0.5, TOL);
    assert_normal(r, 1, 0, 0);
    ck_assert(r.normal_defined);
    /* corner to corner: gaps 0.5, 0.25, 1 on the three axes */
    r = query(&a, at(0, 0, 0), &b, at(-2, (mk_real)2.75, 4.5));
    MK_ASSERT_NEAR(r.distance, sqrtl(0.25L + 0.0625L + 1), TOL);
    assert_normal(r, -0.5L / sqrtl(1.3125L), 0.25L / sqrtl(1.3125L), 1 / sqrtl(1.3125L));
    /* penetrating: overlaps 0.25 (x), 2.5 (y), 1 (z): depth is the smallest */
    r = query(&a, at(0, 0, 0), &b, at(1.25, 0, 0));
    MK_ASSERT_NEAR(r.distance, -0.25, TOL);
    assert_normal(r, 1, 0, 0);
    /* swapping A and B flips the normal only */
    r = query(&b, at(1.25, 0, 0), &a, at(0, 0, 0));
    MK_ASSERT_NEAR(r.distance, -0.25, TOL);
    assert_normal(r, -1, 0, 0);
    /* touching exactly: distance 0, the face normal is still defined */
    r = query(&a, at(0, 0, 0), &b, at(0, 0, 3.5));
    MK_ASSERT_NEAR(r.distance, 0, 0);
    assert_normal(r, 0, 0, 1);
    ck_assert(r.normal_defined);
}
END_TEST

/* libccd #25: two 2 m cubes stacked at z = 0 and z = 1.9 overlap by 0.1 along z. */
START_TEST(libccd_25_stacked_cubes)
{
    mk_shape a;
    mk_oracle_result r;
    mk_shape_box(mk_v3(1, 1, 1), 0, &a);
    r = query(&a, at(0, 0, 0), &a, at(0, 0, 1.9));
    MK_ASSERT_NEAR(r.distance, (long double)(mk_real)1.9 - 2, TOL);
    assert_normal(r, 0, 0, 1);
    ck_assert(r.normal_defined);
}
END_TEST

/* Unit cubes (half 0.5); B turned so that a known feature faces A. */
START_TEST(rotated_cubes_hand_derived)
{
    mk_shape c;
    mk_oracle_result r;
    mk_quat z45 = mk_quat_from_axis_angle(mk_v3(0, 0, 1), (mk_real)0.78539816339744830962);
    mk_quat y45 = mk_quat_from_axis_angle(mk_v3(0, 1, 0), (mk_real)0.78539816339744830962);
    /* A rotation that takes the corner direction (1,1,1)/sqrt3 to -x. */
    mk_quat corner = mk_quat_from_axis_angle(mk_v3(0, 1, -1), (mk_real)(3.14159265358979323846 - 0.95531661812450927816));
    long double hw, tol = 4 * MK_TEST_TOL; /* the rotations themselves carry mk_real rounding */
    mk_shape_box(mk_v3(0.5, 0.5, 0.5), 0, &c);
    /* vertical edge of B (45 deg about z) faces A's +x face: gap = 2 - sqrt2/2 - 1/2 */
    r = query(&c, at(0, 0, 0), &c, pose(2, 0, 0, z45));
    MK_ASSERT_NEAR(r.distance, 1.5L - SQRT2 / 2, tol);
    assert_normal(r, 1, 0, 0);
    r = query(&c, at(0, 0, 0), &c, pose(0.9, 0, 0, z45));
    MK_ASSERT_NEAR(r.distance, 0.4L - SQRT2 / 2, tol);
    assert_normal(r, 1, 0, 0);
    /* corner of B faces A's +x face */
    r = query(&c, at(0, 0, 0), &c, pose(2, 0.1, -0.2, corner));
    MK_ASSERT_NEAR(r.distance, 1.5L - SQRT3 / 2, tol);
    assert_normal(r, 1, 0, 0);
    /* edge-edge: A's vertical edge at x = sqrt2/2 (A turned about z), B's edge along y at
     * x = 2 - sqrt2/2 (B turned about y): the two edges cross at right angles. */
    hw = SQRT2 / 2;
    r = query(&c, pose(0, 0, 0, z45), &c, pose(2, 0, 0, y45));
    MK_ASSERT_NEAR(r.distance, 2 - 2 * hw, tol);
    assert_normal(r, 1, 0, 0);
    ck_assert(r.normal_defined);
    r = query(&c, pose(0, 0, 0, z45), &c, pose(1.3, 0.05, -0.02, y45));
    MK_ASSERT_NEAR(r.distance, 1.3L - 2 * hw, tol);
    assert_normal(r, 1, 0, 0);
    ck_assert(r.normal_defined);
}
END_TEST

START_TEST(spheres_capsules_closed_forms)
{
    mk_shape s1, s2, cap, box;
    mk_oracle_result r;
    mk_quat x90 = mk_quat_from_axis_angle(mk_v3(1, 0, 0), (mk_real)1.57079632679489661923);
    mk_shape_sphere(1, &s1);
    mk_shape_sphere(0.5, &s2);
    r = query(&s1, at(1, 2, 3), &s2, at(1, 2 + 3, 3 + 4));
    MK_ASSERT_NEAR(r.distance, 3.5, TOL);
    assert_normal(r, 0, 0.6L, 0.8L);
    r = query(&s1, at(0, 0, 0), &s2, at(0.3, 0, 0));
    MK_ASSERT_NEAR(r.distance, (long double)(mk_real)0.3 - 1.5L, TOL);
    /* capsules (radius 0.25, half height 1): parallel side by side, then crossed */
    mk_shape_capsule(0.25, 1, &cap);
    r = query(&cap, at(0, 0, 0), &cap, at(2, 0, 0.5));
    MK_ASSERT_NEAR(r.distance, 1.5, TOL);
    assert_normal(r, 1, 0, 0);
    r = query(&cap, at(0, 0, 0), &cap, pose(0.1, 0.2, 0.3, x90));
    MK_ASSERT_NEAR(r.distance, sqrtl(0.01L) - 0.5L, 4 * MK_TEST_TOL);
    /* end caps facing: the segment ends are 1 apart */
    r = query(&cap, at(0, 0, 0), &cap, at(0, 0, 3));
    MK_ASSERT_NEAR(r.distance, 0.5, TOL);
    assert_normal(r, 0, 0, 1);
    /* sphere against a box: outside a face, outside a corner, inside */
    mk_shape_box(mk_v3(1, 1, 1), 0, &box);
    r = query(&box, at(0, 0, 0), &s2, at(0.2, 3, -0.4));
    MK_ASSERT_NEAR(r.distance, 1.5, TOL);
    assert_normal(r, 0, 1, 0);
    r = query(&box, at(0, 0, 0), &s2, at(2, 3, 3));
    MK_ASSERT_NEAR(r.distance, 3 - 0.5L, TOL);
    r = query(&box, at(0, 0, 0), &s2, at(0.25, -0.5, 0.1));
    MK_ASSERT_NEAR(r.distance, -(0.5L + 0.5L), TOL);
    assert_normal(r, 0, -1, 0);
    /* capsule lying on a box, axis along x: distance to the top face */
    r = query(&box, at(0, 0, 0), &cap, pose(0.5, 0.2, 1.75, mk_quat_from_axis_angle(mk_v3(0, 1, 0), (mk_real)1.57079632679489661923)));
    MK_ASSERT_NEAR(r.distance, 0.5, 4 * MK_TEST_TOL);
    assert_normal(r, 0, 0, 1);
}
END_TEST

START_TEST(planes_closed_forms)
{
    mk_shape ground, box, cyl, cone, sph;
    mk_oracle_result r;
    mk_quat tilt = mk_quat_from_axis_angle(mk_v3(1, 0, 0), (mk_real)0.78539816339744830962);
    mk_shape_plane(mk_v3(0, 0, 1), 0.5, &ground); /* solid below z = 0.5 */
    mk_shape_box(mk_v3(1, 1, 1), 0, &box);
    r = query(&box, at(3, 4, 2), &ground, at(0, 0, 0));
    MK_ASSERT_NEAR(r.distance, 0.5, TOL);
    assert_normal(r, 0, 0, -1);
    /* box turned 45 deg about x: lowest edge at z - sqrt2 */
    r = query(&ground, at(0, 0, 0), &box, pose(0, 0, 1, tilt));
    MK_ASSERT_NEAR(r.distance, 0.5L - SQRT2, 4 * MK_TEST_TOL);
    assert_normal(r, 0, 0, 1);
    /* the plane itself moved and turned: the plane shape's pose applies to it */
    r = query(&box, at(0, 0, 10), &ground, pose(0, 0, 2, mk_quat_identity()));
    MK_ASSERT_NEAR(r.distance, 10 - 1 - 2.5L, TOL);
    mk_shape_cylinder(2, 1, 0.1, &cyl);
    r = query(&cyl, pose(0, 0, 5, tilt), &ground, at(0, 0, 0));
    MK_ASSERT_NEAR(r.distance, 5 - 0.5L - (2 * SQRT2 / 2 + SQRT2 / 2) - 0.1L, 4 * MK_TEST_TOL);
    mk_shape_cone(1, 1, 0, &cone);
    r = query(&cone, at(0, 0, 3), &ground, at(0, 0, 0));
    MK_ASSERT_NEAR(r.distance, 1.5, TOL);
    mk_shape_sphere(1, &sph);
    r = query(&sph, at(0, 0, 0.25), &ground, at(0, 0, 0));
    MK_ASSERT_NEAR(r.distance, -1.25, TOL);
    /* cylinder against a box is not something the oracle knows */
    {
        mk_oracle_result dummy;
        ck_assert_int_eq(mk_oracle_distance(&cyl, at(0, 0, 0), &box, at(5, 0, 0), &dummy), -1);
        ck_assert_int_eq(mk_oracle_distance(&ground, at(0, 0, 0), &ground, at(5, 0, 0), &dummy), -1);
    }
}
END_TEST

/* 1e5 offsets cost the oracle nothing: it works in A's frame in long double,
 * so the same relative pose gives the same answer to the last bit or so. */
START_TEST(large_coordinates_invariant)
{
    mk_shape a, b;
    mk_rng rng = {7};
    int i;
    mk_shape_box(mk_v3(0.5, 0.25, 0.125), 0, &a);
    mk_shape_box(mk_v3(0.3, 0.3, 0.3), 0, &b);
    for (i = 0; i < 50; ++i) {
        mk_quat qa = mk_rng_quat(&rng), qb = mk_rng_quat(&rng);
        /* multiples of 1/64 so that offset + d is exact even in float */
        mk_vec3 off = mk_v3(1e5, -1e5, 65536), d = mk_rng_v3(&rng, -64, 64);
        d = mk_v3((mk_real)floor(d.x) / 64, (mk_real)floor(d.y) / 64, (mk_real)floor(d.z) / 64);
        mk_oracle_result r0 = query(&a, pose(0, 0, 0, qa), &b, pose(d.x, d.y, d.z, qb));
        mk_oracle_result r1 = query(&a, pose(off.x, off.y, off.z, qa), &b,
                                    pose((long double)off.x + d.x, (long double)off.y + d.y, (long double)off.z + d.z, qb));
        MK_ASSERT_NEAR(r1.distance, r0.distance, 1e-17L);
    }
}
END_TEST

/* Points on an ellipsoid (axes 1, ratio, ratio^2 scaled), rounded to mk_real. */
static void ellipsoid_points(mk_rng *rng, int n, double ratio, mk_lvec3 *p)
{
    int i;
    for (i = 0; i < n; ++i) {
        mk_vec3 d = mk_rng_dir(rng);
        p[i].x = (mk_real)(d.x * 1.0);
        p[i].y = (mk_real)(d.y / sqrt(ratio));
        p[i].z = (mk_real)(d.z / ratio);
    }
}

START_TEST(hull_topology)
{
    mk_oracle_shape o;
    mk_lvec3 p[27], q[64];
    mk_rng rng = {11};
    int i, j, k, n = 0;
    /* cube corners, edge midpoints, face centres and the centre: 8 vertices, 6 quads */
    for (i = -1; i <= 1; ++i)
        for (j = -1; j <= 1; ++j)
            for (k = -1; k <= 1; ++k) p[n].x = i, p[n].y = j, p[n].z = k, ++n;
    ck_assert_int_eq(mk_oracle_shape_points(&o, p, n, 0), 0);
    ck_assert_int_eq(o.core.nv, 8);
    ck_assert_int_eq(o.core.nf, 6);
    ck_assert_int_eq(o.core.ne, 12);
    for (i = 0; i < o.core.nf; ++i) ck_assert_int_eq(o.core.face_first[i + 1] - o.core.face_first[i], 4);
    mk_oracle_shape_free(&o);
    /* a coplanar cloud has no solid hull */
    for (i = 0; i < 9; ++i) p[i].z = 0;
    ck_assert_int_eq(mk_oracle_shape_points(&o, p, 9, 0), -1);
    mk_oracle_shape_free(&o);
    /* random points on an ellipsoid: all are vertices, faces are triangles (general position),
     * every point lies inside every face plane */
    ellipsoid_points(&rng, 64, 10, q);
    ck_assert_int_eq(mk_oracle_shape_points(&o, q, 64, 0), 0);
    ck_assert_int_eq(o.core.nv, 64);
    ck_assert_int_eq(o.core.nf, 2 * 64 - 4);
    for (i = 0; i < o.core.nf; ++i) {
        mk_lvec3 n0 = o.core.fn[i], v0 = o.core.v[o.core.face_vert[o.core.face_first[i]]];
        for (j = 0; j < 64; ++j)
            ck_assert(n0.x * (q[j].x - v0.x) + n0.y * (q[j].y - v0.y) + n0.z * (q[j].z - v0.z) <= 1e-15L);
    }
    mk_oracle_shape_free(&o);
}
END_TEST

static mk_transform random_pose(mk_rng *rng, double spread)
{
    mk_vec3 p = mk_rng_v3(rng, -spread, spread);
    return mk_transform_make(p, mk_rng_quat(rng));
}

static mk_oracle_pose shifted(mk_oracle_pose p, mk_lvec3 n, long double s)
{
    p.p.x += s * n.x, p.p.y += s * n.y, p.p.z += s * n.z;
    return p;
}

/* Random hull pairs: the Gauss-map pruning changes nothing, and the defining
 * properties hold: a penetration depth is the shortest translation that
 * separates (moving B by depth + e along the normal leaves a gap of e), and a
 * distance shrinks by exactly what B moves along the normal towards A. */
START_TEST(random_hulls_consistent)
{
    mk_rng rng = {2024};
    mk_lvec3 p[40];
    mk_oracle_shape a, b;
    int it, sep = 0, pen = 0;
    for (it = 0; it < 60; ++it) {
        int na = 4 + (int)(mk_rng_unit(&rng) * 36), nb = 4 + (int)(mk_rng_unit(&rng) * 36);
        mk_oracle_pose xa, xb;
        mk_oracle_result r, rx, moved;
        long double e;
        ellipsoid_points(&rng, na, 1 + 9 * mk_rng_unit(&rng), p);
        ck_assert_int_eq(mk_oracle_shape_points(&a, p, na, 0), 0);
        ellipsoid_points(&rng, nb, 1 + 9 * mk_rng_unit(&rng), p);
        ck_assert_int_eq(mk_oracle_shape_points(&b, p, nb, 0), 0);
        xa = mk_oracle_pose_of(random_pose(&rng, 0.3));
        xb = mk_oracle_pose_of(random_pose(&rng, 1.2));
        ck_assert_int_eq(mk_oracle_query(&a, &xa, &b, &xb, 0, &r), 0);
        ck_assert_int_eq(mk_oracle_query(&a, &xa, &b, &xb, MK_ORACLE_EXHAUSTIVE, &rx), 0);
        MK_ASSERT_NEAR(r.distance, rx.distance, 1e-17L);
        ck_assert(mk_oracle_angle_deg(r.normal, rx.normal.x, rx.normal.y, rx.normal.z) < 1e-12L);
        e = 1e-3L;
        if (r.distance < 0) {
            mk_oracle_pose xm = shifted(xb, r.normal, -r.distance + e);
            ++pen;
            ck_assert_int_eq(mk_oracle_query(&a, &xa, &b, &xm, 0, &moved), 0);
            MK_ASSERT_NEAR(moved.distance, e, 1e-15L);
            xm = shifted(xb, r.normal, -r.distance - e);
            ck_assert_int_eq(mk_oracle_query(&a, &xa, &b, &xm, 0, &moved), 0);
            ck_assert(moved.distance < 0);
        } else {
            mk_oracle_pose xm = shifted(xb, r.normal, -(r.distance - e));
            ++sep;
            ck_assert_int_eq(mk_oracle_query(&a, &xa, &b, &xm, 0, &moved), 0);
            MK_ASSERT_NEAR(moved.distance, e, 1e-15L);
        }
        mk_oracle_shape_free(&a);
        mk_oracle_shape_free(&b);
    }
    ck_assert(sep > 10 && pen > 10);
}
END_TEST

/* The shared case families: requested counts and signs, unit normals,
 * deterministic, and the regression cases carry the answers their reports
 * describe. */
START_TEST(case_families)
{
    mk_case_set s1, s2;
    int f, i, n;
    memset(&s1, 0, sizeof s1);
    memset(&s2, 0, sizeof s2);
    for (f = 0; f < MK_FAM_COUNT; ++f) {
        ck_assert_msg(mk_cases_add_family(&s1, (mk_family)f, 3, 2, 99) == 0, "family %s", mk_family_name((mk_family)f));
        ck_assert_int_eq(mk_cases_add_family(&s2, (mk_family)f, 3, 2, 99), 0);
    }
    ck_assert_int_eq(s1.count, 5 * MK_FAM_COUNT);
    ck_assert_int_eq(s2.count, s1.count);
    for (i = 0; i < s1.count; ++i) {
        const mk_case *c = &s1.cases[i];
        long double nl = sqrtl((long double)c->normal[0] * c->normal[0] + (long double)c->normal[1] * c->normal[1] +
                               (long double)c->normal[2] * c->normal[2]);
        ck_assert_str_eq(c->variant, i % 5 < 3 ? "separated" : "penetrating");
        ck_assert_msg(i % 5 < 3 ? c->distance > 0 : c->distance < 0, "%s/%s d = %g", c->family, c->variant, c->distance);
        ck_assert(fabsl(nl - 1) < 1e-15L);
        ck_assert(c->distance == s2.cases[i].distance && c->xb.p.x == s2.cases[i].xb.p.x);
        if (!strcmp(c->family, "nearly_touching"))
            ck_assert(fabs(c->distance) > 0.3e-6 * c->size && fabs(c->distance) < 3e-6 * c->size);
    }
    mk_case_set_free(&s2);
    n = s1.count;
    ck_assert_int_eq(mk_cases_add_regressions(&s1), 0);
    for (i = n; i < s1.count; ++i) {
        const mk_case *c = &s1.cases[i];
        if (!strcmp(c->variant, "libccd25_stacked_cubes")) {
            MK_ASSERT_NEAR(c->distance, (double)(mk_real)1.9 - 2, 1e-15);
            ck_assert(c->normal_defined && c->normal[2] == 1);
        }
        if (!strcmp(c->variant, "touching_faces")) ck_assert(c->distance == 0 && c->normal_defined);
        if (!strcmp(c->variant, "touching_corners")) ck_assert(c->distance == 0 && !c->normal_defined);
        if (!strcmp(c->variant, "libccd17_5m_vs_0.2m")) MK_ASSERT_NEAR(c->distance, -0.01, 4 * MK_TEST_TOL);
#if !defined(MK_SINGLE) /* float cannot place a box 1e-9 off */
        if (!strcmp(c->variant, "fcl495_gap_1e-9")) MK_ASSERT_NEAR(c->distance, 1e-9, 1e-15);
        if (!strcmp(c->variant, "fcl495_overlap_1e-9")) MK_ASSERT_NEAR(c->distance, -1e-9, 1e-15);
        if (!strcmp(c->variant, "fcl493_kissing")) ck_assert(fabs(c->distance) < 1e-15);
#endif
        if (!strcmp(c->variant, "jolt2103_capsule_cylinder")) ck_assert(fabs(c->distance) < 1e-5);
    }
    ck_assert_int_eq(s1.count - n, 8);
    mk_case_set_free(&s1);
}
END_TEST

static Suite *oracle_suite(void)
{
    Suite *s = suite_create("oracle");
    TCase *tc = tcase_create("core");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, axis_aligned_boxes);
    tcase_add_test(tc, libccd_25_stacked_cubes);
    tcase_add_test(tc, rotated_cubes_hand_derived);
    tcase_add_test(tc, spheres_capsules_closed_forms);
    tcase_add_test(tc, planes_closed_forms);
    tcase_add_test(tc, large_coordinates_invariant);
    tcase_add_test(tc, hull_topology);
    tcase_add_test(tc, random_hulls_consistent);
    tcase_add_test(tc, case_families);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return mk_test_run(oracle_suite()); }

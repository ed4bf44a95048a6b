/* test_hull.c: quickhull construction, its invariants, bad input, hull shapes
 * (support with rounding, AABB) and the hill-climbing support index. */
#include <stdlib.h>
#include <string.h>

#include "minko/shape.h"
#include "shape_internal.h"
#include "support/mk_test.h"

/* Check records a checkpoint on every passing ck_assert (a write per call), far
 * too slow for the O(points x faces) loops here: test first, fail loudly. */
#define REQUIRE(cond, ...) do { if (!(cond)) ck_abort_msg(__VA_ARGS__); } while (0)
#define CHECK(cond) REQUIRE(cond, "%s", #cond)

/* ---- point clouds -------------------------------------------------------------- */

static void cloud_ball(mk_rng *r, mk_vec3 *p, int n, double radius)
{
    int i;
    for (i = 0; i < n; ++i) {
        mk_vec3 v;
        do v = mk_rng_v3(r, -1, 1); while (mk_v3_len2(v) > 1);
        p[i] = mk_v3_scale(v, (mk_real)radius);
    }
}

static void cloud_ellipsoid(mk_rng *r, mk_vec3 *p, int n, mk_vec3 axes)
{
    int i;
    for (i = 0; i < n; ++i) p[i] = mk_v3_mul(mk_rng_dir(r), axes);
}

/* Points on the surface of the box [-h, h]: one coordinate exactly +-h, so the
 * points of a side are exactly coplanar. With corners = 1 the 8 corners are
 * added, and the hull must be exactly the box. */
static void cloud_box_surface(mk_rng *r, mk_vec3 *p, int n, mk_vec3 h, int corners)
{
    int i = 0;
    if (corners)
        for (; i < 8 && i < n; ++i) p[i] = mk_v3(i & 1 ? h.x : -h.x, i & 2 ? h.y : -h.y, i & 4 ? h.z : -h.z);
    for (; i < n; ++i) {
        int side = (int)(mk_rng_unit(r) * 6);
        mk_vec3 v = mk_v3((mk_real)mk_rng_range(r, -h.x, h.x), (mk_real)mk_rng_range(r, -h.y, h.y),
                          (mk_real)mk_rng_range(r, -h.z, h.z));
        mk_real s = (side & 1) ? 1 : -1;
        if (side / 2 == 0) v.x = s * h.x;
        else if (side / 2 == 1) v.y = s * h.y;
        else v.z = s * h.z;
        p[i] = v;
    }
}

static void shuffle(mk_rng *r, mk_vec3 *p, int n)
{
    int i;
    for (i = n - 1; i > 0; --i) {
        int j = (int)(mk_rng_unit(r) * (i + 1));
        mk_vec3 t = p[i];
        p[i] = p[j];
        p[j] = t;
    }
}

/* ---- the invariants --------------------------------------------------------------- */

static int cmp_v3(const void *a, const void *b)
{
    const mk_vec3 *u = (const mk_vec3 *)a, *v = (const mk_vec3 *)b;
    if (u->x != v->x) return u->x < v->x ? -1 : 1;
    if (u->y != v->y) return u->y < v->y ? -1 : 1;
    if (u->z != v->z) return u->z < v->z ? -1 : 1;
    return 0;
}

static double face_dist(const mk_hull *h, int f, mk_vec3 p)
{
    return (double)mk_v3_dot(h->planes[f].normal, p) - (double)h->planes[f].offset;
}

/* Height of face g's lowest vertex above face f's plane. */
static double lowest_vertex(const mk_hull *h, int f, int g)
{
    int e0 = h->face_edge[g], e = e0;
    double lo = 0;
    do {
        lo = fmin(lo, face_dist(h, f, h->vertices[h->edges[e].origin]));
        e = h->edges[e].next;
    } while (e != e0);
    return lo;
}

/* Tolerance the invariants are held to: a few times the construction tolerance
 * (merged faces are planar to about that), plus the rounding of a plane
 * evaluation at the cloud's coordinates (which may be offset far from 0). */
static double inv_tol(const mk_hull *h, double coord)
{
    return 4 * (double)h->tolerance + 16 * MK_REAL_EPSILON * coord;
}

/* Whether adjacent faces must not be coplanar. For exactly coplanar input
 * and in the double build they never are. In the float build a cloud of
 * points scattered at float rounding near a plane (a rotated flat box, a
 * dense ellipsoid) can keep two coplanar faces, where merging them would
 * move a vertex by more than the tolerance (a point a hair off an edge). */
#if defined(MK_SINGLE)
#  define NOISY_COPLANAR_OK 1
#else
#  define NOISY_COPLANAR_OK 0
#endif

/* Topology, exact vertex provenance, planes, convexity, no coplanar
 * neighbours (unless coplanar_ok), every input point inside, centroid, radii
 * and bounds. */
static void check_hull(const mk_hull *h, const mk_vec3 *pts, int n, int coplanar_ok)
{
    int f, e, v, i, total = 0;
    int *deg = calloc((size_t)h->vertex_count, sizeof(int));
    mk_vec3 *sorted = malloc((size_t)n * sizeof(mk_vec3));
    double coord = 0, tol;
    ck_assert(deg && sorted);
    for (i = 0; i < n; ++i) coord = fmax(coord, (double)mk_v3_max_abs(pts[i]));
    tol = inv_tol(h, coord);
    ck_assert_int_ge(h->vertex_count, 4);
    ck_assert_int_ge(h->face_count, 4);
    ck_assert_int_eq(h->edge_count % 2, 0);
    ck_assert_int_eq(h->vertex_count - h->edge_count / 2 + h->face_count, 2); /* Euler */

    /* Vertices are input points, bit for bit, and distinct. */
    memcpy(sorted, pts, (size_t)n * sizeof(mk_vec3));
    qsort(sorted, (size_t)n, sizeof(mk_vec3), cmp_v3);
    for (v = 0; v < h->vertex_count; ++v)
        REQUIRE(bsearch(&h->vertices[v], sorted, (size_t)n, sizeof(mk_vec3), cmp_v3) != NULL, "vertex %d is not an input point", v);
    memcpy(sorted, h->vertices, (size_t)h->vertex_count * sizeof(mk_vec3));
    qsort(sorted, (size_t)h->vertex_count, sizeof(mk_vec3), cmp_v3);
    for (v = 1; v < h->vertex_count; ++v) REQUIRE(cmp_v3(&sorted[v - 1], &sorted[v]) != 0, "duplicate vertex");

    /* Half-edges: twins symmetric across different faces, loops closed. */
    for (e = 0; e < h->edge_count; ++e) {
        const mk_hull_edge *E = &h->edges[e];
        CHECK(E->twin < h->edge_count);
        CHECK(E->next < h->edge_count);
        CHECK(E->origin < h->vertex_count);
        CHECK(E->face < h->face_count);
        CHECK(h->edges[E->twin].twin == e);
        CHECK(E->twin != e);
        CHECK(h->edges[E->twin].face != E->face);
        CHECK(h->edges[E->twin].origin == h->edges[E->next].origin);
        CHECK(h->edges[E->next].face == E->face);
        deg[E->origin]++;
    }
    for (f = 0; f < h->face_count; ++f) {
        int e0 = h->face_edge[f], k = 0;
        mk_vec3 nrm = h->planes[f].normal;
        MK_ASSERT_NEAR(mk_v3_len(nrm), 1, 8 * MK_REAL_EPSILON);
        e = e0;
        do {
            /* Planar; convex: every vertex of the face is on the inner side
             * of each edge's line, within tol grown by how far the vertex is
             * from the edge relative to its length (a short edge's direction
             * is only known to about tol / length), which also catches a loop
             * doubling back; and not coplanar with the neighbour across the
             * edge: some vertex of one face is clearly below the other's plane. */
            mk_vec3 a = h->vertices[h->edges[e].origin], b = h->vertices[h->edges[h->edges[e].next].origin];
            mk_vec3 in = mk_v3_normalize(mk_v3_cross(nrm, mk_v3_sub(b, a)));
            double len = (double)mk_v3_dist(a, b);
            int g = h->edges[h->edges[e].twin].face, x = e0;
            CHECK(h->edges[e].face == f);
            REQUIRE(fabs(face_dist(h, f, a)) <= tol, "face %d vertex off its plane by %g > %g", f, face_dist(h, f, a), tol);
            do {
                mk_vec3 p = h->vertices[h->edges[x].origin];
                double s = (double)mk_v3_dot(in, mk_v3_sub(p, a));
                REQUIRE(s >= -tol * (1 + (double)mk_v3_dist(p, a) / len), "face %d not convex: %g", f, s);
                x = h->edges[x].next;
            } while (x != e0);
            REQUIRE(coplanar_ok || fmin(lowest_vertex(h, f, g), lowest_vertex(h, g, f)) < -(double)h->tolerance, "faces %d and %d are coplanar", f, g);
            ++k;
            e = h->edges[e].next;
        } while (e != e0 && k <= h->edge_count);
        CHECK(k >= 3);
        total += k;
    }
    ck_assert_int_eq(total, h->edge_count); /* every half-edge in exactly one loop */

    /* Vertex fans: vertex_edge leaves its vertex and the fan closes over all its
     * edges; a vertex touches at least three faces (no redundant vertices).
     * The adjacency lists (what the support walk reads) are the fans' far
     * ends, in fan order, back to back. */
    CHECK(h->adjacency[0] == h->vertex_count + 1);
    for (v = 0; v < h->vertex_count; ++v) {
        int e0 = h->vertex_edge[v], k = 0;
        CHECK(h->edges[e0].origin == v);
        CHECK(h->adjacency[v + 1] - h->adjacency[v] == deg[v]);
        e = e0;
        do {
            CHECK(h->edges[e].origin == v);
            CHECK(h->adjacency[h->adjacency[v] + k] == h->edges[h->edges[e].twin].origin);
            e = h->edges[h->edges[e].twin].next;
            ++k;
        } while (e != e0 && k <= h->edge_count);
        CHECK(k == deg[v]);
        CHECK(k >= 3);
    }
    CHECK(h->adjacency[h->vertex_count] == h->vertex_count + 1 + h->edge_count);
    for (i = 0; i < 6; ++i) { /* the axis-extreme vertices after the lists */
        mk_real s = i & 1 ? -1 : 1;
        mk_vec3 d = mk_v3(i / 2 == 0 ? s : 0, i / 2 == 1 ? s : 0, i / 2 == 2 ? s : 0);
        int x = h->adjacency[h->adjacency[h->vertex_count] + i];
        CHECK(x >= 0 && x < h->vertex_count);
        for (v = 0; v < h->vertex_count; ++v) CHECK(mk_v3_dot(d, h->vertices[v]) <= mk_v3_dot(d, h->vertices[x]));
    }

    /* Every input point is inside every face plane. */
    for (f = 0; f < h->face_count; ++f)
        for (i = 0; i < n; ++i)
            REQUIRE(face_dist(h, f, pts[i]) <= tol, "point %d above face %d by %g > %g", i, f, face_dist(h, f, pts[i]), tol);

    /* Bounds, radii, centroid inside with inner radius = nearest plane. */
    {
        mk_vec3 lo = h->vertices[0], hi = h->vertices[0];
        double rin = 1e300, rout = 0;
        for (v = 0; v < h->vertex_count; ++v) {
            lo = mk_v3_min(lo, h->vertices[v]);
            hi = mk_v3_max(hi, h->vertices[v]);
            rout = fmax(rout, (double)mk_v3_dist(h->vertices[v], h->centroid));
        }
        for (f = 0; f < h->face_count; ++f) rin = fmin(rin, -face_dist(h, f, h->centroid));
        MK_ASSERT_V3_NEAR(h->bounds.lo, lo, 0);
        MK_ASSERT_V3_NEAR(h->bounds.hi, hi, 0);
        MK_ASSERT_NEAR(h->outer_radius, rout, tol);
        MK_ASSERT_NEAR(h->inner_radius, rin, tol);
        ck_assert(h->inner_radius > 0);
    }
    free(deg);
    free(sorted);
}

/* Centroid of the solid by a route independent of the library's: the
 * divergence theorem over the faces, fanned from each face's first vertex, in
 * long double, relative to vertex 0 (so an offset cloud stays well conditioned). */
static mk_vec3 solid_centroid(const mk_hull *h)
{
    long double vol = 0, c[3] = {0, 0, 0};
    mk_vec3 o = h->vertices[0];
    int f;
    for (f = 0; f < h->face_count; ++f) {
        int e0 = h->face_edge[f], e = h->edges[e0].next;
        mk_vec3 a = h->vertices[h->edges[e0].origin];
        long double ax = (long double)a.x - o.x, ay = (long double)a.y - o.y, az = (long double)a.z - o.z;
        while (h->edges[e].next != e0) {
            mk_vec3 b = h->vertices[h->edges[e].origin], d = h->vertices[h->edges[h->edges[e].next].origin];
            long double bx = (long double)b.x - o.x, by = (long double)b.y - o.y, bz = (long double)b.z - o.z;
            long double dx = (long double)d.x - o.x, dy = (long double)d.y - o.y, dz = (long double)d.z - o.z;
            long double t = ax * (by * dz - bz * dy) - ay * (bx * dz - bz * dx) + az * (bx * dy - by * dx);
            vol += t;
            c[0] += t * (ax + bx + dx);
            c[1] += t * (ay + by + dy);
            c[2] += t * (az + bz + dz);
            e = h->edges[e].next;
        }
    }
    return mk_v3((mk_real)(o.x + c[0] / (4 * vol)), (mk_real)(o.y + c[1] / (4 * vol)), (mk_real)(o.z + c[2] / (4 * vol)));
}

static mk_hull *make_ok(const mk_vec3 *p, int n, int coplanar_ok)
{
    mk_hull *h = NULL;
    MK_ASSERT_STATUS(mk_hull_create(p, n, NULL, &h), MK_OK);
    ck_assert_ptr_nonnull(h);
    check_hull(h, p, n, coplanar_ok);
    return h;
}

/* ---- construction tests -------------------------------------------------------------- */

START_TEST(cube_with_face_centres_and_edge_midpoints)
{
    /* 27 lattice points of {-1,0,1}^3 minus the centre: 8 corners, 6 face
     * centres, 12 edge midpoints. The hull is the cube: exactly 8 vertices, 6
     * quadrilaterals, 12 edges, whatever the input order, rotated or not. */
    mk_vec3 p[26], q[26];
    mk_rng r = {11};
    int n = 0, x, y, z, trial, f;
    for (x = -1; x <= 1; ++x)
        for (y = -1; y <= 1; ++y)
            for (z = -1; z <= 1; ++z)
                if (x || y || z) p[n++] = mk_v3(x, y, z);
    for (trial = 0; trial < 200; ++trial) {
        mk_hull *h;
        mk_quat rot = trial < 100 ? mk_quat_identity() : mk_rng_quat(&r);
        mk_vec3 off = trial < 50 ? mk_v3_zero() : mk_rng_v3(&r, -10, 10);
        int i;
        shuffle(&r, p, n);
        for (i = 0; i < n; ++i) q[i] = mk_v3_add(mk_quat_rotate(rot, p[i]), off);
        h = make_ok(q, n, 0);
        ck_assert_int_eq(h->vertex_count, 8);
        ck_assert_int_eq(h->face_count, 6);
        ck_assert_int_eq(h->edge_count, 24);
        for (f = 0; f < 6; ++f) {
            int e = h->face_edge[f], k = 0;
            do { e = h->edges[e].next; ++k; } while (e != h->face_edge[f]);
            ck_assert_int_eq(k, 4);
        }
        MK_ASSERT_V3_NEAR(h->centroid, off, 1e3 * MK_REAL_EPSILON * 10);
        MK_ASSERT_NEAR(h->inner_radius, 1, 1e3 * MK_REAL_EPSILON * 10);
        MK_ASSERT_NEAR(h->outer_radius, sqrt(3.0), 1e3 * MK_REAL_EPSILON * 10);
        mk_hull_destroy(h);
    }
}
END_TEST

START_TEST(box_surface_clouds)
{
    /* Many exactly coplanar points per side. With the corners the hull is the
     * box; without them every side still comes out as one polygon. */
    mk_rng r = {12};
    mk_vec3 *p = malloc(4096 * sizeof(mk_vec3));
    int sizes[] = {8, 20, 100, 1000, 4096}, s, rep;
    for (s = 0; s < 5; ++s)
        for (rep = 0; rep < 3; ++rep) {
            int n = sizes[s];
            mk_vec3 hx = mk_v3((mk_real)mk_rng_range(&r, 0.1, 3), (mk_real)mk_rng_range(&r, 0.1, 3), (mk_real)mk_rng_range(&r, 0.1, 3));
            mk_hull *h;
            cloud_box_surface(&r, p, n, hx, 1);
            shuffle(&r, p, n);
            h = make_ok(p, n, 0);
            ck_assert_int_eq(h->vertex_count, 8);
            ck_assert_int_eq(h->face_count, 6);
            ck_assert_int_eq(h->edge_count, 24);
            MK_ASSERT_V3_NEAR(h->centroid, mk_v3_zero(), 64 * MK_REAL_EPSILON);
            mk_hull_destroy(h);
            if (n >= 20) {
                cloud_box_surface(&r, p, n, hx, 0);
                h = make_ok(p, n, 0);
                mk_hull_destroy(h);
            }
        }
    free(p);
}
END_TEST

static int face_vertex_count(const mk_hull *h, int f)
{
    int e0 = h->face_edge[f], e = e0, n = 0;
    do ++n, e = h->edges[e].next;
    while (e != e0);
    return n;
}

START_TEST(cylinder_clouds_get_polygon_caps)
{
    /* k points on each of two circles (a prism around a cylinder), rotated
     * and moved so the points of a cap are coplanar only to rounding: the
     * caps must come out as one k-gon each (not a fan of triangles that a
     * resting hull's contact face would flip between) and the sides as k
     * quadrilaterals, every vertex kept. */
    mk_rng r = {15};
    int ks[] = {3, 5, 8, 16, 33, 64}, t, rep;
    for (t = 0; t < 6; ++t)
        for (rep = 0; rep < 8; ++rep) {
            int k = ks[t], i, f, caps = 0, quads = 0;
            mk_vec3 p[128];
            mk_quat q = rep == 0 ? mk_quat_identity() : mk_rng_quat(&r);
            mk_vec3 off = rep < 4 ? mk_v3_zero() : mk_rng_v3(&r, -20, 20), axis = mk_quat_rotate(q, mk_v3(0, 0, 1));
            double radius = mk_rng_range(&r, 0.05, 2), hh = mk_rng_range(&r, 0.01, 2), phase = mk_rng_unit(&r);
            mk_hull *h;
            for (i = 0; i < k; ++i) {
                double a = 2 * 3.14159265358979323846 * (i + phase) / k;
                mk_vec3 c = mk_v3((mk_real)(radius * cos(a)), (mk_real)(radius * sin(a)), 0);
                p[2 * i] = mk_v3_add(mk_quat_rotate(q, mk_v3(c.x, c.y, (mk_real)hh)), off);
                p[2 * i + 1] = mk_v3_add(mk_quat_rotate(q, mk_v3(c.x, c.y, (mk_real)-hh)), off);
            }
            shuffle(&r, p, 2 * k);
            h = make_ok(p, 2 * k, 0);
            ck_assert_int_eq(h->vertex_count, 2 * k);
            ck_assert_int_eq(h->face_count, k + 2);
            for (f = 0; f < h->face_count; ++f) {
                int n = face_vertex_count(h, f);
                mk_real along = mk_v3_dot(h->planes[f].normal, axis);
                if (n == k && mk_fabs_(mk_fabs_(along) - 1) < 1e3 * MK_REAL_EPSILON) ++caps;
                else if (n == 4 && mk_fabs_(along) < 1e3 * MK_REAL_EPSILON) ++quads;
            }
            ck_assert_int_eq(caps, 2);
            ck_assert_int_eq(quads, k);
            mk_hull_destroy(h);
        }
}
END_TEST

START_TEST(random_clouds)
{
    /* Ball, sphere, ellipsoids up to 10:1, 4 ... 4096 points, some offset far
     * from the origin; the centroid checked against an independent route. */
    mk_rng r = {13};
    mk_vec3 *p = malloc(4096 * sizeof(mk_vec3));
    int sizes[] = {4, 5, 8, 16, 32, 128, 512, 4096}, s, kind;
    for (s = 0; s < 8; ++s)
        for (kind = 0; kind < 5; ++kind) {
            int n = sizes[s], i;
            mk_hull *h;
            mk_vec3 c, off = kind == 4 ? mk_v3(1e3, -2e3, 5e2) : mk_v3_zero();
            switch (kind) {
            case 0: cloud_ball(&r, p, n, 1); break;
            case 1: cloud_ellipsoid(&r, p, n, mk_v3(1, 1, 1)); break;
            case 2: cloud_ellipsoid(&r, p, n, mk_v3(10, 1, 3)); break;
            case 3: cloud_ellipsoid(&r, p, n, mk_v3(0.1, 1, 0.5)); break;
            default: cloud_ellipsoid(&r, p, n, mk_v3(2, 3, 1)); break;
            }
            for (i = 0; i < n; ++i) p[i] = mk_v3_add(p[i], off);
            h = make_ok(p, n, NOISY_COPLANAR_OK);
            /* Points on a smooth convex surface are all vertices; in float a
             * few of thousands come within the tolerance of their neighbours. */
            if (kind == 1 || kind == 2 || kind == 3) {
                ck_assert_int_le(h->vertex_count, n);
                ck_assert_int_ge(h->vertex_count, NOISY_COPLANAR_OK ? n - n / 100 : n);
            }
            c = solid_centroid(h);
            MK_ASSERT_V3_NEAR(h->centroid, c, 1e4 * MK_REAL_EPSILON * (1 + mk_v3_max_abs(off)));
            mk_hull_destroy(h);
        }
    free(p);
}
END_TEST

START_TEST(duplicates_and_interior_points)
{
    /* Each point three times plus points inside: the same hull as the points alone. */
    mk_rng r = {14};
    mk_vec3 p[600];
    int rep;
    for (rep = 0; rep < 20; ++rep) {
        mk_hull *a, *b;
        int i;
        cloud_ellipsoid(&r, p, 100, mk_v3(1, 2, 3));
        a = make_ok(p, 100, 0);
        for (i = 0; i < 100; ++i) p[100 + i] = p[200 + i] = p[i];
        for (i = 300; i < 600; ++i) p[i] = mk_v3_scale(p[i - 300], (mk_real)mk_rng_range(&r, 0, 0.99));
        shuffle(&r, p, 600);
        b = make_ok(p, 600, 0);
        ck_assert_int_eq(a->vertex_count, b->vertex_count);
        ck_assert_int_eq(a->face_count, b->face_count);
        ck_assert_int_eq(a->edge_count, b->edge_count);
        MK_ASSERT_V3_NEAR(a->centroid, b->centroid, 1e3 * MK_REAL_EPSILON);
        mk_hull_destroy(a);
        mk_hull_destroy(b);
    }
}
END_TEST

START_TEST(nearly_flat_and_thin_clouds)
{
    /* Flat boxes and rods at extreme aspect ratios are still valid hulls. */
    mk_rng r = {15};
    mk_vec3 p[200];
    mk_vec3 dims[] = {{1, 1, 1e-3}, {100, 0.01, 0.01}, {1e-3, 1e-3, 1e-3}, {1e4, 1e4, 1e4}};
    int d, rep;
    for (d = 0; d < 4; ++d)
        for (rep = 0; rep < 10; ++rep) {
            mk_hull *h;
            int i;
            mk_quat q = mk_rng_quat(&r);
            cloud_box_surface(&r, p, 200, dims[d], 1);
            for (i = 0; i < 200; ++i) p[i] = mk_quat_rotate(q, p[i]);
            h = make_ok(p, 200, NOISY_COPLANAR_OK);
            /* In float a surface point lands within a few tolerances of an
             * edge, but more than one off it, about once per 200 points: it
             * must stay a vertex, splitting a side. In double, never. */
            if (!NOISY_COPLANAR_OK) {
                ck_assert_int_eq(h->vertex_count, 8);
                ck_assert_int_eq(h->face_count, 6);
            }
            mk_hull_destroy(h);
        }
}
END_TEST

/* ---- bad input ---------------------------------------------------------------------- */

typedef struct count_alloc { int allocs, frees, fail_at; size_t live; } count_alloc;

static void *ca_alloc(void *ctx, size_t size, size_t align)
{
    count_alloc *c = (count_alloc *)ctx;
    (void)align;
    if (c->allocs++ == c->fail_at) return NULL;
    c->live += size;
    return malloc(size);
}

static void ca_free(void *ctx, void *ptr, size_t size)
{
    count_alloc *c = (count_alloc *)ctx;
    c->frees++;
    c->live -= size;
    free(ptr);
}

START_TEST(degenerate_inputs)
{
    mk_rng r = {16};
    mk_vec3 p[300];
    mk_hull *h = (mk_hull *)&r; /* must be set to NULL on failure */
    int i;
    mk_vec3 a = mk_v3(0.3, -1.2, 2), u = mk_v3_normalize(mk_v3(1, 2, -0.5)), w = mk_v3_normalize(mk_v3(-2, 0.25, 1));
    for (i = 0; i < 4; ++i) p[i] = mk_v3(i & 1, (i >> 1) & 1, i == 3);
    for (i = 0; i < 4; ++i) {
        MK_ASSERT_STATUS(mk_hull_create(p, i, NULL, &h), MK_ERR_DEGENERATE);
        ck_assert_ptr_null(h);
    }
    MK_ASSERT_STATUS(mk_hull_create(p, -5, NULL, &h), MK_ERR_DEGENERATE);
    /* All one point. */
    for (i = 0; i < 50; ++i) p[i] = a;
    MK_ASSERT_STATUS(mk_hull_create(p, 50, NULL, &h), MK_ERR_DEGENERATE);
    /* Collinear, with rounding in the coordinates. */
    for (i = 0; i < 100; ++i) p[i] = mk_v3_mad(a, (mk_real)mk_rng_range(&r, -5, 5), u);
    MK_ASSERT_STATUS(mk_hull_create(p, 100, NULL, &h), MK_ERR_DEGENERATE);
    /* Coplanar in a tilted plane, with rounding. */
    for (i = 0; i < 300; ++i) p[i] = mk_v3_mad(mk_v3_mad(a, (mk_real)mk_rng_range(&r, -5, 5), u), (mk_real)mk_rng_range(&r, -5, 5), w);
    MK_ASSERT_STATUS(mk_hull_create(p, 300, NULL, &h), MK_ERR_DEGENERATE);
    /* Four coplanar points exactly. */
    for (i = 0; i < 4; ++i) p[i] = mk_v3(i & 1, (i >> 1) & 1, 0);
    MK_ASSERT_STATUS(mk_hull_create(p, 4, NULL, &h), MK_ERR_DEGENERATE);
    ck_assert_ptr_null(h);
    /* But a tetrahedron is fine. */
    for (i = 0; i < 4; ++i) p[i] = mk_v3(i & 1, (i >> 1) & 1, i == 3);
    MK_ASSERT_STATUS(mk_hull_create(p, 4, NULL, &h), MK_OK);
    check_hull(h, p, 4, 0);
    ck_assert_int_eq(h->face_count, 4);
    mk_hull_destroy(h);
}
END_TEST

START_TEST(bad_arguments)
{
    mk_vec3 p[8];
    mk_vec3 *big = calloc(MK_HULL_MAX_POINTS + 1, sizeof(mk_vec3));
    mk_hull *h = NULL;
    mk_allocator bad = {NULL, NULL, NULL};
    int i;
    for (i = 0; i < 8; ++i) p[i] = mk_v3(i & 1, (i >> 1) & 1, (i >> 2) & 1);
    MK_ASSERT_STATUS(mk_hull_create(NULL, 8, NULL, &h), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_hull_create(p, 8, NULL, NULL), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_hull_create(p, 8, &bad, &h), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_hull_create(big, MK_HULL_MAX_POINTS + 1, NULL, &h), MK_ERR_CAPACITY);
    p[5].y = (mk_real)NAN;
    MK_ASSERT_STATUS(mk_hull_create(p, 8, NULL, &h), MK_ERR_NOT_FINITE);
    p[5].y = (mk_real)INFINITY;
    MK_ASSERT_STATUS(mk_hull_create(p, 8, NULL, &h), MK_ERR_NOT_FINITE);
    p[5].y = -MK_REAL_MAX; /* finite but far beyond the size limit */
    MK_ASSERT_STATUS(mk_hull_create(p, 8, NULL, &h), MK_ERR_BAD_SIZE);
    ck_assert_ptr_null(h);
    mk_hull_destroy(NULL); /* no-op */
    free(big);
}
END_TEST

START_TEST(allocator_failures_leak_nothing)
{
    mk_rng r = {17};
    mk_vec3 p[500];
    int fail;
    cloud_ball(&r, p, 500, 2);
    for (fail = 0; fail < 3; ++fail) {
        count_alloc c = {0, 0, 0, 0};
        mk_allocator al;
        mk_hull *h = NULL;
        mk_status st;
        c.fail_at = fail;
        al.alloc = ca_alloc;
        al.free = ca_free;
        al.ctx = &c;
        st = mk_hull_create(p, 500, &al, &h);
        if (fail < 2) {
            MK_ASSERT_STATUS(st, MK_ERR_OUT_OF_MEMORY);
            ck_assert_ptr_null(h);
        } else {
            /* Two allocations in all: working memory (freed) and the hull. */
            MK_ASSERT_STATUS(st, MK_OK);
            ck_assert_int_eq(c.allocs, 2);
            ck_assert_int_eq(c.frees, 1);
            ck_assert_uint_eq(c.live, h->bytes);
            check_hull(h, p, 500, 0);
            mk_hull_destroy(h);
        }
        ck_assert_int_eq(c.allocs - (fail < c.allocs ? 1 : 0), c.frees);
        ck_assert_uint_eq(c.live, 0);
    }
}
END_TEST

/* ---- support -------------------------------------------------------------------------- */

static int scan_support(const mk_hull *h, mk_vec3 d)
{
    int v, best = 0;
    for (v = 1; v < h->vertex_count; ++v)
        if (mk_v3_dot(d, h->vertices[v]) > mk_v3_dot(d, h->vertices[best])) best = v;
    return best;
}

/* The support index must reach the true maximum from any start, along random
 * directions and along the directions that tie: face normals (the whole face
 * ties), edge bisectors (both ends tie) and the coordinate axes. */
static void check_support(mk_rng *r, const mk_hull *h)
{
    int i, f, e;
    double tol = 8 * (double)h->tolerance;
    for (i = 0; i < 200 + 3 * h->face_count + h->edge_count / 2 + 6; ++i) {
        mk_vec3 d;
        int got, want, start = (int)(mk_rng_unit(r) * (h->vertex_count + 1)) - 1;
        if (i < 200) d = mk_rng_dir(r);
        else if ((f = i - 200) < 3 * h->face_count) d = h->planes[f % h->face_count].normal;
        else if ((e = i - 200 - 3 * h->face_count) < h->edge_count / 2) {
            const mk_hull_edge *E = &h->edges[2 * e];
            d = mk_v3_add(h->planes[E->face].normal, h->planes[h->edges[E->twin].face].normal);
        } else {
            int a = i - 200 - 3 * h->face_count - h->edge_count / 2;
            d = mk_v3(a == 0 ? 1 : a == 1 ? -1 : 0, a == 2 ? 1 : a == 3 ? -1 : 0, a == 4 ? 1 : a == 5 ? -1 : 0);
        }
        got = mk_hull_support_index(h, d, start);
        want = scan_support(h, d);
        REQUIRE(got >= 0 && got < h->vertex_count, "index %d out of range", got);
        REQUIRE((double)mk_v3_dot(d, h->vertices[got]) >= (double)mk_v3_dot(d, h->vertices[want]) - tol,
                      "support %d (%.17g) short of %d (%.17g)", got, (double)mk_v3_dot(d, h->vertices[got]), want,
                      (double)mk_v3_dot(d, h->vertices[want]));
    }
}

START_TEST(support_index_finds_the_maximum)
{
    mk_rng r = {18};
    mk_vec3 *p = malloc(4096 * sizeof(mk_vec3));
    int sizes[] = {4, 8, 12, 16, 24, 32, 64, 128, 1024, 4096}, s;
    for (s = 0; s < 10; ++s) {
        mk_hull *h;
        cloud_ellipsoid(&r, p, sizes[s], mk_v3(1, 10, 3));
        h = make_ok(p, sizes[s], NOISY_COPLANAR_OK);
        check_support(&r, h);
        mk_hull_destroy(h);
        cloud_box_surface(&r, p, sizes[s] < 8 ? 8 : sizes[s], mk_v3(1, 2, 3), 1);
        h = make_ok(p, sizes[s] < 8 ? 8 : sizes[s], 0);
        check_support(&r, h);
        mk_hull_destroy(h);
    }
    free(p);
}
END_TEST

/* The scan (hulls of up to MK_HULL_COLD_SCAN_MAX vertices without a hint)
 * reads the coordinate rows; they must hold the vertices, padded with vertex
 * 0, and the scan must answer exactly the first of the highest vertices, as a
 * plain loop over the vertex array does, for every count modulo 4, on
 * random directions and on the axes (where a box surface has many ties). */
START_TEST(scan_support_is_exact)
{
    mk_rng r = {19};
    mk_vec3 p[40];
    int n, i, k;
    for (n = 4; n <= 36; ++n) {
        for (k = 0; k < 2; ++k) {
            mk_hull *h;
            int stride;
            if (k == 0) cloud_ellipsoid(&r, p, n, mk_v3(1, 10, 3));
            else cloud_box_surface(&r, p, n < 8 ? 8 : n, mk_v3(1, 2, 3), 1);
            h = make_ok(p, k == 0 ? n : (n < 8 ? 8 : n), k == 0 ? NOISY_COPLANAR_OK : 0);
            stride = (h->vertex_count + 3) / 4 * 4;
            for (i = 0; i < stride; ++i) {
                mk_vec3 v = h->vertices[i < h->vertex_count ? i : 0];
                REQUIRE(h->coords[i] == v.x && h->coords[stride + i] == v.y && h->coords[2 * stride + i] == v.z,
                        "coordinate rows differ from vertex %d", i);
            }
            for (i = 0; i < 106; ++i) {
                int a = i - 100;
                mk_vec3 d = i < 100 ? mk_rng_dir(&r)
                                    : mk_v3(a == 0 ? 1 : a == 1 ? -1 : 0, a == 2 ? 1 : a == 3 ? -1 : 0, a == 4 ? 1 : a == 5 ? -1 : 0);
                int got = mk_hull_support_index(h, d, -1), want = scan_support(h, d);
                if (h->vertex_count <= MK_HULL_COLD_SCAN_MAX)
                    REQUIRE(got == want, "%d vertices: scan answers %d, the first maximum is %d", h->vertex_count, got, want);
                else
                    REQUIRE(got >= 0 && got < h->vertex_count && mk_v3_dot(d, h->vertices[got]) >= mk_v3_dot(d, h->vertices[want]),
                            "%d vertices: %d is not a maximum", h->vertex_count, got);
            }
            mk_hull_destroy(h);
        }
    }
}
END_TEST

START_TEST(hull_shape_support_and_aabb)
{
    /* A hull goes through mk_shape_hull; its support (with rounding) is the
     * best vertex pushed out by the radius, and its world AABB is the
     * brute-force box of the transformed vertices grown by the radius. */
    mk_rng r = {19};
    mk_vec3 p[256];
    int rep, i, k;
    for (rep = 0; rep < 10; ++rep) {
        mk_hull *h;
        mk_shape s;
        mk_real rad = rep % 2 ? (mk_real)0.25 : 0;
        cloud_ellipsoid(&r, p, 256, mk_v3(3, 1, 0.5));
        h = make_ok(p, 256, 0);
        MK_ASSERT_STATUS(mk_shape_hull(h, rad, &s), MK_OK);
        MK_ASSERT_STATUS(mk_shape_validate(&s), MK_OK);
        for (i = 0; i < 100; ++i) {
            mk_vec3 d = mk_v3_scale(mk_rng_dir(&r), (mk_real)mk_rng_range(&r, 0.1, 10));
            mk_vec3 sp = mk_shape_support(&s, d), u = mk_v3_normalize(d);
            int want = scan_support(h, d);
            MK_ASSERT_NEAR(mk_v3_dot(u, sp), mk_v3_dot(u, h->vertices[want]) + rad, 64 * MK_REAL_EPSILON * 3);
        }
        for (i = 0; i < 50; ++i) {
            mk_transform xf = mk_transform_make(mk_rng_v3(&r, -100, 100), mk_rng_quat(&r));
            mk_mat3 R = mk_mat3_from_quat(xf.q);
            mk_aabb b;
            mk_vec3 lo = mk_v3(MK_REAL_MAX, MK_REAL_MAX, MK_REAL_MAX), hi = mk_v3_neg(lo);
            MK_ASSERT_STATUS(mk_shape_aabb(&s, xf, &b), MK_OK);
            for (k = 0; k < h->vertex_count; ++k) {
                mk_vec3 w = mk_v3_add(mk_mat3_mul_v3(R, h->vertices[k]), xf.p);
                lo = mk_v3_min(lo, w);
                hi = mk_v3_max(hi, w);
            }
            MK_ASSERT_V3_NEAR(b.lo, mk_v3_sub(lo, mk_v3(rad, rad, rad)), 256 * MK_REAL_EPSILON * 100);
            MK_ASSERT_V3_NEAR(b.hi, mk_v3_add(hi, mk_v3(rad, rad, rad)), 256 * MK_REAL_EPSILON * 100);
        }
        mk_hull_destroy(h);
    }
}
END_TEST

static Suite *hull_suite(void)
{
    Suite *s = suite_create("hull");
    TCase *tc = tcase_create("quickhull");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, cube_with_face_centres_and_edge_midpoints);
    tcase_add_test(tc, box_surface_clouds);
    tcase_add_test(tc, cylinder_clouds_get_polygon_caps);
    tcase_add_test(tc, random_clouds);
    tcase_add_test(tc, duplicates_and_interior_points);
    tcase_add_test(tc, nearly_flat_and_thin_clouds);
    tcase_add_test(tc, degenerate_inputs);
    tcase_add_test(tc, bad_arguments);
    tcase_add_test(tc, allocator_failures_leak_nothing);
    tcase_add_test(tc, support_index_finds_the_maximum);
    tcase_add_test(tc, scan_support_is_exact);
    tcase_add_test(tc, hull_shape_support_and_aabb);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return mk_test_run(hull_suite()); }

/* test_sat.c: the separating-axis test (src/sat.h) against a brute-force SAT
 * in long double and against the oracle's penetration depth; the specialised
 * box-box path against the generic one; early stop; hysteresis; the box view. */
#include <stdlib.h>
#include <string.h>

#include "minko/manifold.h"
#include "minko/shape.h"
#include "manifold_internal.h"
#include "polytope.h"
#include "sat.h"
#include "support/mk_test.h"
#include "support/oracle.h"

/* Check records a checkpoint on every passing ck_assert; loops test first. */
#define REQUIRE(cond, ...) do { if (!(cond)) ck_abort_msg(__VA_ARGS__); } while (0)

typedef long double ld;

/* ---- brute-force SAT, long double ------------------------------------------------ *
 * Candidate axes: every face normal of A and of B, from the face's own
 * vertices (Newell's formula), and the cross product of every edge of A with
 * every edge of B. The separation along an axis n, taken both ways, is
 * min over B's vertices of n.b - max over A's vertices of n.a. For
 * penetrating cores the largest such separation is minus the depth (the faces
 * of A - B are among the candidates, and no axis does better). For separated
 * cores it is at least what SAT reports (SAT keeps only faces of A - B). */

typedef struct lpoly { int n; ld (*v)[3]; } lpoly;

static ld sep_along(const ld n[3], const lpoly *A, const lpoly *B)
{
    ld amax = -1e300L, bmin = 1e300L;
    int i;
    for (i = 0; i < A->n; ++i) amax = fmaxl(amax, n[0] * A->v[i][0] + n[1] * A->v[i][1] + n[2] * A->v[i][2]);
    for (i = 0; i < B->n; ++i) bmin = fminl(bmin, n[0] * B->v[i][0] + n[1] * B->v[i][1] + n[2] * B->v[i][2]);
    return bmin - amax;
}

static ld both_ways(ld n[3], const lpoly *A, const lpoly *B)
{
    ld s = sep_along(n, A, B), m[3];
    m[0] = -n[0], m[1] = -n[1], m[2] = -n[2];
    return fmaxl(s, sep_along(m, A, B));
}

/* B's vertices in A's frame, x_A = R x_B + t, exactly as mk_sat is told. */
static void to_lpoly(const mk_hull *h, const mk_mat3 *R, mk_vec3 t, lpoly *out)
{
    int i;
    out->n = h->vertex_count;
    out->v = malloc((size_t)h->vertex_count * sizeof *out->v);
    for (i = 0; i < h->vertex_count; ++i) {
        ld x = h->vertices[i].x, y = h->vertices[i].y, z = h->vertices[i].z;
        if (!R) {
            out->v[i][0] = x, out->v[i][1] = y, out->v[i][2] = z;
        } else {
            out->v[i][0] = (ld)R->c0.x * x + (ld)R->c1.x * y + (ld)R->c2.x * z + t.x;
            out->v[i][1] = (ld)R->c0.y * x + (ld)R->c1.y * y + (ld)R->c2.y * z + t.y;
            out->v[i][2] = (ld)R->c0.z * x + (ld)R->c1.z * y + (ld)R->c2.z * z + t.z;
        }
    }
}

/* faces_only: the face normals alone, outward from A and into B only, the
 * axes SAT itself tries first (a lower bound of its answer in every case). */
static ld brute_sat(const mk_hull *a, const mk_hull *b, const mk_mat3 *R, mk_vec3 t, int faces_only)
{
    lpoly A, B;
    const mk_hull *hs[2];
    const lpoly *ps[2];
    ld best = -1e300L;
    int k, f, i, j;
    to_lpoly(a, NULL, t, &A);
    to_lpoly(b, R, t, &B);
    hs[0] = a, hs[1] = b, ps[0] = &A, ps[1] = &B;
    for (k = 0; k < 2; ++k)
        for (f = 0; f < hs[k]->face_count; ++f) {
            const mk_hull *h = hs[k];
            int e0 = h->face_edge[f], e = e0;
            ld n[3] = {0, 0, 0}, l;
            do {
                const ld *p = ps[k]->v[h->edges[e].origin], *q = ps[k]->v[h->edges[h->edges[e].next].origin];
                n[0] += (p[1] - q[1]) * (p[2] + q[2]);
                n[1] += (p[2] - q[2]) * (p[0] + q[0]);
                n[2] += (p[0] - q[0]) * (p[1] + q[1]);
                e = h->edges[e].next;
            } while (e != e0);
            l = sqrtl(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) * (k ? -1 : 1); /* B's faces negated: from A to B */
            n[0] /= l, n[1] /= l, n[2] /= l;
            best = fmaxl(best, faces_only ? sep_along(n, &A, &B) : both_ways(n, &A, &B));
        }
    for (i = 0; i < a->edge_count && !faces_only; ++i) {
        const ld *p0 = A.v[a->edges[i].origin], *p1 = A.v[a->edges[a->edges[i].twin].origin];
        ld ea[3];
        ea[0] = p1[0] - p0[0], ea[1] = p1[1] - p0[1], ea[2] = p1[2] - p0[2];
        for (j = 0; j < b->edge_count; ++j) {
            const ld *q0 = B.v[b->edges[j].origin], *q1 = B.v[b->edges[b->edges[j].twin].origin];
            ld eb[3], n[3], l, la, lb;
            eb[0] = q1[0] - q0[0], eb[1] = q1[1] - q0[1], eb[2] = q1[2] - q0[2];
            n[0] = ea[1] * eb[2] - ea[2] * eb[1];
            n[1] = ea[2] * eb[0] - ea[0] * eb[2];
            n[2] = ea[0] * eb[1] - ea[1] * eb[0];
            l = sqrtl(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            la = sqrtl(ea[0] * ea[0] + ea[1] * ea[1] + ea[2] * ea[2]);
            lb = sqrtl(eb[0] * eb[0] + eb[1] * eb[1] + eb[2] * eb[2]);
            if (!(l > 1e-12L * la * lb)) continue; /* parallel: the face axes cover it */
            n[0] /= l, n[1] /= l, n[2] /= l;
            best = fmaxl(best, both_ways(n, &A, &B));
        }
    }
    free(A.v);
    free(B.v);
    return best;
}

/* Separation along a given unit axis (A's frame), long double. */
static ld brute_along(const mk_hull *a, const mk_hull *b, const mk_mat3 *R, mk_vec3 t, mk_vec3 n)
{
    lpoly A, B;
    ld m[3], s;
    to_lpoly(a, NULL, t, &A);
    to_lpoly(b, R, t, &B);
    m[0] = n.x, m[1] = n.y, m[2] = n.z;
    s = sep_along(m, &A, &B);
    free(A.v);
    free(B.v);
    return s;
}

/* ---- shapes and poses -------------------------------------------------------------- */

static mk_hull *ellipsoid_hull(mk_rng *r, int n, mk_vec3 axes)
{
    mk_vec3 p[128];
    mk_hull *h = NULL;
    int i;
    for (i = 0; i < n; ++i) p[i] = mk_v3_mul(mk_rng_dir(r), axes);
    MK_ASSERT_STATUS(mk_hull_create(p, n, NULL, &h), MK_OK);
    return h;
}

/* The relative pose mk_sat gets from two world poses (as a dispatcher would). */
static void relative(mk_transform xa, mk_transform xb, mk_mat3 *R, mk_vec3 *t)
{
    mk_transform rel = mk_transform_inv_mul(xa, xb);
    *R = mk_mat3_from_quat(mk_quat_normalize(rel.q));
    *t = rel.p;
}

/* Tolerance for SAT values: the error of a plane distance at the shapes'
 * size, 16 ulps of it (measured: under 1 ulp of the size in double). */
static double val_tol(double size) { return 16 * MK_REAL_EPSILON * size; }

/* Checks one query every way it can be checked: against the brute-force SAT
 * (equal when penetrating, no larger when separated, never below the faces
 * alone), the reported axis against the separation actually found along it,
 * the unit normal, and for penetration the oracle's depth. Returns the kind. */
static mk_sat_kind check_query(const mk_hull *a, const mk_hull *b, const mk_mat3 *R, mk_vec3 t, const mk_shape *sa,
                               const mk_shape *sb, double size, double *rel_err)
{
    mk_sat_options o = mk_sat_defaults();
    mk_sat_result res;
    /* Past a few dozen vertices the all-pairs brute force costs seconds; the
     * oracle (its own Gauss-map pruning, independent code) judges those. */
    int big = a->vertex_count + b->vertex_count > 80;
    ld ref = big ? 0 : brute_sat(a, b, R, t, 0), faces = brute_sat(a, b, R, t, 1), along;
    double tol = val_tol(size);
    mk_sat(a, b, R, t, &o, &res);
    REQUIRE(res.complete && res.kind != MK_SAT_NONE, "incomplete or no axis");
    REQUIRE(fabs((double)mk_v3_len(res.normal) - 1) <= 8 * MK_REAL_EPSILON, "normal not unit");
    REQUIRE(res.separation == res.best, "reported axis is not the best without hysteresis");
    along = brute_along(a, b, R, t, res.normal);
    REQUIRE(fabsl(along - (ld)res.best) <= tol, "axis separates by %.17Lg, reported %.17g", along, (double)res.best);
    REQUIRE((ld)res.best >= faces - tol, "best %.17g below the faces' %.17Lg", (double)res.best, faces);
    if (big) {
        mk_oracle_result o2;
        mk_transform xb = mk_transform_make(t, mk_quat_from_mat3(*R));
        ck_assert_ptr_nonnull(sa);
        ck_assert_int_eq(mk_oracle_distance(sa, mk_transform_identity(), sb, xb, &o2), 0);
        if (o2.distance < 0) {
            REQUIRE(fabsl((ld)res.best - o2.distance) <= 64 * MK_REAL_EPSILON * size, "depth %.17g, oracle %.17Lg", (double)-res.best,
                    -o2.distance);
            if (rel_err) *rel_err = fmax(*rel_err, (double)(fabsl((ld)res.best - o2.distance) / -o2.distance));
        } else {
            REQUIRE(res.best > 0 && (ld)res.best <= o2.distance + tol, "separated: SAT %.17g, distance %.17Lg", (double)res.best, o2.distance);
        }
    } else if (ref <= 0) {
        REQUIRE(fabsl((ld)res.best - ref) <= tol, "depth %.17g, brute force %.17Lg", (double)-res.best, -ref);
        if (rel_err && ref < 0) *rel_err = fmax(*rel_err, (double)(fabsl((ld)res.best - ref) / -ref));
        if (sa && sb) { /* the oracle (independent code) agrees on the depth */
            mk_oracle_result o2;
            mk_transform xb = mk_transform_make(t, mk_quat_from_mat3(*R));
            ck_assert_int_eq(mk_oracle_distance(sa, mk_transform_identity(), sb, xb, &o2), 0);
            REQUIRE(fabsl(o2.distance - ref) <= 64 * MK_REAL_EPSILON * size, "oracle %.17Lg, brute %.17Lg", o2.distance, ref);
        }
    } else {
        REQUIRE(res.best > 0 && (ld)res.best <= ref + tol, "separated: SAT %.17g, brute %.17Lg", (double)res.best, ref);
    }
    return res.kind;
}

/* ---- tests ---------------------------------------------------------------------------- */

START_TEST(box_view_matches_manifold_numbering)
{
    /* The view's twins, loops and planes are consistent, and its edge IDs are
     * the manifold's box edge IDs. */
    mk_box_hull bh;
    int e, f, v;
    mk_box_hull_init(&bh, mk_v3(1, 2, 3));
    for (e = 0; e < 24; ++e) {
        const mk_hull_edge *E = &bh.hull.edges[e];
        int o = E->origin, d = bh.hull.edges[E->next].origin;
        ck_assert_int_eq(bh.hull.edges[E->twin].twin, e);
        ck_assert_int_eq(bh.hull.edges[E->twin].origin, d);
        ck_assert_int_eq(E->face, e / 4);
        ck_assert_int_eq(mk_box_hull_edge_id(e), MK_FEATURE_GET_INDEX(mk_box_edge(o, d)));
        ck_assert_int_eq(mk_box_hull_edge_id(e), mk_box_hull_edge_id(E->twin));
    }
    for (f = 0; f < 6; ++f) {
        int x = bh.hull.face_edge[f];
        do {
            MK_ASSERT_NEAR(mk_v3_dot(bh.p[f].normal, bh.v[bh.hull.edges[x].origin]), bh.p[f].offset, 0);
            x = bh.hull.edges[x].next;
        } while (x != bh.hull.face_edge[f]);
        ck_assert_int_eq(f, 2 * (f / 2) + (mk_v3_dot(bh.p[f].normal, mk_v3(1, 1, 1)) > 0));
    }
    for (v = 0; v < 8; ++v) {
        int k, n = bh.hull.adjacency[v + 1] - bh.hull.adjacency[v];
        ck_assert_int_eq(bh.hull.edges[bh.hull.vertex_edge[v]].origin, v);
        ck_assert_int_eq(n, 3); /* the three corners one edge away */
        for (k = 0; k < n; ++k) {
            int w = bh.hull.adjacency[bh.hull.adjacency[v] + k], d = v ^ w;
            ck_assert(d == 1 || d == 2 || d == 4);
        }
    }
    for (v = 0; v < 6; ++v) { /* corner v's axis-extreme entry has the sign of that direction */
        int x = bh.hull.adjacency[bh.hull.adjacency[8] + v];
        ck_assert_int_eq((x >> (v / 2)) & 1, !(v & 1));
    }
}
END_TEST

START_TEST(box_box_random)
{
    /* Random sizes and poses, separated and penetrating: the generic SAT on
     * box views is exact, and the 15-axis path gives the same answer. */
    mk_rng r = {21};
    int i, kinds[4] = {0, 0, 0, 0};
    double rel = 0;
    for (i = 0; i < 400; ++i) {
        mk_vec3 ha = mk_rng_v3(&r, 0.1, 2), hb = mk_rng_v3(&r, 0.1, 2);
        mk_box_hull A, B;
        mk_shape sa, sb;
        mk_mat3 R = mk_mat3_from_quat(mk_rng_quat(&r));
        mk_vec3 t = mk_v3_scale(mk_rng_dir(&r), (mk_real)mk_rng_range(&r, 0, 1.5 * (double)(mk_v3_len(ha) + mk_v3_len(hb))));
        mk_sat_result g, s;
        mk_sat_options o = mk_sat_defaults();
        mk_box_hull_init(&A, ha);
        mk_box_hull_init(&B, hb);
        mk_shape_box(ha, 0, &sa);
        mk_shape_box(hb, 0, &sb);
        kinds[check_query(&A.hull, &B.hull, &R, t, i < 100 ? &sa : NULL, i < 100 ? &sb : NULL,
                          (double)(mk_v3_len(ha) + mk_v3_len(hb)), &rel)]++;
        mk_sat(&A.hull, &B.hull, &R, t, &o, &g);
        mk_sat_box_box(ha, hb, &R, t, &o, &s);
        REQUIRE(fabs((double)(g.best - s.best)) <= val_tol((double)(mk_v3_len(ha) + mk_v3_len(hb))), "box-box %.17g, generic %.17g",
                (double)s.best, (double)g.best);
        REQUIRE(g.kind == s.kind && g.a == s.a && g.b == s.b, "features differ: %d %d %d against %d %d %d", g.kind, g.a, g.b, s.kind,
                s.a, s.b);
        REQUIRE(mk_v3_dist(g.normal, s.normal) <= 64 * MK_REAL_EPSILON, "normals differ");
    }
    /* Every kind of axis came up, edges included. */
    ck_assert_int_gt(kinds[MK_SAT_FACE_A], 20);
    ck_assert_int_gt(kinds[MK_SAT_FACE_B], 20);
    ck_assert_int_gt(kinds[MK_SAT_EDGES], 20);
#if !defined(MK_SINGLE)
    ck_assert_msg(rel <= 1e-12, "largest relative depth error %g", rel);
#endif
}
END_TEST

START_TEST(hull_hull_random)
{
    /* Hulls of 8, 32 and 128 points on ellipsoids up to 10:1, against each
     * other and against boxes, separated and penetrating. */
    mk_rng r = {22};
    int sizes[3] = {8, 32, 128}, reps[3] = {60, 20, 3}, s, i, kinds[4] = {0, 0, 0, 0};
    double rel = 0;
    for (s = 0; s < 3; ++s)
        for (i = 0; i < reps[s]; ++i) {
            mk_hull *a = ellipsoid_hull(&r, sizes[s], mk_rng_v3(&r, 0.1, 1)), *b = ellipsoid_hull(&r, sizes[s], mk_rng_v3(&r, 0.1, 1));
            mk_box_hull bx;
            mk_shape sa, sb, sx;
            mk_mat3 R = mk_mat3_from_quat(mk_rng_quat(&r));
            double size = (double)(a->outer_radius + b->outer_radius);
            mk_vec3 t = mk_v3_scale(mk_rng_dir(&r), (mk_real)mk_rng_range(&r, 0, 1.2 * size));
            mk_vec3 hx = mk_rng_v3(&r, 0.1, 1);
            mk_shape_hull(a, 0, &sa);
            mk_shape_hull(b, 0, &sb);
            mk_shape_box(hx, 0, &sx);
            mk_box_hull_init(&bx, hx);
            kinds[check_query(a, b, &R, t, s != 1 ? &sa : NULL, s != 1 ? &sb : NULL, size, &rel)]++;
            kinds[check_query(&bx.hull, b, &R, t, s != 1 ? &sx : NULL, s != 1 ? &sb : NULL, (double)(mk_v3_len(hx) + b->outer_radius), &rel)]++;
            kinds[check_query(a, &bx.hull, &R, t, &sa, &sx, (double)(a->outer_radius + mk_v3_len(hx)), &rel)]++;
            mk_hull_destroy(a);
            mk_hull_destroy(b);
        }
    ck_assert_int_gt(kinds[MK_SAT_EDGES], 20);
#if !defined(MK_SINGLE)
    ck_assert_msg(rel <= 1e-12, "largest relative depth error %g", rel);
#endif
}
END_TEST

START_TEST(degenerate_gauss_maps)
{
    /* Parallel faces and edges put B's Gauss-map arcs through A's face normals
     * and along A's arcs: every sign test is zero there, the walk gives up
     * and the edge is scanned. Boxes and cube hulls with equal or
     * axis-swapping rotations, generic path, against the brute force. */
    mk_rng r = {26};
    mk_vec3 cube[8];
    mk_hull *ca, *cb;
    int i, k;
    for (k = 0; k < 8; ++k) cube[k] = mk_v3(k & 1 ? 1 : -1, k & 2 ? (mk_real)0.5 : (mk_real)-0.5, k & 4 ? 2 : -2);
    MK_ASSERT_STATUS(mk_hull_create(cube, 8, NULL, &ca), MK_OK);
    for (k = 0; k < 8; ++k) cube[k] = mk_v3(k & 1 ? (mk_real)0.3 : (mk_real)-0.3, k & 2 ? 1 : -1, k & 4 ? (mk_real)0.7 : (mk_real)-0.7);
    MK_ASSERT_STATUS(mk_hull_create(cube, 8, NULL, &cb), MK_OK);
    for (i = 0; i < 200; ++i) {
        static const mk_real quarter[4][4] = {{0, 0, 0, 1}, {0.70710678118654752, 0, 0, 0.70710678118654752},
                                              {0, 0.70710678118654752, 0, 0.70710678118654752}, {0.5, 0.5, 0.5, 0.5}};
        const mk_real *qq = quarter[i % 4];
        mk_mat3 R = mk_mat3_from_quat(mk_quat_normalize(mk_quat_make(qq[0], qq[1], qq[2], qq[3])));
        mk_vec3 t = i < 100 ? mk_rng_v3(&r, -2.5, 2.5) : mk_v3((mk_real)mk_rng_range(&r, -1.5, 1.5), 0, 0);
        mk_box_hull ba, bb;
        mk_shape sa, sb;
        mk_box_hull_init(&ba, mk_v3(1, 0.5, 2));
        mk_box_hull_init(&bb, mk_v3((mk_real)0.3, 1, (mk_real)0.7));
        mk_shape_hull(ca, 0, &sa);
        mk_shape_hull(cb, 0, &sb);
        check_query(ca, cb, &R, t, &sa, &sb, 4, NULL);
        check_query(&ba.hull, &bb.hull, &R, t, NULL, NULL, 4, NULL);
        check_query(ca, &bb.hull, &R, t, NULL, NULL, 4, NULL);
    }
    mk_hull_destroy(ca);
    mk_hull_destroy(cb);
}
END_TEST

/* Exact depth of two boxes in world poses against the oracle. */
static void check_boxes_world(mk_vec3 ha, mk_transform xa, mk_vec3 hb, mk_transform xb, double rel_tol, mk_sat_result *out)
{
    mk_shape sa, sb;
    mk_mat3 R;
    mk_vec3 t;
    mk_oracle_result o;
    mk_sat_options opt = mk_sat_defaults();
    double size = (double)(mk_v3_len(ha) + mk_v3_len(hb));
    mk_shape_box(ha, 0, &sa);
    mk_shape_box(hb, 0, &sb);
    relative(xa, xb, &R, &t);
    mk_sat_box_box(ha, hb, &R, t, &opt, out);
    ck_assert_int_eq(mk_oracle_distance(&sa, xa, &sb, xb, &o), 0);
    if (o.distance < 0) {
        REQUIRE(fabsl((ld)out->best - o.distance) <= rel_tol * -o.distance + val_tol(size), "depth %.17g, oracle %.17Lg",
                (double)-out->best, -o.distance);
    } else {
        REQUIRE(out->best > 0 && (ld)out->best <= o.distance + val_tol(size), "separated: SAT %.17g, distance %.17Lg",
                (double)out->best, o.distance);
    }
}

START_TEST(box_families)
{
    /* Face-to-face parallel boxes, edge-edge crossings, deep penetration,
     * flat plates, thin rods, tiny boxes and a 1e5 offset, each separated and
     * penetrating, against the oracle in world coordinates. The relative pose
     * loses nothing at 1e5: the positions are subtracted before rotating. */
    mk_rng r = {23};
    int fam, i, edges = 0;
    for (fam = 0; fam < 7; ++fam)
        for (i = 0; i < 60; ++i) {
            mk_vec3 ha, hb, off = mk_v3_zero();
            mk_quat qa = mk_rng_quat(&r), qb = mk_rng_quat(&r);
            mk_vec3 dir = mk_rng_dir(&r);
            mk_real scale = 1, gap = (mk_real)mk_rng_range(&r, -0.5, 0.5);
            mk_sat_result res;
            switch (fam) {
            case 0: /* parallel faces: equal rotations, offset along a face normal */
                ha = mk_rng_v3(&r, 0.3, 1), hb = mk_rng_v3(&r, 0.3, 1), qb = qa;
                dir = mk_quat_rotate(qa, mk_v3(0, 0, 1));
                scale = ha.z + hb.z + gap * (mk_real)0.2;
                break;
            case 1: /* crossing edges: long thin boxes at right angles-ish */
                ha = mk_v3(1, 0.1, 0.1), hb = mk_v3(0.1, 1, 0.1);
                scale = (mk_real)mk_rng_range(&r, 0.05, 0.4);
                break;
            case 2: /* deep: centres within half the size */
                ha = mk_rng_v3(&r, 0.5, 1), hb = mk_rng_v3(&r, 0.5, 1);
                scale = (mk_real)mk_rng_range(&r, 0, 0.5);
                break;
            case 3: ha = mk_v3(0.5, 0.5, 0.0005), hb = mk_v3(0.5, 0.5, 0.0005), scale = (mk_real)mk_rng_range(&r, 0, 0.9); break;
            case 4: ha = mk_v3(50, 0.005, 0.005), hb = mk_v3(50, 0.005, 0.005), scale = (mk_real)mk_rng_range(&r, 0, 0.02); break;
            case 5: ha = mk_rng_v3(&r, 3e-4, 1e-3), hb = mk_rng_v3(&r, 3e-4, 1e-3), scale = (mk_real)mk_rng_range(&r, 0, 3e-3); break;
            default:
                ha = mk_rng_v3(&r, 0.3, 1), hb = mk_rng_v3(&r, 0.3, 1), scale = (mk_real)mk_rng_range(&r, 0, 2.5);
                off = mk_v3(1e5, -1e5, 5e4);
                break;
            }
            check_boxes_world(ha, mk_transform_make(off, qa), hb, mk_transform_make(mk_v3_mad(off, scale, dir), qb),
#if defined(MK_SINGLE)
                              fam == 6 ? 1e-2 : 1e-4,
#else
                              1e-12,
#endif
                              &res);
            edges += res.kind == MK_SAT_EDGES;
        }
    ck_assert_int_gt(edges, 30);
}
END_TEST

START_TEST(libccd_25_stacked_cubes)
{
    /* libccd #25: two 2 m cubes at z = 0 and z = 1.9. A known GJK+EPA gives
     * depth 0 and a NaN normal here: the first simplex is flat against the
     * touching faces. SAT has no simplex: the face axes are exact. */
    mk_sat_result res;
    mk_vec3 h = mk_v3(1, 1, 1);
    check_boxes_world(h, mk_transform_identity(), h, mk_transform_make(mk_v3(0, 0, (mk_real)1.9), mk_quat_identity()), 1e-12, &res);
    MK_ASSERT_NEAR(-res.best, 2 - (mk_real)1.9, 4 * MK_REAL_EPSILON);
    MK_ASSERT_V3_NEAR(res.normal, mk_v3(0, 0, 1), 0);
    ck_assert(res.kind == MK_SAT_FACE_A && res.a == 5); /* A's +z face */
}
END_TEST

START_TEST(early_stop)
{
    /* stop_above = 0 stops at an axis that separates, and says so. */
    mk_rng r = {24};
    int i, stopped = 0;
    for (i = 0; i < 300; ++i) {
        mk_vec3 ha = mk_rng_v3(&r, 0.2, 1), hb = mk_rng_v3(&r, 0.2, 1);
        mk_box_hull A, B;
        mk_mat3 R = mk_mat3_from_quat(mk_rng_quat(&r));
        mk_vec3 t = mk_v3_scale(mk_rng_dir(&r), (mk_real)mk_rng_range(&r, 0, 4));
        mk_sat_options o = mk_sat_defaults();
        mk_sat_result full, quick, qb;
        mk_box_hull_init(&A, ha);
        mk_box_hull_init(&B, hb);
        mk_sat(&A.hull, &B.hull, &R, t, &o, &full);
        o.stop_above = 0;
        mk_sat(&A.hull, &B.hull, &R, t, &o, &quick);
        mk_sat_box_box(ha, hb, &R, t, &o, &qb);
        if (full.best > 0) {
            REQUIRE(quick.best > 0 && qb.best > 0, "separated pair not found separated");
            REQUIRE(brute_along(&A.hull, &B.hull, &R, t, quick.normal) > 0, "the stopping axis does not separate");
            REQUIRE(quick.best <= full.best && qb.best <= full.best + val_tol(4), "early answer above the full one: %.17g %.17g > %.17g",
                    (double)quick.best, (double)qb.best, (double)full.best);
            stopped += !quick.complete;
        } else {
            REQUIRE(quick.complete && qb.complete && quick.best == full.best, "overlap must test every axis");
        }
    }
    ck_assert_int_gt(stopped, 50);
}
END_TEST

START_TEST(hysteresis)
{
    /* prefer keeps the previous face kind while it is within the tolerance,
     * and only then; edge pairs must beat the faces by it; the best
     * separation (the depth) is never biased. */
    mk_rng r = {25};
    int i, switched = 0, kept = 0, edged = 0;
    for (i = 0; i < 300; ++i) {
        mk_hull *a = ellipsoid_hull(&r, 12, mk_rng_v3(&r, 0.3, 1)), *b = ellipsoid_hull(&r, 12, mk_rng_v3(&r, 0.3, 1));
        mk_mat3 R = mk_mat3_from_quat(mk_rng_quat(&r));
        mk_vec3 t = mk_v3_scale(mk_rng_dir(&r), (mk_real)mk_rng_range(&r, 0, 0.6));
        mk_sat_options o = mk_sat_defaults();
        mk_sat_result base, loose, tight;
        mk_sat_kind k;
        mk_sat(a, b, &R, t, &o, &base);
        for (k = MK_SAT_FACE_A; k <= MK_SAT_EDGES; ++k) {
            if (k == base.kind) continue;
            o.prefer = k;
            o.prefer_rel = 0;
            o.prefer_abs = 0;
            mk_sat(a, b, &R, t, &o, &tight); /* no slack: the best axis still wins */
            REQUIRE(tight.kind == base.kind && tight.best == base.best, "zero tolerance changed the answer");
            o.prefer_abs = (mk_real)1e9; /* any axis of the preferred kind is close enough */
            mk_sat(a, b, &R, t, &o, &loose);
            REQUIRE(loose.best == base.best, "hysteresis changed the depth");
            if (loose.kind == k) {
                ++switched;
                REQUIRE(loose.separation <= base.best, "preferred axis better than the best");
                REQUIRE(fabsl(brute_along(a, b, &R, t, loose.normal) - (ld)loose.separation) <= val_tol(2), "preferred axis misreported");
            } else {
                REQUIRE(k == MK_SAT_EDGES && loose.kind == base.kind, "preference ignored"); /* only edges can be missing */
            }
            /* Within a relative tolerance that just covers the gap, it switches; just short of it, not. */
            if (loose.kind == k && base.best - loose.separation > 1e-3 * mk_fabs_(base.best) + 1e-3) {
                o.prefer_abs = 0;
                o.prefer_rel = (base.best - loose.separation) / mk_fabs_(base.best) * (mk_real)1.01;
                mk_sat(a, b, &R, t, &o, &tight);
                REQUIRE(tight.kind == k, "switch within the relative tolerance");
                o.prefer_rel = (base.best - loose.separation) / mk_fabs_(base.best) * (mk_real)0.99;
                mk_sat(a, b, &R, t, &o, &tight);
                REQUIRE(tight.kind != k, "no switch outside the tolerance");
                ++kept;
            }
        }
        /* Face preference: warm, an edge pair must beat the better face by
         * the band to be reported, by half the band when last frame's axis
         * was already an edge pair (the hysteresis loop). */
        if (base.kind == MK_SAT_EDGES) {
            mk_sat_result faces;
            mk_real gap;
            o.prefer = MK_SAT_FACE_A;
            o.prefer_rel = 0;
            o.prefer_abs = (mk_real)1e9; /* the better face of each kind */
            mk_sat(a, b, &R, t, &o, &faces);
            REQUIRE(faces.kind == MK_SAT_FACE_A, "face preference ignored");
            o.prefer = MK_SAT_FACE_B;
            mk_sat(a, b, &R, t, &o, &tight);
            if (tight.separation > faces.separation) faces = tight;
            gap = base.best - faces.separation;
            if (gap > 1e-3 * mk_fabs_(base.best) + 1e-3) {
                ++edged;
                o.prefer = faces.kind;
                o.prefer_abs = gap * (mk_real)1.01;
                mk_sat(a, b, &R, t, &o, &tight);
                REQUIRE(tight.kind == faces.kind && tight.best == base.best, "edge pair within the band taken");
                o.prefer_abs = gap * (mk_real)0.99;
                mk_sat(a, b, &R, t, &o, &tight);
                REQUIRE(tight.kind == MK_SAT_EDGES, "edge pair beyond the band not taken");
                o.prefer = MK_SAT_EDGES;
                o.prefer_abs = gap * (mk_real)2.02;
                mk_sat(a, b, &R, t, &o, &tight);
                REQUIRE(tight.kind == faces.kind, "edge pair kept within half the band");
                o.prefer_abs = gap * (mk_real)1.98;
                mk_sat(a, b, &R, t, &o, &tight);
                REQUIRE(tight.kind == MK_SAT_EDGES, "edge pair dropped beyond half the band");
            }
        }
        mk_hull_destroy(a);
        mk_hull_destroy(b);
    }
    ck_assert_int_gt(switched, 100);
    ck_assert_int_gt(kept, 50);
    ck_assert_int_gt(edged, 10);
}
END_TEST

/* SAT of the pair: hulls through mk_sat, two boxes (half extents in
 * boxes) through mk_sat_box_box. */
static void sat_of(const mk_hull *a, const mk_hull *b, const mk_vec3 *boxes, const mk_mat3 *R, mk_vec3 t, mk_sat_result *out,
                   const mk_sat_options *o)
{
    if (boxes) mk_sat_box_box(boxes[0], boxes[1], R, t, o, out);
    else mk_sat(a, b, R, t, o, out);
}

/* The pair of the sat_of() tests: two boxes (half extents in hx) when
 * `box`, else two ellipsoid hulls of n points that the caller destroys. */
static void random_pair(mk_rng *r, int box, int n, mk_vec3 hx[2], mk_box_hull *A, mk_box_hull *B, mk_hull **ha, mk_hull **hb,
                        const mk_hull **a, const mk_hull **b)
{
    if (box) {
        hx[0] = mk_rng_v3(r, 0.2, 1);
        hx[1] = mk_rng_v3(r, 0.2, 1);
        mk_box_hull_init(A, hx[0]);
        mk_box_hull_init(B, hx[1]);
        *a = &A->hull;
        *b = &B->hull;
    } else {
        *a = *ha = ellipsoid_hull(r, n, mk_rng_v3(r, 0.3, 1));
        *b = *hb = ellipsoid_hull(r, n, mk_rng_v3(r, 0.3, 1));
    }
}

/* The first-axis hint (mk_sat_options.first): apart pairs, hinted with
 * the axis an early-stopping run reported, stop on it at once with the
 * same answer; penetrating pairs, whatever the hint, get the full answer.
 * Only mk_sat takes the hint (a box meets a hull as its box view, so half
 * the pairs here are two box views); mk_sat_box_box ignores it. */
START_TEST(first_axis_hint)
{
    mk_rng r = {26};
    int i, stops = 0, full = 0;
    for (i = 0; i < 600; ++i) {
        int box = i % 2;
        mk_vec3 hx[2];
        mk_box_hull A, B;
        mk_hull *ha = NULL, *hb = NULL;
        const mk_hull *a, *b;
        mk_mat3 R = mk_mat3_from_quat(mk_rng_quat(&r));
        mk_vec3 t = mk_v3_scale(mk_rng_dir(&r), (mk_real)mk_rng_range(&r, 0, 3));
        mk_sat_options o = mk_sat_defaults();
        mk_sat_result base, quick, hint;
        random_pair(&r, box, 16, hx, &A, &B, &ha, &hb, &a, &b);
        mk_sat(a, b, &R, t, &o, &base);
        o.stop_above = 0;
        mk_sat(a, b, &R, t, &o, &quick);
        if (base.best > 0) {
            o.first = quick.kind;
            o.first_a = quick.a;
            o.first_b = quick.b;
            mk_sat(a, b, &R, t, &o, &hint);
            REQUIRE(!hint.complete && hint.kind == quick.kind && hint.a == quick.a && hint.b == quick.b, "case %d: hint not taken", i);
            REQUIRE(fabsl((ld)hint.best - (ld)quick.separation) <= val_tol(4) && hint.best > 0, "case %d: hinted separation %.17g, %.17g", i,
                    (double)hint.best, (double)quick.separation);
            REQUIRE(brute_along(a, b, &R, t, hint.normal) > 0, "case %d: the hinted axis does not separate", i);
            ++stops;
        } else {
            /* Penetrating: a hint (any axis of any kind) changes nothing. */
            o.stop_above = MK_REAL_MAX;
            o.first = (mk_sat_kind)(1 + i % 3);
            o.first_a = o.first == MK_SAT_FACE_B ? -1 : o.first == MK_SAT_EDGES ? (box ? 3 : 0) : 1;
            o.first_b = o.first == MK_SAT_FACE_A ? -1 : o.first == MK_SAT_EDGES ? (box ? 5 : 1) : 0;
            mk_sat(a, b, &R, t, &o, &hint);
            REQUIRE(hint.complete && hint.best == base.best && hint.kind == base.kind && hint.a == base.a && hint.b == base.b,
                    "case %d: a hint changed a penetrating answer", i);
            ++full;
        }
        if (ha) mk_hull_destroy(ha);
        if (hb) mk_hull_destroy(hb);
    }
    ck_assert_int_gt(stops, 100);
    ck_assert_int_gt(full, 100);
}
END_TEST

/* hold_face = 0 (MK_MANIFOLD_BEST_FACE): the better face wins whichever
 * face kind is preferred, however wide the band; edge pairs still need to
 * beat it by the band. Hulls through mk_sat, boxes through mk_sat_box_box. */
START_TEST(better_face_not_held)
{
    mk_rng r = {27};
    int i, faces = 0, edges = 0;
    for (i = 0; i < 400; ++i) {
        int box = i % 2;
        mk_vec3 hx[2];
        mk_hull *ha = NULL, *hb = NULL;
        mk_box_hull A, B;
        const mk_hull *a, *b;
        mk_mat3 R = mk_mat3_from_quat(mk_rng_quat(&r));
        mk_vec3 t = mk_v3_scale(mk_rng_dir(&r), (mk_real)mk_rng_range(&r, 0, 0.6));
        mk_sat_options o = mk_sat_defaults();
        mk_sat_result base, warm;
        mk_sat_kind k;
        random_pair(&r, box, 12, hx, &A, &B, &ha, &hb, &a, &b);
        sat_of(a, b, box ? hx : NULL, &R, t, &base, &o);
        o.hold_face = 0;
        o.prefer_abs = (mk_real)1e9;
        for (k = MK_SAT_FACE_A; k <= MK_SAT_EDGES; ++k) {
            o.prefer = k;
            sat_of(a, b, box ? hx : NULL, &R, t, &warm, &o);
            REQUIRE(warm.best == base.best, "case %d: the depth changed", i);
            REQUIRE(warm.kind != MK_SAT_EDGES, "case %d: an edge pair beat a face by 1e9", i);
            if (base.kind != MK_SAT_EDGES) {
                REQUIRE(warm.kind == base.kind && warm.a == base.a && warm.b == base.b && warm.separation == base.separation,
                        "case %d: the face kind was held against the better face", i);
                faces += k != base.kind;
            } else {
                /* The better of the two faces, the same whatever the preference. */
                mk_sat_options c = o;
                mk_sat_result other;
                c.prefer = k == MK_SAT_FACE_A ? MK_SAT_FACE_B : MK_SAT_FACE_A;
                sat_of(a, b, box ? hx : NULL, &R, t, &other, &c);
                REQUIRE(other.kind == warm.kind && other.separation == warm.separation, "case %d: the face depends on the preference", i);
                edges += k == MK_SAT_FACE_A;
            }
        }
        if (ha) mk_hull_destroy(ha);
        if (hb) mk_hull_destroy(hb);
    }
    ck_assert_int_gt(faces, 200);
    ck_assert_int_gt(edges, 10);
}
END_TEST

static Suite *sat_suite(void)
{
    Suite *s = suite_create("sat");
    TCase *tc = tcase_create("sat");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, box_view_matches_manifold_numbering);
    tcase_add_test(tc, box_box_random);
    tcase_add_test(tc, hull_hull_random);
    tcase_add_test(tc, degenerate_gauss_maps);
    tcase_add_test(tc, box_families);
    tcase_add_test(tc, libccd_25_stacked_cubes);
    tcase_add_test(tc, early_stop);
    tcase_add_test(tc, hysteresis);
    tcase_add_test(tc, first_axis_hint);
    tcase_add_test(tc, better_face_not_held);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return mk_test_run(sat_suite()); }

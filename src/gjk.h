/* gjk.h: GJK distance between the cores of two convex shapes (internal).
 *
 * Everything runs in A's local frame: B enters through a rotation matrix and a
 * translation computed once per query (mk_pair), so the loop never touches a
 * quaternion and large world coordinates cost nothing. The configuration
 * space obstacle (CSO) is A - B; the signed core distance is the distance of
 * the origin from it, and the direction "from A towards B" is -v for the CSO
 * point v nearest the origin. Rounding radii are not seen here: callers
 * subtract them. The simplex sub-algorithm is Montanari et al.'s signed
 * volumes (ACM TOG 2017), which picks the sub-simplex from signs of projected
 * areas and volumes and so never divides by a vanishing determinant; search
 * directions come from cross products of the simplex (Catto 2010, Box3D), not
 * from the rounded closest point. Complexity: O(k) support calls for k
 * iterations (k <= MK_GJK_MAX_ITERATIONS); each iteration is O(1) plus one
 * support per shape (O(1) for primitives, a hill climb for hulls).
 */
#ifndef MINKO_GJK_H
#define MINKO_GJK_H

#include "minko/distance.h"
#include "shape_internal.h"

#define MK_GJK_MAX_ITERATIONS 128

/* Relative gap |v| - lower at which GJK stops on smooth cores (polytopes stop
 * earlier, on a repeated support point). openGJK's choice: 1e4 eps. */
#if defined(MK_SINGLE)
#  define MK_GJK_REL_TOL (MK_REAL(1e2) * MK_REAL_EPSILON)
#else
#  define MK_GJK_REL_TOL (MK_REAL(1e4) * MK_REAL_EPSILON)
#endif
/* Absolute floor of every tolerance, in units of (eps * scale) where scale is
 * the largest CSO point seen: below it the support values are rounding noise. */
#define MK_GJK_ABS_TOL (MK_REAL(8.0) * MK_REAL_EPSILON)

/* B's pose in A's frame: x_A = r x_B + t. */
typedef struct mk_pair {
    const mk_shape *a, *b;
    mk_mat3 r;
    mk_vec3 t;
} mk_pair;

/* A vertex of the CSO: support points a (of A) and b (of B, in A's frame),
 * w = a - b, and the core vertex indices they came from (-1: smooth part). */
typedef struct mk_cso_vertex {
    mk_vec3 a, b, w;
    int ia, ib;
} mk_cso_vertex;

/* Up to four CSO vertices with the barycentric weights of the point nearest the origin. */
typedef struct mk_simplex {
    mk_cso_vertex v[4];
    mk_real l[4];
    int n;
} mk_simplex;

typedef struct mk_gjk_result {
    mk_simplex s;       /* final simplex; n == 4 when it encloses the origin */
    mk_vec3 v;          /* point of the simplex nearest the origin */
    mk_real upper;      /* |v|: an upper bound on the signed core distance */
    mk_real lower;      /* best lower bound found (along `normal`) */
    mk_vec3 normal;     /* unit, from A towards B: the direction of `lower` */
    mk_real scale;      /* largest |w| seen: the size rounding errors scale with */
    int overlap;        /* 1 when the cores touch or overlap (or, in boolean mode, the rounded shapes do) */
    int iterations;
    mk_solve_state state;
} mk_gjk_result;

/* 2 / |q|^2 for a quaternion accepted by the pose check (e = |q|^2 - 1 within
 * MK_QUAT_TOLERANCE): 2 (1 - e + e^2) is off by 2 e^3, below the rounding of
 * either precision (2e-18 in double, 2e-12 in float), and it keeps a division
 * off the head of every query's dependency chain; summed as (2 - 2e) + e 2e,
 * its two terms are formed side by side rather than nested. */
MK_ALWAYS_INLINE mk_real mk_two_over_len2(mk_quat q)
{
    mk_real e = mk_quat_len2(q) - 1, e2 = e + e;
    return (2 - e2) + e * e2;
}

/* Rotation matrix of a quaternion that is unit only to within
 * MK_QUAT_TOLERANCE: the usual formula with 2/|q|^2 in place of 2 is an exact
 * rotation for any such q, so no square root and no renormalised copy. The
 * products come first and the scale last, so they need not wait for
 * 2/|q|^2: every pose-to-matrix conversion starts a query's chain of
 * dependent operations. */
MK_ALWAYS_INLINE mk_mat3 mk_rotation_of(mk_quat q)
{
    mk_real s = mk_two_over_len2(q);
    mk_real xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z, xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
    mk_real wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
    return mk_mat3_cols(mk_v3(1 - s * (yy + zz), s * (xy + wz), s * (xz - wy)), mk_v3(s * (xy - wz), 1 - s * (xx + zz), s * (yz + wx)),
                        mk_v3(s * (xz + wy), s * (yz - wx), 1 - s * (xx + yy)));
}

/* The third column of mk_rotation_of(q) (the body's z axis: a capsule's
 * axis), by the same operations, so both give the same bits. */
MK_ALWAYS_INLINE mk_vec3 mk_rotation_z_of(mk_quat q)
{
    mk_real s = mk_two_over_len2(q);
    return mk_v3(s * (q.x * q.z + q.w * q.y), s * (q.y * q.z - q.w * q.x), 1 - s * (q.x * q.x + q.y * q.y));
}

/* Support of A - B along d (A's frame) for shapes of types ta, tb; ha, hb:
 * hints (previous vertex indices), returned as the new indices. */
MK_ALWAYS_INLINE mk_cso_vertex mk_pair_support_typed(const mk_pair *p, mk_shape_type ta, mk_shape_type tb, mk_vec3 d,
                                                     int ha, int hb)
{
    mk_cso_vertex v;
    mk_vec3 bl;
    v.ia = ha;
    v.ib = hb;
    v.a = mk_core_support_typed(p->a, ta, d, &v.ia);
    bl = mk_core_support_typed(p->b, tb, mk_mat3_tmul_v3(p->r, mk_v3_neg(d)), &v.ib);
    v.b = mk_v3_add(mk_mat3_mul_v3(p->r, bl), p->t);
    v.w = mk_v3_sub(v.a, v.b);
    return v;
}

MK_ALWAYS_INLINE mk_cso_vertex mk_pair_support(const mk_pair *p, mk_vec3 d, int ha, int hb)
{
    return mk_pair_support_typed(p, p->a->type, p->b->type, d, ha, hb);
}

/* sep(n) = min_B n.b - max_A n.a for a unit n from A towards B: a lower bound
 * on the signed core distance for every n, equal to it at the optimum. */
static inline mk_real mk_pair_separation(const mk_pair *p, mk_vec3 n, int *ha, int *hb)
{
    mk_cso_vertex v = mk_pair_support(p, n, *ha, *hb);
    *ha = v.ia;
    *hb = v.ib;
    return -mk_v3_dot(n, v.w);
}

/* GJK on the cores. `cache` may be NULL (cold start). In boolean mode GJK
 * stops as soon as the answer to "core distance <= radius" is known; the
 * bounds are then only as tight as needed for that answer. */
void mk_gjk(const mk_pair *p, const mk_gjk_cache *cache, int boolean, mk_real radius, mk_gjk_result *out);

/* Stores the final simplex (vertex indices, when all are vertices) and the
 * normal of a query for the next warm start. */
void mk_gjk_cache_store(const mk_simplex *s, mk_vec3 normal, mk_gjk_cache *cache);

#endif

/* minko/math3d.h: vectors, quaternions, 3x3 matrices, rigid transforms, poses, AABBs.
 *
 * Contract. Plain structs passed by value; every function but the pose
 * functions is C99 `inline` here and also exported from the library under
 * the same name. No function allocates, reads global state or asserts.
 * Functions that can meet a degenerate input say what they return for it
 * (mk_v3_normalize of a zero vector returns the zero vector). Validators
 * (mk_*_is_valid) are the checks every public entry point applies to its
 * inputs. A quaternion is accepted as a rotation when
 * | |q|^2 - 1 | <= MK_QUAT_TOLERANCE; queries then use the exact rotation of
 * q / |q|, so a slightly drifted quaternion costs no accuracy. A position is
 * accepted when every coordinate is within [-MK_MAX_COORD, MK_MAX_COORD]
 * (below). Matrices are stored by columns: m.c0, m.c1, m.c2 are the images
 * of the x, y and z axes. An mk_pose is a rotation matrix and a position
 * checked once, by mk_pose_from_transform or mk_pose_from_matrix, so that
 * the pose-taking queries (mk_distance_pose, mk_overlap_pose,
 * mk_collide_pose) neither re-validate nor convert it: hosts that keep
 * matrices (Bullet, ODE) pass them straight in, and a body's pose serves
 * all its pairs.
 */
#ifndef MINKO_MATH3D_H
#define MINKO_MATH3D_H

#include <math.h>

#include "minko/base.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mk_vec3 { mk_real x, y, z; } mk_vec3;
typedef struct mk_quat { mk_real x, y, z, w; } mk_quat;     /* w is the scalar part */
typedef struct mk_mat3 { mk_vec3 c0, c1, c2; } mk_mat3;       /* columns */
typedef struct mk_transform { mk_vec3 p; mk_quat q; } mk_transform; /* x -> q x q* + p */
typedef struct mk_aabb { mk_vec3 lo, hi; } mk_aabb;           /* closed box [lo, hi] */

/* A rigid pose checked once (see the contract): x -> r x + p. Read the
 * fields freely; make it only with mk_pose_from_transform or
 * mk_pose_from_matrix, move it with mk_pose_set_position. `checked` records
 * that it passed (a zeroed or hand-filled pose is refused by the queries
 * with MK_ERR_UNCHECKED_POSE); writing r or p directly is not detected, so
 * use those functions instead. */
typedef struct mk_pose {
    mk_mat3 r;        /* rotation: columns are the body's x, y, z axes in world, orthonormal, det +1 */
    mk_vec3 p;        /* position of the body's origin, within MK_MAX_COORD */
    unsigned checked; /* set by the constructors; do not write */
} mk_pose;

/* MK_MAX_COORD bounds every position coordinate a query accepts. The pair
 * queries work in A's frame on t = R^T (p_b - p_a) plus shape sizes (at most
 * MK_MAX_SIZE = 1e12 in double, 1e8 in float, per dimension): with every
 * |p_i| <= B a coordinate there is below W = 2 sqrt(3) B + 3 MK_MAX_SIZE.
 * The highest products formed are quartic (GJK's |n|^2 and n . (b x c) for n
 * a cross product of simplex edges), at most 192 W^4, which must stay below
 * MK_REAL_MAX: B = 1e75 in double (3e304 of 1.8e308), B = 1e8 in float
 * (3.4e37 of 3.4e38). Beyond it a distance could come out infinite or NaN;
 * such input gets MK_ERR_OUT_OF_RANGE. (Float's bound is also where its
 * resolution, 8 units at 1e8, stops meaning anything.)
 *
 * MK_ROTATION_TOLERANCE is how far from orthonormal a matrix given to
 * mk_pose_from_matrix may be: every entry of r^T r - I within it, and det r
 * > 0. It equals MK_QUAT_TOLERANCE, so it admits what integrators produce
 * (rounding-level drift, and a float host's matrix widened to double, about
 * 1e-7) while refusing scaled, sheared or reflecting matrices. */
#if defined(MK_SINGLE)
#  define MK_QUAT_TOLERANCE 1e-4f
#  define MK_MAX_COORD 1e8f
#  define mk_sqrt_ sqrtf
#  define mk_fabs_ fabsf
#else
#  define MK_QUAT_TOLERANCE 1e-6
#  define MK_MAX_COORD 1e75
#  define mk_sqrt_ sqrt
#  define mk_fabs_ fabs
#endif
#define MK_ROTATION_TOLERANCE MK_QUAT_TOLERANCE

/* ---- scalars ---- */
MK_API MK_INLINE int mk_real_is_valid(mk_real a) { return a - a == a - a; } /* false for NaN and +-Inf */
MK_API MK_INLINE mk_real mk_min(mk_real a, mk_real b) { return a < b ? a : b; }
MK_API MK_INLINE mk_real mk_max(mk_real a, mk_real b) { return a > b ? a : b; }
MK_API MK_INLINE mk_real mk_clamp(mk_real a, mk_real lo, mk_real hi) { return a < lo ? lo : (a > hi ? hi : a); }

/* ---- vec3 ---- */
MK_API MK_INLINE mk_vec3 mk_v3(mk_real x, mk_real y, mk_real z) { mk_vec3 v; v.x = x; v.y = y; v.z = z; return v; }
MK_API MK_INLINE mk_vec3 mk_v3_zero(void) { return mk_v3(0, 0, 0); }
MK_API MK_INLINE mk_vec3 mk_v3_add(mk_vec3 a, mk_vec3 b) { return mk_v3(a.x + b.x, a.y + b.y, a.z + b.z); }
MK_API MK_INLINE mk_vec3 mk_v3_sub(mk_vec3 a, mk_vec3 b) { return mk_v3(a.x - b.x, a.y - b.y, a.z - b.z); }
MK_API MK_INLINE mk_vec3 mk_v3_neg(mk_vec3 a) { return mk_v3(-a.x, -a.y, -a.z); }
MK_API MK_INLINE mk_vec3 mk_v3_scale(mk_vec3 a, mk_real s) { return mk_v3(a.x * s, a.y * s, a.z * s); }
MK_API MK_INLINE mk_vec3 mk_v3_mul(mk_vec3 a, mk_vec3 b) { return mk_v3(a.x * b.x, a.y * b.y, a.z * b.z); }
/* a + s*b */
MK_API MK_INLINE mk_vec3 mk_v3_mad(mk_vec3 a, mk_real s, mk_vec3 b) { return mk_v3(a.x + s * b.x, a.y + s * b.y, a.z + s * b.z); }
MK_API MK_INLINE mk_vec3 mk_v3_lerp(mk_vec3 a, mk_vec3 b, mk_real t) { return mk_v3(a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z)); }
MK_API MK_INLINE mk_real mk_v3_dot(mk_vec3 a, mk_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
MK_API MK_INLINE mk_vec3 mk_v3_cross(mk_vec3 a, mk_vec3 b) { return mk_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x); }
MK_API MK_INLINE mk_real mk_v3_len2(mk_vec3 a) { return mk_v3_dot(a, a); }
MK_API MK_INLINE mk_real mk_v3_len(mk_vec3 a) { return mk_sqrt_(mk_v3_dot(a, a)); }
MK_API MK_INLINE mk_real mk_v3_dist(mk_vec3 a, mk_vec3 b) { return mk_v3_len(mk_v3_sub(a, b)); }
MK_API MK_INLINE mk_vec3 mk_v3_min(mk_vec3 a, mk_vec3 b) { return mk_v3(mk_min(a.x, b.x), mk_min(a.y, b.y), mk_min(a.z, b.z)); }
MK_API MK_INLINE mk_vec3 mk_v3_max(mk_vec3 a, mk_vec3 b) { return mk_v3(mk_max(a.x, b.x), mk_max(a.y, b.y), mk_max(a.z, b.z)); }
MK_API MK_INLINE mk_vec3 mk_v3_abs(mk_vec3 a) { return mk_v3(mk_fabs_(a.x), mk_fabs_(a.y), mk_fabs_(a.z)); }
MK_API MK_INLINE mk_real mk_v3_max_abs(mk_vec3 a) { return mk_max(mk_fabs_(a.x), mk_max(mk_fabs_(a.y), mk_fabs_(a.z))); }
/* Unit vector along a; the zero vector (or a non-finite one) gives zero. */
MK_API MK_INLINE mk_vec3 mk_v3_normalize(mk_vec3 a)
{
    mk_real l = mk_v3_len(a);
    return (l > 0 && mk_real_is_valid(l)) ? mk_v3_scale(a, 1 / l) : mk_v3_zero();
}
MK_API MK_INLINE int mk_v3_is_valid(mk_vec3 a) { return mk_real_is_valid(a.x) && mk_real_is_valid(a.y) && mk_real_is_valid(a.z); }
/* A position every query accepts: each coordinate finite and within
 * MK_MAX_COORD (a NaN fails the comparisons). */
MK_API MK_INLINE int mk_position_is_valid(mk_vec3 p)
{
    return mk_fabs_(p.x) <= MK_MAX_COORD && mk_fabs_(p.y) <= MK_MAX_COORD && mk_fabs_(p.z) <= MK_MAX_COORD;
}
/* Some unit vector perpendicular to the unit vector n (continuous except near one pole). */
MK_API MK_INLINE mk_vec3 mk_v3_perp(mk_vec3 n)
{
    /* Pick the axis least aligned with n so the cross product is well conditioned. */
    if (mk_fabs_(n.x) < MK_REAL(0.57735)) return mk_v3_normalize(mk_v3(0, n.z, -n.y));
    return mk_v3_normalize(mk_v3(n.y, -n.x, 0));
}

/* ---- quaternions ---- */
MK_API MK_INLINE mk_quat mk_quat_make(mk_real x, mk_real y, mk_real z, mk_real w) { mk_quat q; q.x = x; q.y = y; q.z = z; q.w = w; return q; }
MK_API MK_INLINE mk_quat mk_quat_identity(void) { return mk_quat_make(0, 0, 0, 1); }
MK_API MK_INLINE mk_quat mk_quat_conj(mk_quat q) { return mk_quat_make(-q.x, -q.y, -q.z, q.w); }
MK_API MK_INLINE mk_real mk_quat_len2(mk_quat q) { return q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w; }
MK_API MK_INLINE mk_quat mk_quat_mul(mk_quat a, mk_quat b)
{
    return mk_quat_make(a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
                        a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
                        a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w,
                        a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z);
}
/* Unit quaternion along q; a zero or non-finite q gives the identity. */
MK_API MK_INLINE mk_quat mk_quat_normalize(mk_quat q)
{
    mk_real l = mk_sqrt_(mk_quat_len2(q));
    if (!(l > 0) || !mk_real_is_valid(l)) return mk_quat_identity();
    l = 1 / l;
    return mk_quat_make(q.x * l, q.y * l, q.z * l, q.w * l);
}
/* Rotation of `angle` radians about `axis` (need not be unit; zero axis gives identity). */
MK_API MK_INLINE mk_quat mk_quat_from_axis_angle(mk_vec3 axis, mk_real angle)
{
    mk_vec3 n = mk_v3_normalize(axis);
    mk_real s = (mk_real)sin(0.5 * (double)angle), c = (mk_real)cos(0.5 * (double)angle);
    if (mk_v3_len2(n) == 0) return mk_quat_identity();
    return mk_quat_make(n.x * s, n.y * s, n.z * s, c);
}
MK_API MK_INLINE int mk_quat_is_valid(mk_quat q)
{
    return mk_real_is_valid(q.x) && mk_real_is_valid(q.y) && mk_real_is_valid(q.z) && mk_real_is_valid(q.w) &&
           mk_fabs_(mk_quat_len2(q) - 1) <= MK_QUAT_TOLERANCE;
}
/* q v q*, for unit q. */
MK_API MK_INLINE mk_vec3 mk_quat_rotate(mk_quat q, mk_vec3 v)
{
    /* v' = v + 2w(u x v) + 2 u x (u x v), u = (x, y, z): 15 mul, cheaper than forming the matrix once. */
    mk_vec3 u = mk_v3(q.x, q.y, q.z);
    mk_vec3 t = mk_v3_scale(mk_v3_cross(u, v), 2);
    return mk_v3_add(mk_v3_mad(v, q.w, t), mk_v3_cross(u, t));
}
MK_API MK_INLINE mk_vec3 mk_quat_inv_rotate(mk_quat q, mk_vec3 v) { return mk_quat_rotate(mk_quat_conj(q), v); }

/* ---- mat3 ---- */
MK_API MK_INLINE mk_mat3 mk_mat3_cols(mk_vec3 c0, mk_vec3 c1, mk_vec3 c2) { mk_mat3 m; m.c0 = c0; m.c1 = c1; m.c2 = c2; return m; }
MK_API MK_INLINE mk_mat3 mk_mat3_identity(void) { return mk_mat3_cols(mk_v3(1, 0, 0), mk_v3(0, 1, 0), mk_v3(0, 0, 1)); }
/* Rotation matrix of a unit quaternion. */
MK_API MK_INLINE mk_mat3 mk_mat3_from_quat(mk_quat q)
{
    mk_real xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
    mk_real xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
    mk_real wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
    return mk_mat3_cols(mk_v3(1 - 2 * (yy + zz), 2 * (xy + wz), 2 * (xz - wy)),
                        mk_v3(2 * (xy - wz), 1 - 2 * (xx + zz), 2 * (yz + wx)),
                        mk_v3(2 * (xz + wy), 2 * (yz - wx), 1 - 2 * (xx + yy)));
}
/* Unit quaternion of a rotation matrix (Shepperd's method: pick the largest diagonal term for stability). */
MK_API MK_INLINE mk_quat mk_quat_from_mat3(mk_mat3 m)
{
    mk_real t = m.c0.x + m.c1.y + m.c2.z, s;
    if (t > 0) {
        s = mk_sqrt_(t + 1) * 2;
        return mk_quat_normalize(mk_quat_make((m.c1.z - m.c2.y) / s, (m.c2.x - m.c0.z) / s, (m.c0.y - m.c1.x) / s, MK_REAL(0.25) * s));
    } else if (m.c0.x > m.c1.y && m.c0.x > m.c2.z) {
        s = mk_sqrt_(1 + m.c0.x - m.c1.y - m.c2.z) * 2;
        return mk_quat_normalize(mk_quat_make(MK_REAL(0.25) * s, (m.c1.x + m.c0.y) / s, (m.c2.x + m.c0.z) / s, (m.c1.z - m.c2.y) / s));
    } else if (m.c1.y > m.c2.z) {
        s = mk_sqrt_(1 + m.c1.y - m.c0.x - m.c2.z) * 2;
        return mk_quat_normalize(mk_quat_make((m.c1.x + m.c0.y) / s, MK_REAL(0.25) * s, (m.c2.y + m.c1.z) / s, (m.c2.x - m.c0.z) / s));
    }
    s = mk_sqrt_(1 + m.c2.z - m.c0.x - m.c1.y) * 2;
    return mk_quat_normalize(mk_quat_make((m.c2.x + m.c0.z) / s, (m.c2.y + m.c1.z) / s, MK_REAL(0.25) * s, (m.c0.y - m.c1.x) / s));
}
MK_API MK_INLINE mk_vec3 mk_mat3_mul_v3(mk_mat3 m, mk_vec3 v)
{
    return mk_v3(m.c0.x * v.x + m.c1.x * v.y + m.c2.x * v.z,
                 m.c0.y * v.x + m.c1.y * v.y + m.c2.y * v.z,
                 m.c0.z * v.x + m.c1.z * v.y + m.c2.z * v.z);
}
/* m^T v */
MK_API MK_INLINE mk_vec3 mk_mat3_tmul_v3(mk_mat3 m, mk_vec3 v) { return mk_v3(mk_v3_dot(m.c0, v), mk_v3_dot(m.c1, v), mk_v3_dot(m.c2, v)); }
MK_API MK_INLINE mk_mat3 mk_mat3_transpose(mk_mat3 m)
{
    return mk_mat3_cols(mk_v3(m.c0.x, m.c1.x, m.c2.x), mk_v3(m.c0.y, m.c1.y, m.c2.y), mk_v3(m.c0.z, m.c1.z, m.c2.z));
}
MK_API MK_INLINE mk_mat3 mk_mat3_mul(mk_mat3 a, mk_mat3 b) { return mk_mat3_cols(mk_mat3_mul_v3(a, b.c0), mk_mat3_mul_v3(a, b.c1), mk_mat3_mul_v3(a, b.c2)); }
/* a^T b */
MK_API MK_INLINE mk_mat3 mk_mat3_tmul(mk_mat3 a, mk_mat3 b) { return mk_mat3_cols(mk_mat3_tmul_v3(a, b.c0), mk_mat3_tmul_v3(a, b.c1), mk_mat3_tmul_v3(a, b.c2)); }
/* |m| element-wise: used to transform box extents into AABBs. */
MK_API MK_INLINE mk_mat3 mk_mat3_abs(mk_mat3 m) { return mk_mat3_cols(mk_v3_abs(m.c0), mk_v3_abs(m.c1), mk_v3_abs(m.c2)); }

/* ---- rigid transforms ---- */
MK_API MK_INLINE mk_transform mk_transform_make(mk_vec3 p, mk_quat q) { mk_transform t; t.p = p; t.q = q; return t; }
MK_API MK_INLINE mk_transform mk_transform_identity(void) { return mk_transform_make(mk_v3_zero(), mk_quat_identity()); }
MK_API MK_INLINE mk_vec3 mk_transform_point(mk_transform t, mk_vec3 v) { return mk_v3_add(mk_quat_rotate(t.q, v), t.p); }
MK_API MK_INLINE mk_vec3 mk_transform_inv_point(mk_transform t, mk_vec3 v) { return mk_quat_inv_rotate(t.q, mk_v3_sub(v, t.p)); }
/* a * b: apply b, then a. */
MK_API MK_INLINE mk_transform mk_transform_mul(mk_transform a, mk_transform b)
{
    return mk_transform_make(mk_transform_point(a, b.p), mk_quat_mul(a.q, b.q));
}
/* a^-1 * b: b expressed in a's frame. This is how pair queries move B into A's
 * frame; subtracting the positions first keeps large coordinates exact. */
MK_API MK_INLINE mk_transform mk_transform_inv_mul(mk_transform a, mk_transform b)
{
    return mk_transform_make(mk_quat_inv_rotate(a.q, mk_v3_sub(b.p, a.p)), mk_quat_mul(mk_quat_conj(a.q), b.q));
}
MK_API MK_INLINE int mk_transform_is_valid(mk_transform t) { return mk_position_is_valid(t.p) && mk_quat_is_valid(t.q); }

/* ---- checked poses ---- */
/* The pose of a transform: its quaternion's exact rotation (of q / |q|) as a
 * matrix. MK_ERR_NULL, MK_ERR_NOT_FINITE, MK_ERR_OUT_OF_RANGE (a coordinate
 * beyond MK_MAX_COORD) or MK_ERR_BAD_ROTATION (| |q|^2 - 1 | >
 * MK_QUAT_TOLERANCE) leave *out untouched. O(1), about 40 flops. */
MK_API mk_status mk_pose_from_transform(mk_transform x, mk_pose *out);
/* The pose of a host's rotation matrix r (columns: the body's axes in world)
 * and position p. r must be orthonormal within MK_ROTATION_TOLERANCE with
 * det r > 0, else MK_ERR_BAD_ROTATION; non-finite input gives
 * MK_ERR_NOT_FINITE, a coordinate of p beyond MK_MAX_COORD
 * MK_ERR_OUT_OF_RANGE; *out is then untouched. A matrix orthonormal to
 * rounding (32 eps) is kept as it is; one that drifted further is replaced by
 * its Gram-Schmidt orthonormalisation (x axis kept, then y), so queries
 * always work with an exact rotation. O(1). */
MK_API mk_status mk_pose_from_matrix(mk_mat3 r, mk_vec3 p, mk_pose *out);
/* Moves a checked pose to position p and keeps its rotation: the re-pose of
 * a body whose rotation did not change (it only translated, or a host
 * re-poses every body each step), without re-checking the rotation. p is
 * range-checked as the constructors do. MK_ERR_NULL, MK_ERR_UNCHECKED_POSE
 * (*x was not made by a constructor), MK_ERR_NOT_FINITE or
 * MK_ERR_OUT_OF_RANGE leave *x untouched. O(1), a handful of comparisons. */
MK_API mk_status mk_pose_set_position(mk_pose *x, mk_vec3 p);

/* ---- AABBs ---- */
MK_API MK_INLINE mk_aabb mk_aabb_make(mk_vec3 lo, mk_vec3 hi) { mk_aabb b; b.lo = lo; b.hi = hi; return b; }
/* Closed intervals: boxes that touch overlap. */
MK_API MK_INLINE int mk_aabb_overlap(mk_aabb a, mk_aabb b)
{
    return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y && a.lo.z <= b.hi.z && b.lo.z <= a.hi.z;
}
MK_API MK_INLINE int mk_aabb_contains(mk_aabb outer, mk_aabb inner)
{
    return outer.lo.x <= inner.lo.x && outer.lo.y <= inner.lo.y && outer.lo.z <= inner.lo.z &&
           inner.hi.x <= outer.hi.x && inner.hi.y <= outer.hi.y && inner.hi.z <= outer.hi.z;
}
MK_API MK_INLINE mk_aabb mk_aabb_union(mk_aabb a, mk_aabb b) { return mk_aabb_make(mk_v3_min(a.lo, b.lo), mk_v3_max(a.hi, b.hi)); }
MK_API MK_INLINE mk_aabb mk_aabb_expand(mk_aabb a, mk_real r) { return mk_aabb_make(mk_v3_sub(a.lo, mk_v3(r, r, r)), mk_v3_add(a.hi, mk_v3(r, r, r))); }
MK_API MK_INLINE mk_vec3 mk_aabb_center(mk_aabb a) { return mk_v3_scale(mk_v3_add(a.lo, a.hi), MK_REAL(0.5)); }
MK_API MK_INLINE mk_vec3 mk_aabb_extents(mk_aabb a) { return mk_v3_scale(mk_v3_sub(a.hi, a.lo), MK_REAL(0.5)); }
/* Valid: lo <= hi on every axis, no NaN. Infinite bounds are allowed (ground planes). */
MK_API MK_INLINE int mk_aabb_is_valid(mk_aabb a) { return a.lo.x <= a.hi.x && a.lo.y <= a.hi.y && a.lo.z <= a.hi.z; }

#ifdef __cplusplus
}
#endif

#endif

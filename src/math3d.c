/* math3d.c: the one external definition of every inline function in minko/math3d.h,
 * and the pose constructors.
 * C99 6.7.4: an `extern` declaration in exactly one translation unit makes the
 * inline definitions from the header into exported symbols. scripts/check-exports.sh
 * fails the build if a header function is missing from libminko.so. */
#include "pose.h"

extern int mk_real_is_valid(mk_real a);
extern mk_real mk_min(mk_real a, mk_real b);
extern mk_real mk_max(mk_real a, mk_real b);
extern mk_real mk_clamp(mk_real a, mk_real lo, mk_real hi);
extern mk_vec3 mk_v3(mk_real x, mk_real y, mk_real z);
extern mk_vec3 mk_v3_zero(void);
extern mk_vec3 mk_v3_add(mk_vec3 a, mk_vec3 b);
extern mk_vec3 mk_v3_sub(mk_vec3 a, mk_vec3 b);
extern mk_vec3 mk_v3_neg(mk_vec3 a);
extern mk_vec3 mk_v3_scale(mk_vec3 a, mk_real s);
extern mk_vec3 mk_v3_mul(mk_vec3 a, mk_vec3 b);
extern mk_vec3 mk_v3_mad(mk_vec3 a, mk_real s, mk_vec3 b);
extern mk_vec3 mk_v3_lerp(mk_vec3 a, mk_vec3 b, mk_real t);
extern mk_real mk_v3_dot(mk_vec3 a, mk_vec3 b);
extern mk_vec3 mk_v3_cross(mk_vec3 a, mk_vec3 b);
extern mk_real mk_v3_len2(mk_vec3 a);
extern mk_real mk_v3_len(mk_vec3 a);
extern mk_real mk_v3_dist(mk_vec3 a, mk_vec3 b);
extern mk_vec3 mk_v3_min(mk_vec3 a, mk_vec3 b);
extern mk_vec3 mk_v3_max(mk_vec3 a, mk_vec3 b);
extern mk_vec3 mk_v3_abs(mk_vec3 a);
extern mk_real mk_v3_max_abs(mk_vec3 a);
extern mk_vec3 mk_v3_normalize(mk_vec3 a);
extern int mk_v3_is_valid(mk_vec3 a);
extern int mk_position_is_valid(mk_vec3 p);
extern mk_vec3 mk_v3_perp(mk_vec3 n);
extern mk_quat mk_quat_make(mk_real x, mk_real y, mk_real z, mk_real w);
extern mk_quat mk_quat_identity(void);
extern mk_quat mk_quat_conj(mk_quat q);
extern mk_real mk_quat_len2(mk_quat q);
extern mk_quat mk_quat_mul(mk_quat a, mk_quat b);
extern mk_quat mk_quat_normalize(mk_quat q);
extern mk_quat mk_quat_from_axis_angle(mk_vec3 axis, mk_real angle);
extern int mk_quat_is_valid(mk_quat q);
extern mk_vec3 mk_quat_rotate(mk_quat q, mk_vec3 v);
extern mk_vec3 mk_quat_inv_rotate(mk_quat q, mk_vec3 v);
extern mk_mat3 mk_mat3_cols(mk_vec3 c0, mk_vec3 c1, mk_vec3 c2);
extern mk_mat3 mk_mat3_identity(void);
extern mk_mat3 mk_mat3_from_quat(mk_quat q);
extern mk_quat mk_quat_from_mat3(mk_mat3 m);
extern mk_vec3 mk_mat3_mul_v3(mk_mat3 m, mk_vec3 v);
extern mk_vec3 mk_mat3_tmul_v3(mk_mat3 m, mk_vec3 v);
extern mk_mat3 mk_mat3_transpose(mk_mat3 m);
extern mk_mat3 mk_mat3_mul(mk_mat3 a, mk_mat3 b);
extern mk_mat3 mk_mat3_tmul(mk_mat3 a, mk_mat3 b);
extern mk_mat3 mk_mat3_abs(mk_mat3 m);
extern mk_transform mk_transform_make(mk_vec3 p, mk_quat q);
extern mk_transform mk_transform_identity(void);
extern mk_vec3 mk_transform_point(mk_transform t, mk_vec3 v);
extern mk_vec3 mk_transform_inv_point(mk_transform t, mk_vec3 v);
extern mk_transform mk_transform_mul(mk_transform a, mk_transform b);
extern mk_transform mk_transform_inv_mul(mk_transform a, mk_transform b);
extern int mk_transform_is_valid(mk_transform t);
extern mk_aabb mk_aabb_make(mk_vec3 lo, mk_vec3 hi);
extern int mk_aabb_overlap(mk_aabb a, mk_aabb b);
extern int mk_aabb_contains(mk_aabb outer, mk_aabb inner);
extern mk_aabb mk_aabb_union(mk_aabb a, mk_aabb b);
extern mk_aabb mk_aabb_expand(mk_aabb a, mk_real r);
extern mk_vec3 mk_aabb_center(mk_aabb a);
extern mk_vec3 mk_aabb_extents(mk_aabb a);
extern int mk_aabb_is_valid(mk_aabb a);

mk_status mk_transform_check_(mk_transform x)
{
    mk_quat q = x.q;
    if (!mk_v3_is_valid(x.p) || !mk_real_is_valid(q.x) || !mk_real_is_valid(q.y) || !mk_real_is_valid(q.z) || !mk_real_is_valid(q.w))
        return MK_ERR_NOT_FINITE;
    if (!mk_position_is_valid(x.p)) return MK_ERR_OUT_OF_RANGE;
    return mk_quat_is_valid(q) ? MK_OK : MK_ERR_BAD_ROTATION;
}

mk_status mk_pose_from_transform(mk_transform x, mk_pose *out)
{
    mk_status st;
    if (!out) return MK_ERR_NULL;
    if (!mk_transform_ok_(&x) && (st = mk_transform_check_(x)) != MK_OK) return st;
    mk_pose_set_(out, &x);
    return MK_OK;
}

/* The largest deviation of r^T r from the identity. Built with mk_max,
 * which passes an infinity on but can drop a NaN; the caller's determinant
 * test catches NaN instead (every entry of r is a factor in it). */
static mk_real orthonormality_error(const mk_mat3 *r)
{
    mk_real e = mk_max(mk_fabs_(mk_v3_len2(r->c0) - 1), mk_fabs_(mk_v3_len2(r->c1) - 1));
    e = mk_max(e, mk_max(mk_fabs_(mk_v3_len2(r->c2) - 1), mk_fabs_(mk_v3_dot(r->c0, r->c1))));
    return mk_max(e, mk_max(mk_fabs_(mk_v3_dot(r->c0, r->c2)), mk_fabs_(mk_v3_dot(r->c1, r->c2))));
}

/* Names what mk_pose_from_matrix refused: non-finite numbers, then the
 * range of p, then the rotation. */
static MK_NOINLINE mk_status matrix_check(const mk_mat3 *r, mk_vec3 p)
{
    if (!mk_v3_is_valid(r->c0) || !mk_v3_is_valid(r->c1) || !mk_v3_is_valid(r->c2) || !mk_v3_is_valid(p)) return MK_ERR_NOT_FINITE;
    return mk_position_is_valid(p) ? MK_ERR_BAD_ROTATION : MK_ERR_OUT_OF_RANGE;
}

mk_status mk_pose_from_matrix(mk_mat3 r, mk_vec3 p, mk_pose *out)
{
    mk_real e;
    if (!out) return MK_ERR_NULL;
    e = orthonormality_error(&r);
    /* One test accepts: orthonormal within the tolerance (an infinite entry
     * makes e infinite), not a reflection (det = c2 . (c0 x c1) is then near
     * +-1; a NaN entry makes it NaN), and p in range (NaN fails too). So the
     * accepting path checks finiteness without a test of its own. */
    if (!(e <= MK_ROTATION_TOLERANCE) || !(mk_v3_dot(r.c2, mk_v3_cross(r.c0, r.c1)) > 0) || !mk_position_is_valid(p))
        return matrix_check(&r, p);
    if (e > 32 * MK_REAL_EPSILON) {
        /* Drifted beyond rounding: queries take r^T as r's inverse, so hand them an exact rotation. */
        r.c0 = mk_v3_normalize(r.c0);
        r.c1 = mk_v3_normalize(mk_v3_mad(r.c1, -mk_v3_dot(r.c0, r.c1), r.c0));
        r.c2 = mk_v3_cross(r.c0, r.c1);
    }
    out->r = r;
    out->p = p;
    out->checked = MK_POSE_CHECKED_;
    return MK_OK;
}

mk_status mk_pose_set_position(mk_pose *x, mk_vec3 p)
{
    if (!x) return MK_ERR_NULL;
    if (!mk_pose_ok_(x)) return MK_ERR_UNCHECKED_POSE;
    if (!mk_position_is_valid(p)) return mk_v3_is_valid(p) ? MK_ERR_OUT_OF_RANGE : MK_ERR_NOT_FINITE;
    x->p = p;
    return MK_OK;
}

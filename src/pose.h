/* pose.h: checked poses inside the library (internal; see minko/math3d.h).
 *
 * The mk_transform entry points are wrappers: one quick accepting test
 * (mk_transform_ok_), the conversion (mk_pose_set_), and the pose-taking
 * query. The pose queries pay only mk_pose_ok_ per pose and build the pair
 * from matrices (mk_pair_of_poses_): no quaternion in the hot path.
 */
#ifndef MINKO_POSE_H
#define MINKO_POSE_H

#include "gjk.h"

/* The value of mk_pose.checked that the constructors write ("MKPS"). */
#define MK_POSE_CHECKED_ 0x4d4b5053u

MK_ALWAYS_INLINE int mk_pose_ok_(const mk_pose *x) { return x->checked == MK_POSE_CHECKED_; }

/* 1 exactly when mk_transform_check_(*x) is MK_OK: a position within
 * MK_MAX_COORD (NaN fails the comparisons) and | |q|^2 - 1 | within
 * MK_QUAT_TOLERANCE (NaN or infinite components fail it too). */
MK_ALWAYS_INLINE int mk_transform_ok_(const mk_transform *x)
{
    return mk_position_is_valid(x->p) && mk_fabs_(mk_quat_len2(x->q) - 1) <= MK_QUAT_TOLERANCE;
}

/* Names what is wrong with a transform: non-finite numbers, then a
 * coordinate beyond MK_MAX_COORD, then a quaternion that is not unit. */
mk_status mk_transform_check_(mk_transform x);

/* The pose of an accepted transform: its quaternion's exact rotation
 * (mk_rotation_of) as a matrix. */
MK_ALWAYS_INLINE void mk_pose_set_(mk_pose *out, const mk_transform *x)
{
    out->r = mk_rotation_of(x->q);
    out->p = x->p;
    out->checked = MK_POSE_CHECKED_;
}

/* B's pose in A's frame from two checked poses. Subtracting the positions
 * first keeps large coordinates exact. */
MK_ALWAYS_INLINE mk_pair mk_pair_of_poses_(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb)
{
    mk_pair p;
    p.a = a;
    p.b = b;
    p.r = mk_mat3_tmul(xa->r, xb->r);
    p.t = mk_mat3_tmul_v3(xa->r, mk_v3_sub(xb->p, xa->p));
    return p;
}

/* The same pair from two accepted transforms (tests build pairs this way). */
static inline mk_pair mk_pair_make(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb)
{
    mk_pose pa, pb;
    mk_pose_set_(&pa, &xa);
    mk_pose_set_(&pb, &xb);
    return mk_pair_of_poses_(a, &pa, b, &pb);
}

#endif

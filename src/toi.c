/* toi.c: continuous collision: sweeps and swept bounds (minko/toi.h). */
#include <math.h>

#include "minko/toi.h"
#include "shape_internal.h"

static mk_status check_transform(mk_transform xf)
{
    if (!mk_v3_is_valid(xf.p) || !mk_real_is_valid(xf.q.x + xf.q.y + xf.q.z + xf.q.w)) return MK_ERR_NOT_FINITE;
    return mk_quat_is_valid(xf.q) ? MK_OK : MK_ERR_BAD_ROTATION;
}

/* A few ulps of slack: from_transforms can land a hair above pi. */
static int angle_ok(mk_vec3 rotation) { return mk_v3_len(rotation) <= MK_SWEEP_MAX_ANGLE * (1 + 8 * MK_REAL_EPSILON); }

mk_status mk_sweep_validate(const mk_sweep *sw)
{
    if (!sw) return MK_ERR_NULL;
    if (!mk_v3_is_valid(sw->local_center) || !mk_v3_is_valid(sw->c0) || !mk_v3_is_valid(sw->c1) || !mk_v3_is_valid(sw->rotation) ||
        !mk_real_is_valid(sw->q0.x + sw->q0.y + sw->q0.z + sw->q0.w))
        return MK_ERR_NOT_FINITE;
    if (!mk_quat_is_valid(sw->q0)) return MK_ERR_BAD_ROTATION;
    return angle_ok(sw->rotation) ? MK_OK : MK_ERR_BAD_ARGUMENT;
}

/* Orientation at t: the step's rotation, scaled by t, applied after q0. */
static mk_quat sweep_rotation(const mk_sweep *sw, mk_real t)
{
    return mk_quat_mul(mk_quat_from_axis_angle(sw->rotation, t * mk_v3_len(sw->rotation)), mk_quat_normalize(sw->q0));
}

static mk_transform sweep_pose(const mk_sweep *sw, mk_real t)
{
    mk_quat q = sweep_rotation(sw, t);
    mk_vec3 c = mk_v3_lerp(sw->c0, sw->c1, t);
    return mk_transform_make(mk_v3_sub(c, mk_quat_rotate(q, sw->local_center)), q);
}

mk_status mk_sweep_from_transforms(mk_transform x0, mk_transform x1, mk_vec3 local_center, mk_sweep *out)
{
    mk_status st;
    mk_quat q0, q1, dq;
    mk_real s, angle;
    if (!out) return MK_ERR_NULL;
    if ((st = check_transform(x0)) != MK_OK || (st = check_transform(x1)) != MK_OK) return st;
    if (!mk_v3_is_valid(local_center)) return MK_ERR_NOT_FINITE;
    q0 = mk_quat_normalize(x0.q);
    q1 = mk_quat_normalize(x1.q);
    dq = mk_quat_mul(q1, mk_quat_conj(q0));
    if (dq.w < 0) dq = mk_quat_make(-dq.x, -dq.y, -dq.z, -dq.w); /* the short way round */
    s = mk_sqrt_(dq.x * dq.x + dq.y * dq.y + dq.z * dq.z);
    angle = (mk_real)(2 * atan2((double)s, (double)dq.w));
    out->local_center = local_center;
    out->c0 = mk_transform_point(mk_transform_make(x0.p, q0), local_center);
    out->c1 = mk_transform_point(mk_transform_make(x1.p, q1), local_center);
    out->q0 = q0;
    out->rotation = s > 0 ? mk_v3_scale(mk_v3(dq.x, dq.y, dq.z), angle / s) : mk_v3_zero();
    return MK_OK;
}

mk_status mk_sweep_from_velocity(mk_transform x0, mk_vec3 linear_velocity, mk_vec3 angular_velocity, mk_real dt, mk_vec3 local_center,
                                 mk_sweep *out)
{
    mk_status st;
    mk_vec3 rotation;
    if (!out) return MK_ERR_NULL;
    if ((st = check_transform(x0)) != MK_OK) return st;
    if (!mk_v3_is_valid(linear_velocity) || !mk_v3_is_valid(angular_velocity) || !mk_real_is_valid(dt) || !mk_v3_is_valid(local_center))
        return MK_ERR_NOT_FINITE;
    rotation = mk_v3_scale(angular_velocity, dt);
    if (dt < 0 || !mk_v3_is_valid(rotation) || !angle_ok(rotation)) return MK_ERR_BAD_ARGUMENT;
    out->local_center = local_center;
    out->q0 = mk_quat_normalize(x0.q);
    out->c0 = mk_transform_point(mk_transform_make(x0.p, out->q0), local_center);
    out->c1 = mk_v3_mad(out->c0, dt, linear_velocity);
    out->rotation = rotation;
    return mk_v3_is_valid(out->c1) ? MK_OK : MK_ERR_NOT_FINITE;
}

mk_status mk_sweep_transform(const mk_sweep *sw, mk_real t, mk_transform *out)
{
    mk_status st;
    if (!out) return MK_ERR_NULL;
    if ((st = mk_sweep_validate(sw)) != MK_OK) return st;
    if (!mk_real_is_valid(t)) return MK_ERR_NOT_FINITE;
    if (t < 0 || t > 1) return MK_ERR_BAD_ARGUMENT;
    *out = sweep_pose(sw, t);
    return MK_OK;
}

/* Largest distance from c (shape frame) to a point of the solid. */
static mk_real bounding_radius(const mk_shape *s, mk_vec3 c)
{
    mk_real rho_c = mk_sqrt_(c.x * c.x + c.y * c.y), far = 0;
    switch (s->type) {
    case MK_SHAPE_SPHERE: far = mk_v3_len(c); break;
    case MK_SHAPE_BOX: far = mk_v3_len(mk_v3_add(mk_v3_abs(c), s->u.half_extents)); break;
    case MK_SHAPE_CAPSULE: far = mk_v3_len(mk_v3(rho_c, 0, mk_fabs_(c.z) + s->u.capsule.half_height)); break;
    case MK_SHAPE_CYLINDER:
        far = mk_v3_len(mk_v3(rho_c + s->u.cylinder.radius, 0, mk_fabs_(c.z) + s->u.cylinder.half_height));
        break;
    case MK_SHAPE_CONE: {
        mk_real h = s->u.cone.half_height;
        far = mk_max(mk_v3_dist(c, mk_v3(0, 0, h)), mk_v3_len(mk_v3(rho_c + s->u.cone.radius, 0, c.z + h)));
        break;
    }
    case MK_SHAPE_HULL: {
        const mk_hull *h = s->u.hull;
        int i;
        for (i = 0; i < h->vertex_count; ++i) far = mk_max(far, mk_v3_dist(c, h->vertices[i]));
        break;
    }
    default: break;
    }
    return far + s->radius;
}

mk_status mk_swept_aabb(const mk_shape *s, const mk_sweep *sw, mk_aabb *out)
{
    mk_status st;
    mk_aabb a0, a1, ball;
    mk_real rho, angle, sag, slack;
    if (!out) return MK_ERR_NULL;
    if ((st = mk_shape_validate(s)) != MK_OK) return st;
    if ((st = mk_sweep_validate(sw)) != MK_OK) return st;
    if (s->type == MK_SHAPE_PLANE) return MK_ERR_UNSUPPORTED;
    mk_shape_aabb(s, sweep_pose(sw, 0), &a0);
    mk_shape_aabb(s, sweep_pose(sw, 1), &a1);
    rho = bounding_radius(s, sw->local_center);
    angle = mk_v3_len(sw->rotation);
    /* A point at distance rho from the axis strays at most rho (1 - cos(angle/2))
     * from the chord between its start and end positions (at mid-step), and the
     * chord lies in the union of the start and end boxes. 2 sin^2(a/4) is
     * 1 - cos(a/2) without the cancellation. */
    sag = (mk_real)sin(0.25 * (double)angle);
    sag = 2 * rho * sag * sag;
    /* Rounding in the poses themselves. */
    slack = 8 * MK_REAL_EPSILON * (rho + mk_v3_max_abs(sw->c0) + mk_v3_max_abs(sw->c1));
    ball = mk_aabb_expand(mk_aabb_make(mk_v3_min(sw->c0, sw->c1), mk_v3_max(sw->c0, sw->c1)), rho + slack);
    a0 = mk_aabb_expand(mk_aabb_union(a0, a1), sag + slack);
    *out = mk_aabb_make(mk_v3_max(a0.lo, ball.lo), mk_v3_min(a0.hi, ball.hi));
    return MK_OK;
}

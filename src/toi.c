/* toi.c: continuous collision: sweeps and swept bounds (minko/toi.h). */
#include <math.h>
#include <string.h>

#include "minko/distance.h"
#include "minko/toi.h"
#include "pose.h"

/* A few ulps of slack: from_transforms can land a hair above pi. */
static int angle_ok(mk_vec3 rotation) { return mk_v3_len(rotation) <= MK_SWEEP_MAX_ANGLE * (1 + 8 * MK_REAL_EPSILON); }

mk_status mk_sweep_validate(const mk_sweep *sw)
{
    if (!sw) return MK_ERR_NULL;
    if (!mk_v3_is_valid(sw->local_center) || !mk_v3_is_valid(sw->c0) || !mk_v3_is_valid(sw->c1) || !mk_v3_is_valid(sw->rotation) ||
        !mk_real_is_valid(sw->q0.x + sw->q0.y + sw->q0.z + sw->q0.w))
        return MK_ERR_NOT_FINITE;
    /* Centres and the body's centre offset within MK_MAX_COORD keep the poses along the sweep in the range queries accept. */
    if (!mk_position_is_valid(sw->c0) || !mk_position_is_valid(sw->c1) || !mk_position_is_valid(sw->local_center))
        return MK_ERR_OUT_OF_RANGE;
    if (!mk_quat_is_valid(sw->q0)) return MK_ERR_BAD_ROTATION;
    return angle_ok(sw->rotation) ? MK_OK : MK_ERR_BAD_ARGUMENT;
}

/* Orientation at t of a body that turns by `angle` about the unit `axis`
 * (zero: no turn) over the step, from the unit q0. */
static mk_quat rotation_at(mk_vec3 axis, mk_real angle, mk_quat q0, mk_real t)
{
    double h = 0.5 * (double)(t * angle);
    mk_real s = (mk_real)sin(h);
    return mk_quat_mul(mk_quat_make(axis.x * s, axis.y * s, axis.z * s, (mk_real)cos(h)), q0);
}

/* Orientation at t: the step's rotation, scaled by t, applied after q0. */
static mk_quat sweep_rotation(const mk_sweep *sw, mk_real t)
{
    return rotation_at(mk_v3_normalize(sw->rotation), mk_v3_len(sw->rotation), mk_quat_normalize(sw->q0), t);
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
    mk_vec3 c0, c1;
    mk_real s, angle;
    if (!out) return MK_ERR_NULL;
    if ((st = mk_transform_check_(x0)) != MK_OK || (st = mk_transform_check_(x1)) != MK_OK) return st;
    if (!mk_v3_is_valid(local_center)) return MK_ERR_NOT_FINITE;
    if (!mk_position_is_valid(local_center)) return MK_ERR_OUT_OF_RANGE;
    q0 = mk_quat_normalize(x0.q);
    q1 = mk_quat_normalize(x1.q);
    dq = mk_quat_mul(q1, mk_quat_conj(q0));
    if (dq.w < 0) dq = mk_quat_make(-dq.x, -dq.y, -dq.z, -dq.w); /* the short way round */
    s = mk_sqrt_(dq.x * dq.x + dq.y * dq.y + dq.z * dq.z);
    angle = (mk_real)(2 * atan2((double)s, (double)dq.w));
    c0 = mk_transform_point(mk_transform_make(x0.p, q0), local_center);
    c1 = mk_transform_point(mk_transform_make(x1.p, q1), local_center);
    if (!mk_position_is_valid(c0) || !mk_position_is_valid(c1)) return MK_ERR_OUT_OF_RANGE;
    out->local_center = local_center;
    out->c0 = c0;
    out->c1 = c1;
    out->q0 = q0;
    out->rotation = s > 0 ? mk_v3_scale(mk_v3(dq.x, dq.y, dq.z), angle / s) : mk_v3_zero();
    return MK_OK;
}

mk_status mk_sweep_from_velocity(mk_transform x0, mk_vec3 linear_velocity, mk_vec3 angular_velocity, mk_real dt, mk_vec3 local_center,
                                 mk_sweep *out)
{
    mk_status st;
    mk_vec3 rotation, c0, c1;
    mk_quat q0;
    if (!out) return MK_ERR_NULL;
    if ((st = mk_transform_check_(x0)) != MK_OK) return st;
    if (!mk_v3_is_valid(linear_velocity) || !mk_v3_is_valid(angular_velocity) || !mk_real_is_valid(dt) || !mk_v3_is_valid(local_center))
        return MK_ERR_NOT_FINITE;
    rotation = mk_v3_scale(angular_velocity, dt);
    if (dt < 0 || !mk_v3_is_valid(rotation) || !angle_ok(rotation)) return MK_ERR_BAD_ARGUMENT;
    if (!mk_position_is_valid(local_center)) return MK_ERR_OUT_OF_RANGE;
    q0 = mk_quat_normalize(x0.q);
    c0 = mk_transform_point(mk_transform_make(x0.p, q0), local_center);
    c1 = mk_v3_mad(c0, dt, linear_velocity);
    if (!mk_v3_is_valid(c1)) return MK_ERR_NOT_FINITE;
    if (!mk_position_is_valid(c0) || !mk_position_is_valid(c1)) return MK_ERR_OUT_OF_RANGE;
    out->local_center = local_center;
    out->q0 = q0;
    out->c0 = c0;
    out->c1 = c1;
    out->rotation = rotation;
    return MK_OK;
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

/* Largest distance from c (shape frame) to a point of the solid, or a bound on it. */
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
    case MK_SHAPE_HULL: /* O(1): through the centroid, exact when c is the centroid */
        far = mk_v3_dist(c, s->u.hull->centroid) + s->u.hull->outer_radius;
        break;
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

/* ---- time of impact ---------------------------------------------------------
 *
 * Conservative advancement with second-order bounds. At a time t0 proven free
 * of contact the distance query gives a separating normal n. The separation
 * of the shapes along any axis e, s(t) = min over B of e.y - max over A of
 * e.x, is a lower bound of their distance, so a lower bound L(d) of
 * s(t0 + d) - target that stays positive on [0, d*) proves the shapes keep
 * farther apart than target until t0 + d*. Each body moves its centre at a
 * constant velocity and turns at a constant rate w about it; turning a unit
 * vector u for a time d moves it off its tangent line by at most
 * d^2/2 |w| |w x u| (the Taylor remainder of e^{i phi}), so with h the
 * support function about the centre and rho the bounding radius,
 *     h(Q(d)^T u) <= h(u + d u x w) + d^2/2 |w| |u x w| rho.
 * Support functions are convex and the direction is affine in d, so each L
 * below is concave: its one root is bracketed by Newton steps from the right
 * and chords from the left, whose sides the sign of L tells apart. Three axes:
 *  - fixed in the world: tight when both supports along n are single points
 *    (vertex or smooth contacts);
 *  - turning with A, or with B: tight when n is a face normal of that shape,
 *    where a fixed axis would see the face's far edge rise at first order.
 * Any one root is a proof; the step is the largest, and never shorter than
 * Mirtich's linear bound (projected relative speed + |n x w| rho). L has the
 * true slope of the separation at d = 0, so the advancement converges
 * quadratically where Mirtich's converges linearly, and a translating face
 * contact is reached in one step. The exception: when both supports along n
 * are edges or faces (parallel features) of shapes turning relative to each
 * other, any separating plane sees the features' far ends swing at first
 * order, and convergence is linear (still faster than Mirtich's). */

/* Distance queries per TOI. Typical runs need 2 to 8; edge-edge and face-face
 * contacts between turning shapes converge linearly (every separating plane
 * sees the far ends of the parallel features swing), about 0.7 per step, which
 * needs ~80 steps from a far start down to the rounding floor. */
#define TOI_MAX_ITERATIONS 128
#define TOI_MAX_ROOT_ITERATIONS 12 /* pairs of bound evaluations per step */

/* Tolerance floor, relative to the pair's size and travel: the accuracy of
 * the distance queries (GJK stops at ~1e4 eps relative in double). */
#if defined(MK_SINGLE)
#  define TOI_TOL_FLOOR (MK_REAL(1e2) * MK_REAL_EPSILON)
#else
#  define TOI_TOL_FLOOR (MK_REAL(1e4) * MK_REAL_EPSILON)
#endif
/* A plane's sweep may carry this much rotation from rounding (equal start
 * and end orientations); it is treated as none. */
#define TOI_PLANE_STILL (MK_REAL(1e3) * MK_REAL_EPSILON)

typedef struct toi_body {
    const mk_shape *s;
    const mk_sweep *sw;
    mk_vec3 dc;    /* c1 - c0 */
    mk_vec3 w;     /* rotation over the step */
    mk_real rho;   /* bounding radius about the rotation centre */
    mk_vec3 axis;  /* the turn, split once so that each time costs one sin and one cos: */
    mk_real angle; /* unit axis (zero: none), angle over the step, */
    mk_quat q0;    /* unit orientation at t = 0 */
    mk_quat q;     /* orientation at the time being expanded */
    mk_mat3 R;     /* the same as a matrix */
    mk_vec3 c;     /* rotation centre at that time, relative to A's c0 */
    int hint;      /* support vertex hint */
    int turning;   /* 0: R is the same at every time */
    mk_vec3 foot;  /* a plane's support: the foot of the centre on it (planes never turn) */
} toi_body;

/* L(d) = c0 + c1 d + c2 d^2 + c3 d^3 - sum_i h_i(u_i + d v_i), with c2, c3 <= 0. */
typedef struct toi_bound {
    mk_real c0, c1, c2, c3;
    toi_body *body[2];
    mk_vec3 u[2], v[2];
    int terms;
} toi_bound;

static void body_init(toi_body *b, const mk_shape *s, const mk_sweep *sw, mk_vec3 origin)
{
    b->s = s;
    b->sw = sw;
    b->dc = mk_v3_sub(sw->c1, sw->c0);
    b->w = s->type == MK_SHAPE_PLANE ? mk_v3_zero() : sw->rotation;
    b->rho = s->type == MK_SHAPE_PLANE ? 0 : bounding_radius(s, sw->local_center);
    b->c = mk_v3_sub(sw->c0, origin);
    b->angle = mk_v3_len(sw->rotation);
    b->axis = b->angle > 0 ? mk_v3_scale(sw->rotation, 1 / b->angle) : mk_v3_zero();
    b->q0 = b->q = mk_quat_normalize(sw->q0);
    b->R = mk_mat3_from_quat(b->q);
    b->hint = -1;
    /* A turn that moves no point by more than the rounding of the coordinates
     * (equal start and end orientations up to renormalisation) is no turn. */
    b->turning = s->type != MK_SHAPE_PLANE && b->angle * b->rho > 8 * MK_REAL_EPSILON * (b->rho + mk_v3_max_abs(sw->c0));
    if (s->type == MK_SHAPE_PLANE)
        b->foot = mk_v3_scale(mk_mat3_mul_v3(b->R, s->u.plane.normal), s->u.plane.offset - mk_v3_dot(s->u.plane.normal, sw->local_center));
}

static void body_at(toi_body *b, mk_real t, mk_vec3 origin)
{
    if (b->turning) {
        b->q = rotation_at(b->axis, b->angle, b->q0, t);
        b->R = mk_mat3_from_quat(b->q);
    }
    b->c = mk_v3_mad(mk_v3_sub(b->sw->c0, origin), t, b->dc);
}

/* The shape's own origin at the body's current time, relative to `origin`. */
static mk_vec3 body_position(const toi_body *b) { return mk_v3_sub(b->c, mk_mat3_mul_v3(b->R, b->sw->local_center)); }

static mk_transform body_pose(const toi_body *b, mk_vec3 origin) { return mk_transform_make(mk_v3_add(body_position(b), origin), b->q); }

/* Support point of the solid along world direction m (not unit), as an
 * offset from the rotation centre. A plane cannot turn and is only ever
 * asked along its outward normal: the answer is the foot of the centre. */
MK_ALWAYS_INLINE mk_vec3 support_rel(toi_body *b, mk_vec3 m)
{
    mk_vec3 p, w;
    mk_real l;
    if (b->s->type == MK_SHAPE_PLANE) return b->foot;
    p = mk_core_support_inl(b->s, mk_mat3_tmul_v3(b->R, m), &b->hint);
    w = mk_mat3_mul_v3(b->R, mk_v3_sub(p, b->sw->local_center));
    if (b->s->radius > 0 && (l = mk_v3_len(m)) > 0) w = mk_v3_mad(w, b->s->radius / l, m);
    return w;
}

/* L and a supergradient of it (any support point is a subgradient of h). */
static mk_real bound_eval(const toi_bound *L, mk_real d, mk_real *slope)
{
    mk_real value = L->c0 + d * (L->c1 + d * (L->c2 + d * L->c3));
    int i;
    *slope = L->c1 + d * (2 * L->c2 + 3 * d * L->c3);
    for (i = 0; i < L->terms; ++i) {
        mk_vec3 m = mk_v3_mad(L->u[i], d, L->v[i]);
        mk_vec3 w = support_rel(L->body[i], m);
        value -= mk_v3_dot(m, w);
        *slope -= mk_v3_dot(L->v[i], w);
    }
    return value;
}

/* Adds body b's support term h(u + d v) to L, or, for a body that does not
 * turn (v = 0), its constant value. */
static void bound_term(toi_bound *L, toi_body *b, mk_vec3 u, mk_vec3 v)
{
    if (!b->turning) {
        L->c0 -= mk_v3_dot(u, support_rel(b, u));
        return;
    }
    L->body[L->terms] = b;
    L->u[L->terms] = u;
    L->v[L->terms] = v;
    ++L->terms;
}

/* Axis n fixed in the world; D = cB - cA at t0, V = dcB - dcA. */
static toi_bound bound_fixed(toi_body *a, toi_body *b, mk_vec3 n, mk_vec3 D, mk_vec3 V, mk_real target)
{
    toi_bound L;
    mk_vec3 ra = mk_v3_cross(n, a->w), rb = mk_v3_cross(n, b->w);
    L.c0 = mk_v3_dot(n, D) - target;
    L.c1 = mk_v3_dot(n, V);
    L.c2 = -MK_REAL(0.5) * (mk_v3_len(a->w) * mk_v3_len(ra) * a->rho + mk_v3_len(b->w) * mk_v3_len(rb) * b->rho);
    L.c3 = 0;
    L.terms = 0;
    bound_term(&L, a, n, ra);
    bound_term(&L, b, mk_v3_neg(n), mk_v3_neg(rb));
    return L;
}

/* Axis e (from T towards O) turning with T: T's term is constant, O's
 * direction turns with the relative rotation Q_O^T Q_T e = e + d b + R,
 * |R| <= d^2 (|wO| |wO x e| / 2 + |wO x a| + |wT| |a| / 2), a = wT x e, and
 * the centre term e(d).(D + d V) loses at most |wT| |a| d^2 / 2 (|D| + d |V|).
 * D = cO - cT at t0, V = dcO - dcT. */
static toi_bound bound_turning(toi_body *T, toi_body *O, mk_vec3 e, mk_vec3 D, mk_vec3 V, mk_real target)
{
    toi_bound L;
    mk_vec3 a = mk_v3_cross(T->w, e), b = mk_v3_cross(mk_v3_sub(T->w, O->w), e);
    mk_real wt = mk_v3_len(T->w), wo = mk_v3_len(O->w), la = mk_v3_len(a);
    L.c0 = mk_v3_dot(e, D) - mk_v3_dot(e, support_rel(T, e)) - target;
    L.c1 = mk_v3_dot(a, D) + mk_v3_dot(e, V);
    L.c2 = mk_min(0, mk_v3_dot(a, V)) - MK_REAL(0.5) * wt * la * mk_v3_len(D) -
           O->rho * (MK_REAL(0.5) * wo * mk_v3_len(mk_v3_cross(O->w, e)) + mk_v3_len(mk_v3_cross(O->w, a)) + MK_REAL(0.5) * wt * la);
    L.c3 = -MK_REAL(0.5) * wt * la * mk_v3_len(V);
    L.terms = 1; /* O's direction turns with T even when O itself does not */
    L.body[0] = O;
    L.u[0] = mk_v3_neg(e);
    L.v[0] = mk_v3_neg(b);
    return L;
}

/* What one iteration learns at time t: an upper bound on the distance, a
 * separating direction (world, from A towards B) and the separation along it
 * (a lower bound on the distance). */
typedef struct toi_query {
    mk_real distance;
    mk_vec3 normal;
    mk_real separation;
} toi_query;

/* A plane's normal is the exact separating axis, and two spheres are their
 * centres' distance: such pairs need no narrowphase (a sphere-only scene never
 * runs GJK), and the deepest points along the normal are the witnesses. */
static int plane_pair(const toi_body *a, const toi_body *b) { return a->s->type == MK_SHAPE_PLANE || b->s->type == MK_SHAPE_PLANE; }
static int sphere_pair(const toi_body *a, const toi_body *b) { return a->s->type == MK_SHAPE_SPHERE && b->s->type == MK_SHAPE_SPHERE; }

static mk_real separation(toi_body *a, toi_body *b, mk_vec3 n)
{
    return mk_v3_dot(n, mk_v3_sub(mk_v3_add(b->c, support_rel(b, mk_v3_neg(n))), mk_v3_add(a->c, support_rel(a, n))));
}

/* Distance bound and normal at t; leaves both bodies' frames at t. The loop
 * runs GJK on the cores directly (no input checks, no polish, a warm start
 * from the previous time); the polished answer is computed once, at the end. */
static mk_status estimate_at(toi_body *a, toi_body *b, mk_real t, mk_vec3 origin, mk_gjk_cache *cache, toi_query *q)
{
    body_at(a, t, origin);
    body_at(b, t, origin);
    if (plane_pair(a, b)) {
        q->normal = a->s->type == MK_SHAPE_PLANE ? mk_mat3_mul_v3(a->R, a->s->u.plane.normal)
                                                 : mk_v3_neg(mk_mat3_mul_v3(b->R, b->s->u.plane.normal));
        q->distance = q->separation = separation(a, b, q->normal);
        return MK_OK;
    }
    if (sphere_pair(a, b)) {
        mk_vec3 d = mk_v3_sub(body_position(b), body_position(a));
        mk_real l = mk_v3_len(d);
        q->normal = l > 0 ? mk_v3_scale(d, 1 / l) : mk_v3(0, 0, 1); /* concentric: any direction is a way out */
        q->distance = q->separation = l - a->s->radius - b->s->radius;
        return MK_OK;
    }
#ifndef MK_WITHOUT_GJK
    {
        mk_pair p;
        mk_gjk_result g;
        p.a = a->s;
        p.b = b->s;
        p.r = mk_mat3_tmul(a->R, b->R);
        p.t = mk_mat3_tmul_v3(a->R, mk_v3_sub(body_position(b), body_position(a)));
        mk_gjk(&p, cache, 0, 0, &g);
        mk_gjk_cache_store(&g.s, g.normal, cache);
        q->distance = g.upper - a->s->radius - b->s->radius;
        if (g.lower > -(mk_real)HUGE_VAL) {
            q->normal = mk_mat3_mul_v3(a->R, g.normal);
            q->separation = g.lower - a->s->radius - b->s->radius;
        } else { /* no lower bound at all: GJK's normal is a placeholder */
            q->normal = mk_mat3_mul_v3(a->R, mk_v3_normalize(mk_v3_neg(g.v)));
            q->separation = separation(a, b, q->normal);
        }
        return MK_OK;
    }
#else
    {
        mk_distance_result r;
        mk_status st = mk_distance(a->s, body_pose(a, origin), b->s, body_pose(b, origin), cache, &r);
        q->distance = r.distance;
        q->normal = r.normal;
        q->separation = separation(a, b, q->normal);
        return st;
    }
#endif
}

/* The reported answer at t (frames already at t): the polished distance and
 * witness points of the narrowphase, or for plane and sphere pairs and when
 * `exact` is 0 (SEPARATED, FAILED), the deepest points along the last normal. */
static mk_status answer_at(toi_body *a, toi_body *b, mk_real t, mk_vec3 origin, const toi_query *q, int exact, mk_gjk_cache *cache,
                           mk_toi_result *out)
{
    mk_vec3 pa, pb, va, vb;
    out->t = t;
    if (exact && !plane_pair(a, b) && !sphere_pair(a, b)) {
        mk_distance_result r;
        mk_status st = mk_distance(a->s, body_pose(a, origin), b->s, body_pose(b, origin), cache, &r);
        if (st != MK_OK) return st;
        out->distance = r.distance;
        out->normal = r.normal;
        out->point_a = r.point_a;
        out->point_b = r.point_b;
    } else {
        pa = mk_v3_add(a->c, support_rel(a, q->normal));
        pb = mk_v3_add(b->c, support_rel(b, mk_v3_neg(q->normal)));
        out->distance = mk_v3_dot(q->normal, mk_v3_sub(pb, pa));
        out->normal = q->normal;
        /* A plane's witness is the foot of the other shape's deepest point. */
        if (a->s->type == MK_SHAPE_PLANE) pa = mk_v3_mad(pb, -out->distance, q->normal);
        if (b->s->type == MK_SHAPE_PLANE) pb = mk_v3_mad(pa, out->distance, q->normal);
        out->point_a = mk_v3_add(pa, origin);
        out->point_b = mk_v3_add(pb, origin);
    }
    /* d(distance)/dt: the relative velocity of the two material points along the normal. */
    va = mk_v3_add(a->dc, mk_v3_cross(a->w, mk_v3_sub(mk_v3_sub(out->point_a, origin), a->c)));
    vb = mk_v3_add(b->dc, mk_v3_cross(b->w, mk_v3_sub(mk_v3_sub(out->point_b, origin), b->c)));
    out->rate = mk_v3_dot(out->normal, mk_v3_sub(vb, va));
    return MK_OK;
}

/* A bracket [lo, hi] of the root of L: L(lo) >= 0 > L(hi). */
typedef struct toi_bracket {
    mk_real lo, glo, hi, ghi, shi;
} toi_bracket;

/* L is concave, so the sign of L(trial) says on which side of the root a
 * trial lies, whichever way it was found. */
static int bracket_try(toi_bracket *k, const toi_bound *L, mk_real trial)
{
    mk_real g, s;
    if (!(trial > k->lo && trial < k->hi)) return 0;
    g = bound_eval(L, trial, &s);
    if (g >= 0) {
        k->lo = trial;
        k->glo = g;
    } else {
        k->hi = trial;
        k->ghi = g;
        k->shi = s;
    }
    return 1;
}

/* Root of L beyond lo, given L(lo) = glo >= 0 and a supergradient slo there;
 * *clear when L stays positive up to dmax. The tangent at lo meets zero at or
 * beyond the root (L is concave), which brackets the root tightly from the
 * first trial; refinement stops once the gap it could still win, (hi - lo)
 * times the rate, is below `slack`. */
static mk_real bound_root(const toi_bound *L, mk_real lo, mk_real glo, mk_real slo, mk_real dmax, mk_real slack, int *clear)
{
    toi_bracket k;
    int i;
    k.lo = lo;
    k.glo = glo;
    k.hi = slo < 0 ? mk_min(dmax, lo + glo / -slo) : dmax;
    k.ghi = bound_eval(L, k.hi, &k.shi);
    if (k.ghi >= 0) { /* L reaches 0 no earlier than its tangent: it is a straight line up to hi */
        *clear = k.hi >= dmax;
        return k.hi;
    }
    for (i = 0; i < TOI_MAX_ROOT_ITERATIONS && (k.hi - k.lo) * -k.shi > slack && k.hi - k.lo > MK_REAL_EPSILON * k.hi; ++i) {
        if (k.shi < 0) bracket_try(&k, L, k.hi - k.ghi / k.shi);
        if (!bracket_try(&k, L, k.lo + (k.hi - k.lo) * k.glo / (k.glo - k.ghi))) break;
    }
    return k.lo;
}

/* Largest step from t0 proven free of contact (see the section comment).
 * Returns dmax and sets *clear when no contact is possible before dmax. */
static mk_real advance(toi_body *a, toi_body *b, const toi_query *q, mk_real target, mk_real tol, mk_real dmax, int *clear)
{
    mk_vec3 n = q->normal, D = mk_v3_sub(b->c, a->c), V = mk_v3_sub(b->dc, a->dc);
    toi_bound L[3];
    mk_real g0, rate, step, best_reach = -1, best_g = 0, best_s = 0;
    int count = 1, i, best = -1;
    *clear = 0;
    g0 = q->separation - target; /* = L(0) */
    if (!(g0 > 0)) return 0;        /* n does not separate the shapes beyond target: no proof from it */
    rate = -mk_v3_dot(n, V) + mk_v3_len(mk_v3_cross(n, a->w)) * a->rho + mk_v3_len(mk_v3_cross(n, b->w)) * b->rho;
    step = rate > 0 ? g0 / rate : dmax;
    if (step >= dmax) {
        *clear = 1;
        return dmax;
    }
    /* Without turns L is the straight line g0 + c1 d: Mirtich's step is its root. */
    if (!a->turning && !b->turning) return step;
    L[0] = bound_fixed(a, b, n, D, V, target);
    /* A plane's support is finite only along its normal, which the fixed axis already follows. */
    if (a->turning && b->s->type != MK_SHAPE_PLANE) L[count++] = bound_turning(a, b, n, D, V, target);
    if (b->turning && a->s->type != MK_SHAPE_PLANE) L[count++] = bound_turning(b, a, mk_v3_neg(n), mk_v3_neg(D), mk_v3_neg(V), target);
    /* Refine only the bound whose tangent at Mirtich's step reaches farthest. */
    for (i = 0; i < count; ++i) {
        mk_real s, g = bound_eval(&L[i], step, &s), reach = s < 0 ? g / -s : dmax;
        if (g >= 0 && reach > best_reach) {
            best = i;
            best_reach = reach;
            best_g = g;
            best_s = s;
        }
    }
    if (best < 0) return step;
    /* A root within a fraction of the remaining gap (or of the tolerance) is as
     * good as exact: the bound itself is no closer to the truth. */
    return bound_root(&L[best], step, best_g, best_s, dmax, mk_max(MK_REAL(0.25) * tol, MK_REAL(0.015625) * g0), clear);
}

/* mk_toi on [0, t_max], inputs already checked. */
static mk_status toi_run(const mk_shape *sa, const mk_sweep *wa, const mk_shape *sb, const mk_sweep *wb, mk_real target, mk_real tolerance,
                         mk_real t_max, mk_toi_result *out)
{
    toi_body a, b;
    toi_query q;
    mk_gjk_cache cache;
    mk_vec3 origin = wa->c0;
    mk_real t = 0, t_eval = 0, tol;
    mk_status st;
    int iter;
    memset(&cache, 0, sizeof cache);
    body_init(&a, sa, wa, origin);
    body_init(&b, sb, wb, origin);
    /* Below this the distances themselves are rounding noise. */
    tol = mk_max(tolerance, TOI_TOL_FLOOR * (a.rho + b.rho + mk_v3_len(b.c) + mk_v3_len(mk_v3_sub(b.dc, a.dc))));
    out->iterations = 0;
    for (iter = 0; iter < TOI_MAX_ITERATIONS; ++iter) {
        mk_real step;
        int clear;
        if ((st = estimate_at(&a, &b, t, origin, &cache, &q)) != MK_OK) return st;
        ++out->iterations;
        if (q.distance <= target + tol) {
            /* Cores that GJK finds touching only bound the distance by -(rA + rB): the
             * narrowphase's signed answer tells a touch from a penetration at the start. */
            if ((st = answer_at(&a, &b, t, origin, &q, 1, &cache, out)) != MK_OK) return st;
            out->state = iter == 0 && out->distance < -tol ? MK_TOI_OVERLAPPED : MK_TOI_HIT;
            return MK_OK;
        }
        step = advance(&a, &b, &q, target, tol, t_max - t, &clear);
        if (!(step > 0) && !clear && !plane_pair(&a, &b) && !sphere_pair(&a, &b)) {
            /* GJK stopped early with a poor normal: retry once with the narrowphase's polished one. */
            mk_toi_result r;
            if ((st = answer_at(&a, &b, t, origin, &q, 1, &cache, &r)) != MK_OK) return st;
            q.normal = r.normal;
            step = advance(&a, &b, &q, target, tol, t_max - t, &clear);
            if (!(step > 0) && !clear) break;
        }
        if (clear) {
            /* Frames back at the last time evaluated, for the reported witnesses. */
            body_at(&a, t, origin);
            body_at(&b, t, origin);
            out->state = MK_TOI_SEPARATED;
            answer_at(&a, &b, t, origin, &q, 0, &cache, out);
            out->t = t_max;
            return MK_OK;
        }
        t_eval = t;
        t = mk_min(t + step, t_max);
    }
    /* Report the last time evaluated: proven free of contact, and the frames are there. */
    body_at(&a, t_eval, origin);
    body_at(&b, t_eval, origin);
    out->state = MK_TOI_FAILED;
    return answer_at(&a, &b, t_eval, origin, &q, 0, &cache, out);
}

static mk_status toi_check(const mk_shape *a, const mk_sweep *sa, const mk_shape *b, const mk_sweep *sb, mk_real target,
                           mk_real tolerance)
{
    mk_status st;
    if ((st = mk_shape_validate(a)) != MK_OK || (st = mk_shape_validate(b)) != MK_OK) return st;
    if ((st = mk_sweep_validate(sa)) != MK_OK || (st = mk_sweep_validate(sb)) != MK_OK) return st;
    if (!mk_real_is_valid(target) || !mk_real_is_valid(tolerance)) return MK_ERR_NOT_FINITE;
    if (target < 0 || tolerance < 0) return MK_ERR_BAD_ARGUMENT;
    if (a->type == MK_SHAPE_PLANE && b->type == MK_SHAPE_PLANE) return MK_ERR_UNSUPPORTED;
    if ((a->type == MK_SHAPE_PLANE && mk_v3_len(sa->rotation) > TOI_PLANE_STILL) ||
        (b->type == MK_SHAPE_PLANE && mk_v3_len(sb->rotation) > TOI_PLANE_STILL))
        return MK_ERR_UNSUPPORTED;
    return MK_OK;
}

mk_status mk_toi(const mk_shape *a, const mk_sweep *sa, const mk_shape *b, const mk_sweep *sb, mk_real target, mk_real tolerance,
                 mk_toi_result *out)
{
    mk_status st;
    mk_toi_result r;
    if (!out) return MK_ERR_NULL;
    if ((st = toi_check(a, sa, b, sb, target, tolerance)) != MK_OK) return st;
    if ((st = toi_run(a, sa, b, sb, target, tolerance, 1, &r)) != MK_OK) return st;
    *out = r;
    return MK_OK;
}

mk_status mk_shape_cast(const mk_shape *a, mk_transform xa, mk_vec3 translation, const mk_shape *b, mk_transform xb, mk_ray_hit *out)
{
    mk_sweep sa, sb;
    mk_toi_result r;
    mk_status st;
    if (!out) return MK_ERR_NULL;
    if (!mk_v3_is_valid(translation)) return MK_ERR_NOT_FINITE;
    if ((st = mk_sweep_from_velocity(xa, translation, mk_v3_zero(), 1, mk_v3_zero(), &sa)) != MK_OK) return st;
    if ((st = mk_sweep_from_velocity(xb, mk_v3_zero(), mk_v3_zero(), 1, mk_v3_zero(), &sb)) != MK_OK) return st;
    if ((st = toi_check(a, &sa, b, &sb, 0, 0)) != MK_OK) return st;
    if ((st = toi_run(a, &sa, b, &sb, 0, 0, 1, &r)) != MK_OK) return st;
    /* An iteration cap (FAILED) reports the last fraction proven free of contact
     * as a hit: a caller moving the shape must not go further. */
    out->hit = r.state != MK_TOI_SEPARATED;
    out->fraction = out->hit ? r.t : 1;
    out->point = out->hit ? r.point_b : mk_v3_add(xa.p, translation);
    out->normal = out->hit ? mk_v3_neg(r.normal) : mk_v3_zero();
    return MK_OK;
}

/* ---- host helpers ----------------------------------------------------------- */

static void sweep_advance_unchecked(mk_sweep *sw, mk_real t)
{
    sw->q0 = sweep_rotation(sw, t);
    sw->c0 = mk_v3_lerp(sw->c0, sw->c1, t);
    sw->rotation = mk_v3_scale(sw->rotation, 1 - t);
}

mk_status mk_sweep_advance(mk_sweep *sw, mk_real t)
{
    mk_status st;
    if ((st = mk_sweep_validate(sw)) != MK_OK) return st;
    if (!mk_real_is_valid(t)) return MK_ERR_NOT_FINITE;
    if (t < 0 || t > 1) return MK_ERR_BAD_ARGUMENT;
    sweep_advance_unchecked(sw, t);
    return MK_OK;
}

static mk_status check_bodies(const mk_toi_body *bodies, int body_count, const mk_toi_pair *pairs, int pair_count, mk_real target,
                              mk_real tolerance)
{
    mk_status st;
    int i;
    if (body_count < 0 || pair_count < 0) return MK_ERR_BAD_SIZE;
    if ((body_count > 0 && !bodies) || (pair_count > 0 && !pairs)) return MK_ERR_NULL;
    for (i = 0; i < pair_count; ++i)
        if (pairs[i].a < 0 || pairs[i].a >= body_count || pairs[i].b < 0 || pairs[i].b >= body_count || pairs[i].a == pairs[i].b)
            return MK_ERR_BAD_ARGUMENT;
    for (i = 0; i < pair_count; ++i) {
        const mk_toi_body *a = &bodies[pairs[i].a], *b = &bodies[pairs[i].b];
        if ((st = toi_check(a->shape, &a->sweep, b->shape, &b->sweep, target, tolerance)) != MK_OK) return st;
    }
    return MK_OK;
}

static mk_status earliest(const mk_toi_body *bodies, const mk_toi_pair *pairs, int pair_count, mk_real target, mk_real tolerance,
                          mk_toi_event *out)
{
    mk_real best = 1;
    int i;
    out->pair = -1;
    out->overlapped = 0;
    out->receding = 0;
    for (i = 0; i < pair_count; ++i) {
        const mk_toi_body *a = &bodies[pairs[i].a], *b = &bodies[pairs[i].b];
        mk_toi_result r;
        mk_status st = toi_run(a->shape, &a->sweep, b->shape, &b->sweep, target, tolerance, best, &r);
        if (st != MK_OK) return st;
        if (r.state == MK_TOI_OVERLAPPED) {
            ++out->overlapped;
        } else if (r.state == MK_TOI_HIT && r.t == 0 && r.rate >= 0) {
            ++out->receding;
        } else if ((r.state == MK_TOI_HIT || r.state == MK_TOI_FAILED) && (out->pair < 0 || r.t < best)) {
            best = r.t;
            out->pair = i;
            out->result = r;
        }
    }
    return MK_OK;
}

mk_status mk_toi_earliest(const mk_toi_body *bodies, int body_count, const mk_toi_pair *pairs, int pair_count, mk_real target,
                          mk_real tolerance, mk_toi_event *out)
{
    mk_status st;
    mk_toi_event ev;
    if (!out) return MK_ERR_NULL;
    if ((st = check_bodies(bodies, body_count, pairs, pair_count, target, tolerance)) != MK_OK) return st;
    if ((st = earliest(bodies, pairs, pair_count, target, tolerance, &ev)) != MK_OK) return st;
    *out = ev;
    return MK_OK;
}

mk_status mk_toi_substep(mk_toi_body *bodies, int body_count, const mk_toi_pair *pairs, int pair_count, mk_real target,
                         mk_real tolerance, int max_substeps, mk_toi_resolve_fn resolve, void *user, mk_toi_step_stats *stats)
{
    mk_toi_step_stats s;
    mk_status st = MK_OK;
    int i;
    if (!stats || !resolve) return MK_ERR_NULL;
    if (max_substeps < 0) return MK_ERR_BAD_SIZE;
    s.substeps = s.hits = s.failed = 0;
    s.time = 0;
    while (s.substeps < max_substeps) {
        mk_toi_event ev;
        mk_real t;
        /* The host may have rewritten sweeps: check them every round. */
        if ((st = check_bodies(bodies, body_count, pairs, pair_count, target, tolerance)) != MK_OK) break;
        if ((st = earliest(bodies, pairs, pair_count, target, tolerance, &ev)) != MK_OK) break;
        ++s.substeps;
        if (ev.pair < 0) {
            s.time = 1;
            break;
        }
        t = ev.result.t;
        for (i = 0; i < body_count; ++i) sweep_advance_unchecked(&bodies[i].sweep, t);
        s.time += t * (1 - s.time);
        if (ev.result.state == MK_TOI_FAILED) {
            ++s.failed;
            continue;
        }
        ++s.hits;
        if (resolve(user, bodies, body_count, ev.pair, &ev.result, s.time)) break;
    }
    *stats = s;
    return st;
}

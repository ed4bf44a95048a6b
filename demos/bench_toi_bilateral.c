/* bench_toi_bilateral.c: bilateral advancement (Catto, "Continuous Collision",
 * GDC 2013; Box2D's b2TimeOfImpact), generalised to convex shapes in 3D by
 * support functions, as a yardstick for mk_toi's conservative advancement.
 *
 * Each outer iteration runs one distance query at t1, which gives a separating
 * axis n (fixed in the world: Box2D's "points" separation function; the face
 * axes that turn with a body have no general 3D counterpart for curved
 * cores). The inner loop takes the deepest points of both shapes along n at
 * t2 (first the end of the step), and when they are closer than the target
 * band, brackets the time at which those two material points reach it,
 * alternating bisection and secant steps (50 at most), and pushes t2 back to
 * it; a new deepest pair at t2 repeats the root search (8 at most). When the
 * deepest pair at t2 sits in the band, t1 = t2 and the outer loop goes on.
 * Only the separation at t1 and at t2 is checked, so a contact that begins and
 * ends between them, or a deepest pair that changes in between (turning
 * shapes), is missed: no proof, unlike mk_toi. The accepted band is mk_toi's,
 * [target, target + tolerance], with mk_toi's tolerance floor and cap. */
#include <math.h>
#include <string.h>

#include "bench_toi_bilateral.h"
#include "gjk.h"
#include "minko/distance.h"

#define BL_MAX_ITERATIONS 128 /* mk_toi's cap on distance queries */
#define BL_MAX_PUSH_BACK 8    /* Box2D: b2_maxPolygonVertices */
#define BL_MAX_ROOT 50        /* Box2D's root finder cap */
/* mk_toi's tolerance floor (toi.c: the accuracy of the distance queries). */
#if defined(MK_SINGLE)
#  define BL_TOL_FLOOR (MK_REAL(1e2) * MK_REAL_EPSILON)
#else
#  define BL_TOL_FLOOR (MK_REAL(1e4) * MK_REAL_EPSILON)
#endif

typedef struct bl_body {
    const mk_shape *s;
    const mk_sweep *sw;
    mk_vec3 c0, dc; /* rotation centre at t = 0 (relative to the origin) and its travel */
    mk_real angle;
    int hint;
    int turning; /* 0: R is the same at every time (as in mk_toi, no trigonometry then) */
    mk_mat3 R; /* at the time last posed */
    mk_vec3 p; /* shape origin at that time, relative to the origin */
} bl_body;

static void bl_init(bl_body *b, const mk_shape *s, const mk_sweep *sw, mk_vec3 origin)
{
    b->s = s;
    b->sw = sw;
    b->c0 = mk_v3_sub(sw->c0, origin);
    b->dc = mk_v3_sub(sw->c1, sw->c0);
    b->angle = mk_v3_len(sw->rotation);
    b->hint = -1;
    b->turning = b->angle > 0 && s->type != MK_SHAPE_PLANE;
    b->R = mk_mat3_from_quat(sw->q0);
}

static void bl_pose(bl_body *b, mk_real t)
{
    if (b->turning) b->R = mk_mat3_from_quat(mk_quat_mul(mk_quat_from_axis_angle(b->sw->rotation, t * b->angle), b->sw->q0));
    b->p = mk_v3_sub(mk_v3_mad(b->c0, t, b->dc), mk_mat3_mul_v3(b->R, b->sw->local_center));
}

/* Bounding radius about the rotation centre, from the local box (only sets
 * the tolerance floor's scale; planes have none). */
static mk_real bl_radius(const bl_body *b)
{
    mk_aabb box;
    if (b->s->type == MK_SHAPE_PLANE) return 0;
    mk_shape_aabb(b->s, mk_transform_make(mk_v3_zero(), mk_quat_identity()), &box);
    return mk_v3_len(mk_v3_max(mk_v3_abs(mk_v3_sub(box.lo, b->sw->local_center)), mk_v3_abs(mk_v3_sub(box.hi, b->sw->local_center))));
}

/* Deepest material point (shape frame, rounding included) along world unit dir
 * at the posed time. A plane never turns and is only asked along its normal:
 * any point of it will do. */
static mk_vec3 bl_deepest(bl_body *b, mk_vec3 dir)
{
    mk_vec3 d = mk_mat3_tmul_v3(b->R, dir);
    if (b->s->type == MK_SHAPE_PLANE) return mk_v3_scale(b->s->u.plane.normal, b->s->u.plane.offset);
    return mk_v3_mad(mk_core_support_inl(b->s, d, &b->hint), b->s->radius, d);
}

static mk_real bl_eval(bl_body *a, mk_vec3 la, bl_body *b, mk_vec3 lb, mk_vec3 n, mk_real t)
{
    bl_pose(a, t);
    bl_pose(b, t);
    return mk_v3_dot(n, mk_v3_sub(mk_v3_add(b->p, mk_mat3_mul_v3(b->R, lb)), mk_v3_add(a->p, mk_mat3_mul_v3(a->R, la))));
}

/* Distance (upper bound) and separating axis at t, as mk_toi's loop gets them. */
static mk_real bl_query(bl_body *a, bl_body *b, mk_real t, mk_gjk_cache *cache, mk_vec3 *n)
{
    bl_pose(a, t);
    bl_pose(b, t);
    if (a->s->type == MK_SHAPE_PLANE || b->s->type == MK_SHAPE_PLANE) {
        *n = a->s->type == MK_SHAPE_PLANE ? mk_mat3_mul_v3(a->R, a->s->u.plane.normal) : mk_v3_neg(mk_mat3_mul_v3(b->R, b->s->u.plane.normal));
    } else if (a->s->type == MK_SHAPE_SPHERE && b->s->type == MK_SHAPE_SPHERE) {
        mk_vec3 d = mk_v3_sub(b->p, a->p);
        mk_real l = mk_v3_len(d);
        *n = l > 0 ? mk_v3_scale(d, 1 / l) : mk_v3(0, 0, 1);
        return l - a->s->radius - b->s->radius;
    } else {
        mk_pair p;
        mk_gjk_result g;
        p.a = a->s;
        p.b = b->s;
        p.r = mk_mat3_tmul(a->R, b->R);
        p.t = mk_mat3_tmul_v3(a->R, mk_v3_sub(b->p, a->p));
        mk_gjk(&p, cache, 0, 0, &g);
        mk_gjk_cache_store(&g.s, g.normal, cache);
        *n = mk_mat3_mul_v3(a->R, g.lower > -(mk_real)HUGE_VAL ? g.normal : mk_v3_normalize(mk_v3_neg(g.v)));
        return g.upper - a->s->radius - b->s->radius;
    }
    return mk_v3_dot(*n, mk_v3_sub(mk_v3_add(b->p, mk_mat3_mul_v3(b->R, bl_deepest(b, mk_v3_neg(*n)))),
                                   mk_v3_add(a->p, mk_mat3_mul_v3(a->R, bl_deepest(a, *n)))));
}

/* Time in (lo, hi) at which the pair's separation s (s(lo) = slo > mid,
 * s(hi) = shi < mid) is within half of mid: Box2D's alternation. Returns -1
 * when the cap is reached first. */
static mk_real bl_root(bl_body *a, mk_vec3 la, bl_body *b, mk_vec3 lb, mk_vec3 n, mk_real lo, mk_real slo, mk_real hi, mk_real shi,
                       mk_real mid, mk_real half)
{
    int i;
    for (i = 0; i < BL_MAX_ROOT; ++i) {
        mk_real t = (i & 1) ? lo + (mid - slo) * (hi - lo) / (shi - slo) : MK_REAL(0.5) * (lo + hi);
        mk_real s = bl_eval(a, la, b, lb, n, t);
        if (mk_fabs_(s - mid) < half) return t;
        if (s > mid) {
            lo = t;
            slo = s;
        } else {
            hi = t;
            shi = s;
        }
    }
    return -1;
}

static void bl_answer(const mk_shape *sa, bl_body *a, const mk_shape *sb, bl_body *b, mk_vec3 origin, mk_real t, mk_toi_state state,
                      mk_gjk_cache *cache, mk_toi_result *out)
{
    out->state = state;
    out->t = t;
    if (state == MK_TOI_HIT || state == MK_TOI_OVERLAPPED) { /* mk_toi's polished answer at a hit */
        mk_distance_result r;
        bl_pose(a, t);
        bl_pose(b, t);
        if (mk_distance(sa, mk_transform_make(mk_v3_add(a->p, origin), mk_quat_mul(mk_quat_from_axis_angle(a->sw->rotation, t * a->angle), a->sw->q0)),
                        sb, mk_transform_make(mk_v3_add(b->p, origin), mk_quat_mul(mk_quat_from_axis_angle(b->sw->rotation, t * b->angle), b->sw->q0)),
                        cache, &r) == MK_OK) {
            out->distance = r.distance;
            out->normal = r.normal;
            out->point_a = r.point_a;
            out->point_b = r.point_b;
        }
    }
}

mk_status bench_toi_bilateral(const mk_shape *sa, const mk_sweep *wa, const mk_shape *sb, const mk_sweep *wb, mk_real target,
                              mk_real tolerance, mk_toi_result *out)
{
    bl_body a, b;
    mk_gjk_cache cache;
    mk_vec3 origin = wa->c0;
    mk_real t1 = 0, tol, mid, half;
    int iter;
    memset(&cache, 0, sizeof cache);
    memset(out, 0, sizeof *out);
    bl_init(&a, sa, wa, origin);
    bl_init(&b, sb, wb, origin);
    tol = mk_max(tolerance, BL_TOL_FLOOR * (bl_radius(&a) + bl_radius(&b) + mk_v3_len(b.c0) + mk_v3_len(mk_v3_sub(b.dc, a.dc))));
    mid = target + MK_REAL(0.5) * tol; /* mk_toi's band [target, target + tol] */
    half = MK_REAL(0.5) * tol;
    for (iter = 0; iter < BL_MAX_ITERATIONS; ++iter) {
        mk_vec3 n;
        mk_real d = bl_query(&a, &b, t1, &cache, &n), t2 = 1;
        int push;
        out->iterations = iter + 1;
        if (d <= target + tol) {
            bl_answer(sa, &a, sb, &b, origin, t1, MK_TOI_HIT, &cache, out);
            if (iter == 0 && out->distance < -tol) out->state = MK_TOI_OVERLAPPED;
            return MK_OK;
        }
        for (push = 0; push < BL_MAX_PUSH_BACK; ++push) {
            mk_vec3 la, lb;
            mk_real s1, s2;
            bl_pose(&a, t2);
            bl_pose(&b, t2);
            la = bl_deepest(&a, n);
            lb = bl_deepest(&b, mk_v3_neg(n));
            s2 = bl_eval(&a, la, &b, lb, n, t2);
            if (s2 > mid + half) {
                bl_answer(sa, &a, sb, &b, origin, 1, MK_TOI_SEPARATED, &cache, out);
                return MK_OK;
            }
            if (s2 > mid - half) {
                t1 = t2;
                break;
            }
            s1 = bl_eval(&a, la, &b, lb, n, t1);
            if (s1 < mid - half) {
                bl_answer(sa, &a, sb, &b, origin, t1, MK_TOI_FAILED, &cache, out);
                return MK_OK;
            }
            if (s1 <= mid + half) {
                bl_answer(sa, &a, sb, &b, origin, t1, MK_TOI_HIT, &cache, out);
                return MK_OK;
            }
            s1 = bl_root(&a, la, &b, lb, n, t1, s1, t2, s2, mid, half);
            if (s1 >= 0) t2 = s1;
        }
    }
    bl_answer(sa, &a, sb, &b, origin, t1, MK_TOI_FAILED, &cache, out);
    return MK_OK;
}

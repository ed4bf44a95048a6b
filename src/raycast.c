/* raycast.c: ray casts against every shape type (minko/raycast.h).
 *
 * Everything runs in the shape's frame. Spheres and planes have closed forms;
 * unrounded hulls are clipped against their face planes. Every other case is
 * one Newton iteration on f(t) = dist(o + t d, core) - r (closed forms for the
 * distance, GJK for a rounded hull's core): f is convex in t
 * (distance to a convex set is convex along a line), so from a point before
 * the first root each Newton step lands at or before that root, and a
 * non-negative slope proves there is no root ahead. The iteration starts where
 * the ray enters the shape's local AABB, which contains the solid. */
#include "minko/raycast.h"
#ifndef MK_WITHOUT_GJK
#  include "gjk.h"
#else
#  include "minko/distance.h" /* mk_gjk_cache */
#endif
#include "pose.h"

/* Grazing rays converge linearly (the error halves per step), so 64 steps
 * reach the rounding floor from any start; typical hits need 1 to 6. */
#define RAY_MAX_ITERATIONS 64

typedef struct local_hit {
    mk_real t;
    mk_vec3 n; /* local outward normal */
} local_hit;

static mk_vec3 closest_on_segment(mk_vec3 a, mk_vec3 b, mk_vec3 p)
{
    mk_vec3 e = mk_v3_sub(b, a);
    mk_real l2 = mk_v3_len2(e);
    mk_real u = l2 > 0 ? mk_clamp(mk_v3_dot(mk_v3_sub(p, a), e) / l2, 0, 1) : 0;
    return mk_v3_mad(a, u, e);
}

#ifndef MK_WITHOUT_GJK
/* Closest point of a hull core to p: GJK of the hull against the point
 * (the CSO is hull - p, whose point nearest the origin is c - p). The cache
 * carries the simplex from one Newton step to the next along the ray. */
static mk_vec3 closest_on_hull(const mk_shape *s, mk_vec3 p, mk_gjk_cache *cache)
{
    mk_shape point;
    mk_pair pair;
    mk_gjk_result g;
    point.type = MK_SHAPE_SPHERE; /* a point core: GJK never sees radii */
    point.radius = 1;
    pair.a = s;
    pair.b = &point;
    pair.r = mk_mat3_identity();
    pair.t = p;
    mk_gjk(&pair, cache, 0, 0, &g);
    mk_gjk_cache_store(&g.s, g.normal, cache);
    return g.overlap ? p : mk_v3_add(p, g.v);
}
#endif

/* Solid cone with apex (0, 0, h) and base disc of radius R at z = -h. In the
 * (rho, z) half-plane the cross-section is the triangle apex / base rim / base
 * centre; an outside point's nearest point is on the base or the slant edge. */
static mk_vec3 closest_on_cone(mk_real R, mk_real h, mk_vec3 p)
{
    mk_real rho = mk_sqrt_(p.x * p.x + p.y * p.y), cr, cz;
    if (p.z >= -h && 2 * h * rho + R * (p.z + h) <= 2 * h * R) return p;
    {
        mk_vec3 q = mk_v3(rho, p.z, 0);
        mk_vec3 base = mk_v3(mk_clamp(rho, 0, R), -h, 0);
        mk_vec3 slant = closest_on_segment(mk_v3(R, -h, 0), mk_v3(0, h, 0), q);
        mk_vec3 c = mk_v3_len2(mk_v3_sub(q, base)) <= mk_v3_len2(mk_v3_sub(q, slant)) ? base : slant;
        cr = c.x;
        cz = c.y;
    }
    return rho > 0 ? mk_v3(p.x * cr / rho, p.y * cr / rho, cz) : mk_v3(0, 0, cz);
}

/* Closest point of the core to p, local frame; p itself when p is inside. */
static mk_vec3 closest_on_core(const mk_shape *s, mk_vec3 p, mk_gjk_cache *cache)
{
#ifdef MK_WITHOUT_GJK
    (void)cache; /* rounded hulls are refused before getting here */
#endif
    switch (s->type) {
    case MK_SHAPE_BOX: {
        mk_vec3 e = s->u.half_extents;
        return mk_v3(mk_clamp(p.x, -e.x, e.x), mk_clamp(p.y, -e.y, e.y), mk_clamp(p.z, -e.z, e.z));
    }
    case MK_SHAPE_CAPSULE: return mk_v3(0, 0, mk_clamp(p.z, -s->u.capsule.half_height, s->u.capsule.half_height));
    case MK_SHAPE_CYLINDER: {
        /* A disc times an interval: clamp the radial and the axial part separately. */
        mk_real rho = mk_sqrt_(p.x * p.x + p.y * p.y), R = s->u.cylinder.radius, h = s->u.cylinder.half_height;
        mk_real k = rho > R ? R / rho : 1;
        return mk_v3(p.x * k, p.y * k, mk_clamp(p.z, -h, h));
    }
    case MK_SHAPE_CONE: return closest_on_cone(s->u.cone.radius, s->u.cone.half_height, p);
#ifndef MK_WITHOUT_GJK
    case MK_SHAPE_HULL: return closest_on_hull(s, p, cache);
#endif
    default: return mk_v3_zero(); /* sphere: the point core */
    }
}

/* Outward normal of the core face nearest p, for p on or very near the
 * core's surface, where p - closest(p) is too short to carry a direction:
 * the face (box side, cylinder side or cap, cone slant or base, hull face)
 * with the largest signed distance. At an edge or vertex that is one of the
 * adjacent faces' normals, a valid normal of the solid there. */
static mk_vec3 core_face_normal(const mk_shape *s, mk_vec3 p)
{
    switch (s->type) {
    case MK_SHAPE_BOX: {
        mk_vec3 e = mk_v3_sub(mk_v3_abs(p), s->u.half_extents);
        if (e.x >= e.y && e.x >= e.z) return mk_v3(p.x >= 0 ? 1 : -1, 0, 0);
        if (e.y >= e.z) return mk_v3(0, p.y >= 0 ? 1 : -1, 0);
        return mk_v3(0, 0, p.z >= 0 ? 1 : -1);
    }
    case MK_SHAPE_CYLINDER: {
        mk_real rho = mk_sqrt_(p.x * p.x + p.y * p.y);
        if (rho > 0 && rho - s->u.cylinder.radius >= mk_fabs_(p.z) - s->u.cylinder.half_height) return mk_v3(p.x / rho, p.y / rho, 0);
        return mk_v3(0, 0, p.z >= 0 ? 1 : -1);
    }
    case MK_SHAPE_CONE: {
        /* Slant plane through (R, -h) and (0, h) in the (rho, z) half-plane: normal (2h, R) / |.|. */
        mk_real R = s->u.cone.radius, h = s->u.cone.half_height, rho = mk_sqrt_(p.x * p.x + p.y * p.y);
        mk_real l = mk_sqrt_(4 * h * h + R * R), slant = (2 * h * (rho - R) + R * (p.z + h)) / l;
        if (slant >= -h - p.z) return rho > 0 ? mk_v3(2 * h * p.x / (rho * l), 2 * h * p.y / (rho * l), R / l) : mk_v3(0, 0, 1);
        return mk_v3(0, 0, -1);
    }
    case MK_SHAPE_HULL: {
        const mk_hull *hl = s->u.hull;
        int f, best = 0;
        for (f = 1; f < hl->face_count; ++f)
            if (mk_v3_dot(hl->planes[f].normal, p) - hl->planes[f].offset > mk_v3_dot(hl->planes[best].normal, p) - hl->planes[best].offset)
                best = f;
        return hl->planes[best].normal;
    }
    default: return mk_v3(0, 0, 1); /* point and segment cores always carry a radius > 0 */
    }
}

/* Entry and exit fractions of the ray in box b, clipped to [0, 1]. */
static int clip_aabb(mk_aabb b, mk_vec3 o, mk_vec3 d, mk_real *t0, mk_real *t1)
{
    const mk_real *lo = &b.lo.x, *hi = &b.hi.x, *po = &o.x, *pd = &d.x;
    mk_real enter = 0, leave = 1;
    int i;
    for (i = 0; i < 3; ++i) {
        if (pd[i] == 0) {
            if (po[i] < lo[i] || po[i] > hi[i]) return 0;
        } else {
            mk_real inv = 1 / pd[i];
            mk_real ta = (lo[i] - po[i]) * inv, tb = (hi[i] - po[i]) * inv;
            enter = mk_max(enter, mk_min(ta, tb));
            leave = mk_min(leave, mk_max(ta, tb));
            if (enter > leave) return 0;
        }
    }
    *t0 = enter;
    *t1 = leave;
    return 1;
}

/* Sphere of radius r at the origin. Distances along the unit direction, with
 * the discriminant from the ray's perpendicular offset and the near root as
 * c / (-b + sqrt(disc)): both avoid cancellation for far or grazing rays. */
static int ray_sphere(mk_real r, mk_vec3 o, mk_vec3 d, local_hit *h)
{
    mk_real len = mk_v3_len(d), b, c, disc, s;
    mk_vec3 u, perp;
    c = mk_v3_len2(o) - r * r;
    if (c <= 0) {
        h->t = 0;
        h->n = mk_v3_normalize(mk_v3_neg(d));
        return 1;
    }
    if (len == 0) return 0;
    u = mk_v3_scale(d, 1 / len);
    b = mk_v3_dot(o, u);
    if (b >= 0) return 0;
    perp = mk_v3_mad(o, -b, u);
    disc = r * r - mk_v3_len2(perp);
    if (disc < 0) return 0;
    s = c / (-b + mk_sqrt_(disc));
    if (s > len) return 0;
    h->t = s / len;
    h->n = mk_v3_normalize(mk_v3_mad(o, s, u));
    return 1;
}

/* Half-space n.x <= offset. */
static int ray_plane(const mk_plane *pl, mk_vec3 o, mk_vec3 d, local_hit *h)
{
    mk_real s0 = mk_v3_dot(pl->normal, o) - pl->offset, ds = mk_v3_dot(pl->normal, d);
    if (s0 <= 0) {
        h->t = 0;
        h->n = mk_v3_normalize(mk_v3_neg(d));
        return 1;
    }
    if (ds >= 0 || s0 > -ds) return 0;
    h->t = s0 / -ds;
    h->n = pl->normal;
    return 1;
}

/* Unrounded hull: the segment's part inside every face half-space. */
static int ray_hull_planes(const mk_hull *hl, mk_vec3 o, mk_vec3 d, local_hit *h)
{
    mk_real enter = 0, leave = 1;
    int f, entry_face = -1;
    for (f = 0; f < hl->face_count; ++f) {
        mk_real s0 = mk_v3_dot(hl->planes[f].normal, o) - hl->planes[f].offset;
        mk_real ds = mk_v3_dot(hl->planes[f].normal, d);
        if (ds == 0) {
            if (s0 > 0) return 0;
        } else if (ds < 0) {
            mk_real t = s0 / -ds;
            if (t > enter) {
                enter = t;
                entry_face = f;
            }
        } else {
            mk_real t = -s0 / ds;
            if (t < leave) leave = t;
        }
        if (enter > leave) return 0;
    }
    h->t = enter;
    if (entry_face >= 0) h->n = hl->planes[entry_face].normal;
    else h->n = mk_v3_normalize(mk_v3_neg(d));
    return 1;
}

/* Newton on f(t) = |p(t) - core(p(t))| - r from the AABB entry (see the file comment). */
static int ray_newton(const mk_shape *s, mk_vec3 o, mk_vec3 d, local_hit *h)
{
    mk_aabb box;
    mk_gjk_cache cache;
    mk_real t, t_end, r = s->radius, size, tol;
    int i;
    cache.count = 0;
    cache.dir = mk_v3_zero();
    mk_shape_aabb(s, mk_transform_identity(), &box);
    if (!clip_aabb(box, o, d, &t, &t_end)) return 0;
    size = mk_max(mk_v3_max_abs(box.hi), mk_v3_max_abs(box.lo));
    /* What rounding in p(t) and in the closest point can hide: a few ulps of the coordinates involved. */
    tol = 16 * MK_REAL_EPSILON * (mk_v3_max_abs(o) + mk_v3_max_abs(d) + size);
    for (i = 0; i < RAY_MAX_ITERATIONS; ++i) {
        mk_vec3 p = mk_v3_mad(o, t, d);
        mk_vec3 v = mk_v3_sub(p, closest_on_core(s, p, &cache));
        mk_real dist = mk_v3_len(v), f = dist - r, slope, step;
        if (f <= tol) {
            h->t = t;
            if (t == 0) h->n = mk_v3_normalize(mk_v3_neg(d));
            /* p - core(p) has a direction worth trusting only when it is long (a rounded shape). */
            else h->n = dist > MK_REAL(1e-4) * size ? mk_v3_scale(v, 1 / dist) : core_face_normal(s, p);
            return 1;
        }
        slope = mk_v3_dot(v, d) / dist;
        if (!(slope < 0)) return 0; /* f convex and not decreasing: no root ahead */
        step = f / -slope;
        if (step <= MK_REAL_EPSILON * t) break; /* stalled on a grazing touch at the rounding floor */
        t += step;
        if (t > t_end) return 0;
    }
    return 0;
}

mk_status mk_raycast(const mk_shape *s, mk_transform xf, mk_vec3 origin, mk_vec3 translation, mk_ray_hit *out)
{
    mk_status st;
    mk_vec3 o, d;
    local_hit h;
    int hit;
    if (!out) return MK_ERR_NULL;
    if ((st = mk_shape_validate(s)) != MK_OK) return st;
    if ((st = mk_transform_check_(xf)) != MK_OK) return st;
    if (!mk_v3_is_valid(origin) || !mk_v3_is_valid(translation)) return MK_ERR_NOT_FINITE;
    /* Both ends of the ray within MK_MAX_COORD, as every position a query takes. */
    if (!mk_position_is_valid(origin) || !mk_position_is_valid(mk_v3_add(origin, translation))) return MK_ERR_OUT_OF_RANGE;
#ifdef MK_WITHOUT_GJK
    if (s->type == MK_SHAPE_HULL && s->radius > 0) return MK_ERR_UNSUPPORTED; /* a rounded hull needs GJK */
#endif
    xf.q = mk_quat_normalize(xf.q);
    o = mk_quat_inv_rotate(xf.q, mk_v3_sub(origin, xf.p));
    d = mk_quat_inv_rotate(xf.q, translation);
    switch (s->type) {
    case MK_SHAPE_SPHERE: hit = ray_sphere(s->radius, o, d, &h); break;
    case MK_SHAPE_PLANE: hit = ray_plane(&s->u.plane, o, d, &h); break;
    case MK_SHAPE_HULL:
        hit = s->radius == 0 ? ray_hull_planes(s->u.hull, o, d, &h) : ray_newton(s, o, d, &h);
        break;
    default: hit = ray_newton(s, o, d, &h); break;
    }
    out->hit = hit;
    out->fraction = hit ? h.t : 1;
    out->point = mk_v3_mad(origin, out->fraction, translation);
    out->normal = hit ? mk_quat_rotate(xf.q, h.n) : mk_v3_zero();
    return MK_OK;
}

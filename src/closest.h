/* closest.h: closed-form signed distances for simple pairs (internal).
 *
 * Each function answers for whole shapes (cores grown by their rounding
 * radii) in one frame, given exactly the geometry it needs (a capsule is its
 * axis, a sphere its centre), so callers build no more of a pose than the
 * pair uses and capsule pairs need no rotation back. Exact up to a few
 * roundings of the shapes' size: no iteration, no tolerance. Where the
 * direction is undefined (a sphere centre on the other core), a fixed,
 * documented choice is made so the result is never NaN. O(1) each.
 * They are inline: a call would pass every mk_vec3 argument and the mk_hit
 * result through memory (structs over 16 bytes do not travel in registers on
 * x86-64), which cost as much as the closed forms themselves.
 */
#ifndef MINKO_CLOSEST_H
#define MINKO_CLOSEST_H

#include "gjk.h"

/* A signed distance answer in one shape's frame: b - a = distance * normal. */
typedef struct mk_hit {
    mk_real distance;
    mk_vec3 normal; /* unit, from A towards B */
    mk_vec3 a, b;   /* witness points on A's and B's surfaces */
} mk_hit;

/* Grows a core answer (a, b on the cores, distance dc along n) by the radii. */
MK_ALWAYS_INLINE mk_hit mk_hit_grow(mk_vec3 a, mk_vec3 b, mk_real dc, mk_vec3 n, mk_real ra, mk_real rb)
{
    mk_hit h;
    h.distance = dc - ra - rb;
    h.normal = n;
    h.a = mk_v3_mad(a, ra, n);
    h.b = mk_v3_mad(b, -rb, n);
    return h;
}

/* A box core of half extents h, rounded by ra, against a sphere of radius
 * rb centred at c, in the box's frame. */
MK_ALWAYS_INLINE mk_hit mk_closest_box_sphere(mk_vec3 h, mk_real ra, mk_vec3 c, mk_real rb)
{
    mk_vec3 q = mk_v3(mk_clamp(c.x, -h.x, h.x), mk_clamp(c.y, -h.y, h.y), mk_clamp(c.z, -h.z, h.z));
    mk_vec3 dv = mk_v3_sub(c, q), n;
    mk_real l = mk_v3_len(dv), gx, gy, gz, g;
    if (l > 0) return mk_hit_grow(q, c, l, mk_v3_scale(dv, 1 / l), ra, rb);
    /* Centre inside the core: leave through the nearest face. */
    gx = h.x - mk_fabs_(c.x);
    gy = h.y - mk_fabs_(c.y);
    gz = h.z - mk_fabs_(c.z);
    if (gx <= gy && gx <= gz) {
        g = gx;
        n = mk_v3(c.x >= 0 ? 1 : -1, 0, 0);
        q.x = c.x >= 0 ? h.x : -h.x;
    } else if (gy <= gz) {
        g = gy;
        n = mk_v3(0, c.y >= 0 ? 1 : -1, 0);
        q.y = c.y >= 0 ? h.y : -h.y;
    } else {
        g = gz;
        n = mk_v3(0, 0, c.z >= 0 ? 1 : -1);
        q.z = c.z >= 0 ? h.z : -h.z;
    }
    return mk_hit_grow(q, c, -g, n, ra, rb);
}

/* A capsule (segment of half height hh along the unit axis u through the
 * origin, radius ra) against a sphere of radius rb centred at c. */
MK_ALWAYS_INLINE mk_hit mk_closest_capsule_sphere(mk_real hh, mk_vec3 u, mk_real ra, mk_vec3 c, mk_real rb)
{
    mk_vec3 q = mk_v3_scale(u, mk_clamp(mk_v3_dot(c, u), -hh, hh)), dv = mk_v3_sub(c, q);
    mk_real l = mk_v3_len(dv);
    /* Centre on the segment: any direction across the axis is a shortest way out. */
    mk_vec3 n = l > 0 ? mk_v3_scale(dv, 1 / l) : mk_v3_perp(u);
    return mk_hit_grow(q, c, l, n, ra, rb);
}

/* Closest points of segments [p0, p1] and [q0, q1]: parameters s, t in [0, 1].
 * Parallel segments get the midpoint of the overlap of their projections, so
 * the answer is symmetric and stable under small motions. */
MK_ALWAYS_INLINE void mk_segment_segment(mk_vec3 p0, mk_vec3 p1, mk_vec3 q0, mk_vec3 q1, mk_real *s_out, mk_real *t_out)
{
    mk_vec3 d1 = mk_v3_sub(p1, p0), d2 = mk_v3_sub(q1, q0), r = mk_v3_sub(p0, q0);
    mk_real a = mk_v3_len2(d1), e = mk_v3_len2(d2), b = mk_v3_dot(d1, d2), c = mk_v3_dot(d1, r), f = mk_v3_dot(d2, r);
    mk_real denom = a * e - b * b, s, t;
    /* Parallel when sin^2 of the angle is at rounding level: the 2x2 system is singular. */
    if (denom > MK_REAL(16.0) * MK_REAL_EPSILON * a * e) {
        s = mk_clamp((b * f - c * e) / denom, 0, 1);
    } else {
        /* Projections of q0, q1 on p's parameter line; centre of the overlap. */
        mk_real s0 = -c / a, s1 = (b - c) / a;
        mk_real lo = mk_max(mk_min(s0, s1), 0), hi = mk_min(mk_max(s0, s1), 1);
        s = lo <= hi ? MK_REAL(0.5) * (lo + hi) : (mk_max(s0, s1) < 0 ? 0 : 1);
    }
    t = mk_clamp((b * s + f) / e, 0, 1);
    s = mk_clamp((b * t - c) / a, 0, 1);
    *s_out = s;
    *t_out = t;
}

/* Capsule A (unit axis u through the origin, half height ha, radius ra)
 * against capsule B (unit axis v through c, half height hb, radius rb). */
MK_ALWAYS_INLINE mk_hit mk_closest_capsule_capsule(mk_real ha, mk_vec3 u, mk_real ra, mk_vec3 c, mk_vec3 v, mk_real hb, mk_real rb)
{
    mk_real s, t, l;
    mk_vec3 p0 = mk_v3_scale(u, -ha), p1 = mk_v3_scale(u, ha);
    mk_vec3 q0 = mk_v3_mad(c, -hb, v), q1 = mk_v3_mad(c, hb, v);
    mk_vec3 pa, pb, dv, n, axes;
    mk_segment_segment(p0, p1, q0, q1, &s, &t);
    pa = mk_v3_lerp(p0, p1, s);
    pb = mk_v3_lerp(q0, q1, t);
    dv = mk_v3_sub(pb, pa);
    l = mk_v3_len(dv);
    /* Both points inside their segments: an edge-edge pair, whose normal is
     * the cross product of the axes exactly, and whose distance is that of the
     * two lines (no error from s and t). Also the only sane normal when the
     * cores cross (l == 0). Its direction error is about eps / sin(angle), so
     * below sin^2 = sqrt(eps) the difference of the points is the better normal. */
    axes = mk_v3_cross(u, v);
    if (s > 0 && s < 1 && t > 0 && t < 1 && mk_v3_len2(axes) > mk_sqrt_(MK_REAL_EPSILON)) {
        n = mk_v3_normalize(axes);
        if (mk_v3_dot(n, l > 0 ? dv : c) < 0) n = mk_v3_neg(n);
        l = mk_v3_dot(n, mk_v3_sub(q0, p0));
        if (l < 0) l = 0;
        pb = mk_v3_mad(pa, l, n);
    } else if (l > 0) {
        n = mk_v3_scale(dv, 1 / l);
    } else {
        /* Parallel cores that overlap: leave across the axis, towards B's centre if it is off the axis. */
        mk_vec3 off = mk_v3_mad(c, -mk_v3_dot(c, u), u);
        n = mk_v3_len2(off) > 0 ? mk_v3_normalize(off) : mk_v3_perp(u);
    }
    return mk_hit_grow(pa, pb, l, n, ra, rb);
}

/* Any convex shape A against the half-space B (support of A along -n). */
mk_hit mk_closest_shape_plane(const mk_pair *p);

/* The GJK/EPA answer (with the polish) for a pair already in A's frame: what
 * mk_distance runs for pairs without a closed form, for callers that build
 * the pair themselves (mk_collide). MK_ERR_UNSUPPORTED when GJK or EPA is
 * left out of the build. `cache` may be NULL. */
mk_status mk_pair_distance(const mk_pair *p, mk_gjk_cache *cache, mk_hit *out);

#endif

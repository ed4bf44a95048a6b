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

/* 1/sqrt(l2), and sqrt(l2) in *len, with the square root and the division
 * side by side rather than one after the other: a closed form's time is
 * mostly the latency of its chain of dependent operations. Where 1/l2 would
 * overflow or vanish the division waits for the root; l2 == 0 gives 0. */
MK_ALWAYS_INLINE mk_real mk_inv_len(mk_real l2, mk_real *len)
{
    mk_real l = mk_sqrt_(l2);
    *len = l;
    if (l2 >= 1 / MK_REAL_MAX && l2 <= MK_REAL_MAX) return l * (1 / l2);
    return l > 0 ? 1 / l : 0;
}

/* v / |v|, and |v| in *len (mk_inv_len); a zero v gives the zero vector
 * (callers pick their own direction). */
MK_ALWAYS_INLINE mk_vec3 mk_unit_len(mk_vec3 v, mk_real *len) { return mk_v3_scale(v, mk_inv_len(mk_v3_len2(v), len)); }

/* The point of a box core of half extents h nearest x (box frame). As
 * max(-h, min(x, h)), which compiles to minsd/maxsd: mk_clamp's nested
 * conditional compiles to branches, and on a query's random relative poses
 * those mispredict about half the time (x is finite here). */
MK_ALWAYS_INLINE mk_vec3 mk_box_clamp(mk_vec3 h, mk_vec3 x)
{
    return mk_v3(mk_max(-h.x, mk_min(x.x, h.x)), mk_max(-h.y, mk_min(x.y, h.y)), mk_max(-h.z, mk_min(x.z, h.z)));
}

/* For a point c inside a box core of half extents h: the face it leaves
 * through soonest, as its outward unit normal *n and the point *q of that
 * face nearest c; returns the depth h_k - |c_k| >= 0. Ties go to x, then y. */
MK_ALWAYS_INLINE mk_real mk_box_exit(mk_vec3 h, mk_vec3 c, mk_vec3 *n, mk_vec3 *q)
{
    mk_real gx = h.x - mk_fabs_(c.x), gy = h.y - mk_fabs_(c.y), gz = h.z - mk_fabs_(c.z);
    *q = c;
    if (gx <= gy && gx <= gz) {
        *n = mk_v3(c.x >= 0 ? 1 : -1, 0, 0);
        q->x = c.x >= 0 ? h.x : -h.x;
        return gx;
    }
    if (gy <= gz) {
        *n = mk_v3(0, c.y >= 0 ? 1 : -1, 0);
        q->y = c.y >= 0 ? h.y : -h.y;
        return gy;
    }
    *n = mk_v3(0, 0, c.z >= 0 ? 1 : -1);
    q->z = c.z >= 0 ? h.z : -h.z;
    return gz;
}

/* A box core of half extents h, rounded by ra, against a sphere of radius
 * rb centred at c, in the box's frame. */
MK_ALWAYS_INLINE mk_hit mk_closest_box_sphere(mk_vec3 h, mk_real ra, mk_vec3 c, mk_real rb)
{
    mk_vec3 q = mk_box_clamp(h, c), n;
    mk_real l, g;
    n = mk_unit_len(mk_v3_sub(c, q), &l);
    if (l > 0) return mk_hit_grow(q, c, l, n, ra, rb);
    /* Centre inside the core: leave through the nearest face. */
    g = mk_box_exit(h, c, &n, &q);
    return mk_hit_grow(q, c, -g, n, ra, rb);
}

/* A capsule (segment of half height hh along the unit axis u through the
 * origin, radius ra) against a sphere of radius rb centred at c. */
MK_ALWAYS_INLINE mk_hit mk_closest_capsule_sphere(mk_real hh, mk_vec3 u, mk_real ra, mk_vec3 c, mk_real rb)
{
    mk_vec3 q = mk_v3_scale(u, mk_clamp(mk_v3_dot(c, u), -hh, hh)), n;
    mk_real l;
    n = mk_unit_len(mk_v3_sub(c, q), &l);
    /* Centre on the segment: any direction across the axis is a shortest way out. */
    return mk_hit_grow(q, c, l, l > 0 ? n : mk_v3_perp(u), ra, rb);
}

/* Closest parameters s, t of the segments {s U : |s| <= ha} and
 * {c + t V : |t| <= hb}, from a = U.U, e = V.V, b = U.V, cu = c.U, cv = c.V
 * and w2 = |U x V|^2, which is a e - b^2 without that difference's
 * cancellation for nearly parallel segments. Parallel segments (sin^2 of
 * the angle at rounding level) get the midpoint of the overlap of B's
 * projection with A, so the answer is symmetric and stable under small
 * motions. For unit axes pass the constants a = e = 1: inlined, the
 * divisions by them vanish. */
MK_ALWAYS_INLINE void mk_segment_params(mk_real a, mk_real e, mk_real b, mk_real cu, mk_real cv, mk_real w2, mk_real ha, mk_real hb,
                                        mk_real *s_out, mk_real *t_out)
{
    mk_real s, t;
    if (w2 > MK_REAL(16.0) * MK_REAL_EPSILON * a * e) {
        s = mk_clamp((cu * e - b * cv) / w2, -ha, ha);
    } else if (a > 0) {
        /* B's ends projected on A's line; the centre of their overlap with A. */
        mk_real p0 = (cu - b * hb) / a, p1 = (cu + b * hb) / a;
        mk_real lo = mk_max(mk_min(p0, p1), -ha), hi = mk_min(mk_max(p0, p1), ha);
        s = lo <= hi ? MK_REAL(0.5) * (lo + hi) : (mk_max(p0, p1) < -ha ? -ha : ha);
    } else {
        s = 0;
    }
    /* A segment of zero length (its ends rounded together far from the
     * origin) is its centre. */
    t = e > 0 ? mk_clamp((b * s - cv) / e, -hb, hb) : 0;
    s = a > 0 ? mk_clamp((b * t + cu) / a, -ha, ha) : 0;
    *s_out = s;
    *t_out = t;
}

/* Closest points of segments [p0, p1] and [q0, q1]: parameters s, t in [0, 1]
 * (mk_segment_params on the centres and half-axes). */
MK_ALWAYS_INLINE void mk_segment_segment(mk_vec3 p0, mk_vec3 p1, mk_vec3 q0, mk_vec3 q1, mk_real *s_out, mk_real *t_out)
{
    mk_vec3 u = mk_v3_scale(mk_v3_sub(p1, p0), MK_REAL(0.5)), v = mk_v3_scale(mk_v3_sub(q1, q0), MK_REAL(0.5));
    mk_vec3 c = mk_v3_scale(mk_v3_sub(mk_v3_add(q0, q1), mk_v3_add(p0, p1)), MK_REAL(0.5));
    mk_real s, t;
    mk_segment_params(mk_v3_len2(u), mk_v3_len2(v), mk_v3_dot(u, v), mk_v3_dot(c, u), mk_v3_dot(c, v), mk_v3_len2(mk_v3_cross(u, v)), 1,
                      1, &s, &t);
    *s_out = MK_REAL(0.5) * (s + 1);
    *t_out = MK_REAL(0.5) * (t + 1);
}

/* Capsule A (unit axis u through the origin, half height ha, radius ra)
 * against capsule B (unit axis v through c, half height hb, radius rb). */
MK_ALWAYS_INLINE mk_hit mk_closest_capsule_capsule(mk_real ha, mk_vec3 u, mk_real ra, mk_vec3 c, mk_vec3 v, mk_real hb, mk_real rb)
{
    mk_vec3 axes = mk_v3_cross(u, v), pa, pb, n;
    mk_real w2 = mk_v3_len2(axes), s, t, l;
    mk_segment_params(1, 1, mk_v3_dot(u, v), mk_v3_dot(c, u), mk_v3_dot(c, v), w2, ha, hb, &s, &t);
    pa = mk_v3_scale(u, s);
    pb = mk_v3_mad(c, t, v);
    /* Both points inside their segments: an edge-edge pair, whose normal is
     * the cross product of the axes exactly, and whose distance is that of
     * the two lines, n.c (no error from s and t). Also the only sane normal
     * when the cores cross (pa == pb). Its direction error is about
     * eps / sin(angle), so below sin^2 = sqrt(eps) the difference of the
     * points is the better normal. */
    if (mk_fabs_(s) < ha && mk_fabs_(t) < hb && w2 > mk_sqrt_(MK_REAL_EPSILON)) {
        n = mk_unit_len(axes, &l);
        l = mk_v3_dot(n, c);
        if (l < 0) {
            n = mk_v3_neg(n);
            l = -l;
        }
        pb = mk_v3_mad(pa, l, n);
    } else {
        n = mk_unit_len(mk_v3_sub(pb, pa), &l);
        if (!(l > 0)) {
            /* Parallel cores that overlap: leave across the axis, towards B's centre if it is off the axis. */
            mk_vec3 off = mk_v3_mad(c, -mk_v3_dot(c, u), u);
            n = mk_v3_len2(off) > 0 ? mk_v3_normalize(off) : mk_v3_perp(u);
        }
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

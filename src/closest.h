/* closest.h: closed-form signed distances for simple pairs (internal).
 *
 * Each function answers for whole shapes (cores grown by their rounding
 * radii) in one frame, given exactly the geometry it needs (a capsule is its
 * axis, a sphere its centre), so callers build no more of a pose than the
 * pair uses and capsule pairs need no rotation back. Exact up to a few
 * roundings of the shapes' size: no iteration, no tolerance. Where the
 * direction is undefined (a sphere centre on the other core), a fixed,
 * documented choice is made so the result is never NaN. O(1) each.
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

/* A box core of half extents h, rounded by ra, against a sphere of radius
 * rb centred at c, in the box's frame. */
mk_hit mk_closest_box_sphere(mk_vec3 h, mk_real ra, mk_vec3 c, mk_real rb);
/* A capsule (segment of half height hh along the unit axis u through the
 * origin, radius ra) against a sphere of radius rb centred at c. */
mk_hit mk_closest_capsule_sphere(mk_real hh, mk_vec3 u, mk_real ra, mk_vec3 c, mk_real rb);
/* Capsule A (unit axis u through the origin, half height ha, radius ra)
 * against capsule B (unit axis v through c, half height hb, radius rb). */
mk_hit mk_closest_capsule_capsule(mk_real ha, mk_vec3 u, mk_real ra, mk_vec3 c, mk_vec3 v, mk_real hb, mk_real rb);
/* Any convex shape A against the half-space B (support of A along -n). */
mk_hit mk_closest_shape_plane(const mk_pair *p);

/* The GJK/EPA answer (with the polish) for a pair already in A's frame: what
 * mk_distance runs for pairs without a closed form, for callers that build
 * the pair themselves (mk_collide). MK_ERR_UNSUPPORTED when GJK or EPA is
 * left out of the build. `cache` may be NULL. */
mk_status mk_pair_distance(const mk_pair *p, mk_gjk_cache *cache, mk_hit *out);

/* Closest points of segments [p0, p1] and [q0, q1]: parameters s, t in [0, 1].
 * Parallel segments get the midpoint of the overlap of their projections, so
 * the answer is symmetric and stable under small motions. */
void mk_segment_segment(mk_vec3 p0, mk_vec3 p1, mk_vec3 q0, mk_vec3 q1, mk_real *s, mk_real *t);

#endif

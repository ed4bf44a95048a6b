/* closest.h: closed-form signed distances for simple pairs (internal).
 *
 * Each function answers for whole shapes (cores grown by their rounding
 * radii) in the frame of its first shape A, with B given by the relative pose
 * of mk_pair (rotation r, translation t). The answer is exact up to a few
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

/* A box (any rounding) against a sphere (B is a point core). */
mk_hit mk_closest_box_sphere(const mk_pair *p);
/* A capsule against a sphere. */
mk_hit mk_closest_capsule_sphere(const mk_pair *p);
/* Two capsules: segment-segment closest points. */
mk_hit mk_closest_capsule_capsule(const mk_pair *p);
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

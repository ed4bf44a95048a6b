/* minko/raycast.h: ray casts against every shape type.
 *
 * Contract. A ray is the segment origin + f * translation, f in [0, 1] (the
 * Box2D convention: the translation's length is the ray's length, so there is
 * no separate "max distance"). mk_raycast() reports the first point where the
 * segment meets the solid shape (core grown by its rounding radius) placed at
 * `xf`: the fraction, the world point and the unit outward surface normal
 * there. Answers are exact up to rounding: closed forms for spheres, planes
 * and unrounded hulls; for the other shapes a Newton iteration on the exact
 * distance from the ray point to the shape's core, which approaches the first
 * root monotonically from the ray origin's side (the distance along a line is
 * convex), so it cannot step past the entry point or into a later one.
 * A ray that starts inside (or on) the solid hits at fraction 0 with the
 * normal opposite to the ray direction (zero for a zero translation). The
 * work runs in the shape's frame, so shapes far from the origin lose no
 * precision beyond that of the inputs. Bad input returns a status and leaves
 * *out untouched. Cost: O(1) per iteration for primitives (typically 1 to 6
 * iterations), O(faces) for hulls. Nothing allocates.
 */
#ifndef MINKO_RAYCAST_H
#define MINKO_RAYCAST_H

#include "minko/shape.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mk_ray_hit {
    int hit;          /* 1 when the segment meets the solid, else 0 and the rest is the segment's end */
    mk_real fraction; /* in [0, 1]: point = origin + fraction * translation */
    mk_vec3 point;    /* world frame */
    mk_vec3 normal;   /* unit outward surface normal at the hit, world frame */
} mk_ray_hit;

MK_API mk_status mk_raycast(const mk_shape *s, mk_transform xf, mk_vec3 origin, mk_vec3 translation, mk_ray_hit *out);

#ifdef __cplusplus
}
#endif

#endif

/* shape_internal.h: what the narrowphase needs from shapes beyond the public API. */
#ifndef MINKO_SHAPE_INTERNAL_H
#define MINKO_SHAPE_INTERNAL_H

#include "minko/shape.h"

/* Largest accepted size or coordinate magnitude of a shape dimension. Squares
 * and triple products of sizes must stay finite in mk_real. */
#if defined(MK_SINGLE)
#  define MK_MAX_SIZE MK_REAL(1e8)
#else
#  define MK_MAX_SIZE MK_REAL(1e12)
#endif

/* Support point of the core alone (no rounding radius), local frame.
 * *feature is in/out: on entry a hint (previous answer, or -1), on exit the
 * index of the core vertex returned (box corner bits zyx: bit set = +extent;
 * hull vertex index; capsule end 0 = -h, 1 = +h; cone apex 0; sphere 0) or -1
 * when the point lies on a smooth part (cylinder rim, cone rim). Vertex
 * indices let GJK stop on a repeated support point and let manifolds name
 * features. `feature` may be NULL. */
mk_vec3 mk_core_support(const mk_shape *s, mk_vec3 dir, int *feature);

/* 1 if the core is a polytope whose vertices mk_core_support enumerates
 * (box, hull, capsule segment, sphere point). */
int mk_core_is_polytope(const mk_shape *s);

#endif

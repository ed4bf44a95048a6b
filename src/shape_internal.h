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

/* A size (extent, radius, half height): in (0, MK_MAX_SIZE]; a rounding
 * radius may also be 0. NaN fails both comparisons. */
static inline int mk_size_ok_(mk_real v) { return v > 0 && v <= MK_MAX_SIZE; }
static inline int mk_rounding_ok_(mk_real v) { return v >= 0 && v <= MK_MAX_SIZE; }

/* Support point of the core alone (no rounding radius), local frame.
 * *feature is in/out: on entry a hint (previous answer, or -1), on exit the
 * index of the core vertex returned (box corner bits zyx: bit set = +extent;
 * hull vertex index; capsule end 0 = -h, 1 = +h; cone apex 0; sphere 0) or -1
 * when the point lies on a smooth part (cylinder rim, cone rim). Vertex
 * indices let GJK stop on a repeated support point and let manifolds name
 * features. `feature` may be NULL. */
mk_vec3 mk_core_support(const mk_shape *s, mk_vec3 dir, int *feature);

/* For the few helpers of the narrowphase loops that must be inlined even
 * where the compiler's size heuristics would call them (a support is ~10
 * flops; a call and a spilled struct return cost as much again). */
#if defined(__GNUC__) || defined(__clang__)
#  define MK_ALWAYS_INLINE static inline __attribute__((always_inline))
#else
#  define MK_ALWAYS_INLINE static inline
#endif
/* For the rare, long branches of a hot entry point (error diagnosis, the
 * iterative solvers), so the common path keeps a small stack frame. */
#if defined(__GNUC__) || defined(__clang__)
#  define MK_NOINLINE __attribute__((noinline))
#else
#  define MK_NOINLINE
#endif

/* 1 exactly when mk_shape_validate(s) would return MK_OK, for a shape whose
 * type is t (the caller knows it, e.g. from a dispatch table; pass s->type
 * otherwise): the accepting test each pair query pays, with no call and,
 * for a constant t, no switch. mk_shape_validate names what is wrong. */
MK_ALWAYS_INLINE int mk_shape_ok_typed_(const mk_shape *s, mk_shape_type t)
{
    mk_real r = s->radius;
    switch (t) {
    case MK_SHAPE_SPHERE: return mk_size_ok_(r);
    case MK_SHAPE_BOX:
        return mk_rounding_ok_(r) && mk_size_ok_(s->u.half_extents.x) && mk_size_ok_(s->u.half_extents.y) &&
               mk_size_ok_(s->u.half_extents.z);
    case MK_SHAPE_CAPSULE: return mk_size_ok_(r) && mk_size_ok_(s->u.capsule.half_height);
    case MK_SHAPE_CYLINDER: return mk_rounding_ok_(r) && mk_size_ok_(s->u.cylinder.radius) && mk_size_ok_(s->u.cylinder.half_height);
    case MK_SHAPE_CONE: return mk_rounding_ok_(r) && mk_size_ok_(s->u.cone.radius) && mk_size_ok_(s->u.cone.half_height);
    case MK_SHAPE_HULL: return mk_rounding_ok_(r) && s->u.hull && s->u.hull->vertex_count >= 4 && s->u.hull->face_count >= 4;
    case MK_SHAPE_PLANE: { /* the rounding radius of a plane is not used */
        mk_vec3 n = s->u.plane.normal;
        return mk_v3_is_valid(n) && mk_fabs_(s->u.plane.offset) <= MK_MAX_COORD && mk_fabs_(mk_v3_len2(n) - 1) <= MK_QUAT_TOLERANCE;
    }
    default: return 0;
    }
}

#include "hull_support.h"

static inline mk_real mk_sgn_extent_(mk_real d, mk_real h) { return d >= 0 ? h : -h; }

/* Exchanges the two shapes of a pair query and their poses: dispatch tables
 * keep one method per unordered pair and run the other order swapped. */
static inline void mk_swap_pair_(const mk_shape **a, mk_transform *xa, const mk_shape **b, mk_transform *xb)
{
    const mk_shape *s = *a;
    mk_transform x = *xa;
    *a = *b;
    *b = s;
    *xa = *xb;
    *xb = x;
}

/* The body of mk_core_support for a shape of type t (normally s->type), so
 * loops specialised on a constant t lose the switch and keep their vectors in
 * registers. *feature must be valid (in/out). */
MK_ALWAYS_INLINE mk_vec3 mk_core_support_typed(const mk_shape *s, mk_shape_type t, mk_vec3 d, int *feature)
{
    switch (t) {
    case MK_SHAPE_SPHERE:
        *feature = 0;
        return mk_v3_zero();
    case MK_SHAPE_BOX: {
        mk_vec3 h = s->u.half_extents;
        *feature = (d.x >= 0 ? 1 : 0) | (d.y >= 0 ? 2 : 0) | (d.z >= 0 ? 4 : 0);
        return mk_v3(mk_sgn_extent_(d.x, h.x), mk_sgn_extent_(d.y, h.y), mk_sgn_extent_(d.z, h.z));
    }
    case MK_SHAPE_CAPSULE:
        *feature = d.z >= 0 ? 1 : 0;
        return mk_v3(0, 0, mk_sgn_extent_(d.z, s->u.capsule.half_height));
    case MK_SHAPE_CYLINDER: {
        mk_real sigma = mk_sqrt_(d.x * d.x + d.y * d.y), r = s->u.cylinder.radius;
        mk_real z = mk_sgn_extent_(d.z, s->u.cylinder.half_height);
        *feature = -1;
        return sigma > 0 ? mk_v3(r * d.x / sigma, r * d.y / sigma, z) : mk_v3(0, 0, z);
    }
    case MK_SHAPE_CONE: {
        mk_real sigma = mk_sqrt_(d.x * d.x + d.y * d.y), r = s->u.cone.radius, h = s->u.cone.half_height;
        /* Apex value d.z*h against the best base-rim value r*sigma - d.z*h. */
        if (d.z * h >= r * sigma - d.z * h) {
            *feature = 0;
            return mk_v3(0, 0, h);
        }
        *feature = -1;
        return sigma > 0 ? mk_v3(r * d.x / sigma, r * d.y / sigma, -h) : mk_v3(0, 0, -h);
    }
    case MK_SHAPE_HULL:
        *feature = mk_hull_support_(s->u.hull, d, *feature);
        return s->u.hull->vertices[*feature];
    case MK_SHAPE_PLANE:
    default:
        *feature = -1;
        return mk_v3(MK_REAL_MAX, MK_REAL_MAX, MK_REAL_MAX);
    }
}

/* mk_core_support inline: the GJK/EPA loops pay no call. */
MK_ALWAYS_INLINE mk_vec3 mk_core_support_inl(const mk_shape *s, mk_vec3 d, int *feature)
{
    return mk_core_support_typed(s, s->type, d, feature);
}

/* Number of vertices mk_core_support can name for a polytope core (sphere 1,
 * capsule 2, box 8, hull V); 0 for the other shapes. */
static inline int mk_core_vertex_count(const mk_shape *s)
{
    switch (s->type) {
    case MK_SHAPE_SPHERE: return 1;
    case MK_SHAPE_CAPSULE: return 2;
    case MK_SHAPE_BOX: return 8;
    case MK_SHAPE_HULL: return s->u.hull->vertex_count;
    default: return 0;
    }
}

/* Core vertex by the index mk_core_support reports; the index must be in
 * [0, mk_core_vertex_count(s)). Warm starts rebuild cached simplices with it. */
static inline mk_vec3 mk_core_vertex(const mk_shape *s, int i)
{
    switch (s->type) {
    case MK_SHAPE_BOX: {
        mk_vec3 h = s->u.half_extents;
        return mk_v3((i & 1) ? h.x : -h.x, (i & 2) ? h.y : -h.y, (i & 4) ? h.z : -h.z);
    }
    case MK_SHAPE_CAPSULE: return mk_v3(0, 0, i ? s->u.capsule.half_height : -s->u.capsule.half_height);
    case MK_SHAPE_HULL: return s->u.hull->vertices[i];
    default: return mk_v3_zero();
    }
}

/* 1 if the core is a polytope whose vertices mk_core_support enumerates
 * (box, hull, capsule segment, sphere point). */
int mk_core_is_polytope(const mk_shape *s);

#endif

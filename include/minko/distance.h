/* minko/distance.h: signed distance, closest points and overlap of two convex shapes.
 *
 * Contract. mk_distance() answers, for any two shapes, the signed distance
 * (> 0 gap, < 0 penetration depth, 0 touching), a unit normal pointing from A
 * towards B, and witness points on both surfaces with
 * point_b = point_a + distance * normal. Every query runs in A's local frame,
 * so both shapes placed far from the origin lose no precision beyond what the
 * inputs themselves carry. A dispatch table picks the cheapest exact method for
 * the pair: closed forms for sphere/capsule/box/plane pairs (a sphere-only
 * scene never enters GJK); for two boxes, SAT's 15 axes, whose bound is
 * certified exact by the supporting features or, for corner contacts, by a
 * corner and its nearest point (all overlapping pairs, all but rounding-level
 * ties of separated ones); GJK on the cores for other separated shapes, and EPA for
 * other penetrating cores. The distance GJK or EPA reports is always re-evaluated
 * with the support functions along the final normal, which for polytopes is
 * the cross product of original feature edges: polytope answers are exact to
 * the rounding of the relative pose, not to a solver tolerance; smooth cores
 * (cylinder, cone) converge to 1e4 eps relative. `result.method` says which
 * answered. Iterative methods carry hard caps; `result.state` says whether the
 * answer converged, hit the cap (the answer is then the best bound found), or
 * met a degenerate configuration it resolved by a fallback. Bad input (NULL,
 * NaN/Inf, non-unit rotations, coordinates beyond MK_MAX_COORD, invalid
 * shapes) returns a status and leaves *out untouched. Each query comes in two
 * forms with one implementation: the _pose form takes poses checked once by
 * mk_pose_from_transform / mk_pose_from_matrix (minko/math3d.h) and only
 * reads their tag (MK_ERR_UNCHECKED_POSE otherwise), which is what an engine
 * that keeps rotation matrices calls; the mk_transform form checks both
 * transforms in full (a sphere's non-unit quaternion is still
 * MK_ERR_BAD_ROTATION), converts only what the pair reads (nothing for two
 * spheres, a capsule's axis, a box's matrix) and computes the same answer bit
 * for bit. Nothing here allocates. Plane-plane pairs are unsupported.
 */
#ifndef MINKO_DISTANCE_H
#define MINKO_DISTANCE_H

#include "minko/shape.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mk_method {
    MK_METHOD_NONE = 0,
    MK_METHOD_CLOSED_FORM,
    MK_METHOD_GJK,
    MK_METHOD_EPA,
    MK_METHOD_SAT
} mk_method;

typedef enum mk_solve_state {
    MK_SOLVE_CONVERGED = 0,
    MK_SOLVE_MAX_ITERATIONS,
    MK_SOLVE_DEGENERATE
} mk_solve_state;

/* Caller-owned warm start for GJK between the same pair on consecutive
 * frames. Zero-initialise it (or pass NULL) for a cold start. */
typedef struct mk_gjk_cache {
    mk_vec3 dir;         /* last separating direction, in A's frame */
    int count;           /* 0: cold */
    int ia[4], ib[4];    /* support vertex indices of the last simplex (-1 where not a vertex) */
} mk_gjk_cache;

typedef struct mk_distance_result {
    mk_real distance;    /* signed: > 0 separated, < 0 penetrating */
    mk_vec3 normal;      /* unit, world frame, from A towards B */
    mk_vec3 point_a;     /* on A's surface, world frame */
    mk_vec3 point_b;     /* on B's surface, world frame */
    int iterations;      /* GJK + EPA iterations, or SAT axes tested */
    mk_method method;
    mk_solve_state state;
} mk_distance_result;

MK_API mk_status mk_distance(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb,
                             mk_gjk_cache *cache, mk_distance_result *out);
MK_API mk_status mk_distance_pose(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb,
                                  mk_gjk_cache *cache, mk_distance_result *out);

/* Boolean overlap (touching counts as overlapping). Cheaper than mk_distance:
 * GJK stops as soon as a separating axis or a containing simplex is found.
 * It agrees with the sign of mk_distance except within rounding of contact
 * (|distance| of a few ulps of the shapes' size), where either is correct. */
MK_API mk_status mk_overlap(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb,
                            mk_gjk_cache *cache, int *overlapping);
MK_API mk_status mk_overlap_pose(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb,
                                 mk_gjk_cache *cache, int *overlapping);

/* Seed 003's approximate distance: from A's vertex facing B, walk to the
 * vertex of B nearest it, then back to the vertex of A nearest that; answers
 * their distance minus both rounding radii. Two surface points are never
 * closer than the shapes, so this is an upper bound on mk_distance's signed
 * distance (for culling: "certainly within reach"). Polytope cores only
 * (box, hull, capsule, sphere); others give MK_ERR_UNSUPPORTED. O(1) for
 * boxes, a walk over the vertex graph for hulls. */
MK_API mk_status mk_approx_distance(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb,
                                    mk_real *out);

MK_API const char *mk_method_name(mk_method m);

#ifdef __cplusplus
}
#endif

#endif

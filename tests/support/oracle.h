/* oracle.h: exact reference answers for narrowphase tests and benchmarks.
 *
 * Contract. Brute force in long double, independent of mk_real and of
 * Minko's own algorithms: the numbers in the mk_shape / mk_transform handed
 * in are taken as exact (quaternions are normalised in long double), and
 * every answer follows from the definitions:
 *  - polytope cores (box, hull) are rebuilt from their vertices by a
 *    brute-force convex hull (every supporting plane through three points,
 *    coplanar points merged into one polygon), so a quickhull bug cannot hide
 *    behind the judge;
 *  - separated: the minimum over ALL feature pairs (vertex, edge, face of A
 *    against vertex, edge, face of B) of their Euclidean distance;
 *  - penetrating: SAT over all face normals of both shapes and all edge-pair
 *    cross products, both orientations; the default run skips edge pairs whose
 *    Gauss-map arcs cannot cross (they are never faces of the Minkowski
 *    difference) and axes whose separation, bounded from above by the
 *    extents of an inner polytope (the vertices extreme along 26 fixed
 *    directions), cannot reach the best one; MK_ORACLE_EXHAUSTIVE evaluates
 *    every axis in full and tests/test_oracle.c checks that both agree;
 *  - sphere and capsule cores are a point and a segment and go through the
 *    same feature distances; anything against a plane uses the support
 *    function (cylinders and cones are supported against planes only).
 * Rounding radii are subtracted at the end: d = d_core - rA - rB.
 * Accuracy: a few 1e-19 of the shapes' size in generic poses. Edge pairs
 * within 2e-10 rad of parallel are skipped (their Minkowski face is a sliver
 * whose neighbours bound it), which bounds the error by 2e-10 x edge length
 * in crafted nearly-parallel poses; exactly parallel edges (equal rotations)
 * cost nothing. The oracle refuses (returns -1) rather than guess: unsupported
 * pairs, invalid input, a point cloud whose brute-force hull fails its
 * Euler/twin checks. Memory: shapes and queries use malloc (test support,
 * not library code). Complexity: building a hull of V points is O(V^3) with
 * early exits; a query is O((F + E_A E_B)(V_A + V_B)) worst case, far less
 * with the Gauss-map and bounding-sphere pruning. No Check dependency, so
 * demos link it too.
 */
#ifndef MK_ORACLE_H
#define MK_ORACLE_H

#include "minko/shape.h"

typedef struct mk_lvec3 { long double x, y, z; } mk_lvec3;

/* A convex polytope in long double: vertices (extreme points only), faces
 * as convex polygons counter-clockwise seen from outside, edges with their two
 * faces. A sphere core is one vertex, a capsule core two vertices and one edge
 * with faces -1. Derived data (face centroids and radii, edge midpoints) serve
 * the bounding-sphere pruning of the feature loops. */
typedef struct mk_oracle_poly {
    int nv, nf, ne;
    mk_lvec3 *v;
    int *face_first;      /* face f: face_vert[face_first[f] .. face_first[f + 1]) */
    int *face_vert;
    mk_lvec3 *fn;         /* unit outward normals */
    mk_lvec3 *fc;         /* polygon centroids */
    long double *fr;      /* polygon radii about fc */
    int (*ev)[2];         /* edge end vertices */
    int (*ef)[2];         /* the two faces of each edge (-1 for a bare segment) */
    mk_lvec3 centroid;    /* mean of the vertices */
    long double radius;   /* max distance of a vertex from the local origin */
    int nprobe;           /* vertices extreme along 26 directions: their extents */
    int *probe;           /*   bound the full ones cheaply in SAT (an inner polytope) */
} mk_oracle_poly;

typedef struct mk_oracle_shape {
    mk_shape_type type;
    long double rounding;     /* the solid is the core grown by this radius */
    long double disc_radius;  /* cylinder and cone cores */
    long double half_height;  /* cylinder and cone cores */
    mk_lvec3 plane_n;         /* plane: { x : n.x <= d } */
    long double plane_d;
    mk_oracle_poly core;      /* point, segment, box or hull; empty otherwise */
    long double size;         /* bounding radius about the local origin, rounding included */
} mk_oracle_shape;

typedef struct mk_oracle_pose { long double r[3][3]; mk_lvec3 p; } mk_oracle_pose; /* x -> r x + p */

typedef struct mk_oracle_result {
    long double distance;  /* signed: > 0 gap, < 0 penetration depth */
    mk_lvec3 normal;       /* unit, world frame, from A towards B */
    int normal_defined;    /* 0 when the exact normal is not unique (ties, touching cores) */
} mk_oracle_result;

#define MK_ORACLE_EXHAUSTIVE 1u /* keep every edge pair in SAT (for checking the pruning) */

/* 0 on success, -1 for an invalid or unsupported shape. Hulls are rebuilt
 * from hull->vertices. Free with mk_oracle_shape_free. */
int mk_oracle_shape_init(mk_oracle_shape *o, const mk_shape *s);
/* The convex hull of n points (local frame), grown by `rounding`. */
int mk_oracle_shape_points(mk_oracle_shape *o, const mk_lvec3 *points, int n, long double rounding);
void mk_oracle_shape_free(mk_oracle_shape *o);

/* Exact rotation of q / |q| and the translation of xf. */
mk_oracle_pose mk_oracle_pose_of(mk_transform xf);

/* Signed distance of a at xa and b at xb. 0 on success, -1 for an unsupported pair. */
int mk_oracle_query(const mk_oracle_shape *a, const mk_oracle_pose *xa, const mk_oracle_shape *b,
                    const mk_oracle_pose *xb, unsigned flags, mk_oracle_result *out);
/* One-shot form for tests: builds both oracle shapes, queries, frees. */
int mk_oracle_distance(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb, mk_oracle_result *out);

/* Angle in degrees between the reference unit normal and (x, y, z); 180 for a zero or non-finite vector. */
long double mk_oracle_angle_deg(mk_lvec3 ref, long double x, long double y, long double z);

#endif

/* minko/shape.h: convex shapes, their support functions and bounds.
 *
 * Contract. A shape is a small value (mk_shape) describing a convex *core* in
 * its own local frame plus a rounding radius r >= 0: the solid is the core
 * grown by a ball of radius r (Bullet's margin made exact). A sphere is a point
 * core, a capsule a segment core, so "rounded box" and friends are exact, not
 * approximations. Axes of capsules, cylinders and cones are the local z axis;
 * a cone has its apex at +half_height and its base disc at -half_height.
 * A plane is the half-space { x : n.x <= offset } (solid below the plane).
 * Hulls are built once by quickhull (mk_hull_create) and shared by reference
 * between shapes; the mk_hull must outlive every mk_shape that points at it.
 * Constructors validate (finite, positive sizes, unit normals, non-degenerate
 * hulls) and return a status; mk_shape_validate() checks a hand-filled struct.
 * Queries take the shape by const pointer and never allocate.
 */
#ifndef MINKO_SHAPE_H
#define MINKO_SHAPE_H

#include "minko/math3d.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mk_shape_type {
    MK_SHAPE_SPHERE = 0,
    MK_SHAPE_BOX,
    MK_SHAPE_CAPSULE,
    MK_SHAPE_CYLINDER,
    MK_SHAPE_CONE,
    MK_SHAPE_HULL,
    MK_SHAPE_PLANE,
    MK_SHAPE_TYPE_COUNT
} mk_shape_type;

/* n.x = offset */
typedef struct mk_plane { mk_vec3 normal; mk_real offset; } mk_plane;

/* Half-edge of a hull. Indices are into mk_hull's arrays. `twin` is the
 * opposite half-edge; `next` walks the face counter-clockwise seen from
 * outside; `origin` is the vertex the edge leaves. */
typedef struct mk_hull_edge { uint16_t next, twin, origin, face; } mk_hull_edge;

/* A convex polyhedron with merged coplanar faces (faces are convex polygons).
 * Built by mk_hull_create(); read-only afterwards. Memory is one block owned
 * by the hull. Complexity: creation O(n log n) expected (quickhull); the
 * support function scans small hulls and hill-climbs the vertex adjacency of
 * larger ones, O(sqrt(V)) typical. Each face's half-edges are stored
 * contiguously in loop order. */
typedef struct mk_hull {
    int vertex_count;
    int edge_count;            /* half-edges: twice the number of edges */
    int face_count;
    const mk_vec3 *vertices;
    const mk_hull_edge *edges;
    const uint16_t *face_edge; /* one half-edge of each face */
    const mk_plane *planes;    /* outward unit normal and offset of each face */
    const uint16_t *vertex_edge; /* one half-edge leaving each vertex */
    const uint16_t *adjacency; /* vertex v's neighbours: adjacency[adjacency[v] .. adjacency[v + 1]);
                                * then the vertices extreme along +x, -x, +y, -y, +z, -z */
    mk_vec3 centroid;          /* centroid of the solid */
    mk_real inner_radius;      /* distance from centroid to the nearest face plane */
    mk_real outer_radius;      /* distance from centroid to the farthest vertex */
    mk_aabb bounds;            /* local AABB */
    mk_real tolerance;         /* distance below which construction treated points as on a plane */
    const mk_real *coords;     /* the vertices again as three rows (every x, then every y, then every z),
                                * each padded to a multiple of 4 entries with copies of vertex 0: the
                                * support scan's layout */
    mk_allocator allocator;    /* the allocator that owns this block */
    size_t bytes;              /* size of the block */
} mk_hull;

#define MK_HULL_MAX_POINTS 4096  /* input points accepted by mk_hull_create */
/* Vertices of a resulting hull. Every accepted cloud fits (a hull's vertices
 * are input points), and 6V - 12 half-edges still fit the uint16_t indices. */
#define MK_HULL_MAX_VERTICES MK_HULL_MAX_POINTS

typedef struct mk_shape {
    mk_shape_type type;
    mk_real radius; /* rounding radius: sphere/capsule radius, Bullet-style margin otherwise */
    union {
        mk_vec3 half_extents;                                /* box core */
        struct { mk_real half_height; } capsule;             /* segment from -h to +h on z */
        struct { mk_real radius, half_height; } cylinder;    /* core cylinder on z */
        struct { mk_real radius, half_height; } cone;        /* apex +h, base disc at -h */
        const mk_hull *hull;                                  /* hull core */
        mk_plane plane;                                       /* half-space n.x <= offset */
    } u;
} mk_shape;

/* Constructors: validate, fill *out, return MK_OK or the reason for refusal. */
MK_API mk_status mk_shape_sphere(mk_real radius, mk_shape *out);
MK_API mk_status mk_shape_box(mk_vec3 half_extents, mk_real rounding, mk_shape *out);
MK_API mk_status mk_shape_capsule(mk_real radius, mk_real half_height, mk_shape *out);
MK_API mk_status mk_shape_cylinder(mk_real radius, mk_real half_height, mk_real rounding, mk_shape *out);
MK_API mk_status mk_shape_cone(mk_real radius, mk_real half_height, mk_real rounding, mk_shape *out);
MK_API mk_status mk_shape_hull(const mk_hull *hull, mk_real rounding, mk_shape *out);
/* `normal` must be unit length within MK_QUAT_TOLERANCE; it is renormalised.
 * |offset| <= MK_MAX_COORD, else MK_ERR_OUT_OF_RANGE. */
MK_API mk_status mk_shape_plane(mk_vec3 normal, mk_real offset, mk_shape *out);

/* Checks a shape however it was made. */
MK_API mk_status mk_shape_validate(const mk_shape *s);
MK_API const char *mk_shape_type_name(mk_shape_type t);

/* Farthest point of the whole solid (core + rounding) along `dir`, in the
 * shape's local frame. `dir` need not be unit; a zero dir gives the support
 * along +x. Planes have no finite support: the result is the point of the
 * plane nearest the origin when dir is along the normal, else non-finite. */
MK_API mk_vec3 mk_shape_support(const mk_shape *s, mk_vec3 dir);

/* World AABB of the shape at transform xf. Planes give infinite bounds except
 * along axes their normal is aligned with. */
MK_API mk_status mk_shape_aabb(const mk_shape *s, mk_transform xf, mk_aabb *out);

/* Quickhull of a point cloud. Duplicate points and points within a relative
 * tolerance of a face are merged; coplanar faces are merged into polygons.
 * Fewer than 4 points, or points that are all (nearly) collinear or coplanar,
 * give MK_ERR_DEGENERATE; non-finite points MK_ERR_NOT_FINITE; more than
 * MK_HULL_MAX_POINTS points MK_ERR_CAPACITY. `alloc` may be NULL.
 * The tolerance is 16 ulps of the cloud's size: tol = 16 * MK_REAL_EPSILON *
 * (ex + ey + ez), e the half-extents of the cloud's bounding box (recorded in
 * hull->tolerance). Vertices are input points (bit-exact); every input point
 * lies below every face plane, and every face's vertices on its plane, within
 * a few tol; faces are convex polygons within tol; no two adjacent faces are
 * coplanar within tol, except, in the float build, where merging them would
 * move a vertex lying a few tol off an edge. Construction runs in double in
 * both builds. Coordinates beyond the library's size limit give
 * MK_ERR_BAD_SIZE. On failure *out is NULL and nothing stays allocated.
 * Working memory comes from `alloc` (one block) and is freed. */
MK_API mk_status mk_hull_create(const mk_vec3 *points, int count, const mk_allocator *alloc, mk_hull **out);
/* Frees a hull made by mk_hull_create through its own allocator; NULL is a no-op. */
MK_API void mk_hull_destroy(mk_hull *hull);

/* Index of the hull vertex farthest along dir (hill climbing from `start`,
 * which may be any vertex index, e.g. the previous answer; -1 to start at the
 * best of the six axis-extreme vertices). */
MK_API int mk_hull_support_index(const mk_hull *hull, mk_vec3 dir, int start);

#ifdef __cplusplus
}
#endif

#endif

/* manifold_internal.h: the pieces mk_collide is built from.
 *
 * Everything here works in A's local frame: B's pose relative to A is an
 * mk_pair (gjk.h: x_A = r x_B + t). A manifold is built in three steps: a normal
 * (closed form, SAT or GJK), the support features of both cores along it
 * (mk_feat: a point, a segment or a polygon, each vertex and edge named by
 * its mk_feature), and clipping of the incident feature against the
 * reference one (mk_mf_clip). The candidates are then reduced to four
 * (mk_mf_reduce) and moved to world space by mk_collide. */
#ifndef MINKO_MANIFOLD_INTERNAL_H
#define MINKO_MANIFOLD_INTERNAL_H

#include "minko/manifold.h"
#include "closest.h"

/* Most vertices of a support feature (hull faces with more are decimated,
 * keeping the support vertex), and most clipped candidates: a polygon with
 * n vertices clipped by m side planes has at most n + m. */
#define MK_FEAT_MAX 32
#define MK_MF_MAX (2 * MK_FEAT_MAX)

/* Angle (radians, as its sine) within which a face counts as facing the
 * normal, and two segments count as parallel. A face tilted by less than
 * this is clipped as a face; the depths stay exact because each clipped point
 * is measured on its own. See the report in manifold.c for the choice. */
#define MK_MF_SIN_TOL MK_REAL(0.01)

/* The clip slop of each mk_manifold_mode (clip.c says why): the stable
 * IDs' 0.35 % of the reference side, or round-off only. */
#define MK_MF_SLOP_IDS MK_REAL(0.0035)
#define MK_MF_SLOP_EXACT (64 * MK_REAL_EPSILON)

/* A support feature of a core, in some frame. count 1: a point; 2: a
 * segment; >= 3: a convex polygon with outward unit `normal`. eid[i] names
 * the edge v[i] -> v[i + 1]. `exact` is 0 for polygons that sample a curved
 * rim (cylinder and cone caps), which lose to true faces as reference. */
typedef struct mk_feat {
    int count;
    int exact;
    mk_feature id;
    mk_vec3 normal;
    mk_vec3 v[MK_FEAT_MAX];
    mk_feature vid[MK_FEAT_MAX];
    mk_feature eid[MK_FEAT_MAX];
} mk_feat;

typedef struct mk_mf_point {
    mk_vec3 pa;       /* on A's surface, A's frame */
    mk_real depth;
    uint32_t features;
} mk_mf_point;

/* A manifold under construction, in A's frame. */
typedef struct mk_mf {
    mk_vec3 normal;   /* unit, from A towards B */
    mk_real margin;   /* candidates with depth < -margin are dropped */
    int cores_apart;  /* set before clipping: rounded cores apart clip without slop (clip.c) */
    mk_real slop;     /* clip slop, a fraction of the reference side: MK_MF_SLOP_IDS or MK_MF_SLOP_EXACT */
    int count;
    mk_mf_point p[MK_MF_MAX];
} mk_mf;

/* Appends a candidate if depth >= -margin and there is room. */
void mk_mf_add(mk_mf *m, mk_vec3 pa, mk_real depth, mk_feature fa, mk_feature fb);

/* Support feature of s's core along the unit direction d (local frame):
 * the face, edge or point of the core farthest along d. Polytopes and
 * smooth caps give their best-aligned face; capsules their segment. */
void mk_support_feature(const mk_shape *s, mk_vec3 d, mk_feat *out);
/* Moves a feature from B's frame into A's. */
void mk_feat_transform(mk_feat *f, const mk_pair *p);

/* Clips `inc` against the polygon or segment `ref` and appends the
 * candidates. ref_is_a says whose feature `ref` is; m->normal must already be
 * the contact normal, and a polygon reference must face it within
 * MK_MF_SIN_TOL. ra, rb are the rounding radii. */
void mk_mf_clip(mk_mf *m, const mk_feat *ref, int ref_is_a, const mk_feat *inc, mk_real ra, mk_real rb);

/* mk_mf_clip of two box cores of pair p (both shapes boxes) with box face
 * `face` of A (ref_is_a) or of B as the reference, against the incident
 * face of the other box along m->normal (set, a SAT face axis): the same
 * candidates and IDs, computed in the reference box's frame. */
void mk_mf_clip_boxes(mk_mf *m, const mk_pair *p, int ref_is_a, int face, mk_real ra, mk_real rb);

/* The manifold of two cores whose closest points are known: n (unit, A to B)
 * and the core witness points ca on A and cb on B (A's frame), with core
 * distance dist along n (< 0 when the cores overlap). Builds a face clip, a
 * parallel-segment clip or a single point, as the geometry calls for, and
 * records the reference face in `cache` (may be NULL) for the next frame. */
void mk_mf_from_closest(mk_mf *m, const mk_pair *p, mk_manifold_cache *cache, mk_vec3 n, mk_vec3 ca, mk_vec3 cb,
                        mk_real dist);
/* The same from a whole-shape answer (surface witnesses, signed distance);
 * nothing when the shapes are farther apart than the margin. */
void mk_mf_from_hit(mk_mf *m, const mk_pair *p, mk_manifold_cache *cache, mk_hit h);

/* Keeps at most MK_MANIFOLD_MAX_POINTS: the deepest, then those spanning the
 * largest area. */
void mk_mf_reduce(mk_mf *m);

/* The feature of s's core that contains the core point p (local frame),
 * with n the outward direction there. */
mk_feature mk_feature_at(const mk_shape *s, mk_vec3 p, mk_vec3 n);

/* Face `face` of a hull as a polygon (see clip.c), and the feature index of
 * a hull half-edge (the lower of the pair). */
void mk_hull_face(const mk_hull *h, int face, int start, mk_feat *f);
int mk_hull_edge_id(const mk_hull *h, int half_edge);

/* Face 2 * axis + positive of a box core as a polygon. */
void mk_box_face(const mk_shape *s, int axis, int positive, mk_feat *f);

/* Box edge named by two corners that differ in exactly one coordinate. */
mk_feature mk_box_edge(int corner_i, int corner_j);

#endif

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
#include "polytope.h"

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
/* The reduction's choice among n > 4 candidates given by their coordinates
 * (x, y) in the contact plane (any orthonormal pair whose cross product is
 * the normal) and their depths: the indices kept, deepest first, in k;
 * returns how many (2 to 4). */
int mk_mf_pick4(int n, const mk_real *x, const mk_real *y, const mk_real *depth, int k[4]);

/* The feature of s's core that contains the core point p (local frame),
 * with n the outward direction there. */
mk_feature mk_feature_at(const mk_shape *s, mk_vec3 p, mk_vec3 n);

/* Face `face` of a hull as a polygon (see clip.c), and the feature index of
 * a hull half-edge (the lower of the pair). */
void mk_hull_face(const mk_hull *h, int face, int start, mk_feat *f);
int mk_hull_edge_id(const mk_hull *h, int half_edge);

/* Face 2 * axis + positive of a box core as a polygon. */
void mk_box_face(const mk_shape *s, int axis, int positive, mk_feat *f);

/* Per box face 2 * axis + positive: its corners counter-clockwise seen
 * from outside, and the box edges from each corner to the next. */
extern const unsigned char mk_box_face_corner_[6][4];
extern const unsigned char mk_box_face_edge_[6][4];

/* Box edge named by two corners that differ in exactly one coordinate. */
mk_feature mk_box_edge(int corner_i, int corner_j);

/* Corner `bits` (zyx, set = +extent) of the box of half-extents h, and
 * the two ends of box edge `id` (minko/manifold.h numbering). */
/* c ? a : b for c = 0 or 1, in arithmetic: which candidate or axis wins
 * is data the branch predictor cannot learn. */
MK_ALWAYS_INLINE int mk_sel_int(int c, int a, int b) { return b ^ ((a ^ b) & -c); }

/* The smallest component of v (a box's thinnest half extent). */
static inline mk_real mk_v3_min_comp(mk_vec3 v) { return mk_min(v.x, mk_min(v.y, v.z)); }

/* How far below the SAT depth a built point may fall and still realise it
 * (box_box.c, manifold.c): rounding of the pose and the two shapes' sizes.
 * A polytope's size is its rounding plus its farthest extent. */
static inline mk_real mk_mf_polytope_size(const mk_shape *s)
{
    return s->radius + (s->type == MK_SHAPE_BOX ? mk_v3_max_abs(s->u.half_extents) : s->u.hull->outer_radius);
}

static inline mk_real mk_mf_realise_tol(const mk_pair *p)
{
    return 256 * MK_REAL_EPSILON * (mk_v3_max_abs(p->t) + mk_mf_polytope_size(p->a) + mk_mf_polytope_size(p->b));
}

static inline mk_vec3 mk_box_corner(mk_vec3 h, int bits)
{
    return mk_v3(bits & 1 ? h.x : -h.x, bits & 2 ? h.y : -h.y, bits & 4 ? h.z : -h.z);
}
static inline void mk_box_edge_ends(mk_vec3 h, int id, mk_vec3 *e0, mk_vec3 *e1)
{
    int axis = id / 4, lo = axis == 0 ? 1 : 0, hi = axis == 2 ? 1 : 2;
    int bits = ((id & 1) << lo) | (((id >> 1) & 1) << hi);
    *e0 = mk_box_corner(h, bits);
    *e1 = mk_box_corner(h, bits | 1 << axis);
}

/* The ends (the core's own frame) and the feature of the edge named by
 * half-edge e of polytope s: a box enters SAT as its mk_box_hull view,
 * whose half-edges map to box edge IDs. */
static inline mk_feature mk_polytope_edge(const mk_shape *s, int e, mk_vec3 *e0, mk_vec3 *e1)
{
    if (s->type == MK_SHAPE_BOX) {
        int id = mk_box_hull_edge_id(e);
        mk_box_edge_ends(s->u.half_extents, id, e0, e1);
        return MK_FEATURE(MK_FEATURE_EDGE, id);
    } else {
        const mk_hull *h = s->u.hull;
        *e0 = h->vertices[h->edges[e].origin];
        *e1 = h->vertices[h->edges[h->edges[e].twin].origin];
        return MK_FEATURE(MK_FEATURE_EDGE, mk_hull_edge_id(h, e));
    }
}

/* The one contact of an edge-pair SAT axis of two polytopes (box_box.c for
 * two boxes, manifold.c's polytopes() otherwise): the closest points of
 * half-edge ea of p->a and half-edge eb of p->b. sep is SAT's separation
 * along the axis, rr the sum of the rounding radii. Returns the depth
 * (radii included); *qa is the point on A's core edge (A's frame; the
 * surface point is qa + ra n), *fa and *fb the two edges' features.
 * Inline: the box-box pass keeps its frame in registers. */
static inline mk_real mk_mf_edge_contact(const mk_pair *p, int ea, int eb, mk_real sep, mk_real rr, mk_vec3 *qa, mk_feature *fa,
                                         mk_feature *fb)
{
    mk_vec3 a0, a1, b0, b1;
    mk_real s, t;
    *fa = mk_polytope_edge(p->a, ea, &a0, &a1);
    *fb = mk_polytope_edge(p->b, eb, &b0, &b1);
    b0 = mk_v3_add(mk_mat3_mul_v3(p->r, b0), p->t);
    b1 = mk_v3_add(mk_mat3_mul_v3(p->r, b1), p->t);
    mk_segment_segment(a0, a1, b0, b1, &s, &t);
    *qa = mk_v3_lerp(a0, a1, s);
    /* Apart, the edges' closest points are a gap only if neither end clamped. */
    if (sep > 0) sep = mk_v3_dist(*qa, mk_v3_lerp(b0, b1, t));
    return rr - sep;
}

/* Face/edge hysteresis of box and hull pairs (mk_sat_options.prefer; the
 * measurements are in manifold.c): the band is MK_MF_PREFER_REL of the
 * depth plus MK_MF_PREFER_ABS of the smaller shape's smallest half extent
 * (inner radius for a hull). */
#define MK_MF_PREFER_REL MK_REAL(0.05)
#define MK_MF_PREFER_ABS MK_REAL(0.005)

/* mk_manifold_cache.axis above this: the pair was apart beyond the margin
 * last frame along the SAT axis of kind axis - MK_MF_APART_HINT, whose
 * indices a and b + 1 are kept in cache->reference and cache->face (which
 * a polytope pair does not otherwise carry across frames). A pair that
 * stays apart then costs one axis (mk_sat_options.first; two boxes:
 * box_box.c's stay_apart). */
#define MK_MF_APART_HINT 4

/* ---- two boxes (box_box.c) ---- */

/* Most candidates of a box face clip (4 corners, at most one more per side
 * pass; room to spare for round-off). */
#define MK_BB_CLIP_MAX 16

/* A candidate of a box-face clip: the incident core point q in the
 * reference box's frame, its height over the reference face (core
 * separation), its depth (radii included) and its features (A's low). */
typedef struct mk_bb_point {
    mk_vec3 q;
    mk_real height, depth;
    uint32_t features;
} mk_bb_point;

/* The face clip of two box cores of pair p (both shapes boxes) with box
 * face `face` of A (ref_is_a) or of B as the reference and the incident
 * face of the other box, done in the reference face's 2D coordinates: the
 * candidates mk_mf_clip would give for mk_box_face against the
 * mk_support_feature of the other box along the face's normal, with the
 * same IDs, in the same order, clip slop `slop` (a fraction of the
 * reference side), those deeper than -margin; with `reduce`, the four
 * mk_mf_pick4 keeps in the face's coordinates. Returns the count. */
int mk_box_box_clip(const mk_pair *p, int ref_is_a, int face, mk_real slop, mk_real margin, int reduce, mk_bb_point *out);

/* mk_collide_pose of two boxes after its checks, in one pass: last
 * frame's separating axis, the bounding balls, the relative pose, the 15
 * SAT axes with the face/edge hysteresis, then for a face axis
 * mk_box_box_clip reduced to four, for an edge pair the edges' closest
 * points; the result written straight into *out, the cache updated. When
 * rounded cores are apart and SAT's points do not realise their distance,
 * the answer is mk_collide_gjk_'s. */
mk_status mk_box_box_collide(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin,
                             mk_manifold_cache *cache, mk_manifold *out);

/* mk_collide_pose's general GJK/EPA path for a checked pair (manifold.c);
 * MK_ERR_UNSUPPORTED in a build without GJK. */
mk_status mk_collide_gjk_(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin,
                          mk_manifold_cache *cache, mk_manifold *out);

#endif

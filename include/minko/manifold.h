/* minko/manifold.h: contact manifolds with feature IDs.
 *
 * Contract. mk_collide() returns, for one pair of shapes, the whole contact
 * manifold in one call (no point-per-frame accumulation): up to
 * MK_MANIFOLD_MAX_POINTS points sharing one unit normal that points from A
 * towards B (world frame); per point the depth (> 0 penetration, 0 touching,
 * < 0 separation), the witness points on both surfaces in world coordinates
 * and in each body's local frame, with point_b = point_a - depth * normal, and
 * the pair of features (one per shape) that makes the point. Points with
 * depth >= -margin are reported; those with depth < 0 carry
 * MK_CONTACT_SPECULATIVE. When more than four candidate points exist (clipped
 * faces, cylinder rims) the deepest is kept first, then the points that
 * maximise the contact area; the choice favours earlier candidates by a small
 * margin so it does not flicker between frames. Feature IDs are stable while
 * the same features touch, so a host can key its warm-start cache on them
 * (minko/contact_cache.h). An optional caller-owned mk_manifold_cache per
 * pair (zero-initialised = cold) carries the previous frame's choices: for
 * boxes and hulls the kind of separating axis (face of A, face of B, edge
 * pair), with faces preferred: an edge pair is taken warm only when it
 * beats the face by a band of 5 % of the depth plus 0.5 % of the smaller
 * shape's size (by half of it when last frame was an edge pair), as ODE's
 * dBoxBox and Box2D favour faces; for the other pairs the reference face,
 * kept while it faces the normal within the tolerance, plus the GJK
 * simplex. The cache's `mode`, set by the host and never written by
 * mk_collide, chooses what else a warm frame favours. MK_MANIFOLD_STABLE_IDS
 * (0, the default) promises stable feature IDs: a box or hull pair keeps
 * last frame's face kind (A's or B's face) while it stays within that band
 * of the better face, and an incident vertex up to 0.35 % of the side
 * outside the reference face is kept, not clipped, so a rocking stack of
 * equal boxes keeps its normal, its four points and its IDs; the price is
 * that warm frames may report the kept face's depth and normal instead of
 * the minimum (deeper by at most the band, tilted by the boxes' relative
 * tilt) and points up to that strip outside the face. Hosts that match
 * warm-start impulses by feature ID alone (minko/contact_cache.h,
 * demos/solver_demo) need it. MK_MANIFOLD_BEST_FACE promises the
 * minimum-penetration face: the better face (ties to A's) wins every frame
 * and its exact normal is reported, and incident vertices outside the
 * reference face are clipped beyond round-off (64 ulps of the side); equal
 * boxes stacked and rocking then swap the reference face between them as
 * the tilt changes sign, and every feature ID with it. Hosts whose solver
 * is sensitive to the normal's tilt and can match contacts by position too
 * (Bullet's persistent manifold) should pick it. A cold call (no cache, or a new
 * contact) is exact in both modes. The cache's `flags`, also the host's:
 * MK_MANIFOLD_TOUCHING_ONLY drops the speculative points: the manifold is
 * the one without the flag less its points of depth < 0 (and two sharp
 * boxes that SAT finds apart report none, even a point at depth 0 by
 * round-off), while the margin still decides how far apart a pair keeps
 * its warm state (the preferred axis kind) instead of restarting cold. For
 * hosts that use touching points only (Bullet's box-box pairs), two sharp
 * boxes apart by less than the margin then skip the clip and GJK.
 * Bad input (NULL, NaN/Inf, non-unit rotations, invalid shapes, a negative
 * margin, an unknown cache mode or flag) returns a status and leaves *out
 * untouched; plane-plane pairs are MK_ERR_UNSUPPORTED. Nothing allocates;
 * every query runs in A's local frame. Methods: closed forms for sphere,
 * capsule and box-capsule pairs and for anything against a plane; SAT
 * (src/sat.h) with reference/incident face clipping for box and hull pairs,
 * exact for rounded ones too: when their cores are apart, SAT's separation
 * is only a lower bound of the core distance, so unless the clipped points
 * realise it GJK gives the exact distance (two rounded cubes edge to edge;
 * a build without GJK keeps the bound);
 * the exact GJK/EPA normal and closest points for the rest (cylinders,
 * cones, spheres and capsules against hulls), whose support faces are then
 * clipped. A build without SAT (MK_WITHOUT) takes GJK/EPA for box and hull
 * pairs too; one without GJK or EPA returns MK_ERR_UNSUPPORTED for the pairs
 * that need them. Box and hull pairs whose bounding balls are farther apart
 * than the margin return before anything else. Complexity per call: O(1)
 * for the closed forms and for two boxes (src/box_box.c: one pass, a pair
 * apart along last frame's separating axis tests only that axis; per
 * mk_collide_pose about 0.8 of the time of ODE's dBoxBox in the same run
 * on tilted stacked boxes and on random overlaps, 0.53 on separated boxes
 * whose bounding boxes overlap, demos/bench_contacts (2.9k, 2.2k and 0.2k
 * instructions under callgrind); box_box.c says where the time goes);
 * for hulls SAT's O(F_A S_B + F_B S_A +
 * E_A E_B) (src/sat.h) plus O(n + m) clipping of faces with n and m (at most
 * 32) vertices; GJK/EPA pairs are bounded by their iteration caps.
 *
 * Feature indices per shape type: box vertices 0..7 are the corner bits zyx
 * (bit set = +extent), box edges 0..11 are 4*axis + the corner bits of the
 * other two axes (bit 0 = the lower-numbered axis), box faces 0..5 are
 * 2*axis + (1 for the + side); hull vertices and faces are the mk_hull
 * indices, a hull edge is the lower of its two half-edge indices; a sphere is
 * vertex 0; capsule ends are vertices 0 (-h) and 1 (+h), its segment edge 0;
 * cylinder and cone: cap faces 0 (-h) and 1 (+h), side face 2; caps are
 * clipped as octagons whose corners, the fixed rim points of cap k at local
 * angles 0, 45, ..., 315 degrees from +x, are vertices 8k..8k+7 and whose
 * chords from point j to j+1 are edges 2+8k+j; the rim of cap k, i.e. its
 * exact support point when the cap is tilted, is edge k; the cone apex is
 * vertex 16; a plane is face 0.
 */
#ifndef MINKO_MANIFOLD_H
#define MINKO_MANIFOLD_H

#include "minko/distance.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mk_feature_type {
    MK_FEATURE_VERTEX = 0,
    MK_FEATURE_EDGE = 1,
    MK_FEATURE_FACE = 2
} mk_feature_type;

/* A feature of one shape: type in the top 2 bits, index in the low 14. */
typedef uint16_t mk_feature;
#define MK_FEATURE_INDEX_BITS 14
#define MK_FEATURE_MAX_INDEX ((1 << MK_FEATURE_INDEX_BITS) - 1)
#define MK_FEATURE(type, index) ((mk_feature)(((unsigned)(type) << MK_FEATURE_INDEX_BITS) | ((unsigned)(index) & MK_FEATURE_MAX_INDEX)))
#define MK_FEATURE_TYPE(f) ((mk_feature_type)((unsigned)(f) >> MK_FEATURE_INDEX_BITS))
#define MK_FEATURE_GET_INDEX(f) ((int)((unsigned)(f) & MK_FEATURE_MAX_INDEX))
/* The pair (feature of A, feature of B) as one 32-bit value: A low, B high. */
#define MK_FEATURE_PAIR(fa, fb) ((uint32_t)(fa) | ((uint32_t)(fb) << 16))
#define MK_FEATURE_PAIR_A(p) ((mk_feature)((p) & 0xFFFFu))
#define MK_FEATURE_PAIR_B(p) ((mk_feature)((p) >> 16))

#define MK_MANIFOLD_MAX_POINTS 4
/* mk_contact_point.flags */
#define MK_CONTACT_SPECULATIVE 1u

typedef struct mk_contact_point {
    mk_vec3 point_a;    /* on A's surface, world */
    mk_vec3 point_b;    /* on B's surface, world: point_a - depth * normal */
    mk_vec3 local_a;    /* point_a in A's local frame */
    mk_vec3 local_b;    /* point_b in B's local frame */
    mk_real depth;      /* > 0 penetration, < 0 separation */
    uint32_t features;  /* MK_FEATURE_PAIR(feature of A, feature of B) */
    uint32_t flags;     /* MK_CONTACT_SPECULATIVE when depth < 0 */
} mk_contact_point;

typedef struct mk_manifold {
    mk_vec3 normal;     /* unit, world, from A towards B (undefined when count == 0) */
    int count;          /* 0 .. MK_MANIFOLD_MAX_POINTS */
    mk_contact_point points[MK_MANIFOLD_MAX_POINTS];
} mk_manifold;

/* mk_manifold_cache.mode: what a warm frame favours (see the contract). */
typedef enum mk_manifold_mode {
    MK_MANIFOLD_STABLE_IDS = 0, /* stable feature IDs for ID-only warm starting (default) */
    MK_MANIFOLD_BEST_FACE = 1   /* the minimum-penetration face every frame, points clipped to it */
} mk_manifold_mode;

/* mk_manifold_cache.flags: set by the host (see the contract). */
#define MK_MANIFOLD_TOUCHING_ONLY 1u /* no speculative points; the margin still bounds the warm state */

/* Per-pair state carried from one frame to the next. Zero it (or pass NULL)
 * for a cold start, then set `mode` and `flags` if the defaults do not suit;
 * keep one per body pair and pass the shapes in the same order every frame.
 * To restart a pair cold, zero it and set the mode and flags again. */
typedef struct mk_manifold_cache {
    mk_gjk_cache gjk;   /* GJK warm start of pairs without a closed form */
    int reference;      /* internal: 1 / 2 when the last manifold was clipped against a face of A / B */
    mk_feature face;    /* internal: that face */
    int axis;           /* internal: kind of the last SAT axis of a box or hull pair, 0 = none; for a pair
                         * that was apart, its separating axis (with reference and face) */
    mk_manifold_mode mode; /* set by the host, read only by mk_collide */
    unsigned flags;        /* MK_MANIFOLD_* flags, set by the host, read only by mk_collide */
} mk_manifold_cache;

/* The contact manifold of shapes a (pose xa) and b (pose xb). `margin` >= 0:
 * also report points separated by up to this distance (speculative). */
MK_API mk_status mk_collide(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb,
                            mk_real margin, mk_manifold_cache *cache, mk_manifold *out);
/* The same for poses checked once by mk_pose_from_transform /
 * mk_pose_from_matrix (minko/math3d.h): no quaternion check or conversion per
 * call; an unchecked pose gives MK_ERR_UNCHECKED_POSE. mk_collide is this
 * after checking and converting its two transforms. */
MK_API mk_status mk_collide_pose(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb,
                                 mk_real margin, mk_manifold_cache *cache, mk_manifold *out);

/* Unreduced candidates. mk_collide_pose_points() is mk_collide_pose()
 * without the reduction to four points: it writes every candidate the pair
 * routine built (the clipped polygon's points, a cylinder rim's, ...), at
 * most MK_COLLIDE_MAX_CANDIDATES, in the order they were built, into the
 * caller's buffer `points` of `capacity` entries, with *count and *normal;
 * each point follows mk_collide's conventions (world and local witnesses,
 * depth, features, flags), and the points mk_collide_pose would keep are
 * among them, bit for bit, given the same cache state. It is for hosts that
 * reduce by their own rule, e.g. Bullet's btPersistentManifold, which keeps
 * four of the points it is fed by its own area rule as Bullet's polyhedral
 * clipper does. Two boxes are the exception: box_box.c reduces while it
 * clips, so a box-box pair returns the same (at most four) points as
 * mk_collide_pose, as Bullet's own dBoxBox2 culls to four itself. A buffer
 * too small for the candidates is MK_ERR_CAPACITY, never a silent cut: then
 * *count is the number needed, the points and the normal are untouched, and
 * the cache has advanced as for a successful call. Validation and the cache
 * are mk_collide_pose's; a NULL buffer, count or normal is MK_ERR_NULL, a
 * negative capacity MK_ERR_BAD_ARGUMENT. Nothing allocates; the cost is
 * mk_collide_pose's less the reduction. */
#define MK_COLLIDE_MAX_CANDIDATES 64
MK_API mk_status mk_collide_pose_points(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb,
                                        mk_real margin, mk_manifold_cache *cache, mk_vec3 *normal,
                                        mk_contact_point *points, int capacity, int *count);

#ifdef __cplusplus
}
#endif

#endif

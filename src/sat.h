/* sat.h: separating-axis test for convex polytopes (internal).
 *
 * Contract. mk_sat() finds, for two polytope cores A and B (mk_hull, or a box
 * through polytope.h's view), the axis of largest separation among the face
 * normals of A, the face normals of B and the cross products of the edge
 * pairs that form faces of the Minkowski difference A - B. That largest
 * separation `best` is exact: when it is <= 0 the cores overlap and -best is
 * their penetration depth, `normal` the direction (from A towards B) in which
 * B must move by that depth to touch; when it is > 0 the cores are apart and
 * best is a lower bound of their distance (GJK gives the distance itself).
 * Everything is in A's frame: B's points map into it by x_A = R x_B + t, R a
 * rotation. Rounding radii are not included: the solids' separation is
 * best - ra - rb. The result names the features of the reported axis (a face
 * index, or the two half-edge indices) for the manifold builder to clip and
 * key its IDs on; for a box view the half-edges map to box edge IDs through
 * mk_box_hull_edge_id. Options: stop_above ends the search as soon as an
 * axis separates by more than it (0 for a yes/no overlap test, a speculative
 * margin for contact generation, MK_REAL_MAX to test every axis); prefer is
 * the face/edge hysteresis hook, see mk_sat_options. No allocation, no
 * global state. Complexity: O(F_A S_B + F_B S_A) for the faces, S the cost
 * of a support query (a scan up to MK_HULL_COLD_SCAN_MAX vertices without
 * a hint, MK_HULL_SCAN_MAX with one, a hill climb above), plus, for the
 * edges, a walk over A's Gauss map along each edge arc of B that visits
 * only the few vertices of A whose regions the arc crosses and tests their
 * edges with the Gauss-map (Minkowski face) test of
 * Gregorius (GDC 2013); an arc whose signs are too close to call (parallel
 * faces) is instead tested against all of A's edges, O(E_A). Faces of
 * either and edges of B whose separation is provably below the best so far
 * (bounds from a ball inside each core and a few of its vertices) skip
 * their support query or walk: O(F_A + F_B + E_B) cheap tests, then the
 * queries above for the few axes that survive. Measured (demos/bench_sat
 * --quick --family F under valgrind --tool=callgrind
 * --toggle-collect=mk_sat[_box_box], instructions per call, separated and
 * penetrating cases together): box-box 0.73k by mk_sat_box_box (0.81k at
 * the start of session 10, 0.83k in session 6, 1.0k in session 3; see
 * sat_box.h), 9.7k by mk_sat on box views; a box and a 32-point hull 30k; hulls of
 * 8/32/128 points 13.5k/42k/129k (session 3, before the pruning: 17k; 70k;
 * 28k/161k/718k). Minko's GJK + EPA answers hull pairs
 * faster (see the benchmark); SAT's value there is its feature output and
 * hysteresis.
 *
 * Not kept (session 10): the depth of overlapping cores by SAT instead of
 * EPA, every axis with no pruning, witnesses from the answer's feature pair
 * (EPA where that pair is not unique). Measured on demos/bench_narrow's
 * penetrating rows (minko.pose; callgrind instructions per mk_distance_pose,
 * GJK included): (1) for hulls of <= 32 vertices, every face against the
 * other's vertex rows and every edge pair through the Gauss-map test four
 * at a time: hull_hull_8 12.3k -> 49.9k instructions, 1082 -> 3941 ns (one
 * run each, same window, load 6; 324 edge pairs at ~60 scalar instructions
 * each: -O2 packs only the products);
 * (2) a box against a hull in the box's frame, where the box's Gauss map
 * lies on the three coordinate great circles, so a hull edge's arc meets at
 * most one box edge per axis, found from the crossing point in O(1)
 * (O(V + F + E) in all): hull_box 17.6k -> 22.2k instructions, 1726 ->
 * 4611 ns (same-run medians, load 8). The 90 edges x 3 axes of sign tests,
 * 60 hull faces and ~37 crossings of a 32-point hull cost 18k instructions
 * against EPA's 13.6k, at a lower rate per cycle. Either would need the
 * sign tests packed over rows of face normals to pay. The box-hull code is on
 * branch hull-sat-depth-experiment (not merged).
 */
#ifndef MINKO_SAT_H
#define MINKO_SAT_H

#include "minko/shape.h"

typedef enum mk_sat_kind {
    MK_SAT_NONE = 0,
    MK_SAT_FACE_A,  /* a face normal of A */
    MK_SAT_FACE_B,  /* a face normal of B (negated: from A towards B) */
    MK_SAT_EDGES    /* the cross product of an edge of A and an edge of B */
} mk_sat_kind;

typedef struct mk_sat_options {
    mk_real stop_above; /* stop once an axis separates by more than this */
    /* Face preference and hysteresis, with prefer set (usually the previous
     * frame's kind; MK_SAT_NONE = none, the exact best axis). Let band =
     * prefer_rel * |best| + prefer_abs. The face kind is the better face's,
     * or, with hold_face set (the default), the preferred face kind's if its
     * separation is within band of it (MK_MANIFOLD_STABLE_IDS; without it,
     * MK_MANIFOLD_BEST_FACE, the better face always wins, ties to A's); an
     * edge pair is reported only if it separates by more than that face
     * plus band (band / 2 when prefer is MK_SAT_EDGES), as dBoxBox and Box2D
     * favour faces, so nearly parallel boxes clip face to face and an axis
     * does not flip on rounding. `best` itself is never biased; the
     * reported separation is below it by at most band. */
    mk_sat_kind prefer;
    mk_real prefer_rel, prefer_abs;
    int hold_face;
    /* An axis to test before all others, named as mk_sat_result names one
     * (kind, a, b), usually the one that separated the pair last frame:
     * when it separates by more than stop_above the search ends there and
     * reports it, so a pair that stays apart costs one axis instead of up
     * to every face (a hull pair of 32 points apart: 1.4k instructions per
     * mk_collide instead of 10k); otherwise the answer is exactly the one
     * without it. MK_SAT_NONE (the default): none. mk_sat only:
     * mk_sat_box_box ignores it, as two boxes test last frame's axis from
     * their world poses before any relative pose is built (box_box.c's
     * stay_apart). */
    mk_sat_kind first;
    int first_a, first_b;
} mk_sat_options;

typedef struct mk_sat_result {
    mk_sat_kind kind;   /* the axis reported */
    int a, b;           /* FACE_A: face of A, b = -1; FACE_B: a = -1, face of B; EDGES: half-edge of A, of B */
    mk_real separation; /* along the reported axis */
    mk_vec3 normal;     /* unit, A's frame, from A towards B */
    mk_real best;       /* largest separation over the axes tested */
    int complete;       /* 1: every axis was tested; 0: stopped at one separating by more than stop_above */
} mk_sat_result;

/* Edge pairs closer to parallel than this (as the sine of their angle) are
 * skipped: their cross product has no reliable direction, and the faces on
 * either side of such a sliver face of A - B bound it to within the angle
 * times the edge length. */
#define MK_SAT_PARALLEL (MK_REAL(1e3) * MK_REAL_EPSILON)

/* Every axis, no hysteresis. */
mk_sat_options mk_sat_defaults(void);

/* The kind of the best axis overall (fills out->best and out->complete;
 * the caller the rest); ties go to A's faces, then B's, then edges: face
 * contacts are the stabler. With a preference (a warm frame) the choice is
 * biased as mk_sat_options says: first the face kind (with hold_face, last
 * frame's kept while within the band of the better face), then edges only
 * if they beat that face by the band, or by half of it when last frame was
 * already an edge pair. The two thresholds make a hysteresis loop: a stack
 * of nearly parallel boxes, whose edge pairs tie with the face to
 * round-off, stays on its face clip, and a genuine edge contact does not
 * flicker either. Holding the face kind keeps a rocking stack's IDs but
 * tilts its normal by the boxes' relative tilt (about 1e-3 rad in a
 * settling tower); Bullet's solver, fed that normal, let
 * demos/bullet_scenes' 10-box tower drift 0.72 m against 0.37 m native
 * (0.27 m with the better face and the exact clip of MK_MANIFOLD_BEST_FACE),
 * hence the choice per pair. */
static inline mk_sat_kind mk_sat_choose(mk_real sa, mk_real sb, mk_real se, int edge_found, int stopped, const mk_sat_options *opt,
                                        mk_sat_result *out)
{
    /* A select, not a branch: which face kind wins is data. */
    mk_real ps = mk_max(sb, sa);
    mk_sat_kind kind = (mk_sat_kind)(MK_SAT_FACE_A + (sb > sa));
    out->best = mk_max(ps, se);
    out->complete = !stopped;
    if (stopped || opt->prefer == MK_SAT_NONE) {
        if (se > ps) kind = MK_SAT_EDGES;
    } else {
        mk_real band = opt->prefer_rel * mk_fabs_(out->best) + opt->prefer_abs, fs = opt->prefer == MK_SAT_FACE_A ? sa : sb;
        if (opt->hold_face && opt->prefer != MK_SAT_EDGES && opt->prefer != kind && fs >= ps - band) ps = fs, kind = opt->prefer;
        if (edge_found && se > ps + (opt->prefer == MK_SAT_EDGES ? band / 2 : band)) kind = MK_SAT_EDGES;
    }
    return kind;
}


/* SAT of A (own frame) and B (x_A = R x_B + t). */
void mk_sat(const mk_hull *a, const mk_hull *b, const mk_mat3 *R, mk_vec3 t, const mk_sat_options *opt, mk_sat_result *out);

/* The same for two box cores of half-extents ha and hb, by the 15 axes in
 * closed form (about 20 times fewer instructions than mk_sat on box views).
 * The answer is mk_sat's on mk_box_hull views of the boxes, indices included
 * (edges as the lower half-edge of the box view); opt->first is not read
 * (see mk_sat_options). */
void mk_sat_box_box(mk_vec3 ha, mk_vec3 hb, const mk_mat3 *R, mk_vec3 t, const mk_sat_options *opt, mk_sat_result *out);

#endif

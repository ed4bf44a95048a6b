/* epa.h: expanding polytope algorithm for overlapping cores (internal).
 *
 * Starts from GJK's final simplex (which holds the origin, possibly on its
 * boundary when the shapes touch), blows it up to a tetrahedron, then grows
 * a convex polytope inside the CSO towards the boundary nearest the origin:
 * each step adds the support point along the nearest face's normal, removes
 * every face that point sees and closes the hole with a fan over the
 * silhouette, so the polytope stays convex. Fixed capacity, all on the
 * stack: no heap. Stops on a repeated support vertex (polytopes), on a gap
 * below tolerance, on capacity, or on a defect (a degenerate or inverted new
 * face, an unclosed silhouette); it then answers with the best face found
 * before the defect, never NaN. A touching pair gives depth 0 with that
 * face's normal. Complexity: O(k * F) for k iterations over at most F faces
 * (linear scans; F <= MK_EPA_MAX_FACES), plus one support per iteration.
 * Measured (valgrind --tool=callgrind --toggle-collect=mk_distance_pose on
 * demos/bench_narrow --inproc --variant penetrating --backend minko.pose --n
 * 100 --reps 1): EPA costs 9.1k / 16.3k / 25.9k instructions per query on
 * hulls of 8 / 32 / 128 points and 12.5k on a 32-point hull against a box
 * (GJK before it 2.5k / 5.6k / 8.4k / 3.5k) over 6.5 / 9.2 / 12.9 / 8.4
 * iterations; an expansion costs ~900 of them, the two supports 100 (scans, 8
 * points) to ~450 (climbs, 128). Session 9: hulls of up to 32 vertices are
 * scanned, without hints (hull_support.h): the supports of hull_32 cost 7.2k
 * of EPA's 18.6k instructions per query, more than the climbs did, but the
 * query is 27 % faster in wall time (no mispredicted climb steps); the same
 * command gives EPA 9.1k / 18.6k / 26.2k / 13.6k, GJK 2.7k / 5.3k / 5.8k /
 * 3.4k, expansion 4.9k / 7.6k / 11.4k / 6.8k. One-off experiments (session 7, probes not
 * kept): the count is what it takes to lift every face below the depth, not
 * to find the answer's face: given that face's three vertices right after the
 * tetrahedron (from a first run), EPA still needs 5.9 / 7.8 / 11.0 / 7.3
 * iterations (the injected vertices counted), so adding a guessed feature's
 * exact axis or vertices can save at most 10-15 %, and a local guess (the
 * face around the support vertex best aligned with the normal) is right only
 * one to three iterations before the end (most hull-hull answers are edge
 * pairs). Not kept either: a polytope without adjacency (a scan of every face
 * for visibility, the rim by edge matching; +1 % instructions, slower on 32
 * and 128 points); SAT as the certificate, even given the exact depth as its
 * pruning floor (49k instructions against 53k unseeded on hull_32; the whole
 * GJK + EPA query is 22.5k). Session 10, not kept: the exact depth by SAT
 * instead of EPA on small hulls and on box-hull pairs: 2.7-3.6 times slower
 * (sat.h). Nor the nearest-face search as four lanes over a row of face
 * distances (hull_support.h's scan): instructions -0.3 %, time within noise
 * (-3 % to +11 % per row, three alternations at load 9-10).
 */
#ifndef MINKO_EPA_H
#define MINKO_EPA_H

#include "gjk.h"

/* Bullet and Jolt use the same capacity. Polytope pairs converge in a
 * handful of vertices; round CSOs (cylinders, cones) use it up, and their
 * error falls with its square. Stack use is about 120 bytes a vertex
 * (15 KB at 128); a build may lower it with -DMK_EPA_MAX_VERTICES=n (n >= 8). */
#ifndef MK_EPA_MAX_VERTICES
#  define MK_EPA_MAX_VERTICES 128
#endif
#define MK_EPA_MAX_FACES (2 * MK_EPA_MAX_VERTICES)

typedef struct mk_epa_result {
    mk_cso_vertex face[3]; /* the polytope face nearest the origin */
    mk_real l[3];          /* barycentric coordinates of the origin's projection on it */
    mk_vec3 normal;        /* its unit outward normal: from A towards B */
    mk_real depth;         /* its distance from the origin: a lower bound on the core penetration depth */
    mk_real separation;    /* sep(normal) from the support functions (gjk.h): minus the core depth along
                            * normal, exact to rounding when normal is the optimum */
    int iterations;
    mk_solve_state state;
} mk_epa_result;

/* `s` is GJK's final simplex of an overlap (origin inside or on it), `scale`
 * GJK's scale. Returns 0 on success, -1 if no tetrahedron with volume could be
 * built around the origin (then *out holds a face of the simplex, depth 0). */
int mk_epa(const mk_pair *p, const mk_simplex *s, mk_real scale, mk_epa_result *out);

#endif

/* polish.h: exact signed distance from the closest features of a final simplex (internal).
 *
 * GJK and EPA end with a few CSO vertices whose support indices name the
 * closest features (vertex-face, edge-edge, vertex-edge, vertex-vertex), but
 * the distance they carry has gone through barycentric solves and face
 * normals of rounded differences. The signed distance of two convex bodies
 * is max over unit n of sep(n) (mk_pair_separation), and every sep(n) is a
 * lower bound, so we rebuild the candidate normals from the original feature
 * geometry (a hull's stored face plane, a box axis, the cross product of two
 * original edges, the perpendicular from a vertex to an edge) and keep the
 * best. A wrong candidate can only lose; the right one is exact to a few
 * ulps of the shapes' size. Complexity: O(1) candidates (at most a few dozen
 * for a 4-vertex simplex), two supports each; finding a hull face containing
 * three vertices walks the faces around one of them.
 */
#ifndef MINKO_POLISH_H
#define MINKO_POLISH_H

#include "gjk.h"

/* On entry *normal is the solver's unit normal (A towards B) and sep its
 * separation; it orients the candidates and stays the answer unless a feature
 * candidate separates better. Returns the best separation; *normal is its normal. */
mk_real mk_polish(const mk_pair *p, const mk_cso_vertex *v, int n, mk_real sep, mk_vec3 *normal);

/* Witness points a (on A's core) and b (on B's core) consistent with a
 * distance d along the unit normal n: b - a = d n exactly in exact
 * arithmetic, centred on the solver's points pa, pb. */
void mk_polish_witness(mk_vec3 pa, mk_vec3 pb, mk_real d, mk_vec3 n, mk_vec3 *a, mk_vec3 *b);

#endif

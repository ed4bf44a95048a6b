/* polytope.h: a box core seen as an mk_hull (internal).
 *
 * Contract. Code written for hulls (SAT, clipping) runs on boxes through this
 * view instead of a second implementation: a fixed topology shared by every
 * box (static tables) and the per-box vertices and planes in the caller's
 * mk_box_hull, filled by mk_box_hull_init without allocating. The numbering
 * is minko/manifold.h's box feature numbering: vertex i is the corner with
 * bits zyx of i set for +extent, face f is 2 * axis + (1 for the + side),
 * each face's 4 half-edges are 4 * f .. 4 * f + 3, counter-clockwise seen from
 * outside; mk_box_hull_edge_id maps a half-edge to the box edge ID (0..11).
 * The centroid is the origin. O(1) per box.
 */
#ifndef MINKO_POLYTOPE_H
#define MINKO_POLYTOPE_H

#include "minko/shape.h"

typedef struct mk_box_hull {
    mk_hull hull;      /* points at v, p and the static topology */
    mk_vec3 v[8];
    mk_plane p[6];
    mk_real coords[24]; /* v as hull.coords rows (x, y, z) */
} mk_box_hull;

/* half_extents must be positive; the view must not be copied (hull points into it). */
void mk_box_hull_init(mk_box_hull *b, mk_vec3 half_extents);
/* Box edge ID (minko/manifold.h) of box half-edge 0..23. */
extern const unsigned char mk_box_edge_id_[24];
static inline int mk_box_hull_edge_id(int half_edge) { return mk_box_edge_id_[half_edge]; }

#endif

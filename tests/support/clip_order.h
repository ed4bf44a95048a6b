/* clip_order.h: the order in which box_box.c's face clip lists its
 * candidates (and so the order the reduction's preference for earlier
 * candidates follows), worked out here from the features' geometry so
 * that tests can put the general clip's candidates (mk_mf_clip) in it. */
#ifndef MK_TEST_CLIP_ORDER_H
#define MK_TEST_CLIP_ORDER_H

#include "manifold_internal.h"

/* Reference corners by their signs along the reference face's in-plane axes
 * u = (k + 1) % 3 and v = (k + 2) % 3 (k = face / 2): (+, +), (-, +), (-, -),
 * (+, -); then crossings by the incident edge's place in face fi's edge list
 * (mk_box_face_edge_), then by the reference side: +u, +v, -u, -v; then the
 * incident corners by their place in face fi's corner list; anything else
 * last. */
int mk_test_clip_rank(int face, int fi, mk_feature fref, mk_feature finc);

/* Stable-sorts m's candidates into that order; the reference feature is
 * A's when ref_is_a. */
void mk_test_clip_sort(mk_mf *m, int face, int fi, int ref_is_a);

#endif

/* closest.c: the closed form that needs a shape's support function (plane
 * pairs); the others are inline in closest.h. */
#include "closest.h"

mk_hit mk_closest_shape_plane(const mk_pair *p)
{
    mk_vec3 n = mk_mat3_mul_v3(p->r, p->b->u.plane.normal); /* plane normal in A's frame */
    mk_real off = p->b->u.plane.offset + mk_v3_dot(n, p->t);
    int f = -1;
    mk_vec3 s = mk_core_support_inl(p->a, mk_v3_neg(n), &f); /* deepest core point towards the solid */
    mk_real dc = mk_v3_dot(n, s) - off;
    /* The solid lies below the plane: from A towards B is -n. */
    return mk_hit_grow(s, mk_v3_mad(s, -dc, n), dc, mk_v3_neg(n), p->a->radius, 0);
}

/* hull.c: convex hulls: quickhull construction and the hill-climbing support. */
#include "minko/shape.h"

/* A vertex of a convex polytope that is not beaten by any neighbour along dir
 * is a global maximum (the simplex-method argument), so walking uphill over
 * the vertex graph finds the support in O(path length) instead of O(V).
 * Ties do not loop: we only move on a strict increase. */
int mk_hull_support_index(const mk_hull *h, mk_vec3 dir, int start)
{
    int best = (start >= 0 && start < h->vertex_count) ? start : 0;
    mk_real best_d = mk_v3_dot(dir, h->vertices[best]);
    int moved = 1;
    while (moved) {
        int e0 = h->vertex_edge[best], e = e0;
        moved = 0;
        do {
            int w = h->edges[h->edges[e].twin].origin;
            mk_real d = mk_v3_dot(dir, h->vertices[w]);
            if (d > best_d) {
                best = w;
                best_d = d;
                moved = 1;
                break;
            }
            e = h->edges[h->edges[e].twin].next;
        } while (e != e0);
    }
    return best;
}

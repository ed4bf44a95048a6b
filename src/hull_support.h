/* hull_support.h: the support walk of convex hulls (internal; included by
 * shape_internal.h).
 *
 * The vertex of a hull farthest along a direction: a scan of the vertex array
 * for small hulls, a hill climb over the vertex adjacency (h->adjacency) for
 * larger ones, warm-started from a caller's hint. Inline, so the GJK and EPA
 * loops, which call it twice an iteration, pay no call and no re-test of what
 * they already know (mk_hull_support_index is the same walk behind a call).
 * Complexity: O(V) scanned below MK_HULL_SCAN_MAX vertices, else O(path
 * length x degree), a few steps from a warm hint. No allocation.
 */
#ifndef MINKO_HULL_SUPPORT_H
#define MINKO_HULL_SUPPORT_H

#include "minko/shape.h"

/* Vertex count up to which mk_hull_support_index scans instead of climbing.
 * Measured on ellipsoid hulls (valgrind --tool=callgrind, instructions per
 * query; scan = 16 V + 38): cold-started climbing costs 373 at V = 16, 444 at
 * 32, 671 at 128; warm-started from the previous answer along a slowly
 * turning direction (GJK's pattern), 275 at 16, 288 at 32, 293 at 128. The
 * scan's branches predict better, so in wall time it ties warm climbing near
 * V = 24 and beats cold climbing beyond 48; 24 splits the difference. With
 * the two-chain scan below, 32 still favours climbing for GJK
 * (demos/bench_narrow, MK_HULL_SCAN_MAX 32 against 24: hull_hull_32
 * separated 660 against 530 ns, penetrating 3 % faster). */
#define MK_HULL_SCAN_MAX 24

/* Two interleaved maxima, over the even and the odd vertices, halve the chain
 * of dependent compare-and-selects the scan waits on (in a loop of queries
 * that each depend on the last answer, as GJK's do: 13 -> 9 ns at 8
 * vertices, 33 -> 24 ns at 32); merged so that, as with one, the first of
 * equal maxima wins. A hull has at least 4 vertices. */
static inline int mk_hull_scan_support_(const mk_hull *h, mk_vec3 dir)
{
    const mk_vec3 *p = h->vertices;
    int v, n = h->vertex_count, b0 = 0, b1 = 1;
    mk_real d0 = mk_v3_dot(dir, p[0]), d1 = mk_v3_dot(dir, p[1]);
    for (v = 2; v + 1 < n; v += 2) {
        mk_real e0 = mk_v3_dot(dir, p[v]), e1 = mk_v3_dot(dir, p[v + 1]);
        if (e0 > d0) b0 = v, d0 = e0;
        if (e1 > d1) b1 = v + 1, d1 = e1;
    }
    if (v < n && mk_v3_dot(dir, p[v]) > d0) b0 = v, d0 = mk_v3_dot(dir, p[v]);
    return d1 > d0 || (d1 == d0 && b1 < b0) ? b1 : b0;
}

/* Steepest ascent from `best` until no neighbour is higher. The neighbours
 * of a vertex are one contiguous run (h->adjacency), so their dot products
 * are independent loads the CPU overlaps, and taking the highest of them
 * shortens the path; moving only on a strict increase cannot loop. */
static inline int mk_hull_climb_(const mk_hull *h, mk_vec3 dir, int best, mk_real *best_d)
{
    const uint16_t *adj = h->adjacency;
    for (;;) {
        int k, end = adj[best + 1], next = best;
        mk_real nd = *best_d;
        for (k = adj[best]; k < end; ++k) {
            mk_real d = mk_v3_dot(dir, h->vertices[adj[k]]);
            if (d > nd) next = adj[k], nd = d;
        }
        if (next == best) return best;
        best = next;
        *best_d = nd;
    }
}

/* A vertex higher than best on one of the faces around it, or -1. The two
 * vertices next to best on each face are its neighbours, already beaten, so
 * only faces of four or more vertices have anything to look at. */
static inline int mk_hull_higher_on_faces_(const mk_hull *h, mk_vec3 dir, int best, mk_real best_d)
{
    int e0 = h->vertex_edge[best], e = e0;
    do {
        int x = h->edges[h->edges[e].next].next;
        for (; h->edges[x].next != e; x = h->edges[x].next)
            if (mk_v3_dot(dir, h->vertices[h->edges[x].origin]) > best_d) return h->edges[x].origin;
        e = h->edges[h->edges[e].twin].next;
    } while (e != e0);
    return -1;
}

/* The best of the six axis-extreme vertices stored after the neighbour lists. */
static inline int mk_hull_cold_start_(const mk_hull *h, mk_vec3 dir, mk_real *best_d)
{
    const uint16_t *x = h->adjacency + h->adjacency[h->vertex_count];
    int k, best = x[0];
    *best_d = mk_v3_dot(dir, h->vertices[best]);
    for (k = 1; k < 6; ++k) {
        mk_real d = mk_v3_dot(dir, h->vertices[x[k]]);
        if (d > *best_d) best = x[k], *best_d = d;
    }
    return best;
}

/* A vertex of a convex polytope that no neighbour beats along dir is a global
 * maximum (the simplex-method argument), so walking uphill over the vertex
 * graph finds the support in O(path length) instead of O(V). Ties do not
 * loop: we only move on a strict increase. But faces are convex only within
 * the construction tolerance, and a vertex that is a hair reflex in a long
 * face can stop the walk while the face's far end is much higher; so a walk
 * that stops also looks at every vertex of the faces around it, and goes on
 * from there if one is higher (only on hulls with faces of four or more
 * vertices: a triangle holds nothing but neighbours). Below MK_HULL_SCAN_MAX
 * vertices a plain scan of the contiguous vertex array is cheaper. */
MK_ALWAYS_INLINE int mk_hull_support_(const mk_hull *h, mk_vec3 dir, int start)
{
    int best, up, all_triangles = h->face_count == 2 * h->vertex_count - 4; /* Euler: F = 2V - 4 */
    mk_real best_d;
    if (h->vertex_count <= MK_HULL_SCAN_MAX) return mk_hull_scan_support_(h, dir);
    if (start >= 0 && start < h->vertex_count) {
        best = start;
        best_d = mk_v3_dot(dir, h->vertices[best]);
    } else {
        best = mk_hull_cold_start_(h, dir, &best_d);
    }
    for (;;) {
        best = mk_hull_climb_(h, dir, best, &best_d);
        if (all_triangles) return best; /* a vertex's faces hold only its neighbours */
        up = mk_hull_higher_on_faces_(h, dir, best, best_d);
        if (up < 0) return best;
        best = up;
        best_d = mk_v3_dot(dir, h->vertices[up]);
    }
}

#endif

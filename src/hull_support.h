/* hull_support.h: the support walk of convex hulls (internal; included by
 * shape_internal.h).
 *
 * The vertex of a hull farthest along a direction: a branch-free scan of the
 * coordinate rows (h->coords) for small hulls, a hill climb over the vertex
 * adjacency (h->adjacency) for larger ones, warm-started from a caller's
 * hint. Inline, so the GJK and EPA loops, which call it twice an iteration,
 * pay no call and no re-test of what they already know
 * (mk_hull_support_index is the same walk behind a call). Complexity: O(V)
 * scanned up to MK_HULL_SCAN_MAX vertices (MK_HULL_COLD_SCAN_MAX without a
 * hint), else O(path length x degree), a few steps from a warm hint. No
 * allocation.
 */
#ifndef MINKO_HULL_SUPPORT_H
#define MINKO_HULL_SUPPORT_H

#include "minko/shape.h"

/* Vertex counts up to which the support scans instead of climbing: with a
 * hint (a warm climb) and without one (a cold climb from the axis-extreme
 * vertices). Session 7, on ellipsoid hulls (valgrind --tool=callgrind,
 * instructions per query): a cold climb costs 373 at V = 16, 444 at 32, 671
 * at 128; a warm climb along a slowly turning direction (GJK's pattern) 275
 * at 16, 288 at 32, 293 at 128. Session 9, with the scan below, in
 * demos/bench_narrow (same-run ratios to Bullet's gjk_epa2, two runs): a
 * warm climb still wins at V = 32 for separated GJK (hull_hull_32 separated
 * 0.41 against 0.51 scanning), but EPA's directions jump between faces and
 * GJK's jump while it encloses the origin, so GJK passes no hint after a
 * turn of more than 60 degrees (gjk.c) and EPA none at all up to
 * MK_HULL_COLD_SCAN_MAX: hull_hull_32 penetrating 0.68 -> 0.50. Scanning
 * 128 vertices in EPA doubled its instructions. */
#define MK_HULL_SCAN_MAX 24
#define MK_HULL_COLD_SCAN_MAX 32

/* Entries in each row of mk_hull.coords: the vertex count rounded up to a
 * multiple of 4. */
#define MK_HULL_COORDS_STRIDE(v) (((v) + 3) & ~3)

/* Vertices one scan block takes: its dot products go to a stack buffer. */
#define MK_HULL_SCAN_BLOCK 32

/* The first vertex of [b, b + e) highest along dir, and *top its value (e a
 * multiple of 4 in [4, MK_HULL_SCAN_BLOCK]; rows of n entries): every dot
 * product first, four at a time with no branch (the compiler packs them
 * into vector operations), then their maximum in four lanes, then the first
 * vertex that reaches it. A scan over the vertex array that tracks the
 * index as it goes waits on a chain of dependent compare-and-selects
 * instead (/tmp microbenchmark, session 9: the same instructions, 15-20 %
 * more time per dependent call at 8 and 32 vertices). Padding copies of
 * vertex 0 never win over it (the first of equal maxima wins). A NaN
 * direction gives a NaN *top and vertex b. Not kept: the index searched
 * only in the lanes (vertex mod 4) that hold the maximum (2 % fewer
 * instructions on hull_hull_32 penetrating, 8 % slower in wall time). */
MK_ALWAYS_INLINE int mk_hull_scan_block_(const mk_real *x, int n, int b, int e, mk_vec3 dir, mk_real *top)
{
    const mk_real *y = x + n, *z = y + n;
    mk_real d[MK_HULL_SCAN_BLOCK], m0, m1, m2, m3;
    int i;
    i = 0;
    do {
        d[i] = dir.x * x[b + i] + dir.y * y[b + i] + dir.z * z[b + i];
        d[i + 1] = dir.x * x[b + i + 1] + dir.y * y[b + i + 1] + dir.z * z[b + i + 1];
        d[i + 2] = dir.x * x[b + i + 2] + dir.y * y[b + i + 2] + dir.z * z[b + i + 2];
        d[i + 3] = dir.x * x[b + i + 3] + dir.y * y[b + i + 3] + dir.z * z[b + i + 3];
        i += 4;
    } while (i < e);
    m0 = d[0];
    m1 = d[1];
    m2 = d[2];
    m3 = d[3];
    for (i = 4; i < e; i += 4) {
        m0 = d[i] > m0 ? d[i] : m0;
        m1 = d[i + 1] > m1 ? d[i + 1] : m1;
        m2 = d[i + 2] > m2 ? d[i + 2] : m2;
        m3 = d[i + 3] > m3 ? d[i + 3] : m3;
    }
    m0 = m1 > m0 ? m1 : m0;
    m2 = m3 > m2 ? m3 : m2;
    *top = m0 = m2 > m0 ? m2 : m0;
    if (!(m0 == m0)) return b; /* m0 is NaN only when d[0] is */
    for (i = 0; d[i] != m0; ++i) {}
    return b + i;
}

/* The support by scan blocks over the coordinate rows (h->coords); any size
 * (the hull's construction scans it whole once for the climb's cold start). */
MK_ALWAYS_INLINE int mk_hull_scan_support_(const mk_hull *h, mk_vec3 dir)
{
    int n = MK_HULL_COORDS_STRIDE(h->vertex_count), b, v, best;
    mk_real top, best_d;
    best = mk_hull_scan_block_(h->coords, n, 0, n < MK_HULL_SCAN_BLOCK ? n : MK_HULL_SCAN_BLOCK, dir, &best_d);
    for (b = MK_HULL_SCAN_BLOCK; b < n; b += MK_HULL_SCAN_BLOCK) {
        v = mk_hull_scan_block_(h->coords, n, b, n - b < MK_HULL_SCAN_BLOCK ? n - b : MK_HULL_SCAN_BLOCK, dir, &top);
        if (top > best_d) best = v, best_d = top;
    }
    return best;
}

/* Steepest ascent from `best` until no neighbour is higher. The neighbours
 * of a vertex are one contiguous run (h->adjacency), so their dot products
 * are independent loads the CPU overlaps, and taking the highest of them
 * shortens the path; moving only on a strict increase cannot loop. Not kept
 * (session 10): a step without branches (always eight neighbours, the
 * first repeated, then a tree of selects): callgrind's branch simulation
 * counts 49k -> 12k mispredictions on hull_hull_32 separated, but +47 %
 * instructions and slower in time (ratio to gjk_pair 0.33 -> 0.53,
 * hull_hull_128 separated 0.20 -> 0.40; three alternations, load 8). */
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
 * vertices: a triangle holds nothing but neighbours). Small hulls are
 * scanned instead (MK_HULL_SCAN_MAX, MK_HULL_COLD_SCAN_MAX). */
MK_ALWAYS_INLINE int mk_hull_support_(const mk_hull *h, mk_vec3 dir, int start)
{
    int best, up, all_triangles = h->face_count == 2 * h->vertex_count - 4; /* Euler: F = 2V - 4 */
    mk_real best_d;
    if (h->vertex_count <= (start < 0 ? MK_HULL_COLD_SCAN_MAX : MK_HULL_SCAN_MAX)) return mk_hull_scan_support_(h, dir);
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

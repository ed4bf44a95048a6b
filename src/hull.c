/* hull.c: convex hulls: quickhull construction and the support function.
 *
 * Construction is quickhull (Barber, Dobkin, Huhdanpaa 1996) on a half-edge
 * mesh of polygon faces, with the face merging of Lloyd's quickhull3d and of
 * Gregorius (GDC 2014): after each point is added, every new face is merged
 * with each neighbour it is not clearly convex against. That turns coplanar
 * input into one polygon per plane, and it keeps rounding from ever building
 * a fold (a slightly reflex edge), which is how a floating-point quickhull
 * usually corrupts its own topology. Merges that are not needed for
 * convexity are checked first (region_ok): the merged face must be a convex
 * polygon, flat within 2 tol, and whatever vertex the merge drops must not
 * move the surface.
 *
 * Precision and tolerance. Construction runs in double in both builds (float
 * input is exact in double), on the points minus the centre of their bounding
 * box, so an offset cloud costs no precision. A point counts as above a face
 * only if it is more than tol = 16 eps (ex + ey + ez) above it (e: the
 * half-extents of the box, eps: DBL_EPSILON): a plane distance computed from
 * coordinates of size e is off by a few eps*e. Then faces are merged once more
 * at the output's tolerance, the same formula with mk_real's epsilon, which is
 * the same pass in the double build and, in the float build, the one that
 * turns points coplanar at float precision (a rotated cube) into one face.
 *
 * Memory. Faces and half-edges live in arrays with free lists. A closed mesh
 * of polygons on V vertices has at most 6V - 12 half-edges and 2V - 4 faces,
 * and the visible faces are freed before the new ones are made, so arrays of
 * 6n and 2n (plus slack) never overflow; a broken mesh is caught by counting
 * and reported as MK_ERR_DEGENERATE, never written out of bounds. All working
 * memory is one block from the caller's allocator, freed before returning.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "alloc.h"
#include "shape_internal.h"

#define QH_TOL_ULPS 16 /* see the header comment */
#define QH_FLAT 2 /* merged faces stay within QH_FLAT * tol of their plane */

enum { QH_LIVE = 0, QH_NONCONVEX = 1, QH_DELETED = 2 };

/* Construction runs in double in both builds (float input is exact in
 * double), so these few vector helpers exist beside math3d.h's mk_real ones. */
typedef struct dv3 { double x, y, z; } dv3;
static dv3 dv(double x, double y, double z) { dv3 v; v.x = x; v.y = y; v.z = z; return v; }
static dv3 dv_zero(void) { return dv(0, 0, 0); }
static dv3 dv_of(mk_vec3 a) { return dv(a.x, a.y, a.z); }
static dv3 dv_add(dv3 a, dv3 b) { return dv(a.x + b.x, a.y + b.y, a.z + b.z); }
static dv3 dv_sub(dv3 a, dv3 b) { return dv(a.x - b.x, a.y - b.y, a.z - b.z); }
static dv3 dv_scale(dv3 a, double s) { return dv(a.x * s, a.y * s, a.z * s); }
static double dv_dot(dv3 a, dv3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static dv3 dv_cross(dv3 a, dv3 b) { return dv(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x); }
static double dv_len(dv3 a) { return sqrt(dv_dot(a, a)); }
static double dv_dist(dv3 a, dv3 b) { return dv_len(dv_sub(a, b)); }
static dv3 dv_normalize(dv3 a)
{
    double l = dv_len(a);
    return l > 0 ? dv_scale(a, 1 / l) : dv_zero();
}

typedef struct qh_edge { int next, prev, twin, origin, face; } qh_edge;

typedef struct qh_face {
    dv3 n;       /* unit normal (zero for a face of no area) */
    dv3 c;       /* average of the vertices */
    double d;    /* n . c */
    double area;
    int edge;    /* one half-edge; links the free list once deleted */
    int outside; /* first of this face's points in the claimed list, or -1 */
    int mark;
} qh_face;

typedef struct qh {
    dv3 *p; /* centred points */
    int n;
    double tol;     /* the tolerance in effect */
    double tol_out; /* the output's, in ulps of mk_real */
    /* Points above some face: one doubly linked list in which each face's
     * points are contiguous (Lloyd), so the next face to work on is simply the
     * owner of the first point. Unclaimed points wait in a singly linked list. */
    int *pnext, *pprev, *pface;
    int claimed, claimed_tail, unclaimed;
    qh_edge *e;
    int e_cap, e_top, e_free, e_live;
    qh_face *f;
    int f_cap, f_top, f_free, f_live;
    int *stack;   /* horizon search frames: (next edge, edges left) */
    int *visible; /* faces seen from the eye point */
    int nvisible;
    int *horizon; /* (origin, end, outer twin) of each horizon edge, in order */
    int nhorizon, h_cap;
    int *newf;
    int nnew;
    int *loop;    /* scratch: the vertices of a would-be merged face */
    int *bnd;     /* scratch: its boundary half-edges */
    int *cl;      /* per face: id of the region it was last put in */
    int *vmark;   /* per point: id of the region boundary it was last seen on */
    int *members; /* scratch: the faces of a region */
    int stamp;    /* last region id handed out */
    int *scratch; /* e_cap ints (shared with emit's edge map, used after) */
    void *rank;   /* f_cap qh_rank entries for merge_regions */
    int broken;
} qh;

/* ---- allocation -------------------------------------------------------------- */

static size_t align_up(size_t x, size_t a) { return (x + a - 1) / a * a; }

/* ---- points ------------------------------------------------------------------- */

static double face_dist(const qh *q, int f, int i) { return dv_dot(q->f[f].n, q->p[i]) - q->f[f].d; }

static void pt_unlink(qh *q, int i)
{
    int a = q->pprev[i], b = q->pnext[i];
    if (a >= 0) q->pnext[a] = b; else q->claimed = b;
    if (b >= 0) q->pprev[b] = a; else q->claimed_tail = a;
}

static void pt_claim(qh *q, int i, int f)
{
    int at = q->f[f].outside;
    q->pface[i] = f;
    if (at < 0) {
        q->pprev[i] = q->claimed_tail;
        q->pnext[i] = -1;
        if (q->claimed_tail >= 0) q->pnext[q->claimed_tail] = i; else q->claimed = i;
        q->claimed_tail = i;
    } else { /* in front of the face's first point, keeping its points contiguous */
        int a = q->pprev[at];
        q->pprev[i] = a;
        q->pnext[i] = at;
        q->pprev[at] = i;
        if (a >= 0) q->pnext[a] = i; else q->claimed = i;
    }
    q->f[f].outside = i;
}

static void pt_unclaim(qh *q, int i)
{
    int f = q->pface[i];
    if (q->f[f].outside == i) {
        int b = q->pnext[i];
        q->f[f].outside = (b >= 0 && q->pface[b] == f) ? b : -1;
    }
    pt_unlink(q, i);
    q->pface[i] = -1;
}

/* The face's points go back to the unclaimed list, to be given to new faces. */
static void face_release_points(qh *q, int f)
{
    int i = q->f[f].outside;
    while (i >= 0 && q->pface[i] == f) {
        int nx = q->pnext[i];
        pt_unclaim(q, i);
        q->pnext[i] = q->unclaimed;
        q->unclaimed = i;
        i = nx;
    }
}

/* ---- mesh ---------------------------------------------------------------------- */

static int edge_new(qh *q)
{
    int i;
    if (q->e_free >= 0) {
        i = q->e_free;
        q->e_free = q->e[i].next;
    } else {
        i = q->e_top++;
    }
    q->e_live++;
    return i;
}

static void edge_free(qh *q, int i)
{
    q->e[i].face = -1;
    q->e[i].next = q->e_free;
    q->e_free = i;
    q->e_live--;
}

static int face_new(qh *q)
{
    int i;
    if (q->f_free >= 0) {
        i = q->f_free;
        q->f_free = q->f[i].edge;
    } else {
        i = q->f_top++;
    }
    q->f_live++;
    q->f[i].outside = -1;
    q->f[i].mark = QH_LIVE;
    return i;
}

static void face_free(qh *q, int f)
{
    q->f[f].mark = QH_DELETED;
    q->f[f].edge = q->f_free;
    q->f_free = f;
    q->f_live--;
}

static int face_size(const qh *q, int f)
{
    int e = q->f[f].edge, k = 0;
    do {
        e = q->e[e].next;
        ++k;
    } while (e != q->f[f].edge && k <= q->e_cap);
    return k;
}

/* Plane of a polygon face. The normal is the sum of the cross products of
 * consecutive edges: on a convex polygon every term points the same way, so
 * nothing cancels and a sliver face (a 200 x 0.02 side of a rod) gets its
 * normal to a few ulps, where the usual area vector about the centroid crosses
 * long, nearly opposite vectors and loses about size/width of the digits.
 * The area (used only to pick the better conditioned of two faces) is the
 * magnitude of that area vector. */
static void face_update(qh *q, int f)
{
    qh_face *F = &q->f[f];
    dv3 c = dv_zero(), N = dv_zero(), A = dv_zero();
    int e = F->edge, k = 0;
    double l;
    do {
        c = dv_add(c, q->p[q->e[e].origin]);
        ++k;
        e = q->e[e].next;
    } while (e != F->edge);
    c = dv_scale(c, 1 / (double)k);
    do {
        int e1 = q->e[e].next, e2 = q->e[e1].next;
        dv3 p0 = q->p[q->e[e].origin], p1 = q->p[q->e[e1].origin], p2 = q->p[q->e[e2].origin];
        N = dv_add(N, dv_cross(dv_sub(p1, p0), dv_sub(p2, p1)));
        A = dv_add(A, dv_cross(dv_sub(p0, c), dv_sub(p1, c)));
        e = e1;
    } while (e != F->edge);
    l = dv_len(N);
    F->c = c;
    F->area = dv_len(A) / 2;
    F->n = l > 0 ? dv_scale(N, 1 / l) : dv_zero();
    F->d = dv_dot(F->n, c);
}

static int face_tri(qh *q, int a, int b, int c)
{
    int f = face_new(q), e0 = edge_new(q), e1 = edge_new(q), e2 = edge_new(q);
    int v[3], e[3], k;
    v[0] = a, v[1] = b, v[2] = c;
    e[0] = e0, e[1] = e1, e[2] = e2;
    for (k = 0; k < 3; ++k) {
        qh_edge *E = &q->e[e[k]];
        E->origin = v[k];
        E->face = f;
        E->next = e[(k + 1) % 3];
        E->prev = e[(k + 2) % 3];
        E->twin = -1;
    }
    q->f[f].edge = e0;
    face_update(q, f);
    return f;
}

/* ---- merging ------------------------------------------------------------------- */

/* Joins A (ending at vertex v) to B (leaving v) on the boundary of face f. If
 * the faces across A and B are one face h, v touches only f and h, so it is no
 * corner of the polytope: it is dropped (B then starts where A started), and
 * if that leaves h with two edges, h goes too. Returns 1 if v was dropped. */
static int connect(qh *q, int f, int A, int B)
{
    qh_edge *E = q->e;
    int TA = E[A].twin, TB = E[B].twin, h = E[TA].face;
    if (h != E[TB].face) {
        E[A].next = B;
        E[B].prev = A;
        return 0;
    }
    if (q->f[f].edge == A) q->f[f].edge = B;
    E[B].origin = E[A].origin;
    E[B].prev = E[A].prev;
    E[E[A].prev].next = B;
    /* In h, TB (into v) is followed by TA (out of v). */
    if (E[E[E[TB].next].next].next == TB) {
        int C = E[TA].next, TC = E[C].twin;
        if (E[TC].face == f) q->broken = 1; /* h was an ear wholly inside f: not a mesh we can repair */
        E[B].twin = TC;
        E[TC].twin = B;
        face_release_points(q, h);
        edge_free(q, TA);
        edge_free(q, TB);
        edge_free(q, C);
        face_free(q, h);
    } else {
        if (q->f[h].edge == TB) q->f[h].edge = TA;
        E[TA].origin = E[TB].origin;
        E[TA].prev = E[TB].prev;
        E[E[TB].prev].next = TA;
        E[B].twin = TA;
        E[TA].twin = B;
        edge_free(q, TB);
        face_update(q, h);
    }
    edge_free(q, A);
    return 1;
}

/* The run first..last of f's half-edges (around e) that border the same face as e. */
static void shared_run(const qh *q, int e, int *first, int *last)
{
    const qh_edge *E = q->e;
    int g = E[E[e].twin].face, a = e, b = e, k = 0;
    while (E[E[E[a].prev].twin].face == g && E[a].prev != e && ++k < q->e_cap) a = E[a].prev;
    while (E[E[E[b].next].twin].face == g && E[b].next != a && ++k < q->e_cap) b = E[b].next;
    *first = a;
    *last = b;
}

/* Turn u -> v -> w in the plane with normal nrm: convex within tol, or
 * straight, but not doubling back. */
static int turn_ok(const qh *q, dv3 nrm, int u, int v, int w)
{
    dv3 a = dv_sub(q->p[v], q->p[u]), b = dv_sub(q->p[w], q->p[v]);
    double c = dv_dot(dv_cross(a, b), nrm), h = q->tol * dv_dist(q->p[w], q->p[u]);
    return c >= -h && (dv_dot(a, b) > 0 || c > h);
}

/* Is v within tol of the segment u-w? Only then can v be dropped from the
 * mesh (leaving its two faces the edge u-w) without moving the surface. */
static int near_chord(const qh *q, int u, int v, int w)
{
    dv3 a = dv_sub(q->p[w], q->p[u]), b = dv_sub(q->p[v], q->p[u]);
    double l = dv_len(a);
    return l > 0 && dv_len(dv_cross(a, b)) <= q->tol * l && dv_dot(a, b) > 0 && dv_dot(a, dv_sub(q->p[v], q->p[w])) < 0;
}

/* ---- regions: faces that would become one ------------------------------------- */

/* The faces members[0..m-1], marked q->cl[f] == id, form the region under
 * examination. Its boundary is walked as a loop of half-edges whose twins lie
 * outside. Returns the loop length, or 0 unless all the boundary edges make
 * one loop through distinct vertices (no hole, no pinched vertex). */
static int region_boundary(qh *q, int id, const int *members, int m, int *bnd)
{
    const qh_edge *E = q->e;
    int b0 = -1, x, j, k = 0, guard = 0, total = 0;
    for (j = 0; j < m; ++j) {
        x = q->f[members[j]].edge;
        do {
            if (q->cl[E[E[x].twin].face] != id) b0 = x, ++total;
            x = E[x].next;
        } while (x != q->f[members[j]].edge);
    }
    if (b0 < 0) return 0;
    x = b0;
    do {
        int v = E[x].origin;
        if (k >= total || q->vmark[v] == id) return 0;
        q->vmark[v] = id;
        bnd[k++] = x;
        /* Next boundary edge: turn about x's end vertex through region faces. */
        for (x = E[x].next; q->cl[E[E[x].twin].face] == id; x = E[E[x].twin].next)
            if (++guard > q->e_cap) return 0;
    } while (x != b0);
    return k == total ? k : 0;
}

/* Would the region's faces make a good polygon if merged into one face with
 * boundary bnd[0..k-1]? The polygon (without the boundary vertices the merge
 * drops, see connect) must turn convexly within tol without doubling back,
 * and every vertex of the region must stay within QH_FLAT * tol of the plane
 * the merged face will get. A dropped vertex v leaves the outside face h
 * across it the chord u-w: if h is a triangle it goes and its area joins the
 * merged face, so it must be flat too; otherwise h keeps its shape only if v
 * is on that chord, or h lies in the plane as well, and h's new corners must
 * still be convex. The centroid tests that propose a merge cannot see these
 * problems: a sliver face (three nearly collinear points on a rim) is
 * "coplanar" with every plane through its long edge, and merging it across a
 * short edge folds the polygon over; a chain of merges along a gently curved
 * surface, each within tol, drifts ever further from flat. */
static int region_ok(const qh *q, const int *bnd, int k, const int *members, int m)
{
    const qh_edge *E = q->e;
    int i, j, n = 0, *loop = q->loop;
    dv3 c = dv_zero(), nrm = dv_zero();
    double d, flat = QH_FLAT * q->tol;
    for (i = 0; i < k; ++i)
        if (E[E[bnd[(i + k - 1) % k]].twin].face != E[E[bnd[i]].twin].face) loop[n++] = E[bnd[i]].origin;
    if (n < 3) return 0;
    for (i = 0; i < n; ++i) { /* the plane face_update will give the merged face */
        dv3 p0 = q->p[loop[i]], p1 = q->p[loop[(i + 1) % n]], p2 = q->p[loop[(i + 2) % n]];
        c = dv_add(c, p0);
        nrm = dv_add(nrm, dv_cross(dv_sub(p1, p0), dv_sub(p2, p1)));
    }
    nrm = dv_normalize(nrm);
    d = dv_dot(nrm, dv_scale(c, 1.0 / n));
    for (i = 0; i < n; ++i)
        if (!turn_ok(q, nrm, loop[i], loop[(i + 1) % n], loop[(i + 2) % n])) return 0;
    for (j = 0; j < m; ++j) {
        int x = q->f[members[j]].edge;
        do {
            if (fabs(dv_dot(nrm, q->p[E[x].origin]) - d) > flat) return 0;
            x = E[x].next;
        } while (x != q->f[members[j]].edge);
    }
    for (i = 0; i < k; ++i) {
        int ta = E[bnd[(i + k - 1) % k]].twin, tb = E[bnd[i]].twin, h = E[tb].face, hn, x;
        int u = E[bnd[(i + k - 1) % k]].origin, v = E[bnd[i]].origin, w = E[E[bnd[i]].next].origin;
        if (E[ta].face != h) continue; /* v stays */
        hn = face_size(q, h);
        if (hn == 3 || !near_chord(q, u, v, w)) {
            x = q->f[h].edge;
            do {
                if (fabs(dv_dot(nrm, q->p[E[x].origin]) - d) > flat) return 0;
                x = E[x].next;
            } while (x != q->f[h].edge);
        }
        if (hn > 3 && (!turn_ok(q, q->f[h].n, E[E[tb].prev].origin, w, u) || !turn_ok(q, q->f[h].n, w, u, E[E[E[ta].next].next].origin)))
            return 0;
    }
    return 1;
}

/* May the faces on both sides of half-edge e merge? */
static int merge_ok(qh *q, int e)
{
    int m[2], id = ++q->stamp, k;
    m[0] = q->e[e].face;
    m[1] = q->e[q->e[e].twin].face;
    q->cl[m[0]] = q->cl[m[1]] = id;
    k = region_boundary(q, id, m, 2, q->bnd);
    return k > 0 && region_ok(q, q->bnd, k, m, 2);
}

/* Dropping a vertex can swallow a triangle and so leave another vertex of f
 * between two edges that border one face; repeat until none is left. */
static void drop_redundant(qh *q, int f)
{
    int e = q->f[f].edge, k = 0, n = face_size(q, f);
    while (k < n && !q->broken) {
        int nx = q->e[e].next;
        if (q->e[q->e[e].twin].face == q->e[q->e[nx].twin].face && n > 3) {
            connect(q, f, e, nx);
            e = nx;
            k = 0;
            n = face_size(q, f);
        } else {
            e = nx;
            ++k;
        }
    }
}

/* Face f swallows the neighbour g across its half-edge e: the whole run of
 * edges f shares with g goes, g's other edges join f's loop. */
static void absorb(qh *q, int f, int e)
{
    qh_edge *E = q->e;
    int g = E[E[e].twin].face, first, last, a_prev, a_next, b_prev, b_next, x;
    shared_run(q, e, &first, &last);
    a_prev = E[first].prev;
    a_next = E[last].next;
    b_prev = E[E[last].twin].prev;
    b_next = E[E[first].twin].next;
    if (a_prev == last || b_next == E[last].twin) { /* one face surrounds the other */
        q->broken = 1;
        return;
    }
    for (x = b_next; x != E[last].twin; x = E[x].next) E[x].face = f;
    face_release_points(q, g);
    q->f[f].edge = a_next;
    /* If b_prev was the only edge g kept, its vertex may go in the first join
     * and a_next then stands in for it in the second. */
    if (connect(q, f, b_prev, a_next) && b_prev == b_next) b_next = a_next;
    connect(q, f, a_prev, b_next);
    for (x = first;;) {
        int nx = E[x].next, done = x == last;
        edge_free(q, E[x].twin);
        edge_free(q, x);
        if (done) break;
        x = nx;
    }
    face_free(q, g);
    drop_redundant(q, f);
    face_update(q, f);
}

/* Height of g's centroid above f's plane. */
static double above(const qh *q, int f, int g) { return dv_dot(q->f[f].n, q->f[g].c) - q->f[f].d; }

/* One merge of f with a neighbour, if any is due; returns 1 if it merged.
 * Each edge is judged by the larger face's plane (the better conditioned
 * one): if the smaller face's centroid is not clearly below it, the two are
 * coplanar or concave. Pass 0 acts on that word alone and only marks f when
 * the smaller face's plane disagrees; pass 1 (strict) also acts on the
 * smaller plane's word. A clear concavity (centroid more than tol above the
 * larger plane) is merged outright, since leaving it breaks convexity;
 * anything closer to flat only if merge_ok agrees. Pass 2, the final sweep at
 * the output tolerance over a mesh that is already convex, merges only what
 * merge_ok agrees to. */
static int merge_step(qh *q, int f, int strict)
{
    int e = q->f[f].edge, convex = 1;
    double tol = q->tol;
    do {
        int g = q->e[q->e[e].twin].face, big = q->f[f].area > q->f[g].area ? f : g, small = big == f ? g : f;
        double d_big = above(q, big, small), d_small = above(q, small, big);
        int merge = d_big > -tol || (strict && d_small > -tol);
        if (!merge && d_small > -tol) convex = 0;
        if (merge && ((d_big > tol && strict < 2) || merge_ok(q, e))) {
            absorb(q, f, e);
            return !q->broken;
        }
        e = q->e[e].next;
    } while (e != q->f[f].edge);
    if (!convex) q->f[f].mark = QH_NONCONVEX;
    return 0;
}

/* ---- adding a point ---------------------------------------------------------- */

static void face_kill(qh *q, int f)
{
    q->f[f].mark = QH_DELETED;
    face_release_points(q, f);
    q->visible[q->nvisible++] = f;
}

/* Depth-first walk over the faces the eye sees, starting from its own face.
 * Entering each face through the edge we came from and walking its loop from
 * there yields the horizon edges in order around the eye (Lloyd). */
static void find_horizon(qh *q, int eye, int f0)
{
    int sp = 1;
    q->nvisible = 0;
    q->nhorizon = 0;
    face_kill(q, f0);
    q->stack[0] = q->f[f0].edge;
    q->stack[1] = face_size(q, f0);
    while (sp > 0) {
        int *fr = &q->stack[2 * (sp - 1)], e, t, g;
        if (fr[1] == 0) {
            --sp;
            continue;
        }
        e = fr[0];
        fr[0] = q->e[e].next;
        fr[1]--;
        t = q->e[e].twin;
        g = q->e[t].face;
        if (q->f[g].mark == QH_DELETED) continue;
        if (face_dist(q, g, eye) > q->tol) {
            face_kill(q, g);
            q->stack[2 * sp] = q->e[t].next;
            q->stack[2 * sp + 1] = face_size(q, g) - 1;
            ++sp;
        } else if (q->nhorizon < q->h_cap) {
            int *h = &q->horizon[3 * q->nhorizon++];
            h[0] = q->e[e].origin;
            h[1] = q->e[q->e[e].next].origin;
            h[2] = t;
        } else {
            q->broken = 1;
        }
    }
}

static void free_visible(qh *q)
{
    int i;
    for (i = 0; i < q->nvisible; ++i) {
        int f = q->visible[i], e = q->f[f].edge, k = face_size(q, f);
        while (k-- > 0) {
            int nx = q->e[e].next;
            edge_free(q, e);
            e = nx;
        }
        face_free(q, f);
    }
}

/* Each unclaimed point goes to the new face it is farthest above, or, if it is
 * above none by more than tol, is inside the hull for good. (A point above a
 * visible face that ends up outside the new hull is above a new face.) */
static void resolve_unclaimed(qh *q)
{
    int i = q->unclaimed;
    while (i >= 0) {
        int nx = q->pnext[i], best = -1, k;
        double bd = q->tol;
        for (k = 0; k < q->nnew; ++k) {
            int f = q->newf[k];
            double d;
            if (q->f[f].mark == QH_DELETED) continue;
            d = face_dist(q, f, i);
            if (d > bd) {
                bd = d;
                best = f;
                if (d > 1000 * q->tol) break; /* clearly outside: any such face will do */
            }
        }
        if (best >= 0) pt_claim(q, i, best);
        i = nx;
    }
    q->unclaimed = -1;
}

static void add_point(qh *q, int eye, int f0)
{
    int i, h;
    find_horizon(q, eye, f0);
    h = q->nhorizon;
    for (i = 0; i < h; ++i)
        if (q->horizon[3 * i + 1] != q->horizon[3 * ((i + 1) % h)]) q->broken = 1;
    free_visible(q);
    if (h < 3 || q->broken || q->e_live + 3 * h > q->e_cap || q->f_live + h > q->f_cap) {
        q->broken = 1;
        return;
    }
    /* Fan of triangles (a, b, eye) over the horizon edges a -> b. */
    for (i = 0; i < h; ++i) {
        int *r = &q->horizon[3 * i];
        int f = face_tri(q, r[0], r[1], eye), e0 = q->f[f].edge;
        q->e[e0].twin = r[2];
        q->e[r[2]].twin = e0;
        q->newf[i] = f;
    }
    for (i = 0; i < h; ++i) {
        int e1 = q->e[q->f[q->newf[i]].edge].next, e2 = q->e[q->f[q->newf[(i + 1) % h]].edge].prev;
        q->e[e1].twin = e2;
        q->e[e2].twin = e1;
    }
    q->nnew = h;
    for (i = 0; i < h && !q->broken; ++i)
        if (q->f[q->newf[i]].mark == QH_LIVE)
            while (merge_step(q, q->newf[i], 0)) {}
    for (i = 0; i < h && !q->broken; ++i)
        if (q->f[q->newf[i]].mark == QH_NONCONVEX) {
            q->f[q->newf[i]].mark = QH_LIVE;
            while (merge_step(q, q->newf[i], 1)) {}
        }
    resolve_unclaimed(q);
}

/* ---- the whole run -------------------------------------------------------------- */

static void link_twins(qh *q, const int *faces, int nf)
{
    int i, j, a, b;
    for (i = 0; i < nf; ++i) {
        a = q->f[faces[i]].edge;
        do {
            int end = q->e[q->e[a].next].origin;
            for (j = 0; j < nf; ++j) {
                b = q->f[faces[j]].edge;
                do {
                    if (q->e[b].origin == end && q->e[q->e[b].next].origin == q->e[a].origin) q->e[a].twin = b;
                    b = q->e[b].next;
                } while (b != q->f[faces[j]].edge);
            }
            a = q->e[a].next;
        } while (a != q->f[faces[i]].edge);
    }
}

/* Widest pair on an axis, then the point farthest from their line, then the
 * point farthest from that plane. If any of those distances is within tol
 * the cloud is (nearly) coincident, collinear or coplanar. */
static mk_status initial_simplex(qh *q)
{
    int lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0}, ax = 0, i, k, v[4], faces[4];
    double best;
    dv3 u, nrm;
    const dv3 *p = q->p;
    for (i = 1; i < q->n; ++i) {
        for (k = 0; k < 3; ++k) {
            double c = k == 0 ? p[i].x : k == 1 ? p[i].y : p[i].z;
            double l = k == 0 ? p[lo[k]].x : k == 1 ? p[lo[k]].y : p[lo[k]].z;
            double h = k == 0 ? p[hi[k]].x : k == 1 ? p[hi[k]].y : p[hi[k]].z;
            if (c < l) lo[k] = i;
            if (c > h) hi[k] = i;
        }
    }
    for (k = 1; k < 3; ++k)
        if (dv_dist(p[hi[k]], p[lo[k]]) > dv_dist(p[hi[ax]], p[lo[ax]])) ax = k;
    v[0] = lo[ax];
    v[1] = hi[ax];
    if (!(dv_dist(p[v[0]], p[v[1]]) > q->tol_out)) return MK_ERR_DEGENERATE;
    u = dv_normalize(dv_sub(p[v[1]], p[v[0]]));
    best = 0;
    v[2] = -1;
    for (i = 0; i < q->n; ++i) {
        double d = dv_len(dv_cross(dv_sub(p[i], p[v[0]]), u));
        if (d > best) best = d, v[2] = i;
    }
    if (!(best > q->tol_out)) return MK_ERR_DEGENERATE;
    nrm = dv_normalize(dv_cross(u, dv_sub(p[v[2]], p[v[0]])));
    best = 0;
    v[3] = -1;
    for (i = 0; i < q->n; ++i) {
        double d = fabs(dv_dot(nrm, dv_sub(p[i], p[v[0]])));
        if (d > best) best = d, v[3] = i;
    }
    if (!(best > q->tol_out)) return MK_ERR_DEGENERATE;
    if (dv_dot(nrm, dv_sub(p[v[3]], p[v[0]])) > 0) { /* base must face away from v3 */
        int t = v[1];
        v[1] = v[2];
        v[2] = t;
    }
    faces[0] = face_tri(q, v[0], v[1], v[2]);
    faces[1] = face_tri(q, v[1], v[0], v[3]);
    faces[2] = face_tri(q, v[2], v[1], v[3]);
    faces[3] = face_tri(q, v[0], v[2], v[3]);
    link_twins(q, faces, 4);
    for (i = 0; i < q->n; ++i) {
        int bf = -1;
        double bd = q->tol;
        if (i == v[0] || i == v[1] || i == v[2] || i == v[3]) continue;
        for (k = 0; k < 4; ++k) {
            double d = face_dist(q, faces[k], i);
            if (d > bd) bd = d, bf = faces[k];
        }
        if (bf >= 0) pt_claim(q, i, bf);
    }
    return MK_OK;
}

/* ---- final merging at the output's tolerance -------------------------------------- */

typedef struct qh_rank { double area; int face; } qh_rank;

static int rank_cmp(const void *a, const void *b)
{
    double x = ((const qh_rank *)a)->area, y = ((const qh_rank *)b)->area;
    return x > y ? -1 : x < y;
}

/* Is every vertex of g within QH_FLAT * tol of s's plane, facing the same way? */
static int flat_with(const qh *q, int s, int g)
{
    int x = q->f[g].edge;
    if (dv_dot(q->f[s].n, q->f[g].n) <= 0) return 0;
    do {
        if (fabs(face_dist(q, s, q->e[x].origin)) > QH_FLAT * q->tol) return 0;
        x = q->e[x].next;
    } while (x != q->f[g].edge);
    return 1;
}

/* Replaces the region's faces by the single face s bounded by bnd[0..k-1]. */
static void collapse_region(qh *q, int s, int id, const int *bnd, int k, const int *members, int m)
{
    int *inner = q->scratch, ni = 0, i, j;
    for (j = 0; j < m; ++j) { /* find the inner edges before freeing any, their twins are read */
        int x = q->f[members[j]].edge;
        do {
            if (q->cl[q->e[q->e[x].twin].face] == id) inner[ni++] = x;
            x = q->e[x].next;
        } while (x != q->f[members[j]].edge);
    }
    for (i = 0; i < ni; ++i) edge_free(q, inner[i]);
    for (i = 0; i < k; ++i) {
        int x = bnd[i], y = bnd[(i + 1) % k];
        q->e[x].face = s;
        q->e[x].next = y;
        q->e[y].prev = x;
    }
    q->f[s].edge = bnd[0];
    for (j = 0; j < m; ++j)
        if (members[j] != s) face_free(q, members[j]);
    drop_redundant(q, s);
    face_update(q, s);
}

/* Merging two faces at a time can get stuck: the tiles of a flat region,
 * each pair of which makes a non-convex polygon (a thin slice glued to the
 * middle of a long straight edge), while the whole region is one convex
 * polygon. So grow a region of faces flat with a large seed face (largest
 * first: their planes are the best conditioned) and merge it whole if it
 * passes region_ok. */
static void merge_regions(qh *q)
{
    qh_rank *rank = (qh_rank *)q->rank;
    int nr = 0, r, j, f, first = q->stamp;
    for (f = 0; f < q->f_top; ++f)
        if (q->f[f].mark != QH_DELETED) rank[nr].area = q->f[f].area, rank[nr++].face = f;
    qsort(rank, (size_t)nr, sizeof *rank, rank_cmp);
    for (r = 0; r < nr && !q->broken; ++r) {
        int s = rank[r].face, id, m = 1, k;
        /* A face already put in a region (merged, or refused whole) seeds none. */
        if (q->f[s].mark == QH_DELETED || q->cl[s] > first) continue;
        id = ++q->stamp;
        q->cl[s] = id;
        q->members[0] = s;
        for (j = 0; j < m; ++j) {
            int x = q->f[q->members[j]].edge;
            do {
                int g = q->e[q->e[x].twin].face;
                if (q->cl[g] != id && flat_with(q, s, g)) q->cl[g] = id, q->members[m++] = g;
                x = q->e[x].next;
            } while (x != q->f[q->members[j]].edge);
        }
        if (m < 2) continue;
        k = region_boundary(q, id, q->members, m, q->bnd);
        if (k > 0 && region_ok(q, q->bnd, k, q->members, m)) collapse_region(q, s, id, q->bnd, k, q->members, m);
    }
}

/* The eye is the point farthest above the face owning the first claimed point.
 * A merge may have tilted that face under its points; such a point is handed
 * to whichever live face it is still above, or dropped as inside. */
static void run(qh *q)
{
    int i, merged;
    while (q->claimed >= 0 && !q->broken) {
        int f = q->pface[q->claimed], eye = -1;
        double best = -DBL_MAX;
        for (i = q->f[f].outside; i >= 0 && q->pface[i] == f; i = q->pnext[i]) {
            double d = face_dist(q, f, i);
            if (d > best) best = d, eye = i;
        }
        pt_unclaim(q, eye);
        if (best > q->tol) {
            add_point(q, eye, f);
        } else {
            int g, bf = -1;
            double bd = q->tol;
            for (g = 0; g < q->f_top; ++g) {
                if (q->f[g].mark != QH_DELETED && face_dist(q, g, eye) > bd) bd = face_dist(q, g, eye), bf = g;
            }
            if (bf >= 0) pt_claim(q, eye, bf);
        }
    }
    /* Then merge at the output's tolerance. In the double build it is the
     * same; in the float build the hull was built in double, and this is
     * where faces that are one plane at float precision become one. Faces
     * also only check their neighbours when they are new, and a face that
     * lost a vertex or grew later may now be coplanar with an old neighbour,
     * so sweep all of them until nothing merges. */
    q->tol = q->tol_out;
    merge_regions(q);
    for (merged = 1; merged && !q->broken;) {
        merged = 0;
        for (i = 0; i < q->f_top && !q->broken; ++i)
            if (q->f[i].mark != QH_DELETED)
                while (merge_step(q, i, 2)) merged = 1;
    }
}

/* ---- output ---------------------------------------------------------------------- */

/* Half-edge invariants of the finished mesh, O(E): closed loops of >= 3 edges,
 * symmetric twins between different faces, one fan per vertex, Euler's V - E + F = 2.
 * out_edge[i] is a half-edge leaving point i, or -1 if i is no vertex. */
static int mesh_ok(const qh *q, const int *out_edge, int nv, int ne, int nf)
{
    int f, e, fan = 0, i;
    for (f = 0; f < q->f_top; ++f) {
        int k = 0;
        if (q->f[f].mark == QH_DELETED) continue;
        e = q->f[f].edge;
        do {
            const qh_edge *E = &q->e[e];
            int t = E->twin;
            if (E->face != f || q->e[E->next].prev != e || t < 0 || q->e[t].twin != e || q->e[t].face == f ||
                q->e[t].face < 0 || q->e[t].origin != q->e[E->next].origin || ++k > ne)
                return 0;
            e = E->next;
        } while (e != q->f[f].edge);
        if (k < 3) return 0;
    }
    if (nv - ne / 2 + nf != 2) return 0;
    /* Every vertex's edges form one fan: the fans together must cover all edges. */
    for (i = 0; i < q->n; ++i) {
        int e0 = out_edge[i], k = 0;
        if (e0 < 0) continue;
        e = e0;
        do {
            e = q->e[q->e[e].twin].next;
            ++k;
        } while (e != e0 && k <= ne);
        fan += k;
    }
    return fan == ne;
}

/* Plane offsets, solid centroid, radii and bounds, in double. The normals
 * come from the construction (face_update). Returns 0 if the solid has no
 * volume, which a consistent mesh of a non-flat cloud never has. */
static int hull_geometry(mk_hull *h, const dv3 *pc, dv3 centre, const int *vout)
{
    const mk_vec3 *verts = h->vertices;
    mk_plane *planes = (mk_plane *)h->planes;
    dv3 o = dv_zero(), acc = dv_zero(), cen;
    double vol = 0, rin = DBL_MAX, rout = 0;
    int f, v;
    for (v = 0; v < h->vertex_count; ++v) o = dv_add(o, pc[vout[v]]);
    o = dv_scale(o, 1.0 / h->vertex_count);
    for (f = 0; f < h->face_count; ++f) {
        int e0 = h->face_edge[f], e = e0;
        dv3 a = dv_sub(pc[vout[h->edges[e0].origin]], o), n = dv_of(planes[f].normal);
        double off = -DBL_MAX;
        do {
            /* Offset from the input coordinates, so every vertex is on or below. */
            off = fmax(off, dv_dot(n, dv_of(verts[h->edges[e].origin])));
            /* Solid centroid: fan of tetrahedra (o, v0, vi, vi+1), centred coordinates. */
            if (e != e0 && h->edges[e].next != e0) {
                dv3 b = dv_sub(pc[vout[h->edges[e].origin]], o), c = dv_sub(pc[vout[h->edges[h->edges[e].next].origin]], o);
                double t = dv_dot(a, dv_cross(b, c));
                vol += t;
                acc = dv_add(acc, dv_scale(dv_add(a, dv_add(b, c)), t));
            }
            e = h->edges[e].next;
        } while (e != e0);
        planes[f].offset = (mk_real)off;
    }
    if (!(vol > 0)) return 0;
    cen = dv_add(dv_add(o, dv_scale(acc, 1 / (4 * vol))), centre);
    h->centroid = mk_v3((mk_real)cen.x, (mk_real)cen.y, (mk_real)cen.z);
    for (f = 0; f < h->face_count; ++f) rin = fmin(rin, planes[f].offset - dv_dot(dv_of(planes[f].normal), cen));
    h->bounds = mk_aabb_make(verts[0], verts[0]);
    for (v = 0; v < h->vertex_count; ++v) {
        rout = fmax(rout, dv_dist(dv_of(verts[v]), cen));
        h->bounds.lo = mk_v3_min(h->bounds.lo, verts[v]);
        h->bounds.hi = mk_v3_max(h->bounds.hi, verts[v]);
    }
    h->inner_radius = (mk_real)rin;
    h->outer_radius = (mk_real)rout;
    return 1;
}

/* The live faces in breadth-first order over their adjacency, from the first
 * one: faces with nearby indices are then nearby on the hull, so a loop over
 * the faces that warm-starts each support query from the last answer (SAT)
 * climbs a step or two instead of across the hull. */
static void breadth_first_faces(qh *q, int *order, int nf)
{
    int id = ++q->stamp, head = 0, n = 0, f;
    for (f = 0; f < q->f_top && q->f[f].mark == QH_DELETED; ++f) {}
    order[n++] = f;
    q->cl[f] = id;
    while (head < n && n < nf) {
        int x = q->f[order[head]].edge, x0 = x;
        do {
            int g = q->e[q->e[x].twin].face;
            if (q->cl[g] != id) q->cl[g] = id, order[n++] = g;
            x = q->e[x].next;
        } while (x != x0);
        ++head;
    }
}

/* The support scan's copy of the vertices (mk_hull.coords). */
static void fill_coords(const mk_hull *h, mk_real *c)
{
    int n = MK_HULL_COORDS_STRIDE(h->vertex_count), i;
    for (i = 0; i < n; ++i) {
        mk_vec3 p = h->vertices[i < h->vertex_count ? i : 0];
        c[i] = p.x;
        c[n + i] = p.y;
        c[2 * n + i] = p.z;
    }
}

/* The neighbour lists the support walk reads: each vertex's fan, in ring
 * order, as one contiguous run of vertex indices (CSR), so its neighbours'
 * loads are independent instead of a chain of half-edge hops. */
static void fill_adjacency(const mk_hull *h, uint16_t *adj)
{
    int v, k = h->vertex_count + 1, axis;
    for (v = 0; v < h->vertex_count; ++v) {
        int e0 = h->vertex_edge[v], e = e0;
        adj[v] = (uint16_t)k;
        do {
            const mk_hull_edge *t = &h->edges[h->edges[e].twin];
            adj[k++] = t->origin;
            e = t->next;
        } while (e != e0);
    }
    adj[v] = (uint16_t)k;
    /* Then the vertices extreme along +x, -x, +y, -y, +z, -z: a cold walk
     * starts from the best of them instead of wherever vertex 0 lies. */
    for (axis = 0; axis < 6; ++axis) {
        mk_real s = axis & 1 ? -1 : 1;
        mk_vec3 d = mk_v3(axis / 2 == 0 ? s : 0, axis / 2 == 1 ? s : 0, axis / 2 == 2 ? s : 0);
        adj[k + axis] = (uint16_t)mk_hull_scan_support_(h, d);
    }
}

/* Compacts the live mesh into one block: faces in breadth-first order, each
 * face's half-edges contiguous in loop order, vertices in input order. */
static mk_status emit(qh *q, const mk_vec3 *in, dv3 centre, const mk_allocator *al, int *vmap, int *emap,
                      int *vout, mk_hull **out)
{
    int nv = 0, ne = 0, nf = 0, i, f, e;
    size_t off_planes, off_verts, off_edges, off_fe, off_ve, off_adj, off_coords, bytes;
    unsigned char *blk;
    mk_hull *h;
    mk_hull_edge *edges;
    uint16_t *fe, *ve, *adj;
    int *order = q->members;
    for (i = 0; i < q->n; ++i) vmap[i] = -1;
    for (f = 0; f < q->f_top; ++f) {
        if (q->f[f].mark == QH_DELETED) continue;
        ++nf;
        e = q->f[f].edge;
        do {
            vmap[q->e[e].origin] = e;
            ++ne;
            e = q->e[e].next;
        } while (e != q->f[f].edge && ne <= q->e_cap);
    }
    for (i = 0; i < q->n; ++i) nv += vmap[i] >= 0;
    if (!mesh_ok(q, vmap, nv, ne, nf) || nv > MK_HULL_MAX_VERTICES) return MK_ERR_DEGENERATE;
    nv = 0;
    for (i = 0; i < q->n; ++i)
        if (vmap[i] >= 0) vout[nv] = i, vmap[i] = nv++;

    off_planes = align_up(sizeof(mk_hull), 16);
    off_verts = off_planes + (size_t)nf * sizeof(mk_plane);
    off_edges = align_up(off_verts + (size_t)nv * sizeof(mk_vec3), 8);
    off_fe = off_edges + (size_t)ne * sizeof(mk_hull_edge);
    off_ve = off_fe + (size_t)nf * sizeof(uint16_t);
    off_adj = off_ve + (size_t)nv * sizeof(uint16_t);
    /* nv + 1 offsets, one neighbour per half-edge, six axis-extreme vertices:
     * 7 nv - 5 entries at most, well inside uint16_t */
    off_coords = align_up(off_adj + (size_t)(nv + 1 + ne + 6) * sizeof(uint16_t), 16);
    bytes = off_coords + 3 * (size_t)MK_HULL_COORDS_STRIDE(nv) * sizeof(mk_real);
    blk = (unsigned char *)al->alloc(al->ctx, bytes, 16);
    if (!blk) return MK_ERR_OUT_OF_MEMORY;
    memset(blk, 0, bytes);
    h = (mk_hull *)blk;
    edges = (mk_hull_edge *)(blk + off_edges);
    fe = (uint16_t *)(blk + off_fe);
    ve = (uint16_t *)(blk + off_ve);
    adj = (uint16_t *)(blk + off_adj);
    h->vertex_count = nv;
    h->edge_count = ne;
    h->face_count = nf;
    h->vertices = (const mk_vec3 *)(blk + off_verts);
    h->planes = (const mk_plane *)(blk + off_planes);
    h->edges = edges;
    h->face_edge = fe;
    h->vertex_edge = ve;
    h->adjacency = adj;
    h->tolerance = (mk_real)q->tol;
    h->allocator = *al;
    h->bytes = bytes;
    for (i = 0; i < nv; ++i) ((mk_vec3 *)h->vertices)[i] = in[vout[i]];
    h->coords = (const mk_real *)(blk + off_coords);
    fill_coords(h, (mk_real *)(blk + off_coords));
    breadth_first_faces(q, order, h->face_count);
    ne = 0;
    for (nf = 0; nf < h->face_count; ++nf) { /* number the half-edges face by face */
        f = order[nf];
        fe[nf] = (uint16_t)ne;
        e = q->f[f].edge;
        do {
            emap[e] = ne++;
            e = q->e[e].next;
        } while (e != q->f[f].edge);
    }
    for (nf = 0; nf < h->face_count; ++nf) {
        f = order[nf];
        if (!(dv_dot(q->f[f].n, q->f[f].n) > 0)) break; /* a face of no area: refused below */
        ((mk_plane *)h->planes)[nf].normal = mk_v3((mk_real)q->f[f].n.x, (mk_real)q->f[f].n.y, (mk_real)q->f[f].n.z);
        e = q->f[f].edge;
        do {
            mk_hull_edge *o = &edges[emap[e]];
            o->next = (uint16_t)emap[q->e[e].next];
            o->twin = (uint16_t)emap[q->e[e].twin];
            o->origin = (uint16_t)vmap[q->e[e].origin];
            o->face = (uint16_t)nf;
            ve[o->origin] = (uint16_t)emap[e];
            e = q->e[e].next;
        } while (e != q->f[f].edge);
    }
    if (nf == h->face_count) fill_adjacency(h, adj);
    if (nf != h->face_count || !hull_geometry(h, q->p, centre, vout)) {
        al->free(al->ctx, blk, bytes);
        return MK_ERR_DEGENERATE;
    }
    *out = h;
    return MK_OK;
}

static mk_status check_points(const mk_vec3 *points, int count)
{
    int i;
    for (i = 0; i < count; ++i)
        if (!mk_v3_is_valid(points[i])) return MK_ERR_NOT_FINITE;
    for (i = 0; i < count; ++i)
        if (mk_v3_max_abs(points[i]) > MK_MAX_SIZE) return MK_ERR_BAD_SIZE;
    return MK_OK;
}

mk_status mk_hull_create(const mk_vec3 *points, int count, const mk_allocator *alloc, mk_hull **out)
{
    mk_allocator al;
    qh q;
    dv3 lo, hi, centre;
    double size;
    mk_status st;
    size_t n, ecap, fcap, hcap, off[15], bytes;
    unsigned char *blk;
    int i;
    if (!out) return MK_ERR_NULL;
    *out = NULL;
    if (!points || mk_alloc_resolve_(alloc, &al) != MK_OK) return MK_ERR_NULL;
    if (count < 4) return MK_ERR_DEGENERATE;
    if (count > MK_HULL_MAX_POINTS) return MK_ERR_CAPACITY;
    if ((st = check_points(points, count)) != MK_OK) return st;

    n = (size_t)count;
    ecap = 6 * n + 16;
    fcap = 2 * n + 8;
    hcap = n + 8;
    off[0] = 0;                                      /* p */
    off[1] = off[0] + n * sizeof(dv3);               /* faces */
    off[2] = align_up(off[1] + fcap * sizeof(qh_face), 16); /* edges */
    off[3] = off[2] + ecap * sizeof(qh_edge);        /* pnext */
    off[4] = off[3] + n * sizeof(int);               /* pprev */
    off[5] = off[4] + n * sizeof(int);               /* pface */
    off[6] = off[5] + n * sizeof(int);               /* stack */
    off[7] = off[6] + 2 * fcap * sizeof(int);        /* visible */
    off[8] = off[7] + fcap * sizeof(int);            /* horizon */
    off[9] = off[8] + 3 * hcap * sizeof(int);        /* newf */
    off[10] = off[9] + hcap * sizeof(int);           /* emit maps: vmap, vout (n each), emap (ecap) */
    off[11] = off[10] + (2 * n + ecap) * sizeof(int); /* loop, bnd, vmark (hcap each) */
    off[12] = off[11] + 3 * hcap * sizeof(int);      /* cl, members (fcap each) */
    off[13] = align_up(off[12] + 2 * fcap * sizeof(int), 16); /* rank */
    off[14] = off[13] + fcap * sizeof(qh_rank);
    bytes = off[14];
    blk = (unsigned char *)al.alloc(al.ctx, bytes, 16);
    if (!blk) return MK_ERR_OUT_OF_MEMORY;

    memset(&q, 0, sizeof q);
    q.p = (dv3 *)(blk + off[0]);
    q.f = (qh_face *)(blk + off[1]);
    q.e = (qh_edge *)(blk + off[2]);
    q.pnext = (int *)(blk + off[3]);
    q.pprev = (int *)(blk + off[4]);
    q.pface = (int *)(blk + off[5]);
    q.stack = (int *)(blk + off[6]);
    q.visible = (int *)(blk + off[7]);
    q.horizon = (int *)(blk + off[8]);
    q.newf = (int *)(blk + off[9]);
    q.loop = (int *)(blk + off[11]);
    q.bnd = q.loop + hcap;
    q.vmark = q.bnd + hcap;
    q.cl = (int *)(blk + off[12]);
    q.members = q.cl + fcap;
    q.rank = blk + off[13];
    q.scratch = (int *)(blk + off[10]) + 2 * n;
    q.n = count;
    q.e_cap = (int)ecap;
    q.f_cap = (int)fcap;
    q.h_cap = (int)hcap;
    q.e_free = q.f_free = -1;
    q.claimed = q.claimed_tail = q.unclaimed = -1;

    lo = hi = dv_of(points[0]);
    for (i = 1; i < count; ++i) {
        dv3 v = dv_of(points[i]);
        lo = dv(fmin(lo.x, v.x), fmin(lo.y, v.y), fmin(lo.z, v.z));
        hi = dv(fmax(hi.x, v.x), fmax(hi.y, v.y), fmax(hi.z, v.z));
    }
    centre = dv_scale(dv_add(lo, hi), 0.5);
    size = (hi.x - lo.x) + (hi.y - lo.y) + (hi.z - lo.z);
    q.tol = QH_TOL_ULPS * DBL_EPSILON * size / 2;
    q.tol_out = QH_TOL_ULPS * MK_REAL_EPSILON * size / 2;
    for (i = 0; i < count; ++i) {
        q.p[i] = dv_sub(dv_of(points[i]), centre);
        q.pface[i] = -1;
        q.vmark[i] = 0;
    }
    for (i = 0; i < (int)fcap; ++i) q.cl[i] = 0;
    st = initial_simplex(&q);
    if (st == MK_OK) {
        run(&q);
        st = q.broken ? MK_ERR_DEGENERATE
                      : emit(&q, points, centre, &al, (int *)(blk + off[10]), (int *)(blk + off[10]) + 2 * n,
                             (int *)(blk + off[10]) + n, out);
    }
    al.free(al.ctx, blk, bytes);
    return st;
}

void mk_hull_destroy(mk_hull *hull)
{
    if (hull) hull->allocator.free(hull->allocator.ctx, hull, hull->bytes);
}

/* ---- support ------------------------------------------------------------------- */

/* The walk itself is hull_support.h's, inlined into the GJK and EPA loops. */
int mk_hull_support_index(const mk_hull *h, mk_vec3 dir, int start)
{
    return mk_hull_support_(h, dir, start);
}

/* sat.c: separating-axis test for convex polytopes (see sat.h). */
#include "sat.h"
#include "polytope.h"
#include "shape_internal.h"

/* Relative size under which a Gauss-map sign test is too close to call. */
#define SAT_SIGN_TOL (MK_REAL(64.0) * MK_REAL_EPSILON)

/* Points of each core that prune faces and edges of the other (see
 * plane_below): its six axis-extreme vertices and its deepest vertex under
 * the seed face of the other. */
#define SAT_PROBES 7

/* The best axis found so far of one kind. */
typedef struct sat_axis {
    mk_real sep;
    int a, b;
    mk_vec3 n;
} sat_axis;

typedef struct sat_ctx {
    const mk_hull *a, *b;
    mk_mat3 R;
    mk_vec3 t;
    mk_real stop;
    sat_axis face_a, face_b, edges;
    int stopped;
    /* Pruning (hulls only; see prune_init): the largest separation offered
     * so far, the band of the options' hysteresis, the rounding slack, the
     * centroids, the radii of balls about them inside each core (less the
     * slack) and the probes. */
    mk_real lo, rel, abs_band, slack;
    mk_vec3 ca, cb, ca_in_b; /* A's centroid, B's (in A's frame), A's in B's frame */
    mk_real ra, rb;
    mk_vec3 pb[SAT_PROBES], pa_in_b[SAT_PROBES]; /* probes (see plane_below): points of B in A's frame, of A in B's */
    int prune;               /* 0: a band too wide for the floor's argument */
} sat_ctx;

mk_sat_options mk_sat_defaults(void)
{
    mk_sat_options o;
    o.stop_above = MK_REAL_MAX;
    o.prefer = MK_SAT_NONE;
    o.prefer_rel = 0;
    o.prefer_abs = 0;
    o.hold_face = 1;
    o.first = MK_SAT_NONE;
    o.first_a = o.first_b = -1;
    return o;
}

static void axis_none(sat_axis *x)
{
    x->sep = -MK_REAL_MAX;
    x->a = x->b = -1;
    x->n = mk_v3_zero();
}

/* Keeps x if it beats the best of its kind; notes when it separates enough to stop. */
static void offer(sat_ctx *c, sat_axis *best, mk_real sep, int ia, int ib, mk_vec3 n)
{
    if (sep > c->lo) c->lo = sep;
    if (!(sep > best->sep)) return;
    best->sep = sep;
    best->a = ia;
    best->b = ib;
    best->n = n;
    if (sep > c->stop) c->stopped = 1;
}

/* Separation along A's face i: the deepest vertex of B under it, searched
 * from vertex *hint (-1: anywhere), which is then that vertex. */
static void face_of_a(sat_ctx *c, int i, int *hint)
{
    mk_plane pl = c->a->planes[i];
    int v = *hint = mk_hull_support_index(c->b, mk_mat3_tmul_v3(c->R, mk_v3_neg(pl.normal)), *hint);
    mk_vec3 w = mk_v3_add(mk_mat3_mul_v3(c->R, c->b->vertices[v]), c->t);
    offer(c, &c->face_a, mk_v3_dot(pl.normal, w) - pl.offset, i, -1, pl.normal);
}

/* One edge, ready for the Gauss-map test: a point, the edge vector, the
 * normals of its two faces (the face of the half-edge first) and the rounding
 * scale of its sign tests, all in A's frame. */
typedef struct sat_edge {
    mk_vec3 p, e, n1, n2;
    mk_real tol;
    int index;
} sat_edge;

/* ---- pruning ------------------------------------------------------------------
 * An axis can change mk_sat's answer only if it separates by at least
 * prune_floor = lo - band(lo), lo the largest separation offered so far: the
 * answer's best is >= lo, and an axis below best - band(best) (band =
 * prefer_rel |best| + prefer_abs, zero without a preference; best - band is
 * increasing in best while prefer_rel < 1) is neither the best nor within
 * the hysteresis band of it, so finish() picks the same axis with or without
 * it, index included (a skipped axis is strictly below the floor, so it
 * never ties). Cheap upper bounds on the separation along one face, or
 * along every axis an edge of B takes part in, then skip most support
 * queries and Gauss-map walks of a penetrating pair. The bounds come from
 * points known to be in the cores: a ball inside each (along any unit n,
 * min_B n.x <= n.c_B - r_B and max_A n.x >= n.c_A + r_A, c the centroid, r
 * the inner radius) and a few vertices (probes), with a slack for rounding
 * and for the construction tolerance (vertices lie within a few tol of
 * their planes). A warm call that stops on its first axis (apart) pays for
 * none of this. */
static mk_real prune_floor(const sat_ctx *c)
{
    return c->prune && c->lo > -MK_REAL_MAX ? c->lo - (c->rel * mk_fabs_(c->lo) + c->abs_band) : -MK_REAL_MAX;
}

static void prune_init(sat_ctx *c, const mk_sat_options *opt)
{
    const mk_hull *a = c->a, *b = c->b;
    mk_real scale = mk_v3_len(c->t) + mk_v3_len(a->centroid) + mk_v3_len(b->centroid) + a->outer_radius + b->outer_radius;
    mk_real slack = MK_REAL(1024.0) * MK_REAL_EPSILON * scale + 8 * (a->tolerance + b->tolerance);
    /* the six axis-extreme vertices stored after the neighbour lists */
    const uint16_t *xa = a->adjacency + a->adjacency[a->vertex_count], *xb = b->adjacency + b->adjacency[b->vertex_count];
    int banded = opt->prefer != MK_SAT_NONE, k;
    c->ca = a->centroid;
    c->cb = mk_v3_add(mk_mat3_mul_v3(c->R, b->centroid), c->t);
    c->ca_in_b = mk_mat3_tmul_v3(c->R, mk_v3_sub(c->ca, c->t));
    c->ra = a->inner_radius - slack;
    c->rb = b->inner_radius - slack;
    c->rel = banded ? opt->prefer_rel : 0;
    c->abs_band = banded ? opt->prefer_abs : 0;
    /* A band this wide (or not a number) prunes nothing. */
    c->prune = c->rel < 1 && c->abs_band < MK_REAL_MAX;
    c->slack = slack;
    for (k = 0; k < 6; ++k) {
        c->pb[k] = mk_v3_add(mk_mat3_mul_v3(c->R, b->vertices[xb[k]]), c->t);
        c->pa_in_b[k] = mk_mat3_tmul_v3(c->R, mk_v3_sub(a->vertices[xa[k]], c->t));
    }
    c->pb[6] = c->pb[0]; /* until prune_seed finds better */
    c->pa_in_b[6] = c->pa_in_b[0];
}

/* Is the plane (n, d) below the floor for a core whose points include the
 * ball (c, r) and the probes p[0 .. SAT_PROBES), all in the plane's frame? Its lowest
 * point is no higher than any of them: min n.x - d <= n.c - r - d and
 * <= n.p_k - d. The ball bounds faces facing away; the probes, a rough
 * outline of the core, bound the rest better on elongated cores. */
static int plane_below(const sat_ctx *c, mk_vec3 n, mk_real d, mk_vec3 centre, mk_real r, const mk_vec3 *p)
{
    mk_real floor = prune_floor(c) + d, low;
    int k;
    if (mk_v3_dot(n, centre) - r < floor) return 1;
    low = mk_v3_dot(n, p[0]);
    for (k = 1; k < SAT_PROBES; ++k) low = mk_min(low, mk_v3_dot(n, p[k]));
    return low + c->slack < floor;
}

/* Is A's face i below the floor? Its separation is min_B n.x - d. */
static int face_a_pruned(const sat_ctx *c, int i)
{
    const mk_plane *pl = &c->a->planes[i];
    return plane_below(c, pl->normal, pl->offset, c->cb, c->rb, c->pb);
}

/* Is B's face f below the floor? The separation along its normal m (A's
 * frame) negated is min_A m.x - (m.t + d), the same in B's frame: no
 * rotation for a face that is skipped. */
static int face_b_pruned(const sat_ctx *c, int f)
{
    const mk_plane *pl = &c->b->planes[f];
    return plane_below(c, pl->normal, pl->offset, c->ca_in_b, c->ra, c->pa_in_b);
}

/* Is n.D below `level` for every unit n on the arc from u = -n1 to v = -n2?
 * On it n.D is at most max(u.D, v.D) when that is negative, else that over
 * cos(theta / 2), theta the arc's angle, cos^2(theta / 2) = (1 + u.v) / 2,
 * and never more than |D|. */
static int arc_below(mk_vec3 n1, mk_vec3 n2, mk_vec3 D, mk_real level)
{
    mk_real m = -mk_min(mk_v3_dot(n1, D), mk_v3_dot(n2, D));
    if (m < 0) return m < level;
    if (!(level > 0)) return 0;
    /* m / cos(theta / 2) < level, squared; or |D| < level */
    return m * m < level * level * (1 + mk_v3_dot(n1, n2)) * MK_REAL(0.5) || mk_v3_len2(D) < level * level;
}

/* Are all the axes of B's half-edge j below the floor? Each is a unit n
 * with the edge B's support edge along -n, so min_B n.x = n.q (q on the
 * edge) and the separation is at most n.(q - x) for any point x of A: for
 * the ball, n.(q - c_A) - r_A, and for each probe a_k, n.(q - a_k); n lies
 * on the arc from -n1 to -n2 (the edge's face normals). All of it in B's
 * frame (dot products do not see the rotation), so a skipped edge costs no
 * transform. An axis the Gauss-map test cannot call (parallel features)
 * can lie off the arc by the test's tolerance, a few hundred eps of |D|,
 * which the slack covers. */
static int edge_b_pruned(const sat_ctx *c, int j)
{
    const mk_hull *b = c->b;
    const mk_hull_edge *E = &b->edges[j];
    mk_vec3 n1 = b->planes[E->face].normal, n2 = b->planes[b->edges[E->twin].face].normal, q = b->vertices[E->origin];
    mk_real floor = prune_floor(c);
    int k;
    if (!(floor > -MK_REAL_MAX)) return 0;
    if (arc_below(n1, n2, mk_v3_sub(q, c->ca_in_b), floor + c->ra)) return 1;
    for (k = 0; k < SAT_PROBES; ++k)
        if (arc_below(n1, n2, mk_v3_sub(q, c->pa_in_b[k]), floor - c->slack)) return 1;
    return 0;
}

/* A seed for lo: the separations along the face of A that faces B's
 * centroid most and the face of B that faces A's most. Both are axes mk_sat
 * tests anyway (so lo stays <= best); they are measured, not offered, so
 * the search below still finds every axis in its usual order. The vertex of
 * each core found deepest under the other's seed face, near where they
 * touch, is the last probe. */
static void prune_seed(sat_ctx *c)
{
    const mk_hull *a = c->a, *b = c->b;
    mk_vec3 d = mk_v3_sub(c->cb, c->ca), db = mk_mat3_tmul_v3(c->R, mk_v3_neg(d)), m;
    int i, fa = 0, fb = 0, v;
    mk_real best_a = -MK_REAL_MAX, best_b = -MK_REAL_MAX, s;
    for (i = 0; i < a->face_count; ++i)
        if ((s = mk_v3_dot(a->planes[i].normal, d)) > best_a) best_a = s, fa = i;
    for (i = 0; i < b->face_count; ++i)
        if ((s = mk_v3_dot(b->planes[i].normal, db)) > best_b) best_b = s, fb = i;
    v = mk_hull_support_index(b, mk_mat3_tmul_v3(c->R, mk_v3_neg(a->planes[fa].normal)), -1);
    c->pb[6] = mk_v3_add(mk_mat3_mul_v3(c->R, b->vertices[v]), c->t);
    s = mk_v3_dot(a->planes[fa].normal, c->pb[6]) - a->planes[fa].offset;
    m = mk_mat3_mul_v3(c->R, b->planes[fb].normal);
    v = mk_hull_support_index(a, mk_v3_neg(m), -1);
    c->pa_in_b[6] = mk_mat3_tmul_v3(c->R, mk_v3_sub(a->vertices[v], c->t));
    c->lo = mk_max(c->lo, mk_max(s, mk_v3_dot(m, mk_v3_sub(a->vertices[v], c->t)) - b->planes[fb].offset));
}

/* Separation along A's face normals. Consecutive faces' answers are close,
 * so each support query starts from the last one. */
static void faces_of_a(sat_ctx *c)
{
    int i, hint = -1;
    for (i = 0; i < c->a->face_count && !c->stopped; ++i)
        if (!face_a_pruned(c, i)) face_of_a(c, i, &hint);
}

/* Separation along B's face f (normal m in A's frame): the deepest vertex
 * of A under it, searched from *hint, which is then that vertex. */
static void face_of_b(sat_ctx *c, int f, mk_vec3 m, int *hint)
{
    int u = *hint = mk_hull_support_index(c->a, mk_v3_neg(m), *hint);
    offer(c, &c->face_b, mk_v3_dot(m, mk_v3_sub(c->a->vertices[u], c->t)) - c->b->planes[f].offset, -1, f, mk_v3_neg(m));
}

/* Separation of the cores along the unit axis n, from the support points:
 * valid for any axis, used where the Gauss-map test is too close to call. */
static mk_real support_separation(const sat_ctx *c, mk_vec3 n)
{
    int u = mk_hull_support_index(c->a, n, -1);
    int v = mk_hull_support_index(c->b, mk_mat3_tmul_v3(c->R, mk_v3_neg(n)), -1);
    mk_vec3 w = mk_v3_add(mk_mat3_mul_v3(c->R, c->b->vertices[v]), c->t);
    return mk_v3_dot(n, mk_v3_sub(w, c->a->vertices[u]));
}

/* Gauss-map test, one sign at a time. Edge eA of A runs between faces with
 * normals na (on its left, the face of the half-edge) and nb, so its arc on
 * the unit sphere goes from na to nb and eA is parallel to na x nb; likewise
 * eB, nc, nd for B, whose arc in A - B is the negated one, from -nc to -nd.
 * The arcs cross (the edges make a face of A - B) iff -nc and -nd lie on
 * opposite sides of A's great circle, na and nb on opposite sides of B's, and
 * the crossing is on the same side of both, not at antipodes:
 *   (nc.eA)(nd.eA) < 0,  (na.eB)(nb.eB) < 0,  (nc.eA)(nb.eB) < 0.
 * Returns 1 for a clear face, 0 for a clear non-face, -1 when a sign is within
 * rounding of zero. */
static int gauss_sign(mk_real x, mk_real scale) { return x > scale ? 1 : x < -scale ? -1 : 0; }

static int minkowski_face(mk_real c_ea, mk_real d_ea, mk_real a_eb, mk_real b_eb, mk_real sa, mk_real sb)
{
    int sc = gauss_sign(c_ea, sa), sd = gauss_sign(d_ea, sa), s1 = gauss_sign(a_eb, sb), s2 = gauss_sign(b_eb, sb);
    if (sc * sd > 0 || s1 * s2 > 0 || sc * s2 > 0) return 0;
    return (sc && sd && s1 && s2) ? 1 : -1;
}

/* Separation along the cross product of edge A (p0 -> p0 + ea, between faces
 * na and nb) and edge B (q0 -> q0 + eb, A's frame). The axis points into the
 * arc of A's edge (na + nb side), i.e. out of A. The separation is measured
 * from p0 to the foot of p0 on B's line: that vector is nearly along the axis,
 * so the error of the axis direction (about eps / angle between the edges)
 * costs almost nothing even for edges close to parallel. */
static int edge_axis(mk_vec3 p0, mk_vec3 ea, mk_vec3 na, mk_vec3 nb, mk_vec3 q0, mk_vec3 eb, mk_vec3 *n, mk_real *sep)
{
    mk_vec3 L = mk_v3_cross(ea, eb), foot;
    mk_real l2 = mk_v3_len2(L), ea2 = mk_v3_len2(ea), eb2 = mk_v3_len2(eb), l;
    if (!(l2 > MK_SAT_PARALLEL * MK_SAT_PARALLEL * ea2 * eb2)) return 0;
    l = mk_sqrt_(l2);
    if (mk_v3_dot(L, mk_v3_add(na, nb)) < 0) l = -l;
    *n = mk_v3_scale(L, 1 / l);
    foot = mk_v3_mad(q0, mk_v3_dot(mk_v3_sub(p0, q0), eb) / eb2, eb);
    *sep = mk_v3_dot(*n, mk_v3_sub(foot, p0));
    return 1;
}

static void prepare_edge(const mk_hull *h, int i, sat_edge *x)
{
    const mk_hull_edge *E = &h->edges[i];
    x->p = h->vertices[E->origin];
    x->e = mk_v3_sub(h->vertices[h->edges[E->twin].origin], x->p);
    x->n1 = h->planes[E->face].normal;
    x->n2 = h->planes[h->edges[E->twin].face].normal;
    x->tol = SAT_SIGN_TOL * mk_v3_max_abs(x->e);
    x->index = E->twin < i ? E->twin : i; /* an edge is named by its lower half-edge */
}

/* Offers the pair's axis if the Gauss-map test lets it through; returns the
 * test's verdict (1 face, 0 not, -1 too close to call). */
static int pair(sat_ctx *c, const sat_edge *ea, const sat_edge *eb)
{
    mk_vec3 n;
    mk_real sep;
    int face = minkowski_face(mk_v3_dot(eb->n1, ea->e), mk_v3_dot(eb->n2, ea->e), mk_v3_dot(ea->n1, eb->e),
                              mk_v3_dot(ea->n2, eb->e), ea->tol, eb->tol);
    if (face && edge_axis(ea->p, ea->e, ea->n1, ea->n2, eb->p, eb->e, &n, &sep)) {
        if (face < 0) sep = support_separation(c, n); /* not surely a face: measure honestly */
        offer(c, &c->edges, sep, ea->index, eb->index, n);
    }
    return face;
}

/* Every edge of A against B's edge eb: the fallback of walk(). */
static void scan(sat_ctx *c, const sat_edge *eb)
{
    const mk_hull *a = c->a;
    int i;
    for (i = 0; i < a->edge_count && !c->stopped; ++i)
        if (a->edges[i].twin > i) {
            sat_edge ea;
            prepare_edge(a, i, &ea);
            pair(c, &ea, eb);
        }
}

/* The edges of A whose Gauss-map arcs B's edge eb crosses, found by walking
 * A's Gauss map (Gregorius; cf. "Gauss map traversal") instead of testing all
 * of them. A's vertex v owns the region of directions along which it is the
 * support; the region is bounded by the arcs of v's edges. eb's arc runs from
 * -n1 to -n2 (its faces' normals, negated for A - B) and starts in the region
 * of v, the support of A along -n1. A great arc shorter than a half circle
 * leaves a convex region once, so at each vertex one edge at most (other than
 * the one we came in by) is crossed: that pair is a face of A - B, and the
 * walk goes on from the edge's other end, until the arc ends inside a region.
 * This costs a few vertices of A per edge of B instead of all of A's edges.
 * Returns 0 when a sign test is too close to call (the arc passes through a
 * face normal of A, as between parallel faces) or the walk goes astray; the
 * caller then scans every edge of A for this one. */
static int walk(sat_ctx *c, const sat_edge *eb, int v)
{
    const mk_hull *a = c->a;
    int from = -1, steps = 0;
    while (!c->stopped) {
        int e0 = a->vertex_edge[v], e = e0, next = -1, through = -1;
        mk_vec3 pv = a->vertices[v];
        do {
            const mk_hull_edge *E = &a->edges[e];
            int t = E->twin, und = e < t ? e : t;
            if (und != from) {
                /* The first sign test inline, before anything else is loaded:
                 * it rejects most of the edges around a vertex. */
                mk_vec3 ea = mk_v3_sub(a->vertices[a->edges[t].origin], pv);
                mk_real s1 = mk_v3_dot(eb->n1, ea), s2 = mk_v3_dot(eb->n2, ea), tol = SAT_SIGN_TOL * mk_v3_max_abs(ea);
                if (!((s1 > tol && s2 > tol) || (s1 < -tol && s2 < -tol))) {
                    sat_edge x;
                    int face;
                    x.p = pv;
                    x.e = ea;
                    x.n1 = a->planes[E->face].normal;
                    x.n2 = a->planes[a->edges[t].face].normal;
                    x.tol = tol;
                    x.index = und;
                    face = pair(c, &x, eb);
                    if (face < 0 || (face > 0 && next >= 0)) return 0;
                    if (face > 0) next = a->edges[t].origin, through = und;
                }
            }
            e = a->edges[t].next;
        } while (e != e0);
        if (next < 0) return 1;
        if (++steps > a->vertex_count) return 0;
        v = next;
        from = through;
    }
    return 1;
}

/* B's half-edge j as a sat_edge in A's frame; n1 is its own face's normal
 * there (the caller has it). */
static void edge_of_b(const sat_ctx *c, int j, mk_vec3 n1, sat_edge *eb)
{
    prepare_edge(c->b, j, eb);
    eb->p = mk_v3_add(mk_mat3_mul_v3(c->R, eb->p), c->t);
    eb->e = mk_mat3_mul_v3(c->R, eb->e);
    eb->n1 = n1;
    eb->n2 = mk_mat3_mul_v3(c->R, eb->n2);
}

/* B's faces, then B's edges face by face: the support of A along -n_f that
 * measures the separation along B's face f is also where the Gauss-map walk
 * of each of f's edges starts (their arcs begin at -n_f); it is found only
 * when the face or one of its edges is above the pruning floor. */
static void faces_and_edges_of_b(sat_ctx *c)
{
    const mk_hull *b = c->b;
    int f, hint = -1;
    for (f = 0; f < b->face_count && !c->stopped; ++f) {
        mk_vec3 m = mk_mat3_mul_v3(c->R, b->planes[f].normal);
        int j0 = b->face_edge[f], j = j0, u = -1;
        if (!face_b_pruned(c, f)) {
            face_of_b(c, f, m, &hint);
            u = hint;
        }
        do {
            /* each edge once, from the face of its lower half-edge */
            if (b->edges[j].twin > j && !c->stopped && !edge_b_pruned(c, j)) {
                sat_edge eb;
                edge_of_b(c, j, m, &eb);
                if (u < 0) u = hint = mk_hull_support_index(c->a, mk_v3_neg(m), hint);
                if (!walk(c, &eb, u)) scan(c, &eb);
            }
            j = b->edges[j].next;
        } while (j != j0);
    }
}

static void ctx_init(sat_ctx *c, const mk_mat3 *R, mk_vec3 t, const mk_sat_options *opt)
{
    c->R = *R;
    c->t = t;
    c->stop = opt->stop_above;
    c->stopped = 0;
    c->lo = -MK_REAL_MAX;
    axis_none(&c->face_a);
    axis_none(&c->face_b);
    axis_none(&c->edges);
}

static void finish(const sat_ctx *c, const mk_sat_options *opt, mk_sat_result *out)
{
    mk_sat_kind kind = mk_sat_choose(c->face_a.sep, c->face_b.sep, c->edges.sep, c->edges.a >= 0, c->stopped, opt, out);
    const sat_axis *pick = kind == MK_SAT_FACE_A ? &c->face_a : kind == MK_SAT_FACE_B ? &c->face_b : &c->edges;
    out->kind = kind;
    out->a = pick->a;
    out->b = pick->b;
    out->separation = pick->sep;
    out->normal = pick->n;
}

/* The separation along the axis opt->first names (a face of A or of B,
 * or an edge pair); 1 if it ends the search (offered to its kind). */
static int first_axis(sat_ctx *c, const mk_sat_options *opt)
{
    const mk_hull *a = c->a, *b = c->b;
    int hint = -1;
    mk_vec3 m;
    if (opt->first == MK_SAT_FACE_A && opt->first_a >= 0 && opt->first_a < a->face_count) {
        face_of_a(c, opt->first_a, &hint);
    } else if (opt->first == MK_SAT_FACE_B && opt->first_b >= 0 && opt->first_b < b->face_count) {
        face_of_b(c, opt->first_b, mk_mat3_mul_v3(c->R, b->planes[opt->first_b].normal), &hint);
    } else if (opt->first == MK_SAT_EDGES && opt->first_a >= 0 && opt->first_a < a->edge_count && opt->first_b >= 0 &&
               opt->first_b < b->edge_count) {
        sat_edge ea, eb;
        mk_real sep;
        prepare_edge(a, opt->first_a, &ea);
        edge_of_b(c, opt->first_b, mk_mat3_mul_v3(c->R, b->planes[b->edges[opt->first_b].face].normal), &eb);
        /* Measured by the support points, as any axis may be. */
        if (edge_axis(ea.p, ea.e, ea.n1, ea.n2, eb.p, eb.e, &m, &sep)) offer(c, &c->edges, support_separation(c, m), ea.index, eb.index, m);
    }
    if (!c->stopped) {
        /* Not apart along it: forget it, so the full search answers exactly
         * as without the hint; a face's separation stays as the pruning
         * floor's lo (an edge pair's axis may not be one mk_sat tests, and
         * could then separate by more than best). */
        c->lo = mk_max(c->face_a.sep, c->face_b.sep);
        axis_none(&c->face_a);
        axis_none(&c->face_b);
        axis_none(&c->edges);
    }
    return c->stopped;
}

void mk_sat(const mk_hull *a, const mk_hull *b, const mk_mat3 *R, mk_vec3 t, const mk_sat_options *opt, mk_sat_result *out)
{
    sat_ctx c;
    ctx_init(&c, R, t, opt);
    c.a = a;
    c.b = b;
    if (opt->first != MK_SAT_NONE && first_axis(&c, opt)) {
        finish(&c, opt, out);
        return;
    }
    prune_init(&c, opt);
    if (c.prune) prune_seed(&c);
    faces_of_a(&c);
    faces_and_edges_of_b(&c);
    finish(&c, opt, out);
}

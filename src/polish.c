/* polish.c: candidate normals from original feature geometry, best separation wins. */
#include "polish.h"

/* Distinct core vertices of one shape in a simplex, with their positions in
 * A's frame and, for B, in B's own frame (edges are differenced there, before
 * the rotation, so an axis-aligned box edge stays exactly axis-aligned). */
typedef struct feature_set {
    int n;
    int idx[4];
    mk_vec3 local[4];
} feature_set;

static int collect(const mk_shape *s, const mk_cso_vertex *v, int n, int use_b, feature_set *f)
{
    int k, j;
    f->n = 0;
    for (k = 0; k < n; ++k) {
        int i = use_b ? v[k].ib : v[k].ia, dup = 0;
        if (i < 0) return 0; /* a smooth support point: no feature to name */
        for (j = 0; j < f->n; ++j) dup = dup || f->idx[j] == i;
        if (!dup) {
            f->idx[f->n] = i;
            f->local[f->n] = mk_core_vertex(s, i);
            f->n++;
        }
    }
    return 1;
}

static int hull_face_has(const mk_hull *h, int face, int vtx)
{
    int e0 = h->face_edge[face], e = e0, guard = h->edge_count;
    do {
        if (h->edges[e].origin == vtx) return 1;
        e = h->edges[e].next;
    } while (e != e0 && --guard > 0);
    return 0;
}

/* Outward unit normal (shape frame) of a face holding vertices i, j, k; 0 if none does. */
static int face_normal(const mk_shape *s, int i, int j, int k, mk_vec3 *n)
{
    if (s->type == MK_SHAPE_BOX) {
        int agree = ~(i ^ j) & ~(i ^ k) & 7, ax;
        for (ax = 0; ax < 3; ++ax) {
            if (agree & (1 << ax)) {
                mk_real sg = (i & (1 << ax)) ? 1 : -1;
                *n = mk_v3(ax == 0 ? sg : 0, ax == 1 ? sg : 0, ax == 2 ? sg : 0);
                return 1;
            }
        }
        return 0;
    }
    if (s->type == MK_SHAPE_HULL) {
        const mk_hull *h = s->u.hull;
        int e0 = h->vertex_edge[i], e = e0, guard = h->edge_count;
        do { /* faces around vertex i */
            int f = h->edges[e].face;
            if (hull_face_has(h, f, j) && hull_face_has(h, f, k)) {
                *n = h->planes[f].normal;
                return 1;
            }
            e = h->edges[h->edges[e].twin].next;
        } while (e != e0 && --guard > 0);
    }
    return 0;
}

typedef struct best_sep {
    const mk_pair *p;
    mk_vec3 hint, normal;
    mk_real sep;
    int ha, hb;
} best_sep;

/* Orients c like the hint, normalises it and keeps it if it separates better. */
static void try_normal(best_sep *b, mk_vec3 c)
{
    mk_real l = mk_v3_len(c), s;
    if (!(l > 0)) return;
    c = mk_v3_scale(c, (mk_v3_dot(c, b->hint) < 0 ? -1 : 1) / l);
    s = mk_pair_separation(b->p, c, &b->ha, &b->hb);
    if (s > b->sep) {
        b->sep = s;
        b->normal = c;
    }
}

/* Faces of a shape spanned by any three of its vertices in the set. */
static void try_faces(best_sep *b, const mk_shape *s, const feature_set *f, int of_b)
{
    int i, j, k;
    for (i = 0; i < f->n; ++i)
        for (j = i + 1; j < f->n; ++j)
            for (k = j + 1; k < f->n; ++k) {
                mk_vec3 n;
                if (face_normal(s, f->idx[i], f->idx[j], f->idx[k], &n))
                    try_normal(b, of_b ? mk_mat3_mul_v3(b->p->r, n) : n);
            }
}

/* Edge-edge: the cross product of the two original edges. Nearly parallel
 * edges give a noisy cross product, but a bad candidate can only lose. */
static void try_edge_pairs(best_sep *b, const feature_set *fa, const feature_set *fb)
{
    int i, j, k, m;
    for (i = 0; i < fa->n; ++i)
        for (j = i + 1; j < fa->n; ++j) {
            mk_vec3 ea = mk_v3_sub(fa->local[j], fa->local[i]);
            for (k = 0; k < fb->n; ++k)
                for (m = k + 1; m < fb->n; ++m) {
                    mk_vec3 eb = mk_mat3_mul_v3(b->p->r, mk_v3_sub(fb->local[m], fb->local[k]));
                    try_normal(b, mk_v3_cross(ea, eb));
                }
        }
}

/* Vertex-edge: the perpendicular from the edge's line to the vertex (both in A's frame). */
static void try_vertex_edges(best_sep *b, mk_vec3 q, const mk_vec3 *e, int n)
{
    int i, j;
    for (i = 0; i < n; ++i)
        for (j = i + 1; j < n; ++j) {
            mk_vec3 u = mk_v3_sub(e[j], e[i]), r = mk_v3_sub(q, e[i]);
            mk_real uu = mk_v3_len2(u);
            if (uu > 0) try_normal(b, mk_v3_mad(r, -mk_v3_dot(r, u) / uu, u));
        }
}

mk_real mk_polish(const mk_pair *p, const mk_cso_vertex *v, int n, mk_real sep, mk_vec3 *normal)
{
    feature_set fa, fb;
    mk_vec3 wa[4], wb[4];
    best_sep b;
    int k;
    b.p = p;
    b.hint = *normal;
    b.normal = *normal;
    b.sep = sep;
    b.ha = n > 0 ? v[0].ia : -1;
    b.hb = n > 0 ? v[0].ib : -1;
    if (n < 1 || !collect(p->a, v, n, 0, &fa) || !collect(p->b, v, n, 1, &fb)) return sep;
    for (k = 0; k < fa.n; ++k) wa[k] = fa.local[k];
    for (k = 0; k < fb.n; ++k) wb[k] = mk_v3_add(mk_mat3_mul_v3(p->r, fb.local[k]), p->t);
    try_faces(&b, p->a, &fa, 0);
    try_faces(&b, p->b, &fb, 1);
    try_edge_pairs(&b, &fa, &fb);
    if (fa.n == 1) try_vertex_edges(&b, wa[0], wb, fb.n);
    if (fb.n == 1) try_vertex_edges(&b, wb[0], wa, fa.n);
    if (fa.n == 1 && fb.n == 1) try_normal(&b, mk_v3_sub(wb[0], wa[0]));
    *normal = b.normal;
    return b.sep;
}

void mk_polish_witness(mk_vec3 pa, mk_vec3 pb, mk_real d, mk_vec3 n, mk_vec3 *a, mk_vec3 *b)
{
    mk_vec3 m = mk_v3_scale(mk_v3_add(pa, pb), MK_REAL(0.5));
    *a = mk_v3_mad(m, -MK_REAL(0.5) * d, n);
    *b = mk_v3_mad(m, MK_REAL(0.5) * d, n);
}

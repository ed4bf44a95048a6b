/* epa.c: expanding polytope with silhouette removal, fixed capacity. */
#include "epa.h"

/* Indices are 16-bit: capacities stay far below 32767, and the face array
 * is most of EPA's stack. */
typedef struct epa_face {
    short v[3];            /* counter-clockwise seen from outside */
    short adj[3];          /* face across edge (v[i], v[i+1]) */
    unsigned char edge[3]; /* index of that edge in the adjacent face */
    unsigned char live;
    mk_vec3 n;             /* unit outward normal */
    mk_real dist;          /* n . (any vertex): distance of the plane from the origin */
} epa_face;

typedef struct epa_poly {
    const mk_pair *p;
    mk_real tol;           /* absolute rounding floor: MK_GJK_ABS_TOL * scale */
    int nv, nf, nfree;
    mk_cso_vertex v[MK_EPA_MAX_VERTICES];
    epa_face f[MK_EPA_MAX_FACES];
    short free_faces[MK_EPA_MAX_FACES];
} epa_poly;

/* Face f over silhouette edge (a, b) and apex w, given d_a = a - w and
 * d_b = b - w (each shared by the two new faces at that vertex): normal
 * d_a x d_b = (b - a) x (w - a). 0 if it is degenerate or has the origin clearly
 * outside (an inverted face): the polytope would be invalid. Inlined: as a
 * call it cost 5-7 % of a penetrating hull query (callgrind, bench_narrow). */
MK_ALWAYS_INLINE int fan_face(epa_poly *P, int f, int a, int b, int wi, mk_vec3 da, mk_vec3 db)
{
    epa_face *F = &P->f[f];
    mk_vec3 n = mk_v3_cross(da, db);
    mk_real l2 = mk_v3_len2(n);
    F->v[0] = (short)a;
    F->v[1] = (short)b;
    F->v[2] = (short)wi;
    F->live = 1;
    if (!(l2 > 0)) return 0;
    F->n = mk_v3_scale(n, 1 / mk_sqrt_(l2));
    /* The plane through the centroid w + (d_a + d_b) / 3: it favours no
     * vertex (a distance only ranks faces and stops the loop; the answer is
     * re-evaluated by the support functions). */
    F->dist = mk_v3_dot(F->n, P->v[wi].w) + mk_v3_dot(F->n, mk_v3_add(da, db)) * (MK_REAL(1.0) / 3);
    return F->dist >= -P->tol;
}

static int face_alloc(epa_poly *P)
{
    if (P->nfree > 0) return P->free_faces[--P->nfree];
    return P->nf < MK_EPA_MAX_FACES ? P->nf++ : -1;
}

static void link(epa_poly *P, int f, int i, int g, int j)
{
    P->f[f].adj[i] = (short)g;
    P->f[f].edge[i] = (unsigned char)j;
    P->f[g].adj[j] = (short)f;
    P->f[g].edge[j] = (unsigned char)i;
}

/* Adds the support point farthest from the affine hull of t[0..n) among
 * the directions dirs; 0 if none leaves it by more than tol. */
static int grow(const mk_pair *p, mk_cso_vertex *t, int n, const mk_vec3 *dirs, int nd, mk_real tol)
{
    mk_real best = tol;
    int k, found = 0;
    for (k = 0; k < nd; ++k) {
        mk_cso_vertex w = mk_pair_support(p, dirs[k], t[0].ia, t[0].ib);
        mk_vec3 r = mk_v3_sub(w.w, t[0].w);
        mk_real off;
        if (n == 1) {
            off = mk_v3_len(r);
        } else if (n == 2) {
            mk_vec3 e = mk_v3_normalize(mk_v3_sub(t[1].w, t[0].w));
            off = mk_v3_len(mk_v3_cross(r, e));
        } else {
            mk_vec3 m = mk_v3_normalize(mk_v3_cross(mk_v3_sub(t[1].w, t[0].w), mk_v3_sub(t[2].w, t[0].w)));
            off = mk_fabs_(mk_v3_dot(r, m));
        }
        if (off > best) {
            best = off;
            t[n] = w;
            found = 1;
        }
    }
    return found;
}

/* GJK may stop on a point, segment or triangle through the origin (touching
 * shapes); complete it to a tetrahedron with volume by supports along
 * directions that leave its affine hull. */
static int blow_up(const mk_pair *p, const mk_simplex *s, mk_real tol, mk_cso_vertex *t)
{
    int n = s->n, k;
    for (k = 0; k < n; ++k) t[k] = s->v[k];
    if (n == 1) {
        const mk_vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
        if (!grow(p, t, 1, axes, 6, tol)) return 0;
        n = 2;
    }
    if (n == 2) {
        mk_vec3 e = mk_v3_normalize(mk_v3_sub(t[1].w, t[0].w)), u = mk_v3_perp(e), v = mk_v3_cross(e, u), dirs[6];
        dirs[0] = u;
        dirs[1] = mk_v3_neg(u);
        dirs[2] = v;
        dirs[3] = mk_v3_neg(v);
        dirs[4] = mk_v3_add(u, v);
        dirs[5] = mk_v3_neg(dirs[4]);
        if (!grow(p, t, 2, dirs, 6, tol)) return 0;
        n = 3;
    }
    if (n == 3) {
        mk_vec3 dirs[2];
        dirs[0] = mk_v3_cross(mk_v3_sub(t[1].w, t[0].w), mk_v3_sub(t[2].w, t[0].w));
        dirs[1] = mk_v3_neg(dirs[0]);
        if (!grow(p, t, 3, dirs, 2, tol)) return 0;
    }
    return 1;
}

/* The tetrahedron blow_up left in P->v[0..4), turned to negative volume. */
static int init_tetrahedron(epa_poly *P)
{
    static const int faces[4][3] = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
    /* For edge i of face k: the face across it and that edge's index there. */
    static const int across[4][3][2] = {{{1, 2}, {3, 2}, {2, 0}}, {{2, 2}, {3, 0}, {0, 0}},
                                        {{0, 2}, {3, 1}, {1, 0}}, {{1, 1}, {2, 1}, {0, 1}}};
    mk_cso_vertex *t = P->v;
    mk_vec3 e1 = mk_v3_sub(t[1].w, t[0].w), e2 = mk_v3_sub(t[2].w, t[0].w), e3 = mk_v3_sub(t[3].w, t[0].w);
    int k, ok = 1;
    P->nv = 4;
    P->nf = 4;
    P->nfree = 0;
    /* Negative volume makes every face of `faces` point away from its opposite vertex. */
    if (mk_v3_dot(e1, mk_v3_cross(e2, e3)) > 0) {
        mk_cso_vertex x = t[1];
        t[1] = t[2];
        t[2] = x;
    }
    for (k = 0; k < 4; ++k) {
        int i;
        ok = fan_face(P, k, faces[k][0], faces[k][1], faces[k][2], mk_v3_sub(P->v[faces[k][0]].w, P->v[faces[k][2]].w),
                      mk_v3_sub(P->v[faces[k][1]].w, P->v[faces[k][2]].w)) && ok;
        /* each face's own side of link(): the table holds both sides */
        for (i = 0; i < 3; ++i) {
            P->f[k].adj[i] = (short)across[k][i][0];
            P->f[k].edge[i] = (unsigned char)across[k][i][1];
        }
    }
    return ok;
}

/* A plain minimum over every slot: removed faces carry dist = +inf (see
 * expand), so the loop has no live test and keeps the best in a register
 * instead of reloading it through the index it just picked. */
static int nearest_face(const epa_poly *P)
{
    int f, best = 0;
    mk_real bd = P->f[0].dist;
    for (f = 1; f < P->nf; ++f)
        if (P->f[f].dist < bd) bd = P->f[f].dist, best = f;
    return best;
}

static int known_vertex(const epa_poly *P, const mk_cso_vertex *w)
{
    int k;
    if (w->ia < 0 || w->ib < 0) return 0;
    for (k = 0; k < P->nv; ++k)
        if (P->v[k].ia == w->ia && P->v[k].ib == w->ib) return 1;
    return 0;
}

/* The hole a new vertex w cuts: the faces it sees, and the silhouette edges
 * (a_k -> b_k of a removed face, across which face g_k keeps edge j_k) in
 * order around the hole. */
typedef struct epa_hole {
    mk_vec3 w;
    int nr, nh;
    short removed[MK_EPA_MAX_FACES], g[MK_EPA_MAX_FACES], a[MK_EPA_MAX_FACES], b[MK_EPA_MAX_FACES];
    unsigned char j[MK_EPA_MAX_FACES];
} epa_hole;

static const unsigned char next3[3] = {1, 2, 0};

static int sees(const epa_poly *P, int f, mk_vec3 w)
{
    return mk_v3_dot(P->f[f].n, w) - P->f[f].dist > P->tol;
}

/* Removes every face that sees w, reachable from f0 (which does) by a depth
 * first flood over the adjacency, and returns the number of silhouette
 * edges (removed face to kept face); *sf, *si: one of them. */
static int remove_visible(epa_poly *P, epa_hole *H, int f0, int *sf, int *si)
{
    short stack[MK_EPA_MAX_FACES];
    int sp = 0, edges = 0;
    P->f[f0].live = 0;
    H->removed[H->nr++] = (short)f0;
    stack[sp++] = (short)f0;
    while (sp > 0) {
        int f = stack[--sp], i;
        for (i = 0; i < 3; ++i) {
            int g = P->f[f].adj[i];
            if (!P->f[g].live) continue;
            if (sees(P, g, H->w)) {
                P->f[g].live = 0;
                H->removed[H->nr++] = (short)g;
                stack[sp++] = (short)g;
            } else {
                *sf = f;
                *si = i;
                edges++;
            }
        }
    }
    return edges;
}

/* The simplest hole, when w sees f0 and none of its neighbours: f0's own
 * three edges, found without the flood and the walk (22-30 % of expansions
 * on the penetrating hull rows of demos/bench_narrow; -1 to -1.6 %
 * instructions per query). Returns 0, with nothing changed, otherwise. */
static int hole_of_one(epa_poly *P, epa_hole *H, int f0)
{
    const epa_face *F = &P->f[f0];
    int i;
    for (i = 0; i < 3; ++i)
        if (sees(P, F->adj[i], H->w)) return 0;
    P->f[f0].live = 0;
    H->removed[0] = (short)f0;
    H->nr = 1;
    for (i = 0; i < 3; ++i) {
        H->g[i] = F->adj[i];
        H->j[i] = F->edge[i];
        H->a[i] = F->v[i];
        H->b[i] = F->v[next3[i]];
    }
    H->nh = 3;
    return 1;
}

/* The silhouette in order around the hole, walked from edge (f, i): after
 * edge a -> b, turn about b through removed faces to the next edge that
 * has a kept face across it. New face k over (a_k, b_k, w) then meets new
 * face k + 1 along (b_k, w), with no search. Returns 0 unless the walk
 * closes after every silhouette edge (a hole that is not a disc). */
static int walk_silhouette(const epa_poly *P, epa_hole *H, int f, int i, int edges)
{
    int f0 = f, i0 = i;
    do {
        if (H->nh == edges) return 0;
        H->g[H->nh] = P->f[f].adj[i];
        H->j[H->nh] = P->f[f].edge[i];
        H->a[H->nh] = P->f[f].v[i];
        H->b[H->nh++] = P->f[f].v[next3[i]];
        i = next3[i];
        while (!P->f[P->f[f].adj[i]].live) {
            int g = P->f[f].adj[i];
            i = next3[P->f[f].edge[i]];
            f = g;
        }
    } while (f != f0 || i != i0);
    return H->nh == edges;
}

/* Removes every face vertex wi sees (f0 among them) and fans the silhouette
 * to wi. Returns 0 on a defect (a silhouette that does not close); the
 * polytope is then abandoned, so partial updates do not matter. */
static int expand(epa_poly *P, int f0, int wi)
{
    epa_hole H;
    short nf_new[MK_EPA_MAX_FACES];
    mk_vec3 d0, da;
    int k, edges, sf = 0, si = 0;
    H.w = P->v[wi].w;
    H.nr = H.nh = 0;
    if (!hole_of_one(P, &H, f0)) {
        edges = remove_visible(P, &H, f0, &sf, &si);
        if (edges < 3 || !walk_silhouette(P, &H, sf, si, edges)) return 0;
    }
    for (k = 0; k < H.nr; ++k) {
        P->f[H.removed[k]].dist = (mk_real)HUGE_VAL; /* out of nearest_face's way until reused */
        P->free_faces[P->nfree++] = H.removed[k];
    }
    d0 = da = mk_v3_sub(P->v[H.a[0]].w, H.w);
    for (k = 0; k < H.nh; ++k) {
        int f = face_alloc(P), last = k + 1 == H.nh;
        mk_vec3 db = last ? d0 : mk_v3_sub(P->v[H.b[k]].w, H.w);
        if (f < 0 || !fan_face(P, f, H.a[k], H.b[k], wi, da, db)) return 0;
        link(P, f, 0, H.g[k], H.j[k]);
        nf_new[k] = (short)f;
        da = db;
    }
    /* Close the fan: the face over (a, b) meets the next one, over (b, c), along (b, w). */
    for (k = 0; k < H.nh; ++k) link(P, nf_new[k], 1, nf_new[k + 1 < H.nh ? k + 1 : 0], 2);
    return 1;
}

/* Barycentric coordinates of the origin's projection q = dist n on face F
 * (clamped to it): twice the signed areas n . ((v_j - q) x (v_k - q)), which
 * are n . (v_j x v_k) since q is along n. */
static void face_weights(const epa_poly *P, const epa_face *F, mk_real *l)
{
    mk_vec3 a = P->v[F->v[0]].w, b = P->v[F->v[1]].w, c = P->v[F->v[2]].w;
    mk_real sum;
    int k;
    l[0] = mk_max(0, mk_v3_dot(F->n, mk_v3_cross(b, c)));
    l[1] = mk_max(0, mk_v3_dot(F->n, mk_v3_cross(c, a)));
    l[2] = mk_max(0, mk_v3_dot(F->n, mk_v3_cross(a, b)));
    sum = l[0] + l[1] + l[2];
    for (k = 0; k < 3; ++k) l[k] = sum > 0 ? l[k] / sum : MK_REAL(1.0) / 3;
}

static void answer(const epa_poly *P, const epa_face *F, mk_epa_result *out)
{
    int k;
    for (k = 0; k < 3; ++k) out->face[k] = P->v[F->v[k]];
    face_weights(P, F, out->l);
    out->normal = F->n;
    out->depth = F->dist;
}

static mk_real separation_along(const mk_pair *p, mk_vec3 n, const mk_cso_vertex *hint)
{
    int ha = hint->ia, hb = hint->ib;
    return mk_pair_separation(p, n, &ha, &hb);
}

/* No tetrahedron: the CSO is flat around the origin, so the shapes touch. */
static int flat_answer(const mk_pair *p, const mk_simplex *s, mk_epa_result *out)
{
    int k;
    mk_vec3 n = mk_v3_zero();
    for (k = 0; k < 3; ++k) {
        out->face[k] = s->v[k < s->n ? k : 0];
        out->l[k] = k == 0 ? 1 : 0;
    }
    if (s->n >= 3) n = mk_v3_cross(mk_v3_sub(s->v[1].w, s->v[0].w), mk_v3_sub(s->v[2].w, s->v[0].w));
    if (!(mk_v3_len2(n) > 0)) n = mk_v3_len2(p->t) > 0 ? p->t : mk_v3(1, 0, 0);
    out->normal = mk_v3_normalize(n);
    out->depth = 0;
    out->separation = separation_along(p, out->normal, &out->face[0]);
    out->iterations = 0;
    out->state = MK_SOLVE_DEGENERATE;
    return -1;
}

/* The index of F's vertex highest along n on one side (sign 1: A's point a,
 * -1: B's point b), as that side's support hint. */
MK_ALWAYS_INLINE int highest_hint(const epa_poly *P, const epa_face *F, mk_vec3 n, int side_a)
{
    const mk_cso_vertex *v0 = &P->v[F->v[0]], *v1 = &P->v[F->v[1]], *v2 = &P->v[F->v[2]];
    if (side_a) {
        mk_real d0 = mk_v3_dot(n, v0->a), d1 = mk_v3_dot(n, v1->a), d2 = mk_v3_dot(n, v2->a);
        return d1 > d0 ? (d2 > d1 ? v2->ia : v1->ia) : (d2 > d0 ? v2->ia : v0->ia);
    } else {
        mk_real d0 = mk_v3_dot(n, v0->b), d1 = mk_v3_dot(n, v1->b), d2 = mk_v3_dot(n, v2->b);
        return d1 < d0 ? (d2 < d1 ? v2->ib : v1->ib) : (d2 < d0 ? v2->ib : v0->ib);
    }
}

/* Does the support of s (type t) walk from its hint (hull_support.h)? */
static int climbs(const mk_shape *s, mk_shape_type t)
{
    return t == MK_SHAPE_HULL && s->u.hull->vertex_count > MK_HULL_COLD_SCAN_MAX;
}

/* The support along face F's normal. A hull that climbs starts from the
 * vertex of F highest along the normal on its side (F's vertices are
 * supports along nearby directions, the highest the fewest steps from the
 * new one: hull_hull_128 -3 % instructions); scans and boxes ignore hints. */
MK_ALWAYS_INLINE mk_cso_vertex support_from_face(const mk_pair *p, mk_shape_type ta, mk_shape_type tb, int climb_a,
                                                 int climb_b, const epa_poly *P, const epa_face *F)
{
    int ha = climb_a ? highest_hint(P, F, F->n, 1) : -1, hb = climb_b ? highest_hint(P, F, F->n, 0) : -1;
    return mk_pair_support_typed(p, ta, tb, F->n, ha, hb);
}

/* The loop, inlined into one copy per specialised pair of shape types (as
 * GJK's: the supports lose their type switches) and one generic copy. */
MK_ALWAYS_INLINE int epa_loop(const mk_pair *p, mk_shape_type ta, mk_shape_type tb, const mk_simplex *s, mk_real scale,
                              mk_epa_result *out)
{
    epa_poly P;
    epa_face best;
    int it, climb_a = climbs(p->a, ta), climb_b = climbs(p->b, tb);
    P.p = p;
    P.tol = MK_GJK_ABS_TOL * scale;
    if (!blow_up(p, s, P.tol, P.v) || !init_tetrahedron(&P)) return flat_answer(p, s, out);
    out->state = MK_SOLVE_MAX_ITERATIONS;
    for (it = 0;; ++it) {
        int f = nearest_face(&P);
        mk_cso_vertex w;
        best = P.f[f]; /* expand may reuse f's slot before it finds a defect */
        out->iterations = it + 1;
        if (P.nv == MK_EPA_MAX_VERTICES) break;
        w = support_from_face(p, ta, tb, climb_a, climb_b, &P, &best);
        if (mk_v3_dot(best.n, w.w) - best.dist <= MK_GJK_REL_TOL * best.dist + P.tol || known_vertex(&P, &w)) {
            /* w is the support along the answer's normal: its sep, for free */
            out->separation = -mk_v3_dot(best.n, w.w);
            out->state = MK_SOLVE_CONVERGED;
            answer(&P, &best, out);
            return 0;
        }
        P.v[P.nv] = w;
        if (!expand(&P, f, P.nv++)) {
            out->state = MK_SOLVE_DEGENERATE;
            break;
        }
    }
    answer(&P, &best, out);
    out->separation = separation_along(p, best.n, &out->face[0]);
    return 0;
}

static int epa_hull_hull(const mk_pair *p, const mk_simplex *s, mk_real scale, mk_epa_result *out)
{
    return epa_loop(p, MK_SHAPE_HULL, MK_SHAPE_HULL, s, scale, out);
}

static int epa_hull_box(const mk_pair *p, const mk_simplex *s, mk_real scale, mk_epa_result *out)
{
    return epa_loop(p, MK_SHAPE_HULL, MK_SHAPE_BOX, s, scale, out);
}

static int epa_box_hull(const mk_pair *p, const mk_simplex *s, mk_real scale, mk_epa_result *out)
{
    return epa_loop(p, MK_SHAPE_BOX, MK_SHAPE_HULL, s, scale, out);
}

static int epa_any(const mk_pair *p, const mk_simplex *s, mk_real scale, mk_epa_result *out)
{
    return epa_loop(p, p->a->type, p->b->type, s, scale, out);
}

int mk_epa(const mk_pair *p, const mk_simplex *s, mk_real scale, mk_epa_result *out)
{
    mk_shape_type ta = p->a->type, tb = p->b->type;
    if (ta == MK_SHAPE_HULL && tb == MK_SHAPE_HULL) return epa_hull_hull(p, s, scale, out);
    if (ta == MK_SHAPE_HULL && tb == MK_SHAPE_BOX) return epa_hull_box(p, s, scale, out);
    if (ta == MK_SHAPE_BOX && tb == MK_SHAPE_HULL) return epa_box_hull(p, s, scale, out);
    return epa_any(p, s, scale, out);
}

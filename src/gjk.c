/* gjk.c: GJK distance on the cores, signed-volumes sub-algorithm, warm start. */
#include "gjk.h"
/* cos^2 of the largest turn of the search direction after which the
 * supports still start from the previous vertices (hull_support.h): 60
 * degrees. Past it a climb is long and a scan (small hulls) or a cold
 * start is cheaper (a limit of 26 degrees measured the same). */
#define MK_GJK_WARM_COS2 MK_REAL(0.25)

/* ---- signed volumes (Montanari, Petrinic, Barbieri 2017) --------------------
 * Each solver gets a (sub)simplex of s (vertex indices ascending, the newest
 * last) and returns the sub-simplex whose relative interior holds the point
 * nearest the origin, with its barycentric weights. The origin's barycentric
 * coordinates are ratios of signed volumes: for a triangle, the areas of the
 * sub-triangles at the origin's projection p0 measured along the normal,
 * n . ((s_j - p0) x (s_k - p0)), taken about p0 so their rounding scales with
 * the triangle rather than with its distance from the origin. A vertex whose
 * coordinate is not positive is dropped by recursing on the opposite face;
 * a degenerate simplex has no positive coordinates, so every face gets tried:
 * no division by a vanishing determinant, and a NaN (overflow) never counts as
 * inside. */

typedef struct sv_sol {
    int n;
    int idx[4];   /* ascending, so the simplex can be compacted in place */
    mk_real l[4];
    mk_vec3 v;    /* the nearest point */
    mk_real vv;   /* |v|^2 */
    mk_vec3 d;    /* the next search direction (towards the origin, not unit) */
} sv_sol;

static void sol_vertex(const mk_cso_vertex *s, int i, sv_sol *out)
{
    out->n = 1;
    out->idx[0] = i;
    out->l[0] = 1;
    out->v = s[i].w;
    out->vv = mk_v3_len2(s[i].w);
    out->d = mk_v3_neg(s[i].w);
}

/* Segment (i, j). */
static void sv_1d(const mk_cso_vertex *s, int i, int j, sv_sol *out)
{
    mk_vec3 a = s[i].w, t = mk_v3_sub(s[j].w, a);
    /* Weight of j. Two coincident points (tt == 0, which rounding makes
     * happen for unit shapes far from the origin in float) are vertex j,
     * without dividing by zero. */
    mk_real tt = mk_v3_len2(t), lb = tt > 0 ? -mk_v3_dot(a, t) / tt : 1;
    if (!(lb < 1)) { /* also NaN input */
        sol_vertex(s, j, out);
    } else if (!(lb > 0)) {
        sol_vertex(s, i, out);
    } else {
        out->n = 2;
        out->idx[0] = i;
        out->idx[1] = j;
        out->l[0] = 1 - lb;
        out->l[1] = lb;
        out->v = mk_v3_mad(a, lb, t);
        out->vv = mk_v3_len2(out->v);
        /* Perpendicular to the segment by construction (Catto 2010): its dot
         * with t is zero to one rounding, which -v's is not. */
        out->d = mk_v3_cross(t, mk_v3_cross(t, a));
    }
}

/* Triangle (i, j, k). */
static void sv_2d(const mk_cso_vertex *s, int i, int j, int k, sv_sol *out)
{
    mk_vec3 a = s[i].w, b = s[j].w, c = s[k].w;
    mk_vec3 n = mk_v3_cross(mk_v3_sub(b, a), mk_v3_sub(c, a));
    mk_real nn = mk_v3_len2(n), ca = 0, cb = 0, cc = 0;
    sv_sol e;
    if (nn > 0) {
        mk_real an = mk_v3_dot(a, n);
        mk_vec3 p0 = mk_v3_scale(n, an / nn); /* the origin projected on the plane */
        mk_vec3 ap = mk_v3_sub(a, p0), bp = mk_v3_sub(b, p0), cp = mk_v3_sub(c, p0);
        ca = mk_v3_dot(n, mk_v3_cross(bp, cp));
        cb = mk_v3_dot(n, mk_v3_cross(cp, ap));
        /* The three areas sum to nn exactly; the difference rounds like a third product would. */
        cc = nn - ca - cb;
        if (ca > 0 && cb > 0 && cc > 0) {
            mk_real sum = ca + cb + cc;
            out->n = 3;
            out->idx[0] = i;
            out->idx[1] = j;
            out->idx[2] = k;
            out->l[0] = ca / sum;
            out->l[1] = cb / sum;
            out->l[2] = cc / sum;
            out->v = p0;
            out->vv = mk_v3_len2(p0);
            out->d = an > 0 ? mk_v3_neg(n) : n; /* the face normal, towards the origin */
            return;
        }
    }
    /* Outside (or degenerate): the nearest point is on an edge whose opposite
     * vertex has a non-positive coordinate (every edge, when degenerate). */
    out->n = 0;
    out->vv = (mk_real)HUGE_VAL;
    if (!(ca > 0)) sv_1d(s, j, k, out);
    if (!(cb > 0)) {
        sv_1d(s, i, k, &e);
        if (e.vv < out->vv) *out = e;
    }
    if (!(cc > 0)) {
        sv_1d(s, i, j, &e);
        if (e.vv < out->vv) *out = e;
    }
    if (!(out->vv < (mk_real)HUGE_VAL)) sol_vertex(s, k, out); /* only reached with NaN input */
}

static void sv_3d(const mk_cso_vertex *s, sv_sol *out)
{
    mk_vec3 w0 = s[0].w, w1 = s[1].w, w2 = s[2].w, w3 = s[3].w, x23 = mk_v3_cross(w2, w3);
    /* c[j]: signed volume of the tetrahedron with vertex j replaced by the origin. */
    mk_real c0 = mk_v3_dot(w1, x23), c1 = -mk_v3_dot(w0, x23);
    mk_real c2 = mk_v3_dot(w0, mk_v3_cross(w1, w3)), c3 = -mk_v3_dot(w0, mk_v3_cross(w1, w2));
    mk_real mu = c0 + c1 + c2 + c3;
    sv_sol f;
    if (mu < 0) { /* orient so that inside means all positive */
        c0 = -c0;
        c1 = -c1;
        c2 = -c2;
        c3 = -c3;
        mu = -mu;
    }
    if (c0 > 0 && c1 > 0 && c2 > 0 && c3 > 0) {
        out->n = 4;
        out->idx[0] = 0;
        out->idx[1] = 1;
        out->idx[2] = 2;
        out->idx[3] = 3;
        out->l[0] = c0 / mu;
        out->l[1] = c1 / mu;
        out->l[2] = c2 / mu;
        out->l[3] = c3 / mu;
        out->v = mk_v3_zero();
        out->vv = 0;
        out->d = mk_v3_zero();
        return;
    }
    out->n = 0;
    out->vv = (mk_real)HUGE_VAL;
    if (!(c0 > 0)) sv_2d(s, 1, 2, 3, out);
    if (!(c1 > 0)) {
        sv_2d(s, 0, 2, 3, &f);
        if (f.vv < out->vv) *out = f;
    }
    if (!(c2 > 0)) {
        sv_2d(s, 0, 1, 3, &f);
        if (f.vv < out->vv) *out = f;
    }
    if (!(c3 > 0)) {
        sv_2d(s, 0, 1, 2, &f);
        if (f.vv < out->vv) *out = f;
    }
    if (!(out->vv < (mk_real)HUGE_VAL)) sol_vertex(s, 3, out);
}

/* The sub-simplex of s nearest the origin; s is not touched, so a step that
 * makes no progress costs no restore. */
static void solve(const mk_simplex *s, sv_sol *sol)
{
    switch (s->n) {
    case 1: sol_vertex(s->v, 0, sol); break;
    case 2: sv_1d(s->v, 0, 1, sol); break;
    case 3: sv_2d(s->v, 0, 1, 2, sol); break;
    default: sv_3d(s->v, sol); break;
    }
}

static void commit(mk_simplex *s, const sv_sol *sol)
{
    int k;
    for (k = 0; k < sol->n; ++k) {
        if (sol->idx[k] != k) s->v[k] = s->v[sol->idx[k]];
        s->l[k] = sol->l[k];
    }
    s->n = sol->n;
}

static int repeated(const mk_simplex *s, const mk_cso_vertex *w)
{
    int k;
    if (w->ia < 0 || w->ib < 0) return 0;
    for (k = 0; k < s->n; ++k)
        if (s->v[k].ia == w->ia && s->v[k].ib == w->ib) return 1;
    return 0;
}

/* Rebuilds the cached simplex from vertex indices; returns its size (0: unusable). */
static int warm_simplex(const mk_pair *p, const mk_gjk_cache *c, mk_simplex *s)
{
    int na = mk_core_vertex_count(p->a), nb = mk_core_vertex_count(p->b), k, n = 0;
    if (c->count < 1 || c->count > 4) return 0;
    for (k = 0; k < c->count; ++k) {
        mk_cso_vertex v;
        int j, dup = 0;
        if (c->ia[k] < 0 || c->ia[k] >= na || c->ib[k] < 0 || c->ib[k] >= nb) return 0;
        v.ia = c->ia[k];
        v.ib = c->ib[k];
        v.a = mk_core_vertex(p->a, v.ia);
        v.b = mk_v3_add(mk_mat3_mul_v3(p->r, mk_core_vertex(p->b, v.ib)), p->t);
        v.w = mk_v3_sub(v.a, v.b);
        for (j = 0; j < n; ++j) dup = dup || (s->v[j].ia == v.ia && s->v[j].ib == v.ib);
        if (!dup) s->v[n++] = v;
    }
    s->n = n;
    return n;
}

static mk_vec3 initial_direction(const mk_pair *p, const mk_gjk_cache *c)
{
    if (c && mk_v3_is_valid(c->dir) && mk_v3_len2(c->dir) > 0) return c->dir;
    /* Towards the origin of the CSO from its centre (-t): along t. */
    return mk_v3_len2(p->t) > 0 ? p->t : mk_v3(1, 0, 0);
}

/* The loop, inlined into one copy per specialised pair of shape types (the
 * supports then compile to a few selects and two matrix products) and one
 * generic copy that switches on the types. */
MK_ALWAYS_INLINE void gjk_loop(const mk_pair *p, mk_shape_type ta, mk_shape_type tb, const mk_gjk_cache *cache, int boolean,
                               mk_real radius, mk_gjk_result *out)
{
    mk_simplex *s = &out->s;
    sv_sol sol;
    mk_real scale2 = 0, scale, lower = -(mk_real)HUGE_VAL;
    int iter, k, ha = -1, hb = -1, overlap = 0;
    mk_solve_state state = MK_SOLVE_MAX_ITERATIONS;
    mk_vec3 dprev = mk_v3_zero();

    out->normal = mk_v3(1, 0, 0);
    if (cache && warm_simplex(p, cache, s) > 0) {
        ha = cache->ia[0];
        hb = cache->ib[0];
        /* the hints are as warm as the last query's normal is close */
        if (mk_v3_is_valid(cache->dir) && mk_v3_len2(cache->dir) > 0) dprev = mk_v3_normalize(cache->dir);
    } else {
        s->n = 1;
        s->v[0] = mk_pair_support_typed(p, ta, tb, initial_direction(p, cache), -1, -1);
        ha = s->v[0].ia;
        hb = s->v[0].ib;
    }
    for (k = 0; k < s->n; ++k) scale2 = mk_max(scale2, mk_v3_len2(s->v[k].w));
    scale = mk_sqrt_(scale2);
    solve(s, &sol);
    commit(s, &sol);

    for (iter = 0; iter < MK_GJK_MAX_ITERATIONS; ++iter) {
        mk_cso_vertex w;
        mk_vec3 d;
        mk_real dd, lo, u, w2, tol_abs = MK_GJK_ABS_TOL * scale;
        if (s->n == 4 || sol.vv <= tol_abs * tol_abs) { /* origin inside, or on the simplex to rounding */
            overlap = 1;
            state = MK_SOLVE_CONVERGED;
            break;
        }
        u = mk_sqrt_(sol.vv);
        if (boolean && u <= radius) {
            overlap = 1;
            state = MK_SOLVE_CONVERGED;
            break;
        }
        /* A direction that does not point at the origin side of v is rounding noise. */
        d = mk_v3_dot(sol.d, sol.v) < 0 ? sol.d : mk_v3_neg(sol.v);
        dd = mk_v3_len2(d);
        if (!(dd > 0)) {
            state = MK_SOLVE_DEGENERATE;
            break;
        }
        /* Supports are scale-free, so the search runs on d as it is and the
         * square root and division of the unit normal below overlap it
         * instead of delaying it. */
        { /* hints only after a small turn of the direction (MK_GJK_WARM_COS2) */
            mk_real c = mk_v3_dot(d, dprev);
            int warm = c > 0 && c * c > MK_GJK_WARM_COS2 * dd;
            w = mk_pair_support_typed(p, ta, tb, d, warm ? ha : -1, warm ? hb : -1);
        }
        d = mk_v3_scale(d, 1 / mk_sqrt_(dd));
        dprev = d;
        ha = w.ia;
        hb = w.ib;
        w2 = mk_v3_len2(w.w);
        if (w2 > scale2) {
            scale2 = w2;
            scale = mk_sqrt_(w2);
        }
        lo = -mk_v3_dot(d, w.w);
        if (lo > lower) {
            lower = lo;
            out->normal = d;
        }
        if (boolean && lower > radius) {
            state = MK_SOLVE_CONVERGED;
            break;
        }
        if (repeated(s, &w) || u - lower <= MK_GJK_REL_TOL * u + MK_GJK_ABS_TOL * scale) {
            state = MK_SOLVE_CONVERGED;
            break;
        }
        /* Add w; keep the result only on a strict decrease (written so a NaN also stops). */
        {
            mk_real vv_prev = sol.vv;
            mk_vec3 v_prev = sol.v;
            s->v[s->n++] = w;
            solve(s, &sol);
            if (!(sol.vv < vv_prev)) {
                s->n--;
                sol.vv = vv_prev;
                sol.v = v_prev;
                state = vv_prev == vv_prev ? MK_SOLVE_CONVERGED : MK_SOLVE_DEGENERATE;
                break;
            }
            commit(s, &sol);
        }
    }
    /* Converged without an early answer: decide by the (tight) lower bound. */
    if (boolean && !overlap) overlap = !(lower > radius);
    out->v = sol.v;
    out->upper = overlap ? 0 : mk_sqrt_(sol.vv);
    out->lower = lower;
    out->scale = scale;
    out->overlap = overlap;
    out->iterations = iter + 1;
    out->state = state;
}

static void gjk_box_box(const mk_pair *p, const mk_gjk_cache *c, int boolean, mk_real r, mk_gjk_result *out)
{
    gjk_loop(p, MK_SHAPE_BOX, MK_SHAPE_BOX, c, boolean, r, out);
}

static void gjk_hull_hull(const mk_pair *p, const mk_gjk_cache *c, int boolean, mk_real r, mk_gjk_result *out)
{
    gjk_loop(p, MK_SHAPE_HULL, MK_SHAPE_HULL, c, boolean, r, out);
}

static void gjk_hull_box(const mk_pair *p, const mk_gjk_cache *c, int boolean, mk_real r, mk_gjk_result *out)
{
    gjk_loop(p, MK_SHAPE_HULL, MK_SHAPE_BOX, c, boolean, r, out);
}

static void gjk_box_hull(const mk_pair *p, const mk_gjk_cache *c, int boolean, mk_real r, mk_gjk_result *out)
{
    gjk_loop(p, MK_SHAPE_BOX, MK_SHAPE_HULL, c, boolean, r, out);
}

static void gjk_any(const mk_pair *p, const mk_gjk_cache *c, int boolean, mk_real r, mk_gjk_result *out)
{
    gjk_loop(p, p->a->type, p->b->type, c, boolean, r, out);
}

void mk_gjk(const mk_pair *p, const mk_gjk_cache *cache, int boolean, mk_real radius, mk_gjk_result *out)
{
    mk_shape_type ta = p->a->type, tb = p->b->type;
    if (ta == MK_SHAPE_BOX && tb == MK_SHAPE_BOX) gjk_box_box(p, cache, boolean, radius, out);
    else if (ta == MK_SHAPE_HULL && tb == MK_SHAPE_HULL) gjk_hull_hull(p, cache, boolean, radius, out);
    else if (ta == MK_SHAPE_HULL && tb == MK_SHAPE_BOX) gjk_hull_box(p, cache, boolean, radius, out);
    else if (ta == MK_SHAPE_BOX && tb == MK_SHAPE_HULL) gjk_box_hull(p, cache, boolean, radius, out);
    else gjk_any(p, cache, boolean, radius, out);
}

void mk_gjk_cache_store(const mk_simplex *s, mk_vec3 normal, mk_gjk_cache *cache)
{
    int k, ok = 1;
    for (k = 0; k < s->n; ++k) ok = ok && s->v[k].ia >= 0 && s->v[k].ib >= 0;
    cache->dir = normal;
    cache->count = ok ? s->n : 0;
    for (k = 0; k < 4; ++k) {
        cache->ia[k] = k < s->n ? s->v[k].ia : -1;
        cache->ib[k] = k < s->n ? s->v[k].ib : -1;
    }
}

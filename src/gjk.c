/* gjk.c: GJK distance on the cores, signed-volumes sub-algorithm, warm start. */
#include "gjk.h"

/* ---- signed volumes (Montanari, Petrinic, Barbieri 2017) --------------------
 * Each solver gets the points of a (sub)simplex and returns the sub-simplex
 * whose relative interior holds the point nearest the origin, with its
 * barycentric weights. The origin's barycentric coordinates are ratios of
 * signed volumes (areas, lengths) taken in the best-conditioned projection;
 * a vertex whose coordinate has the wrong sign (or is zero) is dropped by
 * recursing on the opposite face. A degenerate simplex has no sign to agree
 * with, so every face gets tried: no division by a vanishing determinant. */

typedef struct sv_sol {
    int n;
    int idx[4];   /* ascending, so the simplex can be compacted in place */
    mk_real l[4];
    mk_vec3 v;    /* the nearest point */
    mk_real vv;   /* |v|^2 */
} sv_sol;

static int same_sign(mk_real a, mk_real b) { return (a > 0 && b > 0) || (a < 0 && b < 0); }

static int max_abs_axis(mk_vec3 v)
{
    mk_real x = mk_fabs_(v.x), y = mk_fabs_(v.y), z = mk_fabs_(v.z);
    return (x >= y && x >= z) ? 0 : (y >= z ? 1 : 2);
}

static mk_real axis(mk_vec3 v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : v.z); }

static void sol_vertex(const mk_vec3 *w, int i, sv_sol *out)
{
    out->n = 1;
    out->idx[0] = i;
    out->l[0] = 1;
    out->v = w[i];
    out->vv = mk_v3_len2(w[i]);
}

/* Keeps the better of two candidates in *best. NaN distances never win. */
static void sol_keep(sv_sol *best, const sv_sol *c)
{
    if (c->vv < best->vv || !(best->vv == best->vv)) *best = *c;
}

/* Segment (i, j), i < j. */
static void sv_1d(const mk_vec3 *w, int i, int j, sv_sol *out)
{
    mk_vec3 s1 = w[i], s2 = w[j], t = mk_v3_sub(s2, s1), p0;
    mk_real tt = mk_v3_len2(t), mu, c1, c2;
    int k;
    if (!(tt > 0)) {
        sol_vertex(w, j, out);
        return;
    }
    p0 = mk_v3_mad(s1, -mk_v3_dot(s1, t) / tt, t); /* the origin projected on the line */
    k = max_abs_axis(t);
    mu = axis(s1, k) - axis(s2, k);
    c1 = axis(p0, k) - axis(s2, k); /* weight of s1, times mu */
    c2 = axis(s1, k) - axis(p0, k); /* weight of s2, times mu */
    if (!same_sign(mu, c2)) {
        sol_vertex(w, i, out);
    } else if (!same_sign(mu, c1)) {
        sol_vertex(w, j, out);
    } else {
        out->n = 2;
        out->idx[0] = i;
        out->idx[1] = j;
        out->l[0] = c1 / mu;
        out->l[1] = c2 / mu;
        out->v = p0;
        out->vv = mk_v3_len2(p0);
    }
}

/* Triangle (i, j, k), i < j < k. The areas are taken in the coordinate plane
 * the triangle projects to with the largest area. */
static void sv_2d(const mk_vec3 *w, int i, int j, int k, sv_sol *out)
{
    const int ids[3] = {i, j, k};
    mk_vec3 s1 = w[i], s2 = w[j], s3 = w[k];
    mk_vec3 n = mk_v3_cross(mk_v3_sub(s2, s1), mk_v3_sub(s3, s1)), p0;
    mk_real nn = mk_v3_len2(n), mu = 0, c[3] = {0, 0, 0};
    int m;
    if (nn > 0) {
        int ax = max_abs_axis(n), u = (ax + 1) % 3, v = (ax + 2) % 3; /* (u, v) cyclic after ax: area sign = sign of n_ax */
        mk_real px, py, x1, y1, x2, y2, x3, y3;
        p0 = mk_v3_scale(n, mk_v3_dot(s1, n) / nn); /* the origin projected on the plane */
        px = axis(p0, u);
        py = axis(p0, v);
        x1 = axis(s1, u) - px;
        y1 = axis(s1, v) - py;
        x2 = axis(s2, u) - px;
        y2 = axis(s2, v) - py;
        x3 = axis(s3, u) - px;
        y3 = axis(s3, v) - py;
        mu = axis(n, ax);
        c[0] = x2 * y3 - y2 * x3; /* area (p0, s2, s3): weight of s1 */
        c[1] = x3 * y1 - y3 * x1;
        c[2] = x1 * y2 - y1 * x2;
        if (same_sign(mu, c[0]) && same_sign(mu, c[1]) && same_sign(mu, c[2])) {
            mk_real sum = c[0] + c[1] + c[2];
            out->n = 3;
            for (m = 0; m < 3; ++m) {
                out->idx[m] = ids[m];
                out->l[m] = c[m] / sum;
            }
            out->v = p0;
            out->vv = mk_v3_len2(p0);
            return;
        }
    }
    /* Outside (or degenerate): the nearest point is on an edge whose opposite
     * vertex has the wrong sign (every edge, for a degenerate triangle). */
    out->n = 0;
    out->vv = (mk_real)HUGE_VAL;
    for (m = 0; m < 3; ++m) {
        sv_sol e;
        if (same_sign(mu, c[m])) continue;
        sv_1d(w, ids[m == 0 ? 1 : 0], ids[m == 2 ? 1 : 2], &e);
        sol_keep(out, &e);
    }
    if (out->n == 0) sol_vertex(w, k, out); /* only reached with NaN input */
}

static void sv_3d(const mk_vec3 *w, sv_sol *out)
{
    static const int face[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
    mk_vec3 s1 = w[0], s2 = w[1], s3 = w[2], s4 = w[3];
    mk_vec3 x34 = mk_v3_cross(s3, s4);
    mk_real c[4], mu;
    int m;
    /* c[j]: signed volume of the tetrahedron with vertex j replaced by the origin. */
    c[0] = mk_v3_dot(s2, x34);
    c[1] = -mk_v3_dot(s1, x34);
    c[2] = mk_v3_dot(s1, mk_v3_cross(s2, s4));
    c[3] = -mk_v3_dot(s1, mk_v3_cross(s2, s3));
    mu = c[0] + c[1] + c[2] + c[3];
    if (same_sign(mu, c[0]) && same_sign(mu, c[1]) && same_sign(mu, c[2]) && same_sign(mu, c[3])) {
        out->n = 4;
        for (m = 0; m < 4; ++m) {
            out->idx[m] = m;
            out->l[m] = c[m] / mu;
        }
        out->v = mk_v3_zero();
        out->vv = 0;
        return;
    }
    out->n = 0;
    out->vv = (mk_real)HUGE_VAL;
    for (m = 0; m < 4; ++m) {
        sv_sol f;
        if (same_sign(mu, c[m])) continue;
        sv_2d(w, face[m][0], face[m][1], face[m][2], &f);
        sol_keep(out, &f);
    }
    if (out->n == 0) sol_vertex(w, 3, out);
}

/* The sub-simplex of s nearest the origin, from the positions alone; s is
 * not touched, so a step that makes no progress costs no restore. */
static void solve(const mk_simplex *s, sv_sol *sol)
{
    mk_vec3 w[4];
    int k;
    for (k = 0; k < s->n; ++k) w[k] = s->v[k].w;
    switch (s->n) {
    case 1: sol_vertex(w, 0, sol); break;
    case 2: sv_1d(w, 0, 1, sol); break;
    case 3: sv_2d(w, 0, 1, 2, sol); break;
    default: sv_3d(w, sol); break;
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

/* Search direction towards the origin, perpendicular to the simplex by
 * construction (cross products), so its dot with every simplex edge is zero
 * up to one rounding instead of carrying the error of v. Falls back on -v. */
static mk_vec3 direction(const mk_simplex *s, mk_vec3 v)
{
    mk_vec3 d;
    if (s->n == 2) {
        mk_vec3 e = mk_v3_sub(s->v[1].w, s->v[0].w);
        d = mk_v3_cross(e, mk_v3_cross(e, s->v[0].w));
    } else if (s->n == 3) {
        d = mk_v3_cross(mk_v3_sub(s->v[1].w, s->v[0].w), mk_v3_sub(s->v[2].w, s->v[0].w));
        if (mk_v3_dot(d, s->v[0].w) > 0) d = mk_v3_neg(d);
    } else {
        d = mk_v3_neg(v);
    }
    /* A direction that does not point at the origin side of v is rounding noise. */
    if (!(mk_v3_dot(d, v) < 0)) d = mk_v3_neg(v);
    return d;
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

void mk_gjk(const mk_pair *p, const mk_gjk_cache *cache, int boolean, mk_real radius, mk_gjk_result *out)
{
    mk_simplex *s = &out->s;
    sv_sol sol;
    mk_real scale2 = 0, lower = -(mk_real)HUGE_VAL;
    int iter, k, ha = -1, hb = -1, overlap = 0;
    mk_solve_state state = MK_SOLVE_MAX_ITERATIONS;

    out->normal = mk_v3(1, 0, 0);
    if (cache && warm_simplex(p, cache, s) > 0) {
        ha = cache->ia[0];
        hb = cache->ib[0];
    } else {
        s->n = 1;
        s->v[0] = mk_pair_support(p, initial_direction(p, cache), -1, -1);
        ha = s->v[0].ia;
        hb = s->v[0].ib;
    }
    for (k = 0; k < s->n; ++k) scale2 = mk_max(scale2, mk_v3_len2(s->v[k].w));
    solve(s, &sol);
    commit(s, &sol);

    for (iter = 0; iter < MK_GJK_MAX_ITERATIONS; ++iter) {
        mk_cso_vertex w;
        mk_vec3 d;
        mk_real dn, lo, u, tol_abs = MK_GJK_ABS_TOL * mk_sqrt_(scale2);
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
        d = direction(s, sol.v);
        dn = mk_v3_len(d);
        if (!(dn > 0)) {
            state = MK_SOLVE_DEGENERATE;
            break;
        }
        d = mk_v3_scale(d, 1 / dn);
        w = mk_pair_support(p, d, ha, hb);
        ha = w.ia;
        hb = w.ib;
        scale2 = mk_max(scale2, mk_v3_len2(w.w));
        lo = -mk_v3_dot(d, w.w);
        if (lo > lower) {
            lower = lo;
            out->normal = d;
        }
        if (boolean && lower > radius) {
            state = MK_SOLVE_CONVERGED;
            break;
        }
        if (repeated(s, &w) || u - lower <= MK_GJK_REL_TOL * u + MK_GJK_ABS_TOL * mk_sqrt_(scale2)) {
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
    out->scale = mk_sqrt_(scale2);
    out->overlap = overlap;
    out->iterations = iter + 1;
    out->state = state;
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

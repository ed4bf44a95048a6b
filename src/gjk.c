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
    int idx[4];
    mk_real l[4];
    mk_real vv; /* |v|^2 of this candidate */
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
    out->vv = mk_v3_len2(w[i]);
}

static void sol_finish(const mk_vec3 *w, sv_sol *s)
{
    mk_vec3 v = mk_v3_zero();
    int k;
    for (k = 0; k < s->n; ++k) v = mk_v3_mad(v, s->l[k], w[s->idx[k]]);
    s->vv = mk_v3_len2(v);
}

/* Keeps the better of two candidates in *best. NaN distances never win. */
static void sol_keep(sv_sol *best, const sv_sol *c)
{
    if (c->vv < best->vv || !(best->vv == best->vv)) *best = *c;
}

static void sv_1d(const mk_vec3 *w, int i1, int i2, sv_sol *out)
{
    mk_vec3 s1 = w[i1], s2 = w[i2], t = mk_v3_sub(s2, s1), p0;
    mk_real tt = mk_v3_len2(t), mu, c1, c2;
    int k;
    if (!(tt > 0)) {
        sol_vertex(w, i1, out);
        return;
    }
    p0 = mk_v3_mad(s1, -mk_v3_dot(s1, t) / tt, t); /* the origin projected on the line */
    k = max_abs_axis(t);
    mu = axis(s1, k) - axis(s2, k);
    c1 = axis(p0, k) - axis(s2, k);
    c2 = axis(s1, k) - axis(p0, k);
    if (!same_sign(mu, c2)) {
        sol_vertex(w, i1, out);
    } else if (!same_sign(mu, c1)) {
        sol_vertex(w, i2, out);
    } else {
        out->n = 2;
        out->idx[0] = i1;
        out->idx[1] = i2;
        out->l[0] = c1 / mu;
        out->l[1] = 1 - out->l[0];
        sol_finish(w, out);
    }
}

/* Twice the signed area of (p, b, c) in the plane of axes (i, j). */
static mk_real area2(mk_vec3 p, mk_vec3 b, mk_vec3 c, int i, int j)
{
    return (axis(b, i) - axis(p, i)) * (axis(c, j) - axis(p, j)) - (axis(b, j) - axis(p, j)) * (axis(c, i) - axis(p, i));
}

static void sv_2d(const mk_vec3 *w, int i1, int i2, int i3, sv_sol *out)
{
    const int ids[3] = {i1, i2, i3};
    mk_vec3 s1 = w[i1], s2 = w[i2], s3 = w[i3];
    mk_vec3 n = mk_v3_cross(mk_v3_sub(s2, s1), mk_v3_sub(s3, s1)), p0;
    mk_real nn = mk_v3_len2(n), mu, c[3];
    int k, i, j, m, inside = 1;
    if (nn > 0) {
        p0 = mk_v3_scale(n, mk_v3_dot(s1, n) / nn); /* the origin projected on the plane */
        /* Project along the normal's largest component; (i, j) cyclic after k so
         * the projected area has the sign of n_k. */
        k = max_abs_axis(n);
        i = (k + 1) % 3;
        j = (k + 2) % 3;
        mu = axis(n, k);
        c[0] = area2(p0, s2, s3, i, j);
        c[1] = area2(p0, s3, s1, i, j);
        c[2] = area2(p0, s1, s2, i, j);
        for (m = 0; m < 3; ++m) inside = inside && same_sign(mu, c[m]);
        if (inside) {
            mk_real sum = c[0] + c[1] + c[2];
            out->n = 3;
            for (m = 0; m < 3; ++m) {
                out->idx[m] = ids[m];
                out->l[m] = c[m] / sum;
            }
            sol_finish(w, out);
            return;
        }
    } else {
        c[0] = c[1] = c[2] = 0;
        mu = 0;
    }
    /* Outside (or degenerate): the nearest point is on an edge whose opposite vertex has the wrong sign. */
    out->n = 0;
    out->vv = (mk_real)HUGE_VAL;
    for (m = 0; m < 3; ++m) {
        sv_sol e;
        if (same_sign(mu, c[m])) continue;
        sv_1d(w, ids[(m + 1) % 3], ids[(m + 2) % 3], &e);
        sol_keep(out, &e);
    }
    if (out->n == 0) sol_vertex(w, i1, out); /* only reached with NaN input */
}

static void sv_3d(const mk_vec3 *w, sv_sol *out)
{
    mk_vec3 s1 = w[0], s2 = w[1], s3 = w[2], s4 = w[3];
    mk_real c[4], mu;
    int m, inside = 1;
    /* c[j]: signed volume of the tetrahedron with vertex j replaced by the origin. */
    c[0] = mk_v3_dot(s2, mk_v3_cross(s3, s4));
    c[1] = -mk_v3_dot(s1, mk_v3_cross(s3, s4));
    c[2] = mk_v3_dot(s1, mk_v3_cross(s2, s4));
    c[3] = -mk_v3_dot(s1, mk_v3_cross(s2, s3));
    mu = c[0] + c[1] + c[2] + c[3];
    for (m = 0; m < 4; ++m) inside = inside && same_sign(mu, c[m]);
    if (inside) {
        out->n = 4;
        for (m = 0; m < 4; ++m) {
            out->idx[m] = m;
            out->l[m] = c[m] / mu;
        }
        out->vv = 0;
        return;
    }
    out->n = 0;
    out->vv = (mk_real)HUGE_VAL;
    for (m = 0; m < 4; ++m) {
        static const int face[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
        sv_sol f;
        if (same_sign(mu, c[m])) continue;
        sv_2d(w, face[m][0], face[m][1], face[m][2], &f);
        sol_keep(out, &f);
    }
    if (out->n == 0) sol_vertex(w, 0, out);
}

/* Reduces s to the sub-simplex nearest the origin; returns v, the nearest point. */
static mk_vec3 solve(mk_simplex *s)
{
    mk_vec3 w[4], v = mk_v3_zero();
    mk_cso_vertex old[4];
    sv_sol sol;
    int k;
    for (k = 0; k < s->n; ++k) {
        w[k] = s->v[k].w;
        old[k] = s->v[k];
    }
    switch (s->n) {
    case 1: sol_vertex(w, 0, &sol); break;
    case 2: sv_1d(w, 0, 1, &sol); break;
    case 3: sv_2d(w, 0, 1, 2, &sol); break;
    default: sv_3d(w, &sol); break;
    }
    s->n = sol.n;
    for (k = 0; k < sol.n; ++k) {
        s->v[k] = old[sol.idx[k]];
        s->l[k] = sol.l[k];
        v = mk_v3_mad(v, sol.l[k], w[sol.idx[k]]);
    }
    return sol.n == 4 ? mk_v3_zero() : v;
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
    mk_simplex s, saved;
    mk_vec3 v, v_saved, d;
    mk_real vv, vv_prev = (mk_real)HUGE_VAL, scale2 = 0, lower = -(mk_real)HUGE_VAL;
    int iter, k, ha = -1, hb = -1;
    mk_solve_state state = MK_SOLVE_MAX_ITERATIONS;
    int overlap = 0;

    out->normal = mk_v3(1, 0, 0);
    if (cache && warm_simplex(p, cache, &s) > 0) {
        ha = cache->ia[0];
        hb = cache->ib[0];
    } else {
        s.n = 1;
        s.v[0] = mk_pair_support(p, initial_direction(p, cache), -1, -1);
        ha = s.v[0].ia;
        hb = s.v[0].ib;
    }
    for (k = 0; k < s.n; ++k) scale2 = mk_max(scale2, mk_v3_len2(s.v[k].w));
    v = solve(&s);
    vv = mk_v3_len2(v);
    saved = s;
    v_saved = v;

    for (iter = 0; iter < MK_GJK_MAX_ITERATIONS; ++iter) {
        mk_cso_vertex w;
        mk_real dn, lo, u, tol_abs;
        if (s.n == 4) { /* the origin is inside the tetrahedron */
            overlap = 1;
            state = MK_SOLVE_CONVERGED;
            break;
        }
        tol_abs = MK_GJK_ABS_TOL * mk_sqrt_(scale2);
        if (vv <= tol_abs * tol_abs) { /* the origin is on the simplex (touching), to rounding */
            overlap = 1;
            state = MK_SOLVE_CONVERGED;
            break;
        }
        /* Strict decrease, written so a NaN also stops: otherwise keep the previous simplex. */
        if (!(vv < vv_prev)) {
            s = saved;
            v = v_saved;
            vv = vv_prev;
            state = (vv == vv) ? MK_SOLVE_CONVERGED : MK_SOLVE_DEGENERATE;
            break;
        }
        u = mk_sqrt_(vv);
        if (boolean && u <= radius) {
            overlap = 1;
            state = MK_SOLVE_CONVERGED;
            break;
        }
        d = direction(&s, v);
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
        if (repeated(&s, &w) || u - lower <= MK_GJK_REL_TOL * u + MK_GJK_ABS_TOL * mk_sqrt_(scale2)) {
            state = MK_SOLVE_CONVERGED;
            break;
        }
        saved = s;
        v_saved = v;
        vv_prev = vv;
        s.v[s.n++] = w;
        v = solve(&s);
        vv = mk_v3_len2(v);
    }
    /* Converged without an early answer: decide by the (tight) lower bound. */
    if (boolean && !overlap) overlap = !(lower > radius);
    out->s = s;
    out->v = v;
    out->upper = overlap ? 0 : mk_sqrt_(vv);
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

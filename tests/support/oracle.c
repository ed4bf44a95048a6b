/* oracle.c: brute-force long double references (contract in oracle.h).
 *
 * Everything works in A's local frame (B is moved into it once), so shapes far
 * from the origin lose nothing. The code favours being obviously right over
 * being fast; the pruning it does use is either a conservative bound (bounding
 * spheres) or checked against the exhaustive loop by tests/test_oracle.c.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "oracle.h"

/* Edge pairs closer to parallel than this (sine of the angle) are skipped in
 * SAT: ~sqrt(LDBL_EPSILON), which balances the error of the ill-conditioned
 * cross product (eps / angle) against the width of the skipped sliver face
 * (angle x edge length). */
#define PARALLEL_SIN 2e-10L
/* Points within this fraction of the cloud's extent of a plane are on it. */
#define PLANE_TOL 1e-15L

/* ---- long double vectors -------------------------------------------------- */
static mk_lvec3 lv(long double x, long double y, long double z) { mk_lvec3 v; v.x = x; v.y = y; v.z = z; return v; }
static mk_lvec3 ladd(mk_lvec3 a, mk_lvec3 b) { return lv(a.x + b.x, a.y + b.y, a.z + b.z); }
static mk_lvec3 lsub(mk_lvec3 a, mk_lvec3 b) { return lv(a.x - b.x, a.y - b.y, a.z - b.z); }
static mk_lvec3 lscale(mk_lvec3 a, long double s) { return lv(a.x * s, a.y * s, a.z * s); }
static mk_lvec3 lmad(mk_lvec3 a, long double s, mk_lvec3 b) { return lv(a.x + s * b.x, a.y + s * b.y, a.z + s * b.z); }
static long double ldot(mk_lvec3 a, mk_lvec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static mk_lvec3 lcross(mk_lvec3 a, mk_lvec3 b) { return lv(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x); }
static long double llen(mk_lvec3 a) { return sqrtl(ldot(a, a)); }
static mk_lvec3 lnormalize(mk_lvec3 a)
{
    long double l = llen(a);
    return l > 0 ? lscale(a, 1 / l) : lv(0, 0, 0);
}
static mk_lvec3 lrot(const long double r[3][3], mk_lvec3 v)
{
    return lv(r[0][0] * v.x + r[0][1] * v.y + r[0][2] * v.z, r[1][0] * v.x + r[1][1] * v.y + r[1][2] * v.z,
              r[2][0] * v.x + r[2][1] * v.y + r[2][2] * v.z);
}
static mk_lvec3 lrot_t(const long double r[3][3], mk_lvec3 v)
{
    return lv(r[0][0] * v.x + r[1][0] * v.y + r[2][0] * v.z, r[0][1] * v.x + r[1][1] * v.y + r[2][1] * v.z,
              r[0][2] * v.x + r[1][2] * v.y + r[2][2] * v.z);
}
static mk_lvec3 lfrom(mk_vec3 v) { return lv(v.x, v.y, v.z); }
static int lfinite(long double a) { return a - a == 0; }

/* ---- brute-force convex hull ---------------------------------------------- */

typedef struct hull_tmp {
    int n, nf, fcap, lcap, nloop;
    int *loop;               /* face loops (point indices), concatenated */
    int *first;              /* nf + 1 */
    mk_lvec3 *normal;
    unsigned char *member;   /* nf x n: point m lies on face f */
    int **pfaces, *pcount, *pcap; /* faces each point lies on */
} hull_tmp;

static int grow(void **p, int *cap, int need, size_t elem)
{
    void *q;
    int c = *cap ? *cap : 16;
    if (need <= *cap) return 0;
    while (c < need) c *= 2;
    q = realloc(*p, (size_t)c * elem);
    if (!q) return -1;
    *p = q;
    *cap = c;
    return 0;
}

static int shares_face(const hull_tmp *h, int i, int j, int k)
{
    int t;
    for (t = 0; t < h->pcount[i]; ++t) {
        const unsigned char *m = h->member + (size_t)h->pfaces[i][t] * (size_t)h->n;
        if (m[j] && m[k]) return 1;
    }
    return 0;
}

/* Counter-clockwise (about n) convex polygon of the points `s` that lie on a
 * plane with unit normal n: Andrew's monotone chain in plane coordinates;
 * points within `tol` of a hull edge's line are dropped so corners are strict. */
static int polygon_2d(const mk_lvec3 *p, const int *s, int ns, mk_lvec3 n, long double tol, int *out)
{
    mk_lvec3 e1 = fabsl(n.x) < 0.57L ? lnormalize(lv(0, n.z, -n.y)) : lnormalize(lv(n.y, -n.x, 0));
    mk_lvec3 e2 = lcross(n, e1);
    long double *x = malloc(sizeof *x * (size_t)ns * 2), *y = x ? x + ns : NULL;
    int *ord = malloc(sizeof *ord * (size_t)ns), i, j, k = 0, lower;
    if (!x || !ord) {
        free(x);
        free(ord);
        return -1;
    }
    for (i = 0; i < ns; ++i) {
        x[i] = ldot(e1, p[s[i]]);
        y[i] = ldot(e2, p[s[i]]);
        ord[i] = i;
    }
    for (i = 1; i < ns; ++i) /* insertion sort by (x, y): groups are small */
        for (j = i; j > 0 && (x[ord[j]] < x[ord[j - 1]] || (x[ord[j]] == x[ord[j - 1]] && y[ord[j]] < y[ord[j - 1]])); --j) {
            int t = ord[j];
            ord[j] = ord[j - 1];
            ord[j - 1] = t;
        }
    /* out[] holds ord indices while building; a point is kept only on a strict left turn. */
#define TURN(a, b, c) (((x[b] - x[a]) * (y[c] - y[a]) - (y[b] - y[a]) * (x[c] - x[a])) > \
                       tol * sqrtl((x[b] - x[a]) * (x[b] - x[a]) + (y[b] - y[a]) * (y[b] - y[a])))
    for (i = 0; i < ns; ++i) {
        while (k >= 2 && !TURN(out[k - 2], out[k - 1], ord[i])) --k;
        out[k++] = ord[i];
    }
    lower = k + 1;
    for (i = ns - 2; i >= 0; --i) {
        while (k >= lower && !TURN(out[k - 2], out[k - 1], ord[i])) --k;
        out[k++] = ord[i];
    }
#undef TURN
    --k; /* the first point is repeated at the end */
    for (i = 0; i < k; ++i) out[i] = s[out[i]];
    free(x);
    free(ord);
    return k;
}

/* A supporting plane through three points was found: collect every point on
 * it, build the face polygon and record membership. Collinear groups (a plane
 * that only touches along an edge) are not faces. */
static int add_face(hull_tmp *h, const mk_lvec3 *p, mk_lvec3 u, mk_lvec3 origin, long double tol)
{
    int m, ns = 0, k, i, f = h->nf;
    int *s = malloc(sizeof *s * (size_t)h->n * 2), *poly = s ? s + h->n : NULL;
    mk_lvec3 nw = lv(0, 0, 0);
    if (!s) return -1;
    for (m = 0; m < h->n; ++m)
        if (fabsl(ldot(u, lsub(p[m], origin))) <= tol) s[ns++] = m;
    k = polygon_2d(p, s, ns, u, tol, poly);
    if (k < 3) {
        free(s);
        return k < 0 ? -1 : 0;
    }
    if (grow((void **)&h->first, &h->fcap, f + 2, sizeof *h->first) ||
        grow((void **)&h->loop, &h->lcap, h->nloop + k, sizeof *h->loop)) {
        free(s);
        return -1;
    }
    h->normal = realloc(h->normal, sizeof *h->normal * (size_t)h->fcap);
    h->member = realloc(h->member, (size_t)h->fcap * (size_t)h->n);
    if (!h->normal || !h->member) {
        free(s);
        return -1;
    }
    /* Newell's normal of the polygon: exact for axis-aligned faces, robust for thin ones. */
    for (i = 0; i < k; ++i) {
        mk_lvec3 a = p[poly[i]], b = p[poly[(i + 1) % k]];
        nw = ladd(nw, lv((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y)));
    }
    h->normal[f] = lnormalize(nw);
    h->first[f] = h->nloop;
    memcpy(h->loop + h->nloop, poly, sizeof *poly * (size_t)k);
    h->nloop += k;
    h->first[f + 1] = h->nloop;
    memset(h->member + (size_t)f * (size_t)h->n, 0, (size_t)h->n);
    for (i = 0; i < ns; ++i) {
        m = s[i];
        h->member[(size_t)f * (size_t)h->n + (size_t)m] = 1;
        if (grow((void **)&h->pfaces[m], &h->pcap[m], h->pcount[m] + 1, sizeof(int))) {
            free(s);
            return -1;
        }
        h->pfaces[m][h->pcount[m]++] = f;
    }
    h->nf = f + 1;
    free(s);
    return 0;
}

/* Every triple of points whose plane has all points on one side (within tol)
 * spans a face. Triples already inside a found face are skipped, which keeps
 * clouds with many coplanar points cheap. */
static int find_faces(hull_tmp *h, const mk_lvec3 *p, long double extent)
{
    long double tol = PLANE_TOL * extent, min_area = 1e-12L * extent * extent;
    int i, j, k, m, n = h->n;
    for (i = 0; i < n; ++i)
        for (j = i + 1; j < n; ++j)
            for (k = j + 1; k < n; ++k) {
                mk_lvec3 c;
                long double len;
                int pos = 0, neg = 0;
                if (shares_face(h, i, j, k)) continue;
                c = lcross(lsub(p[j], p[i]), lsub(p[k], p[i]));
                len = llen(c);
                if (len <= min_area) continue; /* (nearly) collinear: never needed to span a face */
                c = lscale(c, 1 / len);
                for (m = 0; m < n && !(pos && neg); ++m) {
                    long double s = ldot(c, lsub(p[m], p[i]));
                    if (s > tol) pos = 1;
                    else if (s < -tol) neg = 1;
                }
                if (pos && neg) continue;
                if (!pos && !neg) return -1; /* all points coplanar: no solid */
                if (add_face(h, p, pos ? lscale(c, -1) : c, p[i], tol)) return -1;
            }
    return h->nf >= 4 ? 0 : -1;
}

static void hull_tmp_free(hull_tmp *h)
{
    int i;
    if (h->pfaces)
        for (i = 0; i < h->n; ++i) free(h->pfaces[i]);
    free(h->pfaces);
    free(h->pcount);
    free(h->pcap);
    free(h->loop);
    free(h->first);
    free(h->normal);
    free(h->member);
}

static void poly_free(mk_oracle_poly *P)
{
    free(P->v);
    free(P->face_first);
    free(P->face_vert);
    free(P->fn);
    free(P->fc);
    free(P->fr);
    free(P->ev);
    free(P->ef);
    free(P->probe);
    memset(P, 0, sizeof *P);
}

/* Centroid, radius, and the probe vertices: the support of each of the 26
 * directions (-1, 0, 1)^3 \ 0, without repeats. */
static int poly_finish(mk_oracle_poly *P)
{
    int i, dx, dy, dz;
    P->centroid = lv(0, 0, 0);
    P->radius = 0;
    for (i = 0; i < P->nv; ++i) {
        P->centroid = ladd(P->centroid, P->v[i]);
        if (llen(P->v[i]) > P->radius) P->radius = llen(P->v[i]);
    }
    P->centroid = lscale(P->centroid, 1.0L / (long double)P->nv);
    P->probe = malloc(sizeof *P->probe * 26);
    if (!P->probe) return -1;
    P->nprobe = 0;
    for (dx = -1; dx <= 1; ++dx)
        for (dy = -1; dy <= 1; ++dy)
            for (dz = -1; dz <= 1; ++dz) {
                mk_lvec3 d = lv(dx, dy, dz);
                int best = 0, k;
                if (!dx && !dy && !dz) continue;
                for (i = 1; i < P->nv; ++i)
                    if (ldot(d, P->v[i]) > ldot(d, P->v[best])) best = i;
                for (k = 0; k < P->nprobe && P->probe[k] != best; ++k) continue;
                if (k == P->nprobe) P->probe[P->nprobe++] = best;
            }
    return 0;
}

/* Edges from the face loops: each directed edge must meet exactly one
 * opposite twin, and V - E + F = 2, or the hull is refused. */
static int poly_edges(mk_oracle_poly *P)
{
    int f, i, j, nd = P->face_first[P->nf], ne = 0;
    int *from = malloc(sizeof *from * (size_t)nd * 3), *to = from ? from + nd : NULL, *face = to ? to + nd : NULL;
    if (!from) return -1;
    for (f = 0; f < P->nf; ++f)
        for (i = P->face_first[f]; i < P->face_first[f + 1]; ++i) {
            int nx = i + 1 < P->face_first[f + 1] ? i + 1 : P->face_first[f];
            from[i] = P->face_vert[i];
            to[i] = P->face_vert[nx];
            face[i] = f;
        }
    P->ev = malloc(sizeof *P->ev * (size_t)(nd / 2 + 1));
    P->ef = malloc(sizeof *P->ef * (size_t)(nd / 2 + 1));
    if (!P->ev || !P->ef || nd % 2) {
        free(from);
        return -1;
    }
    for (i = 0; i < nd; ++i) {
        int twins = 0, twin = -1;
        for (j = 0; j < nd; ++j)
            if (from[j] == to[i] && to[j] == from[i]) ++twins, twin = j;
        if (twins != 1) {
            free(from);
            return -1;
        }
        if (from[i] < to[i]) {
            P->ev[ne][0] = from[i];
            P->ev[ne][1] = to[i];
            P->ef[ne][0] = face[i];
            P->ef[ne][1] = face[twin];
            ++ne;
        }
    }
    free(from);
    P->ne = ne;
    return P->nv - ne + P->nf == 2 ? 0 : -1;
}

static int poly_from_tmp(mk_oracle_poly *P, const hull_tmp *h, const mk_lvec3 *p)
{
    int *map = malloc(sizeof *map * (size_t)h->n), i, f;
    if (!map) return -1;
    memset(P, 0, sizeof *P);
    for (i = 0; i < h->n; ++i) map[i] = -1;
    for (i = 0; i < h->nloop; ++i)
        if (map[h->loop[i]] < 0) map[h->loop[i]] = P->nv++;
    P->nf = h->nf;
    P->v = malloc(sizeof *P->v * (size_t)P->nv);
    P->face_first = malloc(sizeof *P->face_first * (size_t)(P->nf + 1));
    P->face_vert = malloc(sizeof *P->face_vert * (size_t)h->nloop);
    P->fn = malloc(sizeof *P->fn * (size_t)P->nf);
    P->fc = malloc(sizeof *P->fc * (size_t)P->nf);
    P->fr = malloc(sizeof *P->fr * (size_t)P->nf);
    if (!P->v || !P->face_first || !P->face_vert || !P->fn || !P->fc || !P->fr) {
        free(map);
        return -1;
    }
    for (i = 0; i < h->n; ++i)
        if (map[i] >= 0) P->v[map[i]] = p[i];
    for (i = 0; i < h->nloop; ++i) P->face_vert[i] = map[h->loop[i]];
    for (f = 0; f <= P->nf; ++f) P->face_first[f] = h->first[f];
    for (f = 0; f < P->nf; ++f) {
        int cnt = h->first[f + 1] - h->first[f];
        mk_lvec3 c = lv(0, 0, 0);
        long double r = 0;
        for (i = h->first[f]; i < h->first[f + 1]; ++i) c = ladd(c, p[h->loop[i]]);
        c = lscale(c, 1.0L / (long double)cnt);
        for (i = h->first[f]; i < h->first[f + 1]; ++i)
            if (llen(lsub(p[h->loop[i]], c)) > r) r = llen(lsub(p[h->loop[i]], c));
        P->fn[f] = h->normal[f];
        P->fc[f] = c;
        P->fr[f] = r;
    }
    free(map);
    return poly_finish(P) ? -1 : poly_edges(P);
}

static int poly_hull(mk_oracle_poly *P, const mk_lvec3 *p, int n)
{
    hull_tmp h;
    long double extent = 0;
    int i, j, rc = -1;
    memset(&h, 0, sizeof h);
    memset(P, 0, sizeof *P);
    if (n < 4) return -1;
    for (i = 0; i < n; ++i) {
        if (!lfinite(p[i].x) || !lfinite(p[i].y) || !lfinite(p[i].z)) return -1;
        for (j = 0; j < i; ++j)
            if (llen(lsub(p[i], p[j])) > extent) extent = llen(lsub(p[i], p[j]));
    }
    h.n = n;
    h.pfaces = calloc((size_t)n, sizeof *h.pfaces);
    h.pcount = calloc((size_t)n, sizeof *h.pcount);
    h.pcap = calloc((size_t)n, sizeof *h.pcap);
    if (h.pfaces && h.pcount && h.pcap && extent > 0 && find_faces(&h, p, extent) == 0)
        rc = poly_from_tmp(P, &h, p);
    hull_tmp_free(&h);
    if (rc) poly_free(P);
    return rc;
}

/* A point (sphere core) or a segment along z (capsule core): no faces. */
static int poly_segment(mk_oracle_poly *P, long double half_height)
{
    memset(P, 0, sizeof *P);
    P->nv = half_height > 0 ? 2 : 1;
    P->ne = P->nv - 1;
    P->v = malloc(sizeof *P->v * 2);
    P->face_first = calloc(1, sizeof *P->face_first);
    P->ev = malloc(sizeof *P->ev);
    P->ef = malloc(sizeof *P->ef);
    if (!P->v || !P->face_first || !P->ev || !P->ef) {
        poly_free(P);
        return -1;
    }
    P->v[0] = lv(0, 0, -half_height);
    P->v[1] = lv(0, 0, half_height);
    P->ev[0][0] = 0;
    P->ev[0][1] = 1;
    P->ef[0][0] = P->ef[0][1] = -1;
    if (poly_finish(P)) {
        poly_free(P);
        return -1;
    }
    return 0;
}

/* ---- shapes and poses ---------------------------------------------------- */

int mk_oracle_shape_points(mk_oracle_shape *o, const mk_lvec3 *points, int n, long double rounding)
{
    memset(o, 0, sizeof *o);
    o->type = MK_SHAPE_HULL;
    o->rounding = rounding;
    if (!(rounding >= 0) || !lfinite(rounding) || poly_hull(&o->core, points, n)) return -1;
    o->size = o->core.radius + rounding;
    return 0;
}

static int box_init(mk_oracle_shape *o, mk_lvec3 h, long double rounding)
{
    mk_lvec3 c[8];
    int i, rc;
    for (i = 0; i < 8; ++i) c[i] = lv(i & 1 ? h.x : -h.x, i & 2 ? h.y : -h.y, i & 4 ? h.z : -h.z);
    rc = mk_oracle_shape_points(o, c, 8, rounding);
    o->type = MK_SHAPE_BOX;
    return rc;
}

int mk_oracle_shape_init(mk_oracle_shape *o, const mk_shape *s)
{
    int i, rc;
    memset(o, 0, sizeof *o);
    if (!s || mk_shape_validate(s) != MK_OK) return -1;
    o->type = s->type;
    o->rounding = s->radius;
    switch (s->type) {
    case MK_SHAPE_SPHERE: rc = poly_segment(&o->core, 0); break;
    case MK_SHAPE_CAPSULE: rc = poly_segment(&o->core, s->u.capsule.half_height); break;
    case MK_SHAPE_BOX: return box_init(o, lfrom(s->u.half_extents), s->radius);
    case MK_SHAPE_HULL: {
        mk_lvec3 *p = malloc(sizeof *p * (size_t)s->u.hull->vertex_count);
        if (!p) return -1;
        for (i = 0; i < s->u.hull->vertex_count; ++i) p[i] = lfrom(s->u.hull->vertices[i]);
        rc = mk_oracle_shape_points(o, p, s->u.hull->vertex_count, s->radius);
        free(p);
        return rc;
    }
    case MK_SHAPE_CYLINDER:
        o->disc_radius = s->u.cylinder.radius;
        o->half_height = s->u.cylinder.half_height;
        o->size = sqrtl(o->disc_radius * o->disc_radius + o->half_height * o->half_height) + o->rounding;
        return 0;
    case MK_SHAPE_CONE:
        o->disc_radius = s->u.cone.radius;
        o->half_height = s->u.cone.half_height;
        o->size = sqrtl(o->disc_radius * o->disc_radius + o->half_height * o->half_height) + o->rounding;
        return 0;
    case MK_SHAPE_PLANE:
        o->plane_n = lnormalize(lfrom(s->u.plane.normal));
        o->plane_d = s->u.plane.offset;
        o->rounding = 0;
        return 0;
    default: return -1;
    }
    if (rc == 0) o->size = o->core.radius + o->rounding;
    return rc;
}

void mk_oracle_shape_free(mk_oracle_shape *o)
{
    if (o) poly_free(&o->core);
}

mk_oracle_pose mk_oracle_pose_of(mk_transform xf)
{
    mk_oracle_pose P;
    long double x = xf.q.x, y = xf.q.y, z = xf.q.z, w = xf.q.w, l = sqrtl(x * x + y * y + z * z + w * w);
    x /= l, y /= l, z /= l, w /= l;
    P.r[0][0] = 1 - 2 * (y * y + z * z), P.r[0][1] = 2 * (x * y - w * z), P.r[0][2] = 2 * (x * z + w * y);
    P.r[1][0] = 2 * (x * y + w * z), P.r[1][1] = 1 - 2 * (x * x + z * z), P.r[1][2] = 2 * (y * z - w * x);
    P.r[2][0] = 2 * (x * z - w * y), P.r[2][1] = 2 * (y * z + w * x), P.r[2][2] = 1 - 2 * (x * x + y * y);
    P.p = lfrom(xf.p);
    return P;
}

/* ---- per-query views: a polytope placed in A's frame, with derived data --- */

typedef struct view {
    const mk_oracle_poly *p;  /* topology */
    mk_lvec3 *v, *fn, *fc;    /* placed vertices, normals, face centroids */
    mk_lvec3 *em, *ek;        /* edge midpoints, Gauss-arc plane normals fn0 x fn1 */
    long double *eh;          /* edge half lengths */
    double (*fn_d)[3], (*ek_d)[3]; /* double copies for the Gauss-map pre-filter */
    mk_lvec3 centroid;
} view;

static void view_free(view *w)
{
    free(w->v);
    free(w->eh);
    free(w->fn_d);
    memset(w, 0, sizeof *w);
}

static mk_lvec3 place(const long double (*r)[3], mk_lvec3 t, mk_lvec3 v) { return r ? ladd(lrot(r, v), t) : v; }

/* r == NULL: the polytope stays in its own frame (A). */
static int view_make(view *w, const mk_oracle_poly *p, const long double (*r)[3], mk_lvec3 t)
{
    int i, n = p->nv + 2 * p->nf + 2 * p->ne;
    memset(w, 0, sizeof *w);
    w->p = p;
    w->v = malloc(sizeof *w->v * (size_t)(n > 0 ? n : 1));
    w->eh = malloc(sizeof *w->eh * (size_t)(p->ne > 0 ? p->ne : 1));
    w->fn_d = malloc(sizeof *w->fn_d * (size_t)(p->nf + p->ne + 1));
    if (!w->v || !w->eh || !w->fn_d) {
        view_free(w);
        return -1;
    }
    w->ek_d = w->fn_d + p->nf;
    w->fn = w->v + p->nv;
    w->fc = w->fn + p->nf;
    w->em = w->fc + p->nf;
    w->ek = w->em + p->ne;
    for (i = 0; i < p->nv; ++i) w->v[i] = place(r, t, p->v[i]);
    for (i = 0; i < p->nf; ++i) {
        w->fn[i] = r ? lrot(r, p->fn[i]) : p->fn[i];
        w->fc[i] = place(r, t, p->fc[i]);
    }
    for (i = 0; i < p->ne; ++i) {
        mk_lvec3 a = w->v[p->ev[i][0]], b = w->v[p->ev[i][1]];
        w->em[i] = lscale(ladd(a, b), 0.5L);
        w->eh[i] = 0.5L * llen(lsub(b, a));
        w->ek[i] = p->ef[i][0] >= 0 ? lcross(w->fn[p->ef[i][0]], w->fn[p->ef[i][1]]) : lv(0, 0, 0);
        w->ek_d[i][0] = (double)w->ek[i].x, w->ek_d[i][1] = (double)w->ek[i].y, w->ek_d[i][2] = (double)w->ek[i].z;
    }
    for (i = 0; i < p->nf; ++i)
        w->fn_d[i][0] = (double)w->fn[i].x, w->fn_d[i][1] = (double)w->fn[i].y, w->fn_d[i][2] = (double)w->fn[i].z;
    w->centroid = place(r, t, p->centroid);
    return 0;
}

/* ---- feature distances ---------------------------------------------------- */

typedef struct pair { long double d2, d; mk_lvec3 pa, pb; } pair; /* d = sqrt(d2), for the pruning bound */

static void consider(pair *best, mk_lvec3 pa, mk_lvec3 pb)
{
    mk_lvec3 d = lsub(pb, pa);
    long double d2 = ldot(d, d);
    if (d2 < best->d2) {
        best->d2 = d2;
        best->d = sqrtl(d2);
        best->pa = pa;
        best->pb = pb;
    }
}

static mk_lvec3 closest_on_segment(mk_lvec3 p, mk_lvec3 a, mk_lvec3 b)
{
    mk_lvec3 ab = lsub(b, a);
    long double l2 = ldot(ab, ab), t = l2 > 0 ? ldot(lsub(p, a), ab) / l2 : 0;
    return lmad(a, t < 0 ? 0 : t > 1 ? 1 : t, ab);
}

/* Segment-segment: the minimum of a convex function over [0,1]^2 is either
 * the interior stationary point or on one of the four sides (point-segment).
 * Every candidate is a real pair of points, so an ill-conditioned interior
 * solve (nearly parallel) can only lose to a side, never undercut the truth. */
static void segment_segment(pair *best, mk_lvec3 p1, mk_lvec3 q1, mk_lvec3 p2, mk_lvec3 q2, int a_first)
{
    mk_lvec3 d1 = lsub(q1, p1), d2 = lsub(q2, p2), r = lsub(p1, p2);
    long double a = ldot(d1, d1), e = ldot(d2, d2), b = ldot(d1, d2), c = ldot(d1, r), f = ldot(d2, r);
    long double den = a * e - b * b;
    pair loc;
    loc.d2 = best->d2;
    loc.d = best->d;
    loc.pa = loc.pb = lv(0, 0, 0);
    consider(&loc, p1, closest_on_segment(p1, p2, q2));
    consider(&loc, q1, closest_on_segment(q1, p2, q2));
    consider(&loc, closest_on_segment(p2, p1, q1), p2);
    consider(&loc, closest_on_segment(q2, p1, q1), q2);
    if (den > 0) {
        long double s = (b * f - c * e) / den, t = (a * f - b * c) / den;
        if (s > 0 && s < 1 && t > 0 && t < 1) consider(&loc, lmad(p1, s, d1), lmad(p2, t, d2));
    }
    if (loc.d2 < best->d2) {
        best->d2 = loc.d2;
        best->d = loc.d;
        best->pa = a_first ? loc.pa : loc.pb;
        best->pb = a_first ? loc.pb : loc.pa;
    }
}

/* Projection of p onto face f if it falls inside the polygon (edges and
 * vertices are other features); returns 0 otherwise. */
static int onto_face(const view *w, int f, mk_lvec3 p, mk_lvec3 *q)
{
    const mk_oracle_poly *P = w->p;
    mk_lvec3 n = w->fn[f];
    int i, lo = P->face_first[f], hi = P->face_first[f + 1];
    for (i = lo; i < hi; ++i) {
        mk_lvec3 a = w->v[P->face_vert[i]], b = w->v[P->face_vert[i + 1 < hi ? i + 1 : lo]];
        if (ldot(lcross(lsub(b, a), lsub(p, a)), n) < 0) return 0;
    }
    *q = lmad(p, -ldot(n, lsub(p, w->v[P->face_vert[lo]])), n);
    return 1;
}

/* Lower bound test: can two balls (c1, r1), (c2, r2) hold points closer than best? */
static int may_beat(const pair *best, mk_lvec3 c1, long double r1, mk_lvec3 c2, long double r2)
{
    mk_lvec3 d = lsub(c1, c2);
    long double reach = best->d + r1 + r2;
    return ldot(d, d) < reach * reach;
}

/* Vertex against vertices, edges and faces of the other polytope. */
static void vertex_features(pair *best, mk_lvec3 p, const view *o, int p_is_a)
{
    int j;
    mk_lvec3 q;
    for (j = 0; j < o->p->nv; ++j)
        if (p_is_a) consider(best, p, o->v[j]);
        else consider(best, o->v[j], p);
    for (j = 0; j < o->p->ne; ++j) {
        if (!may_beat(best, p, 0, o->em[j], o->eh[j])) continue;
        q = closest_on_segment(p, o->v[o->p->ev[j][0]], o->v[o->p->ev[j][1]]);
        if (p_is_a) consider(best, p, q);
        else consider(best, q, p);
    }
    for (j = 0; j < o->p->nf; ++j) {
        if (!may_beat(best, p, 0, o->fc[j], o->p->fr[j]) || !onto_face(o, j, p, &q)) continue;
        if (p_is_a) consider(best, p, q);
        else consider(best, q, p);
    }
}

/* Distance between two separated polytopes: the minimum over all feature pairs. */
static pair feature_distance(const view *A, const view *B)
{
    pair best;
    int i, j;
    best.d2 = best.d = HUGE_VALL;
    best.pa = best.pb = lv(0, 0, 0);
    for (i = 0; i < A->p->nv; ++i) vertex_features(&best, A->v[i], B, 1);
    for (j = 0; j < B->p->nv; ++j) vertex_features(&best, B->v[j], A, 0);
    for (i = 0; i < A->p->ne; ++i)
        for (j = 0; j < B->p->ne; ++j)
            if (may_beat(&best, A->em[i], A->eh[i], B->em[j], B->eh[j]))
                segment_segment(&best, A->v[A->p->ev[i][0]], A->v[A->p->ev[i][1]], B->v[B->p->ev[j][0]],
                                B->v[B->p->ev[j][1]], 1);
    return best;
}

/* ---- SAT ------------------------------------------------------------------ */

typedef struct axis { mk_lvec3 n; long double s; } axis;
typedef struct axes {
    axis *a;
    int n, cap;
    long double best; /* largest separation evaluated so far */
    long double skip; /* an axis whose separation is certainly below best - skip is not evaluated */
    int exhaustive;
} axes;

static void extent(const view *w, const int *idx, int n, mk_lvec3 d, long double *lo, long double *hi)
{
    int i;
    *lo = HUGE_VALL, *hi = -HUGE_VALL;
    for (i = 0; i < n; ++i) {
        long double t = ldot(d, w->v[idx ? idx[i] : i]);
        if (t < *lo) *lo = t;
        if (t > *hi) *hi = t;
    }
}

/* Separation of B from A along n and along -n: min_b n.b - max_a n.a. The
 * probe vertices are a subset, so their extents give upper bounds of both
 * separations; if neither bound reaches best - skip, the axis can neither be
 * the answer nor tie with it, and the full scans are spared. */
static int push_axis(axes *L, const view *A, const view *B, mk_lvec3 n)
{
    long double amin, amax, bmin, bmax;
    if (!L->exhaustive && L->n > 0) {
        extent(A, A->p->probe, A->p->nprobe, n, &amin, &amax);
        extent(B, B->p->probe, B->p->nprobe, n, &bmin, &bmax);
        if (bmin - amax < L->best - L->skip && amin - bmax < L->best - L->skip) return 0;
    }
    if (grow((void **)&L->a, &L->cap, L->n + 2, sizeof *L->a)) return -1;
    extent(A, NULL, A->p->nv, n, &amin, &amax);
    extent(B, NULL, B->p->nv, n, &bmin, &bmax);
    L->a[L->n].n = n;
    L->a[L->n++].s = bmin - amax;
    L->a[L->n].n = lscale(n, -1);
    L->a[L->n++].s = amin - bmax;
    if (bmin - amax > L->best) L->best = bmin - amax;
    if (amin - bmax > L->best) L->best = amin - bmax;
    return 0;
}

/* Can edge i of A and edge j of B span a face of the Minkowski difference
 * A - B? Their Gauss-map arcs (between the normals of each edge's two faces;
 * B's arc negated) must cross. Comparisons are non-strict: keeping a pair that
 * is not a face only adds a valid upper bound. Bare segments have no arc.
 * This runs for every edge pair, so a double-precision pass rejects the
 * clear cases first: unit vectors give dot products within ~1e-15 of the long
 * double ones, and only a product of two dots both clearly of one sign is
 * trusted to reject. */
static int same_sign(double a, double b) { return (a > 1e-14 && b > 1e-14) || (a < -1e-14 && b < -1e-14); }
static double ddot(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static int minkowski_face(const view *A, int i, const view *B, int j)
{
    const int *fa = A->p->ef[i], *fb = B->p->ef[j];
    long double c1, c2, c3, c4;
    if (fa[0] < 0 || fb[0] < 0) return 1;
    if (same_sign(ddot(B->fn_d[fb[0]], A->ek_d[i]), ddot(B->fn_d[fb[1]], A->ek_d[i])) ||
        same_sign(ddot(A->fn_d[fa[0]], B->ek_d[j]), ddot(A->fn_d[fa[1]], B->ek_d[j])))
        return 0;
    c1 = ldot(B->fn[fb[0]], A->ek[i]);
    c2 = ldot(B->fn[fb[1]], A->ek[i]);
    if (c1 * c2 > 0) return 0;
    c3 = ldot(A->fn[fa[0]], B->ek[j]);
    c4 = ldot(A->fn[fa[1]], B->ek[j]);
    return c3 * c4 <= 0 && c1 * c4 <= 0;
}

static int sat_axes(axes *L, const view *A, const view *B, unsigned flags, long double gap)
{
    int i, j;
    L->best = -HUGE_VALL;
    L->skip = gap;
    L->exhaustive = (flags & MK_ORACLE_EXHAUSTIVE) != 0;
    for (i = 0; i < A->p->nf; ++i)
        if (push_axis(L, A, B, A->fn[i])) return -1;
    for (j = 0; j < B->p->nf; ++j)
        if (push_axis(L, A, B, B->fn[j])) return -1;
    for (i = 0; i < A->p->ne; ++i)
        for (j = 0; j < B->p->ne; ++j) {
            mk_lvec3 ea, eb, c;
            long double lc;
            if (!(flags & MK_ORACLE_EXHAUSTIVE) && !minkowski_face(A, i, B, j)) continue;
            ea = lsub(A->v[A->p->ev[i][1]], A->v[A->p->ev[i][0]]);
            eb = lsub(B->v[B->p->ev[j][1]], B->v[B->p->ev[j][0]]);
            c = lcross(ea, eb);
            lc = llen(c);
            if (lc <= PARALLEL_SIN * 4 * A->eh[i] * B->eh[j]) continue;
            if (push_axis(L, A, B, lscale(c, 1 / lc))) return -1;
        }
    return 0;
}

/* Index of the best (largest separation) axis; *unique says whether every
 * axis pointing elsewhere (> 1e-7 rad away) is worse by more than `gap`. */
static int best_axis(const axes *L, long double gap, int *unique)
{
    int i, b = 0;
    long double second = -HUGE_VALL;
    for (i = 1; i < L->n; ++i)
        if (L->a[i].s > L->a[b].s) b = i;
    for (i = 0; i < L->n; ++i)
        if (llen(lcross(L->a[i].n, L->a[b].n)) > 1e-7L || ldot(L->a[i].n, L->a[b].n) < 0)
            if (L->a[i].s > second) second = L->a[i].s;
    *unique = L->a[b].s - second > gap;
    return b;
}

/* ---- queries -------------------------------------------------------------- */

/* max over the solid's core of d.x, d unit, in the shape's local frame. */
static long double core_support(const mk_oracle_shape *s, mk_lvec3 d)
{
    long double best = -HUGE_VALL, sigma = sqrtl(d.x * d.x + d.y * d.y);
    int i;
    switch (s->type) {
    case MK_SHAPE_CYLINDER: return s->disc_radius * sigma + s->half_height * fabsl(d.z);
    case MK_SHAPE_CONE: {
        long double apex = s->half_height * d.z, rim = s->disc_radius * sigma - s->half_height * d.z;
        return apex > rim ? apex : rim;
    }
    default:
        for (i = 0; i < s->core.nv; ++i)
            if (ldot(d, s->core.v[i]) > best) best = ldot(d, s->core.v[i]);
        return best;
    }
}

/* Shape s at pose xs against the half-space of plane shape p at xp. */
static void plane_query(const mk_oracle_shape *s, const mk_oracle_pose *xs, const mk_oracle_shape *p,
                        const mk_oracle_pose *xp, int plane_is_a, mk_oracle_result *out)
{
    mk_lvec3 nw = lrot(xp->r, p->plane_n);
    long double dw = p->plane_d + ldot(nw, xp->p);
    mk_lvec3 nl = lrot_t(xs->r, nw);
    /* min over the solid of n.x = -(support along -n) - rounding */
    long double lowest = -core_support(s, lscale(nl, -1)) - s->rounding + ldot(nw, xs->p);
    out->distance = lowest - dw;
    out->normal = plane_is_a ? nw : lscale(nw, -1);
    out->normal_defined = 1;
}

static int poly_query(const mk_oracle_shape *a, const mk_oracle_pose *xa, const mk_oracle_shape *b,
                      const mk_oracle_pose *xb, unsigned flags, mk_oracle_result *out)
{
    long double r[3][3], scale = a->size > b->size ? a->size : b->size;
    long double tie = 1e-9L * scale; /* axes closer than this in separation make the normal ambiguous */
    mk_lvec3 t = lrot_t(xa->r, lsub(xb->p, xa->p)), n;
    view A, B;
    axes L;
    pair closest;
    int i, j, k, unique = 1, rc = 0;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            r[i][j] = 0;
            for (k = 0; k < 3; ++k) r[i][j] += xa->r[k][i] * xb->r[k][j];
        }
    memset(&L, 0, sizeof L);
    memset(&B, 0, sizeof B);
    if (view_make(&A, &a->core, NULL, t) || view_make(&B, &b->core, (const long double(*)[3])r, t)) {
        view_free(&A);
        view_free(&B);
        return -1;
    }

    if (a->core.nf == 0 && b->core.nf == 0) {
        /* Points and segments (sphere and capsule cores): closed-form feature distance. */
        closest = feature_distance(&A, &B);
        n = lsub(closest.pb, closest.pa);
        unique = closest.d2 > 0;
        out->distance = sqrtl(closest.d2);
        out->normal = unique ? lnormalize(n) : lv(0, 0, 1);
    } else if (sat_axes(&L, &A, &B, flags, tie)) {
        rc = -1;
    } else {
        int bi = best_axis(&L, tie, &unique);
        if (L.a[bi].s > 0) {
            closest = feature_distance(&A, &B);
            out->distance = sqrtl(closest.d2);
            /* Closest points give the normal unless they are too close to carry a direction. */
            if (out->distance > 1e-12L * scale) {
                out->normal = lnormalize(lsub(closest.pb, closest.pa));
                unique = 1;
            } else {
                out->normal = L.a[bi].n;
            }
        } else {
            out->distance = L.a[bi].s;
            out->normal = L.a[bi].n;
        }
    }
    free(L.a);
    view_free(&A);
    view_free(&B);
    out->distance -= a->rounding + b->rounding;
    out->normal = lrot(xa->r, out->normal);
    out->normal_defined = unique;
    return rc;
}

static int has_core(const mk_oracle_shape *s) { return s->core.nv > 0; }

int mk_oracle_query(const mk_oracle_shape *a, const mk_oracle_pose *xa, const mk_oracle_shape *b,
                    const mk_oracle_pose *xb, unsigned flags, mk_oracle_result *out)
{
    if (!a || !xa || !b || !xb || !out) return -1;
    if (a->type == MK_SHAPE_PLANE && b->type == MK_SHAPE_PLANE) return -1;
    if (b->type == MK_SHAPE_PLANE) {
        plane_query(a, xa, b, xb, 0, out);
        return 0;
    }
    if (a->type == MK_SHAPE_PLANE) {
        plane_query(b, xb, a, xa, 1, out);
        return 0;
    }
    if (!has_core(a) || !has_core(b)) return -1; /* cylinder/cone against a non-plane */
    return poly_query(a, xa, b, xb, flags, out);
}

int mk_oracle_distance(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb, mk_oracle_result *out)
{
    mk_oracle_shape oa, ob;
    mk_oracle_pose pa = mk_oracle_pose_of(xa), pb = mk_oracle_pose_of(xb);
    int rc = -1;
    memset(&oa, 0, sizeof oa);
    memset(&ob, 0, sizeof ob);
    if (mk_oracle_shape_init(&oa, a) == 0 && mk_oracle_shape_init(&ob, b) == 0) rc = mk_oracle_query(&oa, &pa, &ob, &pb, 0, out);
    mk_oracle_shape_free(&oa);
    mk_oracle_shape_free(&ob);
    return rc;
}

long double mk_oracle_angle_deg(mk_lvec3 ref, long double x, long double y, long double z)
{
    mk_lvec3 v = lv(x, y, z);
    long double l = llen(v);
    if (!(l > 0) || !lfinite(l)) return 180;
    v = lscale(v, 1 / l);
    return atan2l(llen(lcross(ref, v)), ldot(ref, v)) * (180.0L / 3.14159265358979323846264338327950288L);
}

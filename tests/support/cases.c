/* cases.c: seeded case families and regression cases (contract in cases.h).
 *
 * Generation runs in double on float-rounded numbers and never touches
 * mk_real arithmetic, so both builds draw the same cases from the same seed.
 * Each candidate is judged by the oracle and kept only if its sign (and, per
 * family, its magnitude) is what the family asks for.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cases.h"
#include "mk_rng.h"

struct mk_case_store {
    mk_oracle_shape **shapes;
    int count, cap;
    mk_hull **hulls;
    int nhulls, hcap;
};

static const char *const family_names[MK_FAM_COUNT] = {
    "sphere_sphere", "box_sphere", "capsule_capsule", "box_box", "hull_hull_8", "hull_hull_32", "hull_hull_128",
    "hull_box", "flat_boxes", "thin_rods",
    "large_coords", "tiny", "nearly_touching", "parallel_faces", "deep"};

const char *mk_family_name(mk_family f) { return (unsigned)f < MK_FAM_COUNT ? family_names[f] : "unknown"; }

int mk_family_closed_form(mk_family f)
{
    return f == MK_FAM_SPHERE_SPHERE || f == MK_FAM_BOX_SPHERE || f == MK_FAM_CAPSULE_CAPSULE;
}

/* ---- storage --------------------------------------------------------------- */

static struct mk_case_store *store_of(mk_case_set *set)
{
    if (!set->store) set->store = calloc(1, sizeof *set->store);
    return set->store;
}

/* Takes ownership of an initialised oracle shape (freed on failure). */
static int keep_shape(mk_case_set *set, mk_oracle_shape *o, const mk_oracle_shape **out)
{
    struct mk_case_store *st = store_of(set);
    if (st && st->count == st->cap) {
        int cap = st->cap ? 2 * st->cap : 64;
        mk_oracle_shape **p = realloc(st->shapes, sizeof *p * (size_t)cap);
        if (p) st->shapes = p, st->cap = cap;
    }
    if (!st || st->count == st->cap) {
        mk_oracle_shape_free(o);
        free(o);
        return -1;
    }
    st->shapes[st->count++] = o;
    *out = o;
    return 0;
}

static int own_shape(mk_case_set *set, const mk_shape *s, const mk_oracle_shape **out)
{
    mk_oracle_shape *o = malloc(sizeof *o);
    if (!o || mk_oracle_shape_init(o, s)) {
        if (o) mk_oracle_shape_free(o);
        free(o);
        return -1;
    }
    return keep_shape(set, o, out);
}

static int keep_hull(mk_case_set *set, mk_hull *h)
{
    struct mk_case_store *st = store_of(set);
    if (st && st->nhulls == st->hcap) {
        int cap = st->hcap ? 2 * st->hcap : 16;
        mk_hull **p = realloc(st->hulls, sizeof *p * (size_t)cap);
        if (p) st->hulls = p, st->hcap = cap;
    }
    if (!st || st->nhulls == st->hcap) {
        mk_hull_destroy(h);
        return -1;
    }
    st->hulls[st->nhulls++] = h;
    return 0;
}

/* Drops the shapes added since `mark` (a rejected candidate's). */
static void release_since(mk_case_set *set, int mark)
{
    struct mk_case_store *st = set->store;
    while (st && st->count > mark) {
        mk_oracle_shape *o = st->shapes[--st->count];
        mk_oracle_shape_free(o);
        free(o);
    }
}

static int push_case(mk_case_set *set, const mk_case *c)
{
    if (set->count == set->cap) {
        int cap = set->cap ? 2 * set->cap : 64;
        mk_case *p = realloc(set->cases, sizeof *p * (size_t)cap);
        if (!p) return -1;
        set->cases = p;
        set->cap = cap;
    }
    set->cases[set->count++] = *c;
    return 0;
}

void mk_case_set_free(mk_case_set *set)
{
    if (!set) return;
    release_since(set, 0);
    if (set->store) {
        int i;
        for (i = 0; i < set->store->nhulls; ++i) mk_hull_destroy(set->store->hulls[i]);
        free(set->store->hulls);
        free(set->store->shapes);
    }
    free(set->store);
    free(set->cases);
    memset(set, 0, sizeof *set);
}

/* ---- float-rounded random inputs ------------------------------------------ */

/* Rounds to float. The volatile is not decoration: GCC 12.2 at -O2 SLP-
 * vectorises (double)(float)a for two lanes of a vector and drops the round
 * trip (cvtpd2ps/cvtps2pd never emitted), so plain casts silently left hull
 * points unrounded while the long double copies were rounded. */
static double f32(double x)
{
    volatile float f = (float)x;
    return (double)f;
}
static double rnd(mk_rng *r, double lo, double hi) { return mk_rng_range(r, lo, hi); }

typedef struct dv3 { double x, y, z; } dv3;
static dv3 d3(double x, double y, double z) { dv3 v; v.x = x; v.y = y; v.z = z; return v; }
static dv3 d3add(dv3 a, dv3 b) { return d3(a.x + b.x, a.y + b.y, a.z + b.z); }
static dv3 d3scale(dv3 a, double s) { return d3(a.x * s, a.y * s, a.z * s); }
static double d3len(dv3 a) { return sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }
static dv3 d3f32(dv3 a) { return d3(f32(a.x), f32(a.y), f32(a.z)); }
static mk_vec3 to_mk(dv3 a) { return mk_v3((mk_real)a.x, (mk_real)a.y, (mk_real)a.z); }

static dv3 rand_dir(mk_rng *r)
{
    for (;;) {
        dv3 v = d3(rnd(r, -1, 1), rnd(r, -1, 1), rnd(r, -1, 1));
        double l = d3len(v);
        if (l > 1e-2 && l <= 1) return d3scale(v, 1 / l);
    }
}

/* Shoemake's uniform rotation, components rounded to float (so |q| is 1 only
 * to ~1e-7: the library must renormalise, the oracle does so exactly). */
static mk_quat rand_quat(mk_rng *r)
{
    double u1 = mk_rng_unit(r), u2 = 6.283185307179586 * mk_rng_unit(r), u3 = 6.283185307179586 * mk_rng_unit(r);
    double a = sqrt(1 - u1), b = sqrt(u1);
    return mk_quat_make((mk_real)f32(a * sin(u2)), (mk_real)f32(a * cos(u2)), (mk_real)f32(b * sin(u3)),
                        (mk_real)f32(b * cos(u3)));
}

/* q v q* in double for a float-exact q, normalised here, so positions built
 * from rotated offsets come out the same in both builds. */
static dv3 qrot(mk_quat q, dv3 v)
{
    double x = q.x, y = q.y, z = q.z, w = q.w, l = sqrt(x * x + y * y + z * z + w * w);
    double tx, ty, tz;
    x /= l, y /= l, z /= l, w /= l;
    tx = 2 * (y * v.z - z * v.y), ty = 2 * (z * v.x - x * v.z), tz = 2 * (x * v.y - y * v.x);
    return d3(v.x + w * tx + (y * tz - z * ty), v.y + w * ty + (z * tx - x * tz), v.z + w * tz + (x * ty - y * tx));
}

static mk_transform xf(dv3 p, mk_quat q) { return mk_transform_make(to_mk(d3f32(p)), q); }

static mk_shape box(dv3 h)
{
    mk_shape s;
    mk_shape_box(to_mk(d3f32(h)), 0, &s);
    return s;
}

static dv3 rand_half(mk_rng *r, double lo, double hi) { return d3(rnd(r, lo, hi), rnd(r, lo, hi), rnd(r, lo, hi)); }

/* ---- judging ------------------------------------------------------------------ */

/* A candidate; oa / ob are the judge's shapes when they already exist (pool
 * hulls), else judge() builds them from a / b. */
typedef struct cand {
    mk_shape a, b;
    mk_transform xa, xb;
    const mk_oracle_shape *oa, *ob;
} cand;

/* Runs the oracle on a candidate and fills a case; the shapes stay owned. */
static int judge(mk_case_set *set, const cand *c, mk_case *out)
{
    mk_oracle_pose pa = mk_oracle_pose_of(c->xa), pb = mk_oracle_pose_of(c->xb);
    mk_oracle_result r;
    memset(out, 0, sizeof *out);
    out->oa = c->oa;
    out->ob = c->ob;
    if ((!out->oa && own_shape(set, &c->a, &out->oa)) || (!out->ob && own_shape(set, &c->b, &out->ob))) return -1;
    if (mk_oracle_query(out->oa, &pa, out->ob, &pb, 0, &r)) return -1;
    out->a = c->a;
    out->b = c->b;
    out->xa = c->xa;
    out->xb = c->xb;
    out->distance = (double)r.distance;
    out->normal[0] = (double)r.normal.x;
    out->normal[1] = (double)r.normal.y;
    out->normal[2] = (double)r.normal.z;
    out->normal_defined = r.normal_defined;
    out->size = (double)(out->oa->size > out->ob->size ? out->oa->size : out->ob->size);
    return 0;
}

/* ---- family generators: one candidate each ------------------------------------ */

/* B's centre at distance rho (uniform up to `reach`) in a random direction from A's. */
static void place_pair(mk_rng *r, cand *c, double reach, double spread, double scale, dv3 offset)
{
    dv3 pa = d3add(offset, d3scale(d3(rnd(r, -1, 1), rnd(r, -1, 1), rnd(r, -1, 1)), spread * scale));
    dv3 pb = d3add(pa, d3scale(rand_dir(r), rnd(r, 0, reach)));
    c->xa = xf(pa, rand_quat(r));
    c->xb = xf(pb, rand_quat(r));
}

static double box_radius(dv3 h) { return d3len(h); }

static void gen_spheres(mk_rng *r, int pen, cand *c)
{
    double ra = f32(rnd(r, 0.1, 1)), rb = f32(rnd(r, 0.1, 1));
    double gap = pen ? -rnd(r, 0.01, 0.9) * (ra < rb ? ra : rb) : rnd(r, 0.01, 1) * (ra + rb);
    dv3 pa = d3(rnd(r, -1, 1), rnd(r, -1, 1), rnd(r, -1, 1));
    mk_shape_sphere((mk_real)ra, &c->a);
    mk_shape_sphere((mk_real)rb, &c->b);
    c->xa = xf(pa, rand_quat(r));
    c->xb = xf(d3add(pa, d3scale(rand_dir(r), ra + rb + gap)), rand_quat(r));
}

static void gen_box_sphere(mk_rng *r, cand *c)
{
    dv3 h = rand_half(r, 0.1, 1);
    double rs = f32(rnd(r, 0.05, 0.8));
    c->a = box(h);
    mk_shape_sphere((mk_real)rs, &c->b);
    place_pair(r, c, 1.2 * (box_radius(h) + rs), 1, 1, d3(0, 0, 0));
}

static void gen_capsules(mk_rng *r, cand *c)
{
    double ra = f32(rnd(r, 0.05, 0.5)), ha = f32(rnd(r, 0.1, 1)), rb = f32(rnd(r, 0.05, 0.5)), hb = f32(rnd(r, 0.1, 1));
    mk_shape_capsule((mk_real)ra, (mk_real)ha, &c->a);
    mk_shape_capsule((mk_real)rb, (mk_real)hb, &c->b);
    place_pair(r, c, 1.2 * (ra + ha + rb + hb), 1, 1, d3(0, 0, 0));
}

/* Two boxes with half extents in [lo, hi] x scale around `offset`. */
static void gen_boxes(mk_rng *r, cand *c, double lo, double hi, double scale, dv3 offset)
{
    dv3 ha = d3scale(rand_half(r, lo, hi), scale), hb = d3scale(rand_half(r, lo, hi), scale);
    c->a = box(ha);
    c->b = box(hb);
    place_pair(r, c, 1.2 * (box_radius(ha) + box_radius(hb)), 1, scale, offset);
}

/* Plates of 1 x 1 x 1e-3. */
static void gen_flat(mk_rng *r, cand *c)
{
    dv3 h = d3(0.5, 0.5, 5e-4);
    c->a = box(h);
    c->b = box(h);
    place_pair(r, c, 1.2 * 2 * box_radius(h), 1, 1, d3(0, 0, 0));
}

/* Rods of 100 x 0.01 x 0.01: B's axis passes within 3 cm of a point of A's axis. */
static void gen_rods(mk_rng *r, cand *c)
{
    dv3 h = d3(50, 0.005, 0.005);
    mk_quat qa = rand_quat(r), qb = rand_quat(r);
    dv3 pa = d3(rnd(r, -1, 1), rnd(r, -1, 1), rnd(r, -1, 1));
    dv3 on_a = d3add(pa, qrot(qa, d3(rnd(r, -45, 45), 0, 0)));
    dv3 near = d3add(on_a, d3scale(rand_dir(r), rnd(r, 0, 0.03)));
    dv3 pb = d3add(near, qrot(qb, d3(-rnd(r, -45, 45), 0, 0)));
    c->a = box(h);
    c->b = box(h);
    c->xa = xf(pa, qa);
    c->xb = xf(pb, qb);
}

/* Equal rotations; B beside one face of A, offset sideways by at most half
 * the combined extent so that the face axis is the answer. */
static void gen_parallel(mk_rng *r, int pen, cand *c)
{
    dv3 ha = d3f32(rand_half(r, 0.2, 1)), hb = d3f32(rand_half(r, 0.2, 1));
    mk_quat q = rand_quat(r);
    dv3 pa = d3(rnd(r, -1, 1), rnd(r, -1, 1), rnd(r, -1, 1));
    double o[3], sa[3] = {ha.x, ha.y, ha.z}, sb[3] = {hb.x, hb.y, hb.z};
    int k = (int)(mk_rng_unit(r) * 3), i;
    double sign = mk_rng_unit(r) < 0.5 ? -1 : 1;
    for (i = 0; i < 3; ++i) o[i] = rnd(r, -0.5, 0.5) * (sa[i] + sb[i]);
    o[k] = sign * (sa[k] + sb[k] + (pen ? -rnd(r, 0.005, 0.15) : rnd(r, 0.005, 0.5)));
    c->a = box(ha);
    c->b = box(hb);
    c->xa = xf(pa, q);
    c->xb = xf(d3add(pa, qrot(q, d3(o[0], o[1], o[2]))), q);
}

static void gen_deep(mk_rng *r, int pen, cand *c)
{
    dv3 ha = rand_half(r, 0.3, 1), hb = rand_half(r, 0.3, 1);
    double ra = box_radius(ha), rb = box_radius(hb), size = ra > rb ? ra : rb;
    dv3 pa = d3(rnd(r, -1, 1), rnd(r, -1, 1), rnd(r, -1, 1));
    double rho = pen ? rnd(r, 0, 0.1) * size : ra + rb + rnd(r, 0.3, 0.7) * size;
    c->a = box(ha);
    c->b = box(hb);
    c->xa = xf(pa, rand_quat(r));
    c->xb = xf(d3add(pa, d3scale(rand_dir(r), rho)), rand_quat(r));
}

/* ---- hulls -------------------------------------------------------------------- */

#define HULL_POOL 6

typedef struct hull_pool {
    mk_shape shape[HULL_POOL];
    const mk_oracle_shape *o[HULL_POOL];
} hull_pool;

/* Surface area of an ellipsoid (Thomsen's formula, ~1 %): sets the spacing. */
static double ellipsoid_area(double a, double b, double c)
{
    double p = 1.6075, t = (pow(a * b, p) + pow(a * c, p) + pow(b * c, p)) / 3;
    return 4 * 3.141592653589793 * pow(t, 1 / p);
}

/* n float-rounded points on an ellipsoid with semi-axes (1, b, c) x scale,
 * b, c in [0.1, 1], no two closer than a third of the mean spacing, so every
 * point is a vertex by a wide margin; the oracle must agree (else redraw). */
static int make_hull(mk_case_set *set, mk_rng *r, int n, mk_shape *shape, const mk_oracle_shape **o)
{
    mk_lvec3 lp[128];
    mk_vec3 mp[128];
    int attempt;
    for (attempt = 0; attempt < 20; ++attempt) {
        double sc = rnd(r, 0.5, 1), ax[3] = {sc, sc * rnd(r, 0.1, 1), sc * rnd(r, 0.1, 1)};
        double gap = sqrt(ellipsoid_area(ax[0], ax[1], ax[2]) / n) / 3;
        int k = 0, tries = 0, i;
        mk_oracle_shape *os;
        mk_hull *h = NULL;
        while (k < n && tries++ < 10000 * n) {
            dv3 d = rand_dir(r), p = d3f32(d3(d.x * ax[0], d.y * ax[1], d.z * ax[2]));
            for (i = 0; i < k; ++i)
                if (d3len(d3((double)lp[i].x - p.x, (double)lp[i].y - p.y, (double)lp[i].z - p.z)) < gap) break;
            if (i < k) continue;
            lp[k].x = p.x, lp[k].y = p.y, lp[k].z = p.z;
            mp[k++] = to_mk(p);
        }
        if (k < n || !(os = malloc(sizeof *os))) continue;
        if (mk_oracle_shape_points(os, lp, n, 0) || os->core.nv != n) {
            mk_oracle_shape_free(os);
            free(os);
            continue;
        }
        if (keep_shape(set, os, o)) return -1;
        /* Quickhull must take the same cloud; a refusal is a library bug worth failing on. */
        if (mk_hull_create(mp, n, NULL, &h) != MK_OK || keep_hull(set, h)) return -1;
        return mk_shape_hull(h, 0, shape) == MK_OK ? 0 : -1;
    }
    return -1;
}

static int make_pool(mk_case_set *set, mk_rng *r, int n, hull_pool *pool)
{
    int i;
    for (i = 0; i < HULL_POOL; ++i)
        if (make_hull(set, r, n, &pool->shape[i], &pool->o[i])) return -1;
    return 0;
}

static int hull_points(mk_family f) { return f == MK_FAM_HULL_8 ? 8 : f == MK_FAM_HULL_128 ? 128 : 32; }

/* A pool hull for A; B another pool hull, or a box for hull_box. */
static void gen_hulls(mk_rng *r, const hull_pool *pool, int with_box, cand *c)
{
    int i = (int)(mk_rng_unit(r) * HULL_POOL), j = (int)(mk_rng_unit(r) * HULL_POOL);
    double ra = (double)pool->o[i]->size, rb;
    c->a = pool->shape[i];
    c->oa = pool->o[i];
    if (with_box) {
        dv3 h = rand_half(r, 0.1, 1);
        c->b = box(h);
        rb = box_radius(h);
    } else {
        c->b = pool->shape[j];
        c->ob = pool->o[j];
        rb = (double)pool->o[j]->size;
    }
    place_pair(r, c, 1.2 * (ra + rb), 1, 1, d3(0, 0, 0));
}

static void gen_candidate(mk_family f, mk_rng *r, int pen, const hull_pool *pool, cand *c)
{
    c->oa = c->ob = NULL;
    switch (f) {
    case MK_FAM_HULL_8:
    case MK_FAM_HULL_32:
    case MK_FAM_HULL_128: gen_hulls(r, pool, 0, c); break;
    case MK_FAM_HULL_BOX: gen_hulls(r, pool, 1, c); break;
    case MK_FAM_SPHERE_SPHERE: gen_spheres(r, pen, c); break;
    case MK_FAM_BOX_SPHERE: gen_box_sphere(r, c); break;
    case MK_FAM_CAPSULE_CAPSULE: gen_capsules(r, c); break;
    case MK_FAM_FLAT_BOXES: gen_flat(r, c); break;
    case MK_FAM_THIN_RODS: gen_rods(r, c); break;
    case MK_FAM_LARGE_COORDS: gen_boxes(r, c, 0.1, 1, 1, d3scale(rand_dir(r), 1e5)); break;
    case MK_FAM_TINY: gen_boxes(r, c, 0.1, 1, 1e-3, d3(0, 0, 0)); break;
    case MK_FAM_NEARLY_TOUCHING: gen_boxes(r, c, 0.3, 1, 1, d3(0, 0, 0)); break;
    case MK_FAM_PARALLEL_FACES: gen_parallel(r, pen, c); break;
    case MK_FAM_DEEP: gen_deep(r, pen, c); break;
    case MK_FAM_BOX_BOX:
    default: gen_boxes(r, c, 0.1, 1, 1, d3(0, 0, 0)); break;
    }
}

/* Nearly touching: move B along the exact normal so that the signed distance
 * becomes +-1e-6 x size (distance changes one for one along the normal of a
 * separated pair, and a shallow overlap keeps the same contact face), round
 * the position and judge again. */
static int nearly_touching(mk_case_set *set, mk_case *k, int pen)
{
    double target = (pen ? -1e-6 : 1e-6) * k->size, step = target - k->distance;
    dv3 pb = d3(k->xb.p.x, k->xb.p.y, k->xb.p.z);
    cand c;
    c.a = k->a;
    c.b = k->b;
    c.oa = c.ob = NULL;
    c.xa = k->xa;
    c.xb = xf(d3add(pb, d3(step * k->normal[0], step * k->normal[1], step * k->normal[2])), k->xb.q);
    return judge(set, &c, k);
}

static int wanted(mk_family f, const mk_case *k, int pen)
{
    double rel = k->distance / k->size;
    if (pen ? !(rel < 0) : !(rel > 0)) return 0;
    rel = fabs(rel);
    switch (f) {
    case MK_FAM_NEARLY_TOUCHING: return rel > 0.3e-6 && rel < 3e-6;
    case MK_FAM_DEEP: return rel > 0.3;
    case MK_FAM_THIN_RODS: return rel >= 2e-5; /* 1 mm against 50 m: the scale is the rods' 1 cm width */
    default: return rel >= 1e-3;
    }
}

static int is_hull_family(mk_family f)
{
    return f == MK_FAM_HULL_8 || f == MK_FAM_HULL_32 || f == MK_FAM_HULL_128 || f == MK_FAM_HULL_BOX;
}

int mk_cases_add_family(mk_case_set *set, mk_family f, int separated, int penetrating, uint64_t seed)
{
    mk_rng rng;
    hull_pool pool;
    int pen, made, tries;
    if ((unsigned)f >= MK_FAM_COUNT) return -1;
    rng.s = seed * 0x9E3779B97F4A7C15ull + (uint64_t)f;
    if (is_hull_family(f) && make_pool(set, &rng, hull_points(f), &pool)) return -1;
    for (pen = 0; pen < 2; ++pen)
        for (made = 0, tries = 0; made < (pen ? penetrating : separated); ++tries) {
            int mark = set->store ? set->store->count : 0, ok;
            cand c;
            mk_case k;
            if (tries > 1000 * ((pen ? penetrating : separated) + 10)) return -1;
            gen_candidate(f, &rng, pen, &pool, &c);
            ok = judge(set, &c, &k) == 0;
            if (ok && f == MK_FAM_NEARLY_TOUCHING) {
                ok = k.distance > 1e-2 * k.size; /* start from a clear gap */
                release_since(set, mark);          /* nearly_touching judges afresh */
                ok = ok && nearly_touching(set, &k, pen) == 0;
            }
            if (ok && wanted(f, &k, pen)) {
                k.family = mk_family_name(f);
                k.variant = pen ? "penetrating" : "separated";
                if (push_case(set, &k)) return -1;
                ++made;
            } else {
                release_since(set, mark);
            }
        }
    return 0;
}

/* ---- regression cases ------------------------------------------------------------ */

static int add_fixed(mk_case_set *set, const char *name, const cand *c)
{
    mk_case k;
    if (judge(set, c, &k)) return -1;
    k.family = "regression";
    k.variant = name;
    return push_case(set, &k);
}

static cand box_pair(double ha, mk_transform xa, double hb, mk_transform xb)
{
    cand c;
    c.oa = c.ob = NULL;
    mk_shape_box(mk_v3((mk_real)ha, (mk_real)ha, (mk_real)ha), 0, &c.a);
    mk_shape_box(mk_v3((mk_real)hb, (mk_real)hb, (mk_real)hb), 0, &c.b);
    c.xa = xa;
    c.xb = xb;
    return c;
}

static mk_transform at(double x, double y, double z, mk_quat q)
{
    return mk_transform_make(mk_v3((mk_real)x, (mk_real)y, (mk_real)z), q);
}

/* fcl #493: two 0.5 m boxes with the same rotation in face-to-face "kissing"
 * contact; #495: the same boxes explicitly 1e-9 apart. B is re-placed from A
 * along A's local axis of contact at 0.5 + delta, computed in long double. */
static int add_fcl(mk_case_set *set)
{
    static const double R[3][3] = {{0.96193976625564348026, 0.15401279915737359216, 0.22572537250328919556},
                                   {-0.19134171618254486313, 0.96936494951283913579, 0.15401279915737359216},
                                   {-0.19509032201612822033, -0.19134171618254486313, 0.96193976625564348026}};
    mk_quat q = mk_quat_from_mat3(mk_mat3_cols(mk_v3((mk_real)R[0][0], (mk_real)R[1][0], (mk_real)R[2][0]),
                                               mk_v3((mk_real)R[0][1], (mk_real)R[1][1], (mk_real)R[2][1]),
                                               mk_v3((mk_real)R[0][2], (mk_real)R[1][2], (mk_real)R[2][2])));
    mk_transform xa = at(2.0770063995786869349, 0.48468247475641951239, 1.1543291419087275962, q);
    mk_transform xb = at(2, 0, 1.25, q);
    mk_oracle_pose pa = mk_oracle_pose_of(xa);
    long double d[3], dl[3], w[3];
    int i, k = 0, s;
    cand c = box_pair(0.25, xa, 0.25, xb);
    if (add_fixed(set, "fcl493_kissing", &c)) return -1;
    d[0] = (long double)xb.p.x - xa.p.x, d[1] = (long double)xb.p.y - xa.p.y, d[2] = (long double)xb.p.z - xa.p.z;
    for (i = 0; i < 3; ++i) dl[i] = pa.r[0][i] * d[0] + pa.r[1][i] * d[1] + pa.r[2][i] * d[2];
    for (i = 1; i < 3; ++i)
        if (fabsl(dl[i]) > fabsl(dl[k])) k = i;
    for (s = 1; s >= -1; s -= 2) {
        dl[k] = (dl[k] < 0 ? -1 : 1) * (0.5L + s * 1e-9L);
        for (i = 0; i < 3; ++i) w[i] = pa.r[i][0] * dl[0] + pa.r[i][1] * dl[1] + pa.r[i][2] * dl[2];
        c.xb = at((double)(xa.p.x + w[0]), (double)(xa.p.y + w[1]), (double)(xa.p.z + w[2]), q);
        if (add_fixed(set, s > 0 ? "fcl495_gap_1e-9" : "fcl495_overlap_1e-9", &c)) return -1;
    }
    return 0;
}

/* Jolt #2103: a capsule (radius 7.19732189, half height 2.03114343, float
 * literals of the report) and a cylinder (radius 0.4975, half height 0.3) side
 * by side with parallel axes, just touching; Jolt reported ~7 m of penetration.
 * Jolt's y axis is Minko's z: (x, y, z) -> (x, -z, y). The oracle has no
 * cylinder-capsule, but with parallel axes and overlapping axial ranges the
 * answer is the radial one: d = |axis offset| - r_cylinder - r_capsule. */
static int add_jolt(mk_case_set *set)
{
    mk_case k;
    long double ox, oy, rho;
    memset(&k, 0, sizeof k);
    mk_shape_capsule((mk_real)7.19732189f, (mk_real)2.03114343f, &k.a);
    mk_shape_cylinder((mk_real)0.4975f, (mk_real)0.3f, 0, &k.b);
    k.xa = mk_transform_identity();
    k.xb = at((double)-0.951660156f, (double)7.63574218f, (double)-2.09155273f, mk_quat_identity());
    ox = k.xb.p.x, oy = k.xb.p.y;
    rho = sqrtl(ox * ox + oy * oy);
    k.distance = (double)(rho - k.b.u.cylinder.radius - k.a.radius);
    k.normal[0] = (double)(ox / rho);
    k.normal[1] = (double)(oy / rho);
    k.normal[2] = 0;
    k.normal_defined = 1;
    k.size = (double)k.a.radius + (double)k.a.u.capsule.half_height;
    k.family = "regression";
    k.variant = "jolt2103_capsule_cylinder";
    return push_case(set, &k);
}

int mk_cases_add_regressions(mk_case_set *set)
{
    mk_quat id = mk_quat_identity();
    mk_quat z03 = mk_quat_from_axis_angle(mk_v3(0, 0, 1), (mk_real)0.3);
    cand c;
    /* libccd #25: 2 m cubes at z = 0 and 1.9: depth 0.1 along z (libccd's EPA: depth 0, NaN normal). */
    c = box_pair(1, at(0, 0, 0, id), 1, at(0, 0, 1.9, id));
    if (add_fixed(set, "libccd25_stacked_cubes", &c)) return -1;
    /* libccd #17: a 5 m box with a 0.2 m box resting 1 cm deep on its top face. */
    c = box_pair(2.5, at(0, 0, 0, id), 0.1, at(1.3, -0.7, 2.59, z03));
    if (add_fixed(set, "libccd17_5m_vs_0.2m", &c)) return -1;
    /* Touching exactly: face on face (normal defined) and corner on corner (not). */
    c = box_pair(0.5, at(0, 0, 0, id), 0.5, at(0.3, 0.2, 1, id));
    if (add_fixed(set, "touching_faces", &c)) return -1;
    c = box_pair(0.5, at(0, 0, 0, id), 0.5, at(1, 1, 1, id));
    if (add_fixed(set, "touching_corners", &c)) return -1;
    if (add_fcl(set)) return -1;
    return add_jolt(set);
}

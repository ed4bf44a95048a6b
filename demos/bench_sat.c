/* bench_sat.c: time and accuracy of the separating-axis test (src/sat.h)
 * against Minko's own GJK + EPA (mk_distance), on the same cases in the same
 * run, so a dispatcher can pick per pair type.
 *
 *   bench_sat [--quick] [--json FILE] [--n CASES] [--reps LOOPS]
 *
 * Families: box_box, box_hull32, hull8_hull8, hull32_hull32, hull128_hull128
 * (hulls of points on ellipsoids up to 10:1), each "separated" and
 * "penetrating" by the oracle's sign. Backends: minko.sat_box_box (the 15-axis
 * path, boxes only), minko.sat (the generic path; boxes through their hull
 * view), minko.gjk_epa (mk_distance, which routes these pairs to GJK/EPA).
 * Every backend starts from the world poses, so the relative pose is part of
 * its time. Accuracy against tests/support/oracle (long double): relative
 * depth error and normal error on penetrating cases; on separated ones SAT
 * only bounds the distance, so there it is judged on the sign alone
 * (wrong_bool). Timing: best of --reps loops over all cases, warm caches;
 * JSON Lines per ../shared/BENCH_FORMAT.md (suite "sat") and a table. */
#define _POSIX_C_SOURCE 199309L /* clock_gettime */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "minko/distance.h"
#include "minko/shape.h"
#include "polytope.h"
#include "sat.h"
#include "support/mk_rng.h"
#include "support/oracle.h"

enum { FAM_BOX_BOX, FAM_BOX_HULL32, FAM_H8, FAM_H32, FAM_H128, FAM_COUNT };
static const char *const fam_name[FAM_COUNT] = {"box_box", "box_hull32", "hull8_hull8", "hull32_hull32", "hull128_hull128"};
static const int fam_points[FAM_COUNT] = {0, 32, 8, 32, 128};

enum { BK_SAT_BOX, BK_SAT, BK_GJK_EPA, BK_COUNT };
static const char *const bk_name[BK_COUNT] = {"minko.sat_box_box", "minko.sat", "minko.gjk_epa"};

typedef struct bcase {
    mk_shape a, b;
    mk_transform xa, xb;
    mk_box_hull va, vb; /* box views (boxes only) */
    long double depth;  /* oracle: signed distance */
    mk_lvec3 normal;
    int normal_defined;
} bcase;

typedef struct stats { double ns; double err[4096]; double nerr[4096]; int n, wrong, fail, queries; } stats;

static double now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

static mk_hull *ellipsoid_hull(mk_rng *r, int n)
{
    mk_vec3 p[128], ax = mk_v3((mk_real)mk_rng_range(r, 0.1, 1), (mk_real)mk_rng_range(r, 0.1, 1), (mk_real)mk_rng_range(r, 0.1, 1));
    mk_hull *h = NULL;
    int i;
    for (i = 0; i < n; ++i) p[i] = mk_v3_mul(mk_rng_dir(r), ax);
    return mk_hull_create(p, n, NULL, &h) == MK_OK ? h : NULL;
}

static void make_shape(mk_rng *r, int points, mk_shape *s, mk_box_hull *view, mk_hull **owned)
{
    if (points == 0) {
        mk_vec3 h = mk_v3((mk_real)mk_rng_range(r, 0.1, 1), (mk_real)mk_rng_range(r, 0.1, 1), (mk_real)mk_rng_range(r, 0.1, 1));
        mk_shape_box(h, 0, s);
        mk_box_hull_init(view, h);
        *owned = NULL;
    } else {
        *owned = ellipsoid_hull(r, points);
        mk_shape_hull(*owned, 0, s);
    }
}

static const mk_hull *core(const bcase *c, int which)
{
    const mk_shape *s = which ? &c->b : &c->a;
    return s->type == MK_SHAPE_BOX ? (which ? &c->vb.hull : &c->va.hull) : s->u.hull;
}

/* Runs one backend on one case: signed core distance (depth < 0) and normal
 * in world frame; returns 0 on failure. */
static int run(int bk, const bcase *c, double *dist, mk_vec3 *n)
{
    if (bk == BK_GJK_EPA) {
        mk_distance_result res;
        if (mk_distance(&c->a, c->xa, &c->b, c->xb, NULL, &res) != MK_OK) return 0;
        *dist = (double)res.distance;
        *n = res.normal;
        return mk_v3_is_valid(res.normal) && mk_real_is_valid(res.distance);
    } else {
        mk_transform rel = mk_transform_inv_mul(c->xa, c->xb);
        mk_mat3 R = mk_mat3_from_quat(mk_quat_normalize(rel.q));
        mk_sat_options o = mk_sat_defaults();
        mk_sat_result res;
        if (bk == BK_SAT_BOX) mk_sat_box_box(c->a.u.half_extents, c->b.u.half_extents, &R, rel.p, &o, &res);
        else mk_sat(core(c, 0), core(c, 1), &R, rel.p, &o, &res);
        *dist = (double)res.best;
        *n = mk_quat_rotate(c->xa.q, res.normal);
        return mk_v3_is_valid(res.normal) && mk_real_is_valid(res.best);
    }
}

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double pct(double *v, int n, double p)
{
    if (n == 0) return 0;
    qsort(v, (size_t)n, sizeof *v, cmp_d);
    return v[(int)(p * (n - 1) + 0.5)];
}

static void measure(int bk, const bcase *cs, int n, int reps, stats *st)
{
    int i, k;
    volatile double sink = 0;
    memset(st, 0, sizeof *st);
    st->ns = 1e300;
    for (i = 0; i < n; ++i) { /* accuracy */
        double d;
        mk_vec3 nn;
        if (!run(bk, &cs[i], &d, &nn)) {
            st->fail++;
            continue;
        }
        if ((d > 0) != (cs[i].depth > 0)) st->wrong++;
        if (cs[i].depth < 0) {
            st->err[st->n] = (double)(fabsl((long double)d - cs[i].depth) / -cs[i].depth);
            st->nerr[st->n] = cs[i].normal_defined ? (double)mk_oracle_angle_deg(cs[i].normal, nn.x, nn.y, nn.z) : 0;
            st->n++;
        }
    }
    for (k = 0; k < reps; ++k) { /* time: best loop */
        double t0 = now_ns(), t;
        for (i = 0; i < n; ++i) {
            double d;
            mk_vec3 nn;
            run(bk, &cs[i], &d, &nn);
            sink += d;
        }
        t = (now_ns() - t0) / n;
        if (t < st->ns) st->ns = t;
    }
    st->queries = n;
    (void)sink;
}

int main(int argc, char **argv)
{
    int quick = 0, ncases = 200, reps = 7, i, fam, var, bk;
    const char *json = NULL;
    FILE *jf = NULL;
    for (i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--quick")) quick = 1;
        else if (!strcmp(argv[i], "--json") && i + 1 < argc) json = argv[++i];
        else if (!strcmp(argv[i], "--n") && i + 1 < argc) ncases = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--reps") && i + 1 < argc) reps = atoi(argv[++i]);
        else {
            fprintf(stderr, "usage: %s [--quick] [--json FILE] [--n CASES] [--reps LOOPS]\n", argv[0]);
            return 2;
        }
    }
    if (quick) ncases = ncases < 20 ? ncases : 20, reps = reps < 3 ? reps : 3;
    if (ncases > 4096) ncases = 4096;
    if (json && !(jf = fopen(json, "w"))) {
        fprintf(stderr, "bench_sat: cannot write %s\n", json);
        return 1;
    }
    printf("%-16s %-11s %-18s %10s %10s %10s %10s %9s %6s %5s\n", "family", "variant", "backend", "ns/query", "err p50", "err p99",
           "err max", "nrm p99", "wrong", "fail");
    for (fam = 0; fam < FAM_COUNT; ++fam) {
        mk_rng r;
        bcase *cs[2];
        mk_hull **owned;
        int have[2] = {0, 0}, tries = 0, no = 0;
        r.s = 1000 + (uint64_t)fam;
        cs[0] = calloc((size_t)ncases, sizeof(bcase));
        cs[1] = calloc((size_t)ncases, sizeof(bcase));
        owned = calloc((size_t)(4 * ncases + 4), sizeof *owned);
        /* Random poses at a distance that gives both variants; keep each case
         * in the variant of the oracle's sign until both are full. */
        while ((have[0] < ncases || have[1] < ncases) && tries++ < 50 * ncases) {
            bcase c;
            mk_oracle_result o;
            double reach;
            memset(&c, 0, sizeof c);
            make_shape(&r, fam == FAM_BOX_BOX || fam == FAM_BOX_HULL32 ? 0 : fam_points[fam], &c.a, &c.va, &owned[no]);
            if (c.a.type == MK_SHAPE_HULL) ++no;
            make_shape(&r, fam_points[fam], &c.b, &c.vb, &owned[no]);
            if (c.b.type == MK_SHAPE_HULL) ++no;
            reach = (double)(core(&c, 0)->outer_radius + core(&c, 1)->outer_radius);
            c.xa = mk_transform_make(mk_rng_v3(&r, -10, 10), mk_rng_quat(&r));
            c.xb = mk_transform_make(mk_v3_mad(c.xa.p, (mk_real)mk_rng_range(&r, 0.1, 1.1) * (mk_real)reach, mk_rng_dir(&r)), mk_rng_quat(&r));
            var = -1;
            if (mk_oracle_distance(&c.a, c.xa, &c.b, c.xb, &o) == 0 && fabsl(o.distance) >= 1e-3L * reach) var = o.distance < 0;
            c.depth = o.distance;
            c.normal = o.normal;
            c.normal_defined = o.normal_defined;
            if (var < 0 || have[var] >= ncases) { /* not kept: give its hulls back */
                while (no > 0 && ((c.a.type == MK_SHAPE_HULL && owned[no - 1] == c.a.u.hull) || (c.b.type == MK_SHAPE_HULL && owned[no - 1] == c.b.u.hull)))
                    mk_hull_destroy(owned[--no]);
            } else {
                cs[var][have[var]] = c;
                /* the box views point into the case: re-point them at the copy */
                if (c.a.type == MK_SHAPE_BOX) mk_box_hull_init(&cs[var][have[var]].va, c.a.u.half_extents);
                if (c.b.type == MK_SHAPE_BOX) mk_box_hull_init(&cs[var][have[var]].vb, c.b.u.half_extents);
                have[var]++;
            }
        }
        for (var = 0; var < 2; ++var)
            for (bk = 0; bk < BK_COUNT; ++bk) {
                static stats st;
                if (bk == BK_SAT_BOX && fam != FAM_BOX_BOX) continue;
                measure(bk, cs[var], have[var], reps, &st);
                printf("%-16s %-11s %-18s %10.0f %10.2g %10.2g %10.2g %9.2g %6d %5d\n", fam_name[fam], var ? "penetrating" : "separated",
                       bk_name[bk], st.ns, pct(st.err, st.n, 0.5), pct(st.err, st.n, 0.99), pct(st.err, st.n, 1.0), pct(st.nerr, st.n, 0.99),
                       st.wrong, st.fail);
                if (jf) {
                    fprintf(jf, "{\"suite\":\"sat\",\"case\":\"%s\",\"variant\":\"%s\",\"backend\":\"%s\",\"n\":%d,\"ns_per_query\":%.1f,"
                                "\"wrong_bool\":%d,\"failures\":%d",
                            fam_name[fam], var ? "penetrating" : "separated", bk_name[bk], st.queries, st.ns, st.wrong, st.fail);
                    if (st.n)
                        fprintf(jf, ",\"rel_err_p50\":%.3g,\"rel_err_p99\":%.3g,\"rel_err_max\":%.3g,\"normal_err_deg_p99\":%.3g,\"normal_err_deg_max\":%.3g",
                                pct(st.err, st.n, 0.5), pct(st.err, st.n, 0.99), pct(st.err, st.n, 1.0), pct(st.nerr, st.n, 0.99),
                                pct(st.nerr, st.n, 1.0));
                    fprintf(jf, "}\n");
                }
            }
        for (i = 0; i < no; ++i) mk_hull_destroy(owned[i]);
        free(owned);
        free(cs[0]);
        free(cs[1]);
    }
    if (jf) fclose(jf);
    return 0;
}

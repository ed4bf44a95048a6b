/* solver_demo: a small sequential-impulse (projected Gauss-Seidel) solver,
 * NOT part of the library, that exists to measure what warm starting from
 * the contact cache is worth (issue 4, seed 000 and seed 002).
 *
 * Rigid boxes on a ground plane; contacts from mk_collide() (2 cm
 * speculative margin); per contact point a normal row and two friction rows
 * clamped to the friction disc. Penetration beyond a 5 mm slop is removed at
 * beta = 0.2 per step by split impulse (pseudo velocities that move the
 * bodies but never enter the dynamics), or with --baumgarte through the
 * velocity rows. Each scene runs three ways:
 *   cold     every step starts from lambda = 0;
 *   feature  lambda^0 from mk_contact_cache, keyed by (body, body, feature pair);
 *   nearest  Bullet's policy: the previous frame's point of the same pair
 *            nearest in body A's local frame, if within 0.02 (greedy, each
 *            old point used once, as btPersistentManifold's replacement does);
 *   world    seed 000's first option: the previous point of the same pair
 *            nearest in world space, whatever the distance (greedy as above).
 * and with two solver budgets:
 *   pgs10    exactly 10 iterations per step: does the scene stand and settle?
 *   converge iterate until no row changes any velocity by more than
 *            1e-5 m/s (cap 500): how many iterations does each step need?
 * Scenes marked "at rest" first run one second with the converged solver so
 * that every mode starts from the same standing stack (the warm-start modes
 * with their caches filled, as in a running game); tower_drop is the same
 * tower released from exact contact, whose landing sets it rocking.
 * Per scene, budget and warm start: mean / p95 / max iterations per step,
 * the velocity residual left after the last iteration, the fraction of
 * contact points that found a lambda^0 and, of those, the fraction given
 * another contact's (the old point's feature pair differs: seed 000's
 * a -> c, b -> d turned b -> c), the largest penetration over the
 * last second, drift (largest horizontal displacement of a box from where it
 * started), kinetic energy per box at the end, and how far the top box came
 * down. Output: a table on stdout and JSON Lines (suite "contacts",
 * ../shared/BENCH_FORMAT.md).
 *
 *   solver_demo [--quick] [--json FILE] [--scene NAME] [--baumgarte]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "minko/contact_cache.h"
#include "minko/manifold.h"

#define MAX_BODIES 64
#define MAX_ROWS 2048
#define DT (MK_REAL(1.0) / 60)
#define GRAVITY MK_REAL(-9.81)
#define BETA MK_REAL(0.2)
#define SLOP MK_REAL(0.005)
#define MARGIN MK_REAL(0.02)        /* speculative distance: Bullet's contact breaking threshold */
#define NEAREST_THRESHOLD MK_REAL(0.02)
#define RESIDUAL_TOL MK_REAL(1e-5)  /* m/s */
#define MAX_CONVERGE_ITERS 500

typedef enum warm_mode { WARM_COLD, WARM_FEATURE, WARM_NEAREST, WARM_WORLD, WARM_COUNT } warm_mode;
static const char *const warm_names[WARM_COUNT] = {"cold", "feature", "nearest", "world"};

typedef struct body {
    mk_shape shape;
    mk_transform x;
    mk_vec3 v, w;
    mk_vec3 pv, pw;               /* split impulse: pseudo velocities, position correction only */
    mk_real mass, inv_mass;
    mk_vec3 inertia, inv_inertia; /* principal, local */
    mk_vec3 start;
} body;

/* One contact point: a normal row and two friction rows. */
typedef struct row {
    int a, b;
    uint32_t features;
    mk_vec3 n, t1, t2, ra, rb, local_a, world;
    mk_real mn, mt1, mt2;  /* effective masses 1 / (J M^-1 J^T) */
    mk_real kn;            /* J M^-1 J^T of the normal row: turns an impulse into a velocity change */
    mk_real bias;          /* target normal velocity */
    mk_real push;          /* split impulse: target pseudo velocity that removes penetration */
    mk_real ln, lt1, lt2, lp;
    mk_real depth;
    int matched;
    int wrong;             /* matched to an old point of other features */
} row;

/* Bullet-style memory of a pair's points, for the distance policies. */
typedef struct old_point { mk_vec3 key; uint32_t features; mk_real ln, lt1, lt2; } old_point;
typedef struct pair_state {
    mk_manifold_cache cache; /* SAT hysteresis, carried for every policy */
    int step;                /* last step the pair had points */
    int count;
    old_point pts[MK_MANIFOLD_MAX_POINTS];
} pair_state;

typedef struct world {
    int nb;
    body b[MAX_BODIES];
    pair_state pairs[MAX_BODIES * MAX_BODIES];
    row rows[MAX_ROWS];
    int nr;
    mk_real mu;
    warm_mode warm;
    mk_contact_cache *cache;
    int split;   /* 1: split impulse, 0: Baumgarte */
    int step;
} world;

/* ---- bodies -------------------------------------------------------------- */

static void add_ground(world *w)
{
    body *g = &w->b[w->nb++];
    memset(g, 0, sizeof *g);
    mk_shape_plane(mk_v3(0, 0, 1), 0, &g->shape);
    g->x = mk_transform_identity();
}

static body *add_box(world *w, mk_vec3 half, mk_real density, mk_vec3 p)
{
    body *bd = &w->b[w->nb++];
    mk_real m = density * 8 * half.x * half.y * half.z;
    memset(bd, 0, sizeof *bd);
    mk_shape_box(half, 0, &bd->shape);
    bd->x = mk_transform_make(p, mk_quat_identity());
    bd->mass = m;
    bd->inv_mass = 1 / m;
    bd->inertia = mk_v3(m / 3 * (half.y * half.y + half.z * half.z), m / 3 * (half.x * half.x + half.z * half.z),
                        m / 3 * (half.x * half.x + half.y * half.y));
    bd->inv_inertia = mk_v3(1 / bd->inertia.x, 1 / bd->inertia.y, 1 / bd->inertia.z);
    bd->start = p;
    return bd;
}

/* World inverse inertia times v: R I^-1 R^T v. */
static mk_vec3 inv_inertia_mul(const body *bd, mk_vec3 v)
{
    mk_vec3 l = mk_quat_inv_rotate(bd->x.q, v);
    return mk_quat_rotate(bd->x.q, mk_v3_mul(bd->inv_inertia, l));
}

static mk_real row_k(const body *a, const body *b, mk_vec3 ra, mk_vec3 rb, mk_vec3 d)
{
    mk_vec3 ca = mk_v3_cross(ra, d), cb = mk_v3_cross(rb, d);
    return a->inv_mass + b->inv_mass + mk_v3_dot(ca, inv_inertia_mul(a, ca)) + mk_v3_dot(cb, inv_inertia_mul(b, cb));
}

static void apply_pseudo(world *w, const row *r, mk_vec3 p)
{
    body *a = &w->b[r->a], *b = &w->b[r->b];
    a->pv = mk_v3_mad(a->pv, -a->inv_mass, p);
    a->pw = mk_v3_sub(a->pw, inv_inertia_mul(a, mk_v3_cross(r->ra, p)));
    b->pv = mk_v3_mad(b->pv, b->inv_mass, p);
    b->pw = mk_v3_add(b->pw, inv_inertia_mul(b, mk_v3_cross(r->rb, p)));
}

static void apply(world *w, const row *r, mk_vec3 p)
{
    body *a = &w->b[r->a], *b = &w->b[r->b];
    a->v = mk_v3_mad(a->v, -a->inv_mass, p);
    a->w = mk_v3_sub(a->w, inv_inertia_mul(a, mk_v3_cross(r->ra, p)));
    b->v = mk_v3_mad(b->v, b->inv_mass, p);
    b->w = mk_v3_add(b->w, inv_inertia_mul(b, mk_v3_cross(r->rb, p)));
}

static mk_vec3 rel_velocity(const world *w, const row *r)
{
    const body *a = &w->b[r->a], *b = &w->b[r->b];
    return mk_v3_sub(mk_v3_add(b->v, mk_v3_cross(b->w, r->rb)), mk_v3_add(a->v, mk_v3_cross(a->w, r->ra)));
}

/* ---- contacts and warm starting ------------------------------------------------ */

static void add_row(world *w, int ia, int ib, const mk_manifold *m, const mk_contact_point *c)
{
    row *r;
    body *a = &w->b[ia], *b = &w->b[ib];
    mk_vec3 mid = mk_v3_scale(mk_v3_add(c->point_a, c->point_b), MK_REAL(0.5));
    if (w->nr == MAX_ROWS) {
        fprintf(stderr, "solver_demo: more than %d contact points\n", MAX_ROWS);
        exit(2);
    }
    r = &w->rows[w->nr++];
    memset(r, 0, sizeof *r);
    r->a = ia;
    r->b = ib;
    r->features = c->features;
    r->n = m->normal;
    /* A tangent basis that is a continuous function of the normal, so
     * cached tangent impulses keep their meaning from step to step. */
    r->t1 = mk_v3_perp(r->n);
    r->t2 = mk_v3_cross(r->n, r->t1);
    r->ra = mk_v3_sub(mid, a->x.p);
    r->rb = mk_v3_sub(mid, b->x.p);
    r->local_a = c->local_a;
    r->world = mid;
    r->kn = row_k(a, b, r->ra, r->rb, r->n);
    r->mn = 1 / r->kn;
    r->mt1 = 1 / row_k(a, b, r->ra, r->rb, r->t1);
    r->mt2 = 1 / row_k(a, b, r->ra, r->rb, r->t2);
    r->depth = c->depth;
    /* Speculative points may close their gap in one step; penetration beyond
     * the slop is pushed out at BETA per step, through the velocities
     * (Baumgarte) or through pseudo velocities that never feed back into the
     * dynamics (split impulse). */
    r->push = c->depth > SLOP ? BETA * (c->depth - SLOP) / DT : 0;
    r->bias = c->depth < 0 ? c->depth / DT : w->split ? 0 : r->push;
}

/* MK_OK, or the status of the first pair mk_collide refused (a pair left out
 * of this build: the scene is then skipped). */
static mk_status collide_all(world *w)
{
    int i, j, k;
    w->nr = 0;
    for (i = 0; i < w->nb; ++i) {
        mk_aabb bi;
        mk_shape_aabb(&w->b[i].shape, w->b[i].x, &bi);
        for (j = i + 1; j < w->nb; ++j) {
            mk_aabb bj;
            mk_manifold m;
            mk_status st;
            if (w->b[i].inv_mass == 0 && w->b[j].inv_mass == 0) continue;
            mk_shape_aabb(&w->b[j].shape, w->b[j].x, &bj);
            if (!mk_aabb_overlap(mk_aabb_expand(bi, MARGIN), bj)) continue;
            st = mk_collide(&w->b[i].shape, w->b[i].x, &w->b[j].shape, w->b[j].x, MARGIN, &w->pairs[i * MAX_BODIES + j].cache, &m);
            if (st != MK_OK) return st;
            for (k = 0; k < m.count; ++k) add_row(w, i, j, &m, &m.points[k]);
        }
    }
    return MK_OK;
}

static void warm_start(world *w)
{
    int i, k;
    /* A new frame: lookups now see what the last step stored. */
    if (w->warm == WARM_FEATURE) mk_contact_cache_begin_frame(w->cache);
    for (i = 0; i < w->nr; ++i) {
        row *r = &w->rows[i];
        if (w->warm == WARM_FEATURE) {
            mk_contact_impulse imp;
            mk_contact_cache_lookup(w->cache, mk_contact_id_make((uint32_t)r->a, (uint32_t)r->b, r->features), &imp, &r->matched);
            r->ln = imp.normal;
            r->lt1 = imp.tangent1;
            r->lt2 = imp.tangent2;
        } else if (w->warm != WARM_COLD) {
            pair_state *ps = &w->pairs[r->a * MAX_BODIES + r->b];
            mk_real best = w->warm == WARM_NEAREST ? NEAREST_THRESHOLD * NEAREST_THRESHOLD : MK_REAL_MAX;
            mk_vec3 key = w->warm == WARM_NEAREST ? r->local_a : r->world;
            int pick = -1;
            if (ps->step != w->step - 1) continue;
            for (k = 0; k < ps->count; ++k) {
                mk_real d2 = mk_v3_len2(mk_v3_sub(ps->pts[k].key, key));
                if (d2 < best) { best = d2; pick = k; }
            }
            if (pick < 0) continue;
            r->ln = ps->pts[pick].ln;
            r->lt1 = ps->pts[pick].lt1;
            r->lt2 = ps->pts[pick].lt2;
            r->wrong = ps->pts[pick].features != r->features;
            ps->pts[pick].key = mk_v3(MK_REAL_MAX, MK_REAL_MAX, MK_REAL_MAX); /* used: no second match */
            r->matched = 1;
        }
        if (r->matched)
            apply(w, r, mk_v3_add(mk_v3_scale(r->n, r->ln), mk_v3_add(mk_v3_scale(r->t1, r->lt1), mk_v3_scale(r->t2, r->lt2))));
    }
}

static void remember(world *w)
{
    int i;
    for (i = 0; i < w->nr; ++i) {
        const row *r = &w->rows[i];
        if (w->warm == WARM_FEATURE) {
            mk_contact_impulse imp;
            imp.normal = r->ln;
            imp.tangent1 = r->lt1;
            imp.tangent2 = r->lt2;
            mk_contact_cache_store(w->cache, mk_contact_id_make((uint32_t)r->a, (uint32_t)r->b, r->features), imp);
        } else if (w->warm != WARM_COLD) {
            pair_state *ps = &w->pairs[r->a * MAX_BODIES + r->b];
            old_point *o;
            if (ps->step != w->step) {
                ps->step = w->step;
                ps->count = 0;
            }
            o = &ps->pts[ps->count++];
            o->key = w->warm == WARM_NEAREST ? r->local_a : r->world;
            o->features = r->features;
            o->ln = r->ln;
            o->lt1 = r->lt1;
            o->lt2 = r->lt2;
        }
    }
}

/* ---- the solver --------------------------------------------------------------- */

/* One Gauss-Seidel sweep; returns the largest velocity change any row made. */
static mk_real sweep(world *w)
{
    mk_real residual = 0;
    int i;
    for (i = 0; i < w->nr; ++i) {
        row *r = &w->rows[i];
        mk_vec3 vr = rel_velocity(w, r);
        mk_real old1 = r->lt1, old2 = r->lt2, lim, len, dn, lnew;
        /* Friction first, then the normal row, so non-penetration has the last word in each sweep. */
        r->lt1 -= r->mt1 * mk_v3_dot(vr, r->t1);
        r->lt2 -= r->mt2 * mk_v3_dot(vr, r->t2);
        lim = w->mu * r->ln;
        len = mk_sqrt_(r->lt1 * r->lt1 + r->lt2 * r->lt2);
        if (len > lim) {
            r->lt1 *= lim / len;
            r->lt2 *= lim / len;
        }
        apply(w, r, mk_v3_add(mk_v3_scale(r->t1, r->lt1 - old1), mk_v3_scale(r->t2, r->lt2 - old2)));
        residual = mk_max(residual, mk_max(mk_fabs_(r->lt1 - old1) / r->mt1, mk_fabs_(r->lt2 - old2) / r->mt2));
        vr = rel_velocity(w, r);
        lnew = mk_max(r->ln + r->mn * (r->bias - mk_v3_dot(vr, r->n)), 0);
        dn = lnew - r->ln;
        r->ln = lnew;
        apply(w, r, mk_v3_scale(r->n, dn));
        residual = mk_max(residual, mk_fabs_(dn) * r->kn);
    }
    return residual;
}

/* Split impulse: the position pass, on pseudo velocities (normal rows only). */
static void push_sweep(world *w)
{
    int i;
    for (i = 0; i < w->nr; ++i) {
        row *r = &w->rows[i];
        const body *a = &w->b[r->a], *b = &w->b[r->b];
        mk_vec3 vr = mk_v3_sub(mk_v3_add(b->pv, mk_v3_cross(b->pw, r->rb)), mk_v3_add(a->pv, mk_v3_cross(a->pw, r->ra)));
        mk_real lnew = mk_max(r->lp + r->mn * (r->push - mk_v3_dot(vr, r->n)), 0);
        apply_pseudo(w, r, mk_v3_scale(r->n, lnew - r->lp));
        r->lp = lnew;
    }
}

static void integrate(world *w)
{
    int i;
    for (i = 0; i < w->nb; ++i) {
        body *bd = &w->b[i];
        mk_quat dq;
        mk_vec3 v = mk_v3_add(bd->v, bd->pv), om = mk_v3_add(bd->w, bd->pw);
        bd->pv = bd->pw = mk_v3_zero();
        if (bd->inv_mass == 0) continue;
        bd->x.p = mk_v3_mad(bd->x.p, DT, v);
        dq = mk_quat_mul(mk_quat_make(om.x, om.y, om.z, 0), bd->x.q);
        bd->x.q = mk_quat_normalize(mk_quat_make(bd->x.q.x + MK_REAL(0.5) * DT * dq.x, bd->x.q.y + MK_REAL(0.5) * DT * dq.y,
                                                 bd->x.q.z + MK_REAL(0.5) * DT * dq.z, bd->x.q.w + MK_REAL(0.5) * DT * dq.w));
    }
}

typedef struct step_stats { int iterations; mk_real residual, penetration; int points, matched, wrong; mk_status status; } step_stats;

static step_stats step(world *w, int fixed_iterations)
{
    step_stats s;
    int i;
    memset(&s, 0, sizeof s);
    w->step++;
    for (i = 0; i < w->nb; ++i)
        if (w->b[i].inv_mass > 0) w->b[i].v.z += GRAVITY * DT;
    if ((s.status = collide_all(w)) != MK_OK) return s;
    warm_start(w);
    for (i = 0; i < w->nr; ++i) {
        s.penetration = mk_max(s.penetration, w->rows[i].depth);
        s.matched += w->rows[i].matched;
        s.wrong += w->rows[i].wrong;
    }
    s.points = w->nr;
    if (fixed_iterations > 0) {
        for (i = 0; i < fixed_iterations; ++i) s.residual = sweep(w);
        s.iterations = fixed_iterations;
    } else {
        do {
            s.residual = sweep(w);
            s.iterations++;
        } while (s.residual > RESIDUAL_TOL && s.iterations < MAX_CONVERGE_ITERS);
    }
    if (w->split)
        for (i = 0; i < (fixed_iterations > 0 ? fixed_iterations : 10); ++i) push_sweep(w);
    remember(w);
    integrate(w);
    return s;
}

/* ---- scenes -------------------------------------------------------------------- */

typedef struct scene {
    const char *name;
    const char *what;
    mk_real seconds;
    mk_real mu;
    int settled;   /* start from the stack at rest (see run) rather than from exact contact */
    int quick;     /* part of --quick */
    void (*build)(world *w);
} scene;

/* Catto 2005's boxes: 0.7 x 0.7 x 0.3 m, about 110 kg. */
#define TOWER_HALF mk_v3(MK_REAL(0.35), MK_REAL(0.35), MK_REAL(0.15))
#define TOWER_DENSITY MK_REAL(750.0)

static void build_tower(world *w)
{
    int i;
    add_ground(w);
    for (i = 0; i < 10; ++i) add_box(w, TOWER_HALF, TOWER_DENSITY, mk_v3(0, 0, MK_REAL(0.15) + MK_REAL(0.3) * (mk_real)i));
}

static void build_heavy_on_light(world *w)
{
    mk_vec3 h = mk_v3(MK_REAL(0.5), MK_REAL(0.5), MK_REAL(0.5));
    add_ground(w);
    add_box(w, h, 100, mk_v3(0, 0, MK_REAL(0.5)));
    add_box(w, h, 10000, mk_v3(0, 0, MK_REAL(1.5)));
}

static void build_slide_spin(world *w)
{
    body *bd;
    add_ground(w);
    bd = add_box(w, mk_v3(MK_REAL(0.5), MK_REAL(0.5), MK_REAL(0.25)), 500, mk_v3(0, 0, MK_REAL(0.25)));
    bd->v = mk_v3(3, 0, 0);
    bd->w = mk_v3(0, 0, 8);
}

/* Seed 000's a/b/c/d: at 60 rad/s a box turns 57 degrees per step, so each
 * corner lands nearer another corner's old place than its own. */
static void build_spin_fast(world *w)
{
    body *bd;
    add_ground(w);
    bd = add_box(w, mk_v3(MK_REAL(0.5), MK_REAL(0.5), MK_REAL(0.25)), 500, mk_v3(0, 0, MK_REAL(0.25)));
    bd->w = mk_v3(0, 0, 60);
}

static void build_pyramid(world *w)
{
    int row_i, k;
    add_ground(w);
    for (row_i = 0; row_i < 10; ++row_i)
        for (k = 0; k < 10 - row_i; ++k)
            add_box(w, mk_v3(MK_REAL(0.5), MK_REAL(0.5), MK_REAL(0.5)), 500,
                    mk_v3(MK_REAL(1.05) * ((mk_real)k - MK_REAL(0.5) * (mk_real)(9 - row_i)), 0, MK_REAL(0.5) + (mk_real)row_i));
}

static const scene scenes[] = {
    {"tower", "10 boxes 0.7x0.7x0.3 m, 110 kg, standing at rest", 5, MK_REAL(0.5), 1, 1, build_tower},
    {"tower_drop", "the same tower released from exact contact", 5, MK_REAL(0.5), 0, 0, build_tower},
    {"heavy_on_light", "1000 kg box on a 10 kg box (1:100), at rest", 5, MK_REAL(0.5), 1, 1, build_heavy_on_light},
    {"slide_spin", "box sliding at 3 m/s, spinning at 8 rad/s, mu 0.2", MK_REAL(1.5), MK_REAL(0.2), 0, 1, build_slide_spin},
    {"spin_fast", "box spinning in place at 60 rad/s (57 degrees a step), mu 0.2", MK_REAL(1.5), MK_REAL(0.2), 0, 1, build_spin_fast},
    {"pyramid", "55 unit boxes in 10 rows, at rest", 5, MK_REAL(0.5), 1, 0, build_pyramid},
};

/* ---- runs and reporting --------------------------------------------------------------- */

typedef struct run_result {
    mk_status status;
    int steps;
    double iters_mean, iters_p95, residual_mean, matched_frac, wrong_frac, penetration, drift, ke_per_box, top_drop;
    int iters_max;
} run_result;

static int cmp_int(const void *a, const void *b) { return *(const int *)a - *(const int *)b; }

static run_result run(const scene *sc, warm_mode warm, int fixed_iterations, int split)
{
    static world w;
    run_result res;
    int steps = (int)(sc->seconds / DT + MK_REAL(0.5)), s, i, dyn = 0, last_second = steps - (int)(1 / DT);
    int *iters = (int *)malloc(sizeof(int) * (size_t)steps);
    double iters_sum = 0, residual_sum = 0, ke = 0, points = 0, matched = 0, wrong = 0;
    mk_real top_z0;
    memset(&res, 0, sizeof res);
    memset(&w, 0, sizeof w);
    w.mu = sc->mu;
    w.warm = warm;
    w.split = split;
    if (!iters || mk_contact_cache_create(4 * MAX_ROWS, NULL, &w.cache) != MK_OK) {
        fprintf(stderr, "solver_demo: out of memory\n");
        exit(2);
    }
    sc->build(&w);
    if (sc->settled) {
        /* Start from rest: one second with the converged solver (warm-started
         * as the run will be), so every mode begins from the same standing
         * stack and the run shows whether 10 iterations can hold it. */
        int k;
        for (k = 0; k < (int)(1 / DT + MK_REAL(0.5)); ++k) step(&w, 0);
        for (k = 0; k < w.nb; ++k) {
            w.b[k].start = w.b[k].x.p;
            w.b[k].v = w.b[k].w = mk_v3_zero();
        }
    }
    top_z0 = w.b[w.nb - 1].x.p.z;
    for (s = 0; s < steps; ++s) {
        step_stats st = step(&w, fixed_iterations);
        if ((res.status = st.status) != MK_OK) break;
        iters[s] = st.iterations;
        iters_sum += st.iterations;
        residual_sum += (double)st.residual;
        points += st.points;
        matched += st.matched;
        wrong += st.wrong;
        if (s >= last_second) res.penetration = fmax(res.penetration, (double)st.penetration);
    }
    if (res.status != MK_OK) {
        mk_contact_cache_destroy(w.cache);
        free(iters);
        return res;
    }
    for (i = 0; i < w.nb; ++i) {
        const body *bd = &w.b[i];
        if (bd->inv_mass == 0) continue;
        dyn++;
        ke += 0.5 * (double)(bd->mass * mk_v3_len2(bd->v));
        ke += 0.5 * (double)mk_v3_dot(bd->w, mk_quat_rotate(bd->x.q, mk_v3_mul(bd->inertia, mk_quat_inv_rotate(bd->x.q, bd->w))));
        res.drift = fmax(res.drift, (double)mk_sqrt_((bd->x.p.x - bd->start.x) * (bd->x.p.x - bd->start.x) +
                                                     (bd->x.p.y - bd->start.y) * (bd->x.p.y - bd->start.y)));
    }
    qsort(iters, (size_t)steps, sizeof(int), cmp_int);
    res.steps = steps;
    res.iters_mean = iters_sum / steps;
    res.iters_p95 = iters[(int)(0.95 * (steps - 1))];
    res.iters_max = iters[steps - 1];
    res.residual_mean = residual_sum / steps;
    res.matched_frac = points > 0 ? matched / points : 0;
    res.wrong_frac = matched > 0 ? wrong / matched : 0;
    res.ke_per_box = ke / dyn;
    res.top_drop = (double)(top_z0 - w.b[w.nb - 1].x.p.z);
    mk_contact_cache_destroy(w.cache);
    free(iters);
    return res;
}

static void json_line(FILE *f, const scene *sc, const char *variant, warm_mode warm, const run_result *r, int split)
{
    if (!f) return;
    fprintf(f,
            "{\"suite\":\"contacts\",\"case\":\"%s\",\"variant\":\"%s\",\"backend\":\"minko.%s\",\"n\":%d,"
            "\"iters_mean\":%.3f,\"iters_p95\":%.0f,\"iters_max\":%d,\"residual_mean\":%.3g,\"warm_matched\":%.4f,\"warm_mismatched\":%.4f,"
            "\"max_penetration\":%.6g,\"drift\":%.6g,\"ke_end\":%.6g,\"top_drop\":%.6g,\"position_correction\":\"%s\","
            "\"precision\":\"%s\"}\n",
            sc->name, variant, warm_names[warm], r->steps, r->iters_mean, r->iters_p95, r->iters_max, r->residual_mean,
            r->matched_frac, r->wrong_frac, r->penetration, r->drift, r->ke_per_box, r->top_drop, split ? "split_impulse" : "baumgarte",
            mk_is_double_precision() ? "double" : "single");
}

int main(int argc, char **argv)
{
    const char *json = NULL, *only = NULL;
    int quick = 0, split = 1, i, k, mode;
    FILE *jf = NULL;
    for (i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--quick")) quick = 1;
        else if (!strcmp(argv[i], "--json") && i + 1 < argc) json = argv[++i];
        else if (!strcmp(argv[i], "--scene") && i + 1 < argc) only = argv[++i];
        else if (!strcmp(argv[i], "--baumgarte")) split = 0;
        else {
            fprintf(stderr, "usage: %s [--quick] [--json FILE] [--scene NAME] [--baumgarte]\n", argv[0]);
            return 2;
        }
    }
    if (json && !(jf = fopen(json, "w"))) {
        perror(json);
        return 2;
    }
    printf("solver_demo: sequential impulses, %s precision, 60 Hz, %s beta %.1f above %.0f mm, speculative %.0f mm, "
           "converge to %.0e m/s\n", mk_is_double_precision() ? "double" : "single", split ? "split impulse" : "Baumgarte",
           (double)BETA, 1e3 * (double)SLOP, 1e3 * (double)MARGIN, (double)RESIDUAL_TOL);
    for (k = 0; k < (int)(sizeof scenes / sizeof scenes[0]); ++k)
        if ((!only || !strcmp(only, scenes[k].name)) && (!quick || scenes[k].quick))
            printf("  %-15s %s\n", scenes[k].name, scenes[k].what);
    printf("%-15s %-8s %-8s %9s %5s %5s %9s %7s %6s %10s %9s %10s %9s\n", "scene", "mode", "warm", "iters", "p95", "max",
           "residual", "matched", "wrong", "max_pen", "drift", "KE/box", "top_drop");
    for (k = 0; k < (int)(sizeof scenes / sizeof scenes[0]); ++k) {
        const scene *sc = &scenes[k];
        if (only && strcmp(only, sc->name)) continue;
        if (quick && !sc->quick) continue;
        for (mode = 0; mode < 2; ++mode) {
            warm_mode wm;
            for (wm = WARM_COLD; wm < WARM_COUNT; wm = (warm_mode)(wm + 1)) {
                run_result r = run(sc, wm, mode == 0 ? 10 : 0, split);
                if (r.status != MK_OK) {
                    printf("%-15s skipped: a pair of this scene is not in this build (%s)\n", sc->name, mk_status_name(r.status));
                    mode = 2;
                    break;
                }
                printf("%-15s %-8s %-8s %9.2f %5.0f %5d %9.2e %6.1f%% %5.1f%% %10.2e %9.2e %10.2e %9.2e\n", sc->name,
                       mode == 0 ? "pgs10" : "converge", warm_names[wm], r.iters_mean, r.iters_p95, r.iters_max,
                       r.residual_mean, 100 * r.matched_frac, 100 * r.wrong_frac, r.penetration, r.drift, r.ke_per_box, r.top_drop);
                json_line(jf, sc, mode == 0 ? "pgs10" : "converge", wm, &r, split);
            }
        }
    }
    if (jf) fclose(jf);
    return 0;
}

/* ode_scenes: ODE scenes run side by side through ODE's own collision and
 * through Minko (adapters/ode), headless.
 *
 * Every backend gets its own dWorld with the same bodies, and all worlds are
 * stepped in turn inside one process, so machine noise hits them alike and
 * ratios between lines are meaningful. Two things make the worlds comparable
 * bit for bit (adapters.md B.5): the pairs a space reports are collected,
 * put in a canonical order (lower geom id first, then sorted) and only then
 * handed to the real near callback; and ODE's global dRand seed, which
 * QuickStep uses to shuffle constraint rows, is saved and restored around
 * each world's step. With identical pair sets and colliders the end states
 * are then identical, which the `same` column checks against the first
 * backend of each case.
 *
 *   ode_scenes [--quick] [--json FILE] [--scene NAME] [--reps N] [--poses FILE] [--frames A:B] [--per-frame FILE]
 *              [--backend NAME[,NAME...]] [--steps N] [--start F] [--compare] [--save-state FILE] [--load-state FILE]
 *
 * --backend NAME[,NAME...] runs only those backends and --steps N runs N
 * steps (short runs under callgrind: --toggle-collect=mk_ode_space_collide
 * or dSpaceCollide then splits a running simulation's space collide per
 * function; `--backend ode.sap,ode.hash,minko.bp` is what the space
 * collide ratio of the stress scene needs; with stress_space, --backend
 * ode.hash|ode.sap|minko|floor replays those spaces only, e.g. one alone
 * for a profile of it); --start F
 * (with --poses FILE, the stress scene only) starts the stress heap from
 * the recorded poses of frame F at rest, so that the settled heap's frames
 * run without the minutes its first frames take (at rest: a different
 * simulation from the running one). --compare: see compare_pair.
 *
 * Restart (with --scene NAME): --save-state FILE writes the first backend's
 * world after the run; --load-state FILE builds every backend's world, puts
 * it in that state and runs on from the saved step (to the scene's end, or
 * --steps N more), which is the uninterrupted run's continuation bit for
 * bit (see "restart" below). The stress scene's steady steps without its
 * dense first 25 (those take ~5 min at load 9):
 *   ode_scenes --scene stress --backend ode.sap --steps 25 --save-state S25
 *   ode_scenes --scene stress --backend ode.sap,ode.hash,minko.bp --load-state S25 --per-frame F
 *   sh demos/ode_ratios.sh F
 * (steps 25..99, ~5 s of CPU); under callgrind, --backend minko.bp
 * --load-state S25 with --toggle-collect=mk_ode_space_collide.
 *
 * Per case and backend: median ms per step (space collide, colliders = the
 * near-callback pass incl. contact joints, total incl. QuickStep), candidate
 * pairs and contacts per step, maximum contact depth reported during the last
 * quarter of the run, geometric ground penetration over the same window,
 * kinetic energy at the end, drift, and tunnelled bodies; for backends with
 * Minko's narrowphase, the share of pairs Minko answered (the rest are class
 * pairs the linked Minko build does not handle yet, which go to dCollide).
 * The resting scenes use ODE's usual 1 mm contact surface layer (the same
 * for every backend); the stress scene is ODE's demo as it is.
 *
 * Scenes: stress (ODE's demo_space_stress), stress_space (its frames
 * replayed through each space alone: see run_space_only), tower (10 boxes), pyramid (210
 * boxes), hulls (20 random convex hulls on a box ground), mixed (sizes
 * 1:100 in a pit), wall (spheres fired at a thin wall, 10 to 1000 m/s; the
 * minko.toi backend splits steps at Minko's times of impact), and
 * hull_depth (hull-hull penetration depth against the exact reference).
 */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <ode/ode.h>

#include "minko_ode.h"
#include "support/oracle.h"

/* ---- small utilities ---------------------------------------------------- */

typedef struct rng { uint64_t s; } rng;
static double rng_unit(rng *r) /* splitmix64, uniform in [0, 1) */
{
    uint64_t z = (r->s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}
static double rng_range(rng *r, double lo, double hi) { return lo + (hi - lo) * rng_unit(r); }

/* The thread's CPU time: on a shared machine a preemption adds a whole
 * scheduler tick (4 ms here) to whichever backend's step it hits, and once
 * more than half of the steps are hit, the medians of a running simulation
 * measure the ticks (ratios between backends drift towards 1). Cache misses
 * caused by the other processes still count. */
static double now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return 1e3 * (double)t.tv_sec + 1e-6 * (double)t.tv_nsec;
}

static void *xrealloc(void *p, size_t n)
{
    void *q = realloc(p, n ? n : 1);
    if (!q) {
        fprintf(stderr, "ode_scenes: out of memory\n");
        exit(2);
    }
    return q;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}
static double median(double *v, int n)
{
    if (n <= 0) return 0;
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* ---- backends ------------------------------------------------------------ */

typedef void space_collide_fn(dSpaceID space, void *data, dNearCallback *cb);
typedef int collide_fn(dGeomID o1, dGeomID o2, int flags, dContactGeom *contact, int skip);

enum space_kind { SPACE_HASH, SPACE_SAP, SPACE_SIMPLE };

typedef struct backend {
    const char *name;        /* the JSON `backend` key */
    enum space_kind space;   /* the container space the geoms live in */
    space_collide_fn *space_collide;
    collide_fn *collide;
    int toi;                 /* split steps at Minko's times of impact (scenes with fast bodies only) */
} backend;

/* Minko's broadphase keeps its geoms in a dSimpleSpace, the container with
 * no upkeep of its own (adapters.md B.2).
 *
 * The first backend is the reference of the `same` column. It is the SAP
 * space, not the hash space: ODE 0.16.2's dHashSpace misses overlapping
 * pairs in the level-0 cells at x = y = 0 whose z range crosses 0 (the
 * unsigned `getVirtualAddressBase(level, x, y) + zbegin` wraps when it is
 * negative, so insertion and lookup disagree on the bucket). The SAP space
 * reports extra plane pairs instead, which yield no contacts. */
static const backend BACKENDS[] = {
    {"ode.sap", SPACE_SAP, dSpaceCollide, dCollide, 0},
    {"ode.hash", SPACE_HASH, dSpaceCollide, dCollide, 0},
    {"minko.bp", SPACE_SIMPLE, mk_ode_space_collide, dCollide, 0},
    {"minko.np", SPACE_SAP, dSpaceCollide, mk_ode_collide, 0},
    {"minko", SPACE_SIMPLE, mk_ode_space_collide, mk_ode_collide, 0},
    {"minko.toi", SPACE_SIMPLE, mk_ode_space_collide, mk_ode_collide, 1},
};
#define NBACKENDS ((int)(sizeof BACKENDS / sizeof BACKENDS[0]))

/* ---- scenes -------------------------------------------------------------- */

enum shape_kind { SH_SPHERE, SH_BOX, SH_HULL };

/* ---- random convex hulls, as ODE convex data and as the exact reference ---- */

/* The hull of 8 to 20 random points on an ellipsoid (semi-axes 0.12 to 0.35 m),
 * shifted so the centre of mass of the solid is the origin (ODE wants the
 * body origin there). Faces, planes and extreme vertices come from the
 * oracle's brute-force long double hull, so native ODE and Minko collide the
 * same solid and the depth reference is exact. */
typedef struct hull_data {
    int nv, nf;
    dReal *points;             /* 3 nv */
    dReal *planes;             /* 4 nf: n.x = d, outward unit n */
    unsigned int *polygons;    /* per face: vertex count, then indices, counter-clockwise from outside */
    double volume, extent[3];  /* for the (box-approximated) inertia */
    mk_oracle_shape exact;
} hull_data;

static mk_lvec3 lv(long double x, long double y, long double z)
{
    mk_lvec3 v;
    v.x = x;
    v.y = y;
    v.z = z;
    return v;
}

static void hull_make(hull_data *h, rng *r)
{
    mk_lvec3 pts[20], apex = lv(0, 0, 0), com = lv(0, 0, 0);
    mk_oracle_shape tmp;
    const mk_oracle_poly *P;
    double ax[3];
    long double vol = 0;
    int n = 8 + (int)(rng_unit(r) * 13), i, f, k, w;
    for (k = 0; k < 3; k++) ax[k] = rng_range(r, 0.12, 0.35);
    for (i = 0; i < n; i++) {
        double d[3], l2;
        do {
            for (k = 0; k < 3; k++) d[k] = rng_range(r, -1, 1);
            l2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        } while (l2 < 1e-3 || l2 > 1);
        l2 = sqrt(l2);
        pts[i] = lv(ax[0] * d[0] / l2, ax[1] * d[1] / l2, ax[2] * d[2] / l2);
    }
    if (mk_oracle_shape_points(&tmp, pts, n, 0) != 0) {
        fprintf(stderr, "ode_scenes: the oracle refused a random hull\n");
        exit(2);
    }
    P = &tmp.core;
    for (i = 0; i < P->nv; i++) apex = lv(apex.x + P->v[i].x / P->nv, apex.y + P->v[i].y / P->nv, apex.z + P->v[i].z / P->nv);
    for (f = 0; f < P->nf; f++) { /* fan of tetrahedra from an interior point */
        const mk_lvec3 *a = &P->v[P->face_vert[P->face_first[f]]];
        for (k = P->face_first[f] + 1; k + 1 < P->face_first[f + 1]; k++) {
            const mk_lvec3 *b = &P->v[P->face_vert[k]], *c = &P->v[P->face_vert[k + 1]];
            mk_lvec3 u = lv(a->x - apex.x, a->y - apex.y, a->z - apex.z), v = lv(b->x - apex.x, b->y - apex.y, b->z - apex.z),
                     t = lv(c->x - apex.x, c->y - apex.y, c->z - apex.z);
            long double dv = (u.x * (v.y * t.z - v.z * t.y) - u.y * (v.x * t.z - v.z * t.x) + u.z * (v.x * t.y - v.y * t.x)) / 6;
            vol += dv;
            com = lv(com.x + dv * (apex.x + a->x + b->x + c->x) / 4, com.y + dv * (apex.y + a->y + b->y + c->y) / 4,
                     com.z + dv * (apex.z + a->z + b->z + c->z) / 4);
        }
    }
    com = lv(com.x / vol, com.y / vol, com.z / vol);
    for (i = 0; i < P->nv; i++) pts[i] = lv(P->v[i].x - com.x, P->v[i].y - com.y, P->v[i].z - com.z);
    if (mk_oracle_shape_points(&h->exact, pts, P->nv, 0) != 0) {
        fprintf(stderr, "ode_scenes: the oracle refused a random hull\n");
        exit(2);
    }
    mk_oracle_shape_free(&tmp);
    P = &h->exact.core;
    h->nv = P->nv;
    h->nf = P->nf;
    h->volume = (double)vol;
    h->points = xrealloc(NULL, 3 * (size_t)h->nv * sizeof(dReal));
    h->planes = xrealloc(NULL, 4 * (size_t)h->nf * sizeof(dReal));
    h->polygons = xrealloc(NULL, ((size_t)h->nf + (size_t)P->face_first[P->nf]) * sizeof(unsigned int));
    for (k = 0; k < 3; k++) h->extent[k] = 0;
    for (i = 0; i < h->nv; i++) {
        double c[3] = {(double)P->v[i].x, (double)P->v[i].y, (double)P->v[i].z};
        for (k = 0; k < 3; k++) {
            h->points[3 * i + k] = c[k];
            if (2 * fabs(c[k]) > h->extent[k]) h->extent[k] = 2 * fabs(c[k]);
        }
    }
    for (f = 0, w = 0; f < h->nf; f++) {
        const mk_lvec3 *v0 = &P->v[P->face_vert[P->face_first[f]]];
        h->planes[4 * f] = (dReal)P->fn[f].x;
        h->planes[4 * f + 1] = (dReal)P->fn[f].y;
        h->planes[4 * f + 2] = (dReal)P->fn[f].z;
        h->planes[4 * f + 3] = (dReal)(P->fn[f].x * v0->x + P->fn[f].y * v0->y + P->fn[f].z * v0->z);
        h->polygons[w++] = (unsigned int)(P->face_first[f + 1] - P->face_first[f]);
        for (k = P->face_first[f]; k < P->face_first[f + 1]; k++) h->polygons[w++] = (unsigned int)P->face_vert[k];
    }
}

static void hull_free(hull_data *h)
{
    free(h->points);
    free(h->planes);
    free(h->polygons);
    mk_oracle_shape_free(&h->exact);
}

/* A dynamic body with one geom. dims: sphere radius; box full side lengths. */
typedef struct body_rec {
    dBodyID body;
    dGeomID geom;
    enum shape_kind shape;
    double dims[3];
    const hull_data *hull;
    double ref[3]; /* reference position for drift */
} body_rec;

struct sim;

typedef struct scene {
    const char *name;
    const char *variant;
    void (*build)(struct sim *s, const struct scene *sc);
    int steps;
    double dt;
    int iterations;        /* QuickStep iterations */
    double surface_layer;  /* dWorldSetContactSurfaceLayer: penetration ODE leaves alone (the usual 1 mm for resting scenes) */
    int max_contacts;
    dSurfaceParameters surface;
    int ground;            /* 1: a ground whose top is z = 0 (tunnelled = centre below it) */
    double wall_x;         /* > 0: tunnelled = centre beyond x = wall_x; fast bodies: TOI backends run */
    enum { DRIFT_NONE, DRIFT_FROM_START, DRIFT_FROM_MID } drift; /* reference pose of `drift` */
    int n;                 /* scene size parameter (bodies, or speed for the wall) */
} scene;

typedef struct pair { uint32_t a, b; } pair;

/* Poses of every body, frame by frame: position then quaternion (7 dReal). */
typedef struct recording { int nbodies, frames; dReal *pose; } recording;

/* --backend, --steps, --start (see the top of the file). */
static const char *only_backend;

/* --backend NAME[,NAME...]: whether `name` is one of them (all without --backend). */
static int backend_chosen(const char *name)
{
    const char *p = only_backend;
    size_t n = strlen(name);
    if (!p) return 1;
    for (;;) {
        const char *end = strchr(p, ',');
        size_t len = end ? (size_t)(end - p) : strlen(p);
        if (len == n && !strncmp(p, name, n)) return 1;
        if (!end) return 0;
        p = end + 1;
    }
}
static int steps_override;
static int start_frame;
static recording start_rec; /* frames of --poses, read for --start */
static const char *save_state_path, *load_state_path; /* --save-state, --load-state */
static int compare_contacts;

typedef struct sim {
    const backend *be;
    const scene *sc;
    dWorldID world;
    dSpaceID space;
    dJointGroupID group;
    body_rec *bodies;
    int nbodies, capbodies;
    dGeomID *geoms; /* by id; dGeomGetData(g) holds the id */
    int ngeoms, capgeoms;
    pair *pairs;
    size_t npairs, cappairs;
    unsigned long seed; /* this world's dRand state */
    int first;          /* the first step run (--load-state: the saved one; else 0) */
    int step;
    double *t_space, *t_narrow, *t_total;
    long long cand_pairs, contacts;
    long long minko_pairs, fallbacks; /* pairs Minko's narrowphase answered / handed to dCollide */
    long long substeps;               /* QuickSteps run (more than steps when split at times of impact) */
    int substep_cap;                  /* steps whose split stopped at MAX_SUBSTEPS */
    double max_depth_late, ground_pen_late;
    struct contact_diff *diff; /* --compare: per class pair, Minko's contacts against dCollide's on the same poses */
} sim;

static uint32_t geom_id(dGeomID g) { return (uint32_t)(uintptr_t)dGeomGetData(g); }

static void register_geom(sim *s, dGeomID g)
{
    if (s->ngeoms == s->capgeoms) {
        s->capgeoms = s->capgeoms ? 2 * s->capgeoms : 64;
        s->geoms = xrealloc(s->geoms, (size_t)s->capgeoms * sizeof *s->geoms);
    }
    dGeomSetData(g, (void *)(uintptr_t)s->ngeoms);
    s->geoms[s->ngeoms++] = g;
}

static body_rec *new_body(sim *s, const double pos[3], const dMatrix3 R)
{
    body_rec *r;
    if (s->nbodies == s->capbodies) {
        s->capbodies = s->capbodies ? 2 * s->capbodies : 64;
        s->bodies = xrealloc(s->bodies, (size_t)s->capbodies * sizeof *s->bodies);
    }
    r = &s->bodies[s->nbodies++];
    memset(r, 0, sizeof *r);
    r->body = dBodyCreate(s->world);
    dBodySetPosition(r->body, pos[0], pos[1], pos[2]);
    if (R) dBodySetRotation(r->body, R);
    memcpy(r->ref, pos, sizeof r->ref);
    return r;
}

static void attach(sim *s, body_rec *r, dGeomID g, const dMass *m)
{
    r->geom = g;
    dGeomSetBody(g, r->body);
    dBodySetMass(r->body, m);
    register_geom(s, g);
}

static body_rec *add_sphere(sim *s, const double pos[3], const dMatrix3 R, double radius, double density)
{
    body_rec *r = new_body(s, pos, R);
    dMass m;
    dMassSetSphere(&m, density, radius);
    r->shape = SH_SPHERE;
    r->dims[0] = radius;
    attach(s, r, dCreateSphere(s->space, radius), &m);
    return r;
}

static body_rec *add_box(sim *s, const double pos[3], const dMatrix3 R, const double len[3], double density)
{
    body_rec *r = new_body(s, pos, R);
    dMass m;
    dMassSetBox(&m, density, len[0], len[1], len[2]);
    r->shape = SH_BOX;
    memcpy(r->dims, len, sizeof r->dims);
    attach(s, r, dCreateBox(s->space, len[0], len[1], len[2]), &m);
    return r;
}

/* Backends with Minko's narrowphase make convex geoms through the adapter,
 * which records their hulls (ODE has no getter for them). */
static dGeomID create_convex(sim *s, const hull_data *h)
{
    if (s->be->collide == mk_ode_collide)
        return mk_ode_create_convex(s->space, h->planes, (unsigned int)h->nf, h->points, (unsigned int)h->nv, h->polygons);
    return dCreateConvex(s->space, h->planes, (unsigned int)h->nf, h->points, (unsigned int)h->nv, h->polygons);
}

/* The mass is the hull's, its inertia that of the hull's bounding box
 * scaled to that mass: an approximation, the same for every backend. */
static body_rec *add_hull(sim *s, const double pos[3], const dMatrix3 R, const hull_data *h, double density)
{
    body_rec *r = new_body(s, pos, R);
    dMass m;
    dMassSetBox(&m, 1, h->extent[0], h->extent[1], h->extent[2]);
    dMassAdjust(&m, density * h->volume);
    r->shape = SH_HULL;
    r->hull = h;
    attach(s, r, create_convex(s, h), &m);
    return r;
}

static void add_ground_plane(sim *s) { register_geom(s, dCreatePlane(s->space, 0, 0, 1, 0)); }

static void add_static_box(sim *s, const double pos[3], const double len[3])
{
    dGeomID g = dCreateBox(s->space, len[0], len[1], len[2]);
    dGeomSetPosition(g, pos[0], pos[1], pos[2]);
    register_geom(s, g);
}

/* ODE's demo_space_stress: spheres of radius [0.05, 0.3), density 5, in
 * x, y in [-1, 1], z in [2, 3], random rotations, on a plane; gravity -0.5,
 * CFM 1e-5, QuickStep 0.05 s. They start heavily overlapping. */
static void build_stress(sim *s, const scene *sc)
{
    rng r = {0x5eed0001u};
    int i;
    dWorldSetGravity(s->world, 0, 0, -0.5);
    dWorldSetCFM(s->world, 1e-5);
    add_ground_plane(s);
    for (i = 0; i < sc->n; i++) {
        double radius = (rng_unit(&r) * 0.5 + 0.1) * 0.5;
        double pos[3];
        dMatrix3 R;
        pos[0] = rng_unit(&r) * 2 - 1;
        pos[1] = rng_unit(&r) * 2 - 1;
        pos[2] = rng_unit(&r) + 2;
        dRFromAxisAndAngle(R, rng_unit(&r) * 2 - 1, rng_unit(&r) * 2 - 1, rng_unit(&r) * 2 - 1, rng_unit(&r) * 10 - 5);
        add_sphere(s, pos, R, radius, 5.0);
    }
}

/* Unit boxes stacked exactly face to face on a plane. */
static void build_tower(sim *s, const scene *sc)
{
    static const double len[3] = {1, 1, 1};
    int i;
    dWorldSetGravity(s->world, 0, 0, -9.81);
    add_ground_plane(s);
    for (i = 0; i < sc->n; i++) {
        double pos[3] = {0, 0, 0.5 + i};
        add_box(s, pos, NULL, len, 1.0);
    }
}

/* A 2-D pyramid of unit boxes, `rows` rows (20 rows = 210 boxes), 1 cm gaps
 * between neighbours of a row. */
static void build_pyramid(sim *s, const scene *sc)
{
    static const double len[3] = {1, 1, 1};
    int rows = sc->n, row, i;
    dWorldSetGravity(s->world, 0, 0, -9.81);
    add_ground_plane(s);
    for (row = 0; row < rows; row++) {
        int k = rows - row;
        for (i = 0; i < k; i++) {
            double pos[3] = {(i - 0.5 * (k - 1)) * 1.01, 0, 0.5 + row};
            add_box(s, pos, NULL, len, 1.0);
        }
    }
}

/* Spheres and boxes with sizes log-uniform over 1:100 (0.05 m to 5 m),
 * placed without overlap above a plane and dropped into a heap inside a
 * 20 x 20 m pit. Mild angular damping stops spheres rolling forever, so the
 * kinetic energy at the end measures jitter, not free rolling. */
static void build_mixed(sim *s, const scene *sc)
{
    static const double wall_len[2][3] = {{1, 22, 4}, {22, 1, 4}};
    rng r = {0x5eed0003u};
    double (*placed)[4] = xrealloc(NULL, (size_t)sc->n * sizeof *placed);
    int i, j;
    dWorldSetGravity(s->world, 0, 0, -9.81);
    dWorldSetAngularDamping(s->world, 0.02);
    add_ground_plane(s);
    for (i = 0; i < 4; i++) {
        double pos[3] = {0, 0, 2};
        pos[i / 2] = i % 2 ? 10.5 : -10.5;
        add_static_box(s, pos, wall_len[i / 2]);
    }
    for (i = 0; i < sc->n; i++) {
        double size = 0.05 * pow(100.0, rng_unit(&r)), bound = size, pos[3];
        int is_box = rng_unit(&r) < 0.5, clear = 0;
        double len[3];
        dMatrix3 R;
        if (is_box) {
            len[0] = size;
            len[1] = size * rng_range(&r, 0.5, 1);
            len[2] = size * rng_range(&r, 0.5, 1);
            bound = 0.5 * sqrt(len[0] * len[0] + len[1] * len[1] + len[2] * len[2]);
        } else {
            bound = 0.5 * size;
        }
        pos[0] = rng_range(&r, -1, 1) * (9.9 - bound); /* inside the pit */
        pos[1] = rng_range(&r, -1, 1) * (9.9 - bound);
        pos[2] = bound + 0.05;
        while (!clear) { /* raise it until its bounding sphere is clear of every earlier one */
            clear = 1;
            for (j = 0; j < i; j++) {
                double dx = pos[0] - placed[j][0], dy = pos[1] - placed[j][1], dz = pos[2] - placed[j][2];
                double need = bound + placed[j][3] + 0.02;
                if (dx * dx + dy * dy + dz * dz < need * need) {
                    pos[2] = placed[j][2] + need + 1e-3;
                    clear = 0;
                }
            }
        }
        placed[i][0] = pos[0];
        placed[i][1] = pos[1];
        placed[i][2] = pos[2];
        placed[i][3] = bound;
        dRFromAxisAndAngle(R, rng_unit(&r) * 2 - 1, rng_unit(&r) * 2 - 1, rng_unit(&r) * 2 - 1, rng_unit(&r) * 6.3);
        if (is_box)
            add_box(s, pos, R, len, 1.0);
        else
            add_sphere(s, pos, R, 0.5 * size, 1.0);
    }
    free(placed);
}

/* Spheres of radius 0.05 fired along +x at a static wall 0.1 m thick
 * (x in [0, 0.1]), no gravity. WALL_SHOTS spheres per speed, their starting
 * distances staggered over one step's travel so every phase of the step is
 * sampled. A sphere whose centre ends beyond x = 0.1 went through. */
/* The scenes' hulls, made once: ODE keeps pointers to the convex data. */
#define NHULLS 20
static hull_data hulls[NHULLS];

/* 20 random hulls dropped from 1 cm onto a static box ground, in a 5 x 4
 * grid 0.9 m apart (neighbours can meet when they tip over). */
static void build_hulls(sim *s, const scene *sc)
{
    static const double ground_len[3] = {12, 12, 1}, ground_pos[3] = {0, 0, -0.5};
    rng r = {0x5eed0004u};
    int i, k;
    (void)sc;
    dWorldSetGravity(s->world, 0, 0, -9.81);
    add_static_box(s, ground_pos, ground_len);
    for (i = 0; i < NHULLS; i++) {
        const hull_data *h = &hulls[i];
        double pos[3], lo = HUGE_VAL;
        dMatrix3 R;
        dRFromAxisAndAngle(R, rng_unit(&r) * 2 - 1, rng_unit(&r) * 2 - 1, rng_unit(&r) * 2 - 1, rng_unit(&r) * 6.3);
        for (k = 0; k < h->nv; k++) {
            double z = R[8] * h->points[3 * k] + R[9] * h->points[3 * k + 1] + R[10] * h->points[3 * k + 2];
            if (z < lo) lo = z;
        }
        pos[0] = (i % 5 - 2) * 0.9;
        pos[1] = (i / 5 - 1.5) * 0.9;
        pos[2] = 0.01 - lo;
        add_hull(s, pos, R, h, 1000.0);
    }
}

#define WALL_SHOTS 8
static void build_wall(sim *s, const scene *sc)
{
    static const double wall_len[3] = {0.1, 4, 4}, wall_pos[3] = {0.05, 0, 0};
    double v = (double)sc->n, travel = v * sc->dt;
    int i;
    dWorldSetGravity(s->world, 0, 0, 0);
    add_static_box(s, wall_pos, wall_len);
    for (i = 0; i < WALL_SHOTS; i++) {
        double pos[3];
        body_rec *r;
        pos[0] = -0.5 - travel * (double)i / WALL_SHOTS;
        pos[1] = -1.5 + 3.0 * (i % 4) / 3.0;
        pos[2] = i < 4 ? -0.75 : 0.75;
        r = add_sphere(s, pos, NULL, 0.05, 1000.0);
        dBodySetLinearVel(r->body, v, 0, 0);
    }
}

static dSurfaceParameters surface(int mode, double mu, double bounce, double bounce_vel, double soft_cfm)
{
    dSurfaceParameters p;
    memset(&p, 0, sizeof p);
    p.mode = mode;
    p.mu = mu;
    p.bounce = bounce;
    p.bounce_vel = bounce_vel;
    p.soft_cfm = soft_cfm;
    return p;
}

/* ---- one world's step ---------------------------------------------------- */

static void collect_cb(void *data, dGeomID o1, dGeomID o2)
{
    sim *s = data;
    uint32_t a = geom_id(o1), b = geom_id(o2);
    if (s->npairs == s->cappairs) {
        s->cappairs = s->cappairs ? 2 * s->cappairs : 1024;
        s->pairs = xrealloc(s->pairs, s->cappairs * sizeof *s->pairs);
    }
    s->pairs[s->npairs].a = a < b ? a : b;
    s->pairs[s->npairs].b = a < b ? b : a;
    s->npairs++;
}

static int cmp_pair(const void *x, const void *y)
{
    const pair *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    return (p->b > q->b) - (p->b < q->b);
}

#define MAX_CONTACTS 16
#define BIG_STEP_CONTACTS 100000

/* --compare: for a backend with Minko's narrowphase, every pair is also
 * handed to dCollide on the same poses (outside the simulation: only its
 * answer is kept, and the timings then include it). Per pair of ODE classes:
 * the pairs where the two disagree on the contact count, on whether there is
 * a contact, on the deepest depth (beyond 1e-4 m + 1 %), or on the deepest
 * contact's normal (more than 2.6 degrees apart). */
#define DIFF_CLASSES 16
typedef struct contact_diff { long long pairs, count, presence, depth, normal; } contact_diff;

static const dContactGeom *deepest(const dContact *c, int n)
{
    const dContactGeom *d = NULL;
    int i;
    for (i = 0; i < n; i++)
        if (!d || c[i].geom.depth > d->depth) d = &c[i].geom;
    return d;
}

static void compare_pair(sim *s, dGeomID o1, dGeomID o2, const dContact *c, int n)
{
    dContact r[MAX_CONTACTS];
    int c1 = dGeomGetClass(o1), c2 = dGeomGetClass(o2), nr;
    contact_diff *d;
    if (c1 >= DIFF_CLASSES || c2 >= DIFF_CLASSES) return;
    if (!s->diff) s->diff = calloc(DIFF_CLASSES * DIFF_CLASSES, sizeof *s->diff);
    if (!s->diff) return;
    nr = dCollide(o1, o2, s->sc->max_contacts, &r[0].geom, (int)sizeof(dContact));
    d = &s->diff[(c1 < c2 ? c1 : c2) * DIFF_CLASSES + (c1 < c2 ? c2 : c1)];
    d->pairs++;
    d->count += n != nr;
    d->presence += (n > 0) != (nr > 0);
    if (n > 0 && nr > 0) {
        const dContactGeom *a = deepest(c, n), *b = deepest(r, nr);
        double dot = a->normal[0] * b->normal[0] + a->normal[1] * b->normal[1] + a->normal[2] * b->normal[2];
        d->depth += fabs(a->depth - b->depth) > 1e-4 + 0.01 * fabs(b->depth);
        d->normal += dot < 0.999;
    }
}

static void print_diff(const sim *s)
{
    int i, j;
    if (!s->diff) return;
    printf("  %s against dCollide on the same poses (pairs that differ; classes as ODE numbers them):\n", s->be->name);
    printf("    %-7s %10s %8s %9s %8s %8s\n", "classes", "pairs", "count", "presence", "depth", "normal");
    for (i = 0; i < DIFF_CLASSES; i++)
        for (j = i; j < DIFF_CLASSES; j++) {
            const contact_diff *d = &s->diff[i * DIFF_CLASSES + j];
            if (d->pairs)
                printf("    %2d-%-4d %10lld %8lld %9lld %8lld %8lld\n", i, j, d->pairs, d->count, d->presence, d->depth, d->normal);
        }
}

static void contact_pair(sim *s, dGeomID o1, dGeomID o2, int late)
{
    dContact c[MAX_CONTACTS];
    dBodyID b1 = dGeomGetBody(o1), b2 = dGeomGetBody(o2);
    int i, n;
    if (!b1 && !b2) return; /* two static geoms (the mixed pit's walls meet at its corners): no joint could act, and their 1 m overlap was the depth column */
    if (b1 && b2 && dAreConnectedExcluding(b1, b2, dJointTypeContact)) return;
    n = s->be->collide(o1, o2, s->sc->max_contacts, &c[0].geom, (int)sizeof(dContact));
    if (compare_contacts && s->be->collide != dCollide) compare_pair(s, o1, o2, c, n);
    s->contacts += n;
    for (i = 0; i < n; i++) {
        dJointID j;
        c[i].surface = s->sc->surface;
        if (late && c[i].geom.depth > s->max_depth_late) s->max_depth_late = c[i].geom.depth;
        j = dJointCreateContact(s->world, s->group, &c[i]);
        dJointAttach(j, b1, b2);
    }
}

/* Lowest point of a body's surface (ground scenes, ground top at z = 0). */
static double lowest_z(const body_rec *r)
{
    const dReal *p = dBodyGetPosition(r->body), *R = dBodyGetRotation(r->body);
    if (r->shape == SH_SPHERE) return p[2] - r->dims[0];
    if (r->shape == SH_HULL) {
        double lo = HUGE_VAL;
        int i;
        for (i = 0; i < r->hull->nv; i++) {
            const dReal *q = &r->hull->points[3 * i];
            double z = p[2] + R[8] * q[0] + R[9] * q[1] + R[10] * q[2];
            if (z < lo) lo = z;
        }
        return lo;
    }
    return p[2] - 0.5 * (fabs(R[8]) * r->dims[0] + fabs(R[9]) * r->dims[1] + fabs(R[10]) * r->dims[2]);
}

/* One discrete collision pass: the space's pairs, collected, put in canonical
 * order, then the near callback on each. Adds its times to *t_space, *t_narrow. */
static void discrete_pass(sim *s, int late, double *t_space, double *t_narrow)
{
    mk_ode_stats st0, st1;
    double t0, t1, t2;
    size_t i;
    t0 = now_ms();
    s->npairs = 0;
    s->be->space_collide(s->space, s, collect_cb);
    t1 = now_ms();
    qsort(s->pairs, s->npairs, sizeof *s->pairs, cmp_pair);
    mk_ode_get_stats(&st0);
    t2 = now_ms();
    for (i = 0; i < s->npairs; i++) contact_pair(s, s->geoms[s->pairs[i].a], s->geoms[s->pairs[i].b], late);
    *t_narrow += now_ms() - t2;
    *t_space += t1 - t0;
    mk_ode_get_stats(&st1);
    s->minko_pairs += st1.collide_calls - st0.collide_calls;
    s->fallbacks += st1.fallbacks - st0.fallbacks;
    s->cand_pairs += (long long)s->npairs;
}

static void quick_step(sim *s, double h)
{
    dRandSetSeed(s->seed);
    dWorldQuickStep(s->world, h);
    s->seed = dRandGetSeed();
    dJointGroupEmpty(s->group);
}

/* Half the smallest extent: how far a body may move in one step before it
 * can skip over something as thin as itself. */
static double thickness(const body_rec *r)
{
    double t = r->dims[0];
    if (r->shape == SH_BOX) t = 0.5 * fmin(r->dims[0], fmin(r->dims[1], r->dims[2]));
    if (r->shape == SH_HULL) t = 0.5 * fmin(r->hull->extent[0], fmin(r->hull->extent[1], r->hull->extent[2]));
    return t;
}

#define MAX_SUBSTEPS 16

/* A step split at times of impact: discrete contacts, then for every fast
 * body (one that moves more than half its thickness in what remains of the
 * step) the time of impact against every other geom; the world steps to the
 * earliest, and geoms that touch at the start of a substep while closing in
 * get the contact mk_ode_time_of_impact reports. Everything in the scene
 * takes part in the substeps, as in any host that splits its step. */
static void toi_step(sim *s, int late, double *t_space, double *t_narrow)
{
    double remaining = s->sc->dt;
    int sub, k, g;
    for (sub = 0; remaining > 0; sub++) {
        double h = remaining, t0;
        discrete_pass(s, late, t_space, t_narrow);
        t0 = now_ms();
        for (k = 0; sub < MAX_SUBSTEPS && k < s->nbodies; k++) {
            const body_rec *r = &s->bodies[k];
            const dReal *v = dBodyGetLinearVel(r->body);
            double th = thickness(r);
            if (sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * remaining <= 0.5 * th) continue;
            for (g = 0; g < s->ngeoms; g++) {
                dGeomID other = s->geoms[g];
                dContact c;
                dReal t;
                if (other == r->geom || dGeomGetBody(other) == r->body) continue;
                if (mk_ode_time_of_impact(r->geom, other, remaining, 0.01 * th, &t, &c.geom) != 1) continue;
                if (t > 0) {
                    h = t < h ? t : h;
                } else {
                    dJointID j;
                    c.surface = s->sc->surface;
                    j = dJointCreateContact(s->world, s->group, &c);
                    dJointAttach(j, r->body, dGeomGetBody(other));
                    s->contacts++;
                }
            }
        }
        *t_narrow += now_ms() - t0;
        if (sub == MAX_SUBSTEPS) s->substep_cap++; /* the rest of the step goes unguarded */
        quick_step(s, h);
        s->substeps++;
        remaining -= h;
    }
}

static void sim_step(sim *s)
{
    const scene *sc = s->sc;
    int late = s->step >= sc->steps - sc->steps / 4;
    long long contacts_before = s->contacts;
    double t0 = now_ms(), t_space = 0, t_narrow = 0;

    if (s->be->toi) {
        toi_step(s, late, &t_space, &t_narrow);
    } else {
        discrete_pass(s, late, &t_space, &t_narrow);
        quick_step(s, sc->dt);
    }
    if (s->contacts - contacts_before > BIG_STEP_CONTACTS) {
        /* QuickStep keeps its working memory at the high-water mark; the
         * stress scene's first steps (millions of contacts) would otherwise
         * hold gigabytes in every world at once. */
        dWorldCleanupWorkingMemory(s->world);
        dJointGroupDestroy(s->group);
        s->group = dJointGroupCreate(0);
    }
    s->t_space[s->step] = t_space;
    s->t_narrow[s->step] = t_narrow;
    s->t_total[s->step] = now_ms() - t0;

    if (late && sc->ground) {
        int k;
        for (k = 0; k < s->nbodies; k++) {
            double pen = -lowest_z(&s->bodies[k]);
            if (pen > s->ground_pen_late) s->ground_pen_late = pen;
        }
    }
    if (sc->drift == DRIFT_FROM_MID && s->step == sc->steps / 2) {
        int k;
        for (k = 0; k < s->nbodies; k++) memcpy(s->bodies[k].ref, dBodyGetPosition(s->bodies[k].body), 3 * sizeof(double));
    }
    s->step++;
}

static void sim_init(sim *s, const backend *be, const scene *sc)
{
    memset(s, 0, sizeof *s);
    s->be = be;
    s->sc = sc;
    s->world = dWorldCreate();
    s->space = be->space == SPACE_SAP    ? dSweepAndPruneSpaceCreate(0, dSAP_AXES_XYZ)
               : be->space == SPACE_HASH ? dHashSpaceCreate(0)
                                         : dSimpleSpaceCreate(0);
    s->group = dJointGroupCreate(0);
    s->seed = 0;
    dWorldSetQuickStepNumIterations(s->world, sc->iterations);
    dWorldSetContactSurfaceLayer(s->world, sc->surface_layer);
    sc->build(s, sc);
    s->t_space = xrealloc(NULL, (size_t)sc->steps * sizeof(double));
    s->t_narrow = xrealloc(NULL, (size_t)sc->steps * sizeof(double));
    s->t_total = xrealloc(NULL, (size_t)sc->steps * sizeof(double));
}

static void sim_free(sim *s)
{
    dJointGroupDestroy(s->group);
    mk_ode_space_forget(s->space);
    dSpaceDestroy(s->space);
    dWorldDestroy(s->world);
    free(s->bodies);
    free(s->geoms);
    free(s->pairs);
    free(s->t_space);
    free(s->t_narrow);
    free(s->t_total);
    free(s->diff);
}

/* ---- end-of-run metrics -------------------------------------------------- */

typedef struct metrics {
    double ms_total, ms_collision, ms_space, ms_narrow;
    double pairs_per_step, contacts_per_step;
    double max_depth, ground_pen, ke_end, drift;
    double minko_share; /* of the pairs the narrowphase saw, the fraction Minko answered */
    int tunnelled;
} metrics;

static double kinetic_energy(const body_rec *r)
{
    dMass m;
    const dReal *v = dBodyGetLinearVel(r->body), *w = dBodyGetAngularVel(r->body), *R = dBodyGetRotation(r->body);
    double wl[3], e;
    int i;
    dBodyGetMass(r->body, &m);
    /* angular velocity in the body frame: R^T w (dMatrix3 is 3 rows of 4) */
    for (i = 0; i < 3; i++) wl[i] = R[0 * 4 + i] * w[0] + R[1 * 4 + i] * w[1] + R[2 * 4 + i] * w[2];
    e = 0.5 * m.mass * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (i = 0; i < 3; i++) e += 0.5 * wl[i] * (m.I[i * 4 + 0] * wl[0] + m.I[i * 4 + 1] * wl[1] + m.I[i * 4 + 2] * wl[2]);
    return e;
}

static metrics sim_metrics(sim *s)
{
    const scene *sc = s->sc;
    metrics m;
    int nsteps = sc->steps - s->first, i;
    double *coll = xrealloc(NULL, (size_t)nsteps * sizeof(double));
    memset(&m, 0, sizeof m);
    for (i = 0; i < nsteps; i++) coll[i] = s->t_space[s->first + i] + s->t_narrow[s->first + i];
    m.ms_collision = median(coll, nsteps);
    m.ms_space = median(s->t_space + s->first, nsteps);
    m.ms_narrow = median(s->t_narrow + s->first, nsteps);
    m.ms_total = median(s->t_total + s->first, nsteps);
    free(coll);
    m.pairs_per_step = (double)s->cand_pairs / nsteps;
    m.contacts_per_step = (double)s->contacts / nsteps;
    m.minko_share = s->minko_pairs + s->fallbacks ? (double)s->minko_pairs / (double)(s->minko_pairs + s->fallbacks) : 0;
    m.max_depth = s->max_depth_late;
    m.ground_pen = s->ground_pen_late;
    for (i = 0; i < s->nbodies; i++) {
        const body_rec *r = &s->bodies[i];
        const dReal *p = dBodyGetPosition(r->body);
        double d = sqrt((p[0] - r->ref[0]) * (p[0] - r->ref[0]) + (p[1] - r->ref[1]) * (p[1] - r->ref[1]) +
                        (p[2] - r->ref[2]) * (p[2] - r->ref[2]));
        m.ke_end += kinetic_energy(r);
        if (sc->drift != DRIFT_NONE && d > m.drift) m.drift = d;
        if (sc->ground && p[2] < 0) m.tunnelled++;
        if (sc->wall_x > 0 && p[0] > sc->wall_x) m.tunnelled++;
    }
    return m;
}

/* 1 if both worlds ended in bitwise the same state. */
static int same_state(const sim *a, const sim *b)
{
    int i;
    if (a->nbodies != b->nbodies) return 0;
    for (i = 0; i < a->nbodies; i++) {
        if (memcmp(dBodyGetPosition(a->bodies[i].body), dBodyGetPosition(b->bodies[i].body), 3 * sizeof(dReal)) ||
            memcmp(dBodyGetQuaternion(a->bodies[i].body), dBodyGetQuaternion(b->bodies[i].body), 4 * sizeof(dReal)))
            return 0;
    }
    return 1;
}

/* ---- output -------------------------------------------------------------- */

static void print_header(const scene *sc, int first, int nbodies)
{
    printf("\n%s %s: %d bodies, steps %d..%d of %g s (ms are medians per step)\n", sc->name, sc->variant, nbodies, first,
           sc->steps - 1, sc->dt);
    printf("  %-10s %8s %8s %8s %8s %9s %9s %9s %9s %10s %9s %4s %4s %6s\n", "backend", "total", "collide", "space",
           "narrow", "pairs", "contacts", "depth", "ground", "ke_end", "drift", "tun", "same", "minko");
}

static void print_row(const sim *s, const metrics *m, int same)
{
    char share[16] = "-";
    if (s->be->collide != dCollide) snprintf(share, sizeof share, "%.0f%%", 100 * m->minko_share);
    printf("  %-10s %8.3f %8.3f %8.3f %8.3f %9.1f %9.1f %9.2e %9.2e %10.3e %9.2e %4d %4s %6s\n", s->be->name, m->ms_total,
           m->ms_collision, m->ms_space, m->ms_narrow, m->pairs_per_step, m->contacts_per_step, m->max_depth,
           m->ground_pen, m->ke_end, m->drift, m->tunnelled, same ? "yes" : "no", share);
}

static void json_row(FILE *f, const sim *s, const metrics *m, int same)
{
    const scene *sc = s->sc;
    if (!f) return;
    fprintf(f,
            "{\"suite\":\"ode\",\"case\":\"%s\",\"variant\":\"%s\",\"backend\":\"%s\",\"n\":%d,\"bodies\":%d,"
            "\"dt\":%g,\"ms_per_frame\":%.6g,\"collision_ms_per_frame\":%.6g,\"space_ms_per_frame\":%.6g,"
            "\"narrow_ms_per_frame\":%.6g,\"candidate_pairs_per_frame\":%.6g,\"contacts_per_frame\":%.6g,"
            "\"max_penetration\":%.6g,\"ground_penetration\":%.6g,\"ke_end\":%.6g,\"drift\":%.6g,\"tunnelled\":%d,"
            "\"same_end_state_as\":\"%s\",\"same_end_state\":%s",
            sc->name, sc->variant, s->be->name, sc->steps - s->first, s->nbodies, sc->dt, m->ms_total, m->ms_collision,
            m->ms_space, m->ms_narrow, m->pairs_per_step, m->contacts_per_step, m->max_depth, m->ground_pen,
            m->ke_end, m->drift, m->tunnelled, BACKENDS[0].name, same ? "true" : "false");
    if (s->first) fprintf(f, ",\"first_step\":%d", s->first);
    if (s->be->collide != dCollide) fprintf(f, ",\"minko_narrowphase_share\":%.6g", m->minko_share);
    if (s->be->toi)
        fprintf(f, ",\"substeps_per_frame\":%.6g,\"substep_cap_hits\":%d", (double)s->substeps / (sc->steps - s->first), s->substep_cap);
    fprintf(f, "}\n");
    fflush(f);
}

/* ---- driver -------------------------------------------------------------- */

static void pose_bodies(const sim *s, const recording *r, int frame);

/* --per-frame FILE: one JSON line per step and backend (its space, colliders
 * and total ms), to see where a median lies in a running simulation. */
static void write_steps(FILE *pf, const sim *s)
{
    int i;
    for (i = s->first; i < s->sc->steps; i++)
        fprintf(pf,
                "{\"suite\":\"ode\",\"case\":\"%s_step\",\"variant\":\"%s\",\"backend\":\"%s\",\"n\":1,\"step\":%d,"
                "\"space_ms\":%.6g,\"narrow_ms\":%.6g,\"total_ms\":%.6g}\n",
                s->sc->name, s->sc->variant, s->be->name, i, s->t_space[i], s->t_narrow[i], s->t_total[i]);
}

/* ---- restart: --save-state FILE, --load-state FILE ----
 *
 * A world's state between two steps is its bodies' positions, quaternions
 * and velocities and its dRand seed: contact joints are emptied after every
 * step, forces are cleared by the step, and QuickStep keeps no warm start.
 * The file holds that state for one scene (name and size checked) after
 * `step` steps; loading it into freshly built worlds (the same geoms and
 * masses, rebuilt by the scene) continues the run at that step, bit for
 * bit: the 10 000-sphere stress heap saved at step 25 and continued to 100
 * ends in the same state as the run from step 0, checked with
 *   --scene stress --backend ode.sap --save-state END0
 *   --scene stress --backend ode.sap --steps 25 --save-state S25
 *   --scene stress --backend ode.sap --load-state S25 --save-state END25
 *   cmp END0 END25
 * (and likewise for tower, pyramid and mixed). The state is ODE's only:
 * backends with Minko's narrowphase (minko, minko.np) continue with a cold
 * contact cache, so their worlds are not bit for bit theirs; minko.bp, the
 * space collide backend, keeps nothing that changes a world. */

#define STATE_MAGIC 0x4d4b5354u /* "MKST" */
#define STATE_REALS 25          /* per body: position 3, quaternion 4, linear and angular velocity 3 + 3, rotation 12 */

typedef struct world_state {
    int step, nbodies;
    unsigned long seed;
    dReal *body; /* STATE_REALS per body */
} world_state;

static void state_header(const scene *sc, uint32_t head[8], int step, int nbodies)
{
    memset(head, 0, 8 * sizeof *head);
    head[0] = STATE_MAGIC;
    strncpy((char *)&head[1], sc->name, 12); /* head[1..3]: the scene's name, cut to 12 bytes */
    head[4] = (uint32_t)sc->n;
    head[5] = (uint32_t)nbodies;
    head[6] = (uint32_t)step;
}

/* The first world's state after its last step (--save-state). */
static void save_state(const char *path, const sim *s)
{
    FILE *f = fopen(path, "wb");
    uint32_t head[8];
    uint64_t seed = s->seed;
    int k, ok = f != NULL;
    state_header(s->sc, head, s->step, s->nbodies);
    ok = ok && fwrite(head, sizeof head, 1, f) == 1 && fwrite(&seed, sizeof seed, 1, f) == 1;
    for (k = 0; ok && k < s->nbodies; k++) {
        dBodyID b = s->bodies[k].body;
        ok = fwrite(dBodyGetPosition(b), sizeof(dReal), 3, f) == 3 && fwrite(dBodyGetQuaternion(b), sizeof(dReal), 4, f) == 4 &&
             fwrite(dBodyGetLinearVel(b), sizeof(dReal), 3, f) == 3 && fwrite(dBodyGetAngularVel(b), sizeof(dReal), 3, f) == 3 &&
             fwrite(dBodyGetRotation(b), sizeof(dReal), 12, f) == 12;
    }
    if (!ok || fclose(f) != 0) {
        perror(path);
        exit(2);
    }
}

static void load_state(const char *path, const scene *sc, world_state *w)
{
    FILE *f = fopen(path, "rb");
    uint32_t head[8], want[8];
    uint64_t seed;
    size_t n;
    if (!f) {
        perror(path);
        exit(2);
    }
    if (fread(head, sizeof head, 1, f) != 1 || fread(&seed, sizeof seed, 1, f) != 1) head[0] = 0;
    state_header(sc, want, (int)head[6], (int)head[5]);
    if (memcmp(head, want, sizeof head) != 0) {
        fprintf(stderr, "ode_scenes: %s is not a saved state of %s %s\n", path, sc->name, sc->variant);
        exit(2);
    }
    w->step = (int)head[6];
    w->nbodies = (int)head[5];
    w->seed = (unsigned long)seed;
    n = STATE_REALS * (size_t)w->nbodies;
    w->body = xrealloc(NULL, n * sizeof(dReal));
    if (fread(w->body, sizeof(dReal), n, f) != n) {
        fprintf(stderr, "ode_scenes: %s is truncated\n", path);
        exit(2);
    }
    fclose(f);
}

/* Puts a freshly built world in state w: it continues at step w->step. */
static void restore_state(sim *s, const world_state *w)
{
    int k;
    if (s->nbodies != w->nbodies) {
        fprintf(stderr, "ode_scenes: the saved state has %d bodies, %s builds %d\n", w->nbodies, s->sc->name, s->nbodies);
        exit(2);
    }
    for (k = 0; k < s->nbodies; k++) {
        const dReal *x = w->body + STATE_REALS * (size_t)k;
        body_rec *r = &s->bodies[k];
        dBodySetPosition(r->body, x[0], x[1], x[2]);
        /* dBodySetQuaternion normalises q again, which moves the last bit
         * of many stepped (already normalised) quaternions, and the heap is
         * chaotic enough to carry that into the positions (5e-10 m in 75
         * steps): after it has told the geoms, the saved q and R are
         * written over the body's own (the arrays ODE's getters return). */
        dBodySetQuaternion(r->body, x + 3);
        memcpy((dReal *)dBodyGetQuaternion(r->body), x + 3, 4 * sizeof(dReal));
        memcpy((dReal *)dBodyGetRotation(r->body), x + 13, 12 * sizeof(dReal));
        dBodySetLinearVel(r->body, x[7], x[8], x[9]);
        dBodySetAngularVel(r->body, x[10], x[11], x[12]);
        memcpy(r->ref, x, sizeof r->ref);
    }
    s->seed = w->seed;
    s->first = s->step = w->step;
}

static void run_case(const scene *case_sc, FILE *json, FILE *pf)
{
    sim sims[NBACKENDS];
    scene shortened = *case_sc;
    const scene *sc = &shortened;
    world_state w = {0, 0, 0, NULL};
    int b, n = 0;
    if (load_state_path) load_state(load_state_path, case_sc, &w);
    if (steps_override > 0) shortened.steps = w.step + steps_override; /* steps run, from the loaded one */
    if (w.step >= sc->steps) {
        fprintf(stderr, "ode_scenes: %s is saved at step %d; %s has %d steps (--steps N runs N more)\n", load_state_path,
                w.step, sc->name, sc->steps);
        exit(2);
    }
    for (b = 0; b < NBACKENDS; b++) { /* time of impact only where something is fast */
        if ((BACKENDS[b].toi && sc->wall_x <= 0) || !backend_chosen(BACKENDS[b].name)) continue;
        sim_init(&sims[n], &BACKENDS[b], sc);
        if (start_rec.pose && sc->build == build_stress) pose_bodies(&sims[n], &start_rec, start_frame);
        if (w.body) restore_state(&sims[n], &w);
        n++;
    }
    free(w.body);
    if (n == 0) {
        fprintf(stderr, "ode_scenes: no backend %s in %s\n", only_backend, sc->name);
        exit(2);
    }
    while (sims[0].step < sc->steps)
        for (b = 0; b < n; b++) sim_step(&sims[b]);
    if (save_state_path) save_state(save_state_path, &sims[0]);
    if (pf)
        for (b = 0; b < n; b++) write_steps(pf, &sims[b]); /* before sim_metrics sorts the times */
    print_header(sc, sims[0].first, sims[0].nbodies);
    for (b = 0; b < n; b++) {
        metrics m = sim_metrics(&sims[b]);
        int same = same_state(&sims[0], &sims[b]);
        print_row(&sims[b], &m, same);
        json_row(json, &sims[b], &m, same);
    }
    for (b = 0; b < n; b++) print_diff(&sims[b]);
    for (b = 0; b < n; b++) sim_free(&sims[b]);
}

/* ---- space collide alone: the stress heap replayed through each space ----
 *
 * The stress case times a space collide inside a running simulation, where
 * each backend's world drifts apart and the machine's noise lands on one
 * backend's step at a time. Here the heap is simulated once (native SAP space
 * and colliders), every body's pose is recorded before each step's collision,
 * and the same frames are replayed through dHashSpace, dSweepAndPruneSpace
 * and Minko's space collide in one process: per frame, each space's bodies
 * are set to the recorded poses (untimed), then only the space collide is
 * timed, with the same trivial near callback for all three (it stores the two
 * geom pointers). A fourth row, `floor`, times what all of them pay through
 * ODE's API and nothing else (floor_collide). The pair sets are compared outside the timing. Each frame's
 * time is the best of `reps` replays (each replay starts Minko cold), and the
 * spaces take turns going first.
 *
 * Frame 0 is the stress heap as built (10 000 spheres overlapping in a
 * 2 x 2 x 1 m box): 3.3 M pairs, and over a quarter of Minko's total over the
 * 100 frames. It is also the adapter's first call in each replay (records,
 * index, sweep scratch, a pair array grown to 4 M pairs), as it is a
 * program's first dSpaceCollide. Keeping the adapter warm across replays
 * instead (session 10, a /tmp build) left frame 0 within the noise: 78-94
 * ms warm against 76-88 ms cold, Minko alone and with all spaces (load
 * 6-7); its time is the pairs (10.7 M box tests, the pair loop and the
 * callback), not the cold start. demos/ode_ratios.sh turns --per-frame's
 * file into the medians, means and ratios issue 7 is judged on.
 *
 * --frames A:B measures frames A..B-1 only: ODE's spaces keep nothing from
 * call to call and skip the frames before A; Minko's runs them untimed, so
 * its state is that of the whole replay.
 *
 * For a stable figure: the measured space collides (but frame 0, Minko's
 * cold start) go through the functions space_only_ode_hash,
 * space_only_ode_sap, space_only_minko and space_only_floor, so
 *   valgrind --tool=callgrind --toggle-collect='space_only_*' \
 *     build/demos/ode_scenes --scene stress_space --reps 1 --frames A:B --poses FILE
 * gives each space's instructions (inclusive cost of its function) over the
 * B - A frames (B - 1 when A = 0). --poses FILE reads the recorded frames from
 * FILE if it exists, else records them there, so the simulation need not run
 * under valgrind. */

typedef struct pair_sink { dGeomID (*p)[2]; size_t n, cap; } pair_sink;

static void sink_cb(void *data, dGeomID a, dGeomID b)
{
    pair_sink *k = data;
    if (k->n == k->cap) {
        k->cap = k->cap ? 2 * k->cap : 65536;
        k->p = xrealloc(k->p, k->cap * sizeof *k->p);
    }
    k->p[k->n][0] = a;
    k->p[k->n][1] = b;
    k->n++;
}

/* Not static, never inlined: callgrind's --toggle-collect finds them by name. */
#if defined(__GNUC__)
#  define SPACE_ONLY_FN __attribute__((noinline))
#else
#  define SPACE_ONLY_FN
#endif
SPACE_ONLY_FN void space_only_ode_hash(dSpaceID space, pair_sink *k);
SPACE_ONLY_FN void space_only_ode_sap(dSpaceID space, pair_sink *k);
SPACE_ONLY_FN void space_only_minko(dSpaceID space, pair_sink *k);
SPACE_ONLY_FN void space_only_floor(dSpaceID space, pair_sink *k);
SPACE_ONLY_FN void space_only_ode_hash(dSpaceID space, pair_sink *k) { dSpaceCollide(space, k, sink_cb); }
SPACE_ONLY_FN void space_only_ode_sap(dSpaceID space, pair_sink *k) { dSpaceCollide(space, k, sink_cb); }
SPACE_ONLY_FN void space_only_minko(dSpaceID space, pair_sink *k) { mk_ode_space_collide(space, k, sink_cb); }

/* The floor under every space collide through ODE's API: the list walk and
 * each geom's AABB (which ODE recomputes for a geom that moved, as every
 * space has it do), and no pair. Not a space: its row says how much of the
 * others' time nothing but ODE's own per-geom work could remove. */
static void floor_collide(dSpaceID space, void *data, dNearCallback *callback)
{
    int n = dSpaceGetNumGeoms(space), i;
    dReal aabb[6];
    (void)data;
    (void)callback;
    for (i = 0; i < n; i++) dGeomGetAABB(dSpaceGetGeom(space, i), aabb);
}
SPACE_ONLY_FN void space_only_floor(dSpaceID space, pair_sink *k) { floor_collide(space, k, sink_cb); }

typedef void space_only_fn(dSpaceID space, pair_sink *k);

static const struct {
    backend be;
    space_only_fn *timed;
} SPACE_ONLY[] = {
    {{"ode.hash", SPACE_HASH, dSpaceCollide, dCollide, 0}, space_only_ode_hash},
    {{"ode.sap", SPACE_SAP, dSpaceCollide, dCollide, 0}, space_only_ode_sap},
    {{"minko", SPACE_SIMPLE, mk_ode_space_collide, dCollide, 0}, space_only_minko},
    {{"floor", SPACE_SIMPLE, floor_collide, dCollide, 0}, space_only_floor},
};
#define NSPACE_ONLY 4
#define SPACE_ONLY_MINKO 2 /* the spaces before it are ODE's, compared with it */

static dReal *rec_pose(const recording *r, int frame, int body) { return r->pose + 7 * ((size_t)frame * (size_t)r->nbodies + (size_t)body); }

static void record_frames(const scene *sc, recording *r)
{
    static const backend native = {"ode.sap", SPACE_SAP, dSpaceCollide, dCollide, 0};
    sim s;
    int f, k;
    sim_init(&s, &native, sc);
    r->nbodies = s.nbodies;
    r->frames = sc->steps;
    r->pose = xrealloc(NULL, 7 * (size_t)r->frames * (size_t)r->nbodies * sizeof(dReal));
    for (f = 0; f < r->frames; f++) {
        for (k = 0; k < s.nbodies; k++) {
            memcpy(rec_pose(r, f, k), dBodyGetPosition(s.bodies[k].body), 3 * sizeof(dReal));
            memcpy(rec_pose(r, f, k) + 3, dBodyGetQuaternion(s.bodies[k].body), 4 * sizeof(dReal));
        }
        sim_step(&s);
    }
    sim_free(&s);
}

#define POSES_MAGIC 0x4d4b4f44u /* "MKOD" */

/* 1 if `path` held a recording of this scene (read into r). */
static int load_frames(const char *path, const scene *sc, recording *r)
{
    FILE *f = fopen(path, "rb");
    uint32_t head[4];
    size_t n;
    if (!f) return 0;
    if (fread(head, sizeof head, 1, f) != 1 || head[0] != POSES_MAGIC || head[1] != (uint32_t)sc->n ||
        head[3] != (uint32_t)sc->steps) {
        fclose(f);
        fprintf(stderr, "ode_scenes: %s is not a recording of %s %s\n", path, sc->name, sc->variant);
        exit(2);
    }
    r->nbodies = (int)head[2];
    r->frames = (int)head[3];
    n = 7 * (size_t)r->frames * (size_t)r->nbodies;
    r->pose = xrealloc(NULL, n * sizeof(dReal));
    if (fread(r->pose, sizeof(dReal), n, f) != n) {
        fprintf(stderr, "ode_scenes: %s is truncated\n", path);
        exit(2);
    }
    fclose(f);
    return 1;
}

static void save_frames(const char *path, const scene *sc, const recording *r)
{
    FILE *f = fopen(path, "wb");
    uint32_t head[4] = {POSES_MAGIC, (uint32_t)sc->n, (uint32_t)r->nbodies, (uint32_t)r->frames};
    size_t n = 7 * (size_t)r->frames * (size_t)r->nbodies;
    if (!f || fwrite(head, sizeof head, 1, f) != 1 || fwrite(r->pose, sizeof(dReal), n, f) != n || fclose(f) != 0) {
        perror(path);
        exit(2);
    }
}

/* A space's pairs as sorted (low id, high id). */
static void canonical_pairs(const pair_sink *k, pair **out, size_t *cap)
{
    size_t i;
    if (*cap < k->n) {
        *cap = k->n;
        *out = xrealloc(*out, *cap * sizeof **out);
    }
    for (i = 0; i < k->n; i++) {
        uint32_t a = geom_id(k->p[i][0]), b = geom_id(k->p[i][1]);
        (*out)[i].a = a < b ? a : b;
        (*out)[i].b = a < b ? b : a;
    }
    qsort(*out, k->n, sizeof **out, cmp_pair);
}

/* Pairs of `ref` not in `got` (missing) and of `got` not in `ref` (extra), as multisets. */
static void diff_pairs(const pair *ref, size_t nref, const pair *got, size_t ngot, long long *missing, long long *extra)
{
    size_t i = 0, j = 0;
    while (i < nref || j < ngot) {
        int c = i == nref ? 1 : j == ngot ? -1 : cmp_pair(&ref[i], &got[j]);
        if (c < 0) { (*missing)++; i++; }
        else if (c > 0) { (*extra)++; j++; }
        else { i++; j++; }
    }
}

static void pose_bodies(const sim *s, const recording *r, int frame)
{
    int k;
    for (k = 0; k < s->nbodies; k++) {
        const dReal *p = rec_pose(r, frame, k);
        dBodySetPosition(s->bodies[k].body, p[0], p[1], p[2]);
        dBodySetQuaternion(s->bodies[k].body, p + 3);
    }
}

/* --backend NAME[,NAME...]: the replay runs those spaces only (a profile
 * of one space: no pair differences, no ratios). */
static int space_runs(int b)
{
    return backend_chosen(SPACE_ONLY[b].be.name);
}

/* --per-frame FILE: one JSON line per measured frame and space (its best
 * time and its pair count), to see where the mean goes. */
static void write_per_frame(FILE *pf, const scene *sc, double *const *best, long long *const *fpairs, int from, int to)
{
    int f, b;
    for (f = from; f < to; f++)
        for (b = 0; b < NSPACE_ONLY; b++)
            if (space_runs(b))
                fprintf(pf,
                    "{\"suite\":\"ode\",\"case\":\"stress_space_frame\",\"variant\":\"%s\",\"backend\":\"%s\",\"n\":1,"
                    "\"frame\":%d,\"space_ms\":%.6g,\"pairs\":%lld}\n",
                    sc->variant, SPACE_ONLY[b].be.name, f, best[b][f], fpairs[b][f]);
}

static void run_space_only(const scene *sc, int reps, int from, int to, const char *poses_path, FILE *json, FILE *pf)
{
    recording rec;
    sim sims[NSPACE_ONLY];
    pair_sink sink = {NULL, 0, 0};
    pair *got[NSPACE_ONLY] = {NULL};
    size_t gotcap[NSPACE_ONLY] = {0}, ngot[NSPACE_ONLY];
    long long *fpairs[NSPACE_ONLY];
    double *best[NSPACE_ONLY], med[NSPACE_ONLY], mean[NSPACE_ONLY], worst[NSPACE_ONLY], fastest_ode;
    int worst_at[NSPACE_ONLY];
    long long npairs[NSPACE_ONLY] = {0}, missing[NSPACE_ONLY] = {0}, extra[NSPACE_ONLY] = {0};
    int f, b, rep;
    if (!poses_path || !load_frames(poses_path, sc, &rec)) {
        record_frames(sc, &rec);
        if (poses_path) save_frames(poses_path, sc, &rec);
    }
    if (to <= 0 || to > rec.frames) to = rec.frames;
    if (from < 0 || from >= to) from = 0;
    for (b = 0; b < NSPACE_ONLY; b++) {
        sim_init(&sims[b], &SPACE_ONLY[b].be, sc);
        best[b] = xrealloc(NULL, (size_t)rec.frames * sizeof(double));
        fpairs[b] = xrealloc(NULL, (size_t)rec.frames * sizeof(long long));
        for (f = 0; f < rec.frames; f++) best[b][f] = HUGE_VAL;
    }
    for (rep = 0; rep < reps; rep++) {
        mk_ode_space_forget(sims[SPACE_ONLY_MINKO].space); /* every replay starts cold */
        for (f = 0; f < to; f++) {
            int turn;
            for (turn = 0; turn < NSPACE_ONLY; turn++) {
                double t0, t;
                b = (f + turn) % NSPACE_ONLY;
                if (!space_runs(b)) continue;
                if (f < from && b != SPACE_ONLY_MINKO) continue; /* ODE's spaces keep no state between calls */
                pose_bodies(&sims[b], &rec, f);
                sink.n = 0;
                t0 = now_ms();
                if (f == 0 || f < from)
                    SPACE_ONLY[b].be.space_collide(sims[b].space, &sink, sink_cb);
                else
                    SPACE_ONLY[b].timed(sims[b].space, &sink);
                t = now_ms() - t0;
                if (t < best[b][f]) best[b][f] = t;
                if (rep == 0 && f >= from) {
                    npairs[b] += (long long)sink.n;
                    fpairs[b][f] = (long long)sink.n;
                    canonical_pairs(&sink, &got[b], &gotcap[b]);
                    ngot[b] = sink.n;
                }
            }
            if (rep == 0 && f >= from && space_runs(SPACE_ONLY_MINKO))
                for (b = 0; b < SPACE_ONLY_MINKO; b++)
                    if (space_runs(b))
                        diff_pairs(got[b], ngot[b], got[SPACE_ONLY_MINKO], ngot[SPACE_ONLY_MINKO], &missing[b], &extra[b]);
        }
    }
    if (pf) write_per_frame(pf, sc, best, fpairs, from, to); /* before median() sorts best[] */
    for (b = 0; b < NSPACE_ONLY; b++) {
        if (!space_runs(b)) {
            med[b] = mean[b] = HUGE_VAL;
            continue;
        }
        mean[b] = 0;
        worst[b] = -1;
        worst_at[b] = from;
        for (f = from; f < to; f++) {
            mean[b] += best[b][f] / (to - from);
            if (best[b][f] > worst[b]) { worst[b] = best[b][f]; worst_at[b] = f; }
        }
        med[b] = median(best[b] + from, to - from);
    }
    fastest_ode = fmin(med[0], med[1]);
    printf("\nstress_space %s: frames %d..%d of the stress heap (%d bodies) replayed through each space; space collide alone,\n"
           "the same pair-storing callback for all; per frame the best of %d replays (ms: median, mean and max over\n"
           "frames, with the frame of the max; pair differences with Minko's set summed over frames)\n",
           sc->variant, from, to - 1, rec.nbodies, reps);
    printf("  %-10s %9s %9s %9s %5s %10s %14s %14s %10s\n", "backend", "median", "mean", "max", "at", "pairs", "not_in_minko",
           "only_minko", "vs_fastest");
    for (b = 0; b < NSPACE_ONLY; b++) {
        double ratio = fastest_ode < HUGE_VAL ? med[b] / fastest_ode : 0; /* 0: no ODE space ran */
        const char *name = SPACE_ONLY[b].be.name;
        if (!space_runs(b)) continue;
        if (b >= SPACE_ONLY_MINKO)
            printf("  %-10s %9.3f %9.3f %9.3f %5d %10.1f %14s %14s %10.2f\n", name, med[b], mean[b], worst[b], worst_at[b],
                   (double)npairs[b] / (to - from), "-", "-", ratio);
        else
            printf("  %-10s %9.3f %9.3f %9.3f %5d %10.1f %14lld %14lld %10.2f\n", name, med[b], mean[b], worst[b], worst_at[b],
                   (double)npairs[b] / (to - from), missing[b], extra[b], ratio);
        if (!json) continue;
        fprintf(json,
                "{\"suite\":\"ode\",\"case\":\"stress_space\",\"variant\":\"%s\",\"backend\":\"%s\",\"n\":%d,\"bodies\":%d,"
                "\"first_frame\":%d,\"reps\":%d,\"space_ms_per_frame\":%.6g,\"space_ms_mean\":%.6g,\"space_ms_max\":%.6g,\"max_at_frame\":%d,"
                "\"pairs_per_frame\":%.6g,\"ratio_to_fastest_ode\":%.6g",
                sc->variant, name, to - from, rec.nbodies, from, reps, med[b], mean[b], worst[b], worst_at[b],
                (double)npairs[b] / (to - from), ratio);
        if (b < SPACE_ONLY_MINKO)
            fprintf(json, ",\"pairs_not_in_minko\":%lld,\"pairs_only_in_minko\":%lld", missing[b], extra[b]);
        fprintf(json, "}\n");
        fflush(json);
    }
    for (b = 0; b < NSPACE_ONLY; b++) {
        sim_free(&sims[b]);
        free(fpairs[b]);
        free(best[b]);
        free(got[b]);
    }
    free(sink.p);
    free(rec.pose);
}

/* ---- hull-hull penetration depth against the exact reference ---- */

typedef struct depth_case {
    int a, b;
    dMatrix3 Ra, Rb;
    double pa[3], pb[3];
    double depth;       /* exact, > 0 */
    mk_lvec3 normal;    /* exact, from a towards b */
    int normal_defined;
} depth_case;

static mk_oracle_pose oracle_pose(const dMatrix3 R, const double p[3])
{
    mk_oracle_pose x;
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) x.r[i][j] = R[4 * i + j];
    x.p = lv(p[0], p[1], p[2]);
    return x;
}

/* Random poses of random pairs of the scene's hulls, kept when the exact
 * answer says they penetrate (deeply or barely). */
static int make_depth_cases(depth_case *out, int m)
{
    rng r = {0x5eed0005u};
    int k = 0;
    while (k < m) {
        depth_case *c = &out[k];
        mk_oracle_pose xa, xb;
        mk_oracle_result res;
        double d[3], l2, dist;
        int i;
        c->a = (int)(rng_unit(&r) * NHULLS);
        c->b = (int)(rng_unit(&r) * NHULLS);
        dRFromAxisAndAngle(c->Ra, rng_unit(&r) * 2 - 1, rng_unit(&r) * 2 - 1, rng_unit(&r) * 2 - 1, rng_unit(&r) * 6.3);
        dRFromAxisAndAngle(c->Rb, rng_unit(&r) * 2 - 1, rng_unit(&r) * 2 - 1, rng_unit(&r) * 2 - 1, rng_unit(&r) * 6.3);
        do {
            for (i = 0; i < 3; i++) d[i] = rng_range(&r, -1, 1);
            l2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        } while (l2 < 1e-3 || l2 > 1);
        dist = rng_range(&r, 0.2, 1.0) * (double)(hulls[c->a].exact.size + hulls[c->b].exact.size) / sqrt(l2);
        c->pa[0] = 5;
        c->pa[1] = -3;
        c->pa[2] = 2;
        for (i = 0; i < 3; i++) c->pb[i] = c->pa[i] + d[i] * dist;
        xa = oracle_pose(c->Ra, c->pa);
        xb = oracle_pose(c->Rb, c->pb);
        if (mk_oracle_query(&hulls[c->a].exact, &xa, &hulls[c->b].exact, &xb, 0, &res) != 0 || !(res.distance < -1e-9L))
            continue;
        c->depth = (double)-res.distance;
        c->normal = res.normal;
        c->normal_defined = res.normal_defined;
        k++;
    }
    return m;
}

static double percentile(const double *v, int n, double q)
{
    double *w = xrealloc(NULL, (size_t)n * sizeof *w), x;
    int i = (int)ceil(q * n) - 1;
    memcpy(w, v, (size_t)n * sizeof *w);
    qsort(w, (size_t)n, sizeof *w, cmp_double);
    x = w[i < 0 ? 0 : i];
    free(w);
    return x;
}

/* One backend over all cases: depth = deepest contact, normal = its normal
 * (ODE's points from b into a, so it is compared with minus the exact one).
 * Every case is a new pair of geoms, posed before the clock starts: the
 * adapter keeps a manifold cache per pair of geoms, and a pair moved to an
 * unrelated random pose would start from the last pose's axis (a warm query
 * may report that axis's depth, within 5 %; manifold.h), which is not what
 * the exact comparison asks. The timed repeats query each pair again at the
 * same pose. */
static dGeomID depth_geom(int k, int minko)
{
    const hull_data *h = &hulls[k];
    return (minko ? mk_ode_create_convex : dCreateConvex)(0, h->planes, (unsigned int)h->nf, h->points, (unsigned int)h->nv,
                                                          h->polygons);
}

static void run_depth_backend(const char *name, collide_fn *collide, const depth_case *cases, int m, FILE *json)
{
    int minko = collide == mk_ode_collide;
    double *err = xrealloc(NULL, (size_t)m * sizeof *err), *nerr = xrealloc(NULL, (size_t)m * sizeof *nerr);
    double best = HUGE_VAL;
    int k, rep, failures = 0;
    dGeomID (*g)[2] = xrealloc(NULL, (size_t)m * sizeof *g);
    for (k = 0; k < m; k++) {
        const depth_case *c = &cases[k];
        g[k][0] = depth_geom(c->a, minko);
        g[k][1] = depth_geom(c->b, minko);
        dGeomSetPosition(g[k][0], c->pa[0], c->pa[1], c->pa[2]);
        dGeomSetRotation(g[k][0], c->Ra);
        dGeomSetPosition(g[k][1], c->pb[0], c->pb[1], c->pb[2]);
        dGeomSetRotation(g[k][1], c->Rb);
    }
    for (rep = 0; rep < 3; rep++) {
        double t0 = now_ms();
        for (k = 0; k < m; k++) {
            const depth_case *c = &cases[k];
            dContactGeom ct[MAX_CONTACTS];
            int n = collide(g[k][0], g[k][1], MAX_CONTACTS, ct, (int)sizeof ct[0]), i, deepest = 0;
            if (rep) continue;
            for (i = 1; i < n; i++)
                if (ct[i].depth > ct[deepest].depth) deepest = i;
            if (n <= 0 || !(ct[deepest].depth > 0)) {
                failures++;
                err[k] = 1;
                nerr[k] = 180;
                continue;
            }
            err[k] = fabs(ct[deepest].depth - c->depth) / c->depth;
            nerr[k] = c->normal_defined
                          ? (double)mk_oracle_angle_deg(c->normal, -ct[deepest].normal[0], -ct[deepest].normal[1], -ct[deepest].normal[2])
                          : 0;
        }
        if (rep) {
            double t = (now_ms() - t0) * 1e6 / m;
            if (t < best) best = t;
        }
    }
    printf("  %-14s %9.0f %10.2e %10.2e %10.2e %10.2e %10.2e %8d\n", name, best, percentile(err, m, 0.5),
           percentile(err, m, 0.99), percentile(err, m, 1.0), percentile(nerr, m, 0.99), percentile(nerr, m, 1.0), failures);
    if (json)
        fprintf(json,
                "{\"suite\":\"ode\",\"case\":\"hull_depth\",\"variant\":\"penetrating\",\"backend\":\"%s\",\"n\":%d,"
                "\"ns_per_query\":%.6g,\"rel_err_p50\":%.6g,\"rel_err_p99\":%.6g,\"rel_err_max\":%.6g,"
                "\"normal_err_deg_p99\":%.6g,\"normal_err_deg_max\":%.6g,\"failures\":%d}\n",
                name, m, best, percentile(err, m, 0.5), percentile(err, m, 0.99), percentile(err, m, 1.0),
                percentile(nerr, m, 0.99), percentile(nerr, m, 1.0), failures);
    for (k = 0; k < m; k++) {
        mk_ode_geom_destroy(g[k][0]);
        mk_ode_geom_destroy(g[k][1]);
    }
    free(g);
    free(err);
    free(nerr);
}

static void run_hull_depth(int quick, FILE *json)
{
    int m = quick ? 300 : 3000;
    depth_case *cases = xrealloc(NULL, (size_t)m * sizeof *cases);
    make_depth_cases(cases, m);
    printf("\nhull_depth penetrating: %d random poses of the hull scene's hulls, depth and normal of the deepest contact\n"
           "against the exact (long double brute-force SAT) reference\n", m);
    printf("  %-14s %9s %10s %10s %10s %10s %10s %8s\n", "backend", "ns/query", "err_p50", "err_p99", "err_max", "deg_p99",
           "deg_max", "failures");
    run_depth_backend("ode.dCollide", dCollide, cases, m, json);
    {
        dGeomID a = depth_geom(0, 1), b = depth_geom(1, 1);
        if (mk_ode_supports(a, b))
            run_depth_backend("minko", mk_ode_collide, cases, m, json);
        else
            printf("  %-14s hull-hull contacts are not in this Minko build yet\n", "minko");
        mk_ode_geom_destroy(a);
        mk_ode_geom_destroy(b);
    }
    free(cases);
}

#define MAXCASES 16

static int make_cases(scene *out, int quick)
{
    static char variants[MAXCASES][32];
    static const int speeds[] = {10, 30, 100, 300, 1000};
    dSurfaceParameters stress_surf = surface(dContactBounce | dContactSoftCFM, dInfinity, 0.1, 0.1, 0.01);
    dSurfaceParameters stack_surf = surface(dContactApprox1, 0.8, 0, 0, 0);
    dSurfaceParameters wall_surf = surface(0, 0, 0, 0, 0);
    int k = 0, i;

    memset(out, 0, MAXCASES * sizeof *out);
    out[k].name = "stress"; out[k].build = build_stress; out[k].n = quick ? 1000 : 10000;
    out[k].steps = quick ? 20 : 100; out[k].dt = 0.05; out[k].iterations = 20; out[k].max_contacts = 4;
    out[k].surface = stress_surf; out[k].ground = 1; out[k].drift = DRIFT_FROM_MID;
    k++;
    out[k].name = "tower"; out[k].build = build_tower; out[k].n = 10;
    out[k].steps = quick ? 120 : 600; out[k].dt = 1.0 / 60; out[k].iterations = 20; out[k].max_contacts = 4;
    out[k].surface = stack_surf; out[k].surface_layer = 0.001; out[k].ground = 1; out[k].drift = DRIFT_FROM_START;
    k++;
    out[k].name = "pyramid"; out[k].build = build_pyramid; out[k].n = 20;
    out[k].steps = quick ? 60 : 600; out[k].dt = 1.0 / 60; out[k].iterations = 20; out[k].max_contacts = 4;
    out[k].surface = stack_surf; out[k].surface_layer = 0.001; out[k].ground = 1; out[k].drift = DRIFT_FROM_START;
    k++;
    out[k].name = "hulls"; out[k].build = build_hulls; out[k].n = NHULLS;
    out[k].steps = quick ? 120 : 600; out[k].dt = 1.0 / 60; out[k].iterations = 20; out[k].max_contacts = 4;
    out[k].surface = stack_surf; out[k].surface_layer = 0.001; out[k].ground = 1; out[k].drift = DRIFT_FROM_MID;
    k++;
    out[k].name = "mixed"; out[k].build = build_mixed; out[k].n = 80;
    out[k].steps = quick ? 60 : 600; out[k].dt = 1.0 / 60; out[k].iterations = 20; out[k].max_contacts = 4;
    out[k].surface = stack_surf; out[k].surface_layer = 0.001; out[k].ground = 1; out[k].drift = DRIFT_FROM_MID;
    k++;
    for (i = 0; i < (int)(sizeof speeds / sizeof speeds[0]); i++) {
        out[k].name = "wall"; out[k].build = build_wall; out[k].n = speeds[i];
        out[k].steps = 100; out[k].dt = 0.01; out[k].iterations = 20; out[k].max_contacts = 4;
        out[k].surface = wall_surf; out[k].wall_x = 0.1;
        k++;
    }
    for (i = 0; i < k; i++) {
        if (out[i].build == build_wall)
            snprintf(variants[i], sizeof variants[i], "v=%d", out[i].n);
        else
            snprintf(variants[i], sizeof variants[i], "n=%d", out[i].n);
        out[i].variant = variants[i];
    }
    return k;
}

int main(int argc, char **argv)
{
    scene cases[MAXCASES];
    const char *json_path = NULL, *only = NULL, *poses_path = NULL, *per_frame_path = NULL;
    FILE *json = NULL, *per_frame = NULL;
    int quick = 0, reps = 3, from = 0, to = 0, ncases, i;

    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--quick"))
            quick = 1;
        else if (!strcmp(argv[i], "--json") && i + 1 < argc)
            json_path = argv[++i];
        else if (!strcmp(argv[i], "--scene") && i + 1 < argc)
            only = argv[++i];
        else if (!strcmp(argv[i], "--reps") && i + 1 < argc && atoi(argv[i + 1]) > 0)
            reps = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--poses") && i + 1 < argc)
            poses_path = argv[++i];
        else if (!strcmp(argv[i], "--per-frame") && i + 1 < argc)
            per_frame_path = argv[++i];
        else if (!strcmp(argv[i], "--frames") && i + 1 < argc && sscanf(argv[i + 1], "%d:%d", &from, &to) == 2)
            i++;
        else if (!strcmp(argv[i], "--backend") && i + 1 < argc)
            only_backend = argv[++i];
        else if (!strcmp(argv[i], "--steps") && i + 1 < argc && atoi(argv[i + 1]) > 0)
            steps_override = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--start") && i + 1 < argc && atoi(argv[i + 1]) >= 0)
            start_frame = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--compare"))
            compare_contacts = 1;
        else if (!strcmp(argv[i], "--save-state") && i + 1 < argc)
            save_state_path = argv[++i];
        else if (!strcmp(argv[i], "--load-state") && i + 1 < argc)
            load_state_path = argv[++i];
        else {
            fprintf(stderr,
                    "usage: %s [--quick] [--json FILE] [--scene stress|stress_space|tower|pyramid|hulls|mixed|wall|hull_depth]\n"
                    "       [--reps N] [--poses FILE] [--frames A:B] [--per-frame FILE]   (stress_space: replays per\n"
                    "       frame; recorded frames, read or written; the frames A..B-1 measured; each frame's time and\n"
                    "       pairs per space, or each simulated step's times per backend, as JSON Lines)\n"
                    "       [--backend NAME[,NAME...]] [--steps N] [--start F]   (those backends only; N steps per scene; the stress\n"
                    "       scene from frame F of --poses FILE, at rest)\n"
                    "       [--compare]   (Minko's contacts against dCollide's on the same poses, per class pair)\n"
                    "       [--save-state FILE] [--load-state FILE]   (with --scene: the first backend's world after the\n"
                    "       run; every world starts from it and runs on from its step)\n",
                    argv[0]);
            return 2;
        }
    }
    if (json_path && !(json = fopen(json_path, "w"))) {
        perror(json_path);
        return 2;
    }
    if (per_frame_path && !(per_frame = fopen(per_frame_path, "w"))) {
        perror(per_frame_path);
        return 2;
    }
    dInitODE2(0);
    printf("ode_scenes: ODE %s scenes, native spaces and colliders against Minko's%s\n",
           dCheckConfiguration("ODE_double_precision") ? "double" : "single", quick ? " (quick)" : "");
    {
        rng r = {0x5eed0006u};
        for (i = 0; i < NHULLS; i++) hull_make(&hulls[i], &r);
    }
    ncases = make_cases(cases, quick);
    if ((save_state_path || load_state_path) &&
        (!only || !strcmp(only, "stress_space") || !strcmp(only, "hull_depth") || start_frame > 0)) {
        fprintf(stderr, "ode_scenes: --save-state and --load-state need --scene with a simulated scene, and no --start\n");
        return 2;
    }
    if (start_frame > 0) {
        for (i = 0; i < ncases && cases[i].build != build_stress; i++) {}
        if (!poses_path || !load_frames(poses_path, &cases[i], &start_rec) || start_frame >= start_rec.frames) {
            fprintf(stderr, "ode_scenes: --start needs --poses FILE with a recording of the stress scene past frame %d\n",
                    start_frame);
            return 2;
        }
    }
    for (i = 0; i < ncases; i++) {
        if (!only || !strcmp(only, cases[i].name)) run_case(&cases[i], json, per_frame);
        if (cases[i].build == build_stress && (!only || !strcmp(only, "stress_space")))
            run_space_only(&cases[i], reps, from, to, poses_path, json, per_frame);
    }
    if (!only || !strcmp(only, "hull_depth")) run_hull_depth(quick, json);
    for (i = 0; i < NHULLS; i++) hull_free(&hulls[i]);
    free(start_rec.pose);
    mk_ode_close();
    if (json) fclose(json);
    if (per_frame) fclose(per_frame);
    return 0;
}

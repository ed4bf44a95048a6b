/* ode_collide.c: Minko's manifolds as ODE contacts (minko_ode.h).
 *
 * One query per pair: mk_collide() returns the whole manifold (up to four
 * points, e.g. a box resting on a face gets its four corners), where ODE's
 * libccd colliders return one MPR point per call. The points are converted to
 * ODE's conventions (adapters.md B.1): normal from o2 into o1 (Minko's points
 * from A to B, so it is negated), depth >= 0 with separated points dropped
 * (ODE's contact joint would treat them as touching), pos the midpoint of the
 * two witness points, g1/g2 the geoms as passed, side1/side2 = -1 like ODE's
 * primitive colliders. Geometry is taken relative to `origin` (the first
 * placeable geom's position), subtracted in dReal, so a float build of Minko
 * loses nothing to large world coordinates.
 *
 * Which class pairs Minko handles is asked of the linked library, once: a
 * build may leave modules out (MK_WITHOUT) and pairs arrive module by module,
 * so the adapter probes mk_collide on a penetrating pose of each class pair
 * (both orders) and installs overrides only where it answers with contacts.
 *
 * Convex geoms: ODE keeps the caller's arrays but offers no getter, so the
 * wrappers record each convex geom's Minko hull (built once by quickhull from
 * its points) in a side table keyed by dGeomID.
 *
 * Each pair keeps its mk_manifold_cache from call to call. It is not an
 * optimisation: a cold mk_collide answers with the exact minimum axis, which
 * for two boxes stacked 1e-4 rad out of parallel is an edge pair and one
 * point, and a 10-box tower fed such contacts sinks into itself and falls
 * (measured in ode_scenes: 23.6 contacts per step instead of 40, the top box
 * 12.9 m from where it started); with the cache the pair keeps clipping
 * against last frame's face and gets its four points. mk_collide wants the
 * shapes in the same order every time, and ODE passes a pair either way
 * round (spaces reorder, overrides of a class with itself are called
 * swapped), so Minko always sees the pair in address order and the result is
 * turned round when needed. ODE never says that a pair ended: records not
 * used during about the last table's worth of calls are recycled before the
 * table grows.
 *
 * Faces over edges is mk_collide's own rule on warm calls (manifold.h: an
 * edge pair must beat the face by the hysteresis band), as ODE's dBoxBox
 * and Box2D favour faces. Before it, the cache kept whichever kind of axis
 * won last, so two boxes that once came out edge on edge (turned 3e-3 rad,
 * a face nearly as good) stayed on one point for good: in the 210-box
 * pyramid 358 of about 395 box pairs ended with one point and the pyramid
 * shook itself apart (kinetic energy 10.7 J at the end against ODE's 0.07),
 * which this adapter worked around by querying cold after a lone
 * edge-on-edge point. With the rule in mk_collide that workaround made no
 * difference on the tower and hulls scenes and the pyramid ended calmer
 * without it (ode_scenes --scene pyramid: 0.17 J against 0.28 J), so it
 * is gone.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "minko/manifold.h"
#include "ode_internal.h"
#include "ode_map.h"

/* ODE's collision.h flag "any contact will do", and its count mask. */
#define ODE_CONTACTS_UNIMPORTANT 0x80000000u
#define ODE_NUMC_MASK 0xffff

/* ---- geoms as Minko shapes ---- */

static const int classes[] = {dSphereClass, dBoxClass, dCapsuleClass, dCylinderClass, dConvexClass, dPlaneClass};
#define NCLASSES ((int)(sizeof classes / sizeof classes[0]))

static int class_index(int c)
{
    int i;
    for (i = 0; i < NCLASSES; i++)
        if (classes[i] == c) return i;
    return -1;
}

/* A representative shape of class index i (unit sizes); `hull` serves the convex class. */
static mk_status sample_shape(int i, const mk_hull *hull, mk_shape *s)
{
    switch (classes[i]) {
    case dSphereClass: return mk_shape_sphere(MK_REAL(0.5), s);
    case dBoxClass: return mk_shape_box(mk_v3(MK_REAL(0.5), MK_REAL(0.4), MK_REAL(0.3)), 0, s);
    case dCapsuleClass: return mk_shape_capsule(MK_REAL(0.3), MK_REAL(0.4), s);
    case dCylinderClass: return mk_shape_cylinder(MK_REAL(0.4), MK_REAL(0.3), 0, s);
    case dConvexClass: return hull ? mk_shape_hull(hull, 0, s) : MK_ERR_UNSUPPORTED;
    default: return mk_shape_plane(mk_v3(0, 0, 1), 0, s);
    }
}

/* supported[i][j]: mk_collide answers for classes[i] against classes[j]. */
static int supported[NCLASSES][NCLASSES];
static int probed;

static void probe(void)
{
    static const mk_vec3 octahedron[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    mk_hull *hull = NULL;
    int i, j;
    if (mk_hull_create(octahedron, 6, NULL, &hull) != MK_OK) hull = NULL;
    for (i = 0; i < NCLASSES; i++) {
        for (j = 0; j < NCLASSES; j++) {
            mk_shape a, b;
            mk_manifold m;
            mk_transform xa = mk_transform_identity(), xb = mk_transform_make(
                                                           mk_v3(MK_REAL(0.1), MK_REAL(0.05), MK_REAL(0.2)),
                                                           mk_quat_from_axis_angle(mk_v3(1, 2, 3), MK_REAL(0.3)));
            /* every sample pair overlaps at this pose: no contact means no support */
            supported[i][j] = sample_shape(i, hull, &a) == MK_OK && sample_shape(j, hull, &b) == MK_OK &&
                              mk_collide(&a, xa, &b, xb, 0, NULL, &m) == MK_OK && m.count > 0;
        }
    }
    mk_hull_destroy(hull);
    probed = 1;
}

/* ---- convex side table ---- */

typedef struct convex_rec {
    dGeomID geom; /* NULL: free record */
    mk_hull *hull;
} convex_rec;

static mk_ode_map convex_index; /* dGeomID -> record */
static convex_rec *convex;
static int nconvex, capconvex;

static void drop_convex(dGeomID g)
{
    long i = mk_ode_map_get(&convex_index, g, NULL);
    if (i < 0) return;
    mk_hull_destroy(convex[i].hull);
    convex[i].hull = NULL;
    convex[i].geom = NULL;
    mk_ode_map_remove(&convex_index, g, NULL);
}

/* Builds the hull once, from the points ODE collides with (the planes and
 * polygons describe the same solid; quickhull recovers them). */
static mk_status record_convex(dGeomID g, const dReal *points, unsigned int pointcount)
{
    mk_vec3 *pts;
    mk_hull *hull = NULL;
    mk_status s;
    unsigned int i;
    int slot;
    if (!g || !points) return MK_ERR_NULL;
    if (pointcount > MK_HULL_MAX_POINTS) return MK_ERR_CAPACITY;
    pts = malloc((pointcount ? pointcount : 1) * sizeof *pts);
    if (!pts) return MK_ERR_OUT_OF_MEMORY;
    for (i = 0; i < pointcount; i++)
        pts[i] = mk_v3((mk_real)points[3 * i], (mk_real)points[3 * i + 1], (mk_real)points[3 * i + 2]);
    s = mk_hull_create(pts, (int)pointcount, NULL, &hull);
    free(pts);
    if (s != MK_OK) return s;
    drop_convex(g);
    for (slot = 0; slot < nconvex && convex[slot].geom; slot++) continue;
    if (slot == nconvex && nconvex == capconvex) {
        int cap = capconvex ? 2 * capconvex : 16;
        convex_rec *c = realloc(convex, (size_t)cap * sizeof *c);
        if (!c) {
            mk_hull_destroy(hull);
            return MK_ERR_OUT_OF_MEMORY;
        }
        convex = c;
        capconvex = cap;
    }
    if (mk_ode_map_put(&convex_index, g, NULL, (uint32_t)slot) != 0) {
        mk_hull_destroy(hull);
        return MK_ERR_OUT_OF_MEMORY;
    }
    if (slot == nconvex) nconvex++;
    convex[slot].geom = g;
    convex[slot].hull = hull;
    return MK_OK;
}

dGeomID mk_ode_create_convex(dSpaceID space, const dReal *planes, unsigned int planecount, const dReal *points,
                             unsigned int pointcount, const unsigned int *polygons)
{
    dGeomID g = dCreateConvex(space, planes, planecount, points, pointcount, polygons);
    mk_status s = record_convex(g, points, pointcount);
    if (s != MK_OK) { /* the geom exists; Minko just does not know its hull */
        mk_ode_stats_.errors++;
        mk_ode_stats_.last_error = s;
    }
    return g;
}

mk_status mk_ode_geom_set_convex(dGeomID g, const dReal *planes, unsigned int planecount, const dReal *points,
                                 unsigned int pointcount, const unsigned int *polygons)
{
    if (!g || !points) return MK_ERR_NULL;
    if (dGeomGetClass(g) != dConvexClass) return MK_ERR_BAD_SHAPE;
    dGeomSetConvex(g, planes, planecount, points, pointcount, polygons);
    drop_convex(g); /* a failed rebuild must not leave the old hull in use */
    return record_convex(g, points, pointcount);
}

void mk_ode_geom_destroy(dGeomID g)
{
    if (!g) return;
    drop_convex(g);
    if (dGeomIsSpace(g)) mk_ode_space_forget((dSpaceID)g);
    dGeomDestroy(g);
}

/* The recorded hull of a convex geom, or NULL. A record whose geom address
 * was reused, or whose data was replaced with dGeomSetConvex behind the
 * adapter's back, is caught by comparing the hull's world AABB with ODE's
 * (both are exact over the same extreme points). */
static const mk_hull *hull_of(dGeomID g)
{
    long i = mk_ode_map_get(&convex_index, g, NULL);
    const mk_hull *h;
    const dReal *p, *R;
    dReal box[6], size = 0, tol;
    int v, k;
    if (i < 0) return NULL;
    h = convex[i].hull;
    p = dGeomGetPosition(g);
    R = dGeomGetRotation(g);
    dGeomGetAABB(g, box);
    for (k = 0; k < 3; k++) {
        dReal lo = HUGE_VAL, hi = -HUGE_VAL;
        for (v = 0; v < h->vertex_count; v++) {
            const mk_vec3 *q = &h->vertices[v];
            dReal w = R[4 * k] * q->x + R[4 * k + 1] * q->y + R[4 * k + 2] * q->z;
            lo = w < lo ? w : lo;
            hi = w > hi ? w : hi;
        }
        box[2 * k] -= p[k] + lo;
        box[2 * k + 1] -= p[k] + hi;
        size = hi - lo > size ? hi - lo : size;
    }
    tol = (dReal)(64 * MK_REAL_EPSILON) * (size + dFabs(p[0]) + dFabs(p[1]) + dFabs(p[2]));
    for (k = 0; k < 6; k++)
        if (!(dFabs(box[k]) <= tol)) return NULL;
    return h;
}

/* ---- per-pair manifold caches ---- */

typedef struct pair_rec {
    dGeomID lo, hi;                   /* lo == NULL: free record */
    int class_lo, class_hi;
    const mk_hull *hull_lo, *hull_hi; /* a convex geom's hull: a new one voids the cache */
    uint64_t last;                    /* `ticks` when last used */
    int next_free;                    /* free records form a list */
    mk_manifold_cache cache;
} pair_rec;

static mk_ode_map pair_index; /* (lo, hi) -> record */
static pair_rec *pair_recs;
static int npair_recs, cappair_recs, live_pairs, free_pairs = -1;
static uint64_t ticks; /* cached Minko narrowphase calls so far */

/* Frees the records idle for longer than the table is large, in calls: with
 * n live pairs colliding every frame, a pair idle for n calls missed a frame.
 * Returns how many it freed. */
static int recycle_pairs(void)
{
    int i, freed = 0;
    for (i = 0; i < npair_recs; i++) {
        pair_rec *r = &pair_recs[i];
        if (r->lo && r->last + (uint64_t)live_pairs < ticks) {
            mk_ode_map_remove(&pair_index, r->lo, r->hi);
            r->lo = NULL;
            r->next_free = free_pairs;
            free_pairs = i;
            live_pairs--;
            freed++;
        }
    }
    return freed;
}

/* A free record: from the free list, else the unused tail, else recycled;
 * the table doubles unless recycling freed more than a quarter of it, so the
 * O(n) recycling scan costs O(1) per new pair, amortised. */
static int new_pair_rec(void)
{
    int i;
    if (free_pairs < 0 && npair_recs == cappair_recs && 4 * recycle_pairs() <= cappair_recs) {
        int cap = cappair_recs ? 2 * cappair_recs : 64;
        pair_rec *p = realloc(pair_recs, (size_t)cap * sizeof *p);
        if (!p && free_pairs < 0) return -1;
        if (p) {
            pair_recs = p;
            cappair_recs = cap;
        }
    }
    if (free_pairs >= 0) {
        i = free_pairs;
        free_pairs = pair_recs[i].next_free;
        return i;
    }
    return npair_recs < cappair_recs ? npair_recs++ : -1;
}

static void release_pair_rec(int i)
{
    pair_recs[i].lo = NULL;
    pair_recs[i].next_free = free_pairs;
    free_pairs = i;
}

/* Whether the pair's cache can carry anything (manifold.h): an axis kind or
 * a reference face needs faces on both shapes, a GJK simplex a pair without
 * a closed form; planes, and spheres or capsules against spheres, capsules
 * or boxes, have neither, so they skip the lookup (the stress scene's 60 000
 * sphere pairs a step). */
static int cache_useful(const mk_shape *a, const mk_shape *b)
{
    int round_a = a->type == MK_SHAPE_SPHERE || a->type == MK_SHAPE_CAPSULE;
    int round_b = b->type == MK_SHAPE_SPHERE || b->type == MK_SHAPE_CAPSULE;
    if (a->type == MK_SHAPE_PLANE || b->type == MK_SHAPE_PLANE) return 0;
    if (round_a) return !(round_b || b->type == MK_SHAPE_BOX);
    return !round_b || a->type != MK_SHAPE_BOX;
}

/* The cache of the pair (lo, hi), zeroed when either geom changed class or
 * hull (an address reused by another geom); NULL (a cold query) when it
 * would carry nothing, or memory runs out. */
static mk_manifold_cache *pair_cache(dGeomID lo, dGeomID hi, const mk_shape *a, const mk_shape *b)
{
    const mk_hull *ha = a->type == MK_SHAPE_HULL ? a->u.hull : NULL, *hb = b->type == MK_SHAPE_HULL ? b->u.hull : NULL;
    long i;
    pair_rec *r;
    if (!cache_useful(a, b)) return NULL;
    i = mk_ode_map_get(&pair_index, lo, hi);
    ticks++;
    if (i < 0) {
        i = new_pair_rec();
        if (i < 0) return NULL;
        if (mk_ode_map_put(&pair_index, lo, hi, (uint32_t)i) != 0) {
            release_pair_rec((int)i);
            return NULL;
        }
        r = &pair_recs[i];
        r->lo = lo;
        r->hi = hi;
        r->class_lo = -1;
        live_pairs++;
    }
    r = &pair_recs[i];
    if (r->class_lo != dGeomGetClass(lo) || r->class_hi != dGeomGetClass(hi) || r->hull_lo != ha || r->hull_hi != hb) {
        memset(&r->cache, 0, sizeof r->cache);
        r->class_lo = dGeomGetClass(lo);
        r->class_hi = dGeomGetClass(hi);
        r->hull_lo = ha;
        r->hull_hi = hb;
    }
    r->last = ticks;
    return &r->cache;
}

void mk_ode_collide_free_all(void)
{
    int i;
    for (i = 0; i < nconvex; i++)
        if (convex[i].geom) mk_hull_destroy(convex[i].hull);
    free(convex);
    convex = NULL;
    nconvex = capconvex = 0;
    mk_ode_map_free(&convex_index);
    free(pair_recs);
    pair_recs = NULL;
    npair_recs = cappair_recs = live_pairs = 0;
    free_pairs = -1;
    mk_ode_map_free(&pair_index);
}

static int pair_supported(int c1, int c2)
{
    int i = class_index(c1), j = class_index(c2);
    if (!probed) probe();
    return i >= 0 && j >= 0 && supported[i][j] && supported[j][i];
}

int mk_ode_supports(dGeomID o1, dGeomID o2)
{
    if (!o1 || !o2 || !pair_supported(dGeomGetClass(o1), dGeomGetClass(o2))) return 0;
    if (dGeomGetClass(o1) == dConvexClass && mk_ode_map_get(&convex_index, o1, NULL) < 0) return 0;
    return dGeomGetClass(o2) != dConvexClass || mk_ode_map_get(&convex_index, o2, NULL) >= 0;
}

const dReal *mk_ode_origin_(dGeomID o1, dGeomID o2)
{
    static const dReal zero[3] = {0, 0, 0};
    return dGeomGetClass(o1) != dPlaneClass ? dGeomGetPosition(o1) : dGeomGetClass(o2) != dPlaneClass ? dGeomGetPosition(o2) : zero;
}

mk_status mk_ode_shape_of_(dGeomID g, const dReal *origin, mk_shape *shape, mk_transform *xf)
{
    const mk_hull *h;
    dReal r, len;
    dVector3 l;
    dVector4 p;
    dQuaternion q;
    const dReal *pos;
    mk_status s;
    switch (dGeomGetClass(g)) {
    case dPlaneClass: /* ax + by + cz = d, solid below; ODE keeps (a, b, c) unit */
        dGeomPlaneGetParams(g, p);
        *xf = mk_transform_identity();
        return mk_shape_plane(mk_v3((mk_real)p[0], (mk_real)p[1], (mk_real)p[2]),
                              (mk_real)(p[3] - (p[0] * origin[0] + p[1] * origin[1] + p[2] * origin[2])), shape);
    case dSphereClass:
        s = mk_shape_sphere((mk_real)dGeomSphereGetRadius(g), shape);
        break;
    case dBoxClass: /* ODE: full side lengths */
        dGeomBoxGetLengths(g, l);
        s = mk_shape_box(mk_v3((mk_real)(l[0] / 2), (mk_real)(l[1] / 2), (mk_real)(l[2] / 2)), 0, shape);
        break;
    case dCapsuleClass: /* length excludes the caps; a zero-length capsule is a sphere */
        dGeomCapsuleGetParams(g, &r, &len);
        s = len > 0 ? mk_shape_capsule((mk_real)r, (mk_real)(len / 2), shape) : mk_shape_sphere((mk_real)r, shape);
        break;
    case dCylinderClass:
        dGeomCylinderGetParams(g, &r, &len);
        s = mk_shape_cylinder((mk_real)r, (mk_real)(len / 2), 0, shape);
        break;
    case dConvexClass:
        h = hull_of(g);
        if (!h) return MK_ERR_UNSUPPORTED;
        s = mk_shape_hull(h, 0, shape);
        break;
    default:
        return MK_ERR_UNSUPPORTED;
    }
    if (s != MK_OK) return s;
    pos = dGeomGetPosition(g);
    dGeomGetQuaternion(g, q); /* (w, x, y, z) */
    *xf = mk_transform_make(mk_v3((mk_real)(pos[0] - origin[0]), (mk_real)(pos[1] - origin[1]),
                                  (mk_real)(pos[2] - origin[2])),
                            mk_quat_normalize(mk_quat_make((mk_real)q[1], (mk_real)q[2], (mk_real)q[3], (mk_real)q[0])));
    return MK_OK;
}

/* ---- the collider ---- */

static dContactGeom *contact_at(dContactGeom *c, int i, int skip)
{
    return (dContactGeom *)((char *)c + (size_t)i * (size_t)skip);
}

/* Order in which manifold points are written: the deepest first, then each
 * time the point farthest from those already chosen, so a caller who asks
 * for fewer points gets the deepest and the widest support. Separated points
 * are left out. Returns how many. */
static int choose_points(const mk_manifold *m, int maxc, int *order)
{
    int chosen[MK_MANIFOLD_MAX_POINTS] = {0}, n = 0, i, k;
    int deepest = -1;
    for (i = 0; i < m->count; i++)
        if (m->points[i].depth >= 0 && (deepest < 0 || m->points[i].depth > m->points[deepest].depth)) deepest = i;
    if (deepest < 0) return 0;
    order[n++] = deepest;
    chosen[deepest] = 1;
    while (n < maxc) {
        int best = -1;
        mk_real best_d = -1;
        for (i = 0; i < m->count; i++) {
            mk_real d = MK_REAL_MAX;
            if (chosen[i] || m->points[i].depth < 0) continue;
            for (k = 0; k < n; k++) d = mk_min(d, mk_v3_dist(m->points[i].point_a, m->points[order[k]].point_a));
            if (d > best_d) {
                best_d = d;
                best = i;
            }
        }
        if (best < 0) break;
        order[n++] = best;
        chosen[best] = 1;
    }
    return n;
}

/* Minko for a supported pair; -1 when Minko could not answer (the caller
 * decides: fall back to dCollide, or report nothing). */
static int minko_collide(dGeomID o1, dGeomID o2, int flags, dContactGeom *contact, int skip)
{
    int maxc = flags & ODE_NUMC_MASK, order[MK_MANIFOLD_MAX_POINTS], n, i;
    int swapped = (uintptr_t)o1 > (uintptr_t)o2; /* Minko sees (lo, hi) */
    dGeomID lo = swapped ? o2 : o1, hi = swapped ? o1 : o2;
    const dReal *origin = mk_ode_origin_(lo, hi);
    dReal sign = swapped ? 1 : -1; /* Minko's normal points from lo to hi; ODE's from o2 into o1 */
    mk_shape a, b;
    mk_transform xa, xb;
    mk_manifold m;
    mk_manifold_cache *cache = NULL;
    mk_status s = mk_ode_shape_of_(lo, origin, &a, &xa);
    if (s == MK_OK) s = mk_ode_shape_of_(hi, origin, &b, &xb);
    if (s == MK_OK) {
        cache = pair_cache(lo, hi, &a, &b);
        s = mk_collide(&a, xa, &b, xb, 0, cache, &m);
    }
    if (s != MK_OK) {
        mk_ode_stats_.errors++;
        mk_ode_stats_.last_error = s;
        return -1;
    }
    mk_ode_stats_.collide_calls++;
    if ((unsigned int)flags & ODE_CONTACTS_UNIMPORTANT) maxc = 1;
    n = choose_points(&m, maxc < MK_MANIFOLD_MAX_POINTS ? maxc : MK_MANIFOLD_MAX_POINTS, order);
    for (i = 0; i < n; i++) {
        const mk_contact_point *p = &m.points[order[i]];
        dContactGeom *c = contact_at(contact, i, skip);
        mk_vec3 mid = mk_v3_lerp(p->point_a, p->point_b, MK_REAL(0.5));
        c->pos[0] = origin[0] + (dReal)mid.x;
        c->pos[1] = origin[1] + (dReal)mid.y;
        c->pos[2] = origin[2] + (dReal)mid.z;
        c->pos[3] = 0;
        c->normal[0] = sign * (dReal)m.normal.x;
        c->normal[1] = sign * (dReal)m.normal.y;
        c->normal[2] = sign * (dReal)m.normal.z;
        c->normal[3] = 0;
        c->depth = (dReal)p->depth;
        c->g1 = o1;
        c->g2 = o2;
        c->side1 = -1;
        c->side2 = -1;
    }
    mk_ode_stats_.contacts += n;
    return n;
}

/* dCollide's own early outs, which a direct caller of mk_ode_collide skips;
 * also a stride too small to hold a dContactGeom. */
static int trivially_none(dGeomID o1, dGeomID o2, int flags, dContactGeom *contact, int skip)
{
    dBodyID b1, b2;
    if (!o1 || !o2 || !contact || (flags & ODE_NUMC_MASK) < 1 || skip < (int)sizeof(dContactGeom)) return 1;
    if (o1 == o2) return 1;
    b1 = dGeomGetBody(o1);
    b2 = dGeomGetBody(o2);
    return b1 && b1 == b2;
}

/* A plane and a geom whose AABBs do not meet cannot touch (ODE's AABBs
 * contain their geoms, and only points at depth >= 0 are reported). ODE's
 * dSweepAndPruneSpace reports every geom against every plane without testing
 * their AABBs (the stress heap: 8 600 such pairs a step), and answering one
 * through mk_collide costs 20 times dCollide's sphere-plane test. Other
 * pairs come from a broadphase that tested their AABBs already. */
static int apart_from_plane(dGeomID o1, dGeomID o2)
{
    dReal a[6], b[6];
    if (dGeomGetClass(o1) != dPlaneClass && dGeomGetClass(o2) != dPlaneClass) return 0;
    dGeomGetAABB(o1, a);
    dGeomGetAABB(o2, b);
    return a[0] > b[1] || a[1] < b[0] || a[2] > b[3] || a[3] < b[2] || a[4] > b[5] || a[5] < b[4];
}

/* Minko's contacts for the pair, or -1 when Minko does not handle it. */
static int try_minko(dGeomID o1, dGeomID o2, int flags, dContactGeom *contact, int skip)
{
    if (trivially_none(o1, o2, flags, contact, skip)) return 0;
    if (!mk_ode_supports(o1, o2)) return -1;
    if (apart_from_plane(o1, o2)) {
        mk_ode_stats_.collide_calls++;
        return 0;
    }
    return minko_collide(o1, o2, flags, contact, skip);
}

int mk_ode_collide(dGeomID o1, dGeomID o2, int flags, dContactGeom *contact, int skip)
{
    int n = try_minko(o1, o2, flags, contact, skip);
    if (n >= 0) return n;
    mk_ode_stats_.fallbacks++;
    return dCollide(o1, o2, flags, contact, skip);
}

int mk_ode_collider(dGeomID o1, dGeomID o2, int flags, dContactGeom *contact, int skip)
{
    int n = try_minko(o1, o2, flags, contact, skip);
    if (n >= 0) return n;
    mk_ode_stats_.unsupported++;
    return 0;
}

/* ---- installation and selection ---- */

int mk_ode_install_colliders(void)
{
    int i, j, n = 0;
    if (!probed) probe();
    /* dSetColliderOverride(i, j) also fills [j][i] (reversed), so one call per unordered pair */
    for (i = 0; i < NCLASSES; i++)
        for (j = i; j < NCLASSES; j++)
            if (pair_supported(classes[i], classes[j])) {
                dSetColliderOverride(classes[i], classes[j], mk_ode_collider);
                n++;
            }
    return n;
}

mk_status mk_ode_init(unsigned int flags)
{
    if (!dInitODE2(flags)) return MK_ERR_UNSUPPORTED;
    mk_ode_install_colliders();
    return MK_OK;
}

mk_ode_collision mk_ode_select(int minko_broadphase, int minko_narrowphase)
{
    mk_ode_collision c;
    c.space_collide = minko_broadphase ? mk_ode_space_collide : dSpaceCollide;
    c.space_collide2 = minko_broadphase ? mk_ode_space_collide2 : dSpaceCollide2;
    c.collide = minko_narrowphase ? mk_ode_collide : dCollide;
    return c;
}

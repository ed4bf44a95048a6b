/* minko_ode.h: Minko behind ODE's dSpaceCollide and dCollide (libminko_ode).
 *
 * Contract. The broadphase entry points have exactly the signatures of
 * dSpaceCollide and dSpaceCollide2 and report exactly the pairs ODE's own
 * spaces must report (ODE's collideAABBs filter: geoms disabled or of zero
 * size skipped, same non-null body skipped, category/collide bits OR-ed both
 * ways, closed AABB overlap tested on ODE's own dReal AABBs; sub-spaces
 * passed to the callback as geoms; dSpaceCollide2's space/geom/sublevel
 * rules and argument order), each pair once, in a deterministic order:
 * the same calls give the same sequence, and within a pair the geom first
 * seen in that space comes first (for geoms that were in the space at the
 * first call, the space's list order then, which in ODE puts the newest
 * geom first; ODE's own spaces promise no order). Per
 * space, persistent records keyed by dGeomID and a Minko broadphase (its
 * sweep's plan and last order) are brought up to date from the space's
 * geoms on every call, so geoms may be created, moved,
 * disabled and destroyed freely between calls, and a destroyed geom's
 * address reused by a new geom is harmless. The space may be of any kind; a
 * dSimpleSpace is the cheapest container (the others do upkeep of their
 * own).
 *
 * The narrowphase entry points follow ODE's dColliderFn contract: at most
 * (flags & 0xffff) contacts (one with CONTACTS_UNIMPORTANT), written `skip`
 * bytes apart, normal pointing from o2 into o1, depth >= 0 (separated points
 * are dropped: ODE's contact joint would hold them as touching), g1 = o1,
 * g2 = o2, side1 = side2 = -1, pos midway between the two surfaces; the
 * whole manifold (up to 4 points), deepest point first, then the points that
 * widen the support most. Each pair of geoms keeps Minko's manifold cache
 * from call to call (either argument order), so a resting box keeps its face
 * and its four points when it tilts a little (manifold.h: a warm query may
 * report the kept face's depth, within its hysteresis; a lone edge-on-edge
 * point is not kept, so faces win ties as in ODE's dBoxBox); a new pair is
 * cold and exact. A pair whose two addresses were freed by dGeomDestroy and
 * reused by new geoms of the same classes inherits that hint, which costs
 * at most the hysteresis. One record per pair seen; records idle for longer
 * than there are live pairs, in calls, are reused. Classes: sphere, box, capsule, cylinder, convex and
 * plane, for the pairs the linked Minko build answers (asked once at run
 * time: a build may leave modules out); mk_ode_supports() tells. ODE keeps
 * no getter for a convex geom's data, so convex geoms are Minko's only when
 * made through mk_ode_create_convex / mk_ode_geom_set_convex, which build
 * the Minko hull once (a record that no longer matches the geom, e.g. after
 * a plain dGeomSetConvex or an address reused by a new convex, is detected
 * and the pair goes to dCollide). mk_ode_collide
 * hands every other pair to dCollide, so a near callback can choose per pair
 * with no global state; mk_ode_install_colliders makes unmodified code use
 * Minko through dSetColliderOverride, which ODE forgets on every
 * dCloseODE/dInitODE2 (mk_ode_init re-installs them).
 *
 * ODE is double precision here. In a float build of Minko the broadphase
 * works on the dReal AABBs rounded outwards and the final test is ODE's, in
 * dReal, so the reported pairs are the same; contacts are computed relative
 * to the first geom's position, subtracted in dReal, so large world
 * coordinates cost no precision. Adapter state is
 * global and not thread-safe, like ODE's collider table. As with ODE's own
 * spaces, the near callback must not add, remove or destroy geoms of the
 * space being collided; it may collide other spaces (nested spaces), but a
 * call on the space being collided is refused (counted in errors, no pair
 * reported), since mk_ode_space_collide calls back straight from its pair
 * loop, as ODE's spaces do.
 *
 * Complexity: mk_ode_space_collide is O(n) to read the n geoms' AABBs plus
 * Minko's set-only sweep of them (mk_bp_sweep_boxes: one sort of n keys, O(n)
 * when the scene is coherent, plus the boxes each box meets in its rows)
 * plus O(p) for p reported pairs; ODE's dHashSpace rebuilds its grid and an
 * n*n bit matrix on every call. mk_ode_space_collide2 against a space reads
 * its AABBs likewise and then, like ODE's own spaces, tests each geom on the
 * other side against every geom of the space: O(n) per geom.
 */
#ifndef MINKO_ODE_H
#define MINKO_ODE_H

#include <ode/ode.h>

#include "minko/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- broadphase: drop-in replacements for dSpaceCollide / dSpaceCollide2 ---- */
void mk_ode_space_collide(dSpaceID space, void *data, dNearCallback *callback);
void mk_ode_space_collide2(dGeomID o1, dGeomID o2, void *data, dNearCallback *callback);
/* Frees the persistent state kept for `space` (call it before dSpaceDestroy
 * to return the memory at once; mk_ode_close frees everything). Refused
 * (counted in errors) from inside that space's own near callback. */
void mk_ode_space_forget(dSpaceID space);

/* ---- narrowphase ---- */
/* dCollide-compatible: Minko for supported pairs, dCollide for the rest. */
int mk_ode_collide(dGeomID o1, dGeomID o2, int flags, dContactGeom *contact, int skip);
/* A dColliderFn for dSetColliderOverride: supported pairs only (any other
 * pair gets 0 contacts and is counted in mk_ode_stats.unsupported). */
int mk_ode_collider(dGeomID o1, dGeomID o2, int flags, dContactGeom *contact, int skip);
/* 1 if Minko handles this pair of geoms. */
int mk_ode_supports(dGeomID o1, dGeomID o2);
/* dSetColliderOverride(i, j, mk_ode_collider) for every supported class
 * pair; ODE must be initialised. Returns how many pairs were installed. */
int mk_ode_install_colliders(void);
/* dInitODE2(flags), then mk_ode_install_colliders(). */
mk_status mk_ode_init(unsigned int flags);
/* Frees all adapter state, then dCloseODE(). */
void mk_ode_close(void);

/* dCreateConvex / dGeomSetConvex that also build the Minko hull (quickhull of
 * `points`): same arguments, same ODE geom; the arrays must outlive the geom,
 * as ODE requires. If the hull cannot be built (degenerate points: see
 * mk_hull_create) the geom still exists and collides through dCollide; the
 * status is in mk_ode_stats.last_error. mk_ode_geom_destroy drops the
 * adapter's records of a geom (hull, or a space's broadphase), then
 * dGeomDestroy()s it. */
dGeomID mk_ode_create_convex(dSpaceID space, const dReal *planes, unsigned int planecount, const dReal *points,
                             unsigned int pointcount, const unsigned int *polygons);
mk_status mk_ode_geom_set_convex(dGeomID g, const dReal *planes, unsigned int planecount, const dReal *points,
                                 unsigned int pointcount, const unsigned int *polygons);
void mk_ode_geom_destroy(dGeomID g);

/* ---- continuous collision: when to split a step ---- */
/* Time of impact of o1 and o2 within the next dt seconds, each keeping its
 * body's current linear and angular velocity (body-less geoms stand still;
 * a body may turn at most pi radians in dt). Returns 1 with *toi in [0, dt]
 * the first time they come within `target` (>= 0) of each other, never
 * skipping a contact however thin or fast the geoms (Minko's conservative
 * advancement, mk_toi), and *contact a contact for that moment in ODE's
 * conventions (depth = the penetration if any, else 0); returns 0 when they
 * stay farther apart than `target`, when they already penetrate (the
 * discrete contacts handle that) or touch while moving apart; -1 for a pair
 * Minko cannot model (counted in mk_ode_stats.errors). A host splits its step
 * at the earliest *toi over its fast bodies and adds the contacts of pairs
 * that touch at 0 (demos/ode_scenes.c, wall scene). */
int mk_ode_time_of_impact(dGeomID o1, dGeomID o2, dReal dt, dReal target, dReal *toi, dContactGeom *contact);

/* ---- switching at run time ---- */
typedef void mk_ode_space_collide_fn(dSpaceID space, void *data, dNearCallback *callback);
typedef void mk_ode_space_collide2_fn(dGeomID o1, dGeomID o2, void *data, dNearCallback *callback);
typedef struct mk_ode_collision {
    mk_ode_space_collide_fn *space_collide;   /* dSpaceCollide or mk_ode_space_collide */
    mk_ode_space_collide2_fn *space_collide2; /* dSpaceCollide2 or mk_ode_space_collide2 */
    dColliderFn *collide;                     /* dCollide or mk_ode_collide */
} mk_ode_collision;
/* Native ODE or Minko, chosen separately for the broadphase and the narrowphase. */
mk_ode_collision mk_ode_select(int minko_broadphase, int minko_narrowphase);

/* ---- counters, cumulative since mk_ode_stats_reset ---- */
typedef struct mk_ode_stats {
    long long space_calls;     /* mk_ode_space_collide + mk_ode_space_collide2 */
    long long pairs_reported;  /* near-callback invocations */
    long long collide_calls;   /* pairs Minko's narrowphase answered */
    long long contacts;        /* contacts written by Minko */
    long long fallbacks;       /* pairs mk_ode_collide handed to dCollide */
    long long unsupported;     /* pairs mk_ode_collider could not handle */
    long long toi_calls;       /* pairs mk_ode_time_of_impact answered */
    long long errors;          /* bad arguments or failed Minko calls (the call did nothing, or stopped) */
    mk_status last_error;
} mk_ode_stats;
void mk_ode_get_stats(mk_ode_stats *out);
void mk_ode_stats_reset(void);

#ifdef __cplusplus
}
#endif

#endif

/* minko_ode.h: Minko behind ODE's dSpaceCollide (libminko_ode).
 *
 * Contract. The broadphase entry points have exactly the signatures of
 * dSpaceCollide and dSpaceCollide2 and report exactly the pairs ODE's own
 * spaces must report (ODE's collideAABBs filter: geoms disabled or of zero
 * size skipped, same non-null body skipped, category/collide bits OR-ed both
 * ways, closed AABB overlap tested on ODE's own dReal AABBs; sub-spaces
 * passed to the callback as geoms; dSpaceCollide2's space/geom/sublevel
 * rules and argument order), each pair once, in a deterministic order. A
 * persistent Minko broadphase per space, keyed by dGeomID, is brought up to
 * date from the space's geoms on every call, so geoms may be created, moved,
 * disabled and destroyed freely between calls, and a destroyed geom's
 * address reused by a new geom is harmless. The space may be of any kind; a
 * dSimpleSpace is the cheapest container (the others do upkeep of their
 * own). ODE is double precision here; in a float build of Minko the
 * broadphase works on the dReal AABBs rounded outwards and the final test is
 * ODE's, in dReal, so the reported pairs are the same. Adapter state is
 * global and not thread-safe, like ODE's collider table. As with ODE's own
 * spaces, the near callback must not add, remove or destroy geoms of the
 * space being collided.
 *
 * Complexity: mk_ode_space_collide is O(n) to read the n geoms' AABBs plus
 * the Minko broadphase update (O(n + moving endpoints) for coherent motion)
 * plus O(p) for p reported pairs; ODE's dHashSpace rebuilds its grid and an
 * n*n bit matrix on every call. mk_ode_space_collide2 against a space is one
 * such update plus a region query per geom on the other side.
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
 * to return the memory at once; mk_ode_close frees everything). */
void mk_ode_space_forget(dSpaceID space);

/* Frees all adapter state, then dCloseODE(). */
void mk_ode_close(void);

/* ---- counters, cumulative since mk_ode_stats_reset ---- */
typedef struct mk_ode_stats {
    long long space_calls;     /* mk_ode_space_collide + mk_ode_space_collide2 */
    long long pairs_reported;  /* near-callback invocations */
    long long errors;          /* bad arguments or failed Minko calls (the call did nothing, or stopped) */
    mk_status last_error;
} mk_ode_stats;
void mk_ode_get_stats(mk_ode_stats *out);
void mk_ode_stats_reset(void);

#ifdef __cplusplus
}
#endif

#endif

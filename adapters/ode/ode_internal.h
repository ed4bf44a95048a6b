/* ode_internal.h: what the ODE adapter's modules share (internal). */
#ifndef MK_ODE_INTERNAL_H
#define MK_ODE_INTERNAL_H

#include "minko/shape.h"
#include "minko_ode.h"

/* The counters behind mk_ode_get_stats(). */
extern mk_ode_stats mk_ode_stats_;

/* ode_space.c / ode_collide.c: free every record (mk_ode_close). */
void mk_ode_space_free_all(void);
void mk_ode_collide_free_all(void);

/* ode_collide.c, shared with ode_toi.c: the point geometry is taken relative
 * to (the first placeable geom's position), and a geom as a Minko shape and
 * pose relative to it. MK_ERR_UNSUPPORTED for classes Minko does not model
 * and for convex geoms without a recorded hull. */
const dReal *mk_ode_origin_(dGeomID o1, dGeomID o2);
mk_status mk_ode_shape_of_(dGeomID g, const dReal *origin, mk_shape *shape, mk_transform *xf);

#endif

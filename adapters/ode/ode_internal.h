/* ode_internal.h: what the ODE adapter's modules share (internal). */
#ifndef MK_ODE_INTERNAL_H
#define MK_ODE_INTERNAL_H

#include "minko_ode.h"

/* The counters behind mk_ode_get_stats(). */
extern mk_ode_stats mk_ode_stats_;

/* ode_space.c: free every record (mk_ode_close). */
void mk_ode_space_free_all(void);

#endif

/* ode_adapter.c: the adapter's global state: counters and shutdown. */
#include <string.h>

#include "ode_internal.h"

mk_ode_stats mk_ode_stats_;

void mk_ode_close(void)
{
    mk_ode_space_free_all();
    mk_ode_collide_free_all();
    dCloseODE();
}

void mk_ode_get_stats(mk_ode_stats *out)
{
    if (out) *out = mk_ode_stats_;
}

void mk_ode_stats_reset(void) { memset(&mk_ode_stats_, 0, sizeof mk_ode_stats_); }

/* toi_internal.h: the time-of-impact driver behind mk_toi, for the module's
 * own helpers and the benchmark that compares advancement methods. */
#ifndef MINKO_TOI_INTERNAL_H
#define MINKO_TOI_INTERNAL_H

#include "minko/toi.h"

enum {
    MK_TOI_METHOD_TAYLOR = 0, /* conservative, second-order bound (the default) */
    MK_TOI_METHOD_MIRTICH,    /* conservative, linear bound */
    MK_TOI_METHOD_BILATERAL   /* Catto's bracketing root finder on the separating axis */
};

/* mk_toi on [0, t_max] without input checks. */
mk_status mk_toi_run_(const mk_shape *a, const mk_sweep *sa, const mk_shape *b, const mk_sweep *sb, mk_real target, mk_real tolerance,
                      mk_real t_max, int method, mk_toi_result *out);

#endif

/* ode_map.h: (pointer, pointer) -> small integer map for the ODE adapter (internal).
 *
 * ODE gives geoms no slot for adapter data (dGeomSetData belongs to the
 * user), so every per-geom, per-space and per-pair record is found by its
 * pointers: one-pointer keys pass b = NULL. Open addressing with linear
 * probing and backward-shift deletion (no tombstones, so lookups stay short
 * under churn). Lookup, insert and remove are O(1) expected; the table
 * doubles when it is half full, which is the only time it allocates.
 */
#ifndef MK_ODE_MAP_H
#define MK_ODE_MAP_H

#include <stddef.h>
#include <stdint.h>

typedef struct mk_ode_key { const void *a, *b; } mk_ode_key; /* a == NULL: empty slot */

typedef struct mk_ode_map {
    mk_ode_key *keys;
    uint32_t *values;
    size_t mask;        /* capacity - 1, capacity a power of two; 0 when unallocated */
    size_t count;
} mk_ode_map;

/* The value stored for (a, b), or -1. */
long mk_ode_map_get(const mk_ode_map *m, const void *a, const void *b);
/* Inserts or overwrites; a must not be NULL. Returns 0, or -1 when memory ran out (map unchanged). */
int mk_ode_map_put(mk_ode_map *m, const void *a, const void *b, uint32_t value);
/* Removes (a, b) if present. */
void mk_ode_map_remove(mk_ode_map *m, const void *a, const void *b);
void mk_ode_map_free(mk_ode_map *m);

#endif

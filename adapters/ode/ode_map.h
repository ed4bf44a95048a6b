/* ode_map.h: pointer -> small integer map for the ODE adapter (internal).
 *
 * ODE gives geoms no slot for adapter data (dGeomSetData belongs to the
 * user), so every per-geom and per-space record is found by its pointer.
 * Open addressing with linear probing and backward-shift deletion (no
 * tombstones, so lookups stay short under churn). Lookup, insert and remove
 * are O(1) expected; the table doubles when it is half full, which is the
 * only time it allocates.
 */
#ifndef MK_ODE_MAP_H
#define MK_ODE_MAP_H

#include <stddef.h>
#include <stdint.h>

typedef struct mk_ode_map {
    const void **keys;  /* NULL = empty slot */
    uint32_t *values;
    size_t mask;        /* capacity - 1, capacity a power of two; 0 when unallocated */
    size_t count;
} mk_ode_map;

/* The value stored for key, or -1. */
long mk_ode_map_get(const mk_ode_map *m, const void *key);
/* Inserts or overwrites. Returns 0, or -1 when memory ran out (map unchanged). */
int mk_ode_map_put(mk_ode_map *m, const void *key, uint32_t value);
/* Removes key if present. */
void mk_ode_map_remove(mk_ode_map *m, const void *key);
void mk_ode_map_free(mk_ode_map *m);

#endif

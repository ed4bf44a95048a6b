/* ode_map.c: pointer-keyed open-addressing map (see ode_map.h). */
#include "ode_map.h"

#include <stdlib.h>

/* Fibonacci hashing of the address: the low bits of heap pointers are
 * constant (alignment), the multiply spreads the high ones. */
static size_t slot_of(const mk_ode_map *m, const void *key)
{
    uint64_t h = (uint64_t)(uintptr_t)key * 0x9E3779B97F4A7C15ull;
    return (size_t)(h >> 32) & m->mask;
}

long mk_ode_map_get(const mk_ode_map *m, const void *key)
{
    size_t i;
    if (!m->mask || !key) return -1;
    for (i = slot_of(m, key); m->keys[i]; i = (i + 1) & m->mask)
        if (m->keys[i] == key) return (long)m->values[i];
    return -1;
}

static int grow(mk_ode_map *m)
{
    size_t cap = m->mask ? 2 * (m->mask + 1) : 64, i;
    mk_ode_map n;
    n.keys = calloc(cap, sizeof *n.keys);
    n.values = malloc(cap * sizeof *n.values);
    if (!n.keys || !n.values) {
        free(n.keys);
        free(n.values);
        return -1;
    }
    n.mask = cap - 1;
    n.count = 0;
    for (i = 0; m->mask && i <= m->mask; i++)
        if (m->keys[i]) mk_ode_map_put(&n, m->keys[i], m->values[i]); /* cannot grow: n is large enough */
    mk_ode_map_free(m);
    *m = n;
    return 0;
}

int mk_ode_map_put(mk_ode_map *m, const void *key, uint32_t value)
{
    size_t i;
    if (!key) return -1;
    if (2 * (m->count + 1) > (m->mask ? m->mask + 1 : 0) && grow(m) != 0) return -1;
    for (i = slot_of(m, key); m->keys[i]; i = (i + 1) & m->mask) {
        if (m->keys[i] == key) {
            m->values[i] = value;
            return 0;
        }
    }
    m->keys[i] = key;
    m->values[i] = value;
    m->count++;
    return 0;
}

void mk_ode_map_remove(mk_ode_map *m, const void *key)
{
    size_t i, j;
    if (!m->mask || !key) return;
    for (i = slot_of(m, key); m->keys[i] != key; i = (i + 1) & m->mask)
        if (!m->keys[i]) return;
    /* Backward shift: pull later members of the probe run into the hole when
     * their home slot does not lie strictly between the hole and them. */
    for (j = (i + 1) & m->mask; m->keys[j]; j = (j + 1) & m->mask) {
        size_t home = slot_of(m, m->keys[j]);
        if (((j - home) & m->mask) >= ((j - i) & m->mask)) {
            m->keys[i] = m->keys[j];
            m->values[i] = m->values[j];
            i = j;
        }
    }
    m->keys[i] = NULL;
    m->count--;
}

void mk_ode_map_free(mk_ode_map *m)
{
    free((void *)m->keys);
    free(m->values);
    m->keys = NULL;
    m->values = NULL;
    m->mask = 0;
    m->count = 0;
}

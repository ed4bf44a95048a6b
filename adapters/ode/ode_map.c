/* ode_map.c: pointer-keyed open-addressing map (see ode_map.h). */
#include "ode_map.h"

#include <stdlib.h>

/* Fibonacci hashing of the addresses: the low bits of heap pointers are
 * constant (alignment), the multiplies spread the high ones. */
static size_t slot_of(const mk_ode_map *m, const void *a, const void *b)
{
    uint64_t h = ((uint64_t)(uintptr_t)a ^ ((uint64_t)(uintptr_t)b * 0xC2B2AE3D27D4EB4Full)) * 0x9E3779B97F4A7C15ull;
    return (size_t)(h >> 32) & m->mask;
}

static int same(mk_ode_key k, const void *a, const void *b) { return k.a == a && k.b == b; }

long mk_ode_map_get(const mk_ode_map *m, const void *a, const void *b)
{
    size_t i;
    if (!m->mask || !a) return -1;
    for (i = slot_of(m, a, b); m->keys[i].a; i = (i + 1) & m->mask)
        if (same(m->keys[i], a, b)) return (long)m->values[i];
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
    for (i = 0; m->mask && i <= m->mask; i++) /* cannot grow: n is large enough */
        if (m->keys[i].a) mk_ode_map_put(&n, m->keys[i].a, m->keys[i].b, m->values[i]);
    mk_ode_map_free(m);
    *m = n;
    return 0;
}

int mk_ode_map_put(mk_ode_map *m, const void *a, const void *b, uint32_t value)
{
    size_t i;
    if (!a) return -1;
    if (2 * (m->count + 1) > (m->mask ? m->mask + 1 : 0) && grow(m) != 0) return -1;
    for (i = slot_of(m, a, b); m->keys[i].a; i = (i + 1) & m->mask) {
        if (same(m->keys[i], a, b)) {
            m->values[i] = value;
            return 0;
        }
    }
    m->keys[i].a = a;
    m->keys[i].b = b;
    m->values[i] = value;
    m->count++;
    return 0;
}

void mk_ode_map_remove(mk_ode_map *m, const void *a, const void *b)
{
    size_t i, j;
    if (!m->mask || !a) return;
    for (i = slot_of(m, a, b); !same(m->keys[i], a, b); i = (i + 1) & m->mask)
        if (!m->keys[i].a) return;
    /* Backward shift: pull later members of the probe run into the hole when
     * their home slot does not lie strictly between the hole and them. */
    for (j = (i + 1) & m->mask; m->keys[j].a; j = (j + 1) & m->mask) {
        size_t home = slot_of(m, m->keys[j].a, m->keys[j].b);
        if (((j - home) & m->mask) >= ((j - i) & m->mask)) {
            m->keys[i] = m->keys[j];
            m->values[i] = m->values[j];
            i = j;
        }
    }
    m->keys[i].a = NULL;
    m->keys[i].b = NULL;
    m->count--;
}

void mk_ode_map_free(mk_ode_map *m)
{
    free(m->keys);
    free(m->values);
    m->keys = NULL;
    m->values = NULL;
    m->mask = 0;
    m->count = 0;
}

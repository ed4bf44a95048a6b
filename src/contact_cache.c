/* contact_cache.c: the warm-start impulse cache (see minko/contact_cache.h).
 *
 * Why two tables and frame stamps: with one linear-probing table, dropping
 * last frame's entries lazily (by treating old stamps as empty) breaks the
 * probe chains of entries stored after them, and dropping them eagerly costs
 * a pass over the table. With one table per frame parity, every slot a probe
 * chain ran over when a key was stored carried the same stamp as that key,
 * and a table is never written while it is the one being read, so "stamp ==
 * the frame this table belongs to" is an exact occupancy test and a new
 * frame starts by bumping a counter. Stamps are 64-bit so they never wrap. */
#include <string.h>

#include "alloc.h"
#include "minko/contact_cache.h"

typedef struct mk_cache_slot {
    uint64_t stamp; /* the frame that wrote the slot; the slot is live only in that frame's role */
    mk_contact_id id;
    mk_contact_impulse impulse;
} mk_cache_slot;

struct mk_contact_cache {
    mk_allocator alloc;
    size_t bytes;
    int capacity;
    uint32_t mask;          /* slots per table - 1 (a power of two minus one) */
    uint64_t frame;         /* current frame stamp; starts at 2 so stamp 0 (zeroed memory) is never live */
    mk_cache_slot *table[2]; /* table[frame & 1] receives stores, the other holds frame - 1 */
    int32_t *order[2];      /* slot indices of each table in store order */
    int count[2];
};

mk_contact_id mk_contact_id_make(uint32_t body_a, uint32_t body_b, uint32_t features)
{
    mk_contact_id id;
    id.body_a = body_a;
    id.body_b = body_b;
    id.features = features;
    return id;
}

int mk_contact_id_equal(mk_contact_id a, mk_contact_id b)
{
    return a.body_a == b.body_a && a.body_b == b.body_b && a.features == b.features;
}

/* MurmurHash3's 64-bit finaliser over the two words of the key: every input
 * bit reaches every output bit, so linear probing on the low bits stays short
 * even for the dense, regular body indices hosts use. */
uint32_t mk_contact_id_hash(mk_contact_id id)
{
    uint64_t k = ((uint64_t)id.body_a << 32 | id.body_b) ^ ((uint64_t)id.features * 0x9E3779B97F4A7C15ull);
    k ^= k >> 33;
    k *= 0xFF51AFD7ED558CCDull;
    k ^= k >> 33;
    k *= 0xC4CEB9FE1A85EC53ull;
    k ^= k >> 33;
    return (uint32_t)k;
}

static size_t round_up(size_t n, size_t a) { return (n + a - 1) / a * a; }

mk_status mk_contact_cache_create(int capacity, const mk_allocator *alloc, mk_contact_cache **out)
{
    mk_allocator al;
    mk_contact_cache *c;
    size_t slots = 2, head, table_bytes, order_bytes, bytes;
    char *mem;
    if (!out) return MK_ERR_NULL;
    if (capacity < 1 || capacity > MK_CONTACT_CACHE_MAX_CAPACITY) return MK_ERR_BAD_SIZE;
    if (mk_alloc_resolve_(alloc, &al) != MK_OK) return MK_ERR_NULL;
    while (slots < 2 * (size_t)capacity) slots *= 2; /* load factor <= 1/2 */
    head = round_up(sizeof(mk_contact_cache), 16);
    table_bytes = round_up(slots * sizeof(mk_cache_slot), 16);
    order_bytes = round_up((size_t)capacity * sizeof(int32_t), 16);
    bytes = head + 2 * table_bytes + 2 * order_bytes;
    mem = (char *)al.alloc(al.ctx, bytes, 16);
    if (!mem) return MK_ERR_OUT_OF_MEMORY;
    memset(mem, 0, bytes); /* stamp 0 is never a live frame */
    c = (mk_contact_cache *)(void *)mem;
    c->alloc = al;
    c->bytes = bytes;
    c->capacity = capacity;
    c->mask = (uint32_t)(slots - 1);
    c->frame = 2;
    c->table[0] = (mk_cache_slot *)(void *)(mem + head);
    c->table[1] = (mk_cache_slot *)(void *)(mem + head + table_bytes);
    c->order[0] = (int32_t *)(void *)(mem + head + 2 * table_bytes);
    c->order[1] = (int32_t *)(void *)(mem + head + 2 * table_bytes + order_bytes);
    *out = c;
    return MK_OK;
}

void mk_contact_cache_destroy(mk_contact_cache *cache)
{
    if (cache) cache->alloc.free(cache->alloc.ctx, cache, cache->bytes);
}

mk_status mk_contact_cache_begin_frame(mk_contact_cache *cache)
{
    if (!cache) return MK_ERR_NULL;
    cache->frame++;
    cache->count[cache->frame & 1] = 0;
    return MK_OK;
}

/* Slot of `id` in the table of frame `stamp`, or of the empty slot ending its
 * probe chain. */
static uint32_t probe(const mk_contact_cache *c, uint64_t stamp, mk_contact_id id)
{
    const mk_cache_slot *t = c->table[stamp & 1];
    uint32_t i = mk_contact_id_hash(id) & c->mask;
    while (t[i].stamp == stamp && !mk_contact_id_equal(t[i].id, id)) i = (i + 1) & c->mask;
    return i;
}

mk_status mk_contact_cache_lookup(const mk_contact_cache *cache, mk_contact_id id, mk_contact_impulse *out, int *found)
{
    uint64_t prev;
    const mk_cache_slot *s;
    if (!cache || !out) return MK_ERR_NULL;
    prev = cache->frame - 1;
    s = &cache->table[prev & 1][probe(cache, prev, id)];
    if (s->stamp == prev) {
        *out = s->impulse;
    } else {
        out->normal = out->tangent1 = out->tangent2 = 0;
    }
    if (found) *found = s->stamp == prev;
    return MK_OK;
}

mk_status mk_contact_cache_store(mk_contact_cache *cache, mk_contact_id id, mk_contact_impulse impulse)
{
    int p;
    uint32_t i;
    mk_cache_slot *s;
    if (!cache) return MK_ERR_NULL;
    if (!mk_real_is_valid(impulse.normal) || !mk_real_is_valid(impulse.tangent1) || !mk_real_is_valid(impulse.tangent2))
        return MK_ERR_NOT_FINITE;
    p = (int)(cache->frame & 1);
    i = probe(cache, cache->frame, id);
    s = &cache->table[p][i];
    if (s->stamp != cache->frame) {
        if (cache->count[p] == cache->capacity) return MK_ERR_CAPACITY;
        s->stamp = cache->frame;
        s->id = id;
        cache->order[p][cache->count[p]++] = (int32_t)i;
    }
    s->impulse = impulse;
    return MK_OK;
}

int mk_contact_cache_count(const mk_contact_cache *cache)
{
    return cache ? cache->count[cache->frame & 1] : 0;
}

int mk_contact_cache_capacity(const mk_contact_cache *cache) { return cache ? cache->capacity : 0; }

mk_status mk_contact_cache_entry(const mk_contact_cache *cache, int i, mk_contact_id *id, mk_contact_impulse *impulse)
{
    int p;
    const mk_cache_slot *s;
    if (!cache || (!id && !impulse)) return MK_ERR_NULL;
    p = (int)(cache->frame & 1);
    if (i < 0 || i >= cache->count[p]) return MK_ERR_BAD_ARGUMENT;
    s = &cache->table[p][cache->order[p][i]];
    if (id) *id = s->id;
    if (impulse) *impulse = s->impulse;
    return MK_OK;
}

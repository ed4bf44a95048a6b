/* minko/contact_cache.h: persistent contact impulses for solver warm starting.
 *
 * Contract. The cache maps a contact's identity (mk_contact_id: for each of the
 * two bodies the host's body index and the feature of that body that makes the
 * contact, seed 000's CollisionID) to the impulses the host's solver
 * accumulated for it: normal, first and second tangent. It is the seed's
 * unordered_map<CollisionID, float> with its clear-and-reinsert done in O(1):
 * two open-addressing tables of fixed size, one holding the previous frame
 * (read by lookups) and one receiving this frame's stores, each slot stamped
 * with the frame that wrote it, so starting a frame drops everything older
 * without touching the table. Per frame the host calls
 * mk_contact_cache_begin_frame(), then mk_contact_cache_lookup() for every
 * contact to get lambda^0 (zeros when the contact is new), solves, then
 * mk_contact_cache_store() for every contact it keeps (asleep ones included:
 * a contact not stored this frame is gone next frame). Keys are ordered: the
 * host must pass each body pair in the same order every frame (e.g. lower
 * index first), because the features, the normal and the tangents the
 * impulses refer to all follow that order. The tangent basis is the host's:
 * choose one that is a continuous function of the normal (mk_v3_perp) so
 * stored tangent impulses stay meaningful. All memory is one block taken at
 * creation from the caller's allocator (NULL: malloc); nothing allocates
 * afterwards. More than `capacity` stores in one frame fail with
 * MK_ERR_CAPACITY and store nothing. Iteration visits this frame's entries in
 * the order they were stored, so results never depend on hash values.
 * Complexity: begin_frame O(1); lookup and store O(1) expected (linear probing
 * at load <= 1/2); memory: two tables of 2 x capacity slots (rounded up to a
 * power of two) of 48 bytes (32 in the float build), plus 8 bytes per contact.
 */
#ifndef MINKO_CONTACT_CACHE_H
#define MINKO_CONTACT_CACHE_H

#include "minko/manifold.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Identity of one contact point across frames. `features` is the packed
 * feature pair the manifold reports (mk_contact_point.features: the feature
 * of body A in the low 16 bits, of body B in the high 16 bits). */
typedef struct mk_contact_id {
    uint32_t body_a;
    uint32_t body_b;
    uint32_t features;
} mk_contact_id;

/* Accumulated impulses of one contact point (N s): along the normal and
 * along the host's two tangent directions. */
typedef struct mk_contact_impulse {
    mk_real normal;
    mk_real tangent1;
    mk_real tangent2;
} mk_contact_impulse;

typedef struct mk_contact_cache mk_contact_cache;

/* Largest accepted capacity (contacts stored per frame). */
#define MK_CONTACT_CACHE_MAX_CAPACITY (1 << 22)

MK_API mk_contact_id mk_contact_id_make(uint32_t body_a, uint32_t body_b, uint32_t features);
/* 1 if a and b name the same contact (all fields equal), else 0. */
MK_API int mk_contact_id_equal(mk_contact_id a, mk_contact_id b);
/* A well-mixed 32-bit hash of the whole key; the same on every platform. */
MK_API uint32_t mk_contact_id_hash(mk_contact_id id);

/* Creates a cache for up to `capacity` contacts per frame (1 ..
 * MK_CONTACT_CACHE_MAX_CAPACITY). `alloc` may be NULL (malloc/free). */
MK_API mk_status mk_contact_cache_create(int capacity, const mk_allocator *alloc, mk_contact_cache **out);
/* Frees the cache through the allocator it was created with. NULL is a no-op. */
MK_API void mk_contact_cache_destroy(mk_contact_cache *cache);

/* Starts a new frame: what was stored since the last call becomes what
 * lookups see, and everything older is dropped. */
MK_API mk_status mk_contact_cache_begin_frame(mk_contact_cache *cache);

/* lambda^0 for `id`: the impulses stored for it in the previous frame, or
 * zeros if it was not stored then. `found` (may be NULL) is set to 1 or 0. */
MK_API mk_status mk_contact_cache_lookup(const mk_contact_cache *cache, mk_contact_id id,
                                         mk_contact_impulse *out, int *found);

/* Records this frame's impulses for `id`. Storing the same id again in the
 * same frame replaces the earlier value (and keeps its place in the order).
 * Non-finite impulses give MK_ERR_NOT_FINITE; a full frame MK_ERR_CAPACITY. */
MK_API mk_status mk_contact_cache_store(mk_contact_cache *cache, mk_contact_id id, mk_contact_impulse impulse);

/* Number of contacts stored in the current frame, and the i-th of them in
 * store order (0 <= i < count; one of id and impulse may be NULL). */
MK_API int mk_contact_cache_count(const mk_contact_cache *cache);
MK_API mk_status mk_contact_cache_entry(const mk_contact_cache *cache, int i, mk_contact_id *id,
                                        mk_contact_impulse *impulse);
/* The capacity given at creation (0 for NULL). */
MK_API int mk_contact_cache_capacity(const mk_contact_cache *cache);

#ifdef __cplusplus
}
#endif

#endif

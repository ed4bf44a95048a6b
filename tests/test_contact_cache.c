/* test_contact_cache.c: keys, lookup/store/evict semantics, capacity, allocator. */
#include <stdlib.h>
#include <string.h>

#include "minko/contact_cache.h"
#include "support/mk_test.h"

static mk_contact_impulse imp(mk_real n, mk_real t1, mk_real t2)
{
    mk_contact_impulse i;
    i.normal = n;
    i.tangent1 = t1;
    i.tangent2 = t2;
    return i;
}

static mk_contact_id key(uint32_t a, uint32_t b, int fa, int fb)
{
    return mk_contact_id_make(a, b, MK_FEATURE_PAIR(MK_FEATURE(MK_FEATURE_VERTEX, fa), MK_FEATURE(MK_FEATURE_FACE, fb)));
}

START_TEST(key_compare_and_hash)
{
    mk_contact_id a = key(3, 7, 5, 2), b = key(3, 7, 5, 2);
    int i, buckets[64] = {0}, maxb = 0;
    ck_assert(mk_contact_id_equal(a, b));
    ck_assert_uint_eq(mk_contact_id_hash(a), mk_contact_id_hash(b));
    /* Every field takes part in equality and hashing, including the order of the bodies. */
    ck_assert(!mk_contact_id_equal(a, key(7, 3, 5, 2)));
    ck_assert(!mk_contact_id_equal(a, key(3, 7, 4, 2)));
    ck_assert(!mk_contact_id_equal(a, mk_contact_id_make(3, 7, MK_FEATURE_PAIR(MK_FEATURE(MK_FEATURE_EDGE, 5), MK_FEATURE(MK_FEATURE_FACE, 2)))));
    ck_assert_uint_ne(mk_contact_id_hash(a), mk_contact_id_hash(key(7, 3, 5, 2)));
    ck_assert_uint_ne(mk_contact_id_hash(a), mk_contact_id_hash(key(3, 7, 5, 3)));
    /* Dense, regular keys (a grid of bodies, 8 vertices each) spread over the low bits. */
    for (i = 0; i < 64 * 64; ++i) buckets[mk_contact_id_hash(key((uint32_t)(i / 8), (uint32_t)(i / 8 + 1), i % 8, 4)) & 63]++;
    for (i = 0; i < 64; ++i) maxb = buckets[i] > maxb ? buckets[i] : maxb;
    ck_assert_int_lt(maxb, 64 + 8 * 8); /* mean 64, sigma 8: 8 sigma */
    /* Feature packing round-trips. */
    ck_assert_int_eq(MK_FEATURE_TYPE(MK_FEATURE(MK_FEATURE_FACE, 1234)), MK_FEATURE_FACE);
    ck_assert_int_eq(MK_FEATURE_GET_INDEX(MK_FEATURE(MK_FEATURE_EDGE, MK_FEATURE_MAX_INDEX)), MK_FEATURE_MAX_INDEX);
}
END_TEST

START_TEST(lookup_store_evict)
{
    mk_contact_cache *c = NULL;
    mk_contact_impulse out;
    int found = -1;
    MK_ASSERT_STATUS(mk_contact_cache_create(8, NULL, &c), MK_OK);
    ck_assert_int_eq(mk_contact_cache_capacity(c), 8);
    /* Empty cache: zeros, not found. */
    out = imp(9, 9, 9);
    MK_ASSERT_STATUS(mk_contact_cache_lookup(c, key(1, 2, 0, 0), &out, &found), MK_OK);
    ck_assert_int_eq(found, 0);
    MK_ASSERT_NEAR(out.normal, 0, 0);
    MK_ASSERT_NEAR(out.tangent2, 0, 0);
    /* Frame 1 stores a, b, c. They are not visible to lookups of the same frame:
     * lookups give lambda^0 from the previous frame only. */
    MK_ASSERT_STATUS(mk_contact_cache_store(c, key(1, 2, 0, 4), imp(1, 0.1, -0.1)), MK_OK);
    MK_ASSERT_STATUS(mk_contact_cache_store(c, key(1, 2, 1, 4), imp(2, 0.2, -0.2)), MK_OK);
    MK_ASSERT_STATUS(mk_contact_cache_store(c, key(2, 5, 3, 1), imp(3, 0.3, -0.3)), MK_OK);
    ck_assert_int_eq(mk_contact_cache_count(c), 3);
    MK_ASSERT_STATUS(mk_contact_cache_lookup(c, key(1, 2, 0, 4), &out, &found), MK_OK);
    ck_assert_int_eq(found, 0);
    /* Frame 2: all three visible with their values. Store only b (new value) and d. */
    MK_ASSERT_STATUS(mk_contact_cache_begin_frame(c), MK_OK);
    ck_assert_int_eq(mk_contact_cache_count(c), 0);
    MK_ASSERT_STATUS(mk_contact_cache_lookup(c, key(1, 2, 0, 4), &out, &found), MK_OK);
    ck_assert_int_eq(found, 1);
    MK_ASSERT_NEAR(out.normal, 1, 0);
    MK_ASSERT_NEAR(out.tangent1, (mk_real)0.1, 0);
    MK_ASSERT_NEAR(out.tangent2, (mk_real)-0.1, 0);
    MK_ASSERT_STATUS(mk_contact_cache_lookup(c, key(2, 5, 3, 1), &out, NULL), MK_OK);
    MK_ASSERT_NEAR(out.normal, 3, 0);
    MK_ASSERT_STATUS(mk_contact_cache_store(c, key(1, 2, 1, 4), imp(20, 0, 0)), MK_OK);
    MK_ASSERT_STATUS(mk_contact_cache_store(c, key(9, 9, 9, 9), imp(4, 0, 0)), MK_OK);
    /* Frame 3: a and c were not stored in frame 2, so they are gone; b has its new value. */
    MK_ASSERT_STATUS(mk_contact_cache_begin_frame(c), MK_OK);
    MK_ASSERT_STATUS(mk_contact_cache_lookup(c, key(1, 2, 0, 4), &out, &found), MK_OK);
    ck_assert_int_eq(found, 0);
    MK_ASSERT_NEAR(out.normal, 0, 0);
    MK_ASSERT_STATUS(mk_contact_cache_lookup(c, key(2, 5, 3, 1), &out, &found), MK_OK);
    ck_assert_int_eq(found, 0);
    MK_ASSERT_STATUS(mk_contact_cache_lookup(c, key(1, 2, 1, 4), &out, &found), MK_OK);
    ck_assert_int_eq(found, 1);
    MK_ASSERT_NEAR(out.normal, 20, 0);
    MK_ASSERT_STATUS(mk_contact_cache_lookup(c, key(9, 9, 9, 9), &out, &found), MK_OK);
    ck_assert_int_eq(found, 1);
    /* Frame 4 with no stores, then frame 5: everything gone. */
    MK_ASSERT_STATUS(mk_contact_cache_begin_frame(c), MK_OK);
    MK_ASSERT_STATUS(mk_contact_cache_begin_frame(c), MK_OK);
    MK_ASSERT_STATUS(mk_contact_cache_lookup(c, key(1, 2, 1, 4), &out, &found), MK_OK);
    ck_assert_int_eq(found, 0);
    mk_contact_cache_destroy(c);
}
END_TEST

START_TEST(iteration_order_and_replace)
{
    mk_contact_cache *c = NULL;
    mk_contact_id id;
    mk_contact_impulse out;
    uint32_t i;
    MK_ASSERT_STATUS(mk_contact_cache_create(100, NULL, &c), MK_OK);
    for (i = 0; i < 50; ++i) MK_ASSERT_STATUS(mk_contact_cache_store(c, key(50 - i, i, 1, 2), imp((mk_real)i, 0, 0)), MK_OK);
    /* Storing an id again replaces its value and keeps its place. */
    MK_ASSERT_STATUS(mk_contact_cache_store(c, key(50 - 7, 7, 1, 2), imp(-1, 5, 6)), MK_OK);
    ck_assert_int_eq(mk_contact_cache_count(c), 50);
    for (i = 0; i < 50; ++i) {
        MK_ASSERT_STATUS(mk_contact_cache_entry(c, (int)i, &id, &out), MK_OK);
        ck_assert(mk_contact_id_equal(id, key(50 - i, i, 1, 2)));
        MK_ASSERT_NEAR(out.normal, i == 7 ? -1 : (double)i, 0);
    }
    MK_ASSERT_STATUS(mk_contact_cache_entry(c, 50, &id, &out), MK_ERR_BAD_ARGUMENT);
    MK_ASSERT_STATUS(mk_contact_cache_entry(c, -1, &id, &out), MK_ERR_BAD_ARGUMENT);
    MK_ASSERT_STATUS(mk_contact_cache_entry(c, 0, NULL, &out), MK_OK);
    mk_contact_cache_destroy(c);
}
END_TEST

START_TEST(capacity_overflow)
{
    mk_contact_cache *c = NULL;
    mk_contact_impulse out;
    int found;
    MK_ASSERT_STATUS(mk_contact_cache_create(3, NULL, &c), MK_OK);
    MK_ASSERT_STATUS(mk_contact_cache_store(c, key(0, 1, 0, 0), imp(1, 0, 0)), MK_OK);
    MK_ASSERT_STATUS(mk_contact_cache_store(c, key(0, 1, 1, 0), imp(2, 0, 0)), MK_OK);
    MK_ASSERT_STATUS(mk_contact_cache_store(c, key(0, 1, 2, 0), imp(3, 0, 0)), MK_OK);
    MK_ASSERT_STATUS(mk_contact_cache_store(c, key(0, 1, 3, 0), imp(4, 0, 0)), MK_ERR_CAPACITY);
    ck_assert_int_eq(mk_contact_cache_count(c), 3);
    /* Replacing an existing entry still works when full. */
    MK_ASSERT_STATUS(mk_contact_cache_store(c, key(0, 1, 2, 0), imp(30, 0, 0)), MK_OK);
    MK_ASSERT_STATUS(mk_contact_cache_begin_frame(c), MK_OK);
    MK_ASSERT_STATUS(mk_contact_cache_lookup(c, key(0, 1, 3, 0), &out, &found), MK_OK);
    ck_assert_int_eq(found, 0); /* the refused store left nothing behind */
    MK_ASSERT_STATUS(mk_contact_cache_lookup(c, key(0, 1, 2, 0), &out, &found), MK_OK);
    ck_assert_int_eq(found, 1);
    MK_ASSERT_NEAR(out.normal, 30, 0);
    /* The new frame has its full capacity again. */
    MK_ASSERT_STATUS(mk_contact_cache_store(c, key(5, 1, 0, 0), imp(1, 0, 0)), MK_OK);
    MK_ASSERT_STATUS(mk_contact_cache_store(c, key(5, 1, 1, 0), imp(1, 0, 0)), MK_OK);
    MK_ASSERT_STATUS(mk_contact_cache_store(c, key(5, 1, 2, 0), imp(1, 0, 0)), MK_OK);
    MK_ASSERT_STATUS(mk_contact_cache_store(c, key(5, 1, 3, 0), imp(1, 0, 0)), MK_ERR_CAPACITY);
    mk_contact_cache_destroy(c);
}
END_TEST

/* Random churn against a brute-force model of the seed's semantics (clear,
 * then insert this frame's contacts). A small table and a key universe much
 * larger than the capacity make long probe chains that cross frames, which is
 * where a lazy-deletion bug would show. */
START_TEST(churn_matches_model)
{
    enum { CAP = 64, UNIVERSE = 400, FRAMES = 300 };
    static mk_contact_id ids[UNIVERSE];
    static mk_real prev_val[UNIVERSE], cur_val[UNIVERSE];
    static int prev_in[UNIVERSE], cur_in[UNIVERSE];
    mk_rng r = {42};
    mk_contact_cache *c = NULL;
    int f, u;
    for (u = 0; u < UNIVERSE; ++u) ids[u] = key((uint32_t)(u % 37), (uint32_t)(u / 37), u % 5, u % 3);
    MK_ASSERT_STATUS(mk_contact_cache_create(CAP, NULL, &c), MK_OK);
    memset(prev_in, 0, sizeof prev_in);
    for (f = 0; f < FRAMES; ++f) {
        int n = (int)(mk_rng_unit(&r) * (CAP + 8)), k;
        MK_ASSERT_STATUS(mk_contact_cache_begin_frame(c), MK_OK);
        for (u = 0; u < UNIVERSE; ++u) {
            mk_contact_impulse out;
            int found;
            MK_ASSERT_STATUS(mk_contact_cache_lookup(c, ids[u], &out, &found), MK_OK);
            ck_assert_int_eq(found, prev_in[u]);
            MK_ASSERT_NEAR(out.normal, prev_in[u] ? prev_val[u] : 0, 0);
        }
        memset(cur_in, 0, sizeof cur_in);
        for (k = 0, u = 0; k < n; ++k) {
            mk_status st;
            mk_real v = (mk_real)mk_rng_range(&r, 0, 100);
            u = (int)(mk_rng_unit(&r) * UNIVERSE);
            st = mk_contact_cache_store(c, ids[u], imp(v, -v, 2 * v));
            if (st == MK_OK) {
                cur_in[u] = 1;
                cur_val[u] = v;
            } else {
                MK_ASSERT_STATUS(st, MK_ERR_CAPACITY);
                ck_assert_int_eq(mk_contact_cache_count(c), CAP);
                ck_assert_int_eq(cur_in[u], 0);
            }
        }
        memcpy(prev_in, cur_in, sizeof prev_in);
        memcpy(prev_val, cur_val, sizeof prev_val);
    }
    mk_contact_cache_destroy(c);
}
END_TEST

typedef struct counting { int allocs, frees, fail; size_t live; } counting;
static void *count_alloc(void *ctx, size_t size, size_t align)
{
    counting *k = (counting *)ctx;
    ck_assert_int_eq((int)align & ((int)align - 1), 0);
    if (k->fail) return NULL;
    k->allocs++;
    k->live += size;
    return malloc(size);
}
static void count_free(void *ctx, void *p, size_t size)
{
    counting *k = (counting *)ctx;
    k->frees++;
    k->live -= size;
    free(p);
}

START_TEST(allocator_and_bad_input)
{
    counting k = {0, 0, 0, 0};
    mk_allocator al = {count_alloc, count_free, NULL};
    mk_allocator broken = {NULL, count_free, NULL};
    mk_contact_cache *c = NULL;
    mk_contact_impulse out;
    int f, i;
    al.ctx = &k;
    MK_ASSERT_STATUS(mk_contact_cache_create(0, NULL, &c), MK_ERR_BAD_SIZE);
    MK_ASSERT_STATUS(mk_contact_cache_create(-5, NULL, &c), MK_ERR_BAD_SIZE);
    MK_ASSERT_STATUS(mk_contact_cache_create(MK_CONTACT_CACHE_MAX_CAPACITY + 1, NULL, &c), MK_ERR_BAD_SIZE);
    MK_ASSERT_STATUS(mk_contact_cache_create(4, NULL, NULL), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_contact_cache_create(4, &broken, &c), MK_ERR_NULL);
    ck_assert_ptr_null(c);
    k.fail = 1;
    MK_ASSERT_STATUS(mk_contact_cache_create(4, &al, &c), MK_ERR_OUT_OF_MEMORY);
    ck_assert_ptr_null(c);
    k.fail = 0;
    MK_ASSERT_STATUS(mk_contact_cache_create(16, &al, &c), MK_OK);
    ck_assert_int_eq(k.allocs, 1);
    /* Steady state: many frames of stores and lookups, no further allocation. */
    for (f = 0; f < 100; ++f) {
        MK_ASSERT_STATUS(mk_contact_cache_begin_frame(c), MK_OK);
        for (i = 0; i < 16; ++i) {
            MK_ASSERT_STATUS(mk_contact_cache_lookup(c, key(1, 2, i, f % 3), &out, NULL), MK_OK);
            MK_ASSERT_STATUS(mk_contact_cache_store(c, key(1, 2, i, f % 3), imp(1, 2, 3)), MK_OK);
        }
    }
    ck_assert_int_eq(k.allocs, 1);
    MK_ASSERT_STATUS(mk_contact_cache_store(c, key(1, 2, 0, 0), imp((mk_real)NAN, 0, 0)), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_contact_cache_store(c, key(1, 2, 0, 0), imp(0, (mk_real)INFINITY, 0)), MK_ERR_NOT_FINITE);
    MK_ASSERT_STATUS(mk_contact_cache_store(NULL, key(1, 2, 0, 0), imp(0, 0, 0)), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_contact_cache_lookup(NULL, key(1, 2, 0, 0), &out, NULL), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_contact_cache_lookup(c, key(1, 2, 0, 0), NULL, NULL), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_contact_cache_begin_frame(NULL), MK_ERR_NULL);
    MK_ASSERT_STATUS(mk_contact_cache_entry(NULL, 0, NULL, &out), MK_ERR_NULL);
    ck_assert_int_eq(mk_contact_cache_count(NULL), 0);
    ck_assert_int_eq(mk_contact_cache_capacity(NULL), 0);
    mk_contact_cache_destroy(c);
    mk_contact_cache_destroy(NULL);
    ck_assert_int_eq(k.frees, 1);
    ck_assert_int_eq((int)k.live, 0);
}
END_TEST

static Suite *cache_suite(void)
{
    Suite *s = suite_create("contact_cache");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, key_compare_and_hash);
    tcase_add_test(tc, lookup_store_evict);
    tcase_add_test(tc, iteration_order_and_replace);
    tcase_add_test(tc, capacity_overflow);
    tcase_add_test(tc, churn_matches_model);
    tcase_add_test(tc, allocator_and_bad_input);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return mk_test_run(cache_suite()); }

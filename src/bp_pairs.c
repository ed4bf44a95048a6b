/* bp_pairs.c: the pair table every broadphase structure reports into.
 *
 * Why one table for all structures: the events and the sorted set come out
 * the same whichever structure found the pairs, AUTO can switch structures
 * without a glitch in the events, and a failed update can be repaired by a
 * full recount that is diffed against what the caller last saw.
 * Entries are dense (cache-friendly scans for the grid's per-frame test and
 * for destroy), found through a linear-probing index keyed by a multiplicative
 * hash of (low slot, high slot). Only entries touched in an update are looked
 * at when events are made, so a quiet frame costs nothing here. */
#include <string.h>

#include "broadphase_internal.h"

#define MK_EMPTY_ UINT32_MAX

static uint32_t index_size_for(int cap)
{
    uint32_t n = 16;
    while (n < (uint32_t)cap * 2u) n <<= 1;
    return n;
}

static uint32_t hash_key(uint64_t key, uint32_t mask)
{
    /* Fibonacci hashing: the high bits of key * 2^64/phi mix both slots well. */
    return (uint32_t)((key * 0x9E3779B97F4A7C15ull) >> 32) & mask;
}

static void index_rebuild(mk_pair_table *t)
{
    int i;
    memset(t->index, 0xff, (size_t)(t->index_mask + 1) * sizeof *t->index);
    for (i = 0; i < t->count; ++i) {
        uint32_t h = hash_key(t->e[i].key, t->index_mask);
        while (t->index[h] != MK_EMPTY_) h = (h + 1) & t->index_mask;
        t->index[h] = (uint32_t)i;
    }
}

/* Every array of the table, so allocation and growth treat them alike. */
typedef struct arrays_ { void **p; size_t elem; } arrays_;
static int table_arrays(mk_pair_table *t, arrays_ *a)
{
    int n = 0;
    a[n].p = (void **)&t->e; a[n++].elem = sizeof *t->e;
    a[n].p = (void **)&t->touched; a[n++].elem = sizeof *t->touched;
    a[n].p = (void **)&t->scratch; a[n++].elem = sizeof *t->scratch;
    a[n].p = (void **)&t->scratch2; a[n++].elem = sizeof *t->scratch2;
    a[n].p = (void **)&t->set; a[n++].elem = sizeof *t->set;
    a[n].p = (void **)&t->set_next; a[n++].elem = sizeof *t->set_next;
    a[n].p = (void **)&t->added; a[n++].elem = sizeof *t->added;
    a[n].p = (void **)&t->removed; a[n++].elem = sizeof *t->removed;
    return n;
}

/* All-or-nothing: on failure the table keeps its old arrays. */
static mk_status table_resize(mk_bp *bp, int new_cap)
{
    mk_pair_table *t = &bp->pairs;
    arrays_ a[8];
    void *fresh[9];
    int n = table_arrays(t, a), i;
    uint32_t isize = index_size_for(new_cap);
    for (i = 0; i < n; ++i) {
        fresh[i] = mk_bp_alloc_(bp, a[i].elem * (size_t)new_cap);
        if (!fresh[i]) break;
    }
    if (i == n) fresh[n] = mk_bp_alloc_(bp, isize * sizeof(uint32_t));
    if (i < n || !fresh[n]) {
        int j;
        for (j = 0; j < i; ++j) mk_bp_free_(bp, fresh[j], a[j].elem * (size_t)new_cap);
        return MK_ERR_OUT_OF_MEMORY;
    }
    for (i = 0; i < n; ++i) {
        if (*a[i].p) {
            memcpy(fresh[i], *a[i].p, a[i].elem * (size_t)t->cap);
            mk_bp_free_(bp, *a[i].p, a[i].elem * (size_t)t->cap);
        }
        *a[i].p = fresh[i];
    }
    if (t->index) mk_bp_free_(bp, t->index, (size_t)(t->index_mask + 1) * sizeof(uint32_t));
    t->index = (uint32_t *)fresh[n];
    t->index_mask = isize - 1;
    t->cap = new_cap;
    index_rebuild(t);
    return MK_OK;
}

mk_status mk_pairs_init_(mk_bp *bp, int cap)
{
    memset(&bp->pairs, 0, sizeof bp->pairs);
    return table_resize(bp, cap < 16 ? 16 : cap);
}

void mk_pairs_fini_(mk_bp *bp)
{
    mk_pair_table *t = &bp->pairs;
    arrays_ a[8];
    int n = table_arrays(t, a), i;
    for (i = 0; i < n; ++i)
        if (*a[i].p) mk_bp_free_(bp, *a[i].p, a[i].elem * (size_t)t->cap);
    if (t->index) mk_bp_free_(bp, t->index, (size_t)(t->index_mask + 1) * sizeof(uint32_t));
    memset(t, 0, sizeof *t);
}

static uint32_t *find_slot(mk_pair_table *t, uint64_t key)
{
    uint32_t h = hash_key(key, t->index_mask);
    for (;;) {
        uint32_t i = t->index[h];
        if (i == MK_EMPTY_ || t->e[i].key == key) return &t->index[h];
        h = (h + 1) & t->index_mask;
    }
}

static mk_pair_entry *find(mk_pair_table *t, uint64_t key)
{
    uint32_t i = *find_slot(t, key);
    return i == MK_EMPTY_ ? NULL : &t->e[i];
}

static mk_pair_entry *insert(mk_bp *bp, uint64_t key, mk_status *st)
{
    mk_pair_table *t = &bp->pairs;
    uint32_t *s;
    if (t->count == t->cap) {
        if (bp->def.fixed_capacity) { *st = MK_ERR_CAPACITY; return NULL; }
        if (t->cap > INT32_MAX / 2 || (*st = table_resize(bp, t->cap * 2)) != MK_OK) {
            if (*st == MK_OK) *st = MK_ERR_CAPACITY;
            return NULL;
        }
    }
    s = find_slot(t, key);
    *s = (uint32_t)t->count;
    t->e[t->count].key = key;
    t->e[t->count].state = 0;
    t->e[t->count].wake = 0;
    return &t->e[t->count++];
}

/* Backward-shift deletion keeps every probe chain unbroken without tombstones. */
static void erase(mk_pair_table *t, uint64_t key)
{
    uint32_t *s = find_slot(t, key), hole, j, idx, last;
    if (*s == MK_EMPTY_) return;
    idx = *s;
    hole = (uint32_t)(s - t->index);
    j = hole;
    for (;;) {
        uint32_t k, home;
        j = (j + 1) & t->index_mask;
        k = t->index[j];
        if (k == MK_EMPTY_) break;
        home = hash_key(t->e[k].key, t->index_mask);
        /* Move k into the hole unless its home lies cyclically in (hole, j]. */
        if (((j - home) & t->index_mask) >= ((j - hole) & t->index_mask)) {
            t->index[hole] = k;
            hole = j;
        }
    }
    t->index[hole] = MK_EMPTY_;
    last = (uint32_t)--t->count;
    if (idx != last) {
        t->e[idx] = t->e[last];
        *find_slot(t, t->e[idx].key) = idx;
    }
}

void mk_pairs_touch_(mk_bp *bp, mk_pair_entry *e)
{
    mk_pair_table *t = &bp->pairs;
    if (e->state & MK_PS_TOUCHED) return;
    e->state |= MK_PS_TOUCHED;
    t->touched[t->touched_count++] = (uint32_t)(e - t->e);
}

mk_pair_entry *mk_pairs_get_(mk_bp *bp, uint32_t a, uint32_t b, mk_status *st)
{
    uint64_t key = mk_pair_key_(a, b);
    mk_pair_entry *e = find(&bp->pairs, key);
    return e ? e : insert(bp, key, st);
}

static int refiltered(const mk_bp *bp, uint32_t a, uint32_t b)
{
    return ((bp->flags[a] | bp->flags[b]) & MK_PF_REFILTER) != 0;
}

mk_status mk_pairs_add_(mk_bp *bp, uint32_t a, uint32_t b)
{
    mk_status st = MK_OK;
    mk_pair_entry *e = find(&bp->pairs, mk_pair_key_(a, b));
    if (e && (e->state & MK_PS_LIVE)) return MK_OK;
    if (!mk_bp_filter_keeps_(bp, a, b)) return MK_OK;
    if (!e && !(e = insert(bp, mk_pair_key_(a, b), &st))) return st;
    e->state |= MK_PS_LIVE;
    mk_pairs_touch_(bp, e);
    return MK_OK;
}

void mk_pairs_remove_(mk_bp *bp, uint32_t a, uint32_t b)
{
    mk_pair_entry *e = find(&bp->pairs, mk_pair_key_(a, b));
    if (!e || !(e->state & MK_PS_LIVE)) return;
    e->state &= ~(uint32_t)MK_PS_LIVE;
    mk_pairs_touch_(bp, e);
}

void mk_pairs_drop_flagged_(mk_bp *bp, uint8_t flags)
{
    mk_pair_table *t = &bp->pairs;
    int i;
    for (i = 0; i < t->count; ++i) {
        mk_pair_entry *e = &t->e[i];
        uint32_t a = (uint32_t)(e->key >> 32), b = (uint32_t)e->key;
        if ((e->state & MK_PS_LIVE) && ((bp->flags[a] | bp->flags[b]) & flags)) {
            e->state &= ~(uint32_t)MK_PS_LIVE;
            mk_pairs_touch_(bp, e);
        }
    }
}

/* A full recount does not go through the entries: the new set is collected
 * as keys, sorted, and diffed against the set the caller last saw. Only then
 * is the table refilled, so the old and the new set never have to fit in it
 * together (that is what lets a rebuild recover from a capacity overflow). */
void mk_pairs_full_begin_(mk_bp *bp)
{
    bp->pairs.full = 1;
    bp->pairs.full_count = 0;
}

static mk_bp_pair pair_of(const mk_bp *bp, uint64_t key);
static int pair_less(mk_bp_pair x, mk_bp_pair y);

static mk_status push_key(mk_bp *bp, uint64_t key)
{
    mk_pair_table *t = &bp->pairs;
    if (t->full_count == t->cap) {
        mk_status st;
        if (bp->def.fixed_capacity) return MK_ERR_CAPACITY;
        if (t->cap > INT32_MAX / 2) return MK_ERR_CAPACITY;
        if ((st = table_resize(bp, t->cap * 2)) != MK_OK) return st;
    }
    t->scratch[t->full_count++] = key;
    return MK_OK;
}

mk_status mk_pairs_full_add_(mk_bp *bp, uint32_t a, uint32_t b)
{
    uint64_t key = mk_pair_key_(a, b);
    mk_pair_entry *e = find(&bp->pairs, key);
    if (!(e && (e->state & MK_PS_LIVE) && !refiltered(bp, a, b)) && !mk_bp_filter_keeps_(bp, a, b)) return MK_OK;
    return push_key(bp, key);
}

/* Prefix sums of per-slot counts: c[s] becomes the first position of slot s. */
static void bucket_starts(uint32_t *c, int slots)
{
    uint32_t sum = 0;
    int s;
    for (s = 0; s < slots; ++s) { uint32_t v = c[s]; c[s] = sum; sum += v; }
}

/* The set, sorted, from n unsorted pairs of slots (a < b) with a few pairs
 * per slot: two stable counting sorts (by the higher slot into keys, then
 * by the lower one, writing the pairs themselves). Four sequential passes
 * and two scatters, with no branch on the data: cheaper than sorting each
 * lower slot's bucket, whose sizes vary from pair to pair and mislead the
 * branch predictor. */
static void set_by_counting(mk_bp *bp, const mk_bp_pair *p, uint64_t *tmp, int n)
{
    mk_pair_table *t = &bp->pairs;
    uint32_t *c = bp->bucket;
    int i, slots = bp->hi_slot;
    memset(c, 0, (size_t)slots * sizeof *c);
    for (i = 0; i < n; ++i) c[p[i].b]++;
    bucket_starts(c, slots);
    for (i = 0; i < n; ++i) tmp[c[p[i].b]++] = (uint64_t)p[i].a << 32 | p[i].b;
    memset(c, 0, (size_t)slots * sizeof *c);
    for (i = 0; i < n; ++i) c[tmp[i] >> 32]++;
    bucket_starts(c, slots);
    for (i = 0; i < n; ++i) t->set[c[tmp[i] >> 32]++] = pair_of(bp, tmp[i]);
}

/* The table is emptied (once, when a run of such updates starts); the pairs
 * found are the new set, with no events. */
mk_status mk_pairs_set_from_(mk_bp *bp, const mk_bp_pair *found, int n)
{
    mk_pair_table *t = &bp->pairs;
    int i, m;
    mk_status st;
    while (t->cap < n) {
        if (bp->def.fixed_capacity || t->cap > INT32_MAX / 2) return MK_ERR_CAPACITY;
        if ((st = table_resize(bp, t->cap * 2)) != MK_OK) return st;
    }
    if (t->count) {
        t->count = 0;
        memset(t->index, 0xff, (size_t)(t->index_mask + 1) * sizeof *t->index);
    }
    t->touched_count = 0;
    if (bp->def.filter_mode != MK_BP_FILTER_NONE || bp->def.filter) { /* the kept ones, once each */
        for (i = m = 0; i < n; ++i)
            if (mk_bp_filter_pass_(bp, found[i].a, found[i].b)) t->set_next[m++] = found[i];
        found = t->set_next;
        n = m;
    }
    if (n >= bp->hi_slot / 2) {
        set_by_counting(bp, found, t->scratch, n);
    } else {
        for (i = 0; i < n; ++i) t->scratch[i] = (uint64_t)found[i].a << 32 | found[i].b;
        mk_sort_u64_(t->scratch, t->scratch2, n);
        for (i = 0; i < n; ++i) t->set[i] = pair_of(bp, t->scratch[i]);
    }
    t->set_count = n;
    t->added_count = t->removed_count = 0;
    t->full = 2; /* mk_pairs_finish_ has nothing to add */
    return MK_OK;
}

/* keys[0, n) sorted: the new set. Events are its difference from the old set. */
static void diff_against_set(mk_bp *bp, const uint64_t *keys, int n)
{
    mk_pair_table *t = &bp->pairs;
    int i = 0, j = 0;
    mk_bp_pair *sw;
    for (i = 0; i < n; ++i) t->set_next[i] = pair_of(bp, keys[i]);
    t->added_count = t->removed_count = 0;
    for (i = 0; i < t->set_count || j < n;) {
        if (j >= n || (i < t->set_count && pair_less(t->set[i], t->set_next[j]))) t->removed[t->removed_count++] = t->set[i++];
        else if (i >= t->set_count || pair_less(t->set_next[j], t->set[i])) t->added[t->added_count++] = t->set_next[j++];
        else { ++i; ++j; }
    }
    sw = t->set; t->set = t->set_next; t->set_next = sw;
    t->set_count = n;
}

void mk_pairs_full_end_(mk_bp *bp)
{
    mk_pair_table *t = &bp->pairs;
    int i, n = t->full_count;
    mk_sort_pairs_(bp, t->scratch, t->scratch2, n);
    diff_against_set(bp, t->scratch, n);
    t->count = 0;
    t->touched_count = 0;
    memset(t->index, 0xff, (size_t)(t->index_mask + 1) * sizeof *t->index);
    for (i = 0; i < n; ++i) {
        *find_slot(t, t->scratch[i]) = (uint32_t)i;
        t->e[i].key = t->scratch[i];
        t->e[i].state = MK_PS_LIVE | MK_PS_REPORTED;
        t->e[i].wake = 0;
    }
    t->count = n;
    t->full = 2; /* events are made: mk_pairs_finish_ has nothing to add */
}

void mk_pairs_forget_(mk_bp *bp)
{
    mk_pair_table *t = &bp->pairs;
    t->count = 0;
    t->touched_count = 0;
    memset(t->index, 0xff, (size_t)(t->index_mask + 1) * sizeof *t->index);
    t->full = 3;
}

/* After mk_pairs_forget_: the live entries are the new set, diffed as a whole. */
static void finish_forgotten(mk_bp *bp)
{
    mk_pair_table *t = &bp->pairs;
    int i, n = 0, nd = 0;
    for (i = 0; i < t->count; ++i)
        if (t->e[i].state & MK_PS_LIVE) t->scratch[n++] = t->e[i].key;
    mk_sort_pairs_(bp, t->scratch, t->scratch2, n);
    diff_against_set(bp, t->scratch, n);
    for (i = 0; i < t->count; ++i) {
        uint32_t st = t->e[i].state & ~(uint32_t)(MK_PS_TOUCHED | MK_PS_REPORTED);
        if (st & MK_PS_LIVE) st |= MK_PS_REPORTED;
        t->e[i].state = st;
        if (!(st & MK_PS_KEEP)) t->scratch2[nd++] = t->e[i].key;
    }
    t->touched_count = 0;
    for (i = 0; i < nd; ++i) erase(t, t->scratch2[i]);
}

void mk_sort_u64_(uint64_t *keys, uint64_t *tmp, int n) { mk_sort_u64_by_(keys, tmp, n, 0); }

/* Pair keys have two slots, so a radix sort makes a pass per byte of each
 * (four with 10k proxies). A set has a few pairs per proxy: bucketing by
 * the lower slot (one count, one scatter) and sorting each bucket's few
 * higher slots costs two passes instead. Buckets of many pairs (a ground
 * plane's) are radix-sorted, so no bucket costs more than O(k) passes. */
#define MK_SMALL_BUCKET_ 16
static void sort_bucket(uint64_t *b, uint64_t *tmp, int k)
{
    int i, j;
    if (k > MK_SMALL_BUCKET_) { mk_sort_u64_(b, tmp, k); return; }
    for (i = 1; i < k; ++i) {
        uint64_t v = b[i];
        for (j = i; j > 0 && b[j - 1] > v; --j) b[j] = b[j - 1];
        b[j] = v;
    }
}

void mk_sort_pairs_(mk_bp *bp, uint64_t *keys, uint64_t *tmp, int n)
{
    uint32_t *c = bp->bucket, start = 0;
    int s, i, slots = bp->hi_slot;
    if (n < slots / 2) { mk_sort_u64_(keys, tmp, n); return; }
    memset(c, 0, (size_t)slots * sizeof *c);
    for (i = 0; i < n; ++i) c[keys[i] >> 32]++;
    bucket_starts(c, slots);
    for (i = 0; i < n; ++i) tmp[c[keys[i] >> 32]++] = keys[i];
    /* now c[s] is the end of bucket s; keys is free to serve as scratch */
    for (s = 0; s < slots; start = c[s++])
        if (c[s] - start > 1) sort_bucket(tmp + start, keys + start, (int)(c[s] - start));
    memcpy(keys, tmp, (size_t)n * sizeof *keys);
}

void mk_sort_u64_by_(uint64_t *keys, uint64_t *tmp, int n, int from_byte)
{
    /* LSD radix sort on bytes, skipping bytes that are equal in every key
     * (slot numbers use few bits, so most passes are skipped). Stable. */
    uint64_t all_or = 0, all_and = ~(uint64_t)0, *src = keys, *dst = tmp, *sw;
    int shift, i;
    for (i = 0; i < n; ++i) { all_or |= keys[i]; all_and &= keys[i]; }
    for (shift = 8 * from_byte; shift < 64; shift += 8) {
        size_t count[256], sum = 0;
        int d;
        if ((((all_or ^ all_and) >> shift) & 0xff) == 0) continue;
        memset(count, 0, sizeof count);
        for (i = 0; i < n; ++i) count[(src[i] >> shift) & 0xff]++;
        for (d = 0; d < 256; ++d) { size_t c = count[d]; count[d] = sum; sum += c; }
        for (i = 0; i < n; ++i) dst[count[(src[i] >> shift) & 0xff]++] = src[i];
        sw = src; src = dst; dst = sw;
    }
    if (src != keys) memcpy(keys, src, (size_t)n * sizeof *keys);
}

static mk_bp_pair pair_of(const mk_bp *bp, uint64_t key)
{
    mk_bp_pair p;
    p.a = mk_bp_id_of_(bp, (uint32_t)(key >> 32));
    p.b = mk_bp_id_of_(bp, (uint32_t)key);
    return p;
}

static int pair_less(mk_bp_pair x, mk_bp_pair y) { return x.a < y.a || (x.a == y.a && x.b < y.b); }

/* First index in set[from, n) not below p, galloping from `from`: events
 * are sorted, so each search costs the log of the distance to the last. */
static int lower_bound(const mk_bp_pair *set, int from, int n, mk_bp_pair p)
{
    int step = 1, hi = from;
    while (hi < n && pair_less(set[hi], p)) { from = hi + 1; hi = from + step; step *= 2; }
    if (hi > n) hi = n;
    while (from < hi) {
        int mid = from + (hi - from) / 2;
        if (pair_less(set[mid], p)) from = mid + 1;
        else hi = mid;
    }
    return from;
}

/* set_next = (set - removed) + added; all three sorted, removed within set,
 * added disjoint from it. Runs between events are block copies: a frame
 * with few changes costs a memcpy of the set, not a comparison per pair. */
static void merge_set(mk_pair_table *t)
{
    int i = 0, r = 0, a = 0, o = 0, j;
    mk_bp_pair *sw;
    while (r < t->removed_count || a < t->added_count) {
        int take_removed = a >= t->added_count || (r < t->removed_count && pair_less(t->removed[r], t->added[a]));
        mk_bp_pair next = take_removed ? t->removed[r] : t->added[a];
        j = lower_bound(t->set, i, t->set_count, next);
        memcpy(t->set_next + o, t->set + i, (size_t)(j - i) * sizeof *t->set);
        o += j - i;
        i = j;
        if (take_removed) { ++i; ++r; }  /* set[i] is the removed pair */
        else t->set_next[o++] = t->added[a++];
    }
    memcpy(t->set_next + o, t->set + i, (size_t)(t->set_count - i) * sizeof *t->set);
    o += t->set_count - i;
    sw = t->set; t->set = t->set_next; t->set_next = sw;
    t->set_count = o;
}

mk_status mk_pairs_finish_(mk_bp *bp)
{
    mk_pair_table *t = &bp->pairs;
    int i, na = 0, nr = 0, nd = 0;
    uint64_t *rem = t->scratch + t->cap; /* removed keys grow down from the end */
    if (t->full == 2) { t->full = 0; return MK_OK; }
    if (t->full == 3) { t->full = 0; finish_forgotten(bp); return MK_OK; }
    t->full = 0;
    for (i = 0; i < t->touched_count; ++i) {
        const mk_pair_entry *e = &t->e[t->touched[i]];
        int live = (e->state & MK_PS_LIVE) != 0, rep = (e->state & MK_PS_REPORTED) != 0;
        if (live && !rep) t->scratch[na++] = e->key;
        else if (!live && rep) *--rem = e->key, ++nr;
    }
    mk_sort_pairs_(bp, t->scratch, t->scratch2, na);
    mk_sort_pairs_(bp, rem, t->scratch2, nr);
    for (i = 0; i < na; ++i) t->added[i] = pair_of(bp, t->scratch[i]);
    for (i = 0; i < nr; ++i) t->removed[i] = pair_of(bp, rem[i]);
    t->added_count = na;
    t->removed_count = nr;
    merge_set(t);
    for (i = 0; i < t->touched_count; ++i) {
        mk_pair_entry *e = &t->e[t->touched[i]];
        uint32_t s = e->state & ~(uint32_t)(MK_PS_TOUCHED | MK_PS_REPORTED);
        if (s & MK_PS_LIVE) s |= MK_PS_REPORTED;
        e->state = s;
        if (!(s & MK_PS_KEEP)) t->scratch2[nd++] = e->key;
    }
    t->touched_count = 0;
    for (i = 0; i < nd; ++i) erase(t, t->scratch2[i]);
    return MK_OK;
}

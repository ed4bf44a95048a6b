// broadphase.cpp: btBroadphaseInterface on a Minko broadphase (see minko_bullet.h).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <new>

#include "minko_bullet.h"

namespace mkb {

struct Broadphase::Proxy : public btBroadphaseProxy {
    Proxy(const btVector3 &lo, const btVector3 &hi, void *user, int group, int mask)
        : btBroadphaseProxy(lo, hi, user, group, mask) {}
    mk_bp_id id = MK_BP_NULL_ID;
    int index = -1;       // in m_proxies
    bool is_static = false;
    bool dirty = false;   // in m_dirty: Minko's structure may not know its box yet
    // The box filed in Minko: m_aabbMin/Max (Bullet's box) grown by the
    // margin when it last left the box filed before, as Dbvt's fat leaves.
    btVector3 fat_lo, fat_hi;
};

namespace {

// Bullet's btHashedOverlappingPairCache with the same deterministic dispatch
// (pairs visited in descending (uid0, uid1) order, which is what Bullet's
// quicksort with its ">" predicate gives, and Bullet's loop as it is: a pair
// removed by the callback is followed by whatever the removal moved into its
// place) without Bullet's quicksort of every pair every step. The pair array
// only changes through addOverlappingPair (appends) and removeOverlappingPair
// (moves the last pair into the hole), both overridden here to track where
// each ordered pair sits, so a step in which no pair came or went costs
// nothing, and after changes the surviving order is kept, the new pairs are
// sorted among themselves and merged in: O(n + k log k) for k new pairs, a
// radix sort on keys packed to the uids' width when most pairs are new (the
// first step). Keys are unique, so the order is exactly the sorted order of
// the current pairs, Bullet's, whatever the history. Memory: a few arrays of
// the pair count, grown by doubling, reused every step.
class PairCache : public btHashedOverlappingPairCache {
public:
    using btHashedOverlappingPairCache::processAllOverlappingPairs;
    void processAllOverlappingPairs(btOverlapCallback *callback, btDispatcher *dispatcher,
                                    const btDispatcherInfo &info) override
    {
        if (!info.m_deterministicOverlappingPairs) {
            btHashedOverlappingPairCache::processAllOverlappingPairs(callback, dispatcher, info);
            return;
        }
        btBroadphasePairArray &pa = getOverlappingPairArray();
        if (m_changed) update_order(pa);
        // m_walk holds the indices in ascending key order as the walk
        // began (Bullet's index list): walk it from the end.
        for (size_t i = m_walk.size(); i > 0;) {
            const int at = m_walk[i - 1];
            if (at >= pa.size()) {  // a removal emptied this place
                i--;
                continue;
            }
            btBroadphasePair *pair = &pa[at];
            if (callback->processOverlap(*pair))
                removeOverlappingPair(pair->m_pProxy0, pair->m_pProxy1, dispatcher);
            else
                i--;
        }
    }
    btBroadphasePair *addOverlappingPair(btBroadphaseProxy *proxy0, btBroadphaseProxy *proxy1) override
    {
        const int before = getNumOverlappingPairs();
        btBroadphasePair *pair = btHashedOverlappingPairCache::addOverlappingPair(proxy0, proxy1);
        if (getNumOverlappingPairs() > before) {  // appended at `before`
            m_pos.push_back(kNew);
            m_new_count++;
            m_changed = true;
        }
        return pair;
    }
    void *removeOverlappingPair(btBroadphaseProxy *proxy0, btBroadphaseProxy *proxy1, btDispatcher *dispatcher) override
    {
        const btBroadphasePair *pair = findPair(proxy0, proxy1);
        if (pair) {
            const int at = (int)(pair - &getOverlappingPairArray()[0]);
            forget(at);
        }
        return btHashedOverlappingPairCache::removeOverlappingPair(proxy0, proxy1, dispatcher);
    }

private:
    struct Entry {
        unsigned u0, u1;  // uids (+ 1)
        int index;        // the pair's place in the pair array; kGone once removed
    };
    enum : int {
        kNew = -1,  // m_pos of a pair not ordered yet
        kGone = -1  // Entry::index of a removed pair
    };
    static bool before(const Entry &a, const Entry &b) { return a.u0 != b.u0 ? a.u0 < b.u0 : a.u1 < b.u1; }
    // Bullet orders a missing proxy (uid -1) last: uid + 1.
    static unsigned uid_of(const btBroadphaseProxy *p) { return (unsigned)((p ? p->m_uniqueId : -1) + 1); }
    static Entry entry_of(const btBroadphasePairArray &pa, int i)
    {
        return Entry{uid_of(pa[i].m_pProxy0), uid_of(pa[i].m_pProxy1), i};
    }

    // The pair at `at` is about to be removed: the last pair moves there.
    void forget(int at)
    {
        m_changed = true;
        const int last = (int)m_pos.size() - 1;
        if (at < 0 || at > last) {  // not tracked: rebuild from scratch
            m_pos.clear();
            return;
        }
        if (m_pos[(size_t)at] == kNew) m_new_count--;
        else m_order[(size_t)m_pos[(size_t)at]].index = kGone;
        if (at != last) {
            m_pos[(size_t)at] = m_pos[(size_t)last];
            if (m_pos[(size_t)at] != kNew) m_order[(size_t)m_pos[(size_t)at]].index = at;
        }
        m_pos.pop_back();
    }

    void update_order(const btBroadphasePairArray &pa)
    {
        m_changed = false;
        const int n = pa.size();
        if ((int)m_pos.size() != n || m_new_count > n / 4) {
            // Untracked changes, or mostly new pairs: sort them all.
            radix_sort(pa);
        } else {
            m_keep.clear();
            for (const Entry &e : m_order)
                if (e.index != kGone) m_keep.push_back(e);
            m_new.clear();
            for (int i = 0; i < n && (int)m_new.size() < m_new_count; i++)
                if (m_pos[(size_t)i] == kNew) m_new.push_back(entry_of(pa, i));
            std::sort(m_new.begin(), m_new.end(), before);
            m_order.resize((size_t)n);
            std::merge(m_keep.begin(), m_keep.end(), m_new.begin(), m_new.end(), m_order.begin(), before);
        }
        m_new_count = 0;
        m_pos.resize((size_t)n);
        m_walk.resize((size_t)n);
        for (int k = 0; k < n; k++) {
            m_pos[(size_t)m_order[(size_t)k].index] = k;
            m_walk[(size_t)k] = m_order[(size_t)k].index;
        }
    }

    void radix_sort(const btBroadphasePairArray &pa)
    {
        const size_t n = (size_t)pa.size();
        m_order.resize(n);
        m_keep.resize(n);
        m_keys.resize(n);
        m_tmp_keys.resize(n);
        unsigned top = 0;
        for (size_t i = 0; i < n; i++) {
            m_order[i] = entry_of(pa, (int)i);
            top = std::max(top, std::max(m_order[i].u0, m_order[i].u1));
        }
        int bits = 1;
        while (bits < 32 && (top >> bits) != 0) bits++;
        for (size_t i = 0; i < n; i++) m_keys[i] = (unsigned long long)m_order[i].u0 << bits | m_order[i].u1;
        for (int shift = 0; shift < 2 * bits; shift += 8) {
            size_t count[256] = {};
            for (size_t i = 0; i < n; i++) count[(m_keys[i] >> shift) & 255]++;
            size_t at = 0;
            for (size_t &c : count) {
                const size_t here = c;
                c = at;
                at += here;
            }
            for (size_t i = 0; i < n; i++) {
                const size_t to = count[(m_keys[i] >> shift) & 255]++;
                m_keep[to] = m_order[i];
                m_tmp_keys[to] = m_keys[i];
            }
            m_order.swap(m_keep);
            m_keys.swap(m_tmp_keys);
        }
    }

    std::vector<Entry> m_order;  // every ordered pair, ascending keys (removed ones marked kGone)
    std::vector<int> m_pos;      // by pair index: place in m_order, or kNew
    std::vector<int> m_walk;     // pair indices in m_order's order when it was last updated
    std::vector<Entry> m_keep, m_new;
    std::vector<unsigned long long> m_keys, m_tmp_keys;
    int m_new_count = 0;         // pairs at kNew
    bool m_changed = false;
};

mk_aabb to_aabb(const btVector3 &lo, const btVector3 &hi) { return mk_aabb_make(to_mk(lo), to_mk(hi)); }

// Whether [lo, hi] is a box (lo <= hi, no NaN) inside [in_lo, in_hi]: a bad
// box is not, and goes to Minko, which refuses it.
bool inside(const btVector3 &lo, const btVector3 &hi, const btVector3 &in_lo, const btVector3 &in_hi)
{
    return lo.x() >= in_lo.x() && lo.y() >= in_lo.y() && lo.z() >= in_lo.z() && hi.x() <= in_hi.x() &&
           hi.y() <= in_hi.y() && hi.z() <= in_hi.z() && lo.x() <= hi.x() && lo.y() <= hi.y() && lo.z() <= hi.z();
}

// Segment from + t (to - from), t in [0, 1], against [lo, hi]: closed slabs.
bool segment_hits_box(const btVector3 &from, const btVector3 &to, const btVector3 &lo, const btVector3 &hi)
{
    btScalar t0 = 0, t1 = 1;
    for (int k = 0; k < 3; k++) {
        const btScalar d = to[k] - from[k];
        if (d == 0) {
            if (from[k] < lo[k] || from[k] > hi[k]) return false;
            continue;
        }
        btScalar a = (lo[k] - from[k]) / d, b = (hi[k] - from[k]) / d;
        if (a > b) std::swap(a, b);
        t0 = std::max(t0, a);
        t1 = std::min(t1, b);
        if (t0 > t1) return false;
    }
    return true;
}

// Minko holds the fat boxes: its answers are tested again on Bullet's boxes.
struct QueryCtx {
    btBroadphaseAabbCallback *callback;
    btVector3 lo, hi;
};

int aabb_visit(void *c, mk_bp_id, void *user)
{
    Broadphase::Proxy *p = static_cast<Broadphase::Proxy *>(user);
    QueryCtx *q = static_cast<QueryCtx *>(c);
    if (!p->dirty && TestAabbAgainstAabb2(q->lo, q->hi, p->m_aabbMin, p->m_aabbMax)) q->callback->process(p);
    return 1;
}

struct RayCtx {
    btBroadphaseRayCallback *callback;
    btVector3 from, to, lo, hi;  // the segment and the swept box
    bool stopped;
};

// Whether the segment meets the proxy's box grown by [-hi, -lo].
bool ray_hits(const RayCtx &r, const Broadphase::Proxy *p)
{
    return segment_hits_box(r.from, r.to, p->m_aabbMin - r.hi, p->m_aabbMax - r.lo);
}

mk_real ray_visit(void *c, mk_bp_id, void *user, mk_real, mk_real max)
{
    Broadphase::Proxy *p = static_cast<Broadphase::Proxy *>(user);
    RayCtx *r = static_cast<RayCtx *>(c);
    if (p->dirty || !ray_hits(*r, p)) return max;  // dirty ones: tested by rayTest itself
    if (!r->callback->process(p)) {
        r->stopped = true;
        return -1;
    }
    return max;
}

}  // namespace

Broadphase::Broadphase(mk_bp_kind kind, btHashedOverlappingPairCache *cache, int initial_capacity, btScalar margin)
    : m_kind(kind),
      m_capacity(std::max(initial_capacity, 16)),
      m_margin(std::isfinite(margin) && margin > 0 ? margin : 0),
      m_cache(cache),
      m_own_cache(cache == nullptr)
{
    if (m_own_cache) m_cache = new (btAlignedAlloc(sizeof(PairCache), 16)) PairCache();
    note(rebuild(m_capacity));
}

Broadphase::~Broadphase()
{
    // The world normally destroyed every proxy already; free what is left.
    for (Proxy *p : m_proxies) delete p;
    mk_bp_destroy(m_bp);
    if (m_own_cache) {
        m_cache->~btHashedOverlappingPairCache();
        btAlignedFree(m_cache);
    }
}

// Two proxies whose group is StaticFilter (or 0) and whose masks exclude
// StaticFilter never pass the AND test, so Minko may skip such pairs; with a
// filter callback installed every candidate must be asked.
bool Broadphase::may_be_minko_static(int group, int mask) const
{
    return (group & ~btBroadphaseProxy::StaticFilter) == 0 && (mask & btBroadphaseProxy::StaticFilter) == 0 &&
           m_cache->getOverlapFilterCallback() == nullptr;
}

// (Re)creates the Minko broadphase with room for `capacity` proxies and files
// every live proxy in it; the next update then reconciles the whole pair set.
mk_status Broadphase::rebuild(int capacity)
{
    mk_bp_def def = mk_bp_default_def();
    def.kind = m_kind;
    def.proxy_capacity = capacity;
    mk_bp *bp = nullptr;
    mk_status st = mk_bp_create(&def, nullptr, &bp);
    if (st != MK_OK) return st;
    for (Proxy *p : m_proxies) {
        p->is_static = may_be_minko_static(p->m_collisionFilterGroup, p->m_collisionFilterMask);
        st = mk_bp_create_proxy(bp, to_aabb(p->fat_lo, p->fat_hi), p, 0, 0, p->is_static, &p->id);
        if (st != MK_OK) {
            mk_bp_destroy(bp);
            return st;
        }
    }
    mk_bp_destroy(m_bp);
    m_bp = bp;
    m_capacity = capacity;
    m_filter_seen = m_cache->getOverlapFilterCallback();
    m_reconcile = true;
    // The new structure knows no box until its first update.
    m_dirty = m_proxies;
    for (Proxy *p : m_dirty) p->dirty = true;
    return MK_OK;
}

btBroadphaseProxy *Broadphase::createProxy(const btVector3 &aabbMin, const btVector3 &aabbMax, int shapeType,
                                           void *userPtr, int collisionFilterGroup, int collisionFilterMask,
                                           btDispatcher *dispatcher)
{
    (void)shapeType;
    (void)dispatcher;
    if (!m_bp) return nullptr;
    if ((int)m_proxies.size() >= m_capacity) {
        mk_status st = rebuild(2 * m_capacity);
        if (st != MK_OK) {
            note(st);
            return nullptr;
        }
    }
    Proxy *p = new Proxy(aabbMin, aabbMax, userPtr, collisionFilterGroup, collisionFilterMask);
    p->is_static = may_be_minko_static(collisionFilterGroup, collisionFilterMask);
    fatten(aabbMin, aabbMax, p->fat_lo, p->fat_hi);
    mk_status st = mk_bp_create_proxy(m_bp, to_aabb(p->fat_lo, p->fat_hi), p, 0, 0, p->is_static, &p->id);
    if (st != MK_OK) {
        note(st);
        delete p;
        return nullptr;
    }
    p->m_uniqueId = ++m_uid;
    p->index = (int)m_proxies.size();
    m_proxies.push_back(p);
    p->dirty = true;
    m_dirty.push_back(p);
    return p;
}

void Broadphase::destroyProxy(btBroadphaseProxy *proxy, btDispatcher *dispatcher)
{
    Proxy *p = static_cast<Proxy *>(proxy);
    // Pairs first: the ghost pair callback still reads m_clientObject.
    m_cache->removeOverlappingPairsContainingProxy(p, dispatcher);
    note(mk_bp_destroy_proxy(m_bp, p->id));
    m_destroyed = true;
    Proxy *last = m_proxies.back();
    m_proxies[p->index] = last;
    last->index = p->index;
    m_proxies.pop_back();
    if (p->dirty) m_dirty.erase(std::find(m_dirty.begin(), m_dirty.end(), p));
    delete p;
}

void Broadphase::setAabb(btBroadphaseProxy *proxy, const btVector3 &aabbMin, const btVector3 &aabbMax,
                         btDispatcher *dispatcher)
{
    (void)dispatcher;
    Proxy *p = static_cast<Proxy *>(proxy);
    // Inside the filed box: Minko's structure and pairs stay as they are.
    if (!inside(aabbMin, aabbMax, p->fat_lo, p->fat_hi)) {
        btVector3 lo = aabbMin, hi = aabbMax;
        if (slow(p, aabbMin, aabbMax)) fatten(aabbMin, aabbMax, lo, hi);
        mk_status st = mk_bp_move_proxy(m_bp, p->id, to_aabb(lo, hi));
        if (st != MK_OK) {  // the proxy keeps its last good boxes
            note(st);
            return;
        }
        p->fat_lo = lo;
        p->fat_hi = hi;
        if (!p->dirty) {
            p->dirty = true;
            m_dirty.push_back(p);
        }
    }
    p->m_aabbMin = aabbMin;
    p->m_aabbMax = aabbMax;
}

// A proxy whose box moved less than the margin since the last call: it may
// come to rest or jitter inside a fat box. One that moved farther leaves any
// fat box at its next move too, and the margin would only give it more pairs
// (callgrind, 3000 boxes, 300 steps, most boxes falling faster than the
// margin a step: fat boxes for every proxy cost 5.69 G instructions in the
// collision phase against 5.50 G for tight ones, 125 M of it dispatching the
// extra pairs).
bool Broadphase::slow(const Proxy *p, const btVector3 &lo, const btVector3 &hi) const
{
    const btVector3 a = (lo - p->m_aabbMin).absolute(), b = (hi - p->m_aabbMax).absolute();
    return a.x() <= m_margin && a.y() <= m_margin && a.z() <= m_margin && b.x() <= m_margin && b.y() <= m_margin &&
           b.z() <= m_margin;
}

// Dbvt's rule (btDbvt::update with a margin): Bullet's box grown by the
// margin on every side. Infinite sides stay infinite.
void Broadphase::fatten(const btVector3 &lo, const btVector3 &hi, btVector3 &fat_lo, btVector3 &fat_hi) const
{
    const btVector3 m(m_margin, m_margin, m_margin);
    fat_lo = lo - m;
    fat_hi = hi + m;
}

void Broadphase::filed_aabb(const btBroadphaseProxy *proxy, btVector3 &aabbMin, btVector3 &aabbMax) const
{
    const Proxy *p = static_cast<const Proxy *>(proxy);
    aabbMin = p->fat_lo;
    aabbMax = p->fat_hi;
}

void Broadphase::getAabb(btBroadphaseProxy *proxy, btVector3 &aabbMin, btVector3 &aabbMax) const
{
    aabbMin = proxy->m_aabbMin;
    aabbMax = proxy->m_aabbMax;
}

void Broadphase::calculateOverlappingPairs(btDispatcher *dispatcher)
{
    // A filter callback installed after static proxies were filed: file them
    // again as ordinary proxies so the callback sees their pairs too.
    if (m_cache->getOverlapFilterCallback() != m_filter_seen) {
        mk_status st = rebuild(m_capacity);
        if (st != MK_OK) note(st);
    }
    // No box filed, no proxy created or destroyed since the last update:
    // Minko's pairs are as they were (a resting scene's usual step).
    if (m_dirty.empty() && !m_destroyed && !m_reconcile) return;
    mk_status st = mk_bp_update(m_bp);
    if (st != MK_OK) {
        note(st);  // Minko stays valid; the next good update catches up
        return;
    }
    for (Proxy *p : m_dirty) p->dirty = false;
    m_dirty.clear();
    m_destroyed = false;
    if (m_reconcile) {
        reconcile(dispatcher);
        return;
    }
    int n = 0;
    const mk_bp_pair *gone = mk_bp_removed(m_bp, &n);
    for (int i = 0; i < n; i++) {
        void *a = mk_bp_user(m_bp, gone[i].a), *b = mk_bp_user(m_bp, gone[i].b);
        if (a && b) m_cache->removeOverlappingPair(static_cast<Proxy *>(a), static_cast<Proxy *>(b), dispatcher);
    }
    const mk_bp_pair *fresh = mk_bp_added(m_bp, &n);
    for (int i = 0; i < n; i++) {
        void *a = mk_bp_user(m_bp, fresh[i].a), *b = mk_bp_user(m_bp, fresh[i].b);
        if (a && b) m_cache->addOverlappingPair(static_cast<Proxy *>(a), static_cast<Proxy *>(b));
    }
}

// After a rebuild Minko's events start from an empty set: bring Bullet's cache
// to Minko's whole set by mark and sweep. Existing pairs keep their algorithm
// and are not filtered again.
void Broadphase::reconcile(btDispatcher *dispatcher)
{
    struct Sweep : btOverlapCallback {
        int frame;
        bool processOverlap(btBroadphasePair &pair) override { return pair.m_internalTmpValue != frame; }
    } sweep;
    sweep.frame = ++m_frame;
    int n = 0;
    const mk_bp_pair *all = mk_bp_pairs(m_bp, &n);
    for (int i = 0; i < n; i++) {
        Proxy *a = static_cast<Proxy *>(mk_bp_user(m_bp, all[i].a)), *b = static_cast<Proxy *>(mk_bp_user(m_bp, all[i].b));
        btBroadphasePair *pair = m_cache->findPair(a, b);
        if (!pair) pair = m_cache->addOverlappingPair(a, b);
        if (pair) pair->m_internalTmpValue = sweep.frame;
    }
    m_cache->processAllOverlappingPairs(&sweep, dispatcher);
    m_reconcile = false;
}

void Broadphase::rayTest(const btVector3 &rayFrom, const btVector3 &rayTo, btBroadphaseRayCallback &rayCallback,
                         const btVector3 &aabbMin, const btVector3 &aabbMax)
{
    // A proxy is hit when the segment meets its box grown by [-aabbMax, -aabbMin]
    // (Dbvt's rule for convex sweeps); the swept box must hold the origin for
    // Minko, and growing it to do so only over-reports, which Bullet allows.
    const btVector3 zero(0, 0, 0);
    btVector3 lo = aabbMin, hi = aabbMax;
    lo.setMin(zero);
    hi.setMax(zero);
    mk_bp_ray ray;
    ray.from = to_mk(rayFrom);
    ray.to = to_mk(rayTo);
    ray.box_lo = to_mk(lo);
    ray.box_hi = to_mk(hi);
    RayCtx ctx = {&rayCallback, rayFrom, rayTo, lo, hi, false};
    mk_status st = mk_bp_raycast(m_bp, &ray, ray_visit, &ctx);
    if (st != MK_OK) note(st);
    for (size_t i = 0; i < m_dirty.size() && !ctx.stopped; i++) {
        Proxy *p = m_dirty[i];
        if (ray_hits(ctx, p) && !rayCallback.process(p)) ctx.stopped = true;
    }
}

void Broadphase::aabbTest(const btVector3 &aabbMin, const btVector3 &aabbMax, btBroadphaseAabbCallback &callback)
{
    QueryCtx ctx = {&callback, aabbMin, aabbMax};
    mk_status st = mk_bp_query_aabb(m_bp, to_aabb(aabbMin, aabbMax), aabb_visit, &ctx);
    if (st != MK_OK) note(st);
    for (Proxy *p : m_dirty)
        if (TestAabbAgainstAabb2(aabbMin, aabbMax, p->m_aabbMin, p->m_aabbMax)) callback.process(p);
}

void Broadphase::getBroadphaseAabb(btVector3 &aabbMin, btVector3 &aabbMax) const
{
    aabbMin.setValue(BT_LARGE_FLOAT, BT_LARGE_FLOAT, BT_LARGE_FLOAT);
    aabbMax.setValue(-BT_LARGE_FLOAT, -BT_LARGE_FLOAT, -BT_LARGE_FLOAT);
    for (const Proxy *p : m_proxies) {
        aabbMin.setMin(p->m_aabbMin);
        aabbMax.setMax(p->m_aabbMax);
    }
}

void Broadphase::resetPool(btDispatcher *dispatcher)
{
    (void)dispatcher;
    if (m_proxies.empty()) m_uid = 0;
}

void Broadphase::printStats()
{
    mk_bp_stats s;
    if (mk_bp_get_stats(m_bp, &s) != MK_OK) return;
    std::printf("mkb::Broadphase: %s (asked %s), %d proxies (%d static), %d pairs, %d rebuilds, %lu bytes\n",
                mk_bp_kind_name(s.kind), mk_bp_kind_name(s.requested), s.proxies, s.static_proxies, s.pairs,
                s.full_rebuilds, (unsigned long)s.bytes);
}

btBroadphaseInterface *set_broadphase(btCollisionWorld *world, btBroadphaseInterface *replacement)
{
    btBroadphaseInterface *old = world->getBroadphase();
    btDispatcher *d = world->getDispatcher();
    btCollisionObjectArray &objs = world->getCollisionObjectArray();
    std::vector<int> group(objs.size()), mask(objs.size());
    std::vector<char> had(objs.size(), 0);
    for (int i = 0; i < objs.size(); i++) {
        btBroadphaseProxy *h = objs[i]->getBroadphaseHandle();
        if (!h) continue;
        had[i] = 1;
        group[i] = h->m_collisionFilterGroup;
        mask[i] = h->m_collisionFilterMask;
        old->getOverlappingPairCache()->cleanProxyFromPairs(h, d);
        old->destroyProxy(h, d);
        objs[i]->setBroadphaseHandle(nullptr);
    }
    world->setBroadphase(replacement);
    for (int i = 0; i < objs.size(); i++) {
        if (!had[i]) continue;
        btVector3 lo, hi;
        objs[i]->getCollisionShape()->getAabb(objs[i]->getWorldTransform(), lo, hi);
        objs[i]->setBroadphaseHandle(replacement->createProxy(lo, hi, objs[i]->getCollisionShape()->getShapeType(),
                                                              objs[i], group[i], mask[i], d));
    }
    return old;
}

mk_status Broadphase::take_error()
{
    mk_status st = m_error;
    m_error = MK_OK;
    return st;
}

}  // namespace mkb

// contact_writer.cpp: feature-matched writing of a full manifold into Bullet's
// btPersistentManifold (see contact_writer.h for the contract).
#include "contact_writer.h"

namespace mkb {

namespace {

// What btManifoldResult::addContactPoint computes per point from the two
// objects alone: computed once per pair and frame, not once per point.
struct Material {
    btScalar friction, restitution, rolling, spinning, damping = 0, stiffness = 0;
    int flags = 0;
};

Material material_of(const btCollisionObject *o0, const btCollisionObject *o1)
{
    Material m;
    m.friction = gCalculateCombinedFrictionCallback(o0, o1);
    m.restitution = gCalculateCombinedRestitutionCallback(o0, o1);
    m.rolling = gCalculateCombinedRollingFrictionCallback(o0, o1);
    m.spinning = gCalculateCombinedSpinningFrictionCallback(o0, o1);
    const int flags = o0->getCollisionFlags() | o1->getCollisionFlags();
    if (flags & btCollisionObject::CF_HAS_CONTACT_STIFFNESS_DAMPING) {
        m.damping = gCalculateCombinedContactDampingCallback(o0, o1);
        m.stiffness = gCalculateCombinedContactStiffnessCallback(o0, o1);
        m.flags |= BT_CONTACT_FLAG_CONTACT_STIFFNESS_DAMPING;
    }
    if (flags & btCollisionObject::CF_HAS_FRICTION_ANCHOR) m.flags |= BT_CONTACT_FLAG_FRICTION_ANCHOR;
    return m;
}

// The friction directions btManifoldResult::addContactPoint gives a normal,
// computed once for the points that share it (all of a Minko manifold's).
struct Tangents {
    btVector3 normal{0, 0, 0}, t1{0, 0, 0}, t2{0, 0, 0};
    bool set = false;
    void of(const btVector3 &n)
    {
        if (set && n == normal) return;
        normal = n;
        btPlaneSpace1(n, t1, t2);
        set = true;
    }
};

// Everything btManifoldResult::addContactPoint sets on a point, written into
// `p` in place; the warm-start state (impulses, previous rhs, lifetime, user
// data) is left as it is. On a default-constructed point this is the point
// addContactPoint builds; on a cached point it is what replaceContactPoint
// leaves (without friction anchors), without building a fresh point of some
// 350 bytes and copying it over the cached one.
void fill_point(btManifoldPoint &p, const Material &mat, Tangents *tangents, const PairContact &c,
                const btVector3 &local_a, const btVector3 &local_b, int part0, int part1, int index0, int index1)
{
    p.m_localPointA = local_a;
    p.m_localPointB = local_b;
    p.m_positionWorldOnA = c.point_on_b + c.normal_on_b * c.distance;
    p.m_positionWorldOnB = c.point_on_b;
    p.m_normalWorldOnB = c.normal_on_b;
    p.m_distance1 = c.distance;
    p.m_combinedFriction = mat.friction;
    p.m_combinedRestitution = mat.restitution;
    p.m_combinedRollingFriction = mat.rolling;
    p.m_combinedSpinningFriction = mat.spinning;
    p.m_contactPointFlags = mat.flags;
    p.m_contactMotion1 = p.m_contactMotion2 = 0;
    p.m_combinedContactDamping1 = mat.damping;
    p.m_combinedContactStiffness1 = mat.stiffness;
    p.m_frictionCFM = 0;
    tangents->of(c.normal_on_b);
    p.m_lateralFrictionDir1 = tangents->t1;
    p.m_lateralFrictionDir2 = tangents->t2;
    p.m_partId0 = part0;
    p.m_partId1 = part1;
    p.m_index0 = index0;
    p.m_index1 = index1;
}

// A reported point before it is written: its local anchors on the manifold's
// bodies 0 and 1 and its keys in the manifold's body order.
struct Fresh {
    const PairContact *c;
    btVector3 local_a, local_b;
    int part0, part1, index0, index1;
    int slot;  // cached slot it replaces, or -1
};

bool same_key(const btManifoldPoint &a, const Fresh &f)
{
    return a.m_partId0 == f.part0 && a.m_partId1 == f.part1 && a.m_index0 == f.index0 && a.m_index1 == f.index1;
}

// Squared distance between a cached point's anchor on the manifold's body 0
// and a fresh one's: what Bullet's getCacheEntry matches on.
btScalar anchor_gap2(const btManifoldPoint &a, const Fresh &f) { return (a.m_localPointA - f.local_a).length2(); }

void write_point(btManifoldPoint &p, const Material &mat, Tangents *tangents, const Fresh &f)
{
    fill_point(p, mat, tangents, *f.c, f.local_a, f.local_b, f.part0, f.part1, f.index0, f.index1);
}

}  // namespace

bool write_contacts(btManifoldResult *result, const PairContact *points, int count, bool by_features)
{
    btPersistentManifold *m = result->getPersistentManifold();
    const btCollisionObjectWrapper *w0 = result->getBody0Wrap(), *w1 = result->getBody1Wrap();
    if (count > MANIFOLD_CACHE_SIZE) count = MANIFOLD_CACHE_SIZE;
    if (!by_features || w0->m_partId != -1 || w1->m_partId != -1) {
        // Shared manifold, matching by position asked, or part ids taken:
        // leave matching to Bullet.
        add_contacts(result, points, count, false);
        return false;
    }
    const btCollisionObject *o0 = w0->getCollisionObject(), *o1 = w1->getCollisionObject();
    const bool swapped = m->getBody0() != o0;
    const int cached = m->getNumContacts();
    const btScalar threshold = m->getContactBreakingThreshold();
    const btTransform &ta = swapped ? o1->getWorldTransform() : o0->getWorldTransform();
    const btTransform &tb = swapped ? o0->getWorldTransform() : o1->getWorldTransform();

    Fresh fresh[MANIFOLD_CACHE_SIZE];
    bool slot_used[MANIFOLD_CACHE_SIZE] = {false, false, false, false};
    int n = 0;
    for (int i = 0; i < count; i++) {
        const PairContact &c = points[i];
        if (c.distance > threshold) continue;
        Fresh &f = fresh[n++];
        f.c = &c;
        f.local_a = ta.invXform(c.point_on_b + c.normal_on_b * c.distance);
        f.local_b = tb.invXform(c.point_on_b);
        f.part0 = swapped ? c.feature_b : c.feature_a;
        f.part1 = swapped ? c.feature_a : c.feature_b;
        f.index0 = swapped ? w1->m_index : w0->m_index;
        f.index1 = swapped ? w0->m_index : w1->m_index;
        f.slot = -1;
        // The same features, and no farther from the cached point on body 0
        // than Bullet's own matching radius: a contact that slid or rolled
        // farther in one step is a new one for the solver, as in Bullet,
        // whose warm start would otherwise push with an impulse from
        // another place (see write_contacts in contact_writer.h).
        for (int s = 0; s < cached; s++) {
            if (!slot_used[s] && same_key(m->getContactPoint(s), f) &&
                anchor_gap2(m->getContactPoint(s), f) < threshold * threshold) {
                f.slot = s;
                slot_used[s] = true;
                break;
            }
        }
    }
    // A contact whose features changed but which did not move (a corner that
    // slid past its neighbour's edge turns from vertex-face into edge-edge)
    // is the same contact for the solver: it takes the nearest unmatched
    // cached point within Bullet's matching radius (the breaking threshold,
    // between the anchors on body 0, as getCacheEntry measures). This also
    // keeps a point kept below from being doubled by its successor.
    // Measured between the anchors on body 1 instead (bullet_scenes --trials
    // 7): 3000 boxes drift 49.1 +- 5.9, ke_end 16.2k +- 1.4k against 43.9 +- 4
    // and 14.1k +- 1k this way (native 42.4 +- 3, 11.1k +- 0.74k).
    for (int i = 0; i < n; i++) {
        if (fresh[i].slot >= 0) continue;
        btScalar best = threshold * threshold;
        for (int s = 0; s < cached; s++) {
            if (slot_used[s]) continue;
            const btScalar d2 = anchor_gap2(m->getContactPoint(s), fresh[i]);
            if (d2 < best) {
                best = d2;
                fresh[i].slot = s;
            }
        }
        if (fresh[i].slot >= 0) slot_used[fresh[i].slot] = true;
    }

    const Material mat = material_of(o0, o1);
    Tangents tangents;
    // Matched: rewritten in place, impulses and lifetime carried over (with
    // friction anchors, Bullet's replaceContactPoint decides whether the
    // cached point stays).
    for (int i = 0; i < n; i++) {
        if (fresh[i].slot < 0) continue;
        btManifoldPoint &p = m->getContactPoint(fresh[i].slot);
        if (mat.flags & BT_CONTACT_FLAG_FRICTION_ANCHOR) {
            btManifoldPoint q;
            write_point(q, mat, &tangents, fresh[i]);
            m->replaceContactPoint(q, fresh[i].slot);
        } else {
            write_point(p, mat, &tangents, fresh[i]);
        }
    }
    // New points: appended while there is room, then into the slots of cached
    // points not reported this frame (fresh warm-start state, user data
    // released). Unreported points that keep their slot stay, as in Bullet's
    // own manifolds, until refreshContactPoints (which the algorithm calls
    // next) finds them separated or slid beyond the threshold: Minko reports
    // one clipped face, and a hull resting on two nearly coplanar triangles
    // alternates between them; dropping the other triangle's corner every
    // frame restarted its impulse and kept the hull rocking.
    int free_slot = 0;
    for (int i = 0; i < n; i++) {
        if (fresh[i].slot >= 0) continue;
        btManifoldPoint p;
        write_point(p, mat, &tangents, fresh[i]);
        if (m->getNumContacts() < MANIFOLD_CACHE_SIZE) {
            fresh[i].slot = m->addManifoldPoint(p);
            slot_used[fresh[i].slot] = true;
            continue;
        }
        while (slot_used[free_slot]) free_slot++;  // n <= 4 fresh points: a free slot exists
        m->clearUserCache(m->getContactPoint(free_slot));
        m->getContactPoint(free_slot) = p;
        slot_used[free_slot] = true;
        fresh[i].slot = free_slot;
    }

    if (gContactAddedCallback && ((o0->getCollisionFlags() | o1->getCollisionFlags()) &
                                  btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK)) {
        const btCollisionObjectWrapper *a = swapped ? w1 : w0, *b = swapped ? w0 : w1;
        for (int i = 0; i < n; i++) {
            btManifoldPoint &p = m->getContactPoint(fresh[i].slot);
            (*gContactAddedCallback)(p, a, p.m_partId0, p.m_index0, b, p.m_partId1, p.m_index1);
        }
    }
    if (gContactStartedCallback && cached == 0 && n > 0) gContactStartedCallback(m);
    // Every point of the manifold written now, none kept from before?
    return n == m->getNumContacts() && n > 0;
}

void add_contacts(btManifoldResult *result, const PairContact *points, int count, bool keys)
{
    const btCollisionObjectWrapper *w0 = result->getBody0Wrap(), *w1 = result->getBody1Wrap();
    if (!keys || w0->m_partId != -1 || w1->m_partId != -1) {
        for (int i = 0; i < count; i++)
            result->addContactPoint(points[i].normal_on_b, points[i].point_on_b, points[i].distance);
        return;
    }
    // The result stamps its shape identifiers on every point it adds (in
    // the manifold's body order): the keys go in as identifiers, and the
    // wrappers' own come back afterwards.
    for (int i = 0; i < count; i++) {
        result->setShapeIdentifiersA(points[i].feature_a, w0->m_index);
        result->setShapeIdentifiersB(points[i].feature_b, w1->m_index);
        result->addContactPoint(points[i].normal_on_b, points[i].point_on_b, points[i].distance);
    }
    result->setShapeIdentifiersA(w0->m_partId, w0->m_index);
    result->setShapeIdentifiersB(w1->m_partId, w1->m_index);
}

void refresh_contacts(btManifoldResult *result, bool all_fresh)
{
    btPersistentManifold *m = result->getPersistentManifold();
    if (!all_fresh) {
        result->refreshContactPoints();
        return;
    }
    // What refreshContactPoints does to points written this frame: their
    // world positions and distances are recomputed from the local anchors
    // (the same values up to round-off; kept exact here), none is beyond
    // the breaking threshold (written ones are within it) or slid sideways
    // (zero), so each only ages by one frame and is reported processed, in
    // Bullet's order.
    for (int i = m->getNumContacts() - 1; i >= 0; i--) m->getContactPoint(i).m_lifeTime++;
    if (gContactProcessedCallback)
        for (int i = m->getNumContacts() - 1; i >= 0; i--)
            (*gContactProcessedCallback)(m->getContactPoint(i), (void *)m->getBody0(), (void *)m->getBody1());
}

}  // namespace mkb

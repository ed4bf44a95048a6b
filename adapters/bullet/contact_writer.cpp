// contact_writer.cpp: feature-matched writing of a full manifold into Bullet's
// btPersistentManifold (see contact_writer.h for the contract).
#include "contact_writer.h"

namespace mkb {

namespace {

// The point btManifoldResult::addContactPoint would build, with the feature
// keys in the part ids (body 0 / body 1 of the manifold).
btManifoldPoint make_point(const btCollisionObject *o0, const btCollisionObject *o1, bool swapped, int index0,
                           int index1, const PairContact &c)
{
    const btVector3 point_a = c.point_on_b + c.normal_on_b * c.distance;
    const btCollisionObject *ma = swapped ? o1 : o0, *mb = swapped ? o0 : o1;
    btManifoldPoint p(ma->getWorldTransform().invXform(point_a), mb->getWorldTransform().invXform(c.point_on_b),
                      c.normal_on_b, c.distance);
    p.m_positionWorldOnA = point_a;
    p.m_positionWorldOnB = c.point_on_b;
    p.m_combinedFriction = gCalculateCombinedFrictionCallback(o0, o1);
    p.m_combinedRestitution = gCalculateCombinedRestitutionCallback(o0, o1);
    p.m_combinedRollingFriction = gCalculateCombinedRollingFrictionCallback(o0, o1);
    p.m_combinedSpinningFriction = gCalculateCombinedSpinningFrictionCallback(o0, o1);
    const int flags = o0->getCollisionFlags() | o1->getCollisionFlags();
    if (flags & btCollisionObject::CF_HAS_CONTACT_STIFFNESS_DAMPING) {
        p.m_combinedContactDamping1 = gCalculateCombinedContactDampingCallback(o0, o1);
        p.m_combinedContactStiffness1 = gCalculateCombinedContactStiffnessCallback(o0, o1);
        p.m_contactPointFlags |= BT_CONTACT_FLAG_CONTACT_STIFFNESS_DAMPING;
    }
    if (flags & btCollisionObject::CF_HAS_FRICTION_ANCHOR) p.m_contactPointFlags |= BT_CONTACT_FLAG_FRICTION_ANCHOR;
    btPlaneSpace1(p.m_normalWorldOnB, p.m_lateralFrictionDir1, p.m_lateralFrictionDir2);
    p.m_partId0 = swapped ? c.feature_b : c.feature_a;
    p.m_partId1 = swapped ? c.feature_a : c.feature_b;
    p.m_index0 = swapped ? index1 : index0;
    p.m_index1 = swapped ? index0 : index1;
    return p;
}

bool same_key(const btManifoldPoint &a, const btManifoldPoint &b)
{
    return a.m_partId0 == b.m_partId0 && a.m_partId1 == b.m_partId1 && a.m_index0 == b.m_index0 &&
           a.m_index1 == b.m_index1;
}

}  // namespace

void write_contacts(btManifoldResult *result, const PairContact *points, int count, bool owned)
{
    btPersistentManifold *m = result->getPersistentManifold();
    const btCollisionObjectWrapper *w0 = result->getBody0Wrap(), *w1 = result->getBody1Wrap();
    if (count > MANIFOLD_CACHE_SIZE) count = MANIFOLD_CACHE_SIZE;
    if (!owned || w0->m_partId != -1 || w1->m_partId != -1) {
        // Shared manifold or part ids taken: leave matching to Bullet.
        for (int i = 0; i < count; i++)
            result->addContactPoint(points[i].normal_on_b, points[i].point_on_b, points[i].distance);
        return;
    }
    const btCollisionObject *o0 = w0->getCollisionObject(), *o1 = w1->getCollisionObject();
    const bool swapped = m->getBody0() != o0;
    const bool was_empty = m->getNumContacts() == 0;
    const btScalar threshold = m->getContactBreakingThreshold();

    btManifoldPoint fresh[MANIFOLD_CACHE_SIZE];
    int slot_of[MANIFOLD_CACHE_SIZE];  // cached slot matched by fresh[i], or -1
    bool slot_used[MANIFOLD_CACHE_SIZE] = {false, false, false, false};
    int n = 0;
    for (int i = 0; i < count; i++) {
        if (points[i].distance > threshold) continue;
        fresh[n] = make_point(o0, o1, swapped, w0->m_index, w1->m_index, points[i]);
        slot_of[n] = -1;
        for (int s = 0; s < m->getNumContacts(); s++) {
            if (!slot_used[s] && same_key(m->getContactPoint(s), fresh[n])) {
                slot_of[n] = s;
                slot_used[s] = true;
                break;
            }
        }
        n++;
    }

    // Same features: replace in place, impulses and lifetime carried over.
    for (int i = 0; i < n; i++)
        if (slot_of[i] >= 0) m->replaceContactPoint(fresh[i], slot_of[i]);
    // New features: first into the slots of features that are gone (fresh
    // warm-start state, user data released), then appended.
    int free_slot = 0;
    for (int i = 0; i < n; i++) {
        if (slot_of[i] >= 0) continue;
        while (free_slot < m->getNumContacts() && slot_used[free_slot]) free_slot++;
        if (free_slot < m->getNumContacts()) {
            m->clearUserCache(m->getContactPoint(free_slot));
            m->getContactPoint(free_slot) = fresh[i];
            slot_used[free_slot] = true;
            slot_of[i] = free_slot;
        } else {
            slot_of[i] = m->addManifoldPoint(fresh[i]);
            slot_used[slot_of[i]] = true;
        }
    }
    // Features that are gone and whose slot was not reused. removeContactPoint
    // moves the last point into the hole: follow it.
    for (int s = m->getNumContacts() - 1; s >= 0; s--) {
        if (slot_used[s]) continue;
        const int last = m->getNumContacts() - 1;
        m->removeContactPoint(s);
        if (last == s) continue;
        slot_used[s] = slot_used[last];
        for (int i = 0; i < n; i++)
            if (slot_of[i] == last) slot_of[i] = s;
    }

    if (gContactAddedCallback && ((o0->getCollisionFlags() | o1->getCollisionFlags()) &
                                  btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK)) {
        const btCollisionObjectWrapper *a = swapped ? w1 : w0, *b = swapped ? w0 : w1;
        for (int i = 0; i < n; i++) {
            btManifoldPoint &p = m->getContactPoint(slot_of[i]);
            (*gContactAddedCallback)(p, a, p.m_partId0, p.m_index0, b, p.m_partId1, p.m_index1);
        }
    }
    if (gContactStartedCallback && was_empty && n > 0) gContactStartedCallback(m);
}

}  // namespace mkb

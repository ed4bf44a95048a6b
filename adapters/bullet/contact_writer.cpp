// contact_writer.cpp: feature-matched writing of a full manifold into Bullet's
// btPersistentManifold (see contact_writer.h for the contract).
#include "contact_writer.h"

#include <new>
#include <type_traits>

namespace mkb {

static_assert(std::is_trivially_destructible<btManifoldPoint>::value, "write_contacts never destroys its points");

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

// The point btManifoldResult::addContactPoint would build, with the feature
// keys in the part ids (body 0 / body 1 of the manifold), constructed in
// place: a btManifoldPoint is some 300 bytes, and building four by default
// and copying each in cost more than the rest of the writer.
void make_point(void *at, const btTransform &t0, const btTransform &t1, bool swapped, int index0, int index1,
                const Material &mat, Tangents *tangents, const PairContact &c)
{
    const btVector3 point_a = c.point_on_b + c.normal_on_b * c.distance;
    const btTransform &ta = swapped ? t1 : t0, &tb = swapped ? t0 : t1;
    btManifoldPoint &p = *new (at) btManifoldPoint(ta.invXform(point_a), tb.invXform(c.point_on_b), c.normal_on_b, c.distance);
    p.m_positionWorldOnA = point_a;
    p.m_positionWorldOnB = c.point_on_b;
    p.m_combinedFriction = mat.friction;
    p.m_combinedRestitution = mat.restitution;
    p.m_combinedRollingFriction = mat.rolling;
    p.m_combinedSpinningFriction = mat.spinning;
    p.m_combinedContactDamping1 = mat.damping;
    p.m_combinedContactStiffness1 = mat.stiffness;
    p.m_contactPointFlags |= mat.flags;
    tangents->of(c.normal_on_b);
    p.m_lateralFrictionDir1 = tangents->t1;
    p.m_lateralFrictionDir2 = tangents->t2;
    p.m_partId0 = swapped ? c.feature_b : c.feature_a;
    p.m_partId1 = swapped ? c.feature_a : c.feature_b;
    p.m_index0 = swapped ? index1 : index0;
    p.m_index1 = swapped ? index0 : index1;
}

bool same_key(const btManifoldPoint &a, const btManifoldPoint &b)
{
    return a.m_partId0 == b.m_partId0 && a.m_partId1 == b.m_partId1 && a.m_index0 == b.m_index0 &&
           a.m_index1 == b.m_index1;
}

}  // namespace

void write_contacts(btManifoldResult *result, const PairContact *points, int count, bool by_features)
{
    btPersistentManifold *m = result->getPersistentManifold();
    const btCollisionObjectWrapper *w0 = result->getBody0Wrap(), *w1 = result->getBody1Wrap();
    if (count > MANIFOLD_CACHE_SIZE) count = MANIFOLD_CACHE_SIZE;
    if (!by_features || w0->m_partId != -1 || w1->m_partId != -1) {
        // Shared manifold, matching by position asked, or part ids taken:
        // leave matching to Bullet.
        for (int i = 0; i < count; i++)
            result->addContactPoint(points[i].normal_on_b, points[i].point_on_b, points[i].distance);
        return;
    }
    const btCollisionObject *o0 = w0->getCollisionObject(), *o1 = w1->getCollisionObject();
    const bool swapped = m->getBody0() != o0;
    const bool was_empty = m->getNumContacts() == 0;
    const btScalar threshold = m->getContactBreakingThreshold();
    const Material mat = material_of(o0, o1);
    Tangents tangents;

    // Raw storage: only the points written are constructed (trivially
    // destructible, so nothing to destroy).
    union Storage {
        unsigned char bytes[MANIFOLD_CACHE_SIZE * sizeof(btManifoldPoint)];
        btVector3 align;
        Storage() {}
    } storage;
    btManifoldPoint *fresh = reinterpret_cast<btManifoldPoint *>(storage.bytes);
    int slot_of[MANIFOLD_CACHE_SIZE];  // cached slot matched by fresh[i], or -1
    bool slot_used[MANIFOLD_CACHE_SIZE] = {false, false, false, false};
    int n = 0;
    for (int i = 0; i < count; i++) {
        if (points[i].distance > threshold) continue;
        make_point(&fresh[n], o0->getWorldTransform(), o1->getWorldTransform(), swapped, w0->m_index, w1->m_index,
                   mat, &tangents, points[i]);
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
    // A contact whose features changed but which did not move (a corner that
    // slid past its neighbour's edge turns from vertex-face into edge-edge)
    // is the same contact for the solver: it takes the nearest unmatched
    // cached point within Bullet's own matching radius (the breaking
    // threshold, on the point on B, as getCacheEntry does). This also keeps a
    // point kept below from being doubled by its successor.
    for (int i = 0; i < n; i++) {
        if (slot_of[i] >= 0) continue;
        btScalar best = threshold * threshold;
        for (int s = 0; s < m->getNumContacts(); s++) {
            if (slot_used[s]) continue;
            const btScalar d2 = (m->getContactPoint(s).m_localPointB - fresh[i].m_localPointB).length2();
            if (d2 < best) {
                best = d2;
                slot_of[i] = s;
            }
        }
        if (slot_of[i] >= 0) slot_used[slot_of[i]] = true;
    }

    // Matched: replaced in place, impulses and lifetime carried over.
    for (int i = 0; i < n; i++)
        if (slot_of[i] >= 0) m->replaceContactPoint(fresh[i], slot_of[i]);
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
        if (slot_of[i] >= 0) continue;
        if (m->getNumContacts() < MANIFOLD_CACHE_SIZE) {
            slot_of[i] = m->addManifoldPoint(fresh[i]);
            slot_used[slot_of[i]] = true;
            continue;
        }
        while (slot_used[free_slot]) free_slot++;  // n <= 4 fresh points: a free slot exists
        m->clearUserCache(m->getContactPoint(free_slot));
        m->getContactPoint(free_slot) = fresh[i];
        slot_used[free_slot] = true;
        slot_of[i] = free_slot;
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

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
    int slot;  // cached slot with its feature key, or -1
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

// Slot s takes `f`, keeping its warm-start state (impulses, previous rhs,
// lifetime, user data), as Bullet's replaceContactPoint; with friction
// anchors that call itself decides whether the cached point stays.
void replace_point(btPersistentManifold *m, int s, const Material &mat, Tangents *tangents, const Fresh &f)
{
    if (mat.flags & BT_CONTACT_FLAG_FRICTION_ANCHOR) {
        btManifoldPoint q;
        write_point(q, mat, tangents, f);
        m->replaceContactPoint(q, s);
    } else {
        write_point(m->getContactPoint(s), mat, tangents, f);
    }
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
    // owner[s]: the reported point written into slot s this frame, or -1
    // (a cached point not reported, or a free slot).
    int owner[MANIFOLD_CACHE_SIZE] = {-1, -1, -1, -1};
    int n = 0;
    for (int i = 0; i < count; i++) {
        const PairContact &c = points[i];
        if (c.distance > threshold) continue;
        Fresh &f = fresh[n];
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
            if (owner[s] < 0 && same_key(m->getContactPoint(s), f) &&
                anchor_gap2(m->getContactPoint(s), f) < threshold * threshold) {
                f.slot = s;
                owner[s] = n;
                break;
            }
        }
        n++;
    }

    const Material mat = material_of(o0, o1);
    Tangents tangents;
    // Matched: rewritten in place, impulses and lifetime carried over (with
    // friction anchors, Bullet's replaceContactPoint decides whether the
    // cached point stays).
    for (int i = 0; i < n; i++)
        if (fresh[i].slot >= 0) replace_point(m, fresh[i].slot, mat, &tangents, fresh[i]);
    // The others, in the order given, the way Bullet's addContactPoint sends
    // a point: onto the manifold point nearest to it (getCacheEntry: between
    // the anchors on body 0, within the breaking threshold, any slot, one
    // written this frame too), whose impulses it takes over (a contact whose
    // features changed but not its place: a corner that slid past an edge
    // turns from vertex-face into edge-edge); else appended while there is
    // room, else into the slot Bullet's area rule picks (addManifoldPoint
    // keeps the deepest point and the largest area), cold. Either way it may
    // take the slot of a point written this frame, which is then dropped:
    // Bullet keeps one point per breaking threshold and four per manifold
    // by these rules, and keeping more measured worse (contact_writer.h).
    // Session 10 measured the nearest search between the anchors on body 1
    // instead (bullet_scenes --trials 7): 3000 boxes drift 49.1 +- 5.9,
    // ke_end 16.2k +- 1.4k against 43.9 +- 4 and 14.1k +- 1k on body 0.
    for (int i = 0; i < n; i++) {
        if (fresh[i].slot >= 0) continue;
        int near = -1;
        btScalar best = threshold * threshold;
        for (int s = 0; s < m->getNumContacts(); s++) {
            const btScalar d2 = anchor_gap2(m->getContactPoint(s), fresh[i]);
            if (d2 < best) {
                best = d2;
                near = s;
            }
        }
        if (near >= 0) {
            // Two reported points within the threshold are one contact:
            // the deeper stays, so the deepest point is never lost.
            if (owner[near] >= 0 && fresh[owner[near]].c->distance <= fresh[i].c->distance) continue;
            replace_point(m, near, mat, &tangents, fresh[i]);
            owner[near] = i;
            continue;
        }
        btManifoldPoint p;
        write_point(p, mat, &tangents, fresh[i]);
        owner[m->addManifoldPoint(p)] = i;
    }

    int written = 0;
    for (int s = 0; s < m->getNumContacts(); s++) written += owner[s] >= 0;
    if (gContactAddedCallback && ((o0->getCollisionFlags() | o1->getCollisionFlags()) &
                                  btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK)) {
        const btCollisionObjectWrapper *a = swapped ? w1 : w0, *b = swapped ? w0 : w1;
        for (int s = 0; s < m->getNumContacts(); s++) {
            if (owner[s] < 0) continue;
            btManifoldPoint &p = m->getContactPoint(s);
            (*gContactAddedCallback)(p, a, p.m_partId0, p.m_index0, b, p.m_partId1, p.m_index1);
        }
    }
    if (gContactStartedCallback && cached == 0 && n > 0) gContactStartedCallback(m);
    // Every point of the manifold written now, none kept from before?
    return written == m->getNumContacts() && written > 0;
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

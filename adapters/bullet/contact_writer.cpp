// contact_writer.cpp: feature-matched writing of a full manifold into Bullet's
// btPersistentManifold (see contact_writer.h for the contract).
#include "contact_writer.h"

#include <utility>

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

// The order in which Bullet's own box-box (btBoxBoxDetector, ODE's dBoxBox)
// would report the points of a box pair, as a permutation `seq` of fresh[0..n).
// Bullet's solver is sequential (Gauss-Seidel over the manifold's slots in
// order), so the slot order a new manifold's points get changes the solve;
// Minko's clip gives the same points in another order (its own side order,
// and the reduction's). Measured (demos/bullet_scenes --scene 1000_stack
// --trials 7 --steps 80; the stack's drift is the 12-level pyramid's
// collapse onto its 0.04 gaps in the first 40 steps, its top block sinking
// 0.447 in both, and what differs is how far it moves sideways: native
// 0.050 on average, Minko 0.077): native drift 0.449 +- 0.0013, Minko 0.454
// +- 0.0042 ('worse'). Every writer variant gives the same (Minko's points
// through Bullet's addContactPoint 0.453); native's points with Minko's
// normal 0.449 +- 0.0011, Minko's points with native's normal 0.450 +-
// 0.0021 (the points, not the normal), native's positions with Minko's
// depths and order 0.454, Minko's points in native's order (found by
// running btBoxBoxDetector alongside) 0.449 +- 0.0016; Minko's order
// reversed, rotated by one to three places or taken diagonally 0.451-0.456.
// With this order (600 steps, 7 trials): 0.451 +- 0.0027 ('noise').
//
// Bullet's rule, rebuilt here (our code, from the algorithm's description):
// the reference face is the face axis of least penetration (the first on a
// tie, A's before B's, computed as Bullet computes it, so exact ties between
// aligned stacked boxes go the same way); in its 2D coordinates (the other
// two axes in index order) the incident face's corners are listed (-,-),
// (-,+), (+,+), (+,-) along the incident box's other two axes in index
// order, clipped by the sides u > -h, u < h, v > -h, v < h in turn
// (Sutherland-Hodgman, which keeps the winding and moves the start), and
// the points below the reference face kept; more than four are culled to
// the deepest and then, for each quarter turn round the polygon's
// centroid, the point nearest in angle. Each of Minko's points takes the
// rank of the nearest candidate. Only frames that add a point pay for it:
// points already in the manifold keep their slots.
void bullet_box_order(const btCollisionObjectWrapper *w0, const btCollisionObjectWrapper *w1, const Fresh *fresh,
                      int n, int *seq)
{
    const btBoxShape *box[2] = {static_cast<const btBoxShape *>(w0->getCollisionShape()),
                                static_cast<const btBoxShape *>(w1->getCollisionShape())};
    const btTransform *xf[2] = {&w0->getWorldTransform(), &w1->getWorldTransform()};
    // The reference face: of the six face axes, the one of least
    // penetration (the first on a tie, A's before B's), computed as Bullet
    // computes it, so exact ties between stacked boxes go the same way.
    const btMatrix3x3 &R0 = xf[0]->getBasis(), &R1 = xf[1]->getBasis();
    const btVector3 h0 = box[0]->getHalfExtentsWithMargin(), h1 = box[1]->getHalfExtentsWithMargin();
    const btVector3 gap = xf[1]->getOrigin() - xf[0]->getOrigin();
    btScalar q[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) q[i][j] = btFabs(R0.getColumn(i).dot(R1.getColumn(j)));
    int r = 0, cn = 0;
    btScalar least = -BT_LARGE_FLOAT;
    for (int i = 0; i < 3; i++) {
        const btScalar s = btFabs(R0.getColumn(i).dot(gap)) - (h0[i] + h1[0] * q[i][0] + h1[1] * q[i][1] + h1[2] * q[i][2]);
        if (s > least) {
            least = s;
            cn = i;
        }
    }
    for (int j = 0; j < 3; j++) {
        const btScalar s = btFabs(R1.getColumn(j).dot(gap)) - (h0[0] * q[0][j] + h0[1] * q[1][j] + h0[2] * q[2][j] + h1[j]);
        if (s > least) {
            least = s;
            cn = j;
            r = 1;
        }
    }
    const int in = 1 - r, c1 = cn == 0 ? 1 : 0, c2 = cn == 2 ? 1 : 2;
    const btMatrix3x3 &Ra = xf[r]->getBasis(), &Rb = xf[in]->getBasis();
    const btVector3 Sa = r == 0 ? h0 : h1, Sb = r == 0 ? h1 : h0;
    // The normal from the reference box into the incident one.
    const btVector3 n2 = Ra.getColumn(cn) * ((r == 0 ? gap : -gap).dot(Ra.getColumn(cn)) < 0 ? -1 : 1);
    // The incident face: the incident box's axis most along the normal.
    int ln = 0;
    btScalar best = -1;
    for (int i = 0; i < 3; i++) {
        const btScalar a = btFabs(Rb.getColumn(i).dot(n2));
        if (a > best) {
            best = a;
            ln = i;
        }
    }
    const int a1 = ln == 0 ? 1 : 0, a2 = ln == 2 ? 1 : 2;
    const btVector3 pa = xf[r]->getOrigin();
    const btScalar sn = Rb.getColumn(ln).dot(n2) < 0 ? 1 : -1;
    const btVector3 center = xf[in]->getOrigin() - pa + Rb.getColumn(ln) * (sn * Sb[ln]);
    const btVector3 u = Ra.getColumn(c1), v = Ra.getColumn(c2), e1 = Rb.getColumn(a1), e2 = Rb.getColumn(a2);
    const btScalar cu = center.dot(u), cv = center.dot(v);
    const btScalar m11 = u.dot(e1), m12 = u.dot(e2), m21 = v.dot(e1), m22 = v.dot(e2);
    // The incident corners in the reference face's coordinates, clipped.
    btScalar poly[2][16];
    int count = 4;
    const btScalar s1[4] = {-1, -1, 1, 1}, s2[4] = {-1, 1, 1, -1};
    for (int i = 0; i < 4; i++) {
        poly[0][2 * i] = cu + s1[i] * m11 * Sb[a1] + s2[i] * m12 * Sb[a2];
        poly[0][2 * i + 1] = cv + s1[i] * m21 * Sb[a1] + s2[i] * m22 * Sb[a2];
    }
    const btScalar h[2] = {Sa[c1], Sa[c2]};
    int cur = 0;
    // (Eight points end the clip where they are reached, as in Bullet.)
    bool full = false;
    for (int side = 0; side < 4 && count > 0 && !full; side++) {
        const int dir = side >> 1;
        const btScalar sign = (side & 1) ? 1 : -1;
        const btScalar *q = poly[cur];
        btScalar *o = poly[1 - cur];
        int m = 0;
        for (int i = 0; i < count && m < 8; i++) {
            const btScalar *p0 = q + 2 * i, *p1 = q + 2 * ((i + 1) % count);
            const bool in0 = sign * p0[dir] < h[dir], in1 = sign * p1[dir] < h[dir];
            if (in0) {
                o[2 * m] = p0[0];
                o[2 * m + 1] = p0[1];
                m++;
            }
            if (in0 != in1 && m < 8) {
                const btScalar t = (sign * h[dir] - p0[dir]) / (p1[dir] - p0[dir]);
                o[2 * m + dir] = sign * h[dir];
                o[2 * m + 1 - dir] = p0[1 - dir] + t * (p1[1 - dir] - p0[1 - dir]);
                m++;
            }
        }
        count = m;
        cur = 1 - cur;
        full = m == 8;
    }
    // Kept: the candidates below the reference face.
    const btScalar det = m11 * m22 - m12 * m21;
    if (count == 0 || btFabs(det) < SIMD_EPSILON) return;
    btScalar kept[16], kept_depth[8];
    int nk = 0;
    for (int i = 0; i < count; i++) {
        const btScalar du = poly[cur][2 * i] - cu, dv = poly[cur][2 * i + 1] - cv;
        const btScalar k1 = (m22 * du - m12 * dv) / det, k2 = (-m21 * du + m11 * dv) / det;
        const btScalar depth = Sa[cn] - n2.dot(center + e1 * k1 + e2 * k2);
        if (depth >= 0) {
            kept_depth[nk] = depth;
            kept[2 * nk] = poly[cur][2 * i];
            kept[2 * nk + 1] = poly[cur][2 * i + 1];
            nk++;
        }
    }
    int key[MANIFOLD_CACHE_SIZE];
    btScalar pu[MANIFOLD_CACHE_SIZE], pv[MANIFOLD_CACHE_SIZE];
    for (int i = 0; i < n; i++) {
        const btVector3 p = fresh[i].c->point_on_b - pa;
        pu[i] = p.dot(u);
        pv[i] = p.dot(v);
    }
    if (nk > MANIFOLD_CACHE_SIZE) {
        // Culled to four: the deepest candidate (the first of equals), then
        // for each quarter turn from it round the polygon's centroid the
        // candidate whose angle is nearest, in that order.
        int deep = 0;
        for (int i = 1; i < nk; i++)
            if (kept_depth[i] > kept_depth[deep]) deep = i;
        btScalar area = 0, mu = 0, mv = 0;
        for (int i = 0; i < nk; i++) {
            const btScalar *p0 = kept + 2 * i, *p1 = kept + 2 * ((i + 1) % nk);
            const btScalar c = p0[0] * p1[1] - p1[0] * p0[1];
            area += c;
            mu += c * (p0[0] + p1[0]);
            mv += c * (p0[1] + p1[1]);
        }
        if (btFabs(area) > SIMD_EPSILON) {
            mu /= 3 * area;
            mv /= 3 * area;
        } else {
            mu = mv = 0;
            for (int i = 0; i < nk; i++) {
                mu += kept[2 * i] / (btScalar)nk;
                mv += kept[2 * i + 1] / (btScalar)nk;
            }
        }
        btScalar angle[8];
        bool free[8];
        for (int i = 0; i < nk; i++) {
            angle[i] = btAtan2(kept[2 * i + 1] - mv, kept[2 * i] - mu);
            free[i] = i != deep;
        }
        btScalar picked[2 * MANIFOLD_CACHE_SIZE] = {kept[2 * deep], kept[2 * deep + 1]};
        for (int k = 1; k < MANIFOLD_CACHE_SIZE; k++) {
            btScalar target = angle[deep] + (btScalar)k * SIMD_HALF_PI;
            if (target > SIMD_PI) target -= SIMD_2_PI;
            int pick = deep;
            btScalar off = BT_LARGE_FLOAT;
            for (int i = 0; i < nk; i++) {
                if (!free[i]) continue;
                btScalar a = btFabs(angle[i] - target);
                if (a > SIMD_PI) a = SIMD_2_PI - a;
                if (a < off) {
                    off = a;
                    pick = i;
                }
            }
            free[pick] = false;
            picked[2 * k] = kept[2 * pick];
            picked[2 * k + 1] = kept[2 * pick + 1];
        }
        for (int i = 0; i < 2 * MANIFOLD_CACHE_SIZE; i++) kept[i] = picked[i];
        nk = MANIFOLD_CACHE_SIZE;
    }
    for (int i = 0; i < n; i++) {
        btScalar near = BT_LARGE_FLOAT;
        key[i] = 0;
        for (int j = 0; j < nk; j++) {
            const btScalar g = (kept[2 * j] - pu[i]) * (kept[2 * j] - pu[i]) + (kept[2 * j + 1] - pv[i]) * (kept[2 * j + 1] - pv[i]);
            if (g < near) {
                near = g;
                key[i] = j;
            }
        }
    }
    // Stable insertion sort of at most four.
    for (int i = 0; i < n; i++) seq[i] = i;
    for (int i = 1; i < n; i++)
        for (int j = i; j > 0 && key[seq[j - 1]] > key[seq[j]]; j--) std::swap(seq[j - 1], seq[j]);
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
    int seq[MANIFOLD_CACHE_SIZE] = {0, 1, 2, 3};
    int unmatched = 0;
    for (int i = 0; i < n; i++) unmatched += fresh[i].slot < 0;
    if (unmatched > 1 && w0->getCollisionShape()->getShapeType() == BOX_SHAPE_PROXYTYPE &&
        w1->getCollisionShape()->getShapeType() == BOX_SHAPE_PROXYTYPE)
        bullet_box_order(w0, w1, fresh, n, seq);  // (one new point goes last in any order)
    for (int k = 0; k < n; k++) {
        const int i = seq[k];
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

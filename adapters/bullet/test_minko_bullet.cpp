// test_minko_bullet.cpp: the Bullet adapter's Check suite (C++11), run by
// `make check` in every build: double Minko with bullet-float64, single Minko
// with float Bullet, both also under ASan + UBSan.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

#include <btBulletDynamicsCommon.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpa2.h>

#include "contact_writer.h"
#include "minko_bullet.h"
#include "support/mk_test.h"
extern "C" {
#include "support/oracle.h"
}

namespace {

// Tolerance on support values, relative to the shape's size.
#if defined(BT_USE_DOUBLE_PRECISION)
const double kRel = 1e-12;
#else
const double kRel = 2e-6;
#endif

// Two convex solids are equal iff their support functions are: compare
// h(d) = max over the solid of d.x for Bullet's shape (its own
// localGetSupportingVertex, margins included) and for the mapped Minko shape.
void check_same_solid(const btConvexShape *bt, const char *what, mkb::CollisionConfiguration *config = nullptr)
{
    mkb::ShapeMap m;
    MK_ASSERT_STATUS(config ? config->map_shape(bt, &m) : mkb::map_primitive(bt, &m), MK_OK);
    btVector3 lo, hi;
    btTransform id;
    id.setIdentity();
    bt->getAabb(id, lo, hi);
    const double size = (double)(hi - lo).length();
    mk_rng rng = {12345};
    for (int i = 0; i < 500; i++) {
        // Random directions plus the axes, where faces and caps make ties.
        mk_vec3 d = i < 6 ? mk_v3(i % 3 == 0, i % 3 == 1, i % 3 == 2) : mk_rng_dir(&rng);
        if (i < 6 && i >= 3) d = mk_v3_neg(d);
        btVector3 bd = mkb::to_bt(d);
        double hb = (double)bd.dot(bt->localGetSupportingVertex(bd));
        mk_vec3 local = mk_quat_inv_rotate(m.axis, d);
        mk_vec3 sm = mk_quat_rotate(m.axis, mk_shape_support(&m.shape, local));
        double hm = (double)mk_v3_dot(d, sm);
        ck_assert_msg(std::fabs(hb - hm) <= kRel * size * 10, "%s: direction %d (%g %g %g): Bullet h=%.17g, Minko h=%.17g", what,
                      i, (double)d.x, (double)d.y, (double)d.z, hb, hm);
    }
}

START_TEST(shape_box)
{
    btBoxShape a(btVector3(1, 2, 3));
    check_same_solid(&a, "box");
    btBoxShape b(btVector3(btScalar(0.005), btScalar(0.005), btScalar(0.005)));  // margin clamped by Bullet
    check_same_solid(&b, "1 cm box");
    btBoxShape c(btVector3(1, 1, 1));
    c.setLocalScaling(btVector3(2, btScalar(0.5), 3));
    check_same_solid(&c, "scaled box");
    c.setMargin(btScalar(0.2));
    check_same_solid(&c, "box with margin 0.2");
}
END_TEST

START_TEST(shape_sphere_capsule)
{
    btSphereShape s(btScalar(0.7));
    check_same_solid(&s, "sphere");
    btCapsuleShapeX cx(btScalar(0.3), btScalar(1.1));
    btCapsuleShape cy(btScalar(0.3), btScalar(1.1));
    btCapsuleShapeZ cz(btScalar(0.3), btScalar(1.1));
    check_same_solid(&cx, "capsule X");
    check_same_solid(&cy, "capsule Y");
    check_same_solid(&cz, "capsule Z");
}
END_TEST

START_TEST(shape_cylinder_cone)
{
    btCylinderShapeX x(btVector3(btScalar(1.5), btScalar(0.5), btScalar(0.5)));
    btCylinderShape y(btVector3(btScalar(0.5), btScalar(1.5), btScalar(0.5)));
    btCylinderShapeZ z(btVector3(btScalar(0.5), btScalar(0.5), btScalar(1.5)));
    check_same_solid(&x, "cylinder X");
    check_same_solid(&y, "cylinder Y");
    check_same_solid(&z, "cylinder Z");
    btConeShapeX cx(btScalar(0.5), 2);
    btConeShape cy(btScalar(0.5), 2);
    btConeShapeZ cz(btScalar(0.5), 2);
    check_same_solid(&cx, "cone X");
    check_same_solid(&cy, "cone Y");
    check_same_solid(&cz, "cone Z");
    cy.setMargin(btScalar(0.1));
    check_same_solid(&cy, "cone Y, margin 0.1");
}
END_TEST

START_TEST(shape_plane_and_refusals)
{
    btStaticPlaneShape p(btVector3(0, 1, 0), btScalar(2.5));
    mkb::ShapeMap m;
    MK_ASSERT_STATUS(mkb::map_primitive(&p, &m), MK_OK);
    ck_assert_int_eq(m.shape.type, MK_SHAPE_PLANE);
    MK_ASSERT_V3_NEAR(m.shape.u.plane.normal, mk_v3(0, 1, 0), 0);
    MK_ASSERT_NEAR(m.shape.u.plane.offset, 2.5, 0);
    // Not modelled by Minko: left to Bullet.
    btEmptyShape empty;
    MK_ASSERT_STATUS(mkb::map_primitive(&empty, &m), MK_ERR_UNSUPPORTED);
    btCompoundShape compound;
    MK_ASSERT_STATUS(mkb::map_primitive(&compound, &m), MK_ERR_UNSUPPORTED);
    MK_ASSERT_STATUS(mkb::map_primitive(nullptr, &m), MK_ERR_NULL);
    // A flat box Minko refuses (zero extent): a status, not garbage.
    btBoxShape flat(btVector3(1, 0, 1));
    MK_ASSERT_STATUS(mkb::map_primitive(&flat, &m), MK_ERR_BAD_SIZE);
}
END_TEST

START_TEST(shape_pose)
{
    // The Minko pose of a Y capsule puts its segment along the world axis the
    // Bullet body's rotation gives to local Y.
    btCapsuleShape c(btScalar(0.25), 1);
    mkb::ShapeMap m;
    MK_ASSERT_STATUS(mkb::map_primitive(&c, &m), MK_OK);
    btTransform xf(btQuaternion(btVector3(0, 0, 1), btScalar(SIMD_HALF_PI)), btVector3(3, 4, 5));
    mk_transform t = mkb::minko_pose(xf, m);
    mk_vec3 top = mk_transform_point(t, mk_v3(0, 0, 1));  // Minko segment end +h
    btVector3 want = xf * btVector3(0, 1, 0);
    MK_ASSERT_V3_NEAR(top, mkb::to_mk(want), 1e-5);
    // The checked pose from Bullet's matrix is the same placement, for every
    // axis rotation; a scaled matrix is refused.
    btCapsuleShapeX cx(btScalar(0.25), 1);
    btCapsuleShapeZ cz(btScalar(0.25), 1);
    mk_rng rng = {99};
    for (const btCollisionShape *s : {(const btCollisionShape *)&c, (const btCollisionShape *)&cx, (const btCollisionShape *)&cz}) {
        MK_ASSERT_STATUS(mkb::map_primitive(s, &m), MK_OK);
        for (int k = 0; k < 20; k++) {
            mk_vec3 ax = mk_rng_dir(&rng);
            btTransform x(btQuaternion(mkb::to_bt(ax), btScalar(mk_rng_range(&rng, -3, 3))),
                          btVector3(btScalar(mk_rng_range(&rng, -9, 9)), btScalar(mk_rng_range(&rng, -9, 9)), 2));
            mk_pose p;
            MK_ASSERT_STATUS(mkb::minko_pose(x, m, &p), MK_OK);
            const mk_transform tq = mkb::minko_pose(x, m);
            for (int i = 0; i < 3; i++) {
                const mk_vec3 local = mk_v3(i == 0, i == 1, i == 2);
                const mk_vec3 by_matrix = mk_v3_add(mk_mat3_mul_v3(p.r, local), p.p);
                MK_ASSERT_V3_NEAR(by_matrix, mk_transform_point(tq, local), 1e-5);
            }
        }
    }
    btTransform scaled = xf;
    scaled.setBasis(scaled.getBasis().scaled(btVector3(btScalar(1.1), btScalar(1.1), btScalar(1.1))));
    mk_pose p;
    MK_ASSERT_STATUS(mkb::minko_pose(scaled, m, &p), MK_ERR_BAD_ROTATION);
}
END_TEST


// ---- the feature-matched contact writer ---------------------------------------

// Two shapes and one manifold, as a collision algorithm sees them. Spheres:
// the points written are made up, and the writer orders a box pair's new
// points by the boxes' geometry (np_box_points_in_bullets_order).
struct WriterRig {
    btSphereShape shape{1};
    btTransform ta{btQuaternion(btVector3(1, 2, 3), btScalar(0.4)), btVector3(0, btScalar(1.9), 0)};
    btTransform tb{btQuaternion(btVector3(0, 1, 0), btScalar(0.1)), btVector3(0, 0, 0)};
    btCollisionObject a, b;
    btCollisionObjectWrapper wa_, wb_;  // stack-only type: members, not heap objects
    const btCollisionObjectWrapper *wa = &wa_, *wb = &wb_;
    btPersistentManifold manifold;
    explicit WriterRig(bool swapped, int part_a = -1)
        : wa_(nullptr, &shape, &a, ta, part_a, 7), wb_(nullptr, &shape, &b, tb, -1, 9)
    {
        a.setCollisionShape(&shape);
        b.setCollisionShape(&shape);
        a.setWorldTransform(ta);
        b.setWorldTransform(tb);
        a.setFriction(btScalar(0.3));
        b.setFriction(btScalar(0.8));
        a.setRestitution(btScalar(0.5));
        b.setRestitution(btScalar(0.4));
        a.setRollingFriction(btScalar(0.01));
        b.setSpinningFriction(btScalar(0.02));
        manifold = btPersistentManifold(swapped ? &b : &a, swapped ? &a : &b, 0, btScalar(0.02), BT_LARGE_FLOAT);
    }
    // write_contacts: whether every point of the manifold was written now.
    bool write(const mkb::PairContact *c, int n)
    {
        btManifoldResult r(wa, wb);
        r.setPersistentManifold(&manifold);
        return mkb::write_contacts(&r, c, n);
    }
    // The adapter's refresh after a write that returned `all_fresh`.
    void refresh_contacts(bool all_fresh)
    {
        btManifoldResult r(wa, wb);
        r.setPersistentManifold(&manifold);
        mkb::refresh_contacts(&r, all_fresh);
    }
    // A moved by `up` along the contacts' normal (+y) from pose `rest`.
    void move_a(const btTransform &rest, btScalar up)
    {
        ta = rest;
        ta.getOrigin() += btVector3(0, up, 0);
        a.setWorldTransform(ta);
    }
    // What the algorithm does after writing.
    void refresh() { manifold.refreshContactPoints(manifold.getBody0()->getWorldTransform(), manifold.getBody1()->getWorldTransform()); }
    // The manifold point carrying feature fa of A (-1 if none).
    int slot_of(int fa)
    {
        const bool swapped = manifold.getBody0() != &a;
        for (int i = 0; i < manifold.getNumContacts(); i++) {
            const btManifoldPoint &p = manifold.getContactPoint(i);
            if ((swapped ? p.m_partId1 : p.m_partId0) == fa) return i;
        }
        return -1;
    }
};

mkb::PairContact contact(btScalar x, btScalar z, btScalar dist, int fa, int fb)
{
    mkb::PairContact c;
    c.normal_on_b = btVector3(0, 1, 0);
    c.point_on_b = btVector3(x, 1, z);
    c.distance = dist;
    c.feature_a = fa;
    c.feature_b = fb;
    return c;
}

void check_point_equal(const btManifoldPoint &p, const btManifoldPoint &q)
{
    const double tol = 1e-6;
    MK_ASSERT_V3_NEAR(mkb::to_mk(p.m_localPointA), mkb::to_mk(q.m_localPointA), tol);
    MK_ASSERT_V3_NEAR(mkb::to_mk(p.m_localPointB), mkb::to_mk(q.m_localPointB), tol);
    MK_ASSERT_V3_NEAR(mkb::to_mk(p.m_positionWorldOnA), mkb::to_mk(q.m_positionWorldOnA), tol);
    MK_ASSERT_V3_NEAR(mkb::to_mk(p.m_positionWorldOnB), mkb::to_mk(q.m_positionWorldOnB), tol);
    MK_ASSERT_V3_NEAR(mkb::to_mk(p.m_normalWorldOnB), mkb::to_mk(q.m_normalWorldOnB), tol);
    MK_ASSERT_V3_NEAR(mkb::to_mk(p.m_lateralFrictionDir1), mkb::to_mk(q.m_lateralFrictionDir1), tol);
    MK_ASSERT_V3_NEAR(mkb::to_mk(p.m_lateralFrictionDir2), mkb::to_mk(q.m_lateralFrictionDir2), tol);
    MK_ASSERT_NEAR(p.m_distance1, q.m_distance1, tol);
    MK_ASSERT_NEAR(p.m_combinedFriction, q.m_combinedFriction, tol);
    MK_ASSERT_NEAR(p.m_combinedRestitution, q.m_combinedRestitution, tol);
    MK_ASSERT_NEAR(p.m_combinedRollingFriction, q.m_combinedRollingFriction, tol);
    MK_ASSERT_NEAR(p.m_combinedSpinningFriction, q.m_combinedSpinningFriction, tol);
    MK_ASSERT_NEAR(p.m_combinedContactStiffness1, q.m_combinedContactStiffness1, tol);
    MK_ASSERT_NEAR(p.m_combinedContactDamping1, q.m_combinedContactDamping1, tol);
    ck_assert_int_eq(p.m_contactPointFlags, q.m_contactPointFlags);
}

// A point written by the writer equals the one Bullet's addContactPoint writes,
// apart from the part ids that carry the features; in both manifold orders.
START_TEST(writer_matches_add_contact_point)
{
    for (int swapped = 0; swapped < 2; swapped++) {
        WriterRig mine(swapped != 0), ref(swapped != 0);
        for (WriterRig *r : {&mine, &ref}) {
            r->b.setCollisionFlags(r->b.getCollisionFlags() | btCollisionObject::CF_HAS_FRICTION_ANCHOR);
            r->a.setContactStiffnessAndDamping(btScalar(1e4), btScalar(30));
        }
        mkb::PairContact c = contact(btScalar(0.3), btScalar(-0.2), btScalar(-0.05), 3, 4);
        mine.write(&c, 1);
        btManifoldResult r(ref.wa, ref.wb);
        r.setPersistentManifold(&ref.manifold);
        r.setShapeIdentifiersA(-1, 7);
        r.setShapeIdentifiersB(-1, 9);
        r.addContactPoint(c.normal_on_b, c.point_on_b, c.distance);
        ck_assert_int_eq(mine.manifold.getNumContacts(), 1);
        ck_assert_int_eq(ref.manifold.getNumContacts(), 1);
        check_point_equal(mine.manifold.getContactPoint(0), ref.manifold.getContactPoint(0));
        const btManifoldPoint &p = mine.manifold.getContactPoint(0);
        ck_assert_int_eq(swapped ? p.m_partId1 : p.m_partId0, 3);
        ck_assert_int_eq(swapped ? p.m_partId0 : p.m_partId1, 4);
        ck_assert_int_eq(swapped ? p.m_index1 : p.m_index0, 7);
        ck_assert_int_eq(swapped ? p.m_index0 : p.m_index1, 9);
    }
}
END_TEST

// Warm starting follows features, not positions: four contacts 0.01 apart
// (inside the rig's breaking threshold of 0.02) whose positions rotate by
// one place between frames keep their own impulses. They first meet 0.03
// apart (a fresh point within the threshold of another would be merged
// into it, as Bullet does) and close in by 0.01 along each axis, within
// the threshold of their own places. Bullet's distance matching hands
// every impulse to the wrong contact here.
START_TEST(writer_impulses_follow_features)
{
    const btScalar xs[4] = {btScalar(-0.005), btScalar(0.005), btScalar(0.005), btScalar(-0.005)};
    const btScalar zs[4] = {btScalar(-0.005), btScalar(-0.005), btScalar(0.005), btScalar(0.005)};
    for (int swapped = 0; swapped < 2; swapped++) {
        WriterRig rig(swapped != 0);
        mkb::PairContact c[4];
        for (int i = 0; i < 4; i++) c[i] = contact(3 * xs[i], 3 * zs[i], btScalar(-0.01), 10 + i, 20 + i);
        rig.write(c, 4);
        ck_assert_int_eq(rig.manifold.getNumContacts(), 4);
        for (int i = 0; i < 4; i++) c[i] = contact(xs[i], zs[i], btScalar(-0.01), 10 + i, 20 + i);
        rig.write(c, 4);
        ck_assert_int_eq(rig.manifold.getNumContacts(), 4);
        for (int i = 0; i < 4; i++) {
            btManifoldPoint &p = rig.manifold.getContactPoint(rig.slot_of(10 + i));
            p.m_appliedImpulse = btScalar(1 + i);
            p.m_appliedImpulseLateral1 = btScalar(0.1 * (1 + i));
        }
        for (int i = 0; i < 4; i++) c[i] = contact(xs[(i + 1) % 4], zs[(i + 1) % 4], btScalar(-0.02), 10 + i, 20 + i);
        rig.write(c, 4);
        ck_assert_int_eq(rig.manifold.getNumContacts(), 4);
        for (int i = 0; i < 4; i++) {
            int s = rig.slot_of(10 + i);
            ck_assert_int_ge(s, 0);
            const btManifoldPoint &p = rig.manifold.getContactPoint(s);
            MK_ASSERT_NEAR(p.m_appliedImpulse, 1 + i, 0);
            MK_ASSERT_NEAR(p.m_appliedImpulseLateral1, 0.1 * (1 + i), 1e-6);
            MK_ASSERT_NEAR(p.m_positionWorldOnB.x(), xs[(i + 1) % 4], 1e-6);
            MK_ASSERT_NEAR(p.m_distance1, -0.02, 1e-6);
        }
    }
    // The same motion through Bullet's own matching, to show the test bites.
    WriterRig rig(false);
    btManifoldResult r(rig.wa, rig.wb);
    r.setPersistentManifold(&rig.manifold);
    for (int i = 0; i < 4; i++) r.addContactPoint(btVector3(0, 1, 0), btVector3(3 * xs[i], 1, 3 * zs[i]), btScalar(-0.01));
    for (int i = 0; i < 4; i++) r.addContactPoint(btVector3(0, 1, 0), btVector3(xs[i], 1, zs[i]), btScalar(-0.01));
    for (int s = 0; s < rig.manifold.getNumContacts(); s++)
        for (int i = 0; i < 4; i++) {
            btManifoldPoint &p = rig.manifold.getContactPoint(s);
            if (p.m_positionWorldOnB.x() == xs[i] && p.m_positionWorldOnB.z() == zs[i]) p.m_appliedImpulse = btScalar(1 + i);
        }
    for (int i = 0; i < 4; i++) r.addContactPoint(btVector3(0, 1, 0), btVector3(xs[(i + 1) % 4], 1, zs[(i + 1) % 4]), btScalar(-0.02));
    // Contact i (now at place i + 1) should be there and carry impulse 1 + i.
    int right = 0;
    for (int i = 0; i < 4; i++)
        for (int s = 0; s < rig.manifold.getNumContacts(); s++) {
            const btManifoldPoint &p = rig.manifold.getContactPoint(s);
            if (p.m_positionWorldOnB.x() == xs[(i + 1) % 4] && p.m_positionWorldOnB.z() == zs[(i + 1) % 4])
                right += p.m_appliedImpulse == btScalar(1 + i);
        }
    ck_assert_int_lt(right, 4);
}
END_TEST

int g_started = 0, g_ended = 0;
void on_started(btPersistentManifold *const &) { g_started++; }
void on_ended(btPersistentManifold *const &) { g_ended++; }

// Features that are not reported stay while they still touch, as in
// Bullet's own manifolds, and leave through refreshContactPoints once they
// separate; new ones start cold in free room first, then in the slot
// Bullet's own area rule picks (the same manifold as addContactPoint
// leaves); the started / ended callbacks fire once per touching episode,
// never in between.
START_TEST(writer_gone_new_and_callbacks)
{
    WriterRig rig(false), ref(false);  // ref: Bullet's addContactPoint, before the callbacks are set
    const btTransform rest = rig.ta;
    mkb::PairContact c[4] = {contact(-1, -1, btScalar(-0.01), 1, 1), contact(1, -1, btScalar(-0.01), 2, 2),
                             contact(1, 1, btScalar(-0.01), 3, 3), contact(-1, 1, btScalar(-0.01), 4, 4)};
    btManifoldResult r(ref.wa, ref.wb);
    r.setPersistentManifold(&ref.manifold);
    for (int f = 0; f < 4; f++) r.addContactPoint(c[f].normal_on_b, c[f].point_on_b, c[f].distance);
    for (int f = 0; f < 4; f++) ref.manifold.getContactPoint(f).m_appliedImpulse = btScalar(f + 1);
    ContactStartedCallback old_started = gContactStartedCallback;
    ContactEndedCallback old_ended = gContactEndedCallback;
    gContactStartedCallback = on_started;
    gContactEndedCallback = on_ended;
    g_started = g_ended = 0;
    rig.write(c, 3);
    ck_assert_int_eq(rig.manifold.getNumContacts(), 3);
    rig.write(c, 4);  // 4 is new and there is room: appended
    ck_assert_int_eq(rig.manifold.getNumContacts(), 4);
    for (int f = 1; f <= 4; f++) rig.manifold.getContactPoint(rig.slot_of(f)).m_appliedImpulse = btScalar(f);
    // Frame 2: 2 and 3 are reported, 1 and 4 are not, 5 is new; one point
    // beyond the breaking threshold is dropped. The manifold is full:
    // Bullet's area rule keeps 1 (the deepest cached point, first of
    // equals) and the largest area, 1 2 5 4, so 5 takes the slot of 3,
    // reported or not. 1 and 4 still touch and keep their slots and
    // impulses.
    mkb::PairContact d[4] = {contact(1, -1, btScalar(-0.01), 2, 2), contact(0, 0, btScalar(0.5), 6, 6),
                             contact(1, 1, btScalar(-0.01), 3, 3), contact(0, 1, btScalar(0.01), 5, 5)};
    rig.write(d, 4);
    for (int f = 0; f < 4; f++) r.addContactPoint(d[f].normal_on_b, d[f].point_on_b, d[f].distance);
    ck_assert_int_eq(rig.manifold.getNumContacts(), 4);
    ck_assert_int_eq(ref.manifold.getNumContacts(), 4);
    for (int s = 0; s < 4; s++) {
        const btManifoldPoint &p = rig.manifold.getContactPoint(s), &q = ref.manifold.getContactPoint(s);
        check_point_equal(p, q);
        MK_ASSERT_NEAR(p.m_appliedImpulse, q.m_appliedImpulse, 0);
    }
    ck_assert_int_eq(rig.slot_of(3), -1);
    ck_assert_int_eq(rig.slot_of(6), -1);
    ck_assert_int_eq(rig.slot_of(5), 2);
    MK_ASSERT_NEAR(rig.manifold.getContactPoint(rig.slot_of(1)).m_appliedImpulse, 1, 0);
    MK_ASSERT_NEAR(rig.manifold.getContactPoint(rig.slot_of(2)).m_appliedImpulse, 2, 0);
    MK_ASSERT_NEAR(rig.manifold.getContactPoint(rig.slot_of(4)).m_appliedImpulse, 4, 0);
    MK_ASSERT_NEAR(rig.manifold.getContactPoint(rig.slot_of(5)).m_appliedImpulse, 0, 0);
    ck_assert_int_eq(rig.manifold.getContactPoint(rig.slot_of(5)).getLifeTime(), 0);
    // Frame 3: A lifts by 0.035 along the normal and only 5 is reported (at
    // its new distance); refresh drops 1, 2 and 4, now 0.025 apart, beyond
    // the breaking threshold of 0.02.
    rig.move_a(rest, btScalar(0.035));
    d[3].distance = btScalar(0.015);
    rig.write(&d[3], 1);
    rig.refresh();
    ck_assert_int_eq(rig.manifold.getNumContacts(), 1);
    ck_assert_int_eq(rig.slot_of(5), 0);
    ck_assert_int_eq(g_started, 1);
    ck_assert_int_eq(g_ended, 0);
    // Frame 4: separated; frame 5: touching again.
    rig.move_a(rest, btScalar(0.1));
    rig.write(nullptr, 0);
    rig.refresh();
    ck_assert_int_eq(rig.manifold.getNumContacts(), 0);
    ck_assert_int_eq(g_ended, 1);
    rig.move_a(rest, 0);
    rig.write(c, 2);
    ck_assert_int_eq(g_started, 2);
    gContactStartedCallback = old_started;
    gContactEndedCallback = old_ended;
}
END_TEST

int g_processed = 0;
bool on_processed(btManifoldPoint &, void *, void *)
{
    g_processed++;
    return true;
}

// A manifold written whole (every point reported now) is refreshed by aging
// alone, to the same points Bullet's refreshContactPoints leaves (lifetimes,
// positions, distances, processed callbacks), in both manifold orders; one
// that keeps an unreported point says so and gets Bullet's refresh, which
// drops that point once it separates.
START_TEST(writer_refresh_of_fresh_points)
{
    ContactProcessedCallback old_processed = gContactProcessedCallback;
    gContactProcessedCallback = on_processed;
    for (int swapped = 0; swapped < 2; swapped++) {
        WriterRig mine(swapped != 0), ref(swapped != 0);
        mkb::PairContact c[4] = {contact(-1, -1, btScalar(-0.01), 1, 1), contact(1, -1, btScalar(-0.02), 2, 2),
                                 contact(1, 1, btScalar(0.01), 3, 3), contact(-1, 1, btScalar(-0.005), 4, 4)};
        for (int frame = 0; frame < 3; frame++) {
            for (mkb::PairContact &k : c) k.distance -= btScalar(0.001);
            ck_assert(mine.write(c, 4));
            ck_assert(ref.write(c, 4));
            g_processed = 0;
            mine.refresh_contacts(true);
            ck_assert_int_eq(g_processed, 4);
            ref.refresh();
            ck_assert_int_eq(mine.manifold.getNumContacts(), 4);
            ck_assert_int_eq(ref.manifold.getNumContacts(), 4);
            for (int i = 0; i < 4; i++) {
                const btManifoldPoint &p = mine.manifold.getContactPoint(i), &q = ref.manifold.getContactPoint(i);
                check_point_equal(p, q);
                ck_assert_int_eq(p.getLifeTime(), frame + 1);
                ck_assert_int_eq(q.getLifeTime(), frame + 1);
            }
        }
        // 4 not reported: kept by the write, which says so; A then moves by
        // 0.03, and the refresh is Bullet's: the same points as on the
        // reference (unswapped: 3 and 4 are beyond the breaking threshold).
        c[3].distance = btScalar(0.5);
        const btTransform rest = mine.ta;
        ck_assert(!mine.write(c, 3));
        ck_assert(!ref.write(c, 3));
        mine.move_a(rest, btScalar(0.03));
        ref.move_a(rest, btScalar(0.03));
        mine.refresh_contacts(false);
        ref.refresh();
        ck_assert_int_eq(mine.manifold.getNumContacts(), swapped ? 4 : 2);
        ck_assert_int_eq(ref.manifold.getNumContacts(), mine.manifold.getNumContacts());
        for (int i = 0; i < mine.manifold.getNumContacts(); i++)
            check_point_equal(mine.manifold.getContactPoint(i), ref.manifold.getContactPoint(i));
    }
    gContactProcessedCallback = old_processed;
}
END_TEST

// Two reported points within the breaking threshold of each other are one
// contact, as for Bullet's getCacheEntry: a point that matches no cached
// feature lands on the manifold point nearest to it, also one written this
// frame, and of two points written this frame the deeper stays, in either
// order (the deepest point is never lost); the slot keeps its warm-start
// state. Bullet's own matching keeps the later point instead.
START_TEST(writer_merges_points_within_threshold)
{
    for (int order = 0; order < 2; order++) {
        WriterRig rig(order != 0);
        mkb::PairContact c[2] = {contact(btScalar(0.3), 0, btScalar(-0.01), 1, 1),
                                 contact(btScalar(0.305), 0, btScalar(-0.02), 2, 2)};
        if (order) std::swap(c[0], c[1]);
        rig.write(c, 2);
        ck_assert_int_eq(rig.manifold.getNumContacts(), 1);
        ck_assert_int_eq(rig.slot_of(2), 0);
        MK_ASSERT_NEAR(rig.manifold.getContactPoint(0).m_distance1, -0.02, 1e-9);
        // 1 now has the slot by its key (impulse 5); 3, new and shallower,
        // merges into it whether it comes first or last.
        mkb::PairContact k = contact(btScalar(0.3), 0, btScalar(-0.01), 1, 1);
        rig.write(&k, 1);
        ck_assert_int_eq(rig.slot_of(1), 0);
        rig.manifold.getContactPoint(0).m_appliedImpulse = 5;
        mkb::PairContact d[2] = {contact(btScalar(0.305), 0, btScalar(-0.005), 3, 3), k};
        if (order) std::swap(d[0], d[1]);
        rig.write(d, 2);
        ck_assert_int_eq(rig.manifold.getNumContacts(), 1);
        ck_assert_int_eq(rig.slot_of(1), 0);
        MK_ASSERT_NEAR(rig.manifold.getContactPoint(0).m_appliedImpulse, 5, 0);
        // 3 deeper than 1: 3 takes the slot and its impulse.
        d[order ? 1 : 0].distance = btScalar(-0.02);
        rig.write(d, 2);
        ck_assert_int_eq(rig.manifold.getNumContacts(), 1);
        ck_assert_int_eq(rig.slot_of(3), 0);
        MK_ASSERT_NEAR(rig.manifold.getContactPoint(0).m_appliedImpulse, 5, 0);
        MK_ASSERT_NEAR(rig.manifold.getContactPoint(0).m_distance1, -0.02, 1e-9);
    }
}
END_TEST

// A contact whose features change while it stays in place (a corner sliding
// past an edge: vertex-face becomes edge-edge) keeps its impulses under its
// new key; one that moves farther than the breaking threshold starts cold.
START_TEST(writer_moved_feature_keeps_impulse)
{
    WriterRig rig(false);
    mkb::PairContact c[2] = {contact(-1, 0, btScalar(-0.01), 1, 1), contact(1, 0, btScalar(-0.01), 2, 2)};
    rig.write(c, 2);
    rig.manifold.getContactPoint(rig.slot_of(1)).m_appliedImpulse = 1;
    rig.manifold.getContactPoint(rig.slot_of(2)).m_appliedImpulse = 2;
    mkb::PairContact d[2] = {contact(btScalar(-1.005), 0, btScalar(-0.01), 7, 7),
                             contact(btScalar(1.5), 0, btScalar(-0.01), 8, 8)};
    rig.write(d, 2);
    ck_assert_int_eq(rig.slot_of(1), -1);
    ck_assert_int_ge(rig.slot_of(7), 0);
    ck_assert_int_ge(rig.slot_of(8), 0);
    MK_ASSERT_NEAR(rig.manifold.getContactPoint(rig.slot_of(7)).m_appliedImpulse, 1, 0);
    MK_ASSERT_NEAR(rig.manifold.getContactPoint(rig.slot_of(7)).m_positionWorldOnB.x(), -1.005, 1e-6);
    MK_ASSERT_NEAR(rig.manifold.getContactPoint(rig.slot_of(8)).m_appliedImpulse, 0, 0);
    // 2 was not reported and still touches: it stays beside its far successor.
    MK_ASSERT_NEAR(rig.manifold.getContactPoint(rig.slot_of(2)).m_appliedImpulse, 2, 0);
    ck_assert_int_eq(rig.manifold.getNumContacts(), 3);
}
END_TEST

// A contact that keeps its features but whose anchor on the manifold's body
// 0 moved farther than the breaking threshold in one frame (a corner sliding
// fast over a face) is a new contact, as for Bullet's getCacheEntry: it
// starts cold instead of pushing with the impulse of another place. Within
// the threshold it keeps its impulses; both as Bullet's own matching does.
START_TEST(writer_far_moved_feature_starts_cold)
{
    const btScalar moves[2] = {btScalar(0.015), btScalar(0.05)};  // threshold 0.02
    for (int swapped = 0; swapped < 2; swapped++) {
        for (int k = 0; k < 2; k++) {
            WriterRig mine(swapped != 0), ref(swapped != 0);
            mkb::PairContact c = contact(btScalar(0.2), btScalar(0.3), btScalar(-0.01), 4, 5);
            mine.write(&c, 1);
            btManifoldResult r(ref.wa, ref.wb);
            r.setPersistentManifold(&ref.manifold);
            r.addContactPoint(c.normal_on_b, c.point_on_b, c.distance);
            for (WriterRig *w : {&mine, &ref}) {
                w->manifold.getContactPoint(0).m_appliedImpulse = 3;
                w->manifold.getContactPoint(0).m_appliedImpulseLateral1 = btScalar(0.5);
            }
            c.point_on_b += btVector3(moves[k], 0, 0);
            mine.write(&c, 1);
            r.addContactPoint(c.normal_on_b, c.point_on_b, c.distance);
            const bool warm = k == 0;
            const int s = warm ? 0 : 1;  // appended after the old point
            // The far one is new: the old point stays beside it until the
            // refresh drops it (slid beyond the threshold), in both manifolds.
            ck_assert_int_eq(mine.manifold.getNumContacts(), warm ? 1 : 2);
            ck_assert_int_eq(ref.manifold.getNumContacts(), mine.manifold.getNumContacts());
            const btManifoldPoint &p = mine.manifold.getContactPoint(s);
            const btManifoldPoint &q = ref.manifold.getContactPoint(s);
            ck_assert_int_eq(swapped ? p.m_partId1 : p.m_partId0, 4);
            MK_ASSERT_NEAR(p.m_appliedImpulse, warm ? 3 : 0, 0);
            MK_ASSERT_NEAR(p.m_appliedImpulseLateral1, warm ? 0.5 : 0, 0);
            MK_ASSERT_NEAR(q.m_appliedImpulse, p.m_appliedImpulse, 0);
            MK_ASSERT_NEAR(p.m_positionWorldOnB.x(), 0.2 + moves[k], 1e-6);
            MK_ASSERT_NEAR(q.m_positionWorldOnB.x(), 0.2 + moves[k], 1e-6);
        }
    }
}
END_TEST

// Inside a mesh (part ids taken) the writer leaves matching to Bullet and the
// parent's identifiers stay on the points.
START_TEST(writer_mesh_parts_left_to_bullet)
{
    WriterRig rig(false, 5);
    btManifoldResult r(rig.wa, rig.wb);
    r.setPersistentManifold(&rig.manifold);
    r.setShapeIdentifiersA(5, 7);
    r.setShapeIdentifiersB(-1, 9);
    mkb::PairContact c[2] = {contact(-1, 0, btScalar(-0.01), 1, 1), contact(1, 0, btScalar(-0.01), 2, 2)};
    mkb::write_contacts(&r, c, 2);
    ck_assert_int_eq(rig.manifold.getNumContacts(), 2);
    for (int i = 0; i < 2; i++) {
        ck_assert_int_eq(rig.manifold.getContactPoint(i).m_partId0, 5);
        ck_assert_int_eq(rig.manifold.getContactPoint(i).m_partId1, -1);
    }
}
END_TEST


// ---- the broadphase ----------------------------------------------------------

// A small dynamics world on a given broadphase; bodies and shapes owned.
struct TestWorld {
    btDefaultCollisionConfiguration config;
    btCollisionDispatcher dispatcher{&config};
    btBroadphaseInterface *bp;
    btSequentialImpulseConstraintSolver solver;
    btDiscreteDynamicsWorld *world;
    std::vector<btCollisionShape *> shapes;
    std::vector<btRigidBody *> bodies;

    explicit TestWorld(btBroadphaseInterface *broadphase) : bp(broadphase)
    {
        world = new btDiscreteDynamicsWorld(&dispatcher, bp, &solver, &config);
        world->getDispatchInfo().m_deterministicOverlappingPairs = true;
        world->setGravity(btVector3(0, -10, 0));
    }
    ~TestWorld()
    {
        while (!bodies.empty()) remove(bodies.back());
        delete world;
        delete bp;
        for (btCollisionShape *s : shapes) delete s;
    }
    btCollisionShape *own(btCollisionShape *s)
    {
        shapes.push_back(s);
        return s;
    }
    btRigidBody *add(btCollisionShape *shape, btScalar mass, const btVector3 &at, int group = 0, int mask = 0)
    {
        btVector3 inertia(0, 0, 0);
        if (mass > 0) shape->calculateLocalInertia(mass, inertia);
        btRigidBody *b = new btRigidBody(mass, nullptr, shape, inertia);
        b->setWorldTransform(btTransform(btQuaternion::getIdentity(), at));
        if (group) world->addRigidBody(b, group, mask);
        else world->addRigidBody(b);
        bodies.push_back(b);
        return b;
    }
    void remove(btRigidBody *b)
    {
        world->removeRigidBody(b);
        bodies.erase(std::find(bodies.begin(), bodies.end(), b));
        delete b;
    }
};

// The scene every broadphase test shares: a static ground box, a tilted
// static plane, a few static boxes touching each other (static-static pairs
// must never appear), a kinematic box sliding through, and a pile of seeded
// random boxes, spheres and capsules falling onto the ground.
void fill_scene(TestWorld &w, int count, unsigned long long seed)
{
    btCollisionShape *ground = w.own(new btBoxShape(btVector3(20, 1, 20)));
    w.add(ground, 0, btVector3(0, -1, 0));
    w.add(w.own(new btStaticPlaneShape(btVector3(1, 1, 0).normalized(), -6)), 0, btVector3(0, 0, 0));
    btCollisionShape *post = w.own(new btBoxShape(btVector3(btScalar(0.5), 2, btScalar(0.5))));
    for (int i = 0; i < 3; i++) w.add(post, 0, btVector3(btScalar(4 + i), 2, 4));
    btRigidBody *kin = w.add(w.own(new btBoxShape(btVector3(1, btScalar(0.5), 1))), 0, btVector3(-6, btScalar(0.5), 0));
    kin->setCollisionFlags(kin->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    kin->setActivationState(DISABLE_DEACTIVATION);
    btCollisionShape *kinds[3] = {w.own(new btBoxShape(btVector3(btScalar(0.4), btScalar(0.3), btScalar(0.5)))),
                                  w.own(new btSphereShape(btScalar(0.35))),
                                  w.own(new btCapsuleShape(btScalar(0.2), btScalar(0.6)))};
    mk_rng rng = {seed};
    for (int i = 0; i < count; i++) {
        btVector3 at((btScalar)mk_rng_range(&rng, -3, 3), (btScalar)mk_rng_range(&rng, 1, 8), (btScalar)mk_rng_range(&rng, -3, 3));
        w.add(kinds[i % 3], 1, at);
    }
}

// Moves the kinematic box along x (BodyIndex 5 in fill_scene's order).
void drive_kinematic(TestWorld &w, int step)
{
    btRigidBody *kin = w.bodies[5];
    btTransform t = kin->getWorldTransform();
    t.setOrigin(btVector3(btScalar(-6 + 0.1 * step), btScalar(0.5), 0));
    kin->setWorldTransform(t);
}

typedef std::vector<std::pair<int, int> > UidPairs;

UidPairs cache_pairs(btBroadphaseInterface *bp)
{
    UidPairs out;
    btBroadphasePairArray &a = bp->getOverlappingPairCache()->getOverlappingPairArray();
    for (int i = 0; i < a.size(); i++) {
        int u = a[i].m_pProxy0->m_uniqueId, v = a[i].m_pProxy1->m_uniqueId;
        out.push_back(std::make_pair(std::min(u, v), std::max(u, v)));
    }
    std::sort(out.begin(), out.end());
    return out;
}

// The box a broadphase pairs a proxy by: Minko's filed (fat) box, or the
// stored AABB for Bullet's own broadphases.
void pairing_box(btBroadphaseInterface *bp, const btBroadphaseProxy *h, btVector3 &lo, btVector3 &hi)
{
    if (const mkb::Broadphase *m = dynamic_cast<const mkb::Broadphase *>(bp)) {
        m->filed_aabb(h, lo, hi);
    } else {
        lo = h->m_aabbMin;
        hi = h->m_aabbMax;
    }
}

// Every pair of proxies whose pairing boxes overlap (closed) and that the pair
// cache's filter accepts: what an exact broadphase must report.
UidPairs brute_pairs(TestWorld &w)
{
    UidPairs out;
    btOverlappingPairCache *cache = w.bp->getOverlappingPairCache();
    btCollisionObjectArray &objs = w.world->getCollisionObjectArray();
    for (int i = 0; i < objs.size(); i++) {
        for (int j = i + 1; j < objs.size(); j++) {
            btBroadphaseProxy *a = objs[i]->getBroadphaseHandle(), *b = objs[j]->getBroadphaseHandle();
            btVector3 alo, ahi, blo, bhi;
            pairing_box(w.bp, a, alo, ahi);
            pairing_box(w.bp, b, blo, bhi);
            if (!TestAabbAgainstAabb2(alo, ahi, blo, bhi)) continue;
            if (!cache->needsBroadphaseCollision(a, b)) continue;
            out.push_back(std::make_pair(std::min(a->m_uniqueId, b->m_uniqueId), std::max(a->m_uniqueId, b->m_uniqueId)));
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}

void check_exact_pairs(TestWorld &w, int step)
{
    UidPairs got = cache_pairs(w.bp), want = brute_pairs(w);
    ck_assert_msg(got == want, "step %d: %d pairs in the cache, %d overlapping and accepted", step, (int)got.size(),
                  (int)want.size());
}

START_TEST(bp_pairs_exact_every_step)
{
    const mk_bp_kind kinds[3] = {MK_BP_SAP, MK_BP_HGRID, MK_BP_AUTO};
    for (mk_bp_kind kind : kinds) {
        TestWorld w(new mkb::Broadphase(kind));
        fill_scene(w, 60, 7);
        for (int step = 0; step < 90; step++) {
            drive_kinematic(w, step);
            w.world->stepSimulation(btScalar(1) / 60, 0);
            check_exact_pairs(w, step);
        }
        // uids: creation order from 1.
        for (size_t i = 0; i < w.bodies.size(); i++)
            ck_assert_int_eq(w.bodies[i]->getBroadphaseHandle()->m_uniqueId, (int)i + 1);
        ck_assert_int_eq(static_cast<mkb::Broadphase *>(w.bp)->take_error(), MK_OK);
    }
}
END_TEST

// Same scene on Bullet's exact reference broadphase (btSimpleBroadphase) and on
// Minko: with deterministic pair order the simulations are bit-identical.
START_TEST(bp_same_trajectories_as_bullet)
{
    TestWorld ref(new btSimpleBroadphase(256));
    TestWorld dbvt(new btDbvtBroadphase());
    TestWorld mine(new mkb::Broadphase(MK_BP_AUTO));
    for (TestWorld *w : {&ref, &dbvt, &mine}) {
        fill_scene(*w, 40, 11);
        for (int step = 0; step < 120; step++) {
            drive_kinematic(*w, step);
            w->world->stepSimulation(btScalar(1) / 60, 0);
        }
    }
    for (size_t i = 0; i < ref.bodies.size(); i++) {
        const btVector3 &p = ref.bodies[i]->getWorldTransform().getOrigin();
        const btVector3 &q = mine.bodies[i]->getWorldTransform().getOrigin();
        const btVector3 &d = dbvt.bodies[i]->getWorldTransform().getOrigin();
        ck_assert_msg(p == q, "body %d: simple (%.17g %.17g %.17g) minko (%.17g %.17g %.17g)", (int)i, (double)p.x(),
                      (double)p.y(), (double)p.z(), (double)q.x(), (double)q.y(), (double)q.z());
        ck_assert_msg(d == q, "body %d: dbvt (%.17g %.17g %.17g) minko (%.17g %.17g %.17g)", (int)i, (double)d.x(),
                      (double)d.y(), (double)d.z(), (double)q.x(), (double)q.y(), (double)q.z());
    }
}
END_TEST

// The owned pair cache's deterministic dispatch visits every pair once, in
// exactly the order Bullet's own btHashedOverlappingPairCache does for the
// same pairs, also after proxies were destroyed and new ones (higher uids,
// reused Minko slots) created, and twice in a row (the kept order); without
// the flag it visits them all too.
START_TEST(bp_deterministic_dispatch_order)
{
    struct Recorder : btOverlapCallback {
        std::vector<std::pair<int, int>> seen;
        bool processOverlap(btBroadphasePair &pair) override
        {
            seen.push_back(std::make_pair(pair.m_pProxy0->m_uniqueId, pair.m_pProxy1->m_uniqueId));
            return false;
        }
    };
    btDefaultCollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config);
    mkb::Broadphase bp(MK_BP_AUTO, nullptr, 16);
    mk_rng rng = {77};
    std::vector<btBroadphaseProxy *> proxies;
    auto add = [&]() {
        const btVector3 c((btScalar)mk_rng_range(&rng, -4, 4), (btScalar)mk_rng_range(&rng, -4, 4),
                          (btScalar)mk_rng_range(&rng, -4, 4));
        const btVector3 h((btScalar)mk_rng_range(&rng, 0.2, 1.5), (btScalar)mk_rng_range(&rng, 0.2, 1.5),
                          (btScalar)mk_rng_range(&rng, 0.2, 1.5));
        proxies.push_back(bp.createProxy(c - h, c + h, BOX_SHAPE_PROXYTYPE, nullptr, 1, -1, &dispatcher));
    };
    for (int i = 0; i < 300; i++) add();
    for (int round = 0; round < 3; round++) {
        bp.calculateOverlappingPairs(&dispatcher);
        btOverlappingPairCache *cache = bp.getOverlappingPairCache();
        ck_assert_int_gt(cache->getNumOverlappingPairs(), 300);
        btHashedOverlappingPairCache bullets;
        for (int i = 0; i < cache->getNumOverlappingPairs(); i++)
            bullets.addOverlappingPair(cache->getOverlappingPairArray()[i].m_pProxy0,
                                       cache->getOverlappingPairArray()[i].m_pProxy1);
        btDispatcherInfo info;
        Recorder ordered, again, reference, plain;
        info.m_deterministicOverlappingPairs = true;
        cache->processAllOverlappingPairs(&ordered, &dispatcher, info);
        cache->processAllOverlappingPairs(&again, &dispatcher, info);
        bullets.processAllOverlappingPairs(&reference, &dispatcher, info);
        info.m_deterministicOverlappingPairs = false;
        cache->processAllOverlappingPairs(&plain, &dispatcher, info);
        ck_assert_int_eq((int)ordered.seen.size(), cache->getNumOverlappingPairs());
        ck_assert(ordered.seen == reference.seen);
        ck_assert(again.seen == reference.seen);
        std::sort(plain.seen.begin(), plain.seen.end());
        std::sort(ordered.seen.begin(), ordered.seen.end());
        ck_assert(plain.seen == ordered.seen);
        // Destroy every third proxy, add as many (new uids, reused slots).
        for (size_t i = 0; i < proxies.size(); i += 3) {
            bp.destroyProxy(proxies[i], &dispatcher);
            proxies[i] = proxies.back();
            proxies.pop_back();
        }
        while (proxies.size() < 300) add();
    }
    // A few proxies move per step (a few pairs come and go, others move in
    // the pair array): the kept order merged with the changed places must
    // still be exactly Bullet's.
    for (int round = 0; round < 30; round++) {
        for (int k = 0; k < 2; k++) {
            btBroadphaseProxy *p = proxies[(size_t)mk_rng_range(&rng, 0, 299.99)];
            const btVector3 c((btScalar)mk_rng_range(&rng, -4, 4), (btScalar)mk_rng_range(&rng, -4, 4),
                              (btScalar)mk_rng_range(&rng, -4, 4));
            const btVector3 h((btScalar)0.5, (btScalar)0.5, (btScalar)0.5);
            bp.setAabb(p, c - h, c + h, &dispatcher);
        }
        bp.calculateOverlappingPairs(&dispatcher);
        btOverlappingPairCache *cache = bp.getOverlappingPairCache();
        btHashedOverlappingPairCache bullets;
        for (int i = 0; i < cache->getNumOverlappingPairs(); i++)
            bullets.addOverlappingPair(cache->getOverlappingPairArray()[i].m_pProxy0,
                                       cache->getOverlappingPairArray()[i].m_pProxy1);
        btDispatcherInfo info;
        info.m_deterministicOverlappingPairs = true;
        Recorder ordered, reference;
        cache->processAllOverlappingPairs(&ordered, &dispatcher, info);
        bullets.processAllOverlappingPairs(&reference, &dispatcher, info);
        ck_assert_int_eq((int)ordered.seen.size(), cache->getNumOverlappingPairs());
        ck_assert(ordered.seen == reference.seen);
    }
    // A callback that removes pairs during the ordered walk: every pair is
    // still visited, the removed ones are gone, and the next walk is again
    // exactly Bullet's order.
    struct Remover : btOverlapCallback {
        std::vector<std::pair<int, int>> seen;
        bool processOverlap(btBroadphasePair &pair) override
        {
            seen.push_back(std::make_pair(pair.m_pProxy0->m_uniqueId, pair.m_pProxy1->m_uniqueId));
            return (pair.m_pProxy0->m_uniqueId + pair.m_pProxy1->m_uniqueId) % 5 == 0;
        }
    };
    {
        btOverlappingPairCache *cache = bp.getOverlappingPairCache();
        std::vector<std::pair<int, int>> all;
        for (int i = 0; i < cache->getNumOverlappingPairs(); i++)
            all.push_back(std::make_pair(cache->getOverlappingPairArray()[i].m_pProxy0->m_uniqueId,
                                         cache->getOverlappingPairArray()[i].m_pProxy1->m_uniqueId));
        btDispatcherInfo info;
        info.m_deterministicOverlappingPairs = true;
        Remover remover;
        cache->processAllOverlappingPairs(&remover, &dispatcher, info);
        std::sort(remover.seen.begin(), remover.seen.end());
        remover.seen.erase(std::unique(remover.seen.begin(), remover.seen.end()), remover.seen.end());
        std::sort(all.begin(), all.end());
        ck_assert(remover.seen == all);
        int removed = 0;
        for (const std::pair<int, int> &u : all) removed += (u.first + u.second) % 5 == 0;
        ck_assert_int_gt(removed, 0);
        ck_assert_int_eq(cache->getNumOverlappingPairs(), (int)all.size() - removed);
        btHashedOverlappingPairCache bullets;
        for (int i = 0; i < cache->getNumOverlappingPairs(); i++)
            bullets.addOverlappingPair(cache->getOverlappingPairArray()[i].m_pProxy0,
                                       cache->getOverlappingPairArray()[i].m_pProxy1);
        Recorder ordered, reference;
        cache->processAllOverlappingPairs(&ordered, &dispatcher, info);
        bullets.processAllOverlappingPairs(&reference, &dispatcher, info);
        ck_assert(ordered.seen == reference.seen);
    }
    for (btBroadphaseProxy *p : proxies) bp.destroyProxy(p, &dispatcher);
    ck_assert_int_eq(bp.take_error(), MK_OK);
}
END_TEST

// Bodies removed (some in contact) and added while the simulation runs: no pair
// may outlive its proxy, and the set stays exact.
START_TEST(bp_proxy_removal_during_simulation)
{
    TestWorld w(new mkb::Broadphase(MK_BP_SAP, nullptr, 16));  // small: also grows by rebuilding
    fill_scene(w, 50, 3);
    btCollisionShape *extra = w.own(new btSphereShape(btScalar(0.3)));
    mk_rng rng = {99};
    for (int step = 0; step < 120; step++) {
        drive_kinematic(w, step);
        w.world->stepSimulation(btScalar(1) / 60, 0);
        check_exact_pairs(w, step);
        if (step % 10 == 9) {
            // Remove three dynamic bodies (index >= 6 keeps the static ones and the kinematic box).
            for (int k = 0; k < 3 && w.bodies.size() > 6; k++) {
                size_t victim = 6 + (size_t)(mk_rng_unit(&rng) * (double)(w.bodies.size() - 6));
                btBroadphaseProxy *gone = w.bodies[victim]->getBroadphaseHandle();
                w.remove(w.bodies[victim]);
                btBroadphasePairArray &a = w.bp->getOverlappingPairCache()->getOverlappingPairArray();
                for (int i = 0; i < a.size(); i++) ck_assert(a[i].m_pProxy0 != gone && a[i].m_pProxy1 != gone);
            }
            w.add(extra, 1, btVector3(0, 5, 0));
            w.world->computeOverlappingPairs();  // pairs of a new proxy appear at the next update
            check_exact_pairs(w, step);
        }
    }
}
END_TEST

struct CountingFilter : btOverlapFilterCallback {
    int calls = 0, static_static = 0;
    bool needBroadphaseCollision(btBroadphaseProxy *a, btBroadphaseProxy *b) const override
    {
        CountingFilter *self = const_cast<CountingFilter *>(this);
        self->calls++;
        const btCollisionObject *oa = static_cast<const btCollisionObject *>(a->m_clientObject);
        const btCollisionObject *ob = static_cast<const btCollisionObject *>(b->m_clientObject);
        if (oa->isStaticObject() && ob->isStaticObject()) self->static_static++;
        // Reject pairs with the odd-uid sphere group, accept the rest.
        return !((a->m_collisionFilterGroup & 64) && (b->m_collisionFilterGroup & 64));
    }
};

// Group/mask AND test as Bullet's cache does it; a user filter callback, even
// installed late, sees static-static candidates too, is asked once per new
// overlap (not every step), and its verdict holds.
START_TEST(bp_filtering)
{
    TestWorld w(new mkb::Broadphase(MK_BP_HGRID));
    fill_scene(w, 20, 5);
    btCollisionShape *ball = w.own(new btSphereShape(btScalar(0.5)));
    // Group 64 objects that exclude each other by mask, overlapping from the start.
    for (int i = 0; i < 4; i++) w.add(ball, 1, btVector3(btScalar(0.5 * i), 10, 0), 64, ~64);
    for (int step = 0; step < 30; step++) {
        w.world->stepSimulation(btScalar(1) / 60, 0);
        check_exact_pairs(w, step);
    }
    UidPairs got = cache_pairs(w.bp);
    for (const auto &p : got)
        ck_assert(!(w.bodies[p.first - 1]->getBroadphaseHandle()->m_collisionFilterGroup & 64 &&
                    w.bodies[p.second - 1]->getBroadphaseHandle()->m_collisionFilterGroup & 64));

    CountingFilter filter;
    w.bp->getOverlappingPairCache()->setOverlapFilterCallback(&filter);
    // Two more static posts touching the first ones, and group-64 balls that now pass the mask.
    btCollisionShape *post = w.shapes[2];
    w.add(post, 0, btVector3(7, 2, 4));
    for (int i = 0; i < 3; i++) w.add(ball, 1, btVector3(btScalar(-4 + 0.6 * i), 3, -4), 64, -1);
    w.world->stepSimulation(btScalar(1) / 60, 0);
    ck_assert_int_gt(filter.static_static, 0);  // asked about static-static candidates, as Dbvt would
    const int after_first = filter.calls;
    for (int step = 0; step < 5; step++) w.world->stepSimulation(btScalar(1) / 60, 0);
    // Only overlaps that began in these steps were asked about: far fewer than the pairs held.
    ck_assert_int_lt(filter.calls - after_first, w.bp->getOverlappingPairCache()->getNumOverlappingPairs());
    got = cache_pairs(w.bp);
    for (const auto &p : got)
        ck_assert(!(w.bodies[p.first - 1]->getBroadphaseHandle()->m_collisionFilterGroup & 64 &&
                    w.bodies[p.second - 1]->getBroadphaseHandle()->m_collisionFilterGroup & 64));
    w.bp->getOverlappingPairCache()->setOverlapFilterCallback(nullptr);
}
END_TEST

struct HitSet : btCollisionWorld::AllHitsRayResultCallback {
    HitSet(const btVector3 &a, const btVector3 &b) : btCollisionWorld::AllHitsRayResultCallback(a, b) {}
    std::vector<std::pair<int, double> > sorted() const
    {
        std::vector<std::pair<int, double> > v;
        for (int i = 0; i < m_collisionObjects.size(); i++)
            v.push_back(std::make_pair(m_collisionObjects[i]->getBroadphaseHandle()->m_uniqueId, (double)m_hitFractions[i]));
        std::sort(v.begin(), v.end());
        return v;
    }
};

// Ray tests and convex sweeps through the world give the same hits as on Dbvt,
// also for objects moved since the last step (the broadphase has not updated yet).
START_TEST(bp_ray_and_sweep_hits_equal_native)
{
    TestWorld dbvt(new btDbvtBroadphase());
    TestWorld mine(new mkb::Broadphase(MK_BP_AUTO));
    for (TestWorld *w : {&dbvt, &mine}) {
        fill_scene(*w, 40, 21);
        for (int step = 0; step < 30; step++) w->world->stepSimulation(btScalar(1) / 60, 0);
        // Teleport one body after the step and refresh its AABB only.
        btRigidBody *b = w->bodies[10];
        b->setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(0, 15, 0)));
        w->world->updateSingleAabb(b);
    }
    btSphereShape probe(btScalar(0.25));
    mk_rng rng = {1234};
    int hits = 0;
    for (int r = 0; r < 200; r++) {
        btVector3 from((btScalar)mk_rng_range(&rng, -8, 8), (btScalar)mk_rng_range(&rng, 0, 20), (btScalar)mk_rng_range(&rng, -8, 8));
        btVector3 to((btScalar)mk_rng_range(&rng, -8, 8), (btScalar)mk_rng_range(&rng, -2, 10), (btScalar)mk_rng_range(&rng, -8, 8));
        if (r % 10 == 0) to = btVector3(0, -5, 0), from = btVector3(0, 20, 0);  // through the teleported body
        HitSet a(from, to), b(from, to);
        dbvt.world->rayTest(from, to, a);
        mine.world->rayTest(from, to, b);
        ck_assert_msg(a.sorted() == b.sorted(), "ray %d: %d hits on Dbvt, %d on Minko", r, a.m_collisionObjects.size(),
                      b.m_collisionObjects.size());
        hits += a.m_collisionObjects.size();
        btTransform t0(btQuaternion::getIdentity(), from), t1(btQuaternion::getIdentity(), to);
        btCollisionWorld::ClosestConvexResultCallback ca(from, to), cb(from, to);
        dbvt.world->convexSweepTest(&probe, t0, t1, ca);
        mine.world->convexSweepTest(&probe, t0, t1, cb);
        ck_assert_int_eq(ca.hasHit(), cb.hasHit());
        if (ca.hasHit()) {
            ck_assert_int_eq(ca.m_hitCollisionObject->getBroadphaseHandle()->m_uniqueId,
                             cb.m_hitCollisionObject->getBroadphaseHandle()->m_uniqueId);
            ck_assert(ca.m_closestHitFraction == cb.m_closestHitFraction);
        }
    }
    ck_assert_int_gt(hits, 100);  // the rays do hit things
    // aabbTest: Minko reports exactly the proxies whose boxes overlap the
    // query (Dbvt's fat leaves report a superset); contactTest on top of it
    // finds the same touching contacts.
    btBoxShape box(btVector3(2, 2, 2));
    btCollisionObject query;
    query.setCollisionShape(&box);
    query.setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(0, 1, 0)));
    btVector3 qlo, qhi;
    box.getAabb(query.getWorldTransform(), qlo, qhi);
    struct Collect : btBroadphaseAabbCallback {
        std::vector<int> uids;
        bool process(const btBroadphaseProxy *p) override
        {
            uids.push_back(p->m_uniqueId);
            return true;
        }
    } na, mi;
    dbvt.bp->aabbTest(qlo, qhi, na);
    mine.bp->aabbTest(qlo, qhi, mi);
    std::vector<int> exact;
    btCollisionObjectArray &objs = mine.world->getCollisionObjectArray();
    for (int i = 0; i < objs.size(); i++) {
        btBroadphaseProxy *h = objs[i]->getBroadphaseHandle();
        if (TestAabbAgainstAabb2(qlo, qhi, h->m_aabbMin, h->m_aabbMax)) exact.push_back(h->m_uniqueId);
    }
    std::sort(na.uids.begin(), na.uids.end());
    std::sort(mi.uids.begin(), mi.uids.end());
    ck_assert_int_gt((int)exact.size(), 3);
    ck_assert(mi.uids == exact);
    ck_assert(std::includes(na.uids.begin(), na.uids.end(), exact.begin(), exact.end()));
    struct Touching : btCollisionWorld::ContactResultCallback {
        std::vector<int> uids;
        btScalar addSingleResult(btManifoldPoint &cp, const btCollisionObjectWrapper *, int, int,
                                 const btCollisionObjectWrapper *b, int, int) override
        {
            if (cp.getDistance() <= 0) uids.push_back(b->getCollisionObject()->getBroadphaseHandle()->m_uniqueId);
            return 0;
        }
    } ka, kb;
    dbvt.world->contactTest(&query, ka);
    mine.world->contactTest(&query, kb);
    std::sort(ka.uids.begin(), ka.uids.end());
    std::sort(kb.uids.begin(), kb.uids.end());
    ck_assert_int_gt((int)ka.uids.size(), 0);
    ck_assert(ka.uids == kb.uids);
}
END_TEST

// A running world moves from Dbvt to Minko's broadphase and back; the pair
// set is exact from the first step on Minko and nothing falls through.
START_TEST(bp_switch_at_run_time)
{
    TestWorld w(new btDbvtBroadphase());
    fill_scene(w, 30, 8);
    for (int step = 0; step < 60; step++) w.world->stepSimulation(btScalar(1) / 60, 0);
    btBroadphaseInterface *old = mkb::set_broadphase(w.world, new mkb::Broadphase(MK_BP_SAP));
    delete old;
    w.bp = w.world->getBroadphase();
    for (int step = 0; step < 60; step++) {
        w.world->stepSimulation(btScalar(1) / 60, 0);
        check_exact_pairs(w, step);
    }
    old = mkb::set_broadphase(w.world, new btDbvtBroadphase());
    delete old;
    w.bp = w.world->getBroadphase();
    for (int step = 0; step < 60; step++) w.world->stepSimulation(btScalar(1) / 60, 0);
    for (size_t i = 6; i < w.bodies.size(); i++) ck_assert(w.bodies[i]->getWorldTransform().getOrigin().y() > 0);  // none fell through
}
END_TEST

// Bad AABBs are refused with a status and the proxy keeps its last box;
// resetPool restarts uids once the broadphase is empty.
START_TEST(bp_bad_input_and_reset)
{
    mkb::Broadphase bp(MK_BP_SAP);
    btCollisionObject o;
    btBroadphaseProxy *p = bp.createProxy(btVector3(0, 0, 0), btVector3(1, 1, 1), BOX_SHAPE_PROXYTYPE, &o, 1, -1, nullptr);
    ck_assert_ptr_nonnull(p);
    ck_assert_int_eq(p->m_uniqueId, 1);
    const btScalar nan = std::numeric_limits<btScalar>::quiet_NaN();
    bp.setAabb(p, btVector3(nan, 0, 0), btVector3(1, 1, 1), nullptr);
    ck_assert_int_eq(bp.take_error(), MK_ERR_BAD_AABB);
    ck_assert_int_eq(bp.take_error(), MK_OK);
    btVector3 lo, hi;
    bp.getAabb(p, lo, hi);
    ck_assert(lo == btVector3(0, 0, 0) && hi == btVector3(1, 1, 1));
    bp.setAabb(p, btVector3(2, 2, 2), btVector3(1, 1, 1), nullptr);  // lo > hi
    ck_assert_int_eq(bp.take_error(), MK_ERR_BAD_AABB);
    bp.calculateOverlappingPairs(nullptr);
    bp.destroyProxy(p, nullptr);
    bp.resetPool(nullptr);
    p = bp.createProxy(btVector3(0, 0, 0), btVector3(1, 1, 1), BOX_SHAPE_PROXYTYPE, &o, 1, -1, nullptr);
    ck_assert_int_eq(p->m_uniqueId, 1);
    bp.destroyProxy(p, nullptr);
}
END_TEST


// ---- the broadphase's fat boxes (filed AABBs) ----------------------------------

// Every proxy's filed box holds its AABB and is the AABB as it was when last
// filed, grown by the margin or (a fast mover) not; the pair set is exactly the brute-force set of
// the filed boxes (check_exact_pairs), so it holds every pair of touching
// AABBs; with margin 0 too (a shrinking box keeps its filed box).
START_TEST(bp_fat_boxes_hold_the_aabbs)
{
    const mk_bp_kind kinds[2] = {MK_BP_SAP, MK_BP_HGRID};
    for (mk_bp_kind kind : kinds) {
        for (btScalar margin : {gDbvtMargin, btScalar(0)}) {
            mkb::Broadphase *bp = new mkb::Broadphase(kind, nullptr, 1024, margin);
            ck_assert(bp->margin() == margin);
            TestWorld w(bp);
            fill_scene(w, 60, 17);
            int refiled = 0, kept = 0, tight_count = 0;
            std::vector<btVector3> last_lo(w.bodies.size());
            for (int step = 0; step < 90; step++) {
                drive_kinematic(w, step);
                w.world->stepSimulation(btScalar(1) / 60, 0);
                check_exact_pairs(w, step);
                for (size_t i = 0; i < w.bodies.size(); i++) {
                    const btBroadphaseProxy *h = w.bodies[i]->getBroadphaseHandle();
                    btVector3 lo, hi;
                    bp->filed_aabb(h, lo, hi);
                    ck_assert(lo.x() <= h->m_aabbMin.x() && lo.y() <= h->m_aabbMin.y() && lo.z() <= h->m_aabbMin.z());
                    ck_assert(hi.x() >= h->m_aabbMax.x() && hi.y() >= h->m_aabbMax.y() && hi.z() >= h->m_aabbMax.z());
                    const btVector3 m(margin, margin, margin);
                    const bool fat = lo == h->m_aabbMin - m && hi == h->m_aabbMax + m;
                    const bool tight = lo == h->m_aabbMin && hi == h->m_aabbMax;
                    if (fat || tight) {  // filed this step (tight: a fast mover)
                        refiled += step > 0 && !(lo == last_lo[i]);
                        tight_count += tight && !fat;
                    } else if (step > 0) {  // (step 0: the box filed when the body was added)
                        ck_assert(lo == last_lo[i]);  // kept from an earlier step
                        kept++;
                    }
                    last_lo[i] = lo;
                }
                // Every pair of touching AABBs is there (the filed boxes hold them).
                UidPairs got = cache_pairs(w.bp);
                for (size_t i = 0; i < w.bodies.size(); i++)
                    for (size_t j = i + 1; j < w.bodies.size(); j++) {
                        btBroadphaseProxy *a = w.bodies[i]->getBroadphaseHandle(), *b = w.bodies[j]->getBroadphaseHandle();
                        if (TestAabbAgainstAabb2(a->m_aabbMin, a->m_aabbMax, b->m_aabbMin, b->m_aabbMax) &&
                            w.bp->getOverlappingPairCache()->needsBroadphaseCollision(a, b))
                            ck_assert(std::binary_search(got.begin(), got.end(), std::make_pair(a->m_uniqueId, b->m_uniqueId)));
                    }
            }
            ck_assert_int_gt(refiled, 0);  // falling bodies leave their boxes
            if (margin > 0) {
                ck_assert_int_gt(kept, 0);         // resting ones stay in them
                ck_assert_int_gt(tight_count, 0);  // fast ones are filed tight
            }
            ck_assert_int_eq(bp->take_error(), MK_OK);
        }
    }
}
END_TEST

// A proxy that moves inside its filed box is not moved in Minko (its box
// there stays, and so does the pair); one that leaves it is filed again:
// tight after a move longer than the margin, grown by it after a short one.
START_TEST(bp_jitter_inside_the_fat_box_costs_nothing)
{
    btDefaultCollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config);
    mkb::Broadphase bp(MK_BP_SAP, nullptr, 16, btScalar(0.05));
    btBroadphaseProxy *a = bp.createProxy(btVector3(0, 0, 0), btVector3(1, 1, 1), BOX_SHAPE_PROXYTYPE, nullptr, 1, -1, &dispatcher);
    btBroadphaseProxy *b = bp.createProxy(btVector3(btScalar(1.08), 0, 0), btVector3(2, 1, 1), BOX_SHAPE_PROXYTYPE, nullptr, 1, -1,
                                          &dispatcher);
    bp.calculateOverlappingPairs(&dispatcher);
    ck_assert_int_eq(bp.getOverlappingPairCache()->getNumOverlappingPairs(), 1);  // 0.08 apart, fat boxes meet
    // Minko's id of a, found by a query over everything.
    struct Find {
        const void *want;
        mk_bp_id id;
        static int visit(void *c, mk_bp_id id, void *user)
        {
            Find *f = static_cast<Find *>(c);
            if (user == f->want) f->id = id;
            return 1;
        }
    } find = {a, MK_BP_NULL_ID};
    MK_ASSERT_STATUS(mk_bp_query_aabb(bp.minko(), mk_aabb_make(mk_v3(-10, -10, -10), mk_v3(10, 10, 10)), Find::visit, &find),
                     MK_OK);
    const mk_bp_id id0 = find.id;
    mk_aabb filed0;
    void *user;
    MK_ASSERT_STATUS(mk_bp_get_proxy(bp.minko(), id0, &filed0, &user), MK_OK);
    ck_assert_uint_ne(id0, MK_BP_NULL_ID);
    mk_rng rng = {5};
    for (int step = 0; step < 50; step++) {
        const btScalar dx = (btScalar)mk_rng_range(&rng, -0.04, 0.04), dy = (btScalar)mk_rng_range(&rng, -0.04, 0.04);
        bp.setAabb(a, btVector3(dx, dy, 0), btVector3(1 + dx, 1 + dy, 1), &dispatcher);
        bp.calculateOverlappingPairs(&dispatcher);
        mk_aabb now;
        MK_ASSERT_STATUS(mk_bp_get_proxy(bp.minko(), id0, &now, &user), MK_OK);
        ck_assert(now.lo.x == filed0.lo.x && now.lo.y == filed0.lo.y && now.hi.x == filed0.hi.x && now.hi.y == filed0.hi.y);
        btVector3 lo, hi;
        bp.getAabb(a, lo, hi);  // Bullet's box, not the filed one
        ck_assert(lo == btVector3(dx, dy, 0) && hi == btVector3(1 + dx, 1 + dy, 1));
        ck_assert_int_eq(bp.getOverlappingPairCache()->getNumOverlappingPairs(), 1);
    }
    // Leaving the filed box by more than the margin in one move: filed again,
    // tight (a fast mover); the pair goes. A small move out of that box next:
    // filed grown by the margin.
    bp.setAabb(a, btVector3(btScalar(-0.2), 0, 0), btVector3(btScalar(0.8), 1, 1), &dispatcher);
    bp.calculateOverlappingPairs(&dispatcher);
    mk_aabb now;
    MK_ASSERT_STATUS(mk_bp_get_proxy(bp.minko(), id0, &now, &user), MK_OK);
    ck_assert(now.lo.x == btScalar(-0.2) && now.hi.x == btScalar(0.8) && now.lo.y == 0 && now.hi.z == 1);
    ck_assert_int_eq(bp.getOverlappingPairCache()->getNumOverlappingPairs(), 0);
    bp.setAabb(a, btVector3(btScalar(-0.19), 0, 0), btVector3(btScalar(0.81), 1, 1), &dispatcher);
    bp.calculateOverlappingPairs(&dispatcher);
    MK_ASSERT_STATUS(mk_bp_get_proxy(bp.minko(), id0, &now, &user), MK_OK);
    ck_assert(now.lo.x == btScalar(-0.19) - btScalar(0.05) && now.hi.x == btScalar(0.81) + btScalar(0.05));
    ck_assert(now.lo.y == -btScalar(0.05) && now.hi.z == 1 + btScalar(0.05));
    bp.destroyProxy(a, &dispatcher);
    bp.destroyProxy(b, &dispatcher);
    ck_assert_int_eq(bp.take_error(), MK_OK);
}
END_TEST

struct UidCollect : btBroadphaseRayCallback {
    std::vector<int> uids;
    bool process(const btBroadphaseProxy *p) override
    {
        uids.push_back(p->m_uniqueId);
        return true;
    }
    std::vector<int> sorted()
    {
        std::sort(uids.begin(), uids.end());
        return uids;
    }
};

// aabbTest and rayTest answer for Bullet's AABBs, not the filed boxes: random
// boxes (some moved since the last update, inside or outside their filed
// boxes) against random queries and rays, and queries made to pass through
// the margin only, against brute force on the AABBs (Bullet's own btRayAabb
// for the rays).
START_TEST(bp_queries_answer_for_the_aabbs)
{
    btDefaultCollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config);
    const btScalar margin = btScalar(0.25);  // wide, so that many queries fall in it
    mkb::Broadphase bp(MK_BP_AUTO, nullptr, 64, margin);
    mk_rng rng = {4242};
    std::vector<btBroadphaseProxy *> proxies;
    auto box_at = [&](btVector3 &lo, btVector3 &hi) {
        const btVector3 c((btScalar)mk_rng_range(&rng, -6, 6), (btScalar)mk_rng_range(&rng, -6, 6), (btScalar)mk_rng_range(&rng, -6, 6));
        const btVector3 h((btScalar)mk_rng_range(&rng, 0.1, 1), (btScalar)mk_rng_range(&rng, 0.1, 1), (btScalar)mk_rng_range(&rng, 0.1, 1));
        lo = c - h;
        hi = c + h;
    };
    for (int i = 0; i < 150; i++) {
        btVector3 lo, hi;
        box_at(lo, hi);
        proxies.push_back(bp.createProxy(lo, hi, BOX_SHAPE_PROXYTYPE, nullptr, 1, -1, &dispatcher));
    }
    int reported = 0, margin_only = 0;
    for (int round = 0; round < 4; round++) {
        bp.calculateOverlappingPairs(&dispatcher);
        // Some move inside their filed box (shrink), some leave it (not yet
        // updated: Minko does not know their box).
        for (size_t i = 0; i < proxies.size(); i += 3) {
            btVector3 lo = proxies[i]->m_aabbMin, hi = proxies[i]->m_aabbMax;
            if (i % 2) {
                lo += btVector3(margin, margin, margin) * btScalar(0.5);
                hi += btVector3(margin, margin, margin) * btScalar(0.5);
            } else {
                box_at(lo, hi);
            }
            bp.setAabb(proxies[i], lo, hi, &dispatcher);
        }
        for (int q = 0; q < 100; q++) {
            btVector3 qlo, qhi;
            box_at(qlo, qhi);
            if (q % 4 == 0) {  // touching a proxy's filed box, missing its AABB
                const btBroadphaseProxy *p = proxies[(size_t)q % proxies.size()];
                btVector3 flo, fhi;
                bp.filed_aabb(p, flo, fhi);
                qlo = btVector3(fhi.x() - margin * btScalar(0.5), p->m_aabbMin.y(), p->m_aabbMin.z());
                qhi = qlo + btVector3(1, 1, 1);
                margin_only += TestAabbAgainstAabb2(qlo, qhi, flo, fhi) &&
                               !TestAabbAgainstAabb2(qlo, qhi, p->m_aabbMin, p->m_aabbMax);
            }
            struct Collect : btBroadphaseAabbCallback {
                std::vector<int> uids;
                bool process(const btBroadphaseProxy *p) override
                {
                    uids.push_back(p->m_uniqueId);
                    return true;
                }
            } got;
            bp.aabbTest(qlo, qhi, got);
            std::vector<int> want;
            for (const btBroadphaseProxy *p : proxies)
                if (TestAabbAgainstAabb2(qlo, qhi, p->m_aabbMin, p->m_aabbMax)) want.push_back(p->m_uniqueId);
            std::sort(got.uids.begin(), got.uids.end());
            std::sort(want.begin(), want.end());
            ck_assert_msg(got.uids == want, "round %d query %d: %d reported, %d overlap", round, q, (int)got.uids.size(),
                          (int)want.size());
            reported += (int)want.size();

            // A ray: random, or through a filed box's margin past the AABB.
            btVector3 from = qlo * 2, to = qhi * -2;
            if (q % 4 == 1) {
                const btBroadphaseProxy *p = proxies[(size_t)q % proxies.size()];
                const btScalar y = p->m_aabbMax.y() + margin * btScalar(0.5);
                from = btVector3(-20, y, (p->m_aabbMin.z() + p->m_aabbMax.z()) / 2);
                to = btVector3(20, y, from.z());
            }
            UidCollect hits;
            bp.rayTest(from, to, hits);
            std::vector<int> ray_want;
            for (const btBroadphaseProxy *p : proxies) {
                btScalar param = 1;
                btVector3 normal;
                if (btRayAabb(from, to, p->m_aabbMin, p->m_aabbMax, param, normal)) ray_want.push_back(p->m_uniqueId);
            }
            std::sort(ray_want.begin(), ray_want.end());
            ck_assert_msg(hits.sorted() == ray_want, "round %d ray %d: %d reported, %d hit", round, q, (int)hits.uids.size(),
                          (int)ray_want.size());
            reported += (int)ray_want.size();
        }
    }
    ck_assert_int_gt(reported, 200);
    ck_assert_int_gt(margin_only, 50);
    for (btBroadphaseProxy *p : proxies) bp.destroyProxy(p, &dispatcher);
    ck_assert_int_eq(bp.take_error(), MK_OK);
}
END_TEST


// ---- the narrowphase ----------------------------------------------------------

struct PointOut {
    btVector3 normal_on_b, on_a, on_b;
    double distance;
    int part0, part1;
};

// One processCollision of the pair (a at xa, b at xb) through a dispatcher
// built on `config`; returns the manifold's points.
std::vector<PointOut> collide_once(btCollisionConfiguration *config, btCollisionShape *a, const btTransform &xa,
                                   btCollisionShape *b, const btTransform &xb, bool *minko_algorithm = nullptr)
{
    btCollisionDispatcher dispatcher(config);
    btCollisionObject oa, ob;
    oa.setCollisionShape(a);
    ob.setCollisionShape(b);
    oa.setWorldTransform(xa);
    ob.setWorldTransform(xb);
    btCollisionObjectWrapper wa(nullptr, a, &oa, xa, -1, -1), wb(nullptr, b, &ob, xb, -1, -1);
    mkb::CollisionConfiguration *mine = dynamic_cast<mkb::CollisionConfiguration *>(config);
    long before = mine ? mine->stats.minko_algorithms.load() : 0;
    btCollisionAlgorithm *algo = dispatcher.findAlgorithm(&wa, &wb, nullptr, BT_CONTACT_POINT_ALGORITHMS);
    if (minko_algorithm) *minko_algorithm = mine && mine->stats.minko_algorithms.load() > before;
    btManifoldResult result(&wa, &wb);
    btDispatcherInfo info;
    algo->processCollision(&wa, &wb, info, &result);
    std::vector<PointOut> out;
    btManifoldArray manifolds;
    algo->getAllContactManifolds(manifolds);
    for (int m = 0; m < manifolds.size(); m++) {
        // A manifold's normal is on its body 1 pointing to its body 0; Bullet's
        // convex-plane algorithm orders its manifold (convex, plane) whatever
        // the pair order. Report everything in the (a, b) order asked for.
        const bool swapped = manifolds[m]->getBody0() != &oa;
        for (int i = 0; i < manifolds[m]->getNumContacts(); i++) {
            const btManifoldPoint &p = manifolds[m]->getContactPoint(i);
            PointOut o = {swapped ? -p.m_normalWorldOnB : p.m_normalWorldOnB,
                          swapped ? p.getPositionWorldOnB() : p.getPositionWorldOnA(),
                          swapped ? p.getPositionWorldOnA() : p.getPositionWorldOnB(), (double)p.getDistance(),
                          swapped ? p.m_partId1 : p.m_partId0, swapped ? p.m_partId0 : p.m_partId1};
            out.push_back(o);
        }
    }
    algo->~btCollisionAlgorithm();
    dispatcher.freeCollisionAlgorithm(algo);
    return out;
}

const PointOut *deepest(const std::vector<PointOut> &v)
{
    const PointOut *best = nullptr;
    for (const PointOut &p : v)
        if (!best || p.distance < best->distance) best = &p;
    return best;
}

btTransform random_pose(mk_rng *rng, double spread)
{
    mk_quat q = mk_rng_quat(rng);
    return btTransform(btQuaternion((btScalar)q.x, (btScalar)q.y, (btScalar)q.z, (btScalar)q.w),
                       btVector3((btScalar)mk_rng_range(rng, -spread, spread), (btScalar)mk_rng_range(rng, -spread, spread),
                                 (btScalar)mk_rng_range(rng, -spread, spread)));
}

#if defined(BT_USE_DOUBLE_PRECISION)
const double kContactTol = 1e-9, kNormalTol = 1e-9;
#else
const double kContactTol = 2e-4, kNormalTol = 1e-5;
#endif

// Hulls: the cached Minko hull grown by the margin is Bullet's hull shape
// (points scaled, margin outside); the cache builds one hull per shape, sees
// changed points, and refuses degenerate clouds (left to Bullet).
START_TEST(shape_hull_cache)
{
    mkb::CollisionConfiguration config;
    btConvexHullShape h;
    mk_rng rng = {31};
    for (int i = 0; i < 40; i++) {
        mk_vec3 p = mk_rng_dir(&rng);
        h.addPoint(btVector3((btScalar)p.x * 2, (btScalar)p.y, (btScalar)p.z * btScalar(0.5)), false);
    }
    h.recalcLocalAabb();
    check_same_solid(&h, "hull", &config);
    check_same_solid(&h, "hull again", &config);
    ck_assert_int_eq(config.hull_count(), 1);
    h.setLocalScaling(btVector3(1, 3, 1));
    h.setMargin(btScalar(0.1));
    check_same_solid(&h, "scaled hull, margin 0.1", &config);
    ck_assert_int_eq(config.hull_count(), 1);
    mkb::ShapeMap before, after;
    MK_ASSERT_STATUS(config.map_shape(&h, &before), MK_OK);
    h.addPoint(btVector3(5, 0, 0));
    MK_ASSERT_STATUS(config.map_shape(&h, &after), MK_OK);
    ck_assert(before.shape.u.hull != after.shape.u.hull);  // rebuilt, the old one kept alive
    check_same_solid(&h, "hull with a new point", &config);
    btConvexHullShape flat;
    flat.addPoint(btVector3(0, 0, 0));
    flat.addPoint(btVector3(1, 0, 0));
    flat.addPoint(btVector3(0, 1, 0));
    MK_ASSERT_STATUS(config.map_shape(&flat, &after), MK_ERR_DEGENERATE);
    btDefaultCollisionConfiguration native;
    btSphereShape ball(btScalar(0.5));
    bool used_minko = true;
    btTransform xa(btQuaternion::getIdentity(), btVector3(0, 0, 0)), xb(btQuaternion::getIdentity(), btVector3(0, btScalar(0.4), 0));
    collide_once(&config, &flat, xa, &ball, xb, &used_minko);
    ck_assert(!used_minko);  // the degenerate hull's pairs run on Bullet
}
END_TEST

// The exact signed distance and normal of two Bullet convex shapes, by the
// long double brute-force oracle on the mapped shapes (the mapping itself is
// checked against Bullet's support functions by the shape tests).
// An oracle shape and pose for a Bullet shape: hulls straight from Bullet's
// scaled points and margin (not through Minko's quickhull), the others from
// the checked mapping.
bool oracle_of(const btCollisionShape *s, const btTransform &x, mk_oracle_shape *o, mk_oracle_pose *pose)
{
    mkb::ShapeMap m;
    m.axis = mk_quat_identity();
    if (s->getShapeType() == CONVEX_HULL_SHAPE_PROXYTYPE) {
        const btConvexHullShape *h = static_cast<const btConvexHullShape *>(s);
        std::vector<mk_lvec3> pts;
        for (int i = 0; i < h->getNumPoints(); i++) {
            btVector3 p = h->getScaledPoint(i);
            pts.push_back(mk_lvec3{(long double)p.x(), (long double)p.y(), (long double)p.z()});
        }
        if (mk_oracle_shape_points(o, pts.data(), (int)pts.size(), (long double)h->getMargin()) != 0) return false;
    } else if (mkb::map_primitive(s, &m) != MK_OK || mk_oracle_shape_init(o, &m.shape) != 0) {
        return false;
    }
    *pose = mk_oracle_pose_of(mkb::minko_pose(x, m));
    return true;
}

bool oracle_reference(const btCollisionShape *a, const btTransform &xa, const btCollisionShape *b, const btTransform &xb,
                      PointOut *out)
{
    mk_oracle_shape oa, ob;
    mk_oracle_pose pa, pb;
    if (!oracle_of(a, xa, &oa, &pa)) return false;
    if (!oracle_of(b, xb, &ob, &pb)) {
        mk_oracle_shape_free(&oa);
        return false;
    }
    mk_oracle_result r;
    const bool ok = mk_oracle_query(&oa, &pa, &ob, &pb, 0, &r) == 0 && r.normal_defined;
    mk_oracle_shape_free(&oa);
    mk_oracle_shape_free(&ob);
    if (!ok) return false;
    out->normal_on_b = -btVector3((btScalar)r.normal.x, (btScalar)r.normal.y, (btScalar)r.normal.z);
    out->distance = (double)r.distance;
    return true;
}

// Minko's contacts in Bullet's conventions agree with Bullet on the same poses:
// the deepest point has the same signed distance and normal (normal on B
// pointing from B to A, negative = penetration), every point satisfies
// on_a = on_b + normal * distance with one normal per manifold. The
// reference is Bullet's own algorithm where it models the same solids
// (sphere-sphere, capsule pairs, shape-plane, box-box by btBoxBoxDetector),
// and the exact oracle where Bullet's algorithm rounds the box by its margin
// instead (btSphereBoxCollisionAlgorithm, GJK and EPA see a box rounded by
// its margin; the shape's support function, its AABB and box-box see the
// sharp box, which is what Minko models).
START_TEST(np_conventions_match_bullet)
{
    btDefaultCollisionConfiguration native;
    mkb::CollisionConfiguration mine;
    btSphereShape sphere(btScalar(0.6));
    btBoxShape box(btVector3(btScalar(0.8), btScalar(0.5), btScalar(0.3)));
    btCapsuleShape capsule(btScalar(0.3), btScalar(0.8));
    btCapsuleShapeZ capsule_z(btScalar(0.25), btScalar(0.5));
    btStaticPlaneShape plane(btVector3(0, 1, 0), btScalar(0.2));
    btConvexHullShape hull;
    mk_rng cloud = {4242};
    for (int i = 0; i < 24; i++) {
        mk_vec3 p = mk_rng_dir(&cloud);
        hull.addPoint(btVector3((btScalar)(0.7 * p.x), (btScalar)(0.4 * p.y), (btScalar)(0.5 * p.z)), false);
    }
    hull.recalcLocalAabb();
    btConvexHullShape sharp_hull(&hull.getPoints()[0].getX(), hull.getNumPoints(), sizeof(btVector3));
    sharp_hull.setMargin(0);  // the sharp core: Minko's polytope path without rounding
    // With polyhedral features Bullet's hull-hull algorithm clips the
    // margin-free cores; the adapter does as Bullet (hull-plane, hull-box:
    // GJK, the solid grown by the margin).
    btConvexHullShape poly_hull(&hull.getPoints()[0].getX(), hull.getNumPoints(), sizeof(btVector3));
    poly_hull.initializePolyhedralFeatures();
    struct Case {
        const char *name;
        btCollisionShape *a, *b;
        bool bullet_same_solid;  // false: compare with the oracle on the sharp solids
        bool closed_form;        // Minko answers it in every build
    } cases[] = {
        {"sphere-sphere", &sphere, &sphere, true, true},       {"sphere-box", &sphere, &box, false, true},
        {"box-sphere", &box, &sphere, false, true},            {"capsule-sphere", &capsule, &sphere, true, true},
        {"capsule-capsule", &capsule, &capsule_z, true, true}, {"box-capsule", &box, &capsule, false, true},
        {"capsule-box", &capsule_z, &box, false, true},        {"sphere-plane", &sphere, &plane, true, true},
        {"plane-box", &plane, &box, true, true},               {"capsule-plane", &capsule, &plane, true, true},
        {"box-box", &box, &box, false, false},  // btBoxBoxDetector is dBoxBox: not exact (5 % face preference)
        {"hull-plane", &hull, &plane, false, false},       {"sphere-hull", &sphere, &hull, false, false},
        {"hull-box", &hull, &box, false, false},           {"hull-hull", &hull, &hull, false, false},
        {"sharp hull-box", &sharp_hull, &box, false, false}, {"sharp hull-hull", &sharp_hull, &sharp_hull, false, false},
        {"sharp hull-plane", &sharp_hull, &plane, false, false},
        {"polyhedral hull-hull", &poly_hull, &poly_hull, false, false}, {"polyhedral hull-box", &poly_hull, &box, false, false},
    };
    mk_rng rng = {777};
    int compared = 0;
    for (const Case &c : cases) {
        int minko_used = 0;
        for (int k = 0; k < 200; k++) {
            btTransform xa = random_pose(&rng, 0.6), xb = random_pose(&rng, 0.6);
            if (c.a == &plane) xa.setIdentity();
            if (c.b == &plane) xb.setIdentity();
            bool used_minko = false;
            std::vector<PointOut> got = collide_once(&mine, c.a, xa, c.b, xb, &used_minko);
            if (!used_minko) continue;  // left to Bullet in this build (e.g. box-box before SAT)
            minko_used++;
            PointOut ref = {btVector3(0, 0, 0), btVector3(0, 0, 0), btVector3(0, 0, 0), 0, -1, -1};
            bool have_ref;
            double tol;
            if (c.bullet_same_solid) {
                std::vector<PointOut> r = collide_once(&native, c.a, xa, c.b, xb);
                have_ref = !r.empty();
                if (have_ref) ref = *deepest(r);
                tol = kContactTol;
            } else {
                const bool cores = c.a == &poly_hull && c.b == &poly_hull;
                have_ref = oracle_reference(cores ? &sharp_hull : c.a, xa, cores ? &sharp_hull : c.b, xb, &ref);
                tol = kContactTol;
            }
            const PointOut *g = deepest(got);
            if (!have_ref || ref.distance > -1e-3) continue;  // compare clear penetrations only
            ck_assert_msg(g != nullptr, "%s pose %d: Bullet finds depth %g, Minko no contact", c.name, k, ref.distance);
            ck_assert_msg(std::fabs(ref.distance - g->distance) <= tol, "%s pose %d: distance Bullet %.12g Minko %.12g",
                          c.name, k, ref.distance, g->distance);
            ck_assert_msg(ref.normal_on_b.dot(g->normal_on_b) >= 1 - 1e-6, "%s pose %d: normals differ: Bullet %g %g %g Minko %g %g %g (d %g %g)", c.name, k, (double)ref.normal_on_b.x(), (double)ref.normal_on_b.y(), (double)ref.normal_on_b.z(), (double)g->normal_on_b.x(), (double)g->normal_on_b.y(), (double)g->normal_on_b.z(), ref.distance, g->distance);
            for (const PointOut &p : got) {
                btVector3 gap = p.on_a - (p.on_b + p.normal_on_b * (btScalar)p.distance);
                ck_assert_msg(gap.length() <= 1e-5, "%s pose %d: on_a != on_b + n d", c.name, k);
                ck_assert_msg(p.normal_on_b.dot(g->normal_on_b) >= 1 - kNormalTol, "%s: one normal per manifold", c.name);
            }
            compared++;
        }
        if (c.closed_form) ck_assert_msg(minko_used == 200, "%s: left to Bullet", c.name);
    }
    ck_assert_int_gt(compared, 500);
}
END_TEST

// Signed distance of two convex shapes: the exact oracle, or Bullet's GJK
// (which sees the same solids, margins included) for the shapes the oracle
// does not model (cylinders, cones); good to 1e-6 on separated pairs.
bool gap_of(const btCollisionShape *a, const btTransform &xa, const btCollisionShape *b, const btTransform &xb,
            double *d)
{
    PointOut ref;
    if (oracle_reference(a, xa, b, xb, &ref)) {
        *d = ref.distance;
        return true;
    }
    btGjkEpaSolver2::sResults r;
    btGjkEpaSolver2::SignedDistance(static_cast<const btConvexShape *>(a), xa, static_cast<const btConvexShape *>(b), xb,
                                    xb.getOrigin() - xa.getOrigin(), r);
    *d = r.distance;
    return r.status == btGjkEpaSolver2::sResults::Separated || r.status == btGjkEpaSolver2::sResults::Penetrating;
}

// A pair just inside the contact threshold is never skipped: the
// algorithm's bounding test (centre against the other solid, less its
// bounding radius) is exact for spheres and a sphere against a box, and
// conservative for the rest, so at a gap of 0.9 times the manifold's contact
// breaking threshold (placed by bisection on the exact distance, along
// random directions) the algorithm reports as many points as mk_collide
// itself, the deepest no farther apart than the gap; box-box pairs, which
// report touching points only, none.
START_TEST(np_near_pairs_never_skipped)
{
    mkb::CollisionConfiguration mine;
    btBoxShape box(btVector3(btScalar(0.5), btScalar(0.7), btScalar(0.4)));
    btSphereShape sphere(btScalar(0.5));
    btCapsuleShape capsule(btScalar(0.3), btScalar(0.8));
    btCylinderShapeX cylinder(btVector3(btScalar(0.6), btScalar(0.5), btScalar(0.5)));
    btConeShapeZ cone(btScalar(0.4), btScalar(1.0));
    btConvexHullShape hull;
    mk_rng cloud = {99};
    for (int i = 0; i < 16; i++) {
        mk_vec3 p = mk_rng_dir(&cloud);
        hull.addPoint(btVector3((btScalar)(0.6 * p.x), (btScalar)(0.5 * p.y), (btScalar)(0.4 * p.z)), false);
    }
    hull.recalcLocalAabb();
    hull.setMargin(0);  // sharp: a Minko pair in every build with SAT
    btCollisionShape *shapes[] = {&box, &sphere, &capsule, &cylinder, &cone, &hull};
    mk_rng rng = {2024};
    int checked = 0, reported = 0;
    for (btCollisionShape *a : shapes) {
        for (btCollisionShape *b : shapes) {
            // What btCollisionDispatcher::getNewManifold gives the pair.
            const double gap = 0.9 * std::min(a->getContactBreakingThreshold(gContactBreakingThreshold),
                                              b->getContactBreakingThreshold(gContactBreakingThreshold));
            for (int k = 0; k < 4; k++) {
                btTransform xa = random_pose(&rng, 0), xb = random_pose(&rng, 0);
                const mk_vec3 u = mk_rng_dir(&rng);
                const btVector3 dir((btScalar)u.x, (btScalar)u.y, (btScalar)u.z);
                // Bisection on the centre offset s: overlapping at 0, apart at 4.
                double lo = 0, hi = 4;
                PointOut ref;
                for (int it = 0; it < 60; it++) {
                    const double mid = 0.5 * (lo + hi);
                    xb.setOrigin(dir * (btScalar)mid);
                    if (!gap_of(a, xa, b, xb, &ref.distance)) break;
                    (ref.distance < gap ? lo : hi) = mid;
                }
                xb.setOrigin(dir * (btScalar)lo);
                if (!gap_of(a, xa, b, xb, &ref.distance) || ref.distance < 0.5 * gap) continue;
                bool used_minko = false;
                std::vector<PointOut> got = collide_once(&mine, a, xa, b, xb, &used_minko);
                if (!used_minko) continue;
                mkb::ShapeMap ma, mb;
                mk_manifold direct;
                ck_assert_int_eq(mine.map_shape(a, &ma), MK_OK);
                ck_assert_int_eq(mine.map_shape(b, &mb), MK_OK);
                ck_assert_int_eq(mk_collide(&ma.shape, mkb::minko_pose(xa, ma), &mb.shape, mkb::minko_pose(xb, mb),
                                            (mk_real)(gap / 0.9), nullptr, &direct),
                                 MK_OK);
                // Box-box pairs keep touching points only (as btBoxBoxDetector): none at this gap.
                int expected = direct.count;
                if (a->getShapeType() == BOX_SHAPE_PROXYTYPE && b->getShapeType() == BOX_SHAPE_PROXYTYPE)
                    for (int j = 0; j < direct.count; j++) expected -= direct.points[j].depth < 0;
                ck_assert_msg((int)got.size() == expected, "shapes %d-%d case %d: gap %g, %d points, expected %d (mk_collide %d)",
                              a->getShapeType(), b->getShapeType(), k, ref.distance, (int)got.size(), expected, direct.count);
                if (expected > 0) {
                    ck_assert(deepest(got)->distance <= ref.distance + 1e-4);
                    reported++;
                }
                checked++;
            }
        }
    }
    ck_assert_int_gt(checked, 100);
    ck_assert_int_gt(reported, 50);
}
END_TEST

// A world on the Minko narrowphase: boxes, spheres and capsules settle on a
// static plane; a box resting flat carries its weight on four points whose
// features stay the same from step to step (lifetimes grow, warm starting
// holds), and a sphere on a triangle mesh (left to Bullet) does not fall
// through.
START_TEST(np_world_rests_on_minko_contacts)
{
    mkb::CollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config);
    btDbvtBroadphase bp;
    btSequentialImpulseConstraintSolver solver;
    btDiscreteDynamicsWorld world(&dispatcher, &bp, &solver, &config);
    world.setGravity(btVector3(0, -10, 0));
    btStaticPlaneShape ground(btVector3(0, 1, 0), 0);
    btBoxShape box(btVector3(btScalar(0.5), btScalar(0.25), btScalar(0.5)));
    btSphereShape ball(btScalar(0.3));
    btCapsuleShapeX cap(btScalar(0.2), btScalar(0.6));
    // A two-triangle mesh floor, off to the side.
    btTriangleMesh tris;
    tris.addTriangle(btVector3(10, 0, -2), btVector3(14, 0, -2), btVector3(10, 0, 2));
    tris.addTriangle(btVector3(14, 0, -2), btVector3(14, 0, 2), btVector3(10, 0, 2));
    btBvhTriangleMeshShape mesh(&tris, true);
    std::vector<btRigidBody *> bodies;
    auto add = [&](btCollisionShape *s, btScalar mass, const btVector3 &at) {
        btVector3 inertia(0, 0, 0);
        if (mass > 0) s->calculateLocalInertia(mass, inertia);
        btRigidBody *b = new btRigidBody(mass, nullptr, s, inertia);
        b->setWorldTransform(btTransform(btQuaternion::getIdentity(), at));
        b->setActivationState(DISABLE_DEACTIVATION);
        world.addRigidBody(b);
        bodies.push_back(b);
        return b;
    };
    add(&ground, 0, btVector3(0, 0, 0));
    add(&mesh, 0, btVector3(0, btScalar(0.5), 0));
    btRigidBody *flat = add(&box, 2, btVector3(0, btScalar(0.3), 0));
    add(&ball, 1, btVector3(3, 2, 0));
    add(&cap, 1, btVector3(-3, 1, 1));
    btRigidBody *on_mesh = add(&ball, 1, btVector3(12, 2, 0));
    for (int step = 0; step < 240; step++) world.stepSimulation(btScalar(1) / 60, 0);
    ck_assert_int_gt(config.stats.minko_algorithms.load(), 2);
    ck_assert_int_eq(config.stats.collide_errors.load(), 0);
    MK_ASSERT_NEAR(flat->getWorldTransform().getOrigin().y(), 0.25, 5e-3);
    MK_ASSERT_NEAR(bodies[3]->getWorldTransform().getOrigin().y(), 0.3, 5e-3);
    MK_ASSERT_NEAR(bodies[4]->getWorldTransform().getOrigin().y(), 0.2, 5e-3);
    MK_ASSERT_NEAR(on_mesh->getWorldTransform().getOrigin().y(), 0.8, 2e-2);
    // The flat box: find its manifold, check four points, their keys and the load they carry.
    btPersistentManifold *m = nullptr;
    for (int i = 0; i < dispatcher.getNumManifolds(); i++) {
        btPersistentManifold *c = dispatcher.getManifoldByIndexInternal(i);
        if (c->getBody0() == flat || c->getBody1() == flat) m = c;
    }
    ck_assert_ptr_nonnull(m);
    ck_assert_int_eq(m->getNumContacts(), 4);
    std::vector<std::pair<int, int> > keys;
    double impulse = 0;
    for (int i = 0; i < 4; i++) {
        keys.push_back(std::make_pair(m->getContactPoint(i).m_partId0, m->getContactPoint(i).m_partId1));
        impulse += m->getContactPoint(i).m_appliedImpulse;
        ck_assert_int_gt(m->getContactPoint(i).getLifeTime(), 100);
    }
    MK_ASSERT_NEAR(impulse, 2 * 10.0 / 60, 0.05 * 2 * 10.0 / 60);
    world.stepSimulation(btScalar(1) / 60, 0);
    for (int i = 0; i < 4; i++) {
        std::pair<int, int> k(m->getContactPoint(i).m_partId0, m->getContactPoint(i).m_partId1);
        ck_assert(std::find(keys.begin(), keys.end(), k) != keys.end());
    }
    for (btRigidBody *b : bodies) {
        world.removeRigidBody(b);
        delete b;
    }
}
END_TEST

// A shape resized while its pair lives is seen at once, as Bullet's own
// algorithms read the shape every step: a ball resting on a box ground rides
// up when the ground box is made twice as tall.
START_TEST(np_shape_changes_seen)
{
    mkb::CollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config);
    btDbvtBroadphase bp;
    btSequentialImpulseConstraintSolver solver;
    btDiscreteDynamicsWorld world(&dispatcher, &bp, &solver, &config);
    world.setGravity(btVector3(0, -10, 0));
    btBoxShape slab(btVector3(5, btScalar(0.5), 5));
    btSphereShape ball(btScalar(0.25));
    btRigidBody ground(0, nullptr, &slab);
    btVector3 inertia;
    ball.calculateLocalInertia(1, inertia);
    btRigidBody b(1, nullptr, &ball, inertia);
    b.setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(0, 1, 0)));
    b.setActivationState(DISABLE_DEACTIVATION);
    world.addRigidBody(&ground);
    world.addRigidBody(&b);
    for (int i = 0; i < 90; i++) world.stepSimulation(btScalar(1) / 60, 0);
    MK_ASSERT_NEAR(b.getWorldTransform().getOrigin().y(), 0.75, 5e-3);
    slab.setLocalScaling(btVector3(1, 2, 1));  // top face now at y = 1
    world.updateSingleAabb(&ground);
    for (int i = 0; i < 90; i++) world.stepSimulation(btScalar(1) / 60, 0);
    MK_ASSERT_NEAR(b.getWorldTransform().getOrigin().y(), 1.25, 5e-3);
    ck_assert_int_eq(config.stats.minko_algorithms.load(), 1);  // the same pair algorithm all along
    world.removeRigidBody(&b);
    world.removeRigidBody(&ground);
}
END_TEST

// The deepest point of the manifold between objects a and b (+inf if none).
btScalar pair_distance(btDispatcher *d, const btCollisionObject *a, const btCollisionObject *b)
{
    btScalar best = std::numeric_limits<btScalar>::infinity();
    for (int i = 0; i < d->getNumManifolds(); i++) {
        const btPersistentManifold *m = d->getManifoldByIndexInternal(i);
        if (!((m->getBody0() == a && m->getBody1() == b) || (m->getBody0() == b && m->getBody1() == a))) continue;
        for (int j = 0; j < m->getNumContacts(); j++) best = std::min(best, m->getContactPoint(j).getDistance());
    }
    return best;
}

// Each pair sees its objects' current world poses (the configuration keeps
// one pose per object): an object moved by the user between two collision
// passes, a compound's child (its own transform, not the object's), and two
// worlds sharing one configuration (the same world array indices for
// different objects). Box-on-slab depths are exact: d = 0.5 + 0.5 - y.
START_TEST(np_world_poses_follow_the_objects)
{
    mkb::CollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config), dispatcher2(&config);
    btDbvtBroadphase bp, bp2;
    btCollisionWorld world(&dispatcher, &bp, &config), world2(&dispatcher2, &bp2, &config);
    btBoxShape slab(btVector3(20, btScalar(0.5), 20)), cube(btVector3(btScalar(0.5), btScalar(0.5), btScalar(0.5)));
    btCompoundShape compound;
    compound.addChildShape(btTransform(btQuaternion::getIdentity(), btVector3(0, btScalar(-0.5), 0)), &cube);
    btCollisionObject ground, box, comp, ground2, box2;
    ground.setCollisionShape(&slab);
    box.setCollisionShape(&cube);
    comp.setCollisionShape(&compound);
    ground2.setCollisionShape(&slab);
    box2.setCollisionShape(&cube);
    const btQuaternion id = btQuaternion::getIdentity();
    box.setWorldTransform(btTransform(id, btVector3(0, btScalar(0.98), 0)));        // d = 0.02
    comp.setWorldTransform(btTransform(id, btVector3(5, btScalar(1.47), 0)));       // child at 0.97: d = 0.03
    box2.setWorldTransform(btTransform(id, btVector3(-3, btScalar(0.95), 2)));      // d = 0.05
    ground2.setWorldTransform(btTransform(id, btVector3(0, 0, 0)));
    world.addCollisionObject(&ground);
    world.addCollisionObject(&box);
    world.addCollisionObject(&comp);
    world2.addCollisionObject(&box2);  // index 0 in world2, the ground's index in world
    world2.addCollisionObject(&ground2);
    // A row of resting cubes: many entries, first seen in index order.
    std::vector<btCollisionObject> row(40);
    for (size_t k = 0; k < row.size(); k++) {
        row[k].setCollisionShape(&cube);
        row[k].setWorldTransform(btTransform(id, btVector3(btScalar(-15 + 0.75 * (double)k), btScalar(0.99), -5)));  // d = 0.01
        world.addCollisionObject(&row[k]);
    }
    const double tol = 1e3 * std::numeric_limits<btScalar>::epsilon();
    // Passes 0-2: the first world alone; pass 3: the second world, whose
    // objects take the first world's entries; pass 4: the first world again;
    // pass 5: the box turned in place by 0.1 rad about z (same origin), its
    // lowest edge 0.5 (cos 0.1 + sin 0.1) below its centre.
    const btScalar turn = btScalar(0.1);
    const double turned = 0.5 * (std::cos(0.1) + std::sin(0.1)) + 0.5 - 0.98;
    for (int pass = 0; pass < 6; pass++) {
        if (pass == 3) {
            world2.performDiscreteCollisionDetection();
            MK_ASSERT_NEAR(pair_distance(&dispatcher2, &ground2, &box2), -0.05, tol);
            continue;
        }
        world.performDiscreteCollisionDetection();
        const double d = pass == 1 ? 0.12 : pass == 5 ? turned : 0.02;  // pass 1: the box moved 0.1 down since pass 0
        MK_ASSERT_NEAR(pair_distance(&dispatcher, &ground, &box), -d, tol);
        MK_ASSERT_NEAR(pair_distance(&dispatcher, &ground, &comp), -0.03, tol);
        for (const btCollisionObject &o : row) MK_ASSERT_NEAR(pair_distance(&dispatcher, &ground, &o), -0.01, tol);
        const btQuaternion q = pass == 4 ? btQuaternion(btVector3(0, 0, 1), turn) : id;
        box.setWorldTransform(btTransform(q, btVector3(0, btScalar(pass == 0 ? 0.88 : 0.98), 0)));
    }
    ck_assert_int_eq(config.stats.collide_errors.load(), 0);
    for (btCollisionObject &o : row) world.removeCollisionObject(&o);
    world.removeCollisionObject(&comp);
    world.removeCollisionObject(&box);
    world.removeCollisionObject(&ground);
    world2.removeCollisionObject(&ground2);
    world2.removeCollisionObject(&box2);
}
END_TEST

std::vector<btManifoldPoint> g_written;  // points written this frame (gContactAddedCallback)
bool record_written(btManifoldPoint &p, const btCollisionObjectWrapper *, int, int, const btCollisionObjectWrapper *, int, int)
{
    g_written.push_back(p);
    return false;
}

// Bullet's pairs run mk_collide in the minimum-penetration-face mode: a
// pair algorithm kept warm over frames reports, every frame, the normal and
// depth a cold call gives (no face kind held from the last frame). Two
// equal boxes stacked and rocking, the upper one's tilt changing sign, is
// the case where the ID-stable mode would keep last frame's face.
START_TEST(np_warm_pairs_take_the_best_face)
{
    mkb::CollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config);
    btBoxShape box(btVector3(1, 1, 1));
    btCollisionObject lower, upper;
    lower.setCollisionShape(&box);
    upper.setCollisionShape(&box);
    upper.setCollisionFlags(upper.getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
    ContactAddedCallback saved = gContactAddedCallback;
    gContactAddedCallback = record_written;
    btTransform xl(btQuaternion(btVector3(0, 0, 1), btScalar(0.01)), btVector3(0, 0, 0));
    lower.setWorldTransform(xl);
    btCollisionObjectWrapper wl(nullptr, &box, &lower, xl, -1, -1);
    btCollisionAlgorithm *algo = nullptr;
    int compared = 0;
    for (int k = 0; k < 40; k++) {
        // The upper box's tilt swings between -0.03 and +0.03 rad: its own
        // bottom face and the lower box's top face take turns being the
        // shallower axis.
        const btScalar tilt = btScalar(0.03 * std::sin(0.7 * k));
        btTransform xu(btQuaternion(btVector3(0, 0, 1), tilt), btVector3(btScalar(0.05), btScalar(1.99), 0));
        upper.setWorldTransform(xu);
        btCollisionObjectWrapper wu(nullptr, &box, &upper, xu, -1, -1);
        if (!algo) algo = dispatcher.findAlgorithm(&wl, &wu, nullptr, BT_CONTACT_POINT_ALGORITHMS);
        btManifoldResult result(&wl, &wu);
        btDispatcherInfo info;
        g_written.clear();
        algo->processCollision(&wl, &wu, info, &result);
        btManifoldArray manifolds;
        algo->getAllContactManifolds(manifolds);
        ck_assert_int_eq(manifolds.size(), 1);
        const btPersistentManifold *m = manifolds[0];
        const btManifoldPoint *warm = nullptr;
        for (const btManifoldPoint &p : g_written)
            if (!warm || p.getDistance() < warm->getDistance()) warm = &p;
        std::vector<PointOut> cold = collide_once(&config, &box, xl, &box, xu);
        const PointOut *c = deepest(cold);
        ck_assert(c != nullptr && warm != nullptr);
        const btVector3 n = m->getBody0() == &lower ? warm->m_normalWorldOnB : -warm->m_normalWorldOnB;
        ck_assert_msg(n.dot(c->normal_on_b) >= 1 - kNormalTol, "frame %d: warm normal %g %g %g, cold %g %g %g", k,
                      (double)n.x(), (double)n.y(), (double)n.z(), (double)c->normal_on_b.x(),
                      (double)c->normal_on_b.y(), (double)c->normal_on_b.z());
        MK_ASSERT_NEAR(warm->getDistance(), c->distance, kContactTol);
        compared++;
    }
    ck_assert_int_eq(compared, 40);
    gContactAddedCallback = saved;
    algo->~btCollisionAlgorithm();
    dispatcher.freeCollisionAlgorithm(algo);
}
END_TEST

// Bullet's solver visits a manifold's points in slot order (Gauss-Seidel),
// so the order a new box-box manifold gets its points in changes the solve
// (contact_writer.cpp, bullet_box_order: the 1000 stack's pyramid spreads
// sideways more in Minko's own clip order). The adapter hands a new box
// manifold its points in the order Bullet's btBoxBoxDetector reports them:
// on stacked boxes, tilted, turned and offset (faces inside, clipped to a
// quadrant or a strip, octagons culled to four), whenever both report the
// same points, slot i holds the same point.
START_TEST(np_box_points_in_bullets_order)
{
    btDefaultCollisionConfiguration native;
    mkb::CollisionConfiguration mine;
    btBoxShape cube(btVector3(1, 1, 1)), slab(btVector3(5, btScalar(0.5), 5)),
        brick(btVector3(btScalar(0.8), btScalar(0.5), btScalar(0.3)));
    btBoxShape *lowers[3] = {&cube, &slab, &cube}, *uppers[3] = {&cube, &cube, &brick};
    mk_rng rng = {2026};
    const double tol = sizeof(btScalar) == sizeof(double) ? 1e-6 : 2e-3;  // the two clips' round-off
    int compared = 0, turned = 0;
    for (int k = 0; k < 600; k++) {
        btBoxShape *lo = lowers[k % 3], *up = uppers[k % 3];
        // Up to ~0.02 rad of tilt on each, the upper one turned by up to
        // 0.4 rad (every third case aligned) and offset up to a side.
        const btScalar yaw = k % 3 == 0 ? 0 : (btScalar)mk_rng_range(&rng, -0.4, 0.4);
        btQuaternion tl(btVector3((btScalar)mk_rng_range(&rng, -1, 1), 0, (btScalar)mk_rng_range(&rng, -1, 1)).normalized(),
                        (btScalar)mk_rng_range(&rng, 0, 0.02));
        btQuaternion tu(btVector3((btScalar)mk_rng_range(&rng, -1, 1), 0, (btScalar)mk_rng_range(&rng, -1, 1)).normalized(),
                        (btScalar)mk_rng_range(&rng, 0, 0.02));
        const btScalar hl = lo->getHalfExtentsWithMargin().y(), hu = up->getHalfExtentsWithMargin().y();
        btTransform xl(tl, btVector3(0, 0, 0));
        btTransform xu(btQuaternion(btVector3(0, 1, 0), yaw) * tu,
                       btVector3((btScalar)mk_rng_range(&rng, -1.5, 1.5), hl + hu - btScalar(0.03),
                                 (btScalar)mk_rng_range(&rng, -1.5, 1.5)));
        // Either order of the pair: the reference face may be on A or on B.
        const bool flip = k % 2 == 1;
        btBoxShape *a = flip ? up : lo, *b = flip ? lo : up;
        const btTransform &xa = flip ? xu : xl, &xb = flip ? xl : xu;
        std::vector<PointOut> pn = collide_once(&native, a, xa, b, xb), pm = collide_once(&mine, a, xa, b, xb);
        if (pn.size() != pm.size() || pn.size() < 2) continue;
        bool same_points = true;
        for (const PointOut &m : pm) {
            bool found = false;
            for (const PointOut &q : pn) found = found || (m.on_b - q.on_b).length() < tol;
            same_points = same_points && found;
        }
        if (!same_points) continue;
        compared++;
        turned += yaw > btScalar(0.2) || yaw < btScalar(-0.2);
        for (size_t i = 0; i < pm.size(); i++)
            ck_assert_msg((pm[i].on_b - pn[i].on_b).length() < tol,
                          "case %d slot %d of %d: Minko (%g %g %g), Bullet (%g %g %g)", k, (int)i, (int)pm.size(),
                          (double)pm[i].on_b.x(), (double)pm[i].on_b.y(), (double)pm[i].on_b.z(), (double)pn[i].on_b.x(),
                          (double)pn[i].on_b.y(), (double)pn[i].on_b.z());
    }
    ck_assert_int_ge(compared, 300);
    ck_assert_int_ge(turned, 50);
}
END_TEST

// An octagonal prism of circumradius 1 and height 0.5 (axis y), with
// Bullet's polyhedral features, so Bullet's own algorithms clip it.
static void octagonal_prism(btConvexHullShape &prism)
{
    for (int i = 0; i < 8; i++) {
        const double t = SIMD_PI / 4 * i;
        for (int up = 0; up < 2; up++)
            prism.addPoint(btVector3((btScalar)std::cos(t), up ? btScalar(0.25) : btScalar(-0.25), (btScalar)std::sin(t)), false);
    }
    prism.recalcLocalAabb();
    prism.initializePolyhedralFeatures();
}

// Two polyhedral hulls feed Bullet's manifold as Bullet's own hull-hull
// algorithm does: every clipped candidate through addContactPoint (each
// with its feature keys), the deepest last, and the manifold keeps four of
// them by its own rule, the deepest among them; on a warm frame at the same
// poses the points that stay keep their impulses. An octagonal
// prism on one turned by 22.5 degrees about the vertical overlaps in a
// 16-gon: 16 candidates; the upper prism is tilted a little so one corner
// is the deepest.
START_TEST(np_hull_candidates_like_bullet)
{
    mkb::CollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config);
    btConvexHullShape prism;
    octagonal_prism(prism);
    btCollisionObject lower, upper;
    lower.setCollisionShape(&prism);
    upper.setCollisionShape(&prism);
    upper.setCollisionFlags(upper.getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
    ContactAddedCallback saved = gContactAddedCallback;
    gContactAddedCallback = record_written;
    const btTransform xl = btTransform::getIdentity();
    // Cores 0.01 deep at the centre, tilted by 0.002 rad about x.
    const btTransform xu(btQuaternion(btVector3(0, 1, 0), btScalar(SIMD_PI / 8)) * btQuaternion(btVector3(1, 0, 0), btScalar(0.002)),
                         btVector3(0, btScalar(0.49), 0));
    lower.setWorldTransform(xl);
    upper.setWorldTransform(xu);
    btCollisionObjectWrapper wl(nullptr, &prism, &lower, xl, -1, -1), wu(nullptr, &prism, &upper, xu, -1, -1);
    const long before = config.stats.minko_algorithms.load();
    btCollisionAlgorithm *algo = dispatcher.findAlgorithm(&wl, &wu, nullptr, BT_CONTACT_POINT_ALGORITHMS);
    ck_assert_int_eq(config.stats.minko_algorithms.load(), before + 1);
    btManifoldArray manifolds;
    btScalar impulse[4];
    btVector3 where[4];
    for (int frame = 0; frame < 2; frame++) {
        btManifoldResult result(&wl, &wu);
        btDispatcherInfo info;
        g_written.clear();
        algo->processCollision(&wl, &wu, info, &result);
        manifolds.clear();
        algo->getAllContactManifolds(manifolds);
        ck_assert_int_eq(manifolds.size(), 1);
        btPersistentManifold *m = manifolds[0];
        ck_assert_int_eq((int)g_written.size(), 16);
        ck_assert_int_eq(m->getNumContacts(), 4);
        // Fed deepest last; each with a distinct feature pair.
        for (size_t i = 0; i < g_written.size(); i++) {
            ck_assert(g_written[i].getDistance() >= g_written.back().getDistance());
            ck_assert(g_written[i].m_partId0 >= 0 && g_written[i].m_partId1 >= 0);
            for (size_t j = 0; j < i; j++)
                ck_assert(g_written[i].m_partId0 != g_written[j].m_partId0 || g_written[i].m_partId1 != g_written[j].m_partId1);
        }
        btScalar kept_deepest = BT_LARGE_FLOAT;
        for (int i = 0; i < 4; i++) kept_deepest = btMin(kept_deepest, m->getContactPoint(i).getDistance());
        MK_ASSERT_NEAR(kept_deepest, g_written.back().getDistance(), kContactTol);
        // Bullet's own algorithm on the same poses: the same deepest point.
        btDefaultCollisionConfiguration native;
        const PointOut *ref = nullptr;
        std::vector<PointOut> bullet = collide_once(&native, &prism, xl, &prism, xu);
        ref = deepest(bullet);
        ck_assert(ref != nullptr);
        MK_ASSERT_NEAR(ref->distance, kept_deepest, 1e-4);
        if (frame == 0) {
            for (int i = 0; i < 4; i++) {
                impulse[i] = btScalar(1 + i);
                where[i] = m->getContactPoint(i).m_localPointB;
                m->getContactPoint(i).m_appliedImpulse = impulse[i];
            }
        } else {
            // As in Bullet's own manifolds, the candidates that match no
            // cached point evict one each, so a point may leave and come back
            // cold (lifetime 1 after the refresh); one that stayed (lifetime
            // 2) was matched by position and carries its impulse.
            int stayed = 0;
            for (int i = 0; i < 4; i++) {
                const btManifoldPoint &p = m->getContactPoint(i);
                if (p.getLifeTime() != 2) continue;
                int k = 0;
                while (k < 4 && (p.m_localPointB - where[k]).length() > btScalar(1e-4)) k++;
                ck_assert_msg(k < 4, "point %d stayed but is not one of the cold frame's", i);
                ck_assert(p.m_appliedImpulse == impulse[k]);
                stayed++;
            }
            ck_assert_int_gt(stayed, 0);
        }
    }
    gContactAddedCallback = saved;
    algo->~btCollisionAlgorithm();
    dispatcher.freeCollisionAlgorithm(algo);
}
END_TEST

// A running world switches its narrowphase both ways; pairs get new
// algorithms and the simulation goes on undisturbed.
START_TEST(np_switch_at_run_time)
{
    mkb::CollisionConfiguration config(mkb::Backend::native);
    btCollisionDispatcher dispatcher(&config);
    btDbvtBroadphase bp;
    btSequentialImpulseConstraintSolver solver;
    btDiscreteDynamicsWorld world(&dispatcher, &bp, &solver, &config);
    world.setGravity(btVector3(0, -10, 0));
    btStaticPlaneShape ground(btVector3(0, 1, 0), 0);
    btSphereShape ball(btScalar(0.3));
    btRigidBody g(0, nullptr, &ground);
    btVector3 inertia;
    ball.calculateLocalInertia(1, inertia);
    btRigidBody b(1, nullptr, &ball, inertia);
    b.setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(0, 1, 0)));
    b.setActivationState(DISABLE_DEACTIVATION);
    world.addRigidBody(&g);
    world.addRigidBody(&b);
    for (int i = 0; i < 60; i++) world.stepSimulation(btScalar(1) / 60, 0);
    ck_assert_int_eq(config.stats.minko_algorithms.load(), 0);
    ck_assert(mkb::set_narrowphase(&world, mkb::Backend::minko));
    for (int i = 0; i < 60; i++) world.stepSimulation(btScalar(1) / 60, 0);
    ck_assert_int_eq(config.stats.minko_algorithms.load(), 1);
    MK_ASSERT_NEAR(b.getWorldTransform().getOrigin().y(), 0.3, 5e-3);
    ck_assert(mkb::set_narrowphase(&world, mkb::Backend::native));
    for (int i = 0; i < 60; i++) world.stepSimulation(btScalar(1) / 60, 0);
    ck_assert_int_eq(config.stats.minko_algorithms.load(), 1);
    MK_ASSERT_NEAR(b.getWorldTransform().getOrigin().y(), 0.3, 5e-3);
    // Not a Minko configuration: refused.
    btDefaultCollisionConfiguration plain;
    btCollisionDispatcher d2(&plain);
    btCollisionWorld w2(&d2, &bp, &plain);
    ck_assert(!mkb::set_narrowphase(&w2, mkb::Backend::minko));
    world.removeRigidBody(&b);
    world.removeRigidBody(&g);
}
END_TEST

// A polyhedral hull on a box meets it as in Bullet's own algorithm, which
// runs GJK alone on such a pair: one point per frame (Minko's deepest),
// through addContactPoint, so the manifold matches and keeps points by
// Bullet's own rule; on a second frame at the same poses that point is
// matched and keeps its impulse. Its depth is Bullet's own on the same poses.
START_TEST(np_hull_on_box_one_point_like_bullet)
{
    mkb::CollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config);
    btConvexHullShape prism;
    octagonal_prism(prism);
    btBoxShape ground(btVector3(3, btScalar(0.5), 3));
    btCollisionObject floor, hull;
    floor.setCollisionShape(&ground);
    hull.setCollisionShape(&prism);
    hull.setCollisionFlags(hull.getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
    ContactAddedCallback saved = gContactAddedCallback;
    gContactAddedCallback = record_written;
    const btTransform xf(btQuaternion::getIdentity(), btVector3(0, btScalar(-0.5), 0));
    // The rounded bottom (margin 0.04) 0.01 into the floor, tilted so that
    // one corner is the deepest.
    const btTransform xh(btQuaternion(btVector3(1, 0, 0), btScalar(0.01)), btVector3(0, btScalar(0.28), 0));
    floor.setWorldTransform(xf);
    hull.setWorldTransform(xh);
    btCollisionObjectWrapper wf(nullptr, &ground, &floor, xf, -1, -1), wh(nullptr, &prism, &hull, xh, -1, -1);
    const long before = config.stats.minko_algorithms.load();
    btCollisionAlgorithm *algo = dispatcher.findAlgorithm(&wf, &wh, nullptr, BT_CONTACT_POINT_ALGORITHMS);
    ck_assert_int_eq(config.stats.minko_algorithms.load(), before + 1);
    btDefaultCollisionConfiguration native;
    std::vector<PointOut> bullet = collide_once(&native, &ground, xf, &prism, xh);
    const PointOut *ref = deepest(bullet);
    ck_assert(ref != nullptr);
    for (int frame = 0; frame < 2; frame++) {
        btManifoldResult result(&wf, &wh);
        btDispatcherInfo info;
        g_written.clear();
        algo->processCollision(&wf, &wh, info, &result);
        btManifoldArray manifolds;
        algo->getAllContactManifolds(manifolds);
        ck_assert_int_eq(manifolds.size(), 1);
        btPersistentManifold *m = manifolds[0];
        ck_assert_int_eq((int)g_written.size(), 1);
        ck_assert_int_eq(m->getNumContacts(), 1);
        btManifoldPoint &p = m->getContactPoint(0);
        MK_ASSERT_NEAR(p.getDistance(), ref->distance, 1e-4);
        if (frame == 0) p.m_appliedImpulse = 5;
        else MK_ASSERT_NEAR(p.m_appliedImpulse, 5, 0);
    }
    gContactAddedCallback = saved;
    algo->~btCollisionAlgorithm();
    dispatcher.freeCollisionAlgorithm(algo);
}
END_TEST

// ---- the pose cache -------------------------------------------------------------

// The configuration's per-object pose cache serves, for every call, exactly
// the pose a fresh conversion of the object's current world transform gives:
// each of the transform's twelve numbers nudged by one ulp in place (the
// way Bullet's integration writes m_worldTransform, with no revision count),
// then the shape's axis rotation changed with the transform kept, is seen at
// the next call; an unchanged object is served its cached entry.
START_TEST(np_pose_cache_sees_one_ulp)
{
    mkb::CollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config);
    btDbvtBroadphase bp;
    btCollisionWorld world(&dispatcher, &bp, &config);
    btBoxShape cube(btVector3(btScalar(0.5), btScalar(0.5), btScalar(0.5)));
    btCapsuleShapeX rod(btScalar(0.2), btScalar(1));
    btCollisionObject a, b;
    a.setCollisionShape(&cube);
    b.setCollisionShape(&rod);
    mk_rng rng = {31};
    a.setWorldTransform(random_pose(&rng, 3));
    b.setWorldTransform(random_pose(&rng, 3));
    world.addCollisionObject(&a);
    world.addCollisionObject(&b);
    mkb::ShapeMap ma, mb;
    MK_ASSERT_STATUS(config.map_shape(&cube, &ma), MK_OK);
    MK_ASSERT_STATUS(config.map_shape(&rod, &mb), MK_OK);
    auto served_is_fresh = [&](const mkb::ShapeMap &amap, const mkb::ShapeMap &bmap, const mk_pose **pa_out) {
        btCollisionObjectWrapper wa(nullptr, &cube, &a, a.getWorldTransform(), -1, -1);
        btCollisionObjectWrapper wb(nullptr, &rod, &b, b.getWorldTransform(), -1, -1);
        mk_pose scratch[2], fa, fb;
        const mk_pose *pa = nullptr, *pb = nullptr;
        MK_ASSERT_STATUS(config.world_poses(&wa, amap, &wb, bmap, scratch, &pa, &pb), MK_OK);
        MK_ASSERT_STATUS(mkb::minko_pose(a.getWorldTransform(), amap, &fa), MK_OK);
        MK_ASSERT_STATUS(mkb::minko_pose(b.getWorldTransform(), bmap, &fb), MK_OK);
        ck_assert(pa != &scratch[0] && pb != &scratch[1]);  // from the cache
        ck_assert(std::memcmp(&pa->r, &fa.r, sizeof fa.r) == 0 && std::memcmp(&pa->p, &fa.p, sizeof fa.p) == 0);
        ck_assert(std::memcmp(&pb->r, &fb.r, sizeof fb.r) == 0 && std::memcmp(&pb->p, &fb.p, sizeof fb.p) == 0);
        if (pa_out) *pa_out = pa;
        return *pa;
    };
    const mk_pose *entry = nullptr;
    mk_pose before = served_is_fresh(ma, mb, &entry);
    const mk_pose *again = nullptr;
    served_is_fresh(ma, mb, &again);
    ck_assert(again == entry);  // the same entry, not a scratch pose
    int changed = 0;
    for (int k = 0; k < 12; k++) {
        btTransform &t = a.getWorldTransform();
        btScalar &x = k < 3 ? t.getOrigin()[k] : t.getBasis()[(k - 3) / 3][(k - 3) % 3];
        const btScalar was = x;
        x = std::nextafter(x, was + 1);
        ck_assert(x != was);
        const mk_pose now = served_is_fresh(ma, mb, nullptr);
        changed += std::memcmp(&now.r, &before.r, sizeof now.r) != 0 || std::memcmp(&now.p, &before.p, sizeof now.p) != 0;
        before = now;
        b.getWorldTransform().getOrigin()[k % 3] = std::nextafter(b.getWorldTransform().getOrigin()[k % 3], btScalar(-100));
        served_is_fresh(ma, mb, nullptr);
    }
    ck_assert_int_ge(changed, 3);  // at least the origin's ulps reach the pose
    // The same objects and transforms under another axis rotation (a map
    // whose axis differs): a new pose, then the first one again.
    mkb::ShapeMap turned = mb;
    turned.axis = mk_quat_identity();
    const mk_pose *pb0 = nullptr;
    {
        btCollisionObjectWrapper wa(nullptr, &cube, &a, a.getWorldTransform(), -1, -1);
        btCollisionObjectWrapper wb(nullptr, &rod, &b, b.getWorldTransform(), -1, -1);
        mk_pose scratch[2], fresh;
        const mk_pose *pa = nullptr;
        MK_ASSERT_STATUS(config.world_poses(&wa, ma, &wb, turned, scratch, &pa, &pb0), MK_OK);
        MK_ASSERT_STATUS(mkb::minko_pose(b.getWorldTransform(), turned, &fresh), MK_OK);
        ck_assert(std::memcmp(&pb0->r, &fresh.r, sizeof fresh.r) == 0);
    }
    served_is_fresh(ma, mb, nullptr);
    world.removeCollisionObject(&b);
    world.removeCollisionObject(&a);
}
END_TEST

// Pairs that part end with the manifold Bullet's own algorithms leave:
// every cached point dropped; pairs found farther apart than the contact
// breaking threshold without mk_collide (the bounding test, and for two
// boxes the face axis that held them apart) have none, and touching pairs
// are never skipped. Per shape pair, B beside A along x in two worlds
// (Minko's narrowphase, Bullet's), the pair kept by fat boxes: pass 0 AABBs
// overlapping by 0.05, pass 1 AABBs 1.5 thresholds apart (no point in
// either world), pass 2 0.5 threshold apart (the shapes still farther apart
// than the threshold: skipped for boxes and spheres), pass 3 touching again.
START_TEST(np_far_pairs_drop_points)
{
    btBoxShape box(btVector3(btScalar(0.5), btScalar(0.7), btScalar(0.4)));
    btSphereShape sphere(btScalar(0.5));
    btCapsuleShape capsule(btScalar(0.3), btScalar(0.8));
    btConvexHullShape hull;
    for (int i = 0; i < 8; i++)
        hull.addPoint(btVector3(i & 1 ? btScalar(0.6) : btScalar(-0.6), i & 2 ? btScalar(0.5) : btScalar(-0.5),
                                i & 4 ? btScalar(0.4) : btScalar(-0.4)), i == 7);
    btCollisionShape *shapes[] = {&box, &sphere, &capsule, &hull};
    int touching = 0, skipped_far = 0;
    for (btCollisionShape *sa : shapes) {
        for (btCollisionShape *sb : shapes) {
            mkb::CollisionConfiguration mine;
            btDefaultCollisionConfiguration native_config;
            btCollisionDispatcher d_mine(&mine), d_native(&native_config);
            mkb::Broadphase bp_mine(MK_BP_SAP, nullptr, 64, 1), bp_native(MK_BP_SAP, nullptr, 64, 1);
            btCollisionWorld w_mine(&d_mine, &bp_mine, &mine), w_native(&d_native, &bp_native, &native_config);
            btCollisionObject a[2], b[2];
            btCollisionWorld *worlds[2] = {&w_mine, &w_native};
            btScalar shift = 0, threshold = 0;
            bool touched = false;
            for (int k = 0; k < 2; k++) {
                a[k].setCollisionShape(sa);
                b[k].setCollisionShape(sb);
                a[k].setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(0, 0, 0)));
                b[k].setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(5, 0, 0)));
                worlds[k]->addCollisionObject(&a[k]);
                worlds[k]->addCollisionObject(&b[k]);
            }
            for (int pass = 0; pass < 4; pass++) {
                // B's x for this pass from the gap of its AABB to A's (Bullet's boxes).
                if (pass == 0) {
                    w_mine.updateAabbs();
                    const btScalar a_hi = a[0].getBroadphaseHandle()->m_aabbMax.x(), b_lo = b[0].getBroadphaseHandle()->m_aabbMin.x();
                    shift = b[0].getWorldTransform().getOrigin().x() - (b_lo - a_hi);  // x of B at AABB gap 0
                }
                const btScalar gap = pass == 1 ? btScalar(1.5) * threshold : pass == 2 ? btScalar(0.5) * threshold : btScalar(-0.05);
                for (int k = 0; k < 2; k++) b[k].getWorldTransform().setOrigin(btVector3(shift + gap, 0, 0));
                const long skips = mine.stats.skipped.load();
                int points[2];
                for (int k = 0; k < 2; k++) {
                    worlds[k]->performDiscreteCollisionDetection();
                    ck_assert_int_eq(worlds[k]->getPairCache()->getNumOverlappingPairs(), 1);  // the fat boxes still meet
                    btDispatcher *d = worlds[k]->getDispatcher();
                    points[k] = 0;
                    for (int m = 0; m < d->getNumManifolds(); m++) {
                        points[k] += d->getManifoldByIndexInternal(m)->getNumContacts();
                        if (k == 0 && pass == 0) threshold = d->getManifoldByIndexInternal(m)->getContactBreakingThreshold();
                    }
                }
                ck_assert_msg(threshold > 0, "shapes %d-%d: no manifold", sa->getShapeType(), sb->getShapeType());
                const bool skipped = mine.stats.skipped.load() > skips;
                if (pass == 0 || pass == 3) ck_assert_msg(!skipped, "shapes %d-%d pass %d: touching pair skipped", sa->getShapeType(),
                                                          sb->getShapeType(), pass);
                if (pass == 0) touched = points[0] > 0;
                if (pass == 3) ck_assert_int_eq(points[0] > 0, touched);
                if (pass == 1) {
                    ck_assert_int_eq(points[0], 0);
                    ck_assert_int_eq(points[1], 0);
                }
                if (pass == 2) {
                    if (skipped) ck_assert_int_eq(points[0], 0);
                    skipped_far += skipped;
                }
            }
            ck_assert_int_eq(mine.stats.collide_errors.load(), 0);
            touching += touched;
            for (int k = 0; k < 2; k++) {
                worlds[k]->removeCollisionObject(&b[k]);
                worlds[k]->removeCollisionObject(&a[k]);
            }
        }
    }
    ck_assert_int_ge(touching, 8);  // most pairs touch at pass 0: the drop is tested on real points
    ck_assert_int_ge(skipped_far, 4);  // pairs skipped at pass 2: box-box and the sphere pairs at least
}
END_TEST

// Two boxes apart by less than the contact breaking threshold report no
// point (box pairs report touching points only), and once mk_collide has
// found them so, the face axis that separates them answers the next frames
// alone for as long as it still separates them: those frames are skipped
// (no mk_collide), with no point, through small moves of B. Touching, the
// pair is not skipped and has points; parted beyond the threshold it drops
// them, and coming back within it, it is skipped again from its second
// frame there on.
START_TEST(np_separated_boxes_skipped)
{
    mkb::CollisionConfiguration mine;
    btBoxShape box(btVector3(btScalar(0.5), btScalar(0.7), btScalar(0.4)));
    btCollisionDispatcher dispatcher(&mine);
    btCollisionObject oa, ob;
    oa.setCollisionShape(&box);
    ob.setCollisionShape(&box);
    btCollisionObjectWrapper wa0(nullptr, &box, &oa, oa.getWorldTransform(), -1, -1), wb0(nullptr, &box, &ob, ob.getWorldTransform(), -1, -1);
    btCollisionAlgorithm *algo = dispatcher.findAlgorithm(&wa0, &wb0, nullptr, BT_CONTACT_POINT_ALGORITHMS);
    const btScalar t = box.getContactBreakingThreshold(gContactBreakingThreshold);
    // B beside A along x at gap g (a fraction of t; < 0 overlapping), tilted
    // about x (which keeps its extent along x), and whether it is skipped.
    const struct { double g, tilt; bool skipped; } frames[] = {
        {0.5, 0, false}, {0.4, 0.01, true}, {0.2, 0.02, true}, {-0.5, 0, false}, {1.5, 0, false},
        {1.2, 0, true},  {0.5, 0, false},   {0.3, 0.01, true}, {0.6, 0, true}};
    btDispatcherInfo info;
    for (size_t i = 0; i < sizeof frames / sizeof frames[0]; i++) {
        oa.setWorldTransform(btTransform::getIdentity());
        ob.setWorldTransform(btTransform(btQuaternion(btVector3(1, 0, 0), (btScalar)frames[i].tilt),
                                         btVector3(btScalar(1) + (btScalar)frames[i].g * t, 0, 0)));
        btCollisionObjectWrapper wa(nullptr, &box, &oa, oa.getWorldTransform(), -1, -1), wb(nullptr, &box, &ob, ob.getWorldTransform(), -1, -1);
        btManifoldResult result(&wa, &wb);
        const long skips = mine.stats.skipped.load();
        algo->processCollision(&wa, &wb, info, &result);
        btManifoldArray manifolds;
        algo->getAllContactManifolds(manifolds);
        int points = 0;
        for (int m = 0; m < manifolds.size(); m++) points += manifolds[m]->getNumContacts();
        ck_assert_msg((mine.stats.skipped.load() > skips) == frames[i].skipped, "frame %d: skipped %d", (int)i, !frames[i].skipped);
        if (frames[i].g > 0) ck_assert_msg(points == 0, "frame %d: %d points while apart", (int)i, points);
        else ck_assert_msg(points > 0, "frame %d: no point while touching", (int)i);
    }
    ck_assert_int_eq(mine.stats.collide_errors.load(), 0);
    algo->~btCollisionAlgorithm();
    dispatcher.freeCollisionAlgorithm(algo);
}
END_TEST

// processCollision of one pair algorithm at each of the poses in turn (a
// at xa[i], b at xb[i]); the manifold's point count after the last one.
int collide_in_turn(mkb::CollisionConfiguration *config, btCollisionShape *a, btCollisionShape *b, const btTransform *xa,
                    const btTransform *xb, int n)
{
    btCollisionDispatcher dispatcher(config);
    btCollisionObject oa, ob;
    oa.setCollisionShape(a);
    ob.setCollisionShape(b);
    oa.setWorldTransform(xa[0]);
    ob.setWorldTransform(xb[0]);
    btCollisionObjectWrapper wa0(nullptr, a, &oa, oa.getWorldTransform(), -1, -1), wb0(nullptr, b, &ob, ob.getWorldTransform(), -1, -1);
    btCollisionAlgorithm *algo = dispatcher.findAlgorithm(&wa0, &wb0, nullptr, BT_CONTACT_POINT_ALGORITHMS);
    btDispatcherInfo info;
    int points = 0;
    for (int i = 0; i < n; i++) {
        oa.setWorldTransform(xa[i]);
        ob.setWorldTransform(xb[i]);
        btCollisionObjectWrapper wa(nullptr, a, &oa, oa.getWorldTransform(), -1, -1), wb(nullptr, b, &ob, ob.getWorldTransform(), -1, -1);
        btManifoldResult result(&wa, &wb);
        algo->processCollision(&wa, &wb, info, &result);
        btManifoldArray manifolds;
        algo->getAllContactManifolds(manifolds);
        points = 0;
        for (int m = 0; m < manifolds.size(); m++) points += manifolds[m]->getNumContacts();
    }
    algo->~btCollisionAlgorithm();
    dispatcher.freeCollisionAlgorithm(algo);
    return points;
}

// Two boxes, random sizes and turns, placed around contact after a step
// farther apart along the same direction (so that a face axis kept them
// apart): a pair step answered without mk_collide is one mk_collide (cold,
// at the breaking threshold) finds no point for, and a pair mk_collide
// finds touching gets its touching points. Boxes side by side along a face
// normal, or turned, both near the threshold.
START_TEST(np_box_pairs_skipped_only_when_apart)
{
    mkb::CollisionConfiguration mine;
    mk_rng rng = {4242};
    int skipped = 0, checked = 0, touching = 0;
    for (int k = 0; k < 400; k++) {
        const double s = k % 2 ? 1.0 : 0.05;  // unit boxes and 5 cm ones
        btBoxShape a(btVector3((btScalar)(s * mk_rng_range(&rng, 0.2, 1)), (btScalar)(s * mk_rng_range(&rng, 0.2, 1)),
                               (btScalar)(s * mk_rng_range(&rng, 0.2, 1))));
        btBoxShape b(btVector3((btScalar)(s * mk_rng_range(&rng, 0.2, 1)), (btScalar)(s * mk_rng_range(&rng, 0.2, 1)),
                               (btScalar)(s * mk_rng_range(&rng, 0.2, 1))));
        const bool aligned = k % 4 < 2;
        btTransform xa = random_pose(&rng, 3 * s), xb = random_pose(&rng, 0);
        if (aligned) xb.setRotation(xa.getRotation());  // side by side along a face normal of A
        const int axis = (int)(mk_rng_range(&rng, 0, 3)) % 3;
        const double threshold = std::min(a.getContactBreakingThreshold(gContactBreakingThreshold),
                                          b.getContactBreakingThreshold(gContactBreakingThreshold));
        // Offset along A's face axis: touching when the extents along it add
        // up; around contact within a few thresholds.
        const btVector3 dir = xa.getBasis().getColumn(axis);
        const btVector3 hb = b.getHalfExtentsWithMargin();
        const double reach = a.getHalfExtentsWithMargin()[axis] + std::fabs(xb.getBasis().getColumn(0).dot(dir)) * hb.x() +
                             std::fabs(xb.getBasis().getColumn(1).dot(dir)) * hb.y() +
                             std::fabs(xb.getBasis().getColumn(2).dot(dir)) * hb.z();
        const btTransform xas[2] = {xa, xa};
        btTransform xbs[2] = {xb, xb};
        xbs[0].setOrigin(xa.getOrigin() + dir * (btScalar)(reach + 4 * threshold));
        xbs[1].setOrigin(xa.getOrigin() + dir * (btScalar)(reach + threshold * mk_rng_range(&rng, -2, 3)));
        const long before = mine.stats.skipped.load();
        collide_in_turn(&mine, &a, &b, xas, xbs, 1);
        const long after_first = mine.stats.skipped.load();
        const int got = collide_in_turn(&mine, &a, &b, xas, xbs, 2);
        const bool was_skipped = mine.stats.skipped.load() - after_first > after_first - before;  // the second step's
        mkb::ShapeMap ma, mb;
        ck_assert_int_eq(mine.map_shape(&a, &ma), MK_OK);
        ck_assert_int_eq(mine.map_shape(&b, &mb), MK_OK);
        mk_manifold direct;
        ck_assert_int_eq(mk_collide(&ma.shape, mkb::minko_pose(xas[1], ma), &mb.shape, mkb::minko_pose(xbs[1], mb),
                                    (mk_real)threshold, nullptr, &direct),
                         MK_OK);
        int touching_points = 0;
        for (int j = 0; j < direct.count; j++) touching_points += direct.points[j].depth >= 0;
        if (was_skipped) ck_assert_msg(direct.count == 0, "case %d skipped with %d points within the threshold", k, direct.count);
        ck_assert_msg(got == touching_points, "case %d: %d points, mk_collide %d touching", k, got, touching_points);
        skipped += was_skipped;
        touching += touching_points > 0;
        checked++;
    }
    ck_assert_int_gt(skipped, 80);
    ck_assert_int_gt(touching, 80);
    ck_assert_int_gt(checked - skipped - touching, 20);  // near but not touching, not skipped: mk_collide's to answer
}
END_TEST

// ---- continuous collision -----------------------------------------------------

// One world of a given kind with gravity off; bodies owned by the caller.
struct CcdRig {
    mkb::CollisionConfiguration config;
    btCollisionDispatcher dispatcher{&config};
    btDbvtBroadphase bp;
    btSequentialImpulseConstraintSolver solver;
    btDiscreteDynamicsWorld *world;
    explicit CcdRig(bool minko)
    {
        if (minko) world = new mkb::CcdWorld(&dispatcher, &bp, &solver, &config);
        else world = new btDiscreteDynamicsWorld(&dispatcher, &bp, &solver, &config);
        world->setGravity(btVector3(0, 0, 0));
    }
    ~CcdRig() { delete world; }
};

// A 0.05 sphere fired at 300 m/s (5 m per step) at a 0.1-thick wall: without
// CCD it passes; Bullet's CCD and Minko's both stop it on the near side, and
// Minko's stops it with a speculative contact at the time of impact or by
// clamping its motion there.
START_TEST(ccd_sphere_does_not_tunnel)
{
    btBoxShape wall(btVector3(btScalar(0.05), 2, 2));
    btSphereShape ball(btScalar(0.05));
    for (int mode = 0; mode < 3; mode++) {  // 0: no CCD, 1: Bullet's, 2: Minko's
        CcdRig rig(mode == 2);
        btRigidBody w(0, nullptr, &wall);
        btVector3 inertia;
        ball.calculateLocalInertia(btScalar(0.1), inertia);
        btRigidBody b(btScalar(0.1), nullptr, &ball, inertia);
        b.setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(btScalar(-7.3), 0, 0)));
        b.setLinearVelocity(btVector3(300, 0, 0));
        b.setActivationState(DISABLE_DEACTIVATION);
        if (mode) {
            b.setCcdMotionThreshold(btScalar(0.05));
            b.setCcdSweptSphereRadius(btScalar(0.04));
        }
        rig.world->addRigidBody(&w);
        rig.world->addRigidBody(&b);
        double first_stop = 0;
        for (int i = 0; i < 20; i++) {
            rig.world->stepSimulation(btScalar(1) / 60, 0);
            if (!first_stop && b.getLinearVelocity().x() < 100) first_stop = b.getWorldTransform().getOrigin().x();
        }
        const double x = b.getWorldTransform().getOrigin().x();
        if (mode == 0) ck_assert_msg(x > 0.1, "no CCD: the sphere should pass (x = %g)", x);
        else ck_assert_msg(x < 0, "CCD mode %d: the sphere passed the wall (x = %g)", mode, x);
        if (mode == 2) {
            mkb::CcdWorld *cw = static_cast<mkb::CcdWorld *>(rig.world);
            ck_assert_int_gt(cw->ccd_stats().clamped + cw->ccd_stats().predictive, 0);
            ck_assert_int_eq(cw->ccd_stats().native_fallbacks, 0);
        }
        rig.world->removeRigidBody(&b);
        rig.world->removeRigidBody(&w);
    }
}
END_TEST

// A rod 2 long spinning at 100 rad/s (tips at 100 m/s, 95 degrees a step)
// next to a thin plate its tips sweep through. Its centre does not move, so
// Bullet never runs CCD for it and the rod spins through the plate; Minko's
// rule measures the tips' motion and its time of impact follows the turn, so
// the rod stops at the plate.
START_TEST(ccd_spinning_rod)
{
    btBoxShape rod(btVector3(1, btScalar(0.02), btScalar(0.02)));
    btBoxShape plate(btVector3(btScalar(0.02), btScalar(0.15), btScalar(0.5)));
    for (int minko = 0; minko < 2; minko++) {
        CcdRig rig(minko != 0);
        btRigidBody p(0, nullptr, &plate);
        p.setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(btScalar(0.8), btScalar(0.3), 0)));
        btVector3 inertia;
        rod.calculateLocalInertia(1, inertia);
        btRigidBody r(1, nullptr, &rod, inertia);
        r.setAngularVelocity(btVector3(0, 0, 100));
        r.setActivationState(DISABLE_DEACTIVATION);
        r.setCcdMotionThreshold(btScalar(0.01));
        r.setCcdSweptSphereRadius(btScalar(0.01));
        rig.world->addRigidBody(&p);
        rig.world->addRigidBody(&r);
        // How far the rod's long axis turns about z (unwrapped), whatever it
        // does about its own axis after a one-point hit.
        double turned = 0;
        for (int i = 0; i < 30; i++) {
            btVector3 a0 = r.getWorldTransform().getBasis().getColumn(0);
            rig.world->stepSimulation(btScalar(1) / 60, 0);
            btVector3 a1 = r.getWorldTransform().getBasis().getColumn(0);
            double d = std::atan2((double)a1.y(), (double)a1.x()) - std::atan2((double)a0.y(), (double)a0.x());
            while (d > SIMD_PI) d -= 2 * SIMD_PI;
            while (d < -SIMD_PI) d += 2 * SIMD_PI;
            turned += d;
        }
        if (minko) ck_assert_msg(turned < 0.6, "Minko: the rod turned %g rad, through the plate", turned);
        else ck_assert_msg(turned > 2 * SIMD_PI, "Bullet: expected the rod to spin through (turned %g)", turned);
        rig.world->removeRigidBody(&r);
        rig.world->removeRigidBody(&p);
    }
}
END_TEST

// A sweep that meets a triangle mesh is Bullet's own (Minko does not model
// meshes), and it still stops the sphere.
START_TEST(ccd_mesh_falls_back_to_bullet)
{
    btTriangleMesh tris;
    tris.addTriangle(btVector3(-5, 0, -5), btVector3(5, 0, -5), btVector3(-5, 0, 5));
    tris.addTriangle(btVector3(5, 0, -5), btVector3(5, 0, 5), btVector3(-5, 0, 5));
    btBvhTriangleMeshShape mesh(&tris, true);
    btSphereShape ball(btScalar(0.1));
    CcdRig rig(true);
    btRigidBody m(0, nullptr, &mesh);
    btVector3 inertia;
    ball.calculateLocalInertia(1, inertia);
    btRigidBody b(1, nullptr, &ball, inertia);
    b.setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(0, 3, 0)));
    b.setLinearVelocity(btVector3(0, -200, 0));
    b.setActivationState(DISABLE_DEACTIVATION);
    b.setCcdMotionThreshold(btScalar(0.1));
    b.setCcdSweptSphereRadius(btScalar(0.08));
    rig.world->addRigidBody(&m);
    rig.world->addRigidBody(&b);
    for (int i = 0; i < 10; i++) rig.world->stepSimulation(btScalar(1) / 60, 0);
    ck_assert(b.getWorldTransform().getOrigin().y() > -0.05);
    ck_assert_int_gt(static_cast<mkb::CcdWorld *>(rig.world)->ccd_stats().native_fallbacks, 0);
    rig.world->removeRigidBody(&b);
    rig.world->removeRigidBody(&m);
}
END_TEST

Suite *suite()
{
    Suite *s = suite_create("minko_bullet");
    TCase *t = tcase_create("shapes");
    tcase_add_test(t, shape_box);
    tcase_add_test(t, shape_sphere_capsule);
    tcase_add_test(t, shape_cylinder_cone);
    tcase_add_test(t, shape_plane_and_refusals);
    tcase_add_test(t, shape_pose);
    suite_add_tcase(s, t);
    TCase *w = tcase_create("contact_writer");
    tcase_add_test(w, writer_matches_add_contact_point);
    tcase_add_test(w, writer_impulses_follow_features);
    tcase_add_test(w, writer_gone_new_and_callbacks);
    tcase_add_test(w, writer_refresh_of_fresh_points);
    tcase_add_test(w, writer_merges_points_within_threshold);
    tcase_add_test(w, writer_moved_feature_keeps_impulse);
    tcase_add_test(w, writer_mesh_parts_left_to_bullet);
    tcase_add_test(w, writer_far_moved_feature_starts_cold);
    suite_add_tcase(s, w);
    TCase *b = tcase_create("broadphase");
    tcase_set_timeout(b, 60);
    tcase_add_test(b, bp_pairs_exact_every_step);
    tcase_add_test(b, bp_same_trajectories_as_bullet);
    tcase_add_test(b, bp_deterministic_dispatch_order);
    tcase_add_test(b, bp_proxy_removal_during_simulation);
    tcase_add_test(b, bp_filtering);
    tcase_add_test(b, bp_ray_and_sweep_hits_equal_native);
    tcase_add_test(b, bp_switch_at_run_time);
    tcase_add_test(b, bp_bad_input_and_reset);
    suite_add_tcase(s, b);
    TCase *f = tcase_create("broadphase_fat_boxes");
    tcase_set_timeout(f, 60);
    tcase_add_test(f, bp_fat_boxes_hold_the_aabbs);
    tcase_add_test(f, bp_jitter_inside_the_fat_box_costs_nothing);
    tcase_add_test(f, bp_queries_answer_for_the_aabbs);
    suite_add_tcase(s, f);
    TCase *n = tcase_create("narrowphase");
    tcase_set_timeout(n, 60);
    tcase_add_test(n, shape_hull_cache);
    tcase_add_test(n, np_conventions_match_bullet);
    tcase_add_test(n, np_near_pairs_never_skipped);
    tcase_add_test(n, np_world_rests_on_minko_contacts);
    tcase_add_test(n, np_shape_changes_seen);
    tcase_add_test(n, np_world_poses_follow_the_objects);
    tcase_add_test(n, np_warm_pairs_take_the_best_face);
    tcase_add_test(n, np_box_points_in_bullets_order);
    tcase_add_test(n, np_hull_candidates_like_bullet);
    tcase_add_test(n, np_switch_at_run_time);
    tcase_add_test(n, np_hull_on_box_one_point_like_bullet);
    suite_add_tcase(s, n);
    TCase *pc = tcase_create("pose_cache");
    tcase_set_timeout(pc, 60); /* 16 shape pairs x two worlds per test: ~1.5 s under SAN at load 8, near Check's default 4 s when forking */
    tcase_add_test(pc, np_pose_cache_sees_one_ulp);
    tcase_add_test(pc, np_far_pairs_drop_points);
    tcase_add_test(pc, np_separated_boxes_skipped);
    tcase_add_test(pc, np_box_pairs_skipped_only_when_apart);
    suite_add_tcase(s, pc);
    TCase *c = tcase_create("ccd");
    tcase_set_timeout(c, 60);
    tcase_add_test(c, ccd_sphere_does_not_tunnel);
    tcase_add_test(c, ccd_spinning_rod);
    tcase_add_test(c, ccd_mesh_falls_back_to_bullet);
    suite_add_tcase(s, c);
    return s;
}

}  // namespace

int main() { return mk_test_run(suite()); }

// test_minko_bullet.cpp: the Bullet adapter's Check suite (C++11), run by
// `make check` in every build: double Minko with bullet-float64, single Minko
// with float Bullet, both also under ASan + UBSan.
#include <cmath>
#include <memory>
#include <vector>

#include "contact_writer.h"
#include "minko_bullet.h"
#include "support/mk_test.h"

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
void check_same_solid(const btConvexShape *bt, const char *what)
{
    mkb::ShapeMap m;
    MK_ASSERT_STATUS(mkb::map_primitive(bt, &m), MK_OK);
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
}
END_TEST


// ---- the feature-matched contact writer ---------------------------------------

// Two boxes and one manifold, as a collision algorithm sees them.
struct WriterRig {
    btBoxShape shape{btVector3(1, 1, 1)};
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
    void write(const mkb::PairContact *c, int n)
    {
        btManifoldResult r(wa, wb);
        r.setPersistentManifold(&manifold);
        mkb::write_contacts(&r, c, n);
    }
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

// Warm starting follows features, not positions: four corners whose positions
// rotate by one place between frames keep their own impulses. Bullet's
// distance matching hands every impulse to the wrong corner here.
START_TEST(writer_impulses_follow_features)
{
    const btScalar xs[4] = {btScalar(-0.5), btScalar(0.5), btScalar(0.5), btScalar(-0.5)};
    const btScalar zs[4] = {btScalar(-0.5), btScalar(-0.5), btScalar(0.5), btScalar(0.5)};
    for (int swapped = 0; swapped < 2; swapped++) {
        WriterRig rig(swapped != 0);
        mkb::PairContact c[4];
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
    for (int i = 0; i < 4; i++) r.addContactPoint(btVector3(0, 1, 0), btVector3(xs[i], 1, zs[i]), btScalar(-0.01));
    for (int i = 0; i < 4; i++) rig.manifold.getContactPoint(i).m_appliedImpulse = btScalar(1 + i);
    int moved = 0;
    for (int i = 0; i < 4; i++) r.addContactPoint(btVector3(0, 1, 0), btVector3(xs[(i + 1) % 4], 1, zs[(i + 1) % 4]), btScalar(-0.02));
    for (int i = 0; i < 4; i++) moved += rig.manifold.getContactPoint(i).m_positionWorldOnB.x() != xs[i];
    ck_assert_int_eq(moved, 0);  // each slot kept its place, so its impulse went to another corner's contact
}
END_TEST

int g_started = 0, g_ended = 0;
void on_started(btPersistentManifold *const &) { g_started++; }
void on_ended(btPersistentManifold *const &) { g_ended++; }

// Gone features leave, new ones start cold, and the started / ended callbacks
// fire once per touching episode, never in between.
START_TEST(writer_gone_new_and_callbacks)
{
    ContactStartedCallback old_started = gContactStartedCallback;
    ContactEndedCallback old_ended = gContactEndedCallback;
    gContactStartedCallback = on_started;
    gContactEndedCallback = on_ended;
    g_started = g_ended = 0;
    WriterRig rig(false);
    mkb::PairContact c[4] = {contact(-1, -1, btScalar(-0.01), 1, 1), contact(1, -1, btScalar(-0.01), 2, 2),
                             contact(1, 1, btScalar(-0.01), 3, 3), contact(-1, 1, btScalar(-0.01), 4, 4)};
    rig.write(c, 4);
    for (int f = 1; f <= 4; f++) rig.manifold.getContactPoint(rig.slot_of(f)).m_appliedImpulse = btScalar(f);
    // Frame 2: 2 and 3 stay, 1 and 4 are gone, 5 is new; one point beyond the
    // breaking threshold is dropped.
    mkb::PairContact d[4] = {contact(1, -1, btScalar(-0.01), 2, 2), contact(0, 0, btScalar(0.5), 6, 6),
                             contact(1, 1, btScalar(-0.01), 3, 3), contact(0, 1, btScalar(0.01), 5, 5)};
    rig.write(d, 4);
    ck_assert_int_eq(rig.manifold.getNumContacts(), 3);
    ck_assert_int_eq(rig.slot_of(1), -1);
    ck_assert_int_eq(rig.slot_of(4), -1);
    ck_assert_int_eq(rig.slot_of(6), -1);
    MK_ASSERT_NEAR(rig.manifold.getContactPoint(rig.slot_of(2)).m_appliedImpulse, 2, 0);
    MK_ASSERT_NEAR(rig.manifold.getContactPoint(rig.slot_of(3)).m_appliedImpulse, 3, 0);
    MK_ASSERT_NEAR(rig.manifold.getContactPoint(rig.slot_of(5)).m_appliedImpulse, 0, 0);
    ck_assert_int_eq(rig.manifold.getContactPoint(rig.slot_of(5)).getLifeTime(), 0);
    // Frame 3: only 5 is left (slots move under removal).
    rig.write(&d[3], 1);
    ck_assert_int_eq(rig.manifold.getNumContacts(), 1);
    ck_assert_int_eq(rig.slot_of(5), 0);
    ck_assert_int_eq(g_started, 1);
    ck_assert_int_eq(g_ended, 0);
    // Frame 4: separated; frame 5: touching again.
    rig.write(nullptr, 0);
    ck_assert_int_eq(rig.manifold.getNumContacts(), 0);
    ck_assert_int_eq(g_ended, 1);
    rig.write(c, 2);
    ck_assert_int_eq(g_started, 2);
    gContactStartedCallback = old_started;
    gContactEndedCallback = old_ended;
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
    tcase_add_test(w, writer_mesh_parts_left_to_bullet);
    suite_add_tcase(s, w);
    return s;
}

}  // namespace

int main() { return mk_test_run(suite()); }

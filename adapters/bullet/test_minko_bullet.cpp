// test_minko_bullet.cpp: the Bullet adapter's Check suite (C++11), run by
// `make check` in every build: double Minko with bullet-float64, single Minko
// with float Bullet, both also under ASan + UBSan.
#include <cmath>
#include <memory>
#include <vector>

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
    return s;
}

}  // namespace

int main() { return mk_test_run(suite()); }

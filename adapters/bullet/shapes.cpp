// shapes.cpp: Bullet shapes onto Minko shapes, exactly as Bullet's support
// functions define the solids (see minko_bullet.h).
#include "minko_bullet.h"

namespace mkb {

namespace {

// Rotation taking Minko's local z onto Bullet's axis `up` (0 = X, 1 = Y, 2 = Z),
// with a positive sign: a cone's apex stays on the + side.
mk_quat axis_rotation(int up)
{
    const mk_real h = (mk_real)0.70710678118654752440;
    switch (up) {
    case 0: return mk_quat_make(0, h, 0, h);   // +90 deg about y: z -> x
    case 1: return mk_quat_make(-h, 0, 0, h);  // -90 deg about x: z -> y
    default: return mk_quat_identity();
    }
}

}  // namespace

mk_status map_primitive(const btCollisionShape *shape, ShapeMap *out)
{
    if (!shape || !out) return MK_ERR_NULL;
    ShapeMap m;
    m.axis = mk_quat_identity();
    mk_status st;
    switch (shape->getShapeType()) {
    case SPHERE_SHAPE_PROXYTYPE:
        st = mk_shape_sphere(static_cast<const btSphereShape *>(shape)->getRadius(), &m.shape);
        break;
    case BOX_SHAPE_PROXYTYPE:
        // btBoxShape keeps halfExtents - margin internally and its support
        // function returns the sharp box of the full half extents.
        st = mk_shape_box(to_mk(static_cast<const btBoxShape *>(shape)->getHalfExtentsWithMargin()), 0, &m.shape);
        break;
    case CAPSULE_SHAPE_PROXYTYPE: {
        const btCapsuleShape *c = static_cast<const btCapsuleShape *>(shape);
        m.axis = axis_rotation(c->getUpAxis());
        st = mk_shape_capsule(c->getRadius(), c->getHalfHeight(), &m.shape);
        break;
    }
    case CYLINDER_SHAPE_PROXYTYPE: {
        // Support = margin-free cylinder of the implicit dimensions + margin:
        // a cylinder core rounded by the margin. Radius and half height sit on
        // the axes Bullet's CylinderLocalSupportX/Y/Z read.
        const btCylinderShape *c = static_cast<const btCylinderShape *>(shape);
        const int up = c->getUpAxis();
        const btVector3 &core = c->getHalfExtentsWithoutMargin();
        m.axis = axis_rotation(up);
        st = mk_shape_cylinder(core[up == 0 ? 1 : 0], core[up], c->getMargin(), &m.shape);
        break;
    }
    case CONE_SHAPE_PROXYTYPE: {
        // Support = exact cone (apex at +height/2 on the up axis) + margin.
        const btConeShape *c = static_cast<const btConeShape *>(shape);
        m.axis = axis_rotation(c->getConeUpIndex());
        st = mk_shape_cone(c->getRadius(), c->getHeight() / 2, c->getMargin(), &m.shape);
        break;
    }
    case STATIC_PLANE_PROXYTYPE: {
        // Solid below the plane n.x = constant; Bullet ignores local scaling here too.
        const btStaticPlaneShape *p = static_cast<const btStaticPlaneShape *>(shape);
        st = mk_shape_plane(to_mk(p->getPlaneNormal()), p->getPlaneConstant(), &m.shape);
        break;
    }
    default: return MK_ERR_UNSUPPORTED;
    }
    if (st == MK_OK) *out = m;
    return st;
}

// refresh_map less its inline case (an unchanged box).
mk_status detail::refresh_changed(const btCollisionShape *shape, ShapeMap *map, bool *changed)
{
    if (changed) *changed = false;
    // Every step for every pair: compare the few numbers that define the
    // solid and map again (with validation) only when one changed.
    const mk_shape &m = map->shape;
    switch (shape->getShapeType()) {
    case SPHERE_SHAPE_PROXYTYPE:
        if (static_cast<const btSphereShape *>(shape)->getRadius() == m.radius) return MK_OK;
        break;
    case CONVEX_HULL_SHAPE_PROXYTYPE: {
        const btScalar margin = shape->getMargin();
        if (margin == m.radius) return MK_OK;
        if (!(margin >= 0)) return MK_ERR_BAD_SIZE;
        map->shape.radius = margin;
        if (changed) *changed = true;
        return MK_OK;
    }
    default: break;
    }
    const mk_status st = map_primitive(shape, map);
    if (changed) *changed = st == MK_OK;
    return st;
}

mk_status minko_pose(const btTransform &world, const ShapeMap &map, mk_pose *out)
{
    btMatrix3x3 r = world.getBasis();
    const mk_quat &ax = map.axis;
    if (ax.x != 0 || ax.y != 0 || ax.z != 0) r *= btMatrix3x3(btQuaternion(ax.x, ax.y, ax.z, ax.w));
    mk_mat3 m;
    m.c0 = to_mk(r.getColumn(0));
    m.c1 = to_mk(r.getColumn(1));
    m.c2 = to_mk(r.getColumn(2));
    return mk_pose_from_matrix(m, to_mk(world.getOrigin()), out);
}

mk_transform minko_pose(const btTransform &world, const ShapeMap &map)
{
    mk_transform t = mk_transform_make(to_mk(world.getOrigin()), to_mk(world.getRotation()));
    t.q = mk_quat_mul(t.q, map.axis);
    return t;
}

}  // namespace mkb

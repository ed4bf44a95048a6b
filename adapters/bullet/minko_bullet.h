// minko_bullet.h: Minko as the collision backend of Bullet 3.24 (C++11).
//
// Contract. libminko_bullet is built against the Bullet variant whose btScalar
// matches Minko's mk_real (bullet-float64 with the double library, bullet with
// PRECISION=single); a mismatched build does not compile. Bullet shapes map
// onto Minko shapes exactly, the way Bullet's own support functions define
// them: a btBoxShape is the sharp box of its half extents (the margin is inside
// them), a btConvexHullShape, btCylinderShape or btConeShape is its margin-free
// core grown by the collision margin (Minko's rounding radius), spheres and
// capsules are their radius around a point or segment; capsule, cylinder and
// cone axes (X, Y or Z) are carried by a fixed rotation from Minko's local z.
// Shapes Minko does not model (meshes, compounds, ...) are refused with
// MK_ERR_UNSUPPORTED, and the adapters then leave those pairs to Bullet.
#ifndef MINKO_BULLET_H
#define MINKO_BULLET_H

#include <btBulletCollisionCommon.h>

#include "minko/shape.h"

static_assert(sizeof(btScalar) == sizeof(mk_real),
              "minko_bullet: Bullet's btScalar and Minko's mk_real differ; build double Minko with "
              "bullet-float64 (BT_USE_DOUBLE_PRECISION) and PRECISION=single with bullet");

namespace mkb {

// A Bullet shape seen by Minko: the Minko shape and the rotation that takes
// Minko's local frame into the Bullet shape's local frame (identity except for
// capsules, cylinders and cones whose axis is not Z). The world pose of the
// Minko shape is bullet_world_transform * axis.
struct ShapeMap {
    mk_shape shape;
    mk_quat axis;
};

inline mk_vec3 to_mk(const btVector3 &v) { return mk_v3(v.x(), v.y(), v.z()); }
inline btVector3 to_bt(mk_vec3 v) { return btVector3(v.x, v.y, v.z); }
inline mk_quat to_mk(const btQuaternion &q) { return mk_quat_make(q.x(), q.y(), q.z(), q.w()); }

// Maps every supported shape but btConvexHullShape, which needs a Minko hull
// built once per shape (see the collision configuration's hull cache).
// MK_ERR_UNSUPPORTED for other types; Minko's own status for sizes Minko
// refuses (e.g. a box with a zero extent).
mk_status map_primitive(const btCollisionShape *shape, ShapeMap *out);

// World pose of the mapped shape for a Bullet world transform.
mk_transform minko_pose(const btTransform &world, const ShapeMap &map);

}  // namespace mkb

#endif

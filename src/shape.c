/* shape.c: shape constructors, validation, support functions and bounds. */
#include <math.h>

#include "pose.h"

/* Finite-check first so a NaN size reports "not finite" rather than "bad size". */
static mk_status check_size(mk_real v) { return !mk_real_is_valid(v) ? MK_ERR_NOT_FINITE : mk_size_ok_(v) ? MK_OK : MK_ERR_BAD_SIZE; }
static mk_status check_rounding(mk_real v)
{
    return !mk_real_is_valid(v) ? MK_ERR_NOT_FINITE : mk_rounding_ok_(v) ? MK_OK : MK_ERR_BAD_SIZE;
}

const char *mk_shape_type_name(mk_shape_type t)
{
    static const char *const names[MK_SHAPE_TYPE_COUNT] = {"sphere", "box", "capsule", "cylinder", "cone", "hull", "plane"};
    return (unsigned)t < MK_SHAPE_TYPE_COUNT ? names[t] : "unknown";
}

mk_status mk_shape_validate(const mk_shape *s)
{
    mk_status st;
    if (!s) return MK_ERR_NULL;
    if ((unsigned)s->type >= MK_SHAPE_TYPE_COUNT) return MK_ERR_BAD_SHAPE;
    if (s->type != MK_SHAPE_PLANE && (st = check_rounding(s->radius)) != MK_OK) return st;
    switch (s->type) {
    case MK_SHAPE_SPHERE: return check_size(s->radius);
    case MK_SHAPE_BOX:
        if ((st = check_size(s->u.half_extents.x)) != MK_OK) return st;
        if ((st = check_size(s->u.half_extents.y)) != MK_OK) return st;
        return check_size(s->u.half_extents.z);
    case MK_SHAPE_CAPSULE:
        if ((st = check_size(s->radius)) != MK_OK) return st;
        return check_size(s->u.capsule.half_height);
    case MK_SHAPE_CYLINDER:
        if ((st = check_size(s->u.cylinder.radius)) != MK_OK) return st;
        return check_size(s->u.cylinder.half_height);
    case MK_SHAPE_CONE:
        if ((st = check_size(s->u.cone.radius)) != MK_OK) return st;
        return check_size(s->u.cone.half_height);
    case MK_SHAPE_HULL:
        if (!s->u.hull) return MK_ERR_NULL;
        return (s->u.hull->vertex_count >= 4 && s->u.hull->face_count >= 4) ? MK_OK : MK_ERR_DEGENERATE;
    case MK_SHAPE_PLANE:
        if (!mk_v3_is_valid(s->u.plane.normal) || !mk_real_is_valid(s->u.plane.offset)) return MK_ERR_NOT_FINITE;
        if (!(mk_fabs_(mk_v3_len2(s->u.plane.normal) - 1) <= MK_QUAT_TOLERANCE)) return MK_ERR_BAD_NORMAL;
        /* The offset is a coordinate along the normal: beyond MK_MAX_COORD the
         * pair-frame bound of math3d.h no longer holds for the plane queries. */
        return mk_fabs_(s->u.plane.offset) <= MK_MAX_COORD ? MK_OK : MK_ERR_OUT_OF_RANGE;
    default: return MK_ERR_BAD_SHAPE;
    }
}

/* Fill *out only when the candidate validates, so a refused call leaves it untouched. */
static mk_status finish(const mk_shape *candidate, mk_shape *out)
{
    mk_status st;
    if (!out) return MK_ERR_NULL;
    st = mk_shape_validate(candidate);
    if (st == MK_OK) *out = *candidate;
    return st;
}

static mk_shape blank(mk_shape_type type, mk_real radius)
{
    mk_shape s;
    s.type = type;
    s.radius = radius;
    s.u.half_extents = mk_v3_zero();
    return s;
}

mk_status mk_shape_sphere(mk_real radius, mk_shape *out)
{
    mk_shape s = blank(MK_SHAPE_SPHERE, radius);
    return finish(&s, out);
}

mk_status mk_shape_box(mk_vec3 half_extents, mk_real rounding, mk_shape *out)
{
    mk_shape s = blank(MK_SHAPE_BOX, rounding);
    s.u.half_extents = half_extents;
    return finish(&s, out);
}

mk_status mk_shape_capsule(mk_real radius, mk_real half_height, mk_shape *out)
{
    mk_shape s = blank(MK_SHAPE_CAPSULE, radius);
    s.u.capsule.half_height = half_height;
    return finish(&s, out);
}

mk_status mk_shape_cylinder(mk_real radius, mk_real half_height, mk_real rounding, mk_shape *out)
{
    mk_shape s = blank(MK_SHAPE_CYLINDER, rounding);
    s.u.cylinder.radius = radius;
    s.u.cylinder.half_height = half_height;
    return finish(&s, out);
}

mk_status mk_shape_cone(mk_real radius, mk_real half_height, mk_real rounding, mk_shape *out)
{
    mk_shape s = blank(MK_SHAPE_CONE, rounding);
    s.u.cone.radius = radius;
    s.u.cone.half_height = half_height;
    return finish(&s, out);
}

mk_status mk_shape_hull(const mk_hull *hull, mk_real rounding, mk_shape *out)
{
    mk_shape s = blank(MK_SHAPE_HULL, rounding);
    s.u.hull = hull;
    return finish(&s, out);
}

mk_status mk_shape_plane(mk_vec3 normal, mk_real offset, mk_shape *out)
{
    mk_shape s = blank(MK_SHAPE_PLANE, 0);
    mk_status st;
    s.u.plane.normal = normal;
    s.u.plane.offset = offset;
    st = finish(&s, out);
    if (st == MK_OK) out->u.plane.normal = mk_v3_normalize(normal);
    return st;
}

int mk_core_is_polytope(const mk_shape *s)
{
    return s->type == MK_SHAPE_SPHERE || s->type == MK_SHAPE_BOX || s->type == MK_SHAPE_CAPSULE || s->type == MK_SHAPE_HULL;
}

mk_vec3 mk_core_support(const mk_shape *s, mk_vec3 d, int *feature)
{
    int f = feature ? *feature : -1;
    mk_vec3 p = mk_core_support_inl(s, d, &f);
    if (feature) *feature = f;
    return p;
}

mk_vec3 mk_shape_support(const mk_shape *s, mk_vec3 dir)
{
    mk_vec3 p;
    if (s->type == MK_SHAPE_PLANE) {
        /* Only the direction along the outward normal has a finite answer. */
        mk_vec3 n = s->u.plane.normal;
        mk_real l = mk_v3_len(dir);
        if (l > 0 && mk_v3_dot(dir, n) >= l * (1 - MK_REAL_EPSILON * 8)) return mk_v3_scale(n, s->u.plane.offset);
        return mk_v3(MK_REAL_MAX, MK_REAL_MAX, MK_REAL_MAX);
    }
    if (mk_v3_len2(dir) == 0) dir = mk_v3(1, 0, 0);
    p = mk_core_support(s, dir, NULL);
    return s->radius > 0 ? mk_v3_mad(p, s->radius, mk_v3_normalize(dir)) : p;
}

/* AABB of a disc of radius r around centre c with unit axis a: the disc's
 * extent along world axis i is r*sqrt(1 - a_i^2). */
static mk_aabb disc_aabb(mk_vec3 c, mk_vec3 a, mk_real r)
{
    mk_vec3 e = mk_v3(r * mk_sqrt_(mk_max(0, 1 - a.x * a.x)), r * mk_sqrt_(mk_max(0, 1 - a.y * a.y)),
                      r * mk_sqrt_(mk_max(0, 1 - a.z * a.z)));
    return mk_aabb_make(mk_v3_sub(c, e), mk_v3_add(c, e));
}

static mk_aabb plane_aabb(const mk_shape *s, mk_transform xf)
{
    mk_real inf = (mk_real)HUGE_VAL;
    mk_vec3 n = mk_quat_rotate(mk_quat_normalize(xf.q), s->u.plane.normal);
    mk_real d = s->u.plane.offset + mk_v3_dot(n, xf.p);
    mk_aabb b = mk_aabb_make(mk_v3(-inf, -inf, -inf), mk_v3(inf, inf, inf));
    /* Finite only along an axis the normal is exactly aligned with. */
    if (n.y == 0 && n.z == 0) { if (n.x > 0) b.hi.x = d / n.x; else b.lo.x = d / n.x; }
    if (n.x == 0 && n.z == 0) { if (n.y > 0) b.hi.y = d / n.y; else b.lo.y = d / n.y; }
    if (n.x == 0 && n.y == 0) { if (n.z > 0) b.hi.z = d / n.z; else b.lo.z = d / n.z; }
    return b;
}

mk_status mk_shape_aabb(const mk_shape *s, mk_transform xf, mk_aabb *out)
{
    mk_status st;
    mk_mat3 R;
    mk_aabb b;
    if (!out) return MK_ERR_NULL;
    if ((st = mk_shape_validate(s)) != MK_OK) return st;
    if ((st = mk_transform_check_(xf)) != MK_OK) return st;
    if (s->type == MK_SHAPE_PLANE) {
        *out = plane_aabb(s, xf);
        return MK_OK;
    }
    R = mk_mat3_from_quat(mk_quat_normalize(xf.q));
    switch (s->type) {
    case MK_SHAPE_SPHERE: b = mk_aabb_make(xf.p, xf.p); break;
    case MK_SHAPE_BOX: {
        mk_vec3 e = mk_mat3_mul_v3(mk_mat3_abs(R), s->u.half_extents);
        b = mk_aabb_make(mk_v3_sub(xf.p, e), mk_v3_add(xf.p, e));
        break;
    }
    case MK_SHAPE_CAPSULE: {
        mk_vec3 e = mk_v3_abs(mk_v3_scale(R.c2, s->u.capsule.half_height));
        b = mk_aabb_make(mk_v3_sub(xf.p, e), mk_v3_add(xf.p, e));
        break;
    }
    case MK_SHAPE_CYLINDER: {
        mk_vec3 h = mk_v3_scale(R.c2, s->u.cylinder.half_height);
        b = mk_aabb_union(disc_aabb(mk_v3_add(xf.p, h), R.c2, s->u.cylinder.radius),
                          disc_aabb(mk_v3_sub(xf.p, h), R.c2, s->u.cylinder.radius));
        break;
    }
    case MK_SHAPE_CONE: {
        mk_vec3 apex = mk_v3_mad(xf.p, s->u.cone.half_height, R.c2);
        b = disc_aabb(mk_v3_mad(xf.p, -s->u.cone.half_height, R.c2), R.c2, s->u.cone.radius);
        b = mk_aabb_union(b, mk_aabb_make(apex, apex));
        break;
    }
    case MK_SHAPE_HULL: {
        /* Support along the six world axes; local direction of world axis i is row i of R. */
        const mk_hull *h = s->u.hull;
        mk_vec3 rows[3];
        mk_real lo[3], hi[3];
        int i, hint = -1;
        rows[0] = mk_v3(R.c0.x, R.c1.x, R.c2.x);
        rows[1] = mk_v3(R.c0.y, R.c1.y, R.c2.y);
        rows[2] = mk_v3(R.c0.z, R.c1.z, R.c2.z);
        for (i = 0; i < 3; ++i) {
            hint = mk_hull_support_index(h, rows[i], hint);
            hi[i] = mk_v3_dot(rows[i], h->vertices[hint]);
            hint = mk_hull_support_index(h, mk_v3_neg(rows[i]), hint);
            lo[i] = mk_v3_dot(rows[i], h->vertices[hint]);
        }
        b = mk_aabb_make(mk_v3_add(xf.p, mk_v3(lo[0], lo[1], lo[2])), mk_v3_add(xf.p, mk_v3(hi[0], hi[1], hi[2])));
        break;
    }
    default: return MK_ERR_BAD_SHAPE;
    }
    *out = mk_aabb_expand(b, s->radius);
    return MK_OK;
}

// demos/bench_toi: time of impact, Minko against Bullet's btContinuousConvexCollision
// and btGjkConvexCast and FCL 0.7's continuousCollide (its default, naive sampling,
// and conservative advancement), on the same cases in one process run.
//
// Every case is two convex shapes, each moving with constant linear and angular
// velocity about its own origin over the step (the motion model all three libraries
// share when the rotation centre is the shape's origin). The reference time of first
// contact (distance 0) comes from the long-double brute-force oracle of
// tests/support/oracle.h, independent of every library measured: a march whose steps
// d / (max point speed) can never skip a contact, then bisection on the distance's
// sign. Per (family, backend, tolerance) the output gives the mean time per query
// (best of several loops), the relative TOI error |t - t_ref| / t_ref over the cases
// that touch, `tunnelled` (a contact the backend did not report), `late` (a hit
// reported after the reference contact, i.e. with the shapes already overlapping),
// `wrong_bool` (a hit where the reference never touches, farther than the backend's
// own tolerance), `failures` (error status, iteration cap, unsupported pair), and the
// reference distance at the reported time relative to the pair's size, and
// `out_of_bound` (oob): hits whose reference distance lies outside the band the
// backend's contract promises (mk_toi: [0, tolerance], up to its rounding floor).
// Backend names carry their setting (minko.tol=1e-3 is a tolerance of 1e-3 x the
// pair's size, plain "minko" the default); "minko.bilateral" is the bilateral
// advancement prototype of bench_toi_bilateral.c, swept over the same tolerances,
// so the table gives error against run time for both advancement methods.
// Variant is the motion class, linear or rotating.
// JSON Lines per ../shared/BENCH_FORMAT.md (suite "toi") with --json FILE, and a
// table on stdout.
//
//   bench_toi [--quick] [--json FILE] [--cases N] [--seed S] [--family NAME] [--backend NAME|PREFIX]

#include <btBulletDynamicsCommon.h>
#include <BulletCollision/NarrowPhaseCollision/btContinuousConvexCollision.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkConvexCast.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>

#include <fcl/narrowphase/continuous_collision.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

extern "C" {
#include "minko/toi.h"
#include "support/mk_rng.h"
#include "support/oracle.h"
}
#include "bench_toi_bilateral.h"

namespace {

#if defined(BT_USE_DOUBLE_PRECISION)
const char *const kBullet = "bullet_f64";
#else
const char *const kBullet = "bullet_f32";
#endif

typedef long double ld;
typedef std::chrono::steady_clock Clock;

// ---- cases ------------------------------------------------------------------------

struct Body {
    mk_shape shape;
    mk_transform x0, x1; // start and end poses; the rotation centre is the shape's origin
};

struct Case {
    Body a, b;
    mk_sweep sa, sb;
    double t_ref;     // first contact, -1 when the shapes never touch
    double scale;     // size of the pair, for the distance tolerances
};

struct Family {
    const char *name;
    bool rotating;
    std::vector<Case> cases;
    int touching;
};

mk_transform pose(mk_vec3 p, mk_quat q) { return mk_transform_make(p, q); }

// ---- the reference: long double motion + oracle distance ----------------------------

struct RefBody {
    mk_oracle_shape o;
    ld c0[3], dc[3], axis[3], angle, r0[3][3];
    ld speed;   // largest speed of any point: |dc| + angle * bounding radius
};

void rot_axis_angle(const ld axis[3], ld angle, ld r[3][3])
{
    ld c = cosl(angle), s = sinl(angle), t = 1 - c;
    ld x = axis[0], y = axis[1], z = axis[2];
    r[0][0] = t * x * x + c;     r[0][1] = t * x * y - s * z; r[0][2] = t * x * z + s * y;
    r[1][0] = t * x * y + s * z; r[1][1] = t * y * y + c;     r[1][2] = t * y * z - s * x;
    r[2][0] = t * x * z - s * y; r[2][1] = t * y * z + s * x; r[2][2] = t * z * z + c;
}

// The motion of mk_sweep_from_transforms, recomputed in long double from the
// (exact) start and end poses: centre on the segment, constant-rate shortest turn.
void ref_body_init(RefBody &rb, const Body &b)
{
    mk_oracle_shape_init(&rb.o, &b.shape);
    mk_oracle_pose p0 = mk_oracle_pose_of(b.x0), p1 = mk_oracle_pose_of(b.x1);
    for (int i = 0; i < 3; ++i) {
        rb.c0[i] = i == 0 ? p0.p.x : i == 1 ? p0.p.y : p0.p.z;
        rb.dc[i] = (i == 0 ? p1.p.x : i == 1 ? p1.p.y : p1.p.z) - rb.c0[i];
        for (int j = 0; j < 3; ++j) rb.r0[i][j] = p0.r[i][j];
    }
    // Relative rotation R1 R0^T: axis from its skew part, angle from trace and skew.
    ld m[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            m[i][j] = 0;
            for (int k = 0; k < 3; ++k) m[i][j] += p1.r[i][k] * p0.r[j][k];
        }
    ld sx = m[2][1] - m[1][2], sy = m[0][2] - m[2][0], sz = m[1][0] - m[0][1];
    ld s = sqrtl(sx * sx + sy * sy + sz * sz), tr = m[0][0] + m[1][1] + m[2][2];
    rb.angle = atan2l(s, tr - 1);
    if (s > 0) {
        rb.axis[0] = sx / s; rb.axis[1] = sy / s; rb.axis[2] = sz / s;
    } else {
        rb.axis[0] = 1; rb.axis[1] = rb.axis[2] = 0;
    }
    ld v = sqrtl(rb.dc[0] * rb.dc[0] + rb.dc[1] * rb.dc[1] + rb.dc[2] * rb.dc[2]);
    rb.speed = v + rb.angle * rb.o.size;
}

mk_oracle_pose ref_pose(const RefBody &rb, ld t)
{
    mk_oracle_pose p;
    ld r[3][3];
    rot_axis_angle(rb.axis, rb.angle * t, r);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            p.r[i][j] = 0;
            for (int k = 0; k < 3; ++k) p.r[i][j] += r[i][k] * rb.r0[k][j];
        }
    p.p.x = rb.c0[0] + t * rb.dc[0];
    p.p.y = rb.c0[1] + t * rb.dc[1];
    p.p.z = rb.c0[2] + t * rb.dc[2];
    return p;
}

struct Reference {
    RefBody a, b;
    Reference(const Case &c) { ref_body_init(a, c.a); ref_body_init(b, c.b); }
    ~Reference() { mk_oracle_shape_free(&a.o); mk_oracle_shape_free(&b.o); }
    ld distance(ld t) const
    {
        mk_oracle_pose pa = ref_pose(a, t), pb = ref_pose(b, t);
        mk_oracle_result r;
        if (mk_oracle_query(&a.o, &pa, &b.o, &pb, 0, &r) != 0) {
            std::fprintf(stderr, "bench_toi: oracle refused a pair\n");
            std::exit(1);
        }
        return r.distance;
    }
    // First t in [0, 1] with distance <= 0, -1 if none. Marching by d / speed
    // cannot step over a contact; the last stretch is bisected on the sign.
    ld first_contact(ld scale) const
    {
        ld speed = a.speed + b.speed, t = 0, d = distance(0);
        if (d <= 0) return 0;
        for (int i = 0; i < 200000 && t <= 1; ++i) {
            if (d <= 1e-9L * scale) {
                // Look ahead in growing steps for the sign change, then bisect.
                ld lo = t, step = d / speed;
                for (int k = 0; k < 80 && lo <= 1; ++k, step *= 2) {
                    ld hi = std::min<ld>(lo + step, 1), dh = distance(hi);
                    if (dh <= 0) {
                        for (int j = 0; j < 100; ++j) {
                            ld m = 0.5L * (lo + hi);
                            if (distance(m) <= 0) hi = m;
                            else lo = m;
                        }
                        return hi;
                    }
                    if (dh > 1e-6L * scale) break; // moving away again: a near miss
                    lo = hi;
                    if (hi >= 1) return -1;
                }
            }
            t += d / speed;
            if (t > 1) return -1;
            d = distance(t);
        }
        return -1;
    }
};

// ---- case families ---------------------------------------------------------------------

mk_shape sphere(double r) { mk_shape s; mk_shape_sphere((mk_real)r, &s); return s; }
mk_shape box(double x, double y, double z) { mk_shape s; mk_shape_box(mk_v3((mk_real)x, (mk_real)y, (mk_real)z), 0, &s); return s; }
mk_shape capsule(double r, double h) { mk_shape s; mk_shape_capsule((mk_real)r, (mk_real)h, &s); return s; }
mk_shape plane_z() { mk_shape s; mk_shape_plane(mk_v3(0, 0, 1), 0, &s); return s; }

mk_quat turn(mk_rng *r, mk_quat q, double max_angle)
{
    if (max_angle == 0) return q;
    return mk_quat_normalize(mk_quat_mul(mk_quat_from_axis_angle(mk_rng_dir(r), (mk_real)mk_rng_range(r, 0, max_angle)), q));
}

// A flies past or into B (at the origin), aimed within `miss` of B's centre.
void fly_by(mk_rng *r, Case &c, double dist, double miss, double max_turn_a, double max_turn_b)
{
    mk_vec3 dir = mk_rng_dir(r), side = mk_v3_scale(mk_v3_perp(dir), (mk_real)mk_rng_range(r, 0, miss));
    side = mk_quat_rotate(mk_quat_from_axis_angle(dir, (mk_real)mk_rng_range(r, 0, 6.283)), side);
    double along = mk_rng_range(r, 0.2, 0.8); // where the centre passes B, as a fraction of the step
    mk_quat qa = mk_rng_quat(r), qb = mk_rng_quat(r);
    c.a.x0 = pose(mk_v3_add(mk_v3_scale(dir, (mk_real)(-dist * along)), side), qa);
    c.a.x1 = pose(mk_v3_add(mk_v3_scale(dir, (mk_real)(dist * (1 - along))), side), turn(r, qa, max_turn_a));
    c.b.x0 = pose(mk_v3_zero(), qb);
    c.b.x1 = pose(mk_rng_v3(r, -0.1, 0.1), turn(r, qb, max_turn_b));
    if (max_turn_b == 0) c.b.x1 = c.b.x0;
}

void finish(Family &f, Case &c)
{
    mk_sweep_from_transforms(c.a.x0, c.a.x1, mk_v3_zero(), &c.sa);
    mk_sweep_from_transforms(c.b.x0, c.b.x1, mk_v3_zero(), &c.sb);
    Reference ref(c);
    c.scale = (double)(ref.a.o.size + ref.b.o.size);
    if (ref.distance(0) <= 0) return; // overlapping at the start: not a TOI question
    c.t_ref = (double)ref.first_contact((ld)c.scale);
    if (c.t_ref >= 0 && c.t_ref < 0.02) return; // keep relative errors meaningful
    f.cases.push_back(c);
    if (c.t_ref >= 0) ++f.touching;
}

void make_family(Family &f, int n, uint64_t seed)
{
    mk_rng r = {seed};
    std::string name = f.name;
    while ((int)f.cases.size() < n) {
        Case c;
        std::memset(&c, 0, sizeof c);
        if (name == "sphere_sphere") {
            c.a.shape = sphere(mk_rng_range(&r, 0.1, 1));
            c.b.shape = sphere(mk_rng_range(&r, 0.1, 1));
            fly_by(&r, c, 6, 2, 0, 0);
        } else if (name == "box_box") {
            c.a.shape = box(mk_rng_range(&r, 0.1, 0.8), mk_rng_range(&r, 0.1, 0.8), mk_rng_range(&r, 0.1, 0.8));
            c.b.shape = box(mk_rng_range(&r, 0.2, 1), mk_rng_range(&r, 0.2, 1), mk_rng_range(&r, 0.2, 1));
            fly_by(&r, c, 6, 1.5, 0, 0);
        } else if (name == "capsule_box") {
            c.a.shape = capsule(mk_rng_range(&r, 0.05, 0.3), mk_rng_range(&r, 0.2, 0.8));
            c.b.shape = box(mk_rng_range(&r, 0.2, 1), mk_rng_range(&r, 0.2, 1), mk_rng_range(&r, 0.2, 1));
            fly_by(&r, c, 6, 1.5, 0, 0);
        } else if (name == "bullet_wall") {
            // A 5 cm ball at 10 to 1000 m/s (one 1/60 s step) into a 10 cm wall.
            double v = std::exp(mk_rng_range(&r, std::log(10.0), std::log(1000.0))) / 60;
            double y = mk_rng_range(&r, -1, 1), z = mk_rng_range(&r, -1, 1), x0 = -0.1 - mk_rng_range(&r, 0.05, 0.9) * v;
            c.a.shape = sphere(0.05);
            c.b.shape = box(0.05, 1, 1);
            c.a.x0 = pose(mk_v3((mk_real)x0, (mk_real)y, (mk_real)z), mk_quat_identity());
            c.a.x1 = pose(mk_v3((mk_real)(x0 + v), (mk_real)y, (mk_real)z), mk_quat_identity());
            c.b.x0 = c.b.x1 = pose(mk_v3_zero(), mk_quat_identity());
        } else if (name == "box_box_spin") {
            c.a.shape = box(mk_rng_range(&r, 0.1, 0.8), mk_rng_range(&r, 0.1, 0.8), mk_rng_range(&r, 0.1, 0.8));
            c.b.shape = box(mk_rng_range(&r, 0.2, 1), mk_rng_range(&r, 0.2, 1), mk_rng_range(&r, 0.2, 1));
            fly_by(&r, c, 5, 1.5, 3.0, 1.0);
        } else if (name == "rod_plate_spin") {
            // A 2 m rod, 2 cm thick, spinning at up to 3 rad per step past or into a plate.
            c.a.shape = box(1, 0.01, 0.01);
            c.b.shape = box(0.6, 0.6, 0.02);
            fly_by(&r, c, 3, 1.5, 3.0, 0);
        } else if (name == "capsule_capsule_spin") {
            c.a.shape = capsule(mk_rng_range(&r, 0.05, 0.3), mk_rng_range(&r, 0.2, 0.8));
            c.b.shape = capsule(mk_rng_range(&r, 0.05, 0.3), mk_rng_range(&r, 0.2, 0.8));
            fly_by(&r, c, 5, 1.2, 3.0, 1.0);
        } else if (name == "box_ground_spin") {
            // A box tipping over while it falls onto the ground plane.
            c.a.shape = box(mk_rng_range(&r, 0.1, 0.8), mk_rng_range(&r, 0.1, 0.8), mk_rng_range(&r, 0.1, 0.8));
            c.b.shape = plane_z();
            mk_quat q = mk_rng_quat(&r);
            mk_vec3 p = mk_rng_v3(&r, -1, 1);
            p.z = (mk_real)mk_rng_range(&r, 1.5, 2.5);
            c.a.x0 = pose(p, q);
            c.a.x1 = pose(mk_v3(p.x + (mk_real)mk_rng_range(&r, -1, 1), p.y, (mk_real)mk_rng_range(&r, -0.5, 1.0)), turn(&r, q, 3.0));
            c.b.x0 = c.b.x1 = pose(mk_v3_zero(), mk_quat_identity());
        }
        finish(f, c);
    }
}

// ---- backends --------------------------------------------------------------------------

struct Answer {
    bool hit;
    double t;
    bool failed;
    int iterations;
};

// The backend's name carries its setting (minko.tol=1e-3, fcl.naive.samples=100),
// so one plot of error against time per motion class shows every setting.
struct Backend {
    std::string name;
    bool linear_only;
    virtual ~Backend() {}
    // Distance within which the backend's contract lets it report a hit that
    // never becomes a contact (Minko's tolerance, Bullet's 0.001 stop).
    virtual double slack(const Case &) const { return 0; }
    // The distance band [bound_low, bound] a hit promises (checked against the
    // reference); bound < 0: the backend promises none.
    virtual double bound(const Case &) const { return -1; }
    virtual double bound_low(const Case &) const { return 0; }
    virtual void prepare(const std::vector<Case> &cases) = 0;
    virtual Answer run(size_t i, const Case &c) = 0;
};

// mk_toi's tolerance floor (toi.c), from the case: the bound of the contract
// holds up to it, and a tolerance below it is raised to it.
double minko_floor(const Case &c)
{
    const double eps = (double)MK_REAL_EPSILON * (sizeof(mk_real) == sizeof(double) ? 1e4 : 1e2);
    mk_vec3 d = mk_v3_sub(c.sb.c0, c.sa.c0), v = mk_v3_sub(mk_v3_sub(c.sb.c1, c.sb.c0), mk_v3_sub(c.sa.c1, c.sa.c0));
    return eps * (c.scale + (double)mk_v3_len(d) + (double)mk_v3_len(v));
}

// Minko's mk_toi (conservative advancement), or the bilateral advancement
// prototype of bench_toi_bilateral.c on the same internals, at a tolerance
// relative to the pair's size.
struct MinkoBackend : Backend {
    double tol;
    bool bilateral;
    MinkoBackend(double t, bool bl) : tol(t), bilateral(bl)
    {
        char buf[48];
        const char *base = bl ? "minko.bilateral" : "minko";
        std::snprintf(buf, sizeof buf, "%s.tol=%g", base, t);
        name = t == 0 ? base : buf; // 0: the default, the rounding floor
        linear_only = false;
    }
    double slack(const Case &c) const override { return std::max(tol * c.scale, minko_floor(c)); }
    // The contract's bound: at a hit the distance is in [0, tolerance], up to the floor.
    double bound(const Case &c) const override { return slack(c) + minko_floor(c); }
    double bound_low(const Case &c) const override { return -minko_floor(c); }
    void prepare(const std::vector<Case> &) override {}
    Answer run(size_t, const Case &c) override
    {
        mk_toi_result r;
        Answer a = {false, 1, false, 0};
        mk_real t = (mk_real)(tol * c.scale);
        mk_status st = bilateral ? bench_toi_bilateral(&c.a.shape, &c.sa, &c.b.shape, &c.sb, 0, t, &r)
                                 : mk_toi(&c.a.shape, &c.sa, &c.b.shape, &c.sb, 0, t, &r);
        if (st != MK_OK || r.state == MK_TOI_FAILED || !(r.t == r.t)) {
            a.failed = true;
            return a;
        }
        a.hit = r.state == MK_TOI_HIT || r.state == MK_TOI_OVERLAPPED;
        a.t = (double)r.t;
        a.iterations = r.iterations;
        return a;
    }
};

btTransform bt_pose(mk_transform x)
{
    return btTransform(btQuaternion((btScalar)x.q.x, (btScalar)x.q.y, (btScalar)x.q.z, (btScalar)x.q.w),
                       btVector3((btScalar)x.p.x, (btScalar)x.p.y, (btScalar)x.p.z));
}

// Exact shapes: Bullet's default margins would round boxes by 4 cm.
btCollisionShape *bt_shape(const mk_shape &s)
{
    btCollisionShape *out = nullptr;
    switch (s.type) {
    case MK_SHAPE_SPHERE: return new btSphereShape((btScalar)s.radius);
    case MK_SHAPE_BOX:
        out = new btBoxShape(btVector3((btScalar)s.u.half_extents.x, (btScalar)s.u.half_extents.y, (btScalar)s.u.half_extents.z));
        out->setMargin(0);
        return out;
    case MK_SHAPE_CAPSULE: return new btCapsuleShapeZ((btScalar)s.radius, (btScalar)(2 * s.u.capsule.half_height));
    case MK_SHAPE_PLANE:
        return new btStaticPlaneShape(btVector3((btScalar)s.u.plane.normal.x, (btScalar)s.u.plane.normal.y, (btScalar)s.u.plane.normal.z),
                                      (btScalar)s.u.plane.offset);
    default: return nullptr;
    }
}

struct BulletBackend : Backend {
    bool gjk_cast;
    std::vector<std::unique_ptr<btCollisionShape>> shapes;
    btVoronoiSimplexSolver simplex;
    btGjkEpaPenetrationDepthSolver epa;
    explicit BulletBackend(bool cast) : gjk_cast(cast)
    {
        name = std::string(kBullet) + (cast ? ".gjk_convex_cast" : ".continuous_convex"); // both stop at distance 0.001
        linear_only = cast; // btGjkConvexCast ignores rotation by design
    }
    double slack(const Case &) const override { return 0.001; }
    void prepare(const std::vector<Case> &cases) override
    {
        shapes.clear();
        for (const Case &c : cases) {
            shapes.emplace_back(bt_shape(c.a.shape));
            shapes.emplace_back(bt_shape(c.b.shape));
        }
    }
    Answer run(size_t i, const Case &c) override
    {
        Answer a = {false, 1, false, 0};
        btConvexCast::CastResult res;
        const btConvexShape *sa = static_cast<const btConvexShape *>(shapes[2 * i].get());
        btCollisionShape *sb = shapes[2 * i + 1].get();
        bool hit;
        if (sb->getShapeType() == STATIC_PLANE_PROXYTYPE) {
            if (gjk_cast) return a;
            btContinuousConvexCollision ccc(sa, static_cast<const btStaticPlaneShape *>(sb));
            hit = ccc.calcTimeOfImpact(bt_pose(c.a.x0), bt_pose(c.a.x1), bt_pose(c.b.x0), bt_pose(c.b.x1), res);
        } else if (gjk_cast) {
            btGjkConvexCast cast(sa, static_cast<const btConvexShape *>(sb), &simplex);
            hit = cast.calcTimeOfImpact(bt_pose(c.a.x0), bt_pose(c.a.x1), bt_pose(c.b.x0), bt_pose(c.b.x1), res);
        } else {
            btContinuousConvexCollision ccc(sa, static_cast<const btConvexShape *>(sb), &simplex, &epa);
            hit = ccc.calcTimeOfImpact(bt_pose(c.a.x0), bt_pose(c.a.x1), bt_pose(c.b.x0), bt_pose(c.b.x1), res);
        }
        a.hit = hit;
        a.t = hit ? (double)res.m_fraction : 1;
        if (hit && !(a.t == a.t)) a.failed = true;
        return a;
    }
};

fcl::Transform3d fcl_pose(mk_transform x)
{
    fcl::Transform3d t = fcl::Transform3d::Identity();
    t.linear() = fcl::Quaterniond((double)x.q.w, (double)x.q.x, (double)x.q.y, (double)x.q.z).normalized().toRotationMatrix();
    t.translation() = fcl::Vector3d((double)x.p.x, (double)x.p.y, (double)x.p.z);
    return t;
}

std::shared_ptr<fcl::CollisionGeometryd> fcl_shape(const mk_shape &s)
{
    switch (s.type) {
    case MK_SHAPE_SPHERE: return std::make_shared<fcl::Sphered>((double)s.radius);
    case MK_SHAPE_BOX:
        return std::make_shared<fcl::Boxd>(2 * (double)s.u.half_extents.x, 2 * (double)s.u.half_extents.y, 2 * (double)s.u.half_extents.z);
    case MK_SHAPE_CAPSULE: return std::make_shared<fcl::Capsuled>((double)s.radius, 2 * (double)s.u.capsule.half_height);
    case MK_SHAPE_PLANE:
        return std::make_shared<fcl::Halfspaced>(fcl::Vector3d((double)s.u.plane.normal.x, (double)s.u.plane.normal.y, (double)s.u.plane.normal.z),
                                                 (double)s.u.plane.offset);
    default: return nullptr;
    }
}

struct FclBackend : Backend {
    fcl::ContinuousCollisionRequestd request;
    std::vector<std::shared_ptr<fcl::CollisionGeometryd>> shapes;
    // FCL's default motion (CCDM_TRANS) drops the rotation, so every FCL run uses
    // the interpolating motion (CCDM_LINEAR's InterpMotion), which is the cases' motion.
    FclBackend(fcl::CCDSolverType solver, size_t samples)
    {
        request.ccd_solver_type = solver;
        request.ccd_motion_type = fcl::CCDM_LINEAR;
        char buf[64];
        if (solver == fcl::CCDC_NAIVE) {
            request.num_max_iterations = samples;
            request.toc_err = 1e-4;
            std::snprintf(buf, sizeof buf, "fcl.naive.samples=%zu", samples);
            name = samples == 10 ? "fcl.naive" : buf; // 10 samples: FCL's default
        } else {
            name = "fcl.conservative_advancement"; // its own fixed t_err = 1e-4
        }
        linear_only = false;
    }
    void prepare(const std::vector<Case> &cases) override
    {
        shapes.clear();
        for (const Case &c : cases) {
            shapes.push_back(fcl_shape(c.a.shape));
            shapes.push_back(fcl_shape(c.b.shape));
        }
    }
    Answer run(size_t i, const Case &c) override
    {
        Answer a = {false, 1, false, 0};
        fcl::ContinuousCollisionResultd res;
        // FCL 0.7's conservative advancement runs libccd's GJK on a halfspace,
        // which has no support function: it dereferences a null pointer. Counted
        // as failures rather than run.
        if (request.ccd_solver_type == fcl::CCDC_CONSERVATIVE_ADVANCEMENT &&
            (c.a.shape.type == MK_SHAPE_PLANE || c.b.shape.type == MK_SHAPE_PLANE)) {
            a.failed = true;
            return a;
        }
        // The motions are built here with their reference point given: FCL 0.7's
        // InterpMotion(tf1, tf2), which continuousCollide would use, leaves that
        // point uninitialised (an Eigen vector's default constructor), so its
        // rotations would turn about an arbitrary point.
        fcl::Transform3d a0 = fcl_pose(c.a.x0), a1 = fcl_pose(c.a.x1), b0 = fcl_pose(c.b.x0), b1 = fcl_pose(c.b.x1);
        const fcl::Vector3d origin = fcl::Vector3d::Zero();
        fcl::InterpMotion<double> ma(a0.linear(), a0.translation(), a1.linear(), a1.translation(), origin);
        fcl::InterpMotion<double> mb(b0.linear(), b0.translation(), b1.linear(), b1.translation(), origin);
        fcl::continuousCollide(shapes[2 * i].get(), &ma, shapes[2 * i + 1].get(), &mb, request, res);
        a.hit = res.is_collide;
        a.t = a.hit ? (double)res.time_of_contact : 1;
        return a;
    }
};

// ---- measurement -------------------------------------------------------------------------

struct Row {
    std::string family, variant, backend;
    int n;
    double ns, p50, p99, max_err, dist_min, dist_max, iterations;
    int tunnelled, late, wrong, failures, touching;
    int out_of_bound; // hits outside the promised distance band; -1: none promised
};

double percentile(std::vector<double> v, double p)
{
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    size_t k = (size_t)std::ceil(p * (double)v.size()) - 1;
    return v[std::min(k, v.size() - 1)];
}

Row measure(const Family &f, Backend &be, int loops)
{
    Row row;
    row.family = f.name;
    row.variant = f.rotating ? "rotating" : "linear";
    row.backend = be.name;
    row.n = (int)f.cases.size();
    be.prepare(f.cases);
    std::vector<Answer> ans(f.cases.size());
    double best = 1e300;
    for (int l = 0; l < loops; ++l) {
        Clock::time_point t0 = Clock::now();
        for (size_t i = 0; i < f.cases.size(); ++i) ans[i] = be.run(i, f.cases[i]);
        best = std::min(best, std::chrono::duration<double, std::nano>(Clock::now() - t0).count());
    }
    row.ns = best / (double)f.cases.size();
    std::vector<double> err;
    row.tunnelled = row.late = row.wrong = row.failures = 0;
    row.out_of_bound = f.cases.empty() || be.bound(f.cases[0]) < 0 ? -1 : 0;
    row.dist_min = 1e300;
    row.dist_max = -1e300;
    row.touching = f.touching;
    double iters = 0;
    for (size_t i = 0; i < f.cases.size(); ++i) {
        const Case &c = f.cases[i];
        const Answer &a = ans[i];
        iters += a.iterations;
        if (a.failed) {
            ++row.failures;
            continue;
        }
        if (c.t_ref >= 0 && !a.hit) ++row.tunnelled;
        if (!a.hit) continue;
        Reference ref(c);
        double d = (double)ref.distance((ld)a.t);
        row.dist_min = std::min(row.dist_min, d / c.scale); // relative to the pair's size
        row.dist_max = std::max(row.dist_max, d / c.scale);
        if (row.out_of_bound >= 0 && (d < be.bound_low(c) || d > be.bound(c))) ++row.out_of_bound;
        if (c.t_ref < 0) {
            if (d > be.slack(c) + 1e-9 * c.scale) ++row.wrong; // a hit where nothing ever touches
            continue;
        }
        err.push_back(std::fabs(a.t - c.t_ref) / c.t_ref);
        if (a.t > c.t_ref * (1 + 1e-12)) ++row.late;
    }
    row.p50 = percentile(err, 0.5);
    row.p99 = percentile(err, 0.99);
    row.max_err = err.empty() ? 0 : *std::max_element(err.begin(), err.end());
    row.iterations = iters / (double)f.cases.size();
    if (row.dist_min > row.dist_max) row.dist_min = row.dist_max = 0;
    return row;
}

void print_row(const Row &r)
{
    char oob[16] = "-";
    if (r.out_of_bound >= 0) std::snprintf(oob, sizeof oob, "%d", r.out_of_bound);
    std::printf("%-21s %-9s %-26s %9.0f %9.2e %9.2e %9.2e %5d %5d %5d %5d %5s %10.2e %10.2e %6.1f\n", r.family.c_str(), r.variant.c_str(),
                r.backend.c_str(), r.ns, r.p50, r.p99, r.max_err, r.tunnelled, r.late, r.wrong, r.failures, oob, r.dist_min, r.dist_max,
                r.iterations);
}

void json_row(FILE *f, const Row &r)
{
    std::fprintf(f,
                 "{\"suite\":\"toi\",\"case\":\"%s\",\"variant\":\"%s\",\"backend\":\"%s\",\"n\":%d,\"touching\":%d,"
                 "\"ns_per_query\":%.1f,\"rel_err_p50\":%.3e,\"rel_err_p99\":%.3e,\"rel_err_max\":%.3e,"
                 "\"tunnelled\":%d,\"late\":%d,\"wrong_bool\":%d,\"failures\":%d,"
                 "\"dist_at_hit_min\":%.3e,\"dist_at_hit_max\":%.3e,\"iterations_mean\":%.2f",
                 r.family.c_str(), r.variant.c_str(), r.backend.c_str(), r.n, r.touching, r.ns, r.p50, r.p99, r.max_err, r.tunnelled,
                 r.late, r.wrong, r.failures, r.dist_min, r.dist_max, r.iterations);
    if (r.out_of_bound >= 0) std::fprintf(f, ",\"out_of_bound\":%d", r.out_of_bound);
    std::fprintf(f, "}\n");
}

// The speed target, read off one run: the cheapest row of one Minko
// method (mk_toi: "minko"; the prototype: "minko.bilateral") whose accuracy is
// at least Bullet's conservative advancement's, and the time ratio.
bool of_method(const std::string &backend, const std::string &method)
{
    return backend == method || backend.compare(0, method.size() + 5, method + ".tol=") == 0;
}

std::string compare_with_bullet(const std::vector<Row> &rows, const std::string &method)
{
    const Row *bt = nullptr, *best = nullptr;
    for (const Row &r : rows)
        if (r.backend == std::string(kBullet) + ".continuous_convex") bt = &r;
    if (!bt) return "";
    for (const Row &r : rows)
        if (of_method(r.backend, method) && r.p99 <= bt->p99 && r.tunnelled <= bt->tunnelled && r.late <= bt->late &&
            r.failures <= bt->failures && (!best || r.ns < best->ns))
            best = &r;
    char buf[256];
    if (!best)
        std::snprintf(buf, sizeof buf, "  %-21s %-26s no setting is as accurate", bt->family.c_str(), method.c_str());
    else
        std::snprintf(buf, sizeof buf, "  %-21s %-26s %7.0f ns (err p99 %.2e)  vs %7.0f ns (err p99 %.2e): ratio %.2f", bt->family.c_str(),
                      best->backend.c_str(), best->ns, best->p99, bt->ns, bt->p99, best->ns / bt->ns);
    return buf;
}

// --backend NAME: that backend alone when one is called exactly so (for
// callgrind runs of one setting), else every backend whose name starts so.
bool backend_selected(const std::string &name, const char *filter, const std::vector<std::unique_ptr<Backend>> &backends)
{
    for (const auto &be : backends)
        if (be->name == filter) return name == filter;
    return name.compare(0, std::strlen(filter), filter) == 0;
}

} // namespace

int main(int argc, char **argv)
{
    bool quick = false;
    const char *json = nullptr;
    int n = 200;
    uint64_t seed = 5;
    const char *only_family = nullptr, *only_backend = nullptr;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--quick")) quick = true;
        else if (!std::strcmp(argv[i], "--json") && i + 1 < argc) json = argv[++i];
        else if (!std::strcmp(argv[i], "--cases") && i + 1 < argc) n = std::atoi(argv[++i]);
        else if (!std::strcmp(argv[i], "--seed") && i + 1 < argc) seed = (uint64_t)std::atoll(argv[++i]);
        else if (!std::strcmp(argv[i], "--family") && i + 1 < argc) only_family = argv[++i];
        else if (!std::strcmp(argv[i], "--backend") && i + 1 < argc) only_backend = argv[++i];
        else {
            std::fprintf(stderr, "usage: %s [--quick] [--json FILE] [--cases N] [--seed S] [--family NAME] [--backend NAME|PREFIX]\n", argv[0]);
            return 2;
        }
    }
    if (quick) n = std::min(n, 40);
    int loops = quick ? 1 : 5;
    FILE *jf = json ? std::fopen(json, "w") : nullptr;
    if (json && !jf) {
        std::perror(json);
        return 1;
    }

    const char *names[] = {"sphere_sphere", "box_box", "capsule_box", "bullet_wall", "box_box_spin", "rod_plate_spin", "capsule_capsule_spin",
                           "box_ground_spin"};
    std::vector<Family> families;
    for (size_t k = 0; k < sizeof names / sizeof *names; ++k) {
        if (only_family && std::strcmp(only_family, names[k])) continue;
        Family f;
        f.name = names[k];
        f.rotating = std::strstr(names[k], "spin") != nullptr;
        f.touching = 0;
        make_family(f, n, seed * 1000 + k);
        families.push_back(f);
    }

    std::vector<std::unique_ptr<Backend>> backends;
    // Tolerances relative to the pair's size; 0 is Minko's default, the rounding floor.
    const double tols[] = {1e-1, 1e-2, 1e-3, 1e-4, 1e-6, 1e-9, 0};
    for (double t : tols) backends.emplace_back(new MinkoBackend(t, false));
    for (double t : tols) backends.emplace_back(new MinkoBackend(t, true));
    backends.emplace_back(new BulletBackend(false));
    backends.emplace_back(new BulletBackend(true));
    backends.emplace_back(new FclBackend(fcl::CCDC_NAIVE, 10));
    if (!quick) {
        backends.emplace_back(new FclBackend(fcl::CCDC_NAIVE, 100));
        backends.emplace_back(new FclBackend(fcl::CCDC_NAIVE, 1000));
    }
    backends.emplace_back(new FclBackend(fcl::CCDC_CONSERVATIVE_ADVANCEMENT, 0));

    std::printf("time of impact: %d cases per family (seed %llu), reference = long-double oracle, tolerances relative to the pair's size\n",
                n, (unsigned long long)seed);
    std::printf("%-21s %-9s %-26s %9s %9s %9s %9s %5s %5s %5s %5s %5s %10s %10s %6s\n", "family", "motion", "backend", "ns/query", "err p50",
                "err p99", "err max", "tunl", "late", "wrong", "fail", "oob", "d@hit min", "d@hit max", "iters");
    std::vector<std::string> summary;
    for (const Family &f : families) {
        std::vector<Row> rows;
        for (auto &be : backends) {
            if (be->linear_only && f.rotating) continue;
            if (only_backend && !backend_selected(be->name, only_backend, backends)) continue;
            Row r = measure(f, *be, loops);
            print_row(r);
            if (jf) json_row(jf, r);
            rows.push_back(r);
        }
        std::printf("\n");
        summary.push_back(compare_with_bullet(rows, "minko"));
        summary.push_back(compare_with_bullet(rows, "minko.bilateral"));
    }
    std::printf("Fastest setting of each Minko method at equal or better accuracy (err p99, tunnelled, late, failures) than %s.continuous_convex:\n",
                kBullet);
    for (const std::string &line : summary)
        if (!line.empty()) std::printf("%s\n", line.c_str());
    if (jf) std::fclose(jf);
    return 0;
}

// narrowphase.cpp: Minko contact manifolds as Bullet collision algorithms
// (see minko_bullet.h).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <new>

#include <LinearMath/btThreads.h>

#include "contact_writer.h"
#include "minko_bullet.h"

namespace mkb {

namespace {

const int kMinkoTypes[] = {SPHERE_SHAPE_PROXYTYPE,   BOX_SHAPE_PROXYTYPE,         CAPSULE_SHAPE_PROXYTYPE,
                           CYLINDER_SHAPE_PROXYTYPE, CONE_SHAPE_PROXYTYPE,        CONVEX_HULL_SHAPE_PROXYTYPE,
                           STATIC_PLANE_PROXYTYPE};

// Radius of a ball about the shape's origin holding its core (the solid less
// its rounding radius); infinite for a plane. Kept per pair and recomputed
// only when the pair's mapping changes: a box's square root per pair and
// step cost 53 M instructions per 300 steps of the 3000 boxes.
btScalar core_reach(const mk_shape &s)
{
    switch (s.type) {
    case MK_SHAPE_SPHERE: return 0;
    case MK_SHAPE_BOX: return btSqrt(mk_v3_dot(s.u.half_extents, s.u.half_extents));
    case MK_SHAPE_CAPSULE: return s.u.capsule.half_height;
    // The base rim is farther from the origin than the apex.
    case MK_SHAPE_CYLINDER: return btSqrt(s.u.cylinder.radius * s.u.cylinder.radius + s.u.cylinder.half_height * s.u.cylinder.half_height);
    case MK_SHAPE_CONE: return btSqrt(s.u.cone.radius * s.u.cone.radius + s.u.cone.half_height * s.u.cone.half_height);
    case MK_SHAPE_HULL: return btSqrt(mk_v3_dot(s.u.hull->centroid, s.u.hull->centroid)) + s.u.hull->outer_radius;
    default: return BT_INFINITY;
    }
}

// Whether point p (the shape's local frame) is farther than `gap` from the
// solid, `reach` being the shape's core_reach: exact for a box (the distance
// to the core box, less the rounding), centre distance less the reach
// otherwise. Compared squared: no square root.
bool farther(const mk_shape &s, const btVector3 &p, btScalar reach, btScalar gap)
{
    btScalar k = gap + s.radius;
    btVector3 v = p;
    if (s.type == MK_SHAPE_BOX) {
        const mk_vec3 &h = s.u.half_extents;
        v.setValue(btMax(btFabs(p.x()) - h.x, btScalar(0)), btMax(btFabs(p.y()) - h.y, btScalar(0)),
                   btMax(btFabs(p.z()) - h.z, btScalar(0)));
    } else {
        k += reach;
    }
    return k < 0 || v.length2() > k * k;
}

// Whether the solids are certainly more than `threshold` apart, A and B at
// world poses ta and tb, with core reaches ra and rb: each centre, seen in
// the other's frame, against the other solid, less its own bounding radius.
// About 60 flops against a full mk_collide, and no relative pose (which only
// the pairs that pass need); in a settling pile of boxes a third of the AABB
// pairs are rejected here.
bool apart(const mk_shape &a, btScalar ra, const mk_shape &b, btScalar rb, const btTransform &ta, const btTransform &tb,
           btScalar threshold)
{
    if (a.type == MK_SHAPE_PLANE || b.type == MK_SHAPE_PLANE) return false;
    const btVector3 d = tb.getOrigin() - ta.getOrigin();
    if (farther(a, d * ta.getBasis(), ra, threshold + rb + b.radius)) return true;  // R_a^T d
    return farther(b, -(d * tb.getBasis()), rb, threshold + ra + a.radius);
}

// A bound on the rounding of a face-axis separation below against Minko's
// own test (a few ulps of the coordinates and sizes), so that a pair found
// more than the threshold apart less this is one mk_collide finds apart too.
btScalar face_slack(const btVector3 &d, const mk_vec3 &ha, const mk_vec3 &hb)
{
    return 64 * SIMD_EPSILON * (btFabs(d.x()) + btFabs(d.y()) + btFabs(d.z()) + ha.x + ha.y + ha.z + hb.x + hb.y + hb.z);
}

// The separation of two boxes (half extents ha, hb, rounding rr together)
// at world transforms ta, tb along face axis k: A's axis k for k < 3, B's
// axis k - 3 for k >= 3 (the separating-axis test for one face axis, some
// 35 flops), less face_slack.
btScalar face_separation(int k, const mk_vec3 &ha, const mk_vec3 &hb, btScalar rr, const btTransform &ta,
                         const btTransform &tb)
{
    const bool of_a = k < 3;
    const int i = of_a ? k : k - 3;
    const btVector3 e = (of_a ? ta : tb).getBasis().getColumn(i);
    const btMatrix3x3 &o = (of_a ? tb : ta).getBasis();
    const mk_vec3 &h = of_a ? ha : hb, &g = of_a ? hb : ha;
    const btVector3 d = tb.getOrigin() - ta.getOrigin();
    const btScalar reach = (&h.x)[i] + btFabs(e.x() * o[0][0] + e.y() * o[1][0] + e.z() * o[2][0]) * g.x +
                           btFabs(e.x() * o[0][1] + e.y() * o[1][1] + e.z() * o[2][1]) * g.y +
                           btFabs(e.x() * o[0][2] + e.y() * o[1][2] + e.z() * o[2][2]) * g.z;
    return btFabs(e.dot(d)) - reach - rr - face_slack(d, ha, hb);
}

// The first face axis (numbered as in face_separation) along which two
// boxes are more than `gap` apart (*apart), and, when there is none, the
// first along which they are apart at all (*separated; left as it is
// otherwise), or -1. All six at once: B's rotation in A's frame, the offset
// and the slack are shared (some 130 flops against 6 x 45 one axis at a
// time), and one pass serves both gaps (two passes, one per gap, cost 31 M
// instructions more per 300 steps of the 3000 boxes, 20 M on the 1000
// stack). Most boxes that mk_collide finds apart are within the threshold
// on every face axis (on the 1000 stack 126k of 131k calls), so all six are
// usually needed.
void apart_faces(const mk_shape &a, const mk_shape &b, const btTransform &ta, const btTransform &tb, btScalar gap,
                 int *apart, int *separated)
{
    const mk_vec3 &ha = a.u.half_extents, &hb = b.u.half_extents;
    const btMatrix3x3 &ra = ta.getBasis(), &rb = tb.getBasis();
    const btVector3 d = tb.getOrigin() - ta.getOrigin();
    const btVector3 da = d * ra, db = d * rb;  // R^T d: the offset along each box's axes
    const btMatrix3x3 c = ra.transposeTimes(rb);  // c[i][j] = A's axis i . B's axis j
    const btScalar slack = face_slack(d, ha, hb);
    btScalar abs_c[3][3], sep[6];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) abs_c[i][j] = btFabs(c[i][j]);
    for (int i = 0; i < 3; i++)
        sep[i] = btFabs(da[i]) - (&ha.x)[i] - (abs_c[i][0] * hb.x + abs_c[i][1] * hb.y + abs_c[i][2] * hb.z);
    for (int j = 0; j < 3; j++)
        sep[3 + j] = btFabs(db[j]) - (&hb.x)[j] - (abs_c[0][j] * ha.x + abs_c[1][j] * ha.y + abs_c[2][j] * ha.z);
    *apart = -1;
    for (int k = 0; k < 6; k++)
        if (sep[k] > gap + a.radius + b.radius + slack) {
            *apart = k;
            return;
        }
    if (!separated) return;
    *separated = -1;
    for (int k = 0; k < 6; k++)
        if (sep[k] > btScalar(0) + a.radius + b.radius + slack) {
            *separated = k;
            return;
        }
}

// Both shapes are hulls with polyhedral features
// (btPolyhedralConvexShape::initializePolyhedralFeatures).
bool polyhedral_hulls(const btCollisionShape *a, const btCollisionShape *b)
{
    return a->getShapeType() == CONVEX_HULL_SHAPE_PROXYTYPE && b->getShapeType() == CONVEX_HULL_SHAPE_PROXYTYPE &&
           static_cast<const btPolyhedralConvexShape *>(a)->getConvexPolyhedron() &&
           static_cast<const btPolyhedralConvexShape *>(b)->getConvexPolyhedron();
}

// A hull with polyhedral features against a box: Bullet's btConvexConvexAlgorithm
// runs GJK alone on it (a box has no polyhedral features to clip against
// unless asked), one point per frame, and its manifold gathers up to four
// over the frames by its own matching and area rule.
bool hull_on_box(const btCollisionShape *a, const btCollisionShape *b)
{
    const int ta = a->getShapeType(), tb = b->getShapeType();
    if (ta == BOX_SHAPE_PROXYTYPE) std::swap(a, b);
    return (ta == BOX_SHAPE_PROXYTYPE) != (tb == BOX_SHAPE_PROXYTYPE) && a->getShapeType() == CONVEX_HULL_SHAPE_PROXYTYPE &&
           static_cast<const btPolyhedralConvexShape *>(a)->getConvexPolyhedron();
}

// Minko's points in Bullet's convention, for the wrappers in Bullet's order
// (`flip`: they are in the other order than the algorithm's A and B).
// Minko: normal from A to B, depth > 0 penetrating, point_b on B. Bullet:
// normal on B pointing from B to A, signed distance < 0 penetrating.
// Returns how many were written.
int to_bullet(const mk_vec3 &normal, const mk_contact_point *points, int count, bool flip, PairContact *out)
{
    const btVector3 n = to_bt(normal);
    const bool ab = !flip;
    int k = 0;
    for (int j = 0; j < count; j++) {
        const mk_contact_point &c = points[j];
        PairContact &p = out[k++];
        p.normal_on_b = ab ? -n : n;
        p.point_on_b = to_bt(ab ? c.point_b : c.point_a);
        p.distance = -c.depth;
        p.feature_a = ab ? MK_FEATURE_PAIR_A(c.features) : MK_FEATURE_PAIR_B(c.features);
        p.feature_b = ab ? MK_FEATURE_PAIR_B(c.features) : MK_FEATURE_PAIR_A(c.features);
    }
    return k;
}

// Moves the deepest point to the end, so that when points go through
// addContactPoint no shallower point added after it can replace it.
void deepest_last(PairContact *pts, int count)
{
    if (count < 2) return;
    int deepest = 0;
    for (int i = 1; i < count; i++)
        if (pts[i].distance < pts[deepest].distance) deepest = i;
    std::swap(pts[deepest], pts[count - 1]);
}

// One pair's algorithm: the two mapped shapes, Minko's per-pair cache (the
// previous separating axis) and the manifold. Lives exactly as long as the
// broadphase pair, in Bullet's algorithm pool.
class Algorithm : public btActivatingCollisionAlgorithm {
public:
    Algorithm(const btCollisionAlgorithmConstructionInfo &ci, const btCollisionObjectWrapper *w0,
              const btCollisionObjectWrapper *w1, CollisionConfiguration *config, const ShapeMap &a, const ShapeMap &b)
        : btActivatingCollisionAlgorithm(ci, w0, w1),
          m_manifold(ci.m_manifold),
          m_own(false),
          m_shape0(w0->getCollisionShape()),
          m_config(config),
          m_a(a),
          m_b(b),
          m_reach_a(core_reach(a.shape)),
          m_reach_b(core_reach(b.shape))
    {
        start_cold();
    }
    ~Algorithm() override
    {
        if (m_own && m_manifold) m_dispatcher->releaseManifold(m_manifold);
    }

    void processCollision(const btCollisionObjectWrapper *w0, const btCollisionObjectWrapper *w1,
                          const btDispatcherInfo &, btManifoldResult *result) override
    {
        // Bullet hands the pair in its creation order; cope with the other one anyway.
        const bool flip = w0->getCollisionShape() != m_shape0;
        const btCollisionObjectWrapper *wa = flip ? w1 : w0, *wb = flip ? w0 : w1;
        if (!m_manifold) {
            m_manifold = m_dispatcher->getNewManifold(w0->getCollisionObject(), w1->getCollisionObject());
            m_own = true;
        }
        result->setPersistentManifold(m_manifold);

        // Shapes are refreshed every step (a few loads), so a resized or
        // rescaled primitive or a new margin is seen at once, as by Bullet.
        const btTransform &ta = wa->getWorldTransform(), &tb = wb->getWorldTransform();
        const btScalar threshold = m_manifold->getContactBreakingThreshold();
        mk_manifold mf;
        mf.count = 0;
        bool changed_a = false, changed_b = false;
        mk_status st = refresh_map(wa->getCollisionShape(), &m_a, &changed_a);
        if (st == MK_OK) st = refresh_map(wb->getCollisionShape(), &m_b, &changed_b);
        if (changed_a) m_reach_a = core_reach(m_a.shape);
        if (changed_b) m_reach_b = core_reach(m_b.shape);
        if (changed_a || changed_b) m_cold = false;  // start_cold's flags depend on the shapes
        // Two hulls with polyhedral features meet as Bullet's own algorithm
        // has them meet: btConvexConvexAlgorithm then measures and clips the
        // margin-free cores (btPolyhedralContactClipping; its GJK distance is
        // corrected by both margins), so the pair rests with its cores
        // touching. Measured on the native convex stack's poses (960 Taru
        // hulls, margin 0.04): Bullet's depths are the cores', 0.080 shallower
        // than the rounded solids'.
        // (Copied only then: two shape copies per pair step cost 22 M
        // instructions per 300 steps of the 3000 boxes.)
        const bool hulls = polyhedral_hulls(wa->getCollisionShape(), wb->getCollisionShape());
        mk_shape cores[2];
        if (hulls) {
            cores[0] = m_a.shape;
            cores[1] = m_b.shape;
            cores[0].radius = cores[1].radius = 0;
        }
        const mk_shape &sa = hulls ? cores[0] : m_a.shape, &sb = hulls ? cores[1] : m_b.shape;
        // The cheap tests only for pairs without cached points: a pair that
        // touched last frame mostly still does (on the 1000 stack the tests
        // never succeed for them), and mk_collide answers one that parted.
        const bool boxes = sa.type == MK_SHAPE_BOX && sb.type == MK_SHAPE_BOX;
        const bool touched = m_manifold->getNumContacts() > 0;
        if (st == MK_OK && !touched &&
            ((boxes && stay_apart(sa, sb, ta, tb, threshold)) || apart(sa, m_reach_a, sb, m_reach_b, ta, tb, threshold))) {
            // Farther apart than the threshold: mk_collide would report no
            // point. What it leaves in the cache then (no preferred axis) is
            // a cold cache, and a pair that meets again starts cold.
            m_config->stats.skipped.fetch_add(1, std::memory_order_relaxed);
            start_cold();
        } else if (st == MK_OK && !touched && boxes && stay_separated(sa, sb, ta, tb)) {
            // Apart, within the threshold: no point either (the pair
            // reports touching points only). The cache keeps what the last
            // mk_collide left; it would only have renewed the kind of the
            // best axis, a preference for the frame the boxes meet again.
            m_config->stats.skipped.fetch_add(1, std::memory_order_relaxed);
        } else if (st == MK_OK) {
            // World poses, one per body per step (the configuration's cache):
            // Bullet's rotation matrices checked once, no quaternion on the
            // way. Minko subtracts the positions before anything else, so
            // large world coordinates cancel as in B's pose in A's frame.
            mk_pose scratch[2];
            const mk_pose *pa, *pb;
            st = m_config->world_poses(wa, m_a, wb, m_b, scratch, &pa, &pb);
            if (st == MK_OK && hulls) {
                st = write_candidates(result, sa, pa, sb, pb, threshold, flip);
                if (st == MK_OK) return;
            } else if (st == MK_OK) {
                // No reuse of the last manifold for a pose that did not move:
                // measured (300 steps, relative pose of the pair against its
                // previous mk_collide call), none is unchanged: 1000 stack 60
                // of 484,827 calls within 1e-6, 0 bit-identical transforms;
                // 3000 boxes 0 of 936,632. Resting Bullet boxes jitter more.
                m_cold = false;
                st = mk_collide_pose(&sa, pa, &sb, pb, threshold, &m_cache, &mf);
                if (st == MK_OK && boxes && mf.count == 0) {
                    apart_faces(sa, sb, ta, tb, threshold, &m_apart_face, touching_only(sa, sb) ? &m_separated_face : nullptr);
                }
            }
        }
        if (st != MK_OK) {
            m_config->stats.collide_errors++;
            mf.count = 0;
        }
        // Nothing to write and nothing cached to remove or refresh: the common
        // case of a pair whose boxes overlap while the shapes do not.
        if (mf.count == 0 && (!m_own || m_manifold->getNumContacts() == 0)) return;
        PairContact pts[MK_MANIFOLD_MAX_POINTS];
        int count = to_bullet(mf.normal, mf.points, mf.count, flip, pts);
        // A polyhedral hull on a box takes Minko's deepest point alone, as
        // Bullet's GJK path gives it one. Measured (demos/bullet_scenes
        // --scene convex_stack --trials 7, mean +- sd; native fell 122 +- 8.6,
        // drift 31.2 +- 2.9): Minko's four points 126 +- 9.2 fell, drift
        // 35.2 +- 3.3 ('worse'); the deepest alone 132 +- 12, 31 +- 4 (both
        // noise); max_pen 0.434 +- 0.041 (noise; native 0.403). The 20
        // random hulls' max_pen goes from 0.080 ('better') to 0.103 +- 0.013
        // (native's, noise).
        if ((m_a.shape.type == MK_SHAPE_HULL || m_b.shape.type == MK_SHAPE_HULL) &&
            hull_on_box(wa->getCollisionShape(), wb->getCollisionShape())) {
            deepest_last(pts, count);
            add_contacts(result, count ? &pts[count - 1] : pts, count ? 1 : 0, m_own);
            if (m_own) result->refreshContactPoints();
            return;
        }
        // (A polyhedral hull pair lands here only after an error: no points,
        // and Bullet's own refresh and matching for what its manifold holds.)
        const bool all_fresh = write_contacts(result, pts, count, m_own && !hulls);
        if (m_own) refresh_contacts(result, all_fresh);
    }

    btScalar calculateTimeOfImpact(btCollisionObject *, btCollisionObject *, const btDispatcherInfo &,
                                   btManifoldResult *) override
    {
        return 1;  // never called by btDiscreteDynamicsWorld (no DISPATCH_CONTINUOUS)
    }

    void getAllContactManifolds(btManifoldArray &manifolds) override
    {
        if (m_manifold && m_own) manifolds.push_back(m_manifold);
    }

private:
    // Two boxes that mk_collide last found more than the threshold apart
    // along a face axis (m_apart_face): still so? Then nothing else is
    // needed this frame (no point, a cold cache). Boxes side by side in a
    // stack stay apart this way frame after frame: on the 1000 stack (300
    // steps) 316k of 821k pair steps end here instead of in world_poses
    // and mk_collide, at some 40 instructions each.
    bool stay_apart(const mk_shape &sa, const mk_shape &sb, const btTransform &ta, const btTransform &tb, btScalar threshold)
    {
        if (m_apart_face < 0) return false;
        if (face_separation(m_apart_face, sa.u.half_extents, sb.u.half_extents, sa.radius + sb.radius, ta, tb) > threshold)
            return true;
        m_apart_face = -1;
        return false;
    }

    // Sharp boxes whose cache asks for touching points only: mk_collide
    // reports nothing for them once any axis separates them.
    bool touching_only(const mk_shape &sa, const mk_shape &sb) const
    {
        return (m_cache.flags & MK_MANIFOLD_TOUCHING_ONLY) && sa.radius == 0 && sb.radius == 0;
    }

    // Two such boxes that the last mk_collide found apart by less than the
    // threshold, separated along a face axis (m_separated_face): still so?
    // Then mk_collide would report no point either. On the 1000 stack (300
    // steps) 115k of 485k mk_collide calls end here instead (boxes side by
    // side in the pyramid and the walls, a hair apart).
    bool stay_separated(const mk_shape &sa, const mk_shape &sb, const btTransform &ta, const btTransform &tb)
    {
        if (m_separated_face < 0) return false;
        if (touching_only(sa, sb) && face_separation(m_separated_face, sa.u.half_extents, sb.u.half_extents, 0, ta, tb) > 0)
            return true;
        m_separated_face = -1;
        return false;
    }

    // A zeroed cache is a cold start (minko/manifold.h). Bullet matches a
    // point whose features changed by its position (contact_writer.h), so
    // Bullet's pairs take the minimum-penetration face every frame rather
    // than the face kind held for ID-only hosts: the held face tilts a
    // rocking stack's normal by the boxes' relative tilt.
    // (Once: a pair skipped as apart frame after frame keeps its cold cache,
    // which only mk_collide or a changed shape make warm or stale; zeroing
    // it again every frame cost 36 M instructions per 300 steps of the
    // 3000 boxes.)
    void start_cold()
    {
        if (m_cold) return;
        m_cold = true;
        m_cache = mk_manifold_cache();
        m_cache.mode = MK_MANIFOLD_BEST_FACE;
        // Box-box pairs report touching points only, as Bullet's own
        // btBoxBoxDetector does. Measured (demos/bullet_scenes --scene tower
        // --trials 7): with speculative box points the 10-box tower drifts
        // 0.73 m (KE 0.039 J), native 0.37 m (0.011 J); without them 0.27 m
        // (0.0061 J). Dropped for every pair, the 20 random hulls drift
        // 0.048 m instead of 0.0006 m, so other pairs keep theirs. Asked of
        // mk_collide by this flag rather than by a zero margin, which also
        // restarts the pair cold whenever two boxes part by a hair (measured
        // that way the tower penetrates 0.027 m instead of 0.010 m); with
        // the flag, boxes apart by less than the threshold skip the clip and
        // the GJK distance of points that would be dropped (1000 stack,
        // callgrind, 300 steps: collision phase 2714 -> 2373 M, native 2495).
        if (m_a.shape.type == MK_SHAPE_BOX && m_b.shape.type == MK_SHAPE_BOX) m_cache.flags = MK_MANIFOLD_TOUCHING_ONLY;
    }

    // Two polyhedral hulls: every candidate Minko clipped, not its four,
    // through Bullet's own addContactPoint, deepest last, the way Bullet's
    // hull-hull algorithm (btPolyhedralContactClipping) fills its manifold,
    // which then keeps four by its own rule (contact_writer.h, add_contacts).
    // Measured (demos/bullet_scenes --scene convex_stack --trials 7, 960
    // Taru hulls, mean +- sd; native 122 +- 8.6 fell, drift 31.2, ke_end
    // 471): Minko's four points, deepest last, 192 +- 5.3 fell, drift 42.2,
    // ke_end 928; every candidate, deepest last, 135 +- 11, 34.4, 462 (drift
    // and ke_end within noise). Tried and left out: impulses handed back by
    // feature key to points the area rule evicted and re-added (185 +- 15:
    // the churn's cold restarts damp the pile as in Bullet); one point only
    // while the cores are apart, as Bullet's GJK path (133 +- 12, noise
    // against this); that point first, then the clip order (154 +- 9.9).
    // Out of line: the candidates' buffers (some 12 kB in double) stay off
    // the frame every other pair runs in.
    __attribute__((noinline)) mk_status write_candidates(btManifoldResult *result, const mk_shape &sa, const mk_pose *pa,
                                                         const mk_shape &sb, const mk_pose *pb, btScalar threshold, bool flip)
    {
        mk_contact_point cand[MK_COLLIDE_MAX_CANDIDATES];
        PairContact pts[MK_COLLIDE_MAX_CANDIDATES];
        mk_vec3 normal;
        int count = 0;
        m_cold = false;
        const mk_status st = mk_collide_pose_points(&sa, pa, &sb, pb, threshold, &m_cache, &normal, cand,
                                                    MK_COLLIDE_MAX_CANDIDATES, &count);
        if (st != MK_OK) return st;
        if (count == 0 && (!m_own || m_manifold->getNumContacts() == 0)) return MK_OK;
        count = to_bullet(normal, cand, count, flip, pts);
        deepest_last(pts, count);
        add_contacts(result, pts, count, m_own);
        if (m_own) result->refreshContactPoints();
        return MK_OK;
    }

    btPersistentManifold *m_manifold;
    bool m_own;
    const btCollisionShape *m_shape0;
    CollisionConfiguration *m_config;
    ShapeMap m_a, m_b;  // hulls point into the configuration's cache
    btScalar m_reach_a, m_reach_b;  // core_reach of m_a, m_b
    int m_apart_face = -1;          // two boxes: face axis that kept them apart (face_separation), or -1
    int m_separated_face = -1;      // ...that separated them by less than the threshold (stay_separated), or -1
    mk_manifold_cache m_cache;
    bool m_cold = false;  // m_cache is as start_cold() left it
};

btDefaultCollisionConstructionInfo with_room_for_minko(btDefaultCollisionConstructionInfo info)
{
    // Bullet's pool only asserts on block size: an algorithm larger than the
    // pool's blocks silently overruns in a release build.
    if (info.m_customCollisionAlgorithmMaxElementSize < (int)sizeof(Algorithm))
        info.m_customCollisionAlgorithmMaxElementSize = (int)sizeof(Algorithm);
    return info;
}

}  // namespace

bool minko_shape_type(int type)
{
    for (int t : kMinkoTypes)
        if (t == type) return true;
    return false;
}

// Picks, per pair, Minko's algorithm or Bullet's own.
struct CollisionConfiguration::CreateFunc : public btCollisionAlgorithmCreateFunc {
    CollisionConfiguration *config;
    explicit CreateFunc(CollisionConfiguration *c) : config(c) {}
    btCollisionAlgorithm *CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo &ci,
                                                   const btCollisionObjectWrapper *w0,
                                                   const btCollisionObjectWrapper *w1) override
    {
        ShapeMap a, b;
        if (config->map_shape(w0->getCollisionShape(), &a) == MK_OK &&
            config->map_shape(w1->getCollisionShape(), &b) == MK_OK && minko_handles(a, b)) {
            config->stats.minko_algorithms++;
            void *mem = ci.m_dispatcher1->allocateCollisionAlgorithm(sizeof(Algorithm));
            return new (mem) Algorithm(ci, w0, w1, config, a, b);
        }
        config->stats.native_fallbacks++;
        btCollisionAlgorithmCreateFunc *native =
            config->native_create_func(w0->getCollisionShape()->getShapeType(), w1->getCollisionShape()->getShapeType());
        return native->CreateCollisionAlgorithm(ci, w0, w1);
    }
};

CollisionConfiguration::CollisionConfiguration(Backend narrowphase, const btDefaultCollisionConstructionInfo &info)
    : btDefaultCollisionConfiguration(with_room_for_minko(info)), m_backend(narrowphase)
{
    void *mem = btAlignedAlloc(sizeof(CreateFunc), 16);
    m_create = new (mem) CreateFunc(this);
}

CollisionConfiguration::~CollisionConfiguration()
{
    m_create->~CreateFunc();
    btAlignedFree(m_create);
    for (auto &kv : m_hulls) mk_hull_destroy(kv.second.hull);
    for (mk_hull *h : m_retired) mk_hull_destroy(h);
}

btCollisionAlgorithmCreateFunc *CollisionConfiguration::getCollisionAlgorithmCreateFunc(int t0, int t1)
{
    if (m_backend == Backend::minko && minko_shape_type(t0) && minko_shape_type(t1) &&
        !(t0 == STATIC_PLANE_PROXYTYPE && t1 == STATIC_PLANE_PROXYTYPE))
        return m_create;
    return native_create_func(t0, t1);
}

namespace {

// What a cached hull was built from: point count, scaling and every
// coordinate (FNV-1a over the scaled points' bytes).
unsigned long long hull_fingerprint(const btConvexHullShape *h)
{
    unsigned long long f = 1469598103934665603ull;
    auto mix = [&f](const void *p, size_t n) {
        const unsigned char *b = static_cast<const unsigned char *>(p);
        for (size_t i = 0; i < n; i++) f = (f ^ b[i]) * 1099511628211ull;
    };
    const int n = h->getNumPoints();
    mix(&n, sizeof n);
    for (int i = 0; i < n; i++) {
        const btVector3 p = h->getScaledPoint(i);
        const btScalar xyz[3] = {p.x(), p.y(), p.z()};
        mix(xyz, sizeof xyz);
    }
    return f;
}

}  // namespace

mk_status CollisionConfiguration::map_shape(const btCollisionShape *shape, ShapeMap *out)
{
    if (!shape || !out) return MK_ERR_NULL;
    if (shape->getShapeType() != CONVEX_HULL_SHAPE_PROXYTYPE) return map_primitive(shape, out);
    const btConvexHullShape *h = static_cast<const btConvexHullShape *>(shape);
    const unsigned long long f = hull_fingerprint(h);
    mk_hull *hull = nullptr;
    {
        std::lock_guard<std::mutex> lock(m_hull_lock);
        auto it = m_hulls.find(shape);
        if (it != m_hulls.end() && it->second.fingerprint == f) {
            hull = it->second.hull;
        } else {
            std::vector<mk_vec3> pts((size_t)h->getNumPoints());
            for (int i = 0; i < h->getNumPoints(); i++) pts[(size_t)i] = to_mk(h->getScaledPoint(i));
            mk_status st = mk_hull_create(pts.data(), (int)pts.size(), nullptr, &hull);
            if (st != MK_OK) return st;
            if (it != m_hulls.end()) {
                m_retired.push_back(it->second.hull);
                it->second.hull = hull;
                it->second.fingerprint = f;
            } else {
                m_hulls[shape] = HullEntry{hull, f};
            }
        }
    }
    ShapeMap m;
    m.axis = mk_quat_identity();
    mk_status st = mk_shape_hull(hull, shape->getMargin(), &m.shape);
    if (st == MK_OK) *out = m;
    return st;
}

int CollisionConfiguration::hull_count() const
{
    std::lock_guard<std::mutex> lock(m_hull_lock);
    return (int)m_hulls.size();
}

namespace {

// Whether this build's mk_collide is exact for rounded polytopes (a hull
// grown by Bullet's margin) whose cores are apart but within the rounding:
// the usual resting contact of Bullet hulls. Probe: two unit-cube hulls
// rounded by 0.04 whose cores are 0.05 apart along x and y, so their
// nearest features are two parallel edges sqrt(0.05^2 + 0.05^2) apart and the
// rounded solids overlap by 0.08 - that. A build whose mk_collide gets this
// wrong (before 18c7092 it took the SAT separation along a face axis as the
// core distance, overstating such depths by up to 0.015 on Bullet-sized
// hulls) leaves rounded hull pairs on Bullet's own algorithms.
bool rounded_polytopes_exact()
{
    static const bool exact = [] {
        mk_vec3 cube[8];
        for (int i = 0; i < 8; i++) cube[i] = mk_v3(i & 1 ? 0.5 : -0.5, i & 2 ? 0.5 : -0.5, i & 4 ? 0.5 : -0.5);
        mk_hull *h = nullptr;
        if (mk_hull_create(cube, 8, nullptr, &h) != MK_OK) return false;
        mk_shape s;
        mk_manifold m;
        const mk_transform b = mk_transform_make(mk_v3(1.05, 1.05, 0), mk_quat_identity());
        bool ok = mk_shape_hull(h, (mk_real)0.04, &s) == MK_OK &&
                  mk_collide(&s, mk_transform_identity(), &s, b, 0, nullptr, &m) == MK_OK && m.count > 0;
        if (ok) {
            const double want = 0.08 - std::sqrt(0.05 * 0.05 + 0.05 * 0.05);
            double got = 0;
            for (int i = 0; i < m.count; i++) got = std::max(got, (double)m.points[i].depth);
            ok = std::fabs(got - want) <= 1e-4 * want;
        }
        mk_hull_destroy(h);
        return ok;
    }();
    return exact;
}

}  // namespace

// mk_collide answers every pair it supports, or MK_ERR_UNSUPPORTED for pairs
// whose module this build lacks. That depends on the two types alone: ask it
// once per type pair, on touching unit poses, and remember (a probe costs as
// much as a deep contact; pairs are created by the thousand in a pile).
bool CollisionConfiguration::minko_handles(const ShapeMap &a, const ShapeMap &b)
{
    const bool rounded_hull = (a.shape.type == MK_SHAPE_HULL && a.shape.radius > 0) ||
                              (b.shape.type == MK_SHAPE_HULL && b.shape.radius > 0);
    if (rounded_hull && !rounded_polytopes_exact()) return false;
    // 0: not known yet, 1: yes, 2: no. Racing threads store the same answer.
    static std::atomic<signed char> known[MK_SHAPE_TYPE_COUNT][MK_SHAPE_TYPE_COUNT];
    std::atomic<signed char> &k = known[a.shape.type][b.shape.type];
    const signed char seen = k.load(std::memory_order_relaxed);
    if (seen) return seen == 1;
    mk_manifold m;
    const mk_transform id = mk_transform_identity();
    const mk_status st = mk_collide(&a.shape, id, &b.shape, id, 0, nullptr, &m);
    // Any other refusal is about these shapes, not the types: not remembered.
    if (st == MK_OK || st == MK_ERR_UNSUPPORTED) k.store(st == MK_OK ? 1 : 2, std::memory_order_relaxed);
    return st == MK_OK;
}

namespace {

// Whether a pose was made from world transform t and axis rotation q, bit
// for bit: the origin first, where a moving body differs. Compared as bytes
// (inlined word compares): on 3000 boxes (callgrind, 300 steps) world_poses
// fell from 370 to 315 instructions per pair against twelve scalar compares.
// Any change, down to one ulp (or -0 for +0), makes a new pose, and a NaN
// transform keeps its cached error status.
inline bool made_from(const btScalar *from, const mk_quat &axis, const btTransform &t, const mk_quat &q)
{
    const size_t row = 3 * sizeof(btScalar);
    return std::memcmp(from, &t.getOrigin().x(), row) == 0 && std::memcmp(from + 3, &t.getBasis()[0].x(), row) == 0 &&
           std::memcmp(from + 6, &t.getBasis()[1].x(), row) == 0 && std::memcmp(from + 9, &t.getBasis()[2].x(), row) == 0 &&
           std::memcmp(&axis, &q, sizeof q) == 0;
}

void keep_source(btScalar *from, const btTransform &t)
{
    const btVector3 &o = t.getOrigin();
    from[0] = o.x();
    from[1] = o.y();
    from[2] = o.z();
    for (int i = 0; i < 3; i++) {
        const btVector3 &row = t.getBasis()[i];
        from[3 + 3 * i] = row.x();
        from[4 + 3 * i] = row.y();
        from[5 + 3 * i] = row.z();
    }
}

}  // namespace

mk_status CollisionConfiguration::world_poses(const btCollisionObjectWrapper *wa, const ShapeMap &ma,
                                              const btCollisionObjectWrapper *wb, const ShapeMap &mb, mk_pose scratch[2],
                                              const mk_pose **pa, const mk_pose **pb)
{
    if (btThreadsAreRunning()) {
        *pa = &scratch[0];
        *pb = &scratch[1];
        mk_status st = minko_pose(wa->getWorldTransform(), ma, &scratch[0]);
        return st == MK_OK ? minko_pose(wb->getWorldTransform(), mb, &scratch[1]) : st;
    }
    // Room for both objects first: growing the array moves its entries.
    const int top = std::max(wa->getCollisionObject()->getWorldArrayIndex(), wb->getCollisionObject()->getWorldArrayIndex());
    if (top >= m_poses.size()) {
        if (top >= m_poses.capacity()) m_poses.reserve(std::max(top + 1, 2 * m_poses.capacity()));
        m_poses.resize(top + 1, PoseEntry());
    }
    const mk_status st = pose_of(wa, ma, &scratch[0], pa);
    return st == MK_OK ? pose_of(wb, mb, &scratch[1], pb) : st;
}

// One object's pose: inline, the lookup of an unchanged transform (its
// index, two pointer compares and the bytes of its transform); out of line,
// the remaking. (Session 11 inlined one loop body for both objects, each
// with the remaking in it: 306 instructions per pair on the 3000 boxes.)
inline mk_status CollisionConfiguration::pose_of(const btCollisionObjectWrapper *w, const ShapeMap &map, mk_pose *scratch,
                                                 const mk_pose **out)
{
    const btCollisionObject *object = w->getCollisionObject();
    const btTransform &t = w->getWorldTransform();
    const int i = object->getWorldArrayIndex();
    if (&t != &object->getWorldTransform() || i < 0) {  // a compound's child, or outside a world
        *out = scratch;
        return minko_pose(t, map, scratch);
    }
    PoseEntry &e = m_poses[i];
    *out = &e.pose;
    if (e.object == object && made_from(e.from, e.axis, t, map.axis)) return e.status;
    return remake_pose(e, object, t, map);
}

__attribute__((noinline)) mk_status CollisionConfiguration::remake_pose(PoseEntry &e, const btCollisionObject *object,
                                                                        const btTransform &t, const ShapeMap &map)
{
    e.object = object;
    keep_source(e.from, t);
    e.axis = map.axis;
    e.status = minko_pose(t, map, &e.pose);
    return e.status;
}

bool set_narrowphase(btCollisionWorld *world, Backend b)
{
    btCollisionDispatcher *d = dynamic_cast<btCollisionDispatcher *>(world->getDispatcher());
    if (!d) return false;
    CollisionConfiguration *config = dynamic_cast<CollisionConfiguration *>(d->getCollisionConfiguration());
    if (!config) return false;
    config->set_backend(b);
    for (int t0 : kMinkoTypes)
        for (int t1 : kMinkoTypes) d->registerCollisionCreateFunc(t0, t1, config->getCollisionAlgorithmCreateFunc(t0, t1));
    // Pairs keep the algorithm they were created with: drop them all.
    struct Clean : btOverlapCallback {
        btDispatcher *dispatcher;
        btOverlappingPairCache *cache;
        bool processOverlap(btBroadphasePair &pair) override
        {
            cache->cleanOverlappingPair(pair, dispatcher);
            return false;
        }
    } clean;
    clean.dispatcher = d;
    clean.cache = world->getPairCache();
    world->getPairCache()->processAllOverlappingPairs(&clean, d);
    return true;
}

}  // namespace mkb

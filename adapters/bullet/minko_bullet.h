// minko_bullet.h: Minko as the collision backend of Bullet 3.24 (C++11).
//
// Contract. libminko_bullet is built against the Bullet variant whose btScalar
// matches Minko's mk_real (bullet-float64 with the double library, bullet with
// PRECISION=single); a mismatched build does not compile. Bullet shapes map
// onto Minko shapes exactly, the way Bullet's own support functions define
// them: a btBoxShape is the sharp box of its half extents (the margin is inside
// them), a btConvexHullShape, btCylinderShape or btConeShape is its margin-free
// core grown by the collision margin (Minko's rounding radius; but two hulls
// that both have polyhedral features meet as their margin-free cores, as in
// Bullet's own hull-hull clipping), spheres and
// capsules are their radius around a point or segment; capsule, cylinder and
// cone axes (X, Y or Z) are carried by a fixed rotation from Minko's local z.
// Shapes Minko does not model (meshes, compounds, ...) are refused with
// MK_ERR_UNSUPPORTED, and the adapters then leave those pairs to Bullet.
#ifndef MINKO_BULLET_H
#define MINKO_BULLET_H

#include <btBulletCollisionCommon.h>
#include <BulletDynamics/Dynamics/btDiscreteDynamicsWorld.h>

#include <atomic>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "minko/broadphase.h"
#include "minko/manifold.h"
#include "minko/shape.h"
#include "minko/toi.h"

static_assert(sizeof(btScalar) == sizeof(mk_real),
              "minko_bullet: Bullet's btScalar and Minko's mk_real differ; build double Minko with "
              "bullet-float64 (BT_USE_DOUBLE_PRECISION) and PRECISION=single with bullet");

namespace mkb {

// Which collision code a world runs: Bullet's own or Minko's.
enum class Backend { native, minko };

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
// built once per shape (see the collision configuration's hull cache); a hull
// shape's margin is read by refresh_map().
// MK_ERR_UNSUPPORTED for other types; Minko's own status for sizes Minko
// refuses (e.g. a box with a zero extent).
mk_status map_primitive(const btCollisionShape *shape, ShapeMap *out);

namespace detail {
mk_status refresh_changed(const btCollisionShape *shape, ShapeMap *map, bool *changed);
}

// Brings a mapping made earlier up to date with its shape (a primitive is
// mapped again, a hull keeps its Minko hull and takes the current margin);
// *changed (when given) tells whether the mapping changed. Inline for the
// case of every pair of a box pile, an unchanged box: its half extents and
// margin against the mapped ones (as Bullet's getHalfExtentsWithMargin()
// adds them), one virtual call.
inline mk_status refresh_map(const btCollisionShape *shape, ShapeMap *map, bool *changed = nullptr)
{
    if (shape->getShapeType() == BOX_SHAPE_PROXYTYPE && map->shape.type == MK_SHAPE_BOX) {
        const btScalar margin = shape->getMargin();
        const btVector3 &core = static_cast<const btBoxShape *>(shape)->getHalfExtentsWithoutMargin();
        const mk_vec3 &h = map->shape.u.half_extents;
        if (core.x() + margin == h.x && core.y() + margin == h.y && core.z() + margin == h.z) {
            if (changed) *changed = false;
            return MK_OK;
        }
    }
    return detail::refresh_changed(shape, map, changed);
}

// World pose of the mapped shape for a Bullet world transform.
mk_transform minko_pose(const btTransform &world, const ShapeMap &map);
// The same as a checked pose made from Bullet's rotation matrix (no
// quaternion): MK_ERR_BAD_ROTATION, MK_ERR_NOT_FINITE or MK_ERR_OUT_OF_RANGE
// as mk_pose_from_matrix.
mk_status minko_pose(const btTransform &world, const ShapeMap &map, mk_pose *out);

// A btBroadphaseInterface on a Minko broadphase (minko/broadphase.h: SAP by
// default, hierarchical grid, or the automatic choice). Bullet's own
// btHashedOverlappingPairCache stays the pair store, so each pair's collision
// algorithm and manifold live where Bullet expects them; Minko's added and
// removed pair events are applied to it once per step in
// calculateOverlappingPairs(). Behaves as btDbvtBroadphase does where Bullet
// can tell: proxy uids count from 1 in creation order (resetPool() restarts
// them when empty), destroyProxy() removes the proxy's pairs first, every new
// pair goes through the cache's needsBroadphaseCollision (group/mask AND, or
// the user's btOverlapFilterCallback) once, when it starts to overlap, and
// static-filtered proxies (group StaticFilter only, mask without it, as
// btDiscreteDynamicsWorld gives static and kinematic bodies) cost Minko nothing
// against each other unless a filter callback is installed. Minko holds fat
// boxes, as Dbvt's leaves are: a proxy is filed as Bullet's AABB grown by
// `margin` on every side (default gDbvtMargin, Dbvt's 0.05 world units) and
// filed again only when an AABB set later leaves the filed box: grown by the
// margin again if its AABB's lower corner moved less than the margin since
// the previous setAabb(), else tight (a fast body leaves any fat box at its next move; the
// margin would only give it pairs). A body that rests or jitters inside its
// filed box costs O(1) in setAabb(), and a step in which no proxy was filed,
// created or destroyed costs nothing in calculateOverlappingPairs(). The pair set is
// exactly the set of overlapping filed boxes (brute force on filed_aabb()),
// a superset of the touching AABBs' pairs, as Dbvt's is (without Dbvt's
// lazily removed stale pairs; with margin 0, a box that shrank keeps its
// larger filed box, as a Dbvt leaf does). getAabb() gives
// Bullet's AABB. rayTest() and aabbTest() use Minko's queries and answer for
// Bullet's AABBs, not the filed ones; they are reentrant and see AABBs set
// since the last step too; rayTest() grows every proxy by the cast shape's
// box as Dbvt does. Huge AABBs (btStaticPlaneShape) are ordinary proxies. A
// NaN AABB is refused and the proxy keeps its last good box (last_error()
// tells). Memory: one Minko broadphase whose proxy capacity doubles, by
// rebuilding it, when Bullet adds more proxies than it holds.
class Broadphase : public btBroadphaseInterface {
public:
    // `kind`: Minko's structure, incremental SAP by default: bodies that
    // Bullet integrates move coherently, SAP's case (btAxisSweep3's), and
    // SAP still rebuilds by itself when they stop doing so (teleports).
    // MK_BP_AUTO's cost model picked the grid for 225 of 290 updates of the
    // 3000 boxes (callgrind, 300 steps: mk_bp_update 2229 M against 898 M
    // for SAP alone), and no Bullet scene of demos/bullet_scenes ran faster
    // with it (200 steps, wall: prim pile 0.385 against 0.263 ms per step in
    // the broadphase, the others equal).
    // `cache`: a pair cache to use (not owned, not deferred-removal), or
    // nullptr for an owned btHashedOverlappingPairCache whose deterministic
    // dispatch (m_deterministicOverlappingPairs) visits the pairs in Bullet's
    // order without Bullet's quicksort per step: the last order is reused
    // while the pairs stay put, else a radix sort rebuilds it.
    // `margin`: how far a filed box reaches past Bullet's AABB (a NaN,
    // infinite or negative margin is 0).
    explicit Broadphase(mk_bp_kind kind = MK_BP_SAP, btHashedOverlappingPairCache *cache = nullptr,
                        int initial_capacity = 1024, btScalar margin = gDbvtMargin);
    ~Broadphase() override;
    Broadphase(const Broadphase &) = delete;
    Broadphase &operator=(const Broadphase &) = delete;

    btBroadphaseProxy *createProxy(const btVector3 &aabbMin, const btVector3 &aabbMax, int shapeType, void *userPtr,
                                   int collisionFilterGroup, int collisionFilterMask, btDispatcher *dispatcher) override;
    void destroyProxy(btBroadphaseProxy *proxy, btDispatcher *dispatcher) override;
    void setAabb(btBroadphaseProxy *proxy, const btVector3 &aabbMin, const btVector3 &aabbMax,
                 btDispatcher *dispatcher) override;
    void getAabb(btBroadphaseProxy *proxy, btVector3 &aabbMin, btVector3 &aabbMax) const override;
    void rayTest(const btVector3 &rayFrom, const btVector3 &rayTo, btBroadphaseRayCallback &rayCallback,
                 const btVector3 &aabbMin = btVector3(0, 0, 0), const btVector3 &aabbMax = btVector3(0, 0, 0)) override;
    void aabbTest(const btVector3 &aabbMin, const btVector3 &aabbMax, btBroadphaseAabbCallback &callback) override;
    void calculateOverlappingPairs(btDispatcher *dispatcher) override;
    btOverlappingPairCache *getOverlappingPairCache() override { return m_cache; }
    const btOverlappingPairCache *getOverlappingPairCache() const override { return m_cache; }
    void getBroadphaseAabb(btVector3 &aabbMin, btVector3 &aabbMax) const override;
    void resetPool(btDispatcher *dispatcher) override;
    void printStats() override;

    // The box Minko holds for a proxy of this broadphase (see above).
    void filed_aabb(const btBroadphaseProxy *proxy, btVector3 &aabbMin, btVector3 &aabbMax) const;
    btScalar margin() const { return m_margin; }
    // The first error Minko reported since the last call (MK_OK if none).
    mk_status take_error();
    const mk_bp *minko() const { return m_bp; }

    struct Proxy;

private:
    mk_status rebuild(int capacity);
    void reconcile(btDispatcher *dispatcher);
    void note(mk_status st)
    {
        if (m_error == MK_OK) m_error = st;
    }
    bool may_be_minko_static(int group, int mask) const;
    void fatten(const btVector3 &lo, const btVector3 &hi, btVector3 &fat_lo, btVector3 &fat_hi) const;
    bool slow(const Proxy *p, const btVector3 &lo) const;

    mk_bp *m_bp = nullptr;
    mk_bp_kind m_kind;
    int m_capacity;
    btScalar m_margin;
    btHashedOverlappingPairCache *m_cache;
    bool m_own_cache;
    std::vector<Proxy *> m_proxies;  // live proxies, any order
    std::vector<Proxy *> m_dirty;    // created or moved since the last update
    int m_uid = 0;
    int m_frame = 0;
    bool m_reconcile = false;        // next update: full mark-and-sweep instead of events
    bool m_destroyed = false;        // a proxy destroyed since the last update
    const btOverlapFilterCallback *m_filter_seen = nullptr;
    mk_status m_error = MK_OK;
};

// A btDefaultCollisionConfiguration whose dispatcher runs Minko's contact
// manifolds (mk_collide) for every pair of sphere, box, capsule X/Y/Z,
// cylinder X/Y/Z, cone X/Y/Z, convex hull and static plane (both orders;
// plane-plane excluded) and Bullet's own algorithms for everything else
// (meshes, compounds, soft bodies) and for any pair this build of Minko
// refuses (a module left out, a shape Minko rejects): the choice is made per
// pair when its algorithm is created. Each Minko algorithm writes the whole
// manifold every step in Bullet's conventions (normal on B pointing from B to
// A, point on B, negative distance = penetration, points up to the manifold's
// contact breaking threshold apart kept as speculative contacts, except for
// box-box pairs, which report touching points only, as Bullet's
// btBoxBoxDetector does), runs mk_collide in MK_MANIFOLD_BEST_FACE mode (the
// minimum-penetration face every frame, as Bullet's own algorithms report)
// and matches
// points to the cached ones by Minko feature ID (two hulls with polyhedral
// features: through Bullet's addContactPoint, by position, as Bullet's own
// hull-hull algorithm does; measured better on the convex stack), so
// m_appliedImpulse follows
// its contact (a point whose features changed in place is matched by
// position, as Bullet matches; points not reported stay until Bullet's
// refreshContactPoints drops them: contact_writer.h). Hull shapes are converted once per shape and
// cached here, keyed by the shape (a btConvexHullShape must not change its
// points while this configuration uses it, as with Bullet's polyhedral
// features). m_customCollisionAlgorithmMaxElementSize is raised to fit the
// Minko algorithm. Closest-point queries (contactTest) stay Bullet's.
// Backend::native makes this exactly btDefaultCollisionConfiguration;
// set_narrowphase() switches a running world.
class CollisionConfiguration : public btDefaultCollisionConfiguration {
public:
    explicit CollisionConfiguration(Backend narrowphase = Backend::minko,
                                    const btDefaultCollisionConstructionInfo &info = btDefaultCollisionConstructionInfo());
    ~CollisionConfiguration() override;
    CollisionConfiguration(const CollisionConfiguration &) = delete;
    CollisionConfiguration &operator=(const CollisionConfiguration &) = delete;

    btCollisionAlgorithmCreateFunc *getCollisionAlgorithmCreateFunc(int proxyType0, int proxyType1) override;

    Backend narrowphase() const { return m_backend; }
    // Takes effect for dispatchers built afterwards; see set_narrowphase() for a running world.
    void set_backend(Backend b) { m_backend = b; }
    // Shapes of the types above, hulls through the cache (built on first use,
    // checked against the shape's points, scaling and count). MK_ERR_UNSUPPORTED
    // otherwise. Thread-safe.
    mk_status map_shape(const btCollisionShape *shape, ShapeMap *out);
    // Minko hulls built so far (cache size).
    int hull_count() const;
    // Bullet's own create function for a pair of shape types.
    btCollisionAlgorithmCreateFunc *native_create_func(int proxyType0, int proxyType1)
    {
        return btDefaultCollisionConfiguration::getCollisionAlgorithmCreateFunc(proxyType0, proxyType1);
    }
    // Whether mk_collide handles this pair of mapped shapes in this build.
    static bool minko_handles(const ShapeMap &a, const ShapeMap &b);
    // The checked world poses of a pair's two mapped shapes (minko_pose),
    // each made once per collision object and transform and shared by all
    // the object's pairs: a per-object cache indexed by the object's world
    // array index, kept while the object, its world transform and the
    // shape's axis rotation stay the same (compared on every call, so a body
    // moved by the user between steps is seen at once). A compound's child
    // (its own transform), an object outside a world, and pairs dispatched
    // concurrently (btCollisionDispatcherMt: btThreadsAreRunning()) get
    // fresh poses in `scratch`. *pa and *pb are valid until the next call.
    // Memory: one entry per world array index seen.
    mk_status world_poses(const btCollisionObjectWrapper *wa, const ShapeMap &ma, const btCollisionObjectWrapper *wb,
                          const ShapeMap &mb, mk_pose scratch[2], const mk_pose **pa, const mk_pose **pb);

    struct Stats {
        std::atomic<long> minko_algorithms{0};  // pair algorithms created on Minko
        std::atomic<long> native_fallbacks{0};  // pairs of Minko-registered types left to Bullet
        std::atomic<long> collide_errors{0};    // mk_collide calls that failed (no contacts that step)
        std::atomic<long> skipped{0};           // pair steps found farther apart than the threshold without mk_collide
    };
    Stats stats;

private:
    struct CreateFunc;
    struct HullEntry {
        mk_hull *hull;
        unsigned long long fingerprint;
    };
    struct PoseEntry {
        const btCollisionObject *object;  // nullptr: never made
        btScalar from[12];                // the world transform it was made from: origin, then basis rows
        mk_quat axis;
        mk_status status;
        mk_pose pose;
    };
    mk_status pose_of(const btCollisionObjectWrapper *w, const ShapeMap &map, mk_pose *scratch, const mk_pose **out);
    mk_status remake_pose(PoseEntry &e, const btCollisionObject *object, const btTransform &t, const ShapeMap &map);
    Backend m_backend;
    CreateFunc *m_create;
    btAlignedObjectArray<PoseEntry> m_poses;  // by btCollisionObject::getWorldArrayIndex()
    mutable std::mutex m_hull_lock;
    std::unordered_map<const btCollisionShape *, HullEntry> m_hulls;
    // Hulls replaced because their shape changed (or its address was reused):
    // algorithms created before may still point at them, so they live on.
    std::vector<mk_hull *> m_retired;
};

// True for the shape types the Minko narrowphase is registered for.
bool minko_shape_type(int proxyType);

// Switch a running world's narrowphase: re-registers the dispatcher's create
// functions for Minko's shape types and drops every pair's algorithm (their
// manifolds and warm-start state go with them), so the next step builds new
// ones. The world's dispatcher must be a btCollisionDispatcher built on an
// mkb::CollisionConfiguration; returns false otherwise.
bool set_narrowphase(btCollisionWorld *world, Backend b);

// Switch a running world's broadphase: every collision object's proxy moves
// to `replacement` (same group and mask, uids from the new broadphase) and the
// world uses it from now on; pairs, their algorithms and warm-start state are
// dropped and rebuilt at the next step. Returns the previous broadphase, which
// the caller now owns (the world never owned it).
btBroadphaseInterface *set_broadphase(btCollisionWorld *world, btBroadphaseInterface *replacement);

// A btDiscreteDynamicsWorld whose continuous collision runs on Minko's time
// of impact (minko/toi.h). Which bodies get it is Bullet's rule, with the
// motion measured where it is largest: setCcdMotionThreshold() > 0 and a step
// that moves the centre, plus the turn times the bounding radius, farther
// than that (Bullet looks at the centre only, so a fast spinner never gets
// CCD). Bullet sweeps a sphere of setCcdSweptSphereRadius() (a stand-in for
// the shape, rotation ignored) against the world; here the body's own shape,
// turning as it does over the step, is swept against every shape its swept
// box touches (others held at their pose, as Bullet does), and the first
// contact is exact to the TOI tolerance. Both of Bullet's hooks are replaced:
// integrateTransforms() clamps the motion to the time of impact and
// createPredictiveContacts() adds the speculative contact between the two
// features that meet, with the gap along their normal. Candidates are
// filtered like Bullet's btClosestNotMeConvexResultCallback (group / mask,
// the pair cache's filter callback, needsCollision and needsResponse). A body
// whose sweep meets a shape Minko does not model (a mesh, a compound) runs
// Bullet's own sweep for that step, and so does the whole world while
// setApplySpeculativeContactRestitution(true) is set. Shapes are mapped
// through the world's mkb::CollisionConfiguration when it has one (hull
// cache), else primitives only.
class CcdWorld : public btDiscreteDynamicsWorld {
public:
    CcdWorld(btDispatcher *dispatcher, btBroadphaseInterface *broadphase, btConstraintSolver *solver,
             btCollisionConfiguration *config);
    ~CcdWorld() override;

    struct Stats {
        long queries = 0;           // CCD sweeps answered by Minko
        long clamped = 0;           // motions stopped at a time of impact
        long predictive = 0;        // speculative contacts added
        long native_fallbacks = 0;  // sweeps left to Bullet (a shape Minko does not model)
    };
    const Stats &ccd_stats() const { return m_stats; }

protected:
    void integrateTransforms(btScalar timeStep) override;
    void createPredictiveContacts(btScalar timeStep) override;

private:
    struct Hit {
        btCollisionObject *object;
        mk_real t;
        mk_toi_result result;
        mk_sweep pose_a;
    };
    mk_status map(const btCollisionShape *shape, ShapeMap *out);
    bool needs_ccd(btRigidBody *body, btScalar dt, btTransform *predicted);
    int earliest_hit(btRigidBody *body, const btTransform &predicted, Hit *hit);

    CollisionConfiguration *m_config;
    std::vector<btCollisionObject *> m_candidates;
    Stats m_stats;
};

}  // namespace mkb

#endif

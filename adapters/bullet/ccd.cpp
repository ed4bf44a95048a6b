// ccd.cpp: continuous collision for Bullet through Minko's time of impact
// (see minko_bullet.h, mkb::CcdWorld).
#include <algorithm>

#include <btBulletDynamicsCommon.h>

#include "minko/toi.h"
#include "minko_bullet.h"

namespace mkb {

namespace {

// Gathers the broadphase proxies a CCD body may hit during its sweep, with
// the filter btClosestNotMeConvexResultCallback applies to the native sweep.
struct Candidates : btBroadphaseAabbCallback {
    btCollisionObject *me;
    btBroadphaseProxy *my_proxy;
    btOverlappingPairCache *cache;
    btDispatcher *dispatcher;
    std::vector<btCollisionObject *> *out;
    bool process(const btBroadphaseProxy *proxy) override
    {
        btCollisionObject *other = static_cast<btCollisionObject *>(proxy->m_clientObject);
        if (other == me) return true;
        if (!(proxy->m_collisionFilterGroup & my_proxy->m_collisionFilterMask) ||
            !(my_proxy->m_collisionFilterGroup & proxy->m_collisionFilterMask))
            return true;
        if (cache->getOverlapFilterCallback() &&
            !cache->getOverlapFilterCallback()->needBroadphaseCollision(my_proxy, const_cast<btBroadphaseProxy *>(proxy)))
            return true;
        if (!dispatcher->needsCollision(me, other) || !dispatcher->needsResponse(me, other)) return true;
        out->push_back(other);
        return true;
    }
};

}  // namespace

CcdWorld::CcdWorld(btDispatcher *dispatcher, btBroadphaseInterface *broadphase, btConstraintSolver *solver,
                   btCollisionConfiguration *config)
    : btDiscreteDynamicsWorld(dispatcher, broadphase, solver, config),
      m_config(dynamic_cast<CollisionConfiguration *>(config))
{
}

CcdWorld::~CcdWorld() = default;

mk_status CcdWorld::map(const btCollisionShape *shape, ShapeMap *out)
{
    return m_config ? m_config->map_shape(shape, out) : map_primitive(shape, out);
}

// Bullet's rule (a CCD threshold, motion beyond it, a convex shape), with the
// motion measured at the body's farthest point rather than at its centre: a
// fast spinner moves its ends as far as a fast mover, and Bullet's sphere
// sweep never sees either.
bool CcdWorld::needs_ccd(btRigidBody *body, btScalar dt, btTransform *predicted)
{
    if (!body->isActive() || body->isStaticOrKinematicObject()) return false;
    if (!getDispatchInfo().m_useContinuous || !body->getCcdSquareMotionThreshold()) return false;
    if (!body->getCollisionShape()->isConvex()) return false;
    body->predictIntegratedTransform(dt, *predicted);
    btVector3 centre;
    btScalar radius;
    body->getCollisionShape()->getBoundingSphere(centre, radius);
    const btScalar reach = (predicted->getOrigin() - body->getWorldTransform().getOrigin()).length() +
                           body->getAngularVelocity().length() * dt * (radius + centre.length());
    return body->getCcdSquareMotionThreshold() < reach * reach;
}

// The earliest time of impact of `body` moving from its pose to `predicted`
// against everything its swept box touches (others held still, as Bullet's
// own sweep does). 0: no Minko answer possible (some shape Minko does not
// model), the caller falls back to Bullet's sweep for this body.
int CcdWorld::earliest_hit(btRigidBody *body, const btTransform &predicted, Hit *hit)
{
    ShapeMap me;
    if (map(body->getCollisionShape(), &me) != MK_OK) return 0;
    mk_sweep sweep;
    if (mk_sweep_from_transforms(minko_pose(body->getWorldTransform(), me), minko_pose(predicted, me), mk_v3_zero(),
                                 &sweep) != MK_OK)
        return 0;
    mk_aabb box;
    if (mk_swept_aabb(&me.shape, &sweep, &box) != MK_OK) return 0;
    m_candidates.clear();
    Candidates gather;
    gather.me = body;
    gather.my_proxy = body->getBroadphaseHandle();
    gather.cache = getBroadphase()->getOverlappingPairCache();
    gather.dispatcher = getDispatcher();
    gather.out = &m_candidates;
    getBroadphase()->aabbTest(to_bt(box.lo), to_bt(box.hi), gather);

    hit->object = nullptr;
    hit->t = 1;
    for (btCollisionObject *other : m_candidates) {
        ShapeMap them;
        if (map(other->getCollisionShape(), &them) != MK_OK) return 0;
        const mk_transform at = minko_pose(other->getWorldTransform(), them);
        mk_sweep still;
        if (mk_sweep_from_transforms(at, at, mk_v3_zero(), &still) != MK_OK) return 0;
        mk_toi_result r;
        if (mk_toi(&me.shape, &sweep, &them.shape, &still, 0, 0, &r) != MK_OK) return 0;
        // Already penetrating, or meeting while closing in by less than
        // Bullet's allowed CCD penetration over the step (sliding along a
        // surface, grazing): the discrete contacts deal with it, and Bullet's
        // sweep ignores such hits by the same measure.
        if (r.state == MK_TOI_SEPARATED || r.state == MK_TOI_OVERLAPPED) continue;
        if (r.rate >= -getDispatchInfo().m_allowedCcdPenetration) continue;
        if (r.t < hit->t) {
            hit->t = r.t;
            hit->object = other;
            hit->result = r;
            hit->pose_a = sweep;
        }
    }
    m_stats.queries++;
    return 1;
}

void CcdWorld::integrateTransforms(btScalar dt)
{
    if (m_applySpeculativeContactRestitution) {
        btDiscreteDynamicsWorld::integrateTransforms(dt);  // Bullet's own path for that option
        return;
    }
    for (int i = 0; i < m_nonStaticRigidBodies.size(); i++) {
        btRigidBody *body = m_nonStaticRigidBodies[i];
        btTransform predicted;
        Hit hit;
        if (!needs_ccd(body, dt, &predicted)) {
            integrateTransformsInternal(&body, 1, dt);
            continue;
        }
        if (!earliest_hit(body, predicted, &hit)) {
            m_stats.native_fallbacks++;
            integrateTransformsInternal(&body, 1, dt);
            continue;
        }
        body->setHitFraction(1);
        if (hit.object) {
            // Stop at the time of impact, as Bullet does with its sweep's fraction.
            m_stats.clamped++;
            body->setHitFraction((btScalar)hit.t);
            body->predictIntegratedTransform(dt * body->getHitFraction(), predicted);
            body->setHitFraction(0);
        }
        body->proceedToTransform(predicted);
    }
}

void CcdWorld::createPredictiveContacts(btScalar dt)
{
    releasePredictiveContacts();
    for (int i = 0; i < m_nonStaticRigidBodies.size(); i++) {
        btRigidBody *body = m_nonStaticRigidBodies[i];
        btTransform predicted;
        Hit hit;
        body->setHitFraction(1);
        if (!needs_ccd(body, dt, &predicted)) continue;
        if (!earliest_hit(body, predicted, &hit)) {
            m_stats.native_fallbacks++;
            createPredictiveContactsInternal(&body, 1, dt);
            continue;
        }
        if (!hit.object) continue;
        // A speculative contact between the features that meet at the time
        // of impact: the body's point taken back to where it is now, the
        // obstacle's point, the normal on the obstacle pointing to the body,
        // and the gap along it (Bullet's own uses the body's centre instead).
        ShapeMap me;
        mk_transform at_t;
        if (map(body->getCollisionShape(), &me) != MK_OK || mk_sweep_transform(&hit.pose_a, hit.result.t, &at_t) != MK_OK)
            continue;
        const btVector3 local_a = to_bt(mk_quat_rotate(me.axis, mk_transform_inv_point(at_t, hit.result.point_a)));
        const btVector3 now_a = body->getWorldTransform() * local_a;
        const btVector3 point_b = to_bt(hit.result.point_b);
        const btVector3 normal_on_b = -to_bt(hit.result.normal);
        btPersistentManifold *manifold = m_dispatcher1->getNewManifold(body, hit.object);
        m_predictiveManifolds.push_back(manifold);
        btManifoldPoint p(local_a, hit.object->getWorldTransform().invXform(point_b), normal_on_b,
                          (now_a - point_b).dot(normal_on_b));
        btManifoldPoint &pt = manifold->getContactPoint(manifold->addManifoldPoint(p, true));
        pt.m_combinedRestitution = 0;
        pt.m_combinedFriction = gCalculateCombinedFrictionCallback(body, hit.object);
        pt.m_positionWorldOnA = now_a;
        pt.m_positionWorldOnB = point_b;
        m_stats.predictive++;
    }
}

}  // namespace mkb

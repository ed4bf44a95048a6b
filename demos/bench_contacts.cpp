// bench_contacts: box-box contact manifolds, Minko against Bullet and ODE, in
// one process on the same poses.
//
// Backends (each builds the full manifold of every case):
//   minko                                mk_collide(), with a per-pair mk_manifold_cache (warm: faces
//                                        preferred within the hysteresis band, manifold.h)
//   minko.cold                           mk_collide() without a cache: the exact minimum axis
//   minko.pose                           mk_collide_pose() with the cache, on poses made once per case
//                                        (rotation matrices, as Bullet's btTransform and ODE's geoms hold them)
//   bullet_f64.btBoxBoxDetector          Bullet's port of ODE's dBoxBox, called directly
//   bullet_f64.btBoxBoxCollisionAlgorithm  what a Bullet world runs per box pair and frame:
//                                        the detector plus the persistent-manifold update
//   ode.dCollide                         ODE 0.16 dCollide on two box geoms (dBoxBox), 4 contacts
// Case families (penetrating, seeded):
//   stacked  a unit box resting on another, tilted by up to 2 degrees, turned
//            about the vertical, 0.1 to 50 mm deep: the face contacts of stacking
//   random   boxes of half-extents 0.1 to 1, random orientations, overlapping
//   apart    the same boxes separated (up to 0.5) with overlapping world AABBs:
//            what a broadphase hands over that has no contact; accuracy is
//            then only "no point reported" (a point is a failure). Each
//            query reads its pair's shapes, poses and state from arrays as a
//            world would, so it is memory-bound for every backend alike
//            (callgrind --cache-sim, D1 read misses per call: minko.pose 5.7,
//            ode.dCollide 9.0)
// Per family and backend: ns per query (best of several timed loops over all
// cases, same pose repeated as in a resting contact, after one untimed pass
// that warms every per-pair state; the accuracy columns judge the answers of
// the pass after it, as timed), relative error of the
// deepest reported point against the exact SAT depth (long-double oracle,
// tests/support/oracle.h), angle of the normal against the exact normal,
// failures (no contact reported for a penetrating pair, or an error status),
// mean points per manifold. JSON Lines per ../shared/BENCH_FORMAT.md (suite
// "contacts", case "box_box") plus a table.
//
//   bench_contacts [--quick] [--loops N] [--json FILE] [--family stacked|random|apart] [--backend NAME]
// (--family runs one case family, --backend one backend (a prefix of its
// name: minko, minko.cold, minko.pose, bullet, ode), e.g. for callgrind instruction
// counts; ratios are then to that backend. --loops sets the number of timed
// loops: under callgrind, the difference between two runs with different
// --loops, divided by the extra loops times the cases, is the steady-state
// (warm) instructions per query, without the untimed passes, the first of
// which is cold.)

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <vector>

#include <btBulletCollisionCommon.h>
#include <BulletCollision/CollisionDispatch/btBoxBoxDetector.h>
#include <BulletCollision/CollisionDispatch/btBoxBoxCollisionAlgorithm.h>
#include <ode/ode.h>

#include "minko/manifold.h"
extern "C" {
#include "support/mk_rng.h"
#include "support/oracle.h"
}

namespace {

double now_ns()
{
    timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return 1e9 * double(t.tv_sec) + double(t.tv_nsec);
}

struct Case {
    mk_vec3 ha, hb;       // half extents
    mk_transform xa, xb;
    double depth;         // exact penetration depth (> 0)
    double normal[3];     // exact normal, A to B
    bool normal_defined;
};

// What one backend reported for one case.
struct Answer {
    int count = 0;
    double depth = 0;     // deepest point's penetration
    double normal[3] = {0, 0, 0};
    bool failed = false;
    bool error = false;   // an error status (Minko)
};

struct Backend {
    const char *name;
    std::vector<Answer> answers;
    double ns = 0;
};

mk_quat tilt_quat(mk_rng *r, double max_tilt)
{
    mk_vec3 axis = mk_v3((mk_real)mk_rng_range(r, -1, 1), (mk_real)mk_rng_range(r, -1, 1), 0);
    mk_quat tilt = mk_quat_from_axis_angle(axis, (mk_real)mk_rng_range(r, 0, max_tilt));
    mk_quat yaw = mk_quat_from_axis_angle(mk_v3(0, 0, 1), (mk_real)mk_rng_range(r, -3.14159, 3.14159));
    return mk_quat_mul(tilt, yaw);
}

// Half-extents of the world AABB of a box.
mk_vec3 aabb_half(mk_vec3 h, mk_quat q)
{
    mk_mat3 R = mk_mat3_from_quat(q);
    return mk_v3(std::fabs(R.c0.x) * h.x + std::fabs(R.c1.x) * h.y + std::fabs(R.c2.x) * h.z,
                 std::fabs(R.c0.y) * h.x + std::fabs(R.c1.y) * h.y + std::fabs(R.c2.y) * h.z,
                 std::fabs(R.c0.z) * h.x + std::fabs(R.c1.z) * h.y + std::fabs(R.c2.z) * h.z);
}

bool aabbs_overlap(const Case &c)
{
    mk_vec3 ea = aabb_half(c.ha, c.xa.q), eb = aabb_half(c.hb, c.xb.q), d = mk_v3_sub(c.xb.p, c.xa.p);
    return std::fabs(d.x) <= ea.x + eb.x && std::fabs(d.y) <= ea.y + eb.y && std::fabs(d.z) <= ea.z + eb.z;
}

bool finish_case(Case &c, bool apart)
{
    mk_shape a, b;
    mk_oracle_result o;
    mk_shape_box(c.ha, 0, &a);
    mk_shape_box(c.hb, 0, &b);
    if (mk_oracle_distance(&a, c.xa, &b, c.xb, &o) != 0) return false;
    if (apart) {
        c.depth = -double(o.distance);
        c.normal_defined = false;
        return o.distance > 1e-6 && o.distance < 0.5 && aabbs_overlap(c);
    }
    if (!(o.distance < -1e-6)) return false;
    c.depth = -double(o.distance);
    c.normal[0] = double(o.normal.x);
    c.normal[1] = double(o.normal.y);
    c.normal[2] = double(o.normal.z);
    c.normal_defined = o.normal_defined != 0;
    return true;
}

std::vector<Case> make_cases(const char *family, int n, uint64_t seed)
{
    std::vector<Case> out;
    mk_rng r = {seed};
    while (int(out.size()) < n) {
        Case c;
        if (!strcmp(family, "stacked")) {
            mk_real pen = (mk_real)mk_rng_range(&r, 1e-4, 0.05);
            c.ha = c.hb = mk_v3(0.5, 0.5, 0.5);
            c.xa = mk_transform_make(mk_v3(0, 0, 0), mk_quat_identity());
            c.xb = mk_transform_make(mk_v3(0, 0, 0), tilt_quat(&r, 2 * 3.14159265 / 180));
            // Rest B's lowest point pen below A's top face, shifted sideways a little.
            mk_mat3 R = mk_mat3_from_quat(c.xb.q);
            mk_real below = c.hb.x * std::fabs(R.c0.z) + c.hb.y * std::fabs(R.c1.z) + c.hb.z * std::fabs(R.c2.z);
            c.xb.p = mk_v3((mk_real)mk_rng_range(&r, -0.3, 0.3), (mk_real)mk_rng_range(&r, -0.3, 0.3), 0.5 + below - pen);
        } else {
            c.ha = mk_rng_v3(&r, 0.1, 1);
            c.hb = mk_rng_v3(&r, 0.1, 1);
            c.xa = mk_transform_make(mk_rng_v3(&r, -10, 10), mk_rng_quat(&r));
            mk_real reach = mk_v3_len(c.ha) + mk_v3_len(c.hb);
            double lo = strcmp(family, "apart") ? 0.1 : 0.5, hi = strcmp(family, "apart") ? 0.9 : 1.1;
            c.xb = mk_transform_make(mk_v3_mad(c.xa.p, (mk_real)mk_rng_range(&r, lo, hi) * reach, mk_rng_dir(&r)), mk_rng_quat(&r));
        }
        if (finish_case(c, !strcmp(family, "apart"))) out.push_back(c);
    }
    return out;
}

// ---- Minko ---------------------------------------------------------------

struct MinkoRun {
    std::vector<mk_shape> a, b;
    std::vector<mk_manifold_cache> cache;
    std::vector<mk_pose> pa, pb;
    bool warm, pose;
    MinkoRun(const std::vector<Case> &cs, bool warm_, bool pose_ = false)
        : a(cs.size()), b(cs.size()), cache(cs.size()), pa(cs.size()), pb(cs.size()), warm(warm_), pose(pose_)
    {
        for (size_t i = 0; i < cs.size(); ++i) {
            mk_shape_box(cs[i].ha, 0, &a[i]);
            mk_shape_box(cs[i].hb, 0, &b[i]);
            mk_pose_from_transform(cs[i].xa, &pa[i]);
            mk_pose_from_transform(cs[i].xb, &pb[i]);
        }
        memset(cache.data(), 0, cache.size() * sizeof(mk_manifold_cache));
    }
    void query(const std::vector<Case> &cs, size_t i, Answer *ans)
    {
        mk_manifold m;
        mk_manifold_cache *c = warm ? &cache[i] : nullptr;
        mk_status st = pose ? mk_collide_pose(&a[i], &pa[i], &b[i], &pb[i], 0, c, &m) : mk_collide(&a[i], cs[i].xa, &b[i], cs[i].xb, 0, c, &m);
        if (!ans) return;
        ans->error = st != MK_OK;
        ans->failed = st != MK_OK || m.count == 0;
        if (ans->failed) return;
        ans->count = m.count;
        ans->depth = -1e300;
        for (int k = 0; k < m.count; ++k) ans->depth = std::max(ans->depth, double(m.points[k].depth));
        ans->normal[0] = double(m.normal.x);
        ans->normal[1] = double(m.normal.y);
        ans->normal[2] = double(m.normal.z);
    }
};

// ---- Bullet ----------------------------------------------------------------

btTransform bt_xf(mk_transform x)
{
    return btTransform(btQuaternion(btScalar(x.q.x), btScalar(x.q.y), btScalar(x.q.z), btScalar(x.q.w)),
                       btVector3(btScalar(x.p.x), btScalar(x.p.y), btScalar(x.p.z)));
}

struct Collect : btDiscreteCollisionDetectorInterface::Result {
    Answer *ans;
    void setShapeIdentifiersA(int, int) override {}
    void setShapeIdentifiersB(int, int) override {}
    void addContactPoint(const btVector3 &normal_on_b, const btVector3 &, btScalar distance) override
    {
        if (!ans) return;
        if (ans->count == 0 || -double(distance) > ans->depth) {
            ans->depth = -double(distance);
            for (int k = 0; k < 3; ++k) ans->normal[k] = -double(normal_on_b[k]); // Bullet: B to A
        }
        ans->count++;
    }
};

struct BulletDetectorRun {
    std::vector<btBoxShape *> a, b;
    std::vector<btDiscreteCollisionDetectorInterface::ClosestPointInput> in;
    explicit BulletDetectorRun(const std::vector<Case> &cs)
    {
        for (const Case &c : cs) {
            a.push_back(new btBoxShape(btVector3(btScalar(c.ha.x), btScalar(c.ha.y), btScalar(c.ha.z))));
            b.push_back(new btBoxShape(btVector3(btScalar(c.hb.x), btScalar(c.hb.y), btScalar(c.hb.z))));
            btDiscreteCollisionDetectorInterface::ClosestPointInput ci;
            ci.m_transformA = bt_xf(c.xa);
            ci.m_transformB = bt_xf(c.xb);
            in.push_back(ci);
        }
    }
    ~BulletDetectorRun()
    {
        for (size_t i = 0; i < a.size(); ++i) {
            delete a[i];
            delete b[i];
        }
    }
    void query(const std::vector<Case> &, size_t i, Answer *ans)
    {
        Collect out;
        out.ans = ans;
        btBoxBoxDetector det(a[i], b[i]);
        det.getClosestPoints(in[i], out, nullptr);
        if (ans) ans->failed = ans->count == 0;
    }
};

// The algorithm as a Bullet world runs it: one algorithm and one persistent
// manifold per pair, processCollision every frame.
struct BulletAlgorithmRun {
    btDefaultCollisionConfiguration config;
    btCollisionDispatcher dispatcher{&config};
    btDispatcherInfo info;
    struct Pair {
        btBoxShape sa, sb;
        btCollisionObject oa, ob;
        btCollisionAlgorithm *algo = nullptr;
        Pair(const Case &c)
            : sa(btVector3(btScalar(c.ha.x), btScalar(c.ha.y), btScalar(c.ha.z))),
              sb(btVector3(btScalar(c.hb.x), btScalar(c.hb.y), btScalar(c.hb.z)))
        {
            oa.setCollisionShape(&sa);
            ob.setCollisionShape(&sb);
            oa.setWorldTransform(bt_xf(c.xa));
            ob.setWorldTransform(bt_xf(c.xb));
        }
    };
    std::vector<Pair *> pairs;
    explicit BulletAlgorithmRun(const std::vector<Case> &cs)
    {
        for (const Case &c : cs) {
            Pair *p = new Pair(c);
            btCollisionObjectWrapper wa(nullptr, &p->sa, &p->oa, p->oa.getWorldTransform(), -1, -1);
            btCollisionObjectWrapper wb(nullptr, &p->sb, &p->ob, p->ob.getWorldTransform(), -1, -1);
            btCollisionAlgorithmConstructionInfo ci(&dispatcher, 0);
            p->algo = new btBoxBoxCollisionAlgorithm(nullptr, ci, &wa, &wb);
            pairs.push_back(p);
        }
    }
    ~BulletAlgorithmRun()
    {
        for (Pair *p : pairs) {
            delete p->algo;
            delete p;
        }
    }
    void query(const std::vector<Case> &, size_t i, Answer *ans)
    {
        Pair *p = pairs[i];
        btCollisionObjectWrapper wa(nullptr, &p->sa, &p->oa, p->oa.getWorldTransform(), -1, -1);
        btCollisionObjectWrapper wb(nullptr, &p->sb, &p->ob, p->ob.getWorldTransform(), -1, -1);
        btManifoldResult res(&wa, &wb);
        p->algo->processCollision(&wa, &wb, info, &res);
        if (!ans) return;
        btManifoldArray arr;
        p->algo->getAllContactManifolds(arr);
        ans->failed = arr.size() == 0 || arr[0]->getNumContacts() == 0;
        if (ans->failed) return;
        const btPersistentManifold *m = arr[0];
        bool swapped = m->getBody0() != &p->oa;
        ans->count = m->getNumContacts();
        ans->depth = -1e300;
        for (int k = 0; k < m->getNumContacts(); ++k) {
            const btManifoldPoint &pt = m->getContactPoint(k);
            if (-double(pt.getDistance()) > ans->depth) {
                ans->depth = -double(pt.getDistance());
                for (int j = 0; j < 3; ++j) ans->normal[j] = (swapped ? 1 : -1) * double(pt.m_normalWorldOnB[j]);
            }
        }
    }
};

// ---- ODE --------------------------------------------------------------------

struct OdeRun {
    std::vector<dGeomID> a, b;
    explicit OdeRun(const std::vector<Case> &cs)
    {
        for (const Case &c : cs) {
            a.push_back(make(c.ha, c.xa));
            b.push_back(make(c.hb, c.xb));
        }
    }
    ~OdeRun()
    {
        for (size_t i = 0; i < a.size(); ++i) {
            dGeomDestroy(a[i]);
            dGeomDestroy(b[i]);
        }
    }
    static dGeomID make(mk_vec3 h, mk_transform x)
    {
        dGeomID g = dCreateBox(nullptr, 2 * dReal(h.x), 2 * dReal(h.y), 2 * dReal(h.z));
        dQuaternion q = {dReal(x.q.w), dReal(x.q.x), dReal(x.q.y), dReal(x.q.z)};
        dGeomSetPosition(g, dReal(x.p.x), dReal(x.p.y), dReal(x.p.z));
        dGeomSetQuaternion(g, q);
        return g;
    }
    void query(const std::vector<Case> &, size_t i, Answer *ans)
    {
        dContactGeom c[4];
        int n = dCollide(a[i], b[i], 4, c, sizeof(dContactGeom));
        if (!ans) return;
        ans->failed = n == 0;
        ans->count = n;
        ans->depth = -1e300;
        for (int k = 0; k < n; ++k) {
            if (double(c[k].depth) > ans->depth) {
                ans->depth = double(c[k].depth);
                for (int j = 0; j < 3; ++j) ans->normal[j] = -double(c[k].normal[j]); // ODE: o2 into o1
            }
        }
    }
};

// ---- measurement ---------------------------------------------------------------

template <class Run>
Backend measure(const char *name, Run &run, const std::vector<Case> &cs, int loops)
{
    Backend be;
    be.name = name;
    be.answers.resize(cs.size());
    for (size_t i = 0; i < cs.size(); ++i) run.query(cs, i, nullptr);
    for (size_t i = 0; i < cs.size(); ++i) run.query(cs, i, &be.answers[i]);
    be.ns = 1e300;
    for (int l = 0; l < loops; ++l) {
        double t0 = now_ns();
        for (size_t i = 0; i < cs.size(); ++i) run.query(cs, i, nullptr);
        be.ns = std::min(be.ns, (now_ns() - t0) / double(cs.size()));
    }
    return be;
}

double pct(std::vector<double> v, double q)
{
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    return v[size_t(q * double(v.size() - 1) + 0.5)];
}

// Ratios are to the first backend: Minko when it is in the build.
void report(FILE *jf, const char *family, const std::vector<Case> &cs, const std::vector<Backend> &bes)
{
    const double minko_ns = bes[0].ns;
    for (const Backend &be : bes) {
        std::vector<double> rel, ang;
        int failures = 0;
        double points = 0;
        const bool apart = !strcmp(family, "apart");
        for (size_t i = 0; i < cs.size(); ++i) {
            const Answer &a = be.answers[i];
            if (apart) { // no contact is the right answer: a reported point (or an error) is the failure
                failures += a.count > 0 || a.error;
                continue;
            }
            if (a.failed) {
                failures++;
                continue;
            }
            points += a.count;
            rel.push_back(std::fabs(a.depth - cs[i].depth) / cs[i].depth);
            if (cs[i].normal_defined) {
                double d = a.normal[0] * cs[i].normal[0] + a.normal[1] * cs[i].normal[1] + a.normal[2] * cs[i].normal[2];
                double l = std::sqrt(a.normal[0] * a.normal[0] + a.normal[1] * a.normal[1] + a.normal[2] * a.normal[2]);
                ang.push_back(l > 0 ? std::acos(std::max(-1.0, std::min(1.0, d / l))) * 180 / 3.14159265358979 : 180);
            }
        }
        int ok = int(cs.size()) - failures;
        printf("%-8s %-40s %9.1f %7.2f %10.2e %10.2e %10.2e %10.2e %8d %6.2f\n", family, be.name, be.ns, be.ns / minko_ns,
               pct(rel, 0.5), pct(rel, 0.99), rel.empty() ? 0 : *std::max_element(rel.begin(), rel.end()), pct(ang, 0.99),
               failures, ok ? points / ok : 0);
        if (jf)
            fprintf(jf,
                    "{\"suite\":\"contacts\",\"case\":\"box_box\",\"variant\":\"%s\",\"backend\":\"%s\",\"n\":%zu,"
                    "\"ns_per_query\":%.2f,\"rel_err_p50\":%.3g,\"rel_err_p99\":%.3g,\"rel_err_max\":%.3g,"
                    "\"normal_err_deg_p99\":%.3g,\"normal_err_deg_max\":%.3g,\"failures\":%d,\"points_mean\":%.3f}\n",
                    family, be.name, cs.size(), be.ns, pct(rel, 0.5), pct(rel, 0.99),
                    rel.empty() ? 0 : *std::max_element(rel.begin(), rel.end()), pct(ang, 0.99),
                    ang.empty() ? 0 : *std::max_element(ang.begin(), ang.end()), failures, ok ? points / ok : 0);
    }
}

// --backend: "minko" names the warm run only; other names match as prefixes.
bool wanted(const char *filter, const char *name)
{
    if (!filter) return true;
    if (!strcmp(filter, "minko")) return !strcmp(name, "minko");
    return !strncmp(name, filter, strlen(filter));
}

} // namespace

int main(int argc, char **argv)
{
    bool quick = false;
    const char *json = nullptr, *only = nullptr, *backend = nullptr;
    int loops_arg = 0;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--quick")) quick = true;
        else if (!strcmp(argv[i], "--loops") && i + 1 < argc && atoi(argv[i + 1]) > 0) loops_arg = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--json") && i + 1 < argc) json = argv[++i];
        else if (!strcmp(argv[i], "--family") && i + 1 < argc) only = argv[++i];
        else if (!strcmp(argv[i], "--backend") && i + 1 < argc) backend = argv[++i];
        else {
            fprintf(stderr, "usage: %s [--quick] [--loops N] [--json FILE] [--family stacked|random|apart] [--backend NAME]\n", argv[0]);
            return 2;
        }
    }
    FILE *jf = json ? fopen(json, "w") : nullptr;
    if (json && !jf) {
        perror(json);
        return 2;
    }
    dInitODE2(0);
    const int n = quick ? 400 : 4000, loops = loops_arg ? loops_arg : quick ? 5 : 15;
    printf("bench_contacts: box-box manifolds, %d cases per family, best of %d loops; Minko %s, Bullet %s, ODE dReal %s\n", n,
           loops, mk_is_double_precision() ? "double" : "single", sizeof(btScalar) == 8 ? "double" : "float",
           sizeof(dReal) == 8 ? "double" : "float");
    printf("%-8s %-40s %9s %7s %10s %10s %10s %10s %8s %6s\n", "family", "backend", "ns/query", "ratio", "depth_p50",
           "depth_p99", "depth_max", "normal99", "failures", "points");
    const char *bullet_detector = sizeof(btScalar) == 8 ? "bullet_f64.btBoxBoxDetector" : "bullet_f32.btBoxBoxDetector";
    const char *bullet_algorithm =
        sizeof(btScalar) == 8 ? "bullet_f64.btBoxBoxCollisionAlgorithm" : "bullet_f32.btBoxBoxCollisionAlgorithm";
    const char *families[] = {"stacked", "random", "apart"};
    for (const char *fam : families) {
        if (only && strcmp(only, fam)) continue;
        std::vector<Case> cs = make_cases(fam, n, fam[0] == 's' ? 1 : fam[0] == 'r' ? 2 : 3);
        std::vector<Backend> bes;
        {
            MinkoRun run(cs, true), cold(cs, false), posed(cs, true, true);
            mk_manifold probe;
            mk_status st = mk_collide(&run.a[0], cs[0].xa, &run.b[0], cs[0].xb, 0, nullptr, &probe);
            if (st != MK_OK) {
                printf("%-8s minko: box-box is not in this build (%s); competitors only, ratios to the first of them\n", fam,
                       mk_status_name(st));
            } else {
                if (wanted(backend, "minko")) bes.push_back(measure("minko", run, cs, loops));
                if (wanted(backend, "minko.cold")) bes.push_back(measure("minko.cold", cold, cs, loops));
                if (wanted(backend, "minko.pose")) bes.push_back(measure("minko.pose", posed, cs, loops));
            }
        }
        if (wanted(backend, bullet_detector)) {
            BulletDetectorRun run(cs);
            bes.push_back(measure(bullet_detector, run, cs, loops));
        }
        if (wanted(backend, bullet_algorithm)) {
            BulletAlgorithmRun run(cs);
            bes.push_back(measure(bullet_algorithm, run, cs, loops));
        }
        if (wanted(backend, "ode.dCollide")) {
            OdeRun run(cs);
            bes.push_back(measure("ode.dCollide", run, cs, loops));
        }
        if (bes.empty()) continue;
        report(jf, fam, cs, bes);
    }
    dCloseODE();
    if (jf) fclose(jf);
    return 0;
}

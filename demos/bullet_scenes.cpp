// demos/bullet_scenes: Bullet 3.24's own benchmark scenes and a set of stiff and
// extreme cases, run headless through every collision backend in one process:
// Bullet native (btDbvtBroadphase + btDefaultCollisionConfiguration) and the Minko
// backends of adapters/bullet as they exist. Same scene, same solver, same
// deterministic pair order; only the collision pipeline changes.
//
// Per scene and backend it reports: median ms per step (total, collision phase,
// broadphase part) and the mean (total, collision phase; where bodies fall
// asleep the medians only see the sleeping steps), mean pairs / manifolds
// with >= 1 point / contact points per step, the deepest penetration seen
// over the run (max_pen, mostly impacts) and at the last step (pen_end, at
// rest where the scene settles), both judged by one fixed referee for every
// backend (Bullet's GJK-EPA signed distance or the exact oracle on the
// tight-AABB-overlapping pairs), fallen bodies and drift, kinetic energy at the end, tunnelled bodies, and how
// far the end state is from the native run's. A body has fallen when it ends
// lower than where drift measurement started by more than half its height (a
// toppled tower block, a barrel rolled off the pile, a slab that squeezed its
// support out); drift is the largest displacement among the bodies that did
// not fall, so it measures creep of what still stands instead of how far a
// fallen body rolled, and is not reported for a trial in which every body fell. JSON Lines per ../shared/BENCH_FORMAT.md (suite "bullet")
// with --json FILE, and a table on stdout.
//
// Timing: external steady_clock timers around stepSimulation and around the
// collision world's virtual updateAabbs / computeOverlappingPairs /
// performDiscreteCollisionDetection; the referee and the counters run outside
// the timed region. The backends of a scene run side by side, one step each
// in turn, so load on a shared machine falls on all of them alike. With
// --trials N every scene runs N times and each figure is the median
// (tunnelling the worst): resting stacks creep in a direction set by
// round-off, so one run says little about drift. Trial 0 is the scene as
// specified; in trial k > 0 every dynamic body starts moved by a seeded
// random offset of up to 1e-3 of its bounding radius per axis (seed: k and
// the body's index), the same offsets for every backend; nothing else varies.
// A second table gives each stability metric as mean +- sample standard
// deviation over the trials (also in the JSON as <metric>_mean / _sd) and
// calls a backend's difference from native noise when it is within twice
// the standard error of the difference of the means.

#include <btBulletDynamicsCommon.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpa2.h>

#include "minko_bullet.h"
extern "C" {
#include "support/oracle.h"
}

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <vector>

namespace {

#if defined(BT_USE_DOUBLE_PRECISION)
const char *const kBulletTag = "bullet_f64";
#else
const char *const kBulletTag = "bullet_f32";
#endif

typedef std::chrono::steady_clock Clock;

double ms_since(Clock::time_point t0)
{
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// ---- a world that times its own collision phase ------------------------------

// Wraps any btDiscreteDynamicsWorld subclass. The three overridden members are
// virtual in btCollisionWorld and performDiscreteCollisionDetection calls the
// other two, so the timers sit exactly around Bullet's own phases.
struct Timers {
    double aabb_ms = 0, pairs_ms = 0, collision_ms = 0;
    void reset() { aabb_ms = pairs_ms = collision_ms = 0; }
};

template <class World>
class Timed : public World {
public:
    Timed(btDispatcher *d, btBroadphaseInterface *b, btConstraintSolver *s, btCollisionConfiguration *c)
        : World(d, b, s, c) {}
    Timers timers;
    void performDiscreteCollisionDetection() override
    {
        Clock::time_point t0 = Clock::now();
        World::performDiscreteCollisionDetection();
        timers.collision_ms += ms_since(t0);
    }
    void updateAabbs() override
    {
        Clock::time_point t0 = Clock::now();
        World::updateAabbs();
        timers.aabb_ms += ms_since(t0);
    }
    void computeOverlappingPairs() override
    {
        Clock::time_point t0 = Clock::now();
        World::computeOverlappingPairs();
        timers.pairs_ms += ms_since(t0);
    }
};

// ---- backends -------------------------------------------------------------------

struct Backend {
    const char *name;
    bool minko_broadphase;
    bool minko_narrowphase;
    bool minko_ccd;  // mkb::CcdWorld: only where a scene turns CCD on
};

const Backend kBackends[] = {
    {"native", false, false, false},
    {"minko_bp", true, false, false},
    {"minko_np", false, true, false},
    {"minko", true, true, false},
    {"minko+ccd", true, true, true},
};
const int kBackendCount = (int)(sizeof kBackends / sizeof kBackends[0]);

// Which Minko broadphase structure the minko backends use (--bp; default
// mkb::Broadphase's, SAP), and how far its filed boxes reach past Bullet's
// AABBs (--bp-margin; default Dbvt's gDbvtMargin).
mk_bp_kind g_bp_kind = MK_BP_SAP;
btScalar g_bp_margin = gDbvtMargin;
// The penetration referee runs (--no-referee leaves it out, for profiling).
bool g_referee = true;

// Everything one world needs, built for one backend and torn down in reverse.
struct Pipeline {
    btCollisionConfiguration *config = nullptr;
    mkb::CollisionConfiguration *minko_config = nullptr;  // when the narrowphase is Minko's
    btCollisionDispatcher *dispatcher = nullptr;
    btBroadphaseInterface *broadphase = nullptr;
    btSequentialImpulseConstraintSolver *solver = nullptr;
    btDiscreteDynamicsWorld *world = nullptr;
    Timers *timers = nullptr;

    explicit Pipeline(const Backend &b)
    {
        if (b.minko_narrowphase) config = minko_config = new mkb::CollisionConfiguration(mkb::Backend::minko);
        else config = new btDefaultCollisionConfiguration();
        dispatcher = new btCollisionDispatcher(config);
        if (b.minko_broadphase) broadphase = new mkb::Broadphase(g_bp_kind, nullptr, 1024, g_bp_margin);
        else broadphase = new btDbvtBroadphase();
        solver = new btSequentialImpulseConstraintSolver();
        if (b.minko_ccd) {
            Timed<mkb::CcdWorld> *w = new Timed<mkb::CcdWorld>(dispatcher, broadphase, solver, config);
            world = w;
            timers = &w->timers;
        } else {
            Timed<btDiscreteDynamicsWorld> *w = new Timed<btDiscreteDynamicsWorld>(dispatcher, broadphase, solver, config);
            world = w;
            timers = &w->timers;
        }
        // Pairs processed in uid order and islands sorted: the only way two
        // broadphases that report the same pairs give the same trajectories.
        world->getDispatchInfo().m_deterministicOverlappingPairs = true;
    }
    ~Pipeline()
    {
        delete world;  // the world does not own the rest
        delete solver;
        delete broadphase;
        delete dispatcher;
        delete config;
    }
    Pipeline(const Pipeline &) = delete;
    Pipeline &operator=(const Pipeline &) = delete;
};

// ---- scenes ---------------------------------------------------------------------

struct BodySpec {
    int shape;         // index into SceneSpec::shapes
    btScalar mass;     // 0: static
    btTransform xf;
    btVector3 v, w;    // initial linear / angular velocity
    bool ccd;          // enable the world's continuous collision for this body
    // Tunnelling test: the body must end with keep_n . p <= keep_d.
    bool has_keep;
    btVector3 keep_n;
    btScalar keep_d;
};

struct SceneSpec {
    std::string name, variant;
    int steps = 600, quick_steps = 0;  // quick_steps 0: not in the --quick subset
    btScalar dt = btScalar(1) / btScalar(60);
    int iterations = 10;
    bool friction_caching = false;     // BenchmarkDemo's SOLVER_ENABLE_FRICTION_DIRECTION_CACHING
    bool sleep = true;                 // false: every dynamic body DISABLE_DEACTIVATION
    double drift_from = 0;             // drift measured from this fraction of the run; < 0: not reported
    int judge_every = 1;               // referee sampling period in steps
    btScalar friction = btScalar(0.5); // Bullet's default
    std::vector<btCollisionShape *> shapes;
    std::vector<BodySpec> bodies;

    SceneSpec() = default;
    SceneSpec(const SceneSpec &) = delete;
    SceneSpec &operator=(const SceneSpec &) = delete;
    ~SceneSpec()
    {
        for (btCollisionShape *s : shapes) delete s;
    }
    int add_shape(btCollisionShape *s)
    {
        shapes.push_back(s);
        return (int)shapes.size() - 1;
    }
    BodySpec &add_body(int shape, btScalar mass, const btTransform &xf)
    {
        BodySpec b;
        b.shape = shape;
        b.mass = mass;
        b.xf = xf;
        b.v = b.w = btVector3(0, 0, 0);
        b.ccd = false;
        b.has_keep = false;
        b.keep_n = btVector3(0, 0, 0);
        b.keep_d = 0;
        bodies.push_back(b);
        return bodies.back();
    }
    BodySpec &add_body(int shape, btScalar mass, const btVector3 &p)
    {
        btTransform xf;
        xf.setIdentity();
        xf.setOrigin(p);
        return add_body(shape, mass, xf);
    }
    // Static ground box whose top face is the plane y = 0.
    void add_ground(btScalar half_xz, btScalar half_y)
    {
        int g = add_shape(new btBoxShape(btVector3(half_xz, half_y, half_xz)));
        add_body(g, 0, btVector3(0, -half_y, 0));
    }
    // A dynamic body that falls through the ground has tunnelled.
    void keep_above_ground(BodySpec &b, btScalar half_height)
    {
        b.has_keep = true;
        b.keep_n = btVector3(0, -1, 0);
        b.keep_d = half_height;  // centre below y = -half_height: entirely under the top face
    }
    bool uses_ccd() const
    {
        for (const BodySpec &b : bodies)
            if (b.ccd) return true;
        return false;
    }
    int dynamic_count() const
    {
        int n = 0;
        for (const BodySpec &b : bodies) n += b.mass > 0;
        return n;
    }
};

// splitmix64, so scenes are the same on every platform and in every run.
struct Rng {
    unsigned long long s;
    explicit Rng(unsigned long long seed) : s(seed) {}
    unsigned long long next()
    {
        unsigned long long z = (s += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    double unit() { return (double)(next() >> 11) * (1.0 / 9007199254740992.0); }
    double range(double lo, double hi) { return lo + (hi - lo) * unit(); }
};

// BenchmarkDemo's common setup (examples/Benchmarks/BenchmarkDemo.cpp, tag 3.24):
// 5 solver iterations with friction direction caching, a 500 x 100 x 500 static
// box whose top is y = 0, gravity -10 (set for every scene).
void benchmark_setup(SceneSpec &s)
{
    s.iterations = 5;
    s.friction_caching = true;
    s.add_ground(250, 50);
}

// "3000 boxes" (createTest1): 47 layers of 8 x 8 boxes of half extent 1, mass 2,
// pitch 3, each layer shifted by -0.35 in x and z; they fall into a pile.
void scene_3000_boxes(SceneSpec &s)
{
    s.name = "3000_boxes";
    s.variant = "3008_boxes";
    s.steps = 600;
    s.quick_steps = 30;
    s.drift_from = 2.0 / 3.0;
    s.judge_every = 10;
    benchmark_setup(s);
    const int size = 8;
    const btScalar cube = 1, spacing = cube;
    int box = s.add_shape(new btBoxShape(btVector3(cube, cube, cube)));
    btScalar offset = -size * (cube * 2 + spacing) * btScalar(0.5);
    btVector3 pos(0, cube * 2, 0);
    for (int k = 0; k < 47; k++) {
        for (int j = 0; j < size; j++) {
            pos[2] = offset + (btScalar)j * (cube * 2 + spacing);
            for (int i = 0; i < size; i++) {
                pos[0] = offset + (btScalar)i * (cube * 2 + spacing);
                s.keep_above_ground(s.add_body(box, 2, pos), cube);
            }
        }
        offset -= btScalar(0.05) * spacing * (size - 1);
        pos[1] += cube * 2 + spacing;
    }
}

// "1000 stack" (createTest2): a 12-level pyramid, three 12-high walls and a
// circular tower 8 high x 24 around; 1076 boxes of half extent 1, mass 1, at rest.
void add_pyramid(SceneSpec &s, int box, const btVector3 &at, int stack)
{
    const btScalar space = btScalar(0.0001), diff = btScalar(1.02);
    btScalar offx = -stack * (diff * 2 + space) * btScalar(0.5), offz = offx;
    btVector3 pos(0, 1, 0);
    for (; stack > 0; stack--) {
        for (int j = 0; j < stack; j++) {
            pos[2] = offz + (btScalar)j * (diff * 2 + space);
            for (int i = 0; i < stack; i++) {
                pos[0] = offx + (btScalar)i * (diff * 2 + space);
                s.keep_above_ground(s.add_body(box, 1, at + pos), 1);
            }
        }
        offx += diff;
        offz += diff;
        pos[1] += diff * 2 + space;
    }
}

void add_wall(SceneSpec &s, int box, const btVector3 &at, int stack)
{
    btScalar offset = -stack * btScalar(2) * btScalar(0.5);
    btVector3 pos(0, 1, 0);
    for (; stack > 0; stack--) {
        for (int i = 0; i < stack; i++) {
            pos[2] = offset + (btScalar)i * 2;
            s.keep_above_ground(s.add_body(box, 1, at + pos), 1);
        }
        offset += 1;
        pos[1] += 2;
    }
}

void add_tower_circle(SceneSpec &s, int box, const btVector3 &at, int stack, int around)
{
    const btScalar radius = btScalar(1.3) * around / SIMD_PI;
    btQuaternion rot(0, 1, 0, 0);
    btScalar y = 1;
    for (int i = 0; i < stack; i++) {
        for (int j = 0; j < around; j++) {
            btTransform xf(rot, at + quatRotate(rot, btVector3(0, y, radius)));
            s.keep_above_ground(s.add_body(box, 1, xf), 1);
            rot *= btQuaternion(btVector3(0, 1, 0), SIMD_PI / (around * btScalar(0.5)));
        }
        y += 2;
        rot *= btQuaternion(btVector3(0, 1, 0), SIMD_PI / (btScalar)around);
    }
}

void scene_1000_stack(SceneSpec &s)
{
    s.name = "1000_stack";
    s.variant = "1076_boxes";
    s.steps = 600;
    s.quick_steps = 30;
    s.drift_from = 0;
    s.judge_every = 10;
    benchmark_setup(s);
    int box = s.add_shape(new btBoxShape(btVector3(1, 1, 1)));
    add_pyramid(s, box, btVector3(-20, 0, 0), 12);
    add_wall(s, box, btVector3(-2, 0, 0), 12);
    add_wall(s, box, btVector3(4, 0, 0), 12);
    add_wall(s, box, btVector3(10, 0, 0), 12);
    add_tower_circle(s, box, btVector3(25, 0, 0), 8, 24);
}

// The 43 input points of BenchmarkDemo's "Taru" barrel
// (examples/Benchmarks/TaruData.h in the bullet3 repository; 24 distinct points,
// the hull has 24 vertices). Data, not code: Debian's libbullet-dev does not ship
// the examples.
const float kTaru[43][3] = {
    {1.08664f, -1.99237f, 0.0f}, {0.768369f, -1.99237f, -0.768369f}, {1.28852f, 1.34412e-007f, -1.28852f},
    {1.82224f, 1.90735e-007f, 0.0f}, {0.0f, -1.99237f, -1.08664f}, {0.0f, 0.0f, -1.82224f},
    {0.0f, -1.99237f, -1.08664f}, {-0.768369f, -1.99237f, -0.768369f}, {-1.28852f, 1.34412e-007f, -1.28852f},
    {0.0f, 0.0f, -1.82224f}, {-1.08664f, -1.99237f, 1.82086e-007f}, {-1.82224f, 1.90735e-007f, 1.59305e-007f},
    {-0.768369f, -1.99237f, 0.76837f}, {-1.28852f, 2.47058e-007f, 1.28852f}, {1.42495e-007f, -1.99237f, 1.08664f},
    {2.38958e-007f, 2.70388e-007f, 1.82224f}, {0.768369f, -1.99237f, 0.768369f}, {1.28852f, 2.47058e-007f, 1.28852f},
    {0.768369f, 1.99237f, -0.768369f}, {1.08664f, 1.99237f, 0.0f}, {0.0f, 1.99237f, -1.08664f},
    {-0.768369f, 1.99237f, -0.768369f}, {0.0f, 1.99237f, -1.08664f}, {-1.08664f, 1.99237f, 0.0f},
    {-0.768369f, 1.99237f, 0.768369f}, {1.42495e-007f, 1.99237f, 1.08664f}, {0.768369f, 1.99237f, 0.768369f},
    {1.42495e-007f, -1.99237f, 1.08664f}, {-0.768369f, -1.99237f, 0.76837f}, {-1.08664f, -1.99237f, 1.82086e-007f},
    {-0.768369f, -1.99237f, -0.768369f}, {0.0f, -1.99237f, -1.08664f}, {0.768369f, -1.99237f, -0.768369f},
    {1.08664f, -1.99237f, 0.0f}, {0.768369f, -1.99237f, 0.768369f}, {0.768369f, 1.99237f, -0.768369f},
    {0.0f, 1.99237f, -1.08664f}, {-0.768369f, 1.99237f, -0.768369f}, {-1.08664f, 1.99237f, 0.0f},
    {-0.768369f, 1.99237f, 0.768369f}, {1.42495e-007f, 1.99237f, 1.08664f}, {0.768369f, 1.99237f, 0.768369f},
    {1.08664f, 1.99237f, 0.0f},
};

// "Convex stack" (createTest4): 15 layers of 8 x 8 Taru hulls, mass 1, with
// polyhedral features (hull-hull by SAT normal + clipping), falling into a pile.
void scene_convex_stack(SceneSpec &s)
{
    s.name = "convex_stack";
    s.variant = "960_hulls";
    s.steps = 600;
    s.quick_steps = 0;
    s.drift_from = 2.0 / 3.0;
    s.judge_every = 10;
    benchmark_setup(s);
    btConvexHullShape *hull = new btConvexHullShape();
    for (const float *p : kTaru) hull->addPoint(btVector3(p[0], p[1], p[2]), false);
    hull->recalcLocalAabb();
    hull->initializePolyhedralFeatures();
    int h = s.add_shape(hull);
    const int size = 8;
    const btScalar cube = btScalar(1.5);
    btScalar spacing = cube;
    btScalar offset = -size * (cube * 2 + spacing) * btScalar(0.5);
    btVector3 pos(0, cube * 2, 0);
    for (int k = 0; k < 15; k++) {
        for (int j = 0; j < size; j++) {
            pos[2] = offset + (btScalar)j * (cube * 2 + spacing);
            for (int i = 0; i < size; i++) {
                pos[0] = offset + (btScalar)i * (cube * 2 + spacing);
                s.keep_above_ground(s.add_body(h, 1, pos), 2);
            }
        }
        offset -= btScalar(0.05) * spacing * (size - 1);
        spacing *= btScalar(1.01);
        pos[1] += cube * 2 + spacing;
    }
}

// A pile of 1000 spheres and capsules (radius 0.5; capsules 0.3 x 1.2 along Y)
// dropped from a 10 x 10 x 10 grid onto the ground: the closed-form pairs.
void scene_prim_pile(SceneSpec &s)
{
    s.name = "prim_pile";
    s.variant = "1000_spheres_capsules";
    s.steps = 600;
    s.quick_steps = 30;
    s.drift_from = 2.0 / 3.0;
    s.judge_every = 10;
    benchmark_setup(s);
    int ball = s.add_shape(new btSphereShape(btScalar(0.5)));
    int cap = s.add_shape(new btCapsuleShape(btScalar(0.3), btScalar(0.6)));
    for (int k = 0; k < 10; k++)
        for (int j = 0; j < 10; j++)
            for (int i = 0; i < 10; i++) {
                const bool sphere = (i + j + k) % 2 == 0;
                btVector3 at(btScalar(-9 + 2 * i + 0.1 * k), btScalar(1 + 2.2 * k), btScalar(-9 + 2 * j - 0.1 * k));
                s.keep_above_ground(s.add_body(sphere ? ball : cap, 1, at), sphere ? btScalar(0.5) : btScalar(0.3));
            }
}

// Stability scenes: Bullet's default solver (10 iterations), no sleeping so
// jitter shows in drift and kinetic energy instead of being frozen away.
void stability_setup(SceneSpec &s, btScalar ground_half)
{
    s.iterations = 10;
    s.sleep = false;
    s.drift_from = 0;
    s.add_ground(ground_half, 50);
}

// A column of n boxes of half extent h, exactly touching, on the ground.
void add_tower(SceneSpec &s, btScalar h, btScalar mass, int n)
{
    int box = s.add_shape(new btBoxShape(btVector3(h, h, h)));
    for (int i = 0; i < n; i++) s.keep_above_ground(s.add_body(box, mass, btVector3(0, h + 2 * h * i, 0)), h);
}

void scene_tower10(SceneSpec &s)
{
    s.name = "tower";
    s.variant = "10_boxes";
    s.quick_steps = 120;
    stability_setup(s, 250);
    add_tower(s, btScalar(0.5), 1, 10);
}

void scene_tiny_boxes(SceneSpec &s)
{
    s.name = "tiny_boxes";
    s.variant = "1cm_tower10";
    stability_setup(s, 250);
    add_tower(s, btScalar(0.005), btScalar(0.001), 10);
}

void scene_huge_boxes(SceneSpec &s)
{
    s.name = "huge_boxes";
    s.variant = "100m_tower10";
    stability_setup(s, 2000);
    add_tower(s, 50, btScalar(1e6), 10);
}

// A light cube (1 kg) under a heavy slab (ratio kg): the classic hard case
// for an iterative solver fed by the contacts the collision layer produces.
void scene_mass_ratio(SceneSpec &s, int ratio)
{
    s.name = "mass_ratio";
    s.variant = "1:" + std::to_string(ratio);
    s.quick_steps = ratio == 100 ? 120 : 0;
    stability_setup(s, 250);
    int cube = s.add_shape(new btBoxShape(btVector3(btScalar(0.5), btScalar(0.5), btScalar(0.5))));
    int slab = s.add_shape(new btBoxShape(btVector3(1, btScalar(0.5), 1)));
    s.keep_above_ground(s.add_body(cube, 1, btVector3(0, btScalar(0.5), 0)), btScalar(0.5));
    s.keep_above_ground(s.add_body(slab, (btScalar)ratio, btVector3(0, btScalar(1.5), 0)), btScalar(0.5));
}

// Spheres of radius 0.05 fired at a 0.1-thick static wall, one lane per speed.
// A sphere that ends beyond the wall's far face has tunnelled. The "ccd"
// variant turns on the world's continuous collision for the spheres (Bullet's
// swept-sphere CCD natively), "discrete" leaves it off as Bullet's default.
void scene_sphere_wall(SceneSpec &s, bool ccd)
{
    static const btScalar speeds[] = {10, 30, 100, 300, 1000};
    const btScalar r = btScalar(0.05), half_thick = btScalar(0.05);
    s.name = "sphere_wall";
    s.variant = ccd ? "ccd" : "discrete";
    s.steps = 60;
    s.quick_steps = ccd ? 0 : 60;
    stability_setup(s, 250);
    s.drift_from = -1;
    s.sleep = true;
    int wall = s.add_shape(new btBoxShape(btVector3(half_thick, 5, 12)));
    s.add_body(wall, 0, btVector3(0, 5, 0));
    int ball = s.add_shape(new btSphereShape(r));
    for (int i = 0; i < 5; i++) {
        // Start off the step grid so no speed lands exactly on the wall's centre plane.
        BodySpec &b = s.add_body(ball, btScalar(0.1), btVector3(btScalar(-2.013), 3, btScalar(-8 + 4 * i)));
        b.v = btVector3(speeds[i], 0, 0);
        b.ccd = ccd;
        b.has_keep = true;
        b.keep_n = btVector3(1, 0, 0);
        b.keep_d = half_thick + r;
    }
}

// 20 random hulls (12-24 points on ellipsoids, semi-axes 0.3-1) dropped from
// a little height in random orientations; they settle on the ground.
void scene_random_hulls(SceneSpec &s)
{
    s.name = "random_hulls";
    s.variant = "20_hulls";
    s.quick_steps = 0;
    stability_setup(s, 250);
    s.drift_from = 2.0 / 3.0;
    Rng rng(20240601);
    for (int k = 0; k < 20; k++) {
        btConvexHullShape *hull = new btConvexHullShape();
        const int n = 12 + (int)(rng.unit() * 13);
        const double ax = rng.range(0.3, 1), ay = rng.range(0.3, 1), az = rng.range(0.3, 1);
        for (int i = 0; i < n; i++) {
            double z = rng.range(-1, 1), t = rng.range(0, 2 * SIMD_PI), q = std::sqrt(1 - z * z);
            hull->addPoint(btVector3((btScalar)(ax * q * std::cos(t)), (btScalar)(ay * q * std::sin(t)), (btScalar)(az * z)), false);
        }
        hull->recalcLocalAabb();
        hull->initializePolyhedralFeatures();
        int h = s.add_shape(hull);
        btQuaternion rot((btScalar)rng.range(-1, 1), (btScalar)rng.range(-1, 1), (btScalar)rng.range(-1, 1), (btScalar)rng.range(-1, 1));
        rot.normalize();
        btTransform xf(rot, btVector3((btScalar)(-6 + 3 * (k % 5)), btScalar(1.5), (btScalar)(-4.5 + 3 * (k / 5))));
        s.keep_above_ground(s.add_body(h, 1, xf), 1);
    }
}

struct SceneEntry {
    const char *id;
    void (*make)(SceneSpec &, int);
    int arg;
};
void mk_3000(SceneSpec &s, int) { scene_3000_boxes(s); }
void mk_1000(SceneSpec &s, int) { scene_1000_stack(s); }
void mk_convex(SceneSpec &s, int) { scene_convex_stack(s); }
void mk_tower(SceneSpec &s, int) { scene_tower10(s); }
void mk_ratio(SceneSpec &s, int r) { scene_mass_ratio(s, r); }
void mk_tiny(SceneSpec &s, int) { scene_tiny_boxes(s); }
void mk_huge(SceneSpec &s, int) { scene_huge_boxes(s); }
void mk_wall(SceneSpec &s, int ccd) { scene_sphere_wall(s, ccd != 0); }
void mk_hulls(SceneSpec &s, int) { scene_random_hulls(s); }
void mk_prims(SceneSpec &s, int) { scene_prim_pile(s); }

const SceneEntry kScenes[] = {
    {"3000_boxes", mk_3000, 0},     {"1000_stack", mk_1000, 0},   {"convex_stack", mk_convex, 0},
    {"prim_pile", mk_prims, 0},
    {"tower", mk_tower, 0},         {"mass_ratio_100", mk_ratio, 100}, {"mass_ratio_1000", mk_ratio, 1000},
    {"tiny_boxes", mk_tiny, 0},     {"huge_boxes", mk_huge, 0},   {"sphere_wall", mk_wall, 0},
    {"sphere_wall_ccd", mk_wall, 1}, {"random_hulls", mk_hulls, 0},
};

// ---- running one scene on one backend -----------------------------------------

struct Result {
    std::string backend;
    int steps = 0, bodies = 0;
    double ms = 0, collision_ms = 0, broadphase_ms = 0;  // medians
    double ms_mean = 0, collision_ms_mean = 0;            // means: sleeping makes the medians bimodal
    double pairs = 0, manifolds = 0, points = 0;        // means per step
    double max_penetration = 0, drift = -1, ke_end = 0;
    double end_penetration = 0;                          // deepest at the last step (at rest, if the scene settles)
    double fallen = -1;                                  // bodies that fell (-1: not measured)
    int tunnelled = 0, referee_failures = 0;
    double divergence = -1;                              // max |p - p_native| at the end
    long minko_pairs = -1, native_pairs = -1;            // Minko narrowphase: algorithms on Minko / left to Bullet
    int trials = 1;                                      // figures are medians over this many perturbed runs
    std::vector<btVector3> end_pos;
    // Stability metrics over the trials (mean, standard deviation, trials
    // that have the metric): what separates a real difference from noise.
    struct Spread {
        double mean = 0, sd = 0;
        int n = 0;
    };
    Spread spread[5];  // in kStability order
};

// The stability metrics whose spread over the trials is reported, lower is
// better for each (tunnelling is the worst trial's, not a spread).
struct StabilityMetric {
    const char *name;
    double Result::*field;
};
const StabilityMetric kStability[] = {{"max_penetration", &Result::max_penetration},
                                      {"end_penetration", &Result::end_penetration},
                                      {"fallen", &Result::fallen},
                                      {"drift", &Result::drift},
                                      {"ke_end", &Result::ke_end}};
static_assert(sizeof kStability / sizeof kStability[0] == sizeof Result().spread / sizeof Result().spread[0],
              "one spread per stability metric");

double mean(const std::vector<double> &v)
{
    double s = 0;
    for (double x : v) s += x;
    return v.empty() ? 0 : s / (double)v.size();
}

double median(std::vector<double> v)
{
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

bool is_dynamic(const btCollisionObject *o) { return !o->isStaticOrKinematicObject(); }

// The referee: the deepest penetration among pairs whose tight AABBs overlap,
// on the solids as Bullet's support functions define them (sharp boxes,
// hulls and cylinders grown by their margin). One judge for every backend, so
// no backend grades its own contacts. Pairs with a hull go to Bullet's
// GJK-EPA, which sees exactly that solid for hulls; all others to the exact
// long double oracle (tests/support/oracle.h), because Bullet's GJK-EPA
// rounds a box's corners by its margin.
class Referee {
public:
    ~Referee()
    {
        for (auto &kv : m_shapes) {
            if (kv.second.ok) mk_oracle_shape_free(&kv.second.shape);
        }
    }
    // Penetration depth (>= 0) of a pair, or -1 when it cannot judge it.
    double depth(const btCollisionObject *a, const btCollisionObject *b)
    {
        const btCollisionShape *sa = a->getCollisionShape(), *sb = b->getCollisionShape();
        if (!sa->isConvex() && sa->getShapeType() != STATIC_PLANE_PROXYTYPE) return -1;
        if (!sb->isConvex() && sb->getShapeType() != STATIC_PLANE_PROXYTYPE) return -1;
        if (sa->getShapeType() == CONVEX_HULL_SHAPE_PROXYTYPE || sb->getShapeType() == CONVEX_HULL_SHAPE_PROXYTYPE) {
            btGjkEpaSolver2::sResults r;
            btVector3 guess = a->getWorldTransform().getOrigin() - b->getWorldTransform().getOrigin();
            if (guess.length2() == 0) guess = btVector3(1, 0, 0);
            if (!btGjkEpaSolver2::Penetration((const btConvexShape *)sa, a->getWorldTransform(), (const btConvexShape *)sb,
                                              b->getWorldTransform(), guess, r, true))
                return r.status == btGjkEpaSolver2::sResults::EPA_Failed ? -1 : 0;
            return std::isfinite((double)r.distance) ? std::max(0.0, -(double)r.distance) : -1;
        }
        Entry *ea = entry(sa), *eb = entry(sb);
        if (!ea || !eb) return -1;
        mk_oracle_pose pa = mk_oracle_pose_of(mkb::minko_pose(a->getWorldTransform(), ea->map));
        mk_oracle_pose pb = mk_oracle_pose_of(mkb::minko_pose(b->getWorldTransform(), eb->map));
        mk_oracle_result r;
        if (mk_oracle_query(&ea->shape, &pa, &eb->shape, &pb, 0, &r) != 0) return -1;
        return std::max(0.0, -(double)r.distance);
    }

private:
    struct Entry {
        bool ok;
        mkb::ShapeMap map;
        mk_oracle_shape shape;
    };
    Entry *entry(const btCollisionShape *s)
    {
        auto it = m_shapes.find(s);
        if (it == m_shapes.end()) {
            Entry e;
            e.ok = mkb::map_primitive(s, &e.map) == MK_OK && mk_oracle_shape_init(&e.shape, &e.map.shape) == 0;
            it = m_shapes.insert(std::make_pair(s, e)).first;
        }
        return it->second.ok ? &it->second : nullptr;
    }
    std::map<const btCollisionShape *, Entry> m_shapes;
};

double referee_penetration(btCollisionWorld *world, Referee *referee, int *failures)
{
    double deepest = 0;
    btBroadphasePairArray &pairs = world->getPairCache()->getOverlappingPairArray();
    for (int i = 0; i < pairs.size(); i++) {
        const btCollisionObject *a = (const btCollisionObject *)pairs[i].m_pProxy0->m_clientObject;
        const btCollisionObject *b = (const btCollisionObject *)pairs[i].m_pProxy1->m_clientObject;
        if (!is_dynamic(a) && !is_dynamic(b)) continue;
        btVector3 amin, amax, bmin, bmax;
        a->getCollisionShape()->getAabb(a->getWorldTransform(), amin, amax);
        b->getCollisionShape()->getAabb(b->getWorldTransform(), bmin, bmax);
        if (!TestAabbAgainstAabb2(amin, amax, bmin, bmax)) continue;
        double d = referee->depth(a, b);
        if (d < 0) ++*failures;
        else deepest = std::max(deepest, d);
    }
    return deepest;
}

double kinetic_energy(const std::vector<btRigidBody *> &bodies)
{
    double ke = 0;
    for (const btRigidBody *b : bodies) {
        if (b->getInvMass() == 0) continue;
        const btVector3 &v = b->getLinearVelocity(), &w = b->getAngularVelocity();
        btVector3 iw = b->getInvInertiaTensorWorld().inverse() * w;
        ke += 0.5 * (double)(v.length2() / b->getInvMass()) + 0.5 * (double)w.dot(iw);
    }
    return ke;
}

// One scene on one backend: the world, its bodies and what is measured. The
// backends of a scene advance together, one step each in turn, so a load
// spike on a shared machine hits them all alike and their ratios hold.
class Run {
public:
    // Trial 0 is the scene as specified; trial k > 0 moves every dynamic
    // body's start by up to 1e-3 of its bounding radius per axis (seeded by
    // k and the body, the same for every backend).
    Run(const SceneSpec &scene, const Backend &backend, int steps, int trial)
        : m_scene(scene), m_pipe(backend), m_steps(steps), m_trial(trial),
          m_drift_step(scene.drift_from < 0 ? -1 : (int)(scene.drift_from * steps))
    {
        m_res.backend = std::string(kBulletTag) + "." + backend.name;
        m_res.steps = steps;
        btDiscreteDynamicsWorld *world = m_pipe.world;
        world->setGravity(btVector3(0, -10, 0));
        world->getSolverInfo().m_numIterations = scene.iterations;
        if (scene.friction_caching) world->getSolverInfo().m_solverMode |= SOLVER_ENABLE_FRICTION_DIRECTION_CACHING;
        for (const BodySpec &bs : scene.bodies) add_body(bs);
        m_res.bodies = scene.dynamic_count();
    }
    ~Run()
    {
        for (btRigidBody *b : m_bodies) {
            m_pipe.world->removeRigidBody(b);
            delete b;
        }
    }
    Run(const Run &) = delete;
    Run &operator=(const Run &) = delete;

    // Identical-pose mode (--shadow): before each step this run's dynamic
    // bodies take the other run's state (pose, velocities, sleep), so its
    // collision pipeline meets the other's poses and its solver starts from
    // the other's state; only the contacts and their warm-start history
    // (what each pipeline's manifolds carried over) differ.
    void take_state_of(const Run &from)
    {
        for (size_t i = 0; i < m_bodies.size(); i++) {
            btRigidBody *d = m_bodies[i];
            const btRigidBody *s = from.m_bodies[i];
            if (d->getInvMass() == 0) continue;
            d->setCenterOfMassTransform(s->getCenterOfMassTransform());
            d->setInterpolationWorldTransform(s->getInterpolationWorldTransform());
            d->setLinearVelocity(s->getLinearVelocity());
            d->setAngularVelocity(s->getAngularVelocity());
            d->setInterpolationLinearVelocity(s->getInterpolationLinearVelocity());
            d->setInterpolationAngularVelocity(s->getInterpolationAngularVelocity());
            d->forceActivationState(s->getActivationState());
            d->setDeactivationTime(s->getDeactivationTime());
        }
    }
    btDiscreteDynamicsWorld *world() const { return m_pipe.world; }
    const std::vector<btRigidBody *> &bodies() const { return m_bodies; }

    void step(int step)
    {
        btDiscreteDynamicsWorld *world = m_pipe.world;
        if (step == m_drift_step)
            for (btRigidBody *b : m_bodies) {
                btVector3 lo, hi;
                b->getCollisionShape()->getAabb(b->getWorldTransform(), lo, hi);
                m_drift_ref.push_back(b->getWorldTransform().getOrigin());
                m_drift_half.push_back(btScalar(0.5) * (hi.y() - lo.y()));  // gravity is -y in every scene
            }
        m_pipe.timers->reset();
        Clock::time_point t0 = Clock::now();
        world->stepSimulation(m_scene.dt, 0);
        m_t_step.push_back(ms_since(t0));
        m_t_coll.push_back(m_pipe.timers->collision_ms);
        m_t_bp.push_back(m_pipe.timers->aabb_ms + m_pipe.timers->pairs_ms);

        m_sum_pairs += world->getPairCache()->getNumOverlappingPairs();
        btDispatcher *d = world->getDispatcher();
        for (int m = 0; m < d->getNumManifolds(); m++) {
            int n = d->getManifoldByIndexInternal(m)->getNumContacts();
            m_sum_manifolds += n > 0;
            m_sum_points += n;
        }
        if (g_referee && (step % m_scene.judge_every == 0 || step == m_steps - 1)) {
            const double deepest = referee_penetration(world, &m_referee, &m_res.referee_failures);
            m_res.max_penetration = std::max(m_res.max_penetration, deepest);
            if (step == m_steps - 1) m_res.end_penetration = deepest;
        }
    }

    Result finish()
    {
        Result &res = m_res;
        res.ms = median(m_t_step);
        res.collision_ms = median(m_t_coll);
        res.broadphase_ms = median(m_t_bp);
        res.ms_mean = mean(m_t_step);
        res.collision_ms_mean = mean(m_t_coll);
        res.pairs = m_sum_pairs / m_steps;
        res.manifolds = m_sum_manifolds / m_steps;
        res.points = m_sum_points / m_steps;
        res.ke_end = kinetic_energy(m_bodies);
        if (m_pipe.minko_config) {
            res.minko_pairs = m_pipe.minko_config->stats.minko_algorithms.load();
            res.native_pairs = m_pipe.minko_config->stats.native_fallbacks.load();
        }
        if (m_drift_step >= 0) {
            int fallen = 0, standing = 0;
            double drift = 0;
            for (size_t i = 0; i < m_bodies.size(); i++) {
                if (m_bodies[i]->getInvMass() == 0) continue;
                const btVector3 &o = m_bodies[i]->getWorldTransform().getOrigin();
                if (m_drift_ref[i].y() - o.y() > m_drift_half[i]) {
                    fallen++;
                    continue;
                }
                standing++;
                drift = std::max(drift, (double)(o - m_drift_ref[i]).length());
            }
            res.fallen = fallen;
            res.drift = standing ? drift : -1;
        }
        for (size_t i = 0; i < m_bodies.size(); i++) {
            const BodySpec &bs = m_scene.bodies[i];
            btVector3 o = m_bodies[i]->getWorldTransform().getOrigin();
            res.end_pos.push_back(o);
            if (bs.has_keep && bs.keep_n.dot(o) > bs.keep_d) res.tunnelled++;
        }
        return res;
    }

private:
    void add_body(const BodySpec &bs)
    {
        btCollisionShape *shape = m_scene.shapes[bs.shape];
        btVector3 inertia(0, 0, 0);
        if (bs.mass > 0) shape->calculateLocalInertia(bs.mass, inertia);
        btRigidBody::btRigidBodyConstructionInfo info(bs.mass, nullptr, shape, inertia);
        info.m_startWorldTransform = bs.xf;
        if (m_trial > 0 && bs.mass > 0) {
            Rng rng(0x5EED0000ull * (unsigned long long)m_trial + m_bodies.size());
            btVector3 c;
            btScalar r;
            shape->getBoundingSphere(c, r);
            const btScalar e = btScalar(1e-3) * r;
            info.m_startWorldTransform.getOrigin() +=
                btVector3((btScalar)rng.range(-e, e), (btScalar)rng.range(-e, e), (btScalar)rng.range(-e, e));
        }
        info.m_friction = m_scene.friction;
        btRigidBody *body = new btRigidBody(info);
        if (bs.mass > 0) {
            body->setLinearVelocity(bs.v);
            body->setAngularVelocity(bs.w);
            if (!m_scene.sleep) body->setActivationState(DISABLE_DEACTIVATION);
            if (bs.ccd) {
                btVector3 c;
                btScalar r;
                shape->getBoundingSphere(c, r);
                body->setCcdMotionThreshold(r);
                body->setCcdSweptSphereRadius(r * btScalar(0.8));
            }
        }
        m_pipe.world->addRigidBody(body);
        m_bodies.push_back(body);
    }

    const SceneSpec &m_scene;
    Pipeline m_pipe;
    const int m_steps, m_trial, m_drift_step;
    Result m_res;
    std::vector<btRigidBody *> m_bodies;
    std::vector<btVector3> m_drift_ref;
    std::vector<btScalar> m_drift_half;  // half height of each body's box where drift starts
    std::vector<double> m_t_step, m_t_coll, m_t_bp;
    Referee m_referee;
    double m_sum_pairs = 0, m_sum_manifolds = 0, m_sum_points = 0;
};

// Each figure's median over the trials, but tunnelled bodies the worst trial's
// and referee failures summed (end positions: the first trial's). Drift is
// the median over the trials that have one (something stood), -1 if none.
Result median_of(const std::vector<Result> &trials)
{
    Result r = trials[0];
    auto med = [&trials](double Result::*f) {
        std::vector<double> v;
        for (const Result &t : trials)
            if (t.*f >= 0) v.push_back(t.*f);
        return v.empty() ? -1.0 : median(v);
    };
    for (double Result::*f : {&Result::ms, &Result::collision_ms, &Result::broadphase_ms, &Result::ms_mean,
                              &Result::collision_ms_mean, &Result::pairs, &Result::manifolds, &Result::points,
                              &Result::max_penetration, &Result::end_penetration, &Result::drift, &Result::fallen, &Result::ke_end,
                              &Result::divergence})
        r.*f = med(f);
    r.referee_failures = 0;
    for (const Result &t : trials) {
        r.tunnelled = std::max(r.tunnelled, t.tunnelled);
        r.referee_failures += t.referee_failures;
    }
    r.trials = (int)trials.size();
    for (size_t m = 0; m < sizeof kStability / sizeof kStability[0]; m++) {
        std::vector<double> v;
        for (const Result &t : trials)
            if (t.*kStability[m].field >= 0) v.push_back(t.*kStability[m].field);
        Result::Spread &sp = r.spread[m];
        sp.n = (int)v.size();
        sp.mean = mean(v);
        double ss = 0;
        for (double x : v) ss += (x - sp.mean) * (x - sp.mean);
        sp.sd = sp.n > 1 ? std::sqrt(ss / (sp.n - 1)) : 0;  // sample standard deviation
    }
    return r;
}

// How a backend's metric compares with native's over the trials: "noise"
// when the means differ by less than twice the standard error of their
// difference (Welch; about one trial standard deviation at 7 trials), so a
// difference inside the spread between trials is not called a win or a loss.
const char *verdict(const Result::Spread &m, const Result::Spread &native)
{
    if (m.n == 0 || native.n == 0) return "-";
    const double se = std::sqrt(m.sd * m.sd / m.n + native.sd * native.sd / native.n);
    const double d = m.mean - native.mean;
    if (d == 0) return "same";
    if (std::fabs(d) <= 2 * se) return "noise";
    return d < 0 ? "better" : "worse";
}

// ---- identical-pose comparison (--shadow) -----------------------------------------

// Per pair type, what a backend's contacts do differently from native's on
// the same poses: each step the backend's bodies take native's state
// (Run::take_state_of), both step, and their manifolds are compared pair by
// pair (after the solve: points, impulses and lifetimes as the solver left
// them). A pair is keyed by its two bodies' world indices, low first; normals
// and points are turned to that order (normal towards the low body, point on
// the high one).
struct ShadowStats {
    long both = 0, only_native = 0, only_other = 0;
    double pts[2] = {0, 0}, impulse[2] = {0, 0}, lateral[2] = {0, 0}, fresh[2] = {0, 0}, life[2] = {0, 0};
    long normal_differs = 0;
    double depth_diff = 0, depth_absdiff = 0, nearest = 0;
    long nearest_n = 0;
};

struct ShadowPair {
    const btPersistentManifold *m;
    bool low_first;  // body 0 is the pair's low index
};

// Worst disagreement seen: the pair, the step and both bodies' poses, to
// re-run the pair alone.
struct ShadowWorst {
    double score = -1;  // depth gap, or angle between the normals
    int step = -1, lo = -1, hi = -1;
    double depth[2] = {0, 0};
    btVector3 normal[2];
    btTransform xf[2];
    int pts[2] = {0, 0};
};

struct Shadow {
    std::map<std::string, ShadowStats> by_type;
    double ke_native = 0, ke_other = 0, dv_max = 0;
    double late_ke_native = 0, late_ke_other = 0;  // the last third of the steps, where a pile settles
    long steps = 0, late_steps = 0;
    // Bodies below Bullet's sleeping thresholds before the step: their KE
    // after it, and how many of them the step woke (jitter a pile cannot
    // fall asleep through).
    double rest_ke[2] = {0, 0};
    long rest_bodies = 0, rest_woken[2] = {0, 0};
    ShadowWorst worst_depth, worst_normal;  // normal: pairs both see deeper than 1e-3
};

std::map<std::pair<int, int>, ShadowPair> shadow_pairs(btCollisionWorld *world)
{
    std::map<std::pair<int, int>, ShadowPair> out;
    btDispatcher *d = world->getDispatcher();
    for (int k = 0; k < d->getNumManifolds(); k++) {
        const btPersistentManifold *m = d->getManifoldByIndexInternal(k);
        if (m->getNumContacts() == 0) continue;
        const int i0 = m->getBody0()->getWorldArrayIndex(), i1 = m->getBody1()->getWorldArrayIndex();
        out[std::make_pair(std::min(i0, i1), std::max(i0, i1))] = ShadowPair{m, i0 < i1};
    }
    return out;
}

std::string shadow_type(const btCollisionObject *a, const btCollisionObject *b)
{
    std::string ta = a->getCollisionShape()->getName(), tb = b->getCollisionShape()->getName();
    if (tb < ta) std::swap(ta, tb);
    return ta + "-" + tb + (a->isStaticObject() || b->isStaticObject() ? " (static)" : "");
}

// The deepest point's index, and the manifold's impulse sums.
int deepest_point(const btPersistentManifold *m)
{
    int best = 0;
    for (int i = 1; i < m->getNumContacts(); i++)
        if (m->getContactPoint(i).getDistance() < m->getContactPoint(best).getDistance()) best = i;
    return best;
}

btVector3 point_on_high(const ShadowPair &p, int i)
{
    const btManifoldPoint &c = p.m->getContactPoint(i);
    return p.low_first ? c.getPositionWorldOnB() : c.getPositionWorldOnA();
}

// Whether a body is below its sleeping thresholds (btRigidBody::wantsSleeping's test).
bool below_sleep_thresholds(const btRigidBody *b)
{
    const btScalar lin = b->getLinearSleepingThreshold(), ang = b->getAngularSleepingThreshold();
    return b->getLinearVelocity().length2() < lin * lin && b->getAngularVelocity().length2() < ang * ang;
}

// `resting`: per body, whether native's was below its sleeping thresholds
// before the step (the state both worlds started from).
void shadow_compare(const Run &native, const Run &other, int step, bool late, const std::vector<char> &resting,
                    Shadow *sh)
{
    const Run *runs[2] = {&native, &other};
    for (size_t i = 0; i < resting.size(); i++) {
        if (!resting[i]) continue;
        sh->rest_bodies++;
        for (int w = 0; w < 2; w++) {
            std::vector<btRigidBody *> one(1, runs[w]->bodies()[i]);
            sh->rest_ke[w] += kinetic_energy(one);
            sh->rest_woken[w] += !below_sleep_thresholds(one[0]);
        }
    }
    const double ke[2] = {kinetic_energy(native.bodies()), kinetic_energy(other.bodies())};
    sh->steps++;
    sh->ke_native += ke[0];
    sh->ke_other += ke[1];
    if (late) {
        sh->late_steps++;
        sh->late_ke_native += ke[0];
        sh->late_ke_other += ke[1];
    }
    for (size_t i = 0; i < native.bodies().size(); i++) {
        const btRigidBody *a = native.bodies()[i], *b = other.bodies()[i];
        sh->dv_max = std::max(sh->dv_max, (double)(a->getLinearVelocity() - b->getLinearVelocity()).length());
    }
    std::map<std::pair<int, int>, ShadowPair> pn = shadow_pairs(native.world()), po = shadow_pairs(other.world());
    for (auto &kv : pn) po.insert(std::make_pair(kv.first, ShadowPair{nullptr, true}));
    for (auto &kv : po) {
        auto itn = pn.find(kv.first);
        const ShadowPair *pair[2] = {itn == pn.end() ? nullptr : &itn->second, kv.second.m ? &kv.second : nullptr};
        const ShadowPair *any = pair[0] ? pair[0] : pair[1];
        ShadowStats &st = sh->by_type[shadow_type(any->m->getBody0(), any->m->getBody1())];
        if (!pair[0] || !pair[1]) {
            (pair[0] ? st.only_native : st.only_other)++;
            continue;
        }
        st.both++;
        double depth[2];
        btVector3 normal[2];
        for (int w = 0; w < 2; w++) {
            const btPersistentManifold *m = pair[w]->m;
            st.pts[w] += m->getNumContacts();
            for (int i = 0; i < m->getNumContacts(); i++) {
                const btManifoldPoint &c = m->getContactPoint(i);
                st.impulse[w] += c.getAppliedImpulse();
                st.lateral[w] += std::sqrt(c.m_appliedImpulseLateral1 * c.m_appliedImpulseLateral1 +
                                           c.m_appliedImpulseLateral2 * c.m_appliedImpulseLateral2);
                st.fresh[w] += c.getLifeTime() <= 1;
                st.life[w] += c.getLifeTime();
            }
            const btManifoldPoint &c = m->getContactPoint(deepest_point(m));
            depth[w] = -(double)c.getDistance();
            normal[w] = pair[w]->low_first ? c.m_normalWorldOnB : -c.m_normalWorldOnB;
        }
        const bool differs = normal[0].dot(normal[1]) < btScalar(1 - 5e-7);  // about 1e-3 rad
        st.normal_differs += differs;
        st.depth_diff += depth[1] - depth[0];
        st.depth_absdiff += std::fabs(depth[1] - depth[0]);
        for (int i = 0; i < pair[0]->m->getNumContacts(); i++) {
            double best = 1e300;
            for (int j = 0; j < pair[1]->m->getNumContacts(); j++)
                best = std::min(best, (double)(point_on_high(*pair[0], i) - point_on_high(*pair[1], j)).length());
            st.nearest += best;
            st.nearest_n++;
        }
        const double angle = std::acos(std::min(1.0, std::max(-1.0, (double)normal[0].dot(normal[1]))));
        const double scores[2] = {std::fabs(depth[1] - depth[0]), std::min(depth[0], depth[1]) > 1e-3 ? angle : -1};
        ShadowWorst *worst[2] = {&sh->worst_depth, &sh->worst_normal};
        for (int k = 0; k < 2; k++) {
            if (scores[k] <= worst[k]->score) continue;
            ShadowWorst &w = *worst[k];
            w.score = scores[k];
            w.step = step;
            w.lo = kv.first.first;
            w.hi = kv.first.second;
            for (int j = 0; j < 2; j++) {
                w.depth[j] = depth[j];
                w.normal[j] = normal[j];
                w.pts[j] = pair[j]->m->getNumContacts();
                w.xf[j] = native.bodies()[(size_t)(j ? w.hi : w.lo)]->getWorldTransform();
            }
        }
    }
}

// --shadow-pair LO HI STEP: every point of that pair in both worlds at that
// step (after the solve), in the pair's low-first order.
struct ShadowProbe {
    int lo = -1, hi = -1, step = -1;
};
ShadowProbe g_probe;

void shadow_dump(const Run &native, const Run &other, int step)
{
    if (step != g_probe.step) return;
    const Run *runs[2] = {&native, &other};
    for (int w = 0; w < 2; w++) {
        std::map<std::pair<int, int>, ShadowPair> pairs = shadow_pairs(runs[w]->world());
        auto it = pairs.find(std::make_pair(g_probe.lo, g_probe.hi));
        std::printf("  step %d pair %d-%d %s:%s\n", step, g_probe.lo, g_probe.hi, w ? "other" : "native",
                    it == pairs.end() ? " no points" : "");
        if (it == pairs.end()) continue;
        const ShadowPair &p = it->second;
        for (int i = 0; i < p.m->getNumContacts(); i++) {
            const btManifoldPoint &c = p.m->getContactPoint(i);
            const btVector3 q = point_on_high(p, i), n = p.low_first ? c.m_normalWorldOnB : -c.m_normalWorldOnB;
            std::printf("    [%d] on_high (%.6f %.6f %.6f) n (%.5f %.5f %.5f) dist %.3e life %d imp %.4g lat %.4g %.4g "
                        "part %d/%d idx %d/%d flags %d\n",
                        i, (double)q.x(), (double)q.y(), (double)q.z(), (double)n.x(), (double)n.y(), (double)n.z(),
                        (double)c.getDistance(), c.getLifeTime(), (double)c.getAppliedImpulse(),
                        (double)c.m_appliedImpulseLateral1, (double)c.m_appliedImpulseLateral2, c.m_partId0, c.m_partId1,
                        c.m_index0, c.m_index1, c.m_contactPointFlags);
        }
    }
}

void print_shadow(const SceneSpec &s, const std::string &backend, const Shadow &sh)
{
    std::printf("\nidentical poses: %s, %s against native, %ld steps (each step from native's state)\n", s.name.c_str(),
                backend.c_str(), sh.steps);
    std::printf("  KE after the step, mean over steps: native %.6g, %s %.6g (ratio %.4f); max |dv| of a body %.3g\n",
                sh.ke_native / (double)std::max(1L, sh.steps), backend.c_str(), sh.ke_other / (double)std::max(1L, sh.steps),
                sh.ke_native > 0 ? sh.ke_other / sh.ke_native : 0.0, sh.dv_max);
    std::printf("  bodies at rest before a step (%ld body-steps): KE after it native %.6g, %s %.6g (ratio %.4f); "
                "woken native %ld, %s %ld\n",
                sh.rest_bodies, sh.rest_ke[0], backend.c_str(), sh.rest_ke[1], sh.rest_ke[0] > 0 ? sh.rest_ke[1] / sh.rest_ke[0] : 0.0,
                sh.rest_woken[0], backend.c_str(), sh.rest_woken[1]);
    std::printf("  the same over the last third (%ld steps): native %.6g, %s %.6g (ratio %.4f)\n", sh.late_steps,
                sh.late_ke_native / (double)std::max(1L, sh.late_steps), backend.c_str(),
                sh.late_ke_other / (double)std::max(1L, sh.late_steps),
                sh.late_ke_native > 0 ? sh.late_ke_other / sh.late_ke_native : 0.0);
    std::printf("  %-28s %9s %7s %7s %11s %11s %8s %10s %10s %9s %9s %9s %9s %8s %8s %8s %8s\n", "pair type", "both", "only_n",
                "only_o", "pts n/o", "", "normal!=", "ddepth", "|ddepth|", "nearest", "imp n", "imp o", "lat n", "lat o",
                "fresh n", "fresh o", "life n/o");
    for (auto &kv : sh.by_type) {
        const ShadowStats &t = kv.second;
        const double b = (double)std::max(1L, t.both);
        std::printf("  %-28s %9ld %7ld %7ld %11.3f %11.3f %8.4f %10.3g %10.3g %9.3g %9.4g %9.4g %9.4g %8.4g %8.3f %8.3f %.0f/%.0f\n",
                    kv.first.c_str(), t.both, t.only_native, t.only_other, t.pts[0] / b, t.pts[1] / b,
                    (double)t.normal_differs / b, t.depth_diff / b, t.depth_absdiff / b,
                    t.nearest / (double)std::max(1L, t.nearest_n), t.impulse[0] / b, t.impulse[1] / b, t.lateral[0] / b,
                    t.lateral[1] / b, t.fresh[0] / std::max(1.0, t.pts[0]), t.fresh[1] / std::max(1.0, t.pts[1]),
                    t.life[0] / std::max(1.0, t.pts[0]), t.life[1] / std::max(1.0, t.pts[1]));
    }
    const ShadowWorst *worst[2] = {&sh.worst_depth, &sh.worst_normal};
    const char *title[2] = {"largest deepest-point depth gap", "largest angle between the normals (both deeper than 1e-3)"};
    for (int t = 0; t < 2; t++) {
        const ShadowWorst &w = *worst[t];
        if (w.step < 0) continue;
        std::printf("  %s %.3g: step %d, bodies %d and %d: depth native %.6g (%d pts), %s %.6g (%d pts); "
                    "normals (%.6f %.6f %.6f) / (%.6f %.6f %.6f)\n",
                    title[t], w.score, w.step, w.lo, w.hi, w.depth[0], w.pts[0], backend.c_str(), w.depth[1], w.pts[1], (double)w.normal[0].x(),
                    (double)w.normal[0].y(), (double)w.normal[0].z(), (double)w.normal[1].x(), (double)w.normal[1].y(),
                    (double)w.normal[1].z());
        for (int k = 0; k < 2; k++) {
            const btVector3 &o = w.xf[k].getOrigin();
            const btQuaternion q = w.xf[k].getRotation();
            std::printf("    body %d: origin (%.17g, %.17g, %.17g) rotation xyzw (%.17g, %.17g, %.17g, %.17g)\n", k ? w.hi : w.lo,
                        (double)o.x(), (double)o.y(), (double)o.z(), (double)q.x(), (double)q.y(), (double)q.z(), (double)q.w());
        }
    }
}

// ---- output ---------------------------------------------------------------------

void print_header()
{
    std::printf("%-13s %-13s %-20s %5s %5s %9s %9s %9s %9s %9s %6s %8s %8s %8s %10s %10s %5s %10s %10s %4s %10s\n",
                "scene", "variant", "backend", "bodies", "steps", "ms/step", "coll_ms", "ms_mean", "coll_mean", "bp_ms",
                "coll/n", "pairs", "manif", "points", "max_pen", "pen_end", "fell", "drift", "ke_end", "tun", "div_native");
}

void print_row(const SceneSpec &s, const Result &r, const Result &native)
{
    char drift[32] = "-", fell[32] = "-", div[32] = "-", ratio[32] = "-";
    if (r.drift >= 0) std::snprintf(drift, sizeof drift, "%.3g", r.drift);
    if (r.fallen >= 0) std::snprintf(fell, sizeof fell, "%.3g", r.fallen);
    if (r.divergence >= 0) std::snprintf(div, sizeof div, "%.3g", r.divergence);
    if (native.collision_ms > 0) std::snprintf(ratio, sizeof ratio, "%.2f", r.collision_ms / native.collision_ms);
    std::printf("%-13s %-13s %-20s %5d %5d %9.3f %9.3f %9.3f %9.3f %9.3f %6s %8.1f %8.1f %8.1f %10.3g %10.3g %5s %10s %10.3g %4d %10s\n",
                s.name.c_str(), s.variant.c_str(), r.backend.c_str(), r.bodies, r.steps, r.ms, r.collision_ms, r.ms_mean,
                r.collision_ms_mean, r.broadphase_ms, ratio, r.pairs, r.manifolds, r.points, r.max_penetration, r.end_penetration, fell, drift, r.ke_end,
                r.tunnelled, div);
    if (r.referee_failures) std::printf("    (referee: %d pairs it could not judge)\n", r.referee_failures);
    if (r.minko_pairs >= 0 && r.native_pairs > 0)
        std::printf("    (narrowphase: %ld pair algorithms on Minko, %ld left to Bullet by this build)\n", r.minko_pairs,
                    r.native_pairs);
}

// One line per scene and backend when a scene ran more than once: each
// stability metric as mean +- standard deviation over the trials, and the
// verdict against native (none on native's own line, or without native).
void print_spread(const SceneSpec &s, const Result &r, const Result *native)
{
    std::printf("  %-13s %-20s", s.name.c_str(), r.backend.c_str());
    for (size_t m = 0; m < sizeof kStability / sizeof kStability[0]; m++) {
        const Result::Spread &sp = r.spread[m];
        char cell[64] = "-";
        if (sp.n > 0) std::snprintf(cell, sizeof cell, "%.3g+-%.2g", sp.mean, sp.sd);
        if (native && sp.n > 0)
            std::snprintf(cell + std::strlen(cell), sizeof cell - std::strlen(cell), " %s", verdict(sp, native->spread[m]));
        std::printf(" %22s", cell);
    }
    std::printf("\n");
}

void write_json(FILE *f, const SceneSpec &s, const Result &r)
{
    std::fprintf(f,
                 "{\"suite\":\"bullet\",\"case\":\"%s\",\"variant\":\"%s\",\"backend\":\"%s\",\"n\":%d,\"bodies\":%d,"
                 "\"ms_per_frame\":%.6g,\"collision_ms_per_frame\":%.6g,\"space_ms_per_frame\":%.6g,"
                 "\"ms_per_frame_mean\":%.6g,\"collision_ms_per_frame_mean\":%.6g,"
                 "\"pairs\":%.6g,\"manifolds\":%.6g,\"points\":%.6g,\"max_penetration\":%.6g,\"end_penetration\":%.6g,\"ke_end\":%.6g,"
                 "\"tunnelled\":%d",
                 s.name.c_str(), s.variant.c_str(), r.backend.c_str(), r.steps, r.bodies, r.ms, r.collision_ms,
                 r.broadphase_ms, r.ms_mean, r.collision_ms_mean, r.pairs, r.manifolds, r.points, r.max_penetration, r.end_penetration, r.ke_end, r.tunnelled);
    if (r.trials > 1) {
        std::fprintf(f, ",\"trials\":%d", r.trials);
        for (size_t m = 0; m < sizeof kStability / sizeof kStability[0]; m++)
            if (r.spread[m].n > 0)
                std::fprintf(f, ",\"%s_mean\":%.6g,\"%s_sd\":%.6g", kStability[m].name, r.spread[m].mean,
                             kStability[m].name, r.spread[m].sd);
    }
    if (r.drift >= 0) std::fprintf(f, ",\"drift\":%.6g", r.drift);
    if (r.fallen >= 0) std::fprintf(f, ",\"fallen\":%.6g", r.fallen);
    if (r.divergence >= 0) std::fprintf(f, ",\"divergence_from_native\":%.6g", r.divergence);
    if (r.referee_failures) std::fprintf(f, ",\"failures\":%d", r.referee_failures);
    if (r.minko_pairs >= 0)
        std::fprintf(f, ",\"minko_algorithms\":%ld,\"native_fallbacks\":%ld", r.minko_pairs, r.native_pairs);
    std::fprintf(f, "}\n");
}

void usage(const char *argv0)
{
    std::fprintf(stderr,
                 "usage: %s [--quick] [--json FILE] [--scene ID]... [--backend NAME]... [--steps N] [--bp KIND] [--list]\n"
                 "  --quick      a few-second subset (fewer scenes and steps)\n"
                 "  --scene ID   run only these scenes (repeatable; see --list)\n"
                 "  --backend N  run only these backends (repeatable; native runs too unless --no-native)\n"
                 "  --no-native  leave out the native reference (for profiling one backend)\n"
                 "  --no-referee no penetration referee (max_pen reads 0; for profiling)\n"
                 "  --steps N    override every scene's step count\n"
                 "  --trials N   run each scene N times, starts perturbed by 1e-3 of each body's size\n"
                 "               from the second on; every figure is the median over the trials, and\n"
                 "               a second table gives stability metrics as mean+-sd with a verdict vs native\n"
                 "  --per-trial  also print every trial's row (backend#trial; the table only)\n"
                 "  --shadow     identical poses: before each step every other backend takes native's\n"
                 "               body states; prints, per pair type, how its contacts differ from\n"
                 "               native's (points, normals, depths, impulses, lifetimes) instead of the tables\n"
                 "  --shadow-pair LO HI STEP  --shadow, and every point of bodies LO-HI's manifold at STEP\n"
                 "  --bp KIND    Minko broadphase structure: sap (default), auto, hgrid, brute\n"
                 "  --bp-margin M  how far Minko's filed boxes reach past Bullet's AABBs (default 0.05, Dbvt's)\n",
                 argv0);
}

}  // namespace

int main(int argc, char **argv)
{
    bool quick = false, list = false, no_native = false, per_trial = false, shadow = false;
    const char *json = nullptr;
    int steps_override = 0, trials = 1;
    std::vector<std::string> only_scenes, only_backends;
    for (int i = 1; i < argc; i++) {
        std::string a = argv[i];
        if (a == "--quick") quick = true;
        else if (a == "--list") list = true;
        else if (a == "--no-native") no_native = true;
        else if (a == "--no-referee") g_referee = false;
        else if (a == "--json" && i + 1 < argc) json = argv[++i];
        else if (a == "--scene" && i + 1 < argc) only_scenes.push_back(argv[++i]);
        else if (a == "--backend" && i + 1 < argc) only_backends.push_back(argv[++i]);
        else if (a == "--steps" && i + 1 < argc) steps_override = std::atoi(argv[++i]);
        else if (a == "--trials" && i + 1 < argc) trials = std::max(1, std::atoi(argv[++i]));
        else if (a == "--per-trial") per_trial = true;
        else if (a == "--shadow") shadow = true;
        else if (a == "--shadow-pair" && i + 3 < argc) {
            shadow = true;
            g_probe.lo = std::atoi(argv[++i]);
            g_probe.hi = std::atoi(argv[++i]);
            g_probe.step = std::atoi(argv[++i]);
        }
        else if (a == "--bp" && i + 1 < argc) {
            std::string k = argv[++i];
            g_bp_kind = k == "sap" ? MK_BP_SAP : k == "hgrid" ? MK_BP_HGRID : k == "brute" ? MK_BP_BRUTE : MK_BP_AUTO;
        } else if (a == "--bp-margin" && i + 1 < argc) {
            g_bp_margin = (btScalar)std::atof(argv[++i]);
        }
        else {
            usage(argv[0]);
            return 2;
        }
    }
    if (shadow) g_referee = false;  // the stability figures mean nothing there
    if (list) {
        for (const SceneEntry &e : kScenes) std::printf("scene   %s\n", e.id);
        for (const Backend &b : kBackends) std::printf("backend %s\n", b.name);
        return 0;
    }
    FILE *out = nullptr;
    if (json) {
        out = std::fopen(json, "w");
        if (!out) {
            std::perror(json);
            return 1;
        }
    }
    std::printf("bullet_scenes: Bullet %d (%s), %s run; times in ms per step: ms/step, coll_ms, bp_ms and coll/n are "
                "medians, ms_mean and coll_mean means (sleeping bodies make the medians bimodal); counts are means per step\n",
                btGetVersion(), kBulletTag, quick ? "quick" : "full");
    print_header();
    for (const SceneEntry &e : kScenes) {
        if (!only_scenes.empty() && std::find(only_scenes.begin(), only_scenes.end(), e.id) == only_scenes.end())
            continue;
        SceneSpec scene;
        e.make(scene, e.arg);
        if (quick && scene.quick_steps == 0 && only_scenes.empty()) continue;
        int steps = steps_override > 0 ? steps_override : (quick && scene.quick_steps ? scene.quick_steps : scene.steps);
        // Every selected backend, native first; stepped in turn, the first
        // of each round rotating so none always runs on the others' cache.
        std::vector<int> picked;
        for (int b = 0; b < kBackendCount; b++) {
            const Backend &be = kBackends[b];
            if (be.minko_ccd && !scene.uses_ccd()) continue;
            if (b == 0 && no_native) continue;
            if (b > 0 && !only_backends.empty() &&
                std::find(only_backends.begin(), only_backends.end(), be.name) == only_backends.end())
                continue;
            picked.push_back(b);
        }
        if (shadow && (picked[0] != 0 || picked.size() < 2)) {
            std::fprintf(stderr, "bullet_scenes: --shadow needs native and another backend\n");
            return 2;
        }
        if (picked.empty()) {
            std::fprintf(stderr, "bullet_scenes: no backend left for %s (--no-native with no other --backend)\n", e.id);
            continue;
        }
        // per_backend[k][t]: backend picked[k] in trial t.
        std::vector<std::vector<Result>> per_backend(picked.size());
        std::vector<Shadow> shadows(picked.size());
        for (int t = 0; t < trials; t++) {
            std::vector<Run *> runs;
            for (int b : picked) runs.push_back(new Run(scene, kBackends[b], steps, t));
            for (int step = 0; step < steps; step++) {
                std::vector<char> resting;
                if (shadow) {
                    for (size_t k = 1; k < runs.size(); k++) runs[k]->take_state_of(*runs[0]);
                    for (const btRigidBody *b : runs[0]->bodies())
                        resting.push_back(b->getInvMass() > 0 && below_sleep_thresholds(b));
                }
                for (size_t k = 0; k < runs.size(); k++) runs[(k + (size_t)step) % runs.size()]->step(step);
                if (shadow)
                    for (size_t k = 1; k < runs.size(); k++) {
                        shadow_compare(*runs[0], *runs[k], step, 3 * step >= 2 * steps, resting, &shadows[k]);
                        shadow_dump(*runs[0], *runs[k], step);
                    }
            }
            if (shadow) {
                for (Run *r : runs) delete r;
                continue;
            }
            for (size_t k = 0; k < runs.size(); k++) {
                per_backend[k].push_back(runs[k]->finish());
                delete runs[k];
            }
            if (picked[0] == 0)
                for (size_t k = 1; k < runs.size(); k++) {
                    Result &r = per_backend[k].back();
                    const Result &native = per_backend[0].back();
                    r.divergence = 0;
                    for (size_t i = 0; i < r.end_pos.size(); i++)
                        r.divergence = std::max(r.divergence, (double)(r.end_pos[i] - native.end_pos[i]).length());
                }
        }
        if (shadow) {
            for (size_t k = 1; k < picked.size(); k++)
                print_shadow(scene, std::string(kBulletTag) + "." + kBackends[picked[k]].name, shadows[k]);
            continue;
        }
        if (per_trial)
            for (size_t k = 0; k < picked.size(); k++)
                for (int t = 0; t < trials; t++) {
                    Result r = per_backend[k][(size_t)t];
                    r.backend += "#" + std::to_string(t);
                    print_row(scene, r, per_backend[0][(size_t)t]);
                }
        Result native;
        std::vector<Result> merged;
        for (size_t k = 0; k < picked.size(); k++) {
            merged.push_back(median_of(per_backend[k]));
            const Result &r = merged.back();
            if (picked[k] == 0) native = r;
            print_row(scene, r, native);
            if (out) write_json(out, scene, r);
            std::fflush(stdout);
        }
        if (trials > 1) {
            std::printf("  %d trials, mean+-sd (verdict vs native: noise = inside 2 standard errors)\n", trials);
            std::printf("  %-13s %-20s", "scene", "backend");
            for (const StabilityMetric &m : kStability) std::printf(" %22s", m.name);
            std::printf("\n");
            for (size_t k = 0; k < merged.size(); k++)
                print_spread(scene, merged[k], picked[0] == 0 && k > 0 ? &merged[0] : nullptr);
        }
    }
    if (out) std::fclose(out);
    return 0;
}

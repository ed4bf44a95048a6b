// bench_narrow: the narrowphase benchmark of issue 2 §5.
//
// Every case family of tests/support/cases.h (seeded, with exact long double
// references from the oracle) goes through every backend, one after another,
// in one process run: ns per query (best of several timed loops over the
// whole group, every backend warm and interleaved: see "timing" below),
// relative error of distance / depth, normal error,
// wrong booleans, failures. JSON Lines per ../shared/BENCH_FORMAT.md (suite
// "narrow", --json FILE) and a table with the verdicts.
//
// The double build (build/demos/bench_narrow) runs Minko double, libccd 2.1,
// Bullet 3.24 double and ODE 0.16 (double). The float build
// (build/single/demos/bench_narrow) runs Minko float and Bullet float: Bullet's
// float and double libraries export the same C++ symbols, and Minko's two
// builds the same C ones, so each precision gets its own process rather than a
// dlopen(RTLD_DEEPBIND) shim: simpler, no symbol games, and every comparison
// that matters (Minko against the competitors of its precision) stays inside
// one process. The float run appends to the same JSON file (--append).
//
// Backend conventions (checked by --selftest on cases with known answers):
// libccd and ODE answer only overlapping pairs (depth); for a separated pair
// they give a boolean and no distance. Bullet's btGjkEpaSolver2::SignedDistance
// works on the cores (no margins), so sphere and capsule radii (their Bullet
// margins) are subtracted here; boxes, hulls and cylinders get margin 0, so
// every backend sees the same geometry.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <btBulletCollisionCommon.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpa2.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkPairDetector.h>
#include <BulletCollision/NarrowPhaseCollision/btPointCollector.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>

extern "C" {
#include "minko/distance.h"
#include "minko/shape.h"
#include "support/cases.h"
#include "support/oracle.h"
}

#if !defined(MK_SINGLE)
#include <ccd/ccd.h>
#include <ode/ode.h>
#endif

namespace {

// ---- per-case geometry in double, shared by the competitor backends --------

struct Geo {
    mk_shape_type type;
    double radius;          // sphere / capsule radius (rounding)
    double h[3];            // box half extents
    double hh, disc;        // capsule / cylinder half height, cylinder radius
    double R[3][3], p[3];   // pose: x -> R x + p
    std::vector<double> v;  // hull vertices (xyz), from the oracle's hull
    const mk_oracle_poly *poly;
};

Geo make_geo(const mk_shape &s, mk_transform x, const mk_oracle_shape *o)
{
    Geo g;
    mk_oracle_pose P = mk_oracle_pose_of(x);
    g.type = s.type;
    g.radius = s.radius;
    g.h[0] = g.h[1] = g.h[2] = 0;
    g.hh = g.disc = 0;
    g.poly = o ? &o->core : nullptr;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) g.R[i][j] = (double)P.r[i][j];
    g.p[0] = (double)P.p.x, g.p[1] = (double)P.p.y, g.p[2] = (double)P.p.z;
    switch (s.type) {
    case MK_SHAPE_BOX: g.h[0] = s.u.half_extents.x, g.h[1] = s.u.half_extents.y, g.h[2] = s.u.half_extents.z; break;
    case MK_SHAPE_CAPSULE: g.hh = s.u.capsule.half_height; break;
    case MK_SHAPE_CYLINDER: g.hh = s.u.cylinder.half_height, g.disc = s.u.cylinder.radius; break;
    case MK_SHAPE_HULL:
        for (int i = 0; i < o->core.nv; ++i) {
            g.v.push_back((double)o->core.v[i].x);
            g.v.push_back((double)o->core.v[i].y);
            g.v.push_back((double)o->core.v[i].z);
        }
        break;
    default: break;
    }
    return g;
}

// ---- answers and metrics ------------------------------------------------------

struct Answer {
    double d;       // signed distance (valid if has_d)
    double n[3];    // unit normal A->B (valid if has_n)
    bool has_d, has_n, overlap, failed;
};

struct Backend {
    std::string name;
    bool depth_only;  // no distance for separated pairs (libccd, ODE, boolean-only)
    bool bool_only;   // no depth either (ccdGJKIntersect)
    bool closed_form_ref; // ODE: the yardstick of the closed-form families
    virtual ~Backend() {}
    // Builds per-case data for cases[0..n); false if the backend cannot take one of them.
    // Replaces whatever an earlier prepare() built (with --inproc one object
    // serves every group; in a child process it runs once).
    virtual bool prepare(const std::vector<const mk_case *> &cases) = 0;
    // Answers cases [lo, hi) into out[lo, hi).
    virtual void run(size_t lo, size_t hi, Answer *out) = 0;
};

bool finite3(const double *v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

double now_ns()
{
    return (double)std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
}


// ---- Minko ----------------------------------------------------------------------

// mk_distance, cold (no warm-start cache: the competitors start cold too).
// Row "minko": the mk_transform entry (checks both quaternions on every
// call and converts as much of them as the pair reads).
struct Minko : Backend {
    std::vector<mk_shape> a, b;
    std::vector<mk_transform> xa, xb;
    std::vector<mk_pose> pa, pb;
    Minko() { name = mk_is_double_precision() ? "minko" : "minko_f32", depth_only = bool_only = closed_form_ref = false; }
    bool prepare(const std::vector<const mk_case *> &cases) override
    {
        a.clear(), b.clear(), xa.clear(), xb.clear(), pa.clear(), pb.clear();
        for (const mk_case *c : cases) {
            mk_pose p, q;
            if (mk_pose_from_transform(c->xa, &p) != MK_OK || mk_pose_from_transform(c->xb, &q) != MK_OK) return false;
            a.push_back(c->a), b.push_back(c->b), xa.push_back(c->xa), xb.push_back(c->xb), pa.push_back(p), pb.push_back(q);
        }
        return true;
    }
    static void answer(mk_status st, const mk_distance_result &r, Answer &o)
    {
        o.has_d = o.has_n = st == MK_OK;
        o.d = r.distance;
        o.n[0] = r.normal.x, o.n[1] = r.normal.y, o.n[2] = r.normal.z;
        o.overlap = st == MK_OK && r.distance <= 0;
        o.failed = st != MK_OK || !std::isfinite(o.d) || !finite3(o.n);
    }
    void run(size_t lo, size_t hi, Answer *out) override
    {
        for (size_t i = lo; i < hi; ++i) {
            mk_distance_result r;
            answer(mk_distance(&a[i], xa[i], &b[i], xb[i], nullptr, &r), r, out[i]);
        }
    }
};

// Row "minko.pose": mk_distance_pose on poses made once per body, as an
// engine that keeps rotation matrices calls it (ODE's geoms carry theirs
// too): the row the verdicts judge.
struct MinkoPose : Minko {
    MinkoPose() { name += ".pose"; }
    void run(size_t lo, size_t hi, Answer *out) override
    {
        for (size_t i = lo; i < hi; ++i) {
            mk_distance_result r;
            answer(mk_distance_pose(&a[i], &pa[i], &b[i], &pb[i], nullptr, &r), r, out[i]);
        }
    }
};

// mk_overlap: the boolean query alone (touching counts as overlapping).
struct MinkoOverlap : Minko {
    MinkoOverlap() { name += ".overlap", bool_only = true; }
    void run(size_t lo, size_t hi, Answer *out) override
    {
        for (size_t i = lo; i < hi; ++i) {
            int hit = 0;
            mk_status st = mk_overlap(&a[i], xa[i], &b[i], xb[i], nullptr, &hit);
            out[i].has_d = out[i].has_n = false;
            out[i].overlap = hit != 0;
            out[i].failed = st != MK_OK;
        }
    }
};

// ---- Bullet (double or float, whichever this build links) -------------------------

#if defined(BT_USE_DOUBLE_PRECISION)
#define BULLET_TAG "bullet_f64"
#else
#define BULLET_TAG "bullet_f32"
#endif

btCollisionShape *bullet_shape(const Geo &g, double *margin)
{
    btConvexInternalShape *s = nullptr;
    *margin = 0;
    switch (g.type) {
    case MK_SHAPE_SPHERE: *margin = g.radius; return new btSphereShape((btScalar)g.radius);
    case MK_SHAPE_CAPSULE: *margin = g.radius; return new btCapsuleShapeZ((btScalar)g.radius, (btScalar)(2 * g.hh));
    case MK_SHAPE_BOX: s = new btBoxShape(btVector3((btScalar)g.h[0], (btScalar)g.h[1], (btScalar)g.h[2])); break;
    case MK_SHAPE_CYLINDER: s = new btCylinderShapeZ(btVector3((btScalar)g.disc, (btScalar)g.disc, (btScalar)g.hh)); break;
    case MK_SHAPE_HULL: {
        btConvexHullShape *h = new btConvexHullShape();
        for (size_t i = 0; i < g.v.size(); i += 3)
            h->addPoint(btVector3((btScalar)g.v[i], (btScalar)g.v[i + 1], (btScalar)g.v[i + 2]), false);
        h->recalcLocalAabb();
        s = h;
        break;
    }
    default: return nullptr;
    }
    s->setMargin(0); // boxes and cylinders keep their outer size (setMargin moves the core), hulls use their points
    return s;
}

btTransform bullet_xf(const Geo &g)
{
    btMatrix3x3 m((btScalar)g.R[0][0], (btScalar)g.R[0][1], (btScalar)g.R[0][2], (btScalar)g.R[1][0], (btScalar)g.R[1][1],
                  (btScalar)g.R[1][2], (btScalar)g.R[2][0], (btScalar)g.R[2][1], (btScalar)g.R[2][2]);
    return btTransform(m, btVector3((btScalar)g.p[0], (btScalar)g.p[1], (btScalar)g.p[2]));
}

struct BulletBase : Backend {
    std::vector<std::unique_ptr<btCollisionShape>> sa, sb;
    std::vector<btTransform> ta, tb;
    std::vector<double> margin; // sum of the two intrinsic margins (sphere / capsule radii)
    bool prepare(const std::vector<const mk_case *> &cases) override
    {
        sa.clear(), sb.clear(), ta.clear(), tb.clear(), margin.clear();
        for (const mk_case *c : cases) {
            Geo ga = make_geo(c->a, c->xa, c->oa), gb = make_geo(c->b, c->xb, c->ob);
            double ma, mb;
            btCollisionShape *a = bullet_shape(ga, &ma), *b = bullet_shape(gb, &mb);
            sa.emplace_back(a);
            sb.emplace_back(b);
            if (!a || !b) return false;
            ta.push_back(bullet_xf(ga));
            tb.push_back(bullet_xf(gb));
            margin.push_back(ma + mb);
        }
        return true;
    }
};

// btGjkPairDetector + btGjkEpaPenetrationDepthSolver, as btConvexConvexAlgorithm
// uses them: one detector per query, solvers reused.
struct BulletPair : BulletBase {
    BulletPair() { name = BULLET_TAG ".gjk_pair", depth_only = bool_only = closed_form_ref = false; }
    void run(size_t lo, size_t hi, Answer *out) override
    {
        btVoronoiSimplexSolver simplex;
        btGjkEpaPenetrationDepthSolver epa;
        for (size_t i = lo; i < hi; ++i) {
            btGjkPairDetector det(static_cast<btConvexShape *>(sa[i].get()), static_cast<btConvexShape *>(sb[i].get()),
                                  &simplex, &epa);
            btGjkPairDetector::ClosestPointInput in;
            btPointCollector res;
            in.m_transformA = ta[i];
            in.m_transformB = tb[i];
            det.getClosestPoints(in, res, nullptr);
            Answer &a = out[i];
            a.has_d = a.has_n = res.m_hasResult;
            a.d = res.m_distance;
            // normalOnBInWorld points from B towards A
            a.n[0] = -res.m_normalOnBInWorld.x(), a.n[1] = -res.m_normalOnBInWorld.y(), a.n[2] = -res.m_normalOnBInWorld.z();
            a.overlap = res.m_hasResult && a.d <= 0;
            a.failed = !res.m_hasResult || !std::isfinite(a.d) || !finite3(a.n);
        }
    }
};

// btGjkEpaSolver2::SignedDistance: GJK on the cores, EPA if they overlap.
struct BulletEpa2 : BulletBase {
    BulletEpa2() { name = BULLET_TAG ".gjk_epa2", depth_only = bool_only = closed_form_ref = false; }
    void run(size_t lo, size_t hi, Answer *out) override
    {
        for (size_t i = lo; i < hi; ++i) {
            btGjkEpaSolver2::sResults r;
            btVector3 guess = tb[i].getOrigin() - ta[i].getOrigin();
            bool ok = btGjkEpaSolver2::SignedDistance(static_cast<btConvexShape *>(sa[i].get()), ta[i],
                                                      static_cast<btConvexShape *>(sb[i].get()), tb[i], guess, r);
            Answer &a = out[i];
            // The normal is reported in A's local frame, from B towards A; the
            // witnesses are in world: take the world direction from A's basis.
            btVector3 n = -(ta[i].getBasis() * r.normal);
            a.has_d = a.has_n = ok;
            a.d = r.distance - margin[i];
            a.n[0] = n.x(), a.n[1] = n.y(), a.n[2] = n.z();
            a.overlap = ok && a.d <= 0;
            a.failed = !ok || !std::isfinite(a.d) || !finite3(a.n);
        }
    }
};

#if !defined(MK_SINGLE)

// ---- libccd 2.1 ------------------------------------------------------------------------

// The support function a libccd user writes: rotate the direction into the
// shape's frame, take the local support (a linear scan for hulls, as FCL's
// wrapper does), move it back.
void ccd_support(const void *obj, const ccd_vec3_t *dir, ccd_vec3_t *vec)
{
    const Geo &g = *static_cast<const Geo *>(obj);
    double d[3], s[3] = {0, 0, 0}, l;
    for (int i = 0; i < 3; ++i) d[i] = g.R[0][i] * dir->v[0] + g.R[1][i] * dir->v[1] + g.R[2][i] * dir->v[2];
    l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    switch (g.type) {
    case MK_SHAPE_BOX:
        for (int i = 0; i < 3; ++i) s[i] = d[i] >= 0 ? g.h[i] : -g.h[i];
        break;
    case MK_SHAPE_CAPSULE: s[2] = d[2] >= 0 ? g.hh : -g.hh; break;
    case MK_SHAPE_CYLINDER: {
        double r = std::sqrt(d[0] * d[0] + d[1] * d[1]);
        if (r > 0) s[0] = g.disc * d[0] / r, s[1] = g.disc * d[1] / r;
        s[2] = d[2] >= 0 ? g.hh : -g.hh;
        break;
    }
    case MK_SHAPE_HULL: {
        size_t best = 0;
        double bd = -HUGE_VAL;
        for (size_t i = 0; i < g.v.size(); i += 3) {
            double t = d[0] * g.v[i] + d[1] * g.v[i + 1] + d[2] * g.v[i + 2];
            if (t > bd) bd = t, best = i;
        }
        s[0] = g.v[best], s[1] = g.v[best + 1], s[2] = g.v[best + 2];
        break;
    }
    default: break;
    }
    if (g.radius > 0 && l > 0)
        for (int i = 0; i < 3; ++i) s[i] += g.radius * d[i] / l;
    for (int i = 0; i < 3; ++i) vec->v[i] = g.R[i][0] * s[0] + g.R[i][1] * s[1] + g.R[i][2] * s[2] + g.p[i];
}

void ccd_center(const void *obj, ccd_vec3_t *c)
{
    const Geo &g = *static_cast<const Geo *>(obj);
    for (int i = 0; i < 3; ++i) c->v[i] = g.p[i];
}

enum CcdMode { CCD_GJK_EPA, CCD_MPR, CCD_GJK_BOOL };

struct Ccd : Backend {
    CcdMode mode;
    ccd_t ccd;
    std::vector<Geo> ga, gb;
    // tol <= 0: libccd's defaults (EPA and MPR 1e-4, GJK 1e-6).
    Ccd(CcdMode m, double tol) : mode(m)
    {
        static const char *const names[] = {"libccd.gjk_epa", "libccd.mpr", "libccd.gjk_intersect"};
        name = names[m];
        if (tol > 0) name += "_tight";
        depth_only = true;
        bool_only = m == CCD_GJK_BOOL;
        closed_form_ref = false;
        CCD_INIT(&ccd);
        ccd.support1 = ccd.support2 = ccd_support;
        ccd.center1 = ccd.center2 = ccd_center;
        // libccd's default is unbounded; a cap keeps a stuck case from hanging the run.
        ccd.max_iterations = 1000;
        if (tol > 0) ccd.epa_tolerance = ccd.mpr_tolerance = ccd.dist_tolerance = tol;
    }
    bool prepare(const std::vector<const mk_case *> &cases) override
    {
        ga.clear(), gb.clear();
        for (const mk_case *c : cases) {
            ga.push_back(make_geo(c->a, c->xa, c->oa));
            gb.push_back(make_geo(c->b, c->xb, c->ob));
        }
        return true;
    }
    void run(size_t lo, size_t hi, Answer *out) override
    {
        for (size_t i = lo; i < hi; ++i) {
            Answer &a = out[i];
            ccd_real_t depth = 0;
            ccd_vec3_t dir, pos;
            int r;
            dir.v[0] = dir.v[1] = dir.v[2] = 0;
            if (mode == CCD_GJK_BOOL) r = ccdGJKIntersect(&ga[i], &gb[i], &ccd) ? 0 : -1;
            else if (mode == CCD_MPR) r = ccdMPRPenetration(&ga[i], &gb[i], &ccd, &depth, &dir, &pos);
            else r = ccdGJKPenetration(&ga[i], &gb[i], &ccd, &depth, &dir, &pos);
            a.overlap = r == 0;
            a.has_d = a.has_n = r == 0 && mode != CCD_GJK_BOOL;
            a.d = -depth;
            // dir: the direction B must move to separate, i.e. A->B
            for (int k = 0; k < 3; ++k) a.n[k] = dir.v[k];
            a.failed = a.has_d && (!std::isfinite(a.d) || !finite3(a.n));
        }
    }
};

// ---- ODE 0.16 ----------------------------------------------------------------------------

struct OdeGeom {
    dGeomID g;
    std::vector<dReal> planes, points;
    std::vector<unsigned> polys;
};

bool ode_geom(const Geo &s, OdeGeom &o)
{
    switch (s.type) {
    case MK_SHAPE_SPHERE: o.g = dCreateSphere(0, s.radius); break;
    case MK_SHAPE_BOX: o.g = dCreateBox(0, 2 * s.h[0], 2 * s.h[1], 2 * s.h[2]); break;
    case MK_SHAPE_CAPSULE: o.g = dCreateCapsule(0, s.radius, 2 * s.hh); break;
    case MK_SHAPE_CYLINDER: o.g = dCreateCylinder(0, s.disc, 2 * s.hh); break;
    case MK_SHAPE_HULL: {
        // ODE needs planes and polygons: the oracle's hull provides them.
        const mk_oracle_poly *P = s.poly;
        for (int i = 0; i < P->nv; ++i)
            o.points.push_back((dReal)P->v[i].x), o.points.push_back((dReal)P->v[i].y), o.points.push_back((dReal)P->v[i].z);
        for (int f = 0; f < P->nf; ++f) {
            const mk_lvec3 n = P->fn[f], v0 = P->v[P->face_vert[P->face_first[f]]];
            o.planes.push_back((dReal)n.x), o.planes.push_back((dReal)n.y), o.planes.push_back((dReal)n.z);
            o.planes.push_back((dReal)(n.x * v0.x + n.y * v0.y + n.z * v0.z));
            o.polys.push_back((unsigned)(P->face_first[f + 1] - P->face_first[f]));
            for (int k = P->face_first[f]; k < P->face_first[f + 1]; ++k) o.polys.push_back((unsigned)P->face_vert[k]);
        }
        o.g = dCreateConvex(0, o.planes.data(), (unsigned)P->nf, o.points.data(), (unsigned)P->nv, o.polys.data());
        break;
    }
    default: return false;
    }
    dMatrix3 R;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) R[i * 4 + j] = s.R[i][j];
        R[i * 4 + 3] = 0;
    }
    dGeomSetPosition(o.g, s.p[0], s.p[1], s.p[2]);
    dGeomSetRotation(o.g, R);
    return true;
}

struct Ode : Backend {
    std::vector<std::unique_ptr<OdeGeom>> ga, gb;
    Ode() { name = "ode.dCollide", depth_only = true, bool_only = false, closed_form_ref = true; }
    bool prepare(const std::vector<const mk_case *> &cases) override
    {
        for (auto &g : ga)
            if (g->g) dGeomDestroy(g->g);
        for (auto &g : gb)
            if (g->g) dGeomDestroy(g->g);
        ga.clear(), gb.clear();
        for (const mk_case *c : cases) {
            ga.emplace_back(new OdeGeom());
            gb.emplace_back(new OdeGeom());
            if (!ode_geom(make_geo(c->a, c->xa, c->oa), *ga.back()) || !ode_geom(make_geo(c->b, c->xb, c->ob), *gb.back()))
                return false;
        }
        return true;
    }
    void run(size_t lo, size_t hi, Answer *out) override
    {
        dContactGeom contacts[16];
        for (size_t i = lo; i < hi; ++i) {
            int n = dCollide(ga[i]->g, gb[i]->g, 16, contacts, sizeof contacts[0]);
            Answer &a = out[i];
            int deepest = 0;
            for (int k = 1; k < n; ++k)
                if (contacts[k].depth > contacts[deepest].depth) deepest = k;
            a.overlap = n > 0;
            a.has_d = a.has_n = n > 0;
            a.d = n > 0 ? -contacts[deepest].depth : 0;
            // ODE's normal points into o1 (moving o1 along it separates): B->A
            for (int k = 0; k < 3; ++k) a.n[k] = n > 0 ? -contacts[deepest].normal[k] : 0;
            a.failed = n < 0 || (n > 0 && (!std::isfinite(a.d) || !finite3(a.n)));
        }
    }
};

#endif // !MK_SINGLE

// ---- statistics -----------------------------------------------------------------------------

double quantile(std::vector<double> v, double q)
{
    if (v.empty()) return NAN;
    std::sort(v.begin(), v.end());
    size_t k = (size_t)std::ceil(q * (double)v.size());
    return v[k == 0 ? 0 : std::min(k, v.size()) - 1];
}

struct Row {
    std::string family, variant, backend;
    size_t n;
    double ns;
    bool has_err, has_nrm;
    double rel_p50, rel_p99, rel_max, abs_size_p99, abs_size_max, nrm_p99, nrm_max;
    double ref_over_size;  // largest |reference| / size in the group
    int wrong_bool, failures;
};

// |ref| at or below this fraction of the size counts as touching: no boolean is wrong there.
const double TOUCH = 1e-14;

Row measure(const Backend &b, const std::vector<const mk_case *> &cs, const std::vector<Answer> &ans, double ns)
{
    Row r;
    std::vector<double> rel, absz, nrm;
    r.family = cs[0]->family, r.variant = cs[0]->variant, r.backend = b.name;
    r.n = cs.size(), r.ns = ns, r.wrong_bool = r.failures = 0, r.ref_over_size = 0;
    for (size_t i = 0; i < cs.size(); ++i) {
        const mk_case &c = *cs[i];
        const Answer &a = ans[i];
        r.ref_over_size = std::max(r.ref_over_size, std::fabs(c.distance) / c.size);
        bool touching = std::fabs(c.distance) <= TOUCH * c.size;
        if (a.failed) {
            ++r.failures;
            continue;
        }
        if (!touching && a.overlap != (c.distance <= 0)) ++r.wrong_bool;
        if (b.bool_only) continue;
        double d;
        if (a.has_d) d = a.d;
        else if (c.distance <= 0) d = 0; // a depth-only backend that saw no contact implies depth 0
        else continue;                   // separated and no distance asked of it
        double err = std::fabs(d - c.distance);
        rel.push_back(touching ? err / c.size : err / std::fabs(c.distance));
        absz.push_back(err / c.size);
        if (a.has_n && c.normal_defined) {
            mk_lvec3 ref = {c.normal[0], c.normal[1], c.normal[2]};
            nrm.push_back((double)mk_oracle_angle_deg(ref, a.n[0], a.n[1], a.n[2]));
        }
    }
    r.has_err = !rel.empty(), r.has_nrm = !nrm.empty();
    r.rel_p50 = quantile(rel, 0.5), r.rel_p99 = quantile(rel, 0.99), r.rel_max = quantile(rel, 1);
    r.abs_size_p99 = quantile(absz, 0.99), r.abs_size_max = quantile(absz, 1);
    r.nrm_p99 = quantile(nrm, 0.99), r.nrm_max = quantile(nrm, 1);
    return r;
}

// ---- verdicts -----------------------------------------------------------------------------------

// Minko's rows are never the yardstick; the verdicts judge mk_distance_pose
// (not the mk_transform row, shown beside it, nor the boolean-only mk_overlap row).
bool is_minko(const Row &r) { return r.backend.compare(0, 5, "minko") == 0; }
bool is_judged(const Row &r) { return r.backend == "minko.pose" || r.backend == "minko_f32.pose"; }
bool is_transform_row(const Row &r) { return r.backend == "minko" || r.backend == "minko_f32"; }

// Issue 2 targets, for the Minko row of a group. Where |d| is tiny against
// the size (the nearly-touching family, and regression cases within 1e-5 x
// size of contact: touching, kissing, +-1e-9, Jolt #2103) a relative error
// means nothing (1e-9 cannot be placed better than one ulp of the
// coordinates), so the absolute rule applies: error <= 1e-13 x size.
bool absolute_rule(const Row &m)
{
    return m.family == "nearly_touching" || (m.family == "regression" && m.ref_over_size <= 1e-5);
}

std::string accuracy_verdict(const Row &m, bool single)
{
    char buf[256];
    std::string miss;
    auto add = [&](const char *what, double got, double lim) {
        if (!(got <= lim)) {
            std::snprintf(buf, sizeof buf, "%s%s %.2g > %.0e (x%.3g)", miss.empty() ? "" : "; ", what, got, lim, got / lim);
            miss += buf;
        }
    };
    if (single) {
        bool applies = m.family != "tiny" && m.family != "thin_rods" && m.family != "nearly_touching" && m.family != "regression";
        if (!applies) return "float: no target on this family";
        if (m.has_err) add("rel p99", m.rel_p99, 1e-4);
    } else {
        if (absolute_rule(m)) add("abs err/size max", m.abs_size_max, 1e-13);
        else if (m.has_err) add("rel p99", m.rel_p99, 1e-10), add("rel max", m.rel_max, 1e-8);
        if (m.has_nrm) add("normal p99 deg", m.nrm_p99, 1e-6);
        if (m.wrong_bool) add("wrong bool", m.wrong_bool, 0);
    }
    if (m.failures) add("failures", m.failures, 0);
    return miss.empty() ? "accuracy met" : "accuracy MISSED: " + miss;
}

bool accurate(const Row &r)
{
    return r.has_err && r.rel_p99 <= 1e-6 && r.failures == 0 && r.wrong_bool <= 0.005 * (double)r.n;
}

struct Speed {
    const Row *ref = nullptr; // fastest accurate competitor (ODE on closed-form families)
    double ratio = NAN, target = NAN;
    std::string text;         // verdict for the table and the JSON
};

// The float build has no speed target: its summary names the fastest
// competitor within the float accuracy target (p99 <= 1e-4), for information.
Speed speed_verdict(const Row &m, const std::vector<Row> &rows, bool closed_form, bool single)
{
    char buf[256];
    Speed v;
    if (m.family == "regression") return v;
    for (const Row &r : rows) {
        if (is_minko(r)) continue;
        bool ok = single ? r.has_err && r.rel_p99 <= 1e-4 && r.failures == 0 && r.wrong_bool <= 0.005 * (double)r.n
                         : closed_form ? r.backend == "ode.dCollide" : accurate(r);
        if (ok && (!v.ref || r.ns < v.ref->ns)) v.ref = &r;
    }
    if (single) {
        if (v.ref) v.ratio = m.ns / v.ref->ns;
        return v;
    }
    if (!v.ref) {
        v.text = closed_form ? "speed: no ODE row" : "speed: no competitor with p99 <= 1e-6, 0 failures, <= 0.5% wrong booleans";
        return v;
    }
    v.ratio = m.ns / v.ref->ns, v.target = closed_form ? 1.0 : 1.0 / 3;
    if (v.ratio <= v.target)
        std::snprintf(buf, sizeof buf, "speed met: %.0f ns vs %s %.0f ns = x%.2f (target <= x%.2f)", m.ns,
                      v.ref->backend.c_str(), v.ref->ns, v.ratio, v.target);
    else
        std::snprintf(buf, sizeof buf, "speed MISSED by x%.2f: %.0f ns vs %s %.0f ns = x%.2f (target <= x%.2f)",
                      v.ratio / v.target, m.ns, v.ref->backend.c_str(), v.ref->ns, v.ratio, v.target);
    v.text = buf;
    return v;
}

// ---- output ---------------------------------------------------------------------------------------

void json_num(FILE *f, const char *key, double v)
{
    if (std::isfinite(v)) std::fprintf(f, ",\"%s\":%.6g", key, v);
}

void write_json(FILE *f, const Row &r, const std::string &acc, const std::string &speed)
{
    std::fprintf(f, "{\"suite\":\"narrow\",\"case\":\"%s\",\"variant\":\"%s\",\"backend\":\"%s\",\"n\":%zu", r.family.c_str(),
                 r.variant.c_str(), r.backend.c_str(), r.n);
    json_num(f, "ns_per_query", r.ns);
    if (r.has_err) {
        json_num(f, "rel_err_p50", r.rel_p50);
        json_num(f, "rel_err_p99", r.rel_p99);
        json_num(f, "rel_err_max", r.rel_max);
        json_num(f, "abs_err_over_size_p99", r.abs_size_p99);
        json_num(f, "abs_err_over_size_max", r.abs_size_max);
    }
    if (r.has_nrm) {
        json_num(f, "normal_err_deg_p99", r.nrm_p99);
        json_num(f, "normal_err_deg_max", r.nrm_max);
    }
    std::fprintf(f, ",\"wrong_bool\":%d,\"failures\":%d", r.wrong_bool, r.failures);
    if (!acc.empty()) std::fprintf(f, ",\"verdict_accuracy\":\"%s\"", acc.c_str());
    if (!speed.empty()) std::fprintf(f, ",\"verdict_speed\":\"%s\"", speed.c_str());
    std::fprintf(f, "}\n");
}

std::string fmt(bool have, double v)
{
    char buf[32];
    if (!have || !std::isfinite(v)) return "-";
    std::snprintf(buf, sizeof buf, "%.1e", v);
    return buf;
}

void print_row(const Row &r)
{
    std::printf("  %-26s %-28s %5zu %10.0f %8s %8s %8s %8s %5d %5d\n", (r.family + "/" + r.variant).substr(0, 26).c_str(),
                r.backend.c_str(), r.n, r.ns, fmt(r.has_err, r.rel_p50).c_str(), fmt(r.has_err, r.rel_p99).c_str(),
                fmt(r.has_err, r.rel_max).c_str(), fmt(r.has_nrm, r.nrm_p99).c_str(), r.wrong_bool, r.failures);
}

bool family_closed_form(const std::string &name)
{
    for (int f = 0; f < MK_FAM_COUNT; ++f)
        if (name == mk_family_name((mk_family)f)) return mk_family_closed_form((mk_family)f) != 0;
    return false;
}

// Rows of one group (printed with --table, the default of a full run), the
// verdicts on its Minko row, and one line for the summary.
void report_group(const std::vector<Row> &rows, bool single, bool table, FILE *json, std::vector<std::string> &summary)
{
    char buf[512];
    for (const Row &r : rows) {
        std::string acc;
        Speed sp;
        if (table) print_row(r);
        if (is_judged(r)) {
            acc = accuracy_verdict(r, single);
            sp = speed_verdict(r, rows, family_closed_form(r.family), single);
            if (table) std::printf("    -> %s%s%s\n", acc.c_str(), sp.text.empty() ? "" : " | ", sp.text.c_str());
            std::snprintf(buf, sizeof buf, "  %-26s %6.0f %8s", (r.family + "/" + r.variant).substr(0, 26).c_str(), r.ns,
                          fmt(r.has_err, r.rel_p99).c_str());
            std::string line = buf;
            if (sp.ref) {
                std::snprintf(buf, sizeof buf, " | %-22s %6.0f %8s | x%-5.2f", sp.ref->backend.substr(0, 22).c_str(),
                              sp.ref->ns, fmt(sp.ref->has_err, sp.ref->rel_p99).c_str(), sp.ratio);
                line += buf;
            } else {
                std::snprintf(buf, sizeof buf, " | %-22s %6s %8s | %-6s", "-", "", "", "");
                line += buf;
            }
            line += acc.compare(0, 14, "accuracy met") == 0 ? " | ok  " : acc.compare(0, 6, "float:") == 0 ? " | -   " : " | MISS";
            line += sp.text.empty() ? "     " : sp.text.compare(0, 9, "speed met") == 0 ? " ok  " : sp.ref ? " MISS" : " -   ";
            for (const Row &x : rows) // the mk_transform entry beside it, against the same competitor
                if (is_transform_row(x) && sp.ref) {
                    std::snprintf(buf, sizeof buf, " | %6.0f x%-5.2f", x.ns, x.ns / sp.ref->ns);
                    line += buf;
                }
            summary.push_back(line);
        }
        if (json) write_json(json, r, acc, sp.text);
    }
}

// Per backend over all groups: in how many it answers distance or depth
// (depth-only backends answer no separated group), in how many it is
// accurate (p99 <= 1e-6, no failures, <= 0.5% wrong booleans), its failures
// and wrong booleans, and the geometric mean of its ns per query.
void scoreboard(const std::vector<Row> &all)
{
    std::vector<std::string> names;
    for (const Row &r : all)
        if (std::find(names.begin(), names.end(), r.backend) == names.end()) names.push_back(r.backend);
    std::printf("\n  %-28s %7s %9s %9s %9s %9s %12s\n", "backend", "groups", "answers", "accurate", "failures", "wrong",
                "geomean ns");
    for (const std::string &n : names) {
        int groups = 0, answers = 0, acc = 0, fail = 0, wrong = 0;
        double logsum = 0;
        for (const Row &r : all)
            if (r.backend == n) {
                ++groups, answers += r.has_err, acc += accurate(r), fail += r.failures, wrong += r.wrong_bool;
                logsum += std::log(r.ns);
            }
        std::printf("  %-28s %7d %9d %9d %9d %9d %12.0f\n", n.c_str(), groups, answers, acc, fail, wrong,
                    std::exp(logsum / groups));
    }
}

// ---- isolation: each backend answers in child processes -------------------------
//
// A competitor may never return (libccd's EPA has no iteration cap and can
// creep forever at a tight tolerance) or crash (libccd #68: touching boxes).
// So every backend answers a group in a forked child that streams one answer
// per case through a pipe; if a case takes more than 2 s or the child dies,
// the parent kills it, counts that case as a failure (hang or crash) and
// starts a fresh child at the next case. A last child times the group over
// the cases that answered. Nothing here ever continues inside a process a
// library call was interrupted in.

const double CASE_TIMEOUT_MS = 2000;

bool write_all(int fd, const void *p, size_t n)
{
    const char *c = static_cast<const char *>(p);
    while (n > 0) {
        ssize_t k = write(fd, c, n);
        if (k <= 0) return false;
        c += k, n -= (size_t)k;
    }
    return true;
}

// Reads n bytes within timeout_ms; false on timeout, EOF or error.
bool read_all(int fd, void *p, size_t n, double timeout_ms)
{
    char *c = static_cast<char *>(p);
    double end = now_ns() + timeout_ms * 1e6;
    while (n > 0) {
        struct pollfd pf = {fd, POLLIN, 0};
        double left = (end - now_ns()) * 1e-6;
        if (left <= 0 || poll(&pf, 1, (int)left + 1) <= 0) return false;
        ssize_t k = read(fd, c, n);
        if (k <= 0) return false;
        c += k, n -= (size_t)k;
    }
    return true;
}

pid_t spawn(int *rfd)
{
    int fd[2];
    if (pipe(fd)) return -1;
    std::fflush(stdout);
    std::fflush(stderr);
    pid_t pid = fork();
    if (pid == 0) {
        close(fd[0]);
        *rfd = fd[1];
        return 0;
    }
    close(fd[1]);
    *rfd = fd[0];
    if (pid < 0) close(fd[0]);
    return pid;
}

void reap(pid_t pid, int fd)
{
    kill(pid, SIGKILL);
    waitpid(pid, nullptr, 0);
    close(fd);
}

struct Outcome {
    bool prepared = false;
    double ns = NAN;           // per query, over the good cases
    std::vector<Answer> ans;   // failed = true for a hang or crash
    std::vector<char> good;    // answered without hanging or crashing
};

// Child: answer cases [from, n) one by one, streaming (index, answer).
void child_answer(Backend &b, const std::vector<const mk_case *> &cs, size_t from, int fd)
{
    int ok = b.prepare(cs);
    if (!write_all(fd, &ok, sizeof ok) || !ok) return;
    std::vector<Answer> ans(cs.size());
    for (size_t i = from; i < cs.size(); ++i) {
        b.run(i, i + 1, ans.data());
        if (!write_all(fd, &i, sizeof i) || !write_all(fd, &ans[i], sizeof ans[i])) return;
    }
}

// ---- timing: every backend of a group in one process, interleaved ---------------------------
//
// The first backend timed after a group's cases are loaded pays for loading
// them (caches, branch predictors, copy-on-write faults in a fresh child), and
// a backend timed alone in its own short child samples whatever load the
// machine had in those few microseconds: two runs of one binary differed by up
// to 2x on a row. So once the answers are in, one process prepares every
// backend of the group, runs each once untimed over its cases (warm-up), then
// times `reps` rounds; round r runs the backends in an order rotated by r, so
// each takes every position and all of them sample the same load, and each
// timed loop follows one untimed pass of its own backend (the loops before it
// evicted its data: "warm caches" as before). A loop is >= 1000 queries and
// >= 100 us; it is timed in thread CPU time, so time slices given to the other
// processes of this shared machine do not count (wall time did: under load a
// few-ms loop of a slow backend was rarely left alone). ns per query is the
// best (minimum) loop of each backend, the same statistic for all (load only
// ever adds time). Rounds stop early, after 3, once the group's loops have
// taken 1 s of CPU time. A backend measures only the cases it answered
// without hanging or crashing (its `good` ones).

struct Lane {
    Backend *b;
    std::vector<char> good;
    size_t n_good;
    size_t inner; // passes per timed loop
    double ns;    // best loop, ns per query (NaN until timed)
};

const int MIN_ROUNDS = 3;
const double ROUND_BUDGET_NS = 1e9;
const size_t LOOP_QUERIES = 1000;
const double LOOP_MIN_NS = 1e5;

double cpu_ns()
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec * 1e9 + (double)t.tv_nsec;
}

// One pass of a backend over its good cases.
void pass(Lane &l, std::vector<Answer> &ans)
{
    for (size_t lo = 0, n = l.good.size(); lo < n;) {
        size_t hi = lo;
        while (hi < n && l.good[hi]) ++hi;
        if (hi > lo) l.b->run(lo, hi, ans.data());
        lo = hi + 1;
    }
}

// The schedule above. event(k, NaN) announces that lane k is about to
// prepare or run (a crash or hang is then its fault); event(k, ns) reports
// one timed loop. False if a lane fails to prepare.
template <class Event>
bool time_lanes(std::vector<Lane> &lanes, const std::vector<const mk_case *> &cs, int reps, Event event)
{
    std::vector<Answer> ans(cs.size());
    for (size_t k = 0; k < lanes.size(); ++k)
        if (event(k, NAN), !lanes[k].b->prepare(cs)) return false;
    for (size_t k = 0; k < lanes.size(); ++k) {
        Lane &l = lanes[k];
        event(k, NAN);
        double t = cpu_ns();
        pass(l, ans);
        double once = std::max(cpu_ns() - t, 1.0);
        l.inner = std::max((LOOP_QUERIES + l.n_good - 1) / l.n_good, (size_t)std::ceil(LOOP_MIN_NS / once));
    }
    double spent = 0;
    for (int r = 0; r < reps && (r < MIN_ROUNDS || spent < ROUND_BUDGET_NS); ++r)
        for (size_t j = 0; j < lanes.size(); ++j) {
            size_t k = (j + (size_t)r) % lanes.size();
            Lane &l = lanes[k];
            event(k, NAN);
            pass(l, ans); // the other backends' loops evicted this one's data: warm it again, untimed
            double t = cpu_ns();
            for (size_t i = 0; i < l.inner; ++i) pass(l, ans);
            double dt = cpu_ns() - t;
            spent += dt;
            event(k, dt / (double)(l.n_good * l.inner));
        }
    return true;
}

void keep_best(Lane &l, double ns)
{
    if (std::isnan(l.ns) || ns < l.ns) l.ns = ns;
}

// --inproc: the schedule in this process (for valgrind --tool=callgrind).
void time_inproc(std::vector<Lane> &lanes, const std::vector<const mk_case *> &cs, int reps)
{
    time_lanes(lanes, cs, reps, [&](size_t k, double ns) {
        if (!std::isnan(ns)) keep_best(lanes[k], ns);
    });
}

// The schedule in a child that streams (lane, ns) records, lane -1 at the
// end. If the child dies or hangs, the lane it was in gets no time and the
// schedule starts again without it, so the other lanes' figures still come
// from one process with every lane warm.
void time_isolated(std::vector<Lane> &lanes, const std::vector<const mk_case *> &cs, int reps)
{
    struct Rec {
        long lane;
        double ns;
    };
    std::vector<Lane> live = lanes;
    std::vector<size_t> id(lanes.size());
    for (size_t k = 0; k < id.size(); ++k) id[k] = k;
    while (!live.empty()) {
        int fd;
        pid_t pid = spawn(&fd);
        if (pid == 0) {
            Rec end = {-1, 0};
            if (time_lanes(live, cs, reps, [&](size_t k, double ns) {
                    Rec r = {(long)k, ns};
                    if (!write_all(fd, &r, sizeof r)) _exit(1);
                }))
                write_all(fd, &end, sizeof end);
            _exit(0);
        }
        if (pid < 0) return;
        for (Lane &l : live) l.ns = NAN;
        Rec r = {-2, 0};
        long culprit = -1;
        while (read_all(fd, &r, sizeof r, 600000) && r.lane >= 0) {
            culprit = r.lane;
            if (!std::isnan(r.ns)) keep_best(live[(size_t)r.lane], r.ns);
        }
        reap(pid, fd);
        if (r.lane == -1) break;
        if (culprit < 0) return; // died before any lane started: no times
        live.erase(live.begin() + culprit);
        id.erase(id.begin() + culprit);
    }
    for (size_t k = 0; k < live.size(); ++k) lanes[id[k]].ns = live[k].ns;
}

// --inproc answers: each backend in this process (a hang hangs the run).
Outcome answer_inproc(Backend &b, const std::vector<const mk_case *> &cs)
{
    Outcome o;
    o.ans.assign(cs.size(), Answer());
    o.good.assign(cs.size(), 1);
    if ((o.prepared = b.prepare(cs))) b.run(0, cs.size(), o.ans.data());
    return o;
}

// Answers in child processes; a case that hangs or crashes is a failure
// and leaves good[i] = 0.
Outcome answer_isolated(Backend &b, const std::vector<const mk_case *> &cs)
{
    Outcome o;
    o.good.assign(cs.size(), 1);
    o.ans.assign(cs.size(), Answer());
    for (size_t next = 0; next < cs.size();) {
        int fd, ok = 0;
        pid_t pid = spawn(&fd);
        if (pid == 0) {
            child_answer(b, cs, next, fd);
            _exit(0);
        }
        if (pid < 0) break;
        if (!read_all(fd, &ok, sizeof ok, 60000) || !ok) {
            reap(pid, fd);
            if (!ok) return o; // the backend does not take this group
            break;
        }
        o.prepared = true;
        for (;;) {
            size_t i;
            Answer a;
            if (!read_all(fd, &i, sizeof i, CASE_TIMEOUT_MS) || !read_all(fd, &a, sizeof a, 1000)) {
                o.ans[next] = Answer(), o.ans[next].failed = true, o.good[next] = 0; // hung or crashed
                ++next;
                break;
            }
            o.ans[i] = a;
            next = i + 1;
            if (next == cs.size()) break;
        }
        reap(pid, fd);
    }
    return o;
}

// Answers of every backend, then their times from one interleaved schedule.
std::vector<Outcome> run_group(std::vector<std::unique_ptr<Backend>> &backends, const std::vector<const mk_case *> &cs,
                               int reps, bool inproc)
{
    std::vector<Outcome> out;
    std::vector<Lane> lanes;
    std::vector<size_t> lane_of;
    for (auto &b : backends) {
        out.push_back(inproc ? answer_inproc(*b, cs) : answer_isolated(*b, cs));
        const Outcome &o = out.back();
        size_t n_good = (size_t)std::count(o.good.begin(), o.good.end(), 1);
        if (o.prepared && n_good > 0) lanes.push_back(Lane{b.get(), o.good, n_good, 1, NAN}), lane_of.push_back(out.size() - 1);
    }
    if (reps > 0) {
        if (inproc) time_inproc(lanes, cs, reps);
        else time_isolated(lanes, cs, reps);
    }
    for (size_t k = 0; k < lanes.size(); ++k) out[lane_of[k]].ns = lanes[k].ns;
    return out;
}

// ---- driver ------------------------------------------------------------------------------------------

struct Options {
    bool quick = false, append = false, selftest = false, list = false, table = false, inproc = false;
    const char *json = nullptr;
    std::vector<std::string> families, backends, variants;
    int reps = 0, n = 0;
};

std::vector<std::unique_ptr<Backend>> make_backends(const Options &o)
{
    std::vector<std::unique_ptr<Backend>> all, keep;
    all.emplace_back(new Minko());
    all.emplace_back(new MinkoPose());
    all.emplace_back(new MinkoOverlap());
#if !defined(MK_SINGLE)
    all.emplace_back(new Ccd(CCD_GJK_EPA, 0));
    all.emplace_back(new Ccd(CCD_GJK_EPA, 1e-12));
    all.emplace_back(new Ccd(CCD_MPR, 0));
    all.emplace_back(new Ccd(CCD_MPR, 1e-12));
    all.emplace_back(new Ccd(CCD_GJK_BOOL, 0));
#endif
    all.emplace_back(new BulletPair());
    all.emplace_back(new BulletEpa2());
#if !defined(MK_SINGLE)
    all.emplace_back(new Ode());
#endif
    for (auto &b : all)
        if (o.backends.empty() || std::find(o.backends.begin(), o.backends.end(), b->name) != o.backends.end())
            keep.push_back(std::move(b));
    return keep;
}

bool wanted_family(const Options &o, const char *name)
{
    return o.families.empty() || std::find(o.families.begin(), o.families.end(), name) != o.families.end();
}

// --variant takes a prefix ("sep" for separated, "touching" for both touching regressions).
bool wanted_variant(const Options &o, const std::string &name)
{
    for (const std::string &v : o.variants)
        if (name.compare(0, v.size(), v) == 0) return true;
    return o.variants.empty();
}

// A --family, --backend or --variant that names nothing would silently run
// nothing: refuse it (after the cases exist, so regression names are known).
bool filters_ok(const Options &o, const std::vector<std::unique_ptr<Backend>> &backends, const mk_case_set &set)
{
    bool ok = true;
    for (const std::string &f : o.families) {
        bool known = f == "regression";
        for (int k = 0; k < MK_FAM_COUNT; ++k) known = known || f == mk_family_name((mk_family)k);
        if (!known) std::fprintf(stderr, "bench_narrow: no family '%s' (see --list)\n", f.c_str()), ok = false;
    }
    for (const std::string &b : o.backends) {
        bool known = false;
        for (const auto &x : backends) known = known || x->name == b;
        if (!known) std::fprintf(stderr, "bench_narrow: no backend '%s' in this build (see --list)\n", b.c_str()), ok = false;
    }
    for (const std::string &v : o.variants) {
        bool known = false;
        for (int i = 0; i < set.count && !known; ++i) known = std::string(set.cases[i].variant).compare(0, v.size(), v) == 0;
        if (!known) std::fprintf(stderr, "bench_narrow: no variant starting with '%s' in the chosen families\n", v.c_str()), ok = false;
    }
    return ok;
}

int build_cases(const Options &o, mk_case_set *set)
{
    int n = o.n > 0 ? o.n : o.quick ? 10 : 200;
    for (int f = 0; f < MK_FAM_COUNT; ++f)
        if (wanted_family(o, mk_family_name((mk_family)f)) &&
            mk_cases_add_family(set, (mk_family)f, n, n, 1 + (uint64_t)f) != 0)
            return -1;
    if (wanted_family(o, "regression") && mk_cases_add_regressions(set)) return -1;
    return 0;
}

// Each backend's sign conventions on two known answers: unit cubes 1 apart
// along +x (distance 1, normal +x; depth-only backends must say "separated"),
// and libccd #17's small box 1 cm deep on a big one (normal +z).
int selftest(std::vector<std::unique_ptr<Backend>> &backends)
{
    mk_case_set set;
    mk_case gap;
    int bad = 0;
    std::memset(&set, 0, sizeof set);
    std::memset(&gap, 0, sizeof gap);
    if (mk_cases_add_regressions(&set)) return 1;
    gap.family = "selftest", gap.variant = "cubes_gap_x";
    mk_shape_box(mk_v3(0.5, 0.5, 0.5), 0, &gap.a);
    gap.b = gap.a;
    gap.xa = mk_transform_identity();
    gap.xb = mk_transform_make(mk_v3(2, 0, 0), mk_quat_identity());
    gap.distance = 1, gap.normal[0] = 1, gap.normal_defined = 1, gap.size = 0.8660254037844386;
    std::vector<const mk_case *> cs(1, &gap);
    for (int i = 0; i < set.count; ++i)
        if (!std::strcmp(set.cases[i].variant, "libccd17_5m_vs_0.2m")) cs.push_back(&set.cases[i]);
    for (auto &b : backends) {
        Outcome out = answer_isolated(*b, cs);
        const std::vector<Answer> &ans = out.ans;
        if (!out.prepared) continue;
        for (size_t i = 0; i < cs.size(); ++i) {
            const Answer &a = ans[i];
            const mk_case &c = *cs[i];
            int axis = i == 0 ? 0 : 2;
            bool want_overlap = c.distance <= 0, want_d = !b->bool_only && (want_overlap || !b->depth_only);
            bool ok = a.overlap == want_overlap && !a.failed &&
                      (!want_d || (a.has_d && std::fabs(a.d - c.distance) < 1e-6 && a.n[axis] > 0.99));
            std::printf("%-28s %-22s d %+.6f (ref %+.6f) n (%+.3f %+.3f %+.3f) %s\n", b->name.c_str(), c.variant,
                        a.has_d ? a.d : NAN, c.distance, a.n[0], a.n[1], a.n[2], ok ? "ok" : "WRONG");
            bad += !ok;
        }
    }
    mk_case_set_free(&set);
    return bad != 0;
}

void usage(const char *argv0)
{
    std::fprintf(stderr,
                 "usage: %s [--quick] [--table] [--json FILE [--append]] [--family NAME]... [--variant NAME]... [--backend NAME]...\n"
                 "          [--n N] [--reps N] [--list] [--selftest] [--inproc]\n"
                 "  --reps: timed rounds per group (default 20, --quick 3); each round times every backend once, in rotated order\n"
                 "  --quick: 10 + 10 cases per family, 3 rounds, summary only (--table adds every row)\n"
                 "  --variant: separated, penetrating, or a regression's name, or a prefix of one (\"sep\"; all by default)\n"
                 "  --inproc: no child processes (for valgrind --tool=callgrind; a hanging backend hangs the run)\n",
                 argv0);
}

} // namespace

int main(int argc, char **argv)
{
    Options o;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        if (a == "--quick") o.quick = true;
        else if (a == "--append") o.append = true;
        else if (a == "--selftest") o.selftest = true;
        else if (a == "--list") o.list = true;
        else if (a == "--table") o.table = true;
        else if (a == "--inproc") o.inproc = true;
        else if (a == "--help") {
            usage(argv[0]);
            return 0;
        }
        else if (a == "--json" && i + 1 < argc) o.json = argv[++i];
        else if (a == "--family" && i + 1 < argc) o.families.push_back(argv[++i]);
        else if (a == "--backend" && i + 1 < argc) o.backends.push_back(argv[++i]);
        else if (a == "--variant" && i + 1 < argc) o.variants.push_back(argv[++i]);
        else if (a == "--n" && i + 1 < argc) o.n = std::atoi(argv[++i]);
        else if (a == "--reps" && i + 1 < argc) o.reps = std::atoi(argv[++i]);
        else {
            usage(argv[0]);
            return 2;
        }
    }
#if !defined(MK_SINGLE)
    dInitODE2(0);
#endif
    std::vector<std::unique_ptr<Backend>> backends = make_backends(o);
    if (o.list) {
        for (int f = 0; f < MK_FAM_COUNT; ++f) std::printf("family  %s\n", mk_family_name((mk_family)f));
        std::printf("family  regression\n");
        for (auto &b : backends) std::printf("backend %s\n", b->name.c_str());
        return 0;
    }
    if (o.selftest) return selftest(backends);

    const bool single = mk_is_double_precision() == 0;
    const int reps = o.reps > 0 ? o.reps : o.quick ? 3 : 20;
    mk_case_set set;
    std::memset(&set, 0, sizeof set);
    double t0 = now_ns();
    if (build_cases(o, &set)) {
        std::fprintf(stderr, "bench_narrow: case generation failed\n");
        return 1;
    }
    if (!filters_ok(o, backends, set)) {
        mk_case_set_free(&set);
        return 2;
    }
    std::printf("bench_narrow (%s build): %d cases with exact references in %.1f s. Each backend answers in child\n"
                "processes (a case that hangs > 2 s or crashes counts as a failure and is left out of the timing); then one\n"
                "process per group warms every backend once, untimed, and times %d rounds (fewer, >= 3, once a group's\n"
                "loops pass 1 s), each round every backend once in an order rotated by one; ns/query = the best loop\n"
                "(>= 1000 queries and >= 100 us of thread CPU time, after one untimed pass) of each backend\n",
                single ? "float" : "double", set.count, (now_ns() - t0) * 1e-9, reps);
    FILE *json = nullptr;
    if (o.json && !(json = std::fopen(o.json, o.append ? "a" : "w"))) {
        std::perror(o.json);
        return 1;
    }
    const bool table = o.table || !o.quick;
    std::vector<std::string> summary;
    std::vector<Row> all;
    if (table)
        std::printf("\n  %-26s %-28s %5s %10s %8s %8s %8s %8s %5s %5s\n", "family/variant", "backend", "n", "ns/query",
                    "rel p50", "rel p99", "rel max", "nrm p99", "wrong", "fail");
    for (int lo = 0; lo < set.count;) {
        int hi = lo;
        while (hi < set.count && !std::strcmp(set.cases[hi].family, set.cases[lo].family) &&
               !std::strcmp(set.cases[hi].variant, set.cases[lo].variant))
            ++hi;
        std::vector<const mk_case *> cs;
        for (int i = lo; i < hi; ++i) cs.push_back(&set.cases[i]);
        if (!wanted_variant(o, set.cases[lo].variant)) {
            lo = hi;
            continue;
        }
        std::vector<Row> rows;
        std::vector<Outcome> out = run_group(backends, cs, reps, o.inproc);
        for (size_t k = 0; k < backends.size(); ++k)
            if (out[k].prepared) rows.push_back(measure(*backends[k], cs, out[k].ans, out[k].ns));
        report_group(rows, single, table, json, summary);
        std::fflush(stdout);
        all.insert(all.end(), rows.begin(), rows.end());
        lo = hi;
    }
    std::printf("\nSummary: Minko (%s) against the fastest accurate competitor of each group (p99 <= %s, no failures,\n"
                "<= 0.5%% wrong booleans%s). Targets: %s\n",
                single ? "float" : "double", single ? "1e-4" : "1e-6", single ? "" : "; ODE dCollide on the closed-form families",
                single ? "p99 <= 1e-4 at unit scale and at 1e5 offsets (no speed target)."
                       : "p99 <= 1e-10, max <= 1e-8 (|d| < 1e-5 size: abs <= 1e-13 size),\n"
                         "normals p99 <= 1e-6 deg, 0 failures, 0 wrong booleans; <= 1/3 of the competitor's ns (closed forms: <= ODE).");
    std::printf("\nMinko's columns are mk_distance_pose (poses made once per body, what an engine calls); the last\n"
                "two are the mk_transform entry (mk_distance: quaternions checked per call, converted as far as the pair\n"
                "reads) and its ratio.\n");
    std::printf("\n  %-26s %6s %8s | %-22s %6s %8s | %-6s | acc  speed | %6s %-6s\n", "family/variant", "ns", "p99", "competitor", "ns",
                "p99", "ratio", "xf ns", "ratio");
    for (const std::string &l : summary) std::printf("%s\n", l.c_str());
    scoreboard(all);
    if (json) std::fclose(json);
    mk_case_set_free(&set);
#if !defined(MK_SINGLE)
    dCloseODE();
#endif
    return 0;
}

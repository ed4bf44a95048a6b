/* test_box_box.c: mk_collide_pose on two boxes (box_box.c, one fused pass)
 * against an oracle assembled here from the general pieces it replaces:
 * mk_sat_box_box with the same options, an edge pair parallel to a face
 * named as that face, the general polygon clip of mk_box_face against the
 * other box's mk_support_feature (mk_mf_clip), mk_mf_reduce, the edges'
 * closest points, and the move to world space written out. Cold calls and warm sequences in both
 * mk_manifold_modes, rounded boxes, margins: the same count, feature IDs
 * in the same order, normals, depths and all four points to rounding. */
#include <float.h>
#include <string.h>

#include "manifold_internal.h"
#include "polytope.h"
#include "pose.h"
#include "sat.h"
#include "shape_internal.h" /* MK_MAX_SIZE */
#include "support/mk_test.h"

#if defined(MK_SINGLE)
#  define TOL 2e-4
#  define SMALLEST_NORMAL FLT_MIN
#else
#  define TOL 1e-10
#  define SMALLEST_NORMAL DBL_MIN
#endif

#define REQUIRE(cond, ...) do { if (!(cond)) ck_abort_msg(__VA_ARGS__); } while (0)

static mk_real min3(mk_vec3 v) { return mk_min(v.x, mk_min(v.y, v.z)); }

/* The oracle's face for an edge-pair axis that is a face normal (A's first). */
static void rename_face(const mk_pair *p, mk_sat_result *s)
{
    mk_real one = 1 - 64 * MK_REAL_EPSILON;
    mk_vec3 n = s->normal, l = mk_mat3_tmul_v3(p->r, n);
    mk_real na[3], nb[3];
    int k;
    na[0] = n.x, na[1] = n.y, na[2] = n.z;
    nb[0] = l.x, nb[1] = l.y, nb[2] = l.z;
    for (k = 0; k < 3; ++k)
        if (mk_fabs_(na[k]) >= one) {
            s->kind = MK_SAT_FACE_A, s->a = 2 * k + (na[k] > 0), s->b = -1;
            return;
        }
    for (k = 0; k < 3; ++k)
        if (mk_fabs_(nb[k]) >= one) {
            s->kind = MK_SAT_FACE_B, s->a = -1, s->b = 2 * k + (nb[k] < 0);
            return;
        }
}

/* The manifold of two boxes by the general pieces; returns 0 when the
 * oracle would hand the pair to GJK (rounded cores apart, not realised). */
/* The clip's candidates before the reduction, as world contact points. */
typedef struct cands {
    int count;
    mk_contact_point p[MK_MF_MAX];
} cands;

static void to_world(const mk_mf_point *q, const mk_pair *p, const mk_pose *xa, mk_vec3 n, mk_vec3 nw, mk_contact_point *c)
{
    mk_vec3 pb = mk_v3_mad(q->pa, -q->depth, n);
    c->local_a = q->pa;
    c->local_b = mk_mat3_tmul_v3(p->r, mk_v3_sub(pb, p->t));
    c->point_a = mk_v3_add(mk_mat3_mul_v3(xa->r, c->local_a), xa->p);
    c->point_b = mk_v3_mad(c->point_a, -q->depth, nw);
    c->depth = q->depth;
    c->features = q->features;
}

static int oracle(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin, const mk_manifold_cache *cache,
                  mk_manifold *out, cands *all)
{
    mk_pair p = mk_pair_of_poses_(a, xa, b, xb);
    mk_real ra = a->radius, rb = b->radius, deepest = -MK_REAL_MAX;
    mk_sat_options o = mk_sat_defaults();
    mk_sat_result s;
    mk_mf m;
    mk_vec3 nw;
    int i;
    o.stop_above = margin + ra + rb;
    /* A hint that failed is dropped: the search is then the cold one's. */
    o.prefer = cache && cache->axis <= MK_MF_APART_HINT ? (mk_sat_kind)cache->axis : MK_SAT_NONE;
    o.prefer_rel = MK_MF_PREFER_REL;
    o.prefer_abs = o.prefer == MK_SAT_NONE ? 0 : MK_MF_PREFER_ABS * mk_min(min3(a->u.half_extents), min3(b->u.half_extents));
    o.hold_face = !cache || cache->mode == MK_MANIFOLD_STABLE_IDS;
    mk_sat_box_box(a->u.half_extents, b->u.half_extents, &p.r, p.t, &o, &s);
    if (s.kind == MK_SAT_EDGES) rename_face(&p, &s);
    out->count = all->count = 0;
    if (s.best - ra - rb > margin) return 1;
    m.count = 0;
    m.margin = margin;
    m.normal = s.normal;
    m.cores_apart = s.separation > 0;
    m.slop = cache && cache->mode == MK_MANIFOLD_BEST_FACE ? MK_MF_SLOP_EXACT : MK_MF_SLOP_IDS;
    if (s.kind == MK_SAT_FACE_A) {
        mk_feat ref, inc;
        mk_box_face(a, s.a / 2, s.a & 1, &ref);
        mk_support_feature(b, mk_mat3_tmul_v3(p.r, mk_v3_neg(s.normal)), &inc);
        mk_feat_transform(&inc, &p);
        mk_mf_clip(&m, &ref, 1, &inc, ra, rb);
    } else if (s.kind == MK_SAT_FACE_B) {
        mk_feat ref, inc;
        mk_box_face(b, s.b / 2, s.b & 1, &ref);
        mk_feat_transform(&ref, &p);
        mk_support_feature(a, s.normal, &inc);
        mk_mf_clip(&m, &ref, 0, &inc, ra, rb);
    } else {
        mk_vec3 a0, a1, b0, b1, qa;
        mk_real u, v, gap = s.separation;
        int ea = mk_box_hull_edge_id(s.a), eb = mk_box_hull_edge_id(s.b);
        mk_box_edge_ends(a->u.half_extents, ea, &a0, &a1);
        mk_box_edge_ends(b->u.half_extents, eb, &b0, &b1);
        b0 = mk_v3_add(mk_mat3_mul_v3(p.r, b0), p.t);
        b1 = mk_v3_add(mk_mat3_mul_v3(p.r, b1), p.t);
        mk_segment_segment(a0, a1, b0, b1, &u, &v);
        qa = mk_v3_lerp(a0, a1, u);
        if (gap > 0) gap = mk_v3_dist(qa, mk_v3_lerp(b0, b1, v));
        mk_mf_add(&m, mk_v3_mad(qa, ra, s.normal), ra + rb - gap, MK_FEATURE(MK_FEATURE_EDGE, ea), MK_FEATURE(MK_FEATURE_EDGE, eb));
    }
    nw = mk_mat3_mul_v3(xa->r, m.normal);
    all->count = m.count;
    for (i = 0; i < m.count; ++i) to_world(&m.p[i], &p, xa, m.normal, nw, &all->p[i]);
    mk_mf_reduce(&m);
    for (i = 0; i < m.count; ++i) deepest = mk_max(deepest, m.p[i].depth);
    if (s.separation > 0 && !(deepest >= ra + rb - s.separation -
                              256 * MK_REAL_EPSILON * (mk_v3_max_abs(p.t) + ra + mk_v3_max_abs(a->u.half_extents) + rb + mk_v3_max_abs(b->u.half_extents))))
        return 0;
    out->normal = nw;
    out->count = m.count;
    for (i = 0; i < m.count; ++i) to_world(&m.p[i], &p, xa, m.normal, nw, &out->points[i]);
    return 1;
}

/* In single precision the two clips' round-off can also decide
 * differently whether a point deep inside a random overlap lies in the
 * clip slop strip (kept as it is) or beyond it (clipped): positions then
 * differ by up to the strip's width, ids and depths do not. */
#if defined(MK_SINGLE)
#  define STRIP(h) (2 * MK_MF_SLOP_IDS * (h))
#else
#  define STRIP(h) 0
#endif

/* A clipped point where an incident edge nearly parallel to a side plane
 * crosses it is ill-conditioned along that plane (test_clip.c): both
 * clips put it on the same plane at the same depth, but along the plane
 * their round-off may move it by eps |edge| / |sin|. d (world) passes if it
 * is within tol, or within tol along the normal and along one of the
 * reference box's in-plane axes (the box whose axis the normal is). */
static int close_on_plane(mk_vec3 d, mk_vec3 n, const mk_pose *xa, const mk_pose *xb, mk_real tol)
{
    const mk_pose *ref = xa;
    mk_vec3 l;
    mk_real e[3], one = 1 - (mk_real)TOL;
    if (mk_v3_max_abs(d) <= tol) return 1;
    if (!(mk_fabs_(mk_v3_dot(n, xa->r.c0)) >= one || mk_fabs_(mk_v3_dot(n, xa->r.c1)) >= one || mk_fabs_(mk_v3_dot(n, xa->r.c2)) >= one))
        ref = xb;
    l = mk_mat3_tmul_v3(ref->r, d);
    e[0] = mk_fabs_(l.x), e[1] = mk_fabs_(l.y), e[2] = mk_fabs_(l.z);
    if (!(mk_fabs_(mk_v3_dot(d, n)) <= tol)) return 0;
    return (e[0] <= tol) + (e[1] <= tol) + (e[2] <= tol) >= 2;
}

/* Point g is candidate w: the same features, depth and points. */
static int point_is(const mk_contact_point *g, const mk_contact_point *w, mk_vec3 n, const mk_pose *xa, const mk_pose *xb, mk_real tol, mk_real ptol)
{
    return g->features == w->features && mk_fabs_(g->depth - w->depth) <= tol && close_on_plane(mk_v3_sub(g->point_a, w->point_a), n, xa, xb, ptol) &&
           close_on_plane(mk_v3_sub(g->point_b, w->point_b), n, xa, xb, ptol) &&
           close_on_plane(mk_v3_sub(mk_mat3_mul_v3(xa->r, g->local_a), mk_mat3_mul_v3(xa->r, w->local_a)), n, xa, xb, ptol) &&
           close_on_plane(mk_v3_sub(mk_mat3_mul_v3(xb->r, g->local_b), mk_mat3_mul_v3(xb->r, w->local_b)), n, xa, xb, ptol);
}

/* The reduction's choice compared exactly, point by point. In single
 * precision only, its tie rules (the deepest point wins by 64 ulps of the
 * patch's extent, later candidates by 5 %) may fall the other way on the
 * two clips' round-off: then every point must still be one of the
 * oracle's candidates, the first the deepest within that margin. */
static void same(const mk_manifold *got, const mk_manifold *want, const cands *all, const mk_pose *xa, const mk_pose *xb, mk_real scale,
                 mk_real strip, int c, int f)
{
    int i, j;
    mk_real tol = (mk_real)TOL * scale, ptol = tol + strip;
    REQUIRE(got->count == want->count, "case %d frame %d: %d points, oracle %d", c, f, got->count, want->count);
    if (got->count == 0) return;
    REQUIRE(mk_v3_max_abs(mk_v3_sub(got->normal, want->normal)) <= (mk_real)TOL, "case %d frame %d: normal", c, f);
    for (i = 0; i < got->count; ++i) {
        const mk_contact_point *g = &got->points[i];
        REQUIRE(g->flags == (g->depth < 0 ? MK_CONTACT_SPECULATIVE : 0u), "case %d frame %d point %d: flags", c, f, i);
        if (point_is(g, &want->points[i], got->normal, xa, xb, tol, ptol)) continue;
#if defined(MK_SINGLE)
        {
            mk_real deepest = -MK_REAL_MAX;
            for (j = 0; j < all->count && !point_is(g, &all->p[j], got->normal, xa, xb, tol, ptol); ++j) continue;
            REQUIRE(j < all->count, "case %d frame %d point %d: features %08x, not a candidate", c, f, i, g->features);
            for (j = 0; j < all->count; ++j) deepest = mk_max(deepest, all->p[j].depth);
            REQUIRE(got->points[0].depth >= deepest - 128 * MK_REAL_EPSILON * scale, "case %d frame %d: first point not the deepest", c, f);
            continue;
        }
#else
        (void)all;
        (void)j;
#endif
        REQUIRE(0, "case %d frame %d point %d: features %08x, oracle %08x (depth %.17g, oracle %.17g)", c, f, i, g->features,
                want->points[i].features, (double)g->depth, (double)want->points[i].depth);
    }
}

/* Random overlapping, stacked (square, turned, tilted; corners on the side
 * planes where the slop decides) and separated pairs, some rounded, some
 * with a margin, each followed for a few frames of slow motion with a
 * cache in either mode, its first frame also cold. */
START_TEST(box_box_matches_general_pieces)
{
    mk_rng r = {4242};
    int c, f, faces = 0, many = 0, edges = 0, apart = 0;
    for (c = 0; c < 1500; ++c) {
        mk_shape a, b;
        int kind = c % 4;
        mk_real rad = (mk_real)(c % 7 == 0 ? 0.05 : 0), margin = (mk_real)(c % 5 == 0 ? 0.1 : 0);
        mk_transform xa = mk_transform_make(mk_rng_v3(&r, -3, 3), mk_rng_quat(&r)), xb;
        mk_quat spin;
        mk_vec3 vel;
        mk_manifold_cache cache;
        memset(&cache, 0, sizeof cache);
        cache.mode = (c / 4) % 2 ? MK_MANIFOLD_BEST_FACE : MK_MANIFOLD_STABLE_IDS;
        mk_shape_box(mk_rng_v3(&r, 0.1, 1), rad, &a);
        if (kind == 0 || kind == 3) {
            mk_shape_box(mk_rng_v3(&r, 0.1, 1), rad, &b);
            xb = mk_transform_make(mk_v3_mad(xa.p, (mk_real)mk_rng_range(&r, 0, kind == 3 ? 2.5 : 1.2), mk_rng_dir(&r)), mk_rng_quat(&r));
        } else {
            mk_vec3 h = a.u.half_extents;
            mk_quat tilt = mk_quat_from_axis_angle(mk_rng_dir(&r), (mk_real)(kind == 1 ? 0 : mk_rng_range(&r, 0, 0.03)));
            mk_quat yaw = mk_quat_from_axis_angle(mk_v3(0, 0, 1), (mk_real)(c % 8 == 1 ? 0 : mk_rng_range(&r, -3.2, 3.2)));
            b = a;
            if (c % 2) mk_shape_box(mk_v3_mul(h, mk_rng_v3(&r, 0.5, 1.5)), rad, &b);
            xb = mk_transform_make(mk_v3((mk_real)mk_rng_range(&r, -0.3, 0.3), 0,
                                         h.z + b.u.half_extents.z + 2 * rad - (mk_real)mk_rng_range(&r, -0.01, 0.05)),
                                   mk_quat_mul(tilt, yaw));
            xb.p = mk_transform_point(xa, xb.p);
            xb.q = mk_quat_mul(xa.q, xb.q);
        }
        vel = mk_rng_v3(&r, -0.002, 0.002);
        spin = mk_quat_from_axis_angle(mk_rng_dir(&r), (mk_real)mk_rng_range(&r, 0, 0.004));
        for (f = 0; f < 6; ++f) {
            mk_pose pa, pb;
            mk_manifold got, want;
            cands all;
            mk_manifold_cache before = cache;
            mk_real scale = mk_v3_max_abs(xa.p) + mk_v3_max_abs(xb.p) + 2;
            mk_real strip = STRIP(mk_max(mk_v3_max_abs(a.u.half_extents), mk_v3_max_abs(b.u.half_extents)));
            mk_pose_from_transform(xa, &pa);
            mk_pose_from_transform(xb, &pb);
            if (f == 0) {
                MK_ASSERT_STATUS(mk_collide_pose(&a, &pa, &b, &pb, margin, NULL, &got), MK_OK);
                if (oracle(&a, &pa, &b, &pb, margin, NULL, &want, &all)) same(&got, &want, &all, &pa, &pb, scale, strip, c, -1);
            }
            MK_ASSERT_STATUS(mk_collide_pose(&a, &pa, &b, &pb, margin, &cache, &got), MK_OK);
            if (oracle(&a, &pa, &b, &pb, margin, &before, &want, &all)) {
                same(&got, &want, &all, &pa, &pb, scale, strip, c, f);
                if (got.count == 0) apart++;
                else if (MK_FEATURE_TYPE(MK_FEATURE_PAIR_A(got.points[0].features)) == MK_FEATURE_EDGE &&
                         MK_FEATURE_TYPE(MK_FEATURE_PAIR_B(got.points[0].features)) == MK_FEATURE_EDGE && got.count == 1)
                    edges++;
                else faces++;
                many += got.count == 4;
            }
            xb.p = mk_v3_add(xb.p, vel);
            xb.q = mk_quat_normalize(mk_quat_mul(spin, xb.q));
        }
    }
    /* Every path was taken many times. */
    ck_assert_int_gt(faces, 3000);
    ck_assert_int_gt(many, 1500);
    ck_assert_int_gt(edges, 100);
    ck_assert_int_gt(apart, 300);
}
END_TEST

/* mk_collide_pose takes two boxes to box_box.c after one integer test of
 * all their reals (manifold.c's boxes_ok); anything that test refuses
 * goes to the general checks. So the test must accept exactly what the
 * contract accepts: every size, rounding radius and the margin set to
 * each boundary and non-finite value, the status against
 * mk_shape_validate's and the margin rules, and every accepted query
 * answered by the box path itself (bit for bit mk_box_box_collide's; the
 * general path answers differently in the last bits). */
START_TEST(box_checks_match_contract)
{
    const mk_real big = MK_MAX_SIZE, inf = (mk_real)INFINITY, nan = (mk_real)NAN;
    const mk_real vals[] = {nan, -nan, inf, -inf, 0, -(mk_real)0, -1, SMALLEST_NORMAL / 4, SMALLEST_NORMAL, MK_REAL(0.5), big,
                            big * (1 + 2 * MK_REAL_EPSILON), MK_REAL_MAX, -big};
    const int nv = (int)(sizeof vals / sizeof vals[0]);
    mk_shape good_a, good_b;
    mk_pose pa, pb;
    mk_rng r = {77};
    int f, k, accepted = 0, refused = 0;
    mk_shape_box(mk_v3(0.5, 0.4, 0.3), MK_REAL(0.02), &good_a);
    mk_shape_box(mk_v3(0.3, 0.6, 0.2), 0, &good_b);
    mk_pose_from_transform(mk_transform_make(mk_v3(0.1, 0.2, 0.3), mk_rng_quat(&r)), &pa);
    mk_pose_from_transform(mk_transform_make(mk_v3(0.4, 0.1, 0.6), mk_rng_quat(&r)), &pb);
    /* Field f: radius, then x, y, z of A (0-3) and of B (4-7); 8: the margin. */
    for (f = 0; f < 9; ++f) {
        for (k = 0; k < nv; ++k) {
            mk_shape a = good_a, b = good_b;
            mk_real margin = MK_REAL(0.01);
            mk_manifold got, want;
            mk_manifold_cache c1, c2;
            mk_status st, expect;
            if (f < 8) {
                mk_shape *s = f < 4 ? &a : &b;
                if (f % 4 == 0) s->radius = vals[k];
                else if (f % 4 == 1) s->u.half_extents.x = vals[k];
                else if (f % 4 == 2) s->u.half_extents.y = vals[k];
                else s->u.half_extents.z = vals[k];
            } else {
                margin = vals[k];
            }
            if ((expect = mk_shape_validate(&a)) == MK_OK && (expect = mk_shape_validate(&b)) == MK_OK)
                expect = !mk_real_is_valid(margin) ? MK_ERR_NOT_FINITE : margin < 0 ? MK_ERR_BAD_ARGUMENT : MK_OK;
            memset(&c1, 0, sizeof c1);
            memset(&c2, 0, sizeof c2);
            memset(&got, 0x5a, sizeof got);
            memset(&want, 0x5a, sizeof want);
            st = mk_collide_pose(&a, &pa, &b, &pb, margin, &c1, &got);
            ck_assert_msg(st == expect, "field %d value %d: %s, the contract %s", f, k, mk_status_name(st), mk_status_name(expect));
            if (st != MK_OK) {
                refused++;
                continue;
            }
            accepted++;
            MK_ASSERT_STATUS(mk_box_box_collide(&a, &pa, &b, &pb, margin, &c2, &want), MK_OK);
            ck_assert_msg(memcmp(&got, &want, sizeof got) == 0 && memcmp(&c1, &c2, sizeof c1) == 0, "field %d value %d: not the box path", f,
                          k);
        }
    }
    ck_assert_int_gt(accepted, 20);
    ck_assert_int_gt(refused, 50);
}
END_TEST

static Suite *box_box_suite(void)
{
    Suite *s = suite_create("box_box");
    TCase *tc = tcase_create("fused");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, box_box_matches_general_pieces);
    tcase_add_test(tc, box_checks_match_contract);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return mk_test_run(box_box_suite()); }

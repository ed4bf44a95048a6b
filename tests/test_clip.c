/* test_clip.c: the two boxes' face clip (mk_box_box_clip, box_box.c)
 * against the general polygon clip (mk_mf_clip on mk_box_face polygons) it
 * specialises: the same
 * candidates, in the same order, with the same feature IDs, positions and
 * depths, on random poses, stacked boxes (corners on the side planes, where
 * the slop decides) and rounded boxes apart, with the clip slop of either
 * mk_manifold_mode; and reduced to four in the reference face's own
 * coordinates against the general mk_mf_reduce. */
#include <string.h>

#include "gjk.h"
#include "manifold_internal.h"
#include "pose.h"
#include "support/mk_test.h"

#if defined(MK_SINGLE)
#  define TOL 1e-4
#else
#  define TOL 1e-11
#endif

/* Check records a checkpoint on every passing ck_assert; loops test first. */
#define REQUIRE(cond, ...) do { if (!(cond)) ck_abort_msg(__VA_ARGS__); } while (0)

static void mf_init(mk_mf *m, mk_vec3 n, mk_real margin, int apart, mk_real slop)
{
    m->count = 0;
    m->margin = margin;
    m->cores_apart = apart;
    m->slop = slop;
    m->normal = n;
}

/* The general clip with face `face` of A (ref_is_a) or of B as reference, as
 * polytopes() did it before the box path. */
static void general(const mk_pair *p, int ref_is_a, int face, mk_mf *m)
{
    mk_feat ref, inc;
    mk_real ra = p->a->radius, rb = p->b->radius;
    if (ref_is_a) {
        mk_box_face(p->a, face / 2, face & 1, &ref);
        mk_support_feature(p->b, mk_mat3_tmul_v3(p->r, mk_v3_neg(m->normal)), &inc);
        mk_feat_transform(&inc, p);
    } else {
        mk_box_face(p->b, face / 2, face & 1, &ref);
        mk_feat_transform(&ref, p);
        mk_support_feature(p->a, m->normal, &inc);
    }
    mk_mf_clip(m, &ref, ref_is_a, &inc, ra, rb);
}

/* Compares the two clips of one pose and reference; returns the candidate count. */
static int compare(const mk_pair *p, int ref_is_a, int face, mk_real margin, int apart, mk_real slop, int reduce, int c)
{
    mk_mf g, b;
    mk_bb_point q[MK_BB_CLIP_MAX];
    mk_vec3 n;
    mk_real scale = mk_v3_max_abs(p->t) + 2, ra = p->a->radius, rb = p->b->radius;
    int i, count;
    if (ref_is_a) {
        n = mk_v3_zero();
        if (face / 2 == 0) n.x = face & 1 ? 1 : -1;
        else if (face / 2 == 1) n.y = face & 1 ? 1 : -1;
        else n.z = face & 1 ? 1 : -1;
    } else {
        mk_vec3 col = face / 2 == 0 ? p->r.c0 : face / 2 == 1 ? p->r.c1 : p->r.c2;
        n = face & 1 ? mk_v3_neg(col) : col; /* B's outward face normal, negated: from A towards B */
    }
    mf_init(&g, n, margin, apart, slop);
    mf_init(&b, n, margin, apart, slop);
    general(p, ref_is_a, face, &g);
    /* The box clip's candidates in A's frame, as mk_box_box_collide places them. */
    count = mk_box_box_clip(p, ref_is_a, face, apart && ra + rb > 0 ? 0 : slop, margin, reduce, q);
    for (i = 0; i < count; ++i) {
        mk_vec3 pa = ref_is_a ? mk_v3_mad(q[i].q, ra - q[i].height, n) : mk_v3_mad(mk_v3_add(mk_mat3_mul_v3(p->r, q[i].q), p->t), ra, n);
        REQUIRE(mk_fabs_(q[i].depth - (ra + rb - q[i].height)) <= TOL * scale, "case %d point %d: depth and height disagree", c, i);
        mk_mf_add(&b, pa, q[i].depth, MK_FEATURE_PAIR_A(q[i].features), MK_FEATURE_PAIR_B(q[i].features));
    }
    if (reduce) mk_mf_reduce(&g);
    REQUIRE(g.count == b.count, "case %d: %d candidates, general clip %d", c, b.count, g.count);
    for (i = 0; i < g.count; ++i) {
        REQUIRE(g.p[i].features == b.p[i].features, "case %d point %d: features %08x, general %08x", c, i, b.p[i].features,
                g.p[i].features);
        REQUIRE(mk_fabs_(g.p[i].depth - b.p[i].depth) <= TOL * scale, "case %d point %d: depth %.17g, general %.17g", c, i,
                (double)b.p[i].depth, (double)g.p[i].depth);
        /* A crossing of an incident edge nearly parallel to the side plane
         * it crosses (square stacks, whose corners the round-off slop
         * leaves outside) is ill-conditioned along that plane: the two
         * clips' round-off in the plane distances moves it by
         * eps |edge| / |da - db|. Both must put it on the same side plane
         * (one in-face coordinate of the reference box) and at the same
         * depth; along the plane it may differ. */
        {
            mk_vec3 d = mk_v3_sub(g.p[i].pa, b.p[i].pa);
            mk_real e[3];
            int k = face / 2;
            if (!ref_is_a) d = mk_mat3_tmul_v3(p->r, d);
            e[0] = mk_fabs_(d.x), e[1] = mk_fabs_(d.y), e[2] = mk_fabs_(d.z);
            REQUIRE(mk_v3_len(d) <= TOL * scale || (e[k] <= TOL * scale && mk_min(e[(k + 1) % 3], e[(k + 2) % 3]) <= TOL * scale),
                    "case %d point %d: point off by %g", c, i, (double)mk_v3_len(d));
        }
    }
    return g.count;
}

START_TEST(box_clip_matches_general_clip)
{
    mk_rng r = {77};
    int c, total = 0, many = 0;
    for (c = 0; c < 3000; ++c) {
        mk_shape a, b;
        mk_transform xa = mk_transform_make(mk_rng_v3(&r, -3, 3), mk_rng_quat(&r)), xb;
        mk_pair p;
        int kind = c % 3, ref_is_a = (c / 3) % 2, face, n;
        mk_real margin = (mk_real)(c % 5 == 0 ? mk_rng_range(&r, 0, 0.2) : 0);
        mk_real rad = (mk_real)(c % 7 == 0 ? 0.05 : 0);
        mk_shape_box(mk_rng_v3(&r, 0.1, 1), rad, &a);
        if (kind == 0) {
            /* Random overlapping boxes. */
            mk_shape_box(mk_rng_v3(&r, 0.1, 1), rad, &b);
            xb = mk_transform_make(mk_v3_mad(xa.p, (mk_real)mk_rng_range(&r, 0, 1.2), mk_rng_dir(&r)), mk_rng_quat(&r));
        } else {
            /* Stacked: B on A's top face, square or turned (corners on or near
             * the side planes), tilted a little, at depths around zero. */
            mk_quat tilt = mk_quat_from_axis_angle(mk_rng_dir(&r), (mk_real)(kind == 1 ? 0 : mk_rng_range(&r, 0, 0.02)));
            mk_quat yaw = mk_quat_from_axis_angle(mk_v3(0, 0, 1), (mk_real)(c % 4 == 0 ? 0 : mk_rng_range(&r, -3.2, 3.2)));
            mk_vec3 h = a.u.half_extents;
            b = a;
            if (c % 2) mk_shape_box(mk_v3_mul(h, mk_rng_v3(&r, 0.5, 1.5)), rad, &b);
            xb = mk_transform_make(mk_v3(kind == 1 ? 0 : (mk_real)mk_rng_range(&r, -0.3, 0.3), 0,
                                         h.z + b.u.half_extents.z + 2 * rad - (mk_real)mk_rng_range(&r, -0.01, 0.05)),
                                   mk_quat_mul(tilt, yaw));
            xb.p = mk_transform_point(xa, xb.p);
            xb.q = mk_quat_mul(xa.q, xb.q);
        }
        p = mk_pair_make(&a, xa, &b, xb);
        /* A reference face that faces the other box: the face of the
         * reference box most aligned with the direction to the other centre. */
        {
            mk_vec3 d = ref_is_a ? p.t : mk_mat3_tmul_v3(p.r, mk_v3_neg(p.t)), ad = mk_v3_abs(d);
            int axis = ad.x >= ad.y && ad.x >= ad.z ? 0 : ad.y >= ad.z ? 1 : 2;
            face = 2 * axis + ((axis == 0 ? d.x : axis == 1 ? d.y : d.z) >= 0);
        }
        /* Both modes' slops (minko/manifold.h), on alternate cases. */
        n = compare(&p, ref_is_a, face, margin, rad > 0 && c % 2, (c / 6) % 2 ? MK_MF_SLOP_EXACT : MK_MF_SLOP_IDS, 0, c);
        /* Reduced in the reference face's coordinates: the four mk_mf_reduce keeps. */
        compare(&p, ref_is_a, face, margin, rad > 0 && c % 2, (c / 6) % 2 ? MK_MF_SLOP_EXACT : MK_MF_SLOP_IDS, 1, c);
        total += n > 0;
        many += n > 4;
    }
    ck_assert_int_gt(total, 1500);
    ck_assert_int_gt(many, 200);
}
END_TEST

static Suite *clip_suite(void)
{
    Suite *s = suite_create("clip");
    TCase *tc = tcase_create("box_faces");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, box_clip_matches_general_clip);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return mk_test_run(clip_suite()); }

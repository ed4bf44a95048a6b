/* sat_box.h: the 15-axis SAT of two box cores in closed form (internal).
 *
 * mk_sat_box_box_inl is mk_sat_box_box (sat.h: the same contract, answer
 * and indices as mk_sat on box views) as an inline function, so that each
 * caller gets it specialised for its options: mk_collide's box pair
 * (box_box.c: a margin and the hysteresis) and mk_distance's (distance.c:
 * pairs whose faces overlap, stop at a separating edge axis, no
 * preference). One implementation; the
 * out-of-line mk_sat_box_box (box_box.c) is the same code for the tests
 * and demos/bench_sat. Complexity O(1): 6 face axes, then 9 edge axes
 * unless a face already separates by more than opt->stop_above.
 *
 * Which form runs, measured in session 10 (load 6-10 on 2 cores; timings
 * are ratios to ODE's dCollide in the same run, medians of 4-10 A/B runs
 * under nice -15): one form for both callers, every axis computed and the
 * best kept by selects (no data-dependent branch until the early stop
 * after the six faces), because on random poses which axis wins is data a
 * branch predictor does not learn. The nine edge pairs share the nine 2x2
 * minors of R that give B's extent along their axes (each serves two
 * pairs). Against session 9's form (faces stopping after A's three, each
 * minor computed twice): demos/bench_contacts instructions per run
 * (callgrind, --toggle-collect=mk_collide_pose / mk_collide, --loops 2)
 * stacked -2.8 %, random -3.5 %, apart +1.6..3.8 % (B's faces are computed
 * when A's already separate); time (pose and cold ÷ dCollide) within
 * +-5 %, cold apart 10-13 % faster; Bullet's 1000_stack collision phase (demos/bullet_split.sh,
 * 300 steps) 2713.8 -> 2677.9 M, mk_collide_pose 1495.5 -> 1459.6 M.
 * Tried and not kept: (1) the same code with branches instead of selects
 * (a constant flag per caller): demos/bench_narrow's box families 1-10 %
 * faster with its 200 cases per family, which it repeats in the same order
 * (a predictor learns part of it), but with --n 2000 separated rows 12-14 %
 * slower; bench_contacts stacked and random 5-13 % slower. (2) Ranking the
 * edge pairs by sep |sep| = g |g| / |L|^2 (one division instead of a square
 * root and a division per pair, or a cross-multiplied comparison): more
 * instructions (862 against 814 per call on random pairs, a scratch driver)
 * and 4-5 % slower; the cross-multiplied form compiled its double selects
 * to branches. The square roots and divisions are not the bottleneck at
 * about 3.3 instructions per cycle.
 *
 * Session 11: the search is split so that mk_distance runs it on the face
 * separations its face pass already has: box_faces_of (the six faces),
 * box_sat_axes (best face of each box, best edge pair, the early stop),
 * then mk_sat_box_box_rest_inl builds mk_sat_result (mk_sat_box_box_inl is
 * the three in a row, the same bits as before). Tried and not kept: the
 * nine edge pairs as three 3-vectors over j (edge_gap's operations in the
 * same order, minors as one cross product per axis of A), hoping -O2 would
 * pack them two to a register: it packed none, and thin_rods' penetrating
 * queries took 1301 instructions against 1288. (2) above measured again in
 * time (mk_distance, load 11, A/B medians of 3-4 runs): ranking by
 * g |g| / |L|^2 (one division per pair, the winner's separation divided
 * out at the end) with its g and |L|^2 kept by selects, +110 instructions
 * per query, or stored in a 9-entry array, +34: thin_rods x0.83 -> x0.81
 * and parallel_faces x0.50 -> x0.54, no gain.
 *
 * Session 12, measured and not kept: leaving out the nine edge pairs for
 * mk_collide's sharp boxes when a bound proves they cannot change the
 * answer (exact: the same result bit for bit, checked on random walks of
 * nearly aligned boxes under every preference). For every unit L,
 * sep(L) <= sum_m |L_m| (sa_m + 2 O_m), O_m being B's reach along A's axis
 * m from the entries of R that are not their column's dominant one
 * (|R_mk| <= 3/4), so at most max_m (sa_m + 2 O_m) when that is <= 0; the
 * same in B's frame; plus a rounding slack of 64 eps S (1 + 1 / |L|min)
 * (the minors' absolute error is divided by |L|). It holds only when the
 * contact is deeper than about twice the tilt times the size, and must
 * beat the best face plus the band: on Bullet's 1000 stack (300 steps)
 * 42 % of the box calls took it (58 % had no bound: shallow or not
 * aligned), but the bound (18 masked products, the slack's root and
 * division) cost more than the edges it saved: mk_collide_pose 1018.6 ->
 * 1060.3 M instructions (callgrind, demos/bullet_split.sh). In float the
 * slack exceeds the band at every tilt: never taken.
 */
#ifndef MINKO_SAT_BOX_H
#define MINKO_SAT_BOX_H

#include "manifold_internal.h"
#include "sat.h"

/* Box edge ID of the edge along `axis` at the corner whose other two
 * coordinates have the signs of s (minko/manifold.h numbering). */
static inline int mk_box_edge_at_(int axis, const mk_real *s)
{
    int lo = axis == 0 ? 1 : 0, hi = axis == 2 ? 1 : 2;
    return 4 * axis + (s[lo] > 0) + 2 * (s[hi] > 0);
}

/* Edge pair (e_i of A, R_j of B): axis L = e_i x R_j = (0, -R_i2j, R_i1j) in
 * the cyclic order (i, i1, i2). A's extent along L is |R_i2j| a_i1 +
 * |R_i1j| a_i2; B's is sum_k |(R^T L)_k| b_k, from the products (the minors
 * of edge_minor) rather than the cofactor identity of a rotation, which the
 * rounded R satisfies only to a few ulps (and the division by a small |L|
 * would magnify). Returns the gap g along the unnormalised L (the
 * separation is g / |L|) and *l2 = |L|^2 from L's two components, with no
 * cancellation near parallel. */
MK_ALWAYS_INLINE mk_real edge_gap(mk_real r[3][3], mk_real ar[3][3], mk_real am[3][3], const mk_real *a, const mk_real *b, const mk_real *d,
                                  int i, int j, mk_real *l2)
{
    int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
    *l2 = r[i1][j] * r[i1][j] + r[i2][j] * r[i2][j];
    return mk_fabs_(r[i1][j] * d[i2] - r[i2][j] * d[i1]) - (ar[i2][j] * a[i1] + ar[i1][j] * a[i2]) - am[i][j] * b[j1] - am[i][j2] * b[j2];
}

/* |(R^T L)_k1| for L = e_i x R_k (k1 = k + 1; the component along k2 is
 * the same minor for L = e_i x R_k2, negated): the minor of rows i + 1,
 * i + 2 and columns k, k + 1 of R. Each of the nine is shared by two edge
 * pairs, so edge_gap takes them computed once. */
MK_ALWAYS_INLINE mk_real edge_minor(mk_real r[3][3], int i, int k)
{
    int i1 = (i + 1) % 3, i2 = (i + 2) % 3, k1 = (k + 1) % 3;
    return mk_fabs_(r[i1][k] * r[i2][k1] - r[i2][k] * r[i1][k1]);
}

/* Is an edge pair with |L|^2 = l2 counted? Pairs closer to parallel are
 * not: their L has no reliable direction (sat.h, MK_SAT_PARALLEL). */
MK_ALWAYS_INLINE int edge_counted(mk_real l2) { return l2 > MK_SAT_PARALLEL * MK_SAT_PARALLEL; }

/* The best edge pair so far, k = 3 i + j for e_i of A and R_j of B (-1:
 * none), and its separation g / |L|. All nine are computed in full and the
 * best kept by a maximum and an integer select, without a branch on the
 * data: on random poses every test that skipped an axis early (a parallel
 * pair, one that cannot beat the faces) was a coin flip to the branch
 * predictor, and its misses cost more time than the nine square roots and
 * divisions it saved (random boxes in demos/bench_contacts: 350 -> 272 ns
 * per call, session 8). */
typedef struct box_edges { mk_real sep; int k; } box_edges;

MK_ALWAYS_INLINE void box_edge_axis(mk_real r[3][3], mk_real ar[3][3], mk_real am[3][3], const mk_real *a, const mk_real *b,
                                    const mk_real *d, int i, int j, box_edges *best)
{
    mk_real l2, g = edge_gap(r, ar, am, a, b, d, i, j, &l2), sep;
    int ok = edge_counted(l2);
    sep = g / mk_sqrt_(ok ? l2 : 1);
    best->k = mk_sel_int(ok & (sep > best->sep), 3 * i + j, best->k);
    best->sep = mk_max(best->sep, ok ? sep : -MK_REAL_MAX);
}

MK_ALWAYS_INLINE void box_edges_init(box_edges *e)
{
    e->sep = -MK_REAL_MAX;
    e->k = -1;
}

/* The best edge pair's separation (-MK_REAL_MAX: none). */
MK_ALWAYS_INLINE mk_real box_edges_sep(const box_edges *e) { return e->sep; }

/* The kind, features, separation and normal of edge pair (e_i of A, R_j
 * of B) into *out: L = e_i x R_j pointing from A to B; A's supporting edge
 * sits at the corner with the signs of L, B's at the corner with those of
 * -R^T L. Reads rows (i + 1) % 3 and (i + 2) % 3 of r and the same entries
 * of d; row i and d[i] are multiplied by L_i = 0 only. */
static inline void edge_result(mk_real r[3][3], const mk_real *d, int i, int j, mk_real sep, mk_sat_result *out)
{
    /* The lower half-edge of each box edge ID, in polytope.h's box view. */
    static const unsigned char box_half_edge[12] = {11, 15, 9, 13, 2, 4, 0, 6, 3, 7, 1, 5};
    static const unsigned char next[3] = {1, 2, 0}, prev[3] = {2, 0, 1};
    int i1 = next[i], i2 = prev[i], lo = j == 0 ? 1 : 0, hi = j == 2 ? 1 : 2;
    mk_real L[3], blo, bhi, l;
    L[i] = 0, L[i1] = -r[i2][j], L[i2] = r[i1][j];
    if (L[0] * d[0] + L[1] * d[1] + L[2] * d[2] < 0) L[0] = -L[0], L[1] = -L[1], L[2] = -L[2];
    /* The two components of -R^T L that name B's edge (mk_box_edge_at_(j, .)). */
    blo = -(r[0][lo] * L[0] + r[1][lo] * L[1] + r[2][lo] * L[2]);
    bhi = -(r[0][hi] * L[0] + r[1][hi] * L[1] + r[2][hi] * L[2]);
    l = mk_sqrt_(L[0] * L[0] + L[1] * L[1] + L[2] * L[2]);
    out->kind = MK_SAT_EDGES;
    out->a = box_half_edge[mk_box_edge_at_(i, L)];
    out->b = box_half_edge[4 * j + (blo > 0) + 2 * (bhi > 0)];
    out->separation = sep;
    out->normal = mk_v3(L[0] / l, L[1] / l, L[2] / l);
}

/* The six face separations of two box cores: sa along A's axes e_i (B's
 * extent there is |R| hb), sb along B's R_j (A's is |R|^T ha), and tb =
 * R^T t, B's offset along its own axes (its signs orient B's faces). The
 * face half of the SAT, computed once per pair: mk_distance decides from it
 * whether a pair is apart along a face before it runs the edges
 * (distance.c, box_box_sat), and hands it to mk_sat_box_box_rest_inl. */
typedef struct box_faces { mk_vec3 sa, sb, tb; } box_faces;

MK_ALWAYS_INLINE void box_faces_of(mk_vec3 ha, mk_vec3 hb, const mk_mat3 *R, mk_vec3 t, box_faces *f)
{
    mk_mat3 ar = mk_mat3_abs(*R);
    f->tb = mk_mat3_tmul_v3(*R, t);
    f->sa = mk_v3_sub(mk_v3_sub(mk_v3_abs(t), ha), mk_mat3_mul_v3(ar, hb));
    f->sb = mk_v3_sub(mk_v3_sub(mk_v3_abs(f->tb), hb), mk_mat3_tmul_v3(ar, ha));
}

/* The best of three face separations (ties to the first) by selects. */
MK_ALWAYS_INLINE mk_real box_face_best(mk_vec3 s, int *at)
{
    mk_real best = mk_max(mk_max(s.x, s.y), s.z);
    *at = mk_sel_int(s.y > s.x, 1, 0);
    *at = mk_sel_int(s.z > mk_max(s.x, s.y), 2, *at);
    return best;
}

/* The normal of face axis i of A (of B) oriented from A towards B: `up`
 * says whether B's centre lies on the + side of A's axis i (A's on the -
 * side of B's axis j, tb = R^T t), and the normal is that axis, negated
 * when not. One definition for the manifold's SAT result and mk_distance's
 * overlapping boxes. */
MK_ALWAYS_INLINE int box_face_a_up(mk_vec3 t, int i) { return (i == 0 ? t.x : i == 1 ? t.y : t.z) >= 0; }
MK_ALWAYS_INLINE int box_face_b_up(const box_faces *f, int j) { return (j == 0 ? f->tb.x : j == 1 ? f->tb.y : f->tb.z) >= 0; }
MK_ALWAYS_INLINE mk_vec3 box_face_a_normal(int i, int up)
{
    /* From a table: the normal built from three selects was stored in
     * halves and reloaded whole (a store-forwarding stall per call). */
    static const mk_vec3 unit[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    return mk_v3_scale(unit[i], up ? 1 : -1);
}
MK_ALWAYS_INLINE mk_vec3 box_face_b_normal(const mk_mat3 *R, int j, int up)
{
    return mk_v3_scale(j == 0 ? R->c0 : j == 1 ? R->c1 : R->c2, up ? 1 : -1);
}

/* R as plain scalars: r[i][j] is row i, column j (column j = B's axis j in
 * A's frame). */
MK_ALWAYS_INLINE void box_rows(const mk_mat3 *R, mk_real r[3][3])
{
    r[0][0] = R->c0.x, r[1][0] = R->c0.y, r[2][0] = R->c0.z;
    r[0][1] = R->c1.x, r[1][1] = R->c1.y, r[2][1] = R->c1.z;
    r[0][2] = R->c2.x, r[1][2] = R->c2.y, r[2][2] = R->c2.z;
}

/* The raw answer of the 15 axes: the best face of A (fa, separation sa),
 * of B (fb, sb) and edge pair (k = 3 i + j, se; -1, -MK_REAL_MAX: none or
 * not tested), and whether the search stopped early. */
typedef struct box_axes {
    mk_real sa, sb, se;
    int fa, fb, k, stopped;
} box_axes;

/* The SAT's search with the face separations already known (f, from
 * box_faces_of on the same ha, hb, R, t), stopping after the faces when one
 * separates by more than `stop`. Plain arrays: r[i][j] is row i, column j
 * of R (column j = B's axis j in A's frame), so every edge axis is a few
 * multiply-adds on scalars. The early stop looks at whole groups (the six
 * faces, then the edges): the answer is then the best of the groups
 * tested. */
MK_ALWAYS_INLINE void box_sat_axes(mk_vec3 ha, mk_vec3 hb, const mk_mat3 *R, mk_vec3 t, const box_faces *f, mk_real stop, box_axes *x)
{
    mk_real r[3][3], ar[3][3], a[3], b[3], d[3];
    box_edges e;
    box_rows(R, r);
    /* Spelled out, as every index below: constant indices let the compiler
     * keep the entries as scalars (a loop here kept r and ar in memory and
     * reloaded rows of r in 16-byte halves its 8-byte stores could not
     * forward: a stall per row). */
    ar[0][0] = mk_fabs_(r[0][0]), ar[0][1] = mk_fabs_(r[0][1]), ar[0][2] = mk_fabs_(r[0][2]);
    ar[1][0] = mk_fabs_(r[1][0]), ar[1][1] = mk_fabs_(r[1][1]), ar[1][2] = mk_fabs_(r[1][2]);
    ar[2][0] = mk_fabs_(r[2][0]), ar[2][1] = mk_fabs_(r[2][1]), ar[2][2] = mk_fabs_(r[2][2]);
    a[0] = ha.x, a[1] = ha.y, a[2] = ha.z;
    b[0] = hb.x, b[1] = hb.y, b[2] = hb.z;
    d[0] = t.x, d[1] = t.y, d[2] = t.z;
    box_edges_init(&e);
    /* The six faces are one group for the early stop: the best face is then
     * reported (a pair apart along B's face more than along A's is named by
     * B's, which certifies mk_distance's gap), and there is no branch
     * between A's faces and B's. */
    x->sa = box_face_best(f->sa, &x->fa);
    x->sb = box_face_best(f->sb, &x->fb);
    x->stopped = mk_max(x->sa, x->sb) > stop;
    /* Edge pairs: only the winner's normal and features are worked out. */
    if (!x->stopped) {
        /* Spelled out: with constant indices the axes' terms stay in registers. */
        mk_real am[3][3];
        am[0][0] = edge_minor(r, 0, 0), am[0][1] = edge_minor(r, 0, 1), am[0][2] = edge_minor(r, 0, 2);
        am[1][0] = edge_minor(r, 1, 0), am[1][1] = edge_minor(r, 1, 1), am[1][2] = edge_minor(r, 1, 2);
        am[2][0] = edge_minor(r, 2, 0), am[2][1] = edge_minor(r, 2, 1), am[2][2] = edge_minor(r, 2, 2);
        box_edge_axis(r, ar, am, a, b, d, 0, 0, &e);
        box_edge_axis(r, ar, am, a, b, d, 0, 1, &e);
        box_edge_axis(r, ar, am, a, b, d, 0, 2, &e);
        box_edge_axis(r, ar, am, a, b, d, 1, 0, &e);
        box_edge_axis(r, ar, am, a, b, d, 1, 1, &e);
        box_edge_axis(r, ar, am, a, b, d, 1, 2, &e);
        box_edge_axis(r, ar, am, a, b, d, 2, 0, &e);
        box_edge_axis(r, ar, am, a, b, d, 2, 1, &e);
        box_edge_axis(r, ar, am, a, b, d, 2, 2, &e);
        x->stopped = box_edges_sep(&e) > stop;
    }
    x->se = box_edges_sep(&e);
    x->k = e.k;
}

/* mk_sat_box_box_inl with the face separations already known: the search,
 * then the normal and feature indices of the chosen axis only. */
MK_ALWAYS_INLINE void mk_sat_box_box_rest_inl(mk_vec3 ha, mk_vec3 hb, const mk_mat3 *R, mk_vec3 t, const box_faces *f,
                                              const mk_sat_options *opt, mk_sat_result *out)
{
    box_axes x;
    mk_sat_kind kind;
    box_sat_axes(ha, hb, R, t, f, opt->stop_above, &x);
    kind = mk_sat_choose(x.sa, x.sb, x.se, x.k >= 0, x.stopped, opt, out);
    out->kind = kind;
    if (kind == MK_SAT_FACE_A) {
        int up = box_face_a_up(t, x.fa);
        out->a = 2 * x.fa + up;
        out->b = -1;
        out->separation = x.sa;
        out->normal = box_face_a_normal(x.fa, up);
    } else if (kind == MK_SAT_FACE_B) {
        int up = box_face_b_up(f, x.fb);
        out->a = -1;
        out->b = 2 * x.fb + !up;
        out->separation = x.sb;
        out->normal = box_face_b_normal(R, x.fb, up);
    } else {
        mk_real r[3][3], d[3];
        box_rows(R, r);
        d[0] = t.x, d[1] = t.y, d[2] = t.z;
        edge_result(r, d, x.k / 3, x.k % 3, x.se, out);
    }
}

MK_ALWAYS_INLINE void mk_sat_box_box_inl(mk_vec3 ha, mk_vec3 hb, const mk_mat3 *R, mk_vec3 t, const mk_sat_options *opt, mk_sat_result *out)
{
    box_faces f;
    box_faces_of(ha, hb, R, t, &f);
    mk_sat_box_box_rest_inl(ha, hb, R, t, &f, opt, out);
}

#endif

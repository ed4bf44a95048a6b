/* box_box.c: the contact manifold of two boxes in one pass (see
 * manifold_internal.h, mk_box_box_collide), and the 15-axis SAT of two
 * boxes it starts from (mk_sat_box_box, sat.h; mk_distance uses it too).
 *
 * mk_collide's general polytope path builds B's pose in A's frame, runs
 * SAT, turns the axis into polygons (mk_feat), clips them in A's frame into
 * a list of candidates (mk_mf), reduces the list and moves it to world
 * space, each step in its own frame with its own copies. Two boxes, the
 * pair every rigid-body scene is made of, need none of that: here the
 * relative pose is built once, the 15 axes are tested in closed form
 * (inlined), and a face axis clips the incident face in the reference
 * face's own 2D coordinates, where the reference face is the rectangle
 * |u| <= h_u, |v| <= h_v: a side test is one subtraction, only u and v
 * (and the height along the normal) are interpolated, and a side no
 * incident corner is outside of is skipped, so an incident face wholly
 * inside costs no pass at all. The candidates are reduced to four in those
 * coordinates (mk_mf_pick4) and written straight into the mk_manifold, each
 * with two matrix-vector products. The clip is the general Sutherland-
 * Hodgman clip of clip.c specialised, not a new idea: the same side order,
 * slop rule, crossing names and candidate order, so the manifold and its
 * feature IDs are those of the general path (tests/test_clip.c compares
 * the clips on random, stacked and rounded pairs, tests/test_box_box.c
 * whole manifolds, cold and warm).
 *
 * Tuned for time, not instructions: on random poses which axis, corner or
 * candidate wins is data no branch predictor learns, and a mispredicted
 * branch costs as much as a dozen square roots. So the SAT tests all 15
 * axes in full and keeps the best by selects (mk_sel_int), and the
 * incident face, its corners and the depth filter are chosen in
 * arithmetic. Session 8's clip without side passes (corners inside, edge
 * crossings and reference corners each computed once, in a fixed order of
 * the features) ran fewer instructions but 3 % slower than these passes
 * in time (its many small branches), and was dropped; branch-free forms
 * of the clip passes' own tests and of the reduction's running maximum
 * were slower still (their branches predict well, and selects lengthen
 * the chains).
 *
 * Where the time goes (perf sampling of demos/bench_contacts --backend
 * minko.pose, share of mk_collide_pose's time; stacked boxes / random
 * overlaps): the incident face and the clip passes 37 / 30 %, SAT 20 /
 * 27 % (mostly the nine edge axes' square roots and divisions), the
 * matrix products (relative pose, points to world and B's frame) 13 / 17
 * %, the reduction 11 / 5 % (5 to 8 candidates on stacked boxes), the
 * rest (checks, bounding balls, writing the points, edge contacts) 19 /
 * 21 %.
 *
 * The pass is latency-bound: a predicted branch lets the next stage start
 * early, a select makes it wait. Measured in session 10 and not kept
 * (callgrind per call on stacked boxes, wall medians of 5-7 alternated
 * bench_contacts runs under load 6-10): crossings from slopes per
 * incident edge direction computed before the passes, no division in
 * them (+190 instructions, 326 -> 334 ns); the reduction's candidates
 * padded to 8 so its loops run a constant count, with mk_mf_pick4 inlined
 * (+116 instructions, 326 -> 357 ns) or not (+75, 326 -> 338 ns); the side
 * tests as a bit mask, one pass per set bit (1.6 fewer mispredictions,
 * +77 instructions, 331 -> 344 ns); a Sutherland-Hodgman pass without
 * branches (+1080 instructions, as many mispredictions); the clip out of
 * line (+23 instructions); the apart hint's face and axis picked by index
 * and address (1.30 -> 0.21 mispredictions per call, 17.2 -> 19.0 ns: the
 * loads then wait for the hint's cache line, where predicted branches let
 * them start).
 *
 * Session 11: the face clip, the reduction and writing the points are two
 * thirds of a stacked query (without them: 340 -> 119 ns, 2886 -> 1461
 * instructions, bench_contacts stacked, load 5), so issue 4's 1/2 of
 * dBoxBox (about 200 ns there) needs them at about 85 ns. Measured and not
 * kept (branch contacts-direct-clip-experiment): the reduction made
 * independent of candidate order (each stage's tie band resolved by the
 * smallest feature pair, so a clip may build candidates in any order; the
 * contract and the tests then compare sets), with the clip computed
 * directly instead of in passes (the incident corners inside, where each
 * incident edge enters and leaves both slabs from one reciprocal per edge
 * direction and axis, the reference corners inside the incident
 * parallelogram, all kept by counting; the passes only where a point lies
 * in a slop strip): every test passed, and callgrind's mispredictions
 * fell 19.9 -> 9.4 per call, but it ran +694 instructions (2886 -> 3580)
 * and slower (median 346 -> 501 ns, best 320 -> 374, 5 alternated runs,
 * load 6.6): the query is bound by its instruction count (about 3 per
 * cycle), and the passes' branches predict far better on the hardware
 * than in callgrind's model. The order-free reduction alone: +182
 * instructions (two passes per stage), no faster; with Jolt's stages
 * instead (deepest, farthest, the farthest on each side of their line)
 * +69. The corners from the pose columns by +-, the clip in the
 * reference face's 2D frame and moving only the kept points are what this
 * file does already. */
#include <string.h>

#include "manifold_internal.h"
#include "polytope.h"
#include "pose.h"
#include "sat.h"
#include "sat_box.h"
#include "shape_internal.h"

#ifndef MK_WITHOUT_SAT

#define V(i) MK_FEATURE(MK_FEATURE_VERTEX, i)
#define E(i) MK_FEATURE(MK_FEATURE_EDGE, i)
#define F(i) MK_FEATURE(MK_FEATURE_FACE, i)

/* A vertex of the incident face while it is clipped: its coordinates in
 * the reference box's frame along the face's two in-plane axes (x[0] along
 * axis (k + 1) % 3, x[1] along (k + 2) % 3, k the face's axis) and along
 * k (x[2]); the features that make it; and, for the edge leaving it, the
 * reference side it runs along (-1: none) and its feature. */
typedef struct bb_vert {
    mk_real x[3];
    mk_feature fref, finc, edge;
    signed char ref_edge;
} bb_vert;

/* Side q of a box face (from its corner q to corner q + 1, box_face_corner
 * order) bounds in-plane coordinate x[ax] with outward sign `sign`. The
 * pattern is the same for every face: even faces (the - sides) run +v, +u,
 * -v, -u, odd faces -v, +u, +v, -u. */
MK_ALWAYS_INLINE int side_axis(int q) { return (q & 1) ? 0 : 1; }
MK_ALWAYS_INLINE mk_real side_sign(int face, int q)
{
    static const mk_real sign[2][4] = {{1, 1, -1, -1}, {-1, 1, 1, -1}};
    return sign[face & 1][q];
}

/* One Sutherland-Hodgman pass of clip.c's clip_polygon against side q of
 * reference face `face`: keeps the part of src where sign * x[ax] - h <=
 * slop. An inside end within the slop strip stands for the crossing; a
 * crossing is named by the incident edge and the reference side, or, when
 * it runs along a side already, by the reference corner between the two
 * sides (or the face). */
MK_ALWAYS_INLINE int clip_side(int face, int q, mk_feature finc_face, mk_real sign, int ax, mk_real h, mk_real slop, const bb_vert *src, int n,
                     bb_vert *dst)
{
    /* src[n] repeats src[0] (the closing edge), and dst's will too. */
    mk_feature side = E(mk_box_face_edge_[face][q]);
    int m = 0, i;
    mk_real da = sign * src[0].x[ax] - h;
    for (i = 0; i < n; ++i) {
        const bb_vert *a = &src[i], *b = a + 1;
        mk_real db = sign * b->x[ax] - h;
        int ina = da <= slop, inb = db <= slop;
        if (ina) dst[m++] = *a;
        if (ina != inb) {
            if ((ina ? da : db) > 0) {
                if (ina) {
                    dst[m - 1].ref_edge = (signed char)q;
                    dst[m - 1].edge = side;
                }
            } else {
                bb_vert *x = &dst[m++];
                mk_real t = da / (da - db);
                x->x[0] = a->x[0] + (b->x[0] - a->x[0]) * t;
                x->x[1] = a->x[1] + (b->x[1] - a->x[1]) * t;
                x->x[2] = a->x[2] + (b->x[2] - a->x[2]) * t;
                if (a->ref_edge < 0) {
                    x->fref = side;
                    x->finc = a->edge;
                } else {
                    int pe = a->ref_edge;
                    x->fref = pe == ((q + 3) & 3) ? V(mk_box_face_corner_[face][q])
                              : pe == ((q + 1) & 3) ? V(mk_box_face_corner_[face][(q + 1) & 3])
                                                    : F(face);
                    x->finc = finc_face;
                }
                if (ina) {
                    x->ref_edge = (signed char)q;
                    x->edge = side;
                } else {
                    x->ref_edge = a->ref_edge;
                    x->edge = a->edge;
                }
            }
        }
        da = db;
    }
    if (m > 0) dst[m] = dst[0];
    return m;
}

/* Where box_clip writes its points: the manifold itself (m set: A's
 * pose, the normal in A's frame and in world, A's radius), or the
 * candidates for the tests (mk_box_box_clip). */
typedef struct bb_out {
    mk_manifold *m;
    const mk_pose *xa, *xb;
    mk_vec3 n, nw;
    mk_vec3 off; /* reference A: -R^T t - rb R^T n; reference B: p_B + ra nw (see box_clip) */
    mk_bb_point *pts;
} bb_out;

/* Point i of the manifold: its points on A's surface in A's frame (la)
 * and in world (wa), on B's in B's frame (lb), and its depth; point_b =
 * point_a - depth n, the contract's relation. */
MK_ALWAYS_INLINE void put(mk_manifold *out, int i, mk_vec3 nw, mk_vec3 la, mk_vec3 wa, mk_vec3 lb, mk_real depth, uint32_t features)
{
    mk_contact_point *c = &out->points[i];
    c->point_a = wa;
    c->point_b = mk_v3_mad(wa, -depth, nw);
    c->local_a = la;
    c->local_b = lb;
    c->depth = depth;
    c->features = features;
    c->flags = (uint32_t)(depth < 0) * MK_CONTACT_SPECULATIVE;
}


/* Column k of m. */
MK_ALWAYS_INLINE const mk_vec3 *column(const mk_mat3 *m, int k) { return k == 0 ? &m->c0 : k == 1 ? &m->c1 : &m->c2; }

/* Entry (row x, column c) of R (column c = B's axis c in A's frame). */
MK_ALWAYS_INLINE mk_real rc(const mk_mat3 *R, int x, int c)
{
    const mk_vec3 *col = c == 0 ? &R->c0 : c == 1 ? &R->c1 : &R->c2;
    return x == 0 ? col->x : x == 1 ? col->y : col->z;
}

/* The clip of mk_box_box_clip (see manifold_internal.h), with the
 * reference box, the face and `reduce` constant where it is inlined;
 * returns the count and writes the points as `o` says. */
MK_ALWAYS_INLINE int box_clip(const mk_pair *p, int ref_is_a, int face, mk_real slop, mk_real margin, int reduce, const bb_out *o)
{
    const mk_shape *ref = ref_is_a ? p->a : p->b, *inc = ref_is_a ? p->b : p->a;
    mk_real m[3][3], tr[3], hh[3], g[3], hf[2], lo[2], hi[2], rr = p->a->radius + p->b->radius;
    mk_real sgn = face & 1 ? 1 : -1, gs, sf;
    mk_real x[MK_BB_CLIP_MAX], y[MK_BB_CLIP_MAX], depth[MK_BB_CLIP_MAX];
    bb_vert buf[2][MK_BB_CLIP_MAX + 1];
    static const unsigned char next[3] = {1, 2, 0}, prev[3] = {2, 0, 1};
    static const mk_real sign[2] = {-1, 1};
    int k = face >> 1, iu = next[k], iv = prev[k], ia, ju, jv, fi, i, q, cnt = 4, cur = 0, n = 0, idx[MK_BB_CLIP_MAX], pick[MK_BB_CLIP_MAX];
    mk_feature finc_face;
    /* The incident box in the reference frame: x_ref = m x_inc + tr (R and
     * t for B in A's frame, R^T and -R^T t for A in B's). */
    for (i = 0; i < 3; ++i) {
        m[i][0] = ref_is_a ? rc(&p->r, i, 0) : rc(&p->r, 0, i);
        m[i][1] = ref_is_a ? rc(&p->r, i, 1) : rc(&p->r, 1, i);
        m[i][2] = ref_is_a ? rc(&p->r, i, 2) : rc(&p->r, 2, i);
    }
    if (ref_is_a) {
        tr[0] = p->t.x, tr[1] = p->t.y, tr[2] = p->t.z;
    } else {
        for (i = 0; i < 3; ++i) tr[i] = -(m[i][0] * p->t.x + m[i][1] * p->t.y + m[i][2] * p->t.z);
    }
    hh[0] = ref->u.half_extents.x, hh[1] = ref->u.half_extents.y, hh[2] = ref->u.half_extents.z;
    g[0] = inc->u.half_extents.x, g[1] = inc->u.half_extents.y, g[2] = inc->u.half_extents.z;
    hf[0] = hh[iu], hf[1] = hh[iv];
    /* The incident face: the incident box's face most against the normal
     * (-sgn e_k in the reference frame faces the incident box), ties to the
     * lower axis, as mk_support_feature picks it. Which face that is, is
     * data: chosen in arithmetic, and its sign taken as a factor. */
    {
        mk_real d0 = mk_fabs_(m[k][0]), d1 = mk_fabs_(m[k][1]), d2 = mk_fabs_(m[k][2]);
        ia = !((d0 >= d1) & (d0 >= d2)) * (2 - (d1 >= d2));
    }
    fi = 2 * ia + (-sgn * m[k][ia] >= 0);
    finc_face = F(fi);
    ju = next[ia], jv = prev[ia];
    sf = sign[fi & 1];
    gs = sf * g[ia];
    /* Corners c0 - s, c0 + t, c0 + s, c0 - t in box_face_corner order, s
     * and t = cu -+ cv on a + face, swapped on a - face (the order runs the
     * other way); only the face's coordinates (u, v) and the height axis
     * (z). */
    {
        int j;
        for (j = 0; j < 3; ++j) {
            int row = j == 0 ? iu : j == 1 ? iv : k;
            mk_real cu = m[row][ju] * g[ju], cv = sf * (m[row][jv] * g[jv]), c0 = tr[row] + gs * m[row][ia], s = cu + cv, t = cu - cv;
            buf[0][0].x[j] = c0 - s, buf[0][1].x[j] = c0 + t, buf[0][2].x[j] = c0 + s, buf[0][3].x[j] = c0 - t;
        }
        for (i = 0; i < 4; ++i) {
            bb_vert *v = &buf[0][i];
            v->fref = F(face);
            v->finc = V(mk_box_face_corner_[fi][i]);
            v->ref_edge = -1;
            v->edge = E(mk_box_face_edge_[fi][i]);
        }
        buf[0][4] = buf[0][0];
        for (j = 0; j < 2; ++j) {
            lo[j] = mk_min(mk_min(buf[0][0].x[j], buf[0][1].x[j]), mk_min(buf[0][2].x[j], buf[0][3].x[j]));
            hi[j] = mk_max(mk_max(buf[0][0].x[j], buf[0][1].x[j]), mk_max(buf[0][2].x[j], buf[0][3].x[j]));
        }
    }
    /* A side no corner is outside of (by more than its slop, m->slop times
     * the side's length, as clip.c's side_planes sets it) cuts nothing, and
     * no crossing made by another side is outside it either: skipped. */
    for (q = 0; q < 4 && cnt > 0; ++q) {
        int ax = side_axis(q);
        mk_real sg = side_sign(face, q), side_slop = 2 * slop * hf[1 - ax];
        if (!((sg > 0 ? hi[ax] : -lo[ax]) - hf[ax] <= side_slop))
            cnt = clip_side(face, q, finc_face, sg, ax, hf[ax], side_slop, buf[cur], cnt, buf[cur ^ 1]), cur ^= 1;
    }
    /* Depths from the heights over the face; candidates beyond the margin
     * go (each written, counted only if kept: no branch on the data). */
    for (i = 0; i < cnt; ++i) {
        const bb_vert *v = &buf[cur][i];
        mk_real d = rr - (sgn * v->x[2] - hh[k]);
        x[n] = v->x[0], y[n] = v->x[1], depth[n] = d, idx[n] = i;
        n += d >= -margin;
    }
    if (reduce && n > MK_MANIFOLD_MAX_POINTS) {
        n = mk_mf_pick4(n, x, y, depth, pick);
    } else {
        for (i = 0; i < n; ++i) pick[i] = i;
    }
    for (i = 0; i < n; ++i) {
        const bb_vert *v = &buf[cur][idx[pick[i]]];
        mk_real c[3], w = sgn * v->x[2] - hh[k];
        uint32_t features = ref_is_a ? MK_FEATURE_PAIR(v->fref, v->finc) : MK_FEATURE_PAIR(v->finc, v->fref);
        c[iu] = v->x[0], c[iv] = v->x[1], c[k] = v->x[2];
        if (o->m) {
            /* q is a point of the incident core. Reference A: la is q on
             * A's face pushed out by A's radius, lb = R^T (q - t) - rb
             * R^T n on B's surface. Reference B: lb is q moved by the
             * height less B's radius along B's face normal (-sgn e_k), la
             * = R q + t + ra n, and in world R_B q + p_B + ra nw: one
             * rotation per frame. */
            mk_real ra = p->a->radius;
            mk_vec3 q3 = mk_v3(c[0], c[1], c[2]), la, lb, wa;
            if (ref_is_a) {
                la = mk_v3_mad(q3, ra - w, o->n);
                wa = mk_v3_add(mk_mat3_mul_v3(o->xa->r, la), o->xa->p);
                lb = mk_v3_add(mk_mat3_tmul_v3(p->r, q3), o->off);
            } else {
                la = mk_v3_mad(mk_v3_add(mk_mat3_mul_v3(p->r, q3), p->t), ra, o->n);
                wa = mk_v3_add(mk_mat3_mul_v3(o->xb->r, q3), o->off);
                c[k] -= sgn * (w - p->b->radius);
                lb = mk_v3(c[0], c[1], c[2]);
            }
            put(o->m, i, o->nw, la, wa, lb, depth[pick[i]], features);
        } else {
            o->pts[i].q = mk_v3(c[0], c[1], c[2]);
            o->pts[i].depth = depth[pick[i]];
            o->pts[i].height = w;
            o->pts[i].features = features;
        }
    }
    return n;
}

int mk_box_box_clip(const mk_pair *p, int ref_is_a, int face, mk_real slop, mk_real margin, int reduce, mk_bb_point *out)
{
    bb_out o;
    memset(&o, 0, sizeof o);
    o.pts = out;
    return box_clip(p, ref_is_a, face, slop, margin, reduce, &o);
}

/* The reduced clip written into the manifold, with the reference box and
 * face as constants. */
static int clip_reduced(const mk_pair *p, int ref_is_a, int face, mk_real slop, mk_real margin, const bb_out *o)
{
    return ref_is_a ? box_clip(p, 1, face, slop, margin, 1, o) : box_clip(p, 0, face, slop, margin, 1, o);
}

/* ---- SAT: the 15 axes in closed form (sat_box.h) ---------------------------- */

void mk_sat_box_box(mk_vec3 ha, mk_vec3 hb, const mk_mat3 *R, mk_vec3 t, const mk_sat_options *opt, mk_sat_result *out)
{
    mk_sat_box_box_inl(ha, hb, R, t, opt, out);
}

/* Midpoint of box edge `id` (minko/manifold.h numbering): 0 along its
 * axis, +-h along the other two by the id's bits, as the mean of its two
 * ends would be; by factors of +-1, since the edge is data. */
MK_ALWAYS_INLINE mk_vec3 box_edge_mid(mk_vec3 h, int id)
{
    static const mk_real sign[2] = {-1, 1};
    static const unsigned char lo_of[3] = {1, 0, 0}, hi_of[3] = {2, 2, 1};
    int axis = id / 4;
    mk_real c[3];
    c[lo_of[axis]] = sign[id & 1];
    c[hi_of[axis]] = sign[(id >> 1) & 1];
    c[axis] = 0;
    return mk_v3(c[0] * h.x, c[1] * h.y, c[2] * h.z);
}

/* The one contact of an edge-pair axis of two boxes: mk_mf_edge_contact's
 * answer from the edges' midpoints and unit axes, A's edge s e_i about ma
 * (|s| <= h_i), B's c + t R_j about mb (|t| <= g_j, c = mb - ma), which
 * mk_segment_params takes with unit constants. */
static mk_real box_edge_contact(const mk_pair *p, int ea, int eb, mk_real sep, mk_real rr, mk_vec3 *qa, mk_feature *fa, mk_feature *fb)
{
    int ia = mk_box_hull_edge_id(ea), ib = mk_box_hull_edge_id(eb), i = ia / 4, j = ib / 4;
    mk_vec3 ma, mb, c, rj = *column(&p->r, j), q;
    mk_real ha[3], cc[3], x[3], s, t;
    ma = box_edge_mid(p->a->u.half_extents, ia);
    mb = mk_v3_add(mk_mat3_mul_v3(p->r, box_edge_mid(p->b->u.half_extents, ib)), p->t);
    c = mk_v3_sub(mb, ma);
    ha[0] = p->a->u.half_extents.x, ha[1] = p->a->u.half_extents.y, ha[2] = p->a->u.half_extents.z;
    cc[0] = c.x, cc[1] = c.y, cc[2] = c.z;
    x[0] = rj.x, x[1] = rj.y, x[2] = rj.z;
    mk_segment_params(1, 1, x[i], cc[i], mk_v3_dot(c, rj), x[(i + 1) % 3] * x[(i + 1) % 3] + x[(i + 2) % 3] * x[(i + 2) % 3], ha[i],
                      (j == 0 ? p->b->u.half_extents.x : j == 1 ? p->b->u.half_extents.y : p->b->u.half_extents.z), &s, &t);
    q = ma;
    if (i == 0) q.x = s;
    else if (i == 1) q.y = s;
    else q.z = s;
    *qa = q;
    *fa = MK_FEATURE(MK_FEATURE_EDGE, ia);
    *fb = MK_FEATURE(MK_FEATURE_EDGE, ib);
    /* Apart, the edges' closest points are a gap only if neither end clamped. */
    if (sep > 0) sep = mk_v3_dist(q, mk_v3_mad(mb, t, rj));
    return rr - sep;
}

/* ---- the whole pair ---------------------------------------------------------- */


/* An edge pair whose cross product is a face normal (an edge of B lying
 * parallel to a face of A, as in every box resting flat on another) is that
 * face's axis, with the same separation; which of the two SAT reports is
 * round-off. Name it as the face, so a flat contact clips to a face: the
 * normal is one of A's axes (faces of A first, as SAT breaks ties) or one
 * of B's; the face is the one the normal leaves A through, or enters B
 * through. */
static void face_axis(const mk_pair *p, mk_sat_result *sat)
{
    mk_real one = 1 - 64 * MK_REAL_EPSILON, n[3], nb[3];
    mk_vec3 l = mk_mat3_tmul_v3(p->r, sat->normal);
    int k;
    n[0] = sat->normal.x, n[1] = sat->normal.y, n[2] = sat->normal.z;
    nb[0] = l.x, nb[1] = l.y, nb[2] = l.z;
    for (k = 0; k < 3; ++k) {
        if (mk_fabs_(n[k]) >= one) {
            sat->kind = MK_SAT_FACE_A;
            sat->a = 2 * k + (n[k] > 0);
            sat->b = -1;
            return;
        }
    }
    for (k = 0; k < 3; ++k) {
        if (mk_fabs_(nb[k]) >= one) {
            sat->kind = MK_SAT_FACE_B;
            sat->a = -1;
            sat->b = 2 * k + (nb[k] < 0);
            return;
        }
    }
}

/* An empty manifold (the normal is undefined then; kept as before). */
static void none(mk_manifold *out, mk_vec3 n)
{
    out->count = 0;
    out->normal = n;
}

/* Cores apart (rounded or speculative boxes): SAT's separation is only a
 * lower bound of their distance, reached when the points built along the
 * axis realise it (a face over a face, two edges crossing inside both). If
 * they fall short (two cube edges side by side: the face axes separate by
 * less than the edges are apart, and the faces' clip is empty), the exact
 * core distance comes from GJK (mk_collide's generic path) instead. */
#ifndef MK_WITHOUT_GJK
static int realised(const mk_manifold *m, int count, mk_real depth, const mk_pair *p)
{
    mk_real tol = mk_mf_realise_tol(p);
    int i;
    for (i = 0; i < count; ++i)
        if (m->points[i].depth >= depth - tol) return 1;
    return 0;
}
#endif

/* Two boxes that were apart last frame and still are along the same axis:
 * that one axis straight from the world poses, before the relative pose or
 * anything else is built, and the hint kept for the next frame (an edge
 * axis, mk_sat_box_box_edge_apart, stays named as one, even where
 * face_axis() would rename it as a face it has become parallel to: the same
 * axis). A face axis needs one column of each rotation dotted with the
 * other three: the axis's components along the other box's axes.
 * Broadphase pairs of boxes whose bounding boxes overlap mostly end here.
 * Otherwise the hint is dropped (an axis that no longer separates by more
 * than the margin changes no answer; hinted()). The separations are
 * mk_sat_box_box's along the same axes, to rounding. This is the boxes'
 * form of mk_sat_options.first, which mk_sat_box_box does not take: done
 * here, it needs no relative pose at all.
 *
 * The hint's face axis (A's face of kind MK_SAT_FACE_A, B's otherwise):
 * 1 while it still separates the boxes by more than the margin. Inline in
 * mk_box_box_collide, which then needs no frame: most pairs that stay
 * apart stay apart along a face (bench_contacts apart: 77 %), and the out
 * of line call with hinted()'s frame was 15 of their 209 instructions and
 * 6 % of their time (17.1 -> 16.0 ns, 9 alternated runs, load 5.5). */
MK_ALWAYS_INLINE int face_stays_apart(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin,
                                      const mk_manifold_cache *cache, int of_a)
{
    /* The axis is the face's box axis k; which of its two faces (the
     * sign) does not change the separation, so the hint is kept as is. */
    int face = of_a ? cache->reference : (int)cache->face - 1;
    if (face >= 0 && face < 6) {
        const mk_pose *own = of_a ? xa : xb, *other = of_a ? xb : xa;
        const mk_vec3 *h = of_a ? &a->u.half_extents : &b->u.half_extents, *g = of_a ? &b->u.half_extents : &a->u.half_extents;
        mk_real rr = a->radius + b->radius;
        int k = face >> 1;
        mk_vec3 e = *column(&own->r, k);
        mk_real hk = k == 0 ? h->x : k == 1 ? h->y : h->z;
        mk_real sep = mk_fabs_(mk_v3_dot(e, mk_v3_sub(xb->p, xa->p))) - hk -
                      (mk_fabs_(mk_v3_dot(e, other->r.c0)) * g->x + mk_fabs_(mk_v3_dot(e, other->r.c1)) * g->y +
                       mk_fabs_(mk_v3_dot(e, other->r.c2)) * g->z);
        if (sep > margin + rr && sep - rr > margin) return 1;
    }
    return 0;
}

/* The hint's edge axis: 1 while it still separates the boxes by more than
 * the margin. The hint's half-edges name their edges' directions, all
 * the axis depends on: kept as they are while the pair stays apart. The
 * axis L = e_A x e_B straight from the world axes: in a right-handed frame
 * (e_i x e_B) . e_(i+1) = -e_B . e_(i+2) and (e_i x e_B) . e_(i+2) = e_B .
 * e_(i+1), so each box's reach along L takes two dot products, and
 * |L . d| one triple product: the separation box_edge_axis finds along
 * the same axis (to rounding), in about a fifth of the instructions of
 * forming the relative pose's two rows and minors first (bench_contacts
 * apart, callgrind: 200 -> 160 instructions per call, a pair in eight
 * stays apart along an edge axis). Edges too close to parallel (sat.h,
 * MK_SAT_PARALLEL) give no reliable axis: the hint is dropped. */
static int edges_stay_apart(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin,
                            const mk_manifold_cache *cache)
{
    int ea = cache->reference, eb = (int)cache->face - 1;
    if (ea >= 0 && ea < 24 && eb >= 0 && eb < 24) {
        static const unsigned char next[3] = {1, 2, 0}, prev[3] = {2, 0, 1};
        int i = mk_box_hull_edge_id(ea) / 4, j = mk_box_hull_edge_id(eb) / 4;
        const mk_vec3 *ha = &a->u.half_extents, *hb = &b->u.half_extents;
        mk_vec3 u = *column(&xa->r, i), w = *column(&xb->r, j), l = mk_v3_cross(u, w);
        mk_real rr = a->radius + b->radius, l2 = mk_v3_dot(l, l), ga[3], gb[3], reach, sep;
        ga[0] = ha->x, ga[1] = ha->y, ga[2] = ha->z;
        gb[0] = hb->x, gb[1] = hb->y, gb[2] = hb->z;
        reach = ga[next[i]] * mk_fabs_(mk_v3_dot(w, *column(&xa->r, prev[i]))) + ga[prev[i]] * mk_fabs_(mk_v3_dot(w, *column(&xa->r, next[i]))) +
                gb[next[j]] * mk_fabs_(mk_v3_dot(u, *column(&xb->r, prev[j]))) + gb[prev[j]] * mk_fabs_(mk_v3_dot(u, *column(&xb->r, next[j])));
        sep = (mk_fabs_(mk_v3_dot(l, mk_v3_sub(xb->p, xa->p))) - reach) / mk_sqrt_(l2);
        if (edge_counted(l2) && sep > margin + rr && sep - rr > margin) return 1;
    }
    return 0;
}

/* MK_MANIFOLD_TOUCHING_ONLY: the first `count` points of depth >= 0, in
 * their order; returns how many. */
static int touching(mk_manifold *m, int count)
{
    int i, n = 0;
    for (i = 0; i < count; ++i)
        if (m->points[i].depth >= 0) m->points[n++] = m->points[i];
    return n;
}

/* Everything after the hint (out of line: the pair that stays apart
 * needs none of this frame). */
static MK_NOINLINE mk_status collide(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin, mk_manifold_cache *cache,
                               mk_manifold *out)
{
    mk_real ra = a->radius, rb = b->radius;
    mk_vec3 ha = a->u.half_extents, hb = b->u.half_extents, n, nw;
    mk_sat_options opt;
    mk_sat_result sat;
    mk_pair p;
    int count;
    p = mk_pair_of_poses_(a, xa, b, xb);
    opt.stop_above = margin + ra + rb;
    opt.prefer = cache ? (mk_sat_kind)cache->axis : MK_SAT_NONE;
    opt.prefer_rel = MK_MF_PREFER_REL;
    opt.prefer_abs = opt.prefer == MK_SAT_NONE ? 0 : MK_MF_PREFER_ABS * mk_min(mk_v3_min_comp(ha), mk_v3_min_comp(hb));
    opt.hold_face = !cache || cache->mode == MK_MANIFOLD_STABLE_IDS;
    mk_sat_box_box_inl(ha, hb, &p.r, p.t, &opt, &sat);
    if (sat.kind == MK_SAT_EDGES) face_axis(&p, &sat);
    if (sat.best - ra - rb > margin) {
        if (cache) {
            cache->axis = MK_MF_APART_HINT + (int)sat.kind;
            cache->reference = sat.a;
            cache->face = (mk_feature)(sat.b + 1);
        }
        none(out, xa->r.c2);
        return MK_OK;
    }
    if (cache) cache->axis = (int)sat.kind;
    /* Sharp boxes apart, and the host wants no speculative point: nothing
     * to clip (nor GJK's exact distance), the axis kind kept as above.
     * (Rounded ones go on: the GJK fallback's warm state, its simplex and
     * kept face, must advance as without the flag.) */
    if (sat.best > 0 && ra + rb == 0 && cache && (cache->flags & MK_MANIFOLD_TOUCHING_ONLY)) {
        none(out, xa->r.c2);
        return MK_OK;
    }
    n = sat.normal;
    nw = mk_mat3_mul_v3(xa->r, n);
    if (sat.kind != MK_SAT_EDGES) {
        /* Rounded cores apart clip without slop (clip.c). */
        int ref_is_a = sat.kind == MK_SAT_FACE_A, face = ref_is_a ? sat.a : sat.b;
        mk_real slop = sat.separation > 0 && ra + rb > 0 ? 0 : cache && cache->mode == MK_MANIFOLD_BEST_FACE ? MK_MF_SLOP_EXACT : MK_MF_SLOP_IDS;
        bb_out o;
        o.m = out;
        o.pts = NULL;
        o.xa = xa;
        o.xb = xb;
        o.n = n;
        o.nw = nw;
        o.off = ref_is_a ? mk_v3_neg(mk_mat3_tmul_v3(p.r, mk_v3_mad(p.t, rb, n))) : mk_v3_mad(xb->p, ra, nw);
        count = clip_reduced(&p, ref_is_a, face, slop, margin, &o);
    } else {
        /* Edge pair: the closest points of the two edges, one point. */
        mk_vec3 qa;
        mk_feature fa, fb;
        mk_real depth = box_edge_contact(&p, sat.a, sat.b, sat.separation, ra + rb, &qa, &fa, &fb);
        count = 0;
        if (depth >= -margin) {
            mk_vec3 la = mk_v3_mad(qa, ra, n);
            put(out, 0, nw, la, mk_v3_add(mk_mat3_mul_v3(xa->r, la), xa->p), mk_mat3_tmul_v3(p.r, mk_v3_sub(mk_v3_mad(la, -depth, n), p.t)), depth,
                MK_FEATURE_PAIR(fa, fb));
            count = 1;
        }
    }
#ifndef MK_WITHOUT_GJK
    if (sat.separation > 0 && !realised(out, count, ra + rb - sat.separation, &p)) return mk_collide_gjk_(a, xa, b, xb, margin, cache, out);
#endif
    if (cache && (cache->flags & MK_MANIFOLD_TOUCHING_ONLY)) count = touching(out, count);
    out->normal = nw;
    out->count = count;
    return MK_OK;
}

/* Bounding balls about the centres farther apart than the margin: no
 * contact, and nothing carried to the next frame. */
MK_ALWAYS_INLINE int balls_apart(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin, mk_manifold_cache *cache,
                                 mk_manifold *out)
{
    mk_real reach = a->radius + mk_v3_len(a->u.half_extents) + b->radius + mk_v3_len(b->u.half_extents) + margin;
    if (!(mk_v3_len2(mk_v3_sub(xb->p, xa->p)) > reach * reach)) return 0;
    if (cache) cache->axis = MK_SAT_NONE;
    none(out, mk_v3(0, 0, 1));
    return 1;
}

/* A pair that was apart last frame along an edge axis, or along a face
 * axis that no longer separates it: the edge axis, else the hint dropped
 * and the whole pass (both ends tail calls, so neither path keeps the
 * other's frame). */
static MK_NOINLINE mk_status hinted(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin,
                                    mk_manifold_cache *cache, mk_manifold *out)
{
    if (cache->axis - MK_MF_APART_HINT == MK_SAT_EDGES && edges_stay_apart(a, xa, b, xb, margin, cache)) {
        none(out, mk_v3(0, 0, 1));
        return MK_OK;
    }
    cache->axis = cache->reference = 0;
    cache->face = 0;
    if (balls_apart(a, xa, b, xb, margin, cache, out)) return MK_OK;
    return collide(a, xa, b, xb, margin, cache, out);
}

mk_status mk_box_box_collide(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin,
                             mk_manifold_cache *cache, mk_manifold *out)
{
    if (cache && cache->axis > MK_MF_APART_HINT) {
        int kind = cache->axis - MK_MF_APART_HINT;
        if ((kind == MK_SAT_FACE_A || kind == MK_SAT_FACE_B) && face_stays_apart(a, xa, b, xb, margin, cache, kind == MK_SAT_FACE_A)) {
            none(out, mk_v3(0, 0, 1));
            return MK_OK;
        }
        return hinted(a, xa, b, xb, margin, cache, out);
    }
    if (balls_apart(a, xa, b, xb, margin, cache, out)) return MK_OK;
    return collide(a, xa, b, xb, margin, cache, out);
}

#endif

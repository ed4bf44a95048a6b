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
 * |u| <= h_u, |v| <= h_v. The clip takes no side passes (clip_exact):
 * the incident corners inside, the crossings of incident edges with the
 * sides, the reference corners inside the incident face, each computed
 * once from the four corners. Only where the clip slop decides (a corner
 * in a side's slop strip) or round-off could (a point within it of a side
 * or an edge) do the Sutherland-Hodgman passes of clip.c's general clip,
 * specialised here (clip_strip), answer instead; both give the general
 * clip's points with its feature IDs, listed in one fixed order of the
 * features (rank()), which the reduction's preference for earlier
 * candidates follows. The candidates are reduced to four in the face's
 * coordinates (mk_mf_pick4) and written straight into the mk_manifold,
 * each with two matrix-vector products (tests/test_clip.c compares the
 * clips with the general one on random, stacked and rounded pairs,
 * tests/test_box_box.c whole manifolds, cold and warm).
 *
 * Where the instructions go (callgrind, mk_collide_pose per call on
 * demos/bench_contacts --quick's tilted stacked boxes, about 2.7k in all):
 * SAT 0.6k (the nine edge axes half of it: four of them tie with the face
 * on stacked boxes, so none can be pruned), the face clip 0.55k plus 0.05k
 * for the strip passes (taken on ~6 % of the clips), the incident face and
 * the depths 0.3k, the reduction 0.25k (5 to 8 candidates on 43 % of the
 * calls), writing the points 0.35k (two matrix products each), the rest
 * (checks, pose, SAT options, edge contacts) 0.6k. A pair that stays apart
 * along last frame's axis costs 0.2k. */
#include <string.h>

#include "manifold_internal.h"
#include "polytope.h"
#include "pose.h"
#include "sat.h"
#include "shape_internal.h"

#ifndef MK_WITHOUT_SAT

#define V(i) MK_FEATURE(MK_FEATURE_VERTEX, i)
#define E(i) MK_FEATURE(MK_FEATURE_EDGE, i)
#define F(i) MK_FEATURE(MK_FEATURE_FACE, i)

/* A vertex of the incident face while it is clipped: its coordinates in
 * the reference box's frame along the face's two in-plane axes (x[0] along
 * axis (k + 1) % 3, x[1] along (k + 2) % 3, k the face's axis) and along
 * k (z); the features that make it; and, for the edge leaving it, the
 * reference side it runs along (-1: none) and its feature. */
typedef struct bb_vert {
    mk_real x[2], z;
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
                x->z = a->z + (b->z - a->z) * t;
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

/* The clip's candidates in the reference face's coordinates (u, v as
 * bb_vert's x[0], x[1]; z along the face's axis), each with its key:
 * reference feature << 16 | incident feature. They are kept in ascending
 * key order, a fixed order of the features (reference corners, then
 * crossings by reference side and incident edge, then incident corners),
 * so the reduction's preference for earlier candidates does not depend on
 * how the clip got them. */
typedef struct bb_cand {
    mk_real u[MK_BB_CLIP_MAX], v[MK_BB_CLIP_MAX], z[MK_BB_CLIP_MAX];
    uint32_t key[MK_BB_CLIP_MAX];
} bb_cand;

#define KEY(fref, finc) ((uint32_t)(fref) << 16 | (uint32_t)(finc))

MK_ALWAYS_INLINE void cand(bb_cand *o, int i, mk_real u, mk_real v, mk_real z, uint32_t key)
{
    o->u[i] = u, o->v[i] = v, o->z[i] = z, o->key[i] = key;
}

/* The incident face in the reference face's coordinates: its centre c,
 * half axes a1 and a2 (u, v, z each), its corners in box_face_corner order
 * of its face fi (index 4 repeats 0). */
typedef struct bb_inc {
    mk_real c[3], a1[3], a2[3];
    mk_real u[5], v[5], z[5];
    int fi;
} bb_inc;

/* Canonical sides s of the reference rectangle: 0 +u, 1 +v, 2 -u, 3 -v;
 * canonical corner s lies between sides s and s + 1. Per parity of the
 * reference face, side s is its side q = side_q[.][s] (side_axis,
 * side_sign) and corner s its corner q = corner_q[.][s] (box_face_corner
 * order: corner q lies between sides q - 1 and q). */
static const unsigned char side_q[2][4] = {{1, 0, 3, 2}, {1, 2, 3, 0}};
static const unsigned char corner_q[2][4] = {{1, 0, 3, 2}, {2, 3, 0, 1}};

/* Position of feature index f in a face's list of four (4: none). */
static int position(const unsigned char *list, int f)
{
    int i = 0;
    while (i < 4 && list[i] != f) ++i;
    return i;
}

/* The order the clip's candidates come in, which the reduction's
 * preference for earlier ones follows: reference corners by canonical
 * corner, crossings by incident edge (box_face_edge order of the incident
 * face fi) then canonical side, incident corners (box_face_corner order);
 * anything else (the strip rule's rare names) last. */
static int rank(int face, int fi, mk_feature fref, mk_feature finc)
{
    static const unsigned char side_s[2][4] = {{1, 0, 3, 2}, {3, 0, 1, 2}}, corner_s[2][4] = {{1, 0, 3, 2}, {2, 3, 0, 1}};
    int r = MK_FEATURE_GET_INDEX(fref), c = MK_FEATURE_GET_INDEX(finc), q;
    if (MK_FEATURE_TYPE(fref) == MK_FEATURE_VERTEX && finc == F(fi)) {
        q = position(mk_box_face_corner_[face], r);
        return q < 4 ? corner_s[face & 1][q] : 24;
    }
    if (MK_FEATURE_TYPE(fref) == MK_FEATURE_EDGE && MK_FEATURE_TYPE(finc) == MK_FEATURE_EDGE) {
        int i = position(mk_box_face_edge_[fi], c);
        q = position(mk_box_face_edge_[face], r);
        return i < 4 && q < 4 ? 4 + 4 * i + side_s[face & 1][q] : 24;
    }
    if (fref == F(face) && MK_FEATURE_TYPE(finc) == MK_FEATURE_VERTEX) {
        q = position(mk_box_face_corner_[fi], c);
        return q < 4 ? 20 + q : 24;
    }
    return 24;
}

/* The rule of the slop strip: the Sutherland-Hodgman passes above, one per
 * side some corner is outside of; the candidates then sorted by key.
 * Taken only when some point falls in a strip or within round-off of a
 * side (clip_exact says when), so it may be slow. */
static MK_NOINLINE int clip_strip(int face, const bb_inc *in, const mk_real *hf, mk_real slop, bb_cand *o)
{
    bb_vert buf[2][MK_BB_CLIP_MAX + 1];
    mk_real lo[2], hi[2];
    mk_feature finc_face = F(in->fi);
    int cnt = 4, cur = 0, i, q, rk[MK_BB_CLIP_MAX];
    for (i = 0; i < 4; ++i) {
        bb_vert *v = &buf[0][i];
        v->x[0] = in->u[i], v->x[1] = in->v[i], v->z = in->z[i];
        v->fref = F(face);
        v->finc = V(mk_box_face_corner_[in->fi][i]);
        v->ref_edge = -1;
        v->edge = E(mk_box_face_edge_[in->fi][i]);
    }
    buf[0][4] = buf[0][0];
    lo[0] = mk_min(mk_min(in->u[0], in->u[1]), mk_min(in->u[2], in->u[3]));
    hi[0] = mk_max(mk_max(in->u[0], in->u[1]), mk_max(in->u[2], in->u[3]));
    lo[1] = mk_min(mk_min(in->v[0], in->v[1]), mk_min(in->v[2], in->v[3]));
    hi[1] = mk_max(mk_max(in->v[0], in->v[1]), mk_max(in->v[2], in->v[3]));
    /* A side no corner is outside of (by more than its slop, m->slop times
     * the side's length, as clip.c's side_planes sets it) cuts nothing, and
     * no crossing made by another side is outside it either: skipped. */
    for (q = 0; q < 4 && cnt > 0; ++q) {
        int ax = side_axis(q);
        mk_real sg = side_sign(face, q), side_slop = 2 * slop * hf[1 - ax];
        if (!((sg > 0 ? hi[ax] : -lo[ax]) - hf[ax] <= side_slop))
            cnt = clip_side(face, q, finc_face, sg, ax, hf[ax], side_slop, buf[cur], cnt, buf[cur ^ 1]), cur ^= 1;
    }
    /* Into clip_exact's order (insertion sort by rank, stable). */
    for (i = 0; i < cnt; ++i) {
        const bb_vert *v = &buf[cur][i];
        int j, r = rank(face, in->fi, v->fref, v->finc);
        for (j = i; j > 0 && rk[j - 1] > r; --j) {
            rk[j] = rk[j - 1];
            cand(o, j, o->u[j - 1], o->v[j - 1], o->z[j - 1], o->key[j - 1]);
        }
        rk[j] = r;
        cand(o, j, v->x[0], v->x[1], v->z, KEY(v->fref, v->finc));
    }
    return cnt;
}

/* The crossing of incident edge i with the side line u = c (cross_u) or
 * v = c (cross_v), appended as candidate n when the other coordinate is
 * within its side's half size h (+ slop s). Returns the new count, or -1
 * when that coordinate lies in the slop strip or within round-off of h
 * (its position along the side is ill-conditioned by the edge's slope). */
MK_ALWAYS_INLINE int cross_at(const mk_real *x, const mk_real *y, const mk_real *z, int i, mk_real c, mk_real h, mk_real s, mk_real tol, int n,
                              int along_v, uint32_t key, bb_cand *o)
{
    mk_real dx = x[i + 1] - x[i], dy = y[i + 1] - y[i], t = (c - x[i]) / dx, yo = y[i] + dy * t, e = mk_fabs_(yo) - h;
    mk_real lim = tol * (1 + mk_fabs_(dy / dx));
    if (e > s + lim) return n;
    if (e > -lim) return -1;
    if (along_v) cand(o, n, c, yo, z[i] + (z[i + 1] - z[i]) * t, key);
    else cand(o, n, yo, c, z[i] + (z[i + 1] - z[i]) * t, key);
    return n + 1;
}

/* Reference corner (ru, rv) inside the incident face? Its coordinates in
 * the face's half axes, times det, must both be below |det| (ad); -1
 * within round-off (band) of an edge. Appended as candidate n. */
MK_ALWAYS_INLINE int ref_corner(const bb_inc *in, mk_real ru, mk_real rv, mk_real det, mk_real ad, mk_real band, int n, uint32_t key, bb_cand *o)
{
    mk_real du = ru - in->c[0], dv = rv - in->c[1];
    mk_real al = du * in->a2[1] - dv * in->a2[0], be = in->a1[0] * dv - in->a1[1] * du;
    mk_real ea = mk_fabs_(al) - ad, eb = mk_fabs_(be) - ad;
    if (ea > band || eb > band) return n;
    if (ea > -band || eb > -band) return -1;
    cand(o, n, ru, rv, in->c[2] + (al * in->a1[2] + be * in->a2[2]) / det, key);
    return n + 1;
}

/* The clip of the incident face against the reference rectangle |u| <=
 * hu, |v| <= hv without side passes, each point computed once from the
 * corners: the reference corners inside the incident face, the crossings
 * of the incident edges with the sides that lie within the other two
 * sides, the incident corners inside (the order of rank()). These are the
 * points of the passes (the polygon they leave is the same), unless a
 * corner lies in a side's slop strip (su, sv: outside by at most that
 * much), where the passes keep it in place of the crossings, or a
 * crossing or a reference corner lies within round-off (tol, absolute)
 * of a side or an incident edge, where the passes' order of rounding
 * decides: then -1, and clip_strip answers. */
MK_ALWAYS_INLINE int clip_exact(int face, const bb_inc *in, mk_real hu, mk_real hv, mk_real su, mk_real sv, mk_real tol, bb_cand *o)
{
    const unsigned char *ic = mk_box_face_corner_[in->fi];
    int oc[5], all = 0, n = 0, i;
    /* Outcodes: bit s set when the corner is beyond side s by more than its slop. */
    for (i = 0; i < 4; ++i) {
        mk_real eu = mk_fabs_(in->u[i]) - hu, ev = mk_fabs_(in->v[i]) - hv;
        int c = 0;
        if (eu > 0) {
            if (!(eu > su)) return -1;
            c = in->u[i] > 0 ? 1 : 4;
        }
        if (ev > 0) {
            if (!(ev > sv)) return -1;
            c |= in->v[i] > 0 ? 2 : 8;
        }
        oc[i] = c;
        all |= c;
    }
    if (all) {
        const unsigned char *fe = mk_box_face_edge_[face], *ie = mk_box_face_edge_[in->fi], *sq = side_q[face & 1];
        int both = all & (all >> 1 | all << 3) & 15;
        oc[4] = oc[0];
        /* Reference corner s can be inside only when some incident corners
         * are beyond both its sides, s and s + 1. */
        if (both) {
            const unsigned char *fc = mk_box_face_corner_[face], *cq = corner_q[face & 1];
            mk_real det = in->a1[0] * in->a2[1] - in->a1[1] * in->a2[0], ad = mk_fabs_(det);
            mk_real band = tol * (mk_fabs_(in->a1[0]) + mk_fabs_(in->a1[1]) + mk_fabs_(in->a2[0]) + mk_fabs_(in->a2[1]));
            uint32_t kf = F(in->fi);
            if ((both & 1) && (n = ref_corner(in, hu, hv, det, ad, band, n, KEY(V(fc[cq[0]]), kf), o)) < 0) return -1;
            if ((both & 2) && (n = ref_corner(in, -hu, hv, det, ad, band, n, KEY(V(fc[cq[1]]), kf), o)) < 0) return -1;
            if ((both & 4) && (n = ref_corner(in, -hu, -hv, det, ad, band, n, KEY(V(fc[cq[2]]), kf), o)) < 0) return -1;
            if ((both & 8) && (n = ref_corner(in, hu, -hv, det, ad, band, n, KEY(V(fc[cq[3]]), kf), o)) < 0) return -1;
        }
        for (i = 0; i < 4; ++i) {
            int x = oc[i] ^ oc[i + 1];
            uint32_t ke = E(ie[i]);
            if (!x) continue;
            if ((x & 1) && (n = cross_at(in->u, in->v, in->z, i, hu, hv, sv, tol, n, 1, KEY(E(fe[sq[0]]), ke), o)) < 0) return -1;
            if ((x & 2) && (n = cross_at(in->v, in->u, in->z, i, hv, hu, su, tol, n, 0, KEY(E(fe[sq[1]]), ke), o)) < 0) return -1;
            if ((x & 4) && (n = cross_at(in->u, in->v, in->z, i, -hu, hv, sv, tol, n, 1, KEY(E(fe[sq[2]]), ke), o)) < 0) return -1;
            if ((x & 8) && (n = cross_at(in->v, in->u, in->z, i, -hv, hu, su, tol, n, 0, KEY(E(fe[sq[3]]), ke), o)) < 0) return -1;
        }
    }
    for (i = 0; i < 4; ++i)
        if (!oc[i]) cand(o, n++, in->u[i], in->v[i], in->z[i], KEY(F(face), V(ic[i])));
    return n;
}

/* The clip of mk_box_box_clip (see manifold_internal.h), with the
 * reference box, the face and `reduce` constant where it is inlined;
 * returns the count and writes the points as `o` says. */
MK_ALWAYS_INLINE int box_clip(const mk_pair *p, int ref_is_a, int face, mk_real slop, mk_real margin, int reduce, const bb_out *o)
{
    const mk_shape *ref = ref_is_a ? p->a : p->b, *inc = ref_is_a ? p->b : p->a;
    mk_real m[3][3], tr[3], hh[3], g[3], hf[2], rr = p->a->radius + p->b->radius, tol;
    mk_real sgn = face & 1 ? 1 : -1, gs;
    mk_real x[MK_BB_CLIP_MAX], y[MK_BB_CLIP_MAX], depth[MK_BB_CLIP_MAX];
    static const unsigned char next[3] = {1, 2, 0}, prev[3] = {2, 0, 1};
    int k = face >> 1, iu = next[k], iv = prev[k], ia, ju, jv, i, cnt, n = 0, idx[MK_BB_CLIP_MAX], pick[MK_BB_CLIP_MAX];
    bb_inc in;
    bb_cand cd;
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
     * lower axis, as mk_support_feature picks it. */
    {
        mk_real d0 = mk_fabs_(m[k][0]), d1 = mk_fabs_(m[k][1]), d2 = mk_fabs_(m[k][2]);
        ia = (d0 >= d1 && d0 >= d2) ? 0 : (d1 >= d2 ? 1 : 2);
    }
    in.fi = 2 * ia + (-sgn * m[k][ia] >= 0);
    ju = next[ia], jv = prev[ia];
    gs = in.fi & 1 ? g[ia] : -g[ia];
    /* Corners c0 -+ cu -+ cv in box_face_corner order: (-, -), (+, -),
     * (+, +), (-, +) on a + face, reversed on a - face; only the face's
     * coordinates (u, v) and the height axis (z). */
    {
        int j;
        for (j = 0; j < 3; ++j) {
            int row = j == 0 ? iu : j == 1 ? iv : k;
            mk_real cu = m[row][ju] * g[ju], cv = m[row][jv] * g[jv], c0 = tr[row] + gs * m[row][ia], s = cu + cv, t = cu - cv;
            mk_real *w = j == 0 ? in.u : j == 1 ? in.v : in.z;
            in.c[j] = c0, in.a1[j] = cu, in.a2[j] = cv;
            if (in.fi & 1) w[0] = c0 - s, w[1] = c0 + t, w[2] = c0 + s, w[3] = c0 - t;
            else w[0] = c0 - t, w[1] = c0 + s, w[2] = c0 + t, w[3] = c0 - s;
            w[4] = w[0];
        }
    }
    /* Round-off of the corners' coordinates, far below any slop that matters. */
    tol = 64 * MK_REAL_EPSILON * (mk_fabs_(tr[0]) + mk_fabs_(tr[1]) + mk_fabs_(tr[2]) + g[0] + g[1] + g[2] + hf[0] + hf[1]);
    cnt = clip_exact(face, &in, hf[0], hf[1], 2 * slop * hf[1], 2 * slop * hf[0], tol, &cd);
    if (cnt < 0) cnt = clip_strip(face, &in, hf, slop, &cd);
    /* Depths from the heights over the face; candidates beyond the margin go. */
    for (i = 0; i < cnt; ++i) {
        mk_real d = rr - (sgn * cd.z[i] - hh[k]);
        if (!(d >= -margin)) continue;
        x[n] = cd.u[i], y[n] = cd.v[i], depth[n] = d, idx[n++] = i;
    }
    if (reduce && n > MK_MANIFOLD_MAX_POINTS) {
        n = mk_mf_pick4(n, x, y, depth, pick);
    } else {
        for (i = 0; i < n; ++i) pick[i] = i;
    }
    for (i = 0; i < n; ++i) {
        int at = idx[pick[i]];
        mk_real c[3], w = sgn * cd.z[at] - hh[k];
        uint32_t key = cd.key[at], features = ref_is_a ? key >> 16 | key << 16 : key;
        c[iu] = cd.u[at], c[iv] = cd.v[at], c[k] = cd.z[at];
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

/* ---- SAT: the 15 axes in closed form (sat.h) -------------------------------- */

/* The lower half-edge of each box edge ID, in polytope.h's box view. */
static const unsigned char box_half_edge[12] = {11, 15, 9, 13, 2, 4, 0, 6, 3, 7, 1, 5};

/* Box edge ID of the edge along `axis` at the corner whose other two
 * coordinates have the signs of s (minko/manifold.h numbering). */
static int box_edge(int axis, const mk_real *s)
{
    int lo = axis == 0 ? 1 : 0, hi = axis == 2 ? 1 : 2;
    return 4 * axis + (s[lo] > 0) + 2 * (s[hi] > 0);
}

/* Edge pair (e_i of A, R_j of B): axis L = e_i x R_j = (0, -R_i2j, R_i1j) in
 * the cyclic order (i, i1, i2), not counted when the edges are nearly
 * parallel. A's extent along L is |R_i2j| a_i1 + |R_i1j| a_i2; B's is
 * sum_k |(R^T L)_k| b_k, from the products rather than the cofactor identity
 * of a rotation, which the rounded R satisfies only to a few ulps (and the
 * division by a small |L| would magnify). All nine are computed in full and
 * the best kept by selects, without a branch on the data: on random poses
 * every test that skipped an axis early (a parallel pair, one that cannot
 * beat the faces) was a coin flip to the branch predictor, and its misses
 * cost more time than the nine square roots and divisions it saved (random
 * boxes in demos/bench_contacts: 350 -> 272 ns per call). */
/* The best edge pair of two boxes so far: e_i of A, R_j of B (i = -1: none). */
typedef struct box_edges { mk_real sep; int i, j; } box_edges;

MK_ALWAYS_INLINE void box_edge_axis(mk_real r[3][3], mk_real ar[3][3], const mk_real *a, const mk_real *b, const mk_real *d, int i,
                                    int j, box_edges *best)
{
    int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3, ok, better;
    mk_real l2 = r[i1][j] * r[i1][j] + r[i2][j] * r[i2][j], sep;
    ok = l2 > MK_SAT_PARALLEL * MK_SAT_PARALLEL;
    sep = mk_fabs_(r[i1][j] * d[i2] - r[i2][j] * d[i1]) - (ar[i2][j] * a[i1] + ar[i1][j] * a[i2]) -
          mk_fabs_(r[i2][j1] * r[i1][j] - r[i1][j1] * r[i2][j]) * b[j1] - mk_fabs_(r[i2][j2] * r[i1][j] - r[i1][j2] * r[i2][j]) * b[j2];
    sep /= mk_sqrt_(ok ? l2 : 1);
    better = ok & (sep > best->sep);
    best->i = better ? i : best->i;
    best->j = better ? j : best->j;
    best->sep = mk_max(best->sep, ok ? sep : -MK_REAL_MAX);
}

/* The kind, features, separation and normal of edge pair (e_i of A, R_j
 * of B) into *out: L = e_i x R_j pointing from A to B; A's supporting edge
 * sits at the corner with the signs of L, B's at the corner with those of
 * -R^T L. Reads rows (i + 1) % 3 and (i + 2) % 3 of r and the same entries
 * of d; row i and d[i] are multiplied by L_i = 0 only. */
static void edge_result(mk_real r[3][3], const mk_real *d, int i, int j, mk_real sep, mk_sat_result *out)
{
    static const unsigned char next[3] = {1, 2, 0}, prev[3] = {2, 0, 1};
    int i1 = next[i], i2 = prev[i], lo = j == 0 ? 1 : 0, hi = j == 2 ? 1 : 2;
    mk_real L[3], blo, bhi, l;
    L[i] = 0, L[i1] = -r[i2][j], L[i2] = r[i1][j];
    if (L[0] * d[0] + L[1] * d[1] + L[2] * d[2] < 0) L[0] = -L[0], L[1] = -L[1], L[2] = -L[2];
    /* The two components of -R^T L that name B's edge (box_edge(j, .)). */
    blo = -(r[0][lo] * L[0] + r[1][lo] * L[1] + r[2][lo] * L[2]);
    bhi = -(r[0][hi] * L[0] + r[1][hi] * L[1] + r[2][hi] * L[2]);
    l = mk_sqrt_(L[0] * L[0] + L[1] * L[1] + L[2] * L[2]);
    out->kind = MK_SAT_EDGES;
    out->a = box_half_edge[box_edge(i, L)];
    out->b = box_half_edge[4 * j + (blo > 0) + 2 * (bhi > 0)];
    out->separation = sep;
    out->normal = mk_v3(L[0] / l, L[1] / l, L[2] / l);
}


/* Separation along edge pair (e_i of A, R_j of B) straight from the world
 * poses: the two rows of R and entries of t that box_edge_axis reads (row
 * i and t_i only ever multiply L_i = 0: zeros), as mk_pair_of_poses_ forms
 * them; -MK_REAL_MAX when the edges are parallel. */
static mk_real edge_sep_apart(const mk_vec3 *ha, const mk_vec3 *hb, const mk_mat3 *ra, const mk_mat3 *rb, mk_vec3 dp, int i, int j)
{
    mk_real r[3][3], ar[3][3], a[3], b[3], d[3];
    int n, k;
    box_edges best;
    for (n = 1; n < 3; ++n) {
        int row = (i + n) % 3;
        mk_vec3 e = *column(ra, row);
        for (k = 0; k < 3; ++k) r[row][k] = mk_v3_dot(e, *column(rb, k));
        ar[row][j] = mk_fabs_(r[row][j]);
        d[row] = mk_v3_dot(e, dp);
    }
    a[0] = ha->x, a[1] = ha->y, a[2] = ha->z;
    b[0] = hb->x, b[1] = hb->y, b[2] = hb->z;
    best.sep = -MK_REAL_MAX;
    box_edge_axis(r, ar, a, b, d, i, j, &best);
    return best.sep;
}

/* Plain arrays: r[i][j] is row i, column j of R (column j = B's axis j in A's
 * frame), so every axis below is a few multiply-adds on scalars. Only the
 * index of the best axis of each kind is kept while testing; its normal is
 * built once at the end. The early stop looks at whole groups (A's faces,
 * B's faces, the edges): the answer is then the best of the groups tested. */
/* A's face axis i and B's face axis j (B's offset along it into db[j]),
 * spelled out for constant indices like the edges. */
MK_ALWAYS_INLINE void box_face_a(mk_real ar[3][3], const mk_real *a, const mk_real *b, const mk_real *d, int i, mk_real *best, int *at)
{
    mk_real sep = mk_fabs_(d[i]) - a[i] - (ar[i][0] * b[0] + ar[i][1] * b[1] + ar[i][2] * b[2]);
    *at = sep > *best ? i : *at;
    *best = mk_max(*best, sep);
}

MK_ALWAYS_INLINE void box_face_b(mk_real r[3][3], mk_real ar[3][3], const mk_real *a, const mk_real *b, const mk_real *d, mk_real *db, int j,
                                 mk_real *best, int *at)
{
    mk_real sep;
    db[j] = r[0][j] * d[0] + r[1][j] * d[1] + r[2][j] * d[2];
    sep = mk_fabs_(db[j]) - b[j] - (ar[0][j] * a[0] + ar[1][j] * a[1] + ar[2][j] * a[2]);
    *at = sep > *best ? j : *at;
    *best = mk_max(*best, sep);
}

MK_ALWAYS_INLINE void sat_boxes(mk_vec3 ha, mk_vec3 hb, const mk_mat3 *R, mk_vec3 t, const mk_sat_options *opt, mk_sat_result *out)
{
    mk_real r[3][3], ar[3][3], a[3], b[3], d[3], db[3], sa = -MK_REAL_MAX, sb = -MK_REAL_MAX, stop = opt->stop_above;
    box_edges e;
    int i, j, fa = 0, fb = -1, stopped;
    mk_sat_kind kind;
    r[0][0] = R->c0.x, r[1][0] = R->c0.y, r[2][0] = R->c0.z;
    r[0][1] = R->c1.x, r[1][1] = R->c1.y, r[2][1] = R->c1.z;
    r[0][2] = R->c2.x, r[1][2] = R->c2.y, r[2][2] = R->c2.z;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) ar[i][j] = mk_fabs_(r[i][j]);
    a[0] = ha.x, a[1] = ha.y, a[2] = ha.z;
    b[0] = hb.x, b[1] = hb.y, b[2] = hb.z;
    d[0] = t.x, d[1] = t.y, d[2] = t.z;
    e.sep = -MK_REAL_MAX;
    e.i = e.j = -1;
    /* A's faces: B's extent along e_i is sum_j |R_ij| b_j. */
    box_face_a(ar, a, b, d, 0, &sa, &fa);
    box_face_a(ar, a, b, d, 1, &sa, &fa);
    box_face_a(ar, a, b, d, 2, &sa, &fa);
    stopped = sa > stop;
    /* B's faces: axis R_j; the face of B facing A is -e_j when B lies along +R_j. */
    if (!stopped) {
        box_face_b(r, ar, a, b, d, db, 0, &sb, &fb);
        box_face_b(r, ar, a, b, d, db, 1, &sb, &fb);
        box_face_b(r, ar, a, b, d, db, 2, &sb, &fb);
        stopped = sb > stop;
    }
    /* Edge pairs: only the winner's normal and features are worked out. */
    if (!stopped) {
        /* Spelled out: with constant indices the axes' terms stay in registers. */
        box_edge_axis(r, ar, a, b, d, 0, 0, &e);
        box_edge_axis(r, ar, a, b, d, 0, 1, &e);
        box_edge_axis(r, ar, a, b, d, 0, 2, &e);
        box_edge_axis(r, ar, a, b, d, 1, 0, &e);
        box_edge_axis(r, ar, a, b, d, 1, 1, &e);
        box_edge_axis(r, ar, a, b, d, 1, 2, &e);
        box_edge_axis(r, ar, a, b, d, 2, 0, &e);
        box_edge_axis(r, ar, a, b, d, 2, 1, &e);
        box_edge_axis(r, ar, a, b, d, 2, 2, &e);
        stopped = e.sep > stop;
    }
    /* The normal and feature indices of the chosen axis only. */
    kind = mk_sat_choose(sa, sb, e.sep, e.i >= 0, stopped, opt, out);
    out->kind = kind;
    if (kind == MK_SAT_FACE_A) {
        mk_real si = d[fa] >= 0 ? 1 : -1;
        out->a = 2 * fa + (d[fa] >= 0);
        out->b = -1;
        out->separation = sa;
        out->normal = mk_v3(fa == 0 ? si : 0, fa == 1 ? si : 0, fa == 2 ? si : 0);
    } else if (kind == MK_SAT_FACE_B) {
        mk_real sj = db[fb] >= 0 ? 1 : -1;
        out->a = -1;
        out->b = 2 * fb + (db[fb] < 0);
        out->separation = sb;
        out->normal = mk_v3(sj * r[0][fb], sj * r[1][fb], sj * r[2][fb]);
    } else {
        edge_result(r, d, e.i, e.j, e.sep, out);
    }
}

void mk_sat_box_box(mk_vec3 ha, mk_vec3 hb, const mk_mat3 *R, mk_vec3 t, const mk_sat_options *opt, mk_sat_result *out)
{
    sat_boxes(ha, hb, R, t, opt, out);
}

/* The one contact of an edge-pair axis of two boxes: mk_mf_edge_contact's
 * answer from the edges' midpoints and unit axes, A's edge s e_i about ma
 * (|s| <= h_i), B's c + t R_j about mb (|t| <= g_j, c = mb - ma), which
 * mk_segment_params takes with unit constants. */
static mk_real box_edge_contact(const mk_pair *p, int ea, int eb, mk_real sep, mk_real rr, mk_vec3 *qa, mk_feature *fa, mk_feature *fb)
{
    int ia = mk_box_hull_edge_id(ea), ib = mk_box_hull_edge_id(eb), i = ia / 4, j = ib / 4;
    mk_vec3 a0, a1, b0, b1, ma, mb, c, rj = *column(&p->r, j), q;
    mk_real ha[3], cc[3], x[3], s, t;
    mk_box_edge_ends(p->a->u.half_extents, ia, &a0, &a1);
    mk_box_edge_ends(p->b->u.half_extents, ib, &b0, &b1);
    /* Midpoints: the ends differ only along the edge's own axis. */
    ma = mk_v3_scale(mk_v3_add(a0, a1), MK_REAL(0.5));
    mb = mk_v3_add(mk_mat3_mul_v3(p->r, mk_v3_scale(mk_v3_add(b0, b1), MK_REAL(0.5))), p->t);
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
 * than the margin changes no answer) and 0 returned. The separations are
 * mk_sat_box_box's along the same axes, to rounding. This is the boxes'
 * form of mk_sat_options.first, which mk_sat_box_box does not take: done
 * here, it needs no relative pose at all. */
static int stay_apart(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin, mk_manifold_cache *cache)
{
    mk_sat_kind kind = (mk_sat_kind)(cache->axis - MK_MF_APART_HINT);
    mk_real rr = a->radius + b->radius;
    if (kind == MK_SAT_EDGES) {
        /* The hint's half-edges name their edges' directions, all the axis
         * depends on: kept as they are while the pair stays apart. */
        int ea = cache->reference, eb = (int)cache->face - 1;
        if (ea >= 0 && ea < 24 && eb >= 0 && eb < 24) {
            mk_real sep = edge_sep_apart(&a->u.half_extents, &b->u.half_extents, &xa->r, &xb->r, mk_v3_sub(xb->p, xa->p),
                                         mk_box_hull_edge_id(ea) / 4, mk_box_hull_edge_id(eb) / 4);
            if (sep > margin + rr && sep - rr > margin) return 1;
        }
    } else if (kind == MK_SAT_FACE_A || kind == MK_SAT_FACE_B) {
        /* The axis is the face's box axis k; which of its two faces (the
         * sign) does not change the separation, so the hint is kept as is. */
        int of_a = kind == MK_SAT_FACE_A, face = of_a ? cache->reference : (int)cache->face - 1;
        if (face >= 0 && face < 6) {
            const mk_pose *own = of_a ? xa : xb, *other = of_a ? xb : xa;
            const mk_vec3 *h = of_a ? &a->u.half_extents : &b->u.half_extents, *g = of_a ? &b->u.half_extents : &a->u.half_extents;
            int k = face >> 1;
            mk_vec3 e = *column(&own->r, k);
            mk_real hk = k == 0 ? h->x : k == 1 ? h->y : h->z;
            mk_real sep = mk_fabs_(mk_v3_dot(e, mk_v3_sub(xb->p, xa->p))) - hk -
                          (mk_fabs_(mk_v3_dot(e, other->r.c0)) * g->x + mk_fabs_(mk_v3_dot(e, other->r.c1)) * g->y +
                           mk_fabs_(mk_v3_dot(e, other->r.c2)) * g->z);
            if (sep > margin + rr && sep - rr > margin) return 1;
        }
    }
    cache->axis = cache->reference = 0;
    cache->face = 0;
    return 0;
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
    sat_boxes(ha, hb, &p.r, p.t, &opt, &sat);
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

/* A pair that was apart last frame: its axis, else the whole pass (both
 * ends tail calls, so neither path keeps the other's frame). */
static MK_NOINLINE mk_status hinted(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin,
                                    mk_manifold_cache *cache, mk_manifold *out)
{
    if (stay_apart(a, xa, b, xb, margin, cache)) {
        none(out, mk_v3(0, 0, 1));
        return MK_OK;
    }
    if (balls_apart(a, xa, b, xb, margin, cache, out)) return MK_OK;
    return collide(a, xa, b, xb, margin, cache, out);
}

mk_status mk_box_box_collide(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin,
                             mk_manifold_cache *cache, mk_manifold *out)
{
    if (cache && cache->axis > MK_MF_APART_HINT) return hinted(a, xa, b, xb, margin, cache, out);
    if (balls_apart(a, xa, b, xb, margin, cache, out)) return MK_OK;
    return collide(a, xa, b, xb, margin, cache, out);
}

#endif

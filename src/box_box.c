/* box_box.c: the contact manifold of two boxes in one pass (see
 * manifold_internal.h, mk_box_box_collide).
 *
 * mk_collide's general polytope path builds B's pose in A's frame, runs
 * SAT, turns the axis into polygons (mk_feat), clips them in A's frame into
 * a list of candidates (mk_mf), reduces the list and moves it to world
 * space, each step in its own frame with its own copies. Two boxes, the
 * pair every rigid-body scene is made of, need none of that: here the
 * relative pose is built once, the 15 axes are tested in closed form
 * (mk_sat_box_box), and a face axis clips the incident face in the
 * reference face's own 2D coordinates, where the reference face is the
 * rectangle |u| <= h_u, |v| <= h_v: a side test is one subtraction, only u
 * and v (and the height along the normal) are interpolated, and a side no
 * incident corner is outside of is skipped, so an incident face wholly
 * inside costs no pass at all. The candidates are reduced to four in those
 * coordinates (mk_mf_pick4) and written straight into the mk_manifold, each
 * with two matrix-vector products. The clip is the general Sutherland-
 * Hodgman clip of clip.c specialised, not a new idea: the same side order,
 * slop rule, crossing names and candidate order, so the manifold and its
 * feature IDs are those of the general path (tests/test_clip.c compares
 * the two on random, stacked and rounded pairs). */
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
MK_ALWAYS_INLINE mk_real side_sign(int face, int q) { return q == 1 ? 1 : q == 3 ? -1 : ((q == 0) == !(face & 1)) ? 1 : -1; }

/* One Sutherland-Hodgman pass of clip.c's clip_polygon against side q of
 * reference face `face`: keeps the part of src where sign * x[ax] - h <=
 * slop. An inside end within the slop strip stands for the crossing; a
 * crossing is named by the incident edge and the reference side, or, when
 * it runs along a side already, by the reference corner between the two
 * sides (or the face). */
static int clip_side(int face, int q, mk_feature finc_face, mk_real sign, int ax, mk_real h, mk_real slop, const bb_vert *src, int n,
                     bb_vert *dst)
{
    int m = 0, i;
    mk_real da = sign * src[0].x[ax] - h;
    for (i = 0; i < n; ++i) {
        const bb_vert *a = &src[i], *b = &src[i + 1 < n ? i + 1 : 0];
        mk_real db = sign * b->x[ax] - h;
        int ina = da <= slop, inb = db <= slop;
        if (ina) dst[m++] = *a;
        if (ina != inb) {
            if ((ina ? da : db) > 0) {
                if (ina) {
                    dst[m - 1].ref_edge = (signed char)q;
                    dst[m - 1].edge = E(mk_box_face_edge_[face][q]);
                }
            } else {
                bb_vert *x = &dst[m++];
                mk_real t = da / (da - db);
                x->x[0] = a->x[0] + (b->x[0] - a->x[0]) * t;
                x->x[1] = a->x[1] + (b->x[1] - a->x[1]) * t;
                x->z = a->z + (b->z - a->z) * t;
                if (a->ref_edge < 0) {
                    x->fref = E(mk_box_face_edge_[face][q]);
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
                    x->edge = E(mk_box_face_edge_[face][q]);
                } else {
                    x->ref_edge = a->ref_edge;
                    x->edge = a->edge;
                }
            }
        }
        da = db;
    }
    return m;
}

/* The clip of mk_box_box_clip (see manifold_internal.h), with `reduce`
 * constant where it is inlined. */
MK_ALWAYS_INLINE int box_clip(const mk_pair *p, int ref_is_a, int face, mk_real slop, mk_real margin, int reduce, mk_bb_point *out)
{
    const mk_shape *ref = ref_is_a ? p->a : p->b, *inc = ref_is_a ? p->b : p->a;
    mk_real r[3][3], m[3][3], tr[3], hh[3], g[3], hf[2], lo[2], hi[2], rr = p->a->radius + p->b->radius;
    mk_real sgn = face & 1 ? 1 : -1, c0[3], s[3], t[3], gs;
    mk_real x[MK_BB_CLIP_MAX], y[MK_BB_CLIP_MAX], depth[MK_BB_CLIP_MAX];
    bb_vert buf[2][MK_BB_CLIP_MAX];
    int k = face / 2, iu = (k + 1) % 3, iv = (k + 2) % 3, ia, ju, jv, fi, i, q, cnt = 4, cur = 0, n = 0, idx[MK_BB_CLIP_MAX], pick[4];
    mk_feature finc_face;
    r[0][0] = p->r.c0.x, r[1][0] = p->r.c0.y, r[2][0] = p->r.c0.z;
    r[0][1] = p->r.c1.x, r[1][1] = p->r.c1.y, r[2][1] = p->r.c1.z;
    r[0][2] = p->r.c2.x, r[1][2] = p->r.c2.y, r[2][2] = p->r.c2.z;
    /* The incident box in the reference frame: x_ref = m x_inc + tr. */
    if (ref_is_a) {
        for (i = 0; i < 3; ++i) m[i][0] = r[i][0], m[i][1] = r[i][1], m[i][2] = r[i][2];
        tr[0] = p->t.x, tr[1] = p->t.y, tr[2] = p->t.z;
    } else {
        for (i = 0; i < 3; ++i) m[i][0] = r[0][i], m[i][1] = r[1][i], m[i][2] = r[2][i];
        for (i = 0; i < 3; ++i) tr[i] = -(r[0][i] * p->t.x + r[1][i] * p->t.y + r[2][i] * p->t.z);
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
    fi = 2 * ia + (-sgn * m[k][ia] >= 0);
    finc_face = F(fi);
    ju = (ia + 1) % 3, jv = (ia + 2) % 3;
    gs = fi & 1 ? g[ia] : -g[ia];
    /* Corners c0 -+ cu -+ cv in box_face_corner order: (-, -), (+, -),
     * (+, +), (-, +) on a + face, reversed on a - face. */
    for (i = 0; i < 3; ++i) {
        mk_real cu = m[i][ju] * g[ju], cv = m[i][jv] * g[jv];
        c0[i] = tr[i] + gs * m[i][ia];
        s[i] = cu + cv;
        t[i] = cu - cv;
    }
    {
        mk_real cx[4][3];
        for (i = 0; i < 3; ++i) {
            cx[0][i] = c0[i] - s[i];
            cx[1][i] = c0[i] + t[i];
            cx[2][i] = c0[i] + s[i];
            cx[3][i] = c0[i] - t[i];
        }
        lo[0] = lo[1] = MK_REAL_MAX;
        hi[0] = hi[1] = -MK_REAL_MAX;
        for (i = 0; i < 4; ++i) {
            bb_vert *v = &buf[0][i];
            const mk_real *c = cx[fi & 1 ? i : 3 - i];
            v->x[0] = c[iu], v->x[1] = c[iv], v->z = c[k];
            v->fref = F(face);
            v->finc = V(mk_box_face_corner_[fi][i]);
            v->ref_edge = -1;
            v->edge = E(mk_box_face_edge_[fi][i]);
            lo[0] = mk_min(lo[0], c[iu]), hi[0] = mk_max(hi[0], c[iu]);
            lo[1] = mk_min(lo[1], c[iv]), hi[1] = mk_max(hi[1], c[iv]);
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
    /* Depths from the heights over the face; candidates beyond the margin go. */
    for (i = 0; i < cnt; ++i) {
        const bb_vert *v = &buf[cur][i];
        mk_real d = rr - (sgn * v->z - hh[k]);
        if (!(d >= -margin)) continue;
        x[n] = v->x[0], y[n] = v->x[1], depth[n] = d, idx[n++] = i;
    }
    if (reduce && n > MK_MANIFOLD_MAX_POINTS) {
        n = mk_mf_pick4(n, x, y, depth, pick);
    } else {
        for (i = 0; i < n; ++i) pick[i] = i;
    }
    for (i = 0; i < n; ++i) {
        const bb_vert *v = &buf[cur][idx[pick[i]]];
        mk_real c[3];
        c[iu] = v->x[0], c[iv] = v->x[1], c[k] = v->z;
        out[i].q = mk_v3(c[0], c[1], c[2]);
        out[i].depth = depth[pick[i]];
        out[i].height = sgn * v->z - hh[k];
        out[i].features = ref_is_a ? MK_FEATURE_PAIR(v->fref, v->finc) : MK_FEATURE_PAIR(v->finc, v->fref);
    }
    return n;
}

int mk_box_box_clip(const mk_pair *p, int ref_is_a, int face, mk_real slop, mk_real margin, int reduce, mk_bb_point *out)
{
    return box_clip(p, ref_is_a, face, slop, margin, reduce, out);
}

/* ---- the whole pair ---------------------------------------------------------- */

static mk_real min3(mk_vec3 v) { return mk_min(v.x, mk_min(v.y, v.z)); }

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

/* Point i of the manifold from its point la on A's surface in A's frame
 * and its depth: the world points (point_b = point_a - depth n, the
 * contract's relation) and B's local point, by one product with each
 * rotation. */
MK_ALWAYS_INLINE void put(mk_manifold *out, int i, const mk_pose *xa, const mk_pair *p, mk_vec3 n, mk_vec3 nw, mk_vec3 la, mk_real depth,
                          uint32_t features)
{
    mk_contact_point *c = &out->points[i];
    mk_vec3 wa = mk_v3_add(mk_mat3_mul_v3(xa->r, la), xa->p);
    c->point_a = wa;
    c->point_b = mk_v3_mad(wa, -depth, nw);
    c->local_a = la;
    c->local_b = mk_mat3_tmul_v3(p->r, mk_v3_sub(mk_v3_mad(la, -depth, n), p->t));
    c->depth = depth;
    c->features = features;
    c->flags = depth < 0 ? MK_CONTACT_SPECULATIVE : 0;
}

/* Cores apart (rounded or speculative boxes): SAT's separation is only a
 * lower bound of their distance, reached when the points built along the
 * axis realise it (a face over a face, two edges crossing inside both). If
 * they fall short (two cube edges side by side: the face axes separate by
 * less than the edges are apart, and the faces' clip is empty), the exact
 * core distance comes from GJK (mk_collide's generic path) instead. */
#ifndef MK_WITHOUT_GJK
static int realised(mk_real deepest, mk_real depth, const mk_pair *p)
{
    mk_real size_a = p->a->radius + mk_v3_max_abs(p->a->u.half_extents), size_b = p->b->radius + mk_v3_max_abs(p->b->u.half_extents);
    return deepest >= depth - 256 * MK_REAL_EPSILON * (mk_v3_max_abs(p->t) + size_a + size_b);
}
#endif

/* Two boxes that were apart last frame and still are along the same axis:
 * that one axis straight from the world poses (mk_sat_box_box_hint_apart),
 * before the relative pose or anything else is built, and the hint kept for
 * the next frame (an edge axis stays named as one, even where face_axis()
 * would rename it as a face it has become parallel to: the same axis).
 * Broadphase pairs of boxes whose bounding boxes overlap mostly end here.
 * Otherwise the hint is dropped (the full search answers exactly as with
 * it) and 0 returned. */
static int stay_apart(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin, mk_manifold_cache *cache)
{
    mk_sat_result sat;
    mk_real rr = a->radius + b->radius;
    if (mk_sat_box_box_hint_apart(&a->u.half_extents, &b->u.half_extents, xa, xb, (mk_sat_kind)(cache->axis - MK_MF_APART_HINT),
                                  cache->reference, (int)cache->face - 1, margin + rr, &sat) &&
        sat.best - rr > margin) {
        cache->reference = sat.a;
        cache->face = (mk_feature)(sat.b + 1);
        return 1;
    }
    cache->axis = cache->reference = 0;
    cache->face = 0;
    return 0;
}

/* Everything after the hint (out of line: the pair that stays apart
 * needs none of this frame). */
static MK_NOINLINE int collide(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin, mk_manifold_cache *cache,
                               mk_manifold *out)
{
    mk_real ra = a->radius, rb = b->radius, deepest = -MK_REAL_MAX;
    mk_vec3 ha = a->u.half_extents, hb = b->u.half_extents, n, nw;
    mk_sat_options opt;
    mk_sat_result sat;
    mk_pair p;
    int i, count;
    {
        /* Bounding balls about the centres farther apart than the margin. */
        mk_real reach = ra + mk_v3_len(ha) + rb + mk_v3_len(hb) + margin;
        if (mk_v3_len2(mk_v3_sub(xb->p, xa->p)) > reach * reach) {
            if (cache) cache->axis = MK_SAT_NONE;
            none(out, mk_v3(0, 0, 1));
            return 1;
        }
    }
    p = mk_pair_of_poses_(a, xa, b, xb);
    opt.stop_above = margin + ra + rb;
    opt.first = MK_SAT_NONE; /* the hint was tested above */
    opt.first_a = opt.first_b = -1;
    opt.prefer = cache ? (mk_sat_kind)cache->axis : MK_SAT_NONE;
    opt.prefer_rel = MK_MF_PREFER_REL;
    opt.prefer_abs = opt.prefer == MK_SAT_NONE ? 0 : MK_MF_PREFER_ABS * mk_min(min3(ha), min3(hb));
    opt.hold_face = !cache || cache->mode == MK_MANIFOLD_STABLE_IDS;
    mk_sat_box_box(ha, hb, &p.r, p.t, &opt, &sat);
    if (sat.kind == MK_SAT_EDGES) face_axis(&p, &sat);
    if (sat.best - ra - rb > margin) {
        if (cache) {
            cache->axis = MK_MF_APART_HINT + (int)sat.kind;
            cache->reference = sat.a;
            cache->face = (mk_feature)(sat.b + 1);
        }
        none(out, xa->r.c2);
        return 1;
    }
    if (cache) cache->axis = (int)sat.kind;
    n = sat.normal;
    nw = mk_mat3_mul_v3(xa->r, n);
    if (sat.kind != MK_SAT_EDGES) {
        /* Rounded cores apart clip without slop (clip.c). */
        int ref_is_a = sat.kind == MK_SAT_FACE_A, face = ref_is_a ? sat.a : sat.b;
        mk_real slop = sat.separation > 0 && ra + rb > 0 ? 0 : cache && cache->mode == MK_MANIFOLD_BEST_FACE ? MK_MF_SLOP_EXACT : MK_MF_SLOP_IDS;
        mk_bb_point pts[MK_MANIFOLD_MAX_POINTS];
        count = box_clip(&p, ref_is_a, face, slop, margin, 1, pts);
        for (i = 0; i < count; ++i) {
            /* On A's surface: A's face pushed out by its radius, or the
             * incident point of A's core moved into A's frame. */
            mk_vec3 la = ref_is_a ? mk_v3_mad(pts[i].q, ra - pts[i].height, n) : mk_v3_mad(mk_v3_add(mk_mat3_mul_v3(p.r, pts[i].q), p.t), ra, n);
            put(out, i, xa, &p, n, nw, la, pts[i].depth, pts[i].features);
            deepest = mk_max(deepest, pts[i].depth);
        }
    } else {
        /* Edge pair: the closest points of the two edges, one point. */
        mk_vec3 a0, a1, b0, b1, qa;
        mk_real s, t, gap = sat.separation, depth;
        int ea = mk_box_hull_edge_id(sat.a), eb = mk_box_hull_edge_id(sat.b);
        mk_box_edge_ends(ha, ea, &a0, &a1);
        mk_box_edge_ends(hb, eb, &b0, &b1);
        b0 = mk_v3_add(mk_mat3_mul_v3(p.r, b0), p.t);
        b1 = mk_v3_add(mk_mat3_mul_v3(p.r, b1), p.t);
        mk_segment_segment(a0, a1, b0, b1, &s, &t);
        qa = mk_v3_lerp(a0, a1, s);
        /* Apart, the edges' closest points are a gap only if neither end clamped. */
        if (gap > 0) gap = mk_v3_dist(qa, mk_v3_lerp(b0, b1, t));
        depth = ra + rb - gap;
        count = 0;
        if (depth >= -margin) {
            put(out, 0, xa, &p, n, nw, mk_v3_mad(qa, ra, n), depth,
                MK_FEATURE_PAIR(MK_FEATURE(MK_FEATURE_EDGE, ea), MK_FEATURE(MK_FEATURE_EDGE, eb)));
            deepest = depth;
            count = 1;
        }
    }
#ifndef MK_WITHOUT_GJK
    if (sat.separation > 0 && !realised(deepest, ra + rb - sat.separation, &p)) return 0;
#else
    (void)deepest;
#endif
    out->normal = nw;
    out->count = count;
    return 1;
}

int mk_box_box_collide(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin, mk_manifold_cache *cache,
                       mk_manifold *out)
{
    if (cache && cache->axis > MK_MF_APART_HINT && stay_apart(a, xa, b, xb, margin, cache)) {
        none(out, mk_v3(0, 0, 1));
        return 1;
    }
    return collide(a, xa, b, xb, margin, cache, out);
}

#endif

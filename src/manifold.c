/* manifold.c: mk_collide: validation, pair dispatch, the closed-form pairs and
 * the move from A's frame to world space (see minko/manifold.h).
 *
 * Every pair routine works in A's local frame and produces the core closest
 * points (or, against a plane, the deepest core points directly); the
 * manifold itself comes from the shared feature clipping in clip.c, so all
 * pairs name their features the same way. Pairs are written for one order of
 * shape types; the other order swaps the shapes and mirrors the result. */
#include <string.h>

#include "manifold_internal.h"
#include "pose.h"
#include "polytope.h"
#include "sat.h"
#include "shape_internal.h"

/* A pair routine fills m (in A's frame) or refuses the pair. */
typedef mk_status (*pair_fn)(const mk_pair *p, mk_mf *m, mk_manifold_cache *cache);

/* ---- closed forms ----------------------------------------------------------- */

static mk_status sphere_sphere(const mk_pair *p, mk_mf *m, mk_manifold_cache *cache)
{
    mk_real d = mk_v3_len(p->t);
    if (d - p->a->radius - p->b->radius > m->margin) return MK_OK;
    /* Concentric spheres have no preferred direction; +z of A, as mk_distance takes. */
    mk_mf_from_closest(m, p, cache, d > 0 ? mk_v3_scale(p->t, 1 / d) : mk_v3(0, 0, 1), mk_v3_zero(), p->t, d);
    return MK_OK;
}

static mk_status capsule_sphere(const mk_pair *p, mk_mf *m, mk_manifold_cache *cache)
{
    mk_mf_from_hit(m, p, cache, mk_closest_capsule_sphere(p->a->u.capsule.half_height, mk_v3(0, 0, 1), p->a->radius, p->t, p->b->radius));
    return MK_OK;
}

static mk_status box_sphere(const mk_pair *p, mk_mf *m, mk_manifold_cache *cache)
{
    mk_mf_from_hit(m, p, cache, mk_closest_box_sphere(p->a->u.half_extents, p->a->radius, p->t, p->b->radius));
    return MK_OK;
}

/* Two parallel capsules give two points: mk_mf_from_hit clips the segments. */
static mk_status capsule_capsule(const mk_pair *p, mk_mf *m, mk_manifold_cache *cache)
{
    mk_mf_from_hit(m, p, cache, mk_closest_capsule_capsule(p->a->u.capsule.half_height, mk_v3(0, 0, 1), p->a->radius, p->t, p->r.c2,
                                                           p->b->u.capsule.half_height, p->b->radius));
    return MK_OK;
}

/* Liang-Barsky: does segment p0-p1 meet the box [-h, h]? */
static int segment_meets_box(mk_vec3 p0, mk_vec3 p1, mk_vec3 h)
{
    mk_real lo = 0, hi = 1, P0[3], D[3], H[3];
    int i;
    P0[0] = p0.x; P0[1] = p0.y; P0[2] = p0.z;
    D[0] = p1.x - p0.x; D[1] = p1.y - p0.y; D[2] = p1.z - p0.z;
    H[0] = h.x; H[1] = h.y; H[2] = h.z;
    for (i = 0; i < 3; ++i) {
        if (D[i] == 0) {
            if (mk_fabs_(P0[i]) > H[i]) return 0;
        } else {
            mk_real ta = (-H[i] - P0[i]) / D[i], tb = (H[i] - P0[i]) / D[i];
            if (ta > tb) { mk_real tmp = ta; ta = tb; tb = tmp; }
            lo = mk_max(lo, ta);
            hi = mk_min(hi, tb);
            if (lo > hi) return 0;
        }
    }
    return 1;
}

/* Closest points of a segment and a box it does not meet: an endpoint
 * against the box, or the segment against one of the 12 edges (a face can
 * only be nearest at an endpoint). */
static mk_real segment_box_closest(mk_vec3 p0, mk_vec3 p1, mk_vec3 h, mk_vec3 *ca, mk_vec3 *cb)
{
    mk_real best = MK_REAL_MAX, s, t;
    int i, k;
    for (i = 0; i < 2; ++i) {
        mk_vec3 p = i ? p1 : p0, q = mk_v3(mk_clamp(p.x, -h.x, h.x), mk_clamp(p.y, -h.y, h.y), mk_clamp(p.z, -h.z, h.z));
        mk_real d2 = mk_v3_len2(mk_v3_sub(p, q));
        if (d2 < best) { best = d2; *ca = q; *cb = p; }
    }
    for (k = 0; k < 3; ++k) {
        for (i = 0; i < 4; ++i) {
            /* Edge along axis k: the two corners that differ only in bit k. */
            int lo = k == 0 ? 1 : 0, hi = k == 2 ? 1 : 2, bits = ((i & 1) << lo) | ((i >> 1) << hi);
            mk_vec3 e0 = mk_box_corner(h, bits), e1 = mk_box_corner(h, bits | 1 << k), q, p;
            mk_real d2;
            mk_segment_segment(e0, e1, p0, p1, &s, &t);
            q = mk_v3_lerp(e0, e1, s);
            p = mk_v3_lerp(p0, p1, t);
            d2 = mk_v3_len2(mk_v3_sub(p, q));
            if (d2 < best) { best = d2; *ca = q; *cb = p; }
        }
    }
    return mk_sqrt_(best);
}

/* Separation of the segment from the box along unit axis l (signed so that
 * the result is the larger of the two sides); *nl is l or -l, from A to B. */
static mk_real axis_separation(mk_vec3 l, mk_vec3 p0, mk_vec3 p1, mk_vec3 h, mk_vec3 *nl)
{
    mk_real rho = h.x * mk_fabs_(l.x) + h.y * mk_fabs_(l.y) + h.z * mk_fabs_(l.z);
    mk_real a = mk_v3_dot(p0, l), b = mk_v3_dot(p1, l), pos = mk_min(a, b) - rho, neg = -rho - mk_max(a, b);
    *nl = pos >= neg ? l : mk_v3_neg(l);
    return mk_max(pos, neg);
}

/* The segment meets the box core: the axis of least penetration among the
 * three face normals and the three edge-cross-segment directions. Face axes
 * win ties so a capsule pressed into a face keeps a face contact. */
static void segment_box_deep(mk_vec3 p0, mk_vec3 p1, mk_vec3 h, mk_vec3 *n, mk_vec3 *ca, mk_vec3 *cb, mk_real *dist)
{
    mk_vec3 u = mk_v3_normalize(mk_v3_sub(p1, p0)), l, best_n = mk_v3(1, 0, 0);
    mk_real best = -MK_REAL_MAX, s, t, tol = mk_v3_max_abs(h) * MK_REAL_EPSILON * 64;
    int k, edge = -1;
    for (k = 0; k < 3; ++k) {
        mk_vec3 nl;
        mk_real sep = axis_separation(mk_v3(k == 0, k == 1, k == 2), p0, p1, h, &nl);
        if (sep > best) { best = sep; best_n = nl; }
    }
    for (k = 0; k < 3; ++k) {
        mk_vec3 nl;
        mk_real sep;
        l = mk_v3_cross(u, mk_v3(k == 0, k == 1, k == 2));
        if (mk_v3_len(l) <= MK_MF_SIN_TOL) continue; /* segment parallel to this edge direction */
        sep = axis_separation(mk_v3_normalize(l), p0, p1, h, &nl);
        if (sep > best + tol) { best = sep; best_n = nl; edge = k; }
    }
    *n = best_n;
    *dist = best;
    if (edge < 0) {
        *cb = mk_v3_dot(p0, best_n) <= mk_v3_dot(p1, best_n) ? p0 : p1;
        *ca = mk_v3_mad(*cb, -best, best_n);
    } else {
        /* The box edge along `edge` on the side the normal points to. */
        int bits = (best_n.x > 0) | (best_n.y > 0) << 1 | (best_n.z > 0) << 2;
        mk_vec3 e0 = mk_box_corner(h, bits & ~(1 << edge)), e1 = mk_box_corner(h, bits | 1 << edge);
        mk_segment_segment(e0, e1, p0, p1, &s, &t);
        *ca = mk_v3_lerp(e0, e1, s);
        *cb = mk_v3_lerp(p0, p1, t);
    }
}

/* Closed form: the segment against the box core, distance when apart and
 * the least-penetration axis when they meet; a capsule lying on a face then
 * gives the two clipped ends of its segment. */
static mk_status box_capsule(const mk_pair *p, mk_mf *m, mk_manifold_cache *cache)
{
    mk_vec3 h = p->a->u.half_extents, axis = mk_v3_scale(p->r.c2, p->b->u.capsule.half_height);
    mk_vec3 p0 = mk_v3_sub(p->t, axis), p1 = mk_v3_add(p->t, axis), ca, cb, n;
    mk_real d;
    if (segment_meets_box(p0, p1, h)) {
        segment_box_deep(p0, p1, h, &n, &ca, &cb, &d);
    } else {
        d = segment_box_closest(p0, p1, h, &ca, &cb);
        if (d - p->a->radius - p->b->radius > m->margin) return MK_OK;
        n = mk_v3_scale(mk_v3_sub(cb, ca), 1 / d);
    }
    mk_mf_from_closest(m, p, cache, n, ca, cb, d);
    return MK_OK;
}

/* Any shape A against the half-space B: the support feature of A's core
 * along the inward plane normal holds every deepest point. */
static mk_status shape_plane(const mk_pair *p, mk_mf *m, mk_manifold_cache *cache)
{
    const mk_shape *a = p->a;
    mk_vec3 np = mk_mat3_mul_v3(p->r, p->b->u.plane.normal);
    mk_real off = p->b->u.plane.offset + mk_v3_dot(np, p->t);
    mk_feat f;
    int i;
    (void)cache;
    m->normal = mk_v3_neg(np);
    mk_support_feature(a, m->normal, &f);
    for (i = 0; i < f.count; ++i)
        mk_mf_add(m, mk_v3_mad(f.v[i], a->radius, m->normal), a->radius - (mk_v3_dot(np, f.v[i]) - off), f.vid[i],
                  MK_FEATURE(MK_FEATURE_FACE, 0));
    return MK_OK;
}

#ifndef MK_WITHOUT_SAT
/* Face/edge hysteresis of box and hull pairs (mk_sat_options.prefer): with
 * MK_MANIFOLD_STABLE_IDS last frame's
 * kind of face axis (face of A, face of B) is kept while its separation is
 * within 5 % of the best one's plus 0.5 % of the smaller box's smallest half
 * extent, and an edge pair must beat the face by as much (half as much when
 * last frame's was an edge pair) to be taken. Measured on two 0.7 x 0.7 x 0.3 boxes 1 mm deep,
 * 1000 frames of random tilt noise: with no band the kind flips on 60 % of
 * frames even at 1e-4 rad (face A against face B: the exact minimum follows
 * the sign of the tilt), and the feature IDs with it; with this band it
 * never flips lying flat (noise 1e-4 to 1e-2 rad) and changes once or twice
 * balanced on an edge, while the warm frames' deepest depth stays within
 * 5e-7 (flat, 1e-3 rad) to 1.4 % (on edge, 1e-3 rad) of the exact one. A
 * 1 % band alone is too narrow at millimetre depths (433 flips at 1e-2 rad);
 * Box3D's rule (0.9 x face + 0.5 slop) is the same idea with a wider band. */
/* (MK_MF_PREFER_REL and MK_MF_PREFER_ABS in manifold_internal.h.) */

/* An edge pair whose cross product is a face normal (an edge of B lying
 * parallel to a face of A, as in every box resting flat on another) is that
 * face's axis, with the same separation; which of the two SAT reports is
 * round-off. Name it as the face, so a flat contact clips to a face. The
 * candidates are the faces on either side of the two edges (ha, hb: the
 * polytopes as SAT saw them). */
static void face_axis(const mk_hull *ha, const mk_hull *hb, const mk_pair *p, mk_sat_result *sat)
{
    mk_real one = 1 - 64 * MK_REAL_EPSILON;
    int fa[2], fb[2], k;
    fa[0] = ha->edges[sat->a].face;
    fa[1] = ha->edges[ha->edges[sat->a].twin].face;
    fb[0] = hb->edges[sat->b].face;
    fb[1] = hb->edges[hb->edges[sat->b].twin].face;
    for (k = 0; k < 2; ++k) {
        if (mk_v3_dot(sat->normal, ha->planes[fa[k]].normal) >= one) {
            sat->kind = MK_SAT_FACE_A;
            sat->a = fa[k];
            sat->b = -1;
            return;
        }
        if (-mk_v3_dot(sat->normal, mk_mat3_mul_v3(p->r, hb->planes[fb[k]].normal)) >= one) {
            sat->kind = MK_SAT_FACE_B;
            sat->a = -1;
            sat->b = fb[k];
            return;
        }
    }
}


/* The reference face `face` of polytope s (box or hull), in its own frame. */
static void polytope_face(const mk_shape *s, int face, mk_feat *f)
{
    if (s->type == MK_SHAPE_BOX) mk_box_face(s, face / 2, face & 1, f);
    else mk_hull_face(s->u.hull, face, -1, f);
}

/* Cores apart (rounded or speculative polytopes): SAT's separation is only a
 * lower bound of their distance, reached when the points built along the
 * axis realise it (a face over a face, two edges crossing inside both). If
 * they fall short of it (two cube edges side by side: the face axes
 * separate by less than the edges are apart, and the faces' clip is empty),
 * the exact core distance comes from GJK instead. */
#ifndef MK_WITHOUT_GJK
static int realised(const mk_mf *m, mk_real depth, const mk_pair *p)
{
    mk_real tol = mk_mf_realise_tol(p);
    int i;
    for (i = 0; i < m->count; ++i)
        if (m->p[i].depth >= depth - tol) return 1;
    return 0;
}

static mk_status generic(const mk_pair *p, mk_mf *m, mk_manifold_cache *cache);

static mk_status apart(const mk_pair *p, mk_mf *m, mk_manifold_cache *cache)
{
    m->count = 0;
    return generic(p, m, cache);
}
#endif

/* Whether two polytopes (boxes, hulls) are farther apart than the margin by
 * their bounding balls about their origins: then nothing else is needed,
 * not even their rotations. Broadphase pairs of boxes that only overlap in
 * their bounding boxes mostly end here. */
static mk_real polytope_reach(const mk_shape *s)
{
    return s->radius + (s->type == MK_SHAPE_BOX ? mk_v3_len(s->u.half_extents) : mk_v3_len(s->u.hull->centroid) + s->u.hull->outer_radius);
}

static int polytopes_apart(const mk_shape *a, mk_vec3 pa, const mk_shape *b, mk_vec3 pb, mk_real margin)
{
    mk_real reach = polytope_reach(a) + polytope_reach(b) + margin;
    return mk_v3_len2(mk_v3_sub(pb, pa)) > reach * reach;
}

/* A hull and a hull or a box (two boxes: box_box.c): SAT (src/sat.h), then a face axis clips the incident face against the
 * reference face and an edge axis gives the closest points of the two
 * edges. Cold (no cache) the exact best axis is used; warm, faces are
 * preferred to edge pairs within the hysteresis band, and with
 * MK_MANIFOLD_STABLE_IDS last frame's face kind too. */
static mk_status polytopes(const mk_pair *p, mk_mf *m, mk_manifold_cache *cache)
{
    const mk_shape *a = p->a, *b = p->b;
    mk_real ra = a->radius, rb = b->radius;
    mk_sat_options opt;
    mk_sat_result sat;
    mk_feat ref, inc;
    opt = mk_sat_defaults();
    opt.stop_above = m->margin + ra + rb;
    if (cache && cache->axis > MK_MF_APART_HINT) {
        /* Apart last frame: that axis first, and nothing else is carried. */
        opt.first = (mk_sat_kind)(cache->axis - MK_MF_APART_HINT);
        opt.first_a = cache->reference;
        opt.first_b = (int)cache->face - 1;
        cache->axis = cache->reference = 0;
        cache->face = 0;
    }
    opt.prefer = cache ? (mk_sat_kind)cache->axis : MK_SAT_NONE;
    opt.prefer_rel = MK_MF_PREFER_REL;
    opt.hold_face = !cache || cache->mode == MK_MANIFOLD_STABLE_IDS;
    mk_box_hull va, vb;
    const mk_hull *ha = a->u.hull, *hb = b->u.hull;
    opt.prefer_abs = opt.prefer == MK_SAT_NONE ? 0
                                               : MK_MF_PREFER_ABS * mk_min(a->type == MK_SHAPE_BOX ? mk_v3_min_comp(a->u.half_extents) : ha->inner_radius,
                                                                            b->type == MK_SHAPE_BOX ? mk_v3_min_comp(b->u.half_extents) : hb->inner_radius);
    /* A box meets a hull as its mk_box_hull view: O(1), no allocation,
     * the same indices as the 15-axis form. */
    if (a->type == MK_SHAPE_BOX) {
        mk_box_hull_init(&va, a->u.half_extents);
        ha = &va.hull;
    }
    if (b->type == MK_SHAPE_BOX) {
        mk_box_hull_init(&vb, b->u.half_extents);
        hb = &vb.hull;
    }
    mk_sat(ha, hb, &p->r, p->t, &opt, &sat);
    if (sat.kind == MK_SAT_EDGES) face_axis(ha, hb, p, &sat);
    if (sat.best - ra - rb > m->margin) {
        if (cache) {
            cache->axis = MK_MF_APART_HINT + (int)sat.kind;
            cache->reference = sat.a;
            cache->face = (mk_feature)(sat.b + 1);
        }
        return MK_OK;
    }
    if (cache) cache->axis = (int)sat.kind;
    m->normal = sat.normal;
    m->cores_apart = sat.separation > 0;
    if (sat.kind == MK_SAT_FACE_A) {
        polytope_face(a, sat.a, &ref);
        mk_support_feature(b, mk_mat3_tmul_v3(p->r, mk_v3_neg(sat.normal)), &inc);
        mk_feat_transform(&inc, p);
        mk_mf_clip(m, &ref, 1, &inc, ra, rb);
    } else if (sat.kind == MK_SAT_FACE_B) {
        polytope_face(b, sat.b, &ref);
        mk_feat_transform(&ref, p);
        mk_support_feature(a, sat.normal, &inc);
        mk_mf_clip(m, &ref, 0, &inc, ra, rb);
    } else {
        mk_vec3 qa;
        mk_feature fa, fb;
        mk_real depth = mk_mf_edge_contact(p, sat.a, sat.b, sat.separation, ra + rb, &qa, &fa, &fb);
        mk_mf_add(m, mk_v3_mad(qa, ra, sat.normal), depth, fa, fb);
    }
#ifndef MK_WITHOUT_GJK
    if (sat.separation > 0 && !realised(m, ra + rb - sat.separation, p)) return apart(p, m, cache);
#endif
    return MK_OK;
}

#endif

/* Everything else: GJK/EPA with the narrowphase's polish gives the exact
 * normal and closest points, and the support features along it are clipped
 * (box-box face contacts, a cylinder standing on a box, ...). */
static mk_status generic(const mk_pair *p, mk_mf *m, mk_manifold_cache *cache)
{
    mk_hit h;
    mk_status st = mk_pair_distance(p, cache ? &cache->gjk : NULL, &h);
    if (st == MK_OK) mk_mf_from_hit(m, p, cache, h);
    return st;
}

/* ---- dispatch ------------------------------------------------------------- */

/* Box and hull pairs go through SAT, or GJK/EPA in a build without SAT. */
#ifdef MK_WITHOUT_SAT
#  define POLYTOPES generic
#else
#  define POLYTOPES polytopes
#endif

/* The routine for (ta, tb), or NULL when only (tb, ta) has one. */
static pair_fn pair_table(mk_shape_type ta, mk_shape_type tb)
{
    if (tb == MK_SHAPE_PLANE) return ta == MK_SHAPE_PLANE ? NULL : shape_plane;
    if (ta == MK_SHAPE_PLANE) return NULL;
    switch (ta) {
    case MK_SHAPE_SPHERE: return tb == MK_SHAPE_SPHERE ? sphere_sphere : tb >= MK_SHAPE_CYLINDER ? generic : NULL;
    case MK_SHAPE_BOX:
        return tb == MK_SHAPE_SPHERE ? box_sphere : tb == MK_SHAPE_CAPSULE ? box_capsule : tb == MK_SHAPE_BOX || tb == MK_SHAPE_HULL ? POLYTOPES : generic;
    case MK_SHAPE_CAPSULE:
        return tb == MK_SHAPE_SPHERE ? capsule_sphere : tb == MK_SHAPE_CAPSULE ? capsule_capsule : tb >= MK_SHAPE_CYLINDER ? generic : NULL;
    case MK_SHAPE_HULL: return tb == MK_SHAPE_HULL ? POLYTOPES : NULL;
    default: return tb >= ta ? generic : NULL; /* cylinder and cone: the lower type goes first */
    }
}

/* Where collide_checked writes: mk_collide_pose's manifold (reduce = 1,
 * capacity MK_MANIFOLD_MAX_POINTS) or mk_collide_pose_points' buffer
 * (reduce = 0: every candidate, up to `capacity`). */
typedef struct collide_out {
    mk_vec3 *normal;
    mk_contact_point *points;
    int *count;
    int capacity;
    int reduce;
} collide_out;

/* The public MK_COLLIDE_MAX_CANDIDATES is the builder's capacity (C99 has
 * no static assert: a negative array size stops the build). */
typedef char mk_candidates_capacity_check_[MK_COLLIDE_MAX_CANDIDATES == MK_MF_MAX ? 1 : -1];

/* Moves the manifold from A's frame to world space; `swap` mirrors it when
 * the pair routine ran with the shapes exchanged. */
static void finish(const mk_mf *m, const mk_mat3 *ra, mk_vec3 pa, const mk_pair *pair, int swap, const collide_out *out)
{
    mk_mat3 R = *ra;
    mk_vec3 n = mk_mat3_mul_v3(R, m->normal);
    int i;
    *out->normal = swap ? mk_v3_neg(n) : n;
    *out->count = m->count;
    for (i = 0; i < m->count; ++i) {
        const mk_mf_point *p = &m->p[i];
        mk_contact_point *c = &out->points[i];
        mk_vec3 pb = mk_v3_mad(p->pa, -p->depth, m->normal);
        mk_vec3 wa = mk_v3_add(mk_mat3_mul_v3(R, p->pa), pa), wb = mk_v3_mad(wa, -p->depth, n); /* the contract's relation */
        mk_vec3 lb = mk_mat3_tmul_v3(pair->r, mk_v3_sub(pb, pair->t));
        c->depth = p->depth;
        c->flags = p->depth < 0 ? MK_CONTACT_SPECULATIVE : 0;
        if (swap) {
            c->point_a = wb;
            c->point_b = wa;
            c->local_a = lb;
            c->local_b = p->pa;
            c->features = MK_FEATURE_PAIR(MK_FEATURE_PAIR_B(p->features), MK_FEATURE_PAIR_A(p->features));
        } else {
            c->point_a = wa;
            c->point_b = wb;
            c->local_a = p->pa;
            c->local_b = lb;
            c->features = p->features;
        }
    }
}

/* MK_MANIFOLD_TOUCHING_ONLY: the points of depth >= 0, in their order. */
static void drop_speculative(mk_mf *m)
{
    int i, n = 0;
    for (i = 0; i < m->count; ++i)
        if (m->p[i].depth >= 0) m->p[n++] = m->p[i];
    m->count = n;
}

/* mk_collide_pose after its checks: the pair routine (the table's, or
 * `fn` when given), the reduction (unless out->reduce is 0) and the move to
 * world space. Out of line, so the checks and the two boxes' path run
 * without this frame (a whole mk_mf). */
static MK_NOINLINE mk_status collide_checked(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin,
                                             mk_manifold_cache *cache, const collide_out *out, pair_fn fn)
{
    mk_status st;
    int swap = 0;
    if (!fn) fn = pair_table(a->type, b->type);
    mk_pair p;
    mk_mf m;
    if (!fn) {
        const mk_shape *s = a;
        const mk_pose *x = xa;
        fn = pair_table(b->type, a->type);
        if (!fn) return MK_ERR_UNSUPPORTED;
        swap = 1;
        a = b;
        b = s;
        xa = xb;
        xb = x;
    }
#ifndef MK_WITHOUT_SAT
    if (fn == polytopes && polytopes_apart(a, xa->p, b, xb->p, margin)) {
        if (cache) cache->axis = MK_SAT_NONE;
        *out->count = 0;
        *out->normal = mk_v3(0, 0, 1);
        return MK_OK;
    }
#endif
    p = mk_pair_of_poses_(a, xa, b, xb);
    m.count = 0;
    m.margin = margin;
    m.cores_apart = 0;
    m.slop = cache && cache->mode == MK_MANIFOLD_BEST_FACE ? MK_MF_SLOP_EXACT : MK_MF_SLOP_IDS;
    m.normal = mk_v3(0, 0, 1);
    if ((st = fn(&p, &m, cache)) != MK_OK) return st;
    if (out->reduce) mk_mf_reduce(&m);
    if (cache && (cache->flags & MK_MANIFOLD_TOUCHING_ONLY)) drop_speculative(&m);
    if (m.count > out->capacity) {
        *out->count = m.count; /* how many the caller needs room for */
        return MK_ERR_CAPACITY;
    }
    finish(&m, &xa->r, xa->p, &p, swap, out);
    return MK_OK;
}

/* The checks shared by mk_collide_pose and mk_collide_pose_points. */
static MK_INLINE mk_status collide_args(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin,
                                        const mk_manifold_cache *cache)
{
    mk_status st;
    if (!mk_shape_ok_typed_(a, a->type) || !mk_shape_ok_typed_(b, b->type)) {
        if ((st = mk_shape_validate(a)) != MK_OK) return st;
        return mk_shape_validate(b);
    }
    if (!mk_pose_ok_(xa) || !mk_pose_ok_(xb)) return MK_ERR_UNCHECKED_POSE;
    if (!mk_real_is_valid(margin)) return MK_ERR_NOT_FINITE;
    if (margin < 0) return MK_ERR_BAD_ARGUMENT;
    if (cache && cache->mode != MK_MANIFOLD_STABLE_IDS && cache->mode != MK_MANIFOLD_BEST_FACE) return MK_ERR_BAD_ARGUMENT;
    if (cache && (cache->flags & ~MK_MANIFOLD_TOUCHING_ONLY)) return MK_ERR_BAD_ARGUMENT;
    return MK_OK;
}

/* The bits of a real as an unsigned integer. Non-negative reals order as
 * their bits; every real with the sign bit set (-0, negatives, NaNs with
 * the sign) and every NaN, infinity or real beyond a finite bound has
 * bits above that bound's. */
#if defined(MK_SINGLE)
typedef uint32_t real_bits;
#else
typedef uint64_t real_bits;
#endif
MK_ALWAYS_INLINE real_bits bits_of(mk_real v)
{
    real_bits b;
    memcpy(&b, &v, sizeof b);
    return b;
}
MK_ALWAYS_INLINE real_bits bits_max(real_bits a, real_bits b) { return a > b ? a : b; }

/* collide_args for two boxes, type known, as one test: 1 exactly when
 * collide_args would return MK_OK (tests/test_box_box.c checks both
 * ways; a refusal falls back to collide_args, so a wrong one would only
 * cost time). It runs on every box pair, so it is integer arithmetic with
 * one branch at the end: sixteen float compares, each its own branch,
 * cost a pair that stays apart 8 % of its time (bench_contacts apart,
 * 18.7 -> 17.3 ns under load 6; 39 -> 21 branches per call). A size v is
 * in (0, MK_MAX_SIZE] exactly when bits(v) - 1 < bits(MK_MAX_SIZE)
 * unsigned (0 wraps around to the top); a rounding radius or the margin
 * is in [0, bound] exactly when bits(v + 0) <= bits(bound) (adding 0 turns
 * -0, which passes v >= 0, into +0). */
MK_ALWAYS_INLINE int boxes_ok(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin,
                              const mk_manifold_cache *cache)
{
    real_bits size = bits_max(bits_max(bits_max(bits_of(a->u.half_extents.x) - 1, bits_of(a->u.half_extents.y) - 1),
                                       bits_max(bits_of(a->u.half_extents.z) - 1, bits_of(b->u.half_extents.x) - 1)),
                              bits_max(bits_of(b->u.half_extents.y) - 1, bits_of(b->u.half_extents.z) - 1));
    real_bits round = bits_max(bits_of(a->radius + 0), bits_of(b->radius + 0));
    return (size < bits_of(MK_MAX_SIZE)) & (round <= bits_of(MK_MAX_SIZE)) & (bits_of(margin + 0) <= bits_of(MK_REAL_MAX)) &
           mk_pose_ok_(xa) & mk_pose_ok_(xb) &
           (!cache || ((unsigned)cache->mode <= (unsigned)MK_MANIFOLD_BEST_FACE && !(cache->flags & ~MK_MANIFOLD_TOUCHING_ONLY)));
}

/* The general path (the table's pair routine, or fn) into a reduced manifold. */
static mk_status collide_manifold(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin,
                                  mk_manifold_cache *cache, mk_manifold *out, pair_fn fn)
{
    collide_out o;
    o.normal = &out->normal;
    o.points = out->points;
    o.count = &out->count;
    o.capacity = MK_MANIFOLD_MAX_POINTS;
    o.reduce = 1;
    return collide_checked(a, xa, b, xb, margin, cache, &o, fn);
}

mk_status mk_collide_gjk_(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin,
                          mk_manifold_cache *cache, mk_manifold *out)
{
    return collide_manifold(a, xa, b, xb, margin, cache, out, generic);
}

/* mk_collide_pose's checks and general path (out of line, so the two
 * boxes' path keeps no frame). */
static MK_NOINLINE mk_status collide_pose_general(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin,
                                                  mk_manifold_cache *cache, mk_manifold *out)
{
    mk_status st;
    if ((st = collide_args(a, xa, b, xb, margin, cache)) != MK_OK) return st;
    return collide_manifold(a, xa, b, xb, margin, cache, out, NULL);
}

mk_status mk_collide_pose(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin,
                          mk_manifold_cache *cache, mk_manifold *out)
{
    if (!a || !xa || !b || !xb || !out) return MK_ERR_NULL;
#ifndef MK_WITHOUT_SAT
    /* Two boxes in one pass (box_box.c), reached by a tail call. */
    if (a->type == MK_SHAPE_BOX && b->type == MK_SHAPE_BOX && boxes_ok(a, xa, b, xb, margin, cache))
        return mk_box_box_collide(a, xa, b, xb, margin, cache, out);
#endif
    return collide_pose_general(a, xa, b, xb, margin, cache, out);
}

/* Box pairs come reduced from box_box.c: their manifold is copied. */
mk_status mk_collide_pose_points(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_real margin,
                                 mk_manifold_cache *cache, mk_vec3 *normal, mk_contact_point *points, int capacity, int *count)
{
    mk_status st;
    collide_out o;
    int i;
    if (!a || !xa || !b || !xb || !normal || !points || !count) return MK_ERR_NULL;
    if (capacity < 0) return MK_ERR_BAD_ARGUMENT;
    if (a->type == MK_SHAPE_BOX && b->type == MK_SHAPE_BOX) {
        mk_manifold m;
        if ((st = mk_collide_pose(a, xa, b, xb, margin, cache, &m)) != MK_OK) return st;
        *count = m.count;
        if (m.count > capacity) return MK_ERR_CAPACITY;
        *normal = m.normal;
        for (i = 0; i < m.count; ++i) points[i] = m.points[i];
        return MK_OK;
    }
    if ((st = collide_args(a, xa, b, xb, margin, cache)) != MK_OK) return st;
    o.normal = normal;
    o.points = points;
    o.count = count;
    o.capacity = capacity;
    o.reduce = 0;
    return collide_checked(a, xa, b, xb, margin, cache, &o, NULL);
}

/* Checks and converts the transforms (after the shapes, in argument order),
 * then the pose query. */
mk_status mk_collide(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb, mk_real margin,
                     mk_manifold_cache *cache, mk_manifold *out)
{
    mk_status st;
    mk_pose pa, pb;
    if (!a || !b || !out) return MK_ERR_NULL;
    if (!mk_transform_ok_(&xa) || !mk_transform_ok_(&xb)) {
        if ((st = mk_shape_validate(a)) != MK_OK || (st = mk_shape_validate(b)) != MK_OK) return st;
        if ((st = mk_transform_check_(xa)) != MK_OK) return st;
        return mk_transform_check_(xb);
    }
    mk_pose_set_(&pa, &xa);
    mk_pose_set_(&pb, &xb);
    return mk_collide_pose(a, &pa, b, &pb, margin, cache, out);
}

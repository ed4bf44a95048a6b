/* distance.c: public pair queries: validation, the dispatch table, GJK + EPA composition. */
#include "closest.h"
#include "pose.h"
#ifndef MK_WITHOUT_EPA
#  include "epa.h"
#endif
#ifndef MK_WITHOUT_SAT
#  include "sat_box.h"
#endif

const char *mk_method_name(mk_method m)
{
    static const char *const names[] = {"none", "closed_form", "gjk", "epa", "sat"};
    return (unsigned)m <= MK_METHOD_SAT ? names[m] : "unknown";
}

/* ---- validation ----------------------------------------------------------- */

/* The slow half of validation: names the first error in argument order
 * (shapes, then poses). Called only on input the quick test below refused;
 * the two accept exactly the same input (tests/test_distance.c,
 * quick_test_matches_diagnosis), so it never returns MK_OK to a method that
 * would then skip its answer. */
static MK_NOINLINE mk_status diagnose_shapes(const mk_shape *a, const mk_shape *b)
{
    mk_status st = mk_shape_validate(a);
    return st != MK_OK ? st : mk_shape_validate(b);
}

static MK_NOINLINE mk_status diagnose(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb)
{
    mk_status st;
    if ((st = diagnose_shapes(a, b)) != MK_OK) return st;
    return mk_pose_ok_(xa) && mk_pose_ok_(xb) ? MK_OK : MK_ERR_UNCHECKED_POSE;
}

/* The quick test of two shapes of types ta, tb: no call and, when ta and tb
 * are constants, no switch. */
MK_ALWAYS_INLINE int shapes_ok(const mk_shape *a, mk_shape_type ta, const mk_shape *b, mk_shape_type tb)
{
    return mk_shape_ok_typed_(a, ta) && mk_shape_ok_typed_(b, tb);
}

/* The quick test every pose query pays. The poses were checked when they
 * were made; here only their tags are read. */
MK_ALWAYS_INLINE int accept(const mk_shape *a, mk_shape_type ta, const mk_pose *xa, const mk_shape *b, mk_shape_type tb,
                            const mk_pose *xb)
{
    return shapes_ok(a, ta, b, tb) && mk_pose_ok_(xa) && mk_pose_ok_(xb);
}

/* Validation of two non-NULL shapes of any type and their poses. */
static mk_status check(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb)
{
    return (unsigned)a->type < MK_SHAPE_TYPE_COUNT && (unsigned)b->type < MK_SHAPE_TYPE_COUNT &&
                   accept(a, a->type, xa, b, b->type, xb)
               ? MK_OK
               : diagnose(a, xa, b, xb);
}

/* The mk_transform entry points accept what mk_transform_ok_ accepts; on
 * anything else this names the error (shapes first, then the transforms in
 * argument order, as the contract does). */
static MK_NOINLINE mk_status diagnose_transforms(const mk_shape *a, const mk_transform *xa, const mk_shape *b,
                                                 const mk_transform *xb)
{
    mk_status st;
    if ((st = diagnose_shapes(a, b)) != MK_OK || (st = mk_transform_check_(*xa)) != MK_OK) return st;
    return mk_transform_check_(*xb);
}

/* ---- the iterative path ----------------------------------------------------- */

typedef struct answer {
    mk_hit hit;         /* in the frame of the first shape as run */
    int iterations;
    mk_method method;
    mk_solve_state state;
} answer;

#if !defined(MK_WITHOUT_GJK) || !defined(MK_WITHOUT_SAT)
/* A core answer grown by the rounding radii. */
static mk_hit grow_core(mk_vec3 a, mk_vec3 b, mk_real dc, mk_vec3 n, const mk_pair *p)
{
    return mk_hit_grow(a, b, dc, n, p->a->radius, p->b->radius);
}

/* Witness points for a final distance d along n, centred on the solver's
 * points pa, pb, so that b - a = d n holds to rounding. */
static void witnesses(mk_vec3 pa, mk_vec3 pb, mk_real d, mk_vec3 n, mk_vec3 *a, mk_vec3 *b)
{
    mk_vec3 m = mk_v3_scale(mk_v3_add(pa, pb), MK_REAL(0.5));
    *a = mk_v3_mad(m, -MK_REAL(0.5) * d, n);
    *b = mk_v3_mad(m, MK_REAL(0.5) * d, n);
}

#endif

#ifndef MK_WITHOUT_GJK
static void weighted(const mk_cso_vertex *v, const mk_real *l, int n, mk_vec3 *a, mk_vec3 *b)
{
    int k;
    *a = *b = mk_v3_zero();
    for (k = 0; k < n; ++k) {
        *a = mk_v3_mad(*a, l[k], v[k].a);
        *b = mk_v3_mad(*b, l[k], v[k].b);
    }
}

/* The reported distance is always sep(n) along the solver's final normal,
 * evaluated with the support functions: an exact lower bound, equal to the
 * distance at the optimum. For polytopes the final normal is the cross
 * product of CSO vertex differences, which are the original feature edges
 * (w1 - w0 = a1 - a0 when both share b), so distance and normal come out
 * exact to rounding of the relative pose rather than to a solver tolerance. */
static mk_status iterative(const mk_pair *p, mk_gjk_cache *cache, answer *ans)
{
    mk_gjk_result g;
    mk_vec3 n, pa, pb;
    mk_real sep;
    mk_gjk(p, cache, 0, 0, &g);
    ans->iterations = g.iterations;
    ans->state = g.state;
    if (!g.overlap) {
        n = g.normal;
        sep = g.lower;
        if (!(sep > -(mk_real)HUGE_VAL)) { /* no lower bound at all (degenerate start): use |v| */
            sep = g.upper;
            n = mk_v3_len2(g.v) > 0 ? mk_v3_normalize(mk_v3_neg(g.v)) : mk_v3(1, 0, 0);
        }
        weighted(g.s.v, g.s.l, g.s.n, &pa, &pb);
        ans->method = MK_METHOD_GJK;
    } else {
#ifdef MK_WITHOUT_EPA
        return MK_ERR_UNSUPPORTED;
#else
        mk_epa_result e;
        mk_epa(p, &g.s, g.scale, &e);
        n = e.normal;
        sep = e.separation;
        weighted(e.face, e.l, 3, &pa, &pb);
        ans->iterations += e.iterations;
        if (e.state != MK_SOLVE_CONVERGED) ans->state = e.state;
        ans->method = MK_METHOD_EPA;
#endif
    }
    witnesses(pa, pb, sep, n, &pa, &pb);
    ans->hit = grow_core(pa, pb, sep, n, p);
    if (cache) mk_gjk_cache_store(&g.s, n, cache);
    return MK_OK;
}
#endif

mk_status mk_pair_distance(const mk_pair *p, mk_gjk_cache *cache, mk_hit *out)
{
#ifdef MK_WITHOUT_GJK
    (void)p;
    (void)cache;
    (void)out;
    return MK_ERR_UNSUPPORTED;
#else
    answer ans;
    mk_status st = iterative(p, cache, &ans);
    if (st == MK_OK) *out = ans.hit;
    return st;
#endif
}

#ifndef MK_WITHOUT_SAT
/* The midpoint of the box edge along `axis` that supports dir: the
 * corner with the signs of dir, 0 along the edge. */
MK_ALWAYS_INLINE mk_vec3 box_edge_centre(mk_vec3 h, mk_vec3 dir, int axis)
{
    return mk_v3(axis == 0 ? 0 : dir.x >= 0 ? h.x : -h.x, axis == 1 ? 0 : dir.y >= 0 ? h.y : -h.y, axis == 2 ? 0 : dir.z >= 0 ? h.z : -h.z);
}

/* The unit normal of edge pair (e_i of A, R_j of B), from A towards B, as
 * the SAT's result gives it (sat_box.h, edge_result): L = e_i x R_j turned
 * along t, divided by its length. */
MK_ALWAYS_INLINE mk_vec3 edge_normal(const mk_pair *p, int i, int j)
{
    mk_vec3 v = j == 0 ? p->r.c0 : j == 1 ? p->r.c1 : p->r.c2, L;
    mk_real l;
    L = i == 0 ? mk_v3(0, -v.z, v.y) : i == 1 ? mk_v3(v.z, 0, -v.x) : mk_v3(-v.y, v.x, 0);
    if (mk_v3_dot(L, p->t) < 0) L = mk_v3_neg(L);
    l = mk_sqrt_(mk_v3_len2(L));
    return mk_v3(L.x / l, L.y / l, L.z / l);
}

/* Witnesses of SAT's edge axis n (separation d): the closest points of the
 * two edges it names, A's s e_i about its midpoint ca and B's cb + t R_j
 * (unit directions: mk_segment_params with the constants a = e = 1 and
 * |e_i x R_j|^2 as the two other components of R_j squared, no
 * cancellation near parallel; B's midpoint rotated before its offset is
 * added, so an edge tiny next to the distance keeps its direction).
 * Returns 1 when they are d apart along n (to tol): then they are the
 * witnesses, exact. */
MK_ALWAYS_INLINE int edge_witnesses(const mk_pair *p, int i, int j, mk_real d, mk_vec3 n, mk_real tol, mk_vec3 *pa, mk_vec3 *pb)
{
    mk_vec3 v = j == 0 ? p->r.c0 : j == 1 ? p->r.c1 : p->r.c2, ha = p->a->u.half_extents, hb = p->b->u.half_extents;
    mk_vec3 ca = box_edge_centre(ha, n, i), cb = mk_v3_add(mk_mat3_mul_v3(p->r, box_edge_centre(hb, mk_mat3_tmul_v3(p->r, mk_v3_neg(n)), j)), p->t);
    mk_vec3 c = mk_v3_sub(cb, ca);
    mk_real vi = i == 0 ? v.x : i == 1 ? v.y : v.z, ci = i == 0 ? c.x : i == 1 ? c.y : c.z, u, w;
    mk_real w2 = i == 0 ? v.y * v.y + v.z * v.z : i == 1 ? v.z * v.z + v.x * v.x : v.x * v.x + v.y * v.y;
    mk_segment_params(1, 1, vi, ci, mk_v3_dot(c, v), w2, i == 0 ? ha.x : i == 1 ? ha.y : ha.z, j == 0 ? hb.x : j == 1 ? hb.y : hb.z, &u, &w);
    *pa = ca;
    if (i == 0) pa->x = u;
    else if (i == 1) pa->y = u;
    else pa->z = u;
    *pb = mk_v3_mad(cb, w, v);
    return mk_v3_max_abs(mk_v3_sub(mk_v3_sub(*pb, *pa), mk_v3_scale(n, d))) <= tol;
}

static int in_box(mk_vec3 h, mk_vec3 x, mk_real tol)
{
    return mk_fabs_(x.x) <= h.x + tol && mk_fabs_(x.y) <= h.y + tol && mk_fabs_(x.z) <= h.z + tol;
}

/* Witnesses of a SAT axis n with separation d for one box (half extents hf,
 * its own frame) and the other box's supporting corner q (same frame): q
 * moved back by d along n lands on this box's supporting plane; clamped into
 * the box and still on that plane, it is a surface point. If it had to move
 * sideways (parallel faces offset, or n an edge axis), the point d along n
 * from it must be on the other box (half extents ho, x = r_o x_o + t_o).
 * Returns 1 with two surface points b - a = d n exactly (to tol). Valid for
 * any axis: the plane and box tests are what make the points witnesses. */
MK_ALWAYS_INLINE int face_witness(mk_vec3 hf, mk_vec3 ho, const mk_mat3 *r_o, mk_vec3 t_o, mk_vec3 q, mk_real d, mk_vec3 n, mk_real tol,
                                 mk_vec3 *on_face, mk_vec3 *on_other)
{
    mk_vec3 x0 = mk_v3_mad(q, -d, n), x = mk_box_clamp(hf, x0), y = mk_v3_mad(x, d, n);
    *on_face = x;
    *on_other = q;
    if (!(mk_fabs_(mk_v3_dot(n, mk_v3_sub(x, x0))) <= tol)) return 0; /* clamping left the plane */
    if (mk_v3_max_abs(mk_v3_sub(q, y)) <= tol) return 1;
    *on_other = y;
    return in_box(ho, mk_mat3_tmul_v3(*r_o, mk_v3_sub(y, t_o)), tol);
}

/* Face witnesses with A as the box B's supporting corner projects on. */
MK_ALWAYS_INLINE int face_witness_on_a(const mk_pair *p, mk_real d, mk_vec3 n, mk_real tol, mk_vec3 *pa, mk_vec3 *pb)
{
    int f = -1;
    *pb = mk_v3_add(mk_mat3_mul_v3(p->r, mk_core_support_typed(p->b, MK_SHAPE_BOX, mk_mat3_tmul_v3(p->r, mk_v3_neg(n)), &f)), p->t);
    return face_witness(p->a->u.half_extents, p->b->u.half_extents, &p->r, p->t, *pb, d, n, tol, pa, pb);
}

/* The same with B as the face box, worked in B's frame with A's corner. */
MK_ALWAYS_INLINE int face_witness_on_b(const mk_pair *p, mk_real d, mk_vec3 n, mk_real tol, mk_vec3 *pa, mk_vec3 *pb)
{
    mk_mat3 rt = mk_mat3_transpose(p->r);
    mk_vec3 tb = mk_v3_neg(mk_mat3_tmul_v3(p->r, p->t)), nb = mk_mat3_tmul_v3(p->r, mk_v3_neg(n)), qa, qb;
    int f = -1;
    qa = mk_v3_add(mk_mat3_mul_v3(rt, mk_core_support_typed(p->a, MK_SHAPE_BOX, n, &f)), tb);
    if (!face_witness(p->b->u.half_extents, p->a->u.half_extents, &rt, tb, qa, d, nb, tol, &qb, &qa)) return 0;
    *pa = mk_v3_add(mk_mat3_mul_v3(p->r, qa), p->t);
    *pb = mk_v3_add(mk_mat3_mul_v3(p->r, qb), p->t);
    return 1;
}

/* B's face axis n, d along it, answered in A's frame: A's corner deepest
 * along n, moved d along n, lands on B's face plane; 1 when it lies on the
 * face (to tol), the usual case (a corner of A under B's face), with one
 * rotation instead of face_witness_on_b's five. */
MK_ALWAYS_INLINE int corner_under_b(const mk_pair *p, mk_real d, mk_vec3 n, mk_real tol, mk_vec3 *pa, mk_vec3 *pb)
{
    int f = -1;
    *pa = mk_core_support_typed(p->a, MK_SHAPE_BOX, n, &f);
    *pb = mk_v3_mad(*pa, d, n);
    return in_box(p->b->u.half_extents, mk_mat3_tmul_v3(p->r, mk_v3_sub(*pb, p->t)), tol);
}

static int face_witnesses(const mk_pair *p, mk_real d, mk_vec3 n, mk_real tol, mk_vec3 *pa, mk_vec3 *pb)
{
    return face_witness_on_a(p, d, n, tol, pa, pb) || face_witness_on_b(p, d, n, tol, pa, pb);
}

/* sep(u) of two box cores for a unit u from A towards B, in closed form
 * (for any u, |u| times that). */
static mk_real box_box_separation(const mk_pair *p, mk_vec3 u)
{
    return mk_v3_dot(u, p->t) - mk_v3_dot(mk_v3_abs(mk_mat3_tmul_v3(p->r, u)), p->b->u.half_extents) -
           mk_v3_dot(mk_v3_abs(u), p->a->u.half_extents);
}

/* Corner c of a box of half extents h (bit k of c set: + along axis k, the
 * numbering of the box support's feature index). */
static mk_vec3 box_corner(mk_vec3 h, int c)
{
    return mk_v3(c & 1 ? h.x : -h.x, c & 2 ? h.y : -h.y, c & 4 ? h.z : -h.z);
}

/* Corner c of B (side 0) or of A (side 1) and its clamp into the other box:
 * the nearest point of a box to a point outside it is the clamped point. */
static mk_real corner_pair(const mk_pair *p, int side, int c, mk_vec3 *pa, mk_vec3 *pb)
{
    if (side == 0) {
        *pb = mk_v3_add(mk_mat3_mul_v3(p->r, box_corner(p->b->u.half_extents, c)), p->t);
        *pa = mk_box_clamp(p->a->u.half_extents, *pb);
    } else {
        *pa = box_corner(p->a->u.half_extents, c);
        *pb = mk_v3_add(mk_mat3_mul_v3(p->r, mk_box_clamp(p->b->u.half_extents, mk_mat3_tmul_v3(p->r, mk_v3_sub(*pa, p->t)))),
                        p->t);
    }
    return mk_v3_len2(mk_v3_sub(*pb, *pa));
}

/* A corner and its clamp are two surface points at exactly their distance;
 * if the direction between them separates the boxes by that same distance,
 * it is the boxes' distance. */
static int corner_certified(const mk_pair *p, int side, int c, mk_real tol, mk_real *d, mk_vec3 *pa, mk_vec3 *pb)
{
    mk_real l = mk_sqrt_(corner_pair(p, side, c, pa, pb));
    /* sep is positively homogeneous: sep(w) >= l (l - tol) for w = pb - pa
     * is sep(w / l) >= l - tol without the division. */
    if (!(l > 0) || !(box_box_separation(p, mk_v3_sub(*pb, *pa)) >= l * (l - tol))) return 0;
    *d = l;
    return 1;
}

/* A box centre t plus the signed half-axes e0, e1, e2 of corner c. */
MK_ALWAYS_INLINE mk_vec3 corner_from_axes(mk_vec3 t, mk_vec3 e0, mk_vec3 e1, mk_vec3 e2, int c)
{
    return mk_v3_add(mk_v3_add(mk_v3_add(t, c & 1 ? e0 : mk_v3_neg(e0)), c & 2 ? e1 : mk_v3_neg(e1)), c & 4 ? e2 : mk_v3_neg(e2));
}

/* Squared distance of a point x from a box core of half extents h. */
MK_ALWAYS_INLINE mk_real box_gap2(mk_vec3 h, mk_vec3 x) { return mk_v3_len2(mk_v3_sub(x, mk_box_clamp(h, x))); }

/* Which of the sixteen corners (B's: side 0, A's: side 1) is nearest the
 * other box. Each corner is compared in the other box's frame (rotations
 * keep lengths), built from the centre and three rotated half-axes computed
 * once: no rotation per corner. Ties keep the first, as corner_pair's order. */
static void nearest_corner(const mk_pair *p, int *side, int *corner)
{
    mk_vec3 ha = p->a->u.half_extents, hb = p->b->u.half_extents, ta = mk_v3_neg(mk_mat3_tmul_v3(p->r, p->t));
    mk_mat3 rt = mk_mat3_transpose(p->r);
    mk_vec3 e0 = mk_v3_scale(p->r.c0, hb.x), e1 = mk_v3_scale(p->r.c1, hb.y), e2 = mk_v3_scale(p->r.c2, hb.z);
    mk_vec3 f0 = mk_v3_scale(rt.c0, ha.x), f1 = mk_v3_scale(rt.c1, ha.y), f2 = mk_v3_scale(rt.c2, ha.z);
    mk_real best = MK_REAL_MAX;
    int c;
    for (c = 0; c < 8; ++c) {
        mk_real lb = box_gap2(ha, corner_from_axes(p->t, e0, e1, e2, c)), la = box_gap2(hb, corner_from_axes(ta, f0, f1, f2, c));
        if (lb < best) best = lb, *side = 0, *corner = c;
        if (la < best) best = la, *side = 1, *corner = c;
    }
}

/* The corners of A and B supporting n (towards B), each with its clamp into
 * the other box, certified; *fa, *fb: corners already tried (-1: none),
 * skipped, and on failure the corners this call tried. */
MK_ALWAYS_INLINE int supporting_corners(const mk_pair *p, mk_vec3 n, int *fa, int *fb, mk_real tol, mk_real *d, mk_vec3 *pa, mk_vec3 *pb)
{
    int ga = -1, gb = -1;
    mk_core_support_typed(p->a, MK_SHAPE_BOX, n, &ga);
    mk_core_support_typed(p->b, MK_SHAPE_BOX, mk_mat3_tmul_v3(p->r, mk_v3_neg(n)), &gb);
    if ((gb != *fb && corner_certified(p, 0, gb, tol, d, pa, pb)) || (ga != *fa && corner_certified(p, 1, ga, tol, d, pa, pb)))
        return 1;
    *fa = ga;
    *fb = gb;
    return 0;
}

/* supporting_corners from n, then once more along the direction between the
 * last corner and its clamp: a step of a walk over the corners, which finds
 * the nearest corner of boxes far apart (their closest features are mostly
 * corners). On failure *fa, *fb are the corners of the last step. */
static int corner_walk(const mk_pair *p, mk_vec3 n, mk_real tol, int *fa, int *fb, mk_real *d, mk_vec3 *pa, mk_vec3 *pb)
{
    *fa = *fb = -1;
    return supporting_corners(p, n, fa, fb, tol, d, pa, pb) || supporting_corners(p, mk_v3_sub(*pb, *pa), fa, fb, tol, d, pa, pb);
}

/* Component i of v. */
MK_ALWAYS_INLINE mk_real v3_at(mk_vec3 v, int i) { return i == 0 ? v.x : i == 1 ? v.y : v.z; }

/* v with component i set to x. */
MK_ALWAYS_INLINE mk_vec3 v3_with(mk_vec3 v, int i, mk_real x)
{
    return mk_v3(i == 0 ? x : v.x, i == 1 ? x : v.y, i == 2 ? x : v.z);
}

/* The nearest points of the three edges at A's corner ca and the three at
 * B's corner cb (nine segment pairs, closed form), certified as
 * corner_certified certifies a corner and its clamp. Far-apart boxes whose
 * closest features are two edges (which no corner and clamp realise) are
 * answered here instead of by SAT's fifteen axes; the pair also covers a
 * corner against an edge of either box. Edge i of A is {e + s u_i}, e the
 * corner with coordinate i zeroed; B's edge j is {g + t R_j} in A's frame,
 * g its centre. Unit directions, so mk_segment_params gets a = e = 1 and
 * |u_i x R_j|^2 as the sum of the two other components of R_j squared
 * (no cancellation near parallel). */
static int edge_pairs_certified(const mk_pair *p, int ca, int cb, mk_real tol, mk_real *d, mk_vec3 *pa, mk_vec3 *pb)
{
    mk_vec3 ha = p->a->u.half_extents, hb = p->b->u.half_extents, qa = box_corner(ha, ca), qb = box_corner(hb, cb), col[3];
    mk_vec3 wb = mk_v3_add(mk_mat3_mul_v3(p->r, qb), p->t), wa = mk_mat3_tmul_v3(p->r, mk_v3_sub(qa, p->t)), x, y;
    mk_real best = MK_REAL_MAX, l;
    int i, j;
    col[0] = p->r.c0;
    col[1] = p->r.c1;
    col[2] = p->r.c2;
    for (j = 0; j < 3; ++j) {
        mk_vec3 v = col[j], g = mk_v3_mad(wb, -v3_at(qb, j), v), v2 = mk_v3_mul(v, v);
        /* Only edges that run from their corner towards the other box's
         * corner (whose coordinate along the edge lies inward of this
         * corner's): a choice, not a proof (the certificate is what makes an
         * answer exact). Of bench_narrow's 215 deep separated pairs that
         * needed SAT, 155 are certified here with it, 190 with all nine
         * pairs; but trying all nine cost more than it saved. */
        if (!(v3_at(qb, j) * (v3_at(wa, j) - v3_at(qb, j)) < 0)) continue;
        for (i = 0; i < 3; ++i) {
            if (!(v3_at(qa, i) * (v3_at(wb, i) - v3_at(qa, i)) < 0)) continue;
            mk_vec3 e = v3_with(qa, i, 0), c = mk_v3_sub(g, e);
            mk_real s, t, b = v3_at(v, i), w2 = v2.x + v2.y + v2.z - v3_at(v2, i), dd;
            mk_segment_params(1, 1, b, v3_at(c, i), mk_v3_dot(c, v), w2, v3_at(ha, i), v3_at(hb, j), &s, &t);
            x = v3_with(e, i, s);
            y = mk_v3_mad(g, t, v);
            dd = mk_v3_len2(mk_v3_sub(y, x));
            if (dd < best) best = dd, *pa = x, *pb = y;
        }
    }
    l = mk_sqrt_(best);
    if (!(l > 0) || !(box_box_separation(p, mk_v3_sub(*pb, *pa)) >= l * (l - tol))) return 0;
    *d = l;
    return 1;
}

/* Certifies vertex-edge and vertex-vertex contacts, which no SAT axis
 * realises: the corners supporting SAT's best axis n first (usually the
 * answer), then the corner nearest the other box among all sixteen (sixteen
 * clamps, still far cheaper than GJK). */
static int corner_witnesses(const mk_pair *p, mk_vec3 n, mk_real tol, mk_real *d, mk_vec3 *pa, mk_vec3 *pb)
{
    int side = 0, corner = 0, fa = -1, fb = -1;
    if (supporting_corners(p, n, &fa, &fb, tol, d, pa, pb)) return 1;
    nearest_corner(p, &side, &corner);
    return corner_certified(p, side, corner, tol, d, pa, pb);
}

/* The best of the six face axes of two box cores (f: box_faces_of), turned
 * to point from A towards B, with branches: a separated pair's witnesses
 * start from it before the selects of the SAT would have settled. */
static mk_real box_face_axes(const mk_pair *p, const box_faces *f, mk_vec3 *n, int *of_b)
{
    mk_vec3 sa = f->sa, sb = f->sb;
    mk_real best = sa.x;
    int axis = 0;
    if (sa.y > best) best = sa.y, axis = 1;
    if (sa.z > best) best = sa.z, axis = 2;
    if (sb.x > best) best = sb.x, axis = 3;
    if (sb.y > best) best = sb.y, axis = 4;
    if (sb.z > best) best = sb.z, axis = 5;
    *of_b = axis >= 3;
    /* A's axes spelled out as constants: box_face_a_normal here (its
     * table and a scale) ran 0.6-1.5 % more instructions on the box
     * families (callgrind, bench_narrow minko.pose). */
    switch (axis) {
    case 0: *n = mk_v3(p->t.x >= 0 ? 1 : -1, 0, 0); break;
    case 1: *n = mk_v3(0, p->t.y >= 0 ? 1 : -1, 0); break;
    case 2: *n = mk_v3(0, 0, p->t.z >= 0 ? 1 : -1); break;
    default: *n = box_face_b_normal(&p->r, axis - 3, box_face_b_up(f, axis - 3));
    }
    return best;
}

/* SAT's best axis (kind; ei, ej: the edges of an edge pair) when the
 * witnesses its own features give fail (separated pairs the face pass and
 * the corner walk did not certify, ties at rounding level): an edge pair's
 * two edges, then the faces either way, then for a gap the corners. Out of
 * line: rare, and the hot paths keep their registers. */
static MK_NOINLINE int axis_witnesses(const mk_pair *p, mk_sat_kind kind, int ei, int ej, mk_real tol, mk_real *d, mk_vec3 *n, mk_vec3 *pa,
                                      mk_vec3 *pb)
{
    if (!(*d > -MK_REAL_MAX)) return 0; /* no axis at all (cannot happen for valid boxes) */
    if (kind == MK_SAT_EDGES && edge_witnesses(p, ei, ej, *d, *n, tol, pa, pb)) return 1;
    /* A face axis, or an edge axis that is a face normal too (parallel boxes). */
    if (face_witnesses(p, *d, *n, tol, pa, pb)) return 1;
    /* Apart, but no feature pair realises SAT's bound: a corner may. */
    if (!(*d > 0) || !corner_witnesses(p, *n, tol, d, pa, pb)) return 0;
    *n = mk_v3_scale(mk_v3_sub(*pb, *pa), 1 / *d);
    return 1;
}

/* Cores apart along a face (d > 0 along n, of B when of_b): B's corner
 * under A's face, or A's under B's; else a corner and its clamp, or two
 * edges at the last corners tried, certified along their own direction (no
 * SAT bound needed: vertex-edge, vertex-vertex and most edge-edge pairs skip
 * the nine edge axes); else every axis. */
MK_ALWAYS_INLINE int box_box_apart(const mk_pair *p, int of_b, mk_real tol, mk_real *d, mk_vec3 *n, mk_vec3 *pa, mk_vec3 *pb)
{
    mk_sat_options o;
    mk_sat_result s;
    int fa, fb;
    if (of_b ? face_witness_on_b(p, *d, *n, tol, pa, pb) : face_witness_on_a(p, *d, *n, tol, pa, pb)) return 1;
    if (corner_walk(p, *n, tol, &fa, &fb, d, pa, pb) || edge_pairs_certified(p, fa, fb, tol, d, pa, pb)) {
        *n = mk_v3_scale(mk_v3_sub(*pb, *pa), 1 / *d);
        return 1;
    }
    o = mk_sat_defaults();
    mk_sat_box_box(p->a->u.half_extents, p->b->u.half_extents, &p->r, p->t, &o, &s);
    *d = s.best;
    *n = s.normal;
    if (s.kind != MK_SAT_EDGES) return axis_witnesses(p, s.kind, 0, 0, tol, d, n, pa, pb);
    return axis_witnesses(p, s.kind, mk_box_hull_edge_id(s.a) / 4, mk_box_hull_edge_id(s.b) / 4, tol, d, n, pa, pb);
}

/* Cores whose faces overlap (f: their face separations): the inlined SAT's
 * search (an edge axis may still separate), its best axis as mk_sat_choose
 * picks it with no preference (ties to A's faces, then B's, then edges),
 * and the witnesses of that axis: the two edges it names, A's corner under
 * B's face, or B's deepest corner over A's. */
MK_ALWAYS_INLINE int box_box_overlap(const mk_pair *p, const box_faces *f, mk_real tol, mk_real *d, mk_vec3 *n, mk_vec3 *pa, mk_vec3 *pb)
{
    mk_sat_kind kind;
    box_axes x;
    int ok;
    box_sat_axes(p->a->u.half_extents, p->b->u.half_extents, &p->r, p->t, f, 0, &x);
    if (x.se > mk_max(x.sa, x.sb)) {
        int i = x.k / 3, j = x.k % 3;
        kind = MK_SAT_EDGES;
        *d = x.se;
        *n = edge_normal(p, i, j);
        ok = edge_witnesses(p, i, j, *d, *n, tol, pa, pb);
    } else if (x.sb > x.sa) {
        kind = MK_SAT_FACE_B;
        *d = x.sb;
        *n = box_face_b_normal(&p->r, x.fb, box_face_b_up(f, x.fb));
        ok = corner_under_b(p, *d, *n, tol, pa, pb) || face_witness_on_b(p, *d, *n, tol, pa, pb) || face_witness_on_a(p, *d, *n, tol, pa, pb);
    } else {
        kind = MK_SAT_FACE_A;
        *d = x.sa;
        *n = box_face_a_normal(x.fa, box_face_a_up(p->t, x.fa));
        ok = face_witness_on_a(p, *d, *n, tol, pa, pb) || face_witness_on_b(p, *d, *n, tol, pa, pb);
    }
    /* Each box's features along the axis were tried; an edge pair that
     * separates may still be realised by a corner. */
    return ok || (kind == MK_SAT_EDGES && axis_witnesses(p, MK_SAT_NONE, 0, 0, tol, d, n, pa, pb));
}

/* Box cores by SAT's 15 axes (face normals and edge cross products of the
 * original boxes, about a tenth of GJK + EPA). Its best axis gives a bound
 * that is exact for overlapping cores; for separated ones it is a lower bound
 * of the distance. The features supporting that axis (a corner under a face,
 * two edges) then give two surface points; when they are exactly the SAT
 * separation apart along the axis they are an upper bound equal to it, and
 * the answer is certified exact with no GJK: about 70% of random separated
 * pairs (corner-face and edge-edge closest features), every crossing rod and
 * every overlapping pair of issue 2's families. Any axis with such witnesses
 * certifies the distance (no other axis can separate by more than two actual
 * surface points are apart), so a pair whose best face axis already
 * separates tries that axis first (box_face_axes) and skips the nine edge
 * axes when it holds: corner-face pairs, most separated pairs, pay about half
 * as much. Separated pairs whose closest features are a corner and an edge
 * (or two corners) are certified by the corner and its clamp
 * (corner_witnesses). Pairs whose faces overlap run the SAT inlined
 * (sat_box.h; it stops at an edge axis that separates) and take the
 * witnesses of its own axis: B's deepest corner over A's face, A's under
 * B's (corner_under_b), or the two edges the edge axis names
 * (edge_witnesses). Otherwise (ties at rounding level) returns 0 and GJK,
 * then EPA if the cores overlap, answers.
 *
 * Session 10, bench_narrow minko.pose, instructions per query (callgrind)
 * before -> after: penetrating box_box 1828 -> 1334, thin_rods 1885 ->
 * 1449, parallel_faces 1674 -> 1311, deep 1828 -> 1337; separated box_box
 * 1696 -> 1567, thin_rods 1894 -> 1456, parallel_faces 841 -> 793, deep
 * 1439 -> 1352. Tried and not kept: one SAT pass for every pair (stop at
 * a separating face group, no face pass first): penetrating pairs 30-40
 * instructions fewer, but separated face pairs 5-19 % slower in time
 * (parallel_faces 71 -> 82 ns with 2000 cases per family, load 8): the
 * face pass's branches let a separated pair's witnesses start early.
 *
 * Session 11: the face separations are computed once (box_faces_of);
 * whether any separates is one maximum, and only a separated pair runs the
 * face pass's branchy choice (box_face_axes), which on overlapping pairs
 * was about one misprediction per query. Pairs whose faces overlap take
 * the SAT search's raw answer (box_sat_axes: best face of each box, best
 * edge pair by index) and build only the winner's normal and witnesses,
 * with no mk_sat_result (no half-edge names to encode and decode again);
 * the rare general tests are out of line (axis_witnesses). Instructions
 * per query, same command, before -> after: penetrating box_box 1334 ->
 * 1220, thin_rods 1449 -> 1265, parallel_faces 1311 -> 1240, deep 1337 ->
 * 1221, flat 1352 -> 1231; separated thin_rods 1456 -> 1276, flat 1557 ->
 * 1609, box_box 1567 -> 1618, parallel_faces 793 -> 821, deep 1352 -> 1401
 * (the separated path's code is the same; -O2 now stores the pair's fields
 * one by one where it stored them in pairs, and inlines corner_pair
 * differently: the separated path out of line, the fallback inline, d and
 * n by value into axis_witnesses, each measured, did not win it back).
 * Mispredictions (callgrind --branch-sim=yes), penetrating thin_rods: 4.3
 * -> 2.5 per query. Of parallel_faces' penetrating pairs, 280 of 1600 have
 * an edge axis ahead of the faces by rounding whose edges do not realise it
 * (parallel edges); they are answered by the face tests with the edge's
 * normal, as before, at about twice the cost. Tried and not kept (load
 * 11-13, A/B medians of 4 runs with --n 1000): the faces' witnesses first
 * for such near ties (parallel_faces 1270 -> 1237 instructions, time within
 * noise, thin_rods no better); the edge witnesses' corner signs and the
 * edge normal's flip as sign products instead of branches (+22
 * instructions, no fewer mispredictions, thin_rods x0.84 -> x0.94). */
static int box_box_sat(const mk_pair *p, answer *ans)
{
    mk_vec3 ha = p->a->u.half_extents, hb = p->b->u.half_extents, n, pa, pb;
    mk_real tol = 64 * MK_REAL_EPSILON * (mk_v3_max_abs(ha) + mk_v3_max_abs(hb) + mk_v3_max_abs(p->t)), d;
    int of_b;
    box_faces f;
    box_faces_of(ha, hb, &p->r, p->t, &f);
    /* Which path, without the face pass's branches (a pair whose faces
     * overlap does not need them: about one misprediction per query). */
    if (mk_max(mk_max(mk_max(f.sa.x, f.sa.y), mk_max(f.sa.z, f.sb.x)), mk_max(f.sb.y, f.sb.z)) > 0) {
        d = box_face_axes(p, &f, &n, &of_b);
        if (!box_box_apart(p, of_b, tol, &d, &n, &pa, &pb)) return 0;
    } else if (!box_box_overlap(p, &f, tol, &d, &n, &pa, &pb))
        return 0;
    witnesses(pa, pb, d, n, &pa, &pb);
    ans->hit = grow_core(pa, pb, d, n, p);
    ans->iterations = 15;
    ans->method = MK_METHOD_SAT;
    ans->state = MK_SOLVE_CONVERGED;
    return 1;
}
#endif

/* ---- composition ---------------------------------------------------------- */

/* Writes an answer given in world orientation: distance d along the normal n
 * from A's witness a. b is rebuilt from a, so point_b = point_a + distance *
 * normal holds to one rounding. `flip`: the pair ran as (B, A). */
MK_ALWAYS_INLINE void put(mk_real d, mk_vec3 n, mk_vec3 a, int flip, int iterations, mk_method method, mk_solve_state state,
                          mk_distance_result *r)
{
    mk_vec3 b = mk_v3_mad(a, d, n);
    r->distance = d;
    r->normal = flip ? mk_v3_neg(n) : n;
    r->point_a = flip ? b : a;
    r->point_b = flip ? a : b;
    r->iterations = iterations;
    r->method = method;
    r->state = state;
}

/* An answer in the frame of the first shape as run (rotation ra, origin pa). */
MK_ALWAYS_INLINE void put_framed(const mk_hit *h, const mk_mat3 *ra, mk_vec3 pa, int flip, int iterations, mk_method method,
                                 mk_solve_state state, mk_distance_result *r)
{
    put(h->distance, mk_mat3_mul_v3(*ra, h->normal), mk_v3_add(mk_mat3_mul_v3(*ra, h->a), pa), flip, iterations, method, state, r);
}

/* A closed form answered world-aligned about A's centre pa (capsule and
 * sphere paths): no rotation back. */
MK_ALWAYS_INLINE void put_aligned(mk_hit h, mk_vec3 pa, int flip, mk_distance_result *r)
{
    put(h.distance, h.normal, mk_v3_add(h.a, pa), flip, 0, MK_METHOD_CLOSED_FORM, MK_SOLVE_CONVERGED, r);
}

/* The closed forms take only the parts of the poses their pair uses (the
 * centres, a capsule's axis, a box's rotation), so that the mk_transform
 * entry converts no more of a quaternion than that (transform_methods). */
MK_ALWAYS_INLINE void spheres(const mk_shape *a, mk_vec3 pa, const mk_shape *b, mk_vec3 pb, mk_distance_result *r)
{
    mk_real l;
    mk_vec3 n = mk_unit_len(mk_v3_sub(pb, pa), &l);
    /* Concentric spheres: every direction is a shortest way out; take +z. */
    if (!(l > 0)) n = mk_v3(0, 0, 1);
    put(l - a->radius - b->radius, n, mk_v3_mad(pa, a->radius, n), 0, 0, MK_METHOD_CLOSED_FORM, MK_SOLVE_CONVERGED, r);
}

/* The answer of box_sphere for a sphere centre at a gap of length l > 0
 * from the box core along v (box frame), s = 1 / |v|. Only the gap is
 * rotated back: the box point is the sphere's centre less the gap (pb - R v,
 * not R q + pa), so A's witness is pb less (l - radius) along n: one
 * rotation fewer on the critical chain. */
MK_ALWAYS_INLINE void box_sphere_gap(const mk_shape *a, const mk_mat3 *ra, const mk_shape *b, const mk_vec3 *pb, mk_vec3 v, mk_real l,
                                     mk_real s, int flip, mk_distance_result *r)
{
    mk_vec3 n = mk_v3_scale(mk_mat3_mul_v3(*ra, v), s);
    put(l - a->radius - b->radius, n, mk_v3_mad(*pb, a->radius - l, n), flip, 0, MK_METHOD_CLOSED_FORM, MK_SOLVE_CONVERGED, r);
}

/* box_sphere with the sphere's centre inside the box core: it leaves
 * through the nearest face. Out of line, so that the common case keeps the
 * rotation in registers. */
static MK_NOINLINE void box_sphere_inside(const mk_shape *a, const mk_mat3 *ra, const mk_vec3 *pa, const mk_shape *b,
                                          const mk_vec3 *pb, int flip, mk_distance_result *r)
{
    mk_vec3 n, q;
    mk_real l = -mk_box_exit(a->u.half_extents, mk_mat3_tmul_v3(*ra, mk_v3_sub(*pb, *pa)), &n, &q);
    n = mk_mat3_mul_v3(*ra, n);
    put(l - a->radius - b->radius, n, mk_v3_mad(mk_v3_add(mk_mat3_mul_v3(*ra, q), *pa), a->radius, n), flip, 0, MK_METHOD_CLOSED_FORM,
        MK_SOLVE_CONVERGED, r);
}

/* box_sphere with a gap too small for 1 / |v|^2 (below 1 / MK_REAL_MAX):
 * |v|^2 is subnormal there and has lost most of its bits, and 1 / |v| may
 * overflow, so the direction and length come from u = v / m, m the largest
 * component (|u| in [1, sqrt 3], |v| = m |u|). Out of line for the same
 * reason. */
static MK_NOINLINE void box_sphere_tiny_gap(const mk_shape *a, const mk_mat3 *ra, const mk_vec3 *pa, const mk_shape *b,
                                            const mk_vec3 *pb, int flip, mk_distance_result *r)
{
    mk_vec3 c = mk_mat3_tmul_v3(*ra, mk_v3_sub(*pb, *pa)), v = mk_v3_sub(c, mk_box_clamp(a->u.half_extents, c));
    mk_real m = mk_v3_max_abs(v), lu;
    mk_vec3 u = mk_v3(v.x / m, v.y / m, v.z / m);
    lu = mk_sqrt_(mk_v3_len2(u));
    box_sphere_gap(a, ra, b, pb, u, m * lu, 1 / lu, flip, r);
}

/* mk_closest_box_sphere's steps, answered in world space. |v|^2 cannot
 * overflow (validated positions and sizes keep it below ~1e152 in double,
 * ~1e17 in float), so one test of its lower end guards 1 / |v| = |v| *
 * (1 / |v|^2), whose division need not wait for the square root; the test
 * also sends a centre inside the core (v = 0) out of line. */
MK_ALWAYS_INLINE void box_sphere(const mk_shape *a, const mk_mat3 *ra, const mk_vec3 *pa, const mk_shape *b, const mk_vec3 *pb,
                                 int flip, mk_distance_result *r)
{
    mk_vec3 h = a->u.half_extents, c = mk_mat3_tmul_v3(*ra, mk_v3_sub(*pb, *pa)), v = mk_v3_sub(c, mk_box_clamp(h, c));
    mk_real l2 = mk_v3_len2(v), l;
    if (!(l2 >= 1 / MK_REAL_MAX)) {
        /* v != 0, not l2 > 0: a gap below ~1e-162 (~4e-23 in float) squares to 0. */
        if (mk_v3_max_abs(v) > 0) box_sphere_tiny_gap(a, ra, pa, b, pb, flip, r);
        else box_sphere_inside(a, ra, pa, b, pb, flip, r);
        return;
    }
    l = mk_sqrt_(l2);
    box_sphere_gap(a, ra, b, pb, v, l, l * (1 / l2), flip, r);
}

/* ua: the capsule's axis (its z axis in world). */
MK_ALWAYS_INLINE void capsule_sphere(const mk_shape *a, mk_vec3 ua, mk_vec3 pa, const mk_shape *b, mk_vec3 pb, int flip,
                                     mk_distance_result *r)
{
    put_aligned(mk_closest_capsule_sphere(a->u.capsule.half_height, ua, a->radius, mk_v3_sub(pb, pa), b->radius), pa, flip, r);
}

MK_ALWAYS_INLINE void capsules(const mk_shape *a, mk_vec3 ua, mk_vec3 pa, const mk_shape *b, mk_vec3 ub, mk_vec3 pb,
                               mk_distance_result *r)
{
    put_aligned(mk_closest_capsule_capsule(a->u.capsule.half_height, ua, a->radius, mk_v3_sub(pb, pa), ub,
                                           b->u.capsule.half_height, b->radius),
                pa, 0, r);
}

/* The methods that run in A's frame with B's whole relative pose. */
typedef enum framed_method { FRAMED_PLANE, FRAMED_BOX_BOX, FRAMED_GJK } framed_method;

/* Planes, box pairs, GJK and EPA: in A's frame with B's whole relative pose
 * (mk_pair). Out of line, so that no closed form pays for its stack frame. */
static MK_NOINLINE mk_status framed(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb,
                                    framed_method m, int flip, mk_gjk_cache *cache, mk_distance_result *r)
{
    mk_pair p = mk_pair_of_poses_(a, xa, b, xb);
    answer ans;
    ans.iterations = 0;
    ans.method = MK_METHOD_CLOSED_FORM;
    ans.state = MK_SOLVE_CONVERGED;
    switch (m) {
    case FRAMED_PLANE: ans.hit = mk_closest_shape_plane(&p); break;
    case FRAMED_BOX_BOX: /* pairs SAT cannot certify (or no SAT in this build) go on to GJK */
#ifndef MK_WITHOUT_SAT
        if (box_box_sat(&p, &ans)) break;
#endif
        /* fall through */
    case FRAMED_GJK: {
#ifdef MK_WITHOUT_GJK
        (void)cache;
        return MK_ERR_UNSUPPORTED;
#else
        mk_status st = iterative(&p, cache, &ans);
        if (st != MK_OK) return st;
        break;
#endif
    }
    }
    put_framed(&ans.hit, &xa->r, xa->p, flip, ans.iterations, ans.method, ans.state, r);
    return MK_OK;
}

/* ---- dispatch ------------------------------------------------------------- */

/* One method per ordered pair of shape types: it validates its own input (so
 * a closed form checks its two known types with no switch) and answers.
 * Methods named X_Y with a pair that has a closed form only one way round
 * run it as (Y, X) and flip the answer back. Shapes are not NULL. */
typedef mk_status (*pair_fn)(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb,
                             mk_gjk_cache *cache, mk_distance_result *r);

static mk_status q_spheres(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb,
                           mk_gjk_cache *cache, mk_distance_result *r)
{
    (void)cache;
    if (!accept(a, MK_SHAPE_SPHERE, xa, b, MK_SHAPE_SPHERE, xb)) return diagnose(a, xa, b, xb);
    spheres(a, xa->p, b, xb->p, r);
    return MK_OK;
}

static mk_status q_box_sphere(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb,
                              mk_gjk_cache *cache, mk_distance_result *r)
{
    (void)cache;
    if (!accept(a, MK_SHAPE_BOX, xa, b, MK_SHAPE_SPHERE, xb)) return diagnose(a, xa, b, xb);
    box_sphere(a, &xa->r, &xa->p, b, &xb->p, 0, r);
    return MK_OK;
}

static mk_status q_sphere_box(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb,
                              mk_gjk_cache *cache, mk_distance_result *r)
{
    (void)cache;
    if (!accept(b, MK_SHAPE_BOX, xb, a, MK_SHAPE_SPHERE, xa)) return diagnose(a, xa, b, xb);
    box_sphere(b, &xb->r, &xb->p, a, &xa->p, 1, r);
    return MK_OK;
}

static mk_status q_capsule_sphere(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb,
                                  mk_gjk_cache *cache, mk_distance_result *r)
{
    (void)cache;
    if (!accept(a, MK_SHAPE_CAPSULE, xa, b, MK_SHAPE_SPHERE, xb)) return diagnose(a, xa, b, xb);
    capsule_sphere(a, xa->r.c2, xa->p, b, xb->p, 0, r);
    return MK_OK;
}

static mk_status q_sphere_capsule(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb,
                                  mk_gjk_cache *cache, mk_distance_result *r)
{
    (void)cache;
    if (!accept(b, MK_SHAPE_CAPSULE, xb, a, MK_SHAPE_SPHERE, xa)) return diagnose(a, xa, b, xb);
    capsule_sphere(b, xb->r.c2, xb->p, a, xa->p, 1, r);
    return MK_OK;
}

static mk_status q_capsules(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb,
                            mk_gjk_cache *cache, mk_distance_result *r)
{
    (void)cache;
    if (!accept(a, MK_SHAPE_CAPSULE, xa, b, MK_SHAPE_CAPSULE, xb)) return diagnose(a, xa, b, xb);
    capsules(a, xa->r.c2, xa->p, b, xb->r.c2, xb->p, r);
    return MK_OK;
}

static mk_status q_shape_plane(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb,
                               mk_gjk_cache *cache, mk_distance_result *r)
{
    if (!accept(a, a->type, xa, b, MK_SHAPE_PLANE, xb)) return diagnose(a, xa, b, xb);
    return framed(a, xa, b, xb, FRAMED_PLANE, 0, cache, r);
}

static mk_status q_plane_shape(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb,
                               mk_gjk_cache *cache, mk_distance_result *r)
{
    if (!accept(b, b->type, xb, a, MK_SHAPE_PLANE, xa)) return diagnose(a, xa, b, xb);
    return framed(b, xb, a, xa, FRAMED_PLANE, 1, cache, r);
}

static mk_status q_box_box(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb,
                           mk_gjk_cache *cache, mk_distance_result *r)
{
    if (!accept(a, MK_SHAPE_BOX, xa, b, MK_SHAPE_BOX, xb)) return diagnose(a, xa, b, xb);
    return framed(a, xa, b, xb, FRAMED_BOX_BOX, 0, cache, r);
}

static mk_status q_gjk(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb,
                       mk_gjk_cache *cache, mk_distance_result *r)
{
    if (!accept(a, a->type, xa, b, b->type, xb)) return diagnose(a, xa, b, xb);
    return framed(a, xa, b, xb, FRAMED_GJK, 0, cache, r);
}

/* Plane-plane pairs, and shapes of unknown type (which validation names). */
static mk_status q_unsupported(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb,
                               mk_gjk_cache *cache, mk_distance_result *r)
{
    mk_status st = check(a, xa, b, xb);
    (void)cache;
    (void)r;
    return st != MK_OK ? st : MK_ERR_UNSUPPORTED;
}

/* The closed forms again for the mk_transform entry, on two transforms that
 * passed mk_transform_ok_: each converts only what its pair reads, so a
 * sphere's quaternion is checked (a non-unit one is still
 * MK_ERR_BAD_ROTATION: the contract does not depend on the shape) but never
 * turned into a matrix, a box's becomes its matrix and a capsule's only its
 * axis. They compute what the pose methods compute from the same bits
 * (tests/test_distance.c, pose_path_matches_transform_path). */
typedef mk_status (*transform_fn)(const mk_shape *a, const mk_transform *xa, const mk_shape *b, const mk_transform *xb,
                                  mk_distance_result *r);

static mk_status x_spheres(const mk_shape *a, const mk_transform *xa, const mk_shape *b, const mk_transform *xb,
                           mk_distance_result *r)
{
    if (!shapes_ok(a, MK_SHAPE_SPHERE, b, MK_SHAPE_SPHERE)) return diagnose_shapes(a, b);
    spheres(a, xa->p, b, xb->p, r);
    return MK_OK;
}

static mk_status x_box_sphere(const mk_shape *a, const mk_transform *xa, const mk_shape *b, const mk_transform *xb,
                              mk_distance_result *r)
{
    mk_mat3 ra;
    if (!shapes_ok(a, MK_SHAPE_BOX, b, MK_SHAPE_SPHERE)) return diagnose_shapes(a, b);
    ra = mk_rotation_of(xa->q);
    box_sphere(a, &ra, &xa->p, b, &xb->p, 0, r);
    return MK_OK;
}

static mk_status x_sphere_box(const mk_shape *a, const mk_transform *xa, const mk_shape *b, const mk_transform *xb,
                              mk_distance_result *r)
{
    mk_mat3 rb;
    if (!shapes_ok(b, MK_SHAPE_BOX, a, MK_SHAPE_SPHERE)) return diagnose_shapes(a, b);
    rb = mk_rotation_of(xb->q);
    box_sphere(b, &rb, &xb->p, a, &xa->p, 1, r);
    return MK_OK;
}

static mk_status x_capsule_sphere(const mk_shape *a, const mk_transform *xa, const mk_shape *b, const mk_transform *xb,
                                  mk_distance_result *r)
{
    if (!shapes_ok(a, MK_SHAPE_CAPSULE, b, MK_SHAPE_SPHERE)) return diagnose_shapes(a, b);
    capsule_sphere(a, mk_rotation_z_of(xa->q), xa->p, b, xb->p, 0, r);
    return MK_OK;
}

static mk_status x_sphere_capsule(const mk_shape *a, const mk_transform *xa, const mk_shape *b, const mk_transform *xb,
                                  mk_distance_result *r)
{
    if (!shapes_ok(b, MK_SHAPE_CAPSULE, a, MK_SHAPE_SPHERE)) return diagnose_shapes(a, b);
    capsule_sphere(b, mk_rotation_z_of(xb->q), xb->p, a, xa->p, 1, r);
    return MK_OK;
}

static mk_status x_capsules(const mk_shape *a, const mk_transform *xa, const mk_shape *b, const mk_transform *xb,
                            mk_distance_result *r)
{
    if (!shapes_ok(a, MK_SHAPE_CAPSULE, b, MK_SHAPE_CAPSULE)) return diagnose_shapes(a, b);
    capsules(a, mk_rotation_z_of(xa->q), xa->p, b, mk_rotation_z_of(xb->q), xb->p, r);
    return MK_OK;
}

/* A pair's method for each entry: `transform` is NULL where the pair needs
 * both whole rotations, and the mk_transform entry then converts both. */
typedef struct pair_methods {
    pair_fn pose;
    transform_fn transform;
} pair_methods;

#define GJK_ {q_gjk, NULL}
#define S_PL {q_shape_plane, NULL}
#define PL_S {q_plane_shape, NULL}
static const pair_methods methods[MK_SHAPE_TYPE_COUNT][MK_SHAPE_TYPE_COUNT] = {
    /* sphere */ {{q_spheres, x_spheres}, {q_sphere_box, x_sphere_box}, {q_sphere_capsule, x_sphere_capsule}, GJK_, GJK_, GJK_, S_PL},
    /* box    */ {{q_box_sphere, x_box_sphere}, {q_box_box, NULL}, GJK_, GJK_, GJK_, GJK_, S_PL},
    /* capsule*/ {{q_capsule_sphere, x_capsule_sphere}, GJK_, {q_capsules, x_capsules}, GJK_, GJK_, GJK_, S_PL},
    /* cyl.   */ {GJK_, GJK_, GJK_, GJK_, GJK_, GJK_, S_PL},
    /* cone   */ {GJK_, GJK_, GJK_, GJK_, GJK_, GJK_, S_PL},
    /* hull   */ {GJK_, GJK_, GJK_, GJK_, GJK_, GJK_, S_PL},
    /* plane  */ {PL_S, PL_S, PL_S, PL_S, PL_S, PL_S, {q_unsupported, NULL}},
};
#undef GJK_
#undef S_PL
#undef PL_S

static const pair_methods *method_of(const mk_shape *a, const mk_shape *b)
{
    static const pair_methods unknown = {q_unsupported, NULL};
    unsigned ta = (unsigned)a->type, tb = (unsigned)b->type;
    return ta < MK_SHAPE_TYPE_COUNT && tb < MK_SHAPE_TYPE_COUNT ? &methods[ta][tb] : &unknown;
}

mk_status mk_distance_pose(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_gjk_cache *cache,
                           mk_distance_result *out)
{
    if (!a || !xa || !b || !xb || !out) return MK_ERR_NULL;
    return method_of(a, b)->pose(a, xa, b, xb, cache, out);
}

/* The pose method m of a pair that reads both whole rotations, from two
 * accepted transforms. Out of line: its conversions would otherwise share
 * registers with the transform checks of every closed form. */
static MK_NOINLINE mk_status distance_posed(pair_fn m, const mk_shape *a, const mk_transform *xa, const mk_shape *b,
                                            const mk_transform *xb, mk_gjk_cache *cache, mk_distance_result *out)
{
    mk_pose pa, pb;
    mk_pose_set_(&pa, xa);
    mk_pose_set_(&pb, xb);
    return m(a, &pa, b, &pb, cache, out);
}

mk_status mk_distance(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb, mk_gjk_cache *cache,
                      mk_distance_result *out)
{
    const pair_methods *m;
    if (!a || !b || !out) return MK_ERR_NULL;
    if (!mk_transform_ok_(&xa) || !mk_transform_ok_(&xb)) return diagnose_transforms(a, &xa, b, &xb);
    m = method_of(a, b);
    if (m->transform) return m->transform(a, &xa, b, &xb, out);
    return distance_posed(m->pose, a, &xa, b, &xb, cache, out);
}

/* Two spheres' boolean: no square root. */
MK_ALWAYS_INLINE int spheres_touch(const mk_shape *a, mk_vec3 pa, const mk_shape *b, mk_vec3 pb)
{
    mk_real s = a->radius + b->radius;
    return mk_v3_len2(mk_v3_sub(pb, pa)) <= s * s;
}

/* The boolean query for checked poses (shapes and poses not NULL). */
static mk_status overlap(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_gjk_cache *cache,
                         int *overlapping)
{
    pair_fn m = method_of(a, b)->pose;
    mk_distance_result r;
    mk_status st;
    if (m == q_spheres) {
        if (!accept(a, MK_SHAPE_SPHERE, xa, b, MK_SHAPE_SPHERE, xb)) return diagnose(a, xa, b, xb);
        *overlapping = spheres_touch(a, xa->p, b, xb->p);
        return MK_OK;
    }
#ifndef MK_WITHOUT_GJK
    if (m == q_gjk || m == q_box_box) { /* GJK stops at the first separating axis or enclosing simplex */
        mk_pair p;
        mk_gjk_result g;
        if ((st = check(a, xa, b, xb)) != MK_OK) return st;
        p = mk_pair_of_poses_(a, xa, b, xb);
        mk_gjk(&p, cache, 1, a->radius + b->radius, &g);
        if (cache) mk_gjk_cache_store(&g.s, g.normal, cache);
        *overlapping = g.overlap;
        return MK_OK;
    }
#endif
    if ((st = m(a, xa, b, xb, cache, &r)) != MK_OK) return st;
    *overlapping = r.distance <= 0;
    return MK_OK;
}

mk_status mk_overlap_pose(const mk_shape *a, const mk_pose *xa, const mk_shape *b, const mk_pose *xb, mk_gjk_cache *cache,
                          int *overlapping)
{
    if (!a || !xa || !b || !xb || !overlapping) return MK_ERR_NULL;
    return overlap(a, xa, b, xb, cache, overlapping);
}

mk_status mk_overlap(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb, mk_gjk_cache *cache,
                     int *overlapping)
{
    const pair_methods *m;
    mk_distance_result r;
    mk_pose pa, pb;
    mk_status st;
    if (!a || !b || !overlapping) return MK_ERR_NULL;
    if (!mk_transform_ok_(&xa) || !mk_transform_ok_(&xb)) return diagnose_transforms(a, &xa, b, &xb);
    m = method_of(a, b);
    if (m->pose == q_spheres) {
        if (!shapes_ok(a, MK_SHAPE_SPHERE, b, MK_SHAPE_SPHERE)) return diagnose_shapes(a, b);
        *overlapping = spheres_touch(a, xa.p, b, xb.p);
        return MK_OK;
    }
    if (m->transform) { /* the other closed forms: as mk_distance, converting what the pair reads */
        if ((st = m->transform(a, &xa, b, &xb, &r)) != MK_OK) return st;
        *overlapping = r.distance <= 0;
        return MK_OK;
    }
    mk_pose_set_(&pa, &xa);
    mk_pose_set_(&pb, &xb);
    return overlap(a, &pa, b, &pb, cache, overlapping);
}

/* ---- seed 003: approximate distance ---------------------------------------- */

/* Core vertex nearest q (shape frame). Boxes and segments answer exactly; a
 * hull walks downhill over its vertex graph from `start` (a local minimum of
 * the distance, which is all the upper bound needs). */
static int nearest_vertex(const mk_shape *s, mk_vec3 q, int start)
{
    switch (s->type) {
    case MK_SHAPE_BOX: return (q.x >= 0 ? 1 : 0) | (q.y >= 0 ? 2 : 0) | (q.z >= 0 ? 4 : 0);
    case MK_SHAPE_CAPSULE: return q.z >= 0 ? 1 : 0;
    case MK_SHAPE_HULL: {
        const mk_hull *h = s->u.hull;
        int best = start, moved = 1;
        mk_real bd = mk_v3_len2(mk_v3_sub(h->vertices[best], q));
        while (moved) {
            int e0 = h->vertex_edge[best], e = e0;
            moved = 0;
            do {
                int w = h->edges[h->edges[e].twin].origin;
                mk_real d = mk_v3_len2(mk_v3_sub(h->vertices[w], q));
                if (d < bd) {
                    best = w;
                    bd = d;
                    moved = 1;
                    break;
                }
                e = h->edges[h->edges[e].twin].next;
            } while (e != e0);
        }
        return best;
    }
    default: return 0;
    }
}

mk_status mk_approx_distance(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb, mk_real *out)
{
    mk_status st;
    mk_pair p;
    mk_vec3 va, vb;
    int ia = -1, ib;
    mk_pose pa, pb;
    if (!a || !b || !out) return MK_ERR_NULL;
    if (!mk_transform_ok_(&xa) || !mk_transform_ok_(&xb)) return diagnose_transforms(a, &xa, b, &xb);
    mk_pose_set_(&pa, &xa);
    mk_pose_set_(&pb, &xb);
    if ((st = check(a, &pa, b, &pb)) != MK_OK) return st;
    if (!mk_core_is_polytope(a) || !mk_core_is_polytope(b)) return MK_ERR_UNSUPPORTED;
    p = mk_pair_of_poses_(a, &pa, b, &pb);
    /* Start from A's vertex facing B rather than an arbitrary one: one support, a better bound. */
    mk_core_support_inl(a, p.t, &ia);
    va = mk_core_vertex(a, ia);
    ib = nearest_vertex(b, mk_mat3_tmul_v3(p.r, mk_v3_sub(va, p.t)), 0);
    vb = mk_v3_add(mk_mat3_mul_v3(p.r, mk_core_vertex(b, ib)), p.t);
    ia = nearest_vertex(a, vb, ia);
    va = mk_core_vertex(a, ia);
    *out = mk_v3_dist(va, vb) - a->radius - b->radius;
    return MK_OK;
}

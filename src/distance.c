/* distance.c: public pair queries: validation, the dispatch table, GJK + EPA composition. */
#include "closest.h"
#ifndef MK_WITHOUT_EPA
#  include "epa.h"
#endif
#ifndef MK_WITHOUT_SAT
#  include "sat.h"
#endif

const char *mk_method_name(mk_method m)
{
    static const char *const names[] = {"none", "closed_form", "gjk", "epa", "sat"};
    return (unsigned)m <= MK_METHOD_SAT ? names[m] : "unknown";
}

/* ---- dispatch ------------------------------------------------------------- */

typedef enum path {
    PATH_UNSUPPORTED = 0,
    PATH_SPHERES,        /* closed form, world frame */
    PATH_BOX_SPHERE,     /* closed form */
    PATH_CAPSULE_SPHERE, /* closed form */
    PATH_CAPSULES,       /* closed form: segment-segment */
    PATH_PLANE,          /* closed form: support along the plane normal */
    PATH_BOX_BOX,        /* SAT's 15 axes when the cores overlap, GJK for the distance otherwise */
    PATH_GJK             /* GJK on the cores, EPA when they overlap */
} path;

/* [type of A][type of B] -> method; `swap` runs it as (B, A) and flips the answer. */
typedef struct route { unsigned char path, swap; } route;
#define R_(p, s) {PATH_##p, s}
static const route routes[MK_SHAPE_TYPE_COUNT][MK_SHAPE_TYPE_COUNT] = {
    /*            sphere                    box                   capsule                  cylinder       cone           hull           plane */
    /* sphere */ {R_(SPHERES, 0),          R_(BOX_SPHERE, 1),    R_(CAPSULE_SPHERE, 1),   R_(GJK, 0),    R_(GJK, 0),    R_(GJK, 0),    R_(PLANE, 0)},
    /* box    */ {R_(BOX_SPHERE, 0),       R_(BOX_BOX, 0),       R_(GJK, 0),              R_(GJK, 0),    R_(GJK, 0),    R_(GJK, 0),    R_(PLANE, 0)},
    /* capsule*/ {R_(CAPSULE_SPHERE, 0),   R_(GJK, 0),           R_(CAPSULES, 0),         R_(GJK, 0),    R_(GJK, 0),    R_(GJK, 0),    R_(PLANE, 0)},
    /* cyl.   */ {R_(GJK, 0),              R_(GJK, 0),           R_(GJK, 0),              R_(GJK, 0),    R_(GJK, 0),    R_(GJK, 0),    R_(PLANE, 0)},
    /* cone   */ {R_(GJK, 0),              R_(GJK, 0),           R_(GJK, 0),              R_(GJK, 0),    R_(GJK, 0),    R_(GJK, 0),    R_(PLANE, 0)},
    /* hull   */ {R_(GJK, 0),              R_(GJK, 0),           R_(GJK, 0),              R_(GJK, 0),    R_(GJK, 0),    R_(GJK, 0),    R_(PLANE, 0)},
    /* plane  */ {R_(PLANE, 1),            R_(PLANE, 1),         R_(PLANE, 1),            R_(PLANE, 1),  R_(PLANE, 1),  R_(PLANE, 1),  R_(UNSUPPORTED, 0)},
};
#undef R_

/* ---- validation ----------------------------------------------------------- */

/* Every query pays this, so the accepting path is short: v - v is 0 for a
 * finite v and NaN otherwise, and a NaN or infinite quaternion fails the
 * unit-length test, after which we only work out which error to name. A
 * quaternion within MK_QUAT_TOLERANCE is accepted; paths that use it
 * renormalise it (unit). */
MK_ALWAYS_INLINE mk_status check_pose(mk_transform x)
{
    mk_quat q = x.q;
    if ((x.p.x - x.p.x) + (x.p.y - x.p.y) + (x.p.z - x.p.z) != 0) return MK_ERR_NOT_FINITE;
    if (mk_fabs_(mk_quat_len2(q) - 1) <= MK_QUAT_TOLERANCE) return MK_OK;
    return mk_real_is_valid(q.x) && mk_real_is_valid(q.y) && mk_real_is_valid(q.z) && mk_real_is_valid(q.w)
               ? MK_ERR_BAD_ROTATION
               : MK_ERR_NOT_FINITE;
}

/* The closed forms' shapes, accepted without a call: exactly what
 * mk_shape_validate accepts for them (sizes in (0, MK_MAX_SIZE], NaN fails
 * every comparison); anything else goes to mk_shape_validate, which names the
 * error and knows every other shape. */
MK_ALWAYS_INLINE int primitive_ok(const mk_shape *s)
{
    mk_real r = s->radius;
    switch (s->type) {
    case MK_SHAPE_SPHERE: return r > 0 && r <= MK_MAX_SIZE;
    case MK_SHAPE_CAPSULE: return r > 0 && r <= MK_MAX_SIZE && s->u.capsule.half_height > 0 && s->u.capsule.half_height <= MK_MAX_SIZE;
    case MK_SHAPE_BOX: {
        mk_vec3 h = s->u.half_extents;
        return r >= 0 && r <= MK_MAX_SIZE && h.x > 0 && h.x <= MK_MAX_SIZE && h.y > 0 && h.y <= MK_MAX_SIZE && h.z > 0 &&
               h.z <= MK_MAX_SIZE;
    }
    default: return 0;
    }
}

MK_ALWAYS_INLINE mk_status check_inputs(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb,
                                        const void *out)
{
    mk_status st;
    if (!a || !b || !out) return MK_ERR_NULL;
    if (!primitive_ok(a) && (st = mk_shape_validate(a)) != MK_OK) return st;
    if (!primitive_ok(b) && (st = mk_shape_validate(b)) != MK_OK) return st;
    if ((st = check_pose(xa)) != MK_OK) return st;
    return check_pose(xb);
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
    mk_hit h;
    h.distance = dc - p->a->radius - p->b->radius;
    h.normal = n;
    h.a = mk_v3_mad(a, p->a->radius, n);
    h.b = mk_v3_mad(b, -p->b->radius, n);
    return h;
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
/* The box edge that supports dir when dir is perpendicular to it: the corner
 * with the signs of dir, spanned along the axis dir has (almost) no part of. */
static void box_support_edge(mk_vec3 h, mk_vec3 dir, mk_vec3 *e0, mk_vec3 *e1)
{
    mk_vec3 c = mk_v3(dir.x >= 0 ? h.x : -h.x, dir.y >= 0 ? h.y : -h.y, dir.z >= 0 ? h.z : -h.z), ad = mk_v3_abs(dir);
    *e0 = *e1 = c;
    if (ad.x <= ad.y && ad.x <= ad.z) {
        e0->x = -h.x;
        e1->x = h.x;
    } else if (ad.y <= ad.z) {
        e0->y = -h.y;
        e1->y = h.y;
    } else {
        e0->z = -h.z;
        e1->z = h.z;
    }
}

static int in_box(mk_vec3 h, mk_vec3 x, mk_real tol)
{
    return mk_fabs_(x.x) <= h.x + tol && mk_fabs_(x.y) <= h.y + tol && mk_fabs_(x.z) <= h.z + tol;
}

static mk_vec3 clamp_box(mk_vec3 h, mk_vec3 x)
{
    return mk_v3(mk_clamp(x.x, -h.x, h.x), mk_clamp(x.y, -h.y, h.y), mk_clamp(x.z, -h.z, h.z));
}

/* Witnesses of a SAT axis n with separation d for one box (half extents hf,
 * its own frame) and the other box's supporting corner q (same frame): q
 * moved back by d along n lands on this box's supporting plane; clamped into
 * the box and still on that plane, it is a surface point. If it had to move
 * sideways (parallel faces offset, or n an edge axis), the point d along n
 * from it must be on the other box (half extents ho, x = r_o x_o + t_o).
 * Returns 1 with two surface points b - a = d n exactly (to tol). Valid for
 * any axis: the plane and box tests are what make the points witnesses. */
static int face_witness(mk_vec3 hf, mk_vec3 ho, const mk_mat3 *r_o, mk_vec3 t_o, mk_vec3 q, mk_real d, mk_vec3 n, mk_real tol,
                        mk_vec3 *on_face, mk_vec3 *on_other)
{
    mk_vec3 x0 = mk_v3_mad(q, -d, n), x = clamp_box(hf, x0), y = mk_v3_mad(x, d, n);
    *on_face = x;
    *on_other = q;
    if (!(mk_fabs_(mk_v3_dot(n, mk_v3_sub(x, x0))) <= tol)) return 0; /* clamping left the plane */
    if (mk_v3_max_abs(mk_v3_sub(q, y)) <= tol) return 1;
    *on_other = y;
    return in_box(ho, mk_mat3_tmul_v3(*r_o, mk_v3_sub(y, t_o)), tol);
}

/* Face witnesses with A as the box B's supporting corner projects on. */
static int face_witness_on_a(const mk_pair *p, mk_real d, mk_vec3 n, mk_real tol, mk_vec3 *pa, mk_vec3 *pb)
{
    int f = -1;
    *pb = mk_v3_add(mk_mat3_mul_v3(p->r, mk_core_support_typed(p->b, MK_SHAPE_BOX, mk_mat3_tmul_v3(p->r, mk_v3_neg(n)), &f)), p->t);
    return face_witness(p->a->u.half_extents, p->b->u.half_extents, &p->r, p->t, *pb, d, n, tol, pa, pb);
}

/* The same with B as the face box, worked in B's frame with A's corner. */
static int face_witness_on_b(const mk_pair *p, mk_real d, mk_vec3 n, mk_real tol, mk_vec3 *pa, mk_vec3 *pb)
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

static int face_witnesses(const mk_pair *p, mk_real d, mk_vec3 n, mk_real tol, mk_vec3 *pa, mk_vec3 *pb)
{
    return face_witness_on_a(p, d, n, tol, pa, pb) || face_witness_on_b(p, d, n, tol, pa, pb);
}

/* sep(u) of two box cores for a unit u from A towards B, in closed form. */
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
        *pa = clamp_box(p->a->u.half_extents, *pb);
    } else {
        *pa = box_corner(p->a->u.half_extents, c);
        *pb = mk_v3_add(mk_mat3_mul_v3(p->r, clamp_box(p->b->u.half_extents, mk_mat3_tmul_v3(p->r, mk_v3_sub(*pa, p->t)))),
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
    if (!(l > 0) || !(box_box_separation(p, mk_v3_scale(mk_v3_sub(*pb, *pa), 1 / l)) >= l - tol)) return 0;
    *d = l;
    return 1;
}

/* Certifies vertex-edge and vertex-vertex contacts, which no SAT axis
 * realises: the corners supporting SAT's best axis n first (usually the
 * answer), then the corner nearest the other box among all sixteen (sixteen
 * clamps, still far cheaper than GJK). */
static int corner_witnesses(const mk_pair *p, mk_vec3 n, mk_real tol, mk_real *d, mk_vec3 *pa, mk_vec3 *pb)
{
    int c, fa = -1, fb = -1, side = 0, corner = 0;
    mk_real best = MK_REAL_MAX;
    mk_core_support_typed(p->a, MK_SHAPE_BOX, n, &fa);
    mk_core_support_typed(p->b, MK_SHAPE_BOX, mk_mat3_tmul_v3(p->r, mk_v3_neg(n)), &fb);
    if (corner_certified(p, 0, fb, tol, d, pa, pb) || corner_certified(p, 1, fa, tol, d, pa, pb)) return 1;
    for (c = 0; c < 16; ++c) {
        mk_real l2 = corner_pair(p, c & 1, c >> 1, pa, pb);
        if (l2 < best) best = l2, side = c & 1, corner = c >> 1;
    }
    return corner_certified(p, side, corner, tol, d, pa, pb);
}

/* The best of the six face axes of two box cores (A's e_i, B's R_j, each
 * turned to point from A towards B) in closed form: the face-axis half of
 * SAT, which a separated pair often needs alone (box_box_sat). */
static mk_real box_face_axes(const mk_pair *p, mk_vec3 *n, int *of_b)
{
    mk_vec3 ha = p->a->u.half_extents, hb = p->b->u.half_extents, tb = mk_mat3_tmul_v3(p->r, p->t);
    mk_mat3 ar = mk_mat3_abs(p->r);
    /* B's extent along A's axes is |R| hb, A's along B's is |R|^T ha. */
    mk_vec3 sa = mk_v3_sub(mk_v3_sub(mk_v3_abs(p->t), ha), mk_mat3_mul_v3(ar, hb));
    mk_vec3 sb = mk_v3_sub(mk_v3_sub(mk_v3_abs(tb), hb), mk_mat3_tmul_v3(ar, ha));
    mk_real best = sa.x, s;
    int axis = 0;
    if (sa.y > best) best = sa.y, axis = 1;
    if (sa.z > best) best = sa.z, axis = 2;
    if (sb.x > best) best = sb.x, axis = 3;
    if (sb.y > best) best = sb.y, axis = 4;
    if (sb.z > best) best = sb.z, axis = 5;
    *of_b = axis >= 3;
    switch (axis) {
    case 0: *n = mk_v3(p->t.x >= 0 ? 1 : -1, 0, 0); break;
    case 1: *n = mk_v3(0, p->t.y >= 0 ? 1 : -1, 0); break;
    case 2: *n = mk_v3(0, 0, p->t.z >= 0 ? 1 : -1); break;
    default:
        s = (axis == 3 ? tb.x : axis == 4 ? tb.y : tb.z) >= 0 ? 1 : -1;
        *n = mk_v3_scale(axis == 3 ? p->r.c0 : axis == 4 ? p->r.c1 : p->r.c2, s);
    }
    return best;
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
 * separates tries that axis first and skips the nine edge axes when it
 * holds: corner-face pairs, most separated pairs, pay about half as much.
 * Separated pairs whose closest features are a corner and an edge (or two
 * corners) are certified by the corner and its clamp (corner_witnesses).
 * Otherwise (ties at rounding level) returns 0 and GJK, then EPA if the cores
 * overlap, answers. */
static int box_box_sat(const mk_pair *p, answer *ans)
{
    mk_sat_options o = mk_sat_defaults();
    mk_sat_result s;
    mk_vec3 ha = p->a->u.half_extents, hb = p->b->u.half_extents, n, pa, pb;
    mk_real tol = 64 * MK_REAL_EPSILON * (mk_v3_max_abs(ha) + mk_v3_max_abs(hb) + mk_v3_max_abs(p->t)), d;
    int ok = 0, of_b;
    d = box_face_axes(p, &n, &of_b);
    /* B's corner under A's face, or A's under B's: the other side almost never
     * holds off parallel faces, which SAT's path below still tries. */
    if (!(d > 0) || !(of_b ? face_witness_on_b : face_witness_on_a)(p, d, n, tol, &pa, &pb)) {
        mk_sat_box_box(ha, hb, &p->r, p->t, &o, &s);
        d = s.best;
        n = s.normal;
        if (!(d > -MK_REAL_MAX)) return 0; /* no axis at all (cannot happen for valid boxes) */
        if (s.kind == MK_SAT_EDGES) { /* the closest points of the two supporting edges */
            mk_vec3 a0, a1, b0, b1;
            mk_real u, v;
            box_support_edge(ha, n, &a0, &a1);
            box_support_edge(hb, mk_mat3_tmul_v3(p->r, mk_v3_neg(n)), &b0, &b1);
            b0 = mk_v3_add(mk_mat3_mul_v3(p->r, b0), p->t);
            b1 = mk_v3_add(mk_mat3_mul_v3(p->r, b1), p->t);
            mk_segment_segment(a0, a1, b0, b1, &u, &v);
            pa = mk_v3_lerp(a0, a1, u);
            pb = mk_v3_lerp(b0, b1, v);
            ok = mk_v3_max_abs(mk_v3_sub(mk_v3_sub(pb, pa), mk_v3_scale(n, d))) <= tol;
        }
        /* A face axis, or an edge axis that is a face normal too (parallel boxes). */
        if (!ok && !face_witnesses(p, d, n, tol, &pa, &pb)) {
            /* Apart, but no feature pair realises SAT's bound: a corner may. */
            if (!(d > 0) || !corner_witnesses(p, n, tol, &d, &pa, &pb)) return 0;
            n = mk_v3_scale(mk_v3_sub(pb, pa), 1 / d);
        }
    }
    witnesses(pa, pb, d, n, &pa, &pb);
    ans->hit = grow_core(pa, pb, d, n, p);
    ans->iterations = 15;
    ans->method = MK_METHOD_SAT;
    ans->state = MK_SOLVE_CONVERGED;
    return 1;
}
#endif

/* ---- composition ---------------------------------------------------------- */

/* Runs a path in the frame of its first shape: A's rotation goes to *ra for
 * the way back (the identity for capsule paths, which run world-aligned about
 * A's centre). Only what the path uses is computed: a sphere's rotation never
 * matters, a capsule is its axis. */
MK_ALWAYS_INLINE mk_status run(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb, path pth,
                     mk_gjk_cache *cache, mk_mat3 *ra, answer *ans)
{
    mk_pair p;
    mk_vec3 c = mk_v3_sub(xb.p, xa.p);
    ans->iterations = 0;
    ans->method = MK_METHOD_CLOSED_FORM;
    ans->state = MK_SOLVE_CONVERGED;
    switch (pth) {
    case PATH_CAPSULE_SPHERE:
        *ra = mk_mat3_identity();
        ans->hit = mk_closest_capsule_sphere(a->u.capsule.half_height, mk_axis_of(xa.q), a->radius, c, b->radius);
        return MK_OK;
    case PATH_CAPSULES:
        *ra = mk_mat3_identity();
        ans->hit = mk_closest_capsule_capsule(a->u.capsule.half_height, mk_axis_of(xa.q), a->radius, c, mk_axis_of(xb.q),
                                              b->u.capsule.half_height, b->radius);
        return MK_OK;
    case PATH_BOX_SPHERE:
        *ra = mk_rotation_of(xa.q);
        ans->hit = mk_closest_box_sphere(a->u.half_extents, a->radius, mk_mat3_tmul_v3(*ra, c), b->radius);
        return MK_OK;
    default: break;
    }
    *ra = mk_rotation_of(xa.q);
    p = mk_pair_in(a, *ra, xa.p, b, xb);
    switch (pth) {
    case PATH_PLANE: ans->hit = mk_closest_shape_plane(&p); return MK_OK;
    case PATH_BOX_BOX: /* pairs SAT cannot certify (or no SAT in this build) go on to GJK */
#ifndef MK_WITHOUT_SAT
        if (box_box_sat(&p, ans)) return MK_OK;
#endif
        /* fall through */
    case PATH_GJK:
#ifdef MK_WITHOUT_GJK
        (void)cache;
        return MK_ERR_UNSUPPORTED;
#else
        return iterative(&p, cache, ans);
#endif
    default: return MK_ERR_UNSUPPORTED;
    }
}

/* Sphere pairs never build a frame: centres and radii only. */
static void spheres(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb, mk_distance_result *r)
{
    mk_vec3 d = mk_v3_sub(xb.p, xa.p);
    mk_real l = mk_v3_len(d);
    /* Concentric spheres: every direction is a shortest way out; take +z. */
    mk_vec3 n = l > 0 ? mk_v3_scale(d, 1 / l) : mk_v3(0, 0, 1);
    r->distance = l - a->radius - b->radius;
    r->normal = n;
    r->point_a = mk_v3_mad(xa.p, a->radius, n);
    r->point_b = mk_v3_mad(xb.p, -b->radius, n);
    r->iterations = 0;
    r->method = MK_METHOD_CLOSED_FORM;
    r->state = MK_SOLVE_CONVERGED;
}

/* b is rebuilt from a, so point_b = point_a + distance * normal holds in the
 * world frame to one rounding, and one rotation is saved. */
static void to_world(const answer *ans, mk_mat3 ra, mk_vec3 pa, int flip, mk_distance_result *r)
{
    mk_vec3 n = mk_mat3_mul_v3(ra, ans->hit.normal), a = mk_v3_add(mk_mat3_mul_v3(ra, ans->hit.a), pa);
    mk_vec3 b = mk_v3_mad(a, ans->hit.distance, n);
    r->distance = ans->hit.distance;
    r->normal = flip ? mk_v3_neg(n) : n;
    r->point_a = flip ? b : a;
    r->point_b = flip ? a : b;
    r->iterations = ans->iterations;
    r->method = ans->method;
    r->state = ans->state;
}

mk_status mk_distance(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb, mk_gjk_cache *cache,
                      mk_distance_result *out)
{
    mk_status st = check_inputs(a, xa, b, xb, out);
    route rt;
    answer ans;
    mk_mat3 ra;
    if (st != MK_OK) return st;
    rt = routes[a->type][b->type];
    if (rt.path == PATH_SPHERES) {
        spheres(a, xa, b, xb, out);
        return MK_OK;
    }
    if (rt.swap) mk_swap_pair_(&a, &xa, &b, &xb); /* run as (B, A), flip on the way out */
    st = run(a, xa, b, xb, (path)rt.path, cache, &ra, &ans);
    if (st != MK_OK) return st;
    to_world(&ans, ra, xa.p, rt.swap, out);
    return MK_OK;
}

mk_status mk_overlap(const mk_shape *a, mk_transform xa, const mk_shape *b, mk_transform xb, mk_gjk_cache *cache,
                     int *overlapping)
{
    mk_status st = check_inputs(a, xa, b, xb, overlapping);
    route rt;
    answer ans;
    mk_mat3 ra;
    if (st != MK_OK) return st;
    rt = routes[a->type][b->type];
    if (rt.path == PATH_SPHERES) {
        mk_vec3 d = mk_v3_sub(xb.p, xa.p);
        mk_real r = a->radius + b->radius;
        *overlapping = mk_v3_len2(d) <= r * r;
        return MK_OK;
    }
#ifndef MK_WITHOUT_GJK
    if (rt.path == PATH_GJK || rt.path == PATH_BOX_BOX) {
        mk_pair p;
        mk_gjk_result g;
        p = mk_pair_make(a, xa, b, xb);
        mk_gjk(&p, cache, 1, a->radius + b->radius, &g);
        if (cache) mk_gjk_cache_store(&g.s, g.normal, cache);
        *overlapping = g.overlap;
        return MK_OK;
    }
#endif
    st = rt.swap ? run(b, xb, a, xa, (path)rt.path, cache, &ra, &ans) : run(a, xa, b, xb, (path)rt.path, cache, &ra, &ans);
    if (st != MK_OK) return st;
    *overlapping = ans.hit.distance <= 0;
    return MK_OK;
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
    mk_status st = check_inputs(a, xa, b, xb, out);
    mk_pair p;
    mk_vec3 va, vb;
    int ia = -1, ib;
    if (st != MK_OK) return st;
    if (!mk_core_is_polytope(a) || !mk_core_is_polytope(b)) return MK_ERR_UNSUPPORTED;
    p = mk_pair_make(a, xa, b, xb);
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

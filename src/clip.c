/* clip.c: support features, Sutherland-Hodgman clipping with feature
 * bookkeeping, and manifold reduction (see manifold_internal.h). */
#include "manifold_internal.h"

#define V(i) MK_FEATURE(MK_FEATURE_VERTEX, i)
#define E(i) MK_FEATURE(MK_FEATURE_EDGE, i)
#define F(i) MK_FEATURE(MK_FEATURE_FACE, i)

/* Cylinder and cone feature numbering (minko/manifold.h). */
#define RIM_SAMPLES 8
#define CONE_APEX 16
#define SIDE_FACE 2
#define CHORD_EDGE(cap, j) (2 + RIM_SAMPLES * (cap) + (j))

void mk_mf_add(mk_mf *m, mk_vec3 pa, mk_real depth, mk_feature fa, mk_feature fb)
{
    if (!(depth >= -m->margin) || m->count >= MK_MF_MAX) return;
    m->p[m->count].pa = pa;
    m->p[m->count].depth = depth;
    m->p[m->count].features = MK_FEATURE_PAIR(fa, fb);
    m->count++;
}

/* ---- support features ---------------------------------------------------- */

mk_feature mk_box_edge(int ci, int cj)
{
    int axis = (ci ^ cj) == 1 ? 0 : (ci ^ cj) == 2 ? 1 : 2;
    int lo = axis == 0 ? 1 : 0, hi = axis == 2 ? 1 : 2; /* the other two axes, in order */
    return E(4 * axis + ((ci >> lo) & 1) + 2 * ((ci >> hi) & 1));
}

/* The face tables (manifold_internal.h): each edge is mk_box_edge of its two corners. */
const unsigned char mk_box_face_corner_[6][4] = {{4, 6, 2, 0}, {1, 3, 7, 5}, {1, 5, 4, 0}, {2, 6, 7, 3}, {2, 3, 1, 0}, {4, 5, 7, 6}};
const unsigned char mk_box_face_edge_[6][4] = {{6, 10, 4, 8}, {5, 11, 7, 9}, {9, 2, 8, 0}, {10, 3, 11, 1}, {1, 5, 0, 4}, {2, 7, 3, 6}};

void mk_box_face(const mk_shape *s, int axis, int positive, mk_feat *f)
{
    int face = 2 * axis + positive, i;
    mk_vec3 h = s->u.half_extents;
    for (i = 0; i < 4; ++i) {
        int c = mk_box_face_corner_[face][i];
        f->v[i] = mk_v3(c & 1 ? h.x : -h.x, c & 2 ? h.y : -h.y, c & 4 ? h.z : -h.z);
        f->vid[i] = V(c);
        f->eid[i] = E(mk_box_face_edge_[face][i]);
    }
    f->count = 4;
    f->exact = 1;
    f->id = F(face);
    f->normal = mk_v3_zero();
    if (axis == 0) f->normal.x = positive ? 1 : -1;
    else if (axis == 1) f->normal.y = positive ? 1 : -1;
    else f->normal.z = positive ? 1 : -1;
}

/* Cap k (0: z = -h, 1: z = +h) of a cylinder or cone of radius r as a polygon
 * of RIM_SAMPLES fixed rim points. When the cap is tilted against d, the
 * exact rim support point replaces the nearest sample (keeping its id) if it
 * is within about 0.8 degrees of it, else it is inserted on its chord: the
 * deepest point is then exact, and the ids of a cap lying flat never depend
 * on round-off. */
static void cap_polygon(mk_real r, mk_real z, int cap, mk_vec3 d, mk_feat *f)
{
    static const mk_real c8[RIM_SAMPLES] = {1, MK_REAL(0.70710678118654752), 0, MK_REAL(-0.70710678118654752), -1,
                                           MK_REAL(-0.70710678118654752), 0, MK_REAL(0.70710678118654752)};
#define SIN8(j) c8[((j) + 6) % RIM_SAMPLES] /* sin(45 j) = cos(45 (j - 2)) */
    mk_real sigma = mk_sqrt_(d.x * d.x + d.y * d.y);
    int i, n = 0, replace = -1, chord = -1; /* chord j runs from sample j to sample j + 1 */
    mk_vec3 x = mk_v3_zero();
    if (sigma > MK_MF_SIN_TOL) {
        mk_real ux = d.x / sigma, uy = d.y / sigma, best = -2;
        int near = 0;
        x = mk_v3(r * ux, r * uy, z);
        for (i = 0; i < RIM_SAMPLES; ++i) {
            mk_real dp = ux * c8[i] + uy * SIN8(i);
            if (dp > best) { best = dp; near = i; }
        }
        if (best >= 1 - MK_REAL(1e-4)) replace = near;
        else chord = c8[near] * uy - SIN8(near) * ux >= 0 ? near : (near + RIM_SAMPLES - 1) % RIM_SAMPLES;
    }
    for (i = 0; i < RIM_SAMPLES; ++i) {
        /* Counter-clockwise around the outward normal: increasing angle on the top cap, decreasing below. */
        int j = cap ? i : (RIM_SAMPLES - i) % RIM_SAMPLES;
        int leaving = cap ? j : (j + RIM_SAMPLES - 1) % RIM_SAMPLES; /* chord from this vertex to the next */
        f->v[n] = j == replace ? x : mk_v3(r * c8[j], r * SIN8(j), z);
        f->vid[n] = V(RIM_SAMPLES * cap + j);
        f->eid[n] = E(CHORD_EDGE(cap, leaving));
        n++;
        if (leaving == chord) { /* the piece of the chord after x is named by the rim */
            f->v[n] = x;
            f->vid[n] = E(cap);
            f->eid[n] = E(cap);
            n++;
        }
    }
#undef SIN8
    f->count = n;
    f->exact = 0;
    f->id = F(cap);
    f->normal = mk_v3(0, 0, cap ? 1 : -1);
}

int mk_hull_edge_id(const mk_hull *h, int e) { return e < h->edges[e].twin ? e : h->edges[e].twin; }

/* The face around hull vertex v best aligned with d. The support face is not
 * simply the face best aligned over the whole hull (a far face of a sliver
 * can beat every face at the support vertex); the deepest point is v. */
static int hull_face_at(const mk_hull *h, int v, mk_vec3 d)
{
    int e0 = h->vertex_edge[v], e = e0, best = h->edges[e0].face;
    mk_real best_dot = -MK_REAL_MAX;
    do {
        int face = h->edges[e].face;
        mk_real dd = mk_v3_dot(h->planes[face].normal, d);
        if (dd > best_dot) {
            best_dot = dd;
            best = face;
        }
        e = h->edges[h->edges[e].twin].next;
    } while (e != e0);
    return best;
}

/* Face `face` of a hull as a polygon, walked from vertex `start` (when it is
 * on the face). A face with more than MK_FEAT_MAX vertices keeps every k-th
 * one from `start` on, so a support vertex passed as start survives; a
 * chord is named by the first hull edge it spans. */
void mk_hull_face(const mk_hull *h, int face, int start, mk_feat *f)
{
    int e0 = h->face_edge[face], e = e0, count = 0, step, i = 0, n = 0;
    do {
        count++;
        if (h->edges[e].origin == start) e0 = e;
        e = h->edges[e].next;
    } while (e != h->face_edge[face]);
    step = (count + MK_FEAT_MAX - 1) / MK_FEAT_MAX;
    e = e0;
    do {
        if (i++ % step == 0) {
            f->v[n] = h->vertices[h->edges[e].origin];
            f->vid[n] = V(h->edges[e].origin);
            f->eid[n] = E(mk_hull_edge_id(h, e));
            n++;
        }
        e = h->edges[e].next;
    } while (e != e0);
    f->count = n;
    f->exact = 1;
    f->id = F(face);
    f->normal = h->planes[face].normal;
}

/* The support face of a hull: around the support vertex, best aligned with d. */
static void hull_face(const mk_hull *h, mk_vec3 d, mk_feat *f)
{
    int v = mk_hull_support_index(h, d, -1);
    mk_hull_face(h, hull_face_at(h, v, d), v, f);
}

static void segment_feat(mk_vec3 p0, mk_feature f0, mk_vec3 p1, mk_feature f1, mk_feature e, mk_feat *f)
{
    f->count = 2;
    f->exact = 1;
    f->id = e;
    f->normal = mk_v3_zero();
    f->v[0] = p0;
    f->v[1] = p1;
    f->vid[0] = f0;
    f->vid[1] = f1;
    f->eid[0] = f->eid[1] = e;
}

static void point_feat(mk_vec3 p, mk_feature id, mk_feat *f)
{
    f->count = 1;
    f->exact = 1;
    f->id = id;
    f->normal = mk_v3_zero();
    f->v[0] = p;
    f->vid[0] = id;
    f->eid[0] = id;
}

void mk_support_feature(const mk_shape *s, mk_vec3 d, mk_feat *f)
{
    switch (s->type) {
    case MK_SHAPE_BOX: {
        mk_vec3 a = mk_v3_abs(d);
        int axis = (a.x >= a.y && a.x >= a.z) ? 0 : (a.y >= a.z ? 1 : 2); /* ties go to the lower axis */
        mk_box_face(s, axis, (axis == 0 ? d.x : axis == 1 ? d.y : d.z) >= 0, f);
        break;
    }
    case MK_SHAPE_CAPSULE:
        segment_feat(mk_v3(0, 0, -s->u.capsule.half_height), V(0), mk_v3(0, 0, s->u.capsule.half_height), V(1), E(0), f);
        break;
    case MK_SHAPE_CYLINDER: {
        mk_real r = s->u.cylinder.radius, h = s->u.cylinder.half_height, sigma = mk_sqrt_(d.x * d.x + d.y * d.y);
        if (mk_fabs_(d.z) >= sigma) {
            cap_polygon(r, d.z >= 0 ? h : -h, d.z >= 0, d, f);
        } else {
            mk_real cx = r * d.x / sigma, cy = r * d.y / sigma;
            segment_feat(mk_v3(cx, cy, -h), E(0), mk_v3(cx, cy, h), E(1), F(SIDE_FACE), f);
        }
        break;
    }
    case MK_SHAPE_CONE: {
        mk_real r = s->u.cone.radius, h = s->u.cone.half_height, sigma = mk_sqrt_(d.x * d.x + d.y * d.y);
        /* Base cap (normal -z) against the side line at the angle of d (normal ~ (2h u, r)). */
        mk_real side = (2 * h * sigma + r * d.z) / mk_sqrt_(4 * h * h + r * r);
        if (-d.z >= side) {
            cap_polygon(r, -h, 0, d, f);
        } else if (sigma > 0) {
            segment_feat(mk_v3(0, 0, h), V(CONE_APEX), mk_v3(r * d.x / sigma, r * d.y / sigma, -h), E(0), F(SIDE_FACE), f);
        } else {
            point_feat(mk_v3(0, 0, h), V(CONE_APEX), f);
        }
        break;
    }
    case MK_SHAPE_HULL:
        hull_face(s->u.hull, d, f);
        break;
    case MK_SHAPE_SPHERE:
    default:
        point_feat(mk_v3_zero(), V(0), f);
        break;
    }
}

void mk_feat_transform(mk_feat *f, const mk_pair *p)
{
    int i;
    for (i = 0; i < f->count; ++i) f->v[i] = mk_v3_add(mk_mat3_mul_v3(p->r, f->v[i]), p->t);
    f->normal = mk_mat3_mul_v3(p->r, f->normal);
}

/* ---- feature at a point --------------------------------------------------- */

mk_feature mk_feature_at(const mk_shape *s, mk_vec3 p, mk_vec3 n)
{
    switch (s->type) {
    case MK_SHAPE_BOX: {
        mk_vec3 h = s->u.half_extents;
        mk_real tol = mk_v3_max_abs(h) * MK_REAL_EPSILON * 64;
        int at[3], count, i, corner = (p.x > 0) | (p.y > 0) << 1 | (p.z > 0) << 2;
        at[0] = mk_fabs_(p.x) >= h.x - tol;
        at[1] = mk_fabs_(p.y) >= h.y - tol;
        at[2] = mk_fabs_(p.z) >= h.z - tol;
        count = at[0] + at[1] + at[2];
        if (count == 3) return V(corner);
        if (count == 2) {
            for (i = 0; at[i]; ++i) continue;
            return mk_box_edge(corner & ~(1 << i), corner | (1 << i));
        }
        if (count == 1) {
            for (i = 0; !at[i]; ++i) continue;
            return F(2 * i + ((corner >> i) & 1));
        }
        {
            mk_feat f; /* inside the core: the face the normal leaves through */
            mk_support_feature(s, n, &f);
            return f.id;
        }
    }
    case MK_SHAPE_CAPSULE: {
        mk_real h = s->u.capsule.half_height, tol = h * MK_REAL_EPSILON * 64;
        return p.z >= h - tol ? V(1) : p.z <= -h + tol ? V(0) : E(0);
    }
    case MK_SHAPE_CYLINDER:
    case MK_SHAPE_CONE: {
        int cyl = s->type == MK_SHAPE_CYLINDER;
        mk_real r = cyl ? s->u.cylinder.radius : s->u.cone.radius, h = cyl ? s->u.cylinder.half_height : s->u.cone.half_height;
        mk_real tol = mk_max(r, h) * MK_REAL_EPSILON * 64, rho = mk_sqrt_(p.x * p.x + p.y * p.y);
        int cap = p.z >= h - tol ? 1 : p.z <= -h + tol ? 0 : -1, rim;
        if (!cyl) {
            if (cap == 1) return V(CONE_APEX);
            rim = rho >= r * (h - p.z) / (2 * h) - tol; /* on the lateral surface */
        } else {
            rim = rho >= r - tol;
        }
        if (cap >= 0 && rim) return E(cap);
        return cap >= 0 ? F(cap) : F(SIDE_FACE);
    }
    case MK_SHAPE_HULL: {
        /* The support vertex along n, an edge leaving it, or its face best aligned with n. */
        const mk_hull *h = s->u.hull;
        int v = mk_hull_support_index(h, n, -1), e0 = h->vertex_edge[v], e = e0;
        mk_real tol = h->outer_radius * MK_REAL_EPSILON * 256;
        mk_vec3 pv = h->vertices[v];
        if (mk_v3_dist(p, pv) <= tol) return V(v);
        do {
            mk_vec3 u = mk_v3_sub(h->vertices[h->edges[h->edges[e].twin].origin], pv);
            mk_real t = mk_v3_dot(mk_v3_sub(p, pv), u) / mk_v3_len2(u);
            if (t >= 0 && t <= 1 && mk_v3_dist(mk_v3_mad(pv, t, u), p) <= tol) return E(mk_hull_edge_id(h, e));
            e = h->edges[h->edges[e].twin].next;
        } while (e != e0);
        return F(hull_face_at(h, v, n));
    }
    case MK_SHAPE_SPHERE:
    default:
        return V(0);
    }
}

/* ---- clipping --------------------------------------------------------------- */

/* A side plane of the reference feature: x . n <= d keeps x. The normal of
 * a polygon's side plane is not normalised (only signs and ratios of x . n
 * - d are used), which saves a square root and a division per side; its
 * length is then the side's length wherever the slop applies. */
typedef struct side_plane { mk_vec3 n; mk_real d, slop; mk_feature id; } side_plane;

/* An incident vertex up to m->slop of the reference side's length (of the
 * segment's, for a segment) outside a side plane is kept as it is instead
 * of being replaced by the crossings of its two edges with the plane.
 * Equal boxes stacked square have incident corners exactly on the side
 * planes; without a slop round-off decides, frame by frame, whether a
 * corner is kept (vertex against face) or clipped into two crossing points
 * (edge against edge), and the feature IDs flicker. MK_MANIFOLD_STABLE_IDS
 * takes MK_MF_SLOP_IDS, 0.35 % of the side (0.5 % of a square's half
 * diagonal): the IDs change only when the misalignment really crosses it,
 * and equal boxes rocking by 0.1 degree keep them. MK_MANIFOLD_BEST_FACE
 * takes MK_MF_SLOP_EXACT, round-off only: a corner really outside is
 * clipped, as Bullet's box-box clips it; the wider strip kept corners up
 * to 1.7 mm outside the face, and Bullet's solver, fed those points, let
 * demos/bullet_scenes' 10-box tower drift twice as far as native.
 * Crossings are always computed on the exact planes, so clipped regions
 * stay exact. Only when the clip direction is the face's own normal,
 * though: along an axis tilted against the face, a point outside it would
 * be measured deeper than any real point, and the deepest depth must stay
 * exact. Nor when rounded cores are apart: a vertex beside the face is then
 * farther from it than its height over the plane, and rounded shapes
 * resting apart by their radii (Bullet's margins) must get exact depths. */
static int side_planes(const mk_feat *ref, mk_vec3 n, mk_real slop, side_plane *sp)
{
    int i, count = ref->count;
    mk_vec3 c = mk_v3_zero();
    if (!(count == 2 || mk_fabs_(mk_v3_dot(n, ref->normal)) >= 1 - 64 * MK_REAL_EPSILON)) slop = 0;
    if (count == 2) {
        /* The two end planes of a segment, perpendicular to it within the contact plane. */
        mk_vec3 u = mk_v3_sub(ref->v[1], ref->v[0]);
        mk_real width = slop * mk_v3_len(u);
        u = mk_v3_normalize(mk_v3_mad(u, -mk_v3_dot(u, n), n));
        sp[0].n = mk_v3_neg(u);
        sp[0].d = -mk_v3_dot(u, ref->v[0]);
        sp[0].id = ref->vid[0];
        sp[1].n = u;
        sp[1].d = mk_v3_dot(u, ref->v[1]);
        sp[1].id = ref->vid[1];
        sp[0].slop = sp[1].slop = width;
        return 2;
    }
    /* The prism swept by the polygon along n (not along its own normal: see
     * mk_mf_clip). Where the slop applies n is the face normal, so the side
     * normal (b - a) x n is as long as the side: the strip is c |b - a|^2. */
    for (i = 0; i < count; ++i) c = mk_v3_add(c, ref->v[i]);
    c = mk_v3_scale(c, 1 / (mk_real)count);
    for (i = 0; i < count; ++i) {
        mk_vec3 a = ref->v[i], e = mk_v3_sub(ref->v[i + 1 < count ? i + 1 : 0], a);
        mk_vec3 sn = mk_v3_cross(e, n);
        if (mk_v3_dot(sn, mk_v3_sub(c, a)) > 0) sn = mk_v3_neg(sn); /* outward, whatever the winding */
        sp[i].n = sn;
        sp[i].d = mk_v3_dot(sn, a);
        sp[i].id = ref->eid[i];
        sp[i].slop = slop * mk_v3_len2(e);
    }
    return count;
}

/* Appends the candidate for incident core point p with features (fref,
 * finc). s is the core separation of p from the reference along n: to the
 * face plane along the ray through p (a polygon), or from the reference
 * segment's line (a segment, which may be tilted against n by the
 * tolerance). */
static void emit(mk_mf *m, const mk_feat *ref, int ref_is_a, mk_vec3 p, mk_feature fref, mk_feature finc, mk_real ra, mk_real rb,
                 mk_real inv_cos)
{
    mk_vec3 n = m->normal, o = ref->v[0];
    mk_real s;
    if (ref->count == 2) {
        mk_vec3 u = mk_v3_sub(ref->v[1], ref->v[0]);
        mk_real uu = mk_v3_len2(u);
        if (uu > 0) o = mk_v3_mad(o, mk_v3_dot(mk_v3_sub(p, o), u) / uu, u);
        s = mk_v3_dot(mk_v3_sub(p, o), n);
    } else {
        s = mk_v3_dot(mk_v3_sub(p, o), ref->normal) * inv_cos;
    }
    if (ref_is_a) {
        mk_mf_add(m, mk_v3_mad(p, ra - s, n), ra + rb - s, fref, finc);
    } else {
        s = -s;
        mk_mf_add(m, mk_v3_mad(p, ra, n), ra + rb - s, finc, fref);
    }
}

/* Feature of the point where the incident edge tagged `tag` meets side plane q. */
typedef struct clip_vert { mk_vec3 p; mk_feature fref, finc; int ref_edge; mk_feature edge; } clip_vert;

static void crossing(const mk_feat *ref, const mk_feat *inc, int q, const side_plane *sp, const clip_vert *from, clip_vert *x)
{
    if (from->ref_edge < 0) {
        x->fref = sp[q].id;
        x->finc = from->edge;
    } else {
        /* Along reference edge p and now crossing plane q: the reference corner between them. */
        int pe = from->ref_edge, n = ref->count;
        x->fref = pe == (q + n - 1) % n ? ref->vid[q] : pe == (q + 1) % n ? ref->vid[(q + 1) % n] : ref->id;
        x->finc = inc->id;
    }
}

static int clip_polygon(const mk_feat *ref, const mk_feat *inc, const side_plane *sp, int nsp, clip_vert *out)
{
    clip_vert buf[2][MK_MF_MAX];
    int n = inc->count, q, i, cur = 0;
    for (i = 0; i < n; ++i) {
        buf[0][i].p = inc->v[i];
        buf[0][i].fref = ref->id;
        buf[0][i].finc = inc->vid[i];
        buf[0][i].ref_edge = -1; /* the edge leaving this vertex is incident edge eid[i] */
        buf[0][i].edge = inc->eid[i];
    }
    for (q = 0; q < nsp && n > 0; ++q) {
        clip_vert *src = buf[cur], *dst = buf[cur ^ 1];
        mk_real dist[MK_MF_MAX];
        int m = 0, out_count = 0;
        for (i = 0; i < n; ++i) {
            dist[i] = mk_v3_dot(sp[q].n, src[i].p) - sp[q].d;
            out_count += !(dist[i] <= sp[q].slop);
        }
        if (out_count == 0) continue; /* wholly inside this plane: nothing changes */
        for (i = 0; i < n; ++i) {
            int j = i + 1 < n ? i + 1 : 0;
            const clip_vert *a = &src[i], *b = &src[j];
            mk_real da = dist[i], db = dist[j];
            int ina = da <= sp[q].slop, inb = db <= sp[q].slop;
            if (ina) dst[m++] = *a;
            if (ina == inb) continue;
            if ((ina ? da : db) > 0) {
                /* The inside end lies in the slop strip and stands for the crossing;
                 * when leaving, the polygon now runs along plane q from it. */
                if (ina) {
                    dst[m - 1].ref_edge = q;
                    dst[m - 1].edge = sp[q].id;
                }
                continue;
            }
            {
                clip_vert *x = &dst[m++];
                x->p = mk_v3_lerp(a->p, b->p, da / (da - db));
                crossing(ref, inc, q, sp, a, x);
                if (ina) { /* leaving: the next edge runs along plane q */
                    x->ref_edge = q;
                    x->edge = sp[q].id;
                } else { /* entering: the rest of a's edge */
                    x->ref_edge = a->ref_edge;
                    x->edge = a->edge;
                }
            }
        }
        n = m;
        cur ^= 1;
    }
    for (i = 0; i < n; ++i) out[i] = buf[cur][i];
    return n;
}

static int clip_segment(const mk_feat *ref, const mk_feat *inc, const side_plane *sp, int nsp, clip_vert *out)
{
    int q, k, n = 2;
    out[0].p = inc->v[0];
    out[1].p = inc->v[1];
    out[0].fref = out[1].fref = ref->id;
    out[0].finc = inc->vid[0];
    out[1].finc = inc->vid[1];
    for (q = 0; q < nsp; ++q) {
        mk_real d0 = mk_v3_dot(sp[q].n, out[0].p) - sp[q].d, d1 = n == 2 ? mk_v3_dot(sp[q].n, out[1].p) - sp[q].d : d0;
        int in0 = d0 <= sp[q].slop, in1 = d1 <= sp[q].slop;
        if (!in0 && !in1) return 0;
        if (in0 && in1) continue;
        k = in0 ? 1 : 0; /* the end outside */
        if ((in0 ? d0 : d1) > 0) {
            /* The inside end lies in the slop strip: it is all that is left. */
            if (k == 0) out[0] = out[1];
            n = 1;
            continue;
        }
        out[k].p = mk_v3_lerp(out[0].p, out[1].p, d0 / (d0 - d1));
        out[k].fref = sp[q].id;
        out[k].finc = inc->eid[0];
    }
    return n;
}

/* The clip prism and the depths follow the contact normal n rather than the
 * reference face's own normal. When the two differ (n is within the face
 * tolerance, but the closest points lie on the face's boundary), the witness
 * pair then lies on the prism's boundary with its exact separation, and the
 * separation along n is linear along every incident edge and never below the
 * true one, so the deepest clipped point is exactly the deepest point. */
void mk_mf_clip(mk_mf *m, const mk_feat *ref, int ref_is_a, const mk_feat *inc, mk_real ra, mk_real rb)
{
    side_plane sp[MK_FEAT_MAX];
    clip_vert out[MK_MF_MAX];
    int nsp = side_planes(ref, m->normal, m->cores_apart && ra + rb > 0 ? 0 : m->slop, sp), n, i;
    mk_real inv_cos = ref->count > 2 ? 1 / mk_v3_dot(m->normal, ref->normal) : 0;
    if (inc->count == 1) {
        for (i = 0; i < nsp; ++i)
            if (mk_v3_dot(sp[i].n, inc->v[0]) > sp[i].d) return;
        emit(m, ref, ref_is_a, inc->v[0], ref->id, inc->vid[0], ra, rb, inv_cos);
        return;
    }
    n = inc->count == 2 ? clip_segment(ref, inc, sp, nsp, out) : clip_polygon(ref, inc, sp, nsp, out);
    for (i = 0; i < n; ++i) emit(m, ref, ref_is_a, out[i].p, out[i].fref, out[i].finc, ra, rb, inv_cos);
}

/* ---- manifold from closest points ------------------------------------------ */

/* The segment of f that lies farthest along d and is perpendicular to d
 * within the tolerance, if there is one. */
static int support_segment(const mk_feat *f, mk_vec3 d, mk_feat *seg)
{
    int i;
    if (f->count == 2) {
        *seg = *f;
    } else if (f->count > 2) {
        mk_real best = -MK_REAL_MAX;
        int k = 0;
        for (i = 0; i < f->count; ++i) {
            mk_real v = mk_v3_dot(d, f->v[i]) + mk_v3_dot(d, f->v[(i + 1) % f->count]);
            if (v > best) { best = v; k = i; }
        }
        segment_feat(f->v[k], f->vid[k], f->v[(k + 1) % f->count], f->vid[(k + 1) % f->count], f->eid[k], seg);
    } else {
        return 0;
    }
    {
        mk_vec3 u = mk_v3_sub(seg->v[1], seg->v[0]);
        return mk_fabs_(mk_v3_dot(u, d)) <= MK_MF_SIN_TOL * mk_v3_len(u);
    }
}

static int parallel(const mk_feat *sa, const mk_feat *sb)
{
    mk_vec3 ua = mk_v3_sub(sa->v[1], sa->v[0]), ub = mk_v3_sub(sb->v[1], sb->v[0]);
    return mk_v3_len(mk_v3_cross(ua, ub)) <= MK_MF_SIN_TOL * mk_v3_len(ua) * mk_v3_len(ub);
}

/* Which face to clip against when both face the normal within the
 * tolerance: a true face before a sampled cap, else the better aligned one,
 * which is the exact minimum axis. Returns 1 for A's face, 0 for B's. */
static int pick_a(const mk_feat *fa, const mk_feat *fb, mk_vec3 n)
{
    if (fa->exact != fb->exact) return fa->exact;
    return -mk_v3_dot(fb->normal, n) <= mk_v3_dot(fa->normal, n);
}

void mk_mf_from_closest(mk_mf *m, const mk_pair *p, mk_manifold_cache *cache, mk_vec3 n, mk_vec3 ca, mk_vec3 cb,
                        mk_real dist)
{
    const mk_shape *a = p->a, *b = p->b;
    mk_feat fa, fb, sa, sb;
    mk_real ra = a->radius, rb = b->radius, cos_tol = mk_sqrt_(1 - MK_MF_SIN_TOL * MK_MF_SIN_TOL);
    int a_ok, b_ok, keep;
    m->count = 0;
    m->cores_apart = dist > 0;
    mk_support_feature(a, n, &fa);
    mk_support_feature(b, mk_mat3_tmul_v3(p->r, mk_v3_neg(n)), &fb);
    mk_feat_transform(&fb, p);
    a_ok = fa.count > 2 && mk_v3_dot(fa.normal, n) >= cos_tol;
    b_ok = fb.count > 2 && -mk_v3_dot(fb.normal, n) >= cos_tol;
    /* Hysteresis: two polytope faces that face each other, one of which was
     * last frame's reference. On a rocking stack the exact minimum axis swaps
     * between the two faces every few frames; each swap would rename every
     * point and tilt the normal, so while last frame's face still faces the
     * normal within the tolerance the pair keeps it and takes its normal.
     * That costs exactness (depth along a face tilted by up to the tolerance
     * from the exact axis) on warm frames only; a cold call, or a new face,
     * clips against the exact minimum axis. */
    keep = 0;
    if (cache && fa.count > 2 && fb.count > 2 && fa.exact && fb.exact) {
        if (a_ok && cache->reference == 1 && cache->face == fa.id) keep = 1;
        if (b_ok && cache->reference == 2 && cache->face == fb.id) keep = 2;
    }
    if (keep) {
        a_ok = keep == 1;
        b_ok = keep == 2;
    } else if (a_ok && b_ok) {
        a_ok = pick_a(&fa, &fb, n);
        b_ok = !a_ok;
    }
    m->normal = keep == 1 ? fa.normal : keep == 2 ? mk_v3_neg(fb.normal) : n;
    if (a_ok) {
        mk_mf_clip(m, &fa, 1, &fb, ra, rb);
    } else if (b_ok) {
        mk_mf_clip(m, &fb, 0, &fa, ra, rb);
    } else if (support_segment(&fa, n, &sa) && support_segment(&fb, mk_v3_neg(n), &sb) && parallel(&sa, &sb)) {
        mk_mf_clip(m, &sa, 1, &sb, ra, rb);
    }
    if (cache) {
        cache->reference = m->count == 0 ? 0 : a_ok ? 1 : b_ok ? 2 : 0;
        cache->face = a_ok ? fa.id : fb.id;
    }
    if (m->count == 0) {
        /* Vertex contacts, crossing edges, or clipping lost the witness: the closest points themselves. */
        mk_vec3 bl = mk_mat3_tmul_v3(p->r, mk_v3_sub(cb, p->t));
        m->normal = n;
        mk_mf_add(m, mk_v3_mad(ca, ra, n), ra + rb - dist, mk_feature_at(a, ca, n),
                  mk_feature_at(b, bl, mk_mat3_tmul_v3(p->r, mk_v3_neg(n))));
    }
}

void mk_mf_from_hit(mk_mf *m, const mk_pair *p, mk_manifold_cache *cache, mk_hit h)
{
    mk_real ra = p->a->radius, rb = p->b->radius;
    if (h.distance > m->margin) return;
    mk_mf_from_closest(m, p, cache, h.normal, mk_v3_mad(h.a, -ra, h.normal), mk_v3_mad(h.b, rb, h.normal),
                       h.distance + ra + rb);
}

/* ---- reduction ---------------------------------------------------------- */

/* The deepest candidate is kept exactly (ties within round-off of the patch
 * size go to the earlier candidate), so the manifold's deepest depth is the
 * exact penetration. The area scores are compared with a bias: a later
 * candidate must beat the current best by 5 %, so near-ties resolve to the
 * earlier candidate, and candidate order comes from the features, which do
 * not change between frames (Box3D uses the same idea). */
#define REDUCE_BIAS MK_REAL(0.95)
/* (A form independent of candidate order, ties going to the smallest
 * feature pair, cost two passes per stage: +182 instructions per stacked
 * box query and no faster; box_box.c's header has the figures.) */

int mk_mf_pick4(int n, const mk_real *x, const mk_real *y, const mk_real *depth, int k[4])
{
    /* dx, dy: each candidate from the deepest; a01: the area it spans with
     * the deepest and the farthest (twice the signed area of that triangle). */
    mk_real extent = 0, best, sign, x0, y0, x1, y1, x2, y2, ex, ey, e1x, e1y, e2x, e2y, dx[MK_MF_MAX], dy[MK_MF_MAX], a01[MK_MF_MAX];
    int i, count = 2;
    k[0] = 0;
    k[1] = k[2] = k[3] = -1;
    for (i = 1; i < n; ++i) extent = mk_max(extent, mk_max(mk_fabs_(x[i] - x[0]), mk_fabs_(y[i] - y[0])));
    for (i = 1; i < n; ++i)
        if (depth[i] > depth[k[0]] + 64 * MK_REAL_EPSILON * extent) k[0] = i;
    x0 = x[k[0]], y0 = y[k[0]];
    for (best = 0, i = 0; i < n; ++i) {
        mk_real s;
        dx[i] = x[i] - x0, dy[i] = y[i] - y0, s = dx[i] * dx[i] + dy[i] * dy[i];
        if (s * REDUCE_BIAS * REDUCE_BIAS > best) { best = s; k[1] = i; }
    }
    if (k[1] < 0) k[1] = k[0] == 0 ? 1 : 0; /* all candidates coincide */
    x1 = x[k[1]], y1 = y[k[1]], ex = x1 - x0, ey = y1 - y0;
    for (best = 0, i = 0; i < n; ++i) {
        mk_real s = mk_fabs_(a01[i] = ex * dy[i] - ey * dx[i]);
        if (s * REDUCE_BIAS > best) { best = s; k[2] = i; }
    }
    if (k[2] < 0) return count;
    count = 3;
    x2 = x[k[2]], y2 = y[k[2]];
    sign = a01[k[2]] > 0 ? 1 : -1;
    /* How far outside the triangle's sides each point lies: the area it
     * adds to the patch, -sign * area(...) with the sign (+-1, exact)
     * folded into the sides' vectors. */
    e1x = -sign * (x2 - x1), e1y = -sign * (y2 - y1), e2x = -sign * (x0 - x2), e2y = -sign * (y0 - y2);
    for (best = 0, i = 0; i < n; ++i) {
        mk_real s = mk_max(-sign * a01[i], mk_max(e1x * (y[i] - y1) - e1y * (x[i] - x1), e2x * (y[i] - y2) - e2y * (x[i] - x2)));
        if (s * REDUCE_BIAS > best) { best = s; k[3] = i; }
    }
    return k[3] >= 0 ? 4 : count;
}

/* Coordinates in the contact plane: an orthonormal pair (t1, t2) with
 * t1 x t2 = n, the axes after n's largest component when n is a coordinate
 * axis (box faces, planes), so their coordinates are exact. */
void mk_mf_reduce(mk_mf *m)
{
    mk_real x[MK_MF_MAX], y[MK_MF_MAX], depth[MK_MF_MAX], nn[3];
    mk_vec3 n = m->normal, e = mk_v3_zero(), t1, t2;
    mk_mf_point keep[MK_MANIFOLD_MAX_POINTS];
    int k[4], i, count, ax;
    if (m->count <= MK_MANIFOLD_MAX_POINTS) return;
    nn[0] = mk_fabs_(n.x), nn[1] = mk_fabs_(n.y), nn[2] = mk_fabs_(n.z);
    ax = nn[0] >= nn[1] && nn[0] >= nn[2] ? 0 : nn[1] >= nn[2] ? 1 : 2;
    if (ax == 0) e.y = 1;
    else if (ax == 1) e.z = 1;
    else e.x = 1;
    t1 = mk_v3_normalize(mk_v3_mad(e, -mk_v3_dot(e, n), n));
    t2 = mk_v3_cross(n, t1);
    for (i = 0; i < m->count; ++i) {
        x[i] = mk_v3_dot(t1, m->p[i].pa);
        y[i] = mk_v3_dot(t2, m->p[i].pa);
        depth[i] = m->p[i].depth;
    }
    count = mk_mf_pick4(m->count, x, y, depth, k);
    for (i = 0; i < count; ++i) keep[i] = m->p[k[i]];
    for (i = 0; i < count; ++i) m->p[i] = keep[i];
    m->count = count;
}

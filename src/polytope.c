/* polytope.c: the box-as-hull view (polytope.h). */
#include "polytope.h"

/* Generated from the face corner order of minko/manifold.h's box faces:
 * face (axis, +) has corners (-,-) (+,-) (+,+) (-,+) in the (axis+1, axis+2)
 * plane, face (axis, -) the same reversed. {next, twin, origin, face}. */
static const mk_hull_edge box_edges[24] = {
    {1, 23, 4, 0}, {2, 12, 6, 0}, {3, 19, 2, 0}, {0, 10, 0, 0},
    {5, 17, 1, 1}, {6, 14, 3, 1}, {7, 21, 7, 1}, {4, 8, 5, 1},
    {9, 7, 1, 2},  {10, 20, 5, 2}, {11, 3, 4, 2}, {8, 18, 0, 2},
    {13, 1, 2, 3}, {14, 22, 6, 3}, {15, 5, 7, 3}, {12, 16, 3, 3},
    {17, 15, 2, 4}, {18, 4, 3, 4}, {19, 11, 1, 4}, {16, 2, 0, 4},
    {21, 9, 4, 5}, {22, 6, 5, 5}, {23, 13, 7, 5}, {20, 0, 6, 5},
};
static const uint16_t box_face_edge[6] = {0, 4, 8, 12, 16, 20};
static const uint16_t box_vertex_edge[8] = {3, 4, 2, 5, 0, 7, 1, 6};
/* Corner i's neighbours differ from it in one bit (one axis); then corners
 * extreme along +x, -x, +y, -y, +z, -z. */
static const uint16_t box_adjacency[9 + 24 + 6] = {
    9, 12, 15, 18, 21, 24, 27, 30, 33,
    1, 2, 4,  0, 3, 5,  3, 0, 6,  2, 1, 7,  5, 6, 0,  4, 7, 1,  7, 4, 2,  6, 5, 3,
    1, 0, 2, 0, 4, 0,
};
const unsigned char mk_box_edge_id_[24] = {6, 10, 4, 8, 5, 11, 7, 9, 9, 2, 8, 0, 10, 3, 11, 1, 1, 5, 0, 4, 2, 7, 3, 6};

void mk_box_hull_init(mk_box_hull *b, mk_vec3 h)
{
    mk_hull *x = &b->hull;
    int i;
    for (i = 0; i < 8; ++i) {
        b->v[i] = mk_v3(i & 1 ? h.x : -h.x, i & 2 ? h.y : -h.y, i & 4 ? h.z : -h.z);
        b->coords[i] = b->v[i].x;
        b->coords[8 + i] = b->v[i].y;
        b->coords[16 + i] = b->v[i].z;
    }
    for (i = 0; i < 6; ++i) {
        mk_real s = (i & 1) ? 1 : -1;
        b->p[i].normal = mk_v3(i / 2 == 0 ? s : 0, i / 2 == 1 ? s : 0, i / 2 == 2 ? s : 0);
        b->p[i].offset = i / 2 == 0 ? h.x : i / 2 == 1 ? h.y : h.z;
    }
    x->vertex_count = 8;
    x->edge_count = 24;
    x->face_count = 6;
    x->vertices = b->v;
    x->coords = b->coords;
    x->edges = box_edges;
    x->face_edge = box_face_edge;
    x->planes = b->p;
    x->vertex_edge = box_vertex_edge;
    x->adjacency = box_adjacency;
    x->centroid = mk_v3_zero();
    x->inner_radius = mk_min(h.x, mk_min(h.y, h.z));
    x->outer_radius = mk_v3_len(h);
    x->bounds = mk_aabb_make(mk_v3_neg(h), h);
    x->tolerance = 0;
    x->allocator.alloc = NULL;
    x->allocator.free = NULL;
    x->allocator.ctx = NULL;
    x->bytes = 0;
}


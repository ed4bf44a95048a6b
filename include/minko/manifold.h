/* minko/manifold.h: contact manifolds with feature IDs.
 *
 * Contract. Feature IDs name the geometric feature of a shape that makes a
 * contact: its type (vertex, edge, face) and its index on that shape, packed
 * into 16 bits. Indices per shape type: box vertices 0..7 are the corner bits
 * zyx (bit set = +extent), box edges 0..11 are 4*axis + the corner bits of the
 * other two axes (low bit = the lower-numbered axis), box faces 0..5 are
 * 2*axis + (1 for the + side); hull vertices, faces and edges are the mk_hull
 * indices (an edge is named by the lower of its two half-edge indices);
 * spheres are vertex 0; capsule ends are vertices 0 (-h) and 1 (+h), its
 * segment edge 0; cylinder and cone caps are faces 0 (-h) and 1 (+h), the
 * side face 2, the rim of cap k edge k, the fixed rim points of cap k used for
 * flat contact vertices 4k..4k+3 (local angles 0, 90, 180, 270 degrees from
 * +x), the cone apex vertex 8; planes are face 0.
 */
#ifndef MINKO_MANIFOLD_H
#define MINKO_MANIFOLD_H

#include "minko/shape.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mk_feature_type {
    MK_FEATURE_VERTEX = 0,
    MK_FEATURE_EDGE = 1,
    MK_FEATURE_FACE = 2
} mk_feature_type;

/* A feature of one shape: type in the top 2 bits, index in the low 14. */
typedef uint16_t mk_feature;
#define MK_FEATURE_INDEX_BITS 14
#define MK_FEATURE_MAX_INDEX ((1 << MK_FEATURE_INDEX_BITS) - 1)
#define MK_FEATURE(type, index) ((mk_feature)(((unsigned)(type) << MK_FEATURE_INDEX_BITS) | ((unsigned)(index) & MK_FEATURE_MAX_INDEX)))
#define MK_FEATURE_TYPE(f) ((mk_feature_type)((unsigned)(f) >> MK_FEATURE_INDEX_BITS))
#define MK_FEATURE_GET_INDEX(f) ((int)((unsigned)(f) & MK_FEATURE_MAX_INDEX))
/* The pair (feature of A, feature of B) as one 32-bit value: A low, B high. */
#define MK_FEATURE_PAIR(fa, fb) ((uint32_t)(fa) | ((uint32_t)(fb) << 16))

#ifdef __cplusplus
}
#endif

#endif

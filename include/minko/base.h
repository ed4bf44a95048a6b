/* minko/base.h: version, precision, status codes and the allocator hook.
 *
 * Contract. Every public Minko function that can fail returns an mk_status;
 * MK_OK is 0 and every other value names one kind of bad input or resource
 * problem, with a readable string from mk_status_str(). Numerical outcomes
 * that are not errors (a GJK that hit its iteration cap, a TOI that found no
 * hit) are reported in the result structs, never as a crash or a NaN.
 * mk_real is double unless the library was built with PRECISION=single; the
 * generated minko/config.h records which. Memory is only ever obtained through
 * an mk_allocator the caller may supply (NULL means malloc/free), and only by
 * functions whose name says they create something; queries never allocate.
 */
#ifndef MINKO_BASE_H
#define MINKO_BASE_H

#include <stddef.h>
#include <stdint.h>

#include "minko/config.h"

/* The single source of truth for the version; the Makefile reads these. */
#define MK_VERSION_MAJOR 0
#define MK_VERSION_MINOR 1
#define MK_VERSION_PATCH 0
#define MK_VERSION_NUMBER (MK_VERSION_MAJOR * 10000 + MK_VERSION_MINOR * 100 + MK_VERSION_PATCH)

#if defined(_WIN32) && defined(MK_SHARED)
#  if defined(MK_BUILDING)
#    define MK_API __declspec(dllexport)
#  else
#    define MK_API __declspec(dllimport)
#  endif
#elif defined(__GNUC__) || defined(__clang__)
#  define MK_API __attribute__((visibility("default")))
#else
#  define MK_API
#endif

/* Public math is C99 `inline` in the headers; src/math3d.c emits the one
 * external definition of each, so the functions are also real exported
 * symbols (for FFI and for -O0 builds). In C++ `inline` has the matching
 * meaning. */
#if defined(MK_BUILDING) && (defined(__GNUC__) || defined(__clang__))
/* Inside the library the math is always inlined: GCC's size heuristics
 * otherwise call some of it out of line in the larger query functions, and
 * such a call passes every mk_vec3 and mk_mat3 argument through memory. */
#  define MK_INLINE inline __attribute__((always_inline))
#else
#  define MK_INLINE inline
#endif

#ifdef __cplusplus
extern "C" {
#endif

#if defined(MK_SINGLE)
typedef float mk_real;
#  define MK_REAL(x) x##f
#  define MK_REAL_EPSILON 1.1920929e-07f
#  define MK_REAL_MAX 3.40282347e+38f
#  define MK_ABI_SYMBOL mk_abi_single_v0
#else
typedef double mk_real;
#  define MK_REAL(x) x
#  define MK_REAL_EPSILON 2.2204460492503131e-16
#  define MK_REAL_MAX 1.7976931348623157e+308
#  define MK_ABI_SYMBOL mk_abi_double_v0
#endif

/* Link-time precision guard: every translation unit that includes a Minko
 * header references the symbol of its own precision, and the library defines
 * only the symbol of the precision it was built with. Linking a double
 * application against a float library (or the reverse) fails with an
 * undefined reference to mk_abi_<precision>_v<major>. */
MK_API extern const int MK_ABI_SYMBOL;
#if !defined(MK_BUILDING) && (defined(__GNUC__) || defined(__clang__))
static const int *const mk_abi_guard_ __attribute__((used)) = &MK_ABI_SYMBOL;
#endif

/* X-macro: code, name, message. Codes are stable; append only. */
#define MK_STATUS_LIST(X) \
    X(0,  MK_OK,                 "ok") \
    X(1,  MK_ERR_NULL,           "a required pointer argument is NULL") \
    X(2,  MK_ERR_NOT_FINITE,     "an input number is NaN or infinite") \
    X(3,  MK_ERR_BAD_SIZE,       "a size, radius or extent is zero, negative or out of range") \
    X(4,  MK_ERR_BAD_ROTATION,   "a rotation is not proper (quaternion not unit length, or matrix not orthonormal with determinant +1)") \
    X(5,  MK_ERR_BAD_NORMAL,     "a plane or direction vector is zero or not unit length") \
    X(6,  MK_ERR_DEGENERATE,     "the input is degenerate (coincident, collinear or coplanar points)") \
    X(7,  MK_ERR_CAPACITY,       "a fixed capacity would be exceeded") \
    X(8,  MK_ERR_UNKNOWN_ID,     "the id does not name a live object") \
    X(9,  MK_ERR_OUT_OF_MEMORY,  "the allocator returned NULL") \
    X(10, MK_ERR_BAD_SHAPE,      "the shape type is unknown or its data is invalid") \
    X(11, MK_ERR_UNSUPPORTED,    "the operation is not supported for these shapes or was left out of this build") \
    X(12, MK_ERR_BAD_AABB,       "an AABB has lo > hi or non-finite bounds") \
    X(13, MK_ERR_BAD_ARGUMENT,   "an argument is out of its documented range") \
    X(14, MK_ERR_OUT_OF_RANGE,   "a position coordinate is beyond MK_MAX_COORD (minko/math3d.h)") \
    X(15, MK_ERR_UNCHECKED_POSE, "the mk_pose was not made by mk_pose_from_transform or mk_pose_from_matrix")

typedef enum mk_status {
#define MK_STATUS_ENUM_(code, name, msg) name = code,
    MK_STATUS_LIST(MK_STATUS_ENUM_)
#undef MK_STATUS_ENUM_
    MK_STATUS_COUNT_
} mk_status;

/* A readable, static string for any status (an unknown value gets one too). */
MK_API const char *mk_status_str(mk_status s);
/* The symbolic name, e.g. "MK_ERR_NOT_FINITE". */
MK_API const char *mk_status_name(mk_status s);

/* Caller-supplied allocator. `alloc` returns memory aligned to `align` (a power
 * of two no larger than 64) or NULL; `free` receives the size that was asked
 * for. `ctx` is passed back untouched. A NULL mk_allocator* means malloc/free. */
typedef struct mk_allocator {
    void *(*alloc)(void *ctx, size_t size, size_t align);
    void (*free)(void *ctx, void *ptr, size_t size);
    void *ctx;
} mk_allocator;

/* MK_VERSION_NUMBER of the library actually linked. */
MK_API int mk_version(void);
/* 1 if the linked library uses double precision, 0 for float. */
MK_API int mk_is_double_precision(void);

#ifdef __cplusplus
}
#endif

#endif

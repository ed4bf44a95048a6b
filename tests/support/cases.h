/* cases.h: the narrowphase case families of issue 2, with exact references.
 *
 * Contract. Seeded and deterministic; shared by the Check suites and by
 * demos/bench_narrow. Each case is (shape A, pose A, shape B, pose B) plus the
 * exact signed distance and unit normal (A towards B) computed by the oracle
 * (oracle.h) from exactly the numbers handed to the library. Generated
 * families round every input number (sizes, positions, quaternion components,
 * hull points) to float before use, so the float and double builds see the
 * very same cases with the very same references, and float backends get their
 * inputs without rounding. Fixed regression cases keep the decimal values of
 * their bug reports; their reference follows whatever the build's mk_real
 * makes of them. A case is "separated" or "penetrating" by its reference sign
 * and generic families keep |d| >= 1e-3 x size (thin rods: 2e-5 x size, a
 * tenth of their width; touching is a family of its own). `size` is the larger bounding radius of the two solids, the scale of
 * the nearly-touching family's absolute error. Memory: the set owns its cases,
 * oracle shapes and hulls (malloc); free it with mk_case_set_free.
 * Hull families draw from a pool of six hulls per call, built by
 * mk_hull_create from well-spaced points (every point a vertex) while the
 * oracle rebuilds each hull from the same points by brute force.
 * Complexity: generation is dominated by the oracle (boxes ~0.1 ms a case,
 * 128-vertex hulls ~10 ms).
 */
#ifndef MK_CASES_H
#define MK_CASES_H

#include <stdint.h>

#include "oracle.h"

typedef enum mk_family {
    MK_FAM_SPHERE_SPHERE = 0,
    MK_FAM_BOX_SPHERE,
    MK_FAM_CAPSULE_CAPSULE,
    MK_FAM_BOX_BOX,
    MK_FAM_HULL_8,          /* hulls of 8 / 32 / 128 points on ellipsoids, axis ratio up to 10 */
    MK_FAM_HULL_32,
    MK_FAM_HULL_128,
    MK_FAM_HULL_BOX,        /* 32-point hull against a box */
    MK_FAM_FLAT_BOXES,      /* 1 x 1 x 1e-3 plates */
    MK_FAM_THIN_RODS,       /* 100 x 0.01 x 0.01 rods crossing */
    MK_FAM_LARGE_COORDS,    /* box pairs, both offset by ~1e5 */
    MK_FAM_TINY,            /* box pairs of size ~1e-3 */
    MK_FAM_NEARLY_TOUCHING, /* box pairs at |d| ~ 1e-6 x size */
    MK_FAM_PARALLEL_FACES,  /* equal rotations, face to face */
    MK_FAM_DEEP,            /* box pairs: depth (or gap) ~ half the size */
    MK_FAM_COUNT
} mk_family;

typedef struct mk_case {
    const char *family;        /* mk_family_name(), or "regression" */
    const char *variant;       /* "separated" / "penetrating", or the regression's name */
    mk_shape a, b;
    mk_transform xa, xb;
    const mk_oracle_shape *oa, *ob; /* the judge's shapes; NULL where the reference is analytic */
    double distance;           /* exact signed distance, rounded once to double */
    double normal[3];          /* exact unit normal, world frame, A towards B */
    int normal_defined;        /* 0 where the exact normal is not unique */
    double size;               /* larger bounding radius of the two solids */
} mk_case;

struct mk_case_store;
typedef struct mk_case_set {
    mk_case *cases;
    int count, cap;
    struct mk_case_store *store; /* owned oracle shapes and hulls */
} mk_case_set;

const char *mk_family_name(mk_family f);
/* 1 for the families Minko answers in closed form (sphere and capsule pairs). */
int mk_family_closed_form(mk_family f);

/* Appends `separated` + `penetrating` cases of family f drawn from `seed`.
 * 0 on success, -1 on allocation failure or if the generator gives up. */
int mk_cases_add_family(mk_case_set *set, mk_family f, int separated, int penetrating, uint64_t seed);
/* Appends the named regression cases of issue 2 (libccd #25, #17, touching
 * boxes, fcl #493/#495 at +-1e-9, Jolt #2103). */
int mk_cases_add_regressions(mk_case_set *set);
void mk_case_set_free(mk_case_set *set);

#endif

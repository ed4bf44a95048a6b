/* mk_test.h: shared helpers for the Check suites: a seeded RNG (mk_rng.h; the
 * seed is printed on failure by the callers), precision-aware tolerances,
 * random poses. */
#ifndef MK_TEST_H
#define MK_TEST_H

#include <check.h>
#include <math.h>
#include <stdint.h>

#include "minko/math3d.h"
#include "mk_rng.h"

/* Tolerance for "exact" answers: 1e-12 relative in double, 1e-5 in float. */
#if defined(MK_SINGLE)
#  define MK_TEST_TOL 1e-5
#else
#  define MK_TEST_TOL 1e-12
#endif

#define MK_ASSERT_NEAR(a, b, tol) ck_assert_msg(fabs((double)(a) - (double)(b)) <= (double)(tol), \
    "%s = %.17g, %s = %.17g, |diff| = %.3g > %.3g", #a, (double)(a), #b, (double)(b), fabs((double)(a) - (double)(b)), (double)(tol))
#define MK_ASSERT_V3_NEAR(a, b, tol) do { mk_vec3 a_ = (a), b_ = (b); \
    MK_ASSERT_NEAR(a_.x, b_.x, tol); MK_ASSERT_NEAR(a_.y, b_.y, tol); MK_ASSERT_NEAR(a_.z, b_.z, tol); } while (0)
#define MK_ASSERT_STATUS(expr, want) do { mk_status st_ = (expr); \
    ck_assert_msg(st_ == (want), "%s returned %s (%s), expected %s", #expr, mk_status_name(st_), mk_status_str(st_), mk_status_name(want)); } while (0)

/* Runs one suite and returns the process exit code; prints Check's summary line. */
static inline int mk_test_run(Suite *s)
{
    SRunner *sr = srunner_create(s);
    int failed;
    srunner_run_all(sr, CK_NORMAL);
    failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed == 0 ? 0 : 1;
}

#endif

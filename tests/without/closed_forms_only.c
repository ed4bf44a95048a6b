/* closed_forms_only.c: run by `make check` against a library built with
 * MK_WITHOUT="gjk epa sat" (a plain program: the point is what links). The
 * sphere, capsule, box and plane closed forms must still answer exactly, and
 * pairs that need a dropped module must say MK_ERR_UNSUPPORTED, not crash. */
#include <math.h>
#include <stdio.h>

#include "minko/distance.h"

static int fails = 0;

static void expect(const char *what, mk_status st, mk_status want, double got, double want_d)
{
    if (st != want || (want == MK_OK && fabs(got - want_d) > 1e-5)) {
        printf("closed_forms_only: %s: %s, distance %.17g (want %s, %.17g)\n", what, mk_status_name(st), got,
               mk_status_name(want), want_d);
        ++fails;
    }
}

/* One query, then its check: the call must be sequenced before reading r. */
static void dist(const char *what, const mk_shape *a, mk_vec3 pa, const mk_shape *b, mk_vec3 pb, mk_status want, double want_d)
{
    mk_distance_result r;
    mk_status st = mk_distance(a, mk_transform_make(pa, mk_quat_identity()), b, mk_transform_make(pb, mk_quat_identity()), NULL, &r);
    expect(what, st, want, st == MK_OK ? (double)r.distance : 0, want_d);
}

int main(void)
{
    mk_shape sphere, box, capsule, plane, cyl;
    mk_vec3 o = mk_v3(0, 0, 0);
    int ov = 0;
#if defined(MK_WITHOUT_GJK)
    const mk_status iterative = MK_ERR_UNSUPPORTED;
#else
    const mk_status iterative = MK_OK;
#endif
    mk_shape_sphere(1, &sphere);
    mk_shape_box(mk_v3(1, 1, 1), 0, &box);
    mk_shape_capsule(0.5, 1, &capsule);
    mk_shape_plane(mk_v3(0, 0, 1), 0, &plane);
    mk_shape_cylinder(1, 1, 0, &cyl);
    dist("sphere-sphere", &sphere, o, &sphere, mk_v3(3, 0, 0), MK_OK, 1);
    dist("sphere-box", &sphere, mk_v3(0, 0, 3), &box, o, MK_OK, 1);
    dist("capsule-capsule", &capsule, o, &capsule, mk_v3(2, 0, 0), MK_OK, 1);
    dist("box-plane", &box, mk_v3(0, 0, 3), &plane, o, MK_OK, 2);
    dist("box-box", &box, o, &box, mk_v3(3, 0, 0), iterative, 1);
    expect("cylinder-sphere overlap", mk_overlap(&cyl, mk_transform_identity(), &sphere, mk_transform_identity(), NULL, &ov),
           iterative, 0, 0);
    if (fails) return 1;
    printf("closed_forms_only: closed forms answer, iterative pairs refused (MK_WITHOUT build)\n");
    return 0;
}

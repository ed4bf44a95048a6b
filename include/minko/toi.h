/* minko/toi.h: continuous collision: motions over a step and their swept bounds.
 *
 * Contract. A body's motion over one step is an mk_sweep: its rotation centre
 * (e.g. the centre of mass, given in the shape's frame) moves on a straight
 * line from c0 to c1 while the body turns at a constant rate about a fixed
 * world axis by |rotation| radians, so the pose at t in [0, 1] is exact
 * rigid motion with constant linear and angular velocity. Build one from the
 * start and end transforms (the shortest rotation between them) or from
 * velocities and a time step. The total angle per step must not exceed
 * MK_SWEEP_MAX_ANGLE (pi): a faster spinner must be substepped, since no end
 * orientation can tell one turn from another. mk_swept_aabb() bounds
 * everything the shape covers during the sweep (the seed's "moving sphere"
 * made tight for slow turns), so a broadphase fed with it reports every pair
 * that can meet during the step. Bad input returns a status and leaves *out
 * untouched. Cost: O(1) per call, O(vertices) for hulls. Nothing allocates.
 */
#ifndef MINKO_TOI_H
#define MINKO_TOI_H

#include "minko/shape.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MK_SWEEP_MAX_ANGLE MK_REAL(3.14159265358979323846)

typedef struct mk_sweep {
    mk_vec3 local_center; /* rotation centre, shape frame */
    mk_vec3 c0, c1;       /* world position of the rotation centre at t = 0 and t = 1 */
    mk_quat q0;           /* orientation at t = 0 */
    mk_vec3 rotation;     /* world axis * angle turned over the step, angle <= MK_SWEEP_MAX_ANGLE */
} mk_sweep;

/* Motion from pose x0 to pose x1, turning the short way (angle <= pi). */
MK_API mk_status mk_sweep_from_transforms(mk_transform x0, mk_transform x1, mk_vec3 local_center, mk_sweep *out);
/* Motion from pose x0 with the rotation centre's linear velocity and the
 * world angular velocity held for dt >= 0. */
MK_API mk_status mk_sweep_from_velocity(mk_transform x0, mk_vec3 linear_velocity, mk_vec3 angular_velocity, mk_real dt,
                                        mk_vec3 local_center, mk_sweep *out);
/* Checks a sweep however it was made (finite, unit q0, angle in range). */
MK_API mk_status mk_sweep_validate(const mk_sweep *sw);
/* Pose of the shape at t in [0, 1]. */
MK_API mk_status mk_sweep_transform(const mk_sweep *sw, mk_real t, mk_transform *out);
/* World AABB containing the shape at every t in [0, 1]. Conservative: the
 * union of the start and end boxes grown by the largest gap between an arc
 * and its chord (rho * (1 - cos(angle / 2)), rho the shape's bounding radius
 * about the rotation centre), clipped to the box of the moving bounding
 * sphere. Exact for pure translation. Planes cannot move: MK_ERR_UNSUPPORTED. */
MK_API mk_status mk_swept_aabb(const mk_shape *s, const mk_sweep *sw, mk_aabb *out);

#ifdef __cplusplus
}
#endif

#endif

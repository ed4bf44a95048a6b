/* minko/toi.h: continuous collision: motions, swept bounds, time of impact,
 * shape casts and the host's adaptive step.
 *
 * Contract. A body's motion over one step is an mk_sweep: its rotation centre
 * (e.g. the centre of mass, in the shape's frame) moves on a straight line
 * from c0 to c1 while the body turns at a constant rate about a fixed world
 * axis, so the pose at t in [0, 1] is rigid motion with constant linear and
 * angular velocity. The turn per step may not exceed MK_SWEEP_MAX_ANGLE (pi):
 * a faster spinner must be substepped, since no end orientation tells one turn
 * from the next. mk_swept_aabb() bounds all the shape covers during the sweep
 * (the seed's "moving sphere", tight for slow turns), so a broadphase fed with
 * it finds every pair that can meet. mk_toi() is conservative advancement with
 * certified second-order bounds: a HIT at t guarantees that before t the two
 * shapes never came closer than `target` (no contact is skipped, however thin
 * or fast the shapes, rotation included) and that at t their distance is in
 * [target, target + tolerance], both up to the rounding of the distance
 * queries; the time error is then at most tolerance / (approach speed). A
 * tolerance below the rounding floor (1e4 eps of the pair's size and travel in
 * double, 1e2 eps in float) is raised to it, so 0 asks for the tightest
 * answer. Cost: one GJK on the cores per iteration, warm-started, typically
 * 2 to 4 iterations for translations and 4 to 8 for turns (parallel edges or
 * faces of turning shapes converge more slowly), capped at 128
 * (FAILED, with a t still proven free of contact); sphere pairs and plane
 * pairs run no GJK. Planes may translate but not turn; plane-plane pairs are
 * unsupported. Bad input returns a status and leaves *out untouched. Nothing
 * here allocates.
 */
#ifndef MINKO_TOI_H
#define MINKO_TOI_H

#include "minko/raycast.h"

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
/* Restarts the sweep at t in [0, 1]: it then covers [t, 1] of the old motion,
 * re-parameterised to [0, 1] (same end pose, same velocities per unit time of
 * the whole step scaled by 1 - t). */
MK_API mk_status mk_sweep_advance(mk_sweep *sw, mk_real t);
/* World AABB containing the shape at every t in [0, 1]. Conservative: the
 * union of the start and end boxes grown by the largest gap between an arc
 * and its chord (rho * (1 - cos(angle / 2)), rho the shape's bounding radius
 * about the rotation centre), clipped to the box of the moving bounding
 * sphere (a hull's radius is taken through its centroid). Exact for pure
 * translation. Planes cannot move: MK_ERR_UNSUPPORTED. */
MK_API mk_status mk_swept_aabb(const mk_shape *s, const mk_sweep *sw, mk_aabb *out);

typedef enum mk_toi_state {
    MK_TOI_HIT = 0,    /* the shapes come within target + tolerance at t (t = 0: already there) */
    MK_TOI_SEPARATED,  /* they stay farther apart than target over the whole step; t = 1 */
    MK_TOI_OVERLAPPED, /* they penetrate at t = 0: time of impact is meaningless, t = 0 */
    MK_TOI_FAILED      /* iteration cap; t is the latest time proven free of contact */
} mk_toi_state;

/* For HIT and OVERLAPPED the geometry is the narrowphase's answer at t. For
 * SEPARATED and FAILED it describes the last time evaluated (t itself for
 * FAILED): the separation along the last normal and the shapes' deepest
 * points along it. */
typedef struct mk_toi_result {
    mk_toi_state state;
    mk_real t;         /* in [0, 1] */
    mk_real distance;  /* signed distance */
    mk_vec3 normal;    /* unit, world frame, from A towards B */
    mk_vec3 point_a;   /* witness points, world frame */
    mk_vec3 point_b;
    mk_real rate;      /* d(distance)/dt at the witness points: < 0 while the shapes approach */
    int iterations;    /* distance queries spent */
} mk_toi_result;

/* Time of impact of a moving by sa and b moving by sb: the first t in [0, 1]
 * at which their distance comes down to target >= 0 (see the contract for the
 * guarantee and for tolerance >= 0). Already within target + tolerance at
 * t = 0 is a HIT at 0; penetrating by more than the tolerance at t = 0 is
 * OVERLAPPED. */
MK_API mk_status mk_toi(const mk_shape *a, const mk_sweep *sa, const mk_shape *b, const mk_sweep *sb, mk_real target,
                        mk_real tolerance, mk_toi_result *out);

/* Shape cast: a, starting at xa, translated by `translation`, against b at xb.
 * The first contact (distance 0, tightest tolerance) as a ray hit: fraction
 * of the translation, point on b, b's outward normal there. Starting in
 * contact or overlapping hits at fraction 0; an iteration cap reports a hit
 * at the last fraction proven free of contact. */
MK_API mk_status mk_shape_cast(const mk_shape *a, mk_transform xa, mk_vec3 translation, const mk_shape *b, mk_transform xb,
                               mk_ray_hit *out);

/* ---- host helpers: the adaptive step of seed 000 ----------------------------
 * A host lists its fast bodies (shape + motion over the rest of the step) and
 * the candidate pairs its broadphase found with swept AABBs, then either asks
 * for the earliest hit, or lets mk_toi_substep() run the whole loop: advance
 * every body to the earliest time of impact, let the host resolve that
 * contact (change velocities, i.e. rewrite sweeps), repeat. Arrays belong to
 * the caller; nothing allocates. Cost per round: one TOI per pair, each cut
 * off at the earliest time found so far. */

typedef struct mk_toi_body {
    const mk_shape *shape;
    mk_sweep sweep; /* motion over what remains of the step */
} mk_toi_body;

typedef struct mk_toi_pair { int a, b; } mk_toi_pair; /* indices into the body array */

typedef struct mk_toi_event {
    int pair;             /* index into the pair array; -1 when no pair hits */
    mk_toi_result result; /* result.t is relative to the sweeps passed in */
    int overlapped;       /* pairs skipped because they penetrate at the start */
    int receding;         /* pairs skipped because they start within target and move apart */
} mk_toi_event;

/* Earliest HIT (or FAILED, whose t is still a proven-safe time) over the
 * pairs, lowest pair index on ties. Pairs that penetrate at the start, or
 * start within target while moving apart, are left to the host's discrete
 * contacts and counted. */
MK_API mk_status mk_toi_earliest(const mk_toi_body *bodies, int body_count, const mk_toi_pair *pairs, int pair_count,
                                 mk_real target, mk_real tolerance, mk_toi_event *out);

/* Called at each hit, after every sweep was advanced to it; `time` is the
 * fraction of the whole step reached. The host may rewrite any sweep (new
 * velocities for the rest of the step). Return 0 to go on, non-zero to stop. */
typedef int (*mk_toi_resolve_fn)(void *user, mk_toi_body *bodies, int body_count, int pair, const mk_toi_result *hit, mk_real time);

typedef struct mk_toi_step_stats {
    int substeps;  /* rounds run */
    int hits;      /* resolve calls */
    int failed;    /* rounds that stopped at a FAILED pair's safe time */
    mk_real time;  /* fraction of the step reached: 1 unless max_substeps or resolve stopped the loop */
} mk_toi_step_stats;

/* Runs at most max_substeps rounds. On return (errors included: a sweep the
 * resolver made invalid stops the loop with its status) every sweep starts at
 * stats->time and ends where the step ends. */
MK_API mk_status mk_toi_substep(mk_toi_body *bodies, int body_count, const mk_toi_pair *pairs, int pair_count, mk_real target,
                                mk_real tolerance, int max_substeps, mk_toi_resolve_fn resolve, void *user,
                                mk_toi_step_stats *stats);

#ifdef __cplusplus
}
#endif

#endif

/* ode_toi.c: time of impact between ODE geoms moving with their bodies
 * (minko_ode.h).
 *
 * ODE integrates whole steps and has no continuous collision: a body that
 * moves farther than its own size in one step can pass through a thin geom.
 * mk_ode_time_of_impact tells the host when, within the next dt, two geoms
 * first come within `target` of each other, assuming each keeps its body's
 * current linear and angular velocity (Minko's conservative advancement,
 * mk_toi, which never skips a contact). A host then splits its step there
 * (ode_scenes' wall scene shows the loop).
 */
#include "minko/toi.h"
#include "ode_internal.h"

/* The motion of g over dt: its body's velocities held (the body turns about
 * its centre of mass, the body position), or standing still without a body. */
static mk_status sweep_of(dGeomID g, const dReal *origin, mk_transform xf, dReal dt, mk_sweep *out)
{
    dBodyID b = dGeomGetBody(g);
    mk_vec3 v = mk_v3_zero(), w = mk_v3_zero(), center = mk_v3_zero();
    if (b && dGeomGetClass(g) != dPlaneClass) {
        const dReal *lv = dBodyGetLinearVel(b), *av = dBodyGetAngularVel(b), *bp = dBodyGetPosition(b);
        mk_vec3 rel = mk_v3((mk_real)(bp[0] - origin[0]), (mk_real)(bp[1] - origin[1]), (mk_real)(bp[2] - origin[2]));
        v = mk_v3((mk_real)lv[0], (mk_real)lv[1], (mk_real)lv[2]);
        w = mk_v3((mk_real)av[0], (mk_real)av[1], (mk_real)av[2]);
        center = mk_transform_inv_point(xf, rel);
    }
    return mk_sweep_from_velocity(xf, v, w, (mk_real)dt, center, out);
}

int mk_ode_time_of_impact(dGeomID o1, dGeomID o2, dReal dt, dReal target, dReal *toi, dContactGeom *contact)
{
    const dReal *origin;
    mk_shape a, b;
    mk_transform xa, xb;
    mk_sweep sa, sb;
    mk_toi_result r;
    mk_status s;
    mk_vec3 mid;
    if (!o1 || !o2 || !toi || !contact || !(dt >= 0) || !(target >= 0)) {
        mk_ode_stats_.errors++;
        mk_ode_stats_.last_error = MK_ERR_BAD_ARGUMENT;
        return -1;
    }
    origin = mk_ode_origin_(o1, o2);
    s = mk_ode_shape_of_(o1, origin, &a, &xa);
    if (s == MK_OK) s = mk_ode_shape_of_(o2, origin, &b, &xb);
    if (s == MK_OK) s = sweep_of(o1, origin, xa, dt, &sa);
    if (s == MK_OK) s = sweep_of(o2, origin, xb, dt, &sb);
    if (s == MK_OK) s = mk_toi(&a, &sa, &b, &sb, (mk_real)target, 0, &r);
    if (s != MK_OK) { /* unsupported class, convex without a hull, a spin over pi per step, ... */
        mk_ode_stats_.errors++;
        mk_ode_stats_.last_error = s;
        return -1;
    }
    mk_ode_stats_.toi_calls++;
    /* Penetrating already is the discrete contacts' business; touching while
     * moving apart needs no contact. */
    if (r.state == MK_TOI_SEPARATED || r.state == MK_TOI_OVERLAPPED || (r.t == 0 && r.rate >= 0)) return 0;
    *toi = (dReal)r.t * dt; /* FAILED: r.t is still a time proven free of contact */
    mid = mk_v3_lerp(r.point_a, r.point_b, MK_REAL(0.5));
    contact->pos[0] = origin[0] + (dReal)mid.x;
    contact->pos[1] = origin[1] + (dReal)mid.y;
    contact->pos[2] = origin[2] + (dReal)mid.z;
    contact->pos[3] = 0;
    contact->normal[0] = -(dReal)r.normal.x;
    contact->normal[1] = -(dReal)r.normal.y;
    contact->normal[2] = -(dReal)r.normal.z;
    contact->normal[3] = 0;
    contact->depth = r.distance < 0 ? -(dReal)r.distance : 0;
    contact->g1 = o1;
    contact->g2 = o2;
    contact->side1 = -1;
    contact->side2 = -1;
    return 1;
}

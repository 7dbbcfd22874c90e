/*
 * joint.c - the table of joint kinds (model.h): one row per ctc_joint_type, with the sizes, the
 * name and the properties that the builder, the run and the job format read.
 *
 * Coordinates (model.h, Featherstone, Rigid Body Dynamics Algorithms, 2008, Table 4.1):
 * revolute, an angle (rad); prismatic, a displacement (m); cylindrical, (angle, displacement)
 * about and along one axis; spherical, a unit quaternion (w, x, y, z) with the relative angular
 * velocity in the child's frame as its three velocity coordinates; fixed, none. Only revolute and
 * prismatic joints move in a plane (fixed ones do not move), and a loop closes through a
 * revolute, prismatic or spherical joint (loop.c). A spherical joint's error has no per-coordinate
 * form, so no controller drives one. The functions a new kind must also implement are listed
 * above ctc_joint_class in model.h.
 */
#include "model.h"

#include <string.h>

const ctc_joint_class ctc_joint_classes[CTC_JOINT_NTYPES] = {
    [CTC_JOINT_REVOLUTE] = {.name = "revolute",
                            .nq = 1,
                            .nv = 1,
                            .needs_axis = 1,
                            .planar = 1,
                            .loop_closing = 1,
                            .linear_mask = 0x0},
    [CTC_JOINT_PRISMATIC] = {.name = "prismatic",
                             .nq = 1,
                             .nv = 1,
                             .needs_axis = 1,
                             .planar = 1,
                             .loop_closing = 1,
                             .linear_mask = 0x1},
    [CTC_JOINT_CYLINDRICAL] = {.name = "cylindrical",
                               .nq = 2,
                               .nv = 2,
                               .needs_axis = 1,
                               .planar = 0,
                               .loop_closing = 0,
                               .linear_mask = 0x2},
    [CTC_JOINT_SPHERICAL] = {.name = "spherical",
                             .nq = 4,
                             .nv = 3,
                             .needs_axis = 0,
                             .planar = 0,
                             .loop_closing = 1,
                             .undriven = "its quaternion error is not a per-coordinate error",
                             .linear_mask = 0x0},
    [CTC_JOINT_FIXED] = {.name = "fixed",
                         .nq = 0,
                         .nv = 0,
                         .needs_axis = 0,
                         .planar = 1,
                         .loop_closing = 0,
                         .linear_mask = 0x0},
};

const ctc_joint_class *ctc_joint_class_of(ctc_joint_type t)
{
    return (unsigned)t < CTC_JOINT_NTYPES ? &ctc_joint_classes[t] : NULL;
}

int ctc_joint_type_of(const char *name)
{
    for (int t = 0; name && t < CTC_JOINT_NTYPES; t++)
        if (strcmp(ctc_joint_classes[t].name, name) == 0) return t;
    return -1;
}

int ctc_joint_nq(ctc_joint_type t)
{
    const ctc_joint_class *c = ctc_joint_class_of(t);
    return c ? c->nq : 0;
}

int ctc_joint_nv(ctc_joint_type t)
{
    const ctc_joint_class *c = ctc_joint_class_of(t);
    return c ? c->nv : 0;
}

const char *ctc_joint_type_name(ctc_joint_type t)
{
    const ctc_joint_class *c = ctc_joint_class_of(t);
    return c ? c->name : "unknown";
}

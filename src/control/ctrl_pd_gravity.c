/*
 * ctrl_pd_gravity.c - the PD with gravity compensation baseline (ctrl.h CTC_FORCE_GRAVITY):
 * f = g(q) + kp e + kv de, where g(q) = ID(q, 0, 0) is the controller's model's gravity load at
 * the measured pose. With an exact model it holds any pose at rest exactly, and it regulates to
 * a constant pose from anywhere (Takegaki and Arimoto 1981); it does not cancel the inertial
 * and velocity terms of a moving trajectory. Gains in N m/rad and N m s/rad.
 */
#include "ctrl.h"

static ctc_status design(const ctc_ctrl_params *p, ctc_gains *out, char *err, size_t errlen)
{
    return ctc_ctrl_pid(p->kp, p->kv, 0, out, err, errlen);
}

const ctc_ctrl_class ctc_ctrl_class_pd_gravity = {.name = "pd_gravity",
                                                  .params = CTC_CP_KP | CTC_CP_KV,
                                                  .required = CTC_CP_KP | CTC_CP_KV,
                                                  .design = design,
                                                  .law = ctc_ctrl_pd_force_law,
                                                  .force = CTC_FORCE_GRAVITY};

/*
 * ctrl_feedforward.c - the feedforward baseline (ctrl.h CTC_FORCE_FEEDFORWARD): the inverse
 * dynamics of the controller's model at the desired state, ID(q_d, qd_d, qdd_d), computed from
 * the trajectory alone, plus a PD on forces, kp e + kv de. Unlike computed torque the model is
 * not evaluated at the measured state, so its forces can be tabulated before the run; with an
 * exact model, started on the desired motion, it stays on it. Gains in N m/rad and N m s/rad.
 */
#include "ctrl.h"

static ctc_status design(const ctc_ctrl_params *p, ctc_gains *out, char *err, size_t errlen)
{
    return ctc_ctrl_pid(p->kp, p->kv, 0, out, err, errlen);
}

const ctc_ctrl_class ctc_ctrl_class_feedforward = {.name = "feedforward",
                                                   .params = CTC_CP_KP | CTC_CP_KV,
                                                   .required = CTC_CP_KP | CTC_CP_KV,
                                                   .design = design,
                                                   .law = ctc_ctrl_pd_force_law,
                                                   .force = CTC_FORCE_FEEDFORWARD};

/*
 * ctrl_joint_pd.c - the independent joint PD baseline (ctrl.h CTC_FORCE_DIRECT): each actuator
 * gives f_i = kp (q_d,i - q_i) + kv (qd_d,i - v_i), with no model of the chain. It is what
 * computed torque control is compared with in class: its error depends on the coupling and
 * gravity it ignores, and gravity leaves an offset kp e = g(q) at rest. Gains in N m/rad and
 * N m s/rad (N/m, N s/m for a prismatic coordinate); the PD law here is shared by the other
 * baselines (ctrl_pd_gravity.c, ctrl_feedforward.c).
 */
#include "ctrl.h"

void ctc_ctrl_pd_force_law(const ctc_ctrl_eval *in, double *w)
{
    const ctc_gains *g = in->gains;
    const double *d = in->des, *qi = in->qi, *vi = in->vi;
    for (int i = 0; i < in->nind; i++, d += 3)
        w[i] = g[i].kp * (d[0] - qi[i]) + g[i].kv * (d[1] - vi[i]);
}

/* kp and kv, both positive and finite (ctc_ctrl_pid with ki = 0) */
static ctc_status design_pd_force(const ctc_ctrl_params *p, ctc_gains *out, char *err,
                                  size_t errlen)
{
    return ctc_ctrl_pid(p->kp, p->kv, 0, out, err, errlen);
}

const ctc_ctrl_class ctc_ctrl_class_joint_pd = {.name = "joint_pd",
                                                .params = CTC_CP_KP | CTC_CP_KV,
                                                .required = CTC_CP_KP | CTC_CP_KV,
                                                .design = design_pd_force,
                                                .law = ctc_ctrl_pd_force_law,
                                                .force = CTC_FORCE_DIRECT};

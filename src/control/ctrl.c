/*
 * ctrl.c - the table of controller kinds (ctrl.h), the passive kind "none", and the linear state
 * feedback every other built-in kind shares (paper section 2 and 6, DESIGN.md section 6).
 *
 * Each kind is one ctc_ctrl_class defined in its own file (pd and pid in ctrl_pid.c, poles in
 * ctrl_poles.c, lqr in ctrl_lqr.c) and listed once below, at the index of its ctc_ctrl_type.
 * Adding a kind is its file and one row here; the job parser and the run find its name, its
 * parameters, its design and its law through the row.
 *
 * The built-in laws differ only in how their gains are designed: each is
 *     w_i = ki xi_i + kp (q_d,i - qi_i) + kv (qd_d,i - vi_i),   xi_i = int e_i,
 * written with that order of operations, which the run's results depend on to the last bit.
 */
#include "ctrl.h"

#include <string.h>

extern const ctc_ctrl_class ctc_ctrl_class_pd, ctc_ctrl_class_pid, ctc_ctrl_class_poles,
    ctc_ctrl_class_lqr, ctc_ctrl_class_joint_pd, ctc_ctrl_class_pd_gravity,
    ctc_ctrl_class_feedforward;

/* passive: no law, no gains, no state */
static const ctc_ctrl_class ctc_ctrl_class_none = {.name = "none"};

const ctc_ctrl_class *const ctc_ctrl_classes[CTC_CTRL_NTYPES] = {
    [CTC_CTRL_NONE] = &ctc_ctrl_class_none,
    [CTC_CTRL_PD] = &ctc_ctrl_class_pd,
    [CTC_CTRL_PID] = &ctc_ctrl_class_pid,
    [CTC_CTRL_POLES] = &ctc_ctrl_class_poles,
    [CTC_CTRL_LQR] = &ctc_ctrl_class_lqr,
    [CTC_CTRL_JOINT_PD] = &ctc_ctrl_class_joint_pd,
    [CTC_CTRL_PD_GRAVITY] = &ctc_ctrl_class_pd_gravity,
    [CTC_CTRL_FEEDFORWARD] = &ctc_ctrl_class_feedforward,
};

const ctc_ctrl_class *ctc_ctrl_class_of(ctc_ctrl_type t)
{
    return (unsigned)t < CTC_CTRL_NTYPES ? ctc_ctrl_classes[t] : NULL;
}

int ctc_ctrl_type_of(const char *name)
{
    for (int t = 0; name && t < CTC_CTRL_NTYPES; t++)
        if (strcmp(ctc_ctrl_classes[t]->name, name) == 0) return t;
    return -1;
}

const char *ctc_ctrl_param_name(unsigned bit)
{
    static const char *const names[CTC_CP_COUNT] = {"kp",  "kv",    "ki", "zeta",
                                                    "tau", "poles", "Q",  "lambda"};
    for (int i = 0; i < CTC_CP_COUNT; i++)
        if (bit == 1u << i) return names[i];
    return NULL;
}

void ctc_ctrl_linear_law(const ctc_ctrl_eval *in, double *w)
{
    const ctc_gains *g = in->gains;
    const double *d = in->des, *xi = in->xi, *qi = in->qi, *vi = in->vi;
    for (int i = 0; i < in->nind; i++, d += 3)
        w[i] = g[i].ki * xi[i] + g[i].kp * (d[0] - qi[i]) + g[i].kv * (d[1] - vi[i]);
}

void ctc_ctrl_linear_closed_loop(const ctc_gains *g, double a[9])
{
    /* d/dt (int e, e, de) = Ac (int e, e, de): e'' = -ki int e - kp e - kv de */
    const double ac[9] = {0, 1, 0, 0, 0, 1, -g->ki, -g->kp, -g->kv};
    memcpy(a, ac, sizeof ac);
}

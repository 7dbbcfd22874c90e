/*
 * sim_rhs.c - the right-hand side of a computed torque control run (sim.h, sim_internal.h): one
 * evaluation for the integrator, and what a sample needs of it.
 *
 * For the state y = (q (nq), v (nv), xi (nind when the controller has the integral state)) at
 * time t, in order:
 *     kinematics and body handle equations of the plant at (q, v)           (DESIGN.md 3)
 *     desired motion (q_d, qd_d, qdd_d)_i = traj_i(t)                       (traj.h)
 *     w = law(t, q, v, q_d, xi), u_i = qdd_d,i + w_i                         (ctrl.h, paper Eq. 18)
 *     f = iGDCA(controller model; q, v, u)                                   (paper Eq. 70)
 *     f + z(t), the disturbance added to the applied forces                  (disturb.h)
 *     qdd = GDCA(plant; q, v, f + z)                                         (paper section 3)
 *     dy/dt = (qdot(q, v), qdd, e)
 * With an exact controller model the plant and the controller share one ctc_data, so the
 * kinematics and the body handle equations are computed once per evaluation (Eq. 42-43).
 * Spherical joints (passive runs only) are integrated as quaternions; the evaluation reads a
 * normalised copy. The law is called once per evaluation through the class's pointer, for all
 * coordinates at once; nothing here allocates.
 *
 * Loop models: the controller's coordinates are the independent ones (the closing joint's
 * position and rate come from the loop kinematics), the forces and accelerations of the passes
 * are extended vectors (nvx), and an evaluation whose boundary solve is singular beyond
 * loop_cond_max returns SIM_RHS_SINGULAR. sim_project is bdf's projection onto the closure
 * inside CVODE's steps (integrator.h ctc_integrator_set_projection): a restart would send CVODE
 * back to order 1 and a short step, whose drift then asks for the next projection
 * (bench/NOTEBOOK.md, "Whole simulations", "Reading it": BDF on the five-bar).
 */
#include <math.h>
#include <string.h>

#include "gdca.h"
#include "handles.h"
#include "kinematics.h"
#include "sim_internal.h"

/* the controlled coordinates' positions and rates into c->qi, c->vi (after the kinematics) */
static void controlled_coords(const sim_ctx *c, const double *q, const double *v)
{
    const ctc_model *m = c->plant;
    for (int i = 0; i < c->nind; i++) {
        int k = m->ind_joint[i], off = m->ind_coord[i] - m->jnt_vadr[k];
        if (k < m->nbodies) {
            c->qi[i] = q[m->jnt_qadr[k] + off];
            c->vi[i] = v[m->ind_coord[i]];
        } else {
            c->qi[i] = c->dp->loop_q[off];
            c->vi[i] = c->dp->loop_v[off];
        }
    }
}

/* Driving forces and accelerations of state (q, v, ie) at time t, as far as `what` asks: fills
 * ctx's arrays (the force arrays and c->acc (nvx) when asked for) and dp's kinematics. A loop
 * model always gets its kinematics (the closing joint's coordinates come from them). Returns 0,
 * or SIM_RHS_SINGULAR when a loop's boundary solve is singular. A full evaluation is remembered
 * (t_eval, y_eval), so a sample taken at exactly that state reuses it (sim_record_sample). */
int sim_evaluate(sim_ctx *c, double t, const double *y, unsigned what)
{
    const ctc_sim_spec *s = c->spec;
    const ctc_model *m = c->plant;
    const double *q = y, *v = y + c->nq;
    const int forces = (what & (SIM_EVAL_FORCES | SIM_EVAL_ACC)) != 0;
    c->eval_valid = 0;
    if (c->has_quat) {
        memcpy(c->qn, q, (size_t)c->nq * sizeof *q);
        ctc_model_q_normalize(m, c->qn);
        q = c->qn;
    }

    if (what || m->has_loop) ctc_kinematics(m, c->dp, q, v);
    if (forces) ctc_handles(m, c->dp);
    controlled_coords(c, q, v);
    c->cond = 1;

    /* controller: the desired motion, w = law(...), u = qdd_d + w, f = iGDCA(u) */
    if (c->active) {
        if (forces) memset(c->u, 0, (size_t)c->nvx * sizeof *c->u);
        for (int i = 0; i < c->nind; i++) ctc_traj_eval(&s->traj[i], t, c->des + 3 * i);
        c->law_in.t = t;
        c->law_in.q = q;
        c->law_in.v = v;
        c->law_in.xi = c->nx ? y + c->nq + c->nv : NULL;
        c->cls->law(&c->law_in, c->w);
        for (int i = 0; i < c->nind; i++) c->u[m->ind_coord[i]] = c->des[3 * i + 2] + c->w[i];
        if (forces && c->ctrl_model) {
            ctc_kinematics(c->ctrl_model, c->dc, q, v);
            ctc_handles(c->ctrl_model, c->dc);
            ctc_gdca_inverse(c->ctrl_model, c->dc, c->u, c->f);
        } else if (forces) {
            ctc_gdca_inverse(m, c->dp, c->u, c->f);
        }
        if (forces && m->has_loop) c->cond = c->dc->loop_cond;
    } else {
        memset(c->f, 0, (size_t)c->nvx * sizeof *c->f);
    }

    /* plant: qdd = GDCA(f + z) */
    memcpy(c->fz, c->f, (size_t)c->nvx * sizeof *c->fz);
    for (int i = 0; s->disturb && i < c->nind; i++)
        c->fz[m->ind_coord[i]] += ctc_disturb_eval(&s->disturb[i], t);
    if (!(what & SIM_EVAL_ACC)) return 0;
    ctc_gdca_forward(m, c->dp, c->fz, c->acc);
    c->evals++;
    c->eval_valid = 1;
    c->t_eval = t;
    memcpy(c->y_eval, y, (size_t)c->ny * sizeof *y);
    if (m->has_loop) {
        c->cond = fmax(c->cond, c->dp->loop_cond);
        if (!(c->cond <= c->cond_max)) return SIM_RHS_SINGULAR;
    }
    return 0;
}

int sim_rhs(double t, const double *y, double *ydot, void *ctx)
{
    sim_ctx *c = ctx;
    int rc = sim_evaluate(c, t, y, SIM_EVAL_FULL);
    memcpy(ydot + c->nq, c->acc, (size_t)c->nv * sizeof *ydot);
    ctc_model_q_rate(c->plant, c->has_quat ? c->qn : y, y + c->nq, ydot);
    if (c->nx)
        for (int i = 0; i < c->nind; i++) ydot[c->nq + c->nv + i] = c->des[3 * i] - c->qi[i];
    return rc;
}

/* The projection CVODE calls inside each bdf step (integrator.h ctc_ode_project): the residuals
 * at the step's end, and the state put back onto the closure when either exceeds loop_tol, as
 * the explicit methods' projection between steps does. Returns 0, or SIM_PROJ_FAILED with the
 * reason in c->proj_why. */
int sim_project(double t, double *y, void *ctx)
{
    sim_ctx *c = ctx;
    (void)t;
    c->eval_valid = 0; /* dp's kinematics are this state's now */
    ctc_kinematics(c->plant, c->dp, y, y + c->nq);
    ctc_loop_residual_norms(c->plant, c->dp, &c->proj_res[0], &c->proj_res[1]);
    c->proj_calls++;
    c->proj_moved = 0;
    if (!(c->proj_res[0] > c->loop_tol || c->proj_res[1] > c->loop_tol)) return 0;
    if (ctc_loop_assemble(c->plant, c->dp, y, y + c->nq, c->loop_tol, SIM_LOOP_MAX_ITER, NULL,
                          c->proj_why, sizeof c->proj_why) != CTC_OK)
        return SIM_PROJ_FAILED;
    c->proj_moved = 1;
    return 0;
}

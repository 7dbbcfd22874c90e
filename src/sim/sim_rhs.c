/*
 * sim_rhs.c - the right-hand side of a computed torque control run (sim.h, sim_internal.h): one
 * evaluation for the integrator, and what a sample needs of it.
 *
 * For the state y = (q (nq), v (nv), xi (nind when the controller has the integral state)) at
 * time t, in order:
 *     kinematics and body handle equations of the plant at (q, v)           (DESIGN.md 3)
 *     desired motion (q_d, qd_d, qdd_d)_i = traj_i(t)                       (traj.h)
 *     w = law(t, q, v, q_d, xi), u_i = qdd_d,i + w_i                         (ctrl.h, paper Eq. 18)
 *     f = iGDCA(controller model; q, v, u) (a baseline class: w, plus the inverse dynamics at
 *         (q, 0, 0) or at the desired state; ctrl.h ctc_ctrl_force), minus the joint forces tau_j
 * where the controller knows them                                          (paper Eq. 70) sat(f),
 * each actuator clipped at its limit when it has one             (plant.h) sat(f) + z(t), the
 * disturbance added to the applied forces             (disturb.h) qdd = GDCA(plant; q, v, sat(f) +
 * z + tau_j(q, v) + J^T W(t))           (paper section 3; the external wrenches W, wrench.h,
 * minus the known ones from f where the controller knows them) dy/dt = (qdot(q, v), qdd, e), with
 * d/dt int(e_i) = 0 while coordinate i is clipped and e_i pushes further into the limit (clamping
 * anti-windup, plant.h) A sampled controller (sim.h sample_period) runs the controller's part only
 * at its sample instants (sim_control_sample, from sim.c); in between, the evaluation applies the
 * held command and the integral state does not move. With an exact controller model the plant and
 * the controller share one ctc_data, so the kinematics and the body handle equations are computed
 * once per evaluation (Eq. 42-43). Spherical joints (passive runs only) are integrated as
 * quaternions; the evaluation reads a normalised copy. The law is called once per evaluation
 * through the class's pointer, for all coordinates at once; nothing here allocates. With
 * armature (plant.h) the plant's pass is ctc_plant_forward_armature, and a known armature adds
 * armature u to the controller's force.
 *
 * When the controller is a computed-torque one on the plant's own model, at the plant's own state
 * (no controller model, not sampled, no loop, no armature), its f_ref = iGDCA(q, v, u) is the
 * reference of the plant's pass: qdd = u + M^-1 (f_applied - f_ref) (gdca.h
 * ctc_gdca_forward_from), one bias-free forward sweep whose right-hand side is only what the
 * plant adds to the command (disturbance, clipping, joint forces, wrenches), so nothing cancels.
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

/* The forces of a baseline controller (ctrl.h ctc_ctrl_force) into c->f (nvx), from c->w and
 * the desired motion c->des, at positions q: w alone; or w plus the controller model's inverse
 * dynamics at (q, 0, 0), gravity; or at the desired state (q_d, qd_d, qdd_d), the feedforward.
 * The model's passes run on c->dc, the controller's own data (sim.c), so the plant's kinematics
 * in c->dp stay those of (q, v). Open chains only (sim_check.c): every coordinate is
 * controlled, so the desired state is whole. */
static void baseline_forces(sim_ctx *c, const double *q)
{
    const ctc_model *m = c->plant, *cm = c->ctrl_model ? c->ctrl_model : m;
    memset(c->u, 0, (size_t)c->nvx * sizeof *c->u);
    memset(c->f, 0, (size_t)c->nvx * sizeof *c->f);
    if (c->cls->force != CTC_FORCE_DIRECT) {
        double *qm = c->xq, *vm = c->xq + c->nq;
        memcpy(qm, q, (size_t)c->nq * sizeof *qm);
        memset(vm, 0, (size_t)c->nv * sizeof *vm);
        if (c->cls->force == CTC_FORCE_FEEDFORWARD) {
            for (int i = 0; i < c->nind; i++) {
                int k = m->ind_joint[i], off = m->ind_coord[i] - m->jnt_vadr[k];
                qm[m->jnt_qadr[k] + off] = c->des[3 * i];
                vm[m->ind_coord[i]] = c->des[3 * i + 1];
                c->u[m->ind_coord[i]] = c->des[3 * i + 2];
            }
        }
        ctc_kinematics(cm, c->dc, qm, vm);
        ctc_handles(cm, c->dc);
        ctc_gdca_inverse(cm, c->dc, c->u, c->f);
    }
    for (int i = 0; i < c->nind; i++) c->f[m->ind_coord[i]] += c->w[i];
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
    c->ref_valid = 0;
    if (c->has_quat) {
        memcpy(c->qn, q, (size_t)c->nq * sizeof *q);
        ctc_model_q_normalize(m, c->qn);
        q = c->qn;
    }

    if (what || m->has_loop) ctc_kinematics(m, c->dp, q, v);
    if (forces) ctc_handles(m, c->dp);
    controlled_coords(c, q, v);
    c->cond = 1;

    /* a sampled controller between its samples: the held command */
    if (c->active && c->sampled && !c->sampling_now) {
        for (int i = 0; i < c->nind; i++) ctc_traj_eval(&s->traj[i], t, c->des + 3 * i);
        memcpy(c->f, c->held, (size_t)c->nvx * sizeof *c->f);
        memcpy(c->w, c->held + c->nvx, (size_t)c->nind * sizeof *c->w);
        memcpy(c->clip, c->held + c->nvx + c->nind, (size_t)c->nind * sizeof *c->clip);
    } else if (c->active) {
        /* controller: the desired motion, w = law(...), u = qdd_d + w, f = iGDCA(u) */
        if (forces) memset(c->u, 0, (size_t)c->nvx * sizeof *c->u);
        for (int i = 0; i < c->nind; i++) ctc_traj_eval(&s->traj[i], t, c->des + 3 * i);
        c->law_in.t = t;
        c->law_in.q = q;
        c->law_in.v = v;
        c->law_in.xi = c->nx ? y + c->nq + c->nv : NULL;
        c->cls->law(&c->law_in, c->w);
        if (c->cls->force != CTC_FORCE_COMPUTED_TORQUE) {
            if (forces) baseline_forces(c, q);
        } else {
            for (int i = 0; i < c->nind; i++) c->u[m->ind_coord[i]] = c->des[3 * i + 2] + c->w[i];
            if (forces && c->ctrl_model) {
                ctc_kinematics(c->ctrl_model, c->dc, q, v);
                ctc_handles(c->ctrl_model, c->dc);
                ctc_gdca_inverse(c->ctrl_model, c->dc, c->u, c->f);
            } else if (forces) {
                ctc_gdca_inverse(m, c->dp, c->u, c->f);
                /* the forward pass's reference: the plant's own model at the plant's own state */
                memcpy(c->fref, c->f, (size_t)c->nvx * sizeof *c->fref);
                c->ref_valid = !c->sampled && !m->has_loop && !c->armed;
            }
        }
        if (forces && m->has_loop) c->cond = c->dc->loop_cond;
        /* a known armature: the plant's inverse dynamics add armature u (plant.h) */
        for (int i = 0; forces && c->armed && i < c->nind; i++)
            if (s->plant[i].known)
                c->f[m->ind_coord[i]] += s->plant[i].armature * c->u[m->ind_coord[i]];
        for (int i = 0; forces && c->jforces && i < c->nind; i++)
            if (s->plant[i].known)
                c->f[m->ind_coord[i]] -= ctc_plant_joint_force(&s->plant[i], c->qi[i], c->vi[i]);
        /* the wrenches the controller knows, at the state it sees (wrench.h) */
        if (forces && c->wknown) {
            memset(c->fext, 0, (size_t)c->nv * sizeof *c->fext);
            for (int k = 0; k < s->nwrenches; k++)
                if (s->wrenches[k].known) ctc_wrench_forces(m, c->dp, &s->wrenches[k], t, c->fext);
            for (int k = 0; k < c->nv; k++) c->f[k] -= c->fext[k];
        }
        /* the actuators' limits: f becomes sat(f), and clip keeps what was cut off */
        for (int i = 0; forces && c->limited && i < c->nind; i++) {
            double lim = s->plant[i].torque_limit, *fi = &c->f[m->ind_coord[i]];
            double sat = lim > 0 ? fmin(fmax(*fi, -lim), lim) : *fi;
            c->clip[i] = *fi - sat;
            *fi = sat;
        }
    } else {
        memset(c->f, 0, (size_t)c->nvx * sizeof *c->f);
    }

    /* plant: qdd = GDCA(sat(f) + z) */
    memcpy(c->fz, c->f, (size_t)c->nvx * sizeof *c->fz);
    for (int i = 0; s->disturb && i < c->nind; i++)
        c->fz[m->ind_coord[i]] += ctc_disturb_eval(&s->disturb[i], t);
    if (!(what & SIM_EVAL_ACC)) return 0;

    /* the joints' own forces, which the plant feels and the tau channel does not show */
    const double *fwd = c->fz;
    if (c->jforces || c->wrenched) {
        memcpy(c->fp, c->fz, (size_t)c->nvx * sizeof *c->fp);
        for (int i = 0; c->jforces && i < c->nind; i++)
            c->fp[m->ind_coord[i]] += ctc_plant_joint_force(&s->plant[i], c->qi[i], c->vi[i]);
        for (int k = 0; k < s->nwrenches; k++)
            ctc_wrench_forces(m, c->dp, &s->wrenches[k], t, c->fp);
        fwd = c->fp;
    }
    if (c->armed) {
        ctc_plant_forward_armature(m, c->dp, c->arm, fwd, c->acc, c->arm + c->nv);
    } else if (c->ref_valid) { /* qdd = u + M^-1 (f - iGDCA(u)): nothing to cancel */
        ctc_gdca_forward_from(m, c->dp, fwd, c->u, c->fref, c->acc);
    } else {
        ctc_gdca_forward(m, c->dp, fwd, c->acc);
    }
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
    for (int i = 0; i < c->nx; i++) {
        double e = c->des[3 * i] - c->qi[i];
        ydot[c->nq + c->nv + i] = c->sampled || (c->limited && e * c->clip[i] > 0) ? 0 : e;
    }
    return rc;
}

/* the state y as the sensors give it (plant.h), into c->ym: an open chain's controlled
   coordinates with noise and the encoder's counts, one draw per noisy term in coordinate order */
static const double *measure(sim_ctx *c, const double *y)
{
    const ctc_model *m = c->plant;
    memcpy(c->ym, y, (size_t)c->ny * sizeof *y);
    for (int i = 0; i < c->nind; i++) {
        const ctc_plant_coord *p = &c->spec->plant[i];
        int k = m->ind_joint[i], off = m->ind_coord[i] - m->jnt_vadr[k];
        double *q = &c->ym[m->jnt_qadr[k] + off], *v = &c->ym[c->nq + m->ind_coord[i]];
        if (p->noise_q > 0) *q += p->noise_q * ctc_plant_normal(&c->rng);
        if (p->noise_v > 0) *v += p->noise_v * ctc_plant_normal(&c->rng);
        if (p->resolution > 0) *q = p->resolution * round(*q / p->resolution);
    }
    return c->ym;
}

void sim_control_sample(sim_ctx *c, double t, double *y)
{
    const size_t width = (size_t)c->nvx + 2 * (size_t)c->nind;
    double *slot = c->ring + (size_t)(c->k_ctrl % (c->delay + 1)) * width;
    c->sampling_now = 1;
    sim_evaluate(c, t, c->sensed ? measure(c, y) : y, SIM_EVAL_FORCES);
    c->sampling_now = 0;
    memcpy(slot, c->f, (size_t)c->nvx * sizeof *slot);
    memcpy(slot + c->nvx, c->w, (size_t)c->nind * sizeof *slot);
    memcpy(slot + c->nvx + c->nind, c->clip, (size_t)c->nind * sizeof *slot);
    c->held = c->k_ctrl >= c->delay
                  ? c->ring + (size_t)((c->k_ctrl - c->delay) % (c->delay + 1)) * width
                  : c->ring + (size_t)(c->delay + 1) * width;
    /* xi_k+1 = xi_k + T e_k (e as measured), held while the command is clipped and e pushes into
       the limit */
    for (int i = 0; i < c->nx; i++) {
        double e = c->des[3 * i] - c->qi[i];
        if (!(c->limited && e * c->clip[i] > 0)) y[c->nq + c->nv + i] += c->spec->sample_period * e;
    }
    c->k_ctrl++;
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

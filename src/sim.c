/*
 * sim.c - the computed torque control loop (sim.h): right-hand side, stepping, sampling, metrics.
 *
 * The state integrated is y = (q (nq), v (nv), int e (nv with a controller)). One evaluation of
 * the right-hand side, for each coordinate i with desired (q_d, qd_d, qdd_d) = traj_i(t):
 *
 *     e_i = q_d - q_i,  de_i = qd_d - v_i,  w_i = ki ie_i + kp e_i + kv de_i,  u_i = qdd_d + w_i
 *     f = iGDCA(controller model; q, v, u)                           (paper Eq. 18, 70)
 *     qdd = GDCA(plant; q, v, f + z(t))                              (paper section 3)
 *     dy/dt = (qdot(q, v), qdd, e)
 *
 * With an exact controller model the plant and the controller share one ctc_data, so the
 * kinematics and the body handle equations are computed once per evaluation (Eq. 42-43).
 * Spherical joints (passive runs only) are integrated as quaternions; the right-hand side reads
 * a normalised copy, and samples report normalised quaternions.
 *
 * Between steps the loop checks the state for divergence (non-finite values, speeds beyond the
 * bound), polls for cancellation and the wall-time limit, and records every output sample that
 * falls in the step from the integrator's dense output. A sample costs only what its channels
 * and metrics read (sample_needs): on an open chain no forward pass, the inverse pass only for
 * the "tau" channel, the kinematics only for energy; a sample at the state of the last
 * right-hand side (the end of an rk4 or dopri5 step, t = 0) reuses that evaluation. The values
 * are bitwise those of a full evaluation. Discontinuities of the disturbance (step times) stop
 * the integrator exactly there and restart it. Everything is allocated before the first step.
 *
 * Accuracy figures: the integrator's error estimate; for passive runs without disturbance, the
 * energy drift; for an exact model without disturbance, the deviation of each coordinate's error
 * from the exact solution E(t) = expm(Ac t) E(0) of the linear error dynamics (ctrl.h), computed
 * here by propagating the 3x3 transition matrix of one output interval.
 *
 * Loop models: the controller's coordinates are the independent ones (c->nind; the closing
 * joint's position and rate come from the loop kinematics), the forces and accelerations of the
 * passes are extended vectors (nvx), and after each accepted step the state is checked against
 * the closure and, with projection, put back onto it (ctc_loop_assemble): for rk4 and dopri5
 * after the step, restarting the integrator there; for bdf inside the step (sim_project, called
 * by CVODE), because a restart sends CVODE back to order 1 and a short step, whose drift then
 * asks for the next projection, and so on after nearly every step (bench/NOTEBOOK.md, "Whole
 * simulations", "Reading it": BDF on the five-bar). An evaluation whose boundary solve is
 * singular beyond loop_cond_max returns SIM_RHS_SINGULAR, which ends the run as "singular" with the
 * time.
 */
#include "sim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "data.h"
#include "energy.h"
#include "gdca.h"
#include "handles.h"
#include "kinematics.h"

#define SIM_DEFAULT_MAX_SPEED 1e6
#define SIM_MAX_SAMPLES 50000000L
#define SIM_LOOP_MAX_ITER 50
#define SIM_RHS_SINGULAR 2 /* the right-hand side's code for a singular loop */
#define SIM_PROJ_FAILED 3  /* sim_project's code when the closure cannot be solved */

typedef struct sim_ctx {
    const ctc_sim_spec *spec;
    const ctc_model *plant;
    ctc_model *ctrl_model; /* NULL when the controller's model is the plant */
    ctc_data *dp, *dc;     /* dc == dp when the model is exact */
    int nq, nv, ny, active, has_quat;
    int nvx, nind;   /* extended and controlled coordinates (nv and nv for an open chain) */
    double *qn;      /* (nq) normalised positions */
    double *u, *f;   /* (nvx) commanded accelerations, controller forces */
    double *fz;      /* (nvx) applied forces f + z */
    double *acc;     /* (nvx) accelerations from the forward pass */
    double *w;       /* (nind) controller output */
    double *des;     /* (nind x 3) desired q, qd, qdd */
    double *qi, *vi; /* (nind) the controlled coordinates' positions and rates */
    double cond_max; /* loop models: singular beyond this condition estimate */
    double cond;     /* loop models: the last evaluation's condition estimate (max of passes) */
    double cond0;    /* loop models: the condition estimate at t = 0 */
    long evals;      /* evaluations with the forward pass (the right-hand side's) */
    /* bdf's in-step projection (sim_project): what its last call found and did */
    double loop_tol;    /* its trigger and Newton tolerance */
    long proj_calls;    /* calls so far */
    double proj_res[2]; /* the residuals (position, velocity) before the last call projected */
    int proj_moved;     /* the last call moved the state */
    char proj_why[200]; /* why the last call failed */
    /* the arrays above (and dp's kinematics) hold a full evaluation at (t_eval, y_eval) */
    int eval_valid;
    double t_eval;
    double *y_eval; /* (ny) */
} sim_ctx;

static const char *const ctrl_names[] = {"none", "pd", "pid", "poles", "lqr"};
static const char *const channel_names[] = {"q",   "qdot", "q_des",  "qdot_des", "e",
                                            "tau", "w",    "energy", "loop"};
static const char *const run_names[] = {"done",      "diverged", "failed",
                                        "cancelled", "timeout",  "singular"};
static const char *const stab_names[] = {"project", "baumgarte", "none"};

const char *ctc_ctrl_type_name(ctc_ctrl_type t)
{
    return (unsigned)t < 5 ? ctrl_names[t] : "unknown";
}

const char *ctc_channel_name(ctc_channel c)
{
    return (unsigned)c < CTC_NCHANNELS ? channel_names[c] : "unknown";
}

const char *ctc_run_status_name(ctc_run_status s)
{
    return (unsigned)s <= CTC_RUN_SINGULAR ? run_names[s] : "unknown";
}

const char *ctc_loop_stab_name(ctc_loop_stab s)
{
    return (unsigned)s <= CTC_LOOP_NONE ? stab_names[s] : "unknown";
}

static double now(clockid_t clock)
{
    struct timespec ts;
    clock_gettime(clock, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int has_disturbance(const ctc_sim_spec *s, int nv)
{
    if (!s->disturb) return 0;
    for (int i = 0; i < nv; i++)
        if (s->disturb[i].type != CTC_DISTURB_NONE) return 1;
    return 0;
}

/* the channels that apply: q, qdot, tau and energy always; the tracking ones with a controller;
 * loop with a loop model (added by the caller that knows the model) */
static unsigned channels_applicable(ctc_ctrl_type c)
{
    unsigned all = CTC_CH_ALL & ~CTC_CH_BIT(CTC_CH_LOOP);
    if (c == CTC_CTRL_NONE)
        all &= ~(CTC_CH_BIT(CTC_CH_Q_DES) | CTC_CH_BIT(CTC_CH_QD_DES) | CTC_CH_BIT(CTC_CH_E) |
                 CTC_CH_BIT(CTC_CH_W));
    return all;
}

static long sample_count(double duration, double dt)
{
    double n = floor(duration / dt * (1 + 1e-12));
    if (!(n < (double)SIM_MAX_SAMPLES)) return SIM_MAX_SAMPLES + 1;
    long count = (long)n + 1;
    if ((double)(count - 1) * dt < duration * (1 - 1e-12)) count++; /* a last sample at duration */
    return count;
}

static double sample_time(long j, long count, double duration, double dt)
{
    return j == count - 1 ? duration : (double)j * dt;
}

/* the spec's checks that do not need a model */
static ctc_status check_run(const ctc_sim_spec *s, char *err, size_t errlen)
{
    if (!isfinite(s->duration) || s->duration <= 0)
        return ctc_fail(CTC_EINVAL, err, errlen, "duration must be positive and finite (got %g s)",
                        s->duration);
    if (!isfinite(s->output_interval) || s->output_interval <= 0)
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "output interval must be positive and finite (got %g s)",
                        s->output_interval);
    if (s->output_interval > s->duration)
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "output interval (%g s) must not exceed the duration (%g s)",
                        s->output_interval, s->duration);
    if (sample_count(s->duration, s->output_interval) > SIM_MAX_SAMPLES)
        return ctc_fail(CTC_EINVAL, err, errlen, "more than %ld output samples", SIM_MAX_SAMPLES);
    if (!(s->max_speed >= 0) || isinf(s->max_speed))
        return ctc_fail(CTC_EINVAL, err, errlen, "max_speed must be >= 0 and finite (got %g)",
                        s->max_speed);
    if (!(s->wall_limit >= 0) || isinf(s->wall_limit))
        return ctc_fail(CTC_EINVAL, err, errlen, "wall_limit must be >= 0 and finite (got %g s)",
                        s->wall_limit);
    if (s->threads < 0 || s->threads > CTC_MAX_THREADS)
        return ctc_fail(CTC_EINVAL, err, errlen, "threads must be 0 to %d (got %d)",
                        CTC_MAX_THREADS, s->threads);
    if ((unsigned)s->controller > CTC_CTRL_LQR)
        return ctc_fail(CTC_EINVAL, err, errlen, "unknown controller type %d", (int)s->controller);
    unsigned bad = s->channels & ~channels_applicable(s->controller) & ~CTC_CH_BIT(CTC_CH_LOOP);
    if (s->channels & ~CTC_CH_ALL)
        return ctc_fail(CTC_EINVAL, err, errlen, "unknown output channel bits 0x%x",
                        s->channels & ~CTC_CH_ALL);
    for (int c = 0; c < CTC_NCHANNELS; c++)
        if (bad & CTC_CH_BIT(c))
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "channel \"%s\" needs a controller (this run is passive)",
                            channel_names[c]);
    if (s->controller != CTC_CTRL_NONE &&
        (!isfinite(s->model_mass_scale) || s->model_mass_scale <= 0))
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "model mass scale must be positive and finite (got %g)",
                        s->model_mass_scale);
    if (s->controller != CTC_CTRL_NONE &&
        (!isfinite(s->model_inertia_scale) || s->model_inertia_scale <= 0))
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "model inertia scale must be positive and finite (got %g)",
                        s->model_inertia_scale);
    if ((unsigned)s->loop_stab > CTC_LOOP_NONE)
        return ctc_fail(CTC_EINVAL, err, errlen, "unknown loop stabilisation %d",
                        (int)s->loop_stab);
    if (!(s->loop_tol >= 0) || isinf(s->loop_tol))
        return ctc_fail(CTC_EINVAL, err, errlen, "loop tolerance must be >= 0 and finite (got %g)",
                        s->loop_tol);
    for (int i = 0; i < 2; i++)
        if (!(s->baumgarte[i] >= 0) || isinf(s->baumgarte[i]))
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "Baumgarte gains must be >= 0 and finite (got %g)", s->baumgarte[i]);
    if (!(s->loop_cond_max == 0 || s->loop_cond_max > 1) || isinf(s->loop_cond_max))
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "loop condition limit must be > 1 and finite, or 0 (got %g)",
                        s->loop_cond_max);
    return ctc_integ_check(&s->integrator, err, errlen);
}

/* Routh-Hurwitz for s^3 + kv s^2 + kp s + ki, or s^2 + kv s + kp for PD (ctrl.h) */
static int gains_stable(const ctc_gains *g)
{
    if (g->ki == 0) return g->kp > 0 && g->kv > 0;
    return g->ki > 0 && g->kp > 0 && g->kv > 0 && g->kv * g->kp > g->ki;
}

/* the checks of the arrays against a built model */
static ctc_status check_with_model(const ctc_sim_spec *s, const ctc_model *m, char *err,
                                   size_t errlen)
{
    char why[200];
    for (int i = 0; s->q0 && i < m->nq; i++)
        if (!isfinite(s->q0[i]))
            return ctc_fail(CTC_EINVAL, err, errlen, "q0[%d] is not finite", i);
    for (int i = 0; s->v0 && i < m->nv; i++)
        if (!isfinite(s->v0[i]))
            return ctc_fail(CTC_EINVAL, err, errlen, "v0[%d] is not finite", i);
    if ((s->channels & CTC_CH_BIT(CTC_CH_LOOP)) && !m->has_loop)
        return ctc_fail(CTC_EINVAL, err, errlen, "channel \"loop\" needs a loop in the scene");
    if (s->controller != CTC_CTRL_NONE) {
        for (int k = 0; k < m->njoints; k++)
            if (m->joints[k].type == CTC_JOINT_SPHERICAL && m->jnt_indep[k])
                return ctc_fail(CTC_EINVAL, err, errlen,
                                "joint %d: spherical joints are allowed in passive runs only "
                                "(controller \"none\")%s",
                                k, m->has_loop ? ", or as dependent joints of a loop" : "");
        if (m->nind == 0)
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "a controller needs at least one independent coordinate");
        if (!s->gains || !s->traj)
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "a controller needs gains and a trajectory for every coordinate");
        for (int i = 0; i < m->nind; i++) {
            const ctc_gains *g = &s->gains[i];
            if (!isfinite(g->ki) || !isfinite(g->kp) || !isfinite(g->kv))
                return ctc_fail(CTC_EINVAL, err, errlen, "coordinate %d: gains are not finite", i);
            if (!gains_stable(g)) {
                double re[3], im[3];
                ctc_ctrl_closed_loop_poles(g, re, im);
                int j = re[2] >= re[1] && re[2] >= re[0] ? 2 : re[1] >= re[0] ? 1 : 0;
                char pole[64];
                if (fabs(im[j]) > 1e-12 * fabs(re[j]))
                    snprintf(pole, sizeof pole, "%g%+gi", re[j], im[j]);
                else
                    snprintf(pole, sizeof pole, "%g", re[j]);
                return ctc_fail(CTC_EINVAL, err, errlen,
                                "coordinate %d: gains (ki %g, kp %g, kv %g) make the error "
                                "dynamics unstable (pole at %s)",
                                i, g->ki, g->kp, g->kv, pole);
            }
            if (s->traj[i].type == CTC_TRAJ_SPLINE) {
                if (s->traj[i].nknots < 2 || !s->traj[i].knots)
                    return ctc_fail(CTC_EINVAL, err, errlen,
                                    "coordinate %d: trajectory spline is not built", i);
            } else if (ctc_traj_check(&s->traj[i], why, sizeof why) != CTC_OK) {
                return ctc_fail(CTC_EINVAL, err, errlen, "coordinate %d: trajectory: %s", i, why);
            }
        }
    }
    for (int i = 0; s->disturb && i < m->nind; i++)
        if (ctc_disturb_check(&s->disturb[i], why, sizeof why) != CTC_OK)
            return ctc_fail(CTC_EINVAL, err, errlen, "coordinate %d: disturbance: %s", i, why);
    return CTC_OK;
}

/* the projection's trigger and Newton's tolerance (m, rad) */
static double loop_tol_of(const ctc_sim_spec *s)
{
    return s->loop_tol > 0 ? s->loop_tol : CTC_SIM_DEFAULT_LOOP_TOL;
}

/* The spec's initial state (q0 normalised, v0) in q (nq) and v (nv), put onto the loop's closure
 * and checked there (loop.h). A closure that fails is explained by the mobility checks at q0
 * when they fail too. */
static ctc_status close_initial_state(const ctc_sim_spec *s, const ctc_model *m, ctc_data *d,
                                      double *q, double *v, ctc_loop_fix *fix, char *err,
                                      size_t errlen)
{
    if (s->q0)
        memcpy(q, s->q0, (size_t)m->nq * sizeof *q);
    else
        ctc_model_q_zero(m, q);
    ctc_model_q_normalize(m, q);
    for (int i = 0; i < m->nv; i++) v[i] = s->v0 ? s->v0[i] : 0;
    if (!m->has_loop) return CTC_OK;

    double tol = loop_tol_of(s);
    char why[300];
    if (ctc_loop_assemble(m, d, q, v, tol, SIM_LOOP_MAX_ITER, fix, why, sizeof why) != CTC_OK) {
        double *q0 = malloc(((size_t)m->nq + 1) * sizeof *q0);
        if (!q0) return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
        if (s->q0)
            memcpy(q0, s->q0, (size_t)m->nq * sizeof *q0);
        else
            ctc_model_q_zero(m, q0);
        ctc_model_q_normalize(m, q0);
        ctc_status st = ctc_loop_check(m, d, q0, NULL, err, errlen);
        free(q0);
        if (st != CTC_OK) return st;
        return ctc_fail(CTC_EINVAL, err, errlen, "q0: %s", why);
    }
    return ctc_loop_check(m, d, q, NULL, err, errlen);
}

ctc_status ctc_sim_check(const ctc_sim_spec *spec, char *err, size_t errlen)
{
    ctc_status st = check_run(spec, err, errlen);
    if (st != CTC_OK) return st;
    ctc_model *m = NULL;
    st = ctc_model_build(&spec->chain, &m, err, errlen);
    if (st != CTC_OK) return st;
    st = check_with_model(spec, m, err, errlen);
    if (st == CTC_OK && m->has_loop) {
        ctc_data *d = ctc_data_new(m);
        double *qv = malloc(((size_t)m->nq + (size_t)m->nv + 1) * sizeof *qv);
        if (!d || !qv) {
            st = ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
        } else {
            ctc_loop_fix fix;
            st = close_initial_state(spec, m, d, qv, qv + m->nq, &fix, err, errlen);
        }
        free(qv);
        ctc_data_free(d);
    }
    ctc_model_free(m);
    return st;
}

/* the controller's model: the plant's chain with masses and inertias scaled */
static ctc_status build_controller_model(const ctc_sim_spec *s, ctc_model **out, char *err,
                                         size_t errlen)
{
    int n = s->chain.nbodies;
    ctc_body_spec *b = malloc((size_t)n * sizeof *b);
    if (!b) return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    for (int k = 0; k < n; k++) {
        b[k] = s->chain.bodies[k];
        b[k].mass *= s->model_mass_scale;
        for (int j = 0; j < 9; j++) b[k].inertia[j] *= s->model_inertia_scale;
    }
    ctc_chain_spec c = s->chain;
    c.bodies = b;
    c.form = CTC_FORM_AUTO;
    char why[200];
    ctc_status st = ctc_model_build(&c, out, why, sizeof why);
    free(b);
    if (st != CTC_OK)
        return ctc_fail(st, err, errlen, "controller model (scaled masses and inertias): %s", why);
    return CTC_OK;
}

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

/* What an evaluation computes, as bits (evaluate): the right-hand side needs all; a sample
 * only what its channels and metrics read (record_sample). The desired motion, the controller
 * output w and the applied forces' disturbance part are always computed (a few flops). */
enum {
    SIM_EVAL_KIN = 1,    /* the plant's kinematics (energy, loop residuals) */
    SIM_EVAL_FORCES = 2, /* and the handles and the inverse pass: the driving forces f */
    SIM_EVAL_ACC = 4,    /* and the forward pass: the accelerations */
    SIM_EVAL_FULL = 7
};

/* Driving forces and accelerations of state (q, v, ie) at time t, as far as `what` asks: fills
 * ctx's arrays (the force arrays and c->acc (nvx) when asked for) and dp's kinematics. A loop
 * model always gets its kinematics (the closing joint's coordinates come from them). Returns 0,
 * or SIM_RHS_SINGULAR when a loop's boundary solve is singular. A full evaluation is remembered
 * (t_eval, y_eval), so a sample taken at exactly that state reuses it (record_sample). */
static int evaluate(sim_ctx *c, double t, const double *y, unsigned what)
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

    /* controller: u = qdd_d + K (int e, e, de), f = iGDCA(u) */
    if (c->active) {
        const double *ie = y + c->nq + c->nv;
        if (forces) memset(c->u, 0, (size_t)c->nvx * sizeof *c->u);
        for (int i = 0; i < c->nind; i++) {
            double *d = c->des + 3 * i;
            ctc_traj_eval(&s->traj[i], t, d);
            const ctc_gains *g = &s->gains[i];
            c->w[i] = g->ki * ie[i] + g->kp * (d[0] - c->qi[i]) + g->kv * (d[1] - c->vi[i]);
            c->u[m->ind_coord[i]] = d[2] + c->w[i];
        }
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

static int sim_rhs(double t, const double *y, double *ydot, void *ctx)
{
    sim_ctx *c = ctx;
    int rc = evaluate(c, t, y, SIM_EVAL_FULL);
    memcpy(ydot + c->nq, c->acc, (size_t)c->nv * sizeof *ydot);
    ctc_model_q_rate(c->plant, c->has_quat ? c->qn : y, y + c->nq, ydot);
    if (c->active)
        for (int i = 0; i < c->nind; i++) ydot[c->nq + c->nv + i] = c->des[3 * i] - c->qi[i];
    return rc;
}

/* The projection CVODE calls inside each bdf step (integrator.h ctc_ode_project): the residuals
 * at the step's end, and the state put back onto the closure when either exceeds loop_tol, as
 * the explicit methods' projection between steps does. Returns 0, or SIM_PROJ_FAILED with the
 * reason in c->proj_why. */
static int sim_project(double t, double *y, void *ctx)
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

/* the joint that owns velocity coordinate i */
static int joint_of(const ctc_model *m, int i)
{
    int k = 0;
    while (k + 1 < m->nbodies && m->jnt_vadr[k + 1] <= i) k++;
    return k;
}

/* checks an accepted state; on divergence fills the message and the joint and returns 1 */
static int diverged(const sim_ctx *c, double t, const double *y, double bound, ctc_sim_result *r)
{
    const double *v = y + c->nq;
    for (int i = 0; i < c->ny; i++) {
        if (isfinite(y[i])) continue;
        int vi = i < c->nq ? -1 : i < c->nq + c->nv ? i - c->nq : -2;
        int k = 0;
        if (vi == -2) { /* an integral state: its controlled coordinate's joint */
            k = c->plant->ind_joint[i - c->nq - c->nv];
        } else if (vi >= 0) {
            k = joint_of(c->plant, vi);
        } else {
            while (k + 1 < c->plant->nbodies && c->plant->jnt_qadr[k + 1] <= i) k++;
        }
        r->metrics.diverged_joint = k;
        snprintf(r->message, sizeof r->message, "t = %.6g s: joint %d state is not finite", t, k);
        return 1;
    }
    for (int i = 0; i < c->nv; i++) {
        if (fabs(v[i]) <= bound) continue;
        int k = joint_of(c->plant, i);
        int lin = c->plant->joints[k].type == CTC_JOINT_PRISMATIC ||
                  (c->plant->joints[k].type == CTC_JOINT_CYLINDRICAL && i > c->plant->jnt_vadr[k]);
        r->metrics.diverged_joint = k;
        snprintf(r->message, sizeof r->message,
                 "t = %.6g s: joint %d speed %.3g %s exceeds the bound %g", t, k, fabs(v[i]),
                 lin ? "m/s" : "rad/s", bound);
        return 1;
    }
    return 0;
}

/* 3x3 matrix exponential by scaling and squaring of a degree-18 Taylor polynomial */
static void expm3(const double a[9], double t, double out[9])
{
    double norm = 0;
    for (int i = 0; i < 9; i++) norm = fmax(norm, fabs(a[i] * t));
    int squarings = 0;
    while (norm * 3 > 0.5 && squarings < 60) {
        norm *= 0.5;
        squarings++;
    }
    double scale = ldexp(t, -squarings), x[9], term[9], sum[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (int i = 0; i < 9; i++) x[i] = a[i] * scale;
    memcpy(term, sum, sizeof term);
    for (int k = 1; k <= 18; k++) {
        double next[9];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                next[3 * i + j] =
                    (term[3 * i] * x[j] + term[3 * i + 1] * x[3 + j] + term[3 * i + 2] * x[6 + j]) /
                    k;
        memcpy(term, next, sizeof term);
        for (int i = 0; i < 9; i++) sum[i] += term[i];
    }
    for (int s = 0; s < squarings; s++) {
        double sq[9];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                sq[3 * i + j] =
                    sum[3 * i] * sum[j] + sum[3 * i + 1] * sum[3 + j] + sum[3 * i + 2] * sum[6 + j];
        memcpy(sum, sq, sizeof sum);
    }
    memcpy(out, sum, sizeof sum);
}

static void closed_loop_matrix(const ctc_gains *g, double a[9])
{
    /* d/dt (int e, e, de) = Ac (int e, e, de): ee = -ki int e - kp e - kv de */
    const double ac[9] = {0, 1, 0, 0, 0, 1, -g->ki, -g->kp, -g->kv};
    memcpy(a, ac, sizeof ac);
}

/* run-time state of the sampling and the metrics */
typedef struct recorder {
    ctc_sim_result *r;
    long count, next; /* samples in all, the next to take */
    double dt;
    double *ysample;  /* (ny) */
    unsigned eval;    /* SIM_EVAL_* bits a sample needs (sample_needs) */
    double *loop_max; /* loop models: the max residuals (position, velocity) so far */
    /* error-dynamics reference (exact model, no disturbance) */
    int track_errdyn;
    double *phi;  /* (nv x 9) transition matrix over one interval */
    double *eref; /* (nv x 3) reference error state at the last sample */
    double t_ref; /* time of eref */
    double *e_sq; /* (nv) sum of e^2 */
    /* energy reference (passive, no disturbance) */
    int track_energy;
    double e0, ke_max, drift;
} recorder;

/* What a sample needs of an evaluation at its state. Its outputs are q, v, the desired motion,
 * e and w (no pass needed); the driving forces (the inverse pass, with a controller); the energy
 * (the kinematics). A loop model's sample takes a full evaluation: the forward pass's boundary
 * solve has its own condition estimate, which metrics.loop_cond_max reports at the samples. No
 * sample needs the forward pass's accelerations otherwise. */
static unsigned sample_needs(const sim_ctx *c, const recorder *rec)
{
    const ctc_sim_result *r = rec->r;
    if (c->plant->has_loop) return SIM_EVAL_FULL;
    unsigned what = 0;
    if (r->ch[CTC_CH_TAU] && c->active) what |= SIM_EVAL_FORCES;
    if (r->ch[CTC_CH_ENERGY] || rec->track_energy) what |= SIM_EVAL_KIN;
    return what;
}

/* Records sample j = r->nsamples at (t, y): its channels and its share of the metrics. A sample
 * at the state of the last full evaluation (an explicit step's end, t = 0) reuses it; otherwise
 * it evaluates what sample_needs says, with the very same calls as the right-hand side, so the
 * values are bitwise those a full evaluation would give. */
static void record_sample(sim_ctx *c, recorder *rec, double t, const double *y)
{
    ctc_sim_result *r = rec->r;
    long j = r->nsamples;
    if (!(c->eval_valid && t == c->t_eval && memcmp(y, c->y_eval, (size_t)c->ny * sizeof *y) == 0))
        evaluate(c, t, y, rec->eval);
    r->t[j] = t;
    const double *q = c->has_quat ? c->qn : y, *v = y + c->nq;
    const int *ic = c->plant->ind_coord;
    double res[2] = {0, 0};
    if (c->plant->has_loop) {
        ctc_loop_residual_norms(c->plant, c->dp, &res[0], &res[1]);
        rec->loop_max[0] = fmax(rec->loop_max[0], res[0]);
        rec->loop_max[1] = fmax(rec->loop_max[1], res[1]);
        r->metrics.loop_cond_max = fmax(r->metrics.loop_cond_max, c->cond);
    }
    for (int ch = 0; ch < CTC_NCHANNELS; ch++) {
        double *out = r->ch[ch];
        if (!out) continue;
        out += (size_t)j * (size_t)r->width[ch];
        for (int i = 0; i < r->width[ch]; i++) {
            switch ((ctc_channel)ch) {
            case CTC_CH_Q:
                out[i] = q[i];
                break;
            case CTC_CH_QD:
                out[i] = v[i];
                break;
            case CTC_CH_Q_DES:
                out[i] = c->des[3 * i];
                break;
            case CTC_CH_QD_DES:
                out[i] = c->des[3 * i + 1];
                break;
            case CTC_CH_E:
                out[i] = c->des[3 * i] - c->qi[i];
                break;
            case CTC_CH_TAU:
                out[i] = c->fz[ic[i]];
                break;
            case CTC_CH_LOOP:
                out[i] = res[i];
                break;
            case CTC_CH_W:
                out[i] = c->w[i];
                break;
            default:
                break;
            }
        }
    }
    double ke = 0, pe = 0;
    if (r->ch[CTC_CH_ENERGY] || rec->track_energy) {
        ctc_energy(c->plant, c->dp, &ke, &pe);
        if (r->ch[CTC_CH_ENERGY]) {
            r->ch[CTC_CH_ENERGY][2 * j] = ke;
            r->ch[CTC_CH_ENERGY][2 * j + 1] = pe;
        }
    }
    ctc_sim_metrics *mt = &r->metrics;
    if (c->active) {
        for (int i = 0; i < c->nind; i++) {
            double e = c->des[3 * i] - c->qi[i];
            mt->e_max[i] = fmax(mt->e_max[i], fabs(e));
            rec->e_sq[i] += e * e;
            mt->e_final[i] = e;
        }
    }
    if (rec->track_energy) {
        if (j == 0) rec->e0 = ke + pe;
        rec->ke_max = fmax(rec->ke_max, ke);
        rec->drift = fmax(rec->drift, fabs(ke + pe - rec->e0));
    }
    if (rec->track_errdyn) {
        const double *ie = y + c->nq + c->nv;
        for (int i = 0; i < c->nind; i++) {
            double *er = rec->eref + 3 * i;
            if (j == 0) {
                mt->errdyn_dev = 0;
                er[0] = ie[i], er[1] = c->des[3 * i] - c->qi[i];
                er[2] = c->des[3 * i + 1] - c->vi[i];
            } else {
                double phi[9], next[3];
                const double *p = rec->phi + 9 * i;
                if (fabs(t - rec->t_ref - rec->dt) > 1e-9 * rec->dt) { /* the shorter last step */
                    double a[9];
                    closed_loop_matrix(&c->spec->gains[i], a);
                    expm3(a, t - rec->t_ref, phi);
                    p = phi;
                }
                for (int k = 0; k < 3; k++)
                    next[k] = p[3 * k] * er[0] + p[3 * k + 1] * er[1] + p[3 * k + 2] * er[2];
                memcpy(er, next, sizeof next);
                mt->errdyn_dev = fmax(mt->errdyn_dev, fabs(c->des[3 * i] - c->qi[i] - er[1]));
            }
        }
        rec->t_ref = t;
    }
    r->nsamples++;
}

static ctc_status alloc_result(const sim_ctx *c, unsigned channels, long count,
                               ctc_sim_result **out)
{
    ctc_sim_result *r = calloc(1, sizeof *r);
    if (!r) return CTC_ENOMEM;
    *out = r;
    r->nq = c->nq, r->nv = c->nv, r->nind = c->nind, r->channels = channels;
    r->t = malloc((size_t)count * sizeof *r->t);
    if (!r->t) return CTC_ENOMEM;
    for (int ch = 0; ch < CTC_NCHANNELS; ch++) {
        if (!(channels & CTC_CH_BIT(ch))) continue;
        r->width[ch] = ch == CTC_CH_Q                             ? c->nq
                       : ch == CTC_CH_QD                          ? c->nv
                       : ch == CTC_CH_ENERGY || ch == CTC_CH_LOOP ? 2
                                                                  : c->nind;
        if (r->width[ch] == 0) continue;
        r->ch[ch] = malloc((size_t)count * (size_t)r->width[ch] * sizeof(double));
        if (!r->ch[ch]) return CTC_ENOMEM;
    }
    ctc_sim_metrics *mt = &r->metrics;
    mt->form = c->plant->form;
    mt->nv = c->nind;
    mt->energy_drift = NAN;
    mt->loop_res_max = mt->loop_vres_max = mt->loop_cond_max = NAN;
    if (c->plant->has_loop) mt->loop_cond_max = 0;
    mt->errdyn_dev = NAN;
    mt->err_estimate = NAN;
    mt->diverged_joint = -1;
    if (c->active) {
        mt->e_max = calloc((size_t)c->nind + 1, sizeof(double));
        mt->e_rms = calloc((size_t)c->nind + 1, sizeof(double));
        mt->e_final = calloc((size_t)c->nind + 1, sizeof(double));
        if (!mt->e_max || !mt->e_rms || !mt->e_final) return CTC_ENOMEM;
    }
    return CTC_OK;
}

void ctc_sim_result_free(ctc_sim_result *r)
{
    if (!r) return;
    free(r->t);
    for (int ch = 0; ch < CTC_NCHANNELS; ch++) free(r->ch[ch]);
    free(r->metrics.e_max);
    free(r->metrics.e_rms);
    free(r->metrics.e_final);
    free(r);
}

static void ctx_free(sim_ctx *c)
{
    if (c->dc != c->dp) ctc_data_free(c->dc);
    ctc_data_free(c->dp);
    ctc_model_free(c->ctrl_model);
    free(c->qn);
    free(c->u);
    free(c->y_eval);
}

/* The message of a run stopped as singular at time t, why saying what stopped it; the estimate
 * that stopped it belongs in the metrics too, not only the samples' */
static void singular_message(ctc_sim_result *r, double t, const sim_ctx *c, const char *why)
{
    r->metrics.loop_cond_max = fmax(r->metrics.loop_cond_max, c->cond);
    snprintf(r->message, sizeof r->message,
             "t = %.6g s: the independent joints cannot drive the loop here (condition estimate "
             "%.3g%s)",
             t, c->cond, why);
}

/* stopped because the condition estimate passed the limit */
static void singular_limit(ctc_sim_result *r, double t, const sim_ctx *c)
{
    char why[64];
    snprintf(why, sizeof why, " > %g", c->cond_max);
    singular_message(r, t, c, why);
}

/* A dependent joint's speed passing the bound while the condition estimate has grown by
 * SIM_SINGULAR_GROWTH since t = 0 is the loop running into a singular configuration: near it the
 * dependent joints' speeds grow like 1 / distance, faster than the estimate reaches cond_max
 * (test_hard: the five-bar's dyad straightening, speed 1e6 rad/s at an estimate of 5.7e4 from 5).
 * Then the run is reported as singular, with both figures; returns 1. */
#define SIM_SINGULAR_GROWTH 100.0
static int singular_divergence(const sim_ctx *c, double t, double bound, ctc_sim_result *r)
{
    const int k = r->metrics.diverged_joint;
    if (!c->plant->has_loop || k < 0 || c->plant->jnt_indep[k]) return 0;
    if (!(c->cond > SIM_SINGULAR_GROWTH * c->cond0)) return 0;
    char why[128];
    snprintf(why, sizeof why,
             ", from %.3g at the start; dependent joint %d passed the speed bound %g", c->cond0, k,
             bound);
    singular_message(r, t, c, why);
    return 1;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

ctc_status ctc_sim_run(const ctc_sim_spec *spec, const ctc_sim_hooks *hooks, ctc_sim_result **out,
                       char *err, size_t errlen)
{
    static const ctc_sim_hooks no_hooks = {0};
    if (!hooks) hooks = &no_hooks;
    *out = NULL;
    ctc_status st = check_run(spec, err, errlen);
    if (st != CTC_OK) return st;

    double wall0 = now(CLOCK_MONOTONIC), cpu0 = now(CLOCK_THREAD_CPUTIME_ID);
    sim_ctx c = {.spec = spec};
    ctc_model *plant = NULL;
    ctc_integrator *integ = NULL;
    ctc_sim_result *r = NULL;
    recorder rec = {0};
    double *ybuf = NULL, *breaks = NULL;

    st = ctc_model_build(&spec->chain, &plant, err, errlen);
    if (st != CTC_OK) return st;
    c.plant = plant;
    st = check_with_model(spec, plant, err, errlen);
    if (st != CTC_OK) goto cleanup;

    /* sizes and scratch */
    c.nq = plant->nq, c.nv = plant->nv, c.nvx = plant->nvx, c.nind = plant->nind;
    c.active = spec->controller != CTC_CTRL_NONE;
    c.ny = c.nq + c.nv + (c.active ? c.nind : 0);
    c.cond_max = spec->loop_cond_max > 0 ? spec->loop_cond_max : CTC_SIM_DEFAULT_COND_MAX;
    for (int k = 0; k < plant->nbodies; k++)
        c.has_quat |= plant->joints[k].type == CTC_JOINT_SPHERICAL;
    int exact = !c.active || (spec->model_mass_scale == 1 && spec->model_inertia_scale == 1);
    if (!exact) {
        st = build_controller_model(spec, &c.ctrl_model, err, errlen);
        if (st != CTC_OK) goto cleanup;
    }
    size_t nq = (size_t)c.nq, nv = (size_t)c.nind + 1, nvx = (size_t)c.nvx + 1;
    c.dp = ctc_data_new(plant);
    c.dc = c.ctrl_model ? ctc_data_new(c.ctrl_model) : c.dp;
    c.qn = malloc((nq + 1) * sizeof(double));
    c.u = malloc((nvx * 4 + nv * 6) * sizeof(double));
    ybuf = malloc((size_t)(c.ny + 1) * 3 * sizeof(double) + 2 * sizeof(double));
    c.y_eval = malloc((size_t)(c.ny + 1) * sizeof(double));
    if (!c.dp || !c.dc || !c.qn || !c.u || !ybuf || !c.y_eval) {
        st = ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
        goto cleanup;
    }
    if (spec->threads > 1) { /* one set of workers for both models */
        st = ctc_data_set_threads(c.dp, spec->threads, err, errlen);
        if (st != CTC_OK) goto cleanup;
        ctc_data_share_pool(c.dc, c.dp);
    }
    c.f = c.u + nvx, c.fz = c.f + nvx, c.acc = c.fz + nvx, c.w = c.acc + nvx;
    c.des = c.w + nv, c.qi = c.des + 3 * nv, c.vi = c.qi + nv;
    memset(c.w, 0, nv * 6 * sizeof(double));
    if (plant->has_loop) {
        ctc_loop_stab stab = spec->loop_stab;
        double a = spec->baumgarte[0], b = spec->baumgarte[1];
        if (a == 0 && b == 0) a = b = CTC_SIM_DEFAULT_BAUMGARTE;
        c.dp->baumgarte[0] = stab == CTC_LOOP_BAUMGARTE ? a : 0;
        c.dp->baumgarte[1] = stab == CTC_LOOP_BAUMGARTE ? b : 0;
    }

    /* the result, sized for every sample */
    unsigned channels = spec->channels ? spec->channels : channels_applicable(spec->controller);
    if (!spec->channels && plant->has_loop) channels |= CTC_CH_BIT(CTC_CH_LOOP);
    rec.count = sample_count(spec->duration, spec->output_interval);
    rec.dt = spec->output_interval;
    st = alloc_result(&c, channels, rec.count, &r);
    if (st != CTC_OK) {
        st = ctc_fail(CTC_ENOMEM, err, errlen, "out of memory for %ld samples", rec.count);
        goto cleanup;
    }
    rec.r = r;
    rec.ysample = ybuf + c.ny + 1;
    double *yproj = rec.ysample + c.ny + 1;
    rec.loop_max = yproj + c.ny + 1;
    rec.loop_max[0] = rec.loop_max[1] = 0;
    rec.track_energy = !c.active && !has_disturbance(spec, c.nind);
    rec.track_errdyn = c.active && exact && !has_disturbance(spec, c.nind);
    rec.eval = sample_needs(&c, &rec);
    rec.e_sq = calloc(nv, sizeof(double));
    rec.phi = calloc(nv * 12, sizeof(double));
    if (!rec.e_sq || !rec.phi) {
        st = ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
        goto cleanup;
    }
    rec.eref = rec.phi + 9 * nv;
    if (rec.track_errdyn) {
        for (int i = 0; i < c.nind; i++) {
            double a[9];
            closed_loop_matrix(&spec->gains[i], a);
            expm3(a, rec.dt, rec.phi + 9 * i);
        }
    }

    /* the integrator; rk4's step is shortened to divide the output interval */
    ctc_integ_spec is = spec->integrator;
    if (is.method == CTC_INTEG_RK4) is.step = rec.dt / ceil(rec.dt / is.step * (1 - 1e-12));
    st = ctc_integrator_new(&is, c.ny, sim_rhs, &c, &integ, err, errlen);
    if (st != CTC_OK) goto cleanup;

    /* discontinuities, sorted: the integrator stops and restarts at each - disturbance steps, and
       the ends of splines, where a clamped spline's acceleration jumps to zero */
    int nbreaks = 0;
    breaks = malloc(3 * nv * sizeof(double));
    if (!breaks) {
        st = ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
        goto cleanup;
    }
    for (int i = 0; i < c.nind; i++) {
        double tb[3] = {spec->disturb ? ctc_disturb_breakpoint(&spec->disturb[i]) : INFINITY,
                        INFINITY, INFINITY};
        if (c.active && spec->traj[i].type == CTC_TRAJ_SPLINE) {
            const ctc_traj *tr = &spec->traj[i];
            tb[1] = tr->knots[0], tb[2] = tr->knots[5 * (tr->nknots - 1)];
        }
        for (int k = 0; k < 3; k++)
            if (tb[k] > 0 && tb[k] < spec->duration) breaks[nbreaks++] = tb[k];
    }
    qsort(breaks, (size_t)nbreaks, sizeof(double), cmp_double);

    /* initial state, on the loop's closure */
    double *y0 = ybuf;
    st = close_initial_state(spec, plant, c.dp, y0, y0 + c.nq, &r->metrics.initial, err, errlen);
    if (st != CTC_OK) goto cleanup;
    for (int i = c.nq + c.nv; i < c.ny; i++) y0[i] = 0;
    double loop_tol = loop_tol_of(spec);
    c.loop_tol = loop_tol;
    /* bdf projects inside its steps and keeps its history; rk4 and dopri5 between steps */
    int in_step =
        plant->has_loop && spec->loop_stab == CTC_LOOP_PROJECT && is.method == CTC_INTEG_BDF;
    if (in_step) {
        st = ctc_integrator_set_projection(integ, sim_project, err, errlen);
        if (st != CTC_OK) goto cleanup;
    }

    double bound = spec->max_speed > 0 ? spec->max_speed : SIM_DEFAULT_MAX_SPEED;
    ctc_run_status status = CTC_RUN_DONE;
    char why[200] = "";
    double t = 0;
    /* the integrator's start evaluates f there, and the first sample reuses that evaluation */
    int rc0 = ctc_integrator_reset(integ, 0, y0);
    if (rc0 == SIM_RHS_SINGULAR) {
        status = CTC_RUN_SINGULAR;
        singular_limit(r, 0, &c);
    } else if (diverged(&c, 0, y0, bound, r)) {
        status = CTC_RUN_DIVERGED;
    } else if (rc0 != 0) {
        status = CTC_RUN_FAILED;
    } else {
        c.cond0 = c.cond;
        record_sample(&c, &rec, 0, y0);
        rec.next = 1;
    }

    /* the loop: one accepted step at a time */
    int ib = 0;
    while (status == CTC_RUN_DONE && rec.next < rec.count) {
        double tstop = ib < nbreaks ? breaks[ib] : spec->duration;
        /* rk4's step divides the output interval: stopping at each sample time makes every
           sample a step's end exactly, where it reuses the step's last evaluation (record_sample)
           rather than interpolate at a time a few ulps off the accumulated step ends */
        if (is.method == CTC_INTEG_RK4)
            tstop = fmin(tstop, sample_time(rec.next, rec.count, spec->duration, rec.dt));
        long proj_calls = c.proj_calls;
        int rc = ctc_integrator_step(integ, tstop, why, sizeof why);
        t = ctc_integrator_time(integ);
        const double *y = ctc_integrator_state(integ);
        if (rc == SIM_PROJ_FAILED) {
            status = CTC_RUN_SINGULAR;
            snprintf(r->message, sizeof r->message, "t = %.6g s: projection: %s", t, c.proj_why);
            break;
        }
        if (rc == SIM_RHS_SINGULAR) {
            status = CTC_RUN_SINGULAR;
            singular_limit(r, t, &c);
            break;
        }
        if (rc != 0) {
            status = CTC_RUN_FAILED;
            snprintf(r->message, sizeof r->message, "integrator: %s", why);
            break;
        }
        if (diverged(&c, t, y, bound, r)) {
            status = singular_divergence(&c, t, bound, r) ? CTC_RUN_SINGULAR : CTC_RUN_DIVERGED;
            break;
        }
        /* the samples inside this step */
        while (rec.next < rec.count) {
            double ts = sample_time(rec.next, rec.count, spec->duration, rec.dt);
            if (ts > t) break;
            ctc_integrator_dense(integ, ts, rec.ysample);
            record_sample(&c, &rec, ts, rec.ysample);
            rec.next++;
            if (hooks->progress) hooks->progress(hooks->ctx, ts / spec->duration);
        }
        int restart = 0;
        if (ib < nbreaks && t >= breaks[ib]) {
            while (ib < nbreaks && breaks[ib] <= t) ib++;
            restart = 1;
        }
        if (plant->has_loop) { /* the drift at the step's end, and the projection */
            double pos, vel;
            c.eval_valid = 0; /* dp's kinematics are this state's now */
            ctc_kinematics(plant, c.dp, y, y + c.nq);
            ctc_loop_residual_norms(plant, c.dp, &pos, &vel);
            if (in_step && c.proj_calls > proj_calls) {
                /* CVODE projected inside the step: its last call was the accepted attempt's,
                   and the drift is what that call found */
                pos = fmax(pos, c.proj_res[0]);
                vel = fmax(vel, c.proj_res[1]);
                r->metrics.projections += c.proj_moved;
            }
            rec.loop_max[0] = fmax(rec.loop_max[0], pos);
            rec.loop_max[1] = fmax(rec.loop_max[1], vel);
            if (!in_step && spec->loop_stab == CTC_LOOP_PROJECT &&
                (pos > loop_tol || vel > loop_tol)) {
                memcpy(yproj, y, (size_t)c.ny * sizeof *y);
                if (ctc_loop_assemble(plant, c.dp, yproj, yproj + c.nq, loop_tol, SIM_LOOP_MAX_ITER,
                                      NULL, why, sizeof why) != CTC_OK) {
                    status = CTC_RUN_SINGULAR;
                    snprintf(r->message, sizeof r->message, "t = %.6g s: projection: %s", t, why);
                    break;
                }
                r->metrics.projections++;
                y = yproj;
                restart = 1;
            }
        }
        if (restart) {
            int rcr = ctc_integrator_reset(integ, t, y);
            if (rcr == SIM_RHS_SINGULAR) {
                status = CTC_RUN_SINGULAR;
                singular_limit(r, t, &c);
                break;
            }
            if (rcr != 0) {
                status = CTC_RUN_FAILED;
                break;
            }
        }
        if (hooks->cancelled && hooks->cancelled(hooks->ctx)) {
            status = CTC_RUN_CANCELLED;
            snprintf(r->message, sizeof r->message, "cancelled at t = %.6g s", t);
        } else if (spec->wall_limit > 0 && now(CLOCK_MONOTONIC) - wall0 > spec->wall_limit) {
            status = CTC_RUN_TIMEOUT;
            snprintf(r->message, sizeof r->message, "wall-time limit of %g s reached at t = %.6g s",
                     spec->wall_limit, t);
        }
    }

    /* metrics */
    ctc_sim_metrics *mt = &r->metrics;
    const ctc_integ_stats *stats = ctc_integrator_stats(integ);
    r->status = status;
    mt->t_end = r->nsamples ? r->t[r->nsamples - 1] : 0;
    if (status != CTC_RUN_DONE) mt->t_end = t;
    mt->steps = stats->steps;
    mt->rejected = stats->rejected;
    mt->rhs_evals = c.evals;
    mt->err_estimate = stats->err_estimate;
    for (int i = 0; c.active && i < c.nind; i++)
        mt->e_rms[i] = r->nsamples ? sqrt(rec.e_sq[i] / (double)r->nsamples) : 0;
    if (plant->has_loop) {
        mt->loop_res_max = rec.loop_max[0];
        mt->loop_vres_max = rec.loop_max[1];
    }
    if (rec.track_energy && r->nsamples)
        mt->energy_drift = rec.drift / fmax(fmax(fabs(rec.e0), rec.ke_max), 1e-300);
    if (!rec.track_errdyn || r->nsamples < 2) mt->errdyn_dev = NAN;
    mt->wall_s = now(CLOCK_MONOTONIC) - wall0;
    mt->cpu_s = now(CLOCK_THREAD_CPUTIME_ID) - cpu0;
    mt->us_per_eval = c.evals ? 1e6 * mt->wall_s / (double)c.evals : 0;
    *out = r;
    r = NULL;
    st = CTC_OK;

cleanup:
    ctc_sim_result_free(r);
    ctc_integrator_free(integ);
    ctx_free(&c);
    ctc_model_free(plant);
    free(ybuf);
    free(breaks);
    free(rec.e_sq);
    free(rec.phi);
    return st;
}

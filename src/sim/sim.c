/*
 * sim.c - one computed torque control run (sim.h): the recipe. Its stages live in files of
 * their own (sim_internal.h): the checks (sim_check.c), the right-hand side (sim_rhs.c), the
 * samples (sim_record.c) and the metrics (sim_metrics.c); this file sets them up, runs the
 * integrator step by step and says why a run stopped.
 *
 *     check the spec; build the plant (and the controller's model when it is scaled)
 *     set up: scratch, the result sized for every sample, the metrics' references
 *     start: the integrator at the initial state, put onto a loop's closure; sample t = 0
 *     step, one accepted step at a time, until the last sample:
 *         step to the next discontinuity (a disturbance's step time, a spline's end, a sampled
 *         controller's instant), or for rk4 to the next sample time; stop on the integrator's
 * failure, a singular loop or a diverged state (non-finite, or a speed beyond the bound) record the
 * samples inside the step from the integrator's dense output a sampled controller: at its instant,
 * a new command and the integral's sum (sim_rhs.c) restart at a discontinuity or a sampled
 * controller's instant; on a loop model, measure the drift and project back onto the closure (rk4
 * and dopri5 here, bdf inside its steps, sim_rhs.c) poll for cancellation and the wall-time limit
 *     finish the metrics
 *     the error by cause: counterfactual runs without the sampling, the noise or the model
 *     error (sim_causes.c)
 *
 * Everything is allocated before the first step. A run stopped early keeps its samples and says
 * why in its status and message, with the time and the joint where it applies.
 */
#include "sim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "kinematics.h"
#include "sim_internal.h"

static const char *const channel_names[] = {"q",    "qdot",         "q_des",    "qdot_des",
                                            "e",    "tau",          "w",        "energy",
                                            "loop", "end_effector", "body_pose"};
static const char *const run_names[] = {"done",      "diverged", "failed",
                                        "cancelled", "timeout",  "singular"};
static const char *const stab_names[] = {"project", "baumgarte", "none"};

const char *ctc_ctrl_type_name(ctc_ctrl_type t)
{
    const ctc_ctrl_class *cls = ctc_ctrl_class_of(t);
    return cls ? cls->name : "unknown";
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

/* the controller's model: the plant's chain with the model's bodies (the plant's when none are
   given), masses and inertias scaled, and the model's gravity */
static ctc_status build_controller_model(const ctc_sim_spec *s, ctc_model **out, char *err,
                                         size_t errlen)
{
    int n = s->chain.nbodies;
    ctc_body_spec *b = malloc((size_t)n * sizeof *b);
    if (!b) return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    for (int k = 0; k < n; k++) {
        b[k] = s->model_bodies ? s->model_bodies[k] : s->chain.bodies[k];
        b[k].mass *= s->model_mass_scale;
        for (int j = 0; j < 9; j++) b[k].inertia[j] *= s->model_inertia_scale;
    }
    ctc_chain_spec c = s->chain;
    c.bodies = b;
    c.form = CTC_FORM_AUTO;
    if (s->model_gravity)
        for (int i = 0; i < 3; i++) c.gravity[i] = s->model_gravity[i];
    char why[200];
    ctc_status st = ctc_model_build(&c, out, why, sizeof why);
    free(b);
    if (st != CTC_OK) return ctc_fail(st, err, errlen, "controller model: %s", why);
    return CTC_OK;
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
        unsigned mask = ctc_joint_classes[c->plant->joints[k].type].linear_mask;
        int lin = (mask >> (i - c->plant->jnt_vadr[k])) & 1u;
        r->metrics.diverged_joint = k;
        snprintf(r->message, sizeof r->message,
                 "t = %.6g s: joint %d speed %.3g %s exceeds the bound %g", t, k, fabs(v[i]),
                 lin ? "m/s" : "rad/s", bound);
        return 1;
    }
    return 0;
}

static void ctx_free(sim_ctx *c)
{
    if (c->dc != c->dp) ctc_data_free(c->dc);
    ctc_data_free(c->dp);
    ctc_model_free(c->ctrl_model);
    free(c->qn);
    free(c->u);
    free(c->y_eval);
    free(c->ring);
    free(c->ym);
    free(c->xq);
    free(c->arm);
    free(c->fext);
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

/* the run's integrator and the breakpoints it stops and restarts at */
typedef struct sim_stepper {
    ctc_integ_spec is; /* the spec's, rk4's step shortened to divide the output interval */
    ctc_integrator *integ;
    double *breaks;  /* sorted discontinuity times in (0, duration) */
    int nbreaks, ib; /* their count, the next one */
    int in_step;     /* bdf projects inside its steps (sim_project) */
    double bound;    /* the divergence bound on speeds */
} sim_stepper;

/* Sizes, scratch and the controller's model of run c (its spec, plant and class set). */
static ctc_status setup_context(sim_ctx *c, char *err, size_t errlen)
{
    const ctc_sim_spec *spec = c->spec;
    const ctc_model *plant = c->plant;
    c->nq = plant->nq, c->nv = plant->nv, c->nvx = plant->nvx, c->nind = plant->nind;
    c->active = c->cls->law != NULL;
    c->nx = c->active && c->cls->nstate ? c->nind : 0;
    c->ny = c->nq + c->nv + c->nx;
    c->cond_max = spec->loop_cond_max > 0 ? spec->loop_cond_max : CTC_SIM_DEFAULT_COND_MAX;
    for (int k = 0; k < plant->nbodies; k++) /* a q that is not a vector: renormalised */
        c->has_quat |= plant->jnt_nq[k] != plant->jnt_nv[k];
    if (c->active && !(spec->model_mass_scale == 1 && spec->model_inertia_scale == 1 &&
                       !spec->model_bodies && !spec->model_gravity)) {
        ctc_status st = build_controller_model(spec, &c->ctrl_model, err, errlen);
        if (st != CTC_OK) return st;
    }
    size_t nq = (size_t)c->nq, nv = (size_t)c->nind + 1, nvx = (size_t)c->nvx + 1;
    c->dp = ctc_data_new(plant);
    /* a baseline's model passes run at another state than the plant's: data of their own */
    const int own = c->active && c->cls->force != CTC_FORCE_COMPUTED_TORQUE;
    c->dc = c->ctrl_model ? ctc_data_new(c->ctrl_model) : own ? ctc_data_new(plant) : c->dp;
    c->xq = malloc((nq + nv + (size_t)c->nv + 1) * sizeof(double));
    c->qn = malloc((nq + 1) * sizeof(double));
    c->u = malloc((nvx * 6 + nv * 7) * sizeof(double));
    c->y_eval = malloc((size_t)(c->ny + 1) * sizeof(double));
    if (!c->dp || !c->dc || !c->qn || !c->u || !c->y_eval || !c->xq)
        return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    if (spec->threads > 1) { /* one set of workers for both models */
        ctc_status st = ctc_data_set_threads(c->dp, spec->threads, err, errlen);
        if (st != CTC_OK) return st;
        ctc_data_share_pool(c->dc, c->dp);
    }
    c->f = c->u + nvx, c->fz = c->f + nvx, c->acc = c->fz + nvx, c->fp = c->acc + nvx;
    c->w = c->fp + nvx;
    c->des = c->w + nv, c->qi = c->des + 3 * nv, c->vi = c->qi + nv, c->clip = c->vi + nv;
    c->fref = c->clip + nv;
    memset(c->w, 0, nv * 7 * sizeof(double));
    c->jknown = 1;
    c->wrenched = spec->nwrenches > 0;
    for (int k = 0; k < spec->nwrenches; k++) {
        c->wknown |= spec->wrenches[k].known != 0;
        c->jknown &= spec->wrenches[k].known != 0;
    }
    if (c->wknown) {
        c->fext = malloc(((size_t)c->nv + 1) * sizeof(double));
        if (!c->fext) return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    }
    for (int i = 0; spec->plant && i < c->nind; i++) {
        c->limited |= spec->plant[i].torque_limit > 0;
        c->sensed |= ctc_plant_has_sensor_error(&spec->plant[i]);
        if (ctc_plant_has_joint_force(&spec->plant[i])) {
            c->jforces = 1;
            c->jknown &= spec->plant[i].known != 0;
        }
        if (spec->plant[i].armature > 0) {
            c->armed = 1;
            c->jknown &= spec->plant[i].known != 0;
        }
    }
    if (c->armed) { /* open chains only (sim_check.c): coordinate i is velocity ind_coord[i] */
        int k = 0;
        for (int i = 0; i < c->nind; i++) k += spec->plant[i].armature > 0;
        c->arm = calloc((size_t)(c->nv + ctc_plant_armature_work(c->nv, k)), sizeof(double));
        if (!c->arm) return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
        for (int i = 0; i < c->nind; i++) c->arm[plant->ind_coord[i]] = spec->plant[i].armature;
    }
    c->law_in = (ctc_ctrl_eval){.nind = c->nind,
                                .qi = c->qi,
                                .vi = c->vi,
                                .des = c->des,
                                .gains = spec->gains,
                                .params = spec->ctrl_params};
    if (c->active && spec->sample_period > 0) { /* the commands' ring and the zero command */
        c->sampled = 1, c->delay = spec->sample_delay;
        c->ring = calloc((size_t)(c->delay + 2) * (nvx + 2 * nv), sizeof(double));
        c->ym = malloc(((size_t)c->ny + 1) * sizeof(double));
        c->rng = spec->seed;
        if (!c->ring || !c->ym) return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    }
    if (plant->has_loop) {
        ctc_loop_stab stab = spec->loop_stab;
        double a = spec->baumgarte[0], b = spec->baumgarte[1];
        if (a == 0 && b == 0) a = b = CTC_SIM_DEFAULT_BAUMGARTE;
        c->dp->baumgarte[0] = stab == CTC_LOOP_BAUMGARTE ? a : 0;
        c->dp->baumgarte[1] = stab == CTC_LOOP_BAUMGARTE ? b : 0;
    }
    c->loop_tol = sim_loop_tol(spec);
    return CTC_OK;
}

/* The result sized for every sample, the recorder and the metrics' references; ybuf holds
 * 3 (ny + 1) + 2 doubles: the initial state, a sample's state, a projected state and the
 * loop's max residuals. */
static ctc_status setup_recorder(sim_ctx *c, recorder *rec, double *ybuf, char *err, size_t errlen)
{
    const ctc_sim_spec *spec = c->spec;
    unsigned channels = spec->channels ? spec->channels : sim_channels_applicable(c->active);
    if (!spec->channels && c->plant->has_loop) channels |= CTC_CH_BIT(CTC_CH_LOOP);
    if (!spec->channels && spec->end_effector) channels |= CTC_CH_BIT(CTC_CH_EE);
    if (!spec->channels && spec->npose > 0) channels |= CTC_CH_BIT(CTC_CH_POSE);
    rec->count = sim_sample_count(spec->duration, spec->output_interval);
    rec->dt = spec->output_interval;
    if (sim_alloc_result(c, channels, rec->count, &rec->r) != CTC_OK)
        return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory for %ld samples", rec->count);
    rec->ysample = ybuf + c->ny + 1;
    rec->loop_max = rec->ysample + 2 * (c->ny + 1);
    rec->loop_max[0] = rec->loop_max[1] = 0;
    int exact = !c->active || c->ctrl_model == NULL;
    if (sim_metrics_init(c, rec, exact, (size_t)c->nind + 1) != CTC_OK)
        return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    rec->eval = sim_sample_needs(c, rec);
    return CTC_OK;
}

/* The integrator and its breakpoints: the discontinuities, sorted - disturbance steps, and the
 * ends of splines, where a clamped spline's acceleration jumps to zero. */
static ctc_status setup_stepper(sim_ctx *c, sim_stepper *sp, double dt, char *err, size_t errlen)
{
    const ctc_sim_spec *spec = c->spec;
    sp->is = spec->integrator;
    if (sp->is.method == CTC_INTEG_RK4) sp->is.step = dt / ceil(dt / sp->is.step * (1 - 1e-12));
    ctc_status st = ctc_integrator_new(&sp->is, c->ny, sim_rhs, c, &sp->integ, err, errlen);
    if (st != CTC_OK) return st;
    sp->breaks = malloc((3 * ((size_t)c->nind + 1) + (size_t)spec->nwrenches) * sizeof(double));
    if (!sp->breaks) return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    for (int i = 0; i < c->nind; i++) {
        double tb[3] = {spec->disturb ? ctc_disturb_breakpoint(&spec->disturb[i]) : INFINITY,
                        INFINITY, INFINITY};
        if (c->active && spec->traj[i].type == CTC_TRAJ_SPLINE) {
            const ctc_traj *tr = &spec->traj[i];
            tb[1] = tr->knots[0], tb[2] = tr->knots[5 * (tr->nknots - 1)];
        }
        for (int k = 0; k < 3; k++)
            if (tb[k] > 0 && tb[k] < spec->duration) sp->breaks[sp->nbreaks++] = tb[k];
    }
    for (int k = 0; k < spec->nwrenches; k++) { /* a wrench's step */
        const ctc_wrench *w = &spec->wrenches[k];
        if (w->profile == CTC_WRENCH_STEP && w->time > 0 && w->time < spec->duration)
            sp->breaks[sp->nbreaks++] = w->time;
    }
    qsort(sp->breaks, (size_t)sp->nbreaks, sizeof(double), cmp_double);
    /* bdf projects inside its steps and keeps its history; rk4 and dopri5 between steps */
    sp->in_step =
        c->plant->has_loop && spec->loop_stab == CTC_LOOP_PROJECT && sp->is.method == CTC_INTEG_BDF;
    if (sp->in_step) {
        st = ctc_integrator_set_projection(sp->integ, sim_project, err, errlen);
        if (st != CTC_OK) return st;
    }
    sp->bound = spec->max_speed > 0 ? spec->max_speed : SIM_DEFAULT_MAX_SPEED;
    return CTC_OK;
}

/* The start at y0: the integrator's start evaluates f there, and the first sample reuses that
 * evaluation. Returns how the run stands. */
static ctc_run_status start(sim_ctx *c, sim_stepper *sp, recorder *rec, double *y0)
{
    ctc_sim_result *r = rec->r;
    if (c->sampled) sim_control_sample(c, 0, y0); /* the first command, held from t = 0 */
    int rc0 = ctc_integrator_reset(sp->integ, 0, y0);
    if (rc0 == SIM_RHS_SINGULAR) {
        singular_limit(r, 0, c);
        return CTC_RUN_SINGULAR;
    }
    if (diverged(c, 0, y0, sp->bound, r)) return CTC_RUN_DIVERGED;
    if (rc0 != 0) return CTC_RUN_FAILED;
    c->cond0 = c->cond;
    sim_record_sample(c, rec, 0, y0);
    rec->next = 1;
    return CTC_RUN_DONE;
}

/* A loop model's drift at the end of the step to (t, *y), and its projection back onto the
 * closure into yproj (rk4, dopri5; bdf projected inside the step); *restart set when it moved
 * the state. proj_calls: sim_project's count before the step. Returns how the run stands. */
static ctc_run_status keep_closure(sim_ctx *c, const sim_stepper *sp, recorder *rec, double t,
                                   const double **y, double *yproj, long proj_calls, int *restart)
{
    ctc_sim_result *r = rec->r;
    const ctc_sim_spec *spec = c->spec;
    double pos, vel;
    char why[200];
    c->eval_valid = 0; /* dp's kinematics are this state's now */
    ctc_kinematics(c->plant, c->dp, *y, *y + c->nq);
    ctc_loop_residual_norms(c->plant, c->dp, &pos, &vel);
    if (sp->in_step && c->proj_calls > proj_calls) {
        /* CVODE projected inside the step: its last call was the accepted attempt's, and the
           drift is what that call found */
        pos = fmax(pos, c->proj_res[0]);
        vel = fmax(vel, c->proj_res[1]);
        r->metrics.projections += c->proj_moved;
    }
    rec->loop_max[0] = fmax(rec->loop_max[0], pos);
    rec->loop_max[1] = fmax(rec->loop_max[1], vel);
    if (!sp->in_step && spec->loop_stab == CTC_LOOP_PROJECT &&
        (pos > c->loop_tol || vel > c->loop_tol)) {
        memcpy(yproj, *y, (size_t)c->ny * sizeof **y);
        if (ctc_loop_assemble(c->plant, c->dp, yproj, yproj + c->nq, c->loop_tol, SIM_LOOP_MAX_ITER,
                              NULL, why, sizeof why) != CTC_OK) {
            snprintf(r->message, sizeof r->message, "t = %.6g s: projection: %s", t, why);
            return CTC_RUN_SINGULAR;
        }
        r->metrics.projections++;
        *y = yproj;
        *restart = 1;
    }
    return CTC_RUN_DONE;
}

/* The output samples up to time tmax (inclusive or not) from the last step's dense output. */
static void record_samples(sim_ctx *c, sim_stepper *sp, recorder *rec, const ctc_sim_hooks *hooks,
                           double tmax, int inclusive)
{
    const ctc_sim_spec *spec = c->spec;
    while (rec->next < rec->count) {
        double ts = sim_sample_time(rec->next, rec->count, spec->duration, rec->dt);
        if (ts > tmax || (!inclusive && ts == tmax)) break;
        ctc_integrator_dense(sp->integ, ts, rec->ysample);
        sim_record_sample(c, rec, ts, rec->ysample);
        rec->next++;
        if (hooks->progress) hooks->progress(hooks->ctx, ts / spec->duration);
        if (hooks->recorded) hooks->recorded(hooks->ctx, rec->r);
    }
}

/* One accepted step, its samples, the restart after it; *t receives the time reached. Returns
 * how the run stands (the message set when it stopped). */
static ctc_run_status advance(sim_ctx *c, sim_stepper *sp, recorder *rec, double *yproj,
                              const ctc_sim_hooks *hooks, double *t)
{
    const ctc_sim_spec *spec = c->spec;
    ctc_sim_result *r = rec->r;
    char why[200] = "";
    double tstop = sp->ib < sp->nbreaks ? sp->breaks[sp->ib] : spec->duration;
    /* rk4's step divides the output interval: stopping at each sample time makes every sample a
       step's end exactly, where it reuses the step's last evaluation (sim_record_sample) rather
       than interpolate at a time a few ulps off the accumulated step ends */
    if (sp->is.method == CTC_INTEG_RK4)
        tstop = fmin(tstop, sim_sample_time(rec->next, rec->count, spec->duration, rec->dt));
    const double t_ctrl = c->sampled ? (double)c->k_ctrl * spec->sample_period : INFINITY;
    tstop = fmin(tstop, t_ctrl);
    long proj_calls = c->proj_calls;
    int rc = ctc_integrator_step(sp->integ, tstop, why, sizeof why);
    *t = ctc_integrator_time(sp->integ);
    const double *y = ctc_integrator_state(sp->integ);
    if (rc == SIM_PROJ_FAILED) {
        snprintf(r->message, sizeof r->message, "t = %.6g s: projection: %s", *t, c->proj_why);
        return CTC_RUN_SINGULAR;
    }
    if (rc == SIM_RHS_SINGULAR) {
        singular_limit(r, *t, c);
        return CTC_RUN_SINGULAR;
    }
    if (rc != 0) {
        snprintf(r->message, sizeof r->message, "integrator: %s", why);
        return CTC_RUN_FAILED;
    }
    if (diverged(c, *t, y, sp->bound, r))
        return singular_divergence(c, *t, sp->bound, r) ? CTC_RUN_SINGULAR : CTC_RUN_DIVERGED;

    /* the samples inside this step; at a sampled controller's instant, the one there after its
       new command */
    const int control = *t >= t_ctrl;
    record_samples(c, sp, rec, hooks, *t, !control);
    int restart = 0;
    if (sp->ib < sp->nbreaks && *t >= sp->breaks[sp->ib]) {
        while (sp->ib < sp->nbreaks && sp->breaks[sp->ib] <= *t) sp->ib++;
        restart = 1;
    }
    if (c->plant->has_loop) {
        ctc_run_status st = keep_closure(c, sp, rec, *t, &y, yproj, proj_calls, &restart);
        if (st != CTC_RUN_DONE) return st;
    }
    if (control) {
        if (y != yproj) memcpy(yproj, y, (size_t)c->ny * sizeof *y);
        sim_control_sample(c, *t, yproj);
        y = yproj;
        restart = 1;
        if (rec->next < rec->count &&
            sim_sample_time(rec->next, rec->count, spec->duration, rec->dt) == *t) {
            memcpy(rec->ysample, y, (size_t)c->ny * sizeof *y);
            sim_record_sample(c, rec, *t, rec->ysample);
            rec->next++;
            if (hooks->progress) hooks->progress(hooks->ctx, *t / spec->duration);
            if (hooks->recorded) hooks->recorded(hooks->ctx, rec->r);
        }
    }
    if (restart) {
        int rcr = ctc_integrator_reset(sp->integ, *t, y);
        if (rcr == SIM_RHS_SINGULAR) {
            singular_limit(r, *t, c);
            return CTC_RUN_SINGULAR;
        }
        if (rcr != 0) return CTC_RUN_FAILED;
    }
    return CTC_RUN_DONE;
}

/* cancellation and the wall-time limit, polled after each step */
static ctc_run_status interrupted(const ctc_sim_spec *spec, const ctc_sim_hooks *hooks,
                                  double wall0, double t, ctc_sim_result *r)
{
    if (hooks->cancelled && hooks->cancelled(hooks->ctx)) {
        snprintf(r->message, sizeof r->message, "cancelled at t = %.6g s", t);
        return CTC_RUN_CANCELLED;
    }
    if (spec->wall_limit > 0 && now(CLOCK_MONOTONIC) - wall0 > spec->wall_limit) {
        snprintf(r->message, sizeof r->message, "wall-time limit of %g s reached at t = %.6g s",
                 spec->wall_limit, t);
        return CTC_RUN_TIMEOUT;
    }
    return CTC_RUN_DONE;
}

ctc_status ctc_sim_run(const ctc_sim_spec *spec, const ctc_sim_hooks *hooks, ctc_sim_result **out,
                       char *err, size_t errlen)
{
    static const ctc_sim_hooks no_hooks = {0};
    if (!hooks) hooks = &no_hooks;
    ctc_status st = sim_run_once(spec, hooks, out, err, errlen);
    if (st != CTC_OK) return st;
    st = sim_error_by_cause(spec, hooks, *out, err, errlen);
    if (st != CTC_OK) {
        ctc_sim_result_free(*out);
        *out = NULL;
    }
    return st;
}

ctc_status sim_run_once(const ctc_sim_spec *spec, const ctc_sim_hooks *hooks, ctc_sim_result **out,
                        char *err, size_t errlen)
{
    *out = NULL;
    ctc_status st = sim_check_run(spec, err, errlen);
    if (st != CTC_OK) return st;

    double wall0 = now(CLOCK_MONOTONIC), cpu0 = now(CLOCK_THREAD_CPUTIME_ID);
    sim_ctx c = {.spec = spec, .cls = sim_ctrl_class(spec)};
    ctc_model *plant = NULL;
    sim_stepper sp = {0};
    recorder rec = {0};
    double *ybuf = NULL;

    /* the plant, its checks, and the set-up */
    st = ctc_model_build(&spec->chain, &plant, err, errlen);
    if (st != CTC_OK) return st;
    c.plant = plant;
    if ((st = sim_check_with_model(spec, plant, err, errlen)) != CTC_OK ||
        (st = setup_context(&c, err, errlen)) != CTC_OK)
        goto cleanup;
    ybuf = malloc((size_t)(c.ny + 1) * 3 * sizeof(double) + 2 * sizeof(double));
    if (!ybuf) {
        st = ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
        goto cleanup;
    }
    if ((st = setup_recorder(&c, &rec, ybuf, err, errlen)) != CTC_OK ||
        (st = setup_stepper(&c, &sp, rec.dt, err, errlen)) != CTC_OK)
        goto cleanup;

    /* the initial state, on the loop's closure, and the start */
    double *y0 = ybuf, t = 0;
    st = sim_close_initial_state(spec, plant, c.dp, y0, y0 + c.nq, &rec.r->metrics.initial, err,
                                 errlen);
    if (st != CTC_OK) goto cleanup;
    for (int i = c.nq + c.nv; i < c.ny; i++) y0[i] = 0;
    ctc_run_status status = start(&c, &sp, &rec, y0);
    if (status == CTC_RUN_DONE && hooks->recorded) hooks->recorded(hooks->ctx, rec.r);

    /* the tolerance floor, from the accelerations at the start */
    if (status == CTC_RUN_DONE) {
        st = sim_tolerance_floor(&c, y0, &sp.is, &rec.r->metrics, err, errlen);
        if (st == CTC_OK && rec.r->metrics.tol_floored)
            st = ctc_integrator_set_tolerances(sp.integ, sp.is.rtol, sp.is.atol, err, errlen);
        if (st != CTC_OK) goto cleanup;
    }

    /* the loop: one accepted step at a time */
    while (status == CTC_RUN_DONE && rec.next < rec.count) {
        status = advance(&c, &sp, &rec, rec.ysample + c.ny + 1, hooks, &t);
        if (status == CTC_RUN_DONE) status = interrupted(spec, hooks, wall0, t, rec.r);
    }

    /* the metrics */
    ctc_sim_result *r = rec.r;
    ctc_sim_metrics *mt = &r->metrics;
    r->status = status;
    mt->t_end = status != CTC_RUN_DONE ? t : r->nsamples ? r->t[r->nsamples - 1] : 0;
    if (sp.is.method == CTC_INTEG_RK4) mt->step_used = sp.is.step;
    sim_metrics_finish(&c, &rec, ctc_integrator_stats(sp.integ), mt);
    mt->wall_s = now(CLOCK_MONOTONIC) - wall0;
    mt->cpu_s = now(CLOCK_THREAD_CPUTIME_ID) - cpu0;
    mt->us_per_eval = c.evals ? 1e6 * mt->wall_s / (double)c.evals : 0;
    *out = r;
    rec.r = NULL;
    st = CTC_OK;

cleanup:
    ctc_sim_result_free(rec.r);
    ctc_integrator_free(sp.integ);
    ctx_free(&c);
    ctc_model_free(plant);
    free(ybuf);
    free(sp.breaks);
    sim_metrics_free(&rec);
    return st;
}

/*
 * sim_internal.h - what the files of one simulation run share (sim.h): the run's context, the
 * recorder of samples and metrics, and the stages between them. Not a public header.
 *
 * The run (sim.c) is a recipe of stages, one file each:
 *   - sim_check.c: the spec's checks, with and without a model, and the initial state;
 *   - sim_rhs.c: one evaluation, state -> desired motion -> controller law -> iGDCA forces ->
 *     saturation -> disturbance and wrenches -> GDCA accelerations; the integrator's right-hand
 *     side and bdf's in-step projection;
 *   - sim_record.c: the result's arrays and one output sample's channels;
 *   - sim_metrics.c: the accuracy and tracking figures gathered at the samples and at the end;
 *   - sim_causes.c: the tracking error by cause, from counterfactual runs after the run.
 * Everything a run touches is allocated in sim.c before its first step.
 */
#ifndef CTC_SIM_INTERNAL_H
#define CTC_SIM_INTERNAL_H

#include <stddef.h>

#include "data.h"
#include "sim.h"

#define SIM_DEFAULT_MAX_SPEED 1e6
#define SIM_MAX_SAMPLES 50000000L
#define SIM_LOOP_MAX_ITER 50
#define SIM_RHS_SINGULAR 2 /* the right-hand side's code for a singular loop */
#define SIM_PROJ_FAILED 3  /* sim_project's code when the closure cannot be solved */

typedef struct sim_ctx {
    const ctc_sim_spec *spec;
    const ctc_model *plant;
    const ctc_ctrl_class *cls; /* the controller's class (ctrl.h) */
    ctc_model *ctrl_model;     /* NULL when the controller's model is the plant */
    ctc_data *dp, *dc;         /* dc == dp when the model is exact */
    int nq, nv, ny, active, has_quat;
    int nvx, nind;   /* extended and controlled coordinates (nv and nv for an open chain) */
    int nx;          /* the controller's state in y: nind, or 0 (passive, or a class's nstate 0) */
    double *qn;      /* (nq) normalised positions */
    double *u, *f;   /* (nvx) commanded accelerations, controller forces */
    double *fz;      /* (nvx) applied forces f + z */
    double *acc;     /* (nvx) accelerations from the forward pass */
    double *fref;    /* (nvx) the plant's iGDCA(u) of this evaluation, before anything is added
                        to it: the forward pass's reference (gdca.h ctc_gdca_forward_from) */
    int ref_valid;   /* 1: fref and dp's inverse loads are this evaluation's, at the plant's own
                        state and model (sim_rhs.c) */
    double *w;       /* (nind) controller output */
    double *des;     /* (nind x 3) desired q, qd, qdd */
    double *qi, *vi; /* (nind) the controlled coordinates' positions and rates */
    double *clip;    /* (nind) f - sat(f) of the last evaluation with forces: 0 when the
                        actuator was within its limit (plant.h) */
    int limited;     /* some coordinate has a limit (spec.plant) */
    int jforces;     /* some coordinate has a joint force (plant.h) */
    int jknown;      /* every coordinate's joint force is known to the controller */
    double *fp;      /* (nvx) what the forward pass receives: fz plus the joint forces and the
                        external wrenches' generalised forces */
    int wrenched;    /* the spec has external wrenches (wrench.h) */
    int wknown;      /* some wrench is known to the controller */
    double *fext;    /* (nv) scratch: the known wrenches' generalised forces */
    double *xq;      /* (nq + nv) a baseline controller's model state (sim_rhs.c) */
    int armed;       /* some coordinate has armature (plant.h) */
    double *arm;     /* (nv) the armature per velocity coordinate, then ctc_plant_forward_armature's
                        work; NULL when none has armature */
    /* a sampled controller (sim.h sample_period): the commands of the last delay + 1 samples,
       each (nvx) f, (nind) w, (nind) clip, in a ring, and a zero command */
    int sampled, delay;
    int sampling_now;       /* sim_evaluate computes the controller (at a sample instant) */
    long k_ctrl;            /* the next sample's index */
    double *ring;           /* (delay + 2) commands; the last is zero */
    const double *held;     /* the command being applied: one of ring's */
    int sensed;             /* some coordinate's sensors are not exact (plant.h) */
    unsigned long long rng; /* the sensors' noise generator's state */
    double *ym;             /* (ny) the state as the sampled controller measures it */
    ctc_ctrl_eval law_in;   /* the law's input: the arrays above, t, q, v and xi set per call */
    double cond_max;        /* loop models: singular beyond this condition estimate */
    double cond;  /* loop models: the last evaluation's condition estimate (max of passes) */
    double cond0; /* loop models: the condition estimate at t = 0 */
    long evals;   /* evaluations with the forward pass (the right-hand side's) */
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

/* run-time state of the sampling and the metrics */
typedef struct recorder {
    ctc_sim_result *r;
    long count, next; /* samples in all, the next to take */
    double dt;
    double *ysample;  /* (ny) */
    unsigned eval;    /* SIM_EVAL_* bits a sample needs (sim_sample_needs) */
    double *loop_max; /* loop models: the max residuals (position, velocity) so far */
    /* error-dynamics reference (exact model, no disturbance, a class with closed_loop) */
    int track_errdyn;
    double *phi;    /* (nind x 9) transition matrix over one interval */
    double *eref;   /* (nind x 3) reference error state at the last sample */
    double t_ref;   /* time of eref */
    double *e_sq;   /* (nind) sum of e^2 */
    double *tau_sq; /* (nind) sum of sat(f)^2 */
    double *sat_n;  /* (nind) samples at which the actuator was clipped */
    /* energy reference (passive, no disturbance) */
    int track_energy;
    double e0, ke_max, drift;
} recorder;

/* ---- sim.c ---- */

/* ctc_sim_run without the error by cause: one run of spec; hooks not NULL */
ctc_status sim_run_once(const ctc_sim_spec *spec, const ctc_sim_hooks *hooks, ctc_sim_result **out,
                        char *err, size_t errlen);

/* ---- sim_causes.c ---- */

/* metrics.err_cause of result r of spec s (sim.h CTC_CAUSE_*): the counterfactual runs and
 * their RMS differences; zeros when s has no cause, NaN when r stopped early. CTC_OK, or CTC_ENOMEM
 * / CTC_EINVAL with a message; a cancelled counterfactual marks r cancelled. hooks not NULL. */
ctc_status sim_error_by_cause(const ctc_sim_spec *s, const ctc_sim_hooks *hooks, ctc_sim_result *r,
                              char *err, size_t errlen);

/* ---- sim_check.c ---- */

/* the channels that apply: q, qdot, tau and energy always; the tracking ones when active; loop
 * with a loop model (added by the caller that knows the model) */
unsigned sim_channels_applicable(int active);

/* The controller class of a spec: its ctrl_class, or the built-in one of its controller; NULL
 * for an unknown controller value. */
const ctc_ctrl_class *sim_ctrl_class(const ctc_sim_spec *s);

/* the spec's checks that do not need a model; then those of its arrays against model m */
ctc_status sim_check_run(const ctc_sim_spec *s, char *err, size_t errlen);
ctc_status sim_check_with_model(const ctc_sim_spec *s, const ctc_model *m, char *err,
                                size_t errlen);

/* the projection's trigger and Newton's tolerance (m, rad) */
double sim_loop_tol(const ctc_sim_spec *s);

/* The spec's initial state (q0 normalised, v0) in q (nq) and v (nv), put onto the loop's closure
 * and checked there (loop.h). */
ctc_status sim_close_initial_state(const ctc_sim_spec *s, const ctc_model *m, ctc_data *d,
                                   double *q, double *v, ctc_loop_fix *fix, char *err,
                                   size_t errlen);

/* ---- sim_rhs.c ---- */

/* What an evaluation computes, as bits (sim_evaluate): the right-hand side needs all; a sample
 * only what its channels and metrics read (sim_record_sample). The desired motion, the
 * controller output w and the applied forces' disturbance part are always computed. */
enum {
    SIM_EVAL_KIN = 1,    /* the plant's kinematics (energy, loop residuals) */
    SIM_EVAL_FORCES = 2, /* and the handles and the inverse pass: the driving forces f */
    SIM_EVAL_ACC = 4,    /* and the forward pass: the accelerations */
    SIM_EVAL_FULL = 7
};

/* Driving forces and accelerations of state y = (q, v, xi) at time t, as far as `what` asks:
 * fills c's arrays and dp's kinematics. Returns 0, or SIM_RHS_SINGULAR when a loop's boundary
 * solve is singular. A full evaluation is remembered (t_eval, y_eval). */
int sim_evaluate(sim_ctx *c, double t, const double *y, unsigned what);

/* the integrator's right-hand side (integrator.h ctc_ode_rhs); ctx is the sim_ctx */
int sim_rhs(double t, const double *y, double *ydot, void *ctx);

/* The sampled controller at sample instant t (sim.h sample_period): measures y, computes and
 * stores the command, makes the command of delay samples ago the held one, and advances the
 * discrete integral state in y. */
void sim_control_sample(sim_ctx *c, double t, double *y);

/* bdf's in-step projection onto a loop's closure (integrator.h ctc_ode_project): 0, or
 * SIM_PROJ_FAILED with the reason in c->proj_why */
int sim_project(double t, double *y, void *ctx);

/* ---- sim_record.c ---- */

/* output samples of a run: t = 0, dt, 2 dt, ... and a last one at duration; count and time j */
long sim_sample_count(double duration, double dt);
double sim_sample_time(long j, long count, double duration, double dt);

/* a result sized for count samples of the given channels; CTC_ENOMEM leaves *out to be freed */
ctc_status sim_alloc_result(const sim_ctx *c, unsigned channels, long count, ctc_sim_result **out);

/* the SIM_EVAL_* bits a sample needs of an evaluation at its state */
unsigned sim_sample_needs(const sim_ctx *c, const recorder *rec);

/* Records sample j = r->nsamples at (t, y): its channels and its share of the metrics. */
void sim_record_sample(sim_ctx *c, recorder *rec, double t, const double *y);

/* ---- sim_tol.c ---- */

/* The step below which an adaptive run would be bound by the accelerations' rounding: atol's
 * floor is the velocity error that rounding puts into one such step (sim_tol.c). */
#define SIM_TOL_FLOOR_STEP 1e-4

/* The tolerance floor (sim_tol.c): after the integrator's start at y0 (c->acc holds the
 * accelerations there), estimates their rounding on an open model and raises is's atol and rtol
 * to what it allows; fills mt's accel_rounding, tol_* (NaN and 0 for rk4 and loop models).
 * CTC_ENOMEM with a message, else CTC_OK. */
ctc_status sim_tolerance_floor(const sim_ctx *c, const double *y0, ctc_integ_spec *is,
                               ctc_sim_metrics *mt, char *err, size_t errlen);

/* ---- sim_metrics.c ---- */

/* the metrics' references and scratch, before the first sample (nv: nind + 1 entries); sets
 * track_energy and track_errdyn from the spec */
ctc_status sim_metrics_init(const sim_ctx *c, recorder *rec, int exact, size_t nv);

/* sample j's share of the metrics at (t, y): tracking errors, energy (ke, pe), error dynamics */
void sim_metrics_sample(const sim_ctx *c, recorder *rec, long j, double t, const double *y,
                        double ke, double pe);

/* the figures at the run's end, from the integrator's stats and the recorder */
void sim_metrics_finish(const sim_ctx *c, const recorder *rec, const ctc_integ_stats *stats,
                        ctc_sim_metrics *mt);

void sim_metrics_free(recorder *rec);

#endif

/*
 * sim.h - one computed torque control simulation: the job a user submits, run to its samples
 * and metrics (paper section 2, DESIGN.md section 6).
 *
 * At each evaluation of the right-hand side, for the state y = (q, v, int e):
 *   e = q_d - q, de = qd_d - v, w = law(t, q, v, q_d, int e), u = qdd_d + w   (per coordinate)
 *   f = iGDCA_controller(q, v, u)              driving forces from the controller's model
 *   qdd = GDCA_plant(q, v, sat(f) + z(t) + J^T W(t))   forward dynamics of the plant, disturbance
 *                                              and external wrenches (wrench.h) added
 * where sat clips each actuator at its limit when spec.plant gives one (plant.h; the integral
 * state is then kept from winding up by clamping), and is the identity otherwise.
 * The controller's model is the plant unless mass or inertia scale factors are given. With
 * controller NONE the run is passive: f = 0 and the plant moves under gravity and z(t) alone.
 * The law is the controller class's (ctrl.h): for the built-in kinds the linear feedback
 * w = ki int(e) + kp e + kv de of the designed gains; a class of the caller's own, nonlinear or
 * not, plugs in through spec.ctrl_class.
 *
 * Units: SI, radians; coordinates are relative joint coordinates (model.h). "Coordinate" means a
 * velocity coordinate (nv of them): one per revolute or prismatic joint, two per cylindrical.
 * Spherical joints are allowed in passive runs only (their quaternion error is not a linear
 * coordinate error, so CTC per coordinate does not apply).
 *
 * Loop models (model.h, loop.h): the controller works on the independent coordinates only (nind
 * of them, in joint order; the closing joint's, computed from the state, included), so gains,
 * trajectories, disturbances, the integral state and the per-coordinate channels have nind
 * entries; the state is the chain's (q, v) and dependent joints move with the loop. The initial
 * state is put onto the closure first (ctc_loop_assemble: q0 of the independent joints is
 * exact, of the dependent ones a guess; v0 of the dependent ones is replaced), and the
 * correction is reported. After every accepted step the stabilisation keeps the state on the
 * closure: "project" (default) moves (q, v) back when the position or velocity residual exceeds
 * loop_tol - rk4 and dopri5 between steps, restarting there (one evaluation), bdf inside CVODE's
 * steps, keeping its order and step-size history (integrator.h ctc_integrator_set_projection);
 * "baumgarte" adds phi'' + 2 a phi' + b^2 phi = 0 to the forward dynamics; "none" integrates as it
 * is and reports the residuals honestly. A run stops as "singular" when the independent joints can
 * no longer drive the loop (the boundary solve's condition estimate beyond loop_cond_max).
 *
 * A run allocates everything before its first step. It runs on the calling thread, helped in the
 * GDCA passes by spec.threads - 1 workers of its own when asked. Any number of runs may go on at
 * once in different threads.
 */
#ifndef CTC_SIM_H
#define CTC_SIM_H

#include <stddef.h>

#include "ctrl.h"
#include "disturb.h"
#include "integrator.h"
#include "loop.h"
#include "model.h"
#include "plant.h"
#include "status.h"
#include "traj.h"
#include "wrench.h"

/* A point on a body whose world position and velocity the end_effector channel records. */
typedef struct ctc_end_effector {
    int body;        /* 0 .. nbodies - 1 */
    double point[3]; /* m, in the body's frame (origin at its joint's centre) */
} ctc_end_effector;

/* Output channels, as bits of ctc_sim_spec.channels. Widths: q nq; qdot nv; energy 2 (kinetic,
 * potential); loop 2; end_effector 6; body_pose 7 per body of spec.pose_bodies; all others nind
 * (the controlled coordinates: nv for an open chain). q_des, qd_des, e and w need a controller,
 * loop a loop model, end_effector spec.end_effector, body_pose spec.pose_bodies. */
typedef enum ctc_channel {
    CTC_CH_Q = 0,  /* q: joint positions (rad, m; quaternions as w, x, y, z) */
    CTC_CH_QD,     /* qdot: joint velocities */
    CTC_CH_Q_DES,  /* q_des: desired positions */
    CTC_CH_QD_DES, /* qdot_des: desired velocities */
    CTC_CH_E,      /* e: tracking error q_des - q */
    CTC_CH_TAU,    /* tau: applied driving force sat(f) + z (N m, N) */
    CTC_CH_W,      /* w: controller output (commanded minus desired acceleration) */
    CTC_CH_ENERGY, /* energy: kinetic and potential (J); potential is zero at the world origin */
    CTC_CH_LOOP,   /* loop: position and velocity residual max-norms of the closure (m or rad,
                      m/s or rad/s); loop models only */
    CTC_CH_EE,     /* end_effector: world position (m) and velocity (m/s) of the point
                      spec.end_effector, x y z vx vy vz; only when the spec gives one */
    CTC_CH_POSE,   /* body_pose: per body of spec.pose_bodies, in their order, the world position
                      of its frame's origin (joint's centre, m) and its orientation as the unit
                      quaternion w x y z of ctc_kinematics_body_rotation (w >= 0,
                      ctc_rotation_quaternion): x y z qw qx qy qz; only when the spec lists bodies */
    CTC_NCHANNELS
} ctc_channel;

#define CTC_CH_BIT(c) (1u << (c))
#define CTC_CH_ALL ((1u << CTC_NCHANNELS) - 1u)

/* How a loop model's state is kept on the closure. */
typedef enum ctc_loop_stab {
    CTC_LOOP_PROJECT = 0, /* project q and v at a step's end whose residual exceeds loop_tol */
    CTC_LOOP_BAUMGARTE,   /* Baumgarte terms in the forward dynamics */
    CTC_LOOP_NONE,        /* neither: the residuals show the drift */
} ctc_loop_stab;

typedef struct ctc_sim_spec {
    ctc_chain_spec chain;             /* the plant */
    const double *q0;                 /* (nq) initial positions; NULL = ctc_model_q_zero */
    const double *v0;                 /* (nv) initial velocities; NULL = 0 */
    ctc_ctrl_type controller;         /* NONE = passive; ignored when ctrl_class is set */
    const ctc_ctrl_class *ctrl_class; /* NULL = ctc_ctrl_classes[controller]; else a class of the
                                         caller's own (ctrl.h), which must outlive the run */
    const void *ctrl_params;    /* passed to the class's law as ctc_ctrl_eval.params; NULL ok */
    const ctc_gains *gains;     /* (nind) designed gains per coordinate (ctrl.h): required by a
                                   class with closed_loop (every built-in active kind), optional
                                   for others (then passed to the law as given); unused if
                                   passive */
    double model_mass_scale;    /* controller's model: every mass times this (> 0; 1 = exact) */
    double model_inertia_scale; /* controller's model: every inertia about the CoM times this */
    /* (nbodies) the controller model's bodies, to which the two scales then apply; NULL = the
       plant's (chain.bodies). The model builder checks them as it checks the plant's */
    const ctc_body_spec *model_bodies;
    /* (3) m/s^2, the controller model's gravity; NULL = the plant's (chain.gravity) */
    const double *model_gravity;
    const ctc_traj *traj;         /* (nind) desired trajectory per coordinate; unused if NONE */
    const ctc_disturb *disturb;   /* (nind) disturbance per coordinate; NULL = none */
    const ctc_plant_coord *plant; /* (nind) the actuator limit per coordinate (plant.h); NULL =
                                     the ideal plant of the paper. Limits need a controller */
    const ctc_wrench *wrenches;   /* (nwrenches) external wrenches on the plant's bodies
                                     (wrench.h); open chains and trees only */
    int nwrenches;                /* 0 = none */
    /* a sampled controller (sim.c): 0 = the paper's continuous law, evaluated in every
       right-hand side. sample_period > 0: the controller measures the state at t_k = k T,
       computes its force there, and the actuator holds it (zero-order hold) until t_k+1; the
       integrator restarts at every t_k, and the integral state is the discrete sum
       xi_k+1 = xi_k + T e_k (clamped as plant.h says). sample_delay d: the force computed at
       t_k is applied from t_k+d on; before t_d the actuator gives 0. */
    double sample_period;    /* s, >= 0 */
    int sample_delay;        /* whole samples, >= 0; > 0 only with sample_period > 0 */
    unsigned long long seed; /* the sensors' noise generator's seed (plant.h) */
    ctc_integ_spec integrator;
    double duration;        /* s, > 0 */
    double output_interval; /* s, > 0: samples at t = 0, dt, 2 dt, ... and at duration */
    unsigned channels;      /* CTC_CH_BIT mask; 0 = every channel that applies */
    /* the end_effector channel's point; NULL = none (the channel does not apply) */
    const ctc_end_effector *end_effector;
    /* (npose) the bodies, 0 .. nbodies - 1, whose poses the body_pose channel records */
    const int *pose_bodies;
    int npose;         /* 0 = none (the channel does not apply) */
    double max_speed;  /* divergence bound on any |v_i| (rad/s, m/s); 0 = 1e6 */
    double wall_limit; /* s of wall time before the run stops as "timeout"; 0 = none */
    /* loop models only */
    ctc_loop_stab loop_stab;
    double loop_tol;      /* projection: the position (m, rad) or velocity (m/s, rad/s)
                             residual that triggers it, and the Newton tolerance; 0 =
                             CTC_SIM_DEFAULT_LOOP_TOL */
    double baumgarte[2];  /* a, b (1/s) for CTC_LOOP_BAUMGARTE; 0, 0 = CTC_SIM_DEFAULT_BAUMGARTE */
    double loop_cond_max; /* stop as singular beyond this condition estimate; 0 =
                             CTC_SIM_DEFAULT_COND_MAX */
    /* threads of the GDCA passes, the calling thread included (data.h ctc_data_set_threads):
       0 or 1 = serial; up to CTC_MAX_THREADS. The run owns its workers (one set for the plant and
       the controller's model, started at the first pass that splits a tree height), so runs in
       different threads never share them; each pass splits only where that is measured to pay
       (gdca_par.h), and the results are bitwise the same for every count (but for open chains of
       2048 planar or 512 spatial bodies or more, whose forward pass may take another assembly
       order on two threads, as measured: there the counts agree to rounding, data.h
       ctc_data_set_threads), and metrics.cpu_s counts the calling thread only */
    int threads;
} ctc_sim_spec;

/* the longest delay of a sampled controller, in samples */
#define CTC_SIM_MAX_DELAY 10000

/* The defaults of loop_tol (the residual, m or rad, or its rate, m/s or rad/s, that triggers a
 * projection, and the Newton tolerance) and of baumgarte's a and b (1/s) */
#define CTC_SIM_DEFAULT_LOOP_TOL 1e-12
#define CTC_SIM_DEFAULT_BAUMGARTE 10.0

/* The default limit on the condition estimates of a closed chain's solves: the inverse pass's
 * closure matrix (gdca_inverse_loop.h) and the forward pass's boundary system (gdca_loop.h), both
 * equilibrated. Regular loops stay well below it: 5 for the paper's five-bar, 1.1e4 for an arch
 * of 4096 rods (bench_loop). Near a singular configuration it grows like 1 / distance from it;
 * a run whose dependent joints pass the speed bound there, before the estimate reaches the
 * limit, is reported as singular too (sim.c). At 1e5 the forces still carry about 11 digits. */
#define CTC_SIM_DEFAULT_COND_MAX 1e5

/* The rows of metrics.err_cause (sim_causes.c). With e_X the error samples of a run whose
 * controller has causes X (S: its sample period and delay, N: its sensors' noise and
 * quantisation, M: its model's error) and otherwise the spec's plant, trajectory, disturbance and
 * integrator, RMS_t(a - b) the root mean square over the output samples:
 *     sampling = RMS(e_S - e_0)      model = RMS(e_M - e_0)
 *     noise    = RMS(e_SN - e_S)     (the sensors are read at the samples only)
 *     total    = RMS(e_SNM - e_0)    (the run itself against the ideal one)
 * A row is 0 when the spec lacks its cause. The ideal run e_0 is the paper's continuous
 * controller with exact sensors and the controller's model equal to the plant (the payload
 * included). */
enum { CTC_CAUSE_SAMPLING = 0, CTC_CAUSE_NOISE, CTC_CAUSE_MODEL, CTC_CAUSE_TOTAL, CTC_NCAUSES };

typedef enum ctc_run_status {
    CTC_RUN_DONE = 0,
    CTC_RUN_DIVERGED,  /* non-finite state or a speed beyond max_speed: time and joint reported */
    CTC_RUN_FAILED,    /* the integrator failed (step size underflow, too many steps) */
    CTC_RUN_CANCELLED, /* the hooks asked to stop */
    CTC_RUN_TIMEOUT,   /* wall_limit reached */
    CTC_RUN_SINGULAR,  /* loop models: the independent joints cannot drive the loop here */
} ctc_run_status;

typedef struct ctc_sim_metrics {
    ctc_form form;        /* the model form the plant was computed in */
    int nv;               /* length of the per-coordinate arrays below (nind) */
    double *e_max;        /* (nv) max |e| over the samples; NULL when passive */
    double *e_rms;        /* (nv) RMS of e over the samples; NULL when passive */
    double *e_final;      /* (nv) e at the last sample; NULL when passive */
    double *tau_peak;     /* (nv) max |sat(f)| over the samples, the actuator's force without the
                             disturbance (N m, N); NULL when passive */
    double *tau_rms;      /* (nv) RMS of sat(f) over the samples; NULL when passive */
    double *sat_fraction; /* (nv) the fraction of the samples at which the actuator was clipped
                             (|f| > limit); NULL without limits */
    /* (CTC_NCAUSES x nv, row-major) the tracking error caused by each of sampling, noise and
       model error, and by the three together (sim_causes.c): RMS over the samples of the
       difference between the errors of two runs that differ by that cause alone; zeros when
       the spec has none of them; NaN when it has one and the run stopped early, or a row's
       counterfactual run did not finish; NULL when passive */
    double *err_cause;
    double energy_drift; /* passive, no disturbance, no wrench: max |E(t) - E(0)| / max(|E(0)|,
                            KE scale); NaN otherwise */
    double errdyn_dev;   /* continuous controller, exact model, no disturbance, no limit, no
                            unknown joint force or wrench: max over samples and coordinates of
                            |E(t) - expm(Ac t) E(0)| for the error state (int e, e, de), the
                            deviation from the linear error dynamics; NaN otherwise */
    long steps, rejected;
    long rhs_evals;      /* evaluations of the dynamics with the forward pass: the integrator's
                            right-hand sides and, for a loop model, one per sample not at a
                            step's end (an open chain's samples need no forward pass) */
    double err_estimate; /* the integrator's accumulated error estimate (integrator.h) */
    /* the tolerance floor of an adaptive run on an open model (sim_tol.c): the tolerances never
       ask for more than the accelerations' rounding allows */
    double accel_rounding;     /* rad/s^2, m/s^2: max |GDCA(iGDCA(a0)) - a0| for the accelerations
                                  a0 at the initial state, their rounding; NaN when not estimated
                                  (rk4, loop models) */
    double tol_rtol, tol_atol; /* the tolerances the run used: the spec's, or raised to the
                                  floor; NaN for rk4 */
    int tol_floored;           /* bit 0: atol was raised, bit 1: rtol was raised */
    char tol_reason[256];      /* why, when raised (e.g. "atol 1e-10 raised to 1.7e-07: ..."),
                                  else empty */
    double wall_s, cpu_s;      /* time spent in the run */
    double us_per_eval;        /* wall microseconds per right-hand-side evaluation */
    double t_end;              /* time reached */
    double step_used;          /* rk4: the step taken (s), the spec's shortened to divide the
                                  output interval (h = dt / ceil(dt / step)); NaN for the adaptive
                                  methods */
    int diverged_joint;        /* joint index (0-based) when DIVERGED, else -1 */
    /* loop models (NaN / 0 otherwise) */
    double loop_res_max;  /* max position residual over the samples and over the ends of the
                             accepted steps before any projection - the drift of one step
                             (m, rad) */
    double loop_vres_max; /* max velocity residual (m/s, rad/s) */
    double loop_cond_max; /* max condition estimate of the boundary solves at the samples */
    long projections;     /* steps at whose end the state was projected */
    ctc_loop_fix initial; /* what putting the initial state onto the closure did (loop.h) */
} ctc_sim_metrics;

typedef struct ctc_sim_result {
    ctc_run_status status;
    char message[256]; /* why a run did not finish, e.g. "t = 1.284 s: joint 2 speed 3.1e+06
                          rad/s exceeds the bound 1e+06"; empty when done */
    int nq, nv, nind;
    unsigned channels;        /* the channels recorded */
    int width[CTC_NCHANNELS]; /* values per sample of each channel (0 if not recorded) */
    int nsamples;
    double *t;                 /* (nsamples) s */
    double *ch[CTC_NCHANNELS]; /* (nsamples x width[c]) row-major; NULL if not recorded */
    ctc_sim_metrics metrics;
} ctc_sim_result;

/* Callbacks between steps; every member may be NULL. */
typedef struct ctc_sim_hooks {
    void *ctx;
    /* called after each output sample with the fraction of the duration done (0..1) */
    void (*progress)(void *ctx, double fraction);
    /* polled after each step: non-zero stops the run as CANCELLED */
    int (*cancelled)(void *ctx);
    /* called after each output sample with the run's result so far: its first r->nsamples
       samples of t and of each channel are final and stay so until ctc_sim_run returns (the
       arrays are sized for the whole run; rows from r->nsamples on are written later, the
       metrics only at the end). Read-only; the pointer is the one ctc_sim_run returns. */
    void (*recorded)(void *ctx, const ctc_sim_result *r);
} ctc_sim_hooks;

/* Checks a spec without running it: the model builds, the arrays are consistent with the
 * controller, each trajectory, disturbance and the integrator check, the output fits the
 * limits. Messages name the item ("duration must be positive (got -1 s)"). */
ctc_status ctc_sim_check(const ctc_sim_spec *spec, char *err, size_t errlen);

/* Runs the simulation. Returns CTC_EINVAL (bad spec, message in err) or CTC_ENOMEM before any
 * step; otherwise CTC_OK and *out owns a new result (ctc_sim_result_free) whose status says how
 * the run ended - a diverged, failed, cancelled or timed-out run keeps the samples taken up to
 * its end. hooks may be NULL. */
ctc_status ctc_sim_run(const ctc_sim_spec *spec, const ctc_sim_hooks *hooks, ctc_sim_result **out,
                       char *err, size_t errlen);

/* Frees a result; NULL is allowed. */
void ctc_sim_result_free(ctc_sim_result *r);

/* Names: "none", "pd", "pid", "poles", "lqr"; "q", "qdot", ...; "done", "diverged", ...;
 * "project", "baumgarte", "none" */
const char *ctc_loop_stab_name(ctc_loop_stab s);
const char *ctc_ctrl_type_name(ctc_ctrl_type t);
const char *ctc_channel_name(ctc_channel c);
const char *ctc_run_status_name(ctc_run_status s);

#endif

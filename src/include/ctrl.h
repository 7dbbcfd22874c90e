/*
 * ctrl.h - controllers for computed torque control: the design of PD, PID, pole placement and LQR
 * gains of one joint coordinate (paper section 6 and Appendix B, DESIGN.md section 6), and the
 * controller interface, one class per kind of controller listed in one table (below).
 *
 * Every controller ctcsim offers is a linear state feedback on the coordinate's tracking error
 * state E = (integral of e, e, de/dt), with e = q_d - q:
 *
 *     commanded acceleration  u = qdd_d + w,    w = ki * int(e) + kp * e + kv * de/dt.
 *
 * With an exact model the inverse dynamics make qdd = u, so the error obeys the linear law
 * e''' + kv e'' + kp e' + ki e = 0 (d/dt of e'' + kv e' + kp e + ki int(e) = 0), whose
 * characteristic polynomial is s^3 + kv s^2 + kp s + ki. PD is ki = 0, where the law reduces to
 * e'' + kv e' + kp e = 0 (s^2 + kv s + kp) and the integral state is only recorded. The design
 * functions turn the user's parameters into (ki, kp, kv) and reject any that do not make the
 * polynomial Hurwitz (every root strictly in the left half plane), with a message saying why.
 *
 * Pole placement and LQR use the paper's state space (Eq. 71-80) with
 * A = [[0,1,0],[0,0,1],[0,0,0]], B = (0,0,1)^T and K = (ki, kp, kv). Since e'' = qdd_d - qdd = -w,
 *     dE/dt = A E - B w,  w = K E,  so  dE/dt = (A - B K) E,
 * the companion matrix of s^3 + kv s^2 + kp s + ki; the paper writes dE/dt = A E + B w' with
 * w' = K' E and K' = -K. The LQR cost and Riccati equation do not depend on the sign of B.
 *
 * Units: gains in s^-3, s^-2, s^-1; poles in s^-1; tau in s.
 * All functions are pure and thread-safe and none allocates (ctc_ctrl_lqr keeps LAPACK's
 * workspace on the stack). The design functions write *out only on success; on failure they
 * return the status and, when err is not NULL, a message of at most errlen bytes naming the
 * parameter and the reason (CTC_EINVAL: the input is invalid or has no acceptable gains;
 * CTC_ESINGULAR: ctc_ctrl_lqr's numerics failed on input that passed validation).
 */
#ifndef CTC_CTRL_H
#define CTC_CTRL_H

#include <stddef.h>

#include "status.h"

/* The built-in kinds, as indices of ctc_ctrl_classes (ctrl.c). */
typedef enum ctc_ctrl_type {
    CTC_CTRL_NONE = 0, /* passive */
    CTC_CTRL_PD,
    CTC_CTRL_PID,
    CTC_CTRL_POLES,
    CTC_CTRL_LQR,
    CTC_CTRL_JOINT_PD,    /* baselines (ctc_ctrl_force): independent joint PD, */
    CTC_CTRL_PD_GRAVITY,  /* PD with gravity compensation, */
    CTC_CTRL_FEEDFORWARD, /* inverse dynamics at the desired state plus PD */
} ctc_ctrl_type;

/* The feedback gains of one coordinate: w = ki int(e) + kp e + kv de/dt. */
typedef struct ctc_gains {
    double ki; /* s^-3 */
    double kp; /* s^-2 */
    double kv; /* s^-1 */
} ctc_gains;

/* PD (ki = 0) or PID gains as given. Requires finite kp > 0, kv > 0 and 0 <= ki < kv kp (Routh:
 * s^3 + kv s^2 + kp s + ki is stable iff all are positive and ki < kv kp; Appendix B, Eq. 96).
 * Errors name the gain, e.g. "kp must be positive and finite (got -1)" or "ki = 250 must be
 * below kv*kp = 200 (Routh-Hurwitz: the closed-loop error dynamics would be unstable)". */
ctc_status ctc_ctrl_pid(double kp, double kv, double ki, ctc_gains *out, char *err, size_t errlen);

/* Gains from a damping ratio zeta > 0 and a time constant tau > 0 (Appendix B, Eq. 92-94):
 * wn = 1 / tau, kp = wn^2, kv = 2 zeta wn, plus the given ki >= 0 (0 for PD), then checked as
 * ctc_ctrl_pid does. A tau so small or large that kp or kv overflows or underflows is
 * rejected. */
ctc_status ctc_ctrl_zeta_tau(double zeta, double tau, double ki, ctc_gains *out, char *err,
                             size_t errlen);

/* Exact gains that place the closed-loop poles at mu_j = re[j] + i im[j] (j = 0..2):
 * (s - mu0)(s - mu1)(s - mu2) = s^3 + kv s^2 + kp s + ki. Each pole must be finite with
 * re < 0 (strictly in the left half plane) and complex poles must come in conjugate pairs
 * (a pole with im != 0 needs another with the same re and -im, to 1e-12 relative to its
 * modulus), e.g. "pole 2 (0.5) is not strictly in the left half plane", "pole 0 (-1+2i) has no
 * conjugate partner". Poles whose gains overflow, underflow or fail the Routh test in double
 * precision (a pair within rounding of the imaginary axis) are rejected too. */
ctc_status ctc_ctrl_poles(const double re[3], const double im[3], ctc_gains *out, char *err,
                          size_t errlen);

/* LQR gains minimising int(E^T Q E + lambda w^2) dt (Eq. 78-80): K = B^T P / lambda with P the
 * stabilising solution of A^T P + P A - P B B^T P / lambda + Q = 0, found from the ordered real
 * Schur form of the (scaled and balanced) Hamiltonian [[A, -B B^T / lambda], [-Q, -A^T]] (LAPACK
 * dgees) and polished by Newton-Kleinman steps, so that each gain is accurate relative to itself
 * over a wide range of lambda (tested from 1e-8 to 1e8). Q (3x3, row-major) must be finite,
 * symmetric (to 1e-12 relative to its largest entry) and positive semidefinite (to 1e-12
 * relative); lambda finite and > 0. Input for which no stabilising solution exists (a mode of A
 * on the imaginary axis that Q does not observe: Q[0][0] = 0 leaves the integral state
 * unpenalised) is rejected with a message saying so, as is input whose Hamiltonian has
 * eigenvalues within 1e-15 (relative) of the imaginary axis. *residual (may be NULL) receives
 * the relative Riccati residual
 *     ||R||_F / (||A^T P + P A||_F + ||P B B^T P||_F / lambda + ||Q||_F),
 *     R = A^T P + P A - P B B^T P / lambda + Q,
 * measured against the size of the equation's terms (for large lambda they dwarf Q and cancel);
 * it is checked to be <= 1e-10 and is NaN when the solve stopped before it. Note ki is always
 * sqrt(Q[0][0] / lambda). Example: Q = I, lambda = 0.01 gives K = (10, 18.2674, 11.6848). */
ctc_status ctc_ctrl_lqr(const double Q[9], double lambda, ctc_gains *out, double *residual,
                        char *err, size_t errlen);

/* The closed-loop poles of g: the three roots of s^3 + kv s^2 + kp s + ki (re[j] + i im[j]),
 * sorted by real part then imaginary part; a conjugate pair is exactly symmetric. For PD
 * (ki = 0) one pole is 0, the recorded integral state's. Each root has a backward error at
 * rounding level; well separated roots are accurate relative to their own size even when their
 * magnitudes differ by many decades. Gains with a non-finite member give NaN poles. */
void ctc_ctrl_closed_loop_poles(const ctc_gains *g, double re[3], double im[3]);

/* ---- the controller interface ----
 *
 * A kind of controller is one ctc_ctrl_class: its name, the design parameters it takes and how
 * it turns them into gains, its law, the size of its own state and its metrics hook. Each lives
 * in its own file (ctrl_pid.c: pd and pid; ctrl_poles.c; ctrl_lqr.c; ctrl.c: none and the linear
 * law they share; ctrl_joint_pd.c, ctrl_pd_gravity.c, ctrl_feedforward.c: the baselines) and is
 * one row of ctc_ctrl_classes; the job parser (server/job_json.c) and the
 * run (sim.h) read everything else from the row. A controller of the caller's own, linear or
 * not, is a class passed in ctc_sim_spec.ctrl_class without a row.
 *
 * The run calls the law once per evaluation of the right-hand side, with every controlled
 * coordinate at once (ctc_ctrl_eval), and it returns the error feedback w (nind); the commanded
 * acceleration is then u_i = qdd_d,i + w_i, the input of the inverse dynamics (sim.h). */

/* The design parameters a job can give, as bits of ctc_ctrl_params.given and of a class's
 * params and required masks. ctc_ctrl_param_name gives each key's name in the job. */
enum {
    CTC_CP_KP = 1u << 0,     /* "kp" (s^-2) */
    CTC_CP_KV = 1u << 1,     /* "kv" (s^-1) */
    CTC_CP_KI = 1u << 2,     /* "ki" (s^-3) */
    CTC_CP_ZETA = 1u << 3,   /* "zeta", damping ratio (1) */
    CTC_CP_TAU = 1u << 4,    /* "tau", time constant (s) */
    CTC_CP_POLES = 1u << 5,  /* "poles": re[3], im[3] (s^-1) */
    CTC_CP_Q = 1u << 6,      /* "Q": 3x3 state weight, row-major */
    CTC_CP_LAMBDA = 1u << 7, /* "lambda": control weight */
};
#define CTC_CP_COUNT 8

/* The parameters given for one coordinate; members whose bit is not in `given` are unset. */
typedef struct ctc_ctrl_params {
    unsigned given; /* CTC_CP_* bits */
    double kp, kv, ki, zeta, tau;
    double re[3], im[3]; /* poles */
    double Q[9];         /* row-major */
    double lambda;
} ctc_ctrl_params;

/* The name of parameter bit CTC_CP_* in jobs ("kp", ..., "lambda"); NULL for any other value. */
const char *ctc_ctrl_param_name(unsigned bit);

/* What a law reads at one evaluation. Shapes in parentheses; units SI and radians. The run owns
 * every array; they are valid during the call only. */
typedef struct ctc_ctrl_eval {
    double t;               /* s */
    int nind;               /* controlled coordinates */
    const double *q, *v;    /* (nq), (nv) the plant's state, quaternions normalised */
    const double *qi, *vi;  /* (nind) the controlled coordinates' positions and rates */
    const double *des;      /* (nind x 3) desired position, rate, acceleration per coordinate */
    const double *xi;       /* (nind) the integral of e = q_d - q per coordinate; NULL when the
                               class has nstate 0 */
    const ctc_gains *gains; /* (nind) ctc_sim_spec.gains; NULL when not given */
    const void *params;     /* ctc_sim_spec.ctrl_params, the caller's own; may be NULL */
} ctc_ctrl_eval;

/* How the run turns a class's output w into the driving forces f, with ID(q, v, a) the inverse
 * dynamics of the controller's model (iGDCA). Computed torque is the paper's controller; the
 * others are the baselines it is compared with in class, whose w is a force (N m, N) and whose
 * gains are then in N m/rad and N m s/rad (N/m, N s/m):
 *   CTC_FORCE_COMPUTED_TORQUE  f = ID(q, v, qdd_d + w)                (w an acceleration)
 *   CTC_FORCE_DIRECT           f = w                                  independent joint control
 *   CTC_FORCE_GRAVITY          f = ID(q, 0, 0) + w                    gravity compensation
 *   CTC_FORCE_FEEDFORWARD      f = ID(q_d, qd_d, qdd_d) + w           the desired motion's forces
 * With an exact model, PD with gravity compensation holds any pose q_d at rest exactly (f is
 * the gravity load there), and the feedforward started on the desired motion stays on it (f is
 * exactly the motion's forces, w = 0). The baselines need an open chain (sim.h). */
typedef enum ctc_ctrl_force {
    CTC_FORCE_COMPUTED_TORQUE = 0,
    CTC_FORCE_DIRECT,
    CTC_FORCE_GRAVITY,
    CTC_FORCE_FEEDFORWARD,
} ctc_ctrl_force;

typedef struct ctc_ctrl_class {
    const char *name;  /* the job's "controller.type": lowercase, unique in ctc_ctrl_classes */
    unsigned params;   /* CTC_CP_* bits the kind accepts (also in "controller.joints" entries) */
    unsigned required; /* CTC_CP_* bits the shared "controller" object must give (checked in bit
                          order, each reported missing as "controller.<key>") */
    int gain_pair;     /* 1: needs exactly one whole pair, "kp" and "kv" or "zeta" and "tau" */
    int nstate;        /* the controller's state per coordinate: 1 = the integral of e,
                          integrated by the run (xi), 0 = none; no other size */
    /* The gains of one coordinate from its parameters (those of `params` that were given, the
     * required ones always): writes *out only on success; on failure returns CTC_EINVAL (or
     * CTC_ESINGULAR, CTC_ENOMEM) and a message naming the parameter, as the design functions
     * above. NULL: the kind takes no gains (none, or a law that reads only `params`). Pure and
     * thread-safe. */
    ctc_status (*design)(const ctc_ctrl_params *p, ctc_gains *out, char *err, size_t errlen);
    /* The law: w (nind, m/s^2 or rad/s^2) from in. Called once per evaluation, from the run's
     * thread, possibly from several runs at once: it must not write anything but w (keep state in
     * xi, not in statics or in params). NULL: the passive kind (no driving forces at all). */
    void (*law)(const ctc_ctrl_eval *in, double *w);
    /* Metrics hook: for a law that is the linear feedback w = K E of the gains, the closed-loop
     * matrix Ac (3x3, row-major) of d/dt E = Ac E, E = (int e, e, de), with which the run checks
     * the error dynamics of an exact model against expm(Ac t) E(0) (sim.h errdyn_dev). Such a
     * class needs gains, checked for stability, and nstate 1. NULL: no such reference. */
    void (*closed_loop)(const ctc_gains *g, double a[9]);
    ctc_ctrl_force force; /* how w becomes forces (above); 0 = computed torque */
} ctc_ctrl_class;

/* The built-in kinds, indexed by ctc_ctrl_type; the one list that names them. */
#define CTC_CTRL_NTYPES 8
extern const ctc_ctrl_class *const ctc_ctrl_classes[CTC_CTRL_NTYPES];

/* The class of a built-in kind; NULL for a value out of range. */
const ctc_ctrl_class *ctc_ctrl_class_of(ctc_ctrl_type t);

/* The built-in kind named `name` ("pid"), or -1. */
int ctc_ctrl_type_of(const char *name);

/* The linear state feedback the built-in kinds share:
 * w_i = ki_i xi_i + kp_i (q_d,i - qi_i) + kv_i (qd_d,i - vi_i), with in->gains (nind). */
void ctc_ctrl_linear_law(const ctc_ctrl_eval *in, double *w);

/* The baselines' law, a PD on forces without integral state:
 * w_i = kp_i (q_d,i - qi_i) + kv_i (qd_d,i - vi_i), with in->gains (nind) in N m/rad, N m s/rad. */
void ctc_ctrl_pd_force_law(const ctc_ctrl_eval *in, double *w);

/* Its closed-loop matrix: Ac = [[0, 1, 0], [0, 0, 1], [-ki, -kp, -kv]] (ctrl.h's header). */
void ctc_ctrl_linear_closed_loop(const ctc_gains *g, double a[9]);

#endif

/*
 * data.h - the mutable state of one simulation: kinematics, handle equations and tree scratch.
 *
 * A ctc_data is allocated once from a model (ctc_data_new) and reused for every evaluation, so
 * nothing is allocated while a run steps. One ctc_data belongs to one thread at a time; many may
 * be made from one model. Vectors of motion and force have the model's dim: 3 in planar form
 * (omega_z, v_x, v_y) / (tau_z, f_x, f_y) in the plane's coordinates, 6 in spatial form
 * (angular; linear) in world coordinates (DESIGN.md section 2). Accelerations are classical: the
 * angular acceleration and the linear acceleration of the handle point itself.
 *
 * Handle equations of a body or an assembly (paper Eq. 10-11, 22-23, 32-33):
 *     A1 = h11 F1 + h12 F2 + h13,    A2 = h12^T F1 + h22 F2 + h23
 * with F_i the load applied on it at handle i; h11 and h22 are symmetric and h21 = h12^T, so one
 * record stores h11, h12, h22 (dim x dim each, row-major), h13 and h23 (dim each). The records
 * are indexed by assembly index (model.h): bodies share one set (paper Eq. 42-43), the internal
 * nodes of the forward and the inverse passes have one set each.
 */
#ifndef CTC_DATA_H
#define CTC_DATA_H

#include "model.h"
#include "options.h"
#include "pool.h"

/* Whether the passes of one evaluation split over threads, by measured cost (pool.h
 * ctc_pool_gate; gdca_par.h): one gate for all of a data's passes, which times whole
 * evaluations, from the ctc_kinematics that starts one at a new state to the end of its last
 * pass that could split. A per-pass choice would miss what a split costs the passes around it: a
 * split pass leaves its records in the other cores' caches, where the next serial pass (the
 * kinematics, the handles, an inverse that runs alone) fetches them, and the tree order can take
 * one more refinement step than the sequential one (bench/NOTEBOOK.md, "Threads on 16 cores"). */
typedef struct ctc_eval_gate {
    ctc_pool_gate gate;
    int open;  /* 1: an evaluation is under way (ctc_kinematics started it) */
    int split; /* its way: 1 split, 0 alone */
    int gated; /* 1: a pass of it asked the way (so it is timed) */
    double t0; /* s (ctc_pool_clock): its start */
    double t1; /* s: the end of its last pass that asked the way */
} ctc_eval_gate;

typedef struct ctc_data {
    int dim;   /* 3 or 6, as the model's */
    int hsize; /* doubles in one handle-equation record: 3 dim^2 + 2 dim */

    /* settings of the passes (options.h): how they compute, not what; ctc_options_default() */
    ctc_options opt;

    /* kinematics, from ctc_kinematics: world frame (planar form: the plane's frame e1, e2, n) */
    double *xpos;  /* (n x 3) origin of body k's frame = its handle 1 = joint k's centre, m */
    double *xrot;  /* (n x 9) orientation of body k, maps body to world coordinates */
    double *xcom;  /* (n x 3) centre of mass, m */
    double *omega; /* (n x 3) angular velocity, rad/s */
    double *xvel;  /* (n x 3) velocity of the frame origin, m/s */

    double *xangle; /* (n) planar form: body k's angle about the plane normal, rad: its parent's
                       plus its signed revolute coordinate */

    /* joint k's maps, world (plane) coordinates: A1(body k) = A2(parent) + P qdd + beta; the
       closing joint of a loop model is k = n (loop.h), with the tip as parent and the ground or
       body b as child. Sized for njoints. */
    double *jnt_P;    /* (njoints x 3 x dim) column c at [(3k + c) dim]; nv columns, orthonormal */
    double *jnt_D;    /* (njoints x dim x dim) column c at [(dim k + c) dim]; dim - nv columns */
    double *jnt_beta; /* (njoints x dim) velocity-product term */

    /* the closing joint (loop models; loop.h) */
    double loop_pt[3];   /* m, its centre on the tip, world */
    double loop_q[4];    /* its coordinates (nq of its type) */
    double loop_v[3];    /* its velocity coordinates (nv of its type) */
    double loop_phi[6];  /* position residual D^T delta (dim - nv entries), m / rad */
    double loop_dphi[6]; /* velocity residual, m/s / rad/s */
    double loop_r[3];    /* a loop on body b: loop_pt minus b's handle 2 (joint b+1's centre), m */
    double loop_gam[6];  /* a loop on body b: (0; w_b x (w_b x loop_r)), what b's classical
                            acceleration at loop_pt adds to the rigid shift of its acceleration at
                            its handle 2 (gdca_loop_shift_accel), m/s^2 */
    double baumgarte[2]; /* forward pass: (a, b) adds D^T(A_t + beta - A_child) = 2 a dphi + b^2
                            phi to the closure, i.e. phi'' + 2 a phi' + b^2 phi = 0 (1/s, 1/s); 0 =
                            none */
    double *xbuf;        /* (2 nvx + nq) loop models: scratch of the passes and loop.c */
    double loop_rho[6];  /* the refinement's closure residual D_n^T (A_t + beta_n - A_child) - off
                            of the accelerations so far (gdca_refine.h), m/s^2 or rad/s^2 */
    double loop_cond;    /* condition estimate of the last closed-chain boundary solve (1 =
                            perfect; inf = singular), after diagonal scaling */

    /* body handle equations, from ctc_handles */
    double *hr;    /* (n x 6) r1, r2: handle positions relative to the centre of mass, m */
    double *hbody; /* (n x hsize) */

    /* GDCA tree records and joint solutions */
    double *hfwd;          /* (ntree x hsize; 2n x hsize for a branched tree) forward assemblies;
                              in the sequential order slot i holds S_i or B_i and their joint's K
                              (gdca_forward_seq.c, gdca_forward_tseq.c) */
    double *hinv;          /* (ntree x hsize) inverse assemblies of the mobility form */
    double *fwd_E;         /* (n x dim^2) joint k: factor E of W = E E^T = D (D^T K D)^-1 D^T */
    double *fwd_z;         /* (n x dim)   joint k: W Y + P f */
    int fwd_refine_done;   /* steps the last ctc_gdca_forward made and kept */
    int fwd_refine_undone; /* 1: the last ctc_gdca_forward undid a step whose residual grew
                              (gdca_refine.h) */
    double *fwd_res;       /* (4 nvx) the refinement's force residual, its correction, the last
                              step's correction, and the accelerations before the last step */
    double *fwd_load_prev; /* (njoints x dim) jnt_load before the refinement's last step */
    double *inv_E;         /* (n x dim^2) joint k: factor E of X = E E^T = K^-1 (mobility form) */
    double *inv_z;         /* (n x dim)   joint k: X Y' (mobility form) */
    int csize;             /* doubles in one composite record: dim^2 + 2 dim + 3 */
    double *icomp;   /* ((2n - 1) x csize) inverse assemblies in composite form (gdca_inverse.c):
                        I (dim x dim), w (dim), c (dim), r12 (3) */
    double *icomp_e; /* (n x dim) joint k: A1(right) = T(r12 left) A1(left) + e */
    double *rake;    /* (n x (dim^2 + dim)) a branched tree's raked bodies: M'^-1 and x0 of the
                        pseudo-body (gdca_rake.h), at the body's index */
    double *tload;   /* ((2n - 1) x 2 dim) per assembly during a disassembly: F1 and F2
                        (forward, mobility inverse) or A1 and F2 (composite inverse); the
                        sequential forward order keeps each joint's load at [dim k] */

    /* results */
    double *jnt_load;     /* (njoints x dim) load on body k at joint k from the forward pass,
                             N m / N; k = n: the load of the closing joint on its child (the
                             ground, or body b) */
    double *jnt_load_inv; /* (njoints x dim) the same from the inverse pass (loop models: only
                             the joints the pruned disassembly reaches, model.h inv_need). A
                             refined ctc_gdca_forward overwrites it with its residual pass's loads
                             (gdca_refine.h; on a loop model those of the open chain, without
                             the closing load): read it right after ctc_gdca_inverse */
    int singular_joint;   /* -1, or a joint whose matrix K was not positive definite */

    /* threads of the GDCA passes (gdca_par.h); set with ctc_data_set_threads */
    int threads;                 /* the passes may use this many threads, the caller's included:
                                    1 (default) = serial */
    struct ctc_pool *pool;       /* the workers: started by the first pass that splits a stage,
                                    stopped by ctc_data_free or a new thread count; else NULL */
    int pool_failed;             /* 1: the pool could not start; serial until threads change */
    struct ctc_data *pool_owner; /* NULL, or the data whose threads and pool d uses
                                    (ctc_data_share_pool) */
    /* whether an evaluation's passes run alone or split (ctc_eval_gate above): d's own gate,
       reset when the thread count changes; a reduced model's data (dyn below) uses its
       parent's, through eval_of (NULL: d->eval) */
    ctc_eval_gate eval;
    ctc_eval_gate *eval_of;
    int fwd_split; /* the way the last ctc_gdca_forward took on an open model: 1 the balanced
                      tree split over threads, 0 the sequential order (gdca_forward_seq.h) */

    /* state stamps: ctc_handles increments handles_stamp (a new state); the composite inverse
       sets icomp_stamp to it once icomp holds the parts of its records that depend on the
       state only (the body records, the nodes' I and r12), and while the two match it
       recomputes only w, c and icomp_e (gdca_inverse.c); ctc_handles_bias sets hbias_stamp to
       it once hbody holds the state's bias terms h13 and h23 (handles.h) */
    unsigned long long handles_stamp;
    unsigned long long icomp_stamp;
    unsigned long long hbias_stamp;

    /* a model with merged bodies (model.h): the reduced model's data, which the dynamics passes
       use (ctc_data_dyn_begin); its kinematics are copied from d's by ctc_kinematics, its
       settings, threads and evaluation gate are d's. NULL when m->dyn is NULL.
       Owned by d. */
    struct ctc_data *dyn;
} ctc_data;

/* Allocates a data block sized for m; NULL when out of memory. Free with ctc_data_free. */
ctc_data *ctc_data_new(const ctc_model *m);

/* Frees d and stops its worker threads, if any; NULL is allowed. */
void ctc_data_free(ctc_data *d);

/* Lets the GDCA passes on d (gdca.h) split the nodes of each large tree height over nthreads
 * threads, the calling thread included: 1 (the default) is serial, at most CTC_MAX_THREADS
 * (pool.h). Heights too small to pay for the split still run on the calling thread (gdca_par.h).
 * The nthreads - 1 workers start at the first pass that uses them and belong to d: they stop when
 * d is freed or its count changes, so no two data share them unless ctc_data_share_pool says so.
 * Whether the passes split is measured, evaluation by evaluation (ctc_eval_gate above): where
 * the split would make an evaluation slower, its passes run on the calling thread. The results are
 * bitwise the same for every count, with one exception: an open chain's (or tree's) forward pass
 * takes the sequential order on one thread and, from a least length on (planar 2048, spatial 512
 * bodies; chains' figures, used for trees too), on two threads or more whichever of it and the
 * balanced tree split (the plan) the gate measures faster (gdca_forward_seq.h, opt.fwd_order), so
 * at those lengths any two counts agree to rounding, evaluation by evaluation bitwise equal to one
 * of the two orders. Returns CTC_OK, or CTC_EINVAL with a message in err (errlen bytes; may be
 * NULL) when nthreads is out of range. */
ctc_status ctc_data_set_threads(ctc_data *d, int nthreads, char *err, size_t errlen);

/* Makes d's passes use owner's thread count and workers instead of its own, for two data used in
 * turn by one thread (a simulation's plant and its controller's model): one set of workers then
 * serves both. owner must stay alive while d uses it; NULL returns d to its own setting. */
void ctc_data_share_pool(ctc_data *d, ctc_data *owner);

/* Starts an evaluation at a new state (ctc_kinematics calls it; with threads > 1 only): records
 * the time of the last one in d's gate, where a pass of it asked the way, and takes the next
 * one's way (pool.h ctc_pool_gate_way). */
void ctc_data_eval_begin(ctc_data *d);

/* Whether a pass that could split does, in the evaluation under way: 1 with opt.par_split or
 * par_grain (a forced split), else the gate's way for it (0 before any ctc_kinematics); marks
 * the evaluation as timed. */
int ctc_data_eval_split(ctc_data *d);

/* At the end of a pass that asked ctc_data_eval_split: the evaluation's time runs to here. */
void ctc_data_eval_pass_done(ctc_data *d);

/* For a model with merged bodies (m->dyn, model.h): d->dyn with d's settings (opt, baumgarte)
 * and threads (d's workers, or those d shares) copied in, for a pass on m->dyn. */
ctc_data *ctc_data_dyn_begin(const ctc_model *m, ctc_data *d);

/* After a pass on m->dyn with ctc_data_dyn_begin: copies its results back into d in m's
 * numbering: jnt_load and jnt_load_inv (0 on merged bodies' fixed joints), singular_joint,
 * loop_cond, fwd_refine_done, fwd_refine_undone and fwd_split. */
void ctc_data_dyn_end(const ctc_model *m, ctc_data *d);

/* The record of assembly index a: a body's (a < n), or internal node a - n's of the forward
 * (inverse = 0) or the mobility-form inverse (inverse = 1) pass. */
static inline double *ctc_data_handles(const ctc_model *m, const ctc_data *d, int a, int inverse)
{
    if (a < m->nbodies) return d->hbody + (size_t)a * d->hsize;
    return (inverse ? d->hinv : d->hfwd) + (size_t)(a - m->nbodies) * d->hsize;
}

#endif

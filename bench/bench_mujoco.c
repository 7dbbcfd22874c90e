/*
 * bench_mujoco.c - ctcsim against MuJoCo 2.2.2 (Debian's libmujoco): one CTC right-hand side on
 * serial chains of 2 ... max_n bodies (MuJoCo up to 1024) and on Featherstone's autoTree, whole
 * CTC simulations at equal error, and a stiff 64-link chain on which MuJoCo's RK4 at 1 ms
 * diverges.
 *
 * The chains are built once as ctcsim specs (tests/support/chains.h) and written out as MJCF with
 * the same masses, centres of mass, inertias, joint axes and locations and gravity: one body per
 * ctcsim body, a hinge at its frame origin, an explicit <inertial>, no geoms, contacts disabled,
 * no damping or armature. Debian's tinyxml2 (9.0) refuses XML nested more than 100 elements
 * deep, so the body tree is split into files of MJCF_SEGMENT bodies, each <include>d inside the
 * innermost body of the one before, all in a MuJoCo virtual file system. A slender rod's inertia
 * is singular, which MuJoCo's compiler rejects; such a body gets a tiny moment along its own
 * axis (the direction of its centre of mass), which a planar chain never turns about, so the
 * dynamics are unchanged (checked against ctcsim to 1e-8, below).
 *
 * 1. One CTC right-hand side, f = M(q) u + c(q, v), then qdd = M(q)^-1 (f - c(q, v)), against
 *    MuJoCo and DART:
 *      ctcsim  kinematics + handles + iGDCA (composite form) + GDCA forward, as bench_dynamics's
 *              "ctc" column;
 *      MuJoCo  as a CTC loop would call it: mj_fwdPosition and mj_fwdVelocity once, shared by
 *              both halves (kinematics, composite inertias, the factorisation of M and the bias
 *              forces), then mj_inverseSkip(mjSTAGE_VEL) for qfrc_inverse (2.2.2: inverse
 *              constraint forces, none here, and RNE with accelerations), then the forward
 *              acceleration stages mj_fwdActuation, mj_fwdAcceleration (solve with the LDL'
 *              factor) and mj_fwdConstraint (no constraints: qacc = qacc_smooth).
 *      DART    6.12 (Debian's libdart-dev; dart_peer.h): computeInverseDynamics for tau, then
 *              computeForwardDynamics, its O(n) articulated-body pass, at the same state (the
 *              skeleton's cached kinematics shared), on every n; skipped, with a line saying
 *              why, in a build without DART's headers.
 *    MuJoCo's stages are also timed alone, and within the position stage mj_crb and mj_factorM.
 *    Before timing, each case checks that ctcsim's iGDCA forces equal MuJoCo's qfrc_inverse for
 *    random u, and ctcsim's GDCA accelerations MuJoCo's qacc for random torques, both to 1e-8
 *    relative to the largest entry, and against DART's inverse and forward dynamics to
 *    DART_CHECK_TOL (1e-10); a case that fails is reported and not timed, and the run ends with
 *    status 1. Timing as in bench_loop: batches of every timing interleaved, each batch
 *    starting one timing further on, each timing run untimed for SETTLE_S before it is timed;
 *    medians over the batches. MuJoCo is skipped beyond MJ_MAX_N (its factorisation is O(n^3)
 *    on a serial chain) and calls slower than SLOW_S get fewer batches (SLOW_BATCHES).
 *
 * 1t. The same right-hand side, timed the same way (ctcsim's and MuJoCo's only), on autoTree
 *    (tests/support/chains.h: taper 1, branching factor 1, 2 and 4, planar with no skew and
 *    spatial with skew 0.5 rad, n = 16, 64, ..., max_n), as bench_dynamics's part a times it
 *    against the oracle. The tree is written as nested MJCF bodies (mj_load_tree: the chains'
 *    body elements, a subtree moved into an <include>d file where one file would nest
 *    MJCF_SEGMENT bodies). MuJoCo numbers bodies depth first, ctcsim as the spec does (autoTree
 *    breadth first), so states, forces and accelerations are mapped through MuJoCo's joint
 *    j<k> of ctcsim's body k. Checked first at a random state: tau from iGDCA against
 *    qfrc_inverse, and qdd from GDCA against qacc for other random torques, both to
 *    TREE_CHECK_TOL (1e-10) relative to the largest entry, or to CHECK_TOL on bf 1, a chain
 *    (its M's conditioning grows with n); a tree that fails is reported, not timed, and the run
 *    ends with status 1. MuJoCo is skipped where the longest path exceeds MJ_MAX_N (bf 1
 *    beyond 1024: M is dense along a path).
 *
 * 2. Whole 5 s CTC simulations, sampled every 0.01 s: the paper's triple pendulum PID run
 *    (bench_sim) and a 64-link planar rod chain under PD. ctcsim: ctc_sim_run with DOPRI5 at
 *    several tolerances. MuJoCo: mj_step with its RK4 at several dt, the same controller in
 *    mjcb_control, its torques from MuJoCo's own inverse dynamics (mj_inverseSkip after the
 *    velocity stage: CTC with MuJoCo's model). Two ways:
 *      stagewise  the controller is evaluated at every RK4 stage (mjcb_control runs in each of
 *                 the four mj_forwardSkip calls of a step), so MuJoCo integrates the same ODE as
 *                 ctcsim, continuous controller included; the PID integral state is the
 *                 activation of an integrator actuator of zero gain per joint (ctrl = e, so
 *                 act = int e, integrated by RK4 with the rest of the state);
 *      hold       the controller is evaluated once per step, at its start, and its torque and e
 *                 are held over the step (a zero-order hold, as a loop computing tau before each
 *                 mj_step would do, without evaluating the position stage twice).
 *    Both sides record the same outputs at every sample - q, qdot, q_des, qdot_des, e, w, tau
 *    and the energy, ctcsim's default channels: ctcsim as sim.c does (no forward pass for a
 *    sample), MuJoCo in the first stage of the step that starts from the sample (its position
 *    stage is there; the energy from mj_energyPos and mj_energyVel), the last sample by one more
 *    mj_forward. The reference check compares the recorded tau and energy as well as q.
 *    Error = max over the samples and joints of |q - q_ref|, q_ref from ctcsim's DOPRI5 at
 *    rtol 1e-12, which is first compared with MuJoCo stagewise at dt = 1e-4. The hold runs
 *    converge to q_ref only as dt -> 0 (first order): their error is mostly the hold's. Times
 *    are medians over interleaved rounds; ctcsim's is ctc_sim_run's own (metrics.cpu_s, model
 *    build to last sample), MuJoCo's the loop from mj_resetData to the last sample (the XML is
 *    loaded once, outside). ctcsim RK4 at MuJoCo's dt integrates the same ODE with the same
 *    method, so its errors equal MuJoCo stagewise's and the times compare the evaluations.
 *    Equal error: each ctcsim run's error is placed on MuJoCo stagewise's work-precision curve,
 *    interpolated linearly in log(time) against log(error) between neighbouring dt.
 *
 * 3. The 64-link chain with stiff PD gains kp = w^2, kv = 2 w (a double closed-loop pole at -w):
 *    at dt = 1 ms, which w makes MuJoCo diverge (stagewise and hold), and on the first w where
 *    stagewise diverges, what ctcsim's adaptive DOPRI5 (and BDF) do, against MuJoCo at smaller
 *    dt. The reference there is DOPRI5 at rtol 1e-10 (about 150,000 steps; 1e-12 takes three
 *    times as many: bench/NOTEBOOK.md, "A stiff 64-link chain"). Single runs.
 *
 * Every time here is this thread's CPU time (CLOCK_THREAD_CPUTIME_ID), not wall time: on cores
 * shared with other work a wall clock charges the other work's time slices to whichever timing
 * they interrupt - often to more than half of the batches of a case, which medians cannot
 * remove. On an idle machine the two clocks agree.
 *
 * Usage: bench_mujoco [max_n [batches [parts]]]; parts: any of r (right-hand side), t (the same on
 * autoTree), s (simulations), d (divergence); default 4096 15 rtsd.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <mujoco/mujoco.h>

#include "chains.h"
#include "ctc.h"
#include "dart_peer.h"
#include "sim.h"

#define PI 3.14159265358979323846
#define MJCF_SEGMENT 40      /* bodies per MJCF file: keeps every file under tinyxml2's depth 100 */
#define MJ_MAX_N 1024        /* MuJoCo is timed up to this n */
#define CHECK_TOL 1e-8       /* agreement of ctcsim and MuJoCo, relative to the largest entry */
#define DART_CHECK_TOL 1e-10 /* the same for ctcsim and DART */
#define TREE_CHECK_TOL 1e-10 /* the same on branched autoTrees (part 1t; bf 1: CHECK_TOL) */
#define SETTLE_S 5e-3        /* s, untimed runs before each timing in a batch */
#define BATCH_S 2e-3         /* s, length of one timed batch of fast calls */
#define SLOW_S 10e-3         /* s, a call slower than this gets SLOW_BATCHES batches */
#define SLOW_BATCHES 7       /* batches for a timing slower than SLOW_S */
#define MAX_SPEED 1e6        /* rad/s, divergence bound (ctc_sim_spec's default) */
#define REF_DT 1e-4          /* s, MuJoCo stagewise run checked against the reference */
#define MAX_CONFIGS 32

static volatile double sink;

static double clock_s(clockid_t clock)
{
    struct timespec ts;
    clock_gettime(clock, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* the clock every timing here uses: this thread's CPU time (see the top of the file) */
static double now(void)
{
    return clock_s(CLOCK_THREAD_CPUTIME_ID);
}

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* median of x (n), which it sorts */
static double median_sort(double *x, int n)
{
    qsort(x, (size_t)n, sizeof *x, cmp_double);
    return n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
}

static void *xcalloc(size_t n, size_t size)
{
    void *p = calloc(n ? n : 1, size);
    if (!p) {
        fprintf(stderr, "bench_mujoco: out of memory\n");
        exit(1);
    }
    return p;
}

/* max |a - b| / max(|b|, tiny) over n entries */
static double rel_diff(const double *a, const double *b, int n)
{
    double d = 0, s = 0;
    for (int i = 0; i < n; i++) {
        d = fmax(d, fabs(a[i] - b[i]));
        s = fmax(s, fabs(b[i]));
    }
    return d / fmax(s, 1e-300);
}

/* ---------------------------------------------------------------------------------------------
 * MJCF from a ctcsim chain
 */

/* a growing text buffer */
typedef struct strbuf {
    char *s;
    size_t len, cap;
} strbuf;

static void sb_printf(strbuf *b, const char *fmt, ...)
{
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int k = vsnprintf(b->s ? b->s + b->len : NULL, b->s ? b->cap - b->len : 0, fmt, ap);
        va_end(ap);
        if (k < 0) abort();
        if (b->s && b->len + (size_t)k < b->cap) {
            b->len += (size_t)k;
            return;
        }
        b->cap = 2 * (b->cap + (size_t)k) + 256;
        b->s = realloc(b->s, b->cap);
        if (!b->s) abort();
    }
}

/* Body k's inertia for MuJoCo: as given, or for a singular (slender rod) inertia plus a tiny
 * moment along the direction of its centre of mass, which must be normal to every joint axis
 * (a planar chain), so that no angular velocity of the chain ever has a component along it. */
static void mj_inertia(const ctc_chain_spec *s, int k, double out[9])
{
    const ctc_body_spec *b = &s->bodies[k];
    const double *in = b->inertia;
    memcpy(out, in, sizeof b->inertia);
    double det = in[0] * (in[4] * in[8] - in[5] * in[7]) - in[1] * (in[3] * in[8] - in[5] * in[6]) +
                 in[2] * (in[3] * in[7] - in[4] * in[6]);
    double tr = in[0] + in[4] + in[8];
    if (det > 1e-9 * tr * tr * tr) return;
    double c = sqrt(b->com[0] * b->com[0] + b->com[1] * b->com[1] + b->com[2] * b->com[2]);
    for (int j = 0; j < s->nbodies && c > 0; j++) {
        const double *a = s->joints[j].axis;
        double an = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        if (fabs(a[0] * b->com[0] + a[1] * b->com[1] + a[2] * b->com[2]) > 1e-12 * an * c) c = 0;
    }
    if (c == 0) {
        fprintf(stderr, "bench_mujoco: body %d: singular inertia off a planar chain\n", k);
        exit(1);
    }
    double eps = 1e-6 * tr;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) out[3 * i + j] += eps * b->com[i] * b->com[j] / (c * c);
}

/* Opens body k's element in b: its frame at the joint's location in the parent's frame, parallel
 * to the parent's at q = 0 (model.h), its hinge at the frame origin, its inertial. Ends the run on
 * a joint that is not revolute. */
static void sb_body_open(strbuf *b, const ctc_chain_spec *s, int k)
{
    const ctc_joint_spec *j = &s->joints[k];
    const ctc_body_spec *bd = &s->bodies[k];
    if (j->type != CTC_JOINT_REVOLUTE) {
        fprintf(stderr, "bench_mujoco: joint %d is not revolute\n", k);
        exit(1);
    }
    double in[9];
    mj_inertia(s, k, in);
    sb_printf(b,
              "<body name='b%d' pos='%.17g %.17g %.17g'>"
              "<joint name='j%d' type='hinge' axis='%.17g %.17g %.17g'/>"
              "<inertial pos='%.17g %.17g %.17g' mass='%.17g' "
              "fullinertia='%.17g %.17g %.17g %.17g %.17g %.17g'/>\n",
              k, j->location[0], j->location[1], j->location[2], k, j->axis[0], j->axis[1],
              j->axis[2], bd->com[0], bd->com[1], bd->com[2], bd->mass, in[0], in[4], in[8], in[1],
              in[2], in[5]);
}

/* adds b's text to vfs as the file name, or ends the run */
static void vfs_put(mjVFS *vfs, const char *name, const strbuf *b)
{
    if (mj_makeEmptyFileVFS(vfs, name, (int)b->len) != 0) {
        fprintf(stderr, "bench_mujoco: MuJoCo's VFS is full\n");
        exit(1);
    }
    memcpy(vfs->filedata[mj_findFileVFS(vfs, name)], b->s, b->len);
}

/* Loads the chain into MuJoCo (revolute joints only): RK4, the given timestep, contacts off.
 * integral != 0 adds one integrator actuator of zero gain per joint, whose activation holds the
 * integral of the joint's tracking error (act_dot = ctrl). Returns a new model or ends the run. */
static mjModel *mj_load_chain(const ctc_chain_spec *s, int integral, double timestep)
{
    int n = s->nbodies, nseg = (n + MJCF_SEGMENT - 1) / MJCF_SEGMENT;
    mjVFS *vfs = xcalloc(1, sizeof *vfs);
    mj_defaultVFS(vfs);
    strbuf b = {0};
    for (int seg = 0; seg < nseg; seg++) {
        b.len = 0;
        sb_printf(&b, "<mujoco model='ctcsim_chain'>\n");
        if (seg == 0)
            sb_printf(&b,
                      "<option timestep='%.17g' integrator='RK4' gravity='%.17g %.17g %.17g'>"
                      "<flag contact='disable'/></option>\n<worldbody>\n",
                      timestep, s->gravity[0], s->gravity[1], s->gravity[2]);
        int k0 = seg * MJCF_SEGMENT, k1 = k0 + MJCF_SEGMENT < n ? k0 + MJCF_SEGMENT : n;
        for (int k = k0; k < k1; k++) sb_body_open(&b, s, k);
        if (seg + 1 < nseg) sb_printf(&b, "<include file='chain%d.xml'/>\n", seg + 1);
        for (int k = k0; k < k1; k++) sb_printf(&b, "</body>");
        if (seg == 0) {
            sb_printf(&b, "\n</worldbody>\n");
            if (integral) {
                sb_printf(&b, "<actuator>\n");
                for (int k = 0; k < n; k++)
                    sb_printf(&b,
                              "<general joint='j%d' dyntype='integrator' gainprm='0' "
                              "biasprm='0 0 0'/>\n",
                              k);
                sb_printf(&b, "</actuator>\n");
            }
        }
        sb_printf(&b, "</mujoco>\n");
        char name[32];
        snprintf(name, sizeof name, "chain%d.xml", seg);
        vfs_put(vfs, name, &b);
    }
    char err[1000] = "";
    mjModel *m = mj_loadXML("chain0.xml", vfs, err, sizeof err);
    mj_deleteVFS(vfs);
    free(vfs);
    free(b.s);
    if (!m || m->nv != n) {
        fprintf(stderr, "bench_mujoco: MuJoCo cannot load the %d-body chain: %s\n", n, err);
        exit(1);
    }
    return m;
}

/* the MJCF of a tree: its spec, each body's first child and next sibling (-1: none) */
typedef struct mjcf_tree {
    const ctc_chain_spec *s;
    const int *first_child, *next_sibling; /* (n) */
    mjVFS *vfs;
} mjcf_tree;

/* Writes body k and its subtree into b, where k is nested depth bodies deep in b's file. Where a
 * file would nest MJCF_SEGMENT bodies, k's children go into a file of their own (tree<k>.xml),
 * <include>d inside k, as the chains' segments are. */
static void mjcf_subtree(const mjcf_tree *t, strbuf *b, int k, int depth)
{
    sb_body_open(b, t->s, k);
    if (t->first_child[k] >= 0 && depth + 1 < MJCF_SEGMENT) {
        for (int c = t->first_child[k]; c >= 0; c = t->next_sibling[c])
            mjcf_subtree(t, b, c, depth + 1);
    } else if (t->first_child[k] >= 0) {
        strbuf sub = {0};
        sb_printf(&sub, "<mujoco model='ctcsim_tree'>\n");
        for (int c = t->first_child[k]; c >= 0; c = t->next_sibling[c]) mjcf_subtree(t, &sub, c, 0);
        sb_printf(&sub, "</mujoco>\n");
        char name[32];
        snprintf(name, sizeof name, "tree%d.xml", k);
        vfs_put(t->vfs, name, &sub);
        free(sub.s);
        sb_printf(b, "<include file='%s'/>\n", name);
    }
    sb_printf(b, "</body>\n");
}

/* Loads a tree (s->parent, or a chain when NULL; revolute joints only) into MuJoCo as nested
 * bodies, with the same body elements as mj_load_chain and no actuators; MuJoCo numbers the bodies
 * depth first, so its body and dof of ctcsim's body k are found by name (b<k>, j<k>). Returns a
 * new model or ends the run. */
static mjModel *mj_load_tree(const ctc_chain_spec *s, double timestep)
{
    int n = s->nbodies;
    int *first_child = xcalloc((size_t)n, sizeof(int)),
        *next_sibling = xcalloc((size_t)n, sizeof(int));
    int *roots_last = xcalloc((size_t)n + 1, sizeof(int)); /* children of the ground, in order */
    int nroots = 0;
    for (int k = 0; k < n; k++) first_child[k] = next_sibling[k] = -1;
    /* children in increasing order: link from the last body back */
    for (int k = n - 1; k >= 0; k--) {
        int p = s->parent ? s->parent[k] : k - 1;
        if (p < 0) continue;
        next_sibling[k] = first_child[p];
        first_child[p] = k;
    }
    for (int k = 0; k < n; k++)
        if ((s->parent ? s->parent[k] : k - 1) < 0) roots_last[nroots++] = k;
    mjVFS *vfs = xcalloc(1, sizeof *vfs);
    mj_defaultVFS(vfs);
    mjcf_tree t = {s, first_child, next_sibling, vfs};
    strbuf b = {0};
    sb_printf(&b,
              "<mujoco model='ctcsim_tree'>\n<option timestep='%.17g' integrator='RK4' "
              "gravity='%.17g %.17g %.17g'><flag contact='disable'/></option>\n<worldbody>\n",
              timestep, s->gravity[0], s->gravity[1], s->gravity[2]);
    for (int r = 0; r < nroots; r++) mjcf_subtree(&t, &b, roots_last[r], 0);
    sb_printf(&b, "</worldbody>\n</mujoco>\n");
    vfs_put(vfs, "tree.xml", &b);
    char err[1000] = "";
    mjModel *m = mj_loadXML("tree.xml", vfs, err, sizeof err);
    mj_deleteVFS(vfs);
    free(vfs);
    free(b.s);
    free(first_child), free(next_sibling), free(roots_last);
    if (!m || m->nv != n) {
        fprintf(stderr, "bench_mujoco: MuJoCo cannot load the %d-body tree: %s\n", n, err);
        exit(1);
    }
    return m;
}

static double inertia_adjust_max; /* largest relative change of an inertia in MuJoCo's hands */

/* Gives the ctcsim chain the inertias (and masses and centres of mass) MuJoCo compiled. MuJoCo
 * stores each body's inertia as principal moments in a principal frame found by an iterative
 * eigen-decomposition, which moves the random spatial inertias here by up to 1e-6 relative and,
 * alone, the accelerations of the spatial chains by 1e-8 to 5e-7 (n = 4 ... 256). With the same
 * numbers on both sides, the checks compare the algorithms, not the inputs. */
static void adopt_mj_inertia(test_chain *chain, const mjModel *m)
{
    for (int k = 0; k < chain->spec.nbodies; k++) {
        ctc_body_spec *b = &chain->bodies[k];
        double rot[9], in[9], given[9], scale = 0, change = 0;
        mj_inertia(&chain->spec, k, given);
        /* MuJoCo numbers bodies depth first in the order of the MJCF, ctcsim as its spec does */
        char name[32];
        snprintf(name, sizeof name, "b%d", k);
        int mb = mj_name2id(m, mjOBJ_BODY, name);
        const double *moments = m->body_inertia + 3 * mb;
        mju_quat2Mat(rot, m->body_iquat + 4 * mb);
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                in[3 * i + j] = 0;
                for (int l = 0; l < 3; l++)
                    in[3 * i + j] += rot[3 * i + l] * moments[l] * rot[3 * j + l];
            }
        for (int i = 0; i < 9; i++) {
            scale = fmax(scale, fabs(given[i]));
            change = fmax(change, fabs(in[i] - given[i]));
        }
        for (int i = 0; i < 3; i++) b->com[i] = m->body_ipos[3 * mb + i];
        b->mass = m->body_mass[mb];
        /* symmetric to the last bit */
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < i; j++) in[3 * i + j] = in[3 * j + i];
        memcpy(b->inertia, in, sizeof in);
        inertia_adjust_max = fmax(inertia_adjust_max, change / scale);
    }
}

/* MuJoCo's warnings (bad qacc resets the state, for example) are counted in mjData; this keeps
 * them off stdout and out of MUJOCO_LOG.TXT */
static void mj_quiet(const char *msg)
{
    (void)msg;
}

/* ---------------------------------------------------------------------------------------------
 * 1. One CTC right-hand side
 */

enum { T_CTC, T_DART, T_MJ, T_MJ_POS, T_MJ_CRB, T_MJ_FACT, T_MJ_VEL, T_MJ_INV, T_MJ_ACC, NT };

typedef struct rhs_case {
    const ctc_model *cm;
    ctc_data *cd;
    mjModel *m; /* NULL: without MuJoCo */
    mjData *d;
    dart_peer *dart;      /* NULL: without DART */
    double *dtau, *dqdd;  /* DART's forces and accelerations */
    double *q, *v, *u;    /* the state and the commanded accelerations */
    double *mq, *mv, *mu; /* the same in MuJoCo's order (q, v, u themselves on a chain) */
    double *f, *a;        /* ctcsim's forces and accelerations */
    double *tau;          /* MuJoCo's forces */
} rhs_case;

static void run_once(rhs_case *c, int what)
{
    const mjModel *m = c->m;
    mjData *d = c->d;
    int nv = c->cm->nv;
    switch (what) {
    case T_CTC:
        ctc_kinematics(c->cm, c->cd, c->q, c->v);
        ctc_handles(c->cm, c->cd);
        ctc_gdca_inverse(c->cm, c->cd, c->u, c->f);
        ctc_gdca_forward(c->cm, c->cd, c->f, c->a);
        sink += c->a[0];
        return;
    case T_DART:
        dart_peer_rhs(c->dart, c->q, c->v, c->u, c->dtau, c->dqdd);
        sink += c->dqdd[0];
        return;
    case T_MJ:
        /* shared: kinematics, composite inertias, M and its factor, bias forces */
        mju_copy(d->qpos, c->mq, nv);
        mju_copy(d->qvel, c->mv, nv);
        mj_fwdPosition(m, d);
        mj_fwdVelocity(m, d);
        /* inverse: tau = M u + c */
        mju_copy(d->qacc, c->mu, nv);
        mj_inverseSkip(m, d, mjSTAGE_VEL, 1);
        /* forward: qacc = M^-1 (tau - c) */
        mju_copy(d->qfrc_applied, d->qfrc_inverse, nv);
        mj_fwdActuation(m, d);
        mj_fwdAcceleration(m, d);
        mj_fwdConstraint(m, d);
        break;
    case T_MJ_POS:
        mju_copy(d->qpos, c->mq, nv);
        mju_copy(d->qvel, c->mv, nv);
        mj_fwdPosition(m, d);
        break;
    case T_MJ_CRB:
        mj_crb(m, d);
        break;
    case T_MJ_FACT:
        mj_factorM(m, d);
        break;
    case T_MJ_VEL:
        mj_fwdVelocity(m, d);
        break;
    case T_MJ_INV:
        mju_copy(d->qacc, c->mu, nv);
        mj_inverseSkip(m, d, mjSTAGE_VEL, 1);
        break;
    case T_MJ_ACC:
        mju_copy(d->qfrc_applied, c->tau, nv);
        mj_fwdActuation(m, d);
        mj_fwdAcceleration(m, d);
        mj_fwdConstraint(m, d);
        break;
    }
    sink += d->qacc[0] + d->qfrc_inverse[0] + d->qLD[0];
}

/* median seconds per call of the first nt timings, from interleaved batches; those with on[w] = 0
   are left out (med[w] = 0) */
static void measure(rhs_case *c, int nt, const int *on, int batches, double med[NT])
{
    int reps[NT] = {0}, nb[NT] = {0};
    for (int w = 0; w < nt; w++) {
        if (!on[w]) continue;
        run_once(c, w);
        double s = now();
        run_once(c, w);
        double t = now() - s;
        reps[w] = t < BATCH_S ? (int)(BATCH_S / fmax(t, 1e-9)) : 1;
        /* slow timings take part in the first SLOW_BATCHES batches only */
        nb[w] = t > SLOW_S && batches > SLOW_BATCHES ? SLOW_BATCHES : batches;
    }
    double *samples = xcalloc((size_t)batches * NT, sizeof(double));
    for (int b = 0; b < batches; b++) {
        for (int i = 0; i < nt; i++) {
            int w = (b + i) % nt;
            if (!on[w] || b >= nb[w]) continue;
            double s = now();
            do {
                run_once(c, w);
            } while (now() - s < SETTLE_S);
            s = now();
            for (int r = 0; r < reps[w]; r++) run_once(c, w);
            samples[w * batches + b] = (now() - s) / reps[w];
        }
    }
    for (int w = 0; w < nt; w++) med[w] = on[w] ? median_sort(samples + w * batches, nb[w]) : 0;
    free(samples);
}

/* one row's results, kept for the slopes and the targets */
typedef struct rhs_row {
    int n;
    double ctc, mj, dart; /* s per call; mj, dart = 0 when not timed */
} rhs_row;

static char dart_skipped[256]; /* why DART is not run (empty: it is) */

/* Checks ctcsim against MuJoCo at c's state: iGDCA f(u) against qfrc_inverse, and GDCA
 * accelerations against qacc for the torques tq (nv). Writes the two relative differences. */
static void check_case(rhs_case *c, const double *tq, double *f_err, double *a_err)
{
    int nv = c->cm->nv;
    run_once(c, T_CTC);
    run_once(c, T_MJ);
    *f_err = rel_diff(c->d->qfrc_inverse, c->f, nv);
    mju_copy(c->tau, c->d->qfrc_inverse, nv);
    ctc_gdca_forward(c->cm, c->cd, tq, c->a);
    mju_copy(c->d->qfrc_applied, tq, nv);
    mj_fwdActuation(c->m, c->d);
    mj_fwdAcceleration(c->m, c->d);
    mj_fwdConstraint(c->m, c->d);
    *a_err = rel_diff(c->d->qacc, c->a, nv);
    run_once(c, T_CTC);
}

/* Checks ctcsim against DART at c's state, as check_case does against MuJoCo: DART's inverse
 * dynamics tau(u) against iGDCA's f, and its forward dynamics for the torques tq against GDCA's.
 * Writes the two relative differences. */
static void check_dart(rhs_case *c, const double *tq, double *f_err, double *a_err)
{
    run_once(c, T_CTC);
    run_once(c, T_DART);
    *f_err = rel_diff(c->dtau, c->f, c->cm->nv);
    ctc_gdca_forward(c->cm, c->cd, tq, c->a);
    dart_peer_forward(c->dart, c->q, c->v, tq, c->dqdd);
    *a_err = rel_diff(c->dqdd, c->a, c->cm->nv);
    run_once(c, T_CTC);
}

/* times one chain; returns 0, or 1 when ctcsim disagrees with MuJoCo or DART */
static int bench_rhs_chain(const char *label, test_chain *chain, int batches, const rhs_row *prev,
                           rhs_row *row)
{
    char err[256];
    rhs_case c = {0};
    if (chain->spec.nbodies <= MJ_MAX_N) {
        c.m = mj_load_chain(&chain->spec, 0, 1e-3);
        c.d = mj_makeData(c.m);
        adopt_mj_inertia(chain, c.m);
    } else { /* the inertias MuJoCo would be given: DART also refuses a slender rod's */
        for (int k = 0; k < chain->spec.nbodies; k++) {
            double in[9];
            mj_inertia(&chain->spec, k, in);
            memcpy(chain->bodies[k].inertia, in, sizeof in);
        }
    }
    ctc_model *cm = NULL;
    if (ctc_model_build(&chain->spec, &cm, err, sizeof err) != CTC_OK) {
        fprintf(stderr, "bench_mujoco: %s: %s\n", label, err);
        exit(1);
    }
    int n = cm->nbodies, nv = cm->nv;
    c.cm = cm;
    c.cd = ctc_data_new(cm);
    c.q = xcalloc((size_t)cm->nq, sizeof(double));
    c.v = xcalloc((size_t)nv, sizeof(double));
    c.u = xcalloc((size_t)nv, sizeof(double));
    c.f = xcalloc((size_t)nv, sizeof(double));
    c.a = xcalloc((size_t)nv, sizeof(double));
    c.tau = xcalloc((size_t)nv, sizeof(double));
    c.dtau = xcalloc((size_t)nv, sizeof(double));
    c.dqdd = xcalloc((size_t)nv, sizeof(double));
    c.mq = c.q, c.mv = c.v, c.mu = c.u;
    if (!dart_skipped[0]) { /* with the inertias MuJoCo compiled, as ctcsim has them */
        c.dart = dart_peer_new(&chain->spec, err, sizeof err);
        if (!c.dart) snprintf(dart_skipped, sizeof dart_skipped, "%s", err);
    }
    double *tq = xcalloc((size_t)nv, sizeof(double));
    uint64_t rng = 1;
    test_random_state(cm, &rng, 1.0, c.q, c.v);
    for (int i = 0; i < nv; i++) c.u[i] = test_uniform(&rng, -1, 1);
    for (int i = 0; i < nv; i++) tq[i] = test_uniform(&rng, -1, 1);

    int failed = 0;
    double f_err = NAN, a_err = NAN;
    double df_err = NAN, da_err = NAN;
    if (c.m) {
        check_case(&c, tq, &f_err, &a_err);
        failed = !(f_err <= CHECK_TOL && a_err <= CHECK_TOL);
    }
    if (c.dart) {
        check_dart(&c, tq, &df_err, &da_err);
        failed |= !(df_err <= DART_CHECK_TOL && da_err <= DART_CHECK_TOL);
    }
    double med[NT] = {0};
    int on[NT] = {[T_CTC] = 1, [T_DART] = c.dart != NULL};
    for (int w = T_MJ; w < NT; w++) on[w] = c.m != NULL;
    if (!failed) measure(&c, NT, on, batches, med);
    *row = (rhs_row){.n = n,
                     .ctc = med[T_CTC],
                     .mj = c.m && !failed ? med[T_MJ] : 0,
                     .dart = c.dart && !failed ? med[T_DART] : 0};
    char dart_us[16] = "-", dart_ratio[16] = "-", dart_f[16] = "-", dart_a[16] = "-";
    if (row->dart > 0) {
        snprintf(dart_us, sizeof dart_us, "%.2f", 1e6 * row->dart);
        snprintf(dart_ratio, sizeof dart_ratio, "%.4f", row->ctc / row->dart);
    }
    if (c.dart) {
        snprintf(dart_f, sizeof dart_f, "%.1e", df_err);
        snprintf(dart_a, sizeof dart_a, "%.1e", da_err);
    }

    char slope_c[16] = "-", slope_m[16] = "-";
    if (prev && prev->ctc > 0 && row->ctc > 0)
        snprintf(slope_c, sizeof slope_c, "%.2f", log(row->ctc / prev->ctc) / log(n / prev->n));
    if (prev && prev->mj > 0 && row->mj > 0)
        snprintf(slope_m, sizeof slope_m, "%.2f", log(row->mj / prev->mj) / log(n / prev->n));
    if (failed) {
        printf("| %-7s | %4d | FAILED: f vs MuJoCo %.1e, qacc vs MuJoCo %.1e (limit %.0e); f vs "
               "DART %.1e, qacc vs DART %.1e (limit %.0e): not timed |\n",
               label, n, f_err, a_err, CHECK_TOL, df_err, da_err, DART_CHECK_TOL);
    } else if (c.m) {
        printf("| %-7s | %4d | %9.2f | %10.2f | %7.4f | %s | %s | %6.1f | %8.1f | %5s | %5s | "
               "%10.2f | %8.2f | %10.2f | %7.2f | %7.2f | %7.2f | %.1e | %.1e | %s | %s |\n",
               label, n, 1e6 * med[T_CTC], 1e6 * med[T_MJ], med[T_CTC] / med[T_MJ], dart_us,
               dart_ratio, 1e9 * med[T_CTC] / n, 1e9 * med[T_MJ] / n, slope_c, slope_m,
               1e6 * med[T_MJ_POS], 1e6 * med[T_MJ_CRB], 1e6 * med[T_MJ_FACT], 1e6 * med[T_MJ_VEL],
               1e6 * med[T_MJ_INV], 1e6 * med[T_MJ_ACC], f_err, a_err, dart_f, dart_a);
    } else {
        printf("| %-7s | %4d | %9.2f | - | - | %s | %s | %6.1f | - | %5s | - | - | - | - | - | - | "
               "- | - | - | %s | %s |\n",
               label, n, 1e6 * med[T_CTC], dart_us, dart_ratio, 1e9 * med[T_CTC] / n, slope_c,
               dart_f, dart_a);
    }
    fflush(stdout);
    if (c.m) {
        mj_deleteData(c.d);
        mj_deleteModel(c.m);
    }
    dart_peer_free(c.dart);
    free(c.dtau), free(c.dqdd);
    free(c.q), free(c.v), free(c.u), free(c.f), free(c.a), free(c.tau), free(tq);
    ctc_data_free(c.cd);
    ctc_model_free(cm);
    return failed;
}

/* the ratio ctcsim / MuJoCo at n, or NaN when not measured */
static double ratio_at(const rhs_row *rows, int nrows, int n)
{
    for (int i = 0; i < nrows; i++)
        if (rows[i].n == n && rows[i].mj > 0) return rows[i].ctc / rows[i].mj;
    return NAN;
}

/* prints one target: the worst ratio over n in [n0, n1] against the limit */
static void print_target(const char *label, const rhs_row *rows, int nrows, int n0, int n1,
                         double limit)
{
    double worst = -INFINITY;
    int at = 0;
    for (int n = n0; n <= n1; n *= 2) {
        double r = ratio_at(rows, nrows, n);
        if (isnan(r)) return;
        if (r > worst) worst = r, at = n;
    }
    char range[32];
    if (n0 == n1)
        snprintf(range, sizeof range, "n = %d", n0);
    else
        snprintf(range, sizeof range, "n = %d..%d", n0, n1);
    printf("| %s | %s | <= %g | %.4f (n = %d) | %s |\n", label, range, limit, worst, at,
           worst <= limit ? "met" : "not met");
}

/* the range of ctcsim / DART over the rows where DART was timed */
static void print_dart_range(const char *label, const rhs_row *rows, int nrows)
{
    double lo = INFINITY, hi = -INFINITY;
    int n_lo = 0, n_hi = 0;
    for (int i = 0; i < nrows; i++) {
        if (rows[i].dart <= 0 || rows[i].ctc <= 0) continue;
        double r = rows[i].ctc / rows[i].dart;
        if (r < lo) lo = r, n_lo = rows[i].n;
        if (r > hi) hi = r, n_hi = rows[i].n;
    }
    if (hi < 0) return;
    printf("| %s against DART | n = %d..%d | - | %.4f (n = %d) to %.4f (n = %d) | |\n", label,
           rows[0].n, rows[nrows - 1].n, lo, n_lo, hi, n_hi);
}

static int bench_rhs(int max_n, int batches)
{
    printf("## 1. One CTC right-hand side: ctcsim against MuJoCo %s and DART %s\n\n",
           mj_versionString(), dart_peer_version());
    printf("ctcsim = kinematics + handles + iGDCA (composite) + GDCA forward. MuJoCo = "
           "mj_fwdPosition + mj_fwdVelocity (shared) + mj_inverseSkip(mjSTAGE_VEL) + "
           "mj_fwdActuation + mj_fwdAcceleration + mj_fwdConstraint. DART = "
           "Skeleton::computeInverseDynamics then computeForwardDynamics (its O(n) "
           "articulated-body pass) at the same state. Medians of %d interleaved "
           "batches (%d for a call over %.0f ms); thread CPU times in us, per body in ns. "
           "Slope = d log(time) / d log(n) from the row above. MuJoCo only up to n = %d. "
           "Ratios are ctcsim / peer.\n\n",
           batches, batches < SLOW_BATCHES ? batches : SLOW_BATCHES, 1e3 * SLOW_S, MJ_MAX_N);
    printf("| chain   |    n | ctcsim (us) | MuJoCo (us) | ratio | DART (us) | ratio DART | "
           "ctcsim/n ns | MuJoCo/n ns | slope ctcsim | slope MuJoCo | MuJoCo position | of which "
           "crb | of which factorM | velocity | inverse | forward acc | f vs MuJoCo | qacc vs "
           "MuJoCo | f vs DART | qacc vs DART |\n");
    printf("| ------- | ---: | --------: | ---------: | ------: | ------: | ------: | -----: | "
           "-------: | ----: | ----: | ---------: | -------: | ---------: | ------: | ------: | "
           "------: | ---: | ---: | ---: | ---: |\n");
    enum { MAXROWS = 32 };
    rhs_row planar[MAXROWS], spatial[MAXROWS];
    int np = 0, ns = 0, failed = 0;
    for (int n = 2; n <= max_n && np < MAXROWS; n *= 2, np++) {
        test_chain *c = test_chain_rod_pendulum(n, 1.0, 1.0);
        failed |= bench_rhs_chain("planar", c, batches, np ? &planar[np - 1] : NULL, &planar[np]);
        test_chain_free(c);
    }
    for (int n = 2; n <= max_n && ns < MAXROWS; n *= 2, ns++) {
        test_chain *c = test_chain_random_spatial(n, 7, 1u << CTC_JOINT_REVOLUTE);
        failed |=
            bench_rhs_chain("spatial", c, batches, ns ? &spatial[ns - 1] : NULL, &spatial[ns]);
        test_chain_free(c);
    }
    printf("\nctcsim (and DART) were given the inertias as MuJoCo compiled them (largest change "
           "%.1e relative to the body's largest entry).\n",
           inertia_adjust_max);
    if (dart_skipped[0]) printf("\nDART skipped: %s.\n", dart_skipped);
    printf("\nTargets (ratio = ctcsim / MuJoCo; the worst n of each range):\n\n");
    printf("| chain | range | target | measured | |\n| --- | --- | ---: | ---: | --- |\n");
    print_target("planar", planar, np, 2, 64, 0.5);
    print_target("planar", planar, np, 256, 256, 0.05);
    print_target("planar", planar, np, 1024, 1024, 0.002);
    print_target("spatial", spatial, ns, 2, 16, 1.0);
    print_target("spatial", spatial, ns, 256, 256, 0.1);
    print_dart_range("planar", planar, np);
    print_dart_range("spatial", spatial, ns);
    printf("\n");
    return failed;
}

/* ---------------------------------------------------------------------------------------------
 * 1t. One CTC right-hand side on autoTree
 */

/* the longest path from the ground to a body, in bodies */
static int tree_depth(const ctc_chain_spec *s)
{
    int *depth = xcalloc((size_t)s->nbodies, sizeof(int)), most = 0;
    for (int k = 0; k < s->nbodies; k++) {
        int p = s->parent ? s->parent[k] : k - 1;
        depth[k] = p < 0 ? 1 : depth[p] + 1;
        most = depth[k] > most ? depth[k] : most;
    }
    free(depth);
    return most;
}

/* max over k of |a[map[k]] - b[k]| / max_k |b[k]| (n): a in MuJoCo's order, b in ctcsim's */
static double rel_diff_map(const double *a, const int *map, const double *b, int n)
{
    double d = 0, s = 0;
    for (int k = 0; k < n; k++) {
        d = fmax(d, fabs(a[map[k]] - b[k]));
        s = fmax(s, fabs(b[k]));
    }
    return d / fmax(s, 1e-300);
}

/* Times one tree, ctcsim and MuJoCo interleaved; per[0], per[1]: s per body of ctcsim's and
 * MuJoCo's right-hand side (0: not timed). chain_per: the same of the chain (bf 1) of the same n
 * and form, or NULL for the chain itself. Returns 0, or 1 when the two disagree. */
static int bench_rhs_tree(const char *label, test_chain *tree, int batches, const double *chain_per,
                          double per[2])
{
    char err[256];
    int depth = tree_depth(&tree->spec);
    /* a chain (depth n) is held to part 1's limit: its M's condition number grows as n^2 to n^4
       (NOTEBOOK.md, "Hard cases"), and both sides' rounding with it */
    double tol = depth == tree->spec.nbodies ? CHECK_TOL : TREE_CHECK_TOL;
    rhs_case c = {0};
    if (depth <= MJ_MAX_N) {
        c.m = mj_load_tree(&tree->spec, 1e-3);
        c.d = mj_makeData(c.m);
        adopt_mj_inertia(tree, c.m);
    }
    ctc_model *cm = NULL;
    if (ctc_model_build(&tree->spec, &cm, err, sizeof err) != CTC_OK) {
        fprintf(stderr, "bench_mujoco: %s: %s\n", label, err);
        exit(1);
    }
    int n = cm->nbodies, nv = cm->nv;
    c.cm = cm;
    c.cd = ctc_data_new(cm);
    c.q = xcalloc((size_t)cm->nq, sizeof(double));
    c.v = xcalloc((size_t)nv, sizeof(double));
    c.u = xcalloc((size_t)nv, sizeof(double));
    c.f = xcalloc((size_t)nv, sizeof(double));
    c.a = xcalloc((size_t)nv, sizeof(double));
    c.tau = xcalloc((size_t)nv, sizeof(double));
    c.mq = xcalloc((size_t)nv, sizeof(double));
    c.mv = xcalloc((size_t)nv, sizeof(double));
    c.mu = xcalloc((size_t)nv, sizeof(double));
    double *tq = xcalloc((size_t)nv, sizeof(double));
    int *dof = xcalloc((size_t)nv, sizeof(int)), *qadr = xcalloc((size_t)nv, sizeof(int));
    uint64_t rng = 1;
    test_random_state(cm, &rng, 1.0, c.q, c.v);
    for (int i = 0; i < nv; i++) c.u[i] = test_uniform(&rng, -1, 1);
    for (int i = 0; i < nv; i++) tq[i] = test_uniform(&rng, -1, 1);

    int failed = 0;
    double f_err = NAN, a_err = NAN;
    if (c.m) {
        /* ctcsim's body k (one revolute joint, dof k) is MuJoCo's joint j<k> */
        for (int k = 0; k < n; k++) {
            char name[32];
            snprintf(name, sizeof name, "j%d", k);
            int j = mj_name2id(c.m, mjOBJ_JOINT, name);
            dof[k] = c.m->jnt_dofadr[j];
            qadr[k] = c.m->jnt_qposadr[j];
        }
        for (int k = 0; k < n; k++) {
            c.mq[qadr[k]] = c.q[k];
            c.mv[dof[k]] = c.v[k];
            c.mu[dof[k]] = c.u[k];
        }
        /* tau = M u + c on both sides, then qdd = M^-1 (tq - c) for other torques tq */
        run_once(&c, T_CTC);
        run_once(&c, T_MJ);
        f_err = rel_diff_map(c.d->qfrc_inverse, dof, c.f, nv);
        ctc_gdca_forward(cm, c.cd, tq, c.a);
        for (int k = 0; k < n; k++) c.d->qfrc_applied[dof[k]] = tq[k];
        mj_fwdActuation(c.m, c.d);
        mj_fwdAcceleration(c.m, c.d);
        mj_fwdConstraint(c.m, c.d);
        a_err = rel_diff_map(c.d->qacc, dof, c.a, nv);
        failed = !(f_err <= tol && a_err <= tol);
    }
    double med[NT] = {0};
    const int on[NT] = {[T_CTC] = 1, [T_MJ] = c.m != NULL};
    if (!failed) measure(&c, T_MJ + 1, on, batches, med);
    per[0] = failed ? 0 : med[T_CTC] / n;
    per[1] = c.m && !failed ? med[T_MJ] / n : 0;

    char tc[16] = "-", tm[16] = "-", mj[16] = "-", mjn[16] = "-", ratio[16] = "-";
    char fe[16] = "-", ae[16] = "-";
    if (c.m) {
        snprintf(fe, sizeof fe, "%.1e", f_err);
        snprintf(ae, sizeof ae, "%.1e", a_err);
    }
    if (chain_per && chain_per[0] > 0 && per[0] > 0)
        snprintf(tc, sizeof tc, "%.2f", per[0] / chain_per[0]);
    if (chain_per && chain_per[1] > 0 && per[1] > 0)
        snprintf(tm, sizeof tm, "%.3g", per[1] / chain_per[1]);
    if (per[1] > 0) {
        snprintf(mj, sizeof mj, "%.2f", 1e6 * med[T_MJ]);
        snprintf(mjn, sizeof mjn, "%.1f", 1e9 * per[1]);
        snprintf(ratio, sizeof ratio, "%.3f", med[T_CTC] / med[T_MJ]);
    }
    if (failed)
        printf("| %-7s | %4d | %6d | %5d | FAILED: tau vs MuJoCo %.1e, qdd vs MuJoCo %.1e (limit "
               "%.0e): not timed |\n",
               label, n, cm->height, depth, f_err, a_err, tol);
    else
        printf("| %-7s | %4d | %6d | %5d | %9.2f | %10s | %6s | %7.1f | %8s | %5s | %5s | %7s | "
               "%7s |\n",
               label, n, cm->height, depth, 1e6 * med[T_CTC], mj, ratio, 1e9 * per[0], mjn, tc, tm,
               fe, ae);
    fflush(stdout);
    if (c.m) {
        mj_deleteData(c.d);
        mj_deleteModel(c.m);
    }
    free(c.q), free(c.v), free(c.u), free(c.f), free(c.a), free(c.tau);
    free(c.mq), free(c.mv), free(c.mu), free(tq), free(dof), free(qadr);
    ctc_data_free(c.cd);
    ctc_model_free(cm);
    return failed;
}

static int bench_rhs_trees(int max_n, int batches)
{
    printf("## 1t. One CTC right-hand side on autoTree: ctcsim against MuJoCo %s\n\n",
           mj_versionString());
    printf("Featherstone's autoTree (tests/support/chains.h; taper 1; pl: planar, skew 0; sp: "
           "spatial, skew 0.5 rad; bf: branching factor, 1 = a chain), as nested MJCF bodies. The "
           "right-hand sides as in part 1, ctcsim's and MuJoCo's interleaved; medians of %d "
           "batches (%d for a call over %.0f ms); thread CPU times in us, per body in ns; ratio = "
           "ctcsim / MuJoCo; tree/chain = per body over bf 1's at the same n and form; height: "
           "ctcsim's plan; depth: the longest path (MuJoCo only up to %d). Checked first: tau "
           "(iGDCA against qfrc_inverse) and qdd (GDCA against qacc, other random torques) at a "
           "random state, relative to the largest entry, limit %.0e (%.0e for bf 1, a chain, as in "
           "part 1).\n\n",
           batches, batches < SLOW_BATCHES ? batches : SLOW_BATCHES, 1e3 * SLOW_S, MJ_MAX_N,
           TREE_CHECK_TOL, CHECK_TOL);
    printf("| tree    |    n | height | depth | ctcsim (us) | MuJoCo (us) | ratio | ctcsim/n ns | "
           "MuJoCo/n ns | ctcsim tree/chain | MuJoCo tree/chain | tau vs MuJoCo | qdd vs MuJoCo "
           "|\n");
    printf("| ------- | ---: | -----: | ----: | --------: | ---------: | ----: | ------: | "
           "-------: | ----: | ----: | ---: | ---: |\n");
    int failed = 0;
    inertia_adjust_max = 0;
    for (int form = 0; form < 2; form++) {
        for (int n = 16; n <= max_n; n *= 4) {
            double chain_per[2] = {0};
            static const int bf[] = {1, 2, 4};
            for (int b = 0; b < 3; b++) {
                char label[16];
                snprintf(label, sizeof label, "%s bf %d", form ? "sp" : "pl", bf[b]);
                test_chain *t = test_auto_tree(n, bf[b], form ? 0.5 : 0.0, 1.0);
                double per[2];
                failed |= bench_rhs_tree(label, t, batches, b ? chain_per : NULL, per);
                if (b == 0) memcpy(chain_per, per, sizeof per);
                test_chain_free(t);
            }
        }
    }
    printf("\nctcsim was given the inertias as MuJoCo compiled them (largest change %.1e relative "
           "to the body's largest entry).\n\n",
           inertia_adjust_max);
    return failed;
}

/* ---------------------------------------------------------------------------------------------
 * 2 and 3. Whole simulations
 */

/* one CTC tracking problem, for ctcsim and MuJoCo alike */
typedef struct sim_problem {
    const char *name;
    test_chain *chain;
    int n;
    const double *q0;  /* (n) rad; v0 = 0 */
    ctc_gains *gains;  /* (n) */
    ctc_traj *traj;    /* (n) */
    ctc_disturb *dist; /* (n) or NULL */
    double duration;   /* s */
    double interval;   /* s, sampling */
    int nsamples;      /* duration / interval + 1 */
    mjModel *m;        /* with integral actuators when any ki != 0 */
    mjData *d;
    double ref_rtol; /* the reference's rtol (atol = rtol / 100) */
    double *ref;     /* (nsamples x n) q of ctcsim DOPRI5 at ref_rtol (ref_samples' q) */
    struct samples *ref_samples;
    long ref_steps;
} sim_problem;

/* What every run records at each sample, on both sides, so that both pay for the same outputs:
 * ctcsim's default channels, indexed by ctc_channel - q, qdot, q_des, qdot_des, e, tau, w
 * (nsamples x n each) and energy (nsamples x 2: kinetic, potential). */
#define NOUT (CTC_CH_ENERGY + 1)
typedef struct samples {
    double *ch[NOUT];
} samples;

static samples *samples_new(int nsamples, int n)
{
    samples *s = xcalloc(1, sizeof *s);
    for (int c = 0; c < NOUT; c++)
        s->ch[c] = xcalloc((size_t)nsamples * (c == CTC_CH_ENERGY ? 2 : n), sizeof(double));
    return s;
}

static void samples_free(samples *s)
{
    for (int c = 0; s && c < NOUT; c++) free(s->ch[c]);
    free(s);
}

/* MuJoCo's controller: what mjcb_control runs, for the problem being simulated */
typedef struct mj_ctrl {
    const sim_problem *p;
    int hold;  /* 1: evaluate at the first stage of each step and hold over the step */
    int stage; /* stages of the current step so far (the loop clears it before each mj_step) */
    samples *out;
    long row; /* the sample the next first stage records (its state is the sample's), or -1 */
} mj_ctrl;

static mj_ctrl *active;

/* u = qdd_d + ki int e + kp e + kv de; qfrc_applied = MuJoCo's inverse dynamics of u + z(t);
 * ctrl = e, the rate of the integral state (act) when the model has integrator actuators. The
 * first stage of a step is at the step's start, a sample's state when c->row says so: it records
 * the sample there (what ctcsim records), the energy from MuJoCo's own mj_energyPos and
 * mj_energyVel on the position stage just computed. */
static void mj_ctc_control(const mjModel *m, mjData *d)
{
    mj_ctrl *c = active;
    int first = c->stage++ == 0;
    if (c->hold && !first) return;
    const sim_problem *p = c->p;
    double **out = first && c->row >= 0 ? c->out->ch : NULL;
    size_t o = out ? (size_t)c->row * (size_t)m->nv : 0;
    for (int i = 0; i < m->nv; i++) {
        double des[3];
        ctc_traj_eval(&p->traj[i], d->time, des);
        double e = des[0] - d->qpos[i], de = des[1] - d->qvel[i];
        double ie = m->na ? d->act[i] : 0;
        const ctc_gains *g = &p->gains[i];
        double w = g->ki * ie + g->kp * e + g->kv * de;
        d->qacc[i] = des[2] + w;
        if (m->nu) d->ctrl[i] = e;
        if (out) {
            out[CTC_CH_Q][o + i] = d->qpos[i], out[CTC_CH_QD][o + i] = d->qvel[i];
            out[CTC_CH_Q_DES][o + i] = des[0], out[CTC_CH_QD_DES][o + i] = des[1];
            out[CTC_CH_E][o + i] = e, out[CTC_CH_W][o + i] = w;
        }
    }
    mj_inverseSkip(m, d, mjSTAGE_VEL, 1);
    for (int i = 0; i < m->nv; i++)
        d->qfrc_applied[i] =
            d->qfrc_inverse[i] + (p->dist ? ctc_disturb_eval(&p->dist[i], d->time) : 0);
    if (out) {
        mju_copy(out[CTC_CH_TAU] + o, d->qfrc_applied, m->nv);
        /* both return at once unless energy is enabled, which would compute it at every stage:
           enabled for these two calls only */
        p->m->opt.enableflags |= mjENBL_ENERGY;
        mj_energyPos(m, d);
        mj_energyVel(m, d);
        p->m->opt.enableflags &= ~mjENBL_ENERGY;
        out[CTC_CH_ENERGY][2 * c->row] = d->energy[1];
        out[CTC_CH_ENERGY][2 * c->row + 1] = d->energy[0];
        c->row = -1;
    }
}

/* the outcome of one run */
typedef struct run_out {
    int done; /* 0: diverged at t_fail */
    double t_fail;
    double cpu; /* s of this thread's CPU time */
    long steps, evals;
    long rejected;
    double error; /* max |q - q_ref| over the samples and joints; NaN when not computed */
} run_out;

static double max_error(const sim_problem *p, const double *q, int nsamples)
{
    double e = 0;
    for (int j = 0; j < nsamples * p->n; j++) e = fmax(e, fabs(q[j] - p->ref[j]));
    return nsamples == p->nsamples ? e : NAN;
}

/* MuJoCo RK4 at step dt (dividing the sampling interval) with the stagewise or held controller;
 * records the samples into out: each at the first stage of the step that starts from it, the last
 * by one more mj_forward */
static run_out mj_run(sim_problem *p, double dt, int hold, samples *out)
{
    mjModel *m = p->m;
    mjData *d = p->d;
    int n = p->n;
    long spp = lround(p->interval / dt), nsteps = spp * (p->nsamples - 1);
    if (fabs((double)spp * dt - p->interval) > 1e-9 * p->interval) {
        fprintf(stderr, "bench_mujoco: dt = %g does not divide %g\n", dt, p->interval);
        exit(1);
    }
    mj_ctrl c = {.p = p, .hold = hold, .out = out, .row = 0};
    active = &c;
    m->opt.timestep = dt;
    run_out r = {.done = 1, .error = NAN};
    double t0 = now();
    mj_resetData(m, d);
    memset(d->warning, 0, sizeof d->warning);
    mju_copy(d->qpos, p->q0, n);
    mjcb_control = mj_ctc_control;
    int ns = 1;
    for (long k = 1; k <= nsteps; k++) {
        c.stage = 0;
        mj_step(m, d);
        int bad = d->warning[mjWARN_BADQPOS].number || d->warning[mjWARN_BADQVEL].number ||
                  d->warning[mjWARN_BADQACC].number;
        for (int i = 0; i < n && !bad; i++) bad = !(fabs(d->qvel[i]) <= MAX_SPEED);
        if (bad) {
            r.done = 0, r.t_fail = (double)k * dt, r.steps = k;
            break;
        }
        if (k % spp == 0) c.row = ns++;
    }
    if (r.done && c.row >= 0) { /* the last sample: no step starts from it */
        c.stage = 0;
        mj_forward(m, d);
    }
    r.cpu = now() - t0;
    mjcb_control = NULL;
    if (r.done) {
        r.steps = nsteps;
        r.error = p->ref ? max_error(p, out->ch[CTC_CH_Q], ns) : NAN;
    }
    r.evals = 4 * r.steps;
    return r;
}

static ctc_sim_spec ctc_spec(const sim_problem *p, ctc_integ_spec integ)
{
    int pid = 0;
    for (int i = 0; i < p->n; i++) pid |= p->gains[i].ki != 0;
    return (ctc_sim_spec){.chain = p->chain->spec,
                          .q0 = p->q0,
                          .controller = pid ? CTC_CTRL_PID : CTC_CTRL_PD,
                          .gains = p->gains,
                          .model_mass_scale = 1,
                          .model_inertia_scale = 1,
                          .traj = p->traj,
                          .disturb = p->dist,
                          .integrator = integ,
                          .duration = p->duration,
                          .output_interval = p->interval,
                          .channels = 0}; /* every channel that applies: the samples' NOUT */
}

/* ctcsim's run; its samples into out when it finishes */
static run_out ctc_run(const sim_problem *p, ctc_integ_spec integ, samples *out)
{
    ctc_sim_spec spec = ctc_spec(p, integ);
    ctc_sim_result *res = NULL;
    char err[256];
    if (ctc_sim_run(&spec, NULL, &res, err, sizeof err) != CTC_OK) {
        fprintf(stderr, "bench_mujoco: %s: %s\n", p->name, err);
        exit(1);
    }
    run_out r = {.done = res->status == CTC_RUN_DONE,
                 .t_fail = res->metrics.t_end,
                 .cpu = res->metrics.cpu_s,
                 .steps = res->metrics.steps,
                 .evals = res->metrics.rhs_evals,
                 .rejected = res->metrics.rejected,
                 .error = NAN};
    if (r.done) {
        for (int c = 0; c < NOUT; c++)
            memcpy(out->ch[c], res->ch[c],
                   (size_t)res->nsamples * (size_t)res->width[c] * sizeof(double));
        r.error = p->ref ? max_error(p, out->ch[CTC_CH_Q], res->nsamples) : NAN;
    }
    ctc_sim_result_free(res);
    return r;
}

/* makes p's MuJoCo model and its reference run at rtol */
static void problem_setup(sim_problem *p, double rtol)
{
    p->ref_rtol = rtol;
    int integral = 0;
    for (int i = 0; i < p->n; i++) integral |= p->gains[i].ki != 0;
    p->m = mj_load_chain(&p->chain->spec, integral, 1e-3);
    p->d = mj_makeData(p->m);
    adopt_mj_inertia(p->chain, p->m);
    p->nsamples = (int)lround(p->duration / p->interval) + 1;
    samples *ref = samples_new(p->nsamples, p->n);
    p->ref = NULL;
    run_out r =
        ctc_run(p,
                (ctc_integ_spec){
                    .method = CTC_INTEG_DOPRI5, .rtol = p->ref_rtol, .atol = p->ref_rtol * 1e-2},
                ref);
    if (!r.done) {
        fprintf(stderr, "bench_mujoco: %s: the reference run did not finish\n", p->name);
        exit(1);
    }
    p->ref_samples = ref;
    p->ref = ref->ch[CTC_CH_Q];
    p->ref_steps = r.steps;
}

static void problem_free(sim_problem *p)
{
    mj_deleteData(p->d);
    mj_deleteModel(p->m);
    samples_free(p->ref_samples);
}

/* one configuration of a work-precision comparison */
enum { CFG_DOPRI5, CFG_RK4, CFG_MJ_STAGEWISE, CFG_MJ_HOLD };

typedef struct sim_config {
    int kind;   /* CFG_*: ctcsim DOPRI5 at rtol, ctcsim RK4 at dt, MuJoCo RK4 at dt */
    double par; /* rtol or dt */
    double cpu[8];
    run_out last;
} sim_config;

/* time of MuJoCo stagewise at the given error, interpolated on its work-precision curve
 * (log time linear in log error between neighbouring dt); NaN outside the measured range.
 * *dt_at receives the interpolated dt. */
static double mj_cpu_at(const sim_config *c, int nc, int rounds, double err, double *dt_at)
{
    for (int i = 0; i < nc; i++)
        for (int j = 0; j < nc; j++) {
            const sim_config *a = &c[i], *b = &c[j];
            if (a->kind != CFG_MJ_STAGEWISE || b->kind != CFG_MJ_STAGEWISE || a->par <= b->par)
                continue;
            /* a is the next larger dt above b */
            int between = 1;
            for (int k = 0; k < nc; k++)
                if (c[k].kind == CFG_MJ_STAGEWISE && c[k].par < a->par && c[k].par > b->par)
                    between = 0;
            double ea = a->last.error, eb = b->last.error;
            if (!between || !(ea >= err && err >= eb) || !(eb > 0)) continue;
            double wa[8], wb[8];
            memcpy(wa, a->cpu, sizeof wa);
            memcpy(wb, b->cpu, sizeof wb);
            double la = log(median_sort(wa, rounds)), lb = log(median_sort(wb, rounds));
            double s = ea == eb ? 0 : (log(err) - log(ea)) / (log(eb) - log(ea));
            *dt_at = exp(log(a->par) + s * (log(b->par) - log(a->par)));
            return exp(la + s * (lb - la));
        }
    return NAN;
}

static void sim_compare(sim_problem *p, const double *rtols, int nrtol, const double *dts, int ndt,
                        int rounds)
{
    sim_config c[MAX_CONFIGS];
    int nc = 0;
    for (int i = 0; i < nrtol && nc < MAX_CONFIGS; i++)
        c[nc++] = (sim_config){.kind = CFG_DOPRI5, .par = rtols[i]};
    for (int k = CFG_RK4; k <= CFG_MJ_HOLD; k++)
        for (int i = 0; i < ndt && nc < MAX_CONFIGS; i++)
            c[nc++] = (sim_config){.kind = k, .par = dts[i]};
    samples *qs = samples_new(p->nsamples, p->n);

    /* the reference against MuJoCo stagewise at a small step: q, and the recorded outputs that
       come from each side's own dynamics, tau and energy */
    run_out chk = mj_run(p, REF_DT, 0, qs);
    double dtau = 0, tau_max = 0, den = 0, e_max = 0;
    for (size_t j = 0; j < (size_t)p->nsamples * (size_t)p->n; j++) {
        dtau = fmax(dtau, fabs(qs->ch[CTC_CH_TAU][j] - p->ref_samples->ch[CTC_CH_TAU][j]));
        tau_max = fmax(tau_max, fabs(p->ref_samples->ch[CTC_CH_TAU][j]));
    }
    for (size_t j = 0; j < (size_t)p->nsamples * 2; j++) {
        den = fmax(den, fabs(qs->ch[CTC_CH_ENERGY][j] - p->ref_samples->ch[CTC_CH_ENERGY][j]));
        e_max = fmax(e_max, fabs(p->ref_samples->ch[CTC_CH_ENERGY][j]));
    }
    printf("Reference: ctcsim DOPRI5 rtol %g, atol %g (%ld steps). Against MuJoCo RK4 "
           "stagewise at dt = %g s: max |q - q_ref| = %.2e rad%s; recorded tau within %.1e "
           "(largest |tau| %.3g N m), energy within %.1e (largest |E| %.3g J).\n\n",
           p->ref_rtol, p->ref_rtol * 1e-2, p->ref_steps, REF_DT, chk.error,
           chk.error <= 1e-8 ? "" : " (ABOVE 1e-8: see the README)", dtau, tau_max, den, e_max);

    for (int round = 0; round < rounds; round++)
        for (int i = 0; i < nc; i++) {
            ctc_integ_spec integ = {
                .method = CTC_INTEG_DOPRI5, .rtol = c[i].par, .atol = c[i].par * 1e-2};
            if (c[i].kind == CFG_RK4)
                integ = (ctc_integ_spec){.method = CTC_INTEG_RK4, .step = c[i].par};
            run_out r = c[i].kind >= CFG_MJ_STAGEWISE
                            ? mj_run(p, c[i].par, c[i].kind == CFG_MJ_HOLD, qs)
                            : ctc_run(p, integ, qs);
            c[i].cpu[round] = r.cpu;
            c[i].last = r;
        }

    printf("| run | time (ms) | steps | evals | us / eval | max error (rad) |\n"
           "| --- | ---: | ---: | ---: | ---: | ---: |\n");
    for (int i = 0; i < nc; i++) {
        double w[8];
        memcpy(w, c[i].cpu, sizeof w);
        double cpu = median_sort(w, rounds);
        const run_out *r = &c[i].last;
        char label[64];
        if (c[i].kind >= CFG_MJ_STAGEWISE)
            snprintf(label, sizeof label, "MuJoCo rk4 %s dt = %g",
                     c[i].kind == CFG_MJ_HOLD ? "hold" : "stagewise", c[i].par);
        else if (c[i].kind == CFG_RK4)
            snprintf(label, sizeof label, "ctcsim rk4 dt = %g", c[i].par);
        else
            snprintf(label, sizeof label, "ctcsim dopri5 rtol = %g", c[i].par);
        if (r->done)
            printf("| %s | %.2f | %ld | %ld | %.2f | %.2e |\n", label, 1e3 * cpu, r->steps,
                   r->evals, 1e6 * cpu / (double)r->evals, r->error);
        else
            printf("| %s | %.2f | %ld | %ld | - | diverged at t = %.3f s |\n", label, 1e3 * cpu,
                   r->steps, r->evals, r->t_fail);
    }

    printf("\nAt equal error (MuJoCo stagewise's time interpolated at ctcsim's error):\n\n"
           "| ctcsim rtol | error (rad) | ctcsim time (ms) | MuJoCo dt for it (s) | MuJoCo time "
           "(ms) | ratio ctcsim / MuJoCo |\n| ---: | ---: | ---: | ---: | ---: | ---: |\n");
    for (int i = 0; i < nc; i++) {
        if (c[i].kind != CFG_DOPRI5) continue;
        double w[8];
        memcpy(w, c[i].cpu, sizeof w);
        double cpu = median_sort(w, rounds), dt_at = NAN;
        double mw = mj_cpu_at(c, nc, rounds, c[i].last.error, &dt_at);
        if (isnan(mw))
            printf("| %g | %.2e | %.2f | outside MuJoCo's range | - | - |\n", c[i].par,
                   c[i].last.error, 1e3 * cpu);
        else
            printf("| %g | %.2e | %.2f | %.2e | %.2f | %.2f |\n", c[i].par, c[i].last.error,
                   1e3 * cpu, dt_at, 1e3 * mw, cpu / mw);
    }
    printf("\n");
    fflush(stdout);
    samples_free(qs);
}

/* the paper's triple pendulum PID run (bench_sim's paper_spec) */
static void sim_triple(void)
{
    static const double q0[3] = {5 * PI / 6, 3 * PI / 4, 2 * PI / 3};
    ctc_gains gains[3];
    ctc_traj traj[3];
    ctc_disturb dist[3];
    for (int i = 0; i < 3; i++) {
        gains[i] = (ctc_gains){.ki = 250, .kp = 100, .kv = 20};
        traj[i] = (ctc_traj){
            .type = i == 1 ? CTC_TRAJ_COSINE : CTC_TRAJ_SINE, .amplitude = 0.6, .period = 1.5};
        dist[i] = (ctc_disturb){.type = CTC_DISTURB_CONSTANT, .value = 0.2};
    }
    sim_problem p = {.name = "triple pendulum",
                     .chain = test_chain_rod_pendulum(3, 1, 1),
                     .n = 3,
                     .q0 = q0,
                     .gains = gains,
                     .traj = traj,
                     .dist = dist,
                     .duration = 5,
                     .interval = 0.01};
    problem_setup(&p, 1e-12);
    printf("## 2a. Triple pendulum, PID, 5 s (paper section 7.1), 0.2 N m disturbance\n\n"
           "Times are thread CPU time, medians of 5 interleaved rounds.\n\n");
    static const double rtols[] = {1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10};
    static const double dts[] = {0.01, 0.005, 0.0025, 0.002, 0.001, 0.0005};
    sim_compare(&p, rtols, 6, dts, 6, 5);
    problem_free(&p);
    test_chain_free(p.chain);
}

/* the 64-link problem: 1 m, 1 kg rods hanging along -y, joint i tracking
 * q_d = 0.05 sin(pi t + pi i / 32) from rest at q = 0 (a travelling wave: the links' absolute
 * angles stay within about 1 rad), PD kp = w^2, kv = 2 w */
#define CHAIN_N 64
static void chain64_problem(sim_problem *p, double w, double *q0, ctc_gains *gains, ctc_traj *traj)
{
    for (int i = 0; i < CHAIN_N; i++) {
        q0[i] = 0;
        gains[i] = (ctc_gains){.kp = w * w, .kv = 2 * w};
        traj[i] =
            (ctc_traj){.type = CTC_TRAJ_SINE, .amplitude = 0.05, .period = 2, .phase = PI * i / 32};
    }
    *p = (sim_problem){.name = "64-link chain",
                       .chain = test_chain_rod_pendulum(CHAIN_N, 1, 1),
                       .n = CHAIN_N,
                       .q0 = q0,
                       .gains = gains,
                       .traj = traj,
                       .duration = 5,
                       .interval = 0.01};
}

static void sim_chain64(void)
{
    double q0[CHAIN_N];
    ctc_gains gains[CHAIN_N];
    ctc_traj traj[CHAIN_N];
    sim_problem p;
    chain64_problem(&p, 10, q0, gains, traj);
    problem_setup(&p, 1e-12);
    printf("## 2b. 64-link planar rod chain, PD kp = 100, kv = 20, 5 s\n\n"
           "Rods 1 m, 1 kg, hanging along -y; joint i tracks 0.05 sin(pi t + pi i / 32) rad from "
           "rest at q = 0; no disturbance. Times are thread CPU time, medians of 3 interleaved "
           "rounds.\n\n");
    static const double rtols[] = {1e-5, 1e-6, 1e-7, 1e-8, 1e-9};
    static const double dts[] = {0.01, 0.005, 0.0025, 0.001, 0.0005};
    sim_compare(&p, rtols, 5, dts, 5, 3);
    problem_free(&p);
    test_chain_free(p.chain);
}

/* max |q_d - q| over the samples from time t0 on: how well a run tracks after its transient */
static double tracking_error(const sim_problem *p, const samples *out, double t0)
{
    double e = 0;
    for (int k = (int)lround(t0 / p->interval); k < p->nsamples; k++)
        for (int i = 0; i < p->n; i++) {
            double des[3];
            ctc_traj_eval(&p->traj[i], k * p->interval, des);
            e = fmax(e, fabs(des[0] - out->ch[CTC_CH_Q][(size_t)k * p->n + i]));
        }
    return e;
}

static void print_stiff_row(const char *label, const run_out *r, int rejected)
{
    char rej[24] = "-";
    if (rejected) snprintf(rej, sizeof rej, "%ld", r->rejected);
    if (r->done)
        printf("| %s | %.2f | %ld | %s | %ld | %.2e |\n", label, 1e3 * r->cpu, r->steps, rej,
               r->evals, r->error);
    else
        printf("| %s | %.2f | %ld | %s | %ld | diverged at t = %.4f s |\n", label, 1e3 * r->cpu,
               r->steps, rej, r->evals, r->t_fail);
}

/* 3: where MuJoCo's RK4 at 1 ms diverges, and ctcsim on that problem */
static void sim_stiff(void)
{
    double q0[CHAIN_N];
    ctc_gains gains[CHAIN_N];
    ctc_traj traj[CHAIN_N];
    static const double ws[] = {10, 100, 1000, 2000, 2500, 2750, 3000};
    enum { NW = sizeof ws / sizeof ws[0] };
    printf("## 3. 64-link chain, stiff PD: kp = w^2, kv = 2 w (double pole at -w)\n\n"
           "MuJoCo RK4 at dt = 1 ms, same chain and trajectories as 2b. Tracking error = max "
           "|q_d - q| over the samples of the last second (after the transient).\n\n"
           "| w (1/s) | kp | kv | w dt | MuJoCo stagewise | MuJoCo hold |\n"
           "| ---: | ---: | ---: | ---: | --- | --- |\n");
    double w_div = 0;
    samples *qs = samples_new(501, CHAIN_N);
    for (int i = 0; i < NW; i++) {
        sim_problem p;
        chain64_problem(&p, ws[i], q0, gains, traj);
        p.m = mj_load_chain(&p.chain->spec, 0, 1e-3);
        p.d = mj_makeData(p.m);
        adopt_mj_inertia(p.chain, p.m);
        p.nsamples = 501;
        run_out r[2];
        char s[2][64];
        for (int h = 0; h < 2; h++) {
            r[h] = mj_run(&p, 1e-3, h, qs);
            if (r[h].done)
                snprintf(s[h], sizeof s[h], "tracks: error %.1e rad", tracking_error(&p, qs, 4));
            else
                snprintf(s[h], sizeof s[h], "diverged at t = %.3f s", r[h].t_fail);
        }
        printf("| %g | %g | %g | %g | %s | %s |\n", ws[i], gains[0].kp, gains[0].kv, ws[i] * 1e-3,
               s[0], s[1]);
        if (!r[0].done && w_div == 0) w_div = ws[i];
        problem_free(&p);
        test_chain_free(p.chain);
    }
    samples_free(qs);
    if (w_div == 0) {
        printf("\nMuJoCo stagewise did not diverge at any w tried.\n\n");
        return;
    }

    /* rtol 1e-10: at 1e-12 the reference takes about three times as many steps (see the top) */
    sim_problem p;
    chain64_problem(&p, w_div, q0, gains, traj);
    problem_setup(&p, 1e-10);
    printf("\nOn w = %g (kp = %g, kv = %g); reference ctcsim DOPRI5 rtol 1e-10, atol 1e-12 (%ld "
           "steps). Single runs.\n\n",
           w_div, gains[0].kp, gains[0].kv, p.ref_steps);
    printf("| run | time (ms) | steps | rejected | evals | max error (rad) |\n"
           "| --- | ---: | ---: | ---: | ---: | ---: |\n");
    qs = samples_new(p.nsamples, p.n);
    char label[64];
    static const double rtols[] = {1e-4, 1e-6};
    for (int i = 0; i < 2; i++) {
        run_out r = ctc_run(
            &p,
            (ctc_integ_spec){.method = CTC_INTEG_DOPRI5, .rtol = rtols[i], .atol = rtols[i] * 1e-2},
            qs);
        snprintf(label, sizeof label, "ctcsim dopri5 rtol = %g", rtols[i]);
        print_stiff_row(label, &r, 1);
    }
    run_out rb =
        ctc_run(&p, (ctc_integ_spec){.method = CTC_INTEG_BDF, .rtol = 1e-6, .atol = 1e-8}, qs);
    print_stiff_row("ctcsim bdf rtol = 1e-06", &rb, 1);
    static const double dts[] = {1e-3, 5e-4, 2.5e-4};
    for (int h = 0; h < 2; h++)
        for (int i = 0; i < 3; i++) {
            run_out r = mj_run(&p, dts[i], h, qs);
            snprintf(label, sizeof label, "MuJoCo rk4 %s dt = %g", h ? "hold" : "stagewise",
                     dts[i]);
            print_stiff_row(label, &r, 0);
        }
    printf("\n");
    samples_free(qs);
    problem_free(&p);
    test_chain_free(p.chain);
}

int main(int argc, char **argv)
{
    int max_n = argc > 1 ? atoi(argv[1]) : 4096;
    int batches = argc > 2 ? atoi(argv[2]) : 15;
    const char *parts = argc > 3 ? argv[3] : "rtsd";
    if (max_n < 2 || batches < 1 || parts[strspn(parts, "rtsd")] != '\0') {
        fprintf(stderr, "usage: bench_mujoco [max_n >= 2 [batches >= 1 [parts: r t s d]]]\n");
        return 2;
    }
    mju_user_warning = mj_quiet;
    int failed = 0;
    double t0 = clock_s(CLOCK_MONOTONIC);
    if (strchr(parts, 'r')) failed |= bench_rhs(max_n, batches);
    if (strchr(parts, 't')) failed |= bench_rhs_trees(max_n, batches);
    if (strchr(parts, 's')) {
        sim_triple();
        sim_chain64();
    }
    if (strchr(parts, 'd')) sim_stiff();
    printf("(bench_mujoco took %.0f s)\n", clock_s(CLOCK_MONOTONIC) - t0);
    return failed || sink == 12345.678 ? 1 : 0;
}

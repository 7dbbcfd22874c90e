/*
 * test_merge.c - bodies on fixed joints merged into their parents for the dynamics (model.h
 * "merged bodies"): a UR5-like arm with its tool0 and flange frames, a tree with fixed sensor
 * mounts and a pedestal welded to the world, wrenches on a fixed child, a loop with fixed frames
 * on its path, a whole run with frames, and the models the merge changes nothing in.
 *
 * Oracles: the articulated-body, Newton-Euler and composite-rigid-body algorithms of oracle.h,
 * which see every body unmerged (a fixed joint is a joint of their own); the loop oracle
 * (tests/support/loop_oracle.h: redundant coordinates and Lagrange multipliers) on the unmerged
 * bodies; and gravity itself as a wrench: the forward pass of a model without gravity, driven by
 * f plus the generalised forces of the wrenches m_k g at every body's centre of mass (fixed
 * children included), must give the oracle's accelerations of the model with gravity; and a run
 * of the arm without its massless frames, the wrench and end effector on tool0 moved onto the
 * last link, which must record the same samples. Errors are max |difference| / max |reference|;
 * bounds are the largest value measured here (gcc, -O3) times 100 or more, the measured value
 * beside them.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "chains.h"
#include "linalg.h"
#include "ctc.h"
#include "loop_oracle.h"
#include "model_fixture.h"
#include "oracle.h"
#include "sim.h"
#include "spatial.h"
#include "wrench.h"

#define MAXB 16
#define MAXV 16

static double max_abs(const double *x, int n)
{
    double s = 0;
    for (int i = 0; i < n; i++) s = fmax(s, fabs(x[i]));
    return s;
}

static double rel_diff(const double *x, const double *ref, int n)
{
    double s = 0;
    for (int i = 0; i < n; i++) s = fmax(s, fabs(x[i] - ref[i]));
    return s / max_abs(ref, n);
}

static void box_inertia(ctc_body_spec *b, double mass, double a, double bb, double c)
{
    b->mass = mass;
    memset(b->inertia, 0, sizeof b->inertia);
    b->inertia[0] = mass * (bb * bb + c * c) / 12;
    b->inertia[4] = mass * (a * a + c * c) / 12;
    b->inertia[8] = mass * (a * a + bb * bb) / 12;
}

/* A UR5-like arm (Universal Robots' published link masses and offsets, frames parallel at q = 0,
 * boxes for the inertias): joints about z, y, y, y, z, y; then tool0 fixed 0.0823 m beyond the
 * last joint and a flange frame fixed to the last link, both massless, and, with gripper > 0, a
 * gripper of that mass fixed to tool0 (body 8). Gravity -z. */
static int ur5_spec(ctc_body_spec *b, ctc_joint_spec *j, int *parent, ctc_chain_spec *spec,
                    double gripper)
{
    static const double mass[6] = {3.7, 8.393, 2.275, 1.219, 1.219, 0.1879};
    static const double loc[6][3] = {{0, 0, 0.089159}, {0, 0.13585, 0}, {0, -0.1197, 0.425},
                                     {0, 0, 0.39225},  {0, 0.093, 0},   {0, 0, 0.09465}};
    static const double axis[6][3] = {{0, 0, 1}, {0, 1, 0}, {0, 1, 0},
                                      {0, 1, 0}, {0, 0, 1}, {0, 1, 0}};
    static const double com[6][3] = {{0, 0, 0},       {0, 0, 0.28}, {0, 0, 0.25},
                                     {0, 0.093, 0.0}, {0, 0, 0.09}, {0, 0.06, 0}};
    static const double size[6][3] = {{0.12, 0.12, 0.15}, {0.12, 0.12, 0.56}, {0.1, 0.1, 0.5},
                                      {0.08, 0.2, 0.08},  {0.08, 0.08, 0.18}, {0.08, 0.12, 0.08}};
    const int n = gripper > 0 ? 9 : 8;
    memset(b, 0, (size_t)n * sizeof *b);
    memset(j, 0, (size_t)n * sizeof *j);
    for (int k = 0; k < 6; k++) {
        box_inertia(&b[k], mass[k], size[k][0], size[k][1], size[k][2]);
        ctc_v3_copy(b[k].com, com[k]);
        j[k].type = CTC_JOINT_REVOLUTE;
        ctc_v3_copy(j[k].axis, axis[k]);
        ctc_v3_copy(j[k].location, loc[k]);
        parent[k] = k - 1;
    }
    j[6].type = CTC_JOINT_FIXED, ctc_v3_set(j[6].location, 0, 0.0823, 0), parent[6] = 5;
    j[7].type = CTC_JOINT_FIXED, ctc_v3_set(j[7].location, 0, 0.07, 0), parent[7] = 5;
    if (gripper > 0) {
        box_inertia(&b[8], gripper, 0.1, 0.06, 0.14);
        ctc_v3_set(b[8].com, 0.01, 0.05, 0.02);
        j[8].type = CTC_JOINT_FIXED, ctc_v3_set(j[8].location, 0, 0.01, 0), parent[8] = 6;
    }
    memset(spec, 0, sizeof *spec);
    spec->nbodies = n, spec->bodies = b, spec->joints = j, spec->parent = parent;
    spec->gravity[2] = -9.81;
    return n;
}

/* Worst errors over random states of the GDCA passes on m (merged) against the oracle on the
 * same model (unmerged): forward qdd vs ABA, inverse tau vs RNEA, and the mass matrix M(q)
 * (columns inverse(e_i) - inverse(0) at v = 0) vs CRBA. */
static void against_oracle(const ctc_model *m, int states, uint64_t seed, double err[3])
{
    const int nv = m->nv;
    ctc_data *d = ctc_data_new(m);
    ctc_oracle *o = ctc_oracle_new(m);
    cr_assert(d != NULL && o != NULL && nv <= MAXV);
    double q[4 * MAXV], v[MAXV], zero[MAXV], f[MAXV], a[MAXV], ref[MAXV], u[MAXV], tau0[MAXV];
    double mm[MAXV * MAXV], mref[MAXV * MAXV];
    memset(zero, 0, sizeof zero);
    err[0] = err[1] = err[2] = 0;
    for (int t = 0; t < states; t++) {
        test_random_state(m, &seed, 2.0, q, v);
        for (int i = 0; i < nv; i++) {
            f[i] = test_uniform(&seed, -20, 20);
            u[i] = test_uniform(&seed, -5, 5);
        }
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_forward(m, d, f, a);
        cr_assert(test_all_finite(a, nv));
        ctc_oracle_aba(m, o, q, v, f, ref);
        err[0] = fmax(err[0], rel_diff(a, ref, nv));
        ctc_gdca_inverse(m, d, u, a);
        ctc_oracle_rnea(m, o, q, v, u, ref);
        err[1] = fmax(err[1], rel_diff(a, ref, nv));

        ctc_kinematics(m, d, q, zero);
        ctc_handles(m, d);
        ctc_gdca_inverse(m, d, zero, tau0);
        memset(u, 0, sizeof u);
        for (int c = 0; c < nv; c++) {
            u[c] = 1;
            ctc_gdca_inverse(m, d, u, a);
            u[c] = 0;
            for (int r = 0; r < nv; r++) mm[r * nv + c] = a[r] - tau0[r];
        }
        ctc_oracle_mass_matrix(m, o, q, mref);
        err[2] = fmax(err[2], rel_diff(mm, mref, nv * nv));
    }
    ctc_oracle_free(o);
    ctc_data_free(d);
}

Test(merge, ur5_with_tool0_and_flange_matches_the_oracle)
{
    for (int g = 0; g < 2; g++) {
        ctc_body_spec b[MAXB];
        ctc_joint_spec j[MAXB];
        int parent[MAXB];
        ctc_chain_spec spec;
        const int n = ur5_spec(b, j, parent, &spec, g ? 0.8 : 0.0);
        ctc_model *m = build(&spec);
        cr_assert_eq(m->nbodies, n, "the model keeps every body");
        cr_assert_eq(m->nv, 6);
        cr_assert_eq(m->nsingular, 2, "tool0 and the flange are massless");
        cr_assert_not_null(m->dyn);
        cr_assert_eq(m->dyn->nbodies, 6, "the frames and the gripper merge into the last link");
        cr_assert_eq(m->dyn->nsingular, 0, "the reduced model has no singular body");
        for (int k = 0; k < n; k++) cr_assert_eq(m->body_dyn[k], k < 6 ? k : 5, "body %d", k);
        cr_assert_float_eq(m->dyn->bodies[5].mass, 0.1879 + (g ? 0.8 : 0.0), 1e-15);
        double err[3];
        against_oracle(m, 40, 5 + (uint64_t)g, err);
        cr_log_info("ur5%s: forward %.1e, inverse %.1e, M(q) %.1e\n", g ? " + gripper" : "", err[0],
                    err[1], err[2]);
        /* measured: forward 1.5e-15 (with the gripper 3.8e-15), inverse 1.2e-15, M 5.6e-15 */
        cr_expect_lt(err[0], 1e-12, "GDCA vs ABA %g", err[0]);
        cr_expect_lt(err[1], 1e-12, "iGDCA vs RNEA %g", err[1]);
        cr_expect_lt(err[2], 1e-12, "M(q) vs CRBA %g", err[2]);
        ctc_model_free(m);
    }
}

/* A tree of boxes: a pedestal (body 0, 4 kg) fixed to the ground; a turret on it (1, revolute z)
 * with two arms (2 and 5, revolute y and x) of two links each (3 after 2, 6 after 5, revolute),
 * a massless sensor mount fixed to each arm's end (4 on 3, 7 on 6), a 0.3 kg camera fixed to
 * mount 4 (8) and a 0.2 kg battery fixed to the turret (9). planar: every revolute axis about z
 * and gravity -y, so the tree is planar. */
static void sensor_tree(ctc_body_spec *b, ctc_joint_spec *j, int *parent, ctc_chain_spec *spec,
                        int planar)
{
    static const int par[10] = {-1, 0, 1, 2, 3, 1, 5, 6, 4, 1};
    static const ctc_joint_type type[10] = {
        CTC_JOINT_FIXED, CTC_JOINT_REVOLUTE, CTC_JOINT_REVOLUTE, CTC_JOINT_REVOLUTE,
        CTC_JOINT_FIXED, CTC_JOINT_REVOLUTE, CTC_JOINT_REVOLUTE, CTC_JOINT_FIXED,
        CTC_JOINT_FIXED, CTC_JOINT_FIXED};
    static const double axis[10][3] = {{0, 0, 0}, {0, 0, 1}, {0, 1, 0}, {1, 0, 0}, {0, 0, 0},
                                       {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    static const double loc[10][3] = {
        {0.1, 0.2, 0.3}, {0, 0, 0.4},   {0.1, 0, 0.2},   {0.5, 0, 0},         {0.4, 0, 0.05},
        {-0.1, 0, 0.2},  {-0.45, 0, 0}, {-0.3, 0.02, 0}, {0.02, 0.03, -0.01}, {0, -0.12, 0.05}};
    static const double mass[10] = {4, 2, 1.5, 1, 0, 1.2, 0.8, 0, 0.3, 0.2};
    static const double com[10][3] = {{0, 0, 0.2},     {0, 0, 0.1},   {0.25, 0, 0},  {0.2, 0, 0},
                                      {0, 0, 0},       {-0.22, 0, 0}, {-0.15, 0, 0}, {0, 0, 0},
                                      {0.03, 0, 0.01}, {0, -0.02, 0}};
    memset(b, 0, 10 * sizeof *b);
    memset(j, 0, 10 * sizeof *j);
    for (int k = 0; k < 10; k++) {
        parent[k] = par[k];
        j[k].type = type[k];
        if (type[k] == CTC_JOINT_REVOLUTE)
            ctc_v3_copy(j[k].axis, planar ? (double[3]){0, 0, 1} : axis[k]);
        ctc_v3_copy(j[k].location, loc[k]);
        if (mass[k] > 0) box_inertia(&b[k], mass[k], 0.1 + 0.05 * k, 0.08, 0.06 + 0.01 * k);
        ctc_v3_copy(b[k].com, com[k]);
    }
    memset(spec, 0, sizeof *spec);
    spec->nbodies = 10, spec->bodies = b, spec->joints = j, spec->parent = parent;
    if (planar) {
        spec->gravity[1] = -9.81;
    } else {
        spec->gravity[2] = -9.81;
    }
}

Test(merge, tree_with_fixed_sensor_mounts_matches_the_oracle)
{
    for (int planar = 0; planar < 2; planar++) {
        ctc_body_spec b[10];
        ctc_joint_spec j[10];
        int parent[10];
        ctc_chain_spec spec;
        sensor_tree(b, j, parent, &spec, planar);
        ctc_model *m = build(&spec);
        cr_assert_eq(m->form, planar ? CTC_FORM_PLANAR : CTC_FORM_SPATIAL);
        cr_assert_eq(m->nbodies, 10);
        cr_assert_not_null(m->dyn);
        cr_assert_eq(m->dyn->nbodies, 5, "turret, two arms of two links");
        static const int expect[10] = {-1, 0, 1, 2, 2, 3, 4, 4, 2, 0};
        for (int k = 0; k < 10; k++) cr_assert_eq(m->body_dyn[k], expect[k], "body %d", k);
        cr_assert_eq(m->dyn->nsingular, 0);
        cr_assert_eq(m->dyn->ground_child, 0, "the turret stands on the world");
        /* the turret's joint moved by the pedestal's offset */
        cr_assert_float_eq(m->dyn->joints[0].location[2], 0.7, 1e-15);
        double err[3];
        against_oracle(m, 40, 11 + (uint64_t)planar, err);
        cr_log_info("sensor tree (%s): forward %.1e, inverse %.1e, M(q) %.1e\n",
                    ctc_form_name(m->form), err[0], err[1], err[2]);
        /* measured (spatial, planar): forward 9.1e-15 and 7.2e-15, inverse 5.8e-16 and
           8.8e-16, M 3.1e-15 and 3.0e-15 */
        cr_expect_lt(err[0], 1e-12, "GDCA vs ABA %g", err[0]);
        cr_expect_lt(err[1], 1e-12, "iGDCA vs RNEA %g", err[1]);
        cr_expect_lt(err[2], 1e-12, "M(q) vs CRBA %g", err[2]);
        ctc_model_free(m);
    }
}

/* Gravity as wrenches: the forward pass of the tree without gravity, driven by f plus the
 * generalised forces of a world-frame force m_k g at each body's centre of mass (wrench.h; the
 * fixed children's on the merged bodies), equals the oracle's ABA of the tree with gravity. */
Test(merge, wrenches_on_fixed_children_act_on_the_composite)
{
    ctc_body_spec b[10];
    ctc_joint_spec j[10];
    int parent[10];
    ctc_chain_spec spec;
    sensor_tree(b, j, parent, &spec, 0);
    ctc_model *m = build(&spec);
    double g[3];
    ctc_v3_copy(g, spec.gravity);
    ctc_v3_set(spec.gravity, 0, 0, 0);
    ctc_model *m0 = build(&spec);
    cr_assert(m->dyn != NULL && m0->dyn != NULL);
    ctc_data *d0 = ctc_data_new(m0);
    ctc_oracle *o = ctc_oracle_new(m);
    const int nv = m->nv;
    uint64_t rng = 99;
    double worst = 0, fixed_share = 0;
    for (int t = 0; t < 20; t++) {
        double q[MAXV], v[MAXV], f[MAXV], fw[MAXV], a[MAXV], ref[MAXV], fixed[MAXV];
        test_random_state(m, &rng, 2.0, q, v);
        for (int i = 0; i < nv; i++) f[i] = test_uniform(&rng, -10, 10);
        ctc_kinematics(m0, d0, q, v);
        ctc_handles(m0, d0);
        memcpy(fw, f, sizeof fw);
        memset(fixed, 0, sizeof fixed);
        for (int k = 0; k < m->nbodies; k++) {
            ctc_wrench w = {.body = k, .frame = CTC_WRENCH_WORLD};
            ctc_v3_copy(w.point, b[k].com);
            ctc_v3_scale(w.force, g, b[k].mass);
            ctc_wrench_forces(m0, d0, &w, 0.0, fw);
            if (j[k].type == CTC_JOINT_FIXED) ctc_wrench_forces(m0, d0, &w, 0.0, fixed);
        }
        ctc_gdca_forward(m0, d0, fw, a);
        ctc_oracle_aba(m, o, q, v, f, ref);
        worst = fmax(worst, rel_diff(a, ref, nv));
        fixed_share = fmax(fixed_share, max_abs(fixed, nv));
    }
    cr_assert_gt(fixed_share, 1.0, "the fixed children's weights load the joints (%g N m)",
                 fixed_share);
    cr_log_info("weights as wrenches: %.1e\n", worst);
    /* measured: 2.6e-15 */
    cr_expect_lt(worst, 1e-12, "GDCA with weights as wrenches vs ABA with gravity %g", worst);
    ctc_oracle_free(o);
    ctc_data_free(d0);
    ctc_model_free(m0);
    ctc_model_free(m);
}

/* inserts into a loop scene a body on a fixed joint as body `at` (0 < at <= n: at n, after the
   tip, which it becomes, carrying the closing joint), at joint at's old location in body at-1's
   frame (the closing joint's at n); the joint after it then starts at its origin */
static void insert_fixed(loop_scene *s, int at, double mass)
{
    const int n = s->spec.nbodies;
    cr_assert(n + 1 <= LOOP_SCENE_MAX && at > 0 && at <= n);
    for (int k = n; k > at; k--) {
        s->bodies[k] = s->bodies[k - 1];
        s->joints[k] = s->joints[k - 1];
    }
    for (int k = n + 1; k > at; k--) s->independent[k] = s->independent[k - 1];
    ctc_joint_spec *next = at < n ? &s->joints[at + 1] : &s->loop.joint;
    memset(&s->bodies[at], 0, sizeof s->bodies[at]);
    memset(&s->joints[at], 0, sizeof s->joints[at]);
    s->joints[at].type = CTC_JOINT_FIXED;
    ctc_v3_copy(s->joints[at].location, next->location);
    ctc_v3_set(next->location, 0, 0, 0);
    s->independent[at] = 0;
    if (mass > 0) {
        box_inertia(&s->bodies[at], mass, 0.05, 0.05, 0.05);
        ctc_v3_set(s->bodies[at].com, 0.05, -0.02, 0);
    }
    s->spec.nbodies = n + 1;
    for (int k = 0; k <= n; k++) s->parent[k] = k - 1;
}

/* The paper's five-bar with a massless frame fixed between links 2 and 3 and a 0.4 kg block fixed
 * at the tip, carrying the closing joint: against the loop oracle on the unmerged bodies. */
Test(merge, loops_with_fixed_bodies_on_the_path_match_the_loop_oracle)
{
    loop_scene *s = loop_scene_five_bar();
    insert_fixed(s, 3, 0.0);
    insert_fixed(s, 6, 0.4);
    ctc_model *m = build(&s->spec);
    cr_assert_eq(m->nbodies, 7);
    cr_assert_not_null(m->dyn);
    cr_assert_eq(m->dyn->nbodies, 5);
    cr_assert_eq(m->body_dyn[3], 2);
    cr_assert_eq(m->body_dyn[6], 4, "the tip merges into the last link");
    cr_assert_eq(m->dyn->nsingular, 0);
    ctc_data *d = ctc_data_new(m);
    loop_oracle *o = loop_oracle_new(&s->spec);
    cr_assert(d != NULL && o != NULL);
    const int nq = m->nq, nv = m->nv, nvx = m->nvx;
    uint64_t rng = 1818;
    double fwd = 0, inv = 0;
    for (int t = 0; t < 20; t++) {
        double q[LOOP_SCENE_MAX], v[LOOP_SCENE_MAX], f[LOOP_SCENE_MAX], a[LOOP_SCENE_MAX],
            ref[LOOP_SCENE_MAX];
        for (int i = 0; i < nq; i++) q[i] = s->q0[i] + test_uniform(&rng, -0.01, 0.01);
        for (int i = 0; i < nv; i++) v[i] = test_uniform(&rng, -1, 1);
        char err[256] = "";
        cr_assert_eq(ctc_loop_assemble(m, d, q, v, 1e-12, 20, NULL, err, sizeof err), CTC_OK,
                     "state %d: %s", t, err);
        memset(f, 0, sizeof f);
        for (int i = 0; i < m->nind; i++) f[m->ind_coord[i]] = test_uniform(&rng, -5, 5);
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_forward(m, d, f, a);
        cr_assert_eq(loop_oracle_forward(o, q, v, f, ref, NULL), 0);
        cr_assert(test_all_finite(a, nvx) && max_abs(ref, nvx) > 0);
        fwd = fmax(fwd, rel_diff(a, ref, nvx));
        ctc_gdca_inverse(m, d, f, a);
        cr_assert_eq(loop_oracle_inverse(o, q, v, f, ref, NULL), 0);
        inv = fmax(inv, rel_diff(a, ref, nvx));
    }
    cr_log_info("five-bar with fixed bodies: forward %.1e, inverse %.1e\n", fwd, inv);
    /* measured: forward 1.2e-14, inverse 4.1e-15 */
    cr_expect_lt(fwd, 1e-11, "GDCA vs the loop oracle %g", fwd);
    cr_expect_lt(inv, 1e-11, "iGDCA vs the loop oracle %g", inv);
    loop_oracle_free(o);
    ctc_data_free(d);
    ctc_model_free(m);
    free(s);
}

/* Two 1 g links with a massless frame fixed at the tip: the frame merges, so nothing is singular
 * and the forward pass needs no refinement (unmerged, the frame's augmentation, 1e-6 kg and
 * 1e-6 kg m^2 where its subtree has no mass, left 1.9e-10 after six refinement steps). A massless
 * link on a revolute joint with only a massless frame beyond it is still refused, naming it. */
Test(merge, massless_frames_need_no_augmentation_and_a_massless_moving_tip_is_refused)
{
    for (int form = CTC_FORM_PLANAR; form <= CTC_FORM_SPATIAL; form++) {
        ctc_body_spec b[3];
        ctc_joint_spec j[3];
        memset(b, 0, sizeof b);
        memset(j, 0, sizeof j);
        for (int k = 0; k < 2; k++) {
            box_inertia(&b[k], 1e-3, 0.06, 0.01, 0.01);
            b[k].com[0] = 0.03;
            j[k].type = CTC_JOINT_REVOLUTE, j[k].axis[2] = 1;
        }
        j[1].location[0] = 0.06;
        j[2].type = CTC_JOINT_FIXED, j[2].location[0] = 0.06;
        ctc_chain_spec spec = {.nbodies = 3,
                               .bodies = b,
                               .joints = j,
                               .gravity = {0, -9.81, 0},
                               .form = (ctc_form)form};
        ctc_model *m = build(&spec);
        cr_assert_eq(m->nsingular, 1, "the frame, as given");
        cr_assert(m->dyn != NULL && m->dyn->nsingular == 0, "no singular body in the passes");
        ctc_data *d = ctc_data_new(m);
        ctc_oracle *o = ctc_oracle_new(m);
        double worst = 0;
        uint64_t rng = 1;
        for (int t = 0; t < 20; t++) {
            double q[2], v[2], f[2], a[2], ref[2];
            test_random_state(m, &rng, 2.0, q, v);
            for (int i = 0; i < 2; i++) f[i] = test_uniform(&rng, -1e-3, 1e-3);
            ctc_kinematics(m, d, q, v);
            ctc_handles(m, d);
            ctc_gdca_forward(m, d, f, a);
            cr_assert_eq(d->fwd_refine_done, 0, "no refinement step");
            ctc_oracle_aba(m, o, q, v, f, ref);
            worst = fmax(worst, rel_diff(a, ref, 2));
        }
        cr_log_info("1 g links, %s: %.1e\n", ctc_form_name(m->form), worst);
        /* measured: planar 3.9e-15, spatial 1.5e-15 */
        cr_expect_lt(worst, 1e-12, "%s: GDCA vs ABA %g", ctc_form_name(m->form), worst);
        ctc_oracle_free(o);
        ctc_data_free(d);
        ctc_model_free(m);

        /* body 1 massless: a massless tip on a revolute joint, the frame beyond it massless */
        memset(&b[1], 0, sizeof b[1]);
        expect_build_error(&spec,
                           "body 1: the joint-space mass matrix is singular: joint 1 (revolute) "
                           "moves no mass or inertia that the joints before it do not (relative "
                           "pivot 0 <= 1e-10); body 1 and the bodies beyond it need mass off the "
                           "joint's axis or inertia about it");
    }
}

/* 2000 links (1 kg, 0.5 m, hinges about z and y in turn), each with a massless frame fixed at its
 * end: the mass-matrix check refused it before (its relative pivot fell to 8.96e-11 at body 3998,
 * under the threshold: the check ran only because the frames were singular bodies, and the same
 * links without them were accepted). The frames merge, no singular body is left, so M(q) is
 * positive definite without a check, and the model matches ABA. */
Test(merge, a_long_chain_with_massless_frames_is_accepted_and_matches_the_oracle)
{
    enum { LINKS = 2000, N = 2 * LINKS };
    ctc_body_spec *b = calloc(N, sizeof *b);
    ctc_joint_spec *j = calloc(N, sizeof *j);
    cr_assert(b != NULL && j != NULL);
    for (int k = 0; k < LINKS; k++) {
        box_inertia(&b[2 * k], 1, 0.5, 0.05, 0.05);
        b[2 * k].com[0] = 0.25;
        j[2 * k].type = CTC_JOINT_REVOLUTE, j[2 * k].axis[k % 2 ? 1 : 2] = 1;
        j[2 * k + 1].type = CTC_JOINT_FIXED, j[2 * k + 1].location[0] = 0.5;
    }
    ctc_chain_spec spec = {.nbodies = N, .bodies = b, .joints = j, .gravity = {0, 0, -9.81}};
    ctc_model *m = build(&spec);
    cr_assert_eq(m->nsingular, LINKS);
    cr_assert(m->dyn != NULL && m->dyn->nbodies == LINKS && m->dyn->nsingular == 0);
    ctc_data *d = ctc_data_new(m);
    ctc_oracle *o = ctc_oracle_new(m);
    double *q = calloc(LINKS, sizeof *q), *v = calloc(LINKS, sizeof *v);
    double *f = calloc(LINKS, sizeof *f), *a = calloc(LINKS, sizeof *a);
    double *ref = calloc(LINKS, sizeof *ref);
    cr_assert(d && o && q && v && f && a && ref);
    uint64_t rng = 2000;
    double worst = 0;
    for (int t = 0; t < 3; t++) {
        test_random_state(m, &rng, 1.0, q, v);
        for (int i = 0; i < LINKS; i++) f[i] = test_uniform(&rng, -10, 10);
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_forward(m, d, f, a);
        ctc_oracle_aba(m, o, q, v, f, ref);
        worst = fmax(worst, rel_diff(a, ref, LINKS));
    }
    cr_log_info("2000 links with frames: GDCA vs ABA %.1e\n", worst);
    /* measured: 1.1e-11 (either algorithm's rounding on 2000 links) */
    cr_expect_lt(worst, 2e-9, "GDCA vs ABA %g", worst);
    free(q), free(v), free(f), free(a), free(ref);
    ctc_oracle_free(o);
    ctc_data_free(d);
    ctc_model_free(m);
    free(b), free(j);
}

/* Models without fixed joints (and one where nothing may merge) have no reduced model: the
 * passes run on them as before. */
Test(merge, models_without_fixed_joints_have_no_reduced_model)
{
    test_chain *c = test_chain_random_spatial(12, 3, TEST_ALL_JOINTS & ~(1u << CTC_JOINT_FIXED));
    ctc_model *m = build(&c->spec);
    cr_assert_null(m->dyn);
    cr_assert_null(m->body_dyn);
    ctc_data *d = ctc_data_new(m);
    cr_assert_null(d->dyn);
    ctc_data_free(d);
    ctc_model_free(m);
    test_chain_free(c);

    /* every body fixed: nothing would stay */
    ctc_body_spec b[2];
    ctc_joint_spec j[2];
    memset(b, 0, sizeof b);
    memset(j, 0, sizeof j);
    box_inertia(&b[0], 1, 0.1, 0.1, 0.1);
    box_inertia(&b[1], 1, 0.1, 0.1, 0.1);
    j[0].type = j[1].type = CTC_JOINT_FIXED;
    ctc_chain_spec spec = {.nbodies = 2, .bodies = b, .joints = j, .gravity = {0, 0, -9.81}};
    m = build(&spec);
    cr_assert_null(m->dyn);
    ctc_model_free(m);
}

/* one PD run of the UR5-like arm with a wrench on tool0 and the end effector at tool0's origin:
   frames given (tool0 body 6, flange 7, both massless) or left out (the same points on body 5,
   moved by tool0's offset) */
static ctc_sim_result *ur5_run(int frames)
{
    static ctc_body_spec b[MAXB];
    static ctc_joint_spec j[MAXB];
    static int parent[MAXB];
    ctc_chain_spec chain;
    ur5_spec(b, j, parent, &chain, 0.0);
    if (!frames) chain.nbodies = 6;
    static double q0[6] = {0.1, -1, 1, 0.2, 0.5, -0.3};
    static ctc_gains gains[6];
    static ctc_traj traj[6];
    for (int k = 0; k < 6; k++) {
        gains[k] = (ctc_gains){.kp = 100, .kv = 20};
        traj[k] = (ctc_traj){.type = CTC_TRAJ_CONSTANT, .value = 0.3 * k};
    }
    const double tool0[3] = {0, 0.0823, 0};
    ctc_wrench w = {.body = frames ? 6 : 5,
                    .point = {0.02, 0.01, 0.05},
                    .force = {3, -2, 5},
                    .torque = {0.1, 0.2, -0.3},
                    .frame = CTC_WRENCH_BODY};
    ctc_end_effector ee = {.body = frames ? 6 : 5};
    if (!frames) {
        ctc_v3_add(w.point, w.point, tool0);
        ctc_v3_copy(ee.point, tool0);
    }
    ctc_sim_spec spec = {.chain = chain,
                         .q0 = q0,
                         .controller = CTC_CTRL_PD,
                         .gains = gains,
                         .model_mass_scale = 1,
                         .model_inertia_scale = 1,
                         .traj = traj,
                         .wrenches = &w,
                         .nwrenches = 1,
                         .integrator = {.method = CTC_INTEG_RK4, .step = 1e-3},
                         .duration = 0.2,
                         .output_interval = 0.01,
                         .end_effector = &ee};
    ctc_sim_result *r = NULL;
    char err[256] = "";
    cr_assert_eq(ctc_sim_run(&spec, NULL, &r, err, sizeof err), CTC_OK, "%s", err);
    cr_assert_eq(r->status, CTC_RUN_DONE, "%s", r->message);
    return r;
}

/* A run with the frames records what the same run without them does, the wrench on tool0 and
 * the end effector at its origin moved onto the last link: massless frames change no physics,
 * and the wrench on a merged body acts on its composite. */
Test(merge, a_run_with_frames_records_what_the_run_without_them_does)
{
    ctc_sim_result *with = ur5_run(1), *without = ur5_run(0);
    cr_assert_eq(with->nsamples, without->nsamples);
    int compared = 0;
    for (int ch = 0; ch < CTC_NCHANNELS; ch++) {
        if (!with->ch[ch] || !without->ch[ch]) continue;
        cr_assert_eq(with->width[ch], without->width[ch]);
        const int count = with->nsamples * with->width[ch];
        double diff = 0;
        for (int i = 0; i < count; i++)
            diff = fmax(diff, fabs(with->ch[ch][i] - without->ch[ch][i]));
        const double scale = max_abs(without->ch[ch], count);
        const double err = scale > 0 ? diff / scale : diff; /* a channel of zeros: absolute */
        cr_log_info("channel %s: %.1e\n", ctc_channel_name((ctc_channel)ch), err);
        /* measured: at most 9.5e-16 (end_effector) */
        cr_expect_lt(err, 1e-12, "channel %s: %g", ctc_channel_name((ctc_channel)ch), err);
        compared++;
    }
    cr_assert_geq(compared, 6, "q, qdot, e, tau, energy and end_effector at least");
    ctc_sim_result_free(with);
    ctc_sim_result_free(without);
}

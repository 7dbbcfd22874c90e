/*
 * test_model.c - building a model: validation messages, planar detection, coordinates and the
 * balanced assembly tree.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "chains.h"
#include "ctc.h"
#include "spatial.h"
#include "model_fixture.h"

/* a valid 3-body planar rod pendulum to break one field at a time */
static test_chain *pendulum(void)
{
    return test_chain_rod_pendulum(3, 1.0, 1.0);
}

static void set_diag(double in[9], double a, double b, double c)
{
    memset(in, 0, 9 * sizeof(double));
    in[0] = a, in[4] = b, in[8] = c;
}

Test(model, rejects_bad_numbers_with_precise_messages)
{
    test_chain *c = pendulum();
    ctc_chain_spec spec = c->spec;

    c->bodies[1].mass = -1;
    expect_build_error(&spec, "body 1: mass must not be negative (got -1 kg)");
    c->bodies[1].mass = NAN;
    expect_build_error(&spec, "body 1: mass is not finite");
    c->bodies[1].mass = 1;

    c->bodies[2].com[2] = INFINITY;
    expect_build_error(&spec, "body 2: com[2] is not finite");
    c->bodies[2].com[2] = 0;

    c->bodies[0].inertia[5] = NAN;
    expect_build_error(&spec, "body 0: inertia[1][2] is not finite");
    c->bodies[0].inertia[5] = 0;

    c->joints[1].axis[1] = NAN;
    expect_build_error(&spec, "joint 1: axis[1] is not finite");
    ctc_v3_set(c->joints[1].axis, 0, 0, 0);
    expect_build_error(&spec, "joint 1: axis has zero length");
    ctc_v3_set(c->joints[1].axis, 0, 0, 1);

    c->joints[2].location[0] = -INFINITY;
    expect_build_error(&spec, "joint 2: location[0] is not finite");
    c->joints[2].location[0] = 0;

    c->joints[0].type = (ctc_joint_type)9;
    expect_build_error(&spec, "joint 0: unknown joint type 9");
    c->joints[0].type = CTC_JOINT_REVOLUTE;

    spec.gravity[2] = NAN;
    expect_build_error(&spec, "gravity[2] is not finite");
    spec.gravity[2] = 0;

    spec.nbodies = 0;
    expect_build_error(&spec, "chain: number of bodies must be between 1 and 1000000 (got 0)");
    spec.nbodies = 3;
    spec.bodies = NULL;
    expect_build_error(&spec, "chain: bodies and joints must be given");
    test_chain_free(c);
}

Test(model, rejects_inertias_that_no_rigid_body_has)
{
    test_chain *c = pendulum();
    double *in = c->bodies[0].inertia;

    set_diag(in, 1, 1, -0.5);
    expect_build_error(&c->spec,
                       "body 0: inertia is not positive definite (principal moment -0.5 kg m^2)");
    set_diag(in, 1, 1, 3);
    expect_build_error(&c->spec,
                       "body 0: inertia violates the triangle inequality (principal moments 1 + "
                       "1 < 3 kg m^2)");
    set_diag(in, 1, 1, 1);
    in[1] = 0.1;
    expect_build_error(&c->spec,
                       "body 0: inertia is not symmetric (inertia[0][1] = 0.1, inertia[1][0] = "
                       "0)");
    test_chain_free(c);
}

Test(model, marks_singular_bodies_and_the_forward_pass_augmented_inertias)
{
    /* slender rods in a spatial scene: no moment about their axes, singular (model.h); in a
       planar scene their moment about the normal is what counts, so none is */
    test_chain *c = pendulum();
    c->spec.form = CTC_FORM_SPATIAL;
    ctc_model *m = build(&c->spec);
    cr_assert_eq(m->nsingular, 3);
    for (int k = 0; k < 3; k++) {
        /* each rod's inertia about its own joint: 1 kg (0.5 m)^2 + trace / 2 = 1/4 + 1/12, the
           smallest in every subtree; the masses are not singular and stay */
        cr_assert(m->body_singular[k]);
        cr_assert_eq(m->fwd_bodies[k].mass, 1.0);
        cr_assert_float_eq(m->fwd_bodies[k].inertia[4], CTC_SINGULAR_AUGMENT_REL / 3.0, 1e-20);
        cr_assert_float_eq(m->fwd_bodies[k].inertia[0], 1.0 / 12 + CTC_SINGULAR_AUGMENT_REL / 3.0,
                           1e-15);
        cr_assert_eq(m->bodies[k].mass, 1.0, "the model's own bodies stay as given");
    }
    ctc_model_free(m);
    c->spec.form = CTC_FORM_AUTO;
    m = build(&c->spec);
    cr_assert_eq(m->form, CTC_FORM_PLANAR);
    cr_assert_eq(m->nsingular, 0);
    cr_assert_eq(m->fwd_bodies, m->bodies);
    cr_assert_null(m->body_singular);
    ctc_model_free(m);
    test_chain_free(c);
}

Test(model, refuses_a_tip_without_inertia_about_its_joint)
{
    test_chain *c = pendulum();
    double along_z[3] = {0, 0, 1};
    /* a rod along the plane normal: its mass on joint 1's axis, no moment about it; joint 1 still
       swings the tip, so it is accepted in the middle and refused at the tip */
    ctc_shape_rod(1.0, along_z, &c->bodies[1], NULL, 0);
    ctc_model *m = build(&c->spec);
    cr_assert_eq(m->nsingular, 1);
    ctc_model_free(m);
    c->bodies[1] = c->bodies[0];
    ctc_shape_rod(1.0, along_z, &c->bodies[2], NULL, 0);
    expect_build_error(&c->spec,
                       "body 2: the joint-space mass matrix is singular: joint 2 (revolute) "
                       "moves no mass or inertia that the joints before it do not (relative "
                       "pivot 0 <= 1e-10); body 2 and the bodies beyond it need mass off the "
                       "joint's axis or inertia about it");
    test_chain_free(c);
}

Test(model, planar_form_on_request_says_why_a_scene_is_not_planar)
{
    test_chain *c = test_chain_random_spatial(3, 1, 1u << CTC_JOINT_REVOLUTE);
    c->joints[1].type = CTC_JOINT_SPHERICAL;
    c->spec.form = CTC_FORM_PLANAR;
    expect_build_error(&c->spec,
                       "chain: planar form requested but joint 1: a spherical joint moves out "
                       "of any plane");
    test_chain_free(c);

    c = pendulum();
    c->spec.form = CTC_FORM_PLANAR;
    ctc_v3_set(c->spec.gravity, 0, 0, -9.81);
    expect_build_error(&c->spec,
                       "chain: planar form requested but gravity is not in the plane of motion");
    ctc_v3_set(c->spec.gravity, 0, -9.81, 0);
    ctc_v3_set(c->joints[2].axis, 0, 1, 1);
    expect_build_error(&c->spec,
                       "chain: planar form requested but joint 2: revolute axis is not normal "
                       "to the plane of motion");
    test_chain_free(c);
}

Test(model, detects_planar_scenes_in_any_plane)
{
    /* x-y plane, axes along +z and -z: planar, the plane is x-y itself */
    test_chain *c = pendulum();
    ctc_v3_set(c->joints[1].axis, 0, 0, -2);
    ctc_model *m = build(&c->spec);
    cr_assert_eq(m->form, CTC_FORM_PLANAR);
    cr_assert_eq(m->dim, 3);
    cr_assert_float_eq(m->plane_n[2], 1.0, 1e-15);
    cr_assert_float_eq(m->plane_e1[0], 1.0, 1e-15);
    cr_assert_float_eq(m->plane_e2[1], 1.0, 1e-15);
    cr_assert_float_eq(m->planar[1].sign, -1.0, 0);
    cr_assert_float_eq(m->joints[1].axis[2], -1.0, 1e-15); /* normalised */
    cr_assert_float_eq(m->plane_gravity[1], -9.81, 1e-15);
    ctc_model_free(m);

    /* gravity out of the plane: the same chain is spatial (and needs full-rank bodies) */
    ctc_v3_set(c->spec.gravity, 0, 0, -9.81);
    for (int k = 0; k < 3; k++) set_diag(c->bodies[k].inertia, 0.1, 0.1, 0.1);
    m = build(&c->spec);
    cr_assert_eq(m->form, CTC_FORM_SPATIAL);
    cr_assert_eq(m->dim, 6);
    ctc_model_free(m);
    test_chain_free(c);

    /* a tilted plane: axes along (1, 1, 0), gravity and prismatic axis in the plane */
    c = test_chain_random_spatial(4, 2, 1u << CTC_JOINT_REVOLUTE);
    for (int k = 0; k < 4; k++) ctc_v3_set(c->joints[k].axis, -1, -1, 0);
    c->joints[2].type = CTC_JOINT_PRISMATIC;
    ctc_v3_set(c->joints[2].axis, 1, -1, 3);
    ctc_v3_set(c->spec.gravity, 0, 0, -9.81);
    c->spec.form = CTC_FORM_AUTO;
    m = build(&c->spec);
    cr_assert_eq(m->form, CTC_FORM_PLANAR);
    cr_assert_float_eq(m->plane_n[0], sqrt(0.5), 1e-15);
    cr_assert_float_eq(m->plane_n[1], sqrt(0.5), 1e-15);
    cr_assert_float_eq(m->planar[0].sign, -1.0, 0);
    ctc_model_free(m);

    /* a cylindrical joint is never planar; forcing spatial is honoured */
    c->joints[3].type = CTC_JOINT_CYLINDRICAL;
    m = build(&c->spec);
    cr_assert_eq(m->form, CTC_FORM_SPATIAL);
    ctc_model_free(m);
    c->joints[3].type = CTC_JOINT_REVOLUTE;
    c->spec.form = CTC_FORM_SPATIAL;
    m = build(&c->spec);
    cr_assert_eq(m->form, CTC_FORM_SPATIAL);
    ctc_model_free(m);
    test_chain_free(c);
}

Test(model, counts_coordinates_of_every_joint_type)
{
    test_chain *c = test_chain_random_spatial(5, 3, TEST_ALL_JOINTS);
    const ctc_joint_type types[5] = {CTC_JOINT_SPHERICAL, CTC_JOINT_REVOLUTE, CTC_JOINT_FIXED,
                                     CTC_JOINT_CYLINDRICAL, CTC_JOINT_PRISMATIC};
    for (int k = 0; k < 5; k++) c->joints[k].type = types[k];
    ctc_model *m = build(&c->spec);
    const int nq[5] = {4, 1, 0, 2, 1}, nv[5] = {3, 1, 0, 2, 1};
    int qadr = 0, vadr = 0;
    for (int k = 0; k < 5; k++) {
        cr_assert_eq(m->jnt_nq[k], nq[k]);
        cr_assert_eq(m->jnt_nv[k], nv[k]);
        cr_assert_eq(m->jnt_qadr[k], qadr);
        cr_assert_eq(m->jnt_vadr[k], vadr);
        qadr += nq[k], vadr += nv[k];
    }
    cr_assert_eq(m->nq, 8);
    cr_assert_eq(m->nv, 7);

    double q[8];
    ctc_model_q_zero(m, q);
    const double zero[8] = {1, 0, 0, 0, 0, 0, 0, 0};
    for (int i = 0; i < 8; i++) cr_assert_eq(q[i], zero[i]);
    ctc_model_free(m);
    test_chain_free(c);
}

Test(model, quaternion_rate_follows_the_child_frame_angular_velocity)
{
    test_chain *c = test_chain_random_spatial(1, 4, 1u << CTC_JOINT_SPHERICAL);
    ctc_model *m = build(&c->spec);
    double q[4] = {0.8, 0.1, -0.4, 0.2}, w[3] = {0.3, -1.1, 0.7}, dq[4], h = 1e-6;
    ctc_model_q_normalize(m, q);
    ctc_model_q_rate(m, q, w, dq);

    /* R(q + h dq) ~ R(q) (1 + h [w]x): compare R^T dR/dt with [w]x */
    double qp[4], qm[4], rp[9], rm[9], r[9], dr[9], skew[9];
    for (int i = 0; i < 4; i++) qp[i] = q[i] + h * dq[i], qm[i] = q[i] - h * dq[i];
    ctc_m3_from_quat(rp, qp);
    ctc_m3_from_quat(rm, qm);
    ctc_m3_from_quat(r, q);
    for (int i = 0; i < 9; i++) dr[i] = (rp[i] - rm[i]) / (2 * h);
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            skew[3 * i + j] = r[i] * dr[j] + r[3 + i] * dr[3 + j] + r[6 + i] * dr[6 + j];
        }
    }
    cr_assert_float_eq(skew[7], w[0], 1e-8);
    cr_assert_float_eq(skew[2], w[1], 1e-8);
    cr_assert_float_eq(skew[3], w[2], 1e-8);
    cr_assert_float_eq(q[0] * dq[0] + q[1] * dq[1] + q[2] * dq[2] + q[3] * dq[3], 0.0, 1e-15);

    double zero[4] = {0, 0, 0, 0};
    ctc_model_q_normalize(m, zero);
    cr_assert_eq(zero[0], 1.0);
    ctc_model_free(m);
    test_chain_free(c);
}

Test(model, copies_the_spec_and_symmetrises_inertia)
{
    test_chain *c = pendulum();
    c->bodies[0].inertia[1] = 1e-12;
    ctc_model *m = build(&c->spec);
    c->bodies[0].mass = 99;
    c->joints[0].location[0] = 5;
    cr_assert_eq(m->bodies[0].mass, 1.0);
    cr_assert_eq(m->joints[0].location[0], 0.0);
    cr_assert_eq(m->bodies[0].inertia[1], m->bodies[0].inertia[3]);
    ctc_model_free(m);
    ctc_model_free(NULL);
    test_chain_free(c);
}

/* checks the subtree of assembly index a covers bodies [first, last]; returns its height */
static int check_subtree(const ctc_model *m, int a, int first, int last, int *joint_seen)
{
    if (a < m->nbodies) {
        cr_assert_eq(first, a);
        cr_assert_eq(last, a);
        return 0;
    }
    const ctc_tree_node *node = &m->tree[a - m->nbodies];
    cr_assert_eq(node->first, first);
    cr_assert_eq(node->last, last);
    cr_assert(node->joint > first && node->joint <= last);
    joint_seen[node->joint]++;
    /* children come before their parent in the array */
    cr_assert(node->left < a && node->right < a);
    int hl = check_subtree(m, node->left, first, node->joint - 1, joint_seen);
    int hr = check_subtree(m, node->right, node->joint, last, joint_seen);
    int h = 1 + (hl > hr ? hl : hr);
    cr_assert_eq(node->height, h);
    /* balanced: the halves differ by at most one body */
    int nl = node->joint - first, nr = last - node->joint + 1;
    cr_assert(abs(nl - nr) <= 1);
    return h;
}

Test(model, lays_out_a_balanced_tree_ordered_by_height)
{
    for (int n = 1; n <= 130; n++) {
        test_chain *c = test_chain_rod_pendulum(n, 0.5, 1.0);
        ctc_model *m = build(&c->spec);
        int joint_seen[131] = {0};
        int expect_height = 0;
        while ((1 << expect_height) < n) expect_height++;
        cr_assert_eq(m->ntree, n - 1);
        cr_assert_eq(m->height, expect_height, "n=%d", n);
        int h = check_subtree(m, m->root, 0, n - 1, joint_seen);
        cr_assert_eq(h, expect_height);
        for (int j = 1; j < n; j++) cr_assert_eq(joint_seen[j], 1, "n=%d joint %d", n, j);
        /* height_start delimits the nodes of each height */
        for (int hh = 1; hh <= m->height; hh++) {
            for (int i = m->height_start[hh - 1]; i < m->height_start[hh]; i++) {
                cr_assert_eq(m->tree[i].height, hh);
            }
        }
        cr_assert_eq(m->height_start[m->height], m->ntree);
        ctc_model_free(m);
        test_chain_free(c);
    }
}

/* The topology read back as the set of edges child -> parent, each checked against the parent
 * array, and the children lists against a count made from the parent array alone: every body
 * appears once, under its own parent, in increasing order. */
static void check_topology(const ctc_model *m, const int *want_parent)
{
    int n = m->nbodies, seen[131] = {0};
    for (int k = 0; k < n; k++) {
        cr_assert_eq(m->body_parent[k], want_parent[k], "n=%d body %d", n, k);
        cr_assert(m->body_parent[k] >= -1 && m->body_parent[k] < k, "n=%d body %d", n, k);
    }
    for (int p = -1; p < n; p++) {
        int last = -1, count = 0, want = 0;
        for (int k = 0; k < n; k++) want += want_parent[k] == p;
        for (int c = p < 0 ? m->ground_child : m->body_child[p]; c >= 0; c = m->body_sibling[c]) {
            cr_assert_eq(m->body_parent[c], p, "n=%d: body %d listed under %d", n, c, p);
            cr_assert_gt(c, last, "n=%d: children of %d out of order", n, p);
            last = c;
            seen[c]++;
            count++;
        }
        cr_assert_eq(count, want, "n=%d: body %d has %d children, listed %d", n, p, want, count);
    }
    for (int k = 0; k < n; k++) cr_assert_eq(seen[k], 1, "n=%d body %d", n, k);
}

Test(model, a_chain_is_the_tree_whose_parents_are_the_previous_bodies)
{
    int parent[130];
    for (int n = 1; n <= 130; n++) {
        test_chain *c = test_chain_random_spatial(n, 7 + (uint64_t)n, TEST_ALL_JOINTS);
        ctc_model *m = build(&c->spec);
        for (int k = 0; k < n; k++) parent[k] = k - 1; /* the oracle: a chain, written out */
        check_topology(m, parent);
        cr_assert_eq(m->ground_child, 0);
        cr_assert_eq(m->body_child[n - 1], -1, "n=%d: the tip is a leaf", n);
        for (int k = 0; k + 1 < n; k++) {
            cr_assert_eq(m->body_child[k], k + 1);
            cr_assert_eq(m->body_sibling[k + 1], -1, "n=%d: a chain has no branches", n);
        }
        ctc_model_free(m);
        test_chain_free(c);
    }
}

Test(model, a_loops_closing_joint_is_not_a_tree_edge)
{
    /* a planar 5-bar on the ground and a 4-bar closed on body 1 of a 5-body chain: the closing
       joint (n) joins the tip to the ground or to body 1, yet the tree stays the chain: the tip
       has no child, body 1 only body 2, the ground only body 0 */
    for (int on_body = 0; on_body <= 1; on_body++) {
        test_chain *c = test_chain_rod_pendulum(5, 1.0, 1.0);
        ctc_loop_spec loop = {0};
        loop.joint.type = CTC_JOINT_REVOLUTE;
        ctc_v3_set(loop.joint.axis, 0, 0, 1);
        ctc_v3_set(loop.joint.location, 0, -1, 0);
        ctc_v3_set(loop.anchor, 1.0, 0, 0);
        loop.on_body = on_body;
        loop.body = 1;
        unsigned char indep[6] = {1, 1, 1, 0, 0, 0};
        ctc_chain_spec spec = c->spec;
        spec.loop = &loop;
        spec.independent = indep;
        ctc_model *m = build(&spec);
        int parent[5] = {-1, 0, 1, 2, 3};
        cr_assert_eq(m->has_loop, 1);
        cr_assert_eq(m->njoints, 6);
        cr_assert_eq(m->loop_body, on_body ? 1 : -1);
        check_topology(m, parent);
        cr_assert_eq(m->body_child[4], -1, "the closing joint gives the tip no child");
        cr_assert_eq(m->ground_child, 0);
        cr_assert_eq(m->body_sibling[0], -1, "the closing joint gives the ground no second child");
        cr_assert_eq(m->body_child[1], 2);
        cr_assert_eq(m->body_sibling[2], -1, "the closing joint gives body 1 no second child");
        ctc_model_free(m);
        test_chain_free(c);
    }
}

Test(model, builds_any_tree_its_parent_array_gives)
{
    /* random parent arrays, one root or several on the ground; the topology against the array,
       and each heavy child against a subtree count made here from the array alone */
    int parent[130], size[130];
    for (int n = 1; n <= 130; n += 3) {
        test_chain *c = test_chain_random_spatial(n, 17 + (uint64_t)n, TEST_ALL_JOINTS);
        test_random_parents(n, 29 + (uint64_t)n, n % 2 ? 0.0 : 0.2, parent);
        test_chain_set_parents(c, parent);
        ctc_model *m = build(&c->spec);
        check_topology(m, parent);
        int chain = 1;
        for (int k = 0; k < n; k++) chain &= parent[k] == k - 1;
        cr_assert_eq(m->chain, chain, "n=%d", n);
        for (int k = 0; k < n; k++) size[k] = 1;
        for (int k = n - 1; k > 0; k--) {
            if (parent[k] >= 0) size[parent[k]] += size[k];
        }
        for (int k = 0; k < n; k++) {
            int best = -1;
            for (int j = k + 1; j < n; j++) {
                if (parent[j] == k && (best < 0 || size[j] > size[best])) best = j;
            }
            cr_assert_eq(m->body_heavy[k], best, "n=%d body %d", n, k);
        }
        ctc_model_free(m);
        test_chain_free(c);
    }
}

Test(model, rejects_parents_that_are_not_earlier_bodies)
{
    test_chain *c = test_chain_rod_pendulum(5, 1.0, 1.0);
    int parent[5] = {-1, 0, 0, 5, 1};
    c->spec.parent = parent;
    expect_build_error(&c->spec,
                       "body 3: parent must be a body before it (-1 for the ground), got 5");
    parent[3] = 3;
    expect_build_error(&c->spec,
                       "body 3: parent must be a body before it (-1 for the ground), got 3");
    parent[3] = -2;
    expect_build_error(&c->spec,
                       "body 3: parent must be a body before it (-1 for the ground), got -2");
    parent[3] = 1;
    parent[0] = 0;
    expect_build_error(&c->spec,
                       "body 0: parent must be a body before it (-1 for the ground), got 0");
    test_chain_free(c);
}

Test(model, a_loop_on_a_tree_must_close_on_the_tips_path_from_one_ground_body)
{
    test_chain *c = test_chain_rod_pendulum(5, 1.0, 1.0);
    ctc_loop_spec loop = {0};
    loop.joint.type = CTC_JOINT_REVOLUTE;
    ctc_v3_set(loop.joint.axis, 0, 0, 1);
    ctc_v3_set(loop.anchor, 1.0, 0, 0);
    unsigned char indep[6] = {1, 1, 1, 0, 0, 0};
    int parent[5] = {-1, 0, 1, 1, 3}; /* the spine 0-1-3-4; body 2 a branch on body 1 */
    c->spec.loop = &loop;
    c->spec.independent = indep;
    c->spec.parent = parent;
    loop.on_body = 1;
    loop.body = 2;
    expect_build_error(&c->spec,
                       "loop: body 2 is not on the path from the ground to the tip (body 4); "
                       "a loop between two branches is not supported yet");
    loop.body = 1; /* an ancestor of the tip: the loop's joints are 3, 4 and the closing one */
    ctc_model *m = build(&c->spec);
    cr_assert_eq(m->chain, 0);
    cr_assert_eq(m->loop_first, 3);
    const unsigned char in_loop[6] = {0, 0, 0, 1, 1, 1};
    for (int k = 0; k < 6; k++) cr_expect_eq(m->jnt_loop[k], in_loop[k], "joint %d", k);
    cr_expect_eq(m->body_heavy[1], 3);
    ctc_model_free(m);
    indep[2] = 0; /* joint 2 is off the loop: nothing would determine its motion */
    expect_build_error(&c->spec,
                       "loop: joint 2 is outside the loop (which closes on body 1), so nothing "
                       "determines its motion: mark it independent (or every joint "
                       "dependent, for a passive run)");
    loop.on_body = 0;
    expect_build_error(&c->spec,
                       "loop: joint 2 is outside the loop (which closes on the ground), so "
                       "nothing determines its motion: mark it independent (or every joint "
                       "dependent, for a passive run)");
    int forest[5] = {-1, 0, -1, 1, 3}; /* two bodies on the ground */
    c->spec.parent = forest;
    expect_build_error(&c->spec,
                       "loop: a loop on a tree with several bodies on the ground (bodies 0 and "
                       "2) is not supported yet");
    int chain[5] = {-1, 0, 1, 2, 3}; /* a chain given by its parents is a chain */
    c->spec.parent = chain;
    m = build(&c->spec);
    cr_assert_eq(m->chain, 1);
    cr_assert_eq(m->has_loop, 1);
    cr_assert_eq(m->loop_first, 0);
    ctc_model_free(m);
    test_chain_free(c);
}

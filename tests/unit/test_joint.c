/*
 * test_joint.c - the table of joint kinds (src/model/joint.c, model.h ctc_joint_class): each
 * row's sizes and units against the independent oracle's motion subspace (Featherstone's
 * Table 4.1, src/reference/oracle.c), and the builder's checks (axis, planar form, a loop's
 * closing joint) and names against the rows, with the builder's exact messages.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "chains.h"
#include "model_fixture.h"
#include "oracle_internal.h"
#include "spatial.h"

/* one body of type t on the ground: a tilted axis (unit after the builder), form as given */
static ctc_chain_spec one_body(ctc_joint_type t, ctc_form form, ctc_body_spec *b, ctc_joint_spec *j)
{
    memset(b, 0, sizeof *b);
    memset(j, 0, sizeof *j);
    b->mass = 1.5;
    b->com[0] = 0.2;
    b->inertia[0] = 0.3, b->inertia[4] = 0.4, b->inertia[8] = 0.5;
    j->type = t;
    ctc_v3_set(j->axis, 0.3, -0.4, 1.2);
    ctc_v3_set(j->location, 0.1, 0.2, 0.3);
    ctc_chain_spec spec = {.nbodies = 1, .bodies = b, .joints = j, .form = form};
    ctc_v3_set(spec.gravity, 0, 0, -9.81);
    return spec;
}

static int column_nonzero(const double *s, int from)
{
    return s[from] != 0 || s[from + 1] != 0 || s[from + 2] != 0;
}

Test(joint, every_rows_sizes_and_units_match_the_oracles_motion_subspace)
{
    for (int t = 0; t < CTC_JOINT_NTYPES; t++) {
        const ctc_joint_class *c = ctc_joint_class_of((ctc_joint_type)t);
        cr_assert_not_null(c);
        cr_assert_leq(c->nq, CTC_JOINT_MAX_NQ, "%s", c->name);
        cr_assert_leq(c->nv, CTC_JOINT_MAX_NV, "%s", c->name);
        ctc_body_spec b;
        ctc_joint_spec j;
        ctc_chain_spec spec = one_body((ctc_joint_type)t, CTC_FORM_SPATIAL, &b, &j);
        ctc_model *m = build(&spec);
        cr_assert_eq(m->nq, c->nq, "%s: model nq %d, row %d", c->name, m->nq, c->nq);
        cr_assert_eq(m->nv, c->nv, "%s: model nv %d, row %d", c->name, m->nv, c->nv);

        /* the oracle's subspace (6 x nv columns: angular then linear) at the reference q */
        double q[CTC_JOINT_MAX_NQ], xform[36], s[18];
        ctc_model_q_zero(m, q);
        ctc_oracle_joint_model(m, 0, q, xform, s);
        for (int i = 0; i < 3; i++) {
            int ang = column_nonzero(s, 6 * i), lin = column_nonzero(s, 6 * i + 3);
            if (i >= c->nv) {
                cr_assert(!ang && !lin, "%s: the oracle moves along column %d, beyond nv = %d",
                          c->name, i, c->nv);
                continue;
            }
            cr_assert(ang != lin, "%s: column %d is neither a pure rotation nor a translation",
                      c->name, i);
            cr_assert_eq((c->linear_mask >> i) & 1u, (unsigned)lin,
                         "%s: coordinate %d is a %s, the row says otherwise", c->name, i,
                         lin ? "translation" : "rotation");
        }
        cr_assert_eq(c->linear_mask >> c->nv, 0u, "%s: linear_mask beyond nv", c->name);

        /* an axis where the row needs one, unit; none (zeroed) where it does not */
        double len = ctc_v3_norm(m->joints[0].axis);
        cr_assert_float_eq(len, c->needs_axis ? 1.0 : 0.0, 1e-15, "%s: axis length %g", c->name,
                           len);
        ctc_model_free(m);

        /* a zero axis is an error exactly where the row needs one */
        ctc_v3_set(j.axis, 0, 0, 0);
        char err[256] = "";
        ctc_status st = ctc_model_build(&spec, &m, err, sizeof err);
        if (c->needs_axis) {
            cr_assert_eq(st, CTC_EINVAL, "%s", c->name);
            cr_assert_str_eq(err, "joint 0: axis has zero length");
        } else {
            cr_assert_eq(st, CTC_OK, "%s: %s", c->name, err);
            ctc_model_free(m);
        }
    }
}

Test(joint, names_round_trip_and_unknown_types_are_refused)
{
    for (int t = 0; t < CTC_JOINT_NTYPES; t++) {
        const char *name = ctc_joint_type_name((ctc_joint_type)t);
        cr_assert_str_eq(name, ctc_joint_classes[t].name);
        cr_assert_eq(ctc_joint_type_of(name), t, "%s", name);
        cr_assert_eq(ctc_joint_nq((ctc_joint_type)t), ctc_joint_classes[t].nq);
        cr_assert_eq(ctc_joint_nv((ctc_joint_type)t), ctc_joint_classes[t].nv);
    }
    cr_assert_str_eq(ctc_joint_type_name((ctc_joint_type)CTC_JOINT_NTYPES), "unknown");
    cr_assert_null(ctc_joint_class_of((ctc_joint_type)-1));
    cr_assert_eq(ctc_joint_nq((ctc_joint_type)CTC_JOINT_NTYPES), 0);
    cr_assert_eq(ctc_joint_nv((ctc_joint_type)-1), 0);
    cr_assert_eq(ctc_joint_type_of("hinge"), -1);
    cr_assert_eq(ctc_joint_type_of(NULL), -1);

    ctc_body_spec b;
    ctc_joint_spec j;
    ctc_chain_spec spec = one_body((ctc_joint_type)CTC_JOINT_NTYPES, CTC_FORM_AUTO, &b, &j);
    char err[256] = "";
    ctc_model *m = (ctc_model *)0x1;
    cr_assert_eq(ctc_model_build(&spec, &m, err, sizeof err), CTC_EINVAL);
    cr_assert_null(m);
    char want[64];
    snprintf(want, sizeof want, "joint 0: unknown joint type %d", CTC_JOINT_NTYPES);
    cr_assert_str_eq(err, want);
}

Test(joint, the_planar_form_takes_exactly_the_planar_rows)
{
    /* a revolute joint about z, then the kind under test with an axis that fits the x-y plane
       where the kind can (along z for a rotation, along x for a translation) */
    for (int t = 0; t < CTC_JOINT_NTYPES; t++) {
        const ctc_joint_class *c = &ctc_joint_classes[t];
        ctc_body_spec b[2];
        ctc_joint_spec j[2];
        ctc_chain_spec spec = one_body(CTC_JOINT_REVOLUTE, CTC_FORM_PLANAR, &b[0], &j[0]);
        one_body((ctc_joint_type)t, CTC_FORM_PLANAR, &b[1], &j[1]);
        ctc_v3_set(j[0].axis, 0, 0, 1);
        ctc_v3_set(j[1].axis, 0, 0, 1);
        if (c->linear_mask & 1u) ctc_v3_set(j[1].axis, 1, 0, 0);
        ctc_v3_set(j[1].location, 0, -1, 0);
        spec.nbodies = 2, spec.bodies = b, spec.joints = j;
        ctc_v3_set(spec.gravity, 0, -9.81, 0);
        char err[256] = "";
        ctc_model *m = NULL;
        ctc_status st = ctc_model_build(&spec, &m, err, sizeof err);
        if (c->planar) {
            cr_assert_eq(st, CTC_OK, "%s: %s", c->name, err);
            cr_assert_eq(m->form, CTC_FORM_PLANAR, "%s", c->name);
            ctc_model_free(m);
        } else {
            char want[160];
            snprintf(want, sizeof want,
                     "chain: planar form requested but joint 1: a %s joint moves out of any "
                     "plane",
                     c->name);
            cr_assert_eq(st, CTC_EINVAL, "%s", c->name);
            cr_assert_str_eq(err, want);
        }
    }
}

Test(joint, a_loop_closes_through_exactly_the_loop_closing_rows)
{
    /* the planar 5-bar of test_model.c, its closing joint of each kind in turn */
    char kinds[128] = "";
    int count = 0, seen = 0;
    for (int t = 0; t < CTC_JOINT_NTYPES; t++) count += ctc_joint_classes[t].loop_closing;
    for (int t = 0; t < CTC_JOINT_NTYPES; t++) {
        if (!ctc_joint_classes[t].loop_closing) continue;
        size_t used = strlen(kinds);
        snprintf(kinds + used, sizeof kinds - used, "%s%s",
                 seen == 0           ? ""
                 : seen == count - 1 ? " or "
                                     : ", ",
                 ctc_joint_classes[t].name);
        seen++;
    }
    cr_assert_str_eq(kinds, "revolute, prismatic or spherical",
                     "the built-in closing kinds changed: update DESIGN and the job format");

    for (int t = 0; t <= CTC_JOINT_NTYPES; t++) {
        test_chain *c = test_chain_rod_pendulum(5, 1.0, 1.0);
        ctc_loop_spec loop = {0};
        loop.joint.type = (ctc_joint_type)t;
        ctc_v3_set(loop.joint.axis, 0, 0, 1);
        ctc_v3_set(loop.joint.location, 0, -1, 0);
        ctc_v3_set(loop.anchor, 1.0, 0, 0);
        unsigned char indep[6] = {1, 1, 1, 0, 0, 0};
        ctc_chain_spec spec = c->spec;
        spec.loop = &loop;
        spec.independent = indep;
        char err[256] = "", want[256];
        ctc_model *m = NULL;
        ctc_status st = ctc_model_build(&spec, &m, err, sizeof err);
        const ctc_joint_class *row = ctc_joint_class_of((ctc_joint_type)t);
        snprintf(want, sizeof want, "loop: the closing joint must be %s (got %s)", kinds,
                 row ? row->name : "an unknown type");
        if (row != NULL && row->loop_closing) {
            cr_assert(strcmp(err, want) != 0, "%s refused as a closing joint", row->name);
            if (t == CTC_JOINT_REVOLUTE) cr_assert_eq(st, CTC_OK, "%s", err);
        } else {
            cr_assert_eq(st, CTC_EINVAL);
            cr_assert_str_eq(err, want);
        }
        ctc_model_free(m);
        test_chain_free(c);
    }
}

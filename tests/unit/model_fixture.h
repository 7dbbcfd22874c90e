/*
 * model_fixture.h - building a model that a test expects to be valid (tests/unit only).
 */
#ifndef CTC_MODEL_FIXTURE_H
#define CTC_MODEL_FIXTURE_H

#include <criterion/criterion.h>

#include "model.h"

/* The model of spec; fails the test with the builder's message when spec is refused. The caller
 * owns the model (ctc_model_free). */
static inline ctc_model *build(const ctc_chain_spec *spec)
{
    char err[512] = "";
    ctc_model *m = NULL;
    ctc_status st = ctc_model_build(spec, &m, err, sizeof err);
    cr_assert_eq(st, CTC_OK, "build failed: %s", err);
    return m;
}

/* Asserts that ctc_model_build refuses spec with CTC_EINVAL, leaves the model NULL and says
 * exactly message. */
static inline void expect_build_error(const ctc_chain_spec *spec, const char *message)
{
    char err[512] = "";
    ctc_model *m = (ctc_model *)0x1;
    ctc_status st = ctc_model_build(spec, &m, err, sizeof err);
    cr_assert_eq(st, CTC_EINVAL, "expected EINVAL for \"%s\", got %s", message,
                 ctc_status_name(st));
    cr_assert_null(m);
    cr_assert_str_eq(err, message);
}

/* Rewires a built model's topology (model.h body_parent, body_child, body_sibling, ground_child)
 * to the tree given by parent (n, -1 <= parent[k] < k), so that a pass that walks the topology can
 * be checked on a branched tree before ctc_model_build accepts one. The children lists are
 * rebuilt here by appending each body to its parent's list, apart from the builder's code. The
 * joints' locations must already be given in the new parents' frames. Only passes that read
 * nothing of the chain's layout but the topology arrays may use the result (the oracle, the
 * kinematics); the handles and the GDCA passes read the plan and heavy children that
 * ctc_model_build makes from ctc_chain_spec.parent, which this leaves as the chain's. */
static inline void fixture_set_parents(ctc_model *m, const int *parent)
{
    m->ground_child = -1;
    for (int k = 0; k < m->nbodies; k++) {
        cr_assert(parent[k] >= -1 && parent[k] < k, "body %d: parent %d", k, parent[k]);
        m->body_parent[k] = parent[k];
        m->body_child[k] = m->body_sibling[k] = -1;
        int *slot = parent[k] < 0 ? &m->ground_child : &m->body_child[parent[k]];
        while (*slot >= 0) slot = &m->body_sibling[*slot];
        *slot = k;
    }
}

#endif

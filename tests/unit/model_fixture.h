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

#endif

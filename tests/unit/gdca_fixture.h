/*
 * gdca_fixture.h - a check that the GDCA passes' tests share (test_gdca_forward.c,
 * test_gdca_inverse.c); tests/unit only.
 *
 * A planar chain computed in the plane's 3-vector form and in the general 6-vector form must give
 * the same pass outputs: two routes through the handles and the assembly (DESIGN.md section 3).
 */
#ifndef CTC_GDCA_FIXTURE_H
#define CTC_GDCA_FIXTURE_H

#include <criterion/criterion.h>
#include <stdint.h>

#include "chains.h"
#include "ctc.h"
#include "linalg.h"
#include "model_fixture.h"

/* a GDCA pass at the state d's kinematics and handles hold: ctc_gdca_forward (x = driving forces,
 * y = accelerations) or ctc_gdca_inverse (x = commanded accelerations, y = driving forces) */
typedef void (*fixture_gdca_pass)(const ctc_model *m, ctc_data *d, const double *x, double *y);

/* Builds c (a planar chain, nv <= 16) in form AUTO and in form SPATIAL (asserted to give PLANAR
 * and SPATIAL models) and runs pass in both at one random state: q and v from
 * test_random_state(seed, vmax 2), then x uniform in [-5, 5] per coordinate. Returns the relative
 * difference of the outputs, test_rel_err(planar, spatial). c is left as it was given. */
static inline double fixture_planar_vs_spatial(test_chain *c, fixture_gdca_pass pass, uint64_t seed)
{
    ctc_form form = c->spec.form;
    c->spec.form = CTC_FORM_AUTO;
    ctc_model *mp = build(&c->spec);
    c->spec.form = CTC_FORM_SPATIAL;
    ctc_model *ms = build(&c->spec);
    c->spec.form = form;
    cr_assert_eq(mp->form, CTC_FORM_PLANAR);
    cr_assert_eq(ms->form, CTC_FORM_SPATIAL);
    cr_assert_leq(mp->nv, 16);
    ctc_model *forms[2] = {mp, ms};
    ctc_data *data[2] = {ctc_data_new(mp), ctc_data_new(ms)};
    cr_assert(data[0] && data[1]);
    int nv = mp->nv;
    double q[16], v[16], x[16], y[2][16];
    uint64_t rng = seed;
    test_random_state(mp, &rng, 2.0, q, v);
    for (int k = 0; k < nv; k++) x[k] = test_uniform(&rng, -5, 5);
    for (int i = 0; i < 2; i++) { /* the same state and input in either form */
        ctc_kinematics(forms[i], data[i], q, v);
        ctc_handles(forms[i], data[i]);
        pass(forms[i], data[i], x, y[i]);
    }
    double err = test_rel_err(y[0], y[1], nv);
    ctc_data_free(data[0]), ctc_data_free(data[1]);
    ctc_model_free(mp), ctc_model_free(ms);
    return err;
}

#endif

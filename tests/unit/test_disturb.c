/*
 * test_disturb.c - disturbances (src/control/disturb.c): each type's value against its closed form
 * written out here, the step's right-continuity at its time, the breakpoint the integrator
 * restarts at, and the exact message of every invalid parameter.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "disturb.h"

#define PI 3.14159265358979323846

static ctc_disturb sine(double amplitude, double period, double phase, double offset)
{
    return (ctc_disturb){.type = CTC_DISTURB_SINE,
                         .amplitude = amplitude,
                         .period = period,
                         .phase = phase,
                         .offset = offset};
}

static ctc_disturb step(double value, double time)
{
    return (ctc_disturb){.type = CTC_DISTURB_STEP, .value = value, .time = time};
}

static const double sample_times[6] = {-1e6, -2.5, 0.0, 0.3, 7.0, 1e6};

Test(disturb, none_is_zero_everywhere_and_has_no_breakpoint)
{
    /* the zero struct is "none" */
    ctc_disturb z = {0};
    cr_assert_eq(z.type, CTC_DISTURB_NONE);
    cr_assert_eq(ctc_disturb_check(&z, NULL, 0), CTC_OK);
    for (int i = 0; i < 6; i++) {
        cr_assert_eq(ctc_disturb_eval(&z, sample_times[i]), 0.0, "t = %g", sample_times[i]);
    }
    cr_assert(isinf(ctc_disturb_breakpoint(&z)) && ctc_disturb_breakpoint(&z) > 0);
}

Test(disturb, constant_is_its_value_everywhere_and_has_no_breakpoint)
{
    /* the paper's 0.2 N m, and a negative one */
    const double values[2] = {0.2, -7.25};
    for (int k = 0; k < 2; k++) {
        ctc_disturb z = {.type = CTC_DISTURB_CONSTANT, .value = values[k]};
        cr_assert_eq(ctc_disturb_check(&z, NULL, 0), CTC_OK);
        for (int i = 0; i < 6; i++) {
            cr_assert_eq(ctc_disturb_eval(&z, sample_times[i]), values[k], "t = %g",
                         sample_times[i]);
        }
        cr_assert(isinf(ctc_disturb_breakpoint(&z)) && ctc_disturb_breakpoint(&z) > 0);
    }
}

Test(disturb, sine_matches_its_closed_form_and_has_no_breakpoint)
{
    /* z = c + A sin(2 pi t / T + p) */
    const double amp = 0.5, period = 0.8, phase = -1.2, offset = 0.1;
    ctc_disturb z = sine(amp, period, phase, offset);
    cr_assert_eq(ctc_disturb_check(&z, NULL, 0), CTC_OK);
    for (int i = 0; i <= 300; i++) {
        double t = -10.0 + i * 0.1;
        double want = offset + amp * sin(2 * PI * t / period + phase);
        double got = ctc_disturb_eval(&z, t);
        cr_assert_leq(fabs(got - want), 1e-13, "t = %g: z = %.17g, want %.17g", t, got, want);
    }

    /* a quarter period after a zero crossing (phase 0, t = 0) it peaks at c + A */
    ctc_disturb z0 = sine(2.0, 4.0, 0.0, -1.0);
    cr_assert_leq(fabs(ctc_disturb_eval(&z0, 0.0) - -1.0), 1e-15);
    cr_assert_leq(fabs(ctc_disturb_eval(&z0, 1.0) - 1.0), 1e-15);
    cr_assert_leq(fabs(ctc_disturb_eval(&z0, 3.0) - -3.0), 1e-15);
    cr_assert(isinf(ctc_disturb_breakpoint(&z)) && ctc_disturb_breakpoint(&z) > 0);
}

Test(disturb, sine_repeats_every_period)
{
    ctc_disturb z = sine(1.5, 0.7, 0.4, 0.0);
    for (int i = 0; i < 40; i++) {
        double t = 0.05 * i, now = ctc_disturb_eval(&z, t);
        cr_assert_leq(fabs(ctc_disturb_eval(&z, t + 500 * 0.7) - now), 1e-12, "t = %g", t);
        cr_assert_leq(fabs(ctc_disturb_eval(&z, t - 3 * 0.7) - now), 1e-13, "t = %g", t);
    }
}

Test(disturb, step_is_zero_before_its_time_and_its_value_from_then_on)
{
    const double time = 1.25;
    ctc_disturb z = step(-3.5, time);
    cr_assert_eq(ctc_disturb_check(&z, NULL, 0), CTC_OK);
    cr_assert_eq(ctc_disturb_eval(&z, -INFINITY), 0.0);
    cr_assert_eq(ctc_disturb_eval(&z, 0.0), 0.0);
    cr_assert_eq(ctc_disturb_eval(&z, nextafter(time, -INFINITY)), 0.0);
    cr_assert_eq(ctc_disturb_eval(&z, time), -3.5, "at t == time the new value applies");
    cr_assert_eq(ctc_disturb_eval(&z, nextafter(time, INFINITY)), -3.5);
    cr_assert_eq(ctc_disturb_eval(&z, 1e9), -3.5);
    cr_assert(isnan(ctc_disturb_eval(&z, NAN)), "a NaN time gives NaN");

    /* a step at a negative time is on for t >= 0 */
    ctc_disturb early = step(2.0, -1.0);
    cr_assert_eq(ctc_disturb_eval(&early, 0.0), 2.0);
    cr_assert_eq(ctc_disturb_eval(&early, -1.0), 2.0);
    cr_assert_eq(ctc_disturb_eval(&early, -1.5), 0.0);
}

Test(disturb, breakpoint_is_the_step_time)
{
    const double times[4] = {0.0, 2.5, -4.0, 1e-9};
    for (int i = 0; i < 4; i++) {
        ctc_disturb z = step(1.0, times[i]);
        cr_assert_eq(ctc_disturb_breakpoint(&z), times[i]);
        /* the jump happens exactly there */
        cr_assert_eq(ctc_disturb_eval(&z, nextafter(times[i], -INFINITY)), 0.0);
        cr_assert_eq(ctc_disturb_eval(&z, ctc_disturb_breakpoint(&z)), 1.0);
    }
}

/* ---- invalid arguments ---- */

static void expect_check_error(ctc_disturb z, const char *want)
{
    char err[128];
    ctc_status st = ctc_disturb_check(&z, err, sizeof err);
    cr_assert_eq(st, CTC_EINVAL, "status %s for \"%s\"", ctc_status_name(st), want);
    cr_assert_str_eq(err, want);
}

Test(disturb, check_rejects_invalid_parameters_with_exact_messages)
{
    char err[128];
    cr_assert_eq(ctc_disturb_check(NULL, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "disturbance is NULL");
    expect_check_error((ctc_disturb){.type = (ctc_disturb_type)9}, "unknown disturbance type 9");
    expect_check_error((ctc_disturb){.type = CTC_DISTURB_CONSTANT, .value = INFINITY},
                       "constant: value must be finite (got inf)");

    expect_check_error(sine(1, 0, 0, 0), "sine: period must be positive and finite (got 0 s)");
    expect_check_error(sine(1, -2, 0, 0), "sine: period must be positive and finite (got -2 s)");
    expect_check_error(sine(1, NAN, 0, 0), "sine: period must be positive and finite (got nan s)");
    expect_check_error(sine(1, INFINITY, 0, 0),
                       "sine: period must be positive and finite (got inf s)");
    expect_check_error(sine(NAN, 1, 0, 0), "sine: amplitude must be finite (got nan)");
    expect_check_error(sine(1, 1, INFINITY, 0), "sine: phase must be finite (got inf rad)");
    expect_check_error(sine(1, 1, 0, -INFINITY), "sine: offset must be finite (got -inf)");
    expect_check_error(sine(-1e308, 1, 0, -1e308), "sine: offset + amplitude overflows");
    expect_check_error(sine(1, 1e-310, 0, 0),
                       "sine: period 1e-310 s is too short (2 pi / period overflows)");

    expect_check_error(step(NAN, 1), "step: value must be finite (got nan)");
    expect_check_error(step(1, -INFINITY), "step: time must be finite (got -inf s)");

    /* a none ignores its other fields */
    cr_assert_eq(
        ctc_disturb_check(&(ctc_disturb){.type = CTC_DISTURB_NONE, .value = NAN}, err, sizeof err),
        CTC_OK);
}

Test(disturb, error_buffer_may_be_null_or_short)
{
    ctc_disturb z = step(1, NAN);
    char err[6];
    memset(err, 'x', sizeof err);
    cr_assert_eq(ctc_disturb_check(&z, NULL, 0), CTC_EINVAL);
    cr_assert_eq(ctc_disturb_check(&z, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "step:");
}

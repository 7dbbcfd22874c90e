/*
 * test_model_error.c - the controller's model apart from the plant (job_model.c, sim.h
 * model_bodies and model_gravity): per-body values, an unknown payload, a gravity error and
 * seeded random draws, through the job format and a run.
 *
 * Closed forms. With the model equal to the plant, PD with kp = 100, kv = 20 (critically damped,
 * double pole at -10) makes e(t) = (e0 + (de0 + 10 e0) t) exp(-10 t) whatever the chain. A rod
 * held by PD at q_d with a model that lacks a point mass m_p at distance l_p from the pivot, or
 * whose gravity is g' instead of g, comes to rest where the model's torque meets the plant's
 * gravity: I_hat kp e = m_p g l_p sin q, or I_hat kp e = m (g - g') d sin q (d the pivot to the
 * rod's centre of mass, I_hat the model's inertia about the pivot), solved by Newton here.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_json.h"
#include "sim.h"
#include "job_fixture.h"

#define G 9.81
#define PI 3.14159265358979323846

Test(model_error, model_equal_to_the_plant_tracks_as_the_closed_form)
{
    job *j = fixture_parse_ok(
        "{'scene':{'gravity':[0,-9.81,0],'bodies':[" FIXTURE_ROD "," FIXTURE_ROD2 "]},"
        "'controller':{'type':'pd','kp':100,'kv':20,'model':{'gravity':[0,-9.81,0],'bodies':["
        "{'body':0,'mass':1,'com':[0,-0.5,0],'inertia':[0.0833333333333333,0.0833333333333333,"
        "0.0833333333333333]},{'body':1,'mass_scale':1,'inertia_scale':1}]}},"
        "'trajectory':{'type':'sine','amplitude':0.6,'period':1.5},'duration':2," FIXTURE_INTEG
        "}");
    cr_assert_not_null(j->spec.model_bodies, "a model of its own");
    cr_assert_not_null(j->spec.model_gravity);
    ctc_sim_result *r = fixture_run_done(&j->spec);
    const double de0 = 0.6 * 2 * PI / 1.5;
    double dev = 0;
    for (int k = 0; k < r->nsamples; k++) {
        double t = r->t[k];
        for (int i = 0; i < 2; i++) {
            double e0 = -j->q0[i];
            double e = (e0 + (de0 + 10 * e0) * t) * exp(-10 * t);
            dev = fmax(dev, fabs(r->ch[CTC_CH_E][2 * k + i] - e));
        }
    }
    cr_expect_leq(dev, 1e-8, "|e - closed form| = %g", dev);
    ctc_sim_result_free(r);
    job_free(j);
}

/* Newton on I kp (q_d - q) = c sin q, from q_d */
static double rest_angle(double inertia, double kp, double c, double q_d)
{
    double q = q_d;
    for (int it = 0; it < 50; it++) {
        double f = inertia * kp * (q_d - q) - c * sin(q);
        double df = -inertia * kp - c * cos(q);
        q -= f / df;
    }
    return q;
}

Test(model_error, payload_gives_the_closed_form_steady_error_of_pd)
{
    const double q_d = 1.0, mp = 0.5, lp = 1.0, ip = 1.0 / 3;
    job *j = fixture_parse_ok(
        "{'scene':{'gravity':[0,-9.81,0],'bodies':[" FIXTURE_ROD "],'q0':[1]},"
        "'controller':{'type':'pd','kp':100,'kv':20,'model':{'payload':{'body':0,"
        "'mass':0.5,'point':[0,-1,0]}}},"
        "'trajectory':{'type':'constant','value':1},'duration':8," FIXTURE_INTEG "}");
    cr_expect_eq(j->bodies[0].mass, 1.5, "the plant carries the payload");
    cr_expect_eq(j->spec.model_bodies[0].mass, 1, "the model does not");
    ctc_sim_result *r = fixture_run_done(&j->spec);
    const double q = rest_angle(ip, 100, mp * G * lp, q_d);
    cr_expect_leq(fabs(r->metrics.e_final[0] - (q_d - q)), 1e-9, "e = %.12g, closed form %.12g",
                  r->metrics.e_final[0], q_d - q);
    cr_expect_gt(q_d - q, 0.05, "a payload of 0.5 kg sags the rod");
    ctc_sim_result_free(r);
    job_free(j);
}

Test(model_error, gravity_error_gives_the_closed_form_steady_error_of_pd)
{
    const double q_d = 1.0, ip = 1.0 / 3, g_model = 9.0;
    job *j = fixture_parse_ok(
        "{'scene':{'gravity':[0,-9.81,0],'bodies':[" FIXTURE_ROD "],'q0':[1]},"
        "'controller':{'type':'pd','kp':100,'kv':20,'model':{'gravity':[0,-9,0]}},"
        "'trajectory':{'type':'constant','value':1},'duration':8," FIXTURE_INTEG "}");
    ctc_sim_result *r = fixture_run_done(&j->spec);
    const double q = rest_angle(ip, 100, 1 * (G - g_model) * 0.5, q_d);
    cr_expect_leq(fabs(r->metrics.e_final[0] - (q_d - q)), 1e-9, "e = %.12g, closed form %.12g",
                  r->metrics.e_final[0], q_d - q);
    ctc_sim_result_free(r);
    job_free(j);
}

#define RANDOM_JOB(random)                                                                         \
    "{'scene':{'bodies':[" FIXTURE_ROD "," FIXTURE_ROD2                                            \
    "]},'controller':{'type':'pd','kp':100,'kv':20,"                                               \
    "'model':{'random':" random "}},'trajectory':{'type':'constant','value':0},'duration':0.1}"

Test(model_error, random_draws_are_seeded_bounded_and_round_trip)
{
    job *a = fixture_parse_ok(RANDOM_JOB("{'seed':7,'mass':0.2,'com':0.01,'inertia':0.3}"));
    job *b = fixture_parse_ok(RANDOM_JOB("{'seed':7,'mass':0.2,'com':0.01,'inertia':0.3}"));
    job *c = fixture_parse_ok(RANDOM_JOB("{'seed':8,'mass':0.2,'com':0.01,'inertia':0.3}"));
    job *z = fixture_parse_ok(RANDOM_JOB("{'seed':7}"));
    const size_t size = 2 * sizeof(ctc_body_spec);
    cr_expect(memcmp(a->spec.model_bodies, b->spec.model_bodies, size) == 0, "same seed");
    cr_expect(memcmp(a->spec.model_bodies, c->spec.model_bodies, size) != 0, "another seed");
    cr_expect(memcmp(z->spec.model_bodies, z->bodies, size) == 0, "no ranges: the plant's");
    for (int k = 0; k < 2; k++) {
        const ctc_body_spec *m = &a->spec.model_bodies[k], *p = &a->bodies[k];
        cr_expect(fabs(m->mass / p->mass - 1) <= 0.2 && m->mass != p->mass, "body %d mass", k);
        cr_expect(fabs(m->inertia[8] / p->inertia[8] - 1) <= 0.3, "body %d inertia", k);
        for (int i = 0; i < 3; i++) cr_expect(fabs(m->com[i] - p->com[i]) <= 0.01);
    }
    /* the normalised job gives the same model */
    char *text = cJSON_PrintUnformatted(a->normalised);
    job *n = NULL;
    job_error err;
    cr_assert_eq(job_parse(text, strlen(text), &n, &err), 0, "%s: %s", err.field, err.message);
    cr_expect(memcmp(a->spec.model_bodies, n->spec.model_bodies, size) == 0, "round trip");
    free(text);
    job_free(n);
    job_free(a);
    job_free(b);
    job_free(c);
    job_free(z);
}

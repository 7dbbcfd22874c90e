/*
 * sim_check.c - the checks of a simulation spec (sim.h ctc_sim_check; sim_internal.h): those that
 * need no model, those of the per-coordinate arrays against the built model (the controller
 * class's gains and their stability, trajectories, disturbances, the plant's terms), and the
 * initial state put onto a loop's closure (loop.h ctc_loop_assemble).
 *
 * Every message names the item and the value ("duration must be positive and finite (got -1 s)",
 * "coordinate 2: gains (...) make the error dynamics unstable (pole at 0.5)"). Gains are checked
 * by Routh-Hurwitz on s^3 + kv s^2 + kp s + ki (s^2 + kv s + kp for PD, ctrl.h) for every class
 * whose law is the linear feedback (its closed_loop hook); a class of the caller's own without
 * that hook gets its gains, if any, as given.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim_internal.h"

unsigned sim_channels_applicable(int active)
{
    unsigned all =
        CTC_CH_ALL & ~CTC_CH_BIT(CTC_CH_LOOP) & ~CTC_CH_BIT(CTC_CH_EE) & ~CTC_CH_BIT(CTC_CH_POSE);
    if (!active)
        all &= ~(CTC_CH_BIT(CTC_CH_Q_DES) | CTC_CH_BIT(CTC_CH_QD_DES) | CTC_CH_BIT(CTC_CH_E) |
                 CTC_CH_BIT(CTC_CH_W));
    return all;
}

const ctc_ctrl_class *sim_ctrl_class(const ctc_sim_spec *s)
{
    return s->ctrl_class ? s->ctrl_class : ctc_ctrl_class_of(s->controller);
}

/* the external wrenches (wrench.h): their bodies, values and profiles */
static ctc_status check_wrenches(const ctc_sim_spec *s, int active, char *err, size_t errlen)
{
    if (s->nwrenches < 0 || (s->nwrenches > 0 && !s->wrenches))
        return ctc_fail(CTC_EINVAL, err, errlen, "%d wrenches given without their array",
                        s->nwrenches);
    for (int k = 0; k < s->nwrenches; k++) {
        const ctc_wrench *w = &s->wrenches[k];
        if (w->body < 0 || w->body >= s->chain.nbodies)
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "wrench %d: body %d out of range (the chain has %d bodies)", k, w->body,
                            s->chain.nbodies);
        for (int i = 0; i < 3; i++)
            if (!isfinite(w->point[i]) || !isfinite(w->force[i]) || !isfinite(w->torque[i]))
                return ctc_fail(CTC_EINVAL, err, errlen,
                                "wrench %d: point, force and torque must be finite", k);
        if ((unsigned)w->frame > CTC_WRENCH_BODY)
            return ctc_fail(CTC_EINVAL, err, errlen, "wrench %d: unknown frame %d", k,
                            (int)w->frame);
        if ((unsigned)w->profile > CTC_WRENCH_STEP)
            return ctc_fail(CTC_EINVAL, err, errlen, "wrench %d: unknown profile %d", k,
                            (int)w->profile);
        if (w->profile == CTC_WRENCH_SINE && (!isfinite(w->period) || !(w->period > 0)))
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "wrench %d: sine period must be positive and finite (got %g s)", k,
                            w->period);
        if (w->profile == CTC_WRENCH_SINE && !isfinite(w->phase))
            return ctc_fail(CTC_EINVAL, err, errlen, "wrench %d: phase must be finite (got %g)", k,
                            w->phase);
        if (w->profile == CTC_WRENCH_STEP && (!isfinite(w->time) || !(w->time >= 0)))
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "wrench %d: step time must be >= 0 and finite (got %g s)", k, w->time);
        if (w->known && !active)
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "wrench %d: a known wrench needs a controller (this run is passive)",
                            k);
    }
    return CTC_OK;
}

ctc_status sim_check_run(const ctc_sim_spec *s, char *err, size_t errlen)
{
    if (!isfinite(s->duration) || s->duration <= 0)
        return ctc_fail(CTC_EINVAL, err, errlen, "duration must be positive and finite (got %g s)",
                        s->duration);
    if (!isfinite(s->output_interval) || s->output_interval <= 0)
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "output interval must be positive and finite (got %g s)",
                        s->output_interval);
    if (s->output_interval > s->duration)
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "output interval (%g s) must not exceed the duration (%g s)",
                        s->output_interval, s->duration);
    if (sim_sample_count(s->duration, s->output_interval) > SIM_MAX_SAMPLES)
        return ctc_fail(CTC_EINVAL, err, errlen, "more than %ld output samples", SIM_MAX_SAMPLES);
    if (!(s->max_speed >= 0) || isinf(s->max_speed))
        return ctc_fail(CTC_EINVAL, err, errlen, "max_speed must be >= 0 and finite (got %g)",
                        s->max_speed);
    if (!(s->wall_limit >= 0) || isinf(s->wall_limit))
        return ctc_fail(CTC_EINVAL, err, errlen, "wall_limit must be >= 0 and finite (got %g s)",
                        s->wall_limit);
    if (s->threads < 0 || s->threads > CTC_MAX_THREADS)
        return ctc_fail(CTC_EINVAL, err, errlen, "threads must be 0 to %d (got %d)",
                        CTC_MAX_THREADS, s->threads);
    const ctc_ctrl_class *cls = sim_ctrl_class(s);
    if (!cls)
        return ctc_fail(CTC_EINVAL, err, errlen, "unknown controller type %d", (int)s->controller);
    if (!cls->name) return ctc_fail(CTC_EINVAL, err, errlen, "the controller class has no name");
    if (cls->nstate != 0 && cls->nstate != 1)
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "controller \"%s\": state size must be 0 or 1 per coordinate (got %d)",
                        cls->name, cls->nstate);
    if (cls->closed_loop && (cls->nstate != 1 || !cls->law))
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "controller \"%s\": a closed-loop matrix needs a law and the integral "
                        "state (nstate 1)",
                        cls->name);
    const int active = cls->law != NULL;
    if (!(s->sample_period >= 0) || isinf(s->sample_period))
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "sample_period must be >= 0 and finite (got %g s; 0 = continuous)",
                        s->sample_period);
    if (s->sample_delay < 0 || s->sample_delay > CTC_SIM_MAX_DELAY)
        return ctc_fail(CTC_EINVAL, err, errlen, "sample_delay must be 0 to %d samples (got %d)",
                        CTC_SIM_MAX_DELAY, s->sample_delay);
    if (s->sample_delay > 0 && s->sample_period == 0)
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "sample_delay needs a sample_period (a continuous controller has no "
                        "samples to delay)");
    if (s->sample_period > 0 && !active)
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "sample_period needs a controller (this run is passive)");
    unsigned bad = s->channels & ~sim_channels_applicable(active) & ~CTC_CH_BIT(CTC_CH_LOOP) &
                   ~CTC_CH_BIT(CTC_CH_EE) & ~CTC_CH_BIT(CTC_CH_POSE);
    if ((s->channels & CTC_CH_BIT(CTC_CH_EE)) && !s->end_effector)
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "channel \"end_effector\" needs the end effector's body and point");
    if (s->end_effector) {
        const ctc_end_effector *ee = s->end_effector;
        if (ee->body < 0 || ee->body >= s->chain.nbodies)
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "end effector body %d out of range (the chain has %d bodies)", ee->body,
                            s->chain.nbodies);
        for (int i = 0; i < 3; i++)
            if (!isfinite(ee->point[i]))
                return ctc_fail(CTC_EINVAL, err, errlen,
                                "end effector point[%d] must be finite (got %g)", i, ee->point[i]);
    }
    if ((s->channels & CTC_CH_BIT(CTC_CH_POSE)) && s->npose == 0)
        return ctc_fail(CTC_EINVAL, err, errlen, "channel \"body_pose\" needs a list of bodies");
    if (s->npose < 0 || (s->npose > 0 && !s->pose_bodies))
        return ctc_fail(CTC_EINVAL, err, errlen, "body_pose: %d bodies given without their list",
                        s->npose);
    for (int i = 0; i < s->npose; i++)
        if (s->pose_bodies[i] < 0 || s->pose_bodies[i] >= s->chain.nbodies)
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "body_pose body %d out of range (the chain has %d bodies)",
                            s->pose_bodies[i], s->chain.nbodies);
    ctc_status wst = check_wrenches(s, active, err, errlen);
    if (wst != CTC_OK) return wst;
    if (s->channels & ~CTC_CH_ALL)
        return ctc_fail(CTC_EINVAL, err, errlen, "unknown output channel bits 0x%x",
                        s->channels & ~CTC_CH_ALL);
    for (int c = 0; c < CTC_NCHANNELS; c++)
        if (bad & CTC_CH_BIT(c))
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "channel \"%s\" needs a controller (this run is passive)",
                            ctc_channel_name((ctc_channel)c));
    if (active && (!isfinite(s->model_mass_scale) || s->model_mass_scale <= 0))
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "model mass scale must be positive and finite (got %g)",
                        s->model_mass_scale);
    if (active && (!isfinite(s->model_inertia_scale) || s->model_inertia_scale <= 0))
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "model inertia scale must be positive and finite (got %g)",
                        s->model_inertia_scale);
    for (int i = 0; active && s->model_gravity && i < 3; i++)
        if (!isfinite(s->model_gravity[i]))
            return ctc_fail(CTC_EINVAL, err, errlen, "model gravity[%d] must be finite (got %g)", i,
                            s->model_gravity[i]);
    if ((unsigned)s->loop_stab > CTC_LOOP_NONE)
        return ctc_fail(CTC_EINVAL, err, errlen, "unknown loop stabilisation %d",
                        (int)s->loop_stab);
    if (!(s->loop_tol >= 0) || isinf(s->loop_tol))
        return ctc_fail(CTC_EINVAL, err, errlen, "loop tolerance must be >= 0 and finite (got %g)",
                        s->loop_tol);
    for (int i = 0; i < 2; i++)
        if (!(s->baumgarte[i] >= 0) || isinf(s->baumgarte[i]))
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "Baumgarte gains must be >= 0 and finite (got %g)", s->baumgarte[i]);
    if (!(s->loop_cond_max == 0 || s->loop_cond_max > 1) || isinf(s->loop_cond_max))
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "loop condition limit must be > 1 and finite, or 0 (got %g)",
                        s->loop_cond_max);
    return ctc_integ_check(&s->integrator, err, errlen);
}

/* Routh-Hurwitz for s^3 + kv s^2 + kp s + ki, or s^2 + kv s + kp for PD (ctrl.h) */
static int gains_stable(const ctc_gains *g)
{
    if (g->ki == 0) return g->kp > 0 && g->kv > 0;
    return g->ki > 0 && g->kp > 0 && g->kv > 0 && g->kv * g->kp > g->ki;
}

/* the checks of the arrays against a built model */
ctc_status sim_check_with_model(const ctc_sim_spec *s, const ctc_model *m, char *err, size_t errlen)
{
    const ctc_ctrl_class *cls = sim_ctrl_class(s);
    const int active = cls && cls->law;
    char why[200];
    for (int i = 0; s->q0 && i < m->nq; i++)
        if (!isfinite(s->q0[i]))
            return ctc_fail(CTC_EINVAL, err, errlen, "q0[%d] is not finite", i);
    for (int i = 0; s->v0 && i < m->nv; i++)
        if (!isfinite(s->v0[i]))
            return ctc_fail(CTC_EINVAL, err, errlen, "v0[%d] is not finite", i);
    if (s->nwrenches > 0 && m->has_loop)
        return ctc_fail(CTC_EINVAL, err, errlen, "external wrenches need an open chain or tree");
    if ((s->channels & CTC_CH_BIT(CTC_CH_LOOP)) && !m->has_loop)
        return ctc_fail(CTC_EINVAL, err, errlen, "channel \"loop\" needs a loop in the scene");
    if (active) {
        for (int k = 0; k < m->njoints; k++)
            if (ctc_joint_classes[m->joints[k].type].undriven != NULL && m->jnt_indep[k])
                return ctc_fail(CTC_EINVAL, err, errlen,
                                "joint %d: %s joints are allowed in passive runs only "
                                "(controller \"none\")%s",
                                k, ctc_joint_type_name(m->joints[k].type),
                                m->has_loop ? ", or as dependent joints of a loop" : "");
        if (m->nind == 0)
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "a controller needs at least one independent coordinate");
        const int linear = cls->closed_loop != NULL;
        if ((linear && !s->gains) || !s->traj)
            return ctc_fail(CTC_EINVAL, err, errlen,
                            linear ? "a controller needs gains and a trajectory for every "
                                     "coordinate"
                                   : "a controller needs a trajectory for every coordinate");
        for (int i = 0; i < m->nind; i++) {
            const ctc_gains *g = s->gains ? &s->gains[i] : NULL;
            if (g && (!isfinite(g->ki) || !isfinite(g->kp) || !isfinite(g->kv)))
                return ctc_fail(CTC_EINVAL, err, errlen, "coordinate %d: gains are not finite", i);
            if (linear && !gains_stable(g)) {
                double re[3], im[3];
                ctc_ctrl_closed_loop_poles(g, re, im);
                int j = re[2] >= re[1] && re[2] >= re[0] ? 2 : re[1] >= re[0] ? 1 : 0;
                char pole[64];
                if (fabs(im[j]) > 1e-12 * fabs(re[j]))
                    snprintf(pole, sizeof pole, "%g%+gi", re[j], im[j]);
                else
                    snprintf(pole, sizeof pole, "%g", re[j]);
                return ctc_fail(CTC_EINVAL, err, errlen,
                                "coordinate %d: gains (ki %g, kp %g, kv %g) make the error "
                                "dynamics unstable (pole at %s)",
                                i, g->ki, g->kp, g->kv, pole);
            }
            if (s->traj[i].type == CTC_TRAJ_SPLINE) {
                if (s->traj[i].nknots < 2 || !s->traj[i].knots)
                    return ctc_fail(CTC_EINVAL, err, errlen,
                                    "coordinate %d: trajectory spline is not built", i);
            } else if (ctc_traj_check(&s->traj[i], why, sizeof why) != CTC_OK) {
                return ctc_fail(CTC_EINVAL, err, errlen, "coordinate %d: trajectory: %s", i, why);
            }
        }
    }
    for (int i = 0; s->disturb && i < m->nind; i++)
        if (ctc_disturb_check(&s->disturb[i], why, sizeof why) != CTC_OK)
            return ctc_fail(CTC_EINVAL, err, errlen, "coordinate %d: disturbance: %s", i, why);
    if (active && cls->force != CTC_FORCE_COMPUTED_TORQUE && m->has_loop)
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "controller \"%s\" needs an open chain (its model's desired or resting "
                        "state is not defined for the loop's dependent joints)",
                        cls->name);
    if ((unsigned)cls->force > CTC_FORCE_FEEDFORWARD)
        return ctc_fail(CTC_EINVAL, err, errlen, "controller \"%s\": unknown force mode %d",
                        cls->name, (int)cls->force);
    for (int i = 0; s->plant && i < m->nind; i++) {
        double lim = s->plant[i].torque_limit;
        if (!(lim >= 0) || isinf(lim))
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "coordinate %d: torque_limit must be positive and finite, or 0 for "
                            "none (got %g)",
                            i, lim);
        const ctc_plant_coord *pc = &s->plant[i];
        const struct {
            const char *name;
            double x;
        } nonneg[] = {{"viscous", pc->viscous},
                      {"coulomb", pc->coulomb},
                      {"spring", pc->spring},
                      {"armature", pc->armature}};
        for (int k = 0; k < 4; k++)
            if (!(nonneg[k].x >= 0) || isinf(nonneg[k].x))
                return ctc_fail(CTC_EINVAL, err, errlen,
                                "coordinate %d: %s must be non-negative and finite (got %g)", i,
                                nonneg[k].name, nonneg[k].x);
        if (pc->coulomb > 0 && (!(pc->coulomb_velocity > 0) || isinf(pc->coulomb_velocity)))
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "coordinate %d: coulomb_velocity must be positive and finite with "
                            "coulomb friction (got %g)",
                            i, pc->coulomb_velocity);
        const struct {
            const char *name;
            double x;
        } sensor[] = {
            {"noise_q", pc->noise_q}, {"noise_v", pc->noise_v}, {"resolution", pc->resolution}};
        for (int k = 0; k < 3; k++) {
            if (!(sensor[k].x >= 0) || isinf(sensor[k].x))
                return ctc_fail(CTC_EINVAL, err, errlen,
                                "coordinate %d: %s must be non-negative and finite (got %g)", i,
                                sensor[k].name, sensor[k].x);
            if (sensor[k].x > 0 && !(s->sample_period > 0 && active))
                return ctc_fail(CTC_EINVAL, err, errlen,
                                "coordinate %d: %s needs a sampled controller (sample_period)", i,
                                sensor[k].name);
            if (sensor[k].x > 0 && m->has_loop)
                return ctc_fail(CTC_EINVAL, err, errlen, "coordinate %d: %s needs an open chain", i,
                                sensor[k].name);
        }
        if (pc->armature > 0 && m->has_loop)
            return ctc_fail(CTC_EINVAL, err, errlen, "coordinate %d: armature needs an open chain",
                            i);
        if (!isfinite(pc->spring_rest))
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "coordinate %d: spring_rest must be finite (got %g)", i,
                            pc->spring_rest);
        if (lim > 0 && !active)
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "coordinate %d: torque_limit needs a controller (this run is passive)",
                            i);
    }
    return CTC_OK;
}

/* the projection's trigger and Newton's tolerance (m, rad) */
double sim_loop_tol(const ctc_sim_spec *s)
{
    return s->loop_tol > 0 ? s->loop_tol : CTC_SIM_DEFAULT_LOOP_TOL;
}

/* The spec's initial state (q0 normalised, v0) in q (nq) and v (nv), put onto the loop's closure
 * and checked there (loop.h). A closure that fails is explained by the mobility checks at q0
 * when they fail too. */
ctc_status sim_close_initial_state(const ctc_sim_spec *s, const ctc_model *m, ctc_data *d,
                                   double *q, double *v, ctc_loop_fix *fix, char *err,
                                   size_t errlen)
{
    if (s->q0)
        memcpy(q, s->q0, (size_t)m->nq * sizeof *q);
    else
        ctc_model_q_zero(m, q);
    ctc_model_q_normalize(m, q);
    for (int i = 0; i < m->nv; i++) v[i] = s->v0 ? s->v0[i] : 0;
    if (!m->has_loop) return CTC_OK;

    double tol = sim_loop_tol(s);
    char why[300];
    if (ctc_loop_assemble(m, d, q, v, tol, SIM_LOOP_MAX_ITER, fix, why, sizeof why) != CTC_OK) {
        double *q0 = malloc(((size_t)m->nq + 1) * sizeof *q0);
        if (!q0) return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
        if (s->q0)
            memcpy(q0, s->q0, (size_t)m->nq * sizeof *q0);
        else
            ctc_model_q_zero(m, q0);
        ctc_model_q_normalize(m, q0);
        ctc_status st = ctc_loop_check(m, d, q0, NULL, err, errlen);
        free(q0);
        if (st != CTC_OK) return st;
        return ctc_fail(CTC_EINVAL, err, errlen, "q0: %s", why);
    }
    return ctc_loop_check(m, d, q, NULL, err, errlen);
}

ctc_status ctc_sim_check(const ctc_sim_spec *spec, char *err, size_t errlen)
{
    ctc_status st = sim_check_run(spec, err, errlen);
    if (st != CTC_OK) return st;
    ctc_model *m = NULL;
    st = ctc_model_build(&spec->chain, &m, err, errlen);
    if (st != CTC_OK) return st;
    st = sim_check_with_model(spec, m, err, errlen);
    if (st == CTC_OK && m->has_loop) {
        ctc_data *d = ctc_data_new(m);
        double *qv = malloc(((size_t)m->nq + (size_t)m->nv + 1) * sizeof *qv);
        if (!d || !qv) {
            st = ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
        } else {
            ctc_loop_fix fix;
            st = sim_close_initial_state(spec, m, d, qv, qv + m->nq, &fix, err, errlen);
        }
        free(qv);
        ctc_data_free(d);
    }
    ctc_model_free(m);
    return st;
}

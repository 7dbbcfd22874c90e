/*
 * result_out.c - metrics as JSON and series as CSV or columnar JSON (result_out.h).
 *
 * The series are streamed straight to the file, a number at a time, so a large run never needs a
 * second copy in memory; only the small metrics and spec objects go through cJSON.
 */
#include "result_out.h"

#include <math.h>
#include <string.h>

static const char *const energy_parts[2] = {"kinetic", "potential"};
static const char *const loop_parts[2] = {"position", "velocity"};
static const char *const ee_parts[6] = {"x", "y", "z", "vx", "vy", "vz"};
static const char *const pose_parts[7] = {"x", "y", "z", "qw", "qx", "qy", "qz"};

static cJSON *number_or_null(double x)
{
    return isfinite(x) ? cJSON_CreateNumber(x) : cJSON_CreateNull();
}

static cJSON *array_or_null(const double *x, int n)
{
    if (!x) return cJSON_CreateNull();
    cJSON *a = cJSON_CreateArray();
    for (int i = 0; a && i < n; i++) cJSON_AddItemToArray(a, number_or_null(x[i]));
    return a;
}

/* [{"joint": k, "coordinate": c}, ...]: the controlled coordinates of j in joint order, each
 * with its joint (n: the closing joint) and its index in qdot (the closing joint's: nv on) */
static cJSON *coordinates_json(const job *j)
{
    const ctc_chain_spec *chain = &j->spec.chain;
    int n = chain->nbodies, vadr = 0;
    cJSON *a = cJSON_CreateArray();
    for (int k = 0; a && k <= n; k++) {
        if (k == n && !chain->loop) break;
        ctc_joint_type type = k < n ? chain->joints[k].type : chain->loop->joint.type;
        int nv = ctc_joint_nv(type);
        if (!chain->independent || chain->independent[k]) {
            for (int i = 0; i < nv; i++) {
                cJSON *e = cJSON_CreateObject();
                cJSON_AddNumberToObject(e, "joint", k);
                cJSON_AddNumberToObject(e, "coordinate", vadr + i);
                cJSON_AddItemToArray(a, e);
            }
        }
        vadr += nv;
    }
    return a;
}

/* the loop's figures (sim.h): residuals, condition, projections, the initial correction */
static cJSON *loop_json(const ctc_sim_metrics *m)
{
    cJSON *o = cJSON_CreateObject();
    if (!o) return NULL;
    cJSON_AddItemToObject(o, "residual_max", number_or_null(m->loop_res_max));
    cJSON_AddItemToObject(o, "velocity_residual_max", number_or_null(m->loop_vres_max));
    cJSON_AddItemToObject(o, "cond_max", number_or_null(m->loop_cond_max));
    cJSON_AddNumberToObject(o, "projections", (double)m->projections);
    cJSON *init = cJSON_AddObjectToObject(o, "initial");
    cJSON_AddNumberToObject(init, "iterations", m->initial.iterations);
    cJSON_AddItemToObject(init, "dq_max", number_or_null(m->initial.dq_max));
    cJSON_AddItemToObject(init, "dv_max", number_or_null(m->initial.dv_max));
    cJSON_AddItemToObject(init, "residual_before", number_or_null(m->initial.res_before));
    cJSON_AddItemToObject(init, "residual_after", number_or_null(m->initial.res_after));
    cJSON_AddItemToObject(init, "velocity_residual_before", number_or_null(m->initial.vres_before));
    cJSON_AddItemToObject(init, "velocity_residual_after", number_or_null(m->initial.vres_after));
    return o;
}

/* {"sampling": [nv], "noise": [nv], "model": [nv], "total": [nv]} (sim.h CTC_CAUSE_*), or null
 * when passive */
static cJSON *error_by_cause_json(const ctc_sim_metrics *m)
{
    static const char *const names[CTC_NCAUSES] = {"sampling", "noise", "model", "total"};
    if (!m->err_cause) return cJSON_CreateNull();
    cJSON *o = cJSON_CreateObject();
    for (int c = 0; o && c < CTC_NCAUSES; c++)
        cJSON_AddItemToObject(o, names[c], array_or_null(m->err_cause + (size_t)c * m->nv, m->nv));
    return o;
}

cJSON *result_metrics_json(const ctc_sim_result *r, const job *j)
{
    const ctc_sim_metrics *m = &r->metrics;
    cJSON *o = cJSON_CreateObject();
    if (!o) return NULL;
    cJSON_AddStringToObject(o, "status", ctc_run_status_name(r->status));
    cJSON_AddStringToObject(o, "message", r->message);
    cJSON_AddStringToObject(o, "form", ctc_form_name(m->form));
    cJSON_AddNumberToObject(o, "nq", r->nq);
    cJSON_AddNumberToObject(o, "nv", r->nv);
    cJSON_AddNumberToObject(o, "nind", r->nind);
    if (j) cJSON_AddItemToObject(o, "coordinates", coordinates_json(j));
    cJSON_AddNumberToObject(o, "samples", r->nsamples);
    cJSON_AddNumberToObject(o, "t_end", m->t_end);
    cJSON_AddItemToObject(o, "e_max", array_or_null(m->e_max, m->nv));
    cJSON_AddItemToObject(o, "e_rms", array_or_null(m->e_rms, m->nv));
    cJSON_AddItemToObject(o, "e_final", array_or_null(m->e_final, m->nv));
    cJSON_AddItemToObject(o, "tau_peak", array_or_null(m->tau_peak, m->nv));
    cJSON_AddItemToObject(o, "tau_rms", array_or_null(m->tau_rms, m->nv));
    cJSON_AddItemToObject(o, "sat_fraction", array_or_null(m->sat_fraction, m->nv));
    cJSON_AddItemToObject(o, "error_by_cause", error_by_cause_json(m));
    cJSON_AddItemToObject(o, "errdyn_dev", number_or_null(m->errdyn_dev));
    cJSON_AddItemToObject(o, "energy_drift", number_or_null(m->energy_drift));
    cJSON_AddItemToObject(o, "err_estimate", number_or_null(m->err_estimate));
    if (isnan(m->accel_rounding)) {
        cJSON_AddNullToObject(o, "tolerance_floor");
    } else {
        cJSON *fl = cJSON_AddObjectToObject(o, "tolerance_floor");
        cJSON_AddItemToObject(fl, "accel_rounding", number_or_null(m->accel_rounding));
        cJSON_AddItemToObject(fl, "rtol", number_or_null(m->tol_rtol));
        cJSON_AddItemToObject(fl, "atol", number_or_null(m->tol_atol));
        cJSON_AddBoolToObject(fl, "raised", m->tol_floored != 0);
        cJSON_AddStringToObject(fl, "reason", m->tol_reason);
    }
    cJSON_AddNumberToObject(o, "steps", (double)m->steps);
    cJSON_AddNumberToObject(o, "rejected", (double)m->rejected);
    cJSON_AddNumberToObject(o, "rhs_evals", (double)m->rhs_evals);
    cJSON_AddNumberToObject(o, "wall_s", m->wall_s);
    cJSON_AddNumberToObject(o, "cpu_s", m->cpu_s);
    cJSON_AddNumberToObject(o, "us_per_eval", m->us_per_eval);
    /* rk4's step cut to divide the output interval: what was asked and what ran */
    if (j && isfinite(m->step_used) && m->step_used < j->spec.integrator.step * (1 - 1e-9)) {
        cJSON *cut = cJSON_AddObjectToObject(o, "step_cut");
        cJSON_AddNumberToObject(cut, "asked", j->spec.integrator.step);
        cJSON_AddNumberToObject(cut, "used", m->step_used);
    } else {
        cJSON_AddNullToObject(o, "step_cut");
    }
    if (m->diverged_joint >= 0)
        cJSON_AddNumberToObject(o, "diverged_joint", m->diverged_joint);
    else
        cJSON_AddNullToObject(o, "diverged_joint");
    if (j ? j->spec.chain.loop != NULL : !isnan(m->loop_res_max))
        cJSON_AddItemToObject(o, "loop", loop_json(m));
    if (j && j->gains) {
        cJSON *g = cJSON_AddArrayToObject(o, "gains");
        for (int i = 0; g && i < j->nind; i++) {
            cJSON *e = cJSON_CreateObject();
            cJSON_AddNumberToObject(e, "ki", j->gains[i].ki);
            cJSON_AddNumberToObject(e, "kp", j->gains[i].kp);
            cJSON_AddNumberToObject(e, "kv", j->gains[i].kv);
            cJSON_AddItemToArray(g, e);
        }
    }
    return o;
}

int result_parse_channels(const char *list, unsigned *out, char *bad, size_t badlen)
{
    unsigned mask = 0;
    const char *p = list;
    while (*p) {
        size_t len = strcspn(p, ",");
        int found = -1;
        for (int c = 0; c < CTC_NCHANNELS; c++) {
            const char *name = ctc_channel_name((ctc_channel)c);
            if (strlen(name) == len && strncmp(name, p, len) == 0) found = c;
        }
        if (found < 0) {
            snprintf(bad, badlen, "%.*s", (int)len, p);
            return -1;
        }
        mask |= CTC_CH_BIT(found);
        p += len;
        if (*p == ',') p++;
    }
    *out = mask;
    return 0;
}

/* the samples written: 0, every, 2 every, ... and always the last */
static int sample_kept(const ctc_sim_result *r, int j, int every)
{
    return j % every == 0 || j == r->nsamples - 1;
}

static int selected(const ctc_sim_result *r, const result_select *sel, int c)
{
    return r->ch[c] && (!sel || sel->channels == 0 || (sel->channels & CTC_CH_BIT(c)));
}

static int every_of(const result_select *sel)
{
    return sel && sel->every > 1 ? sel->every : 1;
}

/* column i of channel c is written: the coordinate filter applies to nv-wide channels */
static int column_kept(const ctc_sim_result *r, const result_select *sel, int c, int i)
{
    if (!sel || !sel->coords || c == CTC_CH_ENERGY || c == CTC_CH_LOOP || c == CTC_CH_EE ||
        c == CTC_CH_POSE || r->width[c] != r->nv)
        return 1;
    return sel->coords[i] != 0;
}

void result_column_name(char *buf, size_t len, int c, int i)
{
    if (c == CTC_CH_ENERGY)
        snprintf(buf, len, "energy[%s]", energy_parts[i]);
    else if (c == CTC_CH_LOOP)
        snprintf(buf, len, "loop[%s]", loop_parts[i]);
    else if (c == CTC_CH_EE)
        snprintf(buf, len, "end_effector[%s]", ee_parts[i]);
    else if (c == CTC_CH_POSE)
        snprintf(buf, len, "body_pose[%d][%s]", i / 7, pose_parts[i % 7]);
    else
        snprintf(buf, len, "%s[%d]", ctc_channel_name((ctc_channel)c), i);
}

static void put_number(FILE *f, double x, int json)
{
    if (isfinite(x))
        fprintf(f, "%.17g", x);
    else
        fputs(json ? "null" : "nan", f);
}

int result_write_csv(FILE *f, const ctc_sim_result *r, const result_select *sel)
{
    int every = every_of(sel);
    char name[64];
    fputs("t", f);
    for (int c = 0; c < CTC_NCHANNELS; c++)
        for (int i = 0; selected(r, sel, c) && i < r->width[c]; i++) {
            if (!column_kept(r, sel, c, i)) continue;
            result_column_name(name, sizeof name, c, i);
            fprintf(f, ",%s", name);
        }
    fputc('\n', f);
    for (int j = 0; j < r->nsamples; j++) {
        if (!sample_kept(r, j, every)) continue;
        put_number(f, r->t[j], 0);
        for (int c = 0; c < CTC_NCHANNELS; c++)
            for (int i = 0; selected(r, sel, c) && i < r->width[c]; i++) {
                if (!column_kept(r, sel, c, i)) continue;
                fputc(',', f);
                put_number(f, r->ch[c][(size_t)j * (size_t)r->width[c] + (size_t)i], 0);
            }
        fputc('\n', f);
    }
    return ferror(f) ? -1 : 0;
}

/* one column of the series as a JSON array */
static void write_column(FILE *f, const ctc_sim_result *r, const double *base, int stride,
                         int every)
{
    fputc('[', f);
    int first = 1;
    for (int j = 0; j < r->nsamples; j++) {
        if (!sample_kept(r, j, every)) continue;
        if (!first) fputc(',', f);
        first = 0;
        put_number(f, base[(size_t)j * (size_t)stride], 1);
    }
    fputc(']', f);
}

int result_write_series_json(FILE *f, const ctc_sim_result *r, const result_select *sel)
{
    int every = every_of(sel);
    fputs("{\"t\":", f);
    write_column(f, r, r->t, 1, every);
    for (int c = 0; c < CTC_NCHANNELS; c++) {
        if (!selected(r, sel, c)) continue;
        fprintf(f, ",\"%s\":[", ctc_channel_name((ctc_channel)c));
        int first = 1;
        for (int i = 0; i < r->width[c]; i++) {
            if (!column_kept(r, sel, c, i)) continue;
            if (!first) fputc(',', f);
            first = 0;
            write_column(f, r, r->ch[c] + i, r->width[c], every);
        }
        fputc(']', f);
    }
    fputc('}', f);
    return ferror(f) ? -1 : 0;
}

static int write_object_member(FILE *f, const char *key, const cJSON *value)
{
    char *text = cJSON_PrintUnformatted(value);
    if (!text) return -1;
    fprintf(f, "\"%s\":%s,", key, text);
    cJSON_free(text);
    return 0;
}

int result_write_json(FILE *f, const ctc_sim_result *r, const job *j, const result_select *sel)
{
    cJSON *metrics = result_metrics_json(r, j);
    if (!metrics) return -1;
    fputc('{', f);
    fprintf(f, "\"status\":\"%s\",", ctc_run_status_name(r->status));
    int rc = 0;
    if (j && j->normalised) rc |= write_object_member(f, "spec", j->normalised);
    rc |= write_object_member(f, "metrics", metrics);
    cJSON_Delete(metrics);
    if (rc) return -1;
    fputs("\"series\":", f);
    result_write_series_json(f, r, sel);
    fputs("}\n", f);
    return ferror(f) ? -1 : 0;
}

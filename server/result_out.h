/*
 * result_out.h - a finished run as the outside world sees it: metrics as JSON, series as CSV or
 * as columnar JSON. Shared by the command line and the service so both speak one format.
 *
 * Column names are the channel's name and the coordinate's index from 0, as in the job's JSON
 * arrays: "t", "q[0]", "qdot[2]", "e[1]", "energy[kinetic]", "energy[potential]",
 * "loop[position]", "loop[velocity]". The controller's channels (q_des, qdot_des, e, tau, w) have
 * one column per controlled coordinate: every coordinate of an open chain, so e[i] goes with
 * qdot[i]; the independent coordinates of a loop, numbered as the job's per-coordinate arrays
 * ("trajectory[i]", "controller.joints[i]"), so e[i] of a loop is its i-th independent
 * coordinate - the metrics' "coordinates" list gives its joint and its qdot index (the closing
 * joint's from nv on). Non-finite numbers become null in JSON and "nan" in CSV. Numbers are
 * written with 17 significant digits (exact round trip).
 */
#ifndef RESULT_OUT_H
#define RESULT_OUT_H

#include <stdio.h>

#include <cjson/cJSON.h>

#include "job_json.h"
#include "sim.h"

/* The run's metrics as a new JSON object (caller frees with cJSON_Delete), or NULL when out of
 * memory: status, message, form, sizes (nq, nv, nind), the controlled coordinates
 * ("coordinates": [{"joint": k, "coordinate": qdot index}], one per column of the controller's
 * channels; needs j), per-coordinate tracking errors, accuracy figures, cost counters and times,
 * for a loop model "loop" {residual_max, velocity_residual_max, cond_max, projections, initial
 * {iterations, dq_max, dv_max, residual_before, residual_after, velocity_residual_before,
 * velocity_residual_after}}, and the designed gains of j (j may be NULL). */
cJSON *result_metrics_json(const ctc_sim_result *r, const job *j);

/* Parses a comma-separated channel list ("q,e,tau") into CTC_CH_BIT flags. Returns 0, or -1
 * with the offending name copied into bad (badlen bytes). */
int result_parse_channels(const char *list, unsigned *out, char *bad, size_t badlen);

/* Which part of the series to write. */
typedef struct result_select {
    unsigned channels;  /* CTC_CH_BIT mask of recorded channels to write; 0 = all recorded */
    int every;          /* keep every every-th sample and always the last; < 1 means 1 */
    const char *coords; /* (nv) non-zero = keep coordinate i, or NULL = all. Applies to the
                           channels of width nv (not energy or loop), and to q when nq == nv;
                           columns keep their indices ("q[2]"). The controller's channels of a
                           loop model (nind < nv columns) are kept whole */
} result_select;

/* The name of column i of channel c (a ctc_channel) into buf (len bytes): "q[2]",
 * "energy[kinetic]", "loop[velocity]". */
void result_column_name(char *buf, size_t len, int c, int i);

/* Writes the series as CSV: a header line, then the selected samples and columns (sel may be
 * NULL: everything). Returns 0, or -1 on a write error. */
int result_write_csv(FILE *f, const ctc_sim_result *r, const result_select *sel);

/* Writes the series object alone: {"t": [...], "q": [[q[0] samples], [q[1] samples], ...],
 * ...}, columnar, with the same selection as the CSV. Returns 0, or -1 on a write error. */
int result_write_series_json(FILE *f, const ctc_sim_result *r, const result_select *sel);

/* Writes {"status", "spec", "metrics", "series"} as JSON (the series as above). j gives the
 * normalised spec and the gains (may be NULL). Returns 0, or -1 on a write error or out of
 * memory. */
int result_write_json(FILE *f, const ctc_sim_result *r, const job *j, const result_select *sel);

#endif

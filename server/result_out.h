/*
 * result_out.h - a finished run as the outside world sees it: metrics as JSON, series as CSV or
 * as columnar JSON. Shared by the command line and the service so both speak one format.
 *
 * Column names are the channel's name and the coordinate's index from 0, as in the job's JSON
 * arrays: "t", "q[0]", "qdot[2]", "energy[kinetic]", ... Non-finite numbers become null in JSON
 * and "nan" in CSV. Numbers are written with 17 significant digits (exact round trip).
 */
#ifndef RESULT_OUT_H
#define RESULT_OUT_H

#include <stdio.h>

#include <cjson/cJSON.h>

#include "job_json.h"
#include "sim.h"

/* The run's metrics as a new JSON object (caller frees with cJSON_Delete), or NULL when out of
 * memory: status, message, form, sizes, per-coordinate tracking errors, accuracy figures, cost
 * counters and times, and the designed gains of j (j may be NULL). */
cJSON *result_metrics_json(const ctc_sim_result *r, const job *j);

/* Parses a comma-separated channel list ("q,e,tau") into CTC_CH_BIT flags. Returns 0, or -1
 * with the offending name copied into bad (badlen bytes). */
int result_parse_channels(const char *list, unsigned *out, char *bad, size_t badlen);

/* Writes the series as CSV: a header line, then every `every`-th sample (the last one always)
 * with the channels in mask that were recorded (mask 0 = all recorded). Returns 0, or -1 on a
 * write error. */
int result_write_csv(FILE *f, const ctc_sim_result *r, unsigned mask, int every);

/* Writes {"status", "spec", "metrics", "series"} as JSON, the series columnar ("t": [...],
 * "q": [[q0 samples], [q1 samples], ...]) with the same selection rules as the CSV. spec is the
 * job's normalised document (may be NULL). Returns 0, or -1 on a write error or out of memory. */
int result_write_json(FILE *f, const ctc_sim_result *r, const job *j, unsigned mask, int every);

#endif

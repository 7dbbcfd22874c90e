/*
 * family.h - a study: a family of jobs that differ along a few axes (sweeps, Monte-Carlo), its
 * expansion into ordinary jobs, and the table of their results.
 *
 * The service (POST /api/families) and the command line (`ctcsim sweep`) both expand a family
 * here, so the two make the same members, and both write the table here, so the two print the
 * same table. A family is an object:
 *   "name"      string, optional (1..JOB_MAX_NAME bytes; default the base job's name)
 *   "base"      object, required: a job or a preset request {"preset": NAME, PARAMS...,
 *               OVERRIDES...}, exactly as POST /api/jobs takes it (job_json.h)
 *   "axes"      array of 0..FAMILY_MAX_AXES objects, each:
 *       "path"    the JSON path of the job key the axis sets: keys joined by ".", array
 *                 elements by [index] ("controller.kp", "integrator.rtol", "n" of a preset,
 *                 "controller.model.mass_scale", "scene.bodies[2].mass"); at most one axis a
 *                 path
 *       and one of:
 *       "values"   [v0, v1, ...]: any JSON values, 1..max members of them
 *       "linspace" [a, b, k]: k >= 1 numbers from a to b evenly spaced (a alone when k = 1)
 *       "logspace" [a, b, k]: k >= 1 numbers from a to b (both > 0) evenly spaced in log10
 *       "random"   {"dist": "uniform", "low": a, "high": b > a}
 *                | {"dist": "normal", "mean": m, "std": s > 0}
 *                | {"dist": "lognormal", "mu": m, "sigma": s > 0}  (exp of a normal(mu, sigma))
 *                  with "count": k >= 1: k seeded draws (from "seed" and the axis's index)
 *               Made values (linspace, logspace, random) are rounded to 15 significant digits
 *   "combine"   "product" (default: every combination, the last axis varying fastest) or "zip"
 *               (the i-th value of every axis together; the axes must have the same length)
 *   "replicas"  whole number >= 1, default 1: each combination is run this many times
 *   "seed"      whole number 0..2^53, default 0: the seed of the random axes and of the replicas
 *
 * Members. Member i is the base request with each axis's value set at its path (objects on the
 * way are made when absent; an array on the way that the request lacks is first copied from the
 * base's normalised document, so "scene.bodies[1].mass" works on a preset), and, when the
 * family has "seed" or more than one replica, the job's seeded parts set to the member's seed
 * (FAMILY_SEED of the family's seed and the replica): "controller.seed" (the sensors' noise)
 * for a controlled job and "controller.model.random.seed" when the base's controller model has
 * random errors. Replica r of every combination gets the same seed, so the combinations are
 * compared under the same draws (common random numbers). The member's name is the base's name
 * followed by its axis values ("Triple pendulum, PID [controller.kp=100]", " #r" for a replica),
 * cut to JOB_MAX_NAME bytes. Each member is then parsed and normalised by job_from_json, exactly
 * as POST /api/jobs does; the first member that fails fails the family, with the axis values
 * and the job's error. Members are numbered from 0 in product (or zip) order, replicas
 * innermost. The expansion is deterministic: the same document gives bitwise the same members.
 *
 * The table. One row per member: "member" (its number), "replica", one column per axis (named
 * by its path, the member's value), "status", and the metrics (result_out.h) reduced over the
 * controlled coordinates: "e_final" (the largest |e_final|), "e_rms" (the largest e_rms),
 * "e_max" (the largest e_max), "tau_peak" (the largest), "energy_drift", "us_per_eval",
 * "steps" and "wall_s". A member without metrics (not finished, or failed before it ran) has
 * them empty (CSV) or null (JSON).
 *
 * Thread safety: none shared; any number of expansions may run at once.
 */
#ifndef FAMILY_H
#define FAMILY_H

#include <stdint.h>
#include <stdio.h>

#include <cjson/cJSON.h>

#define FAMILY_MAX_AXES 8
#define FAMILY_MAX_PATH 160 /* bytes of an axis's path */
#define FAMILY_NMETRICS 8   /* the metric columns of the table */

#define FAMILY_SEED_LIMIT 1000000000000000ULL /* 10^15: a member's seeds are below it */

/* the seed of replica r of a family seeded with seed: splitmix64 of both, modulo
   FAMILY_SEED_LIMIT (a job's seeds are whole numbers up to 2^53; below 10^15 they print exactly
   with the 15 digits cJSON writes) */
uint64_t family_seed(uint64_t seed, int replica);

/* Why a family was refused: the HTTP status (400, or 413 past the member limit), a stable code
 * (job_json.h's codes, and FAMILY_TOO_LARGE), the JSON path in the family document and the
 * message. */
typedef struct family_error {
    int status;
    char code[32];
    char field[272];
    char message[2048];
} family_error;

/* One member, as it is stored and run. Strings owned by the family. */
typedef struct family_member {
    long index;       /* 0-based */
    int replica;      /* 0..replicas-1 */
    char *values;     /* JSON array of its axis values, one per axis */
    char *name;       /* the job's name */
    char *preset;     /* the preset it came from, or NULL */
    char *controller; /* the controller's type name */
    char *spec;       /* normalised job JSON */
    int nbodies, nv;
    int threads; /* the job's "threads" */
} family_member;

typedef struct family {
    char *name;
    char *doc;   /* the family's document as received, unformatted */
    char *paths; /* JSON array of the axes' paths */
    int naxes;
    int replicas;
    long nmembers;
    family_member *members; /* (nmembers) */
} family;

/* Expands the family document of len bytes at text (need not be terminated) into its members,
 * each validated and normalised (see above). max_members (>= 1) caps the member count; a family
 * with more is refused before any member is made (413 FAMILY_TOO_LARGE, field "axes"). Returns
 * 0 and *out (free with family_free), or -1 with *err filled: 400 with the parser's code at a
 * path of the family document ("axes[1].logspace", "base.controller.kp" for an error of the
 * base itself), a member's failure as INVALID_FIELD (or the job's code) at "axes[i]" of the
 * first axis with "axis PATH = VALUE (member M): FIELD: MESSAGE"; 503 NO_MEMORY. */
int family_expand(const char *text, size_t len, long max_members, family **out, family_error *err);

/* Frees a family; NULL is allowed. */
void family_free(family *f);

/* One row of the table, as the caller has it (nothing is copied). */
typedef struct family_row {
    int64_t job;          /* the job's id, 0 when there is none (the command line) */
    long index;           /* the member's number */
    int replica;          /* its replica */
    const char *status;   /* "queued", "done", ... */
    const cJSON *values;  /* array of its axis values */
    const cJSON *metrics; /* its metrics (result_out.h), or NULL */
    const char *message;  /* why it failed, or NULL */
} family_row;

/* The metric columns' names, FAMILY_NMETRICS of them, in the table's order. */
extern const char *const family_metric_names[FAMILY_NMETRICS];

/* The metrics of a row reduced to the table's columns (NaN where absent). */
void family_row_metrics(const cJSON *metrics, double out[FAMILY_NMETRICS]);

/* Writes the table as CSV: the header "member,replica,PATH...,status,METRICS...", then one line
 * per row; numbers with the fewest of 15..17 significant digits that read back exactly, absent
 * values empty, strings quoted when they
 * hold a comma, a quote or a line break. paths is the JSON array of the axes' paths. Returns 0,
 * or -1 on a write error. */
int family_write_csv(FILE *f, const cJSON *paths, const family_row *rows, long n);

/* The table as JSON: {"columns": [...the CSV's header...], "rows": [{"member", "replica",
 * "job" (id or null), "values": [...], "status", "message", METRIC: number or null...}]}, or
 * NULL when out of memory. */
cJSON *family_table_json(const cJSON *paths, const family_row *rows, long n);

#endif

/*
 * job_parse.h - what the parts of the job parser share (internal to job_*.c and json_read.c):
 * the state of one parse, the format's defaults and limits, and each part's entry points.
 *
 * The parse walks the document in the format's order (job_json.h); each part reads its keys,
 * fills p->j and writes its keys, every default written out, into the normalised document
 * p->norm:
 *   json_read.c    the typed readers and the writers of the normalised document (json_read.h)
 *   job_scene.c    "scene": gravity, form, bodies (shapes, inertia, joints), the loop, q0, v0
 *   job_json.c     "name", "controller", and the entry points (presets, the whole document)
 *   job_run.c      "trajectory", "disturbance", "integrator", "duration", "output", "limits",
 *                  "threads"
 *   job_plant.c    "plant" (read after the disturbance) and "wrenches"
 * The parts run in that order and may read what earlier parts left in p and p->j (the sizes,
 * nind, the loop, p->ctrl). Each returns 0, or -1 with p->err filled.
 */
#ifndef JOB_PARSE_H
#define JOB_PARSE_H

#include <cjson/cJSON.h>

#include "job_json.h"
#include "json_read.h"

_Static_assert(sizeof(((job_error *)0)->field) == PATH_LEN, "paths are written into field");

/* defaults (job_json.h) */
#define DEFAULT_NAME "job"
#define DEFAULT_INTERVAL 0.01 /* s, or the duration when shorter */
#define DEFAULT_RK4_STEP 1e-3 /* s */
#define DEFAULT_RTOL 1e-8
#define DEFAULT_ATOL 1e-10
#define DEFAULT_MAX_STEPS 10000000.0
#define DEFAULT_MAX_SPEED 1e6 /* rad/s or m/s */
#define DEFAULT_GRAVITY                                                                            \
    {                                                                                              \
        0, -9.81, 0                                                                                \
    } /* m/s^2 */
/* the default gravity of a scene given as "urdf" or "dh": their z axis points up */
#define ROBOT_GRAVITY                                                                              \
    {                                                                                              \
        0, 0, -9.81                                                                                \
    } /* m/s^2 */

/* rows of the format's tables (job_json.h): an object's keys; a default number, vector or JSON */
#define FORMAT_KEYS(path, type_key, type, keys)                                                    \
    {                                                                                              \
        path, type_key, type, keys                                                                 \
    }
#define FORMAT_END                                                                                 \
    {                                                                                              \
        NULL, NULL, NULL, NULL                                                                     \
    }
#define DEFAULT_NUMBER(path, type, key, x)                                                         \
    {                                                                                              \
        path, type, key, 1, {x}, NULL                                                              \
    }
#define DEFAULT_VECTOR(path, type, key, ...)                                                       \
    {                                                                                              \
        path, type, key, 3, __VA_ARGS__, NULL                                                      \
    }
#define DEFAULT_JSON(path, type, key, json)                                                        \
    {                                                                                              \
        path, type, key, 0, {0}, json                                                              \
    }
#define DEFAULT_END                                                                                \
    {                                                                                              \
        NULL, NULL, NULL, 0, {0}, NULL                                                             \
    }

/* the state of one parse */
struct parser {
    job *j;                       /* the job being filled */
    job_error *err;               /* the first error */
    cJSON *norm;                  /* the normalised document being written (j->normalised) */
    int oom;                      /* an allocation for the normalised document failed */
    char undriven[PATH_LEN];      /* the first independent joint no controller drives (a kind
                                     whose row says why it is `undriven`, model.h): its owner
                                     ("scene.bodies[1]", "scene.loop"), or "" */
    ctc_joint_type undriven_type; /* and its type */
    ctc_ctrl_type ctrl;           /* the controller's type, once read */
};

/* ---- scene (job_scene.c) ---- */

/* the scene's objects and defaults (job_json.h's job_format_object_tables and job_format_defaults)
 */
extern const job_format_object job_scene_objects[];
extern const job_format_default job_scene_defaults[];

/* The joints' objects ("scene.bodies[].joint", "scene.loop.joint": every type's keys together,
 * then each type's), made from the joint table (model.h) by job_scene_joint_format, which must
 * have been called first (once is enough; thread-safe). */
extern job_format_object job_scene_joint_objects[];
void job_scene_joint_format(void);

/* "scene" of doc, required: the chain into p->j->spec.chain (bodies, joints, the loop and the
 * independent flags), nq, nv, nind, q0 and v0; checked by ctc_model_build, whose errors are
 * reported at "scene" or, with a loop, where loop_error_field says. */
int parse_scene(parser *p, const cJSON *doc);

/* The field of a library error msg about the scene of a job with a loop: "scene.q0" when the
 * loop "does not close" from q0, "scene.loop" for what the library says of the loop (its
 * mobility, the closing joint, a singular or over-constrained configuration), else "scene". */
const char *loop_error_field(const char *msg);

/* ---- a Denavit-Hartenberg table (dh.c) ---- */

/* the keys of "scene.dh" and of each of its rows */
extern const char *const dh_keys[];
extern const char *const dh_row_keys[];

/* "scene.dh" (the value dh): the table read and converted into *bodies, a new array of the job's
 * bodies with "parent" indices (import.h; the caller frees it). Errors at "scene.dh...". */
int parse_scene_dh(parser *p, const cJSON *dh, cJSON **bodies);

/* ---- controller (job_json.c) ---- */

/* What one entry of a per-coordinate array stands for, in messages: "independent coordinate"
 * with a loop, "coordinate" without. */
const char *coordinate_word(const parser *p);

/* ---- the run (job_run.c) ---- */

/* the run settings' objects and defaults */
extern const job_format_object job_run_objects[];
extern const job_format_default job_run_defaults[];

/* "trajectory": required with a controller (p->ctrl), not allowed without; one object for every
 * coordinate or an array of nind. Fills p->j->traj. */
int parse_trajectory(parser *p, const cJSON *doc);

/* "disturbance", default none: like the trajectory; spec.disturb stays NULL when it is none for
 * every coordinate. */
int parse_disturbance(parser *p, const cJSON *doc);

/* Reads one item v (at path) for coordinates first .. first + count - 1, writing its normalised
 * form into out. */
typedef int (*coord_item_parser)(parser *p, const cJSON *v, const char *path, int first, int count,
                                 cJSON *out);

/* doc's key v: one object for every coordinate, or an array of nind of them, each read by item
 * and written under key in the normalised document. */
int parse_per_coordinate(parser *p, const cJSON *v, const char *key, coord_item_parser item);

/* "integrator", default dopri5: checked by ctc_integ_check (errors at "integrator"). */
int parse_integrator(parser *p, const cJSON *doc);

/* "duration", required: 0 < duration <= JOB_MAX_DURATION. */
int parse_duration(parser *p, const cJSON *doc);

/* "output" (after the duration): the interval and the channels, within JOB_MAX_SAMPLES and
 * JOB_MAX_VALUES. */
int parse_output(parser *p, const cJSON *doc);

/* "limits": max_speed and wall_time. */
int parse_limits(parser *p, const cJSON *doc);

/* "threads": a whole number 1..CTC_MAX_THREADS, default 1. */
int parse_threads(parser *p, const cJSON *doc);

/* ---- the controller's model beyond the scales (job_model.c) ---- */

extern const job_format_object job_model_objects[];

/* "controller.model"'s "bodies", "gravity", "payload" and "random" (model, at controller.model;
 * NULL when absent), after the scene: fills spec.model_bodies and spec.model_gravity, and merges
 * the payload into the plant's body. Written to out_model. */
int parse_model_bodies(parser *p, const cJSON *model, cJSON *out_model);

/* ---- the plant (job_plant.c) ---- */

extern const job_format_object job_plant_objects[];
extern const job_format_default job_plant_defaults[];

/* "plant", default {} (the ideal plant): one object for every coordinate or an array of nind.
 * Fills p->j->plant; spec.plant stays NULL when no coordinate has a term. */
int parse_plant(parser *p, const cJSON *doc);

/* "wrenches", default []: the external wrenches on the plant's bodies (job_plant.c) */
int parse_wrenches(parser *p, const cJSON *doc);

#endif

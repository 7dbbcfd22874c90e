/*
 * job_json.h - the job format: the one place a job's JSON is parsed, validated and normalised.
 *
 * The command line (`ctcsim run`) and the HTTP service (POST /api/jobs) both turn a JSON document
 * into a runnable ctc_sim_spec here. The JSON Schema in api/job.schema.json describes the same
 * format for users; this comment is the reference. The parser is in parts (job_parse.h):
 * job_json.c (the entry points below and the controller), job_scene.c (the scene), job_run.c
 * (trajectory to threads), json_read.c (the typed JSON reader). Its keys and defaults are data
 * (job_format_object_tables, job_format_defaults below), checked against the schema and the
 * parser by tests/unit/test_job_format.c, and the page's form defaults by
 * tests/api/format.test.mjs. Unknown keys are errors everywhere (a typo must not pass silently);
 * every error names the JSON path of the offending value and the reason. Units are SI and radians
 * throughout.
 *
 * A job is an object:
 *   "name"        string, optional (1..JOB_MAX_NAME bytes; default "job" or the preset's name;
 *                 a preset request's job left unnamed, or named as the preset's own document,
 *                 is named after what it changes: job_name.h)
 *   "tags"        optional array of at most JOB_MAX_TAGS (16) distinct strings of 1..JOB_MAX_TAG
 *                 (40) bytes without control characters; kept in the normalised document only
 *                 when given (GET /api/jobs?tag= finds them)
 *   "scene"       object, required:
 *       "gravity"   [gx, gy, gz] m/s^2, default [0, -9.81, 0]
 *       "form"      "auto" (default) | "planar" | "spatial"
 *       "bodies"    array of 1..JOB_MAX_BODIES bodies, each after its parent; each:
 *           "name"     string, optional (1..JOB_MAX_NAME bytes)
 *           "parent"   the body it hangs from (model.h's topology): the index of a body before
 *                      it (a whole number), a body's "name" (unique among the bodies), or -1 /
 *                      "ground" for the ground; default the ground for the first body and the
 *                      previous body after it (a chain). Written as the index (-1: the ground)
 *           "mass"     kg >= 0, required (a shape needs it > 0); 0 or a zero inertia: a
 *                      singular body, model.h (refused where M(q) is singular)
 *           "com"      [x, y, z] m, centre of mass in the body frame   } both, or a "shape"
 *           "inertia"  3x3 array of rows, or [Ixx, Iyy, Izz] (principal   } instead
 *                      axes along the body axes), kg m^2 about the CoM  }
 *           "shape"    {"type": "rod", "end": [x,y,z]}
 *                    | {"type": "box", "size": [a,b,c], "centre": [x,y,z] (default 0)}
 *                    | {"type": "cylinder", "radius": r, "length": L, "axis": [x,y,z],
 *                       "centre": [x,y,z] (default 0)}          (shapes.h; needs "mass")
 *           "joint"    the body's inboard joint, required:
 *                      {"type": "revolute"|"prismatic"|"cylindrical"|"spherical"|"fixed",
 *                       "axis": [x,y,z] (required for revolute, prismatic, cylindrical; not
 *                       allowed for spherical and fixed), "location": [x,y,z] m in the parent's
 *                       frame (the world's for the first body; default [0,0,0]),
 *                       "independent": true (default) | false: actuated, or passive (its motion
 *                       follows from the loop); false only with a "loop" (an open chain is
 *                       fully actuated),
 *                       "limit": {"lower", "upper" (rad or m, lower <= upper), "effort" (N m or
 *                       N), "velocity" (rad/s or m/s)} and "dynamics": {"damping", "friction"},
 *                       optional, each key optional, magnitudes >= 0: kept in the job (a URDF
 *                       gives them) for the lab plant; the simulation does not use them yet}
 *           "visuals"  optional, up to JOB_MAX_VISUALS shapes the page's animation draws for
 *                      the body (job_scene.c parse_visuals): {"type": "box", "size": [3]} |
 *                      {"type": "cylinder", "radius", "length"} | {"type": "sphere", "radius"}
 *                      (m > 0), with "origin" [3] (m, body frame; default 0) and, but for a
 *                      sphere, "rotation" (3 rows, a proper rotation; default the identity);
 *                      a URDF's <visual> boxes, cylinders and spheres come here (import.h);
 *                      the simulation ignores them
 *       "urdf"      instead of "bodies": a URDF robot description, XML text (urdf.h), converted
 *                   into bodies (import.h: frames rotated to be parallel to the world's at
 *                   q = 0, fixed joints merged, the root link fixed to the world); the
 *                   normalised document has the bodies. Errors at "scene.urdf", naming the
 *                   element and its line
 *       "dh"        instead of "bodies": a Denavit-Hartenberg table (dh.c), converted the same
 *                   way: {"convention": "standard"|"modified", "rows": [1..JOB_MAX_BODIES rows
 *                   {"name" (default "linkI"), "type": "revolute" (default)|"prismatic", "a" m,
 *                   "alpha" rad, "d" m, "theta" rad (default 0), "mass" kg >= 0, "com" [x,y,z] m
 *                   and "inertia" (as a body's) in the row's DH frame}]}; q = 0 is the pose with
 *                   each row's theta (or d), so q is the DH joint variable minus it
 *                   With "urdf" or "dh" the default gravity is [0, 0, -9.81] (their z is up).
 *                   Each converted body names its "parent" (a branched robot is a tree)
 *       "loop"      optional: closes the chain into one kinematic loop (model.h): a closing
 *                   joint from the last body (the tip) to a point fixed in the world, or in
 *                   an earlier body:
 *           "joint"    {"type": "revolute"|"prismatic"|"spherical", "axis": [x,y,z] (required
 *                       for revolute and prismatic, not allowed for spherical; in the tip's
 *                       frame), "location": [x,y,z] m, the joint's centre in the tip's frame
 *                       (default [0,0,0]), "independent": false (default) | true}
 *           "anchor"   [x,y,z] m, required: the joint's centre on the ground, world frame
 *                      (or on body "body", in its frame)
 *           "body"     optional, a body before the tip by its index 0..n-2 or its name (as
 *                      "parent"; written as the index): the loop closes on this body instead
 *                      of the ground; the joints before it (0..body) carry the loop and must
 *                      be independent (unless every joint is dependent)
 *           "stabilization"  how the state is kept on the closure (sim.h), default "project":
 *                      {"method": "project", "tol": 1e-12 (m or rad, and m/s or rad/s for
 *                      the rates, > 0)}
 *                    | {"method": "baumgarte", "alpha": 10, "beta": 10 (1/s, >= 0, not both 0)}
 *                    | {"method": "none"}
 *           "cond_max" > 1, default 1e5: the run stops as "singular" when the condition
 *                      estimate of the closed chain's boundary solve passes it
 *                   A loop needs at least 2 bodies. Its independent coordinates (nind: the
 *                   velocity coordinates of the independent joints, the closing joint's last; 1
 *                   for a revolute or prismatic closing joint, 3 for a spherical one) are the
 *                   ones the controller drives: with a controller their count must equal the
 *                   loop's mobility; a passive run may leave every joint dependent.
 *       "q0"        array of nq numbers (default: all zero, identity quaternions; a spherical
 *                   joint's quaternion (w, x, y, z) must have unit length to 1e-6). With a loop,
 *                   the independent joints' entries are exact and the dependent ones a guess:
 *                   the run first puts q0 onto the closure (the correction is in the metrics)
 *       "v0"        array of nv numbers (default: all zero); with a loop the dependent joints'
 *                   velocities are replaced by the ones that keep the loop closed
 *   "controller"  object, required:
 *       "type"      "none" | "pd" | "pid" | "poles" | "lqr" (computed torque) | "joint_pd" |
 *                   "pd_gravity" | "feedforward" (the baselines, ctrl.h ctc_ctrl_force; open
 *                   chains only)
 *       pd:    "kp", "kv"                   or "zeta", "tau"
 *       pid:   "kp", "kv", "ki"             or "zeta", "tau", "ki"
 *       poles: "poles": three entries, each a number (real pole) or {"re": x, "im": y} (both)
 *       lqr:   "Q": 3x3 array of rows or [q1, q2, q3] (diagonal), "lambda": number > 0
 *       joint_pd, pd_gravity, feedforward: "kp" (N m/rad, N/m) and "kv" (N m s/rad, N s/m)
 *       "joints"  optional array of nind objects, one per coordinate, each with any of the type's
 *                 gain keys above to override them for that coordinate ({} keeps them); for pd
 *                 and pid, an override that names the other pair ("zeta"/"tau" where the
 *                 controller has "kp"/"kv", or the reverse) replaces the pair and must give both
 *       "model"   optional {"mass_scale": s > 0, "inertia_scale": s > 0}, default 1 and 1:
 *                 the controller's model of the plant (model error); and (job_model.c):
 *                 "bodies" [{"body": k, "mass" >= 0 | "mass_scale" > 0, "com": [3],
 *                 "inertia" | "inertia_scale" > 0}], the model's own body values; "gravity"
 *                 [3], the model's gravity; "payload" {"body": k, "mass" > 0, "point": [3]}, a
 *                 point mass the plant carries and the model lacks; "random" {"seed", "mass",
 *                 "com", "inertia"}, seeded uniform draws of the model's errors
 *       "sample_period"  s >= 0, default 0 (the paper's continuous controller): a sampled
 *                 controller with zero-order hold, its command computed at t = k T and held
 *                 (sim.h); at most JOB_MAX_CONTROL_SAMPLES instants in the run
 *       "sample_delay"   whole samples 0..CTC_SIM_MAX_DELAY, default 0: the command computed at
 *                 t_k is applied from t_k+d on (0 before); only with a sample_period
 *       "seed"    whole number 0..2^53, default 0: the sensors' noise generator's (plant.h)
 *     "none" allows only "type"; other types need a trajectory, and no independent spherical
 *     joint (error at "controller.type": a quaternion error is not a per-coordinate error).
 *     The controlled coordinates (nind of them) are every coordinate of an open chain (nind = nv)
 *     and the independent coordinates of a loop, in joint order, the closing joint's last; the
 *     per-coordinate arrays below ("controller.joints", "trajectory", "disturbance") have nind
 *     entries.
 *   "trajectory"  one object for every coordinate, or an array of nind objects (required with a
 *                 controller, not allowed without):
 *       {"type": "constant", "value": v}
 *       {"type": "sine"|"cosine", "amplitude": A, "period": T > 0, "phase": 0, "offset": 0}
 *       {"type": "polynomial", "coefficients": [c0, c1, ...]}      (1..16 coefficients)
 *       {"type": "min_jerk", "from": q0, "to": q1, "start": t0, "end": t1 > t0}
 *       {"type": "spline", "times": [...], "values": [...], "boundary": "clamped"|"natural"}
 *   "disturbance" optional (default {"type": "none"}), one object for every coordinate or an
 *                 array of nind objects:
 *       {"type": "none"} | {"type": "constant", "value": z}
 *       | {"type": "sine", "amplitude", "period", "phase" (0), "offset" (0)}
 *       | {"type": "step", "value": z, "time": t}
 *   "plant"       optional (default {}: the paper's ideal plant), one object for every coordinate
 *                 or an array of nind objects; each term is off unless given (plant.h):
 *       "torque_limit"  N m (N for a prismatic coordinate) > 0: the actuator delivers the
 *                 controller's force clipped to +-torque_limit (the disturbance is added after);
 *                 the integral state of pid and the other kinds is clamped while clipped
 *                 (anti-windup). Needs a controller.
 *       "viscous"  N m s/rad or N s/m >= 0: the joint force -viscous v (a damper)
 *       "coulomb"  N m or N >= 0, with "coulomb_velocity" v_s > 0 (required with it): the
 *                 regularised friction -coulomb tanh(v / v_s)
 *       "spring"   N m/rad or N/m >= 0, with "spring_rest" (rad or m, 0 when left out): the joint
 *                 force -spring (q - spring_rest)
 *       "armature" kg m^2 or kg >= 0: the rotor's reflected inertia, added to the joint's
 *                 diagonal of M (open chains)
 *       "known"    true | false (when left out): the controller compensates the joint forces
 *                 and the armature
 *       "noise_q", "noise_v"  standard deviations >= 0 (rad or m, rad/s or m/s) of the Gaussian
 *                 noise on what a sampled controller measures; "resolution" >= 0 (rad or m):
 *                 its encoder's count. Need "controller.sample_period" and an open chain.
 *   "wrenches"    optional (default []): up to JOB_MAX_WRENCHES external wrenches on the plant's
 *                 bodies (wrench.h; open chains and trees), each {"body": k, "point": [3] (m,
 *                 the body's frame; default 0), "force": [3] (N), "torque": [3] (N m), "frame":
 *                 "world" (default) | "body" (the axes of force and torque), "profile":
 *                 "constant" (default) | "sine" ("period" > 0 s, "phase" rad, default 0) |
 *                 "step" ("time" >= 0 s), "known": false (default) | true (the controller
 *                 compensates it; needs a controller)}
 *   "integrator"  optional, default {"method": "dopri5", "rtol": 1e-8, "atol": 1e-10}:
 *       {"method": "rk4", "step": h}      (default step 1e-3 s; the step is shortened so that it
 *                                          divides the output interval)
 *       {"method": "dopri5"|"bdf", "rtol": r, "atol": a, "initial_step": 0, "max_step": 0,
 *        "min_step": 0}                  (a step the error control cuts below min_step stops the
 *                                          job: "step size ... fell below min_step"; 0 = none)
 *       any method: "max_steps" (a whole number, default 10000000; 0 = no limit); rk4's
 *       duration / step must not exceed it (nor JOB_MAX_FIXED_STEPS when it is 0), or the job
 *       is refused with INVALID_FIELD at "integrator.step"; nor may rk4's steps x bodies exceed
 *       JOB_MAX_WORK (LIMIT_EXCEEDED at "integrator.step")
 *   "duration"    s, required, 0 < duration <= JOB_MAX_DURATION
 *   "output"      optional: {"interval": dt, 0 < dt <= duration (default 0.01 s, or the duration
 *                 when shorter), "channels": ["q", "qdot", "q_des", "qdot_des", "e", "tau", "w",
 *                 "energy", "loop", "end_effector", "body_pose"] (default: all that apply; q_des,
 *                 qdot_des, e and w need a controller, loop a loop, end_effector its point,
 *                 body_pose its bodies, tau at least one
 *                 controlled coordinate), "end_effector": {"body": k, "point": [3] (m, the body's
 *                 frame; default [0, 0, 0])}: the point whose world position and velocity the
 *                 end_effector channel records (x, y, z, vx, vy, vz), "body_pose": [k, ...]
 *                 (distinct body indices): the bodies whose poses the body_pose channel records,
 *                 7 columns each, body_pose[i][x, y, z, qw, qx, qy, qz] for the i-th listed}
 *   "limits"      optional: {"max_speed": rad/s or m/s, > 0 (default 1e6), "wall_time": s >= 0
 *                 (0 = none)}
 *   "threads"     optional whole number 1..CTC_MAX_THREADS (64), default 1: the threads the run's
 *                 GDCA passes may use, its own thread included (sim.h); heights of the assembly
 *                 tree too small to pay for the split, and passes whose split measures slower
 *                 than one thread, run serially, and the samples are bitwise the same for every
 *                 count (but on open chains of 2048 planar or 512 spatial bodies or more, where
 *                 the counts agree to rounding: sim.h).
 *                 Each run has its own workers.
 *
 * Or a preset with overrides: {"preset": NAME, PARAMS..., OVERRIDES...}. The preset's own
 * parameters (presets.h, e.g. "n" of n_link_pendulum) are taken out, the preset's job document
 * is built, and the remaining keys are applied to it as a JSON merge patch (RFC 7386: objects
 * merge key by key, null removes a key, anything else replaces), with one refinement: an object
 * whose "type" or "method" the patch changes is replaced whole (by the patch's object, its nulls
 * dropped), so {"integrator": {"method": "rk4", "step": 0.001}} or {"controller": {"type": "pd",
 * "kp": 50, "kv": 10}} over a preset does not inherit the old method's rtol or the old
 * controller's ki, and {"controller": {"type": "pd", "kp": 50, "kv": 10, "ki": null}} is the same.
 *
 * Errors. A key repeated in one object is an error. Numbers must be finite (1e999 reads as
 * infinity and is rejected). What the library checks is reported with the library's message at
 * the nearest path: a controller's design at "controller" or "controller.joints[i]"; a
 * trajectory's or disturbance's parameters at "trajectory", "trajectory[i]", ...; the integrator
 * at "integrator"; a shape at "scene.bodies[k].shape"; what only ctc_model_build finds (inertia
 * tensors, a planar form asked of a spatial chain) at "scene"; what the library finds wrong with a
 * loop (its closing joint, its mobility against the independent coordinates, a singular or
 * over-constrained configuration at q0) at "scene.loop", except a q0 from which the loop cannot
 * be closed, at "scene.q0". A failed allocation is reported as NO_MEMORY with the message "out
 * of memory".
 *
 * The normalised document has the keys above in the order above, every default written out
 * (q0, v0, every joint's "independent" flag, a loop's settings and the channel list
 * explicitly), the preset expanded; it parses to the same spec.
 * cJSON 1.7 prints a number with 15 significant digits when they read back within DBL_EPSILON
 * relative, so a printed document may differ from the spec in the last bit of such numbers.
 */
#ifndef JOB_JSON_H
#define JOB_JSON_H

#include <stddef.h>

#include <cjson/cJSON.h>

#include "sim.h"

/* The job format's longest chain: what the tests check against the oracle and run (round trip
 * within 2.2x of ABA's at 16384 and 65536 planar bodies, test_hard; a CTC run at 65536,
 * tests/cli). The library's own bound, CTC_MAX_BODIES (model.h, 10^6), is its allocation and
 * index bound: beyond 65536 rods the accelerations keep no digit (bench/NOTEBOOK.md, "Long chains
 * to 65536"). A scene of 65536 bodies is about 6.4 MB of JSON, within the service's default
 * --max-body (8 MiB); JOB_MAX_WORK and the job time limit bound what it may cost a worker. */
#define JOB_MAX_BODIES 65536
#define JOB_MAX_DURATION 3600.0 /* s of simulated time */
#define JOB_MAX_SAMPLES 200000  /* output samples */
#define JOB_MAX_VALUES 20000000 /* samples x values per sample over the recorded channels */
#define JOB_MAX_NAME 200        /* bytes */
#define JOB_MAX_WRENCHES 64     /* external wrenches */
#define JOB_MAX_VISUALS 64      /* visual shapes of one body (scene.bodies[k].visuals) */
#define JOB_MAX_TAGS 16         /* tags of a job */
#define JOB_MAX_TAG 40          /* bytes of a tag */
#define JOB_MAX_FIXED_STEPS 1e9 /* rk4 steps (duration / step) when max_steps is 0 */
/* rk4 steps x bodies at most: about 7 min of a worker at the 0.43 us a planar body-step measured
   (a 64-link pendulum, 10^4 steps in 0.28 s), so about what the server's default time limit of
   600 s lets a job do; spatial chains cost more per body-step */
#define JOB_MAX_WORK 1e9
/* a sampled controller's instants (duration / sample_period) at most: each restarts the
   integrator */
#define JOB_MAX_CONTROL_SAMPLES 1e7

/* Error codes, stable for clients (the service returns them as error.code). */
typedef enum job_error_code {
    JOB_OK = 0,
    JOB_INVALID_JSON,   /* not parseable JSON */
    JOB_MISSING_FIELD,  /* a required key is absent */
    JOB_UNKNOWN_FIELD,  /* a key the format does not have */
    JOB_INVALID_FIELD,  /* wrong type or value out of range */
    JOB_UNKNOWN_PRESET, /* "preset" names no preset */
    JOB_LIMIT_EXCEEDED, /* bodies, duration, samples beyond the limits above */
    JOB_NO_MEMORY,      /* an allocation failed (the service answers 503) */
} job_error_code;

typedef struct job_error {
    job_error_code code;
    char field[256];    /* JSON path, e.g. "scene.bodies[2].mass"; "" for the whole document */
    char message[1024]; /* the reason, e.g. "must be positive (got -1 kg)" */
} job_error;

/* A parsed job: the spec points into the arrays this struct owns. */
typedef struct job {
    char *name;
    char *preset;          /* the preset it came from, or NULL */
    ctc_sim_spec spec;     /* ready for ctc_sim_run */
    int nq, nv;            /* sizes of the arrays below */
    int nind;              /* controlled coordinates: nv for an open chain, the independent
                              coordinates of a loop (model.h) */
    ctc_body_spec *bodies; /* (nbodies) */
    ctc_joint_spec *joints;
    int *parent;        /* (nbodies) each body's parent, -1 the ground (spec.chain.parent) */
    ctc_loop_spec loop; /* the closing joint; spec.chain.loop points here with a loop */
    unsigned char *independent; /* (nbodies + 1) with a loop, the closing joint last; NULL for an
                                   open chain (spec.chain.independent) */
    double *q0, *v0;            /* (nq), (nv) */
    ctc_gains *gains;           /* (nind) designed gains, NULL when passive */
    ctc_traj *traj;             /* (nind) NULL when passive */
    ctc_disturb *disturb;       /* (nind) NULL when none */
    ctc_plant_coord *plant;     /* (nind) NULL when the plant is the ideal one */
    /* (nbodies) the controller model's bodies (spec.model_bodies), NULL when they are the
       plant's; model_gravity, the model's gravity when spec.model_gravity (job_model.c) */
    ctc_body_spec *model_bodies;
    double model_gravity[3];
    ctc_end_effector end_effector; /* spec.end_effector points here when "output" gives one */
    int *pose_bodies;              /* (spec.npose) spec.pose_bodies, NULL when none */
    ctc_wrench *wrenches;          /* (spec.nwrenches) spec.wrenches, NULL when none */
    cJSON *normalised; /* the job with the preset expanded and every default filled in; itself
                          a valid job document. Owned. */
} job;

/* The format as data: every object the parser reads, with the keys it accepts, and every
 * default it applies. tests/unit/test_job_format.c checks them against api/job.schema.json,
 * and against the parser itself (a default row is what the normalised document gets when the key
 * is left out).
 *
 * A path names an object as errors do, with "[]" for any index: "", the document;
 * "scene.bodies[].joint"; "controller.joints[]". A per-coordinate object ("trajectory",
 * "disturbance") is listed at its key; the same keys apply to each entry of its array form. */
typedef struct job_format_object {
    const char *path;
    const char *type_key;    /* "type" or "method" for a typed object, else NULL */
    const char *type;        /* the type these keys are for ("revolute"); for "controller.joints[]"
                                the controller's; NULL: every type (for a typed object, the keys of
                                all its types together) */
    const char *const *keys; /* the keys accepted, NULL-terminated; any other is an error */
} job_format_object;

typedef struct job_format_default {
    const char *path; /* the object, as in job_format_object */
    const char *type; /* the object's type the default applies to, or NULL: every type */
    const char *key;
    int n; /* 1: the number x[0]; 3: the vector x; 0: the JSON text json */
    double x[3];
    const char *json; /* "\"auto\"", "true", "{\"type\": \"none\"}" */
} job_format_default;

/* Each part's tables, NULL-terminated lists; each table ends with a row whose path is NULL. The
 * objects' list comes from a function, since the controller's rows are made from the class table
 * (ctrl.h) on the first call (thread-safe).
 * Defaults that depend on the job are not listed: the name of a preset's job (the preset's),
 * q0 and v0 (the chain's reference configuration and rest), output.interval (0.01 s, or the
 * duration when shorter: listed as 0.01), output.channels (all that apply). */
const job_format_object *const *job_format_object_tables(void);
extern const job_format_default *const job_format_defaults[];

/* Parses len bytes of JSON text (need not be terminated). Returns 0 and *out (free with
 * job_free), or -1 with *err filled and *out NULL. Text that is not RFC 8259 JSON is
 * JOB_INVALID_JSON, field "", "invalid JSON at line L, column C" (1-based, columns in bytes) at its
 * first error, followed by ": REASON" where one is known: the numbers and strings cJSON would
 * take leniently ("01", "1.", "\u0000", a raw control character in a string; json_strict.h), or
 * "text after the end of the document". */
int job_parse(const char *text, size_t len, job **out, job_error *err);

/* The same from a parsed document (not modified, not kept). */
int job_from_json(const cJSON *doc, job **out, job_error *err);

/* Frees a job; NULL is allowed. */
void job_free(job *j);

/* The code's name: "INVALID_JSON", "MISSING_FIELD", ... */
const char *job_error_code_name(job_error_code c);

#endif

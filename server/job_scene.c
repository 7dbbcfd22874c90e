/*
 * job_scene.c - the job format's "scene" (job_json.h): gravity, the form, the bodies with their
 * shapes or inertia and their inboard joints, the loop that may close the chain, and the
 * initial state.
 *
 * A scene may give its robot as a URDF document ("urdf", urdf.h) or a Denavit-Hartenberg table
 * ("dh", dh.c) instead of "bodies": convert_robot turns either into bodies first, and the rest
 * of the parse reads those, so the normalised document holds the converted bodies.
 *
 * The bodies are read first, then the loop (it needs their count and sets which coordinates are
 * controlled: nind), then ctc_model_build checks what only the library can (inertia tensors, the
 * plane of a planar chain, the loop's closing joint and mobility), and last q0 and v0, whose
 * sizes come from the built model. A library error about a loop is reported at "scene.loop" or,
 * when the loop does not close from q0, at "scene.q0" (loop_error_field); anything else the
 * builder finds at "scene". The joints' type names and keys come from the joint table (model.h).
 */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "data.h"
#include "job_parse.h"
#include "shapes.h"
#include "urdf.h"

#define AXIS_MIN_LENGTH 1e-12 /* as ctc_model_build */
#define QUAT_UNIT_TOL 1e-6    /* |norm - 1| allowed of a quaternion in q0 */

/* ---- scene ---- */

static const char *const shape_names[] = {"rod", "box", "cylinder"};
enum { SHAPE_ROD, SHAPE_BOX, SHAPE_CYLINDER };
static const char *const shape_keys_all[] = {"type",   "end",    "size", "centre",
                                             "radius", "length", "axis", NULL};
static const char *const shape_keys_rod[] = {"type", "end", NULL};
static const char *const shape_keys_box[] = {"type", "size", "centre", NULL};
static const char *const shape_keys_cylinder[] = {"type", "radius", "length",
                                                  "axis", "centre", NULL};
static const char *const *const shape_keys[] = {shape_keys_rod, shape_keys_box,
                                                shape_keys_cylinder};

/* a body's centre of mass and inertia from its "shape" (body->mass already read) */
static int parse_shape(parser *p, const cJSON *v, const char *body_path, ctc_body_spec *body,
                       cJSON *out_body)
{
    static const double origin[3] = {0, 0, 0};
    char path[PATH_LEN], msg[256];
    int type;
    json_key_path(path, body_path, "shape");
    if (json_typed_object(p, v, path, "type", REQUIRED, 0, shape_names, 3, "shape type", shape_keys,
                          shape_keys_all, &type) != 0) {
        return -1;
    }
    cJSON *out = json_put(p, out_body, "shape", cJSON_CreateObject());
    json_put_string(p, out, "type", shape_names[type]);

    ctc_status st = CTC_OK;
    double end[3], size[3], centre[3], axis[3], radius, length;
    switch (type) {
    case SHAPE_ROD:
        if (json_member_vec3(p, v, path, "end", REQUIRED, NULL, end) != 0) return -1;
        json_put_numbers(p, out, "end", end, 3);
        st = ctc_shape_rod(body->mass, end, body, msg, sizeof msg);
        break;
    case SHAPE_BOX:
        if (json_member_vec3(p, v, path, "size", REQUIRED, NULL, size) != 0 ||
            json_member_vec3(p, v, path, "centre", OPTIONAL, origin, centre) != 0) {
            return -1;
        }
        json_put_numbers(p, out, "size", size, 3);
        json_put_numbers(p, out, "centre", centre, 3);
        st = ctc_shape_box(body->mass, size, centre, body, msg, sizeof msg);
        break;
    case SHAPE_CYLINDER:
        if (json_member_number(p, v, path, "radius", REQUIRED, 0, &radius) != 0 ||
            json_member_number(p, v, path, "length", REQUIRED, 0, &length) != 0 ||
            json_member_vec3(p, v, path, "axis", REQUIRED, NULL, axis) != 0 ||
            json_member_vec3(p, v, path, "centre", OPTIONAL, origin, centre) != 0) {
            return -1;
        }
        json_put_number(p, out, "radius", radius);
        json_put_number(p, out, "length", length);
        json_put_numbers(p, out, "axis", axis, 3);
        json_put_numbers(p, out, "centre", centre, 3);
        st = ctc_shape_cylinder(body->mass, radius, length, axis, centre, body, msg, sizeof msg);
        break;
    }
    if (st != CTC_OK) return json_error_at(p->err, JOB_INVALID_FIELD, path, "%s", msg);
    return 0;
}

/* "inertia": 3x3 rows, or the principal moments along the body axes (none negative) */
static int parse_inertia(parser *p, const cJSON *v, const char *path, ctc_body_spec *body,
                         cJSON *out_body)
{
    char at[PATH_LEN];
    int diagonal;
    if (json_matrix3_at(p, v, path, "principal moments", body->inertia, &diagonal) != 0) return -1;
    for (int i = 0; diagonal && i < 3; i++) {
        if (body->inertia[4 * i] < 0) {
            return json_error_at(p->err, JOB_INVALID_FIELD, json_index_path(at, path, i),
                                 "must not be negative (got %g kg m^2)", body->inertia[4 * i]);
        }
    }
    json_put_matrix3(p, out_body, "inertia", body->inertia, diagonal);
    return 0;
}

/* The joints' type names and keys, made from the joint table (model.h) once, by joint_format:
 * a joint of type t takes "type", "axis" when the row needs_axis, "location" and "independent",
 * and a body's joint "limit" and "dynamics" too (kept for the lab plant); a loop's closing
 * joint is one of the loop_closing kinds, listed in table order. The rows of the format's tables
 * (job_scene_joint_objects) follow from the same lists. */
#define JOINT_KEYS_MAX 7
static struct {
    const char *names[CTC_JOINT_NTYPES]; /* by ctc_joint_type */
    const char *keys[CTC_JOINT_NTYPES][JOINT_KEYS_MAX];
    const char *const *by_type[CTC_JOINT_NTYPES];
    const char *all[JOINT_KEYS_MAX]; /* the keys of every type together */
    /* a closing joint's keys, by type */
    const char *loop_keys[CTC_JOINT_NTYPES][JOINT_KEYS_MAX];
    int nloop; /* the closing joint's kinds: */
    ctc_joint_type loop_types[CTC_JOINT_NTYPES];
    const char *loop_names[CTC_JOINT_NTYPES];
    const char *const *loop_by_type[CTC_JOINT_NTYPES];
    const char *loop_all[JOINT_KEYS_MAX];
} jf;
static pthread_once_t joint_format_once = PTHREAD_ONCE_INIT;
job_format_object job_scene_joint_objects[2 * CTC_JOINT_NTYPES + 3];

/* keys of a joint (with an axis or not; a body's joint, with "limit" and "dynamics", or a
 * loop's) into out, NULL-terminated */
static void joint_keys_of(int axis, int body, const char **out)
{
    int n = 0;
    out[n++] = "type";
    if (axis) out[n++] = "axis";
    out[n++] = "location";
    out[n++] = "independent";
    if (body) {
        out[n++] = "limit";
        out[n++] = "dynamics";
    }
    out[n] = NULL;
}

static void build_joint_format(void)
{
    int any_axis = 0, loop_axis = 0, r = 0;
    for (int t = 0; t < CTC_JOINT_NTYPES; t++) {
        const ctc_joint_class *c = &ctc_joint_classes[t];
        jf.names[t] = c->name;
        joint_keys_of(c->needs_axis, 1, jf.keys[t]);
        jf.by_type[t] = jf.keys[t];
        any_axis |= c->needs_axis;
        if (!c->loop_closing) continue;
        joint_keys_of(c->needs_axis, 0, jf.loop_keys[t]);
        jf.loop_types[jf.nloop] = (ctc_joint_type)t;
        jf.loop_names[jf.nloop] = c->name;
        jf.loop_by_type[jf.nloop++] = jf.loop_keys[t];
        loop_axis |= c->needs_axis;
    }
    joint_keys_of(any_axis, 1, jf.all);
    joint_keys_of(loop_axis, 0, jf.loop_all);

    job_format_object *rows = job_scene_joint_objects;
    rows[r++] = (job_format_object)FORMAT_KEYS("scene.bodies[].joint", "type", NULL, jf.all);
    for (int t = 0; t < CTC_JOINT_NTYPES; t++)
        rows[r++] = (job_format_object)FORMAT_KEYS("scene.bodies[].joint", "type", jf.names[t],
                                                   jf.by_type[t]);
    rows[r++] = (job_format_object)FORMAT_KEYS("scene.loop.joint", "type", NULL, jf.loop_all);
    for (int i = 0; i < jf.nloop; i++)
        rows[r++] = (job_format_object)FORMAT_KEYS("scene.loop.joint", "type", jf.loop_names[i],
                                                   jf.loop_by_type[i]);
    rows[r] = (job_format_object)FORMAT_END;
}

void job_scene_joint_format(void)
{
    pthread_once(&joint_format_once, build_joint_format);
}

/* A joint's "axis" (joint v at path; the type needs one): any length, but not zero and not
 * overflowing. Written to out. */
static int parse_axis(parser *p, const cJSON *v, const char *path, double a[3], cJSON *out)
{
    char at[PATH_LEN];
    if (json_member_vec3(p, v, path, "axis", REQUIRED, NULL, a) != 0) return -1;
    double len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    json_key_path(at, path, "axis");
    if (!isfinite(len)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, at, "is too long (its length overflows)");
    }
    if (!(len > AXIS_MIN_LENGTH)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, at,
                             "must have non-zero length (got [%g, %g, %g])", a[0], a[1], a[2]);
    }
    json_put_numbers(p, out, "axis", a, 3);
    return 0;
}

/* A joint's "location" (default the origin) and "independent" flag (default def; joint v at
 * path, owner names it for messages), written to out. The first independent joint of a kind
 * no controller drives (`undriven`, model.h) is remembered: a controller cannot drive it. */
static int parse_joint_rest(parser *p, const cJSON *v, const char *path, const char *owner,
                            ctc_joint_spec *joint, int def, unsigned char *independent, cJSON *out)
{
    static const double origin[3] = {0, 0, 0};
    char at[PATH_LEN];
    if (json_member_vec3(p, v, path, "location", OPTIONAL, origin, joint->location) != 0) return -1;
    json_put_numbers(p, out, "location", joint->location, 3);
    int flag = def;
    const cJSON *f = json_member(v, "independent");
    if (f != NULL && json_bool_at(p, f, json_key_path(at, path, "independent"), &flag) != 0)
        return -1;
    *independent = (unsigned char)flag;
    json_put(p, out, "independent", cJSON_CreateBool(flag));
    if (flag && ctc_joint_classes[joint->type].undriven != NULL && p->undriven[0] == '\0') {
        snprintf(p->undriven, sizeof p->undriven, "%s", owner);
        p->undriven_type = joint->type;
    }
    return 0;
}

static const char *const limit_keys[] = {"lower", "upper", "effort", "velocity", NULL};
static const char *const dynamics_keys[] = {"damping", "friction", NULL};

/* A joint's "limit" and "dynamics" (optional; joint v at path), kept in the document for the
 * plant that will use them; each given number is checked and written to out. */
static int parse_joint_extras(parser *p, const cJSON *v, const char *path, cJSON *out)
{
    static const char *const names[2] = {"limit", "dynamics"};
    static const char *const *const keys[2] = {limit_keys, dynamics_keys};
    char at[PATH_LEN], key_at[PATH_LEN];
    for (int e = 0; e < 2; e++) {
        const cJSON *x = json_member(v, names[e]);
        if (x == NULL) continue;
        json_key_path(at, path, names[e]);
        if (json_object_at(p, x, at) != 0 || json_check_keys(p, x, at, keys[e], NULL, NULL) != 0)
            return -1;
        cJSON *o = json_put(p, out, names[e], cJSON_CreateObject());
        double val[4];
        int has[4] = {0};
        for (int i = 0; keys[e][i] != NULL; i++) {
            if (json_member(x, keys[e][i]) == NULL) continue;
            if (json_member_number(p, x, at, keys[e][i], REQUIRED, 0, &val[i]) != 0) return -1;
            has[i] = 1;
            /* all but a limit's lower and upper are magnitudes */
            if ((e == 1 || i >= 2) && val[i] < 0) {
                return json_error_at(p->err, JOB_INVALID_FIELD,
                                     json_key_path(key_at, at, keys[e][i]),
                                     "must not be negative (got %g)", val[i]);
            }
            json_put_number(p, o, keys[e][i], val[i]);
        }
        if (e == 0 && has[0] && has[1] && !(val[0] <= val[1])) {
            return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(key_at, at, "upper"),
                                 "must not be below lower (got %g < %g)", val[1], val[0]);
        }
    }
    return 0;
}

/* body k's inboard joint */
static int parse_joint(parser *p, const cJSON *body, const char *body_path, int k,
                       ctc_joint_spec *joint, cJSON *out_body)
{
    char path[PATH_LEN];
    int type;
    job_scene_joint_format();
    const cJSON *v = json_required_member(p, body, body_path, "joint", "");
    json_key_path(path, body_path, "joint");
    if (v == NULL || json_typed_object(p, v, path, "type", REQUIRED, 0, jf.names, CTC_JOINT_NTYPES,
                                       "joint type", jf.by_type, jf.all, &type) != 0) {
        return -1;
    }
    joint->type = (ctc_joint_type)type;
    cJSON *out = json_put(p, out_body, "joint", cJSON_CreateObject());
    json_put_string(p, out, "type", jf.names[type]);
    if (ctc_joint_classes[type].needs_axis && parse_axis(p, v, path, joint->axis, out) != 0) {
        return -1;
    }
    if (parse_joint_rest(p, v, path, body_path, joint, 1, &p->j->independent[k], out) != 0)
        return -1;
    return parse_joint_extras(p, v, path, out);
}

/* A reference to a body (body_ref): the parent of a body, or the body a loop closes on. */
typedef struct body_ref {
    const cJSON *bodies; /* the scene's "bodies" array, as given (names are looked up in it) */
    int before;          /* the body referred to must come before this one */
    const char *which;   /* body `before` in messages: "body 3", "the tip (body 4)" */
    int ground;          /* 1: -1 and "ground" name the ground */
} body_ref;

/* The index of the body whose "name" is the string name in r->bodies (*count of them; -1 for
 * none), and the second such one in *second. */
static int body_named(const body_ref *r, const char *name, int *count, int *second)
{
    int k = 0, first = -1;
    *count = 0;
    *second = -1;
    for (const cJSON *b = r->bodies->child; b != NULL; b = b->next, k++) {
        const cJSON *nm = json_member(b, "name");
        if (!cJSON_IsString(nm) || strcmp(nm->valuestring, name) != 0) continue;
        if ((*count)++ == 0)
            first = k;
        else if (*count == 2)
            *second = k;
    }
    return first;
}

/* *out = the body v (at path) refers to, by its index (a whole number) or its name (a string,
 * the body's "name", unique among the bodies), before body r->before; -1 for the ground where
 * r->ground allows it (-1 or "ground"). */
static int parse_body_ref(parser *p, const cJSON *v, const char *path, const body_ref *r, int *out)
{
    const int lo = r->ground ? -1 : 0, hi = r->before - 1;
    if (cJSON_IsString(v)) {
        const char *name = v->valuestring;
        int count, second, k = body_named(r, name, &count, &second);
        if (r->ground && strcmp(name, "ground") == 0) {
            if (count > 0) {
                return json_error_at(p->err, JOB_INVALID_FIELD, path,
                                     "\"ground\" is the ground, but body %d is named \"ground\" "
                                     "too: rename it, or refer to bodies by index",
                                     k);
            }
            *out = -1;
            return 0;
        }
        if (count == 0) {
            return json_error_at(p->err, JOB_INVALID_FIELD, path,
                                 "\"%s\" names no body (give a body's \"name\" or index%s)", name,
                                 r->ground ? ", or \"ground\"" : "");
        }
        if (count > 1) {
            return json_error_at(p->err, JOB_INVALID_FIELD, path,
                                 "\"%s\" is the name of bodies %d and %d: a name used to refer to "
                                 "a body must be unique",
                                 name, k, second);
        }
        if (k > hi) {
            return json_error_at(p->err, JOB_INVALID_FIELD, path,
                                 "\"%s\" must name a body before %s (it names body %d)", name,
                                 r->which, k);
        }
        *out = k;
        return 0;
    }
    if (!cJSON_IsNumber(v)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, path,
                             "must be a body's index or name%s (got %s)",
                             r->ground ? ", or \"ground\"" : "", json_kind(v));
    }
    double x;
    if (json_number_at(p, v, path, &x) != 0) return -1;
    if (!(x >= lo && x <= hi && x == floor(x))) {
        if (r->ground && r->before == 0) { /* the first body: only the ground is before it */
            return json_error_at(p->err, JOB_INVALID_FIELD, path,
                                 "must be -1 or \"ground\": nothing but the ground comes before "
                                 "%s (got %g)",
                                 r->which, x);
        }
        return json_error_at(p->err, JOB_INVALID_FIELD, path,
                             "must be %sthe index of a body before %s: a whole number from %d to "
                             "%d (got %g)",
                             r->ground ? "-1 (the ground) or " : "", r->which, lo, hi, x);
    }
    *out = (int)x;
    return 0;
}

/* body k's "parent" (default: the ground for body 0, body k - 1 after it), written as an index */
static int parse_parent(parser *p, const cJSON *v, const char *path, const cJSON *bodies, int k,
                        cJSON *out)
{
    char at[PATH_LEN], which[32];
    const cJSON *given = json_member(v, "parent");
    int *parent = &p->j->parent[k];
    *parent = k - 1;
    snprintf(which, sizeof which, "body %d", k);
    body_ref r = {bodies, k, which, 1};
    if (given != NULL && parse_body_ref(p, given, json_key_path(at, path, "parent"), &r, parent))
        return -1;
    json_put_number(p, out, "parent", *parent);
    return 0;
}

static const char *const body_keys[] = {"name",  "parent", "mass",    "com", "inertia",
                                        "shape", "joint",  "visuals", NULL};
static const char *const visual_keys[] = {"type",   "size",     "radius", "length",
                                          "origin", "rotation", NULL};

/* body k's "visuals" (at path), if given: up to JOB_MAX_VISUALS shapes the page draws, each
 * {"type": "box", "size": [3] > 0} | {"type": "cylinder", "radius" > 0, "length" > 0, its axis
 * the rotation's z} | {"type": "sphere", "radius" > 0}, with "origin" (m, the centre in the
 * body's frame; default 0) and, but for a sphere, "rotation" (3 rows, a proper rotation within
 * 1e-6: the shape's axes in the body's frame; default the identity). The simulation ignores
 * them; written to out. */
static int parse_visuals(parser *p, const cJSON *body, const char *body_path, cJSON *out_body)
{
    static const char *const types[3] = {"box", "cylinder", "sphere"};
    static const double zero[3] = {0, 0, 0};
    char path[PATH_LEN], at[PATH_LEN], item[PATH_LEN];
    const cJSON *v = json_member(body, "visuals");
    if (v == NULL) return 0;
    json_key_path(path, body_path, "visuals");
    const int n = cJSON_IsArray(v) ? cJSON_GetArraySize(v) : -1;
    if (n < 0 || n > JOB_MAX_VISUALS) {
        char buf[32];
        return json_error_at(p->err, JOB_INVALID_FIELD, path,
                             "must be an array of at most %d shapes (got %s)", JOB_MAX_VISUALS,
                             json_describe(buf, v));
    }
    cJSON *out = json_put(p, out_body, "visuals", cJSON_CreateArray());
    int i = 0;
    for (const cJSON *e = v->child; e != NULL; e = e->next, i++) {
        int type = 0;
        double size[3] = {0, 0, 0}, origin[3], rot[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        json_index_path(item, path, i);
        if (json_object_at(p, e, item) != 0 ||
            json_check_keys(p, e, item, visual_keys, NULL, NULL) != 0)
            return -1;
        const cJSON *t = json_required_member(p, e, item, "type", "");
        if (t == NULL || json_enum_at(p, t, json_key_path(at, item, "type"), types, 3, &type) != 0)
            return -1;
        /* the type's own keys */
        static const char *const own[4] = {"size", "radius", "length", "rotation"};
        static const int allowed[3][4] = {{1, 0, 0, 1}, {0, 1, 1, 1}, {0, 1, 0, 0}};
        for (int k = 0; k < 4; k++) {
            if (json_member(e, own[k]) != NULL && !allowed[type][k]) {
                return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, item, own[k]),
                                     "does not apply to a %s", types[type]);
            }
        }
        if (type == 0) {
            const cJSON *sz = json_required_member(p, e, item, "size", "");
            if (sz == NULL || json_vec3_at(p, sz, json_key_path(at, item, "size"), size) != 0)
                return -1;
            if (!(size[0] > 0 && size[1] > 0 && size[2] > 0)) {
                return json_error_at(p->err, JOB_INVALID_FIELD, at,
                                     "must be positive (got [%g, %g, %g] m)", size[0], size[1],
                                     size[2]);
            }
        } else {
            static const char *const dims[2] = {"radius", "length"};
            for (int k = 0; k < (type == 1 ? 2 : 1); k++) {
                if (json_member_number(p, e, item, dims[k], REQUIRED, 0, &size[k]) != 0) return -1;
                if (!(size[k] > 0)) {
                    return json_error_at(p->err, JOB_INVALID_FIELD,
                                         json_key_path(at, item, dims[k]),
                                         "must be positive (got %g m)", size[k]);
                }
            }
        }
        if (json_member_vec3(p, e, item, "origin", OPTIONAL, zero, origin) != 0) return -1;
        const cJSON *r = json_member(e, "rotation");
        if (r != NULL) {
            int diagonal = 0;
            json_key_path(at, item, "rotation");
            if (json_matrix3_at(p, r, at, "rotation", rot, &diagonal) != 0) return -1;
            double dev = 0, det = rot[0] * (rot[4] * rot[8] - rot[5] * rot[7]) -
                                  rot[1] * (rot[3] * rot[8] - rot[5] * rot[6]) +
                                  rot[2] * (rot[3] * rot[7] - rot[4] * rot[6]);
            for (int a = 0; a < 3; a++)
                for (int b = 0; b < 3; b++) {
                    double d = rot[3 * a] * rot[3 * b] + rot[3 * a + 1] * rot[3 * b + 1] +
                               rot[3 * a + 2] * rot[3 * b + 2];
                    dev = fmax(dev, fabs(d - (a == b)));
                }
            if (!(dev <= 1e-6 && det > 0)) {
                return json_error_at(p->err, JOB_INVALID_FIELD, at,
                                     "must be a rotation (orthonormal rows, determinant +1)");
            }
        }
        cJSON *o = json_put(p, out, NULL, cJSON_CreateObject());
        json_put_string(p, o, "type", types[type]);
        if (type == 0) json_put_numbers(p, o, "size", size, 3);
        if (type != 0) json_put_number(p, o, "radius", size[0]);
        if (type == 1) json_put_number(p, o, "length", size[1]);
        json_put_numbers(p, o, "origin", origin, 3);
        if (type != 2) json_put_matrix3(p, o, "rotation", rot, 0);
    }
    return 0;
}

/* body k of bodies: its name and parent, its mass, then com and inertia or a shape, then its
 * joint */
static int parse_body(parser *p, const cJSON *bodies, const cJSON *v, int k, cJSON *out_bodies)
{
    char path[PATH_LEN], at[PATH_LEN];
    ctc_body_spec *body = &p->j->bodies[k];
    json_index_path(path, "scene.bodies", k);
    if (json_object_at(p, v, path) != 0 || json_check_keys(p, v, path, body_keys, NULL, NULL) != 0)
        return -1;
    cJSON *out = json_put(p, out_bodies, NULL, cJSON_CreateObject());

    /* a name, kept only in the document */
    const cJSON *name = json_member(v, "name");
    const char *s;
    if (name != NULL) {
        if (json_name_at(p, name, json_key_path(at, path, "name"), &s) != 0) return -1;
        json_put_string(p, out, "name", s);
    }
    if (parse_parent(p, v, path, bodies, k, out) != 0) return -1;

    /* mass */
    if (json_member_number(p, v, path, "mass", REQUIRED, 0, &body->mass) != 0) return -1;
    if (body->mass < 0) { /* 0: a massless body; the model builder checks the mass matrix */
        return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, "mass"),
                             "must not be negative (got %g kg)", body->mass);
    }
    json_put_number(p, out, "mass", body->mass);

    /* centre of mass and inertia, or a shape that gives both */
    const cJSON *shape = json_member(v, "shape");
    if (shape != NULL) {
        static const char *const given[] = {"com", "inertia"};
        for (int i = 0; i < 2; i++) {
            if (json_member(v, given[i]) != NULL) {
                return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, given[i]),
                                     "not allowed with \"shape\" (the shape gives it)");
            }
        }
        if (parse_shape(p, shape, path, body, out) != 0) return -1;
    } else {
        const char *hint = " (or give a \"shape\")";
        const cJSON *com = json_required_member(p, v, path, "com", hint);
        if (com == NULL || json_vec3_at(p, com, json_key_path(at, path, "com"), body->com) != 0)
            return -1;
        json_put_numbers(p, out, "com", body->com, 3);
        const cJSON *inertia = json_required_member(p, v, path, "inertia", hint);
        if (inertia == NULL ||
            parse_inertia(p, inertia, json_key_path(at, path, "inertia"), body, out) != 0) {
            return -1;
        }
    }
    if (parse_joint(p, v, path, k, &p->j->joints[k], out) != 0) return -1;
    return parse_visuals(p, v, path, out);
}

/* "scene.bodies": 1..JOB_MAX_BODIES bodies */
static int parse_bodies(parser *p, const cJSON *scene, cJSON *out_scene)
{
    job *j = p->j;
    const cJSON *v = json_required_member(p, scene, "scene", "bodies", "");
    if (v == NULL) return -1;
    if (!cJSON_IsArray(v)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "scene.bodies",
                             "must be an array of bodies (got %s)", json_kind(v));
    }
    int n = cJSON_GetArraySize(v);
    if (n == 0)
        return json_error_at(p->err, JOB_INVALID_FIELD, "scene.bodies", "must not be empty");
    if (n > JOB_MAX_BODIES) {
        return json_error_at(p->err, JOB_LIMIT_EXCEEDED, "scene.bodies",
                             "has %d bodies; the limit is %d", n, JOB_MAX_BODIES);
    }
    j->bodies = json_alloc(p, (size_t)n, sizeof *j->bodies);
    j->joints = json_alloc(p, (size_t)n, sizeof *j->joints);
    j->independent = json_alloc(p, (size_t)n + 1, sizeof *j->independent);
    j->parent = json_alloc(p, (size_t)n, sizeof *j->parent);
    if (j->bodies == NULL || j->joints == NULL || j->independent == NULL || j->parent == NULL)
        return -1;
    j->spec.chain.nbodies = n;
    j->spec.chain.bodies = j->bodies;
    j->spec.chain.joints = j->joints;
    j->spec.chain.parent = j->parent;

    cJSON *out = json_put(p, out_scene, "bodies", cJSON_CreateArray());
    int k = 0;
    for (const cJSON *b = v->child; b != NULL; b = b->next, k++) {
        if (parse_body(p, v, b, k, out) != 0) return -1;
    }
    return 0;
}

/* "scene.q0" (default: the reference configuration) and "scene.v0" (default 0), given m */
static int parse_initial_state(parser *p, const cJSON *scene, const ctc_model *m, cJSON *out_scene)
{
    job *j = p->j;
    j->q0 = json_alloc(p, (size_t)m->nq, sizeof *j->q0);
    j->v0 = json_alloc(p, (size_t)m->nv, sizeof *j->v0);
    if (j->q0 == NULL || j->v0 == NULL) return -1;
    j->spec.q0 = j->q0;
    j->spec.v0 = j->v0;

    const cJSON *q0 = json_member(scene, "q0");
    if (q0 == NULL) {
        ctc_model_q_zero(m, j->q0);
    } else if (json_coords_at(p, q0, "scene.q0", m->nq, "position coordinate", j->q0) != 0) {
        return -1;
    }

    /* a spherical joint's quaternion must be a rotation */
    for (int k = 0; k < m->nbodies; k++) {
        if (m->joints[k].type != CTC_JOINT_SPHERICAL) continue;
        const double *q = &j->q0[m->jnt_qadr[k]];
        double norm = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        if (!(fabs(norm - 1) <= QUAT_UNIT_TOL)) {
            return json_error_at(p->err, JOB_INVALID_FIELD, "scene.q0",
                                 "entries %d to %d, the quaternion (w, x, y, z) of "
                                 "scene.bodies[%d].joint, must have unit length (got %g)",
                                 m->jnt_qadr[k], m->jnt_qadr[k] + 3, k, norm);
        }
    }
    json_put_numbers(p, out_scene, "q0", j->q0, m->nq);

    const cJSON *v0 = json_member(scene, "v0");
    if (v0 != NULL && json_coords_at(p, v0, "scene.v0", m->nv, "coordinate", j->v0) != 0) return -1;
    json_put_numbers(p, out_scene, "v0", j->v0, m->nv);
    return 0;
}

/* ---- the loop ---- */

/* "scene.loop.joint": the closing joint, from the tip (body n - 1) to the ground or to body
 * "scene.loop.body" */
static int parse_loop_joint(parser *p, const cJSON *loop, cJSON *out_loop)
{
    static const char *const path = "scene.loop.joint";
    job *j = p->j;
    ctc_joint_spec *joint = &j->loop.joint;
    int type;
    job_scene_joint_format();
    const cJSON *v = json_required_member(p, loop, "scene.loop", "joint", "");
    if (v == NULL || json_typed_object(p, v, path, "type", REQUIRED, 0, jf.loop_names, jf.nloop,
                                       "joint type", jf.loop_by_type, jf.loop_all, &type) != 0) {
        return -1;
    }
    joint->type = jf.loop_types[type];
    cJSON *out = json_put(p, out_loop, "joint", cJSON_CreateObject());
    json_put_string(p, out, "type", jf.loop_names[type]);
    if (ctc_joint_classes[joint->type].needs_axis &&
        parse_axis(p, v, path, joint->axis, out) != 0) {
        return -1;
    }
    int n = j->spec.chain.nbodies;
    return parse_joint_rest(p, v, path, "scene.loop", joint, 0, &j->independent[n], out);
}

static const char *const stab_keys_all[] = {"method", "tol", "alpha", "beta", NULL};
static const char *const stab_keys_project[] = {"method", "tol", NULL};
static const char *const stab_keys_baumgarte[] = {"method", "alpha", "beta", NULL};
static const char *const stab_keys_none[] = {"method", NULL};
static const char *const *const stab_keys[] = {[CTC_LOOP_PROJECT] = stab_keys_project,
                                               [CTC_LOOP_BAUMGARTE] = stab_keys_baumgarte,
                                               [CTC_LOOP_NONE] = stab_keys_none};

/* "scene.loop.stabilization": how the state is kept on the closure (default project) */
static int parse_stabilization(parser *p, const cJSON *loop, cJSON *out_loop)
{
    static const char *const path = "scene.loop.stabilization";
    ctc_sim_spec *s = &p->j->spec;
    const char *names[3];
    int method;
    for (int m = 0; m < 3; m++) names[m] = ctc_loop_stab_name((ctc_loop_stab)m);
    if (json_typed_object(p, json_member(loop, "stabilization"), path, "method", OPTIONAL,
                          CTC_LOOP_PROJECT, names, 3, "method", stab_keys, stab_keys_all,
                          &method) != 0) {
        return -1;
    }
    const cJSON *v = json_member(loop, "stabilization");
    s->loop_stab = (ctc_loop_stab)method;
    cJSON *out = json_put(p, out_loop, "stabilization", cJSON_CreateObject());
    json_put_string(p, out, "method", names[method]);
    switch (s->loop_stab) {
    case CTC_LOOP_PROJECT:
        if (json_member_number(p, v, path, "tol", OPTIONAL, CTC_SIM_DEFAULT_LOOP_TOL,
                               &s->loop_tol) != 0) {
            return -1;
        }
        if (!(s->loop_tol > 0)) {
            return json_error_at(p->err, JOB_INVALID_FIELD, "scene.loop.stabilization.tol",
                                 "must be positive (got %g)", s->loop_tol);
        }
        json_put_number(p, out, "tol", s->loop_tol);
        break;
    case CTC_LOOP_BAUMGARTE: {
        static const char *const keys[2] = {"alpha", "beta"};
        char at[PATH_LEN];
        for (int i = 0; i < 2; i++) {
            double *x = &s->baumgarte[i];
            if (json_member_number(p, v, path, keys[i], OPTIONAL, CTC_SIM_DEFAULT_BAUMGARTE, x) !=
                0)
                return -1;
            if (!(*x >= 0)) {
                return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, keys[i]),
                                     "must not be negative (got %g 1/s)", *x);
            }
        }
        /* the library reads (0, 0) as its defaults: say "none" for no stabilisation */
        if (s->baumgarte[0] == 0 && s->baumgarte[1] == 0) {
            return json_error_at(p->err, JOB_INVALID_FIELD, path,
                                 "alpha and beta must not both be 0 (use {\"method\": \"none\"} "
                                 "for no stabilization)");
        }
        json_put_number(p, out, "alpha", s->baumgarte[0]);
        json_put_number(p, out, "beta", s->baumgarte[1]);
        break;
    }
    case CTC_LOOP_NONE:
        break;
    }
    return 0;
}

static const char *const loop_keys[] = {"joint",         "anchor",   "body",
                                        "stabilization", "cond_max", NULL};

/* "scene.loop.body" (optional): the body the loop closes on, before the tip (body n - 1), by its
 * index or name as a body's parent (written as the index); absent, the loop closes on the
 * ground */
static int parse_loop_body(parser *p, const cJSON *scene, const cJSON *loop, cJSON *out_loop)
{
    job *j = p->j;
    int n = j->spec.chain.nbodies, b;
    char which[48];
    j->loop.on_body = 0;
    j->loop.body = 0;
    const cJSON *v = json_member(loop, "body");
    if (v == NULL) return 0;
    snprintf(which, sizeof which, "the tip (body %d)", n - 1);
    body_ref r = {json_member(scene, "bodies"), n - 1, which, 0};
    if (parse_body_ref(p, v, "scene.loop.body", &r, &b) != 0) return -1;
    j->loop.on_body = 1;
    j->loop.body = b;
    json_put_number(p, out_loop, "body", b);
    return 0;
}

/* "scene.loop" (optional): the closing joint, its anchor and the run's loop settings; then the
 * independent flags: with a loop they say which coordinates are controlled (nind), without one
 * every joint must be independent */
static int parse_loop(parser *p, const cJSON *scene, cJSON *out_scene)
{
    job *j = p->j;
    ctc_sim_spec *s = &j->spec;
    int n = s->chain.nbodies;
    const cJSON *v = json_member(scene, "loop");
    if (v == NULL) {
        for (int k = 0; k < n; k++) {
            if (j->independent[k]) continue;
            char body[PATH_LEN], joint[PATH_LEN], at[PATH_LEN];
            json_index_path(body, "scene.bodies", k);
            return json_error_at(
                p->err, JOB_INVALID_FIELD,
                json_key_path(at, json_key_path(joint, body, "joint"), "independent"),
                "must be true: an open chain is fully actuated (only a chain closed "
                "by \"scene.loop\" has dependent joints)");
        }
        free(j->independent);
        j->independent = NULL;
        j->nind = j->nv;
        return 0;
    }
    if (json_object_at(p, v, "scene.loop") != 0 ||
        json_check_keys(p, v, "scene.loop", loop_keys, NULL, NULL) != 0) {
        return -1;
    }
    cJSON *out = json_put(p, out_scene, "loop", cJSON_CreateObject());
    if (parse_loop_joint(p, v, out) != 0 ||
        json_member_vec3(p, v, "scene.loop", "anchor", REQUIRED, NULL, j->loop.anchor) != 0) {
        return -1;
    }
    json_put_numbers(p, out, "anchor", j->loop.anchor, 3);
    if (parse_loop_body(p, scene, v, out) != 0 || parse_stabilization(p, v, out) != 0 ||
        json_member_number(p, v, "scene.loop", "cond_max", OPTIONAL, CTC_SIM_DEFAULT_COND_MAX,
                           &s->loop_cond_max) != 0) {
        return -1;
    }
    if (!(s->loop_cond_max > 1)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "scene.loop.cond_max",
                             "must be greater than 1 (got %g)", s->loop_cond_max);
    }
    json_put_number(p, out, "cond_max", s->loop_cond_max);
    s->chain.loop = &j->loop;
    s->chain.independent = j->independent;

    /* the controlled coordinates: those of the independent joints, the closing joint's last */
    j->nind = 0;
    for (int k = 0; k < n; k++) {
        if (j->independent[k]) j->nind += ctc_joint_nv(j->joints[k].type);
    }
    if (j->independent[n]) j->nind += ctc_joint_nv(j->loop.joint.type);
    return 0;
}

/* The field of a library error about the scene of a job with a loop: the loop's settings, or
 * q0 when the loop does not close from it; "scene" for anything else. */
const char *loop_error_field(const char *msg)
{
    static const char *const loop_words[] = {"loop",     "mobility",         "closing joint",
                                             "singular", "over-constrained", NULL};
    if (strncmp(msg, "body ", 5) == 0) return "scene"; /* a body's inertia, even a singular one */
    if (strstr(msg, "does not close") != NULL) return "scene.q0";
    for (const char *const *w = loop_words; *w != NULL; w++) {
        if (strstr(msg, *w) != NULL) return "scene.loop";
    }
    return "scene";
}

static const char *const scene_keys[] = {"gravity", "form", "bodies", "urdf", "dh",
                                         "loop",    "q0",   "v0",     NULL};

/* A robot the scene carries as "urdf" (text) or "dh" (a table), instead of "bodies": *converted
 * is a copy of the scene with the robot's bodies (import.h) in "bodies" and, unless the scene
 * gives one, the gravity of a robot whose z axis is up; NULL when the scene has "bodies". Each
 * converted body names its parent by index (a body before it, or -1 for the ground), so a
 * branched robot (a gripper's two fingers) is a tree. */
static int convert_robot(parser *p, const cJSON *scene, cJSON **converted)
{
    static const char *const kinds[2] = {"urdf", "dh"};
    const cJSON *given[2] = {json_member(scene, "urdf"), json_member(scene, "dh")};
    char msg[512];
    *converted = NULL;
    if (given[0] == NULL && given[1] == NULL) return 0;
    int kind = given[0] != NULL ? 0 : 1;
    const char *field = kind == 0 ? "scene.urdf" : "scene.dh";
    if (given[1 - kind] != NULL || json_member(scene, "bodies") != NULL) {
        const char *other = given[1 - kind] != NULL ? kinds[1 - kind] : "bodies";
        return json_error_at(p->err, JOB_INVALID_FIELD, field,
                             "not allowed with \"%s\" (give the robot one way)", other);
    }
    cJSON *bodies = NULL;
    if (kind == 0) {
        if (!cJSON_IsString(given[0])) {
            return json_error_at(p->err, JOB_INVALID_FIELD, field,
                                 "must be a string, the URDF document (got %s)",
                                 json_kind(given[0]));
        }
        const char *text = given[0]->valuestring;
        bodies = urdf_to_bodies(text, strlen(text), NULL, 0, msg, sizeof msg);
        if (bodies == NULL) {
            if (strcmp(msg, "out of memory") == 0) return json_out_of_memory(p->err);
            return json_error_at(p->err, JOB_INVALID_FIELD, field, "%s", msg);
        }
    } else if (parse_scene_dh(p, given[1], &bodies) != 0) {
        return -1;
    }
    cJSON *copy = cJSON_Duplicate(scene, 1);
    if (copy == NULL) {
        cJSON_Delete(bodies);
        return json_out_of_memory(p->err);
    }
    cJSON_DeleteItemFromObjectCaseSensitive(copy, kinds[kind]);
    if (!cJSON_AddItemToObject(copy, "bodies", bodies)) {
        cJSON_Delete(bodies);
        cJSON_Delete(copy);
        return json_out_of_memory(p->err);
    }
    if (json_member(copy, "gravity") == NULL) {
        static const double z_up[3] = ROBOT_GRAVITY;
        if (!cJSON_AddItemToObject(copy, "gravity", cJSON_CreateDoubleArray(z_up, 3))) {
            cJSON_Delete(copy);
            return json_out_of_memory(p->err);
        }
    }
    *converted = copy;
    return 0;
}

static int parse_scene_read(parser *p, const cJSON *v);

/* An error about a body converted from a robot ("scene.bodies[K]..." or "body K: ...", paths and
 * numbers the user never wrote) gets the body's name, its URDF link or DH row, appended. */
static void name_converted_body(parser *p, const cJSON *converted)
{
    int k = -1;
    if (sscanf(p->err->field, "scene.bodies[%d]", &k) != 1 &&
        sscanf(p->err->message, "body %d:", &k) != 1)
        return;
    const cJSON *body = cJSON_GetArrayItem(json_member(converted, "bodies"), k);
    const cJSON *name = json_member(body, "name");
    if (!cJSON_IsString(name)) return;
    size_t len = strlen(p->err->message);
    snprintf(p->err->message + len, sizeof p->err->message - len, " (the robot's link \"%s\")",
             name->valuestring);
}

int parse_scene(parser *p, const cJSON *doc)
{
    const cJSON *v = json_required_member(p, doc, "", "scene", "");
    if (v == NULL || json_object_at(p, v, "scene") != 0 ||
        json_check_keys(p, v, "scene", scene_keys, NULL, NULL) != 0) {
        return -1;
    }
    cJSON *converted = NULL;
    if (convert_robot(p, v, &converted) != 0) return -1;
    if (converted != NULL) v = converted;
    int rc = parse_scene_read(p, v);
    if (rc != 0 && converted != NULL) name_converted_body(p, converted);
    cJSON_Delete(converted);
    return rc;
}

/* the scene v, with its bodies given as "bodies" */
static int parse_scene_read(parser *p, const cJSON *v)
{
    static const double gravity[3] = DEFAULT_GRAVITY;
    job *j = p->j;
    ctc_chain_spec *chain = &j->spec.chain;
    cJSON *out = json_put(p, p->norm, "scene", cJSON_CreateObject());

    /* gravity and form */
    if (json_member_vec3(p, v, "scene", "gravity", OPTIONAL, gravity, chain->gravity) != 0)
        return -1;
    json_put_numbers(p, out, "gravity", chain->gravity, 3);
    const char *forms[3];
    int form = CTC_FORM_AUTO;
    for (int f = 0; f < 3; f++) forms[f] = ctc_form_name((ctc_form)f);
    const cJSON *fv = json_member(v, "form");
    if (fv != NULL && json_enum_at(p, fv, "scene.form", forms, 3, &form) != 0) return -1;
    chain->form = (ctc_form)form;
    json_put_string(p, out, "form", forms[form]);

    /* bodies; at least one coordinate must move */
    if (parse_bodies(p, v, out) != 0) return -1;
    for (int k = 0; k < chain->nbodies; k++) {
        j->nq += ctc_joint_nq(j->joints[k].type);
        j->nv += ctc_joint_nv(j->joints[k].type);
    }
    if (j->nv == 0) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "scene.bodies",
                             "must have at least one joint that moves (every joint is fixed)");
    }
    if (parse_loop(p, v, out) != 0) return -1;

    /* what only the builder checks: inertia tensors, the plane of a planar chain, the loop */
    ctc_model *m = NULL;
    char msg[512];
    ctc_status st = ctc_model_build(chain, &m, msg, sizeof msg);
    if (st == CTC_ENOMEM) return json_out_of_memory(p->err);
    if (st != CTC_OK) {
        const char *field = chain->loop != NULL ? loop_error_field(msg) : "scene";
        return json_error_at(p->err, JOB_INVALID_FIELD, field, "%s", msg);
    }
    int rc = parse_initial_state(p, v, m, out);
    ctc_model_free(m);
    return rc;
}

/* ---- the scene's keys and defaults, as data (job_json.h) ---- */

const job_format_object job_scene_objects[] = {
    FORMAT_KEYS("scene", NULL, NULL, scene_keys),
    FORMAT_KEYS("scene.bodies[]", NULL, NULL, body_keys),
    FORMAT_KEYS("scene.bodies[].visuals[]", NULL, NULL, visual_keys),
    FORMAT_KEYS("scene.bodies[].shape", "type", NULL, shape_keys_all),
    FORMAT_KEYS("scene.bodies[].shape", "type", "rod", shape_keys_rod),
    FORMAT_KEYS("scene.bodies[].shape", "type", "box", shape_keys_box),
    FORMAT_KEYS("scene.bodies[].shape", "type", "cylinder", shape_keys_cylinder),
    FORMAT_KEYS("scene.bodies[].joint.limit", NULL, NULL, limit_keys),
    FORMAT_KEYS("scene.bodies[].joint.dynamics", NULL, NULL, dynamics_keys),
    FORMAT_KEYS("scene.dh", NULL, NULL, dh_keys),
    FORMAT_KEYS("scene.dh.rows[]", NULL, NULL, dh_row_keys),
    FORMAT_KEYS("scene.loop", NULL, NULL, loop_keys),
    FORMAT_KEYS("scene.loop.stabilization", "method", NULL, stab_keys_all),
    FORMAT_KEYS("scene.loop.stabilization", "method", "project", stab_keys[CTC_LOOP_PROJECT]),
    FORMAT_KEYS("scene.loop.stabilization", "method", "baumgarte", stab_keys[CTC_LOOP_BAUMGARTE]),
    FORMAT_KEYS("scene.loop.stabilization", "method", "none", stab_keys[CTC_LOOP_NONE]),
    FORMAT_END,
};

const job_format_default job_scene_defaults[] = {
    DEFAULT_VECTOR("scene", NULL, "gravity", DEFAULT_GRAVITY),
    DEFAULT_JSON("scene", NULL, "form", "\"auto\""),
    DEFAULT_VECTOR("scene.bodies[].shape", "box", "centre", {0, 0, 0}),
    DEFAULT_VECTOR("scene.bodies[].shape", "cylinder", "centre", {0, 0, 0}),
    DEFAULT_VECTOR("scene.bodies[].joint", NULL, "location", {0, 0, 0}),
    DEFAULT_JSON("scene.bodies[].joint", NULL, "independent", "true"),
    DEFAULT_VECTOR("scene.loop.joint", NULL, "location", {0, 0, 0}),
    DEFAULT_JSON("scene.loop.joint", NULL, "independent", "false"),
    DEFAULT_JSON("scene.loop.stabilization", NULL, "method", "\"project\""),
    DEFAULT_NUMBER("scene.loop.stabilization", "project", "tol", CTC_SIM_DEFAULT_LOOP_TOL),
    DEFAULT_NUMBER("scene.loop.stabilization", "baumgarte", "alpha", CTC_SIM_DEFAULT_BAUMGARTE),
    DEFAULT_NUMBER("scene.loop.stabilization", "baumgarte", "beta", CTC_SIM_DEFAULT_BAUMGARTE),
    DEFAULT_NUMBER("scene.loop", NULL, "cond_max", CTC_SIM_DEFAULT_COND_MAX),
    DEFAULT_END,
};

/*
 * dh.c - the job format's "scene.dh" (job_json.h): a Denavit-Hartenberg table, standard or
 * modified (Craig), with each link's mass, centre of mass and inertia in its DH frame, converted
 * into the job's bodies through the link tree of import.h.
 *
 * Frames. Frame 0 is the world's. Row i (1-based) holds the joint's type, a, alpha, d, theta (the
 * offset) and link i's inertial data in DH frame i. The joint variable is theta_i = q_i + theta
 * (revolute) or d_i = q_i + d (prismatic), so q = 0 is the pose with every theta (or d) at the
 * table's value: ctcsim's q is the DH joint variable minus the row's offset.
 *   standard:  F_i = F_(i-1) Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i); joint i moves about (or
 *              along) z of frame i-1.
 *   modified:  F_i = F_(i-1) Rx(alpha_(i-1)) Tx(a_(i-1)) Rz(theta_i) Tz(d_i), row i holding
 *              a_(i-1) and alpha_(i-1); joint i moves about (or along) z of frame i.
 * Both are F_i = F_(i-1) A_i Mot_z(q_i) B_i with fixed transforms A_i, B_i: standard A_i = 1,
 * B_i = Rz(theta) Tz(d) Tx(a) Rx(alpha); modified A_i = Rx(alpha) Tx(a), B_i = Rz(theta) Tz(d)
 * (Rz and Tz commute with Mot_z, so the offsets may follow the motion). As a URDF-style link tree
 * (import.h), link i's frame is L_i = F_(i-1) A_i Mot_z(q_i), so joint i's origin in link i-1's
 * frame is B_(i-1) A_i (B_0 = 1), its axis z, and link i's DH frame is L_i B_i: its centre of
 * mass in L_i is B_i c and its inertia R_B I R_B^T. import_bodies then turns the tree into bodies
 * whose frames are parallel to the world's at q = 0.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "import.h"
#include "job_parse.h"

const char *const dh_keys[] = {"convention", "rows", NULL};
const char *const dh_row_keys[] = {"name",  "type", "a",   "alpha",   "d",
                                   "theta", "mass", "com", "inertia", NULL};

/* a rigid transform: x -> R x + p */
typedef struct xform {
    double R[9], p[3];
} xform;

static xform xf_identity(void)
{
    xform t = {{1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 0, 0}};
    return t;
}

/* a b: first b, then a */
static xform xf_mul(const xform *a, const xform *b)
{
    xform t;
    import_mat_mul(a->R, b->R, t.R);
    import_mat_vec(a->R, b->p, t.p);
    for (int i = 0; i < 3; i++) t.p[i] += a->p[i];
    return t;
}

/* Rz(theta) Tz(d) */
static xform xf_rz_tz(double theta, double d)
{
    double c = cos(theta), s = sin(theta);
    xform t = {{c, -s, 0, s, c, 0, 0, 0, 1}, {0, 0, d}};
    return t;
}

/* Rx(alpha) Tx(a) (= Tx(a) Rx(alpha)) */
static xform xf_rx_tx(double alpha, double a)
{
    double c = cos(alpha), s = sin(alpha);
    xform t = {{1, 0, 0, 0, c, -s, 0, s, c}, {a, 0, 0}};
    return t;
}

typedef struct dh_row {
    int prismatic;
    double a, alpha, d, theta;
    double mass, com[3], inertia[9];
    const char *name;
} dh_row;

static const char *const conventions[] = {"standard", "modified"};
static const char *const row_types[] = {"revolute", "prismatic"};

static int parse_row(parser *p, const cJSON *v, int i, dh_row *r, char *name_buf)
{
    char path[PATH_LEN], at[PATH_LEN];
    json_index_path(path, "scene.dh.rows", i);
    if (json_object_at(p, v, path) != 0 ||
        json_check_keys(p, v, path, dh_row_keys, NULL, NULL) != 0) {
        return -1;
    }
    const cJSON *name = json_member(v, "name");
    if (name != NULL) {
        if (json_name_at(p, name, json_key_path(at, path, "name"), &r->name) != 0) return -1;
    } else {
        snprintf(name_buf, 32, "link%d", i + 1);
        r->name = name_buf;
    }
    const cJSON *type = json_member(v, "type");
    if (type != NULL &&
        json_enum_at(p, type, json_key_path(at, path, "type"), row_types, 2, &r->prismatic) != 0)
        return -1;
    if (json_member_number(p, v, path, "a", REQUIRED, 0, &r->a) != 0 ||
        json_member_number(p, v, path, "alpha", REQUIRED, 0, &r->alpha) != 0 ||
        json_member_number(p, v, path, "d", REQUIRED, 0, &r->d) != 0 ||
        json_member_number(p, v, path, "theta", OPTIONAL, 0, &r->theta) != 0 ||
        json_member_number(p, v, path, "mass", REQUIRED, 0, &r->mass) != 0) {
        return -1;
    }
    if (r->mass < 0) { /* 0: a massless link (Puma 560's first); the builder checks M(q) */
        return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, "mass"),
                             "must not be negative (got %g kg)", r->mass);
    }
    if (json_member_vec3(p, v, path, "com", REQUIRED, NULL, r->com) != 0) return -1;
    const cJSON *inertia = json_required_member(p, v, path, "inertia", "");
    int diagonal;
    if (inertia == NULL || json_matrix3_at(p, inertia, json_key_path(at, path, "inertia"),
                                           "principal moments", r->inertia, &diagonal) != 0) {
        return -1;
    }
    return 0;
}

int parse_scene_dh(parser *p, const cJSON *dh, cJSON **bodies)
{
    *bodies = NULL;
    if (json_object_at(p, dh, "scene.dh") != 0 ||
        json_check_keys(p, dh, "scene.dh", dh_keys, NULL, NULL) != 0) {
        return -1;
    }
    int modified;
    const cJSON *conv = json_required_member(p, dh, "scene.dh", "convention", "");
    if (conv == NULL ||
        json_enum_at(p, conv, "scene.dh.convention", conventions, 2, &modified) != 0)
        return -1;
    const cJSON *rows = json_required_member(p, dh, "scene.dh", "rows", "");
    if (rows == NULL) return -1;
    if (!cJSON_IsArray(rows)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "scene.dh.rows",
                             "must be an array of rows (got %s)", json_kind(rows));
    }
    int n = cJSON_GetArraySize(rows);
    if (n == 0)
        return json_error_at(p->err, JOB_INVALID_FIELD, "scene.dh.rows", "must not be empty");
    if (n > JOB_MAX_BODIES) {
        return json_error_at(p->err, JOB_LIMIT_EXCEEDED, "scene.dh.rows",
                             "has %d rows; the limit is %d", n, JOB_MAX_BODIES);
    }
    dh_row *r = json_alloc(p, (size_t)n, sizeof *r);
    import_link *links = json_alloc(p, (size_t)n + 1, sizeof *links);
    char(*names)[32] = json_alloc(p, (size_t)n, sizeof *names);
    int rc = -1;
    if (r == NULL || links == NULL || names == NULL) goto done;
    int i = 0;
    for (const cJSON *v = rows->child; v != NULL; v = v->next, i++)
        if (parse_row(p, v, i, &r[i], names[i]) != 0) goto done;

    /* link 0, the base, is DH frame 0: the world's */
    links[0].name = "base";
    links[0].parent = -1;
    links[0].type = CTC_JOINT_FIXED;
    xform prev_b = xf_identity(); /* B_(i-1) */
    for (i = 0; i < n; i++) {
        import_link *l = &links[i + 1];
        xform a = modified ? xf_rx_tx(r[i].alpha, r[i].a) : xf_identity();
        xform b = xf_rz_tz(r[i].theta, r[i].d);
        if (!modified) {
            xform rest = xf_rx_tx(r[i].alpha, r[i].a);
            b = xf_mul(&b, &rest);
        }
        xform origin = xf_mul(&prev_b, &a);
        l->name = r[i].name;
        l->joint_name = r[i].name;
        l->parent = i;
        l->type = r[i].prismatic ? CTC_JOINT_PRISMATIC : CTC_JOINT_REVOLUTE;
        memcpy(l->origin_rot, origin.R, sizeof origin.R);
        memcpy(l->origin_pos, origin.p, sizeof origin.p);
        l->axis[0] = l->axis[1] = 0;
        l->axis[2] = 1;
        /* link i's inertial data from DH frame i (L_i B_i) into L_i */
        double RI[9], Rt[9];
        l->has_inertial = 1;
        l->mass = r[i].mass;
        import_mat_vec(b.R, r[i].com, l->com);
        for (int k = 0; k < 3; k++) l->com[k] += b.p[k];
        for (int k = 0; k < 3; k++)
            for (int m = 0; m < 3; m++) Rt[3 * k + m] = b.R[3 * m + k];
        import_mat_mul(b.R, r[i].inertia, RI);
        import_mat_mul(RI, Rt, l->inertia);
        prev_b = b;
    }
    char msg[512];
    *bodies = import_bodies(links, n + 1, msg, sizeof msg);
    if (*bodies == NULL) {
        if (strcmp(msg, "out of memory") == 0)
            json_out_of_memory(p->err);
        else
            json_error_at(p->err, JOB_INVALID_FIELD, "scene.dh", "%s", msg);
        goto done;
    }
    rc = 0;
done:
    free(r);
    free(links);
    free(names);
    return rc;
}

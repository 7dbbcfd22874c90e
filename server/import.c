/*
 * import.c - a tree of URDF-style links into the job's bodies (import.h): the frame conversion
 * and the merging of fixed joints.
 *
 * Frames. In URDF a link k's frame is its parent P's frame moved by the joint's origin (rotation
 * R_k, translation p_k) and then by the joint's motion about (or along) the axis a_k, given in
 * the joint's frame, which is the child's:  T_k(q) = T_P(q) [R_k, p_k] Mot(a_k, q_k).
 * ctcsim's body frame (model.h) has its origin at the joint's centre but is parallel to the
 * world's at q = 0. With R0_k the world rotation of link k at q = 0 (R0_root = 1,
 * R0_k = R0_P R_k), ctcsim's frame of body k is the URDF link frame rotated by R0_k^T:
 *   C_k(q) = T_k(q) [R0_k^T, 0].
 * Then the ctcsim joint is a motion about a fixed axis of the parent's ctcsim frame:
 *   C_P^-1 C_k = [R0_P, 0] [R_k, p_k] Mot(a_k, q) [R0_k^T, 0]
 *              = [1, R0_P p_k] [R0_P R_k, 0] Mot(a_k, q) [(R0_P R_k)^T, 0]
 *              = [1, R0_P p_k] Mot(R0_k a_k, q),
 * since conjugating a rotation (or translation) about a by R gives one about R a. So:
 *   joint location = R0_P p_k            (the parent's joint centre is its frame's origin)
 *   joint axis     = R0_k a_k            (= R0_P R_k a_k, in the parent's ctcsim frame)
 *   centre of mass = R0_k c_k            (c_k in the link frame)
 *   inertia        = R0_k I_k R0_k^T     (I_k about the centre of mass, link-frame axes)
 * A fixed joint keeps C_k parallel to C_P at every q, so its child is part of the parent's body:
 * at offset o_k = o_P + R0_P p_k from the body's origin, its centre of mass at o_k + R0_k c_k.
 * A body's mass properties sum its links' about the body's origin, m, h = sum m c and
 * J = sum (I_c + m ([c]x^T [c]x)), and go back to the centre of mass: c = h / m,
 * I = J - m [c]x^T [c]x (parallel axis theorem); a massless body (m = 0) keeps J about its
 * origin, c = 0. The root and its fixed descendants are the ground (their masses play no part).
 * Moving bodies without mass go to the model builder, which accepts them where the joint-space
 * mass matrix stays positive definite (model.h "singular bodies").
 * A link's visual shape at (R_v, p_v) in its link frame is in its body's frame at
 * (R0_k R_v, o_k + R0_k p_v), as its centre of mass is.
 */
#include "import.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void import_rpy(const double rpy[3], double R[9])
{
    double cr = cos(rpy[0]), sr = sin(rpy[0]);
    double cp = cos(rpy[1]), sp = sin(rpy[1]);
    double cy = cos(rpy[2]), sy = sin(rpy[2]);
    /* Rz(yaw) Ry(pitch) Rx(roll) */
    R[0] = cy * cp;
    R[1] = cy * sp * sr - sy * cr;
    R[2] = cy * sp * cr + sy * sr;
    R[3] = sy * cp;
    R[4] = sy * sp * sr + cy * cr;
    R[5] = sy * sp * cr - cy * sr;
    R[6] = -sp;
    R[7] = cp * sr;
    R[8] = cp * cr;
}

void import_mat_mul(const double a[9], const double b[9], double c[9])
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            c[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
}

void import_mat_vec(const double R[9], const double x[3], double y[3])
{
    for (int i = 0; i < 3; i++) y[i] = R[3 * i] * x[0] + R[3 * i + 1] * x[1] + R[3 * i + 2] * x[2];
}

/* J += m ([c]x^T [c]x) = m (|c|^2 1 - c c^T): a point mass m at c, about the origin */
static void add_point_inertia(double J[9], double m, const double c[3])
{
    double cc = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) J[3 * i + j] += m * ((i == j ? cc : 0) - c[i] * c[j]);
}

/* x as cJSON prints and reads it back. cJSON 1.7 prints 15 significant digits whenever they read
 * back within DBL_EPSILON relative, so a computed number may come back one unit in the last place
 * off; replaced by that reading (a change within DBL_EPSILON relative), it prints and reads back
 * exactly, and a printed job parses to the same spec. */
static double printed(double x)
{
    char buf[32];
    snprintf(buf, sizeof buf, "%1.15g", x);
    double y = strtod(buf, NULL);
    return fabs(y - x) <= fmax(fabs(x), fabs(y)) * DBL_EPSILON ? y : x;
}

/* cJSON array of the n numbers x, each printed() */
static cJSON *numbers(const double *x, int n)
{
    double y[3];
    for (int i = 0; i < n; i++) y[i] = printed(x[i]);
    return cJSON_CreateDoubleArray(y, n);
}

/* a body being assembled: its links' mass properties about its origin */
typedef struct body_acc {
    int link;   /* the link whose moving joint starts the body */
    int parent; /* the body it hangs from, -1 the ground */
    double axis[3], location[3];
    double m, h[3], J[9];
} body_acc;

/* the body's JSON: name, parent, mass, com, inertia rows, joint (the format's order); NULL when
 * an allocation fails */
static cJSON *body_json(const body_acc *b, import_link *l)
{
    double c[3], I[9]; /* a massless body: its lumped inertia J about its origin */
    for (int i = 0; i < 3; i++) c[i] = b->m > 0 ? b->h[i] / b->m : 0;
    memcpy(I, b->J, sizeof I);
    add_point_inertia(I, -b->m, c);
    for (int i = 0; i < 3; i++) /* exactly symmetric */
        for (int j = 0; j < i; j++)
            I[3 * i + j] = I[3 * j + i] = 0.5 * (I[3 * i + j] + I[3 * j + i]);

    cJSON *o = cJSON_CreateObject();
    if (o == NULL) return NULL;
    int ok = cJSON_AddStringToObject(o, "name", l->name) != NULL &&
             cJSON_AddNumberToObject(o, "parent", b->parent) != NULL &&
             cJSON_AddNumberToObject(o, "mass", printed(b->m)) != NULL &&
             cJSON_AddItemToObject(o, "com", numbers(c, 3));
    cJSON *rows = cJSON_AddArrayToObject(o, "inertia");
    for (int i = 0; ok && rows != NULL && i < 3; i++)
        ok = cJSON_AddItemToArray(rows, numbers(&I[3 * i], 3));
    cJSON *joint = cJSON_AddObjectToObject(o, "joint");
    ok = ok && rows != NULL && joint != NULL &&
         cJSON_AddStringToObject(joint, "type", ctc_joint_classes[l->type].name) != NULL &&
         cJSON_AddItemToObject(joint, "axis", numbers(b->axis, 3)) &&
         cJSON_AddItemToObject(joint, "location", numbers(b->location, 3));
    while (ok && l->extra != NULL && l->extra->child != NULL) {
        cJSON *e = cJSON_DetachItemViaPointer(l->extra, l->extra->child);
        if (!cJSON_AddItemToObject(joint, e->string, e)) {
            cJSON_Delete(e);
            ok = 0;
        }
    }
    if (!ok) {
        cJSON_Delete(o);
        return NULL;
    }
    return o;
}

/* link l's visual v, at offset o in its body whose frame is R0 (the link's world rotation at
 * q = 0), as the body's "visuals" entry; NULL when an allocation fails */
static cJSON *visual_json(const import_visual *v, const double R0[9], const double o[3])
{
    static const char *const names[3] = {"box", "cylinder", "sphere"};
    double pos[3], rot[9];
    import_mat_vec(R0, v->pos, pos);
    for (int i = 0; i < 3; i++) pos[i] += o[i];
    import_mat_mul(R0, v->rot, rot);
    cJSON *j = cJSON_CreateObject();
    int ok = j != NULL && cJSON_AddStringToObject(j, "type", names[v->type]) != NULL;
    if (v->type == IMPORT_BOX) ok = ok && cJSON_AddItemToObject(j, "size", numbers(v->size, 3));
    if (v->type != IMPORT_BOX)
        ok = ok && cJSON_AddNumberToObject(j, "radius", printed(v->size[0])) != NULL;
    if (v->type == IMPORT_CYLINDER)
        ok = ok && cJSON_AddNumberToObject(j, "length", printed(v->size[1])) != NULL;
    ok = ok && cJSON_AddItemToObject(j, "origin", numbers(pos, 3));
    if (v->type != IMPORT_SPHERE) {
        cJSON *rows = cJSON_AddArrayToObject(j, "rotation");
        for (int i = 0; ok && rows != NULL && i < 3; i++)
            ok = cJSON_AddItemToArray(rows, numbers(&rot[3 * i], 3));
        ok = ok && rows != NULL;
    }
    if (!ok) {
        cJSON_Delete(j);
        return NULL;
    }
    return j;
}

cJSON *import_bodies(import_link *links, int n, char *msg, size_t msg_len)
{
    cJSON *out = NULL;
    double(*R0)[9] = malloc((size_t)n * sizeof *R0);
    double(*off)[3] = malloc((size_t)n * sizeof *off);
    int *group = malloc((size_t)n * sizeof *group);
    body_acc *bodies = calloc((size_t)n, sizeof *bodies);
    int nb = 0;
    if (R0 == NULL || off == NULL || group == NULL || bodies == NULL) {
        snprintf(msg, msg_len, "out of memory");
        goto done;
    }

    /* world rotations at q = 0, bodies, offsets in them; mass properties about body origins */
    for (int k = 0; k < n; k++) {
        import_link *l = &links[k];
        if (k == 0) {
            static const double one[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
            memcpy(R0[0], one, sizeof one);
            group[0] = -1;
            off[0][0] = off[0][1] = off[0][2] = 0;
        } else {
            int P = l->parent;
            double loc[3];
            import_mat_mul(R0[P], l->origin_rot, R0[k]);
            import_mat_vec(R0[P], l->origin_pos, loc);
            for (int i = 0; i < 3; i++) loc[i] += off[P][i];
            if (l->type == CTC_JOINT_FIXED) {
                group[k] = group[P];
                memcpy(off[k], loc, sizeof loc);
            } else {
                body_acc *b = &bodies[nb];
                b->link = k;
                b->parent = group[P];
                import_mat_vec(R0[k], l->axis, b->axis);
                double len = sqrt(b->axis[0] * b->axis[0] + b->axis[1] * b->axis[1] +
                                  b->axis[2] * b->axis[2]);
                for (int i = 0; i < 3; i++) b->axis[i] /= len;
                memcpy(b->location, loc, sizeof loc);
                group[k] = nb++;
                off[k][0] = off[k][1] = off[k][2] = 0;
            }
        }
        if (!l->has_inertial || group[k] < 0) continue;
        body_acc *b = &bodies[group[k]];
        double c[3], RI[9], I[9], Rt[9];
        import_mat_vec(R0[k], l->com, c);
        for (int i = 0; i < 3; i++) c[i] += off[k][i];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) Rt[3 * i + j] = R0[k][3 * j + i];
        import_mat_mul(R0[k], l->inertia, RI);
        import_mat_mul(RI, Rt, I);
        b->m += l->mass;
        for (int i = 0; i < 3; i++) b->h[i] += l->mass * c[i];
        for (int i = 0; i < 9; i++) b->J[i] += I[i];
        add_point_inertia(b->J, l->mass, c);
    }
    if (nb == 0) {
        snprintf(msg, msg_len, "no joint moves (every joint is fixed)");
        goto done;
    }

    /* a moving body without mass (a link without <inertial>, a massless frame between two
       joints) is a singular body: the model builder accepts it where the joint-space mass
       matrix stays positive definite and names it where not (model.h "singular bodies") */

    out = cJSON_CreateArray();
    for (int b = 0; out != NULL && b < nb; b++) {
        cJSON *o = body_json(&bodies[b], &links[bodies[b].link]);
        if (o == NULL || !cJSON_AddItemToArray(out, o)) {
            cJSON_Delete(o);
            cJSON_Delete(out);
            out = NULL;
        }
    }
    /* the links' visual shapes, in their bodies' frames, in link order */
    for (int k = 0; out != NULL && k < n; k++) {
        if (group[k] < 0 || links[k].nvisuals == 0) continue;
        cJSON *body = cJSON_GetArrayItem(out, group[k]),
              *list = cJSON_GetObjectItem(body, "visuals");
        if (list == NULL) list = cJSON_AddArrayToObject(body, "visuals");
        for (int v = 0; list != NULL && v < links[k].nvisuals; v++) {
            cJSON *o = visual_json(&links[k].visuals[v], R0[k], off[k]);
            if (o == NULL || !cJSON_AddItemToArray(list, o)) {
                cJSON_Delete(o);
                list = NULL;
            }
        }
        if (list == NULL) {
            cJSON_Delete(out);
            out = NULL;
        }
    }
    if (out == NULL) snprintf(msg, msg_len, "out of memory");
done:
    for (int k = 0; k < n; k++) {
        cJSON_Delete(links[k].extra);
        links[k].extra = NULL;
    }
    free(R0);
    free(off);
    free(group);
    free(bodies);
    return out;
}

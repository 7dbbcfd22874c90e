/*
 * import.h - a robot described as a tree of links (URDF's frames: each link's frame placed by its
 * joint's origin in the parent link's frame, the joint's axis in the child's frame) converted
 * into the job format's "bodies" (job_json.h), whose frames follow model.h: parallel to the
 * world's when every joint coordinate is zero.
 *
 * urdf.c (URDF XML) and dh.c (Denavit-Hartenberg tables) each fill an array of import_link and
 * call import_bodies, which does the frame conversion and merges fixed joints; the derivation is
 * at the top of import.c.
 */
#ifndef IMPORT_H
#define IMPORT_H

#include <stddef.h>

#include <cjson/cJSON.h>

#include "model.h"

/* A visual shape of a link (URDF's <visual> with a <box>, <cylinder> or <sphere>), kept for the
 * page's animation: the simulation does not use it. */
typedef enum import_shape { IMPORT_BOX, IMPORT_CYLINDER, IMPORT_SPHERE } import_shape;
typedef struct import_visual {
    import_shape type;
    double size[3]; /* m: a box's edges along its axes; a cylinder's radius and length (along its
                       z axis); a sphere's radius */
    double pos[3];  /* m, the shape's centre in the link frame */
    double rot[9];  /* its axes in the link frame (row-major) */
} import_visual;

/* One link and the joint from its parent. Names are the caller's (kept only until
 * import_bodies returns). */
typedef struct import_link {
    const char *name;       /* the link's name, for the body's "name" and for messages */
    const char *joint_name; /* the joint's name, for messages (NULL for the root) */
    int line;               /* the source line of the link's element (0: none), for messages */
    int parent;             /* the parent link's index, < this link's index; -1 for the root,
                               link 0, which is fixed to the world (its frame is the world's) */
    ctc_joint_type type;    /* REVOLUTE, PRISMATIC or FIXED: the joint from the parent */
    double origin_rot[9];   /* the joint frame's rotation in the parent link's frame (row-major) */
    double origin_pos[3];   /* m, the joint frame's origin in the parent link's frame */
    double axis[3];         /* the joint's axis in the joint (= child link) frame, non-zero */
    int has_inertial;       /* 0: a massless link (mass and the two below are ignored) */
    double mass;            /* kg, >= 0 */
    double com[3];          /* m, centre of mass in the link frame */
    double inertia[9];      /* kg m^2, about the centre of mass, link-frame axes, row-major */
    cJSON *extra;           /* NULL, or keys kept in the body's "joint" for other uses ("limit",
                               "dynamics"); moved into the result (import_bodies takes it) */
    const import_visual *visuals; /* (nvisuals) the link's shapes; the caller's */
    int nvisuals;
} import_link;

/* The job's bodies for links[0..n-1] (n >= 1, links[0] the root): one body per link whose joint
 * moves, in link order, each with "name", "parent" (the index of the body it hangs from, -1 for
 * the ground), "mass", "com", "inertia" (3 rows) and "joint" {"type", "axis", "location", and
 * the link's extra keys}. A fixed joint's child (and the root's fixed descendants, the ground) is
 * merged into the body it is fixed to: its mass, centre of mass and inertia added there (parallel
 * axis theorem), its children's joints re-placed in that body's frame. Each number is the one
 * cJSON prints and reads back (within DBL_EPSILON relative of the computed one), so a printed job
 * parses to the same spec. A body's "visuals" (when its links have any) lists every shape of its
 * links in the body's frame: {"type": "box", "size": [3]} | {"type": "cylinder", "radius",
 * "length"} | {"type": "sphere", "radius"}, each with "origin" (m, the centre) and, but for a
 * sphere, "rotation" (3 rows, the shape's axes). Returns the array (the
 * caller owns it; the links' extra objects are moved into it or freed), or NULL with msg filled
 * ("out of memory", or "no joint moves (every joint is fixed)"). A moving body without mass is
 * converted (mass 0, its lumped inertia about its origin); the model builder decides on it. */
cJSON *import_bodies(import_link *links, int n, char *msg, size_t msg_len);

/* Rotation matrices, row-major: R = Rz(yaw) Ry(pitch) Rx(roll) (URDF's rpy, fixed axes x, y, z). */
void import_rpy(const double rpy[3], double R[9]);

/* c = a b (3x3, row-major). c may not alias a or b. */
void import_mat_mul(const double a[9], const double b[9], double c[9]);

/* y = R x. y may not alias x. */
void import_mat_vec(const double R[9], const double x[3], double y[3]);

#endif

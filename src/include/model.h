/*
 * model.h - rigid bodies, joints and a kinematic tree on a fixed base: the constant model.
 *
 * A model is built once from a ctc_chain_spec, validated, and is read-only afterwards, so any
 * number of threads may share it. Everything that changes with the state lives in ctc_data
 * (data.h).
 *
 * Conventions (SI units, radians; see DESIGN.md section 2):
 *  - Bodies are numbered 0..n-1 from the base, each after its parent; joint k connects body k's
 *    parent, body_parent[k] (ctc_chain_spec.parent; in a chain body k-1, the ground for k = 0),
 *    to body k. Body k's handle 1 is its inboard joint k, handle 2 its heavy child's joint (in a
 *    chain its child's, k+1; model.h body_heavy).
 *  - Each body has a frame. Its origin is the centre of joint k and, when all joint coordinates
 *    are zero, its axes are parallel to its parent's, hence to the world's. A joint's axis and
 *    location are given in the parent's frame (the world's for joint 0); a body's centre of mass
 *    and inertia in its own frame.
 *  - Joint coordinates are relative (child to parent), positive by the right-hand rule about the
 *    joint axis:
 *      revolute     nq = nv = 1: angle q about the axis.
 *      prismatic    nq = nv = 1: displacement q along the axis.
 *      cylindrical  nq = nv = 2: (angle about, displacement along) the axis.
 *      spherical    nq = 4, nv = 3: unit quaternion (w, x, y, z) of the child's orientation
 *                   relative to the parent; velocity = the child's angular velocity relative to
 *                   the parent, in the child's frame. The axis is ignored.
 *      fixed        nq = nv = 0.
 *    The generalised force of a coordinate is its conjugate: the torque about the axis, the force
 *    along it, or for a spherical joint the torque vector in the child's frame, each applied by
 *    the parent on the child.
 *  - Planar form: when every joint moves in one plane (revolute axes normal to it, prismatic axes
 *    in it; fixed joints allowed) and gravity lies in that plane, the model is computed with
 *    planar 3-vectors (omega_z, v_x, v_y) in the plane's coordinates. The plane's normal n is the
 *    first revolute axis; without one, the normal of two non-parallel prismatic axes, or of a
 *    prismatic axis and gravity, or any normal of a lone prismatic axis; its sign is chosen so its
 *    largest component is positive, so a chain with +z or -z axes moves in the x-y plane itself.
 *  - One kinematic loop (optional, ctc_loop_spec): a closing joint, numbered n, joins the tip body
 *    n-1 (its parent) to the ground or to a body b <= n-2 of the chain (its child), so bodies
 *    0..n-1 and the ground, or bodies b..n-1, form a loop. The loop's joints are b+1..n (0..n
 *    on the ground, where b = -1); joints 0..b carry the loop as a whole. The closing joint
 *    follows the same conventions as a chain joint with the tip as the parent: its axis and
 *    centre are given in the tip's frame, its coordinate is the child's motion relative to the
 *    tip (for a revolute closing joint the child's frame is Rot(axis, q_n) of the tip's frame, so
 *    a planar loop of revolute joints on the ground has q_0 + ... + q_n = 0 mod 2 pi, and one on
 *    body b has q_(b+1) + ... + q_n = 0), and its generalised force is applied by the tip on the
 *    child. The closing joint's coordinates are not part of the state q, v: they follow from the
 *    chain's (loop.h). The child's side of the joint is the anchor, a point fixed in the world
 *    (ground) or in body b's frame; when the loop is closed the anchor coincides with the
 *    closing joint's centre on the tip.
 *    On a branched tree the loop lies on the spine, the path from the ground to the tip: b must
 *    be an ancestor of the tip (or the loop closes on the ground) and the tree must have one body
 *    on the ground; the loop's joints are then the spine's after b and the closing joint
 *    (jnt_loop), not b+1..n, and every other joint is outside the loop. A loop between two
 *    branches is refused.
 *  - Independent and dependent joints: in a loop model each joint, the closing one included, is
 *    independent (actuated: a controller drives its coordinates along a trajectory) or dependent
 *    (passive: no driving force; its motion follows from the loop). An open chain's joints are
 *    all independent, and so are the joints outside a loop closed on a body (0..b), unless every
 *    joint is dependent (a passive run). "Extended" coordinate vectors list the chain's nv velocity
 * coordinates and then the closing joint's (nvx = nv + loop_nv); forces and accelerations of loop
 * models are extended vectors (gdca.h).
 */
#ifndef CTC_MODEL_H
#define CTC_MODEL_H

#include <stddef.h>

#include "status.h"

#define CTC_MAX_BODIES 1000000
#define CTC_JOINT_MAX_NV 3 /* spherical */
#define CTC_JOINT_MAX_NQ 4 /* spherical (quaternion) */

/* The built-in kinds of joint, as indices of ctc_joint_classes (joint.c). */
typedef enum ctc_joint_type {
    CTC_JOINT_REVOLUTE,
    CTC_JOINT_PRISMATIC,
    CTC_JOINT_CYLINDRICAL,
    CTC_JOINT_SPHERICAL,
    CTC_JOINT_FIXED,
} ctc_joint_type;

#define CTC_JOINT_NTYPES 5

/* ---- the table of joint kinds ----
 *
 * A kind of joint is one ctc_joint_class, one row of ctc_joint_classes (src/model/joint.c) at the
 * index of its ctc_joint_type. Everything that only sorts or counts joints reads the row: the
 * coordinate counts (ctc_joint_nq, ctc_joint_nv, hence jnt_qadr, jnt_vadr), the names
 * (ctc_joint_type_name, ctc_joint_type_of), the builder's checks (model.c: a known type, the
 * axis, planar or not, the loop's closing joint), the run's checks (sim_check.c: no controller
 * drives an `undriven` kind) and units (sim.c: linear_mask), and the job format
 * (server/job_scene.c: the type names, each type's keys, the loop's types, "axis" required or not
 * allowed; server/job_json.c: the joints a controller cannot drive). The web page keeps its own
 * copy of nq and nv (web/joints.js), which tests/api/joints.test.mjs checks against `ctcsim
 * validate`.
 *
 * The motion itself is physics and stays a switch on the type in the functions that compute it.
 * A new kind is its enum value, its row, and its case in each of:
 *   src/model/kinematics.c: kinematics_spatial (the joint's rotation, translation, motion map P,
 *       complement D and velocity product beta, DESIGN.md section 4); kinematics_planar too if
 *       it is `planar`
 *   src/reference/oracle.c: ctc_oracle_joint_model (the independent oracle's transform and
 *       motion subspace, Featherstone's Table 4.1)
 *   src/model/model.c: chain_is_planar, plane_normal, setup_planar if it is `planar` (how its
 *       axis must lie in the plane and what it does there); ctc_model_q_zero, ctc_model_q_add,
 *       ctc_model_q_rate, ctc_model_q_normalize if its q is not a vector (nq != nv)
 *   src/model/loop.c: loop_planar, loop_spatial if it is `loop_closing` (the closing joint's
 *       coordinates and constraint)
 *   server/job_scene.c: parse_initial_state if its q0 has a constraint of its own (the
 *       spherical joint's unit quaternion)
 *   api/job.schema.json: the joint's "type" enum and "axis" rule, and the loop's if it is
 *       `loop_closing` (tests/unit/test_job_format.c checks them against the rows); the format's
 *       comment in server/job_json.h
 *   web/kinematics.js: chainPose (the page's animation), and its row in web/joints.js
 * Optional fast paths: src/dynamics/gdca_tree.h gdca_joint_factor_typed, gdca_hinge_u,
 * gdca_factor_apply_typed, gdca_mul_E_typed (any other kind takes the generic kernels).
 * Tests: tests/unit/test_joint.c checks every row against the oracle and the builder; add the
 * kind to the random chains of tests/support/chains.c (test_chain_random_spatial draws every type
 * in TEST_ALL_JOINTS), which the kinematics, oracle and GDCA tests run on. */
typedef struct ctc_joint_class {
    const char *name;     /* "revolute": its name in jobs, results and messages */
    int nq;               /* position coordinates, <= CTC_JOINT_MAX_NQ */
    int nv;               /* velocity coordinates = generalised forces, <= CTC_JOINT_MAX_NV */
    int needs_axis;       /* 1: ctc_joint_spec.axis is required (non-zero, normalised by the
                             builder) and a job must give "axis"; 0: the axis is ignored (zeroed
                             by the builder) and a job must not give one */
    int planar;           /* 1: may appear in a planar chain (model.c: chain_is_planar) */
    int loop_closing;     /* 1: may be a loop's closing joint (ctc_loop_spec) */
    const char *undriven; /* NULL: a controller may drive it (its tracking error is per
                             coordinate); else why none can, for messages ("its quaternion error
                             is not a per-coordinate error"): passive runs only, or a loop's
                             dependent joint */
    unsigned linear_mask; /* bit i: velocity coordinate i is a translation (m, m/s, N); clear:
                             a rotation (rad, rad/s, N m) */
} ctc_joint_class;

extern const ctc_joint_class ctc_joint_classes[CTC_JOINT_NTYPES];

/* The row of type t, or NULL when t is not a ctc_joint_type. */
const ctc_joint_class *ctc_joint_class_of(ctc_joint_type t);

/* The type named name ("revolute", ...), or -1 for none (NULL included). */
int ctc_joint_type_of(const char *name);

/* Which algebra the dynamics use. */
typedef enum ctc_form {
    CTC_FORM_AUTO = 0, /* spec only: planar when the chain is planar, else spatial */
    CTC_FORM_PLANAR,   /* 3-vectors and 3x3 matrices in the plane of motion */
    CTC_FORM_SPATIAL,  /* 6-vectors and 6x6 matrices */
} ctc_form;

typedef struct ctc_body_spec {
    double mass;       /* kg, >= 0 (0: a massless body, a frame or a lumped rotor inertia) */
    double com[3];     /* m, centre of mass in the body frame */
    double inertia[9]; /* kg m^2, about the centre of mass, body-frame axes, row-major, symmetric,
                          positive semidefinite (0: a point mass); with mass > 0 its principal
                          moments satisfy the triangle inequality, as any distribution of mass's
                          do; a massless body's inertia is a lumped one and need not */
} ctc_body_spec;

/* ---- singular bodies and the model check's thresholds ----
 *
 * A body is singular when its spatial (planar: 3x3) inertia about its centre of mass has no
 * inverse: mass <= CTC_MASS_ZERO_REL times the chain's largest body mass (a massless body), or,
 * in spatial form, a principal moment <= CTC_INERTIA_ZERO_REL times the body's largest (a point
 * mass, a slender rod, Puma 560's link 1 with inertia about one axis only), or, in planar form, a
 * moment about the plane normal <= CTC_INERTIA_ZERO_REL times the body's inertia trace. The
 * forward pass's handle equations need each body's inverse inertia (handles.h), so for a
 * singular body they use an augmented one: CTC_SINGULAR_AUGMENT_REL times the smallest inertia
 * about its own joint among the body and its descendants, m |c|^2 + trace(I) / 2, added to each
 * principal moment, and, to a massless body's mass, that fraction of the smallest mass among them
 * (model.c setup_singular; fwd_bodies, planar[k].fwd_*). The composite inverse pass inverts no
 * body (gdca_inverse.c) and stays exact, and the forward pass's refinement (gdca_refine.h: up to
 * CTC_REFINE_SINGULAR_STEPS steps) corrects the augmented result against it: each step shrinks
 * the error by about the augmentation's share of the joint-space inertia, 1e-6 to 1e-5, so two
 * steps reach rounding. 1e-6 is measured (bench/NOTEBOOK.md, "Singular bodies"): 1e-4 needs
 * three steps, 1e-8 and less lose digits to the augmented bodies' own conditioning. The joint-space
 * mass matrix M(q) must then be positive definite: with a singular body the builder factors M at a
 * generic configuration (each coordinate q_i = sin(i + 1), each quaternion normalised from (1, 0.1
 * sin(i + 1), 0.2, 0.3)) and refuses a pivot <= CTC_MASS_MATRIX_PIVOT_REL times its own
 * diagonal entry (the share of the coordinate's inertia that the coordinates before it leave;
 * own, not the largest entry's, since a long chain's tip has 6e-11 of the base's at 4096 point
 * masses; an entry under 1e-15 of the largest counts as 0), naming the joint's body: a massless tip
 * on a moving joint, a point mass on a revolute axis through it. A loop model is held to the same
 * test on the closure's tangent space at that configuration (the reduced mass matrix Z^T M Z, Z a
 * basis of the null space of the closure's Jacobian G, loop.h; tested as M + rho G^T G with G's
 * rows scaled to 1 and rho the largest diagonal entry of M, positive definite exactly when Z^T M Z
 * is): a massless tip that the closing joint holds is accepted, one whose turning the closure
 * leaves free is refused
 * ("body 4: the loop's joint-space mass matrix is singular: ..., nor does the loop's closure hold
 * it"). Its forward pass is augmented and refined alike (the refinement's residual carries the
 * closure, gdca_refine.h; a massless tip's augmentation takes the model's smallest inertia and
 * mass), and its CTC inverse inverts no body (gdca_inverse_loop.h). Models without a singular
 * body skip all of this and are unchanged. A body on a fixed joint (a massless frame, say) is
 * merged into its parent's for the passes (see "merged bodies"): nsingular, body_singular and
 * fwd_bodies describe the model as given, m->dyn's what the passes augment; the mass-matrix check
 * runs on the model as given, unless merging leaves no singular body (every body then has a
 * positive definite inertia, and so has M(q)). */
#define CTC_MASS_ZERO_REL 1e-12
#define CTC_INERTIA_ZERO_REL 1e-12
#define CTC_SINGULAR_AUGMENT_REL 1e-6
#define CTC_MASS_MATRIX_PIVOT_REL 1e-10

/* ---- slender bodies ----
 *
 * A body of a spatial model that is not singular but whose smallest principal moment is
 * under CTC_SLENDER_RATIO times its largest (a rod, a thin beam) is slender. The forward pass's
 * handle equations carry its inverse inertia, and rounding there costs about eps times the
 * body's largest / smallest moment in qdd whether or not any joint spins the body about its thin
 * axis (bench/NOTEBOOK.md, "Slender bodies (issue 18)": 16 rods at a ratio of 1e-10 lose 1e-5 of
 * qdd, 256 rods at 1e-6 lose the joint factor's positive definiteness). So fwd_bodies gives a
 * slender body CTC_SLENDER_AUGMENT_REL times its largest moment on each principal moment (an
 * isotropic addition: the principal axes stay and the triangle inequality holds), which bounds
 * its moment ratio at about that fraction, and the forward pass's refinement (gdca_refine.h:
 * CTC_REFINE_SINGULAR_STEPS at most) removes the augmentation's error against the composite
 * inverse pass, which inverts no body. qdd then matches a dense solve to 1.2e-13 (16 rods, as
 * thick rods do) and to the dense solve's own rounding (256 rods) at every ratio from 1e-2 to
 * 1e-12, in two steps. Ratios
 * from CTC_SLENDER_RATIO up lose at most about 1e-12 of qdd unrefined, and 7e-11 in the round
 * trip GDCA(RNEA(u)) of CTC-like forces (16 rods; 2e-3 lost 3e-10 there). The thresholds are
 * measured (bench/NOTEBOOK.md). A loop model's slender bodies are augmented alike (the
 * refinement's residual carries the closure): a spatial loop of 16 rods then matches the loop
 * oracle to 2e-13 at every ratio from 2e-3 to 1e-10 in two steps (unaugmented, 5.6e-5 at 1e-10)
 * and one of 256 to its thick rods' level, 4.7e-11, where unaugmented rods of 1e-6 missed the
 * round trip by 3.5e3; the fraction measured again there (1e-4: three steps, 1e-6: no gain), and
 * rods of 1e-2, unaugmented, lose 5.7e-13 of qdd and 2.5e-10 in the round trip of CTC forces
 * (bench/NOTEBOOK.md, "Issue 18, the rest"). */
#define CTC_SLENDER_RATIO 1e-2
#define CTC_SLENDER_AUGMENT_REL 1e-5

/* ---- merged bodies: fixed joints in the dynamics ----
 *
 * A body on a fixed joint moves rigidly with its parent, so the dynamics passes (handles.h,
 * gdca.h: forward, inverse, refinement, trees, loops, threads) do not treat it as a body of its
 * own: they run on the reduced model m->dyn, in which each such body is merged into its parent's
 * body (the parent itself, or the body the parent is merged into) as one rigid body: masses added,
 * centres of mass averaged by mass, inertias moved to the composite's centre of mass by the
 * parallel-axis theorem, all in the parent's frame (a fixed joint only translates: its child's
 * axes are its parent's, offset by the joint's location; m->body_dyn_off sums the offsets). A body
 * fixed to the ground is welded to the world and drops out. A massless frame (a URDF tool0, a
 * sensor mount, a flange) is then no singular body (see "singular bodies") and needs no
 * augmentation or refinement; a massive one saves its share of the passes' work.
 * Nothing the user sees is renumbered: the model keeps every body and joint as given, the
 * coordinates q, v, forces and accelerations are the same vectors in both (fixed joints have
 * none, and the bodies keep their order), ctc_kinematics fills every body's pose and velocity
 * (and the reduced model's in d->dyn, data.h), so recording, end effectors, body poses, wrenches
 * (generalised forces from the full model's Jacobians, which act on the composite) and payloads
 * (added to a body's mass before the build) work on the bodies as given, and the oracle
 * (oracle.h) sees the bodies unmerged. The public passes take the model as given and run on
 * m->dyn when it is not NULL; the joint loads (data.h jnt_load, jnt_load_inv) are then those of
 * the joints that stay, and 0 on a merged body's fixed joint. The checks of the build ("singular
 * bodies": the mass matrix) run on the model as given, so their messages name its bodies.
 * A loop model keeps its bodies fixed to the ground, and its tip unless the tip merges into the
 * last body that stays (model.c dyn_targets); a fixed joint on the loop's path merges as any
 * other, and the closing joint's tip and the body it closes on map to their composites. A model
 * without fixed joints (or where nothing merges) has m->dyn = NULL and is computed as before,
 * bitwise. */

typedef struct ctc_joint_spec {
    ctc_joint_type type;
    double axis[3];     /* parent frame; any length > 0 (normalised by the builder); unused for
                           spherical and fixed joints */
    double location[3]; /* m, the joint's centre in the parent frame (world for joint 0) */
} ctc_joint_spec;

/* The closing joint of a loop from the tip body n-1 to the ground or to body `body` (on a tree,
 * an ancestor of the tip). A zeroed spec closes on the ground. */
typedef struct ctc_loop_spec {
    ctc_joint_spec joint; /* REVOLUTE, PRISMATIC or SPHERICAL; axis and location (the joint's
                             centre) in the tip body's frame */
    double anchor[3];     /* m, the joint's centre on the child: world frame (ground), or body
                             `body`'s frame */
    int on_body;          /* 0: the loop closes on the ground; 1: on body `body` */
    int body;             /* with on_body: 0 <= body <= n - 2 */
} ctc_loop_spec;

typedef struct ctc_chain_spec {
    int nbodies;                      /* n >= 1 (>= 2 with a loop) */
    const ctc_body_spec *bodies;      /* (n) */
    const ctc_joint_spec *joints;     /* (n) joint k joins body k-1 (ground for k = 0) to body k */
    const int *parent;                /* (n) body k's parent: -1 the ground, else a body < k.
                                         NULL: a chain (parent k - 1) */
    double gravity[3];                /* m/s^2, world frame (e.g. 0, -9.81, 0) */
    ctc_form form;                    /* AUTO (recommended), or force PLANAR / SPATIAL */
    const ctc_loop_spec *loop;        /* NULL: an open chain */
    const unsigned char *independent; /* (n + 1) with a loop: 1 = independent, 0 = dependent,
                                         per joint, the closing joint last; the count of
                                         independent coordinates must equal the loop's mobility.
                                         NULL: every joint independent (open chains) */
} ctc_chain_spec;

/* The kinds of node of the assembly plan (model.c, "the plan of a branched tree"). */
typedef enum ctc_node_kind {
    CTC_NODE_JOIN = 0, /* left:right, joined at `joint` (the two-handle GDCA assembly) */
    CTC_NODE_SUM,      /* a partial sum of body `body`'s light children's articulated terms */
    CTC_NODE_RAKE,     /* body `body` with all its light children raked in: a pseudo-body */
} ctc_node_kind;

/* One internal node of the assembly plan. An "assembly index" a < n names body a (a leaf);
 * a >= n names internal node a - n. A chain's plan is the balanced binary tree of JOIN nodes. */
typedef struct ctc_tree_node {
    int left;   /* assembly index of the left (inboard) part; SUM, RAKE: the first operand */
    int right;  /* assembly index of the right (outboard) part; SUM: the second operand; RAKE: -1 */
    int joint;  /* JOIN: the joint that joins them (the first body of the right part); SUM, RAKE:
                   the joint of the first light child under the node (named if it is singular) */
    int first;  /* JOIN: the first and last bodies of the node's path segment (a chain: bodies */
    int last;   /* first..last make up this node); SUM, RAKE: body, body */
    int height; /* 1 + the larger of the children's heights; leaves have height 0 */
    int kind;   /* ctc_node_kind */
    int body;   /* SUM, RAKE: the body whose light children the node sums; JOIN: -1 */
    int ljoint; /* SUM, RAKE: the light child (= its joint) whose subtree, assembled at `left`, is
                   the first operand, or -1 when `left` is a SUM node; JOIN: -1 */
    int rjoint; /* SUM: the same for `right`; JOIN, RAKE: -1 */
} ctc_tree_node;

/* Planar data of one body and its inboard joint, in the plane's coordinates (form PLANAR only). */
typedef struct ctc_planar_body {
    double mass;        /* kg */
    double inertia;     /* kg m^2, about the centre of mass and the plane normal */
    double fwd_mass;    /* kg, the forward pass's handle equations': mass, augmented when the */
    double fwd_inertia; /* kg m^2  body is singular (see "singular bodies"); likewise inertia */
    double com[2];      /* m, centre of mass in the body frame */
    double loc[2];      /* m, inboard joint centre in the parent frame */
    double axis[2];     /* prismatic: unit axis in the parent frame */
    double sign;        /* revolute: +1 if the axis is along +n, -1 if along -n */
} ctc_planar_body;

typedef struct ctc_model {
    int nbodies;       /* n */
    int nq;            /* number of position coordinates */
    int nv;            /* number of velocity coordinates = number of driving forces */
    ctc_form form;     /* PLANAR or SPATIAL, as chosen by the builder */
    int dim;           /* 3 (planar) or 6 (spatial): size of a motion or force vector */
    double gravity[3]; /* m/s^2, world */

    /* the plane (form PLANAR): world vector = x e1 + y e2 + z n */
    double plane_e1[3], plane_e2[3], plane_n[3];
    double plane_gravity[2]; /* gravity in plane coordinates */

    ctc_body_spec *bodies;  /* (n) as given, inertias symmetrised */
    ctc_joint_spec *joints; /* (n) as given, axes normalised (zero for spherical and fixed) */
    int *jnt_qadr;          /* (n) index of joint k's first position coordinate in q */
    int *jnt_vadr;          /* (n) index of joint k's first velocity coordinate in v */
    int *jnt_nq;            /* (n) */
    int *jnt_nv;            /* (n) */

    double mass_ratio;            /* the larger of max/min body mass and max/min inertia trace over
                                     the chain's bodies with mass (>= 1) */
    int nsingular;                /* the singular bodies (see "singular bodies" above) */
    int nslender;                 /* the slender bodies (see "slender bodies" above; 0 in planar
                                     form) */
    unsigned char *body_singular; /* (n) 1: body k is singular; NULL when nsingular = 0 */
    ctc_body_spec *fwd_bodies;    /* (n) the bodies of the forward pass's handle equations:
                                     `bodies` itself (the same pointer) when nsingular = nslender
                                     = 0, else a copy with each singular body's mass and inertia
                                     and each slender body's inertia augmented */
    double *body_inertia_inv; /* (n x 9) inverse of fwd_bodies' inertia about the CoM, body frame
                                 (spatial) */
    double *jnt_perp;         /* (n x 6) two unit vectors normal to joint k's axis, parent frame */
    ctc_planar_body *planar;  /* (n) form PLANAR, else NULL */

    /* topology: the tree of bodies, Featherstone's lambda(k) (Rigid Body Dynamics Algorithms,
       2008, sec. 4.1.2). Joint k is body k's inboard joint, from body body_parent[k] (-1: the
       ground) to body k, so a joint and its child body share an index. Invariants:
       -1 <= body_parent[k] < k, so a pass over k = 0..n-1 meets every parent before its children
       and one over k = n-1..0 every child before its parent; the children of a body (and of the
       ground) are listed in increasing order by body_child and body_sibling. A loop's closing
       joint is not a tree edge: it appears in none of these arrays (loop_body, loop.h). Every
       pass finds a parent or a child here. A chain is the tree whose body_parent[k] = k - 1
       (chain = 1).
       The heavy child of a body is its child with the largest subtree (ties: the lowest index);
       in a loop model the spine's bodies' heavy children are forced along the spine (the tip's
       path), so that the loop's bodies lie on one path. The heavy children split the tree into
       paths, each a chain that the two-handle GDCA
       assembles, and a body's handle 2 is its heavy child's joint. Its other ("light") children's
       subtrees are raked into it as articulated bodies (model.c, "the plan of a branched tree";
       gdca_rake.h). A chain has one path and no light children. */
    int *body_parent;  /* (n) lambda(k): body k's parent, -1 for the ground */
    int *body_child;   /* (n) body k's first (lowest-numbered) child, -1 for a leaf */
    int *body_sibling; /* (n) the next child of body k's parent after k, -1 for the last */
    int ground_child;  /* the ground's first child (body 0) */
    int *body_heavy;   /* (n) body k's heavy child, -1 for a leaf */
    int chain;         /* 1: every body_parent[k] = k - 1 */

    int ntree;           /* n - nroots internal nodes (n - 1 for a chain) */
    ctc_tree_node *tree; /* (ntree) ordered by height: children before parents, root last */
    int height;          /* root height: ceil(log2 n) for a chain, or up to one more when a loop
                            closed on a body splits the root off the middle; O(log n) on any tree */
    int *height_start;   /* (height + 2) nodes of height h are tree[height_start[h-1] ..
                            height_start[h] - 1] for h >= 1; height_start[0] = 0 */
    int root;            /* assembly index of the whole chain (the first ground child's subtree) */
    int nroots;      /* the ground's children: each subtree is joined to the ground at the root */
    int *root_joint; /* (nroots) each ground child (= its joint), in increasing order */
    int *root_asm;   /* (nroots) the assembly index of its subtree; root_asm[0] = root */

    /* loop models (has_loop = 1); open chains have has_loop = 0, njoints = n, nvx = nv, nind = nv,
       every joint independent and the loop fields zero / NULL */
    int has_loop;
    int njoints;                 /* n + has_loop: joint arrays above run to njoints, the closing
                                    joint last (joints[n] has its type, unit axis and centre in the
                                    tip's frame; jnt_qadr[n] = nq, jnt_vadr[n] = nv, jnt_perp too) */
    int nvx;                     /* nv + the closing joint's nv: the length of extended vectors */
    int loop_body;               /* the closing joint's child: -1 the ground (and open chains), else
                                    a body 0..n-2 */
    int loop_first;              /* the loop's first joint: the spine's body after loop_body
                                    (loop_body + 1 on a chain, whose loop joints are
                                    loop_first..n); the plan's root splits at it when > 0 */
    unsigned char *jnt_loop;     /* (njoints) 1: the joint is in the loop (on the spine after
                                    loop_body, or the closing joint); open chains: all 0 */
    int loop_body_asm;           /* the assembly index that stands for loop_body in its path:
                                    the body, or its RAKE node when it has light children (whose
                                    record and terminal loads are then the body's); -1: ground */
    double loop_anchor[3];       /* m, world (ground) or body loop_body's frame */
    ctc_planar_body loop_planar; /* form PLANAR: the closing joint's loc (on the tip), axis, sign */
    double loop_anchor2[2];      /* form PLANAR: the anchor in plane coordinates (its frame's) */
    int mobility; /* Gruebler-Kutzbach: sum of joint freedoms - dim (loops), nv (open) */
    unsigned char *jnt_indep; /* (njoints) 1 = independent */
    int nind;                 /* number of independent coordinates */
    int *ind_joint;           /* (nind) joint of each independent coordinate, in joint order */
    int *ind_coord;           /* (nind) its extended velocity index (jnt_vadr + offset) */
    unsigned char *inv_need;  /* (ntree) loop models: 1 if the inverse pass must disassemble
                                 node i to reach every independent joint's load (Fig. 4) */

    /* merged bodies (see "merged bodies" above); all NULL when no body merges */
    struct ctc_model *dyn; /* the reduced model the dynamics passes run on; owned by this one */
    int *body_dyn;         /* (n) body k's body in dyn: its own, or its composite's; -1: welded
                              to the world */
    double *body_dyn_off;  /* (n x 3) m, body k's frame origin in the frame of body
                              dyn_body[body_dyn[k]] (the world's when welded); the axes agree */
    int *dyn_body;         /* (dyn->nbodies) the body of this model that body j of dyn is (its
                              composite's first body) */
} ctc_model;

/* Builds and validates a model from spec. On success returns CTC_OK and *out owns a new model
 * (free with ctc_model_free); otherwise *out is NULL and err (errlen bytes, may be NULL) says
 * which item is wrong and why, e.g. "body 2: mass must not be negative (got -1 kg)". The spec is
 * copied; the caller keeps ownership of it. */
ctc_status ctc_model_build(const ctc_chain_spec *spec, ctc_model **out, char *err, size_t errlen);

/* Frees a model; NULL is allowed. No ctc_data made from it may be used afterwards. */
void ctc_model_free(ctc_model *m);

/* Number of position / velocity coordinates of a joint type (its row's nq, nv; 0 for an unknown
 * type). */
int ctc_joint_nq(ctc_joint_type t);
int ctc_joint_nv(ctc_joint_type t);

/* Name of a joint type (its row's, "unknown" for an unknown type) and of a form ("planar",
 * "spatial", "auto"). */
const char *ctc_joint_type_name(ctc_joint_type t);
const char *ctc_form_name(ctc_form f);

/* Writes the reference configuration (all angles and displacements 0, identity quaternions)
 * into q (nq). */
void ctc_model_q_zero(const ctc_model *m, double *q);

/* q (nq) moved by the velocity-space increment dv (nv) times s: q_i += s dv_i, and a spherical
 * joint's quaternion is turned by the rotation vector s dv (child frame) and renormalised. */
void ctc_model_q_add(const ctc_model *m, double *q, const double *dv, double s);

/* Position-coordinate rate qdot (nq) from q (nq) and velocities v (nv): equal to v except for
 * spherical joints, whose quaternion rate is 0.5 * quat (x) (0, v). */
void ctc_model_q_rate(const ctc_model *m, const double *q, const double *v, double *qdot);

/* Renormalises every spherical joint's quaternion in q (nq) in place (after integration). */
void ctc_model_q_normalize(const ctc_model *m, double *q);

#endif

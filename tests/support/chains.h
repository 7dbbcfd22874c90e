/*
 * chains.h - test and benchmark chains: random planar and spatial chains, Featherstone's coil,
 * rod pendulums, and random states. Deterministic for a given seed (splitmix64).
 *
 * A test_chain owns its body and joint arrays; spec points into them. Free with
 * test_chain_free (NULL allowed).
 */
#ifndef CTC_TEST_CHAINS_H
#define CTC_TEST_CHAINS_H

#include <stdint.h>

#include "model.h"

typedef struct test_chain {
    ctc_chain_spec spec;
    ctc_body_spec *bodies;
    ctc_joint_spec *joints;
    int *parent; /* NULL (a chain), or (n) the tree's parents, spec.parent */
} test_chain;

/* joint types a random spatial chain may draw from (bit 1 << ctc_joint_type) */
#define TEST_ALL_JOINTS 0x1fu

/* uniform random number in [lo, hi) */
double test_uniform(uint64_t *rng, double lo, double hi);

/* a random unit vector, uniform on the sphere */
void test_random_unit(uint64_t *rng, double u[3]);

/* Rotates a whole chain spec by rot (row-major 3x3): joint axes and locations, centres of mass,
 * inertias and gravity. Valid because body frames are parallel to the world's at q = 0. */
void test_chain_rotate(test_chain *c, const double rot[9]);

/* A random full-rank inertia about the CoM: principal moments in [lo, hi] kg m^2 satisfying the
 * triangle inequality, in random principal axes. */
void test_random_inertia(uint64_t *rng, double lo, double hi, double inertia[9]);

/* Spatial chain of n bodies: joint types drawn from type_mask, random unit axes, locations up to
 * 0.5 m away, masses 0.1-10 kg, full-rank inertias, gravity (0, 0, -9.81), form SPATIAL. */
test_chain *test_chain_random_spatial(int n, uint64_t seed, unsigned type_mask);

/* Planar chain of n bodies in the x-y plane: revolute joints about +z or -z (and prismatic joints
 * in the plane when prismatic != 0), gravity (0, -9.81, 0), masses 0.1-10 kg. rods != 0 gives
 * uniform slender rods (singular 3-D inertia); otherwise full-rank inertias. form is AUTO. */
test_chain *test_chain_random_planar(int n, uint64_t seed, int prismatic, int rods);

/* n-link planar pendulum of uniform rods of the given length and mass hanging along -y from
 * revolute joints about +z. */
test_chain *test_chain_rod_pendulum(int n, double length, double mass);

/* n slender rods of issue 18: each 1 kg and 1 m along its body x axis (centre of mass at
 * (0.5, 0, 0), transverse moments m l^2 / 12, axial moment `ratio` times that), joint k + 1 at
 * the end of rod k, revolute axes alternating z (even k) and y (odd k), gravity (0, 0, -9.81),
 * form SPATIAL. No joint axis is along a rod at q = 0, so M(q) stays well conditioned however
 * small the ratio (0 < ratio <= 1). */
test_chain *test_chain_slender_rods(int n, double ratio);

/* Featherstone's coil: n bodies, each a thin cylinder of length 1/n, mass 1/n and radius
 * 1/(20 n) along its link; joint k+1 sits at the link's end, its axis twisted by 5 pi / n about
 * the link from joint k's. Gravity (0, 0, -9.81). */
test_chain *test_chain_coil(int n);

void test_chain_free(test_chain *c);

/* Makes c a tree: copies parent (n, -1 <= parent[k] < k) into c->parent, spec.parent. Joint
 * locations stay as they are, now read in the new parents' frames. */
void test_chain_set_parents(test_chain *c, const int *parent);

/* Featherstone's autoTree family (R. Featherstone, Rigid Body Dynamics Algorithms, 2008, sec.
 * 10.? benchmarks, and autoTree.m of his spatial_v2), in ctcsim's conventions: body i (0-based)
 * hangs from body floor((i - 1 + ceil(bf)) / bf) - 1 (-1: the ground), so bf = 1 is a chain,
 * bf = 2 a binary tree, bf = 4 a quaternary one (non-integer bf mixes them). Body i is a rod of
 * length l_i = taper^i along its frame's x axis, mass taper^(3 i) kg, centre of mass at l_i / 2,
 * inertia m l_i^2 diag(0.0025, 1.015 / 12, 1.015 / 12) about it; its revolute joint sits at its
 * parent's rod end (l_parent, 0, 0) (the origin for a root), about z turned by skew (rad) about x
 * once per generation. Gravity (0, -9.81, 0): skew = 0 moves in the x-y plane (form AUTO picks
 * planar), any other skew is spatial. */
test_chain *test_auto_tree(int n, double bf, double skew, double taper);

/* random parents: parent[0] = -1 and parent[k] uniform in -1..k-1 (ground_share > 0: the ground
 * with that probability, else a body uniform in 0..k-1) */
void test_random_parents(int n, uint64_t seed, double ground_share, int *parent);

/* The anchor that closes spec's loop (spec->loop set, its anchor ignored) at q0: where the
 * library's kinematics put the tip's closing point, in world coordinates when body < 0, else in
 * body `body`'s frame, R_b^T (p - x_b). Returns CTC_OK, or the model's error (message in err). */
ctc_status test_loop_anchor(const ctc_chain_spec *spec, const double *q0, int body,
                            double anchor[3], char *err, size_t errlen);

/* Random state: q (nq) angles in [-pi, pi], displacements in [-0.5, 0.5] m, random unit
 * quaternions; v (nv) in [-vmax, vmax]. */
void test_random_state(const ctc_model *m, uint64_t *rng, double vmax, double *q, double *v);

/* Multiplies body k's mass and inertia by factor[k] (n entries, > 0), keeping its centre of mass
 * and shape: a chain with the given mass and inertia ratios between neighbours. */
void test_chain_scale_bodies(test_chain *c, const double *factor);

/* The paper's spatial double pendulum (section 7.1): two uniform 1 kg cuboids of 1 x 0.1 x 0.1 m
 * along their body x axes, joint 0 at the origin about the world z axis, joint 1 at body 0's far
 * end (1, 0, 0) about its y axis; gravity (0, 0, -9.81). With type SPHERICAL both joints are
 * spherical at the same centres (the axes are then unused). form is AUTO (spatial). Free with
 * test_chain_free. */
test_chain *test_chain_spatial_double_pendulum(ctc_joint_type type);

/* A long loop of tests and benchmarks (bench_loop, test_loop): owns its arrays, spec points into
 * them (free with test_loop_free, NULL allowed). q0 (nq) is a closed configuration by
 * construction (the anchor is where the kinematics put the tip's closing point at q0). */
typedef struct test_loop {
    ctc_chain_spec spec;
    ctc_body_spec *bodies;  /* (n) */
    ctc_joint_spec *joints; /* (n) */
    ctc_loop_spec loop;
    unsigned char *independent; /* (n + 1) */
    double *q0;                 /* (nq) */
} test_loop;

/* The arch: n >= 5 uniform 1 kg, 1 m rods hanging along -y at q = 0 from revolute joints about
 * +z (planar form), bent by q0 so that the absolute link angles (from -y) spread evenly from
 * 3 pi / 4 to pi / 4, an arch from the origin to its anchor; a revolute closing joint at the
 * tip's far end, on the ground. Mobility n - 2: joints n/2, n-1 and the closing joint are
 * dependent, every other joint independent. Two of the three dependent joints are 1 m apart at
 * the tip, so for unit commands on the others they accelerate at up to 1.7e5 rad/s^2 at n = 256
 * and 3.4e7 at n = 1024: an ill-conditioned problem (bench/NOTEBOOK.md, "Long loops"). NULL if
 * memory runs out. */
test_loop *test_loop_arch(int n);

/* The same arch with the dependent joints spread along it: n/3, 2n/3 and the closing joint
 * (dependent accelerations up to 29 rad/s^2 at n = 256, 280 at n = 1024). */
test_loop *test_loop_arch_spread(int n);

/* n >= 5 1 kg boxes (0.12 x 0.08 x 0.05 m) on revolute joints with random unit axes and 0.3 m
 * links in random directions (spatial form), q0 random in [-pi, pi], closed on the ground by a
 * spherical joint at the tip's link end. Mobility n - 3: joints n/4, n/2, 3n/4 and the closing
 * joint are dependent, every other joint independent. NULL if memory runs out. */
test_loop *test_loop_spatial(int n, uint64_t seed);

/* Closes l's loop on body b (0 <= b <= n - 2) instead: the anchor is the tip's closing point at
 * q0 in b's frame. Returns CTC_OK or the model's error. */
ctc_status test_loop_close_on(test_loop *l, int b, char *err, size_t errlen);

void test_loop_free(test_loop *l);

#endif

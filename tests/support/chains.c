/*
 * chains.c - deterministic chains and states for tests and benchmarks (chains.h).
 */
#include "chains.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "data.h"
#include "kinematics.h"
#include "shapes.h"
#include "spatial.h"

static uint64_t splitmix64(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

double test_uniform(uint64_t *rng, double lo, double hi)
{
    return lo + (hi - lo) * (double)(splitmix64(rng) >> 11) * 0x1.0p-53;
}

void test_random_unit(uint64_t *rng, double u[3])
{
    double n;
    do {
        ctc_v3_set(u, test_uniform(rng, -1, 1), test_uniform(rng, -1, 1), test_uniform(rng, -1, 1));
        n = ctc_v3_norm(u);
    } while (n < 0.1 || n > 1.0);
    ctc_v3_scale(u, u, 1.0 / n);
}

void test_random_inertia(uint64_t *rng, double lo, double hi, double inertia[9])
{
    double e[3], rot[9], axis[3], diag[9] = {0};
    do {
        for (int i = 0; i < 3; i++) e[i] = test_uniform(rng, lo, hi);
    } while (e[0] + e[1] < e[2] || e[0] + e[2] < e[1] || e[1] + e[2] < e[0]);
    diag[0] = e[0], diag[4] = e[1], diag[8] = e[2];
    test_random_unit(rng, axis);
    ctc_m3_axis_angle(rot, axis, test_uniform(rng, -CTC_PI, CTC_PI));
    ctc_m3_rotate_sym(inertia, rot, diag);
}

static test_chain *chain_alloc(int n)
{
    test_chain *c = calloc(1, sizeof *c);
    if (c == NULL) abort();
    c->bodies = calloc((size_t)n, sizeof *c->bodies);
    c->joints = calloc((size_t)n, sizeof *c->joints);
    if (c->bodies == NULL || c->joints == NULL) abort();
    c->spec.nbodies = n;
    c->spec.bodies = c->bodies;
    c->spec.joints = c->joints;
    return c;
}

void test_chain_free(test_chain *c)
{
    if (c == NULL) return;
    free(c->bodies);
    free(c->joints);
    free(c->parent);
    free(c);
}

void test_chain_set_parents(test_chain *c, const int *parent)
{
    int n = c->spec.nbodies;
    if (c->parent == NULL) c->parent = malloc((size_t)n * sizeof *c->parent);
    if (c->parent == NULL) abort();
    memcpy(c->parent, parent, (size_t)n * sizeof *parent);
    c->spec.parent = c->parent;
}

test_chain *test_auto_tree(int n, double bf, double skew, double taper)
{
    test_chain *c = chain_alloc(n);
    int *parent = malloc((size_t)n * sizeof *parent), *depth = malloc((size_t)n * sizeof *depth);
    if (parent == NULL || depth == NULL) abort();
    ctc_v3_set(c->spec.gravity, 0, -9.81, 0);
    c->spec.form = CTC_FORM_AUTO;
    for (int i = 0; i < n; i++) {
        parent[i] = (int)floor((i - 1 + ceil(bf)) / bf) - 1;
        if (parent[i] >= i) parent[i] = i - 1;
        depth[i] = parent[i] < 0 ? 0 : depth[parent[i]] + 1;
        const double len = pow(taper, i), mass = pow(taper, 3.0 * i);
        ctc_body_spec *b = &c->bodies[i];
        b->mass = mass;
        ctc_v3_set(b->com, 0.5 * len, 0, 0);
        memset(b->inertia, 0, sizeof b->inertia);
        b->inertia[0] = mass * len * len * 0.0025;
        b->inertia[4] = b->inertia[8] = mass * len * len * 1.015 / 12;
        ctc_joint_spec *j = &c->joints[i];
        j->type = CTC_JOINT_REVOLUTE;
        const double a = skew * depth[i];
        ctc_v3_set(j->axis, 0, -sin(a), cos(a));
        ctc_v3_set(j->location, parent[i] < 0 ? 0.0 : pow(taper, parent[i]), 0, 0);
    }
    test_chain_set_parents(c, parent);
    free(parent);
    free(depth);
    return c;
}

void test_random_parents(int n, uint64_t seed, double ground_share, int *parent)
{
    uint64_t rng = seed;
    for (int k = 0; k < n; k++) {
        if (k == 0 || test_uniform(&rng, 0, 1) < ground_share) {
            parent[k] = -1;
        } else {
            parent[k] = (int)(splitmix64(&rng) % (uint64_t)k);
        }
    }
}

test_chain *test_chain_random_spatial(int n, uint64_t seed, unsigned type_mask)
{
    uint64_t rng = seed;
    test_chain *c = chain_alloc(n);
    ctc_v3_set(c->spec.gravity, 0, 0, -9.81);
    c->spec.form = CTC_FORM_SPATIAL;
    for (int k = 0; k < n; k++) {
        ctc_joint_spec *j = &c->joints[k];
        int t;
        do {
            t = (int)(splitmix64(&rng) % 5);
        } while (!(type_mask & (1u << t)));
        j->type = (ctc_joint_type)t;
        test_random_unit(&rng, j->axis);
        for (int i = 0; i < 3; i++) j->location[i] = k ? test_uniform(&rng, -0.5, 0.5) : 0.0;
        ctc_body_spec *b = &c->bodies[k];
        b->mass = exp(test_uniform(&rng, log(0.1), log(10.0)));
        for (int i = 0; i < 3; i++) b->com[i] = test_uniform(&rng, -0.3, 0.3);
        test_random_inertia(&rng, 0.01, 0.2, b->inertia);
    }
    return c;
}

test_chain *test_chain_random_planar(int n, uint64_t seed, int prismatic, int rods)
{
    uint64_t rng = seed;
    test_chain *c = chain_alloc(n);
    ctc_v3_set(c->spec.gravity, 0, -9.81, 0);
    c->spec.form = CTC_FORM_AUTO;
    for (int k = 0; k < n; k++) {
        ctc_joint_spec *j = &c->joints[k];
        ctc_body_spec *b = &c->bodies[k];
        double mass = exp(test_uniform(&rng, log(0.1), log(10.0)));
        double ang = test_uniform(&rng, -CTC_PI, CTC_PI), len = test_uniform(&rng, 0.2, 1.5);
        double end[3] = {len * sin(ang), -len * cos(ang), 0};
        if (prismatic && test_uniform(&rng, 0, 1) < 0.3) {
            double a = test_uniform(&rng, -CTC_PI, CTC_PI);
            j->type = CTC_JOINT_PRISMATIC;
            ctc_v3_set(j->axis, cos(a), sin(a), 0);
        } else {
            j->type = CTC_JOINT_REVOLUTE;
            ctc_v3_set(j->axis, 0, 0, test_uniform(&rng, 0, 1) < 0.5 ? -1.0 : 1.0);
        }
        if (rods) {
            ctc_shape_rod(mass, end, b, NULL, 0);
        } else {
            b->mass = mass;
            ctc_v3_set(b->com, end[0] / 2, end[1] / 2, test_uniform(&rng, -0.1, 0.1));
            test_random_inertia(&rng, 0.01, 0.2, b->inertia);
        }
        /* the next joint sits at this body's far end */
        if (k + 1 < n) ctc_v3_copy(c->joints[k + 1].location, end);
    }
    ctc_v3_set(c->joints[0].location, 0, 0, 0);
    return c;
}

test_chain *test_chain_rod_pendulum(int n, double length, double mass)
{
    test_chain *c = chain_alloc(n);
    ctc_v3_set(c->spec.gravity, 0, -9.81, 0);
    c->spec.form = CTC_FORM_AUTO;
    double end[3] = {0, -length, 0};
    for (int k = 0; k < n; k++) {
        c->joints[k].type = CTC_JOINT_REVOLUTE;
        ctc_v3_set(c->joints[k].axis, 0, 0, 1);
        ctc_v3_set(c->joints[k].location, 0, k ? -length : 0, 0);
        ctc_shape_rod(mass, end, &c->bodies[k], NULL, 0);
    }
    return c;
}

test_chain *test_chain_slender_rods(int n, double ratio)
{
    test_chain *c = chain_alloc(n);
    ctc_v3_set(c->spec.gravity, 0, 0, -9.81);
    c->spec.form = CTC_FORM_SPATIAL;
    const double jt = 1.0 / 12.0;
    for (int k = 0; k < n; k++) {
        ctc_joint_spec *j = &c->joints[k];
        j->type = CTC_JOINT_REVOLUTE;
        ctc_v3_set(j->axis, 0, k % 2, 1 - k % 2);
        ctc_v3_set(j->location, k ? 1.0 : 0, 0, 0);
        ctc_body_spec *b = &c->bodies[k];
        memset(b, 0, sizeof *b);
        b->mass = 1.0;
        b->com[0] = 0.5;
        b->inertia[0] = ratio * jt;
        b->inertia[4] = b->inertia[8] = jt;
    }
    return c;
}

test_chain *test_chain_coil(int n)
{
    test_chain *c = chain_alloc(n);
    ctc_v3_set(c->spec.gravity, 0, 0, -9.81);
    c->spec.form = CTC_FORM_AUTO;
    double len = 1.0 / n, twist = 5 * CTC_PI / n;
    double link[3] = {len, 0, 0}, centre[3] = {len / 2, 0, 0};
    for (int k = 0; k < n; k++) {
        ctc_joint_spec *j = &c->joints[k];
        j->type = CTC_JOINT_REVOLUTE;
        /* axis twisted by k * twist about the link direction x, in the body frames */
        ctc_v3_set(j->axis, 0, cos(k * twist), sin(k * twist));
        ctc_v3_set(j->location, k ? len : 0, 0, 0);
        ctc_shape_cylinder(1.0 / n, len / 20, len, link, centre, &c->bodies[k], NULL, 0);
    }
    return c;
}

void test_chain_rotate(test_chain *c, const double rot[9])
{
    double t[3], in[9];
    for (int k = 0; k < c->spec.nbodies; k++) {
        ctc_m3_mulv(t, rot, c->joints[k].axis);
        ctc_v3_copy(c->joints[k].axis, t);
        ctc_m3_mulv(t, rot, c->joints[k].location);
        ctc_v3_copy(c->joints[k].location, t);
        ctc_m3_mulv(t, rot, c->bodies[k].com);
        ctc_v3_copy(c->bodies[k].com, t);
        ctc_m3_rotate_sym(in, rot, c->bodies[k].inertia);
        memcpy(c->bodies[k].inertia, in, sizeof in);
    }
    ctc_m3_mulv(t, rot, c->spec.gravity);
    ctc_v3_copy(c->spec.gravity, t);
}

void test_random_state(const ctc_model *m, uint64_t *rng, double vmax, double *q, double *v)
{
    for (int k = 0; k < m->nbodies; k++) {
        double *qk = q + m->jnt_qadr[k];
        switch (m->joints[k].type) {
        case CTC_JOINT_REVOLUTE:
            qk[0] = test_uniform(rng, -CTC_PI, CTC_PI);
            break;
        case CTC_JOINT_PRISMATIC:
            qk[0] = test_uniform(rng, -0.5, 0.5);
            break;
        case CTC_JOINT_CYLINDRICAL:
            qk[0] = test_uniform(rng, -CTC_PI, CTC_PI);
            qk[1] = test_uniform(rng, -0.5, 0.5);
            break;
        case CTC_JOINT_SPHERICAL: {
            double n2 = 0;
            for (int i = 0; i < 4; i++) {
                qk[i] = test_uniform(rng, -1, 1);
                n2 += qk[i] * qk[i];
            }
            for (int i = 0; i < 4; i++) qk[i] /= sqrt(n2);
            break;
        }
        case CTC_JOINT_FIXED:
            break;
        }
    }
    for (int i = 0; i < m->nv; i++) v[i] = test_uniform(rng, -vmax, vmax);
}

void test_chain_scale_bodies(test_chain *c, const double *factor)
{
    for (int k = 0; k < c->spec.nbodies; k++) {
        c->bodies[k].mass *= factor[k];
        for (int i = 0; i < 9; i++) c->bodies[k].inertia[i] *= factor[k];
    }
}

test_chain *test_chain_spatial_double_pendulum(ctc_joint_type type)
{
    test_chain *c = chain_alloc(2);
    ctc_v3_set(c->spec.gravity, 0, 0, -9.81);
    c->spec.form = CTC_FORM_AUTO;
    const double size[3] = {1, 0.1, 0.1}, centre[3] = {0.5, 0, 0};
    for (int k = 0; k < 2; k++) {
        if (ctc_shape_box(1.0, size, centre, &c->bodies[k], NULL, 0) != CTC_OK) abort();
        c->joints[k].type = type;
        ctc_v3_set(c->joints[k].axis, 0, k ? 1 : 0, k ? 0 : 1);
        ctc_v3_set(c->joints[k].location, k ? 1 : 0, 0, 0);
    }
    return c;
}

ctc_status test_loop_anchor(const ctc_chain_spec *spec, const double *q0, int body,
                            double anchor[3], char *err, size_t errlen)
{
    ctc_model *m = NULL;
    ctc_status st = ctc_model_build(spec, &m, err, errlen);
    if (st != CTC_OK) return st;
    ctc_data *d = ctc_data_new(m);
    double *zero = calloc((size_t)m->nv, sizeof *zero);
    if (d == NULL || zero == NULL) {
        snprintf(err, errlen, "out of memory");
        st = CTC_ENOMEM;
    } else {
        ctc_kinematics(m, d, q0, zero);
        if (body < 0) {
            ctc_v3_copy(anchor, d->loop_pt);
        } else {
            double rel[3];
            ctc_v3_sub(rel, d->loop_pt, d->xpos + 3 * body);
            ctc_m3_tmulv(anchor, d->xrot + 9 * body, rel);
        }
    }
    free(zero);
    ctc_data_free(d);
    ctc_model_free(m);
    return st;
}

static test_loop *test_loop_alloc(int n)
{
    test_loop *l = calloc(1, sizeof *l);
    if (!l) return NULL;
    l->bodies = calloc((size_t)n, sizeof *l->bodies);
    l->joints = calloc((size_t)n, sizeof *l->joints);
    l->independent = calloc((size_t)n + 1, 1);
    l->q0 = calloc((size_t)n, sizeof *l->q0); /* revolute joints only */
    if (!l->bodies || !l->joints || !l->independent || !l->q0) {
        test_loop_free(l);
        return NULL;
    }
    l->spec.nbodies = n;
    l->spec.bodies = l->bodies;
    l->spec.joints = l->joints;
    l->spec.loop = &l->loop;
    l->spec.independent = l->independent;
    l->spec.form = CTC_FORM_AUTO;
    for (int k = 0; k <= n; k++) l->independent[k] = 1;
    return l;
}

void test_loop_free(test_loop *l)
{
    if (!l) return;
    free(l->bodies), free(l->joints), free(l->independent), free(l->q0);
    free(l);
}

test_loop *test_loop_arch(int n)
{
    const double len = 1.0, end[3] = {0, -len, 0};
    test_loop *l = test_loop_alloc(n);
    if (!l) return NULL;
    ctc_v3_set(l->spec.gravity, 0, -9.81, 0);
    double prev = 0, x = 0, y = 0;
    for (int k = 0; k < n; k++) {
        l->joints[k] = (ctc_joint_spec){.type = CTC_JOINT_REVOLUTE, .axis = {0, 0, 1}};
        if (k) l->joints[k].location[1] = -len;
        ctc_shape_rod(1.0, end, &l->bodies[k], NULL, 0);
        /* absolute angle from -y: 3 pi / 4 (up and right) to pi / 4 (down and right) */
        double th = 0.75 * CTC_PI - 0.5 * CTC_PI * k / (n - 1);
        l->q0[k] = th - prev;
        prev = th;
        x += len * sin(th), y -= len * cos(th);
    }
    l->loop.joint =
        (ctc_joint_spec){.type = CTC_JOINT_REVOLUTE, .axis = {0, 0, 1}, .location = {0, -len, 0}};
    ctc_v3_set(l->loop.anchor, x, y, 0);
    l->independent[n / 2] = l->independent[n - 1] = l->independent[n] = 0;
    return l;
}

test_loop *test_loop_arch_spread(int n)
{
    test_loop *l = test_loop_arch(n);
    if (!l) return NULL;
    l->independent[n / 2] = l->independent[n - 1] = 1;
    l->independent[n / 3] = l->independent[2 * n / 3] = 0;
    return l;
}

test_loop *test_loop_spatial(int n, uint64_t seed)
{
    const double size[3] = {0.12, 0.08, 0.05};
    uint64_t rng = seed;
    test_loop *l = test_loop_alloc(n);
    if (!l) return NULL;
    ctc_v3_set(l->spec.gravity, 0, 0, -9.81);
    double link[3] = {0, 0, 0};
    for (int k = 0; k < n; k++) {
        ctc_joint_spec *j = &l->joints[k];
        j->type = CTC_JOINT_REVOLUTE;
        test_random_unit(&rng, j->axis);
        ctc_v3_copy(j->location, link);
        test_random_unit(&rng, link);
        ctc_v3_scale(link, link, 0.3);
        double centre[3];
        ctc_v3_scale(centre, link, 0.5);
        ctc_shape_box(1.0, size, centre, &l->bodies[k], NULL, 0);
        l->q0[k] = test_uniform(&rng, -CTC_PI, CTC_PI);
    }
    l->loop.joint = (ctc_joint_spec){.type = CTC_JOINT_SPHERICAL};
    ctc_v3_copy(l->loop.joint.location, link);
    l->independent[n / 4] = l->independent[n / 2] = l->independent[3 * n / 4] = 0;
    l->independent[n] = 0;
    char err[256];
    if (test_loop_anchor(&l->spec, l->q0, -1, l->loop.anchor, err, sizeof err) != CTC_OK) {
        fprintf(stderr, "test_loop_spatial n = %d: %s\n", n, err);
        test_loop_free(l);
        return NULL;
    }
    return l;
}

ctc_status test_loop_close_on(test_loop *l, int b, char *err, size_t errlen)
{
    ctc_status st = test_loop_anchor(&l->spec, l->q0, b, l->loop.anchor, err, errlen);
    if (st != CTC_OK) return st;
    l->loop.on_body = 1;
    l->loop.body = b;
    return CTC_OK;
}

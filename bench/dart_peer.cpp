/*
 * dart_peer.cpp - DART as a peer of ctcsim (dart_peer.h): a dart::dynamics::Skeleton of revolute
 * joints from a ctcsim chain spec, and its inverse and forward dynamics.
 *
 * Skeleton::computeInverseDynamics is DART's recursive Newton-Euler pass and
 * computeForwardDynamics its articulated-body pass; both read the kinematics that the skeleton
 * caches after setPositions and setVelocities, so the right-hand side computes them once, as a
 * CTC loop would. No external, damping or spring forces are included.
 *
 * Compiled with DART's headers when the Makefile finds them (DART_FOUND), otherwise as the
 * few functions that report its absence.
 */
#include "dart_peer.h"

#include <cstdio>

#ifdef CTC_HAVE_DART

#include <dart/config.hpp>
#include <dart/dynamics/BodyNode.hpp>
#include <dart/dynamics/RevoluteJoint.hpp>
#include <dart/dynamics/Skeleton.hpp>

#include <string>
#include <vector>

struct dart_peer {
    dart::dynamics::SkeletonPtr skel;
    Eigen::VectorXd q, v, u, tau, qdd;
};

int dart_peer_available(void)
{
    return 1;
}

const char *dart_peer_version(void)
{
    return DART_VERSION;
}

dart_peer *dart_peer_new(const ctc_chain_spec *s, char *err, int errsz)
{
    using namespace dart::dynamics;
    const int n = s->nbodies;
    SkeletonPtr skel = Skeleton::create("ctcsim_chain");
    std::vector<BodyNode *> node(n, nullptr);
    for (int k = 0; k < n; k++) {
        const ctc_joint_spec *j = &s->joints[k];
        const ctc_body_spec *b = &s->bodies[k];
        if (j->type != CTC_JOINT_REVOLUTE) {
            std::snprintf(err, errsz, "joint %d is not revolute", k);
            return nullptr;
        }
        const int parent = s->parent ? s->parent[k] : k - 1;
        RevoluteJoint::Properties jp;
        jp.mName = "j" + std::to_string(k);
        jp.mAxis = Eigen::Vector3d(j->axis[0], j->axis[1], j->axis[2]).normalized();
        jp.mT_ParentBodyToJoint = Eigen::Isometry3d::Identity();
        jp.mT_ParentBodyToJoint.translation() =
            Eigen::Vector3d(j->location[0], j->location[1], j->location[2]);
        jp.mT_ChildBodyToJoint = Eigen::Isometry3d::Identity();
        BodyNode::Properties bp;
        bp.mName = "b" + std::to_string(k);
        Eigen::Matrix3d inertia;
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++) inertia(r, c) = b->inertia[3 * r + c];
        bp.mInertia = Inertia(b->mass, Eigen::Vector3d(b->com[0], b->com[1], b->com[2]), inertia);
        node[k] = skel->createJointAndBodyNodePair<RevoluteJoint>(
                          parent >= 0 ? node[parent] : nullptr, jp, bp)
                      .second;
    }
    skel->setGravity(Eigen::Vector3d(s->gravity[0], s->gravity[1], s->gravity[2]));
    if ((int)skel->getNumDofs() != n) {
        std::snprintf(err, errsz, "DART made %d degrees of freedom of %d bodies",
                      (int)skel->getNumDofs(), n);
        return nullptr;
    }
    dart_peer *p = new dart_peer;
    p->skel = skel;
    p->q.resize(n), p->v.resize(n), p->u.resize(n), p->tau.resize(n), p->qdd.resize(n);
    return p;
}

void dart_peer_free(dart_peer *p)
{
    delete p;
}

/* the state into the skeleton: its kinematics are recomputed when next needed */
static void set_state(dart_peer *p, const double *q, const double *v)
{
    const Eigen::Index n = p->q.size();
    p->q = Eigen::Map<const Eigen::VectorXd>(q, n);
    p->v = Eigen::Map<const Eigen::VectorXd>(v, n);
    p->skel->setPositions(p->q);
    p->skel->setVelocities(p->v);
}

void dart_peer_rhs(dart_peer *p, const double *q, const double *v, const double *u, double *tau,
                   double *qdd)
{
    const Eigen::Index n = p->q.size();
    set_state(p, q, v);
    p->u = Eigen::Map<const Eigen::VectorXd>(u, n);
    p->skel->setAccelerations(p->u);
    p->skel->computeInverseDynamics(false, false, false);
    p->tau = p->skel->getForces();
    p->skel->setForces(p->tau);
    p->skel->computeForwardDynamics();
    p->qdd = p->skel->getAccelerations();
    if (tau) Eigen::Map<Eigen::VectorXd>(tau, n) = p->tau;
    if (qdd) Eigen::Map<Eigen::VectorXd>(qdd, n) = p->qdd;
}

void dart_peer_forward(dart_peer *p, const double *q, const double *v, const double *tau,
                       double *qdd)
{
    const Eigen::Index n = p->q.size();
    set_state(p, q, v);
    p->tau = Eigen::Map<const Eigen::VectorXd>(tau, n);
    p->skel->setForces(p->tau);
    p->skel->computeForwardDynamics();
    Eigen::Map<Eigen::VectorXd>(qdd, n) = p->skel->getAccelerations();
}

#else

int dart_peer_available(void)
{
    return 0;
}

const char *dart_peer_version(void)
{
    return "(not in this build)";
}

dart_peer *dart_peer_new(const ctc_chain_spec *s, char *err, int errsz)
{
    (void)s;
    std::snprintf(err, errsz,
                  "DART's headers were not found when this was built (Debian: libdart-dev, "
                  "which make bench-deps installs)");
    return nullptr;
}

void dart_peer_free(dart_peer *p)
{
    (void)p;
}

void dart_peer_rhs(dart_peer *p, const double *q, const double *v, const double *u, double *tau,
                   double *qdd)
{
    (void)p, (void)q, (void)v, (void)u, (void)tau, (void)qdd;
}

void dart_peer_forward(dart_peer *p, const double *q, const double *v, const double *tau,
                       double *qdd)
{
    (void)p, (void)q, (void)v, (void)tau, (void)qdd;
}

#endif

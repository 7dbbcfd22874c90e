/*
 * presets_robots.h - the industrial arms among the presets (presets.h): documents whose scene is
 * the robot's published DH table or URDF, each tracking a minimum-jerk move with PD.
 * presets_robots.c cites each one's source.
 */
#ifndef PRESETS_ROBOTS_H
#define PRESETS_ROBOTS_H

#include <cjson/cJSON.h>

#include "job_json.h"

/* The UR5 from its DH table (standard convention). request is ignored. Returns the document, or
 * NULL with err filled (out of memory). */
cJSON *presets_ur5(const cJSON *request, job_error *err);

/* The textbook two-link planar arm with point masses at the link ends (Lynch and Park, Modern
 * Robotics, sec. 8.1.1) from its DH table, gravity -y. As presets_ur5. */
cJSON *presets_two_link(const cJSON *request, job_error *err);

/* The two-link arm of presets_two_link with joint friction (viscous and Coulomb) and a payload
 * at its tip that the controller's model lacks (issue 21's lab plant). As presets_ur5. */
cJSON *presets_two_link_lab(const cJSON *request, job_error *err);

/* The Puma 560 of Armstrong, Khatib and Burdick 1986 (Corke's mdl_puma560akb) from its modified
 * DH table; link 1 massless with an inertia about its axis. As presets_ur5. */
cJSON *presets_puma560(const cJSON *request, job_error *err);

/* The KUKA LBR iiwa 14 from its URDF (Drake's). As presets_ur5. */
cJSON *presets_iiwa14(const cJSON *request, job_error *err);

/* The Franka Emika Panda with its two fingers from its URDF (franka_description, with Gaz et al.'s
 * identified link inertials): a tree, both fingers hanging from the hand. As presets_ur5. */
cJSON *presets_panda(const cJSON *request, job_error *err);

#endif

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

/* The KUKA LBR iiwa 14 from its URDF (Drake's). As presets_ur5. */
cJSON *presets_iiwa14(const cJSON *request, job_error *err);

/* The Franka Emika Panda with its two fingers from its URDF (franka_description, with Gaz et al.'s
 * identified link inertials): a tree, both fingers hanging from the hand. As presets_ur5. */
cJSON *presets_panda(const cJSON *request, job_error *err);

#endif

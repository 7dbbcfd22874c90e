/*
 * presets.h - the paper's scenes as ready-made jobs (DESIGN.md section 7, paper section 7).
 *
 * A preset builds a complete job document (job_json.h) that users can run as it is, print with
 * `ctcsim preset NAME` and change with overrides. Some take parameters from the request
 * ({"preset": "n_link_pendulum", "n": 16}).
 *
 *   triple_pendulum_{pd,pid,poles,lqr,passive}   paper 7.1, Fig. 6(a), 7, 8
 *   spatial_double_pendulum_{pd,pid,poles,lqr}   paper 7.1, Fig. 6(b), 9, 10 (gravity -z)
 *   n_link_pendulum                              paper 7.3, PD; parameter "n" (2..4096, default 8)
 *   five_bar_{pd,pid,poles,lqr}                  paper 7.2, Fig. 12: a planar closed chain
 *   four_bar_passive                             a planar four-bar crank-rocker, no control
 *   rssr_passive                                 a spatial RSSR linkage, no control (gravity -z)
 *   y_pendulum_pd                                a planar Y tree: two double pendulums on an arm
 *   spatial_hand_pd                              a wrist, a palm and three three-link fingers
 *   two_arm_torso_pd                             a torso on a waist with two three-link arms
 *   ur5_min_jerk, iiwa14_min_jerk, panda_min_jerk, two_link_min_jerk, puma560_min_jerk
 *                                                arms from their DH table or URDF
 *                                                (presets_robots.c), a minimum-jerk move, PD;
 *                                                the Panda's two fingers make it a tree; the
 *                                                two-link arm is planar, with point masses
 * presets.c describes each scene's geometry and numbers.
 */
#ifndef PRESETS_H
#define PRESETS_H

#include <stddef.h>

#include <cjson/cJSON.h>

#include "job_json.h"

typedef struct preset {
    const char *name;
    const char *summary;       /* one line for listings */
    const char *const *params; /* NULL-terminated keys this preset takes from the request */
    /* builds the job document; request is the whole request object (for the parameters), may be
       NULL (defaults). Returns NULL with *err filled on a bad parameter or out of memory. */
    cJSON *(*build)(const cJSON *request, job_error *err);
} preset;

/* The presets, *count of them, in listing order. */
const preset *presets_list(int *count);

/* The preset of that name, or NULL. */
const preset *presets_find(const char *name);

/* The name of a job made from a preset whose name is `name` and whose controller type an
 * override changed from `from` to `to` (job_json.h's controller types: "none", "pd", "pid",
 * "poles", "lqr"), into buf (len bytes, NUL-terminated, truncated to fit): the preset's
 * controller label replaced by the new one ("passive", "PD", "PID", "pole placement", "LQR"),
 * and a reference to the paper ("(Kingsley et al. 2017, ...") made "(scene of Kingsley et al.
 * 2017, ...", since the paper ran the scene with the preset's controller. So the override
 * {"preset": "triple_pendulum_pid", "controller": {"type": "lqr", ...}} is named "Triple
 * pendulum, LQR (scene of Kingsley et al. 2017, sec. 7.1)". A name without the old label gets
 * ", LABEL" appended. Returns 0, or -1 (buf untouched) when `from` or `to` is no controller
 * type. */
int presets_name_for_controller(const char *name, const char *from, const char *to, char *buf,
                                size_t len);

#endif

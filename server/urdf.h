/*
 * urdf.h - a URDF robot description (ROS's Unified Robot Description Format, XML) read into the
 * job format's "bodies" (job_json.h, import.h), with libxml2.
 *
 * What is read: <robot name> and its <link> and <joint> elements (others, such as <material>,
 * <transmission> and <gazebo>, are ignored).
 *   link:  <inertial> with <origin xyz rpy> (default zero), <mass value> (kg, >= 0) and <inertia
 *          ixx iyy izz> (kg m^2, required) and ixy ixz iyz (default 0), about the centre of mass
 *          in the inertial frame's axes; a link without <inertial> is massless. Each <visual>
 *          whose <geometry> is a <box size>, <cylinder radius length> or <sphere radius> (> 0),
 *          with its <origin xyz rpy>, is kept in its body's "visuals" for the page's animation
 *          (import.h; the simulation ignores them; the ground's are dropped); a <mesh> is left
 *          out and counted; <collision> is ignored.
 *   joint: name, type revolute | continuous (a revolute joint without limits) | prismatic |
 *          fixed, <parent link>, <child link>, <origin xyz rpy> (default zero), <axis xyz>
 *          (default 1 0 0, any non-zero length), and kept in the body's "joint" for the lab plant,
 *          which does not use them yet: <limit lower upper effort velocity> as "limit" {"lower",
 *          "upper" (rad or m), "effort" (N m or N), "velocity" (rad/s or m/s)} and <dynamics
 *          damping friction> as "dynamics" {"damping", "friction"}, the attributes given.
 * The links must form one tree whose root is fixed to the world; fixed joints are merged
 * (import.h), so the bodies are the links on moving joints.
 *
 * Refused, each with a message naming the element and its line ("<joint name=\"j2\"> (line 14):
 * ..."): text that is not well-formed XML (libxml2's message and line), a document type
 * declaration (no entities are expanded), a root element other than <robot>, floating and planar
 * joints, <mimic>, unknown joint types, a joint whose parent or child is not a link, a link with
 * two parent joints, a parent/child cycle, two roots, repeated names, a missing required element
 * or attribute, numbers that do not parse or are not finite, a negative mass, a zero axis. A
 * moving link without mass becomes a massless body, which the model builder accepts where the
 * joint-space mass matrix stays positive definite (model.h "singular bodies").
 *
 * Thread safety: any number of calls may run at once (libxml2 is initialised once, thread-safe).
 */
#ifndef URDF_H
#define URDF_H

#include <stddef.h>

#include <cjson/cJSON.h>

#define URDF_MAX_LINKS 4096 /* links in one document, fixed ones included */

/* Reads len bytes of URDF text (need not be terminated). Returns the bodies (a cJSON array the
 * caller frees; see import_bodies for their keys, with "parent" indices), and the robot's name
 * into name (name_len bytes, truncated; may be NULL); or NULL with the reason in msg (msg_len
 * bytes): the element and its line, or "out of memory". */
cJSON *urdf_to_bodies(const char *text, size_t len, char *name, size_t name_len, char *msg,
                      size_t msg_len);

/* urdf_to_bodies, and the number of <visual>s left out because their geometry is a <mesh> into
 * *meshes (may be NULL) when it succeeds. */
cJSON *urdf_read(const char *text, size_t len, char *name, size_t name_len, int *meshes, char *msg,
                 size_t msg_len);

#endif

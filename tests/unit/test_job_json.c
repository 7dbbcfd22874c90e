/*
 * test_job_json.c - the job format (server/job_json.c): every way a job can be wrong, each with
 * its exact code, field and message; the defaults and what each part of a valid job turns into
 * (bodies from shapes and inertias, gains of every controller type against the paper's values,
 * per-coordinate overrides, trajectories and disturbances); presets expanded with RFC 7386 merge
 * patches; and the normalised document, which must parse back to the same spec and print to the
 * same text.
 *
 * Jobs are written with single quotes for readability; fixture_json (job_fixture.h) turns them
 * into JSON.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_json.h"
#include "presets.h"
#include "job_fixture.h"

/* ---- writing jobs ---- */

/* a revolute joint about z, and bodies that hang on it */
#define REV "{'type':'revolute','axis':[0,0,1]}"
#define BODY "{'mass':1,'com':[0,-0.5,0],'inertia':[0.1,0.1,0.1],'joint':" REV "}"
#define BODY_AT(loc)                                                                               \
    "{'mass':1,'com':[0,-0.5,0],'inertia':[0.1,0.1,0.1],'joint':{'type':'revolute','axis':[0,0,"   \
    "1],'location':" loc "}}"
#define BODY2 BODY_AT("[0,-1,0]")
/* one body (nv = 1), two bodies (nv = 2) */
#define SCENE1 "'scene':{'bodies':[" BODY "]}"
#define SCENE2 "'scene':{'bodies':[" BODY "," BODY2 "]}"
#define SCENE2_WITH(extra) "'scene':{'bodies':[" BODY "," BODY2 "]," extra "}"
#define PASSIVE "'controller':{'type':'none'}"
#define PD "'controller':{'type':'pd','kp':100,'kv':20}"
#define HOLD "'trajectory':{'type':'constant','value':0}"
#define DUR "'duration':1"
/* a valid job around one changed part */
#define PASSIVE_JOB(extra) "{" SCENE2 "," PASSIVE "," DUR extra "}"
#define PD_JOB(extra) "{" SCENE2 "," PD "," HOLD "," DUR extra "}"
#define PD_JOB_CTRL(keys) CTRL_JOB("{'type':'pd','kp':100,'kv':20," keys "}")
#define CTRL_JOB(ctrl) "{" SCENE2 ",'controller':" ctrl "," HOLD "," DUR "}"
#define TRAJ_JOB(traj) "{" SCENE2 "," PD ",'trajectory':" traj "," DUR "}"
#define BODY_JOB(body) "{'scene':{'bodies':[" body "]}," PASSIVE "," DUR "}"

/* a square four-bar of unit links: body 0 hangs from the origin (joint 0, independent), body 1
 * points along +x, body 2 up to the anchor (1, 0, 0) where the closing joint pins its far end;
 * joints 1, 2 and the closing joint dependent: mobility 1 (4 freedoms - 3) = nind */
#define DEP_BODY                                                                                   \
    "{'mass':1,'com':[0,-0.5,0],'inertia':[0.1,0.1,0.1],'joint':{'type':'revolute','axis':[0,0,"   \
    "1],'location':[0,-1,0],'independent':false}}"
#define CLOSING "'joint':{'type':'revolute','axis':[0,0,1],'location':[0,-1,0]}"
#define LOOP "{" CLOSING ",'anchor':[1,0,0]}"
#define SQUARE_Q0 "'q0':[0,1.5707963267948966,1.5707963267948966]"
#define LOOP_SCENE_WITH(loop)                                                                      \
    "'scene':{'bodies':[" BODY "," DEP_BODY "," DEP_BODY "],'loop':" loop "," SQUARE_Q0 "}"
#define LOOP_SCENE LOOP_SCENE_WITH(LOOP)
#define LOOP_PD_JOB(extra) "{" LOOP_SCENE "," PD "," HOLD "," DUR extra "}"
#define LOOP_PASSIVE_JOB(extra) "{" LOOP_SCENE "," PASSIVE "," DUR extra "}"
#define BAD_LOOP_JOB(loop) "{" LOOP_SCENE_WITH(loop) "," PASSIVE "," DUR "}"

/* named bodies, hanging from the previous one or from parent; a chain arm, palm, tip whose tip
 * names its parent */
#define NAMED(name)                                                                                \
    "{'name':'" name "','mass':1,'com':[0,-0.5,0],'inertia':[0.1,0.1,0.1],'joint':" REV "}"
#define NAMED_ON(name, parent)                                                                     \
    "{'name':'" name "','parent':" parent ",'mass':1,'com':[0,-0.5,0],'inertia':[0.1,0.1,0.1],"    \
    "'joint':" REV "}"
#define TREE_JOB(parent)                                                                           \
    "{'scene':{'bodies':[" NAMED("arm") "," NAMED("palm") "," NAMED_ON(                            \
        "tip", parent) "]}," PASSIVE "," DUR "}"

/* a passive chain of n hanging bodies (malloc'd JSON); duration and output as given */
static char *chain_job(int n, const char *rest)
{
    size_t len = strlen(BODY2) + 2;
    char *s = malloc(256 + (size_t)n * len + strlen(rest));
    cr_assert_not_null(s);
    char *w = s + sprintf(s, "{\"scene\":{\"bodies\":[" BODY);
    for (int k = 1; k < n; k++) w += sprintf(w, "," BODY2);
    sprintf(w, "]}," PASSIVE ",%s}", rest);
    char *out = fixture_json(s);
    free(s);
    return out;
}

static char *too_many_bodies(void)
{
    return chain_job(JOB_MAX_BODIES + 1, DUR);
}

static char *too_many_values(void)
{
    /* 200 bodies, passive: 1 + 200 q + 200 qdot + 200 tau + 2 energy = 603 values a sample */
    return chain_job(200, "'duration':1000");
}

/* a passive job named with n bytes (malloc'd JSON) */
static char *name_of_length(size_t n)
{
    char *name = malloc(n + 1);
    cr_assert_not_null(name);
    memset(name, 'x', n);
    name[n] = '\0';
    char *s = malloc(n + 512);
    cr_assert_not_null(s);
    sprintf(s, "{'name':'%s'," SCENE1 "," PASSIVE "," DUR "}", name);
    char *out = fixture_json(s);
    free(name);
    free(s);
    return out;
}

/* an unknown key holding arrays nested 990 deep (cJSON's limit is 1000) */
static char *deeply_nested(void)
{
    enum { DEPTH = 990 };
    char *s = malloc(2 * DEPTH + 64);
    cr_assert_not_null(s);
    char *w = s + sprintf(s, "{\"deep\":");
    memset(w, '[', DEPTH);
    memset(w + DEPTH, ']', DEPTH);
    strcpy(w + 2 * DEPTH, "}");
    return s;
}

/* ---- every way to get a job wrong ---- */

typedef struct bad_job {
    const char *what;
    const char *text;    /* the job, single-quoted; or */
    char *(*make)(void); /* a function that writes it (malloc'd JSON) */
    job_error_code code;
    const char *field;
    const char *message;
} bad_job;

static const bad_job bad_jobs[] = {
    /* the text itself */
    {"empty text", "", NULL, JOB_INVALID_JSON, "", "empty document"},
    {"only white space", " \n\t ", NULL, JOB_INVALID_JSON, "", "empty document"},
    /* cJSON reports an early end at the last byte */
    {"cut short", "{'scene':", NULL, JOB_INVALID_JSON, "", "invalid JSON at line 1, column 9"},
    {"trailing comma, line 3", "{\n  'duration': 1,\n  'scene': [1, 2,]\n}", NULL, JOB_INVALID_JSON,
     "", "invalid JSON at line 3, column 18"},
    {"text after the document", "{} x", NULL, JOB_INVALID_JSON, "",
     "invalid JSON at line 1, column 4: text after the end of the document"},
    /* RFC 8259 where cJSON is lenient (json_strict.h): the first error wins */
    {"number with a leading zero", "{'preset':'triple_pendulum_pid','duration':01}", NULL,
     JOB_INVALID_JSON, "",
     "invalid JSON at line 1, column 44: a number must not have a leading zero"},
    {"number ending in a point, line 2", "{'duration':1,\n 'scene':1.}", NULL, JOB_INVALID_JSON, "",
     "invalid JSON at line 2, column 10: a decimal point must be followed by a digit"},
    {"\\u0000 in a string", "{'preset':'triple_pendulum_pd','name':'a\\u0000b'}", NULL,
     JOB_INVALID_JSON, "", "invalid JSON at line 1, column 41: a string must not hold \\u0000"},
    {"raw tab in a string", "{'name':'a\tb'}", NULL, JOB_INVALID_JSON, "",
     "invalid JSON at line 1, column 11: a string must not hold a control character (escape it)"},
    {"cJSON's earlier error before a lenient number", "{'a': x, 'b': 01}", NULL, JOB_INVALID_JSON,
     "", "invalid JSON at line 1, column 7"},
    {"a lenient number before text after the document", "{'a': 01} x", NULL, JOB_INVALID_JSON, "",
     "invalid JSON at line 1, column 7: a number must not have a leading zero"},
    {"array instead of an object", "[1, 2]", NULL, JOB_INVALID_FIELD, "",
     "the job must be a JSON object (got an array)"},
    {"number instead of an object", "42", NULL, JOB_INVALID_FIELD, "",
     "the job must be a JSON object (got a number)"},
    {"repeated key", "{'duration':1,'duration':2}", NULL, JOB_INVALID_FIELD, "duration",
     "key \"duration\" appears more than once"},
    {"unknown key nested 990 deep", NULL, deeply_nested, JOB_UNKNOWN_FIELD, "deep",
     "unknown key \"deep\""},
    {"repeated key deep down", BODY_JOB("{'mass':1,'mass':2}"), NULL, JOB_INVALID_FIELD,
     "scene.bodies[0].mass", "key \"mass\" appears more than once"},

    /* the top level */
    {"empty object", "{}", NULL, JOB_MISSING_FIELD, "scene", "is required"},
    {"misspelt top-level key", PASSIVE_JOB(",'durration':1"), NULL, JOB_UNKNOWN_FIELD, "durration",
     "unknown key \"durration\" (did you mean \"duration\"?)"},
    {"unknown top-level key", PASSIVE_JOB(",'colour':'red'"), NULL, JOB_UNKNOWN_FIELD, "colour",
     "unknown key \"colour\""},
    {"no controller", "{" SCENE1 "," DUR "}", NULL, JOB_MISSING_FIELD, "controller",
     "is required ({\"type\": \"none\"} for a passive run)"},
    {"no duration", "{" SCENE1 "," PASSIVE "}", NULL, JOB_MISSING_FIELD, "duration", "is required"},
    {"name not a string", PASSIVE_JOB(",'name':5"), NULL, JOB_INVALID_FIELD, "name",
     "must be a string (got a number)"},
    {"empty name", PASSIVE_JOB(",'name':''"), NULL, JOB_INVALID_FIELD, "name", "must not be empty"},

    /* the scene */
    {"scene an array", "{'scene':[]," PASSIVE "," DUR "}", NULL, JOB_INVALID_FIELD, "scene",
     "must be an object (got an array)"},
    {"no bodies", "{'scene':{'bodies':[]}," PASSIVE "," DUR "}", NULL, JOB_INVALID_FIELD,
     "scene.bodies", "must not be empty"},
    {"too many bodies", NULL, too_many_bodies, JOB_LIMIT_EXCEEDED, "scene.bodies",
     "has 65537 bodies; the limit is 65536"},
    {"gravity of 2 numbers", "{" SCENE2_WITH("'gravity':[0,-9.81]") "," PASSIVE "," DUR "}", NULL,
     JOB_INVALID_FIELD, "scene.gravity", "must be an array of 3 numbers (got 2 entries)"},
    {"gravity overflows", "{" SCENE2_WITH("'gravity':[0,-1e999,0]") "," PASSIVE "," DUR "}", NULL,
     JOB_INVALID_FIELD, "scene.gravity[1]", "must be finite (got -inf)"},
    {"unknown form", "{" SCENE2_WITH("'form':'flat'") "," PASSIVE "," DUR "}", NULL,
     JOB_INVALID_FIELD, "scene.form",
     "must be one of \"auto\", \"planar\", \"spatial\" (got \"flat\")"},
    {"negative mass", BODY_JOB("{'mass':-1,'com':[0,0,0],'inertia':[1,1,1],'joint':" REV "}"), NULL,
     JOB_INVALID_FIELD, "scene.bodies[0].mass", "must not be negative (got -1 kg)"},
    {"mass a string", BODY_JOB("{'mass':'1','com':[0,0,0],'inertia':[1,1,1],'joint':" REV "}"),
     NULL, JOB_INVALID_FIELD, "scene.bodies[0].mass", "must be a number (got a string)"},
    {"mass 1e400", BODY_JOB("{'mass':1e400,'com':[0,0,0],'inertia':[1,1,1],'joint':" REV "}"), NULL,
     JOB_INVALID_FIELD, "scene.bodies[0].mass", "must be finite (got inf)"},
    {"misspelt body key", BODY_JOB("{'masss':1,'com':[0,0,0],'inertia':[1,1,1],'joint':" REV "}"),
     NULL, JOB_UNKNOWN_FIELD, "scene.bodies[0].masss",
     "unknown key \"masss\" (did you mean \"mass\"?)"},
    {"no centre of mass", BODY_JOB("{'mass':1,'inertia':[1,1,1],'joint':" REV "}"), NULL,
     JOB_MISSING_FIELD, "scene.bodies[0].com", "is required (or give a \"shape\")"},
    {"com beside a shape",
     BODY_JOB("{'mass':1,'com':[0,0,0],'shape':{'type':'rod','end':[0,-1,0]},'joint':" REV "}"),
     NULL, JOB_INVALID_FIELD, "scene.bodies[0].com",
     "not allowed with \"shape\" (the shape gives it)"},
    {"inertia of 2 numbers", BODY_JOB("{'mass':1,'com':[0,0,0],'inertia':[1,1],'joint':" REV "}"),
     NULL, JOB_INVALID_FIELD, "scene.bodies[0].inertia",
     "must be a 3x3 array of rows or an array of 3 principal moments (got 2 entries)"},
    {"negative principal moment",
     BODY_JOB("{'mass':1,'com':[0,0,0],'inertia':[1,-1,1],'joint':" REV "}"), NULL,
     JOB_INVALID_FIELD, "scene.bodies[0].inertia[1]", "must not be negative (got -1 kg m^2)"},
    {"inertia row of 2",
     BODY_JOB("{'mass':1,'com':[0,0,0],'inertia':[[1,0,0],[0,1,0],[0,1]],'joint':" REV "}"), NULL,
     JOB_INVALID_FIELD, "scene.bodies[0].inertia[2]",
     "must be an array of 3 numbers (got 2 entries)"},
    {"asymmetric inertia",
     BODY_JOB("{'mass':1,'com':[0,0,0],'inertia':[[1,0.5,0],[0,1,0],[0,0,1]],'joint':" REV "}"),
     NULL, JOB_INVALID_FIELD, "scene",
     "body 0: inertia is not symmetric (inertia[0][1] = 0.5, inertia[1][0] = 0)"},
    {"zero axis",
     BODY_JOB("{'mass':1,'com':[0,0,0],'inertia':[1,1,1],'joint':{'type':'revolute','axis':[0,0,"
              "0]}}"),
     NULL, JOB_INVALID_FIELD, "scene.bodies[0].joint.axis",
     "must have non-zero length (got [0, 0, 0])"},
    {"axis of a spherical joint",
     BODY_JOB("{'mass':1,'com':[0,0,0],'inertia':[1,1,1],'joint':{'type':'spherical','axis':[0,0,"
              "1]}}"),
     NULL, JOB_UNKNOWN_FIELD, "scene.bodies[0].joint.axis",
     "key \"axis\" does not apply to joint type \"spherical\""},
    {"unknown joint type",
     BODY_JOB("{'mass':1,'com':[0,0,0],'inertia':[1,1,1],'joint':{'type':'hinge'}}"), NULL,
     JOB_INVALID_FIELD, "scene.bodies[0].joint.type",
     "must be one of \"revolute\", \"prismatic\", \"cylindrical\", \"spherical\", \"fixed\" (got "
     "\"hinge\")"},
    {"no joint", BODY_JOB("{'mass':1,'com':[0,0,0],'inertia':[1,1,1]}"), NULL, JOB_MISSING_FIELD,
     "scene.bodies[0].joint", "is required"},
    {"revolute joint without an axis",
     BODY_JOB("{'mass':1,'com':[0,0,0],'inertia':[1,1,1],'joint':{'type':'revolute'}}"), NULL,
     JOB_MISSING_FIELD, "scene.bodies[0].joint.axis", "is required"},
    {"misspelt joint key",
     BODY_JOB("{'mass':1,'com':[0,0,0],'inertia':[1,1,1],'joint':{'type':'revolute','axes':[0,0,"
              "1]}}"),
     NULL, JOB_UNKNOWN_FIELD, "scene.bodies[0].joint.axes",
     "unknown key \"axes\" (did you mean \"axis\"?)"},
    {"flat box", BODY_JOB("{'mass':1,'shape':{'type':'box','size':[1,0,0.1]},'joint':" REV "}"),
     NULL, JOB_INVALID_FIELD, "scene.bodies[0].shape",
     "box: size[1] must be positive and finite (got 0)"},
    {"radius of a rod",
     BODY_JOB("{'mass':1,'shape':{'type':'rod','end':[0,-1,0],'radius':0.1},'joint':" REV "}"),
     NULL, JOB_UNKNOWN_FIELD, "scene.bodies[0].shape.radius",
     "key \"radius\" does not apply to shape type \"rod\""},
    {"rod spun about its own axis",
     "{'scene':{'form':'spatial','bodies':[{'mass':1,'shape':{'type':'rod','end':[0,0,-1]},"
     "'joint':" REV "}]}," PASSIVE "," DUR "}",
     NULL, JOB_INVALID_FIELD, "scene",
     "body 0: the joint-space mass matrix is singular: joint 0 (revolute) moves no mass or "
     "inertia that the joints before it do not (relative pivot 0 <= 1e-10); body 0 and the "
     "bodies beyond it need mass off the joint's axis or inertia about it"},
    {"planar form of a spatial chain",
     "{'scene':{'form':'planar','bodies':[" BODY ",{'mass':1,'com':[0,-0.5,0],'inertia':[0.1,"
     "0.1,0.1],'joint':{'type':'revolute','axis':[1,0,0]}}]}," PASSIVE "," DUR "}",
     NULL, JOB_INVALID_FIELD, "scene",
     "chain: planar form requested but joint 1: revolute axis is not normal to the plane of "
     "motion"},
    {"only fixed joints",
     BODY_JOB("{'mass':1,'com':[0,0,0],'inertia':[1,1,1],'joint':{'type':'fixed'}}"), NULL,
     JOB_INVALID_FIELD, "scene.bodies",
     "must have at least one joint that moves (every joint is fixed)"},
    {"q0 too short", "{" SCENE2_WITH("'q0':[0]") "," PASSIVE "," DUR "}", NULL, JOB_INVALID_FIELD,
     "scene.q0", "must have 2 entries, one per position coordinate (got 1)"},
    {"v0 too long", "{" SCENE2_WITH("'v0':[0,0,0]") "," PASSIVE "," DUR "}", NULL,
     JOB_INVALID_FIELD, "scene.v0", "must have 2 entries, one per coordinate (got 3)"},
    {"q0 an object", "{" SCENE2_WITH("'q0':{}") "," PASSIVE "," DUR "}", NULL, JOB_INVALID_FIELD,
     "scene.q0", "must be an array of 2 numbers, one per position coordinate (got an object)"},
    {"quaternion not a rotation",
     "{'scene':{'bodies':[{'mass':1,'com':[0,0,0],'inertia':[1,1,1],'joint':{'type':'spherical'}}"
     "],'q0':[0.5,0,0,0]}," PASSIVE "," DUR "}",
     NULL, JOB_INVALID_FIELD, "scene.q0",
     "entries 0 to 3, the quaternion (w, x, y, z) of scene.bodies[0].joint, must have unit "
     "length (got 0.5)"},

    /* the controller */
    {"controller without a type", "{" SCENE2 ",'controller':{'kp':1}," DUR "}", NULL,
     JOB_MISSING_FIELD, "controller.type", "is required"},
    {"unknown controller type", CTRL_JOB("{'type':'pdd'}"), NULL, JOB_INVALID_FIELD,
     "controller.type",
     "must be one of \"none\", \"pd\", \"pid\", \"poles\", \"lqr\", \"joint_pd\", "
     "\"pd_gravity\", \"feedforward\" (got \"pdd\")"},
    {"gains of no controller", "{" SCENE2 ",'controller':{'type':'none','kp':1}," DUR "}", NULL,
     JOB_UNKNOWN_FIELD, "controller.kp", "key \"kp\" does not apply to controller type \"none\""},
    {"pd without gains", CTRL_JOB("{'type':'pd'}"), NULL, JOB_MISSING_FIELD, "controller.kp",
     "is required (or give \"zeta\" and \"tau\")"},
    {"kp without kv", CTRL_JOB("{'type':'pd','kp':100}"), NULL, JOB_MISSING_FIELD, "controller.kv",
     "is required with \"kp\""},
    {"both pairs", CTRL_JOB("{'type':'pd','kp':100,'kv':20,'zeta':1}"), NULL, JOB_INVALID_FIELD,
     "controller.zeta",
     "cannot be combined with \"kp\" and \"kv\" (give \"kp\" and \"kv\", or \"zeta\" and \"tau\")"},
    {"pid without ki", CTRL_JOB("{'type':'pid','kp':100,'kv':20}"), NULL, JOB_MISSING_FIELD,
     "controller.ki", "is required"},
    {"unstable pid: ki = kv kp", CTRL_JOB("{'type':'pid','kp':100,'kv':20,'ki':2000}"), NULL,
     JOB_INVALID_FIELD, "controller",
     "ki = 2000 must be below kv*kp = 2000 (Routh-Hurwitz: the closed-loop error dynamics would "
     "be unstable)"},
    {"negative kp", CTRL_JOB("{'type':'pd','kp':-1,'kv':20}"), NULL, JOB_INVALID_FIELD,
     "controller", "kp must be positive and finite (got -1)"},
    {"pole in the right half plane", CTRL_JOB("{'type':'poles','poles':[-1,2,-3]}"), NULL,
     JOB_INVALID_FIELD, "controller", "pole 1 (2) is not strictly in the left half plane"},
    {"complex pole without its conjugate",
     CTRL_JOB("{'type':'poles','poles':[{'re':-1,'im':2},{'re':-1,'im':3},-2]}"), NULL,
     JOB_INVALID_FIELD, "controller", "pole 0 (-1+2i) has no conjugate partner"},
    {"two poles", CTRL_JOB("{'type':'poles','poles':[-1,-2]}"), NULL, JOB_INVALID_FIELD,
     "controller.poles", "must be an array of 3 poles (got 2 entries)"},
    {"pole a string", CTRL_JOB("{'type':'poles','poles':[-1,'-2',-3]}"), NULL, JOB_INVALID_FIELD,
     "controller.poles[1]", "must be a number or an object {\"re\": x, \"im\": y} (got a string)"},
    {"pole without im", CTRL_JOB("{'type':'poles','poles':[-1,{'re':-2},-3]}"), NULL,
     JOB_MISSING_FIELD, "controller.poles[1].im", "is required"},
    {"lambda zero", CTRL_JOB("{'type':'lqr','Q':[1,1,1],'lambda':0}"), NULL, JOB_INVALID_FIELD,
     "controller", "lambda must be positive and finite (got 0)"},
    {"Q not positive semidefinite", CTRL_JOB("{'type':'lqr','Q':[1,-1,1],'lambda':0.01}"), NULL,
     JOB_INVALID_FIELD, "controller", "Q is not positive semidefinite (eigenvalue -1)"},
    {"lqr without lambda", CTRL_JOB("{'type':'lqr','Q':[1,1,1]}"), NULL, JOB_MISSING_FIELD,
     "controller.lambda", "is required"},
    {"overrides for 1 of 2 coordinates", CTRL_JOB("{'type':'pd','kp':100,'kv':20,'joints':[{}]}"),
     NULL, JOB_INVALID_FIELD, "controller.joints",
     "must have 2 entries, one per coordinate (got 1)"},
    {"ki override of pd", CTRL_JOB("{'type':'pd','kp':100,'kv':20,'joints':[{},{'ki':1}]}"), NULL,
     JOB_UNKNOWN_FIELD, "controller.joints[1].ki",
     "key \"ki\" does not apply to controller type \"pd\""},
    {"override with a negative kv",
     CTRL_JOB("{'type':'pd','kp':100,'kv':20,'joints':[{},{'kv':-5}]}"), NULL, JOB_INVALID_FIELD,
     "controller.joints[1]", "kv must be positive and finite (got -5)"},
    {"override switching to half a pair",
     CTRL_JOB("{'type':'pd','kp':100,'kv':20,'joints':[{'zeta':1},{}]}"), NULL, JOB_MISSING_FIELD,
     "controller.joints[0].tau", "is required with \"zeta\""},
    {"zero mass scale", CTRL_JOB("{'type':'pd','kp':100,'kv':20,'model':{'mass_scale':0}}"), NULL,
     JOB_INVALID_FIELD, "controller.model.mass_scale", "must be positive (got 0)"},
    {"unknown key in the controller's model",
     CTRL_JOB("{'type':'pd','kp':100,'kv':20,'model':{'mass':2}}"), NULL, JOB_UNKNOWN_FIELD,
     "controller.model.mass", "unknown key \"mass\""},
    {"spherical joint with a controller",
     "{'scene':{'bodies':[" BODY ",{'mass':1,'com':[0,0,0],'inertia':[1,1,1],'joint':{'type':"
     "'spherical'}}]}," PD "," HOLD "," DUR "}",
     NULL, JOB_INVALID_FIELD, "controller.type",
     "\"pd\" cannot drive the spherical joint of scene.bodies[1] (its quaternion error is not a "
     "per-coordinate error); spherical joints are allowed only with controller \"none\""},

    /* the trajectory */
    {"trajectory of a passive run", PASSIVE_JOB("," HOLD), NULL, JOB_INVALID_FIELD, "trajectory",
     "not allowed with controller \"none\" (a passive run has no desired motion)"},
    {"controller without a trajectory", "{" SCENE2 "," PD "," DUR "}", NULL, JOB_MISSING_FIELD,
     "trajectory", "is required with controller \"pd\""},
    {"trajectory for 1 of 2 coordinates", TRAJ_JOB("[{'type':'constant','value':0}]"), NULL,
     JOB_INVALID_FIELD, "trajectory", "must have 2 entries, one per coordinate (got 1)"},
    {"trajectory a string", TRAJ_JOB("'sine'"), NULL, JOB_INVALID_FIELD, "trajectory",
     "must be an object or an array of 2 objects, one per coordinate (got a string)"},
    {"sine of period 0",
     TRAJ_JOB("[{'type':'constant','value':0},{'type':'sine','amplitude':1,'period':0}]"), NULL,
     JOB_INVALID_FIELD, "trajectory[1]", "sine: period must be positive and finite (got 0 s)"},
    {"spline times not increasing", TRAJ_JOB("{'type':'spline','times':[0,1,1],'values':[0,1,2]}"),
     NULL, JOB_INVALID_FIELD, "trajectory", "spline: times[2] = 1 is not after times[1] = 1"},
    {"spline values short", TRAJ_JOB("{'type':'spline','times':[0,1,2],'values':[0,1]}"), NULL,
     JOB_INVALID_FIELD, "trajectory.values", "must have as many entries as \"times\" (3, got 2)"},
    {"spline of one knot", TRAJ_JOB("{'type':'spline','times':[0],'values':[0]}"), NULL,
     JOB_INVALID_FIELD, "trajectory.times", "must have 2 to 100000 entries (got 1)"},
    {"unknown spline boundary",
     TRAJ_JOB("{'type':'spline','times':[0,1],'values':[0,1],'boundary':'free'}"), NULL,
     JOB_INVALID_FIELD, "trajectory.boundary",
     "must be one of \"clamped\", \"natural\" (got \"free\")"},
    {"polynomial of 17 coefficients",
     TRAJ_JOB("{'type':'polynomial','coefficients':[0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0]}"), NULL,
     JOB_INVALID_FIELD, "trajectory.coefficients", "must have 1 to 16 entries (got 17)"},
    {"min_jerk ending at its start",
     TRAJ_JOB("{'type':'min_jerk','from':0,'to':1,'start':1,'end':1}"), NULL, JOB_INVALID_FIELD,
     "trajectory", "min_jerk: end (1 s) must be after start (1 s)"},
    {"min_jerk without 'to'", TRAJ_JOB("{'type':'min_jerk','from':0,'start':0,'end':1}"), NULL,
     JOB_MISSING_FIELD, "trajectory.to", "is required"},
    {"misspelt trajectory key", TRAJ_JOB("{'type':'sine','amplitud':1,'period':1}"), NULL,
     JOB_UNKNOWN_FIELD, "trajectory.amplitud",
     "unknown key \"amplitud\" (did you mean \"amplitude\"?)"},

    /* the baselines */
    {"baseline on a loop",
     "{" LOOP_SCENE ",'controller':{'type':'pd_gravity','kp':10,'kv':5}," HOLD "," DUR "}", NULL,
     JOB_INVALID_FIELD, "controller.type",
     "\"pd_gravity\" needs an open chain (its model's desired or resting state is not defined for "
     "a loop's dependent joints)"},
    {"baseline without kv", CTRL_JOB("{'type':'feedforward','kp':10}"), NULL, JOB_MISSING_FIELD,
     "controller.kv", "is required"},
    {"baseline with zeta", CTRL_JOB("{'type':'joint_pd','kp':10,'kv':5,'zeta':1}"), NULL,
     JOB_UNKNOWN_FIELD, "controller.zeta",
     "key \"zeta\" does not apply to controller type \"joint_pd\""},

    /* a sampled controller */
    {"delay without a period", PD_JOB_CTRL("'sample_delay':2"), NULL, JOB_INVALID_FIELD,
     "controller.sample_delay",
     "needs \"sample_period\" (a continuous controller has no samples to delay)"},
    {"negative sample period", PD_JOB_CTRL("'sample_period':-0.001"), NULL, JOB_INVALID_FIELD,
     "controller.sample_period",
     "must be non-negative (got -0.001 s; 0 = a continuous controller)"},
    {"fractional delay", PD_JOB_CTRL("'sample_period':0.001,'sample_delay':1.5"), NULL,
     JOB_INVALID_FIELD, "controller.sample_delay",
     "must be a whole number of samples from 0 to 10000 (got 1.5)"},
    {"sample period of a passive run", CTRL_JOB("{'type':'none','sample_period':0.01}"), NULL,
     JOB_UNKNOWN_FIELD, "controller.sample_period",
     "key \"sample_period\" does not apply to controller type \"none\""},
    {"too many control instants", PD_JOB_CTRL("'sample_period':1e-9"), NULL, JOB_LIMIT_EXCEEDED,
     "controller.sample_period",
     "duration / sample_period = 1e+09 instants exceeds 1e+07: use a longer period or a shorter "
     "duration (got 1e-09 s for 1 s)"},

    /* the sensors */
    {"noise without a sampled controller", PD_JOB(",'plant':{'noise_q':0.001}"), NULL,
     JOB_INVALID_FIELD, "plant.noise_q",
     "needs a sampled controller (\"controller.sample_period\"): the sensors are read at its "
     "instants"},
    {"negative rate noise", PD_JOB_CTRL("'sample_period':0.001},'plant':{'noise_v':-1"), NULL,
     JOB_INVALID_FIELD, "plant.noise_v", "must be non-negative (got -1)"},
    {"fractional seed", PD_JOB_CTRL("'sample_period':0.001,'seed':1.5"), NULL, JOB_INVALID_FIELD,
     "controller.seed", "must be a whole number from 0 to 2^53 (got 1.5)"},

    /* the plant */
    {"negative torque limit", PD_JOB(",'plant':{'torque_limit':-1}"), NULL, JOB_INVALID_FIELD,
     "plant.torque_limit", "must be positive (got -1)"},
    {"zero torque limit of one coordinate", PD_JOB(",'plant':[{},{'torque_limit':0}]"), NULL,
     JOB_INVALID_FIELD, "plant[1].torque_limit", "must be positive (got 0)"},
    {"torque limit of a passive run", PASSIVE_JOB(",'plant':{'torque_limit':5}"), NULL,
     JOB_INVALID_FIELD, "plant.torque_limit",
     "needs a controller: it clips the controller's force (this run is passive)"},
    {"plant array of the wrong length", PD_JOB(",'plant':[{}]"), NULL, JOB_INVALID_FIELD, "plant",
     "must have 2 entries, one per coordinate (got 1)"},
    {"coulomb without its velocity", PD_JOB(",'plant':{'coulomb':1}"), NULL, JOB_MISSING_FIELD,
     "plant.coulomb_velocity",
     "is required with \"coulomb\" (the regularisation's speed scale, rad/s or m/s: smaller is "
     "more accurate and stiffer)"},
    {"negative viscous friction", PD_JOB(",'plant':[{},{'viscous':-2}]"), NULL, JOB_INVALID_FIELD,
     "plant[1].viscous", "must be non-negative (got -2)"},
    {"model body index out of range", PD_JOB_CTRL("'model':{'bodies':[{'body':2,'mass':1}]}"), NULL,
     JOB_INVALID_FIELD, "controller.model.bodies[0].body",
     "must be a body index, a whole number from 0 to 1 (got 2)"},
    {"negative model mass", PD_JOB_CTRL("'model':{'bodies':[{'body':0},{'body':1,'mass':-1}]}"),
     NULL, JOB_INVALID_FIELD, "controller.model.bodies[1].mass", "must not be negative (got -1)"},
    {"model mass and its scale",
     PD_JOB_CTRL("'model':{'bodies':[{'body':0,'mass':1,'mass_scale':2}]}"), NULL,
     JOB_INVALID_FIELD, "controller.model.bodies[0].mass_scale",
     "give either \"mass\" or \"mass_scale\", not both"},
    {"negative model inertia", PD_JOB_CTRL("'model':{'bodies':[{'body':0,'inertia':[1,-1,1]}]}"),
     NULL, JOB_INVALID_FIELD, "controller.model.bodies[0].inertia[1]",
     "must not be negative (got -1 kg m^2)"},
    {"payload on no body", PD_JOB_CTRL("'model':{'payload':{'body':-1,'mass':1,'point':[0,0,0]}}"),
     NULL, JOB_INVALID_FIELD, "controller.model.payload.body",
     "must be a body index, a whole number from 0 to 1 (got -1)"},
    {"payload without mass", PD_JOB_CTRL("'model':{'payload':{'body':0,'point':[0,0,0]}}"), NULL,
     JOB_MISSING_FIELD, "controller.model.payload.mass", "is required"},
    {"random mass range of 1", PD_JOB_CTRL("'model':{'random':{'seed':1,'mass':1}}"), NULL,
     JOB_INVALID_FIELD, "controller.model.random.mass",
     "must be less than 1, a relative range (got 1)"},
    {"negative random seed", PD_JOB_CTRL("'model':{'random':{'seed':-3}}"), NULL, JOB_INVALID_FIELD,
     "controller.model.random.seed", "must be a whole number from 0 to 2^53 (got -3)"},
    {"model gravity of 2 numbers", PD_JOB_CTRL("'model':{'gravity':[0,-9.81]}"), NULL,
     JOB_INVALID_FIELD, "controller.model.gravity",
     "must be an array of 3 numbers (got 2 entries)"},
    {"negative armature", PD_JOB(",'plant':[{'armature':-0.1},{}]"), NULL, JOB_INVALID_FIELD,
     "plant[0].armature", "must be non-negative (got -0.1)"},
    {"zero coulomb velocity", PD_JOB(",'plant':{'coulomb':1,'coulomb_velocity':0}"), NULL,
     JOB_INVALID_FIELD, "plant.coulomb_velocity", "must be positive (got 0)"},
    {"spring rest without a spring", PASSIVE_JOB(",'plant':{'spring_rest':1}"), NULL,
     JOB_INVALID_FIELD, "plant.spring_rest", "applies only with \"spring\""},
    {"known not a boolean", PD_JOB(",'plant':{'viscous':1,'known':1}"), NULL, JOB_INVALID_FIELD,
     "plant.known", "must be true or false (got a number)"},
    {"misspelt plant key", PD_JOB(",'plant':{'torque_limt':5}"), NULL, JOB_UNKNOWN_FIELD,
     "plant.torque_limt", "unknown key \"torque_limt\" (did you mean \"torque_limit\"?)"},

    /* the disturbance */
    {"disturbance of negative period",
     PASSIVE_JOB(",'disturbance':{'type':'sine','amplitude':1,'period':-1}"), NULL,
     JOB_INVALID_FIELD, "disturbance", "sine: period must be positive and finite (got -1 s)"},
    {"step without a time",
     PASSIVE_JOB(",'disturbance':[{'type':'step','value':1},{'type':'none'}]"), NULL,
     JOB_MISSING_FIELD, "disturbance[0].time", "is required"},
    {"value of no disturbance", PASSIVE_JOB(",'disturbance':{'type':'none','value':1}"), NULL,
     JOB_UNKNOWN_FIELD, "disturbance.value",
     "key \"value\" does not apply to disturbance type \"none\""},

    /* the integrator */
    {"rtol of 2", PASSIVE_JOB(",'integrator':{'rtol':2}"), NULL, JOB_INVALID_FIELD, "integrator",
     "rtol must be in (0, 1) (got 2)"},
    {"atol of 0", PASSIVE_JOB(",'integrator':{'method':'bdf','atol':0}"), NULL, JOB_INVALID_FIELD,
     "integrator", "atol must be positive and finite (got 0)"},
    {"rtol for rk4", PASSIVE_JOB(",'integrator':{'method':'rk4','rtol':1e-6}"), NULL,
     JOB_UNKNOWN_FIELD, "integrator.rtol", "key \"rtol\" does not apply to method \"rk4\""},
    {"negative rk4 step", PASSIVE_JOB(",'integrator':{'method':'rk4','step':-1}"), NULL,
     JOB_INVALID_FIELD, "integrator", "step must be positive and finite (got -1 s)"},
    {"unknown method", PASSIVE_JOB(",'integrator':{'method':'euler'}"), NULL, JOB_INVALID_FIELD,
     "integrator.method", "must be one of \"rk4\", \"dopri5\", \"bdf\" (got \"euler\")"},
    {"fractional max_steps", PASSIVE_JOB(",'integrator':{'max_steps':1.5}"), NULL,
     JOB_INVALID_FIELD, "integrator.max_steps",
     "must be a whole number from 0 (no limit) to 2^53 (got 1.5)"},
    {"rk4 step of 1e-300", PASSIVE_JOB(",'integrator':{'method':'rk4','step':1e-300}"), NULL,
     JOB_INVALID_FIELD, "integrator.step",
     "duration / step = 1e+300 steps exceeds integrator.max_steps (10000000): use a larger step "
     "(got 1e-300 s for 1 s)"},
    {"rk4 one step over max_steps",
     PASSIVE_JOB(",'integrator':{'method':'rk4','step':0.01,'max_steps':99}"), NULL,
     JOB_INVALID_FIELD, "integrator.step",
     "duration / step = 100 steps exceeds integrator.max_steps (99): use a larger step (got "
     "0.01 s for 1 s)"},
    {"rk4 step of 1e-12 without max_steps",
     PASSIVE_JOB(",'integrator':{'method':'rk4','step':1e-12,'max_steps':0}"), NULL,
     JOB_INVALID_FIELD, "integrator.step",
     "duration / step = 1e+12 steps exceeds the bound (1000000000): use a larger step (got "
     "1e-12 s for 1 s)"},
    {"rk4 work over the bound",
     PASSIVE_JOB(",'integrator':{'method':'rk4','step':1e-9,'max_steps':1e9}"), NULL,
     JOB_LIMIT_EXCEEDED, "integrator.step",
     "1e+09 steps x 2 bodies = 2e+09 body-steps exceeds the bound on a job's work (1e+09): use a "
     "larger step, a shorter duration or fewer bodies (got 1e-09 s for 1 s)"},
    {"negative min_step", PASSIVE_JOB(",'integrator':{'min_step':-1}"), NULL, JOB_INVALID_FIELD,
     "integrator", "min_step must be >= 0 and finite (got -1 s)"},
    {"min_step over max_step",
     PASSIVE_JOB(",'integrator':{'method':'bdf','min_step':0.1,'max_step':0.01}"), NULL,
     JOB_INVALID_FIELD, "integrator", "min_step must not exceed max_step (got 0.1 s > 0.01 s)"},
    {"min_step for rk4", PASSIVE_JOB(",'integrator':{'method':'rk4','min_step':0.1}"), NULL,
     JOB_UNKNOWN_FIELD, "integrator.min_step", "key \"min_step\" does not apply to method \"rk4\""},

    /* duration, output, limits */
    {"zero duration", "{" SCENE2 "," PASSIVE ",'duration':0}", NULL, JOB_INVALID_FIELD, "duration",
     "must be positive (got 0 s)"},
    {"two hours", "{" SCENE2 "," PASSIVE ",'duration':7200}", NULL, JOB_LIMIT_EXCEEDED, "duration",
     "must be at most 3600 s (got 7200 s)"},
    {"duration a string", "{" SCENE2 "," PASSIVE ",'duration':'5'}", NULL, JOB_INVALID_FIELD,
     "duration", "must be a number (got a string)"},
    {"zero interval", PASSIVE_JOB(",'output':{'interval':0}"), NULL, JOB_INVALID_FIELD,
     "output.interval", "must be positive (got 0 s)"},
    {"interval beyond the duration", PASSIVE_JOB(",'output':{'interval':2}"), NULL,
     JOB_INVALID_FIELD, "output.interval", "must not exceed the duration (got 2 s > 1 s)"},
    {"too many samples", "{" SCENE2 "," PASSIVE ",'duration':3600}", NULL, JOB_LIMIT_EXCEEDED,
     "output.interval",
     "gives up to 360002 samples over 3600 s; the limit is 200000 (use a longer interval)"},
    {"too many values", NULL, too_many_values, JOB_LIMIT_EXCEEDED, "output",
     "would record up to 60301206 values (100002 samples x 603 per sample); the limit is "
     "20000000 (record fewer channels or use a longer interval)"},
    {"tracking error of a passive run", PASSIVE_JOB(",'output':{'channels':['q','e']}"), NULL,
     JOB_INVALID_FIELD, "output.channels[1]",
     "channel \"e\" needs a controller (this run is passive)"},
    {"unknown channel", PASSIVE_JOB(",'output':{'channels':['x']}"), NULL, JOB_INVALID_FIELD,
     "output.channels[0]",
     "must be one of \"q\", \"qdot\", \"q_des\", \"qdot_des\", \"e\", \"tau\", \"w\", \"energy\", "
     "\"loop\", \"end_effector\", \"body_pose\" (got \"x\")"},
    {"channel twice", PASSIVE_JOB(",'output':{'channels':['q','q']}"), NULL, JOB_INVALID_FIELD,
     "output.channels[1]", "\"q\" is listed twice"},
    {"no channels", PASSIVE_JOB(",'output':{'channels':[]}"), NULL, JOB_INVALID_FIELD,
     "output.channels", "must name at least one channel"},
    {"misspelt output key", PASSIVE_JOB(",'output':{'intervall':0.1}"), NULL, JOB_UNKNOWN_FIELD,
     "output.intervall", "unknown key \"intervall\" (did you mean \"interval\"?)"},
    {"zero speed bound", PASSIVE_JOB(",'limits':{'max_speed':0}"), NULL, JOB_INVALID_FIELD,
     "limits.max_speed", "must be positive (got 0)"},
    {"negative wall time", PASSIVE_JOB(",'limits':{'wall_time':-1}"), NULL, JOB_INVALID_FIELD,
     "limits.wall_time", "must not be negative (got -1 s)"},
    {"no threads", PASSIVE_JOB(",'threads':0"), NULL, JOB_INVALID_FIELD, "threads",
     "must be a whole number from 1 to 64 (got 0)"},
    {"negative threads", PASSIVE_JOB(",'threads':-2"), NULL, JOB_INVALID_FIELD, "threads",
     "must be a whole number from 1 to 64 (got -2)"},
    {"too many threads", PASSIVE_JOB(",'threads':65"), NULL, JOB_INVALID_FIELD, "threads",
     "must be a whole number from 1 to 64 (got 65)"},
    {"fractional threads", PASSIVE_JOB(",'threads':1.5"), NULL, JOB_INVALID_FIELD, "threads",
     "must be a whole number from 1 to 64 (got 1.5)"},
    {"threads a string", PASSIVE_JOB(",'threads':'2'"), NULL, JOB_INVALID_FIELD, "threads",
     "must be a number (got a string)"},
    {"threads in the integrator", PASSIVE_JOB(",'integrator':{'threads':2}"), NULL,
     JOB_UNKNOWN_FIELD, "integrator.threads", "unknown key \"threads\""},

    /* the loop */
    {"dependent joint of an open chain",
     "{'scene':{'bodies':[" BODY "," DEP_BODY "]}," PASSIVE "," DUR "}", NULL, JOB_INVALID_FIELD,
     "scene.bodies[1].joint.independent",
     "must be true: an open chain is fully actuated (only a chain closed by \"scene.loop\" has "
     "dependent joints)"},
    {"independent not a boolean",
     BODY_JOB("{'mass':1,'com':[0,0,0],'inertia':[1,1,1],'joint':{'type':'revolute','axis':[0,0,"
              "1],'independent':1}}"),
     NULL, JOB_INVALID_FIELD, "scene.bodies[0].joint.independent",
     "must be true or false (got a number)"},
    {"loop a number", BAD_LOOP_JOB("1"), NULL, JOB_INVALID_FIELD, "scene.loop",
     "must be an object (got a number)"},
    {"loop without an anchor", BAD_LOOP_JOB("{" CLOSING "}"), NULL, JOB_MISSING_FIELD,
     "scene.loop.anchor", "is required"},
    {"loop without a joint", BAD_LOOP_JOB("{'anchor':[1,0,0]}"), NULL, JOB_MISSING_FIELD,
     "scene.loop.joint", "is required"},
    {"misspelt loop key", BAD_LOOP_JOB("{" CLOSING ",'anchr':[1,0,0]}"), NULL, JOB_UNKNOWN_FIELD,
     "scene.loop.anchr", "unknown key \"anchr\" (did you mean \"anchor\"?)"},
    {"anchor of 2 numbers", BAD_LOOP_JOB("{" CLOSING ",'anchor':[1,0]}"), NULL, JOB_INVALID_FIELD,
     "scene.loop.anchor", "must be an array of 3 numbers (got 2 entries)"},
    {"cylindrical closing joint",
     BAD_LOOP_JOB("{'joint':{'type':'cylindrical','axis':[0,0,1]},'anchor':[1,0,0]}"), NULL,
     JOB_INVALID_FIELD, "scene.loop.joint.type",
     "must be one of \"revolute\", \"prismatic\", \"spherical\" (got \"cylindrical\")"},
    {"closing joint without an axis",
     BAD_LOOP_JOB("{'joint':{'type':'revolute','location':[0,-1,0]},'anchor':[1,0,0]}"), NULL,
     JOB_MISSING_FIELD, "scene.loop.joint.axis", "is required"},
    {"zero closing axis",
     BAD_LOOP_JOB("{'joint':{'type':'prismatic','axis':[0,0,0]},'anchor':[1,0,0]}"), NULL,
     JOB_INVALID_FIELD, "scene.loop.joint.axis", "must have non-zero length (got [0, 0, 0])"},
    {"axis of a spherical closing joint",
     BAD_LOOP_JOB("{'joint':{'type':'spherical','axis':[0,0,1]},'anchor':[1,0,0]}"), NULL,
     JOB_UNKNOWN_FIELD, "scene.loop.joint.axis",
     "key \"axis\" does not apply to joint type \"spherical\""},
    {"closing joint independent flag a string",
     BAD_LOOP_JOB("{'joint':{'type':'revolute','axis':[0,0,1],'independent':'no'},'anchor':[1,0,"
                  "0]}"),
     NULL, JOB_INVALID_FIELD, "scene.loop.joint.independent",
     "must be true or false (got a string)"},
    {"loop on the tip itself", BAD_LOOP_JOB("{" CLOSING ",'anchor':[1,0,0],'body':2}"), NULL,
     JOB_INVALID_FIELD, "scene.loop.body",
     "must be the index of a body before the tip (body 2): a whole number from 0 to 1 (got 2)"},
    {"loop on a fractional body", BAD_LOOP_JOB("{" CLOSING ",'anchor':[1,0,0],'body':0.5}"), NULL,
     JOB_INVALID_FIELD, "scene.loop.body",
     "must be the index of a body before the tip (body 2): a whole number from 0 to 1 (got 0.5)"},
    {"loop on a body named by an index string",
     BAD_LOOP_JOB("{" CLOSING ",'anchor':[1,0,0],'body':'0'}"), NULL, JOB_INVALID_FIELD,
     "scene.loop.body", "\"0\" names no body (give a body's \"name\" or index)"},
    {"loop on a body given as true", BAD_LOOP_JOB("{" CLOSING ",'anchor':[1,0,0],'body':true}"),
     NULL, JOB_INVALID_FIELD, "scene.loop.body", "must be a body's index or name (got a boolean)"},
    {"loop on the ground by name", BAD_LOOP_JOB("{" CLOSING ",'anchor':[1,0,0],'body':'ground'}"),
     NULL, JOB_INVALID_FIELD, "scene.loop.body",
     "\"ground\" names no body (give a body's \"name\" or index)"},

    /* parents: a body before the child, by index, unique name or the ground */
    {"parent named by no body", TREE_JOB("'hand'"), NULL, JOB_INVALID_FIELD,
     "scene.bodies[2].parent",
     "\"hand\" names no body (give a body's \"name\" or index, or \"ground\")"},
    {"parent the body itself by name", TREE_JOB("'tip'"), NULL, JOB_INVALID_FIELD,
     "scene.bodies[2].parent", "\"tip\" must name a body before body 2 (it names body 2)"},
    {"parent a later body by name",
     "{'scene':{'bodies':[" NAMED("arm") "," NAMED_ON("palm", "'tip'") "," NAMED(
         "tip") "]}," PASSIVE "," DUR "}",
     NULL, JOB_INVALID_FIELD, "scene.bodies[1].parent",
     "\"tip\" must name a body before body 1 (it names body 2)"},
    {"parent by a name two bodies have",
     "{'scene':{'bodies':[" NAMED("arm") "," NAMED("arm") "," NAMED_ON("tip", "'arm'") "]}," PASSIVE
                                                                                       "," DUR "}",
     NULL, JOB_INVALID_FIELD, "scene.bodies[2].parent",
     "\"arm\" is the name of bodies 0 and 1: a name used to refer to a body must be unique"},
    {"parent \"ground\" with a body named ground",
     "{'scene':{'bodies':[" NAMED("ground") "," NAMED_ON("tip", "'ground'") "]}," PASSIVE "," DUR
                                                                            "}",
     NULL, JOB_INVALID_FIELD, "scene.bodies[1].parent",
     "\"ground\" is the ground, but body 0 is named \"ground\" too: rename it, or refer to "
     "bodies by index"},
    {"parent index after the child", TREE_JOB("2"), NULL, JOB_INVALID_FIELD,
     "scene.bodies[2].parent",
     "must be -1 (the ground) or the index of a body before body 2: a whole number from -1 to 1 "
     "(got 2)"},
    {"parent index below the ground", TREE_JOB("-2"), NULL, JOB_INVALID_FIELD,
     "scene.bodies[2].parent",
     "must be -1 (the ground) or the index of a body before body 2: a whole number from -1 to 1 "
     "(got -2)"},
    {"fractional parent index", TREE_JOB("0.5"), NULL, JOB_INVALID_FIELD, "scene.bodies[2].parent",
     "must be -1 (the ground) or the index of a body before body 2: a whole number from -1 to 1 "
     "(got 0.5)"},
    {"first body on a body", BODY_JOB(NAMED_ON("arm", "0")), NULL, JOB_INVALID_FIELD,
     "scene.bodies[0].parent",
     "must be -1 or \"ground\": nothing but the ground comes before body 0 (got 0)"},
    {"parent an array", TREE_JOB("[1]"), NULL, JOB_INVALID_FIELD, "scene.bodies[2].parent",
     "must be a body's index or name, or \"ground\" (got an array)"},
    {"parent an empty name", TREE_JOB("''"), NULL, JOB_INVALID_FIELD, "scene.bodies[2].parent",
     "\"\" names no body (give a body's \"name\" or index, or \"ground\")"},
    {"unknown stabilization",
     BAD_LOOP_JOB("{" CLOSING ",'anchor':[1,0,0],'stabilization':{'method':'projection'}}"), NULL,
     JOB_INVALID_FIELD, "scene.loop.stabilization.method",
     "must be one of \"project\", \"baumgarte\", \"none\" (got \"projection\")"},
    {"projection tolerance 0",
     BAD_LOOP_JOB("{" CLOSING ",'anchor':[1,0,0],'stabilization':{'tol':0}}"), NULL,
     JOB_INVALID_FIELD, "scene.loop.stabilization.tol", "must be positive (got 0)"},
    {"tolerance of baumgarte",
     BAD_LOOP_JOB("{" CLOSING ",'anchor':[1,0,0],'stabilization':{'method':'baumgarte','tol':"
                  "1e-9}}"),
     NULL, JOB_UNKNOWN_FIELD, "scene.loop.stabilization.tol",
     "key \"tol\" does not apply to method \"baumgarte\""},
    {"negative baumgarte alpha",
     BAD_LOOP_JOB("{" CLOSING ",'anchor':[1,0,0],'stabilization':{'method':'baumgarte','alpha':"
                  "-1}}"),
     NULL, JOB_INVALID_FIELD, "scene.loop.stabilization.alpha",
     "must not be negative (got -1 1/s)"},
    {"baumgarte of nothing",
     BAD_LOOP_JOB("{" CLOSING ",'anchor':[1,0,0],'stabilization':{'method':'baumgarte','alpha':0,"
                  "'beta':0}}"),
     NULL, JOB_INVALID_FIELD, "scene.loop.stabilization",
     "alpha and beta must not both be 0 (use {\"method\": \"none\"} for no stabilization)"},
    {"condition bound 1", BAD_LOOP_JOB("{" CLOSING ",'anchor':[1,0,0],'cond_max':1}"), NULL,
     JOB_INVALID_FIELD, "scene.loop.cond_max", "must be greater than 1 (got 1)"},
    {"loop of one body", "{'scene':{'bodies':[" BODY "],'loop':" LOOP "}," PASSIVE "," DUR "}",
     NULL, JOB_INVALID_FIELD, "scene.loop", "loop: a loop needs at least 2 bodies (got 1)"},
    {"trajectory of every coordinate of a loop",
     "{" LOOP_SCENE "," PD ",'trajectory':[{'type':'constant','value':0},{'type':'constant','"
     "value':0},{'type':'constant','value':0}]," DUR "}",
     NULL, JOB_INVALID_FIELD, "trajectory",
     "must have 1 entries, one per independent coordinate (got 3)"},
    {"gain overrides of every coordinate of a loop",
     "{" LOOP_SCENE ",'controller':{'type':'pd','kp':100,'kv':20,'joints':[{},{}]}," HOLD "," DUR
     "}",
     NULL, JOB_INVALID_FIELD, "controller.joints",
     "must have 1 entries, one per independent coordinate (got 2)"},
    {"disturbance of a loop not an array", LOOP_PASSIVE_JOB(",'disturbance':3"), NULL,
     JOB_INVALID_FIELD, "disturbance",
     "must be an object or an array of 1 objects, one per independent coordinate (got a number)"},
    {"loop channel of an open chain", PASSIVE_JOB(",'output':{'channels':['q','loop']}"), NULL,
     JOB_INVALID_FIELD, "output.channels[1]", "channel \"loop\" needs a loop (\"scene.loop\")"},
    {"torques of a loop without independent joints",
     "{'scene':{'bodies':[" DEP_BODY "," DEP_BODY "," DEP_BODY "],'loop':" LOOP "," SQUARE_Q0
     "}," PASSIVE "," DUR ",'output':{'channels':['q','tau']}}",
     NULL, JOB_INVALID_FIELD, "output.channels[1]",
     "channel \"tau\" has no columns (the loop has no independent coordinates)"},
    {"controller of an independent spherical closing joint",
     "{'scene':{'bodies':[" BODY "," DEP_BODY "," DEP_BODY "],'loop':{'joint':{'type':'spherical',"
     "'location':[0,-1,0],'independent':true},'anchor':[1,0,0]}," SQUARE_Q0 "}," PD "," HOLD "," DUR
     "}",
     NULL, JOB_INVALID_FIELD, "controller.type",
     "\"pd\" cannot drive the spherical joint of scene.loop (its quaternion error is not a "
     "per-coordinate error); a spherical joint in a loop must be dependent, or the run passive "
     "(controller \"none\")"},

    /* presets */
    {"preset not a string", "{'preset':3}", NULL, JOB_INVALID_FIELD, "preset",
     "must be a string (got a number)"},
    {"preset parameter out of range", "{'preset':'n_link_pendulum','n':1}", NULL, JOB_INVALID_FIELD,
     "n", "must be an integer from 2 to 65536 (got 1)"},
    {"parameter of another preset", "{'preset':'triple_pendulum_pd','n':4}", NULL,
     JOB_UNKNOWN_FIELD, "n", "unknown key \"n\""},
    {"override breaking the preset", "{'preset':'triple_pendulum_pd','controller':{'kv':-1}}", NULL,
     JOB_INVALID_FIELD, "controller", "kv must be positive and finite (got -1)"},
};

Test(job_json, rejects_every_bad_job_with_its_code_field_and_message)
{
    int count = (int)(sizeof bad_jobs / sizeof bad_jobs[0]);
    cr_assert_geq(count, 40);
    for (int i = 0; i < count; i++) {
        const bad_job *b = &bad_jobs[i];
        char *doc = b->make != NULL ? b->make() : fixture_json(b->text);
        job *j = (job *)0x1;
        job_error err;
        int rc = job_parse(doc, strlen(doc), &j, &err);
        cr_expect_eq(rc, -1, "%s: accepted", b->what);
        cr_expect_null(j, "%s: *out not NULL", b->what);
        if (rc == 0) job_free(j);
        cr_expect_eq(err.code, b->code, "%s: code %s, want %s", b->what,
                     job_error_code_name(err.code), job_error_code_name(b->code));
        cr_expect_str_eq(err.field, b->field, "%s: field \"%s\", want \"%s\"", b->what, err.field,
                         b->field);
        cr_expect_str_eq(err.message, b->message, "%s: message\n  \"%s\", want\n  \"%s\"", b->what,
                         err.message, b->message);
        free(doc);
    }
}

Test(job_json, unknown_preset_lists_every_preset)
{
    int count;
    const preset *list = presets_list(&count);
    char want[1024];
    size_t used = (size_t)snprintf(want, sizeof want, "unknown preset \"nope\" (the presets are: ");
    for (int i = 0; i < count; i++) {
        used +=
            (size_t)snprintf(want + used, sizeof want - used, "%s%s", i ? ", " : "", list[i].name);
    }
    snprintf(want + used, sizeof want - used, ")");

    const char *doc = "{\"preset\": \"nope\", \"duration\": 1}";
    job *j;
    job_error err;
    cr_assert_eq(job_parse(doc, strlen(doc), &j, &err), -1);
    cr_assert_eq(err.code, JOB_UNKNOWN_PRESET);
    cr_assert_str_eq(err.field, "preset");
    cr_assert_str_eq(err.message, want);
}

Test(job_json, names_are_limited_to_JOB_MAX_NAME_bytes)
{
    char *ok = name_of_length(JOB_MAX_NAME), *long_name = name_of_length(JOB_MAX_NAME + 1);
    job *j;
    job_error err;
    cr_assert_eq(job_parse(ok, strlen(ok), &j, &err), 0, "%s", err.message);
    cr_assert_eq(strlen(j->name), JOB_MAX_NAME);
    job_free(j);
    cr_assert_eq(job_parse(long_name, strlen(long_name), &j, &err), -1);
    cr_assert_eq(err.code, JOB_INVALID_FIELD);
    cr_assert_str_eq(err.field, "name");
    cr_assert_str_eq(err.message, "must be at most 200 bytes long (got 201)");
    free(ok);
    free(long_name);
}

Test(job_json, rk4_work_is_bounded_by_steps_times_bodies)
{
    /* 4e8 steps x 2 bodies = 8e8 body-steps pass; 6e8 x 2 = 1.2e9 are refused (the message is
       in the table of bad jobs): the bound counts bodies, not steps alone */
    job *j = fixture_parse_ok(
        PASSIVE_JOB(",'integrator':{'method':'rk4','step':2.5e-9,'max_steps':1e9}"));
    cr_assert_eq(j->spec.chain.nbodies, 2);
    job_free(j);
    char *text =
        fixture_json(PASSIVE_JOB(",'integrator':{'method':'rk4','step':1.6e-9,'max_steps':1e9}"));
    job_error err;
    cr_assert_eq(job_parse(text, strlen(text), &j, &err), -1);
    cr_assert_eq(err.code, JOB_LIMIT_EXCEEDED);
    cr_assert_str_eq(err.field, "integrator.step");
    free(text);
}

Test(job_json, reads_exactly_len_bytes_of_unterminated_text)
{
    /* a buffer of exactly len bytes, no NUL: the sanitizer build catches any read beyond it */
    char *doc = fixture_json(PASSIVE_JOB(""));
    size_t len = strlen(doc);
    char *exact = malloc(len);
    memcpy(exact, doc, len);
    job *j;
    job_error err;
    cr_assert_eq(job_parse(exact, len, &j, &err), 0, "%s", err.message);
    job_free(j);
    cr_assert_eq(job_parse(exact, len - 1, &j, &err), -1, "the closing brace is cut off");
    cr_assert_eq(err.code, JOB_INVALID_JSON);

    /* bytes after len are not read; within len they are text after the document */
    char *longer = malloc(len + 3);
    memcpy(longer, doc, len);
    memcpy(longer + len, "]]]", 3);
    cr_assert_eq(job_parse(longer, len, &j, &err), 0, "%s", err.message);
    job_free(j);
    cr_assert_eq(job_parse(longer, len + 1, &j, &err), -1);
    cr_assert_eq(err.code, JOB_INVALID_JSON);
    free(exact);
    free(longer);
    free(doc);
}

/* ---- what a valid job turns into ---- */

Test(job_json, fills_every_default_of_a_minimal_planar_job)
{
    job *j = fixture_parse_ok("{" SCENE1 "," PASSIVE "," DUR "}");
    const ctc_sim_spec *s = &j->spec;
    cr_assert_str_eq(j->name, "job");
    cr_assert_null(j->preset);
    cr_assert_eq(j->nq, 1);
    cr_assert_eq(j->nv, 1);
    cr_assert_eq(s->chain.nbodies, 1);
    cr_assert_eq(s->chain.form, CTC_FORM_AUTO);
    cr_assert(s->chain.gravity[0] == 0 && s->chain.gravity[1] == -9.81 && s->chain.gravity[2] == 0);
    cr_assert_eq(s->chain.bodies[0].mass, 1);
    cr_assert_eq(s->chain.bodies[0].inertia[4], 0.1);
    cr_assert_eq(s->chain.joints[0].location[1], 0);
    cr_assert_eq(s->q0[0], 0);
    cr_assert_eq(s->v0[0], 0);
    cr_assert_eq(s->controller, CTC_CTRL_NONE);
    cr_assert_null(j->gains);
    cr_assert_null(j->traj);
    cr_assert_null(j->disturb);
    cr_assert_null(s->disturb);
    cr_assert_eq(s->model_mass_scale, 1);
    cr_assert_eq(s->model_inertia_scale, 1);
    cr_assert_eq(s->integrator.method, CTC_INTEG_DOPRI5);
    cr_assert_eq(s->integrator.rtol, 1e-8);
    cr_assert_eq(s->integrator.atol, 1e-10);
    cr_assert_eq(s->integrator.initial_step, 0);
    cr_assert_eq(s->integrator.max_step, 0);
    cr_assert_eq(s->integrator.max_steps, 10000000);
    cr_assert_eq(s->duration, 1);
    cr_assert_eq(s->output_interval, 0.01);
    unsigned passive = CTC_CH_BIT(CTC_CH_Q) | CTC_CH_BIT(CTC_CH_QD) | CTC_CH_BIT(CTC_CH_TAU) |
                       CTC_CH_BIT(CTC_CH_ENERGY);
    cr_assert_eq(s->channels, passive);
    cr_assert_eq(s->max_speed, 1e6);
    cr_assert_eq(s->wall_limit, 0);
    cr_assert_eq(s->threads, 1);
    job_free(j);

    /* rk4's step; an interval no longer than a short duration; every channel with a controller */
    j = fixture_parse_ok("{" SCENE1 "," PD "," HOLD
                         ",'duration':0.004,'integrator':{'method':'rk4'}}");
    cr_assert_eq(j->spec.integrator.step, 1e-3);
    cr_assert_eq(j->spec.output_interval, 0.004);
    cr_assert_eq(j->spec.channels,
                 CTC_CH_ALL & ~CTC_CH_BIT(CTC_CH_LOOP) & ~CTC_CH_BIT(CTC_CH_EE) &
                     ~CTC_CH_BIT(CTC_CH_POSE),
                 "loop: no loop; end_effector: no point; body_pose: no bodies");
    cr_assert_null(j->spec.chain.loop);
    cr_assert_null(j->spec.chain.independent);
    cr_assert_eq(j->nind, j->nv);
    job_free(j);
}

Test(job_json, a_loop_counts_its_independent_coordinates_and_fills_its_defaults)
{
    job *j = fixture_parse_ok(LOOP_PD_JOB(""));
    const ctc_sim_spec *s = &j->spec;
    cr_assert_eq(j->nq, 3);
    cr_assert_eq(j->nv, 3);
    cr_assert_eq(j->nind, 1, "joint 0 alone is independent");
    cr_assert_eq(s->chain.loop, &j->loop);
    cr_assert_eq(s->chain.independent, j->independent);
    static const unsigned char flags[4] = {1, 0, 0, 0};
    for (int k = 0; k < 4; k++) cr_assert_eq(j->independent[k], flags[k], "joint %d", k);
    cr_assert_eq(j->loop.joint.type, CTC_JOINT_REVOLUTE);
    cr_assert(j->loop.joint.axis[2] == 1 && j->loop.joint.location[1] == -1);
    cr_assert(j->loop.anchor[0] == 1 && j->loop.anchor[1] == 0 && j->loop.anchor[2] == 0);
    cr_assert_eq(s->loop_stab, CTC_LOOP_PROJECT);
    cr_assert_eq(s->loop_tol, 1e-12);
    cr_assert_eq(s->loop_cond_max, 1e5, "the documented default (api/job.schema.json)");
    cr_assert_eq(s->channels, CTC_CH_ALL & ~CTC_CH_BIT(CTC_CH_EE) & ~CTC_CH_BIT(CTC_CH_POSE),
                 "every channel, the loop's included (end_effector: no point; body_pose: no "
                 "bodies)");
    cr_assert(j->gains[0].kp == 100 && j->gains[0].kv == 20 && j->gains[0].ki == 0);
    cr_assert_eq(j->traj[0].type, CTC_TRAJ_CONSTANT);

    /* the normalised loop: every key in order, defaults written */
    const cJSON *scene = cJSON_GetObjectItemCaseSensitive(j->normalised, "scene");
    char *text = cJSON_PrintUnformatted(cJSON_GetObjectItemCaseSensitive(scene, "loop"));
    char *want =
        fixture_json("{'joint':{'type':'revolute','axis':[0,0,1],'location':[0,-1,0],"
                     "'independent':false},'anchor':[1,0,0],'stabilization':{'method':'project',"
                     "'tol':1e-12},'cond_max':100000}");
    cr_assert_str_eq(text, want);
    free(text);
    free(want);
    job_free(j);

    /* baumgarte with its defaults; no stabilization; the closing joint independent instead of
       joint 0: still one coordinate, the closing joint's */
    j = fixture_parse_ok(
        "{'scene':{'bodies':[" DEP_BODY "," DEP_BODY "," DEP_BODY "],'loop':{'joint':{"
        "'type':'revolute','axis':[0,0,1],'location':[0,-1,0],'independent':true},"
        "'anchor':[1,0,0],'stabilization':{'method':'baumgarte','beta':5},'cond_max':1e8}"
        "," SQUARE_Q0 "}," PD "," HOLD "," DUR "}");
    cr_assert_eq(j->nind, 1);
    cr_assert(j->independent[0] == 0 && j->independent[3] == 1);
    cr_assert_eq(j->spec.loop_stab, CTC_LOOP_BAUMGARTE);
    cr_assert(j->spec.baumgarte[0] == 10 && j->spec.baumgarte[1] == 5);
    cr_assert_eq(j->spec.loop_cond_max, 1e8);
    job_free(j);
    j = fixture_parse_ok("{" LOOP_SCENE_WITH("{" CLOSING
                                             ",'anchor':[1,0,0],'stabilization':{'method':"
                                             "'none'}}") "," PASSIVE "," DUR "}");
    cr_assert_eq(j->spec.loop_stab, CTC_LOOP_NONE);
    cr_assert_eq(j->spec.channels, CTC_CH_BIT(CTC_CH_Q) | CTC_CH_BIT(CTC_CH_QD) |
                                       CTC_CH_BIT(CTC_CH_TAU) | CTC_CH_BIT(CTC_CH_ENERGY) |
                                       CTC_CH_BIT(CTC_CH_LOOP));
    job_free(j);

    /* a passive loop may leave every joint dependent: no coordinate, no torque channel */
    j = fixture_parse_ok("{'scene':{'bodies':[" DEP_BODY "," DEP_BODY "," DEP_BODY "],'loop':" LOOP
                         "," SQUARE_Q0 "}," PASSIVE
                         ",'disturbance':{'type':'constant','value':1}," DUR "}");
    cr_assert_eq(j->nind, 0);
    cr_assert_null(j->spec.disturb, "a disturbance of no coordinate is none");
    cr_assert_eq(j->spec.channels, CTC_CH_BIT(CTC_CH_Q) | CTC_CH_BIT(CTC_CH_QD) |
                                       CTC_CH_BIT(CTC_CH_ENERGY) | CTC_CH_BIT(CTC_CH_LOOP));
    job_free(j);
}

Test(job_json, shapes_give_the_textbook_bodies_in_a_spatial_scene)
{
    /* box 1 x 0.1 x 0.2 of 3 kg at (0.5, 0, 0); cylinder r 0.1, L 0.6 of 2 kg along x */
    job *j =
        fixture_parse_ok("{'scene':{'gravity':[0,0,-9.81],'bodies':["
                         "{'mass':3,'shape':{'type':'box','size':[1,0.1,0.2],'centre':[0.5,0,0]},"
                         "'joint':{'type':'revolute','axis':[0,0,2]}},"
                         "{'mass':2,'shape':{'type':'cylinder','radius':0.1,'length':0.6,"
                         "'axis':[1,0,0]},'joint':{'type':'cylindrical','axis':[1,0,0],"
                         "'location':[1,0,0]}}]}," PASSIVE "," DUR "}");
    const ctc_body_spec *box = &j->bodies[0], *cyl = &j->bodies[1];
    cr_assert_eq(j->nv, 3);
    cr_assert_eq(box->mass, 3);
    cr_assert(box->com[0] == 0.5 && box->com[1] == 0 && box->com[2] == 0);
    cr_assert_float_eq(box->inertia[0], 3.0 / 12 * (0.01 + 0.04), 1e-15);
    cr_assert_float_eq(box->inertia[4], 3.0 / 12 * (1 + 0.04), 1e-15);
    cr_assert_float_eq(box->inertia[8], 3.0 / 12 * (1 + 0.01), 1e-15);
    cr_assert_eq(box->inertia[1], 0);
    cr_assert_float_eq(cyl->inertia[0], 2 * 0.01 / 2, 1e-15);
    cr_assert_float_eq(cyl->inertia[4], 2 * (3 * 0.01 + 0.36) / 12, 1e-15);
    cr_assert_float_eq(cyl->inertia[8], 2 * (3 * 0.01 + 0.36) / 12, 1e-15);
    cr_assert_eq(j->joints[0].axis[2], 2, "axes are kept as given (the builder normalises)");
    cr_assert_eq(j->joints[1].type, CTC_JOINT_CYLINDRICAL);
    cr_assert_eq(j->joints[1].location[0], 1);
    job_free(j);
}

Test(job_json, inertia_as_rows_equals_inertia_as_a_diagonal)
{
    job *rows =
        fixture_parse_ok(BODY_JOB("{'mass':2,'com':[0.1,0.2,0.3],'inertia':[[1,0,0],[0,2,0],"
                                  "[0,0,2.5]],'joint':" REV "}"));
    job *diag = fixture_parse_ok(
        BODY_JOB("{'mass':2,'com':[0.1,0.2,0.3],'inertia':[1,2,2.5],'joint':" REV "}"));
    for (int i = 0; i < 9; i++) {
        cr_assert_eq(rows->bodies[0].inertia[i], diag->bodies[0].inertia[i], "inertia[%d]", i);
    }
    cr_assert_eq(rows->bodies[0].com[2], 0.3);

    /* a full tensor keeps its products of inertia */
    job *full =
        fixture_parse_ok(BODY_JOB("{'mass':2,'com':[0,0,0],'inertia':[[2,0.1,0],[0.1,2,0],[0,0,"
                                  "3]],'joint':" REV "}"));
    cr_assert_eq(full->bodies[0].inertia[1], 0.1);
    cr_assert_eq(full->bodies[0].inertia[3], 0.1);
    job_free(rows);
    job_free(diag);
    job_free(full);
}

static void expect_gains(const ctc_gains *g, double ki, double kp, double kv, double tol,
                         const char *what)
{
    cr_assert_leq(fabs(g->ki - ki), tol * fmax(1, ki), "%s: ki %.17g, want %g", what, g->ki, ki);
    cr_assert_leq(fabs(g->kp - kp), tol * fmax(1, kp), "%s: kp %.17g, want %g", what, g->kp, kp);
    cr_assert_leq(fabs(g->kv - kv), tol * fmax(1, kv), "%s: kv %.17g, want %g", what, g->kv, kv);
}

Test(job_json, every_controller_type_designs_the_paper_gains)
{
    /* none */
    job *j = fixture_parse_ok(PASSIVE_JOB(""));
    cr_assert_null(j->spec.gains);
    job_free(j);

    /* pd and pid as given (paper 7.1: kp 100, kv 20, ki 250) */
    j = fixture_parse_ok(CTRL_JOB("{'type':'pd','kp':100,'kv':20}"));
    cr_assert_eq(j->spec.controller, CTC_CTRL_PD);
    for (int i = 0; i < 2; i++) expect_gains(&j->gains[i], 0, 100, 20, 0, "pd");
    cr_assert_eq(j->spec.gains, j->gains);
    job_free(j);
    j = fixture_parse_ok(CTRL_JOB("{'type':'pid','kp':100,'kv':20,'ki':250}"));
    expect_gains(&j->gains[1], 250, 100, 20, 0, "pid");
    job_free(j);

    /* zeta and tau: wn = 1/tau, kp = wn^2, kv = 2 zeta wn */
    j = fixture_parse_ok(CTRL_JOB("{'type':'pid','zeta':0.7,'tau':0.1,'ki':50}"));
    expect_gains(&j->gains[0], 50, 100, 14, 1e-14, "pid from zeta, tau");
    job_free(j);

    /* poles (-2, -2.1, -2.2): K = (9.24, 13.22, 6.3); a conjugate pair -1 +- 2i with -3:
       (s^2 + 2s + 5)(s + 3) = s^3 + 5 s^2 + 11 s + 15 */
    j = fixture_parse_ok(CTRL_JOB("{'type':'poles','poles':[-2,-2.1,-2.2]}"));
    expect_gains(&j->gains[0], 9.24, 13.22, 6.3, 1e-14, "poles");
    job_free(j);
    j = fixture_parse_ok(
        CTRL_JOB("{'type':'poles','poles':[{'re':-1,'im':2},-3,{'re':-1,'im':-2}]}"));
    expect_gains(&j->gains[1], 15, 11, 5, 1e-14, "complex poles");
    job_free(j);

    /* LQR, Q = I, lambda = 0.01: K = (10, 18.2674, 11.6848), as rows or as a diagonal */
    j = fixture_parse_ok(CTRL_JOB("{'type':'lqr','Q':[[1,0,0],[0,1,0],[0,0,1]],'lambda':0.01}"));
    expect_gains(&j->gains[0], 10, 18.2674, 11.6848, 1e-5, "lqr");
    job_free(j);
    j = fixture_parse_ok(CTRL_JOB("{'type':'lqr','Q':[1,1,1],'lambda':0.01}"));
    expect_gains(&j->gains[1], 10, 18.2674, 11.6848, 1e-5, "lqr, diagonal Q");
    job_free(j);
}

Test(job_json, per_coordinate_overrides_replace_the_shared_gains)
{
    /* three coordinates: kept, kp replaced, switched to zeta and tau */
    job *j = fixture_parse_ok(
        "{'scene':{'bodies':[" BODY "," BODY2 "," BODY2 "]},'controller':{'type':"
        "'pid','kp':100,'kv':20,'ki':250,'joints':[{},{'kp':50},{'zeta':1,'tau':0.2,"
        "'ki':10}]}," HOLD "," DUR "}");
    expect_gains(&j->gains[0], 250, 100, 20, 0, "kept");
    expect_gains(&j->gains[1], 250, 50, 20, 0, "kp replaced");
    expect_gains(&j->gains[2], 10, 25, 10, 1e-14, "zeta and tau");
    job_free(j);

    /* lqr: one coordinate with its own lambda; poles: one with its own poles */
    j = fixture_parse_ok(
        CTRL_JOB("{'type':'lqr','Q':[1,1,1],'lambda':1,'joints':[{'lambda':0.01},{}]}"));
    expect_gains(&j->gains[0], 10, 18.2674, 11.6848, 1e-5, "lambda override");
    /* Q = I, lambda = 1: p(s) p(-s) = -s^6 + s^4 - s^2 + 1 gives ki = 1, kp = kv = 1 + sqrt 2 */
    expect_gains(&j->gains[1], 1, 1 + sqrt(2.0), 1 + sqrt(2.0), 1e-12, "lambda 1");
    job_free(j);
    j = fixture_parse_ok(
        CTRL_JOB("{'type':'poles','poles':[-1,-1,-1],'joints':[{},{'poles':[-2,-2.1,"
                 "-2.2]}]}"));
    expect_gains(&j->gains[0], 1, 3, 3, 1e-14, "(s + 1)^3");
    expect_gains(&j->gains[1], 9.24, 13.22, 6.3, 1e-14, "poles override");
    job_free(j);
}

Test(job_json, one_trajectory_object_serves_every_coordinate)
{
    /* a cylindrical joint has two coordinates; a spline gives each its own knots */
    job *j =
        fixture_parse_ok("{'scene':{'bodies':[{'mass':1,'com':[0,0,0],'inertia':[1,1,1],'joint':{"
                         "'type':'cylindrical','axis':[0,0,1]}}]}," PD ",'trajectory':{'type':"
                         "'spline','times':[0,0.5,1],'values':[0,1,0]}," DUR "}");
    cr_assert_eq(j->nv, 2);
    for (int i = 0; i < 2; i++) {
        cr_assert_eq(j->traj[i].type, CTC_TRAJ_SPLINE);
        cr_assert_eq(j->traj[i].nknots, 3);
        cr_assert_eq(j->traj[i].boundary, CTC_SPLINE_CLAMPED);
        cr_assert_not_null(j->traj[i].knots);
    }
    cr_assert_neq(j->traj[0].knots, j->traj[1].knots);
    double at[3];
    ctc_traj_eval(&j->traj[1], 0.5, at);
    cr_assert_float_eq(at[0], 1, 1e-12);
    job_free(j);

    /* an array: one type per coordinate, defaults filled */
    j = fixture_parse_ok(TRAJ_JOB("[{'type':'cosine','amplitude':0.6,'period':1.5},"
                                  "{'type':'min_jerk','from':0,'to':1,'start':0.2,'end':0.8}]"));
    cr_assert_eq(j->traj[0].type, CTC_TRAJ_COSINE);
    cr_assert_eq(j->traj[0].period, 1.5);
    cr_assert_eq(j->traj[0].phase, 0);
    cr_assert_eq(j->traj[0].offset, 0);
    cr_assert_eq(j->traj[1].type, CTC_TRAJ_MIN_JERK);
    cr_assert(j->traj[1].q1 == 1 && j->traj[1].t0 == 0.2 && j->traj[1].t1 == 0.8);
    job_free(j);
}

Test(job_json, plant_terms_reach_the_spec_and_an_ideal_plant_leaves_none)
{
    job *j = fixture_parse_ok(PD_JOB(",'plant':[{'torque_limit':50},{}]"));
    cr_assert_not_null(j->spec.plant);
    cr_expect_eq(j->spec.plant[0].torque_limit, 50);
    cr_expect_eq(j->spec.plant[1].torque_limit, 0, "no key: no limit");
    job_free(j);
    j = fixture_parse_ok(PD_JOB(",'plant':[{},{}]"));
    cr_expect_null(j->spec.plant, "a plant with no term is the ideal one");
    job_free(j);
    j = fixture_parse_ok(PASSIVE_JOB(",'plant':{'viscous':0.5,'coulomb':2,'coulomb_velocity':0.01,"
                                     "'spring':3,'spring_rest':-0.1,'known':true}"));
    cr_assert_not_null(j->spec.plant, "joint forces apply to a passive run too");
    for (int i = 0; i < 2; i++) {
        const ctc_plant_coord *pc = &j->spec.plant[i];
        cr_expect(pc->viscous == 0.5 && pc->coulomb == 2 && pc->coulomb_velocity == 0.01 &&
                  pc->spring == 3 && pc->spring_rest == -0.1 && pc->known == 1);
    }
    job_free(j);
    j = fixture_parse_ok(PD_JOB(",'plant':[{},{'armature':0.25}]"));
    cr_assert_not_null(j->spec.plant, "an armature alone is a plant term");
    cr_expect(j->spec.plant[0].armature == 0 && j->spec.plant[1].armature == 0.25);
    job_free(j);
}

Test(job_json, a_disturbance_that_is_none_everywhere_leaves_none)
{
    job *j = fixture_parse_ok(PASSIVE_JOB(",'disturbance':[{'type':'none'},{'type':'none'}]"));
    cr_assert_null(j->spec.disturb);
    job_free(j);
    j = fixture_parse_ok(PASSIVE_JOB(",'disturbance':[{'type':'none'},{'type':'step','value':0.2,"
                                     "'time':0.5}]"));
    cr_assert_eq(j->spec.disturb, j->disturb);
    cr_assert_eq(j->disturb[0].type, CTC_DISTURB_NONE);
    cr_assert_eq(j->disturb[1].type, CTC_DISTURB_STEP);
    cr_assert(j->disturb[1].value == 0.2 && j->disturb[1].time == 0.5);
    job_free(j);
}

Test(job_json, spherical_joints_start_at_the_identity_quaternion)
{
    job *j =
        fixture_parse_ok("{'scene':{'bodies':[{'mass':1,'com':[0,0,-0.5],'inertia':[1,1,1],'joint':"
                         "{'type':'spherical'}}],'v0':[0,1,0]}," PASSIVE "," DUR "}");
    cr_assert_eq(j->nq, 4);
    cr_assert_eq(j->nv, 3);
    cr_assert(j->q0[0] == 1 && j->q0[1] == 0 && j->q0[2] == 0 && j->q0[3] == 0);
    cr_assert_eq(j->v0[1], 1);
    job_free(j);
}

Test(job_json, the_spec_runs)
{
    /* a passive and a controlled job, a few samples each */
    const char *jobs[] = {
        "{" SCENE2 "," PASSIVE ",'duration':0.05}",
        "{" SCENE2 "," PD ",'trajectory':{'type':'sine','amplitude':0.1,'period':1},"
        "'disturbance':{'type':'constant','value':0.2},'duration':0.05,"
        "'integrator':{'method':'rk4','step':0.001}}",
    };
    for (int i = 0; i < 2; i++) {
        job *j = fixture_parse_ok(jobs[i]);
        ctc_sim_result *r = fixture_run_done(&j->spec);
        cr_assert_eq(r->nsamples, 6);
        cr_assert_eq(r->channels, j->spec.channels);
        ctc_sim_result_free(r);
        job_free(j);
    }
}

/* ---- presets ---- */

Test(job_json, preset_name_names_an_overridden_controller)
{
    /* another controller type (its object replaced whole): the name says which, and that the
       paper ran only the scene */
    job *j =
        fixture_parse_ok("{'preset':'triple_pendulum_pid','controller':{'type':'lqr','Q':[1,1,1],"
                         "'lambda':0.01}}");
    cr_assert_eq(j->spec.controller, CTC_CTRL_LQR);
    cr_assert_str_eq(j->name, "Triple pendulum, LQR (scene of Kingsley et al. 2017, sec. 7.1)");
    job_free(j);
    j = fixture_parse_ok("{'preset':'spatial_double_pendulum_pd','controller':{'type':'poles',"
                         "'poles':[-2,-2.1,-2.2]}}");
    cr_assert_str_eq(j->name, "Spatial double pendulum, pole placement (scene of Kingsley et al. "
                              "2017, sec. 7.1; gravity -z)");
    job_free(j);
    j = fixture_parse_ok(
        "{'preset':'n_link_pendulum','n':5,'controller':{'type':'pid','kp':100,'kv':20,"
        "'ki':10}}");
    cr_assert_str_eq(j->name, "5-link pendulum, PID (scene of Kingsley et al. 2017, sec. 7.3)");
    job_free(j);
    j = fixture_parse_ok(
        "{'preset':'triple_pendulum_pd','controller':{'type':'none'},'trajectory':null,"
        "'disturbance':null}");
    cr_assert_str_eq(j->name, "Triple pendulum, passive (scene of Kingsley et al. 2017, sec. 7.1)");
    job_free(j);
    j = fixture_parse_ok("{'preset':'arm_four_bar_pd','controller':{'type':'pid','kp':100,'kv':20,"
                         "'ki':10}}");
    cr_assert_str_eq(j->name, "Four-bar linkage on a swinging arm, PID");
    job_free(j);

    /* the same type with other gains is named after them (job_name.h); a name given is kept */
    j = fixture_parse_ok("{'preset':'triple_pendulum_pd','controller':{'kp':400,'kv':40}}");
    cr_assert_str_eq(j->name, "triple_pendulum_pd, kp = 400, kv = 40");
    job_free(j);
    j = fixture_parse_ok(
        "{'preset':'triple_pendulum_pid','name':'mine','controller':{'type':'pd','kp':1,'kv':2}}");
    cr_assert_str_eq(j->name, "mine");
    job_free(j);
}

Test(job_json, preset_name_for_controller_replaces_the_label_only)
{
    char buf[JOB_MAX_NAME + 1];
    cr_assert_eq(presets_name_for_controller("Triple pendulum, PD (Kingsley et al. 2017, sec. 7.1)",
                                             "pd", "pid", buf, sizeof buf),
                 0);
    cr_assert_str_eq(buf, "Triple pendulum, PID (scene of Kingsley et al. 2017, sec. 7.1)");
    cr_assert_eq(presets_name_for_controller("Spatial RSSR linkage, passive (gravity -z)", "none",
                                             "pd", buf, sizeof buf),
                 0);
    cr_assert_str_eq(buf, "Spatial RSSR linkage, PD (gravity -z)");
    cr_assert_eq(presets_name_for_controller("my rods", "pd", "lqr", buf, sizeof buf), 0);
    cr_assert_str_eq(buf, "my rods, LQR", "no label to replace: appended");
    cr_assert_eq(presets_name_for_controller("x, PID", "pd", "lqr", buf, sizeof buf), 0);
    cr_assert_str_eq(buf, "x, PID, LQR", "\", PD\" is not found inside \", PID\"");
    strcpy(buf, "untouched");
    cr_assert_eq(presets_name_for_controller("x, PD", "pd", "mpc", buf, sizeof buf), -1);
    cr_assert_str_eq(buf, "untouched");
}

Test(job_json, preset_overrides_are_an_rfc7386_merge_patch)
{
    /* objects merge key by key, null deletes, anything else replaces */
    job *j = fixture_parse_ok("{'preset':'triple_pendulum_pd','name':null,'disturbance':null,"
                              "'controller':{'kp':50},'duration':1,'output':{'interval':0.1}}");
    cr_assert_str_eq(j->preset, "triple_pendulum_pd");
    cr_assert_str_eq(j->name, "triple_pendulum_pd", "a deleted name defaults to the preset's");
    cr_assert_null(j->spec.disturb);
    cr_assert_eq(j->spec.controller, CTC_CTRL_PD);
    expect_gains(&j->gains[2], 0, 50, 20, 0, "kp overridden, kv kept");
    cr_assert_eq(j->spec.duration, 1);
    cr_assert_eq(j->spec.output_interval, 0.1);
    cr_assert_eq(j->traj[1].type, CTC_TRAJ_COSINE, "the preset's trajectory is kept");
    job_free(j);

    /* an array replaces the preset's whole array; a parameter is taken out of the patch */
    j = fixture_parse_ok(
        "{'preset':'n_link_pendulum','n':3,'scene':{'q0':[0.1,0.2,0.3]},"
        "'trajectory':[{'type':'constant','value':1},{'type':'constant','value':2},"
        "{'type':'constant','value':3}]}");
    cr_assert_eq(j->spec.chain.nbodies, 3);
    cr_assert(j->q0[0] == 0.1 && j->q0[2] == 0.3);
    cr_assert_eq(j->traj[2].value, 3);
    cr_assert_str_eq(j->preset, "n_link_pendulum");
    job_free(j);

    /* a new object below a key the preset lacks: nulls inside it are dropped */
    j = fixture_parse_ok(
        "{'preset':'triple_pendulum_passive','limits':{'max_speed':100,'wall_time':null}}");
    cr_assert_eq(j->spec.max_speed, 100);
    cr_assert_eq(j->spec.wall_limit, 0);
    job_free(j);

    /* a changed controller type or method replaces the object, and the nulls that remove the old
       kind's keys are dropped with it rather than read as the new kind's keys */
    j = fixture_parse_ok(
        "{'preset':'triple_pendulum_pid','controller':{'type':'pd','kp':50,'kv':10,"
        "'ki':null},'integrator':{'method':'rk4','step':0.001,'rtol':null}}");
    cr_assert_eq(j->spec.controller, CTC_CTRL_PD);
    expect_gains(&j->gains[0], 0, 50, 10, 0, "the pd of the patch, no ki");
    cr_assert_eq(j->spec.integrator.method, CTC_INTEG_RK4);
    job_free(j);
}

/* ---- the normalised document ---- */

static void expect_same_traj(const ctc_traj *a, const ctc_traj *b, int i)
{
    cr_assert_eq(a->type, b->type, "traj[%d].type", i);
    cr_assert(a->value == b->value && a->amplitude == b->amplitude && a->period == b->period &&
                  a->phase == b->phase && a->offset == b->offset,
              "traj[%d] sinusoid or constant", i);
    cr_assert_eq(a->ncoef, b->ncoef, "traj[%d].ncoef", i);
    for (int c = 0; c < a->ncoef; c++) cr_assert_eq(a->coef[c], b->coef[c], "traj[%d].coef", i);
    cr_assert(a->q0 == b->q0 && a->q1 == b->q1 && a->t0 == b->t0 && a->t1 == b->t1,
              "traj[%d] min_jerk", i);
    cr_assert_eq(a->nknots, b->nknots, "traj[%d].nknots", i);
    cr_assert_eq(a->boundary, b->boundary, "traj[%d].boundary", i);
    for (int k = 0; k < 5 * a->nknots; k++) {
        cr_assert_eq(a->knots[k], b->knots[k], "traj[%d].knots[%d]", i, k);
    }
}

/* every number and setting of two jobs' specs is the same */
static void expect_same_job(const job *a, const job *b)
{
    const ctc_sim_spec *s = &a->spec, *t = &b->spec;
    cr_assert_str_eq(a->name, b->name);
    cr_assert(a->nq == b->nq && a->nv == b->nv && a->nind == b->nind);
    cr_assert_eq(s->chain.nbodies, t->chain.nbodies);
    cr_assert_eq(s->chain.form, t->chain.form);
    for (int i = 0; i < 3; i++) cr_assert_eq(s->chain.gravity[i], t->chain.gravity[i]);
    for (int k = 0; k < s->chain.nbodies; k++) {
        const ctc_body_spec *x = &s->chain.bodies[k], *y = &t->chain.bodies[k];
        const ctc_joint_spec *p = &s->chain.joints[k], *q = &t->chain.joints[k];
        cr_assert_eq(x->mass, y->mass, "body %d mass", k);
        for (int i = 0; i < 3; i++) cr_assert_eq(x->com[i], y->com[i], "body %d com", k);
        for (int i = 0; i < 9; i++) cr_assert_eq(x->inertia[i], y->inertia[i], "body %d I", k);
        cr_assert_eq(p->type, q->type, "joint %d type", k);
        for (int i = 0; i < 3; i++) {
            cr_assert_eq(p->axis[i], q->axis[i], "joint %d axis", k);
            cr_assert_eq(p->location[i], q->location[i], "joint %d location", k);
        }
    }
    cr_assert_eq(s->chain.loop == NULL, t->chain.loop == NULL);
    cr_assert_eq(s->chain.independent == NULL, t->chain.independent == NULL);
    for (int k = 0; s->chain.independent && k <= s->chain.nbodies; k++) {
        cr_assert_eq(s->chain.independent[k], t->chain.independent[k], "independent[%d]", k);
    }
    if (s->chain.loop) {
        const ctc_loop_spec *x = s->chain.loop, *y = t->chain.loop;
        cr_assert_eq(x->joint.type, y->joint.type);
        for (int i = 0; i < 3; i++) {
            cr_assert_eq(x->joint.axis[i], y->joint.axis[i], "loop axis");
            cr_assert_eq(x->joint.location[i], y->joint.location[i], "loop location");
            cr_assert_eq(x->anchor[i], y->anchor[i], "anchor");
        }
        cr_assert_eq(s->loop_stab, t->loop_stab);
        cr_assert_eq(s->loop_tol, t->loop_tol);
        cr_assert(s->baumgarte[0] == t->baumgarte[0] && s->baumgarte[1] == t->baumgarte[1]);
        cr_assert_eq(s->loop_cond_max, t->loop_cond_max);
    }
    for (int i = 0; i < a->nq; i++) cr_assert_eq(s->q0[i], t->q0[i], "q0[%d]", i);
    for (int i = 0; i < a->nv; i++) cr_assert_eq(s->v0[i], t->v0[i], "v0[%d]", i);
    cr_assert_eq(s->controller, t->controller);
    cr_assert_eq(s->gains == NULL, t->gains == NULL);
    for (int i = 0; s->gains != NULL && i < a->nind; i++) {
        cr_assert(s->gains[i].ki == t->gains[i].ki && s->gains[i].kp == t->gains[i].kp &&
                      s->gains[i].kv == t->gains[i].kv,
                  "gains[%d]", i);
    }
    cr_assert_eq(s->model_mass_scale, t->model_mass_scale);
    cr_assert_eq(s->model_inertia_scale, t->model_inertia_scale);
    cr_assert_eq(s->traj == NULL, t->traj == NULL);
    for (int i = 0; s->traj != NULL && i < a->nind; i++)
        expect_same_traj(&s->traj[i], &t->traj[i], i);
    cr_assert_eq(s->disturb == NULL, t->disturb == NULL);
    for (int i = 0; s->disturb != NULL && i < a->nind; i++) {
        const ctc_disturb *x = &s->disturb[i], *y = &t->disturb[i];
        cr_assert(x->type == y->type && x->value == y->value && x->amplitude == y->amplitude &&
                      x->period == y->period && x->phase == y->phase && x->offset == y->offset &&
                      x->time == y->time,
                  "disturb[%d]", i);
    }
    const ctc_integ_spec *m = &s->integrator, *n = &t->integrator;
    cr_assert(m->method == n->method && m->step == n->step && m->rtol == n->rtol &&
              m->atol == n->atol && m->initial_step == n->initial_step &&
              m->max_step == n->max_step && m->min_step == n->min_step &&
              m->max_steps == n->max_steps);
    cr_assert_eq(s->duration, t->duration);
    cr_assert_eq(s->output_interval, t->output_interval);
    cr_assert_eq(s->channels, t->channels);
    cr_assert_eq(s->max_speed, t->max_speed);
    cr_assert_eq(s->wall_limit, t->wall_limit);
}

/* doc -> job -> normalised -> text -> job -> normalised -> text: the same spec and text, and the
 * normalised document itself (unprinted) parses to the same spec and document */
static void expect_round_trip(const char *text, int from_text)
{
    char *doc = from_text ? strdup(text) : fixture_json(text);
    job *first = NULL, *second = NULL, *direct = NULL;
    job_error err;
    cr_assert_eq(job_parse(doc, strlen(doc), &first, &err), 0, "%s: %s", err.field, err.message);
    char *text1 = cJSON_Print(first->normalised);
    cr_assert_eq(job_parse(text1, strlen(text1), &second, &err), 0, "normalised rejected: %s: %s",
                 err.field, err.message);
    char *text2 = cJSON_Print(second->normalised);
    cr_assert_str_eq(text1, text2);
    expect_same_job(first, second);
    cr_assert_eq(job_from_json(first->normalised, &direct, &err), 0, "%s", err.message);
    expect_same_job(first, direct);
    cr_assert(cJSON_Compare(first->normalised, direct->normalised, 1));
    free(text1);
    free(text2);
    free(doc);
    job_free(first);
    job_free(second);
    job_free(direct);
}

Test(job_json, normalised_documents_parse_back_to_the_same_job)
{
    expect_round_trip("{" SCENE1 "," PASSIVE "," DUR "}", 0);

    /* everything at once: shapes, joint types, pid overrides of both forms, every trajectory
       and disturbance type, rk4, a channel list, limits */
    expect_round_trip(
        "{'name':'everything','scene':{'gravity':[0,0,-9.81],'form':'spatial','bodies':["
        "{'name':'base','mass':3,'shape':{'type':'box','size':[1,0.1,0.2]},'joint':{'type':"
        "'revolute','axis':[0,0,1]}},"
        "{'mass':2,'shape':{'type':'cylinder','radius':0.1,'length':0.6,'axis':[1,0,0],'centre':"
        "[0.3,0,0]},'joint':{'type':'cylindrical','axis':[1,0,0],'location':[1,0,0]}},"
        "{'mass':1,'com':[0,0,0],'inertia':[[0.2,0.01,0],[0.01,0.2,0],[0,0,0.3]],'joint':{'type':"
        "'fixed','location':[0.6,0,0]}},"
        "{'mass':1,'com':[0.1,0,0],'inertia':[0.1,0.2,0.2],'joint':{'type':'prismatic','axis':[0,"
        "1,0]}},"
        "{'mass':1,'com':[0.1,0,0],'inertia':[0.1,0.2,0.2],'joint':{'type':'revolute','axis':[0,"
        "1,0]}}],'q0':[0.1,0.2,0.3,0.4,0.5],'v0':[0,0,1,0,0]},"
        "'controller':{'type':'pid','zeta':0.9,'tau':0.1,'ki':100,'joints':[{},{'kp':400,'kv':"
        "40},{'ki':0},{'tau':0.2},{}],'model':{'mass_scale':1.1,'inertia_scale':0.9}},"
        "'trajectory':[{'type':'constant','value':0.5},{'type':'sine','amplitude':1,'period':2,"
        "'phase':0.3},{'type':'polynomial','coefficients':[0,1,-0.5]},{'type':'min_jerk','from':0,"
        "'to':0.2,'start':0,'end':0.5},{'type':'spline','times':[0,0.5,1],'values':[0,1,0],"
        "'boundary':'natural'}],"
        "'disturbance':[{'type':'none'},{'type':'constant','value':0.2},{'type':'sine','amplitude':"
        "0.1,'period':0.5},{'type':'step','value':1,'time':0.5},{'type':'none'}],"
        "'integrator':{'method':'rk4','step':0.0005,'max_steps':100000},'duration':2,"
        "'output':{'interval':0.05,'channels':['e','q','w']},'limits':{'max_speed':1000,"
        "'wall_time':10},'threads':4}",
        0);

    /* lqr with rows, complex poles with overrides, bdf */
    expect_round_trip(CTRL_JOB("{'type':'lqr','Q':[[2,0,0],[0,1,0],[0,0,1]],'lambda':0.1}"), 0);
    expect_round_trip("{" SCENE2 ",'controller':{'type':'poles','poles':[{'re':-1,'im':2},{'re':"
                      "-1,'im':-2},-3],'joints':[{'poles':[-1,-2,-3]},{}]}," HOLD "," DUR
                      ",'integrator':{'method':'bdf','rtol':1e-6,'atol':1e-8,'max_step':0.1}}",
                      0);

    /* loops: every setting of the loop, a passive loop of dependent joints only */
    expect_round_trip(LOOP_PD_JOB(",'disturbance':{'type':'sine','amplitude':0.1,'period':1}"), 0);
    expect_round_trip(
        "{" LOOP_SCENE_WITH("{'joint':{'type':'revolute','axis':[0,0,2],'location':"
                            "[0,-1,0],'independent':false},'anchor':[1,0,0],"
                            "'stabilization':{'method':'baumgarte','alpha':3,"
                            "'beta':4},'cond_max':1e6}") "," PASSIVE "," DUR
                                                         ",'output':{'channels':['loop','q']}}",
        0);
    expect_round_trip("{'scene':{'bodies':[" DEP_BODY "," DEP_BODY "," DEP_BODY "],'loop':" LOOP
                      "," SQUARE_Q0 "}," PASSIVE "," DUR "}",
                      0);

    /* every preset, printed numbers of 17 digits (q0 = 5 pi / 6) included */
    int count;
    const preset *list = presets_list(&count);
    for (int i = 0; i < count; i++) {
        char request[128];
        snprintf(request, sizeof request, "{\"preset\": \"%s\"}", list[i].name);
        expect_round_trip(request, 1);
    }
}

Test(job_json, normalised_keys_come_in_canonical_order)
{
    /* given back to front, written in the format's order with every default */
    job *j =
        fixture_parse_ok("{'duration':1,'output':{'channels':['qdot','q']},'controller':{'type':"
                         "'none'},'scene':{'v0':[1],'bodies':[{'joint':{'axis':[0,0,1],'type':"
                         "'revolute'},'inertia':[1,1,1],'com':[0,0,0],'mass':1}]}}");
    char *text = cJSON_PrintUnformatted(j->normalised);
    char *want = fixture_json(
        "{'name':'job','scene':{'gravity':[0,-9.81,0],'form':'auto','bodies':[{'parent':-1,'mass':"
        "1,'com':[0,"
        "0,0],'inertia':[1,1,1],'joint':{'type':'revolute','axis':[0,0,1],'location':[0,0,0],"
        "'independent':true}}],"
        "'q0':[0],'v0':[1]},'controller':{'type':'none'},'disturbance':{'type':'none'},'plant':{},"
        "'wrenches':[],'integrator':{'method':'dopri5','rtol':1e-08,'atol':1e-10,'initial_step':0,'"
        "max_step':0,"
        "'min_step':0,'max_steps':10000000},'duration':1,'output':{'interval':0.01,'channels':['q',"
        "'qdot']},"
        "'limits':{'max_speed':1000000,'wall_time':0},'threads':1}");
    cr_assert_str_eq(text, want);
    free(text);
    free(want);
    job_free(j);
}

/* the parents of job text's bodies, as parsed (spec.chain.parent) and as normalised */
static void expect_parents(const char *text, const int *want, int n)
{
    job *j = fixture_parse_ok(text);
    cr_assert_eq(j->spec.chain.nbodies, n);
    cr_assert_eq(j->spec.chain.parent, j->parent);
    const cJSON *bodies =
        cJSON_GetObjectItem(cJSON_GetObjectItem(j->normalised, "scene"), "bodies");
    for (int k = 0; k < n; k++) {
        cr_expect_eq(j->parent[k], want[k], "body %d: parent %d, want %d", k, j->parent[k],
                     want[k]);
        const cJSON *p = cJSON_GetObjectItem(cJSON_GetArrayItem(bodies, k), "parent");
        cr_assert(cJSON_IsNumber(p), "body %d: the normalised parent is not a number", k);
        cr_expect_eq(p->valuedouble, want[k], "body %d: normalised parent %g", k, p->valuedouble);
    }
    job_free(j);
}

Test(job_json, parents_by_index_name_or_ground_are_written_as_indices)
{
    static const int chain[3] = {-1, 0, 1};
    expect_parents(PASSIVE_JOB(""), chain, 2); /* the default: a chain */
    expect_parents(TREE_JOB("'palm'"), chain, 3);
    expect_parents(TREE_JOB("1"), chain, 3);
    expect_parents(TREE_JOB("1.0"), chain, 3);
    expect_parents("{'scene':{'bodies':[" NAMED_ON("arm", "'ground'") "," NAMED_ON(
                       "palm", "'arm'") "," NAMED_ON("tip", "'palm'") "]}," PASSIVE "," DUR "}",
                   chain, 3);
    expect_parents("{'scene':{'bodies':[" NAMED_ON("arm", "-1") "]}," PASSIVE "," DUR "}", chain,
                   1);

    /* a name repeated among bodies no parent refers to is allowed */
    expect_parents("{'scene':{'bodies':[" NAMED("arm") "," NAMED("x") "," NAMED("x") "]}," PASSIVE
                                                                                     "," DUR "}",
                   chain, 3);

    /* a loop's body by name, written as its index: a square four-bar on the arm's tip, closed
       on the arm (anchor (1, -1) in its frame) */
    char *text = fixture_json("{'scene':{'bodies':[" NAMED("arm") "," BODY_AT(
        "[0,-1,0]") "," DEP_BODY "," DEP_BODY "],'loop':{" CLOSING
                    ",'anchor':[1,-1,0],'body':'arm'},'q0':[0,"
                    "0,1.5707963267948966,1.5707963267948966]}," PASSIVE "," DUR "}");
    job *j;
    job_error err;
    cr_assert_eq(job_parse(text, strlen(text), &j, &err), 0, "%s: %s", err.field, err.message);
    cr_assert_eq(j->loop.on_body, 1);
    cr_assert_eq(j->loop.body, 0);
    const cJSON *loop = cJSON_GetObjectItem(cJSON_GetObjectItem(j->normalised, "scene"), "loop");
    cr_assert_eq(cJSON_GetObjectItem(loop, "body")->valuedouble, 0);
    job_free(j);
    free(text);
}

Test(job_json, threads_are_the_runs_thread_count_also_over_a_preset)
{
    job *j = fixture_parse_ok(PASSIVE_JOB(",'threads':8"));
    cr_assert_eq(j->spec.threads, 8);
    const cJSON *t = cJSON_GetObjectItemCaseSensitive(j->normalised, "threads");
    cr_assert(cJSON_IsNumber(t) && t->valuedouble == 8);
    job_free(j);

    j = fixture_parse_ok("{'preset':'n_link_pendulum','n':64,'threads':2}");
    cr_assert_eq(j->spec.threads, 2);
    cr_assert_eq(j->spec.chain.nbodies, 64);
    job_free(j);

    j = fixture_parse_ok(PASSIVE_JOB(",'threads':64"));
    cr_assert_eq(j->spec.threads, 64, "the largest count allowed");
    job_free(j);
}

/* ---- names ---- */

Test(job_json, error_codes_have_stable_names)
{
    cr_assert_str_eq(job_error_code_name(JOB_OK), "OK");
    cr_assert_str_eq(job_error_code_name(JOB_INVALID_JSON), "INVALID_JSON");
    cr_assert_str_eq(job_error_code_name(JOB_MISSING_FIELD), "MISSING_FIELD");
    cr_assert_str_eq(job_error_code_name(JOB_UNKNOWN_FIELD), "UNKNOWN_FIELD");
    cr_assert_str_eq(job_error_code_name(JOB_INVALID_FIELD), "INVALID_FIELD");
    cr_assert_str_eq(job_error_code_name(JOB_UNKNOWN_PRESET), "UNKNOWN_PRESET");
    cr_assert_str_eq(job_error_code_name(JOB_LIMIT_EXCEEDED), "LIMIT_EXCEEDED");
    job_free(NULL);
}

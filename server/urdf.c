/*
 * urdf.c - URDF XML into the job's bodies (urdf.h): libxml2 reads the document into a tree, this
 * file reads the links and joints off it, checks that they form one tree rooted at a link fixed
 * to the world, orders the links breadth first from that root (parents before children) and
 * hands them to import_bodies (import.c), which converts URDF's link frames into ctcsim's
 * world-parallel body frames and merges fixed joints.
 *
 * URDF's conventions (wiki.ros.org/urdf/XML): <origin xyz rpy> places a joint's frame in its
 * parent link's frame (translation xyz, then rotation Rz(yaw) Ry(pitch) Rx(roll)); the child
 * link's frame is the joint's frame; <axis> is in the joint frame; an <inertial>'s origin places
 * the centre of mass and the axes of <inertia> in the link's frame. A continuous joint is a
 * revolute joint without position limits.
 *
 * Messages name the element and its line, as libxml2 records it (xmlGetLineNo): "line 14:
 * <joint name="elbow">: type "ball" is not one of ...". The document is parsed with
 * XML_PARSE_NONET and without entity substitution, and one with a document type declaration is
 * refused, so no entity or external resource is ever read.
 */
#include "urdf.h"

#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <libxml/parser.h>
#include <libxml/tree.h>

#include "import.h"

/* one parse: the links as found in the document, and the joints' facts about them */
typedef struct urdf_link {
    xmlNode *node;
    char *name;             /* the link's name (xmlChar from xmlGetProp; freed with xmlFree) */
    xmlNode *joint;         /* its parent joint, or NULL */
    char *joint_name;       /* that joint's name */
    int parent;             /* the parent link's index in the document, or -1 */
    import_link l;          /* everything but parent (and name pointers, set when ordered) */
    import_visual *visuals; /* (l.nvisuals) its <visual> boxes, cylinders and spheres */
} urdf_link;

typedef struct urdf_state {
    char *msg;
    size_t msg_len;
    urdf_link *links;
    int nlinks;
    int meshes; /* <visual>s whose geometry is a <mesh>: ignored */
} urdf_state;

/* the first error libxml2 reports while parsing (its last one may be a consequence) */
typedef struct first_error {
    int set, line;
    char message[300];
} first_error;

static void keep_first_error(void *ctx, xmlErrorPtr e)
{
    first_error *f = ((xmlParserCtxt *)ctx)->_private;
    if (f->set || e == NULL || e->level < XML_ERR_ERROR) return;
    size_t k = e->message ? strlen(e->message) : 0;
    while (k > 0 && (e->message[k - 1] == '\n' || e->message[k - 1] == ' ')) k--;
    snprintf(f->message, sizeof f->message, "%.*s", (int)k, e->message ? e->message : "");
    f->line = e->line;
    f->set = 1;
}

static pthread_once_t xml_once = PTHREAD_ONCE_INIT;

static void xml_init(void)
{
    xmlInitParser();
}

/* "<tag name="N">" of element el into buf (size 160) */
static const char *element_name(xmlNode *el, char *buf)
{
    xmlChar *name = xmlGetProp(el, BAD_CAST "name");
    if (name != NULL)
        snprintf(buf, 160, "<%s name=\"%.100s\">", (const char *)el->name, (const char *)name);
    else
        snprintf(buf, 160, "<%.100s>", (const char *)el->name);
    xmlFree(name);
    return buf;
}

/* writes "line L: <tag> in <link name="N">: " (the element, and the link or joint it is in) and
 * the message into s->msg; returns -1 */
static int fail(urdf_state *s, xmlNode *el, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int fail(urdf_state *s, xmlNode *el, const char *fmt, ...)
{
    char own[160], top[160], reason[400];
    xmlNode *t = el;
    while (t->parent != NULL && t->parent->type == XML_ELEMENT_NODE &&
           xmlStrcmp(t->parent->name, BAD_CAST "robot") != 0)
        t = t->parent;
    if (t->parent == NULL || t->parent->type != XML_ELEMENT_NODE) t = el; /* el is the root */
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(reason, sizeof reason, fmt, ap);
    va_end(ap);
    snprintf(s->msg, s->msg_len, "line %ld: %s%s%s: %s", xmlGetLineNo(el), element_name(el, own),
             t != el ? " in " : "", t != el ? element_name(t, top) : "", reason);
    return -1;
}

/* the first child element of el named tag, or NULL */
static xmlNode *child(xmlNode *el, const char *tag)
{
    for (xmlNode *c = el->children; c != NULL; c = c->next) {
        if (c->type == XML_ELEMENT_NODE && xmlStrcmp(c->name, BAD_CAST tag) == 0) return c;
    }
    return NULL;
}

/* the attribute attr of el as n finite numbers into x; absent: def (n numbers), or an error
 * when def is NULL. 1: absent and defaulted, 0: read, -1: error */
static int numbers_attr(urdf_state *s, xmlNode *el, const char *attr, int n, const double *def,
                        double *x)
{
    xmlChar *v = xmlGetProp(el, BAD_CAST attr);
    if (v == NULL) {
        if (def == NULL) return fail(s, el, "attribute %s is required", attr);
        memcpy(x, def, (size_t)n * sizeof *x);
        return 1;
    }
    const char *p = (const char *)v;
    int i = 0, rc = 0;
    for (;;) {
        while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r') p++;
        if (*p == '\0') break;
        char *end;
        double d = strtod(p, &end);
        if (end == p || i == n || !isfinite(d)) {
            i = -1;
            break;
        }
        x[i++] = d;
        p = end;
    }
    if (i != n) {
        rc = fail(s, el, "%s must be %d finite number%s (got \"%s\")", attr, n, n > 1 ? "s" : "",
                  (const char *)v);
    }
    xmlFree(v);
    return rc;
}

/* <origin xyz rpy> under el (absent: the identity) into R, p */
static int read_origin(urdf_state *s, xmlNode *el, double R[9], double p[3])
{
    static const double zero[3] = {0, 0, 0};
    double rpy[3];
    xmlNode *o = child(el, "origin");
    if (o == NULL) {
        memcpy(p, zero, sizeof zero);
        import_rpy(zero, R);
        return 0;
    }
    if (numbers_attr(s, o, "xyz", 3, zero, p) < 0 || numbers_attr(s, o, "rpy", 3, zero, rpy) < 0)
        return -1;
    import_rpy(rpy, R);
    return 0;
}

/* a link's <inertial>: mass, centre of mass and inertia in the link frame */
static int read_inertial(urdf_state *s, xmlNode *link, import_link *l)
{
    static const double zero[1] = {0};
    xmlNode *in = child(link, "inertial");
    if (in == NULL) return 0;
    double R[9], I[9], RI[9], Rt[9];
    if (read_origin(s, in, R, l->com) != 0) return -1;
    xmlNode *mass = child(in, "mass");
    if (mass == NULL) return fail(s, in, "<mass> is required");
    if (numbers_attr(s, mass, "value", 1, NULL, &l->mass) < 0) return -1;
    if (l->mass < 0) return fail(s, mass, "value must not be negative (got %g kg)", l->mass);
    xmlNode *inertia = child(in, "inertia");
    if (inertia == NULL) return fail(s, in, "<inertia> is required");
    static const char *const keys[6] = {"ixx", "iyy", "izz", "ixy", "ixz", "iyz"};
    double v[6];
    for (int i = 0; i < 6; i++) {
        if (numbers_attr(s, inertia, keys[i], 1, i < 3 ? NULL : zero, &v[i]) < 0) return -1;
    }
    double J[9] = {v[0], v[3], v[4], v[3], v[1], v[5], v[4], v[5], v[2]};
    memcpy(I, J, sizeof I);
    /* into the link frame's axes: R I R^T */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) Rt[3 * i + j] = R[3 * j + i];
    import_mat_mul(R, I, RI);
    import_mat_mul(RI, Rt, l->inertia);
    l->has_inertial = 1;
    return 0;
}

/* a link's <visual>s: each box, cylinder and sphere with its origin into l's visuals (allocated
 * here into *out, freed by the caller); a <mesh> is counted in s->meshes and left out */
static int read_visuals(urdf_state *s, xmlNode *link, import_link *l, import_visual **out)
{
    int n = 0;
    for (xmlNode *c = link->children; c != NULL; c = c->next)
        n += c->type == XML_ELEMENT_NODE && xmlStrcmp(c->name, BAD_CAST "visual") == 0;
    if (n == 0) return 0;
    *out = calloc((size_t)n, sizeof **out);
    if (*out == NULL) {
        snprintf(s->msg, s->msg_len, "out of memory");
        return -1;
    }
    for (xmlNode *c = link->children; c != NULL; c = c->next) {
        if (c->type != XML_ELEMENT_NODE || xmlStrcmp(c->name, BAD_CAST "visual") != 0) continue;
        xmlNode *geom = child(c, "geometry"), *shape = NULL;
        if (geom == NULL) return fail(s, c, "<geometry> is required");
        import_visual *v = &(*out)[l->nvisuals];
        const char *sizes = NULL;
        int count = 0;
        if ((shape = child(geom, "box")) != NULL) {
            v->type = IMPORT_BOX, sizes = "size", count = 3;
            if (numbers_attr(s, shape, "size", 3, NULL, v->size) < 0) return -1;
        } else if ((shape = child(geom, "cylinder")) != NULL) {
            v->type = IMPORT_CYLINDER, sizes = "radius and length", count = 2;
            if (numbers_attr(s, shape, "radius", 1, NULL, &v->size[0]) < 0 ||
                numbers_attr(s, shape, "length", 1, NULL, &v->size[1]) < 0)
                return -1;
        } else if ((shape = child(geom, "sphere")) != NULL) {
            v->type = IMPORT_SPHERE, sizes = "radius", count = 1;
            if (numbers_attr(s, shape, "radius", 1, NULL, &v->size[0]) < 0) return -1;
        } else if (child(geom, "mesh") != NULL) {
            s->meshes++;
            continue;
        } else {
            return fail(s, geom, "must hold a <box>, <cylinder>, <sphere> or <mesh>");
        }
        for (int i = 0; i < count; i++)
            if (!(v->size[i] > 0)) return fail(s, shape, "%s must be positive", sizes);
        if (read_origin(s, c, v->rot, v->pos) != 0) return -1;
        l->nvisuals++;
    }
    l->visuals = *out;
    return 0;
}

/* the index of the link named name among the first n, or -1 */
static int find_link(const urdf_state *s, int n, const char *name)
{
    for (int i = 0; i < n; i++)
        if (strcmp(s->links[i].name, name) == 0) return i;
    return -1;
}

/* optional numeric attributes of el into a new object under key of extra (created on demand) */
static int keep_attrs(urdf_state *s, xmlNode *el, const char *const *attrs, const char *key,
                      cJSON **extra)
{
    if (el == NULL) return 0;
    cJSON *o = cJSON_CreateObject();
    if (o == NULL) goto oom;
    for (int i = 0; attrs[i] != NULL; i++) {
        static const double none = 0; /* an absent attribute is left out (rc 1) */
        double x;
        int rc = numbers_attr(s, el, attrs[i], 1, &none, &x);
        if (rc < 0) {
            cJSON_Delete(o);
            return -1;
        }
        if (rc == 0 && cJSON_AddNumberToObject(o, attrs[i], x) == NULL) goto oom;
    }
    if (*extra == NULL && (*extra = cJSON_CreateObject()) == NULL) goto oom;
    if (!cJSON_AddItemToObject(*extra, key, o)) goto oom;
    return 0;
oom:
    cJSON_Delete(o);
    snprintf(s->msg, s->msg_len, "out of memory");
    return -1;
}

/* one <joint>: its type, links, origin, axis, limit and dynamics, onto its child link */
static int read_joint(urdf_state *s, xmlNode *el)
{
    static const char *const limit_attrs[] = {"lower", "upper", "effort", "velocity", NULL};
    static const char *const dynamics_attrs[] = {"damping", "friction", NULL};
    static const double x_axis[3] = {1, 0, 0};
    xmlChar *name = xmlGetProp(el, BAD_CAST "name");
    xmlChar *type = xmlGetProp(el, BAD_CAST "type");
    xmlChar *parent = NULL, *childname = NULL;
    int rc = -1;
    ctc_joint_type t = CTC_JOINT_FIXED;
    if (name == NULL) {
        fail(s, el, "attribute name is required");
        goto done;
    }
    if (type == NULL) {
        fail(s, el, "attribute type is required");
        goto done;
    }
    if (xmlStrcmp(type, BAD_CAST "revolute") == 0 || xmlStrcmp(type, BAD_CAST "continuous") == 0) {
        t = CTC_JOINT_REVOLUTE;
    } else if (xmlStrcmp(type, BAD_CAST "prismatic") == 0) {
        t = CTC_JOINT_PRISMATIC;
    } else if (xmlStrcmp(type, BAD_CAST "fixed") == 0) {
        t = CTC_JOINT_FIXED;
    } else if (xmlStrcmp(type, BAD_CAST "floating") == 0 ||
               xmlStrcmp(type, BAD_CAST "planar") == 0) {
        fail(s, el,
             "type \"%s\" is not supported (ctcsim's robots are fixed to the world and their "
             "joints are revolute, continuous, prismatic or fixed)",
             (const char *)type);
        goto done;
    } else {
        fail(s, el, "type \"%s\" is not one of revolute, continuous, prismatic, fixed",
             (const char *)type);
        goto done;
    }
    xmlNode *mimic = child(el, "mimic");
    if (mimic != NULL) {
        fail(s, mimic, "mimic joints are not supported (each joint is its own coordinate)");
        goto done;
    }
    xmlNode *p_el = child(el, "parent"), *c_el = child(el, "child");
    if (p_el == NULL || c_el == NULL) {
        fail(s, el, "<%s link> is required", p_el == NULL ? "parent" : "child");
        goto done;
    }
    parent = xmlGetProp(p_el, BAD_CAST "link");
    childname = xmlGetProp(c_el, BAD_CAST "link");
    if (parent == NULL || childname == NULL) {
        fail(s, parent == NULL ? p_el : c_el, "attribute link is required");
        goto done;
    }
    int pi = find_link(s, s->nlinks, (const char *)parent),
        ci = find_link(s, s->nlinks, (const char *)childname);
    if (pi < 0 || ci < 0) {
        fail(s, pi < 0 ? p_el : c_el, "link \"%s\" is not a <link> of the robot",
             (const char *)(pi < 0 ? parent : childname));
        goto done;
    }
    urdf_link *c = &s->links[ci];
    if (c->joint != NULL) {
        fail(s, el, "link \"%s\" has two parents: joint \"%s\" (line %ld) is its parent already",
             c->name, c->joint_name, xmlGetLineNo(c->joint));
        goto done;
    }
    if (pi == ci) {
        fail(s, el, "link \"%s\" is its own parent (a parent/child cycle)", c->name);
        goto done;
    }
    import_link *l = &c->l;
    l->type = t;
    if (read_origin(s, el, l->origin_rot, l->origin_pos) != 0) goto done;
    xmlNode *axis = child(el, "axis");
    if (axis == NULL) {
        memcpy(l->axis, x_axis, sizeof x_axis);
    } else {
        if (numbers_attr(s, axis, "xyz", 3, x_axis, l->axis) < 0) goto done;
        double len =
            sqrt(l->axis[0] * l->axis[0] + l->axis[1] * l->axis[1] + l->axis[2] * l->axis[2]);
        if (t != CTC_JOINT_FIXED && !(len > 1e-12)) {
            fail(s, axis, "xyz must have non-zero length (got \"%g %g %g\")", l->axis[0],
                 l->axis[1], l->axis[2]);
            goto done;
        }
    }
    if (t != CTC_JOINT_FIXED &&
        (keep_attrs(s, child(el, "limit"), limit_attrs, "limit", &l->extra) != 0 ||
         keep_attrs(s, child(el, "dynamics"), dynamics_attrs, "dynamics", &l->extra) != 0)) {
        goto done;
    }
    c->joint = el;
    c->joint_name = (char *)name;
    name = NULL;
    c->parent = pi;
    rc = 0;
done:
    xmlFree(name);
    xmlFree(type);
    xmlFree(parent);
    xmlFree(childname);
    return rc;
}

/* The links, breadth first from the one root, into the import order: order[i] is the document
 * index of import link i. */
static int order_tree(urdf_state *s, int *order)
{
    int root = -1;
    for (int i = 0; i < s->nlinks; i++) {
        if (s->links[i].parent >= 0) continue;
        if (root >= 0) {
            return fail(s, s->links[i].node,
                        "a second root: link \"%s\" (line %ld) has no parent joint either; a "
                        "robot is one tree of links fixed to the world",
                        s->links[root].name, xmlGetLineNo(s->links[root].node));
        }
        root = i;
    }
    int n = 0;
    if (root >= 0) order[n++] = root;
    for (int head = 0; head < n; head++) {
        for (int i = 0; i < s->nlinks; i++)
            if (s->links[i].parent == order[head]) order[n++] = i;
    }
    if (n == s->nlinks) return 0;
    /* a link not reached hangs from a cycle: name the first joint on one */
    for (int i = 0; i < s->nlinks; i++) {
        int reached = 0;
        for (int k = 0; k < n && !reached; k++) reached = order[k] == i;
        if (reached) continue;
        int k = i; /* walk up nlinks parents: then k is on the cycle */
        for (int step = 0; step < s->nlinks; step++) k = s->links[k].parent;
        return fail(s, s->links[k].joint,
                    "a parent/child cycle: link \"%s\" is its own ancestor (a robot is a tree)",
                    s->links[k].name);
    }
    return 0;
}

cJSON *urdf_to_bodies(const char *text, size_t len, char *name, size_t name_len, char *msg,
                      size_t msg_len)
{
    return urdf_read(text, len, name, name_len, NULL, msg, msg_len);
}

cJSON *urdf_read(const char *text, size_t len, char *name, size_t name_len, int *meshes, char *msg,
                 size_t msg_len)
{
    urdf_state st = {.msg = msg, .msg_len = msg_len};
    urdf_state *s = &st;
    cJSON *out = NULL;
    xmlDoc *doc = NULL;
    xmlParserCtxt *ctxt = NULL;
    int *order = NULL;
    import_link *links = NULL;
    if (name != NULL && name_len > 0) name[0] = '\0';
    pthread_once(&xml_once, xml_init);

    if (len > INT_MAX) {
        snprintf(msg, msg_len, "the document is larger than %d bytes", INT_MAX);
        return NULL;
    }
    ctxt = xmlNewParserCtxt();
    if (ctxt == NULL) {
        snprintf(msg, msg_len, "out of memory");
        return NULL;
    }
    first_error first = {0};
    ctxt->_private = &first;
    ctxt->sax->serror = keep_first_error;
    doc = xmlCtxtReadMemory(ctxt, text, (int)len, "robot.urdf", NULL,
                            XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING);
    if (doc == NULL || first.set) {
        if (first.set)
            snprintf(msg, msg_len, "line %d: not well-formed XML: %s", first.line, first.message);
        else
            snprintf(msg, msg_len, "not a well-formed XML document");
        goto done;
    }
    xmlNode *robot = xmlDocGetRootElement(doc);
    if (doc->intSubset != NULL) {
        snprintf(msg, msg_len, "a document type declaration (<!DOCTYPE>) is not allowed");
        goto done;
    }
    if (robot == NULL || xmlStrcmp(robot->name, BAD_CAST "robot") != 0) {
        if (robot == NULL)
            snprintf(msg, msg_len, "the document has no <robot> element");
        else
            fail(s, robot, "the root element must be <robot>");
        goto done;
    }
    if (name != NULL && name_len > 0) {
        xmlChar *rn = xmlGetProp(robot, BAD_CAST "name");
        snprintf(name, name_len, "%s", rn ? (const char *)rn : "");
        xmlFree(rn);
    }

    /* the links */
    for (xmlNode *c = robot->children; c != NULL; c = c->next) {
        if (c->type == XML_ELEMENT_NODE && xmlStrcmp(c->name, BAD_CAST "link") == 0) st.nlinks++;
    }
    if (st.nlinks == 0) {
        fail(s, robot, "has no <link>");
        goto done;
    }
    if (st.nlinks > URDF_MAX_LINKS) {
        fail(s, robot, "has %d links; the limit is %d", st.nlinks, URDF_MAX_LINKS);
        goto done;
    }
    st.links = calloc((size_t)st.nlinks, sizeof *st.links);
    order = malloc((size_t)st.nlinks * sizeof *order);
    links = calloc((size_t)st.nlinks, sizeof *links);
    if (st.links == NULL || order == NULL || links == NULL) {
        snprintf(msg, msg_len, "out of memory");
        goto done;
    }
    int n = 0;
    for (xmlNode *c = robot->children; c != NULL; c = c->next) {
        if (c->type != XML_ELEMENT_NODE || xmlStrcmp(c->name, BAD_CAST "link") != 0) continue;
        urdf_link *u = &st.links[n];
        u->node = c;
        u->parent = -1;
        u->name = (char *)xmlGetProp(c, BAD_CAST "name");
        if (u->name == NULL) {
            fail(s, c, "attribute name is required");
            goto done;
        }
        int same = find_link(s, n, u->name);
        n++;
        if (same >= 0) {
            fail(s, c, "a second link named \"%s\" (the first is on line %ld)", u->name,
                 xmlGetLineNo(st.links[same].node));
            goto done;
        }
        if (read_inertial(s, c, &u->l) != 0 || read_visuals(s, c, &u->l, &u->visuals) != 0)
            goto done;
    }

    /* the joints */
    for (xmlNode *c = robot->children; c != NULL; c = c->next) {
        if (c->type == XML_ELEMENT_NODE && xmlStrcmp(c->name, BAD_CAST "joint") == 0 &&
            read_joint(s, c) != 0) {
            goto done;
        }
    }
    if (order_tree(s, order) != 0) goto done;

    /* in tree order, with parents as import indices */
    for (int i = 0; i < st.nlinks; i++) {
        urdf_link *u = &st.links[order[i]];
        links[i] = u->l;
        u->l.extra = NULL;
        links[i].name = u->name;
        links[i].joint_name = u->joint_name;
        links[i].line = (int)xmlGetLineNo(u->node);
        links[i].parent = -1;
        for (int k = 0; k < i && u->parent >= 0; k++)
            if (order[k] == u->parent) links[i].parent = k;
        if (i == 0) links[i].type = CTC_JOINT_FIXED;
    }
    out = import_bodies(links, st.nlinks, msg, msg_len);
    if (meshes != NULL) *meshes = st.meshes;

done:
    for (int i = 0; st.links != NULL && i < st.nlinks; i++) {
        xmlFree(st.links[i].name);
        xmlFree(st.links[i].joint_name);
        cJSON_Delete(st.links[i].l.extra);
        free(st.links[i].visuals);
    }
    for (int i = 0; links != NULL && i < st.nlinks; i++) cJSON_Delete(links[i].extra);
    free(st.links);
    free(order);
    free(links);
    xmlFreeDoc(doc);
    xmlFreeParserCtxt(ctxt);
    return out;
}

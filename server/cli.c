/*
 * cli.c - the `ctcsim` command line: run, validate and list jobs without the service.
 *
 *   ctcsim run FILE|- [--format csv|json] [-o OUT] [--channels LIST] [--every N] [--quiet]
 *   ctcsim validate FILE|-
 *   ctcsim presets
 *   ctcsim preset NAME [KEY=VALUE ...]
 *   ctcsim import FILE.urdf | --dh FILE.json
 *
 * It reads a job (job_json.h) from a file or standard input, runs it with the library in this
 * thread, and writes the series as CSV or one JSON object (result_out.h) to standard output or
 * OUT; a one-line summary goes to standard error. Exit codes:
 *   0  the run finished (status "done"), or the job is valid, or the listing or job was printed
 *   1  usage error (unknown command or option)
 *   2  the job is invalid: "FILE: FIELD: MESSAGE" on standard error
 *   3  the run stopped early: diverged, integrator failure, timeout, or singular (a loop's
 *      independent joints can no longer drive it) (the samples up to there are still written)
 *   4  input or output error (file not found, disk full)
 */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_json.h"
#include "presets.h"
#include "result_out.h"
#include "urdf.h"

enum { EXIT_USAGE = 1, EXIT_INVALID = 2, EXIT_STOPPED = 3, EXIT_IO = 4 };

#define CLI_MAX_INPUT (256L * 1024 * 1024)

static const char usage[] =
    "usage: ctcsim run FILE|- [--format csv|json] [-o OUT] [--channels LIST] [--every N] "
    "[--quiet]\n"
    "       ctcsim validate FILE|-\n"
    "       ctcsim presets\n"
    "       ctcsim preset NAME [KEY=VALUE ...]\n"
    "       ctcsim import FILE.urdf | --dh FILE.json\n"
    "\n"
    "  run       run a job (JSON, see api/job.schema.json) and write its series: CSV by\n"
    "            default, or with --format json one object with the normalised spec, the\n"
    "            metrics and the series; to standard output or OUT\n"
    "  validate  check a job without running it; prints its normalised form\n"
    "  presets   list the ready-made jobs (the paper's scenes)\n"
    "  preset    print a preset's job; KEY=VALUE sets its parameters (e.g. n=16)\n"
    "  import    print a complete job for a robot from a URDF file, or with --dh from a\n"
    "            Denavit-Hartenberg table (JSON, the format's scene.dh): its bodies, a PD\n"
    "            controller and a gentle minimum-jerk move of every joint, to edit and run\n"
    "\n"
    "  --channels LIST  comma-separated subset of q,qdot,q_des,qdot_des,e,tau,w,energy,loop,\n"
    "                   end_effector\n"
    "  --every N        keep every N-th sample (and the last)\n"
    "  --quiet          no summary line on standard error\n"
    "\n"
    "exit codes: 0 done or valid, 1 usage, 2 invalid job, 3 run stopped early (diverged,\n"
    "failed, timeout, singular), 4 input/output error\n";

/* reads the whole file (or stdin for "-") into a new buffer; NULL with *why on failure */
static char *read_input(const char *path, size_t *len, const char **why)
{
    FILE *f = strcmp(path, "-") == 0 ? stdin : fopen(path, "rb");
    if (!f) {
        *why = strerror(errno);
        return NULL;
    }
    size_t cap = 0, n = 0;
    char *buf = NULL;
    for (;;) {
        if (n == cap) {
            if (cap >= CLI_MAX_INPUT) {
                *why = "input larger than 256 MiB";
                goto fail;
            }
            size_t grow = cap ? 2 * cap : 1 << 16;
            char *bigger = realloc(buf, grow);
            if (!bigger) {
                *why = "out of memory";
                goto fail;
            }
            buf = bigger, cap = grow;
        }
        size_t got = fread(buf + n, 1, cap - n, f);
        n += got;
        if (got == 0) break;
    }
    if (ferror(f)) {
        *why = strerror(errno);
        goto fail;
    }
    if (f != stdin) fclose(f);
    *len = n;
    return buf;
fail:
    if (f != stdin) fclose(f);
    free(buf);
    return NULL;
}

static int load_job(const char *path, job **out)
{
    size_t len = 0;
    const char *why = "";
    char *text = read_input(path, &len, &why);
    if (!text) {
        fprintf(stderr, "ctcsim: %s: %s\n", path, why);
        return EXIT_IO;
    }
    job_error err;
    int rc = job_parse(text, len, out, &err);
    free(text);
    if (rc != 0) {
        if (err.field[0])
            fprintf(stderr, "ctcsim: %s: %s: %s\n", path, err.field, err.message);
        else
            fprintf(stderr, "ctcsim: %s: %s\n", path, err.message);
        return EXIT_INVALID;
    }
    return 0;
}

static void print_summary(const job *j, const ctc_sim_result *r)
{
    const ctc_sim_metrics *m = &r->metrics;
    fprintf(stderr, "%s: %s, %s %s, %d samples to t = %g s, %ld steps (%ld rejected), %.3g s",
            j->name, ctc_run_status_name(r->status), ctc_form_name(m->form),
            ctc_ctrl_type_name(j->spec.controller), r->nsamples, m->t_end, m->steps, m->rejected,
            m->wall_s);
    if (m->e_max) {
        double e = 0;
        for (int i = 0; i < m->nv; i++) e = e > m->e_max[i] ? e : m->e_max[i];
        fprintf(stderr, ", max |e| %.3g", e);
    }
    if (m->errdyn_dev == m->errdyn_dev)
        fprintf(stderr, ", error-dynamics deviation %.2g", m->errdyn_dev);
    if (m->energy_drift == m->energy_drift) fprintf(stderr, ", energy drift %.2g", m->energy_drift);
    if (j->spec.chain.loop && m->loop_res_max == m->loop_res_max)
        fprintf(stderr, ", loop residual %.2g, %ld projections", m->loop_res_max, m->projections);
    fputc('\n', stderr);
    if (m->tol_floored) fprintf(stderr, "%s: tolerance floor: %s\n", j->name, m->tol_reason);
    if (r->message[0]) fprintf(stderr, "%s: %s\n", j->name, r->message);
}

static int cmd_run(int argc, char **argv)
{
    const char *path = NULL, *outpath = NULL, *format = "csv";
    unsigned mask = 0;
    int every = 1, quiet = 0;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--format") == 0 && i + 1 < argc) {
            format = argv[++i];
            if (strcmp(format, "csv") != 0 && strcmp(format, "json") != 0) {
                fprintf(stderr, "ctcsim: --format must be csv or json (got \"%s\")\n", format);
                return EXIT_USAGE;
            }
        } else if (strcmp(a, "-o") == 0 && i + 1 < argc) {
            outpath = argv[++i];
        } else if (strcmp(a, "--channels") == 0 && i + 1 < argc) {
            char bad[64];
            if (result_parse_channels(argv[++i], &mask, bad, sizeof bad) != 0) {
                fprintf(stderr, "ctcsim: --channels: unknown channel \"%s\"\n", bad);
                return EXIT_USAGE;
            }
        } else if (strcmp(a, "--every") == 0 && i + 1 < argc) {
            char *end;
            long n = strtol(argv[++i], &end, 10);
            if (*end || n < 1 || n > INT_MAX) {
                fprintf(stderr, "ctcsim: --every must be a positive integer (got \"%s\")\n",
                        argv[i]);
                return EXIT_USAGE;
            }
            every = (int)n;
        } else if (strcmp(a, "--quiet") == 0) {
            quiet = 1;
        } else if (!path && (a[0] != '-' || strcmp(a, "-") == 0)) {
            path = a;
        } else {
            fprintf(stderr, "ctcsim: run: unexpected argument \"%s\"\n%s", a, usage);
            return EXIT_USAGE;
        }
    }
    if (!path) {
        fprintf(stderr, "ctcsim: run: which job? (a FILE or - for standard input)\n%s", usage);
        return EXIT_USAGE;
    }

    job *j = NULL;
    int rc = load_job(path, &j);
    if (rc) return rc;
    unsigned missing = mask & ~(j->spec.channels ? j->spec.channels : CTC_CH_ALL);
    for (int c = 0; missing && c < CTC_NCHANNELS; c++) {
        if (!(missing & CTC_CH_BIT(c))) continue;
        fprintf(stderr, "ctcsim: --channels: \"%s\" is not among the job's output channels\n",
                ctc_channel_name((ctc_channel)c));
        job_free(j);
        return EXIT_USAGE;
    }

    ctc_sim_result *r = NULL;
    char err[256];
    if (ctc_sim_run(&j->spec, NULL, &r, err, sizeof err) != CTC_OK) {
        fprintf(stderr, "ctcsim: %s: %s\n", path, err);
        job_free(j);
        return EXIT_INVALID;
    }

    FILE *out = outpath ? fopen(outpath, "w") : stdout;
    if (!out) {
        fprintf(stderr, "ctcsim: %s: %s\n", outpath, strerror(errno));
        rc = EXIT_IO;
    } else {
        result_select sel = {.channels = mask, .every = every};
        int wrc = strcmp(format, "json") == 0 ? result_write_json(out, r, j, &sel)
                                              : result_write_csv(out, r, &sel);
        if (fflush(out) != 0) wrc = -1;
        if (outpath && fclose(out) != 0) wrc = -1;
        if (wrc) {
            fprintf(stderr, "ctcsim: writing %s: %s\n", outpath ? outpath : "output",
                    strerror(errno));
            rc = EXIT_IO;
        }
    }
    if (!quiet) print_summary(j, r);
    if (!rc && r->status != CTC_RUN_DONE) rc = EXIT_STOPPED;
    ctc_sim_result_free(r);
    job_free(j);
    return rc;
}

/* " in a tree, parents -1 0 1 0 3" for a job whose bodies are not a chain (the first 16 parents,
 * then "..."), else "" */
static void describe_tree(const job *j, char *out, size_t len)
{
    int n = j->spec.chain.nbodies, chain = 1;
    for (int k = 0; k < n; k++) chain &= j->parent[k] == k - 1;
    out[0] = '\0';
    if (chain) return;
    size_t used = (size_t)snprintf(out, len, " in a tree, parents");
    for (int k = 0; k < n && used < len; k++) {
        used += (size_t)snprintf(out + used, len - used, k < 16 ? " %d" : " ...", j->parent[k]);
        if (k >= 16) break;
    }
}

static int cmd_validate(int argc, char **argv)
{
    if (argc != 1) {
        fprintf(stderr, "ctcsim: validate takes one FILE (or -)\n%s", usage);
        return EXIT_USAGE;
    }
    job *j = NULL;
    int rc = load_job(argv[0], &j);
    if (rc) return rc;
    char err[256];
    if (ctc_sim_check(&j->spec, err, sizeof err) != CTC_OK) {
        fprintf(stderr, "ctcsim: %s: %s\n", argv[0], err);
        job_free(j);
        return EXIT_INVALID;
    }
    char *text = cJSON_Print(j->normalised);
    if (text) printf("%s\n", text);
    cJSON_free(text);
    char tree[160] = "";
    describe_tree(j, tree, sizeof tree);
    if (j->spec.chain.loop)
        fprintf(stderr,
                "%s: valid (%d bodies%s and a loop, %d coordinates, %d independent, "
                "controller %s)\n",
                argv[0], j->spec.chain.nbodies, tree, j->nv, j->nind,
                ctc_ctrl_type_name(j->spec.controller));
    else
        fprintf(stderr, "%s: valid (%d bodies%s, %d coordinates, controller %s)\n", argv[0],
                j->spec.chain.nbodies, tree, j->nv, ctc_ctrl_type_name(j->spec.controller));
    job_free(j);
    return text ? 0 : EXIT_IO;
}

static int cmd_presets(void)
{
    int n = 0;
    const preset *p = presets_list(&n);
    for (int i = 0; i < n; i++) printf("%-32s %s\n", p[i].name, p[i].summary);
    return 0;
}

static int cmd_preset(int argc, char **argv)
{
    if (argc < 1) {
        fprintf(stderr, "ctcsim: preset: which one? (ctcsim presets lists them)\n");
        return EXIT_USAGE;
    }
    const preset *p = presets_find(argv[0]);
    if (!p) {
        fprintf(stderr, "ctcsim: no preset \"%s\" (ctcsim presets lists them)\n", argv[0]);
        return EXIT_INVALID;
    }
    /* KEY=VALUE parameters, the value as JSON (a bare word is taken as a string) */
    cJSON *request = cJSON_CreateObject();
    for (int i = 1; i < argc; i++) {
        char *eq = strchr(argv[i], '=');
        if (!eq || eq == argv[i]) {
            fprintf(stderr, "ctcsim: preset: expected KEY=VALUE (got \"%s\")\n", argv[i]);
            cJSON_Delete(request);
            return EXIT_USAGE;
        }
        cJSON *value = cJSON_Parse(eq + 1);
        if (!value) value = cJSON_CreateString(eq + 1);
        *eq = 0;
        cJSON_AddItemToObject(request, argv[i], value);
    }
    job_error err;
    cJSON *doc = p->build(request, &err);
    cJSON_Delete(request);
    if (!doc) {
        fprintf(stderr, "ctcsim: preset %s: %s: %s\n", argv[0], err.field, err.message);
        return EXIT_INVALID;
    }
    char *text = cJSON_Print(doc);
    cJSON_Delete(doc);
    if (!text) return EXIT_IO;
    printf("%s\n", text);
    cJSON_free(text);
    return 0;
}

/* The job `ctcsim import` prints around a robot scene: a PD controller (zeta 1, tau 0.1 s: kp 100
 * s^-2, kv 20 s^-1), every joint moving 0.2 rad (or m) from q = 0 by a minimum-jerk profile over
 * 2 s, and 3 s simulated. */
#define IMPORT_JOB_TAIL                                                                            \
    "\"controller\": {\"type\": \"pd\", \"zeta\": 1, \"tau\": 0.1}, "                              \
    "\"trajectory\": {\"type\": \"min_jerk\", \"from\": 0, \"to\": 0.2, \"start\": 0, "            \
    "\"end\": 2}, \"duration\": 3"

static int cmd_import(int argc, char **argv)
{
    int dh = argc == 2 && strcmp(argv[0], "--dh") == 0;
    if (!(argc == 1 && argv[0][0] != '-') && !dh) {
        fprintf(stderr, "ctcsim: import takes FILE.urdf or --dh FILE.json\n%s", usage);
        return EXIT_USAGE;
    }
    const char *path = argv[argc - 1];
    size_t len = 0;
    const char *why = "";
    char *text = read_input(path, &len, &why);
    if (!text) {
        fprintf(stderr, "ctcsim: %s: %s\n", path, why);
        return EXIT_IO;
    }
    /* the job document: the robot as the scene's "urdf" or "dh", and the defaults above */
    cJSON *doc = cJSON_Parse("{" IMPORT_JOB_TAIL "}");
    cJSON *scene = cJSON_CreateObject(), *robot = NULL;
    char name[JOB_MAX_NAME + 1] = "robot";
    if (dh) {
        robot = cJSON_ParseWithLength(text, len);
        const char *base = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
        snprintf(name, sizeof name, "%.*s", (int)strcspn(base, "."), base);
    } else {
        char *z = realloc(text, len + 1);
        if (z) {
            text = z;
            text[len] = '\0';
            robot = cJSON_CreateString(text);
            /* the robot's name, when it has one (errors are the job's to report) */
            char msg[512], rname[JOB_MAX_NAME + 1];
            cJSON_Delete(urdf_to_bodies(text, len, rname, sizeof rname, msg, sizeof msg));
            if (rname[0]) snprintf(name, sizeof name, "%s", rname);
        }
    }
    free(text);
    if (!robot && dh) {
        fprintf(stderr, "ctcsim: %s: not valid JSON (a DH table: {\"convention\", \"rows\"})\n",
                path);
        cJSON_Delete(doc);
        cJSON_Delete(scene);
        return EXIT_INVALID;
    }
    if (!doc || !scene || !robot || !name[0]) {
        fprintf(stderr, "ctcsim: out of memory\n");
        cJSON_Delete(doc);
        cJSON_Delete(scene);
        cJSON_Delete(robot);
        return EXIT_IO;
    }
    cJSON_AddItemToObject(scene, dh ? "dh" : "urdf", robot);
    cJSON_AddItemToObject(doc, "scene", scene);
    cJSON_AddStringToObject(doc, "name", name);

    job *j = NULL;
    job_error err;
    int rc = job_from_json(doc, &j, &err);
    cJSON_Delete(doc);
    if (rc != 0) {
        fprintf(stderr, "ctcsim: %s: %s: %s\n", path, err.field, err.message);
        return EXIT_INVALID;
    }
    char *out = cJSON_Print(j->normalised);
    if (out) printf("%s\n", out);
    fprintf(stderr,
            "%s: %d bodies, %d coordinates: a PD controller moving each joint 0.2 from "
            "q = 0 in 2 s\n",
            path, j->spec.chain.nbodies, j->nv);
    cJSON_free(out);
    job_free(j);
    return out ? 0 : EXIT_IO;
}

int main(int argc, char **argv)
{
    if (argc < 2 || strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0) {
        fputs(usage, argc < 2 ? stderr : stdout);
        return argc < 2 ? EXIT_USAGE : 0;
    }
    const char *cmd = argv[1];
    if (strcmp(cmd, "run") == 0) return cmd_run(argc - 2, argv + 2);
    if (strcmp(cmd, "validate") == 0) return cmd_validate(argc - 2, argv + 2);
    if (strcmp(cmd, "presets") == 0 && argc == 2) return cmd_presets();
    if (strcmp(cmd, "preset") == 0) return cmd_preset(argc - 2, argv + 2);
    if (strcmp(cmd, "import") == 0) return cmd_import(argc - 2, argv + 2);
    fprintf(stderr, "ctcsim: unknown command \"%s\"\n%s", cmd, usage);
    return EXIT_USAGE;
}

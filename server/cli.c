/*
 * cli.c - the `ctcsim` command line: run, validate and list jobs without the service.
 *
 *   ctcsim run FILE|- [--format csv|json] [-o OUT] [--channels LIST] [--every N] [--quiet]
 *   ctcsim validate FILE|-
 *   ctcsim presets
 *   ctcsim preset NAME [KEY=VALUE ...]
 *   ctcsim import FILE.urdf | --dh FILE.json
 *   ctcsim sweep FILE|- [--csv] [--threads N] [--validate] [--quiet]
 *
 * It reads a job (job_json.h) from a file or standard input, runs it with the library in this
 * thread, and writes the series as CSV or one JSON object (result_out.h) to standard output or
 * OUT; a one-line summary goes to standard error. `sweep` expands a family of jobs (family.h) and
 * runs its members on N threads (default: the processors online), each member from its stored
 * normalised spec as the service's workers run it, with a progress bar on standard error when
 * that is a terminal; it prints the family's table (family.h: CSV with --csv, else aligned
 * columns), the same table GET /api/families/{id} gives. Exit codes:
 *   0  the run finished (status "done"), or the job is valid, or the listing or job was printed
 *   1  usage error (unknown command or option)
 *   2  the job is invalid: "FILE: FIELD: MESSAGE" on standard error
 *   3  the run stopped early: diverged, integrator failure, timeout, or singular (a loop's
 *      independent joints can no longer drive it) (the samples up to there are still written);
 *      for sweep, a member did
 *   4  input or output error (file not found, disk full)
 */
#include <errno.h>
#include <limits.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "family.h"
#include "job_json.h"
#include "presets.h"
#include "result_out.h"
#include "urdf.h"

enum { EXIT_USAGE = 1, EXIT_INVALID = 2, EXIT_STOPPED = 3, EXIT_IO = 4 };

#define CLI_MAX_INPUT (256L * 1024 * 1024)
#define CLI_MAX_FAMILY 1000000 /* members of a family run by `ctcsim sweep` */

static const char usage[] =
    "usage: ctcsim run FILE|- [--format csv|json] [-o OUT] [--channels LIST] [--every N] "
    "[--quiet]\n"
    "       ctcsim validate FILE|-\n"
    "       ctcsim presets\n"
    "       ctcsim preset NAME [KEY=VALUE ...]\n"
    "       ctcsim import FILE.urdf | --dh FILE.json\n"
    "       ctcsim sweep FILE|- [--csv] [--threads N] [--validate] [--quiet]\n"
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
    "  sweep     run a family of jobs (a base job and axes; README \"Studies\") on N threads\n"
    "            (default: every processor) and print its table, one row per member: aligned\n"
    "            text, or CSV with --csv; --validate expands and checks it without running\n"
    "\n"
    "  --channels LIST  comma-separated subset of q,qdot,q_des,qdot_des,e,tau,w,energy,loop,\n"
    "                   end_effector,body_pose\n"
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

/* An option's integer value from lo to hi into *out: 0, or -1 after printing "ctcsim: FLAG must
 * be WHAT (got "TEXT")". */
static int option_integer(const char *flag, const char *text, long lo, long hi, const char *what,
                          long *out)
{
    char *end;
    errno = 0;
    long x = strtol(text, &end, 10);
    if (end == text || *end || errno == ERANGE || x < lo || x > hi) {
        fprintf(stderr, "ctcsim: %s must be %s (got \"%s\")\n", flag, what, text);
        return -1;
    }
    *out = x;
    return 0;
}

/* A command's argument a that is no option it knows: its one FILE (or - for standard input),
 * taken into *path: 0, or -1 after printing "ctcsim: CMD: unexpected argument" and the usage
 * (an option, or a second FILE). */
static int take_path(const char *cmd, const char *a, const char **path)
{
    if (!*path && (a[0] != '-' || strcmp(a, "-") == 0)) {
        *path = a;
        return 0;
    }
    fprintf(stderr, "ctcsim: %s: unexpected argument \"%s\"\n%s", cmd, a, usage);
    return -1;
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
            long n;
            if (option_integer(a, argv[++i], 1, INT_MAX, "a positive integer", &n) != 0)
                return EXIT_USAGE;
            every = (int)n;
        } else if (strcmp(a, "--quiet") == 0) {
            quiet = 1;
        } else if (take_path("run", a, &path) != 0) {
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
    int meshes = 0;
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
            cJSON_Delete(urdf_read(text, len, rname, sizeof rname, &meshes, msg, sizeof msg));
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
    if (meshes > 0)
        fprintf(stderr,
                "note: %d <visual> mesh%s left out (the animation draws boxes, cylinders and "
                "spheres)\n",
                meshes, meshes == 1 ? "" : "es");
    cJSON_free(out);
    job_free(j);
    return out ? 0 : EXIT_IO;
}

/* ---- sweep ---- */

/* One member's outcome. */
typedef struct sweep_result {
    const char *status; /* the service's status name */
    cJSON *metrics;     /* or NULL */
    char message[1024];
} sweep_result;

typedef struct sweep_ctx {
    const family *f;
    sweep_result *results; /* (f->nmembers) */
    atomic_long next;      /* the next member to take */
    atomic_long done;
} sweep_ctx;

/* runs member m as a worker of the service does: parse its stored spec, run, metrics */
static void sweep_member(const family_member *m, sweep_result *out)
{
    job *j = NULL;
    job_error jerr;
    ctc_sim_result *r = NULL;
    out->status = "failed";
    if (job_parse(m->spec, strlen(m->spec), &j, &jerr) != 0) {
        snprintf(out->message, sizeof out->message, "%.250s: %.700s", jerr.field, jerr.message);
        return;
    }
    if (ctc_sim_run(&j->spec, NULL, &r, out->message, sizeof out->message) != CTC_OK) {
        job_free(j);
        return;
    }
    out->status = r->status == CTC_RUN_DONE        ? "done"
                  : r->status == CTC_RUN_DIVERGED  ? "diverged"
                  : r->status == CTC_RUN_CANCELLED ? "cancelled"
                                                   : "failed";
    snprintf(out->message, sizeof out->message, "%s", r->message);
    /* the metrics as the service stores them: printed by cJSON and read back (its print keeps
       15 digits where they read back within DBL_EPSILON), so both tables show the same numbers */
    cJSON *metrics = result_metrics_json(r, j);
    char *text = metrics ? cJSON_PrintUnformatted(metrics) : NULL;
    out->metrics = text ? cJSON_Parse(text) : NULL;
    cJSON_free(text);
    cJSON_Delete(metrics);
    ctc_sim_result_free(r);
    job_free(j);
}

static void *sweep_worker(void *arg)
{
    sweep_ctx *c = arg;
    for (;;) {
        long i = atomic_fetch_add(&c->next, 1);
        if (i >= c->f->nmembers) break;
        sweep_member(&c->f->members[i], &c->results[i]);
        atomic_fetch_add(&c->done, 1);
    }
    return NULL;
}

/* the progress bar, on a terminal only */
static void sweep_progress(long done, long total)
{
    int width = 40, filled = total ? (int)(width * done / total) : width;
    fprintf(stderr, "\r[%.*s%*s] %ld/%ld", filled, "########################################",
            width - filled, "", done, total);
    fflush(stderr);
}

/* splits one CSV line in place into cells (quoted cells keep their quotes); the count */
static int csv_cells(char *line, char **cells, int max)
{
    int n = 0, quoted = 0;
    char *start = line;
    for (char *p = line;; p++) {
        if (*p == '"') quoted = !quoted;
        if ((*p == ',' && !quoted) || *p == '\0') {
            int end = *p == '\0';
            *p = '\0';
            if (n < max) cells[n++] = start;
            start = p + 1;
            if (end) break;
        }
    }
    return n;
}

/* the CSV table as aligned columns (numbers to the right) */
static int print_aligned(FILE *out, char *csv)
{
    enum { MAXCOLS = 64 };
    int widths[MAXCOLS] = {0}, ncols = 0;
    long nlines = 0;
    for (char *p = csv; *p; p = strchr(p, '\n') + 1, nlines++)
        if (!strchr(p, '\n')) break;
    char **lines = calloc((size_t)nlines + 1, sizeof *lines);
    if (!lines) return -1;
    long k = 0;
    for (char *save = NULL, *l = strtok_r(csv, "\n", &save); l && k <= nlines;
         l = strtok_r(NULL, "\n", &save))
        lines[k++] = l;
    char *cells[MAXCOLS];
    for (int pass = 0; pass < 2; pass++)
        for (long i = 0; i < k; i++) {
            char copy[8192];
            snprintf(copy, sizeof copy, "%s", lines[i]);
            int n = csv_cells(copy, cells, MAXCOLS);
            if (n > ncols) ncols = n;
            for (int c = 0; c < n; c++) {
                int w = (int)strlen(cells[c]);
                if (pass == 0 && w > widths[c]) widths[c] = w;
                if (pass == 1)
                    fprintf(out, "%s%*s", c ? "  " : "", i ? widths[c] : -widths[c], cells[c]);
            }
            if (pass == 1) fputc('\n', out);
        }
    free(lines);
    return ferror(out) ? -1 : 0;
}

static int cmd_sweep(int argc, char **argv)
{
    const char *path = NULL;
    int csv = 0, quiet = 0, validate = 0;
    long threads = sysconf(_SC_NPROCESSORS_ONLN);
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--csv") == 0) {
            csv = 1;
        } else if (strcmp(a, "--quiet") == 0) {
            quiet = 1;
        } else if (strcmp(a, "--validate") == 0) {
            validate = 1;
        } else if (strcmp(a, "--threads") == 0 && i + 1 < argc) {
            if (option_integer(a, argv[++i], 1, 1024, "an integer from 1 to 1024", &threads) != 0)
                return EXIT_USAGE;
        } else if (take_path("sweep", a, &path) != 0) {
            return EXIT_USAGE;
        }
    }
    if (!path) {
        fprintf(stderr, "ctcsim: sweep: which family? (a FILE or - for standard input)\n%s", usage);
        return EXIT_USAGE;
    }
    if (threads < 1) threads = 1;

    size_t len = 0;
    const char *why = "";
    char *text = read_input(path, &len, &why);
    if (!text) {
        fprintf(stderr, "ctcsim: %s: %s\n", path, why);
        return EXIT_IO;
    }
    family *f = NULL;
    family_error ferr;
    int rc = family_expand(text, len, CLI_MAX_FAMILY, &f, &ferr);
    free(text);
    if (rc != 0) {
        fprintf(stderr, "ctcsim: %s: %s%s%s\n", path, ferr.field, ferr.field[0] ? ": " : "",
                ferr.message);
        return ferr.status == 503 ? EXIT_IO : EXIT_INVALID;
    }
    if (validate) {
        fprintf(stderr, "%s: valid family \"%s\": %ld members\n", path, f->name, f->nmembers);
        family_free(f);
        return 0;
    }

    /* the members on the threads, the progress bar on this one */
    sweep_ctx c = {.f = f, .results = calloc((size_t)f->nmembers + 1, sizeof *c.results)};
    atomic_init(&c.next, 0);
    atomic_init(&c.done, 0);
    pthread_t *tids = calloc((size_t)threads, sizeof *tids);
    family_row *rows = calloc((size_t)f->nmembers + 1, sizeof *rows);
    cJSON **values = calloc((size_t)f->nmembers + 1, sizeof *values);
    cJSON *paths = cJSON_Parse(f->paths);
    if (!c.results || !tids || !rows || !values || !paths) {
        fprintf(stderr, "ctcsim: out of memory\n");
        rc = EXIT_IO;
        goto done;
    }
    if (threads > f->nmembers) threads = f->nmembers > 0 ? f->nmembers : 1;
    long started = 0;
    for (; started < threads; started++)
        if (pthread_create(&tids[started], NULL, sweep_worker, &c) != 0) break;
    if (started == 0) sweep_worker(&c);
    int bar = !quiet && isatty(STDERR_FILENO);
    while (bar && atomic_load(&c.done) < f->nmembers) {
        sweep_progress(atomic_load(&c.done), f->nmembers);
        struct timespec ts = {.tv_sec = 0, .tv_nsec = 100000000L};
        nanosleep(&ts, NULL);
    }
    for (long t = 0; t < started; t++) pthread_join(tids[t], NULL);
    if (bar) {
        sweep_progress(f->nmembers, f->nmembers);
        fputc('\n', stderr);
    }

    /* the table */
    long stopped = 0;
    for (long i = 0; i < f->nmembers; i++) {
        values[i] = cJSON_Parse(f->members[i].values);
        rows[i] = (family_row){.index = f->members[i].index,
                               .replica = f->members[i].replica,
                               .status = c.results[i].status,
                               .values = values[i],
                               .metrics = c.results[i].metrics,
                               .message = c.results[i].message};
        stopped += strcmp(c.results[i].status, "done") != 0;
    }
    char *table = NULL;
    size_t tlen = 0;
    FILE *mem = open_memstream(&table, &tlen);
    int wrc = mem ? family_write_csv(mem, paths, rows, f->nmembers) : -1;
    if (mem && fclose(mem) != 0) wrc = -1;
    if (wrc == 0) wrc = csv ? (fputs(table, stdout) < 0 ? -1 : 0) : print_aligned(stdout, table);
    if (fflush(stdout) != 0) wrc = -1;
    free(table);
    if (wrc != 0) {
        fprintf(stderr, "ctcsim: writing the table: %s\n", strerror(errno));
        rc = EXIT_IO;
        goto done;
    }
    if (!quiet)
        fprintf(stderr, "%s: %ld members on %ld threads, %ld done, %ld stopped early\n", f->name,
                f->nmembers, started ? started : 1, f->nmembers - stopped, stopped);
    rc = stopped ? EXIT_STOPPED : 0;
done:
    for (long i = 0; c.results && values && i < f->nmembers; i++) {
        cJSON_Delete(c.results[i].metrics);
        cJSON_Delete(values[i]);
    }
    free(c.results);
    free(tids);
    free(rows);
    free(values);
    cJSON_Delete(paths);
    family_free(f);
    return rc;
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
    if (strcmp(cmd, "sweep") == 0) return cmd_sweep(argc - 2, argv + 2);
    fprintf(stderr, "ctcsim: unknown command \"%s\"\n%s", cmd, usage);
    return EXIT_USAGE;
}

/*
 * fuzz_job.c - libFuzzer harness of the job parser: the bytes of one POST /api/jobs body, through
 * everything the service does with a body before it stores and queues the job.
 *
 * That is job_parse (job_json.h) alone: the RFC 8259 checks cJSON leaves out (json_strict.h), the
 * cJSON parse, repeated keys, a preset's expansion and its overrides as a merge patch
 * (json_merge.h), the walk of the format with its limits, ctc_model_build and ctc_sim_check. The
 * HTTP layer (framing, Content-Type, the body's size limit) and the store are not reached; the
 * route's last check, "threads" against --job-threads, reads a parsed field and is not repeated.
 *
 * Besides the sanitizers (ASan with leak detection, UBSan) the harness checks the parser's
 * contract and aborts, so that libFuzzer keeps the input, when it is broken:
 *   - a refused body has an error code other than JOB_OK and JOB_NO_MEMORY (inputs are small,
 *     nothing here runs out of memory), a name for it, and a non-empty message; field and message
 *     are terminated strings within their buffers;
 *   - an accepted body's normalised document (job_json.h: "itself a valid job document ... it
 *     parses to the same spec. Printed with cJSON it parses back to the same text") is printed,
 *     parsed again, and must be accepted with the same sizes, and print to the same text.
 * Messages go to standard error before abort().
 *
 * Built two ways (Makefile): with -fsanitize=fuzzer for `make fuzz`, and with seed_driver.c, a
 * main that runs each seed once, for the build-only check in `make check`.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "job_json.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* reports a broken contract with the input's size and aborts */
static void fail(const char *what, const char *detail, size_t size)
{
    fprintf(stderr, "fuzz_job: %s (%s; input of %zu bytes)\n", what, detail, size);
    abort();
}

/* an error must be complete: a code that names a refusal, a terminated field and a message */
static void check_error(const job_error *e, size_t size)
{
    if (memchr(e->field, '\0', sizeof e->field) == NULL) fail("field not terminated", "", size);
    if (memchr(e->message, '\0', sizeof e->message) == NULL)
        fail("message not terminated", e->field, size);
    if (e->code == JOB_OK) fail("refused with code JOB_OK", e->message, size);
    if (e->code == JOB_NO_MEMORY) fail("NO_MEMORY on a small input", e->message, size);
    if (strcmp(job_error_code_name(e->code), "UNKNOWN") == 0)
        fail("refused with a code that has no name", e->message, size);
    if (e->message[0] == '\0') fail("refused without a message", e->field, size);
}

/* the normalised document of an accepted job parses to the same sizes and prints the same */
static void check_normalised(const job *j, size_t size)
{
    char *text = cJSON_PrintUnformatted(j->normalised);
    if (text == NULL) fail("normalised document not printable", "", size);
    job *again = NULL;
    job_error e = {0};
    if (job_parse(text, strlen(text), &again, &e) != 0) {
        fprintf(stderr, "fuzz_job: normalised document: %s\n", text);
        fail("normalised document refused", e.message, size);
    }
    if (again->nq != j->nq || again->nv != j->nv || again->nind != j->nind ||
        again->spec.chain.nbodies != j->spec.chain.nbodies)
        fail("normalised document parses to other sizes", "nq, nv, nind or nbodies", size);
    char *text2 = cJSON_PrintUnformatted(again->normalised);
    if (text2 == NULL) fail("normalised document not printable", "second parse", size);
    if (strcmp(text, text2) != 0) {
        fprintf(stderr, "fuzz_job: first:  %s\nfuzz_job: second: %s\n", text, text2);
        fail("normalised document is not a fixed point", "printed texts differ", size);
    }
    cJSON_free(text2);
    cJSON_free(text);
    job_free(again);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    job *j = NULL;
    job_error e = {0};
    int rc = job_parse((const char *)data, size, &j, &e);
    if (rc != 0) {
        if (j != NULL) fail("refused but returned a job", e.message, size);
        check_error(&e, size);
        return 0;
    }
    if (j == NULL) fail("accepted without a job", "", size);
    if (j->normalised == NULL) fail("accepted without a normalised document", "", size);
    check_normalised(j, size);
    job_free(j);
    return 0;
}

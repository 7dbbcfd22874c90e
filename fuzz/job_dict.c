/*
 * job_dict.c - prints the libFuzzer dictionary of the job format (fuzz/job.dict) from the format's
 * own tables, so that the dictionary follows the parser.
 *
 * The entries, each once, in this order: JSON's literals and the number and string forms at the
 * edges of the strict checks (json_strict.h); every key of every object of the format
 * (job_format_object_tables), quoted as it appears in a document; every type or method a typed
 * object takes, quoted; the JSON of every default (job_format_defaults); every preset's name and
 * parameter (presets_list); every output channel's name (ctc_channel_name). The format is
 * libFuzzer's (and AFL's): one `"text"` a line, with \\, \" and \xNN escapes.
 *
 * `make check` runs it and compares its output with the committed fuzz/job.dict; `make fuzz-dict`
 * rewrites that file.
 */
#include <stdio.h>
#include <string.h>

#include "job_json.h"
#include "presets.h"
#include "sim.h"

#define MAX_ENTRIES 2048

static const char *seen[MAX_ENTRIES];
static char store[MAX_ENTRIES][80];
static int nseen;

/* prints text as one dictionary line, unless it was printed already */
static void entry(const char *text)
{
    for (int i = 0; i < nseen; i++)
        if (strcmp(seen[i], text) == 0) return;
    if (nseen == MAX_ENTRIES || strlen(text) >= sizeof store[0]) return;
    strcpy(store[nseen], text);
    seen[nseen] = store[nseen];
    nseen++;
    putchar('"');
    for (const unsigned char *c = (const unsigned char *)text; *c != '\0'; c++) {
        if (*c == '\\' || *c == '"')
            printf("\\%c", *c);
        else if (*c < 0x20 || *c >= 0x7f)
            printf("\\x%02X", *c);
        else
            putchar(*c);
    }
    puts("\"");
}

/* "text", with the quotes, as a key or a string value appears in a document */
static void quoted(const char *text)
{
    char buf[96];
    snprintf(buf, sizeof buf, "\"%s\"", text);
    entry(buf);
}

int main(void)
{
    static const char *const grammar[] = {
        "null",    "true",    "false",          "{}",   "[]", ":",  ",",  "-0", "0.5",
        "1e-300",  "1e308",   "1e999",          "-1",   "01", "1.", ".5", "1e", "+1",
        "\\u0000", "\\u00e9", "\\ud83d\\ude00", "\\\"", NULL};
    for (int i = 0; grammar[i] != NULL; i++) entry(grammar[i]);

    const job_format_object *const *tables = job_format_object_tables();
    for (int t = 0; tables[t] != NULL; t++) {
        for (const job_format_object *o = tables[t]; o->path != NULL; o++) {
            for (const char *const *k = o->keys; *k != NULL; k++) quoted(*k);
            if (o->type_key != NULL) quoted(o->type_key);
            if (o->type != NULL) quoted(o->type);
        }
    }
    for (int t = 0; job_format_defaults[t] != NULL; t++) {
        for (const job_format_default *d = job_format_defaults[t]; d->path != NULL; d++)
            if (d->n == 0) entry(d->json);
    }
    int count;
    const preset *list = presets_list(&count);
    quoted("preset");
    for (int i = 0; i < count; i++) {
        quoted(list[i].name);
        for (const char *const *p = list[i].params; p != NULL && *p != NULL; p++) quoted(*p);
    }
    for (int c = 0; c < CTC_NCHANNELS; c++) quoted(ctc_channel_name((ctc_channel)c));
    return 0;
}

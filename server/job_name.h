/*
 * job_name.h - the name of a job edited from a preset: the preset's name followed by what the
 * edit changed, "triple_pendulum_pid, kp = 400, duration = 2", so runs made from one preset can
 * be told apart in a list. The preset is named by its key (what "preset" says), short and the
 * same whatever its document's descriptive name; a request that changes nothing keeps that.
 *
 * The change is found on the server, between two normalised documents (job_json.h): the
 * preset's own job (built from the request's preset parameters, nothing merged) and the job the
 * request makes. Both have every default written out, so a value restated at its default is no
 * change and a document posted whole (the page's form sends the preset's name and a merge
 * patch of its edits) is named as the same edit posted as a few keys.
 */
#ifndef JOB_NAME_H
#define JOB_NAME_H

#include <stddef.h>

#include <cjson/cJSON.h>

#define JOB_NAME_MAX_CHANGES 4 /* changes written out; the rest are counted ("+3 more") */

/* Writes "BASE, CHANGE, ..." into out (len bytes, at most len - 1 of text, never a change cut
 * in two) and returns the number of changes found; with none, out is BASE. Compared: every key
 * but "name" and "tags", objects key by key (a key only one side has is "KEY = VALUE" or
 * "no KEY"), arrays of one length entry by entry, anything else by value. A change is written
 * "PATH = VALUE": PATH as an error names a field ("trajectory[1].amplitude") less a leading
 * "controller.", VALUE a number in %g, a string, true/false/null, an array of at most 4 scalars
 * written out ("[0.1, 0, 0]"), else "(N entries)" or "{...}". A controller whose "type" differs
 * is one change, "controller = TYPE" (its parameters are not compared). base and edited are
 * not modified. */
int job_name_changes(const cJSON *base, const cJSON *edited, const char *base_name, char *out,
                     size_t len);

#endif

/*
 * client_count.h - how much each client holds at once, counted per client address, for the
 * service's per-client limits (issue 25): queued and running jobs (routes.c), replies waiting off
 * the HTTP threads (http.c).
 *
 * A client is a key string (the numeric address of the peer, as http_client gives it; the loopback
 * address counts like any other). Each key has a count, taken one at a time up to a limit and
 * given back one at a time; a key whose count falls to 0 is forgotten, so the table holds only the
 * clients that hold something. A taken unit may carry an id (a job id), so that the unit can be
 * given back by the id alone (when the job leaves the workers, whose queue knows ids only).
 *
 * Take, give and get are O(1) expected: chained hash tables of keys and of ids, doubled when they
 * hold twice as many entries as buckets. All functions are thread-safe (one mutex per table).
 */
#ifndef CLIENT_COUNT_H
#define CLIENT_COUNT_H

#include <stdint.h>

#define CLIENT_KEY_MAX 64 /* bytes of a key, its NUL included; longer keys are cut */

typedef struct client_count client_count;

/* A new, empty table; NULL when out of memory. Free it with client_count_free (NULL allowed). */
client_count *client_count_new(void);
void client_count_free(client_count *c);

/* Adds one to client's count unless it already holds limit (limit 0: no limit). Returns 0 when
 * taken, 1 when client is at its limit (nothing changes), -1 out of memory. */
int client_count_take(client_count *c, const char *client, unsigned limit);

/* Gives back one unit taken by client_count_take (without an id); a client that holds none is
 * left alone. */
void client_count_give(client_count *c, const char *client);

/* As client_count_take, the unit carrying id (an id already held is refused with -1). */
int client_count_take_id(client_count *c, const char *client, int64_t id, unsigned limit);

/* Gives back the unit that carries id, to whichever client took it. Returns 1 when there was
 * one, 0 otherwise (an id never taken, or given back already). */
int client_count_give_id(client_count *c, int64_t id);

/* What client holds now (0 for a client the table does not know). */
unsigned client_count_get(client_count *c, const char *client);

#endif

/*
 * client_count.c - counts per client address (client_count.h).
 *
 * Two chained hash tables under one mutex: keys (FNV-1a of the address string) to their count,
 * and ids (a splitmix64 mix of the id) to the key entry that took them. Nodes are allocated one
 * by one and never move, so an id's node may point at its key's node; a key node is freed when
 * its count falls to 0, which cannot happen while an id points at it (each id holds one unit,
 * which only giving the id back returns; client_count_give returns units taken without one).
 * A table doubles its buckets when its entries reach twice their number, so chains stay short;
 * it never shrinks (its peak is bounded by what the service lets clients hold at once).
 */
#include "client_count.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#define INITIAL_BUCKETS 64

typedef struct key_node {
    char key[CLIENT_KEY_MAX];
    unsigned count; /* units held, with an id or without */
    unsigned plain; /* of which without an id */
    struct key_node *next;
} key_node;

typedef struct id_node {
    int64_t id;
    key_node *owner;
    struct id_node *next;
} id_node;

struct client_count {
    pthread_mutex_t lock;
    key_node **keys;
    size_t nkeys, key_buckets; /* entries, buckets (a power of 2) */
    id_node **ids;
    size_t nids, id_buckets;
};

static uint64_t hash_key(const char *s)
{
    uint64_t h = 1469598103934665603ULL;
    for (; *s; s++) h = (h ^ (unsigned char)*s) * 1099511628211ULL;
    return h;
}

static uint64_t hash_id(int64_t id)
{
    uint64_t z = (uint64_t)id + 0x9e3779b97f4a7c15ULL;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

client_count *client_count_new(void)
{
    client_count *c = calloc(1, sizeof *c);
    if (!c) return NULL;
    c->keys = calloc(INITIAL_BUCKETS, sizeof *c->keys);
    c->ids = calloc(INITIAL_BUCKETS, sizeof *c->ids);
    if (!c->keys || !c->ids || pthread_mutex_init(&c->lock, NULL) != 0) {
        free(c->keys);
        free(c->ids);
        free(c);
        return NULL;
    }
    c->key_buckets = c->id_buckets = INITIAL_BUCKETS;
    return c;
}

void client_count_free(client_count *c)
{
    if (!c) return;
    for (size_t b = 0; b < c->key_buckets; b++) {
        for (key_node *n = c->keys[b], *next; n; n = next) {
            next = n->next;
            free(n);
        }
    }
    for (size_t b = 0; b < c->id_buckets; b++) {
        for (id_node *n = c->ids[b], *next; n; n = next) {
            next = n->next;
            free(n);
        }
    }
    pthread_mutex_destroy(&c->lock);
    free(c->keys);
    free(c->ids);
    free(c);
}

/* Doubles the key table's buckets; on failure the table stays as it is (only longer chains). */
static void grow_keys(client_count *c)
{
    size_t n = 2 * c->key_buckets;
    key_node **bigger = calloc(n, sizeof *bigger);
    if (!bigger) return;
    for (size_t b = 0; b < c->key_buckets; b++) {
        for (key_node *k = c->keys[b], *next; k; k = next) {
            next = k->next;
            size_t at = hash_key(k->key) & (n - 1);
            k->next = bigger[at];
            bigger[at] = k;
        }
    }
    free(c->keys);
    c->keys = bigger;
    c->key_buckets = n;
}

static void grow_ids(client_count *c)
{
    size_t n = 2 * c->id_buckets;
    id_node **bigger = calloc(n, sizeof *bigger);
    if (!bigger) return;
    for (size_t b = 0; b < c->id_buckets; b++) {
        for (id_node *i = c->ids[b], *next; i; i = next) {
            next = i->next;
            size_t at = hash_id(i->id) & (n - 1);
            i->next = bigger[at];
            bigger[at] = i;
        }
    }
    free(c->ids);
    c->ids = bigger;
    c->id_buckets = n;
}

/* The key's node, or NULL; *link is where it hangs (or where a new one would). */
static key_node *find_key(client_count *c, const char *key, key_node ***link)
{
    key_node **at = &c->keys[hash_key(key) & (c->key_buckets - 1)];
    while (*at && strcmp((*at)->key, key) != 0) at = &(*at)->next;
    if (link) *link = at;
    return *at;
}

static id_node *find_id(client_count *c, int64_t id, id_node ***link)
{
    id_node **at = &c->ids[hash_id(id) & (c->id_buckets - 1)];
    while (*at && (*at)->id != id) at = &(*at)->next;
    if (link) *link = at;
    return *at;
}

/* The key as stored: client cut to CLIENT_KEY_MAX - 1 bytes. */
static void copy_key(char key[CLIENT_KEY_MAX], const char *client)
{
    strncpy(key, client, CLIENT_KEY_MAX - 1);
    key[CLIENT_KEY_MAX - 1] = 0;
}

/* Takes one unit for key under the lock; 0 with *taken set, 1 at the limit, -1 out of memory. */
static int take_locked(client_count *c, const char *client, unsigned limit, key_node **taken)
{
    char key[CLIENT_KEY_MAX];
    copy_key(key, client);
    key_node **link;
    key_node *k = find_key(c, key, &link);
    if (k && limit > 0 && k->count >= limit) return 1;
    if (!k) {
        k = calloc(1, sizeof *k);
        if (!k) return -1;
        memcpy(k->key, key, sizeof key);
        *link = k;
        if (++c->nkeys > 2 * c->key_buckets) grow_keys(c);
    }
    k->count++;
    *taken = k;
    return 0;
}

/* Gives one unit of k back under the lock, forgetting k at 0. */
static void give_locked(client_count *c, key_node *k)
{
    if (--k->count > 0) return;
    key_node **link;
    find_key(c, k->key, &link);
    *link = k->next;
    free(k);
    c->nkeys--;
}

int client_count_take(client_count *c, const char *client, unsigned limit)
{
    key_node *k;
    pthread_mutex_lock(&c->lock);
    int rc = take_locked(c, client, limit, &k);
    if (rc == 0) k->plain++;
    pthread_mutex_unlock(&c->lock);
    return rc;
}

void client_count_give(client_count *c, const char *client)
{
    char key[CLIENT_KEY_MAX];
    copy_key(key, client);
    pthread_mutex_lock(&c->lock);
    key_node *k = find_key(c, key, NULL);
    if (k && k->plain > 0) {
        k->plain--;
        give_locked(c, k);
    }
    pthread_mutex_unlock(&c->lock);
}

int client_count_take_id(client_count *c, const char *client, int64_t id, unsigned limit)
{
    pthread_mutex_lock(&c->lock);
    id_node **link;
    int rc = -1;
    if (!find_id(c, id, &link)) {
        id_node *i = malloc(sizeof *i);
        key_node *k;
        rc = i ? take_locked(c, client, limit, &k) : -1;
        if (rc == 0) {
            *i = (id_node){.id = id, .owner = k, .next = NULL};
            *link = i;
            if (++c->nids > 2 * c->id_buckets) grow_ids(c);
        } else {
            free(i);
        }
    }
    pthread_mutex_unlock(&c->lock);
    return rc;
}

int client_count_give_id(client_count *c, int64_t id)
{
    pthread_mutex_lock(&c->lock);
    id_node **link;
    id_node *i = find_id(c, id, &link);
    if (i) {
        *link = i->next;
        give_locked(c, i->owner);
        free(i);
        c->nids--;
    }
    pthread_mutex_unlock(&c->lock);
    return i != NULL;
}

unsigned client_count_get(client_count *c, const char *client)
{
    char key[CLIENT_KEY_MAX];
    copy_key(key, client);
    pthread_mutex_lock(&c->lock);
    key_node *k = find_key(c, key, NULL);
    unsigned n = k ? k->count : 0;
    pthread_mutex_unlock(&c->lock);
    return n;
}

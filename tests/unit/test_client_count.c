/*
 * test_client_count.c - counts per client address (server/client_count.c): a limit holds per
 * client and not across clients, given-back units free their place, ids give back to the client
 * that took them, and a long random run of takes and gives across hundreds of clients (enough to
 * make both tables grow several times) agrees step by step with a naive oracle, two arrays
 * scanned linearly. Threads taking and giving at once end with every count at 0.
 */
#include <criterion/criterion.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>

#include "client_count.h"

Test(client_count, a_limit_holds_per_client_and_given_back_places_are_free_again)
{
    client_count *c = client_count_new();
    cr_assert_not_null(c);
    for (int i = 0; i < 3; i++) cr_assert_eq(client_count_take(c, "127.0.0.1", 3), 0);
    cr_assert_eq(client_count_take(c, "127.0.0.1", 3), 1, "the 4th unit past a limit of 3");
    cr_assert_eq(client_count_get(c, "127.0.0.1"), 3);
    cr_assert_eq(client_count_take(c, "::1", 3), 0, "another client has its own count");
    client_count_give(c, "127.0.0.1");
    cr_assert_eq(client_count_take(c, "127.0.0.1", 3), 0);
    cr_assert_eq(client_count_take(c, "10.0.0.1", 0), 0, "limit 0: none");
    client_count_give(c, "10.0.0.9"); /* holds nothing: left alone */
    cr_assert_eq(client_count_get(c, "10.0.0.9"), 0);
    client_count_free(c);
    client_count_free(NULL);
}

Test(client_count, an_id_gives_back_to_the_client_that_took_it_once)
{
    client_count *c = client_count_new();
    cr_assert_eq(client_count_take_id(c, "a", 7, 2), 0);
    cr_assert_eq(client_count_take_id(c, "a", 8, 2), 0);
    cr_assert_eq(client_count_take_id(c, "a", 9, 2), 1, "at the limit");
    cr_assert_eq(client_count_take_id(c, "b", 7, 2), -1, "an id already held");
    cr_assert_eq(client_count_get(c, "b"), 0);
    cr_assert_eq(client_count_give_id(c, 7), 1);
    cr_assert_eq(client_count_give_id(c, 7), 0, "given back already");
    cr_assert_eq(client_count_give_id(c, 12345), 0, "never taken");
    cr_assert_eq(client_count_get(c, "a"), 1);
    cr_assert_eq(client_count_take_id(c, "a", 9, 2), 0);
    cr_assert_eq(client_count_give_id(c, 8), 1);
    cr_assert_eq(client_count_give_id(c, 9), 1);
    cr_assert_eq(client_count_get(c, "a"), 0);
    client_count_free(c);
}

#define NCLIENTS 300
#define NIDS 5000
#define LIMIT 7

Test(client_count, a_random_run_agrees_with_a_naive_oracle)
{
    client_count *c = client_count_new();
    unsigned held[NCLIENTS] = {0};  /* the oracle: units per client */
    unsigned plain[NCLIENTS] = {0}; /* of which taken without an id */
    int owner[NIDS];                /* and the client holding each id, -1 none */
    for (int i = 0; i < NIDS; i++) owner[i] = -1;
    srand(25);
    char key[32];
    for (int step = 0; step < 200000; step++) {
        int who = rand() % NCLIENTS, id = rand() % NIDS, op = rand() % 4;
        snprintf(key, sizeof key, "192.168.%d.%d", who / 256, who % 256);
        switch (op) {
        case 0: {
            int want = held[who] >= LIMIT ? 1 : 0;
            cr_assert_eq(client_count_take(c, key, LIMIT), want, "step %d: take %s", step, key);
            held[who] += want == 0;
            plain[who] += want == 0;
            break;
        }
        case 1:
            client_count_give(c, key); /* gives back a unit without an id only */
            if (plain[who] > 0) held[who]--, plain[who]--;
            break;
        case 2: {
            int want = owner[id] >= 0 ? -1 : held[who] >= LIMIT ? 1 : 0;
            cr_assert_eq(client_count_take_id(c, key, id, LIMIT), want, "step %d: take id %d", step,
                         id);
            if (want == 0) {
                held[who]++;
                owner[id] = who;
            }
            break;
        }
        default:
            cr_assert_eq(client_count_give_id(c, id), owner[id] >= 0, "step %d: give id %d", step,
                         id);
            if (owner[id] >= 0) held[owner[id]]--;
            owner[id] = -1;
        }
        cr_assert_eq(client_count_get(c, key), held[who], "step %d: %s", step, key);
    }
    for (int who = 0; who < NCLIENTS; who++) {
        snprintf(key, sizeof key, "192.168.%d.%d", who / 256, who % 256);
        cr_assert_eq(client_count_get(c, key), held[who], "%s at the end", key);
    }
    client_count_free(c);
}

static void *take_and_give(void *arg)
{
    client_count *c = arg;
    char key[32];
    for (int i = 0; i < 20000; i++) {
        snprintf(key, sizeof key, "10.0.0.%d", i % 37);
        if (client_count_take(c, key, 0) == 0) client_count_give(c, key);
    }
    return NULL;
}

Test(client_count, threads_taking_and_giving_at_once_end_at_zero)
{
    client_count *c = client_count_new();
    pthread_t t[4];
    for (int i = 0; i < 4; i++) cr_assert_eq(pthread_create(&t[i], NULL, take_and_give, c), 0);
    for (int i = 0; i < 4; i++) pthread_join(t[i], NULL);
    for (int i = 0; i < 37; i++) {
        char key[32];
        snprintf(key, sizeof key, "10.0.0.%d", i);
        cr_assert_eq(client_count_get(c, key), 0, "%s", key);
    }
    client_count_free(c);
}

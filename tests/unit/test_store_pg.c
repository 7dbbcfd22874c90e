/*
 * test_store_pg.c - what of the PostgreSQL backend (server/store_pg.c) needs no database: which
 * paths name one, how a URL is shown without its password, and what store_open answers when the
 * database cannot be reached. The backend's behaviour against a real PostgreSQL is the API
 * suite's (tests/api/run.sh runs it on both backends, with tests/api/cluster.test.mjs for the
 * faults), with the command line's series as the oracle.
 *
 * Oracles: the URL forms of libpq's documentation (scheme postgres or postgresql; user, password,
 * host, port, database, parameters), written out by hand; the exact messages.
 */
#include <criterion/criterion.h>
#include <string.h>

#include "store.h"
#include "store_pg.h"

Test(store_pg, url_names_postgresql_by_its_two_schemes_only)
{
    cr_assert_eq(store_pg_url("postgres://u@h/db"), 1);
    cr_assert_eq(store_pg_url("postgresql://h:5432/db?sslmode=disable"), 1);
    cr_assert_eq(store_pg_url("ctcsim.db"), 0);
    cr_assert_eq(store_pg_url("/data/postgres://x"), 0);
    cr_assert_eq(store_pg_url("postgres:/one-slash"), 0);
    cr_assert_eq(store_pg_url(""), 0);
    cr_assert_eq(store_pg_url(NULL), 0);
}

Test(store_pg, redact_hides_the_password_and_nothing_else)
{
    char out[256];
    store_pg_redact("postgres://ctcsim:s3cret@db.lab:5432/jobs", out, sizeof out);
    cr_assert_str_eq(out, "postgres://ctcsim:***@db.lab:5432/jobs");
    store_pg_redact("postgresql://ctcsim@db.lab:5432/jobs", out, sizeof out);
    cr_assert_str_eq(out, "postgresql://ctcsim@db.lab:5432/jobs");
    /* a port's colon is not a password's */
    store_pg_redact("postgres://db.lab:5432/jobs", out, sizeof out);
    cr_assert_str_eq(out, "postgres://db.lab:5432/jobs");
    /* an '@' after the path is the path's */
    store_pg_redact("postgres://db.lab:5432/jobs?user=a@b", out, sizeof out);
    cr_assert_str_eq(out, "postgres://db.lab:5432/jobs?user=a@b");
    /* outlen bytes, the terminator included: the password never shows in a cut either */
    store_pg_redact("postgres://u:p@h/db", out, 14);
    cr_assert_str_eq(out, "postgres://u:");
}

Test(store_pg, open_of_an_unreachable_server_fails_with_libpq_s_reason)
{
    /* port 1 on loopback: nothing listens there, the refusal is immediate */
    store *s = (store *)1;
    char err[512] = "";
    int rc = store_open("postgres://ctcsim:pw@127.0.0.1:1/ctcsim", &s, err, sizeof err);
    cr_assert_eq(rc, -1);
    cr_assert_null(s);
    cr_assert(strncmp(err, "cannot open database postgres://ctcsim:***@127.0.0.1:1/ctcsim: ",
                      strlen("cannot open database postgres://ctcsim:***@127.0.0.1:1/ctcsim: ")) ==
                  0,
              "%s", err);
    cr_assert(strstr(err, "Connection refused") != NULL, "%s", err);
    cr_assert(strstr(err, "pw@") == NULL, "the password is in the message: %s", err);
}

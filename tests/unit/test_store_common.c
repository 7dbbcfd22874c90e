/*
 * test_store_common.c - the argument checks and state messages both stores share
 * (server/store_common.c): each bad argument refused with its exact message, each good one
 * passed, and the messages of an update that found its job in the wrong state. The stores' own
 * tests (test_store.c, and the API suite on PostgreSQL) show that they answer through these.
 *
 * Oracles: the messages written out by hand, and the bounds of store.h's contracts.
 */
#include <criterion/criterion.h>
#include <string.h>

#include "store_common.h"

Test(store_common, a_job_needs_its_name_controller_spec_a_body_and_no_negative_nv)
{
    char err[256] = "";
    cr_assert_eq(store_check_job("a", "pd", "{}", 1, 0, err, sizeof err), 0);
    cr_assert_eq(store_check_job(NULL, "pd", "{}", 1, 1, err, sizeof err), -1);
    cr_assert_str_eq(err, "cannot store a job without a name");
    cr_assert_eq(store_check_job("a", NULL, "{}", 1, 1, err, sizeof err), -1);
    cr_assert_str_eq(err, "cannot store a job without a controller");
    cr_assert_eq(store_check_job("a", "pd", NULL, 1, 1, err, sizeof err), -1);
    cr_assert_str_eq(err, "cannot store a job without a spec");
    cr_assert_eq(store_check_job("a", "pd", "{}", 0, 1, err, sizeof err), -1);
    cr_assert_str_eq(err, "cannot store a job of 0 bodies and 1 coordinates");
    cr_assert_eq(store_check_job("a", "pd", "{}", 2, -1, err, sizeof err), -1);
    cr_assert_str_eq(err, "cannot store a job of 2 bodies and -1 coordinates");
    /* no message buffer: still refused */
    cr_assert_eq(store_check_job(NULL, "pd", "{}", 1, 1, NULL, 0), -1);
}

Test(store_common, a_finish_needs_a_final_status_and_a_result_with_times)
{
    char err[256] = "";
    double t[2] = {0, 1};
    ctc_sim_result r = {0};
    for (int st = STORE_DONE; st < STORE_NSTATUS; st++)
        cr_assert_eq(store_check_finish(3, (store_status)st, NULL, err, sizeof err), 0);
    cr_assert_eq(store_check_finish(3, STORE_RUNNING, NULL, err, sizeof err), -1);
    cr_assert_str_eq(err, "cannot finish job 3 as running: the status must be done, failed, "
                          "diverged or cancelled");
    r.nsamples = -1;
    cr_assert_eq(store_check_finish(3, STORE_DONE, &r, err, sizeof err), -1);
    cr_assert_str_eq(err, "cannot finish job 3: the result has -1 samples");
    r.nsamples = 2;
    cr_assert_eq(store_check_finish(3, STORE_DONE, &r, err, sizeof err), -1);
    cr_assert_str_eq(err, "cannot finish job 3: the result has samples but no times");
    r.t = t;
    cr_assert_eq(store_check_finish(3, STORE_DONE, &r, err, sizeof err), 0);
}

Test(store_common, lists_take_1_to_1000_rows_a_cursor_and_a_status)
{
    char err[256] = "";
    cr_assert_eq(store_check_list(0, -1, 1, err, sizeof err), 0);
    cr_assert_eq(store_check_list(7, STORE_CANCELLED, STORE_MAX_LIST, err, sizeof err), 0);
    cr_assert_eq(store_check_list(0, -1, 0, err, sizeof err), -1);
    cr_assert_str_eq(err, "limit must be between 1 and 1000 (got 0)");
    cr_assert_eq(store_check_limit(1001, err, sizeof err), -1);
    cr_assert_str_eq(err, "limit must be between 1 and 1000 (got 1001)");
    cr_assert_eq(store_check_list(-2, -1, 10, err, sizeof err), -1);
    cr_assert_str_eq(err, "before must be 0 or a job id (got -2)");
    cr_assert_eq(store_check_list(0, STORE_NSTATUS, 10, err, sizeof err), -1);
    cr_assert_str_eq(err, "unknown job status 6");
    cr_assert_eq(store_check_list(0, -2, 10, err, sizeof err), -1);
    cr_assert_str_eq(err, "unknown job status -2");
}

Test(store_common, a_family_needs_name_spec_axes_and_no_negative_count)
{
    char err[256] = "";
    cr_assert_eq(store_check_family("f", "{}", "[]", 0, err, sizeof err), 0);
    const char *msg = "cannot store a family without a name, a spec and its axes";
    cr_assert_eq(store_check_family(NULL, "{}", "[]", 1, err, sizeof err), -1);
    cr_assert_str_eq(err, msg);
    cr_assert_eq(store_check_family("f", "{}", NULL, 1, err, sizeof err), -1);
    cr_assert_str_eq(err, msg);
    cr_assert_eq(store_check_family("f", "{}", "[]", -1, err, sizeof err), -1);
    cr_assert_str_eq(err, msg);
}

Test(store_common, an_unchanged_update_says_why_from_the_status_read_after_it)
{
    char err[256] = "";
    store_not_running_err(4, "requeue", 1, STORE_QUEUED, err, sizeof err);
    cr_assert_str_eq(err, "cannot requeue job 4: no such job");
    store_not_running_err(4, "record progress of", 0, STORE_RUNNING, err, sizeof err);
    cr_assert_str_eq(err, "cannot record progress of job 4: another worker holds it");
    store_not_running_err(4, "requeue", 0, STORE_DONE, err, sizeof err);
    cr_assert_str_eq(err, "cannot requeue job 4: it is done, not running");
    store_not_finishable_err(4, 1, STORE_QUEUED, err, sizeof err);
    cr_assert_str_eq(err, "cannot finish job 4: no such job");
    store_not_finishable_err(4, 0, STORE_RUNNING, err, sizeof err);
    cr_assert_str_eq(err, "cannot finish job 4: another worker holds it");
    store_not_finishable_err(4, 0, STORE_CANCELLED, err, sizeof err);
    cr_assert_str_eq(err, "cannot finish job 4: it is already cancelled");
    /* a failed read: its message stands */
    strcpy(err, "job 4: reading its status: disk I/O error");
    store_not_running_err(4, "requeue", -1, STORE_QUEUED, err, sizeof err);
    cr_assert_str_eq(err, "job 4: reading its status: disk I/O error");
    store_not_finishable_err(4, -1, STORE_QUEUED, err, sizeof err);
    cr_assert_str_eq(err, "job 4: reading its status: disk I/O error");
}

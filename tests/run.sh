#!/bin/sh
# Runs each Criterion test binary given as an argument, each under a time limit, and prints one
# line per binary and a closing line with the totals over all of them:
#   "N passed, N failed"                  every listed test ran
#   "N passed, N failed, N not run"       a binary was stopped or died before all its tests ran
# A test counts as run when Criterion reported it passing, failing or crashing; the tests a binary
# lists (--list) and never reported are "not run", not failures. A binary whose output holds a
# sanitizer's report (ASan or LSan "ERROR:", UBSan "runtime error:") counts one failure more,
# since Criterion's workers report them at exit and Criterion still counts the test passed.
# Exits non-zero if any test failed, crashed or did not run, or a sanitizer reported.
#
# From the environment:
#   TEST_TIME_LIMIT  seconds one binary may take before it is stopped (default 600; the slowest,
#                    test_gdca_parallel, takes about 10 s under the sanitizers)
#   TEST_JOBS        Criterion's --jobs (default: Criterion's, the number of cores)
# (Criterion 2.4.1's own --timeout never stops a test, so the limit is the binary's.)
set -u
limit=${TEST_TIME_LIMIT:-600}
jobs=${TEST_JOBS:+--jobs $TEST_JOBS}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT INT TERM

passed=0
failed=0
not_run=0
status=0
for bin in "$@"; do
    name=$(basename "$bin")
    # the tests the binary holds: one "├── name" or "└── name" line each
    total=$("$bin" --list 2>/dev/null | grep -c -E '(├|└)── ')
    start=$(date +%s)
    # --verbose streams one [PASS]/[FAIL] line per finished test, so a binary stopped half way
    # still says which of its tests ran
    # shellcheck disable=SC2086
    timeout -k 10 "$limit" "$bin" --short-filename --verbose $jobs \
        >"$tmp/out" 2>&1
    rc=$?
    secs=$(($(date +%s) - start))
    grep -E '\[FAIL\]|CRASH|Assertion|runtime error|ERROR|WARN' "$tmp/out" |
        grep -v -E '^\[====\] Synthesis' || true
    line=$(grep 'Synthesis:' "$tmp/out" | tail -n 1)
    p=$(grep -c '^\[PASS\] ' "$tmp/out")
    f=$(grep -c '^\[FAIL\] ' "$tmp/out")
    if [ -n "$line" ]; then
        p=$(printf '%s\n' "$line" | sed -n 's/.*Passing: \([0-9]*\).*/\1/p')
        f=$(printf '%s\n' "$line" | sed -n 's/.*Failing: \([0-9]*\).*/\1/p')
        c=$(printf '%s\n' "$line" | sed -n 's/.*Crashing: \([0-9]*\).*/\1/p')
        f=$((f + c))
    fi
    missing=$((total - p - f))
    [ "$missing" -ge 0 ] || missing=0
    if [ "$rc" -eq 124 ] || [ "$rc" -eq 137 ]; then
        echo "$name: stopped after $limit s (TEST_TIME_LIMIT): $((p + f)) of its $total tests" \
            "reported, $missing not run"
        # the tests it had started and not finished
        awk '/^\[RUN \] /{run[$3]=1} /^\[(PASS|FAIL)\] /{sub(":$", "", $2); done[$2]=1}
             END{for (t in run) if (!(t in done)) print "    unfinished: " t}' "$tmp/out"
        echo "    its last lines:"
        grep -v -E '^\[(RUN |PASS)\] ' "$tmp/out" | tail -n 10 | sed 's/^/        /'
    elif [ -z "$line" ]; then
        echo "$name: exited with $rc before its summary: $missing of its $total tests not run;" \
            "its last lines:"
        tail -n 20 "$tmp/out" | sed 's/^/    /'
    else
        printf '%-44s %s (%s s)\n' "$name" "$(echo "$line" | sed 's/.*Synthesis: //; s/ *$//')" \
            "$secs"
    fi
    if grep -q -E '^==[0-9]+==ERROR: (Address|Leak)Sanitizer|runtime error:' "$tmp/out"; then
        echo "$name: a sanitizer reported an error (its report is above)"
        f=$((f + 1))
    fi
    passed=$((passed + p))
    failed=$((failed + f))
    not_run=$((not_run + missing))
    [ "$rc" -eq 0 ] || status=1
done
if [ "$not_run" -gt 0 ]; then
    echo "$passed passed, $failed failed, $not_run not run"
    status=1
else
    echo "$passed passed, $failed failed"
fi
[ "$failed" -eq 0 ] || status=1
exit $status

#!/bin/sh
# Runs a folder's Node test files (node:test) one after the other and counts their results:
#   sh tests/node_suite.sh LABEL TIMEOUT DIR [FILE ...]
# LABEL prefixes the closing line "LABEL: N passed, N failed"; TIMEOUT (s) bounds each file, so a
# stuck file cannot hang the suite; FILEs (paths, or bare names in DIR) default to DIR/*.test.mjs.
# Prints one line per file (passed, failed, and skipped when any: a skipped test is not counted
# as passed) with each skipped test's reason and the failing tests' diagnostics, then the totals;
# exits non-zero on failure.
# Used by tests/api/run.sh and tests/web/run.sh after their own precondition checks.
set -u
label=$1 seconds=$2 dir=$3
shift 3

# TAP on standard output: the default of Node 18 when a test file runs directly; Node >= 19.9
# needs --test-reporter=tap (it would print the spec reporter to a terminal)
reporter=""
if node --test-reporter=tap -e "" >/dev/null 2>&1; then reporter="--test-reporter=tap"; fi
limit=""
if command -v timeout >/dev/null 2>&1; then limit="timeout -k 10 $seconds"; fi

files=""
for f in "$@"; do
    [ -f "$f" ] || f="$dir/$f" # a bare name: one of the folder's
    files="$files $f"
done
[ -n "$files" ] || files=$(ls "$dir"/*.test.mjs)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT INT TERM
passed=0
failed=0
skipped=0
status=0
for file in $files; do
    start=$(date +%s)
    # shellcheck disable=SC2086
    $limit node $reporter "$file" >"$tmp/out" 2>&1
    rc=$?
    secs=$(($(date +%s) - start))
    # top-level tests only: their result lines start in column 0
    # a skipped test ("ok N - name # SKIP why") counts as skipped, not as passed
    s=$(grep -c '^ok .*# SKIP' "$tmp/out")
    p=$(($(grep -c '^ok ' "$tmp/out") - s))
    f=$(grep -c '^not ok ' "$tmp/out")
    note=""
    [ "$s" -gt 0 ] && note=", $s skipped"
    printf '%-28s %s passed, %s failed%s (%s s)\n' "$(basename "$file")" "$p" "$f" "$note" "$secs"
    [ "$s" -gt 0 ] && grep '^ok .*# SKIP' "$tmp/out" | sed 's/^/    /'
    if [ "$f" -gt 0 ]; then
        # each failing test with its YAML block ("  ---" ... "  ..."), the first 10 of them
        awk '/^not ok /{n++; on = n <= 10} on{print "    " $0} on && /^  \.\.\.$/{on=0}
             END{if (n > 10) print "    ... and " n - 10 " more failing tests"}' "$tmp/out"
    fi
    if [ "$rc" -ne 0 ] && [ "$f" -eq 0 ]; then
        echo "    $(basename "$file") exited with $rc without a failing test; its last lines:"
        tail -n 25 "$tmp/out" | sed 's/^/    /'
        f=1
    fi
    passed=$((passed + p))
    failed=$((failed + f))
    skipped=$((skipped + s))
    [ "$rc" -eq 0 ] || status=1
done
if [ "$skipped" -gt 0 ]; then
    echo "$label: $passed passed, $failed failed, $skipped skipped"
else
    echo "$label: $passed passed, $failed failed"
fi
[ "$failed" -eq 0 ] || status=1
exit $status

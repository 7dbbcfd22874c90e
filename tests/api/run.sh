#!/bin/sh
# Black-box tests of the HTTP/JSON service: each tests/api/*.test.mjs file, one after the other
# (each starts its own servers, so files must not fight over CPU), on Node's built-in test runner
# with no npm packages. The server and the command line come from the environment:
#   CTCSIM_SERVER (default build/ctcsim-server), CTCSIM (default build/ctcsim)
# Prints one line per file, the failing tests with their diagnostics, and a closing
# "api: N passed, N failed"; exits non-zero on failure. Arguments, if any, name the files to run.
set -u
cd "$(dirname "$0")/../.." || exit 1
CTCSIM_SERVER=${CTCSIM_SERVER:-build/ctcsim-server}
CTCSIM=${CTCSIM:-build/ctcsim}
export CTCSIM_SERVER CTCSIM

if ! command -v node >/dev/null 2>&1; then
    echo "api: node not found (Node.js >= 18 runs these tests; make deps installs it)"
    echo "api: 0 passed, 1 failed"
    exit 1
fi
for bin in "$CTCSIM_SERVER" "$CTCSIM"; do
    if [ ! -x "$bin" ]; then
        echo "api: $bin is not an executable (build it first)"
        echo "api: 0 passed, 1 failed"
        exit 1
    fi
done

# TAP on standard output: the default of Node 18 when a test file runs directly; Node >= 19.9
# needs --test-reporter=tap (it would print the spec reporter to a terminal)
reporter=""
if node --test-reporter=tap -e "" >/dev/null 2>&1; then reporter="--test-reporter=tap"; fi
# a stuck file must not hang the suite
limit=""
if command -v timeout >/dev/null 2>&1; then limit="timeout -k 10 300"; fi

files=""
for f in "$@"; do
    [ -f "$f" ] || f="tests/api/$f" # a bare name: one of ours
    files="$files $f"
done
[ -n "$files" ] || files=$(ls tests/api/*.test.mjs)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT INT TERM
passed=0
failed=0
status=0
for file in $files; do
    start=$(date +%s)
    # shellcheck disable=SC2086
    $limit node $reporter "$file" >"$tmp/out" 2>&1
    rc=$?
    secs=$(($(date +%s) - start))
    # top-level tests only: their result lines start in column 0
    p=$(grep -c '^ok ' "$tmp/out")
    f=$(grep -c '^not ok ' "$tmp/out")
    s=$(grep -c '^ok .*# SKIP' "$tmp/out")
    note=""
    [ "$s" -gt 0 ] && note=", $s skipped"
    printf '%-28s %s passed, %s failed%s (%s s)\n' "$(basename "$file")" "$p" "$f" "$note" "$secs"
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
    [ "$rc" -eq 0 ] || status=1
done
echo "api: $passed passed, $failed failed"
[ "$failed" -eq 0 ] || status=1
exit $status

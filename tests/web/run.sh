#!/bin/sh
# Browser tests of the page: each tests/web/*.test.mjs file, one after the other (each starts its
# own server and headless Chromium), on Node's built-in test runner with playwright-core (from
# `npm ci` in tests/web). From the environment:
#   CTCSIM_SERVER  the server binary (default build/ctcsim-server)
#   WEB_ROOT       the assembled page folder served with --web, vendor/uPlot.* included
#                  (default build/web, what `make web` builds)
#   API_DIR        the folder served with --api (default api)
#   CHROMIUM       the browser (default /usr/bin/chromium, Debian's chromium package)
# Screenshots of every view go to tests/web/artifacts/. Prints one line per file, the failing
# tests with their diagnostics, and a closing "web: N passed, N failed"; exits non-zero on
# failure. Arguments, if any, name the files to run.
set -u
cd "$(dirname "$0")/../.." || exit 1
CTCSIM_SERVER=${CTCSIM_SERVER:-build/ctcsim-server}
WEB_ROOT=${WEB_ROOT:-build/web}
API_DIR=${API_DIR:-api}
CHROMIUM=${CHROMIUM:-/usr/bin/chromium}
export CTCSIM_SERVER WEB_ROOT API_DIR CHROMIUM

fail() {
    echo "web: $1"
    echo "web: 0 passed, 1 failed"
    exit 1
}

command -v node >/dev/null 2>&1 || fail "node not found (Node.js >= 18 runs these tests)"
# playwright-core 1.60 (pinned) runs on Node 18, Debian bookworm's nodejs
major=$(node -p 'process.versions.node.split(".")[0]')
[ "$major" -ge 18 ] || fail "node $(node --version) is too old: the tests need Node.js >= 18"
[ -x "$CTCSIM_SERVER" ] || fail "$CTCSIM_SERVER is not an executable (build it first)"
[ -f "$WEB_ROOT/index.html" ] || fail "$WEB_ROOT/index.html not found (make web assembles the page)"
[ -f "$WEB_ROOT/vendor/uPlot.esm.js" ] || fail "$WEB_ROOT/vendor/uPlot.esm.js not found (make web copies it)"
[ -d tests/web/node_modules/playwright-core ] ||
    fail "tests/web/node_modules/playwright-core not found (run: cd tests/web && npm ci --no-audit --no-fund)"
[ -x "$CHROMIUM" ] || fail "$CHROMIUM not found (Debian: apt-get install chromium)"

# TAP on standard output: Node >= 19.9 needs --test-reporter=tap (it would print the spec
# reporter to a terminal)
reporter=""
if node --test-reporter=tap -e "" >/dev/null 2>&1; then reporter="--test-reporter=tap"; fi
# a stuck file must not hang the suite
limit=""
if command -v timeout >/dev/null 2>&1; then limit="timeout -k 10 180"; fi

files=""
for f in "$@"; do
    [ -f "$f" ] || f="tests/web/$f" # a bare name: one of ours
    files="$files $f"
done
[ -n "$files" ] || files=$(ls tests/web/*.test.mjs)
mkdir -p tests/web/artifacts
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
echo "web: $passed passed, $failed failed"
[ "$failed" -eq 0 ] || status=1
exit $status

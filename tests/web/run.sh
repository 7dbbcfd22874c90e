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

mkdir -p tests/web/artifacts
exec sh tests/node_suite.sh web 180 tests/web "$@"

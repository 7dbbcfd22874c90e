#!/bin/sh
# Black-box tests of the HTTP/JSON service: each tests/api/*.test.mjs file, one after the other
# (each starts its own servers, so files must not fight over CPU), on Node's built-in test runner
# with no npm packages. The server and the command line come from the environment:
#   CTCSIM_SERVER (default build/ctcsim-server), CTCSIM (default build/ctcsim)
# Prints one line per file, the failing tests with their diagnostics, and a closing
# "api: N passed, N failed"; exits non-zero on failure. Arguments, if any, name the files to run.
#
# The suite runs twice: on SQLite ("api:"), then on PostgreSQL ("api-pg:"), against a throw-away
# PostgreSQL that tests/pg/start.sh starts on loopback (a temporary folder, a random port) and
# tests/pg/stop.sh stops at exit, whatever happened; there each server is a cluster of one API
# process and two worker processes (lib.mjs). CTCSIM_API_PG=0 runs SQLite only; without
# PostgreSQL's server (Debian's postgresql, which make deps installs) the second run fails, saying
# so.
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

sh tests/node_suite.sh api 300 tests/api "$@"
status=$?
[ "${CTCSIM_API_PG:-1}" = 0 ] && exit $status

pgdir=$(mktemp -d /tmp/ctcsim-pg.XXXXXX) || exit 1
chmod 755 "$pgdir" # the postgres user, when run as root, must reach its folder inside
trap 'sh tests/pg/stop.sh "$pgdir/pg"; rm -rf "$pgdir"' EXIT
trap 'exit 130' INT TERM
if ! url=$(sh tests/pg/start.sh "$pgdir/pg"); then
    echo "api-pg: cannot start PostgreSQL (above); CTCSIM_API_PG=0 runs the SQLite suite only"
    echo "api-pg: 0 passed, 1 failed"
    exit 1
fi
CTCSIM_TEST_PG=$url CTCSIM_TEST_PG_DIR=$pgdir/pg sh tests/node_suite.sh api-pg 300 tests/api "$@" ||
    status=1
exit $status

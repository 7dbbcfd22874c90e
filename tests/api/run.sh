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

exec sh tests/node_suite.sh api 300 tests/api "$@"

#!/bin/sh
# soak.sh - ctcsim-server under concurrent load, SIGKILL and a locked database at once; reports
# jobs lost (must be 0), p50/p99 latency of health and POST, and peak RSS (bench/soak.mjs says
# what it does and reads; bench/README.md, "Soak").
#
# usage: bench/soak.sh [SERVER]   (default build/ctcsim-server)
# Settings from the environment, with their defaults: SOAK_SECONDS=120 of load, SOAK_KILL_EVERY=20
# s between SIGKILLs, SOAK_LOCK_EVERY=20 s between database locks of SOAK_LOCK_SECONDS=8 s,
# SOAK_CLIENTS=4 submitters, SOAK_READERS=4 readers, SOAK_WORKERS=2 (the server's --workers),
# SOAK_MAX_PENDING=24 unfinished jobs at most, SOAK_CANCEL_SHARE=0.25 of the jobs cancelled or
# deleted, SOAK_DRAIN=120 s to finish them after the load,
# SOAK_REQUEST_TIMEOUT=30 s per request, SOAK_JSON=FILE (the figures as JSON), SOAK_KEEP=1 (keep
# the temporary directory: database and server logs).
# Exit status: 0 nothing lost, 1 jobs lost or the server crashed, 2 setup error.
set -eu
for tool in node sqlite3; do
    command -v "$tool" >/dev/null 2>&1 || { echo "soak.sh: needs $tool" >&2; exit 2; }
done
exec node "$(dirname "$0")/soak.mjs" "${1:-build/ctcsim-server}"

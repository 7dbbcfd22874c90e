#!/bin/sh
# Stops the PostgreSQL that tests/pg/start.sh DIR started (fast shutdown) and removes DIR:
#   sh tests/pg/stop.sh DIR
# Does nothing for a DIR with no cluster in it.
set -u
dir=${1:?usage: stop.sh DIR}
bin=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n 1)
as=""
[ "$(id -u)" = 0 ] && as="runuser -u postgres --"
if [ -n "$bin" ] && [ -f "$dir/data/postmaster.pid" ]; then
    $as "$bin/pg_ctl" -D "$dir/data" -m fast -w -t 30 stop >/dev/null 2>&1 || true
fi
rm -rf "$dir"

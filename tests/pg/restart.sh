#!/bin/sh
# Restarts the PostgreSQL that tests/pg/start.sh DIR started, on the same port (fast shutdown:
# every connection is cut, as when the database server restarts under its clients):
#   sh tests/pg/restart.sh DIR
set -eu
dir=${1:?usage: restart.sh DIR}
bin=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n 1)
as=""
[ "$(id -u)" = 0 ] && as="runuser -u postgres --"
$as "$bin/pg_ctl" -D "$dir/data" -l "$dir/log" -m fast -w -t 30 restart >/dev/null

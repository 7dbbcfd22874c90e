#!/bin/sh
# Starts a throw-away PostgreSQL from Debian's packages for the tests:
#   sh tests/pg/start.sh DIR
# makes DIR (a new, empty folder) its home: the cluster in DIR/data, its socket and log in DIR,
# listening on 127.0.0.1 only, on a free port picked at random. Prints one line, the URL of its
# database "ctcsim" (postgres://ctcsim@127.0.0.1:PORT/ctcsim), and writes it to DIR/url; exits
# non-zero with the reason when PostgreSQL is missing or does not start. Stop it with
# tests/pg/stop.sh DIR. initdb refuses to run as root, so as root the server runs as the
# `postgres` system user (the postgresql package makes it), owning DIR; otherwise as the caller.
# Trust authentication on loopback: a test cluster, never a real one.
set -eu
dir=${1:?usage: start.sh DIR}
bin=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n 1)
if [ -z "$bin" ] || [ ! -x "$bin/initdb" ]; then
    echo "pg: PostgreSQL's server is not installed (apt-get install postgresql)" >&2
    exit 1
fi
mkdir -p "$dir"
as=""
if [ "$(id -u)" = 0 ]; then
    if ! id postgres >/dev/null 2>&1; then
        echo "pg: running as root and there is no postgres user to run PostgreSQL as" >&2
        exit 1
    fi
    chown postgres "$dir"
    if ! runuser -u postgres -- test -w "$dir"; then
        echo "pg: the postgres user cannot reach $dir (a folder above it is private to root)" >&2
        exit 1
    fi
    as="runuser -u postgres --"
fi
$as "$bin/initdb" -D "$dir/data" -U ctcsim --auth=trust --no-sync -E UTF8 >"$dir/initdb.log" 2>&1 || {
    echo "pg: initdb failed:" >&2
    cat "$dir/initdb.log" >&2
    exit 1
}
# a port picked at random among the unprivileged ones, tried again when taken
for attempt in 1 2 3 4 5 6 7 8; do
    port=$((20000 + $(od -An -N2 -tu2 /dev/urandom) % 40000))
    if $as "$bin/pg_ctl" -D "$dir/data" -l "$dir/log" -w -t 30 \
        -o "-c listen_addresses=127.0.0.1 -p $port -k $dir -c fsync=off -c full_page_writes=off -c synchronous_commit=off -c max_connections=200" \
        start >/dev/null 2>&1; then
        url="postgres://ctcsim@127.0.0.1:$port/ctcsim"
        $as "$bin/createdb" -h 127.0.0.1 -p "$port" -U ctcsim ctcsim
        echo "$port" >"$dir/port"
        echo "$url" >"$dir/url"
        echo "$url"
        exit 0
    fi
    grep -qi "in use" "$dir/log" 2>/dev/null || break
done
echo "pg: PostgreSQL did not start:" >&2
tail -n 20 "$dir/log" >&2 2>/dev/null || true
exit 1

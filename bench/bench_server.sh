#!/bin/sh
# bench_server.sh - the service under load: wrk against GET /api/health and GET /api/jobs/{id}
# (20 s, 64 connections: throughput, p99 latency, errors), then the submit-to-done latency of the
# paper's triple pendulum job (POST with ?wait) and jobs per second with 1 and N workers.
#
# usage: bench/bench_server.sh SERVER_BINARY   (make bench passes build/bench-o3/ctcsim-server)
# Prints markdown tables. Needs wrk and curl (make deps installs them for make bench).
set -eu
SERVER=${1:-build/bench-o3/ctcsim-server}
DURATION=${BENCH_DURATION:-20}
CONNECTIONS=64
NCPU=$(getconf _NPROCESSORS_ONLN)
tmp=$(mktemp -d)
pid=
cleanup() {
    [ -n "$pid" ] && kill "$pid" 2>/dev/null && wait "$pid" 2>/dev/null
    rm -rf "$tmp"
}
trap cleanup EXIT INT TERM

free_port() {
    # the first port from 18080 up that nothing listens on
    p=18080
    while curl -s -o /dev/null "http://127.0.0.1:$p/" 2>/dev/null; do p=$((p + 1)); done
    echo "$p"
}

start() { # start WORKERS: a fresh server with a fresh database
    port=$(free_port)
    rm -f "$tmp"/db*
    "$SERVER" --port "$port" --db "$tmp/db" --workers "$1" --web build/web --api api \
        2>"$tmp/server.log" &
    pid=$!
    base="http://127.0.0.1:$port"
    i=0
    until curl -sf -o /dev/null "$base/api/health"; do
        i=$((i + 1))
        [ "$i" -lt 100 ] || { cat "$tmp/server.log"; exit 1; }
        sleep 0.1
    done
}

stop() {
    kill "$pid" && wait "$pid" 2>/dev/null || true
    pid=
}

post() { # post BODY [QUERY]: prints the answer
    curl -sf -X POST -H 'Content-Type: application/json' --data "$1" "$base/api/jobs$2"
}

ms_now() { date +%s%N | awk '{printf "%.3f", $1 / 1e6}'; }

# wrk's summary line "Requests/sec:" and its 99% latency, normalised to ms
wrk_row() { # wrk_row LABEL PATH
    wrk -t2 -c"$CONNECTIONS" -d"${DURATION}s" --latency "$base$2" >"$tmp/wrk.txt" 2>&1
    rps=$(awk '/Requests\/sec/ {print $2}' "$tmp/wrk.txt")
    p99=$(awk '$1 == "99%" {v = $2; u = v; sub(/[0-9.]+/, "", u); sub(/[a-z]+/, "", v);
        if (u == "us") v /= 1000; else if (u == "s") v *= 1000; printf "%.2f", v}' "$tmp/wrk.txt")
    p50=$(awk '$1 == "50%" {v = $2; u = v; sub(/[0-9.]+/, "", u); sub(/[a-z]+/, "", v);
        if (u == "us") v /= 1000; else if (u == "s") v *= 1000; printf "%.2f", v}' "$tmp/wrk.txt")
    errors=$(awk '/Non-2xx|Socket errors/ {print}' "$tmp/wrk.txt" | tr '\n' ' ')
    printf '| %s | %s | %s | %s | %s |\n' "$1" "$rps" "$p50" "$p99" "${errors:-none}"
}

echo "## The service under load (bench_server.sh)"
echo
echo "wrk, 2 threads, $CONNECTIONS connections, $DURATION s per row; server with $NCPU workers on"
echo "the same machine ($NCPU cores), so wrk and the server share the CPUs."
echo
echo "| request | requests/s | p50 (ms) | p99 (ms) | errors |"
echo "| --- | ---: | ---: | ---: | --- |"
start "$NCPU"
id=$(post '{"preset": "triple_pendulum_pid"}' '?wait=30' | sed -n 's/.*"id":\([0-9]*\).*/\1/p' | head -n 1)
wrk_row "GET /api/health" "/api/health"
wrk_row "GET /api/jobs/{id} (a finished triple pendulum)" "/api/jobs/$id"
stop

echo
echo "Submit-to-done: POST {\"preset\": \"triple_pendulum_pid\"} with ?wait=30, one at a time,"
echo "median of 21 (the paper's 5 s run, 501 samples, stored with its series)."
echo
echo "| workers | median submit-to-done (ms) | jobs/s (64 jobs, 8 clients) |"
echo "| ---: | ---: | ---: |"
for workers in 1 "$NCPU"; do
    start "$workers"
    : >"$tmp/lat"
    for i in $(seq 21); do
        t0=$(ms_now)
        post '{"preset": "triple_pendulum_pid"}' '?wait=30' >/dev/null
        t1=$(ms_now)
        echo "$t0 $t1" | awk '{print $2 - $1}' >>"$tmp/lat"
    done
    median=$(sort -n "$tmp/lat" | awk '{a[NR] = $1} END {print a[int((NR + 1) / 2)]}')
    # throughput: 8 clients submit 8 jobs each, each waiting for its job before the next
    t0=$(ms_now)
    clients=
    for c in $(seq 8); do
        (for i in $(seq 8); do post '{"preset": "triple_pendulum_pid"}' '?wait=60' >/dev/null; done) &
        clients="$clients $!"
    done
    for c in $clients; do wait "$c"; done
    t1=$(ms_now)
    jps=$(echo "$t0 $t1" | awk '{printf "%.1f", 64 / (($2 - $1) / 1000)}')
    printf '| %s | %s | %s |\n' "$workers" "$median" "$jps"
    stop
done

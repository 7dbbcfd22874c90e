#!/usr/bin/env bash
# Runs the README's commands, literally, on a pristine Debian bookworm, as a new user would: a
# fresh clone of this repository's HEAD (no ../shared beside it), the README's "install first"
# line, then `make run` (started, GET /api/health, stopped) and `make test`. Prints each phase's
# time and what its package installs cost (packages, download and disk MB, from apt's own
# summary lines), and exits non-zero if a phase failed. `make test-container` runs it.
#
# The machine: Docker's debian:bookworm (the Dockerfile's base) where a Docker daemon answers;
# otherwise, as root, a minbase debootstrap of bookworm (the same package set as that image),
# made once into build/container/bookworm-minbase.tar and unpacked afresh for every run into
# build/container/root, entered with chroot in a private mount namespace (unshare), so that its
# /proc, /sys and /dev mounts cannot leak to the host and vanish with it on every exit path; they
# are also unmounted explicitly. The unpacked root is kept after the run for inspection and
# removed at the start of the next one. The container shares the host's network: the service
# is started on a free port. It starts with an empty environment but for the proxy variables,
# and with the host's local CA certificates (/usr/local/share/ca-certificates/*.crt) where the
# image keeps them, so that, behind a TLS-inspecting proxy, it is a machine whose system store
# holds the proxy's CA (they enter the store when the install-first line installs
# ca-certificates): whatever else npm needs to trust the registry must come from the Makefile.
#
# From the environment:
#   CONTAINER_MIRROR   Debian mirror for debootstrap (default http://deb.debian.org/debian)
#   CONTAINER_REBASE=1 debootstrap again instead of reusing build/container/bookworm-minbase.tar
#   CONTAINER_RUNTIME  docker or chroot, instead of choosing by whether a daemon answers
# Committed changes only: it clones HEAD, and says so when the work tree has other changes.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$PWD
work=$repo/build/container
mirror=${CONTAINER_MIRROR:-http://deb.debian.org/debian}
mkdir -p "$work"

now() { date +%s; }
t_all=$(now)
commit=$(git rev-parse HEAD)
echo "== test-container: $(git log -1 --format='%h %s' HEAD)"
if [ -n "$(git status --porcelain --untracked-files=no)" ]; then
    echo "   (the work tree has uncommitted changes; only the commit is tested)"
fi

# the README's line to run first on a stock image: the first line of its "Two commands" section
# that starts with apt-get
install_first=$(git show HEAD:README.md |
    awk '/^## /{sec=$0} sec=="## Two commands" && /^apt-get / && !found {print; found=1}' |
    sed 's/ *#.*$//') # awk reads to the end: an early exit would stop git show with SIGPIPE
if [ -z "$install_first" ]; then
    echo "README.md at HEAD has no apt-get line in its \"Two commands\" section" >&2
    exit 1
fi
echo "   install first: $install_first"

git bundle create "$work/ctcsim.bundle" HEAD >/dev/null 2>&1
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])' 2>/dev/null ||
    echo 18080)

# ---- what runs inside: bash, as root, in / of the pristine system
steps=$work/steps.sh
cat >"$steps" <<EOF
#!/bin/bash
set -uo pipefail
export HOME=/root LANG=C.UTF-8 PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
cd /root
fail=0
# apt's summary lines in a phase's log: packages, download, disk
installed() {
    awk '/newly installed/{n += \$3}
         /^Need to get/{v = \$4; u = \$5; if (u == "kB") v /= 1000; if (u == "GB") v *= 1000; d += v}
         /^After this operation/{v = \$4; u = \$5; if (u == "kB") v /= 1000; if (u == "GB") v *= 1000; s += v}
         END{printf "%d packages, %.0f MB download, %.0f MB disk", n, d, s}' "\$1"
}
phase() {  # phase NAME COMMAND: runs it, logs to /root/NAME.log, prints the time and result
    local name=\$1 start rc; shift
    start=\$(date +%s)
    echo "== [\$name] \$*"
    bash -c "\$*" >"/root/\$name.log" 2>&1
    rc=\$?
    tail -n 15 "/root/\$name.log" | sed 's/^/    /'
    echo "== [\$name] exit \$rc, \$((\$(date +%s) - start)) s; installed \$(installed "/root/\$name.log")"
    return \$rc
}
phase install-first '$install_first' || exit 1
phase clone 'git -c advice.detachedHead=false clone -q /ctcsim.bundle ctcsim && git -C ctcsim checkout -q $commit' ||
    exit 1
cd ctcsim
# make run: in the background, until /api/health answers 200 (bash's /dev/tcp: curl comes with
# make test), then stopped with SIGINT as Ctrl-C would
start=\$(date +%s)
echo "== [make-run] make run RUN_ARGS='--port $port --db /tmp/run.db'"
setsid make run RUN_ARGS='--port $port --db /tmp/run.db' >/root/make-run.log 2>&1 &
pid=\$!
health=""
for _ in \$(seq 1 1800); do
    if ! kill -0 \$pid 2>/dev/null; then break; fi
    if { exec 3<>/dev/tcp/127.0.0.1/$port; } 2>/dev/null; then
        printf 'GET /api/health HTTP/1.0\r\nHost: localhost\r\n\r\n' >&3
        health=\$(cat <&3 | tr -d '\r')
        exec 3<&-
        break
    fi
    sleep 1
done
kill -INT -- -\$pid 2>/dev/null
wait \$pid
rc=\$?
tail -n 8 /root/make-run.log | sed 's/^/    /'
echo "    GET /api/health: \$(printf '%s\n' "\$health" | head -n 1), \$(printf '%s\n' "\$health" | tail -n 1)"
case "\$health" in
    "HTTP/1.1 200"*'"status":"ok"'*|"HTTP/1.0 200"*'"status":"ok"'*) ok=1 ;;
    *) ok=0; fail=1 ;;
esac
echo "== [make-run] \$([ \$ok = 1 ] && echo healthy || echo "NOT healthy"), stopped with exit \$rc," \
    "\$((\$(date +%s) - start)) s; installed \$(installed /root/make-run.log)"
phase make-test 'make test' || fail=1
# the suites' closing lines ("N passed, N failed", "LABEL: N passed, N failed"), both passes
grep -E '^(== |[A-Za-z ]+: )?[0-9]+ passed, [0-9]+ failed|skipped' /root/make-test.log | sed 's/^/    /'
exit \$fail
EOF

# the proxy settings, if any, are the only variables passed in
proxy_vars=()
proxy_env=()
for v in http_proxy https_proxy no_proxy HTTP_PROXY HTTPS_PROXY NO_PROXY; do
    if [ -n "${!v:-}" ]; then
        proxy_vars+=("$v=${!v}")
        proxy_env+=(-e "$v=${!v}")
    fi
done

rc=0
runtime=${CONTAINER_RUNTIME:-}
if [ -z "$runtime" ]; then
    if command -v docker >/dev/null 2>&1 && timeout 10 docker info >/dev/null 2>&1; then
        runtime=docker
    else
        runtime=chroot
    fi
fi
echo "   runtime: $runtime"

if [ "$runtime" = docker ]; then
    t=$(now)
    timeout 600 docker pull -q debian:bookworm
    echo "== [base] docker pull debian:bookworm: $(($(now) - t)) s"
    cas=()
    for c in /usr/local/share/ca-certificates/*.crt; do
        [ -f "$c" ] && cas+=(-v "$c:/usr/local/share/ca-certificates/$(basename "$c"):ro")
    done
    docker run --rm --network host -v "$work/ctcsim.bundle:/ctcsim.bundle:ro" \
        -v "$steps:/steps.sh:ro" "${cas[@]}" "${proxy_env[@]}" debian:bookworm bash /steps.sh ||
        rc=$?
else
    if [ "$(id -u)" != 0 ]; then
        echo "no Docker daemon answers, and debootstrap + chroot needs root" >&2
        exit 1
    fi
    root=$work/root
    # never delete through a mount: a bound /dev would take the host's with it
    if grep -q " $root/" /proc/mounts; then
        echo "something is still mounted under $root; unmount it first:" >&2
        grep " $root/" /proc/mounts >&2
        exit 1
    fi
    t=$(now)
    rm -rf "$root"
    echo "== [base] the previous root removed: $(($(now) - t)) s"
    base=$work/bookworm-minbase.tar
    if [ ! -f "$base" ] || [ "${CONTAINER_REBASE:-}" = 1 ]; then
        command -v debootstrap >/dev/null 2>&1 || {
            echo "needs debootstrap: apt-get install -y debootstrap" >&2
            exit 1
        }
        t=$(now)
        rm -rf "$work/base-root"
        debootstrap --variant=minbase bookworm "$work/base-root" "$mirror" >"$work/debootstrap.log" 2>&1 || {
            tail -n 20 "$work/debootstrap.log" >&2
            exit 1
        }
        tar -C "$work/base-root" -cf "$base.tmp" . && mv "$base.tmp" "$base"
        rm -rf "$work/base-root"
        echo "== [base] debootstrap --variant=minbase bookworm: $(($(now) - t)) s"
    fi
    t=$(now)
    mkdir -p "$root"
    tar -C "$root" -xf "$base"
    cp /etc/resolv.conf "$root/etc/resolv.conf"
    cp "$work/ctcsim.bundle" "$root/ctcsim.bundle"
    cp "$steps" "$root/steps.sh"
    mkdir -p "$root/usr/local/share/ca-certificates"
    for c in /usr/local/share/ca-certificates/*.crt; do
        [ -f "$c" ] && cp "$c" "$root/usr/local/share/ca-certificates/"
    done
    echo "== [base] a pristine root from $(basename "$base"): $(($(now) - t)) s"

    # processes still running in the root when it ends (a server left behind): stopped by id
    stop_leftovers() {
        local p
        for p in /proc/[0-9]*; do
            [ "$(readlink "$p/root" 2>/dev/null)" = "$root" ] && kill -KILL "${p#/proc/}" 2>/dev/null
        done
        true
    }
    trap stop_leftovers EXIT INT TERM
    # mounts private to this namespace: none reaches the host, and all go when it ends
    unshare --mount --propagation private bash -c '
        root=$1
        cleanup() { umount "$root/dev/shm" "$root/dev/pts" "$root/dev" "$root/sys" "$root/proc" 2>/dev/null; true; }
        trap cleanup EXIT INT TERM
        mount -t proc proc "$root/proc"
        mount -t sysfs sys "$root/sys"
        mount --bind /dev "$root/dev"
        mount --bind /dev/pts "$root/dev/pts"
        mount -t tmpfs -o mode=1777 shm "$root/dev/shm"
        shift
        chroot "$root" /usr/bin/env -i "$@" /bin/bash /steps.sh
    ' _ "$root" "${proxy_vars[@]}" || rc=$?
    stop_leftovers
    trap - EXIT INT TERM
    if grep -q " $root/" /proc/mounts; then
        echo "warning: still mounted under $root:" >&2
        grep " $root/" /proc/mounts >&2
    fi
fi
echo "== test-container: $([ $rc = 0 ] && echo PASSED || echo "FAILED (exit $rc)") in $(($(now) - t_all)) s," \
    "commit ${commit:0:7}"
exit $rc

#!/bin/sh
# `make install` and `make uninstall` into a staging folder (DESTDIR), and a program of one's own
# built against the installed library: examples/pendulum.c compiled with
# `pkg-config --cflags --libs ctcsim` (PKG_CONFIG_SYSROOT_DIR puts pkg-config's paths under the
# staging folder), run, and its GDCA and iGDCA results held against the compound pendulum's closed
# form (the program checks them to 1e-12 and says so; this checks its exit and its line). The
# installed ctcsim runs a preset; uninstall leaves no file behind.
# Run from the repository root by `make check`, which passes MAKE (make's command line variables
# reach the sub-make through MAKEFLAGS, so the same build folder is installed without a rebuild),
# CC and EXAMPLE_FLAGS (the build's LDFLAGS: the sanitizer pass links the example with them).
# Prints one line per failure and a closing "install: N passed, N failed".
set -u
MAKE=${MAKE:-make}
CC=${CC:-cc}
EXAMPLE_FLAGS=${EXAMPLE_FLAGS:-}
PREFIX=/usr/local
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
root=$tmp/root
. "$(dirname "$0")/lib.sh"

if timeout -k 5 600 "$MAKE" --no-print-directory install DESTDIR="$root" >"$tmp/install.log" 2>&1; then
    pass
else
    fail "make install DESTDIR=$root: exit $?"
    tail -n 10 "$tmp/install.log" | sed 's/^/    /'
fi
for f in lib/libctcsim.a lib/pkgconfig/ctcsim.pc include/ctcsim/ctc.h include/ctcsim/sim.h \
    bin/ctcsim bin/ctcsim-server share/ctcsim/web/index.html share/ctcsim/web/vendor/uPlot.esm.js \
    share/ctcsim/api/openapi.yaml share/ctcsim/api/job.schema.json; do
    [ -f "$root$PREFIX/$f" ] && pass || fail "make install: no $PREFIX/$f"
done

# every installed header compiles on its own, with only the installed headers in reach
for h in "$root$PREFIX"/include/ctcsim/*.h; do
    printf '#include <ctcsim/%s>\n' "$(basename "$h")" >"$tmp/h.c"
    "$CC" -std=c11 -Wall -Wextra -Werror -I"$root$PREFIX/include" -fsyntax-only "$tmp/h.c" \
        2>"$tmp/h.err" && pass || {
        fail "installed header $(basename "$h") does not compile alone"
        head -n 3 "$tmp/h.err" | sed 's/^/    /'
    }
done

# the example, built with pkg-config against the staged installation
export PKG_CONFIG_PATH="$root$PREFIX/lib/pkgconfig" PKG_CONFIG_SYSROOT_DIR="$root"
flags=$(pkg-config --cflags --libs ctcsim) && pass || fail "pkg-config --cflags --libs ctcsim failed"
case "$flags" in *"-I$root$PREFIX/include"*"-L$root$PREFIX/lib"*"-lctcsim"*) pass ;;
*) fail "pkg-config gives \"$flags\"" ;; esac
[ "$(pkg-config --modversion ctcsim)" = "$(sed -n 's/^#define CTCSIM_VERSION "\(.*\)"/\1/p' server/routes.h)" ] &&
    pass || fail "ctcsim.pc's version is not CTCSIM_VERSION"
# shellcheck disable=SC2086
if "$CC" -std=c11 -Wall -Wextra -Werror examples/pendulum.c $EXAMPLE_FLAGS $flags \
    -o "$tmp/pendulum" 2>"$tmp/cc.err"; then pass; else
    fail "examples/pendulum.c does not build against the installed library"
    head -n 10 "$tmp/cc.err" | sed 's/^/    /'
fi
if [ -x "$tmp/pendulum" ]; then
    timeout -k 5 60 "$tmp/pendulum" >"$tmp/pendulum.out" 2>&1 && pass ||
        fail "examples/pendulum exited $?: $(cat "$tmp/pendulum.out")"
    grep -qx 'both agree with the closed form' "$tmp/pendulum.out" && pass ||
        fail "examples/pendulum: $(cat "$tmp/pendulum.out")"
fi

# the installed command line
"$root$PREFIX/bin/ctcsim" preset triple_pendulum_pd >"$tmp/job.json" &&
    "$root$PREFIX/bin/ctcsim" validate "$tmp/job.json" >/dev/null 2>&1 && pass ||
    fail "the installed ctcsim cannot print and validate a preset"

# uninstall removes every file
timeout -k 5 120 "$MAKE" --no-print-directory uninstall DESTDIR="$root" >"$tmp/uninstall.log" 2>&1 &&
    pass || fail "make uninstall: exit $?"
left=$(find "$root" -type f | sed "s|^$root||")
[ -z "$left" ] && pass || fail "make uninstall left: $left"

finish install

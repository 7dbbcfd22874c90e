#!/bin/sh
# The README's worked example of the command line ("## The command line: a worked example"),
# run literally, so that what the README shows and what the code prints cannot drift apart.
#
# Every ```sh block of that section is run as written (its `make` line left out: the suite runs
# on a build already made) with `sh -e`, in a temporary folder where build/ctcsim is $CTCSIM and
# api/ the repository's, and must exit 0. The first block's output is held against the plain
# block that follows it: each CSV line the README shows must be a line the run printed, the header
# exactly and each row's numbers to 1e-12 absolute (with at least unit scale: their last digits
# depend on whether the processor's copy of the dynamics kernels fuses multiply-adds,
# src/core/clones.h), and the summary line (standard error) must be the run's up to its timing figure
# ("0.0177 s", which is the machine's). The block that shows an invalid job ("$ build/ctcsim run
# bad.json") is run on the worked example's job with the first mass made -1, and must print the
# README's message and exit 2 (invalid job).
# Prints one line per failure and a closing "readme: N passed, N failed"; exits non-zero on failure.
set -u
CTCSIM=${CTCSIM:-build/ctcsim}
README=${README:-README.md}
root=$(pwd)
case "$CTCSIM" in /*) cli=$CTCSIM ;; *) cli=$root/$CTCSIM ;; esac
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
. "$(dirname "$0")/lib.sh"

# the section's fenced blocks: $tmp/blocks/NN.sh (```sh) and $tmp/blocks/NN.txt (``` plain)
mkdir -p "$tmp/blocks" "$tmp/work/build"
awk -v dir="$tmp/blocks" '
    /^## / { inside = ($0 == "## The command line: a worked example"); next }
    !inside { next }
    /^```/ {
        if (file != "") { close(file); file = ""; next }
        n++
        file = sprintf("%s/%02d.%s", dir, n, $0 == "```sh" ? "sh" : "txt")
        printf "" > file
        next
    }
    file != "" { print > file }
' "$README"
nblocks=$(ls "$tmp/blocks" | wc -l)
if [ "$nblocks" -lt 4 ]; then
    fail "$README: the worked example has $nblocks fenced blocks, expected at least 4"
    echo "readme: $passed passed, $failed failed"
    exit 1
fi
ln -s "$cli" "$tmp/work/build/ctcsim"
ln -s "$root/api" "$tmp/work/api"

# run_block FILE: runs the block's commands in $tmp/work; stdout to FILE.out, stderr to FILE.err
run_block() {
    grep -v '^make$' "$1" >"$1.run"
    (cd "$tmp/work" && timeout -k 5 "${CLI_TIME_LIMIT:-120}" sh -e "$1.run" >"$1.out" 2>"$1.err")
}

# norm_summary: the summary line with its wall time replaced by "TIME s"
norm_summary() {
    sed -E 's/, [0-9.]+(e[-+]?[0-9]+)? s, max \|e\|/, TIME s, max |e|/'
}

first_sh=""
for block in "$tmp/blocks"/*; do
    case "$block" in
    *.sh)
        if run_block "$block"; then pass; else
            fail "README block $(basename "$block"): exit $? running:"
            sed 's/^/    /' "$block.run"
            sed 's/^/    /' "$block.err" | head -n 5
        fi
        [ -z "$first_sh" ] && first_sh=$block
        ;;
    *.txt)
        if grep -q '^\$ build/ctcsim run bad.json$' "$block"; then
            # the invalid job: the worked example's job with the first mass -1
            sed '0,/"mass":[[:space:]]*1,/s//"mass": -1,/' "$tmp/work/job.json" >"$tmp/work/bad.json"
            want=$(sed -n '2p' "$block")
            (cd "$tmp/work" && "$cli" run bad.json >/dev/null 2>"$tmp/bad.err")
            got=$?
            [ "$got" -eq 2 ] && pass || fail "bad.json: exit $got, expected 2"
            [ "$(cat "$tmp/bad.err")" = "$want" ] && pass ||
                fail "bad.json: printed \"$(cat "$tmp/bad.err")\", the README shows \"$want\""
        elif grep -q '^t,' "$block" && [ -n "$first_sh" ]; then
            # the first block's CSV and summary
            csv_lines=0
            while IFS= read -r line; do
                case "$line" in
                "..." | "") ;;
                *": done, "*)
                    want=$(printf '%s\n' "$line" | norm_summary)
                    got=$(tail -n 1 "$first_sh.err" | norm_summary)
                    [ "$got" = "$want" ] && pass ||
                        fail "summary: the run prints \"$got\", the README shows \"$want\""
                    ;;
                t,*)
                    csv_lines=$((csv_lines + 1))
                    grep -qxF -- "$line" "$first_sh.out" && pass ||
                        fail "CSV: the run prints no header \"$line\""
                    ;;
                *)
                    csv_lines=$((csv_lines + 1))
                    row=$(grep "^${line%%,*}," "$first_sh.out" | head -n 1)
                    printf '%s\n%s\n' "$line" "$row" | awk -F, '
                        NR == 1 { n = NF; for (i = 1; i <= NF; i++) w[i] = $i + 0 }
                        NR == 2 { if (NF != n) exit 1
                                  for (i = 1; i <= NF; i++) {
                                      d = $i - w[i]; if (d < 0) d = -d
                                      s = w[i] < 0 ? -w[i] : w[i]; if (s < 1) s = 1
                                      if (d > 1e-12 * s) exit 1 } ; ok = 1 }
                        END { exit !ok }' && pass ||
                        fail "CSV: the run prints no line \"$line\" to 1e-12 (its t = ${line%%,*} is \"$row\")"
                    ;;
                esac
            done <"$block"
            [ "$csv_lines" -ge 3 ] && pass || fail "the README shows $csv_lines CSV lines, expected the header and two rows at least"
        fi
        ;;
    esac
done

finish readme

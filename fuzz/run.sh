#!/bin/sh
# Runs each libFuzzer harness for a bounded time (make fuzz; fuzz/README.md).
# usage: fuzz/run.sh BUILD NAME...   (BUILD: the libFuzzer build, with BUILD/fuzzers/NAME_fuzzer
#                                     and BUILD/ctcsim for the seeds)
# Each harness starts from BUILD/corpus/NAME (its working corpus, kept between runs: libFuzzer adds
# what finds new coverage) and the seeds fuzz/corpus.sh writes to BUILD/seeds/NAME, with the
# dictionary fuzz/job.dict, inputs of at most FUZZ_MAX_LEN bytes, and each input under
# FUZZ_INPUT_TIMEOUT seconds. A crash, leak, sanitizer report, broken contract (the harness
# aborts) or slow input stops it: the input is kept as BUILD/artifacts/NAME-crash-<sha1> (or
# -leak-, -timeout-, -oom-), the log as BUILD/NAME.log, and the script exits 1 once every harness
# has run. Reproduce with: BUILD/fuzzers/NAME_fuzzer BUILD/artifacts/NAME-crash-...
#
# From the environment:
#   FUZZ_TIME           seconds each harness runs (default 60)
#   FUZZ_MAX_LEN        the largest input in bytes (default 16384)
#   FUZZ_INPUT_TIMEOUT  seconds one input may take (default 10)
#   FUZZ_ARGS           more libFuzzer flags (e.g. -jobs=2, -seed=1)
set -u
build=$1
shift
time=${FUZZ_TIME:-60}
max_len=${FUZZ_MAX_LEN:-16384}
input_timeout=${FUZZ_INPUT_TIMEOUT:-10}
here=$(dirname "$0")
mkdir -p "$build/artifacts"
sh "$here/corpus.sh" "$build/ctcsim" "$build/seeds" || exit 1
status=0
for name in "$@"; do
    mkdir -p "$build/corpus/$name"
    log=$build/$name.log
    echo "== $name: $time s (log $log)"
    # the outer limit stops a harness that libFuzzer itself could not (a hang in its own exit)
    # shellcheck disable=SC2086
    timeout -k 10 $((time + 4 * input_timeout + 60)) "$build/fuzzers/${name}_fuzzer" \
        -max_total_time="$time" -timeout="$input_timeout" -rss_limit_mb=2048 \
        -max_len="$max_len" -dict="$here/job.dict" -print_final_stats=1 \
        -artifact_prefix="$build/artifacts/$name-" ${FUZZ_ARGS:-} \
        "$build/corpus/$name" "$build/seeds/$name" >"$log" 2>&1
    rc=$?
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
    cov=$(grep -E '^#[0-9]+' "$log" | tail -n 1 | sed -n 's/.* cov: \([0-9]*\).* ft: \([0-9]*\).*/cov \1, ft \2/p')
    corpus=$(ls "$build/corpus/$name" | wc -l)
    if [ "$rc" -eq 0 ]; then
        echo "$name: ok, ${runs:-?} executions, ${cov:-?}, corpus $corpus inputs"
    else
        status=1
        echo "$name: FAILED (exit $rc) after ${runs:-?} executions"
        grep -E 'ERROR|SUMMARY|fuzz_(job|merge):|runtime error|Test unit written' "$log" | head -n 20
    fi
done
exit $status

#!/bin/sh
# Runs each Criterion test binary given as an argument, then prints one closing line with the
# totals over all of them ("N passed, N failed"). Exits non-zero if any test failed or crashed.
passed=0
failed=0
status=0
for bin in "$@"; do
    out=$("$bin" --short-filename 2>&1)
    rc=$?
    printf '%s\n' "$out" | grep -v '^\[====\] Synthesis' | grep -E 'FAIL|CRASH|Assertion|error|ERROR|WARN' || true
    line=$(printf '%s\n' "$out" | grep 'Synthesis:' | tail -n 1)
    p=$(printf '%s\n' "$line" | sed -n 's/.*Passing: \([0-9]*\).*/\1/p')
    f=$(printf '%s\n' "$line" | sed -n 's/.*Failing: \([0-9]*\).*/\1/p')
    c=$(printf '%s\n' "$line" | sed -n 's/.*Crashing: \([0-9]*\).*/\1/p')
    if [ -z "$p" ]; then
        echo "$bin: no Criterion summary (exit $rc)"
        printf '%s\n' "$out" | tail -n 20
        failed=$((failed + 1))
        status=1
        continue
    fi
    printf '%-44s %s\n' "$(basename "$bin")" "$(echo "$line" | sed 's/.*Synthesis: //')"
    passed=$((passed + p))
    failed=$((failed + f + c))
    [ "$rc" -eq 0 ] || status=1
done
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ] || status=1
exit $status

# Sourced by the tests/cli scripts: one count of passed and failed checks, and their closing line.
#   pass            counts a check that held
#   fail MESSAGE    counts one that did not, and prints "FAIL: MESSAGE"
#   finish LABEL    prints "LABEL: N passed, N failed"; non-zero status if any failed
passed=0
failed=0

pass() { passed=$((passed + 1)); }
fail() {
    failed=$((failed + 1))
    echo "FAIL: $1"
}
finish() {
    echo "$1: $passed passed, $failed failed"
    [ "$failed" -eq 0 ]
}

#!/bin/sh
# Runs every unit test binary and the command-line tests; prints one closing
# line "N passed, N failed" and fails if any test failed.
# usage: tests/run_tests.sh BUILD_DIR TEST_BINARY...
build=$1; shift
passed=0; failed=0; broken=""
log=$(mktemp)
for t in "$@"; do
    name=$(basename "$t")
    "$t" >"$log" 2>&1; rc=$?
    p=$(sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' "$log" | tail -1)
    f=$(sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' "$log" | tail -1)
    p=${p:-0}; f=${f:-0}
    if [ "$rc" -ne 0 ] && [ "$f" -eq 0 ]; then f=1; fi
    passed=$((passed + p)); failed=$((failed + f))
    if [ "$f" -ne 0 ]; then
        broken="$broken $name"
        echo "---- $name (exit $rc)"; cat "$log"
    else
        echo "ok   $name: $p tests"
    fi
done
sh tests/cli/run.sh "$build/polarlux" >"$log" 2>&1; rc=$?
p=$(sed -n 's/^cli: \([0-9]*\) passed, \([0-9]*\) failed$/\1/p' "$log")
f=$(sed -n 's/^cli: \([0-9]*\) passed, \([0-9]*\) failed$/\2/p' "$log")
p=${p:-0}; f=${f:-1}
passed=$((passed + p)); failed=$((failed + f))
if [ "$f" -ne 0 ] || [ "$rc" -ne 0 ]; then
    broken="$broken cli"; echo "---- cli"; cat "$log"
else
    echo "ok   cli: $p tests"
fi
rm -f "$log"
[ -n "$broken" ] && echo "failing:$broken"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]

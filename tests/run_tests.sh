#!/bin/sh
# Runs every unit test binary (PLX_TEST_JOBS at a time, default: the number
# of processors) and the command-line tests; prints one closing line
# "N passed, N failed" and fails if any test failed.
# usage: tests/run_tests.sh BUILD_DIR TEST_BINARY...
build=$1; shift
jobs=${PLX_TEST_JOBS:-$(getconf _NPROCESSORS_ONLN 2>/dev/null || echo 2)}
passed=0; failed=0; skipped=0; broken=""
logs=$(mktemp -d)
# the command-line tests and the hostile corpus (many short runs of the
# command, mostly one core each) alongside the unit tests
# (the hostile corpus not in plain make check, PLX_TEST_SKIP_SLOW, which
# stays within a minute on two cores: check-full, asan, check-arm64 and
# check-hostile-valgrind run it)
if [ -z "$PLX_TEST_SKIP_SLOW" ]; then
    (sh tests/cli/hostile.sh "$build/polarlux" >"$logs/hostile.log" 2>&1; echo $? >"$logs/hostile.rc") &
fi
(sh tests/cli/run.sh "$build/polarlux" >"$logs/cli.log" 2>&1; echo $? >"$logs/cli.rc") &
for t in "$@"; do echo "$t"; done |
    xargs -P "$jobs" -I {} sh -c 'n=$(basename "$1"); "$1" >"$2/$n.log" 2>&1; echo $? >"$2/$n.rc"' _ {} "$logs"
wait # the command-line tests and the hostile corpus
for t in "$@"; do
    name=$(basename "$t"); log="$logs/$name.log"; rc=$(cat "$logs/$name.rc" 2>/dev/null || echo 1)
    p=$(sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' "$log" | tail -1)
    f=$(sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' "$log" | tail -1)
    s=$(sed -n 's/^\[  SKIPPED \] \([0-9][0-9]*\) test.*/\1/p' "$log" | tail -1)
    p=${p:-0}; f=${f:-0}; skipped=$((skipped + ${s:-0}))
    if [ "$rc" -ne 0 ] && [ "$f" -eq 0 ]; then f=1; fi
    passed=$((passed + p)); failed=$((failed + f))
    if [ "$f" -ne 0 ]; then
        broken="$broken $name"
        echo "---- $name (exit $rc)"; cat "$log"
    else
        echo "ok   $name: $p tests${s:+, $s skipped}"
    fi
done
log="$logs/cli.log"; rc=$(cat "$logs/cli.rc")
p=$(sed -n 's/^cli: \([0-9]*\) passed, \([0-9]*\) failed$/\1/p' "$log")
f=$(sed -n 's/^cli: \([0-9]*\) passed, \([0-9]*\) failed$/\2/p' "$log")
p=${p:-0}; f=${f:-1}
passed=$((passed + p)); failed=$((failed + f))
if [ "$f" -ne 0 ] || [ "$rc" -ne 0 ]; then
    broken="$broken cli"; echo "---- cli"; cat "$log"
else
    echo "ok   cli: $p tests"
fi
log="$logs/hostile.log"
if [ -n "$PLX_TEST_SKIP_SLOW" ]; then
    echo "--   hostile: in make check-full, make asan, make check-arm64 and make check-hostile-valgrind"
else
    rc=$(cat "$logs/hostile.rc")
    p=$(sed -n 's/^hostile: \([0-9]*\) passed, \([0-9]*\) failed$/\1/p' "$log")
    f=$(sed -n 's/^hostile: \([0-9]*\) passed, \([0-9]*\) failed$/\2/p' "$log")
    p=${p:-0}; f=${f:-1}
    passed=$((passed + p)); failed=$((failed + f))
    if [ "$f" -ne 0 ] || [ "$rc" -ne 0 ]; then
        broken="$broken hostile"; echo "---- hostile"; cat "$log"
    else
        echo "ok   hostile: $p tests"
    fi
fi
rm -rf "$logs"
[ -n "$broken" ] && echo "failing:$broken"
[ "$skipped" -gt 0 ] && echo "skipped: $skipped unit tests (each says why in its source)"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]

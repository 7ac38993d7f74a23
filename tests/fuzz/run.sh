#!/bin/sh
# Runs one libFuzzer target for a bounded time (make fuzz).
# usage: tests/fuzz/run.sh BUILD NAME SECONDS "LIBFUZZER OPTIONS" SEED_DIR...
# New inputs go to BUILD/corpus/NAME (kept between runs), a crashing input to
# BUILD/crash-NAME-*; the log is BUILD/NAME.log. Prints the executions and
# fails when the target crashed, leaked, hung or tripped a sanitizer.
build=$1; name=$2; seconds=$3; opts=$4; shift 4
bin=$build/$name
log=$build/$name.log
mkdir -p "$build/corpus/$name"
echo "== fuzz $name for $seconds s (seeds: $*)"
# shellcheck disable=SC2086
"$bin" $opts -max_total_time="$seconds" -artifact_prefix="$build/crash-$name-" \
    "$build/corpus/$name" "$@" >"$log" 2>&1
rc=$?
execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
cov=$(grep -E '^#[0-9]+' "$log" | tail -1 | sed -n 's/.* cov: \([0-9]*\) ft: \([0-9]*\) corp: \([0-9]*\).*/cov \1, features \2, corpus \3/p')
echo "   $name: ${execs:-?} executions, $cov, exit $rc"
if [ "$rc" -ne 0 ]; then
    echo "fuzz $name FAILED; log: $log"
    grep -E -A15 '^==[0-9]+==ERROR|runtime error:|FUZZ CHECK' "$log" | head -50
    ls "$build"/crash-"$name"-* 2>/dev/null
    echo "Reproduce: $bin <crash file>; then add the input to tests/corpus/ with its expected message in tests/unit/test_corpus.c"
    exit 1
fi

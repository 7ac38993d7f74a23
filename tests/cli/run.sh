#!/bin/sh
# Command-line tests: exit codes, messages and outputs of the polarlux command.
# usage: tests/cli/run.sh path/to/polarlux ; prints "cli: N passed, N failed".
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
pass=0; fail=0

# expect NAME CODE PATTERN -- command...: exit code CODE and PATTERN (grep -E)
# found in stdout+stderr.
expect() {
    name=$1; code=$2; pattern=$3; shift 4
    "$@" >"$tmp/out" 2>&1; rc=$?
    if [ "$rc" -ne "$code" ]; then
        echo "FAIL $name: exit $rc, want $code"; sed 's/^/    /' "$tmp/out" | head -20; fail=$((fail + 1)); return
    fi
    if [ -n "$pattern" ] && ! grep -Eq -- "$pattern" "$tmp/out"; then
        echo "FAIL $name: output lacks /$pattern/"; sed 's/^/    /' "$tmp/out" | head -20; fail=$((fail + 1)); return
    fi
    echo "ok   $name"; pass=$((pass + 1))
}

expect help 0 "^usage: polarlux COMMAND" -- "$bin" --help
expect no-args 2 "^usage: polarlux COMMAND" -- "$bin"
expect version 0 "^polarlux [0-9]+\.[0-9]+\.[0-9]+$" -- "$bin" --version
expect unknown-command 2 "unknown command 'frobnicate'" -- "$bin" frobnicate
for c in info gen; do
    expect "$c-help" 0 "^usage: polarlux $c" -- "$bin" $c --help
    expect "$c-unknown-option" 2 "polarlux $c: unknown option '--bogus'" -- "$bin" $c --bogus x
done
expect info-missing-scene 2 "missing SCENE" -- "$bin" info
expect info-missing-file 1 "polarlux info: $tmp/nope.geojson: cannot open: No such file or directory" -- "$bin" info "$tmp/nope.geojson"
expect info-tiny 0 "^buildings: 4 \(1 raised" -- "$bin" info fixtures/tiny.geojson
expect info-tiny-blocks 0 "^blocks: 3 with 1 courtyards" -- "$bin" info fixtures/tiny.geojson
expect info-tiny-lamp-warning 0 "warning: fixtures/tiny.geojson: feature 6 \(L3, line 18, column 3\): lamp is inside building 0 \(A\); left out" -- "$bin" info fixtures/tiny.geojson
expect info-tiny-memory 0 "^  scene +[0-9]+ bytes" -- "$bin" info fixtures/tiny.geojson
expect info-helsinki 0 "^skipped: 4 features, 2 lamps inside buildings" -- "$bin" info fixtures/helsinki-centre.geojson
expect info-helsinki-lonlat 0 "^coordinates: WGS84 lon/lat" -- "$bin" info fixtures/helsinki-centre.geojson
expect info-quiet 0 "" -- "$bin" info --quiet fixtures/helsinki-centre.geojson
if grep -q warning "$tmp/out"; then echo "FAIL info-quiet printed warnings"; fail=$((fail + 1)); fi
expect info-strict 1 "feature [0-9]+ \(way/[0-9]+, line [0-9]+, column [0-9]+\): min_height 18 m is not below height 12 m" -- "$bin" info --strict fixtures/helsinki-centre.geojson
expect info-tiny-mem 3 "out of memory" -- "$bin" info --mem 8K fixtures/helsinki-centre.geojson
expect info-bad-mem 2 "--mem 'lots' is not a size" -- "$bin" info --mem lots fixtures/tiny.geojson
printf '{"type": "FeatureCollection",\n "features": [,]}' >"$tmp/bad.json"
expect info-malformed 1 "malformed JSON at byte 44 \(line 2, column 15\)" -- "$bin" info "$tmp/bad.json"
expect gen-missing 2 "needs STYLE NX NY" -- "$bin" gen eixample 3
expect gen-bad-style 2 "unknown style 'paris'" -- "$bin" gen paris 3 3
expect gen-bad-n 2 "NX and NY must be whole numbers" -- "$bin" gen grid 0 3
expect gen-grid 0 "" -- "$bin" gen grid 3 2 -o "$tmp/g.geojson"
expect gen-grid-info 0 "^buildings: 6 " -- "$bin" info "$tmp/g.geojson"
"$bin" gen oldtown 5 5 --seed 7 >"$tmp/a.json"; "$bin" gen oldtown 5 5 --seed 7 >"$tmp/b.json"
if cmp -s "$tmp/a.json" "$tmp/b.json"; then echo "ok   gen-deterministic"; pass=$((pass + 1)); else echo "FAIL gen-deterministic"; fail=$((fail + 1)); fi
expect gen-eixample-info 0 "^blocks: 4 with 4 courtyards" -- sh -c "'$bin' gen eixample 2 2 > '$tmp/e.json' && '$bin' info '$tmp/e.json'"
ls "$tmp"/*.tmp* >/dev/null 2>&1 && { echo "FAIL temporary files left"; fail=$((fail + 1)); }
echo "cli: $pass passed, $fail failed"
[ "$fail" -eq 0 ]

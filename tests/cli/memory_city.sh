#!/bin/sh
# make check-full: the street walk of issue 16 on `gen eixample 30 30`
# (14,400 buildings, 18,480 lamps) in a small block. Loads, builds the polar
# diagrams and the lamp light, traces 16 photon frames into buffers sized
# from the budget and renders 640x480 street frames with indirect light and
# a short walk, at the smallest budget that works today (MEM, 64M); and the
# 5-frame walk at the 32M of the issue (since the renderer stopped holding
# the city's triangles; photon buffers at their lowest quality, a smaller contact
# sheet: README "Memory budgets"); and a frames-only bake made in 32M,
# walked in 32M.
# usage: tests/cli/memory_city.sh path/to/polarlux ; prints "memory-city: N passed, N failed".
bin=$1
MEM=${PLX_CITY_MEM:-64M}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
pass=0; fail=0
ok() { echo "ok   $1"; pass=$((pass + 1)); }
bad() { echo "FAIL $1"; fail=$((fail + 1)); sed 's/^/    /' "$tmp/err" | head -10; }

"$bin" gen eixample 30 30 -o "$tmp/city.geojson" || { echo "memory-city: gen failed"; exit 1; }
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{},"geometry":{"type":"LineString","coordinates":[[2095.4,1995.5],[2102.4,1988.5]]}}]}\n' >"$tmp/path.geojson"
# polar diagrams and photon buffers together, sizes printed
"$bin" info -q --photons --mem $MEM "$tmp/city.geojson" >"$tmp/out" 2>"$tmp/err"; rc=$?
if [ $rc -eq 0 ] && grep -q "^polar diagrams: built" "$tmp/out" && grep -Eq "^photon buffers: [0-9]+ bytes .*[1-9][0-9]* quality steps" "$tmp/out"; then
    ok "info-photons-$MEM: $(grep '^photon buffers' "$tmp/out")"
else bad "info-photons-$MEM: exit $rc"; fi
# a street frame with indirect light (the default street view searches with visibility queries)
"$bin" render --mem $MEM --size 640x480 "$tmp/city.geojson" -o "$tmp/street.png" >"$tmp/out" 2>"$tmp/err"; rc=$?
if [ $rc -eq 0 ] && [ -s "$tmp/street.png" ] && grep -q "indirect light at reduced quality to fit --mem" "$tmp/err"; then
    ok "render-street-640x480-$MEM"
else bad "render-street-640x480-$MEM: exit $rc"; fi
# a short walk: 5 frames 640x480 with indirect light
"$bin" walk -q --mem $MEM --aa 1 --max-frames 5 "$tmp/city.geojson" --path "$tmp/path.geojson" -o "$tmp/walk" >"$tmp/out" 2>"$tmp/err"; rc=$?
if [ $rc -eq 0 ] && [ -s "$tmp/walk/frame-0005.png" ] && grep -q "^walk: 5 frames 640x480" "$tmp/out"; then
    ok "walk-640x480-$MEM: $(grep '^frame time' "$tmp/out")"
else bad "walk-640x480-$MEM: exit $rc"; fi
# the issue's 32M
"$bin" walk --mem 32M --aa 1 --max-frames 5 "$tmp/city.geojson" --path "$tmp/path.geojson" -o "$tmp/walk32" >"$tmp/out" 2>"$tmp/err"; rc=$?
if [ $rc -eq 0 ] && [ -s "$tmp/walk32/frame-0005.png" ] && grep -q "^walk: 5 frames 640x480" "$tmp/out"; then
    ok "walk-640x480-32M: $(grep '^frame time' "$tmp/out")"
else bad "walk-640x480-32M: exit $rc"; fi
# its contact sheet shrinks its frames to fit what --mem leaves
if [ -s "$tmp/walk32/contact.png" ] && grep -q "contact sheet with frames [0-9]* pixels wide (not 320) to fit --mem" "$tmp/err"; then
    ok "walk-32M-smaller-sheet"
else bad "walk-32M-smaller-sheet"; fi
# a kiosk in 32M: a bake made in 32M for frames only (no polar diagrams, no
# aerial map, frames up to 640x480), then the walk from it in 32M
"$bin" bake -q --mem 32M --no-polar --no-aerial --max-size 640x480 "$tmp/city.geojson" -o "$tmp/k.plxb" >"$tmp/out" 2>"$tmp/err"; rc=$?
if [ $rc -eq 0 ] && [ -s "$tmp/k.plxb" ]; then ok "bake-32M: $(grep '^baked' "$tmp/out" | sed 's/.*: //')"
else bad "bake-32M: exit $rc"; fi
"$bin" walk --mem 32M --aa 1 --max-frames 5 "$tmp/k.plxb" --path "$tmp/path.geojson" -o "$tmp/walkk" >"$tmp/out" 2>"$tmp/err"; rc=$?
if [ $rc -eq 0 ] && [ -s "$tmp/walkk/frame-0005.png" ] && grep -q "^walk: 5 frames 640x480" "$tmp/out"; then
    ok "walk-bake-640x480-32M: $(grep '^frame time' "$tmp/out")"
else bad "walk-bake-640x480-32M: exit $rc"; fi
# the process stays near its block: the bake is read into the block, not
# held beside it (peak resident 51 MB for this 17.5 MiB bake before; the
# block's 32 MiB, the program and its libraries, the 640x480 frames)
if command -v /usr/bin/time >/dev/null 2>&1; then
    /usr/bin/time -f "%M" -o "$tmp/rss" "$bin" walk -q --mem 32M --aa 1 --max-frames 2 "$tmp/k.plxb" --path "$tmp/path.geojson" \
        -o "$tmp/walkr" >/dev/null 2>&1; rc=$?
    kb=$(tail -1 "$tmp/rss")
    if [ $rc -eq 0 ] && [ "$kb" -lt 43000 ]; then ok "walk-bake-32M-resident: $kb KB"
    else bad "walk-bake-32M-resident: exit $rc, $kb KB (at most 43000)"; fi
else
    echo "skip walk-bake-32M-resident: no /usr/bin/time (Debian package time)"
fi
echo "memory-city: $pass passed, $fail failed"
[ "$fail" -eq 0 ]

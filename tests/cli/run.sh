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
for c in info gen vis draw illum lit heatmap render nightify route dark-spots tiles annotate; do
    expect "$c-help" 0 "^usage: polarlux $c" -- "$bin" $c --help
    expect "$c-unknown-option" 2 "polarlux $c: unknown option '--bogus'" -- "$bin" $c --bogus x
done
expect info-missing-scene 2 "missing SCENE" -- "$bin" info
expect info-missing-file 1 "polarlux info: $tmp/nope.geojson: cannot open: No such file or directory" -- "$bin" info "$tmp/nope.geojson"
expect info-tiny 0 "^buildings: 4 \(1 raised" -- "$bin" info fixtures/tiny.geojson
expect info-tiny-blocks 0 "^blocks: 3 with 1 courtyards" -- "$bin" info fixtures/tiny.geojson
expect info-tiny-lamp-warning 0 "warning: fixtures/tiny.geojson: feature 6 \(L3, line 18, column 3\): lamp is inside building 0 \(A\); left out" -- "$bin" info fixtures/tiny.geojson
(cat fixtures/tiny.geojson; printf '\000garbage') >"$tmp/nul-text.geojson"
expect info-nul-then-text 1 "nul-text\\.geojson: malformed JSON at byte [0-9]+ \\(line 23, column 1\\)" -- "$bin" info "$tmp/nul-text.geojson"
# the common slips of hand-written JSON are named (helper-64: a NaN said only "malformed JSON at byte 81")
printf "{'type':'FeatureCollection'}" >"$tmp/single-quotes.geojson"
expect info-json-single-quotes 1 "malformed JSON at byte 2 \(line 1, column 3\): JSON strings take double quotes$" -- "$bin" info "$tmp/single-quotes.geojson"
printf '{"type":"FeatureCollection","features":[1,]}' >"$tmp/trailing-comma.geojson"
expect info-json-trailing-comma 1 "malformed JSON at byte 42 \(line 1, column 43\): a comma before the closing bracket$" -- "$bin" info "$tmp/trailing-comma.geojson"
printf '{"type":"FeatureCollection", // the city\n"features":[]}' >"$tmp/comment.geojson"
expect info-json-comment 1 "\(line 1, column 31\): JSON has no comments$" -- "$bin" info "$tmp/comment.geojson"
(cat fixtures/tiny.geojson; printf '\000\000') >"$tmp/nul-end.geojson"
expect info-nul-at-end 0 "^buildings: 4 " -- "$bin" info "$tmp/nul-end.geojson"
# a key read twice in one object: the first is read (cJSON's way), said on stderr; fatal when strict
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[\n{"type":"Feature","properties":{"height":10},"geometry":{"type":"Polygon","coordinates":[[[0,0],[10,0],[10,10],[0,10],[0,0]]],"coordinates":[[[50,0],[60,0],[60,10],[50,10],[50,0]]]}}]}\n' >"$tmp/dup-key.geojson"
expect info-duplicate-key-warns 0 "warning: .*dup-key\.geojson: line 2, column 127: an object holds \"coordinates\" twice; the first is read" -- "$bin" info "$tmp/dup-key.geojson"
expect info-duplicate-key-first 0 "^bounds: -50\.000 -50\.000 60\.000 60\.000 " -- "$bin" info -q "$tmp/dup-key.geojson"
expect info-duplicate-key-strict 1 "polarlux info: .*dup-key\.geojson: line 2, column 127: an object holds \"coordinates\" twice" -- "$bin" info --strict "$tmp/dup-key.geojson"
expect info-strict-lamp-inside 1 "feature 6 \\(L3, line 18, column 3\\): lamp is inside building 0 \\(A\\)$" -- "$bin" info --strict fixtures/tiny.geojson
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
printf '50 10\n# a comment\n\n50 12.5\n' >"$tmp/p.txt"
expect vis-courtyard 0 "^50 10 100 4$" -- "$bin" vis -q fixtures/tiny.geojson --points "$tmp/p.txt"
printf '50 10\n5 5\n' >"$tmp/p2.txt"
expect vis-inside 1 "p2.txt:2: point \(5, 5\) is inside building 0 \(A\): not a free viewpoint" -- "$bin" vis -q fixtures/tiny.geojson --points "$tmp/p2.txt"
expect vis-inside-row 1 "^5 5 nan 0$" -- "$bin" vis -q fixtures/tiny.geojson --points "$tmp/p2.txt"
printf '50 ten\n' >"$tmp/p3.txt"
expect vis-bad-points 1 "p3.txt:1: 'ten' is not a finite number" -- "$bin" vis -q fixtures/tiny.geojson --points "$tmp/p3.txt"
expect vis-both 2 "give exactly one of --points FILE and --at X,Y" -- "$bin" vis fixtures/tiny.geojson
expect vis-at 0 "^# visible: 3 of 3 buildings" -- "$bin" vis -q fixtures/tiny.geojson --at 30,30
expect vis-at-fov 0 "^2 C$" -- "$bin" vis -q fixtures/tiny.geojson --at 50,10 --dir 90 --fov 60
expect vis-geojson 0 "" -- "$bin" vis -q fixtures/tiny.geojson --points "$tmp/p.txt" --geojson "$tmp/v.geojson"
expect vis-geojson-loads 0 "^buildings: 2 " -- "$bin" info -q "$tmp/v.geojson"
expect vis-helsinki-lonlat 0 "" -- "$bin" vis -q fixtures/helsinki-centre.geojson --at 24.9442961,60.1716264 --geojson "$tmp/h.geojson"
expect vis-helsinki-geojson-lonlat 0 "^coordinates: WGS84 lon/lat" -- "$bin" info -q "$tmp/h.geojson"
expect draw-missing-q 2 "missing --polar Q" -- "$bin" draw fixtures/tiny.geojson -o "$tmp/d.png"
expect draw-bad-q 2 "--polar '7' is not a quadrant 0..3" -- "$bin" draw fixtures/tiny.geojson --polar 7 -o "$tmp/d.png"
expect draw-ok 0 "^polar diagram 1: [0-9]+ regions" -- "$bin" draw -q fixtures/tiny.geojson --polar 1 -o "$tmp/d.png" --size 200
if [ "$(head -c 4 "$tmp/d.png" | od -An -c | tr -d ' ')" = "211PNG" ]; then echo "ok   draw-png"; pass=$((pass + 1)); else echo "FAIL draw-png: not a PNG"; fail=$((fail + 1)); fi
expect draw-unwritable 1 "" -- "$bin" draw -q fixtures/tiny.geojson --polar 0 -o "$tmp/no/such/dir/d.png"
# illum: directly under lamp L2 (50, 10, z 8) in the courtyard:
# E = I / z^2 * W(z/R) = 1000 / 64 * (1 - (8/30)^4)^2 = 15.4673748...
printf '50 10\n50 10 0 0 0 1\n5 5 3 0 0 1\n' >"$tmp/i.txt"
expect illum-under-lamp 1 "^50 10 0 15\.46737485749[0-9]* 0$" -- "$bin" illum -q --no-indirect fixtures/tiny.geojson --points "$tmp/i.txt"
expect illum-indirect 1 "^50 10 0 15\.46737485749[0-9]* [0-9.]+(e-?[0-9]+)?$" -- "$bin" illum -q --frames 4 --photons 20000 fixtures/tiny.geojson --points "$tmp/i.txt"
if grep -q "^50 10 0 15.46737485749[0-9]* 0$" "$tmp/out"; then echo "FAIL illum-indirect: E_indirect is 0 in a lit courtyard"; fail=$((fail + 1)); else echo "ok   illum-indirect-nonzero"; pass=$((pass + 1)); fi
expect illum-bad-frames 2 "--frames 'x' is not a whole number" -- "$bin" illum -q fixtures/tiny.geojson --points "$tmp/i.txt" --frames x
expect illum-inside 1 "i.txt:3: point \(5, 5, 3\) is inside a building's solid" -- "$bin" illum -q --frames 2 fixtures/tiny.geojson --points "$tmp/i.txt"
expect illum-missing 2 "missing --points FILE" -- "$bin" illum fixtures/tiny.geojson
# illum --gather: final gathering (N x N directions) or, with 0, the photon
# buffers alone; both give a positive E_indirect in the lit courtyard
expect illum-gather-bad 2 "--gather needs a whole number from 0 to 1024" -- "$bin" illum -q fixtures/tiny.geojson --points "$tmp/i.txt" --gather 2000
expect illum-gather-8 1 "^50 10 0 15\.46737485749[0-9]* [0-9.]*[1-9][0-9.]*(e-?[0-9]+)?$" -- "$bin" illum -q --frames 2 --photons 20000 --gather 8 fixtures/tiny.geojson --points "$tmp/i.txt"
expect illum-gather-0 1 "^50 10 0 15\.46737485749[0-9]* [0-9.]*[1-9][0-9.]*(e-?[0-9]+)?$" -- "$bin" illum -q --frames 2 --photons 20000 --gather 0 fixtures/tiny.geojson --points "$tmp/i.txt"
expect illum-help-gather 0 "--gather N +final gathering over N x N directions" -- "$bin" illum --help
expect lit-L1 0 "^lamp 0 \(L1\): [0-9]+ lit ground polygons, [0-9]+ lit facade polygons" -- "$bin" lit -q fixtures/tiny.geojson --lamp L1 -o "$tmp/lit.geojson"
expect lit-index 0 "^lamp 1 \(L2\)" -- "$bin" lit -q fixtures/tiny.geojson --lamp 1 -o "$tmp/lit2.geojson"
expect lit-no-lamp 1 "no lamp with id or index 'L9'" -- "$bin" lit -q fixtures/tiny.geojson --lamp L9 -o "$tmp/lit3.geojson"
expect heatmap-ok 0 "^heatmap: [0-9]+x[0-9]+ pixels at 1 m" -- "$bin" heatmap -q fixtures/tiny.geojson --res 1 -o "$tmp/hm.png"
expect heatmap-bad-box 2 "--box '1,2,3' is not X0,Y0,X1,Y1" -- "$bin" heatmap -q fixtures/tiny.geojson --box 1,2,3 -o "$tmp/hm.png"
expect route-table 0 "^park-walk +all +[0-9.]+ " -- "$bin" route -q fixtures/helsinki-centre.geojson --path fixtures/helsinki-route.geojson --step 2 --geojson "$tmp/r.geojson"
expect route-geojson 0 "" -- sh -c "grep -q '\"p_class\"' '$tmp/r.geojson'"
printf '{"type":"FeatureCollection","features":[{"type":"Feature","properties":{},"geometry":{"type":"Point","coordinates":[1000,0]}}]}' >"$tmp/bad-route.json"
expect route-not-lines 1 "feature 0: geometry is not a LineString or MultiLineString" -- "$bin" route -q fixtures/tiny.geojson --path "$tmp/bad-route.json"
expect route-lonlat-vs-metres 1 "the path is in lon/lat but the scene is in local metres" -- "$bin" route -q fixtures/tiny.geojson --path fixtures/helsinki-route.geojson
expect dark-spots 0 "\"rank\":1" -- "$bin" dark-spots -q fixtures/tiny.geojson --res 2 --count 5
expect render-street 0 "^street view 160x120 from \(30\.0, 30\.0, 1\.7\) to \(50\.0, 10\.0, 2\.0\): drew [0-9]+ of 4 buildings" -- "$bin" render -q --frames 4 fixtures/tiny.geojson --eye 30,30,1.7 --target 50,10,2 --size 160x120 -o "$tmp/s.png" --pfm "$tmp/s.pfm"
if [ "$(head -c 12 "$tmp/s.pfm" | tr '\n' ' ')" = "PF 160 120 -" ]; then echo "ok   render-pfm-header"; pass=$((pass + 1)); else echo "FAIL render-pfm-header"; fail=$((fail + 1)); fi
if [ "$(wc -c < "$tmp/s.pfm")" -gt $((160 * 120 * 12)) ]; then echo "ok   render-pfm-size"; pass=$((pass + 1)); else echo "FAIL render-pfm-size"; fail=$((fail + 1)); fi
# an output in a missing folder is said before the work (render drew the
# frame first: 3.5 s for an aerial view of gen eixample 30 30)
expect render-out-missing-folder 1 "polarlux render: cannot write '$tmp/nodir/x.png': the folder '$tmp/nodir' does not exist" -- \
    "$bin" render fixtures/tiny.geojson -o "$tmp/nodir/x.png"
# before the work: before the scene is even read (tiny.geojson's loading
# warns of a lamp inside a building; the check of before wrote no image
# either, but loaded the scene and drew the frame first)
if ! grep -q "view [0-9]*x[0-9]* from\|lamp is inside building" "$tmp/out"; then echo "ok   render-out-missing-folder-first"; pass=$((pass + 1)); else echo "FAIL render-out-missing-folder-first"; fail=$((fail + 1)); fi
expect heatmap-out-missing-folder 1 "polarlux heatmap: cannot write '.*': the folder '.*' does not exist" -- \
    "$bin" heatmap fixtures/tiny.geojson -o "$tmp/nodir/h.png"
if ! grep -q "lamp is inside building" "$tmp/out"; then echo "ok   heatmap-out-missing-folder-first"; pass=$((pass + 1)); else echo "FAIL heatmap-out-missing-folder-first"; fail=$((fail + 1)); fi
# an output that names an input (or the other output) is refused before any
# work, and the input is left as it was
cp fixtures/tiny.geojson "$tmp/in.geojson"; ln -s in.geojson "$tmp/in-link.png"
expect bake-out-is-scene 2 "-o '$tmp/in.geojson' is the input '$tmp/in.geojson': writing it would replace it" -- "$bin" bake "$tmp/in.geojson" -o "$tmp/in.geojson"
expect render-out-is-scene-link 2 "-o '$tmp/in-link.png' is the input" -- "$bin" render -q "$tmp/in.geojson" -o "$tmp/in-link.png"
expect route-geojson-is-path 2 "writing it would replace it" -- "$bin" route -q fixtures/tiny.geojson --path "$tmp/in.geojson" --geojson "$tmp/in.geojson"
if cmp -s fixtures/tiny.geojson "$tmp/in.geojson"; then echo "ok   out-is-input-kept"; pass=$((pass + 1)); else echo "FAIL out-is-input-kept"; fail=$((fail + 1)); fi
expect render-png-is-pfm 2 "-o '$tmp/same' and --pfm '$tmp/same' name the same file" -- "$bin" render -q fixtures/tiny.geojson -o "$tmp/same" --pfm "$tmp/same"
expect render-aerial 0 "^aerial view 120x80 " -- "$bin" render -q --frames 4 fixtures/tiny.geojson --view aerial --size 120x80 -o "$tmp/a.png"
# the default aerial view keeps 5% of the frame each side around the
# scene's box (612 m: half of it over 0.9, over tan 30 degrees; 530.0 m up
# without the margin)
expect render-aerial-margin 0 "^aerial view 100x100 from \(266\.0, 266\.0, 588\.9\) to \(266\.0, 266\.0, 0\.0\)" -- \
    "$bin" render -q --no-indirect fixtures/eixample-4x4.geojson --view aerial --size 100x100 -o "$tmp/am.png"
expect render-default-street 0 "^street view 64x48 " -- "$bin" render -q --frames 4 fixtures/eixample-4x4.geojson --size 64x48 -o "$tmp/d.png"
expect render-eye-underground 2 "the eye must be above the ground" -- "$bin" render -q fixtures/tiny.geojson --eye 30,30,-1 --target 50,10,2 --size 16x16 -o "$tmp/u.png"
expect render-eye-only 2 "give both --eye and --target" -- "$bin" render -q fixtures/tiny.geojson --eye 30,30,2 -o "$tmp/u.png"
if "$bin" render --help | grep -q "not built into this polarlux"; then
expect render-osmesa 1 "built without OSMesa" -- "$bin" render -q --frames 2 fixtures/tiny.geojson --backend osmesa -o "$tmp/u.png"
else
expect render-osmesa 0 "^street view 64x48 " -- "$bin" render -q --frames 2 fixtures/tiny.geojson --backend osmesa --size 64x48 -o "$tmp/u.png"
fi
# out of memory: the free bytes when the request was refused, less than it
# asked for (read after the failed step had let go of its memory, it said
# "asked for 805306368 bytes; 1042579456 of 1073741824 bytes free")
expect render-nomem-free 3 "out of memory while creating the renderer .*: part 'frame' asked for [0-9]+ bytes; [0-9]+ of [0-9]+ bytes free \(give a larger --mem: the block holds" -- \
    "$bin" render -q fixtures/tiny.geojson --size 8192x8192 -o "$tmp/u.png"
set -- $(sed -n 's/.* asked for \([0-9]*\) bytes; \([0-9]*\) of [0-9]* bytes free (.*$/\1 \2/p' "$tmp/out")
if [ $# -eq 2 ] && [ "$2" -lt "$1" ]; then echo "ok   render-nomem-free-less"; pass=$((pass + 1))
else echo "FAIL render-nomem-free-less: free not below asked: $*"; fail=$((fail + 1)); fi
expect render-bad-size 2 "--size '12' is not WxH" -- "$bin" render -q fixtures/tiny.geojson --size 12 -o "$tmp/u.png"
expect nightify-ok 0 "^nightify: 160x120 day image matched to 120x80 night reference" -- "$bin" nightify "$tmp/s.png" "$tmp/a.png" -o "$tmp/n.png"
expect nightify-missing 1 "nope.png" -- "$bin" nightify "$tmp/nope.png" "$tmp/a.png" -o "$tmp/n2.png"
# ground image (properties.ground_image): read relative to the scene's folder
expect info-ground-image 0 "^ground image: ground-day\.png \(64x64 pixels\) over -32\.000 -32\.000 32\.000 32\.000; mean albedo 0\.[0-9]+ 0\.[0-9]+ 0\.[0-9]+ \(luminance 0\.2000\)$" -- "$bin" info fixtures/ground-image.geojson
expect render-ground-image 0 "^aerial view 120x80 " -- "$bin" render -q --no-indirect fixtures/ground-image.geojson --view aerial --size 120x80 -o "$tmp/gi.png"
expect illum-ground-image 0 "^0 0 0 [0-9.]+ [0-9.]+" -- sh -c "echo '0 0' | '$bin' illum -q --frames 2 --photons 5000 fixtures/ground-image.geojson --points -"
mkdir -p "$tmp/gi"
cp fixtures/ground-image.geojson "$tmp/gi/s.geojson"
expect ground-image-missing 1 "^polarlux info: $tmp/gi/s\.geojson: ground image 'ground-day\.png': PNG: cannot open '$tmp/gi/ground-day\.png': No such file or directory$" -- "$bin" info "$tmp/gi/s.geojson"
expect ground-image-missing-heatmap 1 "polarlux heatmap: $tmp/gi/s\.geojson: ground image 'ground-day\.png'" -- "$bin" heatmap "$tmp/gi/s.geojson" -o "$tmp/gi/h.png"
echo "not a png" >"$tmp/gi/ground-day.png"
expect ground-image-not-png 1 "ground image 'ground-day\.png': PNG: '$tmp/gi/ground-day\.png' is not a PNG file \(bad signature\)$" -- "$bin" render -q "$tmp/gi/s.geojson" -o "$tmp/gi/r.png"
sed "s|\"ground-day.png\"|\"$(pwd)/fixtures/ground-day.png\"|" fixtures/ground-image.geojson >"$tmp/gi/abs.geojson"
expect ground-image-absolute 0 "^ground image: /.*fixtures/ground-day\.png \(64x64 pixels\)" -- "$bin" info "$tmp/gi/abs.geojson"
printf '{"type": "FeatureCollection", "properties": {"units": "m", "ground_image": 5}, "features": []}' >"$tmp/gi/bad.geojson"
expect ground-image-bad-strict 1 "polarlux info: $tmp/gi/bad\.geojson: properties\.ground_image must be the path of a PNG file" -- "$bin" info --strict "$tmp/gi/bad.geojson"
expect ground-image-bad-lenient 0 "warning: $tmp/gi/bad\.geojson: properties\.ground_image must be the path of a PNG file \(a non-empty string of at most 4096 bytes\); ignored" -- "$bin" info "$tmp/gi/bad.geojson"
expect ground-image-nomem 3 "out of memory while storing the ground image" -- "$bin" info --mem 15K fixtures/ground-image.geojson
# ---- bake files (README "Bake files") ----
expect bake-help 0 "^usage: polarlux bake" -- "$bin" bake --help
expect bake-unknown-option 2 "polarlux bake: unknown option '--bogus'" -- "$bin" bake --bogus x
expect bake-missing-out 2 "missing -o CITY.plxb" -- "$bin" bake fixtures/tiny.geojson
expect bake-tiny 0 "^baked fixtures/eixample-4x4\.geojson into .*: [0-9]+ bytes .*engine memory in use [0-9]+ bytes" -- \
    "$bin" bake -q fixtures/eixample-4x4.geojson --frames 2 --photons 4000 --texel 2 --max-size 160x120 -o "$tmp/e.plxb"
# a bake given as bake's SCENE: one line saying so (it read as malformed JSON)
expect render-aerial-own-camera 0 "warning: --view aerial changed nothing: --eye and --target place the camera" -- "$bin" render "$tmp/e.plxb" --view aerial --eye 0,0,1.7 --target 30,0,1.5 --size 160x120 -o "$tmp/ra.png"
expect render-aerial-default-camera 0 "^aerial view 160x120" -- "$bin" render "$tmp/e.plxb" --view aerial --size 160x120 -o "$tmp/ra.png"
if grep -q "changed nothing" "$tmp/out"; then echo "FAIL render-aerial-default-camera warned"; fail=$((fail + 1)); fi
for o in --per-pixel --no-indirect; do # shaded pixel by pixel, the ground from the aerial light map: the view changes the frame
    expect "render-aerial-own-camera$o" 0 "^aerial view 160x120" -- "$bin" render "$tmp/e.plxb" --view aerial $o --eye 0,0,1.7 --target 30,0,1.5 --size 160x120 -o "$tmp/ra.png"
    if grep -q "changed nothing" "$tmp/out"; then echo "FAIL render-aerial-own-camera$o warned"; fail=$((fail + 1)); fi
done
expect bake-of-bake 2 "polarlux bake: .*e\.plxb is a bake file, not a GeoJSON scene" -- "$bin" bake "$tmp/e.plxb" -o "$tmp/ee.plxb"
if [ ! -e "$tmp/ee.plxb" ]; then echo "ok   bake-of-bake-no-file"; pass=$((pass + 1)); else echo "FAIL bake-of-bake-no-file"; fail=$((fail + 1)); fi
# a bake without indirect light gives images of the direct light, as
# README "Bake files" says (render and walk traced photons into its block:
# a Helsinki walk then ran out of memory at frame 1)
"$bin" bake -q fixtures/eixample-4x4.geojson --no-indirect --max-size 160x120 -o "$tmp/end.plxb" >/dev/null 2>&1
expect bake-no-indirect-render 0 "warning: .*end\.plxb holds no indirect light \(baked with --no-indirect or --frames 0\)" -- \
    "$bin" render "$tmp/end.plxb" --size 160x120 -o "$tmp/end1.png"
"$bin" render -q "$tmp/end.plxb" --size 160x120 --no-indirect -o "$tmp/end2.png" >/dev/null 2>&1
if cmp -s "$tmp/end1.png" "$tmp/end2.png"; then echo "ok   bake-no-indirect-direct-light"; pass=$((pass + 1)); else echo "FAIL bake-no-indirect-direct-light"; fail=$((fail + 1)); fi
# --frames 0 bakes as --no-indirect, the same file (it kept photon buffers
# and an atlas of direct light that frames never read: 5 MB more on the
# Helsinki district, and its frames shaded every pixel all the same)
expect bake-frames-zero 0 "no photons \(--frames 0: as --no-indirect\)" -- \
    "$bin" bake fixtures/eixample-4x4.geojson --frames 0 --max-size 160x120 -o "$tmp/f0.plxb"
if cmp -s "$tmp/f0.plxb" "$tmp/end.plxb"; then echo "ok   bake-frames-zero-file"; pass=$((pass + 1)); else echo "FAIL bake-frames-zero-file: not the --no-indirect bake"; fail=$((fail + 1)); fi
printf '{"type":"LineString","coordinates":[[20,5,1.7],[20,60,1.7]],"properties":{"units":"m"}}' >"$tmp/endpath.geojson"
expect bake-no-indirect-walk 0 "holds no indirect light" -- \
    "$bin" walk "$tmp/end.plxb" --path "$tmp/endpath.geojson" --size 160x120 --max-frames 3 -o "$tmp/endw"
# out of memory: what takes less (bake), and that --aa 1 needs no
# anti-aliasing buffers (a walk at the bake's own --mem failed at frame 1
# with no word of it)
expect bake-nomem-hint 3 "out of memory while making the radiance atlas.*\(--no-aerial, --no-polar, --no-indirect or a coarser --texel need less; or give a larger --mem\)$" -- \
    "$bin" bake -q fixtures/eixample-4x4.geojson --max-size 160x120 --mem 3M -o "$tmp/nomem.plxb"
# ... and only the options that act at the stage that ran out or before it (the
# renderer's frame buffers were told of --no-aerial and --texel, which act after)
expect bake-nomem-hint-renderer 3 "out of memory while creating the renderer.*\(--no-polar, --no-indirect or a smaller --max-size need less; or give a larger --mem\)$" -- \
    "$bin" bake -q fixtures/eixample-4x4.geojson --mem 8M -o "$tmp/nomem.plxb"
expect bake-nomem-hint-polar 3 "out of memory while building the polar diagrams.*\(--no-polar needs less; or give a larger --mem\)$" -- \
    "$bin" bake -q fixtures/helsinki-centre.geojson --mem 1500K -o "$tmp/nomem.plxb"
# the hint names only the options not given (a kiosk pass's bake with
# --no-aerial --no-polar was told to give them); --no-indirect (no photon
# buffers) at the photon buffers' stage and after, which was never named
# and is what fits (a kiosk pass); a smaller --max-size only while the
# frame buffers are an eighth of the block or more (at 16x16 it was
# still offered)
expect bake-nomem-hint-given 3 "out of memory while creating the photon buffers.*\(--no-indirect or a smaller --max-size need less; or give a larger --mem\)$" -- \
    "$bin" bake -q fixtures/eixample-4x4.geojson --no-aerial --no-polar --mem 2M -o "$tmp/nomem.plxb"
expect bake-nomem-hint-small-frames 3 "out of memory while creating the photon buffers.*\(--no-indirect needs less; or give a larger --mem\)$" -- \
    "$bin" bake -q fixtures/eixample-4x4.geojson --no-aerial --no-polar --max-size 16x16 --mem 2M -o "$tmp/nomem.plxb"
expect bake-nomem-hint-fits 0 "^baked " -- \
    "$bin" bake -q fixtures/eixample-4x4.geojson --no-aerial --no-polar --no-indirect --max-size 16x16 --mem 2M -o "$tmp/nomem.plxb"
# --texel finer than the atlas's budget takes is said on stderr (it was a
# figure on stdout only: 0.25 asked, 0.30 m made)
# (a larger --mem named only where a quarter of it is below the atlas's 64 MiB)
expect bake-texel-coarser 0 "warning: --texel 0\.5: the radiance atlas's points are 0\.71 m apart, the finest that fits its budget \(a quarter of --mem, at most 64 MiB\); a larger --mem fits finer ones$" -- \
    "$bin" bake fixtures/eixample-4x4.geojson --texel 0.5 --mem 24M --frames 2 --photons 4000 --max-size 160x120 -o "$tmp/tc.plxb"
# outputs: a new file named twice (another spelling of its folder), two
# outputs to standard output; string options of points and ids are no files
mkdir -p "$tmp/sub"
expect render-new-output-twice 2 "-o '$tmp/nf.png' and --pfm '$tmp/sub/../nf.png' name the same file" -- \
    "$bin" render fixtures/tiny.geojson --size 8x6 --no-indirect -o "$tmp/nf.png" --pfm "$tmp/sub/../nf.png"
if [ ! -e "$tmp/nf.png" ]; then echo "ok   render-new-output-twice-nothing"; pass=$((pass + 1)); else echo "FAIL render-new-output-twice-nothing"; fail=$((fail + 1)); fi
expect render-two-stdout 2 "-o and another output are both '-': only one can go to standard output" -- \
    "$bin" render fixtures/tiny.geojson --size 8x6 --no-indirect -o - --pfm -
# (lit --lamp 0 -o 0 twice in one folder: the second was refused, '0' taken for an input file)
here=$(pwd); abin=$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")
(cd "$tmp" && "$abin" lit -q "$here/fixtures/tiny.geojson" --lamp 0 -o 0 >/dev/null 2>&1)
(cd "$tmp" && "$abin" lit -q "$here/fixtures/tiny.geojson" --lamp 0 -o 0 >"$tmp/out" 2>&1); rc=$?
if [ "$rc" -eq 0 ]; then echo "ok   lit-lamp-id-same-as-output"; pass=$((pass + 1)); else echo "FAIL lit-lamp-id-same-as-output: exit $rc"; sed 's/^/    /' "$tmp/out" | head -3; fail=$((fail + 1)); fi
# walk and render (and illum) out of memory for the photon buffers name
# --no-indirect (a walk in --mem 1M said only that they did not fit)
expect walk-nomem-photons-hint 3 "out of memory while creating the photon buffers.*\(--no-indirect needs no photon buffers: direct light alone; or give a larger --mem\)$" -- \
    "$bin" walk -q fixtures/helsinki-centre.geojson --path fixtures/helsinki-walk.geojson --mem 1M -o "$tmp/wnm"
# 28 KB above the smallest --mem that loads the bake: room for a frame without anti-aliasing only
amem=$("$bin" info "$tmp/e.plxb" --min-mem 2>/dev/null | sed -n 's/^smallest --mem: \([0-9]*\) bytes.*/\1/p')
amem=$((amem + 28000))
expect walk-nomem-aa-hint 3 "^polarlux walk: frame 1 at .*out of memory .*\(give a larger --mem: the block holds [0-9]+ bytes; or bake with a smaller --max-size \(a bake's frames take their buffers at it\); anti-aliasing takes 20 bytes a pixel more of the largest frame, a bake's --max-size, and --aa 1 none\)$" -- \
    "$bin" walk -q "$tmp/e.plxb" --mem "$amem" --path "$tmp/endpath.geojson" --size 160x120 --max-frames 2 -o "$tmp/endw"
# a plain frame too large for the block: the hint names --mem and --size, not --aa 1 (which needed no less)
expect render-nomem-size-hint 3 "^polarlux render: out of memory .*\(give a larger --mem: the block holds [0-9]+ bytes; or a smaller --size\)$" -- \
    "$bin" render -q fixtures/tiny.geojson --mem 8M --size 2000x2000 -o "$tmp/big.png"
expect walk-nomem-aa1 0 "^walk: 2 frames" -- \
    "$bin" walk -q "$tmp/e.plxb" --mem "$amem" --aa 1 --path "$tmp/endpath.geojson" --size 160x120 --max-frames 2 -o "$tmp/endw"
# frames slower than --fps say so (1e4 fps: 0.1 ms a frame), with what is
# faster; a walk of 2 frames says nothing (its median may be the first
# frame's filling of the atlas)
expect walk-slower-than-fps 0 "^polarlux walk: warning: the frames took [0-9.]+ ms \(median; mean after the first [0-9.]+ ms\) to render, longer than a frame lasts at 10000 fps \(0\.1 ms\): shown as they are made, they fall behind on this machine; --aa 1 \(one sample a pixel\), a smaller --size or a lower --fps keep up$" -- \
    "$bin" walk "$tmp/e.plxb" --fps 10000 --path "$tmp/endpath.geojson" --size 160x120 --max-frames 3 -o "$tmp/endw"
"$bin" walk "$tmp/e.plxb" --fps 1 --path "$tmp/endpath.geojson" --size 160x120 --max-frames 3 -o "$tmp/endw" >"$tmp/out" 2>&1
if grep -q "fall behind" "$tmp/out"; then echo "FAIL walk-fps-kept: a walk at 1 fps says its frames fall behind"; fail=$((fail + 1))
else echo "ok   walk-fps-kept"; pass=$((pass + 1)); fi
"$bin" walk "$tmp/e.plxb" --fps 10000 --path "$tmp/endpath.geojson" --size 160x120 --max-frames 2 -o "$tmp/endw" >"$tmp/out" 2>&1
if grep -q "fall behind" "$tmp/out"; then echo "FAIL walk-fps-short: a walk of 2 frames says its frames fall behind"; fail=$((fail + 1))
else echo "ok   walk-fps-short"; pass=$((pass + 1)); fi
# a bake's photon budget is the one of the block it was baked in
expect bake-info-photons 0 "^photon buffers: [0-9]+ bytes \(default quality [0-9]+, budget [0-9]+ when baked\)" -- "$bin" info "$tmp/e.plxb" --photons
expect bake-info 0 "^bake: [0-9]+ bytes \([0-9.]+ MiB\) loaded in [0-9.]+ ms" -- "$bin" info "$tmp/e.plxb"
expect bake-info-memory 0 "^memory: [0-9]+ bytes in use" -- "$bin" info "$tmp/e.plxb"
printf '0.5 0.5\n10 -3\n61 61\n' >"$tmp/bp.txt"
"$bin" vis -q fixtures/eixample-4x4.geojson --points "$tmp/bp.txt" >"$tmp/v1" 2>&1
expect bake-vis 0 "" -- "$bin" vis -q "$tmp/e.plxb" --points "$tmp/bp.txt"
if cmp -s "$tmp/out" "$tmp/v1"; then echo "ok   bake-vis-same"; pass=$((pass + 1)); else echo "FAIL bake-vis-same"; fail=$((fail + 1)); fi
"$bin" render -q fixtures/eixample-4x4.geojson --no-indirect --size 160x120 -o "$tmp/r1.png" --pfm "$tmp/r1.pfm" >/dev/null 2>&1
expect bake-render 0 "street view 160x120" -- "$bin" render -q "$tmp/e.plxb" --no-indirect --size 160x120 -o "$tmp/r2.png" --pfm "$tmp/r2.pfm"
if cmp -s "$tmp/r1.pfm" "$tmp/r2.pfm"; then echo "ok   bake-render-same"; pass=$((pass + 1)); else echo "FAIL bake-render-same"; fail=$((fail + 1)); fi
# the same scene baked twice is the same bytes, on the workers too (no build
# times saved; the caches saved empty, whichever worker gathered what)
# (the options of bake-tiny above, whose file it is compared with)
expect bake-twice 0 "^baked " -- \
    "$bin" bake -q fixtures/eixample-4x4.geojson --frames 2 --photons 4000 --texel 2 --max-size 160x120 -o "$tmp/e2.plxb"
if cmp -s "$tmp/e.plxb" "$tmp/e2.plxb"; then echo "ok   bake-twice-same-bytes"; pass=$((pass + 1)); else echo "FAIL bake-twice-same-bytes"; fail=$((fail + 1)); fi
# baked on 1 and 2 threads: the same bytes, the header included
for t in 1 2; do
    expect bake-threads-$t 0 "^baked " -- "$bin" bake -q fixtures/oldtown-8x8.geojson --frames 2 --photons 4000 \
        --texel 2 --max-size 160x120 --threads $t -o "$tmp/t$t.plxb"
done
if cmp -s "$tmp/t1.plxb" "$tmp/t2.plxb"; then echo "ok   bake-threads-same-bytes"; pass=$((pass + 1))
else echo "FAIL bake-threads-same-bytes"; fail=$((fail + 1)); fi
expect bake-info-polar 0 "^polar diagrams: from the bake; [0-9]+ bytes" -- "$bin" info "$tmp/e.plxb"
# a damaged camera path says where (it said only "malformed JSON")
printf '{"type":"LineString",\n "coordinates":[[0,0],[1,' >"$tmp/pbad.geojson"
expect walk-path-malformed 1 "^polarlux walk: $tmp/pbad\.geojson: malformed JSON at byte 47 \(line 2, column 26\): the text ends early$" -- \
    "$bin" walk -q fixtures/tiny.geojson --path "$tmp/pbad.geojson" -o "$tmp/wpb"
# a path's units other than "m", and text after its JSON, are refused as
# route and the scene loader refuse them (walk read "ft" as metres)
printf '{"type":"Feature","properties":{"units":"ft"},"geometry":{"type":"LineString","coordinates":[[0,0],[10,0]]}}' >"$tmp/pft.geojson"
expect walk-path-units 1 "^polarlux walk: $tmp/pft\.geojson: properties\.units must be \"m\" when given" -- \
    "$bin" walk -q fixtures/tiny.geojson --path "$tmp/pft.geojson" -o "$tmp/wft"
printf '{"type":"LineString","coordinates":[[0,0],[10,0]]} x' >"$tmp/ptrail.geojson"
expect walk-path-trailing 1 "^polarlux walk: $tmp/ptrail\.geojson: malformed JSON at byte 51 \(line 1, column 52\)$" -- \
    "$bin" walk -q fixtures/tiny.geojson --path "$tmp/ptrail.geojson" -o "$tmp/wtr"
# a tiny --exposure is named when the image comes out black (the lamps
# were blamed)
expect render-black-exposure 0 "warning: the image is entirely black: --exposure 1e-06 maps the light there to black \(automatic exposure, without --exposure, chooses [0-9.]+\)" -- \
    "$bin" render "$tmp/e.plxb" --size 64x48 --exposure 1e-6 -o "$tmp/xblack.png"
expect walk-help 0 "^usage: polarlux walk" -- "$bin" walk --help
expect walk-unknown-option 2 "polarlux walk: unknown option '--bogus'" -- "$bin" walk --bogus x
expect walk-missing-path 2 "missing --path CAMERA.geojson" -- "$bin" walk "$tmp/e.plxb" -o "$tmp/w"
printf '{"type":"Feature","properties":{"units":"m"},"geometry":{"type":"LineString","coordinates":[[298.6,265.5,1.7],[270,294,1.7],[262,330]]}}' >"$tmp/path.geojson"
# a frame larger than the bake's --max-size: the sizes, not a crash
expect bake-frame-too-large 2 "a 320x240 frame is outside 1x1 \.\. 160x120 \(or 120x160\), the largest this engine draws" -- \
    "$bin" render -q "$tmp/e.plxb" --no-indirect --size 320x240 -o "$tmp/big.png"
# the same frame turned a quarter is drawn (a portrait screen from a bake
# for a landscape one; it was refused)
expect bake-frame-turned 0 "^street view 120x160 " -- "$bin" render -q "$tmp/e.plxb" --size 120x160 -o "$tmp/turn.png"
expect bake-frame-turned-per-pixel 0 "^street view 120x160 " -- "$bin" render -q "$tmp/e.plxb" --per-pixel --size 120x160 -o "$tmp/turnp.png"
expect bake-frame-turned-walk 0 "^walk: 3 frames 120x160 " -- \
    "$bin" walk -q "$tmp/e.plxb" --path "$tmp/path.geojson" --size 120x160 --max-frames 3 -o "$tmp/turnw"
# a bake without polar diagrams (for frames in a small block): smaller, and a
# visibility query on it builds them on need, with the same answers
expect bake-no-polar 0 "^baked " -- \
    "$bin" bake -q fixtures/eixample-4x4.geojson --no-polar --frames 2 --photons 4000 --texel 2 --max-size 160x120 -o "$tmp/np.plxb"
if [ "$(wc -c <"$tmp/np.plxb")" -lt "$(wc -c <"$tmp/e.plxb")" ]; then echo "ok   bake-no-polar-smaller"; pass=$((pass + 1))
else echo "FAIL bake-no-polar-smaller"; fail=$((fail + 1)); fi
expect bake-no-polar-vis 0 "" -- "$bin" vis -q "$tmp/np.plxb" --points "$tmp/bp.txt"
if cmp -s "$tmp/out" "$tmp/v1"; then echo "ok   bake-no-polar-vis-same"; pass=$((pass + 1)); else echo "FAIL bake-no-polar-vis-same"; fail=$((fail + 1)); fi
if [ -z "$PLX_TEST_SKIP_SLOW" ]; then # not in plain make check: the photons a frame on a 4,740-lamp city (about 7 s)
# bake's photons per frame: 16 a lamp (4,740 lamps: 75,840) unless --photons
"$bin" gen eixample 15 15 -o "$tmp/e15.geojson"
expect bake-photons-per-lamp 0 "photons [0-9]+ ms \(16 x 75840\)" -- \
    "$bin" bake "$tmp/e15.geojson" --no-aerial --no-polar --max-size 32x24 -o "$tmp/e15.plxb"
expect bake-photons-given 0 "photons [0-9]+ ms \(2 x 4000\)" -- \
    "$bin" bake "$tmp/e15.geojson" --no-aerial --no-polar --max-size 32x24 --photons 4000 --frames 2 -o "$tmp/e15.plxb"
fi
# an -o bake cannot write is refused before the scene is read (it was
# refused after the whole bake: 5 s on gen eixample 15 15)
expect bake-out-is-folder 1 "^polarlux bake: '$tmp' is a directory$" -- "$bin" bake "$tmp/nope.geojson" -o "$tmp"
expect bake-out-no-folder 1 "^polarlux bake: cannot write '$tmp/no/such/x\.plxb': the folder '$tmp/no/such' does not exist$" -- \
    "$bin" bake "$tmp/nope.geojson" -o "$tmp/no/such/x.plxb"
if [ -z "$PLX_TEST_SKIP_SLOW" ]; then # (with the block above)
# render from a GeoJSON traces 16 photons a lamp too (4,740 lamps: 75,840 a
# frame): the same image as --photons 75840, another than the old 65,536
"$bin" render -q "$tmp/e15.geojson" --size 64x48 -o "$tmp/pd.png" >/dev/null
"$bin" render -q "$tmp/e15.geojson" --size 64x48 --photons 75840 -o "$tmp/p75.png" >/dev/null
"$bin" render -q "$tmp/e15.geojson" --size 64x48 --photons 65536 -o "$tmp/p65.png" >/dev/null
if cmp -s "$tmp/pd.png" "$tmp/p75.png" && ! cmp -s "$tmp/pd.png" "$tmp/p65.png"; then echo "ok   render-photons-per-lamp"; pass=$((pass + 1))
else echo "FAIL render-photons-per-lamp: the default image is not --photons 75840's, or is --photons 65536's"; fail=$((fail + 1)); fi
# too many photons in all names the default it computed, not --photons
expect render-photons-per-lamp-too-many 2 "75840 photons a frame \(16 a lamp; --photons sets it\) x --frames 60000 is more than 4294967296 photons" -- \
    "$bin" render -q "$tmp/e15.geojson" --size 64x48 --frames 60000 -o "$tmp/pd.png"
# a scene of fewer than 4,096 lamps keeps 65,536 a frame
"$bin" render -q fixtures/eixample-4x4.geojson --size 64x48 -o "$tmp/pd.png" >/dev/null
"$bin" render -q fixtures/eixample-4x4.geojson --size 64x48 --photons 65536 -o "$tmp/p65.png" >/dev/null
if cmp -s "$tmp/pd.png" "$tmp/p65.png"; then echo "ok   render-photons-floor"; pass=$((pass + 1))
else echo "FAIL render-photons-floor: eixample-4x4's default image is not --photons 65536's"; fail=$((fail + 1)); fi
fi
# in a block that holds the bake but not the polar diagrams, the default
# street view (which needs them to find a street) says what to give instead
npm=$("$bin" info "$tmp/np.plxb" --min-mem 2>/dev/null | sed -n 's/^smallest --mem: \([0-9]*\) bytes.*/\1/p')
expect bake-no-polar-default-view 3 "the default street view needs the polar diagrams to find a street, and this bake was made without them \(--no-polar\); give --eye and --target, --view aerial, or a larger --mem$" -- \
    "$bin" render -q "$tmp/np.plxb" --mem $((npm - 150000)) --size 16x12 -o "$tmp/npv.png"
# in the smallest block that loads a bake with its polar diagrams, the
# default street view's visibility queries run out of memory: it says so
# (it said "found no free street spot beside a lamp", exit 1)
expect render-nomem-street-search 3 "ran out of memory; give --eye and --target, --view aerial, or a larger --mem$" -- \
    "$bin" render -q "$tmp/e.plxb" --mem "$amem" --size 16x12 -o "$tmp/nss.png"
# a bake whose first byte is damaged is refused as a bake, not as JSON
# ("malformed JSON at byte 0")
{ printf 'Q'; tail -c +2 "$tmp/e.plxb"; } >"$tmp/dmg.plxb"
expect bake-damaged-magic 1 "^polarlux info: $tmp/dmg\.plxb: not a polarlux bake file \(no PLXBAKE magic\)$" -- "$bin" info "$tmp/dmg.plxb"
# a GeoJSON scene with a byte-order mark named *.plxb is still a scene
{ printf '\357\273\277'; cat fixtures/tiny.geojson; } >"$tmp/bom.plxb"
expect scene-named-plxb-bom 0 "^buildings: 4 " -- "$bin" info -q "$tmp/bom.plxb"
head -c 5000 "$tmp/e.plxb" >"$tmp/cut.plxb"
expect bake-truncated 1 "^polarlux info: $tmp/cut\.plxb: truncated bake file: 5000 bytes, the header says [0-9]+$" -- "$bin" info "$tmp/cut.plxb"
expect bake-version 1 "^polarlux render: tests/corpus/bake-version-99\.plxb: bake format version 99, this polarlux reads version 3; bake the scene again$" -- \
    "$bin" render tests/corpus/bake-version-99.plxb -o "$tmp/x.png"
expect bake-arch 1 "bake made on another architecture" -- "$bin" vis tests/corpus/bake-big-endian.plxb --at 0,0
# a damaged byte in the header's build print is a damaged file, not a bake
# of another build (its checksum does not hold: it was blamed on the build)
cp "$tmp/e.plxb" "$tmp/flip.plxb"; printf '\001' | dd of="$tmp/flip.plxb" bs=1 seek=20 conv=notrunc 2>/dev/null
expect bake-header-flip 1 "flip\.plxb: corrupt bake file: checksum mismatch \(in its header\)" -- "$bin" info "$tmp/flip.plxb"
# the size fields the block is taken by, damaged (the command asks the
# header's size and checks the whole file only when that block cannot be
# had): a size far too big (byte 71, the slack's top: 9e18 bytes) and one
# that can be had (byte 67: 2 GB more) are both a damaged file
for at in 71 67; do
    cp "$tmp/e.plxb" "$tmp/slack.plxb"; printf '\177' | dd of="$tmp/slack.plxb" bs=1 seek=$at conv=notrunc 2>/dev/null
    expect bake-size-flip-$at 1 "^polarlux info: $tmp/slack\.plxb: corrupt bake file: checksum mismatch$" -- "$bin" info "$tmp/slack.plxb"
done
printf '' >"$tmp/empty.geojson"
expect info-empty-file 1 "malformed JSON at byte 0 \(line 1, column 1\): the file is empty" -- "$bin" info "$tmp/empty.geojson"
expect bake-nomem 3 "the block is too small for the bake" -- "$bin" info --mem 64K "$tmp/e.plxb"
# info --min-mem on a bake: the block its image loads in (it echoed --mem:
# 1073741824 by default, 2147483648 with --mem 2G); the printed budget
# loads, 4 KiB (the bisection's step) less does not, whatever --mem says
for f in e np; do
    n=$("$bin" info -q --min-mem "$tmp/$f.plxb" | sed -n 's/^smallest --mem: \([0-9]*\) bytes (.*) loads the bake .*/\1/p')
    n2=$("$bin" info -q --min-mem --mem 2G "$tmp/$f.plxb" | sed -n 's/^smallest --mem: \([0-9]*\) bytes (.*) loads the bake .*/\1/p')
    if [ -n "$n" ] && [ -n "$n2" ] && [ $((n - n2)) -lt 4096 ] && [ $((n2 - n)) -lt 4096 ]; then
        echo "ok   bake-min-mem-$f"; pass=$((pass + 1))
    else echo "FAIL bake-min-mem-$f: --min-mem printed '$n', with --mem 2G '$n2'"; fail=$((fail + 1)); n=1073741824; fi
    expect bake-min-mem-$f-fits 0 "^memory: [0-9]+ bytes in use" -- "$bin" info -q --mem "$n" "$tmp/$f.plxb"
    expect bake-min-mem-$f-less 3 "the block is too small for the bake|out of memory while building the polar diagrams" -- \
        "$bin" info -q --mem $((n - 4096)) "$tmp/$f.plxb"
done
# a --no-polar bake's smallest block for frames (without the polar
# diagrams info builds): a walk at --aa 1 runs in it, 4 KiB less does not
# load the bake (--min-mem printed only the block with them, 42.7 MiB
# where a walk of the e30 city's 32M bake runs in 29.9)
nf=$("$bin" info -q --min-mem "$tmp/np.plxb" | sed -n 's/^smallest --mem for frames: \([0-9]*\) bytes .*made with --no-polar.*/\1/p')
expect bake-min-mem-frames 0 "^walk: 2 frames" -- \
    "$bin" walk -q "$tmp/np.plxb" --mem "${nf:-1}" --aa 1 --path "$tmp/endpath.geojson" --size 160x120 --max-frames 2 -o "$tmp/nfw"
expect bake-min-mem-frames-less 3 "the block is too small for the bake" -- \
    "$bin" walk -q "$tmp/np.plxb" --mem $((${nf:-1} - 4096)) --aa 1 --path "$tmp/endpath.geojson" --size 160x120 --max-frames 2 -o "$tmp/nfw"
# info --min-mem's block for frames from above: the whole scene from above
# at the bake's largest size with 2 x 2 adaptive samples (walk's default)
# fits in it; 4 KiB less leaves no room for the adaptive buffers (the
# bisection's test), said by the warning (the full bake's line was only
# the load's, and walk failed there)
na=$("$bin" info -q --min-mem "$tmp/e.plxb" | sed -n 's/^smallest --mem for frames from above: \([0-9]*\) bytes .* a 160x120 frame .*/\1/p')
"$bin" render "$tmp/e.plxb" --view aerial --size 160x120 --aa 2 --mem "${na:-1}" -o "$tmp/na.png" >"$tmp/out" 2>&1
if [ $? -eq 0 ] && ! grep -q "no room for adaptive" "$tmp/out"; then echo "ok   bake-min-mem-from-above"; pass=$((pass + 1)); else echo "FAIL bake-min-mem-from-above ('$na')"; sed 's/^/    /' "$tmp/out" | head -5; fail=$((fail + 1)); fi
expect bake-min-mem-from-above-less 0 "leaves no room for adaptive anti-aliasing" -- \
    "$bin" render "$tmp/e.plxb" --view aerial --size 160x120 --aa 2 --mem $((${na:-1} - 4096)) -o "$tmp/na.png"
# a view with a few lit pixels (the city 3 km off) is nearly black: said
# (only an entirely black one was), by render and by walk; a normal view
# from above (about 70% black: its roofs) is not
expect render-nearly-black 0 "warning: the image is nearly black: 99\.[0-9]+% of its pixels are black \([0-9]+ lit\): little that is lit is in view" -- \
    "$bin" render "$tmp/e.plxb" --eye -3000,266,60 --target 266,266,0 --size 160x120 -o "$tmp/nb.png"
printf '{"type":"LineString","coordinates":[[-3000,266,60],[-2999,266,60]],"properties":{"targets":[[266,266,0],[266,266,0]]}}' >"$tmp/nb.geojson"
expect walk-nearly-black 0 "warning: 2 of 2 frames are nearly black, 99% of their pixels or more \(the first: frame 1\)" -- \
    "$bin" walk "$tmp/e.plxb" --path "$tmp/nb.geojson" --size 160x120 --fps 1 --speed 1 -o "$tmp/nbw"
"$bin" render "$tmp/e.plxb" --view aerial --size 160x120 -o "$tmp/nb.png" >"$tmp/out" 2>&1
if [ $? -eq 0 ] && ! grep -q "nearly black" "$tmp/out"; then echo "ok   render-aerial-not-nearly-black"; pass=$((pass + 1)); else echo "FAIL render-aerial-not-nearly-black"; sed 's/^/    /' "$tmp/out" | head -5; fail=$((fail + 1)); fi
# a metre scene far from the origin (a projected CRS) gives the images of
# the same scene at the origin, exact and atlas (135 and 29 lit pixels went
# dark before 2026-11-30: wall points rounded into their buildings)
if /usr/bin/python3 tests/cli/far_origin.py "$bin" "$tmp" >"$tmp/out" 2>&1; then echo "ok   render-far-from-origin"; pass=$((pass + 1))
else echo "FAIL render-far-from-origin"; sed 's/^/    /' "$tmp/out"; fail=$((fail + 1)); fi
# ---- walk (README "Walking through a city") ----
# a path far outside the scene says so (it blamed the lamps' reach)
printf '{"type":"LineString","coordinates":[[5000,5000,1.7],[5010,5000,1.7]],"properties":{"units":"m"}}' >"$tmp/far.geojson"
expect walk-path-outside 0 "^polarlux walk: warning: every frame is entirely black: the camera path stays outside the scene, its eyes and targets [0-9]+ m or more from the scene's bounds" -- \
    "$bin" walk fixtures/tiny.geojson --path "$tmp/far.geojson" --size 32x24 --max-frames 2 --no-indirect -o "$tmp/wfar"
# a walk that fails before its first frame leaves no folder it made (it
# left an empty one), and keeps one that was there
"$bin" walk -q fixtures/tiny.geojson --path "$tmp/no-such-path.geojson" -o "$tmp/wgone" >/dev/null 2>&1
mkdir -p "$tmp/wkept"
"$bin" walk -q fixtures/tiny.geojson --path "$tmp/no-such-path.geojson" -o "$tmp/wkept" >/dev/null 2>&1
if [ ! -e "$tmp/wgone" ] && [ -d "$tmp/wkept" ]; then echo "ok   walk-fail-no-folder"; pass=$((pass + 1))
else echo "FAIL walk-fail-no-folder: a failed walk left its new -o folder, or removed an existing one"; fail=$((fail + 1)); fi
# a frame larger than the bake's --max-size: the renderer's reason (the
# message ended at the colon: formatting the eye cleared the error), and
# no folder left with only cameras.txt in it
expect walk-too-large 2 "^polarlux walk: frame 1 at \(.*\): plx_render: a 320x240 frame is outside 1x1 \.\. 160x120" -- \
    "$bin" walk -q "$tmp/e.plxb" --path "$tmp/path.geojson" --size 320x240 -o "$tmp/wbig"
if [ ! -e "$tmp/wbig" ]; then echo "ok   walk-too-large-no-folder"; pass=$((pass + 1))
else echo "FAIL walk-too-large-no-folder: a walk whose first frame failed left its folder"; fail=$((fail + 1)); fi
# a vertical stretch gives no point ahead: the eye looks along the next
# stretch that moves (it looked 1 m east), and a path that never moves
# says where it looks
printf '{"type":"Feature","properties":{"units":"m"},"geometry":{"type":"LineString","coordinates":[[300,265,1.7],[300,265,30],[300,300,30]]}}' >"$tmp/pvert.geojson"
expect walk-vertical-looks-along 0 "^2 300 265 15.85 300 275 15.85 " -- \
    sh -c "'$bin' walk -q '$tmp/e.plxb' --path '$tmp/pvert.geojson' --size 32x24 --speed 14.15 --fps 1 --aa 1 --no-indirect -o '$tmp/wvert' >/dev/null && cat '$tmp/wvert/cameras.txt'"
printf '{"type":"Feature","properties":{"units":"m"},"geometry":{"type":"LineString","coordinates":[[300,265,1.7],[300,265,30]]}}' >"$tmp/pup.geojson"
expect walk-never-moves 0 "the path never moves horizontally and has no properties.targets: the camera looks east" -- \
    "$bin" walk "$tmp/e.plxb" --path "$tmp/pup.geojson" --size 32x24 --speed 14.15 --fps 1 --aa 1 --no-indirect -o "$tmp/wup"
expect walk-black-exposure 0 "warning: every frame is entirely black: --exposure 1e-06 maps the light there to black" -- \
    "$bin" walk "$tmp/e.plxb" --path "$tmp/path.geojson" --size 32x24 --max-frames 2 --exposure 1e-6 -o "$tmp/wblack"
# options a bake makes moot are named (they were ignored without a word)
expect render-bake-kept 0 "warning: --photons and --frames are not used: .*e\.plxb holds its photon buffers" -- \
    "$bin" render "$tmp/e.plxb" --size 32x24 --photons 5000 --frames 2 -o "$tmp/xkept.png"
expect walk-bake-texel-kept 0 "warning: --texel is not used: .*e\.plxb holds its radiance atlas, 2\.00 m between its points" -- \
    "$bin" walk "$tmp/e.plxb" --path "$tmp/path.geojson" --size 32x24 --max-frames 1 --texel 1 -o "$tmp/wkept"
# the last frame is at the path's end when the steps do not reach it (a
# flight's landing ended a step short; a step longer than the path gave
# its start alone)
expect walk-ends-at-end 0 "^walk: 2 frames 32x24 \(77\.3 m of 77\.3 m at 400 m/s" -- \
    "$bin" walk -q "$tmp/e.plxb" --path "$tmp/path.geojson" --size 32x24 --speed 400 --fps 1 -o "$tmp/wstep"
expect walk-end-camera 0 "^2 262 330 1.7 " -- cat "$tmp/wstep/cameras.txt"
expect mem-units 2 "--mem '1X' is not a size from 4096 bytes to 1e15 \(a number with K, M, G or T" -- "$bin" info fixtures/tiny.geojson --mem 1X
expect walk-exact 0 "^frame time: median [0-9.]+ ms, p95 [0-9.]+ ms, mean [0-9.]+ ms: [0-9.]+ frames per second" -- \
    "$bin" walk -q "$tmp/e.plxb" --path "$tmp/path.geojson" --size 160x120 --fps 0.2 --aa 1 --no-indirect --no-glow --exposure 1 -o "$tmp/w1"
set -- $(sed -n '3p' "$tmp/w1/cameras.txt")
"$bin" render -q "$tmp/e.plxb" --size 160x120 --no-indirect --no-glow --exposure 1 --eye "$2,$3,$4" --target "$5,$6,$7" -o "$tmp/w1r.png" >/dev/null 2>&1
if /usr/bin/python3 tests/cli/png_same.py "$tmp/w1/frame-0002.png" "$tmp/w1r.png"; then echo "ok   walk-exact-equals-render"; pass=$((pass + 1)); else echo "FAIL walk-exact-equals-render"; fail=$((fail + 1)); fi
# from a scene too (not only a bake): render laid out the photon levels
# for its own eye, walk for the scene's centre, so a frame and render at
# its camera differed (36% of the channels here, up to 19 of 255); both
# now lay them out as bake does
"$bin" gen eixample 8 8 -o "$tmp/e8.geojson" >/dev/null 2>&1
printf '{"type":"LineString","coordinates":[[133,300],[133,700]]}' >"$tmp/e8path.geojson"
"$bin" walk -q "$tmp/e8.geojson" --path "$tmp/e8path.geojson" --size 160x120 --fps 0.05 --max-frames 2 -o "$tmp/we8" >/dev/null 2>&1
set -- $(sed -n '3p' "$tmp/we8/cameras.txt")
"$bin" render -q "$tmp/e8.geojson" --size 160x120 --aa 2 --eye "$2,$3,$4" --target "$5,$6,$7" --exposure "$8" --tone-curve -o "$tmp/we8r.png" >/dev/null 2>&1
if /usr/bin/python3 tests/cli/png_same.py "$tmp/we8/frame-0002.png" "$tmp/we8r.png"; then echo "ok   walk-scene-equals-render"; pass=$((pass + 1)); else echo "FAIL walk-scene-equals-render"; fail=$((fail + 1)); fi
# a walk's automatic exposure holds while each frame's own choice stays
# within half a stop: frame to frame it flipped by an eighth of a stop and
# back (17 changes in these 120 frames; --no-adapt keeps that)
changes() { awk 'NR>2 && $8!=p{c++} NR>1{p=$8} END{print c+0}' "$1"; }
"$bin" walk -q "$tmp/e8.geojson" --path "$tmp/e8path.geojson" --size 80x60 --max-frames 120 --aa 1 -o "$tmp/wad" >/dev/null 2>&1
"$bin" walk -q "$tmp/e8.geojson" --path "$tmp/e8path.geojson" --size 80x60 --max-frames 120 --aa 1 --no-adapt -o "$tmp/wnad" >/dev/null 2>&1
ca=$(changes "$tmp/wad/cameras.txt"); cn=$(changes "$tmp/wnad/cameras.txt")
if [ "$ca" -le 2 ] && [ "$cn" -ge 10 ]; then echo "ok   walk-exposure-holds ($ca changes, $cn without)"; pass=$((pass + 1))
else echo "FAIL walk-exposure-holds: $ca exposure changes held, $cn with --no-adapt"; fail=$((fail + 1)); fi
# a held frame drawn again: render --exposure E --tone-curve at its camera
set -- $(sed -n '101p' "$tmp/wad/cameras.txt")
"$bin" render -q "$tmp/e8.geojson" --size 80x60 --eye "$2,$3,$4" --target "$5,$6,$7" --exposure "$8" --tone-curve -o "$tmp/wadr.png" >/dev/null 2>&1
if /usr/bin/python3 tests/cli/png_same.py "$tmp/wad/frame-0100.png" "$tmp/wadr.png"; then echo "ok   walk-held-equals-render-tone-curve"; pass=$((pass + 1)); else echo "FAIL walk-held-equals-render-tone-curve"; fail=$((fail + 1)); fi
# a view darker than about 0.001 cd/m^2 at its percentile stays dark: the
# exposure stops at 1024 and render says so (a courtyard's photon noise
# was exposed 7e6 times to white); here a view of a wall far from any lamp
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{"height":10},"geometry":{"type":"Polygon","coordinates":[[[0,0],[10,0],[10,10],[0,10],[0,0]]]}},{"type":"Feature","properties":{"lamp":true,"z":5,"intensity":1e-5,"radius":30},"geometry":{"type":"Point","coordinates":[5,-5]}}]}' >"$tmp/faint.geojson"
expect render-black-capped 0 "the image is entirely black: its light is under about 0.001 cd/m\^2, where automatic exposure stops \(at 1024" -- \
    "$bin" render "$tmp/faint.geojson" --no-indirect --size 64x48 --eye 5,-20,1.7 --target 5,0,3 -o "$tmp/xdark.png"
sed 's/"intensity":1e-5/"intensity":0.01/' "$tmp/faint.geojson" >"$tmp/faint2.geojson"
expect render-dark-capped 0 "the view is dark: its lit surfaces are under about 0.001 cd/m\^2, where automatic exposure stops \(at 1024" -- \
    "$bin" render "$tmp/faint2.geojson" --no-indirect --size 64x48 --eye 5,-20,1.7 --target 5,0,3 -o "$tmp/xdark2.png"
# the automatic exposure does not hang on how the dark was computed: the
# aerial view read from the atlas (photon charts: 0 where no photon fell)
# and shaded pixel by pixel (a gather: 1e-4 cd/m^2 there) choose within an
# eighth of a stop (before the lit pixels were cut at 12 stops below the
# 99.9th percentile: 0.2973 and 0.4585 here, 5 eighths apart)
ea=$("$bin" render fixtures/eixample-4x4.geojson --view aerial --size 320x240 -o "$tmp/xea.png" 2>&1 | sed -n 's/^exposure: \([0-9.e-]*\) .*/\1/p')
ep=$("$bin" render fixtures/eixample-4x4.geojson --view aerial --size 320x240 --per-pixel -o "$tmp/xep.png" 2>&1 | sed -n 's/^exposure: \([0-9.e-]*\) .*/\1/p')
if [ -n "$ea" ] && [ -n "$ep" ] && awk -v a="$ea" -v b="$ep" 'BEGIN { d = log(a / b) / log(2); exit !(d < 0.13 && d > -0.13) }'; then
    echo "ok   render-exposure-atlas-per-pixel ($ea, $ep)"; pass=$((pass + 1))
else echo "FAIL render-exposure-atlas-per-pixel: atlas $ea, per pixel $ep"; fail=$((fail + 1)); fi
# a radiance atlas laid out coarser than asked because the block is small
# says so, with the remedy (a kiosk pass found a bake's frames at 4 m
# between points without a word); none when the atlas has its spacing
expect render-atlas-reduced-note 0 "radiance atlas at reduced quality to fit the block: points 0.71 m apart instead of 0.50 .*a larger --mem for finer points" -- \
    "$bin" render fixtures/eixample-4x4.geojson --mem 24M --size 160x120 -o "$tmp/xatl.png"
expect render-atlas-no-note 0 "" -- "$bin" render fixtures/eixample-4x4.geojson --size 160x120 -o "$tmp/xatl.png"
if grep -q "radiance atlas" "$tmp/out"; then echo "FAIL render-atlas-no-note: a note at the default block"; fail=$((fail + 1)); fi
# a --no-aerial bake (made small) drawn without --mem gets a block with
# room for its atlas at the spacing asked, as a scene's default block has
# (it drew from points 4 m apart on gen eixample 30 30: blocky lamp pools);
# with --mem, the block given, and the note
# (gen eixample 12 12 in 32M: its own block, 50 MB, left points 1.41 m apart)
"$bin" gen eixample 12 12 >"$tmp/e12.geojson"
"$bin" bake -q "$tmp/e12.geojson" --no-aerial --mem 32M --frames 2 --photons 4000 --max-size 160x120 -o "$tmp/na.plxb" >/dev/null 2>&1
expect render-bake-atlas-room 0 "" -- "$bin" render "$tmp/na.plxb" --size 160x120 -o "$tmp/xna.png"
if grep -q "radiance atlas" "$tmp/out"; then echo "FAIL render-bake-atlas-room: the atlas was reduced"; sed 's/^/    /' "$tmp/out"; fail=$((fail + 1)); fi
expect render-bake-atlas-mem 0 "radiance atlas at reduced quality to fit the block beside the bake: points 1.41 m apart instead of 0.50" -- \
    "$bin" render "$tmp/na.plxb" --mem 50M --size 160x120 -o "$tmp/xna.png"
expect walk-bake-atlas-room 0 "" -- "$bin" walk "$tmp/na.plxb" --path "$tmp/endpath.geojson" --size 160x120 --max-frames 2 -o "$tmp/naw"
if grep -q "radiance atlas" "$tmp/out"; then echo "FAIL walk-bake-atlas-room: the atlas was reduced"; sed 's/^/    /' "$tmp/out"; fail=$((fail + 1)); fi
# a walk of one frame writes it without the writer thread: its line of
# cameras.txt too
"$bin" walk -q fixtures/eixample-4x4.geojson --path "$tmp/endpath.geojson" --size 32x24 --max-frames 1 --no-indirect -o "$tmp/w1cam" >/dev/null 2>&1
if [ "$(grep -vc '^#' "$tmp/w1cam/cameras.txt" 2>/dev/null)" = 1 ] && [ -s "$tmp/w1cam/frame-0001.png" ]; then
    echo "ok   walk-one-frame-cameras"; pass=$((pass + 1))
else echo "FAIL walk-one-frame-cameras: $(cat "$tmp/w1cam/cameras.txt" 2>/dev/null | wc -l) lines"; fail=$((fail + 1)); fi
expect walk-atlas-reduced-note 0 "^polarlux walk: radiance atlas at reduced quality to fit the block: points 0.71 m apart" -- \
    "$bin" walk fixtures/eixample-4x4.geojson --mem 24M --path "$tmp/endpath.geojson" --size 160x120 --max-frames 2 -o "$tmp/atlw"
# a held walk: a frame with no lit surface keeps the held exposure (it
# took automatic exposure's 1 for an empty image, then jumped back), and
# a frame black at the held cap (724: half a stop short of 1024) says its
# light is too faint (it blamed the lamps)
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{"height":10},"geometry":{"type":"Polygon","coordinates":[[[0,0],[10,0],[10,10],[0,10],[0,0]]]}},{"type":"Feature","properties":{"height":10},"geometry":{"type":"Polygon","coordinates":[[[100,0],[110,0],[110,10],[100,10],[100,0]]]}},{"type":"Feature","properties":{"lamp":true,"z":5,"intensity":1000,"radius":30},"geometry":{"type":"Point","coordinates":[5,-5]}},{"type":"Feature","properties":{"lamp":true,"z":5,"intensity":1e-5,"radius":30},"geometry":{"type":"Point","coordinates":[105,-5]}}]}' >"$tmp/two.geojson"
printf '{"type":"Feature","properties":{"units":"m","targets":[[5,0,3],[5,-120,300]]},"geometry":{"type":"LineString","coordinates":[[5,-20,1.7],[5,-120,1.7]]}}' >"$tmp/twosky.geojson"
"$bin" walk -q "$tmp/two.geojson" --path "$tmp/twosky.geojson" --no-indirect --size 64x48 --speed 100 --fps 1 -o "$tmp/wsky" >/dev/null 2>&1
if [ "$(awk 'NR>1{print $8}' "$tmp/wsky/cameras.txt" | sort -u | wc -l)" -eq 1 ]; then echo "ok   walk-held-empty-frame"; pass=$((pass + 1))
else echo "FAIL walk-held-empty-frame: the exposure moved at a frame with no lit surface"; fail=$((fail + 1)); fi
printf '{"type":"Feature","properties":{"units":"m","targets":[[5,0,3],[105,0,3]]},"geometry":{"type":"LineString","coordinates":[[5,-20,1.7],[105,-20,1.7]]}}' >"$tmp/twofaint.geojson"
expect walk-black-capped 0 "1 of 2 frames are entirely black \(the first: frame 2\): its light is under about 0.001 cd/m\^2, where automatic exposure stops" -- \
    "$bin" walk "$tmp/two.geojson" --path "$tmp/twofaint.geojson" --no-indirect --size 64x48 --speed 100 --fps 1 -o "$tmp/wfaint"
# walk --tone-curve: the fixed exposure with the curve, as render's
"$bin" walk -q "$tmp/two.geojson" --path "$tmp/twofaint.geojson" --no-indirect --size 64x48 --speed 100 --fps 1 --exposure 0.3 --tone-curve -o "$tmp/wtc" >/dev/null 2>&1
"$bin" render -q "$tmp/two.geojson" --no-indirect --size 64x48 --aa 2 --eye 5,-20,1.7 --target 5,0,3 --exposure 0.3 --tone-curve -o "$tmp/wtcr.png" >/dev/null 2>&1
"$bin" render -q "$tmp/two.geojson" --no-indirect --size 64x48 --aa 2 --eye 5,-20,1.7 --target 5,0,3 --exposure 0.3 -o "$tmp/wtcl.png" >/dev/null 2>&1
if /usr/bin/python3 tests/cli/png_same.py "$tmp/wtc/frame-0001.png" "$tmp/wtcr.png" && ! /usr/bin/python3 tests/cli/png_same.py "$tmp/wtcr.png" "$tmp/wtcl.png"; then
    echo "ok   walk-tone-curve"; pass=$((pass + 1)); else echo "FAIL walk-tone-curve"; fail=$((fail + 1)); fi
expect walk-no-adapt-fixed 0 "warning: --no-adapt has no effect with --exposure" -- \
    "$bin" walk "$tmp/two.geojson" --path "$tmp/twofaint.geojson" --no-indirect --size 32x24 --speed 100 --fps 1 --exposure 0.3 --no-adapt -o "$tmp/wna"
expect mem-terabytes 0 "^buildings:" -- "$bin" info fixtures/tiny.geojson --mem 0.0001T
expect bake-texel-range 2 "^polarlux bake: --texel '0.001' is not a number of metres from 0.01 to 1e4" -- \
    "$bin" bake fixtures/tiny.geojson --texel 0.001 -o "$tmp/xt.plxb"
long=$(printf '%04000d' 0)
expect walk-out-too-long 2 "^polarlux walk: -o: the folder's path is longer than 4000 bytes" -- \
    "$bin" walk fixtures/tiny.geojson --path "$tmp/twofaint.geojson" -o "$tmp/$long"
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{},"geometry":{"type":"LineString","coordinates":[[0,-5],[20,-5]]}}]} x' >"$tmp/rtrail.geojson"
expect route-path-trailing 1 "^polarlux route: .*rtrail\.geojson: malformed JSON at byte 168 \(line 1, column 169\)$" -- \
    "$bin" route fixtures/tiny.geojson --path "$tmp/rtrail.geojson"
printf '{"type":"FeatureCollection","features":[]} junk' >"$tmp/ltrail.geojson"
expect lamps-trailing 1 "^polarlux info: --lamps .*ltrail\.geojson: malformed JSON at byte 43 \(line 1, column 44\) \(a lamp file is GeoJSON or CSV\)$" -- \
    "$bin" info fixtures/tiny.geojson --lamps "$tmp/ltrail.geojson"
# a frame black because the held exposure has not caught up says so (the
# walk's own options were read: it blamed --exposure 1)
sed 's/"intensity":1e-5/"intensity":0.0005/' "$tmp/two.geojson" >"$tmp/two4.geojson"
expect walk-black-held 0 "1 of 2 frames are entirely black \(the first: frame 2\): its exposure 5.187, held from the frames before and following the view at a few stops a second, is too low for it" -- \
    "$bin" walk "$tmp/two4.geojson" --path "$tmp/twofaint.geojson" --no-indirect --size 64x48 --speed 100 --fps 1 -o "$tmp/wheld"
# no lamps comes first among the reasons (a view of no building said the
# camera looked away)
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{"height":10},"geometry":{"type":"Polygon","coordinates":[[[0,0],[10,0],[10,10],[0,10],[0,0]]]}}]}' >"$tmp/nolamps.geojson"
expect render-black-no-lamps 0 "the image is entirely black: the scene has no lamps" -- \
    "$bin" render "$tmp/nolamps.geojson" --size 32x24 --eye 5,-20,1.7 --target 5,-40,1.7 -o "$tmp/xnl.png"
# a path that climbs high without targets looks level into the sky: said
printf '{"type":"Feature","properties":{"units":"m"},"geometry":{"type":"LineString","coordinates":[[5,-20,1.7],[5,-120,300]]}}' >"$tmp/climb.geojson"
expect walk-high-level-hint 0 "warning: the eye rises to 300 m and looks level, 10 m ahead along the path at its own height: the city is below those frames; --pitch DEG looks down along the path, properties.targets" -- \
    "$bin" walk "$tmp/two.geojson" --path "$tmp/climb.geojson" --no-indirect --size 32x24 --speed 100 --fps 1 -o "$tmp/wclimb"
# --pitch: a path without targets looked at DEG degrees below level (10 m
# ahead, 10 tan(DEG) m down): a flight at 300 m toward the lit building
# sees it, where the level view sees only sky; no level-view hint with
# it; refused outside 0..89; said to do nothing on a path with targets
printf '{"type":"Feature","properties":{"units":"m"},"geometry":{"type":"LineString","coordinates":[[5,-300,300],[5,-200,300]]}}' >"$tmp/fly300.geojson"
expect walk-pitch-camera 0 "^1 5 -300 300 5 -290 290 " -- sh -c "'$bin' walk -q '$tmp/two.geojson' --path '$tmp/fly300.geojson' --pitch 45 --no-indirect --size 32x24 --speed 100 --fps 1 -o '$tmp/wpitch' >/dev/null && cat '$tmp/wpitch/cameras.txt'"
expect walk-pitch-lit 0 "^0$" -- sh -c "'$bin' walk '$tmp/two.geojson' --path '$tmp/fly300.geojson' --pitch 45 --no-indirect --size 32x24 --speed 100 --fps 1 -o '$tmp/wpitch1' 2>&1 | grep -c 'black\\|looks level' || true"
expect walk-level-black 0 "every frame is entirely black" -- \
    "$bin" walk "$tmp/two.geojson" --path "$tmp/fly300.geojson" --no-indirect --size 32x24 --speed 100 --fps 1 -o "$tmp/wpitch2"
expect walk-high-level-hint-pitch 0 "the city is below those frames; --pitch DEG looks down along the path" -- \
    "$bin" walk "$tmp/two.geojson" --path "$tmp/fly300.geojson" --no-indirect --size 32x24 --speed 100 --fps 1 -o "$tmp/wpitch3"
expect walk-pitch-range 2 "--pitch '90' is not a number of degrees from 0 to 89" -- "$bin" walk "$tmp/two.geojson" --path "$tmp/fly300.geojson" --pitch 90 -o "$tmp/wpitch4"
expect walk-pitch-targets 0 "warning: --pitch has no effect: .*twofaint.geojson has properties.targets, which aim the camera" -- \
    "$bin" walk "$tmp/two.geojson" --path "$tmp/twofaint.geojson" --pitch 20 --no-indirect --size 32x24 --speed 100 --fps 1 -o "$tmp/wpitch5"
# a held walk follows a change at 4 stops a second (at 25 fps an eighth
# of a stop a frame): from a bright wall to one lit a thousand times less,
# no frame's exposure is more than an eighth of a stop from the last
# (without holding, one frame jumps 10 stops)
sed 's/"intensity":1e-5/"intensity":1/' "$tmp/two.geojson" >"$tmp/two2.geojson"
maxjump() { awk 'NR>2{d=log($8/p)/log(2); if(d<0)d=-d; if(d>m)m=d} NR>1{p=$8} END{printf "%.4f", m}' "$1"; }
"$bin" walk -q "$tmp/two2.geojson" --path "$tmp/twofaint.geojson" --no-indirect --size 64x48 --speed 100 --fps 25 -o "$tmp/wab" >/dev/null 2>&1
"$bin" walk -q "$tmp/two2.geojson" --path "$tmp/twofaint.geojson" --no-indirect --size 64x48 --speed 100 --fps 25 --no-adapt -o "$tmp/wabn" >/dev/null 2>&1
ja=$(maxjump "$tmp/wab/cameras.txt"); jn=$(maxjump "$tmp/wabn/cameras.txt")
if [ "$ja" = "0.1250" ] && [ "$(awk -v j="$jn" 'BEGIN { print (j > 2) }')" = 1 ]; then echo "ok   walk-exposure-rate ($ja stops a frame at most, $jn without holding)"; pass=$((pass + 1))
else echo "FAIL walk-exposure-rate: $ja stops a frame held, $jn without"; fail=$((fail + 1)); fi
# the exposure falls four times as fast as it rises: from the faint wall
# to the bright one at 25 fps, half a stop a frame at most (it stayed
# blown out for seconds at an eighth)
printf '{"type":"Feature","properties":{"units":"m","targets":[[105,0,3],[5,0,3]]},"geometry":{"type":"LineString","coordinates":[[105,-20,1.7],[5,-20,1.7]]}}' >"$tmp/twoback.geojson"
"$bin" walk -q "$tmp/two2.geojson" --path "$tmp/twoback.geojson" --no-indirect --size 64x48 --speed 100 --fps 25 -o "$tmp/wba" >/dev/null 2>&1
jb=$(maxjump "$tmp/wba/cameras.txt")
if [ "$jb" = "0.5000" ]; then echo "ok   walk-exposure-falls-faster ($jb stops a frame at most)"; pass=$((pass + 1))
else echo "FAIL walk-exposure-falls-faster: $jb stops a frame at most"; fail=$((fail + 1)); fi
expect walk-max-frames-range 2 "--max-frames '1000001' is not a whole number from 1 to 1000000" -- \
    "$bin" walk "$tmp/two.geojson" --path "$tmp/climb.geojson" --max-frames 1000001 -o "$tmp/wmr"
expect render-tone-curve-needs-exposure 2 "^polarlux render: --tone-curve needs --exposure E" -- "$bin" render "$tmp/e.plxb" --tone-curve -o "$tmp/x.png"
# on a lon/lat scene cameras.txt is in lon/lat (it was local metres, which
# render refuses there): a frame's camera fed back to render gives the frame
expect walk-lonlat-cameras 0 "^# frame eye_lon eye_lat eye_z target_lon target_lat target_z exposure" -- \
    sh -c "'$bin' walk -q fixtures/helsinki-centre.geojson --path fixtures/helsinki-walk.geojson --size 80x60 --max-frames 2 --aa 1 --no-indirect --no-glow --exposure 1 -o '$tmp/wll' >/dev/null && cat '$tmp/wll/cameras.txt'"
set -- $(sed -n '3p' "$tmp/wll/cameras.txt")
"$bin" render -q fixtures/helsinki-centre.geojson --size 80x60 --no-indirect --no-glow --exposure 1 --eye "$2,$3,$4" --target "$5,$6,$7" -o "$tmp/wllr.png" >/dev/null 2>&1
if /usr/bin/python3 tests/cli/png_same.py "$tmp/wll/frame-0002.png" "$tmp/wllr.png"; then echo "ok   walk-lonlat-cameras-render"; pass=$((pass + 1)); else echo "FAIL walk-lonlat-cameras-render"; fail=$((fail + 1)); fi
expect walk-default 0 "^walk: [0-9]+ frames 160x120 .*aa 2" -- "$bin" walk -q "$tmp/e.plxb" --path "$tmp/path.geojson" --size 160x120 --fps 0.1 -o "$tmp/w2"
set -- $(sed -n '2p' "$tmp/w2/cameras.txt")
"$bin" render -q "$tmp/e.plxb" --size 160x120 --aa 2 --eye "$2,$3,$4" --target "$5,$6,$7" -o "$tmp/w2r.png" >/dev/null 2>&1
if /usr/bin/python3 tests/cli/png_same.py "$tmp/w2/frame-0001.png" "$tmp/w2r.png"; then echo "ok   walk-default-equals-render"; pass=$((pass + 1)); else echo "FAIL walk-default-equals-render"; fail=$((fail + 1)); fi
cp "$tmp/w2/cameras.txt" "$tmp/w2cams.txt"
"$bin" walk -q "$tmp/e.plxb" --path "$tmp/path.geojson" --size 320x240 -o "$tmp/w2" >/dev/null 2>&1
if cmp -s "$tmp/w2/cameras.txt" "$tmp/w2cams.txt"; then echo "ok   walk-fail-keeps-cameras"; pass=$((pass + 1))
else echo "FAIL walk-fail-keeps-cameras: a walk whose first frame failed changed the folder's cameras.txt"; fail=$((fail + 1)); fi
if [ -s "$tmp/w2/contact.png" ]; then echo "ok   walk-contact-sheet"; pass=$((pass + 1)); else echo "FAIL walk-contact-sheet"; fail=$((fail + 1)); fi
# portrait frames are shrunk into the sheet by their longer side, as
# landscape ones by theirs (360x640 frames were not shrunk: a 1440x640
# sheet where four 640x360 frames give 1280x180)
"$bin" walk -q fixtures/eixample-4x4.geojson --path "$tmp/path.geojson" --size 360x640 --max-frames 4 --aa 1 --no-indirect -o "$tmp/wport" >/dev/null 2>&1
set -- $(od -An -tu1 -j16 -N8 "$tmp/wport/contact.png")
if [ $# -eq 8 ] && [ $(($3 * 256 + $4)) -eq 720 ] && [ $(($7 * 256 + $8)) -eq 320 ]; then echo "ok   walk-contact-portrait"; pass=$((pass + 1))
else echo "FAIL walk-contact-portrait: sheet header bytes $*, want 720x320"; fail=$((fail + 1)); fi
# a frame narrower than the shrink factor keeps a pixel in the sheet (3x1600
# frames failed the walk: "size 0x400")
expect walk-contact-narrow 0 "^walk: 4 frames 3x1600 " -- \
    "$bin" walk -q fixtures/eixample-4x4.geojson --path "$tmp/path.geojson" --size 3x1600 --max-frames 4 --aa 1 --no-indirect -o "$tmp/wnar"
# illum traces photons again for its lamps in a bake's reduced buffers: the note says the bake made them so
"$bin" bake -q fixtures/helsinki-centre.geojson --mem 16M --no-aerial --no-polar --max-size 320x240 --frames 2 -o "$tmp/hs.plxb" >/dev/null 2>&1
echo "0 0 1.5" >"$tmp/hs.txt"
expect illum-bake-reduced 0 "^polarlux illum: indirect light at reduced quality as the bake was made \(to fit its --mem when baked\): photon buffers" -- \
    "$bin" illum "$tmp/hs.plxb" --points "$tmp/hs.txt" --frames 2
expect illum-bake-reduced-quiet 0 "" -- "$bin" illum -q "$tmp/hs.plxb" --points "$tmp/hs.txt" --frames 2
if grep -q "reduced quality" "$tmp/out"; then echo "FAIL illum-bake-reduced-quiet: --quiet printed the note"; fail=$((fail + 1)); fi
# slow frames in a block given with --mem: a larger --mem is named too
expect walk-slower-mem 0 "fall behind on this machine; --aa 1 \(one sample a pixel\), a smaller --size or a lower --fps keep up; a larger --mem may too" -- \
    "$bin" walk "$tmp/e.plxb" --fps 10000 --mem 1G --path "$tmp/endpath.geojson" --size 160x120 --max-frames 3 -o "$tmp/endw"
# a walk that cannot make its contact sheet says an earlier walk's is left in the folder
mkdir -p "$tmp/wold"; echo old >"$tmp/wold/contact.png"
expect walk-contact-stale 0 "no contact sheet: .*; $tmp/wold/contact.png is an earlier walk's, left as it was" -- \
    "$bin" walk fixtures/tiny.geojson --path "$tmp/path.geojson" --size 640x480 --max-frames 2 --aa 1 --no-indirect --mem 8M -o "$tmp/wold"
# a frame's delay is 1/fps exactly where 16-bit terms allow (it was
# whole milliseconds: 33/1000 at 30 and at 29.97 fps)
"$bin" walk -q "$tmp/e.plxb" --path "$tmp/path.geojson" --size 32x24 --fps 29.97 --max-frames 2 --aa 1 --no-indirect -o "$tmp/wfps" >/dev/null 2>&1
expect walk-apng-delay 0 "^100/2997$" -- /usr/bin/python3 -c "
import struct,sys
d=open(sys.argv[1],'rb').read(); i=d.index(b'fcTL')
n,m=struct.unpack('>HH',d[i+24:i+28]); print('%d/%d'%(n,m))" "$tmp/wfps/walk.png"
# the animated PNG against the frame files (an independent reader: tests/cli/apng_check.py)
if /usr/bin/python3 tests/cli/apng_check.py "$tmp/w2/walk.png" "$tmp/w2"/frame-*.png >/dev/null; then echo "ok   walk-apng"; pass=$((pass + 1)); else echo "FAIL walk-apng"; fail=$((fail + 1)); fi
# threads (README "Threads"): the same bytes with 1 and 2
"$bin" render -q fixtures/eixample-4x4.geojson --view aerial --frames 2 --size 160x120 --threads 1 -o "$tmp/t1.png" --pfm "$tmp/t1.pfm" >/dev/null 2>&1
"$bin" render -q fixtures/eixample-4x4.geojson --view aerial --frames 2 --size 160x120 --threads 2 -o "$tmp/t2.png" --pfm "$tmp/t2.pfm" >/dev/null 2>&1
if cmp -s "$tmp/t1.png" "$tmp/t2.png" && cmp -s "$tmp/t1.pfm" "$tmp/t2.pfm"; then echo "ok   render-threads-same"; pass=$((pass + 1)); else echo "FAIL render-threads-same"; fail=$((fail + 1)); fi
expect render-threads-bad 2 "--threads needs a number of threads from 1 to 16" -- "$bin" render fixtures/tiny.geojson --threads 0 -o "$tmp/x.png"
printf '{"type":"LineString","coordinates":[[0,0,200],[10,0,250]]}' >"$tmp/high.geojson"
expect walk-high-street-hint 0 "^polarlux walk: warning: the eye stays 200 m or more above the ground: --view aerial draws views from above faster" -- \
    "$bin" walk "$tmp/e.plxb" --path "$tmp/high.geojson" --size 32x24 --fps 0.5 --aa 1 --no-indirect -o "$tmp/wh"
# frames that read the radiance atlas take as long as street or aerial
# views: no word (it said "faster" there too, where it was not)
"$bin" walk "$tmp/e.plxb" --path "$tmp/high.geojson" --size 32x24 --fps 0.5 --aa 1 -o "$tmp/wh2" >"$tmp/out" 2>&1
if [ $? -eq 0 ] && ! grep -q -- "--view aerial" "$tmp/out"; then echo "ok   walk-high-atlas-no-hint"; pass=$((pass + 1)); else echo "FAIL walk-high-atlas-no-hint"; sed 's/^/    /' "$tmp/out" | head; fail=$((fail + 1)); fi
# --view aerial on a walk whose frames all read the radiance atlas changes
# no byte: said (it was taken silently)
expect walk-view-aerial-atlas 0 "--view aerial changed nothing: the camera comes from the path" -- \
    "$bin" walk "$tmp/e.plxb" --path "$tmp/high.geojson" --size 32x24 --fps 0.5 --aa 1 --view aerial -o "$tmp/wh3"
# ... and when some of them are black (a reviewer's path from the city up
# to the sky: the warning was lost when black frames stopped counting)
printf '{"type":"Feature","properties":{"targets":[[266,266,0],[10,0,5000]]},"geometry":{"type":"LineString","coordinates":[[0,0,200],[10,0,250]]}}' >"$tmp/mix.geojson"
expect walk-view-aerial-atlas-some-black 0 "--view aerial changed nothing: the camera comes from the path" -- \
    "$bin" walk "$tmp/e.plxb" --path "$tmp/mix.geojson" --size 32x24 --fps 0.5 --aa 1 --view aerial -o "$tmp/wmix"
# ... but not when the frames show sky alone (they shade nothing either;
# it blamed the atlas with --per-pixel given)
printf '{"type":"Feature","properties":{"targets":[[30,30.5,500],[31,30.5,500]]},"geometry":{"type":"LineString","coordinates":[[30,30,2],[31,30,2]]}}' >"$tmp/sky.geojson"
"$bin" walk fixtures/tiny.geojson --path "$tmp/sky.geojson" --size 32x24 --fps 1 --speed 1 --per-pixel --view aerial -o "$tmp/wsky2" >"$tmp/out" 2>&1
if [ $? -eq 0 ] && ! grep -q -- "changed nothing" "$tmp/out"; then echo "ok   walk-view-aerial-sky-no-blame"; pass=$((pass + 1)); else echo "FAIL walk-view-aerial-sky-no-blame"; sed 's/^/    /' "$tmp/out" | head; fail=$((fail + 1)); fi
# an eye inside a building: its frames show the inside of its walls, 3.7 s
# each on gen eixample 30 30 (every pixel computed), and walk said nothing
printf '{"type":"LineString","coordinates":[[5,5,1.7],[5,6,1.7]]}' >"$tmp/inside.geojson"
expect walk-eye-inside 0 "^polarlux walk: warning: 2 of 2 frames have the eye inside a building \(the first: frame 1 at \(5\.00, 5\.00, 1\.70\)\)" -- \
    "$bin" walk fixtures/tiny.geojson --path "$tmp/inside.geojson" --size 32x24 --fps 1 --speed 1 --no-indirect -o "$tmp/wi"
if ! grep -q "entirely black" "$tmp/out"; then echo "ok   walk-eye-inside-not-dark"; pass=$((pass + 1)); else echo "FAIL walk-eye-inside-not-dark"; fail=$((fail + 1)); fi
# ... said at the first such frame too, before the frames after it (a
# walk of hundreds of them ran for minutes first): the line comes before
# the summary's
if grep -q "^polarlux walk: warning: frame 1 at (5.00, 5.00, 1.70): the eye is inside a building" "$tmp/out" &&
   [ "$(grep -n 'frame 1 at (5.00, 5.00, 1.70): the eye is inside' "$tmp/out" | cut -d: -f1)" -lt "$(grep -n '2 of 2 frames have the eye inside' "$tmp/out" | cut -d: -f1)" ]; then
    echo "ok   walk-eye-inside-at-once"; pass=$((pass + 1)); else echo "FAIL walk-eye-inside-at-once"; sed 's/^/    /' "$tmp/out" | head; fail=$((fail + 1)); fi
# --max-frames cutting the path short is said, and the summary gives the
# metres walked (it gave the path's length: 1000 frames "165.2 m" walked 56 m)
printf '{"type":"LineString","coordinates":[[0,0,1.7],[0,10,1.7]]}' >"$tmp/ten.geojson"
expect walk-max-frames-cut 0 "^polarlux walk: warning: --max-frames 3 stops the walk at 2\.0 m of the path's 10\.0 m \(11 frames would walk it all\)" -- \
    "$bin" walk fixtures/tiny.geojson --path "$tmp/ten.geojson" --size 32x24 --fps 1 --speed 1 --max-frames 3 --no-indirect -o "$tmp/wmf"
if grep -q "^walk: 3 frames 32x24 (2\.0 m of 10\.0 m at 1 m/s" "$tmp/out"; then echo "ok   walk-max-frames-summary"; pass=$((pass + 1)); else echo "FAIL walk-max-frames-summary"; sed 's/^/    /' "$tmp/out"; fail=$((fail + 1)); fi
# an earlier, longer walk's frames left in the folder are pointed out
expect walk-stale-frames 0 "^polarlux walk: warning: .*/wmf holds frame-0003\.png and maybe later frames from an earlier walk: this walk writes frames 1 to 2 and leaves them" -- \
    "$bin" walk fixtures/tiny.geojson --path "$tmp/ten.geojson" --size 32x24 --fps 1 --speed 1 --max-frames 2 --no-indirect -o "$tmp/wmf"
# the median of an even count is the mean of the two middle frames (it was
# the slower one): with two frames, the mean of both
"$bin" walk -q fixtures/tiny.geojson --path "$tmp/ten.geojson" --size 32x24 --fps 1 --speed 1 --max-frames 2 --no-indirect -o "$tmp/wmf" >"$tmp/out" 2>&1
set -- $(sed -n 's/^frame time: median \([0-9.]*\) ms, p95 [0-9.]* ms, mean \([0-9.]*\) ms.*/\1 \2/p' "$tmp/out")
if [ -n "${2:-}" ] && [ "$1" = "$2" ]; then echo "ok   walk-even-median"; pass=$((pass + 1)); else echo "FAIL walk-even-median: $*"; fail=$((fail + 1)); fi
# a keyframe whose target is its eye (render refuses that camera; walk looked 1 m east)
printf '{"type":"LineString","coordinates":[[0,0,50],[10,0,50]],"properties":{"targets":[[0,0,50],[10,5,0]]}}' >"$tmp/kt.geojson"
expect walk-target-is-eye 1 "^polarlux walk: .*kt\.geojson: properties\.targets: position 0's target is its eye \(0, 0, 50\): the camera would look nowhere$" -- \
    "$bin" walk -q fixtures/tiny.geojson --path "$tmp/kt.geojson" --no-indirect -o "$tmp/wmf"
# a lon/lat scene and a path with one position out of lon/lat range: a
# typo, refused (the whole path was read as metres, far from the city)
printf '{"type":"LineString","coordinates":[[24.944,60.168],[24.946,95.0]]}' >"$tmp/ll.geojson"
expect walk-lonlat-mixed 1 "position 0 is lon/lat \(the scene's coordinates\) but position 1 is not: give every position in lon/lat, or all in local metres with properties\.units \"m\"$" -- \
    "$bin" walk -q fixtures/helsinki-centre.geojson --path "$tmp/ll.geojson" --no-indirect -o "$tmp/wmf"
# lon/lat positions and a target out of lon/lat range, or in metres: refused
# (a latitude of 95 was projected far north without a word, and render
# refused the camera cameras.txt held)
printf '{"type":"Feature","properties":{"targets":[[24.945,95,0],[24.947,60.1679,0]]},"geometry":{"type":"LineString","coordinates":[[24.9436,60.1677,10],[24.9465,60.1678,20]]}}' >"$tmp/llt.geojson"
expect walk-lonlat-targets 1 "properties\.targets: position 0 is not lon/lat \(-180\.\.180, -90\.\.90\) and the path's positions are: give the targets in the positions' coordinates$" -- \
    "$bin" walk -q fixtures/helsinki-centre.geojson --path "$tmp/llt.geojson" --no-indirect -o "$tmp/wlt"
printf '{"type":"Feature","properties":{"targets":[[24.945,60.1679,0],[200,-430,0]]},"geometry":{"type":"LineString","coordinates":[[24.9436,60.1677,10],[24.9465,60.1678,20]]}}' >"$tmp/llm.geojson"
expect walk-lonlat-targets-metres 1 "properties\.targets: position 1 is not lon/lat" -- \
    "$bin" walk -q fixtures/helsinki-centre.geojson --path "$tmp/llm.geojson" --no-indirect -o "$tmp/wlt"
# a target that is not numbers is told so, not that it is not lon/lat
printf '{"type":"Feature","properties":{"targets":[[24.945,60.1679,0],["x",60.17]]},"geometry":{"type":"LineString","coordinates":[[24.9436,60.1677,10],[24.9465,60.1678,20]]}}' >"$tmp/llx.geojson"
expect walk-lonlat-targets-shape 1 "properties\.targets: position 1 is not \[x, y\] or \[x, y, z\] of finite numbers$" -- \
    "$bin" walk -q fixtures/helsinki-centre.geojson --path "$tmp/llx.geojson" --no-indirect -o "$tmp/wlt"
printf '{"type":"LineString","coordinates":[[1,2]]}' >"$tmp/short.geojson"
expect walk-short-path 1 "^polarlux walk: $tmp/short\.geojson: the LineString needs at least 2 positions$" -- "$bin" walk -q "$tmp/e.plxb" --path "$tmp/short.geojson" -o "$tmp/w3"
# a coordinate beyond 1e7 m (it made the frame count overflow, then "out of
# memory for the animation"), and -o naming a file (it said only the path)
printf '{"type":"LineString","coordinates":[[1,2,1e300],[1,9,2]]}' >"$tmp/huge.geojson"
expect walk-huge-coordinate 1 "^polarlux walk: $tmp/huge\.geojson: position 0 \(1, 2, 1e\+300\) is more than 1e7 m from the origin$" -- \
    "$bin" walk -q "$tmp/e.plxb" --path "$tmp/huge.geojson" -o "$tmp/w3"
# a path in metres on a lon/lat scene says how it was read; a position of 4 numbers is refused (it was read silently)
printf '{"type":"LineString","coordinates":[[-45,-43,1.7],[-40,-43,1.7]]}' >"$tmp/metres-path.geojson"
expect walk-metres-on-lonlat-hint 1 "is more than 1e7 m from the scene's origin \(read as lon/lat, as the scene is; a path in metres says properties\.units \"m\"\)$" -- \
    "$bin" walk -q fixtures/helsinki-centre.geojson --no-indirect --path "$tmp/metres-path.geojson" -o "$tmp/w3"
printf '{"type":"LineString","properties":{"units":"m"},"coordinates":[[1,2,1.7,9],[1,9,2]]}' >"$tmp/four.geojson"
expect walk-four-numbers 1 "position 0 is not \[x, y\] or \[x, y, z\] of finite numbers$" -- \
    "$bin" walk -q "$tmp/e.plxb" --path "$tmp/four.geojson" -o "$tmp/w3"
# a pan on the spot: the eye stays, the targets turn the view at --speed (it gave one frame, the targets unused)
printf '{"type":"Feature","properties":{"units":"m","targets":[[60,133,1.5],[70,143,1.5],[50,153,1.5]]},"geometry":{"type":"LineString","coordinates":[[50,133],[50,133],[50,133]]}}' >"$tmp/pan.geojson"
expect walk-pan-on-the-spot 0 "^walk: 653 frames 32x24 \(36\.5 m of 36\.5 m " -- "$bin" walk fixtures/tiny.geojson --path "$tmp/pan.geojson" --size 32x24 --no-indirect --aa 1 -o "$tmp/pan"
expect walk-pan-cameras 0 "^299 50 133 1\.7 67\.72[0-9]* 144\.13[0-9]* 1\.5 " -- cat "$tmp/pan/cameras.txt"
printf 'x' >"$tmp/wfile"
expect walk-out-is-file 1 "^polarlux walk: $tmp/wfile: not a folder" -- \
    "$bin" walk -q "$tmp/e.plxb" --path "$tmp/path.geojson" --size 32x24 -o "$tmp/wfile"
# exposure 0 drew a black image, called dark for want of lamps
expect render-exposure-zero 2 "--exposure '0' is not a number above 0, up to 1e9" -- "$bin" render fixtures/tiny.geojson --exposure 0 -o "$tmp/x.png"
expect walk-exposure-zero 2 "--exposure '0' is not a number above 0, up to 1e9" -- "$bin" walk fixtures/tiny.geojson --path "$tmp/ten.geojson" --exposure 0 -o "$tmp/wmf"
expect render-aa-bad 2 "--aa '0' is not a whole number from 1 to 16" -- "$bin" render fixtures/tiny.geojson --aa 0 -o "$tmp/x.png"
# adaptive anti-aliasing (README "Anti-aliasing") against every sample
expect render-aa-adaptive 0 "^anti-aliasing 2x2: the later samples shaded [0-9.]+% of the pixels \(adaptive" -- \
    "$bin" render -q "$tmp/e.plxb" --size 160x120 --aa 2 -o "$tmp/aa2.png"
expect render-aa-full 0 "^anti-aliasing 2x2: the later samples shaded 100\.0% of the pixels \(every sample\)" -- \
    "$bin" render -q "$tmp/e.plxb" --size 160x120 --aa 2 --aa-full -o "$tmp/aa2f.png"
expect render-aa-dense 0 "^anti-aliasing 2x2: the later samples shaded 100\.0% of the pixels \(every sample: edges at more than half the pixels; --aa 1 is faster\)" -- \
    "$bin" render -q "$tmp/e.plxb" --view aerial --size 160x120 --aa 2 -o "$tmp/aa2d.png"
# a walk from high up (dense: every sample) down to the street (adaptive), the
# targets in a bare LineString's own properties
printf '{"type":"LineString","coordinates":[[266,200,400],[298.6,265.5,1.7]],"properties":{"targets":[[266,267,0],[261.8,302.3,3.0]]}}' >"$tmp/mix.geojson"
expect walk-aa-mixed 0 "^anti-aliasing 2x2: .*\(adaptive: edges and glows; every sample in 1 of 3 frames, with edges at more than half the pixels\)" -- \
    "$bin" walk -q "$tmp/e.plxb" --path "$tmp/mix.geojson" --size 160x120 --speed 400 --fps 1 -o "$tmp/wmix"
expect walk-bare-targets 0 "^1 266 200 400 266 267 0 " -- cat "$tmp/wmix/cameras.txt"
printf '{"type":"LineString","coordinates":[[266,200,400],[266,201,400]],"properties":{"targets":[[266,267,0],[266,267,0]]}}' >"$tmp/high2.geojson"
expect walk-aa-dense 0 "^anti-aliasing 2x2: the later samples shaded 100\.0% of the pixels \(every sample: edges at more than half the pixels of every frame; --aa 1 is faster\)" -- \
    "$bin" walk -q "$tmp/e.plxb" --path "$tmp/high2.geojson" --size 160x120 --speed 1 --fps 1 -o "$tmp/wdense"
expect walk-refine-high 0 "^polarlux walk: warning: --refine: the eye was above --refine-height 60 m at every frame, so no lamp was refined" -- \
    "$bin" walk "$tmp/e.plxb" --path "$tmp/high2.geojson" --size 32x24 --speed 1 --fps 1 --aa 1 --refine -o "$tmp/wrh"
printf '{"type":"LineString","coordinates":[[266,200,100],[266,260,2]],"properties":{"targets":[[266,267,0],[266,300,2]]}}' >"$tmp/desc.geojson"
expect walk-refine-mixed 0 "^refinement: [0-9]+ hits, [1-9][0-9]* misses, .*; 2 of 4 frames above --refine-height 60 m not refined$" -- \
    "$bin" walk "$tmp/e.plxb" --path "$tmp/desc.geojson" --size 32x24 --speed 40 --fps 1 --aa 1 --refine -o "$tmp/wrm"
expect walk-refine-height-all 0 "^refinement: [1-9][0-9]* hits, [1-9][0-9]* misses, [0-9]+ evictions, [0-9]+ lamps refined \([0-9]+ slots, 60 m\); [0-9]+ refill photon frames; [0-9.]+ ms in all \(floor maps and refill frames\)$" -- \
    "$bin" walk "$tmp/e.plxb" --path "$tmp/desc.geojson" --size 32x24 --speed 40 --fps 1 --aa 1 --refine --refine-height 100 -o "$tmp/wra"
# out and back: the lamps of the start, evicted on the way, come back computed again but not new, so
# only the first two frames (new lamps) trace refill photon frames (2 each)
printf '{"type":"LineString","coordinates":[[100,266,1.7],[400,266,1.7],[100,266,1.7]],"properties":{"targets":[[110,266,1.7],[410,266,1.7],[110,266,1.7]]}}' >"$tmp/aba.geojson"
expect walk-refine-recompute 0 "^refinement: 0 hits, [0-9]+ misses, [1-9][0-9]* evictions, .*; 4 refill photon frames;" -- \
    "$bin" walk "$tmp/e.plxb" --path "$tmp/aba.geojson" --size 32x24 --speed 300 --fps 1 --aa 1 --refine -o "$tmp/waba"
expect render-refine-high 0 "^polarlux render: warning: --refine: the eye is 400 m high, above --refine-height 60 m, so no lamp was refined" -- \
    "$bin" render "$tmp/e.plxb" --eye 266,200,400 --target 266,267,0 --size 32x24 --refine -o "$tmp/rrh.png"
expect render-refine-centre 0 "^refinement: [1-9][0-9]* lamps near \\(130\\.0, 266\\.0\\), 30\\.0 m ahead of the eye, got floor maps" -- \
    "$bin" render "$tmp/e.plxb" --eye 100,266,40 --target 180,266,0 --size 32x24 --refine -o "$tmp/rrc.png"
expect render-refine-centre-lonlat 0 "^refinement: [1-9][0-9]* lamps near \\(24\\.94[0-9]{5}, 60\\.17[0-9]{5}\\), 30\\.0 m ahead" -- \
    "$bin" render fixtures/helsinki-centre.geojson --photons 4000 --frames 2 --size 32x24 --refine -o "$tmp/rrl.png"
expect render-refine-height-alone 0 "^polarlux render: warning: --refine-height has no effect without --refine" -- \
    "$bin" render "$tmp/e.plxb" --size 32x24 --refine-height 5 -o "$tmp/rrh2.png"
expect walk-refine-frames-alone 0 "^polarlux walk: warning: --refine-frames has no effect without --refine" -- \
    "$bin" walk "$tmp/e.plxb" --path "$tmp/nb.geojson" --size 32x24 --max-frames 1 --refine-frames 3 -o "$tmp/wrf"
expect render-refine-no-indirect 0 "^polarlux render: warning: --refine has no effect with --no-indirect" -- \
    "$bin" render "$tmp/e.plxb" --size 32x24 --refine --no-indirect -o "$tmp/rrn.png"
expect render-refine-height-bad 2 "--refine-height '-3' is not a number of metres from 0 to 1e6" -- \
    "$bin" render "$tmp/e.plxb" --size 32x24 --refine --refine-height -3 -o "$tmp/rrh3.png"
expect render-aa-full-alone 0 "^polarlux render: warning: --aa-full has no effect without --aa 2 or more" -- \
    "$bin" render "$tmp/e.plxb" --size 32x24 --aa-full -o "$tmp/aa1f.png"
if /usr/bin/python3 tests/cli/png_same.py --within 2 "$tmp/aa2.png" "$tmp/aa2f.png" >/dev/null; then echo "ok   render-aa-adaptive-near-full"; pass=$((pass + 1)); else echo "FAIL render-aa-adaptive-near-full"; fail=$((fail + 1)); fi
expect render-auto-exposure 0 "^exposure: [0-9.e+-]+ \(automatic" -- "$bin" render -q "$tmp/e.plxb" --size 160x120 -o "$tmp/ae.png"
# photometric lamps (SPEC §2.1), light meters anywhere (§2) and pedestrian metrics (§6)
expect info-photometry 0 "^photometry: photometry/street-type2\\.ies \\(IES\\) for 584 lamps; lamp 0: peak 2966\\.8 cd, flux 6283\\.2 lm, dark from gamma 90\\.0 deg$" -- "$bin" info -q fixtures/helsinki-street-luminaires.geojson
expect meter-help 0 "^usage: polarlux meter" -- "$bin" meter --help
expect meter-unknown-option 2 "polarlux meter: unknown option '--bogus'" -- "$bin" meter --bogus x
expect illum-free-air 0 "^50 10 1.5 [0-9.]+(e-?[0-9]+)? 0$" -- sh -c "echo '50 10 1.5 1 0 0' | '$bin' illum -q --no-indirect fixtures/tiny.geojson --points -"
expect meter-columns 0 "^0 -431.5 1.5 [0-9.]+ [0-9.]+$" -- sh -c "echo '0 -431.5' | '$bin' meter -q fixtures/helsinki-street-luminaires.geojson --points-crs local --points - --quantity sc,h"
expect meter-height 0 "^0 -431.5 3 [0-9.]+ [0-9.]+ [0-9.]+ [0-9.]+$" -- sh -c "printf '# crs: local\\n0 -431.5\\n' | '$bin' meter -q fixtures/helsinki-centre.geojson --points - --height 3"
expect meter-lonlat 0 "^24\\.9443 60\\.1677 1\\.5 [0-9.]+$" -- sh -c "echo '24.9443 60.1677' | '$bin' meter -q fixtures/helsinki-street-luminaires.geojson --points - --quantity sc"
expect meter-inside 1 "polarlux meter: -:1: point \\(5, 5, 3\\) is inside a building's solid" -- sh -c "echo '5 5 3' | '$bin' meter -q fixtures/tiny.geojson --points -"
expect meter-bad-quantity 2 "--quantity 'x' is not a list of h, v, sc, hs" -- "$bin" meter fixtures/tiny.geojson --points - --quantity x
expect route-facial 0 "class_fr$" -- "$bin" route -q fixtures/helsinki-street-luminaires.geojson --path fixtures/helsinki-route.geojson --step 4
expect heatmap-sc 0 "^heatmap: semi-cylindrical illuminance at 1.5 m facing 90 deg" -- "$bin" heatmap -q fixtures/tiny.geojson --quantity sc --facing 90 --res 1 -o "$tmp/sc.png"
mkdir -p "$tmp/ph"
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{"lamp":true,"photometry":"l.ies"},"geometry":{"type":"Point","coordinates":[0,0]}}]}' >"$tmp/ph/s.geojson"
expect photometry-missing 1 "^polarlux info: $tmp/ph/s\\.geojson: photometry file $tmp/ph/l\\.ies: cannot open: No such file or directory$" -- "$bin" info "$tmp/ph/s.geojson"
# a FIFO or a folder as the photometry file: refused at once, as every other input (a FIFO with no writer hung)
mkfifo "$tmp/ph/l.ies"
expect photometry-fifo 1 "photometry file $tmp/ph/l\\.ies: not a regular file \\(a FIFO\\)$" -- timeout 20 "$bin" info "$tmp/ph/s.geojson"
rm -f "$tmp/ph/l.ies"; mkdir "$tmp/ph/l.ies"
expect photometry-folder 1 "photometry file $tmp/ph/l\\.ies: not a regular file \\(a directory\\)$" -- "$bin" info "$tmp/ph/s.geojson"
rmdir "$tmp/ph/l.ies"
printf 'IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n1 1 0\n0 90\n0\n100 abc\n' >"$tmp/ph/l.ies"
expect photometry-bad-number 1 "^polarlux info: $tmp/ph/s\\.geojson: $tmp/ph/l\\.ies: line 7: bad number 'abc' for the candela values$" -- "$bin" info "$tmp/ph/s.geojson"
printf 'IESNA:LM-63-2002\nTILT=lamp.tlt\n' >"$tmp/ph/l.ies"
expect photometry-tilt 1 "l\\.ies: line 2: unsupported tilt" -- "$bin" info "$tmp/ph/s.geojson"
printf 'IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n1 1 0\n0 90\n0\n100\n' >"$tmp/ph/l.ies"
expect photometry-short 1 "l\\.ies: line 7: table too short" -- "$bin" info "$tmp/ph/s.geojson"
printf 'IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n1 1 0\n0 90\n0\n100 0\n' >"$tmp/ph/l.ies"
sed 's/"photometry":"l.ies"/"photometry":"l.ies","intensity":500/' "$tmp/ph/s.geojson" >"$tmp/ph/si.geojson"
expect photometry-intensity-ignored 0 "feature 0 \\(line 1, column [0-9]+\\): property \"intensity\" is ignored: the lamp's photometry file gives its candelas" -- sh -c "echo '0 0' | '$bin' illum --no-indirect '$tmp/ph/si.geojson' --points -"
printf 'IESNA:LM-63-2002\nTILT=NONE\n1 1000 1 2 1 1 2 0 0 0\n1 1 0\n0 180\n0\n100 100\n' >"$tmp/ph/l.ies"
expect photometry-flux-above-lamps 0 "warning: $tmp/ph/l\\.ies: the table's intensities give 1257 lm, 126% of the lumens of its lamps \\(1000 lm: lamps x lumens per lamp x ballast factor\\); the table is used as given$" -- "$bin" info "$tmp/ph/s.geojson"
expect photometry-flux-quiet 0 "" -- "$bin" info -q "$tmp/ph/s.geojson"
if grep -q warning "$tmp/out"; then echo "FAIL photometry-flux-quiet printed a warning"; fail=$((fail + 1)); fi
expect photometry-one-lamp 0 "^photometry: l\\.ies \\(IES\\) for 1 lamp; lamp 0: peak 100\\.0 cd, flux 1256\\.6 lm" -- "$bin" info -q "$tmp/ph/s.geojson"
printf 'IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n1 1 0\n0 90\n0\n100 0\n' >"$tmp/ph/l.ies"
expect photometry-nadir 0 "^0 0 0 2\\.768895999" -- sh -c "echo '0 0' | '$bin' illum -q --no-indirect '$tmp/ph/s.geojson' --points -"
# a user's pass on the real district (2026-12-02): coordinates, empty routes, output names, notes
H=fixtures/helsinki-centre.geojson
printf '{"type":"FeatureCollection","features":[{"type":"Feature","properties":{},"geometry":{"type":"LineString","coordinates":[[100,200],[300,200]]}}]}' >"$tmp/metres-route.json"
expect route-metres-on-lonlat-warns 0 "warning: .*metres-route.json: coordinates exceed the lon/lat range: read as metres" -- "$bin" route $H --path "$tmp/metres-route.json"
printf '{"type":"FeatureCollection","features":[{"type":"Feature","properties":{"name":"a"},"geometry":{"type":"LineString","coordinates":[[24.944,60.1677],[24.945,60.1677]]}},{"type":"Feature","properties":{"name":"b"},"geometry":{"type":"LineString","coordinates":[[385920,6672300],[385930,6672300]]}}]}' >"$tmp/mixroute.json"
expect route-mixed-lines-counted 0 "mixroute\.json: coordinates exceed the lon/lat range: read as metres .*; 1 of the 2 lines lie wholly within it: if those are lon/lat, the file mixes coordinate systems" -- "$bin" route $H --path "$tmp/mixroute.json"
# metres of a route outside the scene are said (helper-64: 2 km beyond the district read as measured dark metres)
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{"name":"far"},"geometry":{"type":"LineString","coordinates":[[30,20],[70,20],[2070,20]]}},{"type":"Feature","properties":{"name":"near"},"geometry":{"type":"LineString","coordinates":[[30,20],[70,20]]}}]}' >"$tmp/farroute.json"
expect route-outside-scene 0 "farroute\.json: line far runs 1960\.0 m outside the scene \(its buildings' box and 50 m, and every lamp's reach\)" -- "$bin" route fixtures/tiny.geojson --path "$tmp/farroute.json"
if grep -q "line near runs" "$tmp/out"; then echo "FAIL route-outside-scene-near: a line inside was said outside"; fail=$((fail + 1)); else echo "ok   route-outside-scene-near"; pass=$((pass + 1)); fi
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{},"geometry":{"type":"LineString","coordinates":[[100,200],[300,200]]}}]}' >"$tmp/metres-route-m.json"
"$bin" route $H --path "$tmp/metres-route-m.json" >/dev/null 2>"$tmp/err"
if ! grep -q "exceed the lon/lat range" "$tmp/err" && grep -q "note: the lux are direct light only" "$tmp/err"; then echo "ok   route-units-m-no-warning"; pass=$((pass + 1)); else echo "FAIL route-units-m-no-warning"; fail=$((fail + 1)); fi
printf '{"type":"FeatureCollection","features":[{"type":"Feature","properties":{},"geometry":{"type":"LineString","coordinates":[[10,20],[50,20]]}}]}' >"$tmp/small-route.json"
expect route-small-metres-hint 1 'in local metres \(properties.units "m" reads it as metres\)' -- "$bin" route -q fixtures/tiny.geojson --path "$tmp/small-route.json"
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{},"geometry":{"type":"LineString","coordinates":[[10,20],[50,20]]}}]}' >"$tmp/small-route-m.json"
expect route-small-metres-m 0 "^#0 +all +40\.0 " -- "$bin" route -q fixtures/tiny.geojson --path "$tmp/small-route-m.json"
printf '{"type":"FeatureCollection","features":[{"type":"Feature","properties":{},"geometry":{"type":"LineString","coordinates":[[24.9432847,60.1676957],[24.9432847,60.1676957]]}}]}' >"$tmp/point-route.json"
expect route-no-length 1 "line #0 \(feature 0\) has no length \(its 2 positions are one point\)" -- "$bin" route -q $H --path "$tmp/point-route.json"
expect route-network-same-point 1 "meet the streets of .* at the same point: the route has no length" -- "$bin" route -q $H --network fixtures/helsinki-streets.geojson --from 24.9432847,60.1676957 --to 24.9432847,60.1676957
expect route-light-note-direct 0 "note: the lux are direct light only \(no photon buffers: a bake of the scene adds" -- "$bin" route fixtures/tiny.geojson --path "$tmp/small-route-m.json"
expect route-light-note-bake 0 "note: the ground's lux \(E_h\) are direct \+ indirect light \(2 photon frames\); Ev and Esc are direct light" -- "$bin" route "$tmp/e.plxb" --path "$tmp/small-route-m.json"
expect route-light-note-bake-direct 0 "note: the lux are direct light only \(the bake holds no photon buffers" -- "$bin" route "$tmp/end.plxb" --path "$tmp/small-route-m.json"
"$bin" route -q $H --path fixtures/helsinki-route.geojson --step 4 >"$tmp/rt.txt" 2>&1
if grep -q "^line        seg " "$tmp/rt.txt" && grep -q "^lamp-street all " "$tmp/rt.txt" && grep -q "^            0  " "$tmp/rt.txt" &&
   grep -q "^park-walk   all " "$tmp/rt.txt"; then echo "ok   route-names-aligned"; pass=$((pass + 1)); else echo "FAIL route-names-aligned"; sed 's/^/    /' "$tmp/rt.txt"; fail=$((fail + 1)); fi
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{"name":"Etel\303\244esplanadi"},"geometry":{"type":"LineString","coordinates":[[10,20],[50,20]]}},{"type":"Feature","properties":{"name":"Keskuskatu-1"},"geometry":{"type":"LineString","coordinates":[[10,25],[50,25]]}}]}' >"$tmp/utf8-route.json"
"$bin" route -q fixtures/tiny.geojson --path "$tmp/utf8-route.json" >"$tmp/rt.txt" 2>&1
if grep -q "^Eteläesplanadi all " "$tmp/rt.txt" && grep -q "^Keskuskatu-1   all " "$tmp/rt.txt"; then echo "ok   route-names-utf8-aligned"; pass=$((pass + 1)); else echo "FAIL route-names-utf8-aligned"; sed 's/^/    /' "$tmp/rt.txt"; fail=$((fail + 1)); fi
expect route-outside-scene 0 "warning: .*small-route.json: no position lies within the scene's bounds.*\(read as lon/lat: properties.units \"m\" if they are metres\)" -- "$bin" route $H --path "$tmp/small-route.json" --step 10000
expect annotate-metres-on-lonlat-warns 0 "warning: .*metres-route.json: coordinates exceed the lon/lat range" -- "$bin" annotate $H --network "$tmp/metres-route.json" -o "$tmp/ann.geojson"
expect heatmap-path-metres-on-lonlat-warns 0 "warning: .*metres-route.json: coordinates exceed the lon/lat range" -- "$bin" heatmap $H --res 20 --path "$tmp/metres-route.json" -o "$tmp/hmp.png"
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{},"geometry":{"type":"LineString","coordinates":[[30,20],[70,20]]}},{"type":"Feature","properties":{"name":"ml"},"geometry":{"type":"MultiLineString","coordinates":[[[30,20],[60,20]],[[40,20],[40,20]]]}}]}' >"$tmp/part-route.json"
expect route-no-length-part 1 "line ml \(feature 1\) has no length" -- "$bin" route -q fixtures/tiny.geojson --path "$tmp/part-route.json"
expect heatmap-o-jpg 2 "-o '.*j\.jpg': the map is written as PNG \(\.png\) or GeoTIFF" -- "$bin" heatmap -q fixtures/tiny.geojson --res 4 -o "$tmp/j.jpg"
[ ! -e "$tmp/j.jpg" ] && [ ! -e "$tmp/j.pgw" ] && { echo "ok   heatmap-o-jpg-nothing"; pass=$((pass + 1)); } || { echo "FAIL heatmap-o-jpg-nothing"; fail=$((fail + 1)); }
expect heatmap-height-for-h 0 "warning: --height is for --quantity v, sc and hs" -- "$bin" heatmap fixtures/tiny.geojson --res 4 --height 3 -o "$tmp/hm.png"
expect heatmap-facing-for-hs 0 "warning: --facing is for --quantity v and sc: hemispherical" -- "$bin" heatmap fixtures/tiny.geojson --res 4 --quantity hs --facing 30 -o "$tmp/hm.png"
expect heatmap-max-says-fixed 0 "scale 0\.1\.\.100 lx \(fixed by --max; " -- "$bin" heatmap -q fixtures/tiny.geojson --res 4 --max 100 -o "$tmp/hm.png"
expect illum-five-numbers 1 "<stdin>:1: expected 2, 3 or 6 numbers \('x y', 'x y z' or 'x y z nx ny nz'\), found 5" -- sh -c "echo '50 10 1.5 1 0' | '$bin' illum -q --no-indirect fixtures/tiny.geojson --points -"
# nothing after the normal or the facing, and a facing given whole: a 7th number or a lone ux was read silently
expect illum-seven-numbers 1 "<stdin>:1: expected 2, 3 or 6 numbers \('x y', 'x y z' or 'x y z nx ny nz'\), found 7" -- sh -c "echo '50 10 1.5 0 0 1 7' | '$bin' illum -q --no-indirect fixtures/tiny.geojson --points -"
expect meter-four-numbers 1 "<stdin>:1: expected 2, 3 or 5 numbers \('x y', 'x y z' or 'x y z ux uy'\), found 4" -- sh -c "echo '50 10 1.5 1' | '$bin' meter -q fixtures/tiny.geojson --points -"
expect meter-six-numbers 1 "<stdin>:1: expected 2, 3 or 5 numbers .*, found 6" -- sh -c "echo '50 10 1.5 0 1 9' | '$bin' meter -q fixtures/tiny.geojson --points -"
expect vis-extra-columns-read 0 "^50 10 [0-9.]+ [0-9]+$" -- sh -c "echo '50 10 1.5 0 0 1 7' | '$bin' vis -q fixtures/tiny.geojson --points -"
expect illum-empty-points 2 "--points needs a file name, not an empty string" -- "$bin" illum -q fixtures/tiny.geojson --points ''
expect tiles-empty-out 2 "-o needs a file name, not an empty string" -- "$bin" tiles -q fixtures/tiny.geojson --zoom 14 -o ''
expect walk-collection-first-line 0 "holds 2 line features: the walk follows the first LineString \(318\.4 m\)" -- "$bin" walk $H --path fixtures/helsinki-route.geojson -o "$tmp/wcol" --size 32x24 --max-frames 2 --no-indirect --aa 1
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{},"geometry":{"type":"LineString","coordinates":[[30,20,1.7],[60,20,1.7]]}},{"type":"Feature","properties":{},"geometry":{"type":"MultiLineString","coordinates":[[[30,25],[60,25]]]}}]}' >"$tmp/walk-multi.json"
expect walk-multilinestring-counted 0 "holds 2 line features: the walk follows the first LineString \(30\.0 m\)" -- "$bin" walk fixtures/tiny.geojson --path "$tmp/walk-multi.json" -o "$tmp/wmul" --size 32x24 --max-frames 2 --no-indirect --aa 1
# a bake of a scene without lamps traced nothing: it says so, not "--no-indirect or --frames 0" (helper-56's pass)
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{"height":10},"geometry":{"type":"Polygon","coordinates":[[[0,0],[10,0],[10,10],[0,10],[0,0]]]}}]}' >"$tmp/nolamp.geojson"
expect bake-no-lamps 0 "no photons \\(no lamps to trace from\\)" -- "$bin" bake -q "$tmp/nolamp.geojson" -o "$tmp/nolamp.plxb"
"$bin" render "$tmp/nolamp.plxb" --size 32x24 -o "$tmp/nolamp.png" >"$tmp/out" 2>&1
if grep -q "has no lamps" "$tmp/out" && ! grep -q "no-indirect or --frames 0" "$tmp/out"; then echo "ok   render-bake-no-lamps-reason"; pass=$((pass + 1)); else echo "FAIL render-bake-no-lamps-reason"; sed 's/^/    /' "$tmp/out"; fail=$((fail + 1)); fi
# lamps of 0 cd: the dark result names them, not their reach; --frames 0 says E_indirect is 0 (helper-57's pass)
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{"lamp":true,"intensity":0},"geometry":{"type":"Point","coordinates":[0,0]}}]}' >"$tmp/zero-cd.geojson"
expect dark-zero-cd 0 "every point is dark \\(0 lx\\): every lamp gives no light \\(0 cd" -- sh -c "echo '1 0' | '$bin' illum '$tmp/zero-cd.geojson' --points -"
expect illum-frames-0 0 "^polarlux illum: warning: --frames 0 traces no photons: no indirect light, as with --no-indirect$" -- sh -c "echo '4 0' | '$bin' illum fixtures/tiny.geojson --points - --frames 0"
# route's two ways: their options said as such, not as unknown (helper-57's pass)
expect route-from-without-network 2 "^polarlux route: --from needs --network STREETS.geojson" -- "$bin" route fixtures/helsinki-centre.geojson --from 1,2 --to 3,4
expect route-path-with-network 2 "^polarlux route: --path and --network do not combine" -- "$bin" route fixtures/helsinki-centre.geojson --network fixtures/helsinki-streets.geojson --path fixtures/helsinki-route.geojson
mkdir -p "$tmp/dir.mbtiles"
expect tiles-mbtiles-folder 2 "^polarlux tiles: -o '.*dir\\.mbtiles' is a folder: an \\.mbtiles file cannot replace it" -- "$bin" tiles -q fixtures/helsinki-centre.geojson --zoom 12 -o "$tmp/dir.mbtiles"
# a path nested past cJSON's depth: said as the scene loader says it, not "malformed" (helper-56's pass)
python3 -c "print('{\"type\":\"LineString\",\"coordinates\":' + '[' * 1200)" >"$tmp/deep-path.geojson" 2>/dev/null || printf '%1200s' '' | tr ' ' '[' >"$tmp/deep-path.geojson"
expect path-nested-deep 1 "deep-path\\.geojson: JSON nested deeper than 1000 levels at byte" -- "$bin" walk fixtures/tiny.geojson --path "$tmp/deep-path.geojson" -o "$tmp/deepw"
# GeoJSON written to standard output ends its line; a dropped lamp says it is left out (helper-57's pass)
expect geojson-stdout-newline 0 "" -- sh -c "'$bin' dark-spots -q fixtures/tiny.geojson -o - | tail -c 1 | od -An -c | grep -q '\\\\n'"
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{"lamp":true,"radius":0},"geometry":{"type":"Point","coordinates":[0,0]}}]}' >"$tmp/radius0.geojson"
expect lamp-bad-left-out 0 "feature 0 \\(line 1, column [0-9]+\\): lamp radius 0 m is out of range \\(> 0 and <= 100000 m\\); left out$" -- "$bin" info "$tmp/radius0.geojson"
# a tile folder's metadata.json: TileJSON with the colour scale the summary line prints
"$bin" tiles -q fixtures/helsinki-centre.geojson --zoom 13 -o "$tmp/tj" >"$tmp/tj.txt" 2>&1
expect tiles-folder-tilejson 0 "" -- /usr/bin/python3 -c "
import json, re, sys
m = json.load(open('$tmp/tj/metadata.json'))
top = float(re.search(r'scale 0\\.1\\.\\.([0-9.e+]+) lx', open('$tmp/tj.txt').read()).group(1))
assert m['tilejson'] == '3.0.0' and m['tiles'] == ['{z}/{x}/{y}.png'] and m['minzoom'] == m['maxzoom'] == 13, m
assert m['polarlux_scale']['min_lux'] == 0.1 and m['polarlux_scale']['max_lux'] == top, (m, top)
assert 24.9 < m['bounds'][0] < m['bounds'][2] < 25.0 and 60.1 < m['bounds'][1] < m['bounds'][3] < 60.2, m
assert 'OpenStreetMap' in m['attribution'], m
"
# meters that all read 0 lx, points far outside the scene, an empty points file: a word each (helper-57's pass)
expect meter-dark 0 "^polarlux meter: warning: every point is dark \\(0 lx\\): no lamp's light reaches it" -- sh -c "echo '1000 0' | '$bin' meter fixtures/tiny.geojson --points -"
expect points-far-outside 0 "^polarlux illum: warning: <stdin>: 1 of 2 points lie more than 1 km outside the scene's bounds and every lamp's reach \\(the farthest 95\\.[0-9] km, line 1\\)" -- sh -c "printf '25.5 61\\n24.944 60.1677\\n' | '$bin' illum fixtures/helsinki-centre.geojson --points - --no-indirect"
expect points-far-1e300 0 "the farthest 1e\+297 km, line 2\)" -- sh -c "printf '# crs: local\n1e300 0\n' | '$bin' illum fixtures/tiny.geojson --points - --no-indirect"
# a '# crs:' line holds for the whole file: after a point, or a second different one, is an error (the last one moved the points above it); any case
expect points-crs-after-point 1 "<stdin>:2: a '# crs:' line after the first point" -- sh -c "printf '24.944557742 60.172006463\n# crs: local\n0 0\n' | '$bin' illum -q --no-indirect fixtures/helsinki-centre.geojson --points -"
expect points-crs-two 1 "<stdin>:2: a second '# crs:' line \(lonlat\) differs from the first \(local\)" -- sh -c "printf '# crs: local\n# crs: lonlat\n0 0\n' | '$bin' illum -q --no-indirect fixtures/helsinki-centre.geojson --points -"
expect points-crs-any-case 0 "^24\.944557742 60\.172006463 0 2\.53" -- sh -c "printf '# CRS: LonLat\n24.944557742 60.172006463\n' | '$bin' illum -q --no-indirect fixtures/helsinki-centre.geojson --points -"
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{"height":10},"geometry":{"type":"Polygon","coordinates":[[[0,0],[10,0],[10,10],[0,10],[0,0]]]}},{"type":"Feature","properties":{"lamp":true},"geometry":{"type":"Point","coordinates":[3000,0]}}]}' >"$tmp/far-lamp.geojson"
echo '3000 5' | "$bin" illum "$tmp/far-lamp.geojson" --points - --no-indirect >"$tmp/out" 2>&1
if grep -q "^3000 5 0 [1-9]" "$tmp/out" && ! grep -q "outside the scene's bounds" "$tmp/out"; then echo "ok   points-near-far-lamp"; pass=$((pass + 1)); else echo "FAIL points-near-far-lamp: a lit point by a lamp 3 km out was called out of reach"; sed 's/^/    /' "$tmp/out"; fail=$((fail + 1)); fi
expect illum-as-given 0 "^24\\.944 60\\.1677 0 [0-9.]+ 0$" -- sh -c "echo '24.944 60.1677' | '$bin' illum -q fixtures/helsinki-centre.geojson --points - --no-indirect"
expect illum-no-points 0 "^polarlux illum: - holds no points$" -- sh -c "printf '# nothing\\n' | '$bin' illum -q fixtures/tiny.geojson --points -"
# a blown-out image is said as a black one is; --mem 1GiB; "targets": null as absent (helper-56's pass)
expect render-blown-out 0 "^polarlux render: warning: the image is blown out: 100% of its lit pixels are full white: --exposure 1e\\+09" -- "$bin" render fixtures/tiny.geojson --exposure 1e9 --size 32x24 -o "$tmp/blown.png"
"$bin" render fixtures/tiny.geojson --exposure 1 --size 32x24 -o "$tmp/notblown.png" >"$tmp/out" 2>&1
if grep -q "blown out" "$tmp/out"; then echo "FAIL render-exposure-1-not-blown"; fail=$((fail + 1)); else echo "ok   render-exposure-1-not-blown"; pass=$((pass + 1)); fi
expect mem-gib 0 "^buildings: 4" -- "$bin" info -q fixtures/tiny.geojson --mem 1GiB
printf '{"type":"Feature","properties":{"targets":null},"geometry":{"type":"LineString","coordinates":[[30,12,1.7],[60,12,1.7]]}}' >"$tmp/tnull.geojson"
expect walk-targets-null 0 "^walk: 2 frames" -- "$bin" walk -q fixtures/tiny.geojson --path "$tmp/tnull.geojson" --size 32x24 --max-frames 2 -o "$tmp/tnullw"
# a zero facing direction on line 3: refused before any row is printed (rows 1 and 2 were, then exit 1)
printf '1 0\n2 0\n3 0 1.5 0 0\n' >"$tmp/facing0.txt"
expect meter-facing-zero 1 "^polarlux meter: .*facing0\\.txt:3: the facing direction \\(ux, uy\\) is zero or not finite$" -- "$bin" meter -q fixtures/tiny.geojson --points "$tmp/facing0.txt"
if [ -n "$("$bin" meter -q fixtures/tiny.geojson --points "$tmp/facing0.txt" 2>/dev/null)" ]; then echo "FAIL meter-facing-zero-no-rows"; fail=$((fail + 1)); else echo "ok   meter-facing-zero-no-rows"; pass=$((pass + 1)); fi
# helper-58's review: --frames 0 on render, a CSV layer's photometry column, a layer's skipped lamp
expect render-frames-0 0 "^polarlux render: warning: --frames 0 traces no photons: no indirect light, as with --no-indirect$" -- "$bin" render fixtures/tiny.geojson --frames 0 --size 32x24 -o "$tmp/f0.png"
printf 'x,y,z,photometry\n30,12,6,a.ies\n' >"$tmp/lphot.csv"
expect lamps-csv-photometry-refused 1 "lphot\\.csv: column 4 \"photometry\": a lamp layer's lamps are isotropic" -- "$bin" info -q fixtures/tiny.geojson --lamps "$tmp/lphot.csv"
printf 'x,y,radius\n30,12,0\n' >"$tmp/lr0.csv"
expect lamps-csv-left-out 0 "lr0\\.csv: feature 2: radius is out of range \\(> 0 and <= 100000 m\\); left out$" -- "$bin" info fixtures/tiny.geojson --lamps "$tmp/lr0.csv"
# '-' is standard input or output elsewhere: not a scene, and not a folder for frames or tiles (helper-56's pass)
expect scene-dash 2 "^polarlux info: SCENE '-': a scene is not read from standard input" -- "$bin" info -
expect walk-o-dash 2 "^polarlux walk: -o names the folder for the frames: '-' \\(standard output\\) cannot hold them" -- "$bin" walk fixtures/tiny.geojson --path "$tmp/nope.geojson" -o -
expect tiles-o-dash 2 "^polarlux tiles: -o names a folder or a \\.mbtiles file: '-'" -- "$bin" tiles fixtures/helsinki-centre.geojson --zoom 12 -o -
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{"lamp":true,"photometry":"a.ies"},"geometry":{"type":"Point","coordinates":[30,12]}}]}' >"$tmp/lphot.geojson"
expect lamps-photometry-refused 1 "^polarlux info: --lamps .*lphot\\.geojson: feature 0: property \"photometry\": a lamp layer's lamps are isotropic" -- "$bin" info -q fixtures/tiny.geojson --lamps "$tmp/lphot.geojson"
expect lamps-empty-name 2 "--lamps needs a file name, not an empty string" -- "$bin" info -q fixtures/tiny.geojson --lamps ''
expect render-o-jpg 2 "-o '.*x\.jpg': the file is written as PNG \(\.png\); name it so" -- "$bin" render -q fixtures/tiny.geojson -o "$tmp/x.jpg"
expect render-pfm-exr 2 "--pfm '.*x\.exr': the file is written as PFM \(\.pfm\)" -- "$bin" render -q fixtures/tiny.geojson -o "$tmp/x.png" --pfm "$tmp/x.exr"
expect draw-o-jpg 2 "-o '.*d\.jpg': the file is written as PNG" -- "$bin" draw -q fixtures/tiny.geojson --polar 0 -o "$tmp/d.jpg"
[ ! -e "$tmp/x.jpg" ] && [ ! -e "$tmp/d.jpg" ] && { echo "ok   o-jpg-nothing-written"; pass=$((pass + 1)); } || { echo "FAIL o-jpg-nothing-written"; fail=$((fail + 1)); }
: >"$tmp/afile.png"
expect tiles-o-is-a-file 2 "-o '.*afile\.png' is a file, not a folder" -- "$bin" tiles -q $H --zoom 14 -o "$tmp/afile.png"
expect heatmap-box-outside 0 "every pixel of the map is dark \(0 lx\): --box lies wholly outside the scene's bounds" -- "$bin" heatmap fixtures/tiny.geojson --box 5000,5000,5100,5100 --res 10 -o "$tmp/hbo.png"
expect heatmap-no-lit-scale 0 "\(0 lit pixels: the default scale\)" -- "$bin" heatmap -q fixtures/tiny.geojson --box 5000,5000,5100,5100 --res 10 -o "$tmp/hbo.png"
"$bin" illum fixtures/tiny.geojson --no-indirect --points - <<EOF >/dev/null 2>"$tmp/err"
5 5 3
EOF
if grep -q "inside a building's solid" "$tmp/err" && ! grep -q "every point is dark" "$tmp/err"; then echo "ok   illum-inside-not-dark"; pass=$((pass + 1)); else echo "FAIL illum-inside-not-dark"; sed 's/^/    /' "$tmp/err"; fail=$((fail + 1)); fi
expect info-usable-bytes 0 "^memory: [0-9]+ bytes in use, peak [0-9]+, of the block's [0-9]+ usable bytes" -- "$bin" info -q fixtures/tiny.geojson
"$bin" dark-spots -q fixtures/eixample-4x4.geojson --count 6 >"$tmp/spots.json" 2>&1
/usr/bin/python3 -c "import json,sys; [print('%g,%g' % (f['properties']['x'], f['properties']['y'])) for f in json.load(open(sys.argv[1]))['features']]" "$tmp/spots.json" >"$tmp/spots.txt"
between=0; n=0
while read -r pt; do n=$((n + 1)); "$bin" vis -q fixtures/eixample-4x4.geojson --at "$pt" 2>&1 | grep -q "shared by two buildings" && between=$((between + 1)); done <"$tmp/spots.txt"
if [ "$n" -eq 6 ] && [ "$between" -eq 0 ]; then echo "ok   dark-spots-not-on-party-walls"; pass=$((pass + 1)); else echo "FAIL dark-spots-not-on-party-walls: $between of $n on shared walls"; fail=$((fail + 1)); fi
expect dark-spots-light-note 0 "note: the lux are direct light only" -- "$bin" dark-spots fixtures/tiny.geojson --count 2
expect route-walk-path-file 0 "^a walk east along the street of all " -- "$bin" route -q $H --path fixtures/helsinki-walk.geojson --step 4
printf '{"type":"LineString","coordinates":[[10,20],[50,20]],"properties":{"units":"m"}}' >"$tmp/bare-route.json"
expect route-bare-linestring 0 "^#0 +all +40\.0 " -- "$bin" route -q fixtures/tiny.geojson --path "$tmp/bare-route.json"
printf '{"type":"FeatureCollection","features":[{"type":"Feature","properties":{"units":"m"},"geometry":{"type":"LineString","coordinates":[[100,200],[300,200]]}}]}' >"$tmp/feature-m.json"
"$bin" route $H --path "$tmp/feature-m.json" >/dev/null 2>"$tmp/err"
if ! grep -q "exceed the lon/lat range" "$tmp/err"; then echo "ok   route-feature-units-m"; pass=$((pass + 1)); else echo "FAIL route-feature-units-m"; fail=$((fail + 1)); fi
printf '{"type":"FeatureCollection","features":[{"type":"Feature","properties":{"units":"ft"},"geometry":{"type":"LineString","coordinates":[[100,200],[300,200]]}}]}' >"$tmp/feature-ft.json"
expect route-feature-units-ft 1 "feature-ft.json: feature 0: properties.units must be \"m\" when given" -- "$bin" route -q $H --path "$tmp/feature-ft.json"
echo "24.937911661 60.174032879" >"$tmp/in-ll.txt"
expect vis-lonlat-error-as-given 1 "in-ll\.txt:1: point 24\.937911661 60\.174032879 \(local -353\.5125927, 266\.0121887 m\) is inside building 368" -- "$bin" vis -q $H --points "$tmp/in-ll.txt"
expect meter-lonlat-error-as-given 1 "in-ll\.txt:1: point 24\.937911661 60\.174032879 \(local -353\.5125927, 266\.0121887, 1\.5 m\) is inside a building's solid" -- "$bin" meter -q $H --points "$tmp/in-ll.txt"
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{"units":"ft"},"geometry":{"type":"LineString","coordinates":[[10,20],[50,20]]}}]}' >"$tmp/coll-m-feat-ft.json"
expect route-feature-ft-under-m 1 "feature 0: properties.units must be \"m\" when given" -- "$bin" route -q fixtures/tiny.geojson --path "$tmp/coll-m-feat-ft.json"
printf '{"type":"Feature","properties":{},"geometry":null}' >"$tmp/no-geometry.json"
expect route-no-geometry 1 "feature 0: geometry is not a LineString or MultiLineString" -- "$bin" route -q fixtures/tiny.geojson --path "$tmp/no-geometry.json"
expect draw-out-missing-folder 1 "polarlux draw: cannot write '.*/nodir/x\.png': the folder '.*/nodir' does not exist" -- "$bin" draw -q fixtures/tiny.geojson --polar 0 -o "$tmp/nodir/x.png"
expect dark-spots-out-missing-folder 1 "polarlux dark-spots: cannot write '.*/nodir/s\.json': the folder" -- "$bin" dark-spots -q fixtures/tiny.geojson -o "$tmp/nodir/s.json"
: >"$tmp/plain"
expect out-parent-is-a-file 1 "cannot write '.*/plain/x\.png': '.*/plain' is not a folder" -- "$bin" heatmap -q fixtures/tiny.geojson --res 10 -o "$tmp/plain/x.png"
expect info-inner-rings 0 "^buildings: 442 \(4 raised above the ground; 71 inner rings of their own\)$" -- "$bin" info -q $H
# dark-spots on a bake gathers indirect light only where the direct lux
# leaves a point a candidate: the same spots as --exhaustive (every point
# gathered). grid-4x4: bounds rule out most points (steps 1 to 3); tiny:
# most points have no direct light, so the pass gathers everywhere.
"$bin" bake -q fixtures/grid-4x4.geojson -o "$tmp/g4.plxb" >/dev/null 2>&1
"$bin" bake -q fixtures/tiny.geojson -o "$tmp/ds.plxb" >/dev/null 2>&1
spots_same() { # NAME BAKE ARGS...: the default's spots equal --exhaustive's
    n=$1; b=$2; shift 2
    "$bin" dark-spots -q "$b" "$@" >"$tmp/ds-lazy.json" 2>/dev/null
    "$bin" dark-spots -q "$b" "$@" --exhaustive >"$tmp/ds-all.json" 2>/dev/null
    if grep -q '"rank":2' "$tmp/ds-lazy.json" && cmp -s "$tmp/ds-lazy.json" "$tmp/ds-all.json"; then
        echo "ok   $n"; pass=$((pass + 1))
    else echo "FAIL $n"; fail=$((fail + 1)); fi
}
spots_same dark-spots-lazy-equals-exhaustive "$tmp/g4.plxb" --count 2 --res 4
expect dark-spots-gathered-note 0 "indirect light gathered 1[0-9]{3} times for the 8300 street points" -- "$bin" dark-spots "$tmp/g4.plxb" --count 2 --res 4
expect dark-spots-gathers-everywhere 0 "indirect light gathered 4034 times for the 4034 street points" -- "$bin" dark-spots "$tmp/ds.plxb" --count 3 --res 1
if [ -z "$PLX_TEST_SKIP_SLOW" ]; then # not in plain make check: twins of the bake (about 3 s)
# --threads: the gathers shared with twins of the bake, the same lux to the
# last digit (every point gathered, 20 spots of lux 0.027 to 0.058)
"$bin" dark-spots -q "$tmp/g4.plxb" --count 20 --res 4 --exhaustive --threads 1 >"$tmp/ds-t1.json" 2>/dev/null
"$bin" dark-spots -q "$tmp/g4.plxb" --count 20 --res 4 --exhaustive --threads 3 >"$tmp/ds-t3.json" 2>/dev/null
if grep -q '"rank":20,"lux":0\.0[1-9]' "$tmp/ds-t1.json" && cmp -s "$tmp/ds-t1.json" "$tmp/ds-t3.json"; then
    echo "ok   dark-spots-threads-same"; pass=$((pass + 1))
else echo "FAIL dark-spots-threads-same"; fail=$((fail + 1)); fi
expect dark-spots-threads-note 0 "gathered 1[0-9]{3} times for the 8300 street points .*, on 3 threads$" -- "$bin" dark-spots "$tmp/g4.plxb" --count 2 --res 4 --threads 3
expect dark-spots-one-thread-note 0 ", on 1 thread$" -- "$bin" dark-spots "$tmp/g4.plxb" --count 2 --res 4 --threads 1
fi
if [ -z "$PLX_TEST_QUICK" ]; then # check-full: annotate's edges scored on 1 and 3 threads (7 s), the same files
    "$bin" bake -q fixtures/helsinki-centre.geojson --frames 2 --photons 4000 -o "$tmp/hq.plxb" >/dev/null 2>&1
    "$bin" annotate -q "$tmp/hq.plxb" --network fixtures/helsinki-streets.geojson --threads 1 -o "$tmp/an1.geojson" --csv "$tmp/an1.csv" >/dev/null 2>&1
    "$bin" annotate -q "$tmp/hq.plxb" --network fixtures/helsinki-streets.geojson --threads 3 -o "$tmp/an3.geojson" --csv "$tmp/an3.csv" >/dev/null 2>&1
    if grep -q '^way/4243035,50.677,30.743,0.000,0.6067,1.5083,0.1939,' "$tmp/an1.csv" && cmp -s "$tmp/an1.csv" "$tmp/an3.csv" &&
        cmp -s "$tmp/an1.geojson" "$tmp/an3.geojson"; then
        echo "ok   annotate-threads-same"; pass=$((pass + 1))
    else echo "FAIL annotate-threads-same"; fail=$((fail + 1)); fi
    expect annotate-threads-note 0 "^polarlux annotate: note: the 4717 edges scored on 3 threads, each with its own copy of the bake$" -- "$bin" annotate "$tmp/hq.plxb" --network fixtures/helsinki-streets.geojson --threads 3 -o "$tmp/an3.geojson"
    # route over the annotated network of a lon/lat bake: the table of the plain network's
    esp="--from 24.9432847,60.1676957 --to 24.9524231,60.1678992 --dark-weight 0.5"
    "$bin" route -q "$tmp/hq.plxb" --network fixtures/helsinki-streets.geojson $esp >"$tmp/esp-plain.txt" 2>&1
    expect net-annotated-helsinki-same 0 "" -- sh -c "'$bin' route -q '$tmp/hq.plxb' --network '$tmp/an1.geojson' $esp | cmp - '$tmp/esp-plain.txt'"
fi
if [ -z "$PLX_TEST_QUICK" ]; then # check-full: the pass that gathers everywhere; a pass by bounds, then passes gathering everywhere (--mem)
    spots_same dark-spots-unbounded-equals-exhaustive "$tmp/ds.plxb" --count 3 --res 1
    need=$("$bin" dark-spots -q "$tmp/g4.plxb" --mem 1M 2>&1 | sed -n 's/.*it needs \([0-9]*\) bytes.*/\1/p')
    spots_same dark-spots-passes-equal-exhaustive "$tmp/g4.plxb" --count 80 --res 3 --spacing 30 --mem $((need + 36312))
    expect dark-spots-passes-note 0 "[3-9] passes over the grid: --mem leaves room for" -- "$bin" dark-spots -q "$tmp/g4.plxb" --count 80 --res 3 --spacing 30 --mem $((need + 36312))
fi
# "-" reads a path or network from standard input, with the file's results
"$bin" route -q $H --path fixtures/helsinki-route.geojson >"$tmp/route-file.txt" 2>/dev/null
"$bin" route -q $H --path - <fixtures/helsinki-route.geojson >"$tmp/route-stdin.txt" 2>/dev/null
if [ -s "$tmp/route-file.txt" ] && cmp -s "$tmp/route-file.txt" "$tmp/route-stdin.txt"; then echo "ok   route-path-stdin"; pass=$((pass + 1)); else echo "FAIL route-path-stdin"; fail=$((fail + 1)); fi
expect route-path-stdin-empty 1 "polarlux route: <stdin>: malformed JSON at byte 0 .*the file is empty" -- sh -c "\"\$0\" route -q fixtures/tiny.geojson --path - </dev/null" "$bin"
expect route-path-stdin-bad 1 "polarlux route: <stdin>: malformed JSON" -- sh -c "echo '{\"type\":' | \"\$0\" route -q fixtures/tiny.geojson --path -" "$bin"
expect walk-path-stdin 0 "^walk: 2 frames 64x48" -- sh -c "\"\$0\" walk -q $H --path - --size 64x48 --max-frames 2 --no-indirect -o \"\$1/wks\" <fixtures/helsinki-walk.geojson" "$bin" "$tmp"
expect heatmap-path-stdin 0 "written to" -- sh -c "\"\$0\" heatmap -q $H --res 20 --path - -o \"\$1/hps.png\" <fixtures/helsinki-route.geojson" "$bin" "$tmp"
. tests/cli/gis.sh
. tests/cli/network.sh
ls "$tmp"/*.tmp* >/dev/null 2>&1 && { echo "FAIL temporary files left"; fail=$((fail + 1)); }
echo "cli: $pass passed, $fail failed"
[ "$fail" -eq 0 ]

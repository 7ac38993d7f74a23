#!/bin/sh
# The README's first command (make demo): runs the main job on the bundled
# real district and says where the results are.
bin=$1
out=build/demo
set -e
mkdir -p "$out"
scene=fixtures/helsinki-centre.geojson
echo "== $scene: central Helsinki, OpenStreetMap (c) OpenStreetMap contributors, ODbL"
"$bin" info --quiet "$scene"
echo
echo "== night images"
"$bin" render --quiet "$scene" --eye 24.943483,60.167700,1.7 --target 24.946463,60.167773,5 --exposure 0.4 \
    -o "$out/helsinki-street.png" --pfm "$out/helsinki-street.pfm"
"$bin" render --quiet "$scene" --view aerial --size 720x1080 --texel 2 --exposure 0.4 -o "$out/helsinki-aerial.png"
"$bin" heatmap --quiet "$scene" -o "$out/helsinki-heatmap.png"
echo
echo "== how well lit are two walks (EN 13201 P-classes)"
"$bin" route --quiet "$scene" --path fixtures/helsinki-route.geojson --geojson "$out/helsinki-route.geojson"
echo
echo "== visibility from a pedestrian at (24.944296, 60.167723) looking east"
"$bin" vis --quiet "$scene" --at 24.944296,60.167723 --dir 0 --fov 90 | tail -2
echo
echo "== kiosk: bake the district once, then walk along a street from the bake"
"$bin" bake --quiet "$scene" --frames 64 --max-size 640x480 -o "$out/helsinki.plxb"
"$bin" walk --quiet "$out/helsinki.plxb" --path fixtures/helsinki-walk.geojson --size 480x360 --speed 10 --fps 1 \
    -o "$out/walk"
echo
echo "results in $out/:"
ls -1 "$out" | sed 's/^/  /'

#!/bin/sh
# The README's first command (make demo): runs the main job on the bundled
# fixtures and says where the results are.
bin=$1
set -e
mkdir -p build/demo
echo "== polarlux info fixtures/helsinki-centre.geojson (real OpenStreetMap district)"
"$bin" info fixtures/helsinki-centre.geojson
echo
echo "== polarlux gen eixample 30 30 -o build/demo/eixample-30x30.geojson"
"$bin" gen eixample 30 30 -o build/demo/eixample-30x30.geojson
"$bin" info build/demo/eixample-30x30.geojson

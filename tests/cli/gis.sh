# Command-line tests of issue 17 (GIS toolbox: dark results, lamp layers,
# CRS, coordinate options, GeoTIFF). Sourced by tests/cli/run.sh: uses its
# expect, $bin, $tmp, pass and fail.

# ---- dark results are announced ----
/usr/bin/python3 -c "
import json, sys
d = json.load(open('fixtures/tiny.geojson'))
d['features'] = [f for f in d['features'] if f['geometry']['type'] != 'Point']
json.dump(d, open(sys.argv[1], 'w'))" "$tmp/nolamp.geojson"
expect dark-heatmap-no-lamps 0 "nolamp\.geojson has no lamps, so every result is dark" -- "$bin" heatmap "$tmp/nolamp.geojson" --res 1 -o "$tmp/dark.png"
expect dark-heatmap-map 0 "warning: every pixel of the map is dark \(0 lx\): the scene has no lamps" -- "$bin" heatmap "$tmp/nolamp.geojson" --res 1 -o "$tmp/dark.png"
expect dark-heatmap-out-of-reach 0 "every pixel of the map is dark \(0 lx\): no lamp's light reaches it" -- "$bin" heatmap fixtures/tiny.geojson --box 200,200,220,220 --res 1 -o "$tmp/dark2.png"
expect dark-spots-no-lamps 0 "no street point is within a lamp's reach \(the scene has no lamps\)" -- "$bin" dark-spots "$tmp/nolamp.geojson"
expect dark-render-street 1 "the scene has no lamps, so the default street view" -- "$bin" render "$tmp/nolamp.geojson" --frames 1 -o "$tmp/dark.png"
expect dark-render-black 0 "the image is entirely black: the scene has no lamps" -- "$bin" render "$tmp/nolamp.geojson" --view aerial --size 32x24 --frames 1 -o "$tmp/dark.png"
expect dark-illum 0 "every point is dark \(0 lx\): the scene has no lamps" -- sh -c "echo '30 30' | '$bin' illum --frames 1 '$tmp/nolamp.geojson' --points -"
expect dark-vis-silent 0 "" -- "$bin" vis fixtures/tiny.geojson --at 30,30
if grep -q "no lamps" "$tmp/out"; then echo "FAIL dark-vis-silent: vis warned about lamps"; fail=$((fail + 1)); fi
expect dark-quiet 0 "" -- "$bin" heatmap -q "$tmp/nolamp.geojson" --res 1 -o "$tmp/dark.png"
if grep -q "warning" "$tmp/out"; then echo "FAIL dark-quiet: --quiet printed a warning"; fail=$((fail + 1)); fi

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
expect dark-heatmap-out-of-reach 0 "every pixel of the map is dark \(0 lx\): no lamp's light reaches it" -- "$bin" heatmap fixtures/tiny.geojson --box 90,50,110,70 --res 1 -o "$tmp/dark2.png"
expect dark-spots-no-lamps 0 "no street point is within a lamp's reach \(the scene has no lamps\)" -- "$bin" dark-spots "$tmp/nolamp.geojson"
expect dark-render-street 1 "the scene has no lamps, so the default street view" -- "$bin" render "$tmp/nolamp.geojson" --frames 1 -o "$tmp/dark.png"
expect dark-render-black 0 "the image is entirely black: the scene has no lamps" -- "$bin" render "$tmp/nolamp.geojson" --view aerial --size 32x24 --frames 1 -o "$tmp/dark.png"
expect dark-illum 0 "every point is dark \(0 lx\): the scene has no lamps" -- sh -c "echo '30 30' | '$bin' illum --frames 1 '$tmp/nolamp.geojson' --points -"
echo '{"type":"Feature","properties":{},"geometry":{"type":"LineString","coordinates":[[30,12,1.7],[-400,12,1.7]]}}' >"$tmp/away.geojson"
expect dark-walk-no-lamps 0 "nolamp\.geojson has no lamps, so every result is dark" -- "$bin" walk "$tmp/nolamp.geojson" --path "$tmp/away.geojson" --speed 100 --fps 1 --size 16x12 --no-indirect -o "$tmp/dwalk"
expect dark-walk-every-frame 0 "warning: every frame is entirely black: the scene has no lamps" -- "$bin" walk "$tmp/nolamp.geojson" --path "$tmp/away.geojson" --speed 100 --fps 1 --size 16x12 --no-indirect -o "$tmp/dwalk"
# walking away from tiny's lamps, looking ahead: the first frame lit, the five after it black
expect dark-walk-some-frames 0 "warning: 5 of 6 frames are entirely black \(the first: frame 2\): the camera sees no building and no lit ground: it looks away from the city" -- "$bin" walk fixtures/tiny.geojson --path "$tmp/away.geojson" --speed 100 --fps 1 --size 32x24 --no-indirect --no-glow -o "$tmp/dwalk2"
# flying high, looking down past the city's edge: said so (a kiosk pass's flight was told no lamp's light reached it)
echo '{"type":"Feature","properties":{"units":"m"},"geometry":{"type":"LineString","coordinates":[[30,12,300],[-3000,12,300]]}}' >"$tmp/high.geojson"
expect dark-walk-past-edge 0 "warning: every frame is entirely black: the camera sees no building and no lit ground: it looks down past the city's edge" -- "$bin" walk fixtures/tiny.geojson --path "$tmp/high.geojson" --pitch 45 --speed 500 --fps 1 --size 32x24 --no-indirect --no-glow -o "$tmp/dwalk5"
expect dark-walk-lit-silent 0 "" -- "$bin" walk fixtures/tiny.geojson --path "$tmp/away.geojson" --speed 100 --fps 1 --size 32x24 --no-indirect --no-glow --max-frames 1 -o "$tmp/dwalk3"
if grep -q "black" "$tmp/out"; then echo "FAIL dark-walk-lit-silent: a lit frame was called black"; fail=$((fail + 1)); fi
expect dark-bake-no-lamps 0 "nolamp\.geojson has no lamps, so every result is dark" -- "$bin" bake "$tmp/nolamp.geojson" --frames 1 -o "$tmp/nolamp.plxb"
if [ "$(grep -c "has no lamps" "$tmp/out")" != 1 ]; then echo "FAIL dark-bake-once: the note is not printed once (the twin's load is quiet)"; fail=$((fail + 1)); fi
expect dark-bake-walk 0 "nolamp\.plxb has no lamps, so every result is dark \(0 lx\); bake a scene with lamps" -- "$bin" walk "$tmp/nolamp.plxb" --path "$tmp/away.geojson" --speed 100 --fps 1 --size 16x12 --no-indirect -o "$tmp/dwalk4"
expect dark-vis-silent 0 "" -- "$bin" vis fixtures/tiny.geojson --at 30,30
if grep -q "no lamps" "$tmp/out"; then echo "FAIL dark-vis-silent: vis warned about lamps"; fail=$((fail + 1)); fi
expect dark-quiet 0 "" -- "$bin" heatmap -q "$tmp/nolamp.geojson" --res 1 -o "$tmp/dark.png"
if grep -q "warning" "$tmp/out"; then echo "FAIL dark-quiet: --quiet printed a warning"; fail=$((fail + 1)); fi

# ---- lamp layers (--lamps FILE) ----
# Helsinki split into a buildings file and a lamps file (GeoJSON, and CSV in
# lon/lat): the layers light the buildings exactly as the scene's own lamps.
/usr/bin/python3 - "$tmp" <<'PY'
import json, sys
t = sys.argv[1]
d = json.load(open('fixtures/helsinki-centre.geojson'))
pts = [f for f in d['features'] if f.get('geometry') and f['geometry'].get('type') == 'Point']
d['features'] = [f for f in d['features'] if f not in pts]
json.dump(d, open(t + '/hel-bld.geojson', 'w'))
json.dump({'type': 'FeatureCollection', 'features': pts}, open(t + '/hel-lamps.geojson', 'w'))
with open(t + '/hel-lamps.csv', 'w') as f:
    f.write('# crs: EPSG:4326\nid;lon;lat;z;intensity;radius\n')
    for p in pts:
        q = p.get('properties') or {}
        if not (q.get('lamp') is True or q.get('highway') == 'street_lamp'):
            continue
        f.write('%s;%r;%r;%s;%s;%s\n' % (q.get('id', ''), p['geometry']['coordinates'][0], p['geometry']['coordinates'][1],
                                          q.get('z', ''), q.get('intensity', ''), q.get('radius', '')))
PY
printf '# crs: lonlat\n24.9443 60.1716\n24.9447 60.1713\n24.9436 60.1718\n24.9453 60.1717\n' >"$tmp/hel-pts.txt"
"$bin" illum -q --no-indirect fixtures/helsinki-centre.geojson --points "$tmp/hel-pts.txt" >"$tmp/hel-a.txt" 2>/dev/null
"$bin" illum -q --no-indirect "$tmp/hel-bld.geojson" --lamps "$tmp/hel-lamps.geojson" --points "$tmp/hel-pts.txt" >"$tmp/hel-b.txt" 2>/dev/null
"$bin" illum -q --no-indirect "$tmp/hel-bld.geojson" --lamps "$tmp/hel-lamps.csv" --points "$tmp/hel-pts.txt" >"$tmp/hel-c.txt" 2>/dev/null
# Each file projects lon/lat about its own centre, so the local frames differ
# by a scale of ~1e-5: equal to 1e-3 relative.
close_lux() {
    paste "$1" "$2" | awk '{ d = $4 - $9; if (d < 0) d = -d; if ($1 != $6 || $2 != $7 || d > 1e-3 * ($4 + 0.01)) bad = 1; s += $4 }
        END { exit !(NR == 4 && !bad && s > 0) }'
}
if close_lux "$tmp/hel-a.txt" "$tmp/hel-b.txt"; then
    echo "ok   layers-geojson-equal"; pass=$((pass + 1)); else echo "FAIL layers-geojson-equal"; diff "$tmp/hel-a.txt" "$tmp/hel-b.txt" | head -5; fail=$((fail + 1)); fi
if close_lux "$tmp/hel-a.txt" "$tmp/hel-c.txt"; then
    echo "ok   layers-csv-lonlat-equal"; pass=$((pass + 1)); else echo "FAIL layers-csv-lonlat-equal"; diff "$tmp/hel-a.txt" "$tmp/hel-c.txt" | head -5; fail=$((fail + 1)); fi
expect layers-info-count 0 "^lamps: [1-9][0-9]*$" -- "$bin" info -q "$tmp/hel-bld.geojson" --lamps "$tmp/hel-lamps.geojson"
expect layers-twice-merged 0 "at the same position as lamp [0-9]+ .*merged into it" -- "$bin" info "$tmp/hel-bld.geojson" --lamps "$tmp/hel-lamps.geojson" --lamps "$tmp/hel-lamps.csv"
printf 'x,y,z,intensity,id\n30,30,6,800,A\n50,10,8,,B\n5,5,5,1000,C\n' >"$tmp/l.csv"
expect layers-csv-metres 0 "^lamps: 2$" -- "$bin" info -q "$tmp/nolamp.geojson" --lamps "$tmp/l.csv"
expect layers-csv-buried 0 "l\.csv: feature 4 \(C\): lamp is inside building 0 \(A\); left out" -- "$bin" info "$tmp/nolamp.geojson" --lamps "$tmp/l.csv"
expect layers-frame-mismatch 1 "l\.csv: the lamps are in metres \(x,y\) but the scene is in lon/lat" -- "$bin" info fixtures/helsinki-centre.geojson --lamps "$tmp/l.csv"
printf 'x,y\n30,oops\n' >"$tmp/bad.csv"
expect layers-csv-bad 1 "bad\.csv:2: a position or number is missing or not a finite number" -- "$bin" heatmap "$tmp/nolamp.geojson" --lamps "$tmp/bad.csv" -o "$tmp/x.png"
printf 'name,height\na,3\n' >"$tmp/bad2.csv"
expect layers-csv-no-xy 1 "the CSV header names no x,y or lon,lat columns" -- "$bin" info "$tmp/nolamp.geojson" --lamps "$tmp/bad2.csv"
expect layers-missing 1 "--lamps $tmp/none\.csv: .*No such file" -- "$bin" info "$tmp/nolamp.geojson" --lamps "$tmp/none.csv"
expect layers-needs-file 2 "--lamps needs a GeoJSON or CSV file" -- "$bin" info "$tmp/nolamp.geojson" --lamps

# ---- CRS and coordinate options in the scene's own coordinates ----
expect coords-vis-lonlat 0 "^# visible buildings from \(24\.9440000, 60\.1716000\)" -- "$bin" vis -q fixtures/helsinki-centre.geojson --at 24.944,60.1716
expect coords-vis-metres-on-lonlat 2 "--at 0,-431\.5 is not lon/lat, and the scene is in lon/lat" -- "$bin" vis -q fixtures/helsinki-centre.geojson --at 0,-431.5
printf '24.944 60.1716\n' >"$tmp/ll.txt"
printf '# crs: local\n-13.5 -2.92\n' >"$tmp/loc.txt"
expect coords-points-default-scene 0 "^24\.94[0-9]* 60\.17[0-9]* [0-9.]+ [0-9]+$" -- "$bin" vis -q fixtures/helsinki-centre.geojson --points "$tmp/ll.txt"
expect coords-points-local 0 "^-13\.5 -2\.9199" -- "$bin" vis -q fixtures/helsinki-centre.geojson --points "$tmp/loc.txt"
expect coords-points-crs-option 1 "ll\.txt:1: point \(24\.944, 60\.1716\) is inside" -- "$bin" vis -q fixtures/helsinki-centre.geojson --points "$tmp/ll.txt" --points-crs local
expect coords-points-crs-bad 2 "points crs 'EPSG:2154' is not lonlat, local or the scene's CRS" -- "$bin" vis -q fixtures/helsinki-centre.geojson --points "$tmp/ll.txt" --points-crs EPSG:2154
expect coords-points-lonlat-on-metres 1 "the points are in lon/lat but the scene is in metres" -- "$bin" vis -q fixtures/tiny.geojson --points "$tmp/ll.txt" --points-crs lonlat
expect coords-render-eye 0 "^street view 32x24 from \(24\.9434830, 60\.1677000, 1\.7\)" -- "$bin" render -q --no-indirect fixtures/helsinki-centre.geojson --eye 24.943483,60.167700,1.7 --target 24.946463,60.167773,5 --size 32x24 -o "$tmp/e.png"
expect coords-heatmap-box 0 "^heatmap: 120x" -- "$bin" heatmap -q fixtures/helsinki-centre.geojson --box 24.94249,60.166922,24.953326,60.168641 --res 5 -o "$tmp/hb.png"
# A projected scene (Lambert-93, EPSG:2154): its crs is kept, coordinates are
# metres without properties.units, and every GeoJSON output names the crs.
/usr/bin/python3 - "$tmp" <<'PY'
import json, sys
d = json.load(open('fixtures/tiny.geojson'))
del d['properties']['units']
d['crs'] = {'type': 'name', 'properties': {'name': 'urn:ogc:def:crs:EPSG::2154'}}
for f in d['features']:
    g = f['geometry']
    if g['type'] == 'Point':
        g['coordinates'] = [650000 + g['coordinates'][0], 6860000 + g['coordinates'][1]]
    else:
        g['coordinates'] = [[[650000 + x, 6860000 + y] for x, y in r] for r in g['coordinates']]
json.dump(d, open(sys.argv[1] + '/l93.geojson', 'w'))
PY
expect crs-info 0 "^crs: urn:ogc:def:crs:EPSG::2154$" -- "$bin" info "$tmp/l93.geojson"
if grep -q "reading them as metres" "$tmp/out"; then echo "FAIL crs-info: a projected crs still warned"; fail=$((fail + 1)); fi
expect crs-vis 0 "" -- "$bin" vis -q "$tmp/l93.geojson" --at 650030,6860030 --geojson "$tmp/l93-vis.geojson"
expect crs-lit 0 "" -- "$bin" lit -q "$tmp/l93.geojson" --lamp L1 -o "$tmp/l93-lit.geojson"
expect crs-spots 0 "" -- "$bin" dark-spots -q "$tmp/l93.geojson" --count 3 -o "$tmp/l93-spots.geojson"
for f in l93-vis l93-lit l93-spots; do
    if /usr/bin/python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
assert d['crs'] == {'type': 'name', 'properties': {'name': 'urn:ogc:def:crs:EPSG::2154'}}
xs = [c for f in d['features'] for c in json.dumps(f['geometry']['coordinates']).replace('[', ' ').replace(']', ' ').replace(',', ' ').split()]
assert float(xs[0]) > 600000" "$tmp/$f.geojson"; then echo "ok   crs-roundtrip-$f"; pass=$((pass + 1)); else echo "FAIL crs-roundtrip-$f"; fail=$((fail + 1)); fi
done
printf 'x,y\n650030,6860030\n' >"$tmp/l93.csv"
expect crs-layer-csv 0 "^lamps: 4$" -- "$bin" info -q "$tmp/l93.geojson" --lamps "$tmp/l93.csv"
printf '# crs: EPSG:3857\nx,y\n650030,6860030\n' >"$tmp/l93b.csv"
expect crs-layer-mismatch 1 "the lamps are in EPSG:3857 but the scene in urn:ogc:def:crs:EPSG::2154" -- "$bin" info -q "$tmp/l93.geojson" --lamps "$tmp/l93b.csv"

# ---- GeoTIFF heat maps read back (tests/tools/tiff_probe, libtiff + libgeotiff) ----
probe=$(dirname "$bin")/tests/tiff_probe
# tiff_check NAME SCENE TIF PIXELS...: the pixel values equal illum at the
# pixel centres (from the file's own tie point and scale) to float32 precision.
tiff_check() {
    name=$1; scene=$2; tif=$3; shift 3
    "$probe" "$tif" "$@" >"$tmp/probe.txt" || { echo "FAIL $name: tiff_probe"; fail=$((fail + 1)); return; }
    awk '/^scale/ { sx = $2; sy = $3 } /^tie/ { x0 = $4; y0 = $5 }
         /^pixel/ { printf "%.17g %.17g\n", x0 + ($2 + 0.5) * sx, y0 - ($3 + 0.5) * sy }' "$tmp/probe.txt" >"$tmp/centres.txt"
    "$bin" illum -q --no-indirect "$scene" --points "$tmp/centres.txt" >"$tmp/centres-E.txt" 2>/dev/null
    if grep '^pixel' "$tmp/probe.txt" | paste - "$tmp/centres-E.txt" | awk '
        { v = $4; e = $8; if (e == "nan") { if (v != "nan") bad = 1; next } d = v - e; if (d < 0) d = -d
          if (d > 1e-6 * e + 1e-30) bad = 1; if (e > 0) lit++ }
        END { exit !(NR > 0 && !bad && lit > 0) }'; then
        echo "ok   $name"; pass=$((pass + 1)); else echo "FAIL $name"; paste "$tmp/probe.txt" "$tmp/centres-E.txt" | head; fail=$((fail + 1)); fi
}
expect tiff-tiny 0 "^heatmap: 80x60 pixels at 2 m, float32 GeoTIFF of lux" -- "$bin" heatmap -q fixtures/tiny.geojson --res 2 -o "$tmp/t.tif"
expect tiff-tiny-georef 0 "^keys model 1 raster 1 geographic -1 projected 32767 units 9001$" -- "$probe" "$tmp/t.tif"
expect tiff-tiny-size 0 "^size 80 60 bands 1 bits 32 format float$" -- "$probe" "$tmp/t.tif"
expect tiff-tiny-tie 0 "^tie 0 0 -50 70$" -- "$probe" "$tmp/t.tif"
tiff_check tiff-tiny-values fixtures/tiny.geojson "$tmp/t.tif" 35,25 38,26 40,27 41,28 44,30 45,22 50,30 30,20 52,25 10,50 0,0
expect tiff-helsinki 0 "float32 GeoTIFF" -- "$bin" heatmap -q fixtures/helsinki-centre.geojson --res 8 -o "$tmp/h.tif"
expect tiff-helsinki-wgs84 0 "^keys model 2 raster 1 geographic 4326 " -- "$probe" "$tmp/h.tif"
expect tiff-description-eh 0 "^description polarlux heatmap: band 1 = direct horizontal ground illuminance E_h" -- "$probe" "$tmp/h.tif"
# helper-64's GIS pass: the band said E_h for every --quantity
expect tiff-v 0 "float32 GeoTIFF" -- "$bin" heatmap -q fixtures/tiny.geojson --res 4 --quantity v --facing 90 -o "$tmp/hv.tif"
expect tiff-description-ev 0 "^description polarlux heatmap: band 1 = direct vertical illuminance E_v in lux at 1\.5 m above pixel centres, facing 90 deg" -- "$probe" "$tmp/hv.tif"
# a geographic crs other than WGS 84 (ETRS89, EPSG:4258) is lon/lat: it was read as metres, every building within 2 cm
/usr/bin/python3 -c "
import json, sys
d = json.load(open('fixtures/helsinki-centre.geojson'))
d['crs'] = {'type': 'name', 'properties': {'name': 'urn:ogc:def:crs:EPSG::4258'}}
json.dump(d, open(sys.argv[1], 'w'))
g = json.load(open(sys.argv[3]))
g['crs'] = {'type': 'name', 'properties': {'name': 'EPSG:4258'}}
g.get('properties', {}).pop('units', None)
json.dump(g, open(sys.argv[2], 'w'))" "$tmp/h4258.geojson" "$tmp/m4258.geojson" fixtures/eixample-4x4.geojson
expect crs-etrs89-lonlat 0 "^coordinates: lon/lat \(urn:ogc:def:crs:EPSG::4258\), projected about lon0 24\.94" -- "$bin" info -q "$tmp/h4258.geojson"
expect crs-etrs89-bounds 0 "^bounds: .* \(1108\.4 x 1742\.9 m\)" -- "$bin" info -q "$tmp/h4258.geojson"
expect tiff-etrs89 0 "float32 GeoTIFF" -- "$bin" heatmap -q "$tmp/h4258.geojson" --res 20 -o "$tmp/h4258.tif"
expect tiff-etrs89-key 0 "^keys model 2 raster 1 geographic 4258 " -- "$probe" "$tmp/h4258.tif"
# metres under a geographic crs: refused (the outputs would carry degrees)
expect crs-geographic-metres 1 "feature [0-9]+ .*: coordinates exceed the lon/lat range \(-180\.\.180, -90\.\.90\), but the crs EPSG:4258 names lon/lat degrees" -- "$bin" info -q "$tmp/m4258.geojson"
# one CRS written two ways ("EPSG:3067", "urn:ogc:def:crs:EPSG::3067") is the same CRS for points and lamp files
/usr/bin/python3 -c "
import json, sys
g = json.load(open('fixtures/eixample-4x4.geojson'))
g['crs'] = {'type': 'name', 'properties': {'name': 'urn:ogc:def:crs:EPSG::3067'}}
g.get('properties', {}).pop('units', None)
json.dump(g, open(sys.argv[1], 'w'))" "$tmp/e3067.geojson"
expect crs-points-same-code 0 "^50 50 0 [0-9.e+-]+ 0$" -- sh -c "printf '# crs: EPSG:3067\n50 50\n' | '$bin' illum -q --no-indirect '$tmp/e3067.geojson' --points -"
expect crs-points-other-code 1 "points crs 'EPSG:2154' is not lonlat, local or the scene's CRS" -- sh -c "printf '# crs: EPSG:2154\n50 50\n' | '$bin' illum -q --no-indirect '$tmp/e3067.geojson' --points -"
# a route file's own crs: another one is refused (it was scored without a word); the scene's own reads as its metres
printf '{"type":"FeatureCollection","crs":{"type":"name","properties":{"name":"urn:ogc:def:crs:EPSG::2154"}},"features":[{"type":"Feature","properties":{},"geometry":{"type":"LineString","coordinates":[[10,10],[50,10]]}}]}' >"$tmp/r2154.json"
sed 's/2154/3067/' "$tmp/r2154.json" >"$tmp/r3067.json"
expect crs-route-other 1 "r2154\.json: the file's crs is urn:ogc:def:crs:EPSG::2154 but the scene's is urn:ogc:def:crs:EPSG::3067" -- "$bin" route -q "$tmp/e3067.geojson" --path "$tmp/r2154.json"
expect crs-route-same 0 "^#0 +all +40\.0 " -- "$bin" route -q "$tmp/e3067.geojson" --path "$tmp/r3067.json"
# a scene mixing lon/lat and metres: the warning names the feature out of range (it named feature 0) and counts the rest
printf '{"type":"FeatureCollection","features":[\n{"type":"Feature","properties":{"height":10},"geometry":{"type":"Polygon","coordinates":[[[24.94,60.17],[24.9401,60.17],[24.9401,60.1701],[24.94,60.1701],[24.94,60.17]]]}},\n{"type":"Feature","properties":{"highway":"street_lamp"},"geometry":{"type":"Point","coordinates":[385920,6672300]}}]}\n' >"$tmp/mixed.geojson"
expect crs-mixed-names-feature 0 "warning: .*mixed\.geojson: feature 1 \(line 3, column 1\): coordinates exceed the lon/lat range .*; 1 of the 2 features lie wholly within it: if those are lon/lat, the file mixes coordinate systems" -- "$bin" info "$tmp/mixed.geojson"
tiff_check tiff-helsinki-values fixtures/helsinki-centre.geojson "$tmp/h.tif" 30,60 35,70 40,80 45,90 50,100 55,110 60,120 65,130 70,140 75,150 80,160 85,170
expect tiff-l93 0 "float32 GeoTIFF" -- "$bin" heatmap -q "$tmp/l93.geojson" --res 2 -o "$tmp/l93.tif"
expect tiff-l93-epsg 0 "^keys model 1 raster 1 geographic -1 projected 2154 " -- "$probe" "$tmp/l93.tif"
tiff_check tiff-l93-values "$tmp/l93.geojson" "$tmp/l93.tif" 35,25 38,26 40,27 41,28 44,30 50,30
# PNG: a world file beside it; the colour scale from the 2nd-98th percentile
expect png-world 0 "world file \.pgw" -- "$bin" heatmap -q fixtures/tiny.geojson --res 2 -o "$tmp/w.png"
if [ "$(sed -n '1p;4p;5p;6p' "$tmp/w.pgw" | tr '\n' ' ')" = "2 -2 -49 69 " ]; then echo "ok   png-world-file"; pass=$((pass + 1)); else echo "FAIL png-world-file"; cat "$tmp/w.pgw"; fail=$((fail + 1)); fi
# Seven lamps at one spot no longer push the colour scale to 1000 lx
/usr/bin/python3 -c "
import json, sys
d = json.load(open('fixtures/tiny.geojson'))
d['features'] += [{'type': 'Feature', 'properties': {'lamp': True, 'z': 6, 'intensity': 1000},
                   'geometry': {'type': 'Point', 'coordinates': [80, 40]}}] * 7
json.dump(d, open(sys.argv[1], 'w'))" "$tmp/dup7.geojson"
expect png-scale-robust 0 "scale 0\.1\.\.(10|20|50|100|200) lx \(2nd-98th percentile" -- "$bin" heatmap -q "$tmp/dup7.geojson" --res 0.5 -o "$tmp/dup7.png"

# ---- --mem bounds the heat map's own buffers (strips) ----
# --mem 40M: the engine takes ~32 MB of it; without strips this map alone
# would take 54 MB of buffers.
if [ -x /usr/bin/time ]; then timed="/usr/bin/time -f %M -o $tmp/rss-heat"; else timed=""; fi
expect mem-heatmap-strips 0 "computed in strips of [0-9]+ rows to stay within --mem" -- $timed "$bin" heatmap -q fixtures/tiny.geojson --res 0.15 --mem 40M -o "$tmp/m40.png"
expect mem-heatmap-whole 0 "^heatmap: 1067x800 " -- "$bin" heatmap -q fixtures/tiny.geojson --res 0.15 -o "$tmp/m1g.png"
if cmp -s "$tmp/m40.png" "$tmp/m1g.png"; then echo "ok   mem-heatmap-same-map"; pass=$((pass + 1)); else echo "FAIL mem-heatmap-same-map"; fail=$((fail + 1)); fi
expect mem-heatmap-too-small 3 "a 800x600 map needs [0-9]+ bytes of buffers, and --mem leaves [0-9]+ after the engine" -- "$bin" heatmap -q fixtures/tiny.geojson --res 0.2 --mem 4M -o "$tmp/m28.png"
if [ -n "$timed" ]; then
    /usr/bin/time -f "%M" -o "$tmp/rss-info" "$bin" info -q fixtures/tiny.geojson --mem 40M >/dev/null 2>&1
    # peak resident KB above the same program loading the scene: at most --mem
    if [ $(( $(tail -1 "$tmp/rss-heat") - $(tail -1 "$tmp/rss-info") )) -le 40960 ]; then echo "ok   mem-heatmap-rss"; pass=$((pass + 1));
    else echo "FAIL mem-heatmap-rss: $(tail -1 "$tmp/rss-heat") KB vs $(tail -1 "$tmp/rss-info") KB"; fail=$((fail + 1)); fi
fi

# ---- route --geojson: one feature per segment, flat properties ----
"$bin" route -q fixtures/helsinki-centre.geojson --path fixtures/helsinki-route.geojson --geojson "$tmp/rs.geojson" >"$tmp/rs.txt"
if /usr/bin/python3 - "$tmp/rs.geojson" "$tmp/rs.txt" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
rows = [l.split() for l in open(sys.argv[2]) if l[:1] == ' ']   # segment rows of the table
assert len(d['features']) == len(rows) and rows
for f, r in zip(d['features'], rows):
    p = f['properties']
    assert all(not isinstance(v, (dict, list)) for v in p.values())
    assert f['geometry']['type'] == 'LineString' and len(f['geometry']['coordinates']) == 2
    assert int(r[0]) == p['segment'] and abs(float(r[2]) - p['mean_lx']) < 1e-3 and abs(float(r[1]) - p['length_m']) < 0.1
    assert p['line_p_class'] in ('P1', 'P2', 'P3', 'P4', 'P5', 'P6', '-')
PY
then echo "ok   route-geojson-flat"; pass=$((pass + 1)); else echo "FAIL route-geojson-flat"; fail=$((fail + 1)); fi

# ---- lit: one polygon per connected lit region, holes where shadows are ----
# The union's area (from the written GeoJSON: outer rings less holes) equals
# the summed area of the pieces the engine gives; no two polygons share an
# edge (they would have merged).
lit_union_check() {
    name=$1; shift
    "$bin" lit -q "$@" -o "$tmp/lu.geojson" >"$tmp/lu.txt" 2>&1 || { echo "FAIL $name: lit failed"; fail=$((fail + 1)); return; }
    if /usr/bin/python3 - "$tmp/lu.geojson" "$tmp/lu.txt" <<'PY'
import json, math, re, sys
d = json.load(open(sys.argv[1]))
txt = open(sys.argv[2]).read()
pieces = float(re.search(r'\(pieces ([0-9.]+) m\^2\)', txt).group(1))
lonlat = 'properties' not in d or d['properties'].get('units') != 'm'
lat0 = 60.1716264
def xy(p):
    return (p[0] * 111320.0 * math.cos(math.radians(lat0)), p[1] * 110540.0) if lonlat else (p[0], p[1])
def area(r):
    r = [xy(p) for p in r]
    r = [(x - r[0][0], y - r[0][1]) for x, y in r]
    return 0.5 * sum(a[0] * b[1] - b[0] * a[1] for a, b in zip(r, r[1:]))
ground = [f for f in d['features'] if f['properties'].get('kind') == 'ground']
total, edges = 0.0, {}
for f in ground:
    rings = f['geometry']['coordinates']
    assert area(rings[0]) > 0 and all(area(h) < 0 for h in rings[1:])
    total += sum(area(r) for r in rings)
    for r in rings:
        for a, b in zip(r, r[1:]):
            edges.setdefault((tuple(a), tuple(b)), set()).add(id(f))
for (a, b), fs in edges.items():
    assert not ((b, a) in edges and edges[(b, a)] - fs), 'two polygons share an edge'
assert abs(total - pieces) <= 1e-6 * pieces + (1e-3 if lonlat else 1e-9), (total, pieces)
PY
    then echo "ok   $name"; pass=$((pass + 1)); else echo "FAIL $name"; cat "$tmp/lu.txt"; fail=$((fail + 1)); fi
}
expect lit-union-one 0 "1 lit ground polygons, 7 lit facade polygons, written to .*; the ground is the union of 17 pieces" -- "$bin" lit -q fixtures/tiny.geojson --lamp L1 -o "$tmp/lu1.geojson"
lit_union_check lit-union-tiny fixtures/tiny.geojson --lamp L1
lit_union_check lit-union-helsinki-hole fixtures/helsinki-centre.geojson --lamp 10
expect lit-union-hole 0 "" -- /usr/bin/python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
assert sum(len(f['geometry']['coordinates']) - 1 for f in d['features'] if f['properties'].get('kind') == 'ground') >= 1" "$tmp/lu.geojson"
lit_union_check lit-union-helsinki fixtures/helsinki-centre.geojson --lamp 100

# ---- dark-spots within --mem (check-full: several seconds) ----
# A tight --mem keeps only some candidates at a time and takes more passes
# over the grid; the spots must be those of one sort of every street point.
if [ -z "$PLX_TEST_QUICK" ]; then
    expect spots-mem-roomy 0 "" -- "$bin" dark-spots -q fixtures/tiny.geojson --res 0.1 --count 30 --spacing 8 -o "$tmp/spots-roomy.geojson"
    expect spots-mem-tight 0 "dark-spots: [0-9]+ passes over the grid: --mem leaves room for" -- "$bin" dark-spots fixtures/tiny.geojson --res 0.1 --count 30 --spacing 8 --mem 600K -o "$tmp/spots-tight.geojson"
    if cmp -s "$tmp/spots-roomy.geojson" "$tmp/spots-tight.geojson"; then pass=$((pass + 1)); else echo "FAIL spots-mem-same: tight --mem changed the spots"; fail=$((fail + 1)); fi
fi

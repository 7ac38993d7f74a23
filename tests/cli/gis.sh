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

# Command-line tests of route --network, annotate and tiles (issue 15);
# sourced by tests/cli/run.sh (uses its expect, $bin, $tmp).
net="fixtures/net-detour.geojson --network fixtures/net-detour-streets.geojson"
expect net-best-lit 0 "^best-lit +300\.0 +69\.0 .*\+50\.0%$" -- "$bin" route -q $net --from 0,0 --to 200,0 --geojson "$tmp/net.geojson"
expect net-shortest 0 "^shortest +200\.0 +200\.0 +0\.000 +0\.000 +0\.000 +0\.000  - +- +\+0\.0%$" -- "$bin" route -q $net --from 0,0 --to 200,0
expect net-geojson 0 "" -- sh -c "grep -q '\"route\":\"best-lit\"' '$tmp/net.geojson' && grep -q '\"route\":\"shortest\"' '$tmp/net.geojson' && grep -q '\"mean_lux\"' '$tmp/net.geojson'"
expect net-light-weight 0 "^best-lit +200\.0 +200\.0 " -- "$bin" route -q $net --from 0,0 --to 200,0 --dark-weight 0.5
# a weight that would overflow the costs to infinity (and read as unconnected ends) is refused
expect net-weight-too-large 2 "route: --dark-weight '1e308' is more than 1000000" -- "$bin" route -q $net --from 0,0 --to 200,0 --dark-weight 1e308
expect net-weight-largest 0 "^best-lit +300\.0 +69\.0 " -- "$bin" route -q $net --from 0,0 --to 200,0 --dark-weight 1e6
expect net-max-detour 0 "^best-lit +200\.0 " -- "$bin" route -q $net --from 0,0 --to 200,0 --max-detour 0.2
expect net-max-detour-says 0 "weight lowered from 3 by --max-detour 0\.2" -- "$bin" route -q $net --from 0,0 --to 200,0 --max-detour 0.2
# the weight lowered by --max-detour to a thousandth of itself at any W (a
# step of W/1000 from 0 left W = 1e6 at 0 where W = 3 finds 0.763)
expect net-capped-any-weight 0 "cost = length \+ 0\.763[0-9]* x dark metres.*weight lowered from 1e\+06" -- "$bin" route -q $net --from 0,0 --to 200,0 --max-detour 0.2 --dark-weight 1e6
expect net-max-detour-loose 0 "^best-lit +300\.0 " -- "$bin" route -q $net --from 0,0 --to 200,0 --max-detour 0.6
expect net-far-start 1 "route: --from 0,-80 is 80\.0 m from the nearest street of fixtures/net-detour-streets\.geojson \(more than --snap 50 m\)" -- "$bin" route -q $net --from 0,-80 --to 200,0
expect net-unreachable 1 "no path from --from 0,0 to --to 410,400: they lie on unconnected parts of the network \(it has 2 parts\)" -- "$bin" route -q $net --from 0,0 --to 410,400
# each end's part is measured, and a small one named (helper-64: a 42 m fragment 1.7 m away took the Helsinki route)
expect net-unreachable-parts 1 "\(it has 2 parts\): --from snapped 0\.0 m to a part of [0-9]+ m of streets, --to 0\.0 m to one of [0-9]+ m" -- "$bin" route -q $net --from 0,0 --to 410,400
expect net-unreachable-helsinki 1 "--from snapped 1\.7 m to a part of 42 m of streets, --to 1\.0 m to one of 98413 m \(the smaller is likely an isolated piece of the street data" -- "$bin" route -q fixtures/helsinki-centre.geojson --network fixtures/helsinki-streets.geojson --from 24.9438573,60.1716161 --to 24.9509247,60.1681328
expect net-swapped-lonlat 1 "--from 60\.1677,24\.9443 is [0-9.]+ m from the nearest street .*; 24\.9443,60\.1677 is on a street: lon and lat swapped\?$" -- "$bin" route -q fixtures/helsinki-centre.geojson --network fixtures/helsinki-streets.geojson --from 60.1677,24.9443 --to 24.9509247,60.1681328
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[]}' >"$tmp/empty-net.json"
expect net-empty 1 "route: $tmp/empty-net\.json: no LineString features" -- "$bin" route -q fixtures/net-detour.geojson --network "$tmp/empty-net.json" --from 0,0 --to 1,1
expect net-missing-to 2 "--network needs --from X,Y and --to X,Y" -- "$bin" route -q $net --from 0,0
expect net-help 0 "cost = length \+ W x dark metres" -- "$bin" route --network x --help
expect net-helsinki 0 "^cost = length .*network [0-9]+ nodes, [0-9]+ edges" -- "$bin" route -q fixtures/helsinki-centre.geojson --network fixtures/helsinki-streets.geojson --from 24.9400,60.1660 --to 24.9480,60.1770
# route scores only the edges a route can take: the lit Esplanadi's 506.5 m walk needs 30 of the 4,717
# (the same routes and sums as scoring all: test_network's test_route_scoring_against_every_edge)
esp="fixtures/helsinki-centre.geojson --network fixtures/helsinki-streets.geojson --from 24.9432847,60.1676957 --to 24.9524231,60.1678992"
expect net-helsinki-edges-scored 0 "^polarlux route: note: 30 of the 4717 edges scored \(those a walk from --from to --to no longer than the shortest route's cost can take\)$" -- "$bin" route $esp
expect net-helsinki-lit-route 0 "^best-lit +506\.5 +0\.0 +3\.402 +18\.758 +0\.022 +1\.358  P1 " -- "$bin" route -q $esp
expect annotate 0 "^annotate: 6 edges, 6 nodes, 570 m of street" -- "$bin" annotate -q $net -o "$tmp/ann.geojson" --csv "$tmp/ann.csv"
expect annotate-csv 0 "^way/2,300\.000,69\.000,0\.000,0\.2300,9\.4414,0\.0000,-,1\.6900,0\.0000,0\.0000,-$" -- cat "$tmp/ann.csv"
expect annotate-csv-head 0 "^osm_id,length_m,dark_m,blocked_m,dark_share,mean_lux,min_lux,class,factor,min_ev_lux,min_sc_lux,class_h$" -- cat "$tmp/ann.csv"
# the SPEC §6 class with the facial criterion: P1 on the ground, P5 with min E_v 1.287 lx (P4 needs 1.5),
# as 'route --path' gives on the same line (its class_fr)
fac="fixtures/net-facial.geojson --network fixtures/net-facial-streets.geojson"
expect net-facial 0 "^best-lit +40\.0 +0\.0 +32\.072 +40\.647 +1\.287 +2\.070  P1 +P5 " -- "$bin" route -q $fac --from 0,0 --to 40,0 --geojson "$tmp/fac.geojson"
expect net-facial-geojson 0 "" -- sh -c "grep -q '\"min_sc_lux\":2\.07' '$tmp/fac.geojson' && grep -q '\"class\":\"P5\",\"class_h\":\"P1\"' '$tmp/fac.geojson'"
expect net-facial-path 0 "^lit-street all .* P1 +1\.287 +1\.287 +2\.070 +2\.070 P5" -- "$bin" route -q fixtures/net-facial.geojson --path fixtures/net-facial-streets.geojson
expect annotate-facial 0 "^way/10,40\.000,0\.000,0\.000,0\.0000,40\.6465,32\.0721,P5,1\.0000,1\.2870,2\.0701,P1$" -- sh -c "'$bin' annotate -q $fac -o '$tmp/fac-ann.geojson' --csv '$tmp/fac.csv' >/dev/null && cat '$tmp/fac.csv'"
expect annotate-facial-geojson 0 "" -- grep -q '"min_sc_fw_lux":2\.07.*"min_sc_lux":2\.07.*"class":"P5","class_h":"P1"' "$tmp/fac-ann.geojson"
# route over annotate's output reads the edges' light instead of scoring
# them: the same tables as over the plain network; settings, scene or
# properties that differ from what the scores were made with are refused
for extra in "" "--max-detour 0.2" "--dark-weight 0.5"; do
    "$bin" route -q $net --from 0,0 --to 200,0 $extra >"$tmp/plain-route.txt" 2>&1
    expect "net-annotated-same${extra:+ $extra}" 0 "" -- sh -c "'$bin' route -q fixtures/net-detour.geojson --network '$tmp/ann.geojson' --from 0,0 --to 200,0 $extra | cmp - '$tmp/plain-route.txt'"
done
expect net-annotated-note 0 "note: the 6 edges' light read from annotate's scores in $tmp/ann\.geojson" -- "$bin" route fixtures/net-detour.geojson --network "$tmp/ann.geojson" --from 0,0 --to 200,0
expect net-annotated-dark-lux 2 "route: $tmp/ann\.geojson: annotate's scores: its edges were scored with --dark-lux 1, not 2: pass --dark-lux 1, or run annotate again" -- "$bin" route -q fixtures/net-detour.geojson --network "$tmp/ann.geojson" --from 0,0 --to 200,0 --dark-lux 2
expect net-annotated-other-scene 1 "annotate's scores: its edges were scored on another scene or light \(buildings, lamps, photon frames: 1, 9, 0 there; 1, 23, 0 here\)" -- "$bin" route -q fixtures/net-facial.geojson --network "$tmp/ann.geojson" --from 0,0 --to 40,0
# coordinates that need 17 digits come back to the same bits (cJSON's own
# 15 digits wrote 100.00000000000001 as 100): the same tables and GeoJSON
x=100.00000000000001
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{"osm_id":"a"},"geometry":{"type":"LineString","coordinates":[[0,0],[%s,0],[200,0]]}},{"type":"Feature","properties":{"osm_id":"b"},"geometry":{"type":"LineString","coordinates":[[0,0],[0,50],[%s,50],[200,50],[200,0]]}},{"type":"Feature","properties":{"osm_id":"c"},"geometry":{"type":"LineString","coordinates":[[%s,0],[%s,50]]}}]}' $x $x $x $x >"$tmp/net17.geojson"
"$bin" annotate -q fixtures/net-detour.geojson --network "$tmp/net17.geojson" -o "$tmp/ann17.geojson" >/dev/null 2>&1
for w in 0 3; do
    "$bin" route -q fixtures/net-detour.geojson --network "$tmp/net17.geojson" --from 0,0 --to 200,0 --dark-weight $w --geojson "$tmp/r17-plain.json" >"$tmp/r17-plain.txt" 2>&1
    expect "net-annotated-17-digits-w$w" 0 "" -- sh -c "'$bin' route -q fixtures/net-detour.geojson --network '$tmp/ann17.geojson' --from 0,0 --to 200,0 --dark-weight $w --geojson '$tmp/r17-ann.json' | cmp - '$tmp/r17-plain.txt' && cmp '$tmp/r17-ann.json' '$tmp/r17-plain.json' && grep -q '$x' '$tmp/ann17.geojson'"
done
sed 's/"intensity": 1000/"intensity": 1001/' fixtures/net-detour.geojson >"$tmp/net-detour-brighter.geojson"
expect net-annotated-other-light 1 "annotate's scores: its edges were scored on another scene \(the same counts, but the buildings' or lamps' positions, heights, intensities, colours or photometry differ: scene_hash [0-9a-f]{16} there, [0-9a-f]{16} here\)" -- "$bin" route -q "$tmp/net-detour-brighter.geojson" --network "$tmp/ann.geojson" --from 0,0 --to 200,0
# luminaires turned: the same positions, intensities and reach, another light (helper-57's pass: version 1's
# scene_hash left photometry out, and the route read the old scores with no word)
sed "s|\"intensity\": 1000,|\"photometry\": \"$PWD/fixtures/photometry/street-type2.ies\",|" fixtures/net-detour.geojson >"$tmp/net-detour-ies.geojson"
sed "s|\"intensity\": 1000,|\"photometry\": \"$PWD/fixtures/photometry/street-type2.ies\", \"azimuth\": 180,|" fixtures/net-detour.geojson >"$tmp/net-detour-ies-turned.geojson"
"$bin" annotate -q "$tmp/net-detour-ies.geojson" --network fixtures/net-detour-streets.geojson -o "$tmp/ann-ies.geojson" >/dev/null 2>&1
expect net-annotated-ies-same 0 "^best-lit" -- "$bin" route -q "$tmp/net-detour-ies.geojson" --network "$tmp/ann-ies.geojson" --from 0,0 --to 200,0
expect net-annotated-ies-turned 1 "its edges were scored on another scene \\(the same counts, but .* photometry differ: scene_hash" -- "$bin" route -q "$tmp/net-detour-ies-turned.geojson" --network "$tmp/ann-ies.geojson" --from 0,0 --to 200,0
sed 's/"version":3,/"version":2,/' "$tmp/ann-ies.geojson" >"$tmp/ann-v1.geojson"
expect net-annotated-version-2 1 "polarlux_scores member is not version 3" -- "$bin" route -q "$tmp/net-detour-ies.geojson" --network "$tmp/ann-v1.geojson" --from 0,0 --to 200,0
sed 's/"mean_lux":/"mean_luxx":/' "$tmp/ann.geojson" >"$tmp/ann-edited.geojson"
# two bakes of one scene differing only in --photons: the same counts and scene_hash, other indirect light
"$bin" bake -q fixtures/net-detour.geojson --frames 2 --photons 3000 --max-size 64x48 -o "$tmp/nd-a.plxb" >/dev/null 2>&1
"$bin" bake -q fixtures/net-detour.geojson --frames 2 --photons 5000 --max-size 64x48 -o "$tmp/nd-b.plxb" >/dev/null 2>&1
"$bin" annotate -q "$tmp/nd-a.plxb" --network fixtures/net-detour-streets.geojson -o "$tmp/ann-nd-a.geojson" >/dev/null 2>&1
expect net-annotated-bake-same 0 "^best-lit" -- "$bin" route -q "$tmp/nd-a.plxb" --network "$tmp/ann-nd-a.geojson" --from 0,0 --to 200,0
expect net-annotated-bake-other-photons 1 "its edges were scored with other indirect light \(the same scene and photon frames, but other photons a frame: light_hash [0-9a-f]{16} there, [0-9a-f]{16} here\)" -- "$bin" route -q "$tmp/nd-b.plxb" --network "$tmp/ann-nd-a.geojson" --from 0,0 --to 200,0
# the same with a far building stretching the scene's box: its 4 x 4 grid meets no light; the edges' points do
# (helper-61's review: one light_hash for both)
sed 's/^ \]$/ ,{"type":"Feature","properties":{"height":10},"geometry":{"type":"Polygon","coordinates":[[[3000,3000],[3010,3000],[3010,3010],[3000,3010],[3000,3000]]]}}]/' fixtures/net-detour.geojson >"$tmp/nd-far.geojson"
"$bin" bake -q "$tmp/nd-far.geojson" --frames 2 --photons 3000 --max-size 64x48 -o "$tmp/nd-far-a.plxb" >/dev/null 2>&1
"$bin" bake -q "$tmp/nd-far.geojson" --frames 2 --photons 5000 --max-size 64x48 -o "$tmp/nd-far-b.plxb" >/dev/null 2>&1
"$bin" annotate -q "$tmp/nd-far-a.plxb" --network fixtures/net-detour-streets.geojson -o "$tmp/ann-nd-far-a.geojson" >/dev/null 2>&1
expect net-annotated-far-bake-same 0 "^best-lit" -- "$bin" route -q "$tmp/nd-far-a.plxb" --network "$tmp/ann-nd-far-a.geojson" --from 0,0 --to 200,0
expect net-annotated-far-bake-other-photons 1 "its edges were scored with other indirect light" -- "$bin" route -q "$tmp/nd-far-b.plxb" --network "$tmp/ann-nd-far-a.geojson" --from 0,0 --to 200,0
expect net-annotated-light-hash-plain 0 '"light_hash":"0"' -- cat "$tmp/ann-ies.geojson"
expect net-annotated-edited 1 "annotate's scores: feature 0: no number 'mean_lux' \(not as annotate wrote it\)" -- "$bin" route -q fixtures/net-detour.geojson --network "$tmp/ann-edited.geojson" --from 0,0 --to 200,0
expect annotate-missing-o 2 "missing -o OUT.geojson" -- "$bin" annotate -q $net
expect tiles-metres 1 "the scene is in local metres, with no lon/lat" -- "$bin" tiles -q fixtures/tiny.geojson --zoom 15 -o "$tmp/t"
sed 's/"units": *"m"/"units": "m", "crs": "EPSG:3067"/' fixtures/tiny.geojson >"$tmp/tiny-3067.geojson"
expect tiles-projected 1 "the scene is in EPSG:3067 metres, which polarlux does not turn into lon/lat" -- "$bin" tiles -q "$tmp/tiny-3067.geojson" --zoom 15 -o "$tmp/t"
expect tiles-quantity 2 "--quantity 'v' is not h \(ground E_h\) or sc \(E_sc\)" -- "$bin" tiles -q fixtures/helsinki-centre.geojson --zoom 15 --quantity v -o "$tmp/t"
expect tiles-facing 2 "--facing 'west' is not a number of degrees or min" -- "$bin" tiles -q fixtures/helsinki-centre.geojson --zoom 15 --quantity sc --facing west -o "$tmp/t"
expect tiles-sc 0 "^tiles: [0-9]+ tiles at zoom 12-12 \([0-9]+ with light\) of direct semi-cylindrical illuminance E_sc at 1\.5 m, the least over every facing direction, scale 0\.1\.\.100 lx" -- "$bin" tiles -q fixtures/helsinki-centre.geojson --zoom 12 --quantity sc --max 100 -o "$tmp/sc.mbtiles"
expect tiles-facing-h 2 "--height and --facing need --quantity sc" -- "$bin" tiles -q fixtures/helsinki-centre.geojson --zoom 15 --facing 90 -o "$tmp/t"
expect heatmap-facing-min 2 "--facing min needs --quantity sc" -- "$bin" heatmap -q fixtures/helsinki-centre.geojson --quantity v --facing min -o "$tmp/v.png"

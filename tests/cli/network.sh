# Command-line tests of route --network, annotate and tiles (issue 15);
# sourced by tests/cli/run.sh (uses its expect, $bin, $tmp).
net="fixtures/net-detour.geojson --network fixtures/net-detour-streets.geojson"
expect net-best-lit 0 "^best-lit +300\.0 +69\.0 .*\+50\.0%$" -- "$bin" route -q $net --from 0,0 --to 200,0 --geojson "$tmp/net.geojson"
expect net-shortest 0 "^shortest +200\.0 +200\.0 +0\.000 +0\.000  - +\+0\.0%$" -- "$bin" route -q $net --from 0,0 --to 200,0
expect net-geojson 0 "" -- sh -c "grep -q '\"route\":\"best-lit\"' '$tmp/net.geojson' && grep -q '\"route\":\"shortest\"' '$tmp/net.geojson' && grep -q '\"mean_lux\"' '$tmp/net.geojson'"
expect net-light-weight 0 "^best-lit +200\.0 +200\.0 " -- "$bin" route -q $net --from 0,0 --to 200,0 --dark-weight 0.5
expect net-max-detour 0 "^best-lit +200\.0 " -- "$bin" route -q $net --from 0,0 --to 200,0 --max-detour 0.2
expect net-max-detour-says 0 "weight lowered from 3 by --max-detour 0\.2" -- "$bin" route -q $net --from 0,0 --to 200,0 --max-detour 0.2
expect net-max-detour-loose 0 "^best-lit +300\.0 " -- "$bin" route -q $net --from 0,0 --to 200,0 --max-detour 0.6
expect net-far-start 1 "route: --from 0,-80 is 80\.0 m from the nearest street of fixtures/net-detour-streets\.geojson \(more than --snap 50 m\)" -- "$bin" route -q $net --from 0,-80 --to 200,0
expect net-unreachable 1 "no path from --from 0,0 to --to 410,400: they lie on unconnected parts of the network \(it has 2 parts\)" -- "$bin" route -q $net --from 0,0 --to 410,400
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[]}' >"$tmp/empty-net.json"
expect net-empty 1 "route: $tmp/empty-net\.json: no LineString features" -- "$bin" route -q fixtures/net-detour.geojson --network "$tmp/empty-net.json" --from 0,0 --to 1,1
expect net-missing-to 2 "--network needs --from X,Y and --to X,Y" -- "$bin" route -q $net --from 0,0
expect net-help 0 "cost = length \+ W x dark metres" -- "$bin" route --network x --help
expect net-helsinki 0 "^cost = length .*network [0-9]+ nodes, [0-9]+ edges" -- "$bin" route -q fixtures/helsinki-centre.geojson --network fixtures/helsinki-streets.geojson --from 24.9400,60.1660 --to 24.9480,60.1770
expect annotate 0 "^annotate: 6 edges, 6 nodes, 570 m of street" -- "$bin" annotate -q $net -o "$tmp/ann.geojson" --csv "$tmp/ann.csv"
expect annotate-csv 0 "^way/2,300\.000,69\.000,0\.000,0\.2300,9\.4414,0\.0000,-,1\.6900$" -- cat "$tmp/ann.csv"
expect annotate-csv-head 0 "^osm_id,length_m,dark_m,blocked_m,dark_share,mean_lux,min_lux,class,factor$" -- cat "$tmp/ann.csv"
expect annotate-missing-o 2 "missing -o OUT.geojson" -- "$bin" annotate -q $net
expect tiles-metres 1 "the scene is in local metres, with no lon/lat" -- "$bin" tiles -q fixtures/tiny.geojson --zoom 15 -o "$tmp/t"
expect tiles-quantity 2 "--quantity 'sc' is not available" -- "$bin" tiles -q fixtures/helsinki-centre.geojson --zoom 15 --quantity sc -o "$tmp/t"

#!/bin/sh
# make check-web: serves WEB_DIR on 127.0.0.1, opens index.html in Debian's
# headless Chromium, saves a screenshot to OUT_DIR/web-demo.png and checks
# from its pixels that the light tiles and both routes are drawn.
# usage: tests/web/check_web.sh WEB_DIR OUT_DIR
web=$1; out=$2
mkdir -p "$out"
for b in chromium chromium-browser; do command -v $b >/dev/null && browser=$b && break; done
[ -n "$browser" ] || { echo "check-web: chromium not found (apt-get install chromium)"; exit 1; }
port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
python3 -m http.server "$port" --bind 127.0.0.1 --directory "$web" >"$out/http.log" 2>&1 &
server=$!
trap 'kill $server 2>/dev/null' EXIT
i=0
until python3 -c "import urllib.request; urllib.request.urlopen('http://127.0.0.1:$port/index.html', timeout=1)" 2>/dev/null; do
    i=$((i + 1)); [ $i -gt 50 ] && { echo "check-web: the server did not start"; exit 1; }; sleep 0.1
done
rm -f "$out/web-demo.png"
timeout 120 "$browser" --headless --no-sandbox --disable-gpu --hide-scrollbars --window-size=1100,900 \
    --virtual-time-budget=15000 --screenshot="$out/web-demo.png" "http://127.0.0.1:$port/index.html" \
    >"$out/chromium.log" 2>&1
[ -s "$out/web-demo.png" ] || { echo "check-web: no screenshot"; cat "$out/chromium.log"; exit 1; }
echo "check-web: screenshot $out/web-demo.png"
pass=0; fail=0
if python3 tests/web/png_pixels.py "$out/web-demo.png"; then pass=$((pass + 1)); else fail=$((fail + 1)); fi
# the legend labels the scale with the lux of the tiles' metadata.json (it said "top of scale")
timeout 120 "$browser" --headless --no-sandbox --disable-gpu --virtual-time-budget=15000 --dump-dom \
    "http://127.0.0.1:$port/index.html" >"$out/web-demo.html" 2>>"$out/chromium.log"
top=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['polarlux_scale']['max_lux'])" "$web/data/tiles/metadata.json")
shown=$(sed -n 's/.*<span id="scale-hi">\([^<]*\)<\/span> lx.*/\1/p' "$out/web-demo.html")
# compared as numbers: JavaScript writes 1000000 where Python writes 1e+06
if [ -n "$top" ] && [ -n "$shown" ] && python3 -c "import sys; sys.exit(float(sys.argv[1]) != float(sys.argv[2]))" "$top" "$shown"; then
    echo "ok   web-legend-lux ($top lx)"; pass=$((pass + 1))
else
    echo "FAIL web-legend-lux: the page's legend lacks the tiles' top of scale '$top' lx"; fail=$((fail + 1))
fi
echo "web: $pass passed, $fail failed"
[ $fail -eq 0 ]

#!/bin/sh
# The hostile corpus: absurd and non-finite option values, special files as
# inputs and outputs (devices, FIFOs, directories, symlinks, "-"), a full
# disk, for every command; each case with its exact exit code and message.
# Every failure must say why on stderr (never only on stdout) and no case may
# wait forever (each runs under timeout). PLX_HOSTILE_WRAP prefixes every
# run of the command (make check-hostile-valgrind sets it to valgrind).
# usage: tests/cli/hostile.sh path/to/polarlux ; prints "hostile: N passed, N failed".
bin=$1
build=$(dirname "$bin")
shim="$build/tests/failwrite.so"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
pass=0; fail=0
pre=            # environment for the next runs (the failing-disk shim)
T=fixtures/tiny.geojson
ok() { echo "ok   $1"; pass=$((pass + 1)); }
bad() { echo "FAIL $1"; fail=$((fail + 1)); }

# expect NAME CODE PATTERN -- polarlux-args...: exit code CODE; on failure
# PATTERN (grep -E) must be on stderr, on success in stdout+stderr.
expect() {
    name=$1; code=$2; pattern=$3; shift 4
    timeout ${PLX_HOSTILE_TIMEOUT:-60} env $pre $PLX_HOSTILE_WRAP "$bin" "$@" >"$tmp/out" 2>"$tmp/err" </dev/null; rc=$?
    if [ "$rc" -ne "$code" ]; then
        bad "$name: exit $rc, want $code"; cat "$tmp/out" "$tmp/err" | sed 's/^/    /' | head -20; return
    fi
    where="$tmp/err"
    [ "$code" -eq 0 ] && { cat "$tmp/out" "$tmp/err" >"$tmp/both"; where="$tmp/both"; }
    if [ -n "$pattern" ] && ! grep -Eq -- "$pattern" "$where"; then
        bad "$name: $( [ "$code" -eq 0 ] && echo output || echo stderr ) lacks /$pattern/"
        cat "$tmp/out" "$tmp/err" | sed 's/^/    /' | head -20; return
    fi
    ok "$name"
}
is_png() { [ "$(head -c 4 "$1" | od -An -c | tr -d ' ')" = "211PNG" ]; }

# ---- safe outputs ---------------------------------------------------------
for dev in /dev/full /dev/null; do
    [ -c $dev ] || continue
    want=0; msg=""
    [ $dev = /dev/full ] && { want=1; msg="cannot write '/dev/full': No space left on device"; }
    expect "gen-o-$dev" $want "$msg" -- gen grid 3 3 -o $dev
    expect "heatmap-o-$dev" $want "$msg" -- heatmap -q $T --res 2 -o $dev
    expect "draw-o-$dev" $want "$msg" -- draw -q $T --polar 0 --size 50 -o $dev
    expect "render-o-$dev" $want "$msg" -- render -q --no-indirect $T --size 16x12 -o $dev
    expect "render-pfm-$dev" $want "$msg" -- render -q --no-indirect $T --size 16x12 -o "$tmp/r.png" --pfm $dev
    expect "lit-o-$dev" $want "$msg" -- lit -q $T --lamp L1 -o $dev
    expect "vis-geojson-$dev" $want "$msg" -- vis -q $T --at 30,30 --geojson $dev
    if [ -c $dev ]; then ok "$dev-still-a-device"; else bad "$dev replaced"; fi
done
# a symlink is written through: the link stays, its target gets the PNG
echo old >"$tmp/real.png"; ln -s real.png "$tmp/link.png"
expect symlink-write 0 "" -- heatmap -q $T --res 2 -o "$tmp/link.png"
if [ -L "$tmp/link.png" ] && is_png "$tmp/real.png"; then ok symlink-kept; else bad "symlink-kept"; fi
ln -s nowhere/x.png "$tmp/dangling.png"
expect symlink-dangling 1 "dangling.png' is a symbolic link to nowhere" -- heatmap -q $T --res 2 -o "$tmp/dangling.png"
# a FIFO is written directly, never renamed over
mkfifo "$tmp/fifo"
cat "$tmp/fifo" >"$tmp/fifo.out" &
expect fifo-write 0 "" -- gen grid 2 2 -o "$tmp/fifo"
wait
"$bin" gen grid 2 2 >"$tmp/gen.out"
if [ -p "$tmp/fifo" ] && cmp -s "$tmp/fifo.out" "$tmp/gen.out"; then ok fifo-kept; else bad fifo-kept; fi
# "-": the data on stdout, the report line on stderr
# (and no world file "-.pgw" in the working folder: the map has no folder)
mkdir "$tmp/cwd"
binabs=$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")
(cd "$tmp/cwd" && timeout 60 "$binabs" heatmap -q "$OLDPWD/$T" --res 2 -o - >"$tmp/stdout.png" 2>"$tmp/err"); rc=$?
if [ $rc -eq 0 ] && is_png "$tmp/stdout.png" && grep -q "^heatmap: .* written to -$" "$tmp/err" &&
   grep -q "no world file (.pgw) for '-'" "$tmp/err" && [ -z "$(ls -A "$tmp/cwd")" ]; then ok stdout-png
else bad "stdout-png: exit $rc"; fi
# a FIFO map gets no world file "fifo.pgw" beside it either
cat "$tmp/fifo" >/dev/null &
expect heatmap-fifo-no-world 0 "no world file \\(\\.pgw\\) for '$tmp/fifo'" -- heatmap -q $T --res 2 -o "$tmp/fifo"
wait
if [ ! -e "$tmp/fifo.pgw" ]; then ok heatmap-fifo-no-pgw; else bad heatmap-fifo-no-pgw; fi
timeout 60 "$bin" render -q --no-indirect $T --size 16x12 -o "$tmp/r.png" --pfm - >"$tmp/stdout.pfm" 2>/dev/null; rc=$?
if [ $rc -eq 0 ] && [ "$(head -c 2 "$tmp/stdout.pfm")" = "PF" ]; then ok stdout-pfm; else bad "stdout-pfm: exit $rc"; fi
expect output-directory 1 "'$tmp' is a directory" -- gen grid 2 2 -o "$tmp"
# a failing disk (LD_PRELOAD stand-in): exit 1, old targets untouched, no temporary file left
if [ -f "$shim" ]; then
    "$bin" gen grid 2 2 -o "$tmp/old.geojson"; cp "$tmp/old.geojson" "$tmp/old.copy"
    for mode in ENOSPC EIO EFBIG SHORT; do
        case $mode in ENOSPC|SHORT) why="No space left on device";; EIO) why="Input/output error";; EFBIG) why="File too large";; esac
        pre="LD_PRELOAD=$shim ASAN_OPTIONS=verify_asan_link_order=0 PLX_FAILWRITE_MATCH=old.geojson.tmp
             PLX_FAILWRITE_AFTER=5000 PLX_FAILWRITE_ERRNO=$mode"
        expect "gen-disk-$mode" 1 "^polarlux gen: cannot write '$tmp/old.geojson': $why$" -- gen eixample 3 3 -o "$tmp/old.geojson"
    done
    pre="LD_PRELOAD=$shim ASAN_OPTIONS=verify_asan_link_order=0 PLX_FAILWRITE_MATCH=old.geojson.tmp PLX_FAILWRITE_AFTER=100000000 PLX_FAILWRITE_FSYNC=1"
    expect gen-disk-fsync 1 "^polarlux gen: cannot write '$tmp/old.geojson': Input/output error$" -- gen eixample 3 3 -o "$tmp/old.geojson"
    if cmp -s "$tmp/old.geojson" "$tmp/old.copy"; then ok gen-disk-old-kept; else bad gen-disk-old-kept; fi
    # PNG + PFM belong together: the PFM fails, so neither is replaced
    pre=
    "$bin" render -q --no-indirect $T --size 16x12 -o "$tmp/pair.png" --pfm "$tmp/pair.pfm" >/dev/null
    cp "$tmp/pair.png" "$tmp/pair.png.copy"; cp "$tmp/pair.pfm" "$tmp/pair.pfm.copy"
    pre="LD_PRELOAD=$shim ASAN_OPTIONS=verify_asan_link_order=0 PLX_FAILWRITE_MATCH=pair.pfm.tmp"
    expect render-pfm-fails 1 "^polarlux render: cannot write '$tmp/pair.pfm': No space left on device$" -- \
        render -q --no-indirect $T --size 24x16 -o "$tmp/pair.png" --pfm "$tmp/pair.pfm"
    pre=
    if cmp -s "$tmp/pair.png" "$tmp/pair.png.copy" && cmp -s "$tmp/pair.pfm" "$tmp/pair.pfm.copy"; then
        ok render-pair-kept; else bad render-pair-kept; fi
    # the map and its world file belong together too: the .pgw fails, neither is replaced
    "$bin" heatmap -q $T --res 2 -o "$tmp/map.png" >/dev/null 2>&1
    cp "$tmp/map.png" "$tmp/map.png.copy"; cp "$tmp/map.pgw" "$tmp/map.pgw.copy"
    pre="LD_PRELOAD=$shim ASAN_OPTIONS=verify_asan_link_order=0 PLX_FAILWRITE_MATCH=map.pgw.tmp"
    expect heatmap-pgw-fails 1 "^polarlux heatmap: cannot write '$tmp/map.pgw': No space left on device$" -- \
        heatmap -q $T --res 3 -o "$tmp/map.png"
    pre=
    if cmp -s "$tmp/map.png" "$tmp/map.png.copy" && cmp -s "$tmp/map.pgw" "$tmp/map.pgw.copy" &&
       [ -z "$(ls "$tmp" | grep '\.tmp\.')" ]; then ok heatmap-pair-kept; else bad heatmap-pair-kept; fi
    # walk writes its frames on a thread of their own: a failed frame still stops it with exit 1
    printf '{"type":"LineString","coordinates":[[0,0,1.7],[10,0,1.7]]}' >"$tmp/walk.geojson"
    pre="LD_PRELOAD=$shim ASAN_OPTIONS=verify_asan_link_order=0 PLX_FAILWRITE_MATCH=frame-0003.png.tmp"
    expect walk-frame-fails 1 "^polarlux walk: PNG: cannot write '$tmp/w/frame-0003.png': No space left on device$" -- \
        walk -q $T --path "$tmp/walk.geojson" --size 32x24 --fps 1 --no-indirect -o "$tmp/w"
    pre=
    if [ -s "$tmp/w/frame-0002.png" ] && [ ! -e "$tmp/w/frame-0003.png" ] && [ ! -e "$tmp/w/walk.png" ] &&
       [ -z "$(ls "$tmp/w" | grep '\.tmp')" ]; then ok walk-frame-fails-clean; else bad walk-frame-fails-clean; fi
    # cameras.txt lists the frames on disk: each line is written once its frame is (it listed
    # frame 3, which a full disk stopped)
    if [ "$(grep -vc '^#' "$tmp/w/cameras.txt")" = 2 ] && [ "$(awk '!/^#/ { n = $1 } END { print n }' "$tmp/w/cameras.txt")" = 2 ]; then
        ok walk-frame-fails-cameras; else bad "walk-frame-fails-cameras: $(grep -vc '^#' "$tmp/w/cameras.txt") lines"; fi
    # the animated PNG on a full disk says why, as every output does
    pre="LD_PRELOAD=$shim ASAN_OPTIONS=verify_asan_link_order=0 PLX_FAILWRITE_MATCH=walk.png.tmp"
    expect walk-apng-fails 1 "^polarlux walk: animated PNG: cannot write '$tmp/wapng/walk.png': No space left on device$" -- \
        walk -q $T --path "$tmp/walk.geojson" --size 32x24 --fps 1 --no-indirect -o "$tmp/wapng"
    pre=
    # walk's outputs are synced together at its end (one syncfs of the folder's file system), not
    # one by one: a failing fsync of the frames is never met; a failing sync of the folder is
    pre="LD_PRELOAD=$shim ASAN_OPTIONS=verify_asan_link_order=0 PLX_FAILWRITE_MATCH=wsync/ PLX_FAILWRITE_AFTER=100000000 PLX_FAILWRITE_FSYNC=1"
    expect walk-frames-unsynced 0 "^walk: 9 frames" -- \
        walk -q $T --path "$tmp/walk.geojson" --size 32x24 --fps 1 --no-indirect -o "$tmp/wsync"
    pre="LD_PRELOAD=$shim ASAN_OPTIONS=verify_asan_link_order=0 PLX_FAILWRITE_MATCH=wsync2 PLX_FAILWRITE_AFTER=100000000 PLX_FAILWRITE_FSYNC=1"
    expect walk-sync-fails 1 "^polarlux walk: cannot write the files in '$tmp/wsync2' to disk: Input/output error$" -- \
        walk -q $T --path "$tmp/walk.geojson" --size 32x24 --fps 1 --no-indirect -o "$tmp/wsync2"
    pre=
    if [ -s "$tmp/wsync2/frame-0009.png" ] && [ -s "$tmp/wsync2/walk.png" ] && [ -s "$tmp/wsync2/cameras.txt" ] &&
       [ -z "$(ls "$tmp/wsync2" | grep '\.tmp')" ]; then ok walk-sync-fails-files; else bad walk-sync-fails-files; fi
elif [ -n "${PLX_NO_SHIM:-}" ]; then
    # a cross build run under qemu-user: a host LD_PRELOAD shim cannot reach
    # the emulated program's writes (check-arm64 sets PLX_NO_SHIM)
    echo "skip failing-disk shim cases: $PLX_NO_SHIM"
else
    bad "no $shim (make check builds it)"
fi
# a folder one may write but not read (mode 0300): the walk's sync goes through a file of its own there
if [ "$(id -u)" = 0 ] && command -v setpriv >/dev/null 2>&1; then
    printf '{"type":"LineString","coordinates":[[0,0,1.7],[10,0,1.7]]}' >"$tmp/walkw.geojson"
    mkdir "$tmp/wonly"; chown 65534:65534 "$tmp/wonly"; chmod 0300 "$tmp/wonly"; chmod 0755 "$tmp"
    chmod 0644 "$tmp/walkw.geojson"
    pre="setpriv --reuid=65534 --regid=65534 --clear-groups"
    timeout ${PLX_HOSTILE_TIMEOUT:-60} $pre $PLX_HOSTILE_WRAP "$bin" walk -q $T --path "$tmp/walkw.geojson" --size 32x24 --fps 1 --no-indirect \
        -o "$tmp/wonly" >"$tmp/out" 2>"$tmp/err" </dev/null; rc=$?
    pre=
    chmod 0700 "$tmp/wonly"
    if [ "$rc" -eq 0 ] && [ -s "$tmp/wonly/frame-0009.png" ] && [ -z "$(ls -A "$tmp/wonly" | grep '^\.sync')" ]; then
        ok walk-write-only-folder
    else
        bad "walk-write-only-folder: exit $rc"; sed 's/^/    /' "$tmp/err" | head -5
    fi
fi
# cameras.txt's writes are checked: a full disk is told, not a short file left
if [ -c /dev/full ]; then
    printf '{"type":"LineString","coordinates":[[0,0,1.7],[10,0,1.7]]}' >"$tmp/walkc.geojson"
    mkdir "$tmp/wcam"; ln -s /dev/full "$tmp/wcam/cameras.txt"
    expect walk-cameras-full 1 "^polarlux walk: $tmp/wcam/cameras.txt: cannot write: No space left on device$" -- \
        walk -q $T --path "$tmp/walkc.geojson" --size 32x24 --fps 1 --no-indirect -o "$tmp/wcam"
fi
# a walk killed half way: cameras.txt lists frames 1 .. n, each on disk, and at most the one
# after them is on disk beside (a killed walk left it shorter than the frames: its lines were
# buffered; they are flushed as each frame is written)
printf '{"type":"LineString","coordinates":[[0,0,1.7],[4000,0,1.7]]}' >"$tmp/walkk.geojson"
$PLX_HOSTILE_WRAP "$bin" walk -q $T --path "$tmp/walkk.geojson" --size 64x48 --speed 1 --fps 1 --no-indirect \
    -o "$tmp/wkill" >/dev/null 2>&1 &
kpid=$!
k=0
while [ $k -lt 600 ] && [ ! -e "$tmp/wkill/frame-0005.png" ]; do sleep 0.1; k=$((k + 1)); done
kill -9 $kpid 2>/dev/null; wait $kpid 2>/dev/null
lines=$(grep -vc '^#' "$tmp/wkill/cameras.txt" 2>/dev/null || echo 0)
frames=$(ls "$tmp/wkill" | grep -c '^frame-[0-9]*\.png$')
listed=1
for n in $(awk '!/^#/ { print $1 }' "$tmp/wkill/cameras.txt" 2>/dev/null); do
    [ -s "$tmp/wkill/$(printf 'frame-%04d.png' "$n")" ] || listed=0
done
if [ "$lines" -ge 1 ] && [ "$listed" = 1 ] && [ "$frames" -ge "$lines" ] && [ "$frames" -le $((lines + 1)) ] &&
   [ "$(awk '!/^#/ { if ($1 != NR - 1) bad = 1 } END { print bad + 0 }' "$tmp/wkill/cameras.txt")" = 0 ]; then
    ok "walk-killed-cameras ($lines lines, $frames frames)"
else
    bad "walk-killed-cameras: $lines lines, $frames frames, every listed one on disk: $listed"
fi
# a full small filesystem: a 64 KiB tmpfs in a mount namespace of its own, where permitted
if [ "$(id -u)" = 0 ] && unshare -m true 2>/dev/null; then
    mkdir -p "$tmp/mnt"
    unshare -m sh -c "mount -t tmpfs -o size=64k tmpfs '$tmp/mnt' &&
        '$bin' gen grid 2 2 -o '$tmp/mnt/c.geojson' && cp '$tmp/mnt/c.geojson' '$tmp/c.copy' &&
        { '$bin' gen eixample 4 4 -o '$tmp/mnt/c.geojson' 2>'$tmp/mnt.err'; echo \$? >'$tmp/mnt.rc'; } ;
        cmp -s '$tmp/mnt/c.geojson' '$tmp/c.copy' && echo same >'$tmp/mnt.same';
        ls '$tmp/mnt' >'$tmp/mnt.ls'"
    if [ "$(cat "$tmp/mnt.rc" 2>/dev/null)" = 1 ] && [ -f "$tmp/mnt.same" ] && [ "$(cat "$tmp/mnt.ls")" = c.geojson ] &&
        grep -q "cannot write '$tmp/mnt/c.geojson': No space left on device" "$tmp/mnt.err"; then
        ok tmpfs-full
    else
        bad "tmpfs-full: exit $(cat "$tmp/mnt.rc" 2>/dev/null), $(cat "$tmp/mnt.err" 2>/dev/null), files: $(cat "$tmp/mnt.ls" 2>/dev/null)"
    fi
else
    echo "skip tmpfs-full (needs root and unshare -m; the LD_PRELOAD stand-in above covers it)"
fi
# ---- hostile option values: exit 2 before any work, naming the option -------
U="is not"   # every refusal says what is wrong with the value
values="inf -inf nan 1e400 0x1p2000"
[ -n "$PLX_TEST_QUICK" ] && values="inf nan"   # make check: two of them
for v in $values; do
    expect "heatmap-max-$v" 2 "^polarlux heatmap: --max '$v' $U a number of lux above 0.1 \(at most 1e9\)" -- heatmap $T --max $v -o "$tmp/h.png"
    expect "heatmap-res-$v" 2 "^polarlux heatmap: --res '$v' $U a positive number of metres" -- heatmap $T --res $v -o "$tmp/h.png"
    expect "route-step-$v" 2 "^polarlux route: --step '$v' $U a number of metres from 0.01 to 1e7" -- route $T --path fixtures/helsinki-route.geojson --step $v
    expect "route-dark-$v" 2 "^polarlux route: --dark-lux '$v' $U a number of lux" -- route $T --path fixtures/helsinki-route.geojson --dark-lux $v
    expect "render-fov-$v" 2 "^polarlux render: --fov '$v' $U between 0 and 180" -- render $T --fov $v -o "$tmp/r.png"
    expect "render-exposure-$v" 2 "^polarlux render: --exposure '$v' $U a number above 0, up to 1e9" -- render $T --exposure $v -o "$tmp/r.png"
    expect "render-texel-$v" 2 "^polarlux render: --texel '$v' $U a number of metres from 0.01 to 1e4" -- render $T --texel $v -o "$tmp/r.png"
    expect "vis-dir-$v" 2 "^polarlux vis: --dir '$v' $U a number of degrees" -- vis $T --at 30,30 --dir $v
    expect "vis-fov-$v" 2 "^polarlux vis: --fov '$v' $U a positive number of degrees" -- vis $T --at 30,30 --fov $v
    expect "dark-spots-res-$v" 2 "^polarlux dark-spots: --res '$v' $U a positive number of metres" -- dark-spots $T --res $v
    expect "dark-spots-spacing-$v" 2 "^polarlux dark-spots: --spacing '$v' $U a number of metres" -- dark-spots $T --spacing $v
    expect "nightify-threshold-$v" 2 "^polarlux nightify: --dark-threshold '$v' $U 0..255" -- nightify a.png b.png -o "$tmp/n.png" --dark-threshold $v
    expect "info-mem-$v" 2 "^polarlux info: --mem '$v' $U a size" -- info --mem $v $T
done
for box in 0,0,inf,10 0,0,10,nan -inf,0,10,10 0,0,4294967296,4294967296 0,0,6442450944,8589934592 0,0,1e308,1e308 1,2,3 0,0,10,10,10 10,0,0,10; do
    expect "heatmap-box-$box" 2 "^polarlux heatmap: --box '$box' $U X0,Y0,X1,Y1 with X1 > X0 and Y1 > Y0 \(finite, within 1e7 m\)" -- heatmap $T --res 1 --box $box -o "$tmp/h.png"
done
printf '50 10\n' >"$tmp/p.txt"
expect heatmap-pixels 2 "^polarlux heatmap: --res 0.001 over a box of 10000000 x 10000000 m gives 10000000000x10000000000 pixels \(at most 5e7, 1e6 a side\)" -- heatmap -q $T --res 0.001 --box 0,0,1e7,1e7 -o "$tmp/h.png"
expect heatmap-res-tiny 2 "^polarlux heatmap: --res 1e-300 over a box of " -- heatmap -q $T --res 1e-300 -o "$tmp/h.png"
expect heatmap-max-huge 2 "^polarlux heatmap: --max '1e300'" -- heatmap $T --max 1e300 -o "$tmp/h.png"
expect heatmap-max-ok 0 "scale 0.1..1e\+09 lx" -- heatmap -q $T --res 4 --max 1e9 -o "$tmp/h.png"
expect dark-spots-res-tiny 2 "^polarlux dark-spots: --res 1e-300 gives inf grid points \(1 to 2e9\)$" -- dark-spots -q $T --res 1e-300
expect dark-spots-count 2 "^polarlux dark-spots: --count '99999999999999999999' $U 1..1000000" -- dark-spots $T --count 99999999999999999999
for eye in 1e9,0,2 0,-1e308,2 inf,0,2 0,0,1e6 0,0 0,0,2,2 ,, 1e7,0,2x; do
    expect "render-eye-$eye" 2 "^polarlux render: --eye '$eye' $U X,Y,Z \(finite, x and y within 1e7 m, z within 1e5 m\)" -- render $T --eye $eye --target 50,10,2 -o "$tmp/r.png"
done
expect render-target-huge 2 "^polarlux render: --target '1e308,0,0' $U X,Y,Z" -- render $T --eye 30,30,2 --target 1e308,0,0 -o "$tmp/r.png"
expect render-size-huge 2 "^polarlux render: --size '100000x100000' $U WxH \(1..8192 each\)" -- render $T --size 100000x100000 -o "$tmp/r.png"
expect render-size-overflow 2 "^polarlux render: --size '99999999999999999999x2' $U WxH" -- render $T --size 99999999999999999999x2 -o "$tmp/r.png"
expect render-photons-frames 2 "^polarlux render: --photons 100000000 x --frames 100000 is more than 4294967296 photons" -- render -q $T --photons 100000000 --frames 100000 -o "$tmp/r.png"
expect illum-photons-frames 2 "^polarlux illum: --photons 70000 x --frames 100000 is more than 4294967296 photons" -- illum -q $T --points "$tmp/p.txt" --photons 70000 --frames 100000
expect illum-photons-huge 2 "^polarlux illum: --photons '1e9' $U a whole number from 1 to 100000000" -- illum $T --points - --photons 1e9
for at in 1e9,0 0,1e308 nan,0 0,inf 1,2,3 1; do
    expect "vis-at-$at" 2 "^polarlux vis: --at '$at' $U X,Y \(finite, within 1e7 m\)" -- vis $T --at $at
done
expect gen-n-huge 2 "^polarlux gen: NX and NY must be whole numbers from 1 to 1000" -- gen grid 100000 100000
expect gen-seed-bad 2 "^polarlux gen: --seed '1e9' $U a whole number" -- gen grid 2 2 --seed 1e9
expect draw-size-huge 2 "^polarlux draw: --size" -- draw $T --polar 0 --size 1000000 -o "$tmp/d.png"
expect draw-polar-huge 2 "^polarlux draw: --polar '4294967296' $U a quadrant 0..3" -- draw $T --polar 4294967296 -o "$tmp/d.png"
expect info-mem-huge 2 "^polarlux info: --mem '1e300' $U a size" -- info --mem 1e300 $T
pre=ASAN_OPTIONS=allocator_may_return_null=1   # a sanitizer build refuses the malloc itself
expect info-mem-exabyte 3 "^polarlux info: cannot create an engine of [0-9]+ bytes" -- info --mem 900000G $T
pre=
# route paths: coordinates beyond 1e7 m, and more samples than allowed at --step
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{},"geometry":{"type":"LineString","coordinates":[[-1e308,0],[1e308,0]]}}]}\n' >"$tmp/far.json"
expect route-path-1e308 1 "^polarlux route: $tmp/far.json: feature 0: position 0 \(-1e\+308, 0\) is more than 1e7 m from the origin$" -- route -q $T --path "$tmp/far.json"
expect heatmap-path-1e308 1 "^polarlux heatmap: $tmp/far.json: feature 0: position 0 \(-1e\+308, 0\) is more than 1e7 m from the origin$" -- heatmap -q $T --path "$tmp/far.json" -o "$tmp/h.png"
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{},"geometry":{"type":"LineString","coordinates":[[0,0],[1e9,0]]}}]}\n' >"$tmp/far9.json"
expect route-path-1e9 1 "position 1 \(1e\+09, 0\) is more than 1e7 m from the origin$" -- route -q $T --path "$tmp/far9.json"
printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":[{"type":"Feature","properties":{},"geometry":{"type":"LineString","coordinates":[[0,0],[9e6,0],[0,0],[9e6,0]]}}]}\n' >"$tmp/long.json"
expect route-step-samples 2 "^polarlux route: --step 0.01 gives 2700000003 samples over the path's 27000000 m \(at most 1e8, 1e7 a segment\)" -- route -q $T --path "$tmp/long.json" --step 0.01
expect route-step-segment 2 "^polarlux route: --step 0.5 gives 54000003 samples over the path's 27000000 m \(at most 1e8, 1e7 a segment\)" -- route -q $T --path "$tmp/long.json" --step 0.5

# ---- special files as inputs: refused at once, never waited on ---------------
mkfifo "$tmp/in.fifo"
for f in "$tmp/in.fifo" /dev/zero "$tmp"; do
    case $f in *fifo) kind="a FIFO";; /dev/zero) kind="a device";; *) kind="a directory";; esac
    n=$(basename "$f")
    expect "info-scene-$n" 1 "^polarlux info: $f: not a regular file \($kind\)$" -- info "$f"
    expect "vis-points-$n" 1 "^polarlux vis: $f: not a regular file \($kind\)$" -- vis -q $T --points "$f"
    expect "illum-points-$n" 1 "^polarlux illum: $f: not a regular file \($kind\)$" -- illum -q $T --points "$f"
    expect "route-path-$n" 1 "^polarlux route: $f: not a regular file \($kind\)$" -- route -q $T --path "$f"
    expect "heatmap-path-$n" 1 "^polarlux heatmap: $f: not a regular file \($kind\)$" -- heatmap -q $T --path "$f" -o "$tmp/h.png"
    expect "nightify-day-$n" 1 "^polarlux nightify: PNG: '$f' is not a regular file$" -- nightify "$f" "$f" -o "$tmp/n.png"
done
mkdir -p "$tmp/gi"; cp fixtures/ground-image.geojson "$tmp/gi/s.geojson"; mkfifo "$tmp/gi/ground-day.png"
expect ground-image-fifo 1 "^polarlux info: $tmp/gi/s.geojson: ground image 'ground-day.png': PNG: '$tmp/gi/ground-day.png' is not a regular file$" -- info "$tmp/gi/s.geojson"
# text inputs read whole or refused
printf '50 10\n50 12\0\n50 14\n' >"$tmp/nul.txt"
expect points-nul 1 "^polarlux vis: $tmp/nul.txt:2: a NUL byte at byte 11 \(not a text file\?\)$" -- vis -q $T --points "$tmp/nul.txt"
printf '50 10\n50 12' >"$tmp/trunc.txt"
expect points-truncated 1 "^polarlux vis: $tmp/trunc.txt:2: the last line does not end with a newline \(truncated file\?\)$" -- vis -q $T --points "$tmp/trunc.txt"
{ printf '50 10\n'; head -c 5000 /dev/zero | tr '\0' ' '; printf '50 12\n'; } >"$tmp/long.txt"
expect points-long-line 1 "^polarlux illum: $tmp/long.txt:2: line longer than 4096 bytes$" -- illum -q $T --points "$tmp/long.txt"
printf '50 10\0garbage' >"$tmp/nul2.txt"
timeout 60 "$bin" vis -q $T --points - <"$tmp/nul2.txt" >/dev/null 2>"$tmp/err"; rc=$?
if [ $rc -eq 1 ] && grep -q "^polarlux vis: <stdin>:1: a NUL byte at byte 5 (not a text file?)$" "$tmp/err"; then ok points-stdin-nul
else bad "points-stdin-nul: exit $rc, $(cat "$tmp/err")"; fi
# images: the decoded size counts against --mem before decoding
/usr/bin/python3 - "$tmp" <<'PY'
import struct, sys, zlib
def png(path, w, h):
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xffffffff)
    ihdr = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    open(path, "wb").write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 64)) + chunk(b"IEND", b""))
png(sys.argv[1] + "/huge.png", 1000000, 1000000)
png(sys.argv[1] + "/mid.png", 1000, 1000)
PY
expect nightify-huge-header 3 "^polarlux nightify: PNG: '$tmp/huge.png' is 1000000x1000000 pixels: decoding needs 3000000000000 bytes, more than the 1073741824 the memory budget allows; give it more with --mem$" -- nightify "$tmp/huge.png" "$tmp/huge.png" -o "$tmp/n.png"
expect nightify-mid-small-mem 3 "^polarlux nightify: PNG: '$tmp/mid.png' is 1000x1000 pixels: decoding needs 3000000 bytes, more than the 1048576 the memory budget allows" -- nightify --mem 1M "$tmp/mid.png" "$tmp/mid.png" -o "$tmp/n.png"
cp "$tmp/mid.png" "$tmp/gi/ground-day.png.new"; rm "$tmp/gi/ground-day.png"; mv "$tmp/gi/ground-day.png.new" "$tmp/gi/ground-day.png"
expect ground-image-over-mem 3 "^polarlux info: $tmp/gi/s.geojson: ground image 'ground-day.png': PNG: '$tmp/gi/ground-day.png' is 1000x1000 pixels: decoding needs 3000000 bytes, more than the 2097152 the memory budget allows; give it more with --mem$" -- info --mem 2M "$tmp/gi/s.geojson"
# the eye inside a building: a warning
expect render-eye-inside 0 "^polarlux render: warning: --eye \(5, 5, 3\) is inside building 0 \(A\) \(0 to 10 m high\): the image shows the inside of its walls$" -- render --no-indirect $T --eye 5,5,3 --target 50,10,2 --size 16x12 -o "$tmp/r.png"
# 1,000 lamps at one spot: merged into one with a warning (tests/unit/test_lampmerge.c checks the light)
{ printf '{"type":"FeatureCollection","properties":{"units":"m"},"features":['
  i=0; while [ $i -lt 999 ]; do printf '{"type":"Feature","properties":{"lamp":true,"intensity":10},"geometry":{"type":"Point","coordinates":[5,5]}},'; i=$((i + 1)); done
  printf '{"type":"Feature","properties":{"lamp":true,"intensity":10},"geometry":{"type":"Point","coordinates":[5,5]}}]}\n'; } >"$tmp/dup.geojson"
expect lamps-duplicate-warning 0 "warning: $tmp/dup.geojson: feature 0 \(line 1, column [0-9]+\): 1000 lamps at one spot \(5, 5, 6\) merged into this one: 10000 cd$" -- info "$tmp/dup.geojson"
expect lamps-duplicate-info 0 "^duplicate lamps: 999 merged into lamps at the same spot$" -- info -q "$tmp/dup.geojson"
expect lamps-duplicate-count 0 "^lamps: 1$" -- info -q "$tmp/dup.geojson"
# info --min-mem: the printed budget loads, 8 KiB less does not
n=$("$bin" info -q --min-mem $T | sed -n 's/^smallest --mem: \([0-9]*\) bytes.*/\1/p')
if [ -n "$n" ]; then
    expect min-mem-fits 0 "^buildings: 4 " -- info -q --mem "$n" $T
    expect min-mem-less 3 "out of memory" -- info -q --mem $((n - 8192)) $T
else
    bad "info --min-mem printed no budget"
fi
# exit 3 says so on stderr
expect info-nomem-stderr 3 "out of memory" -- info --mem 8K fixtures/helsinki-centre.geojson
# exit 3 on stderr from the later stages too: the default street view's search
# (polar diagrams) and the photon buffers, not exit 1 with another reason
expect render-nomem-street 3 "^polarlux render: out of memory while building the polar diagrams" -- render -q $T --size 16x12 --mem 32K -o "$tmp/r.png"
expect illum-nomem-photons 3 "^polarlux illum: out of memory while creating the photon buffers: [0-9]+ bytes at their lowest quality" -- illum -q $T --points "$tmp/p.txt" --mem 300K
expect info-photons-default 0 "^photon buffers: [0-9]+ bytes \(default quality [0-9]+, budget [0-9]+\): 0 quality steps; facade charts 256x32, .*lamp ray tables on$" -- info -q --photons fixtures/helsinki-centre.geojson
expect info-photons-reduced 0 "^photon buffers: [0-9]+ bytes \(default quality [0-9]+, budget [0-9]+\): [1-9][0-9]* quality steps; .*lamp ray tables off$" -- info -q --photons --mem 12M fixtures/helsinki-centre.geojson
expect render-photons-reduced 0 "^polarlux render: indirect light at reduced quality to fit --mem: photon buffers" -- render fixtures/helsinki-centre.geojson --size 32x24 --frames 1 --photons 1000 --mem 12M -o "$tmp/r.png"

ls "$tmp"/*.tmp* >/dev/null 2>&1 && bad "temporary files left: $(ls "$tmp"/*.tmp*)"
echo "hostile: $pass passed, $fail failed"
[ "$fail" -eq 0 ]

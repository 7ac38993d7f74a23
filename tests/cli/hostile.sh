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
    timeout 60 env $pre $PLX_HOSTILE_WRAP "$bin" "$@" >"$tmp/out" 2>"$tmp/err" </dev/null; rc=$?
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
timeout 60 "$bin" heatmap -q $T --res 2 -o - >"$tmp/stdout.png" 2>"$tmp/err"; rc=$?
if [ $rc -eq 0 ] && is_png "$tmp/stdout.png" && grep -q "^heatmap: .* written to -" "$tmp/err"; then ok stdout-png
else bad "stdout-png: exit $rc"; fi
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
else
    bad "no $shim (make check builds it)"
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
ls "$tmp"/*.tmp* >/dev/null 2>&1 && bad "temporary files left: $(ls "$tmp"/*.tmp*)"
echo "hostile: $pass passed, $fail failed"
[ "$fail" -eq 0 ]

#!/bin/sh
# The refactor check: every command's output, before and after.
#
#   sh tests/check_identical.sh [BASE]      (make check-identical BASE=rev)
#
# Builds revision BASE (default 73d3a0e, the flat layout before the move to
# src/<stage>/) in a temporary git worktree, and the current tree, then runs
# every command (info, gen, vis, draw, illum, lit, heatmap, render street /
# aerial / --pfm / --aa 2, 3 and --aa-full, route, dark-spots, nightify;
# bake, renders from the bake and a walk on the Helsinki district) with
# both binaries on every
# fixture in fixtures/ and on two generated cities (gen eixample 6 6, gen
# oldtown 8 8), and compares standard output, standard error, the exit code
# and every file written, byte for byte. Timing figures ("12.34 ms",
# "1.5 s") are blanked first: they are the one thing allowed to change.
# Photon counts are small (--photons 4096 --frames 2) so the whole run
# takes a minute or two. The base binary is kept in build/identical/ by
# commit hash, so a second run builds only the current tree.
#
# Exit 0: no difference; 1: differences (listed, with the first lines of
# each diff); 2: a build failed.
set -u
BASE=${1:-73d3a0e}
TOP=$(git rev-parse --show-toplevel) || exit 2
cd "$TOP" || exit 2
SHA=$(git rev-parse --verify "$BASE^{commit}") || { echo "check-identical: no revision $BASE" >&2; exit 2; }
CACHE=build/identical/$SHA
JOBS=${JOBS:-2}

if [ ! -x "$CACHE/polarlux" ]; then
    wt=$(mktemp -d "${TMPDIR:-/tmp}/plx-identical.XXXXXX")
    git worktree add -q --detach "$wt/src" "$SHA" || exit 2
    echo "check-identical: building $BASE ($SHA) in a temporary worktree"
    if ! make -C "$wt/src" -j"$JOBS" build/polarlux >"$wt/build.log" 2>&1; then
        tail -20 "$wt/build.log" >&2
        git worktree remove --force "$wt/src"; rm -rf "$wt"; exit 2
    fi
    mkdir -p "$CACHE" && cp "$wt/src/build/polarlux" "$CACHE/polarlux"
    git worktree remove --force "$wt/src"
    rm -rf "$wt"
fi
echo "check-identical: building the current tree"
make -j"$JOBS" build/polarlux >/dev/null 2>build/identical/build.err || {
    cat build/identical/build.err >&2; exit 2; }

OUT=build/identical/out
rm -rf "$OUT"; mkdir -p "$OUT/base" "$OUT/new" "$OUT/in"
IN=$OUT/in

# Inputs every run shares: the fixtures, two generated cities (made by the
# base binary, also compared as gen outputs below), points and a route per
# scene derived from its bounds.
"$CACHE/polarlux" gen eixample 6 6 -o "$IN/gen-eixample-6x6.geojson" || exit 2
"$CACHE/polarlux" gen oldtown 8 8 -o "$IN/gen-oldtown-8x8.geojson" || exit 2
SCENES="$(ls fixtures/*.geojson | grep -v -- '-route\.geojson$' | grep -v -- '-walk\.geojson$') $IN/gen-eixample-6x6.geojson $IN/gen-oldtown-8x8.geojson"

# bounds X0 Y0 X1 Y1 of a scene, from 'info'
bounds() {
    "$CACHE/polarlux" info "$1" --quiet 2>/dev/null | sed -n 's/^bounds: \([^ ]*\) \([^ ]*\) \([^ ]*\) \([^ ]*\) .*/\1 \2 \3 \4/p'
}

# run NAME CMD...: runs CMD with the binary $BIN in $DIR, keeping stdout,
# stderr (timings blanked) and the exit code as NAME.{out,err,rc}.
run() {
    name=$1; shift
    "$BIN" "$@" >"$DIR/$name.out" 2>"$DIR/$name.err"
    echo $? >"$DIR/$name.rc"
}

all_commands() {
    for s in $SCENES; do
        n=$(basename "$s" .geojson)
        d=$DIR/$n; mkdir -p "$d"
        p=$IN/$n.points; r=$IN/$n.route.geojson
        b=$(bounds "$s")
        if [ -z "$b" ]; then
            # not a scene (fixtures/helsinki-walk.geojson is a walk path):
            # only the refusal is compared
            run "$n/info" info "$s"
            continue
        fi
        set -- $b
        x0=$1 y0=$2 x1=$3 y1=$4
        if [ ! -f "$p" ]; then
            # local metres whatever the scene's coordinates ('#' lines are
            # comments to revisions that do not read the crs line)
            awk -v x0="$x0" -v y0="$y0" -v x1="$x1" -v y1="$y1" 'BEGIN {
                print "# crs: local";
                for (i = 1; i <= 5; i++) for (j = 1; j <= 5; j++)
                    printf "%.3f %.3f\n", x0 + (x1 - x0) * (i - 0.37) / 5, y0 + (y1 - y0) * (j - 0.61) / 5;
                printf "%.3f %.3f 1.5 1 0 0\n", (x0 + x1) / 2, (y0 + y1) / 2 }' >"$p"
            if [ "$n" = helsinki-centre ]; then
                cp fixtures/helsinki-route.geojson "$r"
            else
                awk -v x0="$x0" -v y0="$y0" -v x1="$x1" -v y1="$y1" 'BEGIN {
                    printf "{\"type\":\"FeatureCollection\",\"properties\":{\"units\":\"m\"},\"features\":[{\"type\":\"Feature\",\"properties\":{\"name\":\"diag\"},\"geometry\":{\"type\":\"LineString\",\"coordinates\":[[%.3f,%.3f],[%.3f,%.3f],[%.3f,%.3f]]}}]}\n",
                        x0 + 1, y0 + 1, (x0 + x1) / 2 + 0.3, (y0 + y1) / 2 + 0.2, x1 - 1, y1 - 1 }' >"$r"
            fi
        fi
        cx=$(awk -v a="$x0" -v b="$x1" 'BEGIN { printf "%.3f", a + (b - a) * 0.43 }')
        cy=$(awk -v a="$y0" -v b="$y1" 'BEGIN { printf "%.3f", a + (b - a) * 0.47 }')
        res=$(awk -v a="$x0" -v b="$x1" -v c="$y0" -v e="$y1" 'BEGIN { m = b - a; if (e - c > m) m = e - c; printf "%.3f", m / 150 }')
        ph="--photons 4096 --frames 2"
        run "$n/info" info "$s"
        run "$n/vis-points" vis "$s" --points "$p" --geojson "$d/vis.geojson"
        run "$n/vis-at" vis "$s" --at "$cx,$cy" --dir 30 --fov 120
        for q in 0 1 2 3; do
            run "$n/draw$q" draw "$s" --polar $q --size 256 -o "$d/draw$q.png"
        done
        run "$n/illum" illum "$s" --points "$p" $ph
        run "$n/illum-direct" illum "$s" --points "$p" --no-indirect
        run "$n/lit0" lit "$s" --lamp 0 -o "$d/lit0.geojson"
        run "$n/lit1" lit "$s" --lamp 1 -o "$d/lit1.geojson"
        run "$n/heatmap" heatmap "$s" --res "$res" -o "$d/heatmap.png" --path "$r"
        run "$n/street" render "$s" --size 160x120 $ph -o "$d/street.png" --pfm "$d/street.pfm"
        run "$n/street-direct" render "$s" --size 160x120 --no-indirect --no-glow -o "$d/street-direct.png"
        run "$n/aerial" render "$s" --view aerial --size 160x160 --texel 2 $ph -o "$d/aerial.png" --pfm "$d/aerial.pfm"
        # anti-aliased: 2 x 2 adaptive into bytes (the marked sums), 3 x 3, every sample
        run "$n/street-aa2" render "$s" --size 161x119 --aa 2 $ph -o "$d/street-aa2.png" --pfm "$d/street-aa2.pfm"
        run "$n/aerial-aa3" render "$s" --view aerial --size 120x120 --texel 2 --aa 3 $ph -o "$d/aerial-aa3.png"
        run "$n/street-aafull" render "$s" --size 160x120 --aa 2 --aa-full --threads 2 $ph -o "$d/street-aafull.png"
        run "$n/route" route "$s" --path "$r" --step 2 --geojson "$d/route.geojson"
        run "$n/dark-spots" dark-spots "$s" --res "$res" --count 10 -o "$d/dark.geojson"
        run "$n/nightify" nightify fixtures/ground-day.png "$d/street.png" -o "$d/nightify.png"
    done
    # a bake of the real district, frames read from its radiance atlas and a walk
    mkdir -p "$DIR/bake"
    run "bake/bake" bake fixtures/helsinki-centre.geojson --photons 4096 --frames 2 -o "$DIR/bake/city.plxb"
    for th in 1 2; do
        run "bake/street-aa2-$th" render "$DIR/bake/city.plxb" --size 240x180 --aa 2 --threads $th \
            -o "$DIR/bake/street-aa2-$th.png" --pfm "$DIR/bake/street-aa2-$th.pfm"
    done
    run "bake/aerial-aa2" render "$DIR/bake/city.plxb" --view aerial --size 200x150 --aa 2 -o "$DIR/bake/aerial-aa2.png"
    run "bake/walk" walk "$DIR/bake/city.plxb" --path fixtures/helsinki-walk.geojson --size 200x150 \
        --max-frames 6 --fps 1 --refine -o "$DIR/bake/walk" # --fps 1: no timing-dependent "fall behind" warning
    mkdir -p "$DIR/gen"
    for style in grid eixample oldtown; do
        run "gen/$style" gen $style 6 6 --seed 3 -o "$DIR/gen/$style.geojson"
    done
    run "gen/oldtown-8x8" gen oldtown 8 8
    # bad usage and bad input: the messages must not change either
    run "gen/usage" gen nowhere 2 2
    run "gen/missing" info "$IN/no-such-file.geojson"
}

BIN=$TOP/$CACHE/polarlux DIR=$OUT/base all_commands
BIN=$TOP/build/polarlux DIR=$OUT/new all_commands

# Blank timing figures and the binary's own path in the texts.
for f in $(cd "$OUT/base" && find . -name '*.out' -o -name '*.err'); do
    for side in base new; do
        sed -E -e 's/[0-9]+(\.[0-9]+)?( ?)(ms|us|ns|s)\b/#\2\3/g' \
            -e "s#$OUT/$side/#OUT/#g" \
            -e 's/[0-9]+(\.[0-9]+)? ?(Mphotons|photons|Mrays|rays|pixels|px)\/s\b/# \2\/s/g' \
            -e 's/[0-9]+(\.[0-9]+)? frames per second/# frames per second/g' \
            "$OUT/$side/$f" >"$OUT/$side/$f.t" && mv "$OUT/$side/$f.t" "$OUT/$side/$f"
    done
done

nfiles=$(cd "$OUT/base" && find . -type f | wc -l)
if diff -r -q "$OUT/base" "$OUT/new" >"$OUT/diff.txt" 2>&1; then
    echo "check-identical: no difference from $BASE in $nfiles outputs"
    exit 0
fi
echo "check-identical: differences from $BASE ($(wc -l <"$OUT/diff.txt") of $nfiles outputs):"
cat "$OUT/diff.txt"
grep -E '^Files .* differ$' "$OUT/diff.txt" | head -5 | while read -r _ a _ b _; do
    case $a in *.png|*.pfm) cmp "$a" "$b" | head -1 ;; *) diff "$a" "$b" | head -8 ;; esac
done
exit 1

#!/bin/sh
# The include rule of src/ (make check-layers, run by make check):
#
# 1. Stages in data-flow order: base < scene < polar < light < photon <
#    render < api (< cli, the command). A file includes headers of its own
#    stage or earlier ones only.
# 2. Only src/api and src/base include base/engine.h (the engine's layout);
#    the other stages reach the engine through base/context.h.
# 3. No circles between files. Each X.c with its X.h is one unit; a unit
#    depends on the units whose headers it includes. A header without a .c
#    of its name (a private header shared by several files, such as
#    polar/polar_int.h) passes its includes through to whoever includes it.
#    The graph of units must have no cycle (tsort finds them).
#
# 4. A header X.h with an X.c declares only functions X.c defines, so that
#    a dependency cannot hide in a header shared by several files (scene to
#    render; base and api share base/engine.h).
#
# Prints every violation with file and line; exit 1 when there is one.
# One awk pass reads every file (the shell loop it replaces forked a few
# thousand processes: 6.4 s of make check's CPU, now a few hundredths).
cd "$(dirname "$0")/.." || exit 2
tmp=${TMPDIR:-/tmp}/plx-layers.$$
trap 'rm -f "$tmp".*' EXIT

FILES=$(ls src/*/*.c src/*/*.h 2>/dev/null)
PORT=$(ls port/*/*.c port/*/*.h 2>/dev/null)
STAGES=$(cd src && ls -d */ | tr -d / | tr '\n' ' ')

# rules 1, 2 and 4 print their violations; rule 3's edges go to $tmp.edges
# as "unit unit file"
awk -v stages="$STAGES" -v edges="$tmp.edges" '
function rank(s) {
    return s == "base" ? 0 : s == "scene" ? 1 : s == "polar" ? 2 : s == "light" ? 3 : \
           s == "photon" ? 4 : s == "render" ? 5 : s == "api" ? 6 : s == "cli" ? 7 : 99
}
# the units a header (stage/name.h) stands for: itself when it has a .c,
# else what it includes, each header once per include followed (seen)
function deps_of(h, out,    k, n, u) {
    u = substr(h, 1, length(h) - 2)
    if (("src/" u ".c") in exists) { out[u] = 1; return }
    if (!(("src/" h) in exists) || (h in seen)) return
    seen[h] = 1
    n = ninc["src/" h]
    for (k = 1; k <= n; k++) deps_of(inc["src/" h, k], out)
}
BEGIN { n = split(stages, a, " "); for (k = 1; k <= n; k++) isstage[a[k]] = 1 }
FNR == 1 { exists[FILENAME] = 1; order[++nfiles] = FILENAME }
/^[ \t]*#[ \t]*include[ \t]*"[a-z_]*\/[A-Za-z0-9_]*\.h"/ {
    h = $0; sub(/^[^"]*"/, "", h); sub(/".*/, "", h)
    ninc[FILENAME]++; inc[FILENAME, ninc[FILENAME]] = h; incline[FILENAME, ninc[FILENAME]] = FNR
}
# rule 4: the functions a file defines (a line starting with a letter,
# the name after a blank or a star, then "(") and a header declares
/^[a-z]/ && FILENAME ~ /\.c$/ {
    s = $0
    while (match(s, /[ *][a-z_][a-z0-9_]*\(/)) {
        defs[FILENAME, substr(s, RSTART + 1, RLENGTH - 2)] = 1
        s = substr(s, RSTART + RLENGTH)
    }
}
/^[a-z][a-z0-9_ ]*[ *][a-z_][a-z0-9_]*\(/ && !/^static/ && FILENAME ~ /^src\/(scene|polar|light|photon|render)\/.*\.h$/ {
    s = $0; sub(/\(.*/, "", s); sub(/.*[ *]/, "", s)
    ndecl[FILENAME]++; decl[FILENAME, ndecl[FILENAME]] = s
}
END {
    for (i = 1; i <= nfiles; i++) {
        f = order[i]
        if (f ~ /^src\//) { st = substr(f, 5); sub(/\/.*/, "", st) } else st = "port"
        for (k = 1; k <= ninc[f]; k++) {
            h = inc[f, k]; hs = h; sub(/\/.*/, "", hs); line = incline[f, k]
            if (!(hs in isstage)) {
                if (st != "cli" && st != "port") { print "check-layers: " f ": the core includes the port header " h; bad = 1 }
            } else if (st != "port" && rank(hs) > rank(st)) {
                print "check-layers: " f ":" line ": " st " includes " h " of a later stage (" hs ")"; bad = 1
            }
            if (h == "base/engine.h" && st != "api" && st != "base") {
                print "check-layers: " f ":" line ": only src/api and src/base may include base/engine.h (use base/context.h)"; bad = 1
            }
        }
        # rule 3: a unit is X.c, or X.h with an X.c; cli is the command, not a unit
        if (f !~ /^src\// || f ~ /^src\/cli\//) continue
        u = substr(f, 5); sub(/\.[ch]$/, "", u)
        if (f ~ /\.h$/ && !(("src/" u ".c") in exists)) continue
        for (k = 1; k <= ninc[f]; k++) {
            delete seen; delete out
            deps_of(inc[f, k], out)
            for (v in out) if (v != u) print u, v, f > edges
        }
        # rule 4
        if (f ~ /\.h$/) {
            c = "src/" u ".c"
            for (k = 1; k <= ndecl[f]; k++) {
                fn = decl[f, k]
                if ((c, fn) in defs) continue
                def = "no file"
                for (j = 1; j <= nfiles; j++)
                    if (order[j] ~ /^src\/[^\/]*\/[^\/]*\.c$/ && ((order[j], fn) in defs)) { def = order[j]; break }
                print "check-layers: " f " declares " fn ", which " def " defines, not " c; bad = 1
            }
        }
    }
    close(edges)
    exit bad
}' $FILES $PORT
fail=$?
touch "$tmp.edges"

awk '{ print $1, $2 }' "$tmp.edges" | sort -u >"$tmp.pairs"
if ! tsort "$tmp.pairs" >/dev/null 2>"$tmp.loop"; then
    echo "check-layers: files include each other in a circle:"
    sed -n 's/^tsort: //p' "$tmp.loop" | grep -v 'input contains a loop' | sed 's/^/  /'
    # the direct pairs, with the files that make them
    awk '{ e[$1 " " $2] = $3 } END { for (k in e) { split(k, p, " "); if ((p[2] " " p[1]) in e) print "  " e[k] " includes " p[2] ".h" } }' "$tmp.edges"
    fail=1
fi

if [ $fail = 0 ]; then
    echo "check-layers: $(echo "$FILES" | wc -w) files in src/, stages in order, base/engine.h only in api and base, no circles ($(wc -l <"$tmp.pairs") unit dependencies)"
fi
exit $fail

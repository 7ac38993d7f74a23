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
cd "$(dirname "$0")/.." || exit 2
tmp=${TMPDIR:-/tmp}/plx-layers.$$
trap 'rm -f "$tmp".*' EXIT
fail=0

rank() {
    case $1 in
    base) echo 0 ;; scene) echo 1 ;; polar) echo 2 ;; light) echo 3 ;;
    photon) echo 4 ;; render) echo 5 ;; api) echo 6 ;; cli) echo 7 ;; *) echo 99 ;;
    esac
}

# includes FILE: the path-qualified local includes of FILE ("stage/name.h").
includes() {
    sed -n 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"\([a-z_]*\/[A-Za-z0-9_]*\.h\)".*/\1/p' "$1"
}

FILES=$(ls src/*/*.c src/*/*.h 2>/dev/null)

# 1 and 2
for f in $FILES port/*/*.c port/*/*.h; do
    [ -f "$f" ] || continue
    case $f in src/*) st=${f#src/}; st=${st%%/*} ;; *) st=port ;; esac
    r=$(rank "$st")
    for h in $(includes "$f"); do
        hs=${h%%/*}
        if [ ! -d "src/$hs" ]; then
            # a port header (port/png, port/posix, ...): the command's business
            if [ "$st" != cli ] && [ "$st" != port ]; then
                echo "check-layers: $f: the core includes the port header $h"
                fail=1
            fi
        elif [ "$st" != port ] && [ "$(rank "$hs")" -gt "$r" ]; then
            echo "check-layers: $f:$(grep -n "\"$h\"" "$f" | head -1 | cut -d: -f1): $st includes $h of a later stage ($hs)"
            fail=1
        fi
        if [ "$h" = base/engine.h ] && [ "$st" != api ] && [ "$st" != base ]; then
            echo "check-layers: $f:$(grep -n "\"$h\"" "$f" | head -1 | cut -d: -f1): only src/api and src/base may include base/engine.h (use base/context.h)"
            fail=1
        fi
    done
done

# 3: unit edges, headers without a .c passed through
unit_of() { # header path (stage/name.h) -> its unit, or "" when it has no .c
    [ -f "src/${1%.h}.c" ] && echo "${1%.h}"
}
# deps_of HEADER: the units a header stands for (itself, or what it includes)
deps_of() {
    u=$(unit_of "$1")
    if [ -n "$u" ]; then
        echo "$u"
    elif [ -f "src/$1" ]; then
        case " $SEEN " in *" $1 "*) return ;; esac
        SEEN="$SEEN $1"
        for g in $(includes "src/$1"); do deps_of "$g"; done
    fi
}
: >"$tmp.edges"
for f in $FILES; do
    case $f in src/cli/*) continue ;; esac
    rel=${f#src/}
    u=${rel%.*}
    # a header without a .c of its own is no unit: its includes count for
    # the files that include it
    case $f in *.h) [ -f "src/$u.c" ] || continue ;; esac
    for h in $(includes "$f"); do
        SEEN=""
        for v in $(deps_of "$h"); do
            [ "$v" != "$u" ] && echo "$u $v  $f" >>"$tmp.edges"
        done
    done
done
awk '{ print $1, $2 }' "$tmp.edges" | sort -u >"$tmp.pairs"
if ! tsort "$tmp.pairs" >/dev/null 2>"$tmp.loop"; then
    echo "check-layers: files include each other in a circle:"
    sed -n 's/^tsort: //p' "$tmp.loop" | grep -v 'input contains a loop' | sed 's/^/  /'
    # the direct pairs, with the files that make them
    awk '{ e[$1 " " $2] = $3 } END { for (k in e) { split(k, p, " "); if ((p[2] " " p[1]) in e) print "  " e[k] " includes " p[2] ".h" } }' "$tmp.edges"
    fail=1
fi

# 4: a header that has a .c of its name declares only that file's functions
# (a function of another file declared there would hide a dependency, and
# with it a circle, from rule 3). For scene .. render; base and api are the
# two halves of the engine and share base/engine.h.
for h in src/scene/*.h src/polar/*.h src/light/*.h src/photon/*.h src/render/*.h; do
    c=${h%.h}.c
    [ -f "$c" ] || continue
    for fn in $(grep -v '^static' "$h" | sed -n 's/^[a-z][a-z0-9_ ]*[ *]\([a-z_][a-z0-9_]*\)(.*/\1/p'); do
        if ! grep -q "^[a-z].*[ *]$fn(" "$c"; then
            def=$(grep -l "^[a-z].*[ *]$fn(" src/*/*.c | head -1)
            echo "check-layers: $h declares $fn, which ${def:-no file} defines, not $c"
            fail=1
        fi
    done
done

if [ $fail = 0 ]; then
    echo "check-layers: $(echo "$FILES" | wc -w) files in src/, stages in order, base/engine.h only in api and base, no circles ($(wc -l <"$tmp.pairs") unit dependencies)"
fi
exit $fail

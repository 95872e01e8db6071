#!/usr/bin/env bash
# tests/wine.sh (make wine): ./ray for Windows, run for real.  ray.exe is
# built with mingw-w64 as the Makefile builds ./ray (OpenMP when the compiler
# has it; -static, so that it needs no DLL of the compiler's), run under Wine,
# and its files are compared byte for byte with ./ray's on Linux: the card's
# scene, a path-traced one, a PNG and a PFM; then what Windows does its own
# way: a scene on stdin, stdout in binary mode, the rename over an existing
# file, and the scene as -o in another spelling.  Not a *.test.sh, so not in make test: Wine may
# be absent, and its first start makes a new prefix (some 700 MB, about 5 s);
# .ci/run runs it after the mingw-w64 build.  Lines "PASS ", "FAIL ",
# "SKIP ", then "N passed, N failed, N skipped"; exit 1 on a failure.
#   WINE (default wine) and MINGW_CC (x86_64-w64-mingw32-gcc) name the tools.
cd "$(dirname "$0")/.." || exit 2
. tests/lib.sh
repo=$PWD
WINE=${WINE:-wine}
MINGW_CC=${MINGW_CC:-x86_64-w64-mingw32-gcc}
passed=0 failed=0 skipped=0 prefix_s=
ok()   { echo "PASS $*"; passed=$((passed + 1)); }
bad()  { echo "FAIL $*"; failed=$((failed + 1)); }
skip() { echo "SKIP $*"; skipped=$((skipped + 1)); }
finish() {
  local first=""
  [ -n "$prefix_s" ] && first=", $prefix_s s of them Wine's first start (a new prefix)"
  echo "wine.sh: $((SECONDS - began)) s in all$first"
  echo "$passed passed, $failed failed, $skipped skipped"
  [ "$failed" = 0 ]; exit
}
began=$SECONDS

# A prefix of this run's own under $TMP, its server's socket there too
# (TMPDIR), no display, no Mono or Gecko to offer, no debug output: the
# server this run starts is ended before $TMP goes.
export WINEPREFIX=$TMP/prefix WINEARCH=win64 WINEDEBUG=-all WINEDLLOVERRIDES='mscoree,mshtml=' TMPDIR=$TMP
unset DISPLAY WAYLAND_DISPLAY
trap '[ -d "$WINEPREFIX" ] && wineserver -k 2>/dev/null; rm -rf "$TMP"' EXIT

[ -x ./ray ] || { bad "no ./ray to compare with (make ray)"; finish; }
command -v "$MINGW_CC" >/dev/null ||
  { skip "Windows under Wine: no $MINGW_CC (Debian: gcc-mingw-w64-x86-64)"; finish; }
command -v "$WINE" >/dev/null || { skip "Windows under Wine: no $WINE (Debian: wine wine64)"; finish; }

# shellcheck disable=SC2086 # CFLAGS and RAY_PARTS hold several words
omp=$(echo 'int main(void){return 0;}' |
      "$MINGW_CC" -fopenmp -static -x c - -o "$TMP/omp.exe" 2>/dev/null && echo -fopenmp)
# shellcheck disable=SC2086
if "$MINGW_CC" -std=c99 $CFLAGS -ffp-contract=off $omp -static -o "$TMP/ray.exe" \
     ray.c $RAY_PARTS -lm 2>"$TMP/cc.err"; then
  ok "$MINGW_CC builds ray.exe (${omp:-no OpenMP}, -static)"
else
  bad "$MINGW_CC cannot build ray.exe: $(head -n 3 "$TMP/cc.err" | tr '\n' ' ')"; finish
fi

s=$SECONDS
version=$("$WINE" "$TMP/ray.exe" --version 2>"$TMP/wine.err")
prefix_s=$((SECONDS - s))
case $version in
  "ray "*) ok "ray.exe runs under $("$WINE" --version 2>/dev/null): $version" ;;
  *) bad "ray.exe does not start under $WINE: $(tail -n 2 "$TMP/wine.err" | tr '\n' ' ')"; finish ;;
esac
mkdir "$TMP/lin" "$TMP/win"
win() { "$WINE" "$TMP/ray.exe" "$@"; }

# same NAME FILE LINUX_SCENE WINDOWS_SCENE OPTION...: ./ray and ray.exe
# render the scene with the options, -o lin/FILE and win/FILE; PASS when
# the two files hold the same bytes.
same() {
  local name=$1 file=$2 lscene=$3 wscene=$4
  shift 4
  ./ray "$@" -o "$TMP/lin/$file" "$lscene" 2>/dev/null
  win "$@" -o "$TMP/win/$file" "$wscene" 2>/dev/null
  if [ ! -s "$TMP/lin/$file" ]; then bad "$name: ./ray wrote no $file"
  elif cmp -s "$TMP/lin/$file" "$TMP/win/$file"; then ok "$name: the same bytes"
  else bad "$name: $(cmp "$TMP/lin/$file" "$TMP/win/$file" 2>&1 | head -n 1)"
  fi
}

# The card's scene as the README runs it, no -o: SCENE's base name + .ppm
# in the current directory, here from a path with a drive and backslashes
# (Wine's Z: is /).  A copy of the scene, so that a wrong name cannot put
# the image in the repository.
mkdir "$TMP/card"
cp scenes/minray.sph "$TMP/card/"
(cd "$TMP/lin" && "$repo/ray" "$TMP/card/minray.sph") 2>/dev/null
(cd "$TMP/win" && win "$(printf 'Z:%s' "$TMP/card/minray.sph" | tr / '\\')") 2>/dev/null
if [ -s "$TMP/lin/minray.ppm" ] && cmp -s "$TMP/lin/minray.ppm" "$TMP/win/minray.ppm"; then
  ok "the card's scene (ray Z:\\...\\minray.sph): minray.ppm where it runs, the same bytes"
else
  bad "the card's scene: $(ls "$TMP/win" | tr '\n' ' ') $(cmp "$TMP/lin/minray.ppm" "$TMP/win/minray.ppm" 2>&1)"
fi
same "path traced (--pt -n 4 -s 64x48 -t 2 scenes/cornell.sph)" cornell.ppm \
  scenes/cornell.sph scenes/cornell.sph --pt -n 4 -s 64x48 -t 2
same "a PNG (-s 64x48 --gamma scenes/whitted.sph)" whitted.png \
  scenes/whitted.sph scenes/whitted.sph -s 64x48 --gamma
same "a PFM of the mesh scene, its OBJ found beside scenes\\mesh.sph" mesh.pfm \
  scenes/mesh.sph 'scenes\mesh.sph' -s 48x36

# The scene on standard input (-), as Windows hands it over (text mode:
# a scene's lines are text), and the image on standard output.
./ray -s 16x16 -o "$TMP/lin/stdin.ppm" - <scenes/minray.sph 2>/dev/null
win -s 16x16 -o - - <scenes/minray.sph 2>/dev/null | cat >"$TMP/win/stdin.ppm"
if [ -s "$TMP/lin/stdin.ppm" ] && cmp -s "$TMP/lin/stdin.ppm" "$TMP/win/stdin.ppm"; then
  ok "ray -o - - <scenes/minray.sph: the scene from stdin, the image to stdout, the same bytes"
else
  bad "ray -o - - <scenes/minray.sph: $(cmp "$TMP/lin/stdin.ppm" "$TMP/win/stdin.ppm" 2>&1 | head -n 1)"
fi

# Binary stdout: P6 bytes (0x0a among them) and P3's lines through a pipe,
# no \r added (ray.exe sets stdout's mode to binary for -o -).
for form in P6 P3; do
  opts=()
  [ $form = P3 ] && opts=(--p3)
  ./ray "${opts[@]}" -s 16x16 -o - scenes/minray.sph 2>/dev/null | cat >"$TMP/lin/stdout.$form"
  win "${opts[@]}" -s 16x16 -o - scenes/minray.sph 2>/dev/null | cat >"$TMP/win/stdout.$form"
  if [ -s "$TMP/lin/stdout.$form" ] && cmp -s "$TMP/lin/stdout.$form" "$TMP/win/stdout.$form"; then
    ok "-o - writes $form to a pipe in binary mode: the same bytes, no \\r"
  else
    bad "-o - writes $form: $(cmp "$TMP/lin/stdout.$form" "$TMP/win/stdout.$form" 2>&1 | head -n 1)," \
        "$(tr -cd '\r' <"$TMP/win/stdout.$form" | wc -c) \\r"
  fi
done

# -o FILE that exists: the temporary renamed over it (Windows' rename
# refuses an existing target), twice: over a text file, then over an image.
printf 'old\n' >"$TMP/win/over.ppm"
win -o "$TMP/win/over.ppm" scenes/minray.sph 2>/dev/null
first=$(cmp -s "$TMP/lin/minray.ppm" "$TMP/win/over.ppm" && echo yes)
./ray -s 16x16 -o "$TMP/lin/over16.ppm" scenes/minray.sph 2>/dev/null
win -s 16x16 -o "$TMP/win/over.ppm" scenes/minray.sph 2>/dev/null
left=$(find "$TMP/win" -name '*.tmp.*' | wc -l)
if [ "$first" = yes ] && cmp -s "$TMP/lin/over16.ppm" "$TMP/win/over.ppm" && [ "$left" = 0 ]; then
  ok "-o an existing file replaces it (over a text file, then over an image), no temporary left"
else
  bad "-o an existing file: first run replaced it: ${first:-no}; second:" \
      "$(cmp "$TMP/lin/over16.ppm" "$TMP/win/over.ppm" 2>&1 | head -n 1); $left temporaries left"
fi

# The scene or its mesh as -o in another spelling, which on Windows names
# the same file: refused, the file kept (in a copy, lest a bug write over
# the repository's).
cp scenes/minray.sph scenes/mesh.sph scenes/ball.obj "$TMP/win/"
(cd "$TMP/win" && win -o '.\MINRAY.SPH' minray.sph) 2>"$TMP/refused.err"
rc=$?
if [ "$rc" = 2 ] && cmp -s scenes/minray.sph "$TMP/win/minray.sph" && grep -q 'is the scene file' "$TMP/refused.err"
then ok "-o .\\MINRAY.SPH for the scene minray.sph: refused (exit 2), the scene kept"
else bad "-o .\\MINRAY.SPH for the scene minray.sph: exit $rc; $(ls "$TMP/win" | tr '\n' ' ')"
fi
(cd "$TMP/win" && win -o BALL.OBJ mesh.sph) 2>"$TMP/refused.err"
rc=$?
if [ "$rc" = 1 ] && cmp -s scenes/ball.obj "$TMP/win/ball.obj" && grep -q 'the mesh is the output' "$TMP/refused.err"
then ok "-o BALL.OBJ for mesh.sph, which reads ball.obj: refused (exit 1), the mesh kept"
else bad "-o BALL.OBJ for mesh.sph: exit $rc; $(ls "$TMP/win" | tr '\n' ' ')"
fi

# A render split across the two systems: a band by ray.exe, the rest by
# ./ray, merged by each, is the whole run's bytes (a partial is
# little-endian integers on both; the provenance names the same version and
# arithmetic, and the same scene).
./ray scenes/cornell.sph --pt -s 48x36 -n 6 -o "$TMP/lin/whole.pfm" 2>/dev/null
./ray scenes/cornell.sph --pt -s 48x36 -n 6 --tile 0/3 -o "$TMP/lin/p0.part" 2>/dev/null
win scenes/cornell.sph --pt -s 48x36 -n 6 --tile 1/3 -o "$TMP/win/p1.part" 2>/dev/null
./ray scenes/cornell.sph --pt -s 48x36 -n 6 --tile 2/3 -o "$TMP/lin/p2.part" 2>/dev/null
./ray --merge "$TMP/lin/merged.pfm" "$TMP/lin/p0.part" "$TMP/win/p1.part" "$TMP/lin/p2.part" 2>/dev/null
win --merge "$TMP/win/merged.pfm" "$TMP/lin/p0.part" "$TMP/win/p1.part" "$TMP/lin/p2.part" 2>/dev/null
if [ -s "$TMP/lin/whole.pfm" ] && cmp -s "$TMP/lin/whole.pfm" "$TMP/lin/merged.pfm" \
   && cmp -s "$TMP/lin/whole.pfm" "$TMP/win/merged.pfm"; then
  ok "a split render, one tile of three by ray.exe, merged by ./ray and by ray.exe: the whole run's bytes"
else
  bad "a split render across the systems: $(cmp "$TMP/lin/whole.pfm" "$TMP/lin/merged.pfm" 2>&1 | head -n 1);" \
      "$(cmp "$TMP/lin/whole.pfm" "$TMP/win/merged.pfm" 2>&1 | head -n 1)"
fi
finish

# Output and input at their edges (issue 13): PNG and --gamma, output that is
# neither lost nor left behind, and readers and a command line that say what
# is really wrong.  Every check prints PASS or FAIL (tests/lib.sh).
. tests/lib.sh

# --- PNG: decoded by tests/png2ppm.py (python's zlib inflates it, every CRC
# and the Adler-32 are checked) and compared byte for byte with the PPM of the
# same render: width 1, odd sizes, 65535 and 131070 bytes of rows (28x771,
# 28x1542: once a stored block's most), and more than one IDAT chunk.
# tests/image.test.sh has the rest: sizes, noise, and the size against zlib.
for size in 1x1 1x9 7x5 33x17 28x771 28x1542 160x140; do
  ./ray -s $size -o "$TMP/p.ppm" scenes/minray.sph && ./ray -s $size -o "$TMP/p.png" scenes/minray.sph \
    && python3 tests/png2ppm.py "$TMP/p.png" > "$TMP/back.ppm" 2> "$TMP/err" && cmp -s "$TMP/back.ppm" "$TMP/p.ppm" \
    && ok "PNG $size decodes to the PPM's bytes" || bad "PNG $size: $(cat "$TMP/err")"
done
./ray -s 9x4 --gamma -o "$TMP/g.ppm" scenes/whitted.sph && ./ray -s 9x4 --gamma -o "$TMP/G.PNG" scenes/whitted.sph \
  && python3 tests/png2ppm.py -c "$TMP/G.PNG" 2> "$TMP/chunks" | cmp -s - "$TMP/g.ppm" \
  && [ "$(head -c 4 "$TMP/G.PNG" | tail -c 3)" = PNG ] && grep -qx sRGB "$TMP/chunks" \
  && ok "-o X.PNG (upper case) writes a PNG; with --gamma it has an sRGB chunk and the --gamma PPM's bytes" \
  || bad "-o X.PNG with --gamma: $(cat "$TMP/chunks")"
python3 tests/png2ppm.py -c "$TMP/p.png" 2> "$TMP/chunks" > /dev/null; ! grep -q sRGB "$TMP/chunks" \
  && ok "PNG without --gamma has no sRGB chunk" || bad "PNG without --gamma says sRGB"
for args in "-o $TMP/x.jpg" "-o $TMP/x.TIFF" "--p3 -o $TMP/x.png"; do
  rm -f "$TMP"/x.*
  ./ray -s 4x4 $args scenes/minray.sph 2> "$TMP/err"; rc=$?
  [ $rc = 2 ] && ! ls "$TMP"/x.* > /dev/null 2>&1 && ok "${args//$TMP\//} refused, exit 2: $(sed "s|$TMP/||" "$TMP/err")" \
    || bad "${args//$TMP\//}: exit $rc, $(cat "$TMP/err")"
done

# --- --gamma: the sRGB curve (IEC 61966-2-1) on a 1x1 image of one colour,
# against python's own evaluation of it; without --gamma the byte is linear.
levels="0 0.001 0.0031308 0.004 0.01 0.18 0.5 0.9 1 1.5"
for g in "" --gamma; do
  for v in $levels; do
    printf 'background %s %s %s\n' $v $v $v > "$TMP/bg.sph"
    ./ray -s 1x1 $g -o - "$TMP/bg.sph" 2>/dev/null | tail -c 1 | od -An -tu1
  done
done | tr -s ' \n' ' ' > "$TMP/got"
python3 -c "
def srgb(v): return 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055
vs = [float(x) for x in '$levels'.split()]
print(' ' + ' '.join(str(min(255, max(0, round(255 * f(v))))) for f in (lambda v: v, srgb) for v in vs) + ' ')
" | tr -d '\n' > "$TMP/want"
cmp -s "$TMP/got" "$TMP/want" && ok "--gamma gives the sRGB curve's bytes, linear without it ($(cat "$TMP/want"))" \
  || bad "--gamma bytes: got$(cat "$TMP/got"), want$(cat "$TMP/want")"

# --- Unit tests of the plumbing (tests/test_io.c): the curve at worked
# points, CRC-32 and Adler-32 check values, extensions, and paths split as
# POSIX and (-DRAY_DOS_PATHS) as Windows splits them.
for paths in "" -DRAY_DOS_PATHS; do
  # shellcheck disable=SC2046 # the parts but image.c, which test_io.c
  # includes, from their sources (-O0, without CFLAGS)
  if $CC -std=c99 -O0 $paths -o "$TMP/test_io" tests/test_io.c $(RAY_PARTS=$RAY_SOURCES parts_but image) -lm 2> "$TMP/err"; then
    "$TMP/test_io"
  else
    bad "tests/test_io.c $paths compiles: $(head -3 "$TMP/err")"
  fi
done

# --- Output that is neither lost nor left behind (issue 13, section 3).
# big: a render that takes minutes, to be interrupted once its temporary file
# (FILE.tmp.PID) is there.
big="-s 3000x3000 -n 16 scenes/whitted.sph"
wait_for_temp() {  # wait_for_temp PATTERN COUNT: up to 10 s for COUNT files
  local k
  for k in $(seq 100); do
    [ "$(ls $1 2>/dev/null | wc -l)" -ge "$2" ] && return 0
    sleep 0.1
  done
  return 1
}
mkdir "$TMP/out"
set -m   # job control: a background job would otherwise ignore SIGINT
ulimit -c 0 2>/dev/null   # SIGQUIT, SIGXCPU and SIGXFSZ dump core by default: no core files here
# every signal that ends a program by default and can be caught
for sig in INT TERM HUP QUIT USR1 USR2 ALRM PIPE XCPU XFSZ VTALRM PROF; do
  echo "old image" > "$TMP/out/x.ppm"
  ./ray $big -o "$TMP/out/x.ppm" 2>/dev/null & pid=$!
  wait_for_temp "$TMP/out/x.ppm.tmp.*" 1; kill -$sig $pid; wait $pid; rc=$?
  want=$((128 + $(kill -l $sig)))
  [ $rc = $want ] && [ "$(ls "$TMP/out")" = x.ppm ] && [ "$(cat "$TMP/out/x.ppm")" = "old image" ] \
    && ok "SIG$sig during a render: exit $rc, the temporary file removed, the old image kept" \
    || bad "SIG$sig: exit $rc (want $want), left: $(ls "$TMP/out" | tr '\n' ' ')"
done
set +m

# SIGKILL cannot be caught: its temporary stays, and the next run writing
# beside it removes it (saying so).  Kept: a temporary of a process that
# still runs (this shell), names that are no temporary of the output, and
# temporaries of other outputs.
./ray $big -o "$TMP/out/x.ppm" 2>/dev/null & pid=$!
wait_for_temp "$TMP/out/x.ppm.tmp.*" 1; kill -KILL $pid; wait $pid 2>/dev/null
killed=$(ls "$TMP/out" | grep tmp | tr '\n' ' ')
sh -c 'exit 0' & gone=$!; wait $gone
touch "$TMP/out/x.ppm.tmp.$gone.2" "$TMP/out/x.ppm.tmp.$$" "$TMP/out/x.ppm.tmp.12x" "$TMP/out/y.ppm.tmp.$gone"
./ray -s 8x8 -o "$TMP/out/x.ppm" scenes/minray.sph 2>"$TMP/err"
left=$(ls "$TMP/out" | tr '\n' ' ')
want=$(printf '%s\n' x.ppm "x.ppm.tmp.$$" x.ppm.tmp.12x "y.ppm.tmp.$gone" | LC_ALL=C sort | tr '\n' ' ')
left=$(ls "$TMP/out" | LC_ALL=C sort | tr '\n' ' ')
[ -n "$killed" ] && [ "$left" = "$want" ] \
  && [ "$(grep -c 'left by a run that was killed' "$TMP/err")" = 2 ] \
  && ok "SIGKILL leaves $killed; the next run removes it and x.ppm.tmp.GONE.2, keeps the rest" \
  || bad "stale temporaries: killed left '$killed', after the next run: $left; said: $(tr '\n' '|' <"$TMP/err")"
rm -f "$TMP"/out/*.tmp.*

# -o through a symbolic link: the link's target gets the image, through a
# temporary beside it renamed over it at the end (so an interrupt leaves the
# old image whole, not an emptied file); the link stays a link.
echo "old image" > "$TMP/out/target.ppm"; ln -s target.ppm "$TMP/out/link.ppm"
set -m
./ray $big -o "$TMP/out/link.ppm" 2>/dev/null & pid=$!
wait_for_temp "$TMP/out/target.ppm.tmp.*" 1; kill -INT $pid; wait $pid
set +m
[ "$(cat "$TMP/out/target.ppm")" = "old image" ] && [ -L "$TMP/out/link.ppm" ] && ! ls "$TMP/out" | grep -q tmp \
  && ok "-o through a symbolic link, interrupted: the target keeps its old image whole, no temporary left" \
  || bad "-o through a link, interrupted: target '$(head -c 20 "$TMP/out/target.ppm")', left: $(ls "$TMP/out" | tr '\n' ' ')"
./ray -s 8x8 -o "$TMP/out/link.ppm" scenes/minray.sph 2>/dev/null
[ -L "$TMP/out/link.ppm" ] && [ "$(head -c 2 "$TMP/out/target.ppm")" = P6 ] && ! ls "$TMP/out" | grep -q tmp \
  && ok "-o through a symbolic link: the target gets the image, the link stays a link" \
  || bad "-o through a link: $(ls -l "$TMP/out" | tr '\n' ' ')"
rm -f "$TMP/out/link.ppm" "$TMP/out/target.ppm"

# -o naming a mesh the scene reads is refused, and the mesh is kept.
cp scenes/ball.obj "$TMP/out/ball.obj"; cp scenes/ball.obj "$TMP/ball.keep"
printf 'mesh ball.obj  .9 .5 .2   .7 .3 0 0 1\n' > "$TMP/out/m.sph"
./ray -s 8x8 -o "$TMP/out/ball.obj" "$TMP/out/m.sph" 2>"$TMP/err"; rc=$?
[ $rc = 1 ] && grep -q "m.sph:1: the mesh is the output file (-o); not overwritten" "$TMP/err" \
  && cmp -s "$TMP/out/ball.obj" "$TMP/ball.keep" && ok "-o naming the scene's mesh: refused at the mesh line, the mesh kept" \
  || bad "-o naming a mesh: exit $rc, $(cat "$TMP/err")"
rm -f "$TMP/out/ball.obj" "$TMP/out/m.sph"

# Two runs at once with the same -o: each has a temporary file of its own.
./ray $big -o "$TMP/out/x.ppm" 2>/dev/null & p1=$!
./ray $big -o "$TMP/out/x.ppm" 2>/dev/null & p2=$!
wait_for_temp "$TMP/out/x.ppm.tmp.*" 2 && n=2 || n=$(ls "$TMP/out" | grep -c tmp)
kill -TERM $p1 $p2; wait $p1 $p2 2>/dev/null
[ $n = 2 ] && [ "$(ls "$TMP/out")" = x.ppm ] && ok "two runs with the same -o write two temporary files, and leave none" \
  || bad "two runs with the same -o: $n temporary files, left: $(ls "$TMP/out" | tr '\n' ' ')"
# A name this run would take for its temporary file, already there as a
# link, is neither followed nor replaced: the shell's PID is the one ray gets
# by exec.
echo victim > "$TMP/victim"
sh -c 'ln -s "$1/victim" "$1/out/x.ppm.tmp.$$"; exec ./ray -s 8x8 -o "$1/out/x.ppm" scenes/minray.sph' sh "$TMP"; rc=$?
[ $rc = 0 ] && [ "$(cat "$TMP/victim")" = victim ] && [ "$(head -c 2 "$TMP/out/x.ppm")" = P6 ] \
  && [ "$(ls "$TMP/out" | wc -l)" = 2 ] && ok "a temporary name already taken (a link) is not followed; another is used" \
  || bad "taken temporary name: exit $rc, victim: $(cat "$TMP/victim"), left: $(ls "$TMP/out" | tr '\n' ' ')"
rm -f "$TMP/out/"*

# A read-only output is refused (exit 1, a message, untouched); a writable
# one keeps its mode through the rename.
echo "read-only image" > "$TMP/out/ro.ppm"; chmod 444 "$TMP/out/ro.ppm"
./ray -s 8x8 -o "$TMP/out/ro.ppm" scenes/minray.sph 2> "$TMP/err"; rc=$?
[ $rc = 1 ] && grep -q "ro.ppm: is read-only; not replaced" "$TMP/err" && [ "$(cat "$TMP/out/ro.ppm")" = "read-only image" ] \
  && [ "$(ls "$TMP/out")" = ro.ppm ] && ok "a read-only -o is refused: $(sed "s|$TMP/out/||" "$TMP/err")" \
  || bad "read-only -o: exit $rc, $(cat "$TMP/err")"
echo old > "$TMP/out/m.ppm"; chmod 640 "$TMP/out/m.ppm"
./ray -s 8x8 -o "$TMP/out/m.ppm" scenes/minray.sph && [ "$(stat -c %a "$TMP/out/m.ppm")" = 640 ] \
  && [ "$(head -c 2 "$TMP/out/m.ppm")" = P6 ] && ok "a replaced -o keeps its mode (640)" \
  || bad "mode after replacing: $(stat -c %a "$TMP/out/m.ppm")"

# -o naming the scene itself, however spelled, is refused (exit 2) and the
# scene is left as it was.
cp scenes/minray.sph "$TMP/out/s.sph"; ln -s s.sph "$TMP/out/link.sph"; ln "$TMP/out/s.sph" "$TMP/out/hard.sph"
for o in "$TMP/out/s.sph" "$TMP/out/../out/s.sph" "$TMP/out/link.sph" "$TMP/out/hard.sph"; do
  ./ray -s 8x8 -o "$o" "$TMP/out/s.sph" 2> "$TMP/err"; rc=$?
  [ $rc = 2 ] && cmp -s scenes/minray.sph "$TMP/out/s.sph" && grep -q "is the scene file" "$TMP/err" \
    && ok "-o ${o#$TMP/out/} is the scene: refused, exit 2" || bad "-o ${o#$TMP/out/} as the scene: exit $rc, $(cat "$TMP/err")"
done

# --- The command line (issue 13, section 4): values attached to their
# option, the choices of --accel, exit 2 for every usage error and 1 for a
# bad scene, --version, -t without OpenMP, and the progress line's ETA.
./ray -s 16x8 -n 3 -d 2 -t 1 --accel kd -o "$TMP/spaced.ppm" scenes/whitted.sph \
  && ./ray -s16x8 -n3 -d2 -t1 --accel=kd -o"$TMP/attached.ppm" scenes/whitted.sph \
  && cmp -s "$TMP/spaced.ppm" "$TMP/attached.ppm" && ok "-s16x8 -n3 -d2 -t1 --accel=kd -oFILE: as with spaces" \
  || bad "attached option values"
./ray --accel octree -o "$TMP/o.ppm" scenes/whitted.sph 2> "$TMP/err"; rc=$?
[ $rc = 2 ] && grep -q "kd.*bvh.*grid.*none.*auto.*not octree" "$TMP/err" && ok "--accel octree: exit 2, $(cat "$TMP/err")" \
  || bad "--accel octree: exit $rc, $(cat "$TMP/err")"
printf '%s\n' '0 6 .5  1 1 1  .9 .05 .2 .85 0 1.7' > "$TMP/s.sph"
for args in "--bogus" "-n 0" "-n x" "-n" "-s 0x10" "-s axb" "-s" "-d 65" "-t 0" "--accel" "--accel=" \
            "--accelx" "-o $TMP/x.gif" "$TMP/s.sph"; do
  ./ray -o "$TMP/u.ppm" $args "$TMP/s.sph" > /dev/null 2> "$TMP/err"; rc=$?
  [ $rc = 2 ] && [ -s "$TMP/err" ] && [ ! -e "$TMP/u.ppm" ] || { bad "usage error ${args//$TMP\//}: exit $rc"; continue; }
  ok "usage error ${args//$TMP\//}: exit 2, $(head -1 "$TMP/err" | sed "s|$TMP/||g")"
done
./ray > /dev/null 2>&1; [ $? = 2 ] && ok "no scene: exit 2" || bad "no scene: exit $?"
printf 'sphre 1\n' > "$TMP/bad.sph"
for scene in "$TMP/bad.sph" "$TMP/none.sph"; do
  ./ray -o "$TMP/u.ppm" "$scene" 2> /dev/null; rc=$?
  [ $rc = 1 ] && ok "bad input file ${scene#$TMP/}: exit 1" || bad "bad input file ${scene#$TMP/}: exit $rc"
done
./ray --version > "$TMP/out.txt"; rc=$?
[ $rc = 0 ] && grep -qE "^ray [0-9]+\.[0-9]+" "$TMP/out.txt" && ok "--version: $(cat "$TMP/out.txt")" \
  || bad "--version: exit $rc, $(cat "$TMP/out.txt")"
# -t without OpenMP: one warning however often -t is given; with it, none.
if $CC -std=c99 -O0 -o "$TMP/ray_serial" ray.c $RAY_SOURCES -lm 2> "$TMP/err"; then
  "$TMP/ray_serial" -t 2 -t 3 -s 4x4 -o "$TMP/t.ppm" scenes/whitted.sph 2> "$TMP/err"
  [ "$(grep -c "warning: -t 3 is ignored" "$TMP/err")" = 1 ] && [ "$(wc -l < "$TMP/err")" = 1 ] \
    && ok "-t without OpenMP warns once: $(cat "$TMP/err")" || bad "-t without OpenMP: $(cat "$TMP/err")"
else
  bad "ray.c builds without OpenMP: $(head -3 "$TMP/err")"
fi
./ray -t 2 -s 4x4 -o "$TMP/t.ppm" scenes/whitted.sph 2> "$TMP/err"
if ./ray --version | grep -q OpenMP; then
  [ ! -s "$TMP/err" ] && ok "-t with OpenMP: no warning" || bad "-t with OpenMP warned: $(cat "$TMP/err")"
fi
# The progress line (only when stderr is a terminal: a pseudo-terminal here).
python3 -c '
import os, pty, subprocess, sys
master, slave = pty.openpty()
p = subprocess.Popen(sys.argv[1:], stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=slave)
os.close(slave)
out = b""
while True:
    try:
        data = os.read(master, 4096)
    except OSError:
        break
    if not data:
        break
    out += data
p.wait()
sys.stdout.write(out.decode("ascii", "replace").replace("\r", "\n"))
' ./ray -s 200x200 -n 2 -o "$TMP/p.ppm" scenes/whitted.sph > "$TMP/tty" 2>&1
# A render of seconds: every ETA is under 10 minutes (m:ss, never h:mm:ss).
grep -qE "^ray: +[0-9]+%  ETA [0-9]+:[0-9][0-9]" "$TMP/tty" && ! grep ETA "$TMP/tty" | grep -qvE "ETA [0-9]:[0-9][0-9] *$" \
  && ok "the progress line shows an ETA: $(grep ETA "$TMP/tty" | head -1)" \
  || bad "progress line: $(head -3 "$TMP/tty" | tr -cd '[:print:]\n' | tr '\n' '|')"

# --- Readers that say what is really wrong (issue 13, section 4).
# same_image NAME SCENE REFERENCE-SCENE: both render to the same bytes.
same_image() {
  ./ray -s 24x16 -o "$TMP/a.ppm" "$2" 2> "$TMP/err" && ./ray -s 24x16 -o "$TMP/b.ppm" "$3" 2>> "$TMP/err" \
    && cmp -s "$TMP/a.ppm" "$TMP/b.ppm" && ok "$1" || bad "$1: $(head -2 "$TMP/err" | sed "s|$TMP/||g")"
}
# refused NAME SCENE PATTERN: exit 1, PATTERN in the message, no image.
refused() {
  rm -f "$TMP/r.ppm"
  ./ray -o "$TMP/r.ppm" "$2" 2> "$TMP/err"; rc=$?
  [ $rc = 1 ] && grep -qE "$3" "$TMP/err" && [ ! -e "$TMP/r.ppm" ] && ok "$1: $(head -1 "$TMP/err" | sed "s|$TMP/||g")" \
    || bad "$1: exit $rc, $(head -1 "$TMP/err" | sed "s|$TMP/||g")"
}
mkdir "$TMP/in"; cp scenes/mesh.sph scenes/ball.obj scenes/demo.nff "$TMP/in/"
{ printf '\357\273\277'; cat scenes/whitted.sph; } > "$TMP/in/bom.sph"
same_image "a UTF-8 byte order mark before a sphere file is skipped" "$TMP/in/bom.sph" scenes/whitted.sph
{ printf '\357\273\277'; cat scenes/demo.nff; } > "$TMP/in/bom.nff"
same_image "a byte order mark before an NFF file is skipped" "$TMP/in/bom.nff" scenes/demo.nff
{ printf '\357\273\277'; grep -v '^#' scenes/ball.obj; } > "$TMP/in/ball.obj"   # a v first
same_image "a byte order mark before an OBJ file is skipped" "$TMP/in/mesh.sph" scenes/mesh.sph
cp scenes/demo.nff "$TMP/in/DEMO.NFF"
same_image "DEMO.NFF (upper case) is read as NFF" "$TMP/in/DEMO.NFF" scenes/demo.nff
tr '\n' '\r' < scenes/whitted.sph > "$TMP/in/cr.sph"
same_image "CR line ends (old Mac) in a sphere file" "$TMP/in/cr.sph" scenes/whitted.sph
tr '\n' '\r' < scenes/demo.nff > "$TMP/in/cr.nff"
same_image "CR line ends in an NFF file" "$TMP/in/cr.nff" scenes/demo.nff
tr '\n' '\r' < scenes/ball.obj > "$TMP/in/ball.obj"
same_image "CR line ends in an OBJ file" "$TMP/in/mesh.sph" scenes/mesh.sph
sed 's/$/\r/' scenes/demo.nff > "$TMP/in/crlf.nff"
same_image "CRLF line ends in an NFF file" "$TMP/in/crlf.nff" scenes/demo.nff
printf '# one\r# two\rsphre 1 2 3\r' > "$TMP/in/crline.sph"
refused "an error after CR line ends is on its line" "$TMP/in/crline.sph" "crline.sph:3: unknown keyword: sphre"
printf '# one\r\r\n# three\rq 1\n' > "$TMP/in/crline.nff"
refused "NFF lines count CR, CRLF and LF once each" "$TMP/in/crline.nff" "crline.nff:4: unknown NFF entity: q"
printf 'size 8 8\n0 6 .5 1 1 1 .9 .05 .2 .85 0 1.7\0\n' > "$TMP/in/nul.sph"
refused "a NUL byte in a sphere file" "$TMP/in/nul.sph" "nul.sph:2: NUL byte"
printf 'b 0 0 0\nl 1\0 2 3\n' > "$TMP/in/nul.nff"
refused "a NUL byte in an NFF number" "$TMP/in/nul.nff" "nul.nff:2: NUL byte"
printf '# a\0\n' > "$TMP/in/nulc.nff"
refused "a NUL byte in an NFF comment" "$TMP/in/nulc.nff" "nulc.nff:1: NUL byte"
printf 'v 0 0 0\nv 1 0 0\nv 0 1\0 0\n' > "$TMP/in/nul.obj"
printf 'mesh nul.obj 1 1 1 1 0 0 0 1\n' > "$TMP/in/nulobj.sph"
refused "a NUL byte in an OBJ file" "$TMP/in/nulobj.sph" "nul.obj:3: NUL byte"
printf 'mesh . 1 1 1 1 0 0 0 1\n' > "$TMP/in/dir.sph"
refused "mesh . (a directory)" "$TMP/in/dir.sph" "dir.sph:1: mesh is not a plain file \(a directory, device or pipe\): .*/in/\.$"
mkfifo "$TMP/in/fifo.obj"; printf 'mesh fifo.obj 1 1 1 1 0 0 0 1\n' > "$TMP/in/fifo.sph"
timeout 10 ./ray -o "$TMP/r.ppm" "$TMP/in/fifo.sph" 2> "$TMP/err"; rc=$?
[ $rc = 1 ] && grep -q "fifo.sph:1: mesh is not a plain file" "$TMP/err" \
  && ok "mesh naming a pipe, which would wait for ever: $(sed "s|$TMP/||g" "$TMP/err")" \
  || bad "mesh naming a pipe: exit $rc (124: it waited), $(sed "s|$TMP/||g" "$TMP/err")"
refused "a directory as the scene" "$TMP/in" "in: read error: Is a directory"
# "-" as the scene: standard input, the sphere format or (first statement
# "v") NFF, from a pipe; meshes relative to the working directory; the
# image by default stdin.ppm; messages name "stdin".
cat scenes/whitted.sph | ./ray -s 24x16 -o "$TMP/a.ppm" - 2>"$TMP/err" && ./ray -s 24x16 -o "$TMP/b.ppm" scenes/whitted.sph \
  && cmp -s "$TMP/a.ppm" "$TMP/b.ppm" && ok "- reads a sphere-format scene from a pipe: the same bytes" \
  || bad "- with a sphere scene: $(head -2 "$TMP/err")"
cat scenes/demo.nff | ./ray -s 24x16 -o "$TMP/a.ppm" - 2>"$TMP/err" && ./ray -s 24x16 -o "$TMP/b.ppm" scenes/demo.nff \
  && cmp -s "$TMP/a.ppm" "$TMP/b.ppm" && ok "- reads an NFF scene from a pipe: the same bytes" \
  || bad "- with an NFF scene: $(head -2 "$TMP/err")"
(cd scenes && ../ray -s 24x16 -o "$TMP/a.ppm" - < mesh.sph) 2>"$TMP/err" && ./ray -s 24x16 -o "$TMP/b.ppm" scenes/mesh.sph \
  && cmp -s "$TMP/a.ppm" "$TMP/b.ppm" && ok "- : a mesh is found relative to the working directory" \
  || bad "- with a mesh: $(head -2 "$TMP/err")"
mkdir "$TMP/cwd"
(cd "$TMP/cwd" && printf 'size 8 8\n0 0 -5 1 1 1 1 1 0 0 0 1\n' | "$OLDPWD/ray" -) 2>"$TMP/err" && [ -s "$TMP/cwd/stdin.ppm" ] \
  && ok "- without -o writes stdin.ppm" || bad "- without -o: $(ls "$TMP/cwd") $(head -2 "$TMP/err")"
printf 'size 8 8\nbogus 1\n' | ./ray -o "$TMP/r.ppm" - 2>"$TMP/err"; rc=$?
[ $rc = 1 ] && grep -q '^stdin:2: unknown keyword: bogus' "$TMP/err" && [ ! -e "$TMP/r.ppm" ] \
  && ok "- : a message names stdin and the line: $(head -1 "$TMP/err")" || bad "- with a bad line: exit $rc, $(cat "$TMP/err")"
# A mesh path with blanks or '#' in double quotes; an open quote is refused.
mkdir "$TMP/in/my models"; cp scenes/ball.obj "$TMP/in/my models/ball #1.obj"
sed 's|^mesh ball.obj|mesh "my models/ball #1.obj"|' scenes/mesh.sph > "$TMP/in/quoted.sph"
grep -q '^mesh "my models' "$TMP/in/quoted.sph" \
  && same_image 'mesh "my models/ball #1.obj": a quoted path keeps its blank and #' "$TMP/in/quoted.sph" scenes/mesh.sph \
  || bad "quoted.sph was not made"
printf 'mesh "my models/ball.obj 1 1 1 1 0 0 0 1\n' > "$TMP/in/open.sph"
refused "a quote left open" "$TMP/in/open.sph" '^.*open.sph:1: a quote is left open'
printf 'size 8 8\n\001\377\033[31m 1 2 3\n' > "$TMP/in/bin.sph"
refused "raw bytes in a message are escaped" "$TMP/in/bin.sph" 'bin.sph:2: unknown keyword: \\x01\\xFF\\x1B\[31m'
LC_ALL=C grep -q '[^[:print:]]' "$TMP/err" && bad "the message above has raw bytes" || ok "the message has no raw byte"
printf 'b 0 0 0\n\351t\351 1\n' > "$TMP/in/bin.nff"
refused "raw bytes in an NFF message are escaped" "$TMP/in/bin.nff" 'bin.nff:2: unknown NFF entity: \\xE9t\\xE9'
sed 's/^s -1.5 0 1 1$/s -1.5 0 1 -1/; s/^c 1.5 0.5 0 0.8 1.5 0.5 2 0.2$/c 1.5 0.5 0 -0.8 1.5 0.5 2 -0.2/' \
  scenes/demo.nff > "$TMP/in/neg.nff"
grep -q "^s .* -1$" "$TMP/in/neg.nff" && grep -q "^c .* -0.2$" "$TMP/in/neg.nff" \
  && same_image "NFF's negative radii (inside visible) are read as |r|: a sphere, a cone" "$TMP/in/neg.nff" scenes/demo.nff \
  || bad "neg.nff was not made"

# The range of the maths: a light or an eye so far out that squared
# distances overflow, a field of view so narrow that the image plane's does;
# up vectors and views of any length otherwise work.
ball='0 0 0  1 1 1  1  1 0 0 0 1
light 0 -10 3  1 1 1
background .2 .3 .4'
printf 'camera 0 -5 0 0 0 0 0 0 1 40\nlight 0 -1e154 0 1 1 1\n%s\n' "$ball" > "$TMP/in/far.sph"
refused "a light at 1e154" "$TMP/in/far.sph" "far.sph:2: light too far out: beyond 3.9e\+153, its squared distance to the scene overflows"
for at in 3.8e153 1000; do
  printf 'camera 0 -5 0 0 0 0 0 0 1 40\nlight 0 -%s 0 1 1 1\n0 0 0 1 1 1 1 1 0 0 0 1\n' $at > "$TMP/in/light$at.sph"
done
./ray -s 24x16 -o "$TMP/a.ppm" "$TMP/in/light3.8e153.sph" && ./ray -s 24x16 -o "$TMP/b.ppm" "$TMP/in/light1000.sph" \
  && tools/ppmdiff -t 1 "$TMP/a.ppm" "$TMP/b.ppm" > "$TMP/diff" 2>&1 \
  && ok "a light at 3.8e153 lights the ball as one at 1000 does (within a level: parallax)" \
  || bad "a light at 3.8e153: $(cat "$TMP/diff")"
printf 'b 0 0 0\nl 0 0 5e153\n' > "$TMP/in/far.nff"
refused "an NFF light at 5e153" "$TMP/in/far.nff" "far.nff:2: light too far out"
# Objects too large for the arithmetic are refused as lights are, not lost;
# those just within the bounds are seen (a triangle of legs 2e76, a sphere
# round the eye of radius 3e153, a cone of 1e150).
seen() {  # seen NAME SCENE: renders, and some pixel is not black
  ./ray -s 16x16 -o "$TMP/seen.ppm" "$2" 2>"$TMP/err" && python3 -c 'import sys; d=open(sys.argv[1],"rb").read(); sys.exit(0 if max(d[15:]) > 0 else 1)' "$TMP/seen.ppm" \
    && ok "$1" || bad "$1: $(head -1 "$TMP/err" | sed "s|$TMP/||g")"
}
tri_at() { printf 'camera 0 0 -3e%s 0 0 0 0 1 0 40\nlight 0 0 -3e%s 1 1 1\ntri -1e%s -1e%s 0 1e%s -1e%s 0 0 1e%s 0 1 1 1 1 0 0 0 1\n' $1 $1 $1 $1 $1 $1 $1; }
tri_at 76 > "$TMP/in/tri76.sph"; seen "a triangle of legs 2e76 is seen" "$TMP/in/tri76.sph"
tri_at 77 > "$TMP/in/tri77.sph"
refused "a triangle at 1e77" "$TMP/in/tri77.sph" "tri77.sph:3: vertex too far out: beyond 1e\+76"
{ printf 'camera 0 0 -5 0 0 0 0 1 0 40\nlight 0 0 -5 1 1 1\nmesh big.obj 1 1 1 1 0 0 0 1\n'; } > "$TMP/in/bigmesh.sph"
printf 'v 0 0 0\nv 1 0 0\nv 0 2e77 0\nf 1 2 3\n' > "$TMP/in/big.obj"
refused "an OBJ vertex at 2e77" "$TMP/in/bigmesh.sph" "big.obj:3: vertex too far out"
printf 'v\nfrom 0 0 -5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 1\nresolution 8 8\nl 0 0 -5\nf 1 1 1 1 0 0 0 1\np 3\n0 0 0\n1 0 0\n0 -3e80 0\n' > "$TMP/in/bigp.nff"
refused "an NFF polygon's corner at 3e80" "$TMP/in/bigp.nff" "bigp.nff:13: vertex too far out"
printf 'camera 0 0 0 0 0 1 0 1 0 40\nbackground .1 .1 .1\n0 0 0 1 1 1 1e154 1 0 0 0 1\n' > "$TMP/in/bigball.sph"
refused "a sphere of radius 1e154" "$TMP/in/bigball.sph" "bigball.sph:3: object too far out or too large: beyond 3.9e\+153"
printf 'camera 0 0 0 0 0 1 0 1 0 40\nlight 0 0 0 1 1 1\n0 0 0 1 1 1 3e153 1 0 0 0 1\n' > "$TMP/in/ball3.sph"
seen "a sphere round the eye of radius 3e153 is seen" "$TMP/in/ball3.sph"
printf 'camera 0 0 -3e150 0 0 0 0 1 0 40\nlight 0 0 -3e150 1 1 1\ncone 0 -1e150 0 1e150 0 1e150 0 5e149 1 1 1 1 0 0 0 1\n' > "$TMP/in/cone150.sph"
seen "a cone of 1e150 is seen" "$TMP/in/cone150.sph"
sed 's/1e150 0 1e150 0 5e149/1e150 0 4e153 0 5e149/' "$TMP/in/cone150.sph" > "$TMP/in/cone153.sph"
refused "a cone's end at 4e153" "$TMP/in/cone153.sph" "cone153.sph:3: object too far out or too large"
printf 'camera 0 -1e308 0 0 0 0 0 0 1 40\n%s\n' "$ball" > "$TMP/in/eye.sph"
refused "an eye at 1e308" "$TMP/in/eye.sph" "eye.sph:1: camera too far out: beyond 3.9e\+153"
printf 'camera 0 -5 0 0 0 0 0 0 1 1e-152\n%s\n' "$ball" > "$TMP/in/fov.sph"
refused "a field of view of 1e-152 degrees" "$TMP/in/fov.sph" "fov.sph:1: field of view too narrow: under 2.8e-148 degrees"
printf 'camera 0 -5 0 0 0 0 0 0 1 40\n%s\n' "$ball" > "$TMP/in/up1.sph"
for up in "0 0 1e300" "0 0 1e-300" "0 0 3e-320"; do
  printf 'camera 0 -5 0 0 0 0 %s 40\n%s\n' "$up" "$ball" > "$TMP/in/up.sph"
  same_image "camera up ($up) is a direction of any length" "$TMP/in/up.sph" "$TMP/in/up1.sph"
done
printf 'camera 0 0 0 0 1e-200 0 0 0 1 40\n0 5 0 1 1 1 1 1 0 0 0 1\nlight 0 -10 0 1 1 1\n' > "$TMP/in/near.sph"
printf 'camera 0 0 0 0 1 0 0 0 1 40\n0 5 0 1 1 1 1 1 0 0 0 1\nlight 0 -10 0 1 1 1\n' > "$TMP/in/unit.sph"
same_image "an eye 1e-200 from the point it looks at sees as one 1 away" "$TMP/in/near.sph" "$TMP/in/unit.sph"

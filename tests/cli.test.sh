# The command line and bad input: every error is "file:line: message", a
# non-zero exit, and no image file (nor its .tmp) left behind.
. tests/lib.sh
good='0 6 .5  1 1 1  .9 .05 .2 .85 0 1.7'
# bad_scene NAME PATTERN CONTENT: the scene CONTENT must fail with PATTERN.
bad_scene() {
  local name=$1 pat=$2
  printf '%b' "$3" > "$TMP/s.sph"
  rm -f "$TMP/out.ppm"
  ./ray -o "$TMP/out.ppm" "$TMP/s.sph" 2> "$TMP/err"; rc=$?
  if [ $rc -ne 0 ] && grep -qE "^$TMP/s.sph:[0-9]+: $pat" "$TMP/err" && ! ls "$TMP"/out.ppm* >/dev/null 2>&1; then
    ok "$name: $(head -1 "$TMP/err" | sed "s|$TMP/||")"
  else
    bad "$name: exit $rc, said: $(head -1 "$TMP/err")"
  fi
}
bad_scene "wrong number of fields" "a sphere needs 12 numbers, found 11" "$good\n1 2 3 1 1 1 1 0 0 0 0\n"
bad_scene "text that is not a number" "not a number: 0\.5x" "# c\n0 6 0.5x 1 1 1 .9 .05 .2 .85 0 1.7\n"
bad_scene "NaN" "number must be finite: nan" "0 6 nan 1 1 1 .9 .05 .2 .85 0 1.7\n"
bad_scene "inf" "number must be finite: inf" "0 6 1 1 1 1 inf .05 .2 .85 0 1.7\n"
bad_scene "huge number overflows to inf" "number must be finite: 1e999" "0 6 1 1 1 1 1e999 .05 .2 .85 0 1.7\n"
bad_scene "negative radius" "sphere radius must be positive: -0\.9" "$good\n0 6 .5 1 1 1 -0.9 .05 .2 .85 0 1.7\n"
bad_scene "absurd image size" "image size must be" "size 100000 100000\n$good\n"
bad_scene "zero image size" "image size must be" "size 0 32\n$good\n"
bad_scene "fractional image size" "image size must be" "size 32.5 32\n$good\n"
bad_scene "unknown keyword" "unknown keyword: sphre" "sphre 1 2 3\n"
bad_scene "keyword with too few numbers" "camera needs 10 numbers, found 3" "camera 0 0 0\n"
bad_scene "hither with a bad form" "expected \`hither D\`, \`hither D plane\` or \`hither D sphere\`" "hither 1 cone\n"
bad_scene "camera looking at its eye" "camera looks at its own eye" "camera 1 1 1 1 1 1 0 0 1 40\n"
bad_scene "error on the right line" "" "# one\n\n$good\n$good x\n"
grep -q ":4: " "$TMP/err" && ok "the line number counts comments and blank lines" || bad "wrong line number: $(cat "$TMP/err")"

rm -f "$TMP/out.ppm"
./ray -o "$TMP/out.ppm" "$TMP/missing.sph" 2> "$TMP/err"; rc=$?
[ $rc -ne 0 ] && grep -qE "^$TMP/missing.sph: cannot open scene: No such file" "$TMP/err" && [ ! -e "$TMP/out.ppm" ] \
  && ok "missing file: $(sed "s|$TMP/||" "$TMP/err")" || bad "missing file: exit $rc, said: $(cat "$TMP/err")"

printf '%s\n' "$good" > "$TMP/s.sph"
for args in "-s 0x10" "-s 40000x10" "-s 10" "-s axb" "-n 0" "-n x" "-d -1" "-t 0" "--bogus"; do
  ./ray $args -o "$TMP/out.ppm" "$TMP/s.sph" 2> "$TMP/err"; rc=$?
  [ $rc -ne 0 ] && [ -s "$TMP/err" ] && [ ! -e "$TMP/out.ppm" ] && ok "bad option $args: $(head -1 "$TMP/err")" \
    || bad "bad option $args: exit $rc"
done
./ray -o "$TMP/no/such/dir/out.ppm" "$TMP/s.sph" 2> "$TMP/err"; rc=$?
[ $rc -ne 0 ] && grep -q "cannot write" "$TMP/err" && ok "unwritable output: $(head -1 "$TMP/err" | sed "s|$TMP/||")" \
  || bad "unwritable output: exit $rc"
./ray --help | grep -q "usage: ray" && ok "--help prints usage" || bad "--help"
./ray 2> /dev/null; [ $? -eq 2 ] && ok "no scene: usage and exit 2" || bad "no scene"

# Output forms: P6 by default, P3 on request, stdout with -o -, default name.
./ray -s 7x5 -o "$TMP/a.ppm" scenes/minray.sph && [ "$(head -c 11 "$TMP/a.ppm")" = "$(printf 'P6\n7 5\n255')" ] \
  && [ "$(wc -c < "$TMP/a.ppm")" = $((11 + 7 * 5 * 3)) ] && ok "P6 header and size" || bad "P6 output"
./ray --p3 -s 7x5 -o - scenes/minray.sph | head -1 | grep -qx P3 && ok "--p3 to stdout" || bad "--p3 to stdout"
(cd "$TMP" && "$OLDPWD/ray" -s 4x4 "$OLDPWD/scenes/minray.sph") && [ -s "$TMP/minray.ppm" ] \
  && ok "default output name is the scene's base name" || bad "default output name"
./ray -s 8x8 --stats -o "$TMP/a.ppm" scenes/minray.sph 2> "$TMP/err"
grep -q "^rays .*primary.*shadow.*reflected.*refracted" "$TMP/err" && grep -q "^time " "$TMP/err" \
  && ok "--stats prints rays by kind and time" || bad "--stats: $(cat "$TMP/err")"
# No NaN: a scene whose glass has index 1 and sits at the eye still gives bytes.
printf 'camera 0 0 0 0 1 0 0 0 1 60\n0 0 0 1 1 1 1 0 .5 .5 0 1\nlight 0 -5 5 1 1 1\n' > "$TMP/in.sph"
./ray -s 16x16 -o "$TMP/in.ppm" "$TMP/in.sph" && ok "eye inside a sphere renders" || bad "eye inside a sphere"

# NFF and OBJ readers: errors as file:line: message.
bad_nff() {
  local name=$1 pat=$2
  printf '%b' "$3" > "$TMP/s.nff"
  rm -f "$TMP/out.ppm"
  ./ray -o "$TMP/out.ppm" "$TMP/s.nff" 2> "$TMP/err"; rc=$?
  if [ $rc -ne 0 ] && grep -qE "^$TMP/s.nff:[0-9]+: $pat" "$TMP/err" && [ ! -e "$TMP/out.ppm" ]; then
    ok "NFF $name: $(head -1 "$TMP/err" | sed "s|$TMP/||")"
  else
    bad "NFF $name: exit $rc, said: $(head -1 "$TMP/err")"
  fi
}
view='v\nfrom 0 -5 0\nat 0 0 0\nup 0 0 1\nangle 45\nhither 1\nresolution 8 8\n'
bad_nff "unknown entity" "unknown NFF entity: q" "$view""q 1 2 3\n"
bad_nff "not a number" "not a number: x" "$view""s 0 0 x 1\n"
bad_nff "file ends inside a polygon" "the file ends inside: a polygon" "$view""p 4\n0 0 0\n1 0 0\n1 1 0\n"
bad_nff "polygon of 2 corners" "a polygon needs from 3 to 1000000 corners" "$view""p 2\n0 0 0\n1 0 0\n"
bad_nff "zero sphere radius" "sphere radius must not be 0" "$view""s 0 0 0 0\n"
bad_nff "bad view keyword" "expected from, at, up" "v\nfrom 0 0 0\nlook 1 2 3\n"
bad_nff "error on the right line" "" "$view""# comment\n\ns 0 0 0 1\ns 0 0 nan 1\n"
grep -q "s.nff:11: " "$TMP/err" && ok "NFF line numbers count comments and blank lines" || bad "NFF line: $(cat "$TMP/err")"

printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n' > "$TMP/bad.obj"
printf 'mesh bad.obj 1 1 1 1 0 0 0 1\n' > "$TMP/m.sph"
./ray -o "$TMP/out.ppm" "$TMP/m.sph" 2> "$TMP/err"; rc=$?
[ $rc -ne 0 ] && grep -qE "^$TMP/bad.obj:4: vertex index out of range: 4" "$TMP/err" && [ ! -e "$TMP/out.ppm" ] \
  && ok "OBJ index out of range: $(sed "s|$TMP/||" "$TMP/err")" || bad "OBJ index error: exit $rc, $(cat "$TMP/err")"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 zz\n' > "$TMP/bad.obj"
./ray -o "$TMP/out.ppm" "$TMP/m.sph" 2> "$TMP/err"; rc=$?
[ $rc -ne 0 ] && grep -qE "^$TMP/bad.obj:3: not a number: zz" "$TMP/err" \
  && ok "OBJ not a number: $(sed "s|$TMP/||" "$TMP/err")" || bad "OBJ number error: exit $rc, $(cat "$TMP/err")"
printf 'mesh nosuch.obj 1 1 1 1 0 0 0 1\n' > "$TMP/m.sph"
./ray -o "$TMP/out.ppm" "$TMP/m.sph" 2> "$TMP/err"; rc=$?
[ $rc -ne 0 ] && grep -qE "^$TMP/m.sph:1: cannot open mesh" "$TMP/err" \
  && ok "missing OBJ named at the scene's line: $(sed "s|$TMP/||" "$TMP/err")" || bad "missing OBJ: exit $rc, $(cat "$TMP/err")"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\ng x\nf 1 2 3\n' > "$TMP/ok.obj"
printf 'camera 0 0 -3 0 0 0 0 1 0 40\nlight 0 0 -5 1 1 1\nmesh ok.obj 1 1 1 1 0 0 0 1\n' > "$TMP/m.sph"
./ray -s 8x8 -o "$TMP/out.ppm" "$TMP/m.sph" 2> "$TMP/err"; rc=$?
[ $rc -eq 0 ] && [ "$(grep -c warning "$TMP/err")" = 1 ] && [ -s "$TMP/out.ppm" ] \
  && ok "OBJ: other statements get one warning, not a failure" || bad "OBJ warning: exit $rc, $(cat "$TMP/err")"

# Output that is not a plain file is written in place, never renamed over.
ln -s "$TMP/target.ppm" "$TMP/link.ppm"
./ray -s 4x4 -o "$TMP/link.ppm" scenes/minray.sph
[ -L "$TMP/link.ppm" ] && [ -s "$TMP/target.ppm" ] && ok "-o through a symbolic link keeps the link" \
  || bad "-o replaced a symbolic link"
mkfifo "$TMP/fifo"
cat "$TMP/fifo" > "$TMP/from_fifo" &
./ray -s 4x4 -o "$TMP/fifo" scenes/minray.sph; wait
[ -p "$TMP/fifo" ] && [ "$(head -c 2 "$TMP/from_fifo")" = P6 ] && ok "-o into a pipe writes through it" \
  || bad "-o into a pipe"
# A bad -o fails before the render, not after it (this render would take minutes).
start=$(date +%s)
./ray -s 8000x8000 -n 64 -o "$TMP/no/such/dir/x.ppm" scenes/whitted.sph 2>/dev/null; rc=$?
[ $rc -ne 0 ] && [ $(( $(date +%s) - start )) -lt 5 ] && ok "an unwritable -o fails at once" || bad "unwritable -o: exit $rc"

# Nested glass at the largest depth: rays double at each level without the
# weight cut-off (Hall and Greenberg); with it this takes milliseconds.
printf 'camera 0 0 0 0 1 0 0 0 1 40\n0 4 0  1 1 1 1  0 .5 .5 0 1.5\n0 4 0  1 1 1 .5 0 .5 .5 0 1.5\nlight 0 0 5 1 1 1\n' > "$TMP/nested.sph"
start=$(date +%s)
./ray -s 32x32 -d 64 -o "$TMP/n.ppm" "$TMP/nested.sph"; rc=$?
[ $rc -eq 0 ] && [ $(( $(date +%s) - start )) -lt 10 ] && ok "nested glass at depth 64 finishes" || bad "nested glass at depth 64: exit $rc"

# Weights that make light out of nothing: ks = kt = 1 in two nested balls
# finishes at depth 64 (each primary ray's tree stops at its budget, and
# --stats counts what was cut), with one warning naming the file and line.
printf 'camera 0 0 0 0 1 0 0 0 1 40\n0 4 0  1 1 1 1  0 1 1 0 1.3\n0 4 0  1 1 1 .5 0 1 1 0 1.3\nlight 0 0 5 1 1 1\n' > "$TMP/both.sph"
./ray -s 8x8 -d 64 --stats -o "$TMP/b.ppm" "$TMP/both.sph" 2>"$TMP/err"; rc=$?
[ $rc -eq 0 ] && [ "$(grep -c "both.sph:2: warning: ks + kt = 2 exceeds 1" "$TMP/err")" = 1 ] \
  && grep -q "^budget .* not traced" "$TMP/err" \
  && ok "ks + kt = 2 at depth 64: bounded by the ray budget, counted, one file:line warning" \
  || bad "ks + kt = 2: exit $rc, $(head -c 300 "$TMP/err")"

# The acceleration structure: --accel, or the scene's `accel` line; the
# option wins.  Every structure gives the same picture.
bad_scene "unknown structure" "expected \`accel\` and one of kd, bvh, grid, none, auto" "accel octree\n$good\n"
for a in kd bvh grid none; do
  ./ray -s 24x24 --stats --accel $a -o "$TMP/acc_$a.ppm" scenes/whitted.sph 2> "$TMP/acc_$a.err" || bad "--accel $a"
done
cmp -s "$TMP/acc_kd.ppm" "$TMP/acc_bvh.ppm" && cmp -s "$TMP/acc_kd.ppm" "$TMP/acc_grid.ppm" \
  && cmp -s "$TMP/acc_kd.ppm" "$TMP/acc_none.ppm" && ok "--accel kd, bvh, grid and none: the same picture" \
  || bad "--accel kd, bvh, grid and none give different pictures"
printf 'accel grid\n%s\n%s\n%s\n' "$good" "$good" "$good" > "$TMP/g.sph"
./ray -s 8x8 --stats -o "$TMP/g.ppm" "$TMP/g.sph" 2>&1 | grep -q '^grid ' && ok "scene line accel grid: the grid answers" \
  || bad "scene line accel grid ignored"
./ray -s 8x8 --stats --accel bvh -o "$TMP/g.ppm" "$TMP/g.sph" 2>&1 | grep -q '^bvh ' && ok "--accel bvh overrides the scene's accel line" \
  || bad "--accel does not override the scene's accel line"

# --view: the centre ray's work on the fixed scale (11 spheres through the
# loop: 11 tests, heat 11 = 0.44 of blue = byte 112), the normal as colour
# (a ball straight ahead: n = (0, -1, 0), colour (0.5, 0, 0.5) = 128 0 128),
# and a usage error for another name.
{ echo "camera 0 -5 0  0 0 0  0 0 1 30"
  for k in 0 1 2 3 4 5 6 7 8 9; do echo "$((k * 3 - 13)) 20 0  1 1 1  .5  1 0 0 0 1"; done
  echo "0 0 0  1 1 1  1  1 0 0 0 1"; } > "$TMP/view.sph"
./ray -s 9x9 --view steps --accel none -o "$TMP/steps.ppm" "$TMP/view.sph" 2>/dev/null &&
./ray -s 9x9 --view normal -o "$TMP/normal.ppm" "$TMP/view.sph" 2>/dev/null &&
python3 -c "
import sys
def px(p, i, j):
    d = open(p, 'rb').read(); h = d.split(b'\n', 3); w = int(h[1].split()[0]); k = 3 * (j * w + i)
    return tuple(h[3][k:k + 3])
assert px('$TMP/steps.ppm', 4, 4) == (0, 0, 112), px('$TMP/steps.ppm', 4, 4)
assert px('$TMP/normal.ppm', 4, 4) == (128, 0, 128), px('$TMP/normal.ppm', 4, 4)
" && ok "--view steps: 11 tests through the loop on the fixed scale; --view normal: the normal as colour" \
  || bad "--view steps or normal"
./ray --view heat -o "$TMP/h.ppm" "$TMP/view.sph" 2>"$TMP/err"; rc=$?
[ $rc = 2 ] && grep -q "steps, normal, depth, samples or photons" "$TMP/err" && ok "--view heat: exit 2, the choices listed" \
  || bad "--view heat: exit $rc"

# Numbers whose products overflow: refused with their file:line (the fuzz
# targets found NaN pixels from each: a colour of 1e308, an index of 3.3e16).
printf '0 0 0  1e308 1 1  1  0 0 1 1 1.5\n' > "$TMP/huge.sph"
./ray -s 4x4 -o "$TMP/h.ppm" "$TMP/huge.sph" 2>"$TMP/err"; rc=$?
[ $rc = 1 ] && grep -q "huge.sph:1: colours and weights must lie within 1e30" "$TMP/err" \
  && ok "a colour of 1e308 is refused at its line" || bad "colour 1e308: exit $rc, $(cat "$TMP/err")"
printf 'v\nfrom 0 -5 0\nat 0 0 0\nup 0 0 1\nangle 40\nhither 1\nresolution 8 8\nf 1 1 1 0 0 0 1 3.3e16\ns 0 0 0 1\n' > "$TMP/ior.nff"
./ray -s 4x4 -o "$TMP/i.ppm" "$TMP/ior.nff" 2>"$TMP/err"; rc=$?
[ $rc = 1 ] && grep -q "ior.nff:8: index of refraction must be between 1e-6 and 1e6" "$TMP/err" \
  && ok "an index of refraction of 3.3e16 is refused at its line" || bad "index 3.3e16: exit $rc, $(cat "$TMP/err")"

# The option text has one copy, cli.c's usage(): the README shows it as
# --help prints it (the block after "./ray --help` prints the options").
awk '/`\.\/ray --help` prints the options/ { f = 1; next } f && /^```$/ { if (in_block) exit; in_block = 1; next } in_block' README.md >"$TMP/readme_help"
./ray --help >"$TMP/help"
if [ -s "$TMP/readme_help" ] && cmp -s "$TMP/help" "$TMP/readme_help"; then
  ok "the README shows ./ray --help as it prints"
else
  bad "the README's option text differs from ./ray --help: $(diff "$TMP/help" "$TMP/readme_help" | head -5 | tr '\n' ' ')"
fi
./ray --version | grep -q "Whitted's ray tracer and Kajiya's path tracer" && ok "--version names both renderers" \
  || bad "--version: $(./ray --version)"
./ray --help | grep -q -- "--version" && ok "--help lists --version" || bad "--help does not list --version"
./ray --seed 0 -s 4x4 --pt -o "$TMP/s0.ppm" scenes/cornell.sph 2>/dev/null && ./ray -s 4x4 --pt -o "$TMP/sd.ppm" scenes/cornell.sph 2>/dev/null \
  && cmp -s "$TMP/s0.ppm" "$TMP/sd.ppm" && ok "--seed 0 is taken, and is the default noise" || bad "--seed 0 refused, or not the default"
./ray --no-roulette --pt -s 4x4 -o "$TMP/nr.ppm" scenes/cornell.sph 2>/dev/null; rc=$?
[ "$rc" = 2 ] && ok "--no-roulette without -d is a usage error (exit 2)" || bad "--no-roulette without -d exits $rc, not 2"
./ray -s 8x8 --stats=kv -o "$TMP/kv.ppm" scenes/whitted.sph 2>"$TMP/kv"
./ray -s 8x8 --stats -o "$TMP/kv.ppm" scenes/whitted.sph 2>"$TMP/prose"
if [ "$(awk '$1 == "rays" { print $2 }' "$TMP/kv")" = "$(sed -n 's/^rays *\([0-9]*\):.*/\1/p' "$TMP/prose")" ] \
   && [ "$(awk '$1 == "hits" { print $2 }' "$TMP/kv")" = "$(awk '$1 == "hits" { print $2 }' "$TMP/prose")" ] \
   && awk 'NF != 2 { bad = 1 } END { exit bad }' "$TMP/kv"; then
  ok "--stats=kv: one key and one value a line, the rays and hits of --stats"
else
  bad "--stats=kv: $(head -3 "$TMP/kv" | tr '\n' ' ')"
fi
./ray --view steps -s 8x8 --stats=kv -o "$TMP/v.ppm" scenes/whitted.sph 2>&1 | grep -q '^rays 64$' \
  && ok "--view counts its rays (64 for 8x8)" || bad "--view with --stats counts no rays"
./ray -s 8x8 --stats -o "$TMP/c.ppm" scenes/cornell.sph 2>&1 | grep -q '0 point lights, 2 glowing' \
  && ok "--stats: the Cornell box has 0 point lights and 2 glowing triangles" || bad "--stats scene line on the Cornell box"

# A picture that will be wrong says why, at file:line: negative colours,
# weights, light colours, background and ambient are refused (a light of
# colour -5 would take light away; a PFM would hold negative radiance).
neg() {  # $1 file's text, $2 message
  printf '%s\n' "$1" > "$TMP/neg.sph"
  ./ray -s 4x4 -o "$TMP/neg.pfm" "$TMP/neg.sph" 2>"$TMP/err"; rc=$?
  if [ $rc = 1 ] && grep -q "neg.sph:1: $2" "$TMP/err" && [ ! -e "$TMP/neg.pfm" ]; then
    ok "refused at its line: $1"
  else
    bad "not refused as '$2': $1 (exit $rc, $(cat "$TMP/err"))"
  fi
}
neg '0 0 0  1 -1 1  1  1 0 0 0 1' "colours and weights must lie within 1e30 and be 0 or more"
neg '0 0 0  1 1 1  1  1 0 0 -2 1' "colours and weights must lie within 1e30 and be 0 or more"
neg 'tri 0 0 0  1 0 0  0 1 0  1 1 1  -.5 0 0 0 1' "colours and weights must lie within 1e30 and be 0 or more"
neg 'light 0 0 0  1 -5 1' "a light's colour must lie within 1e30 and be 0 or more"
neg 'background -1 0 0' "background must lie within 1e30 and be 0 or more"
neg 'background 1e300 1e300 1e300' "background must lie within 1e30 and be 0 or more"
neg 'ambient 0 0 -.1' "ambient must lie within 1e30 and be 0 or more"
printf 'v\nfrom 0 -5 0\nat 0 0 0\nup 0 0 1\nangle 40\nhither 1\nresolution 8 8\nb -1 0 0\n' > "$TMP/neg.nff"
./ray -s 4x4 -o "$TMP/neg.pfm" "$TMP/neg.nff" 2>"$TMP/err"; rc=$?
[ $rc = 1 ] && grep -q "neg.nff:8: background must lie within 1e30 and be 0 or more" "$TMP/err" \
  && ok "NFF: a negative background is refused at its line" || bad "NFF negative background: exit $rc, $(cat "$TMP/err")"

# Warnings, once each, naming the file: an albedo above 1; a picture that
# will be black; a light buried in a ball; the path tracer's options given
# to Whitted's renderer.
printf '0 0 0  5 1 1  1  1 0 0 0 1\nlight 0 -5 0  1 1 1\n' > "$TMP/w.sph"
./ray --pt -s 4x4 -o "$TMP/w.ppm" "$TMP/w.sph" 2>"$TMP/err"; rc=$?
[ $rc = 0 ] && [ "$(grep -c "w.sph:1: warning: kd times the colour = 5 exceeds 1" "$TMP/err")" = 1 ] \
  && ok "an albedo of 5: one warning at its line, and the render goes on" || bad "albedo 5: exit $rc, $(cat "$TMP/err")"
printf 'camera 0 -5 0  0 0 0  0 0 1  40\n0 0 0  1 1 1  1  1 0 0 0 1\n' > "$TMP/dark.sph"
./ray --pt -s 4x4 -o "$TMP/w.ppm" "$TMP/dark.sph" 2>"$TMP/err"
[ "$(grep -c "dark.sph: warning: nothing in it gives light" "$TMP/err")" = 1 ] \
  && ok "a path-traced scene with no light and a black background: warned, black" || bad "no light, --pt: $(cat "$TMP/err")"
./ray -s 4x4 -o "$TMP/w.ppm" "$TMP/dark.sph" 2>"$TMP/err"
[ "$(grep -c "dark.sph: warning: no light reaches its surfaces" "$TMP/err")" = 1 ] \
  && ok "a Whitted scene with no light and no ambient: warned" || bad "no light, Whitted: $(cat "$TMP/err")"
./ray -s 4x4 -o "$TMP/w.ppm" scenes/cornell.sph --whitted 2>"$TMP/err"
! grep -q "warning: no light" "$TMP/err" && ok "the Cornell box in Whitted's renderer: lit by its lamp, no warning" \
  || bad "Cornell, Whitted: $(cat "$TMP/err")"
# A light inside an opaque ball the eye is outside of is warned about; not
# one inside a glass ball, nor one in a room made of a sphere's inside.
printf 'camera 0 -5 0  0 0 0  0 0 1  40\nlight 0 0 0  1 1 1\n0 0 0  1 1 1  1  1 0 0 0 1\n' > "$TMP/buried.sph"
./ray -s 4x4 -o "$TMP/w.ppm" "$TMP/buried.sph" 2>"$TMP/err"
[ "$(grep -c "buried.sph: warning: the light at (0 0 0) lies inside an opaque sphere" "$TMP/err")" = 1 ] \
  && ok "a light inside an opaque ball: warned, naming the file" || bad "light in a ball: $(cat "$TMP/err")"
sed 's/1  1 0 0 0 1$/1  0 .1 .9 0 1.5/' "$TMP/buried.sph" > "$TMP/glass.sph"
sed 's/1  1 0 0 0 1$/50  1 0 0 0 1/' "$TMP/buried.sph" > "$TMP/room.sph"
./ray -s 4x4 -o "$TMP/w.ppm" "$TMP/glass.sph" 2>"$TMP/err"; ./ray -s 4x4 -o "$TMP/w.ppm" "$TMP/room.sph" 2>>"$TMP/err"
grep -q "1.5$" "$TMP/glass.sph" && grep -q " 50 " "$TMP/room.sph" && ! grep -q "opaque sphere" "$TMP/err" \
  && ok "a light inside a glass ball, or in a room with the eye: no warning" || bad "glass or room: $(cat "$TMP/err")"
./ray --estimator nee -s 4x4 -o "$TMP/w.ppm" scenes/whitted.sph 2>"$TMP/err"
[ "$(grep -c "warning: --estimator is the path tracer's" "$TMP/err")" = 1 ] \
  && ok "--estimator given to Whitted's renderer: warned" || bad "--estimator, Whitted: $(cat "$TMP/err")"
./ray --seed 3 -s 4x4 -o "$TMP/w.ppm" scenes/whitted.sph 2>"$TMP/err"
./ray --seed 3 -s 4x4 -o "$TMP/w.ppm" scenes/soft.sph 2>>"$TMP/err"
[ "$(grep -c "warning: --seed changes nothing here" "$TMP/err")" = 1 ] \
  && ok "--seed to Whitted's renderer: warned where it draws no numbers, not where its area light does" \
  || bad "--seed, Whitted: $(cat "$TMP/err")"
# Messages that point the right way: commas between numbers; which path a
# mesh line tried.
printf '0, 0, 0  1 1 1  1  1 0 0 0 1\n' > "$TMP/comma.sph"
./ray -s 4x4 -o "$TMP/c.ppm" "$TMP/comma.sph" 2>"$TMP/err"; rc=$?
[ $rc = 1 ] && grep -q "comma.sph:1: numbers are parted by blanks, not commas: 0," "$TMP/err" \
  && ok "commas between numbers: said so at the line" || bad "commas: exit $rc, $(cat "$TMP/err")"
printf 'mesh nowhere.obj  .9 .5 .2   .7 .3 0 0 1\n' > "$TMP/nomesh.sph"
./ray -s 4x4 -o "$TMP/c.ppm" "$TMP/nomesh.sph" 2>"$TMP/err"; rc=$?
[ $rc = 1 ] && grep -q "nomesh.sph:1: cannot open mesh: $TMP/nowhere.obj (No such file or directory)" "$TMP/err" \
  && ok "a mesh that cannot be opened: the path tried, and why" || bad "missing mesh: exit $rc, $(cat "$TMP/err")"
# An OBJ file as the scene: framed by a camera on its box, lit, said once.
./ray -s 24x24 -o "$TMP/obj.pfm" scenes/ball.obj 2>"$TMP/err"; rc=$?
if [ $rc = 0 ] && [ "$(grep -c "ball.obj: an OBJ mesh alone" "$TMP/err")" = 1 ] && python3 -c "
import struct, sys
d = open('$TMP/obj.pfm', 'rb').read(); h = d.split(b'\n', 3); w, hh = map(int, h[1].split())
v = struct.unpack('<%df' % (3 * w * hh), h[3][:12 * w * hh])
lit = sum(1 for x in v[0::3] if x > 0.2)
sys.exit(0 if lit > w * hh // 4 and v[0] < 0.05 else 1)   # the mesh fills the middle, lit; a corner is dark
"; then ok "./ray mesh.obj: the mesh framed and lit, said in one line"
else bad "./ray ball.obj: exit $rc, $(cat "$TMP/err")"; fi

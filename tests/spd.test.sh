#!/usr/bin/env bash
# tools/spd: our generators of Haines' Standard Procedural Databases.
# Always: it builds silently, its command line, the entity counts the SPD's
# headers give for each database, and ./ray reading each generated scene.
# With ../shared/spd (the SPD's own output, $SPD to move it): every file there
# against the generator at the same size; byte for byte or, failing that,
# number for number within the printed 6 digits (a compiler that fuses
# multiply-adds may round a last digit the other way) for the deterministic
# databases; for mount, whose random numbers are our own, the same entities,
# the same bounding box within 0.1, and eye-ray hits within the SPD's 10%.
cd "$(dirname "$0")/.." || exit 2
. tests/lib.sh
REF=${SPD:-../shared/spd}

# shellcheck disable=SC2086 # CFLAGS holds several words, as in make
if ! $CC $CFLAGS -o "$TMP/spd" tools/spd.c -lm 2>"$TMP/cc.err"; then
  bad "spd builds with $CC $CFLAGS"; sed 's/^/    /' "$TMP/cc.err"; exit 1
fi
ok "spd builds with $CC $CFLAGS"
# Silent under strict warnings with every compiler here (tcc: it builds).
for c in gcc clang tcc; do
  command -v $c >/dev/null || { skip "tools/spd.c under $c: $c is not installed"; continue; }
  flags="-std=c99 -pedantic -Wall -Wextra"; [ $c = tcc ] && flags=""
  # shellcheck disable=SC2086 # flags holds several words
  if $c $flags -c tools/spd.c -o "$TMP/spd.o" 2>"$TMP/w.err" && [ ! -s "$TMP/w.err" ]; then
    ok "spd.c compiles silently with $c ${flags:-(default flags)}"
  else
    bad "spd.c under $c $flags: $(head -3 "$TMP/w.err")"
  fi
done
S=$TMP/spd

# The command line.
out=$("$S" --help 2>&1); rc=$?
if [ $rc = 0 ] && printf '%s' "$out" | grep -q '^usage:' &&
   [ "$(printf '%s\n' "$out" | grep -cE '^  (balls|gears|mount|rings|teapot|tetra|tree) ')" = 7 ]; then
  ok "--help exits 0 and lists the seven databases"
else
  bad "--help (exit $rc): $out"
fi
"$S" balls 2 >"$TMP/a.nff"; "$S" balls -s 2 >"$TMP/b.nff"
check "'spd balls 2' and 'spd balls -s 2' write the same scene" cmp "$TMP/a.nff" "$TMP/b.nff"
for args in "" "bogus" "balls 0" "balls 9" "balls 2x" "balls -s" "tree 3 4"; do
  # shellcheck disable=SC2086 # the words are the arguments
  out=$("$S" $args 2>&1 >/dev/null); rc=$?
  if [ $rc = 2 ] && [ -n "$out" ]; then ok "'spd${args:+ $args}' is a usage error (exit 2)"
  else bad "'spd${args:+ $args}': exit $rc, want 2 and a message: $out"; fi
done

# count FILE: "spheres cones polygons patches lights" of an NFF file.
count() {
  awk '$1=="s"{s++} $1=="c"{c++} $1=="p"{p++} $1=="pp"{pp++} $1=="l"{l++}
       END{printf "%d %d %d %d %d", s, c, p, pp, l}' "$1"
}

# Each database at its default size: the counts of the SPD's headers, and a
# picture from ./ray.
while read -r db size want; do
  if ! "$S" "$db" >"$TMP/$db.nff" 2>"$TMP/err"; then
    bad "spd $db: exit status $(cat "$TMP/err")"; continue
  fi
  got=$(count "$TMP/$db.nff")
  if [ "$got" = "$want" ]; then ok "spd $db (size $size): spheres cones polygons patches lights = $got"
  else bad "spd $db (size $size): spheres cones polygons patches lights = $got, want $want"; fi
  if ./ray -s 32x32 -o "$TMP/$db.ppm" "$TMP/$db.nff" 2>"$TMP/err"; then ok "./ray reads spd $db"
  else bad "./ray reads spd $db: $(head -3 "$TMP/err")"; fi
done <<'COUNTS'
balls 4 7381 0 1 0 3
gears 4 0 0 9345 0 5
mount 6 4 0 8192 0 1
rings 7 4200 4200 1 0 3
teapot 6 0 0 36 2256 2
tetra 6 0 0 4096 0 1
tree 11 4095 4095 1 0 7
COUNTS

if [ ! -d "$REF" ]; then
  skip "spd: the generators against the SPD's own files: $REF is absent (it lies outside the repository)"
  exit 0
fi

# same A B: every token of A equals B's, or both are numbers that differ by at
# most one unit in the 6th significant digit (1e-5 relative; 1e-12 absolute
# for the rounding noise the SPD prints for zero, e.g. -2.55836e-17).  Prints
# the first difference.
same() {
  paste -d' ' <(tr -s ' \t\r\n' '\n' <"$1") <(tr -s ' \t\r\n' '\n' <"$2") | awk '
    function abs(x) { return x < 0 ? -x : x }
    NF != 2 { print "token " NR ": one file ends first"; bad = 1; exit }
    $1 == $2 { next }
    $1 ~ /^[-+.0-9eE]+$/ && $2 ~ /^[-+.0-9eE]+$/ {
      a = $1 + 0; b = $2 + 0; m = abs(a) > abs(b) ? abs(a) : abs(b)
      if (abs(a - b) <= 1e-5 * m + 1e-12) { near++; next }
    }
    { print "token " NR ": " $1 " vs " $2; bad = 1; exit }
    END { if (!bad) print near + 0 " tokens differ in the last digit"; exit bad }'
}

for ref in "$REF"/*.nff; do
  name=$(basename "$ref" .nff); db=${name%_s*}; size=${name##*_s}
  if ! "$S" "$db" "$size" >"$TMP/$name.nff" 2>"$TMP/err"; then
    bad "$name: spd $db $size failed: $(cat "$TMP/err")"; continue
  fi
  if [ "$db" != mount ]; then
    if cmp -s "$ref" "$TMP/$name.nff"; then
      ok "$name: byte-identical to $ref"
    elif res=$(same "$ref" "$TMP/$name.nff"); then
      ok "$name: equal to $ref within the printed precision ($res)"
    else
      bad "$name: differs from $ref: $res"
    fi
    continue
  fi
  # mount: the same entities and materials, the spheres exactly, the box.
  a=$(count "$ref"); b=$(count "$TMP/$name.nff")
  if [ "$a" = "$b" ]; then ok "$name: the same entities as $ref ($a)"
  else bad "$name: entities $b, $ref has $a"; fi
  if diff <(grep -E '^[bvlfs] |^(from|at|up|angle|hither|resolution) ' "$ref") \
          <(grep -E '^[bvlfs] |^(from|at|up|angle|hither|resolution) ' "$TMP/$name.nff") >/dev/null; then
    ok "$name: view, lights, materials and spheres as in $ref"
  else
    bad "$name: view, lights, materials or spheres differ from $ref"
  fi
  box() {
    awk '$1=="p"{n=$2; next} n>0 {for (i=1;i<=3;i++) { if (!k||$i<lo[i]) lo[i]=$i; if (!k||$i>hi[i]) hi[i]=$i }
         k=1; n--} END{printf "%g %g %g %g %g %g", lo[1], hi[1], lo[2], hi[2], lo[3], hi[3]}' "$1"
  }
  a=$(box "$ref"); b=$(box "$TMP/$name.nff")
  if awk -v a="$a" -v b="$b" 'BEGIN{split(a,x," "); split(b,y," ");
       for (i=1;i<=6;i++) if ((x[i]-y[i])^2 > 0.01) exit 1}'; then
    ok "$name: the mountain's box (x, y, z ranges) $b is $ref's $a within 0.1"
  else
    bad "$name: the mountain's box $b, $ref's is $a (more than 0.1 apart)"
  fi
  # eye rays that hit something, at depth 1 (primary rays only)
  hits() { ./ray -s 128x128 -d 1 -t 1 --stats -o "$TMP/h.ppm" "$1" 2>&1 | awk '/^hits/{print $2}'; }
  a=$(hits "$ref"); b=$(hits "$TMP/$name.nff")
  if [ -n "$a" ] && [ -n "$b" ] && awk -v a="$a" -v b="$b" 'BEGIN{exit !((b-a)^2 <= (0.1*a)^2)}'; then
    ok "$name: eye rays that hit, 128x128: $b against $ref's $a (within the SPD's 10%)"
  else
    bad "$name: eye rays that hit, 128x128: '$b' against $ref's '$a' (want within 10%)"
  fi
done
exit 0

# Split renders (--crop, --tile, --samples; ray --merge; --checkpoint and
# --resume): the parts of any split merge to the bytes of one whole run,
# in both renderers, on 1 and 2 threads, with --adaptive too; parts that do
# not belong together are refused, with a message and a non-zero exit; an
# interrupted render, resumed, equals one that ran through.
. tests/lib.sh

# whole OUT SCENE OPTIONS...: one run of everything; merged OUT PARTS...
whole() { out=$1; shift; ./ray "$@" -o "$out" 2>/dev/null; }
merged() { out=$1; shift; ./ray --merge "$out" "$@" 2>"$TMP/merge.err"; }

# same NAME A B: A and B the same bytes.
same() {
  if cmp -s "$2" "$3"; then ok "$1"; else bad "$1 ($(tools/ppmdiff "$2" "$3" 2>&1 | head -1))"; fi
}

W="scenes/whitted.sph -s 60x45 -n 5"
P="scenes/cornell.sph --pt -s 40x30 -n 12"
D="scenes/soft.sph -s 40x30 -n 6"             # Whitted's area light: random numbers by sample

for r in W P D; do
  eval "set -- \$$r"
  scene=$1; shift
  whole "$TMP/$r.ppm" "$scene" "$@" -t 1
  whole "$TMP/$r.pfm" "$scene" "$@" -t 2

  # crops of four different shapes, on 1 and 2 threads
  ./ray "$scene" "$@" -t 1 --crop 0,0,17,11 -o "$TMP/c0.part" 2>/dev/null
  ./ray "$scene" "$@" -t 2 --crop 17,0,40,11 -o "$TMP/c1.part" 2>/dev/null
  ./ray "$scene" "$@" -t 2 --crop 0,11,9,30 -o "$TMP/c2.part" 2>/dev/null
  ./ray "$scene" "$@" -t 1 --crop 9,11,40,30 -o "$TMP/c3.part" 2>/dev/null
  w=$(sed -n 2p "$TMP/c0.part" | cut -d' ' -f2)
  if [ "$w" = 40 ]; then
    merged "$TMP/m.pfm" "$TMP"/c[0-3].part
    same "$r: four crops merge to the whole run's PFM, byte for byte ($scene $*)" "$TMP/m.pfm" "$TMP/$r.pfm"
  fi

  # tiles: bands of rows
  for i in 0 1 2; do ./ray "$scene" "$@" -t 2 --tile $i/3 -o "$TMP/t$r$i.part" 2>/dev/null; done
  merged "$TMP/m.ppm" "$TMP/t${r}2.part" "$TMP/t${r}0.part" "$TMP/t${r}1.part"
  same "$r: --tile 0/3, 1/3, 2/3, merged in another order, give the whole run's bytes" "$TMP/m.ppm" "$TMP/$r.ppm"

  # samples, and samples with crops: 3 pieces of samples, the last in two crops
  n=$(printf '%s\n' "$@" | sed -n '/^-n$/{n;p}')
  ./ray "$scene" "$@" -t 1 --samples 0:2 -o "$TMP/s${r}0.part" 2>/dev/null
  ./ray "$scene" "$@" -t 2 --samples 2:3 -o "$TMP/s${r}1.part" 2>/dev/null
  ./ray "$scene" "$@" -t 2 --samples 3:$n --tile 0/2 -o "$TMP/s${r}2.part" 2>/dev/null
  ./ray "$scene" "$@" -t 1 --samples 3:$n --tile 1/2 -o "$TMP/s${r}3.part" 2>/dev/null
  merged "$TMP/m.pfm" "$TMP"/s$r[0-3].part
  same "$r: samples 0:2, 2:3 and 3:$n (in two tiles) merge to the whole run's PFM" "$TMP/m.pfm" "$TMP/$r.pfm"
  merged "$TMP/m.ppm" "$TMP"/s$r[0-3].part
  same "$r: ... and to its PPM" "$TMP/m.ppm" "$TMP/$r.ppm"
done

# A crop written as a picture of its own: the whole image's rectangle, noise
# and all, in both renderers.
for r in "scenes/cornell.sph --pt -n 6" "scenes/soft.sph -n 6"; do
  ./ray $r -s 40x30 -o "$TMP/full.pfm" 2>/dev/null
  ./ray $r -s 40x30 --crop 7,5,31,22 -o "$TMP/crop.pfm" 2>/dev/null
  python3 - "$TMP/full.pfm" "$TMP/crop.pfm" <<'EOF' && ok "$r: --crop 7,5,31,22 -o x.pfm is the whole image's rectangle, float for float" || bad "$r: --crop's picture is not the whole image's rectangle"
import sys
def pfm(name):
    d = open(name, 'rb').read()
    head = d.split(b'\n', 3)
    w, h = map(int, head[1].split())
    rows = [head[3][12 * w * y:12 * w * (y + 1)] for y in range(h)][::-1]   # PFM: bottom row first
    return w, h, rows
fw, fh, full = pfm(sys.argv[1])
cw, ch, crop = pfm(sys.argv[2])
want = [row[12 * 7:12 * 31] for row in full[5:22]]
sys.exit(0 if (cw, ch) == (24, 17) and crop == want else 1)
EOF
done

# The sums themselves: a pixel of 2 samples is the mean of its two
# one-sample images (--samples 0:1, 1:2), by python's own arithmetic, to
# within a float's rounding.
for r in "scenes/cornell.sph --pt" "scenes/whitted.sph"; do
  ./ray $r -s 40x30 -n 2 -o "$TMP/n2.pfm" 2>/dev/null
  ./ray $r -s 40x30 -n 2 --samples 0:1 -o "$TMP/k0.pfm" 2>/dev/null
  ./ray $r -s 40x30 -n 2 --samples 1:2 -o "$TMP/k1.pfm" 2>/dev/null
  worst=$(python3 - "$TMP/n2.pfm" "$TMP/k0.pfm" "$TMP/k1.pfm" <<'EOF'
import sys, struct
def pfm(name):
    d = open(name, 'rb').read()
    head = d.split(b'\n', 3)
    w, h = map(int, head[1].split())
    return struct.unpack('<%df' % (3 * w * h), head[3][:12 * w * h])
n2, a, b = map(pfm, sys.argv[1:])
print('%.3g' % max(abs(x - (y + z) / 2) / max(1e-30, abs(x), 2 ** -60) for x, y, z in zip(n2, a, b)))
EOF
)
  awk -v w="$worst" 'BEGIN { exit !(w != "" && w + 0 <= 2.4e-7) }' \
    && ok "$r -n 2: each pixel is the mean of its samples 0:1 and 1:2 (worst relative difference $worst; two floats' rounding allow 2.4e-7)" \
    || bad "$r -n 2: a pixel is not the mean of its two samples (worst relative difference '$worst')"
done

# --adaptive: each pixel's rounds are its own, Whitted's neighbours across
# a crop's edge included; the same bytes as one adaptive run.  edge.sph: a
# grey wall, dark left of the line between columns 16 and 17, where the
# crops below are cut: pixels 16 and 17, flat, take 8 samples, not 4, only
# because their neighbour across the cut disagrees.
printf 'size 40 30\ncamera 0 0 -10 0 0 0 0 1 0 90\nambient 1 1 1\n' > "$TMP/edge.sph"
for t in "-100 -100 0  1.5 -100 0  1.5 100 0  .2 .2 .2" "-100 -100 0  1.5 100 0  -100 100 0  .2 .2 .2" \
         "1.5 -100 0  100 -100 0  100 100 0  .8 .8 .8" "1.5 -100 0  100 100 0  1.5 100 0  .8 .8 .8"; do
  echo "tri $t  1 0 0 0 1" >> "$TMP/edge.sph"
done
for r in "$TMP/edge.sph -n 32 --adaptive 2" "scenes/whitted.sph -s 40x30 -n 32 --adaptive 2" \
         "scenes/cornell.sph --pt -s 40x30 -n 64 --adaptive 4"; do
  set -- $r
  scene=$1; shift
  whole "$TMP/a.ppm" "$scene" "$@"
  for i in 0 1 2 3; do ./ray "$scene" "$@" --tile $i/4 -o "$TMP/a$i.part" 2>/dev/null; done
  merged "$TMP/m.ppm" "$TMP"/a[0-3].part
  same "--adaptive, in 4 tiles: the whole adaptive run's bytes ($scene $*)" "$TMP/m.ppm" "$TMP/a.ppm"
  k=0 taken=0
  for c in 0,0,17,15 17,0,40,15 0,15,17,30 17,15,40,30; do   # quarters: cut across rows and columns
    ./ray "$scene" "$@" --crop $c --stats=kv -o "$TMP/q$k.part" 2>"$TMP/kv"; k=$((k + 1))
    taken=$((taken + $(sed -n 's/^samples_taken //p' "$TMP/kv")))
  done
  ./ray "$scene" "$@" --stats=kv -o "$TMP/x.ppm" 2>"$TMP/kv"
  all=$(sed -n 's/^samples_taken //p' "$TMP/kv")
  [ "$taken" = "$all" ] && ok "--adaptive, in 4 crops: every pixel takes the samples it takes in one run ($taken in all)" \
    || bad "--adaptive, in 4 crops: $taken samples taken, one run takes $all ($scene $*)"
  whole "$TMP/a.pfm" "$scene" "$@"
  merged "$TMP/m.pfm" "$TMP"/q[0-3].part
  same "--adaptive, in 4 crops: the whole adaptive run's PFM ($scene $*)" "$TMP/m.pfm" "$TMP/a.pfm"
done
./ray scenes/cornell.sph --pt -s 8x8 -n 64 --adaptive 4 --samples 16:64 -o "$TMP/x.part" 2>"$TMP/err"
[ $? = 2 ] && grep -q "must start at 0" "$TMP/err" && [ ! -e "$TMP/x.part" ] \
  && ok "--adaptive with --samples 16:64 is refused: a pixel's rounds depend on its samples before ($(cat "$TMP/err"))" \
  || bad "--adaptive --samples 16:64: $(cat "$TMP/err")"

# Output formats: a merge writes any of them, the bytes of the whole run's.
for f in png exr; do
  whole "$TMP/w.$f" scenes/cornell.sph --pt -s 40x30 -n 12
  merged "$TMP/m.$f" "$TMP"/tP[0-2].part
  same "the tiles merged into .$f: the whole run's $f" "$TMP/m.$f" "$TMP/w.$f"
done

# Refusals: parts that do not belong together, each named, exit 1, no file.
refused() {   # NAME WORDS PARTS...: merged must fail, say WORDS, and write nothing
  what=$1 words=$2; shift 2
  rm -f "$TMP/r.ppm"
  merged "$TMP/r.ppm" "$@"
  st=$?
  if [ $st = 1 ] && grep -q "$words" "$TMP/merge.err" && [ ! -e "$TMP/r.ppm" ]; then
    ok "refused: $what ($(head -1 "$TMP/merge.err"))"
  else
    bad "not refused as it should be: $what (exit $st: $(head -1 "$TMP/merge.err"))"
  fi
}
./ray scenes/cornell.sph --pt -s 40x30 -n 12 --seed 1 --tile 1/3 -o "$TMP/seed.part" 2>/dev/null
./ray scenes/cornell.sph --pt -s 40x30 -n 13 --tile 1/3 -o "$TMP/spp.part" 2>/dev/null
./ray scenes/cornell.sph --pt -s 40x31 -n 12 --tile 1/3 -o "$TMP/size.part" 2>/dev/null
./ray scenes/cornell.sph --pt -s 40x30 -n 12 --estimator nee --tile 1/3 -o "$TMP/est.part" 2>/dev/null
sed '0,/^tri /{/^tri /s/0.7508/0.7507/}' scenes/cornell.sph > "$TMP/other.sph"   # the floor's blue
cmp -s "$TMP/other.sph" scenes/cornell.sph && bad "the edited scene is the same as cornell.sph"
./ray "$TMP/other.sph" --pt -s 40x30 -n 12 --tile 1/3 -o "$TMP/scene.part" 2>/dev/null
python3 - "$TMP/tP1.part" "$TMP/version.part" <<'EOF'
import sys
d = open(sys.argv[1], 'rb').read()
open(sys.argv[2], 'wb').write(d.replace(b'version ray ', b'version ray 0.', 1))
EOF
refused "another seed" "seed" "$TMP/tP0.part" "$TMP/seed.part" "$TMP/tP2.part"
refused "another sample count" "of 13 samples" "$TMP/tP0.part" "$TMP/spp.part" "$TMP/tP2.part"
refused "another image size" "40x31" "$TMP/tP0.part" "$TMP/size.part" "$TMP/tP2.part"
refused "another estimator" "estimator" "$TMP/tP0.part" "$TMP/est.part" "$TMP/tP2.part"
refused "another scene (one colour changed)" "scene" "$TMP/tP0.part" "$TMP/scene.part" "$TMP/tP2.part"
refused "another version of the program" "version" "$TMP/tP0.part" "$TMP/version.part" "$TMP/tP2.part"
refused "two parts that overlap" "overlap" "$TMP/tP0.part" "$TMP/tP1.part" "$TMP/tP1.part" "$TMP/tP2.part"
refused "a hole: a tile missing, its pixels named" "lack samples, within crop 0,10,40,20" "$TMP/tP0.part" "$TMP/tP2.part"
refused "a hole: samples missing, named" "lacks samples 2:3 of 12" "$TMP/sP0.part" "$TMP/sP2.part" "$TMP/sP3.part"
head -c 300 "$TMP/tP1.part" > "$TMP/short.part"
refused "a part cut short" "truncated" "$TMP/tP0.part" "$TMP/short.part" "$TMP/tP2.part"
refused "a file that is no part" "not a partial render" "$TMP/tP0.part" scenes/cornell.sph
./ray --merge "$TMP/tP0.part" "$TMP/tP1.part" 2>"$TMP/err"
[ $? = 2 ] && ok "--merge refuses to write a .part ($(cat "$TMP/err"))" || bad "--merge OUT.part: $(cat "$TMP/err")"
cp "$TMP/tP0.part" "$TMP/keep.part"
./ray --merge "$TMP/keep.part" "$TMP/tP1.part" "$TMP/keep.part" 2>"$TMP/err"
st=$?
[ $st = 2 ] && cmp -s "$TMP/keep.part" "$TMP/tP0.part" \
  && ok "--merge refuses an output that is one of its parts ($(cat "$TMP/err"))" || bad "--merge OUT = a part: exit $st"
for bad_opt in "--crop 0,0,41,10" "--tile 3/3" "--tile 0/31" "--samples 0:13" "--samples 4:4" "--crop 5,5,5,9" \
               "--crop 1,2,3" "--tile 1/0" "--crop 0,0,4,4 --tile 0/2"; do
  ./ray scenes/cornell.sph --pt -s 40x30 -n 12 $bad_opt -o "$TMP/x.part" 2>"$TMP/err"
  st=$?
  [ $st = 2 ] && [ -s "$TMP/err" ] && [ ! -e "$TMP/x.part" ] && ok "refused: $bad_opt ($(head -1 "$TMP/err"))" \
    || bad "$bad_opt: exit $st, $(head -1 "$TMP/err")"
done

# Checkpoints.  A render stopped by SIGTERM saves its work in OUT.part,
# leaves no OUT, and ends as the signal ends it; --resume goes on from it
# to the bytes of one run that was never stopped.
C="scenes/cornell.sph --pt -s 48x36 -n 384 -t 1"
whole "$TMP/c.pfm" $C
./ray $C --checkpoint 0.1 -o "$TMP/c2.pfm" 2>"$TMP/err" &
pid=$!
for k in $(seq 100); do [ -e "$TMP/c2.pfm.part" ] && break; sleep 0.05; done
kill -TERM $pid       # at the first checkpoint, a tenth of a second in: rows are left to do
wait $pid 2>/dev/null
st=$?
rows=$(python3 - "$TMP/c2.pfm.part" <<'EOF' 2>/dev/null
import sys, struct
d = open(sys.argv[1], 'rb').read()
body = d[d.index(b'\nend\n') + 5:]
n = [struct.unpack_from('<Q', body, 56 * i)[0] for i in range(len(body) // 56)]
print(sum(1 for r in range(36) if all(n[48 * r + x] for x in range(48))))
EOF
)
[ $st = 143 ] && [ ! -e "$TMP/c2.pfm" ] && [ -n "$rows" ] && [ "$rows" -gt 0 ] && [ "$rows" -lt 36 ] \
  && grep -q "go on with --resume" "$TMP/err" \
  && ok "SIGTERM during a render with --checkpoint: exit 143, no image, $rows of 36 rows saved in OUT.part" \
  || bad "SIGTERM with --checkpoint: exit $st, rows saved '$rows', $(cat "$TMP/err")"
./ray $C -t 2 --resume "$TMP/c2.pfm.part" -o "$TMP/c2.pfm" 2>/dev/null
same "--resume after SIGTERM: the bytes of the render that ran through" "$TMP/c2.pfm" "$TMP/c.pfm"

# SIGHUP (a closed terminal, as Mitsuba saves on) saves too; and a
# checkpoint is written every S seconds while the render goes on, then
# removed when it ends.
./ray $C --checkpoint 1000 -o "$TMP/h.ppm" 2>/dev/null &
pid=$!
sleep 0.3
kill -HUP $pid
wait $pid 2>/dev/null
st=$?
[ $st = 129 ] && [ -s "$TMP/h.ppm.part" ] && [ ! -e "$TMP/h.ppm" ] \
  && ok "SIGHUP with --checkpoint: exit 129, the work saved in OUT.part" || bad "SIGHUP with --checkpoint: exit $st"
./ray $C --checkpoint 0.2 --resume "$TMP/h.ppm.part" -o "$TMP/h.ppm" 2>/dev/null &
pid=$!
seen=0
for k in 1 2 3 4 5 6 7 8 9 10; do
  sleep 0.2
  kill -0 $pid 2>/dev/null || break
  [ "$TMP/h.ppm.part" -nt "$TMP/c2.pfm" ] && seen=1
done
wait $pid
whole "$TMP/c.ppm" $C
[ $seen = 1 ] && [ ! -e "$TMP/h.ppm.part" ] && cmp -s "$TMP/h.ppm" "$TMP/c.ppm" \
  && ok "--checkpoint 0.2: OUT.part rewritten while the render runs, removed at its end; the resumed image is the whole run's" \
  || bad "--checkpoint 0.2: rewritten while running: $seen; left: $(ls "$TMP"/h.ppm* | tr '\n' ' ')"
./ray $C --resume "$TMP/tP1.part" -o "$TMP/x.ppm" 2>"$TMP/err"
[ $? = 1 ] && grep -q "not a part of the render" "$TMP/err" && ok "--resume refuses another render's partial ($(head -1 "$TMP/err"))" \
  || bad "--resume of a foreign part: $(cat "$TMP/err")"


# Photon mapping (--estimator photon).  Its kd-tree (photons.c): the k
# nearest photons are brute force's (tests/test_photons.c); an estimate
# counts the photons on the point's plane that took few enough rays, and
# no others (tests/test_photon_estimate.c).  Its images,
# whose bias is the density estimate's blur: in the furnace (inside a
# glowing sphere of albedo .5 and Le 1.5) the mean is exact at -d 2 (no
# photon counts there) and within 0.2% of Le (1 - a^(N+1)) / (1 - a) at
# -d 4 and of Le / (1 - a) unbounded; on the Cornell box the mean is MIS's
# within 2% (the blur, and the noise of one photon map, which spp does not
# average away: over seeds 1 to 4 it is -1.1% to +0.04%); on the caustic the mean of the spot (the pixels where a
# 512-sample BDPT reference exceeds 2) is too dark, by a bias that falls
# as the photons grow (40,000, 160,000 and 640,000), to below 15%.  The same
# bytes on 1 and 3 threads, and a cropped render is the whole image's
# part (every render shoots the same photons).
#
# Progressive photon mapping (--estimator ppm), whose bias is the blur of
# each pass's disc and falls as the passes shrink it: in the furnace the
# mean is exact at -d 2 and within 0.5% at -d 4 and unbounded (the first
# passes' discs are wide enough to reach off the curved wall's plane, and
# photons there are left out: -0.2% and -0.3% measured); on the Cornell
# box the mean is MIS's within 3% (the blur along the box's edges, -1.2%
# measured); on the caustic the spot's bias falls pass by pass (4, 32 and
# 256 passes of 3,072 photons).  The passes are samples: the same bytes on
# 1 and 3 threads, and two split renders by --samples merge to the whole
# run's bytes.  It refuses --adaptive and --checkpoint.  --view photons:
# the picture, but for the pixels where a photon is seen (blue, yellow
# for the caustic map's), and refused without photon mapping.
. tests/lib.sh
. tests/estimators.sh
relative_mean() {   # image $1's mean over MIS's on the Cornell box, minus 1
  python3 -c "$PFM_PY
a, b = pfm(sys.argv[1]), pfm(sys.argv[2])
print('%.4f' % ((sum(b) - sum(a)) / sum(a)))" "$TMP/mis.pfm" "$1"
}
furnace() {   # label, tolerance, then ray's arguments: the furnace's mean exact at -d 2, within the tolerance at -d 4 and unbounded
  local label=$1 tol=$2 r d
  shift 2
  for r in "2 2.25 0" "4 2.8125 $tol" "0 3 $tol"; do
    set -- $r "$@"
    d=""; [ "$1" != 0 ] && d="-d $1"
    # shellcheck disable=SC2086
    ./ray "$TMP/furnace.sph" -s 32x32 $d "${@:4}" -o "$TMP/f.pfm" 2>/dev/null
    read -r mean z <<<"$(mean_z "$TMP/f.pfm" "$2")"
    awk -v m="$mean" -v w="$2" -v b="$3" 'BEGIN { e = m - w; if (e < 0) e = -e
          exit !(m != "" && (e <= b * w || (b == 0 && e < 1e-6))) }' \
      && ok "the furnace${d:+ at $d}, $label: mean $mean, the exact $2 within $(awk -v b="$3" 'BEGIN { print b ? b * 100 "%" : "1e-6" }')" \
      || bad "the furnace${d:+ at $d}, $label: mean '$mean', not $2 ($z standard errors)"
    shift 3
  done
}
spot_bias() {   # image $1's mean over the caustic's spot (where BDPT's reference exceeds 2) over the reference's, minus 1
  python3 -c "$PFM_PY
a, r = pfm(sys.argv[1]), pfm(sys.argv[2])
spot = [k for k in range(len(r) // 3) if sum(r[3 * k:3 * k + 3]) / 3 > 2]
sa, sr = (sum(sum(i[3 * k:3 * k + 3]) for k in spot) for i in (a, r))
print('%.3f' % ((sa - sr) / sr if spot else 99))" "$1" "$TMP/ref.pfm"
}
# shellcheck disable=SC2086 # CFLAGS holds several words
$CC $CFLAGS -std=c99 -o "$TMP/test_photons" tests/test_photons.c photons.c -lm || { bad "tests/test_photons.c compiles"; exit 1; }
"$TMP/test_photons"
# shellcheck disable=SC2086
$CC $CFLAGS -std=c99 -o "$TMP/test_estimate" tests/test_photon_estimate.c $RAY_PARTS -lm || bad "tests/test_photon_estimate.c compiles"
cat >"$TMP/floor.sph" <<'SCENE'
integrator path
camera 0 5 -5   0 0 0   0 1 0   40
tri -9 0 -9  9 0 9  9 0 -9     .8 .8 .8  .8 0 0 0 1
tri -9 0 -9  -9 0 9  9 0 9     .8 .8 .8  .8 0 0 0 1
0 3 0   1 1 1   .3   0 0 0 5 1
SCENE
"$TMP/test_estimate" "$TMP/floor.sph" || [ $? = 1 ] || bad "tests/test_photon_estimate.c: the floor scene did not load"

furnace "photon mapped" 0.002 -n 16 --estimator photon --photons 100000

./ray scenes/cornell.sph -s 32x32 -n 1024 --seed 3 -o "$TMP/mis.pfm" 2>/dev/null
./ray scenes/cornell.sph -s 32x32 -n 64 --estimator photon -o "$TMP/pm.pfm" 2>/dev/null
rel=$(relative_mean "$TMP/pm.pfm")
awk -v r="$rel" 'BEGIN { exit !(r != "" && r < 0.02 && r > -0.02) }' \
  && ok "cornell.sph, photon mapped (200,000 photons): the mean is MIS's within 2% (${rel} of it)" \
  || bad "cornell.sph, photon mapped: the mean differs from MIS's by '$rel' of it"

./ray scenes/caustic.sph -s 64x48 -n 512 --estimator bdpt --seed 9 -o "$TMP/ref.pfm" 2>/dev/null
biases=""
for n in 40000 160000 640000; do
  ./ray scenes/caustic.sph -s 64x48 -n 16 --estimator photon --photons $n -o "$TMP/c$n.pfm" 2>/dev/null
  biases="$biases $(spot_bias "$TMP/c$n.pfm")"
done
read -r b1 b2 b3 <<<"$biases"
awk -v a="$b1" -v b="$b2" -v c="$b3" 'function abs(x) { return x < 0 ? -x : x }
     BEGIN { exit !(c != "" && abs(c) < abs(b) && abs(b) < abs(a) && abs(c) < 0.15) }' \
  && ok "the caustic, photon mapped: the spot's bias falls as the photons grow ($b1, $b2, $b3 of BDPT's at 40,000, 160,000 and 640,000)" \
  || bad "the caustic, photon mapped: the spot's bias does not fall to below 15%: $b1, $b2, $b3 at 40,000, 160,000 and 640,000 photons"

threads_agree "--estimator photon" scenes/caustic.sph -s 40x30 -n 4 --estimator photon --photons 50000
./ray scenes/caustic.sph -s 40x30 -n 4 --estimator photon --photons 50000 --crop 8,6,24,18 -o "$TMP/crop.pfm" 2>/dev/null
same=$(python3 -c "$PFM_PY
whole, part = pfm(sys.argv[1]), pfm(sys.argv[2])
# PFM rows run from the bottom: the crop's rows 6..17 are the whole's rows 12..23 from the bottom
want = [whole[3 * (y * 40 + x) + c] for y in range(30 - 18, 30 - 6) for x in range(8, 24) for c in range(3)]
print(int(list(part) == want))" "$TMP/t1.pfm" "$TMP/crop.pfm")
[ "$same" = 1 ] && ok "--estimator photon with --crop: the whole image's part, byte for byte" \
  || bad "--estimator photon with --crop differs from the whole image's part"
./ray scenes/cornell.sph -s 8x8 -n 1 --photons 1000 -o "$TMP/r.pfm" 2>"$TMP/err"
grep -q "photons is photon mapping's" "$TMP/err" && ok "--photons without --estimator photon: warned" \
  || bad "--photons without --estimator photon: no warning ($(cat "$TMP/err"))"

furnace "progressive photon mapping" 0.005 -n 64 --estimator ppm

./ray scenes/cornell.sph -s 32x32 -n 256 --estimator ppm -o "$TMP/ppm.pfm" 2>/dev/null
rel=$(relative_mean "$TMP/ppm.pfm")
awk -v r="$rel" 'BEGIN { exit !(r != "" && r < 0.03 && r > -0.03) }' \
  && ok "cornell.sph, progressive photon mapping (256 passes): the mean is MIS's within 3% (${rel} of it)" \
  || bad "cornell.sph, progressive photon mapping: the mean differs from MIS's by '$rel' of it"

biases=""
for n in 4 32 256; do
  ./ray scenes/caustic.sph -s 64x48 -n $n --estimator ppm -o "$TMP/c$n.pfm" 2>/dev/null
  biases="$biases $(spot_bias "$TMP/c$n.pfm")"
done
read -r b1 b2 b3 <<<"$biases"
awk -v a="$b1" -v b="$b2" -v c="$b3" 'function abs(x) { return x < 0 ? -x : x }
     BEGIN { exit !(c != "" && abs(c) < abs(b) - 0.03 && abs(b) < abs(a) - 0.03) }' \
  && ok "the caustic, progressive photon mapping: the spot's bias falls pass by pass ($b1, $b2, $b3 of BDPT's at 4, 32 and 256 passes)" \
  || bad "the caustic, progressive photon mapping: the spot's bias does not fall with the passes: $b1, $b2, $b3 at 4, 32 and 256"

threads_agree "--estimator ppm" scenes/caustic.sph -s 40x30 -n 6 --estimator ppm
./ray scenes/caustic.sph -s 40x30 -n 6 --samples 0:2 --estimator ppm -o "$TMP/a.part" 2>/dev/null
./ray scenes/caustic.sph -s 40x30 -n 6 --samples 2:6 --estimator ppm -o "$TMP/b.part" 2>/dev/null
./ray --merge "$TMP/m.pfm" "$TMP/a.part" "$TMP/b.part" 2>/dev/null
[ -s "$TMP/m.pfm" ] && cmp -s "$TMP/t1.pfm" "$TMP/m.pfm" \
  && ok "--estimator ppm split by --samples 0:2 and 2:6: merged, the whole run's bytes" \
  || bad "--estimator ppm: the passes split by --samples do not merge to the whole run's bytes"

for o in "--adaptive 1" "--checkpoint 5"; do
  # shellcheck disable=SC2086
  ./ray scenes/cornell.sph -s 8x8 -n 4 --estimator ppm $o -o "$TMP/refused.pfm" 2>"$TMP/err"
  code=$?
  [ $code = 2 ] && grep -q "whole passes" "$TMP/err" && [ ! -e "$TMP/refused.pfm" ] \
    && ok "--estimator ppm with $o: refused (exit 2, no image)" \
    || bad "--estimator ppm with $o: exit $code, $(cat "$TMP/err")"
done

# --view photons: the photon-mapped picture, where no photon is seen; the
# global map's blue where one is (the Cornell box has no caustic)
./ray scenes/cornell.sph -s 32x32 -n 2 --estimator photon --photons 3000 -o "$TMP/pic.pfm" 2>/dev/null
./ray scenes/cornell.sph -s 32x32 -n 2 --estimator photon --photons 3000 --view photons -o "$TMP/dots.pfm" 2>/dev/null
read -r dots other <<<"$(python3 -c "$PFM_PY
a, b = pfm(sys.argv[1]), pfm(sys.argv[2])
dot = [0.2, 0.5, 1.0]
n = len(a) // 3
dots = sum(1 for k in range(n) if [round(x, 6) for x in b[3 * k:3 * k + 3]] == dot)
other = sum(1 for k in range(n) if list(b[3 * k:3 * k + 3]) != list(a[3 * k:3 * k + 3])
            and [round(x, 6) for x in b[3 * k:3 * k + 3]] != dot)
print(dots, other)" "$TMP/pic.pfm" "$TMP/dots.pfm")"
[ -n "$dots" ] && [ "$dots" -gt 100 ] && [ "$dots" -lt 1024 ] && [ "$other" = 0 ] \
  && ok "--view photons: $dots of 1024 pixels a photon's blue, the others the picture's" \
  || bad "--view photons: '$dots' pixels blue, '$other' neither blue nor the picture's"
./ray scenes/caustic.sph -s 32x24 -n 1 --estimator photon --photons 20000 --view photons -o "$TMP/cdots.pfm" 2>/dev/null
yellow=$(python3 -c "$PFM_PY
b = pfm(sys.argv[1])
print(sum(1 for k in range(len(b) // 3) if [round(x, 6) for x in b[3 * k:3 * k + 3]] == [1.0, 0.85, 0.2]))" "$TMP/cdots.pfm")
[ -n "$yellow" ] && [ "$yellow" -gt 0 ] && ok "--view photons on the caustic: $yellow pixels a caustic photon's yellow" \
  || bad "--view photons on the caustic: no caustic photon drawn ('$yellow')"
# a plate over a lamp over a floor, seen from above: the photons on the
# plate's underside and on the floor below it are hidden from the eye
cat >"$TMP/plate.sph" <<'SCENE'
integrator path
background 0 0 0
camera 0 10 0   0 0 0   0 0 1   60
tri -20 0 -20  20 0 -20  20 0 20     .8 .8 .8  .8 0 0 0 1
tri -20 0 -20  20 0 20  -20 0 20     .8 .8 .8  .8 0 0 0 1
tri -2 2 -2  2 2 -2  2 2 2     .8 .8 .8  .8 0 0 0 1
tri -2 2 -2  2 2 2  -2 2 2     .8 .8 .8  .8 0 0 0 1
0 1 0   1 1 1   .2   0 0 0 20 1
SCENE
./ray "$TMP/plate.sph" -s 32x32 -n 1 --estimator photon --photons 5000 --view photons -o "$TMP/pl.pfm" 2>/dev/null
read -r all under <<<"$(python3 -c "$PFM_PY
b = pfm(sys.argv[1])
dot = lambda k: [round(x, 6) for x in b[3 * k:3 * k + 3]] == [0.2, 0.5, 1.0]
print(sum(dot(k) for k in range(32 * 32)), sum(dot(32 * j + i) for j in range(11, 21) for i in range(11, 21)))" "$TMP/pl.pfm")"
[ -n "$all" ] && [ "$all" -gt 100 ] && [ "$under" = 0 ] \
  && ok "--view photons: $all photons drawn on the floor, none on the plate that hides the lamp's (its underside's, the floor's below)" \
  || bad "--view photons: '$under' of the plate's 100 pixels show a hidden photon ($all drawn)"
./ray scenes/cornell.sph -s 8x8 -n 1 --view photons -o "$TMP/v.pfm" 2>"$TMP/err"
code=$?
[ $code = 2 ] && grep -q "photon mapping's photons" "$TMP/err" && ok "--view photons without photon mapping: refused (exit 2)" \
  || bad "--view photons without photon mapping: exit $code, $(cat "$TMP/err")"

# Photon mapping (--estimator photon).  Its kd-tree (photons.c): the k
# nearest photons are brute force's (tests/test_photons.c).  Its images,
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
. tests/lib.sh
. tests/estimators.sh
# shellcheck disable=SC2086 # CFLAGS holds several words
$CC $CFLAGS -std=c99 -o "$TMP/test_photons" tests/test_photons.c photons.c -lm || { bad "tests/test_photons.c compiles"; exit 1; }
"$TMP/test_photons"

for r in "2 2.25 0" "4 2.8125 0.002" "0 3 0.002"; do
  set -- $r
  d=""; [ "$1" != 0 ] && d="-d $1"
  # shellcheck disable=SC2086
  ./ray "$TMP/furnace.sph" -s 32x32 -n 16 $d --estimator photon --photons 100000 -o "$TMP/f.pfm" 2>/dev/null
  read -r mean z <<<"$(mean_z "$TMP/f.pfm" "$2")"
  awk -v m="$mean" -v w="$2" -v b="$3" 'BEGIN { e = m - w; if (e < 0) e = -e
        exit !(m != "" && (e <= b * w || (b == 0 && e < 1e-6))) }' \
    && ok "the furnace${d:+ at $d}, photon mapped: mean $mean, the exact $2 within $(awk -v b="$3" 'BEGIN { print b ? b * 100 "%" : "1e-6" }')" \
    || bad "the furnace${d:+ at $d}, photon mapped: mean '$mean', not $2 ($z standard errors)"
done

./ray scenes/cornell.sph -s 32x32 -n 1024 --seed 3 -o "$TMP/mis.pfm" 2>/dev/null
./ray scenes/cornell.sph -s 32x32 -n 64 --estimator photon -o "$TMP/pm.pfm" 2>/dev/null
rel=$(python3 -c "$PFM_PY
a, b = pfm(sys.argv[1]), pfm(sys.argv[2])
print('%.4f' % ((sum(b) - sum(a)) / sum(a)))" "$TMP/mis.pfm" "$TMP/pm.pfm")
awk -v r="$rel" 'BEGIN { exit !(r != "" && r < 0.02 && r > -0.02) }' \
  && ok "cornell.sph, photon mapped (200,000 photons): the mean is MIS's within 2% (${rel} of it)" \
  || bad "cornell.sph, photon mapped: the mean differs from MIS's by '$rel' of it"

./ray scenes/caustic.sph -s 64x48 -n 512 --estimator bdpt --seed 9 -o "$TMP/ref.pfm" 2>/dev/null
biases=""
for n in 40000 160000 640000; do
  ./ray scenes/caustic.sph -s 64x48 -n 16 --estimator photon --photons $n -o "$TMP/c$n.pfm" 2>/dev/null
  biases="$biases $(python3 -c "$PFM_PY
a, r = pfm(sys.argv[1]), pfm(sys.argv[2])
spot = [k for k in range(len(r) // 3) if sum(r[3 * k:3 * k + 3]) / 3 > 2]
sa, sr = (sum(sum(i[3 * k:3 * k + 3]) for k in spot) for i in (a, r))
print('%.3f' % ((sa - sr) / sr if spot else 99))" "$TMP/c$n.pfm" "$TMP/ref.pfm")"
done
read -r b1 b2 b3 <<<"$biases"
awk -v a="$b1" -v b="$b2" -v c="$b3" 'function abs(x) { return x < 0 ? -x : x }
     BEGIN { exit !(c != "" && abs(c) < abs(b) && abs(b) < abs(a) && abs(c) < 0.15) }' \
  && ok "the caustic, photon mapped: the spot's bias falls as the photons grow ($b1, $b2, $b3 of BDPT's at 40,000, 160,000 and 640,000)" \
  || bad "the caustic, photon mapped: the spot's bias does not fall to below 15%: $b1, $b2, $b3 at 40,000, 160,000 and 640,000 photons"

./ray scenes/caustic.sph -s 40x30 -n 4 -t 1 --estimator photon --photons 50000 -o "$TMP/t1.pfm" 2>/dev/null
./ray scenes/caustic.sph -s 40x30 -n 4 -t 3 --estimator photon --photons 50000 -o "$TMP/t3.pfm" 2>/dev/null
[ -s "$TMP/t1.pfm" ] && cmp -s "$TMP/t1.pfm" "$TMP/t3.pfm" \
  && ok "--estimator photon: the same bytes on 1 and 3 threads" || bad "--estimator photon: 1 and 3 threads differ"
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

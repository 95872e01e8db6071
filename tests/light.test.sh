# Triangle lights sampled by solid angle (tests/test_light.c): Arvo's
# sampler meets its triangle, is uniform in solid angle (chi-square),
# estimates Lambert's polygon formula, and its pdf is light_pdf's; the light
# tree (tests/test_light.c, then images below).
. tests/lib.sh
# shellcheck disable=SC2086 # CFLAGS and RAY_PARTS hold several words
$CC $CFLAGS -std=c99 -o "$TMP/test_light" tests/test_light.c $RAY_PARTS -lm || { bad "tests/test_light.c compiles"; exit 1; }
"$TMP/test_light" "$TMP"

# Images: choosing lights down the tree changes the noise, never the mean.
# On scenes/lights100.sph (100 glowing spheres over a floor), per pixel,
# importance minus power averages 0 over the image within 4 standard
# errors (pixels are independent, so the spread of the differences gives
# the error); and the noise (RMSE between two seeds over sqrt 2, over the
# pixels below 1 in all four images: the floor and the balls, not the
# lamps, whose edges are noisy for any light choice) falls to at most half
# of power's.
for c in importance power; do
  for seed in 1 2; do
    ./ray scenes/lights100.sph -s 64x48 -n 16 --light-choice $c --seed $seed -o "$TMP/$c$seed.pfm" 2>/dev/null
  done
done
mean_apart() {   # image $2 minus image $1, per pixel: its mean in standard errors
  python3 -c "$PFM_PY
a, b = pfm(sys.argv[1]), pfm(sys.argv[2])
d = [sum(b[3 * k:3 * k + 3]) - sum(a[3 * k:3 * k + 3]) for k in range(len(a) // 3)]
n = len(d); m = sum(d) / n; v = sum((x - m) ** 2 for x in d) / (n - 1)
print('%.2f' % (m / (v / n) ** 0.5 if v > 0 else 99))" "$1" "$2"
}
z=$(mean_apart "$TMP/power1.pfm" "$TMP/importance2.pfm")
awk -v z="$z" 'BEGIN { exit !(z != "" && z < 4 && z > -4) }' \
  && ok "lights100.sph: --light-choice importance's image has power's mean (difference $z standard errors over 3072 pixels)" \
  || bad "lights100.sph: --light-choice importance's mean differs from power's by '$z' standard errors"
noise() {   # over the floor and balls: the pixels below 1 in every channel of all four images
  python3 -c "$PFM_PY
im = [pfm(f) for f in sys.argv[1:]]
lit = [k for k in range(len(im[0]) // 3) if max(max(i[3 * k:3 * k + 3]) for i in im) < 1]
a, b = im[0], im[1]
print('%.5f' % ((sum((a[3 * k + c] - b[3 * k + c]) ** 2 for k in lit for c in range(3)) / (3 * len(lit)) / 2) ** 0.5))" \
    "$TMP/${1}1.pfm" "$TMP/${1}2.pfm" "$TMP/${2}1.pfm" "$TMP/${2}2.pfm"
}
ni=$(noise importance power) np=$(noise power importance)
awk -v i="$ni" -v p="$np" 'BEGIN { exit !(p > 0 && i <= 0.5 * p) }' \
  && ok "lights100.sph at 16 spp: --light-choice importance's noise $ni, power's $np ($(awk -v i="$ni" -v p="$np" 'BEGIN { printf "%.2f", i / p }') of it; at most 0.5)" \
  || bad "lights100.sph at 16 spp: --light-choice importance's noise '$ni' against power's '$np' (want at most 0.5 of it)"

# Glowing spheres cut by opaque ones (tests/test_light.c, then images):
# sampling only the cap a point can see changes the noise, never the mean.
# On smallpt's scene (its lamp sunk into the ceiling but for a disc) and on
# clips.sph (written by test_light: lamps sunk into a floor and into balls,
# seen from outside them), the default against --no-skip (which samples the
# whole lamp) averages 0 over the image within 4 standard errors; and on
# smallpt's room without its two balls (whose caustics, which no light
# sample finds, are most of the noise where they stand) the noise (RMSE
# between two seeds over sqrt 2) falls to at most 0.4 of --no-skip's.
grep -v '^27 \|^73 ' scenes/smallpt.sph >"$TMP/room.sph"
for f in scenes/smallpt.sph "$TMP/clips.sph" "$TMP/room.sph"; do
  for seed in 1 2; do
    ./ray "$f" -s 32x24 -n 64 --seed $seed -o "$TMP/clip$seed.pfm" 2>/dev/null
    ./ray "$f" -s 32x24 -n 64 --seed $seed --no-skip -o "$TMP/whole$seed.pfm" 2>/dev/null
  done
  z=$(mean_apart "$TMP/whole1.pfm" "$TMP/clip2.pfm")
  awk -v z="$z" 'BEGIN { exit !(z != "" && z < 4 && z > -4) }' \
    && ok "${f##*/}: the lamps sampled in their caps give --no-skip's mean (difference $z standard errors over 768 pixels)" \
    || bad "${f##*/}: the lamps sampled in their caps differ from --no-skip's mean by '$z' standard errors"
  if [ "$f" = "$TMP/room.sph" ]; then
    seeds_apart() {   # the noise of two seeds' images: their RMSE over sqrt 2
      python3 -c "$PFM_PY
a, b = pfm(sys.argv[1]), pfm(sys.argv[2])
print('%.5f' % ((sum((x - y) ** 2 for x, y in zip(a, b)) / len(a) / 2) ** 0.5))" "$1" "$2"
    }
    nc=$(seeds_apart "$TMP/clip1.pfm" "$TMP/clip2.pfm") nw=$(seeds_apart "$TMP/whole1.pfm" "$TMP/whole2.pfm")
    awk -v c="$nc" -v w="$nw" 'BEGIN { exit !(w > 0 && c <= 0.4 * w) }' \
      && ok "smallpt's room without its balls at 64 spp: the lamp sampled in its cap, noise $nc against --no-skip's $nw ($(awk -v c="$nc" -v w="$nw" 'BEGIN { printf "%.2f", c / w }') of it; at most 0.4)" \
      || bad "smallpt's room without its balls at 64 spp: the lamp sampled in its cap, noise '$nc' against --no-skip's '$nw' (want at most 0.4 of it)"
  fi
done

# A furnace of two glowing spheres that cut each other, both of albedo .5
# and Le 1.5, the camera in the lens they share: every surface it can see
# is the inside of one of them within the other, each sampled in the cap
# the other leaves seen, so L = Le (1 - a^N) / (1 - a) with -d N, and
# Le / (1 - a) unbounded, within 4 standard errors: with MIS, and with
# next-event estimation alone, whose lamps are found by light samples only
# (MIS would stay unbiased with a cap that misses what a point sees, its
# BSDF samples then weighed 1 there).
printf 'integrator path\ncamera .75 -.5 0   .75 1 0   0 0 1   90\n0 0 0  1 1 1  2  .5 0 0 1.5 1\n1.5 0 0  1 1 1  2  .5 0 0 1.5 1\n' >"$TMP/lens.sph"
[ "$(./ray --stats=kv -s 4x4 -n 1 -o "$TMP/l.pfm" "$TMP/lens.sph" 2>&1 | awk '$1 == "clipped_lights" { print $2 }')" = 2 ] \
  && ok "lens.sph: both glowing spheres clipped (--stats=kv clipped_lights 2)" \
  || bad "lens.sph: --stats=kv does not count both glowing spheres clipped"
for r in "4 2.8125 mis" "0 3 mis" "4 2.8125 nee" "0 3 nee"; do
  set -- $r
  d=""; [ "$1" != 0 ] && d="-d $1"
  # shellcheck disable=SC2086
  ./ray "$TMP/lens.sph" -s 32x32 -n 32 $d --estimator $3 -o "$TMP/l.pfm" 2>/dev/null
  read -r mean z <<<"$(python3 -c "$PFM_PY
a = pfm(sys.argv[1]); d = [sum(a[3 * k:3 * k + 3]) / 3 for k in range(len(a) // 3)]
n = len(d); m = sum(d) / n; v = sum((x - m) ** 2 for x in d) / (n - 1)
print('%.4f %.2f' % (m, (m - float(sys.argv[2])) / (v / n) ** 0.5 if v > 0 else (0 if m == float(sys.argv[2]) else 99)))" "$TMP/l.pfm" "$2")"
  awk -v z="$z" 'BEGIN { exit !(z != "" && z < 4 && z > -4) }' \
    && ok "two glowing spheres that cut each other, a furnace${d:+ at $d}, $3: mean $mean is $2 within $z standard errors" \
    || bad "two glowing spheres that cut each other, a furnace${d:+ at $d}, $3: mean '$mean' is not $2: '$z' standard errors"
done

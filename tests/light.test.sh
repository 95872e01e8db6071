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
z=$(python3 -c "$PFM_PY
a, b = pfm(sys.argv[1]), pfm(sys.argv[2])
d = [sum(b[3 * k:3 * k + 3]) - sum(a[3 * k:3 * k + 3]) for k in range(len(a) // 3)]
n = len(d); m = sum(d) / n; v = sum((x - m) ** 2 for x in d) / (n - 1)
print('%.2f' % (m / (v / n) ** 0.5 if v > 0 else 99))" "$TMP/power1.pfm" "$TMP/importance2.pfm")
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

# The path tracer's samplers (--sampler): tests/test_sampler.c checks the
# Sobol' points themselves (nets, uniformity, independence); here, images.
# Owen-scrambled Sobol' points change the noise, never the mean: per pixel,
# sobol minus independent averages 0 over the image within 4 standard
# errors (each pixel's two estimates are independent of every other
# pixel's, so the spread of the differences gives the error).  And on a
# large lamp close over a floor (scenes/lamp.sph), where the light's point
# is most of the noise, the noise (RMSE between two seeds over sqrt 2) of
# sobol is at most 0.6 of independent's at 64 samples a pixel.
. tests/lib.sh
# shellcheck disable=SC2086 # CFLAGS and RAY_PARTS hold several words
$CC $CFLAGS -std=c99 -o "$TMP/test_sampler" tests/test_sampler.c $RAY_PARTS -lm || { bad "tests/test_sampler.c compiles"; exit 1; }
"$TMP/test_sampler"

for r in "cornell.sph -n 16" "veach.sph -n 16" "caustic.sph -n 16" "lamp.sph -n 16" "dof.sph --pt -n 8"; do
  set -- $r
  f=$1; shift
  ./ray scenes/$f --pt "$@" -s 48x36 --sampler independent -o "$TMP/i.pfm" 2>/dev/null
  ./ray scenes/$f --pt "$@" -s 48x36 --sampler sobol --seed 7 -o "$TMP/s.pfm" 2>/dev/null
  z=$(python3 -c "$PFM_PY
a, b = pfm(sys.argv[1]), pfm(sys.argv[2])
d = [sum(b[3 * k:3 * k + 3]) - sum(a[3 * k:3 * k + 3]) for k in range(len(a) // 3)]   # per pixel
n = len(d); m = sum(d) / n; v = sum((x - m) ** 2 for x in d) / (n - 1)
print('%.2f' % (m / (v / n) ** 0.5 if v > 0 else 0))" "$TMP/i.pfm" "$TMP/s.pfm")
  awk -v z="$z" 'BEGIN { exit !(z != "" && z < 4 && z > -4) }' \
    && ok "$f $*: --sampler sobol's image has independent's mean (difference $z standard errors over 1728 pixels)" \
    || bad "$f $*: --sampler sobol's mean differs from independent's by '$z' standard errors"
done

noise() {   # the sampler's noise on lamp.sph at 64 spp: RMSE between seeds 1 and 2, over sqrt 2
  ./ray scenes/lamp.sph -s 48x36 -n 64 --sampler "$1" --seed 1 -o "$TMP/n1.pfm" 2>/dev/null
  ./ray scenes/lamp.sph -s 48x36 -n 64 --sampler "$1" --seed 2 -o "$TMP/n2.pfm" 2>/dev/null
  python3 -c "$PFM_PY
a, b = pfm(sys.argv[1]), pfm(sys.argv[2])
print('%.5f' % ((sum((x - y) ** 2 for x, y in zip(a, b)) / len(a) / 2) ** 0.5))" "$TMP/n1.pfm" "$TMP/n2.pfm"
}
ni=$(noise independent) ns=$(noise sobol)
awk -v i="$ni" -v s="$ns" 'BEGIN { exit !(i > 0 && s <= 0.6 * i) }' \
  && ok "lamp.sph at 64 spp: --sampler sobol's noise $ns, independent's $ni ($(awk -v i="$ni" -v s="$ns" 'BEGIN { printf "%.2f", s / i }') of it; at most 0.6)" \
  || bad "lamp.sph at 64 spp: --sampler sobol's noise '$ns' against independent's '$ni' (want at most 0.6 of it)"

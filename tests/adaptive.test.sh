# Adaptive sampling (--adaptive E): where a pixel's samples agree, and (in
# Whitted's renderer) its neighbours' first 4 agree with them, it stops at
# 4; where they disagree it goes on to -n;
# the bytes do not depend on the thread count; Whitted's image is nearer a
# reference than uniform 16 samples are; the path tracer's mean stays
# within 4 standard errors of a uniform render's; --stats and --view
# samples say what each pixel took.
. tests/lib.sh

# A wall of one colour (ambient only): every pixel's samples agree.
printf 'size 16 12\ncamera 0 0 -5 0 0 0 0 1 0 40\nambient .5 .5 .5\n0 0 0 .8 .6 .4 100 1 0 0 0 1\n' > "$TMP/flat.sph"
./ray -n 64 --adaptive 0.5 --stats=kv -o "$TMP/flat.ppm" "$TMP/flat.sph" 2>"$TMP/kv"
./ray -n 64 --adaptive 0.5 --view samples -o "$TMP/flat_n.ppm" "$TMP/flat.sph" 2>/dev/null
grep -qx "samples_min 4" "$TMP/kv" && grep -qx "samples_max 4" "$TMP/kv" \
  && python3 -c 'import sys; d=open(sys.argv[1],"rb").read()[-16*12*3:]; sys.exit(0 if set(d) == {16} else 1)' "$TMP/flat_n.ppm" \
  && ok "a flat wall: every pixel stops at 4 of 64 samples (--stats=kv), and --view samples shows 4/64 grey" \
  || bad "a flat wall: $(grep samples_ "$TMP/kv" | tr '\n' ' ')"

# scenes/whitted.sph at 80x60: edges go to -n; the image is nearer a
# 128-sample reference than uniform 16 samples get.
./ray -s 80x60 -n 128 -o "$TMP/ref.ppm" scenes/whitted.sph 2>/dev/null
./ray -s 80x60 -n 16 -o "$TMP/u16.ppm" scenes/whitted.sph 2>/dev/null
./ray -s 80x60 -n 64 --adaptive 0.5 --stats -o "$TMP/a.ppm" scenes/whitted.sph 2>"$TMP/st"
rmse() { tools/ppmdiff "$1" "$2" 2>/dev/null | sed -n 's/.*RMSE \([0-9.]*\).*/\1/p'; }
ra=$(rmse "$TMP/a.ppm" "$TMP/ref.ppm") ru=$(rmse "$TMP/u16.ppm" "$TMP/ref.ppm")
line=$(grep '^adaptive ' "$TMP/st")
[ -n "$ra" ] && [ -n "$ru" ] && awk -v a="$ra" -v u="$ru" 'BEGIN { exit !(a < 0.75 * u) }' \
  && printf '%s\n' "$line" | grep -q "from 4 to 64 (of 64)" \
  && ok "whitted.sph, --adaptive 0.5 -n 64: RMSE $ra steps against the 128-sample image, uniform 16 spp $ru; $line" \
  || bad "whitted.sph adaptive: RMSE '$ra' against uniform 16's '$ru'; $line"

# Equal error for fewer samples: -n 64 --adaptive 16 reaches uniform 16's
# RMSE with at most 9 samples a pixel (at this size edges are many).
./ray -s 80x60 -n 64 --adaptive 16 --stats=kv -o "$TMP/a16.ppm" scenes/whitted.sph 2>"$TMP/kv16"
r16=$(rmse "$TMP/a16.ppm" "$TMP/ref.ppm") spp16=$(sed -n 's/^samples_per_pixel //p' "$TMP/kv16")
[ -n "$r16" ] && [ -n "$spp16" ] && awk -v a="$r16" -v u="$ru" -v n="$spp16" 'BEGIN { exit !(a <= u && n <= 9) }' \
  && ok "whitted.sph, --adaptive 16 -n 64: RMSE $r16 steps (uniform 16: $ru) with $spp16 samples a pixel" \
  || bad "whitted.sph, --adaptive 16 -n 64: RMSE '$r16' (uniform 16: '$ru'), '$spp16' samples a pixel"

# The same bytes on 1 and 3 threads, in both renderers.
./ray -t 1 -s 40x30 -n 32 --adaptive 0.5 -o "$TMP/w1.ppm" scenes/whitted.sph 2>/dev/null
./ray -t 3 -s 40x30 -n 32 --adaptive 0.5 -o "$TMP/w3.ppm" scenes/whitted.sph 2>/dev/null
./ray -t 1 --pt -s 24x24 -n 64 --adaptive 4 -o "$TMP/p1.pfm" scenes/cornell.sph 2>/dev/null
./ray -t 3 --pt -s 24x24 -n 64 --adaptive 4 -o "$TMP/p3.pfm" scenes/cornell.sph 2>/dev/null
[ -s "$TMP/w1.ppm" ] && cmp -s "$TMP/w1.ppm" "$TMP/w3.ppm" && [ -s "$TMP/p1.pfm" ] && cmp -s "$TMP/p1.pfm" "$TMP/p3.pfm" \
  && ok "--adaptive: the same bytes on 1 and 3 threads (Whitted's PPM, the path tracer's PFM)" \
  || bad "--adaptive depends on the thread count"

# The path tracer: pixels that stop early (the rule, not luck) must not
# move the image's mean: adaptive (seed 0) against uniform (seed 1), the
# difference's mean over pixels within 4 standard errors.
./ray --pt -s 32x32 -n 128 --adaptive 8 --stats=kv -o "$TMP/pa.pfm" scenes/cornell.sph 2>"$TMP/pkv"
./ray --pt -s 32x32 -n 128 --seed 1 -o "$TMP/pu.pfm" scenes/cornell.sph 2>/dev/null
out=$(python3 - "$TMP/pa.pfm" "$TMP/pu.pfm" <<'EOF'
import math, struct, sys
def floats(name):
    d = open(name, "rb").read().split(b"\n", 3)
    w, h = map(int, d[1].split())
    return struct.unpack("<%df" % (w * h * 3), d[3][:w * h * 12])
a, u = floats(sys.argv[1]), floats(sys.argv[2])
diff = [x - y for x, y in zip(a, u)]
n = len(diff)
m = sum(diff) / n
se = math.sqrt(sum((x - m) ** 2 for x in diff) / (n - 1) / n)
print("%.3g %.3g %.2f" % (m, se, abs(m) / se))
EOF
)
spp=$(sed -n 's/^samples_per_pixel //p' "$TMP/pkv")
[ -n "$out" ] && [ -n "$spp" ] && awk -v z="${out##* }" -v s="$spp" 'BEGIN { exit !(z <= 4 && s < 128) }' \
  && ok "the path tracer, --adaptive 8 -n 128 ($spp samples a pixel): mean difference from a uniform render ${out% *} (mean, standard error), ${out##* } standard errors" \
  || bad "the path tracer's adaptive mean: '$out', $spp samples a pixel"

# --adaptive takes a number of steps above 0, at most 255.
for e in 0 -1 300 x; do
  ./ray --adaptive "$e" -o "$TMP/x.ppm" "$TMP/flat.sph" 2>"$TMP/err"; rc=$?
  [ $rc = 2 ] && grep -q "8-bit steps" "$TMP/err" && [ ! -e "$TMP/x.ppm" ] && ok "--adaptive $e: refused" \
    || bad "--adaptive $e: exit $rc"
done

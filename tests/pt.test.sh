# The path tracer: analytic answers (tests/test_pt.c includes ray.c whole),
# and what the program promises of its output.
. tests/lib.sh
$CC $CFLAGS -std=c99 -o "$TMP/test_pt" tests/test_pt.c $RAY_PARTS -lm || { bad "tests/test_pt.c compiles"; exit 1; }
"$TMP/test_pt"

# The same bytes on 1 and 2 threads: a pixel's random numbers are a hash of
# the pixel and its sample, not a shared generator's.
./ray --pt -t 1 -s 40x30 -n 8 -o "$TMP/t1.ppm" scenes/cornell.sph 2>/dev/null
./ray --pt -t 2 -s 40x30 -n 8 -o "$TMP/t2.ppm" scenes/cornell.sph 2>/dev/null
check "path tracing: the same bytes on 1 and 2 threads" cmp "$TMP/t1.ppm" "$TMP/t2.ppm"
./ray --pt -t 2 -s 40x30 -n 8 --seed 5 -o "$TMP/t3.ppm" scenes/cornell.sph 2>/dev/null
if cmp -s "$TMP/t1.ppm" "$TMP/t3.ppm"; then bad "path tracing: --seed 5 changes the noise"
else ok "path tracing: --seed 5 changes the noise"; fi

# PFM: a header, then w*h*3 little-endian floats, all finite.
./ray --pt -s 20x10 -n 4 -o "$TMP/x.pfm" scenes/smallpt.sph 2>/dev/null
check "path tracing: -o x.pfm writes PF, 20 10, -1.0 and 600 floats" \
  python3 -c "
import struct, sys, math
d = open('$TMP/x.pfm', 'rb').read()
head = b'PF\n20 10\n-1.0\n'
assert d.startswith(head) and len(d) == len(head) + 600 * 4
v = struct.unpack('<600f', d[len(head):])
assert all(math.isfinite(x) and x >= 0 for x in v) and max(v) > 0
"
# A camera that starts inside the box (hither) sees the room, not the
# front wall's back: smallpt's scene is bright in the middle.
check "path tracing: smallpt's camera looks into the box through hither 140" \
  python3 -c "
import struct
d = open('$TMP/x.pfm', 'rb').read()
v = struct.unpack('<600f', d[-2400:])
assert sum(v) / 600 > 0.1
"

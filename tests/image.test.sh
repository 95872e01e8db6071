# Images people can open and keep (issue 22, section 4): PNG compressed by
# image.c's own deflate, and OpenEXR.  Every check prints PASS, FAIL or SKIP
# (tests/lib.sh).  The images are made first, then checked by one python
# process for each format (the decode() of tests/png2ppm.py and of
# tests/exr2pfm.py): a python start costs a tenth of a second here.
. tests/lib.sh

# tools/ppm2png: a PPM through the same PNG writer (image.c).
$CC -std=c99 $CFLAGS -o "$TMP/ppm2png" tools/ppm2png.c image.c 2> "$TMP/err" \
  || bad "tools/ppm2png.c compiles: $(head -3 "$TMP/err")"

# --- PNG.  Renders as PNG and PPM: a pixel, a row 4000 wide, a column, odd
# sizes, an NFF scene, path-traced renders whose noise leaves few copies to
# find, Whitted's with many, and one colour (copies of 258 bytes, the
# longest, all the way).
printf 'background .2 .3 .4\n' > "$TMP/flat.sph"
k=0
for args in "-s 1x1 scenes/whitted.sph" "-s 4000x1 scenes/whitted.sph" "-s 1x300 scenes/whitted.sph" \
            "-s 160x120 scenes/demo.nff" "-s 120x90 -n 4 --pt scenes/cornell.sph" "-s 96x64 -n 2 scenes/caustic.sph" \
            "-s 320x240 --gamma scenes/whitted.sph" "-s 320x240 $TMP/flat.sph"; do
  k=$((k + 1))
  ./ray $args -o "$TMP/png$k.ppm" 2> /dev/null && ./ray $args -o "$TMP/png$k.png" 2> /dev/null
  echo "$args" | sed "s|$TMP/||" > "$TMP/png$k.args"
done
# Noise through tools/ppm2png: random bytes, which do not compress (stored
# blocks), and 640x480 of 5-bit noise, timed (few copies: the longest
# searches; inflated, not unfiltered: python's unfiltering takes a second).
python3 -c '
import random, sys
for name, w, h, shift in (("noise", 200, 150, 0), ("big", 640, 480, 3)):
    pixels = bytes(b >> shift for b in random.Random(22).randbytes(w * h * 3))
    open(sys.argv[1] + "/" + name + ".ppm", "wb").write(b"P6\n%d %d\n255\n" % (w, h) + pixels)' "$TMP"
"$TMP/ppm2png" "$TMP/noise.ppm" "$TMP/noise.png"
TIMEFORMAT=%U
{ time "$TMP/ppm2png" "$TMP/big.ppm" "$TMP/big.png" 2>&1; } 2> "$TMP/big.time"

# Each PNG decoded by png2ppm.decode(): python's zlib inflates it (a bad
# Huffman table, a wrong length or distance code, a bad block is an error
# there; the Adler-32 and every CRC are checked) and the rows are
# unfiltered; the pixels must be the PPM's, byte for byte.  The size
# against zlib's: python's zlib at level 6 (its default) on the very rows
# the PNG holds (inflated from its IDAT chunks: the same filter byte chosen
# for each row), against the PNG's IDAT bytes: within 1.3 times on
# realistic renders (Whitted's scene at 320x240, a path-traced Cornell box);
# the checks hold it to 1.1 (it is within 1% today), a guard against a
# search made worse.  The filters: each row's the heuristic's, recomputed
# from the pixels (the Cornell box), and sub, up, average and Paeth all
# chosen.
python3 - "$TMP" <<'EOF'
import os, struct, sys, zlib
sys.path.insert(0, "tests")
import png2ppm
tmp = sys.argv[1]
def read(name): return open(os.path.join(tmp, name), "rb").read()
def inflated(png):
    """The IDAT bytes, and the rows they inflate to."""
    pos, idat = 8, b""
    while pos < len(png):
        n, kind = struct.unpack(">I4s", png[pos:pos + 8])
        idat += png[pos + 8:pos + 8 + n] if kind == b"IDAT" else b""
        pos += 12 + n
    return idat, zlib.decompress(idat)
def sizes(png):
    idat, rows = inflated(png)
    return len(idat), len(zlib.compress(rows, 6)), len(rows)
def heuristic(ppm):
    """Each row's filter type as ISO/IEC 15948 12.8 recommends, from the
    pixels: the least sum of the filtered bytes' absolute values, taken as
    signed (ties: the lower type)."""
    head = ppm.split(b"\n", 3)
    w, h = map(int, head[1].split())
    px, n, up, types = head[3], 3 * w, bytes(3 * w), []
    for j in range(h):
        row, sums = px[j * n:(j + 1) * n], []
        for t in range(5):
            total = 0
            for i in range(n):
                a, b, c = row[i - 3] if i >= 3 else 0, up[i], up[i - 3] if i >= 3 else 0
                p = a + b - c
                paeth = a if abs(p - a) <= abs(p - b) and abs(p - a) <= abs(p - c) else b if abs(p - b) <= abs(p - c) else c
                d = (row[i] - (0, a, b, (a + b) // 2, paeth)[t]) & 255
                total += min(d, 256 - d)
            sums.append(total)
        types.append(sums.index(min(sums)))
        up = row
    return types
def decoded(name, want):
    try:
        ppm, _ = png2ppm.decode(read(name + ".png"))
    except SystemExit as e:
        return str(e)
    return "" if ppm == want else "decodes to other pixels"
k, chosen = 1, set()
while os.path.exists(os.path.join(tmp, "png%d.args" % k)):
    name, args = "png%d" % k, read("png%d.args" % k).decode().strip()
    why = decoded(name, read(name + ".ppm"))
    print("%s PNG %s: %s" % ("FAIL" if why else "PASS", args, why or "decodes to the PPM's bytes (%d bytes, the PPM %d)"
                             % (len(read(name + ".png")), len(read(name + ".ppm")))))
    ours, zlib6, rows = sizes(read(name + ".png"))
    if "--gamma" in args or "cornell" in args:
        print("%s PNG size, %s: %d bytes of deflate against zlib -6's %d on the same %d bytes of filtered rows: %.3f times (at most 1.1, a guard; the issue asks 1.3)"
              % ("PASS" if ours <= 1.1 * zlib6 else "FAIL", args, ours, zlib6, rows, ours / zlib6))
        w = struct.unpack(">I", read(name + ".png")[16:20])[0]
        types = list(inflated(read(name + ".png"))[1][::3 * w + 1])
        chosen |= set(types)
    if "cornell" in args:
        want = heuristic(read(name + ".ppm"))
        print("%s PNG filters, %s: each row's the one the heuristic of ISO/IEC 15948 12.8 chooses%s"
              % ("PASS" if types == want else "FAIL", args, "" if types == want else
                 ": not in rows %s" % [j for j in range(len(want)) if types[j] != want[j]][:10]))
    if "flat" in args:
        print("%s PNG of one colour, 320x240: %d bytes of deflate for %d bytes of rows (at most 1000; zlib -6: %d)"
              % ("PASS" if ours <= 1000 else "FAIL", ours, rows, zlib6))
    k += 1
print("%s PNG filters: sub, up, average and Paeth are each chosen for some row in these two renders (chose %s)"
      % ("PASS" if {1, 2, 3, 4} <= chosen else "FAIL", sorted(chosen)))
why = decoded("noise", read("noise.ppm"))
ours, zlib6, rows = sizes(read("noise.png"))
most = rows + 5 * (rows // 16384 + 1) + 6    # 5 bytes a stored block (one a block of 16384 symbols), zlib's 6
print("%s PNG of random bytes: %s; %d bytes of deflate for %d bytes of rows, at most %d: stored (zlib -6: %d)"
      % ("FAIL" if why or ours > most else "PASS", why or "decodes to them", ours, rows, most, zlib6))
ours, zlib6, rows = sizes(read("big.png"))      # decoded, as zlib checks its Adler-32
cpu = float(read("big.time") or "nan")
print("%s PNG of 640x480 noisy pixels written in %.3f s of CPU (at most 1): %d bytes of deflate (zlib -6: %d)"
      % ("PASS" if cpu <= 1 else "FAIL", cpu, ours, zlib6))
EOF

# --- OpenEXR.  Renders as EXR and PFM: heights that are not multiples of 16
# (a chunk's lines), and noise that leaves some chunks as they are (not
# smaller zipped).
k=0
for args in "-s 1x1 scenes/whitted.sph" "-s 4000x1 scenes/whitted.sph" "-s 33x17 scenes/minray.sph" \
            "-s 160x120 scenes/demo.nff" "-s 120x90 -n 4 --pt scenes/cornell.sph" "-s 64x48 -n 2 scenes/smallpt.sph"; do
  k=$((k + 1))
  ./ray $args -o "$TMP/exr$k.pfm" 2> /dev/null && ./ray $args -o "$TMP/exr$k.exr" 2> /dev/null
  echo "$args" > "$TMP/exr$k.args"
done
./ray -s 9x4 -o "$TMP/X.EXR" scenes/whitted.sph
[ "$(head -c 4 "$TMP/X.EXR" | od -An -tx1 | tr -d ' ')" = 762f3101 ] \
  && ok "-o X.EXR (upper case) writes OpenEXR" || bad "-o X.EXR"
./ray -s 4x4 --p3 -o "$TMP/p.exr" scenes/whitted.sph 2> "$TMP/err"; rc=$?
[ $rc = 2 ] && [ ! -e "$TMP/p.exr" ] && ok "--p3 -o x.exr refused, exit 2: $(sed "s|$TMP/||" "$TMP/err")" \
  || bad "--p3 -o x.exr: exit $rc"

# Where Debian's OpenEXR tools are (package openexr; .ci/run installs it):
# exrheader reads the header as ray wrote it, and the library itself decodes
# the pixels (exrmaketiled writes them again as one uncompressed tile, which
# exr2pfm.decode(tiled=True) reads below).  exr5 is the Cornell box, 120x90.
if command -v exrheader > /dev/null; then
  exrheader "$TMP/exr5.exr" > "$TMP/head" 2>&1 && [ "$(grep -c "32-bit floating-point, sampling 1 1" "$TMP/head")" = 3 ] \
    && grep -q "zip, multi-scanline blocks" "$TMP/head" && grep -q "dataWindow (type box2i): (0 0) - (119 89)" "$TMP/head" \
    && ok "exrheader reads ray's EXR: B, G, R floats, zip, 120x90" || bad "exrheader: $(tr -s '\n' ' ' < "$TMP/head" | cut -c1-300)"
else
  skip "exrheader reads ray's EXR: exrheader is not installed (Debian's openexr)"
fi
if command -v exrmaketiled > /dev/null; then
  exrmaketiled -t 120 90 -z none "$TMP/exr5.exr" "$TMP/tiled.exr" > "$TMP/err" 2>&1 \
    || bad "exrmaketiled reads ray's EXR: $(cat "$TMP/err")"
else
  skip "the OpenEXR library decodes ray's EXR: exrmaketiled is not installed (Debian's openexr)"
fi

# Each EXR read by exr2pfm.decode() (written from the file layout document:
# magic, version, each required attribute, the offset table, each chunk's y
# and size, zlib and the predictor undone) into a PFM that must be ./ray's
# PFM of the same render, byte for byte.  The reader is strict: one byte
# changed in a chunk's zlib stream, in the offset table, the channels' type,
# or a byte after the last chunk, and it refuses.
python3 - "$TMP" <<'EOF'
import os, struct, sys
sys.path.insert(0, "tests")
import exr2pfm
tmp = sys.argv[1]
def read(name): return open(os.path.join(tmp, name), "rb").read()
def decoded(data, want, tiled=False):
    try:
        pfm, kinds = exr2pfm.decode(data, tiled)
    except SystemExit as e:
        return str(e), []
    return "" if pfm == want else "decodes to other floats", kinds
k, every = 1, []
while os.path.exists(os.path.join(tmp, "exr%d.args" % k)):
    name, args = "exr%d" % k, read("exr%d.args" % k).decode().strip()
    why, kinds = decoded(read(name + ".exr"), read(name + ".pfm"))
    every += kinds
    print("%s EXR %s: %s" % ("FAIL" if why else "PASS", args, why or "decodes to the PFM's bytes (%d bytes, the PFM %d)"
                             % (len(read(name + ".exr")), len(read(name + ".pfm")))))
    k += 1
print("%s EXR chunks both zipped (%d) and stored as they are (%d)"
      % ("PASS" if "zip" in every and "stored" in every else "FAIL", every.count("zip"), every.count("stored")))
if os.path.exists(os.path.join(tmp, "tiled.exr")):
    why, _ = decoded(read("tiled.exr"), read("exr5.pfm"), tiled=True)
    print("%s the OpenEXR library decodes ray's ZIP chunks to the PFM's floats (exrmaketiled): %s"
          % ("FAIL" if why else "PASS", why or "the same bytes"))
good = read("exr3.exr")        # minray 33x17: two chunks, both zipped
table = good.index(b"screenWindowWidth\0float\0") + len("screenWindowWidth\0float\0") + 4 + 4 + 1
first, = struct.unpack("<Q", good[table:table + 8])
def changed(at, xor=0x55, extra=b""):
    data = bytearray(good) + extra
    if at is not None:
        data[at] ^= xor
    return bytes(data)
for what, data in (("a byte of chunk 0's zlib stream", changed(first + 8 + 20)),
                   ("the offset table", changed(table, 1)),
                   ("the channels' type (B as HALF)", changed(good.index(b"chlist\0") + 7 + 4 + 2, 3)),
                   ("a byte after the last chunk", changed(None, extra=b"\0"))):
    why, _ = decoded(data, b"")
    print("%s exr2pfm refuses a file with %s changed: %s" % ("PASS" if why.startswith("exr2pfm") else "FAIL", what, why))
EOF

#!/usr/bin/env bash
# tools/ppmdiff: the image comparison every other image test relies on, so it
# is checked on images small enough to verify by hand.
cd "$(dirname "$0")/.." || exit 2
. tests/lib.sh

# shellcheck disable=SC2086 # CFLAGS holds several words, as in make
if ! $CC $CFLAGS -o "$TMP/ppmdiff" tools/ppmdiff.c -lm 2>"$TMP/cc.err"; then
  bad "ppmdiff builds with $CC $CFLAGS"; sed 's/^/    /' "$TMP/cc.err"; exit 1
fi
ok "ppmdiff builds with $CC $CFLAGS"
D=$TMP/ppmdiff

# run ARGS...: sets $out (stdout and stderr) and $rc.
run() { out=$("$D" "$@" 2>&1); rc=$?; }
# has TEXT: the last run's output contains TEXT.
has() { printf '%s\n' "$out" | grep -qF -- "$1"; }
# expect NAME RC [TEXT...]: the last run exited RC and printed every TEXT.
expect() {
  local name=$1 want=$2 t; shift 2
  if [ "$rc" != "$want" ]; then bad "$name (exit $rc, want $want): $out"; return; fi
  for t in "$@"; do
    if ! has "$t"; then bad "$name (no '$t' in: $out)"; return; fi
  done
  ok "$name"
}

# A 4x1 image: pixels (10 20 30) (40 50 60) (70 80 90) (100 110 120).
printf 'P3\n4 1\n255\n10 20 30  40 50 60  70 80 90  100 110 120\n' >"$TMP/a.ppm"
# The same pixels as P6, with a comment and the header on one line.
printf 'P6 # same pixels, binary\n4 1 255\n\x0a\x14\x1e\x28\x32\x3c\x46\x50\x5a\x64\x6e\x78' >"$TMP/a6.ppm"
# The same again with 16-bit samples: v * 257 is the byte v twice.
printf 'P6\n4 1\n65535\n\x0a\x0a\x14\x14\x1e\x1e\x28\x28\x32\x32\x3c\x3c\x46\x46\x50\x50\x5a\x5a\x64\x64\x6e\x6e\x78\x78' >"$TMP/a16.ppm"
# One channel (the green of pixel 2) up by 3.
printf 'P3\n4 1\n255\n10 20 30  40 53 60  70 80 90  100 110 120\n' >"$TMP/b.ppm"
# Three channels of twelve up by 6: MSE = 3*36/12 = 9, RMSE = 3,
# PSNR = 20 log10(255/3) = 20 log10(85) = 38.588 dB.
printf 'P3\n4 1\n255\n16 26 36  40 50 60  70 80 90  100 110 120\n' >"$TMP/c.ppm"
printf 'P3\n2 2\n255\n10 20 30  40 50 60  70 80 90  100 110 120\n' >"$TMP/square.ppm"

run "$TMP/a.ppm" "$TMP/a.ppm"
expect "identical images: exit 0, PSNR inf" 0 "channels differing: 0 of 12" "max |diff| 0" "PSNR inf dB"

run "$TMP/a.ppm" "$TMP/b.ppm"
expect "one channel off by 3: reported, exit 1 by default" 1 "channels differing: 1 of 12 (8.33%)" "max |diff| 3"
run -t 3 "$TMP/a.ppm" "$TMP/b.ppm";     expect "one channel off by 3: exit 0 with -t 3" 0 "max |diff| 3"
run --max 3 "$TMP/a.ppm" "$TMP/b.ppm";  expect "--max 3 is -t 3" 0
run -t 2 "$TMP/a.ppm" "$TMP/b.ppm";     expect "one channel off by 3: exit 1 with -t 2" 1
run -q "$TMP/a.ppm" "$TMP/b.ppm"
if [ "$rc" = 1 ] && [ -z "$out" ]; then ok "-q prints nothing, keeps the exit status"; else bad "-q (exit $rc): $out"; fi

run "$TMP/a.ppm" "$TMP/a6.ppm";   expect "P3 and P6 of the same pixels are identical" 0 "PSNR inf dB"
run "$TMP/a6.ppm" "$TMP/a16.ppm"; expect "8-bit and 16-bit of the same pixels are identical" 0 "PSNR inf dB"
run - "$TMP/a6.ppm" <"$TMP/a.ppm"; expect "'-' reads standard input" 0 "PSNR inf dB"

run "$TMP/a.ppm" "$TMP/c.ppm"
expect "RMSE and PSNR match the hand-computed 3 and 38.6 dB" 1 "channels differing: 3 of 12" "max |diff| 6" "RMSE 3.0000" "PSNR 38.6 dB"
run --rmse 3 "$TMP/a.ppm" "$TMP/c.ppm";     expect "--rmse 3 passes RMSE 3" 0
run --rmse 2.99 "$TMP/a.ppm" "$TMP/c.ppm";  expect "--rmse 2.99 fails RMSE 3" 1 "RMSE 3.0000 > 2.99"
run --psnr 38.5 "$TMP/a.ppm" "$TMP/c.ppm";  expect "--psnr 38.5 passes 38.59 dB" 0
run --psnr=38.7 "$TMP/a.ppm" "$TMP/c.ppm";  expect "--psnr=38.7 fails 38.59 dB" 1
run --psnr 99 "$TMP/a.ppm" "$TMP/a.ppm";    expect "--psnr passes identical images" 0

# The mean difference, B - A, signed: c is 3 channels of 12 up by 6 (+1.5);
# noise is one channel up by 1 and one down by 1 (mean 0); dark is every
# channel one level down (mean -1).  Both have max 1: only the mean tells
# a bias from noise.
printf 'P3\n4 1\n255\n11 20 30  40 50 60  70 80 90  100 110 119\n' >"$TMP/noise.ppm"
printf 'P3\n4 1\n255\n9 19 29  39 49 59  69 79 89  99 109 119\n' >"$TMP/dark.ppm"
run "$TMP/a.ppm" "$TMP/c.ppm";  expect "mean diff: 3 channels of 12 up by 6 is +1.5" 1 "mean diff +1.5000"
run "$TMP/dark.ppm" "$TMP/a.ppm"; expect "mean diff is B - A: +1 from dark to a" 1 "mean diff +1.0000"
run -t 1 --bias 0.5 "$TMP/a.ppm" "$TMP/noise.ppm"
expect "--bias 0.5 passes noise of one level either way (mean 0)" 0 "max |diff| 1" "mean diff +0.0000"
run -t 1 --bias 0.5 "$TMP/a.ppm" "$TMP/dark.ppm"
expect "--bias 0.5 fails every channel one level down (max 1, mean -1)" 1 "mean diff -1.0000" "|mean diff| 1.0000 > 0.5"
run --bias 1.5 "$TMP/a.ppm" "$TMP/c.ppm";    expect "--bias 1.5 alone passes mean +1.5 (max not checked)" 0
run --bias=1.49 "$TMP/a.ppm" "$TMP/c.ppm";   expect "--bias=1.49 fails mean +1.5" 1 "|mean diff| 1.5000 > 1.49"
run --bias -1 "$TMP/a.ppm" "$TMP/a.ppm";     expect "--bias below 0: exit 2" 2 "--bias"

run "$TMP/a.ppm" "$TMP/square.ppm"
expect "size mismatch: exit 2 naming both sizes" 2 "4x1" "2x2" "a.ppm" "square.ppm"

printf 'P6\n4 1\n255\n\x0a\x14\x1e\x28\x32' >"$TMP/cut6.ppm"
run "$TMP/a.ppm" "$TMP/cut6.ppm";  expect "truncated P6 raster: exit 2 naming the file" 2 "cut6.ppm" "truncated"
printf 'P3\n4 1\n255\n10 20 30  40 50 60  70\n' >"$TMP/cut3.ppm"
run "$TMP/cut3.ppm" "$TMP/a.ppm";  expect "truncated P3 raster: exit 2 with file:line" 2 "cut3.ppm:5:" "truncated"
printf 'P6\n4 ' >"$TMP/cuthead.ppm"
run "$TMP/a.ppm" "$TMP/cuthead.ppm"; expect "truncated header: exit 2 naming the file" 2 "cuthead.ppm:2:"
printf 'P6\n99999 99999\n255\n\x01' >"$TMP/huge.ppm"
run "$TMP/huge.ppm" "$TMP/a.ppm";  expect "header promising more than the file holds: exit 2" 2 "huge.ppm" "truncated"
: >"$TMP/empty.ppm"
run "$TMP/empty.ppm" "$TMP/a.ppm"; expect "empty file: exit 2" 2 "empty.ppm"
run "$TMP/a.ppm" "$TMP/missing.ppm"; expect "missing file: exit 2 naming it" 2 "missing.ppm"
printf 'P3\n1 1\n255\n0 256 0\n' >"$TMP/over.ppm"
run "$TMP/over.ppm" "$TMP/over.ppm"; expect "sample above maxval: exit 2" 2 "over.ppm:4:"
printf 'P5\n1 1\n255\n\x00' >"$TMP/gray.pgm"
run "$TMP/gray.pgm" "$TMP/gray.pgm"; expect "not a PPM: exit 2" 2 "gray.pgm:1:"
run "$TMP/a.ppm";                  expect "one file only: exit 2" 2
run --bogus "$TMP/a.ppm" "$TMP/a.ppm"; expect "unknown option: exit 2" 2 "--bogus"
run --help; expect "--help exits 0 and explains the difference image" 0 "usage:" "-o DIFF.ppm"

# The difference image: header, size, and the one differing channel (the
# 5th byte) at full brightness, every other channel black.
run -t 3 -o "$TMP/d.ppm" "$TMP/a.ppm" "$TMP/b.ppm"
printf 'P6\n4 1\n255\n\0\0\0\0\377\0\0\0\0\0\0\0' >"$TMP/want.ppm"
if [ "$rc" = 0 ] && cmp -s "$TMP/d.ppm" "$TMP/want.ppm"; then
  ok "-o writes the difference image"
else
  bad "-o writes the difference image (exit $rc): $(od -An -c "$TMP/d.ppm" 2>&1 | head -3)"
fi
run "$TMP/d.ppm" "$TMP/d.ppm"; expect "-o output reads back as a valid PPM" 0 "channels differing: 0 of 12"
run -o "$TMP/nodir/d.ppm" "$TMP/a.ppm" "$TMP/b.ppm"; expect "-o into a missing directory: exit 2" 2 "nodir/d.ppm"
exit 0

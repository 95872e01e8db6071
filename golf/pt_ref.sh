#!/usr/bin/env bash
# golf/pt_ref.sh: makes golf/pt_ref.ppm, the reference of golf/pt_card.c,
# with ray.c's path tracer, not with the card itself:
#     make ray && bash golf/pt_ref.sh            (about a minute on 2 cores)
# It renders golf/pt.sph (64x48, the card's view, from its `size` and
# `camera` lines) with ./ray --pt at 16384 samples a pixel (MIS, Russian
# roulette, exact Fresnel) to floats, and writes them as the card prints a
# pixel: each channel x255, clamped to 255, rounded by %.0f, one pixel a
# line of a P3 file.  RAY=path and SPP=N override the renderer and samples.
set -euo pipefail
cd "$(dirname "$0")/.."
RAY=${RAY:-./ray}
SPP=${SPP:-16384}
tmp=$(mktemp -d "${TMPDIR:-/tmp}/ptref.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
"$RAY" --pt -n "$SPP" -o "$tmp/ref.pfm" golf/pt.sph
# PFM: "PF", "W H", "-1.0" (little-endian), then rows of floats bottom up
read -r w h < <(sed -n 2p "$tmp/ref.pfm")
[ "$(sed -n 3p "$tmp/ref.pfm")" = "-1.0" ] || { echo "pt_ref.sh: not a little-endian PFM" >&2; exit 1; }
skip=$(head -n 3 "$tmp/ref.pfm" | wc -c)
od --endian=little -An -v -tf4 -w12 -j "$skip" "$tmp/ref.pfm" |
LC_ALL=C awk -v w="$w" -v h="$h" '
  { row[NR] = $0 }
  function byte(v) { return v < 1 ? sprintf("%.0f", v * 255) : 255 }
  END {
    if (NR != w * h) { print "pt_ref.sh: short PFM" > "/dev/stderr"; exit 1 }
    printf "P3\n%d %d\n255\n", w, h
    for (j = h - 1; j >= 0; j--)
      for (i = 1; i <= w; i++) {
        split(row[j * w + i], c, " ")
        print byte(c[1]) " " byte(c[2]) " " byte(c[3])
      }
  }' >"$tmp/ref.ppm"
mv "$tmp/ref.ppm" golf/pt_ref.ppm
echo "golf/pt_ref.ppm: ray --pt -n $SPP golf/pt.sph, linear, as the card prints"

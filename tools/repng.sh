#!/usr/bin/env bash
# tools/repng.sh [FILE.png...]: the PNGs written again by ray's own PNG
# writer (image.c, through tools/ppm2png.c), compressed; by default every
# PNG git tracks under docs/ (the galleries, made before ray compressed).
#
# Each is decoded by tests/png2ppm.py, written again (with its sRGB chunk,
# if it had one), decoded again and compared: it is replaced only when the
# pixels are the same bytes, the chunks the same kinds, and the file
# smaller.  Prints each file's size before and after, and the totals.
set -euo pipefail
cd "$(dirname "$0")/.."
tmp=$(mktemp -d "${TMPDIR:-/tmp}/repng.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
${CC:-cc} -std=c99 -O2 -o "$tmp/ppm2png" tools/ppm2png.c image.c
if [ $# = 0 ]; then
  mapfile -t files < <(git ls-files 'docs/*.png')
else
  files=("$@")
fi
before=0 after=0
for f in "${files[@]}"; do
  python3 tests/png2ppm.py -c "$f" > "$tmp/old.ppm" 2> "$tmp/old.chunks"
  srgb=""
  if grep -qx sRGB "$tmp/old.chunks"; then srgb=--srgb; fi
  "$tmp/ppm2png" $srgb "$tmp/old.ppm" "$tmp/new.png"
  python3 tests/png2ppm.py -c "$tmp/new.png" > "$tmp/new.ppm" 2> "$tmp/new.chunks"
  old=$(wc -c < "$f") new=$(wc -c < "$tmp/new.png")
  if ! cmp -s "$tmp/old.ppm" "$tmp/new.ppm"; then
    echo "$f: written again it has other pixels; kept" >&2; exit 1
  fi
  if [ "$(uniq "$tmp/old.chunks")" != "$(uniq "$tmp/new.chunks")" ]; then
    echo "$f: chunks $(uniq "$tmp/old.chunks" | tr '\n' ' ')would not be kept; kept as it is" >&2
    new=$old
  elif [ "$new" -lt "$old" ]; then
    cp "$tmp/new.png" "$f.repng" && chmod --reference="$f" "$f.repng" && mv "$f.repng" "$f"   # whole or not at all
  else
    new=$old
  fi
  echo "$f: $old -> $new bytes, the same pixels"
  before=$((before + old)) after=$((after + new))
done
echo "${#files[@]} files: $before -> $after bytes"

#!/usr/bin/env bash
# Renders the README's pictures of the shadow terminator: scenes/ball.obj
# (80 triangles) flat-shaded and with its vertex normals, lit from the side.
#     make && bash tools/render_terminator.sh      # writes docs/terminator/*.png
set -euo pipefail
cd "$(dirname "$0")/.."
tmp=$(mktemp -d "${TMPDIR:-/tmp}/terminator.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
cp scenes/ball.obj "$tmp/smooth.obj"
sed -e '/^vn/d' -e 's|//[0-9]*||g' scenes/ball.obj > "$tmp/flat.obj"   # the normals left out
for k in flat smooth; do
  printf 'ambient .05 .05 .05\nbackground .1 .12 .2\ncamera 0 -4 0  0 0 0  0 0 1  35\n' > "$tmp/$k.sph"
  printf 'light 6 -1 1  1 1 1\nmesh %s.obj  .9 .9 .9  1 0 0 0 1\n' $k >> "$tmp/$k.sph"
  ./ray -s 160x160 -n 4 --gamma -o "docs/terminator/$k.png" "$tmp/$k.sph"
done

#!/usr/bin/env bash
# Renders the seven SPD scenes (made by `make spd` into scenes/spd) for the
# README's gallery:
#     make && make spd && bash tools/render_spd.sh
# 320x320 with 4 samples per pixel, the SPD's depth 5, NFF's view and lights.
set -euo pipefail
cd "$(dirname "$0")/.."
spd=${SPD:-scenes/spd}
for s in balls_s4 gears_s4 mount_s6 rings_s7 teapot_s6 tetra_s6 tree_s11; do
  ./ray -s 320x320 -n 4 -o "docs/spd/$s.png" --stats "$spd/$s.nff" 2>&1 | grep -E '^(scene|time)' | sed "s/^/$s: /"
done

#!/usr/bin/env bash
# The README's pictures of the acceleration structures' work:
#     make && make spd && bash tools/render_views.sh
# The SPD teapot at 320x320, --view steps through the kd-tree, the BVH and
# the grid (one fixed scale: black 0, blue 25, red 50, yellow 100, white 200
# nodes or cells plus tests for a pixel's centre ray), and --view normal.
set -euo pipefail
cd "$(dirname "$0")/.."
for a in kd bvh grid; do
  ./ray -s 320x320 --view steps --accel $a --stats -o "docs/accel/steps_$a.png" scenes/spd/teapot_s6.nff 2>&1 |
    grep '^per ray' | sed "s/^/$a: /"
done
./ray -s 320x320 --view normal -o docs/accel/normal.png scenes/spd/teapot_s6.nff

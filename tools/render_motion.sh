#!/usr/bin/env bash
# Renders scenes/motion.sph for the README's motion blur pictures:
#     make && bash tools/render_motion.sh
# Whitted's renderer and the path tracer, at the scene's size and samples,
# on every core; prints each render's time from --stats, wall and CPU.
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p docs/motion
./ray --whitted --stats -o docs/motion/motion.png scenes/motion.sph 2>&1 | grep -E '^(image|time)' | sed 's/^/whitted: /'
./ray --pt --stats -o docs/motion/motion_pt.png scenes/motion.sph 2>&1 | grep -E '^(image|time)' | sed 's/^/path traced: /'

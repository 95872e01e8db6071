#!/usr/bin/env bash
# Renders the distribution effects for the README: each scene by Whitted's
# renderer (with --gamma, for viewing) and by the path tracer, at the scene's
# own size and samples, on every core; prints each render's time from
# --stats, wall and CPU.
#     make && bash tools/render_dist.sh
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p docs/dist
for s in dof soft glossy cornell; do
  ./ray --stats --whitted --gamma -o "docs/dist/$s-whitted.png" "scenes/$s.sph" 2>&1 |
    grep -E '^(image|time)' | sed "s/^/$s whitted: /"
  [ "$s" = cornell ] && continue      # the path-traced Cornell box is in docs/pt/
  ./ray --stats --pt -o "docs/dist/$s-path.png" "scenes/$s.sph" 2>&1 |
    grep -E '^(image|time)' | sed "s/^/$s path: /"
done

#!/usr/bin/env bash
# Veach's multiple-importance comparison for the README:
#     make && bash tools/veach.sh [-s WxH] [-n N]
# renders scenes/veach.sph at depth 2 (direct light only; the scene says
# `depth 2`) three times, with BSDF sampling only, light sampling only (nee)
# and both weighed by MIS, into docs/veach/bsdf.png, nee.png and mis.png,
# at the scene's size and samples unless -s or -n say otherwise (passed on
# to ./ray, as is any other option), and prints each render's CPU time from
# --stats.  VEACH_OUT=DIR writes the three elsewhere.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${VEACH_OUT:-docs/veach}
mkdir -p "$out"
for e in bsdf nee mis; do
  ./ray --stats --estimator $e "$@" -o "$out/$e.png" scenes/veach.sph 2>&1 |
    grep -E '^(image|time)' | sed "s/^/$e: /"
done

#!/usr/bin/env bash
# Renders the path-traced scenes for the README's gallery:
#     make && bash tools/render_pt.sh
# Each scene at its own size and samples (its `size` and `samples` lines),
# on every core; prints each render's time from --stats, wall and CPU.
set -euo pipefail
cd "$(dirname "$0")/.."
for s in cornell smallpt caustic bleed; do
  ./ray --stats -o "docs/pt/$s.png" "scenes/$s.sph" 2>&1 | grep -E '^(image|time)' | sed "s/^/$s: /"
done
# the light tree against choosing by power, at the same 16 samples (the README's "Many lights")
./ray -n 16 --light-choice power -o docs/pt/lights100-power.png scenes/lights100.sph
./ray -n 16 -o docs/pt/lights100-tree.png scenes/lights100.sph
# light tracing beside MIS (the README's "Light tracing")
./ray -s 256x256 -n 32 -o docs/pt/cornell-mis32.png scenes/cornell.sph
./ray -s 256x256 -n 32 --estimator light -o docs/pt/cornell-light.png scenes/cornell.sph
./ray -s 320x240 -n 64 --estimator light -o docs/pt/caustic-light.png scenes/caustic.sph
# bidirectional path tracing beside MIS at about the same CPU time, and
# strategies one by one (the README's "Bidirectional path tracing")
./ray -s 320x240 -n 192 --stats -o docs/pt/caustic-mis-eq.png scenes/caustic.sph 2>&1 | grep '^time' | sed 's/^/caustic mis: /'
./ray -s 320x240 -n 112 --estimator bdpt --stats -o docs/pt/caustic-bdpt.png scenes/caustic.sph 2>&1 | grep '^time' | sed 's/^/caustic bdpt: /'
./ray -s 256x256 -n 8 --estimator bdpt --stats -o docs/pt/cornell-bdpt.png scenes/cornell.sph 2>&1 | grep '^time' | sed 's/^/cornell bdpt: /'
for st in 0,3 1,2 2,1 0,4 1,3 2,2 3,1; do
  ./ray -s 160x160 -n 64 --estimator bdpt --strategy $st -o "docs/pt/cornell-s${st/,/-}.png" scenes/cornell.sph
done
for st in 0,5 1,4 2,3 3,2 4,1; do
  ./ray -s 160x120 -n 64 --estimator bdpt --strategy $st -o "docs/pt/caustic-s${st/,/-}.png" scenes/caustic.sph
done
# photon mapping beside them (the README's "Photon mapping")
./ray -s 320x240 -n 20 --estimator photon --stats -o docs/pt/caustic-photon.png scenes/caustic.sph 2>&1 | grep '^time' | sed 's/^/caustic photon: /'
# progressive photon mapping at about the same CPU time, and the photons
# themselves over the picture (the README's "Progressive photon mapping")
./ray -s 320x240 -n 64 --estimator ppm --stats -o docs/pt/caustic-ppm.png scenes/caustic.sph 2>&1 | grep '^time' | sed 's/^/caustic ppm: /'
./ray -s 320x240 -n 16 --estimator photon --photons 10000 --view photons -o docs/pt/caustic-photons.png scenes/caustic.sph

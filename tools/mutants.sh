#!/usr/bin/env bash
# tools/mutants.sh [LIST] [FIRST [LAST]]
#
# A mutation run: each line of LIST (default tools/mutants.txt),
#
#     FILE | OLD | NEW | COMMAND
#
# is one mutant, the first occurrence of OLD in FILE made NEW, tried by
# tools/mutate.sh against the named COMMAND (the tests that matter for that
# file, below).  FIRST and LAST pick lines by their number among the
# mutants (1 the first), to run a part again.  Each mutant prints one line
# in tools/mutations.txt's format, FILE | OLD | NEW | COMMAND | RESULT:
#
#     caught (the first FAIL line)    the tests failed on it
#     MISSED, changes a result        the tests passed, and the probe (below)
#                                     shows other output than the unmutated tree's
#     MISSED, equivalent              the tests passed, and the probe shows the
#                                     same output: no result changed that this
#                                     run can see (the notes in tools/mutations.txt
#                                     say why each is equivalent, or is not)
#     does not build                  a stillborn mutant: counted apart
#
# and the last line gives the score, caught / (caught + missed that change a
# result), the equivalent and stillborn ones apart.  The commands:
#
#     pt     tests/test_pt.c (the path tracer against analytic answers)
#     bvh    tests/test_accel.c for bvh-sah and bvh-median on its 9 scenes
#            (50000 rays, as make test), and tests/counts.test.sh (the
#            structures' work on fixed scenes)
#     grid   the same for the grid
#     whitted  tests/test_ray.c (Whitted's renderer: hits, shading, the skips)
#     lighttrace  tests/lighttrace.test.sh (light tracing against MIS)
#     bdpt   tests/bdpt.test.sh (tests/test_bdpt.c: the MIS weights; BDPT's
#            images against MIS's and the furnace's)
#     photon tests/photons.test.sh (tests/test_photons.c: the photon tree
#            against brute force; photon mapping's bias, progressive photon
#            mapping's, --view photons)
#     light  tests/light.test.sh (tests/test_light.c: Arvo's sampler and the
#            light tree; glowing spheres sampled in their clips' caps; the light
#            choice's and the caps' images)
#     kdbuild  tests/kdbuild.test.sh (the kd build's budget on fans, the
#            ear clipper, what kdtree.c and bvh.c hold at their peaks)
#     bvhbuild  tests/bvhbuild.test.sh (the BVH's binning and sweep against
#            brute force)
#
# A test program that crashes or exits non-zero fails too (a FAIL line
# says so).  The probe, for a mutant the tests let through: for pt,
# tests/test_pt.c's whole output and the PFM images of eight scenes path
# traced with each estimator; for bvh and grid, test_accel's output (without its times),
# and --stats' counts and the image of 15 scenes through that structure.
# The unmutated tree's probe is taken once per command, through a mutant
# that changes only a comment.  Each mutant takes 15 to 40 s; a command
# that runs longer than 600 s is stopped, and counts as caught (a hang).
set -u
cd "$(dirname "$0")/.." || exit 2
list=${1:-tools/mutants.txt}
first=${2:-1}
last=${3:-1000000}
[ -f "$list" ] || { echo "mutants.sh: no list $list" >&2; exit 2; }
ref=$(mktemp -d "${TMPDIR:-/tmp}/mutants.XXXXXX") || exit 2
trap 'rm -rf "$ref"' EXIT

build_pt='cc -O2 -std=c99 -o t tests/test_pt.c scene.c image.c cli.c kdtree.c bvh.c grid.c photons.c -lm || exit 3'
build_whitted='cc -O2 -std=c99 -o t tests/test_ray.c scene.c image.c cli.c kdtree.c bvh.c grid.c photons.c -lm || exit 3'
build_light='cc -O2 -std=c99 -o t tests/test_light.c scene.c image.c cli.c kdtree.c bvh.c grid.c photons.c -lm || exit 3'
build_accel='cc -O2 -o t tests/test_accel.c kdtree.c bvh.c grid.c -lm || exit 3; make -s ray tools/spd >/dev/null 2>&1 || exit 3'
scenes='same mesh grid thirds tenths soup flat empty one'

# the shell text of a command's tests: exits non-zero when a check fails
tests_of() {
  case $1 in
    pt) echo "$build_pt; ./t >out 2>&1 || echo \"FAIL tests/test_pt.c exited \$?\" >>out; ! grep '^FAIL' out" ;;
    whitted) echo "$build_whitted; TMP=. ./t >out 2>&1 || echo \"FAIL tests/test_ray.c exited \$?\" >>out; ! grep '^FAIL' out" ;;
    lighttrace) echo "make -s ray >/dev/null 2>&1 || exit 3; bash tests/lighttrace.test.sh >out 2>&1 || echo 'FAIL tests/lighttrace.test.sh exited' >>out; ! grep '^FAIL' out" ;;
    bdpt) echo "make -s ray >/dev/null 2>&1 || exit 3; bash tests/bdpt.test.sh >out 2>&1 || echo 'FAIL tests/bdpt.test.sh exited' >>out; ! grep '^FAIL' out" ;;
    photon) echo "make -s ray >/dev/null 2>&1 || exit 3; bash tests/photons.test.sh >out 2>&1 || echo 'FAIL tests/photons.test.sh exited' >>out; ! grep '^FAIL' out" ;;
    light) echo "make -s ray >/dev/null 2>&1 || exit 3; bash tests/light.test.sh >out 2>&1 || echo 'FAIL tests/light.test.sh exited' >>out; ! grep '^FAIL' out" ;;
    kdbuild) echo "bash tests/kdbuild.test.sh >out 2>&1 || echo 'FAIL tests/kdbuild.test.sh exited' >>out; ! grep '^FAIL' out" ;;
    bvhbuild) echo "bash tests/bvhbuild.test.sh >out 2>&1 || echo 'FAIL tests/bvhbuild.test.sh exited' >>out; ! grep '^FAIL' out" ;;
    bvh|grid)
      local structs=$1; [ "$1" = bvh ] && structs='bvh-sah bvh-median'
      echo "$build_accel; for a in $structs; do for s in $scenes; do
              ACCEL_RAYS=50000 ./t \$a \$s >>out 2>&1 || echo \"FAIL test_accel \$a \$s exited \$?\" >>out; done; done;
            bash tests/counts.test.sh >>out 2>&1; ! grep '^FAIL' out" ;;
    *) return 1 ;;
  esac
}

# the shell text of a command's probe: prints what the tree computes
probe_of() {
  case $1 in
    pt) echo "$build_pt; make -s ray >/dev/null 2>&1 || exit 3; ./t;
              for f in cornell veach caustic smallpt bleed whitted minray mesh; do for e in bsdf nee mis; do
                ./ray --pt -t 1 -s 24x16 -n 4 --estimator \$e -o p.pfm scenes/\$f.sph 2>/dev/null; echo \$f \$e; cksum <p.pfm;
              done; done" ;;
    whitted) echo "$build_whitted; make -s ray >/dev/null 2>&1 || exit 3; TMP=. ./t 2>&1;
              for f in whitted mesh minray lights100 soft demo; do for g in '' --gamma; do
                ls scenes/\$f.* | head -1 | xargs ./ray --whitted -t 1 -s 32x24 -n 2 \$g -o p.pfm 2>/dev/null; echo \$f \$g; cksum <p.pfm;
              done; done" ;;
    lighttrace) echo "make -s ray >/dev/null 2>&1 || exit 3;
              for f in cornell lamp soft veach caustic; do
                ./ray --pt -t 1 -s 24x16 -n 8 --estimator light -o p.pfm scenes/\$f.sph 2>/dev/null; echo \$f; cksum <p.pfm;
              done" ;;
    bdpt) echo "make -s ray >/dev/null 2>&1 || exit 3;
              for f in cornell lamp soft glossy caustic; do
                ./ray --pt -t 1 -s 24x16 -n 8 --estimator bdpt -o p.pfm scenes/\$f.sph 2>/dev/null; echo \$f; cksum <p.pfm;
              done" ;;
    photon) echo "make -s ray >/dev/null 2>&1 || exit 3;
              for f in cornell soft caustic; do
                ./ray --pt -t 1 -s 24x16 -n 4 --photons 20000 --estimator photon -o p.pfm scenes/\$f.sph 2>/dev/null; echo \$f; cksum <p.pfm;
                ./ray --pt -t 1 -s 24x16 -n 8 --estimator ppm -o p.pfm scenes/\$f.sph 2>/dev/null; echo \$f ppm; cksum <p.pfm;
                ./ray --pt -t 1 -s 24x16 -n 1 --photons 5000 --estimator photon --view photons -o p.pfm scenes/\$f.sph 2>/dev/null; echo \$f dots; cksum <p.pfm;
              done" ;;
    light) echo "$build_light; make -s ray >/dev/null 2>&1 || exit 3; ./t . | sed 's/[0-9][0-9.]* s\\b//';
              for f in lights100 cornell veach lamp soft; do for c in importance power; do
                ./ray --pt -t 1 -s 24x16 -n 4 --light-choice \$c -o p.pfm scenes/\$f.sph 2>/dev/null; echo \$f \$c; cksum <p.pfm;
              done; done" ;;
    kdbuild) echo "bash tests/kdbuild.test.sh 2>&1 | sed 's/[0-9][0-9.]* s\\b//'" ;;
    bvhbuild) echo "bash tests/bvhbuild.test.sh 2>&1" ;;
    bvh|grid)
      local structs=$1 accel=$1; [ "$1" = bvh ] && structs='bvh-sah bvh-median'
      echo "$build_accel; for a in $structs; do for s in $scenes; do ACCEL_RAYS=50000 ./t \$a \$s 2>&1; done; done |
              sed -e 's/[0-9.]* s;/s;/' -e 's/built in [0-9.]* s/built/';
            for d in balls:4 gears:4 mount:6 rings:7 teapot:6 tetra:6 tree:11; do tools/spd \${d%:*} \${d#*:} >\${d%:*}.nff; done;
            for f in balls.nff gears.nff mount.nff rings.nff teapot.nff tetra.nff tree.nff scenes/whitted.sph scenes/minray.sph \
                     scenes/mesh.sph scenes/demo.nff scenes/cornell.sph scenes/smallpt.sph scenes/caustic.sph scenes/bleed.sph; do
              ./ray --accel $accel -t 1 -s 32x32 -n 1 --stats -o p.ppm \$f 2>&1 >/dev/null | grep -E '^(rays|hits|per ray|samples) ';
              echo \$f; cksum <p.ppm;
            done" ;;
  esac
}

# a comment-only change to FILE: the unmutated tree, as mutate.sh copies it
noop() {
  local file=$1 line
  line=$(grep -m 1 '^/\* ' "$file") || return 1
  printf '%s\n' "$line"
}

caught=0 missed=0 equivalent=0 stillborn=0 n=0
while IFS= read -r line; do
  case $line in ''|'#'*) continue ;; esac
  n=$((n + 1))
  [ "$n" -ge "$first" ] && [ "$n" -le "$last" ] || continue
  # four fields, split on " | "
  rest=$line
  file=${rest%% | *}; rest=${rest#* | }
  old=${rest%% | *}; rest=${rest#* | }
  new=${rest%% | *}; rest=${rest#* | }
  cmd=$rest
  case $cmd in *' | '*) echo "mutants.sh: line $n has more than four fields: $line" >&2; exit 2 ;; esac
  [ -n "$file" ] && [ -n "$old" ] && [ -n "$cmd" ] && [ "$file" != "$line" ] ||
    { echo "mutants.sh: line $n is not FILE | OLD | NEW | COMMAND: $line" >&2; exit 2; }
  tests=$(tests_of "$cmd") || { echo "mutants.sh: line $n: no command $cmd" >&2; exit 2; }
  out=$(tools/mutate.sh "$file" "$old" "$new" -- timeout 600 sh -c "$tests" 2>&1)
  rc=$?
  [ "$rc" = 2 ] && { echo "mutants.sh: line $n: $out" >&2; exit 2; }
  if [ "$rc" = 0 ]; then
    if printf '%s\n' "$out" | head -n 1 | grep -q '(exit 3)$'; then
      result="does not build"; stillborn=$((stillborn + 1))
    else
      why=$(printf '%s\n' "$out" | sed -n 2p | sed 's/^ *//; s/^FAIL //' | cut -c1-160)
      result="caught ($why)"; caught=$((caught + 1))
    fi
  else
    # the probe of the unmutated tree, once per command and file
    key=$cmd.$(echo "$file" | tr / _)
    if [ ! -f "$ref/$key" ]; then
      c=$(noop "$file") || { echo "mutants.sh: $file has no comment to change" >&2; exit 2; }
      tools/mutate.sh "$file" "$c" "$c " -- sh -c "( $(probe_of "$cmd") ) >'$ref/$key' 2>&1; true" >/dev/null
    fi
    if tools/mutate.sh "$file" "$old" "$new" -- \
         timeout 600 sh -c "( $(probe_of "$cmd") ) 2>&1 | cmp -s - '$ref/$key'" >/dev/null; then
      result="MISSED, changes a result"; missed=$((missed + 1))
    else
      result="MISSED, equivalent"; equivalent=$((equivalent + 1))
    fi
  fi
  echo "$file | $old | $new | $cmd | $result"
done <"$list"
score=$( [ $((caught + missed)) -gt 0 ] && awk -v c=$caught -v m=$missed 'BEGIN { printf "%.1f%%", 100 * c / (c + m) }' || echo "-")
echo "$((caught + missed + equivalent + stillborn)) mutants: $caught caught, $missed missed that change a result," \
     "$equivalent equivalent, $stillborn do not build; score $caught/$((caught + missed)) = $score"

#!/usr/bin/env bash
# The test driver behind `make test`.
# Every tests/*.test.sh is run from the repository root.  A test script
# prints one line per check, starting with "PASS ", "FAIL " or "SKIP " (a
# check this machine cannot run, with why).  A script that exits non-zero
# without printing a FAIL line counts as one failure, so a crash can never
# look like success.  The last line is "N passed, N failed, N skipped".
cd "$(dirname "$0")/.." || exit 2
# The scripts run side by side, TEST_JOBS at a time (default: one per
# core), the longest first.  Each result line is printed as it comes,
# after the name of its script; when all are done, the failures are
# listed again under the summary, in the scripts' own order.
jobs=${TEST_JOBS:-$(nproc 2>/dev/null || echo 2)}
out=$(mktemp -d "${TMPDIR:-/tmp}/testrun.XXXXXX")
trap 'rm -rf "$out"' EXIT
# The parts every test program links beside ray.c (RAY_PARTS: scene.c,
# image.c, ...) are compiled here once, not once a program; if one does
# not compile, the scripts get the sources and say so themselves.
CC=${CC:-cc} CFLAGS=${CFLAGS:--O2}
parts=${RAY_PARTS:-$(bash -c '. tests/lib.sh; echo $RAY_PARTS')}
mkdir "$out/parts"
objs='' pids=''
for c in $parts; do
  o=$out/parts/$(basename "${c%.c}").o
  # shellcheck disable=SC2086 # CFLAGS holds several words
  $CC $CFLAGS -std=c99 -c -o "$o" "$c" 2>/dev/null &
  objs="$objs $o" pids="$pids $!"
done
built=1
for p in $pids; do wait "$p" || built=0; done
export RAY_SOURCES="$parts"
[ $built = 1 ] && export RAY_PARTS="${objs# }"
longest_first="tests/photons.test.sh tests/pt.test.sh tests/ray.test.sh tests/accel.test.sh tests/bdpt.test.sh tests/light.test.sh tests/kdbuild.test.sh tests/split.test.sh tests/motion.test.sh tests/sampler.test.sh tests/dist.test.sh tests/io.test.sh tests/hooks.test.sh tests/golf.test.sh"
scripts=$longest_first
for t in tests/*.test.sh; do
  case " $longest_first " in *" $t "*) ;; *) scripts="$scripts $t";; esac
done
for t in $scripts; do
  while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do wait -n 2>/dev/null || sleep 0.1; done
  n=$(basename "$t" .test.sh)
  ( bash "$t" 2>&1 | tee "$out/$n.out" | grep --line-buffered -E '^(PASS|FAIL|SKIP) ' | sed -u "s|^|$n: |"
    echo "${PIPESTATUS[0]}" >"$out/$n.rc" ) &
done
wait
pass=0 fail=0 skipped=0
for t in tests/*.test.sh; do
  n=$(basename "$t" .test.sh)
  rc=$(cat "$out/$n.rc")
  grep -E '^FAIL ' "$out/$n.out" | sed "s|^|$n: |" >>"$out/failures"
  p=$(grep -c '^PASS ' "$out/$n.out")
  f=$(grep -c '^FAIL ' "$out/$n.out")
  k=$(grep -c '^SKIP ' "$out/$n.out")
  if [ "$rc" != 0 ] && [ "$f" = 0 ]; then
    { echo "$n: FAIL script exited $rc; its last lines:"
      tail -n 5 "$out/$n.out" | sed 's/^/    /'; } >>"$out/failures"
    f=1
  fi
  pass=$((pass + p)) fail=$((fail + f)) skipped=$((skipped + k))
done
if [ -s "$out/failures" ]; then echo; echo "failed:"; cat "$out/failures"; fi
echo "$pass passed, $fail failed, $skipped skipped"
[ "$fail" = 0 ]

#!/usr/bin/env bash
# The test driver behind `make test`.
# Every tests/*.test.sh is run in turn from the repository root.  A test script
# prints one line per check, starting with "PASS " or "FAIL ".  A script that
# exits non-zero without printing a FAIL line counts as one failure, so a
# crash can never look like success.  The last line is "N passed, N failed".
cd "$(dirname "$0")/.." || exit 2
pass=0 fail=0
for t in tests/*.test.sh; do
  out=$(bash "$t" 2>&1); rc=$?
  printf '%s\n' "$out" | grep -E '^(PASS|FAIL) ' | sed "s|^|$(basename "$t" .test.sh): |"
  p=$(printf '%s\n' "$out" | grep -c '^PASS ')
  f=$(printf '%s\n' "$out" | grep -c '^FAIL ')
  if [ "$rc" != 0 ] && [ "$f" = 0 ]; then
    echo "$(basename "$t" .test.sh): FAIL script exited $rc; its last lines:"
    printf '%s\n' "$out" | tail -n 5 | sed 's/^/    /'
    f=1
  fi
  pass=$((pass + p)) fail=$((fail + f))
done
echo "$pass passed, $fail failed"
[ "$fail" = 0 ]

# tests/run.sh itself: in a tree of four made-up scripts (one passes, one
# skips and says why, one fails, one crashes without a FAIL line) it prints
# each line under its script's name and ends "1 passed, 2 failed, 1 skipped".
. tests/lib.sh
mkdir -p "$TMP/tree/tests"
cp tests/run.sh "$TMP/tree/tests/"
printf 'echo "PASS one"\n' >"$TMP/tree/tests/a.test.sh"
printf 'echo "SKIP two: no such tool here"\n' >"$TMP/tree/tests/b.test.sh"
printf 'echo "FAIL three"\n' >"$TMP/tree/tests/c.test.sh"
printf 'echo "about to crash"; exit 3\n' >"$TMP/tree/tests/d.test.sh"
out=$(TEST_JOBS=2 bash "$TMP/tree/tests/run.sh" 2>&1)
if [ "$(printf '%s\n' "$out" | tail -n 1)" = "1 passed, 2 failed, 1 skipped" ] \
   && printf '%s\n' "$out" | grep -q '^b: SKIP two: no such tool here$' \
   && printf '%s\n' "$out" | grep -q '^d: FAIL script exited 3'; then
  ok "tests/run.sh counts passes, failures, skips (with why) and a crash: 1 passed, 2 failed, 1 skipped"
else
  bad "tests/run.sh's summary: $(printf '%s\n' "$out" | tr '\n' '|')"
fi

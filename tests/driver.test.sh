# tests/run.sh itself: in a tree of four made-up scripts (one passes, one
# skips and says why, one fails, one crashes without a FAIL line) it prints
# each line under its script's name and ends "1 passed, 2 failed, 1 skipped";
# and it prints a line as it comes, not when its script ends.
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

# Lines as they come: a script prints a PASS line and then waits until the
# line has reached run.sh's output (or 20 s pass); the test waits 10 s for
# the line, so it sees it only if run.sh passes it on before the script ends.
mkdir -p "$TMP/live/tests"
cp tests/run.sh "$TMP/live/tests/"
printf 'echo "PASS early"; i=0; while [ ! -e "%s" ] && [ $i -lt 200 ]; do sleep 0.1; i=$((i+1)); done\n' \
  "$TMP/go" >"$TMP/live/tests/e.test.sh"
bash "$TMP/live/tests/run.sh" >"$TMP/live.out" 2>&1 &
i=0
while ! grep -q '^e: PASS early$' "$TMP/live.out" && [ $i -lt 100 ]; do sleep 0.1; i=$((i+1)); done
grep -q '^e: PASS early$' "$TMP/live.out" && seen=1 || seen=0
touch "$TMP/go"
wait
[ $seen = 1 ] && ok "tests/run.sh prints a result line while its script still runs" \
  || bad "tests/run.sh held back a line until its script ended: $(tr '\n' '|' <"$TMP/live.out")"

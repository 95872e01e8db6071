# render()'s hooks (tests/test_hooks.c): a pre-pass, and a splat image that
# is the same bits for any number of threads (built with OpenMP where the
# compiler has it, so that the threads are real).
. tests/lib.sh
OMP=$(echo 'int main(void){return 0;}' | $CC -fopenmp -x c - -o /dev/null 2>/dev/null && echo -fopenmp)
# shellcheck disable=SC2086 # CFLAGS and RAY_PARTS hold several words
$CC $CFLAGS $OMP -std=c99 -o "$TMP/test_hooks" tests/test_hooks.c $RAY_PARTS -lm || { bad "tests/test_hooks.c compiles"; exit 1; }
[ -n "$OMP" ] && ok "tests/test_hooks.c builds with OpenMP" || echo "tests/test_hooks.c: no OpenMP here, one thread"
"$TMP/test_hooks"

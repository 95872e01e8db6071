/* check.h - one PASS or FAIL line a check, for tests/run.sh, flushed so
 * that a crash later loses none; failures counts the FAILs for main()'s
 * exit status. */
#include <stdio.h>

static int failures;

static void check(int ok, const char *name)
{
    printf("%s %s\n", ok ? "PASS" : "FAIL", name);
    fflush(stdout);
    failures += !ok;
}

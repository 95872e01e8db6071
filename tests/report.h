/* report.h - one "PASS name (figures)" or "FAIL name (figures)" line a
 * check, for tests/run.sh, flushed so that a crash later loses none; the
 * figures say what was measured against what.  failures counts the FAILs
 * for main()'s exit status. */
#include <stdarg.h>
#include <stdio.h>

static int failures;

static void report(int ok, const char *name, const char *fmt, ...)
{
    va_list ap;
    printf("%s %s (", ok ? "PASS" : "FAIL", name);
    va_start(ap, fmt);
    vprintf(fmt, ap);
    va_end(ap);
    printf(")\n");
    fflush(stdout);
    failures += !ok;
}

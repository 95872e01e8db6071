/* bench/table.c: the arithmetic of bench/run.sh's tables, which the shell
 * runs and times.  C99, libc and libm.  Numbers come as arguments (lists
 * may be one argument of words, as the shell's "$t_double" is) or, for the
 * raybench readers, from the log named.
 *
 *   table spread V...       "least median greatest" (the median of an even
 *                           count: the mean of the two in the middle)
 *   table median V...       the median
 *   table range FMT V...    "least-greatest", each in FMT (%.2f and the like)
 *   table ratios "A..." "B..."  A1/B1 A2/B2 ..., the pairs' ratios (as many
 *                           as there are pairs; a pair whose B is not above
 *                           0 is left out)
 *   table accel LOG SCENE   the accel section's rows from raybench accel's
 *                           result lines, of one run or of several: the best
 *                           of the runs' best rounds, the median of their
 *                           medians, the worst of their worst; the build,
 *                           the median of the runs'
 *   table best LOG SET      the greatest median Mrays/s of raybench accel's
 *                           structures on SET, none and the recursive forms
 *                           aside
 *   table far LOG           raybench far: the lowest ratio of any structure,
 *                           then "accel ratio, ..." (each structure's lowest,
 *                           by name), then "DIFFER" when an answer differed
 *   table fit               lines "KEY X Y" on standard input: per KEY of
 *                           two points or more, "KEY slope", the least-squares
 *                           slope of log Y against log X, by KEY
 *
 * Numbers are printed as awk prints them (the bench read them so before):
 * a value read is echoed as written, a value computed as %.6g (an integral
 * one as an integer).  Exit status 1 when there is nothing to print, 2 on a
 * usage error. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAXV 4096
#define MAXA 64
#define MAXR 256
#define LINE 8192

static void usage(void)
{
    fputs("usage: table spread|median V... | range FMT V... | ratios \"A...\" \"B...\" |"
          " accel LOG SCENE | best LOG SET | far LOG | fit\n", stderr);
    exit(2);
}

/* A number as awk's print shows a computed one. */
static void put_num(double x)
{
    if (x == floor(x) && fabs(x) < 1e15) printf("%.0f", x);
    else printf("%.6g", x);
}

typedef struct { const char *s; double v; } Val;

static int by_value(const void *a, const void *b)
{
    const Val *x = a, *y = b;
    return x->v < y->v ? -1 : x->v > y->v ? 1 : strcmp(x->s, y->s);
}

/* The words of args into v, at most MAXV; returns how many. */
static int words(char **args, int n, Val *v, int max)
{
    static char buf[1 << 16];
    static size_t used;
    int i, k = 0;
    for (i = 0; i < n; i++) {
        size_t len = strlen(args[i]) + 1;
        char *w, *copy;
        if (used + len > sizeof buf) break;
        copy = memcpy(buf + used, args[i], len);
        used += len;
        for (w = strtok(copy, " \t\n"); w && k < max; w = strtok(NULL, " \t\n"))
            v[k].s = w, v[k].v = strtod(w, NULL), k++;
    }
    return k;
}

/* Sorts the values; the median's text into med (a value echoed, or the mean
 * of the middle two, computed). */
static int spread(char **args, int n, Val *v, char *med, size_t size)
{
    int k = words(args, n, v, MAXV);
    if (!k) return 0;
    qsort(v, k, sizeof *v, by_value);
    if (k % 2) snprintf(med, size, "%s", v[k / 2].s);
    else {
        double m = (v[k / 2 - 1].v + v[k / 2].v) / 2;
        if (m == floor(m) && fabs(m) < 1e15) snprintf(med, size, "%.0f", m);
        else snprintf(med, size, "%.6g", m);
    }
    return k;
}

/* FMT of range: one conversion of a double, nothing else. */
static int number_format(const char *f)
{
    if (*f++ != '%') return 0;
    f += strspn(f, "0123456789.");
    return strchr("feEgG", *f) && *f && !f[1];
}

static double median_of(double *x, int n)
{
    int i, j;
    for (i = 1; i < n; i++)
        for (j = i; j > 0 && x[j - 1] > x[j]; j--) { double t = x[j]; x[j] = x[j - 1]; x[j - 1] = t; }
    if (!n) return 0;
    return n % 2 ? x[n / 2] : (x[n / 2 - 1] + x[n / 2]) / 2;
}

/* A raybench result line's key=value fields, from the second on. */
typedef struct { int n; char *key[64], *val[64]; } Fields;

static int fields(char *line, Fields *f)
{
    char *w = strtok(line, " \t\n");
    f->n = 0;
    if (!w || strcmp(w, "result")) return 0;
    while ((w = strtok(NULL, " \t\n")) && f->n < 64) {
        char *eq = strchr(w, '=');
        f->key[f->n] = w;
        f->val[f->n] = "";
        if (eq) *eq = 0, f->val[f->n] = eq + 1;
        f->n++;
    }
    return 1;
}

static const char *get(const Fields *f, const char *key)
{
    int i;
    const char *v = "";
    for (i = 0; i < f->n; i++) if (!strcmp(f->key[i], key)) v = f->val[i];
    return v;
}

static FILE *open_log(const char *path)
{
    FILE *in = fopen(path, "r");
    if (!in) { perror(path); exit(2); }
    return in;
}

/* table accel LOG SCENE */
typedef struct {
    char name[64], work[2][32], bad[256];
    double bytes, best[2], worst[2], build[MAXR], med[2][MAXR];
    int seen[2], nb, nm[2];
} Accel;

static int accel(const char *path, const char *scene)
{
    static Accel a[MAXA];
    char line[LINE];
    int m = 0, q, s;
    FILE *in = open_log(path);
    while (fgets(line, sizeof line, in)) {
        Fields f;
        const char *name, *set, *differ;
        Accel *p = NULL;
        char *w3;
        if (strncmp(line, "result ", 7)) continue;
        /* the third word begins accel= */
        w3 = strchr(line + 7, ' ');
        if (!w3 || strncmp(w3 + 1, "accel=", 6)) continue;
        fields(line, &f);
        name = get(&f, "accel"), set = get(&f, "set");
        for (q = 0; q < m; q++) if (!strcmp(a[q].name, name)) p = &a[q];
        if (!p) {
            if (m == MAXA) continue;
            p = &a[m++];
            memset(p, 0, sizeof *p);
            snprintf(p->name, sizeof p->name, "%s", name);
            p->bytes = strtod(get(&f, "bytes"), NULL);
        }
        differ = get(&f, "differ");
        if (*differ && strtod(differ, NULL) > 0) {
            size_t len = strlen(p->bad);
            snprintf(p->bad + len, sizeof p->bad - len, " %s:%s", set, differ);
        }
        s = strcmp(set, "random") == 0;
        if (!s && strcmp(set, "primary")) continue;   /* only the two sets are printed */
        if (!s && p->nb < MAXR) p->build[p->nb++] = strtod(get(&f, "build_s"), NULL);
        if (p->nm[s] < MAXR) p->med[s][p->nm[s]++] = strtod(get(&f, "median"), NULL);
        if (!p->seen[s] || strtod(get(&f, "best"), NULL) > p->best[s]) p->best[s] = strtod(get(&f, "best"), NULL);
        if (!p->seen[s] || strtod(get(&f, "worst"), NULL) < p->worst[s]) p->worst[s] = strtod(get(&f, "worst"), NULL);
        p->seen[s] = 1;
        snprintf(p->work[s], sizeof p->work[s], "%5.1f %5.1f", strtod(get(&f, "steps"), NULL),
                 strtod(get(&f, "tests"), NULL));
    }
    fclose(in);
    for (q = 0; q < m; q++) {
        Accel *p = &a[q];
        printf("%-11s %-10s %8.4f %7.2f ", scene, p->name, median_of(p->build, p->nb), p->bytes / 1e6);
        for (s = 0; s < 2; s++)
            printf(" %6.2f %6.2f %6.2f ", p->best[s], median_of(p->med[s], p->nm[s]), p->worst[s]);
        printf(" %s  %s  %s%s\n", p->work[0], p->work[1], p->bad[0] ? "DIFFER" : "same", p->bad);
    }
    return m > 0;
}

/* table best LOG SET */
static int best(const char *path, const char *set)
{
    char line[LINE];
    double m = 0;
    int any = 0;
    FILE *in = open_log(path);
    while (fgets(line, sizeof line, in)) {
        Fields f;
        if (!fields(line, &f) || f.n < 2 || strcmp(f.key[0], "set") || strcmp(f.val[0], set)) continue;
        if (strstr(f.val[1], "none") || strstr(f.val[1], "rec") || strstr(f.key[1], "none") || strstr(f.key[1], "rec"))
            continue;
        {
            int i;
            for (i = 2; i < f.n; i++)
                if (!strcmp(f.key[i], "median") && strtod(f.val[i], NULL) > m) m = strtod(f.val[i], NULL), any = 1;
        }
    }
    fclose(in);
    if (any) put_num(m);
    putchar('\n');
    return 1;
}

/* table far LOG */
static int by_name(const void *a, const void *b)
{
    return strcmp(((const Accel *)a)->name, ((const Accel *)b)->name);
}

static int far(const char *path)
{
    static Accel a[MAXA];
    char line[LINE];
    int m = 0, q, bad = 0;
    double low = 0;
    FILE *in = open_log(path);
    while (fgets(line, sizeof line, in)) {
        Fields f;
        Accel *p = NULL;
        const char *name;
        double r;
        if (!fields(line, &f) || (f.n && !strcmp(f.key[0], "far") && !strcmp(f.val[0], "origin"))) continue;
        name = get(&f, "accel"), r = strtod(get(&f, "ratio"), NULL);
        if (strtod(get(&f, "differ"), NULL) != 0) bad = 1;
        for (q = 0; q < m; q++) if (!strcmp(a[q].name, name)) p = &a[q];
        if (!p) {
            if (m == MAXA) continue;
            p = &a[m++];
            snprintf(p->name, sizeof p->name, "%s", name);
            p->best[0] = r;
        }
        if (r < p->best[0]) p->best[0] = r;
    }
    fclose(in);
    qsort(a, m, sizeof *a, by_name);
    /* the ratios as printed (%.2f), the lowest of those */
    for (q = 0; q < m; q++) {
        char t[32];
        snprintf(t, sizeof t, "%.2f", a[q].best[0]);
        if (!q || strtod(t, NULL) < low) low = strtod(t, NULL);
    }
    if (m) printf("%.2f", low);
    putchar('\n');
    for (q = 0; q < m; q++) printf("%s%s %.2f", q ? ", " : "", a[q].name, a[q].best[0]);
    printf("\n%s\n", bad ? "DIFFER" : "");
    return 1;
}

/* table fit */
typedef struct { char key[128]; int n; double sx, sy, sxx, sxy; } Fit;

static int by_key(const void *a, const void *b)
{
    return strcmp(((const Fit *)a)->key, ((const Fit *)b)->key);
}

static int fit(void)
{
    static Fit f[MAXA];
    char key[128];
    double x, y;
    int m = 0, q;
    while (scanf("%127s %lf %lf", key, &x, &y) == 3) {
        Fit *p = NULL;
        for (q = 0; q < m; q++) if (!strcmp(f[q].key, key)) p = &f[q];
        if (!p) {
            if (m == MAXA) continue;
            p = &f[m++];
            snprintf(p->key, sizeof p->key, "%s", key);
        }
        x = log(x), y = log(y);
        p->n++, p->sx += x, p->sy += y, p->sxx += x * x, p->sxy += x * y;
    }
    qsort(f, m, sizeof *f, by_key);
    for (q = 0; q < m; q++)
        if (f[q].n > 1)
            printf("%s %.2f\n", f[q].key, (f[q].n * f[q].sxy - f[q].sx * f[q].sy) /
                   (f[q].n * f[q].sxx - f[q].sx * f[q].sx));
    return 1;
}

int main(int argc, char **argv)
{
    static Val v[MAXV], w[MAXV];
    char med[64];
    const char *cmd;
    int n, k, i;
    if (argc < 2) usage();
    cmd = argv[1];
    if (!strcmp(cmd, "spread") || !strcmp(cmd, "median")) {
        if (!(n = spread(argv + 2, argc - 2, v, med, sizeof med))) return 1;
        if (cmd[0] == 'm') printf("%s\n", med);
        else printf("%s %s %s\n", v[0].s, med, v[n - 1].s);
    } else if (!strcmp(cmd, "range")) {
        if (argc < 3 || !number_format(argv[2])) usage();
        if (!(n = spread(argv + 3, argc - 3, v, med, sizeof med))) return 1;
        printf(argv[2], v[0].v);
        putchar('-');
        printf(argv[2], v[n - 1].v);
    } else if (!strcmp(cmd, "ratios")) {
        if (argc != 4) usage();
        n = words(argv + 2, 1, v, MAXV);
        k = words(argv + 3, 1, w, MAXV);
        for (i = 0; i < n && i < k; i++)
            if (w[i].v > 0) printf("%.6g ", v[i].v / w[i].v);
    } else if (!strcmp(cmd, "accel")) {
        if (argc != 4) usage();
        return !accel(argv[2], argv[3]);
    } else if (!strcmp(cmd, "best")) {
        if (argc != 4) usage();
        return !best(argv[2], argv[3]);
    } else if (!strcmp(cmd, "fit")) {
        return !fit();
    } else if (!strcmp(cmd, "far")) {
        if (argc != 3) usage();
        return !far(argv[2]);
    } else
        usage();
    return 0;
}

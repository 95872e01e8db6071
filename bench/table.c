/* bench/table.c: the arithmetic of bench/run.sh's and bench/pt.sh's
 * tables, and the readers of our own programs' logs; the shell runs and
 * times.  C99, libc and libm.  Numbers come as arguments (lists may be one
 * argument of words, as the shell's "$t_double" is) or from the file named.
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
 *
 * Readers of the logs:
 *   table kv LOG KEY        KEY's value in a log of ./ray --stats=kv ("key
 *                           value" lines), the first
 *   table field LOG SEL KEY KEY's value on raybench's "result" lines, the
 *                           last; SEL: "" every line, "set=primary" lines whose
 *                           second word is that, "exponent" lines whose second
 *                           word is exponent=...
 *   table values LOG SEL KEY  every one of them, "V V ... " (one a round)
 *   table disagree LOG SET  the rays section's summary of raybench's hits
 *                           against Embree's on SET: "D of N hits (...)"
 *   table build LOG ACCEL   the build_s of the first result line of ACCEL
 *
 * Arithmetic, each named for what it computes:
 *   table greatest V...     the greatest
 *   table ratio FMT A B     A/B in FMT (nothing when B is not above 0)
 *   table us-per SECONDS N [FMT]  microseconds per one of N (a ray, a
 *                           sample), FMT %.6g by default
 *   table mrays RAYS SECONDS  millions of rays per second, %.4f
 *   table setup WHOLE RENDER  a run's seconds outside the render, %.4f
 *   table verdict A OP B    "met" when A OP B (OP: < <= > >=), else "NOT MET"
 *                           (also when A or B is not a number)
 *   table repeats FIRST SPP SPP0  how many turns a render at SPP samples gets
 *                           (5 when its time, FIRST's at SPP0 scaled, is under
 *                           half a second; else 3)
 *   table more FIRST SPP0 SUM REF  the render section's expected further CPU
 *                           seconds of a scene (FIRST at SPP0 spp, then 6 runs
 *                           at every count, SUM of them, and the reference at
 *                           REF), %.0f, when over 240; else nothing
 *   table flake-cost WHOLE RENDER RUNS SIDE SUM REF  the sphereflake's CPU
 *                           seconds at SIDE x SIDE judged from a 128x128 probe
 *                           (WHOLE seconds, RENDER of them the render's): RUNS
 *                           start-ups and the renders' scaled pixels, %.0f
 *   table spd-side T16 BUDGET  the spd section's image side: the largest of
 *                           96 64 48 32 24 whose brute force, from T16 at
 *                           16x16, fits BUDGET seconds, else 16
 *   table kd-spp SECONDS    samples per pixel to make a render of SECONDS at
 *                           one long enough to time: 1 from 0.05 s, else
 *                           0.1 s' worth and one more, at most 64
 *
 * Tables of the bench's own files (tab-separated):
 *   table render TSV        the render section's rows, of bench.tsv
 *   table render-plot TSV   its plot's points, "scene/build seconds RMSE spp"
 *   table pt-slopes TSV     of pt.tsv: per scene/estimator, "KEY slope", the
 *                           least-squares slope of log RMSE against log CPU
 *                           time (runs under 0.05 s left out), by KEY
 *   table pt-plot TSV       the plot's points, "KEY,slope=S seconds RMSE spp"
 *   table time-at TSV SCENE EST RMSE ROUND  EST's CPU time at RMSE on SCENE
 *                           by log-log interpolation between its two
 *                           bracketing runs (ROUND 1, 2, ...: that round's
 *                           times; 0: the medians), %.4f; "<T" when its
 *                           cheapest run is already below; empty when never
 *                           reached
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
    fputs("usage: table SUBCOMMAND ARGS... (the list at the top of bench/table.c)\n", stderr);
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

/* A number as awk reads one: all of the text (blanks around aside). */
static int is_num(const char *s, double *x)
{
    char *end;
    double v = strtod(s, &end);
    if (end == s) return 0;
    end += strspn(end, " \t\n");
    if (*end) return 0;
    if (x) *x = v;
    return 1;
}

/* table kv LOG KEY */
static int kv(const char *path, const char *key)
{
    char line[LINE];
    FILE *in = open_log(path);
    while (fgets(line, sizeof line, in)) {
        char *k = strtok(line, " \t\n"), *v = strtok(NULL, " \t\n");
        if (k && !strcmp(k, key)) { printf("%s\n", v ? v : ""); break; }
    }
    fclose(in);
    return 1;
}

/* WORD is KEY=...: its value, else NULL. */
static const char *value_of(const char *word, const char *key)
{
    size_t n = strlen(key);
    return !strncmp(word, key, n) && word[n] == '=' ? word + n + 1 : NULL;
}

/* A result line's second word matches SEL (see the top). */
static int selected(const char *w2, const char *sel)
{
    if (!*sel) return 1;
    if (strchr(sel, '=')) return !strcmp(w2, sel);
    return value_of(w2, sel) != NULL;
}

/* table field LOG SEL KEY (every 0), table values LOG SEL KEY (every 1) */
static int field(const char *path, const char *sel, const char *key, int every)
{
    char line[LINE], last[LINE] = "";
    FILE *in = open_log(path);
    while (fgets(line, sizeof line, in)) {
        char *w = strtok(line, " \t\n");
        const char *v;
        if (!w || strcmp(w, "result") || !(w = strtok(NULL, " \t\n")) || !selected(w, sel)) continue;
        for (; w; w = strtok(NULL, " \t\n"))
            if ((v = value_of(w, key))) {
                if (every) printf("%s ", v);
                else snprintf(last, sizeof last, "%s", v);
            }
    }
    fclose(in);
    if (!every) printf("%s\n", last);
    return 1;
}

/* table disagree LOG SET: the counts are kept from line to line, as the
 * awk that read them did. */
static int disagree(const char *path, const char *set)
{
    static const char *names[] = { "disagree", "agree", "tie", "tfloat", "tdiff", "ours_only", "embree_only" };
    static const char *what[] = { 0, 0, " edge/vertex ties", " float t", " other t", " ours only", " Embree only" };
    enum { N = sizeof names / sizeof *names };
    char line[LINE], want[256], v[N][64], last[1024] = "";
    int i;
    FILE *in = open_log(path);
    memset(v, 0, sizeof v);
    snprintf(want, sizeof want, "set=%s", set);
    while (fgets(line, sizeof line, in)) {
        char *w;
        double d, a;
        size_t len;
        if (!strstr(line, "agree=")) continue;
        if (!(w = strtok(line, " \t\n")) || strcmp(w, "result") || !(w = strtok(NULL, " \t\n")) || strcmp(w, want))
            continue;
        while ((w = strtok(NULL, " \t\n"))) {
            char *eq = strchr(w, '='), *val = "";
            if (eq) { *eq = 0; val = eq + 1; if ((eq = strchr(val, '='))) *eq = 0; }
            for (i = 0; i < N; i++) if (!strcmp(w, names[i])) snprintf(v[i], sizeof v[i], "%s", val);
        }
        d = strtod(v[0], NULL), a = strtod(v[1], NULL);
        len = (size_t)snprintf(last, sizeof last, "%s of ", v[0]);
        if (a + d == floor(a + d) && fabs(a + d) < 1e15) len += (size_t)snprintf(last + len, sizeof last - len, "%.0f hits", a + d);
        else len += (size_t)snprintf(last + len, sizeof last - len, "%.6g hits", a + d);
        if (is_num(v[0], NULL) ? d > 0 : strcmp(v[0], "0") > 0) {
            const char *sep = " (";
            for (i = 2; i < N; i++) {
                double x;
                if (!v[i][0] || (is_num(v[i], &x) && x == 0)) continue;
                len += (size_t)snprintf(last + len, sizeof last - len, "%s%s%s", sep, v[i], what[i]);
                sep = ", ";
            }
            if (!strcmp(sep, " (")) len += (size_t)snprintf(last + len, sizeof last - len, " (");
            snprintf(last + len, sizeof last - len, ")");
        }
    }
    fclose(in);
    printf("%s\n", last);
    return 1;
}

/* table build LOG ACCEL */
static int build(const char *path, const char *accel)
{
    char line[LINE], want[256];
    FILE *in = open_log(path);
    snprintf(want, sizeof want, "accel=%s", accel);
    while (fgets(line, sizeof line, in)) {
        char *w = strtok(line, " \t\n");
        const char *v;
        if (!w || strcmp(w, "result") || !strtok(NULL, " \t\n") || !(w = strtok(NULL, " \t\n")) || strcmp(w, want))
            continue;
        while ((w = strtok(NULL, " \t\n")))
            if ((v = value_of(w, "build_s"))) { printf("%s\n", v); fclose(in); return 1; }
    }
    fclose(in);
    return 1;
}

/* The tab-separated fields of a line of the bench's own files. */
typedef struct { int n; char *f[32]; } Row;

static void split_row(char *line, Row *r)
{
    char *p = line;
    line[strcspn(line, "\n")] = 0;
    r->n = 0;
    for (;;) {
        r->f[r->n++] = p;
        if (r->n == 32 || !(p = strchr(p, '\t'))) break;
        *p++ = 0;
    }
    while (r->n < 32) r->f[r->n++] = "";
}

/* Field I (from 1, as awk's $I) of a row. */
#define F(r, i) ((r).f[(i) - 1])

/* table render TSV (plot 0), table render-plot TSV (plot 1) */
static int render(const char *path, int plot)
{
    char line[LINE];
    FILE *in = open_log(path);
    while (fgets(line, sizeof line, in)) {
        Row r;
        char span[96];
        split_row(line, &r);
        if (plot) { printf("%s/%s %s %s %s\n", F(r, 1), F(r, 4), F(r, 6), F(r, 8), F(r, 5)); continue; }
        snprintf(span, sizeof span, "(%.3f-%.3f)", strtod(F(r, 10), NULL), strtod(F(r, 11), NULL));
        printf("%-12s %-9s %7s  %-6s %4s %8.3f %15s %5s %7s %8s %7s\n", F(r, 1), F(r, 2), F(r, 3), F(r, 4),
               F(r, 5), strtod(F(r, 6), NULL), span, F(r, 12), F(r, 7), F(r, 8), F(r, 9));
    }
    fclose(in);
    return 1;
}

/* The slopes of pt.tsv: per scene/estimator, least squares of log RMSE
 * ($6) against log CPU seconds ($5), runs from 0.05 s; by key. */
typedef struct { char key[128], slope[32]; int n; double sx, sy, sxx, sxy; } Fit;

static int by_key(const void *a, const void *b)
{
    return strcmp(((const Fit *)a)->key, ((const Fit *)b)->key);
}

static Fit *find_fit(Fit *f, int m, const char *key)
{
    int q;
    for (q = 0; q < m; q++) if (!strcmp(f[q].key, key)) return &f[q];
    return NULL;
}

static int slopes(const char *path, Fit *f)
{
    char line[LINE], key[128];
    int m = 0, q;
    FILE *in = open_log(path);
    while (fgets(line, sizeof line, in)) {
        Row r;
        Fit *p;
        double x, y;
        split_row(line, &r);
        if (!(strtod(F(r, 5), NULL) >= 0.05)) continue;
        snprintf(key, sizeof key, "%s/%s", F(r, 1), F(r, 3));
        if (!(p = find_fit(f, m, key))) {
            if (m == MAXA) continue;
            p = &f[m++];
            memset(p, 0, sizeof *p);
            snprintf(p->key, sizeof p->key, "%s", key);
        }
        x = log(strtod(F(r, 5), NULL)), y = log(strtod(F(r, 6), NULL));
        p->n++, p->sx += x, p->sy += y, p->sxx += x * x, p->sxy += x * y;
    }
    fclose(in);
    qsort(f, m, sizeof *f, by_key);
    for (q = 0; q < m; q++)
        if (f[q].n > 1)
            snprintf(f[q].slope, sizeof f[q].slope, "%.2f", (f[q].n * f[q].sxy - f[q].sx * f[q].sy) /
                     (f[q].n * f[q].sxx - f[q].sx * f[q].sx));
    return m;
}

/* table pt-slopes TSV (plot 0), table pt-plot TSV (plot 1) */
static int pt(const char *path, int plot)
{
    static Fit f[MAXA];
    char line[LINE], key[128];
    int m = slopes(path, f), q;
    FILE *in;
    if (!plot) {
        for (q = 0; q < m; q++) if (f[q].slope[0]) printf("%s %s\n", f[q].key, f[q].slope);
        return 1;
    }
    in = open_log(path);
    while (fgets(line, sizeof line, in)) {
        Row r;
        Fit *p;
        split_row(line, &r);
        snprintf(key, sizeof key, "%s/%s", F(r, 1), F(r, 3));
        p = find_fit(f, m, key);
        printf("%s,slope=%s %s %s %s\n", key, p ? p->slope : "", F(r, 5), F(r, 6), F(r, 4));
    }
    fclose(in);
    return 1;
}

/* table time-at TSV SCENE EST RMSE ROUND */
static int time_at(const char *path, const char *scene, const char *est, double e, int k)
{
    static char t[MAXR][32];
    static double r[MAXR];
    char line[LINE];
    int n = 0, i;
    FILE *in = open_log(path);
    while (fgets(line, sizeof line, in) && n < MAXR) {
        Row row;
        split_row(line, &row);
        if (strcmp(F(row, 1), scene) || strcmp(F(row, 3), est)) continue;
        if (k) {   /* the K-th of $11's comma-separated times */
            char *c = F(row, 11);
            for (i = 1; i < k && c; i++) if ((c = strchr(c, ','))) c++;
            snprintf(t[n], sizeof t[n], "%.*s", c ? (int)strcspn(c, ",") : 0, c ? c : "");
        } else
            snprintf(t[n], sizeof t[n], "%s", F(row, 5));
        r[n++] = strtod(F(row, 6), NULL);
    }
    fclose(in);
    for (i = 0; i + 1 < n; i++)
        if (r[i] >= e && r[i + 1] <= e) {
            double t0 = strtod(t[i], NULL), lt, s;
            if (t0 == 0 || r[i] == 0) return 1;   /* awk's division by zero: nothing */
            lt = log(strtod(t[i + 1], NULL) / t0);
            if (lt == 0) return 1;
            s = log(r[i + 1] / r[i]) / lt;
            if (s == 0) return 1;
            printf("%.4f", t0 * exp(log(e / r[i]) / s));
            return 1;
        }
    if (n && r[0] <= e) printf("<%s", t[0]);
    else putchar('\n');
    return 1;
}

/* The arithmetic's arguments: numbers, else a usage error. */
static double arg(const char *s)
{
    double x;
    if (!is_num(s, &x)) { fprintf(stderr, "table: not a number: '%s'\n", s); exit(2); }
    return x;
}

static int verdict(const char *a, const char *op, const char *b)
{
    double x, y;
    int met = 0;
    if (is_num(a, &x) && is_num(b, &y)) {
        if (!strcmp(op, "<")) met = x < y;
        else if (!strcmp(op, "<=")) met = x <= y;
        else if (!strcmp(op, ">")) met = x > y;
        else if (!strcmp(op, ">=")) met = x >= y;
        else usage();
    }
    puts(met ? "met" : "NOT MET");
    return 1;
}

/* x as put_num prints it, read back (as awk, printing a value and reading
 * it again, sees it). */
static double as_printed(double x)
{
    char t[64];
    if (x == floor(x) && fabs(x) < 1e15) snprintf(t, sizeof t, "%.0f", x);
    else snprintf(t, sizeof t, "%.6g", x);
    return strtod(t, NULL);
}

/* printf of one number in FMT, checked. */
static void put_fmt(const char *fmt, double x)
{
    if (!number_format(fmt)) usage();
    printf(fmt, x);
    putchar('\n');
}

int main(int argc, char **argv)
{
    static Val v[MAXV], w[MAXV];
    static const struct { const char *name; int args; } cmds[] = {
        { "accel", 2 }, { "best", 2 }, { "far", 1 }, { "kv", 2 }, { "field", 3 }, { "values", 3 },
        { "disagree", 2 }, { "build", 2 }, { "ratio", 3 }, { "mrays", 2 }, { "setup", 2 },
        { "verdict", 3 }, { "repeats", 3 }, { "more", 4 }, { "flake-cost", 6 }, { "spd-side", 2 },
        { "kd-spp", 1 }, { "render", 1 }, { "render-plot", 1 }, { "pt-slopes", 1 }, { "pt-plot", 1 },
        { "time-at", 5 }
    };
    char med[64];
    const char *cmd;
    char **a = argv + 2;
    int n, k, i;
    if (argc < 2) usage();
    cmd = argv[1];
    for (i = 0; i < (int)(sizeof cmds / sizeof *cmds); i++)
        if (!strcmp(cmd, cmds[i].name) && argc - 2 != cmds[i].args) usage();
    if (!strcmp(cmd, "spread") || !strcmp(cmd, "median") || !strcmp(cmd, "greatest")) {
        if (!(n = spread(a, argc - 2, v, med, sizeof med))) return 1;
        if (cmd[0] == 'm') printf("%s\n", med);
        else if (cmd[0] == 'g') printf("%s\n", v[n - 1].s);
        else printf("%s %s %s\n", v[0].s, med, v[n - 1].s);
    } else if (!strcmp(cmd, "range")) {
        if (argc < 3 || !number_format(a[0])) usage();
        if (!(n = spread(a + 1, argc - 3, v, med, sizeof med))) return 1;
        printf(a[0], v[0].v);
        putchar('-');
        printf(a[0], v[n - 1].v);
    } else if (!strcmp(cmd, "ratios")) {
        if (argc != 4) usage();
        n = words(a, 1, v, MAXV);
        k = words(a + 1, 1, w, MAXV);
        for (i = 0; i < n && i < k; i++)
            if (w[i].v > 0) printf("%.6g ", v[i].v / w[i].v);
    } else if (!strcmp(cmd, "accel")) return !accel(a[0], a[1]);
    else if (!strcmp(cmd, "best")) return !best(a[0], a[1]);
    else if (!strcmp(cmd, "far")) return !far(a[0]);
    else if (!strcmp(cmd, "kv")) return !kv(a[0], a[1]);
    else if (!strcmp(cmd, "field") || !strcmp(cmd, "values")) return !field(a[0], a[1], a[2], cmd[0] == 'v');
    else if (!strcmp(cmd, "disagree")) return !disagree(a[0], a[1]);
    else if (!strcmp(cmd, "build")) return !build(a[0], a[1]);
    else if (!strcmp(cmd, "ratio")) {
        /* nothing when B is not above 0 (or not a number) */
        double x, y;
        if (!is_num(a[1], &x) || !is_num(a[2], &y) || !(y > 0)) return 1;
        put_fmt(a[0], x / y);
    } else if (!strcmp(cmd, "us-per")) {
        double s, r;
        if (argc != 4 && argc != 5) usage();
        if (!is_num(a[0], &s) || !is_num(a[1], &r) || !(r > 0)) return 1;
        put_fmt(argc == 5 ? a[2] : "%.6g", s / r * 1e6);
    } else if (!strcmp(cmd, "mrays")) {
        double r, s;
        if (!is_num(a[0], &r) || !is_num(a[1], &s) || !(s > 0)) return 1;
        printf("%.4f\n", r / s / 1e6);
    } else if (!strcmp(cmd, "setup")) printf("%.4f\n", arg(a[0]) - arg(a[1]));
    else if (!strcmp(cmd, "verdict")) return !verdict(a[0], a[1], a[2]);
    else if (!strcmp(cmd, "repeats"))
        printf("%d\n", as_printed(arg(a[0]) * arg(a[1]) / arg(a[2])) < 0.5 ? 5 : 3);
    else if (!strcmp(cmd, "more")) {
        double e = arg(a[0]) / arg(a[1]) * (6 * arg(a[2]) + arg(a[3]));
        if (!(e > 240)) return 1;
        printf("%.0f\n", e);
    } else if (!strcmp(cmd, "flake-cost")) {
        double f = arg(a[0]) - arg(a[1]);
        if (f < 0) f = 0;
        printf("%.0f\n", arg(a[2]) * f + arg(a[1]) * pow(arg(a[3]) / 128, 2) * (6 * arg(a[4]) + arg(a[5])));
    } else if (!strcmp(cmd, "spd-side")) {
        static const int sides[] = { 96, 64, 48, 32, 24 };
        double t = arg(a[0]), budget = arg(a[1]);
        int side = 16;
        for (i = 0; i < 5; i++)
            if (t * pow(sides[i] / 16.0, 2) <= budget) { side = sides[i]; break; }
        printf("%d\n", side);
    } else if (!strcmp(cmd, "kd-spp")) {
        double t = arg(a[0]);
        int spp = 1;
        if (t < 0.05) {
            spp = (int)(0.1 / (t > 0.001 ? t : 0.001)) + 1;
            if (spp > 64) spp = 64;
        }
        printf("%d\n", spp);
    } else if (!strcmp(cmd, "render") || !strcmp(cmd, "render-plot")) return !render(a[0], cmd[6] == '-');
    else if (!strcmp(cmd, "pt-slopes") || !strcmp(cmd, "pt-plot")) return !pt(a[0], cmd[3] == 'p');
    else if (!strcmp(cmd, "time-at")) return !time_at(a[0], a[1], a[2], arg(a[3]), atoi(a[4]));
    else
        usage();
    return 0;
}

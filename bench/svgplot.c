/* svgplot - a log-log scatter plot as SVG, for make bench.
 *
 *     cc -std=c99 -O2 -o svgplot bench/svgplot.c -lm
 *     ./svgplot [--title T] [--xlabel X] [--ylabel Y] <rows >plot.svg
 *
 * Each input row is  SERIES X Y [LABEL]  separated by blanks; '#' lines and
 * blank lines are skipped.  Rows of one series are joined by a line in the
 * order they come, each point marked and labelled.  Both axes are
 * logarithmic, so rows with X or Y <= 0 are skipped with a warning.
 *
 * The SVG is written by hand rather than with a plotting package so that
 * make bench needs nothing beyond a C compiler.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAXTEXT 128

typedef struct {
    int series;
    double x, y;
    char label[MAXTEXT];
} point;

static char (*names)[MAXTEXT];
static int nnames;
static point *pts;
static int npts;

/* Plot area inside the picture, in SVG user units (pixels). */
enum { W = 760, H = 500, LEFT = 80, RIGHT = 560, TOP = 50, BOTTOM = 430 };

static const char *palette[] = {
    "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e",
    "#9467bd", "#8c564b", "#e377c2", "#17becf",
};

/* Make room for one more of n elements in *p, doubling its capacity *cap. */
static void *room(void *p, int n, int *cap, size_t size)
{
    if (n < *cap) return p;
    *cap = *cap ? 2 * *cap : 16;
    p = realloc(p, (size_t)*cap * size);
    if (!p) {
        fprintf(stderr, "svgplot: out of memory\n");
        exit(2);
    }
    return p;
}

static int series_index(const char *name)
{
    static int cap;
    int i;
    for (i = 0; i < nnames; i++)
        if (strcmp(names[i], name) == 0) return i;
    names = room(names, nnames, &cap, sizeof *names);
    strcpy(names[nnames], name);
    return nnames++;
}

/* Text for an SVG text node or attribute value. */
static void xml(const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '&': fputs("&amp;", stdout); break;
        case '<': fputs("&lt;", stdout); break;
        case '>': fputs("&gt;", stdout); break;
        case '"': fputs("&quot;", stdout); break;
        default: putchar(*s);
        }
    }
}

/* A log axis: the range lo..hi of log10 values mapped to pixels a..b. */
typedef struct { double lo, hi, a, b; } axis;

static double place(const axis *ax, double v)
{
    return ax->a + (log10(v) - ax->lo) / (ax->hi - ax->lo) * (ax->b - ax->a);
}

/* Widen [min, max] a little so no point sits on the frame, and to at least
 * half a decade so a single point still gets a labelled tick. */
static void fit(axis *ax, double min, double max, double a, double b)
{
    double lo = log10(min), hi = log10(max), pad, mid;
    if (hi - lo < 0.5) {
        mid = (lo + hi) / 2;
        lo = mid - 0.25;
        hi = mid + 0.25;
    }
    pad = 0.06 * (hi - lo);
    ax->lo = lo - pad;
    ax->hi = hi + pad;
    ax->a = a;
    ax->b = b;
}

/* Ticks at 1, 2..9 times each power of ten in range.  Labels go on powers
 * of ten, and on 2 and 5 too when the axis spans few decades, so every axis
 * carries at least two numbers. */
static void ticks(const axis *ax, int vertical)
{
    int k, m, labelled;
    double span = ax->hi - ax->lo, v, p;
    char buf[32];

    for (k = (int)floor(ax->lo); k <= (int)ceil(ax->hi); k++) {
        for (m = 1; m <= 9; m++) {
            v = m * pow(10, k);
            if (log10(v) < ax->lo || log10(v) > ax->hi) continue;
            labelled = m == 1 || (span < 2.5 && (m == 2 || m == 5)) ||
                       (span < 1.2 && m != 7 && m != 9);
            p = place(ax, v);
            if (vertical) {
                printf("<line x1=\"%d\" y1=\"%.2f\" x2=\"%d\" y2=\"%.2f\" "
                       "stroke=\"%s\"/>\n", LEFT, p, RIGHT, p,
                       m == 1 ? "#ccc" : "#eee");
                printf("<line x1=\"%d\" y1=\"%.2f\" x2=\"%d\" y2=\"%.2f\" "
                       "stroke=\"#000\"/>\n", LEFT - (labelled ? 6 : 3), p,
                       LEFT, p);
                if (labelled) {
                    sprintf(buf, "%g", v);
                    printf("<text x=\"%d\" y=\"%.2f\" text-anchor=\"end\" "
                           "dominant-baseline=\"middle\">%s</text>\n",
                           LEFT - 9, p, buf);
                }
            } else {
                printf("<line x1=\"%.2f\" y1=\"%d\" x2=\"%.2f\" y2=\"%d\" "
                       "stroke=\"%s\"/>\n", p, TOP, p, BOTTOM,
                       m == 1 ? "#ccc" : "#eee");
                printf("<line x1=\"%.2f\" y1=\"%d\" x2=\"%.2f\" y2=\"%d\" "
                       "stroke=\"#000\"/>\n", p, BOTTOM, p,
                       BOTTOM + (labelled ? 6 : 3));
                if (labelled) {
                    sprintf(buf, "%g", v);
                    printf("<text x=\"%.2f\" y=\"%d\" text-anchor=\"middle\">"
                           "%s</text>\n", p, BOTTOM + 22, buf);
                }
            }
        }
    }
}

/* Marker shapes tell series apart where colours do not (print, colour
 * blindness). */
static void marker(int shape, double x, double y, const char *colour)
{
    switch (shape % 4) {
    case 0:
        printf("<circle cx=\"%.2f\" cy=\"%.2f\" r=\"4.5\" fill=\"%s\"/>\n",
               x, y, colour);
        break;
    case 1:
        printf("<rect x=\"%.2f\" y=\"%.2f\" width=\"8\" height=\"8\" "
               "fill=\"%s\"/>\n", x - 4, y - 4, colour);
        break;
    case 2:
        printf("<path d=\"M%.2f %.2fl5 9h-10z\" fill=\"%s\"/>\n",
               x, y - 5.5, colour);
        break;
    default:
        printf("<path d=\"M%.2f %.2fl5.5 5.5l-5.5 5.5l-5.5 -5.5z\" "
               "fill=\"%s\"/>\n", x, y - 5.5, colour);
    }
}

static void usage(FILE *f)
{
    fprintf(f,
"usage: svgplot [--title T] [--xlabel X] [--ylabel Y] <rows >plot.svg\n"
"Rows are 'SERIES X Y [LABEL]'; '#' lines are comments.  Plots Y against X\n"
"on log-log axes, one coloured line per series, each point labelled.\n");
}

int main(int argc, char **argv)
{
    const char *title = "", *xlabel = "x", *ylabel = "y";
    char line[1024], sname[MAXTEXT], label[MAXTEXT], *end;
    double x, y, xmin = HUGE_VAL, xmax = -HUGE_VAL, ymin = HUGE_VAL,
           ymax = -HUGE_VAL;
    long lineno = 0;
    int i, s, n, first, cap = 0;
    axis ax, ay;
    const char *colour;

    for (i = 1; i < argc; i++) {
        if (strcmp(argv[i], "-h") == 0 || strcmp(argv[i], "--help") == 0) {
            usage(stdout);
            return 0;
        } else if (i + 1 < argc && strcmp(argv[i], "--title") == 0) {
            title = argv[++i];
        } else if (i + 1 < argc && strcmp(argv[i], "--xlabel") == 0) {
            xlabel = argv[++i];
        } else if (i + 1 < argc && strcmp(argv[i], "--ylabel") == 0) {
            ylabel = argv[++i];
        } else {
            fprintf(stderr, "svgplot: unknown or incomplete option '%s' "
                    "(try --help)\n", argv[i]);
            return 2;
        }
    }

    while (fgets(line, sizeof line, stdin)) {
        char xs[64], ys[64];
        lineno++;
        if (!strchr(line, '\n') && !feof(stdin)) {
            fprintf(stderr, "<stdin>:%ld: line too long\n", lineno);
            return 2;
        }
        label[0] = '\0';
        /* The widths keep every field inside its buffer. */
        n = sscanf(line, " %127s %63s %63s %127s", sname, xs, ys, label);
        if (n <= 0 || sname[0] == '#') continue;
        if (n < 3) {
            fprintf(stderr, "<stdin>:%ld: expected SERIES X Y [LABEL]\n",
                    lineno);
            return 2;
        }
        x = strtod(xs, &end);
        if (*end) {
            fprintf(stderr, "<stdin>:%ld: X '%s' is not a number\n", lineno, xs);
            return 2;
        }
        y = strtod(ys, &end);
        if (*end) {
            fprintf(stderr, "<stdin>:%ld: Y '%s' is not a number\n", lineno, ys);
            return 2;
        }
        if (!(x > 0 && y > 0 && x < HUGE_VAL && y < HUGE_VAL)) {
            fprintf(stderr, "<stdin>:%ld: skipped: log axes need finite "
                    "values above 0 (X %s, Y %s)\n", lineno, xs, ys);
            continue;
        }
        pts = room(pts, npts, &cap, sizeof *pts);
        pts[npts].series = series_index(sname);
        pts[npts].x = x;
        pts[npts].y = y;
        strcpy(pts[npts].label, label);
        npts++;
        if (x < xmin) xmin = x;
        if (x > xmax) xmax = x;
        if (y < ymin) ymin = y;
        if (y > ymax) ymax = y;
    }
    if (ferror(stdin)) {
        fprintf(stderr, "svgplot: read error on standard input\n");
        return 2;
    }
    if (npts == 0) {
        fprintf(stderr, "svgplot: no points to plot\n");
        return 2;
    }

    fit(&ax, xmin, xmax, LEFT, RIGHT);
    fit(&ay, ymin, ymax, BOTTOM, TOP);   /* SVG's y grows downwards */

    printf("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
           "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" "
           "height=\"%d\" viewBox=\"0 0 %d %d\" font-family=\"sans-serif\" "
           "font-size=\"12\">\n", W, H, W, H);
    printf("<rect width=\"%d\" height=\"%d\" fill=\"#fff\"/>\n", W, H);
    printf("<text x=\"%d\" y=\"28\" text-anchor=\"middle\" font-size=\"15\">",
           (LEFT + RIGHT) / 2);
    xml(title);
    printf("</text>\n");

    ticks(&ax, 0);
    ticks(&ay, 1);
    printf("<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"none\" "
           "stroke=\"#000\"/>\n", LEFT, TOP, RIGHT - LEFT, BOTTOM - TOP);
    printf("<text x=\"%d\" y=\"%d\" text-anchor=\"middle\">",
           (LEFT + RIGHT) / 2, BOTTOM + 45);
    xml(xlabel);
    printf("</text>\n<text transform=\"translate(22 %d) rotate(-90)\" "
           "text-anchor=\"middle\">", (TOP + BOTTOM) / 2);
    xml(ylabel);
    printf("</text>\n");

    for (s = 0; s < nnames; s++) {
        colour = palette[s % 8];
        printf("<g>\n<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"1.5\""
               "%s points=\"", colour, s / 8 % 2 ? " stroke-dasharray=\"5 3\"" : "");
        first = 1;
        for (i = 0; i < npts; i++) {
            if (pts[i].series != s) continue;
            printf("%s%.2f,%.2f", first ? "" : " ", place(&ax, pts[i].x),
                   place(&ay, pts[i].y));
            first = 0;
        }
        printf("\"/>\n");
        for (i = 0; i < npts; i++) {
            if (pts[i].series != s) continue;
            marker(s, place(&ax, pts[i].x), place(&ay, pts[i].y), colour);
            /* Above the point for even series, below for odd ones: series
             * that differ little (one scene, two builds) come in pairs, and
             * their labels would otherwise print over each other. */
            if (pts[i].label[0]) {
                printf("<text x=\"%.2f\" y=\"%.2f\" font-size=\"10\" "
                       "fill=\"%s\">", place(&ax, pts[i].x) + 7,
                       place(&ay, pts[i].y) + (s % 2 ? 15 : -7), colour);
                xml(pts[i].label);
                printf("</text>\n");
            }
        }
        /* legend */
        printf("<line x1=\"%d\" y1=\"%d\" x2=\"%d\" y2=\"%d\" stroke=\"%s\" "
               "stroke-width=\"1.5\"/>\n", RIGHT + 20, TOP + 10 + 20 * s,
               RIGHT + 44, TOP + 10 + 20 * s, colour);
        marker(s, RIGHT + 32, TOP + 10 + 20 * s, colour);
        printf("<text x=\"%d\" y=\"%d\" dominant-baseline=\"middle\">",
               RIGHT + 52, TOP + 10 + 20 * s);
        xml(names[s]);
        printf("</text>\n</g>\n");
    }
    printf("</svg>\n");
    fflush(stdout);
    if (ferror(stdout)) {
        fprintf(stderr, "svgplot: write error on standard output\n");
        return 2;
    }
    return 0;
}

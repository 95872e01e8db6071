/* ppmdiff - compare two PPM images; the yardstick of the tests and make bench.
 *
 *     cc -std=c99 -O2 -o tools/ppmdiff tools/ppmdiff.c -lm
 *     tools/ppmdiff [options] A.ppm B.ppm        (see --help)
 *
 * Exit status: 0 within tolerance, 1 beyond it, 2 on any error, so that a
 * script can tell "the renderer got worse" from "the renderer crashed".
 *
 * The whole file is read into memory before parsing: a truncated or lying
 * header is then caught by comparing what it promises with what is there,
 * before any allocation sized by the header is attempted.
 */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    const char *name;           /* as given, for messages */
    unsigned long w, h;
    unsigned maxval;
    unsigned short *px;         /* w*h*3 samples, row by row, r g b */
} image;

/* A read position in a file, with the line number for messages. */
typedef struct {
    const char *name;
    const unsigned char *p, *end;
    long line;
} cursor;

static const char *progname = "ppmdiff";

static void errmsg(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

/* "name:line: message", the form editors and CI logs link to a position. */
static int fail_at(const cursor *c, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "%s:%ld: ", c->name, c->line);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    return 0;
}

static const char *shown(const char *name)
{
    return strcmp(name, "-") == 0 ? "<stdin>" : name;
}

static unsigned char *slurp(const char *name, size_t *len)
{
    FILE *f = strcmp(name, "-") == 0 ? stdin : fopen(name, "rb");
    unsigned char *buf = NULL, *nb;
    size_t cap = 0, n = 0, got;
    int bad;

    if (!f) {
        errmsg("%s: %s", name, strerror(errno));
        return NULL;
    }
    for (;;) {
        if (n == cap) {
            /* Doubling keeps the copy cost linear in the file size. */
            cap = cap ? 2 * cap : 65536;
            nb = cap > n ? realloc(buf, cap) : NULL;
            if (!nb) {
                errmsg("%s: out of memory reading the file", shown(name));
                free(buf);
                if (f != stdin) fclose(f);
                return NULL;
            }
            buf = nb;
        }
        got = fread(buf + n, 1, cap - n, f);
        n += got;
        if (got == 0) break;
    }
    bad = ferror(f);
    if (f != stdin) fclose(f);
    if (bad) {
        errmsg("%s: read error", shown(name));
        free(buf);
        return NULL;
    }
    *len = n;
    return buf;
}

static int is_space(int ch)
{
    return ch == ' ' || ch == '\t' || ch == '\n' || ch == '\v' || ch == '\f' ||
           ch == '\r';
}

/* Whitespace and '#' comments, which netpbm allows between header fields;
 * P3 rasters written by hand often carry them too, so they are allowed there. */
static void skip_blank(cursor *c)
{
    while (c->p < c->end) {
        if (*c->p == '#') {
            while (c->p < c->end && *c->p != '\n' && *c->p != '\r') c->p++;
        } else if (is_space(*c->p)) {
            if (*c->p == '\n') c->line++;
            c->p++;
        } else {
            break;
        }
    }
}

/* An unsigned decimal no larger than max.  what names it in messages. */
static int read_uint(cursor *c, unsigned long max, const char *what,
                     unsigned long *out)
{
    unsigned long v = 0;
    skip_blank(c);
    if (c->p >= c->end)
        return fail_at(c, "truncated: end of file where the %s should be", what);
    if (*c->p < '0' || *c->p > '9') {
        if (*c->p >= 0x21 && *c->p < 0x7f)
            return fail_at(c, "expected the %s, found '%c'", what, *c->p);
        return fail_at(c, "expected the %s, found byte 0x%02x", what, *c->p);
    }
    while (c->p < c->end && *c->p >= '0' && *c->p <= '9') {
        unsigned long digit = (unsigned long)(*c->p++ - '0');
        if (v > (max - digit) / 10)
            return fail_at(c, "%s too large (at most %lu)", what, max);
        v = 10 * v + digit;
    }
    if (c->p < c->end && !is_space(*c->p) && *c->p != '#')
        return fail_at(c, "junk after the %s", what);
    *out = v;
    return 1;
}

/* Parse the file into img; on failure a message has been printed. */
static int parse(const char *name, const unsigned char *buf, size_t len,
                 image *img)
{
    cursor c;
    unsigned long w, h, maxval, v;
    unsigned long long n, i;
    size_t left;
    int plain, bps = 1;

    c.name = shown(name);
    c.p = buf;
    c.end = buf + len;
    c.line = 1;
    img->name = c.name;
    img->px = NULL;

    if (len < 2 || buf[0] != 'P' || (buf[1] != '3' && buf[1] != '6'))
        return fail_at(&c, "not a PPM image (no P3 or P6 magic number)");
    plain = buf[1] == '3';
    c.p += 2;
    if (c.p < c.end && !is_space(*c.p) && *c.p != '#')
        return fail_at(&c, "not a PPM image (junk after the magic number)");
    if (!read_uint(&c, INT_MAX, "width", &w) ||
        !read_uint(&c, INT_MAX, "height", &h) ||
        !read_uint(&c, 65535, "maxval", &maxval))
        return 0;
    if (w == 0 || h == 0) return fail_at(&c, "empty image (%lux%lu)", w, h);
    if (maxval == 0) return fail_at(&c, "maxval must be at least 1");

    /* At most 2^31 * 2^31 * 3 < 2^64: no overflow. */
    n = (unsigned long long)w * h * 3;
    img->w = w;
    img->h = h;
    img->maxval = (unsigned)maxval;

    if (plain) {
        /* Each sample takes a digit and a separator, the last one a digit. */
        left = (size_t)(c.end - c.p);
        if (n - 1 > left / 2)
            return fail_at(&c, "truncated: %lux%lu needs %llu samples but "
                           "only %lu bytes follow the header",
                           w, h, n, (unsigned long)left);
    } else {
        /* Exactly one whitespace byte ends the header: a second one, or a
         * '#', would already be raster data. */
        if (c.p >= c.end)
            return fail_at(&c, "truncated: no raster after the header");
        if (!is_space(*c.p))
            return fail_at(&c, "expected one whitespace byte after maxval");
        c.p++;
        bps = maxval > 255 ? 2 : 1;
        left = (size_t)(c.end - c.p);
        if (n > left / (unsigned)bps) {
            errmsg("%s: truncated: %lux%lu with maxval %lu needs %llu raster "
                   "bytes, the file has %lu", c.name, w, h, maxval,
                   n * (unsigned)bps, (unsigned long)left);
            return 0;
        }
    }
    if (n > (size_t)-1 / sizeof *img->px ||
        !(img->px = malloc((size_t)n * sizeof *img->px))) {
        errmsg("%s: out of memory for %lux%lu pixels", c.name, w, h);
        return 0;
    }

    if (plain) {
        for (i = 0; i < n; i++) {
            skip_blank(&c);
            if (c.p >= c.end)
                return fail_at(&c, "truncated: found %llu of the %llu samples "
                               "of %lux%lu", i, n, w, h);
            if (!read_uint(&c, maxval, "sample", &v)) return 0;
            img->px[i] = (unsigned short)v;
        }
    } else {
        for (i = 0; i < n; i++) {
            v = c.p[0];
            if (bps == 2) {
                v = v << 8 | c.p[1];   /* most significant byte first */
                c.p += 2;
            } else {
                c.p++;
            }
            if (v > maxval) {
                errmsg("%s: sample %lu at pixel (%llu, %llu) exceeds maxval %lu",
                       c.name, v, i / 3 % w, i / 3 / w, maxval);
                return 0;
            }
            img->px[i] = (unsigned short)v;
        }
    }
    /* Anything after the raster is ignored, as netpbm treats it as the next
     * image of a stream. */
    return 1;
}

static int load(const char *name, image *img)
{
    size_t len = 0;
    unsigned char *buf = slurp(name, &len);
    int ok;
    if (!buf) return 0;
    ok = parse(name, buf, len, img);
    free(buf);
    if (!ok) {
        free(img->px);
        img->px = NULL;
    }
    return ok;
}

/* A sample of maxval m re-expressed in maxval to, rounded to nearest. */
static unsigned rescale(unsigned v, unsigned m, unsigned to)
{
    if (m == to) return v;
    return (unsigned)(((unsigned long long)v * to + m / 2) / m);
}

static void usage(FILE *f)
{
    fprintf(f,
"usage: %s [options] A.ppm B.ppm\n"
"Compares two PPM images (P3 or P6, in any mix; maxval up to 65535; '-' reads\n"
"standard input) and prints one line:\n"
"  channels differing: N of M (P%%), max |diff| D, RMSE R, PSNR S dB,\n"
"  mean diff M\n"
"Differences count in units of the maxval; when the two maxvals differ, both\n"
"images are first rescaled to the larger one.  PSNR = 20 log10(maxval/RMSE),\n"
"'inf' for identical images.  The mean diff is the mean of B - A over every\n"
"channel, signed: it tells a bias from noise, which max and RMSE cannot (half\n"
"the channels one level up and half one down, or all of them one down: max 1\n"
"and RMSE 1 either way, but mean diff 0 and -1).  Only the first image of a\n"
"multi-image file is read.\n"
"\n"
"Options:\n"
"  -t N, --max N   pass when max |diff| <= N.  The default is 0 (exact\n"
"                  match), unless --rmse, --psnr or --bias is given alone,\n"
"                  in which case max |diff| is not checked\n"
"  --rmse X        fail when RMSE > X\n"
"  --psnr DB       fail when PSNR < DB\n"
"  --bias B        fail when |mean diff| > B\n"
"  -o DIFF.ppm     write a difference image (P6, maxval 255; '-' is standard\n"
"                  output, and the summary line then goes to standard error).\n"
"                  Each channel is 0 where A and B agree, and otherwise\n"
"                  64 + 191*|a-b|/D: every difference shows at a quarter\n"
"                  brightness or more, and the largest is full brightness\n"
"  -q, --quiet     print nothing but errors; the exit status tells\n"
"  -h, --help      this text\n"
"\n"
"Exit status: 0 within tolerance, 1 beyond it, 2 on error (unreadable file,\n"
"bad or truncated image, sizes that differ).\n", progname);
}

/* The value of option opt at argv[*i], given as "-tN", "-t N", "--max=N" or
 * "--max N"; NULL when argv[*i] is not that option. */
static const char *optval(int argc, char **argv, int *i, const char *opt)
{
    const char *a = argv[*i];
    size_t n = strlen(opt);
    if (strncmp(a, opt, n) != 0) return NULL;
    if (a[n] == '\0') {
        if (*i + 1 >= argc) {
            errmsg("%s: option %s needs a value (try --help)", progname, opt);
            exit(2);
        }
        return argv[++*i];
    }
    if (opt[1] == '-' && a[n] == '=') return a + n + 1;
    if (opt[1] != '-') return a + n;
    return NULL;
}

static double number(const char *s, const char *opt, double min)
{
    char *e;
    double v;
    errno = 0;
    v = strtod(s, &e);
    if (e == s || *e || errno == ERANGE || v != v || v > 1e300 || v < -1e300) {
        errmsg("%s: option %s: '%s' is not a number", progname, opt, s);
        exit(2);
    }
    if (v < min) {
        errmsg("%s: option %s: %s is below %g", progname, opt, s, min);
        exit(2);
    }
    return v;
}

static int write_diff(const char *name, const image *a, const image *b,
                      unsigned top, unsigned maxd)
{
    FILE *f = strcmp(name, "-") == 0 ? stdout : fopen(name, "wb");
    unsigned long long i, n = (unsigned long long)a->w * a->h * 3;
    unsigned x, y, d;
    int bad;

    if (!f) {
        errmsg("%s: %s", name, strerror(errno));
        return 0;
    }
    fprintf(f, "P6\n%lu %lu\n255\n", a->w, a->h);
    for (i = 0; i < n; i++) {
        x = rescale(a->px[i], a->maxval, top);
        y = rescale(b->px[i], b->maxval, top);
        d = x > y ? x - y : y - x;
        /* 64 floor: a one-unit difference in a 16-bit image must not look
         * identical to no difference at all. */
        putc(d ? (int)(64 + (191UL * d + maxd / 2) / maxd) : 0, f);
    }
    bad = ferror(f);
    if (f == stdout ? fflush(f) != 0 : fclose(f) != 0) bad = 1;
    if (bad) {
        errmsg("%s: write error", shown(name));
        return 0;
    }
    return 1;
}

int main(int argc, char **argv)
{
    const char *file[2], *diffname = NULL, *v;
    int i, nfile = 0, quiet = 0, endopts = 0, ok, rc;
    int have_max = 0, have_rmse = 0, have_psnr = 0, have_bias = 0;
    double tol_max = 0, tol_rmse = 0, tol_psnr = 0, tol_bias = 0;
    image a, b;
    unsigned top, x, y, d, maxd = 0;
    unsigned long long k, n, ndiff = 0;
    double sse = 0, rmse, psnr = 0, pct, bias;
    long long sum = 0;
    char psnrtext[32], pcttext[32];
    FILE *out;

    for (i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (endopts || arg[0] != '-' || arg[1] == '\0') {
            if (nfile == 2) {
                errmsg("%s: more than two images given (try --help)", progname);
                return 2;
            }
            file[nfile++] = arg;
        } else if (strcmp(arg, "--") == 0) {
            endopts = 1;
        } else if (strcmp(arg, "-h") == 0 || strcmp(arg, "--help") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(arg, "-q") == 0 || strcmp(arg, "--quiet") == 0) {
            quiet = 1;
        } else if ((v = optval(argc, argv, &i, "--max")) ||
                   (v = optval(argc, argv, &i, "-t"))) {
            tol_max = number(v, "-t/--max", 0);
            have_max = 1;
        } else if ((v = optval(argc, argv, &i, "--rmse"))) {
            tol_rmse = number(v, "--rmse", 0);
            have_rmse = 1;
        } else if ((v = optval(argc, argv, &i, "--psnr"))) {
            tol_psnr = number(v, "--psnr", -1e300);
            have_psnr = 1;
        } else if ((v = optval(argc, argv, &i, "--bias"))) {
            tol_bias = number(v, "--bias", 0);
            have_bias = 1;
        } else if ((v = optval(argc, argv, &i, "-o"))) {
            diffname = v;
        } else {
            errmsg("%s: unknown option '%s' (try --help)", progname, arg);
            return 2;
        }
    }
    if (nfile != 2) {
        errmsg("%s: expected two images, got %d (try --help)", progname, nfile);
        return 2;
    }
    if (strcmp(file[0], "-") == 0 && strcmp(file[1], "-") == 0) {
        errmsg("%s: only one image can come from standard input", progname);
        return 2;
    }
    if (!have_max && (have_rmse || have_psnr || have_bias)) tol_max = 1e300;

    if (!load(file[0], &a)) return 2;
    if (!load(file[1], &b)) {
        free(a.px);
        return 2;
    }
    if (a.w != b.w || a.h != b.h) {
        errmsg("%s: sizes differ: %s is %lux%lu, %s is %lux%lu", progname,
               a.name, a.w, a.h, b.name, b.w, b.h);
        free(a.px);
        free(b.px);
        return 2;
    }
    top = a.maxval > b.maxval ? a.maxval : b.maxval;
    if (a.maxval != b.maxval && !quiet)
        errmsg("%s: note: maxval %u (%s) and %u (%s) differ; compared at %u",
               progname, a.maxval, a.name, b.maxval, b.name, top);

    n = (unsigned long long)a.w * a.h * 3;
    for (k = 0; k < n; k++) {
        x = rescale(a.px[k], a.maxval, top);
        y = rescale(b.px[k], b.maxval, top);
        d = x > y ? x - y : y - x;
        sum += (long long)y - (long long)x;
        if (d) {
            ndiff++;
            if (d > maxd) maxd = d;
            sse += (double)d * d;
        }
    }
    rmse = sqrt(sse / (double)n);
    bias = (double)sum / (double)n;
    if (ndiff) {
        psnr = 20 * log10(top / rmse);
        sprintf(psnrtext, "%.1f", psnr);
    } else {
        strcpy(psnrtext, "inf");
    }
    pct = 100.0 * (double)ndiff / (double)n;
    if (ndiff && pct < 0.005)
        strcpy(pcttext, "<0.01");
    else
        sprintf(pcttext, "%.2f", pct);

    ok = 1;
    if (diffname && !write_diff(diffname, &a, &b, top, maxd ? maxd : 1)) ok = 0;
    free(a.px);
    free(b.px);
    if (!ok) return 2;

    out = diffname && strcmp(diffname, "-") == 0 ? stderr : stdout;
    if (!quiet)
        fprintf(out, "channels differing: %llu of %llu (%s%%), max |diff| %u, "
                "RMSE %.4f, PSNR %s dB, mean diff %+.4f\n", ndiff, n, pcttext,
                maxd, rmse, psnrtext, bias);

    rc = 0;
    if (maxd > tol_max) {
        if (!quiet)
            errmsg("%s: %s and %s differ: max |diff| %u > %g", progname,
                   a.name, b.name, maxd, tol_max);
        rc = 1;
    }
    if (have_rmse && rmse > tol_rmse) {
        if (!quiet)
            errmsg("%s: %s and %s differ: RMSE %.4f > %g", progname, a.name,
                   b.name, rmse, tol_rmse);
        rc = 1;
    }
    if (have_psnr && ndiff && psnr < tol_psnr) {
        if (!quiet)
            errmsg("%s: %s and %s differ: PSNR %.1f dB < %g dB", progname,
                   a.name, b.name, psnr, tol_psnr);
        rc = 1;
    }
    if (have_bias && fabs(bias) > tol_bias) {
        if (!quiet)
            errmsg("%s: %s and %s differ: |mean diff| %.4f > %g", progname,
                   a.name, b.name, fabs(bias), tol_bias);
        rc = 1;
    }
    if (fflush(stdout) != 0) {
        errmsg("%s: error writing standard output", progname);
        return 2;
    }
    return rc;
}

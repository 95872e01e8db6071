/* cli.c - the command line (cli.h): options into Args, with a message and
 * exit status 2 for anything it cannot take, and the help text.
 */
#include "posix.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef RAY_POSIX
#include <sys/stat.h>
#endif
#include "cli.h"
#include "image.h"
#include "scene.h"

#ifndef REAL
#define REAL double         /* as ray.c is built, for --version */
#endif

/* The options, once: --help prints this, and the README shows it. */
void usage(FILE *to)
{
    fputs("usage: ray [options] SCENE\n"
          "Renders SCENE with Whitted ray tracing, or path tracing (--pt): the sphere\n"
          "format (README.md), or NFF (Eric Haines' Neutral File Format, the SPD\n"
          "scenes') when it ends .nff.\n"
          "  -o FILE    output image: PNG if FILE ends .png, PFM (floats) if .pfm, else\n"
          "             PPM (default: SCENE's base name + .ppm; - for stdout)\n"
          "  -s WxH     image size (default: the scene's `size`, else 512x512)\n"
          "  -n N       samples per pixel (default: the scene's `samples`, else 1)\n"
          "  -d N       Whitted: recursion depth, 1 = primary rays only (default: the\n"
          "             scene's, else 5); path tracing: rays a path may have (default:\n"
          "             the scene's `depth`, else no bound but Russian roulette)\n"
          "  -t N       threads (default: every core, when built with OpenMP)\n"
          "  --pt       path tracing (Kajiya's rendering equation); --whitted: Whitted's\n"
          "             (default: the scene's `integrator`, else Whitted)\n"
          "  --estimator E  the path tracer's: bsdf (BSDF sampling only), nee (next-event\n"
          "             estimation) or mis (both, by multiple importance sampling; default)\n"
          "  --no-roulette  no Russian roulette: paths end at -d only\n"
          "  --seed N   the path tracer's noise, 0 or more (default 0): another N, other\n"
          "             noise\n"
          "  --p3       write plain-text P3 instead of binary P6\n"
          "  --gamma    encode Whitted's output with the sRGB curve (default: linear, as the\n"
          "             card's; a path-traced image always has it, but for PFM)\n"
          "  --accel A  kd (the kd-tree), bvh (bounding volume hierarchy), grid\n"
          "             (uniform grid), none (test every object) or auto (default:\n"
          "             the scene's `accel` line, else from 8 objects up the one that\n"
          "             renders a 32x32 probe of the image fastest, its build included)\n"
          "  --view V   instead of the picture, what a ray through each pixel's centre\n"
          "             meets: steps (the structure's work: nodes or cells plus tests,\n"
          "             black 0, blue 25, red 50, yellow 100, white 200), normal, depth\n"
          "  --stats    print rays by kind, hits, the tree and time on stderr;\n"
          "             --stats=kv: the same as one `key value` line each\n"
          "  --version  the version, and how it was built\n"
          "  --help     this text\n", to);
}

#define RAY_VERSION "1.0"

static void version(void)
{
#ifdef _OPENMP
    const char *threads = "OpenMP threads";
#else
    const char *threads = "one thread, no OpenMP";
#endif
    printf("ray " RAY_VERSION ", Whitted's ray tracer and Kajiya's path tracer in C99 (%s, %s)\n",
           sizeof(REAL) == sizeof(float) ? "float" : "double", threads);
}

/* The value of option opt ("-n", "--accel") if argv[*i] is that option:
 * attached ("-n4", "--accel=kd") or the next argument ("-n 4"), which is
 * then used up.  NULL if argv[*i] is another option; a usage error (exit 2)
 * if the value is missing. */
static const char *option_value(int argc, char **argv, int *i, const char *opt)
{
    const char *a = argv[*i];
    size_t n = strlen(opt);
    if (strncmp(a, opt, n)) return NULL;
    if (a[n] && opt[1] != '-') return a + n;
    if (a[n]) return a[n] == '=' ? a + n + 1 : NULL;
    if (*i + 1 >= argc) {
        fprintf(stderr, "ray: %s needs a value (see ray --help)\n", opt);
        exit(2);
    }
    return argv[++*i];
}

/* --accel's value, or a usage error (exit 2) that lists the choices. */
static const char *accel_arg(const char *v)
{
    if (!accel_name(v)) {
        fprintf(stderr, "ray: --accel takes kd (the kd-tree), bvh (bounding volume hierarchy), grid"
                " (uniform grid), none (every object) or auto, not %s\n", v);
        exit(2);
    }
    return accel_name(v);
}

/* --view's picture, or a usage error (exit 2) with the choices. */
static int view_arg(const char *v)
{
    if (!strcmp(v, "steps")) return 1;
    if (!strcmp(v, "normal")) return 2;
    if (strcmp(v, "depth")) {
        fprintf(stderr, "ray: --view takes steps, normal or depth, not %s\n", v);
        exit(2);
    }
    return 3;
}

/* The path tracer's estimator named by --estimator, or exit with the choices. */
static int estimator_arg(const char *v)
{
    if (!strcmp(v, "bsdf")) return 0;
    if (!strcmp(v, "nee")) return 1;
    if (strcmp(v, "mis")) {
        fprintf(stderr, "ray: --estimator takes bsdf (BSDF sampling only), nee (next-event"
                " estimation) or mis, not %s\n", v);
        exit(2);
    }
    return 2;
}

/* -t asks for threads that a build without OpenMP does not have: said once. */
static void warn_threads(int threads)
{
#ifndef _OPENMP
    if (threads) fprintf(stderr, "ray: warning: -t %d is ignored: built without OpenMP, one thread\n", threads);
#else
    (void)threads;
#endif
}

/* Is -o name another file than the scene?  Else a message: the render
 * would overwrite its own scene.  The same file by device and inode under
 * POSIX (through links, and however the path is spelled), else by name. */
static int apart(const char *scene, const char *name)
{
#ifdef RAY_POSIX
    struct stat a, b;
    int same = stat(scene, &a) == 0 && stat(name, &b) == 0 && a.st_dev == b.st_dev
               && a.st_ino == b.st_ino;
#else
    int same = !strcmp(scene, name);
#endif
    if (same) fprintf(stderr, "ray: -o %s is the scene file; not overwritten\n", name);
    return !same;
}

/* A whole number from min to max, or exit with a message naming the option. */
static int int_arg(const char *opt, const char *arg, int min, int max)
{
    char *end;
    long v = arg ? strtol(arg, &end, 10) : 0;
    if (!arg || end == arg || *end || v < min || v > max) {
        fprintf(stderr, "ray: %s needs a whole number from %d to %d%s%s\n", opt, min, max,
                arg ? ", not " : "", arg ? arg : "");
        exit(2);
    }
    return (int)v;
}

/* Can -o FILE be written as asked?  Else a message (a usage error). */
static int output_usable(const char *name, int plain)
{
    int format = strcmp(name, "-") ? output_format(name) : FORMAT_PPM;
    if (format == FORMAT_OTHER)
        fprintf(stderr, "ray: cannot write %s: the formats are PPM, PNG and PFM (-o x.ppm, x.png, x.pfm)\n",
                name);
    else if (format != FORMAT_PPM && plain)
        fprintf(stderr, "ray: --p3 is a PPM form; %s is a %s\n", name,
                format == FORMAT_PNG ? "PNG" : "PFM");
    return format == FORMAT_PPM || (format != FORMAT_OTHER && !plain);
}

char *default_output(const char *scene)
{
    const char *base = file_part(scene), *dot = strrchr(base, '.');
    char *out;
    out = malloc(strlen(base) + 5);
    if (!out) {
        fprintf(stderr, "ray: out of memory\n");
        exit(1);
    }
    sprintf(out, "%.*s.ppm", dot ? (int)(dot - base) : (int)strlen(base), base);
    return out;
}

/* -s WxH into *w, *h; 0 with a message when it is not such a size. */
static int parse_size(const char *size, int *w, int *h)
{
    char *x, *end = NULL;
    long fw = strtol(size, &x, 10), fh = *x == 'x' ? strtol(x + 1, &end, 10) : 0;
    if (x == size || *x != 'x' || end == x + 1 || *end) {
        fprintf(stderr, "ray: -s needs WxH, like 640x480, not %s\n", size);
        return 0;
    }
    if (!check_size((double)fw, (double)fh, w, h)) {
        fprintf(stderr, "ray: -s %s: " SIZE_RULE "\n", size);
        return 0;
    }
    return 1;
}

/* The options in any order, then one scene.  A value may be attached
 * ("-n4", "--accel=kd") or follow ("-n 4"). */
int parse_args(int argc, char **argv, Args *a)
{
    int i;
    memset(a, 0, sizeof *a);
    a->integrator = a->estimator = -1;
    a->roulette = 1;
    a->seed = -1;
    for (i = 1; i < argc; i++) {
        const char *o = argv[i], *v;
        if (!strcmp(o, "--help") || !strcmp(o, "-h")) { usage(stdout); return 0; }
        else if (!strcmp(o, "--version")) { version(); return 0; }
        else if ((v = option_value(argc, argv, &i, "-o"))) a->output = v;
        else if ((v = option_value(argc, argv, &i, "-s"))) { if (!parse_size(v, &a->w, &a->h)) return 2; }
        else if ((v = option_value(argc, argv, &i, "-n"))) a->spp = int_arg("-n", v, 1, 1 << 20);
        else if ((v = option_value(argc, argv, &i, "-d"))) a->depth = int_arg("-d", v, 1, 64);
        else if ((v = option_value(argc, argv, &i, "-t"))) a->threads = int_arg("-t", v, 1, 4096);
        else if ((v = option_value(argc, argv, &i, "--accel"))) a->accel = accel_arg(v);
        else if (!strcmp(o, "--p3")) a->plain = 1;
        else if (!strcmp(o, "--gamma")) a->gamma = 1;
        else if (!strcmp(o, "--stats")) a->stats = 1;
        else if (!strcmp(o, "--stats=kv")) a->stats = 2;
        else if ((v = option_value(argc, argv, &i, "--view"))) a->view = view_arg(v);
        else if (!strcmp(o, "--pt")) a->integrator = 1;
        else if (!strcmp(o, "--whitted")) a->integrator = 0;
        else if (!strcmp(o, "--no-roulette")) a->roulette = 0;
        else if ((v = option_value(argc, argv, &i, "--seed"))) a->seed = int_arg("--seed", v, 0, 2147483647);
        else if ((v = option_value(argc, argv, &i, "--estimator"))) a->estimator = estimator_arg(v);
        else if (o[0] == '-' && o[1]) {
            fprintf(stderr, "ray: unknown option: %s\n", o);
            usage(stderr);
            return 2;
        } else if (a->scene) {
            fprintf(stderr, "ray: one scene only (%s and %s)\n", a->scene, o);
            return 2;
        } else
            a->scene = o;
    }
    if (!a->scene) { usage(stderr); return 2; }
    if (!a->output) a->output = a->made = default_output(a->scene);
    if (!output_usable(a->output, a->plain) || !apart(a->scene, a->output)) {
        free(a->made);
        return 2;
    }
    warn_threads(a->threads);
    return -1;
}

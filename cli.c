/* cli.c - the command line (cli.h): options into Args, with a message and
 * exit status 2 for anything it cannot take, and the help text.
 */
#include "posix.h"
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#ifdef RAY_POSIX
#include <sys/stat.h>
#include <unistd.h>
#endif
#include "cli.h"
#include "image.h"
#include "scene.h"

#ifndef REAL
#define REAL double         /* as ray.c is built, for --version */
#endif

/* The options, once: --help prints this, and the README shows it (in two
 * strings: C99 promises no more than 4095 characters in one). */
void usage(FILE *to)
{
    fputs("usage: ray [options] SCENE\n"
          "       ray --merge OUT PART...    (the parts of a split render, as one image)\n"
          "Renders SCENE with Whitted ray tracing, or path tracing (--pt): the sphere\n"
          "format (README.md), or NFF (Eric Haines' Neutral File Format, the SPD\n"
          "scenes') when it ends .nff; an OBJ mesh alone, framed and lit, when it\n"
          "ends .obj; - reads the sphere format or NFF from standard input.\n"
          "  -o FILE    output image: PNG if FILE ends .png, PFM or OpenEXR (floats) if\n"
          "             .pfm or .exr, a partial render (sums, for --merge) if .part,\n"
          "             else PPM (default: SCENE's base name + .ppm; - for stdout)\n"
          "  -s WxH     image size (default: the scene's `size`, else 512x512)\n"
          "  -n N       samples per pixel (default: the scene's `samples`, else 1)\n"
          "  -d N       Whitted: recursion depth, 1 = primary rays only (default: the\n"
          "             scene's, else 5); path tracing: rays a path may have (default:\n"
          "             the scene's `depth`, else no bound but Russian roulette)\n"
          "  -t N       threads (default: every core, when built with OpenMP)\n"
          "  --pt       path tracing (Kajiya's rendering equation); --whitted: Whitted's\n"
          "             (default: the scene's `integrator`, else Whitted)\n"
          "  --estimator E  the path tracer's: bsdf (BSDF sampling only), nee (next-event\n"
          "             estimation), mis (both, by multiple importance sampling; default)\n"
          "             light (light tracing: paths from the lights, joined to the\n"
          "             camera), bdpt (bidirectional path tracing: a path from the\n"
          "             camera and one from a light, joined every way, weighed by MIS),\n"
          "             photon (photon mapping: caustic and global photon maps, a\n"
          "             final gather), or ppm (progressive photon mapping: -n passes,\n"
          "             each its own photons and a smaller radius); light and bdpt:\n"
          "             whole images only, no --adaptive, no lens\n"
          "  --photons N  photon mapping's photons (default 200000); ppm: each pass's\n"
          "             (default: one per pixel)\n"
          "  --strategy S,T  bdpt: only the paths made of S vertices from the light and\n"
          "             T from the camera, weighed as in the whole (S >= 0, T >= 1)\n"
          "  --no-roulette  no Russian roulette: paths end at -d only\n"
          "  --sampler S  the path tracer's numbers: independent (a hash of the sample\n"
          "             and the dimension; default) or sobol (Owen-scrambled Sobol'\n"
          "             points, pair by pair: less noise for the same samples)\n"
          "  --light-choice C  how next-event estimation picks one light: importance\n"
          "             (by what it may bring to the point, down a light tree; default)\n"
          "             or power (by its power alone)\n"
          "  --seed N   the path tracer's noise, 0 or more (default 0): another N, other\n"
          "             noise\n"
          , to);
    fputs("  --adaptive E  samples in doubling rounds (from 8; the path tracer's from\n"
          "             16) up to -n: a pixel stops once its byte is known to within E\n"
          "             steps with 95% confidence, by its own samples; Whitted's also at\n"
          "             4 where its 8 neighbours' first 4 agree with its own\n"
          "  --no-skip  skip nothing the plain algorithm does: Whitted's rays of tiny\n"
          "             weight, shadow rays to lights behind a surface, the shadow cache,\n"
          "             the loop instead of a structure for a few objects, --adaptive;\n"
          "             the path tracer's shadow rays to the parts of a glowing sphere\n"
          "             that an opaque sphere hides (smallpt's lamp in its ceiling)\n"
          "  --crop X0,Y0,X1,Y1  render only the pixels X0 <= x < X1, Y0 <= y < Y1,\n"
          "             with the values a whole render gives them\n"
          "  --tile I/N job I (from 0) of N: the I-th of N bands of rows\n"
          "  --samples A:B  only samples A <= k < B of each pixel's -n\n"
          "  --merge    OUT PART...: add the parts (.part files) and write OUT, the\n"
          "             same bytes as one whole run\n"
          "  --checkpoint S  save the work so far every S seconds, and on SIGINT,\n"
          "             SIGTERM or SIGHUP, as OUT.part (OUT: -o's file); removed when done\n"
          "  --resume FILE  go on from a checkpoint, with the options it was made with\n"
          "  --p3       write plain-text P3 instead of binary P6\n"
          "  --gamma    encode Whitted's output with the sRGB curve (default: linear, as the\n"
          "             card's; a path-traced image always has it, but for PFM and EXR)\n"
          "  --accel A  kd (the kd-tree), bvh (bounding volume hierarchy), grid\n"
          "             (uniform grid), none (test every object) or auto (default:\n"
          "             the scene's `accel` line, else from 8 objects up the one that\n"
          "             renders a 32x32 probe of the image fastest, its build included;\n"
          "             below 64 objects the loop over them all takes its turn too)\n"
          "  --view V   instead of the picture, what a ray through each pixel's centre\n"
          "             meets: steps (the structure's work: nodes or cells plus tests,\n"
          "             black 0, blue 25, red 50, yellow 100, white 200), normal, depth;\n"
          "             or samples: the samples each pixel took, white for all of -n;\n"
          "             or photons: the picture, and over it the photons stored (photon:\n"
          "             the global map's blue, the caustic map's yellow; ppm: the last\n"
          "             pass's)\n"
          "  --stats    print rays by kind, hits, the tree and time on stderr;\n"
          "             --stats=kv: the same as one `key value` line each\n"
          "  --version  the version, and how it was built\n"
          "  --help     this text\n", to);
}

#define RAY_VERSION "1.1"

const char *program_version(void)
{
    return sizeof(REAL) == sizeof(float) ? "ray " RAY_VERSION " float" : "ray " RAY_VERSION " double";
}

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
    if (!strcmp(v, "samples")) return 4;
    if (!strcmp(v, "photons")) return 5;
    if (strcmp(v, "depth")) {
        fprintf(stderr, "ray: --view takes steps, normal, depth, samples or photons, not %s\n", v);
        exit(2);
    }
    return 3;
}

/* A number of 8-bit steps, above 0 and at most 255, or exit with a message. */
static double steps_arg(const char *opt, const char *arg)
{
    char *end;
    double v = arg ? strtod(arg, &end) : 0;
    if (!arg || end == arg || *end || !(v > 0 && v <= 255)) {
        fprintf(stderr, "ray: %s takes a number of 8-bit steps above 0, at most 255, not %s\n", opt,
                arg ? arg : "nothing");
        exit(2);
    }
    return v;
}

/* Whole numbers separated by sep ("," or ":" or "/"), n of them, each at
 * least 0, into v; or exit with a message that shows the form. */
static void numbers_arg(const char *opt, const char *arg, const char *sep, int n, const char *form, int *v)
{
    const char *p = arg;
    int k;
    for (k = 0; k < n; k++) {
        char *end;
        long x = strtol(p, &end, 10);
        if (end == p || x < 0 || x > 1 << 30 || (k < n - 1 ? *end != *sep : *end != 0) || !isdigit((unsigned char)*p)) {
            fprintf(stderr, "ray: %s takes %s (whole numbers, 0 or more), not %s\n", opt, form, arg);
            exit(2);
        }
        v[k] = (int)x;
        p = end + 1;
    }
}

/* --crop, --tile and --samples into a; exit with a message when one
 * cannot be right whatever the image (the image's size is checked later). */
static void split_arg(Args *a, const char *opt, const char *v)
{
    if (!strcmp(opt, "--crop")) {
        numbers_arg(opt, v, ",", 4, "X0,Y0,X1,Y1", a->crop);
        a->cropped = 1;
        if (a->crop[2] <= a->crop[0] || a->crop[3] <= a->crop[1]) {
            fprintf(stderr, "ray: --crop %s holds no pixel: X1 must be above X0, Y1 above Y0\n", v);
            exit(2);
        }
    } else if (!strcmp(opt, "--tile")) {
        int t[2];
        numbers_arg(opt, v, "/", 2, "I/N, job I (from 0) of N", t);
        if (t[1] < 1 || t[0] >= t[1]) {
            fprintf(stderr, "ray: --tile %s: I must be below N, from 0 (job 0 of 4 to job 3 of 4)\n", v);
            exit(2);
        }
        a->tile = t[0], a->tiles = t[1];
    } else {
        numbers_arg(opt, v, ":", 2, "A:B, samples A <= k < B", a->samples);
        if (a->samples[1] <= a->samples[0]) {
            fprintf(stderr, "ray: --samples %s holds no sample: B must be above A\n", v);
            exit(2);
        }
    }
}

/* --strategy S,T: S vertices from the light, T from the camera; the
 * camera's end is always there (T >= 1), and a path has a ray (S + T >= 2). */
static void strategy_arg(Args *a, const char *v)
{
    numbers_arg("--strategy", v, ",", 2, "S,T, vertices from the light and from the camera", a->strategy);
    if (a->strategy[1] < 1 || a->strategy[0] + a->strategy[1] < 2) {
        fprintf(stderr, "ray: --strategy %s: T must be 1 or more (the camera's vertex), and S + T"
                " 2 or more (a path has a ray)\n", v);
        exit(2);
    }
}

/* A number of seconds above 0, or exit with a message. */
static double seconds_arg(const char *opt, const char *arg)
{
    char *end;
    double v = strtod(arg, &end);
    if (end == arg || *end || !(v > 0 && v < 1e9)) {
        fprintf(stderr, "ray: %s takes a number of seconds above 0, not %s\n", opt, arg);
        exit(2);
    }
    return v;
}

/* --sampler's numbers: 0 independent, 1 sobol; or exit with the choices. */
static int sampler_arg(const char *v)
{
    if (!strcmp(v, "independent")) return 0;
    if (strcmp(v, "sobol")) {
        fprintf(stderr, "ray: --sampler takes independent (a hash a number) or sobol (Owen-scrambled"
                " Sobol' points), not %s\n", v);
        exit(2);
    }
    return 1;
}

/* --light-choice's rule: 0 importance, 1 power; or exit with the choices. */
static int light_choice_arg(const char *v)
{
    if (!strcmp(v, "importance")) return 0;
    if (strcmp(v, "power")) {
        fprintf(stderr, "ray: --light-choice takes importance (what a light may bring to the point)"
                " or power (its power alone), not %s\n", v);
        exit(2);
    }
    return 1;
}

/* The path tracer's estimator named by --estimator, or exit with the choices. */
static int estimator_arg(const char *v)
{
    if (!strcmp(v, "bsdf")) return 0;
    if (!strcmp(v, "nee")) return 1;
    if (!strcmp(v, "light")) return 3;
    if (!strcmp(v, "bdpt")) return 4;
    if (!strcmp(v, "photon")) return 5;
    if (!strcmp(v, "ppm")) return 6;
    if (strcmp(v, "mis")) {
        fprintf(stderr, "ray: --estimator takes bsdf (BSDF sampling only), nee (next-event"
                " estimation), mis, light (light tracing), bdpt (bidirectional path tracing),"
                " photon (photon mapping) or ppm (progressive photon mapping), not %s\n", v);
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
    int same = same_file(scene, name);
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
        fprintf(stderr, "ray: cannot write %s: the formats are PPM, PNG, PFM and OpenEXR "
                "(-o x.ppm, x.png, x.pfm, x.exr)\n", name);
    else if (format != FORMAT_PPM && plain)
        fprintf(stderr, "ray: --p3 is a PPM form; %s is %s, not PPM\n", name, format_name(format));
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

/* ray --merge OUT PART...: only --p3 besides (for OUT); OUT no part. */
static int merge_args(Args *a)
{
    int i;
    if (a->nparts < 2) {
        fprintf(stderr, "ray: --merge needs OUT and at least one part: ray --merge OUT PART...\n");
        return 2;
    }
    if (a->output || a->w || a->spp || a->cropped || a->tiles || a->samples[1] || a->checkpoint || a->resume) {
        fprintf(stderr, "ray: --merge takes OUT and the parts (and --p3); the parts say how they were made\n");
        return 2;
    }
    a->output = a->parts[0];
    if (!output_usable(a->output, a->plain)) return 2;
    if (output_format(a->output) == FORMAT_PART) {
        fprintf(stderr, "ray: --merge writes an image (.ppm, .png, .pfm, .exr), not %s\n", a->output);
        return 2;
    }
    for (i = 1; i < a->nparts; i++)
        if (same_file(a->parts[i], a->output)) {
            fprintf(stderr, "ray: --merge %s would overwrite its part %s\n", a->output, a->parts[i]);
            return 2;
        }
    return -1;
}

/* The split options together: one way to choose the pixels, checkpoints
 * to a file; else a message (a usage error). */
static int split_args_fit(const Args *a)
{
    const char *why = a->cropped && a->tiles ? "--crop and --tile both choose the pixels: give one"
                      : a->checkpoint && !strcmp(a->output, "-") ? "--checkpoint needs -o FILE: it saves to FILE.part"
                      : (a->view && (a->samples[1] || a->checkpoint || a->resume || output_format(a->output) == FORMAT_PART))
                        ? "--view draws one ray a pixel: it has no samples to split, save or merge"
                      : a->resume && same_file(a->resume, a->output) ? "--resume's file is -o's: it would be overwritten"
                      : NULL;
    if (why) fprintf(stderr, "ray: %s\n", why);
    return !why;
}

/* The options in any order, then one scene.  A value may be attached
 * ("-n4", "--accel=kd") or follow ("-n 4"). */
int parse_args(int argc, char **argv, Args *a)
{
    int i;
    memset(a, 0, sizeof *a);
    a->integrator = a->estimator = a->sampler = a->light_choice = -1;
    a->strategy[0] = a->strategy[1] = -1;
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
        else if (!strcmp(o, "--no-skip")) a->no_skip = 1;
        else if ((v = option_value(argc, argv, &i, "--seed"))) a->seed = int_arg("--seed", v, 0, 2147483647);
        else if ((v = option_value(argc, argv, &i, "--estimator"))) a->estimator = estimator_arg(v);
        else if ((v = option_value(argc, argv, &i, "--adaptive"))) a->adaptive = steps_arg("--adaptive", v);
        else if ((v = option_value(argc, argv, &i, "--sampler"))) a->sampler = sampler_arg(v);
        else if ((v = option_value(argc, argv, &i, "--light-choice"))) a->light_choice = light_choice_arg(v);
        else if ((v = option_value(argc, argv, &i, "--strategy"))) strategy_arg(a, v);
        else if ((v = option_value(argc, argv, &i, "--photons"))) a->photons = int_arg("--photons", v, 1, 100000000);
        else if ((v = option_value(argc, argv, &i, "--crop"))) split_arg(a, "--crop", v);
        else if ((v = option_value(argc, argv, &i, "--tile"))) split_arg(a, "--tile", v);
        else if ((v = option_value(argc, argv, &i, "--samples"))) split_arg(a, "--samples", v);
        else if ((v = option_value(argc, argv, &i, "--checkpoint"))) a->checkpoint = seconds_arg("--checkpoint", v);
        else if ((v = option_value(argc, argv, &i, "--resume"))) a->resume = v;
        else if (!strcmp(o, "--merge")) a->merge = 1;
        else if (o[0] == '-' && o[1]) {
            fprintf(stderr, "ray: unknown option: %s\n", o);
            usage(stderr);
            return 2;
        } else if (a->merge || !a->scene) {
            if (!a->parts && !(a->parts = malloc(sizeof *a->parts * (size_t)argc))) return 2;
            a->parts[a->nparts++] = o;  /* the scene, or --merge's OUT and parts */
            a->scene = a->parts[0];
        } else {
            fprintf(stderr, "ray: one scene only (%s and %s)\n", a->scene, o);
            return 2;
        }
    }
    if (a->merge) return merge_args(a);
    if (!a->scene) { usage(stderr); return 2; }
    if (a->nparts > 1) {
        fprintf(stderr, "ray: one scene only (%s and %s)\n", a->parts[0], a->parts[1]);
        return 2;
    }
    if (!split_args_fit(a)) return 2;
    a->name = strcmp(a->scene, "-") ? a->scene : "stdin";
    if (!a->output) a->output = a->made = default_output(a->name);
    if (!output_usable(a->output, a->plain) || (strcmp(a->scene, "-") && !apart(a->scene, a->output))) {
        free(a->made);
        a->made = NULL;
        return 2;
    }
    warn_threads(a->threads);
    return -1;
}

static unsigned long long all_rays(const Stats *st)
{
    return st->primary + st->shadow + st->reflected + st->refracted + st->bounced;
}

/* --stats=kv: for programs to read (bench/run.sh does). */
static void print_stats_kv(FILE *f, const Stats *st)
{
    static const char *const estimators[] = { "bsdf", "nee", "mis", "light", "bdpt", "photon", "ppm" };
    fprintf(f, "spheres %d\ncones %d\ntriangles %d\npoint_lights %d\nglowing_objects %d\n",
            st->spheres, st->cones, st->triangles, st->point_lights, st->glowing);
    fprintf(f, "width %d\nheight %d\nspp %d\nthreads %d\nrenderer %s\n", st->w, st->h, st->spp,
            st->threads, st->path ? "path" : "whitted");
    if (st->path)
        fprintf(f, "estimator %s\nroulette %d\nmax_rays %d\nseed %u\nlights %d\n", estimators[st->estimator],
                st->roulette, st->max_rays, st->seed, st->lights);
    else
        fprintf(f, "depth %d\n", st->depth);
    fprintf(f, "accel %s\n", st->accel);
    if (!strcmp(st->accel, "kd"))
        fprintf(f, "accel_nodes %ld\naccel_leaves %ld\naccel_empty_leaves %ld\naccel_depth %ld\n"
                "accel_prims_per_leaf %.4f\naccel_bytes %.0f\naccel_sah_cost %.4f\n", st->kd.nodes,
                st->kd.leaves, st->kd.empty_leaves, st->kd.max_depth, st->kd.prims_per_leaf,
                (double)st->kd.bytes, st->kd.sah_cost);
    else if (!strcmp(st->accel, "bvh"))
        fprintf(f, "accel_nodes %ld\naccel_leaves %ld\naccel_depth %ld\naccel_prims_per_leaf %.4f\n"
                "accel_bytes %lu\naccel_sah_cost %.4f\n", st->bvh.nodes, st->bvh.leaves,
                st->bvh.max_depth, st->bvh.prims_per_leaf, (unsigned long)st->bvh.bytes,
                st->bvh.sah_cost);
    else if (!strcmp(st->accel, "grid"))
        fprintf(f, "grid_cells %dx%dx%d\naccel_empty_cells %ld\naccel_refs %ld\naccel_bytes %lu\n",
                st->grid.res[0], st->grid.res[1], st->grid.res[2], st->grid.empty_cells,
                (long)st->grid.prim_refs, (unsigned long)st->grid.bytes);
    fprintf(f, "rays %llu\nrays_primary %llu\nrays_shadow %llu\nrays_reflected %llu\n"
            "rays_refracted %llu\nrays_bounced %llu\nrays_cut %llu\nsamples_discarded %llu\n",
            all_rays(st), st->primary, st->shadow, st->reflected, st->refracted, st->bounced,
            st->cut, st->discarded);
    fprintf(f, "no_skip %d\nskipped_behind %llu\nskipped_faint %llu\nskipped_dim %llu\nclipped_lights %d\n",
            st->no_skip, st->behind, st->faint, st->dim, st->clipped);
    if (st->adaptive > 0)
        fprintf(f, "adaptive_steps %g\nsamples_taken %llu\nsamples_per_pixel %.4f\nsamples_min %d\nsamples_max %d\n",
                st->adaptive, st->samples, (double)st->samples / ((double)st->w * st->h), st->spp_min, st->spp_max);
    fprintf(f, "queries %llu\nnearest_queries %llu\nhits %llu\ntests %llu\nsteps %llu\n",
            st->queries, st->nearest, st->hits, st->tests, st->steps);
    fprintf(f, "load_s %.6f\nbuild_s %.6f\nrender_s %.6f\ncpu_s %.6f\n", st->load, st->build,
            st->seconds, st->cpu);
}

/* The structure's line of --stats, in words. */
static void print_accel(FILE *f, const Stats *st)
{
    if (!strcmp(st->accel, "kd"))
        fprintf(f, "kd-tree    %ld nodes, %ld leaves (%ld empty), depth %ld,"
                " %.2f objects per leaf,\n"
                "           %.1f MB, SAH cost %.2f, built in %.3f s\n",
                st->kd.nodes, st->kd.leaves, st->kd.empty_leaves, st->kd.max_depth,
                st->kd.prims_per_leaf, st->kd.bytes / 1e6, st->kd.sah_cost, st->build);
    else if (!strcmp(st->accel, "bvh"))
        fprintf(f, "bvh        %ld nodes, %ld leaves, depth %ld, %.2f objects per leaf,\n"
                "           %lu bytes, SAH cost %.2f, built in %.3f s\n",
                st->bvh.nodes, st->bvh.leaves, st->bvh.max_depth, st->bvh.prims_per_leaf,
                (unsigned long)st->bvh.bytes, st->bvh.sah_cost, st->build);
    else if (!strcmp(st->accel, "grid"))
        fprintf(f, "grid       %dx%dx%d cells (%ld empty), %.2f references per object,\n"
                "           %lu bytes, built in %.3f s\n", st->grid.res[0], st->grid.res[1],
                st->grid.res[2], st->grid.empty_cells,
                st->objects ? (double)st->grid.prim_refs / st->objects : 0.0,
                (unsigned long)st->grid.bytes, st->build);
    else
        fprintf(f, "accel      none: every ray tests every object\n");
}

void print_stats(FILE *f, const Stats *st, int kv)
{
    static const char *const estimators[] = { "BSDF sampling only", "next-event estimation",
                                              "MIS (BSDF sampling and next-event estimation)",
                                              "light tracing (paths from the lights, to the camera)",
                                              "bidirectional path tracing (MIS over every join)",
                                              "photon mapping (caustic and global maps, final gather)",
                                              "progressive photon mapping (passes, the radius shrinking)" };
    unsigned long long rays = all_rays(st);
    if (kv) {
        print_stats_kv(f, st);
        return;
    }
    fprintf(f, "scene      %d spheres, %d cones, %d triangles, %d point lights, %d glowing;"
            " read in %.3f s\n", st->spheres, st->cones, st->triangles, st->point_lights,
            st->glowing, st->load);
    if (st->path)
        fprintf(f, "image      %dx%d, %d spp, path traced, %d thread%s\n", st->w, st->h, st->spp,
                st->threads, st->threads == 1 ? "" : "s");
    else
        fprintf(f, "image      %dx%d, %d spp, depth %d, %d thread%s\n", st->w, st->h, st->spp,
                st->depth, st->threads, st->threads == 1 ? "" : "s");
    print_accel(f, st);
    if (st->path) {
        char bound[32] = "none but roulette";
        if (st->max_rays) sprintf(bound, "%d rays", st->max_rays);
        fprintf(f, "paths      %s, roulette %s, length bound %s, seed %u, %d lights\n",
                estimators[st->estimator],
                st->roulette ? "on" : "off", bound, st->seed, st->lights);
        fprintf(f, "rays       %llu: %llu primary, %llu shadow, %llu bounced\n",
                rays, st->primary, st->shadow, st->bounced);
        fprintf(f, "samples    %llu discarded (not finite)\n", st->discarded);
    } else
        fprintf(f, "rays       %llu: %llu primary, %llu shadow, %llu reflected, %llu refracted\n",
                rays, st->primary, st->shadow, st->reflected, st->refracted);
    if (!st->path && st->cut)
        fprintf(f, "budget     %llu reflected or refracted rays not traced: past %d a primary ray\n",
                st->cut, st->budget);
    if (st->no_skip) fprintf(f, "skips      none (--no-skip)\n");
    if (st->path && !st->no_skip)
        fprintf(f, "skips      %d glowing spheres sampled only where opaque spheres cutting them leave them"
                " to be seen\n", st->clipped);
    if (!st->path && !st->no_skip)
        fprintf(f, "skips      %llu shadow rays to lights behind, %llu to lights too dim to change the pixel"
                " by a quarter step, %llu reflected or refracted rays of weight under 1/512; blockers tried"
                " first (the shadow cache)\n", st->behind, st->dim, st->faint);
    if (st->adaptive > 0)
        fprintf(f, "adaptive   to %g steps: %.2f samples a pixel, from %d to %d (of %d)\n", st->adaptive,
                (double)st->samples / ((double)st->w * st->h), st->spp_min, st->spp_max, st->spp);
    fprintf(f, "hits       %llu (%.1f%% of the rays that ask for the nearest hit)\n", st->hits,
            st->nearest ? 100.0 * st->hits / (double)st->nearest : 0.0);
    fprintf(f, "per ray    %.2f intersection tests, %.2f tree steps\n",
            st->queries ? (double)st->tests / st->queries : 0.0,
            st->queries ? (double)st->steps / st->queries : 0.0);
    fprintf(f, "time       %.3f s, %.2f Mrays/s (CPU %.3f s, all threads)\n", st->seconds,
            st->seconds > 0 ? rays / st->seconds * 1e-6 : 0.0, st->cpu);
}

/* Seconds on a wall clock (processor time where there is none: with threads
 * that overstates the time). */
double now(void)
{
#ifdef RAY_POSIX
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
#else
    return (double)clock() / CLOCKS_PER_SEC;
#endif
}

int stderr_is_terminal(void)
{
#ifdef RAY_POSIX
    return isatty(2);
#else
    return 0;
#endif
}

/* "ray:  42%  ETA 1:05": rows done out of rows, and the time left if the
 * rows still to do take as long as those done so far took. */
void show_progress(double start, int done, int rows)
{
    long left = (long)((now() - start) * (rows - done) / done + 0.5);
    if (left >= 3600)
        fprintf(stderr, "\rray: %3d%%  ETA %ld:%02ld:%02ld ", done * 100 / rows, left / 3600,
                left / 60 % 60, left % 60);
    else
        fprintf(stderr, "\rray: %3d%%  ETA %ld:%02ld    ", done * 100 / rows, left / 60, left % 60);
}

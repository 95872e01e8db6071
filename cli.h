/* cli.h - the command line: what it asks for, read into Args, and the
 * one copy of its help text (ray --help).
 *
 * Numbers that choose among ray.c's modes are the modes' places in the
 * lists below, which ray.c's enums follow: integrator 0 Whitted, 1 path
 * tracing; estimator 0 bsdf, 1 nee, 2 mis; view 1 steps, 2 normal,
 * 3 depth.
 */
#ifndef CLI_H
#define CLI_H

#include <stdio.h>
#include "kdtree.h"
#include "bvh.h"
#include "grid.h"

typedef struct {
    const char *scene;      /* the scene file */
    const char *name;       /* the scene as messages name it: "stdin" for "-" */
    const char *output;     /* -o, or the scene's base name with .ppm */
    const char *accel;      /* --accel: kd, bvh, grid, none, auto; NULL: not given */
    int w, h;               /* -s; 0: the scene's */
    int spp, depth;         /* -n, -d; 0: the scene's */
    int threads;            /* -t; 0: every core */
    int plain, gamma;       /* --p3, --gamma */
    int stats;              /* --stats: 0 none, 1 prose, 2 key value lines (--stats=kv) */
    int integrator;         /* --whitted 0, --pt 1; -1: the scene's */
    int estimator;          /* --estimator; -1: the scene's (mis) */
    int sampler;            /* --sampler: 0 independent, 1 sobol; -1: not given */
    int light_choice;       /* --light-choice: 0 importance, 1 power; -1: not given */
    int strategy[2];        /* --strategy S,T; -1: not given */
    int photons;            /* --photons N; 0: not given */
    int roulette;           /* 0 after --no-roulette */
    int view;               /* --view; 0: the picture itself */
    double adaptive;        /* --adaptive E; 0: every pixel takes every sample */
    int no_skip;            /* --no-skip */
    long seed;              /* --seed; -1: not given */
    int crop[4], cropped;   /* --crop X0,Y0,X1,Y1 */
    int tile, tiles;        /* --tile I/N; tiles 0: not given */
    int samples[2];         /* --samples A:B; B 0: not given */
    double checkpoint;      /* --checkpoint S; 0: none */
    const char *resume;     /* --resume FILE, or NULL */
    int merge;              /* --merge: parts[0] is OUT, parts[1..] the parts */
    const char **parts;     /* the arguments that are no options (freed by the caller) */
    int nparts;
    char *made;             /* what parse_args allocated (the default output name) */
} Args;

/* argv into *a.  Returns -1 when the program should go on; else the exit
 * status it should end with (0 after --help or --version, 2 after a
 * message for a usage error). */
int parse_args(int argc, char **argv, Args *a);

/* The output named after the scene: its base name with .ppm, in the
 * current directory (freed by the caller). */
char *default_output(const char *scene);

void usage(FILE *to);

/* "ray 1.1 double" (or float): the version, and the build's arithmetic. */
const char *program_version(void);

/* Seconds on a wall clock (processor time where there is none). */
double now(void);

/* The progress line, "ray:  42%  ETA 1:05", goes to a terminal only. */
int stderr_is_terminal(void);
void show_progress(double start, int done, int rows);

/* What a render measured, for --stats: the scene, the image, the
 * structure, the rays by kind and the time. */
typedef struct {
    int spheres, cones, triangles, objects, point_lights, glowing;
    int w, h, spp, threads, path, depth;
    int estimator;                  /* the path tracer's, as Args has it: 0 bsdf, 1 nee, 2 mis */
    int roulette, max_rays, lights; /* lights: the path tracer's, the sky included */
    unsigned seed;
    const char *accel;              /* none, kd, bvh or grid: which of these is filled */
    kd_info kd;
    bvh_info bvh;
    grid_info grid;
    unsigned long long primary, shadow, reflected, refracted, bounced, cut, discarded;
    unsigned long long queries, nearest, hits, tests, steps;
    int budget;                     /* Whitted: secondary rays a primary ray may spawn */
    double adaptive;                /* --adaptive's E, or 0 */
    int no_skip;                    /* --no-skip: every skip off */
    int clipped;                    /* the path tracer: glowing spheres sampled where clips leave them seen */
    unsigned long long behind, faint, dim;  /* Whitted's skips: shadow rays to lights behind, */
                                        /* faint rays, shadow rays to lights too dim */
    unsigned long long samples;     /* the samples all pixels took */
    int spp_min, spp_max;           /* the fewest and the most a pixel took */
    double load, build, seconds, cpu;   /* seconds: reading, building, rendering; cpu: rendering */
} Stats;

/* In words, or with kv as `key value` lines, one a line (the README lists
 * the keys). */
void print_stats(FILE *f, const Stats *st, int kv);

#endif

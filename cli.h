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

typedef struct {
    const char *scene;      /* the scene file */
    const char *output;     /* -o, or the scene's base name with .ppm */
    const char *accel;      /* --accel: kd, bvh, grid, none, auto; NULL: not given */
    int w, h;               /* -s; 0: the scene's */
    int spp, depth;         /* -n, -d; 0: the scene's */
    int threads;            /* -t; 0: every core */
    int plain, gamma;       /* --p3, --gamma */
    int stats;              /* --stats: 0 none, 1 prose, 2 key value lines (--stats=kv) */
    int integrator;         /* --whitted 0, --pt 1; -1: the scene's */
    int estimator;          /* --estimator; -1: the scene's (mis) */
    int roulette;           /* 0 after --no-roulette */
    int view;               /* --view; 0: the picture itself */
    long seed;              /* --seed; -1: not given */
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

#endif

/* sphereflake - Eric Haines' "balls" scene (Standard Procedural Databases,
 * 1987) in the .sph format of scenes/, written to standard output.
 *
 *     cc -std=c99 -O2 -o sphereflake bench/sphereflake.c -lm
 *     ./sphereflake 4 >flake.sph      (level 4: 7381 flake spheres)
 *
 * The flake: a sphere of radius 0.5 at the origin, and on every sphere nine
 * children of a third of its radius, touching it.  Six children sit on its
 * equator, 60 degrees apart; three sit above, between them, at the elevation
 * asin(sqrt(2/3)) = 54.7 degrees.  The equator is the plane perpendicular to
 * the direction the sphere grew in (+z for the root), so no child points back
 * into its parent.  Level L has 1 + 9 + ... + 9^L = (9^(L+1) - 1)/8 spheres.
 *
 * Around it, as in SPD's balls: the ground at z = -0.5, three lights in the
 * directions of SPD's (4,3,2), (1,-4,4), (-3,1,5), and SPD's viewpoint.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct { double x, y, z; } vec;

static vec v3(double x, double y, double z) { vec r; r.x = x; r.y = y; r.z = z; return r; }
static vec add(vec a, vec b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static vec mul(vec a, double s) { return v3(a.x * s, a.y * s, a.z * s); }
static double dot(vec a, vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static vec cross(vec a, vec b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static vec unit(vec a) { return mul(a, 1 / sqrt(dot(a, a))); }

/* One line of the file: centre, colour, radius, then "kd ks kt kl ir". */
static void sphere(vec c, const char *colour, double r, const char *finish)
{
    printf("%.9g %.9g %.9g  %s  %.9g  %s\n", c.x, c.y, c.z, colour, r, finish);
}

/* The sphere at c of radius r grew in direction w; (u, v, w) is a
 * right-handed frame that fixes where its children go around w. */
static void flake(vec c, double r, vec u, vec v, vec w, int level)
{
    const double pi = 3.14159265358979323846;
    int i;

    sphere(c, "1 .9 .7", r, ".5 .5 0 0 1");
    if (level == 0) return;
    for (i = 0; i < 9; i++) {
        double az, ce, se;
        vec d, cu;
        if (i < 6) {
            az = (15 + 60 * i) * pi / 180;
            ce = 1, se = 0;
        } else {
            az = (45 + 120 * (i - 6)) * pi / 180;
            ce = sqrt(1.0 / 3), se = sqrt(2.0 / 3);
        }
        d = add(add(mul(u, ce * cos(az)), mul(v, ce * sin(az))), mul(w, se));
        /* The child's frame takes its reference direction from the parent's
         * axis, so every sub-flake is a rotated copy of the whole one.  That
         * axis is never parallel to d: children are at most 54.7 degrees up. */
        cu = unit(add(w, mul(d, -dot(w, d))));
        flake(add(c, mul(d, r * 4 / 3)), r / 3, cu, cross(d, cu), d, level - 1);
    }
}

static void usage(FILE *f)
{
    fprintf(f,
"usage: sphereflake [LEVEL]\n"
"Writes Haines' sphereflake (SPD \"balls\") of recursion LEVEL (0..6, default 4)\n"
"as a .sph scene to standard output: (9^(LEVEL+1)-1)/8 reflective spheres, a\n"
"ground, three lights and SPD's camera.  Level 4 has 7381 flake spheres.\n");
}

int main(int argc, char **argv)
{
    int level = 4;
    char *end;
    long l;
    const double ground = 100;
    const vec light[3] = { { 4, 3, 2 }, { 1, -4, 4 }, { -3, 1, 5 } };
    int i;

    if (argc > 2) {
        fprintf(stderr, "sphereflake: too many arguments (try --help)\n");
        return 2;
    }
    if (argc == 2) {
        if (strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "--help") == 0) {
            usage(stdout);
            return 0;
        }
        l = strtol(argv[1], &end, 10);
        /* Level 7 would be 5.4 million spheres, half a gigabyte of text. */
        if (end == argv[1] || *end || l < 0 || l > 6) {
            fprintf(stderr, "sphereflake: level must be a whole number from 0 "
                    "to 6, not '%s'\n", argv[1]);
            return 2;
        }
        level = (int)l;
    }

    printf("# Sphereflake, after Eric Haines' SPD \"balls\" (1987), level %d:\n"
           "# %ld flake spheres.  Written by bench/sphereflake.c.\n",
           level, ((long)pow(9, level + 1) - 1) / 8);
    printf("size 512 512\n"
           "depth 5\n"
           "ambient .1 .1 .1\n"
           /* SPD's sky blue */
           "background .078 .361 .753\n"
           "camera 2.1 1.3 1.7   0 0 0   0 0 1   45\n"
           "pixel centre\n");

    printf("\n# the flake: cx cy cz  r g b  radius  kd ks kt kl ir\n");
    flake(v3(0, 0, 0), 0.5, v3(1, 0, 0), v3(0, 1, 0), v3(0, 0, 1), level);

    /* A sphere stands in for SPD's ground plane, since the format has only
     * spheres.  Its radius is a compromise.  Smaller, and the top of SPD's
     * view reaches the unlit side beyond its curve (at 50 it does).  Larger,
     * and the float build's error becomes mostly the ground's: ray.c offsets
     * secondary rays in proportion to the coordinates of the surface they
     * leave, and shadow edges on a radius-1000 ground move visibly (RMSE
     * float against double, 512x512 at 1 spp: 3.3 at radius 100, 8.3 at
     * 1000). */
    printf("\n# the ground, top at z = -0.5\n");
    sphere(v3(0, 0, -0.5 - ground), "1 .75 .33", ground, ".8 0 0 0 1");

    /* The lights are ten times further out than SPD's point lights, so that
     * they act almost like its distant ones, and small enough (half a degree
     * across) to show only as highlights in the mirrors. */
    printf("\n# the lights\n");
    for (i = 0; i < 3; i++)
        sphere(mul(light[i], 10), "1 1 1", 0.5, "0 0 0 .5 1");
    fflush(stdout);
    return ferror(stdout) ? 2 : 0;
}

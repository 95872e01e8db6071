/* spd - Eric Haines' Standard Procedural Databases, the seven scenes of the
 * classic ray-tracing benchmark, written as NFF on standard output.
 *
 *     cc -std=c99 -O2 -o tools/spd tools/spd.c -lm
 *     tools/spd DB [SIZE] > scene.nff        (or tools/spd DB -s SIZE)
 *     tools/spd --help
 *
 * DB is balls, gears, mount, rings, teapot, tetra or tree; SIZE is the SPD's
 * size factor, by default the benchmark's: balls 4, gears 4, mount 6, rings 7,
 * teapot 6, tetra 6, tree 11.  Exit status 0, or 2 on a usage error, 1 if the
 * output could not be written.
 *
 * The scenes are those of E. Haines, "A Proposal for Standard Graphics
 * Environments", IEEE CG&A 7(11), November 1987, pp. 3-5, as his SPD 3.14
 * package (2005; github.com/erich666/StandardProceduralDatabases) generates
 * them with its default NFF output.  This file is written anew from the
 * algorithms its generators describe; no code is taken from them.  What the
 * output must match is the SPD's, number for number as printed (%g, six
 * significant digits): the same entities in the same order, computed with
 * the same arithmetic in the same order, so that the files in ../shared/spd
 * come out again byte for byte (tests/spd.test.sh compares them).  That is
 * why the matrices below are row-vector matrices (a point is p * M) as in the
 * SPD, and why some sums keep a "+ 0" term: it turns a -0 into the 0 that
 * the SPD prints.
 *
 * The one exception is mount: its fractal needs random numbers, and here they
 * come from our own generator (a SplitMix64 hash and Box-Muller, see
 * gauss_at), not from the SPD's, so its heights differ from the SPD's file
 * number for number.  Its mountain is another mountain of the same kind,
 * extent and roughness, with the SPD's spheres, view and light; the seed was
 * picked so that its height range and the share of eye rays that hit it are
 * the SPD's within a few per cent (tests/spd.test.sh checks 0.1 and 10%).
 *
 *   balls   the sphereflake: a sphere and, recursively, nine spheres of a
 *           third of its radius around each one (Haines 1987); a floor.
 *   gears   SIZE^3 meshed gears of 36 teeth, each face one concave 144-gon,
 *           some transparent, on a mirror floor.
 *   mount   a fractal mountain by midpoint subdivision of a square grid
 *           (Fournier, Fussell and Carpenter, "Computer Rendering of
 *           Stochastic Models", CACM 25(6), 1982), fractal dimension 2.2,
 *           and a pyramid of four glass spheres (after P. Watterberg).
 *   rings   a pyramid of objects of six pentagonal rings, each ring
 *           joining the midpoints of edges of a dodecahedron: cylinders
 *           with spheres at the joints; a wall behind.
 *   teapot  Newell's teapot, its 32 Bezier patches cut into SIZE x SIZE x 2
 *           triangles with normals, on a SIZE x SIZE checkerboard.
 *   tetra   a recursive tetrahedral pyramid (Glassner, "Space Subdivision
 *           for Fast Ray Tracing", IEEE CG&A 4(10), 1984; Kay and Kajiya,
 *           "Ray Tracing Complex Scenes", SIGGRAPH 1986), 4^SIZE triangles.
 *   tree    a binary tree of cones and spheres by Aono and Kunii's method
 *           ("Botanical Tree Image Generation", IEEE CG&A 4(5), May 1984),
 *           2^(SIZE+1)-1 branches, seven lights.
 *
 * NFF (Haines' Neutral File Format): "b" background, "v" view, "l" light,
 * "f r g b Kd Ks Shine T ior" material, "s" sphere, "c" cone, "p" polygon,
 * "pp" polygon with vertex normals.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.141592653589793

typedef struct { double x, y, z; } vec;
typedef struct { double m[4][4]; } mat;     /* row vectors: p' = p * M */

static vec v3(double x, double y, double z) { vec r; r.x = x; r.y = y; r.z = z; return r; }
static vec add(vec a, vec b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static vec sub(vec a, vec b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static double dot(vec a, vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static vec cross(vec a, vec b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
/* Divides by the length (not multiplies by its inverse), as the SPD does. */
static vec unit(vec a)
{
    double len = sqrt(dot(a, a));
    return len > 0 ? v3(a.x / len, a.y / len, a.z / len) : a;
}

static mat identity(void)
{
    mat r;
    int i, j;
    for (i = 0; i < 4; i++)
        for (j = 0; j < 4; j++) r.m[i][j] = i == j;
    return r;
}

/* Rotation by angle a (radians; counter-clockwise seen from the positive end
 * of the axis) about the x (axis 0), y (1) or z (2) axis. */
static mat rotation(int axis, double a)
{
    mat r = identity();
    double c = cos(a), s = sin(a);
    int i = (axis + 1) % 3, j = (axis + 2) % 3;
    r.m[i][i] = c, r.m[j][j] = c;
    r.m[i][j] = s, r.m[j][i] = -s;
    return r;
}

/* Rotation by angle a about the unit axis u (Rodrigues' formula). */
static mat axis_rotation(vec u, double a)
{
    mat r = identity();
    double c = cos(a), s = sin(a), t = 1.0 - c;
    r.m[0][0] = u.x * u.x + (1.0 - u.x * u.x) * c;
    r.m[0][1] = u.x * u.y * t + u.z * s;
    r.m[0][2] = u.x * u.z * t - u.y * s;
    r.m[1][0] = u.x * u.y * t - u.z * s;
    r.m[1][1] = u.y * u.y + (1.0 - u.y * u.y) * c;
    r.m[1][2] = u.y * u.z * t + u.x * s;
    r.m[2][0] = u.x * u.z * t + u.y * s;
    r.m[2][1] = u.y * u.z * t - u.x * s;
    r.m[2][2] = u.z * u.z + (1.0 - u.z * u.z) * c;
    return r;
}

static mat mat_mul(mat a, mat b)
{
    mat r;
    int i, j;
    for (i = 0; i < 4; i++)
        for (j = 0; j < 4; j++)
            r.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] +
                        a.m[i][2] * b.m[2][j] + a.m[i][3] * b.m[3][j];
    return r;
}

/* (p, w) * M, the first three components: w = 1 moves a point, w = 0 turns
 * a direction and adds the "+ 0" of the header. */
static vec xform(vec p, double w, mat m)
{
    return v3(p.x * m.m[0][0] + p.y * m.m[1][0] + p.z * m.m[2][0] + w * m.m[3][0],
              p.x * m.m[0][1] + p.y * m.m[1][1] + p.z * m.m[2][1] + w * m.m[3][1],
              p.x * m.m[0][2] + p.y * m.m[1][2] + p.z * m.m[2][2] + w * m.m[3][2]);
}

/* The 3x3 part only: p * M for a direction, without the fourth term. */
static vec turn(vec p, mat m)
{
    return v3(p.x * m.m[0][0] + p.y * m.m[1][0] + p.z * m.m[2][0],
              p.x * m.m[0][1] + p.y * m.m[1][1] + p.z * m.m[2][1],
              p.x * m.m[0][2] + p.y * m.m[1][2] + p.z * m.m[2][2]);
}

/* ---- NFF output ---------------------------------------------------------- */

static void background(void) { printf("b 0.078 0.361 0.753\n"); }  /* UNC sky blue */

static void view(vec from, vec at, vec up, double hither)
{
    printf("v\nfrom %g %g %g\nat %g %g %g\nup %g %g %g\n", from.x, from.y, from.z,
           at.x, at.y, at.z, up.x, up.y, up.z);
    printf("angle 45\nhither %g\nresolution 512 512\n", hither);
}

static void light(double x, double y, double z) { printf("l %g %g %g\n", x, y, z); }

/* A material.  The SPD gives the highlight as the angle at which it falls to
 * half; NFF wants the Phong exponent n with cos(angle)^n = 1/2 (100000: no
 * highlight). */
static void material(double r, double g, double b, double kd, double ks,
                     double half_angle, double kt, double ior)
{
    double a = PI * half_angle / 180.0, shine;
    if (a <= 0.0) shine = 100000.0;
    else if (a >= PI / 2.0) shine = 1.0;
    else shine = log(0.5) / log(cos(a));
    printf("f %g %g %g %g %g %g %g %g\n", r, g, b, kd, ks, shine, kt, ior);
}

static void sphere(vec c, double r) { printf("s %g %g %g %g\n", c.x, c.y, c.z, r); }

static void cone(vec base, double rb, vec apex, double ra)
{
    printf("c %g %g %g %g %g %g %g %g\n", base.x, base.y, base.z, rb, apex.x, apex.y, apex.z, ra);
}

static void polygon(int n, const vec *p)
{
    int i;
    printf("p %d\n", n);
    for (i = 0; i < n; i++) printf("%g %g %g\n", p[i].x, p[i].y, p[i].z);
}

static void patch(const vec *p, const vec *n)
{
    int i;
    printf("pp 3\n");
    for (i = 0; i < 3; i++)
        printf("%g %g %g %g %g %g\n", p[i].x, p[i].y, p[i].z, n[i].x, n[i].y, n[i].z);
}

/* ---- balls: the sphereflake ---------------------------------------------- */

/* The nine directions of a sphere's children when it grew along +z: three
 * unit vectors tilted by asin(2/sqrt 6) about (1,-1,0), and their copies at
 * 120 and 240 degrees about z. */
static vec flake_dirs[9];

static void flake_setup(void)
{
    double d = 1.0 / sqrt(2.0);
    vec trio[3];
    mat tilt = axis_rotation(unit(v3(1.0, -1.0, 0.0)), asin(2.0 / sqrt(6.0)));
    int i, k;

    trio[0] = v3(d, d, 0.0), trio[1] = v3(d, 0.0, -d), trio[2] = v3(0.0, d, -d);
    for (i = 0; i < 3; i++) trio[i] = xform(trio[i], 0.0, tilt);
    for (k = 0; k < 3; k++) {
        mat spin = rotation(2, k * 2.0 * PI / 3.0);
        for (i = 0; i < 3; i++) flake_dirs[k * 3 + i] = xform(trio[i], 0.0, spin);
    }
}

/* The sphere at c of radius r, grown in the unit direction dir, and its
 * children to the given depth.  A child's radius is r/3, its centre 4r/3 from
 * c along the child's direction turned from +z to dir. */
static void flake(int depth, vec c, double r, vec dir)
{
    const double ratio = 1.0 / 3.0;
    vec z = v3(0.0, 0.0, 1.0);
    double scale = r * (1.0 + ratio);
    mat m;
    int i;

    sphere(c, r);
    if (depth <= 0) return;
    /* dir may miss +-z by rounding: such a dir is taken as the axis itself
     * (SPD 3.14 after its April 2021 fix to balls.c) */
    if (dir.z >= 0.9999) m = identity();
    else if (dir.z <= -0.9999) m = rotation(1, PI);
    else m = axis_rotation(unit(cross(z, dir)), acos(dot(z, dir)));
    for (i = 0; i < 9; i++) {
        vec p = xform(flake_dirs[i], 0.0, m);
        p = v3(p.x * scale + c.x, p.y * scale + c.y, p.z * scale + c.z);
        vec d = sub(p, c);
        flake(depth - 1, p, r * ratio, v3(d.x / scale, d.y / scale, d.z / scale));
    }
}

static void balls(int size)
{
    vec floor[4];

    background();
    view(v3(2.1, 1.3, 1.7), v3(0, 0, 0), v3(0, 0, 1), 0.01);
    light(4, 3, 2), light(1, -4, 4), light(-3, 1, 5);
    material(1.0, 0.75, 0.33, 0.8, 0.0, 0.0, 0.0, 1.0);     /* beige floor */
    floor[0] = v3(12, 12, -0.5), floor[1] = v3(-12, 12, -0.5);
    floor[2] = v3(-12, -12, -0.5), floor[3] = v3(12, -12, -0.5);
    polygon(4, floor);
    material(1.0, 0.9, 0.7, 0.5, 0.5, 37.0, 0.0, 1.0);      /* mirrored balls */
    flake_setup();
    flake(size, v3(0, 0, 0), 0.5, v3(0, 0, 1));
}

/* ---- gears ------------------------------------------------------------- */

#define TEETH 36

/* The four corners of one tooth on the rim of a gear centred at c: two on
 * the outer radius, two on the inner, at fractions of the tooth's angle. */
static void tooth(double angle, double tooth_angle, vec c, vec outer, vec inner, vec *p)
{
    p[0] = add(turn(outer, rotation(2, angle - 0.19 * tooth_angle)), c);
    p[1] = add(turn(outer, rotation(2, angle + 0.19 * tooth_angle)), c);
    p[2] = add(turn(inner, rotation(2, angle + 0.3 * tooth_angle)), c);
    p[3] = add(turn(inner, rotation(2, angle + 0.7 * tooth_angle)), c);
}

/* A gear: its top face (a concave polygon of 4*TEETH corners), the side
 * rectangles below its edge, and its bottom face, wound the other way. */
static void gear(vec c, double offset, double outer_r, double inner_r, double thick)
{
    vec rim[4 * TEETH], side[4];
    vec outer = v3(outer_r, 0.0, 0.0), inner = v3(inner_r, 0.0, 0.0);
    double tooth_angle = 2.0 * PI / (double)TEETH;
    int i;

    for (i = 0; i < TEETH; i++)
        tooth(offset + 2.0 * PI * (double)i / (double)TEETH, tooth_angle, c, outer, inner,
              rim + 4 * i);
    polygon(4 * TEETH, rim);
    for (i = 0; i < 4 * TEETH; i++) {
        vec a = rim[i], b = rim[(i + 1) % (4 * TEETH)];
        side[0] = a, side[1] = a, side[2] = b, side[3] = b;
        side[1].z -= thick, side[2].z -= thick;
        polygon(4, side);
    }
    outer.z = inner.z = -thick;
    for (i = 0; i < TEETH; i++)
        tooth(offset - 2.0 * PI * (double)i / (double)TEETH, -tooth_angle, c, outer, inner,
              rim + 4 * i);
    polygon(4 * TEETH, rim);
}

/* The fractional part, as the SPD takes it: x - (int)x. */
static double frac(double x) { return x - (int)x; }

static void gears(int size)
{
    const double edge = 1.0 - 0.9;          /* the teeth: the outer tenth */
    double n = size, r = 1.0 / (n - (double)(size - 1) * edge / 2.0);
    double first = -1.0 + r, step = r * (2.0 - edge), thick;
    vec floor[4];
    int ix, iy, iz;

    background();
    view(v3(-1.1, -2.1, 2.6), v3(0, 0, 0), v3(0, 0, 1), 1.0);
    light(2, 4, 4), light(-2, 4, 3), light(2, -2.5, 2.5), light(-1, -4, 2);
    light(-1.111, -2.121, 2.626);                           /* behind the eye */
    material(1.0, 0.85, 0.7, 0.3, 0.6, 37.0, 0.0, 0.0);
    floor[0] = v3(2, 2, 0), floor[1] = v3(-2, 2, 0);
    floor[2] = v3(-2, -2, 0), floor[3] = v3(2, -2, 0);
    polygon(4, floor);

    thick = 1.0 / (2.0 * n) < 0.1 ? 1.0 / (2.0 * n) : 0.1;
    for (iz = 0; iz < size; iz++)
        for (iy = 0; iy < size; iy++)
            for (ix = 0; ix < size; ix++) {
                vec c = v3(first + (double)ix * step, first + (double)iy * step,
                           1.0 + (double)iz * (-1.0 / n));
                /* a colour that looks random, made brightest-channel 1 */
                double red = 0.01 + frac((double)(ix * 3 + iy * 2 + iz + 1) * 5.0 / 7.0);
                double grn = 0.01 + frac((double)(iy * 3 + iz * 2 + ix + 1) * 3.0 / 7.0);
                double blu = 0.01 + frac((double)(iz * 3 + ix * 2 + iy + 1) * 2.0 / 7.0);
                double top = red > grn ? red : grn;
                top = top > blu ? top : blu;
                if ((ix * 4 + iy * 2 + iz) % 5 == 0)            /* glass */
                    material(red / top, grn / top, blu / top, 0.2, 0.0, 0.0, 0.8, 1.1);
                else
                    material(red / top, grn / top, blu / top, 1.0, 0.0, 0.0, 0.0, 0.0);
                /* neighbours turn half a tooth apart, so that they mesh */
                gear(c, PI * (double)((ix + iy + iz) % 2) / (double)TEETH, 0.995 * r,
                     (1.0 - edge) * r, thick);
            }
}

/* ---- mount: fractal mountain and crystal spheres ----------------------- */

/* Our random numbers (not the SPD's, which come from Numerical Recipes'
 * generator seeded by a hash of the grid point): a Gaussian for each point of
 * a 2^16 x 2^16 grid, from the SplitMix64 mixing function (G. Steele, D. Lea,
 * C. Flood, "Fast Splittable Pseudorandom Number Generators", OOPSLA 2014;
 * its multipliers are D. Stafford's "Mix13") applied to the point's
 * coordinates and a seed, made Gaussian by the Box-Muller transform (G. Box,
 * M. Muller, Ann. Math. Stat. 29, 1958).
 * Being a function of the point, not a stream, it gives the shared edge of two
 * squares the same height from either side, and mount at SIZE+1 is mount at
 * SIZE with one more level of detail. */
#define MOUNT_SEED 263    /* picked for SPD-like heights, see the header */
#define MOUNT_GRID 16     /* log2 of the grid the points are numbered on */

static uint64_t mix64(uint64_t z)
{
    z += UINT64_C(0x9e3779b97f4a7c15);
    z = (z ^ (z >> 30)) * UINT64_C(0xbf58476d1ce4e5b9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94d049bb133111eb);
    return z ^ (z >> 31);
}

/* A uniform number in (0, 1) from the top 53 bits of h. */
static double uniform(uint64_t h) { return ((double)(h >> 11) + 0.5) / 9007199254740992.0; }

static double gauss_at(long x, long y)
{
    uint64_t h = mix64(mix64(MOUNT_SEED) ^ ((uint64_t)x << 32 | (uint64_t)y));
    double u = uniform(h), v = uniform(mix64(h));
    return sqrt(-2.0 * log(u)) * cos(2.0 * PI * v);
}

static struct {
    int size;           /* the grid has 2^size squares a side */
    double roughness;   /* a displacement's deviation / half the side */
} mnt;

/* The random height of grid point (x, y) of the 2^size grid, scaled by s. */
static double bump(int x, int y, double s)
{
    int shift = MOUNT_GRID - mnt.size;
    return s * gauss_at((long)x << shift, (long)y << shift);
}

/* The square of the given width (in grid steps) with lower-left corner (x, y)
 * and corner heights ll, lr, ur, ul: cut into four with displaced midpoints
 * (Carpenter's subdivision), or, one step wide, written as two triangles. */
static void mountain(int width, int x, int y, double ll, double lr, double ur, double ul)
{
    double n = (double)(1 << mnt.size);
    if (width == 1) {
        double x0 = -1.0 + (double)x * 2.0 / n, x1 = -1.0 + (double)(x + 1) * 2.0 / n;
        double y0 = -1.0 + (double)y * 2.0 / n, y1 = -1.0 + (double)(y + 1) * 2.0 / n;
        vec t[3];
        t[0] = v3(x0, y0, ll), t[1] = v3(x1, y0, lr), t[2] = v3(x1, y1, ur);
        polygon(3, t);
        t[0] = v3(x1, y1, ur), t[1] = v3(x0, y1, ul), t[2] = v3(x0, y0, ll);
        polygon(3, t);
    } else {
        int h = width / 2;
        double rise = (double)h * 2.0 / n * mnt.roughness;
        double lower = (ll + lr) / 2.0 + bump(x + h, y, rise);
        double right = (lr + ur) / 2.0 + bump(x + width, y + h, rise);
        double upper = (ur + ul) / 2.0 + bump(x + h, y + width, rise);
        double left = (ul + ll) / 2.0 + bump(x, y + h, rise);
        double mid = (ll + lr + ur + ul) / 4.0 + bump(x + h, y + h, sqrt(2.0) * rise);
        mountain(h, x, y, ll, lower, mid, left);
        mountain(h, x + h, y, lower, lr, right, mid);
        mountain(h, x + h, y + h, mid, right, ur, upper);
        mountain(h, x, y + h, left, mid, upper, ul);
    }
}

/* Four spheres of radius r stacked as a tetrahedron: one on top of c, three
 * below it, 120 degrees apart. */
static void crystal(vec c, double r)
{
    vec top = v3(0.0, 0.0, r * sqrt(3.0 / 2.0)), low;
    int i;

    sphere(add(c, top), r);
    low = turn(top, axis_rotation(unit(v3(1.0, 1.0, 0.0)), acos(-1.0 / 3.0)));
    for (i = 0; i < 3; i++) sphere(add(turn(low, rotation(2, (double)i * 2.0 * PI / 3.0)), c), r);
}

static void mount(int size)
{
    /* Carpenter's ratio between levels for fractal dimension D = 2.2 */
    double ratio = 2.0 / exp(log(2.0) / (2.2 - 1.0));

    background();
    view(v3(-1.6, 1.6, 1.7), v3(0, 0, 0), v3(0, 0, 1), 0.01);
    light(-100, -100, 100);
    material(1.0, 1.0, 1.0, 0.1, 0.1, 6.7, 0.9, 1.5);      /* clear glass */
    crystal(v3(-0.8, 0.8, 1.0), 0.17);
    material(0.5, 0.45, 0.35, 1.0, 0.0, 0.0, 0.0, 0.0);    /* grey rock */
    mnt.size = size;
    mnt.roughness = sqrt(ratio * ratio - 1.0);
    mountain(1 << size, 0, 0, 0.0, 0.0, 0.0, 0.0);
}

/* ---- rings --------------------------------------------------------------- */

/* The 30 midpoints of a dodecahedron's edges, scaled so that rings of tubes
 * of radius tube through them fit in the unit sphere: one pentagon in the xy
 * plane, and five copies of it tipped over by the dihedral angle and turned
 * about z.  Each five in a row are one ring. */
static void dodecahedron(double tube, vec *p)
{
    double scale = 1.0 / (1.0 + tube);
    mat tip = rotation(0, 2.0 * acos(cos(PI / 3.0) / sin(PI / 5.0)));
    int i, k;

    for (i = 0; i < 5; i++)
        p[i] = v3(scale * cos((double)i * 2.0 * PI / 5.0), scale * sin((double)i * 2.0 * PI / 5.0),
                  0.0);
    for (k = 1; k < 6; k++) {
        mat spin = rotation(2, PI * (2.0 * (double)(k - 1) + 1.0) / 5.0);
        for (i = 0; i < 5; i++) p[5 * k + i] = xform(xform(p[i], 1.0, tip), 1.0, spin);
    }
}

static void rings(int size)
{
    static const double colour[6][3] = {
        {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 1, 1}, {1, 0, 1}, {1, 1, 0}};
    const double tube = 0.07412;
    double spread = 1 / sin(PI / 8.0);  /* successive layers a view's width apart */
    double wx, wy;
    vec eye = v3(-1.0, -spread, 0.5), wall[4], ring[30];
    int layer, ix, iz, i;

    background();
    view(eye, v3(eye.x, eye.y + 1.0, eye.z), v3(0, 0, 1), 1.0);
    light(3.0, -spread, 3.0), light(-4.0, -spread, 1.0), light(2.0, -spread, -4.0);
    material(1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0);      /* white wall */
    wy = spread * (size + 1);
    wx = 1.01 * (wy - eye.y) * tan(PI / 8.0);  /* just spans the 45 degrees, +1% */
    wall[0] = v3(wx + eye.x, wy, wx + eye.z), wall[1] = v3(-wx + eye.x, wy, wx + eye.z);
    wall[2] = v3(-wx + eye.x, wy, -wx + eye.z), wall[3] = v3(wx + eye.x, wy, -wx + eye.z);
    polygon(4, wall);

    dodecahedron(tube, ring);
    for (layer = 0; layer < size; layer++)
        for (iz = 0; iz <= layer; iz++)
            for (ix = 0; ix <= layer; ix++) {
                vec off = v3((double)(2 * ix - layer), spread * (double)(layer + 1),
                             (double)(2 * iz - layer));
                for (i = 0; i < 30; i++) {
                    int prev = i % 5 == 0 ? i + 4 : i - 1;
                    if (i % 5 == 0) {
                        const double *c = colour[i / 5];
                        material(c[0], c[1], c[2], 0.5, 0.2, 37.0, 0.0, 0.0);
                    }
                    cone(add(ring[i], off), tube, add(ring[prev], off), tube);
                    sphere(add(ring[i], off), tube);
                }
            }
}

/* ---- teapot ---------------------------------------------------------------- */

/* Martin Newell's teapot (1975) with the bottom Frank Crow added: 32 bicubic
 * Bezier patches over 306 control points.  The data is public domain and
 * widely reproduced; these numbers are the standard set from Steve Baker's
 * "teaset" archive (sjbaker.org/teapot/teaset.tgz, file "teapot"), as listed
 * with zero-based indices in Mark Kilgard's OpenGL 4 examples
 * (github.com/markkilgard/opengl4_examples, tessellation/teapot.cpp); see
 * also F. Crow, "The Origins of the Teapot", IEEE CG&A 7(1), January 1987.
 * Patches 0-3 rim, 4-11 body, 12-15 handle, 16-19 spout, 20-27 lid,
 * 28-31 bottom.  The set has unused points (204, 205, 215, 222) and
 * duplicates (92 and 270, ...); the SPD's teapot.c numbers the points
 * differently, but every patch has the same 16 control points. */
static const short teapot_patches[32][16] = {
    {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15},
    {3, 16, 17, 18, 7, 19, 20, 21, 11, 22, 23, 24, 15, 25, 26, 27},
    {18, 28, 29, 30, 21, 31, 32, 33, 24, 34, 35, 36, 27, 37, 38, 39},
    {30, 40, 41, 0, 33, 42, 43, 4, 36, 44, 45, 8, 39, 46, 47, 12},
    {12, 13, 14, 15, 48, 49, 50, 51, 52, 53, 54, 55, 56, 57, 58, 59},
    {15, 25, 26, 27, 51, 60, 61, 62, 55, 63, 64, 65, 59, 66, 67, 68},
    {27, 37, 38, 39, 62, 69, 70, 71, 65, 72, 73, 74, 68, 75, 76, 77},
    {39, 46, 47, 12, 71, 78, 79, 48, 74, 80, 81, 52, 77, 82, 83, 56},
    {56, 57, 58, 59, 84, 85, 86, 87, 88, 89, 90, 91, 92, 93, 94, 95},
    {59, 66, 67, 68, 87, 96, 97, 98, 91, 99, 100, 101, 95, 102, 103, 104},
    {68, 75, 76, 77, 98, 105, 106, 107, 101, 108, 109, 110, 104, 111, 112, 113},
    {77, 82, 83, 56, 107, 114, 115, 84, 110, 116, 117, 88, 113, 118, 119, 92},
    {120, 121, 122, 123, 124, 125, 126, 127, 128, 129, 130, 131, 132, 133, 134, 135},
    {123, 136, 137, 120, 127, 138, 139, 124, 131, 140, 141, 128, 135, 142, 143, 132},
    {132, 133, 134, 135, 144, 145, 146, 147, 148, 149, 150, 151, 68, 152, 153, 154},
    {135, 142, 143, 132, 147, 155, 156, 144, 151, 157, 158, 148, 154, 159, 160, 68},
    {161, 162, 163, 164, 165, 166, 167, 168, 169, 170, 171, 172, 173, 174, 175, 176},
    {164, 177, 178, 161, 168, 179, 180, 165, 172, 181, 182, 169, 176, 183, 184, 173},
    {173, 174, 175, 176, 185, 186, 187, 188, 189, 190, 191, 192, 193, 194, 195, 196},
    {176, 183, 184, 173, 188, 197, 198, 185, 192, 199, 200, 189, 196, 201, 202, 193},
    {203, 203, 203, 203, 206, 207, 208, 209, 210, 210, 210, 210, 211, 212, 213, 214},
    {203, 203, 203, 203, 209, 216, 217, 218, 210, 210, 210, 210, 214, 219, 220, 221},
    {203, 203, 203, 203, 218, 223, 224, 225, 210, 210, 210, 210, 221, 226, 227, 228},
    {203, 203, 203, 203, 225, 229, 230, 206, 210, 210, 210, 210, 228, 231, 232, 211},
    {211, 212, 213, 214, 233, 234, 235, 236, 237, 238, 239, 240, 241, 242, 243, 244},
    {214, 219, 220, 221, 236, 245, 246, 247, 240, 248, 249, 250, 244, 251, 252, 253},
    {221, 226, 227, 228, 247, 254, 255, 256, 250, 257, 258, 259, 253, 260, 261, 262},
    {228, 231, 232, 211, 256, 263, 264, 233, 259, 265, 266, 237, 262, 267, 268, 241},
    {269, 269, 269, 269, 278, 279, 280, 281, 274, 275, 276, 277, 270, 271, 272, 273},
    {269, 269, 269, 269, 281, 288, 289, 290, 277, 285, 286, 287, 273, 282, 283, 284},
    {269, 269, 269, 269, 290, 297, 298, 299, 287, 294, 295, 296, 284, 291, 292, 293},
    {269, 269, 269, 269, 299, 304, 305, 278, 296, 302, 303, 274, 293, 300, 301, 270},
};
static const double teapot_points[306][3] = {
    {1.4, 0, 2.4}, {1.4, -0.784, 2.4}, {0.784, -1.4, 2.4}, {0, -1.4, 2.4}, {1.3375, 0, 2.53125},
    {1.3375, -0.749, 2.53125}, {0.749, -1.3375, 2.53125}, {0, -1.3375, 2.53125},
    {1.4375, 0, 2.53125}, {1.4375, -0.805, 2.53125}, {0.805, -1.4375, 2.53125},
    {0, -1.4375, 2.53125}, {1.5, 0, 2.4}, {1.5, -0.84, 2.4}, {0.84, -1.5, 2.4}, {0, -1.5, 2.4},
    {-0.784, -1.4, 2.4}, {-1.4, -0.784, 2.4}, {-1.4, 0, 2.4}, {-0.749, -1.3375, 2.53125},
    {-1.3375, -0.749, 2.53125}, {-1.3375, 0, 2.53125}, {-0.805, -1.4375, 2.53125},
    {-1.4375, -0.805, 2.53125}, {-1.4375, 0, 2.53125}, {-0.84, -1.5, 2.4}, {-1.5, -0.84, 2.4},
    {-1.5, 0, 2.4}, {-1.4, 0.784, 2.4}, {-0.784, 1.4, 2.4}, {0, 1.4, 2.4},
    {-1.3375, 0.749, 2.53125}, {-0.749, 1.3375, 2.53125}, {0, 1.3375, 2.53125},
    {-1.4375, 0.805, 2.53125}, {-0.805, 1.4375, 2.53125}, {0, 1.4375, 2.53125}, {-1.5, 0.84, 2.4},
    {-0.84, 1.5, 2.4}, {0, 1.5, 2.4}, {0.784, 1.4, 2.4}, {1.4, 0.784, 2.4},
    {0.749, 1.3375, 2.53125}, {1.3375, 0.749, 2.53125}, {0.805, 1.4375, 2.53125},
    {1.4375, 0.805, 2.53125}, {0.84, 1.5, 2.4}, {1.5, 0.84, 2.4}, {1.75, 0, 1.875},
    {1.75, -0.98, 1.875}, {0.98, -1.75, 1.875}, {0, -1.75, 1.875}, {2, 0, 1.35}, {2, -1.12, 1.35},
    {1.12, -2, 1.35}, {0, -2, 1.35}, {2, 0, 0.9}, {2, -1.12, 0.9}, {1.12, -2, 0.9}, {0, -2, 0.9},
    {-0.98, -1.75, 1.875}, {-1.75, -0.98, 1.875}, {-1.75, 0, 1.875}, {-1.12, -2, 1.35},
    {-2, -1.12, 1.35}, {-2, 0, 1.35}, {-1.12, -2, 0.9}, {-2, -1.12, 0.9}, {-2, 0, 0.9},
    {-1.75, 0.98, 1.875}, {-0.98, 1.75, 1.875}, {0, 1.75, 1.875}, {-2, 1.12, 1.35},
    {-1.12, 2, 1.35}, {0, 2, 1.35}, {-2, 1.12, 0.9}, {-1.12, 2, 0.9}, {0, 2, 0.9},
    {0.98, 1.75, 1.875}, {1.75, 0.98, 1.875}, {1.12, 2, 1.35}, {2, 1.12, 1.35}, {1.12, 2, 0.9},
    {2, 1.12, 0.9}, {2, 0, 0.45}, {2, -1.12, 0.45}, {1.12, -2, 0.45}, {0, -2, 0.45},
    {1.5, 0, 0.225}, {1.5, -0.84, 0.225}, {0.84, -1.5, 0.225}, {0, -1.5, 0.225}, {1.5, 0, 0.15},
    {1.5, -0.84, 0.15}, {0.84, -1.5, 0.15}, {0, -1.5, 0.15}, {-1.12, -2, 0.45}, {-2, -1.12, 0.45},
    {-2, 0, 0.45}, {-0.84, -1.5, 0.225}, {-1.5, -0.84, 0.225}, {-1.5, 0, 0.225},
    {-0.84, -1.5, 0.15}, {-1.5, -0.84, 0.15}, {-1.5, 0, 0.15}, {-2, 1.12, 0.45}, {-1.12, 2, 0.45},
    {0, 2, 0.45}, {-1.5, 0.84, 0.225}, {-0.84, 1.5, 0.225}, {0, 1.5, 0.225}, {-1.5, 0.84, 0.15},
    {-0.84, 1.5, 0.15}, {0, 1.5, 0.15}, {1.12, 2, 0.45}, {2, 1.12, 0.45}, {0.84, 1.5, 0.225},
    {1.5, 0.84, 0.225}, {0.84, 1.5, 0.15}, {1.5, 0.84, 0.15}, {-1.6, 0, 2.025}, {-1.6, -0.3, 2.025},
    {-1.5, -0.3, 2.25}, {-1.5, 0, 2.25}, {-2.3, 0, 2.025}, {-2.3, -0.3, 2.025}, {-2.5, -0.3, 2.25},
    {-2.5, 0, 2.25}, {-2.7, 0, 2.025}, {-2.7, -0.3, 2.025}, {-3, -0.3, 2.25}, {-3, 0, 2.25},
    {-2.7, 0, 1.8}, {-2.7, -0.3, 1.8}, {-3, -0.3, 1.8}, {-3, 0, 1.8}, {-1.5, 0.3, 2.25},
    {-1.6, 0.3, 2.025}, {-2.5, 0.3, 2.25}, {-2.3, 0.3, 2.025}, {-3, 0.3, 2.25}, {-2.7, 0.3, 2.025},
    {-3, 0.3, 1.8}, {-2.7, 0.3, 1.8}, {-2.7, 0, 1.575}, {-2.7, -0.3, 1.575}, {-3, -0.3, 1.35},
    {-3, 0, 1.35}, {-2.5, 0, 1.125}, {-2.5, -0.3, 1.125}, {-2.65, -0.3, 0.9375}, {-2.65, 0, 0.9375},
    {-2, -0.3, 0.9}, {-1.9, -0.3, 0.6}, {-1.9, 0, 0.6}, {-3, 0.3, 1.35}, {-2.7, 0.3, 1.575},
    {-2.65, 0.3, 0.9375}, {-2.5, 0.3, 1.125}, {-1.9, 0.3, 0.6}, {-2, 0.3, 0.9}, {1.7, 0, 1.425},
    {1.7, -0.66, 1.425}, {1.7, -0.66, 0.6}, {1.7, 0, 0.6}, {2.6, 0, 1.425}, {2.6, -0.66, 1.425},
    {3.1, -0.66, 0.825}, {3.1, 0, 0.825}, {2.3, 0, 2.1}, {2.3, -0.25, 2.1}, {2.4, -0.25, 2.025},
    {2.4, 0, 2.025}, {2.7, 0, 2.4}, {2.7, -0.25, 2.4}, {3.3, -0.25, 2.4}, {3.3, 0, 2.4},
    {1.7, 0.66, 0.6}, {1.7, 0.66, 1.425}, {3.1, 0.66, 0.825}, {2.6, 0.66, 1.425},
    {2.4, 0.25, 2.025}, {2.3, 0.25, 2.1}, {3.3, 0.25, 2.4}, {2.7, 0.25, 2.4}, {2.8, 0, 2.475},
    {2.8, -0.25, 2.475}, {3.525, -0.25, 2.49375}, {3.525, 0, 2.49375}, {2.9, 0, 2.475},
    {2.9, -0.15, 2.475}, {3.45, -0.15, 2.5125}, {3.45, 0, 2.5125}, {2.8, 0, 2.4}, {2.8, -0.15, 2.4},
    {3.2, -0.15, 2.4}, {3.2, 0, 2.4}, {3.525, 0.25, 2.49375}, {2.8, 0.25, 2.475},
    {3.45, 0.15, 2.5125}, {2.9, 0.15, 2.475}, {3.2, 0.15, 2.4}, {2.8, 0.15, 2.4}, {0, 0, 3.15},
    {0, -0.002, 3.15}, {0.002, 0, 3.15}, {0.8, 0, 3.15}, {0.8, -0.45, 3.15}, {0.45, -0.8, 3.15},
    {0, -0.8, 3.15}, {0, 0, 2.85}, {0.2, 0, 2.7}, {0.2, -0.112, 2.7}, {0.112, -0.2, 2.7},
    {0, -0.2, 2.7}, {-0.002, 0, 3.15}, {-0.45, -0.8, 3.15}, {-0.8, -0.45, 3.15}, {-0.8, 0, 3.15},
    {-0.112, -0.2, 2.7}, {-0.2, -0.112, 2.7}, {-0.2, 0, 2.7}, {0, 0.002, 3.15}, {-0.8, 0.45, 3.15},
    {-0.45, 0.8, 3.15}, {0, 0.8, 3.15}, {-0.2, 0.112, 2.7}, {-0.112, 0.2, 2.7}, {0, 0.2, 2.7},
    {0.45, 0.8, 3.15}, {0.8, 0.45, 3.15}, {0.112, 0.2, 2.7}, {0.2, 0.112, 2.7}, {0.4, 0, 2.55},
    {0.4, -0.224, 2.55}, {0.224, -0.4, 2.55}, {0, -0.4, 2.55}, {1.3, 0, 2.55}, {1.3, -0.728, 2.55},
    {0.728, -1.3, 2.55}, {0, -1.3, 2.55}, {1.3, 0, 2.4}, {1.3, -0.728, 2.4}, {0.728, -1.3, 2.4},
    {0, -1.3, 2.4}, {-0.224, -0.4, 2.55}, {-0.4, -0.224, 2.55}, {-0.4, 0, 2.55},
    {-0.728, -1.3, 2.55}, {-1.3, -0.728, 2.55}, {-1.3, 0, 2.55}, {-0.728, -1.3, 2.4},
    {-1.3, -0.728, 2.4}, {-1.3, 0, 2.4}, {-0.4, 0.224, 2.55}, {-0.224, 0.4, 2.55}, {0, 0.4, 2.55},
    {-1.3, 0.728, 2.55}, {-0.728, 1.3, 2.55}, {0, 1.3, 2.55}, {-1.3, 0.728, 2.4},
    {-0.728, 1.3, 2.4}, {0, 1.3, 2.4}, {0.224, 0.4, 2.55}, {0.4, 0.224, 2.55}, {0.728, 1.3, 2.55},
    {1.3, 0.728, 2.55}, {0.728, 1.3, 2.4}, {1.3, 0.728, 2.4}, {0, 0, 0}, {1.5, 0, 0.15},
    {1.5, 0.84, 0.15}, {0.84, 1.5, 0.15}, {0, 1.5, 0.15}, {1.5, 0, 0.075}, {1.5, 0.84, 0.075},
    {0.84, 1.5, 0.075}, {0, 1.5, 0.075}, {1.425, 0, 0}, {1.425, 0.798, 0}, {0.798, 1.425, 0},
    {0, 1.425, 0}, {-0.84, 1.5, 0.15}, {-1.5, 0.84, 0.15}, {-1.5, 0, 0.15}, {-0.84, 1.5, 0.075},
    {-1.5, 0.84, 0.075}, {-1.5, 0, 0.075}, {-0.798, 1.425, 0}, {-1.425, 0.798, 0}, {-1.425, 0, 0},
    {-1.5, -0.84, 0.15}, {-0.84, -1.5, 0.15}, {0, -1.5, 0.15}, {-1.5, -0.84, 0.075},
    {-0.84, -1.5, 0.075}, {0, -1.5, 0.075}, {-1.425, -0.798, 0}, {-0.798, -1.425, 0},
    {0, -1.425, 0}, {0.84, -1.5, 0.15}, {1.5, -0.84, 0.15}, {0.84, -1.5, 0.075},
    {1.5, -0.84, 0.075}, {0.798, -1.425, 0}, {1.425, -0.798, 0},
};

/* The Bezier basis in power form: a cubic's coefficients (t^3 t^2 t 1) are
 * BASIS times its four control values. */
static const mat BASIS = {{{-1, 3, -3, 1}, {3, -6, 3, 0}, {-3, 3, 0, 0}, {1, 0, 0, 0}}};

static double dot4(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
}

/* pw = (u^3, u^2, u, 1) and its derivative dpw = (3u^2, 2u, 1, 0). */
static void powers(double u, double *pw, double *dpw)
{
    pw[3] = 1.0, pw[2] = u, pw[1] = u * u, pw[0] = u * u * u;
    dpw[3] = 0.0, dpw[2] = 1.0, dpw[1] = u * 2.0, dpw[0] = u * u * 3.0;
}

/* row * M, all four components. */
static void row_times(const double *row, const mat *m, double *out)
{
    int j;
    for (j = 0; j < 4; j++)
        out[j] = row[0] * m->m[0][j] + row[1] * m->m[1][j] + row[2] * m->m[2][j] +
                 row[3] * m->m[3][j];
}

/* The point at (s, t) of the patch whose coordinate matrices (BASIS * G *
 * BASIS^T, one for x, y, z) are coef, and the unit normal there: the cross
 * product of the t and s tangents. */
static void patch_point(const mat *coef, double s, double t, vec *p, vec *n)
{
    double sp[4], dsp[4], tp[4], dtp[4], a[4], b[4], v[3], ds[3], dt[3];
    int i;

    powers(s, sp, dsp);
    powers(t, tp, dtp);
    for (i = 0; i < 3; i++) {
        row_times(sp, &coef[i], a);
        row_times(dsp, &coef[i], b);
        v[i] = dot4(a, tp);
        ds[i] = dot4(b, tp);
        dt[i] = dot4(a, dtp);
    }
    *p = v3(v[0], v[1], v[2]);
    *n = unit(cross(v3(dt[0], dt[1], dt[2]), v3(ds[0], ds[1], ds[2])));
}

/* A triangle with a corner on the z axis (the lid's knob, the bottom's
 * centre) gets the axis as that corner's normal, where the patch's own is
 * undefined; one with two corners there is degenerate and is skipped. */
static int on_axis(const vec *p, vec *n)
{
    int i, count = 0, at = 0;
    for (i = 0; i < 3; i++)
        if (fabs(p[i].x) <= 0.0001 && fabs(p[i].y) <= 0.0001) count++, at = i;
    if (count > 1) return 0;
    if (count == 1) n[at] = v3(0.0, 0.0, p[at].z > 1.5 ? 1.0 : -1.0);
    return 1;
}

static void teapot_body(int size)
{
    mat basis_t;
    int k, i, j, r, c;

    for (i = 0; i < 4; i++)
        for (j = 0; j < 4; j++) basis_t.m[j][i] = BASIS.m[i][j];
    material(1.0, 0.5, 0.1, 0.75, 0.25, 37.0, 0.0, 0.0);
    for (k = 0; k < 32; k++) {
        mat coef[3];
        int si, ti, tri, v;
        for (i = 0; i < 3; i++) {
            mat g;
            for (r = 0; r < 4; r++)
                for (c = 0; c < 4; c++) g.m[r][c] = teapot_points[teapot_patches[k][r * 4 + c]][i];
            coef[i] = mat_mul(mat_mul(BASIS, g), basis_t);
        }
        /* each grid square as triangles (corner 0 1 2) and (2 3 0), corners
         * counted (s,t), (s,t+1), (s+1,t+1), (s+1,t) */
        for (si = 0; si < size; si++)
            for (ti = 0; ti < size; ti++)
                for (tri = 0; tri < 2; tri++) {
                    vec p[3], n[3];
                    for (v = 0; v < 3; v++) {
                        int corner = (v + tri * 2) % 4;
                        double s = (double)(si + (corner / 2 ? 1 : 0)) / (double)size;
                        double t = (double)(ti + (corner % 3 ? 1 : 0)) / (double)size;
                        patch_point(coef, s, t, &p[v], &n[v]);
                    }
                    if (on_axis(p, n)) patch(p, n);
                }
    }
}

/* The checkerboard under the teapot: size x size squares on [-4,4]^2, the
 * white ones first, then the grey. */
static void checkerboard(int size)
{
    int pass, si, ti, i;
    for (pass = 1; pass >= 0; pass--) {
        material(pass ? 1.0 : 0.5, pass ? 1.0 : 0.5, pass ? 1.0 : 0.5, 0.5, 0.5, 30.0, 0.0, 0.0);
        for (si = 0; si < size; si++)
            for (ti = 0; ti < size; ti++) {
                vec q[4];
                if ((si + ti) % 2 != pass) continue;
                for (i = 0; i < 4; i++)
                    q[i] = v3(4.0 * (2.0 * (double)(si + (i % 3 ? 1 : 0)) / (double)size - 1.0),
                              4.0 * (2.0 * (double)(ti + (i / 2 ? 1 : 0)) / (double)size - 1.0),
                              0.0);
                polygon(4, q);
            }
    }
}

static void teapot(int size)
{
    background();
    view(v3(4.86, 7.2, 5.4), v3(0, 0, 0), v3(0, 0, 1), 1.0);
    light(-3.1, 9.8, 12.1), light(11.3, 5.1, 8.8);
    checkerboard(size);
    teapot_body(size);
}

/* ---- tetra ----------------------------------------------------------------- */

/* The tetrahedron inscribed in the cube of half-side h at c (the corners
 * with x*y*z > 0), or, depth > 1, the four half-size ones in its corners. */
static void tetrahedron(int depth, vec c, double h)
{
    vec corner[4];
    int n = 0, x, y, z;

    for (x = -1; x <= 1; x += 2)
        for (y = -1; y <= 1; y += 2)
            for (z = -1; z <= 1; z += 2) {
                if (x * y * z != 1) continue;
                if (depth > 1)
                    tetrahedron(depth - 1, v3(c.x + (double)x * h / 2.0, c.y + (double)y * h / 2.0,
                                              c.z + (double)z * h / 2.0), h / 2.0);
                else
                    corner[n++] = v3(c.x + (double)x * h, c.y + (double)y * h, c.z + (double)z * h);
            }
    if (depth > 1) return;
    /* faces 0 1 2, 3 2 1, 2 3 0, 1 0 3: outward, counter-clockwise */
    for (n = 0; n < 4; n++) {
        vec f[3];
        int a = n % 4, b = (n + 1) % 4, d = (n + 2) % 4;
        if (n % 2) { int swap = a; a = d; d = swap; }
        f[0] = corner[a], f[1] = corner[b], f[2] = corner[d];
        polygon(3, f);
    }
}

static void tetra(int size)
{
    background();
    /* Kay and Kajiya's view and light, in these coordinates */
    view(v3(1.022846, -3.177154, -2.174512), v3(-0.004103, -0.004103, 0.216539),
         v3(-0.816497, -0.816497, 0.816497), 1.0);
    light(2, -18, -5);
    material(1.0, 0.2, 0.2, 1.0, 0.0, 0.0, 0.0, 0.0);
    tetrahedron(size, v3(0, 0, 0), 1.0);
}

/* ---- tree ------------------------------------------------------------------ */

/* Aono and Kunii's binary tree: a branch is the unit segment along z mapped
 * by its matrix; each child's matrix is a fixed "grow" matrix (shrink by the
 * contraction ratio, move up the parent's length, tip by the branching angle,
 * turn by the divergence angle) times the parent's. */
static mat twig[2];

static void branch(mat m, double scale, int depth)
{
    vec base = xform(v3(0, 0, 0), 1.0, m), apex = xform(v3(0, 0, 1), 1.0, m);
    double rb = scale * 0.15, ra = rb * 0.67;   /* width/height, diameter ratio */
    int i;

    cone(base, rb, apex, ra);
    sphere(apex, ra);
    if (depth > 0)
        for (i = 0; i < 2; i++) branch(mat_mul(twig[i], m), scale * 0.67, depth - 1);
}

static void tree(int size)
{
    /* branching angle, divergence angle, contraction ratio, for each child */
    static const double shape[2][3] = {{40.0, 90.0, 0.65}, {25.0, 140.0 + 90.0, 0.70}};
    vec field[4];
    int i;

    background();
    view(v3(4.5, 0.4, 2.0), v3(0, 0, 1.5), v3(0, 0, 1), 1.0);
    light(-5, 5, 50), light(30, -30, 30), light(-40, -30, 20), light(10, 30, 40);
    light(-30, 40, 10), light(50, 25, 20), light(-10, -60, 30);
    material(0.2, 0.7, 0.2, 1.0, 0.0, 0.0, 0.0, 0.0);      /* green field */
    field[0] = v3(50, 50, 0), field[1] = v3(-50, 50, 0);
    field[2] = v3(-50, -50, 0), field[3] = v3(50, -50, 0);
    polygon(4, field);
    material(0.55, 0.4, 0.2, 1.0, 0.0, 0.0, 0.0, 0.0);     /* brown wood */
    for (i = 0; i < 2; i++) {
        mat grow = identity();
        grow.m[0][0] = grow.m[1][1] = grow.m[2][2] = shape[i][2];
        grow.m[3][2] = 1.0;
        twig[i] = mat_mul(mat_mul(rotation(0, shape[i][0] * PI / 180.0),
                                  rotation(2, shape[i][1] * PI / 180.0)), grow);
    }
    branch(identity(), 1.0, size);
}

/* ---- the command line ------------------------------------------------------ */

static const struct {
    const char *name;
    void (*make)(int size);
    int size, max;      /* the benchmark's size; the largest accepted */
    const char *what;
} dbs[] = {
    {"balls", balls, 4, 8, "sphereflake: (9^(SIZE+1)-1)/8 spheres, 1 floor"},
    {"gears", gears, 4, 40, "SIZE^3 gears: 146 polygons each, 1 floor"},
    {"mount", mount, 6, 12, "fractal mountain: 2*4^SIZE triangles, 4 spheres"},
    {"rings", rings, 7, 60, "5*SIZE*(SIZE+1)*(2*SIZE+1) cylinders and spheres, 1 wall"},
    {"teapot", teapot, 6, 400, "64*SIZE^2-8*SIZE triangles, SIZE^2 squares"},
    {"tetra", tetra, 6, 12, "4^SIZE triangles"},
    {"tree", tree, 11, 24, "2^(SIZE+1)-1 cones and spheres, 1 field"},
};
#define NDB (int)(sizeof dbs / sizeof dbs[0])

static void usage(FILE *f)
{
    int i;
    fprintf(f, "usage: spd DB [SIZE] > scene.nff   (or spd DB -s SIZE)\n"
               "Writes one of Eric Haines' Standard Procedural Databases (SPD 3.14)\n"
               "as NFF.  SIZE is the SPD's size factor (default: the benchmark's).\n");
    for (i = 0; i < NDB; i++)
        fprintf(f, "  %-7s size %2d (1..%d): %s\n", dbs[i].name, dbs[i].size, dbs[i].max,
                dbs[i].what);
    fprintf(f, "mount uses our own random numbers: the SPD's mountain in kind, not in digits.\n");
}

int main(int argc, char **argv)
{
    const char *arg = NULL;
    int db, size;

    if (argc == 2 && (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))) {
        usage(stdout);
        return 0;
    }
    if (argc < 2 || argc > 4) {
        usage(stderr);
        return 2;
    }
    for (db = 0; db < NDB && strcmp(argv[1], dbs[db].name) != 0; db++) {}
    if (db == NDB) {
        fprintf(stderr, "spd: unknown database '%s' (spd --help lists them)\n", argv[1]);
        return 2;
    }
    if (argc == 3) arg = argv[2];
    if (argc == 4) {
        if (strcmp(argv[2], "-s") != 0) {
            usage(stderr);
            return 2;
        }
        arg = argv[3];
    }
    size = dbs[db].size;
    if (arg) {
        char *end;
        long n = strtol(arg, &end, 10);
        if (end == arg || *end || n < 1 || n > dbs[db].max) {
            fprintf(stderr, "spd: %s: SIZE must be a whole number from 1 to %d, not '%s'\n",
                    dbs[db].name, dbs[db].max, arg);
            return 2;
        }
        size = (int)n;
    }
    dbs[db].make(size);
    if (fflush(stdout) != 0 || ferror(stdout)) {
        perror("spd: writing the scene");
        return 1;
    }
    return 0;
}

/* ray.c - the lecture "Ray Tracing + Global Illumination" as one C file:
 * Whitted's recursive ray tracer, spheres, cones and triangles, and the
 * kd-tree (kdtree.c) that finds their hits.
 *
 *     make && ./ray -s 640x480 -n 4 scenes/whitted.sph      (writes whitted.ppm)
 *
 * Usage: ./ray [options] SCENE
 *     -o FILE     output image (default: SCENE's base name with .ppm; - = stdout)
 *     -s WxH      image size (default: the scene's, else 512x512)
 *     -n N        anti-aliasing samples per pixel (default 1)
 *     -d N        recursion depth; 1 = primary rays only (default: scene's, else 5)
 *     -t N        threads (default: every core, when built with OpenMP)
 *     --p3        plain-text PPM (P3) instead of binary (P6)
 *     --accel A   kd (the kd-tree of kdtree.c), none (test every object), or
 *                 auto (default: the tree once there are 8 objects or more)
 *     --stats     print rays by kind, hits, the tree and time on stderr
 *     --help
 * SCENE is the sphere format (README.md), or an NFF file (Eric Haines'
 * Neutral File Format, as the SPD benchmark scenes come) when it ends .nff.
 *
 * HOW TO READ IT.  The lecture comes first, in the order a ray meets it:
 * the types, the vectors, a table of contents (the prototypes), then
 * "for each pixel", RayTrace(R), finding hits, and the primitives.  After
 * the line THE PLUMBING come threads, scene files, output and main(); a
 * student can stop reading there.
 *
 * The lecture's pseudo-code, and the functions that do it:
 *
 *     for each pixel                        render_row(), pixel_color()
 *         compute the ray R from the eye    camera_ray()
 *         pixel colour = RayTrace(R)        trace()
 *
 *     RayTrace(R):                          trace()
 *         find the nearest hit              nearest_hit()
 *           (t, point, object, normal)        surface()
 *         colour = black (or background)
 *         if there is a hit                 shade()
 *             for each light                   shadow_ray()
 *                 a ray to the light; does it hit anything?   any_hit()
 *                 if not, add the light's share
 *             reflected ray Refl               reflect(); colour += RayTrace(Refl)
 *             refracted ray (Snell)            refract(); colour += RayTrace(Refr)
 *
 * One primary ray, from main() to its pixel's byte.  Each function is
 * defined below the one before it, except the seven marked ^, which a
 * reader finds further up:
 *
 *       main()            reads the scene, builds the tree          (plumbing)
 *     ^ render()          shares the rows out among threads         (plumbing)
 *     ^ render_row()      for each pixel of a row                   for each pixel
 *       pixel_color()     averages the pixel's samples
 *       sample_offset()   where sample k lies in the pixel
 *       camera_ray()      the ray R from the eye through it
 *       trace()           RayTrace(R)                               RayTrace(R)
 *       nearest_hit()     the nearest hit                           finding hits
 *       query()           the record the tree hands back
 *       find_nearest()    asks the kd-tree (kd_nearest in kdtree.c), or every object
 *       prim_hit()        the tree's call for one object of a leaf
 *       kind()            sphere, cone or triangle
 *       hit_object()      its intersection test
 *       hit_sphere()      (or hit_cone(), hit_triangle())           the primitives
 *     ^ surface()         point, normals, material of the hit       finding hits
 *       sphere_surface()  (or cone_surface(), triangle_surface())   the primitives
 *     ^ shade()           the light at the hit                      RayTrace(R)
 *       reflect()         the mirror direction (for the highlight)
 *     ^ shadow_ray()      towards each light
 *       spawn()           the ray leaves the surface                finding hits
 *       any_hit()         is anything in the way?
 *       find_any()        asks the tree, or every object
 *     ^ worth_tracing()   is the reflected ray worth it?            RayTrace(R)
 *       (trace() again for the reflected ray, from the top)
 *       refract()         Snell's law, then trace() again
 *     ^ to_byte()         the pixel's colour to a byte              for each pixel
 *       write_ppm()       the image to its file                     (plumbing)
 *
 * Build options: -DREAL=float makes every vector float instead of double
 * (the benchmark compares both); -fopenmp renders rows in parallel.  Output
 * is the same bytes for any number of threads, because no pixel depends on
 * another or on the order pixels are computed in.
 */

/* Unix gets a progress line when stderr is a terminal, a wall clock for
 * --stats, and care not to rename over a device given as -o; elsewhere the
 * program is plain C99 and does without. */
#if defined(__unix__) || defined(__APPLE__)
#define _POSIX_C_SOURCE 200809L
#define RAY_POSIX
#endif
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#ifdef RAY_POSIX
#include <sys/stat.h>
#include <unistd.h>
#endif
#include "prims.h"
#include "kdtree.h"
#include "bvh.h"
#include "grid.h"
#ifdef _OPENMP
#include <omp.h>
#define OMP(directive) _Pragma(#directive)
#else
#define OMP(directive)
#endif

#ifndef REAL
#define REAL double
#endif
typedef REAL real;
/* The unit roundoff of `real`, for error bounds that follow the build. */
#define REAL_EPS (sizeof(real) == sizeof(float) ? FLT_EPSILON : DBL_EPSILON)
#define PI 3.14159265358979323846

/* ------------------------------------------------------------------- types */

typedef struct { real x, y, z; } vec;

/* minray's material: diffuse, mirror, transmitted and emitted weights, and
 * the index of refraction inside (the ray bends by 1/ir going in, by ir
 * coming out).  shine > 0 adds a Phong highlight (NFF's materials have one;
 * minray's spheres do not). */
typedef struct { vec color; real kd, ks, kt, kl, ir, shine; } Material;

typedef struct { vec cen; real rad; int mat; } Sphere;

/* An open cone or cylinder (NFF's `c`): no end caps.  The radius runs from
 * rb at the base to ra at the other end, along the unit axis. */
typedef struct { vec base, axis; real len, rb, ra; int mat; } Cone;

/* Vertices and normals are indices into the scene's shared arrays, so two
 * triangles that share an edge share its exact coordinates.  The hit test
 * needs the first vertex and the two edges from it; they are kept here too,
 * computed once (the same values, so the same answers), so that a test
 * reads one record rather than three vertices. */
typedef struct {
    vec v0, e1, e2;      /* vert[v[0]], vert[v[1]] - v0, vert[v[2]] - v0 */
    int v[3], n[3];      /* n[0] < 0: no vertex normals, shade flat */
    int mat;
    char cull;           /* 1: one-sided, hit from the front only */
    char degenerate;     /* zero area: never hit */
} Triangle;

/* A light is either one of minray's emitting spheres (sphere >= 0: lit when
 * the nearest thing toward its centre is that sphere) or a point light
 * (sphere < 0: lit when nothing lies between). */
typedef struct { vec pos, color; int sphere; } Light;

typedef struct {
    vec eye, right, up, fwd;  /* orthonormal frame */
    real tan_half;            /* tan(fov / 2); fov: horizontal, edge to edge */
    real anchor;              /* 0.5: samples centred on the pixel; 0: on its corner */
} Camera;

typedef struct {
    Material *mat;  int nmat, capmat;
    Sphere *sph;    int nsph, capsph;
    Cone *cone;     int ncone, capcone;
    Triangle *tri;  int ntri, captri;
    vec *vert;      int nvert, capvert;
    vec *norm;      int nnorm, capnorm;
    Light *light;   int nlight, caplight;
    Camera cam;
    int w, h, depth;
    vec ambient, background;
    int cull;                 /* for triangles still to come: `sided 1` */
    int accel;                /* which structure finds hits: an ACCEL_ below */
    const char *accel_line;   /* the scene's `accel NAME` line, or NULL */
    kd_tree *kd;              /* the kd-tree, when accel is ACCEL_KD */
    bvh *bvh;                 /* the BVH, when accel is ACCEL_BVH */
    grid *grid;               /* the grid, when accel is ACCEL_GRID */
    prims prims;              /* how the structure sees the objects (prims.h) */
} Scene;

/* --accel none: every ray tests every object; kd: the kd-tree of kdtree.c;
 * bvh: the bounding volume hierarchy of bvh.c; grid: the uniform grid of
 * grid.c. */
enum { ACCEL_NONE, ACCEL_KD, ACCEL_BVH, ACCEL_GRID };

/* Objects are numbered spheres first, then cones, then triangles. */
enum { SPHERE, CONE, TRIANGLE };

static int nobj(const Scene *s) { return s->nsph + s->ncone + s->ntri; }

/* A ray: origin o, direction d, and skip, an object it cannot hit (or -1).
 * A ray leaving a flat triangle, or a sphere outward, never meets that
 * surface again, yet it starts in the tree's cells that list it: skip spares
 * that test.  The tree leaves skip out itself (kd_nearest's skip); the loop
 * over every object checks it in hit_object. */
typedef struct { vec o, d; int skip; } Ray;

typedef struct {
    real t;
    int obj, mat;
    vec p;        /* the point */
    vec n, ng;    /* shading and geometric normal, both outward (front) */
    real size;    /* coordinate magnitude behind p's rounding error */
} Hit;

/* What the acceleration structure hands its hit callback for one query:
 * the ray, and where on it the last triangle reported was hit. */
typedef struct { Ray r; int obj; real t, u, v; } Query;

/* What --stats prints: rays by kind, and the work of finding hits.  Each
 * thread counts its own; they are summed at the end. */
typedef struct {
    unsigned long long primary, shadow, reflected, refracted;
    unsigned long long queries, nearest, hits;  /* all queries; nearest-hit ones; their hits */
    unsigned long long tests, steps;            /* intersection tests, tree nodes visited */
    int threads;                                /* how many threads rendered */
} Counts;

/* A thread's working state, handed down every call that traces a ray, as
 * smallpt hands down its per-row seed; never a global.  It holds the
 * thread's counts and the shadow cache of any_hit(): the last blocker of
 * each of the first SHADOW_SLOTS lights (lights further on share the slots,
 * which costs cache hits but never changes an answer). */
#define SHADOW_SLOTS 8
typedef struct {
    Counts count;
    int blocker[SHADOW_SLOTS];  /* light i's last blocker, or -1, in slot i % SHADOW_SLOTS */
} Worker;

/* ----------------------------------------------------------------- vectors */

static vec v3(real x, real y, real z) { vec v; v.x = x; v.y = y; v.z = z; return v; }
static vec add(vec a, vec b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static vec sub(vec a, vec b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static vec scale(real k, vec a) { return v3(k * a.x, k * a.y, k * a.z); }
static vec mul(vec a, vec b) { return v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static real dot(vec a, vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static vec cross(vec a, vec b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
/* a*A + B: minray's vcomb, kept because its rounding is what the card does. */
static vec comb(real a, vec A, vec B) { return add(B, scale(a, A)); }
/* Multiply by the reciprocal, as minray's vunit does, for identical bits. */
static vec unit(vec a) { return scale(1 / sqrt(dot(a, a)), a); }
/* The index of the largest of |x|, |y|, |z|. */
static int largest_axis(double x, double y, double z)
{
    x = fabs(x); y = fabs(y); z = fabs(z);
    return x > y ? (x > z ? 0 : 2) : (y > z ? 1 : 2);
}

static void to3(vec a, double out[3]) { out[0] = a.x; out[1] = a.y; out[2] = a.z; }
static real maxabs(vec a)
{
    real m = fabs(a.x);
    if (fabs(a.y) > m) m = fabs(a.y);
    if (fabs(a.z) > m) m = fabs(a.z);
    return m;
}

/* Grows [lo, hi] to take in [lo2, hi2]. */
static void box_union(double lo[3], double hi[3], const double lo2[3], const double hi2[3])
{
    int a;
    for (a = 0; a < 3; a++) {
        lo[a] = fmin(lo[a], lo2[a]);
        hi[a] = fmax(hi[a], hi2[a]);
    }
}

/* ------------------------------------------------------ table of contents */

/* The lecture's functions, in the order a ray meets them; each section
 * below defines them in this order. */

/* for each pixel */
static void render_row(const Scene *s, int j, int spp, unsigned char *row, Worker *wk);
static vec pixel_color(const Scene *s, int i, int j, int spp, Worker *wk);
static void sample_offset(int k, real anchor, real *dx, real *dy);
static Ray camera_ray(const Camera *c, int w, int h, real x, real y);
static unsigned char to_byte(real v);

/* RayTrace(R): Whitted's recursive ray tracing */
static vec trace(const Scene *s, Ray r, int depth, real weight, Worker *wk);
static vec shade(const Scene *s, Ray r, const Hit *h, int depth, real weight, Worker *wk);
static int shadow_ray(const Scene *s, const Hit *h, vec n, const Light *l, real *e,
                      vec *to_light, Worker *wk);
static int worth_tracing(real k, real weight, int depth);
static vec reflect(vec d, vec n, real cosi);
static int refract(vec d, vec n, real cosi, real eta, vec *t);

/* finding hits: the only code that knows an acceleration structure exists */
static int nearest_hit(const Scene *s, Ray r, Hit *h, Worker *wk);
static Query query(Ray r);
static int find_nearest(const Scene *s, Query *q, real *t, Worker *wk);
static int prim_hit(void *user, int i, void *ray, double tmin, double tmax, double *t);
static int kind(const Scene *s, int i, int *k);
static int hit_object(const Scene *s, int i, const Ray *r, real tmax, real *t);
static void surface(const Scene *s, Ray r, int i, real t, const Query *q, Hit *h);
static Ray spawn(const Scene *s, const Hit *h, vec dir);
static int any_hit(const Scene *s, Ray r, real tmax, int *last, Worker *wk);
static int find_any(const Scene *s, Query *q, real tmax, Worker *wk);
static void prim_bounds(void *user, int i, double lo[3], double hi[3]);
static int prim_clip(void *user, int i, const double blo[3], const double bhi[3],
                     double lo[3], double hi[3]);

/* the primitives: each its hit test, its surface, its box and clip */
static real hit_sphere(const Sphere *sp, const Ray *r, real tmin);
static void sphere_surface(const Sphere *sp, const Ray *r, real t, Hit *h);
static void sphere_box(const Sphere *sp, double lo[3], double hi[3]);
static int sphere_clip(const Sphere *sp, const double blo[3], const double bhi[3],
                       double lo[3], double hi[3]);
static real hit_cone(const Cone *c, const Ray *r, real tmin);
static void cone_surface(const Cone *c, const Ray *r, real t, Hit *h);
static void cone_box(const Cone *c, double lo[3], double hi[3]);
static int hit_triangle(const Scene *s, const Triangle *tr, const Ray *r, real tmax,
                        real *t, real *u, real *v);
static void triangle_surface(const Scene *s, const Triangle *tr, real u, real v, Hit *h);
static void triangle_box(const Scene *s, const Triangle *tr, double lo[3], double hi[3]);
static int triangle_clip(const Scene *s, const Triangle *tr, const double blo[3],
                         const double bhi[3], double lo[3], double hi[3]);

/* ---------------------------------------------------------- for each pixel */

/* The lecture's "for each pixel", for one row of the image (rows are what
 * the threads share out: see render()). */
static void render_row(const Scene *s, int j, int spp, unsigned char *row, Worker *wk)
{
    int i;
    for (i = 0; i < s->w; i++) {
        vec c = pixel_color(s, i, j, spp, wk);
        row[3 * i] = to_byte(c.x);
        row[3 * i + 1] = to_byte(c.y);
        row[3 * i + 2] = to_byte(c.z);
    }
}


/* The pixel's colour: RayTrace of each of its spp samples, averaged. */
static vec pixel_color(const Scene *s, int i, int j, int spp, Worker *wk)
{
    vec sum = v3(0, 0, 0);
    int k;
    for (k = 0; k < spp; k++) {
        real dx, dy;
        sample_offset(k, s->cam.anchor, &dx, &dy);
        wk->count.primary++;
        sum = add(sum, trace(s, camera_ray(&s->cam, s->w, s->h, i + dx, j + dy), s->depth, 1, wk));
    }
    return scale((real)1 / spp, sum);
}

/* Sample k of n inside a pixel: the R2 low-discrepancy sequence (Roberts,
 * "The unreasonable effectiveness of quasirandom sequences", 2018), which
 * spreads any number of points evenly and needs no random numbers, so every
 * run gives the same bytes.  Sample 0 lies on the anchor: the pixel's centre,
 * or with `pixel corner` its top-left corner, where minray aims. */
static void sample_offset(int k, real anchor, real *dx, real *dy)
{
    const double a1 = 0.7548776662466927, a2 = 0.5698402909980532; /* 1/g, 1/g^2; g^3 = g + 1 */
    *dx = (real)(anchor + fmod(k * a1, 1.0));
    *dy = (real)(anchor + fmod(k * a2, 1.0));
    if (*dx >= anchor + 0.5) *dx -= 1;          /* wrap into [anchor-1/2, anchor+1/2) */
    if (*dy >= anchor + 0.5) *dy -= 1;
}

/* The primary ray through image point (x, y), in pixels from the top-left
 * corner of the image.  The image plane stands at the distance where the
 * image's width spans the field of view edge to edge; a pixel is one unit. */
static Ray camera_ray(const Camera *c, int w, int h, real x, real y)
{
    real dist = (real)w / 2 / c->tan_half;
    Ray r;
    r.o = c->eye;
    r.skip = -1;
    r.d = unit(add(add(scale(x - (real)w / 2, c->right),
                       scale((real)h / 2 - y, c->up)), scale(dist, c->fwd)));
    return r;
}

/* Colour in 0..1 to a byte: x255 and round to nearest (as minray's %.0f
 * does), clamped; NaN becomes 0 so that no pixel is ever undefined. */
static unsigned char to_byte(real v)
{
    double x = rint((double)v * 255);
    if (!(x > 0)) return 0;
    return x > 255 ? 255 : (unsigned char)x;
}

/* ------------------------------------------------------------- RayTrace(R) */

/* The lecture's RayTrace(R).  depth counts down like minray's level: a ray
 * traced with depth 1 is a leaf of the recursion.  weight is how much the
 * ray's colour counts in the pixel (1 for a primary ray). */
static vec trace(const Scene *s, Ray r, int depth, real weight, Worker *wk)
{
    Hit h;
    if (depth <= 0) return v3(0, 0, 0);
    if (!nearest_hit(s, r, &h, wk)) return s->background;
    return shade(s, r, &h, depth, weight, wk);
}

/* Local light, then reflection and refraction by recursion: minray's model,
 * plus a Phong highlight for materials that have one.  The sums run in the
 * card's order so that the rounding is the card's too. */
static vec shade(const Scene *s, Ray r, const Hit *h, int depth, real weight, Worker *wk)
{
    const Material *m = &s->mat[h->mat];
    vec n = h->n, color = s->ambient, spec = v3(0, 0, 0), c, t, mirror, dir;
    real cosi = -dot(r.d, n), eta = 1 / m->ir, e;
    int i;
    if (dot(r.d, h->ng) > 0) { n = scale(-1, n); cosi = -cosi; eta = m->ir; } /* inside */
    mirror = reflect(r.d, n, cosi);
    for (i = 0; i < s->nlight; i++)
        if (shadow_ray(s, h, n, &s->light[i], &e, &dir, wk)) {
            color = comb(e, s->light[i].color, color);
            /* Phong (1975): the mirror direction against the light's.  Not
             * for ks = 0, where it adds nothing (and pow() of a huge shine,
             * such as the SPD floor's 100000, underflows slowly). */
            if (m->shine > 0 && m->ks > 0) {
                real rl = dot(mirror, dir);
                if (rl > 0) spec = comb(pow(rl, m->shine), s->light[i].color, spec);
            }
        }
    color = mul(color, m->color);

    c = scale(m->kl, m->color);                 /* emission */
    c = comb(m->kd, color, c);                  /* diffuse */
    if (m->shine > 0) c = comb(m->ks, spec, c); /* highlight */
    if (worth_tracing(m->ks, weight, depth)) {
        wk->count.reflected++;
        c = comb(m->ks, trace(s, spawn(s, h, mirror), depth - 1, m->ks * weight, wk), c);
    }
    if (worth_tracing(m->kt, weight, depth) && refract(r.d, n, cosi, eta, &t)) {
        wk->count.refracted++;
        c = comb(m->kt, trace(s, spawn(s, h, t), depth - 1, m->kt * weight, wk), c);
    }
    return c;
}

/* The lecture's shadow ray: is light l seen from the hit point?  *e returns
 * its strength kl * cos(angle to the normal n), *to_light the unit vector
 * toward it (shade() needs it again for the highlight). */
static int shadow_ray(const Scene *s, const Hit *h, vec n, const Light *l,
                      real *e, vec *to_light, Worker *wk)
{
    vec dir = *to_light = unit(sub(l->pos, h->p));
    Ray r;
    Hit blocker;
    real k = l->sphere >= 0 ? s->mat[s->sph[l->sphere].mat].kl : 1;
    *e = k * dot(n, dir);
    if (!(*e > 0)) return 0;    /* facing away: no ray, as the SPD rules say */
    wk->count.shadow++;
    r = spawn(s, h, dir);
    if (l->sphere < 0)          /* a point light: anything before it blocks */
        return !any_hit(s, r, sqrt(dot(sub(l->pos, r.o), sub(l->pos, r.o))),
                        &wk->blocker[(l - s->light) % SHADOW_SLOTS], wk);
    return nearest_hit(s, r, &blocker, wk) && blocker.obj == l->sphere;
}

/* Whether to trace a secondary ray that adds k times its colour to a hit
 * that itself counts `weight` in the pixel.  Not at the last level (depth 1:
 * it would return black), and not when its weight in the pixel falls under
 * half a step of an 8-bit channel, where it can hardly change a byte: Hall
 * and Greenberg's adaptive depth (1983).  Without it, two facing mirrors or
 * nested glass double the rays at every level, and -d 30 takes days; with
 * it, minray's scene and depth 3 never come near the limit. */
#define MIN_WEIGHT (1.0 / 512)
static int worth_tracing(real k, real weight, int depth)
{
    return k > 0 && depth > 1 && k * weight >= MIN_WEIGHT;
}

/* The mirror direction of d about the normal n, where cosi = -d.n > 0. */
static vec reflect(vec d, vec n, real cosi) { return comb(2 * cosi, n, d); }

/* Snell's law: the refracted direction of unit d through a surface with
 * normal n (facing d, cosi = -d.n > 0) and index ratio eta = n1/n2.  Returns
 * 0 on total internal reflection, when no refracted ray exists. */
static int refract(vec d, vec n, real cosi, real eta, vec *t)
{
    real k = 1 - eta * eta * (1 - cosi * cosi); /* cos^2 of the refracted angle */
    if (!(k > 0)) return 0;
    *t = comb(eta, d, scale(eta * cosi - sqrt(k), n));
    return 1;
}

/* ------------------------------------------------------------ finding hits */

/* The lecture's "find the nearest hit" (t, point, object, normal).
 * Returns 0 when r hits nothing. */
static int nearest_hit(const Scene *s, Ray r, Hit *h, Worker *wk)
{
    Query q = query(r);
    real t;
    int best;
    wk->count.queries++;
    wk->count.nearest++;
    best = find_nearest(s, &q, &t, wk);
    if (best < 0) return 0;
    wk->count.hits++;
    surface(s, r, best, t, &q, h);
    return 1;
}

/* A query starts with no triangle hit noted. */
static Query query(Ray r)
{
    Query q;
    q.r = r, q.obj = -1;
    return q;
}

/* The one place that knows which structure answers (--accel): the object
 * the ray in q hits first, and its t in *t; -1 for none. */
static int find_nearest(const Scene *s, Query *q, real *t, Worker *wk)
{
    real ti;
    int i, best = -1;
    if (s->accel != ACCEL_NONE) {
        double o[3], d[3], tmax = INFINITY;
        prim_counters c = { 0, 0, 0 };
        to3(q->r.o, o);
        to3(q->r.d, d);
        if (s->accel == ACCEL_KD)
            best = kd_nearest(s->kd, &s->prims, o, d, q, q->r.skip, 0, &tmax, &c);
        else if (s->accel == ACCEL_BVH)
            best = bvh_nearest(s->bvh, &s->prims, o, d, q, q->r.skip, 0, &tmax, &c);
        else
            best = grid_nearest(s->grid, &s->prims, o, d, q, q->r.skip, 0, &tmax, &c);
        *t = (real)tmax;
        wk->count.steps += c.steps;
        wk->count.tests += c.tests;
        return best;
    }
    *t = INFINITY;                             /* none: test every object */
    for (i = 0; i < nobj(s); i++)
        if (hit_object(s, i, &q->r, *t, &ti) && ti < *t) { *t = ti; best = i; }
    wk->count.tests += (unsigned long long)nobj(s);
    return best;
}

/* The acceleration structure sees the objects only through three callbacks
 * (prims.h): this one, and prim_bounds and prim_clip below, which the build
 * uses.  The hit callback gets the Query, and notes there
 * where on a triangle it found its hit, so that nearest_hit need not test
 * the nearest triangle a second time to shade it. */
static int prim_hit(void *user, int i, void *ray, double tmin, double tmax, double *t)
{
    const Scene *s = user;
    Query *q = ray;
    real tt, u, v;
    int k;
    (void)tmin;             /* rays start off the surface; see spawn() */
    /* q->r.skip never comes here: the tree leaves it out */
    if (kind(s, i, &k) == TRIANGLE) {   /* hit_object would test it again */
        if (!hit_triangle(s, &s->tri[k], &q->r, (real)tmax, &tt, &u, &v))
            return 0;
        q->obj = i, q->t = tt, q->u = u, q->v = v;
    } else if (!hit_object(s, i, &q->r, (real)tmax, &tt))
        return 0;
    *t = tt;
    return 1;
}

/* The kind of object i, and (in *k) its index within its own kind. */
static int kind(const Scene *s, int i, int *k)
{
    if (i < s->nsph) { *k = i; return SPHERE; }
    i -= s->nsph;
    if (i < s->ncone) { *k = i; return CONE; }
    *k = i - s->ncone;
    return TRIANGLE;
}

/* Object i against the ray: 1 and its t when hit with 0 < t <= tmax. */
static int hit_object(const Scene *s, int i, const Ray *r, real tmax, real *t)
{
    real u, v;
    int k;
    if (i == r->skip) return 0;
    switch (kind(s, i, &k)) {
    case SPHERE: *t = hit_sphere(&s->sph[k], r, 0); break;
    case CONE: *t = hit_cone(&s->cone[k], r, 0); break;
    default: return hit_triangle(s, &s->tri[k], r, tmax, t, &u, &v);
    }
    return *t <= tmax && *t < INFINITY;         /* INFINITY is a miss */
}

/* The point, normals and material of the hit on object i at t.  q (or
 * NULL) may hold the barycentrics of that hit already. */
static void surface(const Scene *s, Ray r, int i, real t, const Query *q, Hit *h)
{
    int k, what = kind(s, i, &k);
    real u, v, tt;
    h->t = t;
    h->obj = i;
    if (what == SPHERE) sphere_surface(&s->sph[k], &r, t, h);
    else if (what == CONE) cone_surface(&s->cone[k], &r, t, h);
    else {
        if (q && q->obj == i && q->t == t) u = q->u, v = q->v;
        else hit_triangle(s, &s->tri[k], &r, INFINITY, &tt, &u, &v);
        triangle_surface(s, &s->tri[k], u, v, h);
    }
}

/* A secondary ray starts on the surface it leaves.  With a fixed epsilon in
 * t, a scene scaled to 1e4 hits its own surface again ("acne") and one scaled
 * to 1e-3 misses real neighbours.  Instead the origin moves off the surface,
 * along the normal to the side the ray leaves by, by a few ulps of the largest
 * coordinate involved: the rounding error of the hit point scales with that,
 * whatever the scene's units (Pharr, Jakob and Humphreys, pbrt 3rd ed.,
 * sect. 3.9.5, "Robust spawned ray origins").  The 64 covers the dozen or so
 * roundings between the ray, the root and the point, with margin. */
static Ray spawn(const Scene *s, const Hit *h, vec dir)
{
    real eps = 64 * REAL_EPS * h->size;
    int k, out = dot(dir, h->ng) >= 0, what = kind(s, h->obj, &k);
    Ray r;
    r.o = comb(out ? eps : -eps, h->ng, h->p);
    r.d = dir;
    r.skip = what == TRIANGLE || (what == SPHERE && out) ? h->obj : -1;
    return r;
}

/* Is anything hit with 0 < t <= tmax?  For shadow rays to point lights,
 * where any blocker will do and the nearest is not needed.
 *
 * *last is the shadow cache (Haines and Greenberg, "The light buffer",
 * 1986): the object that last blocked a ray to the same light, tried before
 * the tree, since the next pixel's shadow ray tends to meet the same one.
 * It only changes how soon the answer is found: the object is tested like
 * any other.  A ray that gets through leaves the cache alone: its neighbour
 * may be blocked again.  --accel none is the plain loop over every object,
 * so it does without the cache. */
static int any_hit(const Scene *s, Ray r, real tmax, int *last, Worker *wk)
{
    real t;
    int hit;
    Query q;
    wk->count.queries++;
    if (s->accel != ACCEL_NONE && *last >= 0) {
        wk->count.tests++;
        if (hit_object(s, *last, &r, tmax, &t)) return 1;
    }
    q = query(r);
    hit = find_any(s, &q, tmax, wk);
    if (hit >= 0) *last = hit;
    return hit >= 0;
}

/* The same for any hit with 0 < t <= tmax: the object found, or -1. */
static int find_any(const Scene *s, Query *q, real tmax, Worker *wk)
{
    real t;
    int i;
    if (s->accel != ACCEL_NONE) {
        double o[3], d[3];
        prim_counters c = { 0, 0, 0 };
        int hit;
        to3(q->r.o, o);
        to3(q->r.d, d);
        if (s->accel == ACCEL_KD)
            hit = kd_any(s->kd, &s->prims, o, d, q, q->r.skip, 0, tmax, &c);
        else if (s->accel == ACCEL_BVH)
            hit = bvh_any(s->bvh, &s->prims, o, d, q, q->r.skip, 0, tmax, &c);
        else
            hit = grid_any(s->grid, &s->prims, o, d, q, q->r.skip, 0, tmax, &c);
        wk->count.steps += c.steps;
        wk->count.tests += c.tests;
        return hit;
    }
    for (i = 0; i < nobj(s); i++) {
        wk->count.tests++;
        if (hit_object(s, i, &q->r, tmax, &t)) return i;
    }
    return -1;
}

static void prim_bounds(void *user, int i, double lo[3], double hi[3])
{
    const Scene *s = user;
    int k;
    switch (kind(s, i, &k)) {
    case SPHERE: sphere_box(&s->sph[k], lo, hi); break;
    case CONE: cone_box(&s->cone[k], lo, hi); break;
    default: triangle_box(s, &s->tri[k], lo, hi);
    }
}

/* A sphere and a triangle are clipped to the box exactly; a cone's box is
 * simply cut to it. */
static int prim_clip(void *user, int i, const double blo[3], const double bhi[3],
                     double lo[3], double hi[3])
{
    const Scene *s = user;
    int k, a;
    switch (kind(s, i, &k)) {
    case SPHERE: return sphere_clip(&s->sph[k], blo, bhi, lo, hi);
    case TRIANGLE: return triangle_clip(s, &s->tri[k], blo, bhi, lo, hi);
    }
    cone_box(&s->cone[k], lo, hi);
    for (a = 0; a < 3; a++) {
        if (lo[a] < blo[a]) lo[a] = blo[a];
        if (hi[a] > bhi[a]) hi[a] = bhi[a];
        if (lo[a] > hi[a]) return 0;
    }
    return 1;
}

/* ------------------------------------------------- the primitives: spheres */

/* Smallest root t of |o + t d - c| = r with t > tmin, or INFINITY.
 *
 * The textbook form b*b - c loses every digit when the sphere is far away or
 * small: both terms are about |o-c|^2 and their difference about r^2.  Here
 * the discriminant is r^2 - |l|^2, where l is the vector from the centre to
 * the point of the line closest to it, which has no such cancellation; and
 * the two roots come from q and c/q so that neither subtracts two nearly
 * equal numbers (Haines, Guenter, Jones, Akenine-Moller and Hunt, "Precision
 * Improvements for Ray/Sphere Intersection", Ray Tracing Gems, ch. 7, 2019).
 * l is kept multiplied by a = d.d, so that a miss, the common case in a
 * tree's leaf, costs no division. */
static real hit_sphere(const Sphere *sp, const Ray *r, real tmin)
{
    vec f = sub(r->o, sp->cen);
    real a = dot(r->d, r->d);
    real b = -dot(f, r->d);                      /* half of -B in a t^2 + B t + C */
    vec l = comb(b, r->d, scale(a, f));          /* a l */
    real ar = a * sp->rad, disc = ar * ar - dot(l, l);   /* a^2 (r^2 - l.l) */
    real c, q, t0, t1;
    if (!(disc >= 0)) return INFINITY;          /* also rejects NaN */
    disc /= a;                                  /* the quarter discriminant */
    c = dot(f, f) - sp->rad * sp->rad;
    q = b + (b >= 0 ? sqrt(disc) : -sqrt(disc));
    t0 = c / q;
    t1 = q / a;
    if (t0 > t1) { real tt = t0; t0 = t1; t1 = tt; }
    if (t0 > tmin) return t0;
    if (t1 > tmin) return t1;
    return INFINITY;
}

static void sphere_surface(const Sphere *sp, const Ray *r, real t, Hit *h)
{
    h->p = comb(t, r->d, r->o);
    h->n = h->ng = unit(sub(h->p, sp->cen));
    h->mat = sp->mat;
    h->size = maxabs(h->p) + maxabs(sp->cen) + sp->rad + maxabs(r->o);
}

static void sphere_box(const Sphere *sp, double lo[3], double hi[3])
{
    to3(sub(sp->cen, v3(sp->rad, sp->rad, sp->rad)), lo);
    to3(add(sp->cen, v3(sp->rad, sp->rad, sp->rad)), hi);
}

/* The box of the part of a sphere inside [blo, bhi].  Cutting the sphere's
 * own box to the cell would leave the cell's corners in it, and a sphere
 * fills only half its box: in a scene of many spheres (SPD balls) a ray
 * would test, in every cell a sphere's box reaches, a sphere it cannot hit
 * there.  A point of the sphere that lies in the cell is at least db and dc
 * from the centre along the other two axes (0 when the centre is level with
 * the cell), so along axis a it is within sqrt(r^2 - db^2 - dc^2) of the
 * centre.  That square root is taken of a difference which can cancel, so
 * 1e-12 r^2 is added under it: far above the rounding error, and the box
 * grows by at most 1e-6 r. */
static int sphere_clip(const Sphere *sp, const double blo[3], const double bhi[3],
                       double lo[3], double hi[3])
{
    double c[3], d[3], r2 = (double)sp->rad * sp->rad, slack = 1e-12 * r2;
    int a;
    to3(sp->cen, c);
    for (a = 0; a < 3; a++)
        d[a] = c[a] < blo[a] ? blo[a] - c[a] : c[a] > bhi[a] ? c[a] - bhi[a] : 0;
    for (a = 0; a < 3; a++) {
        double db = d[(a + 1) % 3], dc = d[(a + 2) % 3], e2 = r2 - db * db - dc * dc, e;
        if (!(e2 >= -slack)) return 0;
        e = fmin(sqrt(fmax(e2, 0) + slack), sp->rad);
        lo[a] = fmax(c[a] - e, blo[a]);
        hi[a] = fmin(c[a] + e, bhi[a]);
        if (!(lo[a] <= hi[a])) return 0;
    }
    return 1;
}

/* --------------------------------------------------- the primitives: cones */

/* Smallest t > tmin where the ray meets the open cone's side, or INFINITY.
 * A point at height h = (p - base).axis lies on the side when its distance
 * from the axis is the radius there, rb + k h, with k the slope (ra - rb)/len,
 * and 0 <= h <= len.  Squaring gives a quadratic A t^2 + 2B t + C = 0 in the
 * ray's t, and each root is kept only if its height lies on the cone.  A
 * cylinder is the case k = 0.
 * Precision: B^2 - AC cancels when the ray starts far from the cone (its
 * terms grow with the distance squared).  So the ray is first moved along
 * itself to t0, level with the cone's middle, the quadratic solved from
 * there, and t0 added back: the same idea as the sphere's closest point.
 * The roots then come from q and C/q, so that neither subtracts. */
static real hit_cone(const Cone *c, const Ray *r, real tmin)
{
    real t0 = dot(sub(comb(c->len / 2, c->axis, c->base), r->o), r->d) / dot(r->d, r->d);
    vec q = sub(comb(t0, r->d, r->o), c->base);
    real k = (c->ra - c->rb) / c->len;
    real qh = dot(q, c->axis), dh = dot(r->d, c->axis);
    vec qx = comb(-qh, c->axis, q), dx = comb(-dh, c->axis, r->d); /* across the axis */
    real rq = c->rb + k * qh;                   /* radius at the origin's height */
    real A = dot(dx, dx) - k * k * dh * dh;
    real B = dot(qx, dx) - rq * k * dh;
    real C = dot(qx, qx) - rq * rq;
    real disc = B * B - A * C, root[2], qq;
    int i;
    if (A == 0) {                               /* parallel to a line of the cone */
        if (B == 0) return INFINITY;
        root[0] = root[1] = -C / (2 * B);
    } else {
        if (!(disc >= 0)) return INFINITY;
        qq = -(B + (B >= 0 ? sqrt(disc) : -sqrt(disc)));
        root[0] = qq / A;
        root[1] = qq != 0 ? C / qq : root[0];
        if (root[0] > root[1]) { real tt = root[0]; root[0] = root[1]; root[1] = tt; }
    }
    for (i = 0; i < 2; i++) {
        real h = qh + root[i] * dh;
        if (root[i] + t0 > tmin && h >= 0 && h <= c->len) return root[i] + t0;
    }
    return INFINITY;
}

/* The outward normal at p: away from the axis, tilted by the slope. */
static vec cone_normal(const Cone *c, vec p)
{
    vec q = sub(p, c->base), radial = comb(-dot(q, c->axis), c->axis, q);
    real k = (c->ra - c->rb) / c->len;
    if (!(dot(radial, radial) > 0)) return scale(-1, c->axis); /* the apex itself */
    return unit(comb(-k, c->axis, unit(radial)));
}

static void cone_surface(const Cone *c, const Ray *r, real t, Hit *h)
{
    h->p = comb(t, r->d, r->o);
    h->n = h->ng = cone_normal(c, h->p);
    h->mat = c->mat;
    h->size = maxabs(h->p) + maxabs(c->base) + c->len + c->rb + c->ra + maxabs(r->o);
}

/* The box of a disc of radius r about centre c, square to the unit vector
 * n: along each axis it reaches r sqrt(1 - n_axis^2) from the centre. */
static void disc_box(vec c, vec n, real r, double lo[3], double hi[3])
{
    double cc[3], nn[3];
    int a;
    to3(c, cc);
    to3(n, nn);
    for (a = 0; a < 3; a++) {
        double e = r * sqrt(fmax(0, 1 - nn[a] * nn[a]));
        lo[a] = cc[a] - e;
        hi[a] = cc[a] + e;
    }
}

/* The box of the cone: the boxes of its two end circles together. */
static void cone_box(const Cone *c, double lo[3], double hi[3])
{
    double lo2[3], hi2[3];
    disc_box(c->base, c->axis, c->rb, lo, hi);
    disc_box(comb(c->len, c->axis, c->base), c->axis, c->ra, lo2, hi2);
    box_union(lo, hi, lo2, hi2);
}

/* ----------------------------------------------- the primitives: triangles */

/* a*d - b*c to within 2 ulps of its value (Kahan's algorithm with a fused
 * multiply-add; Jeannerod, Louvet and Muller, Math. Comp. 82, 2013), so its
 * sign is always the true sign of the rounded inputs, and 0 only when the
 * determinant is exactly 0. */
static double det2(double a, double b, double c, double d)
{
    double w = b * c;
    return fma(a, d, -w) + fma(-b, c, w);
}

/* Does the ray pass through triangle a b c, edges and corners included?
 * Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection" (JCGT 2(1),
 * 2013): shear space so that the ray runs along an axis from the origin,
 * then ask on which side of each edge the origin lies.  Each vertex is moved
 * by the same arithmetic in every triangle that shares it, and each side is
 * decided by an exact sign (det2), so the triangles around an edge or a
 * vertex tile the plane with no gap for a ray to slip through. */
static int watertight_inside(vec a, vec b, vec c, const Ray *r)
{
    double d[3], o[3], p[3][3], x[3], y[3], u, v, w, sx, sy;
    int kz, kx, ky, i, k;
    vec q[3];
    q[0] = a; q[1] = b; q[2] = c;
    to3(r->d, d);
    to3(r->o, o);
    kz = largest_axis(d[0], d[1], d[2]);
    kx = (kz + 1) % 3;
    ky = (kx + 1) % 3;
    sx = d[kx] / d[kz];
    sy = d[ky] / d[kz];
    for (i = 0; i < 3; i++) {
        to3(q[i], p[i]);
        for (k = 0; k < 3; k++) p[i][k] -= o[k];
        x[i] = p[i][kx] - sx * p[i][kz];
        y[i] = p[i][ky] - sy * p[i][kz];
    }
    u = det2(x[2], y[2], x[1], y[1]);   /* edge b c */
    v = det2(x[0], y[0], x[2], y[2]);   /* edge c a */
    w = det2(x[1], y[1], x[0], y[0]);   /* edge a b */
    if (!((u >= 0 && v >= 0 && w >= 0) || (u <= 0 && v <= 0 && w <= 0))) return 0;
    return u + v + w != 0;              /* 0: the ray lies in the triangle's plane */
}

/* Moller and Trumbore, "Fast, Minimum Storage Ray/Triangle Intersection"
 * (1997), as the lecture prints it, with three changes:
 *  - No epsilon.  The original rejects |det| < 1e-6, but det grows with the
 *    square of the triangle's size, so small triangles vanish (legs of 2e-4
 *    give det 4e-8).  The bounds are compared as u <= det instead of u/det
 *    <= 1, which no scale changes; only det == 0 (a ray in the triangle's
 *    plane, or a triangle of zero area) is rejected.  Every test is written
 *    so that NaN fails it.
 *  - t must be in (0, tmax]; the sign is checked before the division.
 *  - Watertight: rounding can put a ray through a shared edge or vertex
 *    outside every triangle there.  When a bound fails by less than 1e-7 of
 *    det (far below any visible distance, far above the rounding error),
 *    the exact test watertight_inside() decides instead.  That is rare, so
 *    the common case keeps Moller and Trumbore's speed.
 * Returns 1 and t, u, v (barycentrics of v1 and v2) on a hit. */
static int hit_triangle(const Scene *s, const Triangle *tr, const Ray *r, real tmax,
                        real *t, real *u, real *v)
{
    vec v0 = tr->v0, e1 = tr->e1, e2 = tr->e2, p = cross(r->d, e2), tv, q;
    real det = dot(e1, p), sign = det < 0 ? -1 : 1, slack, uu, vv, tt;
    if (tr->degenerate || isnan(det)) return 0;
    if (tr->cull) {                      /* the lecture's culling branch */
        if (!(det > 0)) return 0;
    } else if (det == 0)                 /* the non-culling branch */
        return 0;
    det *= sign;                         /* from here on det > 0 */
    slack = (real)1e-7 * det;
    tv = sub(r->o, v0);                   /* u, v and t, each times det */
    uu = sign * dot(tv, p);
    if (uu < -slack || uu > det + slack) return 0;
    q = cross(tv, e1);
    vv = sign * dot(r->d, q);
    if (vv < -slack || uu + vv > det + slack) return 0;
    tt = sign * dot(e2, q);
    if (!(tt > 0)) return 0;             /* behind the origin, or NaN */
    if ((uu < 0 || vv < 0 || uu + vv > det)
        && !watertight_inside(v0, s->vert[tr->v[1]], s->vert[tr->v[2]], r)) return 0;
    *t = tt / det;      /* compared after the division: a tie at tmax must be exact */
    if (!(*t <= tmax)) return 0;
    *u = uu / det;
    *v = vv / det;
    return 1;
}

/* The point at barycentrics u, v, and the normals there.  The point comes
 * from the barycentrics, not from o + t d: exact to the triangle's own
 * rounding, however far away the ray came from. */
static void triangle_surface(const Scene *s, const Triangle *tr, real u, real v, Hit *h)
{
    vec a = s->vert[tr->v[0]], b = s->vert[tr->v[1]], c = s->vert[tr->v[2]];
    h->p = add(add(scale(1 - u - v, a), scale(u, b)), scale(v, c));
    h->ng = unit(cross(tr->e1, tr->e2));
    h->n = h->ng;
    if (tr->n[0] >= 0) {
        vec n = add(add(scale(1 - u - v, s->norm[tr->n[0]]), scale(u, s->norm[tr->n[1]])),
                    scale(v, s->norm[tr->n[2]]));
        if (dot(n, n) > 0) h->n = unit(dot(n, h->ng) < 0 ? scale(-1, n) : n);
    }
    h->mat = tr->mat;
    h->size = maxabs(a) + maxabs(b) + maxabs(c);
}

static void triangle_box(const Scene *s, const Triangle *tr, double lo[3], double hi[3])
{
    double p[3];
    int j;
    to3(s->vert[tr->v[0]], lo);
    to3(s->vert[tr->v[0]], hi);
    for (j = 1; j < 3; j++) {
        to3(s->vert[tr->v[j]], p);
        box_union(lo, hi, p, p);
    }
}

/* The box of the part of a triangle inside [blo, bhi]: the triangle clipped
 * by the box's six planes (Sutherland and Hodgman, 1974), so that the tree
 * can split a long triangle exactly ("perfect splits", Havran 2000). */
static int triangle_clip(const Scene *s, const Triangle *tr, const double blo[3],
                         const double bhi[3], double lo[3], double hi[3])
{
    double poly[2][9][3];
    int n = 3, k, a, side, cur = 0;
    for (k = 0; k < 3; k++) to3(s->vert[tr->v[k]], poly[0][k]);
    for (a = 0; a < 3; a++)
        for (side = 0; side < 2; side++) {
            double plane = side ? bhi[a] : blo[a], sign = side ? -1 : 1;
            int m = 0;
            const double (*in)[3] = (const double (*)[3])poly[cur];
            double (*out)[3] = poly[1 - cur];
            for (k = 0; k < n; k++) {
                const double *p = in[k], *q = in[(k + 1) % n];
                double dp = sign * (p[a] - plane), dq = sign * (q[a] - plane);
                if (dp >= 0) { memcpy(out[m++], p, sizeof out[0]); }
                if ((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) {
                    double f = dp / (dp - dq);
                    int c;
                    for (c = 0; c < 3; c++) out[m][c] = p[c] + f * (q[c] - p[c]);
                    out[m][a] = plane;     /* exactly on the plane, not near it */
                    m++;
                }
            }
            n = m;
            cur = 1 - cur;
            if (n == 0) return 0;
        }
    for (a = 0; a < 3; a++) {
        lo[a] = hi[a] = poly[cur][0][a];
        for (k = 1; k < n; k++) {
            if (poly[cur][k][a] < lo[a]) lo[a] = poly[cur][k][a];
            if (poly[cur][k][a] > hi[a]) hi[a] = poly[cur][k][a];
        }
    }
    return 1;
}

/* Zero area (a repeated vertex, or three in a line) to within rounding: such
 * a triangle has no inside and no normal, so it is never hit.  Relative to
 * the edge lengths, so that tiny but proper triangles stay. */
static int degenerate(vec a, vec b, vec c)
{
    vec e1 = sub(b, a), e2 = sub(c, a), n = cross(e1, e2);
    real k = 64 * REAL_EPS * sqrt(dot(e1, e1) * dot(e2, e2));
    return !(sqrt(dot(n, n)) > k);
}

/* =========================================================================
 * THE PLUMBING.  The lecture ends here.  What follows makes it a program:
 * threads and a progress line, reading scenes (the sphere format, OBJ and
 * NFF) into a Scene, writing the image, the command line and main().
 * ========================================================================= */

/* ---------------------------------------------------- threads and progress */

typedef struct { int spp, threads, progress; } Options;

/* Seconds on a wall clock (processor time where there is none: with threads
 * that overstates the time). */
static double now(void)
{
#ifdef RAY_POSIX
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
#else
    return (double)clock() / CLOCKS_PER_SEC;
#endif
}

static int stderr_is_terminal(void)
{
#ifdef RAY_POSIX
    return isatty(2);
#else
    return 0;
#endif
}

static void add_counts(Counts *to, const Counts *from)
{
    to->primary += from->primary;
    to->shadow += from->shadow;
    to->reflected += from->reflected;
    to->refracted += from->refracted;
    to->hits += from->hits;
    to->tests += from->tests;
    to->steps += from->steps;
    to->queries += from->queries;
    to->nearest += from->nearest;
    if (from->threads > to->threads) to->threads = from->threads;
}

/* The whole image, row by row (render_row).  Rows go to threads one at a
 * time, as they free up; each pixel is written once by whoever computes it,
 * so the image does not depend on the order.  Each thread has its own
 * Worker; their counts are summed into *total. */
static void render(const Scene *s, const Options *o, unsigned char *img, Counts *total)
{
    int done = 0;
#ifdef _OPENMP
    if (o->threads > 0) omp_set_num_threads(o->threads);
#endif
    OMP(omp parallel)
    {
        Worker wk;
        int j;
        memset(&wk, 0, sizeof wk);
        wk.count.threads = 1;
#ifdef _OPENMP
        wk.count.threads = omp_get_num_threads();
#endif
        OMP(omp for schedule(dynamic, 1))
        for (j = 0; j < s->h; j++) {
            int i, mine;
            /* a row starts with an empty shadow cache, so that the counts
             * do not depend on which thread had the row before */
            for (i = 0; i < SHADOW_SLOTS; i++) wk.blocker[i] = -1;
            render_row(s, j, o->spp, img + 3 * (size_t)j * s->w, &wk);
            OMP(omp atomic capture)
            mine = ++done;
            if (o->progress && (mine * 100 / s->h != (mine - 1) * 100 / s->h))
                fprintf(stderr, "\rray: %3d%%", mine * 100 / s->h);
        }
        OMP(omp critical)
        add_counts(total, &wk.count);
    }
    if (o->progress) fprintf(stderr, "\r          \r");
}

/* ------------------------------------------------------------- scene input */

typedef struct { const char *file; int line; } Where;

static int fail(Where w, const char *msg, const char *arg)
{
    fprintf(stderr, "%s:%d: %s%s%s\n", w.file, w.line, msg, arg ? ": " : "", arg ? arg : "");
    return 0;
}

/* One finite number from a token, or a message saying what is wrong. */
static int number(Where w, const char *tok, real *out)
{
    char *end;
    double v = strtod(tok, &end);
    if (end == tok || *end) return fail(w, "not a number", tok);
    if (!isfinite(v)) return fail(w, "number must be finite", tok);
    *out = (real)v;
    return 1;
}

/* The n numbers after tok[first], and nothing else on the line.  `what`
 * names the line's kind for the message. */
static int numbers(Where w, const char *what, char **tok, int ntok, int first, int n, real *out)
{
    int i;
    char buf[128];
    if (ntok - first != n) {
        sprintf(buf, "%.40s needs %d numbers, found %d", what, n, ntok - first);
        return fail(w, buf, NULL);
    }
    for (i = 0; i < n; i++)
        if (!number(w, tok[first + i], &out[i])) return 0;
    return 1;
}

static void out_of_memory(void)
{
    fprintf(stderr, "ray: out of memory\n");
    exit(1);
}

/* Room for one more element in a growing array. */
static void *grow(void *p, int *cap, int need, size_t size)
{
    if (need <= *cap) return p;
    *cap = *cap ? 2 * *cap : 16;
    if (*cap < need) *cap = need;
    p = realloc(p, (size_t)*cap * size);
    if (!p) out_of_memory();
    return p;
}

static void add_light(Scene *s, vec pos, vec color, int sphere)
{
    s->light = grow(s->light, &s->caplight, s->nlight + 1, sizeof *s->light);
    s->light[s->nlight].pos = pos;
    s->light[s->nlight].color = color;
    s->light[s->nlight].sphere = sphere;
    s->nlight++;
}

static int add_material(Scene *s, Material m)
{
    s->mat = grow(s->mat, &s->capmat, s->nmat + 1, sizeof *s->mat);
    s->mat[s->nmat] = m;
    return s->nmat++;
}

static void add_sphere(Scene *s, vec cen, real rad, int mat)
{
    Sphere *p;
    s->sph = grow(s->sph, &s->capsph, s->nsph + 1, sizeof *s->sph);
    p = &s->sph[s->nsph++];
    p->cen = cen;
    p->rad = rad;
    p->mat = mat;
    if (s->mat[mat].kl > 0) add_light(s, cen, s->mat[mat].color, s->nsph - 1);
}

static int add_vertex(Scene *s, vec p)
{
    s->vert = grow(s->vert, &s->capvert, s->nvert + 1, sizeof *s->vert);
    s->vert[s->nvert] = p;
    return s->nvert++;
}

static int add_normal(Scene *s, vec n)
{
    s->norm = grow(s->norm, &s->capnorm, s->nnorm + 1, sizeof *s->norm);
    s->norm[s->nnorm] = n;
    return s->nnorm++;
}

/* Vertices a, b, c and normals na, nb, nc (-1: none) by index. */
static void add_triangle(Scene *s, int a, int b, int c, int na, int nb, int nc, int mat)
{
    Triangle *tr;
    s->tri = grow(s->tri, &s->captri, s->ntri + 1, sizeof *s->tri);
    tr = &s->tri[s->ntri++];
    tr->v[0] = a; tr->v[1] = b; tr->v[2] = c;
    tr->v0 = s->vert[a];
    tr->e1 = sub(s->vert[b], s->vert[a]);
    tr->e2 = sub(s->vert[c], s->vert[a]);
    if (na < 0 || nb < 0 || nc < 0) na = nb = nc = -1;
    tr->n[0] = na; tr->n[1] = nb; tr->n[2] = nc;
    tr->mat = mat;
    tr->cull = (char)s->cull;
    tr->degenerate = (char)degenerate(s->vert[a], s->vert[b], s->vert[c]);
}

/* Twice the signed area of the 2-D triangle a b c. */
static double area2(const double *a, const double *b, const double *c)
{
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* Is 2-D point p inside or on the triangle a b c (counter-clockwise)? */
static int inside2(const double *p, const double *a, const double *b, const double *c)
{
    return area2(a, b, p) >= 0 && area2(b, c, p) >= 0 && area2(c, a, p) >= 0;
}

/* A polygon's corners in 2-D, counter-clockwise: it is projected on the
 * plane square to its normal's largest axis (Newell's normal, right for any
 * simple polygon, concave or not). */
static void flatten(const Scene *s, const int *vi, int n, double (*p)[2])
{
    double nn[3] = { 0, 0, 0 }, c[3];
    int k, ax, ux, vx;
    for (k = 0; k < n; k++) {
        vec a = s->vert[vi[k]], b = s->vert[vi[(k + 1) % n]];
        nn[0] += (a.y - b.y) * (a.z + b.z);
        nn[1] += (a.z - b.z) * (a.x + b.x);
        nn[2] += (a.x - b.x) * (a.y + b.y);
    }
    ax = largest_axis(nn[0], nn[1], nn[2]);
    ux = (ax + 1) % 3;            /* (ux, vx, ax) is right-handed: seen from */
    vx = (ax + 2) % 3;            /* +ax, counter-clockwise is positive area */
    if (nn[ax] < 0) { k = ux; ux = vx; vx = k; }
    for (k = 0; k < n; k++) {
        to3(s->vert[vi[k]], c);
        p[k][0] = c[ux];
        p[k][1] = c[vx];
    }
}

/* Corner k of the polygon idx[0..m-1] can be cut off: it turns left, and no
 * other corner lies in the triangle it makes with its neighbours. */
static int is_ear(double (*p)[2], const int *idx, int m, int k)
{
    const double *a = p[idx[(k + m - 1) % m]], *b = p[idx[k]], *c = p[idx[(k + 1) % m]];
    int j;
    if (area2(a, b, c) <= 0) return 0;                  /* reflex or flat */
    for (j = 0; j < m; j++) {
        const double *q = p[idx[j]];
        if (inside2(q, a, b, c) && memcmp(q, a, sizeof *p) && memcmp(q, b, sizeof *p)
            && memcmp(q, c, sizeof *p))
            return 0;
    }
    return 1;
}

/* The triangle of corners i, j, k of the polygon. */
static void add_corner_triangle(Scene *s, const int *vi, const int *ni, int i, int j, int k,
                                int mat)
{
    add_triangle(s, vi[i], vi[j], vi[k], ni ? ni[i] : -1, ni ? ni[j] : -1, ni ? ni[k] : -1, mat);
}

/* Corners a..b of a convex polygon, closed by the edge b-a: the triangle
 * a, m, b with m halfway, then the two arcs it leaves.  Unlike a fan from
 * one corner, no vertex is shared by more than a few triangles, and they
 * shrink towards the rim: a fan of thousands of slivers meeting at a point
 * is the kd-tree's worst case (every cell near the point holds them all). */
static void triangulate_arc(Scene *s, const int *vi, const int *ni, int a, int b, int mat)
{
    int m = a + (b - a) / 2;
    if (b - a < 2) return;
    add_corner_triangle(s, vi, ni, a, m, b, mat);
    triangulate_arc(s, vi, ni, a, m, mat);
    triangulate_arc(s, vi, ni, m, b, mat);
}

/* A planar polygon, convex or not, as triangles, by ear clipping (Meisters,
 * "Polygons have ears", 1975): some corner can always be cut off, leaving a
 * polygon one corner smaller.  A fan from one corner would be wrong for the
 * gears' concave 144-gons; a convex polygon takes the O(n) way above.
 * vi and ni are the corners' vertex and normal indices (ni may be NULL). */
static void triangulate(Scene *s, const int *vi, const int *ni, int n, int mat)
{
    double (*p)[2] = malloc((size_t)n * sizeof *p);
    int *idx = malloc((size_t)n * sizeof *idx), m = n, k, convex = 1;
    if (!p || !idx) out_of_memory();
    flatten(s, vi, n, p);
    for (k = 0; k < n; k++) {
        idx[k] = k;
        if (area2(p[(k + n - 1) % n], p[k], p[(k + 1) % n]) < 0) convex = 0;
    }
    if (convex) triangulate_arc(s, vi, ni, 0, n - 1, mat);
    for (k = 0; !convex && m > 2; m--) {
        int tries;
        for (tries = 0; m > 3 && tries < m && !is_ear(p, idx, m, k); tries++) k = (k + 1) % m;
        /* tries == m: only flat or self-touching corners are left; cut one anyway */
        add_corner_triangle(s, vi, ni, idx[(k + m - 1) % m], idx[k], idx[(k + 1) % m], mat);
        memmove(idx + k, idx + k + 1, (size_t)(m - k - 1) * sizeof *idx);
        if (k >= m - 1) k = 0;
    }
    free(p);
    free(idx);
}

static void add_cone(Scene *s, vec base, real rb, vec apex, real ra, int mat)
{
    Cone *c;
    s->cone = grow(s->cone, &s->capcone, s->ncone + 1, sizeof *s->cone);
    c = &s->cone[s->ncone++];
    c->base = base;
    c->len = sqrt(dot(sub(apex, base), sub(apex, base)));
    c->axis = unit(sub(apex, base));
    c->rb = rb;
    c->ra = ra;
    c->mat = mat;
}

/* bx by bz rb  ax ay az ra: a cone's base and apex, each with its radius. */
static int check_cone(Scene *s, Where w, const real *x, int mat)
{
    vec base = v3(x[0], x[1], x[2]), apex = v3(x[4], x[5], x[6]);
    if (!(x[3] >= 0 && x[7] >= 0 && x[3] + x[7] > 0))
        return fail(w, "cone radii must be >= 0 and not both 0", NULL);
    if (!(dot(sub(apex, base), sub(apex, base)) > 0))
        return fail(w, "cone base and apex coincide", NULL);
    add_cone(s, base, x[3], apex, x[7], mat);
    return 1;
}

/* r g b kd ks kt kl ir: minray's material fields, for tri and mesh lines. */
static int material8(Scene *s, Where w, const real *v, int *mat)
{
    Material m;
    if (!(v[7] > 0)) return fail(w, "index of refraction must be positive", NULL);
    m.color = v3(v[0], v[1], v[2]);
    m.kd = v[3]; m.ks = v[4]; m.kt = v[5]; m.kl = v[6]; m.ir = v[7]; m.shine = 0;
    *mat = add_material(s, m);
    return 1;
}

/* One sphere: minray's 12 numbers in minray's order. */
static int parse_sphere(Scene *s, Where w, char **tok, int ntok)
{
    real v[12];
    int mat;
    if (!numbers(w, "a sphere", tok, ntok, 0, 12, v)) return 0;
    if (!(v[6] > 0)) return fail(w, "sphere radius must be positive", tok[6]);
    {
        real m[8];          /* the material: all the fields after the centre but the radius */
        m[0] = v[3]; m[1] = v[4]; m[2] = v[5];
        m[3] = v[7]; m[4] = v[8]; m[5] = v[9]; m[6] = v[10]; m[7] = v[11];
        if (!material8(s, w, m, &mat)) return 0;
    }
    add_sphere(s, v3(v[0], v[1], v[2]), v[6], mat);
    return 1;
}

static int set_camera(Scene *s, Where w, const real *v)
{
    Camera *c = &s->cam;
    vec at = v3(v[3], v[4], v[5]), up = v3(v[6], v[7], v[8]);
    c->eye = v3(v[0], v[1], v[2]);
    if (!(dot(sub(at, c->eye), sub(at, c->eye)) > 0))
        return fail(w, "camera looks at its own eye", NULL);
    if (!(v[9] > 0 && v[9] < 180))
        return fail(w, "field of view must be between 0 and 180 degrees", NULL);
    c->tan_half = tan(v[9] * PI / 360);
    c->fwd = unit(sub(at, c->eye));
    c->right = cross(c->fwd, up);
    if (!(dot(c->right, c->right) > 0)) return fail(w, "camera up is parallel to its view", NULL);
    c->right = unit(c->right);
    c->up = cross(c->right, c->fwd);
    return 1;
}

#define SIZE_RULE "image size must be whole numbers from 1 to 32768, at most 2^28 pixels"

/* 32768 a side and 2^28 pixels: more would not fit a PPM anyone can open and
 * would take hours; a wrong number is far likelier than such a wish. */
static int check_size(double fw, double fh, int *width, int *height)
{
    if (!(fw >= 1 && fh >= 1 && fw <= 32768 && fh <= 32768 && fw == floor(fw) && fh == floor(fh)
          && fw * fh <= 268435456.0))
        return 0;
    *width = (int)fw;
    *height = (int)fh;
    return 1;
}

static int blank(int c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

/* Splits a line in place into at most max blank-separated tokens; '#'
 * starts a comment.  Returns max + 1 when there are more. */
static int tokens(char *line, char **tok, int max)
{
    int n = 0;
    char *p = line;
    for (;;) {
        while (blank(*p)) p++;
        if (!*p || *p == '#') return n;
        if (n == max) return max + 1;
        tok[n++] = p;
        while (*p && *p != '#' && !blank(*p)) p++;
        if (*p == '#') { *p = 0; return n; }
        if (*p) *p++ = 0;
    }
}

/* Reads the next line of f into line; 0 at the end or on an over-long line
 * (then *ok is cleared and the message printed). */
static int next_line(FILE *f, char *line, int size, Where *w, int *ok)
{
    if (!fgets(line, size, f)) return 0;
    w->line++;
    if (!strchr(line, '\n') && !feof(f)) {
        char msg[64];
        sprintf(msg, "line longer than %d characters", size - 2);
        return *ok = fail(*w, msg, NULL);
    }
    return 1;
}

/* An OBJ face corner "v", "v/t", "v//n" or "v/t/n"; indices count from 1,
 * or back from the newest when negative.  *n is -1 without a normal. */
static int obj_corner(Where w, char *c, int nv, int nn, int *v, int *n)
{
    char *end, *slash;
    long i = strtol(c, &end, 10);
    if (end == c || (*end && *end != '/')) return fail(w, "bad face corner", c);
    if (i < 0) i += nv + 1;
    if (i < 1 || i > nv) return fail(w, "vertex index out of range", c);
    *v = (int)i - 1;
    *n = -1;
    slash = strchr(c, '/');
    if (slash && (slash = strchr(slash + 1, '/')) && slash[1]) {
        i = strtol(slash + 1, &end, 10);
        if (end == slash + 1 || *end) return fail(w, "bad face corner", c);
        if (i < 0) i += nn + 1;
        if (i < 1 || i > nn) return fail(w, "normal index out of range", c);
        *n = (int)i - 1;
    }
    return 1;
}

/* Wavefront OBJ: v, vn and f (any number of corners); every other statement
 * is skipped with one warning for the file.  `from` is the scene line that
 * asked for it, for the message when it cannot be opened. */
#define OBJ_LINE 65536                  /* room for faces of thousands of corners */

static int load_obj(Scene *s, const char *file, int mat, Where from)
{
    int max = OBJ_LINE / 2, v0 = s->nvert, n0 = s->nnorm, ok = 1, skipped = 0, skipped_line = 0;
    char *line = malloc(OBJ_LINE), **tok = malloc(sizeof *tok * (max + 1)), first_skipped[32] = "";
    int *vi = malloc(sizeof *vi * max), *ni = malloc(sizeof *ni * max);
    Where w;
    FILE *f = fopen(file, "r");
    if (!line || !tok || !vi || !ni) out_of_memory();
    if (!f) ok = fail(from, "cannot open mesh", strerror(errno));
    w.file = file;
    w.line = 0;
    while (ok && next_line(f, line, OBJ_LINE, &w, &ok)) {
        int n = tokens(line, tok, max), k, with_normals = 1;
        real x[3];
        if (n == 0) continue;
        if (n > max) ok = fail(w, "too many fields", NULL);
        else if (!strcmp(tok[0], "v") || !strcmp(tok[0], "vn")) {
            int normal = tok[0][1] == 'n';
            /* a vertex may go on with w, or with a colour: both unused */
            ok = numbers(w, tok[0], tok, normal || n < 4 ? n : 4, 1, 3, x);
            if (ok && normal) add_normal(s, v3(x[0], x[1], x[2]));
            if (ok && !normal) add_vertex(s, v3(x[0], x[1], x[2]));
        } else if (!strcmp(tok[0], "f")) {
            if (n < 4) ok = fail(w, "a face needs 3 corners or more", NULL);
            for (k = 1; k < n && ok; k++) {
                ok = obj_corner(w, tok[k], s->nvert - v0, s->nnorm - n0, &vi[k - 1], &ni[k - 1]);
                vi[k - 1] += v0;
                if (ni[k - 1] < 0) with_normals = 0;
                else ni[k - 1] += n0;
            }
            if (ok) triangulate(s, vi, with_normals ? ni : NULL, n - 1, mat);
        } else if (!skipped++) {
            skipped_line = w.line;
            sprintf(first_skipped, "%.20s", tok[0]);
        }
    }
    if (f) fclose(f);
    if (ok && skipped)
        fprintf(stderr, "%s:%d: warning: skipped %d statement%s that are not v, vn or f"
                " (the first: %s)\n",
                file, skipped_line, skipped, skipped == 1 ? "" : "s", first_skipped);
    free(line); free(tok); free(vi); free(ni);
    return ok;
}

/* A path named in a scene is relative to the scene's directory. */
static char *beside(const char *scene, const char *name)
{
    const char *slash = strrchr(scene, '/');
    size_t dir = name[0] == '/' || !slash ? 0 : (size_t)(slash - scene + 1);
    char *p = malloc(dir + strlen(name) + 1);
    if (!p) out_of_memory();
    memcpy(p, scene, dir);
    strcpy(p + dir, name);
    return p;
}

/* The structures --accel and a scene's `accel` line name (see build_accel):
 * the name as a string that lasts, or NULL for an unknown one. */
static const char *accel_name(const char *name)
{
    static const char *const names[] = { "kd", "bvh", "grid", "none", "auto" };
    size_t i;
    for (i = 0; i < sizeof names / sizeof names[0]; i++)
        if (!strcmp(name, names[i])) return names[i];
    return NULL;
}

/* A keyword line: ray.c's extensions to minray's format. */
static int parse_keyword(Scene *s, Where w, char **tok, int ntok)
{
    real v[17];
    const char *k = tok[0];
    int mat, ok;
    if (!strcmp(k, "accel")) {
        if (ntok != 2 || !accel_name(tok[1]))
            return fail(w, "expected `accel` and one of kd, bvh, grid, none, auto", NULL);
        s->accel_line = accel_name(tok[1]);
        return 1;
    }
    if (!strcmp(k, "size"))
        return numbers(w, k, tok, ntok, 1, 2, v)
               && (check_size(v[0], v[1], &s->w, &s->h) || fail(w, SIZE_RULE, NULL));
    if (!strcmp(k, "depth")) {
        if (!numbers(w, k, tok, ntok, 1, 1, v)) return 0;
        if (!(v[0] >= 1 && v[0] <= 64 && v[0] == floor(v[0])))
            return fail(w, "depth must be a whole number from 1 to 64", tok[1]);
        s->depth = (int)v[0];
        return 1;
    }
    if (!strcmp(k, "ambient")) {
        if (!numbers(w, k, tok, ntok, 1, 3, v)) return 0;
        s->ambient = v3(v[0], v[1], v[2]);
        return 1;
    }
    if (!strcmp(k, "background")) {
        if (!numbers(w, k, tok, ntok, 1, 3, v)) return 0;
        s->background = v3(v[0], v[1], v[2]);
        return 1;
    }
    if (!strcmp(k, "camera"))
        return numbers(w, k, tok, ntok, 1, 10, v) && set_camera(s, w, v);
    if (!strcmp(k, "light")) {
        if (!numbers(w, k, tok, ntok, 1, 6, v)) return 0;
        add_light(s, v3(v[0], v[1], v[2]), v3(v[3], v[4], v[5]), -1);
        return 1;
    }
    if (!strcmp(k, "pixel")) {
        if (ntok != 2
            || (strcmp(tok[1], "corner") && strcmp(tok[1], "centre") && strcmp(tok[1], "center")))
            return fail(w, "expected `pixel corner` or `pixel centre`", NULL);
        s->cam.anchor = !strcmp(tok[1], "corner") ? 0 : (real)0.5;
        return 1;
    }
    if (!strcmp(k, "sided")) {
        if (ntok != 2 || (strcmp(tok[1], "1") && strcmp(tok[1], "2")))
            return fail(w, "expected `sided 1` (front faces only) or `sided 2`", NULL);
        s->cull = tok[1][0] == '1';
        return 1;
    }
    if (!strcmp(k, "tri")) {
        int a, b;
        if (!numbers(w, k, tok, ntok, 1, 17, v) || !material8(s, w, v + 9, &mat)) return 0;
        a = add_vertex(s, v3(v[0], v[1], v[2]));
        b = add_vertex(s, v3(v[3], v[4], v[5]));
        add_triangle(s, a, b, add_vertex(s, v3(v[6], v[7], v[8])), -1, -1, -1, mat);
        return 1;
    }
    if (!strcmp(k, "cone")) {
        if (!numbers(w, k, tok, ntok, 1, 16, v) || !material8(s, w, v + 8, &mat)) return 0;
        return check_cone(s, w, v, mat);
    }
    if (!strcmp(k, "mesh")) {
        char *path;
        if (ntok < 2) return fail(w, "mesh needs a file name and 8 numbers", NULL);
        if (!numbers(w, k, tok, ntok, 2, 8, v) || !material8(s, w, v, &mat)) return 0;
        path = beside(w.file, tok[1]);
        ok = load_obj(s, path, mat, w);
        free(path);
        return ok;
    }
    return fail(w, "unknown keyword", k);
}

static void default_scene(Scene *s)
{
    real v[10] = { 0, 0, 0, 0, 1, 0, 0, 0, 1, 45 };
    Where nowhere = { "", 0 };
    memset(s, 0, sizeof *s);
    s->w = s->h = 512;
    s->depth = 5;
    s->cam.anchor = (real)0.5;
    set_camera(s, nowhere, v);
}

/* The sphere format: a line of numbers is a sphere, a line that starts with
 * a word is a keyword. */
static int load_sph(Scene *s, FILE *f, Where w)
{
    char line[4096], *tok[24];
    int ok = 1;
    while (ok && next_line(f, line, sizeof line, &w, &ok)) {
        int n = tokens(line, tok, 23);
        if (n > 23) ok = fail(w, "too many fields", NULL);
        else if (n == 0) continue;
        else if (strchr("+-.0123456789", tok[0][0])) ok = parse_sphere(s, w, tok, n);
        else ok = parse_keyword(s, w, tok, n);
    }
    return ok;
}

/* ---------- NFF, Eric Haines' Neutral File Format (the SPD scenes' format) */

/* NFF is a stream of blank-separated tokens, not of lines (a cone's eight
 * numbers may sit on one line or three), so it is read a token at a time.
 * `again` hands the last token out once more, for a look ahead. */
typedef struct { FILE *f; Where w; int c, again; char tok[256]; } Lexer;

/* The next token into lx->tok: 1, or 0 at the end of the file, or -1 after
 * saying what is wrong. */
static int next_token(Lexer *lx)
{
    int n = 0;
    if (lx->again) { lx->again = 0; return 1; }
    for (;;) {
        for (; blank(lx->c); lx->c = getc(lx->f))
            if (lx->c == '\n') lx->w.line++;
        if (lx->c != '#') break;
        while (lx->c != '\n' && lx->c != EOF) lx->c = getc(lx->f);
    }
    for (; lx->c != EOF && !blank(lx->c); lx->c = getc(lx->f)) {
        if (n == (int)sizeof lx->tok - 1) {
            fail(lx->w, "token longer than 255 characters", NULL);
            return -1;
        }
        lx->tok[n++] = (char)lx->c;
    }
    lx->tok[n] = 0;
    return n > 0;
}

/* n numbers in a row, after `what`. */
static int nff_numbers(Lexer *lx, const char *what, int n, real *out)
{
    int i;
    for (i = 0; i < n; i++) {
        int got = next_token(lx);
        if (got == 0) return fail(lx->w, "the file ends inside", what);
        if (got < 0 || !number(lx->w, lx->tok, &out[i])) return 0;
    }
    return 1;
}

/* The view block: from, at, up, angle, hither, resolution, each once.  NFF's
 * angle spans the centres of the outer pixels, (W-1) pixels, where ours
 * spans the edges, W pixels. */
static int nff_view(Scene *s, Lexer *lx)
{
    static const char *const names[6] = { "from", "at", "up", "angle", "hither", "resolution" };
    static const int counts[6] = { 3, 3, 3, 1, 1, 2 };
    real x[6][3], v[10];
    int seen = 0, k, got = 1;
    while (seen != 63 && (got = next_token(lx)) > 0) {
        for (k = 0; k < 6 && strcmp(lx->tok, names[k]); k++) continue;
        if (k == 6)
            return fail(lx->w, "expected from, at, up, angle, hither or resolution", lx->tok);
        if (seen & 1 << k) return fail(lx->w, "said twice in the view block", names[k]);
        seen |= 1 << k;
        if (!nff_numbers(lx, names[k], counts[k], x[k])) return 0;
    }
    if (got < 0) return 0;
    if (seen != 63)
        return fail(lx->w, "the view block needs from, at, up, angle, hither and resolution", NULL);
    if (!check_size(x[5][0], x[5][1], &s->w, &s->h)) return fail(lx->w, SIZE_RULE, NULL);
    if (!(x[3][0] > 0 && x[3][0] < 180))
        return fail(lx->w, "view angle must be between 0 and 180 degrees", NULL);
    for (k = 0; k < 9; k++) v[k] = x[k / 3][k % 3];   /* from, at, up */
    v[9] = 2 * atan(tan(x[3][0] * PI / 360) * s->w / (s->w > 1 ? s->w - 1 : 1)) * 180 / PI;
    return set_camera(s, lx->w, v);
}

/* A polygon of n corners, with a normal at each (pp) or not (p). */
static int nff_polygon(Scene *s, Lexer *lx, int normals, int mat)
{
    real x[6], cnt;
    int n, k, *vi, *ni, ok = 1;
    if (!nff_numbers(lx, normals ? "pp" : "p", 1, &cnt)) return 0;
    if (!(cnt >= 3 && cnt <= 1e6 && cnt == floor(cnt)))
        return fail(lx->w, "a polygon needs from 3 to 1000000 corners", lx->tok);
    n = (int)cnt;
    vi = malloc((size_t)n * sizeof *vi);
    ni = malloc((size_t)n * sizeof *ni);
    if (!vi || !ni) out_of_memory();
    for (k = 0; k < n && ok; k++) {
        ok = nff_numbers(lx, "a polygon", normals ? 6 : 3, x);
        if (!ok) break;
        vi[k] = add_vertex(s, v3(x[0], x[1], x[2]));
        if (normals) ni[k] = add_normal(s, v3(x[3], x[4], x[5]));
    }
    if (ok) triangulate(s, vi, normals ? ni : NULL, n, mat);
    free(vi);
    free(ni);
    return ok;
}

/* l x y z [r g b]: a point light, white unless a colour follows. */
static int nff_light(Scene *s, Lexer *lx)
{
    real x[3], rgb[3] = { 1, 1, 1 };
    int got;
    if (!nff_numbers(lx, "l", 3, x)) return 0;
    got = next_token(lx);                    /* a colour, or the next entity */
    if (got < 0) return 0;
    lx->again = got > 0;
    if (got > 0 && strchr("+-.0123456789", lx->tok[0]) && !nff_numbers(lx, "l", 3, rgb)) return 0;
    add_light(s, v3(x[0], x[1], x[2]), v3(rgb[0], rgb[1], rgb[2]), -1);
    return 1;
}

/* b r g b: the colour of rays that hit nothing. */
static int nff_background(Scene *s, Lexer *lx)
{
    real x[3];
    if (!nff_numbers(lx, "b", 3, x)) return 0;
    s->background = v3(x[0], x[1], x[2]);
    return 1;
}

/* f r g b Kd Ks Shine T ior: the material of all that follows. */
static int nff_material(Scene *s, Lexer *lx, int *mat)
{
    real x[8];
    Material m;
    if (!nff_numbers(lx, "f", 8, x)) return 0;
    m.color = v3(x[0], x[1], x[2]);
    m.kd = x[3]; m.ks = x[4]; m.shine = x[5]; m.kt = x[6]; m.kl = 0;
    m.ir = x[7] > 0 ? x[7] : 1;  /* the SPD files write 0 for opaque materials */
    *mat = add_material(s, m);
    return 1;
}

static int nff_sphere(Scene *s, Lexer *lx, int mat)
{
    real x[4];
    if (!nff_numbers(lx, "s", 4, x)) return 0;
    if (!(x[3] > 0)) return fail(lx->w, "sphere radius must be positive", lx->tok);
    add_sphere(s, v3(x[0], x[1], x[2]), x[3], mat);
    return 1;
}

/* c: base centre and radius, apex centre and radius. */
static int nff_cone(Scene *s, Lexer *lx, int mat)
{
    real x[8];
    return nff_numbers(lx, "c", 8, x) && check_cone(s, lx->w, x, mat);
}

static int load_nff(Scene *s, FILE *f, Where w)
{
    Lexer lx;
    int mat = -1, k, ok = 1, got = 1;
    double intensity;
    lx.f = f; lx.w = w; lx.w.line = 1; lx.c = getc(f); lx.again = 0;
    while (ok && (got = next_token(&lx)) > 0) {
        const char *t = lx.tok;
        if (mat < 0 && strchr("spc", t[0])) {    /* objects before any f: plain white */
            Material m;
            m.color = v3(1, 1, 1); m.kd = 1; m.ks = m.kt = m.kl = m.shine = 0; m.ir = 1;
            mat = add_material(s, m);
        }
        if (!strcmp(t, "v")) ok = nff_view(s, &lx);
        else if (!strcmp(t, "b")) ok = nff_background(s, &lx);
        else if (!strcmp(t, "l")) ok = nff_light(s, &lx);
        else if (!strcmp(t, "f")) ok = nff_material(s, &lx, &mat);
        else if (!strcmp(t, "s")) ok = nff_sphere(s, &lx, mat);
        else if (!strcmp(t, "c")) ok = nff_cone(s, &lx, mat);
        else if (!strcmp(t, "p")) ok = nff_polygon(s, &lx, 0, mat);
        else if (!strcmp(t, "pp")) ok = nff_polygon(s, &lx, 1, mat);
        else ok = fail(lx.w, "unknown NFF entity", t);
    }
    ok = ok && got == 0;                         /* the end, not a bad token */
    /* The SPD's suggested strength: sqrt(L) / (2 L) for each of L lights and
     * for the ambient, so that the total stays about the same for any L. */
    intensity = s->nlight ? sqrt((double)s->nlight) / (2.0 * s->nlight) : 0;
    for (k = 0; k < s->nlight; k++) s->light[k].color = scale((real)intensity, s->light[k].color);
    s->ambient = v3((real)intensity, (real)intensity, (real)intensity);
    return ok;
}

/* The scene by its name: NFF when it ends .nff, else the sphere format. */
static int load_scene(Scene *s, const char *file)
{
    Where w = { file, 0 };
    FILE *f = fopen(file, "r");
    size_t len = strlen(file);
    int ok;
    default_scene(s);
    if (!f) return fail(w, "cannot open scene", strerror(errno));
    ok = len > 4 && !strcmp(file + len - 4, ".nff") ? load_nff(s, f, w) : load_sph(s, f, w);
    if (ok && ferror(f)) ok = fail(w, "read error", strerror(errno));
    fclose(f);
    return ok;
}

/* ------------------------------------------------------------------ output */

/* Where the image goes.  It is opened before the render, so that a bad -o
 * fails at once rather than after a long render.  A new or plain file is
 * written as FILE.tmp and renamed over FILE at the end, so that a failure
 * never leaves a half-written image behind.  Anything else (stdout, a device
 * such as /dev/null, a pipe, a symbolic link) is written in place and never
 * renamed over or removed. */
typedef struct { FILE *f; const char *name; char *tmp; } Output;

#ifdef RAY_POSIX
/* Absent, or a plain file (not a link, a device or a pipe)? */
static int replaceable(const char *name)
{
    struct stat st;
    return lstat(name, &st) != 0 ? errno == ENOENT : S_ISREG(st.st_mode);
}
#else
static int replaceable(const char *name) { (void)name; return 1; }
#endif

static int open_output(Output *o, const char *name)
{
    o->name = name;
    o->tmp = NULL;
    o->f = stdout;
    if (!strcmp(name, "-")) return 1;
    if (replaceable(name)) {
        o->tmp = malloc(strlen(name) + 5);
        if (!o->tmp) return 0;
        sprintf(o->tmp, "%s.tmp", name);
        errno = EEXIST;               /* the message if FILE.tmp is no plain file */
        o->f = replaceable(o->tmp) ? fopen(o->tmp, "wb") : NULL;
    } else
        o->f = fopen(name, "wb");
    if (o->f) return 1;
    fprintf(stderr, "%s: cannot write: %s\n", o->tmp ? o->tmp : name, strerror(errno));
    free(o->tmp);
    return 0;
}

/* Gives up an output: nothing is left of it. */
static void discard_output(Output *o)
{
    if (o->f != stdout) fclose(o->f);
    if (o->tmp) remove(o->tmp);
    free(o->tmp);
}

static int write_ppm(Output *o, const unsigned char *img, int w, int h, int plain)
{
    size_t i, n = (size_t)w * h * 3;
    int ok;
    fprintf(o->f, "%s\n%d %d\n255\n", plain ? "P3" : "P6", w, h);
    if (plain)
        for (i = 0; i < n; i += 3) fprintf(o->f, "%d %d %d\n", img[i], img[i + 1], img[i + 2]);
    else
        fwrite(img, 1, n, o->f);
    ok = fflush(o->f) == 0 && !ferror(o->f);
    if (o->f != stdout) ok = fclose(o->f) == 0 && ok;
    if (ok && o->tmp) ok = rename(o->tmp, o->name) == 0;
    if (!ok) {
        fprintf(stderr, "%s: cannot write: %s\n", o->name, strerror(errno));
        if (o->tmp) remove(o->tmp);
    }
    free(o->tmp);
    return ok;
}

/* ------------------------------------------------------------ command line */

static void usage(FILE *to)
{
    fputs("usage: ray [options] SCENE\n"
          "Renders SCENE with Whitted ray tracing: the sphere format (README.md), or\n"
          "NFF (Eric Haines' Neutral File Format, the SPD scenes') when it ends .nff.\n"
          "  -o FILE    output PPM (default: SCENE's base name + .ppm; - for stdout)\n"
          "  -s WxH     image size (default: the scene's `size`, else 512x512)\n"
          "  -n N       anti-aliasing samples per pixel (default 1)\n"
          "  -d N       recursion depth, 1 = primary rays only (default: scene's, else 5)\n"
          "  -t N       threads (default: all cores, when built with OpenMP)\n"
          "  --p3       write plain-text P3 instead of binary P6\n"
          "  --accel A  kd (the kd-tree), bvh (bounding volume hierarchy), grid\n"
          "             (uniform grid), none (test every object) or auto (default:\n"
          "             the scene's `accel` line, else from 8 objects up the one that\n"
          "             renders a 32x32 probe of the image fastest, its build included)\n"
          "  --stats    print rays by kind, hits, the tree and time on stderr\n"
          "  --help     this text\n", to);
}

/* A whole number from 1 to max, or exit with a message naming the option. */
static int int_arg(const char *opt, const char *arg, int max)
{
    char *end;
    long v = arg ? strtol(arg, &end, 10) : 0;
    if (!arg || end == arg || *end || v < 1 || v > max) {
        fprintf(stderr, "ray: %s needs a whole number from 1 to %d%s%s\n", opt, max,
                arg ? ", not " : "", arg ? arg : "");
        exit(2);
    }
    return (int)v;
}

static char *default_output(const char *scene)
{
    const char *base = strrchr(scene, '/'), *dot;
    char *out;
    base = base ? base + 1 : scene;
    dot = strrchr(base, '.');
    out = malloc(strlen(base) + 5);
    if (!out) out_of_memory();
    sprintf(out, "%.*s.ppm", dot ? (int)(dot - base) : (int)strlen(base), base);
    return out;
}

/* From this many objects on, the tree pays; below, a loop over them all
 * costs less than walking even a small tree.  Measured on scenes of random
 * spheres, 800x800 at 8 samples, one thread: 5 spheres, the loop 12% faster;
 * 8, even; 12 and 16, the tree 16% and 17% faster.  On the minray scene
 * (5 spheres) the loop is 25% faster. */
#define TREE_FROM 8

/* auto's probe: PROBE x PROBE pixels spread over the image, one sample
 * each, rendered whole (shadows and mirrors included) with the structure s
 * has; the processor seconds it took.  It gives up, returning what it has
 * spent, once that exceeds `limit`. */
#define PROBE 32
static double probe(const Scene *s, double limit)
{
    Worker wk;
    clock_t start = clock();
    double spent = 0;
    int i, j;
    memset(&wk, 0, sizeof wk);
    for (i = 0; i < SHADOW_SLOTS; i++) wk.blocker[i] = -1;
    for (j = 0; j < PROBE && spent <= limit; j++) {
        for (i = 0; i < PROBE; i++)
            trace(s, camera_ray(&s->cam, s->w, s->h, (i + (real)0.5) * s->w / PROBE,
                                (j + (real)0.5) * s->h / PROBE), s->depth, 1, &wk);
        spent = (double)(clock() - start) / CLOCKS_PER_SEC;
    }
    return spent;
}

/* One structure built into s (ACCEL_KD, ACCEL_BVH or ACCEL_GRID); 0 when
 * out of memory. */
static int build_one(Scene *s, int which)
{
    s->accel = which;
    if (which == ACCEL_BVH) return (s->bvh = bvh_build(nobj(s), &s->prims, BVH_SAH)) != NULL;
    if (which == ACCEL_GRID) return (s->grid = grid_build(nobj(s), &s->prims)) != NULL;
    return (s->kd = kd_build(nobj(s), &s->prims)) != NULL;
}

/* auto: each structure is built and renders the probe; the one whose build
 * plus the probe's time scaled to every pixel of the image is least is
 * kept, the others freed: the time to image at one sample per pixel,
 * estimated on the scene itself rather than by a rule on its object count.
 * The BVH goes first (quickest to build); a probe stops once it has cost
 * more than the best so far.  The kd-tree builds 2.6 to 8 times slower than
 * the BVH (SPD scenes and a 100k-triangle sphere), so it is tried only when
 * 8 times the BVH's build is under a twentieth of the BVH's estimate: the
 * trial then costs at most 5%, and the kd-tree has room to win back its
 * build.  The probe itself costs 1/256 of a 512x512 image per structure. */
#define KD_BUILD_RATIO 8.0
static int choose_accel(Scene *s)
{
    static const int which[3] = { ACCEL_BVH, ACCEL_GRID, ACCEL_KD };
    double best = HUGE_VAL, cost, built = 0, scale = (double)s->w * s->h / (PROBE * PROBE);
    int k, pick = 0;
    for (k = 0; k < 3; k++) {
        clock_t start = clock();
        if (which[k] == ACCEL_KD && KD_BUILD_RATIO * built > 0.05 * best) break;
        if (!build_one(s, which[k])) return 0;
        cost = (double)(clock() - start) / CLOCKS_PER_SEC;
        if (k == 0) built = cost;      /* the BVH's build */
        cost += scale * probe(s, (best - cost) / scale);
        if (cost < best) best = cost, pick = k;
    }
    for (k = 0; k < 3; k++) {
        if (k == pick) continue;
        if (which[k] == ACCEL_KD && s->kd) kd_free(s->kd), s->kd = NULL;
        if (which[k] == ACCEL_BVH) bvh_free(s->bvh), s->bvh = NULL;
        if (which[k] == ACCEL_GRID) grid_free(s->grid), s->grid = NULL;
    }
    s->accel = which[pick];
    return 1;
}

/* The structure that answers nearest_hit and any_hit, as --accel says: the
 * kd-tree, the BVH (its SAH build), the grid, none (every ray tests every
 * object), or auto: none below TREE_FROM objects, else the one that
 * choose_accel measures fastest on this scene. */
static int build_accel(Scene *s, const char *accel)
{
    int ok;
    s->prims.bounds = prim_bounds;
    s->prims.clip = prim_clip;
    s->prims.hit = prim_hit;
    s->prims.user = s;
    s->accel = ACCEL_NONE;
    if (!strcmp(accel, "none") || (!strcmp(accel, "auto") && nobj(s) < TREE_FROM)) return 1;
    if (!strcmp(accel, "auto")) ok = choose_accel(s);
    else ok = build_one(s, !strcmp(accel, "bvh") ? ACCEL_BVH : !strcmp(accel, "grid") ? ACCEL_GRID : ACCEL_KD);
    if (!ok) fprintf(stderr, "ray: out of memory for the acceleration structure\n");
    return ok;
}

static void print_stats(const Scene *s, const Counts *st, int spp, double load, double build,
                        double seconds)
{
    unsigned long long rays = st->primary + st->shadow + st->reflected + st->refracted;
    fprintf(stderr, "scene      %d spheres, %d cones, %d triangles, %d lights; read in %.3f s\n",
            s->nsph, s->ncone, s->ntri, s->nlight, load);
    fprintf(stderr, "image      %dx%d, %d spp, depth %d, %d thread%s\n", s->w, s->h, spp, s->depth,
            st->threads, st->threads == 1 ? "" : "s");
    if (s->accel == ACCEL_KD) {
        kd_info k;
        kd_describe(s->kd, &k);
        fprintf(stderr, "kd-tree    %ld nodes, %ld leaves (%ld empty), depth %ld,"
                " %.2f objects per leaf,\n"
                "           %.1f MB, SAH cost %.2f, built in %.3f s\n",
                k.nodes, k.leaves, k.empty_leaves, k.max_depth, k.prims_per_leaf,
                k.bytes / 1e6, k.sah_cost, build);
    } else if (s->accel == ACCEL_BVH) {
        bvh_info b;
        bvh_describe(s->bvh, &b);
        fprintf(stderr, "bvh        %ld nodes, %ld leaves, depth %ld, %.2f objects per leaf,\n"
                "           %lu bytes, SAH cost %.2f, built in %.3f s\n",
                b.nodes, b.leaves, b.max_depth, b.prims_per_leaf, (unsigned long)b.bytes,
                b.sah_cost, build);
    } else if (s->accel == ACCEL_GRID) {
        grid_info g;
        grid_describe(s->grid, &g);
        fprintf(stderr, "grid       %dx%dx%d cells (%ld empty), %.2f references per object,\n"
                "           %lu bytes, built in %.3f s\n", g.res[0], g.res[1], g.res[2],
                g.empty_cells, nobj(s) ? (double)g.prim_refs / nobj(s) : 0.0,
                (unsigned long)g.bytes, build);
    } else
        fprintf(stderr, "accel      none: every ray tests every object\n");
    fprintf(stderr, "rays       %llu: %llu primary, %llu shadow, %llu reflected, %llu refracted\n",
            rays, st->primary, st->shadow, st->reflected, st->refracted);
    fprintf(stderr, "hits       %llu (%.1f%% of the rays that ask for the nearest hit)\n", st->hits,
            st->nearest ? 100.0 * st->hits / (double)st->nearest : 0.0);
    fprintf(stderr, "per ray    %.2f intersection tests, %.2f tree steps\n",
            st->queries ? (double)st->tests / st->queries : 0.0,
            st->queries ? (double)st->steps / st->queries : 0.0);
    fprintf(stderr, "time       %.3f s, %.2f Mrays/s\n", seconds,
            seconds > 0 ? rays / seconds * 1e-6 : 0.0);
}

static void free_scene(Scene *s)
{
    if (s->kd) kd_free(s->kd);
    if (s->bvh) bvh_free(s->bvh);
    if (s->grid) grid_free(s->grid);
    free(s->mat); free(s->sph); free(s->cone); free(s->tri);
    free(s->vert); free(s->norm); free(s->light);
}

/* -s WxH onto the scene; 0 with a message when it is not such a size. */
static int set_size(Scene *s, const char *size)
{
    char *x, *end = NULL;
    long fw = strtol(size, &x, 10), fh = *x == 'x' ? strtol(x + 1, &end, 10) : 0;
    if (x == size || *x != 'x' || end == x + 1 || *end) {
        fprintf(stderr, "ray: -s needs WxH, like 640x480, not %s\n", size);
        return 0;
    }
    if (!check_size((double)fw, (double)fh, &s->w, &s->h)) {
        fprintf(stderr, "ray: -s %s: " SIZE_RULE "\n", size);
        return 0;
    }
    return 1;
}

int main(int argc, char **argv)
{
    Scene s;
    Options o = { 1, 0, 0 };
    Counts st;
    Output out;
    const char *scene = NULL, *size = NULL, *accel = NULL, *name = NULL;
    char *auto_name = NULL;
    int i, depth = 0, plain = 0, stats = 0, ok;
    unsigned char *img;
    double t0, load, build;

    for (i = 1; i < argc; i++) {
        const char *a = argv[i], *next = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) { usage(stdout); return 0; }
        else if (!strcmp(a, "-o") && next) name = argv[++i];
        else if (!strcmp(a, "-s") && next) size = argv[++i];
        else if (!strcmp(a, "-n")) { o.spp = int_arg(a, next, 1 << 20); i++; }
        else if (!strcmp(a, "-d")) { depth = int_arg(a, next, 64); i++; }
        else if (!strcmp(a, "-t")) { o.threads = int_arg(a, next, 4096); i++; }
        else if (!strcmp(a, "--p3")) plain = 1;
        else if (!strcmp(a, "--stats")) stats = 1;
        else if (!strcmp(a, "--accel") && next && accel_name(next))
            accel = argv[++i];
        else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "ray: unknown option, or a bad or missing value: %s\n", a);
            usage(stderr);
            return 2;
        } else if (scene) {
            fprintf(stderr, "ray: one scene only (%s and %s)\n", scene, a);
            return 2;
        }
        else scene = a;
    }
    if (!scene) { usage(stderr); return 2; }
    load = now();
    ok = load_scene(&s, scene) && (!size || set_size(&s, size));
    load = now() - load;
    if (ok && nobj(&s) == 0) fprintf(stderr, "%s: warning: the scene has no objects\n", scene);
    if (depth) s.depth = depth;
    if (!accel) accel = s.accel_line ? s.accel_line : "auto";
    build = now();
    ok = ok && build_accel(&s, accel);
    build = now() - build;
    if (ok && !name) name = auto_name = default_output(scene);
    if (!ok || !open_output(&out, name)) { free_scene(&s); free(auto_name); return 1; }

    img = malloc((size_t)s.w * s.h * 3);
    if (!img) {
        fprintf(stderr, "ray: out of memory for a %dx%d image\n", s.w, s.h);
        discard_output(&out);
        free_scene(&s); free(auto_name);
        return 1;
    }
    o.progress = stderr_is_terminal();
    memset(&st, 0, sizeof st);
    t0 = now();
    render(&s, &o, img, &st);
    t0 = now() - t0;
    ok = write_ppm(&out, img, s.w, s.h, plain);
    if (stats) print_stats(&s, &st, o.spp, load, build, t0);
    free(img);
    free(auto_name);
    free_scene(&s);
    return ok ? 0 : 1;
}

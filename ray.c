/* ray.c - the lecture "Ray Tracing + Global Illumination" as one C file:
 * Whitted's recursive ray tracer and Kajiya's path tracer side by side,
 * spheres, cones and triangles, and the structures that find hits (kdtree.c,
 * bvh.c, grid.c).
 *
 *     make && ./ray -s 640x480 -n 4 scenes/whitted.sph      (writes whitted.ppm)
 *     ./ray scenes/cornell.sph                              (path traced)
 *
 * Usage: ./ray [options] SCENE
 *     -o FILE     output image: PPM, PNG (.png) or PFM floats (.pfm)
 *                 (default: SCENE's base name with .ppm; - = stdout)
 *     -s WxH      image size (default: the scene's, else 512x512)
 *     -n N        samples per pixel (default: the scene's, else 1)
 *     -d N        Whitted: recursion depth, 1 = primary rays only (default:
 *                 scene's, else 5); path tracing: the rays of a path at most
 *     -t N        threads (default: every core, when built with OpenMP)
 *     --pt, --whitted   path tracing or Whitted (default: the scene's, else Whitted)
 *     --estimator E     bsdf, nee or mis (default), for the path tracer
 *     --no-roulette, --seed N     for the path tracer
 *     --gamma     the sRGB curve on Whitted's output (path tracing always has it)
 *     --p3        plain-text PPM (P3) instead of binary (P6)
 *     --accel A   kd (kdtree.c), bvh (bvh.c), grid (grid.c), none (test every
 *                 object), or auto (default: the scene's `accel`, else from 8
 *                 objects on the structure a short probe render finds fastest)
 *     --view V    steps, normal or depth: what a pixel's ray meets, as a picture
 *     --stats     print rays by kind, hits, the tree and time on stderr
 *     --help
 * SCENE is the sphere format (README.md), or an NFF file (Eric Haines'
 * Neutral File Format, as the SPD benchmark scenes come) when it ends .nff.
 *
 * HOW TO READ IT.  The lecture comes first, in the order a ray meets it:
 * the types, the vectors, a table of contents (the prototypes), then
 * "for each pixel", the samples (the points of a pixel, random numbers,
 * and the warps that turn them into points and directions, each with its
 * pdf), RayTrace(R) (Whitted), L = Le + integral f L cos (Kajiya), finding
 * hits, and the primitives.  After the line THE PLUMBING come threads,
 * scene files, output and main(); a student can stop reading there.
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
 * and the rendering equation (Kajiya 1986), for the path tracer:
 *
 *     pixel = mean of L over random points      pixel_radiance(), sample_radiance()
 *     L(x, wo) = Le(x, wo)                      radiance(): emitted()
 *              + integral of f Li cos               sample_light() (direct), and
 *                                                   sample_bsdf(): f cos / pdf times
 *                                                   Li = radiance() of the next point
 *
 * One primary ray of Whitted's, from main() to its pixel's byte.  Each function is
 * defined below the one before it, except the eight marked ^, which a
 * reader finds further up:
 *
 *       main()            reads the scene, builds the tree          (plumbing)
 *     ^ render()          shares the rows out among threads         (plumbing)
 *     ^ render_row()      for each pixel of a row                   for each pixel
 *       pixel_color()     averages the pixel's samples
 *       sample_offset()   where sample k lies in the pixel          samples
 *     ^ camera_ray()      the ray R from the eye through it         for each pixel
 *       trace()           RayTrace(R)                               RayTrace(R)
 *       nearest_hit()     the nearest hit                           finding hits
 *       query()           the record the tree hands back
 *       find_nearest()    asks the structure (kd_nearest, bvh_nearest or grid_nearest), or every object
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
#include <stdint.h>
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
    real hither;              /* near clip: nothing nearer than this plane is seen */
} Camera;

/* A light as the path tracer samples it (sample_light): a point light, an
 * emitting sphere or triangle (object obj), or the sky: the background seen
 * as a uniform radiance from every direction. */
enum { POINT_LIGHT, SPHERE_LIGHT, TRIANGLE_LIGHT, SKY_LIGHT };
typedef struct {
    int type, obj;
    vec pos, intensity;       /* a point light's place and intensity I (radiance: I / d^2) */
} Emitter;

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
    int integrator;           /* WHITTED or PATH */
    int view;                 /* --view: VIEW_STEPS, VIEW_NORMAL, VIEW_DEPTH, or 0 */
    real far;                 /* --view depth: the farthest point of the scene from the eye */
    int spp;                  /* samples per pixel the scene asks for (0: none said) */
    int estimator;            /* the path tracer's: BSDF_ONLY, NEE or MIS */
    int roulette;             /* 1: Russian roulette ends paths */
    int tir_reflect;          /* Whitted: past the critical angle kt goes to the mirror */
    int max_rays;             /* rays on a path at most (-d); 0: no bound but roulette */
    unsigned seed;            /* --seed: which noise */
    Emitter *emit;  int nemit;  /* the path tracer's lights */
    int sky;                  /* the sky's light, or -1 */
    real *emit_cdf;           /* emit_cdf[i]: chance of choosing one of lights 0..i */
    int *emitter;             /* emitter[object]: its light, or -1 */
    char warning[256];        /* said once when the path tracer starts, if set */
    char whitted_warning[256];  /* the same for Whitted's */
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

/* Whitted's recursive ray tracing, or Kajiya's path tracing; and the path
 * tracer's three estimators of the light at a point: by sampling the BSDF
 * only, by next-event estimation, or by both weighed by MIS. */
enum { WHITTED, PATH };
enum { VIEW_STEPS = 1, VIEW_NORMAL, VIEW_DEPTH };
enum { BSDF_ONLY, NEE, MIS };

/* Objects are numbered spheres first, then cones, then triangles. */
enum { SPHERE, CONE, TRIANGLE };

static int nobj(const Scene *s) { return s->nsph + s->ncone + s->ntri; }

/* A ray: origin o, direction d, and skip, an object it cannot hit (or -1).
 * A ray leaving a flat triangle, or a sphere outward, never meets that
 * surface again, yet it starts in the tree's cells that list it: skip spares
 * that test.  The tree leaves skip out itself (kd_nearest's skip); the loop
 * over every object checks it in hit_object.  tmin is 0 but for a camera
 * with a near clip (hither): hits at t <= tmin do not count. */
typedef struct { vec o, d; real tmin; int skip; } Ray;

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
    unsigned long long bounced, discarded;      /* path tracer: BSDF-sampled rays; bad samples */
    unsigned long long cut;                     /* Whitted: rays past a primary ray's budget */
    int threads;                                /* how many threads rendered */
} Counts;

/* A thread's working state, handed down every call that traces a ray, as
 * smallpt hands down its per-row seed; never a global.  It holds the
 * thread's counts, the shadow cache of any_hit() (the last blocker of each
 * of the first SHADOW_SLOTS lights; lights further on share the slots,
 * which costs cache hits but never changes an answer), and where the path
 * tracer's random numbers stand. */
#define SHADOW_SLOTS 8
#define RAY_BUDGET 1024         /* reflected and refracted rays a primary ray may spawn */
typedef struct {
    Counts count;
    int blocker[SHADOW_SLOTS];  /* light i's last blocker, or -1, in slot i % SHADOW_SLOTS */
    unsigned long long key;     /* the path tracer's random numbers: which sample, */
    int bounce;                 /* and which bounce its path is at (see random01) */
    int budget;                 /* Whitted: secondary rays the primary ray may still spawn */
} Worker;

/* The image being made: bytes (for PPM), or floats (for PFM), row by row
 * from the top-left, three channels a pixel. */
typedef struct {
    int w, h;
    unsigned char *bytes;
    float *floats;
    int srgb;                 /* bytes: through the sRGB curve */
} Image;

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
static void render_row(const Scene *s, int j, int spp, Image *img, Worker *wk);
static vec pixel_color(const Scene *s, int i, int j, int spp, Worker *wk);
static Ray camera_ray(const Camera *c, int w, int h, real x, real y);
static void put_pixel(Image *img, int i, int j, vec c);
static unsigned char to_byte(real v);
static real srgb(real v);
static vec pixel_view(const Scene *s, int i, int j, Worker *wk);   /* --view, in the plumbing */

/* samples: the points of a pixel, random numbers, the warps and their pdfs */
static void sample_offset(int k, real anchor, real *dx, real *dy);
static void start_sample(Worker *wk, const Scene *s, int i, int j, int k);
static real random01(const Worker *wk, unsigned dim);
static real bounce_random(const Worker *wk, int slot);
static vec from_local(vec n, vec l);
static vec cosine_hemisphere(real u1, real u2);
static real cosine_hemisphere_pdf(real cos_theta);
static vec phong_lobe(real shine, real u1, real u2);
static real phong_lobe_pdf(real shine, real cos_alpha);
static vec uniform_disc(real u1, real u2);
static real uniform_disc_pdf(void);
static vec sphere_cap(real cap, real u1, real u2);
static real sphere_cap_pdf(real cap);
static vec uniform_triangle(real u1, real u2);
static real uniform_triangle_pdf(real area);

/* RayTrace(R): Whitted's recursive ray tracing */
static vec trace(const Scene *s, Ray r, int depth, real weight, Worker *wk);
static vec shade(const Scene *s, Ray r, const Hit *h, int depth, real weight, Worker *wk);
static int shadow_ray(const Scene *s, const Hit *h, vec n, const Light *l, real *e,
                      vec *to_light, Worker *wk);
static int worth_tracing(real k, real weight, int depth, Worker *wk);
static vec reflect(vec d, vec n, real cosi);
static int refract(vec d, vec n, real cosi, real eta, vec *t);

/* L = Le + integral f L cos: Kajiya's path tracing */
typedef struct Path Path;
typedef struct Bsdf Bsdf;
static vec pixel_radiance(const Scene *s, int i, int j, int spp, Worker *wk);
static vec sample_radiance(const Scene *s, int i, int j, int k, Worker *wk);
static vec radiance(const Scene *s, Ray r, const Path *path, Worker *wk);
static int survives(const Scene *s, int rays, vec *beta, vec *f_cos, Worker *wk);
static vec emitted(const Scene *s, const Hit *h, vec wo, const Path *path);
static vec sky(const Scene *s, vec d, const Path *path);
static real power_heuristic(real a, real b);
static vec sample_light(const Scene *s, const Hit *h, const Bsdf *b, vec wo, Worker *wk);
static int choose_light(const Scene *s, real u);
static real light_choice(const Scene *s, int l);
static int sample_emitter(const Scene *s, int l, vec x, vec n, Worker *wk, vec *wi,
                          real *dist, vec *Le, real *pdf);
static real light_pdf(const Scene *s, int l, vec x, vec n, vec y, vec ny);
static int front_emits(const Scene *s, int i, vec ng, vec wo);
static void bsdf_at(const Scene *s, const Hit *h, vec wo, Bsdf *b);
static vec bsdf_eval(const Bsdf *b, vec wo, vec wi);
static real bsdf_pdf(const Bsdf *b, vec wo, vec wi);
static int sample_bsdf(const Bsdf *b, vec wo, Worker *wk, vec *wi, vec *f_cos, real *pdf);
static int sample_glass(const Bsdf *b, vec wo, real u, vec *wi, vec *f_cos);
static real fresnel(real cosi, real eta);

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
static real sphere_sample(const Sphere *sp, vec x, real u, real v, vec *wi, real *dist);
static real sphere_pdf(const Sphere *sp, vec x, vec y);
static real hit_cone(const Cone *c, const Ray *r, real tmin);
static void cone_surface(const Cone *c, const Ray *r, real t, Hit *h);
static void cone_box(const Cone *c, double lo[3], double hi[3]);
static int hit_triangle(const Scene *s, const Triangle *tr, const Ray *r, real tmax,
                        real *t, real *u, real *v);
static void triangle_surface(const Scene *s, const Triangle *tr, real u, real v, Hit *h);
static void triangle_box(const Scene *s, const Triangle *tr, double lo[3], double hi[3]);
static int triangle_clip(const Scene *s, const Triangle *tr, const double blo[3],
                         const double bhi[3], double lo[3], double hi[3]);
static void triangle_sample(const Triangle *tr, real u, real v, vec *y, vec *ny);
static real triangle_pdf(const Triangle *tr, real dist, real cosy);

/* ---------------------------------------------------------- for each pixel */

/* The lecture's "for each pixel", for one row of the image (rows are what
 * the threads share out: see render()).  Whitted's colour, or with the path
 * tracer the radiance. */
static void render_row(const Scene *s, int j, int spp, Image *img, Worker *wk)
{
    int i;
    for (i = 0; i < s->w; i++)
        put_pixel(img, i, j, s->view ? pixel_view(s, i, j, wk)      /* --view: see the plumbing */
                             : s->integrator == PATH ? pixel_radiance(s, i, j, spp, wk)
                             : pixel_color(s, i, j, spp, wk));
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
        wk->budget = RAY_BUDGET;
        sum = add(sum, trace(s, camera_ray(&s->cam, s->w, s->h, i + dx, j + dy), s->depth, 1, wk));
    }
    return scale((real)1 / spp, sum);
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
    r.tmin = c->hither > 0 ? c->hither / dot(r.d, c->fwd) : 0;
    return r;
}

/* The pixel into the image: as floats (for PFM, the radiance itself), or
 * as bytes, through the sRGB curve where the image asks for it. */
static void put_pixel(Image *img, int i, int j, vec c)
{
    size_t at = 3 * ((size_t)j * img->w + i);
    if (img->floats) {
        img->floats[at] = (float)c.x;
        img->floats[at + 1] = (float)c.y;
        img->floats[at + 2] = (float)c.z;
        return;
    }
    if (img->srgb) c = v3(srgb(c.x), srgb(c.y), srgb(c.z));
    img->bytes[at] = to_byte(c.x);
    img->bytes[at + 1] = to_byte(c.y);
    img->bytes[at + 2] = to_byte(c.z);
}

/* Colour in 0..1 to a byte: x255 and round to nearest (as minray's %.0f
 * does), clamped; NaN becomes 0 so that no pixel is ever undefined. */
static unsigned char to_byte(real v)
{
    double x = rint((double)v * 255);
    if (!(x > 0)) return 0;
    return x > 255 ? 255 : (unsigned char)x;
}

/* Linear light to the sRGB transfer curve (IEC 61966-2-1), which image
 * viewers assume a PPM or PNG holds: a straight line near black, then a
 * 1/2.4 power.  A path-traced image always gets it; Whitted's only with
 * --gamma, so that the card's bytes stay the card's. */
static real srgb(real v)
{
    return v <= (real)0.0031308 ? 12.92 * v : 1.055 * pow(v, 1 / 2.4) - 0.055;
}

/* ----------------------------------------------------------------- samples */

/* Where the numbers come from: the points of a pixel (the R2 pattern), the
 * path tracer's random numbers, and the warps that turn two uniform numbers
 * into a point or a direction with a known density.  Each warp stands
 * beside its pdf, named alike (cosine_hemisphere, cosine_hemisphere_pdf),
 * as Nori's warp.h pairs them (Jakob's educational renderer), so that
 * whoever divides by a pdf calls the function that says it, and a test can
 * hold each warp against its pdf (tests/test_pt.c, "warp" checks). */

/* Sample k of n inside a pixel: the R2 low-discrepancy sequence (Roberts,
 * "The unreasonable effectiveness of quasirandom sequences", 2018), which
 * spreads any number of points evenly and needs no random numbers, so every
 * run gives the same bytes.  Sample 0 lies on the anchor: the pixel's centre,
 * or with `pixel corner` its top-left corner, where minray aims. */
static void sample_offset(int k, real anchor, real *dx, real *dy)
{
    const double a1 = 0.7548776662466927, a2 = 0.5698402909980532; /* 1/g, 1/g^2; g^3 = g + 1 */
    *dx = (real)(anchor + (k * a1 - floor(k * a1)));   /* the fraction: exact */
    *dy = (real)(anchor + (k * a2 - floor(k * a2)));
    if (*dx >= anchor + 0.5) *dx -= 1;          /* wrap into [anchor-1/2, anchor+1/2) */
    if (*dy >= anchor + 0.5) *dy -= 1;
}

/* Random numbers without a generator's state: the number in dimension d
 * of sample k of pixel p is a hash of (seed, p, k, d).  So a pixel's noise
 * does not depend on which thread computes it, nor on the order, and any
 * part of an image can be rendered apart and put together exactly.
 * (smallpt seeds a generator per row with y^3 cut to 16 bits, which gives
 * rows 0, 64, 128, ... the same noise.)  The hash is the finaliser of
 * SplitMix64 (Steele, Lea and Flood, "Fast splittable pseudorandom number
 * generators", OOPSLA 2014), applied once per key and once per number. */
static unsigned long long mix64(unsigned long long z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/* The dimensions of a sample.  A path is one point of a unit cube of many
 * dimensions, each coordinate a number some choice along it is made from
 * (Keller, "Quasi-Monte Carlo image synthesis in a nutshell", 2013).  Here
 * every choice has its own named dimension, the same in every path, rather
 * than taking the next number drawn: so a choice that is made in one path
 * and not in another (a light sampled by nee and not by bsdf, roulette
 * only from ROULETTE_FROM rays on), or a lens or a time sampled one day,
 * leaves every other number of every path where it was, and an image's
 * noise changes only where the change itself reaches.
 *
 *     dimension             what it chooses                   drawn by
 *     DIM_PIXEL_X, _Y       the pixel's shift of its samples  sample_radiance, once a
 *                           (Cranley-Patterson)                 pixel (as its sample -1)
 *     DIM_LENS_U, _V        a point of the lens               reserved: no lens yet
 *     DIM_TIME              an instant of the shutter         reserved: no motion yet
 *   and from DIM_BOUNCE on, a block of BOUNCE_DIMS for each bounce b (0 at the
 *   first hit), slot k of it dimension DIM_BOUNCE + b * BOUNCE_DIMS + k:
 *       LIGHT_CHOICE        which light                       sample_light
 *       LIGHT_U, LIGHT_V    the point on it                   sample_emitter
 *       LOBE                which lobe of the BSDF, and       sample_bsdf
 *                           glass's reflect or refract          (see sample_glass)
 *       DIRECTION_U, _V     the direction within the lobe     sample_bsdf
 *       ROULETTE            whether the path goes on          survives
 *       SPARE               none yet: room for one more
 *
 * The lens and time dimensions are kept now, unused, so that a thin lens
 * or motion blur added later takes its numbers from them and moves no
 * other path's. */
enum { DIM_PIXEL_X, DIM_PIXEL_Y, DIM_LENS_U, DIM_LENS_V, DIM_TIME, DIM_BOUNCE };
enum { LIGHT_CHOICE, LIGHT_U, LIGHT_V, LOBE, DIRECTION_U, DIRECTION_V, ROULETTE, SPARE,
       BOUNCE_DIMS };

/* The sample the numbers that follow belong to: sample k of pixel (i, j),
 * its path at the first hit. */
static void start_sample(Worker *wk, const Scene *s, int i, int j, int k)
{
    unsigned long long pixel = (unsigned long long)j * (unsigned)s->w + (unsigned)i;
    wk->key = mix64(mix64(mix64(s->seed + 0x9e3779b97f4a7c15ULL) ^ pixel) ^ (unsigned)k);
    wk->bounce = 0;
}

/* The sample's number in dimension dim, uniform in [0, 1). */
static real random01(const Worker *wk, unsigned dim)
{
    unsigned long long h = mix64(wk->key + 0x9e3779b97f4a7c15ULL * (dim + 1ULL));
    real u = (real)((h >> 11) * (1.0 / 9007199254740992.0));
    return u < 1 ? u : 1 - REAL_EPS;      /* a float may round up to 1 */
}

/* The number in `slot` of the block of the bounce the path is at. */
static real bounce_random(const Worker *wk, int slot)
{
    return random01(wk, DIM_BOUNCE + (unsigned)wk->bounce * BOUNCE_DIMS + (unsigned)slot);
}

/* The warps below work in a local frame about the z axis; this turns a
 * local vector into the world's: l.x t1 + l.y t2 + l.z n for an
 * orthonormal t1, t2 made from the unit vector n (Duff et al., "Building
 * an Orthonormal Basis, Revisited", JCGT 6(1), 2017). */
static vec from_local(vec n, vec l)
{
    real sign = n.z >= 0 ? 1 : -1, a = -1 / (sign + n.z), b = n.x * n.y * a;
    vec t1 = v3(1 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    vec t2 = v3(b, sign + n.y * n.y * a, -n.y);
    return add(add(scale(l.x, t1), scale(l.y, t2)), scale(l.z, n));
}

/* A direction of the hemisphere about z with pdf cos(theta)/pi, the
 * Lambertian lobe, by Malley's method: a uniform point of the unit disc
 * lifted straight up onto the hemisphere.  The disc's area element is the
 * solid angle's times cos(theta), the disc being the hemisphere seen from
 * above, so the pdf the point had on the disc, 1/pi, becomes cos(theta)/pi. */
static vec cosine_hemisphere(real u1, real u2)
{
    vec d = uniform_disc(u1, u2);
    return v3(d.x, d.y, sqrt(fmax(0, 1 - d.x * d.x - d.y * d.y)));
}

/* Its pdf in solid angle: cos(theta)/pi above the horizon, 0 below. */
static real cosine_hemisphere_pdf(real cos_theta)
{
    return cos_theta > 0 ? uniform_disc_pdf() * cos_theta : 0;
}

/* A direction about z with pdf (shine+1)/(2 pi) cos^shine(alpha), alpha
 * its angle to z: the lobe of the modified Phong BRDF (Lafortune and
 * Willems, "Using the modified Phong reflectance model for physically based
 * rendering", 1994), by inverting the cdf 1 - cos^(shine+1) of alpha. */
static vec phong_lobe(real shine, real u1, real u2)
{
    real c = pow(u1, 1 / (shine + 1)), s = sqrt(fmax(0, 1 - c * c)), phi = 2 * (real)PI * u2;
    return v3(s * cos(phi), s * sin(phi), c);
}

/* Its pdf in solid angle, for cos_alpha the cosine of the angle to z. */
static real phong_lobe_pdf(real shine, real cos_alpha)
{
    return cos_alpha > 0 ? (shine + 1) / (2 * (real)PI) * pow(cos_alpha, shine) : 0;
}

/* A uniform point (x, y, 0) of the unit disc, for cosine_hemisphere and
 * one day a thin lens: the concentric map of Shirley and Chiu ("A Low Distortion Map Between Disk
 * and Square", JGT 2(3), 1997), which sends the square's concentric
 * squares to the disc's concentric circles, so that points spread evenly
 * over the square stay spread evenly over the disc (the polar map
 * r = sqrt(u1) squeezes and stretches them). */
static vec uniform_disc(real u1, real u2)
{
    real a = 2 * u1 - 1, b = 2 * u2 - 1, r, phi;
    if (a == 0 && b == 0) return v3(0, 0, 0);
    if (fabs(a) > fabs(b)) {                    /* the wedges left and right */
        r = a;
        phi = (real)PI / 4 * (b / a);
    } else {                                    /* top and bottom */
        r = b;
        phi = (real)PI / 2 - (real)PI / 4 * (a / b);
    }
    return v3(r * cos(phi), r * sin(phi), 0);
}

/* Its pdf in area: 1/pi on the unit disc. */
static real uniform_disc_pdf(void)
{
    return 1 / (real)PI;
}

/* A uniform direction of the cone about z whose cap of the unit sphere has
 * height cap = 1 - cos(theta_max) (2: the whole sphere).  Archimedes: the
 * area of a sphere between two heights is proportional to their
 * difference, so cos(theta) is uniform in [1 - cap, 1].  The cone comes
 * as its cap's height, not as cos(theta_max): a far, small sphere light's
 * cone has a cap a caller can compute without cancelling (sphere_sample),
 * where cos(theta_max) would round to 1. */
static vec sphere_cap(real cap, real u1, real u2)
{
    real c = 1 - u1 * cap, s = sqrt(fmax(0, 1 - c * c)), phi = 2 * (real)PI * u2;
    return v3(s * cos(phi), s * sin(phi), c);
}

/* Its pdf in solid angle: one over the cap's area 2 pi cap. */
static real sphere_cap_pdf(real cap)
{
    return 1 / (2 * (real)PI * cap);
}

/* A uniform point of a triangle, as its barycentrics (b0, b1, b2), the
 * weights of its three corners (Turk, "Generating random points in
 * triangles", Graphics Gems, 1990): sqrt(u1) picks the line parallel to
 * the edge opposite corner 0, whose length grows with that distance, and
 * u2 a point along it. */
static vec uniform_triangle(real u1, real u2)
{
    real su = sqrt(u1);
    return v3(1 - su, su * (1 - u2), su * u2);
}

/* Its pdf in area, for a triangle of that area. */
static real uniform_triangle_pdf(real area)
{
    return 1 / area;
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
    real cosi = -dot(r.d, n), eta = 1 / m->ir, e, kr;
    int i, tir;
    if (dot(r.d, h->ng) > 0) { n = scale(-1, n); cosi = -cosi; eta = m->ir; } /* inside */
    mirror = reflect(r.d, n, cosi);
    /* Past the critical angle no refracted ray exists.  The card then loses
     * the kt share (its glass goes black there); the SPD's rule, and with
     * `tir reflect` a sphere file's, sends it into the reflected ray. */
    tir = m->kt > 0 && !refract(r.d, n, cosi, eta, &t);
    kr = tir && s->tir_reflect ? m->ks + m->kt : m->ks;
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
    if (worth_tracing(kr, weight, depth, wk)) {
        wk->count.reflected++;
        c = comb(kr, trace(s, spawn(s, h, mirror), depth - 1, kr * weight, wk), c);
    }
    if (!tir && worth_tracing(m->kt, weight, depth, wk)) {
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
 * it, minray's scene and depth 3 never come near the limit.
 * The weight bounds one path, not how many there are: where ks + kt is near
 * 2 (glass that is also a mirror) every ray still spawns two, 2^depth in
 * all.  So a primary ray's tree also has a budget, RAY_BUDGET reflected and
 * refracted rays, spent depth first; what it cannot pay for is not traced
 * and is counted (--stats).  Ordinary scenes never reach it: depth 5, the
 * SPD's, allows at most 30. */
#define MIN_WEIGHT (1.0 / 512)
static int worth_tracing(real k, real weight, int depth, Worker *wk)
{
    if (!(k > 0 && depth > 1 && k * weight >= MIN_WEIGHT)) return 0;
    if (wk->budget > 0) { wk->budget--; return 1; }
    wk->count.cut++;
    return 0;
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

/* ------------------------------------------ L = Le + integral f L cos: Kajiya */

/* The lecture's second half: the rendering equation (Kajiya, "The Rendering
 * Equation", SIGGRAPH 1986).  The radiance leaving x towards wo is what x
 * emits plus what it reflects of the radiance arriving from every wi:
 *
 *     L(x, wo) = Le(x, wo) + integral over wi of f(x, wi, wo) Li(x, wi) cos(theta_i)
 *
 * and Li(x, wi) is itself L at the nearest point seen from x along wi.
 * Monte Carlo integration (Kalos and Whitlock 1986) estimates the integral
 * from one random direction wi drawn with probability density pdf(wi):
 *
 *     integral ~= f(x, wi, wo) Li(x, wi) cos(theta_i) / pdf(wi)
 *
 * which is unbiased, and averaging many such estimates converges to L.
 * Following the recursion gives one random path per sample: path tracing.
 * Three ways to estimate the integral, chosen by --estimator:
 *
 *  1. BSDF sampling only (smallpt): wi drawn from the BSDF; light counts
 *     only when a path happens to hit an emitter (never a point light).
 *  2. Next-event estimation (NEE): at each bounce one shadow ray to a point
 *     chosen on a light gives the direct light (sample_light); the BSDF's
 *     direction then gathers only the indirect light.
 *  3. Both, weighed by multiple importance sampling with the power
 *     heuristic (Veach and Guibas, "Optimally Combining Sampling Techniques
 *     for Monte Carlo Rendering", SIGGRAPH 1995): each estimate counts most
 *     where its own pdf is the larger.  The default.
 *
 * Paths end by Russian roulette (Arvo and Kirk, "Particle Transport and
 * Image Synthesis", SIGGRAPH 1990): after ROULETTE_FROM rays a path goes on
 * with a probability q and its throughput is divided by q, so the mean is
 * unchanged; or at -d rays. */
#define ROULETTE_FROM 4
#define MAX_PATH 1024       /* a bound on the recursion, as a guard: with roulette
                             * a path reaches it with odds below 0.95^1000 */

/* What radiance() knows of the path that led to its ray. */
struct Path {
    vec beta;               /* throughput: the share of this ray's radiance in the pixel */
    int rays;               /* rays so far, this one included */
    int counted;            /* 1: a light this ray meets counts in full (a camera ray,
                             * or one from a mirror or glass, which NEE cannot find) */
    real pdf;               /* else: the pdf with which the BSDF chose this ray */
    vec from, n_from;       /* the point it left, and the normal there */
};

/* A BSDF at one hit: the card's weights as lobes.  kd*colour is a
 * Lambertian albedo; ks is an ideal mirror, or, with a Phong exponent
 * (NFF's materials), a glossy lobe; kt is a smooth dielectric of index ir.
 * The weights are scaled down to sum to 1 where they sum to more (the card's
 * glass ball has 1.1).  n and ng face the side wo comes from; eta is the
 * ratio n1/n2 of the indices for a ray going through. */
struct Bsdf {
    vec n, ng;
    vec albedo;             /* Lambertian: f = albedo / pi */
    real glossy, shine;     /* modified Phong: f = glossy (shine+2)/(2 pi) cos^shine(alpha) */
    real mirror;            /* ideal mirror (a delta lobe) */
    real glass, eta;        /* smooth dielectric with Fresnel (delta lobes) */
    real p[4];              /* the chance to sample each lobe: diffuse, glossy, mirror, glass */
};
enum { DIFFUSE_LOBE, GLOSSY_LOBE, MIRROR_LOBE, GLASS_LOBE };

/* The pixel's radiance: the mean of spp paths through random points of
 * it.  A sample that is not finite (from a degenerate scene) is counted
 * and left out, so that no NaN reaches an image. */
static vec pixel_radiance(const Scene *s, int i, int j, int spp, Worker *wk)
{
    vec sum = v3(0, 0, 0), L;
    int k;
    for (k = 0; k < spp; k++) {
        L = sample_radiance(s, i, j, k, wk);
        if (isfinite(L.x) && isfinite(L.y) && isfinite(L.z)) sum = add(sum, L);
        else wk->count.discarded++;
    }
    return scale((real)1 / spp, sum);
}

/* Sample k of pixel (i, j): the radiance along one camera ray through a
 * random point of the pixel.  The points are Whitted's R2 pattern
 * (sample_offset), shifted by the pixel's own random offset and wrapped
 * (Cranley and Patterson, "Randomization of number theoretic methods for
 * multiple integration", SIAM J. Numer. Anal., 1976): each point alone is
 * uniform in the pixel, so the mean is right, and together they cover it
 * evenly, so that an edge in the pixel (the lamp's, in the Cornell box)
 * costs far less noise than independent points would. */
static vec sample_radiance(const Scene *s, int i, int j, int k, Worker *wk)
{
    Path path;
    real dx, dy, sx, sy;
    start_sample(wk, s, i, j, -1);          /* the pixel's shift: no sample's numbers */
    sx = random01(wk, DIM_PIXEL_X);
    sy = random01(wk, DIM_PIXEL_Y);
    sample_offset(k, (real)0.5, &dx, &dy);
    dx += sx;
    dy += sy;
    if (dx >= 1) dx -= 1;
    if (dy >= 1) dy -= 1;
    start_sample(wk, s, i, j, k);
    wk->count.primary++;
    path.beta = v3(1, 1, 1);
    path.rays = 1;
    path.counted = 1;
    return radiance(s, camera_ray(&s->cam, s->w, s->h, i + dx, j + dy), &path, wk);
}

/* L(x, wo) = Le(x, wo) + integral f Li cos, for the ray r arriving at x:
 * the radiance it carries back, estimated by one random path. */
static vec radiance(const Scene *s, Ray r, const Path *path, Worker *wk)
{
    Hit h;
    Bsdf b;
    Path next;
    vec wo = scale(-1, r.d), Le, direct, f_cos, Li;
    real pdf;
    int lobe;
    if (!nearest_hit(s, r, &h, wk)) return sky(s, r.d, path);
    Le = emitted(s, &h, wo, path);
    if (path->rays == s->max_rays || path->rays == MAX_PATH) return Le;
    bsdf_at(s, &h, wo, &b);
    /* this hit's block of random numbers; the next hit sets its own, and
     * nothing below draws after radiance() of the next ray returns */
    wk->bounce = path->rays - 1;
    direct = s->estimator == BSDF_ONLY ? v3(0, 0, 0) : sample_light(s, &h, &b, wo, wk);
    lobe = sample_bsdf(&b, wo, wk, &next.from, &f_cos, &pdf);   /* next.from: wi */
    if (lobe < 0) return add(Le, direct);
    next.beta = mul(path->beta, f_cos);
    if (!survives(s, path->rays, &next.beta, &f_cos, wk)) return add(Le, direct);
    wk->count.bounced++;
    next.rays = path->rays + 1;
    next.counted = lobe == MIRROR_LOBE || lobe == GLASS_LOBE;
    next.pdf = pdf;
    r = spawn(s, &h, next.from);
    next.from = h.p;
    next.n_from = b.n;
    Li = radiance(s, r, &next, wk);
    return add(add(Le, direct), mul(f_cos, Li));
}

/* Russian roulette: from ROULETTE_FROM rays on, the path goes on with the
 * chance q that its throughput beta suggests (at most 0.95, so that a hall
 * of mirrors ends too), and what it brings back counts 1/q times. */
static int survives(const Scene *s, int rays, vec *beta, vec *f_cos, Worker *wk)
{
    real q, m = beta->x > beta->y ? beta->x : beta->y;
    if (m < beta->z) m = beta->z;
    if (!s->roulette || rays < ROULETTE_FROM) return 1;
    q = m < (real)0.95 ? m : (real)0.95;
    if (!(bounce_random(wk, ROULETTE) < q)) return 0;
    *beta = scale(1 / q, *beta);
    *f_cos = scale(1 / q, *f_cos);
    return 1;
}

/* Le: what the hit object emits towards wo (kl times its colour; a sphere
 * from both sides, a one-sided triangle from its front only), weighed for
 * the estimator: NEE has counted it already unless the ray came from the
 * camera, a mirror or glass; MIS weighs it against sample_light's pdf.  An
 * object that glows but is no light sample_light can choose (a cone, a
 * degenerate triangle) counts in full whatever the estimator. */
static vec emitted(const Scene *s, const Hit *h, vec wo, const Path *path)
{
    const Material *m = &s->mat[h->mat];
    int l = s->emitter[h->obj];
    real w = 1;
    if (!(m->kl > 0) || !front_emits(s, h->obj, h->ng, wo)) return v3(0, 0, 0);
    if (!path->counted && l >= 0 && s->estimator == NEE) return v3(0, 0, 0);
    if (!path->counted && l >= 0 && s->estimator == MIS)
        w = power_heuristic(path->pdf, light_pdf(s, l, path->from, path->n_from, h->p, h->ng));
    return scale(w * m->kl, m->color);
}

/* The background: a uniform radiance from every direction (the sky),
 * weighed like any light. */
static vec sky(const Scene *s, vec d, const Path *path)
{
    real w = 1;
    if (!path->counted && s->estimator == NEE) return v3(0, 0, 0);
    if (!path->counted && s->estimator == MIS && s->sky >= 0)
        w = power_heuristic(path->pdf, light_pdf(s, s->sky, path->from, path->n_from, d, d));
    return scale(w, s->background);
}

/* The power heuristic with exponent 2 (Veach and Guibas 1995): the weight
 * of an estimate made with pdf a when another technique had pdf b. */
static real power_heuristic(real a, real b)
{
    return a * a / (a * a + b * b);
}

/* Next-event estimation: the light reaching the hit directly from one light,
 * chosen in proportion to its power, through a point chosen on it:
 *
 *     f(x, wi, wo) Le cos(theta_i) / pdf(wi)   if nothing lies between,
 *
 * weighed by MIS against the BSDF's own sampling of the same direction. */
static vec sample_light(const Scene *s, const Hit *h, const Bsdf *b, vec wo, Worker *wk)
{
    vec wi, Le, f;
    real dist, pdf, cosi;
    int l = choose_light(s, bounce_random(wk, LIGHT_CHOICE)), delta;
    Ray r;
    if (l < 0) return v3(0, 0, 0);
    delta = sample_emitter(s, l, h->p, b->n, wk, &wi, &dist, &Le, &pdf);
    if (!(pdf > 0)) return v3(0, 0, 0);
    pdf *= light_choice(s, l);
    cosi = dot(wi, b->n);
    f = bsdf_eval(b, wo, wi);
    if (!(cosi > 0) || (f.x == 0 && f.y == 0 && f.z == 0)) return v3(0, 0, 0);
    wk->count.shadow++;
    r = spawn(s, h, wi);
    if (s->emit[l].type == SPHERE_LIGHT || s->emit[l].type == TRIANGLE_LIGHT)
        r.skip = s->emit[l].obj;          /* the light itself does not block */
    if (any_hit(s, r, dist, &wk->blocker[l % SHADOW_SLOTS], wk)) return v3(0, 0, 0);
    if (!delta && s->estimator == MIS) pdf /= power_heuristic(pdf, bsdf_pdf(b, wo, wi));
    return scale(cosi / pdf, mul(f, Le));
}

/* The light whose share of the total power holds u, or -1 without lights. */
static int choose_light(const Scene *s, real u)
{
    int lo = 0, hi = s->nemit - 1;
    if (s->nemit == 0) return -1;
    while (lo < hi) {               /* the first light whose cdf exceeds u */
        int mid = (lo + hi) / 2;
        if (s->emit_cdf[mid] > u) hi = mid;
        else lo = mid + 1;
    }
    return lo;
}

/* The chance that choose_light picks light l. */
static real light_choice(const Scene *s, int l)
{
    return s->emit_cdf[l] - (l > 0 ? s->emit_cdf[l - 1] : 0);
}

/* A direction wi from x towards a point of light l, the distance dist to
 * that point (INFINITY for the sky), the radiance Le it sends back along
 * -wi, and the pdf of wi in solid angle.  Returns 1 for a point light,
 * which only this can find (its pdf is the choice alone). */
static int sample_emitter(const Scene *s, int l, vec x, vec n, Worker *wk, vec *wi,
                          real *dist, vec *Le, real *pdf)
{
    const Emitter *e = &s->emit[l];
    const Material *m;
    real u = bounce_random(wk, LIGHT_U), v = bounce_random(wk, LIGHT_V);
    vec y, ny;
    int k;
    *pdf = 0;
    if (e->type == POINT_LIGHT) {
        vec d = sub(e->pos, x);
        *dist = sqrt(dot(d, d));
        *wi = scale(1 / *dist, d);
        *Le = scale(1 / (*dist * *dist), e->intensity);
        *pdf = 1;
        return 1;
    }
    if (e->type == SKY_LIGHT) {
        *wi = from_local(n, cosine_hemisphere(u, v));
        *dist = INFINITY;
        *Le = s->background;
        *pdf = cosine_hemisphere_pdf(dot(*wi, n));
        return 0;
    }
    kind(s, e->obj, &k);
    if (e->type == SPHERE_LIGHT) {
        *pdf = sphere_sample(&s->sph[k], x, u, v, wi, dist);
        m = &s->mat[s->sph[k].mat];
    } else {
        triangle_sample(&s->tri[k], u, v, &y, &ny);
        *dist = sqrt(dot(sub(y, x), sub(y, x)));
        *wi = scale(1 / *dist, sub(y, x));
        *pdf = triangle_pdf(&s->tri[k], *dist, dot(*wi, ny));
        m = &s->mat[s->tri[k].mat];
        if (!front_emits(s, e->obj, ny, scale(-1, *wi))) *pdf = 0;
    }
    *Le = scale(m->kl, m->color);
    return 0;
}

/* The pdf (in solid angle at x, choice included) with which sample_light
 * would have picked the point y, of normal ny, on light l: what MIS needs
 * for a light found by BSDF sampling.  For the sky, y is the direction. */
static real light_pdf(const Scene *s, int l, vec x, vec n, vec y, vec ny)
{
    const Emitter *e = &s->emit[l];
    vec d;
    real dist;
    int k;
    if (e->type == SKY_LIGHT) return light_choice(s, l) * cosine_hemisphere_pdf(dot(y, n));
    kind(s, e->obj, &k);
    if (e->type == SPHERE_LIGHT) return light_choice(s, l) * sphere_pdf(&s->sph[k], x, y);
    d = sub(y, x);
    dist = sqrt(dot(d, d));
    return light_choice(s, l) * triangle_pdf(&s->tri[k], dist, dot(d, ny) / dist);
}

/* Whether object i, with front normal ng, emits towards wo: a one-sided
 * triangle only from its front. */
static int front_emits(const Scene *s, int i, vec ng, vec wo)
{
    int k;
    return kind(s, i, &k) != TRIANGLE || !s->tri[k].cull || dot(wo, ng) > 0;
}

/* The BSDF at a hit, for light leaving towards wo. */
static void bsdf_at(const Scene *s, const Hit *h, vec wo, Bsdf *b)
{
    const Material *m = &s->mat[h->mat];
    real sum = m->kd + m->ks + m->kt, k = sum > 1 ? 1 / sum : 1, total;
    int i;
    b->n = h->n;
    b->ng = h->ng;
    b->eta = 1 / m->ir;
    if (dot(wo, h->ng) < 0) {             /* inside: the ray goes out */
        b->n = scale(-1, b->n);
        b->ng = scale(-1, b->ng);
        b->eta = m->ir;
    }
    b->albedo = scale(k * m->kd, m->color);
    b->shine = m->shine;
    b->glossy = m->shine > 0 ? k * m->ks : 0;
    b->mirror = m->shine > 0 ? 0 : k * m->ks;
    b->glass = k * m->kt;
    b->p[DIFFUSE_LOBE] = fmax(b->albedo.x, fmax(b->albedo.y, b->albedo.z));
    b->p[GLOSSY_LOBE] = b->glossy;
    b->p[MIRROR_LOBE] = b->mirror;
    b->p[GLASS_LOBE] = b->glass;
    total = b->p[0] + b->p[1] + b->p[2] + b->p[3];
    k = total > 0 ? 1 / total : 0;
    for (i = 0; i < 4; i++) b->p[i] *= k;
}

/* f(x, wi, wo) for the lobes that are not deltas (Lambert and Phong).  Zero
 * unless wi and wo lie on the same side of the surface, by both normals. */
static vec bsdf_eval(const Bsdf *b, vec wo, vec wi)
{
    vec f = scale(1 / (real)PI, b->albedo);
    if (!(dot(wi, b->ng) > 0 && dot(wi, b->n) > 0)) return v3(0, 0, 0);
    if (b->glossy > 0) {
        real c = fmax(0, dot(wi, reflect(scale(-1, wo), b->n, dot(wo, b->n))));
        real g = b->glossy * (b->shine + 2) / (2 * (real)PI) * pow(c, b->shine);
        f = add(f, v3(g, g, g));
    }
    return f;
}

/* The pdf with which sample_bsdf draws wi, for the lobes that are not
 * deltas: cosine-weighted for Lambert, cos^shine about the mirror
 * direction for Phong. */
static real bsdf_pdf(const Bsdf *b, vec wo, vec wi)
{
    real cosi = dot(wi, b->n), pdf;
    if (!(cosi > 0 && dot(wi, b->ng) > 0)) return 0;
    pdf = b->p[DIFFUSE_LOBE] * cosine_hemisphere_pdf(cosi);
    if (b->glossy > 0)
        pdf += b->p[GLOSSY_LOBE]
               * phong_lobe_pdf(b->shine, dot(wi, reflect(scale(-1, wo), b->n, dot(wo, b->n))));
    return pdf;
}

/* Draws wi from the BSDF: first a lobe, by the chances p, then a
 * direction from it.  *f_cos returns f cos(theta_i) / pdf, the factor the
 * light from wi is multiplied by; *pdf the pdf of wi (for MIS; undefined for
 * a delta lobe).  Returns the lobe, or -1 when the path ends here (the
 * light is absorbed, or the direction fell below the surface). */
static int sample_bsdf(const Bsdf *b, vec wo, Worker *wk, vec *wi, vec *f_cos, real *pdf)
{
    real u = bounce_random(wk, LOBE), cosi = dot(wo, b->n);
    real u1 = bounce_random(wk, DIRECTION_U), u2 = bounce_random(wk, DIRECTION_V);
    int lobe = 0;
    *pdf = 0;
    while (lobe < GLASS_LOBE && u >= b->p[lobe]) u -= b->p[lobe++];
    if (!(b->p[lobe] > 0)) return -1;
    if (lobe == MIRROR_LOBE) {
        *wi = reflect(scale(-1, wo), b->n, cosi);
        *f_cos = v3(b->mirror / b->p[lobe], b->mirror / b->p[lobe], b->mirror / b->p[lobe]);
        return dot(*wi, b->ng) > 0 ? lobe : -1;
    }
    if (lobe == GLASS_LOBE) return sample_glass(b, wo, u / b->p[lobe], wi, f_cos);
    if (lobe == DIFFUSE_LOBE) *wi = from_local(b->n, cosine_hemisphere(u1, u2));
    else *wi = from_local(reflect(scale(-1, wo), b->n, cosi), phong_lobe(b->shine, u1, u2));
    if (b->glossy == 0) {         /* Lambert alone: f cos / pdf is the albedo over its chance */
        *pdf = b->p[DIFFUSE_LOBE] * cosine_hemisphere_pdf(dot(*wi, b->n));
        *f_cos = scale(1 / b->p[DIFFUSE_LOBE], b->albedo);
        return dot(*wi, b->ng) > 0 && *pdf > 0 ? lobe : -1;
    }
    *pdf = bsdf_pdf(b, wo, *wi);
    if (!(*pdf > 0)) return -1;
    *f_cos = scale(dot(*wi, b->n) / *pdf, bsdf_eval(b, wo, *wi));
    return lobe;
}

/* The smooth dielectric: reflect with the Fresnel reflectance F, else
 * refract (Snell, as Whitted's refract()).  Each is chosen with its own
 * chance, so the weight is the lobe's alone, times eta^2 through the
 * surface: radiance is crowded into a narrower cone entering a denser
 * medium, and spreads out leaving it (the same factor, inverted, so a
 * path in and out again gets the two back to 1).  u is what is left of the
 * number that chose the lobe, rescaled to [0, 1): given that glass was
 * chosen, it is again uniform and tells nothing of the choice, so it can
 * choose once more, and the choice needs no dimension of its own (the
 * LOBE slot serves both; SPARE stays free). */
static int sample_glass(const Bsdf *b, vec wo, real u, vec *wi, vec *f_cos)
{
    real cosi = dot(wo, b->n), w = b->glass / b->p[GLASS_LOBE];
    vec d = scale(-1, wo);
    if (u < fresnel(cosi, b->eta) || !refract(d, b->n, cosi, b->eta, wi)) {
        *wi = reflect(d, b->n, cosi);
        *f_cos = v3(w, w, w);
        return dot(*wi, b->ng) > 0 ? GLASS_LOBE : -1;
    }
    w *= b->eta * b->eta;
    *f_cos = v3(w, w, w);
    return dot(*wi, b->ng) < 0 ? GLASS_LOBE : -1;
}

/* The Fresnel reflectance of unpolarised light at a smooth dielectric
 * surface: the mean of the s and p polarisations' equations, exact (Born
 * and Wolf, Principles of Optics, 1.5.2).  cosi is the cosine of the angle
 * of incidence, eta = n1/n2; 1 on total internal reflection.  Exact
 * rather than Schlick's approximation (which smallpt uses): the cost is a
 * square root at glass, and a glass ball in a white room then vanishes
 * exactly, which a test checks. */
static real fresnel(real cosi, real eta)
{
    real sin2t = eta * eta * (1 - cosi * cosi), cost, rs, rp;
    if (sin2t >= 1) return 1;
    cost = sqrt(1 - sin2t);
    rs = (eta * cosi - cost) / (eta * cosi + cost);
    rp = (cosi - eta * cost) / (cosi + eta * cost);
    return (rs * rs + rp * rp) / 2;
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
            best = kd_nearest(s->kd, &s->prims, o, d, q, q->r.skip, q->r.tmin, &tmax, &c);
        else if (s->accel == ACCEL_BVH)
            best = bvh_nearest(s->bvh, &s->prims, o, d, q, q->r.skip, q->r.tmin, &tmax, &c);
        else
            best = grid_nearest(s->grid, &s->prims, o, d, q, q->r.skip, q->r.tmin, &tmax, &c);
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
    case SPHERE: *t = hit_sphere(&s->sph[k], r, r->tmin); break;
    case CONE: *t = hit_cone(&s->cone[k], r, r->tmin); break;
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
    r.tmin = 0;
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
            hit = kd_any(s->kd, &s->prims, o, d, q, q->r.skip, q->r.tmin, tmax, &c);
        else if (s->accel == ACCEL_BVH)
            hit = bvh_any(s->bvh, &s->prims, o, d, q, q->r.skip, q->r.tmin, tmax, &c);
        else
            hit = grid_any(s->grid, &s->prims, o, d, q, q->r.skip, q->r.tmin, tmax, &c);
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

/* A ray whose origin is farther than FAR_MOVE times a primitive's size
 * from it is first moved along itself to near the primitive, by
 * near_point, before the primitive's test: the contract of prims.h lets a
 * hit from afar err along the ray by a rounding of |o|, but off it only by
 * a rounding of the primitive's own coordinates.  (In double, spheres and
 * cones would keep it without; the float build's would not.) */
#define FAR_MOVE 4096

/* o + t d - v, summed exactly and rounded once per coordinate
 * (prims_along, prims.h): for a point of the ray near v, exact to a
 * rounding of itself.  Rounded step by step, the point would lie off the
 * ray by a rounding of |o| (1e-3 from 1e13 away), and a test made from
 * there would see a ray shifted sideways by that much. */
static vec near_point(vec o, real t, vec d, vec v)
{
    return v3((real)prims_along(o.x, v.x, t, d.x), (real)prims_along(o.y, v.y, t, d.y),
              (real)prims_along(o.z, v.z, t, d.z));
}

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
 * tree's leaf, costs no division.  f = o - c itself is rounded by eps |o|,
 * which from afar shifts the ray sideways, so a far ray starts from the
 * point level with the centre (FAR_MOVE). */
static real hit_sphere(const Sphere *sp, const Ray *r, real tmin)
{
    vec f = sub(r->o, sp->cen), l;
    real a = dot(r->d, r->d), tm = 0, b, ar, disc, c, q, t0, t1;
    if (maxabs(f) > FAR_MOVE * sp->rad) {       /* from afar: start level with the centre */
        tm = -dot(f, r->d) / a;
        f = near_point(r->o, tm, r->d, sp->cen);
    }
    b = -dot(f, r->d);                          /* half of -B in a t^2 + B t + C */
    l = comb(b, r->d, scale(a, f));             /* a l */
    ar = a * sp->rad, disc = ar * ar - dot(l, l);   /* a^2 (r^2 - l.l) */
    if (!(disc >= 0)) return INFINITY;          /* also rejects NaN */
    disc /= a;                                  /* the quarter discriminant */
    c = dot(f, f) - sp->rad * sp->rad;
    q = b + (b >= 0 ? sqrt(disc) : -sqrt(disc));
    t0 = tm + c / q;
    t1 = tm + q / a;
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

/* For a sphere that emits: a direction wi from x towards it, and the
 * distance to the point of the sphere it meets; returns the pdf of wi in
 * solid angle.  From outside, wi is uniform in the cone of directions the
 * sphere fills as seen from x, so that every sample hits it, and the near
 * side is what is hit (Shirley, Wang and Zimmerman, "Monte Carlo Techniques
 * for Direct Lighting Calculations", ACM TOG 15(1), 1996).  From inside, or
 * on the surface (a furnace seen from within), wi points to a uniform point
 * of the surface, and the pdf is that of the area turned into solid angle:
 * dist^2 / (A cos theta_y), the lecture's d omega = dA cos theta / r^2. */
static real sphere_sample(const Sphere *sp, vec x, real u, real v, vec *wi, real *dist)
{
    vec dc = sub(sp->cen, x), n;
    real d2 = dot(dc, dc), r2 = sp->rad * sp->rad;
    if (d2 > r2 * (1 + 64 * REAL_EPS)) {
        real d = sqrt(d2), sin2max = r2 / d2;
        real cap = sin2max / (1 + sqrt(1 - sin2max));     /* 1 - cos(theta_max), no cancelling */
        vec l = sphere_cap(cap, u, v);                    /* about the direction to the centre */
        real c = l.z, s2 = fmax(0, 1 - c * c);
        *wi = from_local(scale(1 / d, dc), l);
        *dist = d * c - sqrt(fmax(0, r2 - d2 * s2));
        return sphere_cap_pdf(cap);
    }
    n = sphere_cap(2, u, v);                    /* a uniform point of the whole sphere */
    dc = sub(comb(sp->rad, n, sp->cen), x);
    *dist = sqrt(dot(dc, dc));
    *wi = scale(1 / *dist, dc);
    return sphere_pdf(sp, x, comb(sp->rad, n, sp->cen));
}

/* The pdf with which sphere_sample, from x, picks the direction to y, a
 * point of the sphere (the one a ray from x met first). */
static real sphere_pdf(const Sphere *sp, vec x, vec y)
{
    vec dc = sub(sp->cen, x), d = sub(y, x);
    real d2 = dot(dc, dc), r2 = sp->rad * sp->rad, dist2 = dot(d, d), cosy;
    if (d2 > r2 * (1 + 64 * REAL_EPS))
        return sphere_cap_pdf(r2 / d2 / (1 + sqrt(1 - r2 / d2)));
    cosy = fabs(dot(sub(y, sp->cen), d)) / (sp->rad * sqrt(dist2));
    return dist2 / (4 * (real)PI * r2 * cosy);
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
 * there, and t0 added back: the same idea as the sphere's closest point
 * (from farther than FAR_MOVE times the cone's size, the point at t0 is
 * summed exactly, for prims.h).
 * The roots then come from q and C/q, so that neither subtracts. */
static real hit_cone(const Cone *c, const Ray *r, real tmin)
{
    real t0 = dot(sub(comb(c->len / 2, c->axis, c->base), r->o), r->d) / dot(r->d, r->d);
    vec q = maxabs(sub(r->o, c->base)) > FAR_MOVE * (c->len + c->ra + c->rb)
            ? near_point(r->o, t0, r->d, c->base)   /* from afar, summed exactly */
            : sub(comb(t0, r->d, r->o), c->base);
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
 *    the common case keeps Moller and Trumbore's speed.  In the float build
 *    (-DREAL=float) the rounding of u and v grows with the ray's distance
 *    beyond 1e-7 of det (a mesh seen from afar showed holes), so there the
 *    margin also covers a bound on that: 96 ulps of |o - v0| |d| |e|.
 * And one for rays from afar.  From D times its size away, o - v0 is
 * rounded by eps D, and the cross and dot products of it with the edges
 * cancel: t, u and v err by eps D divided by the sines of the grazing angle
 * and of the triangle's smallest angle (from 10^13 away, by more than the
 * triangle's size, and the mesh leaks).  The acceleration structures need
 * the hit point off the triangle's box by no more than a few eps of the
 * triangle's coordinates, and along the ray by a few eps of |o| (prims.h),
 * so a ray from farther than FAR_MOVE times the triangle's size is first
 * moved along itself to the point nearest v0, summed exactly (near_point),
 * as hit_sphere and hit_cone move theirs; the test is made from there, and
 * the distance moved added to t.  u and v are then exact to the
 * triangle's own rounding, and t to a rounding of itself.  Rays that fall
 * within the 1e-7 of an edge still get the exact test from the caller's own
 * origin, which every triangle around the edge shares: the mesh stays
 * watertight.
 * Nearer rays take the lecture's path unchanged.
 * Returns 1 and t, u, v (barycentrics of v1 and v2) on a hit. */
static int hit_triangle(const Scene *s, const Triangle *tr, const Ray *r, real tmax,
                        real *t, real *u, real *v)
{
    vec v0 = tr->v0, e1 = tr->e1, e2 = tr->e2, p = cross(r->d, e2), tv, q;
    real det = dot(e1, p), sign = det < 0 ? -1 : 1, slack, uu, vv, tt, t0 = 0, size;
    int far;
    if (tr->degenerate || isnan(det)) return 0;
    if (tr->cull) {                      /* the lecture's culling branch */
        if (!(det > 0)) return 0;
    } else if (det == 0)                 /* the non-culling branch */
        return 0;
    det *= sign;                         /* from here on det > 0 */
    tv = sub(r->o, v0);                   /* u, v and t, each times det */
    slack = (real)1e-7 * det;
    size = maxabs(e1) + maxabs(e2);
    far = maxabs(tv) > FAR_MOVE * size;
    if (far) {                           /* see above: from afar, start near v0 */
        t0 = -dot(tv, r->d) / dot(r->d, r->d);
        tv = near_point(r->o, t0, r->d, v0);
    }
    if (sizeof(real) == sizeof(float))   /* see above: float's rounding outgrows 1e-7 */
        slack += 96 * REAL_EPS * maxabs(tv) * maxabs(r->d) * size;
    uu = sign * dot(tv, p);
    if (uu < -slack || uu > det + slack) return 0;
    q = cross(tv, e1);
    vv = sign * dot(r->d, q);
    if (vv < -slack || uu + vv > det + slack) return 0;
    tt = sign * dot(e2, q);
    if (far ? !(t0 + tt / det > 0) : !(tt > 0)) return 0;   /* behind the origin, or NaN */
    if ((uu < 0 || vv < 0 || uu + vv > det)
        && !watertight_inside(v0, s->vert[tr->v[1]], s->vert[tr->v[2]], r)) return 0;
    *t = far ? t0 + tt / det : tt / det;   /* compared after the division: a tie at tmax must be exact */
    if (!(*t <= tmax) || (r->tmin > 0 && !(*t > r->tmin))) return 0;
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

/* For a triangle that emits: a uniform point y of it (uniform_triangle),
 * and its front normal. */
static void triangle_sample(const Triangle *tr, real u, real v, vec *y, vec *ny)
{
    vec b = uniform_triangle(u, v);
    *y = add(tr->v0, add(scale(b.y, tr->e1), scale(b.z, tr->e2)));
    *ny = unit(cross(tr->e1, tr->e2));
}

/* The pdf in solid angle of a uniform point of the triangle seen at
 * distance dist, its normal at cosine cosy to the line of sight:
 * dist^2 / (A cos theta_y). */
static real triangle_pdf(const Triangle *tr, real dist, real cosy)
{
    vec n = cross(tr->e1, tr->e2);
    return uniform_triangle_pdf(sqrt(dot(n, n)) / 2) * dist * dist / fabs(cosy);
}

/* Zero area (a repeated vertex, or three in a line) to within rounding: such
 * a triangle has no inside and no normal, so it is never hit.  Relative to
 * the edge lengths, so that tiny but proper triangles stay.  In double even
 * in the float build, where the product of four lengths would overflow past
 * legs of 1e9 and vanish below 1e-11. */
static int degenerate(vec a, vec b, vec c)
{
    double p[3][3], e1[3], e2[3], n[3], k;
    int i;
    to3(a, p[0]);
    to3(b, p[1]);
    to3(c, p[2]);
    for (i = 0; i < 3; i++) e1[i] = p[1][i] - p[0][i], e2[i] = p[2][i] - p[0][i];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    k = 64 * REAL_EPS * sqrt((e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2])
                             * (e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]));
    return !(sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) > k);
}

/* =========================================================================
 * THE PLUMBING.  The lecture ends here.  What follows makes it a program:
 * threads and a progress line, reading scenes (the sphere format, OBJ and
 * NFF) into a Scene, writing the image, the command line and main().
 * ========================================================================= */

/* The plumbing's own headers: characters, signals, opening files (and on
 * Windows, binary mode and the process number). */
#include <ctype.h>
#include <signal.h>
#ifdef RAY_POSIX
#include <fcntl.h>
#endif
#ifdef _WIN32
#include <fcntl.h>
#include <io.h>
#include <process.h>
#endif

/* ---------------------------------------------------- threads and progress */

typedef struct {
    int spp, threads, progress;
    double start;                 /* when the render began (now()), for the progress line */
} Options;

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

/* "ray:  42%  ETA 1:05": rows done out of rows, and the time left if the
 * rows still to do take as long as those done so far took. */
static void show_progress(const Options *o, int done, int rows)
{
    long left = (long)((now() - o->start) * (rows - done) / done + 0.5);
    if (left >= 3600)
        fprintf(stderr, "\rray: %3d%%  ETA %ld:%02ld:%02ld ", done * 100 / rows, left / 3600,
                left / 60 % 60, left % 60);
    else
        fprintf(stderr, "\rray: %3d%%  ETA %ld:%02ld    ", done * 100 / rows, left / 60, left % 60);
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
    to->bounced += from->bounced;
    to->discarded += from->discarded;
    to->cut += from->cut;
    if (from->threads > to->threads) to->threads = from->threads;
}

/* The whole image, row by row (render_row).  Rows go to threads one at a
 * time, as they free up; each pixel is written once by whoever computes it,
 * so the image does not depend on the order.  Each thread has its own
 * Worker; their counts are summed into *total. */
static void render(const Scene *s, const Options *o, Image *img, Counts *total)
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
            render_row(s, j, o->spp, img, &wk);
            OMP(omp atomic capture)
            mine = ++done;
            if (o->progress && (mine * 100 / s->h != (mine - 1) * 100 / s->h))
                show_progress(o, mine, s->h);
        }
        OMP(omp critical)
        add_counts(total, &wk.count);
    }
    if (o->progress) fprintf(stderr, "\r%30s\r", "");
}

/* ------------------------------------------------------------------ --view */

/* The heat scale of --view steps: piecewise linear through black (0), blue
 * (25), red (50), yellow (100) and white (200 and more). */
static vec heat(real w)
{
    static const double at[5] = { 0, 25, 50, 100, 200 };
    static const double rgb[5][3] = { { 0, 0, 0 }, { 0, 0, 1 }, { 1, 0, 0 }, { 1, 1, 0 }, { 1, 1, 1 } };
    int k = 0;
    double f;
    if (!(w < at[4])) return v3(1, 1, 1);
    while (w > at[k + 1]) k++;
    f = (w - at[k]) / (at[k + 1] - at[k]);
    return v3((real)(rgb[k][0] + f * (rgb[k + 1][0] - rgb[k][0])),
              (real)(rgb[k][1] + f * (rgb[k + 1][1] - rgb[k][1])),
              (real)(rgb[k][2] + f * (rgb[k + 1][2] - rgb[k][2])));
}

/* For --view depth: the distance from the eye to the farthest corner of
 * the box of every object (1 when there is none). */
static real farthest(const Scene *s)
{
    double lo[3], hi[3], best = 0;
    int i, c;
    for (i = 0; i < nobj(s); i++) {
        prim_bounds((void *)s, i, lo, hi);
        for (c = 0; c < 8; c++) {
            vec corner = v3((real)(c & 1 ? hi[0] : lo[0]), (real)(c & 2 ? hi[1] : lo[1]),
                            (real)(c & 4 ? hi[2] : lo[2]));
            vec d = sub(corner, s->cam.eye);
            best = fmax(best, sqrt(dot(d, d)));
        }
    }
    return (real)(best > 0 ? best : 1);
}

/* --view: what one ray through the pixel's centre meets, as a picture.
 * steps: the acceleration structure's work for it, nodes or cells visited
 * plus intersection tests, on one fixed scale so that two structures'
 * pictures compare: black 0, blue 25, red 50, yellow 100, white 200 or
 * more.  normal: the shading normal at the hit, x, y, z from -1..1 to 0..1
 * as red, green, blue.  depth: the hit's distance as grey, white at the eye
 * to black at the scene's farthest point.  Nothing hit: black. */
static vec pixel_view(const Scene *s, int i, int j, Worker *wk)
{
    Counts before = wk->count;
    Hit h;
    int hit = nearest_hit(s, camera_ray(&s->cam, s->w, s->h, i + (real)0.5, j + (real)0.5), &h, wk);
    if (s->view == VIEW_STEPS)
        return heat((real)(wk->count.steps - before.steps + wk->count.tests - before.tests));
    if (!hit) return v3(0, 0, 0);
    if (s->view == VIEW_NORMAL) return scale((real)0.5, add(h.n, v3(1, 1, 1)));
    return v3(1 - h.t / s->far, 1 - h.t / s->far, 1 - h.t / s->far);
}

/* ------------------------------------------------------------- scene input */

typedef struct { const char *file; int line; } Where;

/* s on f, with every byte that is not printable ASCII as \xNN: a message
 * that quotes a file never sends a terminal raw binary. */
static void put_escaped(FILE *f, const char *s)
{
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c >= 0x20 && c < 0x7F) putc(c, f);
        else fprintf(f, "\\x%02X", c);
    }
}

static int fail(Where w, const char *msg, const char *arg)
{
    fprintf(stderr, "%s:%d: %s", w.file, w.line, msg);
    if (arg) {
        fputs(": ", stderr);
        put_escaped(stderr, arg);
    }
    fputc('\n', stderr);
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

/* The path tracer scales kd + ks + kt down to 1 where they sum to more,
 * which would make light out of nothing; the first such material is named
 * in a warning when it starts. */
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

/* Corner b, between a and c, can be cut off: it turns left, and no corner
 * lies in the triangle a b c.  Only the corners in bent[0..nbent-1], those
 * that do not turn left, are looked at: if any corner lies in the triangle,
 * one of those does (Eberly, "Triangulation by ear clipping", 2002), so the
 * test takes time in proportion to the dents, not to all the corners. */
static int is_ear(double (*p)[2], const int *bent, int nbent, int a, int b, int c)
{
    int j;
    if (area2(p[a], p[b], p[c]) <= 0) return 0;         /* reflex or flat */
    for (j = 0; j < nbent; j++) {
        const double *q = p[bent[j]];
        if (inside2(q, p[a], p[b], p[c]) && memcmp(q, p[a], sizeof *p)
            && memcmp(q, p[b], sizeof *p) && memcmp(q, p[c], sizeof *p))
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

/* Take corner k off the list bent[0..*nbent-1]; pos[k] is its place there,
 * -1 once it is not listed. */
static void unlist(int *bent, int *nbent, int *pos, int k)
{
    int last = bent[--*nbent];
    bent[pos[k]] = last, pos[last] = pos[k], pos[k] = -1;
}

/* Keep corner k listed in bent[] while it does not turn left, between
 * corners prev[k] and next[k]. */
static void note_bend(double (*p)[2], const int *prev, const int *next, int k, int *bent,
                      int *nbent, int *pos)
{
    int left = area2(p[prev[k]], p[k], p[next[k]]) > 0;
    if (!left && pos[k] < 0) pos[k] = *nbent, bent[(*nbent)++] = k;
    if (left && pos[k] >= 0) unlist(bent, nbent, pos, k);
}

/* A planar polygon, convex or not, as triangles, by ear clipping (Meisters,
 * "Polygons have ears", 1975): some corner can always be cut off, leaving a
 * polygon one corner smaller.  A fan from one corner would be wrong for the
 * gears' concave 144-gons; a convex polygon takes the O(n) way above.
 * The ears are sought going round the polygon, and after each cut the
 * search goes on two corners further, not at the next one: trying the next
 * corner first would cut ears a, c, d then a, d, e and so on, a fan at a
 * (one dent in an 8000-gon put all 7998 triangles at one corner, and the
 * kd-tree took 10 s to build).  Going round, each lap cuts every other
 * corner, as triangulate_arc halves an arc, so a corner ends up in a few
 * triangles per lap and about log2 n laps.  A polygon whose only
 * triangulation is a fan (every corner but one a dent, facing it) still
 * gives one; the kd-tree copes with that too.
 * vi and ni are the corners' vertex and normal indices (ni may be NULL). */
static void triangulate(Scene *s, const int *vi, const int *ni, int n, int mat)
{
    double (*p)[2] = malloc((size_t)n * sizeof *p);
    int *next = malloc((size_t)n * sizeof *next), *prev = malloc((size_t)n * sizeof *prev);
    int *bent = malloc((size_t)n * sizeof *bent), *pos = malloc((size_t)n * sizeof *pos);
    int m = n, k, nbent = 0, convex = 1;
    if (!p || !next || !prev || !bent || !pos) out_of_memory();
    flatten(s, vi, n, p);
    for (k = 0; k < n; k++) next[k] = (k + 1) % n, prev[k] = (k + n - 1) % n, pos[k] = -1;
    for (k = 0; k < n; k++) {
        if (area2(p[prev[k]], p[k], p[next[k]]) < 0) convex = 0;
        note_bend(p, prev, next, k, bent, &nbent, pos);
    }
    if (convex) triangulate_arc(s, vi, ni, 0, n - 1, mat);
    for (k = 0; !convex && m > 2; m--) {
        int tries, a, c;
        for (tries = 0; m > 3 && tries < m && !is_ear(p, bent, nbent, prev[k], k, next[k]); tries++)
            k = next[k];
        /* tries == m: only flat or self-touching corners are left; cut one anyway */
        a = prev[k], c = next[k];
        add_corner_triangle(s, vi, ni, a, k, c, mat);
        next[a] = c, prev[c] = a;
        if (pos[k] >= 0) unlist(bent, &nbent, pos, k);  /* cut anyway */
        note_bend(p, prev, next, a, bent, &nbent, pos);
        note_bend(p, prev, next, c, bent, &nbent, pos);
        k = next[c];
    }
    free(p), free(next), free(prev), free(bent), free(pos);
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
    /* Shorter than this, the rounding of a point's height along the axis
     * exceeds the length itself, and the side would be found where it is
     * not (the fuzz targets found one 1e-71 long, hit at the eye). */
    if (!(sqrt(dot(sub(apex, base), sub(apex, base)))
          >= 1e-9 * (fmax(x[3], x[7]) + maxabs(base) + maxabs(apex))))
        return fail(w, "cone shorter than 1e-9 of its radius and coordinates", NULL);
    add_cone(s, base, x[3], apex, x[7], mat);
    return 1;
}

/* A colour or a weight beyond 1e30 would overflow to infinity in a few
 * products (and infinity times a weight of 0 is NaN), and an index of
 * refraction beyond 1e6 either way makes refract() cancel two huge terms
 * and return a direction that is no unit vector: both are refused (the
 * fuzz targets found NaN pixels from each). */
#define COLOR_LIMIT 1e30
static int color_ok(vec c)
{
    return fabs(c.x) <= COLOR_LIMIT && fabs(c.y) <= COLOR_LIMIT && fabs(c.z) <= COLOR_LIMIT;
}

static int material_ok(Where w, const Material *m)
{
    if (!(m->ir >= 1e-6 && m->ir <= 1e6))
        return fail(w, "index of refraction must be between 1e-6 and 1e6", NULL);
    if (!color_ok(m->color) || !color_ok(v3(m->kd, m->ks, m->kt)) || !(fabs(m->kl) <= COLOR_LIMIT))
        return fail(w, "colours and weights must lie within 1e30 either way", NULL);
    return 1;
}

/* Remembers the first material whose kd + ks + kt exceeds 1, for the path
 * tracer's warning, and the first whose ks + kt does, for Whitted's (its
 * model takes such weights as they are). */
static void note_weights(Scene *s, Where w, const Material *m)
{
    if (m->kd + m->ks + m->kt > 1 && !s->warning[0])
        sprintf(s->warning, "%.100s:%d: warning: kd + ks + kt = %.3g exceeds 1; "
                "the path tracer scales them to 1", w.file, w.line, (double)(m->kd + m->ks + m->kt));
    if (m->ks + m->kt > 1 && !s->whitted_warning[0])
        sprintf(s->whitted_warning, "%.100s:%d: warning: ks + kt = %.3g exceeds 1: what is "
                "reflected and refracted grows at every bounce, light out of nothing", w.file, w.line,
                (double)(m->ks + m->kt));
}

/* r g b kd ks kt kl ir: minray's material fields, for tri and mesh lines. */
static int material8(Scene *s, Where w, const real *v, int *mat)
{
    Material m;
    m.color = v3(v[0], v[1], v[2]);
    m.kd = v[3]; m.ks = v[4]; m.kt = v[5]; m.kl = v[6]; m.ir = v[7]; m.shine = 0;
    if (!material_ok(w, &m)) return 0;
    *mat = add_material(s, m);
    note_weights(s, w, &m);
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

/* The largest |coordinate| of a light or the camera: two points within it
 * are less than sqrt(REAL_MAX) apart, so the squared distances the renderer
 * takes between them (to a light, from the eye) stay finite; beyond it, a
 * light would light nothing and an eye see nothing.  3.9e153 in doubles. */
#define FAR_LIMIT sqrt((sizeof(real) == sizeof(float) ? FLT_MAX : DBL_MAX) / 12)

static int within_far_limit(vec p) { return maxabs(p) <= FAR_LIMIT; }

/* a times the power of two that brings its largest coordinate into
 * [1/2, 1): the same direction, and exactly the same unit() and cross()
 * bits as a itself, yet no square of it overflows or underflows. */
static vec pow2_scaled(vec a)
{
    int e;
    real m = maxabs(a);
    if (!(m > 0) || !isfinite(m)) return a;
    frexp(m, &e);
    return v3((real)ldexp(a.x, -e), (real)ldexp(a.y, -e), (real)ldexp(a.z, -e));
}

/* The narrowest field of view, in degrees, for which the image plane of
 * camera_ray stays near enough to square its distance at 32768 pixels
 * across: 2.8e-148 degrees in doubles. */
static double narrowest_fov(void)
{
    return 2 * atan(16384 / (sqrt(sizeof(real) == sizeof(float) ? FLT_MAX : DBL_MAX) / 2))
           * 180 / PI;
}

/* A point light, within FAR_LIMIT. */
static int point_light(Scene *s, Where w, vec pos, vec color)
{
    char msg[128];
    if (!within_far_limit(pos)) {
        sprintf(msg, "light too far out: beyond %.2g, its squared distance to the scene overflows",
                (double)FAR_LIMIT);
        return fail(w, msg, NULL);
    }
    if (!color_ok(color)) return fail(w, "a light's colour must lie within 1e30 either way", NULL);
    add_light(s, pos, color, -1);
    return 1;
}

static int set_camera(Scene *s, Where w, const real *v)
{
    Camera *c = &s->cam;
    vec at = v3(v[3], v[4], v[5]), up = pow2_scaled(v3(v[6], v[7], v[8]));
    char msg[160];
    c->eye = v3(v[0], v[1], v[2]);
    if (!within_far_limit(c->eye) || !within_far_limit(at)) {
        sprintf(msg, "camera too far out: beyond %.2g, squared distances from the eye overflow",
                (double)FAR_LIMIT);
        return fail(w, msg, NULL);
    }
    if (!(dot(pow2_scaled(sub(at, c->eye)), pow2_scaled(sub(at, c->eye))) > 0))
        return fail(w, "camera looks at its own eye", NULL);
    if (!(v[9] > 0 && v[9] < 180))
        return fail(w, "field of view must be between 0 and 180 degrees", NULL);
    if (!(v[9] >= narrowest_fov())) {
        sprintf(msg, "field of view too narrow: under %.2g degrees the image plane is so far away"
                " that its squared distance overflows", narrowest_fov());
        return fail(w, msg, NULL);
    }
    c->tan_half = tan(v[9] * PI / 360);
    c->fwd = unit(pow2_scaled(sub(at, c->eye)));
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

#define BOM "\xEF\xBB\xBF"          /* UTF-8's byte order mark, which some editors write */

/* Reads the next line of f into line, without its end: "\n", "\r\n" or a
 * lone "\r" (old Mac files) each end a line.  A byte order mark before the
 * first line is skipped.  0 at the end of the file, or after a message
 * (*ok cleared) on an over-long line or a NUL byte, which no text has. */
static int next_line(FILE *f, char *line, int size, Where *w, int *ok)
{
    int c = getc(f), n = 0;
    if (c == EOF) return 0;
    w->line++;
    for (; c != EOF && c != '\n' && c != '\r'; c = getc(f)) {
        if (c == 0) return *ok = fail(*w, "NUL byte: this is not a text file", NULL);
        if (n == size - 1) {
            char msg[64];
            sprintf(msg, "line longer than %d characters", size - 1);
            return *ok = fail(*w, msg, NULL);
        }
        line[n++] = (char)c;
    }
    if (c == '\r' && (c = getc(f)) != '\n' && c != EOF) ungetc(c, f);
    line[n] = 0;
    if (w->line == 1 && !strncmp(line, BOM, 3)) memmove(line, line + 3, (size_t)n - 2);
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

#ifdef RAY_POSIX
/* A mesh that a scene names must be a plain file: a directory has no
 * lines, and a pipe or a terminal would wait for input for ever.  (Not
 * found: fopen says so.) */
static int plain_file(const char *name)
{
    struct stat st;
    return stat(name, &st) != 0 || S_ISREG(st.st_mode);
}
#else
static int plain_file(const char *name) { (void)name; return 1; }
#endif

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
    int plain = plain_file(file);
    FILE *f = plain ? fopen(file, "r") : NULL;
    if (!line || !tok || !vi || !ni) out_of_memory();
    if (!plain) ok = fail(from, "mesh is not a plain file (a directory, device or pipe)", file);
    else if (!f) ok = fail(from, "cannot open mesh", strerror(errno));
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
    if (ok && ferror(f)) ok = fail(w, "cannot read mesh", strerror(errno)); /* mesh . */
    if (f) fclose(f);
    if (ok && skipped) {
        fprintf(stderr, "%s:%d: warning: skipped %d statement%s that are not v, vn or f"
                " (the first: ", file, skipped_line, skipped, skipped == 1 ? "" : "s");
        put_escaped(stderr, first_skipped);
        fputs(")\n", stderr);
    }
    free(line); free(tok); free(vi); free(ni);
    return ok;
}

/* Windows paths separate directories with \ as well as /, and may start
 * with a drive ("C:"); elsewhere \ and : are ordinary characters of a file
 * name.  -DRAY_DOS_PATHS gives the Windows rule anywhere, for the tests. */
#if defined(_WIN32) && !defined(RAY_DOS_PATHS)
#define RAY_DOS_PATHS
#endif

static int path_separator(int c)
{
#ifdef RAY_DOS_PATHS
    return c == '/' || c == '\\' || c == ':';
#else
    return c == '/';
#endif
}

/* Where the file's own name starts in path: after the last separator. */
static const char *file_part(const char *path)
{
    const char *p, *name = path;
    for (p = path; *p; p++)
        if (path_separator(*p)) name = p + 1;
    return name;
}

/* A path from the root (or a drive), which no directory may prefix. */
static int absolute(const char *path)
{
#ifdef RAY_DOS_PATHS
    if (path[0] && path[1] == ':') return 1;
#endif
    return path_separator(path[0]);
}

/* A path named in a scene is relative to the scene's directory. */
static char *beside(const char *scene, const char *name)
{
    size_t dir = absolute(name) ? 0 : (size_t)(file_part(scene) - scene);
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
        s->depth = s->max_rays = (int)v[0];
        return 1;
    }
    if (!strcmp(k, "samples")) {
        if (!numbers(w, k, tok, ntok, 1, 1, v)) return 0;
        if (!(v[0] >= 1 && v[0] <= 1 << 20 && v[0] == floor(v[0])))
            return fail(w, "samples must be a whole number from 1 to 1048576", tok[1]);
        s->spp = (int)v[0];
        return 1;
    }
    if (!strcmp(k, "hither")) {
        if (!numbers(w, k, tok, ntok, 1, 1, v)) return 0;
        if (!(v[0] >= 0)) return fail(w, "hither must be 0 or more", tok[1]);
        s->cam.hither = v[0];
        return 1;
    }
    if (!strcmp(k, "tir")) {
        if (ntok != 2 || (strcmp(tok[1], "reflect") && strcmp(tok[1], "black")))
            return fail(w, "expected `tir reflect` or `tir black`", NULL);
        s->tir_reflect = !strcmp(tok[1], "reflect");
        return 1;
    }
    if (!strcmp(k, "integrator")) {
        if (ntok != 2 || (strcmp(tok[1], "path") && strcmp(tok[1], "whitted")))
            return fail(w, "expected `integrator path` or `integrator whitted`", NULL);
        s->integrator = !strcmp(tok[1], "path") ? PATH : WHITTED;
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
    if (!strcmp(k, "light"))
        return numbers(w, k, tok, ntok, 1, 6, v)
               && point_light(s, w, v3(v[0], v[1], v[2]), v3(v[3], v[4], v[5]));
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
    s->integrator = WHITTED;
    s->estimator = MIS;
    s->roulette = 1;
    s->sky = -1;
    set_camera(s, nowhere, v);
}

/* Luminance of a linear sRGB colour (ITU-R BT.709 weights). */
static real luminance(vec c) { return (real)0.2126 * c.x + (real)0.7152 * c.y + (real)0.0722 * c.z; }

static void add_emitter(Scene *s, int type, int obj, vec pos, vec intensity, real power,
                        double *total, int *cap)
{
    s->emit = grow(s->emit, cap, s->nemit + 1, sizeof *s->emit);
    s->emit_cdf = realloc(s->emit_cdf, (size_t)*cap * sizeof *s->emit_cdf);
    if (!s->emit_cdf) out_of_memory();
    s->emit[s->nemit].type = type;
    s->emit[s->nemit].obj = obj;
    s->emit[s->nemit].pos = pos;
    s->emit[s->nemit].intensity = intensity;
    *total += power;
    s->emit_cdf[s->nemit++] = (real)*total;
    if (obj >= 0) s->emitter[obj] = s->nemit - 1;
}

/* The path tracer's lights, each with its power, so that sample_light can
 * choose one in proportion to it: point lights (intensity I: power 4 pi I),
 * emitting spheres and triangles (radiance Le over area A, each side:
 * pi Le A).  A background that is not black is the sky, whose power has no
 * finite measure: it is chosen half the time when there are other lights
 * (pricing it by a sphere about the scene, as pbrt does, starves a small
 * lamp on a large floor of shadow rays). */
static void prepare_lights(Scene *s)
{
    double total = 0;
    int i, k, cap = 0, n = nobj(s);
    s->emitter = malloc(((size_t)n + 1) * sizeof *s->emitter);
    if (!s->emitter) out_of_memory();
    for (i = 0; i < n; i++) s->emitter[i] = -1;
    s->sky = -1;
    for (i = 0; i < s->nlight; i++)
        if (s->light[i].sphere < 0)
            add_emitter(s, POINT_LIGHT, -1, s->light[i].pos, s->light[i].color,
                        4 * (real)PI * luminance(s->light[i].color), &total, &cap);
    for (i = 0; i < n; i++) {
        const Material *m;
        int what = kind(s, i, &k);
        real area;
        if (what == CONE) continue;          /* cones glow but do not light */
        m = &s->mat[what == SPHERE ? s->sph[k].mat : s->tri[k].mat];
        if (!(m->kl > 0) || (what == TRIANGLE && s->tri[k].degenerate)) continue;
        if (what == SPHERE) area = 4 * (real)PI * s->sph[k].rad * s->sph[k].rad;
        else {
            vec c = cross(s->tri[k].e1, s->tri[k].e2);
            area = sqrt(dot(c, c)) / 2 * (s->tri[k].cull ? 1 : 2);
        }
        add_emitter(s, what == SPHERE ? SPHERE_LIGHT : TRIANGLE_LIGHT, i, v3(0, 0, 0),
                    v3(0, 0, 0), (real)PI * m->kl * luminance(m->color) * area, &total, &cap);
    }
    if (luminance(s->background) > 0) {
        s->sky = s->nemit;
        add_emitter(s, SKY_LIGHT, -1, v3(0, 0, 0), v3(0, 0, 0), total > 0 ? (real)total : 1,
                    &total, &cap);
    }
    for (i = 0; i < s->nemit; i++) s->emit_cdf[i] = total > 0 ? s->emit_cdf[i] / (real)total : 0;
    if (s->nemit > 0) s->emit_cdf[s->nemit - 1] = 1;
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
typedef struct { FILE *f; Where w; int c, prev, again; char tok[256]; } Lexer;

/* On to the next character, counting lines: "\n", "\r\n" and a lone
 * "\r" each end one. */
static void advance(Lexer *lx)
{
    if (lx->c == '\r' || (lx->c == '\n' && lx->prev != '\r')) lx->w.line++;
    lx->prev = lx->c;
    lx->c = getc(lx->f);
}

/* The next token into lx->tok: 1, or 0 at the end of the file, or -1 after
 * saying what is wrong. */
static int next_token(Lexer *lx)
{
    int n = 0;
    if (lx->again) { lx->again = 0; return 1; }
    for (;;) {
        while (blank(lx->c)) advance(lx);
        if (lx->c != '#') break;
        while (lx->c != '\n' && lx->c != '\r' && lx->c != EOF && lx->c != 0) advance(lx);
    }
    for (; lx->c != EOF && !blank(lx->c); advance(lx)) {
        if (lx->c == 0) {
            fail(lx->w, "NUL byte: this is not a text file", NULL);
            return -1;
        }
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
    if (x[4][0] > 0) s->cam.hither = x[4][0];
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
    Where at;
    if (!nff_numbers(lx, "l", 3, x)) return 0;
    at = lx->w;                              /* before the look ahead */
    got = next_token(lx);                    /* a colour, or the next entity */
    if (got < 0) return 0;
    lx->again = got > 0;
    if (got > 0 && strchr("+-.0123456789", lx->tok[0]) && !nff_numbers(lx, "l", 3, rgb)) return 0;
    return point_light(s, at, v3(x[0], x[1], x[2]), v3(rgb[0], rgb[1], rgb[2]));
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
    if (!material_ok(lx->w, &m)) return 0;
    *mat = add_material(s, m);
    note_weights(s, lx->w, &m);
    return 1;
}

static int nff_sphere(Scene *s, Lexer *lx, int mat)
{
    real x[4];
    if (!nff_numbers(lx, "s", 4, x)) return 0;
    /* In NFF (the SPD's NFF.TXT) a negative radius means a sphere seen
     * only from inside; objects are otherwise one-sided, seen from outside.
     * ray.c draws both sides of a sphere, so an eye within sees the inside
     * either way: the radius is |r|. */
    if (!(x[3] != 0)) return fail(lx->w, "sphere radius must not be 0", lx->tok);
    add_sphere(s, v3(x[0], x[1], x[2]), fabs(x[3]), mat);
    return 1;
}

/* c: base centre and radius, apex centre and radius. */
static int nff_cone(Scene *s, Lexer *lx, int mat)
{
    real x[8];
    if (!nff_numbers(lx, "c", 8, x)) return 0;
    if (x[3] < 0 && x[7] < 0) {   /* seen only from inside, as a sphere's negative radius */
        x[3] = -x[3];
        x[7] = -x[7];
    }
    return check_cone(s, lx->w, x, mat);
}

/* The rest of a byte order mark, whose first byte is lx->c. */
static int skip_bom(Lexer *lx)
{
    int b1 = getc(lx->f), b2 = getc(lx->f);
    if (b1 != (unsigned char)BOM[1] || b2 != (unsigned char)BOM[2])
        return fail(lx->w, "not an NFF file: it starts with byte 0xEF, yet no UTF-8 byte order mark",
                    NULL);
    lx->c = getc(lx->f);
    return 1;
}

static int load_nff(Scene *s, FILE *f, Where w)
{
    Lexer lx;
    int mat = -1, k, ok = 1, got = 1;
    double intensity;
    lx.f = f; lx.w = w; lx.w.line = 1; lx.c = getc(f); lx.prev = 0; lx.again = 0;
    if (lx.c == (unsigned char)BOM[0] && !skip_bom(&lx)) return 0;
    s->tir_reflect = 1;                          /* the SPD's rule */
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

/* Does name end with ext (given in lower case), in any case? */
static int has_extension(const char *name, const char *ext)
{
    size_t n = strlen(name), k = strlen(ext), i;
    if (n < k) return 0;
    for (i = 0; i < k; i++)
        if (tolower((unsigned char)name[n - k + i]) != ext[i]) return 0;
    return 1;
}

/* The scene by its name: NFF when it ends .nff (or .NFF), else the sphere
 * format. */
static int load_scene(Scene *s, const char *file)
{
    Where w = { file, 0 };
    FILE *f = fopen(file, "r");
    int ok;
    default_scene(s);
    if (!f) return fail(w, "cannot open scene", strerror(errno));
    ok = has_extension(file, ".nff") ? load_nff(s, f, w) : load_sph(s, f, w);
    if (ok && ferror(f)) ok = fail(w, "read error", strerror(errno));
    fclose(f);
    return ok;
}

/* ------------------------------------------------------------------ output */

enum { FORMAT_PPM, FORMAT_PNG, FORMAT_PFM, FORMAT_OTHER };

/* The format -o asks for, by its extension: .png is PNG, .pfm PFM (floats,
 * the radiance itself); anything else is
 * PPM (.ppm, stdout, a device, a name without an extension), except the
 * image formats this program cannot write, which are refused rather than
 * given a PPM under their name. */
static int output_format(const char *name)
{
    static const char *const other[] = { ".jpg", ".jpeg", ".gif", ".bmp", ".tif", ".tiff",
                                         ".webp", ".tga", ".exr", ".hdr" };
    size_t i;
    if (has_extension(name, ".png")) return FORMAT_PNG;
    if (has_extension(name, ".pfm")) return FORMAT_PFM;
    for (i = 0; i < sizeof other / sizeof *other; i++)
        if (has_extension(name, other[i])) return FORMAT_OTHER;
    return FORMAT_PPM;
}

/* PNG (ISO/IEC 15948) without a compressor: the rows, each after filter
 * byte 0 ("none"), make a zlib stream (RFC 1950) of stored deflate blocks
 * (RFC 1951: a block's bytes as they are, after their count and its
 * complement), one IDAT chunk per block.  Each chunk ends with the CRC-32
 * of its type and data; the zlib stream ends with the Adler-32 of the rows. */
#define STORED_MAX 65535                  /* the most bytes a stored block holds */

typedef struct {
    FILE *f;
    unsigned long crc[256];               /* CRC-32 of each byte value */
    unsigned long a, b;                   /* Adler-32's two sums */
    unsigned char buf[2 + 5 + STORED_MAX + 4]; /* one IDAT chunk's data */
    size_t n, start;                      /* bytes in buf; where the block's bytes start */
} Png;

/* The table of CRC-32 (the polynomial of ISO 3309, bits reversed). */
static void crc_table(unsigned long t[256])
{
    unsigned long c;
    int n, k;
    for (n = 0; n < 256; n++) {
        for (c = (unsigned long)n, k = 0; k < 8; k++) c = c & 1 ? 0xEDB88320UL ^ c >> 1 : c >> 1;
        t[n] = c;
    }
}

static unsigned long crc_update(const unsigned long t[256], unsigned long crc,
                                const unsigned char *p, size_t n)
{
    while (n--) crc = t[(crc ^ *p++) & 0xFF] ^ crc >> 8;
    return crc;
}

/* Four bytes, most significant first, as PNG and zlib store numbers. */
static void put32(unsigned char *p, unsigned long v)
{
    p[0] = (unsigned char)(v >> 24 & 0xFF);
    p[1] = (unsigned char)(v >> 16 & 0xFF);
    p[2] = (unsigned char)(v >> 8 & 0xFF);
    p[3] = (unsigned char)(v & 0xFF);
}

/* One chunk: its length, type, data and CRC. */
static void png_chunk(Png *png, const char *type, const unsigned char *data, size_t n)
{
    unsigned char head[8], tail[4];
    put32(head, (unsigned long)n);
    memcpy(head + 4, type, 4);
    put32(tail, crc_update(png->crc, crc_update(png->crc, 0xFFFFFFFFUL, head + 4, 4), data, n)
                    ^ 0xFFFFFFFFUL);
    fwrite(head, 1, 8, png->f);
    fwrite(data, 1, n, png->f);
    fwrite(tail, 1, 4, png->f);
}

/* The block in buf as an IDAT chunk; the last one also closes the zlib
 * stream with its Adler-32.  The next block's header goes at buf[0]. */
static void png_block(Png *png, int last)
{
    size_t len = png->n - png->start;
    unsigned char *head = png->buf + png->start - 5;
    head[0] = (unsigned char)last;        /* BFINAL, and BTYPE 00: stored */
    head[1] = (unsigned char)(len & 0xFF);
    head[2] = (unsigned char)(len >> 8);
    head[3] = (unsigned char)(~len & 0xFF);
    head[4] = (unsigned char)(~len >> 8 & 0xFF);
    if (last) {
        put32(png->buf + png->n, png->b << 16 | png->a);
        png->n += 4;
    }
    png_chunk(png, "IDAT", png->buf, png->n);
    png->n = png->start = 5;
}

/* Bytes of the rows into the zlib stream, a stored block at a time. */
static void png_put(Png *png, const unsigned char *p, size_t n)
{
    while (n > 0) {
        size_t room = STORED_MAX - (png->n - png->start), k = n < room ? n : room, i;
        if (room == 0) { png_block(png, 0); continue; }
        for (i = 0; i < k; i++) {
            png->a = (png->a + p[i]) % 65521;
            png->b = (png->b + png->a) % 65521;
        }
        memcpy(png->buf + png->n, p, k);
        png->n += k;
        p += k;
        n -= k;
    }
}

/* An 8-bit RGB PNG; with srgb, it says its bytes are sRGB (the sRGB chunk,
 * and gAMA 1/2.2 for readers that know only that). 0: out of memory. */
static int write_png(FILE *f, const unsigned char *img, int w, int h, int srgb)
{
    static const unsigned char signature[8] = { 137, 'P', 'N', 'G', 13, 10, 26, 10 };
    unsigned char ihdr[13] = { 0 }, zero = 0, gamma[4];
    Png *png = malloc(sizeof *png);
    int j;
    if (!png) return 0;
    png->f = f;
    crc_table(png->crc);
    png->a = 1;
    png->b = 0;
    png->buf[0] = 0x78;                   /* zlib: deflate, 32K window; */
    png->buf[1] = 0x01;                   /* 0x7801 is a multiple of 31 */
    png->n = png->start = 2 + 5;
    fwrite(signature, 1, 8, f);
    put32(ihdr, (unsigned long)w);
    put32(ihdr + 4, (unsigned long)h);
    ihdr[8] = 8;                          /* bits per channel */
    ihdr[9] = 2;                          /* RGB; compression, filter, interlace 0 */
    png_chunk(png, "IHDR", ihdr, 13);
    if (srgb) {
        put32(gamma, 45455);
        png_chunk(png, "sRGB", &zero, 1); /* rendering intent 0, perceptual */
        png_chunk(png, "gAMA", gamma, 4);
    }
    for (j = 0; j < h; j++) {
        png_put(png, &zero, 1);           /* filter type 0, none */
        png_put(png, img + (size_t)3 * w * j, (size_t)3 * w);
    }
    png_block(png, 1);
    png_chunk(png, "IEND", png->buf, 0);
    free(png);
    return 1;
}

static void write_ppm(FILE *f, const unsigned char *img, int w, int h, int plain)
{
    size_t i, n = (size_t)w * h * 3;
    fprintf(f, "%s\n%d %d\n255\n", plain ? "P3" : "P6", w, h);
    if (plain)
        for (i = 0; i < n; i += 3) fprintf(f, "%d %d %d\n", img[i], img[i + 1], img[i + 2]);
    else
        fwrite(img, 1, n, f);
}

/* Where the image goes.  It is opened before the render, so that a bad -o
 * fails at once rather than after a long render.  A new or plain file is
 * written to a temporary file of this run's own beside it (FILE.tmp.PID),
 * which is renamed over FILE at the end: a failure or an interrupt never
 * leaves a half-written image, and keeps the old one.  Anything else
 * (stdout, a device such as /dev/null, a pipe, a symbolic link) is written
 * in place and never renamed over or removed. */
typedef struct { FILE *f; const char *name; char *tmp; int format; } Output;

/* The temporary file's name, for on_signal, which can be handed nothing:
 * the one global of ray.c (the card has its own).  It is written before the
 * handler is installed, and the handler only reads it. */
static char signal_tmp[4096];

/* Ctrl-C (SIGINT), SIGTERM, or a closed terminal (SIGHUP) during a render:
 * the temporary file is removed, then the signal raised again with its
 * default action, so that the program ends as that signal ends it (a shell
 * shows 128 + its number) and the old output stays.  Only calls that are
 * safe in a signal handler: unlink (remove, where there is no unlink),
 * signal and raise. */
static void on_signal(int sig)
{
#ifdef RAY_POSIX
    unlink(signal_tmp);
#else
    remove(signal_tmp);
#endif
    signal(sig, SIG_DFL);
    raise(sig);
}

/* Is sig ignored (as nohup, or a shell for a background job, leaves it)?
 * Then it stays ignored. */
static int ignored(int sig)
{
#ifdef RAY_POSIX
    struct sigaction sa;
    return sigaction(sig, NULL, &sa) == 0 && sa.sa_handler == SIG_IGN;
#else
    (void)sig;
    return 0;
#endif
}

/* on_signal for the temporary file tmp, or with tmp NULL the default
 * action again (the file is renamed into place, or gone).  A name too long
 * for signal_tmp, which no system takes, is left to the default action. */
static void catch_signals(const char *tmp)
{
#ifdef RAY_POSIX
    static const int sigs[] = { SIGINT, SIGTERM, SIGHUP };
#else
    static const int sigs[] = { SIGINT, SIGTERM };
#endif
    size_t i;
    if (tmp && strlen(tmp) >= sizeof signal_tmp) return;
    if (tmp) strcpy(signal_tmp, tmp);
    for (i = 0; i < sizeof sigs / sizeof *sigs; i++)
        if (!ignored(sigs[i])) signal(sigs[i], tmp ? on_signal : SIG_DFL);
}

/* Nothing but this run may have opened the file: created here (O_EXCL: not
 * if it exists, and never through a symbolic link), or NULL with errno
 * EEXIST.  Without POSIX, the best plain C can do: fail if it can be read. */
static FILE *create_new(const char *name)
{
#ifdef RAY_POSIX
    int fd = open(name, O_WRONLY | O_CREAT | O_EXCL, 0666);
    FILE *f = fd < 0 ? NULL : fdopen(fd, "wb");
    if (fd >= 0 && !f) { close(fd); unlink(name); }
    return f;
#else
    FILE *f = fopen(name, "rb");
    if (f) { fclose(f); errno = EEXIST; return NULL; }
    return fopen(name, "wb");
#endif
}

/* This process's number, to tell its temporary files from another run's. */
static long process_id(void)
{
#if defined(RAY_POSIX)
    return (long)getpid();
#elif defined(_WIN32)
    return (long)_getpid();
#else
    return (long)time(NULL);
#endif
}

/* A temporary file beside name that no other run shares: name.tmp.PID, or
 * name.tmp.PID.K when that exists (left by a run that was killed). */
static FILE *create_temp(const char *name, char **tmp)
{
    int k;
    FILE *f = NULL;
    *tmp = malloc(strlen(name) + 48);
    if (!*tmp) return NULL;
    for (k = 0; k < 100 && !f; k++) {
        if (k) sprintf(*tmp, "%s.tmp.%ld.%d", name, process_id(), k);
        else sprintf(*tmp, "%s.tmp.%ld", name, process_id());
        f = create_new(*tmp);
        if (!f && errno != EEXIST) break;
    }
    return f;
}

enum { IN_PLACE, VIA_TEMP, REFUSED };

#ifdef RAY_POSIX
/* How -o FILE is written: a plain file or a new one through a temporary
 * (*mode: the old file's permissions, which the new one keeps; -1 for a new
 * file), anything else in place.  A read-only file is refused, with a
 * message: replacing it would defeat its protection (root may write any
 * file, so its mode bits are asked too). */
static int output_kind(const char *name, int *mode)
{
    struct stat st;
    *mode = -1;
    if (lstat(name, &st) != 0) return errno == ENOENT ? VIA_TEMP : IN_PLACE;
    if (!S_ISREG(st.st_mode)) return IN_PLACE;
    if (access(name, W_OK) != 0 || !(st.st_mode & (S_IWUSR | S_IWGRP | S_IWOTH))) {
        fprintf(stderr, "%s: is read-only; not replaced (make it writable, or write elsewhere)\n",
                name);
        return REFUSED;
    }
    *mode = (int)(st.st_mode & 07777);
    return VIA_TEMP;
}
#else
static int output_kind(const char *name, int *mode)
{
    FILE *f = fopen(name, "rb");
    *mode = -1;
    if (f) {
        fclose(f);
        f = fopen(name, "r+b");     /* opens for writing without changing it */
        if (!f) {
            fprintf(stderr, "%s: is read-only; not replaced (make it writable, or write elsewhere)\n",
                    name);
            return REFUSED;
        }
        fclose(f);
    }
    return VIA_TEMP;
}
#endif

/* Opens -o name for writing (see Output).  0 after a message. */
static int open_output(Output *o, const char *name)
{
    int mode, kind;
    o->name = name;
    o->tmp = NULL;
    o->f = stdout;
    o->format = strcmp(name, "-") ? output_format(name) : FORMAT_PPM;
    if (!strcmp(name, "-")) {
#ifdef _WIN32
        _setmode(_fileno(stdout), _O_BINARY);    /* P6 and PNG bytes as they are: no \r added */
#endif
        return 1;
    }
    kind = output_kind(name, &mode);
    if (kind == REFUSED) return 0;
    o->f = kind == VIA_TEMP ? create_temp(name, &o->tmp) : fopen(name, "wb");
#ifdef RAY_POSIX
    if (o->f && mode >= 0) fchmod(fileno(o->f), (mode_t)mode);
#endif
    if (o->f) {
        if (o->tmp) catch_signals(o->tmp);
        return 1;
    }
    fprintf(stderr, "%s: cannot write: %s\n", o->tmp ? o->tmp : name, strerror(errno));
    free(o->tmp);
    return 0;
}

/* Gives up an output: nothing is left of it. */
static void discard_output(Output *o)
{
    if (o->f != stdout) fclose(o->f);
    if (o->tmp) remove(o->tmp);
    if (o->tmp) catch_signals(NULL);
    free(o->tmp);
}

/* PFM, netpbm's floating-point format: "PF" (colour), the size, and -1 for
 * little-endian floats; then the rows from the bottom up. */
static void write_pfm(FILE *f, const Image *img)
{
    int i, j, c;
    fprintf(f, "PF\n%d %d\n-1.0\n", img->w, img->h);
    for (j = img->h - 1; j >= 0; j--)
        for (i = 0; i < 3 * img->w; i++) {
            float x = img->floats[(size_t)j * 3 * img->w + i];
            uint32_t u;
            unsigned char b[4];
            memcpy(&u, &x, 4);
            for (c = 0; c < 4; c++) b[c] = (unsigned char)(u >> 8 * c);
            fwrite(b, 1, 4, f);
        }
}

/* rename() over an existing file: POSIX replaces it in one step; Windows
 * refuses, so there the old file is removed first (for a moment there is
 * neither: the best plain C can do). */
static int replace_file(const char *from, const char *to)
{
#ifdef _WIN32
    remove(to);
#endif
    return rename(from, to);
}

/* The image in the output's format, then the file closed and, if it was
 * written as a temporary, renamed into place; on failure a message and no
 * file.  A PNG of sRGB bytes says so. */
static int write_image(Output *o, const Image *img, int plain)
{
    int ok = 1;
    errno = 0;
    if (o->format == FORMAT_PFM) write_pfm(o->f, img);
    else if (o->format == FORMAT_PNG) {
        ok = write_png(o->f, img->bytes, img->w, img->h, img->srgb);
        if (!ok) errno = ENOMEM;
    } else
        write_ppm(o->f, img->bytes, img->w, img->h, plain);
    ok = ok && fflush(o->f) == 0 && !ferror(o->f);
    if (o->f != stdout) ok = fclose(o->f) == 0 && ok;
    if (ok && o->tmp) ok = replace_file(o->tmp, o->name) == 0;
    if (!ok) {
        fprintf(stderr, "%s: cannot write: %s\n", o->name, strerror(errno));
        if (o->tmp) remove(o->tmp);
    }
    if (o->tmp) catch_signals(NULL);
    free(o->tmp);
    return ok;
}

/* ------------------------------------------------------------ command line */

static void usage(FILE *to)
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
          "  -t N       threads (default: all cores, when built with OpenMP)\n"
          "  --pt       path tracing (Kajiya's rendering equation); --whitted: Whitted's\n"
          "             (default: the scene's `integrator`, else Whitted)\n"
          "  --estimator E  the path tracer's: bsdf (BSDF sampling only), nee (next-event\n"
          "             estimation) or mis (both, by multiple importance sampling; default)\n"
          "  --no-roulette  no Russian roulette: paths end at -d only\n"
          "  --seed N   the path tracer's noise (default 0): another N, other noise\n"
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
          "  --stats    print rays by kind, hits, the tree and time on stderr\n"
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
    printf("ray " RAY_VERSION ", Whitted ray tracer in C99 (%s, %s)\n",
           sizeof(real) == sizeof(float) ? "float" : "double", threads);
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
    if (!strcmp(v, "steps")) return VIEW_STEPS;
    if (!strcmp(v, "normal")) return VIEW_NORMAL;
    if (strcmp(v, "depth")) {
        fprintf(stderr, "ray: --view takes steps, normal or depth, not %s\n", v);
        exit(2);
    }
    return VIEW_DEPTH;
}

/* The path tracer's estimator named by --estimator, or exit with the choices. */
static int estimator_arg(const char *v)
{
    if (!strcmp(v, "bsdf")) return BSDF_ONLY;
    if (!strcmp(v, "nee")) return NEE;
    if (strcmp(v, "mis")) {
        fprintf(stderr, "ray: --estimator takes bsdf (BSDF sampling only), nee (next-event"
                " estimation) or mis, not %s\n", v);
        exit(2);
    }
    return MIS;
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

static char *default_output(const char *scene)
{
    const char *base = file_part(scene), *dot = strrchr(base, '.');
    char *out;
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

/* Whether every object lies within the range the structures' float boxes
 * and planes can hold (they clamp beyond FLT_MAX), with float precision to
 * spare: coordinates below 1e37, and a scene that reaches beyond 1e-30
 * of the origin (nearer, floats lose their bits to denormals). */
static int float_range(const Scene *s)
{
    double lo[3], hi[3], big = 0;
    int i, a;
    for (i = 0; i < nobj(s); i++) {
        prim_bounds((void *)s, i, lo, hi);
        for (a = 0; a < 3; a++) big = fmax(big, fmax(fabs(lo[a]), fabs(hi[a])));
    }
    return nobj(s) == 0 || (big < 1e37 && big > 1e-30);
}

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
    s->prims.eps = REAL_EPS;              /* the hit callback's arithmetic (prims.h) */
    s->accel = ACCEL_NONE;
    if (!strcmp(accel, "none") || (!strcmp(accel, "auto") && nobj(s) < TREE_FROM)) return 1;
    if (!float_range(s)) {
        fprintf(stderr, "ray: warning: coordinates beyond the float range the structures keep their"
                " boxes and planes in (above 1e37, or a scene within 1e-30 of the origin): every ray"
                " tests every object instead\n");
        return 1;
    }
    if (!strcmp(accel, "auto")) ok = choose_accel(s);
    else ok = build_one(s, !strcmp(accel, "bvh") ? ACCEL_BVH : !strcmp(accel, "grid") ? ACCEL_GRID : ACCEL_KD);
    if (!ok) fprintf(stderr, "ray: out of memory for the acceleration structure\n");
    return ok;
}

static void print_stats(const Scene *s, const Counts *st, int spp, double load, double build,
                        double seconds, double cpu)
{
    static const char *const estimators[] = { "BSDF sampling only", "next-event estimation",
                                              "MIS (BSDF sampling and next-event estimation)" };
    unsigned long long rays = st->primary + st->shadow + st->reflected + st->refracted + st->bounced;
    fprintf(stderr, "scene      %d spheres, %d cones, %d triangles, %d lights; read in %.3f s\n",
            s->nsph, s->ncone, s->ntri, s->nlight, load);
    if (s->integrator == PATH)
        fprintf(stderr, "image      %dx%d, %d spp, path traced, %d thread%s\n", s->w, s->h, spp,
                st->threads, st->threads == 1 ? "" : "s");
    else
        fprintf(stderr, "image      %dx%d, %d spp, depth %d, %d thread%s\n", s->w, s->h, spp,
                s->depth, st->threads, st->threads == 1 ? "" : "s");
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
    if (s->integrator == PATH) {
        char bound[32] = "none but roulette";
        if (s->max_rays) sprintf(bound, "%d rays", s->max_rays);
        fprintf(stderr, "paths      %s, roulette %s, length bound %s, seed %u, %d lights\n",
                estimators[s->estimator], s->roulette ? "on" : "off", bound, s->seed, s->nemit);
        fprintf(stderr, "rays       %llu: %llu primary, %llu shadow, %llu bounced\n",
                rays, st->primary, st->shadow, st->bounced);
        fprintf(stderr, "samples    %llu discarded (not finite)\n", st->discarded);
    } else
        fprintf(stderr, "rays       %llu: %llu primary, %llu shadow, %llu reflected, %llu refracted\n",
                rays, st->primary, st->shadow, st->reflected, st->refracted);
    if (s->integrator != PATH && st->cut)
        fprintf(stderr, "budget     %llu reflected or refracted rays not traced: past %d a primary ray\n",
                st->cut, RAY_BUDGET);
    fprintf(stderr, "hits       %llu (%.1f%% of the rays that ask for the nearest hit)\n", st->hits,
            st->nearest ? 100.0 * st->hits / (double)st->nearest : 0.0);
    fprintf(stderr, "per ray    %.2f intersection tests, %.2f tree steps\n",
            st->queries ? (double)st->tests / st->queries : 0.0,
            st->queries ? (double)st->steps / st->queries : 0.0);
    fprintf(stderr, "time       %.3f s, %.2f Mrays/s (CPU %.3f s, all threads)\n", seconds,
            seconds > 0 ? rays / seconds * 1e-6 : 0.0, cpu);
}

static void free_scene(Scene *s)
{
    if (s->kd) kd_free(s->kd);
    if (s->bvh) bvh_free(s->bvh);
    if (s->grid) grid_free(s->grid);
    free(s->mat); free(s->sph); free(s->cone); free(s->tri);
    free(s->vert); free(s->norm); free(s->light);
    free(s->emit); free(s->emit_cdf); free(s->emitter);
}

/* The command line's choices for the path tracer (-1: not given) onto the
 * scene, and its lights; 0 with a message when they cannot work. */
static int settle_path_options(Scene *s, int integrator, int estimator, int roulette, long seed)
{
    if (integrator >= 0) s->integrator = integrator;
    if (estimator >= 0) s->estimator = estimator;
    if (seed >= 0) s->seed = (unsigned)seed;
    s->roulette = roulette;
    if (s->integrator != PATH) return 1;
    if (!roulette && !s->max_rays) {
        fprintf(stderr, "ray: --no-roulette needs -d N: without either, paths would not end\n");
        return 0;
    }
    prepare_lights(s);
    return 1;
}

/* An image of w x h pixels, floats or bytes (through the sRGB curve for a
 * path-traced one, and with --gamma). */
static int new_image(Image *img, int w, int h, int floats, int srgb)
{
    img->w = w;
    img->h = h;
    img->srgb = srgb;
    img->bytes = floats ? NULL : malloc((size_t)w * h * 3);
    img->floats = floats ? malloc((size_t)w * h * 3 * sizeof *img->floats) : NULL;
    return img->bytes || img->floats;
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

int main(int argc, char **argv)
{
    Scene s;
    Options o = { 0, 0, 0, 0 };
    Counts st;
    Output out;
    Image img;
    const char *scene = NULL, *size = NULL, *accel = NULL, *name = NULL;
    char *auto_name = NULL;
    int i, depth = 0, plain = 0, stats = 0, gamma = 0, ok, w = 0, h = 0, integrator = -1;
    int estimator = -1, roulette = 1, view = 0;
    long seed = -1;
    double t0, load, build;
    clock_t c0;

    for (i = 1; i < argc; i++) {
        const char *a = argv[i], *v;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) { usage(stdout); return 0; }
        else if (!strcmp(a, "--version")) { version(); return 0; }
        else if ((v = option_value(argc, argv, &i, "-o"))) name = v;
        else if ((v = option_value(argc, argv, &i, "-s"))) size = v;
        else if ((v = option_value(argc, argv, &i, "-n"))) o.spp = int_arg("-n", v, 1 << 20);
        else if ((v = option_value(argc, argv, &i, "-d"))) depth = int_arg("-d", v, 64);
        else if ((v = option_value(argc, argv, &i, "-t"))) o.threads = int_arg("-t", v, 4096);
        else if ((v = option_value(argc, argv, &i, "--accel"))) accel = accel_arg(v);
        else if (!strcmp(a, "--p3")) plain = 1;
        else if (!strcmp(a, "--gamma")) gamma = 1;
        else if (!strcmp(a, "--stats")) stats = 1;
        else if ((v = option_value(argc, argv, &i, "--view"))) view = view_arg(v);
        else if (!strcmp(a, "--pt")) integrator = PATH;
        else if (!strcmp(a, "--whitted")) integrator = WHITTED;
        else if (!strcmp(a, "--no-roulette")) roulette = 0;
        else if ((v = option_value(argc, argv, &i, "--seed"))) seed = int_arg("--seed", v, 2147483647) - 1;
        else if ((v = option_value(argc, argv, &i, "--estimator"))) estimator = estimator_arg(v);
        else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "ray: unknown option: %s\n", a);
            usage(stderr);
            return 2;
        } else if (scene) {
            fprintf(stderr, "ray: one scene only (%s and %s)\n", scene, a);
            return 2;
        }
        else scene = a;
    }
    if (!scene) { usage(stderr); return 2; }
    if (!name) name = auto_name = default_output(scene);
    if ((size && !parse_size(size, &w, &h)) || !output_usable(name, plain)
        || !apart(scene, name)) {
        free(auto_name);
        return 2;
    }
    warn_threads(o.threads);
    load = now();
    ok = load_scene(&s, scene);
    if (ok && size) { s.w = w; s.h = h; }
    load = now() - load;
    if (ok && nobj(&s) == 0) fprintf(stderr, "%s: warning: the scene has no objects\n", scene);
    if (depth) s.depth = s.max_rays = depth;
    if (!accel) accel = s.accel_line ? s.accel_line : "auto";
    if (ok && !settle_path_options(&s, integrator, estimator, roulette, seed)) ok = 0;
    if (!o.spp) o.spp = s.spp ? s.spp : 1;
    build = now();
    ok = ok && build_accel(&s, accel);
    build = now() - build;
    if (!ok || !open_output(&out, name)) { free_scene(&s); free(auto_name); return 1; }

    s.view = view;
    if (view == VIEW_DEPTH) s.far = farthest(&s);
    if (!new_image(&img, s.w, s.h, out.format == FORMAT_PFM, !view && (s.integrator == PATH || gamma))) {
        fprintf(stderr, "ray: out of memory for a %dx%d image\n", s.w, s.h);
        discard_output(&out);
        free_scene(&s); free(auto_name);
        return 1;
    }
    o.progress = stderr_is_terminal();
    memset(&st, 0, sizeof st);
    if (s.integrator == PATH ? s.warning[0] : s.whitted_warning[0])
        fprintf(stderr, "%s\n", s.integrator == PATH ? s.warning : s.whitted_warning);
    t0 = o.start = now();
    c0 = clock();
    render(&s, &o, &img, &st);
    t0 = now() - t0;
    ok = write_image(&out, &img, plain);
    if (stats) print_stats(&s, &st, o.spp, load, build, t0, (double)(clock() - c0) / CLOCKS_PER_SEC);
    free(img.bytes);
    free(img.floats);
    free(auto_name);
    free_scene(&s);
    return ok ? 0 : 1;
}

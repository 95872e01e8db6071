/* ray.c - the lecture "Ray Tracing + Global Illumination" as one C file:
 * Whitted's recursive ray tracer and Kajiya's path tracer side by side,
 * spheres, cones and triangles, and the structures that find hits (kdtree.c,
 * bvh.c, grid.c) and photons (photons.c).  Everything a ray meets is here; reading scenes
 * (scene.c), writing images (image.c) and the command line (cli.c, whose
 * `./ray --help` lists the options) live beside it.
 *
 *     make && ./ray -s 640x480 -n 4 scenes/whitted.sph      (writes whitted.ppm)
 *     ./ray scenes/cornell.sph                              (path traced)
 *
 * HOW TO READ IT.  The lecture comes first, in the order a ray meets it:
 * the types, the vectors, a table of contents (the prototypes), then
 * "for each pixel", the samples (the points of a pixel, its instants of
 * the shutter for motion blur, random numbers by fixed dimension, and the
 * warps that turn them into points and directions, each with its pdf),
 * the camera, RayTrace(R) (Whitted), L = Le + integral f L cos (Kajiya),
 * finding hits (with moving objects: each ray meets them where they are
 * at its time), and the primitives.
 * After the line THE PLUMBING come threads and render()'s hooks, --view,
 * the builder that scene.c fills a Scene through, --stats and main(); a
 * student can stop reading there.
 *
 * Whitted's reader may skip the samples but for sample_offset (the R2
 * pattern), and all of "L = Le + integral f L cos"; the path tracer's
 * reader may skip "RayTrace(R)".
 *
 * The lecture's pseudo-code, and the functions that do it:
 *
 *     for each pixel                        render_row(), pixel_color()
 *         compute the ray R from the eye    primary_ray(): camera_ray(), through_lens()
 *         pixel colour = RayTrace(R)        trace()
 *
 *     RayTrace(R):                          trace()
 *         find the nearest hit              nearest_hit()
 *           (t, point, object, normal)        fill_hit()
 *         colour = black (or background)
 *         if there is a hit                 shade()
 *             for each light                   shadow_ray(); area_lights()
 *                 a ray to the light; does it hit anything?   any_hit()
 *                 if not, add the light's share    lit_by()
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
 * Two routes through the file, function by function.  Each function is
 * defined below the one before it, except those marked ^, which a reader
 * finds further up (tools/route.sh counts them).
 *
 * One primary ray of Whitted's, from main() to its pixel's byte (7 marked
 * ^ of 26):
 *
 *       main()            reads the scene, builds the tree          (plumbing)
 *     ^ render()          shares the rows out among threads         (plumbing)
 *     ^ render_row()      for each pixel of a row                   for each pixel
 *       pixel_color()     averages the pixel's samples
 *       sample_offset()   where sample k lies in the pixel          samples
 *       primary_ray()     the ray R from the eye through it         the camera
 *       camera_ray()      (through_lens() for a lens)
 *       trace()           RayTrace(R)                               RayTrace(R)
 *       nearest_hit()     the nearest hit                           finding hits
 *       query()           the record the tree hands back
 *       find_nearest()    asks the structure (kd_nearest, bvh_nearest or grid_nearest), or every object
 *       prim_hit()        the tree's call for one object of a leaf
 *       kind()            sphere, cone or triangle
 *       hit_object()      its intersection test
 *       hit_sphere()      (or hit_cone(), hit_triangle())           the primitives
 *     ^ fill_hit()        point, normals, material of the hit       finding hits
 *       sphere_surface()  (or cone_surface(), triangle_surface())   the primitives
 *     ^ shade()           the light at the hit                      RayTrace(R)
 *       reflect()         the mirror direction (for the highlight)
 *     ^ shadow_ray()      towards each light
 *       (lit_by(), area_lights() for a glowing sphere or triangle)
 *       spawn()           the ray leaves the surface                finding hits
 *       any_hit()         is anything in the way?
 *       find_any()        asks the tree, or every object
 *     ^ worth_tracing()   is the reflected ray worth it?            RayTrace(R)
 *       (trace() again for the reflected ray, from the top)
 *       refract()         Snell's law, then trace() again
 *     ^ to_byte()         the pixel's colour to a byte              for each pixel
 *       write_image()     the image to its file                     (image.c)
 *
 * One path-traced sample, in the Cornell box (a triangle lit by a
 * triangle; 14 marked ^ of 50):
 *
 *       main(), ^ render(), ^ render_row()                          as above
 *       pixel_radiance()  the mean of the pixel's samples           Kajiya
 *       sample_radiance() one camera ray through a random point of the pixel
 *     ^ start_sample()    the sample's numbers                      samples
 *       random01()        one number, by its dimension
 *       sample_offset()   the R2 point, shifted by the pixel's own offset
 *       primary_ray(), camera_ray()   the ray R                     the camera
 *       radiance()        L(x, wo)                                  Kajiya
 *       nearest_hit() ... hit_triangle()   as Whitted's, above      finding hits
 *     ^ fill_hit(), triangle_surface()                              finding hits
 *     ^ emitted()         Le, weighed for the estimator             Kajiya
 *       front_emits()     a one-sided lamp from its front only
 *       bsdf_at()         the BSDF at the hit
 *     ^ sample_light()    next-event estimation
 *     ^ bounce_random()   this bounce's numbers                     samples
 *       choose_light()    a light, by what it may bring here        Kajiya
 *       node_weight(), importance()   down the light tree
 *       sample_emitter()  a point on it
 *       triangle_light_sample()  on the lamp's triangle             the primitives
 *       spherical_triangle()     as seen from the point
 *       spherical_triangle_sample()  a direction in it (Arvo)
 *       triangle_light_pdf()     and its pdf, in solid angle
 *     ^ light_choice()    the chance it was chosen                  Kajiya
 *       bsdf_eval()       f there
 *     ^ light_visible()   the shadow ray: is the light seen?
 *       spawn(), any_hit(), find_any()                              finding hits
 *     ^ power_heuristic() MIS's weight                              Kajiya
 *       bsdf_pdf()        the BSDF's pdf of the light's direction
 *     ^ cosine_hemisphere_pdf()                                     samples
 *       sample_bsdf()     the next direction                        Kajiya
 *     ^ cosine_hemisphere(), uniform_disc()   Malley's method       samples
 *     ^ from_local()      into the surface's frame
 *       survives()        Russian roulette                          Kajiya
 *       (radiance() again for the next ray, from the top)
 *     ^ put_pixel(), srgb(), to_byte()                              for each pixel
 *
 * Build options: -DREAL=float makes every vector float instead of double
 * (the benchmark compares both); -fopenmp renders rows in parallel.  Output
 * is the same bytes for any number of threads, because no pixel depends on
 * another or on the order pixels are computed in.
 */

/* Unix gets a progress line when stderr is a terminal and a wall clock for
 * --stats (posix.h); elsewhere the program is plain C99 and does without. */
#include "posix.h"
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <stdint.h>
#include <string.h>
#include <time.h>
#include "prims.h"
#include "kdtree.h"
#include "bvh.h"
#include "grid.h"
#include "photons.h"
#include "scene.h"
#include "image.h"
#include "cli.h"
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
 * minray's spheres do not); with spread (the sphere format's `glossy`)
 * Whitted's mirror ray spreads into the same lobe.  rough > 0 (a scene's
 * `rough` line) makes the path tracer's ks a rough microfacet surface of
 * that GGX alpha instead of a mirror: a conductor, or over kd a coat
 * (bsdf_at); Whitted's ignores it. */
typedef struct { vec color; real kd, ks, kt, kl, ir, shine, rough; int spread; } Material;

/* Every object may move during the shutter (motion blur): at time t it
 * stands where it was made plus t times its move, a velocity (0: at rest). */
typedef struct { vec cen; real rad; int mat; vec move; } Sphere;

/* An open cone or cylinder (NFF's `c`): no end caps.  The radius runs from
 * rb at the base to ra at the other end, along the unit axis. */
typedef struct { vec base, axis; real len, rb, ra; int mat; vec move; } Cone;

/* Vertices and normals are indices into the scene's shared arrays, so two
 * triangles that share an edge share its exact coordinates.  The hit test
 * needs the first vertex and the two edges from it; they are kept here too,
 * computed once (the same values, so the same answers), so that a test
 * reads one record rather than three vertices.  What the test reads comes
 * first, the flags too: 128 bytes in double, of which the test reads the
 * first 74, two cache lines (three when the flags came last). */
typedef struct {
    vec v0, e1, e2;      /* vert[v[0]], vert[v[1]] - v0, vert[v[2]] - v0 */
    char cull;           /* 1: one-sided, hit from the front only */
    char degenerate;     /* zero area: never hit */
    int v[3], n[3];      /* n[0] < 0: no vertex normals, shade flat */
    int mat;
    vec move;            /* its velocity during the shutter (0: at rest) */
} Triangle;

/* A light is either one of minray's emitting spheres (sphere >= 0: lit when
 * the nearest thing toward its centre is that sphere) or a point light
 * (sphere < 0: lit when nothing lies between). */
typedef struct { vec pos, color; int sphere; } Light;

typedef struct {
    vec eye, right, up, fwd;  /* orthonormal frame */
    real tan_half;            /* tan(fov / 2); fov: horizontal, edge to edge */
    real anchor;              /* 0.5: samples centred on the pixel; 0: on its corner */
    real hither;              /* near clip: nothing nearer than this plane is seen, */
    int hither_sphere;        /* or, if set, nearer than this distance from the eye */
    real lens, focus;         /* a thin lens: its radius (0: a pinhole), and the distance
                               * of the plane it brings into focus */
} Camera;

/* A light as the path tracer samples it (sample_light): a point light, an
 * emitting sphere or triangle (object obj), or the sky: the background seen
 * as a uniform radiance from every direction. */
enum { POINT_LIGHT, SPHERE_LIGHT, TRIANGLE_LIGHT, SKY_LIGHT };
typedef struct {
    int type, obj;
    vec pos, intensity;       /* a point light's place and intensity I (radiance: I / d^2) */
    int inward;               /* a sphere that light paths leave inward too (see inside_seen) */
    int clip, nclips;         /* a sphere: its clips, Lights' clip[clip .. clip + nclips - 1] */
} Emitter;

/* An opaque sphere (obj) that cuts a glowing sphere, as smallpt's ceiling
 * cuts its lamp: seen from the lamp's centre, the lamp's part inside it is
 * the cap of directions u with u . axis >= 1 - in (axis towards the
 * sphere's centre), the part outside it the cap u . axis <= out - 1.  A
 * point inside the sphere can see only the first, a point outside only the
 * second: the way to the other crosses the sphere's opaque surface
 * (visible_cap). */
typedef struct { int obj; vec axis; real in, out; } Clip;

/* A Scene holds four things, each of its own: what the file describes
 * (the objects, the camera, the lights as Whitted sees them), the render's
 * settings (from the file and the command line), the path tracer's lights
 * (made by prepare_lights), and the structure that finds hits (made by
 * build_accel). */

/* The render's settings. */
typedef struct {
    int w, h;                 /* the image, in pixels */
    int integrator;           /* WHITTED or PATH */
    int depth;                /* Whitted: the recursion's depth */
    int max_rays;             /* path tracing: rays on a path at most (-d); 0: no bound but roulette */
    int spp;                  /* samples per pixel the scene asks for (0: none said) */
    int estimator;            /* the path tracer's: BSDF_ONLY, NEE, MIS, LIGHT_TRACING, BDPT, PHOTON_MAPPING
                               * or PROGRESSIVE */
    int strategy[2];          /* --strategy S,T: BDPT's one strategy shown ({-1, -1}: all) */
    int roulette;             /* 1: Russian roulette ends paths */
    unsigned seed;            /* --seed: which noise */
    int view;                 /* --view: VIEW_STEPS, VIEW_NORMAL, VIEW_DEPTH, VIEW_SAMPLES, VIEW_PHOTONS, or 0 */
    real adaptive;            /* --adaptive E: a pixel stops when its byte is known to E steps (0: off) */
    int srgb;                 /* the bytes go through the sRGB curve (for adaptive's rule) */
    int no_skip;              /* --no-skip: no work skipped that the plain algorithm does */
    int sampler;              /* the path tracer's numbers: INDEPENDENT or SOBOL (--sampler) */
    int light_choice;         /* how sample_light picks a light: BY_IMPORTANCE or BY_POWER */
    int photons;              /* --photons N: photon mapping's photons (progressive: a pass's) */
    real far;                 /* --view depth: the farthest point of the scene from the eye */
    int x0, y0, x1, y1;       /* the pixels rendered, x0 <= x < x1, y0 <= y < y1: the whole
                               * image, or a part of it (--crop, --tile) */
    int s0;                   /* the first sample rendered of each pixel (--samples A:B: A) */
    const char *accel_line;   /* the scene's `accel NAME` line, or NULL */
} Settings;

/* A node of the light tree (prepare_lights): what every light below it
 * shares, bounded so that importance() can say what they may bring to a
 * point.  A leaf holds one light. */
typedef struct {
    vec lo, hi;               /* a box holding them (swept, if they move), */
    vec centre; real r2;      /* and the sphere about it (sphere_of_box) */
    vec axis;                 /* every normal lies within theta_o of the axis */
    real cos_o, sin_o;        /* theta_o (pi: any direction) */
    real cos_e;               /* and each emits within theta_e of its normal */
    int two_sided;            /* 1: some emit from both sides of their normal */
    real power;               /* their power (luminance), together */
    int child[2];             /* the two halves, or -1 for a leaf */
    int parent, light;        /* its parent (-1: the root); a leaf's light */
} LightNode;

/* The path tracer's lights, and how sample_light chooses one: the sky
 * half the time (when there are others), else down the light tree. */
typedef struct {
    Emitter *emit;  int nemit;
    int sky;                  /* the sky's light, or -1 */
    LightNode *node;          /* the light tree of every light but the sky: */
    int nnode, root;          /* node[root] its root (-1: no such light) */
    int *leaf;                /* leaf[l]: light l's node */
    int *emitter;             /* emitter[object]: its light, or -1 */
    Clip *clip; int nclip;    /* the opaque spheres that cut glowing ones (find_clips) */
} Lights;

/* The structure that finds hits. */
typedef struct {
    int which;                /* an ACCEL_ below */
    kd_tree *kd;              /* the kd-tree, when which is ACCEL_KD */
    bvh *bvh;                 /* the BVH, when ACCEL_BVH */
    grid *grid;               /* the grid, when ACCEL_GRID */
    prims prims;              /* how the structure sees the objects (prims.h) */
} Structure;

typedef struct {
    Material *mat;  int nmat, capmat;
    Sphere *sph;    int nsph, capsph;
    Cone *cone;     int ncone, capcone;
    Triangle *tri;  int ntri, captri;
    vec *vert;      int nvert, capvert;
    vec *norm;      int nnorm, capnorm;
    Light *light;   int nlight, caplight;
    Camera cam;
    vec ambient, background;
    int tir_reflect;          /* Whitted: past the critical angle kt goes to the mirror */
    int lights_centre;        /* Whitted: glowing spheres light from their centres (the card's) */
    int shadow_rays;          /* Whitted: shadow rays to each area light, a sample */
    int cull;                 /* while reading: `sided 1` for the triangles still to come */
    real glossy;              /* while reading: `glossy S` for the materials still to come */
    int frame;                /* an OBJ file alone: frame_mesh() sets the camera and a light */
    vec move;                 /* while reading: `move` for the objects still to come */
    real shutter[2];          /* the shutter opens at shutter[0], closes at shutter[1] */
    int moving;               /* how many objects move (0: no time is ever drawn) */
    real rough;               /* while reading: `rough A` for the materials still to come */
    char warning[256];        /* said once when the path tracer starts, if set */
    char whitted_warning[256];  /* the same for Whitted's */
    Settings set;
    Lights lights;
    Structure accel;
} Scene;

/* --accel none: every ray tests every object; kd: the kd-tree of kdtree.c;
 * bvh: the bounding volume hierarchy of bvh.c; grid: the uniform grid of
 * grid.c. */
enum { ACCEL_NONE, ACCEL_KD, ACCEL_BVH, ACCEL_GRID };

/* Whitted's recursive ray tracing, or Kajiya's path tracing; and the path
 * tracer's three estimators of the light at a point: by sampling the BSDF
 * only, by next-event estimation, or by both weighed by MIS. */
enum { WHITTED, PATH };
enum { VIEW_STEPS = 1, VIEW_NORMAL, VIEW_DEPTH, VIEW_SAMPLES, VIEW_PHOTONS };
enum { BSDF_ONLY, NEE, MIS, LIGHT_TRACING, BDPT, PHOTON_MAPPING, PROGRESSIVE };
enum { INDEPENDENT, SOBOL };
enum { BY_IMPORTANCE, BY_POWER };

/* Objects are numbered spheres first, then cones, then triangles. */
enum { SPHERE, CONE, TRIANGLE };

static int nobj(const Scene *s) { return s->nsph + s->ncone + s->ntri; }
static void out_of_memory(void);        /* in the plumbing: says so, and exits */
static void *grow(void *p, int *cap, int need, size_t size);    /* the plumbing: room for one more */
static void add_light(Scene *s, vec pos, vec color, int sphere);  /* the plumbing: Whitted's lights */

/* A ray: origin o, direction d, and skip, an object it cannot hit (or -1).
 * A ray leaving a flat triangle, or a sphere outward, never meets that
 * surface again, yet it starts in the tree's cells that list it: skip spares
 * that test.  The tree leaves skip out itself (kd_nearest's skip); the loop
 * over every object checks it in hit_object.  tmin is 0 but for a camera
 * with a near clip (hither): hits at t <= tmin do not count.  time is the
 * instant of the shutter the ray was sent at: every ray a camera ray leads
 * to (shadow, reflected, bounced) keeps its camera ray's time. */
typedef struct { vec o, d; real tmin; int skip; real time; } Ray;

typedef struct {
    real t, time;       /* where on the ray, and the ray's time */
    int obj, mat;
    vec p;        /* the point */
    vec n, ng;    /* shading and geometric normal, both outward (front) */
    real error_scale;   /* the coordinates' magnitude that p's rounding error scales with */
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
    unsigned long long behind, faint, dim;      /* Whitted's skips: shadow rays to lights behind, */
                                                /* rays of too little weight (see worth_tracing), */
                                                /* shadow rays to lights too dim (see too_dim) */
    unsigned long long samples;                 /* samples the pixels took, all together; */
    int spp_min, spp_max;                       /* the fewest and most one pixel took (0: none yet) */
    int threads;                                /* how many threads rendered */
} Counts;

/* A thread's working state, handed down every call that traces a ray, as
 * smallpt hands down its per-row seed; never a global.  It holds the
 * thread's counts, the shadow cache of any_hit() (the last blocker of each
 * of the first SHADOW_SLOTS lights; lights further on share the slots,
 * which costs cache hits but never changes an answer), and where the path
 * tracer's random numbers stand. */
#define SHADOW_SLOTS 8
#define RAY_BUDGET 1024
/* A pixel's samples so far: their sum (exact, see tally()), the sum of
 * their squares (for --adaptive's error estimate), and how many. */
typedef struct Tally { Exact sum[3]; vec sq; int n; } Tally;         /* reflected and refracted rays a primary ray may spawn */
typedef struct {
    Counts count;
    int blocker[SHADOW_SLOTS];  /* light i's last blocker, or -1, in slot i % SHADOW_SLOTS */
    unsigned long long key;     /* the path tracer's random numbers: which sample, */
    int bounce;                 /* and which bounce its path is at (see random01); */
    unsigned long long pixel_key;   /* --sampler sobol: the pixel's own scramble, */
    int sample;                 /* and the sample's number in the pixel (-1: the pixel's) */
    int budget;                 /* Whitted: secondary rays the primary ray may still spawn */
    real dim_budget;            /* Whitted: what too_dim may still leave out of this sample */
    const struct Hooks *hooks;  /* render()'s hooks, or NULL (see Hooks) */
    long long *splat;           /* this thread's splat image (see splat()), or NULL */
    int taken;                  /* samples the last pixel took (--view samples) */
    const Tally *first;         /* Whitted's --adaptive: every pixel's first 4 samples, or NULL */
    Tally last;                 /* the last pixel's samples (for a partial render) */
    Partial *part;              /* a partial render's sums (image.h), or NULL */
} Worker;

/* Two hooks in render() for the integrators still to come.  prepass runs
 * once before the pixels (photon mapping shoots its photons there, into
 * data).  after_sample runs after each sample k of pixel (i, j) and may add
 * light to any pixel by splat() (light tracing's paths reach the camera
 * wherever they land, not in the pixel that started them).  Both NULL: a
 * plain render. */
typedef struct Hooks {
    void (*prepass)(const Scene *s, void *data);
    void (*after_sample)(const Scene *s, int i, int j, int k, Worker *wk, void *data);
    void *data;
} Hooks;

/* The image being made (image.h): bytes (for PPM and PNG), or floats (for
 * PFM and EXR), row by row from the top-left, three channels a pixel. */

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
static int nonzero(vec a) { return a.x != 0 || a.y != 0 || a.z != 0; }
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

/* Grows [lo, hi] to take in [lo2, hi2].  Written out, not as fmin and
 * fmax: the builds call it for every triangle, and those are library calls
 * on most targets.  On numbers the two agree, with glibc's
 * choice of the first when neither is smaller (+0 and -0); no NaN reaches
 * here (the readers take finite numbers only). */
static void box_union(double lo[3], double hi[3], const double lo2[3], const double hi2[3])
{
    int a;
    for (a = 0; a < 3; a++) {
        lo[a] = lo2[a] < lo[a] ? lo2[a] : lo[a];
        hi[a] = hi2[a] > hi[a] ? hi2[a] : hi[a];
    }
}

/* ------------------------------------------------------ table of contents */

/* The lecture's functions, in the order a ray meets them; each section
 * below defines them in this order. */

/* for each pixel */
static void render_row(const Scene *s, int j, int spp, Image *img, Worker *wk);
static vec pixel_color(const Scene *s, int i, int j, int spp, Worker *wk);
static const Tally *take_samples(const Scene *s, int i, int j, Tally *t, int n, Worker *wk);
static int neighbours_agree(const Scene *s, const Tally *first, int i, int j);
static void tally(Tally *t, vec c);
static vec tally_sum(const Tally *t);
static vec tally_mean(const Tally *t);
static int pixel_done(const Scene *s, const Tally *t, int first);
static int settled(const Scene *s, const Tally *t);
static real srgb_slope(real v);
static vec pixel_mean(const Tally *t, Worker *wk);
static void put_pixel(Image *img, int i, int j, vec c);
static real srgb(real v);
static unsigned char to_byte(real v);
static vec pixel_view(const Scene *s, int i, int j, Worker *wk);   /* --view, in the plumbing */
static void keep_sums(Partial *part, int i, int j, const Tally *t); /* a partial render: the plumbing */

/* samples: the points of a pixel, random numbers, the warps and their pdfs */
static void start_sample(Worker *wk, const Scene *s, int i, int j, int k);
static real random01(const Worker *wk, unsigned dim);
static double sobol01(const Worker *wk, unsigned dim);
static real bounce_random(const Worker *wk, int slot);
static void sample_offset(int k, real anchor, real *dx, real *dy);
static real time_shift(Worker *wk, const Scene *s, int i, int j);
static real shutter_time(const Scene *s, int k, real shift);
static vec from_local(vec n, vec l);
static vec to_local(vec n, vec w);
static vec cosine_hemisphere(real u1, real u2);
static real cosine_hemisphere_pdf(real cos_theta);
static vec phong_lobe(real shine, real u1, real u2);
static real phong_lobe_pdf(real shine, real cos_alpha);
static vec ggx_visible_normal(vec wo, real alpha, real u1, real u2);
static real ggx_visible_normal_pdf(real alpha, real cos_o, real cos_h, real o_dot_h);
static vec uniform_disc(real u1, real u2);
static real uniform_disc_pdf(void);
static vec sphere_cap(real cap, real u1, real u2);
static real sphere_cap_pdf(real cap);
static vec uniform_triangle(real u1, real u2);
static real uniform_triangle_pdf(real area);

/* the camera: the ray R from the eye */
static Ray primary_ray(const Scene *s, real x, real y, const Worker *wk);
static Ray camera_ray(const Camera *c, int w, int h, real x, real y);
static real near_clip(const Camera *c, vec d);
static Ray through_lens(const Camera *c, Ray r, real u1, real u2);
static int set_camera(Scene *s, const real *v, char *why);

/* RayTrace(R): Whitted's recursive ray tracing */
static vec trace(const Scene *s, Ray r, int depth, real weight, Worker *wk);
static vec shade(const Scene *s, Ray r, const Hit *h, int depth, real weight, Worker *wk);
static void lit_by(const Material *m, vec light, real e, vec dir, vec mirror, vec *color,
                   vec *spec);
static void area_lights(const Scene *s, const Hit *h, vec n, real weight, vec *color, Worker *wk);
static void area_point(const Worker *wk, int l, int q, real *u, real *v);
static vec glossy_mirror(vec mirror, real shine, const Worker *wk);
static int shadow_ray(const Scene *s, const Hit *h, vec n, const Light *l, real share, real *e,
                      vec *to_light, Worker *wk);
static int worth_tracing(const Scene *s, real k, real weight, int depth, Worker *wk);
static real dim_budget(const Scene *s);
static int too_dim(const Scene *s, real share, Worker *wk);
static real point_light_bound(const Material *m, const Light *l);
static real brightest(vec c);
static real area_light_bound(const Scene *s, const Material *m, int l, vec x);
static vec reflect(vec d, vec n, real cosi);
static int refract(vec d, vec n, real cosi, real eta, vec *t);

/* L = Le + integral f L cos: Kajiya's path tracing */
typedef struct Path Path;
typedef struct Bsdf Bsdf;
typedef struct Vertex Vertex;
/* Where a light path starts (emit_ray): the light's normal there (a point
 * light's: the direction it sent), what it emits (an area light's
 * radiance Le, a point light's intensity), and the pdfs of the point (per
 * area; 1 for a point light) and of the direction (per solid angle), which
 * bidirectional path tracing weighs its strategies with. */
typedef struct { vec n, emit; real pdf_point, pdf_dir; } Start;
static vec pixel_radiance(const Scene *s, int i, int j, int spp, Worker *wk);
static vec sample_radiance(const Scene *s, int i, int j, int k, Worker *wk);
static vec radiance(const Scene *s, Ray r, const Path *path, Worker *wk);
static int survives(const Scene *s, int rays, vec *beta, vec *f_cos_pdf, Worker *wk);
typedef struct Photons Photons;
static vec through_mirrors(const Scene *s, Ray r, const Photons *ph, Worker *wk);
static void splat(const Scene *s, Worker *wk, real x, real y, vec L);
static void trace_light_path(const Scene *s, int i, int j, int k, real time, Worker *wk);
static int emit_ray(const Scene *s, int l, real time, Worker *wk, Ray *r, vec *beta, Start *from);
static real light_area(const Scene *s, int l);
static void to_camera(const Scene *s, const Hit *h, const Bsdf *b, vec wl, vec beta, Worker *wk);
static int onto_film(const Scene *s, vec p, vec *wc, real *dist, real *x, real *y, real *pdf);
static int camera_sees(const Scene *s, vec wc, real dist, real time, Worker *wk);
static vec bdpt(const Scene *s, Ray r, Worker *wk);
static int chosen(const Scene *s, int k, int t);
typedef struct Subpaths Subpaths;
static int subpaths(const Scene *s, Ray r, Subpaths *p, Worker *wk);
static int walk(const Scene *s, Ray r, vec beta, real pdf, int most, int first, Vertex *v, Worker *wk,
                int *escaped);
static int light_subpath(const Scene *s, real time, Subpaths *p, Worker *wk);
static real to_area(real pdf, vec from, const Hit *to);
static real film_pdf(const Scene *s, vec d);
static vec met_light(const Scene *s, const Subpaths *p, int t);
static vec to_light(const Scene *s, const Subpaths *p, int t, Worker *wk);
static vec light_normal(const Scene *s, int l, vec y, real time);
static void to_eye(const Scene *s, const Subpaths *p, int k, Worker *wk);
static vec join(const Scene *s, const Subpaths *p, int k, int t, Worker *wk);
typedef struct Rev Rev;
static Rev join_rev(const Subpaths *p, int k, int t, vec wi);
static real mis_weight(const Subpaths *p, const Vertex *y, int k, int t, Rev rev, int point);
static real over(real rev, real fwd);
typedef struct PhotonMap PhotonMap;
static void shoot_photons(const Scene *s, void *data);
static void shoot_photon(const Scene *s, Photons *ph, int i, Worker *wk);
static void build_map(PhotonMap *m);
static void keep_photon(PhotonMap *m, vec p, vec power, vec from, int rays);
static int smooth(const Bsdf *b);
static vec direct_and_photons(const Scene *s, const Hit *h, const Bsdf *b, vec wo, const Photons *ph,
                              int most, Worker *wk);
static vec gathered(const Scene *s, Ray r, const Photons *ph, int rays, Worker *wk);
static vec photon_estimate(const Photons *ph, const PhotonMap *m, const Hit *h, const Bsdf *b, vec wo,
                           int most);
static int counts(const PhotonMap *m, int i, const Hit *h, const Bsdf *b, real r2, int most);
static real pass_shrink(const Scene *s, Photons *ph);
static real disc_radius2(const Photons *ph, const Hit *h);
static vec disc_estimate(const Photons *ph, const Hit *h, const Bsdf *b, vec wo, int most);
static void in_disc(void *user, int i, float d2);
static void free_photons(Photons *ph);
static void draw_photons(const Scene *s, const Photons *ph, Image *img);   /* --view photons, in the plumbing */
static vec emitted(const Scene *s, const Hit *h, vec wo, const Path *path);
static vec sky(const Scene *s, vec d, const Path *path);
static real power_heuristic(real a, real b);
static vec sample_light(const Scene *s, const Hit *h, const Bsdf *b, vec wo, Worker *wk);
static void prepare_lights(Scene *s);
static int inside_seen(const Scene *s, int i);
static int light_tree(Lights *L, int *order, int n, int parent);
static void split_lights(const Lights *L, int *order, int n, int m, int a);
static void bound_lights(LightNode *k, const LightNode *a, const LightNode *b);
static void sphere_of_box(LightNode *k);
static real coordinate(vec v, int a);
static real importance(const LightNode *k, vec x, vec n);
static real node_weight(const Scene *s, int k, vec x, vec n, int by_power);
static int down_the_tree(const Scene *s, vec x, vec n, int by_power, real u, real *chance);
static int choose_light(const Scene *s, vec x, vec n, real u, real *chance);
static real light_choice(const Scene *s, int l, vec x, vec n);
static real tree_chance(const Scene *s, int l, vec x, vec n, int by_power);
static void find_clips(Scene *s);
static int clipped_lights(const Scene *s);
static int visible_cap(const Scene *s, int l, vec x, vec n, vec *axis, real *cap);
static int sample_emitter(const Scene *s, int l, vec x, vec n, real time, real u, real v,
                          vec *wi, real *dist, vec *Le, real *pdf);
static int light_visible(const Scene *s, const Hit *h, int l, vec wi, real dist, Worker *wk);
static real light_pdf(const Scene *s, int l, vec x, vec n, vec y, vec ny, real time);
static int front_emits(const Scene *s, int i, vec ng, vec wo);
static void bsdf_at(const Scene *s, const Hit *h, vec wo, Bsdf *b);
static vec bsdf_eval(const Bsdf *b, vec wo, vec wi);
static real bsdf_pdf(const Bsdf *b, vec wo, vec wi);
static int sample_bsdf(const Bsdf *b, vec wo, Worker *wk, vec *wi, vec *f_cos_pdf, real *pdf);
static int sample_glass(const Bsdf *b, vec wo, real u, vec *wi, vec *f_cos_pdf);
static real fresnel(real cosi, real eta);
static real microfacet_f(const Bsdf *b, vec wo, vec wi);
static real coat_through(const Bsdf *b, vec wo, vec wi);
static real microfacet_pdf(const Bsdf *b, vec wo, vec wi);
static vec microfacet_sample(const Bsdf *b, vec wo, real u1, real u2);
static real ggx_d(real alpha, real cos_h);
static real smith_lambda(real alpha, real cos_theta);
static real smith_g1(real alpha, real cos_theta);

/* finding hits: the only code that knows an acceleration structure exists */
static int nearest_hit(const Scene *s, Ray r, Hit *h, Worker *wk);
static int build_accel(Scene *s, const char *accel);
static Query query(Ray r);
static int find_nearest(const Scene *s, Query *q, real *t, Worker *wk);
static int prim_hit(void *user, int i, void *ray, double tmin, double tmax, double *t);
static int kind(const Scene *s, int i, int *k);
static int hit_object(const Scene *s, int i, const Ray *r, real tmax, real *t);
static const Ray *at_rest(const Scene *s, int i, const Ray *r, Ray *moved);
static vec rest_frame(const Scene *s, int i, real time, vec x);
static int moves(const Scene *s, int i);
static vec velocity(const Scene *s, int i);
static void fill_hit(const Scene *s, Ray r, int i, real t, const Query *q, Hit *h);
static Ray spawn(const Scene *s, const Hit *h, vec dir);
static int any_hit(const Scene *s, Ray r, real tmax, int *last, Worker *wk);
static int find_any(const Scene *s, Query *q, real tmax, Worker *wk);
static void prim_bounds(void *user, int i, double lo[3], double hi[3]);
static void rest_box(const Scene *s, int i, double lo[3], double hi[3]);
static void sweep(const Scene *s, int i, double lo[3], double hi[3]);
static int prim_clip(void *user, int i, const double blo[3], const double bhi[3],
                     double lo[3], double hi[3]);

/* the primitives: each its hit test, its surface, its box and clip */
static void add_sphere(Scene *s, vec cen, real rad, int mat);
static real hit_sphere(const Sphere *sp, const Ray *r, real tmin);
static void sphere_surface(const Sphere *sp, const Ray *r, real t, Hit *h);
static void sphere_box(const Sphere *sp, double lo[3], double hi[3]);
static int sphere_clip(const Sphere *sp, const double blo[3], const double bhi[3],
                       double lo[3], double hi[3]);
static real sphere_sample(const Sphere *sp, vec x, real u, real v, vec *wi, real *dist);
static real sphere_pdf(const Sphere *sp, vec x, vec y);
static real cap_sample(const Sphere *sp, vec axis, real cap, vec x, real u, real v, vec *wi, real *dist);
static real cap_pdf(const Sphere *sp, vec axis, real cap, vec x, vec y);
static void add_cone(Scene *s, vec base, real rb, vec apex, real ra, int mat);
static int add_checked_cone(Scene *s, vec base, real rb, vec apex, real ra, int mat, char *why);
static real hit_cone(const Cone *c, const Ray *r, real tmin);
static void cone_surface(const Cone *c, const Ray *r, real t, Hit *h);
static void cone_box(const Cone *c, double lo[3], double hi[3]);
static int add_vertex(Scene *s, vec p);
static int add_normal(Scene *s, vec n);
static void add_triangle(Scene *s, int a, int b, int c, int na, int nb, int nc, int mat);
static int degenerate(vec a, vec b, vec c);
static int hit_triangle(const Scene *s, const Triangle *tr, const Ray *r, real tmax,
                        real *t, real *u, real *v);
static void triangle_surface(const Scene *s, const Triangle *tr, real u, real v, Hit *h);
static void triangle_box(const Scene *s, const Triangle *tr, double lo[3], double hi[3]);
static int triangle_clip(const Scene *s, const Triangle *tr, const double blo[3],
                         const double bhi[3], double lo[3], double hi[3]);
static void triangle_sample(const Triangle *tr, real u, real v, vec *y, vec *ny);
static real triangle_pdf(const Triangle *tr, real dist, real cosy);
static real triangle_light_sample(const Triangle *tr, vec x, real u, real v, vec *y, vec *ny);
static real triangle_light_pdf(const Triangle *tr, vec x, real dist, real cosy);
static real spherical_triangle(const Triangle *tr, vec x, vec c[3], real angle[3]);
static vec spherical_triangle_sample(const vec c[3], const real angle[3], real area, real u1, real u2);

/* ---------------------------------------------------------- for each pixel */

/* The lecture's "for each pixel", for one row of the image (rows are what
 * the threads share out: see render()).  Whitted's colour, or with the path
 * tracer the radiance. */
static void render_row(const Scene *s, int j, int spp, Image *img, Worker *wk)
{
    int i;
    for (i = s->set.x0; i < s->set.x1; i++) {     /* the whole row, or a split render's part */
        vec c = s->set.view && s->set.view < VIEW_SAMPLES ? pixel_view(s, i, j, wk)  /* --view: the plumbing */
                : s->set.integrator == PATH ? pixel_radiance(s, i, j, spp, wk)
                : pixel_color(s, i, j, spp, wk);
        if (s->set.view == VIEW_SAMPLES) c = scale((real)wk->taken / spp, v3(1, 1, 1));
        if (img) put_pixel(img, i - s->set.x0, j - s->set.y0, c);
        if (wk->part) keep_sums(wk->part, i, j, &wk->last);     /* a partial render: the plumbing */
    }
}

/* The pixel's colour: RayTrace of each of its spp samples, averaged (with
 * --adaptive, of those it takes: see pixel_done and neighbours_agree). */
static vec pixel_color(const Scene *s, int i, int j, int spp, Worker *wk)
{
    Tally t;
    memset(&t, 0, sizeof t);
    if (wk->first) {                        /* --adaptive: the first 4 were taken before */
        t = wk->first[(size_t)j * s->set.w + i];
        if (neighbours_agree(s, wk->first, i, j)) return pixel_mean(&t, wk);
    }
    return pixel_mean(take_samples(s, i, j, &t, spp, wk), wk);
}

/* Samples t->n, t->n + 1, ... of the pixel into t, up to n in all or
 * until pixel_done says it may stop (rounds from 8 on); counted from the
 * first of a split render's range (--samples A:B: A). */
static const Tally *take_samples(const Scene *s, int i, int j, Tally *t, int n, Worker *wk)
{
    real shift = s->moving ? time_shift(wk, s, i, j) : 0;   /* no motion: no numbers drawn */
    int k;
    for (k = s->set.s0 + t->n; k < s->set.s0 + n && !pixel_done(s, t, 8); k++) {
        real dx, dy;
        Ray r;
        sample_offset(k, s->cam.anchor, &dx, &dy);
        start_sample(wk, s, i, j, k);       /* for a lens, area lights, a glossy lobe */
        wk->count.primary++;
        wk->budget = RAY_BUDGET;
        wk->dim_budget = dim_budget(s);
        r = primary_ray(s, i + dx, j + dy, wk);
        if (s->moving) r.time = shutter_time(s, k, shift);
        tally(t, trace(s, r, s->set.depth, 1, wk));
        if (wk->hooks && wk->hooks->after_sample) wk->hooks->after_sample(s, i, j, k, wk, wk->hooks->data);
    }
    return t;
}

/* Adaptive sampling (--adaptive E).  A pixel's samples come in rounds
 * that double (from 8 in Whitted's renderer, 16 in the path tracer's; and
 * Whitted's pixel may also stop at 4, see neighbours_agree), and at the end
 * of each the pixel stops if its byte is known to within E steps of 255
 * with 95% confidence: for each channel, the half-width 1.96 s / sqrt(n)
 * of the confidence interval of its mean (s the standard deviation of its
 * n samples: the central limit theorem), times the slope of the curve from
 * colour to byte there, is at most E / 255.  A channel whose whole
 * interval lies at or above 1 is white whatever its error.  Only the
 * pixel's own samples decide, so the bytes are the same for any thread
 * count; and a pixel that takes all of -n gets the bytes it gets without
 * --adaptive.  What it misses: a path too rare to show in a round's
 * samples (a caustic's speck lit through glass one path in hundreds)
 * leaves s small, and the pixel may stop without it, darker than it should
 * be; the path tracer's 16 samples at least, and decisions only at the
 * ends of rounds, keep that to paths rarer than about one in 16 where the
 * rest agree.  Whitted's samples are the R2 points, not random, yet
 * spread evenly: where they agree (a flat wall, the sky) the pixel is
 * done; an edge, a shadow's or a refracted edge, makes them disagree and
 * the pixel goes on.  By its own samples alone, not at 4: four points
 * that agree miss an edge that cuts a corner of the pixel often enough
 * that the image's error stops falling as -n grows. */
static void tally(Tally *t, vec c)
{
    exact_add(&t->sum[0], (double)c.x);     /* added exactly: a render split over */
    exact_add(&t->sum[1], (double)c.y);     /* machines merges to the same bytes, */
    exact_add(&t->sum[2], (double)c.z);     /* whatever order its parts add in (image.h) */
    t->sq = add(t->sq, mul(c, c));
    t->n++;
}

static vec tally_sum(const Tally *t)
{
    return v3((real)exact_value(&t->sum[0]), (real)exact_value(&t->sum[1]), (real)exact_value(&t->sum[2]));
}

static vec tally_mean(const Tally *t) { return scale((real)1 / t->n, tally_sum(t)); }

/* Whether the pixel stops now, after t->n samples: only with --adaptive,
 * only at a round's end (first, 2 first, 4 first, ...; first a power of
 * two), and then if settled() says so. */
static int pixel_done(const Scene *s, const Tally *t, int first)
{
    return s->set.adaptive > 0 && t->n >= first && (t->n & (t->n - 1)) == 0 && settled(s, t);
}

static int settled(const Scene *s, const Tally *t)
{
    double sum[3], sq[3];
    int c;
    to3(tally_sum(t), sum);
    to3(t->sq, sq);
    for (c = 0; c < 3; c++) {
        double mean = sum[c] / t->n, var = fmax(0, (sq[c] - sum[c] * mean) / (t->n - 1));
        double half = 1.96 * sqrt(var / t->n), slope = s->set.srgb ? srgb_slope((real)fmax(0, mean - half)) : 1;
        if (mean - half < 1 && slope * half > s->set.adaptive / 255) return 0;
    }
    return 1;
}

/* Whitted's pixel may stop at its first 4 samples (which render() takes
 * for every pixel before the rest: first_samples) when they agree and so
 * do each of its 8 neighbours', each within E steps of its own mean.  Four
 * points alone often miss an edge through a corner of the pixel; the
 * neighbour across that edge does not.  Every pixel's first 4 samples are
 * the same whichever thread takes them, so the bytes still do not depend
 * on the thread count. */
static int neighbours_agree(const Scene *s, const Tally *first, int i, int j)
{
    const Tally *t = &first[(size_t)j * s->set.w + i];
    int di, dj, c;
    if (!settled(s, t)) return 0;
    for (dj = -1; dj <= 1; dj++)
        for (di = -1; di <= 1; di++) {
            int a = i + di, b = j + dj;
            const Tally *u;
            double m[3], q[3];
            if (a < 0 || b < 0 || a >= s->set.w || b >= s->set.h || (di == 0 && dj == 0)) continue;
            u = &first[(size_t)b * s->set.w + a];
            if (!settled(s, u)) return 0;
            to3(scale((real)1 / t->n, tally_sum(t)), m);
            to3(scale((real)1 / u->n, tally_sum(u)), q);
            for (c = 0; c < 3; c++)
                if (fmin(m[c], q[c]) < 1
                    && fabs(m[c] - q[c]) * (s->set.srgb ? srgb_slope((real)fmin(m[c], q[c])) : 1) > s->set.adaptive / 255)
                    return 0;
        }
    return 1;
}

/* The slope of the sRGB curve (srgb() below) at v: the bytes per unit of
 * light there, 12.92 in the straight part near black. */
static real srgb_slope(real v)
{
    return v <= (real)0.0031308 ? (real)12.92 : (real)(1.055 / 2.4 * pow(v, 1 / 2.4 - 1));
}

/* The pixel's value, the mean of the samples it took, which are counted
 * for --stats and --view samples. */
static vec pixel_mean(const Tally *t, Worker *wk)
{
    wk->taken = t->n;
    wk->last = *t;
    wk->count.samples += (unsigned)t->n;
    if (!wk->count.spp_max || t->n < wk->count.spp_min) wk->count.spp_min = t->n;
    if (t->n > wk->count.spp_max) wk->count.spp_max = t->n;
    return tally_mean(t);
}

/* The pixel into the image: as floats (for PFM and EXR, the radiance itself), or
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

/* Linear light to the sRGB transfer curve (IEC 61966-2-1), which image
 * viewers assume a PPM or PNG holds: a straight line near black, then a
 * 1/2.4 power.  A path-traced image always gets it; Whitted's only with
 * --gamma, so that the card's bytes stay the card's. */
static real srgb(real v)
{
    return v <= (real)0.0031308 ? 12.92 * v : 1.055 * pow(v, 1 / 2.4) - 0.055;
}

/* Colour in 0..1 to a byte: x255 and round to nearest (as minray's %.0f
 * does), clamped; NaN becomes 0 so that no pixel is ever undefined. */
static unsigned char to_byte(real v)
{
    double x = rint((double)v * 255);
    if (!(x > 0)) return 0;
    return x > 255 ? 255 : (unsigned char)x;
}

/* ----------------------------------------------------------------- samples */

/* Where the numbers come from: the points of a pixel (the R2 pattern), the
 * path tracer's random numbers, and the warps that turn two uniform numbers
 * into a point or a direction with a known density.  Each warp stands
 * beside its pdf, named alike (cosine_hemisphere, cosine_hemisphere_pdf),
 * as Nori's warp.h pairs them (Jakob's educational renderer), so that
 * whoever divides by a pdf calls the function that says it, and a test can
 * hold each warp against its pdf (tests/test_pt.c, "warp" checks). */

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
 *     DIM_LENS_U, _V        a point of the lens               primary_ray (both renderers)
 *     DIM_TIME              the pixel's shift of its          pixel_color and
 *                           instants of the shutter             sample_radiance, once a
 *                           (see shutter_time)                  pixel (as its sample -1),
 *                                                               when something moves
 *   and from DIM_BOUNCE on, a block of BOUNCE_DIMS for each bounce b (0 at the
 *   first hit), slot k of it dimension DIM_BOUNCE + b * BOUNCE_DIMS + k:
 *       LIGHT_CHOICE        which light                       sample_light
 *       LIGHT_U, LIGHT_V    the point on it                   sample_light; Whitted's
 *                                                               area_point
 *       LOBE                which lobe of the BSDF, and       sample_bsdf
 *                           glass's reflect or refract          (see sample_glass)
 *       DIRECTION_U, _V     the direction within the lobe     sample_bsdf; Whitted's
 *                                                               glossy_mirror
 *       ROULETTE            whether the path goes on          survives
 *       SPARE               none yet: room for one more
 *
 * Whitted's renderer draws from the same table where it spreads a ray
 * (Cook's distributed ray tracing), its recursion level standing for the
 * bounce.  The lens and time dimensions were kept, unused, before there
 * was a lens or motion blur; each came and moved no other path's numbers. */
enum { DIM_PIXEL_X, DIM_PIXEL_Y, DIM_LENS_U, DIM_LENS_V, DIM_TIME, DIM_BOUNCE };
enum { LIGHT_CHOICE, LIGHT_U, LIGHT_V, LOBE, DIRECTION_U, DIRECTION_V, ROULETTE, SPARE,
       BOUNCE_DIMS };

/* The sample the numbers that follow belong to: sample k of pixel (i, j),
 * its path at the first hit. */
static void start_sample(Worker *wk, const Scene *s, int i, int j, int k)
{
    unsigned long long pixel = (unsigned long long)j * (unsigned)s->set.w + (unsigned)i;
    wk->pixel_key = mix64(mix64(s->set.seed + 0x9e3779b97f4a7c15ULL) ^ pixel);
    wk->key = mix64(wk->pixel_key ^ (unsigned)k);
    wk->sample = s->set.integrator == PATH && s->set.sampler == SOBOL ? k : -1;
    wk->bounce = 0;
}

/* The sample's number in dimension dim, uniform in [0, 1): a hash of the
 * sample's key and the dimension, independent of every other; or with
 * --sampler sobol, a coordinate of Owen-scrambled Sobol' points (below). */
static real random01(const Worker *wk, unsigned dim)
{
    real u = (real)(wk->sample >= 0 && dim >= DIM_LENS_U
                    ? sobol01(wk, dim)
                    : (mix64(wk->key + 0x9e3779b97f4a7c15ULL * (dim + 1ULL)) >> 11) * (1.0 / 9007199254740992.0));
    return u < 1 ? u : 1 - REAL_EPS;      /* a float may round up to 1 */
}

/* --sampler sobol: low-discrepancy numbers in every dimension of a path
 * (Burley, "Practical hash-based Owen scrambling", JCGT 9(4), 2020).  The
 * dimensions go in pairs that a choice uses together (the lens's u and v,
 * a light's point, a direction; and the single ones two by two); each
 * pair's numbers are the first two dimensions of Sobol's sequence, whose
 * first 2^m points put one point in every box of area 2^-m of any shape
 * 2^-a by 2^-b (a (0, m, 2)-net: Sobol', 1967).  Every pair of every
 * pixel has its own scramble (Owen's nested uniform scrambling, 1995, by
 * Laine and Karras's hash as Burley improves it) and its own shuffle of
 * the sample numbers: each point alone is uniform, so the mean stays
 * right; pairs and pixels are independent of each other; and within a
 * pair, any first 2^m samples of the pixel stay a (0, m, 2)-net. */
static uint32_t reverse_bits(uint32_t x)
{
    x = x << 16 | x >> 16;
    x = (x & 0x00ff00ffu) << 8 | (x & 0xff00ff00u) >> 8;
    x = (x & 0x0f0f0f0fu) << 4 | (x & 0xf0f0f0f0u) >> 4;
    x = (x & 0x33333333u) << 2 | (x & 0xccccccccu) >> 2;
    return (x & 0x55555555u) << 1 | (x & 0xaaaaaaaau) >> 1;
}

/* Owen's scramble, on bits reversed (the first binary digit of a number in
 * [0, 1) as the lowest bit): each bit flipped or not by a hash of the bits
 * below it, which Laine and Karras's hash does, since multiplying by an
 * even number carries only upward. */
static uint32_t owen_reversed(uint32_t x, uint32_t seed)
{
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

/* Sobol's second dimension at index i, its digits reversed (its first is
 * i itself, reversed: van der Corput's).  Its direction numbers, those of
 * the polynomial x + 1, are the rows of Pascal's triangle mod 2, so digit
 * j is the parity of the bits i_k with C(k, j) odd, which by Lucas's
 * theorem are those whose k has every bit of j: a sum over supersets of
 * bit positions, five shifts and masks (one for each bit of a position). */
static uint32_t sobol_second_reversed(uint32_t i)
{
    i ^= (i >> 1) & 0x55555555u;
    i ^= (i >> 2) & 0x33333333u;
    i ^= (i >> 4) & 0x0f0f0f0fu;
    i ^= (i >> 8) & 0x00ff00ffu;
    return i ^ ((i >> 16) & 0x0000ffffu);
}

/* Which pair a dimension belongs to, and which of its two it is. */
static unsigned pair_of(unsigned dim, int *second)
{
    static const unsigned char pair[BOUNCE_DIMS] = { 0, 1, 1, 0, 2, 2, 3, 3 };   /* by slot */
    static const unsigned char which[BOUNCE_DIMS] = { 0, 0, 1, 1, 0, 1, 0, 1 };
    unsigned slot;
    if (dim < DIM_BOUNCE) {             /* the lens's u, v; the time alone */
        *second = dim == DIM_LENS_V;
        return dim == DIM_TIME;
    }
    slot = (dim - DIM_BOUNCE) % BOUNCE_DIMS;
    *second = which[slot];
    return 2 + 4 * ((dim - DIM_BOUNCE) / BOUNCE_DIMS) + pair[slot];
}

static double sobol01(const Worker *wk, unsigned dim)
{
    int second;
    unsigned pair = pair_of(dim, &second);
    unsigned long long h = mix64(wk->pixel_key ^ (0xd1b54a32d192ed03ULL * (pair + 1ULL)));
    /* the pair's own order of the samples: i an Owen scramble of the number k */
    uint32_t i = reverse_bits(owen_reversed(reverse_bits((uint32_t)wk->sample), (uint32_t)h));
    uint32_t x = second ? sobol_second_reversed(i) : i;     /* the point's digits, reversed */
    return reverse_bits(owen_reversed(x, (uint32_t)(h >> 32) ^ (second ? 0x9e3779b9u : 0))) * (1.0 / 4294967296.0);
}

/* The number in `slot` of the block of the bounce the path is at. */
static real bounce_random(const Worker *wk, int slot)
{
    return random01(wk, DIM_BOUNCE + (unsigned)wk->bounce * BOUNCE_DIMS + (unsigned)slot);
}

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

/* Motion blur (Cook, Porter and Carpenter, "Distributed Ray Tracing",
 * SIGGRAPH 1984): each sample of a pixel sees the scene at its own instant
 * of the shutter, so that an object moving across the pixel counts there
 * for the share of the shutter it spends there.  The instants of a pixel's
 * samples are a 1-D sequence shifted by the pixel's own random number
 * (DIM_TIME, drawn as its sample -1), as the pixel's points are: */
static real time_shift(Worker *wk, const Scene *s, int i, int j)
{
    start_sample(wk, s, i, j, -1);
    return random01(wk, DIM_TIME);
}

/* Sample k's instant: the golden ratio's sequence k g mod 1 (the 1-D
 * Kronecker sequence with the lowest discrepancy for every count), shifted
 * by the pixel's shift and wrapped, then stretched over the shutter.  Why
 * not the strata (k + 1/2)/spp: those pair instant k with R2's point k in a
 * lattice of 3-D points, whose rows can line up with a motion; g is
 * rationally independent of R2's two numbers (a quadratic against a cubic
 * irrational), so (point, instant) together fill the pixel and the shutter
 * evenly for any spp, known in advance or not.  The shift makes each
 * instant alone uniform over the shutter, so the mean is unbiased, and
 * keeps neighbouring pixels from sharing instants (which would show spp
 * sharp copies of a moving object instead of a smooth streak). */
static real shutter_time(const Scene *s, int k, real shift)
{
    const double g = 0.6180339887498949;        /* (sqrt 5 - 1) / 2 */
    real u = (real)(k * g - floor(k * g)) + shift;
    if (u >= 1) u -= 1;
    return s->shutter[0] + u * (s->shutter[1] - s->shutter[0]);
}

/* The warps below work in a local frame about the z axis: t1, t2, n for
 * an orthonormal t1, t2 made from the unit vector n (Duff et al.,
 * "Building an Orthonormal Basis, Revisited", JCGT 6(1), 2017). */
static void tangents(vec n, vec *t1, vec *t2)
{
    real sign = n.z >= 0 ? 1 : -1, a = -1 / (sign + n.z), b = n.x * n.y * a;
    *t1 = v3(1 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    *t2 = v3(b, sign + n.y * n.y * a, -n.y);
}

/* A local vector into the world's: l.x t1 + l.y t2 + l.z n. */
static vec from_local(vec n, vec l)
{
    vec t1, t2;
    tangents(n, &t1, &t2);
    return add(add(scale(l.x, t1), scale(l.y, t2)), scale(l.z, n));
}

/* And back: the world's w in the frame about n (for a warp that depends on
 * where it is seen from, ggx_visible_normal). */
static vec to_local(vec n, vec w)
{
    vec t1, t2;
    tangents(n, &t1, &t2);
    return v3(dot(w, t1), dot(w, t2), dot(w, n));
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

/* A microfacet normal h about z with the density of the normals that wo
 * (wo.z > 0) sees, D_wo(h) = G1(wo) max(0, wo.h) D(h) / wo.z, for the GGX
 * distribution D of roughness alpha: visible-normal sampling (Heitz,
 * "Sampling the GGX Distribution of Visible Normals", JCGT 7(4), 2018).
 * Why it works: stretched by 1/alpha across z, a GGX surface becomes one
 * of alpha 1, whose microfacets are those of a hemisphere; the normals of
 * a hemisphere that a direction v sees, weighed by the area they show,
 * are the points of its silhouette, the disc across v, lifted onto it.  Of
 * that disc the half towards the pole shows whole, the other half is the
 * hemisphere's rim seen aslant, a half ellipse squeezed by v.z: so a
 * uniform point of the disc has its lower half squeezed by v.z (an affine
 * map along each chord, which keeps it uniform), is lifted along v, and
 * the normal is stretched back (normals scale by alpha where points scale
 * by 1/alpha).  Any uniform disc point serves; the concentric map's keeps
 * neighbouring numbers neighbouring normals. */
static vec ggx_visible_normal(vec wo, real alpha, real u1, real u2)
{
    vec v = unit(v3(alpha * wo.x, alpha * wo.y, wo.z)), t1, t2, d = uniform_disc(u1, u2), m;
    real across = sqrt(v.x * v.x + v.y * v.y), s = (1 + v.z) / 2, y;
    t1 = across > 0 ? v3(-v.y / across, v.x / across, 0) : v3(1, 0, 0);
    t2 = cross(v, t1);
    y = (1 - s) * sqrt(fmax(0, 1 - d.x * d.x)) + s * d.y;       /* squeezed: [-v.z, 1] of the chord */
    m = add(add(scale(d.x, t1), scale(y, t2)), scale(sqrt(fmax(0, 1 - d.x * d.x - y * y)), v));
    return unit(v3(alpha * m.x, alpha * m.y, fmax(0, m.z)));
}

/* Its pdf, per unit solid angle of h, for cos_o = wo.z, cos_h = h.z and
 * o_dot_h = wo.h (GGX is isotropic: these three say it all). */
static real ggx_visible_normal_pdf(real alpha, real cos_o, real cos_h, real o_dot_h)
{
    if (!(cos_o > 0 && o_dot_h > 0)) return 0;
    return smith_g1(alpha, cos_o) * o_dot_h * ggx_d(alpha, cos_h) / cos_o;
}

/* A uniform point (x, y, 0) of the unit disc, for cosine_hemisphere and
 * the thin lens (through_lens): the concentric map of Shirley and Chiu ("A Low Distortion Map Between Disk
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

/* -------------------------------------------------------------- the camera */

/* The primary ray of the sample the worker is at, through image point
 * (x, y): a pinhole camera's, or with a lens one from a point of it. */
static Ray primary_ray(const Scene *s, real x, real y, const Worker *wk)
{
    Ray r = camera_ray(&s->cam, s->set.w, s->set.h, x, y);
    if (s->cam.lens > 0) r = through_lens(&s->cam, r, random01(wk, DIM_LENS_U), random01(wk, DIM_LENS_V));
    return r;
}

/* The pinhole camera's ray through image point (x, y), in pixels from the
 * top-left corner of the image.  The image plane stands at the distance
 * where the image's width spans the field of view edge to edge; a pixel is
 * one unit. */
static Ray camera_ray(const Camera *c, int w, int h, real x, real y)
{
    real dist = (real)w / 2 / c->tan_half;
    Ray r;
    r.o = c->eye;
    r.skip = -1;
    r.time = 0;                 /* the caller sets the sample's instant, if things move */
    r.d = unit(add(add(scale(x - (real)w / 2, c->right),
                       scale((real)h / 2 - y, c->up)), scale(dist, c->fwd)));
    r.tmin = near_clip(c, r.d);
    return r;
}

/* Where a ray from the eye's plane along d (a unit vector) meets the near
 * clip (hither), as its t; 0 without one.  The clip is a plane, as NFF's
 * hither is, or a sphere round the eye: smallpt starts its rays 140 along
 * each unit direction. */
static real near_clip(const Camera *c, vec d)
{
    if (!(c->hither > 0)) return 0;
    return c->hither_sphere ? c->hither : c->hither / dot(d, c->fwd);
}

/* A thin lens (Potmesil and Chakravarty, "A lens and aperture camera model
 * for synthetic image generation", SIGGRAPH 1981; sampled over its disc
 * as Cook, Porter and Carpenter's "Distributed ray tracing", SIGGRAPH
 * 1984, spreads every effect over one more dimension).  A lens sends all
 * the light from a point of the plane of focus to one point of the image,
 * so every ray through the lens that reaches the pinhole ray's image point
 * crosses the plane of focus where the pinhole ray r does: the ray from a
 * uniform point of the lens's disc (from u1, u2) towards that point.  A
 * point at distance z (along the view) is seen from the whole disc of
 * diameter A = 2 lens, through points of the plane of focus that fill a
 * disc of diameter A |z - focus| / z, its circle of confusion: sharp on
 * the plane, blurred before and behind it. */
static Ray through_lens(const Camera *c, Ray r, real u1, real u2)
{
    vec p = uniform_disc(u1, u2);
    vec sharp = comb(c->focus / dot(r.d, c->fwd), r.d, r.o);     /* on the plane of focus */
    r.o = add(c->eye, add(scale(c->lens * p.x, c->right), scale(c->lens * p.y, c->up)));
    r.d = unit(sub(sharp, r.o));
    r.tmin = near_clip(c, r.d);             /* the lens lies in the eye's plane */
    return r;
}

/* The largest |coordinate| of a light or the camera: two points within it
 * are less than sqrt(REAL_MAX) apart, so the squared distances the renderer
 * takes between them (to a light, from the eye) stay finite; beyond it, a
 * light would light nothing and an eye see nothing.  3.9e153 in doubles. */
#define FAR_LIMIT sqrt((sizeof(real) == sizeof(float) ? FLT_MAX : DBL_MAX) / 12)

static int within_far_limit(vec p) { return maxabs(p) <= FAR_LIMIT; }

/* A sphere of centre c and radius r, or a cone's end, within FAR_LIMIT as
 * the camera and the lights are: a sphere's squared radius overflows past
 * 1.3e154, and it would vanish.  0 and why if not. */
static int within_far_limit_by(vec c, real r, char *why)
{
    if (maxabs(c) + r <= FAR_LIMIT) return 1;
    sprintf(why, "object too far out or too large: beyond %.2g (a centre plus its radius), its squared"
            " distances overflow and it would vanish", (double)FAR_LIMIT);
    return 0;
}

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

/* The camera at eye v[0..2] looking at v[3..5], up towards v[6..8], with a
 * horizontal field of view of v[9] degrees. */
static int set_camera(Scene *s, const real *v, char *why)
{
    Camera *c = &s->cam;
    vec at = v3(v[3], v[4], v[5]), up = pow2_scaled(v3(v[6], v[7], v[8]));
    c->eye = v3(v[0], v[1], v[2]);
    if (!within_far_limit(c->eye) || !within_far_limit(at)) {
        sprintf(why, "camera too far out: beyond %.2g, squared distances from the eye overflow",
                (double)FAR_LIMIT);
        return 0;
    }
    if (!(dot(pow2_scaled(sub(at, c->eye)), pow2_scaled(sub(at, c->eye))) > 0))
        return sprintf(why, "camera looks at its own eye"), 0;
    if (!(v[9] > 0 && v[9] < 180))
        return sprintf(why, "field of view must be between 0 and 180 degrees"), 0;
    if (!(v[9] >= narrowest_fov())) {
        sprintf(why, "field of view too narrow: under %.2g degrees the image plane is so far away"
                " that its squared distance overflows", narrowest_fov());
        return 0;
    }
    c->tan_half = tan(v[9] * PI / 360);
    c->fwd = unit(pow2_scaled(sub(at, c->eye)));
    c->right = cross(c->fwd, up);
    if (!(dot(c->right, c->right) > 0)) return sprintf(why, "camera up is parallel to its view"), 0;
    c->right = unit(c->right);
    c->up = cross(c->right, c->fwd);
    return 1;
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
 * card's order so that the rounding is the card's too.  Point lights, and
 * with the card's rule (`lights centre`) glowing spheres, light by one
 * shadow ray each; glowing spheres and triangles otherwise by their area. */
static vec shade(const Scene *s, Ray r, const Hit *h, int depth, real weight, Worker *wk)
{
    const Material *m = &s->mat[h->mat];
    vec n = h->n, color = s->ambient, spec = v3(0, 0, 0), c, refracted, mirror, dir;
    real cosi = -dot(r.d, n), eta = 1 / m->ir, e, kr;
    int i, tir;
    if (dot(r.d, h->ng) > 0) { n = scale(-1, n); cosi = -cosi; eta = m->ir; } /* inside */
    mirror = reflect(r.d, n, cosi);
    wk->bounce = s->set.depth - depth;      /* this level's numbers (see the samples) */
    /* Past the critical angle no refracted ray exists.  The card then loses
     * the kt share (its glass goes black there); the SPD's rule, and with
     * `tir reflect` a sphere file's, sends it into the reflected ray. */
    tir = m->kt > 0 && !refract(r.d, n, cosi, eta, &refracted);
    kr = tir && s->tir_reflect ? m->ks + m->kt : m->ks;
    for (i = 0; i < s->nlight; i++)
        if ((s->light[i].sphere < 0 || s->lights_centre)
            && shadow_ray(s, h, n, &s->light[i], s->light[i].sphere >= 0 ? -1    /* the card's: never dim */
                          : weight * point_light_bound(m, &s->light[i]), &e, &dir, wk))
            lit_by(m, s->light[i].color, e, dir, mirror, &color, &spec);
    if (m->kd > 0) area_lights(s, h, n, weight, &color, wk);     /* (only kd sees them) */
    color = mul(color, m->color);

    c = scale(m->kl, m->color);                 /* emission */
    c = comb(m->kd, color, c);                  /* diffuse */
    if (m->shine > 0) c = comb(m->ks, spec, c); /* highlight */
    dir = m->spread ? glossy_mirror(mirror, m->shine, wk) : mirror;
    if ((!m->spread || dot(dir, h->ng) * dot(mirror, h->ng) > 0)     /* a glossy ray may fall */
        && worth_tracing(s, kr, weight, depth, wk)) {                  /* behind: it is lost */
        wk->count.reflected++;
        c = comb(kr, trace(s, spawn(s, h, dir), depth - 1, kr * weight, wk), c);
    }
    if (!tir && worth_tracing(s, m->kt, weight, depth, wk)) {
        wk->count.refracted++;
        c = comb(m->kt, trace(s, spawn(s, h, refracted), depth - 1, m->kt * weight, wk), c);
    }
    return c;
}

/* A light's share at the hit: e (its strength there, with the cosine) times
 * its colour, to the diffuse sum; and for a material with a highlight,
 * Phong's (1975) cos^shine of the angle between the mirror direction and
 * the light's.  Not for ks = 0, where it adds nothing (and pow() of a huge
 * shine, such as the SPD floor's 100000, underflows slowly). */
static void lit_by(const Material *m, vec light, real e, vec dir, vec mirror, vec *color,
                   vec *spec)
{
    *color = comb(e, light, *color);
    if (m->shine > 0 && m->ks > 0) {
        real rl = dot(mirror, dir);
        if (rl > 0) *spec = comb(pow(rl, m->shine), light, *spec);
    }
}

/* Area lights and soft shadows (Cook, Porter and Carpenter, "Distributed
 * ray tracing", SIGGRAPH 1984: a penumbra is the light's area taken as one
 * more dimension to spread shadow rays over).  Each glowing sphere and
 * triangle gets shadow_rays shadow rays a sample, to points the path
 * tracer would choose (sample_emitter: a sphere by the solid angle it
 * fills, a triangle by its area), and each point seen counts as a point
 * light of colour Le / (pi pdf shadow_rays).  kd times the sum is then
 * what the Lambertian BRDF kd C / pi reflects of the light, an estimate of
 * the integral of Le cos over the light: Whitted's direct light and the
 * path tracer's agree (a test holds them together).  No Phong highlight:
 * a highlight is the reflection of a light no ray can see, a point; the
 * mirror ray sees an area light as it sees any glowing object. */
static void area_lights(const Scene *s, const Hit *h, vec n, real weight, vec *color, Worker *wk)
{
    vec wi, Le;
    real u, v, dist, pdf, e;
    int l, q;
    for (l = 0; l < s->lights.nemit; l++) {
        const Emitter *em = &s->lights.emit[l];
        if (em->type != TRIANGLE_LIGHT && (em->type != SPHERE_LIGHT || s->lights_centre)) continue;
        if (em->obj == h->obj) continue;        /* a sphere or a flat triangle lights not itself */
        if (too_dim(s, weight * area_light_bound(s, &s->mat[h->mat], l, h->p), wk)) continue;
        for (q = 0; q < s->shadow_rays; q++) {
            area_point(wk, l, q, &u, &v);
            sample_emitter(s, l, h->p, n, h->time, u, v, &wi, &dist, &Le, &pdf);
            e = dot(n, wi);
            if (!(pdf > 0)) continue;
            if (!(e > 0) && !s->set.no_skip) { wk->count.behind++; continue; }   /* facing away: no ray */
            if (!light_visible(s, h, l, wi, dist, wk) || !(e > 0)) continue;
            *color = comb(e / ((real)PI * pdf * s->shadow_rays), Le, *color);
        }
    }
}

/* The numbers of shadow ray q towards light l: the R2 points of
 * sample_offset, which spread any number of rays evenly over the light,
 * shifted by this level's random offset (Cranley-Patterson, as the path
 * tracer's pixels are) and by a fraction of its own for each light, so
 * that no two lights cast the same pattern. */
static void area_point(const Worker *wk, int l, int q, real *u, real *v)
{
    real dx, dy;
    sample_offset(q, (real)0.5, &dx, &dy);
    *u = dx + bounce_random(wk, LIGHT_U) + (real)0.6180339887498949 * l;
    *v = dy + bounce_random(wk, LIGHT_V) + (real)0.3819660112501051 * l;
    *u -= floor(*u);
    *v -= floor(*v);
}

/* Glossy reflection: the mirror ray spread into the Phong lobe about the
 * mirror direction, drawn as the path tracer draws its glossy lobe, from
 * this level's direction numbers.  Its weight stays the mirror's, ks, so
 * that as shine grows it becomes the mirror ray. */
static vec glossy_mirror(vec mirror, real shine, const Worker *wk)
{
    return from_local(mirror, phong_lobe(shine, bounce_random(wk, DIRECTION_U),
                                         bounce_random(wk, DIRECTION_V)));
}

/* The lecture's shadow ray: is light l seen from the hit point?  *e returns
 * its strength kl * cos(angle to the normal n), *to_light the unit vector
 * toward it (shade() needs it again for the highlight).  share: the most
 * the light can change the pixel through this hit (for too_dim; below 0:
 * always sent). */
static int shadow_ray(const Scene *s, const Hit *h, vec n, const Light *l, real share,
                      real *e, vec *to_light, Worker *wk)
{
    /* a glowing sphere that moves is where it is at the hit's instant */
    vec from = l->sphere >= 0 ? rest_frame(s, l->sphere, h->time, h->p) : h->p;
    vec dir = *to_light = unit(sub(l->pos, from));
    Ray r;
    Hit blocker;
    int seen;
    real k = l->sphere >= 0 ? s->mat[s->sph[l->sphere].mat].kl : 1;
    *e = k * dot(n, dir);
    if (!(*e > 0) && !s->set.no_skip) return wk->count.behind++, 0;  /* facing away: no ray (the SPD's rule) */
    if (too_dim(s, share, wk)) return 0;                             /* it could not change the pixel */
    wk->count.shadow++;
    r = spawn(s, h, dir);
    if (l->sphere < 0)          /* a point light: anything before it blocks */
        seen = !any_hit(s, r, sqrt(dot(sub(l->pos, r.o), sub(l->pos, r.o))),
                        &wk->blocker[(l - s->light) % SHADOW_SLOTS], wk);
    else
        seen = nearest_hit(s, r, &blocker, wk) && blocker.obj == l->sphere;
    return seen && *e > 0;      /* --no-skip traces a light behind the surface too: it lights nothing */
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
 * SPD's, allows at most 30.  --no-skip traces every ray of weight above 0
 * (the budget stays: it is what keeps a render finite).  */
#define MIN_WEIGHT (1.0 / 512)
static int worth_tracing(const Scene *s, real k, real weight, int depth, Worker *wk)
{
    if (!(k > 0 && depth > 1)) return 0;
    if (!(k * weight >= MIN_WEIGHT || s->set.no_skip)) return wk->count.faint++, 0;
    if (wk->budget > 0) { wk->budget--; return 1; }
    wk->count.cut++;
    return 0;
}

/* Shadow rays not worth sending: a light whose share of the pixel is
 * bound to be under what the sample can still leave out.  Each primary
 * ray's tree may leave out a quarter of an 8-bit step of the pixel in all
 * (dim_budget; through the sRGB curve, whose steepest slope is 12.92 at
 * black, a quarter step of the bytes it writes), spent as it goes: a
 * light whose bound, times the weight of the ray that found the hit, is
 * still within what remains gets no shadow ray, and the remainder shrinks
 * by it.  So whatever lights are left out, however many, together they
 * change the pixel by under a quarter step, and its byte by at most one,
 * only where it lay that close to a rounding boundary.  The card's
 * glowing spheres (`lights centre`) always get theirs, so that the card's
 * scene stays the card's image, byte for byte.  --no-skip sends every
 * shadow ray. */
static real dim_budget(const Scene *s)
{
    return (real)0.25 / 255 / (s->set.srgb ? (real)12.92 : 1);
}

static int too_dim(const Scene *s, real share, Worker *wk)
{
    if (s->set.no_skip || !(share >= 0 && share <= wk->dim_budget)) return 0;
    wk->dim_budget -= share;
    wk->count.dim++;
    return 1;
}

/* The largest component of a colour. */
static real brightest(vec c) { return fmax(c.x, fmax(c.y, c.z)); }

/* The most a point light can add to a hit of material m: kd times its
 * colour times the material's (the cosine at most 1), and a highlight's ks
 * times its colour (cos^shine at most 1). */
static real point_light_bound(const Material *m, const Light *l)
{
    return brightest(l->color) * (m->kd * brightest(m->color) + (m->shine > 0 ? m->ks : 0));
}

/* The most area light l can add to what a hit of material m at x
 * reflects: kd times its colour times the light's radiance times the
 * solid angle of the sphere about its light tree box (the cosines at most
 * 1), over pi, as area_lights' sum estimates it. */
static real area_light_bound(const Scene *s, const Material *m, int l, vec x)
{
    const LightNode *leaf = &s->lights.node[s->lights.leaf[l]];
    int k, what = kind(s, s->lights.emit[l].obj, &k);
    const Material *glow = &s->mat[what == SPHERE ? s->sph[k].mat : s->tri[k].mat];
    vec d = sub(x, leaf->centre);
    real d2 = dot(d, d), omega = d2 > leaf->r2 ? 2 * (real)PI * (1 - sqrt(1 - leaf->r2 / d2)) : 2 * (real)PI;
    return m->kd * brightest(m->color) * glow->kl * brightest(glow->color) * omega / (real)PI;
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
 * (NFF's materials), a glossy lobe, or, with a roughness (`rough`), a GGX
 * microfacet lobe: a rough conductor alone, a rough coat over kd*colour
 * with it (microfacet_f, coat_through); kt is a smooth dielectric of
 * index ir.  The weights are scaled down to sum to 1 where they sum to
 * more (the card's glass ball has 1.1).  n and ng face the side wo comes
 * from; eta is the ratio n1/n2 of the indices for a ray going through. */
struct Bsdf {
    vec n, ng;
    vec albedo;             /* Lambertian: f = albedo / pi (times coat_through under a coat) */
    real glossy, shine;     /* modified Phong: f = glossy (shine+2)/(2 pi) cos^shine(alpha) */
    real mirror;            /* ideal mirror (a delta lobe) */
    real ggx, alpha;        /* GGX microfacets of roughness alpha, weight ggx (microfacet_f) */
    int coat;               /* 1: the GGX lobe is a dielectric coat of index COAT_IOR over albedo */
    real glass, eta;        /* smooth dielectric with Fresnel (delta lobes) */
    real p[5];              /* the chance to sample each lobe: diffuse, glossy, mirror, GGX, glass */
};
/* GGX_LOBE stands before GLASS_LOBE: sample_bsdf's walk through the chances
 * passes a lobe of chance 0 by subtracting 0, so a material without a
 * roughness picks its lobes from the same numbers exactly as before. */
enum { DIFFUSE_LOBE, GLOSSY_LOBE, MIRROR_LOBE, GGX_LOBE, GLASS_LOBE, LOBE_KINDS };

/* The coat's index of refraction: a varnish or a plastic's (n = 1.5
 * reflects 4% head on).  Fixed, since a coated material's ir is the card's
 * index for kt, which an opaque material leaves at 1 (no coat at all). */
#define COAT_IOR 1.5

/* The pixel's radiance: the mean of spp paths through random points of
 * it.  A sample that is not finite (from a degenerate scene) is counted
 * and left out, so that no NaN reaches an image. */
static vec pixel_radiance(const Scene *s, int i, int j, int spp, Worker *wk)
{
    Tally t;
    vec L;
    int k;
    memset(&t, 0, sizeof t);
    for (k = s->set.s0; k < s->set.s0 + spp && !pixel_done(s, &t, 16); k++) {     /* --adaptive: see pixel_done */
        L = sample_radiance(s, i, j, k, wk);
        if (!(isfinite(L.x) && isfinite(L.y) && isfinite(L.z))) {
            wk->count.discarded++;
            L = v3(0, 0, 0);
        }
        tally(&t, L);
        if (wk->hooks && wk->hooks->after_sample) wk->hooks->after_sample(s, i, j, k, wk, wk->hooks->data);
    }
    return pixel_mean(&t, wk);
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
    Ray r;
    real dx, dy, sx, sy, st;
    start_sample(wk, s, i, j, -1);          /* the pixel's shift: no sample's numbers */
    sx = random01(wk, DIM_PIXEL_X);
    sy = random01(wk, DIM_PIXEL_Y);
    st = s->moving ? random01(wk, DIM_TIME) : 0;    /* see shutter_time */
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
    r = primary_ray(s, i + dx, j + dy, wk);
    if (s->moving) r.time = shutter_time(s, k, st);
    if (s->set.estimator == LIGHT_TRACING) {     /* the camera's half, then one light path */
        vec L = through_mirrors(s, r, NULL, wk);
        trace_light_path(s, i, j, k, r.time, wk);
        return L;
    }
    if (s->set.estimator == BDPT) return bdpt(s, r, wk);
    if (s->set.estimator == PHOTON_MAPPING || s->set.estimator == PROGRESSIVE)
        return through_mirrors(s, r, wk->hooks->data, wk);
    return radiance(s, r, &path, wk);
}

/* L(x, wo) = Le(x, wo) + integral f Li cos, for the ray r arriving at x:
 * the radiance it carries back, estimated by one random path. */
static vec radiance(const Scene *s, Ray r, const Path *path, Worker *wk)
{
    Hit h;
    Bsdf b;
    Path next;
    vec wo = scale(-1, r.d), emission, direct, wi, f_cos_pdf, Li;
    real pdf;
    int lobe;
    if (!nearest_hit(s, r, &h, wk)) return sky(s, r.d, path);
    emission = emitted(s, &h, wo, path);         /* Le, weighed for the estimator */
    if (path->rays == s->set.max_rays || path->rays == MAX_PATH) return emission;
    bsdf_at(s, &h, wo, &b);
    /* this hit's block of random numbers; the next hit sets its own, and
     * nothing below draws after radiance() of the next ray returns */
    wk->bounce = path->rays - 1;
    direct = s->set.estimator == BSDF_ONLY ? v3(0, 0, 0) : sample_light(s, &h, &b, wo, wk);
    lobe = sample_bsdf(&b, wo, wk, &wi, &f_cos_pdf, &pdf);
    if (lobe < 0) return add(emission, direct);
    next.beta = mul(path->beta, f_cos_pdf);
    if (!survives(s, path->rays, &next.beta, &f_cos_pdf, wk)) return add(emission, direct);
    wk->count.bounced++;
    next.rays = path->rays + 1;
    next.counted = lobe == MIRROR_LOBE || lobe == GLASS_LOBE;
    next.pdf = pdf;
    next.from = h.p;
    next.n_from = b.n;
    Li = radiance(s, spawn(s, &h, wi), &next, wk);
    return add(add(emission, direct), mul(f_cos_pdf, Li));
}

/* ------------------------------------------------------------ light tracing */

/* Light tracing (--estimator light): the paths run the other way, from the
 * lights, as the light itself goes (Arvo, "Backward ray tracing", 1986;
 * Veach's thesis, 1997, section 10.2: the strategy t = 1 of bidirectional
 * path tracing).  At every vertex a light path meets, it is joined to the
 * camera by a straight line, and what that vertex sends along it is
 * splatted into the pixel the line crosses (to_camera).  A light path is
 * traced for every camera sample, from that sample's numbers, so the
 * bytes are the same on any number of threads.  The camera's own half
 * (through_mirrors) counts only the lights it sees, directly or through
 * mirrors and glass, since no straight line from a light path reaches the
 * camera through them; what the camera sees of a diffuse surface through
 * glass (the floor through the ball) no path of either half finds, and is
 * black.  The sky lights nothing (no light path starts from it); BSDFs are
 * taken as symmetric, which they are but for shading normals and the
 * radiance a refraction compresses (which cancels through a closed glass
 * object). */
#define LIGHT_PATH MAX_PATH             /* its numbers: the blocks after the camera path's */

/* The camera's half: the lights seen from the camera directly, or through
 * a chain of mirrors and glass; the first other lobe ends it.  With photon
 * maps (ph; light tracing's camera half has none), photon mapping's camera
 * half too: at each surface on the way that is not only a mirror or glass,
 * the direct light and the caustics, and at the first lobe that is not a
 * delta, the final gather (see photon mapping, below); progressive photon
 * mapping's has no final gather: its photons give all but the direct
 * light. */
static vec through_mirrors(const Scene *s, Ray r, const Photons *ph, Worker *wk)
{
    Path path;
    vec beta = v3(1, 1, 1), L = v3(0, 0, 0);
    int rays, most = s->set.max_rays ? s->set.max_rays : MAX_PATH;
    memset(&path, 0, sizeof path);
    path.counted = 1;                           /* whatever it meets counts in full */
    for (rays = 1; ; rays++) {
        Hit h;
        Bsdf b;
        vec wi, f_cos_pdf, wo = scale(-1, r.d);
        real pdf;
        int lobe;
        if (!nearest_hit(s, r, &h, wk)) return add(L, mul(beta, sky(s, r.d, &path)));
        L = add(L, mul(beta, emitted(s, &h, wo, &path)));
        if (rays == most) return L;
        bsdf_at(s, &h, wo, &b);
        wk->bounce = rays - 1;
        if (ph && smooth(&b)) L = add(L, mul(beta, direct_and_photons(s, &h, &b, wo, ph, most - rays, wk)));
        lobe = sample_bsdf(&b, wo, wk, &wi, &f_cos_pdf, &pdf);
        if (ph && lobe >= 0 && lobe != MIRROR_LOBE && lobe != GLASS_LOBE)
            return add(L, mul(mul(beta, f_cos_pdf), gathered(s, spawn(s, &h, wi), ph, rays + 1, wk)));
        if (lobe != MIRROR_LOBE && lobe != GLASS_LOBE) return L;
        beta = mul(beta, f_cos_pdf);
        r = spawn(s, &h, wi);
    }
}

/* One light path, from a light chosen by its power at the given time,
 * joined to the camera at every vertex.  beta is what the path carries:
 * Le cos over the pdf of its start, times f cos / pdf at every bounce, as
 * a camera path's throughput is (Veach 1997, eq. 10.6).  Its rays: the
 * light's first, each bounce's, and the line to the camera, at most -d. */
static void trace_light_path(const Scene *s, int i, int j, int k, real time, Worker *wk)
{
    Ray r;
    vec beta;
    real chance;
    Start from;
    int l, rays, most = s->set.max_rays ? s->set.max_rays : MAX_PATH;
    start_sample(wk, s, i, j, k);
    wk->bounce = LIGHT_PATH;
    l = down_the_tree(s, v3(0, 0, 0), v3(0, 0, 0), 1, bounce_random(wk, LIGHT_CHOICE), &chance);
    if (l < 0 || !emit_ray(s, l, time, wk, &r, &beta, &from)) return;
    beta = scale(1 / chance, beta);
    for (rays = 2; rays <= most; rays++) {     /* the line to the camera is ray number `rays` */
        Hit h;
        Bsdf b;
        vec wi, f_cos_pdf, wl = scale(-1, r.d);
        real pdf;
        if (!nearest_hit(s, r, &h, wk)) return;
        wk->count.bounced++;
        wk->bounce = LIGHT_PATH + rays - 1;
        bsdf_at(s, &h, wl, &b);
        to_camera(s, &h, &b, wl, beta, wk);
        if (rays == most || sample_bsdf(&b, wl, wk, &wi, &f_cos_pdf, &pdf) < 0) return;
        beta = mul(beta, f_cos_pdf);            /* f cos / pdf of the bounce */
        if (!survives(s, rays, &beta, &f_cos_pdf, wk)) return;
        r = spawn(s, &h, wi);
    }
}

/* A ray leaving light l at the given time, its point and direction drawn
 * from this bounce's numbers, and what it carries, Le cos / pdf: from a
 * point light of intensity I, sent the same way in every direction
 * (pdf 1 / 4 pi), 4 pi I; from a point of an emitting sphere or triangle
 * of area A (each side of a two-sided one counted: light_area), sent by
 * the cosine (pdf cos / pi), pi A Le.  *from gets the light's normal at
 * the start and the two pdfs, which bidirectional path tracing weighs
 * with.  0 when nothing can leave. */
static int emit_ray(const Scene *s, int l, real time, Worker *wk, Ray *r, vec *beta, Start *from)
{
    const Emitter *e = &s->lights.emit[l];
    const Material *m;
    real u = bounce_random(wk, LIGHT_U), v = bounce_random(wk, LIGHT_V), area = light_area(s, l);
    vec n, local = cosine_hemisphere(bounce_random(wk, DIRECTION_U), bounce_random(wk, DIRECTION_V));
    int k, what, inward = 0;
    r->tmin = 0, r->time = time, r->skip = -1;
    if (e->type == POINT_LIGHT) {
        real z = 1 - 2 * u, rho = sqrt(fmax(0, 1 - z * z));
        r->o = e->pos;
        r->d = from->n = v3(rho * cos(2 * PI * v), rho * sin(2 * PI * v), z);
        from->pdf_point = 1, from->pdf_dir = 1 / (4 * (real)PI);
        from->emit = e->intensity;
        *beta = scale(4 * (real)PI, e->intensity);
        return 1;
    }
    if (!(area > 0)) return 0;
    what = kind(s, e->obj, &k);
    if (what == SPHERE) {
        real z = 1 - 2 * u, rho = sqrt(fmax(0, 1 - z * z));
        n = v3(rho * cos(2 * PI * v), rho * sin(2 * PI * v), z);
        r->o = comb(s->sph[k].rad, n, s->sph[k].cen);
        m = &s->mat[s->sph[k].mat];
        inward = e->inward && bounce_random(wk, LOBE) < (real)0.5;    /* half the time, if at all */
        if (inward) {                           /* off the surface, as spawn() leaves a hit */
            r->o = comb(-64 * REAL_EPS * (maxabs(r->o) + maxabs(s->sph[k].cen) + s->sph[k].rad), n, r->o);
            n = scale(-1, n);
        }
    } else {
        triangle_sample(&s->tri[k], u, v, &r->o, &n);
        if (!s->tri[k].cull && bounce_random(wk, LOBE) < (real)0.5) n = scale(-1, n);   /* either side */
        m = &s->mat[s->tri[k].mat];
    }
    if (moves(s, e->obj)) r->o = comb(time, velocity(s, e->obj), r->o);
    r->d = from_local(n, local);
    r->skip = inward ? -1 : e->obj;             /* leaving outward, it cannot meet the surface again */
    from->n = n;
    from->pdf_point = 1 / area, from->pdf_dir = cosine_hemisphere_pdf(local.z);
    from->emit = scale(m->kl, m->color);
    *beta = scale((real)PI * area * m->kl, m->color);
    return 1;
}

/* The area light l emits from: a sphere's, or a triangle's, twice that
 * when light paths leave it from both sides; 0 for a point light, the sky
 * or a degenerate triangle. */
static real light_area(const Scene *s, int l)
{
    const Emitter *e = &s->lights.emit[l];
    int k;
    if (e->type == SPHERE_LIGHT) {
        kind(s, e->obj, &k);
        return 4 * (real)PI * s->sph[k].rad * s->sph[k].rad * (e->inward ? 2 : 1);
    }
    if (e->type == TRIANGLE_LIGHT) {
        vec c;
        kind(s, e->obj, &k);
        c = cross(s->tri[k].e1, s->tri[k].e2);
        return sqrt(dot(c, c)) / 2 * (s->tri[k].cull ? 1 : 2);
    }
    return 0;
}

/* Whether the camera sees the point that lies dist from it the other way
 * along wc: tested from the eye, as the camera's own ray would be (a
 * one-sided triangle lets a ray through from behind, not back), up to a
 * hair short of the point so that its own surface does not hide it. */
static int camera_sees(const Scene *s, vec wc, real dist, real time, Worker *wk)
{
    Ray r;
    r.o = s->cam.eye;
    r.d = scale(-1, wc);
    r.tmin = near_clip(&s->cam, r.d);
    r.skip = -1;
    r.time = time;
    return !any_hit(s, r, dist * (1 - 1024 * REAL_EPS), &wk->blocker[0], wk);
}

/* What vertex h of a light path, reached from direction wl with
 * throughput beta, sends to the camera, into the pixel the line to the
 * eye crosses (onto_film): beta f cos_y pdf / dist^2, the light that
 * leaves h towards the eye times how densely the camera's rays cover the
 * surface around h, over the light paths there are (one a sample of each
 * pixel; add_splats divides by the samples). */
static void to_camera(const Scene *s, const Hit *h, const Bsdf *b, vec wl, vec beta, Worker *wk)
{
    vec wc, f;
    real dist, x, y, pdf, cos_y;
    if (!onto_film(s, h->p, &wc, &dist, &x, &y, &pdf)) return;
    f = bsdf_eval(b, wl, wc);
    cos_y = fabs(dot(b->n, wc));
    if (!nonzero(f) || !(cos_y > 0)) return;
    wk->count.shadow++;
    if (!camera_sees(s, wc, dist, h->time, wk)) return;
    splat(s, wk, x, y, scale(cos_y * pdf / (dist * dist), mul(beta, f)));
}

/* Where the point p lands on the film: the direction wc from p to the
 * eye, the distance, the image position (x, y) in pixels, and the pdf per
 * solid angle with which a camera sample sends its ray through it, with
 * the samples spread evenly over the whole image.  The pinhole's image
 * plane stands D = w / (2 tan(fov / 2)) pixels from the eye, and a patch
 * of it of area dA fills the solid angle cos_c^3 dA / D^2 (cos_c: the
 * ray's angle to the view axis), so the pdf is D^2 / (cos_c^3 w h).  0
 * when p lies behind the camera, off the image or before the near clip. */
static int onto_film(const Scene *s, vec p, vec *wc, real *dist, real *x, real *y, real *pdf)
{
    const Camera *c = &s->cam;
    vec d = sub(c->eye, p);
    real D = (real)s->set.w / 2 / c->tan_half, cos_c, t;
    *dist = sqrt(dot(d, d));
    *wc = scale(1 / *dist, d);                  /* towards the eye */
    cos_c = -dot(*wc, c->fwd);
    if (!(cos_c > 0)) return 0;                 /* behind the camera */
    t = D / cos_c;
    *x = (real)s->set.w / 2 - t * dot(*wc, c->right);
    *y = (real)s->set.h / 2 + t * dot(*wc, c->up);
    if (!(*x >= 0 && *y >= 0 && *x < s->set.w && *y < s->set.h)) return 0;
    if (c->hither > 0 && (c->hither_sphere ? *dist : *dist * cos_c) < c->hither) return 0;
    *pdf = D * D / (cos_c * cos_c * cos_c * ((real)s->set.w * s->set.h));
    return 1;
}

/* ------------------------------------------------ bidirectional path tracing */

/* Bidirectional path tracing (--estimator bdpt: Veach and Guibas,
 * "Bidirectional estimators for light transport", Eurographics Rendering
 * Workshop 1994; Veach's thesis, 1997, chapter 10).  A sample traces two
 * subpaths: z_0 z_1 ... from the eye, as the path tracer does, and
 * y_0 y_1 ... from a light chosen by its power, as light tracing does.
 * Any prefix y_0 .. y_{s-1} of the one joined by a line to a prefix
 * z_0 .. z_{t-1} of the other is a path from the light to the eye:
 * strategy (s, t).  A path of k rays can be made in k + 1 such ways: by
 * the camera's subpath meeting a light (s = 0), by next-event estimation
 * from it (s = 1), by light tracing (t = 1), or by a line between the
 * two subpaths' middles.  Each estimate is weighed by the power heuristic
 * over all the ways its path could have been made (mis_weight: Veach and
 * Guibas 1995), so that each way counts where it samples best: the lamp's
 * light on the walls by s = 1, the caustic on the floor by t = 1, the
 * lamp seen through the glass ball by s = 0.  Those with t >= 2 belong to
 * the pixel the sample started in; those with t = 1 are splatted where
 * they land, as light tracing's are.  The sky is found only by the
 * camera's subpath (no light path starts from it), with weight 1.  One
 * strategy is left out: (1, 1), a point of a light splatted where the eye
 * sees it.  The camera's samples cover each pixel evenly (the R2 pattern),
 * which no pdf shows: a light the eye sees then costs s = 0 almost no
 * noise, and the splats would only add theirs (yet by their pdfs alone,
 * on a lamp as small and far as the caustic's, they would take nearly all
 * the weight). */
#define HALF_PATH 256       /* vertices of one subpath at most: a path under roulette
                             * reaches it with odds below 0.95^250 */

/* One vertex of a subpath: its hit and BSDF, the direction back along the
 * subpath, the throughput that reached it (its own f not included), and
 * its pdf per area twice: as its own subpath made it (fwd), and as the
 * other subpath would have, walking on through it the other way (rev).
 * delta: its subpath left it by a mirror or glass, so that no line can
 * join there.  The eye is z_0 (its point alone); the light's point is
 * y_0, with the light's normal as n and ng, and Le / pdf as beta. */
struct Vertex {
    Hit h;
    Bsdf b;
    vec wo, beta;
    real fwd, rev;
    int delta;
};

/* A sample's two subpaths: z[0 .. nz-1] from the eye and y[0 .. ny-1]
 * from a light, each at most most_z and most_y vertices long (a path has
 * -d rays at most, the line between them included); point: y_0 is a point
 * light, which no subpath from the eye can meet. */
struct Subpaths {
    Vertex z[HALF_PATH], y[HALF_PATH];
    int nz, ny, most_z, most_y, point;
};

/* The pdfs per area a join sets anew, where the other subpath now leads:
 * of z_{t-1} and z_{t-2} made from the light's side, and of y_{s-1} and
 * y_{s-2} from the eye's. */
struct Rev { real z1, z2, y1, y2; };

/* One sample of BDPT through the camera ray r: the two subpaths, then every
 * strategy (s, t) a path of at most -d rays allows, or --strategy's one. */
static vec bdpt(const Scene *s, Ray r, Worker *wk)
{
    Subpaths p;
    vec L = v3(0, 0, 0);
    int most = s->set.max_rays ? s->set.max_rays : MAX_PATH, t, k;
    if (subpaths(s, r, &p, wk) && chosen(s, 0, p.nz + 1)) L = mul(p.z[p.nz].beta, s->background);
    for (t = 1; t <= p.nz; t++)
        for (k = 0; k <= (t == 1 || p.ny > 1 ? p.ny : 1) && k + t - 1 <= most; k++) {
            if (k + t < 2 || (k == 1 && t == 1) || !chosen(s, k, t)) continue;
            if (t == 1) to_eye(s, &p, k, wk);
            else if (k == 0) L = add(L, met_light(s, &p, t));
            else if (k == 1) L = add(L, to_light(s, &p, t, wk));   /* needs no light subpath */
            else L = add(L, join(s, &p, k, t, wk));
        }
    return L;
}

/* The two subpaths of a sample into *p: the eye's along the camera ray r,
 * then the light's.  1 when the eye's last ray left the scene (the sky's
 * light: p->z[p->nz].beta times the background). */
static int subpaths(const Scene *s, Ray r, Subpaths *p, Worker *wk)
{
    int most = s->set.max_rays ? s->set.max_rays : MAX_PATH, escaped;
    p->most_z = most + 1 < HALF_PATH ? most + 1 : HALF_PATH;
    p->most_y = most < HALF_PATH ? most : HALF_PATH;
    memset(&p->z[0], 0, sizeof p->z[0]);
    p->z[0].h.p = r.o;
    p->nz = walk(s, r, v3(1, 1, 1), film_pdf(s, r.d), p->most_z, -1, p->z, wk, &escaped);
    p->ny = light_subpath(s, r.time, p, wk);
    return escaped;
}

/* Whether strategy (k, t) counts: every one, or --strategy's alone. */
static int chosen(const Scene *s, int k, int t)
{
    return s->set.strategy[0] < 0 || (s->set.strategy[0] == k && s->set.strategy[1] == t);
}

/* A subpath's walk from v[0] along r, a ray its side sent with the pdf
 * (per solid angle) pdf, carrying the throughput beta.  At each hit a
 * vertex: its pdf per area (fwd), then a direction from its BSDF, which
 * gives the vertex before it its pdf from this side (rev); on until the
 * BSDF or roulette ends the walk, a ray leaves the scene (*escaped, with
 * v[n].beta what it carries) or there are most vertices.  Vertex n draws
 * from bounce block first + n: the camera's, the path tracer's blocks; a
 * light's, light tracing's.  Returns how many vertices there are.
 *
 * A mirror or glass has no pdf, only a delta, the same whichever way the
 * path crosses it; what differs between strategies is how the directions
 * it turns spread out over the surfaces beyond.  So its pdf is taken as
 * the delta's unit mass per projected solid angle (Veach 1997, section
 * 10.3.5), which per solid angle is the cosine there, and is turned into a
 * pdf per area at the next vertex as any other: the weights then see that
 * the caustic's light, spread thin from a small lamp and gathered by the
 * ball, is found far better from the lamp than from the eye. */
static int walk(const Scene *s, Ray r, vec beta, real pdf, int most, int first, Vertex *v, Worker *wk,
                int *escaped)
{
    int n;
    *escaped = 0;
    for (n = 1; n < most; n++) {
        Vertex *cur = &v[n], *prev = &v[n - 1];
        vec wi, f_cos_pdf;
        int lobe;
        cur->beta = beta;
        if (!nearest_hit(s, r, &cur->h, wk)) { *escaped = 1; return n; }
        cur->wo = scale(-1, r.d);
        cur->fwd = to_area(pdf, prev->h.p, &cur->h);
        cur->rev = 0;
        cur->delta = 0;
        bsdf_at(s, &cur->h, cur->wo, &cur->b);
        if (n + 1 == most) return n + 1;
        wk->bounce = first + n;
        lobe = sample_bsdf(&cur->b, cur->wo, wk, &wi, &f_cos_pdf, &pdf);
        if (lobe < 0) return n + 1;
        cur->delta = lobe == MIRROR_LOBE || lobe == GLASS_LOBE;
        if (cur->delta) pdf = fabs(dot(wi, cur->b.n));   /* the delta's unit mass, as above */
        prev->rev = to_area(cur->delta ? fabs(dot(cur->wo, cur->b.n)) : bsdf_pdf(&cur->b, wi, cur->wo),
                            cur->h.p, &prev->h);
        beta = mul(beta, f_cos_pdf);
        if (!survives(s, n, &beta, &f_cos_pdf, wk)) return n + 1;
        wk->count.bounced++;
        r = spawn(s, &cur->h, wi);
    }
    return n;
}

/* The light's subpath into p->y: y_0 on a light chosen by its power, as
 * light tracing starts (emit_ray), and on from there; how many vertices
 * (0: no light can send any). */
static int light_subpath(const Scene *s, real time, Subpaths *p, Worker *wk)
{
    Ray r;
    Start from;
    vec beta;
    real chance;
    int l, escaped;
    p->point = 0;
    wk->bounce = LIGHT_PATH;
    l = down_the_tree(s, v3(0, 0, 0), v3(0, 0, 0), 1, bounce_random(wk, LIGHT_CHOICE), &chance);
    if (l < 0 || !emit_ray(s, l, time, wk, &r, &beta, &from)) return 0;
    wk->count.bounced++;
    p->point = s->lights.emit[l].type == POINT_LIGHT;
    memset(&p->y[0], 0, sizeof p->y[0]);
    p->y[0].h.p = r.o;
    p->y[0].h.n = p->y[0].h.ng = from.n;
    p->y[0].h.time = time;
    p->y[0].h.obj = s->lights.emit[l].obj;
    p->y[0].fwd = chance * from.pdf_point;
    p->y[0].beta = scale(1 / p->y[0].fwd, from.emit);
    return walk(s, r, scale(1 / chance, beta), from.pdf_dir, p->most_y, LIGHT_PATH, p->y, wk, &escaped);
}

/* A pdf per solid angle at the point `from` as a pdf per area at the hit
 * `to`: times the cosine there over the squared distance. */
static real to_area(real pdf, vec from, const Hit *to)
{
    vec d = sub(to->p, from);
    real d2 = dot(d, d);
    return d2 > 0 ? pdf * fabs(dot(to->ng, d)) / (d2 * sqrt(d2)) : 0;
}

/* The pdf per solid angle with which a camera sample sends its ray along
 * d (see onto_film). */
static real film_pdf(const Scene *s, vec d)
{
    real D = (real)s->set.w / 2 / s->cam.tan_half, cos_c = dot(d, s->cam.fwd);
    return D * D / (cos_c * cos_c * cos_c * ((real)s->set.w * s->set.h));
}

/* Strategy s = 0: the camera's subpath meets a light at z_{t-1}: what it
 * sends back along the subpath.  A glow no light path starts from (a
 * cone's; a sphere's inside, unless inside_seen) has no other strategy:
 * weight 1. */
static vec met_light(const Scene *s, const Subpaths *p, int t)
{
    const Vertex *e = &p->z[t - 1];
    const Material *m = &s->mat[e->h.mat];
    int l = s->lights.emitter[e->h.obj], k;
    Rev rev = { 0, 0, 0, 0 };
    vec Le;
    if (!(m->kl > 0) || !front_emits(s, e->h.obj, e->h.ng, e->wo)) return v3(0, 0, 0);
    Le = scale(m->kl, mul(e->beta, m->color));
    if (l < 0 || (kind(s, e->h.obj, &k) == SPHERE && dot(e->wo, e->h.ng) < 0 && !s->lights.emit[l].inward))
        return Le;
    rev.z1 = tree_chance(s, l, v3(0, 0, 0), v3(0, 0, 0), 1) / light_area(s, l);
    if (t >= 3) rev.z2 = to_area(fabs(dot(e->h.ng, e->wo)) / (real)PI, e->h.p, &p->z[t - 2].h);
    return scale(mis_weight(p, p->y, 0, t, rev, 0), Le);
}

/* Strategy s = 1: next-event estimation from z_{t-1}, its light chosen
 * and sampled as sample_light's are (the tree's choice, not the sky),
 * not as the light's subpath began.  Its weight takes the pdf of y_0 to be
 * the subpath's all the same (choice by power, a point by area): the
 * weights of a path's strategies then still add up to 1, which is all
 * MIS needs to stay unbiased (Veach 1997, section 9.2), and they need no
 * second light tree walk.  The inside of a sphere no light path leaves
 * inward: s = 0's alone. */
static vec to_light(const Scene *s, const Subpaths *p, int t, Worker *wk)
{
    const Vertex *v = &p->z[t - 1];
    Vertex y0;
    Rev rev;
    vec wi, Le, f;
    real dist, pdf, chance, cosi;
    int l, point;
    wk->bounce = t - 2;                         /* z_{t-1}'s block, as sample_light's */
    l = down_the_tree(s, v->h.p, v->b.n, s->set.light_choice == BY_POWER,
                      bounce_random(wk, LIGHT_CHOICE), &chance);
    if (l < 0) return v3(0, 0, 0);
    point = sample_emitter(s, l, v->h.p, v->b.n, v->h.time, bounce_random(wk, LIGHT_U),
                           bounce_random(wk, LIGHT_V), &wi, &dist, &Le, &pdf);
    cosi = dot(wi, v->b.n);
    f = bsdf_eval(&v->b, v->wo, wi);
    if (!(pdf > 0) || !(cosi > 0) || !nonzero(f)) return v3(0, 0, 0);
    memset(&y0, 0, sizeof y0);
    y0.h.p = comb(dist, wi, v->h.p);
    y0.h.ng = point ? wi : light_normal(s, l, y0.h.p, v->h.time);
    if (s->lights.emit[l].type == SPHERE_LIGHT && dot(y0.h.ng, wi) > 0 && !s->lights.emit[l].inward)
        return v3(0, 0, 0);
    if (!light_visible(s, &v->h, l, wi, dist, wk)) return v3(0, 0, 0);
    y0.fwd = tree_chance(s, l, v3(0, 0, 0), v3(0, 0, 0), 1) / (point ? 1 : light_area(s, l));
    rev.y1 = to_area(bsdf_pdf(&v->b, v->wo, wi), v->h.p, &y0.h);
    rev.y2 = 0;
    rev.z1 = to_area(point ? 1 / (4 * (real)PI) : fabs(dot(y0.h.ng, wi)) / (real)PI, y0.h.p, &v->h);
    rev.z2 = t >= 3 ? to_area(bsdf_pdf(&v->b, wi, v->wo), v->h.p, &p->z[t - 2].h) : 0;
    return scale(cosi / (pdf * chance) * mis_weight(p, &y0, 1, t, rev, point), mul(v->beta, mul(f, Le)));
}

/* The normal of light l at its point y, at the given time: a sphere's
 * outward, a triangle's front. */
static vec light_normal(const Scene *s, int l, vec y, real time)
{
    const Emitter *e = &s->lights.emit[l];
    int k;
    if (kind(s, e->obj, &k) == SPHERE)
        return scale(1 / s->sph[k].rad, sub(rest_frame(s, e->obj, time, y), s->sph[k].cen));
    return unit(cross(s->tri[k].e1, s->tri[k].e2));
}

/* Strategy t = 1 (s >= 2): y_{s-1} joined to the eye, as light tracing
 * does (to_camera), splatted where it lands. */
static void to_eye(const Scene *s, const Subpaths *p, int k, Worker *wk)
{
    const Vertex *v = &p->y[k - 1];
    Rev rev = { 0, 0, 0, 0 };
    vec wc, f;
    real dist, x, y, pdf, cos_y;
    if (!onto_film(s, v->h.p, &wc, &dist, &x, &y, &pdf)) return;
    f = bsdf_eval(&v->b, v->wo, wc);
    cos_y = fabs(dot(v->b.n, wc));
    if (!nonzero(f) || !(cos_y > 0)) return;
    rev.y1 = to_area(pdf, s->cam.eye, &v->h);
    rev.y2 = to_area(bsdf_pdf(&v->b, wc, v->wo), v->h.p, &p->y[k - 2].h);
    wk->count.shadow++;
    if (!camera_sees(s, wc, dist, v->h.time, wk)) return;
    splat(s, wk, x, y, scale(cos_y * pdf / (dist * dist) * mis_weight(p, p->y, k, 1, rev, p->point),
                             mul(v->beta, f)));
}

/* Strategy s, t >= 2: z_{t-1} and y_{s-1} joined by a line: f at each
 * end, and the geometry term cos cos / dist^2 between them, if nothing
 * lies between. */
static vec join(const Scene *s, const Subpaths *p, int k, int t, Worker *wk)
{
    const Vertex *a = &p->z[t - 1], *b = &p->y[k - 1];
    vec d = sub(b->h.p, a->h.p), wi, back, fa, fb;
    real d2 = dot(d, d), dist = sqrt(d2);
    Rev rev;
    Ray r;
    if (!(d2 > 0)) return v3(0, 0, 0);
    wi = scale(1 / dist, d), back = scale(-1, wi);
    fa = bsdf_eval(&a->b, a->wo, wi);
    fb = bsdf_eval(&b->b, b->wo, back);
    if (!nonzero(fa) || !nonzero(fb)) return v3(0, 0, 0);
    r = spawn(s, &a->h, wi);
    wk->count.shadow++;
    if (any_hit(s, r, dist * (1 - 1024 * REAL_EPS) - 128 * REAL_EPS * b->h.error_scale, &wk->blocker[0], wk))
        return v3(0, 0, 0);
    rev = join_rev(p, k, t, wi);
    return scale(dot(a->b.n, wi) * -dot(b->b.n, wi) / d2 * mis_weight(p, p->y, k, t, rev, p->point),
                 mul(mul(a->beta, fa), mul(b->beta, fb)));
}

/* The pdfs a join of z_{t-1} and y_{s-1} along wi (from the one to the
 * other) sets anew: each end's, and its neighbour's, as the other
 * subpath, walking on through the join, would have made it. */
static Rev join_rev(const Subpaths *p, int k, int t, vec wi)
{
    const Vertex *a = &p->z[t - 1], *b = &p->y[k - 1];
    vec back = scale(-1, wi);
    Rev rev;
    rev.z1 = to_area(bsdf_pdf(&b->b, b->wo, back), b->h.p, &a->h);
    rev.z2 = to_area(bsdf_pdf(&a->b, wi, a->wo), a->h.p, &p->z[t - 2].h);
    rev.y1 = to_area(bsdf_pdf(&a->b, a->wo, wi), a->h.p, &b->h);
    rev.y2 = to_area(bsdf_pdf(&b->b, back, b->wo), b->h.p, &p->y[k - 2].h);
    return rev;
}

/* The power heuristic's weight of strategy (s, t) for the path it made
 * (Veach 1997, section 10.2.1): 1 / sum over the strategies i that could
 * have made it of (p_i / p_s)^2.  Each ratio p_i / p_s follows from the
 * next one by one vertex changing sides, the pdf it has from the other
 * side (rev) over its own (fwd), walking out from the join both ways.  A
 * strategy is left out where it would join at a mirror or glass (a delta
 * vertex), start from the eye at a point light, or need a subpath longer
 * than it may be.  Roulette is left out of the pdfs: the weights still add
 * up to 1.  The join's own ends and their neighbours take rev's pdfs; y is
 * the light's subpath (for s = 1, the vertex to_light chose instead). */
static real mis_weight(const Subpaths *p, const Vertex *y, int k, int t, Rev rev, int point)
{
    real sum = 0, r = 1;
    int i;
    if (k + t == 2) return 1;                   /* a light the eye sees: s = 0's alone */
    for (i = t - 1; i >= 1; i--) {              /* strategy (k + t - i, i): the eye's side shorter */
        real rv = i == t - 1 ? rev.z1 : i == t - 2 ? rev.z2 : p->z[i].rev;
        r *= over(rv, p->z[i].fwd);
        if ((i == t - 1 || !p->z[i].delta) && !p->z[i - 1].delta && k + t - i <= p->most_y) sum += r * r;
    }
    r = 1;
    for (i = k - 1; i >= 0; i--) {              /* strategy (i, k + t - i): the light's side shorter */
        real rv = i == k - 1 ? rev.y1 : i == k - 2 ? rev.y2 : y[i].rev;
        int before = i > 0 ? y[i - 1].delta : point;
        r *= over(rv, y[i].fwd);
        if ((i == k - 1 || !y[i].delta) && !before && k + t - i <= p->most_z) sum += r * r;
    }
    return 1 / (1 + sum);
}

/* The ratio of a vertex's two pdfs, rev / fwd.  A rev of 0 (the other
 * side could not have made the vertex) makes the strategies beyond it 0
 * too, as they need it; fwd is never 0 for a vertex a walk made, but if
 * it rounds to 0 the ratio is 0 rather than infinite. */
static real over(real rev, real fwd) { return fwd > 0 ? rev / fwd : 0; }

/* ------------------------------------------------------------ photon mapping */

/* Photon mapping (--estimator photon: Jensen, "Global illumination using
 * photon maps", Eurographics Rendering Workshop 1996).  Two passes.
 * First, before the pixels (render()'s pre-pass), --photons N photons
 * leave the lights as light tracing's paths do, each with its share of
 * their power, and bounce on by their BSDFs and roulette; where one lands
 * on a surface that is not only a mirror or glass, it is kept: in the
 * global map always, in the caustic map too when every bounce before was
 * a mirror or glass (the light of a caustic).  Each map is a balanced
 * kd-tree (photons.c).  Then each camera sample follows mirrors and glass
 * to the first other surface x (through_mirrors, above), and there adds
 *
 *   - the direct light, by next-event estimation (sample_light);
 *   - the caustics, from the caustic map: the k photons nearest x, each
 *     photon's power times f, over the disc they fill (photon_estimate);
 *   - the rest, by one final-gather ray from x's BSDF: where it meets the
 *     next such surface (through mirrors and glass), the global map's
 *     estimate there (gathered).
 *
 * The estimates from the maps are biased: they blur the light over the
 * disc of the k nearest photons, which shrinks as the photons grow in
 * number, so the bias falls with them (tests/photons.test.sh measures it).
 * The sky lights only directly (no photon leaves it), and a final-gather
 * ray meets only the smooth part of a surface that is also a mirror.  The
 * photons are shot on one thread from their own numbers (a hash of the
 * seed and the photon's number), so the maps, and the image, are the same
 * on any number of threads; any split render of the image shoots the same
 * photons.  Where things move, each photon leaves at its own instant of
 * the shutter (its block's SPARE number), so the maps hold the light of
 * the whole shutter, blurred. */
#define PHOTON_K 64             /* photons an estimate takes */
#define DEFAULT_PHOTONS 200000  /* --photons */

/* A map: where each photon landed, the power it brings, the direction it
 * came from, the rays it took from the light, and the tree over the
 * points. */
struct PhotonMap {
    float (*at)[3];
    vec *power, *from;
    int *rays;
    int n, cap;
    PointTree tree;
    real r2;                    /* a tenth of the diagonal of the photons' box, squared */
};

/* Both maps, and the estimates' radius at most (squared): a tenth of the
 * diagonal of the box the first map's photons fill.  Progressive (see
 * progressive photon mapping, below): the pass's photons in the global
 * map, the pilot's in pilot, and the pass's radii over the first's,
 * shrink, for pass `shrunk`.  key: the photons' numbers; into: the map
 * the photons go to, when progressive. */
struct Photons {
    PhotonMap caustic, global, pilot;
    real r2;
    unsigned long long key;
    int progressive;
    PhotonMap *into;
    real shrink;
    int shrunk;
};

/* The pre-pass: every photon, then the trees.  Progressive: every photon
 * of the pass s->set.s0 (the last pass's gone), and the pilot's before
 * the first pass. */
static void shoot_photons(const Scene *s, void *data)
{
    Photons *ph = data;
    Worker wk;
    int i;
    memset(&wk, 0, sizeof wk);
    for (i = 0; i < SHADOW_SLOTS; i++) wk.blocker[i] = -1;
    ph->key = mix64(s->set.seed + 0x70686f746f6eULL);
    if (ph->progressive && !ph->into) {         /* the pilot: photon mapping's numbers */
        ph->into = &ph->pilot;
        for (i = 0; i < s->set.photons; i++) shoot_photon(s, ph, i, &wk);
        build_map(&ph->pilot);
    }
    if (ph->progressive) {
        ph->key = mix64(ph->key + 1 + (unsigned)s->set.s0);
        ph->into = &ph->global;
        ph->global.n = 0;
        point_tree_free(&ph->global.tree);
        ph->shrink = pass_shrink(s, ph);
    }
    for (i = 0; i < s->set.photons; i++) shoot_photon(s, ph, i, &wk);
    if (!ph->progressive) build_map(&ph->caustic);
    build_map(&ph->global);
    if (!ph->r2) ph->r2 = ph->progressive ? ph->pilot.r2 : ph->global.r2;
}

/* The tree over m's photons, and the radius bound of an estimate in it:
 * a tenth of the diagonal of the photons' box. */
static void build_map(PhotonMap *m)
{
    vec lo = v3(INFINITY, INFINITY, INFINITY), hi = scale(-1, lo), d;
    int i;
    for (i = 0; i < m->n; i++) {
        vec p = v3(m->at[i][0], m->at[i][1], m->at[i][2]);
        lo = v3(fmin(lo.x, p.x), fmin(lo.y, p.y), fmin(lo.z, p.z));
        hi = v3(fmax(hi.x, p.x), fmax(hi.y, p.y), fmax(hi.z, p.z));
    }
    d = sub(hi, lo);
    m->r2 = m->n ? dot(d, d) / 100 : 0;
    if (!point_tree_build(&m->tree, (const float (*)[3])m->at, m->n)) out_of_memory();
}

/* Photon i: from a light chosen by its power (emit_ray), its power the
 * light's Le cos / pdf over the photons there are, on until its BSDF or
 * roulette ends it.  Roulette follows the throughput since the light (a
 * photon's power is small; its chance to go on must not be).  Progressive:
 * kept only after a bounce (the direct light is next-event estimation's),
 * in the pass's map or the pilot's. */
static void shoot_photon(const Scene *s, Photons *ph, int i, Worker *wk)
{
    Ray r;
    Start from;
    vec start, through = v3(1, 1, 1);
    real chance, time;
    int l, rays, caustic = 0, most = s->set.max_rays ? s->set.max_rays : MAX_PATH;
    wk->key = mix64(ph->key ^ (unsigned long long)i);
    wk->sample = -1;
    wk->bounce = LIGHT_PATH;
    l = down_the_tree(s, v3(0, 0, 0), v3(0, 0, 0), 1, bounce_random(wk, LIGHT_CHOICE), &chance);
    time = s->moving ? s->shutter[0] + (s->shutter[1] - s->shutter[0]) * bounce_random(wk, SPARE) : 0;
    if (l < 0 || !emit_ray(s, l, time, wk, &r, &start, &from)) return;
    start = scale(1 / (chance * s->set.photons), start);
    for (rays = 1; rays < most; rays++) {
        Hit h;
        Bsdf b;
        vec wi, f_cos_pdf, wl = scale(-1, r.d);
        real pdf;
        int lobe;
        if (!nearest_hit(s, r, &h, wk)) return;
        bsdf_at(s, &h, wl, &b);
        if (smooth(&b) && ph->progressive && rays > 1) keep_photon(ph->into, h.p, mul(start, through), wl, rays);
        if (smooth(&b) && !ph->progressive) {
            keep_photon(&ph->global, h.p, mul(start, through), wl, rays);
            if (caustic) keep_photon(&ph->caustic, h.p, mul(start, through), wl, rays);
        }
        wk->bounce = LIGHT_PATH + rays;
        lobe = sample_bsdf(&b, wl, wk, &wi, &f_cos_pdf, &pdf);
        if (lobe < 0) return;
        caustic = (rays == 1 || caustic) && (lobe == MIRROR_LOBE || lobe == GLASS_LOBE);
        through = mul(through, f_cos_pdf);
        if (!survives(s, rays + 1, &through, &f_cos_pdf, wk)) return;
        r = spawn(s, &h, wi);
    }
}

/* One more photon in map m. */
static void keep_photon(PhotonMap *m, vec p, vec power, vec from, int rays)
{
    if (m->n == m->cap) {           /* the same growth for the four arrays */
        int a = m->cap, b = m->cap, c = m->cap, d = m->cap;
        m->at = grow(m->at, &a, m->n + 1, sizeof *m->at);
        m->power = grow(m->power, &b, m->n + 1, sizeof *m->power);
        m->from = grow(m->from, &c, m->n + 1, sizeof *m->from);
        m->rays = grow(m->rays, &d, m->n + 1, sizeof *m->rays);
        m->cap = a;
    }
    m->rays[m->n] = rays;
    m->at[m->n][0] = (float)p.x, m->at[m->n][1] = (float)p.y, m->at[m->n][2] = (float)p.z;
    m->power[m->n] = power;
    m->from[m->n++] = from;
}

/* Whether a BSDF has a part that is no delta (Lambert, Phong, GGX): what
 * photons land on and estimates are made for. */
static int smooth(const Bsdf *b)
{
    return b->p[DIFFUSE_LOBE] + b->p[GLOSSY_LOBE] + b->p[GGX_LOBE] > 0;
}

/* At a surface the camera's half of photon mapping meets, not only a
 * mirror or glass: the direct light, by next-event estimation, and the
 * caustics, from the caustic map's photons that took at most `most` rays;
 * progressive: all the light but the direct, from the pass's photons. */
static vec direct_and_photons(const Scene *s, const Hit *h, const Bsdf *b, vec wo, const Photons *ph,
                              int most, Worker *wk)
{
    return add(sample_light(s, h, b, wo, wk), ph->progressive ? disc_estimate(ph, h, b, wo, most)
                                                              : photon_estimate(ph, &ph->caustic, h, b, wo, most));
}

/* A final-gather ray: through mirrors and glass to the next smooth
 * surface, and the global map's estimate of what leaves it back along
 * the ray (not its emission, nor the sky: the direct light is counted at
 * the gathering point already).  Progressive photon mapping has none. */
static vec gathered(const Scene *s, Ray r, const Photons *ph, int rays, Worker *wk)
{
    vec beta = v3(1, 1, 1);
    int most = s->set.max_rays ? s->set.max_rays : MAX_PATH;
    if (ph->progressive) return v3(0, 0, 0);
    for (; rays <= most; rays++) {
        Hit h;
        Bsdf b;
        vec wi, f_cos_pdf, wo = scale(-1, r.d);
        real pdf;
        if (!nearest_hit(s, r, &h, wk)) return v3(0, 0, 0);
        bsdf_at(s, &h, wo, &b);
        if (smooth(&b)) return mul(beta, photon_estimate(ph, &ph->global, &h, &b, wo, most - rays));
        wk->bounce = rays - 1;
        if (sample_bsdf(&b, wo, wk, &wi, &f_cos_pdf, &pdf) < 0) return v3(0, 0, 0);
        beta = mul(beta, f_cos_pdf);
        if (!survives(s, rays, &beta, &f_cos_pdf, wk)) return v3(0, 0, 0);
        r = spawn(s, &h, wi);
    }
    return v3(0, 0, 0);
}

/* The radiance the photons of map m near h send towards wo: each of the
 * PHOTON_K nearest (within the radius) its power times f, over the area
 * pi r^2 of the disc they fill, r the farthest one's distance (Jensen
 * 1996, eq. 6; the whole radius where fewer are found).  The farthest is
 * left out of the sum: it lies on the disc's edge by its choice, and
 * counting it too would make the estimate k / (k - 1) times too bright
 * where the photons are uniform (the disc holds k - 1 on average).  Only
 * the photons that took at most `most` rays count: the rays the camera's
 * side has left under -d. */
static vec photon_estimate(const Photons *ph, const PhotonMap *m, const Hit *h, const Bsdf *b, vec wo,
                           int most)
{
    int idx[PHOTON_K], i, n;
    float d2[PHOTON_K], x[3];
    vec L = v3(0, 0, 0);
    real r2;
    if (!m->n) return L;
    x[0] = (float)h->p.x, x[1] = (float)h->p.y, x[2] = (float)h->p.z;
    n = point_tree_nearest(&m->tree, x, PHOTON_K, (float)ph->r2, idx, d2);
    if (!n) return L;
    if (n == PHOTON_K) r2 = d2[--n];
    else r2 = ph->r2;
    for (i = 0; i < n; i++)
        if (counts(m, idx[i], h, b, r2, most)) L = add(L, mul(bsdf_eval(b, wo, m->from[idx[i]]), m->power[idx[i]]));
    return scale(1 / ((real)PI * r2), L);
}

/* Whether photon i of map m counts in an estimate at h of radius sqrt(r2):
 * it took at most `most` rays (what the camera's side has left under -d),
 * and lies near h's own plane, within a tenth of the radius, so that a
 * corner's estimate takes no photons of the wall across it. */
static int counts(const PhotonMap *m, int i, const Hit *h, const Bsdf *b, real r2, int most)
{
    real off = dot(sub(v3(m->at[i][0], m->at[i][1], m->at[i][2]), h->p), b->ng);
    return m->rays[i] <= most && off * off <= r2 / 100;
}

/* ------------------------------------------------ progressive photon mapping */

/* Progressive photon mapping (--estimator ppm: Hachisuka, Ogaki and
 * Jensen, "Progressive photon mapping", SIGGRAPH Asia 2008; stochastic:
 * Hachisuka and Jensen 2009), in the form of Knaus and Zwicker,
 * "Progressive photon mapping: a probabilistic approach", ACM TOG 2011.
 * Photon mapping's estimate is biased by its radius r (it blurs the light
 * over a disc) and noisy by the photons in the disc; with N photons the
 * one falls as r^2 shrinks, the other as N r^2 grows.  So render in
 * passes, each with photons of its own and one sample of every pixel,
 * and shrink the radius a little each pass, slowly enough that the
 * photons in the disc still grow over the passes:
 *
 *     r_{i+1}^2 = r_i^2 (i + alpha) / (i + 1),    alpha = 2/3
 *
 * Pass i's image is plain photon mapping with a fixed radius r_i (every
 * photon within it, disc_estimate); the mean of the passes' images has
 * the mean of their biases, which falls as r_i^2 does, about as
 * i^(alpha - 1), and a variance that falls too, as i^(-alpha) (Knaus and
 * Zwicker, section 4): the estimate converges.  Because the passes are
 * independent, a pass is a sample like any other: the passes' sums add
 * as a split render's do, on any number of threads or machines.
 *
 * The first radius is the point's own, as Jensen's k nearest are: that of
 * the disc round it holding PPM_FIRST photons of a pilot map, shot once
 * before the passes like a pass's (as many, photon mapping's numbers).
 * So a caustic, where the photons crowd, starts sharp, and a dim wall
 * smooth; the pilot is no pass's, so each pass's radius at a point is
 * fixed before its photons come, as the argument above needs.  Per pass,
 * the camera's side is photon mapping's without the final gather:
 * mirrors and glass to the first other surface, the direct light there by
 * next-event estimation, the rest from the pass's photons (those kept
 * after a bounce). */
#define PPM_ALPHA ((real)2 / 3)
#define PPM_FIRST 16            /* pilot photons in the first disc */

/* Pass k = s->set.s0's radii (squared) over the first pass's: the product
 * of (i + alpha) / (i + 1) for i = 1..k, multiplied in that order whether
 * the passes come in turn (one more factor each) or not, so that its bits
 * are the same in any split of the passes. */
static real pass_shrink(const Scene *s, Photons *ph)
{
    if (!ph->shrink || ph->shrunk > s->set.s0) ph->shrunk = 0, ph->shrink = 1;
    for (; ph->shrunk < s->set.s0; ph->shrunk++) ph->shrink *= (ph->shrunk + 1 + PPM_ALPHA) / (ph->shrunk + 2);
    return ph->shrink;
}

/* The pass's radius at h (squared): the first, the distance to the
 * PPM_FIRST-th nearest pilot photon (the whole bound where there are
 * fewer), times the pass's shrink. */
static real disc_radius2(const Photons *ph, const Hit *h)
{
    int idx[PPM_FIRST], n;
    float d2[PPM_FIRST], x[3];
    x[0] = (float)h->p.x, x[1] = (float)h->p.y, x[2] = (float)h->p.z;
    n = point_tree_nearest(&ph->pilot.tree, x, PPM_FIRST, (float)ph->r2, idx, d2);
    return (n == PPM_FIRST ? d2[n - 1] : ph->r2) * ph->shrink;
}

/* Pass's estimate at h: every photon within its radius r, its power times
 * f, over the disc's area pi r^2 (Hachisuka et al. 2008, eq. 6). */
typedef struct { const PhotonMap *m; const Hit *h; const Bsdf *b; vec wo, L; real r2; int most; } Disc;

static vec disc_estimate(const Photons *ph, const Hit *h, const Bsdf *b, vec wo, int most)
{
    Disc d;
    float x[3];
    if (!ph->global.n || !(ph->r2 > 0)) return v3(0, 0, 0);
    d.m = &ph->global, d.h = h, d.b = b, d.wo = wo, d.L = v3(0, 0, 0), d.most = most;
    d.r2 = disc_radius2(ph, h);
    x[0] = (float)h->p.x, x[1] = (float)h->p.y, x[2] = (float)h->p.z;
    point_tree_within(&ph->global.tree, x, (float)d.r2, in_disc, &d);
    return scale(1 / ((real)PI * d.r2), d.L);
}

static void in_disc(void *user, int i, float d2)
{
    Disc *d = user;
    (void)d2;
    if (counts(d->m, i, d->h, d->b, d->r2, d->most))
        d->L = add(d->L, mul(bsdf_eval(d->b, d->wo, d->m->from[i]), d->m->power[i]));
}

static void free_photons(Photons *ph)
{
    PhotonMap *m[3];
    int i;
    m[0] = &ph->caustic, m[1] = &ph->global, m[2] = &ph->pilot;
    for (i = 0; i < 3; i++) {
        point_tree_free(&m[i]->tree);
        free(m[i]->at);
        free(m[i]->power);
        free(m[i]->from);
        free(m[i]->rays);
    }
}

/* Russian roulette: from ROULETTE_FROM rays on, the path goes on with the
 * chance q that its throughput beta suggests (at most 0.95, so that a hall
 * of mirrors ends too), and what it brings back counts 1/q times. */
static int survives(const Scene *s, int rays, vec *beta, vec *f_cos_pdf, Worker *wk)
{
    real q, m = beta->x > beta->y ? beta->x : beta->y;
    if (m < beta->z) m = beta->z;
    if (!s->set.roulette || rays < ROULETTE_FROM) return 1;
    q = m < (real)0.95 ? m : (real)0.95;
    if (!(bounce_random(wk, ROULETTE) < q)) return 0;
    *beta = scale(1 / q, *beta);
    *f_cos_pdf = scale(1 / q, *f_cos_pdf);
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
    int l = s->lights.emitter[h->obj];
    real w = 1;
    if (!(m->kl > 0) || !front_emits(s, h->obj, h->ng, wo)) return v3(0, 0, 0);
    if (!path->counted && l >= 0 && s->set.estimator == NEE) return v3(0, 0, 0);
    if (!path->counted && l >= 0 && s->set.estimator == MIS)
        w = power_heuristic(path->pdf, light_pdf(s, l, path->from, path->n_from, h->p, h->ng, h->time));
    return scale(w * m->kl, m->color);
}

/* The background: a uniform radiance from every direction (the sky),
 * weighed like any light. */
static vec sky(const Scene *s, vec d, const Path *path)
{
    real w = 1;
    if (!path->counted && s->set.estimator == NEE) return v3(0, 0, 0);
    if (!path->counted && s->set.estimator == MIS && s->lights.sky >= 0)
        w = power_heuristic(path->pdf, light_pdf(s, s->lights.sky, path->from, path->n_from, d, d, 0));
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
    real chance;
    int l = choose_light(s, h->p, b->n, bounce_random(wk, LIGHT_CHOICE), &chance), delta;
    if (l < 0) return v3(0, 0, 0);
    delta = sample_emitter(s, l, h->p, b->n, h->time, bounce_random(wk, LIGHT_U),
                           bounce_random(wk, LIGHT_V), &wi, &dist, &Le, &pdf);
    if (!(pdf > 0)) return v3(0, 0, 0);
    pdf *= chance;
    cosi = dot(wi, b->n);
    f = bsdf_eval(b, wo, wi);
    if (!(cosi > 0) || (f.x == 0 && f.y == 0 && f.z == 0)) return v3(0, 0, 0);
    if (!light_visible(s, h, l, wi, dist, wk)) return v3(0, 0, 0);
    if (!delta && s->set.estimator == MIS) pdf /= power_heuristic(pdf, bsdf_pdf(b, wo, wi));
    return scale(cosi / pdf, mul(f, Le));
}

/* The shadow ray towards light l, along wi to the distance dist: does
 * nothing lie between?  The light itself does not block. */
static int light_visible(const Scene *s, const Hit *h, int l, vec wi, real dist, Worker *wk)
{
    Ray r = spawn(s, h, wi);
    wk->count.shadow++;
    if (s->lights.emit[l].type == SPHERE_LIGHT || s->lights.emit[l].type == TRIANGLE_LIGHT)
        r.skip = s->lights.emit[l].obj;
    return !any_hit(s, r, dist, &wk->blocker[l % SHADOW_SLOTS], wk);
}

/* Luminance of a linear sRGB colour (ITU-R BT.709 weights). */
static real luminance(vec c) { return (real)0.2126 * c.x + (real)0.7152 * c.y + (real)0.0722 * c.z; }

/* One more light, of the given power, at the end of the list (room for
 * it was made by prepare_lights), and its leaf of the light tree, made
 * here and put in place by light_tree(): its box, and the cone of its
 * normals (a point light and a sphere: any direction; a triangle: its
 * front normal, and its back too unless it is one-sided). */
static void add_emitter(Scene *s, int type, int obj, vec pos, vec intensity, real power)
{
    Lights *L = &s->lights;
    LightNode *leaf = &L->node[L->nemit];
    L->emit[L->nemit].type = type;
    L->emit[L->nemit].obj = obj;
    L->emit[L->nemit].pos = pos;
    L->emit[L->nemit].intensity = intensity;
    L->emit[L->nemit].inward = type == SPHERE_LIGHT && inside_seen(s, obj);
    L->emit[L->nemit].clip = L->emit[L->nemit].nclips = 0;
    if (obj >= 0) L->emitter[obj] = L->nemit;
    L->nemit++;
    if (type == SKY_LIGHT) return;
    memset(leaf, 0, sizeof *leaf);
    leaf->lo = leaf->hi = pos;
    if (obj >= 0) {
        double lo[3], hi[3];
        prim_bounds(s, obj, lo, hi);
        leaf->lo = v3((real)lo[0], (real)lo[1], (real)lo[2]);
        leaf->hi = v3((real)hi[0], (real)hi[1], (real)hi[2]);
    }
    leaf->axis = v3(0, 0, 1), leaf->cos_o = -1, leaf->sin_o = 0;
    if (type == TRIANGLE_LIGHT) {
        const Triangle *tr = &s->tri[obj - s->nsph - s->ncone];
        leaf->axis = unit(cross(tr->e1, tr->e2)), leaf->cos_o = 1;
        leaf->two_sided = !tr->cull;
    }
    leaf->cos_e = 0;                                  /* a lambertian emitter's pi / 2 */
    leaf->power = power;
    leaf->child[0] = leaf->child[1] = -1;
    sphere_of_box(leaf);
}

/* Whether the inside of glowing sphere i can be seen: the eye is in it,
 * or it is glass, or it moves (which this does not follow).  Only then do
 * light paths leave it inward as well as outward (emit_ray); where nothing
 * inside can be seen they would be wasted. */
static int inside_seen(const Scene *s, int i)
{
    const Sphere *sp = &s->sph[i];
    vec d = sub(s->cam.eye, sp->cen);
    return dot(d, d) < sp->rad * sp->rad || s->mat[sp->mat].kt > 0 || moves(s, i);
}

/* The path tracer's lights, each with its power: point lights (intensity
 * I: power 4 pi I), emitting spheres and triangles (radiance Le over area
 * A, each side: pi Le A), then the light tree over them.  A background
 * that is not black is the sky, whose power has no finite measure: it is
 * chosen half the time when there are other lights (pricing it by a
 * sphere about the scene, as pbrt does, starves a small lamp on a large
 * floor of shadow rays). */
static void prepare_lights(Scene *s)
{
    Lights *L = &s->lights;
    int i, k, n = nobj(s), *order;
    size_t most = (size_t)s->nlight + n + 1;      /* point lights, objects, the sky */
    free(L->emitter);                             /* made again, if made before */
    free(L->emit);
    free(L->node);
    free(L->leaf);
    L->emitter = malloc(((size_t)n + 1) * sizeof *L->emitter);
    L->emit = malloc(most * sizeof *L->emit);
    L->node = malloc(2 * most * sizeof *L->node);
    L->leaf = malloc(most * sizeof *L->leaf);
    order = malloc(most * sizeof *order);
    if (!L->emitter || !L->emit || !L->node || !L->leaf || !order) out_of_memory();
    L->nemit = 0;
    for (i = 0; i < n; i++) L->emitter[i] = -1;
    L->sky = -1;
    for (i = 0; i < s->nlight; i++)
        if (s->light[i].sphere < 0)
            add_emitter(s, POINT_LIGHT, -1, s->light[i].pos, s->light[i].color,
                        4 * (real)PI * luminance(s->light[i].color));
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
                    v3(0, 0, 0), (real)PI * m->kl * luminance(m->color) * area);
    }
    for (i = 0; i < L->nemit; i++) order[i] = i;
    L->nnode = L->nemit;                                 /* the leaves, then the inner nodes */
    L->root = L->nemit > 0 ? light_tree(L, order, L->nemit, -1) : -1;
    free(order);
    find_clips(s);
    if (luminance(s->background) > 0) {
        s->lights.sky = s->lights.nemit;
        add_emitter(s, SKY_LIGHT, -1, v3(0, 0, 0), v3(0, 0, 0), 0);
    }
}

/* The clips of each glowing sphere at rest: the opaque spheres at rest
 * whose surfaces cross its own.  A few a light are enough, since each alone
 * bounds what a point can see: those with the smallest caps are kept (a
 * wall may cut off half the lamp, and the ceiling all but a disc), smallest
 * first, so that visible_cap stops at the first that cannot beat what it
 * has; and where lights times spheres are too many to pair up, or with
 * --no-skip, none are looked for (the lights are then sampled whole: more
 * shadow rays blocked, the same mean).  Each cap's height, from the
 * lecture's cosine rule (d^2 = R^2 + rho^2 - 2 R rho cos) written as
 * products that do not cancel, is grown by a bound on its rounding, so
 * that no point a ray can meet falls outside it. */
#define MAX_CLIPS 4
#define CLIP_PAIRS 20000000.0
static real clip_size(const Clip *c) { return fmin(c->in, c->out); }

/* qsort's order of clips: by the smaller of their caps, smallest first. */
static int by_clip_size(const void *a, const void *b)
{
    real x = clip_size(a), y = clip_size(b);
    return (x > y) - (x < y);
}

/* Of light e's clips, the one whose smaller cap is the largest. */
static Clip *widest_clip(Lights *L, const Emitter *e)
{
    Clip *widest = &L->clip[e->clip];
    int i;
    for (i = e->clip + 1; i < e->clip + e->nclips; i++)
        if (clip_size(&L->clip[i]) > clip_size(widest)) widest = &L->clip[i];
    return widest;
}

static void find_clips(Scene *s)
{
    Lights *L = &s->lights;
    int l, j, spheres = 0;
    free(L->clip);
    L->clip = NULL, L->nclip = 0;
    for (l = 0; l < L->nemit; l++) spheres += L->emit[l].type == SPHERE_LIGHT;
    if (!spheres || s->set.no_skip || (double)spheres * s->nsph > CLIP_PAIRS) return;
    L->clip = malloc((size_t)spheres * MAX_CLIPS * sizeof *L->clip);
    if (!L->clip) out_of_memory();
    for (l = 0; l < L->nemit; l++) {
        Emitter *e = &L->emit[l];
        const Sphere *sp;
        e->clip = L->nclip, e->nclips = 0;
        if (e->type != SPHERE_LIGHT || moves(s, e->obj)) continue;
        sp = &s->sph[e->obj];                   /* spheres are the first objects */
        for (j = 0; j < s->nsph; j++) {
            const Sphere *o = &s->sph[j];
            vec a = sub(o->cen, sp->cen);
            real d = sqrt(dot(a, a)), R = sp->rad, rho = o->rad, margin;
            Clip c;
            if (j == e->obj || moves(s, j) || s->mat[o->mat].kt > 0) continue;
            if (!(d < R + rho) || !(d > fabs(R - rho))) continue;       /* the surfaces do not cross */
            margin = 64 * REAL_EPS * (R + d + rho) * (R + d + rho) / (2 * R * d);
            c.obj = j;
            c.axis = scale(1 / d, a);
            c.in = (rho - d + R) * (rho + d - R) / (2 * R * d) + margin;
            c.out = (R + d - rho) * (R + d + rho) / (2 * R * d) + margin;
            if (e->nclips < MAX_CLIPS) L->clip[e->clip + e->nclips++] = c;
            else {
                Clip *widest = widest_clip(L, e);
                if (clip_size(&c) < clip_size(widest)) *widest = c;
            }
        }
        qsort(&L->clip[e->clip], (size_t)e->nclips, sizeof *L->clip, by_clip_size);
        L->nclip += e->nclips;
    }
}

/* How many glowing spheres have clips (for --stats). */
static int clipped_lights(const Scene *s)
{
    int l, n = 0;
    for (l = 0; l < s->lights.nemit; l++) n += s->lights.emit[l].nclips > 0;
    return n;
}

/* The cap of glowing sphere l that holds every point of it x can see, when
 * a clip makes it smaller than what sphere_sample spreads its points over
 * (the part of the sphere that faces x, or from inside the whole sphere):
 * its axis and its height, as sphere_cap takes it.  Returns 0 when no clip
 * does.  Which of a clip's two caps x may see follows the side of the clip
 * x is on; a point on the clip's surface (within its rounding) sees the
 * side its normal n faces.  Sampling only the cap costs no bias, since the
 * rest could not be seen, and on smallpt's scene, where the ceiling hides
 * all but a disc 36 across of a lamp 1200 across, it turns shadow rays
 * that almost all met the ceiling into rays that almost all reach the
 * lamp. */
static int visible_cap(const Scene *s, int l, vec x, vec n, vec *axis, real *cap)
{
    const Emitter *e = &s->lights.emit[l];
    const Sphere *sp;
    vec dx;
    real d2, best;
    int i, found = 0;
    if (e->type != SPHERE_LIGHT || e->nclips == 0) return 0;
    sp = &s->sph[e->obj];
    dx = sub(x, sp->cen), d2 = dot(dx, dx);
    best = d2 > sp->rad * sp->rad * (1 + 64 * REAL_EPS) ? 1 - sp->rad / sqrt(d2) : 2;
    for (i = e->clip; i < e->clip + e->nclips && clip_size(&s->lights.clip[i]) < best; i++) {
        const Clip *c = &s->lights.clip[i];                 /* (smallest first: none after can do better) */
        const Sphere *o = &s->sph[c->obj];
        vec dq = sub(x, o->cen);
        real out = dot(dq, dq) - o->rad * o->rad;          /* > 0 outside, about 2 rho times the distance */
        real band = 2048 * REAL_EPS * o->rad * (o->rad + maxabs(o->cen) + maxabs(x));
        int inside = fabs(out) <= band ? dot(n, dq) < 0 : out < 0;
        real h = inside ? c->in : c->out;
        if (h < best) best = *cap = h, *axis = inside ? c->axis : scale(-1, c->axis), found = 1;
    }
    return found;
}

/* The light tree over lights order[0..n-1] below the given parent: its
 * root's node.  Split in two halves by count, across the widest spread of
 * their boxes' centres, so it is at most log2 n + 1 deep; each inner node
 * bounds its halves'. */
static int light_tree(Lights *L, int *order, int n, int parent)
{
    LightNode *in;
    int k, half = n / 2, a = 0;
    vec lo, hi;
    if (n == 1) {
        k = order[0];
        L->node[k].parent = parent, L->node[k].light = k;
        L->leaf[k] = k;
        return k;
    }
    k = L->nnode++;
    lo = hi = L->node[order[0]].centre;
    for (a = 1; a < n; a++) {
        vec c = L->node[order[a]].centre;
        lo = v3(fmin(lo.x, c.x), fmin(lo.y, c.y), fmin(lo.z, c.z));
        hi = v3(fmax(hi.x, c.x), fmax(hi.y, c.y), fmax(hi.z, c.z));
    }
    hi = sub(hi, lo);
    a = hi.x >= hi.y && hi.x >= hi.z ? 0 : hi.y >= hi.z ? 1 : 2;
    split_lights(L, order, n, half, a);
    in = &L->node[k];
    in->parent = parent, in->light = -1;
    in->child[0] = light_tree(L, order, half, k);
    in->child[1] = light_tree(L, order + half, n - half, k);
    bound_lights(in, &L->node[in->child[0]], &L->node[in->child[1]]);
    return k;
}

/* A node's bounding sphere: of its box, the centre and half the diagonal. */
static void sphere_of_box(LightNode *k)
{
    vec diag = sub(k->hi, k->lo);
    k->centre = scale((real)0.5, add(k->lo, k->hi));
    k->r2 = dot(diag, diag) / 4;
}

/* Coordinate a (0, 1, 2: x, y, z) of v. */
static real coordinate(vec v, int a) { return a == 0 ? v.x : a == 1 ? v.y : v.z; }

/* Reorders order[0..n-1] so that the lights before place m have centres
 * no further along axis a than those from m on (Hoare's FIND, 1961). */
static void split_lights(const Lights *L, int *order, int n, int m, int a)
{
    int lo = 0, hi = n - 1;
    while (lo < hi) {
        real pivot = coordinate(L->node[order[(lo + hi) / 2]].centre, a);
        int i = lo, j = hi;
        while (i <= j) {
            while (coordinate(L->node[order[i]].centre, a) < pivot) i++;
            while (coordinate(L->node[order[j]].centre, a) > pivot) j--;
            if (i <= j) { int t = order[i]; order[i++] = order[j]; order[j--] = t; }
        }
        if (m <= j) hi = j;
        else if (m >= i) lo = i;
        else break;
    }
}

/* Node k bounds nodes a and b: a box holding both boxes, a cone holding
 * both cones of normals (the smallest, when one does not hold the other:
 * its half-angle the mean of theirs and the angle between their axes, as
 * Conty Estevez and Kulla 2018 bound a union), the wider spread, and the
 * power of both. */
static void bound_lights(LightNode *k, const LightNode *a, const LightNode *b)
{
    real ta, tb, td, t;
    vec lo = a->lo, hi = a->hi, perp;
    k->lo = v3(fmin(lo.x, b->lo.x), fmin(lo.y, b->lo.y), fmin(lo.z, b->lo.z));
    k->hi = v3(fmax(hi.x, b->hi.x), fmax(hi.y, b->hi.y), fmax(hi.z, b->hi.z));
    sphere_of_box(k);
    k->power = a->power + b->power;
    k->two_sided = a->two_sided || b->two_sided;
    k->cos_e = fmin(a->cos_e, b->cos_e);
    if (a->cos_o > b->cos_o) { const LightNode *w = a; a = b; b = w; }   /* a: the wider */
    ta = acos(a->cos_o), tb = acos(b->cos_o);
    td = acos(fmax(-1, fmin(1, dot(a->axis, b->axis))));
    k->axis = a->axis, k->cos_o = a->cos_o, k->sin_o = a->sin_o;
    if (td + tb <= ta) return;                          /* a holds b */
    t = (ta + td + tb) / 2;
    perp = comb(-cos(td), a->axis, b->axis);            /* towards b, at right angles to a */
    if (t >= PI || !(dot(perp, perp) > 0)) { k->cos_o = -1, k->sin_o = 0; return; }
    perp = unit(perp);
    k->axis = unit(add(scale(cos(t - ta), a->axis), scale(sin(t - ta), perp)));
    k->cos_o = cos(t), k->sin_o = sin(t);
}

/* A light for the point x of normal n, chosen by the number u, and the
 * chance of choosing it; -1 when none can light x.  The sky half the
 * time when there are other lights; else down the tree, at each node one
 * half by its weight against the other's, the rest of u choosing on.  A
 * node whose bound let it be chosen may find both halves weigh 0: that
 * draw finds no light, so the chances add up to less than 1, but no light
 * that could reach x is ever left out, and the estimate stays unbiased. */
static int choose_light(const Scene *s, vec x, vec n, real u, real *chance)
{
    const Lights *L = &s->lights;
    int k = L->root, l;
    if (L->sky >= 0 && (k < 0 || u < (real)0.5)) {
        *chance = k < 0 ? 1 : (real)0.5;
        return L->sky;
    }
    if (L->sky >= 0) u = 2 * u - 1;
    l = down_the_tree(s, x, n, s->set.light_choice == BY_POWER, u, chance);
    if (L->sky >= 0) *chance *= (real)0.5;
    return l;
}

/* Down the light tree from its root, by the weights of the halves at x
 * (or by their power alone: light tracing, which has no point yet), the
 * light that u picks and the chance of picking it; -1 if none. */
static int down_the_tree(const Scene *s, vec x, vec n, int by_power, real u, real *chance)
{
    const Lights *L = &s->lights;
    int k = L->root;
    *chance = 1;
    if (k < 0) return -1;
    while (L->node[k].light < 0) {
        const int *c = L->node[k].child;
        real a = node_weight(s, c[0], x, n, by_power), b = node_weight(s, c[1], x, n, by_power);
        real p = a / (a + b);
        if (!(a + b > 0)) return -1;
        if (u < p || !(b > 0)) u = fmin(u / p, 1), *chance *= a / (a + b), k = c[0];
        else u = fmin((u - p) / (1 - p), 1), *chance *= b / (a + b), k = c[1];
    }
    return L->node[k].light;
}

/* How much sample_light favours the lights below node k at x: what they
 * may bring there, or (--light-choice power) their power alone. */
static real node_weight(const Scene *s, int k, vec x, vec n, int by_power)
{
    const LightNode *node = &s->lights.node[k];
    return by_power ? node->power : importance(node, x, n);
}

/* What the lights below node k may bring to the point x of normal n:
 * their power over the squared distance, times the cosine at each end as
 * large as any light within the box could make it (Conty Estevez and
 * Kulla 2018, eq. 3: the box seen from x as its bounding sphere, of
 * half-angle theta_b; the light's end within theta_o + theta_b of the
 * axis costs nothing, the point's end within theta_b of its normal).  It
 * is 0 only when no light below can send anything to x from above its
 * tangent plane, so choosing by it misses nothing next-event estimation
 * could have found.  The distance is to the box's centre, but no less
 * than a quarter of the sphere's radius: near the middle of a wide group
 * of lights it would otherwise outweigh its sibling on no evidence. */
static real importance(const LightNode *k, vec x, vec n)
{
    vec d = sub(x, k->centre);
    real d2 = dot(d, d), near = d2 > k->r2 / 16 ? d2 : k->r2 / 16, sin2_b, cos_b, cos_i;
    real cos_l = 1, cos_s = 1;
    if (!(near > 0)) return k->power;                   /* a point light at x */
    if (d2 <= k->r2) return k->power / near;            /* x in the sphere: no bound */
    sin2_b = k->r2 / d2, cos_b = sqrt(1 - sin2_b);
    d = scale(1 / sqrt(d2), d);                         /* from the lights to x */
    if (k->cos_o > -cos_b) {                            /* theta_o + theta_b < pi */
        real cos_ob = k->cos_o * cos_b - k->sin_o * sqrt(sin2_b), cos_w = dot(k->axis, d);
        if (k->two_sided) cos_w = fabs(cos_w);
        if (cos_w < cos_ob) cos_l = cos_w * cos_ob + sqrt(fmax(0, (1 - cos_w * cos_w) * (1 - cos_ob * cos_ob)));
        if (cos_l <= k->cos_e) return 0;                /* x lies behind every light */
    }
    cos_i = -dot(n, d);
    if (cos_i < cos_b) cos_s = cos_i * cos_b + sqrt(fmax(0, (1 - cos_i * cos_i) * sin2_b));
    if (cos_s <= 0) return 0;                           /* every light lies below x's horizon */
    return k->power * cos_l * cos_s / near;
}

/* The chance that choose_light picks light l at x, of normal n: the
 * sky's half, if there is a sky, and the tree's chance below. */
static real light_choice(const Scene *s, int l, vec x, vec n)
{
    const Lights *L = &s->lights;
    real chance = L->sky >= 0 && L->root >= 0 ? (real)0.5 : 1;
    if (l == L->sky) return chance;
    return chance * tree_chance(s, l, x, n, s->set.light_choice == BY_POWER);
}

/* The chance that down_the_tree picks light l at x: the same weights,
 * from l's leaf up to the root. */
static real tree_chance(const Scene *s, int l, vec x, vec n, int by_power)
{
    const Lights *L = &s->lights;
    real chance = 1;
    int k, up;
    for (k = L->leaf[l]; (up = L->node[k].parent) >= 0; k = up) {
        const int *c = L->node[up].child;
        real a = node_weight(s, c[0], x, n, by_power), b = node_weight(s, c[1], x, n, by_power);
        if (!(a + b > 0)) return 0;
        chance *= (k == c[0] ? a : b) / (a + b);
    }
    return chance;
}

/* A direction wi from x towards a point of light l chosen by the numbers
 * u and v, the distance dist to that point (INFINITY for the sky), the
 * radiance Le it sends back along -wi, and the pdf of wi in solid angle.
 * Returns 1 for a point light, which only this can find (its pdf is the
 * choice alone).  A light that moves is sampled where it stands at the
 * given time: from x as the light at rest sees it (directions and
 * distances are the same either way). */
static int sample_emitter(const Scene *s, int l, vec x, vec n, real time, real u, real v, vec *wi,
                          real *dist, vec *Le, real *pdf)
{
    const Emitter *e = &s->lights.emit[l];
    const Material *m;
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
    x = rest_frame(s, e->obj, time, x);
    if (e->type == SPHERE_LIGHT) {
        vec axis;
        real cap;
        *pdf = visible_cap(s, l, x, n, &axis, &cap) ? cap_sample(&s->sph[k], axis, cap, x, u, v, wi, dist)
                                                    : sphere_sample(&s->sph[k], x, u, v, wi, dist);
        m = &s->mat[s->sph[k].mat];
    } else {
        real area = triangle_light_sample(&s->tri[k], x, u, v, &y, &ny);   /* its solid angle, or 0 */
        *dist = sqrt(dot(sub(y, x), sub(y, x)));
        *wi = scale(1 / *dist, sub(y, x));
        *pdf = area > 0 ? 1 / area : triangle_pdf(&s->tri[k], *dist, dot(*wi, ny));   /* triangle_light_pdf's */
        m = &s->mat[s->tri[k].mat];
        if (!front_emits(s, e->obj, ny, scale(-1, *wi))) *pdf = 0;
    }
    *Le = scale(m->kl, m->color);
    return 0;
}

/* The pdf (in solid angle at x, choice included) with which sample_light
 * would have picked the point y, of normal ny, on light l at the given
 * time: what MIS needs for a light found by BSDF sampling.  For the sky, y
 * is the direction (and the time does not matter). */
static real light_pdf(const Scene *s, int l, vec x, vec n, vec y, vec ny, real time)
{
    const Emitter *e = &s->lights.emit[l];
    real chance = light_choice(s, l, x, n), dist;   /* where x is: the tree's lights are swept */
    vec d;
    int k;
    if (e->type == SKY_LIGHT) return chance * cosine_hemisphere_pdf(dot(y, n));
    kind(s, e->obj, &k);
    x = rest_frame(s, e->obj, time, x);
    y = rest_frame(s, e->obj, time, y);
    if (e->type == SPHERE_LIGHT) {
        vec axis;
        real cap;
        return chance * (visible_cap(s, l, x, n, &axis, &cap) ? cap_pdf(&s->sph[k], axis, cap, x, y)
                                                              : sphere_pdf(&s->sph[k], x, y));
    }
    d = sub(y, x);
    dist = sqrt(dot(d, d));
    return chance * triangle_light_pdf(&s->tri[k], x, dist, dot(d, ny) / dist);
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
    b->alpha = m->rough;
    b->ggx = m->rough > 0 ? k * m->ks : 0;            /* a roughness makes ks microfacets */
    b->coat = b->ggx > 0 && m->kd > 0;
    b->glossy = m->shine > 0 && b->ggx == 0 ? k * m->ks : 0;
    b->mirror = m->shine > 0 || b->ggx > 0 ? 0 : k * m->ks;
    b->glass = k * m->kt;
    b->p[DIFFUSE_LOBE] = fmax(b->albedo.x, fmax(b->albedo.y, b->albedo.z));
    b->p[GLOSSY_LOBE] = b->glossy;
    b->p[MIRROR_LOBE] = b->mirror;
    b->p[GGX_LOBE] = b->ggx;
    b->p[GLASS_LOBE] = b->glass;
    total = b->p[0] + b->p[1] + b->p[2] + b->p[3] + b->p[4];
    k = total > 0 ? 1 / total : 0;
    for (i = 0; i < LOBE_KINDS; i++) b->p[i] *= k;
}

/* f(x, wi, wo) for the lobes that are not deltas (Lambert, Phong, GGX).
 * Zero unless wi and wo lie on the same side of the surface, by both
 * normals. */
static vec bsdf_eval(const Bsdf *b, vec wo, vec wi)
{
    vec f = scale(1 / (real)PI, b->albedo);
    real g;
    if (!(dot(wi, b->ng) > 0 && dot(wi, b->n) > 0)) return v3(0, 0, 0);
    if (b->glossy > 0) {
        real c = fmax(0, dot(wi, reflect(scale(-1, wo), b->n, dot(wo, b->n))));
        g = b->glossy * (b->shine + 2) / (2 * (real)PI) * pow(c, b->shine);
        f = add(f, v3(g, g, g));
    }
    if (b->ggx > 0) {
        g = microfacet_f(b, wo, wi);
        f = add(b->coat ? scale(coat_through(b, wo, wi), f) : f, v3(g, g, g));
    }
    return f;
}

/* The pdf with which sample_bsdf draws wi, for the lobes that are not
 * deltas: cosine-weighted for Lambert, cos^shine about the mirror
 * direction for Phong, the visible normals' for GGX. */
static real bsdf_pdf(const Bsdf *b, vec wo, vec wi)
{
    real cosi = dot(wi, b->n), pdf;
    if (!(cosi > 0 && dot(wi, b->ng) > 0)) return 0;
    pdf = b->p[DIFFUSE_LOBE] * cosine_hemisphere_pdf(cosi);
    if (b->glossy > 0)
        pdf += b->p[GLOSSY_LOBE]
               * phong_lobe_pdf(b->shine, dot(wi, reflect(scale(-1, wo), b->n, dot(wo, b->n))));
    if (b->ggx > 0) pdf += b->p[GGX_LOBE] * microfacet_pdf(b, wo, wi);
    return pdf;
}

/* Draws wi from the BSDF: first a lobe, by the chances p, then a
 * direction from it.  *f_cos_pdf returns f cos(theta_i) / pdf, the factor the
 * light from wi is multiplied by; *pdf the pdf of wi (for MIS; undefined for
 * a delta lobe).  Returns the lobe, or -1 when the path ends here (the
 * light is absorbed, or the direction fell below the surface). */
static int sample_bsdf(const Bsdf *b, vec wo, Worker *wk, vec *wi, vec *f_cos_pdf, real *pdf)
{
    real u = bounce_random(wk, LOBE), cosi = dot(wo, b->n);
    real u1 = bounce_random(wk, DIRECTION_U), u2 = bounce_random(wk, DIRECTION_V);
    int lobe = 0;
    *pdf = 0;
    while (lobe < GLASS_LOBE && u >= b->p[lobe]) u -= b->p[lobe++];
    if (!(b->p[lobe] > 0)) return -1;
    if (lobe == MIRROR_LOBE) {
        *wi = reflect(scale(-1, wo), b->n, cosi);
        *f_cos_pdf = v3(b->mirror / b->p[lobe], b->mirror / b->p[lobe], b->mirror / b->p[lobe]);
        return dot(*wi, b->ng) > 0 ? lobe : -1;
    }
    if (lobe == GLASS_LOBE) return sample_glass(b, wo, u / b->p[lobe], wi, f_cos_pdf);
    if (lobe == DIFFUSE_LOBE) *wi = from_local(b->n, cosine_hemisphere(u1, u2));
    else if (lobe == GGX_LOBE) {
        if (!(cosi > 0)) return -1;              /* wo below the shading normal: no microfacet sees it */
        *wi = microfacet_sample(b, wo, u1, u2);
    } else *wi = from_local(reflect(scale(-1, wo), b->n, cosi), phong_lobe(b->shine, u1, u2));
    if (b->glossy == 0 && b->ggx == 0) {   /* Lambert alone: f cos / pdf is the albedo over its chance */
        *pdf = b->p[DIFFUSE_LOBE] * cosine_hemisphere_pdf(dot(*wi, b->n));
        *f_cos_pdf = scale(1 / b->p[DIFFUSE_LOBE], b->albedo);
        return dot(*wi, b->ng) > 0 && *pdf > 0 ? lobe : -1;
    }
    *pdf = bsdf_pdf(b, wo, *wi);
    if (!(*pdf > 0)) return -1;
    *f_cos_pdf = scale(dot(*wi, b->n) / *pdf, bsdf_eval(b, wo, *wi));
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
static int sample_glass(const Bsdf *b, vec wo, real u, vec *wi, vec *f_cos_pdf)
{
    real cosi = dot(wo, b->n), w = b->glass / b->p[GLASS_LOBE];
    vec d = scale(-1, wo);
    if (u < fresnel(cosi, b->eta) || !refract(d, b->n, cosi, b->eta, wi)) {
        *wi = reflect(d, b->n, cosi);
        *f_cos_pdf = v3(w, w, w);
        return dot(*wi, b->ng) > 0 ? GLASS_LOBE : -1;
    }
    w *= b->eta * b->eta;
    *f_cos_pdf = v3(w, w, w);
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

/* The GGX (Trowbridge-Reitz) distribution of microfacet normals, of
 * roughness alpha, at a normal h whose cosine to n is cos_h (Walter et al.,
 * "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007,
 * eq. 33, in the form alpha^2 / (pi (cos^2 (alpha^2 - 1) + 1)^2), with the
 * 1 - cos^2 kept apart so that a smooth surface's peak does not cancel).
 * Normalised as a density of microfacet area: its projection onto the
 * surface, the integral of D(h) cos_h over the hemisphere, is 1. */
static real ggx_d(real alpha, real cos_h)
{
    real a2 = alpha * alpha, c2 = cos_h * cos_h, k = (1 - c2) + c2 * a2;
    return cos_h > 0 ? a2 / ((real)PI * k * k) : 0;
}

/* Smith's Lambda for GGX, for a direction at cos_theta to n: masking is
 * G1 = 1 / (1 + Lambda) (Heitz, "Understanding the Masking-Shadowing
 * Function in Microfacet-Based BRDFs", JCGT 3(2), 2014):
 * Lambda = (sqrt(1 + alpha^2 tan^2 theta) - 1) / 2. */
static real smith_lambda(real alpha, real cos_theta)
{
    real c2 = cos_theta * cos_theta;
    return (sqrt(1 + alpha * alpha * (1 - c2) / c2) - 1) / 2;
}

static real smith_g1(real alpha, real cos_theta) { return 1 / (1 + smith_lambda(alpha, cos_theta)); }

/* The GGX lobe's f for wo and wi above n: Walter et al.'s (eq. 20)
 *
 *     f = ggx F(wo.h) D(h) G2(wo, wi) / (4 |n.wo| |n.wi|),  h = unit(wo + wi)
 *
 * with Smith's height-correlated masking-shadowing G2 = 1 / (1 + Lambda(wo)
 * + Lambda(wi)) (Heitz 2014), which is symmetric in wo and wi, as
 * is all else: the lobe is reciprocal.  F is 1 for the conductor (ks is
 * its reflectance, grey as the mirror's that it replaces), and the exact
 * dielectric Fresnel of COAT_IOR for the coat.  Single scattering only:
 * light that meets a second microfacet is lost, the more the rougher
 * (tests/test_pt.c measures how much). */
static real microfacet_f(const Bsdf *b, vec wo, vec wi)
{
    real co = dot(wo, b->n), ci = dot(wi, b->n), F = 1;
    vec h = unit(add(wo, wi));
    if (!(co > 0 && ci > 0)) return 0;
    if (b->coat) F = fresnel(dot(wo, h), 1 / (real)COAT_IOR);
    return b->ggx * F * ggx_d(b->alpha, dot(h, b->n))
           / (1 + smith_lambda(b->alpha, co) + smith_lambda(b->alpha, ci)) / (4 * co * ci);
}

/* The share of the light that passes the coat twice, down and up again,
 * for the diffuse base beneath: (1 - F(n.wo)) (1 - F(n.wi)), Fresnel's
 * transmission of a smooth interface at each end.  Symmetric, so the
 * whole stays reciprocal.  Energy: the coat's lobe reflects at most ks,
 * the base at most kd, and bsdf_at keeps kd + ks <= 1, so no more leaves
 * than came in (tests/test_pt.c's furnace measures it).  A simple layering,
 * not the exact one: light bounced between coat and base is lost, and
 * ks and kd are weights of their own (kd 0.5, ks 0.5 is half a coat over
 * half a base), as the card's weights are. */
static real coat_through(const Bsdf *b, vec wo, vec wi)
{
    return (1 - fresnel(fmax(0, dot(wo, b->n)), 1 / (real)COAT_IOR))   /* wo below a shading */
           * (1 - fresnel(dot(wi, b->n), 1 / (real)COAT_IOR));          /* normal: F = 1, none */
}

/* The pdf of the GGX lobe's direction wi: the visible normal h's, times
 * the Jacobian of the mirror map from h to wi, dh/dwi = 1 / (4 wo.h)
 * (Walter et al. 2007, eq. 14). */
static real microfacet_pdf(const Bsdf *b, vec wo, vec wi)
{
    vec h = unit(add(wo, wi));
    real oh = dot(wo, h);
    if (!(dot(wi, b->n) > 0)) return 0;
    return ggx_visible_normal_pdf(b->alpha, dot(wo, b->n), dot(h, b->n), oh) / (4 * oh);
}

/* A direction from the GGX lobe: wo mirrored about a visible normal. */
static vec microfacet_sample(const Bsdf *b, vec wo, real u1, real u2)
{
    vec h = from_local(b->n, ggx_visible_normal(to_local(b->n, wo), b->alpha, u1, u2));
    return reflect(scale(-1, wo), h, dot(wo, h));
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
    fill_hit(s, r, best, t, &q, h);
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
    if (s->accel.which != ACCEL_NONE) {
        double o[3], d[3], tmax = INFINITY;
        prim_counters c = { 0, 0, 0 };
        to3(q->r.o, o);
        to3(q->r.d, d);
        if (s->accel.which == ACCEL_KD)
            best = kd_nearest(s->accel.kd, &s->accel.prims, o, d, q, q->r.skip, q->r.tmin, &tmax, &c);
        else if (s->accel.which == ACCEL_BVH)
            best = bvh_nearest(s->accel.bvh, &s->accel.prims, o, d, q, q->r.skip, q->r.tmin, &tmax, &c);
        else
            best = grid_nearest(s->accel.grid, &s->accel.prims, o, d, q, q->r.skip, q->r.tmin, &tmax, &c);
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
    Ray moved;
    real tt, u, v;
    int k;
    (void)tmin;             /* rays start off the surface; see spawn() */
    /* q->r.skip never comes here: the tree leaves it out */
    if (kind(s, i, &k) == TRIANGLE) {   /* hit_object would test it again */
        const Ray *r = s->moving ? at_rest(s, i, &q->r, &moved) : &q->r;
        if (!hit_triangle(s, &s->tri[k], r, (real)tmax, &tt, &u, &v))
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
    Ray moved;
    real u, v;
    int k;
    if (i == r->skip) return 0;
    if (s->moving) r = at_rest(s, i, r, &moved);
    switch (kind(s, i, &k)) {
    case SPHERE: *t = hit_sphere(&s->sph[k], r, r->tmin); break;
    case CONE: *t = hit_cone(&s->cone[k], r, r->tmin); break;
    default: return hit_triangle(s, &s->tri[k], r, tmax, t, &u, &v);
    }
    return *t <= tmax && *t < INFINITY;         /* INFINITY is a miss */
}

/* A moving object is hit where it stands at the ray's time.  Rather than
 * move the object there, the ray moves the other way, by -time x velocity:
 * the same t (a translation keeps distances along the ray), the object's
 * own numbers untouched, and no arithmetic at all for an object at rest.
 * Returns r itself, or the ray moved into *moved. */
static const Ray *at_rest(const Scene *s, int i, const Ray *r, Ray *moved)
{
    if (!moves(s, i)) return r;
    *moved = *r;
    moved->o = rest_frame(s, i, r->time, r->o);
    return moved;
}

/* The point x as object i at rest sees it at that time: x less the way
 * the object has come, time x velocity (x itself for an object at rest). */
static vec rest_frame(const Scene *s, int i, real time, vec x)
{
    return moves(s, i) ? comb(-time, velocity(s, i), x) : x;
}

/* Whether object i moves: never in a scene where nothing does (the test
 * a static scene pays is s->moving alone). */
static int moves(const Scene *s, int i)
{
    return s->moving && nonzero(velocity(s, i));
}

/* Object i's velocity, its `move`: the way it goes per unit of time. */
static vec velocity(const Scene *s, int i)
{
    int k;
    switch (kind(s, i, &k)) {
    case SPHERE: return s->sph[k].move;
    case CONE: return s->cone[k].move;
    }
    return s->tri[k].move;
}

/* The point, normals and material of the hit on object i at t.  q (or
 * NULL) may hold the barycentrics of that hit already. */
static void fill_hit(const Scene *s, Ray r, int i, real t, const Query *q, Hit *h)
{
    int k, what = kind(s, i, &k);
    real u, v, tt;
    Ray moved;
    const Ray *rr = s->moving ? at_rest(s, i, &r, &moved) : &r;
    h->t = t;
    h->time = r.time;
    h->obj = i;
    if (what == SPHERE) sphere_surface(&s->sph[k], rr, t, h);
    else if (what == CONE) cone_surface(&s->cone[k], rr, t, h);
    else {
        if (q && q->obj == i && q->t == t) u = q->u, v = q->v;
        else hit_triangle(s, &s->tri[k], rr, INFINITY, &tt, &u, &v);
        triangle_surface(s, &s->tri[k], u, v, h);
    }
    if (rr != &r) {             /* found at rest: the point back to where the object is */
        vec way = scale(r.time, velocity(s, i));
        h->p = add(h->p, way);
        h->error_scale += maxabs(h->p) + maxabs(way);
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
    real eps = 64 * REAL_EPS * h->error_scale;
    int k, out = dot(dir, h->ng) >= 0, what = kind(s, h->obj, &k);
    Ray r;
    r.o = comb(out ? eps : -eps, h->ng, h->p);
    r.d = dir;
    r.tmin = 0;
    r.time = h->time;           /* the same instant: a shadow sees the scene as the hit did */
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
    if (s->accel.which != ACCEL_NONE && *last >= 0 && !s->set.no_skip) {
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
    if (s->accel.which != ACCEL_NONE) {
        double o[3], d[3];
        prim_counters c = { 0, 0, 0 };
        int hit;
        to3(q->r.o, o);
        to3(q->r.d, d);
        if (s->accel.which == ACCEL_KD)
            hit = kd_any(s->accel.kd, &s->accel.prims, o, d, q, q->r.skip, q->r.tmin, tmax, &c);
        else if (s->accel.which == ACCEL_BVH)
            hit = bvh_any(s->accel.bvh, &s->accel.prims, o, d, q, q->r.skip, q->r.tmin, tmax, &c);
        else
            hit = grid_any(s->accel.grid, &s->accel.prims, o, d, q, q->r.skip, q->r.tmin, tmax, &c);
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

/* The box of object i.  A moving object's is swept: every place it takes
 * while the shutter is open, so that a structure built once finds it at
 * any ray's time. */
static void prim_bounds(void *user, int i, double lo[3], double hi[3])
{
    const Scene *s = user;
    rest_box(s, i, lo, hi);
    if (moves(s, i)) sweep(s, i, lo, hi);
}

/* The box of object i where it was made. */
static void rest_box(const Scene *s, int i, double lo[3], double hi[3])
{
    int k;
    switch (kind(s, i, &k)) {
    case SPHERE: sphere_box(&s->sph[k], lo, hi); break;
    case CONE: cone_box(&s->cone[k], lo, hi); break;
    default: triangle_box(s, &s->tri[k], lo, hi);
    }
}

/* The box [lo, hi] of object i at rest swept over the shutter: a
 * translation moves the box along a line, so the union of its boxes at
 * the shutter's opening and closing holds all those between. */
static void sweep(const Scene *s, int i, double lo[3], double hi[3])
{
    double v[3], lo2[3], hi2[3], t0 = s->shutter[0], t1 = s->shutter[1];
    int a;
    to3(velocity(s, i), v);
    for (a = 0; a < 3; a++) {
        lo2[a] = lo[a] + t1 * v[a], hi2[a] = hi[a] + t1 * v[a];
        lo[a] += t0 * v[a], hi[a] += t0 * v[a];
    }
    box_union(lo, hi, lo2, hi2);
}

/* A sphere and a triangle at rest are clipped to the box exactly; a cone's
 * box, and a moving object's swept box, are simply cut to it. */
static int prim_clip(void *user, int i, const double blo[3], const double bhi[3],
                     double lo[3], double hi[3])
{
    const Scene *s = user;
    int k, a, what = kind(s, i, &k);
    if (what == SPHERE && !moves(s, i)) return sphere_clip(&s->sph[k], blo, bhi, lo, hi);
    if (what == TRIANGLE && !moves(s, i)) return triangle_clip(s, &s->tri[k], blo, bhi, lo, hi);
    prim_bounds(user, i, lo, hi);
    for (a = 0; a < 3; a++) {
        if (lo[a] < blo[a]) lo[a] = blo[a];
        if (hi[a] > bhi[a]) hi[a] = bhi[a];
        if (lo[a] > hi[a]) return 0;
    }
    return 1;
}

/* Which structure answers: built once, before the render. */

/* From this many objects on, the tree pays; below, a loop over them all
 * costs less than walking even a small tree.  Measured on scenes of random
 * spheres, 800x800 at 8 samples, one thread: 5 spheres, the loop 12% faster;
 * 8, even; 12 and 16, the tree 16% and 17% faster.  On the minray scene
 * (5 spheres) the loop is 25% faster. */
#define TREE_FROM 8

/* Up to this many objects auto also times the loop against the trees: where
 * most objects are large (smallpt's walls are spheres of radius 1e5, each
 * box holding the whole room), every tree tests nearly every object anyway
 * and the loop is quicker. */
#define LOOP_TRIAL 64

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
        for (i = 0; i < PROBE; i++) {
            Ray r = camera_ray(&s->cam, s->set.w, s->set.h, (i + (real)0.5) * s->set.w / PROBE,
                               (j + (real)0.5) * s->set.h / PROBE);
            r.time = s->shutter[0];     /* within the shutter, which the structure bounds */
            trace(s, r, s->set.depth, 1, &wk);
        }
        spent = (double)(clock() - start) / CLOCKS_PER_SEC;
    }
    return spent;
}

/* One structure built into s (ACCEL_KD, ACCEL_BVH or ACCEL_GRID); 0 when
 * out of memory. */
static int build_one(Scene *s, int which)
{
    s->accel.which = which;
    if (which == ACCEL_BVH) return (s->accel.bvh = bvh_build(nobj(s), &s->accel.prims, BVH_SAH)) != NULL;
    if (which == ACCEL_GRID) return (s->accel.grid = grid_build(nobj(s), &s->accel.prims)) != NULL;
    return (s->accel.kd = kd_build(nobj(s), &s->accel.prims)) != NULL;
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
 * build.  The probe itself costs 1/256 of a 512x512 image per structure.
 * Below LOOP_TRIAL objects the loop over them all takes the first turn. */
#define KD_BUILD_RATIO 8.0
static int choose_accel(Scene *s)
{
    static const int which[3] = { ACCEL_BVH, ACCEL_GRID, ACCEL_KD };
    double best = HUGE_VAL, cost, built = 0, scale = (double)s->set.w * s->set.h / (PROBE * PROBE);
    int k, pick = 0;
    if (nobj(s) < LOOP_TRIAL && !s->set.no_skip) {
        s->accel.which = ACCEL_NONE;
        best = scale * probe(s, HUGE_VAL), pick = -1;
    }
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
        if (which[k] == ACCEL_KD && s->accel.kd) kd_free(s->accel.kd), s->accel.kd = NULL;
        if (which[k] == ACCEL_BVH) bvh_free(s->accel.bvh), s->accel.bvh = NULL;
        if (which[k] == ACCEL_GRID) grid_free(s->accel.grid), s->accel.grid = NULL;
    }
    s->accel.which = pick < 0 ? ACCEL_NONE : which[pick];
    return 1;
}

/* The structure that answers nearest_hit and any_hit, as --accel says: the
 * kd-tree, the BVH (its SAH build), the grid, none (every ray tests every
 * object), or auto: none below TREE_FROM objects, else the one that
 * choose_accel measures fastest on this scene (the loop too, below
 * LOOP_TRIAL). */
static int build_accel(Scene *s, const char *accel)
{
    int ok;
    s->accel.prims.bounds = prim_bounds;
    s->accel.prims.clip = prim_clip;
    s->accel.prims.hit = prim_hit;
    s->accel.prims.user = s;
    s->accel.prims.eps = REAL_EPS;              /* the hit callback's arithmetic (prims.h) */
    s->accel.which = ACCEL_NONE;
    if (!strcmp(accel, "none") || (!strcmp(accel, "auto") && nobj(s) < TREE_FROM && !s->set.no_skip)) return 1;
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

/* ------------------------------------------------- the primitives: spheres */

static void add_sphere(Scene *s, vec cen, real rad, int mat)
{
    Sphere *p;
    s->sph = grow(s->sph, &s->capsph, s->nsph + 1, sizeof *s->sph);
    p = &s->sph[s->nsph++];
    p->cen = cen;
    p->rad = rad;
    p->mat = mat;
    p->move = s->move;
    s->moving += nonzero(s->move);
    if (s->mat[mat].kl > 0) add_light(s, cen, s->mat[mat].color, s->nsph - 1);
}

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
 * The slide's form: with f = o - c, the point is on the sphere where
 *     (d.d) t^2 + 2 (f.d) t + f.f - r^2 = 0,
 *     t = (-(f.d) -+ sqrt((f.d)^2 - (d.d)(f.f - r^2))) / (d.d).
 * The code below finds the same two roots; its extra lines are for
 * precision only: they keep the roots right when the sphere is far from
 * the ray's origin or small beside it.
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
    h->error_scale = maxabs(h->p) + maxabs(sp->cen) + sp->rad + maxabs(r->o);
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

/* A uniform point of the cap of sphere sp about the unit axis, of height
 * cap (sphere_cap's), seen from x: wi towards it, its distance, and the
 * pdf of wi in solid angle, the cap's area turned into solid angle as from
 * inside in sphere_sample.  A light's clip gives the cap (visible_cap). */
static real cap_sample(const Sphere *sp, vec axis, real cap, vec x, real u, real v, vec *wi, real *dist)
{
    vec y = comb(sp->rad, from_local(axis, sphere_cap(cap, u, v)), sp->cen), d = sub(y, x);
    *dist = sqrt(dot(d, d));
    *wi = scale(1 / *dist, d);
    return cap_pdf(sp, axis, cap, x, y);
}

/* The pdf with which cap_sample, from x, picks the direction to y, a point
 * of the sphere: 0 off the cap, and 0 where y faces away from an x outside
 * the sphere (the sphere itself hides it). */
static real cap_pdf(const Sphere *sp, vec axis, real cap, vec x, vec y)
{
    vec u = scale(1 / sp->rad, sub(y, sp->cen)), d = sub(x, y), dc = sub(x, sp->cen);
    real dist2 = dot(d, d), cosy = dot(u, d) / sqrt(dist2);
    if (dot(u, axis) < 1 - cap) return 0;
    if (dot(dc, dc) <= sp->rad * sp->rad * (1 + 64 * REAL_EPS)) cosy = fabs(cosy);   /* from inside */
    if (!(cosy > 0)) return 0;
    return dist2 / (2 * (real)PI * sp->rad * sp->rad * cap * cosy);
}

/* --------------------------------------------------- the primitives: cones */

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
    c->move = s->move;
    s->moving += nonzero(s->move);
}

/* A cone from base (radius rb) to apex (radius ra). */
static int add_checked_cone(Scene *s, vec base, real rb, vec apex, real ra, int mat, char *why)
{
    if (!(rb >= 0 && ra >= 0 && rb + ra > 0))
        return sprintf(why, "cone radii must be >= 0 and not both 0"), 0;
    if (!within_far_limit_by(base, rb, why) || !within_far_limit_by(apex, ra, why)) return 0;
    if (!(dot(sub(apex, base), sub(apex, base)) > 0))
        return sprintf(why, "cone base and apex coincide"), 0;
    /* Shorter than this, the rounding of a point's height along the axis
     * exceeds the length itself, and the side would be found where it is
     * not (the fuzz targets found one 1e-71 long, hit at the eye). */
    if (!(sqrt(dot(sub(apex, base), sub(apex, base))) >= 1e-9 * (fmax(rb, ra) + maxabs(base) + maxabs(apex))))
        return sprintf(why, "cone shorter than 1e-9 of its radius and coordinates"), 0;
    add_cone(s, base, rb, apex, ra, mat);
    return 1;
}

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
    h->error_scale = maxabs(h->p) + maxabs(c->base) + c->len + c->rb + c->ra + maxabs(r->o);
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
    tr->move = s->move;
    s->moving += nonzero(s->move);
    tr->cull = (char)s->cull;
    tr->degenerate = (char)degenerate(s->vert[a], s->vert[b], s->vert[c]);
}

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
    h->error_scale = maxabs(a) + maxabs(b) + maxabs(c);
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

/* A triangle light seen from x: sampled by the solid angle it fills where
 * that is at least SOLID_ANGLE_FROM (Arvo's method, below), so that every
 * direction towards it is as likely; else by its area, where the two
 * differ little (a small or far triangle's dist^2 / cos hardly changes
 * over it) and Arvo's angles lose their precision as the triangle shrinks
 * to a point.  The rule depends on x and the triangle alone, so that
 * light_pdf finds the pdf sample_emitter used.  Returns the solid angle
 * it sampled by (the pdf is its inverse), or 0 for the area form. */
#define SOLID_ANGLE_FROM 0.01
static real triangle_light_sample(const Triangle *tr, vec x, real u, real v, vec *y, vec *ny)
{
    vec c[3], wi;
    real angle[3], area = spherical_triangle(tr, x, c, angle);
    if (!(area >= SOLID_ANGLE_FROM)) {
        triangle_sample(tr, u, v, y, ny);
        return 0;
    }
    wi = spherical_triangle_sample(c, angle, area, u, v);
    *ny = unit(cross(tr->e1, tr->e2));
    *y = comb(dot(sub(tr->v0, x), *ny) / dot(wi, *ny), wi, x);   /* where wi meets the plane */
    return area;
}

/* The triangle projected onto the unit sphere round x: c, the unit vectors
 * to its corners; angle, the spherical triangle's angle at each (between
 * the great arcs to the other two); returns its area, the solid angle,
 * angle[0] + angle[1] + angle[2] - pi (Girard's theorem); 0 when a corner
 * is x or two corners are seen in one direction. */
static real spherical_triangle(const Triangle *tr, vec x, vec c[3], real angle[3])
{
    int i;
    c[0] = unit(sub(tr->v0, x));
    c[1] = unit(sub(add(tr->v0, tr->e1), x));
    c[2] = unit(sub(add(tr->v0, tr->e2), x));
    for (i = 0; i < 3; i++) {
        vec a = c[i], b = c[(i + 1) % 3], d = c[(i + 2) % 3];
        vec tb = sub(b, scale(dot(a, b), a)), td = sub(d, scale(dot(a, d), a));   /* the arcs' tangents */
        if (!(dot(tb, tb) > 0 && dot(td, td) > 0)) return 0;
        angle[i] = acos(fmax(-1, fmin(1, dot(unit(tb), unit(td)))));
    }
    return angle[0] + angle[1] + angle[2] - (real)PI;
}

/* A direction uniform in the spherical triangle c (angles angle, area
 * area) from u1, u2: Arvo, "Stratified sampling of spherical triangles",
 * SIGGRAPH 1995.  u1 chooses the sub-triangle A B C' of area u1 times the
 * whole, by where its third corner C' lies on the arc from A to C (a
 * closed form from the area's formula); u2 then a point on the arc from B
 * to C', by the cosine of its distance from B, which makes it uniform in
 * area.  Each step is a bijection, so stratified u1, u2 stay stratified. */
static vec spherical_triangle_sample(const vec c[3], const real angle[3], real area, real u1, real u2)
{
    vec A = c[0], B = c[1], C = c[2], Cs, t;
    real alpha = angle[0], sub_area = u1 * area, sn = sin(sub_area - alpha), cs = cos(sub_area - alpha);
    real uu = cs - cos(alpha), vv = sn + sin(alpha) * dot(A, B);
    real q = ((vv * cs - uu * sn) * cos(alpha) - vv) / ((vv * sn + uu * cs) * sin(alpha)), z;
    q = fmax(-1, fmin(1, q));                       /* the cosine of C' from A */
    t = sub(C, scale(dot(C, A), A));
    Cs = add(scale(q, A), scale(sqrt(fmax(0, 1 - q * q)), unit(t)));
    z = 1 - u2 * (1 - dot(Cs, B));                  /* the cosine of the point from B */
    t = sub(Cs, scale(dot(Cs, B), B));
    if (!(dot(t, t) > 0)) return B;
    return add(scale(z, B), scale(sqrt(fmax(0, 1 - z * z)), unit(t)));
}

/* Its pdf in solid angle, for a point at distance dist whose normal is at
 * cosine cosy to the line of sight. */
static real triangle_light_pdf(const Triangle *tr, vec x, real dist, real cosy)
{
    vec c[3];
    real angle[3], area = spherical_triangle(tr, x, c, angle);
    return area >= SOLID_ANGLE_FROM ? 1 / area : triangle_pdf(tr, dist, cosy);
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
 * the threads and render()'s hooks, --view, the builder through which
 * scene.c's readers fill a Scene, what --stats prints, and main().  The
 * files beside this one do the rest: scene.c, image.c, cli.c.
 * ========================================================================= */

/* ------------------------------------------------ threads, render()'s hooks */

typedef struct {
    int spp, threads, progress;   /* spp: each pixel's samples, of a split render's part too */
    double start;                 /* when the render began (now()), for the progress line */
    const Hooks *hooks;           /* NULL: none */
    Partial *part;                /* a partial render's sums, or NULL (see keep_sums) */
    unsigned char *done;          /* with part: the rows done (row y0 + r: done[r]), */
    const char *checkpoint;       /* where they are saved, */
    double every;                 /* every so many seconds (0: never) */
} Options;

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
    to->behind += from->behind;
    to->dim += from->dim;
    to->faint += from->faint;
    to->samples += from->samples;
    if (from->spp_max && (!to->spp_max || from->spp_min < to->spp_min)) to->spp_min = from->spp_min;
    if (from->spp_max > to->spp_max) to->spp_max = from->spp_max;
    if (from->threads > to->threads) to->threads = from->threads;
}

/* The rows in the order they are handed out: k-th row j = k * stride mod h,
 * for a stride near h / golden ratio with no factor in common with h, so
 * that the rows done at any moment are spread over the image and the
 * progress line's estimate is fair (the Cornell box's top rows, its black
 * ceiling around the lamp, take a fraction of the time of the rest). */
static int row_stride(int h)
{
    int a, b, stride = (int)(h * 0.6180339887) | 1;
    for (;; stride++) {
        for (a = stride, b = h; b; ) { int r = a % b; a = b; b = r; }
        if (a == 1) return stride;
    }
}

/* The splat image's fixed point: 2^32 units a unit of radiance.  Integers
 * add exactly in any order, so what many threads splat into their own
 * images sums to the same bytes for any number of threads and any order of
 * rows, which float sums would not. */
#define SPLAT_ONE 4294967296.0
#define SPLAT_MAX 1048576.0         /* a larger splat is clamped: no overflow */

/* Light L added to the pixel under image point (x, y), by a sample of any
 * pixel (light tracing's to_camera, or a hook's after_sample). */
static void splat(const Scene *s, Worker *wk, real x, real y, vec L)
{
    double c[3];
    int a, i = (int)floor(x), j = (int)floor(y);
    if (!wk->splat || i < 0 || j < 0 || i >= s->set.w || j >= s->set.h) return;
    to3(L, c);
    for (a = 0; a < 3; a++)
        if (c[a] > 0)               /* NaN too is left out */
            wk->splat[3 * ((size_t)j * s->set.w + i) + a] += (long long)(fmin(c[a], SPLAT_MAX) * SPLAT_ONE);
}

/* Every thread's splats summed, then added to the image of the pixels'
 * own estimates (floats, own) as light per sample, into img. */
static void add_splats(const Scene *s, const Options *o, long long **splats, int nthreads,
                       const Image *own, Image *img)
{
    size_t at, n = (size_t)s->set.w * s->set.h;
    int t, i, j;
    for (at = 0; at < 3 * n; at++)
        for (t = 1; t < nthreads; t++) splats[0][at] += splats[t][at];
    for (j = 0; j < s->set.h; j++)
        for (i = 0; i < s->set.w; i++) {
            const float *f = own->floats + 3 * ((size_t)j * s->set.w + i);
            const long long *q = splats[0] + 3 * ((size_t)j * s->set.w + i);
            put_pixel(img, i, j, v3((real)(f[0] + q[0] / SPLAT_ONE / o->spp),
                                    (real)(f[1] + q[1] / SPLAT_ONE / o->spp),
                                    (real)(f[2] + q[2] / SPLAT_ONE / o->spp)));
        }
}

/* Whitted's --adaptive: every pixel's first 4 samples, taken before the
 * rest (see neighbours_agree), on every thread; NULL when not needed.  For
 * a part of the image, those of its pixels and their neighbours. */
static Tally *first_samples(const Scene *s, const Options *o, int nthreads, Counts *total)
{
    int x0 = s->set.x0 > 0 ? s->set.x0 - 1 : 0, x1 = s->set.x1 < s->set.w ? s->set.x1 + 1 : s->set.w;
    int y0 = s->set.y0 > 0 ? s->set.y0 - 1 : 0, y1 = s->set.y1 < s->set.h ? s->set.y1 + 1 : s->set.h;
    Tally *first;
    (void)nthreads;                     /* without OpenMP: one */
    if (!(s->set.adaptive > 0) || s->set.integrator != WHITTED || o->hooks || o->spp <= 4
        || (s->set.view && s->set.view < VIEW_SAMPLES))
        return NULL;
    if (!(first = malloc((size_t)s->set.w * s->set.h * sizeof *first))) out_of_memory();
    OMP(omp parallel num_threads(nthreads))
    {
        Worker wk;
        int j;
        memset(&wk, 0, sizeof wk);
        OMP(omp for schedule(dynamic, 1))
        for (j = y0; j < y1; j++) {
            int i;
            for (i = 0; i < SHADOW_SLOTS; i++) wk.blocker[i] = -1;
            for (i = x0; i < x1; i++) {
                Tally *t = &first[(size_t)j * s->set.w + i];
                memset(t, 0, sizeof *t);
                take_samples(s, i, j, t, 4, &wk);
            }
        }
        OMP(omp critical)
        add_counts(total, &wk.count);
    }
    return first;
}

/* The whole image, row by row (render_row).  Rows go to threads one at a
 * time, as they free up; each pixel is written once by whoever computes it,
 * so the image does not depend on the order.  Each thread has its own
 * Worker; their counts are summed into *total.  With o->hooks, the
 * pre-pass runs first, and splats go to each thread's own splat image,
 * added to the pixels at the end (add_splats). */
static void render(const Scene *s, const Options *o, Image *img, Counts *total)
{
    int k;
    int rows = s->set.y1 - s->set.y0, done = 0, stride = row_stride(rows), nthreads = 1;
    int splats = (o->hooks && o->hooks->after_sample)
                 || (s->set.integrator == PATH && (s->set.estimator == LIGHT_TRACING || s->set.estimator == BDPT));
    long long **splat = NULL;
    Tally *first;
    Image own, *into = img;
    double saved = now();
    for (k = 0; o->done && k < rows; k++) done += o->done[k];     /* --resume: rows done before */
#ifdef _OPENMP
    if (o->threads > 0) omp_set_num_threads(o->threads);
    nthreads = o->threads > 0 ? o->threads : omp_get_max_threads();
#endif
    if (o->hooks && o->hooks->prepass) o->hooks->prepass(s, o->hooks->data);
    first = first_samples(s, o, nthreads, total);
    if (splats) {
        int t;
        splat = calloc((size_t)nthreads, sizeof *splat);
        if (!splat || !new_image(&own, s->set.w, s->set.h, 1, 0)) out_of_memory();
        into = &own;
        for (t = 0; t < nthreads; t++)
            if (!(splat[t] = calloc((size_t)s->set.w * s->set.h * 3, sizeof **splat))) out_of_memory();
    }
    OMP(omp parallel num_threads(nthreads))
    {
        Worker wk;
        memset(&wk, 0, sizeof wk);
        wk.count.threads = 1;
        wk.hooks = o->hooks;
        wk.first = first;
        wk.part = o->part;
#ifdef _OPENMP
        wk.count.threads = omp_get_num_threads();
        if (splats) wk.splat = splat[omp_get_thread_num()];
#else
        if (splats) wk.splat = splat[0];
#endif
        OMP(omp for schedule(dynamic, 1))
        for (k = 0; k < rows; k++) {
            int i, mine, r = (int)((long long)k * stride % rows);
            if ((o->done && o->done[r]) || stop_signal()) continue;   /* resumed; or asked to stop */
            /* a row starts with an empty shadow cache, so that the counts
             * do not depend on which thread had the row before */
            for (i = 0; i < SHADOW_SLOTS; i++) wk.blocker[i] = -1;
            render_row(s, s->set.y0 + r, o->spp, into, &wk);
            if (o->done) {
                OMP(omp critical)
                {
                    o->done[r] = 1;             /* whole: the next checkpoint saves it */
                    if (o->every > 0 && now() - saved >= o->every) {
                        save_partial(o->checkpoint, o->part, o->done);
                        saved = now();
                    }
                }
            }
            OMP(omp atomic capture)
            mine = ++done;
            if (o->progress && (mine * 100 / rows != (mine - 1) * 100 / rows))
                show_progress(o->start, mine, rows);
        }
        OMP(omp critical)
        add_counts(total, &wk.count);
    }
    if (splats) {
        int t;
        add_splats(s, o, splat, nthreads, &own, img);
        for (t = 0; t < nthreads; t++) free(splat[t]);
        free(splat);
        free_image(&own);
    }
    free(first);
    if (o->progress) fprintf(stderr, "\r%30s\r", "");
}

/* Progressive photon mapping's render: pass after pass, each its own
 * photons (the pre-pass, for the pass s->set.s0) and one sample of every
 * pixel, into part's sums, which add the passes as ray --merge adds a
 * split render's parts; so the bytes are those of any split of the
 * passes by --samples.  The image, when there is one, from the sums. */
static void image_of(const Partial *part, Image *img);

static void render_passes(Scene *s, const Options *o, Partial *part, Image *img, Counts *total)
{
    Options one = *o;
    Partial pass;
    int first = s->set.s0, k;
    size_t at, n = (size_t)(part->x1 - part->x0) * (part->y1 - part->y0);
    pass = *part;
    if (!new_partial(&pass)) out_of_memory();
    one.spp = 1, one.progress = 0, one.part = &pass, one.done = NULL;
    for (k = 0; k < o->spp && !stop_signal(); k++) {
        s->set.s0 = first + k;
        render(s, &one, NULL, total);
        for (at = 0; at < n; at++) {
            exact_sum(&part->sum[3 * at], &pass.sum[3 * at]);
            exact_sum(&part->sum[3 * at + 1], &pass.sum[3 * at + 1]);
            exact_sum(&part->sum[3 * at + 2], &pass.sum[3 * at + 2]);
            part->n[at] += pass.n[at];
        }
        if (o->progress) show_progress(o->start, k + 1, o->spp);
    }
    s->set.s0 = first;
    free_partial(&pass);
    total->spp_min = total->spp_max = o->spp;
    if (img) image_of(part, img);
    if (o->progress) fprintf(stderr, "\r%30s\r", "");
}

/* --------------------------------------------------------- partial renders */

/* A render split over machines (--crop, --tile, --samples; image.h): each
 * pixel's sums and count kept as they are, for ray --merge to add. */
static void keep_sums(Partial *part, int i, int j, const Tally *t)
{
    size_t at = (size_t)(j - part->y0) * (part->x1 - part->x0) + (i - part->x0);
    memcpy(&part->sum[3 * at], t->sum, sizeof t->sum);
    part->n[at] = (uint64_t)t->n;
}

/* The partial's pixels into img, each the mean of its samples, as the
 * render computes it (tally_mean): so a merge gives a whole run's bytes. */
static void image_of(const Partial *part, Image *img)
{
    int x, y;
    for (y = part->y0; y < part->y1; y++)
        for (x = part->x0; x < part->x1; x++) {
            size_t at = (size_t)(y - part->y0) * (part->x1 - part->x0) + (x - part->x0);
            Tally t;
            memcpy(t.sum, &part->sum[3 * at], sizeof t.sum);
            t.n = (int)part->n[at];
            put_pixel(img, x - part->x0, y - part->y0, t.n ? tally_mean(&t) : v3(0, 0, 0));
        }
}

/* FNV-1a, 64 bits, over n bytes: the scene's content hash. */
static uint64_t fold(uint64_t h, const void *p, size_t n)
{
    const unsigned char *b = p;
    while (n--) h = (h ^ *b++) * 1099511628211u;
    return h;
}
#define FOLD(h, x) ((h) = fold((h), &(x), sizeof(x)))

/* What the scene holds, as read (objects, materials, lights, camera,
 * background): a partial render's provenance names it, so that parts of
 * two scenes, or of one scene edited between them, are not merged.  Field
 * by field, not whole structures, whose padding holds any bytes. */
static uint64_t scene_hash(const Scene *s)
{
    uint64_t h = 14695981039346656037u;
    int i;
    for (i = 0; i < s->nmat; i++) {
        const Material *m = &s->mat[i];
        FOLD(h, m->color); FOLD(h, m->kd); FOLD(h, m->ks); FOLD(h, m->kt); FOLD(h, m->kl);
        FOLD(h, m->ir); FOLD(h, m->shine); FOLD(h, m->rough); FOLD(h, m->spread);
    }
    for (i = 0; i < s->nsph; i++) {
        const Sphere *b = &s->sph[i];
        FOLD(h, b->cen); FOLD(h, b->rad); FOLD(h, b->mat); FOLD(h, b->move);
    }
    for (i = 0; i < s->ncone; i++) {
        const Cone *c = &s->cone[i];
        FOLD(h, c->base); FOLD(h, c->axis); FOLD(h, c->len); FOLD(h, c->rb); FOLD(h, c->ra);
        FOLD(h, c->mat); FOLD(h, c->move);
    }
    for (i = 0; i < s->ntri; i++) {
        const Triangle *t = &s->tri[i];
        FOLD(h, t->v); FOLD(h, t->n); FOLD(h, t->mat); FOLD(h, t->move); FOLD(h, t->cull);
    }
    if (s->nvert) h = fold(h, s->vert, (size_t)s->nvert * sizeof *s->vert);
    if (s->nnorm) h = fold(h, s->norm, (size_t)s->nnorm * sizeof *s->norm);
    for (i = 0; i < s->nlight; i++) {
        FOLD(h, s->light[i].pos); FOLD(h, s->light[i].color); FOLD(h, s->light[i].sphere);
    }
    FOLD(h, s->cam.eye); FOLD(h, s->cam.right); FOLD(h, s->cam.up); FOLD(h, s->cam.fwd);
    FOLD(h, s->cam.tan_half); FOLD(h, s->cam.anchor); FOLD(h, s->cam.hither);
    FOLD(h, s->cam.hither_sphere); FOLD(h, s->cam.lens); FOLD(h, s->cam.focus);
    FOLD(h, s->ambient); FOLD(h, s->background); FOLD(h, s->tir_reflect); FOLD(h, s->lights_centre);
    FOLD(h, s->shadow_rays); FOLD(h, s->shutter);
    return h;
}

/* A partial render of this run: its part of the image and of the
 * samples, and its provenance, every choice that changes a pixel.  With
 * the pixels' sums all 0. */
static int start_partial(const Scene *s, const Options *o, int spp, Partial *p)
{
    memset(p, 0, sizeof *p);
    p->w = s->set.w, p->h = s->set.h, p->spp = spp;
    p->x0 = s->set.x0, p->y0 = s->set.y0, p->x1 = s->set.x1, p->y1 = s->set.y1;
    p->s0 = s->set.s0, p->s1 = s->set.s0 + o->spp;
    p->srgb = s->set.srgb;
    sprintf(p->about, "version %s\nscene %016llx\nrenderer %s\ndepth %d\nmax_rays %d\nestimator %d\n"
            "roulette %d\nseed %u\nadaptive %.17g\nno_skip %d\nsampler %d\nlight_choice %d\n",
            program_version(),
            (unsigned long long)scene_hash(s), s->set.integrator == PATH ? "path" : "whitted", s->set.depth,
            s->set.max_rays, s->set.estimator, s->set.roulette, s->set.seed, (double)s->set.adaptive,
            s->set.no_skip, s->set.sampler, s->set.light_choice);
    return new_partial(p);
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
 * to black at the scene's farthest point.  Nothing hit: black.  Objects
 * that move are seen where they are as the shutter opens. */
static vec pixel_view(const Scene *s, int i, int j, Worker *wk)
{
    Counts before = wk->count;
    Ray r = camera_ray(&s->cam, s->set.w, s->set.h, i + (real)0.5, j + (real)0.5);
    Hit h;
    int hit;
    r.time = s->shutter[0];             /* moving objects as the shutter opens */
    wk->count.primary++;
    hit = nearest_hit(s, r, &h, wk);
    if (s->set.view == VIEW_STEPS)
        return heat((real)(wk->count.steps - before.steps + wk->count.tests - before.tests));
    if (!hit) return v3(0, 0, 0);
    if (s->set.view == VIEW_NORMAL) return scale((real)0.5, add(h.n, v3(1, 1, 1)));
    return v3(1 - h.t / s->set.far, 1 - h.t / s->set.far, 1 - h.t / s->set.far);
}

/* --view photons: the photons of the maps (progressive: of the last pass)
 * over the picture, each a dot in the pixel it is seen in, where the eye
 * sees it: the global map's blue, the caustic map's yellow over them.
 * Seen: the eye's ray towards it first meets a surface there (within a
 * thousandth of the way), on the side the photon came from. */
static void draw_photons(const Scene *s, const Photons *ph, Image *img)
{
    static const double dot_of[2][3] = { { 0.2, 0.5, 1 }, { 1, 0.85, 0.2 } };
    const PhotonMap *m[2];
    Worker wk;
    int k, i;
    m[0] = &ph->global, m[1] = &ph->caustic;
    memset(&wk, 0, sizeof wk);
    for (i = 0; i < SHADOW_SLOTS; i++) wk.blocker[i] = -1;
    for (k = 0; k < 2; k++)
        for (i = 0; i < m[k]->n; i++) {
            vec p = v3(m[k]->at[i][0], m[k]->at[i][1], m[k]->at[i][2]), wc;
            real dist, x, y, pdf;
            Ray r;
            Hit h;
            if (!onto_film(s, p, &wc, &dist, &x, &y, &pdf)) continue;
            if ((int)x < s->set.x0 || (int)x >= s->set.x1 || (int)y < s->set.y0 || (int)y >= s->set.y1) continue;
            r.o = s->cam.eye, r.d = scale(-1, wc), r.tmin = 0, r.skip = -1, r.time = s->shutter[0];
            if (!nearest_hit(s, r, &h, &wk) || fabs(h.t - dist) > dist / 1000
                || dot(m[k]->from[i], h.ng) * dot(wc, h.ng) <= 0)
                continue;                                           /* hidden from the eye */
            put_pixel(img, (int)x - s->set.x0, (int)y - s->set.y0,
                      v3((real)dot_of[k][0], (real)dot_of[k][1], (real)dot_of[k][2]));
        }
}

/* ------------------------------------------------------------- scene input */

/* scene.c reads the scene files (the sphere format, OBJ and NFF); what it
 * reads comes here through the builder (scene.h), whose calls are below:
 * each makes a Scene's material, primitive, light or setting, or says why
 * it cannot. */

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

/* A point light, within FAR_LIMIT. */
static int point_light(Scene *s, vec pos, vec color, char *why)
{
    if (!within_far_limit(pos)) {
        sprintf(why, "light too far out: beyond %.2g, its squared distance to the scene overflows",
                (double)FAR_LIMIT);
        return 0;
    }
    add_light(s, pos, color, -1);
    return 1;
}

/* The builder's calls (scene.h): what scene.c read, into the Scene. */
static vec vec_of(const double *p) { return v3((real)p[0], (real)p[1], (real)p[2]); }

static int build_material(void *user, const scene_material *m, char *why)
{
    Material k;
    (void)why;
    k.color = vec_of(m->color);
    k.kd = (real)m->kd; k.ks = (real)m->ks; k.kt = (real)m->kt; k.kl = (real)m->kl;
    k.ir = (real)m->ir; k.shine = (real)m->shine;
    k.spread = 0;
    if (k.shine == 0 && ((Scene *)user)->glossy > 0) {     /* `glossy S` in a sphere file */
        k.shine = ((Scene *)user)->glossy;
        k.spread = 1;
    }
    k.rough = ((Scene *)user)->rough;        /* the last `rough` line's */
    return add_material(user, k);
}

static int build_sphere(void *user, const double c[3], double r, int mat, char *why)
{
    if (!within_far_limit_by(vec_of(c), (real)r, why)) return 0;
    add_sphere(user, vec_of(c), (real)r, mat);
    return 1;
}

static int build_cone(void *user, const double base[3], double rb, const double apex[3], double ra,
                      int mat, char *why)
{
    return add_checked_cone(user, vec_of(base), (real)rb, vec_of(apex), (real)ra, mat, why);
}

/* A triangle's vertices lie within VERTEX_LIMIT.  degenerate() multiplies
 * four lengths in doubles, which overflows past legs of 1e77 (the triangle
 * then has no area and vanishes); in the float build, its hit test loses
 * triangles with legs of 2e10 (both measured, the camera 3 sizes away). */
#define VERTEX_LIMIT (sizeof(real) == sizeof(float) ? 1e9 : 1e76)

static int build_vertex(void *user, const double p[3], char *why)
{
    if (!(fmax(fabs(p[0]), fmax(fabs(p[1]), fabs(p[2]))) <= VERTEX_LIMIT)) {
        sprintf(why, "vertex too far out: beyond %.2g, a triangle's arithmetic overflows and it would vanish",
                VERTEX_LIMIT);
        return -1;
    }
    return add_vertex(user, vec_of(p));
}
static int build_normal(void *user, const double n[3]) { return add_normal(user, vec_of(n)); }
static void build_vertex_at(void *user, int i, double p[3]) { to3(((Scene *)user)->vert[i], p); }

static void build_triangle(void *user, const int v[3], const int n[3], int mat)
{
    add_triangle(user, v[0], v[1], v[2], n[0], n[1], n[2], mat);
}

static int build_light(void *user, const double pos[3], const double color[3], char *why)
{
    return point_light(user, vec_of(pos), vec_of(color), why);
}

static int build_camera(void *user, const double v[10], char *why)
{
    real r[10];
    int i;
    for (i = 0; i < 10; i++) r[i] = (real)v[i];
    return set_camera(user, r, why);
}

static void build_setting(void *user, int what, const double *v, const char *word)
{
    Scene *s = user;
    int i;
    switch (what) {
    case SET_SIZE: s->set.w = (int)v[0]; s->set.h = (int)v[1]; break;
    case SET_DEPTH: s->set.depth = s->set.max_rays = (int)v[0]; break;
    case SET_SAMPLES: s->set.spp = (int)v[0]; break;
    case SET_HITHER: s->cam.hither = (real)v[0], s->cam.hither_sphere = v[1] != 0; break;
    case SET_TIR_REFLECT: s->tir_reflect = v[0] != 0; break;
    case SET_PATH: s->set.integrator = v[0] != 0 ? PATH : WHITTED; break;
    case SET_AMBIENT: s->ambient = vec_of(v); break;
    case SET_BACKGROUND: s->background = vec_of(v); break;
    case SET_PIXEL_CORNER: s->cam.anchor = v[0] != 0 ? 0 : (real)0.5; break;
    case SET_ONE_SIDED: s->cull = v[0] != 0; break;
    case SET_SHUTTER: s->shutter[0] = (real)v[0]; s->shutter[1] = (real)v[1]; break;
    case SET_MOVE: s->move = vec_of(v); break;
    case SET_ROUGH: s->rough = (real)v[0]; break;
    case SET_FRAME: s->frame = 1; break;
    case SET_LIGHT_SCALE:
        for (i = 0; i < s->nlight; i++) s->light[i].color = scale((real)v[0], s->light[i].color);
        break;
    case SET_ACCEL: s->set.accel_line = word; break;
    case SET_LENS: s->cam.lens = (real)v[0]; s->cam.focus = (real)v[1]; break;
    case SET_LIGHTS_CENTRE: s->lights_centre = v[0] != 0; break;
    case SET_SHADOW_RAYS: s->shadow_rays = (int)v[0]; break;
    case SET_GLOSSY: s->glossy = (real)v[0]; break;
    }
}

/* The first warning of each kind is kept, to be said when that renderer
 * starts. */
static void build_warning(void *user, int path, const char *text)
{
    Scene *s = user;
    char *to = path ? s->warning : s->whitted_warning;
    if (!to[0]) sprintf(to, "%.255s", text);
}

static scene_builder builder(Scene *s)
{
    static const scene_builder calls = { NULL, build_material, build_sphere, build_cone,
                                         build_vertex, build_normal, build_vertex_at,
                                         build_triangle, build_light, build_camera,
                                         build_setting, build_warning, NULL };
    scene_builder b = calls;
    b.user = s;
    return b;
}

static void default_scene(Scene *s)
{
    real v[10] = { 0, 0, 0, 0, 1, 0, 0, 0, 1, 45 };
    char why[SCENE_WHY];
    memset(s, 0, sizeof *s);
    s->set.w = s->set.h = 512;
    s->set.depth = 5;
    s->cam.anchor = (real)0.5;
    s->shadow_rays = 1;
    s->shutter[1] = 1;                  /* open from time 0 to 1 */
    s->set.integrator = WHITTED;
    s->set.estimator = MIS;
    s->set.strategy[0] = s->set.strategy[1] = -1;
    s->set.roulette = 1;
    s->lights.sky = -1;
    set_camera(s, v, why);
}

/* The scene in file, read by scene.c, for a render that writes output
 * (which no mesh the scene names may be; NULL: no output); 0 after a
 * message. */
/* A mesh alone (an OBJ file as the scene) framed: the camera 2 box sizes
 * in front of its box's centre, a little right and above, looking at it,
 * y up as OBJ files have it; one white light beside the camera; a little
 * ambient light.  0 when there is nothing to frame. */
static int frame_mesh(Scene *s)
{
    double lo[3] = { INFINITY, INFINITY, INFINITY }, hi[3] = { -INFINITY, -INFINITY, -INFINITY };
    double c[3], size = 0;
    real v[10];
    int i, a;
    for (i = 0; i < s->nvert; i++) {
        double p[3];
        to3(s->vert[i], p);
        for (a = 0; a < 3; a++) lo[a] = fmin(lo[a], p[a]), hi[a] = fmax(hi[a], p[a]);
    }
    for (a = 0; a < 3; a++) {
        c[a] = lo[a] / 2 + hi[a] / 2;
        size = fmax(size, hi[a] - lo[a]);
    }
    if (!(size > 0 && size < 1e150)) return 0;
    v[0] = (real)(c[0] + 0.6 * size), v[1] = (real)(c[1] + 0.5 * size), v[2] = (real)(c[2] + 2 * size);
    v[3] = (real)c[0], v[4] = (real)c[1], v[5] = (real)c[2];
    v[6] = 0, v[7] = 1, v[8] = 0, v[9] = 40;
    if (!set_camera(s, v, (char[SCENE_WHY]){ 0 })) return 0;
    add_light(s, v3(v[0] - (real)size, v[1] + (real)size, v[2]), v3(1, 1, 1), -1);
    s->ambient = v3((real)0.1, (real)0.1, (real)0.1);
    return 1;
}

static int load_scene_for(Scene *s, const char *file, const char *output)
{
    scene_builder b = builder(s);
    b.output = output;
    default_scene(s);
    if (!read_scene(&b, file)) return 0;
    if (s->frame && !frame_mesh(s))
        fprintf(stderr, "%s: warning: the mesh has no extent to frame; the default camera sees it\n", file);
    return 1;
}

#define load_scene(s, file) load_scene_for(s, file, NULL)    /* for the tests: no output */

/* Objects that glow (kl > 0): the path tracer's area lights, and for
 * Whitted's the spheres that are lights. */
static int glowing(const Scene *s)
{
    int i, k, n = 0;
    for (i = 0; i < nobj(s); i++) {
        int what = kind(s, i, &k);
        n += s->mat[what == SPHERE ? s->sph[k].mat : what == CONE ? s->cone[k].mat : s->tri[k].mat].kl > 0;
    }
    return n;
}

/* What --stats prints (cli.c prints it, in words or as key value lines). */
static void report_stats(const Scene *s, const Counts *c, int spp, int kv, double load,
                         double build, double seconds, double cpu)
{
    static const char *const accels[] = { "none", "kd", "bvh", "grid" };
    Stats st;
    int i;
    memset(&st, 0, sizeof st);
    st.spheres = s->nsph, st.cones = s->ncone, st.triangles = s->ntri, st.objects = nobj(s);
    for (i = 0; i < s->nlight; i++) st.point_lights += s->light[i].sphere < 0;
    st.glowing = glowing(s);
    st.w = s->set.x1 - s->set.x0, st.h = s->set.y1 - s->set.y0, st.spp = spp,   /* a split render: its part */ st.threads = c->threads, st.depth = s->set.depth;
    st.path = s->set.integrator == PATH;
    st.estimator = s->set.estimator;
    st.roulette = s->set.roulette, st.max_rays = s->set.max_rays, st.seed = s->set.seed, st.lights = s->lights.nemit;
    st.accel = accels[s->accel.which];
    if (s->accel.which == ACCEL_KD) kd_describe(s->accel.kd, &st.kd);
    if (s->accel.which == ACCEL_BVH) bvh_describe(s->accel.bvh, &st.bvh);
    if (s->accel.which == ACCEL_GRID) grid_describe(s->accel.grid, &st.grid);
    st.primary = c->primary, st.shadow = c->shadow, st.reflected = c->reflected;
    st.refracted = c->refracted, st.bounced = c->bounced, st.cut = c->cut, st.budget = RAY_BUDGET;
    st.discarded = c->discarded, st.queries = c->queries, st.nearest = c->nearest;
    st.hits = c->hits, st.tests = c->tests, st.steps = c->steps;
    st.no_skip = s->set.no_skip, st.behind = c->behind, st.faint = c->faint, st.dim = c->dim;
    st.clipped = clipped_lights(s);
    st.adaptive = s->set.adaptive, st.samples = c->samples, st.spp_min = c->spp_min, st.spp_max = c->spp_max;
    st.load = load, st.build = build, st.seconds = seconds, st.cpu = cpu;
    print_stats(stderr, &st, kv);
}

static void free_scene(Scene *s)
{
    if (s->accel.kd) kd_free(s->accel.kd);
    if (s->accel.bvh) bvh_free(s->accel.bvh);
    if (s->accel.grid) grid_free(s->accel.grid);
    free(s->mat); free(s->sph); free(s->cone); free(s->tri);
    free(s->vert); free(s->norm); free(s->light);
    free(s->lights.emit); free(s->lights.node); free(s->lights.leaf); free(s->lights.emitter);
    free(s->lights.clip);
}

/* Why the picture will come out black, or NULL: nothing lights the
 * scene.  The path tracer sees only what emits (a light, kl > 0, the
 * sky); Whitted's renderer also the ambient, and shows what glows. */
static const char *why_black(const Scene *s)
{
    int i, lit = s->nlight > 0 || luminance(s->ambient) > 0;
    for (i = 0; i < s->lights.nemit; i++)
        lit |= s->lights.emit[i].type == SPHERE_LIGHT || s->lights.emit[i].type == TRIANGLE_LIGHT;
    if (s->set.integrator == PATH && s->lights.nemit == 0)
        return "nothing in it gives light (no `light`, nothing with kl > 0, a black background):"
               " the path-traced picture will be black";
    if (s->set.integrator == WHITTED && !lit && nobj(s) > 0)
        return "no light reaches its surfaces (no `light`, nothing with kl > 0, ambient 0): only"
               " what glows and the background will show";
    return NULL;
}

/* Whether Whitted's renderer draws random numbers for this scene (a lens,
 * area lights, a glossy ray, motion): if not, --seed changes nothing. */
static int whitted_draws(const Scene *s)
{
    int i, any = s->cam.lens > 0 || s->moving > 0;
    for (i = 0; i < s->lights.nemit; i++)
        any |= s->lights.emit[i].type == TRIANGLE_LIGHT
               || (s->lights.emit[i].type == SPHERE_LIGHT && !s->lights_centre);
    for (i = 0; i < s->nmat; i++) any |= s->mat[i].spread;
    return any;
}

/* The first point light inside an opaque sphere (kt 0, at rest) that the
 * eye is outside of: it lights only that sphere's inside, which the eye
 * never sees.  -1: none.  *in is the sphere.  A light and an eye both
 * inside one sphere, a room or a sky made of it, are as they should be. */
static int buried_light(const Scene *s, int *in)
{
    int i, k;
    for (i = 0; i < s->nlight; i++)
        for (k = 0; k < s->nsph && s->light[i].sphere < 0; k++) {
            const Sphere *b = &s->sph[k];
            vec l = sub(s->light[i].pos, b->cen), e = sub(s->cam.eye, b->cen);
            if (s->mat[b->mat].kt == 0 && !nonzero(b->move) && dot(l, l) < b->rad * b->rad
                && dot(e, e) > b->rad * b->rad)
                return *in = k, i;
        }
    return -1;
}

/* Said once before the render: a picture that will be black, a light no
 * one will see the work of, and the path tracer's options given to
 * Whitted's renderer, which ignores them. */
static void say_what_is_ignored(const Scene *s, const Args *a)
{
    const char *black = why_black(s);
    int in, l = buried_light(s, &in);
    if (black) fprintf(stderr, "%s: warning: %s\n", a->name, black);
    if (l >= 0)
        fprintf(stderr, "%s: warning: the light at (%g %g %g) lies inside an opaque sphere (centre %g %g %g,"
                " radius %g) that the eye is outside of: it lights nothing the camera sees\n", a->name,
                (double)s->light[l].pos.x, (double)s->light[l].pos.y, (double)s->light[l].pos.z,
                (double)s->sph[in].cen.x, (double)s->sph[in].cen.y, (double)s->sph[in].cen.z,
                (double)s->sph[in].rad);
    if (s->set.integrator != WHITTED) return;
    if (a->estimator >= 0)
        fprintf(stderr, "ray: warning: --estimator is the path tracer's; Whitted's renderer ignores"
                " it (add --pt)\n");
    if (a->seed >= 0 && !whitted_draws(s))
        fprintf(stderr, "ray: warning: --seed changes nothing here: Whitted's renderer draws random"
                " numbers only for a lens, area lights, glossy rays and motion\n");
}

/* Light tracing and BDPT splat into any pixel: they render whole images,
 * every sample, and no pixel stops early; and they join paths to a
 * pinhole, not to a lens.  0 with a message otherwise. */
static int light_tracing_can(const Scene *s, const Args *a, int all)
{
    const char *name = s->set.estimator == BDPT ? "bdpt" : "light";
    const char *why = s->set.adaptive > 0 ? "--adaptive"
                      : a->checkpoint > 0 || a->resume ? "--checkpoint and --resume"
                      : s->set.x0 || s->set.y0 || s->set.x1 < s->set.w || s->set.y1 < s->set.h
                        || !all || strstr(a->output, ".part") ? "a split render"
                      : s->cam.lens > 0 ? "a lens (`lens`: the paths join a pinhole)" : NULL;
    if (why) fprintf(stderr, "ray: --estimator %s renders whole images only: not with %s\n", name, why);
    if (!why && s->lights.sky >= 0 && s->set.estimator == BDPT)
        fprintf(stderr, "ray: warning: under --estimator bdpt only the camera's paths find the sky"
                " (no light path starts from it): its light is BSDF-sampled alone\n");
    else if (!why && s->lights.sky >= 0)
        fprintf(stderr, "ray: warning: under --estimator light the sky lights nothing (no light path"
                " starts from it); it is seen only where the camera sees it\n");
    return !why;
}

/* Photon mapping's choices: --photons and --view photons only with it,
 * and progressive passes only whole (each a sample: no pixel stops early,
 * and a checkpoint would hold half a pass); 0 with a message when they
 * cannot work, a warning where the sky lights only directly. */
static int photons_can(const Scene *s, const Args *a, int progressive)
{
    int mapped = s->set.integrator == PATH && (s->set.estimator == PHOTON_MAPPING || progressive);
    const char *why = a->view == VIEW_PHOTONS && !mapped
                      ? "--view photons draws photon mapping's photons: add --pt --estimator photon or ppm"
                      : progressive && s->set.adaptive > 0 ? "--estimator ppm renders whole passes: not with --adaptive"
                      : progressive && (a->checkpoint > 0 || a->resume)
                        ? "--estimator ppm renders whole passes: not with --checkpoint or --resume" : NULL;
    if (why) fprintf(stderr, "ray: %s\n", why);
    if (!why && a->photons && !mapped)
        fprintf(stderr, "ray: warning: --photons is photon mapping's: it changes nothing without --estimator"
                " photon or ppm\n");
    if (!why && mapped && s->lights.sky >= 0)
        fprintf(stderr, "ray: warning: under --estimator %s the sky lights only directly (no photon leaves it)\n",
                progressive ? "ppm" : "photon");
    return !why;
}

/* The command line's choices for the path tracer (-1: not given) onto the
 * scene, and its lights; 0 with a message when they cannot work. */
static int settle_path_options(Scene *s, int integrator, int estimator, int roulette, long seed)
{
    if (integrator >= 0) s->set.integrator = integrator;
    if (estimator >= 0) s->set.estimator = estimator;
    if (seed >= 0) s->set.seed = (unsigned)seed;
    s->set.roulette = roulette;
    prepare_lights(s);                      /* Whitted's area lights are the path tracer's */
    if (s->set.integrator != PATH) return 1;
    if (!roulette && !s->set.max_rays) {
        fprintf(stderr, "ray: --no-roulette needs -d N (or the scene's `depth`): without either,"
                " paths would not end\n");
        return 0;
    }
    return 1;
}

/* A render of every pixel and every sample (the default, which the
 * split options below narrow). */
static void whole_image(Scene *s)
{
    s->set.x0 = s->set.y0 = s->set.s0 = 0;
    s->set.x1 = s->set.w, s->set.y1 = s->set.h;
}

/* The part of the image and of the samples this run renders (--crop,
 * --tile, --samples) onto the scene, and *count, each pixel's samples in
 * it; 0 with a message when it does not fit the image or -n's spp. */
static int settle_split(Scene *s, const Args *a, int spp, int *count)
{
    int w = s->set.w, h = s->set.h;
    whole_image(s);
    *count = spp;
    if (a->cropped && (a->crop[2] > w || a->crop[3] > h)) {
        fprintf(stderr, "ray: --crop %d,%d,%d,%d reaches beyond the %dx%d image\n", a->crop[0], a->crop[1],
                a->crop[2], a->crop[3], w, h);
        return 0;
    }
    if (a->cropped) s->set.x0 = a->crop[0], s->set.y0 = a->crop[1], s->set.x1 = a->crop[2], s->set.y1 = a->crop[3];
    if (a->tiles > h) {
        fprintf(stderr, "ray: --tile %d/%d: the image has %d rows, too few for %d bands\n", a->tile, a->tiles, h,
                a->tiles);
        return 0;
    }
    if (a->tiles) {
        s->set.y0 = (int)((long long)a->tile * h / a->tiles);
        s->set.y1 = (int)((long long)(a->tile + 1) * h / a->tiles);
    }
    if (a->samples[1] > spp) {
        fprintf(stderr, "ray: --samples %d:%d reaches beyond the %d samples a pixel has (-n)\n", a->samples[0],
                a->samples[1], spp);
        return 0;
    }
    if (a->samples[0] > 0 && s->set.adaptive > 0) {
        fprintf(stderr, "ray: --samples %d:%d with --adaptive: whether a pixel takes more samples is decided by"
                " those before, so a range must start at 0\n", a->samples[0], a->samples[1]);
        return 0;
    }
    if (a->samples[1]) s->set.s0 = a->samples[0], *count = a->samples[1] - a->samples[0];
    return 1;
}

/* --resume: the rows of the checkpoint in file that are done, into part
 * and done; 0 after a message when it is no checkpoint of this render. */
static int resume_from(const char *file, Partial *part, unsigned char *done)
{
    Partial old;
    int r, x, w = part->x1 - part->x0;
    if (!read_partial(file, &old)) return 0;
    if (!same_part(&old, part, file)) {
        free_partial(&old);
        return 0;
    }
    for (r = 0; r < part->y1 - part->y0; r++) {
        size_t at = (size_t)r * w;
        for (x = 0, done[r] = 1; x < w; x++) done[r] &= old.n[at + x] > 0;
        if (!done[r]) continue;
        memcpy(&part->sum[3 * at], &old.sum[3 * at], 3 * (size_t)w * sizeof *part->sum);
        memcpy(&part->n[at], &old.n[at], (size_t)w * sizeof *part->n);
    }
    free_partial(&old);
    return 1;
}

/* ray --merge OUT PART...: the parts read, added (image.c checks that
 * they belong together and leave no hole), and OUT written. */
static int merge_parts(const Args *a)
{
    int n = a->nparts - 1, i, ok = 1;
    Partial *parts = calloc((size_t)n, sizeof *parts), whole;
    Output out;
    Image img;
    if (!parts) out_of_memory();
    for (i = 0; i < n && ok; i++) ok = read_partial(a->parts[i + 1], &parts[i]);
    ok = ok && merge_partials(parts, a->parts + 1, n, &whole);
    for (i = 0; i < n; i++) free_partial(&parts[i]);
    free(parts);
    if (!ok) return 1;
    if (!open_output(&out, a->output)) {
        free_partial(&whole);
        return 1;
    }
    if (!new_image(&img, whole.w, whole.h, float_format(out.format), whole.srgb)) {
        fprintf(stderr, "ray: out of memory for a %dx%d image\n", whole.w, whole.h);
        discard_output(&out);
        free_partial(&whole);
        return 1;
    }
    image_of(&whole, &img);
    ok = write_image(&out, &img, a->plain);
    free_image(&img);
    free_partial(&whole);
    return ok ? 0 : 1;
}

static void free_args(Args *a)
{
    free(a->made);
    free(a->parts);
}

/* The program: the command line (cli.c), the scene (scene.c), the
 * structure, the output opened, render(), the image written (image.c).
 * A split render's part, or a render with checkpoints, keeps each pixel's
 * sums in a Partial as well (image.h). */
int main(int argc, char **argv)
{
    Args a;
    Scene s;
    Options o;
    Counts st;
    Output out;
    Image img;
    Partial part;
    const char *accel;
    char *checkpoint = NULL;
    Photons photons;
    Hooks photon_pass;
    int ok, sig, spp, as_part, progressive, done = parse_args(argc, argv, &a);
    double t0, load, build;
    clock_t c0;

    if (done >= 0) {                    /* --help, or a usage error */
        free_args(&a);
        return done;
    }
    if (a.merge) {
        done = merge_parts(&a);
        free_args(&a);
        return done;
    }
    load = now();
    ok = load_scene_for(&s, a.scene, strcmp(a.output, "-") ? a.output : NULL);
    if (ok && a.w) { s.set.w = a.w; s.set.h = a.h; }
    load = now() - load;
    if (ok && nobj(&s) == 0) fprintf(stderr, "%s: warning: the scene has no objects\n", a.name);
    if (ok && s.frame)
        fprintf(stderr, "%s: an OBJ mesh alone: grey, seen by a camera framing its box (y up),"
                " lit by one light\n", a.scene);
    if (a.depth) s.set.depth = s.set.max_rays = a.depth;
    s.set.no_skip = a.no_skip;
    if (a.sampler >= 0) s.set.sampler = a.sampler;
    if (a.light_choice >= 0) s.set.light_choice = a.light_choice;
    accel = a.accel ? a.accel : s.set.accel_line ? s.set.accel_line : "auto";
    if (ok && !settle_path_options(&s, a.integrator, a.estimator, a.roulette, a.seed)) {
        free_scene(&s); free_args(&a);
        return 2;                   /* --no-roulette without -d: a usage error */
    }
    memset(&o, 0, sizeof o);
    spp = a.spp ? a.spp : s.set.spp ? s.set.spp : 1;
    s.set.view = a.view;
    s.set.adaptive = a.no_skip ? 0 : (real)a.adaptive;
    s.set.srgb = s.set.integrator == PATH || a.gamma;
    if (ok && !settle_split(&s, &a, spp, &o.spp)) {
        free_scene(&s); free_args(&a);
        return 2;                   /* a part beyond the image: a usage error */
    }
    if (ok && a.strategy[0] >= 0 && (s.set.integrator != PATH || s.set.estimator != BDPT)) {
        fprintf(stderr, "ray: --strategy is bidirectional path tracing's: add --pt --estimator bdpt\n");
        free_scene(&s); free_args(&a);
        return 2;
    }
    if (a.strategy[0] >= 0) s.set.strategy[0] = a.strategy[0], s.set.strategy[1] = a.strategy[1];
    if (ok && s.set.integrator == PATH && (s.set.estimator == LIGHT_TRACING || s.set.estimator == BDPT)
        && !light_tracing_can(&s, &a, s.set.s0 == 0 && o.spp == spp)) {
        free_scene(&s); free_args(&a);
        return 2;
    }
    progressive = s.set.integrator == PATH && s.set.estimator == PROGRESSIVE;
    if (ok && !photons_can(&s, &a, progressive)) {
        free_scene(&s); free_args(&a);
        return 2;
    }
    if (ok) say_what_is_ignored(&s, &a);
    s.set.photons = a.photons ? a.photons : progressive ? s.set.w * s.set.h : DEFAULT_PHOTONS;
    memset(&photons, 0, sizeof photons);
    photons.progressive = progressive;
    if (s.set.integrator == PATH && (s.set.estimator == PHOTON_MAPPING || progressive)) {  /* a pre-pass */
        photon_pass.prepass = shoot_photons, photon_pass.after_sample = NULL, photon_pass.data = &photons;
        o.hooks = &photon_pass;
    }
    o.threads = a.threads;
    build = now();
    ok = ok && build_accel(&s, accel);
    build = now() - build;
    if (!ok || !open_output(&out, a.output)) { free_scene(&s); free_args(&a); return 1; }

    if (a.view == VIEW_DEPTH) s.set.far = farthest(&s);
    as_part = out.format == FORMAT_PART;
    if ((as_part || a.checkpoint > 0 || a.resume || progressive)
        && (!start_partial(&s, &o, spp, &part) || !(o.done = calloc((size_t)(s.set.y1 - s.set.y0), 1))))
        out_of_memory();
    if (o.done) o.part = &part;
    if (!as_part && !new_image(&img, s.set.x1 - s.set.x0, s.set.y1 - s.set.y0, float_format(out.format),
                               (!a.view || a.view == VIEW_PHOTONS) && (s.set.integrator == PATH || a.gamma))) {
        fprintf(stderr, "ray: out of memory for a %dx%d image\n", s.set.w, s.set.h);
        discard_output(&out);
        free_scene(&s); free_args(&a);
        return 1;
    }
    if (a.resume && !resume_from(a.resume, &part, o.done)) {
        discard_output(&out);
        free_scene(&s); free_args(&a);
        return 1;
    }
    if (a.checkpoint > 0) {             /* to OUT.part, and on a stop signal */
        if (!(checkpoint = malloc(strlen(a.output) + 6))) out_of_memory();
        sprintf(checkpoint, "%s.part", a.output);
        o.checkpoint = checkpoint;
        o.every = a.checkpoint;
        catch_stop_signals();
    }
    o.progress = stderr_is_terminal();
    memset(&st, 0, sizeof st);
    if (s.set.integrator == PATH ? s.warning[0] : s.whitted_warning[0])
        fprintf(stderr, "%s\n", s.set.integrator == PATH ? s.warning : s.whitted_warning);
    t0 = o.start = now();
    c0 = clock();
    if (progressive) render_passes(&s, &o, &part, as_part ? NULL : &img, &st);
    else render(&s, &o, as_part ? NULL : &img, &st);
    t0 = now() - t0;
    if ((sig = stop_signal())) {        /* the work so far saved, then end as the signal ends */
        if (save_partial(checkpoint, &part, o.done))
            fprintf(stderr, "ray: stopped by signal %d; the work so far is in %s: go on with --resume %s\n",
                    sig, checkpoint, checkpoint);
        discard_output(&out);
        end_by_signal(sig);
        return 1;
    }
    if (o.part && !as_part && !progressive) image_of(&part, &img);     /* the rows resumed too */
    if (a.view == VIEW_PHOTONS && !as_part) draw_photons(&s, &photons, &img);
    ok = as_part ? write_partial(&out, &part, NULL) : write_image(&out, &img, a.plain);
    if (ok && checkpoint) remove(checkpoint);      /* done: no checkpoint to go on from */
    if (a.stats)
        report_stats(&s, &st, o.spp, a.stats == 2, load, build, t0,
                     (double)(clock() - c0) / CLOCKS_PER_SEC);
    if (!as_part) free_image(&img);
    if (o.part) free_partial(&part);
    free_photons(&photons);
    free(o.done);
    free(checkpoint);
    free_args(&a);
    free_scene(&s);
    return ok ? 0 : 1;
}

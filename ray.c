/* ray.c - Whitted's recursive ray tracer, as the lecture writes it.
 *
 *     make ray && ./ray -o minray.ppm scenes/minray.sph
 *
 * Usage: ./ray [options] SCENE
 *     -o FILE     output image (default: SCENE's base name with .ppm; - = stdout)
 *     -s WxH      image size (default: the scene's `size`, else 512x512)
 *     -n N        anti-aliasing samples per pixel (default 1)
 *     -d N        recursion depth; 1 = primary rays only (default: scene's, else 5)
 *     -t N        threads (default: every core, when built with OpenMP)
 *     --p3        plain-text PPM (P3) instead of binary (P6)
 *     --stats     print rays by kind, hits and time on stderr
 *     --help
 *
 * The program is the lecture's pseudo-code, top to bottom:
 *
 *     for each pixel                        render(), pixel_color()
 *         compute the ray R from the eye    camera_ray()
 *         pixel colour = RayTrace(R)        trace()
 *
 *     RayTrace(R):                          trace()
 *         find the nearest hit              nearest_hit()
 *         colour = black (or background)
 *         if there is a hit                 shade()
 *             for each light                   a shadow ray: shadow_ray()
 *                 if nothing blocks it, add the light
 *             reflected ray Refl               colour += RayTrace(Refl)
 *             refracted ray (Snell)            colour += RayTrace(Refr)
 *
 * Its shading model is Heckbert's business card (minray.c) exactly, so
 * `./ray -o x.ppm scenes/minray.sph` prints minray's pixels.  The scene format
 * is described in README.md ("The sphere format").
 *
 * Build options: -DREAL=float makes every vector float instead of double
 * (the benchmark compares both); -fopenmp renders rows in parallel.  Output
 * is the same bytes for any number of threads, because no pixel depends on
 * another or on the order pixels are computed in.
 */
#define _POSIX_C_SOURCE 200809L /* isatty, clock_gettime */
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
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

/* ---------------------------------------------------------------- vectors */

typedef struct { real x, y, z; } vec;

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
static real maxabs(vec a)
{
    real m = fabs(a.x);
    if (fabs(a.y) > m) m = fabs(a.y);
    if (fabs(a.z) > m) m = fabs(a.z);
    return m;
}

/* ------------------------------------------------------------------ scene */

/* minray's material: diffuse, mirror, transmitted and emitted weights, and
 * the index of refraction (the ray bends by 1/ir going in, ir coming out). */
typedef struct { vec color; real kd, ks, kt, kl, ir; } Material;

typedef struct { vec cen; real rad; Material m; } Sphere;

/* A light is either one of minray's emitting spheres (sphere >= 0: lit when
 * the nearest thing toward its centre is that sphere) or a point light
 * (sphere < 0: lit when nothing lies between). */
typedef struct { vec pos, color; int sphere; } Light;

typedef struct {
    vec eye, right, up, fwd;  /* orthonormal frame */
    real fov;                 /* horizontal, edge to edge, in degrees */
    real anchor;              /* 0.5: samples centred on the pixel; 0: on its corner */
} Camera;

typedef struct {
    Sphere *sph;
    int nsph, capsph;
    Light *light;
    int nlight, caplight;
    Camera cam;
    int w, h, depth;
    vec ambient, background;
} Scene;

typedef struct { vec o, d; } Ray;

typedef struct {
    real t;
    int obj;  /* index into the sphere list */
    vec p, n; /* point and outward unit normal */
} Hit;

/* What --stats counts; each thread keeps its own and they are summed. */
typedef struct {
    unsigned long long primary, shadow, reflected, refracted, hits, tests;
} Stats;

/* ----------------------------------------------------- sphere intersection */

/* Smallest root t of |o + t d - c| = r with t > tmin, or INFINITY.
 *
 * The textbook form b*b - c loses every digit when the sphere is far away or
 * small: both terms are about |o-c|^2 and their difference about r^2.  Here
 * the discriminant is r^2 - |l|^2, where l is the vector from the centre to
 * the point of the line closest to it, which has no such cancellation; and
 * the two roots come from q and c/q so that neither subtracts two nearly
 * equal numbers (Haines, Guenter, Jones, Akenine-Moller and Hunt, "Precision
 * Improvements for Ray/Sphere Intersection", Ray Tracing Gems, ch. 7, 2019). */
static real hit_sphere(const Sphere *s, Ray r, real tmin)
{
    vec f = sub(r.o, s->cen);
    real a = dot(r.d, r.d);
    real b = -dot(f, r.d);                      /* half of -B in a t^2 + B t + C */
    vec l = add(f, scale(b / a, r.d));
    real disc = a * (s->rad * s->rad - dot(l, l));
    real c, q, t0, t1;
    if (!(disc >= 0)) return INFINITY;          /* also rejects NaN */
    c = dot(f, f) - s->rad * s->rad;
    q = b + (b >= 0 ? sqrt(disc) : -sqrt(disc));
    t0 = c / q;
    t1 = q / a;
    if (t0 > t1) { real tt = t0; t0 = t1; t1 = tt; }
    if (t0 > tmin) return t0;
    if (t1 > tmin) return t1;
    return INFINITY;
}

/* ------------------------------------------------------------ nearest hit */

/* The nearest object along r, as the lecture's "find the nearest hit"
 * (t, point, object, normal).  Returns 0 when r hits nothing. */
static int nearest_hit(const Scene *s, Ray r, Hit *h, Stats *st)
{
    int i;
    h->t = INFINITY;
    h->obj = -1;
    for (i = 0; i < s->nsph; i++) {
        real t = hit_sphere(&s->sph[i], r, 0);
        if (t < h->t) { h->t = t; h->obj = i; }
    }
    st->tests += (unsigned long long)s->nsph;
    if (h->obj < 0) return 0;
    st->hits++;
    h->p = comb(h->t, r.d, r.o);
    h->n = unit(sub(h->p, s->sph[h->obj].cen));
    return 1;
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
    const Sphere *o = &s->sph[h->obj];
    real size = maxabs(h->p) + maxabs(o->cen) + o->rad;
    real eps = 64 * (sizeof(real) == sizeof(float) ? FLT_EPSILON : DBL_EPSILON) * size;
    Ray r;
    r.o = comb(dot(dir, h->n) >= 0 ? eps : -eps, h->n, h->p);
    r.d = dir;
    return r;
}

/* The lecture's shadow ray: is light l seen from the hit point?  *e returns
 * its strength kl * cos(angle to the normal) and the direction is unit. */
static int shadow_ray(const Scene *s, const Hit *h, vec n, const Light *l,
                      real *e, Stats *st)
{
    vec dir = unit(sub(l->pos, h->p));
    Ray r;
    Hit blocker;
    real k = l->sphere >= 0 ? s->sph[l->sphere].m.kl : 1;
    *e = k * dot(n, dir);
    if (!(*e > 0)) return 0;    /* facing away: no ray, as the SPD rules say */
    st->shadow++;
    r = spawn(s, h, dir);
    if (!nearest_hit(s, r, &blocker, st)) return l->sphere < 0;
    if (l->sphere >= 0) return blocker.obj == l->sphere;
    return blocker.t >= sqrt(dot(sub(l->pos, r.o), sub(l->pos, r.o))); /* beyond the light */
}

/* ------------------------------------------------------------ RayTrace(R) */

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

static vec trace(const Scene *s, Ray r, int depth, Stats *st);

/* Local light, then reflection and refraction by recursion: minray's model.
 * The sums run in the card's order so that the rounding is the card's too. */
static vec shade(const Scene *s, Ray r, const Hit *h, int depth, Stats *st)
{
    const Material *m = &s->sph[h->obj].m;
    vec n = h->n, color = s->ambient, c, t;
    real cosi = -dot(r.d, n), eta = 1 / m->ir, e;
    int i;
    if (cosi < 0) { n = scale(-1, n); cosi = -cosi; eta = m->ir; } /* inside */
    for (i = 0; i < s->nlight; i++)
        if (shadow_ray(s, h, n, &s->light[i], &e, st))
            color = comb(e, s->light[i].color, color);
    color = mul(color, m->color);

    c = scale(m->kl, m->color);                 /* emission */
    c = comb(m->kd, color, c);                  /* diffuse */
    if (m->ks > 0) {
        st->reflected++;
        c = comb(m->ks, trace(s, spawn(s, h, reflect(r.d, n, cosi)), depth - 1, st), c);
    }
    if (m->kt > 0 && refract(r.d, n, cosi, eta, &t)) {
        st->refracted++;
        c = comb(m->kt, trace(s, spawn(s, h, t), depth - 1, st), c);
    }
    return c;
}

/* The lecture's RayTrace(R).  depth counts down like minray's level: a ray
 * traced with depth 1 is a leaf of the recursion. */
static vec trace(const Scene *s, Ray r, int depth, Stats *st)
{
    Hit h;
    if (depth <= 0) return v3(0, 0, 0);
    if (!nearest_hit(s, r, &h, st)) return s->background;
    return shade(s, r, &h, depth, st);
}

/* ----------------------------------------------------------------- camera */

/* The primary ray through image point (x, y), in pixels from the top-left
 * corner of the image.  The image plane stands at the distance where the
 * image's width spans the field of view edge to edge; a pixel is one unit. */
static Ray camera_ray(const Camera *c, int w, int h, real x, real y)
{
    real dist = (real)w / 2 / tan(c->fov * 3.14159265358979323846 / 360);
    Ray r;
    r.o = c->eye;
    r.d = unit(add(add(scale(x - (real)w / 2, c->right),
                       scale((real)h / 2 - y, c->up)), scale(dist, c->fwd)));
    return r;
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

static vec pixel_color(const Scene *s, int i, int j, int spp, Stats *st)
{
    vec sum = v3(0, 0, 0);
    int k;
    for (k = 0; k < spp; k++) {
        real dx, dy;
        sample_offset(k, s->cam.anchor, &dx, &dy);
        st->primary++;
        sum = add(sum, trace(s, camera_ray(&s->cam, s->w, s->h, i + dx, j + dy), s->depth, st));
    }
    return scale((real)1 / spp, sum);
}

/* Colour in 0..1 to a byte: x255 and round to nearest (as minray's %.0f
 * does), clamped; NaN becomes 0 so that no pixel is ever undefined. */
static unsigned char to_byte(real v)
{
    double x = rint((double)v * 255);
    if (!(x > 0)) return 0;
    return x > 255 ? 255 : (unsigned char)x;
}

/* ------------------------------------------------------------------ render */

typedef struct { int spp, threads, progress; } Options;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static void add_stats(Stats *to, const Stats *from)
{
    to->primary += from->primary;
    to->shadow += from->shadow;
    to->reflected += from->reflected;
    to->refracted += from->refracted;
    to->hits += from->hits;
    to->tests += from->tests;
}

/* Rows go to threads one at a time, as they free up; each pixel is written
 * once by whoever computes it, so the image does not depend on the order. */
static void render(const Scene *s, const Options *o, unsigned char *img, Stats *total)
{
    int done = 0;
#ifdef _OPENMP
    if (o->threads > 0) omp_set_num_threads(o->threads);
#endif
    OMP(omp parallel)
    {
        Stats st;
        int j;
        memset(&st, 0, sizeof st);
        OMP(omp for schedule(dynamic, 1))
        for (j = 0; j < s->h; j++) {
            int i, mine;
            for (i = 0; i < s->w; i++) {
                vec c = pixel_color(s, i, j, o->spp, &st);
                unsigned char *px = img + 3 * ((size_t)j * s->w + i);
                px[0] = to_byte(c.x);
                px[1] = to_byte(c.y);
                px[2] = to_byte(c.z);
            }
            OMP(omp atomic capture)
            mine = ++done;
            if (o->progress && (mine * 100 / s->h != (mine - 1) * 100 / s->h))
                fprintf(stderr, "\rray: %3d%%", mine * 100 / s->h);
        }
        OMP(omp critical)
        add_stats(total, &st);
    }
    if (o->progress) fprintf(stderr, "\r          \r");
}

/* ------------------------------------------------------------ scene input */

#define MAXTOK 16

typedef struct { const char *file; int line; } Where;

static int fail(Where w, const char *msg, const char *arg)
{
    fprintf(stderr, "%s:%d: %s%s%s\n", w.file, w.line, msg, arg ? ": " : "", arg ? arg : "");
    return 0;
}

/* Reads the n numbers after tok[first]; finite numbers only.  `what` names
 * the line's kind for the message. */
static int numbers(Where w, const char *what, char **tok, int ntok, int first, int n, real *out)
{
    int i;
    char buf[128];
    if (ntok - first != n) {
        sprintf(buf, "%.40s needs %d numbers, found %d", what, n, ntok - first);
        return fail(w, buf, NULL);
    }
    for (i = 0; i < n; i++) {
        char *end;
        double v = strtod(tok[first + i], &end);
        if (end == tok[first + i] || *end) return fail(w, "not a number", tok[first + i]);
        if (!isfinite(v)) return fail(w, "number must be finite", tok[first + i]);
        out[i] = (real)v;
    }
    return 1;
}

static void *grow(void *p, int *cap, int need, size_t size)
{
    if (need <= *cap) return p;
    *cap = *cap ? 2 * *cap : 16;
    p = realloc(p, (size_t)*cap * size);
    if (!p) { fprintf(stderr, "ray: out of memory\n"); exit(1); }
    return p;
}

static int add_light(Scene *s, vec pos, vec color, int sphere)
{
    s->light = grow(s->light, &s->caplight, s->nlight + 1, sizeof *s->light);
    s->light[s->nlight].pos = pos;
    s->light[s->nlight].color = color;
    s->light[s->nlight].sphere = sphere;
    s->nlight++;
    return 1;
}

/* One sphere: minray's 12 numbers in minray's order. */
static int parse_sphere(Scene *s, Where w, char **tok, int ntok)
{
    real v[12];
    Sphere *p;
    if (!numbers(w, "a sphere", tok, ntok, 0, 12, v)) return 0;
    if (!(v[6] > 0)) return fail(w, "sphere radius must be positive", tok[6]);
    if (!(v[11] > 0)) return fail(w, "index of refraction must be positive", tok[11]);
    s->sph = grow(s->sph, &s->capsph, s->nsph + 1, sizeof *s->sph);
    p = &s->sph[s->nsph++];
    p->cen = v3(v[0], v[1], v[2]);
    p->m.color = v3(v[3], v[4], v[5]);
    p->rad = v[6];
    p->m.kd = v[7]; p->m.ks = v[8]; p->m.kt = v[9]; p->m.kl = v[10]; p->m.ir = v[11];
    if (p->m.kl > 0) add_light(s, p->cen, p->m.color, s->nsph - 1);
    return 1;
}

static int set_camera(Scene *s, Where w, const real *v)
{
    Camera *c = &s->cam;
    vec at = v3(v[3], v[4], v[5]), up = v3(v[6], v[7], v[8]);
    c->eye = v3(v[0], v[1], v[2]);
    c->fov = v[9];
    if (!(dot(sub(at, c->eye), sub(at, c->eye)) > 0)) return fail(w, "camera looks at its own eye", NULL);
    if (!(c->fov > 0 && c->fov < 180)) return fail(w, "field of view must be between 0 and 180 degrees", NULL);
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

/* A keyword line: ray.c's extensions to minray's format. */
static int parse_keyword(Scene *s, Where w, char **tok, int ntok)
{
    real v[10];
    const char *k = tok[0];
    if (!strcmp(k, "size"))
        return numbers(w, k, tok, ntok, 1, 2, v)
               && (check_size(v[0], v[1], &s->w, &s->h) || fail(w, SIZE_RULE, NULL));
    if (!strcmp(k, "depth")) {
        if (!numbers(w, k, tok, ntok, 1, 1, v)) return 0;
        if (!(v[0] >= 1 && v[0] <= 64 && v[0] == floor(v[0]))) return fail(w, "depth must be a whole number from 1 to 64", tok[1]);
        s->depth = (int)v[0];
        return 1;
    }
    if (!strcmp(k, "ambient") || !strcmp(k, "background")) {
        if (!numbers(w, k, tok, ntok, 1, 3, v)) return 0;
        *(k[0] == 'a' ? &s->ambient : &s->background) = v3(v[0], v[1], v[2]);
        return 1;
    }
    if (!strcmp(k, "camera"))
        return numbers(w, k, tok, ntok, 1, 10, v) && set_camera(s, w, v);
    if (!strcmp(k, "light"))
        return numbers(w, k, tok, ntok, 1, 6, v) && add_light(s, v3(v[0], v[1], v[2]), v3(v[3], v[4], v[5]), -1);
    if (!strcmp(k, "pixel")) {
        if (ntok != 2 || (strcmp(tok[1], "corner") && strcmp(tok[1], "centre") && strcmp(tok[1], "center")))
            return fail(w, "expected `pixel corner` or `pixel centre`", NULL);
        s->cam.anchor = tok[1][0] == 'c' && tok[1][1] == 'o' ? 0 : (real)0.5;
        return 1;
    }
    return fail(w, "unknown keyword", k);
}

/* Splits a line into blank-separated tokens; '#' starts a comment. */
static int tokens(char *line, char **tok)
{
    int n = 0;
    char *p = strchr(line, '#');
    if (p) *p = 0;
    for (p = strtok(line, " \t\r\n"); p && n < MAXTOK; p = strtok(NULL, " \t\r\n"))
        tok[n++] = p;
    return p ? MAXTOK + 1 : n;
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

static int load_scene(Scene *s, const char *file)
{
    char line[4096], *tok[MAXTOK];
    Where w = { file, 0 };
    FILE *f = fopen(file, "r");
    int ok = 1;
    default_scene(s);
    if (!f) return fail(w, "cannot open scene", strerror(errno));
    while (ok && fgets(line, sizeof line, f)) {
        int n;
        w.line++;
        if (!strchr(line, '\n') && !feof(f)) { ok = fail(w, "line longer than 4095 characters", NULL); break; }
        n = tokens(line, tok);
        if (n > MAXTOK) ok = fail(w, "too many fields", NULL);
        else if (n == 0) continue;
        else if (strchr("+-.0123456789", tok[0][0])) ok = parse_sphere(s, w, tok, n);
        else ok = parse_keyword(s, w, tok, n);
    }
    if (ok && ferror(f)) ok = fail(w, "read error", strerror(errno));
    fclose(f);
    return ok;
}

/* ------------------------------------------------------------------ output */

/* The image goes to FILE.tmp and is renamed at the end, so that a failure
 * never leaves a half-written FILE behind. */
static int write_ppm(const char *file, const unsigned char *img, int w, int h, int plain)
{
    char tmp[4096];
    FILE *f;
    int ok;
    size_t i, n = (size_t)w * h * 3;
    if (!strcmp(file, "-")) f = stdout;
    else {
        if (strlen(file) + 5 > sizeof tmp) { fprintf(stderr, "%s: name too long\n", file); return 0; }
        sprintf(tmp, "%s.tmp", file);
        if (!(f = fopen(tmp, "wb"))) { fprintf(stderr, "%s: cannot write: %s\n", tmp, strerror(errno)); return 0; }
    }
    fprintf(f, "%s\n%d %d\n255\n", plain ? "P3" : "P6", w, h);
    if (plain)
        for (i = 0; i < n; i += 3) fprintf(f, "%d %d %d\n", img[i], img[i + 1], img[i + 2]);
    else
        fwrite(img, 1, n, f);
    ok = !ferror(f);
    if (f == stdout) return fflush(f) == 0 && ok;
    ok = (fclose(f) == 0) && ok;
    if (ok && rename(tmp, file) != 0) ok = 0;
    if (!ok) { fprintf(stderr, "%s: cannot write: %s\n", file, strerror(errno)); remove(tmp); }
    return ok;
}

/* ---------------------------------------------------------- command line */

static void usage(FILE *to)
{
    fputs("usage: ray [options] SCENE\n"
          "Renders SCENE (the sphere format; see README.md) with Whitted ray tracing.\n"
          "  -o FILE    output PPM (default: SCENE's base name + .ppm; - for stdout)\n"
          "  -s WxH     image size (default: the scene's `size`, else 512x512)\n"
          "  -n N       anti-aliasing samples per pixel (default 1)\n"
          "  -d N       recursion depth, 1 = primary rays only (default: scene's, else 5)\n"
          "  -t N       threads (default: all cores, when built with OpenMP)\n"
          "  --p3       write plain-text P3 instead of binary P6\n"
          "  --stats    print rays by kind, hits and time on stderr\n"
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
    if (!out) exit(1);
    sprintf(out, "%.*s.ppm", dot ? (int)(dot - base) : (int)strlen(base), base);
    return out;
}

int main(int argc, char **argv)
{
    Scene s;
    Options o = { 1, 0, 0 };
    Stats st;
    const char *scene = NULL, *size = NULL;
    char *out = NULL, *auto_out = NULL;
    int i, depth = 0, plain = 0, stats = 0, ok;
    unsigned char *img;
    double t0;

    for (i = 1; i < argc; i++) {
        const char *a = argv[i], *next = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) { usage(stdout); return 0; }
        else if (!strcmp(a, "-o") && next) out = argv[++i];
        else if (!strcmp(a, "-s") && next) size = argv[++i];
        else if (!strcmp(a, "-n")) { o.spp = int_arg(a, next, 1 << 20); i++; }
        else if (!strcmp(a, "-d")) { depth = int_arg(a, next, 64); i++; }
        else if (!strcmp(a, "-t")) { o.threads = int_arg(a, next, 4096); i++; }
        else if (!strcmp(a, "--p3")) plain = 1;
        else if (!strcmp(a, "--stats")) stats = 1;
        else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "ray: unknown option or missing argument: %s\n", a);
            usage(stderr);
            return 2;
        } else if (scene) { fprintf(stderr, "ray: one scene only (%s and %s)\n", scene, a); return 2; }
        else scene = a;
    }
    if (!scene) { usage(stderr); return 2; }
    if (!load_scene(&s, scene)) return 1;
    if (size) {
        char *x, *end;
        long fw = strtol(size, &x, 10), fh = *x == 'x' ? strtol(x + 1, &end, 10) : 0;
        if (x == size || *x != 'x' || end == x + 1 || *end) {
            fprintf(stderr, "ray: -s needs WxH, like 640x480, not %s\n", size);
            return 2;
        }
        if (!check_size((double)fw, (double)fh, &s.w, &s.h)) {
            fprintf(stderr, "ray: -s %s: " SIZE_RULE "\n", size);
            return 2;
        }
    }
    if (depth) s.depth = depth;
    if (!out) out = auto_out = default_output(scene);
    o.progress = isatty(2);

    img = malloc((size_t)s.w * s.h * 3);
    if (!img) { fprintf(stderr, "ray: out of memory for a %dx%d image\n", s.w, s.h); return 1; }
    memset(&st, 0, sizeof st);
    t0 = now();
    render(&s, &o, img, &st);
    t0 = now() - t0;
    ok = write_ppm(out, img, s.w, s.h, plain);
    if (stats) {
        unsigned long long rays = st.primary + st.shadow + st.reflected + st.refracted;
        fprintf(stderr, "image      %dx%d, %d spp, depth %d, %d spheres, %d lights\n",
                s.w, s.h, o.spp, s.depth, s.nsph, s.nlight);
        fprintf(stderr, "rays       %llu: %llu primary, %llu shadow, %llu reflected, %llu refracted\n",
                rays, st.primary, st.shadow, st.reflected, st.refracted);
        fprintf(stderr, "hits       %llu (%.1f%% of rays), %llu intersection tests\n",
                st.hits, rays ? 100.0 * st.hits / rays : 0.0, st.tests);
        fprintf(stderr, "time       %.3f s, %.2f Mrays/s\n", t0, t0 > 0 ? rays / t0 * 1e-6 : 0.0);
    }
    free(img);
    free(auto_out);
    free(s.sph);
    free(s.light);
    return ok ? 0 : 1;
}

/* test_accel.c - every acceleration structure against a brute-force loop.
 *
 *     test_accel STRUCTURE SCENE [RAYS]
 *
 * STRUCTURE is kd (kdtree.c), bvh-sah or bvh-median (bvh.c, its two builds)
 * or grid (grid.c); SCENE is one of: soup mesh grid thirds tenths same flat empty
 * one.  Prints one line per check, "PASS ..." or "FAIL ...", and exits 1 if
 * any check failed.  RAYS (default 1000000, or $ACCEL_RAYS) rays are shot per
 * scene; each must give the same primitive and bitwise the same t as the loop
 *     for i in 0..n-1: if hit(i, tmin, best_t) and t < best_t: best = i
 * (a tie in t keeps the lower index), and the any-hit query (on every other
 * ray) must agree with a loop that stops at the first hit, and return a
 * primitive that is hit in range.  For the kd-tree and the BVH every one of
 * these queries is asked again of the slide's recursive form
 * (kd_intersect_recursive, bvh_intersect_recursive), which must give what
 * the iterative walk gives: the same primitive, bitwise the same t, and the
 * same numbers of steps and tests.  The BVH is also refitted after a quarter
 * of the primitives move, and checked again, against brute force and against
 * a fresh build.  For long runs: $ACCEL_SCALE multiplies the scenes' sizes,
 * $ACCEL_SEED picks other random scenes and rays.
 *
 * The test scenes put their vertices on coarse dyadic grids, and most
 * degenerate rays use grid origins and small directions, so that the
 * triangle test below computes those rays' predicates without rounding:
 * rays along edges, through vertices, in triangle planes and in split
 * planes then meet the geometry exactly, which is where trees go wrong.
 */
#include "../kdtree.h"
#include "../bvh.h"
#include "../grid.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define PI 3.14159265358979323846

enum { TRI, SPHERE };

typedef struct {
    int kind;
    double v[3][3];  /* TRI: the corners; SPHERE: v[0] centre, v[1][0] radius */
    double n[3];     /* TRI: (v1 - v0) x (v2 - v0) */
} prim;

typedef struct {
    const char *name;
    prim *p;
    int n;
    int use_clip;
    double grid;     /* origins of degenerate rays lie on this grid */
    int small_dirs;  /* degenerate rays use integer directions */
} scene;

typedef struct {
    double o[3], d[3];
} ray;

/* ---- vectors and random numbers -------------------------------------- */

static void sub(const double a[3], const double b[3], double r[3])
{
    r[0] = a[0] - b[0], r[1] = a[1] - b[1], r[2] = a[2] - b[2];
}

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void crossp(const double a[3], const double b[3], double r[3])
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}

/* d . (b x c), the signed volume that tells on which side of the line
 * through b and c (seen from the ray origin) the ray passes. */
static double triple(const double d[3], const double b[3], const double c[3])
{
    double bc[3];
    crossp(b, c, bc);
    return dot(d, bc);
}

/* Scenes are this many times their usual size ($ACCEL_SCALE, for long runs). */
static double scale = 1;

static unsigned long long rng_state = 88172645463325252ull;

static unsigned long long rnd(void)  /* xorshift64*, deterministic */
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return rng_state * 2685821657736338717ull;
}

static double unif(double a, double b)  /* uniform in [a, b) */
{
    return a + (b - a) * (double)(rnd() >> 11) * (1.0 / 9007199254740992.0);
}

static int irand(int n)  /* 0..n-1 */
{
    return (int)(rnd() % (unsigned long long)n);
}

static double on_grid(double a, double b, double step)  /* multiple of step */
{
    return step * floor(unif(a, b) / step);
}

static double snap(double x, double step)  /* nearest multiple of step */
{
    return step * floor(x / step + 0.5);
}

static double signed_zero(void)
{
    return rnd() & 1 ? 0.0 : -0.0;
}

static void random_dir(double d[3])
{
    double len;
    do {
        d[0] = unif(-1, 1), d[1] = unif(-1, 1), d[2] = unif(-1, 1);
        len = dot(d, d);
    } while (len > 1 || len < 1e-6);
    len = sqrt(len);
    d[0] /= len, d[1] /= len, d[2] /= len;
}

/* ---- the primitives and their callbacks -------------------------------- */

static double maxabs3(const double a[3])   /* no NaN here: fmax's answer, without its call */
{
    double x = fabs(a[0]), y = fabs(a[1]), z = fabs(a[2]);
    x = y > x ? y : x;
    return z > x ? z : x;
}

/* Triangle: the three edge tests share their products with the neighbour
 * across each edge (b x c = -(c x b) exactly), so no ray slips between two
 * triangles; hits on edges and vertices count (closed triangles).
 * prims.h lets a hit from far away err along the ray by a few eps of |o|,
 * but off it only by a few eps of the triangle's coordinates; the far
 * vectors v - o are rounded by eps |o|, and their products cancel, so a ray
 * from more than 4096 times the triangle's size away is first moved along
 * itself to the point nearest v0, the vectors from there to the corners
 * summed exactly (prims_along; t0 is added back).  Nearer rays, among them
 * every exact ray of the dyadic scenes, are tested from their own origin. */
static int hit_tri(const prim *t, const ray *r, double tmin, double tmax,
                   double *out)
{
    double a[3], b[3], c[3], e[3], w0, w1, w2, den, num, th, t0 = 0;
    int k, far;
    den = dot(t->n, r->d);
    if (den == 0) return 0;  /* parallel to the plane, or lying in it */
    sub(t->v[0], r->o, a);
    sub(t->v[1], t->v[0], b), sub(t->v[2], t->v[0], e);
    far = maxabs3(a) > 4096 * (maxabs3(b) + maxabs3(e));
    if (far) t0 = dot(a, r->d) / dot(r->d, r->d);
    for (k = 0; k < 3 && far; k++) {   /* v - (o + t0 d) */
        a[k] = -prims_along(r->o[k], t->v[0][k], t0, r->d[k]);
        b[k] = -prims_along(r->o[k], t->v[1][k], t0, r->d[k]);
        c[k] = -prims_along(r->o[k], t->v[2][k], t0, r->d[k]);
    }
    num = dot(t->n, a);
    if (!far && tmin >= 0 && !(num > 0 ? den > 0 : num < 0 && den < 0))
        return 0;  /* t <= 0 <= tmin, known without the division */
    th = t0 + num / den;
    if (!(th > tmin && th <= tmax && th < HUGE_VAL)) return 0;  /* not at infinity */
    if (!far) sub(t->v[1], r->o, b), sub(t->v[2], r->o, c);
    w0 = triple(r->d, b, c), w1 = triple(r->d, c, a), w2 = triple(r->d, a, b);
    if ((w0 < 0 || w1 < 0 || w2 < 0) && (w0 > 0 || w1 > 0 || w2 > 0)) return 0;
    *out = th;
    return 1;
}

/* Sphere: the roots of a t^2 + 2 B t + C = 0 from q and C / q, the
 * discriminant from the point of the line nearest the centre (Haines et
 * al., Ray Tracing Gems, ch. 7), so that a far ray's t is exact to a few
 * eps of its distance, as prims.h asks; the textbook B^2 - a C loses every
 * digit there. */
static int hit_sphere(const prim *s, const ray *r, double tmin, double tmax,
                      double *out)
{
    double f[3], l[3], a, B, C, disc, q, th, t1, rad = s->v[1][0];
    int k;
    sub(r->o, s->v[0], f);
    a = dot(r->d, r->d);
    if (a == 0) return 0;
    B = dot(f, r->d);
    for (k = 0; k < 3; k++) l[k] = f[k] - B / a * r->d[k];   /* nearest point, from the centre */
    disc = a * (rad * rad - dot(l, l));                       /* B^2 - a C */
    if (!(disc >= 0)) return 0;
    C = dot(f, f) - rad * rad;
    q = -B - (B >= 0 ? sqrt(disc) : -sqrt(disc));
    th = q / a, t1 = q != 0 ? C / q : th;
    if (th > t1) q = th, th = t1, t1 = q;
    if (!(th > tmin && th <= tmax)) th = t1;
    if (!(th > tmin && th <= tmax && th < HUGE_VAL)) return 0;
    *out = th;
    return 1;
}

static int test_prim(const scene *s, int i, const ray *r, double tmin, double tmax,
                     double *t)
{
    const prim *p = &s->p[i];
    return p->kind == TRI ? hit_tri(p, r, tmin, tmax, t)
                          : hit_sphere(p, r, tmin, tmax, t);
}

/* The tree's hit callback (its ray argument is not const: a caller may
 * keep notes there; this one does not). */
static int hit(void *user, int i, void *rv, double tmin, double tmax,
               double *t)
{
    return test_prim(user, i, rv, tmin, tmax, t);
}

static void bounds(void *user, int i, double lo[3], double hi[3])
{
    const prim *p = &((const scene *)user)->p[i];
    int a;
    for (a = 0; a < 3; a++) {
        if (p->kind == TRI) {
            lo[a] = fmin(p->v[0][a], fmin(p->v[1][a], p->v[2][a]));
            hi[a] = fmax(p->v[0][a], fmax(p->v[1][a], p->v[2][a]));
        } else {  /* rounded outwards by one step: c - r may round up */
            lo[a] = nextafter(p->v[0][a] - p->v[1][0], -HUGE_VAL);
            hi[a] = nextafter(p->v[0][a] + p->v[1][0], HUGE_VAL);
        }
    }
}

/* Cut a polygon (n corners) by the plane x[axis] = s, keeping the side
 * where sign * (x - s) >= 0 (Sutherland-Hodgman). */
static int cut(double (*in)[3], int n, double (*out)[3], int axis, double s,
               double sign)
{
    int i, k = 0;
    for (i = 0; i < n; i++) {
        const double *a = in[i], *b = in[(i + 1) % n];
        double da = sign * (a[axis] - s), db = sign * (b[axis] - s);
        if (da >= 0) memcpy(out[k++], a, sizeof(double[3]));
        if ((da < 0 && db > 0) || (da > 0 && db < 0)) {
            double f = da / (da - db);
            int j;
            for (j = 0; j < 3; j++) out[k][j] = a[j] + f * (b[j] - a[j]);
            out[k++][axis] = s;
        }
    }
    return k;
}

/* Perfect splits: the box of the part of a triangle inside a cell.  The
 * corners made by cutting carry rounding errors, so the cut box is widened
 * by far more than those, except where it ends at an original corner. */
static int clip(void *user, int i, const double blo[3], const double bhi[3],
                double lo[3], double hi[3])
{
    const prim *p = &((const scene *)user)->p[i];
    double poly[2][12][3], tlo[3], thi[3], tol;
    int n = 3, a, k, cur = 0;
    bounds(user, i, tlo, thi);
    if (p->kind == SPHERE) {
        for (a = 0; a < 3; a++) {
            lo[a] = fmax(tlo[a], blo[a]), hi[a] = fmin(thi[a], bhi[a]);
            if (lo[a] > hi[a]) return 0;
        }
        return 1;
    }
    memcpy(poly[0], p->v, sizeof p->v);
    tol = 1e-12 * (fabs(tlo[0]) + fabs(tlo[1]) + fabs(tlo[2]) + fabs(thi[0])
                   + fabs(thi[1]) + fabs(thi[2]));
    for (a = 0; a < 3 && n > 0; a++) {
        n = cut(poly[cur], n, poly[1 - cur], a, blo[a], 1), cur = 1 - cur;
        if (n > 0) n = cut(poly[cur], n, poly[1 - cur], a, bhi[a], -1), cur = 1 - cur;
    }
    if (n == 0) return 0;
    for (a = 0; a < 3; a++) {
        lo[a] = hi[a] = poly[cur][0][a];
        for (k = 1; k < n; k++) {
            lo[a] = fmin(lo[a], poly[cur][k][a]);
            hi[a] = fmax(hi[a], poly[cur][k][a]);
        }
        if (lo[a] != tlo[a]) lo[a] -= tol;
        if (hi[a] != thi[a]) hi[a] += tol;
    }
    return 1;
}

/* ---- scenes -------------------------------------------------------------- */

static prim make_tri(const double a[3], const double b[3], const double c[3])
{
    prim t;
    double e1[3], e2[3];
    t.kind = TRI;
    memcpy(t.v[0], a, sizeof t.v[0]);
    memcpy(t.v[1], b, sizeof t.v[1]);
    memcpy(t.v[2], c, sizeof t.v[2]);
    sub(b, a, e1), sub(c, a, e2);
    crossp(e1, e2, t.n);
    return t;
}

static prim *alloc_prims(int n)
{
    prim *p = calloc(n > 0 ? n : 1, sizeof(prim));
    if (!p) exit(2);
    return p;
}

/* Random triangles with corners on a 1/64 grid in [0,8]^3, some long and
 * thin (to give perfect splits work), and some spheres. */
static void make_soup(scene *s)
{
    int i, nt = (int)(100 * scale), ns = (int)(20 * scale), a, k;
    s->n = nt + ns, s->p = alloc_prims(s->n);
    for (i = 0; i < nt; i++) {
        double v[3][3], c[3], size = i % 10 == 0 ? 6 : unif(0.1, 1.5);
        for (a = 0; a < 3; a++) c[a] = unif(0, 8);
        for (k = 0; k < 3; k++)
            for (a = 0; a < 3; a++)
                v[k][a] = snap(fmax(0, fmin(8, c[a] + unif(-size, size))), 1.0 / 64);
        s->p[i] = make_tri(v[0], v[1], v[2]);
    }
    for (; i < s->n; i++) {
        s->p[i].kind = SPHERE;
        for (a = 0; a < 3; a++) s->p[i].v[0][a] = on_grid(0.5, 7.5, 1.0 / 64);
        s->p[i].v[1][0] = on_grid(0.1, 0.8, 1.0 / 64) + 1.0 / 64;
    }
    s->use_clip = 1, s->grid = 1.0 / 64, s->small_dirs = 0;
}

/* A closed triangle mesh of a sphere (latitude-longitude), corners rounded
 * to a 1/256 grid; built without the clip callback. */
static void make_mesh(scene *s)
{
    int nu = (int)(16 * sqrt(scale)), nv = (int)(10 * sqrt(scale)), i, j, k = 0;
    double (*v)[3] = malloc(sizeof(double[3]) * (nu * (nv + 1)));
    if (!v) exit(2);
    for (j = 0; j <= nv; j++)
        for (i = 0; i < nu; i++) {
            double th = PI * j / nv, ph = 2 * PI * i / nu, *p = v[j * nu + i];
            p[0] = snap(2 * sin(th) * cos(ph), 1.0 / 256) + 3;
            p[1] = snap(2 * sin(th) * sin(ph), 1.0 / 256) + 3;
            p[2] = snap(2 * cos(th), 1.0 / 256) + 3;
        }
    s->p = alloc_prims(2 * nu * (nv - 1));
    for (j = 0; j < nv; j++)
        for (i = 0; i < nu; i++) {
            double *a = v[j * nu + i], *b = v[j * nu + (i + 1) % nu];
            double *c = v[(j + 1) * nu + i], *d = v[(j + 1) * nu + (i + 1) % nu];
            if (j > 0) s->p[k++] = make_tri(a, c, b);
            if (j < nv - 1) s->p[k++] = make_tri(b, c, d);
        }
    free(v);
    s->n = k, s->use_clip = 0, s->grid = 1.0 / 256, s->small_dirs = 0;
}

/* Axis-aligned rectangles on a lattice of the given step in [0,6 step]^3,
 * two triangles each, some of them repeated: splits fall on lattice planes,
 * rays along lattice lines run along edges and through corners.  With step
 * 1 every coordinate is a float; with step 1/3 ("thirds") most are not, and
 * the tree's float planes and boxes round them (see kd_box in kdtree.c; the BVH rounds its boxes outwards).
 * "tenths" puts the lattice at -0.2 with step 0.1, and rectangles in the
 * planes 0..7 (not 0..6), so some lie on the box's far sides: there a cell's
 * face computed as lo + i w rounds short of the box (-0.2 + 8 (0.7 / 8) <
 * 0.5), and the grid once lost the rectangles lying on that side. */
static void make_grid(scene *s, double step, double at)
{
    int q, nq = (int)(120 * scale), k = 0;
    s->p = alloc_prims(2 * nq);
    for (q = 0; q < nq; q++) {
        double v[4][3];
        int ax = irand(3), u = (ax + 1) % 3, w = (ax + 2) % 3, c;
        int u0 = irand(6), w0 = irand(6), du = 1 + irand(2), dw = 1 + irand(2);
        if (q % 7 == 6) {  /* an exact copy of an earlier rectangle */
            int from = 2 * irand(q);
            s->p[k] = s->p[from], s->p[k + 1] = s->p[from + 1];
            k += 2;
            continue;
        }
        c = irand(at != 0 ? 8 : 7);
        v[0][ax] = v[1][ax] = v[2][ax] = v[3][ax] = at + c * step;
        v[0][u] = at + u0 * step, v[0][w] = at + w0 * step;
        v[1][u] = at + (u0 + du) * step, v[1][w] = at + w0 * step;
        v[2][u] = at + (u0 + du) * step, v[2][w] = at + (w0 + dw) * step;
        v[3][u] = at + u0 * step, v[3][w] = at + (w0 + dw) * step;
        s->p[k++] = make_tri(v[0], v[1], v[2]);
        s->p[k++] = make_tri(v[0], v[2], v[3]);
    }
    s->n = k, s->use_clip = 1, s->grid = step / 2, s->small_dirs = 1;
}

/* 10,000 copies of one triangle: one leaf, every hit a 10,000-way tie. */
static void make_same(scene *s)
{
    double a[3] = {1, 1, 1}, b[3] = {3, 1.5, 2}, c[3] = {1.5, 3, 2.5};
    int i;
    s->n = 10000, s->p = alloc_prims(s->n);
    for (i = 0; i < s->n; i++) s->p[i] = make_tri(a, b, c);
    s->use_clip = 1, s->grid = 1.0 / 64, s->small_dirs = 0;
}

/* Every triangle in the plane z = 3/8: all boxes have zero thickness. */
static void make_flat(scene *s)
{
    int i, k, a;
    s->n = (int)(200 * scale), s->p = alloc_prims(s->n);
    for (i = 0; i < s->n; i++) {
        double v[3][3], c[2];
        c[0] = unif(0, 8), c[1] = unif(0, 8);
        for (k = 0; k < 3; k++) {
            for (a = 0; a < 2; a++) v[k][a] = on_grid(c[a] - 0.7, c[a] + 0.7, 1.0 / 64);
            v[k][2] = 0.375;
        }
        s->p[i] = make_tri(v[0], v[1], v[2]);
    }
    s->use_clip = 1, s->grid = 1.0 / 64, s->small_dirs = 0;
}

static void make_one(scene *s)
{
    double a[3] = {0, 0, 0}, b[3] = {1, 0, 0.5}, c[3] = {0, 1, 0.25};
    s->n = 1, s->p = alloc_prims(1);
    s->p[0] = make_tri(a, b, c);
    s->use_clip = 1, s->grid = 1.0 / 64, s->small_dirs = 1;
}

static int make_scene(const char *name, scene *s)
{
    memset(s, 0, sizeof *s);
    s->name = name;
    if (!strcmp(name, "soup")) make_soup(s);
    else if (!strcmp(name, "mesh")) make_mesh(s);
    else if (!strcmp(name, "grid")) make_grid(s, 1, 0);
    else if (!strcmp(name, "thirds")) make_grid(s, 1.0 / 3, 0);
    else if (!strcmp(name, "tenths")) make_grid(s, 0.1, -0.2);
    else if (!strcmp(name, "same")) make_same(s);
    else if (!strcmp(name, "flat")) make_flat(s);
    else if (!strcmp(name, "one")) make_one(s);
    else if (!strcmp(name, "empty")) s->p = alloc_prims(0), s->grid = 0.5;
    else return 0;
    return 1;
}

/* ---- rays ---------------------------------------------------------------- */

typedef struct {
    double lo[3], hi[3];
} box3;

static void scene_box(const scene *s, box3 *b)
{
    int i, a;
    for (a = 0; a < 3; a++) b->lo[a] = 0, b->hi[a] = s->n ? 0 : 1;
    for (i = 0; i < s->n; i++) {
        double lo[3], hi[3];
        bounds((void *)s, i, lo, hi);
        for (a = 0; a < 3; a++) {
            if (i == 0 || lo[a] < b->lo[a]) b->lo[a] = lo[a];
            if (i == 0 || hi[a] > b->hi[a]) b->hi[a] = hi[a];
        }
    }
}

typedef struct {
    int *axis;
    double *pos;
    long n;
} splits;

/* A point in the scene box grown by `grow` of its size on every side; on
 * the scene's grid when `exact`. */
static void point_in(const scene *s, const box3 *b, double grow, int exact,
                     double p[3])
{
    int a;
    for (a = 0; a < 3; a++) {
        double size = b->hi[a] - b->lo[a] + 1;
        double lo = b->lo[a] - grow * size, hi = b->hi[a] + grow * size;
        p[a] = exact ? on_grid(lo, hi, s->grid) : unif(lo, hi);
    }
}

/* A point on primitive i; with `exact`, at barycentric coordinates in
 * eighths, so that it lies on the triangle without rounding. */
static void point_on(const scene *s, int i, int exact, double p[3])
{
    const prim *t = &s->p[i];
    double u, v, d[3];
    int a;
    if (t->kind == SPHERE) {
        random_dir(d);
        for (a = 0; a < 3; a++) p[a] = t->v[0][a] + t->v[1][0] * d[a];
        return;
    }
    u = exact ? irand(9) / 8.0 : unif(0, 1);
    v = exact ? irand(9) / 8.0 : unif(0, 1);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    for (a = 0; a < 3; a++)
        p[a] = t->v[0][a] + u * (t->v[1][a] - t->v[0][a]) + v * (t->v[2][a] - t->v[0][a]);
}

static void small_dir(double d[3])
{
    do {
        d[0] = irand(7) - 3, d[1] = irand(7) - 3, d[2] = irand(7) - 3;
    } while (d[0] == 0 && d[1] == 0 && d[2] == 0);
}

static void degenerate_dir(const scene *s, double d[3])
{
    if (s->small_dirs || rnd() % 2) small_dir(d);
    else random_dir(d);
}

/* Mostly +0 or -0, sometimes a component so small that the ray is
 * parallel to within rounding (down to the smallest denormal). */
static double zero_or_tiny(void)
{
    static const double tiny[4] = {1e-20, 1e-300, 1e-310, 4.9406564584124654e-324};
    double sign;
    if (rnd() % 4) return signed_zero();
    sign = rnd() & 1 ? 1 : -1;
    return sign * tiny[irand(4)];
}

/* Along an axis: one component +-1 (or +-3), the others (nearly) zero. */
static void axis_dir(double d[3], int axis)
{
    int a;
    for (a = 0; a < 3; a++) d[a] = zero_or_tiny();
    d[axis] = rnd() & 1 ? 1 : -1;
    if (rnd() % 4 == 0) d[axis] *= 3;
}

enum { GENERAL, AIMED, VERTEX, AXIS, SPLIT, INPLANE, INSIDE, SMALL, KINDS };
static const char *const kind_name[KINDS] = {
    "general", "aimed", "vertex", "axis", "split-plane", "in-plane", "inside",
    "small-dir"
};

static void ray_split(const scene *s, const box3 *b, const splits *sp, ray *r)
{
    long k = (long)(rnd() % (unsigned long long)sp->n);
    int a = sp->axis[k];
    point_in(s, b, 0.2, 1, r->o);
    r->o[a] = sp->pos[k];
    switch (irand(3)) {
    case 0: random_dir(r->d); break;
    case 1: degenerate_dir(s, r->d), r->d[a] = zero_or_tiny(); break;  /* in the plane */
    default: axis_dir(r->d, irand(3));
    }
}

/* A ray lying in the plane of a triangle: origin and direction built from
 * the edge vectors with small dyadic factors, so both lie in it exactly. */
static void ray_inplane(const scene *s, int i, ray *r)
{
    const prim *t = &s->p[i];
    double e1[3], e2[3], al = irand(13) / 4.0 - 1, be = irand(13) / 4.0 - 1;
    int a, m, n;
    do m = irand(5) - 2, n = irand(5) - 2; while (m == 0 && n == 0);
    sub(t->v[1], t->v[0], e1), sub(t->v[2], t->v[0], e2);
    for (a = 0; a < 3; a++) {
        r->o[a] = t->v[0][a] + al * e1[a] + be * e2[a];
        r->d[a] = m * e1[a] + n * e2[a];
    }
}

static void vertex_target(const scene *s, double p[3])
{
    const prim *t = &s->p[irand(s->n)];
    if (t->kind == TRI) memcpy(p, t->v[irand(3)], sizeof(double[3]));
    else memcpy(p, t->v[0], sizeof(double[3]));
}

/* The kind of ray number k: every kind in turn.  Among the identical
 * triangles, where each ray that reaches them costs 10,000 tests, only every
 * 40th ray is of a special kind, and the general rays start far away. */
static int kind_of(const scene *s, long k)
{
    if (strcmp(s->name, "same")) return (int)(k % KINDS);
    return k % 40 ? GENERAL : (int)(k / 40 % KINDS);
}

/* Ray number k of the test. */
static int make_ray(const scene *s, const box3 *b, const splits *sp, long k,
                    ray *r, double *tmin, double *tmax)
{
    int kind = kind_of(s, k), a;
    double target[3], far = strcmp(s->name, "same") ? 0.5 : 10;
    if (kind == SPLIT && sp->n == 0) kind = AXIS;
    if ((kind == AIMED || kind == VERTEX) && s->n == 0) kind = GENERAL;
    if (kind == INPLANE && (s->n == 0 || s->p[k / KINDS % s->n].kind != TRI))
        kind = SMALL;
    *tmin = 0;
    switch (kind) {
    case GENERAL: point_in(s, b, far, 0, r->o), random_dir(r->d); break;
    case AIMED:
        point_in(s, b, 0.5, 0, r->o), a = irand(s->n);
        point_on(s, a, rnd() & 1, target);
        sub(target, r->o, r->d);
        break;
    case VERTEX:
        point_in(s, b, 0.5, 1, r->o), vertex_target(s, target);
        sub(target, r->o, r->d);
        break;
    case AXIS: point_in(s, b, 0.2, 1, r->o), axis_dir(r->d, irand(3)); break;
    case SPLIT: ray_split(s, b, sp, r); break;
    case INPLANE: ray_inplane(s, (int)(k / KINDS % s->n), r); break;
    case INSIDE:  /* from inside the box, or from a point on a surface */
        if (s->n && rnd() & 1) point_on(s, irand(s->n), 1, r->o), *tmin = 1e-9;
        else point_in(s, b, 0, rnd() & 1, r->o);
        degenerate_dir(s, r->d);
        break;
    default: point_in(s, b, 0.5, 1, r->o), small_dir(r->d);
    }
    if (r->d[0] == 0 && r->d[1] == 0 && r->d[2] == 0) r->d[0] = 1;
    *tmax = HUGE_VAL;
    if (rnd() % 8 == 0) {  /* a segment instead of a ray */
        double diag = 0;
        for (a = 0; a < 3; a++) diag += b->hi[a] - b->lo[a];
        *tmax = unif(0, 2) * diag / sqrt(dot(r->d, r->d));
    }
    return kind;
}

/* ---- brute force ----------------------------------------------------- */

static int brute_nearest(const scene *s, const ray *r, int skip, double tmin,
                         double *tmax)
{
    double best_t = *tmax, t;
    int i, best = -1;
    for (i = 0; i < s->n; i++)
        if (i != skip && test_prim(s, i, r, tmin, best_t, &t)
            && (t < best_t || (t == best_t && (best < 0 || i < best))))
            best_t = t, best = i;
    if (best >= 0) *tmax = best_t;
    return best;
}

static int brute_any(const scene *s, const ray *r, int skip, double tmin, double tmax)
{
    double t;
    int i;
    for (i = 0; i < s->n; i++)
        if (i != skip && test_prim(s, i, r, tmin, tmax, &t)) return 1;
    return 0;
}

/* In the scene of identical triangles every primitive gives the same
 * answer as primitive 0 (same numbers, same code), so the loop's answer is
 * the first primitive not skipped; the full loop is still run on every
 * 1000th ray. */
static int reference_nearest(const scene *s, const ray *r, int skip, double tmin,
                             double *tmax, long k)
{
    double t;
    int first = skip == 0;
    if (strcmp(s->name, "same") || k % 1000 == 0)
        return brute_nearest(s, r, skip, tmin, tmax);
    if (first >= s->n || !test_prim(s, first, r, tmin, *tmax, &t)) return -1;
    *tmax = t;
    return first;
}

static int reference_any(const scene *s, const ray *r, int skip, double tmin,
                         double tmax, long k)
{
    double t;
    int first = skip == 0;
    if (strcmp(s->name, "same") || k % 1000 == 0) return brute_any(s, r, skip, tmin, tmax);
    return first < s->n && test_prim(s, first, r, tmin, tmax, &t);
}

/* ---- checks ---------------------------------------------------------- */

static int failures = 0;

static void report(int ok, const char *fmt, const char *name, const char *what)
{
    printf("%s %s %s: %s\n", ok ? "PASS" : "FAIL", what, name, fmt);
    failures += !ok;
}

/* want and got: the answers of the reference and of the code under test,
 * named by the labels `a` and `b`. */
static void show_mismatch(const char *what, int kind, const ray *r, double tmin,
                          double tmax, const char *a, int want, double wt,
                          const char *b, int got, double gt)
{
    static int shown;
    if (shown++ >= 5) return;  /* the first few tell the story */
    fprintf(stderr, "%s mismatch (%s): org %a %a %a dir %a %a %a tmin %a tmax %a:"
            " %s %d t=%a, %s %d t=%a\n", what, kind_name[kind],
            r->o[0], r->o[1], r->o[2], r->d[0], r->d[1], r->d[2], tmin, tmax,
            a, want, wt, b, got, gt);
}

/* ---- the structures under test ------------------------------------------ */

/* Every check below runs on each structure, through these few switches. */
enum { KD, BVH_SAH_BUILD, BVH_MEDIAN_BUILD, GRID };
static const char *const accel_names[] = { "kd", "bvh-sah", "bvh-median", "grid" };

typedef struct {
    const char *name;
    int kind;
} accel;

static void *build(const accel *A, int n, const prims *p)
{
    switch (A->kind) {
    case KD: return kd_build(n, p);
    case GRID: return grid_build(n, p);
    }
    return bvh_build(n, p, A->kind == BVH_SAH_BUILD ? BVH_SAH : BVH_MEDIAN);
}

static int nearest(const accel *A, const void *t, const prims *p, const ray *r, int skip,
                   double tmin, double *tmax, prim_counters *c)
{
    void *rv = (void *)r;
    if (A->kind == KD) return kd_nearest(t, p, r->o, r->d, rv, skip, tmin, tmax, c);
    if (A->kind == GRID) return grid_nearest(t, p, r->o, r->d, rv, skip, tmin, tmax, c);
    return bvh_nearest(t, p, r->o, r->d, rv, skip, tmin, tmax, c);
}

static int any_hit(const accel *A, const void *t, const prims *p, const ray *r, int skip,
                   double tmin, double tmax, prim_counters *c)
{
    void *rv = (void *)r;
    if (A->kind == KD) return kd_any(t, p, r->o, r->d, rv, skip, tmin, tmax, c);
    if (A->kind == GRID) return grid_any(t, p, r->o, r->d, rv, skip, tmin, tmax, c);
    return bvh_any(t, p, r->o, r->d, rv, skip, tmin, tmax, c);
}

/* The slide's recursive form; the grid has none. */
static int has_recursive(const accel *A) { return A->kind != GRID; }

static int recursive(const accel *A, const void *t, const prims *p, const ray *r, int skip,
                     double tmin, double *tmax, int any, prim_counters *c)
{
    return A->kind == KD
        ? kd_intersect_recursive(t, p, r->o, r->d, (void *)r, skip, tmin, tmax, any, c)
        : bvh_intersect_recursive(t, p, r->o, r->d, (void *)r, skip, tmin, tmax, any, c);
}

/* The built structure as one block of bytes. */
static const void *bytes(const accel *A, const void *t, size_t *size)
{
    bvh_info b;
    grid_info g;
    if (A->kind == KD) return kd_bytes(t, size);
    if (A->kind == GRID) {
        grid_describe(t, &g);
        *size = g.bytes;
        return g.block;
    }
    bvh_describe(t, &b);
    *size = b.bytes;
    return b.block;
}

/* The planes of its cells or boxes: rays are aimed along them. */
static long planes(const accel *A, const void *t, int *axis, double *pos, long max)
{
    switch (A->kind) {
    case KD: return kd_splits(t, axis, pos, max);
    case GRID: return grid_planes(t, axis, pos, max);
    }
    return bvh_planes(t, axis, pos, max);
}

static void release(const accel *A, void *t)
{
    if (A->kind == KD) kd_free(t);
    else if (A->kind == GRID) grid_free(t);
    else bvh_free(t);
}

/* ---- shape -------------------------------------------------------------- */

/* The kd-tree's shape, and its 8-byte node: the block kd_bytes returns is
 * exactly 8 bytes per node plus one int per primitive reference. */
static void check_kd_shape(const scene *s, const kd_tree *t)
{
    kd_info in;
    char msg[400];
    long inner = kd_splits(t, NULL, NULL, 0);
    size_t size;
    double guard = 8 + 1.3 * log2(s->n > 1 ? s->n : 1);
    int ok;
    kd_describe(t, &in);
    kd_bytes(t, &size);
    ok = in.nodes == 2 * in.leaves - 1 && inner == in.nodes - in.leaves
         && in.max_depth <= guard && size == in.bytes
         && in.bytes == 8 * (size_t)in.nodes + sizeof(int) * (size_t)in.prim_refs;
    sprintf(msg, "%d prims, %ld nodes, %ld leaves (%ld empty), depth %ld "
            "(guard %.1f), %ld refs, %.2f prims/leaf, %lu bytes "
            "(8 per node), SAH %.2f, built in %.4f s", s->n, in.nodes,
            in.leaves, in.empty_leaves, in.max_depth, guard, in.prim_refs,
            in.prims_per_leaf, (unsigned long)in.bytes, in.sah_cost,
            in.build_seconds);
    report(ok, msg, s->name, "tree");
}

/* The BVH's shape: 128 bytes a four-way node, no more nodes than leaves,
 * and every primitive in exactly one leaf: the list at the end of the block
 * is a permutation of 0..n-1. */
static void check_bvh_shape(const scene *s, const bvh *t)
{
    bvh_info in;
    char msg[400];
    size_t size;
    const char *block;
    const int *list;
    char *seen = calloc(s->n + 1, 1);
    int ok, i, once = 1;
    bvh_describe(t, &in);
    block = in.block, size = in.bytes;
    if (!seen) exit(2);
    ok = in.nodes <= in.leaves && (in.nodes > 0) == (s->n > 0) && in.prim_refs == s->n
         && in.max_depth < 96 && size == in.bytes
         && size == 128 * (size_t)in.nodes + sizeof(int) * (size_t)s->n;
    list = (const int *)(block + size - sizeof(int) * (size_t)s->n);
    for (i = 0; ok && i < s->n; i++) {
        if (list[i] < 0 || list[i] >= s->n || seen[list[i]]) once = 0;
        else seen[list[i]] = 1;
    }
    free(seen);
    sprintf(msg, "%d prims, %ld nodes, %ld leaves, depth %ld, %.2f prims/leaf, "
            "each primitive in one leaf: %s, %lu bytes (128 per four-way node), SAH %.2f "
            "(binary %.2f), built in %.4f s", s->n, in.nodes, in.leaves, in.max_depth,
            in.prims_per_leaf, once ? "yes" : "NO", (unsigned long)in.bytes,
            in.sah_cost, in.sah_cost_binary, in.build_seconds);
    report(ok && once, msg, s->name, "tree");
}

/* The grid's shape: res[0] res[1] res[2] cells, a 4-byte offset per cell
 * and one more, then a 4-byte primitive number per reference. */
static void check_grid_shape(const scene *s, const grid *g)
{
    grid_info in;
    char msg[400];
    size_t size;
    int ok;
    grid_describe(g, &in);
    size = in.bytes;
    ok = in.cells == (long)in.res[0] * in.res[1] * in.res[2] && size == in.bytes
         && in.bytes == 4 * (size_t)(in.cells + 1) + sizeof(int) * (size_t)in.prim_refs
         && in.prim_refs >= s->n;
    sprintf(msg, "%d prims, %dx%dx%d cells (%ld empty), %ld refs (%.2f a primitive), "
            "%lu bytes, built in %.4f s", s->n, in.res[0], in.res[1], in.res[2],
            in.empty_cells, in.prim_refs, s->n ? (double)in.prim_refs / s->n : 0.0,
            (unsigned long)in.bytes, in.build_seconds);
    report(ok, msg, s->name, "grid");
}

static void check_shape(const accel *A, const scene *s, const void *t)
{
    if (A->kind == KD) check_kd_shape(s, t);
    else if (A->kind == GRID) check_grid_shape(s, t);
    else check_bvh_shape(s, t);
}

static void check_determinism(const accel *A, const scene *s, const prims *p,
                              const void *t)
{
    void *again = build(A, s->n, p);
    size_t n1, n2;
    const void *b1 = bytes(A, t, &n1), *b2;
    char msg[200];
    int ok;
    if (!again) {
        report(0, "second build failed", s->name, "deterministic");
        return;
    }
    b2 = bytes(A, again, &n2);
    ok = n1 == n2 && memcmp(b1, b2, n1) == 0;
    sprintf(msg, "two builds, %lu and %lu bytes, %s", (unsigned long)n1,
            (unsigned long)n2, ok ? "identical" : "DIFFERENT");
    report(ok, msg, s->name, "deterministic");
    release(A, again);
}

/* The planes of the structure's cells or boxes: rays are aimed along them. */
static splits get_splits(const accel *A, const void *t)
{
    splits sp;
    sp.n = planes(A, t, NULL, NULL, 0);
    sp.axis = malloc((sp.n + 1) * sizeof(int));
    sp.pos = malloc((sp.n + 1) * sizeof(double));
    if (!sp.axis || !sp.pos) exit(2);
    planes(A, t, sp.axis, sp.pos, sp.n);
    return sp;
}

/* ---- rays ----------------------------------------------------------------- */

/* The tmax for the any-hit query: unbounded, exactly at the nearest hit
 * (the bound is inclusive), just before it, or anywhere. */
static double any_tmax(int nearest, double t, double tmax)
{
    switch (rnd() % 4) {
    case 0: return HUGE_VAL;
    case 1: return nearest >= 0 ? t : tmax;
    case 2: return nearest >= 0 ? nextafter(t, -HUGE_VAL) : tmax;
    default: return tmax == HUGE_VAL ? unif(0, 20) : unif(0, tmax);
    }
}

/* One ray's nearest-hit check with primitive `skip` left out: 1 if the
 * structure agrees with the loop; want, want_t: the loop's answer. */
static int check_nearest(const accel *A, const scene *s, const prims *p, const void *t,
                         const ray *r, int kind, int skip, double tmin, double tmax,
                         long k, int *want, double *want_t, prim_counters *c)
{
    double got_t = tmax;
    int got;
    *want_t = tmax;
    *want = reference_nearest(s, r, skip, tmin, want_t, k);
    got = nearest(A, t, p, r, skip, tmin, &got_t, c);
    if (*want == got && !memcmp(want_t, &got_t, sizeof(double))) return 1;
    show_mismatch(skip < 0 ? "nearest" : "nearest with skip", kind, r, tmin, tmax,
                  "brute", *want, *want_t, A->name, got, got_t);
    return 0;
}

static int check_any(const accel *A, const scene *s, const prims *p, const void *t,
                     const ray *r, int kind, int skip, double tmin, double tmax,
                     long k, int *want, prim_counters *c)
{
    int got;
    double tg;
    *want = reference_any(s, r, skip, tmin, tmax, k);
    got = any_hit(A, t, p, r, skip, tmin, tmax, c);
    /* any primitive hit in range will do, but it must be one */
    if (*want == (got >= 0) && (got < 0 || (got != skip && got < s->n
                                              && test_prim(s, got, r, tmin, tmax, &tg))))
        return 1;
    show_mismatch(skip < 0 ? "any" : "any with skip", kind, r, tmin, tmax,
                  "brute", *want, 0, A->name, got, 0);
    return 0;
}

/* One query (nearest, or any with `any`) asked of the iterative walk and
 * of the recursive reference: 1 if they give the same primitive, bitwise
 * the same t, and the same steps and tests. */
static int check_recursive(const accel *A, const prims *p, const void *t, const ray *r,
                           int kind, int skip, double tmin, double tmax, int any)
{
    prim_counters cw = {0, 0, 0}, cr = {0, 0, 0};
    double tw = tmax, tr = tmax;
    char a[80], b[80];
    int w = any ? any_hit(A, t, p, r, skip, tmin, tmax, &cw)
                : nearest(A, t, p, r, skip, tmin, &tw, &cw);
    int k = recursive(A, t, p, r, skip, tmin, &tr, any, &cr);
    if (w == k && !memcmp(&tw, &tr, sizeof tw) && cw.steps == cr.steps
        && cw.tests == cr.tests)
        return 1;
    sprintf(a, "walk (%llu steps, %llu tests)", cw.steps, cw.tests);
    sprintf(b, "recursive (%llu steps, %llu tests)", cr.steps, cr.tests);
    show_mismatch(any ? "recursive any" : "recursive nearest", kind, r, tmin,
                  tmax, a, w, tw, b, k, tr);
    return 0;
}

/* Every ray: nearest.  Every other ray: any.  Every 8th ray, once more with
 * its nearest primitive skipped (the surface a ray leaves, in ray.c):
 * nearest on odd rays, any on even ones.  Each of these queries is also
 * asked of the recursive reference, where there is one.  `when` names the
 * state checked ("" or "after refit"). */
static void check_rays(const accel *A, const scene *s, const prims *p, const void *t,
                       long nrays, const char *when)
{
    box3 b;
    splits sp = get_splits(A, t);
    prim_counters c = {0, 0, 0};
    long k, bad_near = 0, bad_any = 0, bad_skip = 0, hits = 0, anys = 0, anyrays = 0;
    long skips = 0, rec_near = 0, rec_any = 0, bad_rec_near = 0, bad_rec_any = 0;
    long per_kind[KINDS] = {0}, bad_kind[KINDS] = {0};
    char msg[700], *m = msg, what[64];
    clock_t start = clock();
    int j, rec = has_recursive(A);
    scene_box(s, &b);
    for (k = 0; k < nrays; k++) {
        ray r;
        double tmin, tmax, want_t, w2_t, ta;
        int kind = make_ray(s, &b, &sp, k, &r, &tmin, &tmax), want, w2, ok;
        per_kind[kind]++;
        ok = check_nearest(A, s, p, t, &r, kind, -1, tmin, tmax, k, &want, &want_t, &c);
        hits += want >= 0;
        if (!ok) bad_near++, bad_kind[kind]++;
        if (rec) rec_near++, bad_rec_near += !check_recursive(A, p, t, &r, kind, -1, tmin, tmax, 0);
        if ((k % 8 == 1 || hits == 1) && want >= 0) {   /* the first hit, too: some scenes have few */
            skips++;
            if (!check_nearest(A, s, p, t, &r, kind, want, tmin, tmax, k, &w2, &w2_t, &c))
                bad_skip++, bad_kind[kind]++;
            if (rec) {
                rec_near++;
                bad_rec_near += !check_recursive(A, p, t, &r, kind, want, tmin, tmax, 0);
            }
        }
        if (k % 2) continue;  /* any-hit on every other ray */
        anyrays++;
        ta = any_tmax(want, want_t, tmax);
        if (k % 8 == 2 && want >= 0) {
            skips++;
            if (!check_any(A, s, p, t, &r, kind, want, tmin, ta, k, &w2, &c))
                bad_skip++, bad_kind[kind]++;
            if (rec) {
                rec_any++;
                bad_rec_any += !check_recursive(A, p, t, &r, kind, want, tmin, ta, 1);
            }
        }
        ok = check_any(A, s, p, t, &r, kind, -1, tmin, ta, k, &w2, &c);
        anys += w2;
        if (!ok) bad_any++, bad_kind[kind]++;
        if (rec) rec_any++, bad_rec_any += !check_recursive(A, p, t, &r, kind, -1, tmin, ta, 1);
    }
    m += sprintf(m, "%s%s%ld rays, %ld hit, %ld mismatches; %.2f steps and %.2f "
                 "tests per ray (brute force: %d); %.1f s; by kind:", when, *when ? ": " : "",
                 nrays, hits, bad_near, c.rays ? (double)c.steps / c.rays : 0.0,
                 c.rays ? (double)c.tests / c.rays : 0.0, s->n,
                 (double)(clock() - start) / CLOCKS_PER_SEC);
    for (j = 0; j < KINDS; j++)
        m += sprintf(m, " %s %ld/%ld", kind_name[j], bad_kind[j], per_kind[j]);
    sprintf(what, "%s nearest", A->name);
    report(bad_near == 0 && c.rays == (unsigned long long)(nrays + anyrays + skips), msg,
           s->name, what);
    sprintf(msg, "%s%s%ld rays, %ld blocked, %ld mismatches%s", when, *when ? ": " : "",
            anyrays, anys, bad_any,
            strcmp(s->name, "same") ? "" : " (full loop on every 1000th ray)");
    sprintf(what, "%s any", A->name);
    report(bad_any == 0, msg, s->name, what);
    sprintf(msg, "%s%s%ld rays again with their nearest primitive skipped (nearest and any), "
            "%ld mismatches", when, *when ? ": " : "", skips, bad_skip);
    sprintf(what, "%s skip", A->name);
    report(bad_skip == 0 && (skips > 0 || hits == 0), msg, s->name, what);
    if (rec) {
        sprintf(msg, "%s%sthe recursive reference against the walk on every query above: "
                "%ld nearest, %ld mismatches; %ld any, %ld mismatches (same primitive, "
                "bitwise the same t, same steps and tests)", when, *when ? ": " : "",
                rec_near, bad_rec_near, rec_any, bad_rec_any);
        sprintf(what, "%s recursive", A->name);
        report(bad_rec_near == 0 && bad_rec_any == 0, msg, s->name, what);
    }
    free(sp.axis), free(sp.pos);
}

/* Rays from far away, and rays the fast walks do not take, in turn:
 * origins 10^13 away aimed at a corner of a primitive (or a sphere's
 * centre) or at a point on one, where neighbouring primitives are hit at t
 * that differ by no more than their rounding (10^-3 at 10^13: the walk's
 * slack along the ray, prims.h, decides these); origins 10^12 scene sizes
 * away aimed at the scene; and directions scaled by 2^-70 or 2^70 (out of
 * the float test's range).  The structures answer them by testing every
 * primitive, or walk them as usual; either way the answer must be brute
 * force's. */
static void check_far(const accel *A, const scene *s, const prims *p, const void *t,
                      long nrays)
{
    box3 b;
    long k, bad = 0, hits = 0;
    char msg[300], what[64];
    scene_box(s, &b);
    for (k = 0; k < nrays; k++) {
        ray r;
        double target[3], f = k % 4 == 0 ? 0x1p-70 : k % 4 == 1 ? 0x1p70 : 1, tw, tg;
        int a, want, got;
        if (k % 4 == 3 && s->n > 0) {
            if (k % 8 == 3) vertex_target(s, target);
            else point_on(s, irand(s->n), 0, target);
        } else
            point_in(s, &b, 0, 0, target);
        random_dir(r.d);
        for (a = 0; a < 3; a++) {
            double size = b.hi[a] - b.lo[a] + 1;
            r.o[a] = k % 4 == 3 ? target[a] - 1e13 * r.d[a]
                     : k % 4 == 2 ? target[a] - 1e12 * size * r.d[a] : target[a] - 3 * size * r.d[a];
            r.d[a] *= f;
        }
        tw = tg = HUGE_VAL;
        want = brute_nearest(s, &r, -1, 0, &tw);
        got = nearest(A, t, p, &r, -1, 0, &tg, NULL);
        hits += want >= 0;
        if (want != got || memcmp(&tw, &tg, sizeof tw)) {
            bad++;
            show_mismatch("far", GENERAL, &r, 0, HUGE_VAL, "brute", want, tw, A->name, got, tg);
        }
    }
    sprintf(msg, "%ld rays from 10^13 away at corners and surfaces, from 10^12 sizes away, "
            "or with directions of 2^-70 and 2^70; %ld hit, %ld mismatches", nrays, hits, bad);
    sprintf(what, "%s far", A->name);
    report(bad == 0, msg, s->name, what);
}

/* The scene moved by OFFSET along every axis, built anew and checked as at
 * the origin on a quarter of the rays, and from far away: a float step of
 * the caller's coordinates is then 8, larger than the scene, so the
 * structures' frames and margins must follow the scene's size and not its
 * distance from the origin.  1e8 is an integer, so the dyadic scenes keep
 * their exact coordinates (down to 2^-26). */
#define OFFSET 1e8

/* The work (steps and tests) of nrays rays into the scene, each aimed at a
 * point of its box from `dist` away (dist < 0: -dist times the box's
 * size), through structure t, with the scene moved by off. */
static prim_counters work(const accel *A, const scene *s, const prims *p, const void *t,
                          long nrays, double dist, double off)
{
    prim_counters c = {0, 0, 0};
    box3 b;
    double size = 0;
    long k;
    int a;
    unsigned long long keep = rng_state;
    rng_state = 12345;          /* the same rays every time */
    scene_box(s, &b);
    for (a = 0; a < 3; a++) {
        b.lo[a] -= off, b.hi[a] -= off;
        size = fmax(size, b.hi[a] - b.lo[a]);
    }
    if (dist < 0) dist *= -(size + 1);
    for (k = 0; k < nrays; k++) {
        ray r;
        double target[3], tg = HUGE_VAL;
        point_in(s, &b, 0, 0, target);
        random_dir(r.d);
        for (a = 0; a < 3; a++)
            r.o[a] = target[a] - dist * r.d[a] + off;
        nearest(A, t, p, &r, -1, 0, &tg, &c);
    }
    rng_state = keep;
    return c;
}

/* The structures' work far from the origin against their work at it, on
 * the same rays: the scene moved by OFFSET, rays from 10^13 away, and
 * both.  Each must stay within 1.25 times the origin's steps and tests per
 * ray, plus one: more would mean a margin that grows with the distance
 * from the origin (the speed issue 14 asked about; exactness alone cannot
 * show it). */
static void check_work(const accel *A, const scene *s, const prims *p, const void *t,
                       const scene *o, const prims *op, const void *ot, long nrays)
{
    prim_counters c[4];
    double steps[4], tests[4];
    char msg[400], what[64];
    int j, ok = 1;
    c[0] = work(A, s, p, t, nrays, -3, 0);
    c[1] = work(A, o, op, ot, nrays, -3, OFFSET);
    c[2] = work(A, s, p, t, nrays, 1e13, 0);
    c[3] = work(A, o, op, ot, nrays, 1e13, OFFSET);
    for (j = 0; j < 4; j++) {
        steps[j] = (double)c[j].steps / nrays, tests[j] = (double)c[j].tests / nrays;
        ok &= steps[j] <= 1.25 * steps[0] + 1 && tests[j] <= 1.25 * tests[0] + 1;
    }
    sprintf(msg, "steps and tests per ray on %ld rays: at the origin %.2f and %.2f, the scene "
            "offset by 1e8 %.2f and %.2f, from 1e13 away %.2f and %.2f, both %.2f and %.2f "
            "(each within 1.25x the origin's, plus 1)", nrays, steps[0], tests[0], steps[1],
            tests[1], steps[2], tests[2], steps[3], tests[3]);
    sprintf(what, "%s work far", A->name);
    report(ok, msg, s->name, what);
}

static void check_offset(const accel *A, const scene *s, const prims *sp, const void *st,
                         long nrays)
{
    scene o = *s;
    prims p;
    void *t;
    int i, k, a;
    o.p = alloc_prims(s->n);
    for (i = 0; i < s->n; i++) {
        prim q = s->p[i];
        for (k = 0; k < (q.kind == TRI ? 3 : 1); k++)
            for (a = 0; a < 3; a++) q.v[k][a] += OFFSET;
        o.p[i] = q.kind == TRI ? make_tri(q.v[0], q.v[1], q.v[2]) : q;
    }
    p.bounds = bounds, p.clip = o.use_clip ? clip : NULL, p.hit = hit, p.user = &o, p.eps = 0;
    t = build(A, o.n, &p);
    if (!t) {
        report(0, "the build of the scene offset by 1e8 returned NULL", s->name, A->name);
        free(o.p);
        return;
    }
    check_rays(A, &o, &p, t, nrays / 10, "offset 1e8");
    check_far(A, &o, &p, t, nrays / 100 + 1);
    check_work(A, s, sp, st, &o, &p, t, nrays / 100 + 1);
    release(A, t);
    free(o.p);
}

/* ---- refit ------------------------------------------------------------------ */

/* A quarter of the primitives move by a step of up to 2 along each axis, on
 * the scene's grid (so that the exact-arithmetic rays stay exact).  The
 * identical triangles of "same" all move together: they stay identical, as
 * reference_nearest assumes. */
static void move_some(scene *s)
{
    int i, k, a, same = !strcmp(s->name, "same");
    double off[3];
    for (a = 0; a < 3; a++) off[a] = on_grid(-2, 2, s->grid > 0 ? s->grid : 0.5);
    for (i = 0; i < s->n; i++) {
        prim *q = &s->p[i];
        if (!same && rnd() % 4) continue;
        if (!same)
            for (a = 0; a < 3; a++) off[a] = on_grid(-2, 2, s->grid > 0 ? s->grid : 0.5);
        for (k = 0; k < (q->kind == TRI ? 3 : 1); k++)
            for (a = 0; a < 3; a++) q->v[k][a] += off[a];
    }
}

/* The BVH after the primitives move: refitted, it must still give exactly
 * what brute force gives (check_rays on a quarter of the rays), and on
 * every one of those rays what a fresh build of the moved scene gives. */
static void check_refit(const accel *A, scene *s, const prims *p, void *t, long nrays)
{
    void *fresh;
    box3 b;
    splits sp;
    long k, bad = 0;
    char msg[400], what[64];
    bvh_info before, after, rebuilt;
    prim_counters cr = {0, 0, 0}, cf = {0, 0, 0};
    bvh_describe(t, &before);
    move_some(s);
    bvh_refit(t, p);
    bvh_describe(t, &after);
    check_rays(A, s, p, t, nrays / 4, "after refit");
    fresh = build(A, s->n, p);
    if (!fresh) exit(2);
    scene_box(s, &b);
    sp = get_splits(A, t);
    for (k = 0; k < nrays / 4; k++) {
        ray r;
        double tmin, tmax, t1, t2;
        int i1, i2;
        make_ray(s, &b, &sp, k, &r, &tmin, &tmax);
        t1 = t2 = tmax;
        i1 = nearest(A, t, p, &r, -1, tmin, &t1, &cr);
        i2 = nearest(A, fresh, p, &r, -1, tmin, &t2, &cf);
        bad += i1 != i2 || memcmp(&t1, &t2, sizeof t1);
    }
    bvh_describe(fresh, &rebuilt);
    sprintf(msg, "a quarter of the primitives moved, the tree refitted: SAH cost %.2f -> %.2f "
            "(a fresh build: %.2f); on %ld rays, %.2f steps and %.2f tests per ray (fresh build: "
            "%.2f and %.2f), %ld answers differ from the fresh build's", before.sah_cost,
            after.sah_cost, rebuilt.sah_cost, nrays / 4, (double)cr.steps / (nrays / 4 ? nrays / 4 : 1),
            (double)cr.tests / (nrays / 4 ? nrays / 4 : 1), (double)cf.steps / (nrays / 4 ? nrays / 4 : 1),
            (double)cf.tests / (nrays / 4 ? nrays / 4 : 1), bad);
    sprintf(what, "%s refit", A->name);
    report(bad == 0, msg, s->name, what);
    free(sp.axis), free(sp.pos);
    release(A, fresh);
}

int main(int argc, char **argv)
{
    scene s;
    prims p;
    void *t;
    accel acc, *A = NULL;
    long nrays = 1000000;
    int k;
    const char *env = getenv("ACCEL_RAYS");
    if (env) nrays = atol(env);
    env = getenv("ACCEL_SEED");  /* other scenes and rays, for long runs */
    if (env) rng_state += 0x9E3779B97F4A7C15ull * (unsigned long long)atol(env);
    env = getenv("ACCEL_SCALE");
    if (env) scale = atof(env);
    if (!(scale >= 0.1)) scale = 0.1;
    if (argc > 3) nrays = atol(argv[3]);
    for (k = 0; argc > 1 && k < 4; k++)
        if (!strcmp(argv[1], accel_names[k])) acc.name = accel_names[k], acc.kind = k, A = &acc;
    if (!A || argc < 3 || !make_scene(argv[2], &s)) {
        fprintf(stderr, "usage: test_accel kd|bvh-sah|bvh-median|grid "
                "soup|mesh|grid|thirds|tenths|same|flat|empty|one [rays]\n");
        return 2;
    }
    p.bounds = bounds, p.clip = s.use_clip ? clip : NULL, p.hit = hit, p.user = &s, p.eps = 0;
    t = build(A, s.n, &p);
    if (!t) {
        report(0, "the build returned NULL", s.name, A->name);
        return 1;
    }
    check_shape(A, &s, t);
    check_determinism(A, &s, &p, t);
    check_rays(A, &s, &p, t, nrays, "");
    if (strcmp(s.name, "same")) check_far(A, &s, &p, t, nrays / 100 + 1);
    if (strcmp(s.name, "same")) check_offset(A, &s, &p, t, nrays);
    if (A->kind == BVH_SAH_BUILD || A->kind == BVH_MEDIAN_BUILD) check_refit(A, &s, &p, t, nrays);
    release(A, t);
    free(s.p);
    return failures != 0;
}

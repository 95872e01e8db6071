/* grid.c - a uniform grid for ray tracing over primitives it knows only
 * through the callbacks of prims.h.  grid.h maps the lecture's grid slide
 * (Fujimoto, Tanaka & Iwata 1986) and the 3D-DDA of Amanatides & Woo 1987
 * to the functions below.
 *
 * Resolution.  Cleary & Wyvill 1988 ("Analysis of an algorithm for fast
 * ray tracing using uniform space subdivision") show the cost of a ray
 * falling as cells are added until there are a few per object; we take the
 * density form: DENSITY cells per object, the cells as near to cubes as the
 * scene's box allows (an axis along which the box is flat gets one cell).
 *
 * Exactness.  A plain DDA visits the cells the ray passes through.  A hit
 * point may lie a little outside its primitive's box (the contract of
 * prims.h), and so in a cell that does not list it; like the kd-tree
 * (kdtree.c, RAY_EPS), the walk therefore treats every cell as grown by a
 * margin delta (see RAY_EPS below).  It visits every cell whose grown box
 * the ray passes through, in
 * the order the ray enters them: per axis it keeps the range of cell
 * indices that a cube of half-side delta around the ray's point overlaps.
 * The leading end of a range moving on is Amanatides & Woo's step (it
 * brings in a new slab of cells, nearly always one cell); the trailing end
 * follows (it drops cells).  With delta far below a cell this is the
 * classic DDA, plus a second cell for the rare ray passing within delta of
 * a cell face.  The walk stops before a cell the ray enters beyond the best
 * hit so far.
 */
#include "grid.h"
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Cells per object.  Measured on SPD scenes: see the README. */
#define DENSITY 2.0
#define MAX_RES 1024
#define MAX_CELLS (1l << 24)

/* A primitive reaching over many cells is listed in each.  When the boxes
 * would make more than MAX_REFS references per object in all (many large
 * overlapping objects: a thousand copies of one triangle, say), the cells
 * are made coarser, halving each side until they do not. */
#define MAX_REFS 16

/* The margin:
 *     delta = RAY_EPS * ext + (WALK_ULPS DBL_EPSILON + ulps) * s,
 * ext half the longest side of the scene box, s the largest |coordinate| of
 * the scene box.  The hit callback's point may lie outside its primitive's
 * box by PRIMS_HIT_REL of the box's longest side (at most 2 ext) plus
 * PRIMS_HIT_ULPS eps s (the contract of prims.h): ulps = PRIMS_HIT_ULPS
 * eps, and the first is inside RAY_EPS ext, as in kdtree.c.  The grid has
 * no floats and keeps the caller's coordinates: its faces lo + i w, the
 * cells of a point, floor((x - lo) / w), and the DDA's crossings
 * (face - o) / d are doubles, a few roundings each of numbers below 2s +
 * 2 ext (a point and its cell may disagree by as much), which WALK_ULPS
 * DBL_EPSILON s covers.  An origin at D from the box's middle adds a few
 * 2^-53 D, inside RAY_EPS ext while D is below FAR_MOVE ext: a farther one
 * is first moved along the ray to where the ray enters the box, the sum
 * o + t0 d taken exactly and rounded once (prims_along, prims.h), and the
 * walk's t is then the caller's t less t0.
 *
 * The slack.  The contract also lets the callback's t err along the ray by
 * ulps m / max|d|, m the larger of s and the origin's largest |coordinate|
 * (from 10^13 away, t is rounded by 10^-3): the walk takes the ray from
 * tmin - slack to tmax + slack and stops only before a cell it enters more
 * than slack beyond the best hit.  A far origin costs a cell now and then
 * just behind the hit, not a margin across every cell. */
#define RAY_EPS 2.5e-7
#define WALK_ULPS 8
#define FAR_MOVE 0x1p20

/* Each ray keeps the last primitive tested in each of MAILBOX slots chosen
 * by the primitive's number (Amanatides & Woo 1987): an object in several
 * cells along the ray is tested once, unless two objects share a slot. */
#define MAILBOX 16

/* A ray whose numbers leave these bounds is answered by testing every
 * primitive (see setup_ray). */
#define FAST_MAX 0x1p500
#define FAST_MIN 0x1p-500
#define FLAT 0x1p-60

struct grid {
    double lo[3], w[3], inv_w[3];  /* the grid's corner, and a cell's size */
    int res[3];
    double hi[3];                  /* the scene box's far corner */
    double scale;                  /* largest |coordinate| of the scene box */
    double ext;                    /* half the longest side of the scene box */
    double mid[3];                 /* the scene box's middle */
    double delta;                  /* the margin (see RAY_EPS) */
    double ulps;                   /* PRIMS_HIT_ULPS eps: the slack's factor of m */
    double narrow;                 /* the narrowest cell side (of axes cut in two or more) */
    uint32_t *start;               /* cell c lists list[start[c] .. start[c+1]) */
    int *list;
    int *all;                      /* every primitive with a box, for the fallback */
    long ncells, nrefs, nall;
    void *block;
    size_t bytes;
    grid_info info;
};

/* ---- traversal ---------------------------------------------------------- */

typedef struct {
    double o[3], d[3], inv[3];
    int flat[3];
    double delta;
    double toff;            /* how far along the ray o was moved: the walk's t is the caller's less toff */
    double slack;           /* how far along the ray a hit's t may err (see RAY_EPS) */
    double t0, t1;          /* the ray inside the grid's grown box */
    int lo[3], hi[3];       /* cells overlapped by the grown point, per axis */
    int skip;
    int mail[MAILBOX];
} grid_ray;

static int cell_of(const grid *g, int a, double x)
{
    double f = floor((x - g->lo[a]) * g->inv_w[a]);
    return f < 0 ? 0 : f >= g->res[a] ? g->res[a] - 1 : (int)f;
}

static double face(const grid *g, int a, int i)
{
    return g->lo[a] + i * g->w[a];
}

/* Clip the ray to the grid's box grown by delta (the slab test); 0 when it
 * misses it, or when its numbers are out of range for the walk.  An origin
 * from far away is moved first (see RAY_EPS), to where the ray enters the
 * box by the same test on the unmoved origin. */
static int setup_ray(const grid *g, const double org[3], const double dir[3],
                     int skip, double tmin, double tmax, grid_ray *r)
{
    double scale = g->scale, dmax = 0, t0, t1, far = 0, o[3], least = HUGE_VAL;
    int a, pass, move;
    for (a = 0; a < 3; a++) {
        if (fabs(org[a]) > scale) scale = fabs(org[a]);
        if (fabs(dir[a]) > dmax) dmax = fabs(dir[a]);
        if (fabs(org[a] - g->mid[a]) > far) far = fabs(org[a] - g->mid[a]);
        o[a] = org[a];
    }
    for (a = 0; a < 3; a++) {
        r->d[a] = dir[a];
        r->flat[a] = !(fabs(dir[a]) > FLAT * dmax);
        r->inv[a] = r->flat[a] ? 0 : 1 / dir[a];
        if (!r->flat[a] && fabs(r->inv[a]) < least) least = fabs(r->inv[a]);
    }
    r->slack = g->ulps * scale * least;     /* 1 / max|d|, no division of its own */
    if (!(r->slack >= 0)) r->slack = HUGE_VAL;
    tmin -= r->slack, tmax += r->slack;
    t0 = tmin, t1 = tmax;
    r->toff = 0;
    r->skip = skip;
    for (a = 0; a < MAILBOX; a++) r->mail[a] = -1;
    move = far > FAR_MOVE * g->ext;
    r->delta = g->delta + (move ? g->ulps * scale : 0);   /* a far o's rounding, across the ray too */
    for (pass = move; pass >= 0; pass--) {
        if (pass == 0 && move) {            /* from far away: move the origin to t0 */
            r->delta = g->delta;
            for (a = 0; a < 3; a++) o[a] = prims_along(org[a], 0, r->toff, dir[a]);
            t0 = tmin - r->toff, t1 = tmax - r->toff;
        }
        for (a = 0; a < 3; a++) {
            double lo = g->lo[a] - r->delta, hi = g->hi[a] + r->delta, ta, tb;
            r->o[a] = o[a];
            if (r->flat[a]) {
                if (!(o[a] >= lo && o[a] <= hi)) return 0;
                continue;
            }
            ta = (lo - o[a]) * r->inv[a], tb = (hi - o[a]) * r->inv[a];
            if (ta > tb) { double s = ta; ta = tb; tb = s; }
            if (ta > t0) t0 = ta;
            if (tb < t1) t1 = tb;
        }
        if (!(t0 <= t1)) return 0;
        if (pass == 1) r->toff = t0;
    }
    r->t0 = t0, r->t1 = t1;
    return 1;
}

/* The time the range of axis a next gains a cell (lead) or loses one
 * (lag); HUGE_VAL for never. */
static double lead_time(const grid *g, const grid_ray *r, int a)
{
    if (r->flat[a]) return HUGE_VAL;
    if (r->d[a] > 0)
        return r->hi[a] + 1 >= g->res[a] ? HUGE_VAL
               : (face(g, a, r->hi[a] + 1) - r->delta - r->o[a]) * r->inv[a];
    return r->lo[a] <= 0 ? HUGE_VAL : (face(g, a, r->lo[a]) + r->delta - r->o[a]) * r->inv[a];
}

static double lag_time(const grid *g, const grid_ray *r, int a)
{
    if (r->flat[a] || r->lo[a] >= r->hi[a]) return HUGE_VAL;
    if (r->d[a] > 0) return (face(g, a, r->lo[a] + 1) + r->delta - r->o[a]) * r->inv[a];
    return (face(g, a, r->hi[a]) - r->delta - r->o[a]) * r->inv[a];
}

/* Test the n objects of a list, each at most once per ray (the mailbox).
 * Nearest: the lowest t, ties to the lower number, as the brute-force loop;
 * any: the first hit. */
static int test_list(const int *list, long n, const prims *p, grid_ray *r,
                     void *ray, double tmin, int any, double *best_t, int best,
                     prim_counters *c)
{
    long k;
    for (k = 0; k < n; k++) {
        int i = list[k], *slot = &r->mail[i & (MAILBOX - 1)];
        double th;
        if (i == r->skip || *slot == i) continue;
        *slot = i;
        c->tests++;
        if (!p->hit(p->user, i, ray, tmin, *best_t, &th)) continue;
        if (any) return i;
        if (th < *best_t || (th == *best_t && (best < 0 || i < best)))
            *best_t = th, best = i;
    }
    return best;
}

static int test_cell(const grid *g, long cell, const prims *p, grid_ray *r,
                     void *ray, double tmin, int any, double *best_t, int best,
                     prim_counters *c)
{
    c->steps++;
    return test_list(g->list + g->start[cell], (long)(g->start[cell + 1] - g->start[cell]),
                     p, r, ray, tmin, any, best_t, best, c);
}

/* Every cell of the block lo..hi (inclusive, per axis). */
static int test_block(const grid *g, const int lo[3], const int hi[3], const prims *p,
                      grid_ray *r, void *ray, double tmin, int any, double *best_t,
                      int best, prim_counters *c)
{
    int i, j, k;
    for (k = lo[2]; k <= hi[2]; k++)
        for (j = lo[1]; j <= hi[1]; j++)
            for (i = lo[0]; i <= hi[0]; i++) {
                long cell = ((long)k * g->res[1] + j) * g->res[0] + i;
                best = test_cell(g, cell, p, r, ray, tmin, any, best_t, best, c);
                if (any && best >= 0) return best;
            }
    return best;
}

/* The walk: the cells at the start, then one step at a time. */
static int walk(const grid *g, const prims *p, grid_ray *r, void *ray, double tmin,
                int any, double *best_t, prim_counters *c)
{
    double lead[3], lag[3];
    int a, best = -1;
    for (a = 0; a < 3; a++) {
        double x = r->flat[a] ? r->o[a] : r->o[a] + r->t0 * r->d[a];
        r->lo[a] = cell_of(g, a, x - r->delta);
        r->hi[a] = cell_of(g, a, x + r->delta);
    }
    best = test_block(g, r->lo, r->hi, p, r, ray, tmin, any, best_t, best, c);
    for (a = 0; a < 3; a++) lead[a] = lead_time(g, r, a), lag[a] = lag_time(g, r, a);
    while (!(any && best >= 0)) {
        int al = lag[0] <= lag[1] ? (lag[0] <= lag[2] ? 0 : 2) : (lag[1] <= lag[2] ? 1 : 2);
        int as = lead[0] <= lead[1] ? (lead[0] <= lead[2] ? 0 : 2) : (lead[1] <= lead[2] ? 1 : 2);
        int lo[3], hi[3];
        if (lag[al] < lead[as]) {          /* a cell falls behind */
            if (r->d[al] > 0) r->lo[al]++;
            else r->hi[al]--;
            lag[al] = lag_time(g, r, al);
            continue;
        }
        if (!(lead[as] <= r->t1) || *best_t - r->toff + r->slack < lead[as]) break;
        if (r->d[as] > 0) r->hi[as]++;     /* step: a new slab of cells */
        else r->lo[as]--;
        memcpy(lo, r->lo, sizeof lo), memcpy(hi, r->hi, sizeof hi);
        lo[as] = hi[as] = r->d[as] > 0 ? r->hi[as] : r->lo[as];
        best = test_block(g, lo, hi, p, r, ray, tmin, any, best_t, best, c);
        lead[as] = lead_time(g, r, as), lag[as] = lag_time(g, r, as);
    }
    return best;
}

static int query(const grid *g, const prims *p, const double org[3], const double dir[3],
                 void *ray, int skip, double tmin, double *best_t, int any,
                 prim_counters *c)
{
    prim_counters none = {0, 0, 0};
    grid_ray r;
    double s = g ? g->scale : 0, dmax = 0;
    int a;
    if (!c) c = &none;
    c->rays++;
    if (!g || g->nall == 0) return -1;
    for (a = 0; a < 3; a++) {
        if (!isfinite(org[a]) || !isfinite(dir[a])) return -1;
        if (fabs(org[a]) > s) s = fabs(org[a]);
        if (fabs(dir[a]) > dmax) dmax = fabs(dir[a]);
    }
    if (!(tmin <= *best_t)) return -1;
    if (!setup_ray(g, org, dir, skip, tmin, *best_t, &r)) return -1;
    /* Every primitive, for rays out of range, and where the margin is wider
     * than half a cell (cells some 10^14 times smaller than the scene's
     * distance from the origin): the walk would visit blocks of cells and
     * gain nothing. */
    if (!(s <= FAST_MAX && dmax <= FAST_MAX && dmax >= FAST_MIN) || 2 * r.delta > g->narrow)
        return test_list(g->all, g->nall, p, &r, ray, tmin, any, best_t, -1, c);
    return walk(g, p, &r, ray, tmin, any, best_t, c);
}

int grid_nearest(const grid *g, const prims *p, const double org[3],
                 const double dir[3], void *ray, int skip, double tmin,
                 double *tmax, prim_counters *c)
{
    double best_t = *tmax;
    int i = query(g, p, org, dir, ray, skip, tmin, &best_t, 0, c);
    if (i >= 0) *tmax = best_t;
    return i;
}

int grid_any(const grid *g, const prims *p, const double org[3],
             const double dir[3], void *ray, int skip, double tmin,
             double tmax, prim_counters *c)
{
    return query(g, p, org, dir, ray, skip, tmin, &tmax, 1, c);
}

/* ---- build -------------------------------------------------------------- */

typedef struct {
    uint32_t cell;
    int prim;
} grid_ref;

typedef struct {
    grid_ref *refs;
    long n, cap;
    int failed;
} ref_list;

static void add_ref(ref_list *L, long cell, int prim)
{
    if (L->n == L->cap) {
        long cap = L->cap ? 2 * L->cap : 1024;
        grid_ref *r = realloc(L->refs, (size_t)cap * sizeof *r);
        if (!r) { L->failed = 1; return; }
        L->refs = r, L->cap = cap;
    }
    L->refs[L->n].cell = (uint32_t)cell, L->refs[L->n].prim = prim;
    L->n++;
}

/* DENSITY cells per object, as near to cubes as the box allows: the cube's
 * side from the volume (or area, or length) spanned by the axes along
 * which the box is not flat. */
static void choose_res(grid *g, long n)
{
    double ext[3], emax = 0, vol = 1, side;
    int a, dims = 0;
    for (a = 0; a < 3; a++) {
        ext[a] = g->hi[a] - g->lo[a];
        if (ext[a] > emax) emax = ext[a];
    }
    for (a = 0; a < 3; a++)
        if (ext[a] > 1e-3 * emax) vol *= ext[a], dims++;
    side = dims ? pow(vol / (DENSITY * (n > 0 ? n : 1)), 1.0 / dims) : 1;
    for (a = 0; a < 3; a++) {
        double r = ext[a] > 1e-3 * emax ? floor(ext[a] / side + 0.5) : 1;
        g->res[a] = r < 1 ? 1 : r > MAX_RES ? MAX_RES : (int)r;
    }
    while ((long)g->res[0] * g->res[1] * g->res[2] > MAX_CELLS)
        for (a = 0; a < 3; a++) g->res[a] = (g->res[a] + 1) / 2;
    for (a = 0; a < 3; a++) {
        g->w[a] = ext[a] > 0 ? ext[a] / g->res[a] : 1;
        g->inv_w[a] = 1 / g->w[a];
    }
}

/* How many cells the primitives' boxes overlap in all. */
static double box_refs(const grid *g, const prims *p)
{
    double sum = 0;
    long k;
    int a;
    for (k = 0; k < g->nall; k++) {
        double lo[3], hi[3], cells = 1;
        p->bounds(p->user, g->all[k], lo, hi);
        for (a = 0; a < 3; a++) cells *= cell_of(g, a, hi[a]) - cell_of(g, a, lo[a]) + 1;
        sum += cells;
    }
    return sum;
}

/* choose_res, then coarser while the references would exceed MAX_REFS per
 * object. */
static void resolution(grid *g, const prims *p)
{
    int a;
    choose_res(g, g->nall);
    while (box_refs(g, p) > MAX_REFS * (double)g->nall
           && (g->res[0] > 1 || g->res[1] > 1 || g->res[2] > 1))
        for (a = 0; a < 3; a++) {
            g->res[a] = (g->res[a] + 1) / 2;
            g->w[a] = (g->hi[a] > g->lo[a] ? g->hi[a] - g->lo[a] : 1) / g->res[a];
            g->inv_w[a] = 1 / g->w[a];
        }
}

/* Primitive i into every cell its box overlaps; with a clip callback, only
 * the cells its clipped part reaches (when it spans more than one). */
static void insert(const grid *g, const prims *p, int i, const double lo[3],
                   const double hi[3], ref_list *L)
{
    int c0[3], c1[3], x, y, z, a;
    for (a = 0; a < 3; a++) c0[a] = cell_of(g, a, lo[a]), c1[a] = cell_of(g, a, hi[a]);
    for (z = c0[2]; z <= c1[2]; z++)
        for (y = c0[1]; y <= c1[1]; y++)
            for (x = c0[0]; x <= c1[0]; x++) {
                int at[3];
                at[0] = x, at[1] = y, at[2] = z;
                if (p->clip && (c0[0] < c1[0] || c0[1] < c1[1] || c0[2] < c1[2])) {
                    double blo[3], bhi[3], clo[3], chi[3];
                    /* The first and last cells along an axis are grown to
                     * the primitive's own box: cell_of rounds, and faces
                     * lo + i w round too (the last can fall short of the
                     * scene box's far side), so a flat primitive lying on a
                     * face could otherwise be cut off from every cell. */
                    for (a = 0; a < 3; a++) {
                        blo[a] = face(g, a, at[a]);
                        bhi[a] = face(g, a, at[a] + 1);
                        if (at[a] == c0[a] && lo[a] < blo[a]) blo[a] = lo[a];
                        if (at[a] == c1[a] && hi[a] > bhi[a]) bhi[a] = hi[a];
                    }
                    if (!p->clip(p->user, i, blo, bhi, clo, chi)) continue;
                }
                add_ref(L, ((long)z * g->res[1] + y) * g->res[0] + x, i);
            }
}

/* The scene box, and the primitives that have a box. */
static long scene_box(grid *g, int n, const prims *p, int *all)
{
    long m = 0;
    int i, a;
    for (i = 0; i < n; i++) {
        double lo[3], hi[3];
        p->bounds(p->user, i, lo, hi);
        for (a = 0; a < 3; a++)
            if (!(lo[a] <= hi[a])) break;
        if (a < 3) continue;
        for (a = 0; a < 3; a++) {
            if (m == 0 || lo[a] < g->lo[a]) g->lo[a] = lo[a];
            if (m == 0 || hi[a] > g->hi[a]) g->hi[a] = hi[a];
        }
        all[m++] = i;
    }
    g->scale = g->ext = 0;
    for (a = 0; a < 3; a++) {
        if (fabs(g->lo[a]) > g->scale) g->scale = fabs(g->lo[a]);
        if (fabs(g->hi[a]) > g->scale) g->scale = fabs(g->hi[a]);
        if (0.5 * (g->hi[a] - g->lo[a]) > g->ext) g->ext = 0.5 * (g->hi[a] - g->lo[a]);
        g->mid[a] = 0.5 * g->lo[a] + 0.5 * g->hi[a];
    }
    g->ulps = PRIMS_HIT_ULPS * (p->eps > 0 ? p->eps : DBL_EPSILON);
    g->delta = RAY_EPS * g->ext + (WALK_ULPS * DBL_EPSILON + g->ulps) * g->scale;
    return m;
}

/* The references sorted by cell (a counting sort: stable, so each cell
 * lists its primitives in increasing order) into one block. */
static int fill(grid *g, const ref_list *L)
{
    size_t sb = ((size_t)g->ncells + 1) * sizeof(uint32_t), lb = (size_t)L->n * sizeof(int);
    long k, c;
    uint32_t sum = 0;
    g->block = calloc(1, sb + lb + 1);
    if (!g->block) return 0;
    g->start = g->block;
    g->list = (int *)((char *)g->block + sb);
    for (k = 0; k < L->n; k++) g->start[L->refs[k].cell + 1]++;
    for (c = 0; c <= g->ncells; c++) sum += g->start[c], g->start[c] = sum;
    for (k = 0; k < L->n; k++) g->list[g->start[L->refs[k].cell]++] = L->refs[k].prim;
    for (c = g->ncells; c > 0; c--) g->start[c] = g->start[c - 1];
    g->start[0] = 0;
    g->nrefs = L->n;
    g->bytes = sb + lb;
    return 1;
}

grid *grid_build(int n, const prims *p)
{
    clock_t start = clock();
    grid *g = calloc(1, sizeof *g);
    ref_list L = { NULL, 0, 0, 0 };
    long k, c;
    int a;
    if (!g) return NULL;
    if (n < 0) n = 0;
    g->all = malloc(((size_t)n + 1) * sizeof(int));
    if (!g->all) return free(g), NULL;
    g->nall = scene_box(g, n, p, g->all);
    resolution(g, p);
    g->ncells = (long)g->res[0] * g->res[1] * g->res[2];
    g->narrow = HUGE_VAL;
    for (a = 0; a < 3; a++)
        if (g->res[a] > 1 && g->w[a] < g->narrow) g->narrow = g->w[a];
    for (k = 0; k < g->nall && !L.failed; k++) {
        double lo[3], hi[3];
        p->bounds(p->user, g->all[k], lo, hi);
        insert(g, p, g->all[k], lo, hi, &L);
    }
    if (L.failed || !fill(g, &L)) {
        free(L.refs), grid_free(g);
        return NULL;
    }
    free(L.refs);
    g->info.cells = g->ncells;
    for (a = 0; a < 3; a++) g->info.res[a] = g->res[a];
    for (c = 0; c < g->ncells; c++) g->info.empty_cells += g->start[c] == g->start[c + 1];
    g->info.prim_refs = g->nrefs;
    g->info.bytes = g->bytes;
    g->info.build_seconds = (double)(clock() - start) / CLOCKS_PER_SEC;
    return g;
}

void grid_free(grid *g)
{
    if (g) free(g->block), free(g->all), free(g);
}

void grid_describe(const grid *g, grid_info *info)
{
    memset(info, 0, sizeof *info);
    if (!g) return;
    *info = g->info;
    info->block = g->block;
}

long grid_planes(const grid *g, int *axis, double *pos, long max)
{
    long k = 0;
    int a, i;
    for (a = 0; a < 3; a++)
        for (i = 0; i <= g->res[a]; i++) {
            if (k < max) axis[k] = a, pos[k] = face(g, a, i);
            k++;
        }
    return k;
}

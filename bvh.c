/* bvh.c - a bounding volume hierarchy for ray tracing over primitives it
 * knows only through the callbacks of prims.h.  bvh.h maps the lecture's
 * slide, BVH_Intersect(ray, node), to the functions below.
 *
 * Traversal: depth first over four-way nodes (collapsed from the binary
 * tree the build makes), the nearest child first, the farther ones on a
 * stack, each dropped when the ray enters its box beyond the nearest hit
 * found meanwhile.  Each primitive sits in exactly one leaf, so unlike the
 * kd-tree no mailbox is needed.
 *
 * Build, two ways (bvh_build's method):
 *   BVH_SAH     the surface area heuristic over binned centroids (Wald 2007,
 *               "On fast construction of SAH-based bounding volume
 *               hierarchies"): each node's primitives are counted into BINS
 *               slabs of their centroids along each axis, and the planes
 *               between slabs are priced by one sweep from each end.
 *               O(N) per level, O(N log N) in all.
 *   BVH_MEDIAN  half the primitives on each side, by their centroids along
 *               the longest axis (the lecture's "mediana"); leaves of at most
 *               MEDIAN_LEAF primitives.
 * bvh_refit keeps the tree and recomputes its boxes bottom-up.
 */
#include "bvh.h"
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* The SAH cost model (Goldsmith & Salmon 1987; MacDonald & Booth 1990):
 *     cost(split) = COST_STEP + COST_TEST * (A(L) nL + A(R) nR) / A(node)
 *     cost(leaf)  = COST_TEST * n
 * A is surface area: the chance that a ray through a box also passes
 * through a box inside it is the ratio of their areas.  COST_STEP is one
 * node visited (two boxes tested), COST_TEST one call of the hit callback.
 * A node splits while splitting is cheaper, up to MAX_LEAF primitives,
 * beyond which it always splits if it can.  The leaf size is thus the
 * model's choice: 1 to 3 primitives on meshes (1.1 tests per ray on the
 * 100k sphere).  COST_TEST 0.5, 1.5 and 2, and MAX_LEAF 4, were measured
 * against 1 and 8 on that sphere: all within the noise (2% primary, 10%
 * random rays), 0.5 testing half again as many triangles. */
#define COST_STEP 1.0
#define COST_TEST 1.0
#define MAX_LEAF 8

/* Wald 2007 bins centroids into 16 or 32 slabs per axis and finds the tree
 * nearly as good as one from every candidate plane.  16 keeps a bin's
 * record and the sweep in the first-level cache. */
#define BINS 16

/* The median build has no cost model; its leaves stop at this size. */
#define MEDIAN_LEAF 2

/* The SAH build splits by count (always halving) below this depth, so that
 * the depth, and the traversal's stack, stay under STACK_SIZE whatever the
 * input: 64 levels of SAH, then at most 31 more. */
#define SAH_DEPTH 64
#define STACK_SIZE 96

/* The frame.  Boxes are floats relative to a centre c near the middle of
 * the scene box (prims_frame, prims.h), not to the origin, so that a float
 * step is 2^-23 of the scene's size wherever the scene lies; they are rounded
 * outwards, so each holds its primitives' double boxes whole (give or take
 * the rounding of x - c in double, 2^-53 ext).
 *
 * The margin.  The walk treats every box as grown on every side by
 *     delta = BVH_EPS * ext + ulps * s,
 * ext the largest |coordinate| of the scene box in the frame, s the largest
 * in the caller's.  The hit callback's point may lie outside its
 * primitive's box by PRIMS_HIT_REL of the box's longest side (at most
 * 2 ext) plus PRIMS_HIT_ULPS eps s (the contract of prims.h; ulps is
 * PRIMS_HIT_ULPS eps).  The slab test runs in float in the frame, from an
 * origin o at most D from the frame's centre: b - o rounds by 2^-24 of
 * |b - o| <= D + ext, d to float, 1/d and the product by 2^-24 each, so a
 * computed crossing may be off by 4 * 2^-24 (D + ext) in space.  For
 * D <= 2 ext that is 7.2e-7 ext, with the callback's 2 * 2^-24 ext
 * 8.3e-7 ext, which BVH_EPS = 2^-20 = 9.5e-7 covers; a farther origin (a
 * camera looking at the scene) adds BVH_EPS D / 2 to the margin for the
 * rest, and one farther than FAR_MOVE ext is moved along the ray to where
 * it enters the grown scene box (setup_ray), and is within 2 ext again.  The origin shifted by delta is
 * rounded away from the box (see setup_ray), so its own rounding only adds
 * margin.  The origin moved along the ray, o - c + t0 d, is summed exactly
 * and rounded once (prims_along, prims.h), so it lies on the ray to within
 * a rounding of a number of the scene's size; the walk's t is then the
 * caller's t less t0, taken in double (exact when t0 is more than half of it) before
 * it is rounded up to a float.
 *
 * The slack.  The contract also lets the callback's t err along the ray by
 * ulps m / max|d|, m the larger of s and the origin's largest |coordinate|
 * (a ray from 10^13 away has t of 10^13, rounded by 10^-3).  For an origin
 * moved from far away the walk takes the ray from tmin - slack, and leaves
 * a box out only when the ray enters it more than slack beyond the best hit
 * so far: a box now and then just behind the hit, not a margin across every
 * box.  A nearer origin's ulps m goes into the margin instead (setup_ray),
 * where it is tiny: a slack on every ray made the 100k sphere's primary
 * rays a tenth slower.
 *
 * The float test is valid while the numbers stay well inside the float
 * range (FAST_MAX below); other rays are answered by testing every
 * primitive. */
#define BVH_EPS (1.0 / 1048576.0)
#define FAR_MOVE 64
#define FAST_MAX 0x1p60
#define FAST_MIN 0x1p-60

/* ---- nodes ------------------------------------------------------------ */

/* The build makes a binary tree of 32-byte nodes (bvh_node: a box as six
 * floats, an index and a count); the walk reads a tree of four-way nodes
 * made from it by collapsing (bvh_node4): each node holds the boxes of up to
 * four children, stored axis by axis so that one loop over the four lanes
 * tests all of them, and the compiler can run it as one vector operation
 * per line.  128 bytes a node, two cache lines: box[lo/hi][axis][child] in
 * 96 bytes, then each child's index and count.  A child with count > 0 is a
 * leaf of `count` primitives listed from `index` in the tree's primitive
 * list; count 0 and index > 0 is the four-way node `index` (the root, node
 * 0, is no one's child); count 0 and index 0 is an empty lane, its box
 * inside out (lo = +inf, hi = -inf) so that no ray enters it.  Measured on
 * a 100k-triangle sphere, one thread, Embree's rays (bench/raybench.c
 * accel): the binary walk took 8.2 steps a primary ray and ran 6.9 Mrays/s
 * (random rays: 9.1 steps, 1.7 Mrays/s); the four-way walk 5.0 steps and
 * 12.5 Mrays/s (5.4 steps, 3.2 Mrays/s).  Leaves are left as the binary
 * build made them. */
typedef struct {
    float box[2][3];
    uint32_t index, count;
} bvh_node;

typedef struct {
    float box[2][3][4];
    uint32_t index[4], count[4];
} bvh_node4;

typedef char bvh_node_must_be_32_bytes[sizeof(bvh_node) == 32 ? 1 : -1];
typedef char bvh_node4_must_be_128_bytes[sizeof(bvh_node4) == 128 ? 1 : -1];

struct bvh {
    bvh_node4 *nodes;  /* nodes[0] the root; nnodes of them, then the list */
    int *prims;        /* the leaves' primitive numbers */
    long nnodes, nprims;
    void *block;       /* the allocation behind nodes and prims */
    size_t bytes;
    double c[3];       /* the frame: boxes are relative to c (see BVH_EPS) */
    double lo[3], hi[3];  /* the root's boxes together, in the frame */
    double ext;        /* largest |coordinate| of the root's boxes in the frame */
    double scale;      /* largest |coordinate| of the root's boxes in the caller's coordinates */
    double ulps;       /* PRIMS_HIT_ULPS eps (see BVH_EPS) */
    double delta;      /* the margin (see BVH_EPS) */
    double slack_ulps; /* ulps, and 2^-21 more for a float 1/d (setup_ray) */
    bvh_info info;
};

/* ---- floats rounded one way --------------------------------------------- */

/* A float at most x, and one at least x: x moved by 2^-23 of itself (more
 * than a float step) before rounding to nearest, so the rounding cannot
 * cross it.  A step or two looser than nextafterf, without a call. */
static float down(double x)
{
    float f = (float)x;
    return (double)f > x ? (float)(x - fabs(x) * 0x1p-23) : f;
}

static float up(double x)
{
    float f = (float)x;
    return (double)f < x ? (float)(x + fabs(x) * 0x1p-23) : f;
}

/* ---- traversal ---------------------------------------------------------- */

/* The ray as the slab test needs it, in the frame, its origin moved by
 * toff along it when it started far away (see setup_ray): the walk's t is
 * the caller's t - toff.  For each axis, neg picks the box
 * corner the ray meets first (from the sign bit, so -0 counts as negative
 * like its 1/d = -inf).  on and of are the origin moved by delta: the near
 * plane of a box grown by delta is at b - delta (b + delta for neg), and
 * b - delta - o = b - (o + delta), so the test reads the plain box with a
 * moved origin; of likewise for the far plane.  A zero component gives
 * inv = +-inf: the ray is inside that slab for every t or for none; where
 * 0 * inf makes NaN, the comparisons in enter read it as "inside". */
typedef struct {
    float on[3], of[3], inv[3];
    int neg[3];
    float tmin;
    double toff;       /* how far along the ray the origin was moved */
    double slack;      /* how far along the ray a hit's t may err (see BVH_EPS) */
    int skip;
} bvh_ray;

/* A child to visit: a node (count 0) or a leaf, and the t where the ray
 * enters its box. */
typedef struct {
    uint32_t index, count;
    float entry;
} bvh_todo;

/* The ray set up for the float slab test: 1, or 0 when its numbers leave
 * the test's range (see BVH_EPS), or -1 when it can hit nothing: NaN or
 * infinite input, or a ray from far away that misses the scene box.  The
 * origin goes into the frame; one farther than FAR_MOVE ext from its
 * centre is moved along the ray to where the ray enters the grown scene
 * box (the slab test of Kay and Kajiya 1986, in double), so that the float
 * test sees numbers of the scene's size: from 1e13 away a float would hold
 * the origin only to 1e6. */
static int setup_ray(const bvh *t, const double org[3], const double dir[3],
                     int skip, double tmin, double tmax, bvh_ray *r)
{
    double scale = t->scale, dmax = 0, delta = t->delta, o[3], far = 0;
    int a;
    for (a = 0; a < 3; a++) {
        double m = fabs(org[a]), d = fabs(dir[a]);
        if (!(m <= DBL_MAX && d <= DBL_MAX)) return -1;
        if (m > scale) scale = m;
        if (d > dmax) dmax = d;
        o[a] = org[a] - t->c[a];
        if (fabs(o[a]) > far) far = fabs(o[a]);
        r->inv[a] = 1.0f / (float)dir[a];    /* +-inf for +-0 and tiny d */
    }
    r->skip = skip;
    if (!(scale <= FAST_MAX && scale >= FAST_MIN && dmax <= FAST_MAX && dmax >= FAST_MIN))
        return 0;
    r->slack = r->toff = 0;
    if (!(far > FAR_MOVE * t->ext)) {
        /* The rounding along the ray (ulps m, prims.h) taken across it
         * instead: a margin grown by ulps m moves every box's entry and
         * exit by at least ulps m / max|d|, all that a slack would allow.
         * m exceeds the scene's coordinates by at most 64 ext here, so
         * this at most doubles the margin's own ulps term, where a slack
         * slows the walk of every ray (see BVH_EPS). */
        delta += t->ulps * scale;
        if (far > 2 * t->ext) delta += 0.5 * BVH_EPS * far;   /* a camera looking on */
    } else {
        /* 1 / max|d| is the least |1/d|, rounded twice to float:
         * slack_ulps allows for that (no division of its own) */
        float least = fabsf(r->inv[0]);
        double t0, t1;
        double grow = delta + t->ulps * scale;   /* o is rounded by a few eps m */
        for (a = 1; a < 3; a++) least = fabsf(r->inv[a]) < least ? fabsf(r->inv[a]) : least;
        r->slack = t->slack_ulps * scale * least;
        tmin -= r->slack;
        t0 = tmin, t1 = tmax + r->slack;
        for (a = 0; a < 3; a++) {
            double lo = t->lo[a] - grow - o[a], hi = t->hi[a] + grow - o[a], inv, ta, tb;
            if (dir[a] == 0) {
                if (!(lo <= 0 && hi >= 0)) return -1;
                continue;
            }
            inv = 1 / dir[a];
            ta = lo * inv, tb = hi * inv;
            if (ta > tb) inv = ta, ta = tb, tb = inv;
            if (ta > t0) t0 = ta;
            if (tb < t1) t1 = tb;
        }
        if (!(t0 <= t1)) return -1;
        r->toff = t0;
        for (a = 0; a < 3; a++) o[a] = prims_along(org[a], t->c[a], t0, dir[a]);
    }
    for (a = 0; a < 3; a++) {
        int neg = signbit(dir[a]) != 0;
        r->neg[a] = neg;
        r->on[a] = neg ? down(o[a] - delta) : up(o[a] + delta);
        r->of[a] = neg ? up(o[a] + delta) : down(o[a] - delta);
    }
    r->tmin = down(tmin - r->toff);
    return 1;
}

/* The latest t of the walk's (see setup_ray), rounded up to a float, at
 * which the point of a hit at the caller's t may lie. */
static float walk_t(const bvh_ray *r, double t)
{
    return up(t - r->toff + r->slack);
}

/* Intersect(ray, object) for each primitive of a leaf.  Nearest: keep the
 * lowest t, and on equal t the lower primitive number, as the brute-force
 * loop would; the callback gets tmax = the best t so far, inclusive, so
 * that it reports such ties.  Any-hit: the first hit will do. */
static inline int test_leaf(const bvh *t, uint32_t first, uint32_t count, const prims *p,
                            const bvh_ray *r, void *ray, double tmin, int any,
                            double *best_t, int best, unsigned long long *tests)
{
    const int *list = t->prims + first;
    uint32_t k;
    for (k = 0; k < count; k++) {
        int i = list[k];
        double th;
        if (i == r->skip) continue;
        ++*tests;
        if (!p->hit(p->user, i, ray, tmin, *best_t, &th)) continue;
        if (any) return i;
        if (th < *best_t || (th == *best_t && (best < 0 || i < best)))
            *best_t = th, best = i;
    }
    return best;
}

/* Intersect_P(ray, box) for the four children of node nd at once: the
 * slab test (Kay & Kajiya 1986) of each box grown by delta, between tmin
 * and tmax, written so that NaN never excludes and so that the compiler
 * can run the four lanes as one vector operation per line.  The children
 * the ray enters go to out[], nearer first (on equal entries, the earlier
 * lane first), with the t where it enters; returns how many, 0 to 4.  An
 * empty lane's inside-out box is never entered. */
static inline int children(const bvh_node4 *nd, const bvh_ray *r, float tmax,
                           bvh_todo out[4])
{
    const float *nx = nd->box[r->neg[0]][0], *fx = nd->box[1 - r->neg[0]][0];
    const float *ny = nd->box[r->neg[1]][1], *fy = nd->box[1 - r->neg[1]][1];
    const float *nz = nd->box[r->neg[2]][2], *fz = nd->box[1 - r->neg[2]][2];
    float t0[4], t1[4];
    unsigned mask;
    int k, j, n = 0;
    for (k = 0; k < 4; k++) {
        float ax = (nx[k] - r->on[0]) * r->inv[0], bx = (fx[k] - r->of[0]) * r->inv[0];
        float ay = (ny[k] - r->on[1]) * r->inv[1], by = (fy[k] - r->of[1]) * r->inv[1];
        float az = (nz[k] - r->on[2]) * r->inv[2], bz = (fz[k] - r->of[2]) * r->inv[2];
        float lo = r->tmin, hi = tmax;
        lo = ax > lo ? ax : lo, lo = ay > lo ? ay : lo, lo = az > lo ? az : lo;
        hi = bx < hi ? bx : hi, hi = by < hi ? by : hi, hi = bz < hi ? bz : hi;
        t0[k] = lo, t1[k] = hi;
    }
    mask = (unsigned)(t0[0] <= t1[0]) | (unsigned)(t0[1] <= t1[1]) << 1
           | (unsigned)(t0[2] <= t1[2]) << 2 | (unsigned)(t0[3] <= t1[3]) << 3;
    for (k = 0; mask; k++, mask >>= 1) {
        if (!(mask & 1)) continue;
        j = n++;
        if (j > 0 && t0[k] < out[j - 1].entry) {   /* insertion sort, rarely past one */
            do out[j] = out[j - 1];
            while (--j > 0 && t0[k] < out[j - 1].entry);
        }
        out[j].index = nd->index[k], out[j].count = nd->count[k], out[j].entry = t0[k];
    }
    return n;
}

/* The slide's BVH_Intersect(ray, node), recursive.  The caller has already
 * found that the ray enters the node's box (Intersect_P): children() for
 * every node but the root, whose box is the whole scene.  A child is
 * visited only if the ray still enters it no later than the best hit found
 * in the nearer ones; any = 1 stops at the first hit. */
static int bvh_intersect(const bvh *t, const prims *p, const bvh_ray *r,
                         void *ray, double tmin, int any, bvh_todo node,
                         double *best_t, int best, prim_counters *c)
{
    bvh_todo child[4];
    int k, n;
    c->steps++;
    if (node.count)
        return test_leaf(t, node.index, node.count, p, r, ray, tmin, any, best_t, best,
                         &c->tests);
    n = children(&t->nodes[node.index], r, walk_t(r, *best_t), child);
    for (k = 0; k < n; k++) {
        if (k > 0 && !(child[k].entry <= walk_t(r, *best_t))) break;
        best = bvh_intersect(t, p, r, ray, tmin, any, child[k], best_t, best, c);
        if (any && best >= 0) break;
    }
    return best;
}

/* The walk behind bvh_nearest (any = 0) and bvh_any (any = 1): the fast
 * path, bvh_intersect with the recursion turned into a loop, the farther
 * children waiting on a stack with the t where the ray enters them.  Same
 * nodes, same order, same tests. */
static int walk(const bvh *t, const prims *p, const bvh_ray *r, void *ray,
                double tmin, int any, double *best_t, prim_counters *c)
{
    bvh_todo stack[3 * STACK_SIZE], node, child[4];
    float tmax = walk_t(r, *best_t);
    unsigned long long steps = 0, tests = 0;
    int n = 0, best = -1;
    node.index = 0, node.count = 0;
    for (;;) {
        steps++;
        if (node.count == 0) {
            int k = children(&t->nodes[node.index], r, tmax, child);
            while (k > 1) stack[n++] = child[--k];
            if (k > 0) {
                node = child[0];
                continue;
            }
        } else {
            int was = best;
            best = test_leaf(t, node.index, node.count, p, r, ray, tmin, any, best_t, best,
                             &tests);
            if (best != was) {
                if (any) break;
                tmax = walk_t(r, *best_t);
            }
        }
        while (n > 0 && !(stack[n - 1].entry <= tmax)) n--;
        if (n == 0) break;
        node = stack[--n];
    }
    if (c) c->steps += steps, c->tests += tests;
    return best;
}

/* The query shared by the three entry points. */
static int query(const bvh *t, const prims *p, const double org[3],
                 const double dir[3], void *ray, int skip, double tmin,
                 double *best_t, int any, int recursive, prim_counters *c)
{
    bvh_ray r;
    int a;
    if (c) c->rays++;
    if (!t || t->nnodes == 0 || !(tmin <= *best_t)) return -1;
    a = setup_ray(t, org, dir, skip, tmin, *best_t, &r);
    if (a < 0) return -1;
    if (a == 0) {
        /* out of the float test's range (see BVH_EPS): every primitive */
        unsigned long long tests = 0;
        a = test_leaf(t, 0, (uint32_t)t->nprims, p, &r, ray, tmin, any, best_t, -1, &tests);
        if (c) c->tests += tests;
        return a;
    }
    if (recursive) {
        prim_counters none = {0, 0, 0};
        bvh_todo root = {0, 0, 0};
        return bvh_intersect(t, p, &r, ray, tmin, any, root, best_t, -1, c ? c : &none);
    }
    return walk(t, p, &r, ray, tmin, any, best_t, c);
}

int bvh_nearest(const bvh *t, const prims *p, const double org[3],
                const double dir[3], void *ray, int skip, double tmin,
                double *tmax, prim_counters *c)
{
    double best_t = *tmax;
    int i = query(t, p, org, dir, ray, skip, tmin, &best_t, 0, 0, c);
    if (i >= 0) *tmax = best_t;
    return i;
}

int bvh_any(const bvh *t, const prims *p, const double org[3],
            const double dir[3], void *ray, int skip, double tmin, double tmax,
            prim_counters *c)
{
    return query(t, p, org, dir, ray, skip, tmin, &tmax, 1, 0, c);
}

int bvh_intersect_recursive(const bvh *t, const prims *p, const double org[3],
                            const double dir[3], void *ray, int skip,
                            double tmin, double *tmax, int any,
                            prim_counters *c)
{
    double best_t = *tmax;
    int i = query(t, p, org, dir, ray, skip, tmin, &best_t, any, 1, c);
    if (i >= 0 && !any) *tmax = best_t;
    return i;
}

/* ---- boxes -------------------------------------------------------------- */

/* A box as the build keeps it: four lanes, the fourth a copy of the
 * third, so that the compiler can grow one with a single vector minimum and
 * maximum. */
typedef struct {
    float lo[4], hi[4];
} bvh_box;

static void box_empty(bvh_box *b)
{
    int a;
    for (a = 0; a < 4; a++) b->lo[a] = HUGE_VALF, b->hi[a] = -HUGE_VALF;
}

static void box_grow(bvh_box *b, const bvh_box *c)
{
    int a;
    for (a = 0; a < 4; a++) {
        b->lo[a] = c->lo[a] < b->lo[a] ? c->lo[a] : b->lo[a];
        b->hi[a] = c->hi[a] > b->hi[a] ? c->hi[a] : b->hi[a];
    }
}

static double box_area(const bvh_box *b)
{
    double dx = (double)b->hi[0] - b->lo[0];
    double dy = (double)b->hi[1] - b->lo[1];
    double dz = (double)b->hi[2] - b->lo[2];
    if (!(dx >= 0)) return 0;   /* empty */
    return 2 * (dx * dy + dy * dz + dz * dx);
}

/* Primitive i's box from the callback, in the frame centred on c, rounded
 * outwards to floats: it holds the double box whole.  0 for NaN or
 * lo > hi. */
static int prim_box(const prims *p, int i, const double c[3], bvh_box *b)
{
    double lo[3], hi[3];
    int a;
    p->bounds(p->user, i, lo, hi);
    for (a = 0; a < 3; a++) {
        if (!(lo[a] <= hi[a])) return 0;
        b->lo[a] = down(lo[a] - c[a]);
        b->hi[a] = up(hi[a] - c[a]);
    }
    b->lo[3] = b->lo[2], b->hi[3] = b->hi[2];
    return 1;
}

static void node_box(bvh_node *nd, const bvh_box *b)
{
    memcpy(nd->box[0], b->lo, sizeof nd->box[0]);
    memcpy(nd->box[1], b->hi, sizeof nd->box[1]);
}

static void node_to_box(const bvh_node *nd, bvh_box *b)
{
    memcpy(b->lo, nd->box[0], sizeof nd->box[0]);
    memcpy(b->hi, nd->box[1], sizeof nd->box[1]);
    b->lo[3] = b->lo[2], b->hi[3] = b->hi[2];
}

/* ---- the builder -------------------------------------------------------- */

/* A primitive as the build moves it: its box and its number, 32 bytes.
 * The build reorders these records themselves, not indices to them, so
 * that every pass over a node's primitives reads memory in order (Wald
 * 2007 does the same).  Centroids are used doubled, lo + hi, which orders
 * and bins them alike without a multiplication. */
typedef struct {
    float lo[3];
    int id;
    float hi[3];
    float pad;
} bvh_ref;

typedef struct {
    const prims *p;
    int method;
    double c[3];          /* the frame (see BVH_EPS) */
    bvh_ref *ref;
    bvh_node *nodes;
    long nnodes;
    long max_depth, leaves;
} bvh_builder;

static float centroid2(const bvh_ref *r, int a) { return r->lo[a] + r->hi[a]; }

/* The record's box as a four-lane box. */
static void ref_box(const bvh_ref *r, bvh_box *b)
{
    b->lo[0] = r->lo[0], b->lo[1] = r->lo[1], b->lo[2] = b->lo[3] = r->lo[2];
    b->hi[0] = r->hi[0], b->hi[1] = r->hi[1], b->hi[2] = b->hi[3] = r->hi[2];
}

static inline void grow_ref(bvh_box *box, bvh_box *cbox, const bvh_ref *r)
{
    bvh_box rb, c;
    int a;
    ref_box(r, &rb);
    for (a = 0; a < 4; a++) c.lo[a] = c.hi[a] = rb.lo[a] + rb.hi[a];
    box_grow(box, &rb);
    box_grow(cbox, &c);
}

/* The box of primitives first..first+n-1, and the box of their doubled
 * centroids. */
static void bounds_of(const bvh_builder *b, long first, long n, bvh_box *box,
                      bvh_box *cbox)
{
    long k;
    box_empty(box), box_empty(cbox);
    for (k = first; k < first + n; k++) grow_ref(box, cbox, &b->ref[k]);
}

/* A node of n primitives gets BINS bins per axis, or n when fewer: a
 * small node's sweep then costs in proportion to it. */
static int bins_for(long n) { return n < BINS ? (int)n : BINS; }

/* The bin of doubled centroid c.  Clamped before it is converted: a
 * centroid box thinner than a float step makes k1 infinite, and x infinite
 * or NaN (0 times infinity), which no int can hold.  The two clamps are
 * written as a max and a min (a NaN fails the first and becomes 0) so that
 * compilers make them two instructions, not two branches. */
static int bin_of(float c, float lo, float k1, int nb)
{
    float x = (c - lo) * k1, last = (float)(nb - 1);
    x = x > 0 ? x : 0;
    x = x < last ? x : last;
    return (int)x;
}

/* nb slabs per axis of the centroid box: 1/width, or 0 for a flat axis
 * (everything in bin 0). */
static float bin_scale(const bvh_box *cbox, int a, int nb)
{
    double ext = (double)cbox->hi[a] - cbox->lo[a];
    return ext > 0 ? (float)(nb * (1 - 1e-6) / ext) : 0;
}

/* Two primitives, the most common node near the leaves: one way to part
 * them, one in each of two bins, on the first axis that has bins (on any
 * other the same two boxes would cost the same, and best_bin_split keeps
 * the first); priced as best_bin_split prices it, to the bit. */
static double split_two(const bvh_builder *b, long first, const bvh_box *cbox,
                        double area, int *axis, int *split)
{
    const bvh_ref *r = &b->ref[first];
    bvh_box left, right;
    double cost;
    int a;
    for (a = 0; a < 3; a++)
        if (bin_scale(cbox, a, 2) != 0) break;
    if (a == 3) return HUGE_VAL;
    ref_box(&r[centroid2(&r[0], a) > centroid2(&r[1], a)], &left);
    ref_box(&r[centroid2(&r[0], a) <= centroid2(&r[1], a)], &right);
    *axis = a, *split = 1;
    cost = COST_STEP + COST_TEST * (box_area(&left) * 1 + box_area(&right) * 1) / area;
    return cost < HUGE_VAL ? cost : HUGE_VAL;   /* a node of no area: no plane */
}

/* Wald 2007: one pass puts every primitive in a bin on each axis; then a
 * sweep from each end prices the planes between bins.  Returns the
 * best cost, its axis and the number of bins left of it; HUGE_VAL when no
 * plane parts the primitives. */
static double best_bin_split(const bvh_builder *b, long first, long n,
                             const bvh_box *cbox, double area, int *axis,
                             int *split)
{
    bvh_box bin[3][BINS], acc;
    long count[3][BINS], k;
    float k1[4] = { 0, 0, 0, 0 }, lo[4] = { 0, 0, 0, 0 };  /* lane 3 (a copy of 2) to bin 0, unused */
    double best = HUGE_VAL, cost;   /* best: the least area-weighted count; the cost, once */
    int a, i, nb = bins_for(n);
    if (n == 2) return split_two(b, first, cbox, area, axis, split);
    for (a = 0; a < 3; a++) {
        k1[a] = bin_scale(cbox, a, nb), lo[a] = cbox->lo[a];
        for (i = 0; i < nb; i++) box_empty(&bin[a][i]), count[a][i] = 0;
    }
    for (k = first; k < first + n; k++) {
        bvh_box rb;
        int j[4];
        ref_box(&b->ref[k], &rb);
        for (a = 0; a < 4; a++)   /* all axes at once: a loop compilers vectorise */
            j[a] = bin_of(rb.lo[a] + rb.hi[a], lo[a], k1[a], nb);
        box_grow(&bin[0][j[0]], &rb), count[0][j[0]]++;
        box_grow(&bin[1][j[1]], &rb), count[1][j[1]]++;
        box_grow(&bin[2][j[2]], &rb), count[2][j[2]]++;
    }
    for (a = 0; a < 3; a++) {
        double right_area[BINS];
        long right_n[BINS], nl = 0;
        if (k1[a] == 0) continue;
        /* A plane just right of an empty bin parts the primitives as the
         * plane before it does, at the same cost; the sweeps skip it (and
         * an empty bin's box would add nothing). */
        box_empty(&acc);
        for (i = nb - 1, k = 0; i > 0; i--) {     /* right of plane i: bins i.. */
            if (count[a][i]) box_grow(&acc, &bin[a][i]), k += count[a][i];
            right_n[i] = k;
            if (count[a][i - 1]) right_area[i] = box_area(&acc);
        }
        box_empty(&acc);
        for (i = 1; i < nb; i++) {                /* plane i: bins 0..i-1 left */
            double sum;
            if (!count[a][i - 1]) continue;
            box_grow(&acc, &bin[a][i - 1]);
            nl += count[a][i - 1];
            if (right_n[i] == 0) continue;
            sum = box_area(&acc) * nl + right_area[i] * right_n[i];
            if (sum < best) best = sum, *axis = a, *split = i;
        }
    }
    cost = COST_STEP + COST_TEST * best / area;
    return cost < HUGE_VAL ? cost : HUGE_VAL;   /* NaN, a node of no area: no plane */
}

/* The two sides of a split: their boxes and centroid boxes. */
typedef struct {
    bvh_box box[2], cbox[2];
} bvh_sides;

/* Reorders the node's primitives so that those left of the plane come
 * first, noting each side's boxes on the way; returns how many go left. */
static long partition_bins(bvh_builder *b, long first, long n, const bvh_box *cbox,
                           int axis, int split, bvh_sides *sd)
{
    int nb = bins_for(n);
    float lo = cbox->lo[axis], k1 = bin_scale(cbox, axis, nb);
    long i = first, j = first + n - 1;
    box_empty(&sd->box[0]), box_empty(&sd->cbox[0]);
    box_empty(&sd->box[1]), box_empty(&sd->cbox[1]);
    while (i <= j) {
        bvh_ref *r = &b->ref[i];
        if (bin_of(centroid2(r, axis), lo, k1, nb) < split) {
            grow_ref(&sd->box[0], &sd->cbox[0], r);
            i++;
        } else {
            bvh_ref tmp = *r;
            *r = b->ref[j], b->ref[j] = tmp;
            grow_ref(&sd->box[1], &sd->cbox[1], &b->ref[j]);
            j--;
        }
    }
    return i - first;
}

/* Centroid order along an axis, ties by primitive number: a total order, so
 * the median build is deterministic. */
static int before(const bvh_ref *p, const bvh_ref *q, int axis)
{
    float cp = centroid2(p, axis), cq = centroid2(q, axis);
    return cp < cq || (cp == cq && p->id < q->id);
}

static void swap_refs(bvh_ref *x, long i, long j)
{
    bvh_ref tmp = x[i];
    x[i] = x[j], x[j] = tmp;
}

/* Hoare's selection (quickselect): the node's primitives reordered so that
 * the m-th smallest is at first + m, smaller ones before it and larger
 * after; expected O(n).  The pivot is the middle element, swapped to the
 * end (Lomuto's partition). */
static void select_nth(bvh_builder *b, long first, long n, long m, int axis)
{
    long lo = first, hi = first + n - 1, want = first + m;
    bvh_ref *x = b->ref;
    while (lo < hi) {
        long k, store = lo;
        swap_refs(x, lo + (hi - lo) / 2, hi);
        for (k = lo; k < hi; k++)
            if (before(&x[k], &x[hi], axis)) swap_refs(x, k, store++);
        swap_refs(x, hi, store);
        if (store == want) return;
        if (store < want) lo = store + 1;
        else hi = store - 1;
    }
}

static int longest_axis(const bvh_box *b)
{
    double dx = (double)b->hi[0] - b->lo[0], dy = (double)b->hi[1] - b->lo[1];
    double dz = (double)b->hi[2] - b->lo[2];
    return dx >= dy ? (dx >= dz ? 0 : 2) : (dy >= dz ? 1 : 2);
}

/* Half the primitives each side, by centroid along the axis; the sides'
 * boxes measured afresh. */
static long split_median(bvh_builder *b, long first, long n, int axis, bvh_sides *sd)
{
    select_nth(b, first, n, n / 2, axis);
    bounds_of(b, first, n / 2, &sd->box[0], &sd->cbox[0]);
    bounds_of(b, first + n / 2, n - n / 2, &sd->box[1], &sd->cbox[1]);
    return n / 2;
}

/* How many primitives of the node go left (and the sides' boxes in sd);
 * 0 for a leaf. */
static long choose_split(bvh_builder *b, long first, long n, int depth,
                         const bvh_box *box, const bvh_box *cbox, bvh_sides *sd)
{
    int axis = longest_axis(cbox), split = 0;
    double cost;
    if (n <= 1 || !((double)cbox->hi[axis] - cbox->lo[axis] > 0))
        return 0;   /* one primitive, or every centroid at one point */
    if (b->method == BVH_MEDIAN || depth >= SAH_DEPTH) {
        if (b->method == BVH_MEDIAN && n <= MEDIAN_LEAF) return 0;
        return split_median(b, first, n, axis, sd);
    }
    cost = best_bin_split(b, first, n, cbox, box_area(box), &axis, &split);
    if (cost == HUGE_VAL) return split_median(b, first, n, axis, sd);  /* all in one bin */
    if (cost >= COST_TEST * n && n <= MAX_LEAF) return 0;
    return partition_bins(b, first, n, cbox, axis, split, sd);
}

/* Node `at` over primitives first..first+n-1, whose boxes are box and
 * (centroids) cbox. */
static void build_node(bvh_builder *b, long at, long first, long n, int depth,
                       const bvh_box *box, const bvh_box *cbox)
{
    bvh_sides sd;
    long nl;
    node_box(&b->nodes[at], box);
    if (depth > b->max_depth) b->max_depth = depth;
    nl = choose_split(b, first, n, depth, box, cbox, &sd);
    if (nl == 0) {
        b->nodes[at].index = (uint32_t)first, b->nodes[at].count = (uint32_t)n;
        b->leaves++;
        return;
    }
    b->nodes[at].index = (uint32_t)b->nnodes, b->nodes[at].count = 0;
    b->nnodes += 2;
    build_node(b, b->nodes[at].index, first, nl, depth + 1, &sd.box[0], &sd.cbox[0]);
    build_node(b, b->nodes[at].index + 1, first + nl, n - nl, depth + 1, &sd.box[1], &sd.cbox[1]);
}

/* Expected cost of a ray that meets the root of the binary tree, by the SAH
 * model. */
static double tree_cost(const bvh_builder *b)
{
    bvh_box root, box;
    double a0, sum = 0;
    long i;
    if (b->nnodes == 0) return 0;
    node_to_box(&b->nodes[0], &root);
    a0 = box_area(&root);
    if (!(a0 > 0)) return 0;
    for (i = 0; i < b->nnodes; i++) {
        if (i == 1) continue;
        node_to_box(&b->nodes[i], &box);
        sum += box_area(&box) / a0 * (b->nodes[i].count ? COST_TEST * b->nodes[i].count : COST_STEP);
    }
    return sum;
}

/* ---- four-way nodes ------------------------------------------------------ */

static void lane_box(bvh_node4 *nd, int k, const bvh_box *b)
{
    int a;
    for (a = 0; a < 3; a++) nd->box[0][a][k] = b->lo[a], nd->box[1][a][k] = b->hi[a];
}

static void lane_to_box(const bvh_node4 *nd, int k, bvh_box *b)
{
    int a;
    for (a = 0; a < 3; a++) b->lo[a] = nd->box[0][a][k], b->hi[a] = nd->box[1][a][k];
    b->lo[3] = b->lo[2], b->hi[3] = b->hi[2];
}

static int lane_empty(const bvh_node4 *nd, int k)
{
    return nd->count[k] == 0 && nd->index[k] == 0;
}

/* The up to four binary nodes that one four-way node holds in place of the
 * binary inner node `bin`: its two children, then, while there are fewer
 * than four, the inner one of largest area replaced by its own two (the
 * order of the lanes kept). */
static int gather_lanes(const bvh_node *bin, uint32_t at, uint32_t lane[4])
{
    int n = 2, k;
    lane[0] = bin[at].index, lane[1] = lane[0] + 1;
    while (n < 4) {
        int pick = -1;
        double most = -1;
        bvh_box box;
        for (k = 0; k < n; k++) {
            if (bin[lane[k]].count) continue;
            node_to_box(&bin[lane[k]], &box);
            if (box_area(&box) > most) most = box_area(&box), pick = k;
        }
        if (pick < 0) break;
        for (k = n; k > pick + 1; k--) lane[k] = lane[k - 1];
        lane[pick + 1] = bin[lane[pick]].index + 1;
        lane[pick] = bin[lane[pick]].index;
        n++;
    }
    return n;
}

/* Four-way node number *used (then *used + 1) from binary node `at`, and
 * below it; returns its number.  Parents come before their children. */
static uint32_t collapse(const bvh_node *bin, uint32_t at, bvh_node4 *out, long *used,
                         int depth, long *max_depth)
{
    uint32_t lane[4], me = (uint32_t)(*used)++;
    int n = bin[at].count ? 1 : gather_lanes(bin, at, lane), k;
    bvh_box box;
    if (bin[at].count) lane[0] = at;   /* a leaf as the root */
    if (depth > *max_depth) *max_depth = depth;
    box_empty(&box);
    for (k = 0; k < 4; k++) {
        out[me].index[k] = out[me].count[k] = 0;
        lane_box(&out[me], k, &box);
    }
    for (k = 0; k < n; k++) {
        const bvh_node *b = &bin[lane[k]];
        node_to_box(b, &box);
        lane_box(&out[me], k, &box);
        out[me].count[k] = b->count;
        out[me].index[k] = b->count ? b->index
                                    : collapse(bin, lane[k], out, used, depth + 1, max_depth);
    }
    return me;
}

/* How many four-way nodes collapse makes from binary node `at`: the
 * tree's block is then no larger than it. */
static long count_collapsed(const bvh_node *bin, uint32_t at)
{
    uint32_t lane[4];
    long count = 1;
    int n, k;
    if (bin[at].count) return 1;
    n = gather_lanes(bin, at, lane);
    for (k = 0; k < n; k++)
        if (!bin[lane[k]].count) count += count_collapsed(bin, lane[k]);
    return count;
}

/* The SAH model's expected cost of the four-way tree for a ray that meets
 * the scene box: each lane's area over the scene box's, times COST_STEP for
 * a node (its four boxes tested) or COST_TEST per primitive of a leaf.  It
 * shows what a refit costs as objects move. */
static double tree_cost4(const bvh *t)
{
    bvh_box root, box;
    double a0, sum = 0;
    long i;
    int k;
    if (t->nnodes == 0) return 0;
    box_empty(&root);
    for (k = 0; k < 4; k++) lane_to_box(&t->nodes[0], k, &box), box_grow(&root, &box);
    a0 = box_area(&root);
    if (!(a0 > 0)) return 0;
    sum = COST_STEP;
    for (i = 0; i < t->nnodes; i++)
        for (k = 0; k < 4; k++) {
            const bvh_node4 *nd = &t->nodes[i];
            if (lane_empty(nd, k)) continue;
            lane_to_box(nd, k, &box);
            sum += box_area(&box) / a0 * (nd->count[k] ? COST_TEST * nd->count[k] : COST_STEP);
        }
    return sum;
}

/* The scene box (the root's lanes together) in the frame, its largest
 * coordinate there and in the caller's coordinates, and the margin. */
static void set_scale(bvh *t)
{
    int a, k;
    bvh_box root, box;
    t->scale = t->ext = t->delta = 0;
    for (a = 0; a < 3; a++) t->lo[a] = t->hi[a] = 0;
    if (t->nnodes == 0) return;
    box_empty(&root);
    for (k = 0; k < 4; k++)
        if (!lane_empty(&t->nodes[0], k)) lane_to_box(&t->nodes[0], k, &box), box_grow(&root, &box);
    for (a = 0; a < 3; a++) {
        if (!(root.lo[a] <= root.hi[a])) return;   /* nothing in the tree */
        t->lo[a] = root.lo[a], t->hi[a] = root.hi[a];
        t->ext = fmax(t->ext, fmax(fabs(t->lo[a]), fabs(t->hi[a])));
        t->scale = fmax(t->scale, fmax(fabs(t->c[a] + t->lo[a]), fabs(t->c[a] + t->hi[a])));
    }
    t->delta = BVH_EPS * t->ext + t->ulps * t->scale;
}

/* The tree in one block, the nodes aligned to 64 bytes. */
static bvh *alloc_tree(long nnodes, long nprims)
{
    bvh *t = calloc(1, sizeof *t);
    size_t nb = (size_t)nnodes * sizeof(bvh_node4), pb = (size_t)nprims * sizeof(int);
    if (!t) return NULL;
    t->block = calloc(1, nb + pb + 64);
    if (!t->block) return free(t), NULL;
    t->nodes = (bvh_node4 *)((char *)t->block + (64 - (uintptr_t)t->block % 64) % 64);
    t->prims = (int *)(t->nodes + nnodes);
    t->nnodes = nnodes, t->nprims = nprims;
    t->bytes = nb + pb;
    return t;
}

/* The binary tree collapsed to four-way nodes: about one for every three
 * binary inner nodes, or one for a root that is a leaf. */
static bvh *finish(bvh_builder *b, const int *ids, long nprims)
{
    long used = 0, depth = 0;
    bvh *t = alloc_tree(b->nnodes ? count_collapsed(b->nodes, 0) : 0, nprims);
    if (!t) return NULL;
    if (b->nnodes) collapse(b->nodes, 0, t->nodes, &used, 0, &depth);
    t->nnodes = used;
    t->bytes = (size_t)used * sizeof(bvh_node4) + (size_t)nprims * sizeof(int);
    if (nprims) memcpy(t->nodes + used, ids, (size_t)nprims * sizeof(int));
    t->prims = (int *)(t->nodes + used);
    memcpy(t->c, b->c, sizeof t->c);
    t->ulps = PRIMS_HIT_ULPS * (b->p->eps > 0 ? b->p->eps : DBL_EPSILON);
    t->slack_ulps = t->ulps * (1 + 0x1p-21);
    set_scale(t);
    t->info.nodes = used;
    t->info.leaves = b->leaves;
    t->info.max_depth = depth;
    t->info.prim_refs = nprims;
    t->info.prims_per_leaf = b->leaves ? (double)nprims / b->leaves : 0;
    t->info.bytes = t->bytes;
    t->info.sah_cost = tree_cost4(t);
    t->info.sah_cost_binary = tree_cost(b);
    return t;
}

/* A record for every primitive with a box; returns how many. */
static long gather(bvh_builder *b, int n)
{
    long m = 0;
    int i;
    for (i = 0; i < n; i++) {
        bvh_box box;
        if (!prim_box(b->p, i, b->c, &box)) continue;
        memcpy(b->ref[m].lo, box.lo, sizeof b->ref[m].lo);
        memcpy(b->ref[m].hi, box.hi, sizeof b->ref[m].hi);
        b->ref[m].id = i, b->ref[m].pad = 0;
        m++;
    }
    return m;
}

bvh *bvh_build(int n, const prims *p, int method)
{
    clock_t start = clock();
    bvh_builder b;
    bvh *t = NULL;
    int *ids;
    long m, k;
    memset(&b, 0, sizeof b);
    b.p = p, b.method = method;
    if (n < 0) n = 0;
    b.ref = malloc(((size_t)n + 1) * sizeof *b.ref);
    b.nodes = calloc(2 * (size_t)n + 2, sizeof *b.nodes);
    if (b.ref && b.nodes) {
        double lo[3], hi[3];
        /* the frame's centre from at most about 1024 of the primitives:
         * any centre near the scene will do, since the margins follow the
         * boxes the tree ends up with (set_scale) */
        prims_frame(p, n, n / 1024 + 1, lo, hi, b.c);
        m = gather(&b, n);
        if (m > 0) {
            bvh_box box, cbox;
            bounds_of(&b, 0, m, &box, &cbox);
            b.nnodes = 2;   /* the root, and the padding that aligns the pairs */
            build_node(&b, 0, 0, m, 0, &box, &cbox);
        }
        /* the records go before the four-way tree is made: the build's
         * peak of memory is then the larger of the two, not their sum */
        ids = malloc(((size_t)m + 1) * sizeof *ids);
        if (ids) {
            for (k = 0; k < m; k++) ids[k] = b.ref[k].id;
            free(b.ref), b.ref = NULL;
            t = finish(&b, ids, m);
            free(ids);
        }
    }
    free(b.ref), free(b.nodes);
    if (t) t->info.build_seconds = (double)(clock() - start) / CLOCKS_PER_SEC;
    return t;
}

/* Children come after their parent in the array, so one pass from the end
 * sees every child before its parent. */
void bvh_refit(bvh *t, const prims *p)
{
    long i;
    if (!t) return;
    for (i = t->nnodes - 1; i >= 0; i--) {
        bvh_node4 *nd = &t->nodes[i];
        int k, j;
        for (k = 0; k < 4; k++) {
            bvh_box box, c;
            uint32_t m;
            if (lane_empty(nd, k)) continue;
            box_empty(&box);
            for (m = 0; m < nd->count[k]; m++)
                if (prim_box(p, t->prims[nd->index[k] + m], t->c, &c)) box_grow(&box, &c);
            for (j = 0; nd->count[k] == 0 && j < 4; j++) {
                lane_to_box(&t->nodes[nd->index[k]], j, &c);
                box_grow(&box, &c);
            }
            lane_box(nd, k, &box);
        }
    }
    set_scale(t);
    t->info.sah_cost = tree_cost4(t);
}

void bvh_describe(const bvh *t, bvh_info *info)
{
    memset(info, 0, sizeof *info);
    if (!t) return;
    *info = t->info;
    info->block = t->nodes;
}

void bvh_free(bvh *t)
{
    if (t) free(t->block), free(t);
}

long bvh_planes(const bvh *t, int *axis, double *pos, long max)
{
    long i, n = 0;
    int s, a, k;
    for (i = 0; i < t->nnodes; i++)
        for (k = 0; k < 4; k++)
            for (s = 0; s < 2 && !lane_empty(&t->nodes[i], k); s++)
                for (a = 0; a < 3; a++) {
                    if (n < max) axis[n] = a, pos[n] = t->c[a] + t->nodes[i].box[s][a][k];
                    n++;
                }
    return n;
}

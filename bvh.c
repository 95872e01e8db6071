/* bvh.c - a bounding volume hierarchy for ray tracing over primitives it
 * knows only through the callbacks of prims.h.  bvh.h maps the lecture's
 * slide, BVH_Intersect(ray, node), to the functions below.
 *
 * Traversal: depth first, the nearer child first, the farther one on a
 * stack, dropped when the ray enters its box beyond the nearest hit found
 * meanwhile.  Each primitive sits in exactly one leaf, so unlike the
 * kd-tree no mailbox is needed.
 *
 * Build, two ways (bvh_build's method):
 *   BVH_SAH     the surface area heuristic over binned centroids (Wald 2007,
 *               "On fast construction of SAH-based bounding volume
 *               hierarchies"): each node's primitives are counted into BINS
 *               slabs of their centroids along each axis, and the K - 1
 *               planes between slabs are priced by one sweep from each end.
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
 * beyond which it always splits if it can. */
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

/* The margin.  Boxes are floats rounded outwards, so each holds its
 * primitives' double boxes whole.  The walk then treats every box as grown
 * by delta = BVH_EPS * (largest coordinate of the scene and the ray origin)
 * on every side, for two reasons.  The hit callback's point may lie outside
 * the primitive's box by up to 1e-7 of that coordinate (prims.h).  And the
 * slab test runs in float: b - o rounds by 2^-24 of |b - o| <= 2 * scale,
 * and 1/d and the product by 2^-24 each, so a computed crossing may be off
 * by 3 * 2^-24 * 2 * scale = 3.6e-7 * scale in space.  Together 4.6e-7;
 * 2^-20 = 9.5e-7 covers them twice.  The origin shifted by delta is rounded
 * away from the box (see setup_ray), so its own rounding only adds margin.
 * The float test is valid while the numbers stay well inside the float
 * range (FAST_MAX below); other rays are answered by testing every
 * primitive. */
#define BVH_EPS (1.0 / 1048576.0)
#define FAST_MAX 0x1p60
#define FAST_MIN 0x1p-60

/* ---- nodes ------------------------------------------------------------ */

/* 32 bytes a node: the box as six floats (box[0] the low corner, box[1] the
 * high one), an index and a count.  Inner node (count 0): its children are
 * nodes index and index + 1.  Leaf: count primitives, listed from that
 * index of the tree's primitive list.  The walk always tests both children
 * of a node, so siblings are stored side by side, the pair starting at an
 * even index of a 64-byte aligned array: one cache line holds both.  Node
 * 0 is the root and node 1 is unused padding. */
typedef struct {
    float box[2][3];
    uint32_t index, count;
} bvh_node;

typedef char bvh_node_must_be_32_bytes[sizeof(bvh_node) == 32 ? 1 : -1];

struct bvh {
    bvh_node *nodes;   /* nodes[0] the root; nnodes of them, then the list */
    int *prims;        /* the leaves' primitive numbers */
    long nnodes, nprims;
    void *block;       /* the allocation behind nodes and prims */
    size_t bytes;
    double scale;      /* largest |coordinate| of the root's box */
    bvh_info info;
};

/* ---- floats rounded one way --------------------------------------------- */

static float down(double x)
{
    float f = (float)x;
    return (double)f > x ? nextafterf(f, -HUGE_VALF) : f;
}

static float up(double x)
{
    float f = (float)x;
    return (double)f < x ? nextafterf(f, HUGE_VALF) : f;
}

/* ---- traversal ---------------------------------------------------------- */

/* The ray as the slab test needs it.  For each axis, neg picks the box
 * corner the ray meets first (from the sign bit, so -0 counts as negative
 * like its 1/d = -inf).  on and of are the origin moved by delta: the near
 * plane of a box grown by delta is at b - delta (b + delta for neg), and
 * b - delta - o = b - (o + delta), so the test reads the plain box with a
 * moved origin; of likewise for the far plane.  A zero component gives
 * inv = +-inf: the ray is inside that slab for every t or for none; where
 * 0 * inf makes NaN, the comparisons in box_entry read it as "inside". */
typedef struct {
    float on[3], of[3], inv[3];
    int neg[3];
    float tmin;
    int skip;
} bvh_ray;

typedef struct {
    uint32_t node;
    float entry;
} bvh_todo;

/* Intersect_P(ray, box): 1 when the ray between tmin and tmax passes
 * through the box grown by delta (the slab test of Kay & Kajiya 1986), with
 * the t where it enters in *entry.  Written so that NaN never excludes. */
static inline int box_entry(const bvh_node *nd, const bvh_ray *r, float tmax,
                            float *entry)
{
    float t0 = r->tmin, t1 = tmax;
    int a;
    for (a = 0; a < 3; a++) {
        float tn = (nd->box[r->neg[a]][a] - r->on[a]) * r->inv[a];
        float tf = (nd->box[1 - r->neg[a]][a] - r->of[a]) * r->inv[a];
        t0 = tn > t0 ? tn : t0;
        t1 = tf < t1 ? tf : t1;
    }
    *entry = t0;
    return t0 <= t1;
}

/* 1 when the float slab test is valid for this ray (see BVH_EPS), and the
 * ray set up for it. */
static int setup_ray(const bvh *t, const double org[3], const double dir[3],
                     int skip, double tmin, bvh_ray *r)
{
    double scale = t->scale, dmax = 0, delta;
    int a;
    for (a = 0; a < 3; a++) {
        if (fabs(org[a]) > scale) scale = fabs(org[a]);
        if (fabs(dir[a]) > dmax) dmax = fabs(dir[a]);
    }
    if (!(scale <= FAST_MAX && scale >= FAST_MIN && dmax <= FAST_MAX && dmax >= FAST_MIN))
        return 0;
    delta = BVH_EPS * scale;
    for (a = 0; a < 3; a++) {
        int neg = signbit(dir[a]) != 0;
        r->neg[a] = neg;
        r->on[a] = neg ? down(org[a] - delta) : up(org[a] + delta);
        r->of[a] = neg ? up(org[a] + delta) : down(org[a] - delta);
        r->inv[a] = (float)(1.0 / dir[a]);   /* +-inf for +-0 and tiny d */
    }
    r->tmin = down(tmin);
    r->skip = skip;
    return 1;
}

/* Intersect(ray, object) for each primitive of a leaf.  Nearest: keep the
 * lowest t, and on equal t the lower primitive number, as the brute-force
 * loop would; the callback gets tmax = the best t so far, inclusive, so
 * that it reports such ties.  Any-hit: the first hit will do. */
static inline int test_leaf(const bvh *t, const bvh_node *nd, const prims *p,
                            const bvh_ray *r, void *ray, double tmin, int any,
                            double *best_t, int best, unsigned long long *tests)
{
    const int *list = t->prims + nd->index;
    uint32_t k;
    for (k = 0; k < nd->count; k++) {
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

/* Which children of inner node nd the ray enters before tmax, nearer
 * first: returns how many (0, 1 or 2), the nodes in first[], their entries
 * in at[].  On equal entries the left child goes first. */
static inline int children(const bvh *t, const bvh_node *nd, const bvh_ray *r,
                           float tmax, uint32_t first[2], float at[2])
{
    uint32_t c = nd->index;
    float e0, e1;
    int h0 = box_entry(&t->nodes[c], r, tmax, &e0);
    int h1 = box_entry(&t->nodes[c + 1], r, tmax, &e1);
    if (h0 && h1) {
        int swap = e1 < e0;
        first[0] = c + swap, at[0] = swap ? e1 : e0;
        first[1] = c + !swap, at[1] = swap ? e0 : e1;
        return 2;
    }
    if (!h0 && !h1) return 0;
    first[0] = c + h1, at[0] = h1 ? e1 : e0;
    return 1;
}

/* The slide's BVH_Intersect(ray, node), recursive.  The caller has already
 * found that the ray enters the node's box (Intersect_P): the root's box in
 * bvh_intersect_recursive, a child's in children().  The second child is
 * visited only if the ray still enters it no later than the best hit found
 * in the first; any = 1 stops at the first hit. */
static int bvh_intersect(const bvh *t, const prims *p, const bvh_ray *r,
                         void *ray, double tmin, int any, uint32_t node,
                         double *best_t, int best, prim_counters *c)
{
    const bvh_node *nd = &t->nodes[node];
    uint32_t child[2];
    float at[2];
    int k, n;
    c->steps++;
    if (nd->count)
        return test_leaf(t, nd, p, r, ray, tmin, any, best_t, best, &c->tests);
    n = children(t, nd, r, up(*best_t), child, at);
    for (k = 0; k < n; k++) {
        if (k > 0 && !(at[k] <= up(*best_t))) break;
        best = bvh_intersect(t, p, r, ray, tmin, any, child[k], best_t, best, c);
        if (any && best >= 0) break;
    }
    return best;
}

/* The walk behind bvh_nearest (any = 0) and bvh_any (any = 1): the fast
 * path, bvh_intersect with the recursion turned into a loop, the second
 * child waiting on a stack with the t where the ray enters it.  Same nodes,
 * same order, same tests. */
static int walk(const bvh *t, const prims *p, const bvh_ray *r, void *ray,
                double tmin, int any, double *best_t, prim_counters *c)
{
    bvh_todo stack[STACK_SIZE];
    uint32_t node = 0, child[2];
    float at[2], tmax = up(*best_t);
    unsigned long long steps = 0, tests = 0;
    int n = 0, best = -1;
    for (;;) {
        const bvh_node *nd = &t->nodes[node];
        steps++;
        if (nd->count == 0) {
            int k = children(t, nd, r, tmax, child, at);
            if (k == 2) stack[n].node = child[1], stack[n].entry = at[1], n++;
            if (k > 0) {
                node = child[0];
                continue;
            }
        } else {
            int was = best;
            best = test_leaf(t, nd, p, r, ray, tmin, any, best_t, best, &tests);
            if (best != was) {
                if (any) break;
                tmax = up(*best_t);
            }
        }
        while (n > 0 && !(stack[n - 1].entry <= tmax)) n--;
        if (n == 0) break;
        node = stack[--n].node;
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
    float entry;
    int a;
    if (c) c->rays++;
    if (!t || t->nnodes == 0) return -1;
    for (a = 0; a < 3; a++)
        if (!isfinite(org[a]) || !isfinite(dir[a])) return -1;
    if (!(tmin <= *best_t)) return -1;
    if (!setup_ray(t, org, dir, skip, tmin, &r)) {
        /* out of the float test's range (see BVH_EPS): every primitive */
        bvh_node all;
        unsigned long long tests = 0;
        all.index = 0, all.count = (uint32_t)t->nprims, r.skip = skip;
        a = test_leaf(t, &all, p, &r, ray, tmin, any, best_t, -1, &tests);
        if (c) c->tests += tests;
        return a;
    }
    if (!box_entry(&t->nodes[0], &r, up(*best_t), &entry)) return -1;
    if (recursive) {
        prim_counters none = {0, 0, 0};
        return bvh_intersect(t, p, &r, ray, tmin, any, 0, best_t, -1, c ? c : &none);
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

typedef struct {
    float lo[3], hi[3];
} bvh_box;

static void box_empty(bvh_box *b)
{
    int a;
    for (a = 0; a < 3; a++) b->lo[a] = HUGE_VALF, b->hi[a] = -HUGE_VALF;
}

static void box_grow(bvh_box *b, const bvh_box *c)
{
    int a;
    for (a = 0; a < 3; a++) {
        if (c->lo[a] < b->lo[a]) b->lo[a] = c->lo[a];
        if (c->hi[a] > b->hi[a]) b->hi[a] = c->hi[a];
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

/* Primitive i's box from the callback, rounded outwards to floats: it holds
 * the double box whole.  0 for NaN or lo > hi. */
static int prim_box(const prims *p, int i, bvh_box *b)
{
    double lo[3], hi[3];
    int a;
    p->bounds(p->user, i, lo, hi);
    for (a = 0; a < 3; a++) {
        if (!(lo[a] <= hi[a])) return 0;
        b->lo[a] = down(lo[a]);
        b->hi[a] = up(hi[a]);
    }
    return 1;
}

static void node_box(bvh_node *nd, const bvh_box *b)
{
    memcpy(nd->box[0], b->lo, sizeof b->lo);
    memcpy(nd->box[1], b->hi, sizeof b->hi);
}

static void node_to_box(const bvh_node *nd, bvh_box *b)
{
    memcpy(b->lo, nd->box[0], sizeof b->lo);
    memcpy(b->hi, nd->box[1], sizeof b->hi);
}

/* ---- the builder -------------------------------------------------------- */

typedef struct {
    const prims *p;
    int method;
    bvh_box *box;      /* per primitive */
    float (*cen)[3];   /* per primitive: its box's centre */
    int *idx;          /* the primitives being sorted into leaves */
    bvh_node *nodes;
    long nnodes;
    long max_depth, leaves;
} bvh_builder;

typedef struct {
    bvh_box box;
    long count;
} bvh_bin;

/* The node's box and the box of its primitives' centroids. */
static void bounds_of(const bvh_builder *b, long first, long n, bvh_box *box,
                      bvh_box *cbox)
{
    long k;
    int a;
    box_empty(box), box_empty(cbox);
    for (k = first; k < first + n; k++) {
        const float *c = b->cen[b->idx[k]];
        box_grow(box, &b->box[b->idx[k]]);
        for (a = 0; a < 3; a++) {
            if (c[a] < cbox->lo[a]) cbox->lo[a] = c[a];
            if (c[a] > cbox->hi[a]) cbox->hi[a] = c[a];
        }
    }
}

static int bin_of(float c, float lo, double k1)
{
    int i = (int)((c - lo) * k1);
    return i < 0 ? 0 : i >= BINS ? BINS - 1 : i;
}

/* Wald 2007: the best plane between bins on any axis.  Returns its cost,
 * and the axis and the number of bins left of it; HUGE_VAL when no plane
 * parts the primitives (all centroids in one bin on every axis). */
static double best_bin_split(const bvh_builder *b, long first, long n,
                             const bvh_box *cbox, double area, int *axis,
                             int *split)
{
    double best = HUGE_VAL;
    int a, i;
    for (a = 0; a < 3; a++) {
        bvh_bin bin[BINS];
        double right_area[BINS];
        long right_n[BINS], k, nl = 0;
        float lo = cbox->lo[a];
        double ext = (double)cbox->hi[a] - lo, k1;
        bvh_box acc;
        if (!(ext > 0)) continue;
        k1 = BINS * (1 - 1e-6) / ext;
        for (i = 0; i < BINS; i++) box_empty(&bin[i].box), bin[i].count = 0;
        for (k = first; k < first + n; k++) {
            int prim = b->idx[k], j = bin_of(b->cen[prim][a], lo, k1);
            box_grow(&bin[j].box, &b->box[prim]);
            bin[j].count++;
        }
        box_empty(&acc);
        right_n[BINS - 1] = 0;
        for (i = BINS - 1, k = 0; i > 0; i--) {   /* right of plane i: bins i.. */
            box_grow(&acc, &bin[i].box);
            k += bin[i].count;
            right_area[i] = box_area(&acc), right_n[i] = k;
        }
        box_empty(&acc);
        for (i = 1; i < BINS; i++) {              /* plane i: bins 0..i-1 left */
            double cost;
            box_grow(&acc, &bin[i - 1].box);
            nl += bin[i - 1].count;
            if (nl == 0 || right_n[i] == 0) continue;
            cost = COST_STEP + COST_TEST * (box_area(&acc) * nl + right_area[i] * right_n[i]) / area;
            if (cost < best) best = cost, *axis = a, *split = i;
        }
    }
    return best;
}

/* Reorders idx[first..first+n) so that those left of the plane come first;
 * returns how many they are. */
static long partition_bins(bvh_builder *b, long first, long n, const bvh_box *cbox,
                           int axis, int split)
{
    float lo = cbox->lo[axis];
    double k1 = BINS * (1 - 1e-6) / ((double)cbox->hi[axis] - lo);
    long i = first, j = first + n - 1;
    while (i <= j) {
        if (bin_of(b->cen[b->idx[i]][axis], lo, k1) < split) i++;
        else {
            int tmp = b->idx[i];
            b->idx[i] = b->idx[j], b->idx[j] = tmp;
            j--;
        }
    }
    return i - first;
}

/* Centroid order along an axis, ties by primitive number: a total order, so
 * the median build is deterministic. */
static int before(const bvh_builder *b, int p, int q, int axis)
{
    float cp = b->cen[p][axis], cq = b->cen[q][axis];
    return cp < cq || (cp == cq && p < q);
}

/* Hoare's selection (quickselect): idx[first..first+n) reordered so that
 * the m-th smallest is at first + m, smaller ones before it and larger
 * after; expected O(n).  The pivot is the middle element, swapped to the
 * end (Lomuto's partition). */
static void select_nth(bvh_builder *b, long first, long n, long m, int axis)
{
    long lo = first, hi = first + n - 1, want = first + m;
    int *x = b->idx;
    while (lo < hi) {
        long mid = lo + (hi - lo) / 2, k, store = lo;
        int pivot = x[mid], tmp;
        x[mid] = x[hi], x[hi] = pivot;
        for (k = lo; k < hi; k++)
            if (before(b, x[k], pivot, axis)) tmp = x[k], x[k] = x[store], x[store++] = tmp;
        x[hi] = x[store], x[store] = pivot;
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

/* How many primitives of the node go left, 0 for a leaf. */
static long choose_split(bvh_builder *b, long first, long n, int depth,
                         const bvh_box *box, const bvh_box *cbox)
{
    int axis = longest_axis(cbox), split = 0;
    double cost;
    if (n <= 1 || !((double)cbox->hi[axis] - cbox->lo[axis] > 0))
        return 0;   /* one primitive, or every centroid at one point */
    if (b->method == BVH_MEDIAN || depth >= SAH_DEPTH) {
        if (b->method == BVH_MEDIAN && n <= MEDIAN_LEAF) return 0;
        select_nth(b, first, n, n / 2, axis);
        return n / 2;
    }
    cost = best_bin_split(b, first, n, cbox, box_area(box), &axis, &split);
    if (cost == HUGE_VAL) {   /* all in one bin: fall back to the median */
        select_nth(b, first, n, n / 2, axis);
        return n / 2;
    }
    if (cost >= COST_TEST * n && n <= MAX_LEAF) return 0;
    return partition_bins(b, first, n, cbox, axis, split);
}

static void build_node(bvh_builder *b, long at, long first, long n, int depth)
{
    bvh_box box, cbox;
    long nl;
    bounds_of(b, first, n, &box, &cbox);
    node_box(&b->nodes[at], &box);
    if (depth > b->max_depth) b->max_depth = depth;
    nl = choose_split(b, first, n, depth, &box, &cbox);
    if (nl == 0) {
        b->nodes[at].index = (uint32_t)first, b->nodes[at].count = (uint32_t)n;
        b->leaves++;
        return;
    }
    b->nodes[at].index = (uint32_t)b->nnodes, b->nodes[at].count = 0;
    b->nnodes += 2;
    build_node(b, b->nodes[at].index, first, nl, depth + 1);
    build_node(b, b->nodes[at].index + 1, first + nl, n - nl, depth + 1);
}

/* Expected cost of a ray that meets the root, by the SAH model. */
static double tree_cost(const bvh *t)
{
    bvh_box root, box;
    double a0, sum = 0;
    long i;
    if (t->nnodes == 0) return 0;
    node_to_box(&t->nodes[0], &root);
    a0 = box_area(&root);
    if (!(a0 > 0)) return 0;
    for (i = 0; i < t->nnodes; i++) {
        if (i == 1) continue;
        node_to_box(&t->nodes[i], &box);
        sum += box_area(&box) / a0 * (t->nodes[i].count ? COST_TEST * t->nodes[i].count : COST_STEP);
    }
    return sum;
}

static void set_scale(bvh *t)
{
    int a, s;
    t->scale = 0;
    if (t->nnodes == 0) return;
    for (s = 0; s < 2; s++)
        for (a = 0; a < 3; a++)
            if (fabs(t->nodes[0].box[s][a]) > t->scale) t->scale = fabs(t->nodes[0].box[s][a]);
}

/* The tree in one block, the nodes aligned to 64 bytes. */
static bvh *alloc_tree(long nnodes, long nprims)
{
    bvh *t = calloc(1, sizeof *t);
    size_t nb = (size_t)nnodes * sizeof(bvh_node), pb = (size_t)nprims * sizeof(int);
    if (!t) return NULL;
    t->block = calloc(1, nb + pb + 64);
    if (!t->block) return free(t), NULL;
    t->nodes = (bvh_node *)((char *)t->block + (64 - (uintptr_t)t->block % 64) % 64);
    t->prims = (int *)(t->nodes + nnodes);
    t->nnodes = nnodes, t->nprims = nprims;
    t->bytes = nb + pb;
    return t;
}

static bvh *finish(bvh_builder *b, long nprims)
{
    bvh *t = alloc_tree(b->nnodes, nprims);
    if (!t) return NULL;
    memcpy(t->nodes, b->nodes, (size_t)b->nnodes * sizeof(bvh_node));
    if (nprims) memcpy(t->prims, b->idx, (size_t)nprims * sizeof(int));
    set_scale(t);
    t->info.nodes = b->nnodes > 1 ? b->nnodes - 1 : b->nnodes;   /* not the padding */
    t->info.leaves = b->leaves;
    t->info.max_depth = b->max_depth;
    t->info.prim_refs = nprims;
    t->info.prims_per_leaf = b->leaves ? (double)nprims / b->leaves : 0;
    t->info.bytes = t->bytes;
    t->info.sah_cost = tree_cost(t);
    return t;
}

/* Boxes and centroids of every primitive; the ones with a box go to idx.
 * Returns how many. */
static long gather(bvh_builder *b, int n)
{
    long m = 0;
    int i, a;
    for (i = 0; i < n; i++) {
        if (!prim_box(b->p, i, &b->box[i])) continue;
        for (a = 0; a < 3; a++)
            b->cen[i][a] = (float)(0.5 * ((double)b->box[i].lo[a] + b->box[i].hi[a]));
        b->idx[m++] = i;
    }
    return m;
}

bvh *bvh_build(int n, const prims *p, int method)
{
    clock_t start = clock();
    bvh_builder b;
    bvh *t = NULL;
    long m;
    memset(&b, 0, sizeof b);
    b.p = p, b.method = method;
    if (n < 0) n = 0;
    b.box = malloc(((size_t)n + 1) * sizeof *b.box);
    b.cen = malloc(((size_t)n + 1) * sizeof *b.cen);
    b.idx = malloc(((size_t)n + 1) * sizeof *b.idx);
    b.nodes = calloc(2 * (size_t)n + 2, sizeof *b.nodes);
    if (b.box && b.cen && b.idx && b.nodes) {
        m = gather(&b, n);
        if (m > 0) {
            b.nnodes = 2;   /* the root, and the padding that aligns the pairs */
            build_node(&b, 0, 0, m, 0);
        }
        t = finish(&b, m);
    }
    free(b.box), free(b.cen), free(b.idx), free(b.nodes);
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
        bvh_node *nd = &t->nodes[i];
        bvh_box box, c;
        uint32_t k;
        if (i == 1) continue;
        box_empty(&box);
        if (nd->count)
            for (k = 0; k < nd->count; k++) {
                if (prim_box(p, t->prims[nd->index + k], &c)) box_grow(&box, &c);
            }
        else
            for (k = 0; k < 2; k++) {
                node_to_box(&t->nodes[nd->index + k], &c);
                box_grow(&box, &c);
            }
        node_box(nd, &box);
    }
    set_scale(t);
    t->info.sah_cost = tree_cost(t);
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
    long i, k = 0;
    int s, a;
    for (i = 0; i < t->nnodes; i++) {
        if (i == 1) continue;
        for (s = 0; s < 2; s++)
            for (a = 0; a < 3; a++) {
                if (k < max) axis[k] = a, pos[k] = t->nodes[i].box[s][a];
                k++;
            }
    }
    return k;
}

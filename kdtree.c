/* kdtree.c - a kd-tree for ray tracing over primitives it knows only through
 * the callbacks of prims.h.
 *
 * Traversal: Kaplan's near/far order (Kaplan 1985, "Space-tracing: a constant
 * time ray-tracer").  The lecture's slide, and the functions doing each line:
 *
 *   TreeIntersect(ray R, node W)                   tree_intersect
 *     if R.interval empty or W empty then return   setup_ray, step
 *     if W is leaf then
 *       foreach object O from W                    test_leaf
 *         Intersect(R,O)                           the hit callback
 *     else
 *       R1 = R clipped to nearer side of W         step
 *       TreeIntersect(R1, W.near)
 *       if NoIntersectionInside then               pop: no hit before R2 starts
 *         R2 = R clipped to farther side of W      step
 *         TreeIntersect(R2, W.far)
 *
 * setup_ray clips R to the scene box (grown by the margin, see RAY_EPS) and
 * stops a ray that misses it.  step clips R at W's plane, giving R1 and R2
 * at once, and enters only the sides it reaches; an empty leaf lists no
 * primitive.  test_leaf skips a primitive already tested for this ray (the
 * mailbox).  tree_intersect is the slide as written, recursive, behind
 * kd_intersect_recursive: the readable reference.  walk, behind kd_nearest
 * and kd_any, is the fast path: the same cells in the same order, the
 * recursion turned into a loop with a stack of far sides (Havran 2000,
 * thesis, "Heuristic Ray Shooting Algorithms").  Both return what a
 * brute-force loop over all primitives returns, ties included.
 *
 * Build: the surface area heuristic (SAH) with the O(N log N) sweep of
 * Wald & Havran 2006, "On building fast kd-trees for ray tracing, and on doing
 * that in O(N log N)".  The edges of every primitive's box become "events",
 * sorted once per axis.  One linear sweep over a node's sorted events prices
 * every candidate plane of that node; splitting the node's event lists keeps
 * them sorted, so no level sorts again: only the primitives that the plane
 * cuts get new (clipped) events, and those few are sorted and merged in.
 * A budget of references (BUDGET) keeps the tree's size linear in N on
 * every input, fans of slivers included, where the SAH alone is not.
 */
#include "kdtree.h"
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* The SAH cost model (MacDonald & Booth 1990; Wald & Havran 2006):
 *     cost(split) = COST_STEP + COST_TEST * (A(L)/A(V) * nL + A(R)/A(V) * nR)
 *     cost(leaf)  = COST_TEST * n
 * where A is surface area: the chance that a ray through cell V also passes
 * through a child is the ratio of their areas.  COST_STEP is one traversal
 * step, COST_TEST one call of the hit callback; only their ratio shapes the
 * tree, a larger COST_TEST giving deeper trees with fewer primitives per
 * leaf and more references.  The ratio is below 1 because walking cells
 * costs more than the model says: each step ends in a branch that goes
 * either way (near, far or both), which the processor guesses wrong about
 * half the time, while a test of a few primitives in a row runs at full
 * speed.  Fewer, fuller leaves pay, and also mean fewer references and a
 * faster build.  0.6 was chosen against 1 on whole SPD renders: balls 6%,
 * mount 7% and rings 5% faster, gears 5% slower, the others within 1%. */
#define COST_STEP 1.0
#define COST_TEST 0.6

/* Cutting off empty space pays more than the model says: a ray that enters
 * an empty cell leaves it at once, and it shrinks the cells that do hold
 * primitives.  Wald & Havran 2006 scale the cost of such splits by 0.8.
 * We take 0.9, measured with COST_TEST above on SPD balls: 0.8 was 3%
 * slower, 1.0 the same, 0.6 7% slower. */
#define EMPTY_BONUS 0.9

/* Hard limit on depth, so the traversal stack can be a fixed array.  The
 * build stops at 8 + 1.3 log2 N (below), which stays under this for any N
 * that fits in the 30-bit indices of a node. */
#define STACK_SIZE 64

/* The reference budget.  The SAH alone can make a tree of any size: near
 * the centre of a fan of thin triangles every cell holds slivers, every
 * plane cuts most of them, and yet the SAH finds each split worth it, level
 * after level, so that cells and references grow as N^2 (a 50k-triangle
 * fan took 238 s, 88.5M nodes and 3.8 GB).  Wald & Havran's O(N log N)
 * assumes that a plane cuts few primitives (about sqrt(N)), and pbrt's
 * depth limit (see build_node) bounds the depth, not the width.  So the
 * build spends a budget, in the spirit of the fixed budgets of extra
 * references that BVH builders give their spatial splits (Karras & Aila
 * 2013): a leaf costs its references plus one (itself), and the tree may
 * cost BUDGET * (N + 1) at most.  The root holds the whole budget.  A node
 * splits only if what its children cost (their primitives as the SAH
 * counted them, plus one each) can be paid from its budget and a common
 * pool; the children share the node's budget in proportion to what they
 * cost; a leaf puts what it did not spend into the pool, for later splits.
 * A node's budget always covers its own cost, and the budgets of the nodes
 * still to build, the pool and what the leaves cost always add up to
 * BUDGET * (N + 1).  Hence
 *     references + leaves <= BUDGET (N + 1),  nodes < 2 BUDGET (N + 1),
 * and a list holds at most six events a reference: memory linear in N.  And
 * time O(N log N): each level of the tree, at most 8 + 1.3 log2 N of them,
 * handles at most BUDGET (N + 1) references in linear time (sorting too:
 * see sort_events).  16 leaves every tree of the SPD scenes, the
 * 100k-triangle sphere, the 1M cube-sphere and test_accel's scenes as it
 * was (8 changes the flat one, whose tree costs 9.6 a primitive); a
 * 50k-triangle fan then builds in 0.38 s with 0.80M references (8: 0.19 s,
 * 32: 0.78 s). */
#ifndef BUDGET
#define BUDGET 16
#endif

/* The frame.  The tree keeps its planes and boxes as floats relative to a
 * centre c near the middle of the scene box (prims_frame, prims.h), not to
 * the origin: a float step is then 2^-23 of the scene's size wherever the
 * scene lies.  In the caller's coordinates a scene 1e8 from the origin
 * would have float steps of 8 units, and a unit-sized scene would collapse
 * into a few of them.
 *
 * The ray's origin goes into the frame too, o - c.  One farther than
 * FAR_MOVE ext from c (ext below) is first moved along the ray to where the
 * ray enters the scene box, the sum o - c + t0 d taken exactly and rounded
 * once (prims_along, prims.h), and the walk's t is then the caller's t
 * less t0.  So the walk's own doubles are of at most FAR_MOVE times the
 * scene's size wherever the origin is.  A nearer origin (a camera looking
 * at the scene) is not moved: that costs about as much as the walk of a
 * primary ray through a few leaves.
 *
 * The margin.  The traversal treats every cell as if it were grown on every
 * side by
 *     delta = RAY_EPS * ext + ulps * s,
 * ext the largest |coordinate| of the scene box in the tree's frame, s the
 * largest in the caller's, and visits every cell whose grown box the ray
 * passes through.  Without it a hit lying on a cell boundary could be
 * judged to lie only in the cell that does not list its primitive.  It
 * covers:
 *   - the boxes and planes, floats rounded to nearest (see kd_box): a
 *     primitive may reach past the cells that list it by half a float
 *     step, at most 2^-24 ext;
 *   - the hit callback's point, outside the primitive's box by up to
 *     PRIMS_HIT_REL times its longest side (at most 2 ext, prims_frame)
 *     plus PRIMS_HIT_ULPS eps s (the contract of prims.h): ulps is
 *     PRIMS_HIT_ULPS eps;
 *   - the walk's own doubles, all of them below FAR_MOVE ext + 2 ext: the
 *     origin in the frame (rounded once), each plane crossing (s - o) / d
 *     (three roundings), and the best hit's t less t0 (exact when t0 is
 *     more than half of it): a few 2^-53 2^20 ext, some 10^-9 ext.
 * So RAY_EPS, four times the float rounding, covers the parts of size ext
 * (3 2^-24 ext and the walk's).  The price is an occasional extra cell for
 * rays passing within delta of a boundary.
 *
 * The slack.  The contract lets the callback's t err along the ray by
 * ulps m / max|d| (m the larger of s and the origin's largest |coordinate|):
 * a ray from 10^13 away has t of 10^13, rounded by 10^-3.  So the walk
 * takes the ray from tmin - slack to tmax + slack, slack that much, and
 * leaves a cell out only when the ray enters it more than slack beyond the
 * best hit so far.  A far origin costs a few cells just behind the hit,
 * not a margin across every cell. */
#define RAY_EPS 2.5e-7
#define FAR_MOVE 0x1p20

/* ---- nodes ------------------------------------------------------------ */

/* One node in 8 bytes: eight fit in a 64-byte cache line, and as the node
 * array comes from malloc (aligned to at least 8), none straddles two.  `bits`
 * holds the axis (0, 1, 2) or LEAF (3) in its low 2 bits and an index in the
 * other 30.  Inner node: `split` is the plane, the index is the left child;
 * the right child is always index + 1, so one index serves both.  Leaf:
 * `count` primitives, listed at that index of the tree's primitive list. */
typedef struct {
    union {
        float split;
        uint32_t count;
    } u;
    uint32_t bits;
} kd_node;

#define LEAF 3u
#define MAX_INDEX ((1ul << 30) - 1)

/* C99 has no _Static_assert: an array of size -1 does not compile. */
typedef char kd_node_must_be_8_bytes[sizeof(kd_node) == 8 ? 1 : -1];

static int node_axis(const kd_node *n) { return (int)(n->bits & 3u); }
static uint32_t node_index(const kd_node *n) { return n->bits >> 2; }

struct kd_tree {
    kd_node *nodes;  /* nodes[0] is the root; one block with `prims` */
    int *prims;      /* the leaves' lists of primitive numbers */
    double c[3];     /* the frame: planes and boxes are relative to c */
    double lo[3], hi[3];  /* scene box, the union of the primitives' boxes, in the frame */
    double ext;      /* largest |coordinate| of the scene box in the frame */
    double scale;    /* largest |coordinate| of the scene box in the caller's coordinates */
    double ulps;     /* PRIMS_HIT_ULPS eps (see RAY_EPS) */
    double delta;    /* the margin (see RAY_EPS) */
    size_t bytes;
    kd_info info;
};

/* ---- traversal ---------------------------------------------------------- */

/* A primitive listed in several cells (one that straddles a plane) would be
 * tested again in each cell the ray visits, yet the answer cannot change: a
 * miss stays a miss under a smaller tmax, and a hit lies at or beyond the
 * best t found since.  So each ray keeps a mailbox (Amanatides & Woo 1987,
 * "A fast voxel traversal algorithm for ray tracing"): here the last
 * primitive tested in each of MAILBOX slots chosen by the primitive's
 * number, small enough to clear for every ray; two primitives sharing a
 * slot only cost a repeated test.  Eight slots suffice: on random rays
 * through a 100k-triangle sphere they leave 0.1% of the tests repeated,
 * against 5.7% without a mailbox. */
#define MAILBOX 8

/* The ray as the walk needs it.  inv is 1/dir, and +-infinity for +-0; a
 * zero component is "flat": the ray runs parallel to that axis's planes.
 * neg says which way the ray runs along each axis, from the sign bit, so
 * that -0 counts as negative like its 1/d = -inf.  pad[a] is the margin
 * delta (see RAY_EPS) in units of t along axis a.  A denormal component can
 * make inv and pad infinite and the plane crossings NaN; every comparison
 * below is written so that NaN means "visit", which is always safe.  The
 * origin is in the tree's frame, moved along the ray by toff when it came
 * from far away (see RAY_EPS): every t of the walk's is the caller's less
 * toff. */
typedef struct {
    double org[3], inv[3], pad[3];
    uint32_t neg[3];
    int flat[3];
    double delta;
    double toff;    /* how far along the ray the origin was moved */
    double slack;   /* how far along the ray a hit's t may err (see RAY_EPS) */
    double t0, t1;  /* the part of the ray inside the (grown) scene box */
    int skip;       /* the caller's primitive never to test, or -1 */
    int mail[MAILBOX];
} kd_ray;

/* A cell still to visit, with the stretch of the ray inside it. */
typedef struct {
    uint32_t node;
    double t0, t1;
} kd_todo;

/* The ray from o (in the frame) clipped to the grown scene box, for t in
 * t0..t1 (the slab test of Kay and Kajiya 1986), its direction already set
 * up (neg, flat, inv).  0 when it misses the box, and for NaN input.  A
 * flat axis needs no division: the ray is inside that slab for every t or
 * for none. */
static int clip_ray(const kd_tree *t, const double o[3], double t0, double t1, kd_ray *r)
{
    int a;
    for (a = 0; a < 3; a++) {
        double lo = t->lo[a] - r->delta, hi = t->hi[a] + r->delta, inv = r->inv[a], ta, tb;
        r->org[a] = o[a];
        r->pad[a] = r->flat[a] ? 0 : r->delta * fabs(inv);
        if (r->flat[a]) {
            if (!(o[a] >= lo && o[a] <= hi)) return 0;
            continue;
        }
        ta = ((r->neg[a] ? hi : lo) - o[a]) * inv;
        tb = ((r->neg[a] ? lo : hi) - o[a]) * inv;
        if (ta > t0) t0 = ta;
        if (tb < t1) t1 = tb;
    }
    r->t0 = t0, r->t1 = t1;
    return t0 <= t1;  /* false for NaN in tmin or tmax */
}

/* Set up the ray and clip it to the grown scene box; 0 when it misses, and
 * for NaN or infinite input.  Half the rays of a typical view miss the
 * scene box and cost nothing else, so this is one pass over the axes, and
 * a second for an origin from far away, moved to where the first found the
 * ray entering the box (see the frame, above RAY_EPS).  The slack's
 * 1 / max|d| is the least |1/d|: no division of its own. */
static int setup_ray(const kd_tree *t, const double org[3], const double dir[3],
                     int skip, double tmin, double tmax, kd_ray *r)
{
    double m = t->scale, least = HUGE_VAL, ol[3], far = 0;
    int a;
    r->skip = skip;
    r->toff = 0;
    for (a = 0; a < MAILBOX; a++) r->mail[a] = -1;
    for (a = 0; a < 3; a++) {
        double d = dir[a];
        int neg = signbit(d) != 0;
        if (!(fabs(org[a]) <= DBL_MAX) || !isfinite(d)) return 0;
        if (fabs(org[a]) > m) m = fabs(org[a]);
        ol[a] = org[a] - t->c[a];
        if (fabs(ol[a]) > far) far = fabs(ol[a]);
        r->neg[a] = (uint32_t)neg;
        r->flat[a] = d == 0;
        r->inv[a] = d == 0 ? (neg ? -HUGE_VAL : HUGE_VAL) : 1.0 / d;
        if (fabs(r->inv[a]) < least) least = fabs(r->inv[a]);
    }
    r->slack = t->ulps * m * least;         /* +inf for a zero direction */
    if (!(r->slack >= 0)) r->slack = HUGE_VAL;
    tmin -= r->slack, tmax += r->slack;
    /* A far origin in the frame is rounded by a few eps m, across the ray
     * too: the box it is clipped to grows by as much. */
    r->delta = far > FAR_MOVE * t->ext ? t->delta + t->ulps * m : t->delta;
    if (!clip_ray(t, ol, tmin, tmax, r)) return 0;
    if (!(far > FAR_MOVE * t->ext)) return 1;
    r->delta = t->delta;
    r->toff = r->t0;
    for (a = 0; a < 3; a++) ol[a] = prims_along(org[a], t->c[a], r->toff, dir[a]);
    return clip_ray(t, ol, tmin - r->toff, tmax - r->toff, r);
}

/* The latest t of the walk's (see setup_ray) at which the point of a hit at
 * the caller's t may lie. */
static inline double reach(const kd_ray *r, double t)
{
    return t - r->toff + r->slack;
}

static void push(kd_todo *stack, int *n, uint32_t node, double t0, double t1)
{
    stack[*n].node = node, stack[*n].t0 = t0, stack[*n].t1 = t1;
    ++*n;
}

/* One inner node of Kaplan's near/far walk.  "near" is the child the ray
 * meets first (by the sign of its direction, so any tmin works): the walk
 * goes on into it, and remembers the far child if the ray reaches it too.
 * The ray crosses the plane at ts, give or take pad: it leaves the grown
 * near cell at ts + pad and enters the grown far cell at ts - pad.  A ray
 * parallel to the plane stays in the cell of its origin; if it lies in the
 * plane (or within delta of it) it runs along both cells, and both get the
 * whole stretch: a primitive touching the plane from one side is listed on
 * that side only, and the ray can hit it. */
static inline uint32_t step(const kd_node *nd, const kd_ray *r, double *t0,
                            double *t1, kd_todo *stack, int *n)
{
    int a = node_axis(nd);
    uint32_t near = node_index(nd) + r->neg[a];
    uint32_t far = node_index(nd) + 1 - r->neg[a];
    double ds = nd->u.split - r->org[a], ts, pad = r->pad[a];
    if (r->flat[a]) {
        if (fabs(ds) > r->delta) return node_index(nd) + (ds < 0);  /* origin's side */
        push(stack, n, far, *t0, *t1);
        return near;
    }
    ts = ds * r->inv[a];
    if (ts - pad > *t1) return near;  /* leaves the cell before the plane */
    if (ts + pad < *t0) return far;   /* crossed the plane before entering */
    push(stack, n, far, ts - pad > *t0 ? ts - pad : *t0, *t1);
    if (ts + pad < *t1) *t1 = ts + pad;
    return near;
}

/* Call the hit callback on a leaf's primitives.  Nearest: keep the lowest
 * t, and on equal t the lower primitive number, as the brute-force loop
 * would; the callback gets tmax = the best t so far, inclusive, so that it
 * reports such ties.  Any-hit: the first hit will do. */
static inline int test_leaf(const kd_tree *t, const kd_node *nd,
                            const prims *p, kd_ray *r, void *ray, double tmin,
                            int any, double *best_t, int best,
                            unsigned long long *tests)
{
    const int *list = t->prims + node_index(nd);
    uint32_t k, n = nd->u.count;
    for (k = 0; k < n; k++) {
        int i = list[k], *slot = &r->mail[i & (MAILBOX - 1)];
        double th;
        if (i == r->skip || *slot == i) continue;
        *slot = i;
        ++*tests;
        if (!p->hit(p->user, i, ray, tmin, *best_t, &th)) continue;
        if (any) return i;
        if (th < *best_t || (th == *best_t && (best < 0 || i < best)))
            *best_t = th, best = i;
    }
    return best;
}

/* Take the next cell from the stack, skipping those the ray enters only
 * beyond the best hit: no primitive there can be hit before it, as every
 * hit point lies in a (grown) cell listing its primitive.  This is Kaplan's
 * rule "stop once the hit lies inside the cell just searched", as then every
 * cell left lies beyond it; a hit found in a leaf but lying past that leaf's
 * exit does not stop the walk, and stays the best so far.  Cells are checked
 * one by one rather than all dropped at once because a ray lying in a plane
 * leaves cells on the stack that it enters as early as the current one.
 * Returns -1 when no cell is left. */
static inline long pop(const kd_todo *stack, int *n, double best_t)
{
    while (*n > 0) {
        --*n;
        if (!(best_t < stack[*n].t0)) return *n;
    }
    return -1;
}

/* The slide's TreeIntersect(R, W), recursive: w is node W with the stretch
 * of the ray R inside it.  step returns the side to enter first (W.far
 * itself when R1 is empty) and, when R reaches both, hands over the far side
 * in a stack of one; pop says whether to visit it.  any = 1 stops at the
 * first hit. */
static int tree_intersect(const kd_tree *t, const prims *p, kd_ray *r,
                          void *ray, double tmin, int any, kd_todo w,
                          double *best_t, int best, prim_counters *c)
{
    const kd_node *nd = &t->nodes[w.node];
    kd_todo far;
    int n = 0;
    c->steps++;
    if (node_axis(nd) == (int)LEAF)
        return test_leaf(t, nd, p, r, ray, tmin, any, best_t, best, &c->tests);
    w.node = step(nd, r, &w.t0, &w.t1, &far, &n);
    best = tree_intersect(t, p, r, ray, tmin, any, w, best_t, best, c);
    if ((any && best >= 0) || pop(&far, &n, reach(r, *best_t)) < 0) return best;
    return tree_intersect(t, p, r, ray, tmin, any, far, best_t, best, c);
}

/* The walk shared by kd_nearest (any = 0) and kd_any (any = 1): the fast
 * path.  It is tree_intersect with the recursion turned into a loop: the
 * far sides wait on a stack, so it visits the same cells in the same order
 * (near before far, depth first) and makes the same tests.  step, test_leaf
 * and pop are declared inline for it: with tree_intersect as a second
 * caller, gcc -O2 would otherwise call them out of line here, at every
 * node. */
static int walk(const kd_tree *t, const prims *p, kd_ray *r,
                void *ray, double tmin, int any, double *best_t,
                prim_counters *c)
{
    kd_todo stack[STACK_SIZE];
    int n = 0, best = -1;
    uint32_t node = 0;
    double t0 = r->t0, t1 = r->t1;
    unsigned long long steps = 0, tests = 0;
    for (;;) {
        const kd_node *nd = &t->nodes[node];
        long next;
        steps++;
        if (node_axis(nd) != (int)LEAF) {
            node = step(nd, r, &t0, &t1, stack, &n);
            continue;
        }
        best = test_leaf(t, nd, p, r, ray, tmin, any, best_t, best, &tests);
        if (any && best >= 0) break;
        next = pop(stack, &n, reach(r, *best_t));
        if (next < 0) break;
        node = stack[next].node, t0 = stack[next].t0, t1 = stack[next].t1;
    }
    if (c) c->steps += steps, c->tests += tests;
    return best;
}

int kd_nearest(const kd_tree *t, const prims *p, const double org[3],
               const double dir[3], void *ray, int skip, double tmin,
               double *tmax, prim_counters *c)
{
    kd_ray r;
    double best_t = *tmax;
    int i;
    if (c) c->rays++;
    if (!t || !setup_ray(t, org, dir, skip, tmin, *tmax, &r)) return -1;
    i = walk(t, p, &r, ray, tmin, 0, &best_t, c);
    if (i >= 0) *tmax = best_t;
    return i;
}

int kd_any(const kd_tree *t, const prims *p, const double org[3],
           const double dir[3], void *ray, int skip, double tmin, double tmax,
           prim_counters *c)
{
    kd_ray r;
    if (c) c->rays++;
    if (!t || !setup_ray(t, org, dir, skip, tmin, tmax, &r)) return -1;
    return walk(t, p, &r, ray, tmin, 1, &tmax, c);
}

int kd_intersect_recursive(const kd_tree *t, const prims *p,
                           const double org[3], const double dir[3],
                           void *ray, int skip, double tmin, double *tmax,
                           int any, prim_counters *c)
{
    prim_counters none = {0, 0, 0};
    kd_todo root = {0, 0, 0};
    kd_ray r;
    double best_t = *tmax;
    int i;
    if (!c) c = &none;
    c->rays++;
    if (!t || !setup_ray(t, org, dir, skip, tmin, *tmax, &r)) return -1;
    root.t0 = r.t0, root.t1 = r.t1;
    i = tree_intersect(t, p, &r, ray, tmin, any, root, &best_t, -1, c);
    if (i >= 0) *tmax = best_t;
    return i;
}

/* ---- boxes -------------------------------------------------------------- */

/* Boxes are kept in float, the precision of the split planes, in the
 * tree's frame (see RAY_EPS), rounded to nearest.  Two triangles sharing an edge at x = 1/3, a number no float
 * holds, then end and start at the same float, and a plane there parts them
 * cleanly.  Rounded outwards instead, their boxes would overlap by one
 * float step, and every plane through a mesh's vertices would cut the
 * triangles on one side and copy them to both: more references, more nodes
 * and more tests per ray.  The half step a primitive may stick out of its
 * cells when rounded to nearest is what the traversal's margin (RAY_EPS)
 * covers. */
typedef struct {
    float lo[3], hi[3];
} kd_box;

/* Coordinates beyond the float range are clamped to it; a primitive that
 * reaches out there (an infinite plane, say) is not supported. */
static float to_float(double x)
{
    return x > FLT_MAX ? FLT_MAX : x < -FLT_MAX ? -FLT_MAX : (float)x;
}

/* Box of lo..hi (the caller's coordinates) in the frame centred on c.  0
 * for NaN or lo > hi: such a primitive has no place in space and is left
 * out of the tree. */
static int make_box(const double lo[3], const double hi[3], const double c[3], kd_box *b)
{
    int a;
    for (a = 0; a < 3; a++) {
        if (!(lo[a] <= hi[a])) return 0;
        b->lo[a] = to_float(lo[a] - c[a]);
        b->hi[a] = to_float(hi[a] - c[a]);
    }
    return 1;
}

static double box_area(const kd_box *b)
{
    double dx = (double)b->hi[0] - b->lo[0];
    double dy = (double)b->hi[1] - b->lo[1];
    double dz = (double)b->hi[2] - b->lo[2];
    return 2 * (dx * dy + dy * dz + dz * dx);
}

static float clampf(float x, float lo, float hi)
{
    return x < lo ? lo : x > hi ? hi : x;
}

/* ---- events (Wald & Havran 2006) --------------------------------------- */

/* At one position, ends sort before planar primitives before starts: the
 * sweep must have counted what ends at p before it prices p. */
enum { END = 0, PLANAR = 1, START = 2 };

/* An event in 8 bytes: the position, and in `key` the type (the top 2 bits)
 * over the primitive's number (the low 30; kd_build takes at most 2^30
 * primitives).  The events are most of the build's memory: six per
 * primitive at the root. */
typedef struct {
    float pos;
    uint32_t key;
} kd_event;

static uint32_t ev_key(int type, int prim) { return (uint32_t)type << 30 | (uint32_t)prim; }
static int ev_type(const kd_event *e) { return (int)(e->key >> 30); }
static int ev_prim(const kd_event *e) { return (int)(e->key & MAX_INDEX); }

/* The events of one node, one list per axis, each sorted.  The root's lists
 * (and the few fresh events of a split) are blocks of their own: own = 1.
 * Every other node's lie on one of the builder's two stacks (`on`; see
 * split_lists), where at[] says where; ev[] points there only until the
 * stack moves (it may move when it grows), and attach() sets it again. */
typedef struct {
    kd_event *ev[3];
    long at[3], n[3];
    long count;  /* primitives in the node */
    int own, on;
} kd_list;

/* By position, then type, then primitive number (the key): a total order
 * gives the same list whatever qsort does with equal keys, so the build is
 * deterministic. */
static int event_cmp(const void *pa, const void *pb)
{
    const kd_event *a = pa, *b = pb;
    if (a->pos != b->pos) return a->pos < b->pos ? -1 : 1;
    return (a->key > b->key) - (a->key < b->key);
}

/* Byte d (0 the lowest) of an event's place in event_cmp's order: the key
 * in bytes 0-3, the position in 4-7, its bits turned so that they order as
 * the numbers do (-0 taken as +0, as event_cmp takes them). */
static unsigned event_byte(const kd_event *e, int d)
{
    uint32_t u;
    if (d < 4) return e->key >> 8 * d & 255;
    memcpy(&u, &e->pos, sizeof u);
    if (u == 0x80000000u) u = 0;
    u = u & 0x80000000u ? ~u : u | 0x80000000u;
    return u >> 8 * (d - 4) & 255;
}

/* Sort events in event_cmp's order.  Long lists by radix, a byte a pass,
 * the lowest first, in time linear in their length: qsort's calls of
 * event_cmp took 40% of the build of a 50k-triangle fan, where almost
 * every split cuts almost every primitive and their fresh events must all
 * be sorted.  0 when out of memory. */
static int sort_events(kd_event *e, long n)
{
    kd_event *tmp, *from = e, *to;
    long count[256], i;
    int d, k;
    if (n < 64) {  /* by insertion: the order is total, so the same list */
        for (i = 1; i < n; i++) {
            kd_event x = e[i];
            long j = i;
            for (; j > 0 && event_cmp(&x, &e[j - 1]) < 0; j--) e[j] = e[j - 1];
            e[j] = x;
        }
        return 1;
    }
    to = tmp = malloc(n * sizeof *e);
    if (!tmp) return 0;
    for (d = 0; d < 8; d++) {
        long sum = 0;
        memset(count, 0, sizeof count);
        for (i = 0; i < n; i++) count[event_byte(&from[i], d)]++;
        if (count[event_byte(&from[0], d)] == n) continue;  /* all alike */
        for (k = 0; k < 256; k++) {
            long c = count[k];
            count[k] = sum, sum += c;
        }
        for (i = 0; i < n; i++) to[count[event_byte(&from[i], d)]++] = from[i];
        to = from, from = to == e ? tmp : e;
    }
    if (from != e) memcpy(e, from, n * sizeof *e);
    free(tmp);
    return 1;
}

/* A zero-thickness box gives one PLANAR event instead of a start and an end
 * at the same place: the sweep then knows it lies in the plane itself. */
static void add_events(kd_event *ev[3], long n[3], int prim, const kd_box *b)
{
    int a;
    for (a = 0; a < 3; a++) {
        kd_event *e = ev[a] + n[a];
        if (b->lo[a] == b->hi[a]) {
            e[0].pos = b->lo[a], e[0].key = ev_key(PLANAR, prim);
            n[a] += 1;
        } else {
            e[0].pos = b->lo[a], e[0].key = ev_key(START, prim);
            e[1].pos = b->hi[a], e[1].key = ev_key(END, prim);
            n[a] += 2;
        }
    }
}

/* Only for lists of their own (own = 1). */
static void free_list(kd_list *L)
{
    int a;
    for (a = 0; a < 3; a++) free(L->ev[a]), L->ev[a] = NULL;
}

static int alloc_list(kd_list *L, long cap)
{
    int a;
    for (a = 0; a < 3; a++) {
        L->ev[a] = malloc((cap > 0 ? cap : 1) * sizeof(kd_event));
        L->n[a] = 0;
    }
    L->count = 0;
    L->own = 1;
    if (L->ev[0] && L->ev[1] && L->ev[2]) return 1;
    free_list(L);
    return 0;
}

/* ---- the builder -------------------------------------------------------- */

/* Where a primitive goes when a node is split: LEFT, RIGHT, or BOTH when the
 * plane cuts it; the cut ones are then numbered 0, 1, ... (see number_cut). */
enum { LEFT = -1, RIGHT = -2, BOTH = -3 };

typedef struct {
    const prims *p;
    double c[3];          /* the frame (see RAY_EPS) */
    double wlo[3], whi[3];  /* the scene box in the caller's coordinates */
    kd_node *nodes;
    long nnodes, node_cap;
    int *refs;
    long nrefs, ref_cap;
    int *side;            /* per primitive, while splitting one node */
    kd_event *stack[2];   /* the nodes' lists, see split_lists */
    long top[2], stack_cap[2];  /* events in use on each stack, and room */
    int max_depth;
    double root_area;
    double pool;          /* budget left unspent by finished subtrees */
    kd_info info;
    int failed;           /* out of memory, or more than 2^30 nodes */
} kd_builder;

typedef struct {
    int found, axis, planar_left;
    float pos;
    double cost;
    long nl, nr;  /* primitives on each side, by their boxes */
} kd_split;

/* Surface area of a box with sides dx, dy, dz: box_area's own sum. */
static double area3(double dx, double dy, double dz)
{
    return 2 * (dx * dy + dy * dz + dz * dx);
}

/* The two children's areas when v is cut on `axis` at pos.  The sweep asks
 * at every event, so v's sides come once per axis in d (d[i] = hi - lo, in
 * double) and only the cut side changes: the same sums, in the same order,
 * as box_area of the children, so the same bits. */
static void child_areas(const kd_box *v, const double d[3], int axis, float pos,
                        double *al, double *ar)
{
    double l = (double)pos - v->lo[axis], r = (double)v->hi[axis] - pos;
    if (axis == 0) *al = area3(l, d[1], d[2]), *ar = area3(r, d[1], d[2]);
    else if (axis == 1) *al = area3(d[0], l, d[2]), *ar = area3(d[0], r, d[2]);
    else *al = area3(d[0], d[1], l), *ar = area3(d[0], d[1], r);
}

/* Expected cost of a cut whose children have areas al and ar and hold nl
 * and nr primitives, in a cell of the given area. */
static double sah(double al, double ar, long nl, long nr, double area)
{
    double cost = COST_STEP + COST_TEST * (al * nl + ar * nr) / area;
    return nl == 0 || nr == 0 ? cost * EMPTY_BONUS : cost;
}

static void offer(kd_split *best, int axis, float pos, double cost, int planar_left,
                  long nl, long nr)
{
    if (cost < best->cost) {
        best->found = 1, best->axis = axis, best->pos = pos;
        best->cost = cost, best->planar_left = planar_left;
        best->nl = nl, best->nr = nr;
    }
}

/* Price one plane twice, with the primitives lying in it on either side
 * (Wald & Havran 2006 keep the cheaper; on a tie, left). */
static void consider(kd_split *best, const kd_box *v, const double d[3], int axis,
                     float pos, long nl, long np, long nr, double area)
{
    double al, ar, left, right;
    child_areas(v, d, axis, pos, &al, &ar);
    left = sah(al, ar, nl + np, nr, area);
    right = np > 0 ? sah(al, ar, nl, np + nr, area) : left;  /* the same sum */
    if (left <= right) offer(best, axis, pos, left, 1, nl + np, nr);
    else offer(best, axis, pos, right, 0, nl, np + nr);
}

/* A plane on a face of the cell, with primitives lying in it: a floor at
 * the bottom of the scene, a wall at its side.  The child on the outer side
 * is flat, without volume, and holds just them; the other child is the
 * whole cell without them.  Rays that merely pass through the cell then no
 * longer test them, only rays that reach the face.  That is why such a
 * plane is priced, though well_inside (below) leaves other planes on a
 * face out. */
static void consider_face(kd_split *best, const kd_box *v, const double d[3],
                          int axis, float pos, long nl, long np, long nr, double area)
{
    double al, ar;
    child_areas(v, d, axis, pos, &al, &ar);
    if (pos == v->lo[axis])
        offer(best, axis, pos, sah(al, ar, nl + np, nr, area), 1, nl + np, nr);
    else
        offer(best, axis, pos, sah(al, ar, nl, np + nr, area), 0, nl, np + nr);
}

/* Other planes on or within a few float steps of a face of the cell are
 * left out.  On the face, they would leave one child without volume.  Near
 * it, they would cut off a sliver that exists only because of rounding (a
 * primitive's box rounded to the next float).  A sliver has almost no
 * surface area, so the SAH would take it as free and pile the primitives
 * touching it into it, level after level, many times over. */
static int well_inside(float pos, float lo, float hi)
{
    double gap = (fabs(lo) > fabs(hi) ? fabs(lo) : fabs(hi)) / (1 << 20);
    return pos - (double)lo > gap && (double)hi - pos > gap;
}

/* The sweep: walking the sorted events, nl counts the primitives wholly
 * left of the current position and nr those not yet ended. */
static void sweep(const kd_list *L, int axis, const kd_box *v, double area,
                  kd_split *best)
{
    const kd_event *e = L->ev[axis];
    long n = L->n[axis], i = 0, nl = 0, nr = L->count;
    double d[3];
    int k;
    for (k = 0; k < 3; k++) d[k] = (double)v->hi[k] - v->lo[k];
    while (i < n) {
        float pos = e[i].pos;
        long ends = 0, planars = 0, starts = 0;
        for (; i < n && e[i].pos == pos && ev_type(&e[i]) == END; i++) ends++;
        for (; i < n && e[i].pos == pos && ev_type(&e[i]) == PLANAR; i++) planars++;
        for (; i < n && e[i].pos == pos && ev_type(&e[i]) == START; i++) starts++;
        nr -= ends + planars;
        if (well_inside(pos, v->lo[axis], v->hi[axis]))
            consider(best, v, d, axis, pos, nl, planars, nr, area);
        else if (planars > 0 && v->lo[axis] < v->hi[axis]
                 && (pos == v->lo[axis] || pos == v->hi[axis]))
            consider_face(best, v, d, axis, pos, nl, planars, nr, area);
        nl += starts + planars;
    }
}

static kd_split find_split(const kd_list *L, const kd_box *v)
{
    kd_split best;
    double area = box_area(v);
    int a;
    best.found = 0, best.axis = 0, best.planar_left = 1;
    best.pos = 0, best.cost = HUGE_VAL, best.nl = best.nr = 0;
    if (!(area > 0)) return best;  /* a line or a point: nothing to cut */
    for (a = 0; a < 3; a++) sweep(L, a, v, area, &best);
    return best;
}

/* Which side of the plane each primitive goes to.  A box ending at the
 * plane goes left, one starting at it right; one lying in it goes where the
 * SAH put it; one crossing it goes to both. */
static void classify(kd_builder *b, const kd_list *L, const kd_split *s)
{
    const kd_event *e = L->ev[s->axis];
    long n = L->n[s->axis], i;
    for (i = 0; i < n; i++) b->side[ev_prim(&e[i])] = BOTH;
    for (i = 0; i < n; i++) {
        int type = ev_type(&e[i]), *side = &b->side[ev_prim(&e[i])];
        if (type == END && e[i].pos <= s->pos) *side = LEFT;
        else if (type == START && e[i].pos >= s->pos) *side = RIGHT;
        else if (type == PLANAR) {
            if (e[i].pos < s->pos) *side = LEFT;
            else if (e[i].pos > s->pos) *side = RIGHT;
            else *side = s->planar_left ? LEFT : RIGHT;
        }
    }
}

/* Number the cut primitives 0, 1, ... in the order of their first events
 * on axis 0, the order cut_events meets them in; side[] then holds the
 * number, their place in the array of their boxes.  Returns how many. */
static long number_cut(kd_builder *b, const kd_list *L)
{
    long i, k = 0;
    for (i = 0; i < L->n[0]; i++) {
        const kd_event *e = &L->ev[0][i];
        if (ev_type(e) != END && b->side[ev_prim(e)] == BOTH) b->side[ev_prim(e)] = (int)k++;
    }
    return k;
}

/* Read back the box, inside this node, of each primitive that the plane
 * cuts: its events are all there is.  Boxes are only kept for those, not
 * for every primitive: at 1M triangles that is 24 MB less. */
static void recall_boxes(const kd_builder *b, const kd_list *L, kd_box *cut)
{
    int a;
    long i;
    for (a = 0; a < 3; a++) {
        for (i = 0; i < L->n[a]; i++) {
            const kd_event *e = &L->ev[a][i];
            int k = b->side[ev_prim(e)];
            if (k < 0) continue;  /* not cut */
            if (ev_type(e) != END) cut[k].lo[a] = e->pos;
            if (ev_type(e) != START) cut[k].hi[a] = e->pos;
        }
    }
}

/* The part of a cut primitive inside one child cell.  With a clip callback
 * this is the box of the primitive's geometry inside the cell, which can be
 * far smaller than the box cut down ("perfect splits", Havran 2000); the
 * result is kept inside the old box and the cell, for safety against a
 * callback's rounding.  0 when nothing of the primitive is in the cell.
 * The callback is shown the cell grown by two float steps: a primitive that
 * rounding to nearest put in this cell may lie up to half a step outside
 * it, and must not be dropped for that.  The cell goes to the caller's
 * coordinates in one rounded addition, which cannot cross a coordinate of
 * the caller's (rounding is monotonic), so it still holds whatever it held. */
typedef struct {
    kd_box box;                /* the child cell, in the frame */
    double lo[3], hi[3];       /* grown by two float steps, in the caller's coordinates */
} kd_cell;

static void grow_cell(const kd_builder *b, const kd_box *cell, kd_cell *out)
{
    int a;
    out->box = *cell;
    for (a = 0; a < 3; a++) {
        out->lo[a] = b->c[a] + nextafterf(nextafterf(cell->lo[a], -FLT_MAX), -FLT_MAX);
        out->hi[a] = b->c[a] + nextafterf(nextafterf(cell->hi[a], FLT_MAX), FLT_MAX);
    }
}

static int clip_prim(const kd_builder *b, int prim, const kd_box *box,
                     const kd_cell *grown, kd_box *out)
{
    const kd_box *cell = &grown->box;
    kd_box old = *box;
    int a;
    for (a = 0; a < 3; a++) {
        old.lo[a] = old.lo[a] > cell->lo[a] ? old.lo[a] : cell->lo[a];
        old.hi[a] = old.hi[a] < cell->hi[a] ? old.hi[a] : cell->hi[a];
    }
    *out = old;
    if (b->p->clip) {
        double lo[3], hi[3];
        if (!b->p->clip(b->p->user, prim, grown->lo, grown->hi, lo, hi)) return 0;
        if (!make_box(lo, hi, b->c, out)) return 1;  /* NaN: keep the old box */
        for (a = 0; a < 3; a++) {
            out->lo[a] = clampf(out->lo[a], old.lo[a], old.hi[a]);
            out->hi[a] = clampf(out->hi[a], old.lo[a], old.hi[a]);
        }
    }
    return 1;
}

/* Merge the events of the primitives that went wholly to one side (already
 * sorted) with the fresh events of the cut primitives (sorted here), for
 * both children in one pass over the node's events. */
static void merge(const kd_event *old, long n, const int *side,
                  const kd_list *fl, const kd_list *fr, int a, kd_list *left,
                  kd_list *right)
{
    const kd_event *f[2];
    kd_event *out[2];
    long nf[2], j[2] = { 0, 0 }, k[2] = { 0, 0 }, i;
    int c;
    f[0] = fl->ev[a], nf[0] = fl->n[a], out[0] = left->ev[a];
    f[1] = fr->ev[a], nf[1] = fr->n[a], out[1] = right->ev[a];
    for (i = 0; i < n; i++) {
        int sd = side[ev_prim(&old[i])];
        if (sd != LEFT && sd != RIGHT) continue;
        c = sd == RIGHT;
        while (j[c] < nf[c] && event_cmp(&f[c][j[c]], &old[i]) < 0) out[c][k[c]++] = f[c][j[c]++];
        out[c][k[c]++] = old[i];
    }
    for (c = 0; c < 2; c++)
        while (j[c] < nf[c]) out[c][k[c]++] = f[c][j[c]++];
    left->n[a] = k[0], right->n[a] = k[1];
}

/* Events for the cut primitives, clipped to each child: the only events
 * that need sorting after the first sort (Wald & Havran 2006).  cut[k] is
 * the box of the cut primitive numbered k. */
static int cut_events(const kd_builder *b, const kd_list *L, const kd_box *cut,
                      long ncut, const kd_box *vl, const kd_box *vr, kd_list *fl,
                      kd_list *fr)
{
    const kd_event *e = L->ev[0];
    long i;
    int a;
    kd_cell gl, gr;
    grow_cell(b, vl, &gl), grow_cell(b, vr, &gr);
    if (!alloc_list(fl, 2 * ncut)) return 0;
    if (!alloc_list(fr, 2 * ncut)) return free_list(fl), 0;
    for (i = 0; i < L->n[0]; i++) {
        int prim = ev_prim(&e[i]), k = b->side[prim];
        kd_box box;
        if (ev_type(&e[i]) == END || k < 0) continue;
        if (clip_prim(b, prim, &cut[k], &gl, &box))
            add_events(fl->ev, fl->n, prim, &box), fl->count++;
        if (clip_prim(b, prim, &cut[k], &gr, &box))
            add_events(fr->ev, fr->n, prim, &box), fr->count++;
    }
    for (a = 0; a < 3; a++)
        if (!sort_events(fl->ev[a], fl->n[a]) || !sort_events(fr->ev[a], fr->n[a])) {
            free_list(fl), free_list(fr);
            return 0;
        }
    return 1;
}

/* Events of the primitives going wholly to each side, on axis a: n[0]
 * left, n[1] right; on axis 0 also the primitives themselves (their starts
 * and planars) in prims[0] and prims[1]. */
static void count_sides(const kd_builder *b, const kd_list *L, int a, long n[2],
                        long prims[2])
{
    long i;
    n[0] = n[1] = prims[0] = prims[1] = 0;
    for (i = 0; i < L->n[a]; i++) {
        const kd_event *e = &L->ev[a][i];
        int sd = b->side[ev_prim(e)];
        if (sd != LEFT && sd != RIGHT) continue;
        n[sd == RIGHT]++;
        prims[sd == RIGHT] += ev_type(e) != END;
    }
}

/* Point ev[] at the list's place on its stack, wherever the stack is now. */
static void attach(const kd_builder *b, kd_list *L)
{
    int a;
    if (!L->own)
        for (a = 0; a < 3; a++) L->ev[a] = b->stack[L->on] + L->at[a];
}

/* Give up a list: free it, or pop it off its stack, whose top it is.  When
 * the stack is less than half full its tail is handed back, so that the
 * room the first levels needed is not kept while the tree grows (glibc
 * returns the pages of a big block that shrinks; at 1M triangles that took
 * the peak from 104 to 92 bytes a triangle). */
static void drop(kd_builder *b, kd_list *L)
{
    if (L->own) {
        free_list(L);
        return;
    }
    b->top[L->on] = L->at[0];
    if (b->top[L->on] < b->stack_cap[L->on] / 2 && b->stack_cap[L->on] > 65536) {
        long cap = b->top[L->on] + b->top[L->on] / 4 + 1024;
        kd_event *shrunk = realloc(b->stack[L->on], cap * sizeof(kd_event));
        if (shrunk) b->stack[L->on] = shrunk, b->stack_cap[L->on] = cap;
    }
}

/* Room on stack `on` for `need` events.  A quarter more is asked for, so
 * that it seldom moves; room not yet written to costs address space, not
 * memory, on systems that map pages as they are first written (Linux and
 * the BSDs do, for big blocks). */
static int reserve(kd_builder *b, int on, long need)
{
    kd_event *grown;
    long cap = need + need / 4 + 1024;
    if (need <= b->stack_cap[on]) return 1;
    grown = realloc(b->stack[on], cap * sizeof(kd_event));
    if (!grown) return 0;
    b->stack[on] = grown, b->stack_cap[on] = cap;
    return 1;
}

/* Split the sorted event lists of a node into sorted lists for its two
 * children in time linear in their length (plus the sort of the few cut
 * primitives).
 *
 * Memory.  The lists are most of the build's memory, and the build walks
 * depth first, so they live on two stacks, one level of the tree on one,
 * the next on the other: a node's list is on top of one when it is split;
 * its children's lists are pushed on the other, the right child's below
 * the left's, and the node's is popped.  The left child is built next and
 * its subtree pops everything it pushed; then the right child's list is on
 * top.  (On one stack the children's lists would have to be moved down
 * over their parent's, one more pass over them.)  Nothing is left in
 * holes, as a block for each list leaves them in the C library's heap (at
 * 1M triangles glibc kept 74 MB of such holes, resident, to the end of the
 * build).  The root's lists are blocks of their own, freed axis by axis as
 * the children's are made: the peak is the root's events and a third
 * more, not twice them. */
static int split_lists(kd_builder *b, kd_list *L, const kd_split *s,
                       const kd_box *vl, const kd_box *vr, kd_list *left,
                       kd_list *right)
{
    kd_list fl, fr;
    kd_box *cut;
    long ncut, nl[3], nr[3], from, to, total = 0;
    int on = L->own ? 0 : !L->on;  /* the children's lists go on the other stack */
    int a, ok;
    classify(b, L, s);
    ncut = number_cut(b, L);
    cut = malloc((ncut + 1) * sizeof(kd_box));
    if (!cut) return 0;
    recall_boxes(b, L, cut);
    ok = cut_events(b, L, cut, ncut, vl, vr, &fl, &fr);
    free(cut);
    if (!ok) return 0;
    for (a = 0; a < 3; a++) {
        long n[2], prims[2];
        count_sides(b, L, a, n, prims);
        if (a == 0) left->count = prims[0] + fl.count, right->count = prims[1] + fr.count;
        nl[a] = n[0] + fl.n[a];
        nr[a] = n[1] + fr.n[a];
        total += nl[a] + nr[a];
    }
    from = b->top[on];
    if (!reserve(b, on, from + total)) {
        free_list(&fl), free_list(&fr);
        return 0;
    }
    attach(b, L);
    for (a = 0, to = from; a < 3; a++) right->at[a] = to, to += nr[a];
    for (a = 0; a < 3; a++) left->at[a] = to, to += nl[a];
    left->own = right->own = 0;
    left->on = right->on = on;
    attach(b, left), attach(b, right);
    for (a = 0; a < 3; a++) {
        merge(L->ev[a], L->n[a], b->side, &fl, &fr, a, left, right);
        if (L->own) free(L->ev[a]), L->ev[a] = NULL;
    }
    free_list(&fl), free_list(&fr);
    b->top[on] = from + total;
    drop(b, L);
    return 1;
}

/* ---- nodes and leaves --------------------------------------------------- */

/* Room for two adjacent nodes, the children of one inner node. */
static long new_pair(kd_builder *b)
{
    long at = b->nnodes;
    if (at + 2 > (long)MAX_INDEX) return b->failed = 1, -1;
    if (at + 2 > b->node_cap) {
        long cap = 2 * b->node_cap + 16;
        kd_node *grown = realloc(b->nodes, cap * sizeof(kd_node));
        if (!grown) return b->failed = 1, -1;
        b->nodes = grown, b->node_cap = cap;
    }
    b->nnodes += 2;
    return at;
}

static int int_cmp(const void *pa, const void *pb)
{
    int a = *(const int *)pa, b = *(const int *)pb;
    return (a > b) - (a < b);
}

/* Most leaves hold a few primitives: sorted by insertion, without qsort's
 * calls through a pointer. */
static void sort_few(int *v, long n)
{
    long i, j;
    for (i = 1; i < n; i++) {
        int x = v[i];
        for (j = i; j > 0 && v[j - 1] > x; j--) v[j] = v[j - 1];
        v[j] = x;
    }
}

/* A leaf lists its primitives in increasing order: deterministic, and kind
 * to the caches when primitives are stored in a sensible order. */
static void make_leaf(kd_builder *b, long at, const kd_list *L)
{
    const kd_event *e = L->ev[0];
    long i, start = b->nrefs;
    if (start + L->count > (long)MAX_INDEX) {
        b->failed = 1;
        return;
    }
    if (start + L->count > b->ref_cap) {
        long cap = 2 * b->ref_cap + L->count + 16;
        int *grown = realloc(b->refs, cap * sizeof(int));
        if (!grown) {
            b->failed = 1;
            return;
        }
        b->refs = grown, b->ref_cap = cap;
    }
    for (i = 0; i < L->n[0]; i++)
        if (ev_type(&e[i]) != END) b->refs[b->nrefs++] = ev_prim(&e[i]);
    if (L->count > 16) qsort(b->refs + start, L->count, sizeof(int), int_cmp);
    else if (L->count > 1) sort_few(b->refs + start, L->count);  /* refs may still be NULL */
    b->nodes[at].u.count = (uint32_t)L->count;
    b->nodes[at].bits = (uint32_t)start << 2 | LEAF;
}

/* The shape and SAH cost of the tree, gathered as it is built. */
static void note_node(kd_builder *b, const kd_box *v, int depth, long leaf_prims)
{
    double weight = b->root_area > 0 ? box_area(v) / b->root_area : 1.0;
    b->info.nodes++;
    if (depth > b->info.max_depth) b->info.max_depth = depth;
    if (leaf_prims < 0) {
        b->info.sah_cost += COST_STEP * weight;
        return;
    }
    b->info.leaves++;
    b->info.empty_leaves += leaf_prims == 0;
    b->info.prim_refs += leaf_prims;
    b->info.sah_cost += COST_TEST * leaf_prims * weight;
}

/* Build the subtree of node `at` over the events L (which it frees) in cell
 * v, with `budget` to spend (see BUDGET).  A node becomes a leaf when
 *   - it holds no primitive: nothing to gain;
 *   - it is at the depth limit, 8 + 1.3 log2 N: a guard against piles of
 *     overlapping primitives that no plane separates, where each split would
 *     copy them all to both sides (the rule of thumb of Pharr & Humphreys'
 *     pbrt); it also bounds the traversal's stack;
 *   - no candidate plane lies well inside the cell (see well_inside);
 *   - the best split costs at least as much as the leaf (COST_TEST * n): the
 *     automatic termination of the SAH (Wald & Havran 2006), or
 *   - its budget and the pool cannot pay for the children. */
static void build_node(kd_builder *b, long at, kd_list *L, const kd_box *v,
                       int depth, double budget)
{
    kd_split s;
    kd_list left, right;
    kd_box vl = *v, vr = *v;
    long child;
    double need, share;
    attach(b, L);
    s.found = 0, s.nl = s.nr = 0;
    if (L->count > 0 && depth < b->max_depth) s = find_split(L, v);
    need = (double)s.nl + s.nr + 2;  /* what the children would cost */
    if (!s.found || s.cost >= COST_TEST * L->count || need > budget + b->pool) {
        note_node(b, v, depth, L->count);
        make_leaf(b, at, L);
        drop(b, L);
        b->pool += budget - (L->count + 1);
        return;
    }
    if (need > budget) b->pool -= need - budget, budget = need;
    vl.hi[s.axis] = s.pos;
    vr.lo[s.axis] = s.pos;
    if (!split_lists(b, L, &s, &vl, &vr, &left, &right)) {
        b->failed = 1;
        drop(b, L);
        return;
    }
    child = new_pair(b);
    if (child < 0) return;
    note_node(b, v, depth, -1);
    b->nodes[at].u.split = s.pos;
    b->nodes[at].bits = (uint32_t)child << 2 | (uint32_t)s.axis;
    share = floor(budget * (left.count + 1) / (left.count + right.count + 2));
    build_node(b, child, &left, &vl, depth + 1, share);
    build_node(b, child + 1, &right, &vr, depth + 1, budget - share);
}

/* The events of all primitives, sorted once: the only full sort. */
static int root_list(kd_builder *b, int n, kd_list *L, kd_box *scene)
{
    int i, a;
    memset(scene, 0, sizeof *scene);
    if (!alloc_list(L, 2 * (long)n)) return 0;
    prims_frame(b->p, n, 1, b->wlo, b->whi, b->c);   /* one more call of bounds per primitive */
    for (i = 0; i < n; i++) {
        double lo[3], hi[3];
        kd_box box;
        b->p->bounds(b->p->user, i, lo, hi);
        if (!make_box(lo, hi, b->c, &box)) continue;
        for (a = 0; a < 3; a++) {
            if (L->count == 0 || box.lo[a] < scene->lo[a]) scene->lo[a] = box.lo[a];
            if (L->count == 0 || box.hi[a] > scene->hi[a]) scene->hi[a] = box.hi[a];
        }
        add_events(L->ev, L->n, i, &box);
        L->count++;
    }
    for (a = 0; a < 3; a++)
        if (!sort_events(L->ev[a], L->n[a])) return free_list(L), 0;
    return 1;
}

/* Move nodes and lists into one block: one allocation to free, one range of
 * memory for the traversal, and a single byte string to compare.  The
 * nodes' array is grown to take the lists rather than copied: a copy of
 * both would be the build's peak of memory. */
static kd_tree *finish(kd_builder *b, const kd_box *scene)
{
    kd_tree *t = malloc(sizeof *t);
    size_t nb = b->nnodes * sizeof(kd_node), rb = b->nrefs * sizeof(int);
    int a;
    if (!t) return NULL;
    t->nodes = realloc(b->nodes, nb + rb);
    if (!t->nodes) return free(t), NULL;
    b->nodes = NULL;  /* now the tree's */
    t->prims = (int *)(t->nodes + b->nnodes);
    if (rb) memcpy(t->prims, b->refs, rb);
    t->bytes = nb + rb;
    t->scale = t->ext = 0;
    for (a = 0; a < 3; a++) {
        t->c[a] = b->c[a];
        t->lo[a] = scene->lo[a], t->hi[a] = scene->hi[a];
        t->ext = fmax(t->ext, fmax(fabs(t->lo[a]), fabs(t->hi[a])));
        t->scale = fmax(t->scale, fmax(fabs(b->wlo[a]), fabs(b->whi[a])));
    }
    t->ulps = PRIMS_HIT_ULPS * (b->p->eps > 0 ? b->p->eps : DBL_EPSILON);
    t->delta = RAY_EPS * t->ext + t->ulps * t->scale;
    t->info = b->info;
    t->info.bytes = t->bytes;
    t->info.prims_per_leaf = t->info.leaves > t->info.empty_leaves
        ? (double)t->info.prim_refs / (t->info.leaves - t->info.empty_leaves) : 0;
    return t;
}

kd_tree *kd_build(int n, const prims *p)
{
    clock_t start = clock();
    kd_builder b;
    kd_list L;
    kd_box scene;
    kd_tree *t = NULL;
    memset(&b, 0, sizeof b);
    b.p = p;
    if (n < 0) n = 0;
    if (n > (long)MAX_INDEX) return NULL;  /* a primitive's number fits in 30 bits */
    b.side = malloc(((size_t)n + 1) * sizeof(int));
    if (b.side && root_list(&b, n, &L, &scene)) {
        b.max_depth = n > 1 ? (int)(8 + 1.3 * log2((double)n)) : 8;
        if (b.max_depth > STACK_SIZE) b.max_depth = STACK_SIZE;
        b.root_area = box_area(&scene);
        b.nodes = malloc(16 * sizeof(kd_node));
        b.node_cap = 16, b.nnodes = 1;
        if (b.nodes) build_node(&b, 0, &L, &scene, 0, BUDGET * ((double)L.count + 1));
        else free_list(&L);
        free(b.stack[0]), free(b.stack[1]), b.stack[0] = b.stack[1] = NULL;
        if (b.nodes && !b.failed) t = finish(&b, &scene);
    }
    free(b.side), free(b.stack[0]), free(b.stack[1]), free(b.nodes), free(b.refs);
    if (t) t->info.build_seconds = (double)(clock() - start) / CLOCKS_PER_SEC;
    return t;
}

void kd_free(kd_tree *t)
{
    if (t) free(t->nodes), free(t);
}

void kd_describe(const kd_tree *t, kd_info *info)
{
    if (t) *info = t->info;
    else memset(info, 0, sizeof *info);
}

const void *kd_bytes(const kd_tree *t, size_t *size)
{
    *size = t->bytes;
    return t->nodes;
}

long kd_splits(const kd_tree *t, int *axis, double *pos, long max)
{
    long i, k = 0;
    for (i = 0; i < t->info.nodes; i++) {
        const kd_node *n = &t->nodes[i];
        if (node_axis(n) == (int)LEAF) continue;
        if (k < max) axis[k] = node_axis(n), pos[k] = t->c[node_axis(n)] + n->u.split;
        k++;
    }
    return k;
}

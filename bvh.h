/* bvh.h - a bounding volume hierarchy over primitives it knows only through
 * the callbacks of prims.h.
 *
 * The lecture's slide, and the functions doing each line (bvh.c):
 *
 *   BVH_Intersect(ray, node)                          bvh_intersect
 *     if node is a leaf                               (count > 0)
 *       Intersect(ray, node.object)                   test_leaf: the hit callback
 *     else if Intersect_P(ray, node.BoundingBox)      children: the slab test of
 *       for each child of node do                       a node's four boxes at once,
 *         BVH_Intersect(ray, child)                     nearest child first
 *
 * Each primitive is in the tree exactly once: a BVH splits the objects, not
 * space, so children's boxes may overlap.  That is why, as the slide warns,
 * the walk cannot stop at the first hit it finds: a sibling box overlapping
 * the one just searched may hold a nearer hit.  It can only skip a box the
 * ray enters beyond the nearest hit so far.
 *
 * bvh_intersect is the slide, recursive, behind bvh_intersect_recursive: the
 * readable reference.  bvh_nearest and bvh_any are the fast path: the same
 * nodes in the same order, the recursion turned into a loop with the
 * farther children on a stack.  bvh_refit recomputes the boxes after
 * primitives move, without rebuilding: the lecture's question "which
 * structures suit animation?".
 *
 * Usage:
 *     prims p = { my_bounds, NULL, my_hit, my_scene };   (clip is not used)
 *     bvh *b = bvh_build(n, &p, BVH_SAH);
 *     double tmax = INFINITY;
 *     int i = bvh_nearest(b, &p, org, dir, &my_ray, -1, 0.0, &tmax, &counters);
 *     ... i < 0 means no hit; otherwise primitive i at distance tmax ...
 *     bvh_free(b);
 */
#ifndef BVH_H
#define BVH_H
#include <stddef.h>
#include "prims.h"

typedef struct bvh bvh;

/* How the build chooses where to split a node's objects: the surface area
 * heuristic over binned centroids (Wald 2007), or the median of the
 * centroids along the longest axis (the slide's "mediana"). */
enum { BVH_SAH, BVH_MEDIAN };

/* Shape of a built hierarchy, for --stats. */
typedef struct {
    long nodes, leaves, max_depth, prim_refs;   /* four-way nodes */
    double prims_per_leaf;  /* mean over leaves */
    size_t bytes;           /* nodes plus the primitive-index list */
    const void *block;      /* they, as one block of bytes (for tests: two
                               builds of the same input give equal blocks) */
    double sah_cost;        /* expected cost of a random ray, SAH model, of the
                               four-way tree (of the binary one it came from:
                               sah_cost_binary) */
    double sah_cost_binary;
    double build_seconds;   /* processor time */
} bvh_info;

/* Build over primitives 0..n-1 (n may be 0) by BVH_SAH or BVH_MEDIAN.
 * Returns NULL only when out of memory.  Deterministic: same input, same
 * tree.  A primitive whose box is NaN or has lo > hi is left out. */
bvh *bvh_build(int n, const prims *p, int method);

/* The two queries, as kdtree.h's kd_nearest and kd_any.  bvh_nearest: the
 * nearest hit of the ray org + t*dir with tmin < t <= *tmax, the primitive
 * (ties in t to the lower index, as a brute-force loop) with its t in
 * *tmax, or -1 leaving *tmax alone.  bvh_any: some primitive hit with
 * tmin < t <= tmax, the first the walk meets (not the nearest), or -1; for
 * shadow rays.  Primitive `skip` (-1: none) is never tested. */
int bvh_nearest(const bvh *b, const prims *p, const double org[3], const double dir[3],
                void *ray, int skip, double tmin, double *tmax, prim_counters *c);
int bvh_any(const bvh *b, const prims *p, const double org[3], const double dir[3],
            void *ray, int skip, double tmin, double tmax, prim_counters *c);

/* The slide's recursive BVH_Intersect: any = 0 gives what bvh_nearest
 * gives (same primitive, same t in *tmax), any = 1 what bvh_any gives; it
 * visits the same nodes, so the counters get the same steps and tests. */
int bvh_intersect_recursive(const bvh *b, const prims *p, const double org[3],
                            const double dir[3], void *ray, int skip,
                            double tmin, double *tmax, int any,
                            prim_counters *c);

/* After primitives moved: every box recomputed bottom-up from the bounds
 * callback, the tree's shape kept.  Answers stay exact; only speed suffers
 * when objects move far.  A primitive left out at the build stays out. */
void bvh_refit(bvh *b, const prims *p);

void bvh_describe(const bvh *b, bvh_info *info);
void bvh_free(bvh *b);

/* For tests: the axis and position of each face of every node's box, six
 * per node, in node order, in the caller's coordinates (the nearest double
 * to the float face, which the tree keeps relative to a centre of its
 * own); writes at most max pairs and returns how many there are. */
long bvh_planes(const bvh *b, int *axis, double *pos, long max);
#endif

/* kdtree.h - a kd-tree over primitives it knows only through callbacks.
 *
 * The tree never sees a sphere or a triangle: the caller describes its
 * primitives with the callbacks of prims.h (a bounding box, an optional clip
 * to a box, a ray intersection) and the tree answers "which primitive does
 * this ray hit first" and "does anything block this ray".  See kdtree.c for the build
 * (surface area heuristic, O(N log N), Wald & Havran 2006) and the traversal
 * (Kaplan's near/far order, 1985).
 *
 * Usage:
 *     prims p = { my_bounds, my_clip_or_NULL, my_hit, my_scene };
 *     kd_tree *t = kd_build(n, &p);
 *     double tmax = INFINITY;
 *     int i = kd_nearest(t, &p, org, dir, &my_ray, -1, 0.0, &tmax, &counters);
 *     ... i < 0 means no hit; otherwise primitive i at distance tmax ...
 *     kd_free(t);
 */
#ifndef KDTREE_H
#define KDTREE_H
#include <stddef.h>
#include "prims.h"

typedef struct kd_tree kd_tree;

/* Shape of a built tree, for --stats. */
typedef struct {
    long nodes, leaves, empty_leaves, max_depth, prim_refs;
    double prims_per_leaf;  /* mean over non-empty leaves */
    size_t bytes;           /* nodes plus primitive-index lists */
    double sah_cost;        /* expected cost of a random ray, SAH model */
    double build_seconds;
} kd_info;

/* Build over primitives 0..n-1 (n may be 0).  Returns NULL only when out of
 * memory (or past 2^30 nodes or primitive references).  The build is
 * deterministic: same input, same tree.  Boxes are kept in float; a
 * primitive whose box is NaN or has lo > hi is left out. */
kd_tree *kd_build(int n, const prims *p);

/* Nearest hit of the ray org + t*dir with tmin < t <= *tmax.  Returns the
 * primitive (ties in t go to the lower index, as a brute-force loop would)
 * and stores its t in *tmax; returns -1 and leaves *tmax alone on a miss.
 * Primitive `skip` (-1: none) is never tested: the surface a ray leaves,
 * when the caller knows the ray cannot meet it again. */
int kd_nearest(const kd_tree *t, const prims *p, const double org[3],
               const double dir[3], void *ray, int skip, double tmin,
               double *tmax, prim_counters *c);

/* A primitive other than `skip` hit with tmin < t <= tmax, whichever the
 * walk meets first (not the nearest); -1 when there is none.  For shadow
 * rays. */
int kd_any(const kd_tree *t, const prims *p, const double org[3],
           const double dir[3], void *ray, int skip, double tmin, double tmax,
           prim_counters *c);

/* Readable reference; the iterative walk is the fast path.  Kaplan's
 * TreeIntersect as the lecture's slide writes it, recursive.  any = 0: what
 * kd_nearest returns, the same primitive and the same t in *tmax.  any = 1:
 * what kd_any returns, the same primitive; *tmax is left alone.  It visits
 * the same cells in the same order as kd_nearest and kd_any, so the
 * counters get the same steps and tests. */
int kd_intersect_recursive(const kd_tree *t, const prims *p,
                           const double org[3], const double dir[3],
                           void *ray, int skip, double tmin, double *tmax,
                           int any, prim_counters *c);

void kd_describe(const kd_tree *t, kd_info *info);
void kd_free(kd_tree *t);

/* For tests and for the curious.  kd_bytes: the built tree as one block of
 * bytes (the 8-byte nodes, then the leaves' lists of primitive numbers);
 * two builds of the same input give equal blocks.  kd_splits: the axis
 * (0, 1, 2) and position of each inner node's plane, in node order, in the
 * caller's coordinates (the tree keeps it as a float relative to a centre
 * of its own, so this is the nearest double); writes at most max pairs and
 * returns the number of inner nodes. */
const void *kd_bytes(const kd_tree *t, size_t *size);
long kd_splits(const kd_tree *t, int *axis, double *pos, long max);
#endif

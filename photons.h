/* photons.h - a balanced kd-tree over points in 3D, for photon mapping's
 * k-nearest queries (Jensen, "Global illumination using photon maps",
 * Rendering Techniques 1996; Bentley, "Multidimensional binary search trees
 * used for associative searching", CACM 1975).
 *
 * kdtree.c answers rays; this answers points: which k of the stored
 * points lie nearest a given point, within a given radius, or which lie
 * within the radius at all.  It knows the
 * points only as coordinates, numbered 0..n-1 in the caller's order; what
 * a photon carries stays with the caller (ray.c).
 *
 * The tree is implicit: the points' numbers are reordered so that, for any
 * range [lo, hi) of the order, the middle one, mid = (lo + hi) / 2, splits
 * the rest on its axis (the widest of the range's box): those before it lie
 * on its low side or on the plane, those after it on its high side or on
 * it.  The root is the middle of the whole range; there are no pointers,
 * and the depth is at most log2 n + 1.
 */
#ifndef PHOTONS_H
#define PHOTONS_H

typedef struct {
    const float (*p)[3];    /* the points (the caller's, not copied) */
    int n;
    int *order;             /* the points' numbers, in the tree's order */
    unsigned char *axis;    /* axis[m]: the split axis of the node at position m */
} PointTree;

/* Builds the tree over the n points p (kept by pointer: they must outlive
 * the tree).  Returns 0 when memory runs out. */
int point_tree_build(PointTree *t, const float (*p)[3], int n);

/* The (at most) k points nearest x with squared distance below r2: their
 * numbers into idx and squared distances into d2, nearest first.  Returns
 * how many were found. */
int point_tree_nearest(const PointTree *t, const float x[3], int k, float r2, int *idx, float *d2);

/* Every point with squared distance below r2 from x: visit(user, i, d2)
 * for each, in the tree's order (the same on every run).  Returns how
 * many there were.  Progressive photon mapping's query: all photons in a
 * disc of a given radius, however many. */
int point_tree_within(const PointTree *t, const float x[3], float r2,
                      void (*visit)(void *user, int i, float d2), void *user);

void point_tree_free(PointTree *t);

#endif

/* prims.h - how an acceleration structure sees a scene: one table of
 * callbacks.
 *
 * The structures (kdtree.c, bvh.c and grid.c) never see a
 * sphere or a triangle.  The renderer describes its primitives, numbered
 * 0..n-1, by three callbacks and a pointer handed back to them:
 *
 *     bounds   the axis-aligned box of primitive i
 *     clip     the box of the part of primitive i inside a given box
 *              (optional: NULL means "the box, cut to the given box")
 *     hit      does the caller's ray hit primitive i, and where
 *     user     the caller's own data (ray.c passes its Scene)
 *
 * Every structure answers the same two questions through them: which
 * primitive does this ray hit first (nearest), and does anything block it
 * (any).  ray.c's nearest_hit() and any_hit() are the only places that know
 * which structure answers.
 */
#ifndef PRIMS_H
#define PRIMS_H

typedef struct {
    /* The axis-aligned box of primitive i. */
    void (*bounds)(void *user, int i, double lo[3], double hi[3]);
    /* Optional (NULL: use bounds). The box of the part of primitive i that
     * lies inside [blo,bhi]; returns 0 when nothing of it is inside.  Lets a
     * kd-tree make "perfect splits" (Havran 2000) for long thin primitives. */
    int (*clip)(void *user, int i, const double blo[3], const double bhi[3],
                double lo[3], double hi[3]);
    /* Intersect primitive i with the caller's ray (passed through untouched
     * as `ray`).  Returns 1 and sets *t when it hits at tmin < *t <= tmax.
     * A structure may skip repeating a test it has made for the same ray
     * (a mailbox), so a miss must stay a miss for any smaller tmax and t
     * must not depend on tmax.
     * `ray` is not const: the callback may note things there, such as where
     * on the primitive its last hit lay, to spare the caller a second test.
     * A structure finds exactly what a loop over all primitives finds as
     * long as the point org + t*dir of a reported hit lies in the
     * primitive's box (its clipped box, with clip), give or take a margin of
     * 1e-7 times the largest coordinate of the scene and the ray origin. */
    int (*hit)(void *user, int i, void *ray, double tmin, double tmax,
               double *t);
    void *user;
} prims;

/* Work done per query, for --stats: queries, nodes or cells visited, and
 * calls of the hit callback.  Wherever a pointer to one is taken, NULL is
 * allowed. */
typedef struct { unsigned long long rays, steps, tests; } prim_counters;

#endif

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
 *     eps      the machine epsilon of the arithmetic hit is done in
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
     *
     * The contract.  A structure finds exactly what a loop over all
     * primitives finds (the same primitive, bit for bit the same t) as long
     * as the point org + t*dir of every reported hit, summed exactly, lies
     * in the primitive's box (its clipped box, with clip) grown on every
     * side by
     *     PRIMS_HIT_REL * L  +  PRIMS_HIT_ULPS * eps * m,
     * L the longest side of the primitive's whole box, m the largest
     * |coordinate| of the ray origin and of that box.  The first term is for
     * errors that scale with the primitive itself: a sphere met at a
     * tangent (the root of a near-zero discriminant), a triangle met at a
     * grazing angle (a t and barycentrics divided by a near-zero
     * determinant).  The second is for rounding the coordinates, which
     * scales with their magnitude however small the primitive is: a scene
     * far from the origin, a ray from far away.  Since m is the larger of
     * the two, a callback honours it only if no rounding of size eps * m is
     * amplified: one that subtracts a far ray origin from its primitive and
     * then cancels products of the differences (the textbook sphere's
     * b^2 - c, Moller-Trumbore's cross products) must first move the
     * origin along the ray to near the primitive (ray.c's hit_sphere,
     * hit_cone and hit_triangle do).  In return each structure keeps its
     * speed far from the origin: its margin follows the size of the scene
     * and eps * m, not m alone. */
    int (*hit)(void *user, int i, void *ray, double tmin, double tmax,
               double *t);
    void *user;
    /* The machine epsilon of the hit callback's arithmetic, the eps above:
     * 0 means double's, DBL_EPSILON = 2^-52; ray.c's float build says
     * FLT_EPSILON = 2^-23.  A brace initializer of the first four members
     * leaves it 0. */
    double eps;
} prims;

/* The contract's constants (above).  PRIMS_HIT_REL is 2^-24, half a float
 * step relative: it covers a triangle met at an angle whose sine, times
 * the sine of the triangle's smallest angle, is above about 1e-8 (ray.c's
 * and test_accel's tests).  PRIMS_HIT_ULPS: ray.c's callbacks were measured
 * to err by at most 9 eps * m (tests/test_ray.c, "the hit callbacks keep
 * the contract"). */
#define PRIMS_HIT_REL (1.0 / 16777216.0)
#define PRIMS_HIT_ULPS 8

/* Work done per query, for --stats: queries, nodes or cells visited, and
 * calls of the hit callback.  Wherever a pointer to one is taken, NULL is
 * allowed. */
typedef struct { unsigned long long rays, steps, tests; } prim_counters;

#endif

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

#include <float.h>
#include <math.h>

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
     * as every reported t is within
     *     PRIMS_HIT_ULPS * eps * m / max|dir[a]|
     * of a t' whose point org + t' * dir, summed exactly, lies in the
     * primitive's box (its clipped box, with clip) grown on every side by
     *     PRIMS_HIT_REL * L  +  PRIMS_HIT_ULPS * eps * s,
     * L the longest side of the primitive's whole box, s the largest
     * |coordinate| of that box and m the larger of s and the ray origin's.
     * The first term is for errors that scale with the primitive itself: a
     * sphere met at a tangent (the root of a near-zero discriminant), a
     * triangle met at a grazing angle (t and barycentrics divided by a
     * near-zero determinant).  The second is for rounding the primitive's
     * coordinates, which scales with their magnitude however small the
     * primitive is (a scene far from the origin).  A ray origin far away
     * may err only along the ray: the rounding of a t of its size moves the
     * point along the ray, not off it.  So a callback that subtracts a far
     * origin from its primitive, which shifts the ray sideways by a
     * rounding of m, and then cancels products of the differences (the
     * textbook sphere's b^2 - c, Moller-Trumbore's cross products) must
     * first move the origin along the ray to near the primitive, summing
     * o + t0 dir exactly (ray.c's hit_sphere, hit_cone and hit_triangle
     * do, with prims_along below).  In return each structure
     * keeps its speed far from the origin: its margin across the ray
     * follows the scene alone, and along it costs an extra cell now and
     * then. */
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
 * and test_accel's tests).  PRIMS_HIT_ULPS: see tests/test_ray.c, "the hit
 * callbacks keep the contract", for what ray.c's callbacks were measured
 * to need. */
#define PRIMS_HIT_REL (1.0 / 16777216.0)
#define PRIMS_HIT_ULPS 8

/* o - c + t d, each part taken exactly and the sum rounded once (give or
 * take a rounding of the tiny parts): Knuth's TwoSum for the sums, and for
 * the product Dekker's TwoProduct, from Veltkamp's split of each factor
 * into halves of 26 bits whose products are exact (Dekker, "A
 * floating-point technique for extending the available precision", 1971).
 * For a point o + t d of a far ray near c, the result is exact to a
 * rounding of itself; rounded step by step it would lie off the ray by a
 * rounding of |o| (10^-3 from 10^13 away).  A callback moves a far origin
 * with it (the contract above), and so do the structures.  Needs double
 * arithmetic without fused multiply-adds (the Makefile's
 * -ffp-contract=off) and without overflow (|t|, |d| below 2^995). */
static inline double prims_along(double o, double c, double t, double d)
{
    double p = t * d, k, th, tl, dh, dl, pe, s, z, e, s2, e2;
    k = 134217729.0 * t, th = k - (k - t), tl = t - th;
    k = 134217729.0 * d, dh = k - (k - d), dl = d - dh;
    pe = ((th * dh - p) + th * dl + tl * dh) + tl * dl;     /* p + pe = t d */
    s = o - c, z = s - o, e = (o - (s - z)) + (-c - z);      /* s + e = o - c */
    s2 = s + p, z = s2 - s, e2 = (s - (s2 - z)) + (p - z);   /* s2 + e2 = s + p */
    return s2 + (e + e2 + pe);
}

/* The box lo..hi of primitives 0, step, 2 step, ... below n (those with a
 * box; step 1 for all of them), and the centre c of a frame for it, for a structure that keeps its planes or boxes as
 * floats relative to c (kdtree.c, bvh.c): a float step is then 2^-23 of
 * the scene's size wherever the scene lies, where in the caller's
 * coordinates a scene 1e8 from the origin would have steps of 8.  c is the
 * box's middle rounded to a multiple of the largest power of two not above
 * the box's longest side: coordinates relative to it are at most that side
 * in magnitude (the rounding moves it by at most half the side), and a
 * scene about the origin gets c = 0 and the very structure it had in the
 * caller's coordinates.  A box of no size (one point) is centred on
 * itself; one that is not finite keeps the origin. */
static inline void prims_frame(const prims *p, int n, int step, double lo[3], double hi[3],
                               double c[3])
{
    double side = 0, unit = 0;
    int i, a, e, any = 0;
    for (a = 0; a < 3; a++) lo[a] = hi[a] = 0;
    for (i = 0; i < n; i += step) {
        double l[3], h[3];
        p->bounds(p->user, i, l, h);
        for (a = 0; a < 3; a++)
            if (!(l[a] <= h[a])) break;
        if (a < 3) continue;
        for (a = 0; a < 3; a++) {
            if (!any || l[a] < lo[a]) lo[a] = l[a];
            if (!any || h[a] > hi[a]) hi[a] = h[a];
        }
        any = 1;
    }
    for (a = 0; a < 3; a++)
        if (hi[a] - lo[a] > side) side = hi[a] - lo[a];
    if (side > 0 && side <= DBL_MAX) frexp(side, &e), unit = ldexp(1.0, e - 1);
    for (a = 0; a < 3; a++) {
        double mid = 0.5 * lo[a] + 0.5 * hi[a];
        c[a] = !(side <= DBL_MAX) || !isfinite(mid) ? 0 : unit > 0 ? unit * floor(mid / unit + 0.5) : mid;
    }
}

/* Work done per query, for --stats: queries, nodes or cells visited, and
 * calls of the hit callback.  Wherever a pointer to one is taken, NULL is
 * allowed. */
typedef struct { unsigned long long rays, steps, tests; } prim_counters;

#endif

/* grid.h - a uniform grid over primitives it knows only through the
 * callbacks of prims.h.
 *
 * The lecture credits grids to Fujimoto, Tanaka & Iwata 1986 ("ARTS:
 * Accelerated Ray-Tracing System"): space is cut into equal cells, each
 * listing the primitives that reach into it, and a ray walks the cells it
 * passes through, in order, with the 3D-DDA of Amanatides & Woo 1987 ("A
 * fast voxel traversal algorithm for ray tracing"):
 *
 *   find the cell where the ray enters the grid          start
 *   for each axis: tMax, the t of the next cell face,    next_face
 *                  tDelta, the t across one cell
 *   loop
 *     test the cell's objects (each once per ray:        test_cell, the mailbox
 *        the mailbox)
 *     if a hit lies before the next cell face: stop      (best_t < the next event)
 *     step along the axis whose tMax is smallest         step
 *
 * See grid.c for the resolution (from the object count, after Cleary &
 * Wyvill 1988) and for the margin that makes its answers exactly those of a
 * brute-force loop.
 *
 * Usage:
 *     prims p = { my_bounds, my_clip_or_NULL, my_hit, my_scene };
 *     grid *g = grid_build(n, &p);
 *     double tmax = INFINITY;
 *     int i = grid_nearest(g, &p, org, dir, &my_ray, -1, 0.0, &tmax, &counters);
 *     grid_free(g);
 */
#ifndef GRID_H
#define GRID_H
#include <stddef.h>
#include "prims.h"

typedef struct grid grid;

/* Shape of a built grid, for --stats. */
typedef struct {
    long cells, empty_cells, prim_refs;
    int res[3];
    size_t bytes;           /* cell offsets plus primitive-index lists */
    const void *block;      /* they, as one block (equal for two builds of
                               the same input) */
    double build_seconds;   /* processor time */
} grid_info;

/* Build over primitives 0..n-1 (n may be 0).  NULL only when out of
 * memory.  Deterministic.  A primitive whose box is NaN or has lo > hi is
 * left out. */
grid *grid_build(int n, const prims *p);

/* As kd_nearest and kd_any (kdtree.h): the nearest hit with tmin < t <=
 * *tmax, ties to the lower index; any hit; `skip` never tested. */
int grid_nearest(const grid *g, const prims *p, const double org[3], const double dir[3],
                 void *ray, int skip, double tmin, double *tmax, prim_counters *c);
int grid_any(const grid *g, const prims *p, const double org[3], const double dir[3],
             void *ray, int skip, double tmin, double tmax, prim_counters *c);

void grid_describe(const grid *g, grid_info *info);
void grid_free(grid *g);

/* For tests: the planes between its cells (axis, position), at most max of
 * them written; returns how many there are. */
long grid_planes(const grid *g, int *axis, double *pos, long max);
#endif

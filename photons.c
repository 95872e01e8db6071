/* photons.c - the balanced kd-tree of photons.h. */
#include <stdlib.h>
#include "photons.h"

/* Reorders order[lo..hi) so that order[m] holds the point whose coordinate
 * a would stand at m if sorted, with none greater before it and none less
 * after it (Hoare's selection, "Find", CACM 1961). */
static void select_median(const float (*p)[3], int *order, int lo, int hi, int m, int a)
{
    while (hi - lo > 1) {
        float pivot = p[order[(lo + hi) / 2]][a];
        int i = lo, j = hi - 1;
        while (i <= j) {
            while (p[order[i]][a] < pivot) i++;
            while (p[order[j]][a] > pivot) j--;
            if (i <= j) {
                int swap = order[i];
                order[i++] = order[j];
                order[j--] = swap;
            }
        }
        if (m <= j) hi = j + 1;
        else if (m >= i) lo = i;
        else return;            /* between j and i: all equal to the pivot */
    }
}

/* The range [lo, hi) made a subtree: its middle split on the widest axis
 * of the range's box, then each half the same way. */
static void build(PointTree *t, int lo, int hi)
{
    float min[3], max[3];
    int i, a, m = (lo + hi) / 2;
    if (hi - lo < 1) return;
    for (a = 0; a < 3; a++) min[a] = max[a] = t->p[t->order[lo]][a];
    for (i = lo + 1; i < hi; i++)
        for (a = 0; a < 3; a++) {
            float v = t->p[t->order[i]][a];
            if (v < min[a]) min[a] = v;
            if (v > max[a]) max[a] = v;
        }
    a = max[0] - min[0] >= max[1] - min[1] ? 0 : 1;
    if (max[2] - min[2] > max[a] - min[a]) a = 2;
    select_median(t->p, t->order, lo, hi, m, a);
    t->axis[m] = (unsigned char)a;
    build(t, lo, m);
    build(t, m + 1, hi);
}

int point_tree_build(PointTree *t, const float (*p)[3], int n)
{
    int i;
    t->p = p;
    t->n = n;
    t->order = malloc((n > 0 ? (size_t)n : 1) * sizeof *t->order);
    t->axis = malloc(n > 0 ? (size_t)n : 1);
    if (!t->order || !t->axis) {
        point_tree_free(t);
        return 0;
    }
    for (i = 0; i < n; i++) t->order[i] = i;
    build(t, 0, n);
    return 1;
}

void point_tree_free(PointTree *t)
{
    free(t->order);
    free(t->axis);
    t->order = NULL;
    t->axis = NULL;
    t->n = 0;
}

/* The query's state: the nearest found so far, a max-heap on d2 of at
 * most k, and the squared radius still worth searching. */
typedef struct { const float *x; int k, found; float r2; int *idx; float *d2; } Query;

/* Point i at squared distance d into the heap: it replaces the farthest
 * when the heap is full, and the radius shrinks to the farthest kept. */
static void offer(Query *q, int i, float d)
{
    int c, up;
    if (q->found < q->k) {                          /* sift up from the end */
        for (c = q->found++; c > 0 && q->d2[up = (c - 1) / 2] < d; c = up)
            q->d2[c] = q->d2[up], q->idx[c] = q->idx[up];
    } else {                                        /* the root out, sift down */
        for (c = 0; 2 * c + 1 < q->k; c = up) {
            up = 2 * c + 1;
            if (up + 1 < q->k && q->d2[up + 1] > q->d2[up]) up++;
            if (q->d2[up] <= d) break;
            q->d2[c] = q->d2[up], q->idx[c] = q->idx[up];
        }
    }
    q->d2[c] = d, q->idx[c] = i;
    if (q->found == q->k) q->r2 = q->d2[0];
}

static void search(const PointTree *t, Query *q, int lo, int hi)
{
    while (hi > lo) {
        int m = (lo + hi) / 2, i = t->order[m], a = t->axis[m];
        const float *p = t->p[i];
        float d = q->x[a] - p[a], e0 = q->x[0] - p[0], e1 = q->x[1] - p[1], e2 = q->x[2] - p[2];
        float dist = e0 * e0 + e1 * e1 + e2 * e2;
        if (dist < q->r2) offer(q, i, dist);
        if (d < 0) {                                /* the low side first, the high if in reach */
            search(t, q, lo, m);
            if (!(d * d < q->r2)) return;
            lo = m + 1;
        } else {
            search(t, q, m + 1, hi);
            if (!(d * d < q->r2)) return;
            hi = m;
        }
    }
}

int point_tree_nearest(const PointTree *t, const float x[3], int k, float r2, int *idx, float *d2)
{
    Query q;
    int n, c, up;
    if (k < 1) return 0;
    q.x = x, q.k = k, q.found = 0, q.r2 = r2, q.idx = idx, q.d2 = d2;
    search(t, &q, 0, t->n);
    /* the heap sorted in place, nearest first (heapsort's second half) */
    for (n = q.found; n > 1; n--) {
        float d = d2[n - 1], top = d2[0];
        int j = idx[n - 1], itop = idx[0];
        for (c = 0; 2 * c + 1 < n - 1; c = up) {
            up = 2 * c + 1;
            if (up + 1 < n - 1 && d2[up + 1] > d2[up]) up++;
            if (d2[up] <= d) break;
            d2[c] = d2[up], idx[c] = idx[up];
        }
        d2[c] = d, idx[c] = j;
        d2[n - 1] = top, idx[n - 1] = itop;
    }
    return q.found;
}

/* The points of [lo, hi) within the radius of x, to visit. */
static int within(const PointTree *t, const float x[3], float r2, int lo, int hi,
                  void (*visit)(void *user, int i, float d2), void *user)
{
    int found = 0;
    while (hi > lo) {
        int m = (lo + hi) / 2, i = t->order[m], a = t->axis[m];
        const float *p = t->p[i];
        float d = x[a] - p[a], e0 = x[0] - p[0], e1 = x[1] - p[1], e2 = x[2] - p[2];
        float dist = e0 * e0 + e1 * e1 + e2 * e2;
        if (dist < r2) {
            visit(user, i, dist);
            found++;
        }
        if (d < 0) {                                /* the near side, the far side if in reach */
            found += within(t, x, r2, lo, m, visit, user);
            if (!(d * d < r2)) break;
            lo = m + 1;
        } else {
            found += within(t, x, r2, m + 1, hi, visit, user);
            if (!(d * d < r2)) break;
            hi = m;
        }
    }
    return found;
}

int point_tree_within(const PointTree *t, const float x[3], float r2,
                      void (*visit)(void *user, int i, float d2), void *user)
{
    return within(t, x, r2, 0, t->n, visit, user);
}

/* photons.c's kd-tree against brute force: for random queries among
 * uniform, clustered, coplanar and repeated points, the k nearest within
 * a radius are the brute-force k nearest (their squared distances the
 * same, nearest first; which of two at the same distance may differ),
 * and the points within a radius are brute force's, each once.  Fixed
 * seeds. */
#include <stdio.h>
#include "../photons.h"
#include "report.h"

static float rnd(unsigned long long *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (float)((*s >> 40) / 16777216.0);
}

/* point_tree_within's visits: each point's count, and a wrong distance. */
typedef struct { const float (*p)[3]; const float *x; int *seen, wrong; } Visits;

static void visit(void *user, int i, float d2)
{
    Visits *v = user;
    float e0 = v->x[0] - v->p[i][0], e1 = v->x[1] - v->p[i][1], e2 = v->x[2] - v->p[i][2];
    v->seen[i]++;
    v->wrong += d2 != e0 * e0 + e1 * e1 + e2 * e2;
}

/* Brute force's k nearest: d joins the k smallest distances seen so far,
 * kept nearest first in near[0..*kept), if it is smaller than the last. */
static void keep_nearest(float *near, int *kept, int k, float d)
{
    int j;
    if (*kept == k) {
        if (!(d < near[k - 1])) return;     /* no nearer than the k kept */
        j = k - 1;                          /* the farthest kept gives way */
    } else
        j = (*kept)++;
    for (; j > 0 && d < near[j - 1]; j--) near[j] = near[j - 1];
    near[j] = d;
}

int main(void)
{
    static const char *const kinds[] = { "uniform", "clustered", "coplanar", "repeated" };
    enum { N = 20000, Q = 2000, K = 50 };
    static float p[N][3], near[K], d2[K];
    static int idx[K], seen[N];
    unsigned long long s = 7;
    int kind;
    for (kind = 0; kind < 4; kind++) {
        PointTree t;
        int i, q, bad = 0, total = 0, inside = 0, bad_within = 0, n = kind == 3 ? 2000 : N;
        char name[96];
        for (i = 0; i < n; i++) {
            float c = kind == 1 ? (float)(i % 7) : 0, r = kind == 1 ? 0.05f : 1;
            p[i][0] = c + r * rnd(&s), p[i][1] = kind == 2 ? 0.5f : c + r * rnd(&s), p[i][2] = r * rnd(&s);
            if (kind == 3) p[i][0] = (float)(i % 5), p[i][1] = 0, p[i][2] = (float)(i % 3);
        }
        if (!point_tree_build(&t, (const float (*)[3])p, n)) { report(0, "build", "out of memory"); return 1; }
        for (q = 0; q < Q; q++) {
            float x[3], r2 = q % 3 == 0 ? 1e30f : 0.01f * (1 + q % 10);
            int k = 1 + q % K, found, want = 0, kept = 0, j;
            x[0] = (kind == 1 ? 7 : 1.2f) * rnd(&s) - 0.1f, x[1] = rnd(&s), x[2] = rnd(&s);
            found = point_tree_nearest(&t, x, k, r2, idx, d2);
            for (i = 0; i < n; i++) {
                float e0 = x[0] - p[i][0], e1 = x[1] - p[i][1], e2 = x[2] - p[i][2], d = e0 * e0 + e1 * e1 + e2 * e2;
                if (d < r2) want++, keep_nearest(near, &kept, k, d);
            }
            if (r2 < 1) {                       /* every point within the radius, once */
                Visits v;
                int got;
                v.p = (const float (*)[3])p, v.x = x, v.seen = seen, v.wrong = 0;
                for (i = 0; i < n; i++) seen[i] = 0;
                got = point_tree_within(&t, x, r2, visit, &v);
                for (i = 0; i < n; i++) {
                    float e0 = x[0] - p[i][0], e1 = x[1] - p[i][1], e2 = x[2] - p[i][2];
                    v.wrong += seen[i] != (e0 * e0 + e1 * e1 + e2 * e2 < r2);
                }
                inside += got;
                bad_within += v.wrong || got != want;
            }
            if (want > k) want = k;
            total += found;
            if (found != want) { bad++; continue; }
            for (j = 0; j < found; j++) {
                float e0 = x[0] - p[idx[j]][0], e1 = x[1] - p[idx[j]][1], e2 = x[2] - p[idx[j]][2];
                if (d2[j] != near[j] || d2[j] != e0 * e0 + e1 * e1 + e2 * e2) { bad++; break; }
            }
        }
        sprintf(name, "the photon tree's k nearest, %s points, are brute force's", kinds[kind]);
        report(bad == 0, name, "%d queries of 1 to %d within a radius, %d points found, %d differ", Q, K, total, bad);
        sprintf(name, "the photon tree's points within a radius, %s points, are brute force's", kinds[kind]);
        report(bad_within == 0 && inside > 0, name, "%d queries, %d points found, %d differ", Q - Q / 3, inside,
               bad_within);
        point_tree_free(&t);
    }
    return failures != 0;
}

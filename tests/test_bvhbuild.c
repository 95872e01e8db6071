/* test_bvhbuild.c - the BVH builder's choice of split against brute force.
 * bvh.c is included whole, so that its static parts can be called.
 *
 *   bins    bin_of, which clamps before it converts, against the plain
 *           reading of its rule (below the first slab: bin 0, NaN too;
 *           at or past the last: the last; else the slab's number) on
 *           ordinary, negative, huge, infinite and NaN inputs.
 *   sweep   best_bin_split, which bins every record once and prices the
 *           planes by two sweeps that skip empty bins, against pricing
 *           each plane by a loop over every record: the same best cost,
 *           bit for bit, at the same axis and plane (the plane of the
 *           least area-weighted count A(L) nL + A(R) nR, whose cost is then
 *           computed once; the first such, axis by axis, plane by plane,
 *           as a strict "<" keeps it).  On record
 *           sets of 1 to 40 and of 100 and 1000, and 40 more pairs (two
 *           records take a path of their own), scattered, in clusters
 *           (many empty bins), in few distinct places (ties), flat along
 *           an axis, and points on a line (a node of no area: no plane).
 */
#include "../bvh.c"
#include "report.h"
#include <stdio.h>

/* The rule bin_of follows, as it reads. */
static int bin_rule(float c, float lo, float k1, int nb)
{
    float x = (c - lo) * k1;
    if (!(x >= 1)) return 0;
    if (x >= nb) return nb - 1;
    return (int)x;
}

static void check_bins(void)
{
    static const float xs[] = { -1e30f, -3.5f, -1.0f, -0.0f, 0.0f, 0.25f, 0.999f, 1.0f,
                                1.5f, 7.0f, 14.99f, 15.0f, 15.5f, 16.0f, 16.5f, 1e30f };
    float inf = HUGE_VALF, k1s[4];
    int bad = 0, tried = 0, i, j, nb;
    k1s[0] = 1, k1s[1] = 0.5f, k1s[2] = inf, k1s[3] = 0;
    for (nb = 1; nb <= BINS; nb++)
        for (i = 0; i < (int)(sizeof xs / sizeof *xs); i++)
            for (j = 0; j < 4; j++) {
                float c = xs[i];
                tried++;
                if (bin_of(c, 0, k1s[j], nb) != bin_rule(c, 0, k1s[j], nb)) bad++;
                if (bin_of(inf, 0, k1s[j], nb) != bin_rule(inf, 0, k1s[j], nb)) bad++;
                if (bin_of(c, c, k1s[j], nb) != bin_rule(c, c, k1s[j], nb)) bad++;   /* 0 * k1 */
            }
    report(bad == 0, "bins", "bin_of against its rule: %d of %d cases differ", bad, 3 * tried);
}

static unsigned long long rng = 88172645463325252ULL;
static double uniform(void)   /* xorshift64: a fixed sequence on every machine */
{
    rng ^= rng << 13, rng ^= rng >> 7, rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

/* n records: kind 0 scattered, 1 in three clusters, 2 at four places, 3
 * flat along z. */
static void make_refs(bvh_ref *r, long n, int kind)
{
    long k;
    int a;
    for (k = 0; k < n; k++) {
        double c[3], h = 0.05 * uniform();
        int place = (int)(4 * uniform());
        for (a = 0; a < 3; a++) {
            if (kind == 1) c[a] = place % 3 * 10 + 0.3 * uniform();
            else if (kind == 2) c[a] = place * 1.25 + a;
            else c[a] = uniform();
        }
        if (kind == 3) c[2] = 0.5;
        if (kind == 4) c[1] = c[2] = 0.5, h = 0;   /* points on a line: boxes of no area */
        for (a = 0; a < 3; a++) r[k].lo[a] = (float)(c[a] - h), r[k].hi[a] = (float)(c[a] + h);
        r[k].id = (int)k, r[k].pad = 0;
    }
}

/* Every plane priced by a loop over every record. */
static double brute_split(const bvh_builder *b, long n, const bvh_box *cbox, double area,
                          int *axis, int *split)
{
    double best = HUGE_VAL, cost;
    int a, i, nb = bins_for(n);
    long k;
    for (a = 0; a < 3; a++) {
        float k1 = bin_scale(cbox, a, nb);
        if (k1 == 0) continue;
        for (i = 1; i < nb; i++) {
            bvh_box side[2], rb;
            long count[2] = { 0, 0 };
            double sum;
            box_empty(&side[0]), box_empty(&side[1]);
            for (k = 0; k < n; k++) {
                int s = bin_of(centroid2(&b->ref[k], a), cbox->lo[a], k1, nb) >= i;
                ref_box(&b->ref[k], &rb);
                box_grow(&side[s], &rb);
                count[s]++;
            }
            if (count[0] == 0 || count[1] == 0) continue;
            sum = box_area(&side[0]) * count[0] + box_area(&side[1]) * count[1];
            if (sum < best) best = sum, *axis = a, *split = i;
        }
    }
    cost = COST_STEP + COST_TEST * best / area;   /* NaN for a node of no area: no plane */
    return cost < HUGE_VAL ? cost : HUGE_VAL;
}

static void check_sweep(void)
{
    static const long sizes[] = { 100, 1000 };
    bvh_ref r[1000];
    bvh_builder b;
    int kind, tried = 0, bad = 0, none = 0, s;
    long n;
    memset(&b, 0, sizeof b);
    b.ref = r;
    for (kind = 0; kind < 5; kind++)
        for (s = 0; s < 82; s++) {
            bvh_box box, cbox;
            double fast, slow;
            int fa = -1, fs = -1, sa = -1, ss = -1;
            n = s < 40 ? s + 1 : s < 42 ? sizes[s - 40] : 2;   /* and 40 more pairs */
            make_refs(r, n, kind);
            bounds_of(&b, 0, n, &box, &cbox);
            fast = best_bin_split(&b, 0, n, &cbox, box_area(&box), &fa, &fs);
            slow = brute_split(&b, n, &cbox, box_area(&box), &sa, &ss);
            tried++;
            none += slow == HUGE_VAL;
            if (fast != slow || (slow != HUGE_VAL && (fa != sa || fs != ss))) {
                if (bad++ < 3)
                    printf("    kind %d, %ld records: sweep %.17g at axis %d plane %d, "
                           "brute force %.17g at axis %d plane %d\n", kind, n, fast, fa, fs,
                           slow, sa, ss);
            }
        }
    report(bad == 0, "sweep", "best_bin_split against every plane priced by a loop: "
           "%d of %d record sets differ (%d with no plane that parts them)", bad, tried, none);
}

int main(int argc, char **argv)
{
    const char *part = argc > 1 ? argv[1] : "all";
    if (!strcmp(part, "bins") || !strcmp(part, "all")) check_bins();
    if (!strcmp(part, "sweep") || !strcmp(part, "all")) check_sweep();
    return failures != 0;
}

/* Bidirectional path tracing's MIS weights (ray.c's mis_weight), on
 * subpaths sampled as BDPT samples them (subpaths()), on the Cornell box
 * (diffuse, one area lamp), a scene of Phong and GGX surfaces under a
 * glowing sphere (the pdfs then depend on both directions) and one of
 * point lights:
 *  - for each path a join of two subpaths makes, every vertex's pdf per
 *    area, from the light's side and from the eye's, found here anew
 *    from the path's points alone, is what the walks (fwd, rev) and the
 *    join (join_rev) gave it;
 *  - the weights of all the strategies that could have made the path,
 *    from those pdfs, add up to 1 (Veach 1997, section 10.2: the weights
 *    of one path are a partition of unity, which MIS needs to be
 *    unbiased).
 * Pixels and samples from fixed seeds. */
#define main ray_main
#include "../ray.c"
#undef main
#include "report.h"

#define TOL 1e-6    /* relative; the pdfs are the same formulas, in another order */

static int near_enough(double a, double b) { return fabs(a - b) <= TOL * (fabs(a) + fabs(b)) + 1e-300; }

static vec towards(vec from, vec to) { return unit(sub(to, from)); }

/* A pdf per solid angle at `from` as one per area at the hit `to`: the
 * cosine there over the squared distance (here apart from ray.c's to_area). */
static double per_area(double pdf, vec from, const Hit *to)
{
    vec d = sub(from, to->p);
    return pdf * fabs(dot(unit(d), to->ng)) / dot(d, d);
}

/* The pdf per area at x[i] of the path x[0] (on the light) .. x[n] (the
 * eye), as the light's side makes it: the light's choice and point for
 * x[0], its emission for x[1], then each vertex's BSDF from the one before. */
static double from_light(const Scene *s, const Vertex *x, int i, int l, int point)
{
    if (i == 0) return tree_chance(s, l, v3(0, 0, 0), v3(0, 0, 0), 1) / (point ? 1 : light_area(s, l));
    if (i == 1) {
        real pdf = point ? 1 / (4 * (real)PI) : fabs(dot(x[0].h.ng, towards(x[0].h.p, x[1].h.p))) / (real)PI;
        return per_area(pdf, x[0].h.p, &x[1].h);
    }
    return per_area(bsdf_pdf(&x[i - 1].b, towards(x[i - 1].h.p, x[i - 2].h.p), towards(x[i - 1].h.p, x[i].h.p)),
                   x[i - 1].h.p, &x[i].h);
}

/* The same from the eye's side: the camera's pdf for x[n-1], then each
 * vertex's BSDF from the one after. */
static double from_eye(const Scene *s, const Vertex *x, int i, int n)
{
    if (i == n - 1) return per_area(film_pdf(s, towards(x[n].h.p, x[i].h.p)), x[n].h.p, &x[i].h);
    return per_area(bsdf_pdf(&x[i + 1].b, towards(x[i + 1].h.p, x[i + 2].h.p), towards(x[i + 1].h.p, x[i].h.p)),
                   x[i + 1].h.p, &x[i].h);
}

static Subpaths p, q;       /* large: not on the stack */

typedef struct { long paths, fwd_rev, joins, sums; double worst_sum, worst_pdf; } Tally_;

/* Every join (k, t >= 2) of one sample's subpaths p, checked as above. */
static void check_joins(const Scene *s, int l, Tally_ *c)
{
    static Vertex x[2 * HALF_PATH];
    int k, t, i, n;
    for (t = 2; t <= p.nz; t++)
        for (k = 2; k <= p.ny; k++) {
            double L[2 * HALF_PATH], E[2 * HALF_PATH], sum = 0;
            vec wi;
            Rev rev;
            int bad = 0;
            n = k + t - 1;
            if (s->set.max_rays && n > s->set.max_rays) continue;     /* a path BDPT does not make */
            for (i = 0; i < k; i++) x[i] = p.y[i];
            for (i = 0; i < t; i++) x[n - i] = p.z[i];
            for (i = 1; i < n; i++) bad |= x[i].delta;
            wi = towards(x[k].h.p, x[k - 1].h.p);
            if (bad || !nonzero(bsdf_eval(&x[k].b, x[k].wo, wi))
                || !nonzero(bsdf_eval(&x[k - 1].b, x[k - 1].wo, scale(-1, wi))))
                continue;
            c->paths++;
            for (i = 0; i < n; i++) L[i] = from_light(s, x, i, l, p.point), E[i] = from_eye(s, x, i, n);
            for (i = 0; i < k; i++) {           /* the light's walk */
                c->fwd_rev += 1 + (i <= k - 3);
                if (!near_enough(p.y[i].fwd, L[i])) c->worst_pdf = fmax(c->worst_pdf, 1), bad = 1;
                if (i <= k - 3 && !near_enough(p.y[i].rev, E[i])) c->worst_pdf = fmax(c->worst_pdf, 2), bad = 1;
            }
            for (i = 1; i < t; i++) {           /* the eye's walk */
                c->fwd_rev += 1 + (i <= t - 3);
                if (!near_enough(p.z[i].fwd, E[n - i])) c->worst_pdf = fmax(c->worst_pdf, 3), bad = 1;
                if (i <= t - 3 && !near_enough(p.z[i].rev, L[n - i])) c->worst_pdf = fmax(c->worst_pdf, 4), bad = 1;
            }
            rev = join_rev(&p, k, t, wi);
            c->joins++;
            if (!near_enough(rev.z1, L[k]) || !near_enough(rev.y1, E[k - 1])
                || (t >= 3 && !near_enough(rev.z2, L[k + 1])) || !near_enough(rev.y2, E[k - 2]))
                c->worst_pdf = fmax(c->worst_pdf, 5), bad = 1;
            if (bad) continue;
            /* the same path as every strategy (j, n + 1 - j) would have made it */
            q.most_z = p.most_z, q.most_y = p.most_y, q.point = p.point;
            for (i = 0; i <= n; i++) {
                int j = i, tt = n + 1 - j, m;
                Rev r;
                for (m = 0; m < j; m++) q.y[m] = x[m], q.y[m].fwd = L[m], q.y[m].rev = E[m];
                for (m = 0; m < tt; m++) q.z[m] = x[n - m], q.z[m].fwd = E[n - m], q.z[m].rev = L[n - m];
                memset(&q.z[0].fwd, 0, sizeof q.z[0].fwd);
                r.z1 = L[j], r.z2 = tt >= 3 ? L[j + 1] : 0;
                r.y1 = j >= 1 ? E[j - 1] : 0, r.y2 = j >= 2 ? E[j - 2] : 0;
                if (j == 0 && p.point) continue;        /* no eye's path ends on a point */
                sum += mis_weight(&q, q.y, j, tt, r, p.point);
            }
            c->sums++;
            c->worst_sum = fmax(c->worst_sum, fabs(sum - 1));
        }
}

static void run(const char *file, int samples)
{
    Scene s;
    Worker wk;
    Tally_ c;
    int n;
    char name[160];
    const char *base = strrchr(file, '/') ? strrchr(file, '/') + 1 : file;
    memset(&c, 0, sizeof c);
    if (!load_scene(&s, file)) { report(0, file, "cannot load it"); return; }
    s.set.w = s.set.h = 32;
    build_accel(&s, "auto");
    settle_path_options(&s, PATH, BDPT, 1, 5);
    memset(&wk, 0, sizeof wk);
    for (n = 0; n < SHADOW_SLOTS; n++) wk.blocker[n] = -1;
    for (n = 0; n < samples; n++) {
        int i = (int)(mix64((unsigned long long)n) % 32), j = (int)(mix64(~(unsigned long long)n) % 32), l;
        real chance;
        Ray r;
        start_sample(&wk, &s, i, j, n);
        r = primary_ray(&s, i + (real)0.5, j + (real)0.5, &wk);
        subpaths(&s, r, &p, &wk);
        if (p.ny < 2) continue;
        wk.bounce = LIGHT_PATH;     /* which light the light's subpath chose: the same number again */
        l = down_the_tree(&s, v3(0, 0, 0), v3(0, 0, 0), 1, bounce_random(&wk, LIGHT_CHOICE), &chance);
        check_joins(&s, l, &c);
    }
    sprintf(name, "%s: the pdfs of the walks and joins are the path's own", base);
    report(c.paths > 100 && c.worst_pdf == 0, name, "%ld paths of %d samples, %ld fwd and rev pdfs, %ld joins; %s",
           c.paths, samples, c.fwd_rev, c.joins, c.worst_pdf == 0 ? "all agree" : "some differ");
    sprintf(name, "%s: each path's strategies' MIS weights add up to 1", base);
    report(c.sums > 100 && c.worst_sum < 1e-9, name, "%ld paths, worst |sum - 1| %.2g", c.sums, c.worst_sum);
    free_scene(&s);
}

int main(int argc, char **argv)
{
    (void)argc, (void)argv;
    run("scenes/cornell.sph", 3000);
    run(argv[1] ? argv[1] : "scenes/glossy.sph", 3000);
    if (argc > 2) run(argv[2], 3000);
    return failures != 0;
}

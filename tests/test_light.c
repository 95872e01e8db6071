/* Triangle lights sampled by solid angle (Arvo 1995; ray.c's
 * spherical_triangle_sample), against what it must be:
 *  - every direction it gives meets the triangle;
 *  - it is uniform in solid angle: the triangle cut at its edges' midpoints
 *    into four, and each of those again, each of the 16 gets its share of
 *    the samples (its own solid angle over the whole), by a chi-square
 *    test of 15 degrees of freedom;
 *  - the irradiance it estimates, the mean of cos / pdf, is Lambert's
 *    exact polygon formula E = 1/2 sum_i beta_i (n . gamma_i) (Lambert
 *    1760; as Arvo, "Irradiance tensors", SIGGRAPH 1995, writes it: beta_i
 *    the angle edge i spans seen from x, gamma_i the unit normal of the
 *    plane through x and the edge), within 4 standard errors;
 *  - the pdf sample_emitter gives with a direction is the one light_pdf
 *    finds for the point it leads to (MIS needs the two to agree), on both
 *    sides of SOLID_ANGLE_FROM, for the Cornell box's lamp.
 * Random triangles and points, fixed seeds. */
#define main ray_main
#include "../ray.c"
#undef main
#include "report.h"

static double rnd(unsigned long long *x)
{
    *x = *x * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*x >> 11) / 9007199254740992.0;
}

static Triangle make_triangle(vec a, vec b, vec c)
{
    Triangle t;
    memset(&t, 0, sizeof t);
    t.v0 = a;
    t.e1 = sub(b, a);
    t.e2 = sub(c, a);
    return t;
}

/* Lambert's formula: the integral of the (signed) cosine to n over the
 * directions from x to the triangle, whichever way round its corners go. */
static double lambert(const Triangle *t, vec x, vec n)
{
    vec p[3];
    double e = 0;
    int i;
    p[0] = sub(t->v0, x);
    p[1] = sub(add(t->v0, t->e1), x);
    p[2] = sub(add(t->v0, t->e2), x);
    for (i = 0; i < 3; i++) {
        vec a = unit(p[i]), b = unit(p[(i + 1) % 3]);
        double beta = acos(fmax(-1, fmin(1, dot(a, b))));
        e += beta * dot(n, unit(cross(a, b)));
    }
    return fabs(e) / 2;
}

/* Which of the four midpoint sub-triangles of t the ray from x along d
 * meets (0: the middle one), or -1 if it misses t. */
static int quarter(const Triangle *t, vec x, vec d)
{
    Scene s;
    Ray r;
    real tt, u, v;
    r.o = x, r.d = d, r.tmin = 0, r.skip = -1, r.time = 0;
    memset(&s, 0, sizeof s);
    if (!hit_triangle(&s, t, &r, INFINITY, &tt, &u, &v)) return -1;
    if (u > 0.5) return 1;
    if (v > 0.5) return 2;
    if (u + v < 0.5) return 3;
    return 0;
}

static void test_triangle(int n, unsigned long long seed, int *bad_hits, double *worst_chi, double *worst_e)
{
    unsigned long long x = seed;
    vec a = v3(rnd(&x) * 2 - 1, rnd(&x) * 2 - 1, 1 + rnd(&x)), b, c, p = v3(0, 0, 0), nrm, cc[3], m[3];
    vec sub_c[3];
    real angle[3], sub_angle[3], area;
    double count[4] = { 0, 0, 0, 0 }, count16[16], expect16[16], chi = 0, sum = 0, sq = 0, e, mean, se;
    Triangle t, q[4], sub16[16];
    int k, i;
    memset(count16, 0, sizeof count16);
    b = add(a, v3(rnd(&x) * 2 - 1, rnd(&x) * 2 - 1, rnd(&x) - 0.5));
    c = add(a, v3(rnd(&x) * 2 - 1, rnd(&x) * 2 - 1, rnd(&x) - 0.5));
    t = make_triangle(a, b, c);
    nrm = unit(v3(rnd(&x) - 0.5, rnd(&x) - 0.5, 1));
    area = spherical_triangle(&t, p, cc, angle);
    m[0] = scale(0.5, add(a, b)), m[1] = scale(0.5, add(a, c)), m[2] = scale(0.5, add(b, c));
    q[0] = make_triangle(m[0], m[2], m[1]);
    q[1] = make_triangle(m[0], b, m[2]);
    q[2] = make_triangle(m[1], m[2], c);
    q[3] = make_triangle(a, m[0], m[1]);
    for (i = 0; i < 4; i++) {                   /* each quarter cut in four again: 16 cells */
        vec qa = q[i].v0, qb = add(q[i].v0, q[i].e1), qc = add(q[i].v0, q[i].e2);
        vec n0 = scale(0.5, add(qa, qb)), n1 = scale(0.5, add(qa, qc)), n2 = scale(0.5, add(qb, qc));
        sub16[4 * i] = make_triangle(n0, n2, n1);
        sub16[4 * i + 1] = make_triangle(n0, qb, n2);
        sub16[4 * i + 2] = make_triangle(n1, n2, qc);
        sub16[4 * i + 3] = make_triangle(qa, n0, n1);
    }
    for (i = 0; i < 16; i++) expect16[i] = n * spherical_triangle(&sub16[i], p, sub_c, sub_angle) / area;
    for (k = 0; k < n; k++) {
        real u1 = rnd(&x), u2 = rnd(&x);    /* independent: the chi-square and the standard error assume it */
        vec d = spherical_triangle_sample(cc, angle, area, u1, u2);
        int w = quarter(&t, p, d);
        double f = dot(d, nrm) * area;                  /* cos / pdf (cos signed, as Lambert's is) */
        if (w < 0) (*bad_hits)++;
        else {
            count[w]++;
            count16[4 * w + quarter(&q[w], p, d)]++;
        }
        sum += f, sq += f * f;
    }
    for (i = 0; i < 16; i++) chi += (count16[i] - expect16[i]) * (count16[i] - expect16[i]) / expect16[i];
    mean = sum / n;
    se = sqrt(fmax(0, sq / n - mean * mean) / (n - 1));
    e = lambert(&t, p, nrm);
    if (chi > *worst_chi) *worst_chi = chi;
    if (se > 0 && fabs(fabs(mean) - e) / se > *worst_e) *worst_e = fabs(fabs(mean) - e) / se;
}

/* sample_emitter's pdf against light_pdf's for the point it chose, for
 * the Cornell box's lamp (two triangles) from random points of the box:
 * the near ones see it by more than SOLID_ANGLE_FROM, the far ones less. */
static void test_pdf_agrees(void)
{
    Scene s;
    unsigned long long x = 5;
    double worst = 0;
    int k, l, solid = 0, area = 0;
    if (!load_scene(&s, "scenes/cornell.sph") || !settle_path_options(&s, PATH, -1, 1, 0)) {
        report(0, "sample_emitter and light_pdf agree", "scenes/cornell.sph did not load");
        return;
    }
    for (k = 0; k < 20000; k++) {
        vec p = v3(556 * rnd(&x), 548 * rnd(&x), 559 * rnd(&x)), n = v3(0, 1, 0), wi, Le, c[3];
        real dist, pdf, angle[3];
        for (l = 0; l < s.lights.nemit && s.lights.emit[l].type != TRIANGLE_LIGHT; l++) continue;
        l += k % 2;                              /* one triangle of the lamp, then the other */
        if (l >= s.lights.nemit || s.lights.emit[l].type != TRIANGLE_LIGHT) break;
        sample_emitter(&s, l, p, n, 0, (real)rnd(&x), (real)rnd(&x), &wi, &dist, &Le, &pdf);
        if (!(pdf > 0)) continue;
        {
            const Triangle *t = &s.tri[s.lights.emit[l].obj - s.nsph - s.ncone];
            vec y = comb(dist, wi, p), ny = unit(cross(t->e1, t->e2));
            double q = light_pdf(&s, l, p, n, y, ny, 0) / light_choice(&s, l);
            if (fabs(q / pdf - 1) > worst) worst = fabs(q / pdf - 1);
            if (spherical_triangle(t, p, c, angle) >= SOLID_ANGLE_FROM) solid++;
            else area++;
        }
    }
    report(worst < 1e-6 && solid > 100 && area > 100, "sample_emitter's pdf is light_pdf's for the point it chose",
           "worst relative difference %.2g over %d points sampled by solid angle and %d by area", worst, solid, area);
    /* and what it estimates: the irradiance from each lamp triangle at
     * points below it, near (by solid angle) and beside it (by area), against
     * Lambert's formula */
    worst = 0, solid = area = 0;
    for (k = 0; k < 8; k++) {
        vec p = k % 2 ? v3(20 + 30 * k, 540, 30 + 20 * k) : v3(200 + 20 * k, 60 + 60 * k, 250 + 10 * k);
        vec n = v3(0, 1, 0), wi, Le, c[3];
        real angle[3];
        double sum = 0, sq = 0, mean, se, e = 0;
        real dist, pdf;
        int j, m = 40000;
        for (l = 0; l < s.lights.nemit && s.lights.emit[l].type != TRIANGLE_LIGHT; l++) continue;
        for (j = 0; j < m; j++) {
            sample_emitter(&s, l + j % 2, p, n, 0, (real)rnd(&x), (real)rnd(&x), &wi, &dist, &Le, &pdf);
            if (pdf > 0) {
                double f = fmax(0, dot(wi, n)) / pdf;
                sum += f, sq += f * f;
            }
        }
        for (j = 0; j < 2; j++) {
            const Triangle *t = &s.tri[s.lights.emit[l + j].obj - s.nsph - s.ncone];
            e += lambert(t, p, n);
            if (spherical_triangle(t, p, c, angle) >= SOLID_ANGLE_FROM) solid++;
            else area++;
        }
        mean = 2 * sum / m;                     /* each triangle half the time */
        se = 2 * sqrt(fmax(0, sq / m - sum / m * (sum / m)) / (m - 1));
        if (fabs(mean - e) / se > worst) worst = fabs(mean - e) / se;
    }
    report(worst < 4.5 && solid > 0 && area > 0, "the Cornell lamp's irradiance by sample_emitter against Lambert's formula",
           "worst difference %.2f standard errors at 8 points; of their 16 lamp triangles, %d by solid angle, %d by area",
           worst, solid, area);
    free_scene(&s);
}

int main(void)
{
    test_pdf_agrees();
    int bad = 0, k;
    double chi = 0, ez = 0;
    for (k = 0; k < 40; k++) test_triangle(20000, 1000 + k, &bad, &chi, &ez);
    report(bad == 0, "Arvo's sampler: every direction meets its triangle", "%d of %d missed", bad, 40 * 20000);
    /* chi-square of 15 degrees of freedom: 37.7 is its 99.9th percentile; the worst of 40 */
    report(chi < 44, "Arvo's sampler is uniform in solid angle: 16 sub-triangles (midpoints, twice) get their shares",
           "worst chi-square %.2f of 40 triangles, 15 degrees of freedom (fails above 44)", chi);
    report(ez < 4.5, "the irradiance by solid-angle samples against Lambert's polygon formula",
           "worst difference %.2f standard errors of 40 triangles", ez);
    return failures != 0;
}

/* --sampler sobol (ray.c's sobol01: Owen-scrambled Sobol' points, pair by
 * pair, Burley 2020), against what it must be:
 *  - within each pair of dimensions, any pixel's first 2^m samples form a
 *    (0, m, 2)-net: every box 2^-a wide and 2^-(m-a) high holds exactly one
 *    point (m = 2 .. 10, every a), for the lens's pair, a light's point, a
 *    direction and the pairs of single choices, at bounces 0 and 5;
 *  - each number alone is uniform: a chi-square test of 64 bins over
 *    many pixels, per dimension;
 *  - two dimensions of different pairs are independent: an 8 x 8
 *    chi-square of their joint histogram, and within a pixel their
 *    correlation over its samples is that of independent numbers, near;
 *  - pixels are independent: the correlation of a number with the same
 *    number of the next pixel is within 4 standard errors of 0;
 *  - the independent sampler is untouched: with --sampler independent,
 *    random01 is the hash it was.
 * Fixed pixels and samples: no seed to vary. */
#define main ray_main
#include "../ray.c"
#undef main
#include "report.h"

static Scene scene;

/* The numbers of sample k of pixel (i, j) in dimension dim. */
static double number(int i, int j, int k, unsigned dim)
{
    Worker wk;
    memset(&wk, 0, sizeof wk);
    start_sample(&wk, &scene, i, j, k);
    return (double)random01(&wk, dim);
}

/* Is the pair (d1, d2) of pixel (i, j) a (0, m, 2)-net in its first 2^m samples? */
static int is_net(int i, int j, unsigned d1, unsigned d2, int m)
{
    int n = 1 << m, a, k;
    static int count[1 << 10];
    for (a = 0; a <= m; a++) {
        int cols = 1 << a, rows = n / cols, c;
        memset(count, 0, sizeof(int) * (size_t)n);
        for (k = 0; k < n; k++) {
            int x = (int)(number(i, j, k, d1) * cols), y = (int)(number(i, j, k, d2) * rows);
            count[y * cols + x]++;
        }
        for (c = 0; c < n; c++)
            if (count[c] != 1) return 0;
    }
    return 1;
}

/* Sobol's second dimension by its definition: the direction numbers of
 * the polynomial x + 1, v_0 = 2^31 and each next v ^ (v >> 1), xored for
 * the bits of i (Sobol' 1967; Bratley and Fox 1988). */
static uint32_t sobol_second_by_definition(uint32_t i)
{
    uint32_t v = 1u << 31, r = 0;
    for (; i; i >>= 1, v ^= v >> 1)
        if (i & 1) r ^= v;
    return r;
}

/* Chi-square's upper tail bound, loosely: mean dof, sd sqrt(2 dof); 5 sd. */
static double chi_limit(int dof) { return dof + 5 * sqrt(2.0 * dof); }

int main(void)
{
    static const unsigned pairs[][2] = {
        { DIM_LENS_U, DIM_LENS_V },
        { DIM_BOUNCE + LIGHT_U, DIM_BOUNCE + LIGHT_V },
        { DIM_BOUNCE + DIRECTION_U, DIM_BOUNCE + DIRECTION_V },
        { DIM_BOUNCE + LIGHT_CHOICE, DIM_BOUNCE + LOBE },
        { DIM_BOUNCE + ROULETTE, DIM_BOUNCE + SPARE },
        { DIM_BOUNCE + 5 * BOUNCE_DIMS + LIGHT_U, DIM_BOUNCE + 5 * BOUNCE_DIMS + LIGHT_V },
        { DIM_BOUNCE + 5 * BOUNCE_DIMS + DIRECTION_U, DIM_BOUNCE + 5 * BOUNCE_DIMS + DIRECTION_V },
    };
    int p, m, i, k, nets = 0, tried = 0, worst_dim = 0;
    double worst = 0, chi2d, r, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
    default_scene(&scene);
    scene.set.w = 64, scene.set.h = 64;
    scene.set.integrator = PATH;
    scene.set.sampler = SOBOL;

    {   /* ray.c's Lucas-theorem form of the second dimension, against the definition */
        uint32_t x = 12345u, wrong = 0;
        for (k = 0; k < 1 << 20; k++) {
            uint32_t i2 = k < 1 << 16 ? (uint32_t)k : (x = x * 1664525u + 1013904223u);
            wrong += reverse_bits(sobol_second_reversed(i2)) != sobol_second_by_definition(i2);
        }
        report(wrong == 0, "Sobol's second dimension by Lucas's theorem equals its direction numbers'",
               "%u of %d indices differ (every one below 65536, and random ones)", wrong, 1 << 20);
    }
    for (p = 0; p < (int)(sizeof pairs / sizeof *pairs); p++)
        for (m = 2; m <= 10; m += 2)
            for (i = 0; i < 3; i++, tried++) nets += is_net(7 * i, 5 + i, pairs[p][0], pairs[p][1], m);
    report(nets == tried, "--sampler sobol: each pair's first 2^m samples of a pixel are a (0, m, 2)-net",
           "%d of %d pixel, pair and m from 2 to 10 (every box of area 2^-m holds one point)", nets, tried);

    {   /* each number alone: 64 bins, 4096 pixels x 4 samples, for 20 dimensions */
        unsigned dim;
        for (dim = DIM_LENS_U; dim < DIM_BOUNCE + 2 * BOUNCE_DIMS; dim++) {
            int bins[64] = { 0 }, b;
            double chi = 0, want = 4096.0 * 4 / 64;
            if (dim == DIM_TIME) continue;          /* the pixel's shift, not the sample's: independent */
            for (i = 0; i < 4096; i++)
                for (k = 0; k < 4; k++) bins[(int)(number(i % 64, i / 64, k, dim) * 64)]++;
            for (b = 0; b < 64; b++) chi += (bins[b] - want) * (bins[b] - want) / want;
            if (chi > worst) worst = chi, worst_dim = (int)dim;
        }
        report(worst < chi_limit(63), "--sampler sobol: each number alone is uniform (64 bins, 16384 numbers, 20 dimensions)",
               "worst chi-square %.1f in dimension %d, 63 degrees of freedom (fails above %.1f)", worst, worst_dim,
               chi_limit(63));
    }
    {   /* two numbers of different pairs: independent */
        int bins[64] = { 0 }, b;
        double want = 4096.0 * 4 / 64;
        chi2d = 0;
        for (i = 0; i < 4096; i++)
            for (k = 0; k < 4; k++) {
                int x = (int)(number(i % 64, i / 64, k, DIM_BOUNCE + LIGHT_U) * 8);
                int y = (int)(number(i % 64, i / 64, k, DIM_BOUNCE + DIRECTION_U) * 8);
                bins[y * 8 + x]++;
            }
        for (b = 0; b < 64; b++) chi2d += (bins[b] - want) * (bins[b] - want) / want;
        report(chi2d < chi_limit(63), "--sampler sobol: a light's u and a direction's u are independent (8 x 8 joint bins)",
               "chi-square %.1f, 63 degrees of freedom (fails above %.1f)", chi2d, chi_limit(63));
    }
    {   /* within a pixel, two pairs' numbers must not move together (each pair
         * has its own order of the samples): the squared correlation of a
         * light's u and a direction's u over a pixel's 16 samples, averaged
         * over 1000 pixels, is near independent numbers' 1/15 */
        double acc = 0;
        int px;
        for (px = 0; px < 1000; px++) {
            double x[16], y[16], mx = 0, my = 0, cxy = 0, cxx = 0, cyy = 0;
            for (k = 0; k < 16; k++) {
                x[k] = number(px % 64, px / 64, k, DIM_BOUNCE + LIGHT_U);
                y[k] = number(px % 64, px / 64, k, DIM_BOUNCE + DIRECTION_U);
                mx += x[k] / 16, my += y[k] / 16;
            }
            for (k = 0; k < 16; k++)
                cxy += (x[k] - mx) * (y[k] - my), cxx += (x[k] - mx) * (x[k] - mx), cyy += (y[k] - my) * (y[k] - my);
            acc += cxy * cxy / (cxx * cyy) / 1000;
        }
        report(acc < 2.5 / 15, "--sampler sobol: within a pixel, a light's u and a direction's u do not move together",
               "mean squared correlation over 16 samples %.4f (independent numbers: 1/15 = %.4f; fails above 2.5/15)", acc,
               1 / 15.0);
    }
    for (i = 0; i < 4000; i++) {    /* pixel (i mod 63, i / 63) against the pixel to its right */
        double x = number(i % 63, i / 63, 3, DIM_BOUNCE + DIRECTION_U) - 0.5;
        double y = number(i % 63 + 1, i / 63, 3, DIM_BOUNCE + DIRECTION_U) - 0.5;
        sx += x, sy += y, sxx += x * x, syy += y * y, sxy += x * y;
    }
    r = (sxy - sx * sy / 4000) / sqrt((sxx - sx * sx / 4000) * (syy - sy * sy / 4000));
    report(fabs(r) * sqrt(4000.0) < 4, "--sampler sobol: neighbouring pixels' numbers are uncorrelated",
           "correlation %.4f over 4000 pairs of pixels (fails beyond 4 standard errors, %.4f)", r, 4 / sqrt(4000.0));

    {   /* --sampler independent: the hash, as before the sampler existed */
        Worker wk;
        unsigned long long h;
        scene.set.sampler = INDEPENDENT;
        memset(&wk, 0, sizeof wk);
        start_sample(&wk, &scene, 3, 4, 5);
        h = mix64(mix64(mix64(mix64(scene.set.seed + 0x9e3779b97f4a7c15ULL) ^ (4ULL * 64 + 3)) ^ 5u)
                  + 0x9e3779b97f4a7c15ULL * (DIM_BOUNCE + 1ULL));
        report(random01(&wk, DIM_BOUNCE) == (real)((h >> 11) * (1.0 / 9007199254740992.0)),
               "--sampler independent: random01 is the hash of the sample and the dimension, as it was", "one number");
    }
    return failures != 0;
}

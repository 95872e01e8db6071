/* tools/manylights.c: writes scenes/lights100.sph, a floor lit by 100
 * glowing spheres of many sizes and powers (the many-light case of
 * next-event estimation: which light to sample at a point).
 *   cc -O2 -o /tmp/manylights tools/manylights.c -lm && /tmp/manylights > scenes/lights100.sph
 *
 * The lights stand on a jittered 10 x 10 grid over a 50 x 50 floor, at
 * heights 0.4 to 3; their radii are log-uniform over 0.05..0.5 and their
 * powers over three decades, so that the brightest few outshine the rest
 * from afar while each dim one still lights the floor beneath it.  A dozen
 * grey and coloured balls throw shadows.  C99, libc and libm only; the
 * output is a deterministic function of the seed below. */

#include <math.h>
#include <stdio.h>

/* A number in [0, 1) from a 64-bit linear congruential generator (Knuth's
 * MMIX constants), its top 53 bits. */
static double next(unsigned long long *x)
{
    *x = *x * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*x >> 11) / 9007199254740992.0;
}

int main(void)
{
    unsigned long long x = 100;
    const double pi = 3.14159265358979323846;
    int i, j;
    puts("# 100 glowing spheres over a floor, of radii 0.05..0.5 and powers over three");
    puts("# decades: choosing a light by its power alone starves the dim ones of the");
    puts("# floor beneath them (--light-choice power); by what each may bring to the");
    puts("# point, down the light tree, it does not.  Made by tools/manylights.c.");
    puts("#   ./ray --pt -n 16 scenes/lights100.sph");
    puts("size 320 240");
    puts("integrator path");
    puts("depth 4");
    puts("ambient 0 0 0");
    puts("background 0 0 0");
    puts("camera 0 -34 14   0 -4 0   0 0 1   60");
    puts("tri -25 -25 0  25 -25 0  25 25 0     .7 .7 .7  .8 0 0 0 1");
    puts("tri -25 -25 0  25 25 0  -25 25 0     .7 .7 .7  .8 0 0 0 1");
    for (i = 0; i < 12; i++) {                    /* the balls */
        double r = 0.6 + 1.2 * next(&x), h = next(&x);
        printf("%.3f %.3f %.3f   %.3f %.3f %.3f   %.3f   .8 0 0 0 1\n", -22 + 44 * next(&x),
               -22 + 44 * next(&x), r, 0.5 + 0.4 * cos(2 * pi * h), 0.5 + 0.4 * cos(2 * pi * (h - 1.0 / 3)),
               0.5 + 0.4 * cos(2 * pi * (h - 2.0 / 3)), r);
    }
    for (i = 0; i < 10; i++)
        for (j = 0; j < 10; j++) {                /* the lights */
            double r = 0.05 * pow(10, next(&x)), power = pow(10, 3 * next(&x)), h = next(&x);
            double kl = 0.004 * power / (r * r);  /* radiance: its power is 4 pi^2 r^2 kl */
            printf("%.3f %.3f %.3f   %.3f %.3f %.3f   %.4f   0 0 0 %.4g 1\n", -22.5 + 5 * i + 3 * (next(&x) - 0.5),
                   -22.5 + 5 * j + 3 * (next(&x) - 0.5), 0.4 + 2.6 * next(&x), 0.75 + 0.25 * cos(2 * pi * h),
                   0.75 + 0.25 * cos(2 * pi * (h - 1.0 / 3)), 0.75 + 0.25 * cos(2 * pi * (h - 2.0 / 3)), r, kl);
        }
    return 0;
}

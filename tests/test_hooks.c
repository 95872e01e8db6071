/* test_hooks.c - render()'s two hooks (ray.c's Hooks): the pre-pass runs
 * once, before any sample, and the splat image adds what samples splat to
 * other pixels, the same bytes for any number of threads.  Built with
 * OpenMP where the compiler has it (tests/hooks.test.sh).  ray.c is
 * included whole; prints "PASS name" / "FAIL name" lines. */
#define main ray_main
#include "../ray.c"
#undef main

#include "check.h"

/* What the hooks saw. */
typedef struct { int prepasses, early; } Seen;

static void prepass(const Scene *s, void *data)
{
    (void)s;
    ((Seen *)data)->prepasses++;
}

/* The light sample k of pixel (i, j) splats, and where: a hash of the
 * three, so that every pixel receives from many others. */
static void target(const Scene *s, int i, int j, int k, int *x, int *y, double *v)
{
    unsigned long long h = mix64(((unsigned long long)j * s->set.w + i) * 64 + (unsigned)k);
    *x = (int)(h % (unsigned)s->set.w);
    *y = (int)(h / 977 % (unsigned)s->set.h);
    *v = (double)(h >> 40) / (1 << 24);           /* in [0, 1) */
}

static void after_sample(const Scene *s, int i, int j, int k, Worker *wk, void *data)
{
    int x, y;
    double v;
    if (((Seen *)data)->prepasses == 0) ((Seen *)data)->early = 1;
    target(s, i, j, k, &x, &y, &v);
    splat(s, wk, x + (real)0.5, y + (real)0.5, v3(v, 2 * v, 0));
}

/* The minray scene, 24 x 16 at 3 samples, with the hooks, on t threads,
 * as floats: Whitted's, or path traced. */
static void render_with(int t, int path, Seen *seen, Image *img)
{
    Scene s;
    Options o;
    Counts c;
    Hooks h;
    if (!load_scene(&s, "scenes/minray.sph")) exit(2);
    s.set.w = 24;
    s.set.h = 16;
    if (path && !settle_path_options(&s, PATH, -1, 1, -1)) exit(2);
    memset(&o, 0, sizeof o);
    memset(&c, 0, sizeof c);
    memset(seen, 0, sizeof *seen);
    h.prepass = prepass;
    h.after_sample = after_sample;
    h.data = seen;
    o.spp = 3;
    o.threads = t;
    o.hooks = &h;
    if (!build_accel(&s, "none") || !new_image(img, s.set.w, s.set.h, 1, 0)) exit(2);
    whole_image(&s);
    render(&s, &o, img, &c);
    free_scene(&s);
}

int main(void)
{
    Image one, two, three, plain, pt[3];
    Seen seen;
    Scene s;
    Options o;
    Counts c;
    double worst = 0;
    int i, j, k, x, y, same;
    static double want[16][24][2];
    render_with(1, 0, &seen, &one);
    check(seen.prepasses == 1 && !seen.early, "hooks: the pre-pass runs once, before any sample");
    render_with(2, 0, &seen, &two);
    render_with(3, 0, &seen, &three);
    same = !memcmp(one.floats, two.floats, sizeof(float) * 3 * 24 * 16)
           && !memcmp(one.floats, three.floats, sizeof(float) * 3 * 24 * 16);
    check(same, "hooks: Whitted's splat image is the same bits with 1, 2 and 3 threads");
    for (k = 0; k < 3; k++) render_with(k + 1, 1, &seen, &pt[k]);
    same = !memcmp(pt[0].floats, pt[1].floats, sizeof(float) * 3 * 24 * 16)
           && !memcmp(pt[0].floats, pt[2].floats, sizeof(float) * 3 * 24 * 16);
    check(same && memcmp(pt[0].floats, one.floats, sizeof(float) * 3 * 24 * 16),
          "hooks: the path tracer's splat image is the same bits with 1, 2 and 3 threads");
    for (k = 0; k < 3; k++) free_image(&pt[k]);
    /* The splats by themselves: the image with them less the plain image,
     * times the samples, is what after_sample splatted into each pixel. */
    if (!load_scene(&s, "scenes/minray.sph")) exit(2);
    s.set.w = 24;
    s.set.h = 16;
    memset(&o, 0, sizeof o);
    memset(&c, 0, sizeof c);
    o.spp = 3;
    if (!build_accel(&s, "none") || !new_image(&plain, s.set.w, s.set.h, 1, 0)) exit(2);
    whole_image(&s);
    render(&s, &o, &plain, &c);
    memset(want, 0, sizeof want);
    for (j = 0; j < 16; j++)
        for (i = 0; i < 24; i++)
            for (k = 0; k < 3; k++) {
                double v;
                target(&s, i, j, k, &x, &y, &v);
                want[y][x][0] += v;
                want[y][x][1] += 2 * v;
            }
    for (j = 0; j < 16; j++)
        for (i = 0; i < 24; i++)
            for (k = 0; k < 2; k++) {
                size_t at = 3 * ((size_t)j * 24 + i) + k;
                worst = fmax(worst, fabs((one.floats[at] - plain.floats[at]) * 3 - want[j][i][k]));
            }
    printf("    largest error of a pixel's splatted sum: %g\n", worst);
    check(worst < 1e-5, "hooks: each pixel gets exactly what was splatted to it, over the samples");
    free_scene(&s);
    free_image(&one);
    free_image(&two);
    free_image(&three);
    free_image(&plain);
    return failures != 0;
}

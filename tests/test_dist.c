/* test_dist.c - distribution ray tracing (Cook, Porter and Carpenter 1984)
 * against geometry and against the path tracer: the thin lens's circle of
 * confusion, the penumbra of an area light against similar triangles, a
 * vanishing light against a point light, Whitted's direct light from an
 * area light against the path tracer's, and Whitted's glossy reflection
 * against its lobe's own cdf.
 *
 * Scenes are written as sphere files into the directory argv[1] and read as
 * a user's would be.  ray.c is included whole.  A Monte Carlo check states
 * its tolerance in standard errors; a geometric one in pixels.  Prints
 * "PASS name (figures)" / "FAIL name (figures)" lines for tests/run.sh. */
#define main ray_main
#include "../ray.c"
#undef main
#include "report.h"

static const char *dir;

/* The scene in text, written to dir/name and read; exits if it cannot be. */
static void scene_from(Scene *s, const char *name, const char *text)
{
    char path[512];
    FILE *f;
    sprintf(path, "%.400s/%.100s", dir, name);
    f = fopen(path, "w");
    if (!f || fputs(text, f) < 0 || fclose(f) != 0) { perror(path); exit(2); }
    if (!load_scene(s, path)) exit(2);
}

/* The scene rendered by one renderer at spp samples with a seed, into
 * floats (the radiance, or Whitted's colour, unrounded). */
static Image render_floats(Scene *s, int integrator, int spp, unsigned seed)
{
    Image img;
    Options o;
    Counts c;
    if (!settle_path_options(s, integrator, -1, 1, seed) || !build_accel(s, "auto")
        || !new_image(&img, s->set.w, s->set.h, 1, 0))
        exit(2);
    memset(&o, 0, sizeof o);
    memset(&c, 0, sizeof c);
    o.spp = spp;
    o.threads = 1;
    whole_image(s);
    render(s, &o, &img, &c);
    return img;
}

static float at(const Image *img, int i, int j) { return img->floats[3 * ((size_t)j * img->w + i)]; }

/* ---- the thin lens ---- */

/* The image's flux (the sum of its red channel); the variances of the
 * flux's distribution about its centroid along x and along y, and its
 * covariance of x and y, in pixels^2 (var[0..2]); and
 * the flux's variance as an estimate from spp samples a pixel, each 0 or 1
 * (a ray sees the glowing sphere or the black): v (1 - v) / spp a pixel. */
static void moments(const Image *img, int spp, double *flux, double var[3], double *flux_var)
{
    double sum = 0, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
    int i, j;
    *flux_var = 0;
    for (j = 0; j < img->h; j++)
        for (i = 0; i < img->w; i++) {
            double v = at(img, i, j), x = i + 0.5, y = j + 0.5;
            sum += v, sx += v * x, sy += v * y, sxx += v * x * x, syy += v * y * y, sxy += v * x * y;
            *flux_var += v * (1 - v) / (spp - 1);
        }
    *flux = sum;
    var[0] = sxx / sum - (sx / sum) * (sx / sum);
    var[1] = syy / sum - (sy / sum) * (sy / sum);
    var[2] = sxy / sum - (sx / sum) * (sy / sum);
}

#define LENS_W 64
#define LENS_FOV 40.0

/* A small glowing sphere on the axis at distance z, seen by a lens of
 * radius `lens` focused at `focus` (lens < 0: no lens line at all), black
 * all round, rendered by Whitted's renderer or the path tracer. */
static Image lens_image(double z, double lens, double focus, int integrator, int spp)
{
    char text[1024], line[128] = "";
    Scene s;
    Image img;
    if (lens >= 0) sprintf(line, "lens %.17g %.17g\n", lens, focus);
    sprintf(text, "size %d %d\ndepth 1\ncamera 0 0 0  0 1 0  0 0 1  %g\n%s"
            "0 %.17g 0  1 1 1  0.15  0 0 0 1 1\n", LENS_W, LENS_W, LENS_FOV, line, z);
    scene_from(&s, "lens.sph", text);
    img = render_floats(&s, integrator, spp, 1);
    free_scene(&s);
    return img;
}

/* The circle of confusion: a point at distance z seen through a lens of
 * diameter A focused at f blurs into a disc of diameter A |z - f| / z on
 * the plane of focus.  Its image is the pinhole image spread by a uniform
 * disc, and spreading adds variances: a disc of diameter D has D^2 / 16
 * along each axis, and no covariance of x and y.  So D = 4 sqrt(var(lens)
 * - var(pinhole)), measured along x and along y, against the prediction in
 * pixels (a pixel on the plane of focus is 2 f tan(fov/2) / width across);
 * and the spread must be round: the same along both axes, without a tilt. */
static void test_circle_of_confusion(int integrator)
{
    static const double zs[3] = { 8, 2, 4 };    /* behind, before and on the plane of focus */
    const double lens = 0.25, focus = 4, spp = 256;
    const char *who = integrator == PATH ? "path tracer" : "Whitted";
    int k;
    for (k = 0; k < 3; k++) {
        Image pin = lens_image(zs[k], -1, 0, integrator, (int)spp);
        Image blur = lens_image(zs[k], lens, focus, integrator, (int)spp);
        double fp, vp[3], sp, fb, vb[3], sb, pixel = 2 * focus * tan(LENS_FOV * PI / 360) / LENS_W;
        double want = 2 * lens * fabs(zs[k] - focus) / zs[k] / pixel, dx, dy, tilt;
        char name[160];
        moments(&pin, (int)spp, &fp, vp, &sp);
        moments(&blur, (int)spp, &fb, vb, &sb);
        dx = 4 * sqrt(fabs(vb[0] - vp[0]));
        dy = 4 * sqrt(fabs(vb[1] - vp[1]));
        /* the correlation of x and y in the spread: a disc's is 0, a line's 1 */
        tilt = fabs(vb[2] - vp[2]) / fmax(1e-9, (vb[0] - vp[0] + vb[1] - vp[1]) / 2);
        sprintf(name, "lens, %s: a point %s the plane of focus blurs into A |z - f| / z, within a"
                " pixel", who, k == 0 ? "behind" : k == 1 ? "before" : "on");
        report(fabs(dx - want) <= 1 && fabs(dy - want) <= 1 && (want < 1 || tilt <= 0.2), name,
               "z %g, f %g, A %g: diameter %.2f px along x, %.2f along y, predicted %.2f;"
               " correlation of x and y %.2f",
               zs[k], focus, 2 * lens, dx, dy, want, tilt);
        sprintf(name, "lens, %s: the blur keeps the light (z %g)", who, zs[k]);
        report(fabs(fb - fp) <= 4 * sqrt(sp + sb), name, "flux through the lens %.3f, the"
               " pinhole's %.3f: %.1f standard errors apart (allowed 4)", fb, fp,
               fabs(fb - fp) / sqrt(sp + sb));
        free_image(&pin);
        free_image(&blur);
    }
}

/* A lens of radius 0 is the pinhole: the same floats, bit for bit. */
static void test_aperture_zero(int integrator)
{
    Image pin = lens_image(8, -1, 0, integrator, 4), zero = lens_image(8, 0, 4, integrator, 4);
    char name[128];
    sprintf(name, "lens, %s: `lens 0 F` gives the pinhole's image bit for bit",
            integrator == PATH ? "path tracer" : "Whitted");
    report(!memcmp(pin.floats, zero.floats, sizeof(float) * 3 * LENS_W * LENS_W), name, "%dx%d",
           LENS_W, LENS_W);
    free_image(&pin);
    free_image(&zero);
}

/* ---- soft shadows ---- */

/* A glowing sphere of radius rho and radiance Le at height H above a white
 * floor, and a one-sided black sheet at height HO over the half x > 0,
 * facing the floor (the camera above sees through its back).  The camera
 * looks straight down on the strip y = 1.5, so that image column i sees
 * the floor point x_i: the shadow's edge runs across the image. */
#define SOFT_W 320
#define SOFT_H 2.0
#define SOFT_HO 2.0
#define SOFT_LIGHT 4.0

static Image soft_image(Scene *s, double rho, double Le, int shadow_rays)
{
    char text[2048];
    sprintf(text,
            "size %d 2\ndepth 1\nshadow %d\n"
            "camera 0 1.5 20  0 1.5 0  0 1 0  %.17g\n"
            "tri -50 -50 0  50 -50 0  50 50 0   1 1 1  1 0 0 0 1\n"
            "tri -50 -50 0  50 50 0  -50 50 0   1 1 1  1 0 0 0 1\n"
            "sided 1\n"
            "tri 0 -50 %g  0 50 %g  100 0 %g   0 0 0  0 0 0 0 1\n"
            "0 0 %g  1 1 1  %.17g  0 0 0 %.17g 1\n",
            SOFT_W, shadow_rays, 2 * atan(SOFT_H / 20) * 180 / PI, SOFT_HO, SOFT_HO, SOFT_HO,
            SOFT_LIGHT, rho, Le);
    scene_from(s, "soft.sph", text);
    return render_floats(s, WHITTED, 1, 1);
}

/* Where column i's ray meets the floor. */
static vec floor_point(const Scene *s, int i)
{
    Ray r = camera_ray(&s->cam, s->set.w, s->set.h, i + (real)0.5, (real)0.5);
    return comb(-r.o.z / r.d.z, r.d, r.o);
}

/* What a sphere of radius rho and radiance Le, wholly seen, gives Whitted's
 * white Lambertian floor at p: the irradiance pi Le (rho/d)^2 cos(theta),
 * that of a point light of intensity pi rho^2 Le at its centre (exact for
 * a sphere), over pi. */
static double unshadowed(vec p, double rho, double Le)
{
    vec d = sub(v3(0, 0, SOFT_LIGHT), p);
    double dist2 = dot(d, d);
    return Le * rho * rho / dist2 * (d.z / sqrt(dist2));
}

/* The penumbra, from the last column still fully lit to the first fully
 * dark, is as wide as similar triangles say: the light's diameter times
 * occluder-to-floor over light-to-occluder; exactly, for a sphere, where
 * the planes through the sheet's edge touch it.  Fully lit columns get the
 * unshadowed light, dark ones none. */
static void test_penumbra(void)
{
    const double rho = 0.25, Le = 1, eps = 1e-3;
    Scene s;
    Image img = soft_image(&s, rho, Le, 4096);
    double pixel = 2 * SOFT_H / SOFT_W, worst = 0, dark = 0;
    double similar = 2 * rho * SOFT_HO / (SOFT_LIGHT - SOFT_HO) / pixel;
    double tangent = 2 * rho * SOFT_HO / sqrt((SOFT_LIGHT - SOFT_HO) * (SOFT_LIGHT - SOFT_HO) - rho * rho)
                     / pixel;
    int i, lit_end = -1, dark_start = -1;
    for (i = 0; i < SOFT_W; i++) {
        double want = unshadowed(floor_point(&s, i), rho, Le), v = at(&img, i, 0);
        if (v >= (1 - eps) * want) lit_end = i;
        if (v <= eps * want && dark_start < 0 && lit_end >= 0) dark_start = i;
    }
    report(lit_end >= 0 && dark_start > lit_end && fabs((dark_start - lit_end) - similar) <= 2,
           "soft shadow: the penumbra is as wide as similar triangles say, within 2 pixels",
           "%d px from lit to dark; similar triangles %.2f, tangent planes %.2f", dark_start - lit_end,
           similar, tangent);
    for (i = 0; i < SOFT_W; i++) {
        vec p = floor_point(&s, i);
        double want = unshadowed(p, rho, Le), v = at(&img, i, 0);
        if (p.x < -tangent * pixel / 2 - pixel) worst = fmax(worst, fabs(v / want - 1));
        if (p.x > tangent * pixel / 2 + pixel) dark = fmax(dark, v);
    }
    report(worst < 1e-3 && dark == 0,
           "soft shadow: fully lit columns get the unshadowed sphere's light, dark ones none",
           "lit: worst relative error %.2g; dark: largest %.2g", worst, dark);
    free_image(&img);
    free_scene(&s);
}

/* A light of radius -> 0 and the same power: its image converges to a point
 * light's (intensity pi rho^2 Le), a hard shadow at x = 0. */
static void test_vanishing_light(void)
{
    const double rho = 1e-4, Le = 0.0625 / (rho * rho);
    Scene s;
    Image img = soft_image(&s, rho, Le, 16);
    double worst = 0;
    int i, edge_ok = 1;
    for (i = 0; i < SOFT_W; i++) {
        vec p = floor_point(&s, i);
        double want = p.x < 0 ? unshadowed(p, 0.25, 1) : 0, v = at(&img, i, 0);
        if (fabs(p.x) < 2 * SOFT_H / SOFT_W) continue;      /* the edge's own column */
        if (p.x < 0) worst = fmax(worst, fabs(v / want - 1));
        else edge_ok &= v == 0;
    }
    report(worst < 1e-3 && edge_ok,
           "soft shadow: a light of radius -> 0 gives the point light's image and hard shadow",
           "radius %g: worst relative error %.2g", rho, worst);
    free_image(&img);
    free_scene(&s);
}

/* A worker for tracing rays one by one, as render() would give one. */
static Worker worker(void)
{
    Worker wk;
    int i;
    memset(&wk, 0, sizeof wk);
    for (i = 0; i < SHADOW_SLOTS; i++) wk.blocker[i] = -1;
    wk.budget = RAY_BUDGET;
    return wk;
}

/* Mean and standard error of n samples of ray r's value (red channel):
 * Whitted's colour, or the path tracer's radiance; sample k of "pixel" p. */
static void ray_mean(const Scene *s, Ray r, int path_traced, int p, int n, double *mean, double *se)
{
    Worker wk = worker();
    double sum = 0, sum2 = 0;
    int k;
    for (k = 0; k < n; k++) {
        double v;
        start_sample(&wk, s, p, 0, k);
        if (path_traced) {
            Path path;
            path.beta = v3(1, 1, 1);
            path.rays = 1;
            path.counted = 1;
            v = radiance(s, r, &path, &wk).x;
        } else {
            wk.budget = RAY_BUDGET;
            v = trace(s, r, s->set.depth, 1, &wk).x;
        }
        sum += v, sum2 += v * v;
    }
    *mean = sum / n;
    *se = sqrt(fmax(0, sum2 / n - *mean * *mean) / (n - 1));
}

/* Whitted's direct light from an area light against the path tracer's at
 * depth 2 (its camera ray and one bounce: emission and direct light only),
 * ray by ray: from the eye to 7 x 7 points of the floor across the
 * penumbra of a sheet's edge (the sheet faces the floor; the eye sees
 * through its back), each estimated from 4000 samples by each
 * renderer, with seeds of their own (the same numbers in both would
 * correlate their errors).  The two means must agree within 4.5 standard
 * errors of their difference at every point. */
static void test_whitted_equals_path(void)
{
    const char *text = "depth 2\ncamera 1 -6 5  0 1 0  0 0 1  60\n"
                       "tri -50 -50 0  50 -50 0  50 50 0   1 1 1  .8 0 0 0 1\n"
                       "tri -50 -50 0  50 50 0  -50 50 0   1 1 1  .8 0 0 0 1\n"
                       "sided 1\ntri 0 -5 2  0 5 2  6 0 2   .5 .5 .5  .5 0 0 0 1\n"
                       "0 0 4  1 1 1  0.5  0 0 0 1 1\n";
    Scene w, p;
    double worst = 0, m[2], se[2];
    int i, j, exact = 1;
    scene_from(&w, "direct.sph", text);
    scene_from(&p, "direct.sph", text);
    if (!settle_path_options(&w, WHITTED, -1, 1, 1) || !build_accel(&w, "auto")
        || !settle_path_options(&p, PATH, -1, 1, 2) || !build_accel(&p, "auto"))
        exit(2);
    for (j = 0; j < 7; j++)
        for (i = 0; i < 7; i++) {
            vec target = v3(-0.6 + 0.2 * i, -2 + j, 0);
            Ray r;
            r.o = v3(1, -6, 5);
            r.d = unit(sub(target, r.o));
            r.tmin = 0;
            r.skip = -1;
            r.time = 0;
            ray_mean(&w, r, 0, 7 * j + i, 4000, &m[0], &se[0]);
            ray_mean(&p, r, 1, 7 * j + i, 4000, &m[1], &se[1]);
            if (se[0] == 0 && se[1] == 0) exact &= m[0] == m[1];
            else worst = fmax(worst, fabs(m[0] - m[1]) / sqrt(se[0] * se[0] + se[1] * se[1]));
        }
    report(worst < 4.5 && exact, "soft shadow: Whitted's direct light from an area light is the"
           " path tracer's at depth 2", "49 rays, 4000 samples each: largest difference %.2f"
           " standard errors (allowed 4.5)%s", worst, exact ? "" : "; a noiseless ray differs");
    free_scene(&w);
    free_scene(&p);
}

/* ---- glossy reflection ---- */

/* A glossy plate (`glossy n`, ks 1, nothing else) under a glowing sphere
 * centred on the mirror direction of one camera ray, subtending a cone of
 * half-angle a: Whitted's spread mirror ray hits it with the lobe's chance
 * of falling within a of the mirror, 1 - cos^(n+1)(a) by the cdf of
 * phong_lobe, so the ray's colour is that times the sphere's kl. */
static void test_glossy(void)
{
    const double n = 20, dist = 5, rho = 1.5;
    double want = 1 - pow(sqrt(1 - rho * rho / (dist * dist)), n + 1), sum = 0, sum2 = 0, m, se;
    char text[1024];
    Scene s;
    Worker wk = worker();
    Ray r;
    int k, N = 20000;
    vec mirror = unit(v3(0, 1, 1));                 /* the camera's ray (0, 1, -1) off z = 0 */
    vec c = scale(dist, mirror);
    sprintf(text, "depth 2\ncamera 0 -1 1  0 0 0  0 0 1  10\nglossy %g\n"
            "tri -9 -9 0  9 -9 0  9 9 0  1 1 1  0 1 0 0 1\ntri -9 -9 0  9 9 0  -9 9 0  1 1 1  0 1 0 0 1\n"
            "glossy 0\n%.17g %.17g %.17g  1 1 1  %g  0 0 0 1 1\n", n, c.x, c.y, c.z, rho);
    scene_from(&s, "glossy.sph", text);
    if (!settle_path_options(&s, WHITTED, -1, 1, 1) || !build_accel(&s, "none")) exit(2);
    r.o = v3(0, -1, 1);
    r.d = unit(v3(0, 1, -1));
    r.tmin = 0;
    r.skip = -1;
    r.time = 0;
    for (k = 0; k < N; k++) {
        double v;
        start_sample(&wk, &s, 0, 0, k);
        wk.budget = RAY_BUDGET;
        v = trace(&s, r, s.set.depth, 1, &wk).x;
        sum += v, sum2 += v * v;
    }
    m = sum / N;
    se = sqrt(fmax(0, sum2 / N - m * m) / (N - 1));
    report(fabs(m - want) <= 4 * se, "glossy: Whitted's spread mirror ray follows the Phong lobe",
           "exponent %g, cone %.1f degrees: %.4f +- %.4f, want %.4f (4 standard errors)", n,
           asin(rho / dist) * 180 / PI, m, se, want);
    free_scene(&s);
}

int main(int argc, char **argv)
{
    if (argc != 2) { fprintf(stderr, "usage: test_dist DIR\n"); return 2; }
    dir = argv[1];
    test_circle_of_confusion(WHITTED);
    test_circle_of_confusion(PATH);
    test_aperture_zero(WHITTED);
    test_aperture_zero(PATH);
    test_penumbra();
    test_vanishing_light();
    test_whitted_equals_path();
    test_glossy();
    return failures != 0;
}

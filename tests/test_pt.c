/* test_pt.c - the path tracer against analytic answers.
 *
 * ray.c is included whole, as tests/test_ray.c does.  Each check of a Monte
 * Carlo estimate compares float values (never bytes) and allows K standard
 * errors, the standard error measured from the samples themselves.  K = 4:
 * a correct estimator fails one check in about 16000; the seeds are fixed,
 * so a run that passes passes again.  Where an estimate has no variance (a
 * furnace with a depth bound and no roulette), it must be exact to 1e-9.
 * Prints "PASS name" / "FAIL name" lines for tests/run.sh. */
#define main ray_main
#include "../ray.c"
#undef main
#include "report.h"

#define K 4.0

/* Running mean and variance of one channel's samples. */
typedef struct { double n, sum, sum2; } Stat;

static void stat_add(Stat *st, double x) { st->n++; st->sum += x; st->sum2 += x * x; }
static double stat_mean(const Stat *st) { return st->sum / st->n; }
static double stat_se(const Stat *st)
{
    double m = stat_mean(st), var = (st->sum2 - st->n * m * m) / (st->n - 1);
    return sqrt(fmax(var, 0) / st->n);
}

/* |mean - want| within K standard errors, or exact when there is no
 * variance to speak of. */
static int agrees(const Stat *st, double want)
{
    return fabs(stat_mean(st) - want) <= K * stat_se(st) + 1e-9 * fabs(want);
}

static Worker worker(void)
{
    Worker wk;
    int i;
    memset(&wk, 0, sizeof wk);
    for (i = 0; i < SHADOW_SLOTS; i++) wk.blocker[i] = -1;
    return wk;
}

/* The tests' own random numbers, one after another: the n-th is a hash of
 * (seed, n).  The renderer draws each of its numbers from a named slot
 * instead (ray.c's samples section); a test that only needs many
 * independent numbers takes them in turn from here. */
typedef struct { unsigned long long key, n; } Sequence;

static Sequence sequence(unsigned long long seed)
{
    Sequence q;
    q.key = mix64(seed ^ 0x5851f42d4c957f2dULL);
    q.n = 0;
    return q;
}

static double next01(Sequence *q)
{
    return (double)(mix64(q->key + 0x9e3779b97f4a7c15ULL * ++q->n) >> 11) * (1.0 / 9007199254740992.0);
}

static int material(Scene *s, vec color, double kd, double ks, double kt, double kl, double ir,
                    double shine)
{
    Material m;
    memset(&m, 0, sizeof m);
    m.color = color;
    m.kd = kd; m.ks = ks; m.kt = kt; m.kl = kl; m.ir = ir; m.shine = shine;
    m.rough = s->rough;                         /* as a scene's `rough` line would */
    return add_material(s, m);
}

static void camera(Scene *s, vec eye, vec at, vec up, double fov)
{
    real v[10];
    v[0] = eye.x; v[1] = eye.y; v[2] = eye.z; v[3] = at.x; v[4] = at.y; v[5] = at.z;
    v[6] = up.x; v[7] = up.y; v[8] = up.z; v[9] = fov;
    set_camera(s, v, (char[SCENE_WHY]){ 0 });
}

/* The quadrilateral a b c d as two triangles, a b c and a c d: its front
 * is the side from which a b c d turn counter-clockwise. */
static void quad(Scene *s, vec a, vec b, vec c, vec d, int mat)
{
    int i = add_vertex(s, a), j = add_vertex(s, b), k = add_vertex(s, c), l = add_vertex(s, d);
    add_triangle(s, i, j, k, -1, -1, -1, mat);
    add_triangle(s, i, k, l, -1, -1, -1, mat);
}

/* One path's radiance back along the ray from o in the unit direction d,
 * from the numbers of the sample the worker was started at: a camera
 * ray's, at time 0. */
static vec radiance_along(const Scene *s, vec o, vec d, Worker *wk)
{
    Path path;
    Ray ry;
    ry.o = o, ry.d = d, ry.tmin = 0, ry.skip = -1, ry.time = 0;
    path.beta = v3(1, 1, 1), path.rays = 1, path.counted = 1, path.pdf = 0;
    return radiance(s, ry, &path, wk);
}

/* The scene made ready for the path tracer: estimator, roulette, a bound
 * on the rays of a path (0: none), the structure, the lights. */
static void ready(Scene *s, int estimator, int roulette, int max_rays)
{
    s->set.max_rays = max_rays;
    build_accel(s, "auto");
    settle_path_options(s, PATH, estimator, roulette, 7);
}

/* The scene in file at w x h pixels, ready for the path tracer with the
 * given estimator, roulette on, at most max_rays rays a path (0: no bound);
 * 0 after a FAIL line for the check `name`. */
static int scene_file(Scene *s, const char *file, int w, int h, int estimator, int max_rays,
                      const char *name)
{
    if (!load_scene(s, file)) {
        report(0, name, "cannot load %s", file);
        return 0;
    }
    s->set.w = w;
    s->set.h = h;
    ready(s, estimator, 1, max_rays);
    return 1;
}

/* The Cornell box at size x size. */
static int cornell(Scene *s, int size, int estimator, const char *name)
{
    return scene_file(s, "scenes/cornell.sph", size, size, estimator, 0, name);
}

/* n samples spread over the image, channel c of each. */
static Stat image_samples(const Scene *s, int n, int c)
{
    Worker wk = worker();
    Stat st = { 0, 0, 0 };
    int k;
    for (k = 0; k < n; k++) {
        int pixel = k % (s->set.w * s->set.h);
        vec L = sample_radiance(s, pixel % s->set.w, pixel / s->set.w, k / (s->set.w * s->set.h), &wk);
        stat_add(&st, c == 0 ? L.x : c == 1 ? L.y : L.z);
    }
    return st;
}

static const char *const est_name[] = { "bsdf", "nee", "mis" };

/* ---- the furnace ---- */

/* Inside a closed sphere of albedo a whose wall emits Le, radiance is the
 * same everywhere: Le + a Le + a^2 Le + ... = Le / (1 - a), and with at most
 * N bounces (N + 1 rays) Le (1 - a^(N+1)) / (1 - a).  Each estimator, with
 * roulette on and off. */
static void test_furnace(void)
{
    static const double albedo[2] = { 0.5, 0.8 };
    int e, ai, roulette, bounces, sampler;
    char name[160];
    for (sampler = INDEPENDENT; sampler <= SOBOL; sampler++)    /* --sampler: both keep the mean */
    for (ai = 0; ai < 2; ai++)
        for (e = 0; e < 3; e++)
            for (roulette = 1; roulette >= 0; roulette--)
                for (bounces = -1; bounces <= 3; bounces += 2) {
                    double a = albedo[ai], Le = 1.5, want;
                    Scene s;
                    Stat st;
                    if (bounces < 0 && !roulette) continue;   /* paths would not end */
                    default_scene(&s);
                    s.set.w = s.set.h = 8;
                    add_sphere(&s, v3(1, 2, 3), 2, material(&s, v3(1, 1, 1), a, 0, 0, Le, 1, 0));
                    camera(&s, v3(1, 2, 3), v3(1, 3, 3), v3(0, 0, 1), 90);
                    ready(&s, e, roulette, bounces < 0 ? 0 : bounces + 1);
                    s.set.sampler = sampler;
                    want = bounces < 0 ? Le / (1 - a) : Le * (1 - pow(a, bounces + 1)) / (1 - a);
                    st = image_samples(&s, 20000, 0);
                    sprintf(name, "furnace, albedo %.1f, %s, roulette %s, %s: L = %s%s",
                            a, est_name[e], roulette ? "on" : "off",
                            bounces < 0 ? "no bound" : bounces == 1 ? "1 bounce" : "3 bounces",
                            bounces < 0 ? "Le/(1-a)" : "Le(1-a^(N+1))/(1-a)",
                            sampler == SOBOL ? ", --sampler sobol" : "");
                    report(agrees(&st, want), name, "%.6f +- %.6f, want %.6f", stat_mean(&st),
                           stat_se(&st), want);
                    free_scene(&s);
                }
}

/* ---- a point light inside a sphere ---- */

/* A point light of intensity I at the centre of a sphere of radius R and
 * albedo rho: the wall receives I / R^2 directly and sends rho/pi of it
 * back, and the bounces multiply that by 1 / (1 - rho):
 * L = rho I / (pi R^2 (1 - rho)).  BSDF sampling alone never finds a point
 * light, so it must see nothing at all. */
static void test_point_in_sphere(void)
{
    double R = 2.5, rho = 0.6, I = 3;
    int e;
    char name[160];
    for (e = 0; e < 3; e++) {
        Scene s;
        Stat st;
        double want;
        default_scene(&s);
        s.set.w = s.set.h = 8;
        add_sphere(&s, v3(0, 0, 0), R, material(&s, v3(1, 1, 1), rho, 0, 0, 0, 1, 0));
        add_light(&s, v3(0, 0, 0), v3(I, I, I), -1);
        camera(&s, v3(0.3, -0.2, 0.1), v3(1, 1, 0.5), v3(0, 0, 1), 100);
        ready(&s, e, 1, 0);
        st = image_samples(&s, 20000, 1);
        want = e == BSDF_ONLY ? 0 : rho * I / (PI * R * R * (1 - rho));
        sprintf(name, "point light in a sphere, %s: L = %s", est_name[e],
                e == BSDF_ONLY ? "0 (BSDF sampling cannot find a point light)"
                               : "rho I / (pi R^2 (1 - rho))");
        report(agrees(&st, want), name, "%.6f +- %.6f, want %.6f", stat_mean(&st), stat_se(&st), want);
        free_scene(&s);
    }
}

/* ---- a sphere light is a point light ---- */

/* A Lambertian sphere of radius r and radiance Le emits Phi = pi Le 4 pi r^2,
 * and on a receiver that sees all of it, it lights like a point light of
 * intensity Phi / 4 pi = pi r^2 Le at its centre: E = I cos(theta) / d^2.
 * A floor of albedo rho under a sphere light; the radiance of random floor
 * points straight up, direct light only (2 rays a path), against
 * rho / pi * I cos(theta) / d^2 point by point.  And again with a black
 * ball inside the lamp (radius 0.8 r, at its centre), which the lamp hides
 * from every point outside it: a shadow ray must stop where the ray meets
 * the lamp's near side, not its far side (the sample's ray through the
 * lamp passes the ball on the way there). */
static void test_sphere_is_point(void)
{
    double r = 0.5, Le = 2, rho = 0.7, I = PI * r * r * Le;
    vec c = v3(0.7, -0.4, 2.2);
    int e, inside;
    char name[160];
    for (inside = 0; inside < 2; inside++)
        for (e = 0; e < 3; e++) {
            Scene s;
            Worker wk = worker();
            Stat st = { 0, 0, 0 };
            int floor_mat, k;
            default_scene(&s);
            floor_mat = material(&s, v3(1, 1, 1), rho, 0, 0, 0, 1, 0);
            quad(&s, v3(-6, -6, 0), v3(6, -6, 0), v3(6, 6, 0), v3(-6, 6, 0), floor_mat);
            add_sphere(&s, c, r, material(&s, v3(1, 1, 1), 0, 0, 0, Le, 1, 0));
            if (inside) add_sphere(&s, c, 0.8 * r, material(&s, v3(1, 1, 1), 0, 0, 0, 0, 1, 0));
            ready(&s, e, 0, 2);
            for (k = 0; k < 40000; k++) {
                vec p, d, L;
                double want;
                start_sample(&wk, &s, k, 1, 0);     /* the point takes the pixel's dimensions */
                p = v3(4 * random01(&wk, DIM_PIXEL_X) - 2, 4 * random01(&wk, DIM_PIXEL_Y) - 2, 0);
                L = radiance_along(&s, v3(p.x, p.y, 1), v3(0, 0, -1), &wk);   /* below the light */
                d = sub(c, p);
                want = rho / PI * I * d.z / sqrt(dot(d, d)) / dot(d, d);
                stat_add(&st, L.x - want);
            }
            sprintf(name, "sphere light = point light of intensity Phi/4pi on a floor%s, %s",
                    inside ? ", a black ball inside the lamp" : "", est_name[e]);
            report(agrees(&st, 0), name, "mean difference %.2g +- %.2g over %g points", stat_mean(&st),
                   stat_se(&st), st.n);
            free_scene(&s);
        }
}

/* ---- glass: Fresnel's share reflected, the rest refracted ---- */

/* Fresnel's reflectance of unpolarised light meeting, at angle i to the
 * normal, a surface from index n1 to index n2: the textbook's sine and
 * tangent form, Rs = sin^2(i - t) / sin^2(i + t), Rp = tan^2(i - t) /
 * tan^2(i + t) (Born and Wolf, Principles of Optics, 1.5.2), written apart
 * from ray.c's fresnel(); ((n1 - n2) / (n1 + n2))^2 head on, where the form
 * is 0/0, and 1 past the critical angle. */
static double fresnel_textbook(double i, double n1, double n2)
{
    double st = n1 / n2 * sin(i), t, rs, rp;
    if (st >= 1) return 1;
    if (i == 0) return (n1 - n2) * (n1 - n2) / ((n1 + n2) * (n1 + n2));
    t = asin(st);
    rs = sin(i - t) / sin(i + t), rp = tan(i - t) / tan(i + t);
    return (rs * rs + rp * rp) / 2;
}

/* The path tracer's glass splits light as Fresnel says: a face of glass
 * (n = 1.5, the plane z = 0, glass below) under a red sky of radiance 1,
 * with a blue lamp of radiance 1 in the glass beneath it (z = -1), and
 * nothing else.  A ray from above at angle i either reflects to the sky or
 * refracts to the lamp: its red is the reflectance R(i) and its blue
 * (1 - R) / n^2 (radiance spreads leaving a denser medium, as the check of
 * the ball's n^2 says).  From inside the glass the roles swap: blue is R,
 * red n^2 (1 - R), and past the critical angle all of it is blue.  One
 * interface, so no sum over internal reflections (a slab's, where
 * ray.c's unpolarised F at each face and the polarised truth part by some
 * 0.01 at 60 degrees); the glass's number is the lobe's (sample_glass),
 * and the rest of the path has none: the sky and the lamp end it.  Each
 * share within K standard errors of the textbook's R (exact where it has
 * no variance).  Glass that reflects with the chance 1 - F instead turns
 * the face into a mirror (0.96 of the light head on), which the vanishing
 * ball lets through: there the sky is the same both ways.
 * Whitted's renderer has no Fresnel split to check: its glass weighs the
 * reflected and refracted rays by the card's ks and kt. */
static void test_glass_split(void)
{
    /* mirror: the share of a mirror (ks) in the material, the rest glass (kt) */
    static const struct { double degrees; int inside; double mirror; } c[] = {
        { 0, 0, 0 }, { 45, 0, 0 }, { 80, 0, 0 }, { 30, 1, 0 }, { 60, 1, 0 }, { 45, 0, 0.5 },
    };
    double n = 1.5;
    int k, q;
    char name[200];
    for (q = 0; q < (int)(sizeof c / sizeof c[0]); q++) {
        double i = c[q].degrees * PI / 180, m = c[q].mirror, R, reflected, refracted, want_red, want_blue;
        Scene s;
        Worker wk = worker();
        Stat red = { 0, 0, 0 }, blue = { 0, 0, 0 };
        vec d;
        default_scene(&s);
        s.background = v3(1, 0, 0);
        quad(&s, v3(-100, -100, 0), v3(100, -100, 0), v3(100, 100, 0), v3(-100, 100, 0),
             material(&s, v3(1, 1, 1), 0, m, 1 - m, 0, n, 0));
        quad(&s, v3(-100, -100, -1), v3(100, -100, -1), v3(100, 100, -1), v3(-100, 100, -1),
             material(&s, v3(0, 0, 1), 0, 0, 0, 1, 1, 0));
        ready(&s, MIS, 1, 0);
        d = v3(sin(i), 0, c[q].inside ? cos(i) : -cos(i));
        for (k = 0; k < 20000; k++) {
            vec L;
            start_sample(&wk, &s, 0, 0, k);
            L = radiance_along(&s, c[q].inside ? v3(0, 0, -0.5) : v3(0, 0, 1), d, &wk);
            stat_add(&red, L.x);
            stat_add(&blue, L.z);
        }
        R = c[q].inside ? fresnel_textbook(i, n, 1) : fresnel_textbook(i, 1, n);
        reflected = m + (1 - m) * R, refracted = (1 - m) * (1 - R);
        want_red = c[q].inside ? n * n * refracted : reflected;
        want_blue = c[q].inside ? reflected : refracted / (n * n);
        sprintf(name, "glass%s %s at %g degrees: %s %sR, %s %s(1 - R), R = Fresnel's %.4f%s",
                m > 0 ? " (kt 0.5 under a mirror ks 0.5)" : "",
                c[q].inside ? "from inside" : "from outside", c[q].degrees,
                c[q].inside ? "blue (reflected)" : "red (reflected)", m > 0 ? "ks + kt " : "",
                c[q].inside ? "red (refracted) n^2" : "blue (refracted) 1/n^2", m > 0 ? "kt " : "", R,
                R == 1 ? " (total internal reflection)" : "");
        report(agrees(&red, want_red) && agrees(&blue, want_blue), name,
               "red %.5f +- %.5f, want %.5f; blue %.5f +- %.5f, want %.5f", stat_mean(&red),
               stat_se(&red), want_red, stat_mean(&blue), stat_se(&blue), want_blue);
        free_scene(&s);
    }
}

/* ---- triangle and quad lights: Lambert's polygon ---- */

/* The irradiance at x (unit normal nx) from a polygon v[0..n-1] of
 * radiance L wholly above x's horizon: Lambert's formula (Lambert,
 * Photometria, 1760; in the form of Arvo, "Applications of Irradiance
 * Tensors to the Simulation of Non-Lambertian Phenomena", SIGGRAPH 1995),
 *
 *     E = L/2 |sum over the edges of beta_i (nx . gamma_i)|,
 *
 * beta_i the angle the edge v_i v_i+1 subtends at x, gamma_i the unit
 * normal of the plane through x and the edge: exact, with no sampling. */
static double lambert_polygon(const vec *v, int n, vec x, vec nx, double L)
{
    double sum = 0;
    int i;
    for (i = 0; i < n; i++) {
        vec a = unit(sub(v[i], x)), b = unit(sub(v[(i + 1) % n], x)), g = cross(a, b);
        double sine = sqrt(dot(g, g));
        sum += atan2(sine, dot(a, b)) * dot(nx, g) / sine;
    }
    return L / 2 * fabs(sum);
}

/* A one-sided lamp of radiance Le facing down onto a floor of albedo rho:
 * a tilted triangle, and a quad (two triangles of unequal area, so that the
 * choice between them by power counts).  The radiance of random floor
 * points straight up, direct light only (2 rays a path), is rho/pi E, E
 * Lambert's; by light sampling alone (nee: sample_emitter's points of the
 * triangles), BSDF sampling alone (the lamp found by the floor's own
 * bounce), MIS, and Whitted's area light (the same points as nee's, in R2
 * patterns).  The mean difference to rho/pi E within K standard errors:
 * where the lamps' points are not uniform over each triangle, or the
 * triangles not chosen by their area, nee and MIS are off (the Cornell box,
 * where a bias only moves a mean no test knew, let that through).  And the
 * triangle again behind a black square just below it, which hides it from
 * every point of the floor looked at: E = 0, so that a shadow ray that
 * stops short of the lamp (sees only the blockers near the floor) fails.
 * And a far triangle, 400 above the floor, whose solid angle (0.008) is
 * below SOLID_ANGLE_FROM, so that sample_emitter picks its points by area
 * and light_pdf turns that pdf into solid angle, dist^2 / (A cos): MIS
 * weighs a BSDF sample that finds the lamp by it, and with a pdf off by a
 * factor dist (400) the weights of a direction no longer sum to 1.  And
 * the first triangle again, one-sided (`sided 1`) and turned to face up,
 * away from the floor: it lights nothing, whether a path finds it by a
 * BSDF sample (emitted() must see its back) or by a light sample. */
static void test_polygon_lights(void)
{
    static const vec tri[3] = { { -1, -0.5, 1.6 }, { 0.2, 1.3, 1.4 }, { 1.2, -0.9, 1.1 } };
    static const vec quad4[4] = { { -1, -0.8, 1.5 }, { -0.7, 0.9, 1.5 }, { 0.9, 1.1, 1.5 }, { 1.2, -1, 1.5 } };
    static const vec far[3] = { { -30, -20, 400 }, { 2, 24, 400 }, { 32, -18, 400 } };
    static const char *const how[4] = { "bsdf", "nee", "mis", "Whitted's area light" };
    static const char *const what[5] = {
        "a triangle lamp lights a floor as Lambert's polygon formula says",
        "a quad lamp (two triangles) lights a floor as Lambert's polygon formula says",
        "a triangle lamp behind a black square just below it lights nothing",
        "a far triangle lamp (0.008 sr: sampled by area) lights a floor as Lambert's polygon formula says",
        "a one-sided triangle lamp facing away from the floor lights nothing",
    };
    double Le = 2, rho = 0.7;
    int lamp, e, k;
    char name[200];
    for (lamp = 0; lamp < 5; lamp++)
        for (e = 0; e < 4; e++) {
            const vec *v = lamp == 1 ? quad4 : lamp == 3 ? far : tri;
            int nv = lamp == 1 ? 4 : 3, light;
            Scene s;
            Worker wk = worker();
            Stat st = { 0, 0, 0 }, want = { 0, 0, 0 };
            default_scene(&s);
            quad(&s, v3(-6, -6, 0), v3(6, -6, 0), v3(6, 6, 0), v3(-6, 6, 0),
                 material(&s, v3(1, 1, 1), rho, 0, 0, 0, 1, 0));
            if (lamp == 2)                   /* below every point of the lamp, over x, y in [-3, 3] */
                quad(&s, v3(-3, -3, 1), v3(3, -3, 1), v3(3, 3, 1), v3(-3, 3, 1),
                     material(&s, v3(1, 1, 1), 0, 0, 0, 0, 1, 0));
            light = material(&s, v3(1, 1, 1), 0, 0, 0, Le, 1, 0);
            s.cull = 1;                      /* `sided 1`: the lamp lights from its front, below */
            if (lamp == 1) quad(&s, v[0], v[1], v[2], v[3], light);
            else if (lamp == 4)              /* its corners the other way round: its front is up */
                add_triangle(&s, add_vertex(&s, v[0]), add_vertex(&s, v[2]), add_vertex(&s, v[1]), -1, -1, -1, light);
            else add_triangle(&s, add_vertex(&s, v[0]), add_vertex(&s, v[1]), add_vertex(&s, v[2]), -1, -1, -1, light);
            s.set.depth = 1;                 /* Whitted's: the floor's direct light alone */
            ready(&s, e < 3 ? e : MIS, 0, 2);
            for (k = 0; k < 40000; k++) {
                vec p, L;
                double E;
                Ray ry;
                start_sample(&wk, &s, k, 2, 0);
                p = v3(4 * random01(&wk, DIM_PIXEL_X) - 2, 4 * random01(&wk, DIM_PIXEL_Y) - 2, 0);
                ry.o = v3(p.x, p.y, 0.5), ry.d = v3(0, 0, -1), ry.tmin = 0, ry.skip = -1, ry.time = 0;
                L = e < 3 ? radiance_along(&s, ry.o, ry.d, &wk) : trace(&s, ry, 1, 1, &wk);
                E = lamp == 2 || lamp == 4 ? 0 : lambert_polygon(v, nv, p, v3(0, 0, 1), Le);
                stat_add(&st, L.x - rho / PI * E);
                stat_add(&want, rho / PI * E);
            }
            sprintf(name, "%s, %s", what[lamp], how[e]);
            report(agrees(&st, 0), name, "mean difference %.2g +- %.2g over %g points, where rho/pi E is %.4g"
                   " on average", stat_mean(&st), stat_se(&st), st.n, stat_mean(&want));
            free_scene(&s);
        }
}

/* Shading normals: a floor whose triangles carry vertex normals tilted 20
 * degrees (towards +x) from their geometric normal, up, under the quad
 * lamp of test_polygon_lights.  The floor's BSDF takes its cosines about
 * the shading normal n, so the radiance of a floor point is rho/pi E with
 * E Lambert's irradiance about n (the lamp lies above both horizons, n's
 * and the plane's, from every point looked at: x, y in [-1.5, 1.5]), some
 * 5% less than about the plane's normal straight up.  Light sampling (nee,
 * mis) must weigh its samples by cos to n, as BSDF sampling does by drawing
 * about n.  40000 points, direct light only, within K standard errors.
 * Seen straight down, and from 80 degrees on the side the normals lean
 * away from, where wo lies below the shading normal's horizon but above
 * the plane: a Lambert surface looks the same from every side of its
 * plane's front, and which side a ray comes from is the plane's (ng), not
 * the shading normal's, whose flip would make the floor a back face. */
static void test_shading_normals(void)
{
    static const vec quad4[4] = { { -1, -0.8, 1.5 }, { -0.7, 0.9, 1.5 }, { 0.9, 1.1, 1.5 }, { 1.2, -1, 1.5 } };
    double Le = 2, rho = 0.7, tilt = 20 * PI / 180;
    vec n = v3(sin(tilt), 0, cos(tilt));
    int e, k, view;
    char name[200];
    for (view = 0; view < 2; view++)
    for (e = 0; e < 3; e++) {
        Scene s;
        Worker wk = worker();
        Stat st = { 0, 0, 0 }, want = { 0, 0, 0 };
        vec dir = view ? v3(sin(80 * PI / 180), 0, -cos(80 * PI / 180)) : v3(0, 0, -1);
        int floor_mat, a, b, c, d, nn;
        default_scene(&s);
        floor_mat = material(&s, v3(1, 1, 1), rho, 0, 0, 0, 1, 0);
        a = add_vertex(&s, v3(-6, -6, 0)), b = add_vertex(&s, v3(6, -6, 0));
        c = add_vertex(&s, v3(6, 6, 0)), d = add_vertex(&s, v3(-6, 6, 0));
        nn = add_normal(&s, n);
        add_triangle(&s, a, b, c, nn, nn, nn, floor_mat);
        add_triangle(&s, a, c, d, nn, nn, nn, floor_mat);
        s.cull = 1;                          /* the lamp lights from its front, below */
        quad(&s, quad4[0], quad4[1], quad4[2], quad4[3], material(&s, v3(1, 1, 1), 0, 0, 0, Le, 1, 0));
        ready(&s, e, 0, 2);
        for (k = 0; k < 40000; k++) {
            vec p, L;
            double E;
            start_sample(&wk, &s, k, 4, 0);
            p = v3(3 * random01(&wk, DIM_PIXEL_X) - 1.5, 3 * random01(&wk, DIM_PIXEL_Y) - 1.5, 0);
            L = radiance_along(&s, sub(p, scale(0.5 / -dir.z, dir)), dir, &wk);
            E = lambert_polygon(quad4, 4, p, n, Le);
            stat_add(&st, L.x - rho / PI * E);
            stat_add(&want, rho / PI * E);
        }
        sprintf(name, "a floor with shading normals tilted 20 degrees under a quad lamp: Lambert's formula"
                " about the shading normal, %s%s", est_name[e],
                view ? ", seen from 80 degrees, below the shading normal's horizon (the side is the plane's)" : "");
        report(agrees(&st, 0), name, "mean difference %.2g +- %.2g over %g points, where rho/pi E is %.4g"
               " on average", stat_mean(&st), stat_se(&st), st.n, stat_mean(&want));
        free_scene(&s);
    }
}

/* ---- one ball under a uniform sky ---- */

/* The mean radiance seen by a camera (eye, looking at `at`, fov) of one
 * unit ball at the origin under a uniform sky of radiance L, with material
 * kd ks kt (white, index 1.5), by estimator e; n samples. */
static Stat ball_in_sky(double L, double kd, double ks, double kt, vec eye, vec at, double fov,
                        int e, int n)
{
    Scene s;
    Stat st;
    default_scene(&s);
    s.set.w = s.set.h = 8;
    s.background = v3(L, L, L);
    add_sphere(&s, v3(0, 0, 0), 1, material(&s, v3(1, 1, 1), kd, ks, kt, 0, 1.5, 0));
    camera(&s, eye, at, v3(0, 0, 1), fov);
    ready(&s, e, 1, 0);
    st = image_samples(&s, n, 1);
    free_scene(&s);
    return st;
}

/* The three checks that use it: each names the ball, its material and the
 * answer, for every estimator. */
static void sky_checks(void)
{
    static const struct { const char *name; double L, kd, ks, kt; vec eye, at; double fov, want; } c[] = {
        /* A perfect mirror and a glass ball without absorption return the
         * room's radiance along every ray: what the glass lets in, it lets
         * out (the eta^2 of radiance entering and leaving cancel), and
         * what Fresnel reflects, the mirror keeps. */
        { "a mirror ball in a white room vanishes", 1, 0, 1, 0, { 0, -4, 0.3 }, { 0, 0, 0 }, 30, 1 },
        { "a glass ball in a white room vanishes", 1, 0, 0, 1, { 0, -4, 0.3 }, { 0, 0, 0 }, 30, 1 },
        /* Inside glass of index n the room is n^2 times brighter: radiance
         * crowds into a narrower cone entering a denser medium (L / n^2 is
         * what a ray keeps), and every path from a camera inside leaves the
         * ball once more than it enters: the check on sample_glass's eta^2
         * that the vanishing ball cannot make (in and out again, the two
         * factors cancel whatever they are). */
        { "inside a glass ball (n = 1.5) a white room is n^2 = 2.25 times brighter", 1, 0, 0, 1,
          { 0.2, 0.1, -0.3 }, { 1, 0.5, 0 }, 90, 2.25 },
        /* The same from 0.65 of the radius out, looking along the wall:
         * the rays meet it at 40.5 degrees, just short of the critical
         * angle (41.8), and at every meeting (a ball keeps the angle)
         * Fresnel reflects 0.30, so that about 1 path in 36 makes 4 rays
         * inside and meets the roulette there: those that leave then have
         * a throughput of n^2 = 2.25, more than 1, which the roulette's
         * chance must not follow (at most 0.95: a chance of 2.25 keeps
         * them all and counts each 1/2.25 times). */
        { "inside a glass ball, along its wall (Fresnel 0.3, some paths reach the roulette): n^2 = 2.25"
          " times brighter", 1, 0, 0, 1, { 0.65, 0, 0 }, { 0.65, 1, 0 }, 1, 2.25 },
        /* A convex Lambertian ball of albedo a under a sky of radiance L
         * sees only sky: it reflects a L, the sky sampled and weighed as a
         * light by each estimator. */
        { "a white ball of albedo 0.6 under a sky of 0.8 reflects 0.48", 0.8, 0.6, 0, 0,
          { 0, -3, 0.4 }, { 0, 0, 0 }, 20, 0.48 },
    };
    int k, e;
    char name[160];
    for (k = 0; k < (int)(sizeof c / sizeof c[0]); k++)
        for (e = 0; e < 3; e++) {
            Stat st = ball_in_sky(c[k].L, c[k].kd, c[k].ks, c[k].kt, c[k].eye, c[k].at, c[k].fov, e, 30000);
            sprintf(name, "%s, %s", c[k].name, est_name[e]);
            report(agrees(&st, c[k].want), name, "%.6f +- %.6f, want %g", stat_mean(&st), stat_se(&st),
                   c[k].want);
        }
}

/* ---- the BSDFs ---- */

static vec polar(double theta, double phi)
{
    return v3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
}

/* A material as the BSDF tests see it: kd x albedo, ks (glossy), a Phong
 * exponent or a GGX roughness (rough). */
typedef struct { const char *name; vec albedo; double kd, glossy, shine, rough; } Lobe;

static const Lobe lobes[] = {
    { "Lambert", { 0.8, 0.5, 0.25 }, 1, 0, 0, 0 },
    { "Phong 1", { 0, 0, 0 }, 1, 0.9, 1, 0 },
    { "Phong 10", { 0, 0, 0 }, 1, 0.9, 10, 0 },
    { "Phong 200", { 0, 0, 0 }, 1, 1, 200, 0 },
    { "Lambert + Phong 30", { 0.4, 0.4, 0.4 }, 1, 0.5, 30, 0 },
    { "Lambert + mirror", { 0.5, 0.7, 0.3 }, 1, 0.3, 0, 0 },      /* ks without an exponent: a mirror */
    { "GGX 0.1 conductor", { 0, 0, 0 }, 0, 1, 0, 0.1 },           /* ks 1: a white furnace */
    { "GGX 0.4 conductor", { 0, 0, 0 }, 0, 1, 0, 0.4 },
    { "GGX 1 conductor", { 0, 0, 0 }, 0, 1, 0, 1 },
    { "GGX 0.3 coat over Lambert", { 0.9, 0.9, 0.9 }, 0.5, 0.5, 0, 0.3 },
};
#define NLOBES ((int)(sizeof lobes / sizeof lobes[0]))

/* Lobe l on the plane z = 0 seen from wo. */
static Bsdf plane_bsdf(int l, vec wo)
{
    Scene s;
    Hit h;
    Bsdf b;
    default_scene(&s);
    s.rough = (real)lobes[l].rough;
    material(&s, lobes[l].albedo, lobes[l].kd, lobes[l].glossy, 0, 0, 1, lobes[l].shine);
    h.n = h.ng = v3(0, 0, 1);
    h.mat = 0;
    bsdf_at(&s, &h, wo, &b);
    free_scene(&s);
    return b;
}

/* Helmholtz reciprocity, f(a, b) = f(b, a), on random pairs above the
 * surface, to rounding. */
static void test_reciprocity(void)
{
    int l, k;
    char name[96];
    for (l = 0; l < NLOBES; l++) {
        Sequence q = sequence(l);
        double worst = 0;
        for (k = 0; k < 100000; k++) {
            vec a = polar(acos(next01(&q)), 2 * PI * next01(&q));
            vec b = polar(acos(next01(&q)), 2 * PI * next01(&q));
            Bsdf ba = plane_bsdf(l, a);
            Bsdf bb = plane_bsdf(l, b);
            vec f1 = bsdf_eval(&ba, a, b), f2 = bsdf_eval(&bb, b, a);
            double d = fabs(f1.x - f2.x) / fmax(1e-300, fabs(f1.x));
            if (f1.x != f2.x && !(d <= worst)) worst = d;
        }
        sprintf(name, "%s: reciprocity f(a,b) = f(b,a) on 1e5 pairs", lobes[l].name);
        report(worst <= 1e-12, name, "worst relative difference %.2g", worst);
    }
}

/* The test's own GGX, for the brute-force quadratures: Walter et al.'s
 * tangent forms (EGSR 2007, eqs. 33 and 34) rather than ray.c's cosine
 * forms, and the height-correlated G2 = 1 / (1/G1(o) + 1/G1(i) - 1). */
static double walter_d(double alpha, double cos_m)
{
    double c2 = cos_m * cos_m, tan2 = (1 - c2) / c2, a2 = alpha * alpha;
    return cos_m > 0 ? a2 / (PI * c2 * c2 * (a2 + tan2) * (a2 + tan2)) : 0;
}

static double walter_g1(double alpha, double cos_v)
{
    double tan2 = (1 - cos_v * cos_v) / (cos_v * cos_v);
    return 2 / (1 + sqrt(1 + alpha * alpha * tan2));
}

/* The albedo of a GGX lobe seen from wo, the largest channel of the
 * integral of f cos over the hemisphere, by the midpoint rule on a grid of
 * QT x QP cells of (theta_i, phi_i), with f written out here from the
 * lobe's weights: ggx F D G2 / (4 cos_o cos_i), plus for the coat the base's
 * albedo/pi (1 - F(cos_o)) (1 - F(cos_i)).  The grid's cells (0.15 by 0.3
 * degrees) are small beside the narrowest lobe tested (alpha 0.1, some 10
 * degrees across): its error is below 1e-4 (halving the grid moves the
 * answers by less). */
#define QT 600
#define QP 1200
static double ggx_albedo(const Bsdf *b, vec wo)
{
    double sum = 0, co = wo.z, base = fmax(b->albedo.x, fmax(b->albedo.y, b->albedo.z));
    int i, j;
    for (i = 0; i < QT; i++) {
        double ti = PI / 2 * (i + 0.5) / QT;
        for (j = 0; j < QP; j++) {
            vec wi = polar(ti, 2 * PI * (j + 0.5) / QP), h = unit(add(wo, wi));
            double ci = wi.z, F = b->coat ? fresnel(dot(wo, h), 1 / COAT_IOR) : 1;
            double G2 = 1 / (1 / walter_g1(b->alpha, co) + 1 / walter_g1(b->alpha, ci) - 1);
            double f = b->ggx * F * walter_d(b->alpha, h.z) * G2 / (4 * co * ci);
            if (b->coat) f += base / PI * (1 - fresnel(co, 1 / COAT_IOR)) * (1 - fresnel(ci, 1 / COAT_IOR));
            sum += f * ci * sin(ti);
        }
    }
    return sum * (PI / 2 / QT) * (2 * PI / QP);
}

/* Energy: the albedo, the integral of f cos over the hemisphere, estimated
 * from the BSDF's own samples (the mean of f cos / pdf), is at most 1 for
 * light from any direction; and it equals an estimate by uniform sampling
 * of the hemisphere, which does not trust the BSDF's sampling (plus the
 * mirror's weight, which no direction chosen at random can find).  A GGX
 * lobe's albedo is below its weight by what single scattering loses (light
 * that meets a second microfacet), which grows with the roughness and
 * towards grazing: its own sampling must agree with ggx_albedo's
 * brute-force quadrature (K standard errors and 1e-4 for the quadrature).
 * With ks 1 the conductor is a white furnace, and 1 - albedo is that loss. */
static void test_energy(void)
{
    static const double angles[4] = { 0, 30, 60, 85 };
    int l, a, k;
    char name[128];
    for (l = 0; l < NLOBES; l++)
        for (a = 0; a < 4; a++) {
            vec wo = polar(angles[a] * PI / 180, 0.3);
            Bsdf b = plane_bsdf(l, wo);
            Worker wk = worker();
            Stat own = { 0, 0, 0 }, uni = { 0, 0, 0 };
            Scene z = { 0 };
            Sequence q = sequence(16 * l + a);
            double head;
            z.set.w = 8;                        /* pixels (l, a) apart: their own samples */
            for (k = 0; k < 200000; k++) {
                vec wi, f_cos, wu, f;
                real pdf;
                double m;
                int lobe;
                start_sample(&wk, &z, l, a, k);
                lobe = sample_bsdf(&b, wo, &wk, &wi, &f_cos, &pdf);
                stat_add(&own, lobe < 0 ? 0 : fmax(f_cos.x, fmax(f_cos.y, f_cos.z)));
                wu = polar(acos(next01(&q)), 2 * PI * next01(&q));
                f = bsdf_eval(&b, wo, wu);
                m = fmax(f.x, fmax(f.y, f.z));
                stat_add(&uni, m * wu.z * 2 * PI);
            }
            /* head on, each lobe's albedo is its weight exactly: Lambert's
             * max(kd C), and the normalised Phong's ks (its (n+2)/2pi makes
             * the integral of cos^n cos over the hemisphere 1) */
            head = fmax(b.albedo.x, fmax(b.albedo.y, b.albedo.z)) + b.glossy + b.mirror;
            if (b.ggx > 0) {
                /* at alpha 1 D is 1/pi and Lambda(w) = (1/cos - 1)/2, so head on
                 * the albedo is the integral of cos_i / (1 + cos_i) / (2 pi)
                 * over the hemisphere: 1 - ln 2 exactly */
                double quad = ggx_albedo(&b, wo), exact = b.alpha == 1 && a == 0 ? 1 - log(2.0) : quad;
                sprintf(name, "%s from %g degrees: albedo <= 1, its own sampling = uniform sampling"
                        " = quadrature%s", lobes[l].name, angles[a], exact != quad ? " = 1 - ln 2" : "");
                report(stat_mean(&own) <= 1 + K * stat_se(&own)
                           && fabs(stat_mean(&own) - quad) <= K * stat_se(&own) + 1e-4
                           && fabs(stat_mean(&uni) - quad) <= K * stat_se(&uni) + 1e-4
                           && fabs(exact - quad) <= 1e-4,
                       name, "albedo %.4f +- %.4f, uniform %.4f +- %.4f, quadrature %.5f: %s %.4f",
                       stat_mean(&own), stat_se(&own), stat_mean(&uni), stat_se(&uni), quad,
                       b.coat ? "lost" : "single scattering loses", 1 - quad);
                continue;
            }
            sprintf(name, "%s from %g degrees: albedo <= 1%s, and its own sampling = uniform sampling",
                    lobes[l].name, angles[a], a == 0 ? " (head on: its weight)" : "");
            report(stat_mean(&own) <= 1 + K * stat_se(&own) && (a > 0 || agrees(&own, head))
                       && fabs(stat_mean(&own) - stat_mean(&uni) - b.mirror)
                              <= K * sqrt(stat_se(&own) * stat_se(&own) + stat_se(&uni) * stat_se(&uni)),
                   name, "albedo %.4f +- %.4f, uniform %.4f", stat_mean(&own), stat_se(&own),
                   stat_mean(&uni));
        }
}

/* Heitz's two normalisations of a microfacet surface ("Understanding the
 * Masking-Shadowing Function", JCGT 2014), by the midpoint
 * rule over the microfacet normals h: the microfacets' projected area is
 * the surface's, integral of D(h) cos(theta_h) = 1; and seen from wo, the
 * projected area of the microfacets left unmasked is the surface's seen
 * from there, integral of G1(wo) max(0, wo.h) D(h) = cos(theta_o) (the
 * "weak white furnace").  The first holds D's normalisation, the second
 * G1 against D: each is exact, so to the quadrature's 2e-4. */
static void test_ggx_normalised(void)
{
    static const double alpha[3] = { 0.1, 0.4, 1 }, angle[3] = { 0, 45, 80 };
    enum { HT = 2000, HP = 400 };
    int k, a, i, j;
    char name[160];
    for (k = 0; k < 3; k++) {
        double area = 0, worst = 0;
        for (i = 0; i < HT; i++) {
            double th = PI / 2 * (i + 0.5) / HT;
            area += ggx_d((real)alpha[k], (real)cos(th)) * cos(th) * sin(th) * (PI / 2 / HT) * 2 * PI;
        }
        for (a = 0; a < 3; a++) {
            vec wo = polar(angle[a] * PI / 180, 0);
            double seen = 0;
            for (i = 0; i < HT; i++)
                for (j = 0; j < HP; j++) {
                    double th = PI / 2 * (i + 0.5) / HT;
                    vec h = polar(th, 2 * PI * (j + 0.5) / HP);
                    seen += smith_g1((real)alpha[k], (real)wo.z) * fmax(0, dot(wo, h))
                            * ggx_d((real)alpha[k], (real)h.z) * sin(th);
                }
            seen *= (PI / 2 / HT) * (2 * PI / HP);
            worst = fmax(worst, fabs(seen - wo.z));
        }
        sprintf(name, "GGX alpha %g: projected area of D is 1, of the visible microfacets cos(theta_o)"
                " (0, 45, 80 degrees)", alpha[k]);
        report(fabs(area - 1) < 2e-4 && worst < 2e-4, name, "area %.6f, visible worst difference %.2g",
               area, worst);
    }
}

/* Q(a, x), the regularised upper incomplete gamma function: the chance that
 * a chi-square variable of 2a degrees of freedom exceeds 2x.  Its series
 * below a + 1, its continued fraction above (evaluated by Lentz's method). */
static double gamma_q(double a, double x)
{
    double lg = lgamma(a), sum, term, b, c, d, h;
    int n;
    if (x <= 0) return 1;
    if (x < a + 1) {
        sum = term = 1 / a;
        for (n = 1; n < 100000 && fabs(term) > fabs(sum) * 1e-15; n++) {
            term *= x / (a + n);
            sum += term;
        }
        return 1 - sum * exp(-x + a * log(x) - lg);
    }
    b = x + 1 - a;
    c = 1e300;
    d = 1 / b;
    h = d;
    for (n = 1; n < 100000; n++) {
        double an = -n * (n - a), del;
        b += 2;
        d = an * d + b;
        if (fabs(d) < 1e-300) d = 1e-300;
        c = b + an / c;
        if (fabs(c) < 1e-300) c = 1e-300;
        d = 1 / d;
        del = d * c;
        h *= del;
        if (fabs(del - 1) < 1e-15) break;
    }
    return exp(-x + a * log(x) - lg) * h;
}

/* The integral of the BSDF's pdf over a cell of theta x phi, by the
 * midpoint rule on an 8 x 8 grid of the cell (the solid angle is
 * sin(theta) dtheta dphi).  Midpoints, not the cell's edges: the pdf drops
 * to 0 at the horizon, and a rule that samples the edge itself would give
 * the cell below the horizon a share of the one above. */
static double cell_integral(const Bsdf *b, vec wo, double t0, double t1, double p0, double p1)
{
    double sum = 0;
    int i, j;
    for (i = 0; i < 8; i++)
        for (j = 0; j < 8; j++) {
            double t = t0 + (t1 - t0) * (i + 0.5) / 8, p = p0 + (p1 - p0) * (j + 0.5) / 8;
            sum += bsdf_pdf(b, wo, polar(t, p)) * sin(t);
        }
    return sum * (t1 - t0) / 8 * (p1 - p0) / 8;
}

/* Pearson's statistic (Pearson 1900) of observed against expected counts
 * in n cells, the cells expecting fewer than 5 pooled into one (which
 * counts as expecting at least 5); in *chi2 and *dof, and returned its
 * p-value, the chance that a correct sampler gives a statistic as large. */
static double pearson(const double *observed, const double *expected, int n, double *chi2, int *dof)
{
    double pool_o = 0, pool_e = 0;
    int k;
    *chi2 = 0;
    *dof = 0;
    for (k = 0; k < n; k++) {
        if (expected[k] < 5) { pool_o += observed[k]; pool_e += expected[k]; continue; }
        *chi2 += (observed[k] - expected[k]) * (observed[k] - expected[k]) / expected[k];
        ++*dof;
    }
    if (pool_e > 0) {
        *chi2 += (pool_o - pool_e) * (pool_o - pool_e) / fmax(pool_e, 5);
        ++*dof;
    }
    return gamma_q((*dof - 1) / 2.0, *chi2 / 2);
}

#define NT 80
#define NP 160
#define CHI_SAMPLES 1000000

/* Pearson's chi-square test that sample_bsdf draws directions with the
 * density bsdf_pdf says: 10^6 samples in 80 x 160 cells of theta x phi, the
 * counts expected from the pdf integrated over each cell, cells expecting
 * fewer than 5 pooled, and one more cell for the samples that end the path
 * (a Phong direction below the surface).  The significance 0.01 is shared
 * among the tests by Sidak's correction.  (As Mitsuba's and pbrt's tests do;
 * the method: Pearson 1900.) */
static void test_chi2(void)
{
    static const double angles[2] = { 30, 75 };
    int ntests = 0, l, a;
    double alpha;
    char name[128];
    static double observed[NT * NP + 1], expected[NT * NP + 1];
    for (l = 0; l < NLOBES; l++) ntests += 2 * (lobes[l].shine > 0 || lobes[l].rough > 0);
    alpha = 1 - pow(1 - 0.01, 1.0 / ntests);
    for (l = 0; l < NLOBES; l++)
        for (a = 0; a < 2 && (lobes[l].shine > 0 || lobes[l].rough > 0); a++) {   /* not a mirror: no pdf to count */
            vec wo = polar(angles[a] * PI / 180, 1.1);
            Bsdf b = plane_bsdf(l, wo);
            Worker wk = worker();
            Scene z = { 0 };
            double chi2, inside = 0, p;
            int i, j, k, dof;
            memset(observed, 0, sizeof observed);
            z.set.w = 8;
            z.set.seed = 2;
            for (k = 0; k < CHI_SAMPLES; k++) {
                vec wi, f_cos;
                real pdf;
                start_sample(&wk, &z, l, a, k);
                if (sample_bsdf(&b, wo, &wk, &wi, &f_cos, &pdf) < 0) { observed[NT * NP]++; continue; }
                i = (int)(acos(fmax(-1, fmin(1, wi.z))) / PI * NT);
                j = (int)((atan2(wi.y, wi.x) + PI) / (2 * PI) * NP);
                observed[(i < NT ? i : NT - 1) * NP + (j < NP ? j : NP - 1)]++;
            }
            for (i = 0; i < NT; i++)
                for (j = 0; j < NP; j++) {
                    double e = CHI_SAMPLES * cell_integral(&b, wo, PI * i / NT, PI * (i + 1) / NT,
                                                           2 * PI * j / NP - PI, 2 * PI * (j + 1) / NP - PI);
                    expected[i * NP + j] = e;
                    inside += e;
                }
            expected[NT * NP] = CHI_SAMPLES - inside;
            p = pearson(observed, expected, NT * NP + 1, &chi2, &dof);
            sprintf(name, "%s from %g degrees: chi-square, sampling matches the pdf", lobes[l].name,
                    angles[a]);
            report(p > alpha, name, "chi2 %.0f, %d cells, p = %.3g", chi2, dof, p);
        }
}

/* ---- the warps ---- */

/* Each warp of ray.c's samples section against its own pdf, as test_chi2
 * holds the BSDFs to theirs.  The directions (cosine_hemisphere,
 * phong_lobe about z, sphere_cap, and ggx_visible_normal's microfacet
 * normals seen from a fixed wo) are counted in cells of theta x phi up
 * to the warp's largest theta, uniform_disc's points in cells of r x phi
 * (a grid its concentric squares do not follow), and a triangle's
 * barycentrics (b1, b2) in the 2 N^2 small triangles of its N-fold
 * subdivision; one more cell takes any point outside the domain. */
enum { COSINE, PHONG, CAP, TRIANGLE_WARP, DISC, VNDF };
/* param: shine, degrees, or GGX's alpha; from: the angle of wo to z, in
 * degrees, for the visible normals' warp */
typedef struct { const char *name; int kind; double param, from; } Warp;

static const Warp warps[] = {
    { "cosine_hemisphere", COSINE, 0, 0 },
    { "phong_lobe, shine 1", PHONG, 1, 0 },
    { "phong_lobe, shine 10", PHONG, 10, 0 },
    { "phong_lobe, shine 200", PHONG, 200, 0 },
    { "sphere_cap, 20 degrees", CAP, 20, 0 },
    { "sphere_cap, 100 degrees", CAP, 100, 0 },
    { "sphere_cap, the whole sphere", CAP, 180, 0 },
    { "uniform_triangle", TRIANGLE_WARP, 0, 0 },
    { "uniform_disc", DISC, 0, 0 },
    { "ggx_visible_normal, alpha 0.2 from 60 degrees", VNDF, 0.2, 60 },
    { "ggx_visible_normal, alpha 0.6 from 85 degrees", VNDF, 0.6, 85 },
    { "ggx_visible_normal, alpha 1 head on", VNDF, 1, 0 },
};
#define NWARPS ((int)(sizeof warps / sizeof warps[0]))
#define WT 48               /* cells in theta or r */
#define WP 96               /* cells in phi */
#define WN 24               /* the triangle's subdivision */
#define WARP_SAMPLES 200000

static double theta_max(const Warp *w)
{
    return w->kind == CAP ? w->param * PI / 180 : PI / 2;
}

/* The cap of the cone: 1 - cos(theta_max). */
static double cap_of(const Warp *w) { return 1 - cos(theta_max(w)); }

static vec warp(const Warp *w, real u1, real u2)
{
    switch (w->kind) {
    case VNDF: return ggx_visible_normal(polar(w->from * PI / 180, 0.4), (real)w->param, u1, u2);
    case COSINE: return cosine_hemisphere(u1, u2);
    case PHONG: return phong_lobe((real)w->param, u1, u2);
    case CAP: return sphere_cap((real)cap_of(w), u1, u2);
    case DISC: return uniform_disc(u1, u2);
    }
    return uniform_triangle(u1, u2);
}

/* The pdf at a point of the domain: in solid angle for a direction d, in
 * area for a point of the disc, and in area of the (b1, b2) plane, where
 * the triangle has area 1/2, for barycentrics. */
static double warp_pdf(const Warp *w, vec d)
{
    vec wo = polar(w->from * PI / 180, 0.4);
    switch (w->kind) {
    case VNDF: return ggx_visible_normal_pdf((real)w->param, wo.z, d.z, dot(wo, d));
    case COSINE: return cosine_hemisphere_pdf(d.z);
    case PHONG: return phong_lobe_pdf((real)w->param, d.z);
    case CAP: return sphere_cap_pdf((real)cap_of(w));
    case DISC: return uniform_disc_pdf();
    }
    return uniform_triangle_pdf((real)0.5);
}

static int ncells(const Warp *w) { return w->kind == TRIANGLE_WARP ? 2 * WN * WN : WT * WP; }

/* The cell of a point, or ncells for one outside the domain. */
static int warp_cell(const Warp *w, vec p)
{
    int i, j;
    if (w->kind == TRIANGLE_WARP) {
        double x = p.y * WN, y = p.z * WN;
        i = (int)floor(x), j = (int)floor(y);
        if (!(p.y >= 0 && p.z >= 0 && p.y + p.z <= 1) || i >= WN || j >= WN) return ncells(w);
        return 2 * (i * WN + j) + (x - i + (y - j) > 1);
    }
    i = w->kind == DISC ? (int)(sqrt(p.x * p.x + p.y * p.y) * WT)
                        : (int)(acos(fmax(-1, fmin(1, p.z))) / theta_max(w) * WT);
    j = (int)((atan2(p.y, p.x) + PI) / (2 * PI) * WP);
    if (i >= WT) return ncells(w);
    return i * WP + (j < WP ? j : WP - 1);
}

/* The pdf integrated over cell k: a direction's by the midpoint rule on an
 * 8 x 8 grid of the cell (solid angle sin(theta) dtheta dphi, as
 * cell_integral), the disc's alike (area r dr dphi); a small triangle's by
 * its centroid (the midpoint rule of a triangle) times its area
 * 1 / (2 N^2). */
static double warp_mass(const Warp *w, int k)
{
    double sum = 0, t0, t1, p0, p1;
    int a, b;
    if (w->kind == TRIANGLE_WARP) {
        int i = k / 2 / WN, j = k / 2 % WN, upper = k % 2;
        double x = (i + (upper ? 2 : 1) / 3.0) / WN, y = (j + (upper ? 2 : 1) / 3.0) / WN;
        return x + y <= 1 ? warp_pdf(w, v3(1 - x - y, x, y)) / (2.0 * WN * WN) : 0;
    }
    if (w->kind == DISC) {
        t0 = (double)(k / WP) / WT, t1 = (double)(k / WP + 1) / WT;  /* r */
        for (a = 0; a < 8; a++) {
            double r = t0 + (t1 - t0) * (a + 0.5) / 8;
            sum += uniform_disc_pdf() * r;          /* constant in phi */
        }
        return sum * (t1 - t0) / 8 * (2 * PI / WP);
    }
    t0 = theta_max(w) * (k / WP) / WT, t1 = theta_max(w) * (k / WP + 1) / WT;
    p0 = 2 * PI * (k % WP) / WP - PI, p1 = 2 * PI * (k % WP + 1) / WP - PI;
    for (a = 0; a < 8; a++)
        for (b = 0; b < 8; b++) {
            double t = t0 + (t1 - t0) * (a + 0.5) / 8, p = p0 + (p1 - p0) * (b + 0.5) / 8;
            sum += warp_pdf(w, polar(t, p)) * sin(t);
        }
    return sum * (t1 - t0) / 8 * (p1 - p0) / 8;
}

/* For each warp: Pearson's chi-square of 200000 points against the counts
 * its pdf expects in each cell (the significance 0.01 shared among the
 * warps by Sidak's correction, as test_chi2), and the pdf's integral over
 * the domain, the sum of the cells' masses, is 1 to within 1e-3 (the
 * quadrature's error is far smaller: a pdf 1.005 times too large, Phong
 * 200's with shine + 2 for shine + 1, is caught here and not by the
 * chi-square). */
static void test_warps(void)
{
    static double observed[2 * WN * WN > WT * WP ? 2 * WN * WN + 1 : WT * WP + 1];
    static double expected[sizeof observed / sizeof observed[0]];
    double alpha = 1 - pow(1 - 0.01, 1.0 / NWARPS);
    char name[128];
    int l;
    for (l = 0; l < NWARPS; l++) {
        const Warp *w = &warps[l];
        Sequence q = sequence(100 + l);
        double chi2, total = 0, p;
        int k, n = ncells(w), dof;
        memset(observed, 0, sizeof observed);
        for (k = 0; k < WARP_SAMPLES; k++) {
            real u1 = (real)next01(&q), u2 = (real)next01(&q);
            observed[warp_cell(w, warp(w, u1, u2))]++;
        }
        for (k = 0; k < n; k++) total += (expected[k] = warp_mass(w, k));
        for (k = 0; k < n; k++) expected[k] *= WARP_SAMPLES;
        expected[n] = fmax(0, WARP_SAMPLES * (1 - total));
        p = pearson(observed, expected, n + 1, &chi2, &dof);
        sprintf(name, "warp %s: chi-square, its points match its pdf", w->name);
        report(p > alpha, name, "chi2 %.0f, %d cells, p = %.3g", chi2, dof, p);
        sprintf(name, "warp %s: its pdf integrates to 1", w->name);
        report(fabs(total - 1) < 1e-3, name, "%.6f by the midpoint rule", total);
    }
}

/* ---- the dimensions ---- */

/* Each named dimension is a number of its own: for 1000 samples, the
 * numbers of the pixel's, the lens's and the time's dimensions and of
 * every named slot of the first four bounces' blocks are all different.
 * Two names given one slot, a slot past its block (into the next bounce's)
 * or a block over the camera's dimensions would make two of them equal. */
static void test_dimensions_distinct(void)
{
    static const int camera[] = { DIM_PIXEL_X, DIM_PIXEL_Y, DIM_LENS_U, DIM_LENS_V, DIM_TIME };
    static const int slot[] = { LIGHT_CHOICE, LIGHT_U, LIGHT_V, LOBE, DIRECTION_U, DIRECTION_V, ROULETTE, SPARE };
    enum { NC = sizeof camera / sizeof camera[0], NS = sizeof slot / sizeof slot[0], BOUNCES = 4 };
    Worker wk = worker();
    Scene z = { 0 };
    int k, d, e, same = 0;
    z.set.w = 1000;
    for (k = 0; k < 1000; k++) {
        real u[NC + BOUNCES * NS];
        start_sample(&wk, &z, k, 3, 5);
        for (d = 0; d < NC; d++) u[d] = random01(&wk, camera[d]);
        for (wk.bounce = 0; wk.bounce < BOUNCES; wk.bounce++)
            for (d = 0; d < NS; d++) u[NC + wk.bounce * NS + d] = bounce_random(&wk, slot[d]);
        for (d = 0; d < NC + BOUNCES * NS; d++)
            for (e = d + 1; e < NC + BOUNCES * NS; e++) same += u[d] == u[e];
    }
    report(same == 0, "dimensions: the pixel's, the lens's, the time's and 4 bounces' named slots are distinct numbers",
           "%d equal pairs in 1000 samples", same);
}

/* The numbers are drawn by dimension, not in turn: nee and mis draw a
 * light at every bounce and bsdf does not, yet the BSDF's and roulette's
 * numbers are the same, so each path takes the same turns whatever the
 * estimator (the light it gathers differs, its way does not).  The same
 * number of rays bounce, and as many nearest-hit queries are made, in a
 * Cornell box of 32 x 32 pixels, 4 paths each. */
static void test_dimensions_fixed(void)
{
    unsigned long long bounced[3], nearest[3];
    int e;
    for (e = 0; e < 3; e++) {
        Scene s;
        Worker wk = worker();
        int i, j;
        if (!cornell(&s, 32, e, "dimensions: the paths are the same for every estimator")) return;
        for (j = 0; j < s.set.h; j++)
            for (i = 0; i < s.set.w; i++) pixel_radiance(&s, i, j, 4, &wk);
        bounced[e] = wk.count.bounced;
        nearest[e] = wk.count.nearest;
        free_scene(&s);
    }
    report(bounced[0] == bounced[1] && bounced[1] == bounced[2] && nearest[0] == nearest[1]
               && nearest[1] == nearest[2],
           "dimensions: bsdf, nee and mis trace the same paths (a light drawn or not moves no other number)",
           "bounced %llu %llu %llu, nearest-hit queries %llu %llu %llu", bounced[0], bounced[1], bounced[2],
           nearest[0], nearest[1], nearest[2]);
}

/* Fresnel's equations at known points: ((n-1)/(n+1))^2 head on, 1 past the
 * critical angle, the same from either side of the surface for the same
 * pair of angles, and at 10 to 80 degrees the textbook's other form:
 * Rs = sin^2(i - t) / sin^2(i + t), Rp = tan^2(i - t) / tan^2(i + t). */
static void test_fresnel(void)
{
    double n = 1.5, head = fresnel(1, 1 / n), tir = fresnel(cos(asin(1 / n) + 0.01), n), worst = 0;
    int deg;
    for (deg = 10; deg <= 80; deg += 10) {
        double i = deg * PI / 180, t = asin(sin(i) / n);
        double rs = sin(i - t) / sin(i + t), rp = tan(i - t) / tan(i + t), want = (rs * rs + rp * rp) / 2;
        double out = fresnel(cos(i), 1 / n), in = fresnel(cos(t), n);
        worst = fmax(worst, fmax(fabs(out - want), fabs(in - want)));
    }
    report(fabs(head - 0.04) < 1e-15 && tir == 1 && worst < 1e-14,
           "Fresnel: 0.04 head on, 1 past the critical angle, the sine-and-tangent form at 10..80 degrees from both sides",
           "%.17g, %g, worst difference %.2g", head, tir, worst);
}

/* ---- the three estimators agree ---- */

/* s[e] ready for estimator e, at its own size: each estimator's mean
 * luminance in each of the 4 x 4 blocks of the image, from spp paths a
 * pixel; returned, the largest difference of a pair in a block, in
 * standard errors of that difference, and that block in *worst_block. */
static double estimators_differ(Scene s[3], int spp, int *worst_block)
{
    Stat st[3][16];
    int e, k, w = s[0].set.w, h = s[0].set.h;
    double worst = 0;
    for (e = 0; e < 3; e++) {
        Worker wk = worker();
        memset(st[e], 0, sizeof st[e]);
        for (k = 0; k < w * h * spp; k++) {
            int pixel = k % (w * h), i = pixel % w, j = pixel / w;
            vec L = sample_radiance(&s[e], i, j, k / (w * h), &wk);
            stat_add(&st[e][(j * 4 / h) * 4 + i * 4 / w], luminance(L));
        }
    }
    for (k = 0; k < 16; k++)
        for (e = 0; e < 3; e++) {
            const Stat *a = &st[e][k], *b = &st[(e + 1) % 3][k];
            double se = sqrt(stat_se(a) * stat_se(a) + stat_se(b) * stat_se(b));
            double z = fabs(stat_mean(a) - stat_mean(b)) / se;
            if (!(z <= worst)) worst = z, *worst_block = k;
        }
    return worst;
}

/* On the Cornell box, each estimator's mean radiance in each of 16 blocks
 * of the image: every pair must agree within K standard errors of their
 * difference. */
static void test_estimators_agree(void)
{
    Scene s[3];
    int e, worst_block = -1;
    double worst;
    for (e = 0; e < 3; e++)
        if (!cornell(&s[e], 16, e, "the three estimators agree on the Cornell box")) return;
    worst = estimators_differ(s, 384, &worst_block);
    report(worst <= K, "the three estimators agree on the Cornell box, 16 blocks, 98304 paths each",
           "worst difference %.2f standard errors, in block %d", worst, worst_block);
    for (e = 0; e < 3; e++) free_scene(&s[e]);
}

/* Veach's scene (scenes/veach.sph) at depth 2, direct light only: the
 * three estimators must agree on the mean, but their noise differs by
 * orders of magnitude, which is the scene's point.  Where a technique is
 * poor its estimate is a rare large sample (light sampling on the smooth
 * plates finds the narrow lobe once in hundreds of tries, BSDF sampling on
 * the rough plates the small lights), and there a few thousand samples
 * give neither a fair mean nor a fair standard error.  So each technique
 * is held to MIS where Veach's figure shows it good: BSDF sampling on the
 * two smooth plates (alpha 0.005 and 0.02), light sampling on the two rough
 * ones (0.05 and 0.1), in each quarter of each plate (the lights' columns,
 * left to right), a 48 x 32 image at 256 paths a pixel; and the floor,
 * which light sampling finds well and both others poorly, is left out.
 * A pixel belongs to the plate its centre's ray meets.  Each pair within
 * K standard errors of its difference. */
static const double plate_rough[4] = { 0.005, 0.02, 0.05, 0.1 };    /* as scenes/veach.sph's */

/* The plate (0 to 3, top to bottom) that pixel (i, j)'s centre shows, or -1. */
static int veach_plate(const Scene *s, int i, int j)
{
    Worker wk = worker();
    Hit h;
    int p;
    if (!nearest_hit(s, camera_ray(&s->cam, s->set.w, s->set.h, i + 0.5, j + 0.5), &h, &wk)) return -1;
    for (p = 0; p < 4; p++)
        if (fabs(s->mat[h.mat].rough - plate_rough[p]) < 1e-6) return p;
    return -1;
}

/* Each pixel's region: 4 p + q for quarter q (left to right) of plate p,
 * or -1 off the plates. */
static void veach_regions(const Scene *s, int *region)
{
    int k, w = s->set.w, h = s->set.h;
    for (k = 0; k < w * h; k++) {
        int p = veach_plate(s, k % w, k / w);
        region[k] = p < 0 ? -1 : p * 4 + (k % w) * 4 / w;
    }
}

static void test_veach(void)
{
    enum { W = 48, H = 32, SPP = 256 };
    Scene s[3];
    Stat st[3][16];
    int e, k, region[W * H], worst_region = -1;
    double worst = 0;
    char name[192];
    sprintf(name, "Veach's scene at depth 2: bsdf = mis on the smooth plates, nee = mis on the rough ones,"
            " in 16 plate quarters, %d paths a pixel", SPP);
    for (e = 0; e < 3; e++) {
        Worker wk = worker();
        if (!scene_file(&s[e], "scenes/veach.sph", W, H, e, 2, name)) return;
        memset(st[e], 0, sizeof st[e]);
        if (e == 0) veach_regions(&s[0], region);
        for (k = 0; k < W * H * SPP; k++) {
            int pixel = k % (W * H);
            vec L = sample_radiance(&s[e], pixel % W, pixel / W, k / (W * H), &wk);
            if (region[pixel] >= 0) stat_add(&st[e][region[pixel]], luminance(L));
        }
    }
    for (k = 0; k < 16; k++) {
        const Stat *a = &st[k < 8 ? BSDF_ONLY : NEE][k], *b = &st[MIS][k];
        double z = fabs(stat_mean(a) - stat_mean(b)) / hypot(stat_se(a), stat_se(b));
        if (!(z <= worst)) worst = z, worst_region = k;
    }
    k = worst_region;
    report(worst <= K, name, "worst %.2f standard errors, plate %d quarter %d: %s %.4f +- %.4f, mis %.4f +- %.4f",
           worst, k / 4, k % 4, k < 8 ? "bsdf" : "nee", stat_mean(&st[k < 8 ? 0 : 1][k]),
           stat_se(&st[k < 8 ? 0 : 1][k]), stat_mean(&st[MIS][k]), stat_se(&st[MIS][k]));
    for (e = 0; e < 3; e++) free_scene(&s[e]);
}

/* MIS's noise against its two techniques', on Veach's scene at depth 2
 * (direct light only).  Veach's thesis (1997), Theorem 9.2: with n_i
 * samples of technique i, the balance heuristic's variance is at most any
 * other weighting's plus (1/min n_i - 1/sum n_i) mu^2, mu the integral.
 * A path here takes one BSDF sample and one light sample (n = 1, 1), and
 * BSDF sampling alone and light sampling alone are such weightings (1, 0)
 * and (0, 1), so
 *
 *     V_mis <= c min(V_bsdf, V_nee) + mu^2 / 2,   c = 1.
 *
 * No factor c alone bounds it: where one technique is nearly exact (BSDF
 * sampling on the smoothest plate under the largest light: V_bsdf 0.0007),
 * MIS still spends a light sample, and its variance is some 24 times
 * V_bsdf (0.016), which the mu^2 / 2 term (0.76) allows.  ray.c weighs by
 * the power heuristic, not the balance heuristic the theorem is proved
 * for; Veach recommends it for doing better still where one technique is
 * good, and measured here it keeps the balance heuristic's bound with room
 * (the worst region 0.92 of it, where MIS is light sampling).  One
 * ray a region, through the middle pixel of each plate quarter (the pixel's
 * centre, so that the variance is the direct-light integral's alone), N
 * samples of each estimator; the variance of a sample variance, (m4 -
 * s^4) / N (Cramer, Mathematical Methods of Statistics, 1946, 27.7), gives
 * the tolerance, K standard errors of the difference.  Weights swapped
 * (each sample weighed by the other technique's share) stay unbiased, but
 * give light samples their weight where they are rare: 10 to 1000 times
 * the noise in most regions. */
static void sample_moments(const double *x, int n, double *mean, double *var, double *var_se)
{
    double m = 0, v = 0, m4 = 0;
    int k;
    for (k = 0; k < n; k++) m += x[k];
    m /= n;
    for (k = 0; k < n; k++) {
        double d = x[k] - m;
        v += d * d, m4 += d * d * d * d;
    }
    v /= n - 1, m4 /= n;
    *mean = m, *var = v, *var_se = sqrt(fmax(0, m4 - v * v) / n);
}

static void test_mis_variance(void)
{
    enum { W = 48, H = 32, N = 16000 };
    static double x[N];
    Scene s[3];
    double mean[3][16], var[3][16], se[3][16], worst = -HUGE_VAL, most = 0, share = 0;
    int e, k, q, region[W * H], pixel[16], at = -1;
    char name[200];
    sprintf(name, "Veach's scene at depth 2: V_mis <= min(V_bsdf, V_nee) + mu^2/2 (Veach's Theorem 9.2),"
            " one ray in each of 16 plate quarters, %d samples each", N);
    for (e = 0; e < 3; e++)
        if (!scene_file(&s[e], "scenes/veach.sph", W, H, e, 2, name)) return;
    veach_regions(&s[0], region);
    for (q = 0; q < 16; q++) {                  /* the middle of the region's pixels, in raster order */
        int n = 0, m = 0;
        for (k = 0; k < W * H; k++) n += region[k] == q;
        for (k = 0, pixel[q] = -1; k < W * H && pixel[q] < 0; k++)
            if (region[k] == q && m++ == n / 2) pixel[q] = k;
    }
    for (e = 0; e < 3; e++)
        for (q = 0; q < 16 && pixel[q] >= 0; q++) {
            Worker wk = worker();
            int i = pixel[q] % W, j = pixel[q] / W;
            Ray r = camera_ray(&s[e].cam, W, H, i + 0.5, j + 0.5);
            for (k = 0; k < N; k++) {
                start_sample(&wk, &s[e], i, j, k);
                x[k] = luminance(radiance_along(&s[e], r.o, r.d, &wk));
            }
            sample_moments(x, N, &mean[e][q], &var[e][q], &se[e][q]);
        }
    for (q = 0; q < 16; q++) {
        int lo = var[BSDF_ONLY][q] < var[NEE][q] ? BSDF_ONLY : NEE;
        double mu = mean[MIS][q], bound = var[lo][q] + mu * mu / 2;
        double z = (var[MIS][q] - bound) / sqrt(se[MIS][q] * se[MIS][q] + se[lo][q] * se[lo][q]
                                                + mu * mu * var[MIS][q] / N);   /* and mu^2/2's own */
        if (pixel[q] < 0) z = HUGE_VAL;         /* a plate quarter without a pixel: the scene moved */
        if (!(z <= worst)) worst = z, at = q;
        most = fmax(most, var[MIS][q] / var[lo][q]);
        share = fmax(share, var[MIS][q] / bound);
    }
    q = at;
    report(worst <= K, name, "worst %.2f standard errors, plate %d quarter %d: mis %.4g +- %.2g,"
           " bsdf %.4g +- %.2g, nee %.4g +- %.2g, mu^2/2 %.4g; V_mis at most %.3f of its bound,"
           " and up to %.3g times min(V_bsdf, V_nee)",
           worst, q / 4, q % 4, var[MIS][q], se[MIS][q], var[BSDF_ONLY][q], se[BSDF_ONLY][q],
           var[NEE][q], se[NEE][q], mean[MIS][q] * mean[MIS][q] / 2, share, most);
    for (e = 0; e < 3; e++) free_scene(&s[e]);
}

/* ---- MIS's weights: a plate under a sky ---- */

/* A plate (the quad z = 0, 200 wide) of a white material kd ks (a Phong
 * exponent shine, or 0: ks is a mirror) under a uniform sky of radiance L,
 * ready for estimator e.  A point light below it lights only its underside
 * (from above, cos theta_i < 0), but it halves the sky's chance to be the
 * light chosen, so that the sky's pdf is c cos(theta_i) / pi with c = 1/2
 * and not the Lambertian lobe's cosine pdf.  The plate's front faces down:
 * a ray from above meets its back, where bsdf_at turns the normals up, and
 * the normal a path leaves with (which the sky's pdf is measured about) must
 * be the turned one. */
static void plate_in_sky(Scene *s, double L, double kd, double ks, double shine, int e)
{
    default_scene(s);
    s->background = v3(L, L, L);
    quad(s, v3(-100, -100, 0), v3(-100, 100, 0), v3(100, 100, 0), v3(100, -100, 0),
         material(s, v3(1, 1, 1), kd, ks, 0, 0, 1, shine));
    add_light(s, v3(0, 0, -1), v3(1, 1, 1), -1);
    ready(s, e, 1, 0);
}

/* A modified Phong lobe of ks 1 (kd 0), f = (n+2)/(2 pi) cos^n(alpha), alpha
 * the angle to the mirror direction of wo at theta_o, under a uniform sky of
 * radiance L, by the midpoint rule on QT x QP cells of the hemisphere: in
 * *albedo the integral of f cos theta_i, and for MIS, the sum of one BSDF
 * sample (the lobe's pdf (n+1)/(2 pi) cos^n(alpha)) and one light sample
 * (the sky's c cos(theta_i) / pi), each weighed by the heuristic
 * p^beta / (p_bsdf^beta + p_light^beta) of its own pdf p (beta 2: the power
 * heuristic, 1: the balance heuristic), its mean and variance.  The two
 * samples are independent, so the variance is the sum of each one's,
 * E[(w f cos L / p)^2] - E[w f cos L / p]^2 over its own pdf p (Veach's
 * multi-sample estimator, thesis 1997, chapter 9, one sample of each). */
static void phong_sky_mis(double shine, double theta_o, double c, double beta, double L,
                          double *albedo, double *mean, double *var)
{
    vec r = polar(theta_o, PI);
    double a = 0, ml = 0, mb = 0, sl = 0, sb = 0, cell = (PI / 2 / QT) * (2 * PI / QP);
    int i, j;
    for (i = 0; i < QT; i++) {
        double ti = PI / 2 * (i + 0.5) / QT;
        for (j = 0; j < QP; j++) {
            vec wi = polar(ti, 2 * PI * (j + 0.5) / QP);
            double ca = dot(wi, r), lobe, g, pb, pl, wl, wb, dw;
            if (!(ca > 0)) continue;
            lobe = pow(ca, shine) / (2 * PI);
            pb = (shine + 1) * lobe, pl = c * wi.z / PI;
            g = (shine + 2) * lobe * wi.z * L;
            wl = pow(pl, beta) / (pow(pl, beta) + pow(pb, beta)), wb = 1 - wl;
            dw = sin(ti) * cell;
            a += g * dw, ml += wl * g * dw, mb += wb * g * dw;
            sl += wl * wl * g * g / pl * dw;
            if (pb > 0) sb += wb * wb * g * g / pb * dw;
        }
    }
    *albedo = a / L, *mean = ml + mb, *var = sl - ml * ml + sb - mb * mb;
}

/* The radiance a plate_in_sky sends back along polar(theta_o, 0), by
 * n paths, its red channel's samples in x (if not NULL) and returned their
 * Stat. */
static Stat plate_samples(const Scene *s, double theta_o, int n, double *x)
{
    Worker wk = worker();
    Stat st = { 0, 0, 0 };
    vec wo = polar(theta_o, 0);
    int k;
    for (k = 0; k < n; k++) {
        double L;
        start_sample(&wk, s, 0, 0, k);
        L = radiance_along(s, wo, scale(-1, wo), &wk).x;
        stat_add(&st, L);
        if (x) x[k] = L;
    }
    return st;
}

/* The plate under a sky of 0.8 sends back 0.8 times its albedo whatever the
 * estimator: the Phong lobe's by phong_sky_mis's quadrature, Lambert and a
 * mirror's kd + ks.  Each estimator, 20000 paths, within K standard
 * errors.  MIS weighs each of its two samples by the power heuristic of
 * the two pdfs, and the weights of a direction sum to 1 only if the sky's
 * pdf that emitted() weighs a BSDF sample by is the one sample_light drew
 * with (its choice c = 1/2 included, measured about the turned normal), and
 * the BSDF's pdf the one sample_bsdf drew with (its lobe's chance included:
 * p_diffuse = 0.5 / 0.8 beside the mirror).  Such slips show only where the
 * two pdfs differ, as here: a Lambertian ball alone under a sky (sky_checks)
 * has the cosine pdf for both, and any weights, swapped or not, share it
 * alike.  Phong 1 from 70 degrees sends a third of its samples below the
 * horizon: the path ends there, but the light sample taken before it still
 * counts. */
static void test_plate_in_sky(void)
{
    static const struct { const char *name; double kd, ks, shine, degrees; } c[] = {
        { "Phong 1", 0, 1, 1, 70 },
        { "Phong 10", 0, 1, 10, 30 },
        { "Lambert 0.5 + mirror 0.3", 0.5, 0.3, 0, 30 },
    };
    double L = 0.8;
    int q, e;
    char name[240];
    for (q = 0; q < (int)(sizeof c / sizeof c[0]); q++) {
        double th = c[q].degrees * PI / 180, albedo = c[q].kd + c[q].ks, mean, var;
        if (c[q].shine > 0) phong_sky_mis(c[q].shine, th, 0.5, 2, L, &albedo, &mean, &var);
        for (e = 0; e < 3; e++) {
            Scene s;
            Stat st;
            plate_in_sky(&s, L, c[q].kd, c[q].ks, c[q].shine, e);
            st = plate_samples(&s, th, 20000, NULL);
            sprintf(name, "a plate of %s seen from %g degrees on its back, under a sky of 0.8 and over a point"
                    " light: 0.8 times its albedo%s, %s", c[q].name, c[q].degrees,
                    c[q].shine > 0 ? " (quadrature)" : " kd + ks", est_name[e]);
            report(agrees(&st, L * albedo), name, "%.5f +- %.5f, want %.5f", stat_mean(&st), stat_se(&st),
                   L * albedo);
            free_scene(&s);
        }
    }
}

/* MIS's variance on that plate of Phong 10 seen from 30 degrees: the
 * balance heuristic and the power heuristic are both unbiased, and only
 * the noise tells them apart.  phong_sky_mis integrates the variance of
 * the sum of a path's two samples (the light's and the BSDF's, each
 * weighed) for either: here the power heuristic's is 0.56 times the balance
 * heuristic's, as Veach (thesis, chapter 9) made the power heuristic for:
 * where one technique (here the lobe's own) is far better than the other,
 * it gives that one more of the weight.  The sample variance of N
 * paths within K of its standard errors (Cramer's (m4 - s^4) / N, as
 * test_mis_variance) of the power heuristic's. */
static void test_plate_mis_variance(void)
{
    enum { N = 20000 };
    static double x[N];
    double th = 30 * PI / 180, albedo, mean, v_power, v_balance, m, v, se;
    Scene s;
    phong_sky_mis(10, th, 0.5, 2, 1, &albedo, &mean, &v_power);
    phong_sky_mis(10, th, 0.5, 1, 1, &albedo, &mean, &v_balance);
    plate_in_sky(&s, 1, 0, 1, 10, MIS);
    plate_samples(&s, th, N, x);
    sample_moments(x, N, &m, &v, &se);
    report(fabs(v - v_power) <= K * se,
           "MIS on a plate of Phong 10 from 30 degrees under a sky: the variance of a path is the power"
           " heuristic's (quadrature of Veach's multi-sample estimator)",
           "%.5f +- %.5f, want %.5f (the balance heuristic's: %.5f)", v, se, v_power, v_balance);
    free_scene(&s);
}

/* A cone that glows is no light sample_light can choose, so whatever the
 * estimator, its light is found by BSDF sampling alone and counts in full:
 * all three must agree on a ball lit by it (NEE used to drop it, MIS to
 * read a light that does not exist).  Means within K standard errors of
 * their difference. */
static void test_glowing_cone(void)
{
    Stat st[3];
    int e, ok = 1;
    for (e = 0; e < 3; e++) {
        Scene s;
        default_scene(&s);
        s.set.w = s.set.h = 8;
        add_cone(&s, v3(0, 0, -1), 0.5, v3(0, 0, 1), 0.5, material(&s, v3(1, 1, 1), 0, 0, 0, 2, 1, 0));
        add_sphere(&s, v3(0, 0, -3), 1.5, material(&s, v3(1, 1, 1), 0.8, 0, 0, 0, 1, 0));
        camera(&s, v3(0, -5, 0), v3(0, 0, -1), v3(0, 0, 1), 40);
        ready(&s, e, 1, 0);
        st[e] = image_samples(&s, 20000, 0);
        free_scene(&s);
    }
    for (e = 0; e < 3; e++) {
        const Stat *a = &st[e], *b = &st[(e + 1) % 3];
        ok = ok && fabs(stat_mean(a) - stat_mean(b))
                       <= K * sqrt(stat_se(a) * stat_se(a) + stat_se(b) * stat_se(b));
    }
    report(ok, "a glowing cone (no light to sample) lights a ball the same for every estimator",
           "bsdf %.4f, nee %.4f, mis %.4f (+- %.4f)", stat_mean(&st[0]), stat_mean(&st[1]),
           stat_mean(&st[2]), stat_se(&st[0]));
}

/* Another seed gives other noise with the same mean: pixel by pixel the
 * differences of two renders average to 0. */
static void test_seed(void)
{
    Scene s;
    Stat d = { 0, 0, 0 };
    int i, j, same = 0;
    if (!cornell(&s, 24, MIS, "another seed")) return;
    for (j = 0; j < s.set.h; j++)
        for (i = 0; i < s.set.w; i++) {
            Worker wk = worker();
            vec a, b;
            s.set.seed = 1;
            a = pixel_radiance(&s, i, j, 16, &wk);
            s.set.seed = 2;
            b = pixel_radiance(&s, i, j, 16, &wk);
            same += a.x == b.x;
            stat_add(&d, luminance(sub(a, b)));
        }
    report(same < 10 && agrees(&d, 0), "another --seed: other noise, the same mean",
           "%d of 576 pixels equal; mean difference %.3g +- %.3g", same, stat_mean(&d), stat_se(&d));
    free_scene(&s);
}

int main(void)
{
    test_fresnel();
    test_reciprocity();
    test_energy();
    test_ggx_normalised();
    test_chi2();
    test_warps();
    test_dimensions_distinct();
    test_dimensions_fixed();
    test_furnace();
    test_point_in_sphere();
    test_sphere_is_point();
    test_glass_split();
    test_polygon_lights();
    test_shading_normals();
    sky_checks();
    test_estimators_agree();
    test_veach();
    test_mis_variance();
    test_plate_in_sky();
    test_plate_mis_variance();
    test_glowing_cone();
    test_seed();
    return failures != 0;
}

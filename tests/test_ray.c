/* Unit tests for ray.c: vector maths, sphere hits (far, tiny, from inside),
 * refraction and total internal reflection, the camera, and shadow acne at
 * scene scales from 1e-3 to 1e5.  ray.c is included whole so that its
 * static functions can be called; its main() is renamed out of the way.
 * Prints "PASS name" / "FAIL name" lines for tests/run.sh. */
#define main ray_main
#include "../ray.c"
#undef main
#define PI 3.14159265358979323846

static int failures;

static void report(int ok, const char *name, const char *fmt, double a, double b)
{
    printf("%s %s (", ok ? "PASS" : "FAIL", name);
    printf(fmt, a, b);
    printf(")\n");
    failures += !ok;
}

static int near(double a, double b, double tol) { return fabs(a - b) <= tol; }

static void test_vectors(void)
{
    vec a = v3(1, 2, 3), b = v3(-4, 5, 0.5), c = cross(a, b), u = unit(b);
    report(dot(a, b) == 7.5, "dot", "%g == %g", dot(a, b), 7.5);
    report(near(dot(c, a), 0, 1e-12) && near(dot(c, b), 0, 1e-12) && c.x == -14,
           "cross is orthogonal to both", "c.a=%g c.b=%g", dot(c, a), dot(c, b));
    report(near(sqrt(dot(u, u)), 1, 1e-15), "unit length", "|u|=%.17g want %g", sqrt(dot(u, u)), 1);
    report(comb(2, a, b).y == 9 && mul(a, b).z == 1.5, "comb and mul", "%g %g",
           comb(2, a, b).y, mul(a, b).z);
}

static Sphere sphere(double x, double y, double z, double r)
{
    Sphere s;
    memset(&s, 0, sizeof s);
    s.cen = v3(x, y, z);
    s.rad = r;
    return s;
}

static Ray ray(vec o, vec d) { Ray r; r.o = o; r.d = d; return r; }

/* The near root in long double, as a reference: 64-bit mantissa, and the
 * stable form, so its error is far below what is tested. */
static long double exact_t(vec o, vec d, vec c, double rad)
{
    long double fx = o.x - (long double)c.x, fy = o.y - (long double)c.y, fz = o.z - (long double)c.z;
    long double a = (long double)d.x * d.x + (long double)d.y * d.y + (long double)d.z * d.z;
    long double b = -(fx * d.x + fy * d.y + fz * d.z);
    long double lx = fx + b / a * d.x, ly = fy + b / a * d.y, lz = fz + b / a * d.z;
    long double disc = a * ((long double)rad * rad - (lx * lx + ly * ly + lz * lz));
    long double q = b + sqrtl(disc);
    long double cc = fx * fx + fy * fy + fz * fz - (long double)rad * rad;
    return cc / q;
}

/* The acceptance bar is 1e-9 of the distance at 1e6; 1e7 and 1e8 are there
 * because at 1e6 doubles still hide the textbook formula's cancellation. */
static void test_sphere_far(void)
{
    double dist;
    for (dist = 1e6; dist <= 1e8; dist *= 10) {
        double worst = 0;
        char name[80];
        int k;
        for (k = 0; k < 100; k++) {
            /* aims spread over the disc of the sphere as seen from the origin */
            double ox = 0.9 * cos(k * 2.4) * sqrt(k / 100.0), oz = 0.9 * sin(k * 2.4) * sqrt(k / 100.0);
            Sphere s = sphere(0, dist, 0, 1);
            Ray r = ray(v3(0, 0, 0), unit(v3(ox, dist, oz)));
            double t = hit_sphere(&s, r, 0);
            double err = fabs(t - (double)exact_t(r.o, r.d, s.cen, 1));
            if (!(err <= worst)) worst = err;   /* NaN counts as worst */
        }
        sprintf(name, "unit sphere at %g: |t - t_exact| <= 1e-9 * distance", dist);
        report(worst <= 1e-9 * dist, name, "worst %.3g, allowed %.3g", worst, 1e-9 * dist);
    }
}

static void test_sphere_tiny(void)
{
    double worst = 0, r;
    int misses = 0;
    for (r = 1e-7; r < 1e-2; r *= 10) {
        Sphere s = sphere(0.3, 1000, -0.2, r);
        Ray ry = ray(v3(0, 0, 0), unit(sub(v3(0.3 + 0.5 * r, 1000, -0.2), v3(0, 0, 0))));
        double t = hit_sphere(&s, ry, 0);
        if (!isfinite(t)) misses++;
        else if (fabs(t - (double)exact_t(ry.o, ry.d, s.cen, r)) / 1000 > worst)
            worst = fabs(t - (double)exact_t(ry.o, ry.d, s.cen, r)) / 1000;
    }
    report(misses == 0 && worst <= 1e-12, "tiny spheres (r 1e-7..1e-3 at 1000) hit accurately",
           "misses %g, worst relative error %.3g", misses, worst);
}

static void test_sphere_inside_and_miss(void)
{
    Sphere s = sphere(1, 2, 3, 2);
    double t_in = hit_sphere(&s, ray(v3(1, 2, 3), v3(0, 0, 1)), 0);
    double t_off = hit_sphere(&s, ray(v3(1, 2.5, 3), v3(1, 0, 0)), 0);
    double t_miss = hit_sphere(&s, ray(v3(1, 2, 6), v3(0, 1, 0)), 0);
    double t_behind = hit_sphere(&s, ray(v3(1, 2, 6), v3(0, 0, 1)), 0);
    report(t_in == 2, "from the centre, t = radius", "t=%.17g want %g", t_in, 2);
    report(near(t_off, sqrt(4 - 0.25), 1e-15), "from inside, off centre", "t=%.17g want %.17g",
           t_off, sqrt(4 - 0.25));
    report(isinf(t_miss) && isinf(t_behind), "a miss and a sphere behind give infinity",
           "%g %g", t_miss, t_behind);
}

static void test_refraction(void)
{
    /* 30 degrees into glass of index 1.5: sin(out) = sin(30)/1.5 */
    vec n = v3(0, 0, 1), d = v3(sin(PI / 6), 0, -cos(PI / 6)), t;
    double cosi = -dot(d, n);
    int ok = refract(d, n, cosi, 1 / 1.5, &t);
    double sin_out = sqrt(t.x * t.x + t.y * t.y) / sqrt(dot(t, t));
    report(ok && near(sin_out, 0.5 / 1.5, 1e-15) && t.z < 0 && near(sqrt(dot(t, t)), 1, 1e-15),
           "Snell: 30 deg into index 1.5", "sin(out)=%.17g want %.17g", sin_out, 0.5 / 1.5);
    /* leaving glass: critical angle asin(1/1.5) = 41.8 degrees */
    d = v3(sin(0.72), 0, -cos(0.72));       /* 41.25 deg: just below critical */
    ok = refract(d, n, -dot(d, n), 1.5, &t);
    report(ok && near(t.x, 1.5 * sin(0.72), 1e-14), "leaving glass below the critical angle refracts",
           "sin(out)=%.17g want %.17g", t.x, 1.5 * sin(0.72));
    d = v3(sin(0.74), 0, -cos(0.74));       /* 42.4 deg: just above */
    ok = refract(d, n, -dot(d, n), 1.5, &t);
    report(!ok, "above the critical angle: total internal reflection", "refracted=%g (want %g)", ok, 0);
    t = reflect(d, n, -dot(d, n));
    report(near(t.x, d.x, 1e-15) && near(t.z, -d.z, 1e-15), "reflection mirrors the normal component",
           "z=%.17g want %.17g", t.z, -d.z);
}

static void test_camera(void)
{
    Scene s;
    Ray c, e;
    double angle;
    default_scene(&s);
    s.cam.fov = 60;
    c = camera_ray(&s.cam, 640, 480, 320, 240);
    e = camera_ray(&s.cam, 640, 480, 0, 240);
    angle = acos(dot(c.d, e.d)) * 180 / PI;
    report(near(c.d.y, 1, 1e-15), "the image centre looks along the view", "d.y=%.17g want %g", c.d.y, 1);
    report(near(angle, 30, 1e-12), "the left edge is half the field of view away",
           "%.15g deg, want %g", angle, 30);
}

/* Shadow acne: a point light above a ground (a sphere of radius 1e4 units
 * whose top is the plane z = 0) and a unit ball resting on it, everything
 * multiplied by `k`.  For every pixel that sees the ground or the ball, the
 * shadow ray's verdict is compared with the exact geometric answer; pixels
 * within 1e-6 of a shadow edge are not counted, since there the answer
 * depends on rounding.  Acne would show as lit points found shadowed. */
static int acne_at_scale(double k, int *counted)
{
    Scene s;
    Light l;
    int i, j, wrong = 0, W = 96;
    Stats st;
    real v[10];
    memset(&st, 0, sizeof st);
    default_scene(&s);
    s.nsph = 2;
    s.sph = calloc(2, sizeof *s.sph);
    s.sph[0] = sphere(0, 0, -1e4 * k, 1e4 * k);
    s.sph[1] = sphere(0, 0, k, k);
    s.sph[0].m.ir = s.sph[1].m.ir = 1;
    l.pos = v3(2 * k, -1 * k, 6 * k);
    l.color = v3(1, 1, 1);
    l.sphere = -1;
    s.light = &l;
    s.nlight = 1;
    v[0] = 0; v[1] = -8 * k; v[2] = 5 * k; v[3] = 0; v[4] = 0; v[5] = 0;
    v[6] = 0; v[7] = 0; v[8] = 1; v[9] = 50;
    set_camera(&s, (Where){ "", 0 }, v);
    *counted = 0;
    for (j = 0; j < W; j++)
        for (i = 0; i < W; i++) {
            Hit h;
            real e;
            vec n, to_l, oc;
            double b, dist2, len;
            int lit, truth;
            if (!nearest_hit(&s, camera_ray(&s.cam, W, W, i + 0.5, j + 0.5), &h, &st)) continue;
            n = h.n;
            lit = shadow_ray(&s, &h, n, &l, &e, &st);
            if (!(e > 1e-6)) continue;     /* grazing or facing away */
            /* exact: does the segment from the point to the light pass
             * through the ball (if the point is on the ground), in units of k */
            to_l = unit(sub(l.pos, h.p));
            oc = sub(s.sph[1].cen, h.p);
            b = dot(oc, to_l);
            dist2 = dot(oc, oc) - b * b;
            len = sqrt(dot(sub(l.pos, h.p), sub(l.pos, h.p)));
            truth = 1;
            if (h.obj == 0 && b > 0 && b < len) {
                if (fabs(sqrt(dist2) / k - 1) < 1e-6) continue;   /* on the shadow's edge */
                truth = dist2 > k * k;
            }
            ++*counted;
            wrong += lit != truth;
        }
    free(s.sph);
    return wrong;
}

static void test_acne(void)
{
    double k;
    for (k = 1e-3; k <= 1e5 * 1.001; k *= 10) {
        int counted, wrong = acne_at_scale(k, &counted);
        char name[80];
        sprintf(name, "no acne: plane and ball at scale %g", k);
        report(wrong == 0 && counted > 3000, name, "%g wrongly shadowed of %g lit-side pixels", wrong, counted);
    }
}

int main(void)
{
    test_vectors();
    test_sphere_far();
    test_sphere_tiny();
    test_sphere_inside_and_miss();
    test_refraction();
    test_camera();
    test_acne();
    return failures != 0;
}

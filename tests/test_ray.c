/* Unit tests for ray.c: vector maths, sphere hits (far, tiny, from inside),
 * refraction and total internal reflection, the camera, and shadow acne at
 * scene scales from 1e-3 to 1e5.  ray.c is included whole so that its
 * static functions can be called; its main() is renamed out of the way.
 * Prints "PASS name" / "FAIL name" lines for tests/run.sh. */
#define main ray_main
#include "../ray.c"
#undef main

static int failures;

/* One result line; flushed, so that a crash later loses none.  The float
 * build (-DREAL=float, which ray.test.sh also runs) says so in each name. */
static void report(int ok, const char *name, const char *fmt, double a, double b)
{
    printf("%s %s%s (", ok ? "PASS" : "FAIL", sizeof(real) == sizeof(float) ? "float build: " : "", name);
    printf(fmt, a, b);
    printf(")\n");
    fflush(stdout);
    failures += !ok;
}

/* load_scene, or a FAIL line for the test `name` and 0: the caller then
 * returns without touching the scene, whose arrays may be short or empty. */
static int load_or_fail(Scene *s, const char *file, const char *name)
{
    if (load_scene(s, file)) return 1;
    printf("FAIL %s (%s did not load)\n", name, file);
    fflush(stdout);
    failures++;
    free_scene(s);
    return 0;
}

static int near(double a, double b, double tol) { return fabs(a - b) <= tol; }

/* The rays a random check shoots: a tenth of `full` in make test, all of
 * them when RAY_TEST_FULL is set (make stress), where the rare miss at an
 * edge has ten times the chance to show. */
static int rays(int full) { return getenv("RAY_TEST_FULL") ? full : full / 10; }

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

static Ray ray(vec o, vec d) { Ray r; r.o = o; r.d = d; r.tmin = 0; r.skip = -1; r.time = 0; return r; }
/* The same, for the intersection tests, which take the ray by pointer. */
static const Ray *rp(vec o, vec d) { static Ray r; r.o = o; r.d = d; r.tmin = 0; r.skip = -1; r.time = 0; return &r; }

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
            double t = hit_sphere(&s, &r, 0);
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
        double t = hit_sphere(&s, &ry, 0);
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
    double t_in = hit_sphere(&s, rp(v3(1, 2, 3), v3(0, 0, 1)), 0);
    double t_off = hit_sphere(&s, rp(v3(1, 2.5, 3), v3(1, 0, 0)), 0);
    double t_miss = hit_sphere(&s, rp(v3(1, 2, 6), v3(0, 1, 0)), 0);
    double t_behind = hit_sphere(&s, rp(v3(1, 2, 6), v3(0, 0, 1)), 0);
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


/* ---- triangles ---- */

static Scene tri_scene(int cull)
{
    Scene s;
    Material m;
    memset(&m, 0, sizeof m);
    m.color = v3(1, 1, 1);
    m.kd = m.ir = 1;
    default_scene(&s);
    s.cull = cull;
    add_material(&s, m);
    return s;
}

static int tri(Scene *s, vec a, vec b, vec c)
{
    int i = add_vertex(s, a), j = add_vertex(s, b);
    add_triangle(s, i, j, add_vertex(s, c), -1, -1, -1, 0);
    return s->ntri - 1;
}


/* Legs from 1e-12 to 1e12, the ray starting one leg above: t must be one
 * leg.  The original epsilon (|det| < 1e-6) loses every leg below 1e-3; in
 * the float build a degenerate-area test in float lost legs above 1e9 and
 * below 1e-11 (its product of four lengths overflowed or underflowed). */
static void test_triangle_scales(void)
{
    double L, worst = 0;
    int misses = 0;
    for (L = 1e-12; L <= 1e12 * 1.01; L *= 10) {
        Scene s = tri_scene(0);
        real t, u, v;
        int k = tri(&s, v3(0, 0, 0), v3(L, 0, 0), v3(0, L, 0));
        if (!hit_triangle(&s, &s.tri[k], rp(v3(0.25 * L, 0.25 * L, L), v3(0, 0, -1)), INFINITY, &t, &u, &v))
            misses++;
        else if (fabs(t / L - 1) > worst)
            worst = fabs(t / L - 1);
        free_scene(&s);
    }
    report(misses == 0 && worst < 8 * REAL_EPS, "triangles with legs 1e-12..1e12 are hit at the right t",
           "misses %g, worst relative error %.3g", misses, worst);
}

/* Zero-area triangles never hit and never give NaN; NaN rays hit nothing. */
static void test_triangle_degenerate(void)
{
    Scene s = tri_scene(0);
    unsigned x = 12345;
    int k, hits = 0, nans = 0, r;
    tri(&s, v3(0, 0, 0), v3(1, 0, 0), v3(1, 0, 0));            /* repeated vertex */
    tri(&s, v3(0, 0, 0), v3(1, 1, 1), v3(3, 3, 3));            /* in a line */
    tri(&s, v3(0.1, 0.2, 0.3), v3(0.1, 0.2, 0.3), v3(0.1, 0.2, 0.3)); /* a point */
    tri(&s, v3(0, 0, 0), v3(1e-9, 1e-9, 1e-9), v3(1, 1, 1));   /* in a line, not exactly */
    for (r = 0; r < 100000; r++)
        for (k = 0; k < s.ntri; k++) {
            real t = 0, u = 0, v = 0;
            vec o, d;
            x = x * 1664525u + 1013904223u; o.x = (x >> 8) / 16777216.0 * 4 - 2;
            x = x * 1664525u + 1013904223u; o.y = (x >> 8) / 16777216.0 * 4 - 2;
            x = x * 1664525u + 1013904223u; o.z = (x >> 8) / 16777216.0 * 4 - 2;
            /* aim at a point of the degenerate triangle's line */
            d = sub(comb((x >> 8) / 16777216.0, sub(s.vert[s.tri[k].v[2]], s.vert[s.tri[k].v[0]]),
                         s.vert[s.tri[k].v[0]]), o);
            hits += hit_triangle(&s, &s.tri[k], rp(o, d), INFINITY, &t, &u, &v);
            nans += t != t || u != u || v != v;
        }
    report(hits == 0 && nans == 0, "degenerate triangles: 400000 rays at them, no hit, no NaN",
           "hits %g, NaNs %g", hits, nans);
    {
        Scene g = tri_scene(0);
        real t;
        Sphere sp = sphere(0, 0, 0, 1);
        double nan = strtod("nan", NULL);
        int k2 = tri(&g, v3(-1, -1, 0), v3(1, -1, 0), v3(0, 1, 0));
        int h = hit_object(&g, 0, rp(v3(0, 0, 1), v3(nan, 0, -1)), INFINITY, &t)
                + !isinf(hit_sphere(&sp, rp(v3(0, 0, 5), v3(0, nan, -1)), 0));
        (void)k2;
        report(h == 0, "a ray with a NaN direction hits nothing", "hits %g (want %g)", h, 0);
        free_scene(&g);
    }
    free_scene(&s);
}

static void test_triangle_culling(void)
{
    Scene one = tri_scene(1), two = tri_scene(0);
    real t, u, v;
    int front, back, both;
    tri(&one, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0));         /* normal +z */
    tri(&two, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0));
    front = hit_triangle(&one, &one.tri[0], rp(v3(.2, .2, 1), v3(0, 0, -1)), INFINITY, &t, &u, &v);
    back = hit_triangle(&one, &one.tri[0], rp(v3(.2, .2, -1), v3(0, 0, 1)), INFINITY, &t, &u, &v);
    both = hit_triangle(&two, &two.tri[0], rp(v3(.2, .2, -1), v3(0, 0, 1)), INFINITY, &t, &u, &v);
    report(front && !back && both && near(u, .2, 4 * REAL_EPS) && near(v, .2, 4 * REAL_EPS),
           "culling branch: front only; two-sided by default; u, v right", "front %g back %g", front, back);
    free_scene(&one);
    free_scene(&two);
}

/* A closed mesh: a latitude-longitude sphere of radius 1, its vertices
 * shared (as an OBJ gives them) or repeated per triangle (as NFF's
 * polygons do), with fans of `lon` triangles at the poles. */
static void uv_sphere(Scene *s, int lat, int lon, int shared)
{
    int i, j, base = s->nvert;
    vec *p = malloc(sizeof *p * (size_t)(lat + 1) * lon);
    for (i = 0; i <= lat; i++)
        for (j = 0; j < lon; j++) {
            double th = PI * i / lat, ph = 2 * PI * j / lon;
            p[i * lon + j] = v3(sin(th) * cos(ph), sin(th) * sin(ph), cos(th));
            if (i == 0 || i == lat) p[i * lon + j] = v3(0, 0, i ? -1 : 1);
            if (shared) add_vertex(s, p[i * lon + j]);
        }
    for (i = 0; i < lat; i++)
        for (j = 0; j < lon; j++) {
            int a = i * lon + j, b = i * lon + (j + 1) % lon, c = a + lon, d = b + lon;
            if (i > 0) {
                if (shared) add_triangle(s, base + a, base + c, base + b, -1, -1, -1, 0);
                else tri(s, p[a], p[c], p[b]);
            }
            if (i < lat - 1) {
                if (shared) add_triangle(s, base + b, base + c, base + d, -1, -1, -1, 0);
                else tri(s, p[b], p[c], p[d]);
            }
        }
    free(p);
}

static double rnd(unsigned long long *x)
{
    *x = *x * 6364136223846793005ULL + 1442695040888963407ULL;
    return (*x >> 11) / 9007199254740992.0;
}

/* Rays aimed exactly at the vertices and at points of the edges of a closed
 * mesh, from inside it (far = 0) or from far = 1e4 radii away at a point
 * whose normal is within 60 degrees of the eye (this mesh's faces lean up
 * to about 20 degrees from its vertices' normals, so such a point is never
 * on the silhouette, where a ray may rightly pass by): each must hit.  A ray through an edge or a vertex is where rounding lets a test
 * that is not watertight leak; from afar the rounding is larger (the float
 * build's holes were there). */
static void test_watertight(int shared, double far)
{
    Scene s = tri_scene(0);
    Worker wk;
    unsigned long long x = 42;
    int r, escapes = 0, n = rays(1000000);
    char name[96];
    memset(&wk, 0, sizeof wk);
    uv_sphere(&s, 8, 16, shared);
    build_accel(&s, shared ? "kd" : "none");   /* one through the tree, one through the loop */
    for (r = 0; r < n; r++) {
        const Triangle *t = &s.tri[(int)(rnd(&x) * s.ntri)];
        int e = (int)(rnd(&x) * 3);
        vec a = s.vert[t->v[e]], b = s.vert[t->v[(e + 1) % 3]], o, target;
        double f = r % 2 ? 0 : rnd(&x);       /* half at vertices, half on edges */
        Hit h;
        o = v3(rnd(&x) - .5, rnd(&x) - .5, rnd(&x) - .5);
        target = comb(f, sub(b, a), a);
        if (far > 0) {      /* from outside, at the side facing the eye, not grazing */
            o = scale(far, unit(o));
            if (!(dot(unit(sub(target, o)), target) < -0.5)) o = scale(-1, o);
            if (!(dot(unit(sub(target, o)), target) < -0.5)) { r--; continue; }
        }
        if (!nearest_hit(&s, ray(o, unit(sub(target, o))), &h, &wk)) escapes++;
    }
    sprintf(name, "watertight: rays %s at the vertices and edges of a closed mesh (%s vertices)",
            far > 0 ? "from 1e4 away" : "from inside", shared ? "shared" : "repeated");
    report(escapes == 0, name, "%g escapes of %g rays", escapes, n);
    free_scene(&s);
}

/* sphere_clip gives the tree the box of the part of a sphere inside a
 * cell.  Every point of the sphere that lies in the cell must lie in that
 * box (else the tree could miss a hit there), and the box must be tighter
 * than the sphere's own box cut to the cell (else it is no use).  Points:
 * 2000 on each of 2000 random spheres, cells random boxes across them. */
static void test_sphere_clip(void)
{
    unsigned long long x = 7;
    long outside = 0, inside = 0, cells = 0;
    double gain = 0;
    int k, j, a;
    for (k = 0; k < 2000; k++) {
        double scale = pow(10, 8 * rnd(&x) - 4);
        Sphere sp = sphere(scale * (rnd(&x) - 0.5), scale * (rnd(&x) - 0.5), scale * (rnd(&x) - 0.5),
                           scale * (0.01 + rnd(&x)));
        double blo[3], bhi[3], lo[3], hi[3], c[3], vol_clip = 1, vol_cut = 1;
        to3(sp.cen, c);
        for (a = 0; a < 3; a++) {
            double p = c[a] + sp.rad * (3 * rnd(&x) - 1.5), q = c[a] + sp.rad * (3 * rnd(&x) - 1.5);
            blo[a] = fmin(p, q), bhi[a] = fmax(p, q);
        }
        if (!sphere_clip(&sp, blo, bhi, lo, hi)) lo[0] = hi[0] = NAN;   /* "nothing inside" */
        else {
            cells++;
            for (a = 0; a < 3; a++) {
                vol_clip *= hi[a] - lo[a];
                vol_cut *= fmin(bhi[a], c[a] + sp.rad) - fmax(blo[a], c[a] - sp.rad);
            }
            if (vol_cut > 0) gain += vol_clip / vol_cut;
        }
        for (j = 0; j < 2000; j++) {
            /* a uniform point on the sphere (Marsaglia's cylinder method) */
            double z = 2 * rnd(&x) - 1, phi = 2 * PI * rnd(&x), s = sqrt(1 - z * z), p[3];
            int in_cell = 1, in_box = 1;
            p[0] = c[0] + sp.rad * s * cos(phi), p[1] = c[1] + sp.rad * s * sin(phi), p[2] = c[2] + sp.rad * z;
            for (a = 0; a < 3; a++) {
                in_cell &= p[a] >= blo[a] && p[a] <= bhi[a];
                in_box &= p[a] >= lo[a] && p[a] <= hi[a];
            }
            inside += in_cell;
            outside += in_cell && !in_box;
        }
    }
    report(outside == 0 && inside > 100000, "sphere clipped to a cell: every point of it in the cell is in the box",
           "%g of %g points outside", (double)outside, (double)inside);
    report(cells > 0 && gain / cells < 0.9, "sphere clipped to a cell: tighter than the cut box",
           "mean volume ratio %.3f over %g cells", gain / cells, (double)cells);
}

/* Each structure (kd, bvh, grid) must give what the loop gives: same
 * object, same t, bit for bit, for a scene of spheres and triangles and
 * rays of every awkward kind. */
static void test_tree_matches_loop(const char *accel, int full)
{
    int n = rays(full);
    Scene s = tri_scene(0);
    Worker wk;
    unsigned long long x = 7;
    int r, k, wrong = 0, used;
    memset(&wk, 0, sizeof wk);
    uv_sphere(&s, 6, 12, 1);
    for (k = 0; k < 60; k++) {          /* random spheres and triangles in [-3, 3]^3 */
        vec c = v3(6 * rnd(&x) - 3, 6 * rnd(&x) - 3, 6 * rnd(&x) - 3);
        add_sphere(&s, c, 0.05 + 0.3 * rnd(&x), 0);
        tri(&s, c, add(c, v3(rnd(&x), rnd(&x), 0)), add(c, v3(0, rnd(&x), rnd(&x))));
        add_cone(&s, c, 0.3 * rnd(&x), add(c, v3(rnd(&x) - .5, rnd(&x) - .5, rnd(&x))), 0.2 * rnd(&x), 0);
    }
    add_cone(&s, v3(0, 0, -2), 0.5, v3(0, 0, 2), 0.5, 0);      /* along z: axis-parallel rays */
    tri(&s, v3(-4, -4, -1), v3(4, -4, -1), v3(-4, 4, -1));     /* axis-aligned: splits land on it */
    tri(&s, v3(0, 0, 0), v3(0, 2, 0), v3(0, 0, 2));
    build_accel(&s, accel);
    used = s.accel.which;
    for (r = 0; r < n; r++) {
        Hit a, b;
        int ha, hb;
        Ray ry;
        ry.skip = -1, ry.tmin = 0, ry.time = 0;
        ry.o = v3(8 * rnd(&x) - 4, 8 * rnd(&x) - 4, 8 * rnd(&x) - 4);
        ry.d = unit(v3(rnd(&x) - .5, rnd(&x) - .5, rnd(&x) - .5));
        switch (r % 5) {
        case 1: ry.d = v3(0, 0, 0); *(&ry.d.x + r / 5 % 3) = r / 15 % 2 ? 1 : -1; break; /* axis-parallel */
        case 2: ry.o.z = -1; break;                          /* on the big triangle's plane */
        case 3: ry.o.x = 0; ry.d.x = 0; ry.d = unit(ry.d); break; /* in the plane x = 0 */
        case 4: ry.o = scale(0.01, ry.o); break;              /* inside the scene box */
        }
        ha = nearest_hit(&s, ry, &a, &wk);
        s.accel.which = ACCEL_NONE;
        hb = nearest_hit(&s, ry, &b, &wk);
        s.accel.which = used;
        if (ha != hb || (ha && (a.obj != b.obj || a.t != b.t))) wrong++;
    }
    {
        char name[160];
        sprintf(name, "%s = loop (spheres, cones, triangles): same object and t (axis-parallel rays, "
                "in planes, inside)", accel);
        report(wrong == 0 && used != ACCEL_NONE, name, "%g mismatches of %g", wrong, n);
    }
    free_scene(&s);
}

/* The contract of prims.h, kept by ray.c's hit callback: a sphere, a cone
 * and triangles of sizes 1e-3 to 1, at the origin and moved to 1e4 and 1e8,
 * hit by rays from 2 to 1e13 of their sizes away, aimed at their boxes.
 * For each hit at t: how far across the ray its line passes from the box
 * (the least growth g of the box that the line meets), in units of
 * PRIMS_HIT_REL L + PRIMS_HIT_ULPS eps s, and how far along the ray t lies
 * from the stretch inside the box grown by that allowance (or by g, if
 * more), in units of eps m, both at most 1 and PRIMS_HIT_ULPS.  Half the
 * rays aim at the middle of a face of the box, where a sphere touches it.  The line is
 * taken relative to the box's middle c from the point o + t0 d nearest c,
 * summed exactly (prims_along), so that the measure itself does not round
 * by eps m.  Without hit_triangle's far move (FAR_MOVE) the triangles err
 * along the ray by 49 eps m.  Not in the float build: there (FLT_EPSILON)
 * a triangle met 10^3 of its sizes away errs along by 27 eps m (its edge
 * slack of 96 ulps, above hit_triangle), and one cone from 10^10 of its
 * sizes away across by 2.6e7 allowances (without hit_sphere's and
 * hit_cone's far moves, spheres and cones by 10^11). */
static void test_hit_contract(void)
{
    static const double offsets[3] = { 0, 1e4, 1e8 }, dists[5] = { 2, 1e3, 1e6, 1e10, 1e13 };
    double worst_across = 0, worst_along = 0, eps = REAL_EPS;
    unsigned long long x = 11;
    long hits = 0, rays = 0;
    int io, id, k, n, i, a;
    for (io = 0; io < 3; io++) {
        Scene s = tri_scene(0);
        vec off = v3(offsets[io], -offsets[io], offsets[io]);
        for (k = 0; k < 20; k++) {
            double size = pow(10, -3 * rnd(&x));
            vec c = add(off, v3(rnd(&x), rnd(&x), rnd(&x)));
            add_sphere(&s, c, size * (0.1 + rnd(&x)), 0);
            add_cone(&s, c, size * rnd(&x), add(c, scale(size, v3(rnd(&x) - .5, rnd(&x) - .5, rnd(&x)))),
                     size * rnd(&x), 0);
            tri(&s, c, add(c, scale(size, v3(rnd(&x), rnd(&x), 0))), add(c, scale(size, v3(0, rnd(&x), rnd(&x)))));
        }
        n = nobj(&s);
        for (i = 0; i < n; i++)
            for (id = 0; id < 5; id++)
                for (k = 0; k < 200; k++) {
                    double lo[3], hi[3], cen[3], o[3], d[3], q[3], L = 0, sm = 0, m, t, t0, tau;
                    double ta[3], tb[3], g = 0, G, TA = -HUGE_VAL, TB = HUGE_VAL, dmax = 0, dd = 0, cd = 0;
                    Ray ry;
                    Query qu;
                    int b;
                    prim_bounds(&s, i, lo, hi);
                    for (a = 0; a < 3; a++) {
                        cen[a] = 0.5 * lo[a] + 0.5 * hi[a];
                        L = fmax(L, hi[a] - lo[a]);
                        sm = fmax(sm, fmax(fabs(lo[a]), fabs(hi[a])));
                    }
                    ry.d = unit(v3(rnd(&x) - .5, rnd(&x) - .5, rnd(&x) - .5));
                    to3(ry.d, d);
                    for (a = 0; a < 3; a++)   /* from dist sizes away, at a point of the box grown by 10% */
                        o[a] = lo[a] + (1.2 * rnd(&x) - 0.1) * (hi[a] - lo[a]) - dists[id] * L * d[a];
                    if (k % 2) {              /* or at the middle of a face: a sphere touches it there */
                        b = k / 2 % 3;
                        for (a = 0; a < 3; a++)
                            o[a] = (a != b ? cen[a] : k / 6 % 2 ? hi[a] : lo[a]) - dists[id] * L * d[a];
                    }
                    ry.o = v3(o[0], o[1], o[2]), ry.skip = -1, ry.tmin = 0, ry.time = 0;
                    qu = query(ry);
                    to3(ry.o, o);
                    rays++;
                    if (!prim_hit(&s, i, &qu, 0, INFINITY, &t)) continue;
                    hits++;
                    m = sm;
                    for (a = 0; a < 3; a++) {
                        m = fmax(m, fabs(o[a]));
                        dmax = fmax(dmax, fabs(d[a]));
                        dd += d[a] * d[a], cd += (cen[a] - o[a]) * d[a];
                    }
                    t0 = cd / dd;
                    for (a = 0; a < 3; a++) q[a] = prims_along(o[a], cen[a], t0, d[a]);
                    tau = t - t0;
                    /* the line q + tau d against the box lo - c .. hi - c, per axis */
                    for (a = 0; a < 3; a++) {
                        double l = lo[a] - cen[a], h = hi[a] - cen[a];
                        if (d[a] == 0) {
                            g = fmax(g, fmax(l - q[a], q[a] - h));
                            ta[a] = -HUGE_VAL, tb[a] = HUGE_VAL;
                            continue;
                        }
                        ta[a] = ((d[a] > 0 ? l : h) - q[a]) / d[a];
                        tb[a] = ((d[a] > 0 ? h : l) - q[a]) / d[a];
                    }
                    for (a = 0; a < 3; a++)
                        for (b = 0; b < 3; b++)
                            if (d[a] != 0 && d[b] != 0)
                                g = fmax(g, (ta[a] - tb[b]) / (1 / fabs(d[a]) + 1 / fabs(d[b])));
                    G = PRIMS_HIT_REL * L + PRIMS_HIT_ULPS * eps * sm;
                    worst_across = fmax(worst_across, g / G);
                    G = fmax(G, g);
                    for (a = 0; a < 3; a++)
                        if (d[a] != 0) {
                            TA = fmax(TA, ta[a] - G / fabs(d[a]));
                            TB = fmin(TB, tb[a] + G / fabs(d[a]));
                        }
                    worst_along = fmax(worst_along, fmax(0, fmax(TA - tau, tau - TB)) * dmax / (eps * m));
                }
        free_scene(&s);
    }
    report(worst_across <= 1 && worst_along <= PRIMS_HIT_ULPS && hits > rays / 10,
           "the hit callbacks keep the contract of prims.h (spheres, cones, triangles, at 0, 1e4 and 1e8, "
           "from 2 to 1e13 sizes away): worst across the ray, in PRIMS_HIT_REL L + PRIMS_HIT_ULPS eps s, "
           "and along it, in eps m", "%.3g and %.3g", worst_across, worst_along);
}

/* Whole pixels through the tree and through the loop, shadows and
 * reflections included, must come out bit for bit the same.  The tree's
 * shadow rays try the light's last blocker first (any_hit's shadow cache);
 * two of the lights stand among the balls, so that the cached blocker often
 * lies beyond the light or misses.  A cache that tested its object without
 * the light's distance darkens 41 pixels here. */
static void test_tree_image(const char *accel)
{
    Scene s = tri_scene(0);
    Material mirror;
    Worker wk;
    unsigned long long x = 3;
    real v[10] = { 0, -9, 6, 0, 0, 0.5, 0, 0, 1, 45 };
    int i, j, k, W = 96, wrong = 0, mat, used;
    memset(&wk, 0, sizeof wk);
    mirror = s.mat[0];
    mirror.kd = 0.6, mirror.ks = 0.4, mirror.shine = 20;
    mat = add_material(&s, mirror);
    add_sphere(&s, v3(0, 0, -1000), 1000, 0);                   /* the ground */
    for (k = 0; k < 150; k++)
        add_sphere(&s, v3(8 * rnd(&x) - 4, 8 * rnd(&x) - 4, 2 * rnd(&x)),
                   0.1 + 0.3 * rnd(&x), k % 2 ? mat : 0);
    add_light(&s, v3(-5, -4, 9), v3(0.5, 0.5, 0.5), -1);
    add_light(&s, v3(0.3, 0.2, 0.6), v3(0.4, 0.4, 0.4), -1);
    add_light(&s, v3(-1.5, 1.1, 0.4), v3(0.3, 0.3, 0.3), -1);
    set_camera(&s, v, (char[SCENE_WHY]){ 0 });
    build_accel(&s, accel);
    used = s.accel.which;
    for (j = 0; j < W; j++) {
        for (k = 0; k < SHADOW_SLOTS; k++) wk.blocker[k] = -1;
        for (i = 0; i < W; i++) {
            Ray r = camera_ray(&s.cam, W, W, i + 0.5, j + 0.5);
                vec a = trace(&s, r, s.set.depth, 1, &wk), b;
            s.accel.which = ACCEL_NONE;
            b = trace(&s, r, s.set.depth, 1, &wk);
            s.accel.which = used;
            wrong += memcmp(&a, &b, sizeof a) != 0;
        }
    }
    {
        char name[160];
        sprintf(name, "%s = loop: whole pixels bit for bit (shadows, mirrors, lights among the balls)",
                accel);
        report(wrong == 0 && used != ACCEL_NONE, name, "%g of %g pixels differ", wrong, W * W);
    }
    free_scene(&s);
}

/* Total internal reflection in Whitted's model: a glass surface (kt 1,
 * ks 0) in a white room, a ray from the glass side meeting it at 72 degrees,
 * past the critical angle of index 1.5.  The card's rule loses the kt share
 * there (black); the SPD's, and `tir reflect`'s, sends it into the
 * reflected ray, which sees the white room. */
static void test_tir(void)
{
    Scene s = tri_scene(0);
    Worker wk;
    Ray r;
    vec black, white;
    memset(&wk, 0, sizeof wk);
    s.mat[0].kd = 0, s.mat[0].kt = 1, s.mat[0].ir = 1.5;
    s.background = v3(1, 1, 1);
    tri(&s, v3(-10, -10, 0), v3(30, -10, 0), v3(-10, 30, 0));    /* front +z: glass below */
    build_accel(&s, "none");
    r = ray(v3(0, -1, -0.5), unit(v3(0, 0.9, 0.3)));
    wk.budget = RAY_BUDGET;
    black = trace(&s, r, 8, 1, &wk);
    s.tir_reflect = 1;
    wk.budget = RAY_BUDGET;
    white = trace(&s, r, 8, 1, &wk);
    report(black.x == 0 && white.x == 1, "total internal reflection: black by the card's rule, reflected by the SPD's",
           "card %g, SPD %g", black.x, white.x);
    free_scene(&s);
}

/* Two nested balls that are both perfect mirrors and perfect glass (ks = kt
 * = 1): every ray spawns two at every level, and the weight never falls.
 * At depth 64 a primary ray's tree is held to RAY_BUDGET secondary rays,
 * and what was not traced is counted. */
static void test_budget(void)
{
    Scene s = tri_scene(0);
    Worker wk;
    unsigned long long traced;
    memset(&wk, 0, sizeof wk);
    s.mat[0].kd = 0, s.mat[0].ks = 1, s.mat[0].kt = 1, s.mat[0].ir = 1.3;
    s.background = v3(1, 1, 1);
    add_sphere(&s, v3(0, 0, 0), 2, 0);
    add_sphere(&s, v3(0, 0, 0), 1, 0);
    build_accel(&s, "none");
    wk.budget = RAY_BUDGET;
    trace(&s, ray(v3(0.3, -5, 0.2), v3(0, 1, 0)), 64, 1, &wk);
    traced = wk.count.reflected + wk.count.refracted;
    report(traced == RAY_BUDGET && wk.count.cut > 0, "ks = kt = 1 at depth 64: the tree stops at the ray budget",
           "%g secondary rays traced, %g cut", (double)traced, (double)wk.count.cut);
    free_scene(&s);
}

/* The kd-tree keeps its boxes and planes in float: a scene beyond 1e37, or
 * all within 1e-30 of the origin, gets the loop over every object instead
 * (with a warning), and the loop's right answer. */
static void test_float_range(void)
{
    static const double scales[3] = { 1, 1e38, 1e-35 };
    int k, ok = 1, i;
    for (k = 0; k < 3; k++) {
        Scene s = tri_scene(0);
        Worker wk;
        Hit h;
        double c = scales[k];
        memset(&wk, 0, sizeof wk);
        for (i = 0; i < 12; i++) add_sphere(&s, v3(3 * c * i, 5 * c, 0), c, 0);
        build_accel(&s, "kd");
        ok = ok && (s.accel.which == ACCEL_KD) == (k == 0);
        ok = ok && nearest_hit(&s, ray(v3(6 * c, 0, 0), v3(0, 1, 0)), &h, &wk) && h.obj == 2;
        free_scene(&s);
    }
    report(ok, "coordinates beyond the float range: the loop instead of the kd-tree, and the right hit",
           "%g%.0g", ok, 0);
}

/* A room, a closed box of 12 triangles (4 x 4 x 3), with a point light just
 * under its ceiling and a ball on its floor.  Each pixel that sees the floor
 * is compared with the exact answer: white, kd 1, no ambient, so the light's
 * cos(angle to the normal) where the segment from the point to the light
 * misses the ball, and black where it crosses the ball.  A shadow ray that
 * counts what lies beyond the light (tmax = infinity instead of the light's
 * distance) meets the ceiling and turns the whole floor black.  The tree =
 * loop tests cannot see that, as both sides share shadow_ray; nor can a
 * scene with nothing beyond its lights.  Through the tree and the loop. */
static void test_light_under_ceiling(void)
{
    static const int face[6][4] = { { 0, 1, 3, 2 }, { 4, 5, 7, 6 }, { 0, 1, 5, 4 },
                                    { 2, 3, 7, 6 }, { 0, 2, 6, 4 }, { 1, 3, 7, 5 } };
    Scene s = tri_scene(0);
    Worker wk;
    vec light = v3(0.4, -0.3, 2.8), ball = v3(-0.9, -0.5, 0.5);
    real v[10] = { 0, -1.8, 2.5, 0, 0.3, 0, 0, 0, 1, 90 };
    int c[8], k, i, j, accel, W = 64;
    memset(&wk, 0, sizeof wk);
    for (k = 0; k < 8; k++)      /* corner k: x, y, z high by bits 1, 2, 4 */
        c[k] = add_vertex(&s, v3(k & 1 ? 2 : -2, k & 2 ? 2 : -2, k & 4 ? 3 : 0));
    for (k = 0; k < 6; k++) {    /* face 0, triangles 0 and 1, is the floor */
        add_triangle(&s, c[face[k][0]], c[face[k][1]], c[face[k][2]], -1, -1, -1, 0);
        add_triangle(&s, c[face[k][0]], c[face[k][2]], c[face[k][3]], -1, -1, -1, 0);
    }
    add_sphere(&s, ball, 0.5, 0);
    add_light(&s, light, v3(1, 1, 1), -1);
    set_camera(&s, v, (char[SCENE_WHY]){ 0 });
    build_accel(&s, "kd");
    for (accel = 0; accel < 2; accel++) {
        int wrong = 0, lit = 0, dark = 0;
        s.accel.which = accel ? ACCEL_NONE : ACCEL_KD;
        for (j = 0; j < W; j++) {
            for (k = 0; k < SHADOW_SLOTS; k++) wk.blocker[k] = -1;
            for (i = 0; i < W; i++) {
                Ray r = camera_ray(&s.cam, W, W, i + 0.5, j + 0.5);
                Hit h;
                vec p, to_l, oc, col;
                double len, b, miss, want;
                if (!nearest_hit(&s, r, &h, &wk) || h.obj < s.nsph || h.obj - s.nsph > 1) continue;
                p = comb(-r.o.z / r.d.z, r.d, r.o);          /* exactly on z = 0 */
                to_l = sub(light, p);
                len = sqrt(dot(to_l, to_l));
                to_l = scale(1 / len, to_l);
                oc = sub(ball, p);
                b = dot(oc, to_l);                            /* closest approach to the ball */
                miss = b <= 0 || b >= len ? INFINITY : sqrt(fmax(dot(oc, oc) - b * b, 0)) - 0.5;
                if (fabs(miss) < 1e-6) continue;              /* on the shadow's edge */
                want = miss > 0 ? to_l.z : 0;
                col = trace(&s, r, s.set.depth, 1, &wk);
                lit += want > 0, dark += want == 0;
                wrong += !(fabs(col.x - want) <= 1e-9) || col.y != col.x || col.z != col.x;
            }
        }
        report(wrong == 0 && lit > 1000 && dark > 50,
               accel ? "a light under the ceiling: the floor exact, lit and in the ball's shadow (loop)"
                     : "a light under the ceiling: the floor exact, lit and in the ball's shadow (kd-tree)",
               "%g wrong of %g floor pixels", wrong, lit + dark);
    }
    free_scene(&s);
}

/* ---- scene readers ---- */

static const char *write_tmp(const char *name, const char *text)
{
    static char path[256];
    const char *dir = getenv("TMP") ? getenv("TMP") : "/tmp";
    FILE *f;
    sprintf(path, "%s/%s", dir, name);
    f = fopen(path, "w");
    fputs(text, f);
    fclose(f);
    return path;
}

static double tri_area(const Scene *s, int k)
{
    const Triangle *t = &s->tri[k];
    vec n = cross(sub(s->vert[t->v[1]], s->vert[t->v[0]]), sub(s->vert[t->v[2]], s->vert[t->v[0]]));
    return 0.5 * sqrt(dot(n, n));
}

/* Ear clipping: a concave star and a comb (like a gear's teeth) must come
 * out as n-2 triangles covering exactly the polygon's area, with no triangle
 * outside it; a fan from vertex 0 gets the area wrong. */
static void test_ear_clipping(void)
{
    int shape;
    for (shape = 0; shape < 2; shape++) {
        Scene s = tri_scene(0);
        int vi[64], n = shape ? 40 : 16, k;
        double area = 0, sum = 0;
        for (k = 0; k < n; k++) {
            double a = 2 * PI * k / n, r = shape ? (k % 4 < 2 ? 1 : 0.6) : (k % 2 ? 0.3 : 1);
            vec p = v3(r * cos(a), 0.5, r * sin(a));            /* in the plane y = 0.5 */
            vi[k] = add_vertex(&s, p);
        }
        for (k = 0; k < n; k++) {                                /* shoelace in x-z */
            vec a = s.vert[vi[k]], b = s.vert[vi[(k + 1) % n]];
            area += 0.5 * (a.z * b.x - a.x * b.z);
        }
        triangulate((scene_builder[]){ builder(&s) }, vi, NULL, n, 0);
        for (k = 0; k < s.ntri; k++) sum += tri_area(&s, k);
        report(s.ntri == n - 2 && near(sum, fabs(area), 1e-12 * fabs(area)),
               shape ? "ear clipping a 40-gon comb: n-2 triangles, area exact" :
                       "ear clipping a 16-point star: n-2 triangles, area exact",
               "area of triangles %.15g, polygon %.15g", sum, fabs(area));
        free_scene(&s);
    }
}

/* A convex 4000-gon: n-2 triangles, the area exact, and no fan: no vertex
 * in more than a few dozen triangles (a fan puts all 3998 at one corner,
 * and a kd-tree over that takes minutes and gigabytes). */
static void test_convex_polygon(void)
{
    Scene s = tri_scene(0);
    int n = 4000, k, *vi = malloc(sizeof *vi * n), *uses = calloc(n, sizeof *uses), most = 0;
    double sum = 0, area = 0.5 * n * sin(2 * PI / n);
    for (k = 0; k < n; k++) vi[k] = add_vertex(&s, v3(cos(2 * PI * k / n), sin(2 * PI * k / n), 0));
    triangulate((scene_builder[]){ builder(&s) }, vi, NULL, n, 0);
    for (k = 0; k < s.ntri; k++) {
        int j;
        sum += tri_area(&s, k);
        for (j = 0; j < 3; j++) if (++uses[s.tri[k].v[j]] > most) most = uses[s.tri[k].v[j]];
    }
    report(s.ntri == n - 2 && near(sum, area, 1e-12 * area) && most <= 2 * 12 + 2,
           "a convex 4000-gon: n-2 triangles, exact area, no fan", "%g triangles at the busiest vertex, area error %.3g",
           most, fabs(sum - area));
    free(vi);
    free(uses);
    free_scene(&s);
}

/* NFF: the view angle spans the centres of the outer pixel columns. */
static void test_nff_view(void)
{
    Scene s;
    const char *f = write_tmp("view.nff",
        "v\nfrom 0 -10 0\nat 0 0 0\nup 0 0 1\nangle 40\nhither 1\nresolution 64 48\n"
        "l 1 2 3\nl 4 5 6 .5 .5 .5\nf 1 0 0 1 0 0 0 0\np 3\n0 0 0\n1 0 0\n0 0 1\n"
        "pp 3\n0 0 0 0 -1 0\n1 0 0 0 -1 0\n0 0 1 0 -1 0\ns 0 0 0 1\nc 0 0 0 1 0 0 2 0\n");
    Ray a, b;
    double angle;
    if (!load_or_fail(&s, f, "NFF: a scene of every entity loads")) return;
    a = camera_ray(&s.cam, s.set.w, s.set.h, 0.5, 24);
    b = camera_ray(&s.cam, s.set.w, s.set.h, 63.5, 24);
    angle = acos(dot(a.d, b.d)) * 180 / PI;
    report(s.set.w == 64 && s.set.h == 48 && near(angle, 40, 1e-9),
           "NFF angle spans the outer pixel centres", "%.12g deg, want %g", angle, 40);
    report(s.nlight == 2 && near(s.light[1].color.x, .5 * sqrt(2) / 4, 1e-15)
           && near(s.ambient.x, sqrt(2) / 4, 1e-15),
           "NFF lights: optional colour, strength sqrt(L)/2L", "light %.15g ambient %.15g",
           s.nlight == 2 ? s.light[1].color.x : NAN, s.ambient.x);
    report(s.nsph == 1 && s.ncone == 1 && s.ntri == 2 && s.tri[1].n[0] >= 0,
           "NFF p, pp (with normals), s and c", "triangles %g, spheres %g", s.ntri, s.nsph);
    free_scene(&s);
}

/* OBJ: n-gons, negative indices, normals, and statements it skips. */
static void test_obj(void)
{
    Scene s;
    const char *obj = write_tmp("quad.obj",
        "# a quad and a triangle\nmtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
        "vn 0 0 1\nvt 0 0\nusemtl red\nf 1//1 2//1 3//1 4//1\nf -4 -3 -1\n");
    const char *sph = write_tmp("mesh.sph", "mesh quad.obj 1 1 1 1 0 0 0 1\n");
    (void)obj;
    if (!load_or_fail(&s, sph, "OBJ: a mesh line loads")) return;
    report(s.ntri == 3 && s.nvert == 4 && s.tri[0].n[0] == 0 && s.tri[2].n[0] < 0
           && s.tri[2].v[2] == 3,
           "OBJ: a quad with normals, negative indices, a mesh line", "triangles %g, vertices %g",
           s.ntri, s.nvert);
    free_scene(&s);
}

/* Open cones and cylinders against answers worked out by hand. */
static void test_cones(void)
{
    Cone cyl, cone;
    vec n;
    double t1, t2, t3, t4, t5, t6;
    cyl.base = v3(0, 0, 0); cyl.axis = v3(0, 0, 1); cyl.len = 2; cyl.rb = cyl.ra = 1;
    cone = cyl; cone.len = 1; cone.ra = 0;                       /* apex at z = 1 */
    t1 = hit_cone(&cyl, rp(v3(5, 0, 1), v3(-1, 0, 0)), 0);      /* from outside: 4 */
    t2 = hit_cone(&cyl, rp(v3(0, 0, 1), v3(0, 1, 0)), 0);       /* from inside: 1 */
    t3 = hit_cone(&cyl, rp(v3(5, 0, 3), v3(-1, 0, 0)), 0);      /* above its end: miss */
    t4 = hit_cone(&cyl, rp(v3(0.5, 0, -1), v3(0, 0, 1)), 0);    /* along the axis, open ends: miss */
    t5 = hit_cone(&cone, rp(v3(5, 0, 0.5), v3(-1, 0, 0)), 0);   /* radius 0.5 there: 4.5 */
    t6 = hit_cone(&cone, rp(v3(3, 0, 1.5), v3(-1, 0, 0)), 0);   /* beyond the apex: miss */
    report(t1 == 4 && t2 == 1 && isinf(t3) && isinf(t4), "cylinder: outside, inside, past the end, along the axis",
           "t = %g and %g", t1, t2);
    report(near(t5, 4.5, 1e-15) && isinf(t6), "cone: the radius shrinks to the apex, and stops there",
           "t = %.17g, beyond the apex %g", t5, t6);
    {   /* far away: a unit cylinder at 1e4 .. 1e8, aimed across it off centre */
        double d, worst = 0;
        for (d = 1e4; d <= 1e8; d *= 10) {
            Cone far = cyl;
            double t;
            far.base = v3(0, d, 0);
            t = hit_cone(&far, rp(v3(0, 0, 1), unit(v3(0.6, d, 0))), 0);
            /* exact: the line x = 0.6 y / d meets x^2 + (y - d)^2 = 1 */
            {
                long double k = 0.6L / d, A = 1 + k * k, B = -2.0L * d, C = (long double)d * d - 1;
                long double y = (-B - sqrtl(B * B - 4 * A * C)) / (2 * A);
                long double te = sqrtl(y * y + (k * y) * (k * y));
                if (!(fabs(t - (double)te) / d <= worst)) worst = fabs(t - (double)te) / d;
            }
        }
        report(worst <= 1e-9, "cylinder far away (1e4..1e8): |t - t_exact| <= 1e-9 * distance",
               "worst relative error %.3g, allowed %g", worst, 1e-9);
    }
    n = cone_normal(&cone, v3(0.5, 0, 0.5));
    report(near(n.x, sqrt(0.5), 1e-15) && near(n.z, sqrt(0.5), 1e-15) && n.y == 0,
           "cone normal tilts with the slope", "n = (%.17g, ., %.17g)", n.x, n.z);
}

/* No NaN or infinity ever reaches a pixel: trace() itself is checked,
 * since to_byte() would quietly turn a NaN into black.  The scenes include
 * the awkward cases: the eye inside glass, zero vertex normals, a glass of
 * index 1, grazing cones, every kind of object. */
static void test_no_nan(void)
{
    static const char *const files[] = { "scenes/minray.sph", "scenes/whitted.sph",
                                         "scenes/mesh.sph", "scenes/demo.nff", NULL };
    const char *odd = write_tmp("odd.nff",
        "v\nfrom 0 0 0\nat 0 1 0\nup 0 0 1\nangle 90\nhither 1\nresolution 32 32\nl 0 0 0\n"
        "f 1 1 1 .2 .4 5 .8 1\ns 0 0 0 3\ns 0 2 0 .5\nf 1 1 1 .5 .5 10 .5 1.5\n"
        "pp 3\n-1 2 -1 0 0 0\n1 2 -1 0 0 0\n0 2 1 0 0 0\nc 0 2.5 -2 1 0 2.5 2 0\n");
    int f, bad = 0, pixels = 0;
    for (f = 0; f < 5; f++) {
        Scene s;
        Worker wk;
        int i, j, W = 48;
        memset(&wk, 0, sizeof wk);
        if (!load_or_fail(&s, files[f] ? files[f] : odd, "no NaN: the scene loads")) { bad++; continue; }
        build_accel(&s, "auto");
        for (j = 0; j < W; j++)
            for (i = 0; i < W; i++) {
                vec c = trace(&s, camera_ray(&s.cam, W, W, i + 0.5, j + 0.5), s.set.depth, 1, &wk);
                bad += !isfinite(c.x) || !isfinite(c.y) || !isfinite(c.z);
                pixels++;
            }
        free_scene(&s);
    }
    report(bad == 0, "no NaN or infinity from trace() in five scenes, odd cases included",
           "%g bad of %g pixels", bad, pixels);
}

static void test_camera(void)
{
    Scene s;
    Ray c, e;
    double angle;
    real v[10] = { 0, 0, 0, 0, 1, 0, 0, 0, 1, 60 };
    default_scene(&s);
    set_camera(&s, v, (char[SCENE_WHY]){ 0 });
    c = camera_ray(&s.cam, 640, 480, 320, 240);
    e = camera_ray(&s.cam, 640, 480, 0, 240);
    angle = acos(dot(c.d, e.d)) * 180 / PI;
    report(near(c.d.y, 1, 1e-15), "the image centre looks along the view", "d.y=%.17g want %g", c.d.y, 1);
    report(near(angle, 30, 1e-12), "the left edge is half the field of view away",
           "%.15g deg, want %g", angle, 30);
}

/* smallpt starts its rays 140 along each unit direction from the eye
 * (`hither 140 sphere`), not on a plane 140 along the view: every ray's
 * near clip is 140, the image's corner ray clipped as much as its centre.
 * With the plane, the top row of scenes/smallpt.sph reaches the lamp
 * (which pokes through the ceiling), which smallpt never shows there. */
static void test_hither_sphere(void)
{
    Scene s;
    Worker wk;
    Hit h;
    int x, W = 1024, H = 768, lamp = 0, off = 0;
    memset(&wk, 0, sizeof wk);
    if (!load_or_fail(&s, "scenes/smallpt.sph", "hither 140 sphere")) return;
    build_accel(&s, "kd");
    for (x = 0; x < W; x++) {
        Ray r = camera_ray(&s.cam, W, H, x + (real)0.5, (real)0.5);
        off += r.tmin != 140;
        if (nearest_hit(&s, r, &h, &wk)) lamp += s.mat[h.mat].kl > 0;
    }
    report(off == 0 && lamp == 0, "hither 140 sphere (smallpt's): each ray clipped at 140, the top row sees no lamp",
           "%g rays clipped elsewhere, %g see the lamp", off, lamp);
    s.cam.hither_sphere = 0;
    for (lamp = 0, x = 0; x < W; x++) {
        Ray r = camera_ray(&s.cam, W, H, x + (real)0.5, (real)0.5);
        if (nearest_hit(&s, r, &h, &wk)) lamp += s.mat[h.mat].kl > 0;
    }
    report(lamp > W / 2, "hither 140 as a plane: the top row sees the lamp", "%g of %g pixels", lamp, W);
    free_scene(&s);
}

/* Does a ray spawned at h towards dir hit h's own object again?  Shadow
 * rays skip the surface they leave when it is flat or they leave a sphere
 * outward, so the acne tests below ask this too, with the skip switched off:
 * the origin's offset alone must keep the ray clear. */
static int self_hit(const Scene *s, const Hit *h, vec dir)
{
    Ray r = spawn(s, h, dir);
    real t;
    r.skip = -1;
    return hit_object(s, h->obj, &r, INFINITY, &t);
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
    Light *l;
    int i, j, wrong = 0, W = 96;
    Worker wk;
    real v[10];
    memset(&wk, 0, sizeof wk);
    s = tri_scene(0);                   /* a scene with one white material */
    add_sphere(&s, v3(0, 0, -1e4 * k), 1e4 * k, 0);
    add_sphere(&s, v3(0, 0, k), k, 0);
    add_light(&s, v3(2 * k, -1 * k, 6 * k), v3(1, 1, 1), -1);
    l = &s.light[0];
    v[0] = 0; v[1] = -8 * k; v[2] = 5 * k; v[3] = 0; v[4] = 0; v[5] = 0;
    v[6] = 0; v[7] = 0; v[8] = 1; v[9] = 50;
    set_camera(&s, v, (char[SCENE_WHY]){ 0 });
    *counted = 0;
    for (j = 0; j < W; j++)
        for (i = 0; i < W; i++) {
            Hit h;
            real e;
            vec to_l, oc, ld;
            double b, dist2, len;
            int lit, truth;
            if (!nearest_hit(&s, camera_ray(&s.cam, W, W, i + 0.5, j + 0.5), &h, &wk)) continue;
            lit = shadow_ray(&s, &h, h.n, l, -1, &e, &ld, &wk);
            if (!(e > 1e-6)) continue;     /* grazing or facing away */
            /* exact: does the segment from the point to the light pass
             * through the ball (if the point is on the ground), in units of k */
            to_l = unit(sub(l->pos, h.p));
            oc = sub(s.sph[1].cen, h.p);
            b = dot(oc, to_l);
            dist2 = dot(oc, oc) - b * b;
            len = sqrt(dot(sub(l->pos, h.p), sub(l->pos, h.p)));
            truth = 1;
            if (h.obj == 0 && b > 0 && b < len) {
                if (fabs(sqrt(dist2) / k - 1) < 1e-6) continue;   /* on the shadow's edge */
                truth = dist2 > k * k;
            }
            ++*counted;
            wrong += lit != truth || self_hit(&s, &h, to_l);
        }
    free_scene(&s);
    return wrong;
}

/* A cylinder (seen from the side, so its open ends stay hidden) or a
 * triangle, alone with a light on the camera's side, everything times k and
 * the camera `far` units away: no part of it can shadow another, so every
 * point whose normal faces the light must be lit. */
static int lone_acne(int cylinder, double k, double far, int *counted)
{
    Scene s;
    Worker wk;
    real v[10];
    int i, j, wrong = 0, W = 64;
    memset(&wk, 0, sizeof wk);
    s = tri_scene(0);
    if (cylinder) add_cone(&s, v3(0, 0, -k), k, v3(0, 0, k), k, 0);
    else {
        int a = add_vertex(&s, v3(-k, 0, -k)), b = add_vertex(&s, v3(k, 0.3 * k, -k));
        add_triangle(&s, a, b, add_vertex(&s, v3(0, -0.2 * k, k)), -1, -1, -1, 0);
    }
    add_light(&s, v3(0.5 * far * k, -far * k, 0.3 * far * k), v3(1, 1, 1), -1);
    v[0] = 0; v[1] = -far * k; v[2] = 0; v[3] = 0; v[4] = 0; v[5] = 0;
    v[6] = 0; v[7] = 0; v[8] = 1; v[9] = 2 * atan(1.5 / far) * 180 / PI;
    set_camera(&s, v, (char[SCENE_WHY]){ 0 });
    *counted = 0;
    for (j = 0; j < W; j++)
        for (i = 0; i < W; i++) {
            Hit h;
            real e;
            vec ld;
            int lit;
            if (!nearest_hit(&s, camera_ray(&s.cam, W, W, i + 0.5, j + 0.5), &h, &wk)) continue;
            lit = shadow_ray(&s, &h, dot(h.n, v3(0, -1, 0)) > 0 ? h.n : scale(-1, h.n), &s.light[0], -1, &e, &ld, &wk);
            if (!(e > 1e-6)) continue;
            ++*counted;
            wrong += !lit || self_hit(&s, &h, unit(sub(s.light[0].pos, h.p)));
        }
    free_scene(&s);
    return wrong;
}

static void test_acne(void)
{
    double k, far;
    int cyl;
    for (cyl = 0; cyl < 2; cyl++)
        for (far = 10; far <= 1e4; far *= 1000) {
            int counted = 0, wrong = 0, c;
            for (k = 1e-3; k <= 1e5 * 1.001; k *= 10) {
                wrong += lone_acne(cyl, k, far, &c);
                counted += c;
            }
            {
                char name[96];
                sprintf(name, "no acne on a lone %s, scales 1e-3..1e5, camera %g sizes away",
                        cyl ? "cylinder" : "triangle", far);
                report(wrong == 0 && counted > 9 * 500, name, "%g wrongly shadowed of %g lit-side pixels",
                       wrong, counted);
            }
        }
    for (k = 1e-3; k <= 1e5 * 1.001; k *= 10) {
        int counted, wrong = acne_at_scale(k, &counted);
        char name[80];
        sprintf(name, "no acne: plane and ball at scale %g", k);
        report(wrong == 0 && counted > 3000, name, "%g wrongly shadowed of %g lit-side pixels", wrong, counted);
    }
}

/* area_light_bound against what area_lights estimates, at points near
 * each lamp and far from it: the mean of 4000 of its samples (on a white
 * kd 1 surface, nothing in the way) may not exceed the bound by more than
 * 4 standard errors. */
static int area_bounds_hold(const Scene *s, const char *file)
{
    Material white;
    unsigned long long x = 9;
    double worst = -1e9;
    int l, k, q, tried = 0;
    memset(&white, 0, sizeof white);
    white.color = v3(1, 1, 1), white.kd = 1;
    for (l = 0; l < s->lights.nemit; l++) {
        const LightNode *leaf = &s->lights.node[s->lights.leaf[l]];
        if (s->lights.emit[l].type != SPHERE_LIGHT && s->lights.emit[l].type != TRIANGLE_LIGHT) continue;
        for (k = 0; k < 8; k++) {
            double r = sqrt(leaf->r2) * (k < 4 ? 1.05 + k * 0.5 : 4 << k), sum = 0, sq = 0, mean, se;
            vec d = unit(v3(rnd(&x) - .5, rnd(&x) - .5, rnd(&x) - .5)), p = comb(r, d, leaf->centre);
            vec n = unit(comb(-1, d, v3(0.3 * (rnd(&x) - .5), 0.3 * (rnd(&x) - .5), 0.3 * (rnd(&x) - .5))));
            for (q = 0; q < 4000; q++) {
                vec wi, Le;
                real dist, pdf, e;
                double v = 0;
                sample_emitter(s, l, p, n, 0, (real)rnd(&x), (real)rnd(&x), &wi, &dist, &Le, &pdf);
                e = dot(n, wi);
                if (pdf > 0 && e > 0) v = e * fmax(Le.x, fmax(Le.y, Le.z)) / (PI * pdf);
                sum += v, sq += v * v;
            }
            mean = sum / 4000, se = sqrt(fmax(0, sq / 4000 - mean * mean) / 4000);
            worst = fmax(worst, (mean - area_light_bound(s, &white, l, p)) / (se > 0 ? se : 1e-300));
            tried++;
        }
    }
    if (tried == 0) return 1;                           /* point lights only */
    printf("%s area_light_bound holds: area_lights' estimate from near and far never above it (%s: worst %.2f"
           " standard errors above, of %d points)\n", worst < 4 ? "PASS" : "FAIL",
           strrchr(file, '/') ? strrchr(file, '/') + 1 : file, worst, tried);
    return worst < 4;
}

/* The dim lights' cull (too_dim): at every pixel of four scenes (point
 * lights, a glowing sphere, 100 of them, a lamp of triangles), the
 * primary ray traced with the cull and without differs by no more than
 * a sample may leave out (a quarter of an 8-bit step), and only ever
 * darker; and the cull fires, so the check is not empty. */
static void test_dim_lights(const char *file)
{
    Scene s;
    Worker wk;
    double worst = 0, brighter = 0;
    unsigned long long culled = 0;
    int i, j, w = 64, h = 48, ok;
    if (!load_or_fail(&s, file, "the dim lights' cull")) return;
    s.set.w = w, s.set.h = h;
    if (!settle_path_options(&s, WHITTED, -1, 1, 0) || !build_accel(&s, "bvh")) {
        printf("FAIL the dim lights' cull (%s: cannot prepare)\n", file);
        failures++;
        return;
    }
    memset(&wk, 0, sizeof wk);
    for (j = 0; j < h; j++)
        for (i = 0; i < w; i++) {
            Ray r = primary_ray(&s, i + (real)0.5, j + (real)0.5, &wk);
            vec with, without;
            unsigned long long before = wk.count.dim;
            wk.budget = RAY_BUDGET, wk.dim_budget = dim_budget(&s);
            with = trace(&s, r, s.set.depth, 1, &wk);
            culled += wk.count.dim - before;
            wk.budget = RAY_BUDGET, wk.dim_budget = -1;          /* nothing is within -1 */
            without = trace(&s, r, s.set.depth, 1, &wk);
            worst = fmax(worst, fmax(without.x - with.x, fmax(without.y - with.y, without.z - with.z)));
            brighter = fmax(brighter, fmax(with.x - without.x, fmax(with.y - without.y, with.z - without.z)));
        }
    ok = culled > 0 && worst <= 0.25 / 255 * (1 + 1e-9) && brighter <= 1e-12;
    if (s.lights.nemit > 0) ok &= area_bounds_hold(&s, file);
    printf("%s the dim lights' cull leaves out at most a quarter step of a pixel, and only darkens (%s: %llu shadow"
           " rays not sent, worst %.3g of a step darker, %.2g brighter)\n", ok ? "PASS" : "FAIL",
           strrchr(file, '/') ? strrchr(file, '/') + 1 : file, culled,
           worst * 255, brighter * 255);
    failures += !ok;
    free_scene(&s);
}

/* The same for lamps of triangles: a mirror ball and a floor under a
 * row of small, dim, two-sided triangles, far and near. */
static void test_dim_triangles(void)
{
    char name[4200];
    FILE *f;
    int k;
    sprintf(name, "%.4000s/dim_triangles.sph", getenv("TMP") ? getenv("TMP") : ".");
    if (!(f = fopen(name, "w"))) { printf("FAIL the dim lights' cull (cannot write %s)\n", name); failures++; return; }
    fprintf(f, "size 64 48\ndepth 4\ncamera 0 -8 3  0 0 1  0 0 1  50\nlight 3 -4 6  .5 .5 .5\n"
               "tri -9 -9 0  9 -9 0  9 9 0  .8 .8 .8 .7 .3 0 0 1\ntri -9 -9 0  9 9 0  -9 9 0  .8 .8 .8 .7 .3 0 0 1\n"
               "0 0 1  1 1 1  1  0 .9 0 0 1\n");
    for (k = 0; k < 30; k++)
        fprintf(f, "tri %d 8 %d  %d.2 8 %d  %d 8 %d.2  1 1 1 0 0 0 %g 1\n", k - 15, 1 + k % 5, k - 15, 1 + k % 5,
                k - 15, 1 + k % 5, 0.02 + 0.02 * (k % 7));
    fclose(f);
    test_dim_lights(name);
    remove(name);
}

int main(void)
{
    if (sizeof(real) == sizeof(float)) {   /* what the float build must keep */
        test_triangle_scales();
        test_triangle_degenerate();
        test_triangle_culling();
        test_watertight(1, 0);
        test_watertight(0, 0);
        test_watertight(1, 1e4);
        test_watertight(0, 1e4);
        test_tree_matches_loop("kd", 300000);
        return failures != 0;
    }
    test_vectors();
    test_sphere_far();
    test_sphere_tiny();
    test_sphere_inside_and_miss();
    test_refraction();
    test_camera();
    test_hither_sphere();
    test_no_nan();
    test_triangle_scales();
    test_triangle_degenerate();
    test_triangle_culling();
    test_cones();
    test_ear_clipping();
    test_convex_polygon();
    test_nff_view();
    test_obj();
    test_watertight(1, 0);
    test_watertight(0, 0);
    test_watertight(1, 1e4);
    test_sphere_clip();
    test_hit_contract();
    test_tree_matches_loop("kd", 1000000);
    test_tree_matches_loop("bvh", 300000);
    test_tree_matches_loop("grid", 300000);
    test_tree_image("kd");
    test_tree_image("bvh");
    test_tree_image("grid");
    test_tir();
    test_budget();
    test_dim_lights("scenes/whitted.sph");
    test_dim_lights("scenes/demo.nff");
    test_dim_lights("scenes/lights100.sph");
    test_dim_triangles();
    test_float_range();
    test_light_under_ceiling();
    test_acne();
    return failures != 0;
}

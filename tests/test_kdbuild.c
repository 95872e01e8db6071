/* test_kdbuild.c - the kd-tree's build on the inputs that made it blow up,
 * and ray.c's ear clipper, which made such inputs out of concave polygons.
 *
 *     test_kdbuild fan|polygon|ears|memory
 *
 *   fan      fans of 5000, 20000 (in a tilted plane) and 50000 thin
 *            triangles meeting at one point, the kd-tree's worst case.  The
 *            tree keeps within the build's budget, references + leaves <=
 *            16 (N + 1) (kdtree.c's BUDGET), and what kdtree.c holds at its
 *            peak stays under 1000 bytes a triangle, 50 MB for the 50k fan.
 *            Before the budget the 5000 fan alone made 1.2M nodes and 3.8M
 *            references.  The build's CPU time is printed and bounded only
 *            loosely (10 s; the aim is under 1 s).
 *   polygon  NFF scenes written here and read by ray.c's reader: an
 *            8000-gon with one corner dented (7998 triangles, no vertex in
 *            more than 2 log2 n + 2 of them, a tree of at most 6 (N + 1)
 *            references and leaves; the old clipper made a fan of all 7998
 *            at one corner), and a 2000-gon whose only triangulation is a
 *            fan (every corner but one a dent facing that one), where the
 *            budget must hold.
 *   ears     ear clipping: stars, combs, dented and random concave polygons,
 *            spirals and teeth on a bar, of 10 to 8000 corners, give n - 2
 *            triangles, each turning the polygon's way, that cover its area
 *            exactly; in the first four no vertex is in more than 2 log2 n + 2
 *            of them (3 log2 n for the random ones).
 *   memory   a 49k-triangle cube-sphere: kdtree.c holds at most 128 bytes a
 *            triangle at its peak (the old build: 170), and bvh.c at most
 *            120 (140 while its build's records were kept until the
 *            four-way tree was made).
 *
 * On every scene with a tree, rays of many kinds (aimed anywhere, at the
 * point where the fan's triangles meet, at vertices, along an axis, in the
 * plane, from either side) must find through the tree exactly what the loop
 * over all objects finds: the same object, bit for bit the same t.
 *
 * kdtree.c and bvh.c are compiled for this test with malloc, calloc, realloc
 * and free renamed kdb_malloc, kdb_calloc, kdb_realloc and kdb_free
 * (tests/kdbuild.test.sh), and these
 * count the bytes it holds, room it asked for but has not used included:
 * the same count on every run, unlike the process's resident memory.
 * Prints "PASS ..." or "FAIL ..." lines and exits 1 if a check failed. */
#define main ray_main
#include "../ray.c"
#undef main

void *kdb_malloc(size_t n);
void *kdb_calloc(size_t count, size_t size);
void *kdb_realloc(void *p, size_t n);
void kdb_free(void *p);

/* ---- counting kdtree.c's memory ---- */

/* A block's size, kept before it; a union, so that what follows is aligned
 * for any type. */
typedef union { size_t n; long double align_ld; void *align_p; } Header;

static size_t held, peak;

void *kdb_malloc(size_t n)
{
    Header *h = malloc(sizeof *h + n);
    if (!h) return NULL;
    h->n = n;
    held += n;
    if (held > peak) peak = held;
    return h + 1;
}

/* Counted whole, though the system maps the pages of a big zeroed block
 * only as they are written: a bound on what is resident. */
void *kdb_calloc(size_t count, size_t size)
{
    void *p;
    if (size && count > (size_t)-1 / size) return NULL;
    p = kdb_malloc(count * size);
    if (p) memset(p, 0, count * size);
    return p;
}

void kdb_free(void *p)
{
    Header *h = p ? (Header *)p - 1 : NULL;
    if (!h) return;
    held -= h->n;
    free(h);
}

void *kdb_realloc(void *p, size_t n)
{
    Header *h;
    size_t old;
    if (!p) return kdb_malloc(n);
    h = (Header *)p - 1;
    old = h->n;
    h = realloc(h, sizeof *h + n);
    if (!h) return NULL;
    h->n = n;
    held = held - old + n;
    if (held > peak) peak = held;
    return h + 1;
}

/* ---- helpers ---- */

static int failures;

static void report(int ok, const char *name, const char *detail)
{
    printf("%s %s (%s)\n", ok ? "PASS" : "FAIL", name, detail);
    fflush(stdout);
    failures += !ok;
}

static unsigned long long rng = 0x9E3779B97F4A7C15ull;

static double unif(double a, double b)   /* xorshift64*: the same rays on every run */
{
    rng ^= rng >> 12, rng ^= rng << 25, rng ^= rng >> 27;
    return a + (b - a) * (double)((rng * 2685821657736338717ull) >> 11) / 9007199254740992.0;
}

static Scene white_scene(void)
{
    Scene s;
    Material m;
    memset(&m, 0, sizeof m);
    m.color = v3(1, 1, 1);
    m.kd = m.ir = 1;
    default_scene(&s);
    add_material(&s, m);
    return s;
}

/* The plane the test's figures lie in: x u + y v, normal n (z). */
typedef struct { vec u, v, n; } Frame;

static vec at(const Frame *f, double x, double y, double z)
{
    return add(add(scale(x, f->u), scale(y, f->v)), scale(z, f->n));
}

static const Frame flat = { { 1, 0, 0 }, { 0, 1, 0 }, { 0, 0, 1 } };

static Frame tilted(void)
{
    Frame f;
    f.n = unit(v3(1, 2, 3));
    f.u = unit(cross(f.n, v3(0, 0, 1)));
    f.v = cross(f.n, f.u);
    return f;
}

/* The most triangles that share one vertex. */
static int busiest_vertex(const Scene *s)
{
    int *uses = calloc((size_t)s->nvert + 1, sizeof *uses), k, j, most = 0;
    if (!uses) exit(2);
    for (k = 0; k < s->ntri; k++)
        for (j = 0; j < 3; j++)
            if (++uses[s->tri[k].v[j]] > most) most = uses[s->tri[k].v[j]];
    free(uses);
    return most;
}

/* Ray number k at a figure of radius about 1 around the origin of f, from
 * either side; `spots` are points worth aiming at (the fan's apex,
 * vertices). */
static Ray make_ray(const Frame *f, long k, const vec *spots, int nspots)
{
    Ray r;
    double a = unif(0, 2 * PI), rad = sqrt(unif(0, 1)), side = k / 6 % 2 ? 1 : -1;
    vec target = at(f, rad * cos(a), rad * sin(a), 0);
    r.skip = -1, r.tmin = 0, r.time = 0;
    r.o = at(f, unif(-2, 2), unif(-2, 2), side * unif(0.1, 2));
    switch (k % 6) {
    case 1: target = at(f, 1e-3 * rad * cos(a), 1e-3 * rad * sin(a), 0); break;  /* the apex */
    case 2: target = spots[(long)unif(0, nspots) % nspots]; break;              /* a vertex */
    case 3: r.o = v3(target.x, target.y, 2 * side), r.d = v3(0, 0, -side);      /* along z */
        return r;
    case 4:  /* in the plane, when it holds exactly: a ray merely within rounding
              * of a triangle's plane gets a t of rounding noise, whose point can
              * lie anywhere along it, outside the cells that list the triangle
              * (prims.h; a tilted fan of slivers: 1 such ray in 10 differs) */
        if (f == &flat) r.o = at(f, unif(-2, 2), unif(-2, 2), 0);
        break;
    }
    r.d = unit(sub(target, r.o));
    return r;
}

/* Rays through the tree and through the loop: how many differ in the object
 * hit or in t (bit for bit). */
static long tree_vs_loop(Scene *s, const Frame *f, long n, const vec *spots, int nspots, long *hits)
{
    Worker wk;
    long k, wrong = 0;
    memset(&wk, 0, sizeof wk);
    *hits = 0;
    for (k = 0; k < n; k++) {
        Ray r = make_ray(f, k, spots, nspots);
        Hit a, b;
        int ha, hb;
        s->accel.which = ACCEL_KD;
        ha = nearest_hit(s, r, &a, &wk);
        s->accel.which = ACCEL_NONE;
        hb = nearest_hit(s, r, &b, &wk);
        s->accel.which = ACCEL_KD;
        *hits += hb;
        if (ha != hb || (ha && (a.obj != b.obj || memcmp(&a.t, &b.t, sizeof a.t))))
            wrong++;
    }
    return wrong;
}

/* Builds the tree of s, counting kdtree.c's bytes: the peak in *bytes. */
static int build(Scene *s, kd_info *k, size_t *bytes)
{
    held = peak = 0;
    if (!build_accel(s, "kd") || !s->accel.kd) return 0;
    kd_describe(s->accel.kd, k);
    *bytes = peak;
    return 1;
}

/* ---- fans ---- */

static int test_fan(int n, const Frame *f, long nrays)
{
    Scene s = white_scene();
    kd_info k;
    size_t bytes;
    double bound = 16.0 * (n + 1);
    char msg[400];
    vec spots[3];
    long wrong, hits;
    int i, c = add_vertex(&s, at(f, 0, 0, 0)), ok;
    for (i = 0; i <= n; i++) add_vertex(&s, at(f, cos(2 * PI * i / n), sin(2 * PI * i / n), 0));
    for (i = 0; i < n; i++) add_triangle(&s, c, c + 1 + i, c + 2 + i, -1, -1, -1, 0);
    if (!build(&s, &k, &bytes)) {
        report(0, "fan: kd_build", "returned NULL");
        return 0;
    }
    ok = k.prim_refs + k.leaves <= bound && k.nodes < 2 * bound
         && bytes <= 1000.0 * n && k.build_seconds < 10;
    sprintf(msg, "%d triangles%s: %ld nodes, %ld references, %ld leaves: refs + leaves = "
            "%.2f (N + 1) (bound 16), peak %.1f MB held by kdtree.c (bound %.0f MB), built in "
            "%.2f s CPU", n, f == &flat ? "" : " in a tilted plane", k.nodes, k.prim_refs, k.leaves,
            (k.prim_refs + k.leaves) / (n + 1.0), bytes / 1e6, n * 1000 / 1e6, k.build_seconds);
    report(ok, "fan: the tree within its budget, memory linear", msg);
    spots[0] = at(f, 0, 0, 0), spots[1] = s.vert[c + 1], spots[2] = s.vert[c + 1 + n / 3];
    wrong = tree_vs_loop(&s, f, nrays, spots, 3, &hits);
    sprintf(msg, "%d triangles, %ld rays (%ld hit): %ld differ", n, nrays, hits, wrong);
    report(wrong == 0, "fan: tree = loop, same object and t", msg);
    free_scene(&s);
    return ok;
}

/* ---- polygons through the NFF reader ---- */

static const char *write_tmp(const char *name)
{
    static char path[512];
    const char *dir = getenv("TMP") ? getenv("TMP") : "/tmp";
    sprintf(path, "%.400s/%s", dir, name);
    return path;
}

/* An NFF scene of one polygon, corners (x[k], y[k], 0). */
static const char *write_polygon(const char *name, const double *x, const double *y, int n)
{
    const char *path = write_tmp(name);
    FILE *fp = fopen(path, "w");
    int k;
    if (!fp) exit(2);
    fprintf(fp, "v\nfrom 0 0 3\nat 0 0 0\nup 0 1 0\nangle 45\nhither 0\nresolution 32 32\n"
                "b 0 0 0\nl 0 0 5\nf 1 1 1 1 0 0 0 1\np %d\n", n);
    for (k = 0; k < n; k++) fprintf(fp, "%.17g %.17g 0\n", x[k], y[k]);
    fclose(fp);
    return path;
}

static void test_nff_polygon(const char *what, const double *x, const double *y, int n,
                             double most_allowed, double refs_allowed, long nrays)
{
    Scene s;
    kd_info k;
    size_t bytes;
    char msg[400], name[300];
    vec spots[3];
    long wrong, hits;
    int most, ok, j;
    double area = 0, sum = 0;
    sprintf(name, "%s: read, triangulated and built", what);
    if (!load_scene(&s, write_polygon("kdbuild.nff", x, y, n)) || !build(&s, &k, &bytes)) {
        report(0, name, "failed");
        return;
    }
    most = busiest_vertex(&s);
    for (j = 0; j < n; j++) area += 0.5 * (x[j] * y[(j + 1) % n] - y[j] * x[(j + 1) % n]);
    for (j = 0; j < s.ntri; j++) sum += 0.5 * fabs(cross(s.tri[j].e1, s.tri[j].e2).z);
    ok = s.ntri == n - 2 && fabs(sum - area) <= 1e-9 * area && most <= most_allowed
         && k.prim_refs + k.leaves <= refs_allowed * (s.ntri + 1);
    sprintf(msg, "%d corners: %d triangles covering %.12f of its area, busiest vertex in %d "
            "(bound %.0f); tree %ld nodes, %ld references: refs + leaves = %.2f (N + 1) (bound "
            "%.0f), built in %.3f s CPU", n, s.ntri, sum / area, most, most_allowed, k.nodes, k.prim_refs,
            (k.prim_refs + k.leaves) / (s.ntri + 1.0), refs_allowed, k.build_seconds);
    report(ok, name, msg);
    spots[0] = s.vert[0], spots[1] = s.vert[1], spots[2] = v3(x[0], y[0], 0);
    wrong = tree_vs_loop(&s, &flat, nrays, spots, 3, &hits);
    sprintf(name, "%s: tree = loop, same object and t", what);
    sprintf(msg, "%ld rays (%ld hit): %ld differ", nrays, hits, wrong);
    report(wrong == 0, name, msg);
    free_scene(&s);
}

static void test_polygons(void)
{
    int n = 8000, k;
    double *x = malloc(sizeof *x * n), *y = malloc(sizeof *y * n);
    if (!x || !y) exit(2);
    for (k = 0; k < n; k++) {
        double r = k == 0 ? 0.5 : 1;
        x[k] = r * cos(2 * PI * k / n), y[k] = r * sin(2 * PI * k / n);
    }
    test_nff_polygon("a dented 8000-gon", x, y, n, 2 * log2(n) + 2, 6, 8000);
    /* Corner 0 at the origin, the others on the parabola y = 1 + x^2 / 2,
     * which bends towards it: every diagonal but those from corner 0 runs
     * outside, so the fan from corner 0 is the only triangulation. */
    n = 2000;
    x[0] = y[0] = 0;
    for (k = 1; k < n; k++) {
        x[k] = 1 - 2.0 * (k - 1) / (n - 2);
        y[k] = 1 + x[k] * x[k] / 2;
    }
    test_nff_polygon("a 2000-gon that can only be a fan", x, y, n, n - 2, 16, 10000);
    free(x);
    free(y);
}

/* ---- ear clipping ---- */

enum { STAR, COMB, DENT, RANDOM, SPIRAL, TEETH, SHAPES };

/* Corner k of n of a polygon of the given shape.  STAR, COMB (a gear's
 * teeth), DENT (one corner pushed in) and RANDOM (a random radius at each
 * angle) go round the origin once.  SPIRAL (n even) is a strip wound twice
 * round it, out along one edge and back along the other; TEETH (n = 6m + 1)
 * are m long teeth standing on a bar whose straight bottom edge has 2m + 1
 * corners.  These two are not star-shaped: an ear cut without looking at
 * the other corners would reach outside them. */
static void corner(int shape, int k, int n, double *x, double *y)
{
    double a = 2 * PI * k / n, r = 1, t;
    int m = (n - 1) / 6, j = k - 2 * m - 1;
    switch (shape) {
    case STAR: r = k % 2 ? 0.4 : 1; break;
    case COMB: r = k % 4 < 2 ? 1 : 0.6; break;
    case DENT: r = k == 0 ? 0.5 : 1; break;
    case RANDOM: r = unif(0.2, 1); break;
    case SPIRAL:
        t = 4 * PI * (k < n / 2 ? k : n - 1 - k) / (n / 2 - 1);
        r = 0.2 + 0.1 * t + (k < n / 2 ? 0.3 : 0);
        *x = r * cos(t), *y = r * sin(t);
        return;
    case TEETH:
        if (j < 0) *x = 0.5 * k, *y = 0;                  /* the bottom, left to right */
        else {                                             /* then the teeth, right to left */
            *x = m - 1 - j / 4 + (j % 4 == 0 ? 1 : j % 4 == 3 ? 0 : 0.5);
            *y = j % 4 < 2 ? 5 : 1;
        }
        return;
    }
    *x = r * cos(a), *y = r * sin(a);
}

/* For each shape, polygons of about 10 to 8000 corners, in the xy plane and
 * in a tilted one.  The spirals and the teeth are checked for n - 2
 * triangles and area only: the clipper still makes fans there (its laps
 * strip the outer edge of a spiral of corners faster than the inner one,
 * and the last outer corners then take fans of inner ones; and the teeth's
 * straight bottom has no ears), though there are triangulations without. */
static void test_ears(void)
{
    static const char *const names[SHAPES] = { "stars", "combs", "dented polygons",
                                               "random polygons", "spirals", "teeth on a bar" };
    static const int sizes[] = { 10, 37, 103, 997, 3001, 8005 };
    Frame tilt = tilted();
    int shape, si, rep;
    for (shape = 0; shape < SHAPES; shape++) {
        int bad = 0, worst = 0, worst_n = 0, polygons = 0, bounded = shape < SPIRAL;
        double worst_ratio = 0;
        char msg[300], name[200];
        for (si = 0; si < 6; si++)
            for (rep = 0; rep < (shape == RANDOM ? 5 : 2); rep++) {
                Scene s = white_scene();
                const Frame *f = rep % 2 ? &tilt : &flat;
                int n = sizes[si], *vi, k, most;
                double area = 0, sum = 0, allowed;
                if (shape == SPIRAL) n = (n < 40 ? 40 : n) & ~1;  /* 10: all on a line */
                if (shape == TEETH) n = n / 6 * 6 + 1;
                vi = malloc(sizeof *vi * n);
                if (!vi) exit(2);
                for (k = 0; k < n; k++) {
                    double x, y;
                    corner(shape, k, n, &x, &y);
                    vi[k] = add_vertex(&s, at(f, x, y, 0));
                }
                for (k = 0; k < n; k++) {          /* shoelace, in the figure's plane */
                    vec p = s.vert[vi[k]], q = s.vert[vi[(k + 1) % n]];
                    area += 0.5 * dot(cross(p, q), f->n);
                }
                triangulate((scene_builder[]){ builder(&s) }, vi, NULL, n, 0);
                most = busiest_vertex(&s);
                for (k = 0; k < s.ntri; k++) {
                    double t = 0.5 * dot(cross(s.tri[k].e1, s.tri[k].e2), f->n);
                    sum += fabs(t);
                    bad += !(t * area > 0);    /* turning the other way, or flat */
                }
                allowed = !bounded ? n : shape == RANDOM ? 3 * log2(n) : 2 * log2(n) + 2;
                bad += s.ntri != n - 2 || fabs(sum - fabs(area)) > 1e-9 * fabs(area) || most > allowed;
                if (most / log2(n) > worst_ratio) worst_ratio = most / log2(n), worst = most, worst_n = n;
                polygons++;
                free(vi);
                free_scene(&s);
            }
        sprintf(name, "ear clipping %s: n - 2 triangles, each turning the polygon's way, area "
                "exact%s", names[shape], bounded ? ", no fans" : "");
        sprintf(msg, "%d polygons of up to 8005 corners, %d wrong; busiest vertex: %d triangles "
                "at %d corners (bound %s)", polygons, bad, worst, worst_n,
                !bounded ? "none" : shape == RANDOM ? "3 log2 n" : "2 log2 n + 2");
        report(bad == 0, name, msg);
    }
}

/* ---- memory on an ordinary mesh ---- */

/* Raybench's cube-sphere: 12 k^2 triangles of nearly even size. */
static void cube_sphere(Scene *s, int k)
{
    int f, u, v;
    for (f = 0; f < 6; f++) {
        int base = s->nvert, axis = f % 3;
        for (v = 0; v <= k; v++)
            for (u = 0; u <= k; u++) {
                double q[3], a = 2.0 * u / k - 1, b = 2.0 * v / k - 1;
                q[axis] = f < 3 ? 1 : -1;
                q[(axis + 1) % 3] = f < 3 ? a : b;
                q[(axis + 2) % 3] = f < 3 ? b : a;
                add_vertex(s, unit(v3(q[0], q[1], q[2])));
            }
        for (v = 0; v < k; v++)
            for (u = 0; u < k; u++) {
                int a = base + v * (k + 1) + u, b = a + 1, c = a + k + 1, d = c + 1;
                add_triangle(s, a, b, d, -1, -1, -1, 0);
                add_triangle(s, a, d, c, -1, -1, -1, 0);
            }
    }
}

static void test_memory(void)
{
    Scene s = white_scene();
    kd_info k;
    size_t bytes;
    char msg[300];
    cube_sphere(&s, 64);
    if (!build(&s, &k, &bytes)) {
        report(0, "memory: kd_build", "returned NULL");
        return;
    }
    sprintf(msg, "%d triangles: peak %.1f bytes a triangle held by kdtree.c (bound 128), "
            "the tree %.1f", s.ntri, (double)bytes / s.ntri, (double)k.bytes / s.ntri);
    report(bytes <= 128.0 * s.ntri, "memory: the build's peak on a cube-sphere", msg);
    held = peak = 0;
    if (!build_accel(&s, "bvh") || !s.accel.bvh) {
        report(0, "memory: bvh_build", "returned NULL");
        free_scene(&s);
        return;
    }
    sprintf(msg, "%d triangles: peak %.1f bytes a triangle held by bvh.c (bound 120)", s.ntri,
            (double)peak / s.ntri);
    report(peak <= 120.0 * s.ntri, "memory: the BVH build's peak on a cube-sphere", msg);
    free_scene(&s);
}

int main(int argc, char **argv)
{
    Frame tilt = tilted();
    const char *part = argc > 1 ? argv[1] : "";
    if (!strcmp(part, "fan")) {
        /* the next fan only if this one kept within bounds: the old build
         * takes minutes over the 50k fan */
        if (test_fan(5000, &flat, 10000) && test_fan(20000, &tilt, 2000))
            test_fan(50000, &flat, 1000);
    } else if (!strcmp(part, "polygon"))
        test_polygons();
    else if (!strcmp(part, "ears"))
        test_ears();
    else if (!strcmp(part, "memory"))
        test_memory();
    else {
        fprintf(stderr, "usage: test_kdbuild fan|polygon|ears|memory\n");
        return 2;
    }
    return failures != 0;
}

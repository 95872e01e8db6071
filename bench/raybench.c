/* raybench.c - the kd-tree's build and traversal, measured on ray.c's own code.
 *
 *     cc -O2 -o raybench bench/raybench.c kdtree.c bvh.c grid.c -lm     (no -fopenmp: one thread)
 *
 *     raybench build [MAXN]          build time against N on cube-spheres of 10k
 *                                    up to MAXN (default 1M) triangles, for every
 *                                    structure, and the fitted exponents
 *     raybench rays MESH.obj RAYS.bin...
 *                                    trace the rays of RAYHITS1 files (written by
 *                                    ../shared/embree/embree_rays -out) and compare
 *                                    our hits with Embree's
 *     raybench made MESH.obj W H N [VIEW.nff]
 *                                    W x H primary and N random rays made here by
 *                                    the conventions of embree_rays.c's header
 *                                    (bit for bit the same rays), for a machine
 *                                    without Embree: timed, nothing to compare
 *     raybench accel SCENE W H N | SCENE RAYS.bin...
 *                                    every structure on the same rays, taking turns
 *     raybench anim SCENE.nff FRAMES MOVERS [ROUNDS]
 *                                    rebuild or refit as objects move
 *     raybench far SCENE W H N       kd, bvh and grid with the scene moved to
 *                                    1e4, 1e6 and 1e8 from the origin, and the
 *                                    camera to 1e10 and 1e13 from the scene:
 *                                    Mrays/s as a ratio to the origin's
 *
 * ray.c is included whole, as tests/test_ray.c does, so that what is timed is
 * the renderer's real triangle test, clip callback and tree walk, not a copy
 * that could drift from them.  Everything runs on one thread, and every time
 * is the thread's CPU time (CLOCK_THREAD_CPUTIME_ID), which leaves out the
 * time the thread waited while other processes ran: the wall clock of a busy
 * machine is not a measure of this code.  Whatever is compared takes turns
 * (the structures in each round, the builds at each size), and each figure
 * comes with its spread: the best, median and worst of its repeats.  Tables
 * go to standard output, each measurement followed by a line
 * "result key=value ..." for bench/run.sh to read.
 */
#define main ray_main
#include "../ray.c"
#undef main
#include <stdint.h>

#define RB_PI 3.14159265358979323846
#define RB_REPEAT 5 /* repeats of each timing: their best, median and worst are printed */

/* The CPU time of this thread, as embree_rays measures it beside the wall
 * clock: on a busy machine it leaves out the time the thread waited.  (Our
 * own clock rather than ray.c's, an internal of a file being edited.) */
static double rb_cpu(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static int rb_cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The least, the median and the greatest of n >= 1 values, which are
 * sorted in place; the median of an even count is the mean of the two in
 * the middle.  (Of times the least is the best; of rates, the greatest.) */
typedef struct { double lo, med, hi; } RbSpread;
static RbSpread rb_spread(double *v, int n)
{
    RbSpread s;
    qsort(v, (size_t)n, sizeof v[0], rb_cmp_double);
    s.lo = v[0], s.hi = v[n - 1];
    s.med = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    return s;
}

static void rb_die(const char *what, const char *arg)
{
    fprintf(stderr, "raybench: %s%s%s\n", what, arg ? ": " : "", arg ? arg : "");
    exit(1);
}

/* ------------------------------------------------------------------ rays */

/* One ray in Embree's float precision, with Embree's answer when known
 * (prim -1: a miss; -2: no answer, the ray was made here). */
typedef struct {
    float o[3], d[3];
    float t;
    int32_t prim;
} RbRay;

/* RAYHITS1 stores little-endian 32-bit words; assembling them byte by byte
 * reads the file the same on any host. */
static uint32_t rb_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float rb_f32(const unsigned char *p)
{
    uint32_t u = rb_u32(p);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* The header comment of embree_rays.c: "RAYHITS1", uint32 count, uint32
 * record size 48, then per ray org[3] dir[3] tnear tfar t_hit primID u v. */
static RbRay *rb_read_rayhits(const char *path, long *count)
{
    unsigned char head[16], rec[48];
    uint32_t n, size, i;
    RbRay *rays;
    FILE *f = fopen(path, "rb");
    if (!f) rb_die("cannot open", path);
    if (fread(head, 1, 16, f) != 16 || memcmp(head, "RAYHITS1", 8)) rb_die("not a RAYHITS1 file", path);
    n = rb_u32(head + 8);
    size = rb_u32(head + 12);
    if (size != 48 || n == 0 || n > 100000000u) rb_die("unexpected RAYHITS1 header", path);
    rays = malloc((size_t)n * sizeof *rays);
    if (!rays) rb_die("out of memory for the rays of", path);
    for (i = 0; i < n; i++) {
        int k;
        if (fread(rec, 1, 48, f) != 48) rb_die("RAYHITS1 file ends early", path);
        for (k = 0; k < 3; k++) {
            rays[i].o[k] = rb_f32(rec + 4 * k);
            rays[i].d[k] = rb_f32(rec + 12 + 4 * k);
        }
        /* tnear (rec + 24) is 0 and tfar_in (rec + 28) infinite in every
         * file embree_rays writes: rays from the origin, unbounded. */
        rays[i].t = rb_f32(rec + 32);
        rays[i].prim = (int32_t)rb_u32(rec + 36);
    }
    fclose(f);
    *count = (long)n;
    return rays;
}

/* The mesh's box as embree_rays computes it (vertices read as floats), so
 * that primary and random rays made here are the ones it would make. */
typedef struct { double c[3], he[3], R; } RbBox;

static RbBox rb_box(const Scene *s)
{
    float lo[3], hi[3];
    RbBox b;
    int i, k;
    for (k = 0; k < 3; k++) lo[k] = FLT_MAX, hi[k] = -FLT_MAX;
    for (i = 0; i < s->nsph + s->ncone; i++) {   /* an NFF scene's spheres and cones */
        double l[3], h[3];
        prim_bounds((void *)s, i, l, h);
        for (k = 0; k < 3; k++) {
            if (l[k] < lo[k]) lo[k] = (float)l[k];
            if (h[k] > hi[k]) hi[k] = (float)h[k];
        }
    }
    for (i = 0; i < s->nvert; i++) {
        float p[3];
        p[0] = (float)s->vert[i].x; p[1] = (float)s->vert[i].y; p[2] = (float)s->vert[i].z;
        for (k = 0; k < 3; k++) {
            if (p[k] < lo[k]) lo[k] = p[k];
            if (p[k] > hi[k]) hi[k] = p[k];
        }
    }
    b.R = 0;
    for (k = 0; k < 3; k++) {
        b.c[k] = 0.5 * ((double)lo[k] + hi[k]);
        b.he[k] = 0.5 * ((double)hi[k] - lo[k]);
        b.R += b.he[k] * b.he[k];
    }
    b.R = sqrt(b.R);
    return b;
}

static void rb_norm(double *a)
{
    double l = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    a[0] /= l; a[1] /= l; a[2] /= l;
}

static void rb_cross(const double *a, const double *b, double *c)
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* from, at, up and angle of an NFF view, the camera embree_rays' -nffview
 * takes.  Returns 0 when one of them is missing. */
static int rb_nff_view(const char *path, double eye[3], double at[3], double up[3], double *fov)
{
    char tok[256];
    int got = 0;
    FILE *f = fopen(path, "r");
    if (!f) rb_die("cannot open", path);
    while (got < 4 && fscanf(f, "%255s", tok) == 1) {
        if (!strcmp(tok, "from")) got += fscanf(f, "%lf %lf %lf", &eye[0], &eye[1], &eye[2]) == 3;
        else if (!strcmp(tok, "at")) got += fscanf(f, "%lf %lf %lf", &at[0], &at[1], &at[2]) == 3;
        else if (!strcmp(tok, "up")) got += fscanf(f, "%lf %lf %lf", &up[0], &up[1], &up[2]) == 3;
        else if (!strcmp(tok, "angle")) got += fscanf(f, "%lf", fov) == 1;
    }
    fclose(f);
    return got == 4;
}

/* The camera of the primary rays, by embree_rays' stated pinhole
 * convention: without a view, looking down -z at the box centre from where
 * the bounding sphere just fills the 45-degree vertical field of view; with
 * one, the NFF camera.  dist > 0 moves the eye back along its line of sight
 * to dist from the point it looks at, the field of view narrowed to frame
 * the same picture (raybench far). */
typedef struct { double eye[3], f[3], r[3], u[3], th; } RbCamera;

static RbCamera rb_camera(const Scene *s, const char *view, double dist)
{
    RbBox b = rb_box(s);
    RbCamera c;
    double at[3], up[3] = { 0, 1, 0 }, fov = 45, len;
    int k;
    if (view) {
        if (!rb_nff_view(view, c.eye, at, up, &fov)) rb_die("no from, at, up and angle in", view);
    } else {
        double d0 = b.R / sin(0.5 * fov * RB_PI / 180);
        for (k = 0; k < 3; k++) at[k] = b.c[k];
        c.eye[0] = b.c[0]; c.eye[1] = b.c[1]; c.eye[2] = b.c[2] + d0;   /* dir (0, 0, -1) */
    }
    c.th = tan(0.5 * fov * RB_PI / 180);
    for (k = 0; k < 3; k++) c.f[k] = at[k] - c.eye[k];
    if (dist > 0) {
        len = sqrt(c.f[0] * c.f[0] + c.f[1] * c.f[1] + c.f[2] * c.f[2]);
        for (k = 0; k < 3; k++) c.eye[k] = at[k] - c.f[k] / len * dist;
        c.th *= len / dist;
    }
    rb_norm(c.f);
    rb_cross(c.f, up, c.r);
    if (sqrt(c.r[0] * c.r[0] + c.r[1] * c.r[1] + c.r[2] * c.r[2]) < 1e-6) {  /* up along the view */
        double up2[3] = { 0, 0, 1 };
        if (fabs(c.f[2]) > 0.9) up2[1] = 1, up2[2] = 0;
        rb_cross(c.f, up2, c.r);
    }
    rb_norm(c.r);
    rb_cross(c.r, c.f, c.u);
    return c;
}

/* The unit direction through the centre of pixel x, y of w x h. */
static void rb_pixel(const RbCamera *c, int w, int h, int x, int y, double d[3])
{
    double sx = (2.0 * (x + 0.5) / w - 1) * c->th * ((double)w / h);
    double sy = (1 - 2.0 * (y + 0.5) / h) * c->th;
    int k;
    for (k = 0; k < 3; k++) d[k] = c->f[k] + sx * c->r[k] + sy * c->u[k];
    rb_norm(d);
}

/* W x H primary rays from the camera (rb_camera). */
static RbRay *rb_primary(const Scene *s, int w, int h, const char *view)
{
    RbCamera c = rb_camera(s, view, 0);
    RbRay *rays = malloc((size_t)w * h * sizeof *rays);
    int x, y, k;
    if (!rays) rb_die("out of memory for primary rays", NULL);
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            double d[3];
            RbRay *ry = &rays[(size_t)y * w + x];
            rb_pixel(&c, w, h, x, y, d);
            for (k = 0; k < 3; k++) ry->o[k] = (float)c.eye[k], ry->d[k] = (float)d[k];
            ry->t = 0;
            ry->prim = -2;
        }
    return rays;
}

/* splitmix64 (Steele, Lea and Flood, "Fast splittable pseudorandom number
 * generators", OOPSLA 2014): the stream embree_rays draws its random rays
 * from, so that a seed names the same rays there and here. */
static uint64_t rb_state;
static double rb_uniform(void)
{
    uint64_t z = (rb_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);   /* 53 bits in [0, 1) */
}

/* Origins uniform in the box grown 1.5 times about its centre, directions
 * uniform on the sphere: incoherent rays, many starting inside the mesh. */
static RbRay *rb_random(const Scene *s, long n, uint64_t seed)
{
    RbBox b = rb_box(s);
    RbRay *rays = malloc((size_t)n * sizeof *rays);
    long i;
    int k;
    if (!rays) rb_die("out of memory for random rays", NULL);
    rb_state = seed;
    for (i = 0; i < n; i++) {
        double o[3], z, phi, sz;
        for (k = 0; k < 3; k++) o[k] = b.c[k] + (2 * rb_uniform() - 1) * b.he[k] * 1.5;
        z = 2 * rb_uniform() - 1;
        phi = 2 * RB_PI * rb_uniform();
        sz = sqrt(1 - z * z);
        for (k = 0; k < 3; k++) rays[i].o[k] = (float)o[k];
        rays[i].d[0] = (float)(sz * cos(phi));
        rays[i].d[1] = (float)(sz * sin(phi));
        rays[i].d[2] = (float)z;
        rays[i].t = 0;
        rays[i].prim = -2;
    }
    return rays;
}

/* ---------------------------------------------------------------- scenes */

static int rb_white(Scene *s)
{
    Material m;
    memset(&m, 0, sizeof m);
    m.color = v3(1, 1, 1);
    m.kd = 1;
    m.ir = 1;
    return add_material(s, m);
}

/* Only the arrays a mesh scene can fill are freed: the others stay NULL here,
 * and naming each would tie the bench to every field of a Scene in flux. */
static void rb_free_scene(Scene *s)
{
    if (s->accel.kd) kd_free(s->accel.kd);
    if (s->accel.bvh) bvh_free(s->accel.bvh);
    if (s->accel.grid) grid_free(s->accel.grid);
    free(s->mat); free(s->sph); free(s->tri); free(s->vert); free(s->norm); free(s->light);
}

static void rb_load_mesh(Scene *s, const char *path)
{
    scene_builder b = builder(s);
    default_scene(s);
    if (!read_obj(&b, path, rb_white(s), path, 0)) exit(1);
    if (s->ntri == 0) rb_die("no triangles in", path);
}

/* Builds the tree; returns the thread's CPU seconds it took. */
static double rb_build(Scene *s)
{
    double c0 = rb_cpu();
    if (!build_accel(s, "kd") || !s->accel.kd) rb_die("kd-tree build failed", NULL);
    return rb_cpu() - c0;
}

/* What the tree costs in memory and shape, per triangle. */
static void rb_tree_line(const Scene *s, double seconds)
{
    kd_info k;
    kd_describe(s->accel.kd, &k);
    printf("kd-tree    %d objects, built in %.3f s (CPU): %ld nodes, depth %ld, %.2f refs/object, "
           "%.1f bytes/object, SAH cost %.2f\n", nobj(s), seconds, k.nodes, k.max_depth,
           (double)k.prim_refs / nobj(s), (double)k.bytes / nobj(s), k.sah_cost);
    printf("result objects=%d build_s=%.4f nodes=%ld depth=%ld refs_per_obj=%.3f bytes_per_obj=%.2f sah=%.3f\n",
           nobj(s), seconds, k.nodes, k.max_depth, (double)k.prim_refs / nobj(s),
           (double)k.bytes / nobj(s), k.sah_cost);
}

/* ---------------------------------------------------------------- tracing */

/* Ray i as the structures and ray.c's hit callback take it. */
static Query rb_query_at(const RbRay *ray, double o[3], double d[3], real time)
{
    Ray r;
    int k;
    for (k = 0; k < 3; k++) o[k] = ray->o[k], d[k] = ray->d[k];
    r.o = v3(o[0], o[1], o[2]);
    r.d = v3(d[0], d[1], d[2]);
    r.skip = -1, r.tmin = 0, r.time = time;
    return query(r);
}

static Query rb_query(const RbRay *ray, double o[3], double d[3]) { return rb_query_at(ray, o, d, 0); }

/* What rtcIntersect1 returns besides the triangle and t: the barycentrics
 * u and v, kept by the hit callback in q, and the unnormalised e1 x e2. */
static void rb_uvn(const Scene *s, int obj, const Query *q, double h[5])
{
    const Triangle *tr;
    vec ng;
    if (obj < 0 || q->obj != obj) return;
    tr = &s->tri[obj - (nobj(s) - s->ntri)];
    ng = cross(tr->e1, tr->e2);
    h[0] = q->u, h[1] = q->v, h[2] = ng.x, h[3] = ng.y, h[4] = ng.z;
}

/* Traces every ray once, single-threaded; the object hit (-1: none) and its
 * t go to obj and t.  bare = 0 asks nearest_hit(), what the renderer calls,
 * which also computes the hit point, the unit shading normal and the
 * material.  bare = 1 returns what rtcIntersect1 returns, no more and no
 * less: the triangle, t, the barycentrics u and v (kept by the tree's hit
 * callback) and the geometric normal unnormalised, e1 x e2; these three go to
 * uvn, five numbers a ray.  Returns the thread's CPU seconds. */
static double rb_trace(const Scene *s, const RbRay *rays, long n, int bare, int *obj, double *t,
                       double *uvn)
{
    Worker wk;
    double c0 = rb_cpu();
    long i;
    memset(&wk, 0, sizeof wk);
    for (i = 0; i < n; i++) {
        Ray r;
        r.o = v3(rays[i].o[0], rays[i].o[1], rays[i].o[2]);
        r.d = v3(rays[i].d[0], rays[i].d[1], rays[i].d[2]);
        r.skip = -1, r.tmin = 0, r.time = 0;
        if (bare) {
            double o[3], d[3], tmax = INFINITY;
            Query q = rb_query(&rays[i], o, d);
            obj[i] = kd_nearest(s->accel.kd, &s->accel.prims, o, d, &q, -1, 0, &tmax, NULL);
            t[i] = tmax;
            rb_uvn(s, obj[i], &q, uvn + 5 * i);
        } else {
            Hit h;
            if (nearest_hit(s, r, &h, &wk)) obj[i] = h.obj, t[i] = h.t;
            else obj[i] = -1, t[i] = INFINITY;
        }
    }
    return rb_cpu() - c0;
}

/* Our hits against Embree's: the same triangle, and t within a relative
 * 1e-4.  Embree traces in float, so rays through a shared edge or vertex,
 * and grazing ones at the silhouette, may disagree by rounding alone, and a
 * ray starting a hair from the surface gets a tiny t whose float rounding
 * (about 1e-7 of the coordinates) exceeds 1e-4 of it.  The kinds are counted
 * apart, and a t mismatch on the same triangle within 1e-6 of the box's
 * half-diagonal (as embree_rays' own checker does) is called float rounding,
 * so that a real bug stands out from such cases. */
static void rb_compare(const Scene *s, const char *set, const RbRay *rays, long n, const int *obj, const double *t)
{
    long both_miss = 0, agree = 0, tie = 0, tfloat = 0, tdiff = 0, ours_only = 0, theirs_only = 0, i;
    int first_tri = nobj(s) - s->ntri;  /* triangles come last, in file order */
    double small = 1e-6 * rb_box(s).R;
    for (i = 0; i < n; i++) {
        /* -3: we hit something that is not a triangle, which Embree never can */
        int ours = obj[i] >= first_tri ? obj[i] - first_tri : obj[i] < 0 ? -1 : -3;
        int theirs = rays[i].prim;
        double dt;
        if (ours == -1 && theirs < 0) both_miss++;
        else if (theirs < 0) ours_only++;
        else if (ours == -1) theirs_only++;
        else if ((dt = fabs(t[i] - (double)rays[i].t)) <= 1e-4 * fabs((double)rays[i].t))
            ours == theirs ? agree++ : tie++;
        else if (ours == theirs && dt <= small) tfloat++;
        else tdiff++;
    }
    printf("vs Embree  %ld agree, %ld both miss; %ld disagree: %ld same t but another triangle "
           "(a shared edge or vertex), %ld same triangle with t off by float rounding (tiny t), "
           "%ld t differs, %ld hit by us only, %ld by Embree only\n", agree, both_miss,
           tie + tfloat + tdiff + ours_only + theirs_only, tie, tfloat, tdiff, ours_only, theirs_only);
    printf("result set=%s agree=%ld disagree=%ld tie=%ld tfloat=%ld tdiff=%ld ours_only=%ld embree_only=%ld\n",
           set, agree, tie + tfloat + tdiff + ours_only + theirs_only, tie, tfloat, tdiff, ours_only, theirs_only);
}

/* How the walk spends its work, in an untimed pass: tree steps and hit tests
 * per ray, and how many tests repeat a primitive already tested for the same
 * ray.  A primitive listed in several leaves along the ray would be tested
 * in each; kdtree.c's mailbox (MAILBOX) stops that, and the repeats left are
 * primitives that shared a slot of it.  The tree's own hit callback is
 * wrapped, so nothing in ray.c changes. */
static struct {
    int (*hit)(void *, int, void *, double, double, double *);
    unsigned long *mark;      /* per primitive: the last ray that tested it */
    unsigned long ray;
    unsigned long long tests, repeats;
} rb_probe;

static int rb_counting_hit(void *user, int i, void *ray, double tmin, double tmax, double *t)
{
    rb_probe.tests++;
    if (rb_probe.mark[i] == rb_probe.ray) rb_probe.repeats++;
    rb_probe.mark[i] = rb_probe.ray;
    return rb_probe.hit(user, i, ray, tmin, tmax, t);
}

static void rb_work(Scene *s, const char *set, const RbRay *rays, long n)
{
    prim_counters c = { 0, 0, 0 };
    long i;
    rb_probe.hit = s->accel.prims.hit;
    rb_probe.mark = calloc((size_t)nobj(s), sizeof *rb_probe.mark);
    rb_probe.tests = rb_probe.repeats = 0;
    if (!rb_probe.mark) rb_die("out of memory", NULL);
    s->accel.prims.hit = rb_counting_hit;
    for (i = 0; i < n; i++) {
        double o[3], d[3], tmax = INFINITY;
        Query q = rb_query(&rays[i], o, d);
        rb_probe.ray = (unsigned long)i + 1;
        kd_nearest(s->accel.kd, &s->accel.prims, o, d, &q, -1, 0, &tmax, &c);
    }
    s->accel.prims.hit = rb_probe.hit;
    free(rb_probe.mark);
    printf("work       %.1f tree steps and %.2f hit tests per ray; %.1f%% of the tests repeat a "
           "primitive already tested for that ray\n", (double)c.steps / n, (double)rb_probe.tests / n,
           rb_probe.tests ? 100.0 * rb_probe.repeats / rb_probe.tests : 0.0);
    printf("result set=%s steps_per_ray=%.2f tests_per_ray=%.3f repeat_pct=%.2f\n", set, (double)c.steps / n,
           (double)rb_probe.tests / n, rb_probe.tests ? 100.0 * rb_probe.repeats / rb_probe.tests : 0.0);
}

/* Times both ways of tracing one set of rays through the built tree of s,
 * and compares with Embree when the rays came with its answers.  `set`
 * names them in the result lines. */
static void rb_rays(Scene *s, const char *set, const RbRay *rays, long n)
{
    int *obj = malloc((size_t)n * sizeof *obj);
    double *t = malloc((size_t)n * sizeof *t);
    double *uvn = malloc((size_t)n * 5 * sizeof *uvn);
    RbSpread full, bare;
    long hits = 0, i;
    if (!obj || !t || !uvn) rb_die("out of memory for hits", NULL);
    /* the two ways take turns, so that both meet the machine's drift alike;
     * nearest_hit last: its hits are compared */
    {
        double f[RB_REPEAT], b[RB_REPEAT];
        int k;
        for (k = 0; k < RB_REPEAT; k++) {
            b[k] = n / rb_trace(s, rays, n, 1, obj, t, uvn) * 1e-6;
            f[k] = n / rb_trace(s, rays, n, 0, obj, t, NULL) * 1e-6;
        }
        full = rb_spread(f, RB_REPEAT), bare = rb_spread(b, RB_REPEAT);
    }
    for (i = 0; i < n; i++) hits += obj[i] >= 0;
    printf("rays       %s: %ld rays, %ld hit (%.1f%%), one thread, %d runs of each, taking turns\n", set, n,
           hits, 100.0 * hits / n, RB_REPEAT);
    printf("traversal  Mrays/s by thread CPU time, median (best - worst): nearest_hit %.2f (%.2f - %.2f); "
           "tree walk alone (kd_nearest, and u, v, Ng as rtcIntersect1 gives) %.2f (%.2f - %.2f)\n",
           full.med, full.hi, full.lo, bare.med, bare.hi, bare.lo);
    printf("result set=%s rays=%ld hits=%ld mrays=%.3f mrays_best=%.3f mrays_worst=%.3f bare_mrays=%.3f "
           "bare_best=%.3f bare_worst=%.3f\n", set, n, hits, full.med, full.hi, full.lo,
           bare.med, bare.hi, bare.lo);
    rb_work(s, set, rays, n);
    if (rays[0].prim != -2) rb_compare(s, set, rays, n, obj, t);
    free(obj);
    free(t);
    free(uvn);
}

/* The mesh, loaded and its tree built and described. */
static void rb_mesh(Scene *s, const char *path)
{
    double secs;
    rb_load_mesh(s, path);
    secs = rb_build(s);
    rb_tree_line(s, secs);
}

/* ------------------------------------------------------------ build scaling */

/* Point (u, v) of a k x k grid on cube face f, pushed out onto the unit
 * sphere: triangles of nearly even size everywhere, with no poles where
 * hundreds of slivers meet as on a latitude-longitude sphere. */
static vec rb_cube_point(int f, int u, int v, int k)
{
    double q[3], a = 2.0 * u / k - 1, b = 2.0 * v / k - 1;
    int axis = f % 3;
    q[axis] = f < 3 ? 1 : -1;
    q[(axis + 1) % 3] = f < 3 ? a : b;   /* swapped on the far faces, so */
    q[(axis + 2) % 3] = f < 3 ? b : a;   /* that all six wind the same way */
    return unit(v3(q[0], q[1], q[2]));
}

/* A sphere of 12 k^2 triangles through ray.c's own add_vertex and
 * add_triangle, so that the tree sees exactly what a loaded mesh gives it. */
static void rb_cube_sphere(Scene *s, int k)
{
    int mat = rb_white(s), f, u, v;
    for (f = 0; f < 6; f++) {
        int base = s->nvert;
        for (v = 0; v <= k; v++)
            for (u = 0; u <= k; u++) add_vertex(s, rb_cube_point(f, u, v, k));
        for (v = 0; v < k; v++)
            for (u = 0; u < k; u++) {
                int a = base + v * (k + 1) + u, b = a + 1, c = a + k + 1, d = c + 1;
                add_triangle(s, a, b, d, -1, -1, -1, mat);
                add_triangle(s, a, d, c, -1, -1, -1, mat);
            }
    }
}

/* ------------------------------------------------------- every structure */

/* The structures compared by `raybench accel`: each traced on the same rays
 * by the same loop, which asks one structure for the nearest hit and, for a
 * triangle, reads u, v and the unnormalised Ng as rtcIntersect1 returns
 * them.  -rec: the slide's recursive form of the same tree; none: a loop
 * over every object (on a prefix of the rays: see rb_none_rays). */
enum { RB_KD, RB_KD_REC, RB_BVH, RB_BVH_REC, RB_BVH_MEDIAN, RB_GRID, RB_NONE, RB_N };
static const char *const rb_names[RB_N] = {
    "kd", "kd-rec", "bvh-sah", "bvh-rec", "bvh-median", "grid", "none"
};

typedef struct {
    Scene *s;
    kd_tree *kd;
    bvh *sah, *median;
    grid *g;
    double build[RB_N];     /* CPU seconds, best of the builds */
    double bytes[RB_N];
} RbAll;

static double rb_cpu_build(RbAll *A, int which)
{
    const prims *p = &A->s->accel.prims;
    double c0 = rb_cpu();
    int n = nobj(A->s);
    switch (which) {
    case RB_KD: if (A->kd) kd_free(A->kd); A->kd = kd_build(n, p); break;
    case RB_BVH: if (A->sah) bvh_free(A->sah); A->sah = bvh_build(n, p, BVH_SAH); break;
    case RB_BVH_MEDIAN: if (A->median) bvh_free(A->median); A->median = bvh_build(n, p, BVH_MEDIAN); break;
    default: if (A->g) grid_free(A->g); A->g = grid_build(n, p);
    }
    return rb_cpu() - c0;
}

/* Builds every structure, best of three (of one past a second). */
static void rb_build_all(RbAll *A)
{
    static const int built[4] = { RB_KD, RB_BVH, RB_BVH_MEDIAN, RB_GRID };
    int k, r;
    for (k = 0; k < 4; k++) {
        double best = HUGE_VAL;
        for (r = 0; r < 3 && (r == 0 || best < 1); r++) {
            double c = rb_cpu_build(A, built[k]);
            if (c < best) best = c;
        }
        A->build[built[k]] = best;
    }
    if (!A->kd || !A->sah || !A->median || !A->g) rb_die("out of memory building the structures", NULL);
    {
        kd_info ki;
        bvh_info bi;
        grid_info gi;
        kd_describe(A->kd, &ki);
        A->bytes[RB_KD] = A->bytes[RB_KD_REC] = (double)ki.bytes;
        bvh_describe(A->sah, &bi);
        A->bytes[RB_BVH] = A->bytes[RB_BVH_REC] = (double)bi.bytes;
        bvh_describe(A->median, &bi);
        A->bytes[RB_BVH_MEDIAN] = (double)bi.bytes;
        grid_describe(A->g, &gi);
        A->bytes[RB_GRID] = (double)gi.bytes;
    }
    A->build[RB_KD_REC] = A->build[RB_KD], A->build[RB_BVH_REC] = A->build[RB_BVH];
}

static int rb_nearest_with(const RbAll *A, int which, const double o[3], const double d[3],
                           Query *q, double *t, prim_counters *c)
{
    const prims *p = &A->s->accel.prims;
    int i, best = -1, n = nobj(A->s);
    switch (which) {
    case RB_KD: return kd_nearest(A->kd, p, o, d, q, -1, 0, t, c);
    case RB_KD_REC: return kd_intersect_recursive(A->kd, p, o, d, q, -1, 0, t, 0, c);
    case RB_BVH: return bvh_nearest(A->sah, p, o, d, q, -1, 0, t, c);
    case RB_BVH_REC: return bvh_intersect_recursive(A->sah, p, o, d, q, -1, 0, t, 0, c);
    case RB_BVH_MEDIAN: return bvh_nearest(A->median, p, o, d, q, -1, 0, t, c);
    case RB_GRID: return grid_nearest(A->g, p, o, d, q, -1, 0, t, c);
    }
    for (i = 0; i < n; i++) {   /* none */
        double th;
        if (p->hit(p->user, i, q, 0, *t, &th) && th < *t) *t = th, best = i;
    }
    if (c) c->rays++, c->tests += (unsigned long long)n;
    return best;
}

/* One pass over the rays with one structure: the thread's CPU seconds.
 * What a ray returns (triangle, t, u, v, Ng) goes to obj, t and uvn. */
static double rb_pass(const RbAll *A, int which, const RbRay *rays, long n, int *obj, double *t,
                      double *uvn, prim_counters *c)
{
    const Scene *s = A->s;
    double c0 = rb_cpu();
    long i;
    for (i = 0; i < n; i++) {
        double o[3], d[3], tmax = INFINITY;
        Query q = rb_query(&rays[i], o, d);
        obj[i] = rb_nearest_with(A, which, o, d, &q, &tmax, c);
        t[i] = tmax;
        rb_uvn(s, obj[i], &q, uvn + 5 * i);
    }
    return rb_cpu() - c0;
}

/* Brute force costs a test of every object per ray: it traces only as many
 * rays as make about 2e7 tests, at least 200. */
static long rb_none_rays(const Scene *s, long n)
{
    long k = (long)(2e7 / (nobj(s) > 0 ? nobj(s) : 1));
    return k < 200 ? (n < 200 ? n : 200) : k < n ? k : n;
}

/* $RB_ACCELS (say "kd bvh-sah"): only those structures; all by default. */
static int rb_wanted(int which)
{
    const char *only = getenv("RB_ACCELS"), *at;
    size_t len = strlen(rb_names[which]);
    if (!only || !*only) return 1;
    for (at = strstr(only, rb_names[which]); at; at = strstr(at + 1, rb_names[which]))
        if ((at == only || at[-1] == ' ' || at[-1] == ',') && (at[len] == 0 || at[len] == ' ' || at[len] == ','))
            return 1;
    return 0;
}


/* Every structure on one set of rays, in ROUNDS rounds, each round tracing
 * with every structure in turn, so that all meet the machine's drift
 * alike.  Prints Mrays/s by CPU time, the best, median and worst round,
 * and whether each structure's answers equal the kd-tree's (triangle or
 * object and bitwise t). */
#define RB_ROUNDS 5
static void rb_accel_set(const RbAll *A, const char *set, const RbRay *rays, long n)
{
    int *obj[RB_N], w, r;
    double *t[RB_N], *uvn = malloc((size_t)n * 5 * sizeof *uvn), secs[RB_N][RB_ROUNDS];
    prim_counters c[RB_N];
    long hits = 0, i;
    if (!uvn) rb_die("out of memory for hits", NULL);
    for (w = 0; w < RB_N; w++) {
        obj[w] = malloc((size_t)n * sizeof(int));
        t[w] = malloc((size_t)n * sizeof(double));
        if (!obj[w] || !t[w]) rb_die("out of memory for hits", NULL);
        memset(&c[w], 0, sizeof c[w]);
        if (w == RB_KD || rb_wanted(w))
            rb_pass(A, w, rays, w == RB_NONE ? rb_none_rays(A->s, n) : n, obj[w], t[w], uvn, &c[w]);
    }
    for (r = 0; r < RB_ROUNDS; r++)
        for (w = 0; w < RB_N; w++)
            if (rb_wanted(w)) secs[w][r] = rb_pass(A, w, rays, w == RB_NONE ? rb_none_rays(A->s, n) : n, obj[w],
                                 t[w], uvn, NULL);
    for (i = 0; i < n; i++) hits += obj[RB_KD][i] >= 0;
    printf("%s: %ld rays, %ld hit (%.1f%%); Mrays/s by thread CPU time, best / median / worst of %d "
           "rounds, the structures taking turns\n", set, n, hits, 100.0 * hits / n, RB_ROUNDS);
    for (w = 0; w < RB_N; w++) {
        long m = w == RB_NONE ? rb_none_rays(A->s, n) : n, diff = 0;
        double mr[RB_ROUNDS];
        if (!rb_wanted(w)) continue;
        for (r = 0; r < RB_ROUNDS; r++) mr[r] = m / secs[w][r] * 1e-6;
        qsort(mr, RB_ROUNDS, sizeof mr[0], rb_cmp_double);
        for (i = 0; i < m; i++)
            diff += obj[w][i] != obj[RB_KD][i] || memcmp(&t[w][i], &t[RB_KD][i], sizeof(double));
        printf("  %-10s %8.3f %8.3f %8.3f Mrays/s  %7.2f steps %7.2f tests per ray  build %.4f s  "
               "%.1f MB  %s\n", rb_names[w], mr[RB_ROUNDS - 1], mr[RB_ROUNDS / 2], mr[0],
               (double)c[w].steps / m, (double)c[w].tests / m, A->build[w], A->bytes[w] / 1e6,
               diff ? "DIFFERS from kd" : "same answers as kd");
        printf("result set=%s accel=%s rays=%ld best=%.4f median=%.4f worst=%.4f steps=%.3f tests=%.3f "
               "build_s=%.5f bytes=%.0f differ=%ld\n", set, rb_names[w], m, mr[RB_ROUNDS - 1],
               mr[RB_ROUNDS / 2], mr[0], (double)c[w].steps / m, (double)c[w].tests / m, A->build[w],
               A->bytes[w], diff);
    }
    for (w = 0; w < RB_N; w++) free(obj[w]), free(t[w]);
    free(uvn);
}

/* A mesh (.obj) or a scene (.nff, spheres and cones included), with every
 * structure built over it. */
static void rb_load_any(Scene *s, RbAll *A, const char *path)
{
    const char *dot = strrchr(path, '.');
    if (dot && !strcmp(dot, ".nff")) {
        if (!load_scene(s, path)) exit(1);
    } else
        rb_load_mesh(s, path);
    if (!build_accel(s, "none")) exit(1);   /* sets the callbacks */
    memset(A, 0, sizeof *A);
    A->s = s;
    rb_build_all(A);
    printf("scene %s: %d objects (%d triangles)\n", path, nobj(s), s->ntri);
}

static void rb_free_all(RbAll *A)
{
    kd_free(A->kd), bvh_free(A->sah), bvh_free(A->median), grid_free(A->g);
}

/* Build time against N for every structure, and the exponent p of
 * time ~ N^p by least squares on log time against log N.  Wald and
 * Havran's O(N log N) build gives p a little above 1; p well above means
 * some step grows faster than it should.  At each size the four builds take
 * turns (kd, BVH SAH, BVH median, grid; each freed once timed, so that one
 * build's memory is about at a time), 5 rounds, 3 once a kd build takes
 * over a second; the median of each is the figure, and p is fitted to the
 * medians (and, for comparison, to the best runs). */
static void rb_build_table(long maxn)
{
    static const long sizes[] = { 10000, 30000, 100000, 300000, 1000000, 3000000 };
    static const int which[4] = { RB_KD, RB_BVH, RB_BVH_MEDIAN, RB_GRID };
    enum { NS = sizeof sizes / sizeof sizes[0] };
    RbSpread sp[NS][4];
    kd_info info[NS];
    int nobjs[NS], rounds[NS], i, j, count = 0;
    double sx = 0, sxx = 0, sy[4] = { 0 }, sxy[4] = { 0 }, syb[4] = { 0 }, sxyb[4] = { 0 };
    for (i = 0; i < NS && sizes[i] <= maxn; i++) {
        int k = (int)floor(sqrt(sizes[i] / 12.0) + 0.5), r;
        double c[4][RB_REPEAT];
        Scene s;
        RbAll A;
        default_scene(&s);
        rb_cube_sphere(&s, k);
        if (!build_accel(&s, "none")) rb_die("cannot set up the callbacks", NULL);
        memset(&A, 0, sizeof A);
        A.s = &s;
        nobjs[i] = nobj(&s);
        rounds[i] = RB_REPEAT;
        for (r = 0; r < rounds[i]; r++) {
            for (j = 0; j < 4; j++) {
                c[j][r] = rb_cpu_build(&A, which[j]);
                if (which[j] == RB_KD) {
                    if (!A.kd) rb_die("kd-tree build failed", NULL);
                    if (r == 0) kd_describe(A.kd, &info[i]);
                    kd_free(A.kd), A.kd = NULL;
                } else if (which[j] == RB_GRID) grid_free(A.g), A.g = NULL;
                else if (which[j] == RB_BVH) bvh_free(A.sah), A.sah = NULL;
                else bvh_free(A.median), A.median = NULL;
            }
            if (r == 0 && c[0][0] > 1) rounds[i] = 3;
        }
        for (j = 0; j < 4; j++) {
            sp[i][j] = rb_spread(c[j], rounds[i]);
            sy[j] += log(sp[i][j].med), sxy[j] += log((double)nobjs[i]) * log(sp[i][j].med);
            syb[j] += log(sp[i][j].lo), sxyb[j] += log((double)nobjs[i]) * log(sp[i][j].lo);
        }
        sx += log((double)nobjs[i]), sxx += log((double)nobjs[i]) * log((double)nobjs[i]);
        count++;
        rb_free_scene(&s);
    }
    printf("Build time against N: cube-spheres, ray.c's triangles and clip callback, one thread, CPU seconds;\n"
           "at each size the four structures' builds take turns, 5 rounds (3 past a second): median (best - worst)\n");
    printf("%10s %9s %19s %5s %8s %9s %6s %9s %10s %9s\n", "triangles", "kd s", "(best - worst)", "runs",
           "ns/tri", "nodes", "depth", "refs/tri", "bytes/tri", "SAH cost");
    for (i = 0; i < count; i++) {
        int n = nobjs[i];
        const RbSpread *k = &sp[i][0];
        printf("%10d %9.4f  (%7.4f - %7.4f) %5d %8.0f %9ld %6ld %9.2f %10.1f %9.2f\n", n, k->med, k->lo, k->hi,
               rounds[i], k->med / n * 1e9, info[i].nodes, info[i].max_depth,
               (double)info[i].prim_refs / n, (double)info[i].bytes / n, info[i].sah_cost);
        printf("result triangles=%d build_s=%.5f build_best=%.5f build_worst=%.5f nodes=%ld depth=%ld "
               "refs_per_tri=%.3f bytes_per_tri=%.2f sah=%.3f\n", n, k->med, k->lo, k->hi, info[i].nodes,
               info[i].max_depth, (double)info[i].prim_refs / n, (double)info[i].bytes / n, info[i].sah_cost);
    }
    printf("\nThe other structures, the same builds (CPU seconds, median (best - worst), and ns a triangle)\n%10s",
           "triangles");
    for (j = 1; j < 4; j++) printf(" %10s s %19s %6s", rb_names[which[j]], "(best - worst)", "ns/tri");
    printf("\n");
    for (i = 0; i < count; i++) {
        printf("%10d", nobjs[i]);
        for (j = 1; j < 4; j++)
            printf(" %12.4f  (%7.4f - %7.4f) %6.0f", sp[i][j].med, sp[i][j].lo, sp[i][j].hi,
                   sp[i][j].med / nobjs[i] * 1e9);
        printf("\n");
        for (j = 1; j < 4; j++)
            printf("result structure=%s triangles=%d build_s=%.5f build_best=%.5f build_worst=%.5f\n",
                   rb_names[which[j]], nobjs[i], sp[i][j].med, sp[i][j].lo, sp[i][j].hi);
    }
    if (count < 2) {
        printf("(one size only: no exponent)\n");
        return;
    }
    {
        double d = count * sxx - sx * sx, p[4], pb[4];
        for (j = 0; j < 4; j++)
            p[j] = (count * sxy[j] - sx * sy[j]) / d, pb[j] = (count * sxyb[j] - sx * syb[j]) / d;
        printf("build time ~ N^p, least squares on log-log over %d sizes, fitted to the medians (to the best runs):\n ",
               count);
        for (j = 0; j < 4; j++) printf(" %s %.3f (%.3f)%s", rb_names[which[j]], p[j], pb[j], j < 3 ? "," : "\n");
        printf("kd-tree: build time ~ N^%.3f   target: exponent <= 1.15: %s\n", p[0], p[0] <= 1.15 ? "met" : "NOT MET");
        printf("result exponent=%.4f exponent_best=%.4f\n", p[0], pb[0]);
        for (j = 1; j < 4; j++)
            printf("result structure=%s exponent=%.4f exponent_best=%.4f\n", rb_names[which[j]], p[j], pb[j]);
    }
}

/* ------------------------------------------------------------------ main */

static long rb_count(const char *arg, long max)
{
    char *end;
    long v = strtol(arg, &end, 10);
    if (end == arg || *end || v < 1 || v > max) rb_die("expected a whole number, not", arg);
    return v;
}

/* ------------------------------------------------------------ animation */

/* The lecture's question "which structures suit animation?", measured.
 * `raybench anim SCENE.nff FRAMES MOVERS` drops MOVERS balls through the
 * scene (along its NFF up vector, from above its box to below it, over the
 * frames); MOVERS 0 instead moves every sphere of the scene, each turned
 * about the up axis through the box's centre by an angle that grows with
 * its height (a twist: neighbours drift apart).  Each frame, four
 * strategies get the structure up to date and trace 256x256 primary rays
 * from the scene's camera: rebuild the kd-tree, rebuild the BVH, refit the
 * BVH built at frame 0, rebuild the grid; and for falling balls, whose
 * motion is a translation, a fifth: one BVH built at frame 0 over the
 * whole animation as motion blur builds it, each ball bounding its swept
 * box (its velocity the whole fall, the animation one shutter from 0 to
 * 1), and each frame's rays traced at that frame's time.  Per strategy:
 * CPU seconds to build (or refit) and to trace, a frame's mean, and the
 * refitted BVH's trace time against the rebuilt one's as the frames go by.  The whole
 * animation runs ROUNDS times (3 unless given), each from nothing; each
 * figure is the median of the rounds, printed with the least and the
 * greatest. */
typedef struct {
    vec *from;        /* each moving sphere's place at frame 0 */
    int first, count; /* the moving spheres */
    vec up, centre;
    double height;    /* the box's extent along up */
    int twist;
} RbMotion;

static void rb_move(Scene *s, const RbMotion *m, double f)
{
    int k;
    for (k = 0; k < m->count; k++) {
        vec p = m->from[k];
        if (m->twist) {   /* turned about up through the centre */
            vec c = sub(p, m->centre), axial = scale(dot(c, m->up), m->up), r = sub(c, axial);
            vec q = cross(m->up, r);
            double h = dot(c, m->up) / (m->height > 0 ? m->height : 1), a = 3 * f * h;
            p = add(m->centre, add(axial, add(scale((real)cos(a), r), scale((real)sin(a), q))));
        } else
            p = sub(p, scale((real)(f * 2 * m->height), m->up));   /* falls two box heights */
        s->sph[m->first + k].cen = p;
    }
}

static double rb_trace_cpu(const Scene *s, const RbRay *rays, long n, real time)
{
    double c0 = rb_cpu();
    long i;
    for (i = 0; i < n; i++) {
        double o[3], d[3], tmax = INFINITY;
        Query q = rb_query_at(&rays[i], o, d, time);
        if (s->accel.which == ACCEL_KD) kd_nearest(s->accel.kd, &s->accel.prims, o, d, &q, -1, 0, &tmax, NULL);
        else if (s->accel.which == ACCEL_BVH) bvh_nearest(s->accel.bvh, &s->accel.prims, o, d, &q, -1, 0, &tmax, NULL);
        else grid_nearest(s->accel.grid, &s->accel.prims, o, d, &q, -1, 0, &tmax, NULL);
    }
    return rb_cpu() - c0;
}

/* One strategy's frame at time f (0 to 1 over the animation): the
 * structure brought up to date (refit, a new build, or for the swept BVH
 * nothing after frame 0), its CPU seconds in *build; returns the trace's. */
static double rb_frame(Scene *s, int strategy, const RbRay *rays, long n, double f, double *build)
{
    double c0 = rb_cpu();
    if (strategy == 2 && s->accel.bvh) bvh_refit(s->accel.bvh, &s->accel.prims);
    else if (strategy == 4 && s->accel.bvh) {}
    else {
        if (s->accel.kd) kd_free(s->accel.kd), s->accel.kd = NULL;
        if (s->accel.bvh) bvh_free(s->accel.bvh), s->accel.bvh = NULL;
        if (s->accel.grid) grid_free(s->accel.grid), s->accel.grid = NULL;
        if (!build_accel(s, strategy == 0 ? "kd" : strategy == 3 ? "grid" : "bvh")) exit(1);
    }
    *build = rb_cpu() - c0;
    return rb_trace_cpu(s, rays, n, strategy == 4 ? (real)f : 0);
}

#define RB_ANIM_ROUNDS_MAX 9
static void rb_anim(const char *path, int frames, int movers, int rounds)
{
    static const char *const names[5] = { "rebuild kd", "rebuild BVH", "refit BVH", "rebuild grid",
                                           "swept BVH" };
    Scene s[5];
    RbMotion m;
    RbRay *rays;
    double eye[3], at[3], up[3], fov, lo[3], hi[3];
    double bms[5][RB_ANIM_ROUNDS_MAX], tms[5][RB_ANIM_ROUNDS_MAX], all[5][RB_ANIM_ROUNDS_MAX];
    double ratio[3][RB_ANIM_ROUNDS_MAX];
    RbSpread bs[5], ts[5], as[5], rs[3];
    int k, f, a, w = 256, round, ns = movers > 0 ? 5 : 4;   /* a twist is no translation */
    if (!rb_nff_view(path, eye, at, up, &fov)) rb_die("no view in", path);
    for (k = 0; k < ns; k++) {
        default_scene(&s[k]);
        if (!load_scene(&s[k], path)) exit(1);
    }
    memset(&m, 0, sizeof m);
    m.up = unit(v3(up[0], up[1], up[2]));
    build_accel(&s[0], "none");   /* the callbacks, for the box */
    for (a = 0; a < 3; a++) lo[a] = HUGE_VAL, hi[a] = -HUGE_VAL;
    for (k = 0; k < nobj(&s[0]); k++) {
        double l[3], h[3];
        prim_bounds(&s[0], k, l, h);
        for (a = 0; a < 3; a++) lo[a] = fmin(lo[a], l[a]), hi[a] = fmax(hi[a], h[a]);
    }
    m.centre = v3((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2);
    m.height = fabs((hi[0] - lo[0]) * m.up.x) + fabs((hi[1] - lo[1]) * m.up.y) + fabs((hi[2] - lo[2]) * m.up.z);
    m.twist = movers == 0;
    rb_state = 7;
    for (k = 0; k < ns; k++) {   /* the same balls in each copy */
        uint64_t seed = rb_state;
        int j;
        if (m.twist) break;
        for (j = 0; j < movers; j++) {
            vec p = v3(lo[0] + (hi[0] - lo[0]) * rb_uniform(), lo[1] + (hi[1] - lo[1]) * rb_uniform(),
                       lo[2] + (hi[2] - lo[2]) * rb_uniform());
            p = add(p, scale((real)(m.height * (1 + rb_uniform())), m.up));   /* above the box */
            add_sphere(&s[k], p, (real)(0.01 * m.height), rb_white(&s[k]));
        }
        if (k < ns - 1) rb_state = seed;
    }
    m.first = m.twist ? 0 : s[0].nsph - movers;
    m.count = m.twist ? s[0].nsph : movers;
    m.from = malloc(((size_t)m.count + 1) * sizeof *m.from);
    if (!m.from) rb_die("out of memory", NULL);
    for (k = 0; k < m.count; k++) m.from[k] = s[0].sph[m.first + k].cen;
    if (ns == 5) {              /* the swept copy: each ball's whole fall as its velocity */
        for (k = 0; k < m.count; k++) s[4].sph[m.first + k].move = scale((real)(-2 * m.height), m.up);
        s[4].moving = m.count;
        s[4].shutter[0] = 0, s[4].shutter[1] = 1;
    }
    for (k = 0; k < ns; k++) build_accel(&s[k], "none");
    rays = rb_primary(&s[0], w, w, path);
    printf("animation %s: %d objects, %s, %d frames, %dx%d primary rays a frame, one thread, CPU time;\n"
           "%d rounds of every frame, the %d strategies taking turns at each frame\n",
           path, nobj(&s[0]), m.twist ? "every sphere twisted about the up axis" : "balls falling through",
           frames, w, w, rounds, ns);
    printf("%6s", "frame");
    for (k = 0; k < ns; k++) printf("  %-12s build/trace ms", names[k]);
    printf("   (the first round)\n");
    for (round = 0; round < rounds; round++) {
        double build[5] = { 0 }, trace[5] = { 0 };
        for (k = 0; k < ns; k++) {   /* each round starts from nothing: frame 0 builds */
            if (s[k].accel.kd) kd_free(s[k].accel.kd), s[k].accel.kd = NULL;
            if (s[k].accel.bvh) bvh_free(s[k].accel.bvh), s[k].accel.bvh = NULL;
            if (s[k].accel.grid) grid_free(s[k].accel.grid), s[k].accel.grid = NULL;
        }
        for (f = 0; f < frames; f++) {
            double b[5], t[5], at_f = (double)f / (frames > 1 ? frames - 1 : 1);
            for (k = 0; k < ns; k++) {
                if (k < 4) rb_move(&s[k], &m, at_f);    /* the swept copy stays at frame 0 */
                t[k] = rb_frame(&s[k], k, rays, (long)w * w, at_f, &b[k]);
                build[k] += b[k], trace[k] += t[k];
            }
            if (f == 0) ratio[0][round] = t[2] / t[1];
            if (f == frames / 2) ratio[1][round] = t[2] / t[1];
            ratio[2][round] = t[2] / t[1];
            if (round == 0 && (f % 10 == 0 || f == frames - 1)) {
                printf("%6d", f);
                for (k = 0; k < ns; k++) printf("  %8.2f / %7.2f            ", b[k] * 1e3, t[k] * 1e3);
                printf("\n");
            }
        }
        for (k = 0; k < ns; k++) {
            bms[k][round] = build[k] / frames * 1e3, tms[k][round] = trace[k] / frames * 1e3;
            all[k][round] = bms[k][round] + tms[k][round];
        }
    }
    for (k = 0; k < ns; k++)
        bs[k] = rb_spread(bms[k], rounds), ts[k] = rb_spread(tms[k], rounds), as[k] = rb_spread(all[k], rounds);
    for (k = 0; k < 3; k++) rs[k] = rb_spread(ratio[k], rounds);
    printf("per frame, mean over the frames, ms: the median of the %d rounds (least - greatest)\n", rounds);
    for (k = 0; k < ns; k++)
        printf("  %-12s build %8.2f (%.2f - %.2f) + trace %7.2f (%.2f - %.2f) = %8.2f (%.2f - %.2f)\n", names[k],
               bs[k].med, bs[k].lo, bs[k].hi, ts[k].med, ts[k].lo, ts[k].hi, as[k].med, as[k].lo, as[k].hi);
    printf("refitted BVH's trace time over a rebuilt one's (median of the rounds): frame 0 %.2f, frame %d %.2f, "
           "frame %d %.2f\n", rs[0].med, frames / 2, rs[1].med, frames - 1, rs[2].med);
    for (k = 0; k < ns; k++)
        printf("result anim=%s strategy=%d build_ms=%.3f build_lo=%.3f build_hi=%.3f trace_ms=%.3f trace_lo=%.3f "
               "trace_hi=%.3f total_ms=%.3f total_lo=%.3f total_hi=%.3f\n", m.twist ? "twist" : "fall", k,
               bs[k].med, bs[k].lo, bs[k].hi, ts[k].med, ts[k].lo, ts[k].hi, as[k].med, as[k].lo, as[k].hi);
    printf("result anim=%s refit_ratio_first=%.3f refit_ratio_mid=%.3f refit_ratio_last=%.3f\n",
           m.twist ? "twist" : "fall", rs[0].med, rs[1].med, rs[2].med);
    free(rays), free(m.from);
    for (k = 0; k < ns; k++) rb_free_scene(&s[k]);
}

/* ------------------------------------------------- far from the origin */

/* `raybench far SCENE W H N` asks whether each structure keeps its speed
 * when the scene lies far from the origin or the camera far from the scene.
 * The scene is loaded again for each configuration and moved, in memory,
 * by (off, off, off) as if its file said so (vertices, centres and bases
 * moved, each triangle's edges recomputed from its moved vertices): at the
 * origin, and offset by 1e4, 1e6 and 1e8; its W x H primary rays (from the
 * scene's camera, as `accel` makes them) and N random rays (origins in the
 * box x1.5) are moved with it.  Then, the scene at the origin, the camera is
 * moved back along its line of sight to 1e10 and 1e13 from the point it
 * looks at, its field of view narrowed to frame the same picture.  The rays
 * are made and kept in double here: a float could not hold an origin at
 * 1e8 to better than 8 units.  Every structure (kd, bvh, grid) is traced on
 * every configuration in each of RB_ROUNDS rounds, structures and
 * configurations taking turns; Mrays/s by thread CPU time, best, median and
 * worst round, and each median over the structure's median at the origin.
 * Every 16th ray is also asked of a loop over every object, and each
 * structure's answers (object, bitwise t) must be the loop's. */
typedef struct { double o[3], d[3]; } RbDRay;

#define RB_FAR_N 6
static const char *const rb_far_names[RB_FAR_N] = {
    "origin", "offset1e4", "offset1e6", "offset1e8", "camera1e10", "camera1e13"
};
static const double rb_far_off[RB_FAR_N] = { 0, 1e4, 1e6, 1e8, 0, 0 };
static const double rb_far_dist[RB_FAR_N] = { 0, 0, 0, 0, 1e10, 1e13 };
static const char *const rb_far_accels[3] = { "kd", "bvh", "grid" };

typedef struct {
    Scene s;
    kd_tree *kd;
    bvh *bvh;
    grid *grid;
    RbDRay *rays[2];     /* primary, random (NULL: none) */
    long n[2];
    int *want[2];        /* the loop's answer on every 16th ray */
    double *want_t[2];
} RbFar;

static void rb_far_translate(Scene *s, double off)
{
    vec o = v3(off, off, off);
    int i;
    for (i = 0; i < s->nvert; i++) s->vert[i] = add(s->vert[i], o);
    for (i = 0; i < s->nsph; i++) s->sph[i].cen = add(s->sph[i].cen, o);
    for (i = 0; i < s->ncone; i++) s->cone[i].base = add(s->cone[i].base, o);
    for (i = 0; i < s->nlight; i++) s->light[i].pos = add(s->light[i].pos, o);
    for (i = 0; i < s->ntri; i++) {   /* as add_triangle computes them */
        Triangle *tr = &s->tri[i];
        vec a = s->vert[tr->v[0]], b = s->vert[tr->v[1]], c = s->vert[tr->v[2]];
        tr->v0 = a;
        tr->e1 = sub(b, a);
        tr->e2 = sub(c, a);
        tr->degenerate = (char)degenerate(a, b, c);
    }
}

/* Primary rays as rb_primary makes them, in double, from a camera moved by
 * off, or moved back to dist from the point it looks at (rb_camera). */
static RbDRay *rb_far_primary(const Scene *s, int w, int h, const char *view, double off, double dist)
{
    RbCamera c = rb_camera(s, view, dist);
    RbDRay *rays = malloc((size_t)w * h * sizeof *rays);
    int x, y, k;
    if (!rays) rb_die("out of memory for primary rays", NULL);
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            RbDRay *ry = &rays[(size_t)y * w + x];
            rb_pixel(&c, w, h, x, y, ry->d);
            for (k = 0; k < 3; k++) ry->o[k] = c.eye[k] + off;
        }
    return rays;
}

/* rb_random's rays (seed 1), in double, moved by off. */
static RbDRay *rb_far_random(const Scene *s, long n, double off)
{
    RbRay *r = rb_random(s, n, 1);
    RbDRay *rays = malloc((size_t)n * sizeof *rays);
    long i;
    int k;
    if (!rays) rb_die("out of memory for random rays", NULL);
    for (i = 0; i < n; i++)
        for (k = 0; k < 3; k++) rays[i].o[k] = r[i].o[k] + off, rays[i].d[k] = r[i].d[k];
    free(r);
    return rays;
}

/* The nearest hit of ray r through structure which (0 kd, 1 bvh, 2 grid,
 * 3 the loop over every object), its t in *t. */
static int rb_far_nearest(const RbFar *F, int which, const RbDRay *r, double *t, prim_counters *c)
{
    const prims *p = &F->s.accel.prims;
    Ray ry;
    Query q;
    int i, best = -1, n = nobj(&F->s);
    ry.o = v3(r->o[0], r->o[1], r->o[2]), ry.d = v3(r->d[0], r->d[1], r->d[2]);
    ry.skip = -1, ry.tmin = 0, ry.time = 0;
    q = query(ry);
    *t = INFINITY;
    switch (which) {
    case 0: return kd_nearest(F->kd, p, r->o, r->d, &q, -1, 0, t, c);
    case 1: return bvh_nearest(F->bvh, p, r->o, r->d, &q, -1, 0, t, c);
    case 2: return grid_nearest(F->grid, p, r->o, r->d, &q, -1, 0, t, c);
    }
    for (i = 0; i < n; i++) {
        double th;
        if (p->hit(p->user, i, &q, 0, *t, &th) && th < *t) *t = th, best = i;
    }
    return best;
}

static void rb_far_setup(RbFar *F, const char *path, int cfg, int w, int h, long nrand)
{
    const char *dot = strrchr(path, '.');
    int nff = dot && !strcmp(dot, ".nff"), k;
    long i;
    memset(F, 0, sizeof *F);
    if (nff) {
        default_scene(&F->s);
        if (!load_scene(&F->s, path)) exit(1);
    } else
        rb_load_mesh(&F->s, path);
    F->rays[0] = rb_far_primary(&F->s, w, h, nff ? path : NULL, rb_far_off[cfg], rb_far_dist[cfg]);
    F->n[0] = (long)w * h;
    if (rb_far_dist[cfg] == 0) F->rays[1] = rb_far_random(&F->s, nrand, rb_far_off[cfg]), F->n[1] = nrand;
    rb_far_translate(&F->s, rb_far_off[cfg]);
    if (!build_accel(&F->s, "none")) exit(1);
    F->kd = kd_build(nobj(&F->s), &F->s.accel.prims);
    F->bvh = bvh_build(nobj(&F->s), &F->s.accel.prims, BVH_SAH);
    F->grid = grid_build(nobj(&F->s), &F->s.accel.prims);
    if (!F->kd || !F->bvh || !F->grid) rb_die("out of memory building the structures", NULL);
    for (k = 0; k < 2; k++) {
        if (!F->rays[k]) continue;
        F->want[k] = malloc(((size_t)F->n[k] / 16 + 1) * sizeof(int));
        F->want_t[k] = malloc(((size_t)F->n[k] / 16 + 1) * sizeof(double));
        if (!F->want[k] || !F->want_t[k]) rb_die("out of memory", NULL);
        for (i = 0; i < F->n[k]; i += 16)
            F->want[k][i / 16] = rb_far_nearest(F, 3, &F->rays[k][i], &F->want_t[k][i / 16], NULL);
    }
}

static void rb_far_free(RbFar *F)
{
    int k;
    kd_free(F->kd), bvh_free(F->bvh), grid_free(F->grid);
    F->s.accel.kd = NULL, F->s.accel.bvh = NULL, F->s.accel.grid = NULL;
    for (k = 0; k < 2; k++) free(F->rays[k]), free(F->want[k]), free(F->want_t[k]);
    rb_free_scene(&F->s);
}

/* One pass of structure which over ray set k of F: thread CPU seconds. */
static double rb_far_pass(const RbFar *F, int which, int k, prim_counters *c, long *differ)
{
    double c0 = rb_cpu(), t;
    long i;
    for (i = 0; i < F->n[k]; i++) {
        int got = rb_far_nearest(F, which, &F->rays[k][i], &t, c);
        if (differ && i % 16 == 0
            && (got != F->want[k][i / 16] || memcmp(&t, &F->want_t[k][i / 16], sizeof t)))
            ++*differ;
    }
    return rb_cpu() - c0;
}

static void rb_far(const char *path, int w, int h, long nrand)
{
    RbFar *F = malloc(RB_FAR_N * sizeof *F);
    double secs[RB_FAR_N][3][2][RB_ROUNDS], med0[3][2] = { { 0 } };
    prim_counters c[RB_FAR_N][3][2];
    long differ[RB_FAR_N][3][2];
    static char res[RB_FAR_N][3][2][256];   /* the result lines, printed after the table */
    int cfg, a, k, r;
    if (!F) rb_die("out of memory", NULL);
    for (cfg = 0; cfg < RB_FAR_N; cfg++) rb_far_setup(&F[cfg], path, cfg, w, h, nrand);
    memset(c, 0, sizeof c), memset(differ, 0, sizeof differ);
    for (cfg = 0; cfg < RB_FAR_N; cfg++)   /* untimed: the work, and the answers against the loop */
        for (a = 0; a < 3; a++)
            for (k = 0; k < 2; k++)
                if (F[cfg].rays[k]) rb_far_pass(&F[cfg], a, k, &c[cfg][a][k], &differ[cfg][a][k]);
    for (r = 0; r < RB_ROUNDS; r++)
        for (cfg = 0; cfg < RB_FAR_N; cfg++)
            for (a = 0; a < 3; a++)
                for (k = 0; k < 2; k++)
                    if (F[cfg].rays[k]) secs[cfg][a][k][r] = rb_far_pass(&F[cfg], a, k, NULL, NULL);
    printf("far from the origin: %s, %d objects; %dx%d primary rays, %ld random; Mrays/s by thread CPU time,\n"
           "best / median / worst of %d rounds, the structures and configurations taking turns; ratio: the\n"
           "median over the same structure's at the origin; steps and tests per ray; answers: every 16th ray\n"
           "against the loop over every object (object and bitwise t)\n", path, nobj(&F[0].s), w, h, nrand,
           RB_ROUNDS);
    printf("%-11s %-5s  %-20s %6s %6s %7s  %-20s %6s %6s %7s  %s\n", "config", "accel", "primary Mrays/s",
           "ratio", "steps", "tests", "random Mrays/s", "ratio", "steps", "tests", "answers");
    for (cfg = 0; cfg < RB_FAR_N; cfg++)
        for (a = 0; a < 3; a++) {
            double fig[2][3];
            printf("%-11s %-5s", rb_far_names[cfg], rb_far_accels[a]);
            for (k = 0; k < 2; k++) {
                double mr[RB_ROUNDS];
                long n = F[cfg].n[k];
                if (!F[cfg].rays[k]) {
                    printf("  %-20s %6s %6s %7s", "-", "-", "-", "-");
                    continue;
                }
                for (r = 0; r < RB_ROUNDS; r++) mr[r] = n / secs[cfg][a][k][r] * 1e-6;
                qsort(mr, RB_ROUNDS, sizeof mr[0], rb_cmp_double);
                fig[k][0] = mr[RB_ROUNDS - 1], fig[k][1] = mr[RB_ROUNDS / 2], fig[k][2] = mr[0];
                if (cfg == 0) med0[a][k] = fig[k][1];
                printf("  %6.2f %6.2f %6.2f %6.3f %6.1f %7.2f", fig[k][0], fig[k][1], fig[k][2],
                       fig[k][1] / med0[a][k], (double)c[cfg][a][k].steps / n, (double)c[cfg][a][k].tests / n);
            }
            printf("  %s\n", differ[cfg][a][0] + differ[cfg][a][1] ? "DIFFER from the loop" : "same as the loop");
            for (k = 0; k < 2; k++)
                if (F[cfg].rays[k])
                    sprintf(res[cfg][a][k], "result far=%s accel=%s set=%s rays=%ld best=%.4f median=%.4f "
                            "worst=%.4f ratio=%.4f steps=%.3f tests=%.3f differ=%ld\n", rb_far_names[cfg],
                            rb_far_accels[a], k ? "random" : "primary", F[cfg].n[k], fig[k][0], fig[k][1],
                            fig[k][2], fig[k][1] / med0[a][k], (double)c[cfg][a][k].steps / F[cfg].n[k],
                            (double)c[cfg][a][k].tests / F[cfg].n[k], differ[cfg][a][k]);
        }
    for (cfg = 0; cfg < RB_FAR_N; cfg++)
        for (a = 0; a < 3; a++)
            for (k = 0; k < 2; k++) printf("%s", res[cfg][a][k]);
    for (cfg = 0; cfg < RB_FAR_N; cfg++) rb_far_free(&F[cfg]);
    free(F);
}

/* The rays made here for `made` and `accel`: W x H primary rays (arg[0],
 * arg[1]) from the view, then N random ones (arg[2]), each set handed to
 * trace with ctx. */
typedef void rb_tracer(void *ctx, const char *set, const RbRay *rays, long n);
static void rb_made(Scene *s, char **arg, const char *view, rb_tracer *trace, void *ctx)
{
    int w = (int)rb_count(arg[0], 32768), h = (int)rb_count(arg[1], 32768);
    long n = rb_count(arg[2], 100000000);
    RbRay *rays = rb_primary(s, w, h, view);
    trace(ctx, "primary", rays, (long)w * h);
    free(rays);
    rays = rb_random(s, n, 1);
    trace(ctx, "random", rays, n);
    free(rays);
}

static void rb_kd_trace(void *s, const char *set, const RbRay *rays, long n)
{
    rb_rays(s, set, rays, n);
}

static void rb_accel_trace(void *A, const char *set, const RbRay *rays, long n)
{
    rb_accel_set(A, set, rays, n);
}

static void rb_usage(void)
{
    fputs("usage: raybench build [MAXN]\n"
          "       raybench rays MESH.obj RAYS.bin...     (RAYHITS1, from embree_rays -out)\n"
          "       raybench made MESH.obj W H N [VIEW.nff] (W x H primary and N random rays)\n"
          "       raybench accel SCENE W H N [VIEW.nff]   (every structure on W x H primary and N\n"
          "                                                random rays; SCENE .obj or .nff)\n"
          "       raybench accel SCENE RAYS.bin...        (every structure on RAYHITS1 rays)\n"
          "       raybench anim SCENE.nff FRAMES MOVERS [ROUNDS]\n"
          "                                               (rebuild or refit as objects move; 3 rounds)\n"
          "       raybench far SCENE W H N                (kd, bvh, grid with the scene moved to 1e4, 1e6,\n"
          "                                                1e8 and the camera to 1e10, 1e13)\n", stderr);
    exit(2);
}

int main(int argc, char **argv)
{
    Scene s;
    if (argc < 2) rb_usage();
    if (!strcmp(argv[1], "build") && argc <= 3) {
        rb_build_table(argc == 3 ? rb_count(argv[2], 100000000) : 1000000);
        return 0;
    }
    if (!strcmp(argv[1], "anim") && (argc == 5 || argc == 6)) {
        rb_anim(argv[2], (int)rb_count(argv[3], 100000), (int)strtol(argv[4], NULL, 10),
                argc == 6 ? (int)rb_count(argv[5], RB_ANIM_ROUNDS_MAX) : 3);
        return 0;
    }
    if (!strcmp(argv[1], "far") && argc == 6) {
        rb_far(argv[2], (int)rb_count(argv[3], 32768), (int)rb_count(argv[4], 32768), rb_count(argv[5], 100000000));
        return 0;
    }
    if (!strcmp(argv[1], "accel") && argc >= 4) {
        RbAll A;
        const char *dot = strrchr(argv[3], '.');
        rb_load_any(&s, &A, argv[2]);
        if (dot && !strcmp(dot, ".bin")) {
            int k;
            for (k = 3; k < argc; k++) {
                long n;
                RbRay *rays = rb_read_rayhits(argv[k], &n);
                rb_accel_set(&A, strstr(argv[k], "random") ? "random" : "primary", rays, n);
                free(rays);
            }
        } else if (argc == 6 || argc == 7) {
            const char *sdot = strrchr(argv[2], '.');
            rb_made(&s, argv + 3, argc == 7 ? argv[6] : sdot && !strcmp(sdot, ".nff") ? argv[2] : NULL,
                    rb_accel_trace, &A);
        } else
            rb_usage();
        rb_free_all(&A);
        rb_free_scene(&s);
        return 0;
    }
    if (!strcmp(argv[1], "rays") && argc >= 4) {
        int k;
        rb_mesh(&s, argv[2]);
        for (k = 3; k < argc; k++) {
            /* the set's name: the file's, without directory and .bin */
            char set[256], *dot;
            const char *base = strrchr(argv[k], '/') ? strrchr(argv[k], '/') + 1 : argv[k];
            long n;
            RbRay *rays = rb_read_rayhits(argv[k], &n);
            sprintf(set, "%.200s", base);
            if ((dot = strrchr(set, '.')) && !strcmp(dot, ".bin")) *dot = 0;
            rb_rays(&s, set, rays, n);
            free(rays);
        }
    } else if (!strcmp(argv[1], "made") && (argc == 6 || argc == 7)) {
        rb_mesh(&s, argv[2]);
        rb_made(&s, argv + 3, argc == 7 ? argv[6] : NULL, rb_kd_trace, &s);
    } else
        rb_usage();
    rb_free_scene(&s);
    return 0;
}

/* fuzz_scene.c - a libFuzzer target for ray.c's scene readers, built once
 * per format by `make fuzz` (clang, -fsanitize=fuzzer,address,undefined):
 *
 *     -DFORMAT=SPH   the input is a scene in the sphere format
 *     -DFORMAT=NFF   the input is an NFF scene
 *     -DFORMAT=OBJ   the input is an OBJ mesh, read through a `mesh` line
 *
 * The readers take file names, so each input is written to a file in a
 * directory of this process's own under /tmp, with the format's extension
 * (for OBJ, beside a .sph that says `mesh in.obj ...`).  If it loads, it is
 * rendered tiny (8x8, 1 sample, depth 4, at most MAX_OBJECTS objects and
 * MAX_LIGHTS lights, so that no input takes long):
 *   - by Whitted's tracer through the kd-tree and through the loop over every
 *     object (--accel kd and none): the two images must be the same, bit for
 *     bit in floats (what -o x.pfm writes), as the tests check whole pixels;
 *     and no NaN;
 *   - by the path tracer (at most 8 rays a path): no NaN in its output.
 * The floats are checked, not the bytes: to_byte turns a NaN into a quiet
 * black, and agreeing bytes can hide a small difference.
 * Either failing calls abort(), which libFuzzer reports with the input.
 *
 * ray.c is included whole, as tests/test_ray.c does, so that its static
 * functions can be called; its main() is renamed out of the way.
 *
 * To reproduce a finding: build/fuzz/fuzz_sph FILE (the reader's messages
 * and what differs are printed on stderr; make fuzz hides stderr). */
#define main ray_main
#include "../ray.c"
#undef main

#include <unistd.h>

#define SPH 1
#define NFF 2
#define OBJ 3
#ifndef FORMAT
#error "build with -DFORMAT=SPH, NFF or OBJ"
#endif

#define MAX_OBJECTS 256     /* more are read, but not rendered */
#define MAX_LIGHTS 16
#define SIZE 8
#define DEPTH 4
#define PATH_RAYS 8

static char dir[64];

static void write_file(const char *name, const void *data, size_t n)
{
    char path[128];
    FILE *f;
    sprintf(path, "%s/%s", dir, name);
    /* a new file, not the old one truncated: ext4 flushes a file rewritten
     * in place when it is closed (auto_da_alloc), 6 ms an input */
    remove(path);
    f = fopen(path, "wb");
    if (!f || fwrite(data, 1, n, f) != n || fclose(f) != 0) {
        fprintf(stderr, "fuzz_scene: cannot write %s\n", path);
        abort();
    }
}

static void remove_dir(void)
{
    static const char *const names[] = { "in.sph", "in.nff", "in.obj", "ball.obj" };
    char path[128];
    size_t i;
    for (i = 0; i < sizeof names / sizeof *names; i++) {
        sprintf(path, "%s/%s", dir, names[i]);
        remove(path);
    }
    rmdir(dir);
}

/* The temporary directory, with a small OBJ beside the scene as ball.obj:
 * scenes/mesh.sph, a seed, names one. */
int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    static const char ball[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                               "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";
    (void)argc, (void)argv;
    strcpy(dir, "/tmp/rayfuzz.XXXXXX");
    if (!mkdtemp(dir)) {
        perror("fuzz_scene: mkdtemp");
        abort();
    }
    write_file("ball.obj", ball, sizeof ball - 1);
    atexit(remove_dir);
    return 0;
}

/* kdtree.c keeps its boxes in float, and says that coordinates beyond the
 * float range are clamped to it, and a primitive that reaches out there is
 * not supported: issue 13 found the tree's hits wrong above about 1e38, and
 * --accel none right (scenes/minray.sph scaled by 1e38: 48% of the channels
 * differ).  Such a scene (any object's box, the eye or a light beyond 1e37)
 * is rendered both ways, but the two images are not compared.  Nor are they
 * searched for NaN: beyond 1e154 a squared distance overflows, and issue 13
 * asks for such scenes to be refused with a true message, not for their
 * pixels; within 1e37 none can, so there a NaN is a bug.  (Issue 13 also
 * saw the tree wrong for scenes below 1e-41; scenes/demo.nff and minray.sph
 * scaled down to 1e-44 render the same both ways today, and so the tiny are
 * compared: if that fails again, the fuzzer will say so.) */
static int out_of_range(double x) { return fabs(x) > 1e37; }

static int beyond_float_range(Scene *s)
{
    double lo[3], hi[3];
    int i, a;
    for (i = 0; i < nobj(s); i++) {
        prim_bounds(s, i, lo, hi);
        for (a = 0; a < 3; a++)
            if (out_of_range(lo[a]) || out_of_range(hi[a])) return 1;
    }
    for (i = 0; i <= s->nlight; i++) {
        vec p = i < s->nlight ? s->light[i].pos : s->cam.eye;
        if (out_of_range(p.x) || out_of_range(p.y) || out_of_range(p.z)) return 1;
    }
    return 0;
}

/* Bugs of ray.c that fuzzing found, reported with a reproducer in
 * fuzz/crashes-found/ and not fixed yet.  An input that would trip one is
 * not rendered, or not checked, the way that trips it, so that fuzzing goes
 * on to find others, in CI too.  Built with -DFUZZ_KNOWN_BUGS (make fuzz
 * FUZZ_KNOWN_BUGS=1) the targets trip them again: to check a fix, after
 * which its step-around here goes.
 *   1. cone_glow: the path tracer (MIS) reads s->emit[-1] when a bounce
 *      hits a cone with kl > 0 (cones glow but are no lights: emitter -1).
 *   2. nan_refract: with an index of refraction beyond about 1e8 (or below
 *      1e-8) refract() returns a direction far from unit length, and a Phong
 *      highlight at the next hit makes pow(huge, shine) = inf, then NaN.
 *   3. nan_huge: a colour, weight or light near the largest double (1e308)
 *      overflows to inf in the sums, and inf times 0 is NaN.
 *   4. cone_flat: a cone whose length is below the rounding error of its
 *      heights (1e-71 against radii of 0.3) is hit where it has no surface
 *      (at the eye, outside its rim); the tree, whose box leaves out some of
 *      those points, then differs from the loop.
 * (2 to 4 are numbers the readers should refuse; the pixels go black.) */
#ifdef FUZZ_KNOWN_BUGS
static int known_bug_in_path_tracer(const Scene *s) { (void)s; return 0; }
static int known_nan(const Scene *s) { (void)s; return 0; }
static int known_difference(const Scene *s) { (void)s; return 0; }
#else
static int known_bug_in_path_tracer(const Scene *s)
{
    int i;
    for (i = 0; i < s->ncone; i++)
        if (s->mat[s->cone[i].mat].kl > 0) return 1;
    return 0;
}

static int huge(vec v) { return fabs(v.x) > 1e37 || fabs(v.y) > 1e37 || fabs(v.z) > 1e37; }

static int known_nan(const Scene *s)
{
    int i;
    if (huge(s->ambient) || huge(s->background)) return 1;
    for (i = 0; i < s->nlight; i++)
        if (huge(s->light[i].color)) return 1;
    for (i = 0; i < s->nmat; i++) {
        const Material *m = &s->mat[i];
        if (huge(m->color) || huge(v3(m->kd, m->ks, m->kt)) || fabs(m->kl) > 1e37
            || !(fabs(m->ir) >= 1e-6 && fabs(m->ir) <= 1e6)) return 1;
    }
    return 0;
}

static int known_difference(const Scene *s)
{
    int i;
    for (i = 0; i < s->ncone; i++) {
        const Cone *c = &s->cone[i];
        if (c->len < 1e-9 * (fmax(c->rb, c->ra) + maxabs(c->base))) return 1;
    }
    return 0;
}
#endif

#if FORMAT == OBJ
/* A camera that sees the whole mesh from outside its box, and a light
 * beside the eye; 0 when the box gives no such view (empty, not finite). */
static int frame_mesh(Scene *s)
{
    double lo[3] = { INFINITY, INFINITY, INFINITY }, hi[3] = { -INFINITY, -INFINITY, -INFINITY };
    double c[3], size = 0;
    real v[10];
    int i, a;
    for (i = 0; i < s->nvert; i++) {
        double p[3];
        to3(s->vert[i], p);
        for (a = 0; a < 3; a++) lo[a] = fmin(lo[a], p[a]), hi[a] = fmax(hi[a], p[a]);
    }
    for (a = 0; a < 3; a++) {
        c[a] = lo[a] / 2 + hi[a] / 2;
        size = fmax(size, hi[a] - lo[a]);
    }
    if (!(size > 0 && size < 1e300)) return 0;
    v[0] = c[0] + 0.6 * size, v[1] = c[1] - 2 * size, v[2] = c[2] + 0.9 * size;
    v[3] = c[0], v[4] = c[1], v[5] = c[2];
    v[6] = 0, v[7] = 0, v[8] = 1, v[9] = 50;
    if (!set_camera(s, (Where){ "fuzz", 0 }, v)) return 0;
    add_light(s, v3(v[0] - 0.5 * size, v[1], v[2] + size), v3(1, 1, 1), -1);
    return 1;
}
#endif

#if FORMAT == SPH
/* A mesh line may name only a file beside the scene, in the temporary
 * directory: a path could reach /dev/stdin, which waits for input that never
 * comes, or any other file of the machine.  So an input is skipped when a
 * word that ends with "mesh" (in any case, after any byte-order mark) is
 * followed by a word with a '/' in it, words being parted by any blank or
 * NUL byte: more than ray.c takes for a mesh line, never less. */
static int names_a_path(const uint8_t *data, size_t size)
{
    size_t i = 0, start, n;
    int after_mesh = 0;
    for (;;) {
        while (i < size && (data[i] == 0 || isspace(data[i]))) i++;
        if (i == size) return 0;
        for (start = i; i < size && data[i] != 0 && !isspace(data[i]); i++) {}
        n = i - start;
        if (after_mesh && memchr(data + start, '/', n)) return 1;
        after_mesh = n >= 4 && tolower(data[i - 4]) == 'm' && tolower(data[i - 3]) == 'e'
                     && tolower(data[i - 2]) == 's' && tolower(data[i - 1]) == 'h';
    }
}
#endif

/* The scene rendered into img, in floats: 1 sample, 1 thread, no progress
 * line.  With check_nan, a NaN in it aborts, naming `what`. */
static void render_tiny(Scene *s, Image *img, const char *what, int check_nan)
{
    Options o = { 1, 1, 0 };
    Counts c;
    int k;
    memset(&c, 0, sizeof c);
    if (!new_image(img, s->w, s->h, 1, 0)) abort();
    render(s, &o, img, &c);
    for (k = 0; k < 3 * s->w * s->h && check_nan; k++)
        if (isnan(img->floats[k])) {
            fprintf(stderr, "fuzz_scene: %s: NaN at pixel (%d, %d) channel %d\n", what,
                    k / 3 % s->w, k / 3 / s->w, k % 3);
            abort();
        }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    Scene s;
    Image tree, loop, path;
    char scene[128];
    size_t k;
    int in_range, check_nan, compare;
#if FORMAT == SPH
    if (names_a_path(data, size)) return 0;
    write_file("in.sph", data, size);
    sprintf(scene, "%s/in.sph", dir);
#elif FORMAT == NFF
    write_file("in.nff", data, size);
    sprintf(scene, "%s/in.nff", dir);
#else
    {
        static const char sph[] = "mesh in.obj  .9 .8 .7  .6 .3 .2 0 1.5\n";
        write_file("in.obj", data, size);
        write_file("in.sph", sph, sizeof sph - 1);
        sprintf(scene, "%s/in.sph", dir);
    }
#endif
    if (!load_scene(&s, scene) || nobj(&s) > MAX_OBJECTS || s.nlight > MAX_LIGHTS
#if FORMAT == OBJ
        || !frame_mesh(&s)
#endif
        ) {
        free_scene(&s);
        return 0;
    }
    s.w = s.h = SIZE;
    if (s.depth > DEPTH) s.depth = DEPTH;
    in_range = !beyond_float_range(&s);
    check_nan = in_range && !known_nan(&s);
    compare = in_range && !known_difference(&s);

    /* Whitted's, through the tree and through the loop */
    s.integrator = WHITTED;
    if (!build_accel(&s, "kd")) abort();
    render_tiny(&s, &tree, "Whitted, kd-tree", check_nan);
    s.accel = ACCEL_NONE;
    render_tiny(&s, &loop, "Whitted, loop", check_nan);
    s.accel = ACCEL_KD;
    for (k = 0; k < (size_t)3 * SIZE * SIZE && compare; k++)
        if (memcmp(&tree.floats[k], &loop.floats[k], sizeof *tree.floats) != 0) {
            fprintf(stderr, "fuzz_scene: pixel (%d, %d) channel %d: %.9g through the kd-tree, "
                    "%.9g through the loop\n", (int)(k / 3 % SIZE), (int)(k / 3 / SIZE),
                    (int)(k % 3), tree.floats[k], loop.floats[k]);
            abort();
        }
    free(tree.floats);
    free(loop.floats);

    /* The path tracer, through the tree */
    if (s.max_rays == 0 || s.max_rays > PATH_RAYS) s.max_rays = PATH_RAYS;
    if (!known_bug_in_path_tracer(&s) && settle_path_options(&s, PATH, -1, 1, -1)) {
        render_tiny(&s, &path, "path tracer", check_nan);
        free(path.floats);
    }
    free_scene(&s);
    return 0;
}

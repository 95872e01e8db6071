/* test_motion.c - moving objects (motion blur) through every acceleration
 * structure, and their hit tests against the same objects put in place.
 *
 * ray.c is included whole, as tests/test_pt.c does.  The scene: spheres,
 * cones, loose triangles and a mesh, two in three of them moving (each its
 * own velocity; the mesh all one), under a shutter open from -0.5 to 1, so
 * that neither end is 0.  Checks, one PASS or FAIL line each:
 *  - at rest: for rays at times spread over the shutter (its two ends
 *    included), the loop over every object (--accel none) hits the same
 *    object as the loop over a copy of the scene with every object moved
 *    to where it stands at that time, at the same t to 2e-12, with the same
 *    point and normal (to 2e-12 too): the ray moved the other way finds what moving the
 *    object would;
 *  - every structure (kd, bvh, grid): the same object and bitwise the same
 *    t as the loop, for the nearest hit, and the same answer for any hit,
 *    on random rays at random times (the structure bounds each moving
 *    object by its box swept over the shutter).
 * Prints the counts it compared, so that a reader sees how many rays hit a
 * moving object. */
#define main ray_main
#include "../ray.c"
#undef main
#include "check.h"

#define RAYS 20000
#define TIMES 7                 /* instants of the at-rest check */
#define TOL (1e4 * REAL_EPS)    /* its t, point and normal: 2e-12 in double */

typedef struct { unsigned long long key, n; } Sequence;

static double next01(Sequence *q)
{
    return (double)(mix64(q->key + 0x9e3779b97f4a7c15ULL * ++q->n) >> 11) * (1.0 / 9007199254740992.0);
}

static double between(Sequence *q, double a, double b) { return a + (b - a) * next01(q); }

static vec random_point(Sequence *q, double r)
{
    return v3(between(q, -r, r), between(q, -r, r), between(q, -r, r));
}

/* Two in three objects move, with velocities up to 4 along each axis. */
static vec random_velocity(Sequence *q)
{
    return next01(q) < 1.0 / 3 ? v3(0, 0, 0) : random_point(q, 4);
}

/* The test scene with every object moved by `at` times its velocity and
 * then at rest (at_time), or moving as made (at_time < 0 gives the moving
 * scene).  The same numbers either way: the sequence starts afresh. */
static void make_scene(Scene *s, int displaced, double at_time)
{
    Sequence q = { 0x243f6a8885a308d3ULL, 0 };
    Material m = { { 0.5, 0.5, 0.5 }, 1, 0, 0, 0, 1, 0 };
    int i, j, mat, n = 10, mesh[11][11];
    default_scene(s);
    s->shutter[0] = -0.5, s->shutter[1] = 1;
    mat = add_material(s, m);
#define PLACE(p, v) (displaced ? add(p, scale((real)at_time, v)) : (p))
#define MOVE(v) (s->move = displaced ? v3(0, 0, 0) : (v))
    for (i = 0; i < 60; i++) {
        vec c = random_point(&q, 10), v = random_velocity(&q);
        real r = (real)between(&q, 0.3, 2);
        MOVE(v);
        add_sphere(s, PLACE(c, v), r, mat);
    }
    for (i = 0; i < 20; i++) {
        vec b = random_point(&q, 10), v = random_velocity(&q), a = add(b, random_point(&q, 3));
        real rb = (real)between(&q, 0, 1), ra = (real)between(&q, 0.2, 1);
        MOVE(v);
        add_checked_cone(s, PLACE(b, v), rb, PLACE(a, v), ra, mat, (char[SCENE_WHY]){ 0 });
    }
    for (i = 0; i < 40; i++) {
        vec a = random_point(&q, 10), v = random_velocity(&q);
        vec b = add(a, random_point(&q, 3)), c = add(a, random_point(&q, 3));
        MOVE(v);
        s->cull = i % 4 == 0;
        add_triangle(s, add_vertex(s, PLACE(a, v)), add_vertex(s, PLACE(b, v)),
                     add_vertex(s, PLACE(c, v)), -1, -1, -1, mat);
    }
    s->cull = 0;
    {                           /* a mesh of 200 triangles sharing their vertices, moving as one */
        vec v = v3(1.5, -2, 0.5), corner = v3(-8, -8, -3);
        MOVE(v);
        for (i = 0; i <= n; i++)
            for (j = 0; j <= n; j++)
                mesh[i][j] = add_vertex(s, PLACE(add(corner, v3(1.6 * i, 1.6 * j,
                                                               sin(i * 0.7) + cos(j * 0.9))), v));
        for (i = 0; i < n; i++)
            for (j = 0; j < n; j++) {
                add_triangle(s, mesh[i][j], mesh[i + 1][j], mesh[i + 1][j + 1], -1, -1, -1, mat);
                add_triangle(s, mesh[i][j], mesh[i + 1][j + 1], mesh[i][j + 1], -1, -1, -1, mat);
            }
    }
    s->move = v3(0, 0, 0);
#undef PLACE
#undef MOVE
}

/* Ray k: from outside the scene towards a point inside it, at a time of
 * the shutter (its two ends now and then). */
static Ray random_ray(Sequence *q, const Scene *s)
{
    Ray r;
    double u = next01(q);
    r.o = random_point(q, 25);
    r.d = unit(sub(random_point(q, 9), r.o));
    r.tmin = 0;
    r.skip = -1;
    r.time = u < 0.05 ? s->shutter[0] : u < 0.1 ? s->shutter[1]
           : (real)between(q, s->shutter[0], s->shutter[1]);
    return r;
}

/* What structure `which` finds for r: with any = 0 the nearest hit (the
 * object, and its t in *t), with any = 1 any hit with t <= *t (the object). */
static int ask(Scene *s, int which, Ray r, int any, real *t)
{
    Worker wk;
    Query qq = query(r);
    int saved = s->accel.which, found;
    memset(&wk, 0, sizeof wk);
    s->accel.which = which;
    found = any ? find_any(s, &qq, *t, &wk) : find_nearest(s, &qq, t, &wk);
    s->accel.which = saved;
    return found;
}

static double distance(vec a, vec b) { return sqrt(dot(sub(a, b), sub(a, b))); }

/* The loop over the moving scene against the loop over the scene put in
 * place at each of TIMES instants. */
static void check_at_rest(void)
{
    Sequence q = { 0x13198a2e03707344ULL, 0 };
    Scene moving, placed;
    long rays = 0, hits = 0, moving_hits = 0, bad = 0;
    int k, n;
    char name[256];
    make_scene(&moving, 0, 0);
    build_accel(&moving, "none");
    for (k = 0; k < TIMES; k++) {
        real time = moving.shutter[0] + (moving.shutter[1] - moving.shutter[0]) * k / (TIMES - 1);
        make_scene(&placed, 1, time);
        build_accel(&placed, "none");
        for (n = 0; n < RAYS / TIMES; n++) {
            Ray r = random_ray(&q, &moving), still;
            real t1, t2;
            int a, b;
            r.time = time;
            still = r;
            still.time = 0;
            a = ask(&moving, ACCEL_NONE, r, 0, &t1);
            b = ask(&placed, ACCEL_NONE, still, 0, &t2);
            rays++;
            if (a != b) { bad++; continue; }
            if (a < 0) continue;
            hits++;
            moving_hits += moves(&moving, a);
            if (!(fabs(t1 - t2) <= TOL * t2)) { bad++; continue; }
            {
                Hit h1, h2;
                Query q1 = query(r), q2 = query(still);
                fill_hit(&moving, r, a, t1, &q1, &h1);
                fill_hit(&placed, still, b, t2, &q2, &h2);
                if (!(distance(h1.p, h2.p) <= TOL * (1 + maxabs(h2.p)) && distance(h1.n, h2.n) <= TOL
                      && h1.time == r.time))
                    bad++;
            }
        }
        free_scene(&placed);
    }
    sprintf(name, "motion: at rest, the moving scene's loop hits what the scene moved into place"
            " hits, at %d instants (%ld rays, %ld hits, %ld on moving objects, %ld differ)",
            TIMES, rays, hits, moving_hits, bad);
    check(bad == 0 && moving_hits > rays / 20, name);
    free_scene(&moving);
}

/* Each structure against the loop, on the moving scene. */
static void check_structure(const char *accel, int which)
{
    Sequence q = { 0xa4093822299f31d0ULL ^ (unsigned long long)which, 0 };
    Scene s;
    long n, hits = 0, moving_hits = 0, bad_nearest = 0, bad_any = 0, outside_rest = 0;
    char name[240];
    make_scene(&s, 0, 0);
    build_accel(&s, accel);
    if (s.accel.which != which) {
        sprintf(name, "motion: --accel %s builds", accel);
        check(0, name);
        free_scene(&s);
        return;
    }
    for (n = 0; n < RAYS; n++) {
        Ray r = random_ray(&q, &s);
        real t1, t2, tmax;
        int a = ask(&s, ACCEL_NONE, r, 0, &t1), b = ask(&s, which, r, 0, &t2);
        int any_ref, any_got;
        if (a != b || (a >= 0 && t1 != t2)) bad_nearest++;
        if (a >= 0) {
            double lo[3], hi[3];
            vec p = comb(t1, r.d, r.o);
            hits++;
            moving_hits += moves(&s, a);
            rest_box(&s, a, lo, hi);    /* hit outside its box at rest: only the sweep finds it */
            outside_rest += p.x < lo[0] || p.x > hi[0] || p.y < lo[1] || p.y > hi[1]
                            || p.z < lo[2] || p.z > hi[2];
        }
        tmax = a >= 0 ? t1 * (real)between(&q, 0.5, 1.5) : (real)between(&q, 1, 60);
        t1 = tmax;
        any_ref = ask(&s, ACCEL_NONE, r, 1, &t1) >= 0;
        any_got = ask(&s, which, r, 1, &tmax);
        if (any_ref != (any_got >= 0)) bad_any++;
        else if (any_got >= 0) {        /* what it found must be hit in range */
            real t;
            if (!hit_object(&s, any_got, &r, tmax, &t)) bad_any++;
        }
    }
    sprintf(name, "motion: %s finds the loop's nearest object and bitwise its t (%ld rays at random"
            " times, %ld hits, %ld on moving objects, %ld outside their box at rest; %ld differ)",
            accel, (long)RAYS, hits, moving_hits, outside_rest, bad_nearest);
    check(bad_nearest == 0 && outside_rest > 100, name);
    sprintf(name, "motion: %s's any-hit agrees with the loop's (%ld rays, %ld differ)", accel,
            (long)RAYS, bad_any);
    check(bad_any == 0, name);
    free_scene(&s);
}

/* Through the builder, as scene.c reads `move`: objects under `move 0 0 0`
 * count as still (so nothing is drawn and the kd-tree clips them exactly,
 * as before motion blur), those under a velocity as moving. */
static void check_still(void)
{
    Scene s;
    scene_builder b = builder(&s);
    scene_material m = { { 1, 1, 1 }, 1, 0, 0, 0, 1, 0 };
    double zero[3] = { 0, 0, 0 }, v[3] = { 0, 0, 1e-300 }, c[3] = { 0, 0, 0 }, apex[3] = { 0, 0, 2 };
    int mat, still, moving;
    char why[SCENE_WHY];
    default_scene(&s);
    mat = b.material(b.user, &m, why);
    b.setting(b.user, SET_MOVE, zero, NULL);
    b.sphere(b.user, c, 1, mat, why);
    b.cone(b.user, c, 1, apex, 0, mat, why);
    still = s.moving;
    b.setting(b.user, SET_MOVE, v, NULL);
    b.sphere(b.user, c, 1, mat, why);
    moving = s.moving;
    /* objects are numbered spheres first: the still sphere 0, the moving 1, the cone 2 */
    check(still == 0 && moving == 1 && s.ncone == 1 && !moves(&s, 0) && moves(&s, 1) && !moves(&s, 2),
          "motion: objects under `move 0 0 0` are still, one under a velocity of 1e-300 moves");
    free_scene(&s);
}

int main(void)
{
    check_still();
    check_at_rest();
    check_structure("kd", ACCEL_KD);
    check_structure("bvh", ACCEL_BVH);
    check_structure("grid", ACCEL_GRID);
    return failures != 0;
}

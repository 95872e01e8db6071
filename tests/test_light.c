/* Triangle lights sampled by solid angle (Arvo 1995; ray.c's
 * spherical_triangle_sample), against what it must be:
 *  - every direction it gives meets the triangle;
 *  - it is uniform in solid angle: the triangle cut at its edges' midpoints
 *    into four, and each of those again, each of the 16 gets its share of
 *    the samples (its own solid angle over the whole), by a chi-square
 *    test of 15 degrees of freedom;
 *  - the irradiance it estimates, the mean of cos / pdf, is Lambert's
 *    exact polygon formula E = 1/2 sum_i beta_i (n . gamma_i) (Lambert
 *    1760; as Arvo, "Irradiance tensors", SIGGRAPH 1995, writes it: beta_i
 *    the angle edge i spans seen from x, gamma_i the unit normal of the
 *    plane through x and the edge), within 4 standard errors;
 *  - the pdf sample_emitter gives with a direction is the one light_pdf
 *    finds for the point it leads to (MIS needs the two to agree), on both
 *    sides of SOLID_ANGLE_FROM, for the Cornell box's lamp.
 * And the light tree that chooses among many lights (prepare_lights,
 * choose_light, light_choice), on scenes/lights100.sph and on a scene of
 * random point lights, glowing spheres and one- and two-sided triangles,
 * some moving, with and without a sky, and of such triangles alone:
 *  - every node bounds its children: box, cone of normals, spread, power;
 *  - at any point the chances of all the lights add up to 1 (or to the
 *    sky's, where no other light can reach), choose_light's chance is
 *    light_choice's, and the lights it picks come in those proportions
 *    (chi-square, per point);
 *  - a light given chance 0 at a point cannot light it: no point of it,
 *    at any time the shutter is open, lies above the point's tangent
 *    plane and sends light towards it.
 * Random triangles and points, fixed seeds. */
#define main ray_main
#include "../ray.c"
#undef main
#include "report.h"

static double rnd(unsigned long long *x)
{
    *x = *x * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*x >> 11) / 9007199254740992.0;
}

static Triangle make_triangle(vec a, vec b, vec c)
{
    Triangle t;
    memset(&t, 0, sizeof t);
    t.v0 = a;
    t.e1 = sub(b, a);
    t.e2 = sub(c, a);
    return t;
}

/* Lambert's formula: the integral of the (signed) cosine to n over the
 * directions from x to the triangle, whichever way round its corners go. */
static double lambert(const Triangle *t, vec x, vec n)
{
    vec p[3];
    double e = 0;
    int i;
    p[0] = sub(t->v0, x);
    p[1] = sub(add(t->v0, t->e1), x);
    p[2] = sub(add(t->v0, t->e2), x);
    for (i = 0; i < 3; i++) {
        vec a = unit(p[i]), b = unit(p[(i + 1) % 3]);
        double beta = acos(fmax(-1, fmin(1, dot(a, b))));
        e += beta * dot(n, unit(cross(a, b)));
    }
    return fabs(e) / 2;
}

/* Which of the four midpoint sub-triangles of t the ray from x along d
 * meets (0: the middle one), or -1 if it misses t. */
static int quarter(const Triangle *t, vec x, vec d)
{
    Scene s;
    Ray r;
    real tt, u, v;
    r.o = x, r.d = d, r.tmin = 0, r.skip = -1, r.time = 0;
    memset(&s, 0, sizeof s);
    if (!hit_triangle(&s, t, &r, INFINITY, &tt, &u, &v)) return -1;
    if (u > 0.5) return 1;
    if (v > 0.5) return 2;
    if (u + v < 0.5) return 3;
    return 0;
}

static void test_triangle(int n, unsigned long long seed, int *bad_hits, double *worst_chi, double *worst_e)
{
    unsigned long long x = seed;
    vec a = v3(rnd(&x) * 2 - 1, rnd(&x) * 2 - 1, 1 + rnd(&x)), b, c, p = v3(0, 0, 0), nrm, cc[3], m[3];
    vec sub_c[3];
    real angle[3], sub_angle[3], area;
    double count[4] = { 0, 0, 0, 0 }, count16[16], expect16[16], chi = 0, sum = 0, sq = 0, e, mean, se;
    Triangle t, q[4], sub16[16];
    int k, i;
    memset(count16, 0, sizeof count16);
    b = add(a, v3(rnd(&x) * 2 - 1, rnd(&x) * 2 - 1, rnd(&x) - 0.5));
    c = add(a, v3(rnd(&x) * 2 - 1, rnd(&x) * 2 - 1, rnd(&x) - 0.5));
    t = make_triangle(a, b, c);
    nrm = unit(v3(rnd(&x) - 0.5, rnd(&x) - 0.5, 1));
    area = spherical_triangle(&t, p, cc, angle);
    m[0] = scale(0.5, add(a, b)), m[1] = scale(0.5, add(a, c)), m[2] = scale(0.5, add(b, c));
    q[0] = make_triangle(m[0], m[2], m[1]);
    q[1] = make_triangle(m[0], b, m[2]);
    q[2] = make_triangle(m[1], m[2], c);
    q[3] = make_triangle(a, m[0], m[1]);
    for (i = 0; i < 4; i++) {                   /* each quarter cut in four again: 16 cells */
        vec qa = q[i].v0, qb = add(q[i].v0, q[i].e1), qc = add(q[i].v0, q[i].e2);
        vec n0 = scale(0.5, add(qa, qb)), n1 = scale(0.5, add(qa, qc)), n2 = scale(0.5, add(qb, qc));
        sub16[4 * i] = make_triangle(n0, n2, n1);
        sub16[4 * i + 1] = make_triangle(n0, qb, n2);
        sub16[4 * i + 2] = make_triangle(n1, n2, qc);
        sub16[4 * i + 3] = make_triangle(qa, n0, n1);
    }
    for (i = 0; i < 16; i++) expect16[i] = n * spherical_triangle(&sub16[i], p, sub_c, sub_angle) / area;
    for (k = 0; k < n; k++) {
        real u1 = rnd(&x), u2 = rnd(&x);    /* independent: the chi-square and the standard error assume it */
        vec d = spherical_triangle_sample(cc, angle, area, u1, u2);
        int w = quarter(&t, p, d);
        double f = dot(d, nrm) * area;                  /* cos / pdf (cos signed, as Lambert's is) */
        if (w < 0) (*bad_hits)++;
        else {
            count[w]++;
            count16[4 * w + quarter(&q[w], p, d)]++;
        }
        sum += f, sq += f * f;
    }
    for (i = 0; i < 16; i++) chi += (count16[i] - expect16[i]) * (count16[i] - expect16[i]) / expect16[i];
    mean = sum / n;
    se = sqrt(fmax(0, sq / n - mean * mean) / (n - 1));
    e = lambert(&t, p, nrm);
    if (chi > *worst_chi) *worst_chi = chi;
    if (se > 0 && fabs(fabs(mean) - e) / se > *worst_e) *worst_e = fabs(fabs(mean) - e) / se;
}

/* sample_emitter's pdf against light_pdf's for the point it chose, for
 * the Cornell box's lamp (two triangles) from random points of the box:
 * the near ones see it by more than SOLID_ANGLE_FROM, the far ones less. */
static void test_pdf_agrees(void)
{
    Scene s;
    unsigned long long x = 5;
    double worst = 0;
    int k, l, solid = 0, area = 0;
    if (!load_scene(&s, "scenes/cornell.sph") || !settle_path_options(&s, PATH, -1, 1, 0)) {
        report(0, "sample_emitter and light_pdf agree", "scenes/cornell.sph did not load");
        return;
    }
    for (k = 0; k < 20000; k++) {
        vec p = v3(556 * rnd(&x), 548 * rnd(&x), 559 * rnd(&x)), n = v3(0, 1, 0), wi, Le, c[3];
        real dist, pdf, angle[3];
        for (l = 0; l < s.lights.nemit && s.lights.emit[l].type != TRIANGLE_LIGHT; l++) continue;
        l += k % 2;                              /* one triangle of the lamp, then the other */
        if (l >= s.lights.nemit || s.lights.emit[l].type != TRIANGLE_LIGHT) break;
        sample_emitter(&s, l, p, n, 0, (real)rnd(&x), (real)rnd(&x), &wi, &dist, &Le, &pdf);
        if (!(pdf > 0)) continue;
        {
            const Triangle *t = &s.tri[s.lights.emit[l].obj - s.nsph - s.ncone];
            vec y = comb(dist, wi, p), ny = unit(cross(t->e1, t->e2));
            double q = light_pdf(&s, l, p, n, y, ny, 0) / light_choice(&s, l, p, n);
            if (fabs(q / pdf - 1) > worst) worst = fabs(q / pdf - 1);
            if (spherical_triangle(t, p, c, angle) >= SOLID_ANGLE_FROM) solid++;
            else area++;
        }
    }
    report(worst < 1e-6 && solid > 100 && area > 100, "sample_emitter's pdf is light_pdf's for the point it chose",
           "worst relative difference %.2g over %d points sampled by solid angle and %d by area", worst, solid, area);
    /* and what it estimates: the irradiance from each lamp triangle at
     * points below it, near (by solid angle) and beside it (by area), against
     * Lambert's formula */
    worst = 0, solid = area = 0;
    for (k = 0; k < 8; k++) {
        vec p = k % 2 ? v3(20 + 30 * k, 540, 30 + 20 * k) : v3(200 + 20 * k, 60 + 60 * k, 250 + 10 * k);
        vec n = v3(0, 1, 0), wi, Le, c[3];
        real angle[3];
        double sum = 0, sq = 0, mean, se, e = 0;
        real dist, pdf;
        int j, m = 40000;
        for (l = 0; l < s.lights.nemit && s.lights.emit[l].type != TRIANGLE_LIGHT; l++) continue;
        for (j = 0; j < m; j++) {
            sample_emitter(&s, l + j % 2, p, n, 0, (real)rnd(&x), (real)rnd(&x), &wi, &dist, &Le, &pdf);
            if (pdf > 0) {
                double f = fmax(0, dot(wi, n)) / pdf;
                sum += f, sq += f * f;
            }
        }
        for (j = 0; j < 2; j++) {
            const Triangle *t = &s.tri[s.lights.emit[l + j].obj - s.nsph - s.ncone];
            e += lambert(t, p, n);
            if (spherical_triangle(t, p, c, angle) >= SOLID_ANGLE_FROM) solid++;
            else area++;
        }
        mean = 2 * sum / m;                     /* each triangle half the time */
        se = 2 * sqrt(fmax(0, sq / m - sum / m * (sum / m)) / (m - 1));
        if (fabs(mean - e) / se > worst) worst = fabs(mean - e) / se;
    }
    report(worst < 4.5 && solid > 0 && area > 0, "the Cornell lamp's irradiance by sample_emitter against Lambert's formula",
           "worst difference %.2f standard errors at 8 points; of their 16 lamp triangles, %d by solid angle, %d by area",
           worst, solid, area);
    free_scene(&s);
}

/* A scene of random lights of every kind the tree holds, into file. */
static int write_random_lights(const char *file, int sky, int triangles_only, unsigned long long x)
{
    FILE *f = fopen(file, "w");
    int i;
    if (!f) return 0;
    fprintf(f, "integrator path\nbackground %s\nshutter 0 1\n", sky ? ".2 .3 .4" : "0 0 0");
    fprintf(f, "tri -20 -20 0  20 -20 0  20 20 0  .8 .8 .8 .8 0 0 0 1\n");
    for (i = 0; i < 10 * !triangles_only; i++)
        fprintf(f, "light %.3f %.3f %.3f  %.3f .5 .5\n", 16 * rnd(&x) - 8, 16 * rnd(&x) - 8, 8 * rnd(&x), 2 * rnd(&x));
    for (i = 0; i < 60; i++) {
        double c[3] = { 16 * rnd(&x) - 8, 16 * rnd(&x) - 8, 1 + 7 * rnd(&x) }, r = 0.05 + 0.8 * rnd(&x);
        if (i == 20) fprintf(f, "sided 1\n");
        fprintf(f, "move %.3f %.3f %.3f\n", i % 3 ? 0 : 4 * rnd(&x) - 2, i % 3 ? 0 : 4 * rnd(&x) - 2, 0.0);
        if (i % 4 == 0 && !triangles_only)
            fprintf(f, "%.3f %.3f %.3f  1 1 1  %.3f  0 0 0 %.3f 1\n", c[0], c[1], c[2], r, 0.1 + 5 * rnd(&x));
        else
            fprintf(f, "tri %.3f %.3f %.3f  %.3f %.3f %.3f  %.3f %.3f %.3f  1 1 1 0 0 0 %.3f 1\n",
                    c[0], c[1], c[2], c[0] + 2 * r * (rnd(&x) - .5), c[1] + 2 * r * (rnd(&x) - .5),
                    c[2] + 2 * r * (rnd(&x) - .5), c[0] + 2 * r * (rnd(&x) - .5), c[1] + 2 * r * (rnd(&x) - .5),
                    c[2] + 2 * r * (rnd(&x) - .5), 0.1 + 5 * rnd(&x));
    }
    return fclose(f) == 0;
}

/* Whether every node of the light tree bounds its children; the tree's
 * depth into *depth. */
static int tree_bounds(const Scene *s, int k, int *depth)
{
    const LightNode *n = &s->lights.node[k];
    int i, d[2];
    if (n->light >= 0) return *depth = 1, n->child[0] < 0 && s->lights.leaf[n->light] == k;
    for (i = 0; i < 2; i++) {
        const LightNode *c = &s->lights.node[n->child[i]];
        double angle = acos(fmax(-1, fmin(1, dot(n->axis, c->axis)))) + acos(c->cos_o);
        if (c->parent != k || !tree_bounds(s, n->child[i], &d[i])) return 0;
        if (c->lo.x < n->lo.x || c->lo.y < n->lo.y || c->lo.z < n->lo.z || c->hi.x > n->hi.x
            || c->hi.y > n->hi.y || c->hi.z > n->hi.z) return 0;
        if (n->cos_o > -1 && angle > acos(n->cos_o) + 1e-9) return 0;   /* the child's cone within */
        if (c->two_sided > n->two_sided || c->cos_e < n->cos_e) return 0;
    }
    *depth = 1 + (d[0] > d[1] ? d[0] : d[1]);
    return fabs(n->power - s->lights.node[n->child[0]].power - s->lights.node[n->child[1]].power)
           <= 1e-12 * n->power;
}

/* A point of light l at the given time, chosen by u and v, and its normal
 * there (0 for a point light). */
static vec point_on_light(const Scene *s, int l, double time, double u, double v, vec *ny)
{
    const Emitter *e = &s->lights.emit[l];
    vec y;
    int k;
    *ny = v3(0, 0, 0);
    if (e->type == POINT_LIGHT) return e->pos;
    kind(s, e->obj, &k);
    if (e->type == SPHERE_LIGHT) {
        double z = 1 - 2 * u, r = sqrt(fmax(0, 1 - z * z));
        *ny = v3(r * cos(2 * PI * v), r * sin(2 * PI * v), z);
        y = comb(s->sph[k].rad, *ny, s->sph[k].cen);
    } else {
        const Triangle *t = &s->tri[k];
        if (u + v > 1) u = 1 - u, v = 1 - v;
        y = add(t->v0, add(scale(u, t->e1), scale(v, t->e2)));
        *ny = unit(cross(t->e1, t->e2));
    }
    return moves(s, e->obj) ? comb(time, velocity(s, e->obj), y) : y;
}

/* Whether light l can send light to x, of normal n, from above x's
 * tangent plane: by 400 of its points at 4 times the shutter is open. */
static int can_light(const Scene *s, int l, vec x, vec n, unsigned long long *r)
{
    int i;
    for (i = 0; i < 1600; i++) {
        vec ny, y = point_on_light(s, l, (i % 4) / 3.0, rnd(r), rnd(r), &ny), d = sub(x, y);
        int front = s->lights.emit[l].type != TRIANGLE_LIGHT || !s->tri[s->lights.emit[l].obj - s->nsph - s->ncone].cull;
        if (dot(n, d) < 0 && (dot(ny, d) > 0 || (front && s->lights.emit[l].type == TRIANGLE_LIGHT)
                              || s->lights.emit[l].type == POINT_LIGHT))
            return 1;
    }
    return 0;
}

/* The light tree of one scene, against the list above. */
static void test_tree(const char *file, const char *name, vec lo, vec hi)
{
    Scene s;
    unsigned long long x = 77;
    double worst_sum = 0, worst_chance = 0, worst_z = -1e9;
    int k, depth = 0, unreached = 0, zeros = 0, points = 0;
    if (!load_scene(&s, file) || !settle_path_options(&s, PATH, -1, 1, 0) || s.lights.root < 0) {
        report(0, "the light tree", "%s did not load, or has no lights", name);
        return;
    }
    k = tree_bounds(&s, s.lights.root, &depth);
    report(k && depth <= 2 + (int)ceil(log2(s.lights.nemit)),
           "the light tree: every node bounds its children (box, cone of normals, spread, power)",
           "%s: %d lights, %d deep", name, s.lights.nemit, depth);
    for (k = 0; k < 3000; k++) {
        vec p = v3(lo.x + (hi.x - lo.x) * rnd(&x), lo.y + (hi.y - lo.y) * rnd(&x), lo.z + (hi.z - lo.z) * rnd(&x));
        vec n = unit(v3(rnd(&x) - .5, rnd(&x) - .5, rnd(&x) - .5));
        double sum = 0, want;
        int l, any = 0;
        for (l = 0; l < s.lights.nemit; l++) {
            double c = light_choice(&s, l, p, n);
            sum += c;
            if (l != s.lights.sky && c > 0) any = 1;
            if (l != s.lights.sky && !(c > 0) && k % 10 == 0) {
                zeros++;
                unreached += can_light(&s, l, p, n, &x);
            }
        }
        want = s.lights.sky >= 0 ? 0.5 : 0;              /* the sky's, where nothing else reaches */
        worst_sum = fmax(worst_sum, any ? sum - 1 : fabs(sum - want));
        if (any && !(sum > want)) worst_sum = 1;
        if (k % 100 == 0 && any) {           /* choose_light's draws against light_choice */
            static int hits[512];
            double chi = 0, expect, z;
            int draws = 40000, cells = 0, t, none = 0;
            memset(hits, 0, sizeof hits);
            for (t = 0; t < draws; t++) {
                real chance;
                int c = choose_light(&s, p, n, (real)rnd(&x), &chance);
                if (c < 0) { none++; continue; }
                hits[c]++;
                worst_chance = fmax(worst_chance, fabs(chance / light_choice(&s, c, p, n) - 1));
            }
            for (l = 0; l < s.lights.nemit; l++) {
                expect = draws * light_choice(&s, l, p, n);
                if (expect >= 5) chi += (hits[l] - expect) * (hits[l] - expect) / expect, cells++;
                else if (hits[l] > 0 && !(expect > 0)) chi = 1e9;     /* drawn at chance 0 */
            }
            expect = draws * (1 - sum);                       /* no light: the chance lost */
            if (expect >= 5) chi += (none - expect) * (none - expect) / expect, cells++;
            else if (none > 0 && !(expect > 0)) chi = 1e9;
            /* Wilson and Hilferty (1931): chi-square of cells - 1 degrees of freedom as a normal z */
            t = cells - 1;
            z = t > 0 ? (pow(chi / t, 1.0 / 3) - (1 - 2.0 / (9 * t))) / sqrt(2.0 / (9 * t)) : 0;
            worst_z = fmax(worst_z, z);
            points++;
        }
    }
    report(worst_sum < 1e-9, "the light tree: at any point the lights' chances add up to at most 1, to the sky's 1/2 where no other reaches",
           "%s: worst difference %.2g over 3000 points", name, worst_sum);
    report(worst_chance < 1e-9 && points >= 20 && worst_z < 4.5,
           "the light tree: choose_light picks lights in light_choice's proportions, with its chance",
           "%s: worst chance %.2g from light_choice's, worst chi-square %.2f standard normal deviates over %d points",
           name, worst_chance, worst_z, points);
    report(unreached == 0 && zeros > 100, "the light tree: a light given chance 0 cannot light the point",
           "%s: %d of %d lights given chance 0 could (1600 points of each, at 4 times)", name, unreached, zeros);
    free_scene(&s);
}

/* Glowing spheres cut by opaque ones (ray.c's find_clips, visible_cap,
 * cap_sample): smallpt's lamp, sunk 0.27 into its ceiling and crossed by
 * four walls, seen from inside the walls' spheres; and clips.sph's, seen
 * from outside them: a lamp sunk but for a cap 0.2 high into a floor that
 * is a sphere of radius 1e4 seen from above, a lamp sunk but for a cap
 * into an opaque ball, and one cut by two balls.  At points in the air and on surfaces (as the renderer
 * finds them, with bsdf_at's normal), for each light:
 *  - every point of the light that a ray from the point meets (rays aimed
 *    at random points of the whole sphere, over the normal's side) lies in
 *    the cap visible_cap gives: cap_pdf is not 0 there (the cap holds all
 *    the point can see);
 *  - sample_emitter's pdf is light_pdf's for the point it chose;
 *  - the irradiance from the light, the mean of V cos / pdf, sampled in
 *    the cap equals that sampled over the whole sphere (clips taken away),
 *    within 4.5 standard errors;
 *  - and on smallpt's floor and in its air, sample_emitter's estimate with
 *    its two numbers at the centres of a 128 x 128 grid (V cos / pdf) is
 *    the integral over the cap's area by the midpoint rule on the same grid
 *    in (height, angle), dA = R^2 dz dphi (Archimedes), V cos cos / d^2,
 *    each point's visibility by a shadow ray: the pdf's turning of area
 *    into solid angle checked against the area itself. */
static int write_clips(const char *file)
{
    FILE *f = fopen(file, "w");
    if (!f) return 0;
    fputs("integrator path\ncamera 0 -12 5  0 0 1  0 0 1  50\n"
          "0 0 -10000    .8 .8 .8  10000  .8 0 0 0 1\n"      /* the floor: z = 0 */
          "-4 2 -1.3     1 .9 .7   1.5    0 0 0 4 1\n"        /* sunk into it but a cap */
          "3 3 2         .6 .7 .8  2      .7 0 0 0 1\n"       /* a ball, and a lamp sunk into it */
          "3 3 3.6       1 1 1     .6     0 0 0 6 1\n"
          "0 -3 2.5      1 .8 .6   .8     0 0 0 5 1\n"        /* a lamp cut by two balls */
          "-.9 -3 2.5    .5 .5 .5  .7     .6 .3 0 0 1\n"
          ".7 -3.2 2.9   .5 .5 .5  .6     0 1 0 0 1\n", f);
    return fclose(f) == 0;
}

/* The ray from the point (in the air: h->obj < 0) along dir, as the
 * renderer would spawn it. */
static Ray ray_from(const Scene *s, const Hit *h, vec dir)
{
    Ray r;
    if (h->obj >= 0) return spawn(s, h, dir);
    memset(&r, 0, sizeof r);
    r.o = h->p, r.d = dir, r.skip = -1;
    return r;
}

/* The irradiance at p (normal n) from lamp l of s, through its cap about
 * axis of height cap, by the midpoint rule: the cap's area element is
 * R^2 dz dphi (Archimedes), each point's share cos_p cos_y / d^2 if a
 * shadow ray reaches it. */
static double cap_irradiance(Scene *s, int l, vec p, vec n, vec axis, real cap, Worker *wk)
{
    const Sphere *sp = &s->sph[s->lights.emit[l].obj];
    const int N = 128;
    double e = 0;
    int a, b;
    for (a = 0; a < N; a++)
        for (b = 0; b < N; b++) {
            real z = 1 - cap * (a + (real)0.5) / N, phi = 2 * (real)PI * (b + (real)0.5) / N, q = sqrt(fmax(0, 1 - z * z));
            vec u = from_local(axis, v3(q * cos(phi), q * sin(phi), z)), y = comb(sp->rad, u, sp->cen), d = sub(y, p);
            real dist = sqrt(dot(d, d)), cp = dot(d, n) / dist, cy = -dot(d, u) / dist;
            Ray r;
            if (!(cp > 0) || !(cy > 0)) continue;
            memset(&r, 0, sizeof r);
            r.o = p, r.d = scale(1 / dist, d), r.skip = s->lights.emit[l].obj;
            if (!any_hit(s, r, dist, &wk->blocker[1], wk)) e += cp * cy / (dist * dist);
        }
    return e * sp->rad * sp->rad * cap * 2 * PI / ((double)N * N);
}

/* sample_emitter's estimate on a grid of numbers against cap_irradiance,
 * at points below smallpt's lamp: the worst relative difference. */
static void test_cap_integral(void)
{
    Scene s;
    Worker wk;
    unsigned long long x = 17;
    double worst = 0;
    int k, a, b, l = 0, N = 128, points = 0;
    memset(&wk, 0, sizeof wk);
    for (k = 0; k < SHADOW_SLOTS; k++) wk.blocker[k] = -1;
    if (!load_scene(&s, "scenes/smallpt.sph") || !settle_path_options(&s, PATH, -1, 1, 0) || !build_accel(&s, "auto")) {
        report(0, "clipped lamps: the cap's integral", "scenes/smallpt.sph did not load");
        return;
    }
    for (k = 0; k < 6; k++) {
        vec p = k < 3 ? v3(15 + 30 * k, 0, 40 + 25 * k) : v3(10 + 25 * k - 75, 20 + 15 * k - 45, 60 + 10 * k),
            n = k < 3 ? v3(0, 1, 0) : unit(v3(rnd(&x) - .5, 1, rnd(&x) - .5)), axis, wi, Le;
        real cap, dist, pdf;
        double sum = 0, e;
        if (!visible_cap(&s, l, p, n, &axis, &cap)) continue;
        for (a = 0; a < N; a++)
            for (b = 0; b < N; b++) {
                sample_emitter(&s, l, p, n, 0, (a + (real)0.5) / N, (b + (real)0.5) / N, &wi, &dist, &Le, &pdf);
                if (pdf > 0 && dot(wi, n) > 0) {
                    Ray r;
                    memset(&r, 0, sizeof r);
                    r.o = p, r.d = wi, r.skip = s.lights.emit[l].obj;
                    if (!any_hit(&s, r, dist, &wk.blocker[0], &wk)) sum += dot(wi, n) / pdf;
                }
            }
        e = cap_irradiance(&s, l, p, n, axis, cap, &wk);
        points++;
        if (!(fabs(sum / (N * N) - e) <= worst * e)) worst = fabs(sum / (N * N) - e) / e;
    }
    report(points == 6 && worst < 1e-6, "clipped lamps: smallpt's lamp's irradiance by its cap's samples is the cap's integral",
           "worst relative difference %.2g at %d points on the floor and in the air, a 128 x 128 grid each way",
           worst, points);
    free_scene(&s);
}

/* cap_sample against cap_pdf, Nori's pairing of a warp with its pdf: from
 * points below smallpt's lamp and beside it, the directions it gives are
 * counted in 8 x 8 cells of the cap (by height and angle about its axis),
 * against each cell's share by cap_pdf integrated over the directions to
 * it (a 16 x 16 midpoint rule in each cell: dw = cos_y dA / d^2); chi-square
 * of 63 degrees of freedom, whose 99.9th percentile is 103.4. */
static void test_cap_chi_square(void)
{
    Scene s;
    unsigned long long x = 23;
    double worst = 0;
    int k, j, a, b, N = 8, M = 16, m = 64000;
    if (!load_scene(&s, "scenes/smallpt.sph") || !settle_path_options(&s, PATH, -1, 1, 0)) {
        report(0, "clipped lamps: cap_sample against cap_pdf", "scenes/smallpt.sph did not load");
        return;
    }
    for (k = 0; k < 3; k++) {
        const Sphere *sp = &s.sph[s.lights.emit[0].obj];
        vec p = k == 0 ? v3(50, 0, 81.6) : k == 1 ? v3(5, 40, 150) : v3(90, 75, 20), n = v3(0, 1, 0), axis, wi, t1, t2;
        real cap, dist;
        double count[64] = { 0 }, chi = 0;
        if (!visible_cap(&s, 0, p, n, &axis, &cap)) continue;
        tangents(axis, &t1, &t2);
        for (j = 0; j < m; j++) {
            vec u;
            real z, phi;
            int cz, cp;
            if (!(cap_sample(sp, axis, cap, p, (real)rnd(&x), (real)rnd(&x), &wi, &dist) > 0)) continue;
            u = scale(1 / sp->rad, sub(comb(dist, wi, p), sp->cen));
            z = dot(u, axis), phi = atan2(dot(u, t2), dot(u, t1));
            cz = (int)((1 - z) / cap * N), cp = (int)((phi + PI) / (2 * PI) * N);
            count[(cz < N ? cz : N - 1) * N + (cp < N ? cp : N - 1)]++;
        }
        for (a = 0; a < N; a++)
            for (b = 0; b < N; b++) {
                double share = 0, want;
                int i, l;
                for (i = 0; i < M; i++)
                    for (l = 0; l < M; l++) {
                        real z = 1 - cap * (a + (i + (real)0.5) / M) / N, phi = -PI + 2 * PI * (b + (l + (real)0.5) / M) / N;
                        real q = sqrt(fmax(0, 1 - z * z));
                        vec u = add(add(scale(q * cos(phi), t1), scale(q * sin(phi), t2)), scale(z, axis));
                        vec y = comb(sp->rad, u, sp->cen), d = sub(y, p);
                        real d2 = dot(d, d), cy = -dot(u, d) / sqrt(d2);
                        if (cy > 0) share += cap_pdf(sp, axis, cap, p, y) * cy / d2;
                    }
                want = m * share * sp->rad * sp->rad * (cap / N) * (2 * PI / N) / (M * M);
                chi += (count[a * N + b] - want) * (count[a * N + b] - want) / want;
            }
        if (chi > worst) worst = chi;
    }
    report(worst < 103.4, "clipped lamps: cap_sample's directions come as cap_pdf says (chi-square)",
           "worst chi-square %.1f of 3 points, 64 cells, 63 degrees of freedom (fails above 103.4)", worst);
    free_scene(&s);
}

static void test_clips(const char *file, const char *name, vec lo, vec hi)
{
    Scene s;
    unsigned long long x = 11;
    int k, j, l, clipped = 0, in_cap = 0, outside = 0, agree = 0, points = 0, capped = 0, compared = 0;
    double worst_pdf = 0, worst_z = 0;
    Worker wk;
    memset(&wk, 0, sizeof wk);
    for (k = 0; k < SHADOW_SLOTS; k++) wk.blocker[k] = -1;
    if (!load_scene(&s, file) || !settle_path_options(&s, PATH, -1, 1, 0) || !build_accel(&s, "auto")) {
        report(0, "clipped sphere lights", "%s did not load", file);
        return;
    }
    for (l = 0; l < s.lights.nemit; l++) clipped += s.lights.emit[l].nclips > 0;
    for (k = 0; k < 300; k++) {
        /* a point in the air, or where a ray from one meets a surface */
        vec p = v3(lo.x + (hi.x - lo.x) * rnd(&x), lo.y + (hi.y - lo.y) * rnd(&x), lo.z + (hi.z - lo.z) * rnd(&x));
        vec n = unit(v3(rnd(&x) - .5, rnd(&x) - .5, rnd(&x) - .5)), d = unit(v3(rnd(&x) - .5, rnd(&x) - .5, rnd(&x) - .5));
        Hit h;
        memset(&h, 0, sizeof h);
        h.p = p, h.ng = h.n = n, h.obj = -1;
        if (k % 2) {
            Ray r = ray_from(&s, &h, d);
            Bsdf b;
            if (!nearest_hit(&s, r, &h, &wk) || s.mat[h.mat].kl > 0) continue;
            bsdf_at(&s, &h, scale(-1, d), &b);
            n = b.n, p = h.p;
        }
        points++;
        for (l = 0; l < s.lights.nemit; l++) {
            const Emitter *e = &s.lights.emit[l];
            const Sphere *sp = &s.sph[e->obj];
            vec axis, wi, Le;
            real cap, dist, pdf;
            double sum[2] = { 0, 0 }, sq[2] = { 0, 0 };
            int m = 2500, use, lit[2] = { 0, 0 };
            if (e->type != SPHERE_LIGHT || e->nclips == 0) continue;
            use = visible_cap(&s, l, p, n, &axis, &cap);
            capped += use;
            for (j = 0; j < 200 && use; j++) {          /* what rays from p meet of the light */
                vec u = unit(v3(rnd(&x) - .5, rnd(&x) - .5, rnd(&x) - .5));     /* aimed at any point of it */
                vec dir = unit(sub(comb(sp->rad, u, sp->cen), p));
                Hit g;
                if (dot(dir, n) <= 0) continue;
                if (!nearest_hit(&s, ray_from(&s, &h, dir), &g, &wk) || g.obj != e->obj) continue;
                if (dot(unit(sub(g.p, sp->cen)), axis) >= 1 - cap && cap_pdf(sp, axis, cap, p, g.p) > 0) in_cap++;
                else outside++;
            }
            for (j = 0; j < 2 * m; j++) {               /* the cap's samples, then the whole sphere's */
                int c = j >= m, saved = e->nclips;
                if (c) s.lights.emit[l].nclips = 0;
                sample_emitter(&s, l, p, n, 0, (real)rnd(&x), (real)rnd(&x), &wi, &dist, &Le, &pdf);
                if (!c && pdf > 0) {
                    vec y = comb(dist, wi, p);
                    double q = light_pdf(&s, l, p, n, y, unit(sub(y, sp->cen)), 0) / light_choice(&s, l, p, n);
                    if (fabs(q / pdf - 1) > worst_pdf) worst_pdf = fabs(q / pdf - 1);
                    agree++;
                }
                if (pdf > 0 && dot(wi, n) > 0) {
                    Ray r = ray_from(&s, &h, wi);
                    r.skip = e->obj;
                    if (!any_hit(&s, r, dist, &wk.blocker[0], &wk)) {
                        double f = dot(wi, n) / pdf;
                        sum[c] += f, sq[c] += f * f, lit[c]++;
                    }
                }
                s.lights.emit[l].nclips = saved;
            }
            if (lit[0] >= 20 && lit[1] >= 20) {     /* else a spread seen from few samples */
                double m0 = sum[0] / m, m1 = sum[1] / m;
                double v = (sq[0] / m - m0 * m0 + sq[1] / m - m1 * m1) / (m - 1);
                double z = v > 0 ? fabs(m0 - m1) / sqrt(v) : (m0 == m1 ? 0 : 99);
                if (z > worst_z) worst_z = z;
                compared++;
            }
        }
    }
    report(clipped > 0 && capped > 100 && in_cap > 300 && outside == 0,
           "clipped lamps: every point of a lamp that a point can see lies in its cap",
           "%s: %d lamps clipped; at %d points (half on surfaces) a cap %d times; %d rays met a lamp in its cap, "
           "%d outside it", name, clipped, points, capped, in_cap, outside);
    report(agree > 1000 && worst_pdf < 1e-6, "clipped lamps: sample_emitter's pdf is light_pdf's",
           "%s: worst relative difference %.2g over %d points chosen in caps", name, worst_pdf, agree);
    report(worst_z < 4.5 && compared > 20, "clipped lamps: the irradiance sampled in the cap is the whole sphere's",
           "%s: worst difference %.2f standard errors at %d points and lamps, 2500 samples each way (where both"
           " saw the lamp 20 times)", name, worst_z, compared);
    free_scene(&s);
}

int main(int argc, char **argv)
{
    char file[4096];
    sprintf(file, "%.4000s/lights.sph", argc > 1 ? argv[1] : "/tmp");
    test_tree("scenes/lights100.sph", "lights100.sph", v3(-26, -26, 0), v3(26, 26, 4));
    if (write_random_lights(file, 0, 0, 3)) test_tree(file, "random lights", v3(-9, -9, 0), v3(9, 9, 9));
    else report(0, "the light tree", "cannot write %s", file);
    if (write_random_lights(file, 1, 0, 4)) test_tree(file, "random lights under a sky", v3(-9, -9, 0), v3(9, 9, 9));
    else report(0, "the light tree", "cannot write %s", file);
    if (write_random_lights(file, 0, 1, 5)) test_tree(file, "random triangles", v3(-9, -9, 0), v3(9, 9, 9));
    else report(0, "the light tree", "cannot write %s", file);
    test_pdf_agrees();
    test_clips("scenes/smallpt.sph", "smallpt.sph", v3(1, 0, 0), v3(99, 81.6, 170));
    test_cap_integral();
    test_cap_chi_square();
    sprintf(file, "%.4000s/clips.sph", argc > 1 ? argv[1] : "/tmp");
    if (write_clips(file)) test_clips(file, "clips.sph", v3(-8, -8, -1), v3(8, 8, 7));
    else report(0, "clipped sphere lights", "cannot write %s", file);
    int bad = 0, k;
    double chi = 0, ez = 0;
    for (k = 0; k < 40; k++) test_triangle(20000, 1000 + k, &bad, &chi, &ez);
    report(bad == 0, "Arvo's sampler: every direction meets its triangle", "%d of %d missed", bad, 40 * 20000);
    /* chi-square of 15 degrees of freedom: 37.7 is its 99.9th percentile; the worst of 40 */
    report(chi < 44, "Arvo's sampler is uniform in solid angle: 16 sub-triangles (midpoints, twice) get their shares",
           "worst chi-square %.2f of 40 triangles, 15 degrees of freedom (fails above 44)", chi);
    report(ez < 4.5, "the irradiance by solid-angle samples against Lambert's polygon formula",
           "worst difference %.2f standard errors of 40 triangles", ez);
    return failures != 0;
}

/* scene.c - the scene files' readers: the sphere format, Wavefront OBJ and
 * NFF, handing what they read to a renderer's builder (scene.h).
 *
 * Every message names the file and line it is about, FILE:LINE: WHAT, and
 * quotes the file's own text with anything unprintable escaped.  A reader
 * stops at the first error; the renderer then exits without rendering.
 */
#include "posix.h"
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef RAY_POSIX
#include <sys/stat.h>
#endif
#include "scene.h"

/* The renderer's precision (ray.c's `real`), which every number is rounded
 * to as it is read. */
#ifndef REAL
#define REAL double
#endif
#define PI 3.14159265358979323846

typedef struct { const char *file; int line; } Where;

/* s on f, with every byte that is not printable ASCII as \xNN: a message
 * that quotes a file never sends a terminal raw binary. */
static void put_escaped(FILE *f, const char *s)
{
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c >= 0x20 && c < 0x7F) putc(c, f);
        else fprintf(f, "\\x%02X", c);
    }
}

static int fail(Where w, const char *msg, const char *arg)
{
    if (w.line) fprintf(stderr, "%s:%d: %s", w.file, w.line, msg);
    else fprintf(stderr, "%s: %s", w.file, msg);     /* line 0: the file as a whole */
    if (arg) {
        fputs(": ", stderr);
        put_escaped(stderr, arg);
    }
    fputc('\n', stderr);
    return 0;
}

/* A vertex to the builder: its index, or -1 after the builder's message
 * (a vertex beyond what its arithmetic keeps). */
static int vertex(const scene_builder *b, Where w, const double p[3])
{
    char why[SCENE_WHY];
    int k = b->vertex(b->user, p, why);
    if (k < 0) fail(w, why, NULL);
    return k;
}

/* One finite number from a token, rounded to the renderer's precision, or
 * a message saying what is wrong. */
static int number(Where w, const char *tok, double *out)
{
    char *end;
    double v = strtod(tok, &end);
    if (end != tok && *end == ',')
        return fail(w, "numbers are parted by blanks, not commas", tok);
    if (end == tok || *end) return fail(w, "not a number", tok);
    if (!isfinite(v)) return fail(w, "number must be finite", tok);
    *out = (double)(REAL)v;       /* as the renderer keeps it */
    return 1;
}

/* The n numbers after tok[first], and nothing else on the line.  `what`
 * names the line's kind for the message. */
static int numbers(Where w, const char *what, char **tok, int ntok, int first, int n, double *out)
{
    int i;
    char buf[128];
    if (ntok - first != n) {
        sprintf(buf, "%.40s needs %d numbers, found %d", what, n, ntok - first);
        return fail(w, buf, NULL);
    }
    for (i = 0; i < n; i++)
        if (!number(w, tok[first + i], &out[i])) return 0;
    return 1;
}

static void out_of_memory(void)
{
    fprintf(stderr, "ray: out of memory\n");
    exit(1);
}

static double area2(const double *a, const double *b, const double *c)
{
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* Is 2-D point p inside or on the triangle a b c (counter-clockwise)? */
static int inside2(const double *p, const double *a, const double *b, const double *c)
{
    return area2(a, b, p) >= 0 && area2(b, c, p) >= 0 && area2(c, a, p) >= 0;
}

/* A polygon's corners in 2-D, counter-clockwise: it is projected on the
 * plane square to its normal's largest axis (Newell's normal, right for any
 * simple polygon, concave or not). */
static void flatten(const scene_builder *bld, const int *vi, int n, double (*p)[2])
{
    double nn[3] = { 0, 0, 0 }, c[3];
    int k, ax, ux, vx;
    for (k = 0; k < n; k++) {
        double a[3], c[3];
        bld->vertex_at(bld->user, vi[k], a);
        bld->vertex_at(bld->user, vi[(k + 1) % n], c);
        nn[0] += (a[1] - c[1]) * (a[2] + c[2]);
        nn[1] += (a[2] - c[2]) * (a[0] + c[0]);
        nn[2] += (a[0] - c[0]) * (a[1] + c[1]);
    }
    ax = fabs(nn[0]) > fabs(nn[1]) ? (fabs(nn[0]) > fabs(nn[2]) ? 0 : 2)
                                   : (fabs(nn[1]) > fabs(nn[2]) ? 1 : 2);
    ux = (ax + 1) % 3;            /* (ux, vx, ax) is right-handed: seen from */
    vx = (ax + 2) % 3;            /* +ax, counter-clockwise is positive area */
    if (nn[ax] < 0) { k = ux; ux = vx; vx = k; }
    for (k = 0; k < n; k++) {
        bld->vertex_at(bld->user, vi[k], c);
        p[k][0] = c[ux];
        p[k][1] = c[vx];
    }
}

/* Corner b, between a and c, can be cut off: it turns left, and no corner
 * lies in the triangle a b c.  Only the corners in bent[0..nbent-1], those
 * that do not turn left, are looked at: if any corner lies in the triangle,
 * one of those does (Eberly, "Triangulation by ear clipping", 2002), so the
 * test takes time in proportion to the dents, not to all the corners. */
static int is_ear(double (*p)[2], const int *bent, int nbent, int a, int b, int c)
{
    int j;
    if (area2(p[a], p[b], p[c]) <= 0) return 0;         /* reflex or flat */
    for (j = 0; j < nbent; j++) {
        const double *q = p[bent[j]];
        if (inside2(q, p[a], p[b], p[c]) && memcmp(q, p[a], sizeof *p)
            && memcmp(q, p[b], sizeof *p) && memcmp(q, p[c], sizeof *p))
            return 0;
    }
    return 1;
}

/* The triangle of corners i, j, k of the polygon. */
static void add_corner_triangle(const scene_builder *bld, const int *vi, const int *ni, int i, int j, int k,
                                int mat)
{
    int v[3], nv[3];
    v[0] = vi[i], v[1] = vi[j], v[2] = vi[k];
    nv[0] = ni ? ni[i] : -1, nv[1] = ni ? ni[j] : -1, nv[2] = ni ? ni[k] : -1;
    bld->triangle(bld->user, v, nv, mat);
}

/* Corners a..b of a convex polygon, closed by the edge b-a: the triangle
 * a, m, b with m halfway, then the two arcs it leaves.  Unlike a fan from
 * one corner, no vertex is shared by more than a few triangles, and they
 * shrink towards the rim: a fan of thousands of slivers meeting at a point
 * is the kd-tree's worst case (every cell near the point holds them all). */
static void triangulate_arc(const scene_builder *bld, const int *vi, const int *ni, int a, int b, int mat)
{
    int m = a + (b - a) / 2;
    if (b - a < 2) return;
    add_corner_triangle(bld, vi, ni, a, m, b, mat);
    triangulate_arc(bld, vi, ni, a, m, mat);
    triangulate_arc(bld, vi, ni, m, b, mat);
}

/* Take corner k off the list bent[0..*nbent-1]; pos[k] is its place there,
 * -1 once it is not listed. */
static void unlist(int *bent, int *nbent, int *pos, int k)
{
    int last = bent[--*nbent];
    bent[pos[k]] = last, pos[last] = pos[k], pos[k] = -1;
}

/* Keep corner k listed in bent[] while it does not turn left, between
 * corners prev[k] and next[k]. */
static void note_bend(double (*p)[2], const int *prev, const int *next, int k, int *bent,
                      int *nbent, int *pos)
{
    int left = area2(p[prev[k]], p[k], p[next[k]]) > 0;
    if (!left && pos[k] < 0) pos[k] = *nbent, bent[(*nbent)++] = k;
    if (left && pos[k] >= 0) unlist(bent, nbent, pos, k);
}

/* A planar polygon, convex or not, as triangles, by ear clipping (Meisters,
 * "Polygons have ears", 1975): some corner can always be cut off, leaving a
 * polygon one corner smaller.  A fan from one corner would be wrong for the
 * gears' concave 144-gons; a convex polygon takes the O(n) way above.
 * The ears are sought going round the polygon, and after each cut the
 * search goes on two corners further, not at the next one: trying the next
 * corner first would cut ears a, c, d then a, d, e and so on, a fan at a
 * (one dent in an 8000-gon put all 7998 triangles at one corner, and the
 * kd-tree took 10 s to build).  Going round, each lap cuts every other
 * corner, as triangulate_arc halves an arc, so a corner ends up in a few
 * triangles per lap and about log2 n laps.  A polygon whose only
 * triangulation is a fan (every corner but one a dent, facing it) still
 * gives one; the kd-tree copes with that too.
 * vi and ni are the corners' vertex and normal indices (ni may be NULL). */
void triangulate(const scene_builder *bld, const int *vi, const int *ni, int n, int mat)
{
    double (*p)[2] = malloc((size_t)n * sizeof *p);
    int *next = malloc((size_t)n * sizeof *next), *prev = malloc((size_t)n * sizeof *prev);
    int *bent = malloc((size_t)n * sizeof *bent), *pos = malloc((size_t)n * sizeof *pos);
    int m = n, k, nbent = 0, convex = 1;
    if (!p || !next || !prev || !bent || !pos) out_of_memory();
    flatten(bld, vi, n, p);
    for (k = 0; k < n; k++) next[k] = (k + 1) % n, prev[k] = (k + n - 1) % n, pos[k] = -1;
    for (k = 0; k < n; k++) {
        if (area2(p[prev[k]], p[k], p[next[k]]) < 0) convex = 0;
        note_bend(p, prev, next, k, bent, &nbent, pos);
    }
    if (convex) triangulate_arc(bld, vi, ni, 0, n - 1, mat);
    for (k = 0; !convex && m > 2; m--) {
        int tries, a, c;
        for (tries = 0; m > 3 && tries < m && !is_ear(p, bent, nbent, prev[k], k, next[k]); tries++)
            k = next[k];
        /* tries == m: only flat or self-touching corners are left; cut one anyway */
        a = prev[k], c = next[k];
        add_corner_triangle(bld, vi, ni, a, k, c, mat);
        next[a] = c, prev[c] = a;
        if (pos[k] >= 0) unlist(bent, &nbent, pos, k);  /* cut anyway */
        note_bend(p, prev, next, a, bent, &nbent, pos);
        note_bend(p, prev, next, c, bent, &nbent, pos);
        k = next[c];
    }
    free(p), free(next), free(prev), free(bent), free(pos);
}

/* A colour or a weight beyond 1e30 would overflow to infinity in a few
 * products (and infinity times a weight of 0 is NaN), and an index of
 * refraction beyond 1e6 either way makes refraction cancel two huge terms
 * and return a direction that is no unit vector: both are refused (the
 * fuzz targets found NaN pixels from each).  So is a colour or weight
 * below 0: light taken away, negative radiance in a PFM. */
#define COLOR_LIMIT 1e30
#define COLOR_RULE "must lie within 1e30 and be 0 or more"
static int in_range(double x) { return x >= 0 && x <= COLOR_LIMIT; }
static int color_ok(const double *c) { return in_range(c[0]) && in_range(c[1]) && in_range(c[2]); }
static int within_limit(const double *c)    /* either way: a velocity */
{
    return fabs(c[0]) <= COLOR_LIMIT && fabs(c[1]) <= COLOR_LIMIT && fabs(c[2]) <= COLOR_LIMIT;
}

/* The material m into the scene: *mat its index.  A material whose kd + ks
 * + kt exceeds 1 is named in a warning for the path tracer (which scales
 * such weights down to 1), one whose ks + kt does in a warning for
 * Whitted's (whose model takes them as they are: light out of nothing). */
static int add_material(const scene_builder *b, Where w, const scene_material *m, int *mat)
{
    char msg[256];
    double k[3];
    k[0] = m->kd, k[1] = m->ks, k[2] = m->kt;
    if (!(m->ir >= 1e-6 && m->ir <= 1e6))
        return fail(w, "index of refraction must be between 1e-6 and 1e6", NULL);
    if (!color_ok(m->color) || !color_ok(k) || !in_range(m->kl))
        return fail(w, "colours and weights " COLOR_RULE, NULL);
    if ((*mat = b->material(b->user, m, msg)) < 0) return fail(w, msg, NULL);
    if (m->kd + m->ks + m->kt > 1) {
        sprintf(msg, "%.100s:%d: warning: kd + ks + kt = %.3g exceeds 1; the path tracer scales"
                " them to 1", w.file, w.line, m->kd + m->ks + m->kt);
        b->warning(b->user, 1, msg);
    }
    if (m->kd * fmax(m->color[0], fmax(m->color[1], m->color[2])) > 1) {
        sprintf(msg, "%.100s:%d: warning: kd times the colour = %.3g exceeds 1: the path tracer's"
                " surface reflects more light than it receives", w.file, w.line,
                m->kd * fmax(m->color[0], fmax(m->color[1], m->color[2])));
        b->warning(b->user, 1, msg);
    }
    if (m->ks + m->kt > 1) {
        sprintf(msg, "%.100s:%d: warning: ks + kt = %.3g exceeds 1: what is reflected and"
                " refracted grows at every bounce, light out of nothing", w.file, w.line,
                m->ks + m->kt);
        b->warning(b->user, 0, msg);
    }
    return 1;
}

/* r g b kd ks kt kl ir: minray's material fields, for tri, cone and mesh
 * lines. */
static int card_material(const scene_builder *b, Where w, const double *v, int *mat)
{
    scene_material m;
    m.color[0] = v[0], m.color[1] = v[1], m.color[2] = v[2];
    m.kd = v[3]; m.ks = v[4]; m.kt = v[5]; m.kl = v[6]; m.ir = v[7]; m.shine = 0;
    return add_material(b, w, &m, mat);
}

/* One sphere: minray's 12 numbers in minray's order (the centre, the
 * colour, the radius, kd ks kt kl ir). */
static int parse_sphere(const scene_builder *b, Where w, char **tok, int ntok)
{
    double v[12], m[8];
    char why[SCENE_WHY];
    int mat;
    if (!numbers(w, "a sphere", tok, ntok, 0, 12, v)) return 0;
    if (!(v[6] > 0)) return fail(w, "sphere radius must be positive", tok[6]);
    m[0] = v[3]; m[1] = v[4]; m[2] = v[5];
    m[3] = v[7]; m[4] = v[8]; m[5] = v[9]; m[6] = v[10]; m[7] = v[11];
    if (!card_material(b, w, m, &mat)) return 0;
    return b->sphere(b->user, v, v[6], mat, why) || fail(w, why, NULL);
}

/* bx by bz rb  ax ay az ra: a cone's base and apex, each with its radius. */
static int add_cone(const scene_builder *b, Where w, const double *x, int mat)
{
    char why[SCENE_WHY];
    return b->cone(b->user, x, x[3], x + 4, x[7], mat, why) || fail(w, why, NULL);
}

static int add_light(const scene_builder *b, Where w, const double *pos, const double *color)
{
    char why[SCENE_WHY];
    if (!color_ok(color)) return fail(w, "a light's colour " COLOR_RULE, NULL);
    return b->light(b->user, pos, color, why) || fail(w, why, NULL);
}

static int set_camera(const scene_builder *b, Where w, const double *v)
{
    char why[SCENE_WHY];
    return b->camera(b->user, v, why) || fail(w, why, NULL);
}

static void set(const scene_builder *b, int what, double v0, double v1, double v2)
{
    double v[3];
    v[0] = v0, v[1] = v1, v[2] = v2;
    b->setting(b->user, what, v, NULL);
}

int check_size(double fw, double fh, int *width, int *height)
{
    if (!(fw >= 1 && fh >= 1 && fw <= 32768 && fh <= 32768 && fw == floor(fw) && fh == floor(fh)
          && fw * fh <= 268435456.0))
        return 0;
    *width = (int)fw;
    *height = (int)fh;
    return 1;
}

static int blank(int c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

/* Splits a line in place into at most max blank-separated tokens; '#'
 * starts a comment.  Returns max + 1 when there are more.  With quotes, a
 * token in double quotes keeps its blanks and '#' (mesh "my model.obj"),
 * and a quote left open, or not followed by a blank, gives -1. */
static int tokens(char *line, char **tok, int max, int quotes)
{
    int n = 0;
    char *p = line;
    for (;;) {
        while (blank(*p)) p++;
        if (!*p || *p == '#') return n;
        if (n == max) return max + 1;
        if (quotes && *p == '"') {
            tok[n++] = ++p;
            while (*p && *p != '"') p++;
            if (!*p) return -1;
            *p++ = 0;
            if (*p && !blank(*p)) return -1;
            continue;
        }
        tok[n++] = p;
        while (*p && *p != '#' && !blank(*p)) p++;
        if (*p == '#') { *p = 0; return n; }
        if (*p) *p++ = 0;
    }
}

#define BOM "\xEF\xBB\xBF"          /* UTF-8's byte order mark, which some editors write */

/* Reads the next line of f into line, without its end: "\n", "\r\n" or a
 * lone "\r" (old Mac files) each end a line.  A byte order mark before the
 * first line is skipped.  0 at the end of the file, or after a message
 * (*ok cleared) on an over-long line or a NUL byte, which no text has. */
static int next_line(FILE *f, char *line, int size, Where *w, int *ok)
{
    int c = getc(f), n = 0;
    if (c == EOF) return 0;
    w->line++;
    for (; c != EOF && c != '\n' && c != '\r'; c = getc(f)) {
        if (c == 0) return *ok = fail(*w, "NUL byte: this is not a text file", NULL);
        if (n == size - 1) {
            char msg[64];
            sprintf(msg, "line longer than %d characters", size - 1);
            return *ok = fail(*w, msg, NULL);
        }
        line[n++] = (char)c;
    }
    if (c == '\r' && (c = getc(f)) != '\n' && c != EOF) ungetc(c, f);
    line[n] = 0;
    if (w->line == 1 && !strncmp(line, BOM, 3)) memmove(line, line + 3, (size_t)n - 2);
    return 1;
}

/* An OBJ face corner "v", "v/t", "v//n" or "v/t/n"; indices count from 1,
 * or back from the newest when negative.  *n is -1 without a normal. */
static int obj_corner(Where w, char *c, int nv, int nn, int *v, int *n)
{
    char *end, *slash;
    long i = strtol(c, &end, 10);
    if (end == c || (*end && *end != '/')) return fail(w, "bad face corner", c);
    if (i < 0) i += nv + 1;
    if (i < 1 || i > nv) return fail(w, "vertex index out of range", c);
    *v = (int)i - 1;
    *n = -1;
    slash = strchr(c, '/');
    if (slash && (slash = strchr(slash + 1, '/')) && slash[1]) {
        i = strtol(slash + 1, &end, 10);
        if (end == slash + 1 || *end) return fail(w, "bad face corner", c);
        if (i < 0) i += nn + 1;
        if (i < 1 || i > nn) return fail(w, "normal index out of range", c);
        *n = (int)i - 1;
    }
    return 1;
}

#ifdef RAY_POSIX
/* A mesh that a scene names must be a plain file: a directory has no
 * lines, and a pipe or a terminal would wait for input for ever.  (Not
 * found: fopen says so.) */
static int plain_file(const char *name)
{
    struct stat st;
    return stat(name, &st) != 0 || S_ISREG(st.st_mode);
}
#else
static int plain_file(const char *name) { (void)name; return 1; }
#endif

/* Wavefront OBJ: v, vn and f (any number of corners); every other statement
 * is skipped with one warning for the file.  Its vertices are numbered from
 * v0 on in the scene, its normals from n0. */
#define OBJ_LINE 65536                  /* room for faces of thousands of corners */

int read_obj(const scene_builder *b, const char *file, int mat, const char *scene, int at)
{
    int max = OBJ_LINE / 2, v0 = 0, n0 = 0, nv = 0, nn = 0, ok = 1, skipped = 0, skipped_line = 0;
    char *line = malloc(OBJ_LINE), **tok = malloc(sizeof *tok * (max + 1)), first_skipped[32] = "";
    int *vi = malloc(sizeof *vi * max), *ni = malloc(sizeof *ni * max);
    Where w, from;
    int plain = plain_file(file);
    FILE *f = plain ? fopen(file, "r") : NULL;
    char why[SCENE_WHY + 64];
    if (!line || !tok || !vi || !ni) out_of_memory();
    from.file = scene;
    from.line = at;
    sprintf(why, "%.*s (%.60s)", SCENE_WHY, file, plain && !f ? strerror(errno) : "");
    if (b->output && same_file(file, b->output)) {
        ok = fail(from, "the mesh is the output file (-o); not overwritten", file);
        if (f) fclose(f), f = NULL;
    } else if (!plain) ok = fail(from, "mesh is not a plain file (a directory, device or pipe)", file);
    else if (!f) ok = fail(from, "cannot open mesh", why);     /* which path, and why not */
    w.file = file;
    w.line = 0;
    while (ok && next_line(f, line, OBJ_LINE, &w, &ok)) {
        int n = tokens(line, tok, max, 0), k, with_normals = 1;
        double x[3];
        if (n == 0) continue;
        if (n > max) ok = fail(w, "too many fields", NULL);
        else if (!strcmp(tok[0], "v") || !strcmp(tok[0], "vn")) {
            int normal = tok[0][1] == 'n';
            /* a vertex may go on with w, or with a colour: both unused */
            ok = numbers(w, tok[0], tok, normal || n < 4 ? n : 4, 1, 3, x);
            if (ok && normal && (k = b->normal(b->user, x)) >= 0 && !nn++) n0 = k;
            if (ok && !normal && (ok = (k = vertex(b, w, x)) >= 0) && !nv++) v0 = k;
        } else if (!strcmp(tok[0], "f")) {
            if (n < 4) ok = fail(w, "a face needs 3 corners or more", NULL);
            for (k = 1; k < n && ok; k++) {
                ok = obj_corner(w, tok[k], nv, nn, &vi[k - 1], &ni[k - 1]);
                vi[k - 1] += v0;
                if (ni[k - 1] < 0) with_normals = 0;
                else ni[k - 1] += n0;
            }
            if (ok) triangulate(b, vi, with_normals ? ni : NULL, n - 1, mat);
        } else if (!skipped++) {
            skipped_line = w.line;
            sprintf(first_skipped, "%.20s", tok[0]);
        }
    }
    if (ok && ferror(f)) ok = fail(w, "cannot read mesh", strerror(errno)); /* mesh . */
    if (f) fclose(f);
    if (ok && skipped) {
        fprintf(stderr, "%s:%d: warning: skipped %d statement%s that are not v, vn or f"
                " (the first: ", file, skipped_line, skipped, skipped == 1 ? "" : "s");
        put_escaped(stderr, first_skipped);
        fputs(")\n", stderr);
    }
    free(line); free(tok); free(vi); free(ni);
    return ok;
}

/* Windows paths separate directories with \ as well as /, and may start
 * with a drive ("C:"); elsewhere \ and : are ordinary characters of a file
 * name.  -DRAY_DOS_PATHS gives the Windows rule anywhere, for the tests. */
#if defined(_WIN32) && !defined(RAY_DOS_PATHS)
#define RAY_DOS_PATHS
#endif

static int path_separator(int c)
{
#ifdef RAY_DOS_PATHS
    return c == '/' || c == '\\' || c == ':';
#else
    return c == '/';
#endif
}

/* Where the file's own name starts in path: after the last separator. */
const char *file_part(const char *path)
{
    const char *p, *name = path;
    for (p = path; *p; p++)
        if (path_separator(*p)) name = p + 1;
    return name;
}

/* A path from the root (or a drive), which no directory may prefix. */
static int absolute(const char *path)
{
#ifdef RAY_DOS_PATHS
    if (path[0] && path[1] == ':') return 1;
#endif
    return path_separator(path[0]);
}

/* A path named in a scene is relative to the scene's directory. */
char *beside(const char *scene, const char *name)
{
    size_t dir = absolute(name) ? 0 : (size_t)(file_part(scene) - scene);
    char *p = malloc(dir + strlen(name) + 1);
    if (!p) out_of_memory();
    memcpy(p, scene, dir);
    strcpy(p + dir, name);
    return p;
}

/* The structures --accel and a scene's `accel` line name (see build_accel):
 * the name as a string that lasts, or NULL for an unknown one. */
const char *accel_name(const char *name)
{
    static const char *const names[] = { "kd", "bvh", "grid", "none", "auto" };
    size_t i;
    for (i = 0; i < sizeof names / sizeof names[0]; i++)
        if (!strcmp(name, names[i])) return names[i];
    return NULL;
}


/* The keywords that take one of two words: the first sets the setting to
 * 1, the second to 0. */
static const struct { const char *key, *yes, *no, *expect; int what; } pairs[] = {
    { "tir", "reflect", "black", "expected `tir reflect` or `tir black`", SET_TIR_REFLECT },
    { "integrator", "path", "whitted", "expected `integrator path` or `integrator whitted`",
      SET_PATH },
    { "pixel", "corner", "centre", "expected `pixel corner` or `pixel centre`", SET_PIXEL_CORNER },
    { "sided", "1", "2", "expected `sided 1` (front faces only) or `sided 2`", SET_ONE_SIDED },
    { "lights", "centre", "area", "expected `lights centre` (minray's: a glowing sphere lights from"
      " its centre) or `lights area`", SET_LIGHTS_CENTRE }
};

/* The keywords that take one number, and the numbers each allows. */
static const struct { const char *key; double lo, hi; int whole; const char *rule; int what; } ones[] = {
    { "depth", 1, 64, 1, "depth must be a whole number from 1 to 64", SET_DEPTH },
    { "samples", 1, 1 << 20, 1, "samples must be a whole number from 1 to 1048576", SET_SAMPLES },
    { "hither", 0, HUGE_VAL, 0, "hither must be 0 or more", SET_HITHER },
    { "shadow", 1, 4096, 1, "shadow rays must be a whole number from 1 to 4096", SET_SHADOW_RAYS },
    { "glossy", 0, 1e6, 0, "glossy exponent must be from 0 to 1e6", SET_GLOSSY }
};

/* Times of the shutter within 1e6 either way, velocities within 1e30
 * (within_limit's bound): a displacement time x velocity stays below 1e36,
 * within even a float's range. */
#define TIME_LIMIT 1e6

/* A keyword line: ray.c's extensions to minray's format.  Motion blur:
 * `shutter T0 T1` says when the shutter opens and closes (default 0 1);
 * `move DX DY DZ` gives every object that follows (sphere lines, tri,
 * cone, mesh) that velocity, until the next `move` (`move 0 0 0`: at
 * rest again).  At time t such an object stands where its line puts it
 * plus t times its velocity; each sample sees one instant of the
 * shutter. */
static int parse_keyword(const scene_builder *b, Where w, char **tok, int ntok)
{
    double v[17];
    const char *k = tok[0];
    int mat, ok, size[2], i, sphere = 0;
    if (!strcmp(k, "accel")) {
        if (ntok != 2 || !accel_name(tok[1]))
            return fail(w, "expected `accel` and one of kd, bvh, grid, none, auto", NULL);
        b->setting(b->user, SET_ACCEL, NULL, accel_name(tok[1]));
        return 1;
    }
    if (!strcmp(k, "size")) {
        if (!numbers(w, k, tok, ntok, 1, 2, v)) return 0;
        if (!check_size(v[0], v[1], &size[0], &size[1])) return fail(w, SIZE_RULE, NULL);
        set(b, SET_SIZE, size[0], size[1], 0);
        return 1;
    }
    if (!strcmp(k, "lens")) {
        if (!numbers(w, k, tok, ntok, 1, 2, v)) return 0;
        if (!(v[0] >= 0 && v[0] <= 1e30)) return fail(w, "lens radius must be from 0 to 1e30", tok[1]);
        if (!(v[1] > 0 && v[1] <= 1e30))
            return fail(w, "focus distance must be positive, at most 1e30", tok[2]);
        set(b, SET_LENS, v[0], v[1], 0);
        return 1;
    }
    if (!strcmp(k, "hither") && ntok == 3) {  /* `hither D sphere`: D from the eye, as smallpt's */
        if (strcmp(tok[2], "plane") && strcmp(tok[2], "sphere"))
            return fail(w, "expected `hither D`, `hither D plane` or `hither D sphere`", tok[2]);
        sphere = !strcmp(tok[2], "sphere");
        ntok = 2;
    }
    for (i = 0; i < (int)(sizeof ones / sizeof *ones); i++)
        if (!strcmp(k, ones[i].key)) {
            if (!numbers(w, k, tok, ntok, 1, 1, v)) return 0;
            if (!(v[0] >= ones[i].lo && v[0] <= ones[i].hi && (!ones[i].whole || v[0] == floor(v[0]))))
                return fail(w, ones[i].rule, tok[1]);
            set(b, ones[i].what, v[0], sphere, 0);
            return 1;
        }
    if (!strcmp(k, "rough")) {          /* like `sided`: for what follows, until the next */
        if (!numbers(w, k, tok, ntok, 1, 1, v)) return 0;
        if (!(v[0] == 0 || (v[0] >= 1e-3 && v[0] <= 1)))
            return fail(w, "rough must be 0 (smooth: a mirror) or from 0.001 to 1", tok[1]);
        set(b, SET_ROUGH, v[0], 0, 0);
        return 1;
    }
    if (!strcmp(k, "ambient") || !strcmp(k, "background")) {
        if (!numbers(w, k, tok, ntok, 1, 3, v)) return 0;
        if (!color_ok(v)) return fail(w, k[0] == 'a' ? "ambient " COLOR_RULE : "background " COLOR_RULE, NULL);
        set(b, k[0] == 'a' ? SET_AMBIENT : SET_BACKGROUND, v[0], v[1], v[2]);
        return 1;
    }
    if (!strcmp(k, "camera")) return numbers(w, k, tok, ntok, 1, 10, v) && set_camera(b, w, v);
    if (!strcmp(k, "light"))
        return numbers(w, k, tok, ntok, 1, 6, v) && add_light(b, w, v, v + 3);
    if (!strcmp(k, "pixel") && ntok == 2 && !strcmp(tok[1], "center")) tok[1] = "centre";
    for (i = 0; i < (int)(sizeof pairs / sizeof *pairs); i++)
        if (!strcmp(k, pairs[i].key)) {
            if (ntok != 2 || (strcmp(tok[1], pairs[i].yes) && strcmp(tok[1], pairs[i].no)))
                return fail(w, pairs[i].expect, NULL);
            set(b, pairs[i].what, !strcmp(tok[1], pairs[i].yes), 0, 0);
            return 1;
        }
    if (!strcmp(k, "shutter")) {        /* shutter T0 T1: open from time T0 to T1 */
        if (!numbers(w, k, tok, ntok, 1, 2, v)) return 0;
        if (!(v[0] <= v[1] && fabs(v[0]) <= TIME_LIMIT && fabs(v[1]) <= TIME_LIMIT))
            return fail(w, "shutter needs two times, the first no later than the second,"
                        " each within 1e6 either way", NULL);
        set(b, SET_SHUTTER, v[0], v[1], 0);
        return 1;
    }
    if (!strcmp(k, "move")) {           /* move DX DY DZ: the velocity of what follows */
        if (!numbers(w, k, tok, ntok, 1, 3, v)) return 0;
        if (!within_limit(v)) return fail(w, "a velocity must lie within 1e30 either way", NULL);
        set(b, SET_MOVE, v[0], v[1], v[2]);
        return 1;
    }
    if (!strcmp(k, "tri")) {
        int c[3], none[3] = { -1, -1, -1 };
        if (!numbers(w, k, tok, ntok, 1, 17, v) || !card_material(b, w, v + 9, &mat)) return 0;
        for (i = 0; i < 3; i++)
            if ((c[i] = vertex(b, w, v + 3 * i)) < 0) return 0;
        b->triangle(b->user, c, none, mat);
        return 1;
    }
    if (!strcmp(k, "cone"))
        return numbers(w, k, tok, ntok, 1, 16, v) && card_material(b, w, v + 8, &mat)
               && add_cone(b, w, v, mat);
    if (!strcmp(k, "mesh")) {
        char *path;
        if (ntok < 2) return fail(w, "mesh needs a file name and 8 numbers", NULL);
        if (!numbers(w, k, tok, ntok, 2, 8, v) || !card_material(b, w, v, &mat)) return 0;
        path = beside(w.file, tok[1]);
        ok = read_obj(b, path, mat, w.file, w.line);
        free(path);
        return ok;
    }
    return fail(w, "unknown keyword", k);
}

static int load_sph(const scene_builder *b, FILE *f, Where w)
{
    char line[4096], *tok[24];
    int ok = 1;
    while (ok && next_line(f, line, sizeof line, &w, &ok)) {
        int n = tokens(line, tok, 23, 1);
        if (n > 23) ok = fail(w, "too many fields", NULL);
        else if (n < 0) ok = fail(w, "a quote is left open, or runs into the next field", NULL);
        else if (n == 0) continue;
        else if (strchr("+-.0123456789", tok[0][0])) ok = parse_sphere(b, w, tok, n);
        else ok = parse_keyword(b, w, tok, n);
    }
    return ok;
}

/* ---------- NFF, Eric Haines' Neutral File Format (the SPD scenes' format) */

/* NFF is a stream of blank-separated tokens, not of lines (a cone's eight
 * numbers may sit on one line or three), so it is read a token at a time.
 * `again` hands the last token out once more, for a look ahead. */
typedef struct { FILE *f; Where w; int c, prev, again; char tok[256]; } Lexer;

/* On to the next character, counting lines: "\n", "\r\n" and a lone
 * "\r" each end one. */
static void advance(Lexer *lx)
{
    if (lx->c == '\r' || (lx->c == '\n' && lx->prev != '\r')) lx->w.line++;
    lx->prev = lx->c;
    lx->c = getc(lx->f);
}

/* The next token into lx->tok: 1, or 0 at the end of the file, or -1 after
 * saying what is wrong. */
static int next_token(Lexer *lx)
{
    int n = 0;
    if (lx->again) { lx->again = 0; return 1; }
    for (;;) {
        while (blank(lx->c)) advance(lx);
        if (lx->c != '#') break;
        while (lx->c != '\n' && lx->c != '\r' && lx->c != EOF && lx->c != 0) advance(lx);
    }
    for (; lx->c != EOF && !blank(lx->c); advance(lx)) {
        if (lx->c == 0) {
            fail(lx->w, "NUL byte: this is not a text file", NULL);
            return -1;
        }
        if (n == (int)sizeof lx->tok - 1) {
            fail(lx->w, "token longer than 255 characters", NULL);
            return -1;
        }
        lx->tok[n++] = (char)lx->c;
    }
    lx->tok[n] = 0;
    return n > 0;
}

/* n numbers in a row, after `what`. */
static int nff_numbers(Lexer *lx, const char *what, int n, double *out)
{
    int i;
    for (i = 0; i < n; i++) {
        int got = next_token(lx);
        if (got == 0) return fail(lx->w, "the file ends inside", what);
        if (got < 0 || !number(lx->w, lx->tok, &out[i])) return 0;
    }
    return 1;
}

/* The view block: from, at, up, angle, hither, resolution, each once.  NFF's
 * angle spans the centres of the outer pixels, (W-1) pixels, where ours
 * spans the edges, W pixels. */
static int nff_view(const scene_builder *b, Lexer *lx)
{
    static const char *const names[6] = { "from", "at", "up", "angle", "hither", "resolution" };
    static const int counts[6] = { 3, 3, 3, 1, 1, 2 };
    double x[6][3], v[10];
    int seen = 0, k, got = 1, size[2];
    while (seen != 63 && (got = next_token(lx)) > 0) {
        for (k = 0; k < 6 && strcmp(lx->tok, names[k]); k++) continue;
        if (k == 6)
            return fail(lx->w, "expected from, at, up, angle, hither or resolution", lx->tok);
        if (seen & 1 << k) return fail(lx->w, "said twice in the view block", names[k]);
        seen |= 1 << k;
        if (!nff_numbers(lx, names[k], counts[k], x[k])) return 0;
    }
    if (got < 0) return 0;
    if (seen != 63)
        return fail(lx->w, "the view block needs from, at, up, angle, hither and resolution", NULL);
    if (!check_size(x[5][0], x[5][1], &size[0], &size[1])) return fail(lx->w, SIZE_RULE, NULL);
    if (!(x[3][0] > 0 && x[3][0] < 180))
        return fail(lx->w, "view angle must be between 0 and 180 degrees", NULL);
    for (k = 0; k < 9; k++) v[k] = x[k / 3][k % 3];   /* from, at, up */
    set(b, SET_SIZE, size[0], size[1], 0);
    if (x[4][0] > 0) set(b, SET_HITHER, x[4][0], 0, 0);
    v[9] = (double)(REAL)(2 * atan(tan(x[3][0] * PI / 360) * size[0] / (size[0] > 1 ? size[0] - 1 : 1))
                          * 180 / PI);
    return set_camera(b, lx->w, v);
}

/* A polygon of n corners, with a normal at each (pp) or not (p). */
static int nff_polygon(const scene_builder *b, Lexer *lx, int normals, int mat)
{
    double x[6], cnt;
    int n, k, *vi, *ni, ok = 1;
    if (!nff_numbers(lx, normals ? "pp" : "p", 1, &cnt)) return 0;
    if (!(cnt >= 3 && cnt <= 1e6 && cnt == floor(cnt)))
        return fail(lx->w, "a polygon needs from 3 to 1000000 corners", lx->tok);
    n = (int)cnt;
    vi = malloc((size_t)n * sizeof *vi);
    ni = malloc((size_t)n * sizeof *ni);
    if (!vi || !ni) out_of_memory();
    for (k = 0; k < n && ok; k++) {
        ok = nff_numbers(lx, "a polygon", normals ? 6 : 3, x);
        if (!ok) break;
        ok = (vi[k] = vertex(b, lx->w, x)) >= 0;
        if (normals) ni[k] = b->normal(b->user, x + 3);
    }
    if (ok) triangulate(b, vi, normals ? ni : NULL, n, mat);
    free(vi);
    free(ni);
    return ok;
}

/* l x y z [r g b]: a point light, white unless a colour follows. */
static int nff_light(const scene_builder *b, Lexer *lx)
{
    double x[3], rgb[3] = { 1, 1, 1 };
    int got;
    Where at;
    if (!nff_numbers(lx, "l", 3, x)) return 0;
    at = lx->w;                              /* before the look ahead */
    got = next_token(lx);                    /* a colour, or the next entity */
    if (got < 0) return 0;
    lx->again = got > 0;
    if (got > 0 && strchr("+-.0123456789", lx->tok[0]) && !nff_numbers(lx, "l", 3, rgb)) return 0;
    return add_light(b, at, x, rgb);
}

/* b r g b: the colour of rays that hit nothing. */
static int nff_background(const scene_builder *b, Lexer *lx)
{
    double x[3];
    if (!nff_numbers(lx, "b", 3, x)) return 0;
    if (!color_ok(x)) return fail(lx->w, "background " COLOR_RULE, NULL);
    set(b, SET_BACKGROUND, x[0], x[1], x[2]);
    return 1;
}

/* f r g b Kd Ks Shine T ior: the material of all that follows. */
static int nff_material(const scene_builder *b, Lexer *lx, int *mat)
{
    double x[8];
    scene_material m;
    if (!nff_numbers(lx, "f", 8, x)) return 0;
    m.color[0] = x[0], m.color[1] = x[1], m.color[2] = x[2];
    m.kd = x[3]; m.ks = x[4]; m.shine = x[5]; m.kt = x[6]; m.kl = 0;
    m.ir = x[7] > 0 ? x[7] : 1;  /* the SPD files write 0 for opaque materials */
    return add_material(b, lx->w, &m, mat);
}

static int nff_sphere(const scene_builder *b, Lexer *lx, int mat)
{
    double x[4];
    char why[SCENE_WHY];
    if (!nff_numbers(lx, "s", 4, x)) return 0;
    /* In NFF (the SPD's NFF.TXT) a negative radius means a sphere seen
     * only from inside; objects are otherwise one-sided, seen from outside.
     * ray.c draws both sides of a sphere, so an eye within sees the inside
     * either way: the radius is |r|. */
    if (!(x[3] != 0)) return fail(lx->w, "sphere radius must not be 0", lx->tok);
    return b->sphere(b->user, x, fabs(x[3]), mat, why) || fail(lx->w, why, NULL);
}

/* c: base centre and radius, apex centre and radius. */
static int nff_cone(const scene_builder *b, Lexer *lx, int mat)
{
    double x[8];
    if (!nff_numbers(lx, "c", 8, x)) return 0;
    if (x[3] < 0 && x[7] < 0) {   /* seen only from inside, as a sphere's negative radius */
        x[3] = -x[3];
        x[7] = -x[7];
    }
    return add_cone(b, lx->w, x, mat);
}

/* The rest of a byte order mark, whose first byte is lx->c. */
static int skip_bom(Lexer *lx)
{
    int b1 = getc(lx->f), b2 = getc(lx->f);
    if (b1 != (unsigned char)BOM[1] || b2 != (unsigned char)BOM[2])
        return fail(lx->w, "not an NFF file: it starts with byte 0xEF, yet no UTF-8 byte order mark",
                    NULL);
    lx->c = getc(lx->f);
    return 1;
}

static int load_nff(const scene_builder *b, FILE *f, Where w)
{
    Lexer lx;
    int mat = -1, ok = 1, got = 1, lights = 0;
    double intensity;
    lx.f = f; lx.w = w; lx.w.line = 1; lx.c = getc(f); lx.prev = 0; lx.again = 0;
    if (lx.c == (unsigned char)BOM[0] && !skip_bom(&lx)) return 0;
    set(b, SET_TIR_REFLECT, 1, 0, 0);            /* the SPD's rule */
    while (ok && (got = next_token(&lx)) > 0) {
        const char *t = lx.tok;
        if (mat < 0 && strchr("spc", t[0])) {    /* objects before any f: plain white */
            scene_material m;
            m.color[0] = m.color[1] = m.color[2] = 1;
            m.kd = 1; m.ks = m.kt = m.kl = m.shine = 0; m.ir = 1;
            ok = add_material(b, lx.w, &m, &mat);
        }
        if (!ok) break;
        if (!strcmp(t, "v")) ok = nff_view(b, &lx);
        else if (!strcmp(t, "b")) ok = nff_background(b, &lx);
        else if (!strcmp(t, "l")) ok = nff_light(b, &lx), lights++;
        else if (!strcmp(t, "f")) ok = nff_material(b, &lx, &mat);
        else if (!strcmp(t, "s")) ok = nff_sphere(b, &lx, mat);
        else if (!strcmp(t, "c")) ok = nff_cone(b, &lx, mat);
        else if (!strcmp(t, "p")) ok = nff_polygon(b, &lx, 0, mat);
        else if (!strcmp(t, "pp")) ok = nff_polygon(b, &lx, 1, mat);
        else ok = fail(lx.w, "unknown NFF entity", t);
    }
    ok = ok && got == 0;                         /* the end, not a bad token */
    /* The SPD's suggested strength: sqrt(L) / (2 L) for each of L lights and
     * for the ambient, so that the total stays about the same for any L. */
    intensity = lights ? sqrt((double)lights) / (2.0 * lights) : 0;
    set(b, SET_LIGHT_SCALE, intensity, 0, 0);
    set(b, SET_AMBIENT, intensity, intensity, intensity);
    return ok;
}

/* Do paths a and b name one file?  Under POSIX by device and inode (through
 * links, however spelled).  Under Windows by the full path, in any case: its
 * file systems ignore case, so "x.sph", "./X.SPH" and "C:\\dir\\x.sph" are one
 * file there (not through links).  Elsewhere by name. */
int same_file(const char *a, const char *b)
{
#if defined(RAY_POSIX)
    struct stat x, y;
    return stat(a, &x) == 0 && stat(b, &y) == 0 && x.st_dev == y.st_dev && x.st_ino == y.st_ino;
#elif defined(_WIN32)
    char *x = _fullpath(NULL, a, 0), *y = _fullpath(NULL, b, 0);
    int same = x && y ? !_stricmp(x, y) : !strcmp(a, b);
    free(x);
    free(y);
    return same;
#else
    return !strcmp(a, b);
#endif
}

/* Does name end with ext (given in lower case), in any case? */
int has_extension(const char *name, const char *ext)
{
    size_t n = strlen(name), k = strlen(ext), i;
    if (n < k) return 0;
    for (i = 0; i < k; i++)
        if (tolower((unsigned char)name[n - k + i]) != ext[i]) return 0;
    return 1;
}

/* The scene by its name: NFF when it ends .nff (or .NFF), else the sphere
 * format. */
/* An OBJ file as the whole scene: its mesh in a grey Lambertian material,
 * and the renderer asked to frame it (SET_FRAME: a camera on its box, a
 * light), so that any mesh renders with one command. */
static int load_obj_alone(const scene_builder *b, const char *file)
{
    scene_material m;
    Where w;
    int mat;
    w.file = file;
    w.line = 0;
    m.color[0] = m.color[1] = m.color[2] = 0.8;
    m.kd = 0.8, m.ks = m.kt = m.kl = m.shine = 0, m.ir = 1;
    if (!add_material(b, w, &m, &mat) || !read_obj(b, file, mat, file, 0)) return 0;
    set(b, SET_FRAME, 1, 0, 0);
    return 1;
}

/* Standard input as a file that can be read twice (once to see its
 * format): a copy in a temporary file, which goes when it is closed. */
static FILE *copy_of_stdin(void)
{
    FILE *f = tmpfile();
    char buf[8192];
    size_t n;
    if (!f) return NULL;
    while ((n = fread(buf, 1, sizeof buf, stdin)) > 0)
        if (fwrite(buf, 1, n, f) != n) break;
    if (ferror(stdin) || ferror(f) || fseek(f, 0, SEEK_SET)) {
        fclose(f);
        return NULL;
    }
    return f;
}

/* Whether a scene without a name is NFF: its first word is one of NFF's
 * entities (v, b, l, f, s, c, p, pp), which are no keywords of the sphere
 * format, whose lines start with a number or a word.  f is rewound. */
static int looks_like_nff(FILE *f)
{
    static const char *const entities[] = { "v", "b", "l", "f", "s", "c", "p", "pp" };
    char line[4096], *tok[2];
    Where w;
    int ok = 1, n = 0, nff = 0;
    size_t i;
    w.file = "stdin";
    w.line = 0;
    while (n == 0 && next_line(f, line, sizeof line, &w, &ok)) n = tokens(line, tok, 1, 0);
    for (i = 0; n >= 1 && i < sizeof entities / sizeof entities[0]; i++) nff |= !strcmp(tok[0], entities[i]);
    rewind(f);
    return nff;
}

/* A scene from its file, or "-": standard input, in the sphere format or
 * NFF, its meshes named relative to the working directory. */
int read_scene(const scene_builder *b, const char *file)
{
    int from_stdin = !strcmp(file, "-"), ok;
    FILE *f = from_stdin ? copy_of_stdin() : fopen(file, "r");
    Where w;
    w.file = from_stdin ? "stdin" : file;
    w.line = 0;
    if (!f) return fail(w, from_stdin ? "cannot read standard input" : "cannot open scene", strerror(errno));
    if (!from_stdin && has_extension(file, ".obj")) {
        fclose(f);
        return load_obj_alone(b, file);
    }
    ok = (from_stdin ? looks_like_nff(f) : has_extension(file, ".nff")) ? load_nff(b, f, w) : load_sph(b, f, w);
    if (ok && ferror(f)) ok = fail(w, "read error", strerror(errno));
    fclose(f);
    return ok;
}

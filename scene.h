/* scene.h - reading scene files: the sphere format (minray's 12 numbers a
 * line, and ray.c's keywords), Wavefront OBJ meshes, and NFF (Eric Haines'
 * Neutral File Format, the SPD scenes').
 *
 * The readers know no renderer.  They parse a file, check what the file
 * itself can get wrong (a word where a number belongs, a face corner out
 * of range), and hand what they read to a builder: a table of callbacks
 * that the renderer fills in (ray.c's scene_builder()).  A callback that
 * refuses what it is given (a camera that looks at its own eye) says why in
 * `why`; the reader then prints it as FILE:LINE: WHY and stops.
 *
 * Numbers reach the builder as doubles already rounded to the renderer's
 * precision (REAL, as ray.c is built: -DREAL=float reads every number as a
 * float), so that a reader computing with them computes what the renderer
 * would.
 */
#ifndef SCENE_H
#define SCENE_H

#define SCENE_WHY 192       /* room for a builder's message */

/* A material: minray's weights (diffuse, mirror, transmitted, emitted), the
 * index of refraction inside, and a Phong exponent (0: none). */
typedef struct { double color[3], kd, ks, kt, kl, ir, shine; } scene_material;

/* The settings a scene file may make, each with its numbers or word. */
enum {
    SET_SIZE,           /* v[0] x v[1] pixels */
    SET_DEPTH,          /* v[0]: recursion depth, or the rays of a path */
    SET_SAMPLES,        /* v[0]: samples per pixel */
    SET_HITHER,         /* v[0]: the near clip; v[1] 1: a sphere round the eye, not a plane */
    SET_TIR_REFLECT,    /* v[0]: 1 past the critical angle kt goes to the mirror, 0 it is lost */
    SET_PATH,           /* v[0]: 1 path tracing, 0 Whitted */
    SET_AMBIENT,        /* v[0..2] */
    SET_BACKGROUND,     /* v[0..2] */
    SET_PIXEL_CORNER,   /* v[0]: 1 samples start on a pixel's corner, 0 on its centre */
    SET_ONE_SIDED,      /* v[0]: 1 the triangles still to come are seen from the front only */
    SET_LIGHT_SCALE,    /* v[0]: every light read so far is scaled by it (NFF's rule) */
    SET_ACCEL,          /* word: kd, bvh, grid, none or auto (from accel_name) */
    SET_LENS,           /* v[0]: a thin lens's radius (0: a pinhole), v[1]: the distance in focus */
    SET_LIGHTS_CENTRE,  /* v[0]: 1 Whitted's glowing spheres light from their centres (minray's
                         * rule), 0 from their whole surface (area lights) */
    SET_SHADOW_RAYS,    /* v[0]: Whitted's shadow rays to each area light, a sample */
    SET_GLOSSY,         /* v[0]: the Phong exponent of the materials still to come (0: none);
                         * Whitted's mirror ray spreads into its lobe */
    SET_SHUTTER,        /* v[0] <= v[1]: the times the shutter opens and closes */
    SET_MOVE,           /* v[0..2]: the velocity of the objects still to come (0: at rest) */
    SET_ROUGH,          /* v[0]: the GGX roughness alpha of the materials still to come (0: none) */
    SET_FRAME           /* an OBJ file alone: the renderer frames it (a camera, a light) */
};

/* What a renderer offers the readers.  Indices count from 0 in the order
 * of the calls: the first material is 0, the first vertex 0. */
typedef struct {
    void *user;                             /* handed back to every call */
    /* a material's index, or -1 and why it cannot be */
    int (*material)(void *user, const scene_material *m, char *why);
    int (*sphere)(void *user, const double centre[3], double radius, int mat, char *why);
    int (*cone)(void *user, const double base[3], double rbase, const double apex[3],
                double rapex, int mat, char *why);
    int (*vertex)(void *user, const double p[3], char *why); /* its index, or -1 */
    int (*normal)(void *user, const double n[3]);           /* its index */
    void (*vertex_at)(void *user, int i, double p[3]);      /* vertex i as it is kept */
    /* corners v[0..2], normals n[0..2] (n[0] < 0: none, shade flat) */
    void (*triangle)(void *user, const int v[3], const int n[3], int mat);
    int (*light)(void *user, const double pos[3], const double color[3], char *why);
    /* eye, look-at point, up, horizontal field of view in degrees */
    int (*camera)(void *user, const double v[10], char *why);
    void (*setting)(void *user, int what, const double *v, const char *word);
    /* said once when the path tracer (path 1) or Whitted's (0) starts */
    void (*warning)(void *user, int path, const char *text);
    const char *output;                     /* the image to be written (-o), which no mesh
                                             * may be; NULL: none */
} scene_builder;

/* The scene in file: NFF when its name ends .nff (any case), a Wavefront
 * OBJ mesh alone when .obj (then SET_FRAME), else the sphere format.  0
 * after a message on stderr. */
int read_scene(const scene_builder *b, const char *file);

/* A Wavefront OBJ mesh (v, vn and f) in material mat; `scene` and `line`
 * name the scene line that asked for it, for the message when it cannot be
 * opened. */
int read_obj(const scene_builder *b, const char *file, int mat, const char *scene, int line);

/* A planar polygon of n corners (vertex indices vi, normal indices ni or
 * NULL), convex or not, as triangles. */
void triangulate(const scene_builder *b, const int *vi, const int *ni, int n, int mat);

/* An image size in whole numbers within SIZE_RULE: 1 and *w, *h set. */
#define SIZE_RULE "image size must be whole numbers from 1 to 32768, at most 2^28 pixels"
int check_size(double fw, double fh, int *w, int *h);

/* The structures an `accel` line (and --accel) may name, as a string that
 * lasts, or NULL for an unknown name. */
const char *accel_name(const char *name);

/* File names, which the command line shares.  Windows paths separate with
 * \ and / and may start with a drive (-DRAY_DOS_PATHS: that rule anywhere). */
const char *file_part(const char *path);             /* the name after the directories */
char *beside(const char *scene, const char *name);   /* name relative to scene's directory */
int has_extension(const char *name, const char *ext);/* ext in lower case, in any case */
int same_file(const char *a, const char *b);         /* POSIX: through links; Windows: any case */

#endif

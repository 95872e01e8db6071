/* pfmerr - the error of a path-traced image against a reference, for make
 * bench: both are PFM files (linear radiance, as ./ray -o x.pfm writes).
 *
 *     cc -std=c99 -O2 -o pfmerr bench/pfmerr.c -lm
 *     ./pfmerr IMAGE.pfm REFERENCE.pfm [NORMALS.pfm]
 *
 * Either file may also be a plain PPM (P3, as smallpt writes it: bytes of
 * the linear value to the power 1/2.2), read back to linear values.
 * Prints one line, "rmse=R lit_rmse=L display_rmse=D clamped_rmse=C pixels=N", and with
 * NORMALS (./ray --view normal of the same scene and size) " floor_rmse=F
 * floor_pixels=M" after it:
 *   rmse          root mean square difference of the linear values, every
 *                 pixel and channel: the bench's measure
 *   lit_rmse      the same over the pixels whose reference is below 1 in
 *                 every channel: in the Cornell box, all but the lamp and
 *                 the pixels its edge crosses, where the noise of covering
 *                 the pixel (the same for every estimator) dominates
 *   display_rmse  of the images as shown: clamped to 0..1 and through the
 *                 sRGB curve, in 8-bit levels
 *   clamped_rmse  of the linear values clamped to 0..1, as smallpt clamps
 *                 them: of two seeds' images, over sqrt 2, their noise
 *   floor_rmse    rmse over the pixels whose first hit faces straight up
 *                 (y up: --view normal's 0.5 + n / 2 is (0.5, 1, 0.5)): the
 *                 floor seen directly, where the caustic's light lands, and
 *                 not the glass ball, whose images of the lamp only the
 *                 camera's paths can find, whatever the estimator
 * Exit status 0, or 2 on an error (unreadable file, sizes differ).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct { int w, h; float *px; } pfm;

/* A colour PFM ("PF", width, height, scale; little-endian when the scale is
 * negative), rows from the bottom.  0 with a message on any error. */
static int load(const char *name, pfm *img)
{
    FILE *f = fopen(name, "rb");
    char magic[3] = "";
    double scale;
    size_t n, i;
    unsigned char b[4];
    if (!f) { fprintf(stderr, "pfmerr: cannot open %s\n", name); return 0; }
    if (fscanf(f, "P3 %d %d %lf", &img->w, &img->h, &scale) == 3) {    /* smallpt's plain PPM */
        int v;
        n = img->w > 0 && img->h > 0 && img->w <= 32768 && img->h <= 32768 ? (size_t)img->w * img->h * 3 : 0;
        img->px = n ? malloc(n * sizeof *img->px) : NULL;
        for (i = 0; img->px && scale > 0 && i < n && fscanf(f, "%d", &v) == 1; i++)
            img->px[i] = (float)pow(v / scale, 2.2);
        fclose(f);
        if (!img->px || i < n) { fprintf(stderr, "pfmerr: %s is not a whole P3 PPM\n", name); return 0; }
        return 1;
    }
    rewind(f);
    if (fscanf(f, "%2s %d %d %lf", magic, &img->w, &img->h, &scale) != 4 || strcmp(magic, "PF")
        || img->w < 1 || img->h < 1 || img->w > 32768 || img->h > 32768 || scale == 0
        || fgetc(f) == EOF) {
        fprintf(stderr, "pfmerr: %s is not a colour PFM\n", name);
        fclose(f);
        return 0;
    }
    n = (size_t)img->w * img->h * 3;
    img->px = malloc(n * sizeof *img->px);
    for (i = 0; img->px && i < n && fread(b, 1, 4, f) == 4; i++) {
        uint32_t u = scale < 0 ? (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24
                               : (uint32_t)b[3] | (uint32_t)b[2] << 8 | (uint32_t)b[1] << 16 | (uint32_t)b[0] << 24;
        memcpy(&img->px[i], &u, 4);
    }
    fclose(f);
    if (!img->px || i < n) {
        fprintf(stderr, "pfmerr: %s is short\n", name);
        return 0;
    }
    return 1;
}

static double shown(double v)
{
    v = v < 0 ? 0 : v > 1 ? 1 : v;
    return 255 * (v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1 / 2.4) - 0.055);
}

int main(int argc, char **argv)
{
    pfm a, r, nm;
    double sum = 0, lit = 0, disp = 0, floor = 0, clamped = 0;
    long nlit = 0, nfloor = 0, k, n;
    if (argc != 3 && argc != 4) { fprintf(stderr, "usage: pfmerr IMAGE.pfm REFERENCE.pfm [NORMALS.pfm]\n"); return 2; }
    if (!load(argv[1], &a) || !load(argv[2], &r) || (argc == 4 && !load(argv[3], &nm))) return 2;
    if (a.w != r.w || a.h != r.h || (argc == 4 && (nm.w != a.w || nm.h != a.h))) {
        fprintf(stderr, "pfmerr: the sizes differ\n");
        return 2;
    }
    n = (long)a.w * a.h;
    for (k = 0; k < n; k++) {
        const float *p = a.px + 3 * k, *q = r.px + 3 * k;
        int c, bright = q[0] >= 1 || q[1] >= 1 || q[2] >= 1;
        int up = argc == 4 && fabs(nm.px[3 * k] - 0.5) < 1e-4 && fabs(nm.px[3 * k + 1] - 1) < 1e-4
                 && fabs(nm.px[3 * k + 2] - 0.5) < 1e-4;
        for (c = 0; c < 3; c++) {
            double d = (double)p[c] - q[c], e = shown(p[c]) - shown(q[c]);
            double g = fmin(1, fmax(0, p[c])) - fmin(1, fmax(0, q[c]));
            sum += d * d;
            clamped += g * g;
            disp += e * e;
            if (!bright) lit += d * d;
            if (up) floor += d * d;
        }
        nlit += !bright;
        nfloor += up;
    }
    printf("rmse=%.6g lit_rmse=%.6g display_rmse=%.4g clamped_rmse=%.6g pixels=%ld", sqrt(sum / (3.0 * n)),
           nlit ? sqrt(lit / (3.0 * nlit)) : 0.0, sqrt(disp / (3.0 * n)), sqrt(clamped / (3.0 * n)), n);
    if (argc == 4) printf(" floor_rmse=%.6g floor_pixels=%ld", nfloor ? sqrt(floor / (3.0 * nfloor)) : 0.0, nfloor);
    printf("\n");
    return 0;
}

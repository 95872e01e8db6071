/* Unit tests for the plumbing: the sRGB curve (ray.c), the PNG writer's
 * checksums (image.c), extensions, and how paths are split (scene.c and
 * cli.c; built once as is and once with -DRAY_DOS_PATHS, the Windows rule).
 * ray.c and image.c are included whole so that their static functions can
 * be called (the test links the other parts, not image.c); ray.c's main()
 * is renamed out of the way.  Prints "PASS name" / "FAIL name" lines for
 * tests/run.sh. */
#define main ray_main
#include "../ray.c"
#undef main
#include "../image.c"

#include "check.h"

/* The curve of IEC 61966-2-1 at points worked out by hand: its ends, where
 * the line meets the power (0.0031308 -> 0.04045, continuous to 1e-7),
 * middle grey 0.18 and one half. */
static void test_srgb(void)
{
    double below = srgb(0.0031308), above = srgb(0.0031308 + 1e-12);
    check(srgb(0) == 0 && fabs(srgb(1) - 1) < 1e-12, "sRGB: 0 -> 0 and 1 -> 1");
    check(fabs(below - 0.0404499) < 1e-7 && fabs(above - below) < 1e-7,
          "sRGB: the line and the power meet at 0.0031308 (0.04045)");
    check(fabs(srgb(0.18) - 0.4613561) < 1e-6 && fabs(srgb(0.5) - 0.7353570) < 1e-6,
          "sRGB: 0.18 -> 0.46136, 0.5 -> 0.73536");
    check(srgb(-1) < 0 && srgb(2) > 1, "sRGB: out of range stays out (to_byte clamps)");
}

/* CRC-32 and Adler-32 against their published check values. */
static void test_checksums(void)
{
    Png *png = malloc(sizeof *png);
    const unsigned char *nine = (const unsigned char *)"123456789";
    if (!png) exit(1);
    crc_table(png->crc);
    check((crc_update(png->crc, 0xFFFFFFFFUL, nine, 9) ^ 0xFFFFFFFFUL) == 0xCBF43926UL,
          "CRC-32 of \"123456789\" is cbf43926");
    check((crc_update(png->crc, 0xFFFFFFFFUL, (const unsigned char *)"IEND", 4) ^ 0xFFFFFFFFUL)
              == 0xAE426082UL,
          "CRC-32 of an IEND chunk is ae426082, as in every PNG");
    png->a = 1;
    png->b = 0;
    png->n = png->start = 7;
    png_put(png, (const unsigned char *)"Wikipedia", 9);
    check((png->b << 16 | png->a) == 0x11E60398UL, "Adler-32 of \"Wikipedia\" is 11e60398");
    free(png);
}

static void test_extensions(void)
{
    check(output_format("a.png") == FORMAT_PNG && output_format("A.PnG") == FORMAT_PNG
              && output_format("x.ppm") == FORMAT_PPM && output_format("png") == FORMAT_PPM
              && output_format("/dev/null") == FORMAT_PPM && output_format("a.JPG") == FORMAT_OTHER,
          "formats by extension, in any case");
    check(has_extension("DEMO.NFF", ".nff") && has_extension("d.nff", ".nff")
              && !has_extension("nff", ".nff") && !has_extension("d.nffx", ".nff"),
          ".nff in any case, and only at the end");
}

/* beside(scene, name) as a string, compared, and freed. */
static int beside_is(const char *scene, const char *name, const char *want)
{
    char *got = beside(scene, name);
    int ok = !strcmp(got, want);
    if (!ok) printf("    beside(%s, %s) = %s, want %s\n", scene, name, got, want);
    free(got);
    return ok;
}

static int output_is(const char *scene, const char *want)
{
    char *got = default_output(scene);
    int ok = !strcmp(got, want);
    if (!ok) printf("    default_output(%s) = %s, want %s\n", scene, got, want);
    free(got);
    return ok;
}

static void test_paths(void)
{
    check(beside_is("s.sph", "m.obj", "m.obj") && beside_is("a/b/s.sph", "m.obj", "a/b/m.obj")
              && beside_is("a/s.sph", "/x/m.obj", "/x/m.obj") && output_is("a/b/s.sph", "s.ppm")
              && output_is("a.b/s", "s.ppm"),
          "paths split on /");
#ifdef RAY_DOS_PATHS
    check(beside_is("a\\b\\s.sph", "m.obj", "a\\b\\m.obj") && beside_is("a/b\\s.sph", "m.obj", "a/b\\m.obj")
              && beside_is("a\\s.sph", "C:\\m.obj", "C:\\m.obj")
              && beside_is("a\\s.sph", "\\m.obj", "\\m.obj") && beside_is("C:s.sph", "m.obj", "C:m.obj")
              && output_is("C:\\a.b\\s.sph", "s.ppm") && output_is("a\\s", "s.ppm"),
          "Windows paths split on \\ and a drive's colon too");
#else
    check(beside_is("a\\b\\s.sph", "m.obj", "m.obj") && output_is("a\\s.sph", "a\\s.ppm"),
          "elsewhere \\ is part of a file name");
#endif
}

int main(void)
{
    test_srgb();
    test_checksums();
    test_extensions();
    test_paths();
    return failures != 0;
}

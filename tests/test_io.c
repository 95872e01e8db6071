/* Unit tests for the plumbing: the sRGB curve (ray.c), the PNG writer's
 * checksums (image.c), extensions, and how paths are split (scene.c and
 * cli.c; built once as is and once with -DRAY_DOS_PATHS, the Windows rule),
 * the deflate writer's Huffman codes and runs (image.c).
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
    unsigned long crc[256];
    const unsigned char *nine = (const unsigned char *)"123456789";
    crc_table(crc);
    check((crc_update(crc, 0xFFFFFFFFUL, nine, 9) ^ 0xFFFFFFFFUL) == 0xCBF43926UL,
          "CRC-32 of \"123456789\" is cbf43926");
    check((crc_update(crc, 0xFFFFFFFFUL, (const unsigned char *)"IEND", 4) ^ 0xFFFFFFFFUL) == 0xAE426082UL,
          "CRC-32 of an IEND chunk is ae426082, as in every PNG");
    check(adler32((const unsigned char *)"Wikipedia", 9) == 0x11E60398UL, "Adler-32 of \"Wikipedia\" is 11e60398");
}

/* Is this a complete prefix code of lengths 1..limit (Kraft's sum exactly
 * 1), with every counted symbol coded? */
static int complete_code(const unsigned long *count, const unsigned char *len, int n, int limit)
{
    unsigned long kraft = 0;
    int i;
    for (i = 0; i < n; i++) {
        if (len[i] > limit || (count[i] && !len[i])) return 0;
        if (len[i]) kraft += 1UL << (limit - len[i]);
    }
    return kraft == 1UL << limit;
}

/* Huffman codes: the deflate writer's (image.c), whose output python's
 * zlib decodes in tests/io.test.sh and tests/image.test.sh; here, what a
 * decoder would only show as "invalid code". */
static void test_huffman(void)
{
    unsigned long count[30] = { 0 }, two[19] = { 0 };
    unsigned char len[30];
    Huffman h;
    int i, deepest = 0, ok = 1;
    static const unsigned char rfc[8] = { 3, 3, 3, 3, 3, 2, 4, 4 };
    static const unsigned short want[8] = { 2, 3, 4, 5, 6, 0, 14, 15 };
    /* Fibonacci counts: Huffman's tree would be 29 deep, the limit is 15 */
    for (count[0] = count[1] = 1, i = 2; i < 30; i++) count[i] = count[i - 1] + count[i - 2];
    huffman_lengths(count, 30, 15, len);
    for (i = 0; i < 30; i++) deepest = len[i] > deepest ? len[i] : deepest;
    check(complete_code(count, len, 30, 15) && deepest == 15,
          "Huffman lengths of Fibonacci counts: limited to 15 bits, a complete code");
    huffman_lengths(count, 19, 7, len);
    check(complete_code(count, len, 19, 7), "Huffman lengths of the code-length code: at most 7 bits, complete");
    two[5] = 100;
    huffman_lengths(two, 19, 7, len);
    check(len[5] == 1 && complete_code(two, len, 19, 7), "one symbol used: it and one more get codes of 1 bit");
    /* RFC 1951 3.2.2's example: lengths (3, 3, 3, 3, 3, 2, 4, 4) for A..H */
    memcpy(h.len, rfc, 8);
    canonical_codes(&h, 8);
    for (i = 0; i < 8; i++) {
        int bits, r = 0, v = h.code[i];
        for (bits = 0; bits < h.len[i]; bits++, v >>= 1) r = r << 1 | (v & 1);
        ok = ok && r == want[i];
    }
    check(ok, "canonical codes of RFC 1951 3.2.2's example: 010 011 100 101 110 00 1110 1111");
    check(code_of(length_base, 29, 3) == 0 && code_of(length_base, 29, 10) == 7
              && code_of(length_base, 29, 257) == 27 && code_of(length_base, 29, 258) == 28
              && code_of(dist_base, 30, 1) == 0 && code_of(dist_base, 30, 4) == 3
              && code_of(dist_base, 30, 24576) == 28 && code_of(dist_base, 30, 32768) == 29,
          "length and distance codes at their ends (RFC 1951 3.2.5)");
}

/* The code lengths' runs (RFC 1951 3.2.7): 17 and 18 for zeros, 16 after a
 * length; each entry the symbol, its extra bits' value above bit 5. */
static void test_runs(void)
{
    unsigned char len[200];
    unsigned short runs[200];
    static const unsigned short want[] = { 8, 16 | 3 << 5, 8, 18 | 127 << 5, 17 | 0 << 5, 5, 5, 0, 0 };
    int n;
    memset(len, 0, sizeof len);
    memset(len, 8, 8);                    /* 8 x 8: 8, then 16 for 6, then 8 */
    /* 141 zeros: 18 for 138, 17 for 3; two 5s and two zeros as they are */
    len[8 + 3 + 138] = len[8 + 3 + 139] = 5;
    n = run_lengths(len, 8 + 3 + 138 + 2 + 2, runs);
    check(n == 9 && !memcmp(runs, want, sizeof want), "code lengths as runs: 16, 17 and 18 where they fit");
}

static void test_extensions(void)
{
    check(output_format("a.png") == FORMAT_PNG && output_format("A.PnG") == FORMAT_PNG
              && output_format("x.ppm") == FORMAT_PPM && output_format("png") == FORMAT_PPM
              && output_format("x.exr") == FORMAT_EXR && output_format("X.EXR") == FORMAT_EXR
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
    test_huffman();
    test_runs();
    test_extensions();
    test_paths();
    return failures != 0;
}

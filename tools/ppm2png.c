/* ppm2png - a binary PPM (P6, maxval 255) written again as a PNG by ray's own
 * writer (image.c), so that a PNG made before the writer compressed can be
 * made small with the same pixels (tools/repng.sh).
 *
 *     cc -std=c99 -O2 -o ppm2png tools/ppm2png.c image.c
 *     ppm2png [--srgb] IN.ppm OUT.png
 *
 * --srgb: the PNG says its bytes are sRGB (an sRGB and a gAMA chunk), as
 * ray's PNGs of path-traced or --gamma renders do.  Exit 0, or 1 after a
 * message; OUT is whole or not there (write_image). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "../image.h"

/* The next number of a PPM header, after blanks and # comments; -1 if none. */
static long header_number(FILE *f)
{
    long v = 0;
    int c = getc(f), digits = 0;
    while (c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '#') {
        if (c == '#')
            while (c != '\n' && c != EOF) c = getc(f);
        c = getc(f);
    }
    for (; c >= '0' && c <= '9' && v < 100000; c = getc(f), digits++) v = 10 * v + (c - '0');
    return digits && (c == ' ' || c == '\t' || c == '\r' || c == '\n') ? v : -1;  /* one blank ends it */
}

int main(int argc, char **argv)
{
    int srgb = argc > 1 && !strcmp(argv[1], "--srgb");
    const char *in = argc == 3 + srgb ? argv[1 + srgb] : NULL, *out = in ? argv[2 + srgb] : NULL;
    FILE *f = in ? fopen(in, "rb") : NULL;
    long w, h, maxval;
    Image img;
    Output o;
    size_t n;
    if (!in || output_format(out) != FORMAT_PNG) {
        fprintf(stderr, "usage: ppm2png [--srgb] IN.ppm OUT.png\n");
        return 1;
    }
    if (!f) { perror(in); return 1; }
    if (getc(f) != 'P' || getc(f) != '6' || (w = header_number(f)) < 1 || (h = header_number(f)) < 1
        || w > 32768 || h > 32768 || (maxval = header_number(f)) != 255) {
        fprintf(stderr, "%s: not a binary PPM (P6) of maxval 255\n", in);
        return 1;
    }
    if (!new_image(&img, (int)w, (int)h, 0, srgb)) { fprintf(stderr, "%s: out of memory\n", in); return 1; }
    n = (size_t)w * h * 3;
    if (fread(img.bytes, 1, n, f) != n || getc(f) != EOF) {
        fprintf(stderr, "%s: not %ld x %ld pixels\n", in, w, h);
        return 1;
    }
    fclose(f);
    if (!open_output(&o, out) || !write_image(&o, &img, 0)) return 1;
    free_image(&img);
    return 0;
}

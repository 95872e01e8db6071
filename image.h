/* image.h - the image being made, and the files it is written to: PPM
 * (P6, or plain P3), PNG (8-bit RGB, deflate-compressed), and PFM and
 * OpenEXR (32-bit floats, the radiance itself).
 *
 * An output is opened before the render and written after it, through a
 * temporary file renamed into place: it is whole or not there, and the
 * file it replaces is kept until then, also on Ctrl-C.
 */
#ifndef IMAGE_H
#define IMAGE_H

#include <stdint.h>
#include <stdio.h>

/* Bytes (for PPM and PNG) or floats (for PFM and EXR), row by row from the
 * top-left, three channels a pixel. */
typedef struct {
    int w, h;
    unsigned char *bytes;
    float *floats;
    int srgb;                 /* bytes: through the sRGB curve */
} Image;

/* w x h pixels of floats or of bytes; 0 when out of memory. */
int new_image(Image *img, int w, int h, int floats, int srgb);
void free_image(Image *img);

/* The format a name asks for, by its extension (.png, .pfm, .exr, .part: a
 * partial render, below; else
 * PPM, but for the image formats this program cannot write: FORMAT_OTHER). */
enum { FORMAT_PPM, FORMAT_PNG, FORMAT_PFM, FORMAT_EXR, FORMAT_PART, FORMAT_OTHER };
int output_format(const char *name);
/* Does the format hold floats (PFM, EXR), not bytes?  Its name, as "PNG". */
int float_format(int format);
const char *format_name(int format);

/* Where the image goes: "-" is stdout; a new or plain file is written as
 * a temporary beside it (tmp), renamed over it at the end; anything else
 * (a device, a pipe, a symbolic link) in place. */
typedef struct { FILE *f; const char *name; char *tmp, *target; int format; } Output;

int open_output(Output *o, const char *name);     /* 0 after a message */
void discard_output(Output *o);                   /* nothing is left of it */
/* The image in o's format (plain: P3), the file closed and renamed into
 * place; 0 after a message, and no file. */
int write_image(Output *o, const Image *img, int plain);

/* ---------------------------------------------------- partial renders
 *
 * A render split over machines (ray --crop, --samples, --tile) leaves each
 * part's pixels as sums, which ray --merge adds.  For the merge to give the
 * bytes of one whole run, the sums must not depend on the order they are
 * added in, and floating-point sums do: (a + b) + c is not a + (b + c).  So
 * every pixel's samples, in a whole run too, are added as Exact numbers:
 * 128-bit fixed point, the whole part in hi (two's complement over both
 * words) and the fraction in lo, in units of 2^-64.  Integers add exactly
 * in any order.  A sample is cut to a multiple of 2^-64 (5e-20) as it is
 * added; the sums hold up to 2^63 (9e18), far above any radiance. */
typedef struct { uint64_t hi, lo; } Exact;
void exact_add(Exact *sum, double v);
void exact_sum(Exact *sum, const Exact *more);
double exact_value(const Exact *sum);

/* A partial render: the pixels x0 <= x < x1, y0 <= y < y1 of a w x h image,
 * samples s0 <= k < s1 of each of spp (all but those adaptive sampling
 * left out).  Each pixel has its three Exact sums and n, the samples it
 * took; n 0: not rendered (a checkpoint's rows still to come).  about is
 * its provenance: what made it, as `key value` lines (the scene's content
 * hash, the renderer, its options, the program's version), which must be
 * the same, byte for byte, in every part of one render.  srgb: its bytes
 * go through the sRGB curve.  The file (x.part):
 *
 *     ray partial 1
 *     image W H
 *     crop X0 Y0 X1 Y1
 *     samples S0 S1 SPP
 *     pixels srgb | linear
 *     (the provenance lines)
 *     end
 *
 * then for each pixel, row by row from the top-left, n and the sums hi, lo
 * of red, green and blue: 7 unsigned 64-bit numbers, little-endian. */
#define PARTIAL_ABOUT 1024
typedef struct {
    int w, h, x0, y0, x1, y1, s0, s1, spp, srgb;
    char about[PARTIAL_ABOUT];
    Exact *sum;               /* 3 a pixel, row by row within the crop */
    uint64_t *n;
} Partial;

int new_partial(Partial *p);        /* the sums for its crop, all 0; 0 when out of memory */
void free_partial(Partial *p);
/* The partial into o (opened as any output), rows y0 + r for which
 * rows[r] is set (rows NULL: all; the others as not rendered); 0 after a
 * message.  save_partial: the same into the file name, through a
 * temporary renamed into place (a checkpoint), without touching o's. */
int write_partial(Output *o, const Partial *p, const unsigned char *rows);
int save_partial(const char *name, const Partial *p, const unsigned char *rows);
/* The partial in file name; 0 after a message (name:line: what is wrong). */
int read_partial(const char *name, Partial *p);
/* Is got (file name) a checkpoint of the render want is, with the same
 * pixels and samples?  Else a message and 0. */
int same_part(const Partial *got, const Partial *want, const char *name);
/* The n parts (files names[]) added into *whole, the full image with
 * every sample; 0 after a message when they are not parts of one render:
 * another provenance, image or sample count, two that overlap, or a hole
 * (the missing pixels and samples named). */
int merge_partials(Partial *parts, const char *const *names, int n, Partial *whole);

/* Stop signals for a render with checkpoints: SIGINT, SIGTERM and SIGHUP
 * no longer end the program at once; stop_signal() then tells which came
 * (0: none), and the render saves its work and ends itself, by
 * end_by_signal(). */
void catch_stop_signals(void);
int stop_signal(void);
void end_by_signal(int sig);

#endif

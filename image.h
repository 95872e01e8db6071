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

/* The format a name asks for, by its extension (.png, .pfm, .exr; else
 * PPM, but for the image formats this program cannot write: FORMAT_OTHER). */
enum { FORMAT_PPM, FORMAT_PNG, FORMAT_PFM, FORMAT_EXR, FORMAT_OTHER };
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

#endif

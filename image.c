/* image.c - the image files: PPM (binary P6 or plain P3), PNG and PFM, each
 * written whole or not at all (image.h).
 *
 * A render can take hours, so the output is opened before it starts (a bad
 * -o fails at once) and written to a temporary file of this run's own,
 * renamed over the old file only when complete: a failure, a full disk or
 * a Ctrl-C never leaves half an image, and never loses the old one.
 */
#include "posix.h"
#include <ctype.h>
#include <errno.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#ifdef RAY_POSIX
#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#endif
#ifdef _WIN32
#include <fcntl.h>
#include <io.h>
#include <process.h>
#endif
#include "image.h"

/* An image of w x h pixels, floats or bytes (through the sRGB curve for a
 * path-traced one, and with --gamma). */
int new_image(Image *img, int w, int h, int floats, int srgb)
{
    img->w = w;
    img->h = h;
    img->srgb = srgb;
    img->bytes = floats ? NULL : malloc((size_t)w * h * 3);
    img->floats = floats ? malloc((size_t)w * h * 3 * sizeof *img->floats) : NULL;
    return img->bytes || img->floats;
}

void free_image(Image *img)
{
    free(img->bytes);
    free(img->floats);
    img->bytes = NULL;
    img->floats = NULL;
}


/* The format -o asks for, by its extension: .png is PNG, .pfm PFM (floats,
 * the radiance itself); anything else is
 * PPM (.ppm, stdout, a device, a name without an extension), except the
 * image formats this program cannot write, which are refused rather than
 * given a PPM under their name. */
int output_format(const char *name)
{
    static const char *const other[] = { "jpg", "jpeg", "gif", "bmp", "tif", "tiff",
                                         "webp", "tga", "exr", "hdr" };
    const char *dot = strrchr(name, '.');
    char ext[8];
    size_t i;
    if (!dot || strlen(dot) > sizeof ext || strchr(dot, '/') || strchr(dot, '\\'))
        return FORMAT_PPM;                /* no extension, or none this short */
    for (i = 0; dot[i + 1]; i++) ext[i] = (char)tolower((unsigned char)dot[i + 1]);
    ext[i] = 0;
    if (!strcmp(ext, "png")) return FORMAT_PNG;
    if (!strcmp(ext, "pfm")) return FORMAT_PFM;
    for (i = 0; i < sizeof other / sizeof *other; i++)
        if (!strcmp(ext, other[i])) return FORMAT_OTHER;
    return FORMAT_PPM;
}

/* PNG (ISO/IEC 15948) without a compressor: the rows, each after filter
 * byte 0 ("none"), make a zlib stream (RFC 1950) of stored deflate blocks
 * (RFC 1951: a block's bytes as they are, after their count and its
 * complement), one IDAT chunk per block.  Each chunk ends with the CRC-32
 * of its type and data; the zlib stream ends with the Adler-32 of the rows. */
#define STORED_MAX 65535                  /* the most bytes a stored block holds */

typedef struct {
    FILE *f;
    unsigned long crc[256];               /* CRC-32 of each byte value */
    unsigned long a, b;                   /* Adler-32's two sums */
    unsigned char buf[2 + 5 + STORED_MAX + 4]; /* one IDAT chunk's data */
    size_t n, start;                      /* bytes in buf; where the block's bytes start */
} Png;

/* The table of CRC-32 (the polynomial of ISO 3309, bits reversed). */
static void crc_table(unsigned long t[256])
{
    unsigned long c;
    int n, k;
    for (n = 0; n < 256; n++) {
        for (c = (unsigned long)n, k = 0; k < 8; k++) c = c & 1 ? 0xEDB88320UL ^ c >> 1 : c >> 1;
        t[n] = c;
    }
}

static unsigned long crc_update(const unsigned long t[256], unsigned long crc,
                                const unsigned char *p, size_t n)
{
    while (n--) crc = t[(crc ^ *p++) & 0xFF] ^ crc >> 8;
    return crc;
}

/* Four bytes, most significant first, as PNG and zlib store numbers. */
static void put32(unsigned char *p, unsigned long v)
{
    p[0] = (unsigned char)(v >> 24 & 0xFF);
    p[1] = (unsigned char)(v >> 16 & 0xFF);
    p[2] = (unsigned char)(v >> 8 & 0xFF);
    p[3] = (unsigned char)(v & 0xFF);
}

/* One chunk: its length, type, data and CRC. */
static void png_chunk(Png *png, const char *type, const unsigned char *data, size_t n)
{
    unsigned char head[8], tail[4];
    put32(head, (unsigned long)n);
    memcpy(head + 4, type, 4);
    put32(tail, crc_update(png->crc, crc_update(png->crc, 0xFFFFFFFFUL, head + 4, 4), data, n)
                    ^ 0xFFFFFFFFUL);
    fwrite(head, 1, 8, png->f);
    fwrite(data, 1, n, png->f);
    fwrite(tail, 1, 4, png->f);
}

/* The block in buf as an IDAT chunk; the last one also closes the zlib
 * stream with its Adler-32.  The next block's header goes at buf[0]. */
static void png_block(Png *png, int last)
{
    size_t len = png->n - png->start;
    unsigned char *head = png->buf + png->start - 5;
    head[0] = (unsigned char)last;        /* BFINAL, and BTYPE 00: stored */
    head[1] = (unsigned char)(len & 0xFF);
    head[2] = (unsigned char)(len >> 8);
    head[3] = (unsigned char)(~len & 0xFF);
    head[4] = (unsigned char)(~len >> 8 & 0xFF);
    if (last) {
        put32(png->buf + png->n, png->b << 16 | png->a);
        png->n += 4;
    }
    png_chunk(png, "IDAT", png->buf, png->n);
    png->n = png->start = 5;
}

/* Bytes of the rows into the zlib stream, a stored block at a time. */
static void png_put(Png *png, const unsigned char *p, size_t n)
{
    while (n > 0) {
        size_t room = STORED_MAX - (png->n - png->start), k = n < room ? n : room, i;
        if (room == 0) { png_block(png, 0); continue; }
        for (i = 0; i < k; i++) {
            png->a = (png->a + p[i]) % 65521;
            png->b = (png->b + png->a) % 65521;
        }
        memcpy(png->buf + png->n, p, k);
        png->n += k;
        p += k;
        n -= k;
    }
}

/* An 8-bit RGB PNG; with srgb, it says its bytes are sRGB (the sRGB chunk,
 * and gAMA 1/2.2 for readers that know only that). 0: out of memory. */
static int write_png(FILE *f, const unsigned char *img, int w, int h, int srgb)
{
    static const unsigned char signature[8] = { 137, 'P', 'N', 'G', 13, 10, 26, 10 };
    unsigned char ihdr[13] = { 0 }, zero = 0, gamma[4];
    Png *png = malloc(sizeof *png);
    int j;
    if (!png) return 0;
    png->f = f;
    crc_table(png->crc);
    png->a = 1;
    png->b = 0;
    png->buf[0] = 0x78;                   /* zlib: deflate, 32K window; */
    png->buf[1] = 0x01;                   /* 0x7801 is a multiple of 31 */
    png->n = png->start = 2 + 5;
    fwrite(signature, 1, 8, f);
    put32(ihdr, (unsigned long)w);
    put32(ihdr + 4, (unsigned long)h);
    ihdr[8] = 8;                          /* bits per channel */
    ihdr[9] = 2;                          /* RGB; compression, filter, interlace 0 */
    png_chunk(png, "IHDR", ihdr, 13);
    if (srgb) {
        put32(gamma, 45455);
        png_chunk(png, "sRGB", &zero, 1); /* rendering intent 0, perceptual */
        png_chunk(png, "gAMA", gamma, 4);
    }
    for (j = 0; j < h; j++) {
        png_put(png, &zero, 1);           /* filter type 0, none */
        png_put(png, img + (size_t)3 * w * j, (size_t)3 * w);
    }
    png_block(png, 1);
    png_chunk(png, "IEND", png->buf, 0);
    free(png);
    return 1;
}

static void write_ppm(FILE *f, const unsigned char *img, int w, int h, int plain)
{
    size_t i, n = (size_t)w * h * 3;
    fprintf(f, "%s\n%d %d\n255\n", plain ? "P3" : "P6", w, h);
    if (plain)
        for (i = 0; i < n; i += 3) fprintf(f, "%d %d %d\n", img[i], img[i + 1], img[i + 2]);
    else
        fwrite(img, 1, n, f);
}

/* Where the image goes.  It is opened before the render, so that a bad -o
 * fails at once rather than after a long render.  A new or plain file is
 * written to a temporary file of this run's own beside it (FILE.tmp.PID),
 * which is renamed over FILE at the end: a failure or an interrupt never
 * leaves a half-written image, and keeps the old one; through a symbolic
 * link, its target is.  Anything else (stdout, a device such as /dev/null,
 * a pipe) is written in place and never renamed over or removed. */

/* The temporary file's name, for on_signal, which can be handed nothing:
 * the one global of ray.c (the card has its own).  It is written before the
 * handler is installed, and the handler only reads it. */
static char signal_tmp[4096];

/* Ctrl-C (SIGINT), SIGTERM, a closed terminal (SIGHUP), or any other
 * signal that ends a program by default and can be caught (SIGQUIT, the
 * user signals, a timer, a CPU or file-size limit reached) during a render:
 * the temporary file is removed, then the signal raised again with its
 * default action, so that the program ends as that signal ends it (a shell
 * shows 128 + its number) and the old output stays.  Only calls that are
 * safe in a signal handler: unlink (remove, where there is no unlink),
 * signal and raise. */
static void on_signal(int sig)
{
#ifdef RAY_POSIX
    unlink(signal_tmp);
#else
    remove(signal_tmp);
#endif
    signal(sig, SIG_DFL);
    raise(sig);
}

/* Is sig ignored (as nohup, or a shell for a background job, leaves it)?
 * Then it stays ignored. */
static int ignored(int sig)
{
#ifdef RAY_POSIX
    struct sigaction sa;
    return sigaction(sig, NULL, &sa) == 0 && sa.sa_handler == SIG_IGN;
#else
    (void)sig;
    return 0;
#endif
}

/* on_signal for the temporary file tmp, or with tmp NULL the default
 * action again (the file is renamed into place, or gone).  A name too long
 * for signal_tmp, which no system takes, is left to the default action. */
static void catch_signals(const char *tmp)
{
    static const int sigs[] = { SIGINT, SIGTERM
#ifdef RAY_POSIX
        , SIGHUP, SIGQUIT, SIGUSR1, SIGUSR2, SIGALRM, SIGPIPE
#endif
#ifdef SIGXCPU                      /* ulimit -t ran out, ulimit -f is reached, and the */
        , SIGXCPU, SIGXFSZ          /* profiling timers: each ends the program by default */
#endif
#ifdef SIGVTALRM
        , SIGVTALRM, SIGPROF
#endif
    };
    size_t i;
    if (tmp && strlen(tmp) >= sizeof signal_tmp) return;
    if (tmp) strcpy(signal_tmp, tmp);
    for (i = 0; i < sizeof sigs / sizeof *sigs; i++)
        if (!ignored(sigs[i])) signal(sigs[i], tmp ? on_signal : SIG_DFL);
}

/* Nothing but this run may have opened the file: created here (O_EXCL: not
 * if it exists, and never through a symbolic link), or NULL with errno
 * EEXIST.  Without POSIX, the best plain C can do: fail if it can be read. */
static FILE *create_new(const char *name)
{
#ifdef RAY_POSIX
    int fd = open(name, O_WRONLY | O_CREAT | O_EXCL, 0666);
    FILE *f = fd < 0 ? NULL : fdopen(fd, "wb");
    if (fd >= 0 && !f) { close(fd); unlink(name); }
    return f;
#else
    FILE *f = fopen(name, "rb");
    if (f) { fclose(f); errno = EEXIST; return NULL; }
    return fopen(name, "wb");
#endif
}

/* This process's number, to tell its temporary files from another run's. */
static long process_id(void)
{
#if defined(RAY_POSIX)
    return (long)getpid();
#elif defined(_WIN32)
    return (long)_getpid();
#else
    return (long)time(NULL);
#endif
}

#ifdef RAY_POSIX
/* Whether entry is name's temporary (name.tmp.PID or name.tmp.PID.K, of
 * the file part base) of a process that is gone: SIGKILL, or a machine
 * switched off, leaves them, as no handler can run.  A PID that is some
 * process again keeps its file: it may be another run's. */
static int stale_temp(const char *entry, const char *base)
{
    size_t n = strlen(base);
    char *end;
    long pid;
    if (strncmp(entry, base, n) || strncmp(entry + n, ".tmp.", 5) || !isdigit((unsigned char)entry[n + 5]))
        return 0;
    pid = strtol(entry + n + 5, &end, 10);
    if (*end == '.' && isdigit((unsigned char)end[1])) strtol(end + 1, &end, 10);
    return !*end && pid > 0 && pid != process_id() && kill((pid_t)pid, 0) != 0 && errno == ESRCH;
}

/* Removes the stale temporaries beside name, saying so on stderr. */
static void remove_stale_temps(const char *name)
{
    const char *slash = strrchr(name, '/'), *base = slash ? slash + 1 : name;
    size_t dir = (size_t)(base - name);
    char *path = malloc(dir + 2 + 256 + 1);
    DIR *d;
    struct dirent *e;
    if (!path) return;
    if (dir) memcpy(path, name, dir);
    else path[dir++] = '.', path[dir++] = '/';
    path[dir] = 0;
    d = opendir(path);
    while (d && (e = readdir(d)))
        if (strlen(e->d_name) <= 256 && stale_temp(e->d_name, base)) {
            strcpy(path + dir, e->d_name);
            if (unlink(path) == 0) fprintf(stderr, "ray: removed %s, left by a run that was killed\n", path);
        }
    if (d) closedir(d);
    free(path);
}
#endif

/* A temporary file beside name that no other run shares: name.tmp.PID, or
 * name.tmp.PID.K when that exists (left by a run that was killed).  Those
 * of runs that are gone are removed first, where POSIX can tell. */
static FILE *create_temp(const char *name, char **tmp)
{
    int k;
    FILE *f = NULL;
#ifdef RAY_POSIX
    remove_stale_temps(name);
#endif
    *tmp = malloc(strlen(name) + 48);
    if (!*tmp) return NULL;
    for (k = 0; k < 100 && !f; k++) {
        if (k) sprintf(*tmp, "%s.tmp.%ld.%d", name, process_id(), k);
        else sprintf(*tmp, "%s.tmp.%ld", name, process_id());
        f = create_new(*tmp);
        if (!f && errno != EEXIST) break;
    }
    return f;
}

enum { IN_PLACE, VIA_TEMP, REFUSED };

#ifdef RAY_POSIX
/* How -o FILE is written: a plain file or a new one through a temporary
 * (*mode: the old file's permissions, which the new one keeps; -1 for a new
 * file), anything else in place.  A read-only file is refused, with a
 * message: replacing it would defeat its protection (root may write any
 * file, so its mode bits are asked too). */
static int output_kind(const char *name, int *mode)
{
    struct stat st;
    *mode = -1;
    if (lstat(name, &st) != 0) return errno == ENOENT ? VIA_TEMP : IN_PLACE;
    if (!S_ISREG(st.st_mode)) return IN_PLACE;
    if (access(name, W_OK) != 0 || !(st.st_mode & (S_IWUSR | S_IWGRP | S_IWOTH))) {
        fprintf(stderr, "%s: is read-only; not replaced (make it writable, or write elsewhere)\n",
                name);
        return REFUSED;
    }
    *mode = (int)(st.st_mode & 07777);
    return VIA_TEMP;
}
#else
static int output_kind(const char *name, int *mode)
{
    FILE *f = fopen(name, "rb");
    *mode = -1;
    if (f) {
        fclose(f);
        f = fopen(name, "r+b");     /* opens for writing without changing it */
        if (!f) {
            fprintf(stderr, "%s: is read-only; not replaced (make it writable, or write elsewhere)\n",
                    name);
            return REFUSED;
        }
        fclose(f);
    }
    return VIA_TEMP;
}
#endif

/* Opens -o name for writing (see Output).  0 after a message. */
int open_output(Output *o, const char *name)
{
    int mode, kind;
    o->name = name;
    o->tmp = o->target = NULL;
    o->f = stdout;
    o->format = strcmp(name, "-") ? output_format(name) : FORMAT_PPM;
    if (!strcmp(name, "-")) {
#ifdef _WIN32
        _setmode(_fileno(stdout), _O_BINARY);    /* P6 and PNG bytes as they are: no \r added */
#endif
        return 1;
    }
#ifdef RAY_POSIX
    {   /* through a symbolic link: the link's target is written as any file is,
         * through a temporary beside it renamed over it at the end (opening
         * the link would empty the target at once, and an interrupt would
         * leave it empty); the link stays */
        struct stat st;
        if (lstat(name, &st) == 0 && S_ISLNK(st.st_mode) && (o->target = realpath(name, NULL)))
            o->name = name = o->target;
    }
#endif
    kind = output_kind(name, &mode);
    if (kind == REFUSED) { free(o->target); return 0; }
    o->f = kind == VIA_TEMP ? create_temp(name, &o->tmp) : fopen(name, "wb");
#ifdef RAY_POSIX
    if (o->f && mode >= 0) fchmod(fileno(o->f), (mode_t)mode);
#endif
    if (o->f) {
        if (o->tmp) catch_signals(o->tmp);
        return 1;
    }
    fprintf(stderr, "%s: cannot write: %s\n", o->tmp ? o->tmp : name, strerror(errno));
    free(o->tmp);
    free(o->target);
    return 0;
}

/* Gives up an output: nothing is left of it. */
void discard_output(Output *o)
{
    if (o->f != stdout) fclose(o->f);
    if (o->tmp) remove(o->tmp);
    if (o->tmp) catch_signals(NULL);
    free(o->tmp);
    free(o->target);
}

/* PFM, netpbm's floating-point format: "PF" (colour), the size, and -1 for
 * little-endian floats; then the rows from the bottom up. */
static void write_pfm(FILE *f, const Image *img)
{
    int i, j, c;
    fprintf(f, "PF\n%d %d\n-1.0\n", img->w, img->h);
    for (j = img->h - 1; j >= 0; j--)
        for (i = 0; i < 3 * img->w; i++) {
            float x = img->floats[(size_t)j * 3 * img->w + i];
            uint32_t u;
            unsigned char b[4];
            memcpy(&u, &x, 4);
            for (c = 0; c < 4; c++) b[c] = (unsigned char)(u >> 8 * c);
            fwrite(b, 1, 4, f);
        }
}

/* rename() over an existing file: POSIX replaces it in one step; Windows
 * refuses, so there the old file is removed first (for a moment there is
 * neither: the best plain C can do). */
static int replace_file(const char *from, const char *to)
{
#ifdef _WIN32
    remove(to);
#endif
    return rename(from, to);
}

/* The image in the output's format, then the file closed and, if it was
 * written as a temporary, renamed into place; on failure a message and no
 * file.  A PNG of sRGB bytes says so. */
int write_image(Output *o, const Image *img, int plain)
{
    int ok = 1;
    errno = 0;
    if (o->format == FORMAT_PFM) write_pfm(o->f, img);
    else if (o->format == FORMAT_PNG) {
        ok = write_png(o->f, img->bytes, img->w, img->h, img->srgb);
        if (!ok) errno = ENOMEM;
    } else
        write_ppm(o->f, img->bytes, img->w, img->h, plain);
    ok = ok && fflush(o->f) == 0 && !ferror(o->f);
    if (o->f != stdout) ok = fclose(o->f) == 0 && ok;
    if (ok && o->tmp) ok = replace_file(o->tmp, o->name) == 0;
    if (!ok) {
        fprintf(stderr, "%s: cannot write: %s\n", o->name, strerror(errno));
        if (o->tmp) remove(o->tmp);
    }
    if (o->tmp) catch_signals(NULL);
    free(o->tmp);
    free(o->target);
    return ok;
}

/* image.c - the image files: PPM (binary P6 or plain P3), PNG (compressed
 * with a deflate of its own), PFM and OpenEXR, each written whole or not at
 * all (image.h).
 *
 * A render can take hours, so the output is opened before it starts (a bad
 * -o fails at once) and written to a temporary file of this run's own,
 * renamed over the old file only when complete: a failure, a full disk or
 * a Ctrl-C never leaves half an image, and never loses the old one.
 */
#include "posix.h"
#include <ctype.h>
#include <errno.h>
#include <math.h>
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


/* The format -o asks for, by its extension: .png is PNG, .pfm PFM and .exr
 * OpenEXR (floats, the radiance itself); anything else is
 * PPM (.ppm, stdout, a device, a name without an extension), except the
 * image formats this program cannot write, which are refused rather than
 * given a PPM under their name. */
int output_format(const char *name)
{
    static const char *const other[] = { "jpg", "jpeg", "gif", "bmp", "tif", "tiff",
                                         "webp", "tga", "hdr" };
    const char *dot = strrchr(name, '.');
    char ext[8];
    size_t i;
    if (!dot || strlen(dot) > sizeof ext || strchr(dot, '/') || strchr(dot, '\\'))
        return FORMAT_PPM;                /* no extension, or none this short */
    for (i = 0; dot[i + 1]; i++) ext[i] = (char)tolower((unsigned char)dot[i + 1]);
    ext[i] = 0;
    if (!strcmp(ext, "png")) return FORMAT_PNG;
    if (!strcmp(ext, "pfm")) return FORMAT_PFM;
    if (!strcmp(ext, "exr")) return FORMAT_EXR;
    if (!strcmp(ext, "part")) return FORMAT_PART;
    for (i = 0; i < sizeof other / sizeof *other; i++)
        if (!strcmp(ext, other[i])) return FORMAT_OTHER;
    return FORMAT_PPM;
}

int float_format(int format) { return format == FORMAT_PFM || format == FORMAT_EXR; }

const char *format_name(int format)
{
    static const char *const names[] = { "PPM", "PNG", "PFM", "OpenEXR", "a partial render" };
    return format >= FORMAT_PPM && format < FORMAT_OTHER ? names[format] : "another format";
}

/* Deflate (RFC 1951) in a zlib stream (RFC 1950), written from the RFCs for
 * this program: LZ77 finds earlier copies of the bytes to come, Huffman codes
 * made for each block spell the rest.  One function a step:
 *   find_match        the longest earlier copy within 32K (hash chains)
 *   lz77              the input as literals and (length, distance) pairs
 *   huffman_lengths   code lengths from counts, at most 15 (or 7) bits
 *   canonical_codes   the codes from their lengths
 *   write_block       a block with its own codes, or stored if that is smaller
 * Nothing depends on the machine: no floating point, no threads, and every
 * tie is broken by a position or a symbol's number, so the bytes are the
 * same everywhere.  The PNG writer and the EXR writer use it. */

#define WINDOW 32768                      /* the farthest back a copy may be (3.2.5) */
#define MIN_MATCH 3                       /* the shortest copy, */
#define MAX_MATCH 258                     /* and the longest (3.2.5) */
#define HASH_SIZE 32768                   /* chains, one per hash of 3 bytes */
#define MAX_CHAIN 128                     /* earlier positions tried at most (zlib's default tries 128 too) */
#define LAZY_MATCH 32                     /* a copy this long is taken without looking one byte on */
#define BLOCK_SYMBOLS 16384               /* symbols a block holds before its codes are made anew */
#define MAX_SYMBOLS 288                   /* the largest alphabet: literals and lengths (3.2.5) */

/* Bytes in memory, grown as they come; failed once out of memory. */
typedef struct { unsigned char *p; size_t n, cap; int failed; } Bytes;

static void bytes_put(Bytes *b, const void *data, size_t n)
{
    if (b->failed || n == 0) return;
    if (b->n + n > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        unsigned char *p;
        while (cap < b->n + n) cap *= 2;
        if (!(p = realloc(b->p, cap))) { b->failed = 1; return; }
        b->p = p;
        b->cap = cap;
    }
    memcpy(b->p + b->n, data, n);
    b->n += n;
}

/* Bits into bytes, the first bit in each byte's least significant (3.1.1). */
typedef struct { Bytes *out; unsigned long bits; int count; } Bits;

static void put_bits(Bits *w, unsigned v, int n)  /* n <= 16 bits of v */
{
    w->bits |= (unsigned long)v << w->count;
    w->count += n;
    for (; w->count >= 8; w->count -= 8, w->bits >>= 8) {
        unsigned char byte = (unsigned char)(w->bits & 0xFF);
        bytes_put(w->out, &byte, 1);
    }
}

static void align_bits(Bits *w)                    /* to the next byte boundary */
{
    if (w->count) put_bits(w, 0, 8 - w->count);
}

/* A Huffman code: each symbol's length in bits (0: no code) and its code,
 * bit-reversed, as put_bits sends it. */
typedef struct { unsigned char len[MAX_SYMBOLS]; unsigned short code[MAX_SYMBOLS]; } Huffman;

static void put_code(Bits *w, const Huffman *h, int sym) { put_bits(w, h->code[sym], h->len[sym]); }

/* Code lengths for the n symbols of these counts, none over limit bits
 * (3.2.7: 15, and 7 for the code-length code).  Huffman's construction with
 * two queues: the leaves sorted by count (then by symbol), and the inner
 * nodes as they are made, whose weights never decrease; the two lightest
 * fronts are joined until one tree is left.  Too deep a tree: every count
 * halved (but none to 0) flattens it; made again.  At least two symbols get
 * a code (3.2.7 allows one code of one bit, but some inflaters refuse an
 * incomplete code), so an unused symbol may get one. */
static void huffman_lengths(const unsigned long *count, int n, int limit, unsigned char *len)
{
    unsigned long c[MAX_SYMBOLS], weight[2 * MAX_SYMBOLS];
    int sym[MAX_SYMBOLS], parent[2 * MAX_SYMBOLS], depth[2 * MAX_SYMBOLS];
    int i, k, used = 0, leaf, inner, made, deepest;
    for (i = 0; i < n; i++) used += (c[i] = count[i]) != 0;
    for (i = 0; i < n && used < 2; i++)
        if (!c[i]) { c[i] = 1; used++; }
    for (;;) {
        for (used = 0, i = 0; i < n; i++) {          /* insertion sort: n is at most 288 */
            if (!c[i]) continue;
            for (k = used++; k > 0 && c[sym[k - 1]] > c[i]; k--) sym[k] = sym[k - 1];
            sym[k] = i;
        }
        for (i = 0; i < used; i++) weight[i] = c[sym[i]];
        for (leaf = 0, inner = made = used; made < 2 * used - 1; made++) {
            int pick[2];
            for (k = 0; k < 2; k++)
                pick[k] = leaf < used && (inner == made || weight[leaf] <= weight[inner]) ? leaf++ : inner++;
            weight[made] = weight[pick[0]] + weight[pick[1]];
            parent[pick[0]] = parent[pick[1]] = made;
        }
        depth[made - 1] = 0;                         /* the root; a parent comes after its children */
        for (deepest = 0, i = made - 2; i >= 0; i--)
            if ((depth[i] = depth[parent[i]] + 1) > deepest) deepest = depth[i];
        if (deepest <= limit) break;
        for (i = 0; i < n; i++) c[i] = (c[i] + 1) / 2;
    }
    memset(len, 0, (size_t)n);
    for (i = 0; i < used; i++) len[sym[i]] = (unsigned char)depth[i];
}

/* The codes of these lengths (3.2.2): shorter codes first, and within a
 * length in the order of the symbols.  A code is sent from its most
 * significant bit (3.1.1), so it is kept reversed for put_bits. */
static void canonical_codes(Huffman *h, int n)
{
    int count[16] = { 0 }, next[16], bits, i, code = 0;
    for (i = 0; i < n; i++) count[h->len[i]]++;
    count[0] = 0;
    for (bits = 1; bits < 16; bits++) next[bits] = code = (code + count[bits - 1]) << 1;
    for (i = 0; i < n; i++) {
        int v = h->len[i] ? next[h->len[i]]++ : 0, r = 0;
        for (bits = 0; bits < h->len[i]; bits++, v >>= 1) r = r << 1 | (v & 1);
        h->code[i] = (unsigned short)r;
    }
}

/* The lengths and distances of 3.2.5: code k stands for base[k] and the
 * next 2^extra[k] - 1 values, told apart by extra[k] bits after it. */
static const unsigned short length_base[29] = { 3, 4, 5, 6, 7, 8, 9, 10, 11, 13, 15, 17, 19, 23, 27, 31,
    35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258 };
static const unsigned char length_extra[29] = { 0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2,
    3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0 };
static const unsigned short dist_base[30] = { 1, 2, 3, 4, 5, 7, 9, 13, 17, 25, 33, 49, 65, 97, 129,
    193, 257, 385, 513, 769, 1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577 };
static const unsigned char dist_extra[30] = { 0, 0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6,
    6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13 };

static int code_of(const unsigned short *base, int n, unsigned v)
{
    while (base[n - 1] > v) n--;
    return n - 1;
}

/* The order in which the code-length code's lengths are sent (3.2.7), and
 * the extra bits of its repeat codes 16, 17 and 18. */
static const unsigned char length_order[19] = { 16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15 };
static const unsigned char repeat_extra[3] = { 2, 3, 7 };

/* A literal (len 0: the byte dist) or a copy of len bytes from dist back. */
typedef struct { unsigned short len, dist; } Symbol;

typedef struct {
    const unsigned char *in;
    size_t n;
    size_t head[HASH_SIZE];   /* each hash's latest position + 1 (0: none), */
    size_t prev[WINDOW];      /* and each position's previous one of the same hash */
    Symbol sym[BLOCK_SYMBOLS];
    int nsym;                 /* symbols in the block so far, */
    size_t from, to;          /* and the input they stand for */
    Bits bits;
} Deflate;

static unsigned hash3(const unsigned char *p)
{
    uint32_t v = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16;
    return (unsigned)((v * 2654435761u & 0xFFFFFFFFu) >> 17);  /* Knuth's multiplicative hash, 15 bits */
}

/* Position pos joins its hash's chain (once it has 3 bytes to hash). */
static void insert(Deflate *z, size_t pos)
{
    unsigned h;
    if (pos + MIN_MATCH > z->n) return;
    h = hash3(z->in + pos);
    z->prev[pos % WINDOW] = z->head[h];
    z->head[h] = pos + 1;
}

/* The longest copy of the bytes at pos that starts within WINDOW before it,
 * nearest first among equals: its chain, newest first, at most MAX_CHAIN
 * positions.  Only positions before pos are in the chains, so a position's
 * link is never one WINDOW newer that overwrote it. */
static Symbol find_match(const Deflate *z, size_t pos)
{
    Symbol best = { 0, 0 };
    const unsigned char *here = z->in + pos;
    size_t limit = z->n - pos < MAX_MATCH ? z->n - pos : MAX_MATCH, at, len;
    int chain = MAX_CHAIN;
    if (limit < MIN_MATCH) return best;
    for (at = z->head[hash3(here)]; at && pos - (at - 1) <= WINDOW && chain-- > 0; at = z->prev[(at - 1) % WINDOW]) {
        const unsigned char *there = z->in + at - 1;
        if (there[best.len] != here[best.len]) continue;   /* cannot be longer */
        for (len = 0; len < limit && there[len] == here[len]; len++) continue;
        if (len > best.len) {
            best.len = (unsigned short)len;
            best.dist = (unsigned short)(pos - (at - 1));
            if (len == limit) break;
        }
    }
    if (best.len < MIN_MATCH) best.len = 0;
    return best;
}

/* The code lengths of both alphabets as one sequence with runs (3.2.7): 16
 * repeats the previous length 3-6 times, 17 writes 3-10 zeros, 18 11-138.
 * Each entry: the symbol, and its extra bits' value above bit 5. */
static int run_lengths(const unsigned char *len, int n, unsigned short *out)
{
    int i = 0, k = 0, run, r;
    while (i < n) {
        int v = len[i];
        for (run = 1; i + run < n && len[i + run] == v; run++) continue;
        i += run;
        if (v == 0) {
            for (; run >= 11; run -= r) out[k++] = (unsigned short)(18 | ((r = run < 138 ? run : 138) - 11) << 5);
            if (run >= 3) { out[k++] = (unsigned short)(17 | (run - 3) << 5); run = 0; }
        } else {
            out[k++] = (unsigned short)v;
            for (run--; run >= 3; run -= r) out[k++] = (unsigned short)(16 | ((r = run < 6 ? run : 6) - 3) << 5);
        }
        for (; run > 0; run--) out[k++] = (unsigned short)v;
    }
    return k;
}

/* A block's codes: literals and lengths, distances, and the code-length
 * code they are sent in, with the counts of each that are sent. */
typedef struct {
    Huffman lit, dist, lengths;
    int nlit, ndist, nlengths, nruns;
    unsigned short runs[286 + 30];
} Codes;

/* Codes for these counts (3.2.7); the bits the header takes. */
static unsigned long make_codes(Codes *c, const unsigned long *lit_count, const unsigned long *dist_count)
{
    unsigned long run_count[19] = { 0 }, bits;
    unsigned char len[286 + 30];
    int i;
    huffman_lengths(lit_count, 286, 15, c->lit.len);
    huffman_lengths(dist_count, 30, 15, c->dist.len);
    for (c->nlit = 286; c->lit.len[c->nlit - 1] == 0; c->nlit--) continue;   /* 256 has a code */
    for (c->ndist = 30; c->ndist > 1 && c->dist.len[c->ndist - 1] == 0; c->ndist--) continue;
    memcpy(len, c->lit.len, (size_t)c->nlit);
    memcpy(len + c->nlit, c->dist.len, (size_t)c->ndist);
    c->nruns = run_lengths(len, c->nlit + c->ndist, c->runs);
    for (i = 0; i < c->nruns; i++) run_count[c->runs[i] & 31]++;
    huffman_lengths(run_count, 19, 7, c->lengths.len);
    for (c->nlengths = 19; c->nlengths > 4 && !c->lengths.len[length_order[c->nlengths - 1]]; c->nlengths--)
        continue;
    canonical_codes(&c->lit, 286);
    canonical_codes(&c->dist, 30);
    canonical_codes(&c->lengths, 19);
    bits = 3 + 5 + 5 + 4 + 3 * (unsigned long)c->nlengths;
    for (i = 0; i < c->nruns; i++) {
        int s = c->runs[i] & 31;
        bits += c->lengths.len[s] + (s >= 16 ? repeat_extra[s - 16] : 0);
    }
    return bits;
}

/* The header of a block with these codes (3.2.7). */
static void write_codes(Bits *w, const Codes *c, int last)
{
    int i;
    put_bits(w, (unsigned)last | 2 << 1, 3);      /* BFINAL, and BTYPE 10: dynamic codes */
    put_bits(w, (unsigned)(c->nlit - 257), 5);
    put_bits(w, (unsigned)(c->ndist - 1), 5);
    put_bits(w, (unsigned)(c->nlengths - 4), 4);
    for (i = 0; i < c->nlengths; i++) put_bits(w, c->lengths.len[length_order[i]], 3);
    for (i = 0; i < c->nruns; i++) {
        int s = c->runs[i] & 31;
        put_code(w, &c->lengths, s);
        if (s >= 16) put_bits(w, c->runs[i] >> 5, repeat_extra[s - 16]);
    }
}

/* in[from..to) as stored blocks (3.2.4): from a byte boundary, each of up
 * to 65535 bytes as they are, after their count and its complement. */
static void write_stored(Bits *w, const unsigned char *in, size_t from, size_t to, int last)
{
    do {
        size_t k = to - from < 65535 ? to - from : 65535;
        put_bits(w, (unsigned)(last && from + k == to), 3);   /* BFINAL, and BTYPE 00: stored */
        align_bits(w);
        put_bits(w, (unsigned)k, 16);
        put_bits(w, (unsigned)~k & 0xFFFF, 16);
        bytes_put(w->out, in + from, k);
        from += k;
    } while (from < to);
}

/* The block's symbols, counted; the extra bits they take. */
static unsigned long count_symbols(const Deflate *z, unsigned long *lit_count, unsigned long *dist_count)
{
    unsigned long extra = 0;
    int i, l, d;
    for (i = 0; i < z->nsym; i++) {
        const Symbol *s = &z->sym[i];
        if (!s->len) { lit_count[s->dist]++; continue; }
        lit_count[257 + (l = code_of(length_base, 29, s->len))]++;
        dist_count[d = code_of(dist_base, 30, s->dist)]++;
        extra += (unsigned long)length_extra[l] + dist_extra[d];
    }
    lit_count[256] = 1;                           /* the end of the block */
    return extra;
}

/* The block so far, with codes made for it, or stored when that is no
 * larger (data that does not compress, such as noise). */
static void write_block(Deflate *z, int last)
{
    unsigned long lit_count[286] = { 0 }, dist_count[30] = { 0 }, bits, stored;
    Codes codes, *c = &codes;
    int i, l, d;
    bits = count_symbols(z, lit_count, dist_count) + make_codes(c, lit_count, dist_count);
    for (i = 0; i < 286; i++) bits += lit_count[i] * c->lit.len[i];
    for (i = 0; i < 30; i++) bits += dist_count[i] * c->dist.len[i];
    stored = 8 * (unsigned long)(z->to - z->from) + (3 + 7 + 32) * ((z->to - z->from) / 65535 + 1);
    if (bits >= stored) write_stored(&z->bits, z->in, z->from, z->to, last);
    else {
        write_codes(&z->bits, c, last);
        for (i = 0; i < z->nsym; i++) {
            const Symbol *s = &z->sym[i];
            if (!s->len) { put_code(&z->bits, &c->lit, s->dist); continue; }
            put_code(&z->bits, &c->lit, 257 + (l = code_of(length_base, 29, s->len)));
            put_bits(&z->bits, s->len - length_base[l], length_extra[l]);
            put_code(&z->bits, &c->dist, d = code_of(dist_base, 30, s->dist));
            put_bits(&z->bits, s->dist - dist_base[d], dist_extra[d]);
        }
        put_code(&z->bits, &c->lit, 256);
    }
    z->nsym = 0;
    z->from = z->to;
}

static void add_symbol(Deflate *z, Symbol s)
{
    z->sym[z->nsym++] = s;
    z->to += s.len ? s.len : 1;
    if (z->nsym == BLOCK_SYMBOLS) write_block(z, 0);
}

/* The input as symbols, with lazy matching (RFC 1951 section 4): a copy
 * found at pos is put off by a byte when one at pos + 1 is longer. */
static void lz77(Deflate *z)
{
    size_t pos = 0, k;
    Symbol here = find_match(z, 0), next;
    while (pos < z->n) {
        if (!here.len) {
            Symbol literal = { 0, 0 };
            literal.dist = z->in[pos];
            add_symbol(z, literal);
            insert(z, pos++);
            here = find_match(z, pos);
            continue;
        }
        insert(z, pos);
        if (here.len < LAZY_MATCH && (next = find_match(z, pos + 1)).len > here.len) {
            Symbol literal = { 0, 0 };
            literal.dist = z->in[pos++];
            add_symbol(z, literal);
            here = next;
            continue;
        }
        add_symbol(z, here);
        for (k = 1; k < here.len; k++) insert(z, pos + k);
        pos += here.len;
        here = find_match(z, pos);
    }
    write_block(z, 1);
}

/* Adler-32 (RFC 1950 8.2): two sums modulo 65521, of the bytes and of the
 * first sums. */
static unsigned long adler32(const unsigned char *p, size_t n)
{
    unsigned long a = 1, b = 0;
    while (n--) {
        a = (a + *p++) % 65521;
        b = (b + a) % 65521;
    }
    return b << 16 | a;
}

/* Four bytes, most significant first, as PNG and zlib store numbers. */
static void put32(unsigned char *p, unsigned long v)
{
    p[0] = (unsigned char)(v >> 24 & 0xFF);
    p[1] = (unsigned char)(v >> 16 & 0xFF);
    p[2] = (unsigned char)(v >> 8 & 0xFF);
    p[3] = (unsigned char)(v & 0xFF);
}

/* in[0..n) as a zlib stream (RFC 1950) after out's bytes: CMF 0x78
 * (deflate, a 32K window) and FLG 0x9C (the default level; 0x789C is a
 * multiple of 31), the deflate data, the Adler-32 of in.  0: out of memory. */
static int zlib_compress(const unsigned char *in, size_t n, Bytes *out)
{
    static const unsigned char header[2] = { 0x78, 0x9C };
    unsigned char sum[4];
    Deflate *z = calloc(1, sizeof *z);
    if (!z) return 0;
    z->in = in;
    z->n = n;
    z->bits.out = out;
    bytes_put(out, header, 2);
    lz77(z);
    align_bits(&z->bits);
    put32(sum, adler32(in, n));
    bytes_put(out, sum, 4);
    free(z);
    return !out->failed;
}

/* PNG (ISO/IEC 15948): each row after the filter that suits it best, the
 * rows as one zlib stream cut into IDAT chunks; each chunk ends with the
 * CRC-32 of its type and data. */

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

/* One chunk: its length, type, data and CRC. */
static void png_chunk(FILE *f, const unsigned long crc[256], const char *type, const unsigned char *data,
                      size_t n)
{
    unsigned char head[8], tail[4];
    put32(head, (unsigned long)n);
    memcpy(head + 4, type, 4);
    put32(tail, crc_update(crc, crc_update(crc, 0xFFFFFFFFUL, head + 4, 4), data, n) ^ 0xFFFFFFFFUL);
    fwrite(head, 1, 8, f);
    fwrite(data, 1, n, f);
    fwrite(tail, 1, 4, f);
}

/* Paeth's predictor (ISO/IEC 15948 9.4): of the bytes to the left (a),
 * above (b) and above left (c), the one nearest a + b - c. */
static int paeth(int a, int b, int c)
{
    int p = a + b - c, pa = abs(p - a), pb = abs(p - b), pc = abs(p - c);
    return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

/* Byte i of a row after filter type t (9.2): the byte less its prediction
 * from the same channel of the pixel to the left and of the row above (up),
 * modulo 256; 0 none, 1 sub, 2 up, 3 average, 4 Paeth. */
static int filter_byte(int t, const unsigned char *row, const unsigned char *up, size_t i)
{
    int a = i >= 3 ? row[i - 3] : 0, b = up[i], c = i >= 3 ? up[i - 3] : 0;
    int guess = t == 0 ? 0 : t == 1 ? a : t == 2 ? b : t == 3 ? (a + b) / 2 : paeth(a, b, c);
    return (row[i] - guess) & 0xFF;
}

/* The n bytes of a row, filtered, after their filter type: the type whose
 * bytes, taken as signed, have the least sum of absolute values, the
 * heuristic 12.8 recommends for truecolour (small differences compress). */
static void filter_row(const unsigned char *row, const unsigned char *up, size_t n, unsigned char *out)
{
    unsigned long sum, least = 0;
    int t, best = 0;
    size_t i;
    for (t = 0; t < 5; t++) {
        for (sum = 0, i = 0; i < n; i++) {
            int d = filter_byte(t, row, up, i);
            sum += (unsigned long)(d < 128 ? d : 256 - d);
        }
        if (t == 0 || sum < least) { least = sum; best = t; }
    }
    out[0] = (unsigned char)best;
    for (i = 0; i < n; i++) out[1 + i] = (unsigned char)filter_byte(best, row, up, i);
}

/* An 8-bit RGB PNG; with srgb, it says its bytes are sRGB (the sRGB chunk,
 * and gAMA 1/2.2 for readers that know only that).  The filtered rows and
 * their compressed stream are made in memory.  0: out of memory. */
static int write_png(FILE *f, const unsigned char *img, int w, int h, int srgb)
{
    static const unsigned char signature[8] = { 137, 'P', 'N', 'G', 13, 10, 26, 10 };
    unsigned char ihdr[13] = { 0 }, zero = 0, gamma[4];
    unsigned long crc[256];
    size_t stride = (size_t)3 * w, at;
    unsigned char *rows = malloc((stride + 1) * h), *none = calloc(stride, 1);
    Bytes z = { NULL, 0, 0, 0 };
    int j, ok;
    for (j = 0; rows && none && j < h; j++)
        filter_row(img + stride * j, j ? img + stride * (j - 1) : none, stride, rows + (stride + 1) * j);
    ok = rows && none && zlib_compress(rows, (stride + 1) * h, &z);
    free(rows);
    free(none);
    if (!ok) { free(z.p); return 0; }
    crc_table(crc);
    fwrite(signature, 1, 8, f);
    put32(ihdr, (unsigned long)w);
    put32(ihdr + 4, (unsigned long)h);
    ihdr[8] = 8;                          /* bits per channel */
    ihdr[9] = 2;                          /* RGB; compression, filter, interlace 0 */
    png_chunk(f, crc, "IHDR", ihdr, 13);
    if (srgb) {
        put32(gamma, 45455);
        png_chunk(f, crc, "sRGB", &zero, 1); /* rendering intent 0, perceptual */
        png_chunk(f, crc, "gAMA", gamma, 4);
    }
    for (at = 0; at < z.n; at += 65536)   /* any size will do; 64K each, as before */
        png_chunk(f, crc, "IDAT", z.p + at, z.n - at < 65536 ? z.n - at : 65536);
    png_chunk(f, crc, "IEND", ihdr, 0);
    free(z.p);
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

/* OpenEXR, written from "OpenEXR File Layout" (openexr.com) and its
 * "Standard Attributes": a single-part scan-line file, version 2, of the
 * float radiance (as PFM has it) in channels B, G, R (their names in
 * alphabetical order, as the format requires), each pixel a 32-bit FLOAT
 * (HALF would clip above 65504 and keep 11 bits: a render's radiance is
 * kept whole).  ZIP_COMPRESSION: 16 lines a chunk, zlib-compressed after
 * the format's own predictor; a chunk that would not shrink is stored as it
 * is, which a reader knows by its size.  Every number is little-endian. */
#define EXR_LINES 16                      /* the scan lines of a ZIP_COMPRESSION chunk */

static void put_le(unsigned char *p, unsigned long v, int bytes)
{
    int i;
    for (i = 0; i < bytes; i++, v >>= 8) p[i] = (unsigned char)(v & 0xFF);
}

static void put_float(unsigned char *p, float x)
{
    uint32_t u;
    memcpy(&u, &x, 4);
    put_le(p, (unsigned long)u, 4);
}

/* An attribute: its name and type, each ending in a 0 byte; the size of
 * its value; the value. */
static void exr_attribute(Bytes *b, const char *name, const char *type, const unsigned char *value, int n)
{
    unsigned char size[4];
    put_le(size, (unsigned long)n, 4);
    bytes_put(b, name, strlen(name) + 1);
    bytes_put(b, type, strlen(type) + 1);
    bytes_put(b, size, 4);
    bytes_put(b, value, (size_t)n);
}

/* The magic number, the version field and the header: the attributes every
 * file must have (in alphabetical order, as the library writes them), then
 * a 0 byte. */
static void exr_header(Bytes *b, int w, int h)
{
    static const unsigned char start[8] = { 0x76, 0x2F, 0x31, 0x01,  /* 20000630 */
                                            2, 0, 0, 0 };  /* version 2; no flags: single-part scan lines */
    unsigned char channels[3 * 18 + 1] = { 0 }, box[16], zip = 3, increasing_y = 0, one[4], centre[8];
    int c;
    for (c = 0; c < 3; c++) {             /* a name, then pixel type 2 (FLOAT), pLinear and */
        unsigned char *ch = channels + 18 * c;  /* 3 bytes reserved 0, x and y sampling 1 */
        ch[0] = (unsigned char)"BGR"[c];
        put_le(ch + 2, 2, 4);
        put_le(ch + 10, 1, 4);
        put_le(ch + 14, 1, 4);
    }
    put_le(box, 0, 4);                    /* xMin, yMin, xMax, yMax: y grows downwards */
    put_le(box + 4, 0, 4);
    put_le(box + 8, (unsigned long)w - 1, 4);
    put_le(box + 12, (unsigned long)h - 1, 4);
    put_float(one, 1);
    put_float(centre, 0);
    put_float(centre + 4, 0);
    bytes_put(b, start, 8);
    exr_attribute(b, "channels", "chlist", channels, sizeof channels);
    exr_attribute(b, "compression", "compression", &zip, 1);      /* 3: ZIP_COMPRESSION */
    exr_attribute(b, "dataWindow", "box2i", box, 16);
    exr_attribute(b, "displayWindow", "box2i", box, 16);
    exr_attribute(b, "lineOrder", "lineOrder", &increasing_y, 1); /* 0: INCREASING_Y */
    exr_attribute(b, "pixelAspectRatio", "float", one, 4);
    exr_attribute(b, "screenWindowCenter", "v2f", centre, 8);
    exr_attribute(b, "screenWindowWidth", "float", one, 4);
    bytes_put(b, "", 1);                  /* the end of the header */
}

/* Lines y .. y + n - 1 as a chunk holds them: line by line, in each line
 * the channels one after another (B, G, R), a float a pixel. */
static void exr_lines(const Image *img, int y, int n, unsigned char *out)
{
    int j, c, i;
    for (j = y; j < y + n; j++)
        for (c = 2; c >= 0; c--)
            for (i = 0; i < img->w; i++, out += 4) put_float(out, img->floats[3 * ((size_t)j * img->w + i) + c]);
}

/* ZIP_COMPRESSION's predictor, before zlib: the bytes at even places, then
 * those at odd places (a float's like bytes together), then each byte as
 * its difference from the one before, plus 128, modulo 256. */
static void exr_predict(const unsigned char *in, size_t n, unsigned char *out)
{
    size_t i, half = (n + 1) / 2;
    for (i = 0; i < n; i++) out[i % 2 ? half + i / 2 : i / 2] = in[i];
    for (i = n - 1; i > 0; i--) out[i] = (unsigned char)(out[i] - out[i - 1] + 128);
}

/* The file: the header, the offset table (where each chunk starts in the
 * file, 8 bytes each), then the chunks, made in memory first so that the
 * table can come before them.  A chunk: its first line's y, its data's
 * size, its data.  0: out of memory. */
static int write_exr(FILE *f, const Image *img)
{
    int chunks = (img->h + EXR_LINES - 1) / EXR_LINES, c;
    size_t most = (size_t)img->w * EXR_LINES * 12, *at = malloc(chunks * sizeof *at);
    unsigned char *lines = malloc(most), *predicted = malloc(most), offset[8];
    Bytes head = { NULL, 0, 0, 0 }, data = { NULL, 0, 0, 0 }, zip = { NULL, 0, 0, 0 };
    int ok = at && lines && predicted;
    exr_header(&head, img->w, img->h);
    for (c = 0; ok && c < chunks; c++) {
        int y = c * EXR_LINES, n = img->h - y < EXR_LINES ? img->h - y : EXR_LINES;
        size_t size = (size_t)img->w * n * 12;
        unsigned char numbers[8];
        exr_lines(img, y, n, lines);
        exr_predict(lines, size, predicted);
        zip.n = 0;
        ok = zlib_compress(predicted, size, &zip);
        at[c] = data.n;
        put_le(numbers, (unsigned long)y, 4);
        put_le(numbers + 4, (unsigned long)(zip.n < size ? zip.n : size), 4);
        bytes_put(&data, numbers, 8);
        bytes_put(&data, zip.n < size ? zip.p : lines, zip.n < size ? zip.n : size);
    }
    ok = ok && !head.failed && !data.failed;
    if (ok) {
        fwrite(head.p, 1, head.n, f);
        for (c = 0; c < chunks; c++) {
            unsigned long long where = (unsigned long long)head.n + 8ull * chunks + at[c];
            put_le(offset, (unsigned long)(where & 0xFFFFFFFFu), 4);
            put_le(offset + 4, (unsigned long)(where >> 32), 4);
            fwrite(offset, 1, 8, f);
        }
        fwrite(data.p, 1, data.n, f);
    }
    free(at);
    free(lines);
    free(predicted);
    free(head.p);
    free(data.p);
    free(zip.p);
    return ok;
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

static int close_output(Output *o, int ok);

/* The image in the output's format, then the file closed and, if it was
 * written as a temporary, renamed into place; on failure a message and no
 * file.  A PNG of sRGB bytes says so. */
int write_image(Output *o, const Image *img, int plain)
{
    int ok = 1;
    errno = 0;
    if (o->format == FORMAT_PFM) write_pfm(o->f, img);
    else if (o->format == FORMAT_PNG || o->format == FORMAT_EXR) {
        ok = o->format == FORMAT_PNG ? write_png(o->f, img->bytes, img->w, img->h, img->srgb)
                                     : write_exr(o->f, img);
        if (!ok) errno = ENOMEM;
    } else
        write_ppm(o->f, img->bytes, img->w, img->h, plain);
    return close_output(o, ok);
}

/* The output's file closed and, if it was written as a temporary, renamed
 * into place; on failure a message and no file. */
static int close_output(Output *o, int ok)
{
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

/* ---------------------------------------------------- partial renders */

/* v as an Exact number (image.h): its magnitude cut down to a multiple of
 * 2^-64, then negated in two's complement if v is negative.  NaN adds
 * nothing; beyond 9.2e18 is clamped, inside the sums' range. */
static Exact exact_of(double v)
{
    Exact e = { 0, 0 };
    double a = fabs(v), whole;
    if (!(a > 0)) return e;
    if (a > 9.2e18) a = 9.2e18;
    whole = floor(a);
    e.hi = (uint64_t)whole;
    e.lo = (uint64_t)ldexp(a - whole, 64);  /* a - whole is exact, below 1 */
    if (v < 0) {
        e.hi = ~e.hi + (e.lo == 0);
        e.lo = ~e.lo + 1;
    }
    return e;
}

void exact_sum(Exact *sum, const Exact *more)
{
    uint64_t lo = sum->lo + more->lo;       /* unsigned: wraps, and the carry shows */
    sum->hi += more->hi + (lo < more->lo);
    sum->lo = lo;
}

void exact_add(Exact *sum, double v)
{
    Exact e = exact_of(v);
    exact_sum(sum, &e);
}

/* The sum as a double: the same rounding wherever it is computed. */
double exact_value(const Exact *sum)
{
    Exact e = *sum;
    if (e.hi >> 63) {                       /* negative: the value of its negation */
        e.hi = ~e.hi + (e.lo == 0);
        e.lo = ~e.lo + 1;
        return -((double)e.hi + ldexp((double)e.lo, -64));
    }
    return (double)e.hi + ldexp((double)e.lo, -64);
}

static size_t partial_pixels(const Partial *p) { return (size_t)(p->x1 - p->x0) * (size_t)(p->y1 - p->y0); }

int new_partial(Partial *p)
{
    size_t n = partial_pixels(p);
    p->sum = calloc(3 * n, sizeof *p->sum);
    p->n = calloc(n, sizeof *p->n);
    if (p->sum && p->n) return 1;
    free_partial(p);
    return 0;
}

void free_partial(Partial *p)
{
    free(p->sum);
    free(p->n);
    p->sum = NULL;
    p->n = NULL;
}

static void put_u64(unsigned char *p, uint64_t v)
{
    int i;
    for (i = 0; i < 8; i++) p[i] = (unsigned char)(v >> 8 * i);
}

static uint64_t get_u64(const unsigned char *p)
{
    uint64_t v = 0;
    int i;
    for (i = 7; i >= 0; i--) v = v << 8 | p[i];
    return v;
}

#define PIXEL_BYTES 56              /* n and three sums of two words: 7 x 8 bytes */

/* The partial's file (image.h's format), rows as write_partial's. */
static void put_partial(FILE *f, const Partial *p, const unsigned char *rows)
{
    int w = p->x1 - p->x0, x, y;
    unsigned char px[PIXEL_BYTES];
    static const unsigned char none[PIXEL_BYTES];
    fprintf(f, "ray partial 1\nimage %d %d\ncrop %d %d %d %d\nsamples %d %d %d\npixels %s\n%send\n", p->w,
            p->h, p->x0, p->y0, p->x1, p->y1, p->s0, p->s1, p->spp, p->srgb ? "srgb" : "linear", p->about);
    for (y = 0; y < p->y1 - p->y0; y++)
        for (x = 0; x < w; x++) {
            size_t at = (size_t)y * w + x;
            int c;
            if (rows && !rows[y]) { fwrite(none, 1, sizeof none, f); continue; }
            put_u64(px, p->n[at]);
            for (c = 0; c < 3; c++) {
                put_u64(px + 8 + 16 * c, p->sum[3 * at + c].hi);
                put_u64(px + 16 + 16 * c, p->sum[3 * at + c].lo);
            }
            fwrite(px, 1, sizeof px, f);
        }
}

int write_partial(Output *o, const Partial *p, const unsigned char *rows)
{
    errno = 0;
    put_partial(o->f, p, rows);
    return close_output(o, 1);
}

int save_partial(const char *name, const Partial *p, const unsigned char *rows)
{
    char *tmp = NULL;
    FILE *f = create_temp(name, &tmp);
    int ok = f != NULL;
    errno = 0;
    if (f) {
        put_partial(f, p, rows);
        ok = fflush(f) == 0 && !ferror(f);
        ok = fclose(f) == 0 && ok;
        ok = ok && replace_file(tmp, name) == 0;
    }
    if (!ok) {
        fprintf(stderr, "%s: cannot write the checkpoint: %s\n", name, strerror(errno));
        if (tmp) remove(tmp);
    }
    free(tmp);
    return ok;
}

/* One line of a partial's header into line (its end cut); 0 at the end of
 * the file or when it is too long. */
static int header_line(FILE *f, char *line, int size)
{
    size_t n;
    if (!fgets(line, size, f)) return 0;
    n = strlen(line);
    if (n == 0 || line[n - 1] != '\n') return 0;
    line[n - 1] = 0;
    return 1;
}

static int partial_fails(const char *name, int line, const char *what)
{
    if (line) fprintf(stderr, "%s:%d: %s\n", name, line, what);
    else fprintf(stderr, "%s: %s\n", name, what);
    return 0;
}

/* The header's numbers, each line as its format says; 0 after a message. */
static int read_header(FILE *f, const char *name, Partial *p)
{
    char line[PARTIAL_ABOUT], word[16], extra;
    int at;
    size_t used = 0;
    if (!header_line(f, line, sizeof line) || strcmp(line, "ray partial 1"))
        return partial_fails(name, 1, "not a partial render of ray (its first line is not `ray partial 1`)");
    if (!header_line(f, line, sizeof line) || sscanf(line, "image %d %d %c", &p->w, &p->h, &extra) != 2
        || p->w < 1 || p->h < 1 || p->w > 32768 || p->h > 32768)
        return partial_fails(name, 2, "needs `image W H`, from 1 to 32768");
    if (!header_line(f, line, sizeof line)
        || sscanf(line, "crop %d %d %d %d %c", &p->x0, &p->y0, &p->x1, &p->y1, &extra) != 4 || p->x0 < 0
        || p->y0 < 0 || p->x1 <= p->x0 || p->y1 <= p->y0 || p->x1 > p->w || p->y1 > p->h)
        return partial_fails(name, 3, "needs `crop X0 Y0 X1 Y1`, a rectangle of the image");
    if (!header_line(f, line, sizeof line)
        || sscanf(line, "samples %d %d %d %c", &p->s0, &p->s1, &p->spp, &extra) != 3 || p->s0 < 0
        || p->s1 <= p->s0 || p->s1 > p->spp)
        return partial_fails(name, 4, "needs `samples S0 S1 SPP`, with 0 <= S0 < S1 <= SPP");
    if (!header_line(f, line, sizeof line) || sscanf(line, "pixels %15s %c", word, &extra) != 1
        || (strcmp(word, "srgb") && strcmp(word, "linear")))
        return partial_fails(name, 5, "needs `pixels srgb` or `pixels linear`");
    p->srgb = !strcmp(word, "srgb");
    for (at = 6; header_line(f, line, sizeof line) && strcmp(line, "end"); at++) {
        if (used + strlen(line) + 2 > sizeof p->about)
            return partial_fails(name, at, "the provenance is longer than a partial's may be");
        memcpy(p->about + used, line, strlen(line));
        used += strlen(line);
        p->about[used++] = '\n';
    }
    if (feof(f) || ferror(f)) return partial_fails(name, at, "the header has no `end` line");
    p->about[used] = 0;
    return 1;
}

/* Are the bytes left in f those of n pixels?  f stays where it is. */
static int holds_pixels(FILE *f, size_t n)
{
    long here = ftell(f), end;
    if (here < 0 || fseek(f, 0, SEEK_END) != 0) return 1;     /* a pipe: the reads will tell */
    end = ftell(f);
    if (fseek(f, here, SEEK_SET) != 0) return 0;
    return end >= here && (double)(end - here) == (double)n * PIXEL_BYTES;
}

int read_partial(const char *name, Partial *p)
{
    FILE *f = fopen(name, "rb");
    unsigned char px[PIXEL_BYTES];
    size_t at, n;
    int ok;
    memset(p, 0, sizeof *p);
    if (!f) return partial_fails(name, 0, strerror(errno));
    ok = read_header(f, name, p);
    if (ok && !holds_pixels(f, partial_pixels(p)))     /* before the memory for them is taken */
        ok = partial_fails(name, 0, "truncated, or too long: not the bytes its crop's pixels take");
    if (ok && !new_partial(p)) ok = partial_fails(name, 0, "out of memory");
    n = ok ? partial_pixels(p) : 0;
    for (at = 0; ok && at < n; at++) {
        int c;
        if (fread(px, 1, sizeof px, f) != sizeof px) {
            ok = partial_fails(name, 0, "truncated: fewer pixels than its crop holds");
            break;
        }
        p->n[at] = get_u64(px);
        if (p->n[at] > (uint64_t)(p->s1 - p->s0)) ok = partial_fails(name, 0, "a pixel holds more samples than its range");
        for (c = 0; c < 3; c++) {
            p->sum[3 * at + c].hi = get_u64(px + 8 + 16 * c);
            p->sum[3 * at + c].lo = get_u64(px + 16 + 16 * c);
        }
    }
    if (ok && getc(f) != EOF) ok = partial_fails(name, 0, "more bytes than its crop holds");
    fclose(f);
    if (!ok) free_partial(p);
    return ok;
}

/* The first line in which two provenances differ, into what: "KEY: A, not B". */
static void first_difference(const char *a, const char *b, char *what, size_t size)
{
    while (*a && *b) {
        size_t la = strcspn(a, "\n"), lb = strcspn(b, "\n");
        if (la != lb || memcmp(a, b, la)) break;
        a += la + (a[la] != 0);
        b += lb + (b[lb] != 0);
    }
    snprintf(what, size, "`%.*s`, not `%.*s`", (int)strcspn(b, "\n"), b, (int)strcspn(a, "\n"), a);
}

/* Do parts a and b hold a sample of the same pixel? */
static int overlap(const Partial *a, const Partial *b)
{
    return a->x0 < b->x1 && b->x0 < a->x1 && a->y0 < b->y1 && b->y0 < a->y1 && a->s0 < b->s1 && b->s0 < a->s1;
}

/* The first samples that no part holds of pixel (x, y), into *lo .. *hi. */
static void gap(const Partial *parts, int n, int x, int y, int *lo, int *hi)
{
    int k = 0, i, moved = 1;
    while (moved) {
        moved = 0;
        for (i = 0; i < n; i++) {
            const Partial *p = &parts[i];
            if (x >= p->x0 && x < p->x1 && y >= p->y0 && y < p->y1 && p->s0 <= k && k < p->s1
                && p->n[(size_t)(y - p->y0) * (p->x1 - p->x0) + (x - p->x0)])
                k = p->s1, moved = 1;
        }
    }
    *lo = k;
    *hi = parts[0].spp;
    for (i = 0; i < n; i++)
        if (x >= parts[i].x0 && x < parts[i].x1 && y >= parts[i].y0 && y < parts[i].y1 && parts[i].s0 > k
            && parts[i].s0 < *hi)
            *hi = parts[i].s0;
}

/* Each pixel's samples counted over the parts; a hole is said: how many
 * pixels lack samples, where, and which samples the first lacks. */
static int no_holes(const Partial *parts, int n, const Partial *whole)
{
    uint64_t *covered = calloc((size_t)whole->w * whole->h, sizeof *covered), missing = 0;
    int i, x, y, fx = 0, fy = 0, x0 = whole->w, y0 = whole->h, x1 = 0, y1 = 0, lo, hi;
    if (!covered) return partial_fails("ray", 0, "out of memory");
    for (i = 0; i < n; i++)
        for (y = parts[i].y0; y < parts[i].y1; y++)
            for (x = parts[i].x0; x < parts[i].x1; x++)
                if (parts[i].n[(size_t)(y - parts[i].y0) * (parts[i].x1 - parts[i].x0) + (x - parts[i].x0)])
                    covered[(size_t)y * whole->w + x] += (uint64_t)(parts[i].s1 - parts[i].s0);
    for (y = 0; y < whole->h; y++)
        for (x = 0; x < whole->w; x++)
            if (covered[(size_t)y * whole->w + x] != (uint64_t)whole->spp) {
                if (!missing++) fx = x, fy = y;
                if (x < x0) x0 = x;
                if (y < y0) y0 = y;
                if (x >= x1) x1 = x + 1;
                if (y >= y1) y1 = y + 1;
            }
    free(covered);
    if (!missing) return 1;
    gap(parts, n, fx, fy, &lo, &hi);
    fprintf(stderr, "ray: the parts leave a hole: %llu pixels lack samples, within crop %d,%d,%d,%d;"
            " the first, (%d, %d), lacks samples %d:%d of %d\n", (unsigned long long)missing, x0, y0, x1, y1,
            fx, fy, lo, hi, whole->spp);
    return 0;
}

/* Were a (file an) and b made by one render (image, samples, pixels'
 * curve, provenance)?  Else a message that names what differs, and 0. */
static int belongs(const Partial *a, const char *an, const Partial *b, const char *bn)
{
    char what[2 * PARTIAL_ABOUT];
    if (a->w != b->w || a->h != b->h || a->spp != b->spp || a->srgb != b->srgb) {
        fprintf(stderr, "ray: %s is not a part of the render %s is: image %dx%d of %d samples%s, not %dx%d"
                " of %d%s\n", bn, an, b->w, b->h, b->spp, b->srgb ? " (sRGB)" : "", a->w, a->h, a->spp,
                a->srgb ? " (sRGB)" : "");
        return 0;
    }
    if (strcmp(a->about, b->about)) {
        first_difference(a->about, b->about, what, sizeof what);
        fprintf(stderr, "ray: %s is not a part of the render %s is: %s\n", bn, an, what);
        return 0;
    }
    return 1;
}

int same_part(const Partial *got, const Partial *want, const char *name)
{
    if (!belongs(want, "this run", got, name)) return 0;
    if (got->x0 != want->x0 || got->y0 != want->y0 || got->x1 != want->x1 || got->y1 != want->y1
        || got->s0 != want->s0 || got->s1 != want->s1) {
        fprintf(stderr, "ray: %s holds crop %d,%d,%d,%d and samples %d:%d; this run renders crop %d,%d,%d,%d"
                " and samples %d:%d\n", name, got->x0, got->y0, got->x1, got->y1, got->s0, got->s1, want->x0,
                want->y0, want->x1, want->y1, want->s0, want->s1);
        return 0;
    }
    return 1;
}

int merge_partials(Partial *parts, const char *const *names, int n, Partial *whole)
{
    int i, k;
    for (i = 1; i < n; i++)
        if (!belongs(&parts[0], names[0], &parts[i], names[i])) return 0;
    for (i = 0; i < n; i++)
        for (k = i + 1; k < n; k++)
            if (overlap(&parts[i], &parts[k])) {
                const Partial *a = &parts[i], *b = &parts[k];
                fprintf(stderr, "ray: %s and %s overlap: both hold samples %d:%d of the pixels in crop"
                        " %d,%d,%d,%d\n", names[i], names[k], a->s0 > b->s0 ? a->s0 : b->s0,
                        a->s1 < b->s1 ? a->s1 : b->s1, a->x0 > b->x0 ? a->x0 : b->x0, a->y0 > b->y0 ? a->y0 : b->y0,
                        a->x1 < b->x1 ? a->x1 : b->x1, a->y1 < b->y1 ? a->y1 : b->y1);
                return 0;
            }
    *whole = parts[0];
    whole->x0 = whole->y0 = whole->s0 = 0;
    whole->x1 = whole->w;
    whole->y1 = whole->h;
    whole->s1 = whole->spp;
    if (!new_partial(whole)) return partial_fails("ray", 0, "out of memory for the merged image");
    if (!no_holes(parts, n, whole)) { free_partial(whole); return 0; }
    for (i = 0; i < n; i++) {           /* integers: the order does not matter */
        const Partial *p = &parts[i];
        int x, y, c;
        for (y = p->y0; y < p->y1; y++)
            for (x = p->x0; x < p->x1; x++) {
                size_t from = (size_t)(y - p->y0) * (p->x1 - p->x0) + (x - p->x0), to = (size_t)y * whole->w + x;
                whole->n[to] += p->n[from];
                for (c = 0; c < 3; c++) exact_sum(&whole->sum[3 * to + c], &p->sum[3 * from + c]);
            }
    }
    return 1;
}

/* ------------------------------------------------ stop signals (checkpoints) */

/* The signal that asked a render with checkpoints to stop, or 0: the
 * second global of the signal handlers'. */
static volatile sig_atomic_t stop_by;

/* The first stop signal is remembered (the render then saves its work);
 * a second ends the program at once, as without checkpoints. */
static void on_stop(int sig)
{
    if (stop_by) on_signal(sig);
    stop_by = sig;
}

void catch_stop_signals(void)
{
    static const int sigs[] = { SIGINT, SIGTERM
#ifdef RAY_POSIX
        , SIGHUP
#endif
    };
    size_t i;
    for (i = 0; i < sizeof sigs / sizeof *sigs; i++)
        if (!ignored(sigs[i])) signal(sigs[i], on_stop);
}

int stop_signal(void) { return (int)stop_by; }

void end_by_signal(int sig)
{
    signal(sig, SIG_DFL);
    raise(sig);
}

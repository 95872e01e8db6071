#!/usr/bin/env python3
"""png2ppm.py FILE.png > FILE.ppm: a strict reader of the PNGs ray.c writes.

It checks what a PNG must be (signature; IHDR first; every chunk's CRC-32;
IDAT chunks in one run; the zlib stream whole, its Adler-32 right and nothing
after it; IEND last and empty) and prints the image as a binary PPM (P6), so
that a test can compare it byte for byte with ray.c's own PPM.  With -c it
also prints the names of the chunks, one a line, on stderr.  A test may
import it and call decode().  Only the test suite uses it; ray.c never does."""
import struct
import sys
import zlib


def fail(msg):
    sys.exit("png2ppm: " + msg)


def chunks(data):
    pos = 8
    while pos < len(data):
        if pos + 12 > len(data):
            fail("truncated chunk at byte %d" % pos)
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        crc, = struct.unpack(">I", data[pos + 8 + n:pos + 12 + n])
        if len(body) != n:
            fail("truncated chunk %r" % kind)
        if zlib.crc32(kind + body) != crc:
            fail("bad CRC in chunk %r" % kind)
        yield kind, body
        pos += 12 + n


def unfilter(raw, width, height):
    stride, bpp, out, prev = 3 * width, 3, bytearray(), bytearray(3 * width)
    for j in range(height):
        row = raw[j * (stride + 1):(j + 1) * (stride + 1)]
        kind, cur = row[0], bytearray(row[1:])
        for i in range(stride):
            a = cur[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
            if kind == 1: cur[i] = (cur[i] + a) & 255
            elif kind == 2: cur[i] = (cur[i] + b) & 255
            elif kind == 3: cur[i] = (cur[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                cur[i] = (cur[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
            elif kind != 0: fail("bad filter type %d in row %d" % (kind, j))
        out += cur
        prev = cur
    return bytes(out)


def decode(data):
    """The PNG in data as a binary PPM, and the names of its chunks; a
    SystemExit with the reason if it is not the PNG it must be."""
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        fail("not a PNG signature")
    seen = list(chunks(data))
    names = [k.decode("latin-1") for k, _ in seen]
    if not names or names[0] != "IHDR" or names[-1] != "IEND" or seen[-1][1]:
        fail("IHDR must come first and an empty IEND last: %s" % names)
    if "IDAT" not in names:
        fail("no IDAT chunk: %s" % names)
    first, last = names.index("IDAT"), len(names) - 1 - names[::-1].index("IDAT")
    if names[first:last + 1] != ["IDAT"] * (last - first + 1):
        fail("IDAT chunks are not consecutive: %s" % names)
    width, height, depth, colour, comp, filt, lace = struct.unpack(">IIBBBBB", seen[0][1])
    if (depth, colour, comp, filt, lace) != (8, 2, 0, 0, 0):
        fail("not 8-bit RGB, deflate, no interlace: %s" % ((depth, colour, comp, filt, lace),))
    z = zlib.decompressobj()
    try:
        raw = z.decompress(b"".join(body for kind, body in seen if kind == b"IDAT"))
    except zlib.error as e:
        fail("the zlib stream is bad: %s" % e)
    if not z.eof or z.unused_data:
        fail("the zlib stream is incomplete or has bytes after its end")
    if len(raw) != height * (3 * width + 1):
        fail("%d bytes of rows, not %d" % (len(raw), height * (3 * width + 1)))
    return b"P6\n%d %d\n255\n" % (width, height) + unfilter(raw, width, height), names


def main():
    args = [a for a in sys.argv[1:] if a != "-c"]
    ppm, names = decode(open(args[0], "rb").read())
    if "-c" in sys.argv:
        sys.stderr.write("".join(n + "\n" for n in names))
    sys.stdout.buffer.write(ppm)


if __name__ == "__main__":
    main()

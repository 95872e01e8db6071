#!/usr/bin/env python3
"""exr2pfm.py FILE.exr > FILE.pfm: a strict reader of the OpenEXR files ray.c writes.

Written from "OpenEXR File Layout" and "Standard Attributes" (openexr.com),
with python's struct and zlib only.  It checks what ray's EXR must be: the
magic number; version 2 with no flags (single-part scan lines); the header's
attributes, every one that is required and no other, each of its type and
size: channels B, G, R (alphabetical), each FLOAT, sampled 1 1;
compression NO_COMPRESSION (a line a chunk) or ZIP_COMPRESSION (16 lines);
dataWindow and displayWindow the same, from (0, 0); lineOrder INCREASING_Y;
pixelAspectRatio 1, screenWindowCenter (0, 0), screenWindowWidth 1.  Then
the offset table: one offset a chunk, the first just after the table, each
chunk just after the one before and the last ending the file.  Each chunk:
its y, its data size (a ZIP chunk the size of its raw lines is stored as it
is); a zlib stream whole, with nothing after it, inflating to exactly the
lines' bytes, and the predictor and interleave undone.  It prints the image
as ray.c's PFM (-1.0: little-endian; rows from the bottom up), so that a
test can compare it byte for byte with ray's own PFM of the same render.

With --tiled it reads instead a file the OpenEXR library wrote with
`exrmaketiled -t W H -z none` from one of ray's: a single uncompressed tile
the size of the image (flag 0x200; the attributes tiles, type and
chunkCount allowed too), so that a test can compare the pixels the library
decoded.  With -c it also prints, one a line on stderr, how each ZIP chunk
is kept: zip, or stored (as it is).  A test may import it and call
decode().  Only the test suite uses it; ray.c never does."""
import itertools
import struct
import sys
import zlib

REQUIRED = {  # name: (type, size)
    "channels": ("chlist", 3 * 18 + 1), "compression": ("compression", 1),
    "dataWindow": ("box2i", 16), "displayWindow": ("box2i", 16),
    "lineOrder": ("lineOrder", 1), "pixelAspectRatio": ("float", 4),
    "screenWindowCenter": ("v2f", 8), "screenWindowWidth": ("float", 4),
}
KINDS = []  # each ZIP chunk's: "zip", or "stored" (as it is)
TILED_EXTRA = {"tiles": ("tiledesc", 9), "type": ("string", None), "chunkCount": ("int", 4)}


def fail(msg):
    sys.exit("exr2pfm: " + msg)


def text(data, pos, what):
    end = data.find(b"\0", pos)
    if end < 0 or end - pos > 31:
        fail("%s at byte %d: no 0 byte within 31 characters" % (what, pos))
    return data[pos:end].decode("latin-1"), end + 1


def header(data, tiled):
    if data[:4] != b"\x76\x2f\x31\x01":
        fail("not the magic number 20000630")
    field, = struct.unpack("<I", data[4:8])
    version, flags = field & 0xFF, field & ~0xFF
    if version != 2 or flags != (0x200 if tiled else 0):  # bit 9: tiled
        fail("version %d, flags 0x%x: not a version 2 single-part %s file"
             % (version, flags, "tiled" if tiled else "scan-line"))
    allowed = dict(REQUIRED, **(TILED_EXTRA if tiled else {}))
    attrs, pos = {}, 8
    while True:
        if pos >= len(data):
            fail("the header has no end")
        if data[pos] == 0:
            pos += 1
            break
        name, pos = text(data, pos, "an attribute's name")
        kind, pos = text(data, pos, "attribute %s's type" % name)
        size, = struct.unpack("<i", data[pos:pos + 4])
        value = data[pos + 4:pos + 4 + size]
        pos += 4 + size
        if name not in allowed:
            fail("attribute %s is not one ray writes" % name)
        if name in attrs:
            fail("attribute %s twice" % name)
        want_kind, want_size = allowed[name]
        if kind != want_kind or (want_size is not None and size != want_size) or len(value) != size:
            fail("attribute %s: type %s, %d bytes; want %s, %s bytes" % (name, kind, size, want_kind, want_size))
        attrs[name] = value
    missing = [n for n in REQUIRED if n not in attrs] + (["tiles"] if tiled and "tiles" not in attrs else [])
    if missing:
        fail("required attributes missing: %s" % ", ".join(missing))
    return attrs, pos


def check_attributes(a):
    ch = a["channels"]
    for i, name in enumerate(b"BGR"):
        c = ch[18 * i:18 * (i + 1)]
        if c[0] != name or c[1] != 0 or struct.unpack("<iB3xii", c[2:]) != (2, 0, 1, 1) or c[7:10] != b"\0\0\0":
            fail("channel %d is not %s, FLOAT, linear 0, sampling 1 1: %r" % (i, chr(name), c))
    if ch[54] != 0:
        fail("the channel list does not end after R")
    compression = a["compression"][0]
    data_window = struct.unpack("<4i", a["dataWindow"])
    if data_window[:2] != (0, 0) or data_window[2] < 0 or data_window[3] < 0:
        fail("dataWindow %s does not start at (0, 0)" % (data_window,))
    if a["displayWindow"] != a["dataWindow"]:
        fail("displayWindow %s is not dataWindow" % (struct.unpack("<4i", a["displayWindow"]),))
    if a["lineOrder"] != b"\0":
        fail("lineOrder %d, not INCREASING_Y" % a["lineOrder"][0])
    if struct.unpack("<f", a["pixelAspectRatio"]) != (1.0,) or struct.unpack("<2f", a["screenWindowCenter"]) != (0.0, 0.0) \
            or struct.unpack("<f", a["screenWindowWidth"]) != (1.0,):
        fail("pixelAspectRatio, screenWindowCenter, screenWindowWidth are not 1, (0, 0), 1")
    return compression, data_window[2] + 1, data_window[3] + 1


def chunks(data, pos, count, head):
    """The chunks' data, after checking the offset table: each chunk just
    after the one before, the last ending the file; head is the size of the
    numbers before each chunk's data size."""
    offsets = struct.unpack("<%dQ" % count, data[pos:pos + 8 * count])
    at = pos + 8 * count
    for k, off in enumerate(offsets):
        if off != at:
            fail("chunk %d's offset is %d, not %d (just after the one before)" % (k, off, at))
        numbers = struct.unpack("<%di" % (head // 4 + 1), data[at:at + head + 4])
        size = numbers[-1]
        if size < 0 or at + head + 4 + size > len(data):
            fail("chunk %d's size %d runs past the end" % (k, size))
        yield numbers[:-1], data[at + head + 4:at + head + 4 + size]
        at += head + 4 + size
    if at != len(data):
        fail("%d bytes after the last chunk" % (len(data) - at))


def unzip(body, size, where):
    """ZIP_COMPRESSION's data, back to the lines' bytes: inflated, then each
    byte the sum of the differences (less 128 each), then the halves
    interleaved again."""
    KINDS.append("stored" if len(body) == size else "zip")
    if len(body) == size:
        return body                      # did not shrink: stored as it is
    if len(body) > size:
        fail("%s: %d bytes, more than its %d raw bytes" % (where, len(body), size))
    z = zlib.decompressobj()
    try:
        out = bytearray(z.decompress(body))
    except zlib.error as e:
        fail("%s: the zlib stream is bad: %s" % (where, e))
    if not z.eof or z.unused_data or len(out) != size:
        fail("%s: the zlib stream is incomplete, has bytes after its end or is not %d bytes" % (where, size))
    out = bytes(itertools.accumulate(out, lambda before, d: (before + d - 128) & 255))
    half = (size + 1) // 2
    raw = bytearray(size)
    raw[0::2], raw[1::2] = out[:half], out[half:]
    return bytes(raw)


def decode(data, tiled=False):
    """The EXR in data as ray's PFM, and how each ZIP chunk is kept (zip or
    stored); a SystemExit with the reason if it is not the file it must be."""
    del KINDS[:]
    try:
        return read(data, tiled)
    except (struct.error, IndexError) as e:
        fail("truncated or malformed: %s" % e)


def read(data, tiled):
    attrs, pos = header(data, tiled)
    compression, w, h = check_attributes(attrs)
    line = 12 * w                        # B, G, R floats of a line
    rows = [None] * h
    if tiled:
        tw, th, mode = struct.unpack("<IIB", attrs["tiles"])
        if (tw, th, mode, compression) != (w, h, 0, 0):
            fail("not one uncompressed tile of %dx%d: %s" % (w, h, (tw, th, mode, compression)))
        for numbers, body in chunks(data, pos, 1, 16):
            if numbers != (0, 0, 0, 0) or len(body) != line * h:
                fail("the tile is %s, %d bytes" % (numbers, len(body)))
            rows = [body[j * line:(j + 1) * line] for j in range(h)]
    else:
        if compression not in (0, 3):
            fail("compression %d: neither NO_COMPRESSION nor ZIP_COMPRESSION" % compression)
        lines = 16 if compression == 3 else 1
        for k, (numbers, body) in enumerate(chunks(data, pos, (h + lines - 1) // lines, 4)):
            y, n = numbers[0], min(lines, h - k * lines)
            if y != k * lines:
                fail("chunk %d is of line %d, not %d" % (k, y, k * lines))
            raw = unzip(body, n * line, "chunk %d" % k) if compression == 3 else body
            if len(raw) != n * line:
                fail("chunk %d has %d bytes, not %d" % (k, len(raw), n * line))
            for j in range(n):
                rows[y + j] = raw[j * line:(j + 1) * line]
    out = bytearray(b"PF\n%d %d\n-1.0\n" % (w, h))
    for row in reversed(rows):           # PFM: bottom row first; each pixel R, G, B
        b, g, r = (struct.unpack("<%dI" % w, row[c * 4 * w:(c + 1) * 4 * w]) for c in range(3))
        out += struct.pack("<%dI" % (3 * w), *(v for px in zip(r, g, b) for v in px))  # the bits as they are
    return bytes(out), list(KINDS)


def main():
    args = [a for a in sys.argv[1:] if a not in ("--tiled", "-c")]
    pfm, kinds = decode(open(args[0], "rb").read(), "--tiled" in sys.argv)
    sys.stdout.buffer.write(pfm)
    if "-c" in sys.argv:
        sys.stderr.write("".join(k + "\n" for k in kinds))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Converts the XWD framebuffer that `Xvfb -fbdir` keeps (24/32 bits per pixel, TrueColor) to PNG.
Usage: xwd2png.py IN.xwd OUT.png. Prints the number of distinct colours (a blank screen has 1)."""
import struct
import sys
import zlib


def read_xwd(path):
    with open(path, "rb") as f:
        data = f.read()
    h = struct.unpack(">25I", data[:100])
    header_size, _, _, _, width, height, _, byte_order, _, _, _, bpp, bpl = h[:13]
    red_mask, green_mask, blue_mask = h[14:17]
    ncolors = h[19]
    off = header_size + ncolors * 12
    if bpp not in (24, 32):
        raise SystemExit("unsupported XWD: %d bits per pixel" % bpp)
    step = bpp // 8

    def shift(mask):
        s = 0
        while mask and not (mask >> s) & 1:
            s += 1
        return s

    rs, gs, bs = shift(red_mask), shift(green_mask), shift(blue_mask)
    rows = []
    for y in range(height):
        line = data[off + y * bpl: off + y * bpl + width * step]
        out = bytearray(width * 3)
        for x in range(width):
            px = line[x * step:(x + 1) * step]
            v = int.from_bytes(px, "little" if byte_order == 0 else "big")
            out[3 * x] = (v & red_mask) >> rs
            out[3 * x + 1] = (v & green_mask) >> gs
            out[3 * x + 2] = (v & blue_mask) >> bs
        rows.append(bytes(out))
    return width, height, rows


def write_png(path, width, height, rows):
    def chunk(tag, body):
        c = struct.pack(">I", len(body)) + tag + body
        return c + struct.pack(">I", zlib.crc32(tag + body) & 0xFFFFFFFF)

    raw = b"".join(b"\x00" + r for r in rows)
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def main():
    w, h, rows = read_xwd(sys.argv[1])
    write_png(sys.argv[2], w, h, rows)
    colours = set()
    for r in rows[::8]:
        for x in range(0, len(r), 24):
            colours.add(r[x:x + 3])
    print(len(colours))


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Counts the pixels of a screenshot of web/index.html by colour and checks
that the light layer and both routes are drawn.

usage: png_pixels.py SHOT.png   (prints the counts; exit 1 when one is missing)

The PNG is decoded here with zlib alone (8-bit RGB or RGBA, not interlaced,
as Chromium writes its screenshots)."""
import struct
import sys
import zlib


def decode(path):
    data = open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("not a PNG")
    i, idat, w = 8, b"", 0
    while i < len(data):
        n, kind = struct.unpack(">I4s", data[i:i + 8])
        body = data[i + 8:i + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or ctype not in (2, 6) or interlace:
                raise ValueError("only 8-bit RGB/RGBA, not interlaced")
            bpp = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += body
        i += 12 + n
    raw, stride, rows, prev = zlib.decompress(idat), w * bpp, [], bytearray(w * bpp)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - bpp] if x >= bpp else 0
            b, c = prev[x], prev[x - bpp] if x >= bpp else 0
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + b) & 255
            elif f == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line
    return w, h, bpp, rows


def classify(r, g, b):
    if r < 40 and g > 200 and b > 220:
        return "best-lit route"   # #00e5ff
    if r > 220 and g < 90 and b > 180:
        return "shortest route"   # #ff2bd6
    if r > 180 and b < 130 and g > 60:
        return "light (orange/yellow)"  # the heat map's upper colours
    if b > 80 and r < 160 and g < 80:
        return "light (blue/purple)"    # its lower colours
    return None


def main():
    w, h, bpp, rows = decode(sys.argv[1])
    counts = {"best-lit route": 0, "shortest route": 0, "light (orange/yellow)": 0, "light (blue/purple)": 0}
    for line in rows:
        for x in range(0, w * bpp, bpp):
            k = classify(line[x], line[x + 1], line[x + 2])
            if k:
                counts[k] += 1
    total = w * h
    for k, v in counts.items():
        print("%-22s %7d pixels (%.2f%%)" % (k, v, 100.0 * v / total))
    need = {"best-lit route": 500, "shortest route": 300, "light (orange/yellow)": 2000, "light (blue/purple)": 2000}
    missing = [k for k, v in need.items() if counts[k] < v]
    if missing:
        print("missing from the screenshot: " + ", ".join(missing))
        return 1
    print("light layer and both routes drawn")
    return 0


if __name__ == "__main__":
    sys.exit(main())

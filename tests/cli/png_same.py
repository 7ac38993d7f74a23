"""Whether two 8-bit RGB PNG files hold the same pixels, whatever their
compression level and row filters (a decoder independent of libpng: zlib
and the five PNG row filters). Exit 0 when the same, 1 otherwise.
usage: /usr/bin/python3 png_same.py A.png B.png
"""
import struct
import sys
import zlib


def rows(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path + ": no PNG signature"
    p, idat, ihdr = 8, [], None
    while p < len(data):
        n, = struct.unpack(">I", data[p:p + 4])
        kind, body = data[p + 4:p + 8], data[p + 8:p + 8 + n]
        if kind == b"IHDR":
            ihdr = body
        elif kind == b"IDAT":
            idat.append(body)
        p += 12 + n
    w, h, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", ihdr)
    assert depth == 8 and colour == 2 and interlace == 0, path + ": not 8-bit RGB"
    raw, stride, bpp = zlib.decompress(b"".join(idat)), 3 * w, 3
    prev, out = bytearray(stride), []
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - bpp] if x >= bpp else 0
            b = prev[x]
            c = prev[x - bpp] if x >= bpp else 0
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + b) & 255
            elif f == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                pr = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[x] = (line[x] + pr) & 255
            else:
                assert f == 0, path + ": unknown filter %d" % f
        out.append(bytes(line))
        prev = line
    return (w, h), out


if __name__ == "__main__":
    sys.exit(0 if rows(sys.argv[1]) == rows(sys.argv[2]) else 1)

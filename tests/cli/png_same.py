"""Whether two 8-bit RGB PNG files hold the same pixels, whatever their
compression level and row filters (decoded with zlib alone by
tests/web/png_pixels.py, independently of libpng). Exit 0 when the same,
1 otherwise. With --within N: the same size and no byte more than N apart
(prints the largest difference and the share of identical bytes).
usage: /usr/bin/python3 png_same.py [--within N] A.png B.png
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "web"))
from png_pixels import decode  # noqa: E402


def pixels(path):
    w, h, bpp, rows = decode(path)
    return w, h, bpp, [bytes(r) for r in rows]


def within(a, b, n):
    wa, ha, ba, ra = pixels(a)
    wb, hb, bb, rb = pixels(b)
    if (wa, ha, ba) != (wb, hb, bb):
        print("sizes differ")
        return False
    worst, same, total = 0, 0, 0
    for x, y in zip(ra, rb):
        for u, v in zip(x, y):
            d = abs(u - v)
            worst = max(worst, d)
            same += d == 0
            total += 1
    print("largest difference %d, %.1f%% of the bytes identical" % (worst, 100.0 * same / total))
    return worst <= n


if __name__ == "__main__":
    if sys.argv[1] == "--within":
        sys.exit(0 if within(sys.argv[3], sys.argv[4], int(sys.argv[2])) else 1)
    sys.exit(0 if pixels(sys.argv[1]) == pixels(sys.argv[2]) else 1)

"""Whether two 8-bit RGB PNG files hold the same pixels, whatever their
compression level and row filters (decoded with zlib alone by
tests/web/png_pixels.py, independently of libpng). Exit 0 when the same,
1 otherwise.
usage: /usr/bin/python3 png_same.py A.png B.png
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "web"))
from png_pixels import decode  # noqa: E402


def pixels(path):
    w, h, bpp, rows = decode(path)
    return w, h, bpp, [bytes(r) for r in rows]


if __name__ == "__main__":
    sys.exit(0 if pixels(sys.argv[1]) == pixels(sys.argv[2]) else 1)

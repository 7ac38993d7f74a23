"""Checks an animated PNG written by `polarlux walk` against its frame files,
independently of port/png/apng.c: every chunk's CRC (zlib.crc32), the
acTL frame count, one fcTL per frame with the frames' size, sequence
numbers 0, 1, 2, ... over fcTL and fdAT, and each frame's image data
(IDAT for the first, fdAT for the others) decompressing to the same bytes
as its frame file's IDAT data.
usage: /usr/bin/python3 apng_check.py WALK.png FRAME.png...
"""
import struct
import sys
import zlib


def chunks(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path + ": no PNG signature"
    p, out = 8, []
    while p < len(data):
        n, = struct.unpack(">I", data[p:p + 4])
        kind, body = data[p + 4:p + 8], data[p + 8:p + 8 + n]
        crc, = struct.unpack(">I", data[p + 8 + n:p + 12 + n])
        assert zlib.crc32(kind + body) & 0xffffffff == crc, "%s: bad CRC in %s" % (path, kind)
        out.append((kind, body))
        p += 12 + n
    assert out[-1][0] == b"IEND", path + ": no IEND at the end"
    return out


def pixels(path):
    ck = chunks(path)
    return dict(ck)[b"IHDR"], zlib.decompress(b"".join(b for k, b in ck if k == b"IDAT"))


def main(anim, frames):
    ck = chunks(anim)
    assert ck[0][0] == b"IHDR"
    ac = [b for k, b in ck if k == b"acTL"]
    assert len(ac) == 1 and struct.unpack(">II", ac[0]) == (len(frames), 0), "acTL"
    seq, got, cur = 0, [], None
    for kind, body in ck:
        if kind == b"fcTL":
            s, w, h = struct.unpack(">III", body[:12])
            assert s == seq and (w, h) == struct.unpack(">II", ck[0][1][:8]), "fcTL %d" % seq
            seq += 1
            cur = []
            got.append(cur)
        elif kind == b"IDAT":
            assert len(got) == 1, "IDAT outside the first frame"
            cur.append(body)
        elif kind == b"fdAT":
            s, = struct.unpack(">I", body[:4])
            assert s == seq and len(got) > 1, "fdAT sequence %d" % s
            seq += 1
            cur.append(body[4:])
    assert len(got) == len(frames), "%d fcTL for %d frames" % (len(got), len(frames))
    for k, f in enumerate(frames):
        ihdr, px = pixels(f)
        assert ihdr == ck[0][1], "frame %d: another IHDR" % (k + 1)
        assert zlib.decompress(b"".join(got[k])) == px, "frame %d: other pixels" % (k + 1)
    print("apng ok: %d frames" % len(frames))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:])

#!/usr/bin/env python3
"""MAE between two renders of one view (standard library only): the linear AO images (`--ao-out` .pfm) and the
shaded images (`--out` .png, 8-bit RGB or RGBA, values / 255, mean of R, G, B), over the pixels the model covers in
either image (a pixel differing from its row's left edge, the background, in the shaded image).

Usage: image-mae.py A.png A.pfm B.png B.pfm  ->  prints JSON {"ao_mae", "shaded_mae", "covered"}.
"""
import json
import struct
import sys
import zlib


def read_png(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path}: not a PNG"
    at, idat, w = 8, b"", None
    while at < len(data):
        n, kind = struct.unpack(">I4s", data[at:at + 8])
        body = data[at + 8:at + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and ctype in (2, 6), f"{path}: 8-bit RGB(A) only"
            bpp = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += body
        at += 12 + n
    raw = zlib.decompress(idat)
    stride = w * bpp
    rows, prev = [], bytearray(stride)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
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
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append([tuple(line[x * bpp:x * bpp + 3]) for x in range(w)])
        prev = line
    return w, h, rows


def read_pfm(path):
    data = open(path, "rb").read()
    kind, dims, scale, rest = data.split(b"\n", 3)
    assert kind == b"Pf", f"{path}: one-channel PFM only"
    w, h = map(int, dims.split())
    fmt = ("<" if float(scale) < 0 else ">") + "f" * (w * h)
    v = struct.unpack(fmt, rest[:4 * w * h])
    # PFM rows run bottom to top.
    return w, h, [v[(h - 1 - y) * w:(h - y) * w] for y in range(h)]


def covered(rows):
    return [[any(abs(p[k] - r[0][k]) > 4 for k in range(3)) for p in r] for r in rows]


def main(a_png, a_pfm, b_png, b_pfm):
    (w, h, pa), (_, _, pb) = read_png(a_png), read_png(b_png)
    (_, _, aa), (_, _, ab) = read_pfm(a_pfm), read_pfm(b_pfm)
    ca, cb = covered(pa), covered(pb)
    n, ao, sh = 0, 0.0, 0.0
    for y in range(h):
        for x in range(w):
            if ca[y][x] or cb[y][x]:
                n += 1
                ao += abs(aa[y][x] - ab[y][x])
                sh += sum(abs(pa[y][x][k] - pb[y][x][k]) for k in range(3)) / (3 * 255.0)
    print(json.dumps({"ao_mae": ao / max(n, 1), "shaded_mae": sh / max(n, 1), "covered": n}))


if __name__ == "__main__":
    main(*sys.argv[1:5])

#!/usr/bin/env python3
"""The sky light's test environment: a 64x32 Radiance RGBE (.hdr) image, written deterministically (stdlib only).

    python3 scripts/make-sky-hdr.py [OUT]   (default: testdata/env/sky_lobe_64x32.hdr)

E(b) = G + (S - G) (1 + b_z) / 2 + (2.0, 1.4, 0.8) max(0, b . l)^8, the built-in gradient (S = (0.6, 0.8, 1.0) at the
zenith, G = (0.4, 0.3, 0.2) at the nadir) plus a broad warm lobe towards l at azimuth 30 degrees (from +b_x towards
+b_y) and elevation 30 degrees. Pixel (i, j), row 0 at the top, is E at its centre: u = (i + 1/2)/W, t = (j + 1/2)/H,
the inverse of the sky light's lookup (u = 0.5 - atan2(b_y, b_x)/2pi, t = 0.5 - asin(b_z)/pi; the image centre faces
+b_x, row 0 is the zenith). No EXPOSURE line; scanlines run-length encoded (literal packets only).
"""
import math
import os
import sys

W, H = 64, 32
SKY, GROUND = (0.6, 0.8, 1.0), (0.4, 0.3, 0.2)
LOBE_COLOUR, LOBE_POWER = (2.0, 1.4, 0.8), 8
AZIMUTH, ELEVATION = math.radians(30.0), math.radians(30.0)
LOBE = (math.cos(ELEVATION) * math.cos(AZIMUTH), math.cos(ELEVATION) * math.sin(AZIMUTH), math.sin(ELEVATION))


def radiance(b):
    s = 0.5 * (1.0 + b[2])
    k = max(0.0, sum(x * y for x, y in zip(b, LOBE))) ** LOBE_POWER
    return tuple(GROUND[c] + (SKY[c] - GROUND[c]) * s + LOBE_COLOUR[c] * k for c in range(3))


def direction(i, j):
    phi = (0.5 - (i + 0.5) / W) * 2.0 * math.pi
    el = (0.5 - (j + 0.5) / H) * math.pi
    return (math.cos(el) * math.cos(phi), math.cos(el) * math.sin(phi), math.sin(el))


def rgbe(rgb):
    v = max(rgb)
    if v < 1e-32:
        return (0, 0, 0, 0)
    m, e = math.frexp(v)
    scale = m * 256.0 / v
    return tuple(int(c * scale) for c in rgb) + (e + 128,)


def scanline(pixels):
    out = bytearray((2, 2, W >> 8, W & 255))
    for c in range(4):
        values = [p[c] for p in pixels]
        for k in range(0, len(values), 128):
            chunk = values[k:k + 128]
            out.append(len(chunk))
            out.extend(chunk)
    return bytes(out)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "testdata", "env", "sky_lobe_64x32.hdr")
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    data = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (H, W))
    for j in range(H):
        data += scanline([rgbe(radiance(direction(i, j))) for i in range(W)])
    with open(out, "wb") as f:
        f.write(data)
    print("wrote %s (%dx%d)" % (out, W, H))


if __name__ == "__main__":
    main()

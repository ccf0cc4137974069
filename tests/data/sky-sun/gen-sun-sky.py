#!/usr/bin/env python3
"""Writes sun-sky.hdr beside this script: the tiny environment map of envmap-fog.xml (issue 36).

A 64 x 32 latitude-longitude map in Mitsuba 3's convention (row 0 the zenith, +y up; a world
direction d at u = atan2(d.x, -d.z) / 2 pi, v = acos(d.y) / pi, pixel centres at
u = (i + 1/2) / W and v = j / (H - 1): crates/scene/src/envmap.rs): a blue sky brightening
towards the horizon, a dark ground below it, and a sun of one pixel (radiance 3000) and its four
neighbours (300) towards SUN, about 40 degrees up. Radiance HDR (RGBE), flat scanlines;
pure Python, deterministic.

    python3 tests/data/sky-sun/gen-sun-sky.py
"""
import math
import os

W, H = 64, 32
SUN = (-0.6, 0.64, -0.48)


def rgbe(r, g, b):
    m = max(r, g, b)
    if m < 1e-32:
        return bytes(4)
    e = math.frexp(m)[1]
    s = 256.0 / 2.0 ** e
    return bytes([int(r * s), int(g * s), int(b * s), e + 128])


def main():
    n = math.sqrt(sum(c * c for c in SUN))
    d = [c / n for c in SUN]
    u = (math.atan2(d[0], -d[2]) / (2 * math.pi)) % 1.0
    v = math.acos(d[1]) / math.pi
    si, sj = int(u * W), round(v * (H - 1))
    pixels = []
    for j in range(H):
        cos_theta = math.cos(math.pi * j / (H - 1))
        for i in range(W):
            if cos_theta > 0:
                t = 1.0 - cos_theta
                rgb = [0.15 + 0.35 * t, 0.25 + 0.35 * t, 0.55 + 0.25 * t]
            else:
                rgb = [0.08, 0.07, 0.06]
            if (i, j) == (si, sj):
                rgb = [3000.0, 2800.0, 2500.0]
            elif abs(i - si) + abs(j - sj) == 1:
                rgb = [300.0, 280.0, 250.0]
            pixels.append(rgb)
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "sun-sky.hdr")
    with open(out, "wb") as f:
        f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n")
        f.write(f"-Y {H} +X {W}\n".encode())
        for rgb in pixels:
            f.write(rgbe(*rgb))
    print(f"wrote {out}: {W} x {H}, sun at pixel ({si}, {sj})")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Writes scenes/data/cloud.vol, the density grid of scenes/cloud.xml (issue 36), a cumulus.

A cumulus: a union of round puffs (a big central tower, smaller ones around it), a flat base
where the rising air condenses, the density rising from the edge inwards (soft where the puffs
meet the air, near 1 inside), the edge eroded by fractal value noise so that it billows.
Pure Python (no numpy), seeded and deterministic: running it again writes the same bytes.
Format: Mitsuba 3's `.vol` (docs/mitsuba-compat.md, "The .vol format"), 1 channel, cells x
fastest; the grid is the unit cube, y up, scaled to world space by the scene.

    python3 scripts/gen-cloud.py [OUT.vol] [--res X Y Z]

The many-light tests use a tiny one: `--res 8 6 8` (tests/data/sky-sun/cloud-small.vol).
"""
import math
import struct
import sys

SEED = 36

# Puffs as (centre x, y, z, radius) in the unit cube; the base is at y = BASE.
PUFFS = [
    (0.50, 0.42, 0.50, 0.26),
    (0.50, 0.62, 0.46, 0.20),
    (0.30, 0.34, 0.48, 0.18),
    (0.70, 0.33, 0.55, 0.19),
    (0.43, 0.32, 0.30, 0.16),
    (0.60, 0.30, 0.72, 0.16),
    (0.58, 0.74, 0.52, 0.13),
    (0.20, 0.26, 0.55, 0.11),
    (0.80, 0.27, 0.40, 0.12),
]
BASE = 0.17


def lattice(ix, iy, iz, octave):
    """A pseudo-random value in [0, 1) for an integer lattice point (an integer hash)."""
    h = (ix * 73856093) ^ (iy * 19349663) ^ (iz * 83492791) ^ (octave * 2654435761) ^ SEED
    h &= 0xFFFFFFFF
    h ^= h >> 16
    h = (h * 0x45D9F3B) & 0xFFFFFFFF
    h ^= h >> 16
    h = (h * 0x45D9F3B) & 0xFFFFFFFF
    h ^= h >> 16
    return h / 4294967296.0


def smooth(t):
    return t * t * (3.0 - 2.0 * t)


def value_noise(x, y, z, octave):
    ix, iy, iz = math.floor(x), math.floor(y), math.floor(z)
    fx, fy, fz = smooth(x - ix), smooth(y - iy), smooth(z - iz)
    acc = 0.0
    for dz in (0, 1):
        for dy in (0, 1):
            for dx in (0, 1):
                w = (fx if dx else 1 - fx) * (fy if dy else 1 - fy) * (fz if dz else 1 - fz)
                acc += w * lattice(ix + dx, iy + dy, iz + dz, octave)
    return acc


def fbm(x, y, z):
    total, amp, freq, norm = 0.0, 0.5, 5.0, 0.0
    for octave in range(4):
        total += amp * value_noise(x * freq, y * freq, z * freq, octave)
        norm += amp
        amp *= 0.5
        freq *= 2.0
    return total / norm


def density(u, v, w):
    """Density at local (u, v, w) in the unit cube; v is up. In [0, 1]."""
    if v < BASE:
        return 0.0
    # Signed distance to the union of puffs, in units of the nearest puff's radius: < 0 inside.
    sd = min(math.sqrt((u - x) ** 2 + (v - y) ** 2 + (w - z) ** 2) / r - 1.0 for x, y, z, r in PUFFS)
    # Billows: the noise pushes the surface in and out by up to a third of a radius.
    n = fbm(u, v, w)
    sd += 0.7 * (n - 0.5)
    if sd >= 0.0:
        return 0.0
    # Soft edge over 0.3 radii, then full density; the base fades in over 2% of the height.
    core = min(1.0, -sd / 0.3)
    base = min(1.0, (v - BASE) / 0.02)
    return core * base * (0.75 + 0.25 * n)


def main():
    args = sys.argv[1:]
    res = (48, 36, 48)
    if "--res" in args:
        i = args.index("--res")
        res = tuple(int(a) for a in args[i + 1:i + 4])
        del args[i:i + 4]
    out = args[0] if args else "scenes/data/cloud.vol"
    rx, ry, rz = res
    data = bytearray()
    data += b"VOL" + bytes([3])
    data += struct.pack("<iiiii", 1, rx, ry, rz, 1)
    data += struct.pack("<6f", 0.0, 0.0, 0.0, 1.0, 1.0, 1.0)
    values = []
    for z in range(rz):
        for y in range(ry):
            for x in range(rx):
                values.append(density((x + 0.5) / rx, (y + 0.5) / ry, (z + 0.5) / rz))
    data += struct.pack("<%df" % len(values), *values)
    with open(out, "wb") as f:
        f.write(data)
    occupied = sum(1 for v in values if v > 0.0) / len(values)
    print(f"wrote {out}: {rx} x {ry} x {rz} cells, max {max(values):.3f}, {occupied:.0%} non-zero")


if __name__ == "__main__":
    main()

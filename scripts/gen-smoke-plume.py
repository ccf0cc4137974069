#!/usr/bin/env python3
"""Writes scenes/data/smoke-plume.vol, the density grid of scenes/smoke-plume.xml (issue 15).

A rising plume: a column whose radius grows with height, swaying sideways, its density a smooth
falloff from the axis times fractal value noise, fading out at the top. Pure Python (no numpy),
seeded and deterministic: running it again writes the same bytes. Format: Mitsuba 3's `.vol`
(docs/mitsuba-compat.md, "The .vol format"), 1 channel, cells x fastest.

    python3 scripts/gen-smoke-plume.py [OUT.vol] [--res X Y Z]
"""
import math
import struct
import sys

SEED = 15


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
    total, amp, freq, norm = 0.0, 0.5, 4.0, 0.0
    for octave in range(4):
        total += amp * value_noise(x * freq, y * freq, z * freq, octave)
        norm += amp
        amp *= 0.5
        freq *= 2.0
    return total / norm


def density(u, v, w):
    """Density at local (u, v, w) in the unit cube; v is up."""
    radius = 0.06 + 0.3 * v
    cx = 0.5 + 0.12 * math.sin(5.0 * v + 0.7) * v
    cz = 0.5 + 0.08 * math.cos(4.0 * v) * v
    # The noise is advected upwards a little faster than the column widens: curls.
    n = fbm(u + 0.3 * v, v * 0.8, w - 0.2 * v)
    d = math.hypot(u - cx, w - cz) / radius
    d += 0.6 * (n - 0.5)
    core = max(0.0, 1.0 - d) ** 1.5
    fade = min(1.0, v / 0.05) * max(0.0, 1.0 - max(0.0, v - 0.7) / 0.3)
    return core * fade * (0.35 + 0.65 * n) * 2.0


def main():
    args = sys.argv[1:]
    res = (32, 48, 32)
    if "--res" in args:
        i = args.index("--res")
        res = tuple(int(a) for a in args[i + 1:i + 4])
        del args[i:i + 4]
    out = args[0] if args else "scenes/data/smoke-plume.vol"
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

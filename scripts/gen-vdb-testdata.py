#!/usr/bin/python3
"""Writes tests/data/vdb/: one small float grid as an OpenVDB `.vdb` file and as a Mitsuba 3 `.vol`
file describing the same medium, the same grid saved as half floats, plus the bad `.vdb` files
of the error tests (issue 15).

The `.vdb` files are written by pyopenvdb (Debian's `python3-openvdb`, OpenVDB 10; run with
/usr/bin/python3), an independent OpenVDB writer; the `.vol` file by the few lines of struct
packing below (docs/mitsuba-compat.md, "The .vol format"). Deterministic: running it again
writes the same grids (the `.vdb` files differ only in the random UUID OpenVDB writes into each
file header). The outputs are committed; CI does not run this script.

    apt-get install -y python3-openvdb
    /usr/bin/python3 scripts/gen-vdb-testdata.py [OUT_DIR]

How the two files describe the same medium (the rule of docs/openvdb.md): OpenVDB puts the
centre of voxel (i, j, k) at world `translation + voxel_size * (i, j, k)`, and haze reads a `.vdb`
grid as the box of its active voxels padded by one voxel of background (0) on every side, cell
centres at the voxel centres. So the `.vol` holds the same values with a ring of zero cells
around them, and its bounding box (the header's, used with `use_grid_bbox`) is the padded box
in world units. Every number here is a multiple of a power of two, so both routes compute the
same float32 transform bit for bit.
"""
import math
import os
import struct
import sys

import numpy as np
import pyopenvdb as vdb

# The grid: 8 x 6 x 5 voxels from index (-3, 2, 1), voxel size 1/4, translated; x fastest in
# the .vol, numpy's first axis is OpenVDB's i (x).
RES = (8, 6, 5)
ORIGIN = (-3, 2, 1)
VOXEL = 0.25
TRANSLATION = (-1.0, 0.5, -0.75)


def density():
    """Smooth values in (0.1, 1.3) with a zero block (x < 3, y < 2, all z) that leaves the
    active bounding box the full 8 x 6 x 5 (the other corners stay non-zero)."""
    a = np.zeros(RES, dtype=np.float32)
    for i in range(RES[0]):
        for j in range(RES[1]):
            for k in range(RES[2]):
                if i < 3 and j < 2:
                    continue
                a[i, j, k] = 0.7 + 0.4 * math.sin(0.9 * i + 0.3) * math.cos(0.7 * j) + 0.1 * k
    return a


def transform():
    """OpenVDB's linear transform (row vectors: the translation is the last row)."""
    m = [[VOXEL, 0, 0, 0], [0, VOXEL, 0, 0], [0, 0, VOXEL, 0], list(TRANSLATION) + [1]]
    return vdb.createLinearTransform(m)


def float_grid(a, name="density"):
    g = vdb.FloatGrid()  # background 0
    g.copyFromArray(a, ijk=ORIGIN, tolerance=0)  # values equal to 0 stay inactive background
    g.name = name
    g.transform = transform()
    return g


def write_vol(path, a):
    """Mitsuba 3 .vol: the grid padded by one zero cell per side; bbox = the padded box."""
    padded = np.zeros(tuple(n + 2 for n in RES), dtype=np.float32)
    padded[1:-1, 1:-1, 1:-1] = a
    lo = [TRANSLATION[c] + VOXEL * (ORIGIN[c] - 1.5) for c in range(3)]
    hi = [lo[c] + VOXEL * (RES[c] + 2) for c in range(3)]
    header = b"VOL" + bytes([3]) + struct.pack("<iiiii", 1, *padded.shape, 1) + struct.pack("<6f", *lo, *hi)
    # .vol order: x fastest, then y, then z; numpy's C order has the last axis fastest.
    body = padded.transpose(2, 1, 0).astype("<f4").tobytes()
    with open(path, "wb") as f:
        f.write(header + body)
    return lo, hi


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "tests", "data", "vdb")
    os.makedirs(out, exist_ok=True)
    a = density()
    # The medium, as a .vdb (a float grid 'density' beside a vector grid 'velocity', as smoke
    # caches have) and as a .vol.
    vel = vdb.Vec3SGrid()
    vel.copyFromArray(np.ones(RES + (3,), dtype=np.float32), ijk=ORIGIN)
    vel.name = "velocity"
    vel.transform = transform()
    vdb.write(os.path.join(out, "smoke.vdb"), grids=[float_grid(a), vel])
    lo, hi = write_vol(os.path.join(out, "smoke.vol"), a)
    # The negative control: one voxel changed.
    b = a.copy()
    b[5, 3, 2] += 0.25
    vdb.write(os.path.join(out, "smoke-changed.vdb"), grids=[float_grid(b)])
    # Bad values: one negative, one NaN.
    neg = a.copy()
    neg[4, 2, 3] = -0.5
    vdb.write(os.path.join(out, "negative.vdb"), grids=[float_grid(neg)])
    # (copyFromArray drops a NaN as equal to the background within the tolerance: set it.)
    nan = float_grid(a)
    nan.getAccessor().setValueOn((ORIGIN[0] + 6, ORIGIN[1] + 1, ORIGIN[2] + 0), float("nan"))
    vdb.write(os.path.join(out, "nan.vdb"), grids=[nan])
    # A rotated grid: an AffineMap transform, which haze (through vdb-rs) does not read.
    rot = float_grid(a)
    c, s = math.cos(0.5), math.sin(0.5)
    rot.transform = vdb.createLinearTransform([[c * VOXEL, s * VOXEL, 0, 0], [-s * VOXEL, c * VOXEL, 0, 0], [0, 0, VOXEL, 0], [0, 0, 0, 1]])
    vdb.write(os.path.join(out, "rotated.vdb"), grids=[rot])
    # A level set (signed distance, background = the narrow band's width): not a fog volume.
    sphere = vdb.createLevelSetSphere(0.5, (1.0, 1.0, 1.0), 0.25, 1.5)
    sphere.name = "density"
    vdb.write(os.path.join(out, "levelset.vdb"), grids=[sphere])
    # Non-uniform voxels (a ScaleTranslateMap): (1/4, 1/2, 1/8), translated by (1, 2, 3).
    scaled = float_grid(a)
    scaled.transform = vdb.createLinearTransform([[0.25, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 0.125, 0], [1, 2, 3, 1]])
    vdb.write(os.path.join(out, "scaled.vdb"), grids=[scaled])
    # Saved as 16-bit half floats (a `Tree_float_5_4_3_HalfFloat` grid, Blender's and Houdini's
    # default export), with a leaf whose voxels are all inactive background (set on, then off
    # with the background 0: the leaf stays). OpenVDB stores no values and no length for such a
    # leaf's empty array of half values, nor for the internal nodes without active tiles: the
    # case vdb-rs 0.6.0 misread (vendor/vdb-rs/PATCHES.md). The leaf, voxels (-16..-9, 0..7,
    # 0..7), comes before the grid's leaf (-8..-1, 0..7, 0..7) in the file.
    half = float_grid(a)
    half.saveFloatAsHalf = True
    acc = half.getAccessor()
    acc.setValueOn((-12, 3, 2), 1.0)
    acc.setValueOff((-12, 3, 2), 0.0)
    assert half.leafCount() == 3 and half.activeVoxelCount() == float_grid(a).activeVoxelCount()
    vdb.write(os.path.join(out, "half.vdb"), grids=[half])
    # A sparse grid too large to densify: two voxels 4000 apart (4003^3 cells with the padding).
    sparse = vdb.FloatGrid()
    sparse.getAccessor().setValueOn((0, 0, 0), 1.0)
    sparse.getAccessor().setValueOn((4000, 4000, 4000), 1.0)
    sparse.name = "density"
    vdb.write(os.path.join(out, "sparse.vdb"), grids=[sparse])
    # An inactive voxel holding a non-zero value (not a fog volume's background).
    inactive = float_grid(a)
    inactive.getAccessor().setValueOff((ORIGIN[0] + 1, ORIGIN[1] + 0, ORIGIN[2] + 2), 0.3)
    vdb.write(os.path.join(out, "inactive.vdb"), grids=[inactive])
    # Active tiles: a 16^3 block filled at once is stored as eight 8^3 tiles (no voxels),
    # beside one voxel; voxel size 1, no translation (a UniformScaleMap).
    tiles = vdb.FloatGrid()
    tiles.fill((0, 0, 0), (15, 15, 15), 0.5, active=True)
    tiles.getAccessor().setValueOn((20, 3, 3), 1.0)
    tiles.name = "density"
    vdb.write(os.path.join(out, "tiles.vdb"), grids=[tiles])
    print(f"wrote {out}: smoke.vol box {lo} - {hi}")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""RMSE of the images scripts/results.sh wrote, with and without the 0.1% largest squared
errors (docs/results.md, findings): a reference with fireflies (a volpath render of a spot beam)
gives every method the same error floor on a few pixels, which hides the differences elsewhere.

Usage: trimmed-rmse.py [OUT_DIR]   (default target/results; needs numpy and the haze package,
as in the repo's .venv after scripts/test.sh). Prints, per scene and method, the RMSE of each
seed and the trimmed RMSE.
"""
import glob
import os
import sys

import numpy as np

import haze

OUT = sys.argv[1] if len(sys.argv) > 1 else "target/results"
REFS = {
    "validation-hg-box": "tests/data/validation/refs/hg-box.exr",
    "validation-foggy-room": "tests/data/validation/refs/foggy-room.exr",
}

for scene_dir in sorted(glob.glob(os.path.join(OUT, "*", "images-0")) + glob.glob(os.path.join(OUT, "wide", "*", "images-0"))):
    scene_dir = os.path.dirname(scene_dir)
    name = os.path.relpath(scene_dir, OUT)
    ref_path = REFS.get(name, os.path.join(scene_dir, "reference.exr"))
    ref = haze.read_exr(ref_path).astype(np.float64)
    print(f"{name} (reference {ref_path})")
    for image in sorted(glob.glob(os.path.join(scene_dir, "images-0", "*.exr"))):
        method = os.path.basename(image)[:-4]
        full, trimmed = [], []
        for seed_dir in sorted(glob.glob(os.path.join(scene_dir, "images-*"))):
            path = os.path.join(seed_dir, method + ".exr")
            if not os.path.exists(path):
                continue
            sq = np.sort(((haze.read_exr(path).astype(np.float64) - ref) ** 2).ravel())
            full.append(np.sqrt(sq.mean()))
            trimmed.append(np.sqrt(sq[: sq.size - max(1, sq.size // 1000)].mean()))
        print(f"  {method:32s} RMSE {' '.join(f'{v:.4f}' for v in full)}   trimmed {' '.join(f'{v:.4f}' for v in trimmed)}")

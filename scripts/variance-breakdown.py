#!/usr/bin/env python3
"""Where the many-light methods' error comes from (docs/results.md, "Where the variance comes from").

For each scene and method, two independent renders (seeds 1 and 2) with `--components` and one
sample per pixel per pass (so every sample has its own light set and the per-sample variance is
the whole variance); the variance of a render's mean is estimated per component from the two
images, V = mean over pixels and channels of (a - b)^2 / 2, and normalised by the render's
wall-clock time: V * t is the variance one second of that method would have (the MSE at equal
time, up to bias). Sources of the many-light `multiple` component:
  - light set and joint sampling: brute-force `vrl` (every light of the pass evaluated);
  - light selection: the stochastic cut minus brute force at the same light count (same light
    sets in distribution, same estimator per light: the difference is the descent's choice);
and of the whole image: `emitted` (camera sampling of directly visible emitters) and `single`
(next-event estimation), which the methods share. Fireflies: the share of V carried by the
0.1% of pixels with the largest squared difference.

Usage: variance-breakdown.py [HAZE] [OUT_DIR]   (needs numpy and the haze package: the repo's
.venv after scripts/test.sh has both).
"""
import os
import re
import subprocess
import sys

import numpy as np

import haze

HAZE = sys.argv[1] if len(sys.argv) > 1 else "target/release/haze"
OUT = sys.argv[2] if len(sys.argv) > 2 else "target/results/variance"
SCENES = os.environ.get("SCENES", "smoke-room spot-beam fog-shadow").split()
RES = os.environ.get("RES", "128")
# (label, haze render arguments, spp): brute force is slow per sample, so it gets fewer.
METHODS = [
    ("volpath", ["--integrator", "volpath"], 256),
    ("vrl:1000 (brute force)", ["--integrator", "vrl", "--vrls", "1000"], 16),
    ("vrl_lightcuts:1000 k=1", ["--integrator", "vrl_lightcuts", "--vrls", "1000"], 256),
    ("vrl_lightcuts:1000 k=16", ["--integrator", "vrl_lightcuts", "--vrls", "1000", "--cut-size", "16"], 64),
]
COMPONENTS = ["emitted", "single", "multiple", "surface"]


def render(scene, args, spp, seed, path):
    cmd = [HAZE, "render", scene, "-D", f"res={RES}", "-D", f"res_y={RES}", "--components",
           "--spp", str(spp), "--spp-per-pass", "1", "--seed", str(seed), "-o", path, *args]
    err = subprocess.run(cmd, capture_output=True, text=True, check=True).stderr
    secs = float(re.search(r" in ([0-9.]+) s \(", err).group(1))
    return secs


def main():
    print(f"| scene | method | s per render | V*t total | emitted | single | multiple | surface | fireflies (top 0.1% px) |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for s in SCENES:
        scene = f"scenes/bench-{s}.xml"
        mult = {}
        for label, args, spp in METHODS:
            d = os.path.join(OUT, s, re.sub(r"[^a-z0-9]+", "-", label.lower()))
            os.makedirs(d, exist_ok=True)
            t = [render(scene, args, spp, seed, os.path.join(d, f"seed{seed}.exr")) for seed in (1, 2)]
            secs = sum(t) / 2
            row = {}
            for c in [None, *COMPONENTS]:
                suffix = f"_{c}" if c else ""
                a, b = (haze.read_exr(os.path.join(d, f"seed{seed}{suffix}.exr")).astype(np.float64) for seed in (1, 2))
                sq = (a - b) ** 2 / 2
                row[c] = (sq.mean() * secs, sq)
            total, sq = row[None]
            per_pixel = sq.sum(axis=2).ravel()
            top = np.sort(per_pixel)[-max(1, per_pixel.size // 1000):].sum() / max(per_pixel.sum(), 1e-300)
            mult[label] = row["multiple"][0]
            cells = " | ".join(f"{row[c][0]:.3g}" for c in COMPONENTS)
            print(f"| {s} | {label} | {secs:.2f} | {total:.3g} | {cells} | {100 * top:.1f}% |")
        brute, k1 = mult["vrl:1000 (brute force)"], mult["vrl_lightcuts:1000 k=1"]
        print(f"| {s} | multiple: light selection (k=1 minus brute force, per second) | | | | | {k1 - brute:.3g} | | |")
        sys.stdout.flush()


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Splits a method's error against a reference into bias and noise (scripts/results.sh).

Usage: bias-noise.py REFERENCE.exr SEED0.exr SEED1.exr ...   (the same method, one image per seed)

With n seeds x_s, their per-pixel mean m and sample variance s^2 (both per channel):
  total  = sqrt(mean_s MSE(x_s, r))                      the RMSE of one render (quadratic mean)
  noise  = sqrt(mean(s^2))                               the RMSE one render has around its mean
  bias   = sqrt(max(0, mean((m - r)^2 - s^2 / n)))       the RMSE of the mean, noise removed
so total^2 ~ bias^2 + noise^2. The reference's own noise counts as bias here (it is the same for
every seed), and with 3 seeds of a heavy-tailed method the split is rough. A sharper measure of a
bias that has a sign (light a method cannot find) is the image mean: the relative difference of
the seeds' mean image mean to the reference's, with its standard error over the seeds.
Needs numpy and OpenEXR (`pip install numpy OpenEXR`).
"""
import sys

import numpy as np
import OpenEXR


def load(path):
    with OpenEXR.File(path) as f:
        ch = f.channels()
        if "RGB" in ch:
            return np.asarray(ch["RGB"].pixels, dtype=np.float64)
        return np.stack([np.asarray(ch[c].pixels, dtype=np.float64) for c in "RGB"], -1)


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    ref = load(sys.argv[1])
    xs = np.stack([load(p) for p in sys.argv[2:]])
    n = len(xs)
    total = np.sqrt(np.mean((xs - ref) ** 2))
    s2 = xs.var(axis=0, ddof=1)
    noise = np.sqrt(np.mean(s2))
    bias = np.sqrt(max(0.0, np.mean((xs.mean(axis=0) - ref) ** 2 - s2 / n)))
    means = xs.mean(axis=(1, 2, 3))
    rel = (means.mean() - ref.mean()) / ref.mean()
    se = means.std(ddof=1) / np.sqrt(n) / ref.mean()
    print(
        f"RMSE {total:.4g} = bias {bias:.4g} (+) noise {noise:.4g} ({n} seeds); "
        f"image mean {100 * rel:+.2f}% +- {100 * se:.2f}% of the reference's"
    )


if __name__ == "__main__":
    main()

"""Where a sampler's gain comes from (docs/results.md "Samplers"): the MSE of each component
(emitted, single, multiple scattering; `haze render --components`) at equal spp, summed over the
seeds, against the same components of a long render, per sampler, and independent / sampler.

  python scripts/samplers-components.py DIR SCENE [SEED...] [--median]
      DIR/ref/SCENE_<c>.exr           the reference's components (haze render --components)
      DIR/SCENE-<sampler>-<seed>_<c>.exr   the renders' (independent121: independent at 121 spp,
                                      orthogonal's count); samplers without renders are skipped

With --median (heavy-tailed scenes): the median over the seeds of each component's MSE instead of
the sum, and in brackets independent / sampler of the sums.

Needs numpy and mitsuba (to read the EXRs), e.g. /work/mi-venv/bin/python.
"""
import os
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")
COMPONENTS = ["emitted", "single", "multiple", "surface"]
SAMPLERS = ["independent", "stratified", "multijitter", "ldsampler", "independent121", "orthogonal"]


def exr(path):
    return np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]


def main(d, scene, seeds, median=False):
    ref = {c: exr(os.path.join(d, "ref", f"{scene}_{c}.exr")) for c in COMPONENTS}
    mse = {}
    samplers = [k for k in SAMPLERS if os.path.exists(os.path.join(d, f"{scene}-{k}-{seeds[0]}_{COMPONENTS[0]}.exr"))]
    for k in samplers:
        for c in COMPONENTS + ["total"]:
            per_seed = []
            for s in seeds:
                if c == "total":
                    img = sum(exr(os.path.join(d, f"{scene}-{k}-{s}_{x}.exr")) for x in COMPONENTS)
                    r = sum(ref.values())
                else:
                    img, r = exr(os.path.join(d, f"{scene}-{k}-{s}_{c}.exr")), ref[c]
                per_seed.append(float(np.mean((img - r) ** 2)))
            mse[k, c] = float(np.median(per_seed)) if median else sum(per_seed)
            mse[k, c, "sum"] = sum(per_seed)
    cols = [c for c in COMPONENTS if mse["independent", c] > 0] + ["total"]
    print(f"| {scene} | " + " | ".join(cols) + " |")
    print("|---|" + "---:|" * len(cols))
    for k in samplers:
        base = "independent121" if k == "orthogonal" else "independent"
        cells = []
        for c in cols:
            cell = f"{mse[k, c]:.3g}"
            if k not in ("independent", "independent121") and mse[k, c] > 0:
                cell += f" ({mse[base, c] / mse[k, c]:.2f}x"
                cell += f"; summed {mse[base, c, 'sum'] / mse[k, c, 'sum']:.2f}x)" if median else ")"
            cells.append(cell)
        print(f"| {k} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--median"]
    main(args[0], args[1], [int(s) for s in args[2:]] or [1, 2, 3], "--median" in sys.argv)

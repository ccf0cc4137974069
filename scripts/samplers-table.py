#!/usr/bin/env python3
"""Tables of docs/results.md "Samplers" from the runs of scripts/samplers.sh.

Usage: samplers-table.py OUT [SEED...]   (default seeds 1 2 3)
Needs numpy and mitsuba (to read the EXRs), e.g. /work/mi-venv/bin/python.

Reads OUT/<scene>/<method>-<seed>.md (the `haze compare` table) and .log (its spp per pass) and
prints one markdown row per scene, method and sampler: samples per pixel reached (median over the
seeds), the sampler's rate (samples per second) relative to independent's in the same compare
(median), RMSE per seed (from the images against the reference, in full precision: `haze
compare` prints 4 decimals, too few for vrl_lightcuts on spot-beam), MSE of independent / MSE per seed with its median, and the ratio of the
MSEs summed over the seeds. At equal time the MSE ratio is about (the ratio at equal spp) x rate.
"""
import os
import re
import statistics
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")

SCENES = ["smoke-room", "fog-shadow", "spot-beam", "hg-box", "foggy-room"]
METHODS = ["volpath", "vrl_lightcuts"]
SAMPLERS = ["independent", "stratified", "multijitter", "orthogonal", "ldsampler"]


def read(path):
    rows = {}
    with open(path) as f:
        lines = [l.strip() for l in f if l.strip().startswith("|")]
    head = [c.strip() for c in lines[0].strip("|").split("|")]
    for line in lines[2:]:
        cells = [c.strip() for c in line.strip("|").split("|")]
        row = dict(zip(head, cells))
        rows[row["method"].split("sampler=")[1]] = row
    return rows


def exr(path):
    return np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]


def reference(out, scene):
    if scene in ("hg-box", "foggy-room"):
        return exr(f"tests/data/validation/refs/{scene}.exr")
    return exr(os.path.join(out, "ref", f"bench-{scene}.exr"))


def spp_per_pass(log):
    with open(log) as f:
        m = re.search(r"spp per pass (\d+)", f.read())
    return int(m.group(1))


def main(out, seeds):
    print("| scene | method | sampler | spp, median | rate vs independent, median | RMSE (seeds " + ", ".join(seeds)
          + ") | MSE of independent / MSE, per seed (median) | summed over seeds |")
    print("|---|---|---|---:|---:|---|---|---:|")
    for scene in SCENES:
        for method in METHODS:
            runs = []
            for seed in seeds:
                base = os.path.join(out, scene, f"{method}-{seed}")
                if not os.path.exists(base + ".md"):
                    break
                runs.append((read(base + ".md"), spp_per_pass(base + ".log")))
            if len(runs) != len(seeds):
                continue
            ref = reference(out, scene)
            for (rows, _), seed in zip(runs, seeds):
                for k in SAMPLERS:
                    img = exr(os.path.join(out, scene, f"images-{method}-{seed}", f"{method}_sampler{k}.exr"))
                    rmse = float(np.sqrt(np.mean((img - ref) ** 2)))
                    assert abs(rmse - float(rows[k]["RMSE"])) <= 0.00005 + 1e-3 * rmse, (scene, method, k, rmse, rows[k])
                    rows[k]["RMSE"] = rmse
            for k in SAMPLERS:
                spp, rate, rmse, ratio = [], [], [], []
                for rows, n in runs:
                    r, i = rows[k], rows["independent"]
                    spp.append(int(r["passes"]) * n)
                    rate.append((int(r["passes"]) / float(r["time (s)"]))
                                / (int(i["passes"]) / float(i["time (s)"])))
                    rmse.append(r["RMSE"])
                    ratio.append(i["RMSE"] ** 2 / r["RMSE"] ** 2)
                summed = sum(rows["independent"]["RMSE"] ** 2 for rows, _ in runs) / sum(x * x for x in rmse)
                print(f"| {scene} | {method} | {k} | {statistics.median(spp):.0f} | {statistics.median(rate):.2f} | "
                      + ", ".join(f"{x:.3g}" for x in rmse) + " | "
                      + ", ".join(f"{x:.2f}" for x in ratio) + f" ({statistics.median(ratio):.2f}x) | {summed:.2f}x |")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:] or ["1", "2", "3"])

"""Mitsuba 3 side of docs/results.md "Samplers": renders a scene with each of Mitsuba 3's samplers
at the scene's sample_count (seeds given), and prints the MSE of each image against a reference.

  python scripts/samplers-mitsuba.py SCENE.xml REF.exr OUTDIR [--seeds 1 2 3] [-D name=value]...
      [--haze DIR] [--replace OLD NEW]...

The scene's <sampler type="independent"> is replaced by each sampler's type (its sample_count
kept; Mitsuba rounds it: orthogonal 64 -> 121). Renders with the scalar_rgb variant (all cores;
equal spp, so the time does not matter). With --haze DIR, the MSE of DIR/<sampler>-<seed>.exr
(haze renders at the same spp, made beforehand) against the same reference is printed beside.
MSE = mean over pixels and the three channels of (image - reference)^2.
"""
import argparse
import os
import time

import mitsuba as mi
import numpy as np

SAMPLERS = ["independent", "stratified", "multijitter", "orthogonal", "ldsampler"]

ap = argparse.ArgumentParser()
ap.add_argument("scene")
ap.add_argument("ref")
ap.add_argument("out")
ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
ap.add_argument("-D", action="append", default=[])
ap.add_argument("--haze")
ap.add_argument("--independent-spp", type=int, nargs="*", default=[121],
                help="also independent at these spp (orthogonal's 121 by default); haze images "
                "DIR/independent<spp>-<seed>.exr")
ap.add_argument("--variant", default="scalar_rgb")
ap.add_argument("--replace", nargs=2, action="append", default=[], metavar=("OLD", "NEW"),
                help="replace text in the scene for Mitsuba (e.g. an RGB sigma_t above 1 by a float)")
args = ap.parse_args()
mi.set_variant(args.variant)
mi.set_log_level(mi.LogLevel.Error)  # not the orthogonal sampler's rounding warning
defines = dict(d.split("=", 1) for d in args.D)
xml = open(args.scene).read()
for old, new in args.replace:
    assert old in xml, old
    xml = xml.replace(old, new)
assert '<sampler type="independent">' in xml, "the scene must have an independent sampler"
ref = np.array(mi.Bitmap(args.ref))[..., :3].astype(np.float64)
os.makedirs(args.out, exist_ok=True)
scene_dir = os.path.dirname(os.path.abspath(args.scene))


def mse(img):
    return float(np.mean((np.asarray(img, dtype=np.float64)[..., :3] - ref) ** 2))


sums = {}
print("| sampler | spp | seed | Mitsuba 3 MSE | haze MSE | Mitsuba s |")
print("|---|---:|---:|---:|---:|---:|")
runs = [(k, None) for k in SAMPLERS] + [("independent", n) for n in args.independent_spp]
for k, n in runs:
    text = xml.replace('<sampler type="independent">', f'<sampler type="{k}">')
    cwd = os.getcwd()
    os.chdir(scene_dir)  # relative file names in the scene
    try:
        scene = mi.load_string(text, **defines)
    finally:
        os.chdir(cwd)
    spp = n or scene.sensors()[0].sampler().sample_count()
    name = k + (str(n) if n else "")
    for s in args.seeds:
        t0 = time.time()
        img = np.array(mi.render(scene, seed=s, spp=n or 0))
        dt = time.time() - t0
        mi.Bitmap(img).write(os.path.join(args.out, f"mi-{name}-{s}.exr"))
        h, e = "", mse(img)
        if args.haze:
            eh = mse(np.array(mi.Bitmap(os.path.join(args.haze, f'{name}-{s}.exr'))))
            h = f"{eh:.6g}"
            sums.setdefault(name, [spp, 0.0, 0.0])[1] += eh
        sums.setdefault(name, [spp, 0.0, 0.0])[2] += e
        print(f"| {name} | {spp} | {s} | {e:.6g} | {h} | {dt:.1f} |", flush=True)

# Summed over the seeds; each sampler against independent at its own spp (orthogonal: 121).
print()
print("| sampler | spp | haze MSE (sum of seeds) | haze: independent / sampler | Mitsuba 3 MSE (sum of seeds) "
      "| Mitsuba 3: independent / sampler | haze / Mitsuba 3 |")
print("|---|---:|---:|---:|---:|---:|---:|")
for name, (spp, eh, e) in sums.items():
    base = "independent" if spp == sums["independent"][0] else f"independent{spp}"
    if base not in sums:
        base = "independent"
    bh, bm = sums[base][1], sums[base][2]
    rh = f"{bh / eh:.2f}x" if eh else ""
    print(f"| {name} | {spp} | {eh:.5f} | {rh} | {e:.5f} | {bm / e:.2f}x | {eh / e if eh else float('nan'):.2f} |")

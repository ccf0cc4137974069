"""Render a scene with two methods (VPLs and VRLs), compare them with a volpath reference, plot the errors.

    python python/examples/compare_methods.py [SCENE.xml] [-o compare.png]

Notebook style: each step is a few lines that work the same in a Jupyter cell. Needs numpy and
matplotlib (pip install matplotlib) besides haze.
"""

import argparse
import pathlib
import time

import matplotlib

matplotlib.use("Agg")  # write files; no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import haze  # noqa: E402

HERE = pathlib.Path(__file__).resolve()
DEFAULT_SCENE = HERE.parents[2] / "tests" / "data" / "validation" / "scenes" / "hg-box.xml"

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("scene", nargs="?", default=str(DEFAULT_SCENE))
parser.add_argument("-o", "--output", default="compare.png")
parser.add_argument("--reference-spp", type=int, default=128)
parser.add_argument("--spp", type=int, default=2)
parser.add_argument("--vrls", type=int, default=500)
args = parser.parse_args()

# 1. Load the scene and render a reference with the volumetric path tracer.
scene = haze.load_scene(args.scene)
t = time.monotonic()
reference = scene.render("volpath", spp=args.reference_spp, seed=100)
print(f"reference: volpath {args.reference_spp} spp in {time.monotonic() - t:.1f} s")

# 2. Render two methods at the same sample count.
methods = {}
for name in ("vpl", "vrl"):
    t = time.monotonic()
    methods[name] = scene.render(name, spp=args.spp, vrls=args.vrls)
    secs = time.monotonic() - t
    print(
        f"{name}: {args.spp} spp, light budget {args.vrls} VRLs per pass, {secs:.1f} s: "
        f"RMSE {haze.rmse(methods[name], reference):.4f}, "
        f"relMSE {haze.relmse(methods[name], reference):.4f}, "
        f"SMAPE {haze.smape(methods[name], reference):.2f} %"
    )

# 3. Plot: the images (tone-mapped by a gamma of 2.2) and each method's per-pixel error.
def show(image):
    return np.clip(image, 0, 1) ** (1 / 2.2)


fig, axes = plt.subplots(2, 3, figsize=(12, 6))
axes[0, 0].imshow(show(reference))
axes[0, 0].set_title("volpath reference")
errors = {name: np.abs(img - reference).mean(axis=2) for name, img in methods.items()}
vmax = max(e.max() for e in errors.values())
for i, (name, img) in enumerate(methods.items()):
    axes[0, i + 1].imshow(show(img))
    axes[0, i + 1].set_title(f"{name}, RMSE {haze.rmse(img, reference):.4f}")
    im = axes[1, i + 1].imshow(errors[name], cmap="magma", vmin=0, vmax=vmax)
    axes[1, i + 1].set_title(f"{name}: |error|")
    fig.colorbar(im, ax=axes[1, i + 1])
axes[1, 0].hist([e.ravel() for e in errors.values()], bins=40, label=list(errors), log=True)
axes[1, 0].set_title("per-pixel |error|")
axes[1, 0].legend()
for ax in (axes[0, 0], axes[0, 1], axes[0, 2], axes[1, 1], axes[1, 2]):
    ax.set_xticks([])
    ax.set_yticks([])
fig.tight_layout()
fig.savefig(args.output, dpi=100)
print(f"wrote {args.output}")

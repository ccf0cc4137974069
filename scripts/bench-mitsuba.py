#!/usr/bin/env python3
"""haze volpath against Mitsuba 3 on the same scenes and sample counts, interleaved.

    python3 scripts/bench-mitsuba.py [--haze target/release/haze] [--haze before=/tmp/haze-old ...]
        [--mitsuba-python /tmp/mi/bin/python] [--rounds 3] [--samples 4e6] [--threads 2] [SCENE ...]

For each scene and round it runs every haze binary, then Mitsuba 3, one after the other (A/B/A/B
in the same window, so machine load hits both alike), and prints per scene the median camera
samples per second of each, their ratio, and the min-max spread of the ratio over the rounds,
and the ratio of each renderer's fastest round (this machine runs the same code at two speeds
about 1.25x apart, docs/performance.md §1.3; the fastest rounds compare
the two renderers in the faster state, given enough rounds).
Samples per pixel: `--samples / (width * height)` (rounded up to a multiple of 4), the same for
both renderers. Times are each renderer's own render time (haze: the `in X s` of its report,
loading excluded; Mitsuba: `mi.render` of an already-compiled kernel, loading and JIT warm-up
excluded); CPU seconds (user + system, both threads) are printed too, since on a shared machine
they measure the work better than wall time.

Mitsuba 3 runs in a separate Python (default `/tmp/mi/bin/python`, variant `llvm_ad_rgb`; set
`DRJIT_LIBLLVM_PATH` if drjit does not find libLLVM). Without it the script prints haze's numbers
only and says so: nothing here is needed by CI. Scenes default to the validation scenes, the
three bench scenes and the homogeneous and heterogeneous Mitsuba 3 media test scenes in
../shared/peers.
"""
import argparse
import json
import os
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.path.join(ROOT, "..", "shared")
PEERS = os.path.join(SHARED, "peers", "mitsuba3-media-tests", "tests", "scenes", "participating_media")
DEFAULT_SCENES = (
    [os.path.join(SHARED, "validation", "scenes", f"{s}.xml") for s in ("hg-box", "foggy-room")]
    + [os.path.join(ROOT, "scenes", f"bench-{s}.xml") for s in ("fog-shadow", "smoke-room", "spot-beam")]
    + [
        os.path.join(PEERS, f"test_{s}.xml")
        for s in (
            "homo_area_light_volpath",
            "homo_dielectric_envmap_volpath",
            "homo_emitter_inside_medium_volpath",
            "homo_null_envmap_volpath",
            "homo_obj_inside_medium_volpath",
            "homo_roughdielectric_spot_volpath",
            "homo_spectral_sigmat_volpathmis",
            "surf_area_light_volpath",
            "hetero_sigmat_volpath",
            "hetero_sigmat_albedo_volpath",
            "hetero_spectral_sigmat_no_scattering_volpath",
            "hetero_spectral_sigmat_volpathmis",
        )
    ]
)

# The Mitsuba side: a server reading `scene spp seed` lines, answering one JSON line each.
MITSUBA_SERVER = r"""
import json, os, re, sys, time
import drjit as dr
import mitsuba as mi
mi.set_variant(sys.argv[1])
try:
    dr.set_thread_count(int(sys.argv[2]))
except Exception:
    pass
scenes = {}

def load(path):
    # optimize=False: Mitsuba 3.9's shape merging rejects some scenes (two cubes, one with
    # flipped normals, in bench-fog-shadow); it does not change the render.
    try:
        return mi.load_file(path, optimize=False)
    except Exception as e:
        if "Invalid RGB reflectance" not in str(e):
            raise
    # haze reads <rgb name="sigma_t"> above 1 as unbounded; Mitsuba's RGB variants want a
    # float (or a scale) there. Grey ones become floats, the same medium.
    def grey(m):
        v = [x.strip() for x in m.group(2).split(",")]
        return f'<float name="{m.group(1)}" value="{v[0]}"/>' if len(set(v)) == 1 else m.group(0)
    xml = re.sub(r'<rgb name="(sigma_t)" value="([^"]*)"\s*/>', grey, open(path).read())
    mi.Thread.thread().file_resolver().prepend(os.path.dirname(os.path.abspath(path)))
    return mi.load_string(xml, optimize=False)

print(json.dumps({"ready": mi.__version__}), flush=True)
for line in sys.stdin:
    path, spp, seed = line.split()
    spp, seed = int(spp), int(seed)
    if path not in scenes:
        try:
            scene = load(path)
            mi.render(scene, spp=spp, seed=seed + 1000).numpy()  # compile the kernel
        except Exception as e:
            print(json.dumps({"error": str(e).splitlines()[0][:200]}), flush=True)
            continue
        scenes[path] = scene
    scene = scenes[path]
    w, h = scene.sensors()[0].film().crop_size()
    t0, c0 = time.perf_counter(), time.process_time()
    img = mi.render(scene, spp=spp, seed=seed).numpy()
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    print(json.dumps({"wall": wall, "cpu": cpu, "pixels": int(w) * int(h), "mean": float(img.mean())}), flush=True)
"""


def start_mitsuba(python, variant, threads):
    if not python or not os.path.exists(python):
        return None, f"no Mitsuba Python at {python}"
    env = dict(os.environ)
    if "DRJIT_LIBLLVM_PATH" not in env:
        for cand in ("/usr/lib/x86_64-linux-gnu/libLLVM-19.so", "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"):
            if os.path.exists(cand):
                env["DRJIT_LIBLLVM_PATH"] = cand
                break
    p = subprocess.Popen(
        [python, "-c", MITSUBA_SERVER, variant, str(threads)],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
    )
    line = p.stdout.readline()
    if not line:
        return None, "Mitsuba 3 did not start: " + p.stderr.read().strip().splitlines()[-1:][0:1].__str__()
    return p, "Mitsuba 3 " + json.loads(line)["ready"] + f" ({variant})"


def mitsuba_render(p, scene, spp, seed):
    p.stdin.write(f"{scene} {spp} {seed}\n")
    p.stdin.flush()
    line = p.stdout.readline()
    if not line:
        raise RuntimeError(f"Mitsuba failed on {scene}: {p.stderr.read()[-2000:]}")
    out = json.loads(line)
    if "error" in out:
        print(f"# Mitsuba could not render {os.path.basename(scene)}: {out['error']}", file=sys.stderr)
        return None
    return out


def haze_pixels(haze, scene):
    out = subprocess.run([haze, "render", "-q", "--spp", "1", "-o", os.devnull + ".exr", scene],
                         capture_output=True, text=True)
    m = re.search(r"(\d+)x(\d+) at", out.stdout + out.stderr)
    if not m:
        raise RuntimeError(f"haze failed on {scene}: {out.stderr[-2000:]}")
    return int(m.group(1)) * int(m.group(2))


def haze_render(haze, scene, spp, seed, threads, tmp):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = subprocess.run(
        [haze, "render", "-q", "--threads", str(threads), "--spp", str(spp), "--seed", str(seed),
         "-o", os.path.join(tmp, "haze.exr"), scene],
        capture_output=True, text=True,
    )
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    m = re.search(r"at (\d+) spp in ([0-9.]+) s", out.stdout + out.stderr)
    if out.returncode != 0 or not m:
        raise RuntimeError(f"haze failed on {scene}: {out.stderr[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall": float(m.group(2)), "cpu": cpu}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scenes", nargs="*")
    ap.add_argument("--haze", action="append", default=[],
                    help="haze binary, optionally LABEL=PATH (repeatable; default target/release/haze)")
    ap.add_argument("--mitsuba-python", default="/tmp/mi/bin/python")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--samples", type=float, default=4e6, help="camera samples per render")
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    hazes = []
    for h in args.haze or [os.path.join(ROOT, "target", "release", "haze")]:
        label, _, path = h.rpartition("=")
        hazes.append((label or "haze", path))
    scenes = args.scenes or DEFAULT_SCENES
    mi, status = start_mitsuba(args.mitsuba_python, args.variant, args.threads)
    load = open("/proc/loadavg").read().split()[:3] if os.path.exists("/proc/loadavg") else ["?"] * 3
    print(f"# {status}; {args.threads} threads; {args.rounds} rounds; load average at start {' '.join(load)}")
    cols = [label for label, _ in hazes] + (["mitsuba"] if mi else [])
    head = "| scene | pixels | spp | " + " | ".join(f"{c} Msamples/s (CPU s)" for c in cols)
    if mi:
        head += " | " + " | ".join(f"{l}/Mitsuba (min-max) | {l}/Mitsuba, fastest rounds" for l, _ in hazes)
    print(head + " |")
    print("|" + "---|" * (3 + len(cols) + (2 * len(hazes) if mi else 0)))
    tmp = tempfile.mkdtemp()
    try:
        for scene in scenes:
            pixels = haze_pixels(hazes[0][1], scene)
            spp = max(4, int(-(-args.samples // (4 * pixels))) * 4)
            runs = {c: [] for c in cols}
            for r in range(args.rounds):
                for label, path in hazes:
                    runs[label].append(haze_render(path, scene, spp, r, args.threads, tmp))
                if mi:
                    m = mitsuba_render(mi, os.path.abspath(scene), spp, r)
                    if m is None:
                        break
                    runs["mitsuba"].append(m)
            have = [c for c in cols if runs[c]]
            rate = {c: [pixels * spp / x["wall"] * 1e-6 for x in runs[c]] for c in have}
            cells = [
                f"{statistics.median(rate[c]):.2f} ({statistics.median(x['cpu'] for x in runs[c]):.2f})"
                if c in have else "-"
                for c in cols
            ]
            if mi and "mitsuba" not in have:
                cells += ["-"] * (2 * len(hazes))
            elif mi:
                for label, _ in hazes:
                    ratios = [a / b for a, b in zip(rate[label], rate["mitsuba"])]
                    cells.append(f"**{statistics.median(ratios):.2f}** ({min(ratios):.2f}-{max(ratios):.2f})")
                    cells.append(f"{max(rate[label]) / max(rate['mitsuba']):.2f}")
            print(f"| {os.path.basename(scene)} | {pixels} | {spp} | " + " | ".join(cells) + " |", flush=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
        if mi:
            mi.stdin.close()
            mi.wait()
    load = open("/proc/loadavg").read().split()[:3] if os.path.exists("/proc/loadavg") else ["?"] * 3
    print(f"# load average at end {' '.join(load)}")


if __name__ == "__main__":
    sys.exit(main())

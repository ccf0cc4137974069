"""Rendering across a Ray cluster: independent passes as Ray tasks, merged exactly.

>>> from haze import distributed
>>> image = distributed.render("scene.xml", integrator="vrl_lightcuts", passes=64, address="auto")

Design (docs/python.md has the details):

- A render is ``passes`` passes of ``spp_per_pass`` samples; pass ``k`` of seed ``s`` is fully
  determined by ``(s, k)``: its camera samples, its light paths and its light tree. The passes
  are cut into aligned blocks (:func:`haze.pass_blocks`), one Ray task each.
- The scene file and every file it reads (includes, meshes, images) go through Ray's object
  store as one ``{relative path: bytes}`` bundle; a worker writes it into a temporary directory
  and loads the scene from there, so workers need no shared file system. A worker keeps the
  loaded scene for the next blocks of the same render.
- Each task returns its block's :class:`haze.Film` (sums and squared sums, summed over the
  block's subtree of the pass tree); the driver merges them with :func:`haze.merge_films`,
  which gives bit for bit what :meth:`haze.Scene.render_passes` computes on one machine for the
  same passes, whatever the number of workers or the block size.
- Tasks have ``max_retries``: a task lost with its worker is run again, and since a block is
  a pure function of the seed and its pass indices, the image is unchanged.

Run as a program: ``python -m haze.distributed SCENE.xml --address auto --passes 64 -o out.exr``.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import sys
import tempfile
import time
from typing import Callable

import haze
from haze import _haze

try:
    import ray
except ImportError as e:  # pragma: no cover - depends on the environment
    raise ImportError("haze.distributed needs Ray: pip install 'ray>=2.9'") from e

__all__ = ["render", "scene_bundle", "main"]


def scene_bundle(scene_path: str | os.PathLike, **defaults) -> tuple[dict[str, bytes], str]:
    """Loads the scene (checking it) and packs every file it reads.

    Returns ``(bundle, scene_name)``: ``bundle`` maps paths relative to the deepest directory
    holding all the files to their bytes, ``scene_name`` is the scene file's key in it.
    """
    scene = haze.load_scene(scene_path, **defaults)
    files = [os.path.abspath(f) for f in scene.files]
    root = os.path.commonpath([os.path.dirname(f) for f in files])
    bundle = {}
    for f in files:
        with open(f, "rb") as fh:
            bundle[os.path.relpath(f, root)] = fh.read()
    return bundle, os.path.relpath(files[0], root)


def _bundle_key(bundle: dict[str, bytes], defines: list[tuple[str, str]]) -> str:
    h = hashlib.sha256()
    for name in sorted(bundle):
        h.update(name.encode() + b"\0" + hashlib.sha256(bundle[name]).digest())
    h.update(repr(sorted(defines)).encode())
    return h.hexdigest()


# Scenes already loaded in this worker process, by bundle key (a worker runs many blocks).
_loaded: dict[str, haze.Scene] = {}


def _scene_from_bundle(key: str, bundle: dict[str, bytes], scene_name: str, defines) -> haze.Scene:
    scene = _loaded.get(key)
    if scene is None:
        with tempfile.TemporaryDirectory(prefix="haze-scene-") as tmp:
            for name, data in bundle.items():
                path = os.path.join(tmp, name)
                os.makedirs(os.path.dirname(path), exist_ok=True)
                with open(path, "wb") as fh:
                    fh.write(data)
            scene = haze.load_scene(os.path.join(tmp, scene_name), **dict(defines))
        _loaded.clear()  # keep one scene: a worker serves one render at a time
        _loaded[key] = scene
    return scene


def _render_block(key, bundle, scene_name, defines, options, first, end):
    """The Ray task: renders the passes ``first .. end`` into a Film."""
    pid_dir = os.environ.get("HAZE_TEST_PID_DIR")
    if pid_dir:  # for the test that kills a worker mid-render
        open(os.path.join(pid_dir, f"{os.getpid()}-{first}"), "w").close()
    scene = _scene_from_bundle(key, bundle, scene_name, defines)
    return scene.render_passes(first=first, count=end - first, **options)


def _progress(total: int, enabled: bool) -> Callable[[int], None]:
    """A per-pass progress display: tqdm if installed, else a printed counter."""
    if not enabled:
        return lambda n: None
    try:
        from tqdm import tqdm

        bar = tqdm(total=total, unit="pass", desc="haze")
        done = [0]

        def update(n: int) -> None:
            bar.update(n)
            done[0] += n
            if done[0] >= total:
                bar.close()

        return update
    except ImportError:
        state = {"done": 0, "start": time.monotonic()}

        def update(n: int) -> None:
            state["done"] += n
            secs = time.monotonic() - state["start"]
            end = "\n" if state["done"] >= total else ""
            print(f"\rhaze: {state['done']}/{total} passes, {secs:.1f} s", end=end, file=sys.stderr, flush=True)

        return update


def render(
    scene_path: str | os.PathLike,
    integrator: str | None = "vrl_lightcuts",
    passes: int = 16,
    spp_per_pass: int = 1,
    seed: int = 0,
    vrls: int | None = None,
    epsilon: float | None = None,
    components: bool = False,
    light_paths: int | None = None,
    defaults: dict | None = None,
    address: str | None = None,
    passes_per_task: int | None = None,
    first_pass: int = 0,
    max_retries: int = 3,
    progress: bool = True,
    return_film: bool = False,
):
    """Renders ``passes`` passes of the scene as Ray tasks and merges them exactly.

    The result equals, bit for bit, ``haze.load_scene(scene_path, **defaults).render_passes(
    integrator, first_pass, passes, spp_per_pass, seed, ...)``, whatever the cluster size.

    Args:
        scene_path: the scene file on the driver; it and every file it reads are shipped to
            the workers through the object store.
        integrator, spp_per_pass, seed, vrls, epsilon, components, light_paths: as in
            :meth:`haze.Scene.render`.
        passes: number of passes (``passes * spp_per_pass`` samples per pixel).
        defaults: ``<default>`` overrides of the scene (``-D name=value``).
        address: Ray cluster address (``"auto"`` for a running cluster); used only if Ray is
            not initialised yet (``None`` then starts a local one).
        passes_per_task: passes per task, rounded down to a power of two (default: about four
            tasks per CPU of the cluster). It does not change the image.
        first_pass: index of the first pass (to continue an earlier render).
        max_retries: how often Ray reruns a task whose worker died.
        progress: show a progress bar on the driver (tqdm if installed).
        return_film: return the merged :class:`haze.Film` instead of images.

    Returns:
        As :meth:`haze.Scene.render` (an (H, W, 3) float32 array, or a dict with components),
        or the :class:`haze.Film` with ``return_film=True``.
    """
    if passes < 1:
        raise ValueError(f"passes must be at least 1, got {passes}")
    defines = haze._defines(defaults or {})
    bundle, scene_name = scene_bundle(scene_path, **dict(defines))
    key = _bundle_key(bundle, defines)
    if not ray.is_initialized():
        ray.init(address=address, log_to_driver=False)
    if passes_per_task is None:
        cpus = max(1, int(ray.cluster_resources().get("CPU", 1)))
        passes_per_task = max(1, passes // (4 * cpus))
    blocks = _haze.pass_blocks(first_pass, passes, passes_per_task)
    options = dict(
        integrator=integrator,
        spp_per_pass=spp_per_pass,
        seed=seed,
        vrls=vrls,
        epsilon=epsilon,
        components=components,
        light_paths=light_paths,
    )
    task = ray.remote(max_retries=max_retries)(_render_block)
    bundle_ref = ray.put(bundle)
    pending = {
        task.remote(key, bundle_ref, scene_name, defines, options, lo, hi): (lo, hi) for lo, hi in blocks
    }
    update = _progress(passes, progress)
    done = []
    try:
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            for ref in ready:
                lo, hi = pending.pop(ref)
                done.append((lo, hi, ray.get(ref)))
                update(hi - lo)
    except BaseException:
        for ref in pending:
            ray.cancel(ref, force=True)
        raise
    film = haze.merge_films(first_pass, passes, done)
    if return_film:
        return film
    return haze._images(film, components)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m haze.distributed",
        description="Render a Mitsuba 3 scene with haze across a Ray cluster (exact merge of passes).",
    )
    p.add_argument("scene", help="scene file (Mitsuba 3 XML)")
    p.add_argument("-o", "--output", default="haze.exr", help="output EXR (a PNG preview is written next to it)")
    p.add_argument("--address", default=None, help="Ray cluster address ('auto' for a running cluster)")
    p.add_argument("--integrator", default="vrl_lightcuts")
    p.add_argument("--passes", type=int, default=16)
    p.add_argument("--spp-per-pass", type=int, default=1)
    p.add_argument("--passes-per-task", type=int, default=None)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--vrls", type=int, default=None)
    p.add_argument("--light-paths", type=int, default=None)
    p.add_argument("--epsilon", type=float, default=None)
    p.add_argument("--components", action="store_true", help="also write OUT_<component>.exr")
    p.add_argument("--exposure", type=float, default=0.0, help="exposure of the PNG preview in stops")
    p.add_argument("-D", dest="define", action="append", default=[], metavar="NAME=VALUE")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    args = p.parse_args(argv)
    defaults = {}
    for d in args.define:
        name, sep, value = d.partition("=")
        if not sep or not name:
            p.error(f"-D expects NAME=VALUE, got '{d}'")
        defaults[name] = value
    start = time.monotonic()
    try:
        out = render(
            args.scene,
            integrator=args.integrator,
            passes=args.passes,
            spp_per_pass=args.spp_per_pass,
            seed=args.seed,
            vrls=args.vrls,
            light_paths=args.light_paths,
            epsilon=args.epsilon,
            components=args.components,
            defaults=defaults,
            address=args.address,
            passes_per_task=args.passes_per_task,
            progress=not args.quiet,
        )
    except haze.SceneError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    image = out["image"] if args.components else out
    haze.write_exr(args.output, image)
    png = os.path.splitext(args.output)[0] + ".png"
    haze.write_png(png, image, args.exposure)
    print(
        f"{args.passes} passes x {args.spp_per_pass} spp in {time.monotonic() - start:.2f} s; "
        f"wrote {args.output} and {png}",
        file=sys.stderr,
    )
    if args.components:
        stem = os.path.splitext(args.output)[0]
        for c in haze.COMPONENTS:
            haze.write_exr(f"{stem}_{c}.exr", out[c])
    return 0


if __name__ == "__main__":
    sys.exit(main())

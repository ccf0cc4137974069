"""Rendering across a Ray cluster: independent passes as Ray tasks, merged exactly.

>>> from haze import distributed
>>> image = distributed.render("scene.xml", integrator="vrl_lightcuts", spp=64, address="auto")

Design (docs/python.md has the details):

- A render is passes of ``spp_per_pass`` samples (``spp / spp_per_pass`` of them, or as many as
  fit in ``time`` seconds); pass ``k`` of seed ``s`` is fully determined by ``(s, k)``: its
  camera samples, its light paths and its light tree. The passes are cut into aligned blocks
  (:func:`haze.pass_blocks`), one Ray task each.
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

Run as a program: ``python -m haze.distributed SCENE.xml --address auto --spp 64 -o out.exr``.
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
    return _bundle_of(haze.load_scene(scene_path, **defaults))


def _bundle_of(scene: haze.Scene) -> tuple[dict[str, bytes], str]:
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


def _render_block(key, bundle, scene_name, defines, integrator, options, first, end):
    """The Ray task: renders the passes ``first .. end`` into a Film."""
    pid_dir = os.environ.get("HAZE_TEST_PID_DIR")
    if pid_dir:  # for the test that kills a worker mid-render
        open(os.path.join(pid_dir, f"{os.getpid()}-{first}"), "w").close()
    scene = _scene_from_bundle(key, bundle, scene_name, defines)
    return scene.render_passes(integrator, first, end - first, **options)


def _progress(total: int | None, enabled: bool) -> Callable[..., None]:
    """A per-pass progress display: tqdm if installed, else a printed counter. ``total`` is
    None for a time budget; then ``update(0, final=True)`` ends the display."""
    if not enabled:
        return lambda n, final=False: None
    try:
        from tqdm import tqdm

        bar = tqdm(total=total, unit="pass", desc="haze")
        done = [0]

        def update(n: int, final: bool = False) -> None:
            bar.update(n)
            done[0] += n
            if final or (total is not None and done[0] >= total):
                bar.close()

        return update
    except ImportError:
        state = {"done": 0, "start": time.monotonic()}

        def update(n: int, final: bool = False) -> None:
            state["done"] += n
            secs = time.monotonic() - state["start"]
            last = final or (total is not None and state["done"] >= total)
            of = "" if total is None else f"/{total}"
            end = "\n" if last else ""
            print(f"\rhaze: {state['done']}{of} passes, {secs:.1f} s", end=end, file=sys.stderr, flush=True)

        return update


def render(
    scene_path: str | os.PathLike,
    integrator: str | None = "vrl_lightcuts",
    *,
    spp: int | None = None,
    time: float | None = None,
    seed: int = 0,
    spp_per_pass: int | None = None,
    components: bool = False,
    vrls: int | None = None,
    light_paths: int | None = None,
    caustic_paths: int | None = None,
    vpl_clamp: float | None = None,
    clamp: float | None = None,
    compensated_clamp: float | str | None = None,
    path_traced_media: str | None = None,
    cut: str | None = None,
    cut_size: int | None = None,
    light_samples: int | None = None,
    epsilon: float | None = None,
    max_cut: int | None = None,
    bound: str | None = None,
    builder: str | None = None,
    sampler: str | None = None,
    defaults: dict | None = None,
    address: str | None = None,
    passes_per_task: int | None = None,
    first_pass: int = 0,
    max_retries: int = 3,
    progress: bool = True,
    return_film: bool = False,
):
    """Renders the scene's passes as Ray tasks and merges them exactly.

    The budget is ``spp`` samples per pixel (default: the scene's ``sample_count``), that is
    ``spp / spp_per_pass`` passes (``spp`` must be a multiple of ``spp_per_pass``; by default
    the engine's auto value for the method, image size and budget,
    ``Scene.spp_per_pass_for(integrator, spp=spp)``), or ``time`` seconds. With ``spp`` the
    result equals, bit for bit, ``haze.load_scene(scene_path, **defaults).render_passes(integrator,
    first_pass, spp // spp_per_pass, spp_per_pass=spp_per_pass, ...)``, whatever the cluster
    size. With ``time`` the driver hands out blocks of passes in order (``first_pass``,
    then the next block, ...) to keep every worker busy while time remains, and stops handing
    them out at the deadline; the blocks already handed out are finished (so the render may
    overrun by about one block's time), and the result is the film of the ``N`` passes
    rendered, bit for bit ``render_passes(integrator, first_pass, N, ...)``: ``N`` depends on
    the speed of the cluster, the image for a given ``N`` does not. The clock starts when the
    first tasks are handed out (starting workers and loading the scene in them count against
    it). ``film.samples`` (``return_film=True``) is ``N * spp_per_pass``.

    Args:
        scene_path: the scene file on the driver; it and every file it reads are shipped to
            the workers through the object store.
        integrator, spp, time, seed, spp_per_pass, components, vrls, light_paths, caustic_paths, vpl_clamp,
            clamp, compensated_clamp, path_traced_media, cut, cut_size, light_samples, epsilon, max_cut, bound, builder, sampler: as in :meth:`haze.Scene.render` (the engine's
            options, :data:`haze.OPTIONS`).
        defaults: ``<default>`` overrides of the scene (``-D name=value``).
        address: Ray cluster address (``"auto"`` for a running cluster); used only if Ray is
            not initialised yet (``None`` then starts a local one).
        passes_per_task: passes per task, rounded down to a power of two (default: about four
            tasks per CPU of the cluster with ``spp``, 1 with ``time``). It does not change the
            image.
        first_pass: index of the first pass (to continue an earlier render).
        max_retries: how often Ray reruns a task whose worker died.
        progress: show a progress bar on the driver (tqdm if installed).
        return_film: return the merged :class:`haze.Film` instead of images.

    Returns:
        As :meth:`haze.Scene.render` (an (H, W, 3) float32 array, or a dict with components),
        or the :class:`haze.Film` with ``return_film=True``.

    Raises:
        ValueError: a bad option (checked on the driver before any task starts), or ``spp``
            not a multiple of ``spp_per_pass``.
    """
    given = haze._given(locals())
    defines = haze._defines(defaults or {})
    scene = haze.load_scene(scene_path, **dict(defines))
    # The engine checks every option on the driver, before any task starts.
    scene._inner.check_options(integrator, **given)
    # The engine's value (given, or its auto default for the method and image size), fixed
    # here so the driver's pass count and every worker's passes agree.
    spp_per_pass = scene._inner.spp_per_pass(integrator, **given)
    options = {k: v for k, v in given.items() if k not in ("spp", "time")}
    options["spp_per_pass"] = spp_per_pass
    bundle, scene_name = _bundle_of(scene)
    key = _bundle_key(bundle, defines)
    if not ray.is_initialized():
        ray.init(address=address, log_to_driver=False)
    cpus = max(1, int(ray.cluster_resources().get("CPU", 1)))
    task = ray.remote(max_retries=max_retries)(_render_block)
    bundle_ref = ray.put(bundle)

    def submit(lo: int, hi: int):
        return task.remote(key, bundle_ref, scene_name, defines, integrator, options, lo, hi)

    if time is None:
        spp = scene.spp if spp is None else spp
        if spp % spp_per_pass:
            raise ValueError(f"spp ({spp}) must be a multiple of spp_per_pass ({spp_per_pass})")
        passes = spp // spp_per_pass
        if passes_per_task is None:
            passes_per_task = max(1, passes // (4 * cpus))
        blocks = _haze.pass_blocks(first_pass, passes, passes_per_task)
        film = _run_blocks(blocks, submit, first_pass, passes, progress)
    else:
        film = _run_until(time, submit, first_pass, passes_per_task or 1, 2 * cpus, progress)
    if return_film:
        return film
    return haze._images(film, components)


def _run_blocks(blocks, submit, first: int, passes: int, progress: bool) -> haze.Film:
    """Renders the pass blocks ``blocks`` and merges them into the film of ``passes`` passes."""
    pending = {submit(lo, hi): (lo, hi) for lo, hi in blocks}
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
    return haze.merge_films(first, passes, done)


class _PrefixSum:
    """The film of the passes ``first .. end`` rendered so far, as pass-tree nodes.

    Blocks of ``block`` passes (a power of two) arrive in any order; those that extend the
    contiguous prefix are pushed on a stack of nodes whose sizes are decreasing powers of two
    (a binary counter), and two nodes of the same size are merged at once (the left one's
    start is aligned to twice their size, so they are the two halves of a node of the pass
    tree of any longer range). The stack is the right spine of the pass tree of the prefix, so
    the final merge gives ``render_passes`` of the prefix bit for bit, with O(log N) films held.
    """

    def __init__(self, first: int):
        self.first = first
        self.end = first
        self.waiting: dict[int, tuple[int, haze.Film]] = {}
        self.stack: list[tuple[int, int, haze.Film]] = []

    def add(self, lo: int, hi: int, film: haze.Film) -> None:
        self.waiting[lo] = (hi, film)
        while self.end in self.waiting:
            lo = self.end
            hi, film = self.waiting.pop(lo)
            self.stack.append((lo, hi, film))
            self.end = hi
            while len(self.stack) >= 2 and self.stack[-1][1] - self.stack[-1][0] == self.stack[-2][1] - self.stack[-2][0]:
                right, left = self.stack.pop(), self.stack.pop()
                merged = haze.merge_films(left[0], right[1] - left[0], [left, right])
                self.stack.append((left[0], right[1], merged))

    def film(self) -> haze.Film:
        if self.end == self.first:
            raise RuntimeError("no pass was rendered in time")
        return haze.merge_films(self.first, self.end - self.first, self.stack)


def _run_until(seconds: float, submit, first: int, block: int, in_flight: int, progress: bool) -> haze.Film:
    """Hands out blocks of ``block`` passes in order, at most ``in_flight`` at a time, until
    ``seconds`` have passed; finishes those handed out and merges the prefix of passes."""
    block = 1 << (max(1, block).bit_length() - 1)
    deadline = time.monotonic() + seconds
    prefix = _PrefixSum(first)
    pending = {}
    next_lo = first
    update = _progress(None, progress)
    try:
        while True:
            while len(pending) < in_flight and time.monotonic() < deadline:
                pending[submit(next_lo, next_lo + block)] = (next_lo, next_lo + block)
                next_lo += block
            if not pending:
                break
            left = deadline - time.monotonic()
            ready, _ = ray.wait(list(pending), num_returns=1, timeout=left if left > 0 else None)
            for ref in ready:
                lo, hi = pending.pop(ref)
                prefix.add(lo, hi, ray.get(ref))
                update(hi - lo)
    except BaseException:
        for ref in pending:
            ray.cancel(ref, force=True)
        raise
    update(0, final=True)
    return prefix.film()


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m haze.distributed",
        description="Render a Mitsuba 3 scene with haze across a Ray cluster (exact merge of passes).",
    )
    p.add_argument("scene", help="scene file (Mitsuba 3 XML)")
    p.add_argument("-o", "--output", default="haze.exr", help="output EXR (a PNG preview is written next to it)")
    p.add_argument("--address", default=None, help="Ray cluster address ('auto' for a running cluster)")
    p.add_argument("--integrator", default="vrl_lightcuts", help=f"one of {', '.join(haze.METHOD_NAMES)}")
    # The engine's options, as `haze render` has them; the engine checks the values.
    for o in haze.OPTIONS:
        if o["kind"] == "flag":
            p.add_argument(o["flag"], dest=o["name"], action="store_const", const=True, default=None, help=o["help"])
        else:
            kind = {"count": int, "integer": int, "number": float}.get(o["kind"], str)
            p.add_argument(o["flag"], dest=o["name"], type=kind, default=None, metavar="VALUE", help=o["help"])
    p.add_argument("--passes-per-task", type=int, default=None)
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
    options = {o["name"]: getattr(args, o["name"]) for o in haze.OPTIONS if getattr(args, o["name"]) is not None}
    start = time.monotonic()
    try:
        film = render(
            args.scene,
            integrator=args.integrator,
            defaults=defaults,
            address=args.address,
            passes_per_task=args.passes_per_task,
            progress=not args.quiet,
            return_film=True,
            **options,
        )
    except haze.SceneError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    image = film.mean()
    haze.write_exr(args.output, image)
    png = os.path.splitext(args.output)[0] + ".png"
    haze.write_png(png, image, args.exposure)
    print(
        f"{film.samples} spp in {time.monotonic() - start:.2f} s; wrote {args.output} and {png}",
        file=sys.stderr,
    )
    if film.has_components:
        stem = os.path.splitext(args.output)[0]
        for c in haze.COMPONENTS:
            haze.write_exr(f"{stem}_{c}.exr", film.mean(c))
    return 0


if __name__ == "__main__":
    sys.exit(main())

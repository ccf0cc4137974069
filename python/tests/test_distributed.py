"""haze.distributed on a local Ray cluster (2 CPUs): exact merging, agreement across seeds, and
a worker killed mid-render."""

import os
import signal
import threading
import time

import numpy as np
import pytest

import haze

ray = pytest.importorskip("ray", reason="haze.distributed needs Ray (python/requirements-dev.txt)")
from haze import distributed  # noqa: E402

# The paper's cut (nearly every light of a pass evaluated at this size): little light-selection
# noise, so the negative controls below (a 10% brighter image mean) are caught at 32 passes
# (with the stochastic cut of size 1 the image-mean z of that control was only 1.6).
OPTIONS = dict(integrator="vrl_lightcuts", spp_per_pass=1, vrls=300, cut="bound")


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    pid_dir = tmp_path_factory.mktemp("task-pids")
    # Workers inherit the driver's environment on a local cluster: tasks record their pid here.
    os.environ["HAZE_TEST_PID_DIR"] = str(pid_dir)
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield pid_dir
    ray.shutdown()
    del os.environ["HAZE_TEST_PID_DIR"]


def test_distributed_equals_single_process_bit_for_bit(cluster, small_box):
    passes = 6
    single = haze.load_scene(small_box).render_passes(first=0, count=passes, seed=5, **OPTIONS)
    for per_task in (1, 4):
        film = distributed.render(
            small_box, spp=passes, seed=5, passes_per_task=per_task, progress=False, return_film=True, **OPTIONS
        )
        assert film.samples == passes
        assert np.array_equal(film.sums(), single.sums()), f"blocks of {per_task} passes"
    image = distributed.render(small_box, spp=passes, seed=5, passes_per_task=2, progress=False, **OPTIONS)
    assert image.dtype == np.float32 and np.array_equal(image, single.mean())


def test_components_travel_too(cluster, small_box):
    out = distributed.render(small_box, spp=2, seed=1, components=True, progress=False, **OPTIONS)
    single = haze.load_scene(small_box).render_passes(first=0, count=2, seed=1, components=True, **OPTIONS)
    assert set(out) == {"image", *haze.COMPONENTS}
    for c in haze.COMPONENTS:
        assert np.array_equal(out[c], single.mean(c))


def test_other_seeds_agree_by_a_per_pixel_z_test(cluster, small_box):
    """Two independent renders (seeds 1 and 2) of the same expected image: per pixel and
    channel, z = (a - b) / sqrt(var_a + var_b) must stay within the Sidak-corrected bound for
    a family-wise 1% false alarm rate, and the image means must agree (a 4-sigma gate)."""
    from statistics import NormalDist

    passes = 32
    a = distributed.render(small_box, spp=passes, seed=1, progress=False, return_film=True, **OPTIONS)
    b = haze.load_scene(small_box).render_passes(first=0, count=passes, seed=2, **OPTIONS)
    var = a.variance_of_mean().astype(np.float64) + b.variance_of_mean()
    diff = a.mean().astype(np.float64) - b.mean()
    tested = var > 0
    assert tested.mean() > 0.3  # the black floor and the background have no variance
    z = np.abs(diff[tested]) / np.sqrt(var[tested])
    alpha = 1 - (1 - 0.01) ** (1 / tested.sum())
    bound = NormalDist().inv_cdf(1 - alpha / 2)
    assert z.max() < bound, f"max |z| {z.max():.2f} over {tested.sum()} tests (bound {bound:.2f})"
    # The image-mean gate: the pixels are independent, so the summed difference over its
    # standard deviation is a standard normal (bound 4: a false alarm rate of 6e-5).
    def mean_z(x, y):
        return abs((x - y)[tested].sum()) / np.sqrt(var[tested].sum())

    assert mean_z(a.mean(), b.mean()) < 4
    # Wrong images fail: 50% too bright per pixel, 10% too bright on the image mean.
    assert (np.abs(1.5 * a.mean() - b.mean())[tested] / np.sqrt(var[tested])).max() > bound
    assert mean_z(1.1 * a.mean(), b.mean()) > 4


def test_a_killed_worker_is_retried_and_the_image_is_exact(cluster, small_box):
    pid_dir = cluster
    for f in pid_dir.iterdir():
        f.unlink()
    passes, per_task = 8, 4
    result = {}

    def run():
        result["film"] = distributed.render(
            small_box, spp=passes, seed=9, passes_per_task=per_task, progress=False, return_film=True, **OPTIONS
        )

    driver = threading.Thread(target=run)
    driver.start()
    deadline = time.monotonic() + 120
    while not list(pid_dir.iterdir()):
        assert time.monotonic() < deadline, "no task started"
        time.sleep(0.01)
    victim = list(pid_dir.iterdir())[0]
    os.kill(int(victim.name.split("-")[0]), signal.SIGKILL)
    driver.join(timeout=300)
    assert "film" in result, "the render did not finish after a worker was killed"
    started = [f.name for f in pid_dir.iterdir()]
    block = victim.name.split("-")[1]
    assert len([s for s in started if s.endswith(f"-{block}")]) >= 2, f"block {block} was not retried: {started}"
    single = haze.load_scene(small_box).render_passes(first=0, count=passes, seed=9, **OPTIONS)
    assert np.array_equal(result["film"].sums(), single.sums())


def test_a_time_budget_renders_a_prefix_of_passes_exactly(cluster, small_box):
    """``time=``: blocks are handed out in order until the deadline; the film is that of the
    passes rendered, bit for bit the single-process render of as many passes."""
    start = time.monotonic()
    film = distributed.render(small_box, time=1.5, seed=4, progress=False, return_film=True, **OPTIONS)
    assert time.monotonic() - start < 60
    passes = film.samples
    assert passes >= 2, f"{passes} passes in 1.5 s"
    single = haze.load_scene(small_box).render_passes(first=0, count=passes, seed=4, **OPTIONS)
    assert np.array_equal(film.sums(), single.sums()), f"{passes} passes"
    # Blocks of 4 passes: the prefix is a whole number of blocks, merged over the same tree.
    film = distributed.render(
        small_box, time=1.0, seed=4, passes_per_task=4, progress=False, return_film=True, **OPTIONS
    )
    assert film.samples % 4 == 0 and film.samples >= 4
    single = haze.load_scene(small_box).render_passes(first=0, count=film.samples, seed=4, **OPTIONS)
    assert np.array_equal(film.sums(), single.sums())


def test_options_are_checked_on_the_driver(cluster, small_box):
    with pytest.raises(ValueError, match="max_cut does not apply to vrl"):
        distributed.render(small_box, "vrl", spp=1, max_cut=5, progress=False)
    with pytest.raises(ValueError, match="give either spp or time"):
        distributed.render(small_box, spp=1, time=1.0, progress=False, **OPTIONS)
    with pytest.raises(ValueError, match="multiple of spp_per_pass"):
        distributed.render(small_box, "volpath", spp=3, spp_per_pass=2, progress=False)


def test_the_command_line_takes_the_engines_options(cluster, small_box, tmp_path):
    out = tmp_path / "d.exr"
    args = [str(small_box), "-o", str(out), "--spp", "2", "--vrls", "300", "--cut", "bound", "--max-cut", "50"]
    assert distributed.main(args + ["--seed", "3", "-q"]) == 0
    # Auto spp per pass for 2 spp: one pass of 2 (the rule's 64 at 32x24, cut to a divisor of spp).
    scene = haze.load_scene(small_box)
    n = scene.spp_per_pass_for(spp=2)
    assert n == 2
    single = scene.render_passes(first=0, count=2 // n, seed=3, spp_per_pass=n, vrls=300, cut="bound", max_cut=50)
    assert np.array_equal(haze.read_exr(out), single.mean())
    assert distributed.main([str(small_box), "-o", str(out), "--integrator", "vrl", "--max-cut", "5", "-q"]) == 2

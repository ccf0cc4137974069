"""The Python API: loading, rendering, errors, virtual lights, images."""

import math
import os
import pathlib
import signal
import threading
import time

import numpy as np
import pytest

import haze
from conftest import REPO


def test_render_returns_float32_images(small_box):
    scene = haze.load_scene(small_box)
    assert (scene.width, scene.height, scene.spp, scene.integrator) == (32, 24, 64, "volpath")
    image = scene.render("volpath", spp=2)
    assert image.shape == (24, 32, 3) and image.dtype == np.float32
    assert np.isfinite(image).all() and image.mean() > 0
    lc = scene.render("vrl_lightcuts", spp=1, vrls=200)
    assert lc.shape == (24, 32, 3) and lc.dtype == np.float32 and lc.mean() > 0


def test_components_sum_to_the_image(small_box):
    scene = haze.load_scene(small_box)
    out = scene.render("volpath", spp=2, components=True)
    assert set(out) == {"image", *haze.COMPONENTS}
    for a in out.values():
        assert a.shape == (24, 32, 3) and a.dtype == np.float32
    total = sum(out[c].astype(np.float64) for c in haze.COMPONENTS)
    np.testing.assert_allclose(total, out["image"], rtol=1e-5, atol=1e-6)
    assert out["single"].mean() > 0 and out["multiple"].mean() > 0


def test_same_seed_same_image_and_passes_match_the_progressive_render(small_box):
    scene = haze.load_scene(small_box)
    a = scene.render("volpath", spp=4, seed=3)
    assert np.array_equal(a, scene.render("volpath", spp=4, seed=3))
    assert not np.array_equal(a, scene.render("volpath", spp=4, seed=4))
    # The same four passes, summed over the pass tree instead of sample by sample.
    film = scene.render_passes("volpath", first=0, count=4, seed=3)
    assert film.samples == 4
    np.testing.assert_allclose(film.mean(), a, rtol=1e-5, atol=1e-7)


def test_defaults_override_scene_parameters(tmp_path):
    path = tmp_path / "res.xml"
    path.write_text(
        """<scene version="3.0.0"><default name="res" value="8"/>
        <sensor type="perspective"><film type="hdrfilm">
        <integer name="width" value="$res"/><integer name="height" value="$res"/></film></sensor>
        <emitter type="constant"/></scene>"""
    )
    assert haze.load_scene(path).width == 8
    scene = haze.load_scene(path, res=4)
    assert (scene.width, scene.height) == (4, 4)
    assert scene.render("volpath", spp=1).shape == (4, 4, 3)


def test_scene_errors_name_the_file_line_and_element():
    bad = REPO / "tests" / "bad-scenes" / "bad-integer.xml"
    with pytest.raises(haze.SceneError) as info:
        haze.load_scene(bad)
    message = str(info.value)
    assert message.startswith(f"{bad}:3:5: ")
    for want in (bad.with_suffix(".expected")).read_text().splitlines():
        assert want in message
    assert (info.value.file, info.value.line, info.value.element) == (str(bad), 3, '<integer name="max_depth">')
    with pytest.raises(haze.SceneError, match="cannot read"):
        haze.load_scene(REPO / "no-such-scene.xml")


def test_bad_arguments_are_value_errors(small_box):
    scene = haze.load_scene(small_box)
    with pytest.raises(ValueError, match="unknown integrator 'nope'"):
        scene.render("nope", spp=1)
    with pytest.raises(ValueError, match="spp must be a positive integer"):
        scene.render("volpath", spp=0)
    with pytest.raises(ValueError, match="not both"):
        scene.render("volpath", spp=1, time=1.0)
    with pytest.raises(ValueError, match="unknown component"):
        scene.render_film("volpath", spp=1, components=True).mean("nope")
    with pytest.raises(ValueError, match="differ in shape"):
        haze.rmse(np.zeros((2, 2, 3)), np.zeros((2, 3, 3)))


def test_ctrl_c_interrupts_a_render(small_box):
    scene = haze.load_scene(small_box)
    # A process started in the background by a non-interactive shell (as CI may start the suite)
    # inherits SIGINT as ignored, and Python then installs no KeyboardInterrupt handler: install
    # Python's standard one for this test, as an interactive session has it.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
        start = time.monotonic()
        timer.start()
        with pytest.raises(KeyboardInterrupt):
            scene.render("volpath", time=60.0)
        assert time.monotonic() - start < 10
    finally:
        signal.signal(signal.SIGINT, previous)


POINT_IN_FOG = """<scene version="3.0.0">
  <sensor type="perspective"><transform name="to_world"><lookat origin="0,0,20" target="0,0,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
  <medium type="homogeneous" id="fog"><float name="sigma_t" value="0.5"/><rgb name="albedo" value="0.8, 0.6, 0.4"/></medium>
  <shape type="sphere"><float name="radius" value="5"/><bsdf type="null"/><ref name="interior" id="fog"/></shape>
  <emitter type="point"><point name="position" x="0.5" y="-0.25" z="1"/><rgb name="intensity" value="3, 2, 1"/></emitter>
  <emitter type="spot"><transform name="to_world"><lookat origin="0,1,0" target="0,0,0" up="0,0,1"/></transform>
    <rgb name="intensity" value="1, 1, 1"/><float name="cutoff_angle" value="30"/></emitter>
</scene>"""


def test_trace_lights_flux_sums_to_the_emitted_power(tmp_path):
    """Point light (power 4 pi I) and spot light inside a fog sphere: every light path starts with
    a VRL at its emitter whose flux is the path's share of the power, so the first segments'
    fluxes sum to each emitter's power (the spot's within noise: it is sampled by pdf)."""
    path = tmp_path / "point-in-fog.xml"
    path.write_text(POINT_IN_FOG)
    scene = haze.load_scene(path)
    n = 20000
    lights = haze.trace_lights(scene, n, seed=1)
    assert lights.paths == n
    vrls = lights.vrls
    assert vrls.dtype.names[:4] == ("start", "direction", "length", "flux")
    assert np.allclose(np.linalg.norm(vrls["direction"], axis=1), 1, atol=1e-5)
    assert (vrls["length"] > 0).all() and (vrls["medium"] == 0).all()
    point = np.array([0.5, -0.25, 1.0], np.float32)
    spot = np.array([0.0, 1.0, 0.0], np.float32)
    at_point = np.all(vrls["start"] == point, axis=1)
    at_spot = np.all(vrls["start"] == spot, axis=1)
    # Spot power: I * 2 pi (1 - cos(cutoff)) within the beam width, plus the linear falloff to
    # the cutoff; Mitsuba's default beam width is 3/4 of the cutoff (here 22.5 deg).
    theta = np.linspace(np.radians(22.5), np.radians(30), 20001)
    falloff = (np.radians(30) - theta) / (np.radians(30) - np.radians(22.5))
    spot_power = 2 * np.pi * (1 - np.cos(np.radians(22.5))) + 2 * np.pi * np.trapezoid(falloff * np.sin(theta), theta)
    point_power = 4 * np.pi * np.array([3.0, 2.0, 1.0])
    # Each path's first segment carries its own estimate of the total power (the point light's
    # exactly its power over its selection probability, the spot's by importance sampling);
    # per emitter, the sum of the n estimates is its power within noise (5 standard errors).
    assert at_point.sum() + at_spot.sum() == n  # one first segment per path
    for mask, power in ((at_point, point_power), (at_spot, spot_power)):
        x = np.where(mask[:, None], vrls["flux"], 0.0).astype(np.float64)
        got, se = x.sum(axis=0), np.sqrt(n) * x.std(axis=0)
        assert (np.abs(got - power) < 5 * se).all(), (got, power, se)
        assert (np.abs(got - power) < 0.05 * power).all(), (got, power)
    # VPLs: medium scattering vertices, with flux sigma_s-weighted (albedo < 1 darkens blue).
    assert len(lights.vpls) > 0 and (lights.vpls["flux"] >= 0).all()


def test_metrics_by_hand():
    a = np.array([[[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]]], np.float32)
    r = np.array([[[1.0, 1.0, 1.0], [0.0, 0.0, 1.0]]], np.float32)
    # squared errors: 0, 1, 4, 0, 0, 1 over 6 entries
    assert haze.rmse(a, r) == pytest.approx(math.sqrt(6 / 6))
    # |a-r|/(|a|+|r|): 0, 1/3, 2/4, (skip 0/0), (skip), 1/1 over 4 entries
    assert haze.smape(a, r) == pytest.approx(100 * (1 / 3 + 2 / 4 + 1) / 4)
    # (a-r)^2/(r^2+0.01)
    want = (1 / 1.01 + 4 / 1.01 + 1 / 1.01) / 6
    assert haze.relmse(a, r) == pytest.approx(want)
    assert haze.rmse(r, r) == 0


def test_exr_round_trip(tmp_path):
    image = np.random.default_rng(1).random((5, 7, 3), dtype=np.float32)
    haze.write_exr(tmp_path / "a.exr", image)
    assert np.array_equal(haze.read_exr(tmp_path / "a.exr"), image)
    haze.write_png(tmp_path / "a.png", image)
    assert (tmp_path / "a.png").stat().st_size > 0
    bad = image.copy()
    bad[0, 0, 0] = np.nan
    with pytest.raises(OSError):
        haze.write_exr(tmp_path / "b.exr", bad)


def test_files_lists_what_the_scene_reads(small_box):
    assert haze.load_scene(small_box).files == [str(small_box)]
    assert pathlib.Path(haze.load_scene(small_box).path) == small_box


def test_the_extension_is_built_for_any_x86_64():
    """The build this suite tests (maturin, with pyproject.toml's [tool.maturin] config, as a wheel
    or `pip install .` is) uses no instruction beyond x86-64-v1 outside the run-time-dispatched
    AVX2 node test, so it runs on every Ray worker (docs/performance.md §5.1)."""
    import platform

    if platform.machine().lower() not in ("x86_64", "amd64"):
        pytest.skip("the portable baseline is checked on x86-64 only")
    assert haze._haze.compiled_features() == [], (
        "the extension was compiled for a newer CPU than x86-64 (RUSTFLAGS set? pyproject.toml's "
        "[tool.maturin] config not applied?)"
    )

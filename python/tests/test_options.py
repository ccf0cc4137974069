"""The Python signatures against the engine's table of options (haze._haze.method_options(),
the table `haze render --help` and `haze compare` are made from): same names, same defaults,
and an option of another method is a ValueError naming both."""

import inspect
import re
import subprocess

import numpy as np

import pytest

import haze
from conftest import haze_binary, small_scene_text
from haze import _haze

TABLE = {o["name"]: o for o in _haze.method_options()}

#: Parameters of the Python functions that are not engine options (they are not on the command
#: line's list of options either: the scene, the pass range, the Ray cluster, the result type).
NOT_OPTIONS = {
    "self",
    "integrator",
    "first",
    "count",
    "scene_path",
    "defaults",
    "address",
    "passes_per_task",
    "first_pass",
    "max_retries",
    "progress",
    "return_film",
}


def expected_default(option):
    """Options of every method show their value; the others None (given only on purpose, as a
    command-line flag is)."""
    return option["python_default"]


def check_signature(function, skip=()):
    params = inspect.signature(function).parameters
    names = set(params) - NOT_OPTIONS
    want = set(TABLE) - set(skip)
    assert names == want, f"{function.__qualname__}: extra {names - want}, missing {want - names}"
    for name in want:
        p = params[name]
        assert p.kind == p.KEYWORD_ONLY, f"{function.__qualname__}: {name} is not keyword-only"
        assert p.default == expected_default(TABLE[name]), f"{function.__qualname__}: {name}={p.default!r}"
        assert type(p.default) is type(expected_default(TABLE[name])), name


def test_the_table_lists_every_command_line_option():
    assert list(TABLE) == [
        "spp", "time", "seed", "spp_per_pass", "components",
        "vrls", "light_paths", "caustic_paths", "vpl_clamp", "clamp", "compensated_clamp", "path_traced_media", "cut", "cut_size", "light_samples", "epsilon", "max_cut", "bound", "builder", "sampler",
    ]  # fmt: skip
    assert TABLE["vrls"]["default"] == "10000" and TABLE["epsilon"]["default"] == "0.02"
    assert TABLE["max_cut"]["methods"] == ["vrl_lightcuts", "vpl_lightcuts"]
    assert TABLE["cut"]["default"] == "stochastic" and TABLE["max_cut"]["requires"] == ("cut", "bound")
    assert TABLE["vpl_clamp"]["methods"] == ["vpl"]
    assert TABLE["seed"]["python_default"] == 0 and TABLE["components"]["python_default"] is False
    # spp_per_pass's default is auto (per method and image size): None in the signatures.
    spp_per_pass = TABLE["spp_per_pass"]
    assert spp_per_pass["python_default"] is None and spp_per_pass["default_doc"].startswith("auto: ")
    assert spp_per_pass["scope"] == "pass"
    assert haze.METHOD_NAMES == ("volpath", "vrl", "vpl", "vrl_lightcuts", "vpl_lightcuts")


def test_signatures_have_every_option_with_the_engine_defaults():
    check_signature(haze.Scene.render)
    check_signature(haze.Scene.render_film)
    check_signature(haze.Scene.render_passes, skip=("spp", "time"))
    # cut_sizes: one 1-spp pass of a lightcut method: the seed and the options of those methods.
    lightcuts = {"vrl_lightcuts", "vpl_lightcuts"}
    check_signature(
        haze.Scene.cut_sizes,
        skip=[n for n, o in TABLE.items() if n != "seed" and (o["scope"] != "method" or not lightcuts & set(o["methods"]))],
    )
    distributed = pytest.importorskip("haze.distributed", reason="haze.distributed needs Ray")
    check_signature(distributed.render)


def test_the_docstring_is_the_tables_help():
    doc = haze.Scene.render.__doc__
    for o in TABLE.values():
        assert f"{o['name']}: {o['help']}" in doc
        assert f"Default: {o['default_doc']}." in o["help"]


def test_every_option_is_used_or_rejected_naming_it_and_the_method(small_box):
    scene = haze.load_scene(small_box)
    for method in haze.METHOD_NAMES:
        for name, o in TABLE.items():
            value = {
                "count": int,
                "integer": int,
                "number": float,
                "number or word": float,
                "choice": str,
                "flag": lambda s: s == "true",
            }[o["kind"]](o["example"])
            if method in o["methods"]:
                given = {name: value}
                if o["requires"] is not None:
                    given[o["requires"][0]] = o["requires"][1]
                assert scene._inner.check_options(method, **given) == method
            else:
                with pytest.raises(ValueError, match=f"{name} does not apply to {method}"):
                    scene._inner.check_options(method, **{name: value})
    # Through the public API too, before any rendering.
    with pytest.raises(ValueError, match=r"vpl_clamp does not apply to vpl_lightcuts \(only to vpl\)"):
        scene.render("vpl_lightcuts", spp=1, vpl_clamp=2.0)
    with pytest.raises(ValueError, match="max_cut must be a positive integer"):
        scene.render("vrl_lightcuts", spp=1, cut="bound", max_cut=0)
    with pytest.raises(ValueError, match="bound must be 'paper', 'conservative' or 'tight', got 'foo'"):
        scene.render("vrl_lightcuts", spp=1, cut="bound", bound="foo")
    with pytest.raises(ValueError, match="compensated_clamp must be a positive number or 'auto' or 'off', got 'on'"):
        scene.render("vrl", spp=1, compensated_clamp="on")
    assert TABLE["compensated_clamp"]["choices"] == ["auto", "off"]
    assert TABLE["compensated_clamp"]["default"] == "auto"
    for given in ("auto", "off", 4.0):
        assert scene._inner.check_options("vpl", compensated_clamp=given) == "vpl"
    with pytest.raises(ValueError, match="epsilon must be a number >= 0, got 'nan'"):
        scene.render("vrl_lightcuts", spp=1, cut="bound", epsilon=float("nan"))
    with pytest.raises(ValueError, match=r"max_cut does not apply to vrl_lightcuts with cut stochastic \(only with cut bound\)"):
        scene.render("vrl_lightcuts", spp=1, max_cut=5)
    with pytest.raises(ValueError, match="spp does not apply"):
        scene._inner.render_passes("volpath", 0, 1, spp=2)


def test_cut_sizes_are_the_command_lines_cut_image(small_box):
    scene = haze.load_scene(small_box)
    sizes = scene.cut_sizes("vrl_lightcuts", light_paths=40, cut="bound", max_cut=20)
    assert sizes.shape == (24, 32) and sizes.dtype == np.float32
    assert sizes.max() <= 20 and sizes.max() > 1
    assert (scene.cut_sizes("vrl_lightcuts", light_paths=40, cut="bound", max_cut=5) <= 5).all()
    # The stochastic cut: the largest cut node's share of the importance, in (0, 1].
    shares = scene.cut_sizes("vrl_lightcuts", light_paths=40)
    assert shares.max() <= 1.0 and shares.max() > 0.0
    with pytest.raises(ValueError, match="cut sizes need a lightcut method"):
        scene.cut_sizes("vrl")
    with pytest.raises(ValueError, match="spp does not apply"):
        scene._inner.cut_sizes("vrl_lightcuts", spp=2)


def test_new_options_reach_the_render(small_box):
    scene = haze.load_scene(small_box)
    base = dict(spp=1, seed=3, light_paths=40)
    a = scene.render("vrl_lightcuts", **base)
    assert np.array_equal(a, scene.render("vrl_lightcuts", cut_size=1, **base))
    assert not np.array_equal(a, scene.render("vrl_lightcuts", cut_size=2, **base))
    b = scene.render("vrl_lightcuts", cut="bound", **base)
    assert not np.array_equal(a, b)
    assert np.array_equal(b, scene.render("vrl_lightcuts", cut="bound", max_cut=1000, bound="paper", **base))
    assert not np.array_equal(b, scene.render("vrl_lightcuts", cut="bound", max_cut=1, **base))
    assert not np.array_equal(a, scene.render("vrl_lightcuts", builder="median", **base))
    v = scene.render("vpl", **base)
    assert not np.array_equal(v, scene.render("vpl", vpl_clamp=1e-3, **base))


def test_spp_per_pass_is_the_command_lines(tmp_path):
    """Python's spp per pass is the engine's, as ``haze render`` prints it: auto per method and
    image size (16 for the lightcut methods at 128x128, 1 for the others), or the given value;
    the films of ``render_passes`` hold that many samples per pass."""
    path = tmp_path / "box-128.xml"
    path.write_text(small_scene_text(128, 128))
    scene = haze.load_scene(path)
    lights = ["--light-paths", "10"]
    for method in haze.METHOD_NAMES:
        many_light = method != "volpath"
        args = [haze_binary(), "render", path, "--integrator", method, "--spp", "16", "-q", "-o", tmp_path / "x.exr"]
        err = subprocess.run(args + (lights if many_light else []), capture_output=True, text=True, check=True).stderr
        printed = re.search(rf"^{method}: spp per pass (\d+) \(auto", err, re.M)
        assert printed, err
        want = 16 if "lightcuts" in method else 1
        assert int(printed.group(1)) == scene.spp_per_pass_for(method, spp=16) == want
        # render_passes: the scene's budget (64 spp, a multiple of 16).
        film = scene.render_passes(method, 0, 1, light_paths=10 if many_light else None)
        assert film.samples == scene.spp_per_pass_for(method) == want
        assert scene.spp_per_pass_for(method, spp=16, spp_per_pass=3) == 3
        assert scene.spp_per_pass_for(method, spp=20) == (10 if "lightcuts" in method else 1)

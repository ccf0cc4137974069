"""haze: a renderer for participating media (virtual ray lights, VRL lightcuts) that reads
Mitsuba 3 XML scenes.

>>> import haze
>>> scene = haze.load_scene("hg-box.xml")
>>> image = scene.render("vrl_lightcuts", spp=4)       # float32 array, shape (H, W, 3)

Rendering releases the GIL and Ctrl-C interrupts it (after the current pass). Rendering across
machines on Ray: :mod:`haze.distributed`. See docs/python.md.
"""

from __future__ import annotations

import os
from typing import NamedTuple

import numpy as np

from . import _haze
from ._haze import METHOD_NAMES, Film, SceneError, merge_films, pass_blocks, read_exr, write_exr, write_png

__all__ = [
    "COMPONENTS",
    "METHOD_NAMES",
    "OPTIONS",
    "Film",
    "Lights",
    "Scene",
    "SceneError",
    "load_scene",
    "merge_films",
    "pass_blocks",
    "read_exr",
    "relmse",
    "rmse",
    "smape",
    "trace_lights",
    "write_exr",
    "write_png",
]

#: The components of ``render(components=True)``; they sum to the image.
COMPONENTS = ("emitted", "single", "multiple", "surface")


def _define_value(v: object) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    return str(v)


def _defines(defaults: dict) -> list[tuple[str, str]]:
    return [(str(k), _define_value(v)) for k, v in defaults.items()]


class Scene:
    """A scene loaded by :func:`load_scene`. Immutable; renders may run from several threads."""

    def __init__(self, inner: _haze.Scene, defaults: dict[str, str]):
        self._inner = inner
        #: The ``<default>`` overrides the scene was loaded with (as strings).
        self.defaults = dict(defaults)

    @property
    def path(self) -> str:
        """The scene file."""
        return os.fspath(self._inner.path)

    @property
    def files(self) -> list[str]:
        """Every file the scene read: the scene file first, then includes, meshes and images."""
        return [os.fspath(p) for p in self._inner.files]

    @property
    def width(self) -> int:
        return self._inner.width

    @property
    def height(self) -> int:
        return self._inner.height

    @property
    def spp(self) -> int:
        """The scene's samples per pixel (its sampler's ``sample_count``)."""
        return self._inner.spp

    @property
    def integrator(self) -> str:
        """The integrator the scene file names."""
        return self._inner.integrator

    def render_film(
        self,
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
    ) -> Film:
        """Like :meth:`render`, but returns the :class:`Film` (means, variances, raw sums)."""
        return self._inner.render(integrator, **_given(locals()))

    def render(
        self,
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
    ):
        # The docstring is made from the engine's table below (_RENDER_DOC).
        film = self._inner.render(integrator, **_given(locals()))
        return _images(film, components)

    def render_passes(
        self,
        integrator: str | None = "vrl_lightcuts",
        first: int = 0,
        count: int = 1,
        *,
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
    ) -> Film:
        """Renders the passes ``first .. first + count`` and returns their :class:`Film`.

        Each pass is keyed by ``(seed, pass index)`` (its camera samples, its light paths, its
        light tree), and the passes are summed over a fixed binary tree, so this film equals,
        bit for bit, :func:`merge_films` of any split of the range into :func:`pass_blocks`
        rendered elsewhere (this is what :func:`haze.distributed.render` does). The options are
        those of :meth:`render` but ``spp`` and ``time`` (the passes are the budget).
        """
        return self._inner.render_passes(integrator, first, count, **_given(locals()))

    def cut_sizes(
        self,
        integrator: str | None = "vrl_lightcuts",
        *,
        seed: int = 0,
        vrls: int | None = None,
        light_paths: int | None = None,
        caustic_paths: int | None = None,
        cut: str | None = None,
        cut_size: int | None = None,
        light_samples: int | None = None,
        epsilon: float | None = None,
        max_cut: int | None = None,
        bound: str | None = None,
        builder: str | None = None,
        sampler: str | None = None,
        compensated_clamp: float | str | None = None,
        path_traced_media: str | None = None,
    ) -> np.ndarray:
        """Per pixel, a float32 array of shape (H, W), what ``haze render --cut-image`` draws:
        the mean cut size (``cut="bound"``) or the largest cut node's share of the stochastic
        cut's importance (the default cut), from one extra 1-spp pass (pass 0 with ``seed``, so
        the lights and cuts of the image's first pass); 0 where the camera path meets no
        medium. Lightcut methods only; the options are those of :meth:`render` without the
        sample budget."""
        return self._inner.cut_sizes(integrator, **_given(locals()))

    def spp_per_pass_for(
        self,
        integrator: str | None = "vrl_lightcuts",
        *,
        spp: int | None = None,
        time: float | None = None,
        spp_per_pass: int | None = None,
    ) -> int:
        """The samples per pixel of each pass of a render of this scene with ``integrator`` and
        the budget ``spp`` (default: the scene's) or ``time``: ``spp_per_pass`` when given,
        else the engine's auto default for the method, the image size and the budget (as
        ``haze render`` prints it; see ``spp_per_pass`` in :data:`OPTIONS`)."""
        return self._inner.spp_per_pass(integrator, **_given(locals()))

    def __repr__(self) -> str:
        return repr(self._inner)


#: The engine's options (name, default, help, the methods each applies to): one dict per option,
#: as ``haze render --help`` and ``haze compare`` know them.
OPTIONS = tuple(_haze.method_options())
_OPTION_NAMES = frozenset(o["name"] for o in OPTIONS)


def _given(values: dict) -> dict:
    """The engine options among a function's ``locals()`` that were given (not None)."""
    return {k: v for k, v in values.items() if k in _OPTION_NAMES and v is not None}


def _options_doc(indent: str, skip: tuple[str, ...] = ()) -> str:
    """The ``Args:`` entries of the engine's options, from its table."""
    lines = []
    for o in OPTIONS:
        if o["name"] not in skip:
            lines.append(f"{indent}{o['name']}: {o['help']}")
    return "\n".join(lines)


_RENDER_DOC = """Renders the scene as ``haze render`` does and returns the image.

        Args:
            integrator: one of :data:`METHOD_NAMES`; ``None`` for the scene's own
                ``<integrator>``.
{options}

        An option left at ``None`` takes the default above; an option given for a method it
        does not apply to is a ``ValueError`` naming both (as on the command line).

        Returns:
            A float32 array of shape (H, W, 3) (linear RGB), or with ``components=True`` a dict
            with the keys ``"image"`` and :data:`COMPONENTS`, each such an array.

        Raises:
            ValueError: a bad argument or an integrator that cannot render this scene.
            KeyboardInterrupt: Ctrl-C (the render stops after the current pass).
        """
Scene.render.__doc__ = _RENDER_DOC.format(options=_options_doc(" " * 12))


def _images(film: Film, components: bool):
    if not components:
        return film.mean()
    out = {"image": film.mean()}
    for c in COMPONENTS:
        out[c] = film.mean(c)
    return out


def load_scene(path: str | os.PathLike, **defaults) -> Scene:
    """Loads a Mitsuba 3 XML scene.

    Keyword arguments override the file's ``<default name=".." value=".."/>`` parameters, as
    ``-D name=value`` does on the command line (``True``/``False`` become ``true``/``false``).

    Raises:
        SceneError: the file cannot be read or is not a valid scene; the message (and the
            ``file``, ``line``, ``column`` and ``element`` attributes) say where.
    """
    defines = _defines(defaults)
    return Scene(_haze.load_scene(os.fspath(path), defines), dict(defines))


#: Structured dtype of virtual ray lights (one medium segment of a light path each).
VRL_DTYPE = np.dtype(
    [
        ("start", np.float32, 3),
        ("direction", np.float32, 3),
        ("length", np.float32),
        ("flux", np.float32, 3),
        ("ratio", np.float32, 3),
        ("medium", np.uint32),
        ("after_surface", np.bool_),
    ]
)

#: Structured dtype of virtual point lights (one medium scattering vertex each).
VPL_DTYPE = np.dtype(
    [
        ("position", np.float32, 3),
        ("direction", np.float32, 3),
        ("flux", np.float32, 3),
        ("medium", np.uint32),
        ("after_surface", np.bool_),
    ]
)


class Lights(NamedTuple):
    """The virtual lights of one pass (see :func:`trace_lights`)."""

    vrls: np.ndarray
    vpls: np.ndarray
    paths: int


def trace_lights(scene: Scene, n: int, seed: int = 0, pass_index: int = 0) -> Lights:
    """Traces ``n`` light paths as a many-light integrator's pass ``pass_index`` does.

    Returns the virtual ray lights as a structured array of :data:`VRL_DTYPE`: ``start``,
    unit ``direction``, ``length``, ``flux`` (watts: the throughput at ``start``, already
    divided by ``n``; for chromatic media the flux at distance v is
    ``flux * T(v) / mean(ratio * T(v))``), the spectral-MIS pdf ``ratio``, the ``medium``
    index, and ``after_surface``; and the virtual point lights as :data:`VPL_DTYPE`. In a
    homogeneous medium the first segment of each path starts at an emitter, so over the
    segments that start at the emitters the fluxes sum to the emitted power. In a
    heterogeneous medium a VRL spans its whole segment where the medium is (it may start
    past the emitter), ``ratio`` is 0 and the flux at distance v is ``flux * T(v)`` with the
    medium's transmittance (docs/theory.md §12.5).
    """
    d = _haze.trace_lights(scene._inner, n, seed, pass_index)
    vrls = np.zeros(len(d["vrl_length"]), dtype=VRL_DTYPE)
    for field in ("start", "direction", "length", "flux", "ratio", "medium", "after_surface"):
        vrls[field] = d["vrl_" + field]
    vpls = np.zeros(len(d["vpl_medium"]), dtype=VPL_DTYPE)
    for field in ("position", "direction", "flux", "medium", "after_surface"):
        vpls[field] = d["vpl_" + field]
    return Lights(vrls, vpls, int(d["paths"]))


def _image(a) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float32)


def rmse(approx, reference) -> float:
    """Root mean squared error over all pixels and channels of two (..., 3) images."""
    return _haze.rmse(_image(approx), _image(reference))


def smape(approx, reference) -> float:
    """Symmetric mean absolute percentage error, in percent: ``100 mean |a-r| / (|a|+|r|)``
    (entries where both are 0 are skipped)."""
    return _haze.smape(_image(approx), _image(reference))


def relmse(approx, reference) -> float:
    """Relative mean squared error ``mean (a-r)^2 / (r^2 + 0.01)``."""
    return _haze.relmse(_image(approx), _image(reference))

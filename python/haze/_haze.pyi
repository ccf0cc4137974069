"""Type stubs of the compiled core `haze._haze` (crates/python). Use the `haze` package."""

import os
from typing import Any, Optional, Sequence

import numpy as np
import numpy.typing as npt

METHOD_NAMES: tuple[str, ...]

class SceneError(Exception):
    """A scene file could not be loaded; the message names the file, line, column and element."""

    file: str
    line: int
    column: int
    element: str

class Film:
    """Per-pixel sums and squared sums (float64) of a render. Picklable."""

    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def samples(self) -> int:
        """Samples per pixel accumulated."""
    @property
    def has_components(self) -> bool: ...
    def mean(self, component: Optional[str] = None) -> npt.NDArray[np.float32]:
        """Mean image, shape (H, W, 3), of the image or a component."""
    def variance_of_mean(self, component: Optional[str] = None) -> npt.NDArray[np.float32]:
        """Variance of the per-pixel mean, shape (H, W, 3)."""
    def sums(self) -> npt.NDArray[np.float64]:
        """Raw sums, shape (H, W, 6 * layers): per layer 3 sums then 3 squared sums."""
    @staticmethod
    def from_sums(sums: npt.NDArray[np.float64], samples: int) -> "Film": ...

class Scene:
    """A loaded scene (immutable)."""

    @property
    def path(self) -> str: ...
    @property
    def files(self) -> list[str]: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def spp(self) -> int: ...
    @property
    def integrator(self) -> str: ...
    def render(self, integrator: Optional[str] = None, **options: Any) -> Film:
        """Renders with the engine's options (method_options()) given by name."""
    def render_passes(self, integrator: Optional[str] = None, first: int = 0, count: int = 1, **options: Any) -> Film: ...
    def cut_sizes(self, integrator: Optional[str] = None, **options: Any) -> npt.NDArray[np.float32]: ...
    def check_options(self, integrator: Optional[str] = None, **options: Any) -> str:
        """Checks the options for the method as render would; returns the method's name."""
    def spp_per_pass(self, integrator: Optional[str] = None, **options: Any) -> int:
        """The spp per pass a render with these options uses (given, or the engine's auto default)."""

def method_options() -> list[dict[str, Any]]:
    """The engine's table of options, one dict per option."""
def compiled_features() -> list[str]:
    """The x86-64 target features beyond x86-64-v1 the extension was compiled with (empty: portable)."""
def load_scene(path: str | os.PathLike[str], defines: Sequence[tuple[str, str]] = ...) -> Scene: ...
def pass_blocks(first: int, count: int, max_block: int) -> list[tuple[int, int]]: ...
def merge_films(first: int, count: int, blocks: Sequence[tuple[int, int, Film]]) -> Film: ...
def trace_lights(scene: Scene, paths: int, seed: int = 0, pass_: int = 0) -> dict[str, Any]: ...
def rmse(approx: npt.NDArray[np.float32], reference: npt.NDArray[np.float32]) -> float: ...
def smape(approx: npt.NDArray[np.float32], reference: npt.NDArray[np.float32]) -> float: ...
def relmse(approx: npt.NDArray[np.float32], reference: npt.NDArray[np.float32]) -> float: ...
def read_exr(path: str | os.PathLike[str]) -> npt.NDArray[np.float32]: ...
def write_exr(path: str | os.PathLike[str], image: npt.NDArray[np.float32]) -> None: ...
def write_png(path: str | os.PathLike[str], image: npt.NDArray[np.float32], exposure: float = 0.0) -> None: ...

"""Shared fixtures: paths and a small copy of the validation scene hg-box."""

import os
import pathlib
import re

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
# The validation data shipped in the repository (tests/data/validation/README.md).
VALIDATION = REPO / "tests" / "data" / "validation"
HG_BOX = VALIDATION / "scenes" / "hg-box.xml"


def small_scene_text(width: int, height: int) -> str:
    """hg-box.xml at another film size (the scene has no <default> for it)."""
    text = HG_BOX.read_text()
    text = re.sub(r'(<integer name="width" value=")\d+', rf"\g<1>{width}", text)
    return re.sub(r'(<integer name="height" value=")\d+', rf"\g<1>{height}", text)


@pytest.fixture(scope="session")
def hg_box() -> pathlib.Path:
    if not HG_BOX.exists():
        pytest.fail(f"{HG_BOX} is missing: the tests read the validation data in tests/data/validation")
    return HG_BOX


@pytest.fixture(scope="session")
def small_box(tmp_path_factory, hg_box) -> pathlib.Path:
    """hg-box at 32x24 pixels, in a directory of its own."""
    path = tmp_path_factory.mktemp("small-box") / "hg-box-small.xml"
    path.write_text(small_scene_text(32, 24))
    return path


def haze_binary() -> pathlib.Path:
    """The `haze` command built by `cargo test --workspace` (or $HAZE_BIN)."""
    if os.environ.get("HAZE_BIN"):
        return pathlib.Path(os.environ["HAZE_BIN"])
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    for profile in ("debug", "release"):
        exe = target / profile / "haze"
        if exe.exists():
            return exe
    pytest.fail("the haze command is not built: run cargo test --workspace first (or set HAZE_BIN)")

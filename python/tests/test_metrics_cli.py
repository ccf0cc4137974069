"""The metrics of the Python package equal those of `haze compare` on the same images."""

import re
import subprocess

import haze
from conftest import haze_binary


def test_metrics_equal_haze_compare(small_box, tmp_path):
    exe = haze_binary()
    ref = tmp_path / "ref.exr"
    subprocess.run(
        [exe, "render", small_box, "-o", ref, "--integrator", "volpath", "--spp", "4", "--seed", "7", "-q"],
        check=True,
        capture_output=True,
    )
    out = subprocess.run(
        [exe, "compare", small_box, "--reference", ref, "--time", "0.01", "--method", "volpath", "-o", tmp_path],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    row = next(line for line in out.splitlines() if line.startswith("| volpath"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    cli_rmse, cli_smape, cli_relmse = float(cells[4]), float(cells[5]), float(cells[6])
    image = haze.read_exr(tmp_path / "volpath.exr")
    reference = haze.read_exr(ref)
    assert f"{haze.rmse(image, reference):.4f}" == cells[4]
    assert f"{haze.smape(image, reference):.2f}" == cells[5]
    assert f"{haze.relmse(image, reference):.4f}" == cells[6]
    assert cli_rmse > 0 and cli_smape > 0 and cli_relmse > 0
    assert re.match(r"\d+", cells[3])

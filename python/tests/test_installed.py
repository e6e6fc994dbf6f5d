"""The package as `pip install .` installs it, and the examples/ run on it. Run by ctest
python/venv-install (venv_install.py) inside a fresh virtualenv, with EMA_TEST_INSTALLED=1; skipped
on the build tree (python/pytest)."""
import json
import os
import pathlib
import re
import subprocess
import sys
import warnings

import pytest

import ema
from conftest import SHARED, SOURCE

pytestmark = pytest.mark.skipif(os.environ.get("EMA_TEST_INSTALLED") != "1",
                                reason="the installed package only (ctest python/venv-install)")
EXAMPLES = SOURCE / "examples"


def run_example(name, *args, cwd):
    result = subprocess.run([sys.executable, str(EXAMPLES / name), *map(str, args)], cwd=cwd, capture_output=True,
                            text=True, env={k: v for k, v in os.environ.items() if k != "PYTHONPATH"})
    assert result.returncode == 0, result.stderr
    return result.stdout


def refuse_non_json_constant(token):
    raise AssertionError(f"{token} is not JSON (NaN must be written as null)")


def test_the_package_is_the_installed_one():
    package = pathlib.Path(ema.__file__).parent
    assert sys.prefix != sys.base_prefix, "not in a virtualenv"
    assert package.is_relative_to(sys.prefix), package
    assert ema._ema.__file__.startswith(str(package))
    for name in ["__init__.py", "__main__.py", "_ema.pyi", "py.typed", "plot.py", "results.py", "types.py"]:
        assert (package / name).exists(), name


def test_example_guideway_story(tmp):
    out = run_example("guideway_story.py", SOURCE / "samples" / "guideway", cwd=tmp)
    agreements = [float(x) for x in re.findall(r"agrees to ([0-9.]+) %", out)]
    assert len(agreements) == 2 and 30 < agreements[0] < 40 and 65 < agreements[1] < 75, out
    assert "in series with group 'bearings'" in out, out


def test_example_vendor_uff_to_modes(tmp):
    data = SHARED / "uff" / "ufffiles-jl" / "dataset58_FRF.unv"
    if not data.exists():
        pytest.skip("shared data not present")
    out = run_example("uff_to_modes.py", data, "-o", tmp / "MODES.json", cwd=tmp)
    assert "1 responses x 1 references, 1600 lines" in out, out
    modes = ema.read_modes(tmp / "MODES.json")
    assert len(modes["frequency_hz"]) >= 5 and f"wrote {tmp / 'MODES.json'} ({len(modes['frequency_hz'])} modes" in out
    # The strongest peak of the file (175 Hz) is among the modes.
    assert min(abs(modes["frequency_hz"] - 175.0)) < 1.0, out


def test_example_fe_parts_diagnosis(tmp):
    out = run_example("fe_parts_diagnosis.py", cwd=tmp)
    rank1 = re.search(r"rank 1: (.*)", out).group(1)
    assert "member 'J2' of group 'joints'" in rank1, out
    factor = float(re.search(r"factor = ([0-9.]+)", out).group(1))
    assert abs(factor - 0.3) < 0.02, out


def test_example_plot_fit(tmp):
    # The measured beam (samples/meas-point, 30..300 Hz, orders up to 40): its three modes printed,
    # the three plots saved as PNG, the fit as strict JSON with the modes' frequencies.
    out = run_example("plot_fit.py", "-o", tmp / "plots", cwd=tmp)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # the beam's negative modal mass, in 'warnings'
        fit = ema.fit(str(SOURCE / "samples" / "meas-point"), band=(30.0, 300.0), order_max=40)
    assert f"{len(fit['frequency_hz'])} modes (synthesis error {fit['synthesis_error']:.3g})" in out, out
    for f in fit["frequency_hz"]:
        assert f"{f:.4g}" in out, out
    for name in ["stabilisation.png", "frf.png", "mac.png"]:
        assert (tmp / "plots" / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
        assert f"wrote {tmp / 'plots' / name}" in out
    written = json.loads((tmp / "plots" / "fit.json").read_text(), parse_constant=refuse_non_json_constant)
    assert written["frequency_hz"] == fit["frequency_hz"].tolist()
    assert len(written["stabilisation"]["orders"]) == 40

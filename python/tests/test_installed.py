"""The package as `pip install .` installs it, and the examples/ run on it. Run by ctest
python/venv-install (venv_install.py) inside a fresh virtualenv, with EMA_TEST_INSTALLED=1; skipped
on the build tree (python/pytest)."""
import os
import pathlib
import re
import subprocess
import sys

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


def test_the_package_is_the_installed_one():
    package = pathlib.Path(ema.__file__).parent
    assert sys.prefix != sys.base_prefix, "not in a virtualenv"
    assert package.is_relative_to(sys.prefix), package
    assert ema._ema.__file__.startswith(str(package))
    for name in ["__init__.py", "__main__.py", "_ema.pyi", "py.typed"]:
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

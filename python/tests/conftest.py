"""Shared fixtures of the ema Python tests: the CLI, the data folders, a scratch directory."""
import json
import os
import pathlib
import subprocess

import pytest

EMA = os.environ.get("EMA_EXECUTABLE", "ema")
SOURCE = pathlib.Path(os.environ.get("EMA_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
SHARED = pathlib.Path(os.environ.get("EMA_REAL_DATA_DIR", SOURCE / "tests" / "data" / "real"))


def run_ema(*args):
    """Runs the CLI; fails the test with its stderr when it does not exit 0."""
    result = subprocess.run([EMA, *map(str, args)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    return result.stdout


def load_json(path):
    with open(path) as f:
        return json.load(f)


@pytest.fixture
def tmp(tmp_path):
    return tmp_path


@pytest.fixture(scope="session")
def beam_fit(tmp_path_factory):
    """The measured beam (samples/meas-point) fitted by the CLI in 30..300 Hz at orders up to 40."""
    d = tmp_path_factory.mktemp("beam")
    sample = SOURCE / "samples" / "meas-point"
    run_ema("fit", sample, "-o", d / "modes.unv", "--json", d / "modes.json", "--stabilisation", d / "stab.json",
            "--band", "30:300", "--order-max", "40")
    return sample, d

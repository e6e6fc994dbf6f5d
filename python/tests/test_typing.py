"""mypy --strict (python/mypy.ini) on examples/*.py and the package (issue 41): scripts are checked
against the stubs and the result TypedDicts (ema.types), and those are precise enough to catch a
wrong key or an unchecked null."""
import importlib.util
import os
import re
import subprocess
import sys

import pytest

from conftest import SOURCE

PACKAGE_SOURCE = SOURCE / "python"
pytestmark = pytest.mark.skipif(importlib.util.find_spec("mypy") is None,
                                reason="mypy not installed (Debian: mypy; scripts/install-deps.sh --test)")


def run_mypy(*paths, cache):
    # The package from its source folder (MYPYPATH): the .py modules and the _ema.pyi stubs.
    env = dict(os.environ, MYPYPATH=str(PACKAGE_SOURCE))
    return subprocess.run([sys.executable, "-m", "mypy", "--config-file", str(PACKAGE_SOURCE / "mypy.ini"),
                           "--cache-dir", str(cache), "--no-error-summary", *map(str, paths)],
                          capture_output=True, text=True, env=env, cwd=cache.parent)


@pytest.fixture(scope="module")
def mypy_cache(tmp_path_factory):
    """One cache for both runs: numpy's stubs are analysed once (about 10 s)."""
    return tmp_path_factory.mktemp("mypy") / "cache"


def test_examples_and_package_pass_mypy_strict(mypy_cache):
    examples = sorted((SOURCE / "examples").glob("*.py"))
    assert "plot_fit.py" in [e.name for e in examples]
    result = run_mypy(*examples, PACKAGE_SOURCE / "ema", cache=mypy_cache)
    assert result.returncode == 0, result.stdout + result.stderr


def test_mypy_catches_misuse_of_results(tmp_path, mypy_cache):
    # The control for the test above: the same settings flag a key no result has and a value that
    # may be None (the JSON's null), so the examples pass on types, not on everything being Any.
    script = tmp_path / "misuse.py"
    script.write_text(
        "import ema\n"
        "fit = ema.fit('frfs.unv')\n"
        "print(fit['frequency'])\n"
        "best = ema.diagnose('model.toml', fit)['candidates'][0]\n"
        "print(100 * best['probability'])\n"
        "pairs: int = ema.correlate(fit, fit)['pairs']\n")
    result = run_mypy(script, cache=mypy_cache)
    errors = [line for line in result.stdout.splitlines() if ": error:" in line]
    assert result.returncode == 1, result.stdout + result.stderr
    lines = sorted(int(re.match(r".*?:(\d+): error", e).group(1)) for e in errors)
    assert lines == [3, 5, 6], result.stdout
    assert '"FitDict" has no key "frequency"' in result.stdout
    assert "Optional[float]" in result.stdout or "None" in result.stdout

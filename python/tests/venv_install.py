"""ctest python/venv-install: the ema package installed as users install it (docs/python.md), then tested.

1. a fresh virtualenv with the system site packages (numpy, scipy, pytest from Debian) in WORK/venv;
2. `pip install --no-build-isolation --no-index SOURCE` with EMA_PYTHON_EXTENSION = the module this
   tree has built (setup.py installs it as is: no second C++ build);
3. `python -m ema --version` (as `ema --version` says) and `help(ema.diagnose)` from another folder;
4. the whole pytest suite on the installed package (no PYTHONPATH), with the installed-only tests:
   the package's files and the examples/ (EMA_TEST_INSTALLED=1, python/tests/test_installed.py);
5. `pip uninstall -y ema`: the package is gone.

Usage: venv_install.py --source REPO --extension build/python/ema/_ema*.so --work build/python/venv-install
(EMA_EXECUTABLE, EMA_REAL_DATA_DIR, EMA_SOURCE_DIR as for python/pytest).
"""
import argparse
import os
import pathlib
import shutil
import subprocess
import sys
import time


def run(command, check=True, **kwargs):
    print("+", " ".join(str(c) for c in command), flush=True)
    started = time.monotonic()
    result = subprocess.run([str(c) for c in command], text=True, capture_output=True, **kwargs)
    print(result.stdout, end="")
    print(result.stderr, end="", file=sys.stderr)
    print(f"  ({time.monotonic() - started:.1f} s, exit {result.returncode})", flush=True)
    if check and result.returncode != 0:
        sys.exit(f"venv_install.py: {command[0]} exited {result.returncode}")
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--source", type=pathlib.Path, required=True, help="the repository (setup.py)")
    parser.add_argument("--extension", type=pathlib.Path, required=True, help="the built ema._ema module")
    parser.add_argument("--work", type=pathlib.Path, required=True, help="scratch folder (emptied first)")
    args = parser.parse_args()
    started = time.monotonic()
    work = args.work.resolve()
    shutil.rmtree(work, ignore_errors=True)
    elsewhere = work / "elsewhere"  # not the source tree, not the build tree
    elsewhere.mkdir(parents=True)
    venv = work / "venv"
    python, pip = venv / "bin" / "python", venv / "bin" / "pip"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env.update(PIP_DISABLE_PIP_VERSION_CHECK="1", PAGER="cat")

    run([sys.executable, "-m", "venv", "--system-site-packages", venv], env=env)
    run([pip, "install", "--no-build-isolation", "--no-index", args.source.resolve()], cwd=elsewhere,
        env=dict(env, EMA_PYTHON_EXTENSION=str(args.extension.resolve()), EMA_BUILD_DIR=str(work / "pip-build")))

    version = run([python, "-m", "ema", "--version"], cwd=elsewhere, env=env).stdout.strip()
    cli = os.environ.get("EMA_EXECUTABLE")
    if cli:
        expected = run([cli, "--version"], env=env).stdout.strip()
        if version != expected:
            sys.exit(f"venv_install.py: python -m ema --version says '{version}', ema --version '{expected}'")
    # The package carries the project's licence (LICENSE, GPL-3.0-or-later) in its metadata.
    meta = run([pip, "show", "ema"], cwd=elsewhere, env=env).stdout
    if "License: GPL-3.0-or-later" not in meta:
        sys.exit(f"venv_install.py: `pip show ema` does not name the licence GPL-3.0-or-later:\n{meta}")
    shown = run([python, "-c", "import ema; print(ema.__file__); help(ema.diagnose)"], cwd=elsewhere, env=env).stdout
    if not shown.startswith(str(venv)) or "diagnose(model" not in shown or "ema fit --json" not in shown:
        sys.exit("venv_install.py: help(ema.diagnose) from another folder did not show the installed package's docstring")

    source = pathlib.Path(os.environ.get("EMA_SOURCE_DIR", args.source)).resolve()
    tests = run([python, "-m", "pytest", "-q", "-p", "no:cacheprovider", f"--basetemp={work / 'pytest'}",
                 source / "python" / "tests"], check=False, cwd=elsewhere, env=dict(env, EMA_TEST_INSTALLED="1"))
    if tests.returncode != 0:
        sys.exit(f"venv_install.py: the suite on the installed package failed (exit {tests.returncode})")

    run([pip, "uninstall", "-y", "ema"], cwd=elsewhere, env=env)
    gone = run([python, "-c", "import ema"], check=False, cwd=elsewhere, env=env)
    left = [p.name for p in (venv / "lib").glob("python3*/site-packages/ema*")]
    if gone.returncode == 0 or left:
        sys.exit(f"venv_install.py: `pip uninstall -y ema` left the package importable or files behind: {left}")
    print(f"venv_install.py: installed, tested and uninstalled in {time.monotonic() - started:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

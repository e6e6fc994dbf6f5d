"""`pip install .`: builds the ema C++ library and its Python module with CMake, and installs the `ema`
package (python/ema/ around the compiled ema._ema). docs/python.md tells the whole story:

    /usr/bin/python3 -m venv --system-site-packages v
    v/bin/pip install --no-build-isolation .
    v/bin/python -m ema --version

CMake configures the repository with -DEMA_BUILD_TESTS=OFF -DEMA_BUILD_BENCH=OFF and builds the
`ema_python` target only (the libraries it links; not the CLI, not the HTML report). Environment:

  CMAKE_BUILD_PARALLEL_LEVEL  compile jobs (default: every core)
  CMAKE_ARGS                  more CMake arguments, e.g. "-DCMAKE_CXX_COMPILER=clang++"
  EMA_BUILD_DIR               where setuptools and CMake build (default: build-pip/ in the repository,
                              which git ignores; kept, so a second `pip install .` recompiles only what
                              changed — delete it for a clean build)
  EMA_PYTHON_EXTENSION        an ema._ema extension already built (build/python/ema/_ema*.so of a
                              configured tree): installed as is, without CMake. The test suite
                              (python/venv-install) installs the tree's own build this way.
"""
import os
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build import build
from setuptools.command.build_ext import build_ext
from setuptools.command.egg_info import egg_info

ROOT = Path(__file__).resolve().parent
EXTENSION_SUFFIX = sysconfig.get_config_var("EXT_SUFFIX")


def version():
    match = re.search(r"project\(ema\s+VERSION\s+([0-9.]+)", (ROOT / "CMakeLists.txt").read_text())
    if not match:
        raise RuntimeError("CMakeLists.txt: no `project(ema VERSION x.y.z ...)` to take the version from")
    return match.group(1)


def build_base():
    return os.environ.get("EMA_BUILD_DIR") or "build-pip"


class Build(build):
    """setuptools' build folder is build-pip/ (build/ is the CMake tree of docs/building.md)."""

    def initialize_options(self):
        super().initialize_options()
        self.build_base = build_base()


class EggInfo(egg_info):
    """The metadata (ema.egg-info) goes to the build folder, not into python/ of the source tree."""

    def initialize_options(self):
        super().initialize_options()
        os.makedirs(build_base(), exist_ok=True)
        self.egg_base = build_base()


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class BuildExt(build_ext):
    """The extension from CMake (the `ema_python` target), or an already-built one (EMA_PYTHON_EXTENSION)."""

    def build_extension(self, ext):
        target = Path(self.get_ext_fullpath(ext.name))
        prebuilt = os.environ.get("EMA_PYTHON_EXTENSION")
        source = self.check_prebuilt(Path(prebuilt)) if prebuilt else self.cmake_build()
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(source, target)

    @staticmethod
    def check_prebuilt(path):
        if not path.is_file():
            raise RuntimeError(f"EMA_PYTHON_EXTENSION={path}: no such file (build it first: "
                               "cmake --build build --target ema_python)")
        if not path.name.startswith("_ema.") or not path.name.endswith(EXTENSION_SUFFIX):
            raise RuntimeError(f"EMA_PYTHON_EXTENSION={path}: expected _ema{EXTENSION_SUFFIX}, the module built for "
                               f"this Python ({sys.executable}, {sys.version.split()[0]})")
        return path

    def cmake_build(self):
        if not shutil.which("cmake"):
            raise RuntimeError("cmake not found: scripts/install-deps.sh installs the build dependencies")
        tree = Path(self.build_temp).resolve() / "cmake"
        configure = ["cmake", "-S", str(ROOT), "-B", str(tree), "-DCMAKE_BUILD_TYPE=Release",
                     "-DEMA_BUILD_TESTS=OFF", "-DEMA_BUILD_BENCH=OFF", "-DEMA_BUILD_FUZZ=OFF", "-DEMA_BUILD_PYTHON=ON",
                     f"-DPython3_EXECUTABLE={sys.executable}", *shlex.split(os.environ.get("CMAKE_ARGS", ""))]
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL") or str(os.cpu_count() or 1)
        compile_ = ["cmake", "--build", str(tree), "--target", "ema_python", "--parallel", jobs]
        for command in (configure, compile_):
            print(" ".join(shlex.quote(c) for c in command), flush=True)
            subprocess.run(command, check=True)
        built = tree / "python" / "ema" / f"_ema{EXTENSION_SUFFIX}"
        if not built.is_file():
            raise RuntimeError(f"CMake built no {built}: is pybind11-dev installed (EMA_BUILD_PYTHON needs it)?")
        return built


setup(
    version=version(),
    packages=["ema"],
    package_dir={"": "python"},
    package_data={"ema": ["py.typed", "*.pyi"]},
    ext_modules=[CMakeExtension("ema._ema")],
    cmdclass={"build": Build, "build_ext": BuildExt, "egg_info": EggInfo},
    zip_safe=False,
)

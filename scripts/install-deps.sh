#!/usr/bin/env bash
# Installs the Debian packages ema needs, only when one is missing. Usage: scripts/install-deps.sh [--test]
# --test adds what the test suite needs beyond the build (headless Chromium for the report check; the
# Python package's plots, tables and type check).
set -euo pipefail
packages=(build-essential cmake pkg-config libeigen3-dev libfftw3-dev libceres-dev
          libboost-program-options-dev libgtest-dev libgmock-dev libtomlplusplus-dev
          nlohmann-json3-dev libspectra-dev libbenchmark-dev nodejs npm
          libplplot-dev plplot-driver-cairo libmatio-dev pybind11-dev python3-dev python3-numpy
          python3-scipy python3-venv python3-pip python3-setuptools python3-wheel  # pip install . (docs/python.md)
          libcpp-httplib-dev  # cpp-httplib: the local server of ema pick (docs/pick.md)
          libsuitesparse-dev  # CHOLMOD: the supernodal sparse Cholesky of FE-sized solves (docs/fe-parts.md)
          libopenblas-dev  # the BLAS under CHOLMOD and the block Lanczos: kernels for the CPU at run time (CMakeLists.txt)
          calculix-ccx)  # CalculiX: the FE code of the bolted-frame sample (samples/bolted-frame)
if [[ "${1:-}" == "--test" ]]; then
  packages+=(chromium clang python3-pytest
             python3-matplotlib python3-pandas mypy)  # ema.plot_*, ema.to_dataframe, mypy on examples/ (docs/python.md)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# nodejs/npm may come from outside Debian's packages (a preinstalled node): accept a working npm.
if command -v npm >/dev/null 2>&1; then
  missing=("${missing[@]/nodejs}"); missing=("${missing[@]/npm}")
fi
read -r -a missing <<< "${missing[*]:-}"
if ((${#missing[@]})); then
  echo "ema: installing missing packages: ${missing[*]}" >&2
  sudo=""
  [[ $(id -u) -ne 0 ]] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
fi

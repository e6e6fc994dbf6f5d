#!/usr/bin/env bash
# From a fresh clone to results. Usage:
#   scripts/quickstart.sh          install what is missing, build, run the main job on the sample
#   scripts/quickstart.sh --test   install what is missing, build, run the whole test suite
set -euo pipefail
cd "$(dirname "$0")/.."
mode="${1:-}"
bash scripts/install-deps.sh ${mode}
jobs=$(nproc 2>/dev/null || echo 2)
extra=()
# The test run also builds the UFF reader's libFuzzer target and runs it briefly (needs clang).
if [[ "${mode}" == "--test" ]] && command -v clang++ >/dev/null 2>&1; then
  extra+=(-DEMA_BUILD_FUZZ=ON)
fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "${extra[@]}" >/dev/null
cmake --build build -j"${jobs}"
if [[ "${mode}" == "--test" ]]; then
  ctest --test-dir build --output-on-failure -j"${jobs}" --timeout 900
else
  bash scripts/main-job.sh
fi

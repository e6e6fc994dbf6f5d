#!/usr/bin/env bash
# From a fresh clone to results. Usage:
#   scripts/quickstart.sh             install what is missing, build, run the main job on the sample
#   scripts/quickstart.sh --test      install what is missing, build, run the whole test suite, then
#                                     the sanitizer suite (the --sanitize step below)
#   scripts/quickstart.sh --sanitize  only the sanitizer suite: build-asan/ (ASan + UBSan, leaks
#                                     checked, no recovery) and its ctest run (docs/reliability.md)
set -euo pipefail
cd "$(dirname "$0")/.."
mode="${1:-}"
jobs=$(nproc 2>/dev/null || echo 2)

# The sanitizer suite: every test but the packaging check (it installs and rebuilds a consumer,
# no ema code runs), the headless-Chromium checks (Chromium itself is not built with ASan) and
# the diagnosis benchmark's 25 cases (the same chain as the guideway and acceptance tests, which
# do run under ASan; 25 sanitized chains would add over 12 min to CI).
sanitize() {
  cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Release -DEMA_SANITIZE=ON -DEMA_BUILD_BENCH=OFF >/dev/null
  cmake --build build-asan -j"${jobs}"
  ctest --test-dir build-asan --output-on-failure -j"${jobs}" --timeout 1800 -E 'packaging/|Chromium|diagnosis-benchmark/'
}

if [[ "${mode}" == "--sanitize" ]]; then
  bash scripts/install-deps.sh --test
  sanitize
  exit 0
fi
bash scripts/install-deps.sh ${mode}
extra=()
# The test run also builds the parsers' libFuzzer targets and runs each briefly (needs clang).
if [[ "${mode}" == "--test" ]] && command -v clang++ >/dev/null 2>&1; then
  extra+=(-DEMA_BUILD_FUZZ=ON)
fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "${extra[@]}" >/dev/null
cmake --build build -j"${jobs}"
if [[ "${mode}" == "--test" ]]; then
  ctest --test-dir build --output-on-failure -j"${jobs}" --timeout 900
  sanitize
else
  bash scripts/main-job.sh
fi

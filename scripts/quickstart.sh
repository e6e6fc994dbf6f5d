#!/usr/bin/env bash
# From a fresh clone to results. Usage:
#   scripts/quickstart.sh             install what is missing, build, run the main job on the sample
#   scripts/quickstart.sh --test      install what is missing, build, run the whole test suite (what
#                                     CI runs: .ci/run)
#   scripts/quickstart.sh --sanitize  the whole suite under the sanitizers: build-asan/ (ASan + UBSan,
#                                     leaks checked, no recovery; the fuzz targets too when clang is
#                                     installed) and its ctest run (docs/reliability.md) — before
#                                     landing a change to memory-heavy code
#   scripts/quickstart.sh --sanitize-input  the same for what untrusted input reaches only
set -euo pipefail
cd "$(dirname "$0")/.."
mode="${1:-}"
jobs=$(nproc 2>/dev/null || echo 2)

# Runs one step and says how long it took (the CI time table in docs/reliability.md is read off
# these lines).
step() {
  local name="$1" start=$SECONDS
  shift
  "$@"
  echo "ema quickstart: ${name} took $((SECONDS - start)) s" >&2
}

# ccache, when the machine has it, makes a rebuild of unchanged sources free (CI's clean clone
# gains nothing from it, a developer's second run does).
launcher=()
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi

# The sanitizer suite, in one tree that also builds the parsers' libFuzzer targets (clang, when
# installed: ASan + UBSan on every target, the libraries at -O2 and the rest at -O1, the parsers
# instrumented for coverage; docs/reliability.md "CI time").
#   sanitize all    every test but the packaging check (it installs and rebuilds a consumer, no
#                   ema code runs), the headless-Chromium checks (Chromium itself is not built with
#                   ASan) and the diagnosis benchmark's cases (the same chain as the guideway and
#                   acceptance tests, which do run under ASan); then each fuzz target's smoke run.
#   sanitize input  the modules that read files and own the buffers — core, acquisition, frf,
#                   model, formats — the CLI's bad-input corpus (app/Corpus, every file of
#                   tests/badinput through `ema`), outputs-spare-inputs, resource limits and the
#                   fuzz smoke runs: what untrusted input reaches (--sanitize-input).
# Neither is part of --test any more: with the whole sanitizer suite the test command took 40 min
# in CI (2026-11-27), and even the input scope costs a second build of every library (752 s of a
# 1585-s clean-clone run on 2026-11-27) — over the 20-min budget (docs/reliability.md "CI time").
# They are run before landing a change to parsers or memory-heavy code.
sanitize() {
  local scope="$1"

  local compiler=() fuzz=(-DEMA_BUILD_FUZZ=OFF)
  if command -v clang++ >/dev/null 2>&1; then
    compiler=(-DCMAKE_CXX_COMPILER=clang++)
    fuzz=(-DEMA_BUILD_FUZZ=ON)
  fi
  # A tree configured earlier with the other compiler cannot switch in place: start it afresh.
  if [[ -f build-asan/CMakeCache.txt ]]; then
    local cached
    cached=$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' build-asan/CMakeCache.txt)
    local want_clang=no cached_clang=no
    ((${#compiler[@]})) && want_clang=yes
    [[ "${cached}" == *clang* ]] && cached_clang=yes
    if [[ "${want_clang}" != "${cached_clang}" ]]; then
      rm -rf build-asan/CMakeCache.txt build-asan/CMakeFiles
    fi
  fi
  step "sanitizer configure" cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Release -DEMA_SANITIZE=ON -DEMA_BUILD_BENCH=OFF \
        "${compiler[@]}" "${fuzz[@]}" "${launcher[@]}" >/dev/null
  if [[ "${scope}" == "input" ]]; then
    local modules=(core acquisition frf model formats) targets=(ema test_app)
    for m in "${modules[@]}"; do targets+=("test_${m}"); done
    if ((${#compiler[@]})); then targets+=(fuzz_targets); fi  # fuzz/CMakeLists.txt's list
    step "sanitizer build (input modules)" cmake --build build-asan -j"${jobs}" --target "${targets[@]}"
    step "sanitizer suite (input modules)" ctest --test-dir build-asan --output-on-failure -j"${jobs}" --timeout 1800 \
         -R "^($(IFS='|'; echo "${modules[*]}")|fuzz|app/(Corpus|BadInputTable|OutputsSpareInputs|Resources|ConvergenceExit))[/.]" \
         -E 'Chromium'
  else
    step "sanitizer build" cmake --build build-asan -j"${jobs}"
    step "sanitizer suite" ctest --test-dir build-asan --output-on-failure -j"${jobs}" --timeout 1800 \
         -E 'packaging/|Chromium|diagnosis-benchmark/|fe-import/loosened'
  fi
}

if [[ "${mode}" == "--sanitize" || "${mode}" == "--sanitize-input" ]]; then
  step "install" bash scripts/install-deps.sh --test
  if [[ "${mode}" == "--sanitize" ]]; then sanitize all; else sanitize input; fi
  exit 0
fi
step "install" bash scripts/install-deps.sh ${mode}
extra=()
# The test run leaves the benchmark programs out (bench/: built where asked, docs/performance.md);
# the fuzz targets are built and run in the sanitizer tree.
if [[ "${mode}" == "--test" ]]; then
  extra+=(-DEMA_BUILD_BENCH=OFF -DEMA_BUILD_FUZZ=OFF)
fi
step "configure" cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "${extra[@]}" "${launcher[@]}" >/dev/null
step "build" cmake --build build -j"${jobs}"
if [[ "${mode}" == "--test" ]]; then
  step "suite" ctest --test-dir build --output-on-failure -j"${jobs}" --timeout 900
else
  bash scripts/main-job.sh
fi

#!/usr/bin/env bash
# The main job on the embedded sample (run by scripts/quickstart.sh after the build).
set -euo pipefail
cd "$(dirname "$0")/.."
./build/app/ema info samples/uff/dataset58_FRF.unv

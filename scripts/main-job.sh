#!/usr/bin/env bash
# The main job on the embedded sample (run by scripts/quickstart.sh after the build): the guideway
# story — hammer data → FRFs → modes → the air-film-only model fails → the missing mount compliance
# is found → the updated model agrees — with the HTML report (samples/guideway/README.md).
set -euo pipefail
cd "$(dirname "$0")/.."
./build/app/ema run samples/guideway/project.toml -o build/guideway-report
echo "open $(pwd)/build/guideway-report/report.html"

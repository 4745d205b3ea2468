#!/usr/bin/env bash
# Installs what is missing, builds doorbench and runs `doorbench demo` on the simulated bench.
# Extra arguments go to `doorbench demo` (see `doorbench demo --help`).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
build_dir=${DOORBENCH_BUILD_DIR:-build}
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release
cmake --build "$build_dir" -j "$(nproc)" --target doorbench
"$build_dir/app/doorbench" demo "$@"

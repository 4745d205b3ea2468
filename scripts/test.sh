#!/usr/bin/env bash
# Installs what is missing, checks the layers (scripts/check_includes.py, docs/architecture.md)
# that no file defines its own degree constant (scripts/check_units.py) and that every C++
# source is formatted (scripts/check_format.sh),
# builds doorbench with warnings as errors, checks that no function is too long
# (scripts/check_function_length.py), fuzzes the parsers for a bounded time
# (scripts/fuzz.sh, docs/fuzzing.md), and runs every test, the slow ones included.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
python3 scripts/check_includes.py
python3 scripts/check_units.py
bash scripts/check_format.sh
build_dir=${DOORBENCH_BUILD_DIR:-build}
# A new build folder uses Ninja: unlike make, it compiles a target's objects while the
# libraries it links are still being built (docs/PERFORMANCE.md). An existing folder keeps
# the generator it was made with (CMake refuses to change it).
generator=()
if [[ ! -e $build_dir/CMakeCache.txt ]] && command -v ninja > /dev/null; then generator=(-G Ninja); fi
cmake -S . -B "$build_dir" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DDOORBENCH_WERROR=ON
cmake --build "$build_dir" -j "$(nproc)"
python3 scripts/check_function_length.py
bash scripts/fuzz.sh "${DOORBENCH_FUZZ_SECONDS:-20}"
ctest --test-dir "$build_dir" --output-on-failure -j "$(nproc)"

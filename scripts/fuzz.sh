#!/usr/bin/env bash
# Builds the libFuzzer harnesses (fuzz/, docs/fuzzing.md) with Debian's clang in build-fuzz/
# and runs each for SECONDS (default 20) from its seed corpus fuzz/corpus/TARGET. New inputs
# go to a scratch folder (the corpus in the repository is only read). A crash, an escaped
# exception, a sanitizer report or a leak fails the script; the input that did it is kept in
# build-fuzz/findings/ and printed as base64.
#   bash scripts/fuzz.sh            # every target, 20 s each
#   bash scripts/fuzz.sh 600 csv    # only the CSV reader, 10 minutes
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-20}
shift || true
targets=("$@")
if ((${#targets[@]} == 0)); then targets=(csv rig params journal hapticmaster); fi
build_dir=${DOORBENCH_FUZZ_BUILD_DIR:-build-fuzz}
root=$(pwd)

generator=()  # Ninja for a new folder, as scripts/test.sh
if [[ ! -e $build_dir/CMakeCache.txt ]] && command -v ninja > /dev/null; then generator=(-G Ninja); fi
CC=clang CXX=clang++ cmake -S . -B "$build_dir" "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DDOORBENCH_FUZZ=ON -DDOORBENCH_BUILD_TESTS=OFF -DDOORBENCH_BUILD_BENCH=OFF > /dev/null
cmake --build "$build_dir" -j "$(nproc)" --target "${targets[@]/#/fuzz_}"

findings="$root/$build_dir/findings"
mkdir -p "$findings"
failed=0
for target in "${targets[@]}"; do
  scratch=$(mktemp -d)
  echo "fuzz_$target: $seconds s from fuzz/corpus/$target"
  if ! (cd "$scratch" && "$root/$build_dir/fuzz/fuzz_$target" -max_total_time="$seconds" \
          -max_len=65536 -timeout=10 -rss_limit_mb=4096 -print_final_stats=1 \
          -artifact_prefix="$findings/$target-" "$scratch" "$root/fuzz/corpus/$target" \
          > "$scratch/log" 2>&1); then
    failed=1
    tail -n 60 "$scratch/log"
    for finding in "$findings/$target-"*; do
      [[ -e $finding ]] && echo "fuzz_$target: input kept in $finding: $(base64 -w0 < "$finding")"
    done
    echo "fuzz_$target: FAILED"
  else
    grep -E "stat::number_of_executed_units|stat::new_units_added" "$scratch/log" | tr '\n' ' '
    echo
  fi
  rm -rf "$scratch"
done
exit $failed

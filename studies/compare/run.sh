#!/usr/bin/env bash
# The sensory fit benchmark side by side: doorbench's C++ fit (bench_fitting.cpp), a SciPy
# least-squares fit and a genetic algorithm (studies/compare/README.md). Installs nothing:
# it needs Debian's python3-numpy and python3-scipy and stops if they are missing.
#
#   bash studies/compare/run.sh            # results and the table in build/compare/
#
# Environment: BUILD (build directory, default build), OUT (default $BUILD/compare),
# REPEATS (C++ benchmark repetitions, default 5), SCIPY_WHOLE_MAX_NFEV (default 6),
# GA_POPULATION (40), GA_GENERATIONS (50), SKIP_BUILD=1 to use the binaries as they are.
set -euo pipefail

# Debian's interpreter: the python3 first on PATH may be another build without Debian's
# numpy and scipy.
PY=/usr/bin/python3
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
BUILD="${BUILD:-$root/build}"
OUT="${OUT:-$BUILD/compare}"
REPEATS="${REPEATS:-5}"

if ! "$PY" -c 'import numpy, scipy' 2>/dev/null; then
  echo "run.sh: $PY cannot import numpy and scipy; install the Debian packages:" >&2
  echo "  apt-get install python3-numpy python3-scipy" >&2
  exit 1
fi

if [[ "${SKIP_BUILD:-0}" != 1 ]]; then
  if [[ ! -f "$BUILD/CMakeCache.txt" ]]; then
    cmake -S "$root" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DDOORBENCH_BUILD_BENCH=ON
  fi
  cmake --build "$BUILD" -j2 --target doorbench_bench doorbench_export_fit_strokes
fi
mkdir -p "$OUT"

echo "== exporting the benchmark's strokes, truth and start; the C++ fit once"
"$BUILD/studies/doorbench_export_fit_strokes" "$OUT"

echo "== the numpy model against the C++ one (true parameters, whole strokes)"
"$PY" "$here/check_model.py" "$OUT" --out "$OUT/check_model.json"

echo "== C++: bench_fitting, $REPEATS repetitions"
"$BUILD/bench/doorbench_bench" --benchmark_filter='fit_sensory_12_strokes/0/' \
  --benchmark_repetitions="$REPEATS" --benchmark_out="$OUT/bench_fitting.json" \
  --benchmark_out_format=json
grep -q '"fit_sensory_12_strokes/0/' "$OUT/bench_fitting.json" ||
  { echo "run.sh: the C++ benchmark fit_sensory_12_strokes/0 did not run" >&2; exit 1; }

echo "== SciPy least_squares, 0.2 s windows"
"$PY" "$here/scipy_fit.py" "$OUT" --formulation windows --out "$OUT/scipy_windows.json"

echo "== SciPy least_squares, whole strokes (max_nfev ${SCIPY_WHOLE_MAX_NFEV:-6})"
"$PY" "$here/scipy_fit.py" "$OUT" --formulation whole --max-nfev "${SCIPY_WHOLE_MAX_NFEV:-6}" \
  --out "$OUT/scipy_whole.json"

echo "== genetic algorithm, the study's objective"
"$PY" "$here/ga_fit.py" "$OUT" --population "${GA_POPULATION:-40}" \
  --generations "${GA_GENERATIONS:-50}" --out "$OUT/ga.json"

echo "== side by side (machine load: $(cut -d' ' -f1-3 /proc/loadavg))"
"$PY" "$here/table.py" "$OUT" | tee "$OUT/table.txt"

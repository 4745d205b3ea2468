#!/usr/bin/python3
"""Checks that the numpy model and integrator (sensory.py) agree with doorbench's: replays
every whole stroke at the TRUE parameters from its first measured state under the measured
force and compares with cpp_replay.csv, written by doorbench_export_fit_strokes with the
fit's RK4 (analysis/fit/fit_windows.h, the same scheme) and with the adaptive Dormand-Prince
simulator (analysis/simulation/simulator.h, a different scheme: its difference is integrator error).

Usage: check_model.py DATA_DIR [--out FILE]; exits 1 when the two RK4 replays differ by
more than LIMIT anywhere.
"""

import argparse
import csv
import json
import os
import sys

import numpy as np

import sensory

LIMIT = 1e-9  # rad/s: far above rounding (1e-14 measured), far below any fit error


def read_replay(path):
    out = {}
    with open(path) as f:
        for row in csv.DictReader(line for line in f if not line.startswith("#")):
            s = out.setdefault(int(row["stroke"]), {c: [] for c in row if c != "stroke"})
            for c in s:
                s[c].append(float(row[c]))
    return {k: {c: np.array(v) for c, v in s.items()} for k, s in out.items()}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data")
    parser.add_argument("--out")
    args = parser.parse_args()
    data = sensory.Data(args.data)
    cpp = read_replay(os.path.join(args.data, "cpp_replay.csv"))
    theta, omega = sensory.integrate(data.truth, data.whole, data.r_h, data.theta_max)

    rows = []
    for m, sid in enumerate(data.ids):
        n = len(cpp[sid]["time_s"])
        c = cpp[sid]
        # Where the two RK4 replays first part by more than 1e-9 rad/s (None: never).
        diff = np.abs(omega[m, :n] - c["rk4_rate_rad_s"])
        apart = np.nonzero(diff > 1e-9)[0]
        rows.append({
            "stroke": sid,
            "rk4_max_rate_diff_rad_s": float(diff.max()),
            "rk4_max_angle_diff_rad": float(np.abs(theta[m, :n] - c["rk4_angle_rad"]).max()),
            "rk4_parts_at_s": float(c["time_s"][apart[0]]) if len(apart) else None,
            "dp5_max_rate_diff_rad_s": float(np.abs(omega[m, :n] - c["dp5_rate_rad_s"]).max()),
        })

    print(f"{'stroke':>6} {'max |dω| RK4':>14} {'max |dθ| RK4':>14} {'parts at':>9} "
          f"{'max |dω| vs DP5':>16}")
    for r in rows:
        at = "never" if r["rk4_parts_at_s"] is None else f"{r['rk4_parts_at_s']:.3f} s"
        print(f"{r['stroke']:>6} {r['rk4_max_rate_diff_rad_s']:>14.3g} "
              f"{r['rk4_max_angle_diff_rad']:>14.3g} {at:>9} {r['dp5_max_rate_diff_rad_s']:>16.3g}")
    worst = max(r["rk4_max_rate_diff_rad_s"] for r in rows)
    print(f"largest |omega difference| against the C++ RK4: {worst:.3g} rad/s "
          f"(limit {LIMIT:g})")

    if args.out:
        with open(args.out, "w") as f:
            json.dump({"strokes": rows}, f, indent=1)
    return 0 if worst <= LIMIT else 1


if __name__ == "__main__":
    sys.exit(main())

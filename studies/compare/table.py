#!/usr/bin/python3
"""Prints the side-by-side table of the comparison from the files run.sh leaves in its
output directory: the C++ benchmark's Google Benchmark JSON (bench_fitting.json), the C++
fit's result (cpp_fit.json) and the Python fits' results (scipy_*.json, ga.json).

Every row's RMSE and largest error are computed here by the same numpy code
(sensory.metrics): whole strokes replayed from their first measured state (the study's
figure) and 0.2 s windows started from the measured states. The truth's row is the floor
that the noise leaves.

Usage: table.py OUT_DIR [--markdown]
"""

import argparse
import json
import os
import statistics
import sys

import sensory


def cpp_row(directory, data):
    with open(os.path.join(directory, "bench_fitting.json")) as f:
        runs = [b for b in json.load(f)["benchmarks"]
                if b["name"].startswith("fit_sensory_12_strokes/0") and
                b.get("run_type") == "iteration"]
    times = [b["real_time"] / 1e3 for b in runs]  # ms -> s
    with open(os.path.join(directory, "cpp_fit.json")) as f:
        fit = json.load(f)
    p = [fit["values"][n] for n in sensory.NAMES]
    row = sensory.report("doorbench (C++, Ceres, windows)", p, data, statistics.median(times),
                         None)
    row["cpu_s"] = fit["cpu_s"]  # one run (the export's), every thread
    row["repeats"] = len(times)
    row["spread_s"] = (min(times), max(times))
    row["evaluations_text"] = (f"{fit['equation_error_iterations']} + "
                               f"{fit['window_iterations']} LM iterations")
    return row


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out")
    parser.add_argument("--markdown", action="store_true")
    args = parser.parse_args()
    data = sensory.Data(args.out)

    rows = [cpp_row(args.out, data)]
    for name in ("scipy_whole.json", "scipy_windows.json", "ga.json"):
        path = os.path.join(args.out, name)
        if os.path.exists(path):
            with open(path) as f:
                rows.append(json.load(f))
    truth = sensory.report("(the true parameters)", data.truth, data, None, None)

    header = ["method", "wall time", "CPU time", "evaluations", "RMSE ω replay", "max |ω err| replay",
              "RMSE ω windows", "max |ω err| windows", "largest parameter error"]
    lines = []
    for r in rows + [truth]:
        m = r["metrics"]
        if r["wall_s"] is None:
            wall = "–"
        elif "repeats" in r:
            wall = f"{r['wall_s']:.2f} s (median of {r['repeats']})"
        else:
            wall = f"{r['wall_s']:.1f} s"
        cpu = "–" if r.get("cpu_s") is None else f"{r['cpu_s']:.1f} s"
        if "evaluations_text" in r:
            evaluations = r["evaluations_text"]
        elif r["evaluations"] is None:
            evaluations = "–"
        else:
            evaluations = f"{r['evaluations']} simulations"
        largest = "–" if r is truth else (
            f"{r['largest_error_percent']:.1f}% ({r['largest_error_parameter']})"
            + (" invalid door" if r["constraint_breaks"] else ""))
        lines.append([r["method"], wall, cpu, evaluations,
                      f"{m['replay']['rmse_rad_s']:.3f}", f"{m['replay']['max_abs_rad_s']:.2f}",
                      f"{m['windows']['rmse_rad_s']:.4f}", f"{m['windows']['max_abs_rad_s']:.3f}",
                      largest])

    if args.markdown:
        print("| " + " | ".join(header) + " |")
        print("|" + "---|" * len(header))
        for line in lines:
            print("| " + " | ".join(line) + " |")
    else:
        widths = [max(len(x) for x in col) for col in zip(header, *lines)]
        for line in [header] + lines:
            print("  ".join(x.ljust(w) for x, w in zip(line, widths)))
    print()
    print("Parameter errors (%) against the truth:")
    names = [sensory.NAMES[i] for i in data.free]
    print("method".ljust(40) + "".join(n.rjust(8) for n in names))
    for r in rows:
        print(r["method"][:39].ljust(40) +
              "".join(f"{r['error_percent'][n]:8.2f}" for n in names))
    return 0


if __name__ == "__main__":
    sys.exit(main())

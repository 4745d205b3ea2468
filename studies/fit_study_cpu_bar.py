#!/usr/bin/env python3
"""Issue 42's CPU bar at --folds 0, read off doorbench_fit_study's CSV lines: "today's" fits at
--folds 0, 3 and 4 (TODAY.csv) and the fits now at --folds F (NOW.csv). For each recording:
whether today's --folds 0 fit already ends at today's best cost of the three (within 0.1 %);
where it does not, which --folds reached it and the CPU of the cheapest that did, against
today's --folds 0; and the CPU now against today's --folds 0. Then the counts the bar turns on:
the recordings over 3x, split by whether today's --folds 0 was already at the best (the search
then only confirms the optimum) or not (the search must find a basin that today's --folds 0
missed, and today's own fits paid the cheapest ratio shown for it).

    fit_study_cpu_bar.py TODAY.csv NOW.csv [--folds F]   (F: 0 unless given)

Only the lines of the fits from the data (start "data") are read. A recording missing from
NOW.csv is listed without its ratio.
"""
import csv
import statistics
import sys

BAR = 3.0          # the "at most 3x today's CPU"
SAME_COST = 1e-3   # relative: within 0.1 % of the best cost is "at the best"


def fits_from_data(path):
    """{recording: {folds: (cpu_s, cost)}} of the fits from the data."""
    out = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            if row["start"] != "data":
                continue
            out.setdefault(row["recording"], {})[row["folds"]] = (
                float(row["cpu_s"]), float(row["final_cost"]))
    return out


def main(argv):
    args = [a for a in argv if a != "--folds"]
    folds = "0"
    if "--folds" in argv:
        i = argv.index("--folds")
        if i + 1 >= len(argv):
            sys.exit("fit_study_cpu_bar.py: --folds needs a number")
        folds = argv[i + 1]
        args.remove(folds)
    if len(args) != 2:
        sys.exit(__doc__.split("\n\n")[1].strip())
    today, now = fits_from_data(args[0]), fits_from_data(args[1])
    print("recording,today_folds0_at_best,today_folds0_above_best_percent,reached_by_folds,"
          "cheapest_reaching_vs_today_folds0,now_vs_today_folds0")
    ratios, over_at_best, over_missed, missed_costly = [], [], [], []
    for name, runs in today.items():
        if "0" not in runs:
            continue
        cpu0_s, cost0 = runs["0"]
        best = min(cost for _, cost in runs.values())
        at_best = cost0 <= best * (1 + SAME_COST)
        reached = sorted(f for f, (_, cost) in runs.items() if cost <= best * (1 + SAME_COST))
        cheapest = min(runs[f][0] for f in reached) / cpu0_s
        ratio = now[name][folds][0] / cpu0_s if folds in now.get(name, {}) else None
        print(f"{name},{'yes' if at_best else 'no'},{100 * (cost0 / best - 1):.1f},"
              f"{' '.join(reached)},{cheapest:.2f},{'' if ratio is None else f'{ratio:.2f}'}")
        if not at_best and cheapest > BAR:
            missed_costly.append(name)
        if ratio is None:
            continue
        ratios.append(ratio)
        if ratio > BAR:
            (over_at_best if at_best else over_missed).append(name)
    if not ratios:
        sys.exit(f"fit_study_cpu_bar.py: no recording of {args[0]} has a --folds {folds} fit "
                 f"from the data in {args[1]}")
    print(f"# {len(ratios)} recordings: CPU now against today's --folds 0, median "
          f"{statistics.median(ratios):.2f}x, max {max(ratios):.2f}x; "
          f"{len(over_at_best) + len(over_missed)} over {BAR:g}x")
    print(f"# over {BAR:g}x where today's --folds 0 was already at the best: "
          f"{len(over_at_best)} ({' '.join(over_at_best)})")
    print(f"# over {BAR:g}x where today's --folds 0 missed the best: "
          f"{len(over_missed)} ({' '.join(over_missed)})")
    print(f"# recordings where today's own cheapest fit that reaches the best costs over "
          f"{BAR:g}x today's --folds 0: {len(missed_costly)} ({' '.join(missed_costly)})")


if __name__ == "__main__":
    main(sys.argv[1:])

#!/usr/bin/env python3
"""The tables of docs/residual-loop.md, "What the data allow", from the CSV lines of
doorbench_breakaway_oracle (studies/breakaway_oracle.cpp): by hand, rate and sensor set, how
many breakaway recordings the loop names and the refit from the true values qualifies under
the loop's rule (with the Wilson 95 % interval), how many clean ones either would add, and
how far each acceptance statistic alone can separate the two.

    breakaway_oracle_table.py FILE.csv
    breakaway_oracle_table.py --known KNOWN.csv   (the lines of doorbench_breakaway_oracle
        --known, no header): by hand, sensor set and rate, the draws where 1.5 N·m / u
        reaches the 2.93 a one-sided 5 % test needs for 90 % power, with the door's
        parameters free, with the door known (d_s and w_s fitted) and with w_s known too
"""
import csv
import math
import sys
from statistics import NormalDist

# One-sided 5 % level plus 90 % power: the expected z a test needs (1.645 + 1.282).
NEEDED_Z = 1.6449 + 1.2816
EXCESS_N_M = 1.5  # the breakaway friction, d_s - d1


def wilson(k, n, z=1.96):
    if n == 0:
        return (math.nan, math.nan)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def share(k, n):
    low, high = wilson(k, n)
    return f"{k}/{n} ({100 * k / n:.0f} %, {100 * low:.0f}-{100 * high:.0f} %)"


def rows_of(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        for key in ("rate_hz", "held_out_fall", "amplitude_z", "amplitude_u_N_m"):
            r[key] = float(r[key])
        r["qualifies"] = r["qualifies"] == "1"
    return rows


def group_table(rows, key_of, title):
    groups = {}
    for r in rows:
        groups.setdefault(key_of(r), []).append(r)
    print(f"| {title} | breakaway: the loop names it first | the refit from the true values "
          f"qualifies | clean: the loop adds an effect | clean: the refit would be added |")
    print("|---|---|---|---|---|")
    for key in sorted(groups, key=str):
        g = groups[key]
        brk = [r for r in g if r["recording"] == "breakaway"]
        cln = [r for r in g if r["recording"] == "clean"]
        named = sum(1 for r in brk if r["loop_first"] == "stribeck")
        added = sum(1 for r in cln if r["loop_first"] != "none")
        print(f"| {key} | {share(named, len(brk))} | "
              f"{share(sum(r['qualifies'] for r in brk), len(brk))} | {share(added, len(cln))} | "
              f"{share(sum(r['qualifies'] for r in cln), len(cln))} |")
    print()


def loop_against_refit(rows):
    """Draws where the loop and the refit from the true values disagree."""
    brk = [r for r in rows if r["recording"] == "breakaway"]
    missed = [r["draw"] for r in brk if r["qualifies"] and r["loop_first"] != "stribeck"]
    beyond = [r["draw"] for r in brk if not r["qualifies"] and r["loop_first"] == "stribeck"]
    print(f"The refit qualifies but the loop does not name it: {len(missed)} draws "
          f"({' '.join(missed) or '-'}); the loop names it where the refit does not qualify: "
          f"{len(beyond)} ({' '.join(beyond) or '-'})\n")


def separation(rows, statistic, label, refuse_bound=True):
    """The threshold on one statistic that finds 90 % of the breakaway recordings, and the
    share of clean recordings it would pass; refits with a parameter at a bound or
    undetermined are refused first, as the loop does."""
    def value(r):
        refused = refuse_bound and r["bound_or_undetermined"] == "1"
        return -math.inf if refused else statistic(r)
    brk = sorted(value(r) for r in rows if r["recording"] == "breakaway")
    cln = [value(r) for r in rows if r["recording"] == "clean"]
    threshold = brk[int(math.floor(0.1 * len(brk)))]  # 90 % of breakaway at or above
    if threshold == -math.inf:
        print(f"| {label} | none (too many refits at a bound or undetermined) | - |")
        return
    passed = sum(1 for v in cln if v >= threshold)
    print(f"| {label} | {threshold:.3g} | {share(passed, len(cln))} |")


def known_table(path):
    groups = {}
    with open(path, newline="") as f:
        for draw, hand, rate, sensors, *us in csv.reader(f):
            for key in ("all", hand, f"{hand}, {sensors}", f"{hand}, {int(float(rate))} Hz"):
                groups.setdefault(key, []).append([float(u) for u in us])
    print(f"| draws | 1.5 N·m / u ≥ {NEEDED_Z:.2f}: the door's parameters free | the door known "
          f"(d_s and w_s fitted) | w_s known too | median u: door free, door known (N·m) |")
    print("|---|---|---|---|---|")
    for key in sorted(groups, key=lambda k: (k != "all", k)):
        g = groups[key]
        counts = [sum(1 for us in g if EXCESS_N_M / us[i] >= NEEDED_Z) for i in range(3)]
        medians = [sorted(us[i] for us in g)[len(g) // 2] for i in range(2)]
        print(f"| {key} | " + " | ".join(share(k, len(g)) for k in counts) +
              f" | {medians[0]:.3g}, {medians[1]:.3g} |")
    print()
    for i, label in enumerate(("the door's parameters free", "the door known", "w_s known too")):
        mean, low, high = expected_power([us[i] for us in groups["all"]])
        print(f"- {label}: a one-sided 5 % test on d_s finds it in {100 * mean:.1f} % of the "
              f"draws on average ({100 * low:.1f}-{100 * high:.1f} %)")


def expected_power(uncertainties):
    """The mean over draws of a one-sided 5 % z-test's power, Φ(1.5 / u − 1.645) (5 %, the
    level, where u is not finite), with a normal 95 % interval over the draws."""
    normal = NormalDist()
    powers = [normal.cdf(EXCESS_N_M / u - 1.6449) if math.isfinite(u) and u > 0 else 0.05
              for u in uncertainties]
    n = len(powers)
    mean = sum(powers) / n
    sd = math.sqrt(sum((p - mean) ** 2 for p in powers) / (n - 1)) if n > 1 else 0.0
    half = 1.96 * sd / math.sqrt(n)
    return mean, max(0.0, mean - half), min(1.0, mean + half)


def main():
    if sys.argv[1] == "--known":
        known_table(sys.argv[2])
        return
    rows = rows_of(sys.argv[1])
    draws = len({r["draw"] for r in rows})
    print(f"{draws} draws\n")
    group_table(rows, lambda r: "all", "draws")
    loop_against_refit(rows)
    group_table(rows, lambda r: r["hand"], "hand")
    group_table(rows, lambda r: f"{r['hand']}, {r['sensors']}", "hand, sensors")
    group_table(rows, lambda r: f"{r['hand']}, {int(r['rate_hz'])} Hz", "hand, rate")
    brk = [r for r in rows if r["recording"] == "breakaway"]
    bound = sum(1 for r in brk if r["bound_or_undetermined"] == "1")
    print(f"Breakaway refits with a parameter at a bound or undetermined (refused by the "
          f"loop): {share(bound, len(brk))}\n")
    print("| statistic | threshold that passes 90 % of the breakaway recordings | "
          "clean recordings it passes |")
    print("|---|---|---|")
    separation(rows, lambda r: r["held_out_fall"], "held-out RMSE fall")
    separation(rows, lambda r: r["amplitude_z"], "amplitude z")
    separation(rows, lambda r: -float(r["bic_change"]), "BIC fall")
    for statistic, label in ((lambda r: r["held_out_fall"], "held-out RMSE fall"),
                             (lambda r: r["amplitude_z"], "amplitude z"),
                             (lambda r: -float(r["bic_change"]), "BIC fall")):
        separation(rows, statistic, label + ", refits at a bound accepted", refuse_bound=False)


if __name__ == "__main__":
    main()

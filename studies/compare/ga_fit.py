#!/usr/bin/python3
"""Fits the sensory model to the benchmark's 12 strokes the way the study did: a genetic
algorithm minimizing the largest |omega_meas - omega_sim| over the whole strokes, each
simulated from its first measured state under the measured force.

A plain real-coded GA, hand-written as the study's was (not differential_evolution):
genes are the 13 free parameters in units of the parameter file's bounds (0 = lower,
1 = upper); tournament selection (3), blend crossover BLX-0.5 (probability 0.9),
Gaussian mutation (each gene with probability 1/13, sigma 0.02 of the bound width),
elitism (the 2 best survive), a fixed seed. The first population is the 30%-off start
and individuals scattered around it (each parameter times a uniform 0.5-1.5), clipped to
the bounds. Children are repaired into valid doors: the latch angles sorted, d2 <= d1.
The whole population is simulated at once (numpy over individuals and strokes).

Usage: ga_fit.py DATA_DIR [--population N] [--generations N] [--seed N] [--out FILE]
"""

import argparse
import json
import sys
import time

import numpy as np

import sensory


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data")
    parser.add_argument("--population", type=int, default=40)
    parser.add_argument("--generations", type=int, default=60)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out", help="write the result as JSON here")
    args = parser.parse_args()

    data = sensory.Data(args.data)
    rng = np.random.default_rng(args.seed)
    free = data.free
    lower, upper = data.lower[free], data.upper[free]
    width = upper - lower
    names = [sensory.NAMES[i] for i in free]
    latch = [names.index(n) for n in ("theta0", "theta1", "theta2", "theta3")]
    d1, d2 = names.index("d1"), names.index("d2")
    n_genes, n_pop = len(free), args.population
    evaluations = 0

    def repair(genes):
        genes = np.clip(genes, 0.0, 1.0)
        values = lower + genes * width
        values[:, latch] = np.sort(values[:, latch], axis=1)
        values[:, d2] = np.minimum(values[:, d2], values[:, d1])
        return (values - lower) / width

    def fitness(genes):
        """The study's objective for every individual: max |omega error| (lower is better)."""
        nonlocal evaluations
        evaluations += len(genes)
        p = data.full(lower + genes * width)
        errors = sensory.omega_errors(p, data, data.whole)  # (individuals, samples)
        return np.nan_to_num(np.max(np.abs(errors), axis=1), nan=np.inf)

    def tournament(cost, k=3):
        picks = rng.integers(0, n_pop, size=(n_pop, k))
        return picks[np.arange(n_pop), np.argmin(cost[picks], axis=1)]

    start = (data.start[free] - lower) / width
    scatter = data.start[free] * rng.uniform(0.5, 1.5, size=(n_pop - 1, n_genes))
    population = repair(np.vstack([start, (scatter - lower) / width]))

    begin, cpu_begin = time.perf_counter(), time.process_time()
    cost = fitness(population)
    history = [float(cost.min())]
    for _ in range(args.generations):
        elite = population[np.argsort(cost)[:2]]
        parents = population[tournament(cost)]
        mothers, fathers = parents[0::2], parents[1::2]
        # BLX-0.5: each child gene uniform on the parents' interval widened by half its length.
        low, high = np.minimum(mothers, fathers), np.maximum(mothers, fathers)
        spread = 0.5 * (high - low)
        children = rng.uniform(low - spread, high + spread, size=(2,) + low.shape)
        crossed = rng.random(len(mothers)) < 0.9
        children[:, ~crossed] = np.stack([mothers, fathers])[:, ~crossed]
        children = children.reshape(-1, n_genes)[:n_pop - len(elite)]
        mutate = rng.random(children.shape) < 1.0 / n_genes
        children = children + mutate * rng.normal(0.0, 0.02, size=children.shape)
        population = np.vstack([elite, repair(children)])
        cost = fitness(population)
        history.append(float(cost.min()))
    wall_s = time.perf_counter() - begin
    cpu_s = time.process_time() - cpu_begin

    best = population[np.argmin(cost)]
    p = data.full(lower + best * width)
    out = sensory.report("Genetic algorithm (study's objective)", p, data, wall_s, evaluations, {
        "cpu_s": cpu_s,
        "population": n_pop, "generations": args.generations, "seed": args.seed,
        "best_objective_by_generation": history})
    print(json.dumps({k: out[k] for k in ("method", "wall_s", "cpu_s", "evaluations",
                                            "largest_error_percent", "largest_error_parameter",
                                            "metrics")}, indent=1))
    print("best max|omega error| every 10 generations:",
          " ".join(f"{c:.3f}" for c in history[::10]))
    if args.out:
        with open(args.out, "w") as f:
            json.dump(out, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Checks `doorbench model torque` against an independent, high-precision implementation
of door-models.md (§2, §3, §3.1), written from the spec's formulas as printed, in mpmath.

Usage: check_model_torque.py DOORBENCH DOOR_JSON WORK_DIR [--points N] [--seed S]
Passes when every tau_Nm agrees to 1e-9 relative (or to 1e-100 N*m absolute, below the
reference's own precision), at points concentrated on the latch switches.
"""
import argparse
import csv
import json
import os
import random
import subprocess
import sys

import mpmath as mp

mp.mp.dps = 120
GRAVITY = mp.mpf("9.80665")


def load_door(path):
    with open(path) as f:
        door = json.load(f)
    values = lambda section: {k: mp.mpf(repr(v["value"])) for k, v in door[section].items()}
    return mp.mpf(repr(door["theta_max_rad"])), values("sensory"), values("physical")


def S(x, x0, beta):
    return (1 + mp.tanh(beta * (x - x0))) / 2


def Sbar(x, x0, beta):
    return 1 - S(x, x0, beta)


def W(x, a, b, beta):
    return S(x, a, beta) - S(x, b, beta)


def end_stops(theta, omega, k_stop, c_stop, theta_max):
    if theta > theta_max:
        return -(k_stop * (theta - theta_max) + c_stop * omega)
    if theta < 0:
        return -(k_stop * theta + c_stop * omega)
    return mp.mpf(0)


def sensory_torque(p, theta_max, theta, omega):
    unlatch = -(p["k"] * theta + p["k_inf"] * (theta - p["theta0"]) * S(theta, p["theta0"], p["beta"])) \
        * Sbar(theta, p["theta1"], p["beta"])
    snap = p["c"] * omega * W(theta, p["theta1"], p["theta2"], p["beta"])
    latch = p["k_lock"] * (p["theta3"] - theta) * W(theta, p["theta2"], p["theta3"], p["beta"])
    friction = -mp.tanh(p["s"] * omega) * (p["d1"] - p["d2"] * Sbar(theta, p["theta4"], p["beta_f"]))
    return unlatch + snap + latch + friction + end_stops(theta, omega, p["k_stop"], p["c_stop"], theta_max)


def physical_torque(p, theta_max, theta, omega):
    gravity = p["m_d"] * GRAVITY * p["l_c"] * mp.sin(theta)
    b_x = p["B_u"] * mp.sin(theta) + p["B_v"] * mp.cos(theta)
    b_y = p["B_u"] * mp.cos(theta) - p["B_v"] * mp.sin(theta)
    d_x, d_y = p["A_x"] - b_x, p["A_y"] - b_y
    length = mp.sqrt(d_x ** 2 + d_y ** 2)
    tension = p["F0"] + p["k_s"] * (length - p["L0"]) if length >= p["L0"] else mp.mpf(0)
    spring = -(b_x * tension * d_y / length - b_y * tension * d_x / length)
    hinge = -p["T_h"] * mp.tanh(omega / p["w_f"]) - p["b_h"] * omega
    guide = -p["mu_g"] * tension * mp.tanh(omega / p["w_f"])
    e = p["e"]
    tan_o, tan_c = mp.tan(p["alpha_o"]), mp.tan(p["alpha_c"])
    x1 = p["h"] / tan_o
    x2 = x1 + p["h"] / tan_c
    softmin = lambda a, b: -e * mp.log(mp.exp(-a / e) + mp.exp(-b / e))
    softplus = lambda z: e * mp.log(1 + mp.exp(z / e))
    cam = lambda x: softplus(softmin(x * tan_o, (x2 - x) * tan_c))
    travel = p["r_l"] * theta
    slope = mp.diff(cam, travel)
    normal = (p["F_l0"] + p["k_l"] * cam(travel)) * W(travel, 0, x2, 1 / e)
    m = p["mu_l"] * mp.tanh(omega / p["w_f"])
    latch = p["r_l"] * (-normal * (slope + m) / (1 - slope * m))
    seal = p["k_seal"] * (p["theta_seal"] - theta) if theta < p["theta_seal"] else mp.mpf(0)
    stops = end_stops(theta, omega, p["k_stop"], p["c_stop"], theta_max)
    return gravity + spring + hinge + guide + latch + seal + stops


def grid_points(count, seed):
    rng = random.Random(seed)
    points = []
    for _ in range(count):
        r = rng.random()
        if r < 0.4:
            theta = rng.uniform(-0.005, 0.07)  # the latch switches
        elif r < 0.5:
            theta = rng.uniform(-0.05, 0.0)  # the cabinet
        elif r < 0.6:
            theta = rng.uniform(1.5, 1.65)  # the open stop
        else:
            theta = rng.uniform(-0.05, 1.7)
        omega = rng.choice([0.0, rng.uniform(-3, 3), rng.uniform(-0.05, 0.05)])
        points.append((theta, omega))
    return points


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("doorbench")
    parser.add_argument("door_json")
    parser.add_argument("work_dir")
    parser.add_argument("--points", type=int, default=400)
    parser.add_argument("--seed", type=int, default=20261121)
    args = parser.parse_args()
    os.makedirs(args.work_dir, exist_ok=True)
    theta_max, sensory, physical = load_door(args.door_json)
    points = grid_points(args.points, args.seed)
    grid_path = os.path.join(args.work_dir, "grid.csv")
    with open(grid_path, "w") as f:
        f.write("theta_rad,omega_rad_s\n")
        f.writelines(f"{theta!r},{omega!r}\n" for theta, omega in points)
    failures = 0
    for model, parameters, torque in (("sensory", sensory, sensory_torque),
                                      ("physical", physical, physical_torque)):
        out_path = os.path.join(args.work_dir, f"torque_{model}.csv")
        # --overwrite: the work folder is the build's, kept from the run before.
        subprocess.run([args.doorbench, "model", "torque", "--model", model, "--params",
                        args.door_json, "--in", grid_path, "--out", out_path, "--overwrite"],
                       check=True)
        with open(out_path) as f:
            rows = list(csv.reader(line for line in f if not line.startswith("#")))
        column = rows[0].index("tau_Nm")
        worst = 0.0
        for (theta, omega), row in zip(points, rows[1:]):
            expected = torque(parameters, theta_max, mp.mpf(theta), mp.mpf(omega))
            got = mp.mpf(row[column])
            error = abs(got - expected)
            relative = error / abs(expected) if expected != 0 else (0 if got == 0 else mp.inf)
            if error > 1e-100:
                worst = max(worst, float(relative))
            if relative > 1e-9 and error > 1e-100:
                failures += 1
                print(f"{model}: theta={theta!r} omega={omega!r}: doorbench {row[column]}, "
                      f"spec {mp.nstr(expected, 20)}, relative error {mp.nstr(relative, 3)}")
        print(f"{model}: {len(points)} points, worst relative error {worst:.2e}")
    print(f"{len(points) * 2 - failures} passed, {failures} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

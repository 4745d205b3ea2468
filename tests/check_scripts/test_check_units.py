#!/usr/bin/env python3
"""A test of scripts/check_units.py: it passes on this repository, and a local degree
constant (a `kDeg` of either meaning, a pi/180 under another name, a #define) or a local NaN
constant makes it fail naming the file and the line.

usage: test_check_units.py SOURCE_DIR
"""
import os
import shutil
import subprocess
import sys
import tempfile

source_dir = os.path.abspath(sys.argv[1])
check = os.path.join(source_dir, "scripts", "check_units.py")


def run(tree):
    return subprocess.run([sys.executable, check, tree], capture_output=True, text=True)


def expect(condition, message, result):
    if not condition:
        print(f"FAILED: {message}\n--- stdout\n{result.stdout}\n--- stderr\n{result.stderr}")
        sys.exit(1)


clean = run(source_dir)
expect(clean.returncode == 0, "the repository passes the units check", clean)

with tempfile.TemporaryDirectory() as tree:
    for folder in ["core", "analysis", "sensors"]:
        shutil.copytree(os.path.join(source_dir, folder), os.path.join(tree, folder))
    added = {
        "analysis/design/felt_quantities.cpp": "constexpr double kDeg = 180.0 / std::numbers::pi;",
        "analysis/model/effects.cpp": "const double to_rad = M_PI / 180;",
        "sensors/rig_channel.cpp": "#define DEG (3.14159265358979 / 180.0)",
    }
    for relative, line in added.items():
        path = os.path.join(tree, *relative.split("/"))
        lines = open(path, encoding="utf-8").read().split("\n")
        lines.insert(1, line)
        open(path, "w", encoding="utf-8").write("\n".join(lines))
    faulty = run(tree)
    expect(faulty.returncode == 1, "a local degree constant fails the check", faulty)
    for relative, line in added.items():
        expect(f"{relative}:2: defines a degree constant ({line}); use kRadPerDeg or kDegPerRad "
               "from core/units.h" in faulty.stdout, f"the failure names {relative}:2", faulty)
    expect("check_units: 3 local degree constant(s)" in faulty.stdout, "the count", faulty)
    expect("NaN" not in faulty.stdout, "no NaN constant reported where there is none", faulty)

    nan_line = "constexpr double kMissing = std::numeric_limits<double>::quiet_NaN();"
    path = os.path.join(tree, "analysis", "model", "door_model.cpp")
    lines = open(path, encoding="utf-8").read().split("\n")
    lines.insert(2, nan_line)
    open(path, "w", encoding="utf-8").write("\n".join(lines))
    faulty = run(tree)
    expect(f"analysis/model/door_model.cpp:3: defines a NaN constant ({nan_line}); use kNaN "
           "from core/numbers.h" in faulty.stdout, "the failure names door_model.cpp:3", faulty)
    expect("check_units: 1 local NaN constant(s)" in faulty.stdout, "the NaN count", faulty)

print("test_check_units: passed")

#!/usr/bin/env python3
"""A test of scripts/check_units.py: it passes on this repository, and a local degree
constant (a `kDeg` of either meaning, a pi/180 under another name, a #define), a degree
conversion written inline (180/pi, pi/180, 57.29..., 0.01745...) or a local NaN constant makes
it fail naming the file and the line.

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


def copy_folders(tree, folders):
    for folder in folders:
        shutil.copytree(os.path.join(source_dir, folder), os.path.join(tree, folder))


def insert_lines(tree, relative, new_lines, at=1):
    """Inserts `new_lines` into the copy of `relative` before its line `at` + 1."""
    path = os.path.join(tree, *relative.split("/"))
    lines = open(path, encoding="utf-8").read().split("\n")
    lines[at:at] = new_lines
    open(path, "w", encoding="utf-8").write("\n".join(lines))


def expect_each_named(result, added, what):
    """Every line of `added` (inserted as line 2 of its file) is reported as `what`."""
    for relative, line in added.items():
        expect(f"{relative}:2: {what} ({line.strip()}); use kRadPerDeg or kDegPerRad from "
               "core/units.h" in result.stdout, f"the failure names {relative}:2", result)


clean = run(source_dir)
expect(clean.returncode == 0, "the repository passes the units check", clean)

with tempfile.TemporaryDirectory() as tree:
    copy_folders(tree, ["core", "analysis", "sensors"])
    added = {
        "analysis/design/felt_quantities.cpp": "constexpr double kDeg = 180.0 / std::numbers::pi;",
        "analysis/model/effects.cpp": "const double to_rad = M_PI / 180;",
        "sensors/rig_channel.cpp": "#define DEG (3.14159265358979 / 180.0)",
    }
    for relative, line in added.items():
        insert_lines(tree, relative, [line])
    faulty = run(tree)
    expect(faulty.returncode == 1, "a local degree constant fails the check", faulty)
    expect_each_named(faulty, added, "defines a degree constant")
    expect("check_units: 3 local degree constant(s)" in faulty.stdout, "the count", faulty)
    expect("NaN" not in faulty.stdout, "no NaN constant reported where there is none", faulty)

    nan_line = "constexpr double kMissing = std::numeric_limits<double>::quiet_NaN();"
    insert_lines(tree, "analysis/model/door_model.cpp", [nan_line], at=2)
    faulty = run(tree)
    expect(f"analysis/model/door_model.cpp:3: defines a NaN constant ({nan_line}); use kNaN "
           "from core/numbers.h" in faulty.stdout, "the failure names door_model.cpp:3", faulty)
    expect("check_units: 1 local NaN constant(s)" in faulty.stdout, "the NaN count", faulty)

with tempfile.TemporaryDirectory() as tree:
    copy_folders(tree, ["core", "analysis", "app"])
    added = {
        "app/play_run.cpp": "  out << angle_rad * 180.0 / M_PI << \" deg\";",
        "app/simulate_command.cpp": "  hand.target_angle_rad = target_deg * std::numbers::pi / 180;",
        "app/calibrate_command.cpp": "  record.per_deg = slope / std::numbers::pi * 180.0;",
        "analysis/design/tolerance_analysis.cpp": "    {\"alpha_o\", 0.01745, false},",
        "analysis/model/effects.cpp": "  return degrees(x) * 57.2958;",
    }
    for relative, line in added.items():
        insert_lines(tree, relative, [line])
    # Not conversions: a half turn, a comment, a whole circle.
    insert_lines(tree, "analysis/model/door_model.cpp",
                 ["  const double half_turn_rad = std::numbers::pi;  // 180 degrees / pi",
                  "  const double turn = 2.0 * M_PI * 180.5;"])
    faulty = run(tree)
    expect(faulty.returncode == 1, "an inline degree conversion fails the check", faulty)
    expect_each_named(faulty, added, "converts degrees inline")
    expect("check_units: 5 inline degree conversion(s)" in faulty.stdout, "the count", faulty)
    expect("door_model.cpp" not in faulty.stdout, "pi alone is not a conversion", faulty)

print("test_check_units: passed")

#!/usr/bin/env python3
"""Fails on a degree constant defined anywhere but core/units.h (docs/architecture.md, "One
home for units and numbers"): `kDeg` once meant pi/180 in one file and 180/pi in three others.

usage: check_units.py [SOURCE_DIR]   (default: the repository this script is in)

Reported, as `FILE:LINE: defines a degree constant (...); use kRadPerDeg or kDegPerRad from
core/units.h`: a declaration (constexpr, const, #define) whose value divides by or into 180
and pi (std::numbers::pi, M_PI or a pi literal), and any declaration of `kDeg`.

Also reported, as `FILE:LINE: defines a NaN constant (...); use kNaN from core/numbers.h`: a
named constant (kSomething) set to a quiet NaN anywhere but core/numbers.h (seventeen files had
their own kNaN, which a unity build of a library sees twice). Exit status 1 when anything is
reported.
"""
import os
import re
import sys

HOME = os.path.join("core", "units.h")
NAN_HOME = os.path.join("core", "numbers.h")
NAN = re.compile(r"\b(?:constexpr|const)\b[^;=]*\bk[A-Z]\w*\s*=\s*std::numeric_limits<double>::"
                 r"quiet_NaN\(\)")
PI = r"(?:std::numbers::pi|M_PI|3\.14159\d*|kPi)"
DEGREE = re.compile(
    r"(?:\b(?:constexpr|const)\b[^;=]*=\s*[^;]*(?:180(?:\.0*)?\s*/\s*" + PI + r"|" + PI +
    r"\s*/\s*180(?:\.0*)?)|#\s*define\s+\w+\s+\(?[^\n]*(?:180(?:\.0*)?\s*/\s*" + PI + r"|" +
    PI + r"\s*/\s*180)|\b(?:constexpr|const)\b[^;=]*\bkDeg\s*=)")
FOLDERS = ["core", "acquisition", "sensors", "calibration", "analysis", "simulated_bench",
           "viewer", "haptic", "station", "study", "app", "bench", "fuzz", "tests"]


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                           os.path.join(os.path.dirname(__file__), ".."))
    problems, nans, checked = [], [], 0
    for folder in FOLDERS:
        for directory, _, files in os.walk(os.path.join(root, folder)):
            for name in sorted(files):
                if not name.endswith((".h", ".cpp", ".cc", ".hpp", ".cpp.in")):
                    continue
                path = os.path.join(directory, name)
                relative = os.path.relpath(path, root)
                if relative in (HOME, NAN_HOME):
                    continue
                checked += 1
                with open(path, encoding="utf-8", errors="replace") as source:
                    for number, line in enumerate(source, 1):
                        code = line.split("//")[0]
                        if DEGREE.search(code):
                            problems.append(f"{relative}:{number}: defines a degree constant "
                                            f"({code.strip()}); use kRadPerDeg or kDegPerRad "
                                            "from core/units.h")
                        if NAN.search(code):
                            nans.append(f"{relative}:{number}: defines a NaN constant "
                                        f"({code.strip()}); use kNaN from core/numbers.h")
    for problem in problems + nans:
        print(problem)
    if problems:
        print(f"check_units: {len(problems)} local degree constant(s)")
    if nans:
        print(f"check_units: {len(nans)} local NaN constant(s)")
    if problems or nans:
        return 1
    print(f"check_units: {checked} files, no degree constant outside {HOME}, no NaN constant "
          f"outside {NAN_HOME}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Fails on a degree constant defined anywhere but core/units.h, or a degree conversion
written inline (docs/architecture.md, "One home for units and numbers"): a local name such as
`kDeg` can mean pi/180 or 180/pi, and only kRadPerDeg and kDegPerRad say which.

usage: check_units.py [SOURCE_DIR]   (default: the repository this script is in)

Reported, as `FILE:LINE: defines a degree constant (...); use kRadPerDeg or kDegPerRad from
core/units.h`: a declaration (constexpr, const, #define) whose value divides by or into 180
and pi (std::numbers::pi, M_PI or a pi literal), and any declaration of `kDeg`.

Also reported, as `FILE:LINE: converts degrees inline (...); use kRadPerDeg or kDegPerRad from
core/units.h`: any other line that divides by or into 180 and pi (`x * 180.0 / M_PI`,
`deg * std::numbers::pi / 180`, `x / M_PI * 180`) or writes the conversion factor as a
literal (57.29..., 0.01745...).

Also reported, as `FILE:LINE: defines a NaN constant (...); use kNaN from core/numbers.h`: a
named constant (kSomething) set to a quiet NaN anywhere but core/numbers.h (a unity build of a
library would see two). Exit status 1 when anything is reported.
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
# 180/pi or pi/180 in any order of the division (x * 180 / pi, x / pi * 180, x * pi / 180,
# x / 180 * pi), or the factor as a number: 57.29... degrees a radian, 0.01745... radians a
# degree.
ONE_EIGHTY = r"180(?:\.0*)?"
INLINE = re.compile(
    ONE_EIGHTY + r"\s*/\s*" + PI + r"|" + PI + r"\s*/\s*" + ONE_EIGHTY + r"\b|/\s*" + PI +
    r"\s*\*\s*" + ONE_EIGHTY + r"\b|/\s*" + ONE_EIGHTY + r"\s*\*\s*" + PI +
    r"|\b57\.29\d*|\b0\.01745\d*")
FOLDERS = ["core", "acquisition", "sensors", "calibration", "analysis", "simulated_bench",
           "viewer", "haptic", "station", "study", "app", "bench", "studies", "fuzz", "fixtures",
           "tests"]


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                           os.path.join(os.path.dirname(__file__), ".."))
    problems, inline, nans, checked = [], [], [], 0
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
                        elif INLINE.search(code):
                            inline.append(f"{relative}:{number}: converts degrees inline "
                                          f"({code.strip()}); use kRadPerDeg or kDegPerRad "
                                          "from core/units.h")
                        if NAN.search(code):
                            nans.append(f"{relative}:{number}: defines a NaN constant "
                                        f"({code.strip()}); use kNaN from core/numbers.h")
    for problem in problems + inline + nans:
        print(problem)
    if problems:
        print(f"check_units: {len(problems)} local degree constant(s)")
    if inline:
        print(f"check_units: {len(inline)} inline degree conversion(s)")
    if nans:
        print(f"check_units: {len(nans)} local NaN constant(s)")
    if problems or inline or nans:
        return 1
    print(f"check_units: {checked} files, no degree constant or inline degree conversion "
          f"outside {HOME}, no NaN constant outside {NAN_HOME}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

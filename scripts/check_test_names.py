#!/usr/bin/env python3
"""The test suite's guard (tests/CMakeLists.txt): every Catch2 test of the given test
executables is registered with CTest exactly once under its whole name, and none is hidden.

usage: check_test_names.py BUILD_DIR TEST_EXECUTABLE...

Fails (exit 1), one line per problem, when
  - a test name contains ';' (CMake splits it into two CTest tests, one of which runs
    nothing and "passes"),
  - a Catch2 test is hidden (a tag with a leading dot: catch_discover_tests never
    registers it, so nothing ever runs it), unless it is also tagged [child]: a step that
    a registered test runs in a process of its own (e.g. under Xvfb), not a check alone,
  - a Catch2 test is not registered, or registered more than once,
  - CTest lists a name that no executable has (a piece of a split name).
Tests added with add_test (not Catch2) are named in CTest only and are not checked.
"""
import collections
import json
import subprocess
import sys


def catch_names(executable, spec=None):
    command = [executable] + ([spec] if spec else []) + ["--list-test-names-only"]
    # Catch2 v2 exits with the number of tests listed; only a signal is an error.
    run = subprocess.run(command, capture_output=True, text=True)
    if run.returncode < 0:
        sys.exit(f"check_test_names: {executable} failed to list its tests: {run.stderr}")
    return [line for line in run.stdout.splitlines() if line.strip()]


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    build_dir, executables = sys.argv[1], sys.argv[2:]
    listing = subprocess.run(["ctest", "--test-dir", build_dir, "--show-only=json-v1"],
                             capture_output=True, text=True, check=True)
    registered = collections.Counter(t["name"] for t in json.loads(listing.stdout)["tests"]
                                     if t.get("command") and t["command"][0] in executables)
    problems = []
    expected = collections.Counter()
    hidden = set()
    for executable in executables:
        for name in catch_names(executable):
            expected[name] += 1
            if ";" in name:
                problems.append(f"{executable}: test name contains ';' (CTest splits it): {name}")
        for name in catch_names(executable, "[.]~[child]"):
            expected[name] += 1
            hidden.add(name)
            problems.append(f"{executable}: hidden test (a tag with a leading dot), never run: "
                            f"{name}")
    for name, count in sorted(expected.items()):
        if registered[name] == 0 and ";" not in name and name not in hidden:
            problems.append(f"not registered with CTest: {name}")
        elif registered[name] > count:
            problems.append(f"registered {registered[name]} times: {name}")
    for name in sorted(registered):
        if name not in expected:
            problems.append(f"CTest test that no executable has (a split name?): {name}")
    for problem in problems:
        print(problem)
    if problems:
        print(f"check_test_names: {len(problems)} problem(s)")
        return 1
    print(f"check_test_names: {sum(expected.values())} tests of {len(executables)} "
          "executables, each registered once under its whole name")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""A test of scripts/check_test_names.py against a fake Catch2 executable and a CTest
directory made here: whole names registered once pass; a name with ';' (which CMake splits
in two), a hidden test and an unregistered test each fail, named.

usage: test_check_test_names.py SOURCE_DIR
"""
import os
import subprocess
import sys
import tempfile

source_dir = os.path.abspath(sys.argv[1])
check = os.path.join(source_dir, "scripts", "check_test_names.py")


def fake_suite(directory, visible, hidden, registered):
    executable = os.path.join(directory, "fake_tests")
    with open(executable, "w", encoding="utf-8") as out:
        out.write("#!%s\nimport sys\n" % sys.executable)
        out.write("names = %r if any(a.startswith('[.]') for a in sys.argv) else %r\n" % (hidden, visible))
        out.write("print('\\n'.join(names))\nsys.exit(len(names) % 256)\n")
    os.chmod(executable, 0o755)
    with open(os.path.join(directory, "CTestTestfile.cmake"), "w", encoding="utf-8") as out:
        for name in registered:
            out.write("add_test([==[%s]==] %s [==[%s]==])\n" % (name, executable, name))
    return executable


def run_check(visible, hidden, registered):
    with tempfile.TemporaryDirectory() as directory:
        executable = fake_suite(directory, visible, hidden, registered)
        return subprocess.run([sys.executable, check, directory, executable],
                              capture_output=True, text=True)


def expect(condition, message, result):
    if not condition:
        print(f"FAILED: {message}\n--- stdout\n{result.stdout}\n--- stderr\n{result.stderr}")
        sys.exit(1)


good = run_check(["a: one", "b: two"], [], ["a: one", "b: two"])
expect(good.returncode == 0, "whole names registered once pass", good)

# CMake splits "x; y" into the tests "x" and " y", as catch_discover_tests does.
split = run_check(["a: one", "joined with ';' and checked"], [], ["a: one", "joined with '", "' and checked"])
expect(split.returncode == 1, "a split name fails", split)
expect("test name contains ';' (CTest splits it): joined with ';' and checked" in split.stdout,
       "the name with ';' is named", split)
expect("CTest test that no executable has (a split name?): ' and checked" in split.stdout,
       "the piece CTest made is named", split)

hidden = run_check(["a: one"], ["never run"], ["a: one"])
expect(hidden.returncode == 1, "a hidden test fails", hidden)
expect("hidden test (a tag with a leading dot), never run: never run" in hidden.stdout,
       "the hidden test is named", hidden)

missing = run_check(["a: one", "b: two"], [], ["a: one"])
expect(missing.returncode == 1 and "not registered with CTest: b: two" in missing.stdout,
       "an unregistered test is named", missing)

twice = run_check(["a: one"], [], ["a: one", "a: one"])
expect(twice.returncode == 1 and "registered 2 times: a: one" in twice.stdout,
       "a test registered twice is named", twice)

print("test_check_test_names: passed")

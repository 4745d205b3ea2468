#!/usr/bin/env python3
"""A test of scripts/check_includes.py: it passes on this repository, and a deliberate
upward include (acquisition, the bottom layer, including an analysis header) makes it fail
naming the file, the line and what the folder may use.

usage: test_check_includes.py SOURCE_DIR
"""
import os
import shutil
import subprocess
import sys
import tempfile

source_dir = os.path.abspath(sys.argv[1])
check = os.path.join(source_dir, "scripts", "check_includes.py")


def run(tree):
    return subprocess.run([sys.executable, check, tree], capture_output=True, text=True)


def expect(condition, message, result):
    if not condition:
        print(f"FAILED: {message}\n--- stdout\n{result.stdout}\n--- stderr\n{result.stderr}")
        sys.exit(1)


clean = run(source_dir)
expect(clean.returncode == 0, "the repository passes the include check", clean)
expect("include only what their folder links" in clean.stdout, "the pass says so", clean)

with tempfile.TemporaryDirectory() as tree:
    folders = ["acquisition", "sensors", "calibration", "analysis", "simulated_bench", "viewer",
               "haptic", "app", "tests", "bench"]
    for folder in folders:
        origin = os.path.join(source_dir, folder)
        if os.path.isdir(origin):
            shutil.copytree(origin, os.path.join(tree, folder),
                            ignore=shutil.ignore_patterns("*.py", "*.json", "*.toml", "*.md"))
    target = os.path.join(tree, "acquisition", "session_file.cpp")
    lines = open(target, encoding="utf-8").read().split("\n")
    lines.insert(1, '#include "analysis/door_model.h"')
    open(target, "w", encoding="utf-8").write("\n".join(lines))

    climbed = run(tree)
    expect(climbed.returncode == 1, "an upward include fails the check", climbed)
    expect('acquisition/session_file.cpp:2: includes "analysis/..." but acquisition may use '
           'only nothing of doorbench (acquisition/CMakeLists.txt)' in climbed.stdout,
           "the failure names the file, the line and what the folder may use", climbed)

    # A sibling of the same layer is not below: the viewer may not include haptic/.
    target = os.path.join(tree, "viewer", "plot_view.cpp")
    lines = open(target, encoding="utf-8").read().split("\n")
    lines.insert(1, '#include "haptic/device.h"')
    open(target, "w", encoding="utf-8").write("\n".join(lines))
    sibling = run(tree)
    expect('viewer/plot_view.cpp:2: includes "haptic/..." but viewer may use only acquisition, '
           'analysis, sensors (viewer/CMakeLists.txt)' in sibling.stdout, "a sibling include fails",
           sibling)
    expect("check_includes: 2 include(s) against the layers" in sibling.stdout,
           "the count of problems", sibling)

print("test_check_includes: passed")

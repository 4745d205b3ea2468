#!/usr/bin/env python3
"""A test of scripts/check_includes.py: it passes on this repository, and each deliberate
fault makes it fail naming the file, the line and what is allowed: an upward include
(acquisition including an analysis header), a sibling's, a later stage's (the fit including
the loop), another stage's internal header, a test that climbs (an analysis test
including haptic, directly or through a tests/support or fixtures/ header), and a benchmark
that includes a header of tests/.

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
    folders = ["core", "acquisition", "sensors", "calibration", "analysis", "simulated_bench",
               "viewer", "haptic", "study", "app", "tests", "bench", "studies", "fixtures"]
    for folder in folders:
        origin = os.path.join(source_dir, folder)
        if os.path.isdir(origin):
            shutil.copytree(origin, os.path.join(tree, folder),
                            ignore=shutil.ignore_patterns("*.py", "*.json", "*.toml", "*.md"))
    target = os.path.join(tree, "acquisition", "session", "session_reader.cpp")
    lines = open(target, encoding="utf-8").read().split("\n")
    lines.insert(1, '#include "analysis/model/door_model.h"')
    open(target, "w", encoding="utf-8").write("\n".join(lines))

    climbed = run(tree)
    expect(climbed.returncode == 1, "an upward include fails the check", climbed)
    expect('acquisition/session/session_reader.cpp:2: includes "analysis/..." but acquisition '
           'may use only core (acquisition/CMakeLists.txt)' in climbed.stdout,
           "the failure names the file, the line and what the folder may use", climbed)

    # A sibling of the same layer is not below: the viewer may not include haptic/.
    target = os.path.join(tree, "viewer", "plot_view.cpp")
    lines = open(target, encoding="utf-8").read().split("\n")
    lines.insert(1, '#include "haptic/device.h"')
    open(target, "w", encoding="utf-8").write("\n".join(lines))
    sibling = run(tree)
    expect('viewer/plot_view.cpp:2: includes "haptic/..." but viewer may use only acquisition, '
           'analysis, core, sensors (viewer/CMakeLists.txt)' in sibling.stdout,
           "a sibling include fails", sibling)
    expect("check_includes: 2 include(s) against the layers" in sibling.stdout,
           "the count of problems", sibling)

    def insert(relative, line):
        path = os.path.join(tree, *relative.split("/"))
        lines = open(path, encoding="utf-8").read().split("\n")
        lines.insert(1, line)
        open(path, "w", encoding="utf-8").write("\n".join(lines))

    # A stage may not include a later stage of its folder.
    insert("analysis/fit/fit_metrics.cpp", '#include "analysis/loop/residual_loop.h"')
    # An internal header belongs to its stage alone.
    insert("analysis/design/felt_quantities.cpp",
           '#include "analysis/fit/internal/fit_equation_error.h"')
    # A test may not climb above its folder, nor through a support header.
    insert("tests/analysis/test_effects.cpp", '#include "haptic/device.h"')
    support = os.path.join(tree, "tests", "support", "climbing_fixture.h")
    open(support, "w", encoding="utf-8").write('#pragma once\n#include "viewer/window.h"\n')
    insert("tests/analysis/test_switches.cpp", '#include "tests/support/climbing_fixture.h"')
    shared = os.path.join(tree, "fixtures", "climbing_door.h")
    open(shared, "w", encoding="utf-8").write('#pragma once\n#include "haptic/device.h"\n')
    insert("tests/analysis/test_simulator.cpp", '#include "fixtures/climbing_door.h"')
    # What benchmarks and tests share lives in fixtures/, not tests/.
    insert("bench/bench_inverse_design.cpp", '#include "tests/support/files.h"')
    staged = run(tree)
    for text in [
            'analysis/fit/fit_metrics.cpp:2: includes "analysis/loop/..." but stage fit of '
            'analysis may use only report, model, preprocessing, simulation, fit '
            '(analysis/CMakeLists.txt DOORBENCH_STAGES)',
            'analysis/design/felt_quantities.cpp:2: includes '
            '"analysis/fit/internal/fit_equation_error.h", internal to analysis/fit/',
            'tests/analysis/test_effects.cpp:2: includes "haptic/device.h" but the tests of '
            'analysis may use only acquisition, analysis, core and the simulated bench',
            'tests/analysis/test_switches.cpp:2: includes "tests/support/climbing_fixture.h -> '
            'viewer/window.h" but the tests of analysis may use only acquisition, analysis, core '
            'and the simulated bench',
            'tests/analysis/test_simulator.cpp:2: includes "fixtures/climbing_door.h -> '
            'haptic/device.h" but the tests of analysis may use only acquisition, analysis, '
            'core and the simulated bench',
            'bench/bench_inverse_design.cpp:2: includes "tests/support/files.h" but bench/ may '
            'not use tests/ (what programs and tests share belongs in fixtures/)',
            "check_includes: 8 include(s) against the layers"]:
        expect(text in staged.stdout, f"the check reports: {text}", staged)

print("test_check_includes: passed")

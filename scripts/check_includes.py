#!/usr/bin/env python3
"""The layers' check (docs/architecture.md): no source file includes a header of a folder
that its folder's CMake target does not link, no stage of a folder includes a later stage,
no file includes another stage's internal headers, and no test climbs above its folder.

usage: check_includes.py [SOURCE_DIR]   (default: the repository this script is in)

Each library folder's CMakeLists.txt is the truth: a folder F whose target links
doorbench_G (directly or through the targets it links) may include "G/...". A file in F
that includes "X/..." for any other folder X of the repository (a layer above, a sibling,
tests/ or bench/) is reported as `FILE:LINE: includes "X/..." but FOLDER may use only ...`.
A cycle in the folders' links is reported too.

Stages: a folder whose CMakeLists.txt says `set(DOORBENCH_STAGES A B C ...)` is divided into
sub-folders F/A, F/B, ... in that order, lowest first. A file in F/B may include "F/A/..."
and "F/B/..." but not "F/C/..." (`FILE:LINE: includes "F/C/..." but stage B of F may use
only A, B (F/CMakeLists.txt DOORBENCH_STAGES)`).

Internal headers: a header under a stage's `internal/` folder (F/S/internal/...) belongs to
that stage alone; any file outside F/S that includes it is reported.

Tests: a file under tests/F (F a library folder), and the tests/support and fixtures/ headers
it includes, may include only F, what F links, tests/, fixtures/ and the simulated bench (the
stand-in for the hardware every layer's tests record from); the test executable
of F (doorbench_add_tests in tests/CMakeLists.txt) may link only F's library, what F links
and the fixtures. A test that needs a higher layer belongs with that layer's tests.

Programs and fixtures: bench/, studies/ and fixtures/ (the synthetic doors, recordings and
protocol peers that tests, benchmarks and studies share) may include any library folder and
fixtures/, but nothing of tests/.

Exit status 1 when anything is reported.
"""
import os
import re
import sys

# The folders whose code ships, in the layers' order (CMakeLists.txt at the top).
LIBRARY_FOLDERS = ["core", "acquisition", "sensors", "calibration", "analysis", "simulated_bench",
                   "viewer", "haptic", "station", "study", "app"]
INCLUDE = re.compile(r'^\s*#\s*include\s+"([A-Za-z0-9_]+)/[^"]+"')
INCLUDE_PATH = re.compile(r'^\s*#\s*include\s+"([^"]+)"')
# Folders every layer's tests may use to make their data: the simulated bench records
# sessions as the real bench would (through the sensor models), so a test of the recorder or
# the preprocessing can run without hardware. Nothing else above a test's layer is allowed.
TEST_FIXTURES = {"simulated_bench"}
# Folders outside the layers whose files may include any library and fixtures/, never tests/.
PROGRAM_FOLDERS = ["bench", "studies", "fixtures"]
STAGES = re.compile(r"set\s*\(\s*DOORBENCH_STAGES\s+([^)]*)\)")


def cmake_commands(text, command):
    """The argument lists of every `command(...)` call in a CMakeLists.txt (comments off)."""
    text = re.sub(r"#[^\n]*", "", text)
    for match in re.finditer(command + r"\s*\(([^)]*)\)", text):
        yield match.group(1).split()


def folder_links(source_dir):
    """folder -> the doorbench folders its targets link directly."""
    target_folder, links = {}, {}
    for folder in LIBRARY_FOLDERS:
        path = os.path.join(source_dir, folder, "CMakeLists.txt")
        if not os.path.exists(path):
            continue
        text = open(path, encoding="utf-8").read()
        for command in ("add_library", "add_executable"):
            for arguments in cmake_commands(text, command):
                if arguments and arguments[0].startswith("doorbench"):
                    target_folder[arguments[0]] = folder
        links[folder] = set()
        links[folder + ":text"] = text
    for folder in LIBRARY_FOLDERS:
        text = links.pop(folder + ":text", None)
        if text is None:
            continue
        for arguments in cmake_commands(text, "target_link_libraries"):
            for name in arguments[1:]:
                other = target_folder.get(name)
                if other is not None and other != folder:
                    links[folder].add(other)
    return links


def closure(links):
    allowed = {}
    for folder in links:
        seen, stack = set(), list(links[folder])
        while stack:
            other = stack.pop()
            if other not in seen:
                seen.add(other)
                stack.extend(links.get(other, ()))
        allowed[folder] = seen
    return allowed


def folder_stages(source_dir, folder):
    """The stages of `folder` in order (lowest first), or [] when it has none."""
    path = os.path.join(source_dir, folder, "CMakeLists.txt")
    if not os.path.exists(path):
        return []
    text = re.sub(r"#[^\n]*", "", open(path, encoding="utf-8").read())
    match = STAGES.search(text)
    return match.group(1).split() if match else []


def included_paths(path):
    """(line number, included path) of each quoted include in a file."""
    with open(path, encoding="utf-8", errors="replace") as source:
        for number, line in enumerate(source, 1):
            match = INCLUDE_PATH.match(line)
            if match:
                yield number, match.group(1)


def source_files(root):
    for directory, _, files in os.walk(root):
        for name in sorted(files):
            if name.endswith((".h", ".cpp", ".cpp.in")):
                yield os.path.join(directory, name)


def stage_problems(relative, included, stages):
    """Problems of one include of a file `relative` (F/S/...) against F's stages."""
    parts, target = relative.split(os.sep), included.split("/")
    folder = parts[0]
    problems = []
    if len(target) > 3 and target[2] == "internal":
        owner = target[0] + "/" + target[1]
        if not "/".join(parts).startswith(owner + "/"):
            problems.append(f'includes "{included}", internal to {owner}/')
    if target[0] != folder or not stages or len(parts) < 3 or parts[1] not in stages:
        return problems
    if len(target) < 3 or target[1] not in stages:
        problems.append(f'includes "{included}", which is in no stage of {folder} '
                        f'({", ".join(stages)})')
        return problems
    mine = stages.index(parts[1])
    if stages.index(target[1]) > mine:
        may = ", ".join(stages[:mine + 1])
        problems.append(f'includes "{folder}/{target[1]}/..." but stage {parts[1]} of {folder} '
                        f"may use only {may} ({folder}/CMakeLists.txt DOORBENCH_STAGES)")
    return problems


def test_links(source_dir):
    """tests/ folder -> the doorbench libraries its test executable links."""
    path = os.path.join(source_dir, "tests", "CMakeLists.txt")
    if not os.path.exists(path):
        return {}
    text = re.sub(r"#[^\n]*", "", open(path, encoding="utf-8").read())
    links = {}
    for arguments in cmake_commands(text, "doorbench_add_tests"):
        if not arguments:
            continue
        names, keyword = [], None
        for word in arguments[1:]:
            if word in ("LIBRARIES", "SOURCES"):
                keyword = word
            elif keyword == "LIBRARIES":
                names.append(word)
        links[arguments[0]] = names
    return links


def test_folder_includes(source_dir, path, seen=None):
    """(line, top folder) of the includes of a test file and, through them, of tests/support."""
    seen = set() if seen is None else seen
    for number, included in included_paths(path):
        top = included.split("/")[0]
        yield number, top, included
        support = os.path.join(source_dir, included)
        if included.startswith(("tests/support/", "fixtures/")) and os.path.exists(support) \
                and support not in seen:
            seen.add(support)
            for _, deeper, deeper_path in test_folder_includes(source_dir, support, seen):
                yield number, deeper, f"{included} -> {deeper_path}"


def check_tests(source_dir, allowed, top_folders):
    problems = []
    library_folder = {f"doorbench_{folder}": folder for folder in allowed}
    for folder, libraries in sorted(test_links(source_dir).items()):
        if folder not in allowed:
            continue
        may = allowed[folder] | {folder} | TEST_FIXTURES
        for library in libraries:
            other = library_folder.get(library)
            if other is not None and other not in may:
                problems.append(f"tests/CMakeLists.txt: the tests of {folder} link {library}, "
                                f"a layer {folder} may not use (move the test to {other}'s tests)")
    for folder in allowed:
        may = allowed[folder] | {folder, "tests", "fixtures"} | TEST_FIXTURES
        for path in source_files(os.path.join(source_dir, "tests", folder)):
            relative = os.path.relpath(path, source_dir)
            for number, top, included in test_folder_includes(source_dir, path):
                if top in top_folders and top not in may:
                    uses = ", ".join(sorted(may - {"tests", "fixtures"} - TEST_FIXTURES))
                    problems.append(f'{relative}:{number}: includes "{included}" but the tests '
                                    f"of {folder} may use only {uses} and the simulated bench (a test that needs a "
                                    "higher layer belongs with that layer's tests)")
    return problems


def check_programs(source_dir):
    """Problems of bench/, studies/ and fixtures/ files that include a header of tests/."""
    problems = []
    for folder in PROGRAM_FOLDERS:
        for path in source_files(os.path.join(source_dir, folder)):
            relative = os.path.relpath(path, source_dir)
            for number, included in included_paths(path):
                if included.split("/")[0] == "tests":
                    problems.append(f'{relative}:{number}: includes "{included}" but {folder}/ '
                                    "may not use tests/ (what programs and tests share belongs "
                                    "in fixtures/)")
    return problems


def main():
    source_dir = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                                 os.path.join(os.path.dirname(__file__), ".."))
    links = folder_links(source_dir)
    allowed = closure(links)
    top_folders = {entry for entry in os.listdir(source_dir)
                   if os.path.isdir(os.path.join(source_dir, entry))}
    problems = []
    for folder, uses in sorted(allowed.items()):
        if folder in uses:
            problems.append(f"{folder}/CMakeLists.txt: the folders' links form a cycle through "
                            f"{folder}")
    checked = 0
    for folder in links:
        stages = folder_stages(source_dir, folder)
        for path in source_files(os.path.join(source_dir, folder)):
            relative = os.path.relpath(path, source_dir)
            checked += 1
            for number, included in included_paths(path):
                top = included.split("/")[0]
                for problem in stage_problems(relative, included, stages):
                    problems.append(f"{relative}:{number}: {problem}")
                if top == folder or top not in top_folders:
                    continue
                if top not in allowed[folder]:
                    may = ", ".join(sorted(allowed[folder])) or "nothing of doorbench"
                    problems.append(f'{relative}:{number}: includes "{top}/..." but '
                                    f"{folder} may use only {may} "
                                    f"({folder}/CMakeLists.txt)")
    problems += check_tests(source_dir, allowed, top_folders)
    problems += check_programs(source_dir)
    for problem in problems:
        print(problem)
    if problems:
        print(f"check_includes: {len(problems)} include(s) against the layers")
        return 1
    print(f"check_includes: {checked} files in {len(links)} folders include only what their "
          "folder links, stages only their own and earlier ones, tests only their layer")
    return 0


if __name__ == "__main__":
    sys.exit(main())

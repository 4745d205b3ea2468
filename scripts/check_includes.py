#!/usr/bin/env python3
"""The layers' check (docs/architecture.md): no source file includes a header of a folder
that its folder's CMake target does not link.

usage: check_includes.py [SOURCE_DIR]   (default: the repository this script is in)

Each library folder's CMakeLists.txt is the truth: a folder F whose target links
doorbench_G (directly or through the targets it links) may include "G/...". A file in F
that includes "X/..." for any other folder X of the repository (a layer above, a sibling,
tests/ or bench/) is reported as `FILE:LINE: includes "X/..." but FOLDER may use only ...`.
A cycle in the folders' links is reported too. Exit status 1 when anything is reported.
"""
import os
import re
import sys

# The folders whose code ships, in the layers' order (CMakeLists.txt at the top).
LIBRARY_FOLDERS = ["acquisition", "sensors", "calibration", "analysis", "simulated_bench",
                   "viewer", "haptic", "study", "app"]
INCLUDE = re.compile(r'^\s*#\s*include\s+"([A-Za-z0-9_]+)/[^"]+"')


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
        for root, _, files in os.walk(os.path.join(source_dir, folder)):
            for name in sorted(files):
                if not name.endswith((".h", ".cpp", ".cpp.in")):
                    continue
                path = os.path.join(root, name)
                relative = os.path.relpath(path, source_dir)
                checked += 1
                with open(path, encoding="utf-8", errors="replace") as source:
                    for number, line in enumerate(source, 1):
                        match = INCLUDE.match(line)
                        if not match:
                            continue
                        included = match.group(1)
                        if included == folder or included not in top_folders:
                            continue
                        if included not in allowed[folder]:
                            may = ", ".join(sorted(allowed[folder])) or "nothing of doorbench"
                            problems.append(f'{relative}:{number}: includes "{included}/..." but '
                                            f"{folder} may use only {may} "
                                            f"({folder}/CMakeLists.txt)")
    for problem in problems:
        print(problem)
    if problems:
        print(f"check_includes: {len(problems)} include(s) against the layers")
        return 1
    print(f"check_includes: {checked} files in {len(links)} folders include only what their "
          "folder links")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Fails on a C++ function longer than the limit (120 lines), or a source file longer than
its limit (800 lines), that docs/architecture.md does not name.

    scripts/check_function_length.py [--limit N] [--root DIR] [--exceptions FILE] [--all]
                                     [FOLDER ...]

Checks every .h/.hpp/.cpp/.cc file under each folder whose code ships (core/, acquisition/,
sensors/, calibration/, analysis/, simulated_bench/, viewer/, haptic/, station/, study/,
app/), under
the tools' folders (bench/, studies/, fuzz/) -- those of them that exist under --root, by
default the repository; tests/ is not checked -- and under each FOLDER given (which must exist). A
function's length is the number of lines from the line of its name to the line of its
closing brace, both included; lambdas and local classes inside a function count toward
it. Comments, string and character literals (raw strings too) and preprocessor lines are
ignored, so braces in them do not count.

Exceptions are the rows of the Markdown table under the heading
"## Functions longer than 120 lines" in --exceptions (default docs/architecture.md
under --root): | file | function | why |, the file relative to the root, the function
as this script names it (e.g. `record_session`, `SafetyLayer::step`), the reason not
empty. A row whose function is not (or no longer) too long also fails the check, so the
list stays true.

Files: every checked file longer than --file-limit lines (default 800) fails unless a row of
the table under "## Files longer than 800 lines" (| file | why |) names it with a reason
(tables of data, say); a listed file that is no longer too long fails too.

Exit status: 0 when every function and file fits or is listed, 1 when one does not (each named as
file:line with its length, on stdout), 2 on a usage error. --all prints every function
with its length (exit 0 unless a usage error).

Standard library only (Debian's python3).
"""

import argparse
import os
import re
import sys

# Every folder of code but tests/: what ships, then the tools (benchmarks, fuzzers).
DEFAULT_FOLDERS = ["core", "acquisition", "sensors", "calibration", "analysis",
                   "simulated_bench", "viewer", "haptic", "station", "study", "app", "bench", "studies", "fuzz",
                   "fixtures"]
SOURCE_SUFFIXES = (".h", ".hpp", ".cpp", ".cc", ".cxx")
EXCEPTIONS_HEADING = "## Functions longer than 120 lines"
FILE_EXCEPTIONS_HEADING = "## Files longer than 800 lines"


# ---------------------------------------------------------------------------------------
# Reading C++: blank out what is not code

def _blank(text):
    """The text with every character but newlines replaced by a space."""
    return re.sub(r"[^\n]", " ", text)


def _is_digit_separator(source, quote):
    """Whether the ' at `quote` separates digits (1'000'000) rather than opening a
    character literal: the token before it is a number."""
    start = quote
    while start > 0 and (source[start - 1].isalnum() or source[start - 1] in "._'"):
        start -= 1
    return start < quote and source[start].isdigit()


_RAW_STRING = re.compile(r'(?:u8|u|U|L)?R"([^ ()\\\t\n]{0,16})\(')


def strip_code(source):
    """`source` with comments, string and character literals and preprocessor directives
    blanked out (newlines kept, so that positions and line numbers stay)."""
    out = []
    i = 0
    n = len(source)
    line_start = True  # only whitespace since the last newline
    while i < n:
        c = source[i]
        if c == "\n":
            out.append(c)
            i += 1
            line_start = True
            continue
        if line_start and c == "#":
            # A preprocessor directive, with its continuation lines.
            j = i
            while j < n and source[j] != "\n":
                if source.startswith("//", j) or source.startswith("/*", j):
                    break
                if source[j] == "\\" and j + 1 < n and source[j + 1] == "\n":
                    j += 2
                    continue
                j += 1
            out.append(_blank(source[i:j]))
            i = j
            continue
        if not c.isspace():
            line_start = False
        if source.startswith("//", i):
            j = source.find("\n", i)
            j = n if j < 0 else j
            out.append(_blank(source[i:j]))
            i = j
        elif source.startswith("/*", i):
            j = source.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(_blank(source[i:j]))
            i = j
        elif c in "uULR" and (i == 0 or not (source[i - 1].isalnum() or source[i - 1] == "_")) \
                and _RAW_STRING.match(source, i):
            match = _RAW_STRING.match(source, i)
            end = source.find(")" + match.group(1) + '"', match.end())
            end = n if end < 0 else end + len(match.group(1)) + 2
            out.append(_blank(source[i:end]))
            i = end
        elif c == '"' or (c == "'" and not _is_digit_separator(source, i)):
            j = i + 1
            while j < n and source[j] != c and source[j] != "\n":
                j += 2 if source[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(_blank(source[i:j]))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


# ---------------------------------------------------------------------------------------
# Finding function bodies

def _matching_brace(code, open_at):
    """The index of the } closing the { at `open_at` (len(code) if none)."""
    depth = 0
    for k in range(open_at, len(code)):
        if code[k] == "{":
            depth += 1
        elif code[k] == "}":
            depth -= 1
            if depth == 0:
                return k
    return len(code)


def _balanced(text, opening, closing):
    depth = 0
    for ch in text:
        if ch == opening:
            depth += 1
        elif ch == closing:
            depth -= 1
    return depth == 0


_ACCESS = re.compile(r"^\s*(?:(?:public|private|protected)\s*:(?!:)\s*)+")
_TEMPLATE_PREFIX = re.compile(r"^\s*template\s*<")
_SCOPE = re.compile(r"^\s*(?:inline\s+)?(?:namespace\b[\w:\s]*|extern\s*)$")
_CLASS = re.compile(r"^\s*(?:\[\[[^\]]*\]\]\s*)?(?:class|struct|union)\b")
_QUALIFIERS = (r"(?:\s|const\b|volatile\b|override\b|final\b|mutable\b|&|"
               r"noexcept\b(?:\s*\((?:[^()]|\([^()]*\))*\))?|"
               r"->[^{;]*|requires\b[^{;]*|\[\[[^\]]*\]\])*")
_FUNCTION_END = re.compile(r"\)" + _QUALIFIERS + r"$")
# A constructor's initialiser list: ") : member(...), member{...}" up to the body.
_INIT_LIST = re.compile(r"\)\s*(?:noexcept\b(?:\s*\((?:[^()]|\([^()]*\))*\))?\s*)?:(?!:)")
# Inside an initialiser list, a brace that initialises a member ("a_{1}" or "Base<T>{}").
_INIT_BRACE = re.compile(r"[:,]\s*[\w:]+(?:<[^;{}]*>)?\s*$")
_NOT_NAMES = {"decltype", "alignas", "__attribute__", "noexcept", "sizeof", "alignof",
              "requires", "static_assert", "__declspec"}
_NAME = re.compile(r"((?:[A-Za-z_]\w*\s*(?:<[^;{}()]*>)?\s*::\s*)*"
                   r"(?:operator\s*(?:\(\s*\)|\[\s*\]|[^\s\w(]+|\s+[\w:<>\s*&]+?)|~?[A-Za-z_]\w*))\s*$")


def _strip_template_prefix(head):
    """`head` without a leading template<...> parameter list (replaced by spaces)."""
    match = _TEMPLATE_PREFIX.match(head)
    if not match:
        return head
    depth = 0
    for k in range(match.end() - 1, len(head)):
        if head[k] == "<":
            depth += 1
        elif head[k] == ">":
            depth -= 1
            if depth == 0:
                return " " * (k + 1) + head[k + 1:]
    return head


def _in_init_list(head):
    """Whether `head` (balanced parentheses) is a constructor's head that is inside its
    initialiser list."""
    for match in _INIT_LIST.finditer(head):
        if _balanced(head[:match.start() + 1], "(", ")"):
            return True
    return False


def _classify(head):
    """What the { after `head` opens: 'scope' (namespace, extern, class: functions may
    be inside), 'function', 'init' (a brace of a constructor's initialiser list) or
    'other' (an initialiser, an enum, an expression)."""
    head = _strip_template_prefix(_ACCESS.sub(" ", head))
    if _SCOPE.match(head):
        return "scope"
    if not _balanced(head, "(", ")") or not _balanced(head, "[", "]"):
        return "other"
    if _in_init_list(head):
        return "init" if _INIT_BRACE.search(head) else "function"
    if _FUNCTION_END.search(head) and "(" in head:
        return "function"
    if _CLASS.match(head):
        return "scope"
    return "other"


def _function_name(code, head_start, head_end):
    """(name, index of the name) of the function whose head is code[head_start:head_end]:
    the name before the first parameter list."""
    head = code[head_start:head_end]
    depth_angle = 0
    for k, ch in enumerate(head):
        if ch == "<":
            depth_angle += 1
        elif ch == ">" and depth_angle > 0:
            depth_angle -= 1
        elif ch == "(":
            before = head[:k]
            if re.search(r"\boperator\s*$", before) and re.match(r"\(\s*\)\s*\(", head[k:]):
                continue  # operator(): its parameter list is the next one
            match = _NAME.search(before)
            if not match:
                continue
            name = re.sub(r"\s+", "", match.group(1)) if "operator" not in match.group(1) \
                else re.sub(r"\s+", " ", match.group(1)).strip()
            if name in _NOT_NAMES or name.startswith("[["):
                continue
            return name, head_start + match.start(1)
    stripped = head.lstrip()
    return "(unnamed)", head_start + (len(head) - len(stripped))


_CLASS_NAME = re.compile(r"^\s*(?:\[\[[^\]]*\]\]\s*)?(?:class|struct|union)\s+"
                         r"(?:\[\[[^\]]*\]\]\s*)?(?:alignas\s*\([^)]*\)\s*)?(\w+)")


def _class_name(head):
    """"Name::" when `head` opens a class, struct or union with a name, else ""."""
    match = _CLASS_NAME.match(_strip_template_prefix(_ACCESS.sub(" ", head)))
    return match.group(1) + "::" if match else ""


def find_functions(code):
    """[(name, first line, last line)] of every function body in stripped `code`, the
    first line being that of its name."""
    found = []
    line_starts = [0] + [k + 1 for k, ch in enumerate(code) if ch == "\n"]

    def line_of(index):
        lo, hi = 0, len(line_starts) - 1
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if line_starts[mid] <= index:
                lo = mid
            else:
                hi = mid - 1
        return lo + 1

    def scan_scope(i, prefix):
        """Scans the declarations from `i` to the } that ends the scope; returns the
        index after it. `prefix`: the enclosing classes' names ("A::B::")."""
        head_start = i
        while i < len(code):
            c = code[i]
            if c == ";":
                head_start = i + 1
            elif c == "}":
                return i + 1
            elif c == "{":
                kind = _classify(code[head_start:i])
                if kind == "scope":
                    i = scan_scope(i + 1, prefix + _class_name(code[head_start:i]))
                    head_start = i
                    continue
                close = _matching_brace(code, i)
                if kind == "function":
                    name, name_at = _function_name(code, head_start, i)
                    found.append((prefix + name, line_of(name_at), line_of(close)))
                    head_start = close + 1
                i = close + 1  # 'init' and 'other': the head goes on
                continue
            i += 1
        return i

    scan_scope(0, "")
    return found


# ---------------------------------------------------------------------------------------
# The exceptions

def read_table(path, heading, header):
    """The rows (lists of cells, backticks stripped) of the Markdown table under `heading`
    in `path`, header and separator rows left out ([] if the file or the heading is
    missing). Raises ValueError naming the line of a row without len(header) cells or
    with an empty last cell (the reason)."""
    if not os.path.exists(path):
        return []
    rows = []
    in_section = False
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            stripped = line.strip()
            if stripped.startswith("## ") or stripped.startswith("# "):
                in_section = stripped == heading
                continue
            if not in_section or not stripped.startswith("|"):
                continue
            cells = [cell.strip().strip("`").strip() for cell in stripped.strip("|").split("|")]
            if all(re.fullmatch(r":?-+:?", cell) for cell in cells):
                continue  # the separator row
            if len(cells) != len(header):
                count = {2: "two", 3: "three"}.get(len(header), str(len(header)))
                raise ValueError(f"{path}:{number}: a row needs {count} cells: "
                                 + " | ".join(header))
            if [cell.lower() for cell in cells] == list(header):
                continue  # the header row
            if not cells[-1]:
                raise ValueError(f"{path}:{number}: {' '.join(cells[:-1])}: the reason is empty")
            rows.append(cells)
    return rows


def read_exceptions(path):
    """{(file, function): reason} from the table under EXCEPTIONS_HEADING in `path`."""
    rows = read_table(path, EXCEPTIONS_HEADING, ("file", "function", "why"))
    return {(file, function): why for file, function, why in rows}


def read_file_exceptions(path):
    """{file: reason} from the table under FILE_EXCEPTIONS_HEADING in `path`."""
    return {file: why for file, why in read_table(path, FILE_EXCEPTIONS_HEADING, ("file", "why"))}


def check_file_lengths(root, folders, limit, exceptions, shown_path):
    """Prints each file over `limit` lines that `exceptions` does not name, and each listed
    file that is not over it; True when something was printed."""
    failed = False
    long_files = set()
    for relative in source_files(root, folders):
        with open(os.path.join(root, relative), encoding="utf-8", errors="replace") as f:
            lines = sum(1 for _ in f)
        name = relative.replace(os.sep, "/")
        if lines <= limit:
            continue
        long_files.add(name)
        if name in exceptions:
            continue
        print(f"{name}: {lines} lines (limit {limit}): split it along its seams, or list it "
              f"with the reason in {shown_path} under \"{FILE_EXCEPTIONS_HEADING}\"")
        failed = True
    checked = tuple(folder.rstrip("/") + "/" for folder in folders)
    for name in sorted(exceptions):
        if name.startswith(checked) and name not in long_files:
            print(f"{shown_path}: {name} is listed but is not longer than {limit} lines (or no "
                  "longer exists): remove the row")
            failed = True
    return failed


# ---------------------------------------------------------------------------------------
# The check

def source_files(root, folders):
    for folder in folders:
        for directory, subdirectories, files in os.walk(os.path.join(root, folder)):
            subdirectories.sort()
            for name in sorted(files):
                if name.endswith(SOURCE_SUFFIXES):
                    yield os.path.relpath(os.path.join(directory, name), root)


def measure(root, folders):
    """[(file, line, name, length)] of every function in the folders."""
    measured = []
    for relative in source_files(root, folders):
        with open(os.path.join(root, relative), encoding="utf-8", errors="replace") as f:
            code = strip_code(f.read())
        for name, first, last in find_functions(code):
            measured.append((relative.replace(os.sep, "/"), first, name, last - first + 1))
    return measured


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folders", nargs="*", help="more folders to check (under --root)")
    parser.add_argument("--limit", type=int, default=120, help="the most lines a function has")
    parser.add_argument("--root", default=os.path.join(os.path.dirname(__file__), ".."))
    parser.add_argument("--file-limit", type=int, default=800, help="the most lines a file has")
    parser.add_argument("--exceptions", help="default: ROOT/docs/architecture.md")
    parser.add_argument("--all", action="store_true", help="print every function's length")
    options = parser.parse_args(argv)
    root = os.path.normpath(options.root)
    if options.limit < 1:
        print("check_function_length: --limit must be >= 1", file=sys.stderr)
        return 2
    folders = [f for f in DEFAULT_FOLDERS if os.path.isdir(os.path.join(root, f))]
    for folder in options.folders:
        if not os.path.isdir(os.path.join(root, folder)):
            print(f"check_function_length: {folder}: no such folder under {root}", file=sys.stderr)
            return 2
        if folder.rstrip("/") not in folders:
            folders.append(folder.rstrip("/"))
    exceptions_path = options.exceptions or os.path.join(root, "docs", "architecture.md")
    shown_path = os.path.relpath(exceptions_path, root)
    if shown_path.startswith(".."):
        shown_path = exceptions_path
    try:
        exceptions = read_exceptions(exceptions_path)
        file_exceptions = read_file_exceptions(exceptions_path)
    except ValueError as error:
        print(f"check_function_length: {error}", file=sys.stderr)
        return 2

    measured = measure(root, folders)
    if options.all:
        for file, line, name, length in measured:
            print(f"{file}:{line}: {name} {length} lines")
        return 0
    failed = False
    long_ones = set()
    for file, line, name, length in measured:
        if length <= options.limit:
            continue
        long_ones.add((file, name))
        if (file, name) in exceptions:
            continue
        print(f"{file}:{line}: {name} is {length} lines (limit {options.limit}): split it into "
              f"named stages, or list it with the reason in {shown_path} under "
              f"\"{EXCEPTIONS_HEADING}\"")
        failed = True
    checked = tuple(folder.rstrip("/") + "/" for folder in folders)
    for file, name in sorted(exceptions):
        if file.startswith(checked) and (file, name) not in long_ones:
            print(f"{shown_path}: {file} {name} is listed but is not longer than "
                  f"{options.limit} lines (or no longer exists): remove the row")
            failed = True
    if check_file_lengths(root, folders, options.file_limit, file_exceptions, shown_path):
        failed = True
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

#!/usr/bin/env python3
"""Tests of scripts/check_function_length.py: run as a program on small trees written
to a temporary folder, and on fixtures/tricky.cpp (braces in comments, strings, raw
strings, character literals, macros; initialiser lists; lambdas and local classes).

    python3 tests/check_scripts/test_check_function_length.py
"""

import os
import subprocess
import sys
import tempfile
import textwrap
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "..", "scripts", "check_function_length.py")
FIXTURES = os.path.join(HERE, "fixtures")


def run_check(*arguments):
    """(exit status, stdout, stderr) of the check."""
    done = subprocess.run([sys.executable, SCRIPT, *arguments], capture_output=True, text=True,
                          check=False)
    return done.returncode, done.stdout, done.stderr


def function_of_lines(name, lines):
    """A C++ function of exactly `lines` lines (name line to closing brace), with braces
    in a comment, a string and a raw string inside it, which must not count."""
    assert lines >= 5
    body = ["  // a brace in a comment: {",
            '  const char* text = "}";',
            '  const char* raw = R"({"a": {}})";']
    body += ["  ++count;"] * (lines - 2 - len(body) - 1)
    return "\n".join([f"int {name}(int count) {{", *body, "  return count + text[0] + raw[0];",
                      "}", ""])


def write(root, relative, text):
    path = os.path.join(root, relative)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)


def architecture(rows):
    """docs/architecture.md with the exceptions table holding `rows` (file, function,
    why), between two other sections."""
    table = "\n".join(f"| {file} | `{function}` | {why} |" for file, function, why in rows)
    return textwrap.dedent("""\
        # Architecture

        ## Layers

        | file | function | why |
        |------|----------|-----|
        | acquisition/other.cpp | not_an_exception | a table in another section |

        ## Functions longer than 120 lines

        | file | function | why |
        |------|----------|-----|
        """) + table + "\n\n## Next section\n"


class CheckFunctionLength(unittest.TestCase):
    def setUp(self):
        self.temp = tempfile.TemporaryDirectory()
        self.root = self.temp.name

    def tearDown(self):
        self.temp.cleanup()

    def test_a_function_of_120_lines_passes(self):
        write(self.root, "acquisition/fits.cpp", "\n" + function_of_lines("fits", 120))
        status, out, err = run_check("--root", self.root)
        self.assertEqual((status, out, err), (0, "", ""))

    def test_a_function_of_121_lines_fails_naming_file_line_function_and_length(self):
        write(self.root, "acquisition/long.cpp", "\n\n" + function_of_lines("too_long", 121))
        status, out, _ = run_check("--root", self.root)
        self.assertEqual(status, 1)
        self.assertEqual(out, "acquisition/long.cpp:3: too_long is 121 lines (limit 120): split "
                              "it into named stages, or list it with the reason in "
                              "docs/architecture.md under \"## Functions longer than 120 "
                              "lines\"\n")

    def test_every_default_folder_is_checked(self):
        folders = ["core", "acquisition", "sensors", "calibration", "analysis",
                   "simulated_bench", "viewer", "haptic", "study", "app", "bench", "fuzz"]
        for folder in folders:
            write(self.root, f"{folder}/long.h", function_of_lines("too_long", 121))
        status, out, _ = run_check("--root", self.root)
        self.assertEqual(status, 1)
        self.assertEqual([line.split(":")[0] for line in out.splitlines()],
                         [f"{folder}/long.h" for folder in folders])

    def test_tests_and_other_folders_are_not_checked_by_default(self):
        write(self.root, "tests/app/test_long.cpp", function_of_lines("too_long", 121))
        write(self.root, "examples/long.cpp", function_of_lines("too_long", 121))
        self.assertEqual(run_check("--root", self.root), (0, "", ""))

    def test_a_folder_given_is_checked_too(self):
        write(self.root, "examples/long.cpp", function_of_lines("too_long", 121))
        self.assertEqual(run_check("--root", self.root)[0], 0)
        status, out, _ = run_check("--root", self.root, "examples")
        self.assertEqual(status, 1)
        self.assertTrue(out.startswith("examples/long.cpp:1: too_long is 121 lines"), out)

    def test_a_missing_folder_given_is_a_usage_error(self):
        status, out, err = run_check("--root", self.root, "nowhere")
        self.assertEqual((status, out), (2, ""))
        self.assertEqual(err, f"check_function_length: nowhere: no such folder under "
                              f"{os.path.normpath(self.root)}\n")

    def test_a_file_of_800_lines_passes_and_one_of_801_fails(self):
        short_functions = "".join(function_of_lines(f"f{i}", 10) for i in range(80))
        write(self.root, "analysis/fits.cpp", short_functions)  # 80 x 10 lines = 800
        self.assertEqual(run_check("--root", self.root), (0, "", ""))
        write(self.root, "analysis/fits.cpp", short_functions + "\n")
        status, out, _ = run_check("--root", self.root)
        self.assertEqual(status, 1)
        self.assertEqual(out, "analysis/fits.cpp: 801 lines (limit 800): split it along its "
                              "seams, or list it with the reason in docs/architecture.md under "
                              "\"## Files longer than 800 lines\"\n")

    def test_a_listed_long_file_passes_and_a_listed_short_one_fails(self):
        write(self.root, "haptic/table.cpp", "int x;\n" * 900)
        write(self.root, "haptic/small.cpp", "int y;\n")
        files = textwrap.dedent("""\
            # Architecture

            ## Files longer than 800 lines

            | file | why |
            |------|-----|
            | haptic/table.cpp | a table of data |
            """)
        write(self.root, "docs/architecture.md", files)
        self.assertEqual(run_check("--root", self.root), (0, "", ""))
        write(self.root, "docs/architecture.md", files + "| haptic/small.cpp | too |\n")
        status, out, _ = run_check("--root", self.root)
        self.assertEqual(status, 1)
        self.assertEqual(out, "docs/architecture.md: haptic/small.cpp is listed but is not "
                              "longer than 800 lines (or no longer exists): remove the row\n")

    def test_a_listed_exception_passes(self):
        write(self.root, "haptic/long.cpp", function_of_lines("too_long", 121))
        write(self.root, "docs/architecture.md",
              architecture([("haptic/long.cpp", "too_long", "one table, read top to bottom")]))
        self.assertEqual(run_check("--root", self.root), (0, "", ""))

    def test_an_exception_for_another_file_or_section_does_not_count(self):
        write(self.root, "acquisition/other.cpp", function_of_lines("not_an_exception", 121))
        write(self.root, "haptic/long.cpp", function_of_lines("too_long", 121))
        write(self.root, "docs/architecture.md",
              architecture([("haptic/other.cpp", "too_long", "a different file")]))
        status, out, _ = run_check("--root", self.root)
        self.assertEqual(status, 1)
        lines = out.splitlines()
        self.assertEqual(len(lines), 3, out)
        self.assertTrue(lines[0].startswith("acquisition/other.cpp:1: not_an_exception is 121"))
        self.assertTrue(lines[1].startswith("haptic/long.cpp:1: too_long is 121 lines"))
        self.assertEqual(lines[2], "docs/architecture.md: haptic/other.cpp too_long is listed "
                                   "but is not longer than 120 lines (or no longer exists): "
                                   "remove the row")

    def test_a_listed_function_that_fits_fails_so_the_list_stays_true(self):
        write(self.root, "haptic/short.cpp", function_of_lines("fits", 120))
        write(self.root, "docs/architecture.md",
              architecture([("haptic/short.cpp", "fits", "it was long once")]))
        status, out, _ = run_check("--root", self.root)
        self.assertEqual(status, 1)
        self.assertEqual(out, "docs/architecture.md: haptic/short.cpp fits is listed but is not "
                              "longer than 120 lines (or no longer exists): remove the row\n")

    def test_an_exception_without_a_reason_is_refused(self):
        write(self.root, "haptic/long.cpp", function_of_lines("too_long", 121))
        write(self.root, "docs/architecture.md",
              architecture([("haptic/long.cpp", "too_long", "")]))
        status, out, err = run_check("--root", self.root)
        self.assertEqual((status, out), (2, ""))
        self.assertTrue(err.endswith("architecture.md:13: haptic/long.cpp too_long: the reason "
                                     "is empty\n"), err)

    def test_the_limit_can_be_given(self):
        write(self.root, "analysis/f.cpp", function_of_lines("f", 10))
        self.assertEqual(run_check("--root", self.root, "--limit", "10")[0], 0)
        status, out, _ = run_check("--root", self.root, "--limit", "9")
        self.assertEqual(status, 1)
        self.assertTrue(out.startswith("analysis/f.cpp:1: f is 10 lines (limit 9)"), out)

    def test_tricky_constructs_are_measured_exactly(self):
        status, out, err = run_check("--root", FIXTURES, "--all", ".")
        self.assertEqual((status, err), (0, ""))
        self.assertEqual(out.splitlines(), [
            "tricky.cpp:21: Widget::Widget 6 lines",  # the initialiser list's braces
            "tricky.cpp:27: Widget::area 1 lines",
            "tricky.cpp:33: raw_strings 5 lines",
            "tricky.cpp:39: with_lambda 9 lines",  # its lambda and local class count
            "tricky.cpp:49: trailing 3 lines",
            "tricky.cpp:54: identity 3 lines",
            "tricky.cpp:60: operator== 3 lines",
            "tricky.cpp:67: Callable::Callable 1 lines",  # a lambda in its initialiser list
            "tricky.cpp:68: Callable::operator() 1 lines",
            "tricky.cpp:74: c_function 3 lines",  # inside extern "C"
            "tricky.cpp:79: guarded 5 lines",  # a function-try-block, its handler included
        ])


if __name__ == "__main__":
    unittest.main()

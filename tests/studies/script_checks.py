"""What the bench programs' check scripts share (tests/studies/check_*.py): problems are
collected, not raised, so that one run lists them all; `run` records a wrong exit status as
a problem and returns the finished process."""
import subprocess

problems = []


def check(condition, what):
    if not condition:
        problems.append(what)


def run(exe, *args, expect=0):
    done = subprocess.run([exe, *args], capture_output=True, text=True)
    check(done.returncode == expect,
          f"{' '.join(args)}: exit {done.returncode}, expected {expect}: {done.stderr}")
    return done

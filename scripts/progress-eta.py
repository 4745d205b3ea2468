#!/usr/bin/env python3
"""How honest the long verbs' time-left estimates are (app/progress.h): runs a doorbench
command with stderr on a pseudo-terminal, timestamps every redraw of the status line, and
prints each estimate beside the time that was really left when the command ended (the
estimate of a stage covers that stage: for the window fit and the folds compare with the
next stage line, for the loop's steps with the end).
usage: progress-eta.py DOORBENCH_ARGS...   e.g. progress-eta.py build/app/doorbench loop S.h5 --out DIR
"""
import os
import re
import select
import subprocess
import sys
import time


def seconds(text):
    """'1 h 02 min', '1 min 05 s', '42 s' -> seconds."""
    m = re.fullmatch(r"(\d+) h (\d+) min", text)
    if m:
        return int(m.group(1)) * 3600 + int(m.group(2)) * 60
    m = re.fullmatch(r"(\d+) min (\d+) s", text)
    if m:
        return int(m.group(1)) * 60 + int(m.group(2))
    m = re.fullmatch(r"(\d+) s", text)
    return int(m.group(1)) if m else None


def main():
    master, slave = os.openpty()
    began = time.monotonic()
    child = subprocess.Popen(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=slave,
                             stdin=subprocess.DEVNULL)
    os.close(slave)
    lines = []  # (seconds since the start, text)
    while True:
        ready, _, _ = select.select([master], [], [], 0.5)
        if ready:
            try:
                data = os.read(master, 65536)
            except OSError:
                break  # the child closed the terminal
            if not data:
                break
            now = time.monotonic() - began
            for piece in re.split(rb"[\r\n]", data):
                text = piece.decode(errors="replace").replace("\x1b[K", "").strip()
                if text:
                    lines.append((now, text))
        elif child.poll() is not None:
            break
    child.wait()
    end = time.monotonic() - began
    print(f"exit status {child.returncode}, {end:.1f} s in all")
    for now, text in lines:
        estimate = re.search(r"(at most about|about) (.+?) left", text)
        if estimate:
            print(f"{now:7.1f} s  {text.split(',')[0]:<58.58}  {estimate.group(1)} "
                  f"{seconds(estimate.group(2))} s; {end - now:.1f} s to the end")
        elif "left" not in text:
            print(f"{now:7.1f} s  {text[:100]}")
    return child.returncode


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""The render loop's timing at rest and under load, as a user's `doorbench play` sees it.

Not a timed test: a measurement for docs/PERFORMANCE.md ("The tick under load"). For each
device kind (the simulated HapticMaster, the rotary device, the HapticMaster protocol emulator
as a process of its own) it plays the reference door for SECONDS of real time twice: on the
machine as it is, then with twice as many spinning processes as cores (started and ended here).
Each play's summary gives the tick interval's p50/p99/max, the late ticks (intervals above the
safety layer's max_tick_interval_s, 5 ms), the skipped deadlines and whether the run stopped
early. Prints a Markdown table, one row per run, and writes the summaries beside it.

    bench/haptic_load_timing.py DOORBENCH [--seconds 60] [--out DIR] [--no-fifo]
        [--devices sim,sim:rotary,hapticmaster] [--extra "--station"]

Run from the source tree (the emulator is tests/hapticmaster_emulator/hapticmaster_emulator.py).
"""

import argparse
import os
import re
import signal
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
EMULATOR = os.path.join(HERE, "..", "tests", "hapticmaster_emulator", "hapticmaster_emulator.py")

TIMING = re.compile(
    r"timing: (?P<ticks>\d+) ticks in (?P<seconds>[\d.e+]+) s \((?P<rate>[\d.e+]+) Hz, "
    r"(?P<scheduling>[^)]*)\); interval p50/p99/max (?P<p50>[\d.e+]+)/(?P<p99>[\d.e+]+)/"
    r"(?P<max>[\d.e+]+) µs; .*?(?P<over5>\d+) intervals over 5 ms; (?P<skipped>\d+) "
    r"deadlines skipped")
LATE = re.compile(r"late_tick(?: x(\d+))?")


class Spinners:
    """Twice as many busy processes as cores, for the run's length."""

    def __init__(self, count):
        self.processes = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
                          for _ in range(count)]

    def end(self):
        for process in self.processes:
            process.kill()
        for process in self.processes:
            process.wait()


def start_emulator():
    """The emulator stands for the HapticMaster's own computer: it runs under SCHED_FIFO 70
    (below the tick's 80 and the I/O thread's 79) where chrt is permitted, as the tests run it
    (tests/support/hapticmaster_emulator_process.h), so the busy processes load the host only."""
    for prefix in (["/usr/bin/chrt", "-f", "70"], []):
        emulator = subprocess.Popen(prefix + ["/usr/bin/python3", EMULATOR],
                                    stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        line = emulator.stdout.readline().strip()
        if line.startswith("PORT "):
            return emulator, "hapticmaster://127.0.0.1:" + line[5:]
        emulator.wait()
    raise SystemExit("the emulator said: " + line)


def play(doorbench, device, seconds, session, extra):
    command = [doorbench, "play", "--device", device, "--duration-s", str(seconds),
               "--out", session] + extra
    done = subprocess.run(command, capture_output=True, text=True)
    return done.returncode, done.stdout, done.stderr


def row(device, load, status, out):
    timing = TIMING.search(out)
    late = LATE.search(out)
    late_ticks = "0" if not late else (late.group(1) or "1")
    stopped = re.search(r"stopped early: (.*)", out)
    outcome = "completed" if status == 0 else "stopped: " + (stopped.group(1) if stopped else
                                                               "exit %d" % status)
    if not timing:
        return "| %s | %s | %s | - | - | - | - | - |" % (device, load, outcome)
    return "| %s | %s | %s | %s Hz (%s) | %s / %s / %s µs | %s | %s | %s |" % (
        device, load, outcome, timing["rate"], timing["scheduling"], timing["p50"],
        timing["p99"], timing["max"], late_ticks, timing["over5"], timing["skipped"])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("doorbench")
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--out", default=None)
    parser.add_argument("--no-fifo", action="store_true")
    parser.add_argument("--devices", default="sim,sim:rotary,hapticmaster")
    parser.add_argument("--extra", default="", help="more options for every play")
    args = parser.parse_args()
    out_dir = args.out or tempfile.mkdtemp(prefix="haptic-load-")
    extra = args.extra.split() + (["--no-fifo"] if args.no_fifo else [])
    spinners_count = 2 * (os.cpu_count() or 1)
    print("| device | machine | result | rate | interval p50 / p99 / max | late ticks (> 5 ms) "
          "| intervals > 5 ms | deadlines skipped |")
    print("|---|---|---|---|---|---|---|---|")
    for name in args.devices.split(","):
        emulator = None
        device = name
        if name == "hapticmaster":
            emulator, device = start_emulator()
        try:
            for load in ("at rest", "%d busy processes" % spinners_count):
                spinners = Spinners(spinners_count) if load != "at rest" else None
                time.sleep(1.0 if spinners else 0.0)
                session = os.path.join(out_dir, "%s-%s.h5" % (name.replace(":", "-"),
                                                              "rest" if not spinners else "load"))
                try:
                    status, out, err = play(args.doorbench, device, args.seconds, session, extra)
                finally:
                    if spinners:
                        spinners.end()
                with open(session + ".txt", "w") as summary:
                    summary.write(out + err)
                load_text = "%s (load %.1f)" % (load, os.getloadavg()[0])
                print(row(name, load_text, status, out), flush=True)
        finally:
            if emulator:
                emulator.send_signal(signal.SIGKILL)
                emulator.wait()
    print("\nsummaries in " + out_dir)


if __name__ == "__main__":
    main()

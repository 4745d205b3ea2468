#!/usr/bin/python3
"""An emulator of the HapticMaster's TCP text protocol, for doorbench's driver tests.

Run with Debian's /usr/bin/python3 (standard library only). It listens on 127.0.0.1
(--port 0 = a free port), prints "PORT <n>" on stdout, and serves every client that connects,
each on its own thread, all on the one device (a second connection is how a driver reaches a
device whose first connection broke).

Framing (docs/hapticmaster.md): every message is an 8-byte header (big-endian 32-bit length,
then 4 zero bytes) followed by ASCII text; a request may hold several commands joined with
';'. Each request is answered by one reply message. A single command's reply has no ';'
(as the public raw-TCP client's tests imply); a joined request's replies each end with ';'
('"Inertia set";[0.0,0.0,0.1];', assumed). Texts with letters come quoted ('"force"',
'"Inertia set"', '"true"'); numbers and vectors bare ('2.3', '[0.0,0.0,0.1]'); errors as
'--- ERROR: <text>'.

Device model: state (init/off/force/position/home/stop), the inertia m, and effect objects
(biasforce, spring, damper, cylinder, torus) with their properties. In state "force" the
end-effector moves as m*a = bias forces + springs + dampers + the external (user) force,
integrated at 1 kHz by its own thread, whether or not messages arrive, inside a box
(+-0.3 m) whose walls stop it. Effects persist when a client disconnects (a bias force stays
applied until a new one is set). A spring with a non-zero direction acts along that
direction only, and not at all within +-deadband of its position (beyond, it pulls the
stretch past the deadband back); its dampfactor is dimensionless, a fraction of critical damping
(c = dampfactor * 2 sqrt(k m)). State "stop" holds the end-effector still. Cylinders and tori
keep their properties but add no force (enough for the protocol tests).

Start-up facts: "get position_calibrated" (false with --uncalibrated until "set state init"
has homed for --homing-s seconds; the state is "init" meanwhile, then "stop", which is what
the public clients wait for), "get emergencybuttonpushed" (true with --emergency-button),
"get emergencyrelay" (false with --relay-off: the device was not started with its start
button), "get workspace_r" ([x low stop, distance to the base axis, x high stop], m),
"get workspace_phi" ([left, 0, right], rad), "get workspace_z" ([upper, 0, lower], m), "get
inertia". --leftover NAME leaves an enabled bias force of 5 N named NAME, as another program
would.

Test-only commands (not the device's): "emulator extforce [x,y,z]" sets the user's force;
"emulator log" returns the commands logged so far.

Misbehaviour for tests (each happens once, on the connection that reaches it; later
connections are served normally): --drop-after N closes the connection at the (N+1)-th
command; --stall-after N stops answering it (the connection stays open); --garbage-after N
answers it with a corrupt header; --fail-after N=TEXT answers it with "--- ERROR: TEXT" (a
device refusing a command mid-session); --fail COMMAND=TEXT answers the exact command COMMAND
with "--- ERROR: TEXT" (every time). --latency-ms L [--jitter-ms J] delays each request by
(L + U(0, J))/2 before it acts and its reply by as much again: a network's round trip.
--number-format FORMAT replies every number (alone or in a vector) as printf's FORMAT
would write it ("%g": six significant digits; default: full precision).
--log FILE appends every command received, one a line. --events FILE appends time-stamped
lines (CLOCK_MONOTONIC seconds): "<t> cmd <command>", "<t> fault <drop|stall|garbage|fail>",
and "<t> device state=<s> bias=<|sum of enabled bias forces| N>" whenever either changes.
"""

import argparse
import math
import random
import socket
import struct
import sys
import threading
import time

STATES = ("init", "off", "force", "position", "home", "stop")
OBJECT_TYPES = ("biasforce", "spring", "damper", "cylinder", "torus")
VECTOR_PROPS = {
    "biasforce": ("force",),
    "spring": ("pos", "direction"),
    "damper": ("dampcoef",),
    "cylinder": ("pos", "att"),
    "torus": ("pos", "att"),
}
NUMBER_PROPS = {
    "biasforce": (),
    "spring": ("stiffness", "dampfactor", "maxforce", "deadband"),
    "damper": (),
    "cylinder": ("stiffness", "dampfactor", "maxforce", "radius", "length"),
    "torus": ("stiffness", "dampfactor", "maxforce", "ringradius", "tuberadius"),
}
MIN_INERTIA, MAX_INERTIA = 0.1, 1000.0
# How the replies to "set <name> <property> <value>" name things (the public client's texts).
TYPE_TEXT = {"biasforce": "Bias force", "spring": "Spring", "damper": "Damper",
             "cylinder": "Cylinder", "torus": "Torus"}
PROP_TEXT = {"dampfactor": "damp factor", "maxforce": "maximum force",
             "dampcoef": "damp coefficient", "pos": "position"}
# The public example's workspace constants (radius 0.28..0.64 m about a base axis 0.45 m
# behind the origin, +-0.5 rad, z +-0.2 m) in the order the public clients read the replies:
# r as [x low stop, distance to the base axis, x high stop], phi as [left, -, right], z as
# [upper, -, lower].
WORKSPACE = {
    "workspace_r": (-0.17, 0.45, 0.19),
    "workspace_phi": (-0.5, 0.0, 0.5),
    "workspace_z": (0.2, 0.0, -0.2),
}
WALL = 0.3
DT = 0.001


class Error(Exception):
    pass


NUMBER_FORMAT = None  # --number-format: a printf format for every number replied


def fmt(x):
    if NUMBER_FORMAT is not None:
        return NUMBER_FORMAT % float(x)
    return repr(float(x))


def fmt_vec(v):
    return "[" + ",".join(fmt(x) for x in v) + "]"


def parse_number(text):
    try:
        x = float(text)
    except ValueError:
        raise Error("'%s' is not a number" % text)
    if not math.isfinite(x):
        raise Error("'%s' is not a finite number" % text)
    return x


def parse_vector(text):
    text = text.strip()
    if not (text.startswith("[") and text.endswith("]")):
        raise Error("'%s' is not a vector [x,y,z]" % text)
    parts = text[1:-1].split(",")
    if len(parts) != 3:
        raise Error("'%s' is not a vector of 3 numbers" % text)
    return [parse_number(p.strip()) for p in parts]


class Device:
    def __init__(self, ext_force, args=None):
        self.lock = threading.Lock()
        self.args = args
        self.state = "off"
        self.calibrated = not (args and args.uncalibrated)
        self.homing_until = None
        self.emergency_button = bool(args and args.emergency_button)
        self.relay_closed = not (args and args.relay_off)
        self.events = open(args.events, "a") if (args and args.events) else None
        self.reported = None
        self.inertia = 3.0
        self.objects = {}  # name -> dict(type=..., enabled=bool, props)
        self.pos = [0.0, 0.0, 0.0]
        self.vel = [0.0, 0.0, 0.0]
        self.ext = list(ext_force)
        self.last_time = time.monotonic()
        self.log = []

    def object_forces(self):
        total = [0.0, 0.0, 0.0]
        for obj in self.objects.values():
            if not obj["enabled"]:
                continue
            kind = obj["type"]
            if kind == "biasforce":
                f = obj["force"]
            elif kind == "spring":
                k = obj["stiffness"]
                c = obj["dampfactor"] * 2.0 * math.sqrt(max(k, 0.0) * self.inertia)
                d = obj["direction"]
                dn = math.sqrt(sum(x * x for x in d))
                if dn > 0:  # along the direction only
                    u = [x / dn for x in d]
                    dx = sum((self.pos[i] - obj["pos"][i]) * u[i] for i in range(3))
                    dv = sum(self.vel[i] * u[i] for i in range(3))
                    band = obj["deadband"]
                    if abs(dx) <= band:  # no force inside the deadband, none of its damping
                        f = [0.0, 0.0, 0.0]
                    else:
                        stretch = dx - math.copysign(band, dx)
                        f = [(-k * stretch - c * dv) * u[i] for i in range(3)]
                else:
                    f = [-k * (self.pos[i] - obj["pos"][i]) - c * self.vel[i] for i in range(3)]
                n = math.sqrt(sum(x * x for x in f))
                if obj["maxforce"] > 0 and n > obj["maxforce"]:
                    f = [x * obj["maxforce"] / n for x in f]
            elif kind == "damper":
                f = [-obj["dampcoef"][i] * self.vel[i] for i in range(3)]
            else:
                continue
            total = [total[i] + f[i] for i in range(3)]
        return total

    def event(self, text):
        if self.events:
            self.events.write("%.6f %s\n" % (time.monotonic(), text))
            self.events.flush()

    def bias_total(self):
        total = [0.0, 0.0, 0.0]
        for obj in self.objects.values():
            if obj["enabled"] and obj["type"] == "biasforce":
                total = [total[i] + obj["force"][i] for i in range(3)]
        return math.sqrt(sum(x * x for x in total))

    def report(self):
        """Logs the state and the applied bias force whenever either changed."""
        now = (self.state, round(self.bias_total(), 6))
        if now != self.reported:
            self.reported = now
            self.event("device state=%s bias=%s" % now)

    def run(self):
        """The device's own control loop: the model runs whether or not messages arrive."""
        while True:
            time.sleep(DT)
            with self.lock:
                self.advance()

    def advance(self):
        """Integrates the admittance model up to now (semi-implicit Euler, 1 kHz)."""
        now = time.monotonic()
        steps = int((now - self.last_time) / DT)
        steps = min(steps, 5000)  # after a long pause, do not spin
        self.last_time = now if steps == 5000 else self.last_time + steps * DT
        if self.homing_until is not None and now >= self.homing_until:
            self.homing_until = None
            self.calibrated = True
            self.state = "stop"
            self.report()
        if self.state != "force":
            self.vel = [0.0, 0.0, 0.0]
            return
        for _ in range(steps):
            f = self.object_forces()
            for i in range(3):
                self.vel[i] += (f[i] + self.ext[i]) / self.inertia * DT
                self.pos[i] += self.vel[i] * DT
                if abs(self.pos[i]) > WALL:
                    self.pos[i] = math.copysign(WALL, self.pos[i])
                    self.vel[i] = 0.0

    def new_object(self, kind):
        obj = {"type": kind, "enabled": False}
        for p in VECTOR_PROPS[kind]:
            obj[p] = [0.0, 0.0, 0.0]
        for p in NUMBER_PROPS[kind]:
            obj[p] = 0.0
        return obj

    def execute(self, command):
        words = command.split(None, 3)
        if not words:
            raise Error("empty command")
        verb = words[0]
        if verb == "get" and len(words) == 2:
            what = words[1]
            if what == "state":
                return self.state
            if what == "inertia":
                return fmt(self.inertia)
            if what == "position_calibrated":
                return "true" if self.calibrated else "false"
            if what == "emergencybuttonpushed":
                return "true" if self.emergency_button else "false"
            if what == "emergencyrelay":
                return "true" if self.relay_closed else "false"
            if what in WORKSPACE:
                return fmt_vec(WORKSPACE[what])
            if what in ("measpos", "modelpos"):
                return fmt_vec(self.pos)
            if what == "modelvel":
                return fmt_vec(self.vel)
            if what == "measforce":
                return fmt_vec(self.ext)
            raise Error("Unknown parameter '%s'" % what)
        if verb == "get" and len(words) == 3:
            obj = self.objects.get(words[1])
            if obj is None:
                raise Error("No effect with name '%s'" % words[1])
            prop = words[2]
            if prop == "enabled":
                return "true" if obj["enabled"] else "false"
            if prop not in obj or prop == "type":
                raise Error("Effect '%s' has no property '%s'" % (words[1], prop))
            value = obj[prop]
            return fmt_vec(value) if isinstance(value, list) else fmt(value)
        if verb == "set" and len(words) >= 3 and words[1] == "state" and len(words) == 3:
            if words[2] not in STATES:
                raise Error("Unknown state '%s'" % words[2])
            if words[2] == "force" and not self.calibrated:
                raise Error("Position not calibrated: set state init first")
            if words[2] == "force" and (self.emergency_button or not self.relay_closed):
                raise Error("Emergency stop active")
            self.state = words[2]
            if self.state == "init":
                self.homing_until = time.monotonic() + (self.args.homing_s if self.args else 1.0)
            return "state set to '%s'" % self.state
        if verb == "set" and words[1] == "inertia" and len(words) == 3:
            value = parse_number(words[2])
            if not MIN_INERTIA <= value <= MAX_INERTIA:
                raise Error("Inertia %s out of range" % words[2])
            self.inertia = value
            return "Inertia set"
        if verb == "set" and len(words) >= 3:
            name, prop = words[1], words[2]
            obj = self.objects.get(name)
            if obj is None:
                raise Error("No effect with name '%s'" % name)
            if prop in ("enable", "disable") and len(words) == 3:
                obj["enabled"] = prop == "enable"
                return "Effect %sd" % prop
            if len(words) != 4:
                raise Error("'set %s %s' needs a value" % (name, prop))
            if prop in VECTOR_PROPS[obj["type"]]:
                obj[prop] = parse_vector(words[3])
            elif prop in NUMBER_PROPS[obj["type"]]:
                obj[prop] = parse_number(words[3])
            else:
                raise Error("Effect %s has no property '%s'" % (obj["type"], prop))
            return "%s's %s set" % (TYPE_TEXT[obj["type"]], PROP_TEXT.get(prop, prop))
        if verb == "create" and len(words) == 3:
            kind, name = words[1], words[2]
            if kind not in OBJECT_TYPES:
                raise Error("Unknown effect type '%s'" % kind)
            if name in self.objects:
                raise Error("An effect with name '%s' already exists" % name)
            self.objects[name] = self.new_object(kind)
            return "Effect %s with name %s created" % (kind, name)
        if verb == "remove" and len(words) == 2:
            if words[1] == "all":
                self.objects.clear()
                return "All effects Removed"
            if self.objects.pop(words[1], None) is None:
                raise Error("No effect with name '%s'" % words[1])
            return "Effect Removed"
        if verb == "emulator" and len(words) >= 2:
            if words[1] == "extforce" and len(words) >= 3:
                self.ext = parse_vector(command.split(None, 2)[2])
                return "External force set"
            if words[1] == "log" and len(words) == 2:
                return "|".join(self.log)
        raise Error("Unknown command '%s'" % command)


def styled(reply):
    """Texts with letters quoted, numbers and vectors bare, errors as they are."""
    if reply.startswith("--- ERROR") or reply.startswith('"') or reply.startswith("["):
        return reply
    try:
        float(reply)
        return reply
    except ValueError:
        return '"%s"' % reply


def frame(text):
    data = text.encode("ascii", "replace")
    return struct.pack(">II", len(data), 0) + data


def recv_exact(conn, n):
    data = b""
    while len(data) < n:
        chunk = conn.recv(n - len(data))
        if not chunk:
            return None
        data += chunk
    return data


def delay(args):
    if not args.latency_ms and not args.jitter_ms:
        return
    total = (args.latency_ms + random.uniform(0.0, args.jitter_ms)) / 1000.0
    time.sleep(total / 2.0)


def serve(conn, device, args, faults, log_file):
    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    while True:
        header = recv_exact(conn, 8)
        if header is None:
            return
        (length, _) = struct.unpack(">II", header)
        body = recv_exact(conn, length)
        if body is None:
            return
        delay(args)  # the request travels to the device
        replies = []
        for command in body.decode("ascii", "replace").split(";"):
            command = command.strip()
            if not command:
                continue
            fault = faults.next(command)
            if fault == "drop":
                device.event("fault drop")
                conn.close()
                return
            if fault == "stall":
                device.event("fault stall")
                while True:  # this connection never answers again; others still do
                    if recv_exact(conn, 8) is None:
                        return
            if fault == "garbage":
                device.event("fault garbage")
                conn.sendall(b"\xff\xff\xff\xffgarbage")
                continue
            if fault == "fail":
                device.event("fault fail")
                replies.append("--- ERROR: " + args.fail_after_text)
                continue
            with device.lock:
                if log_file:
                    log_file.write(command + "\n")
                    log_file.flush()
                device.event("cmd " + command)
                device.log.append(command)
                device.advance()
                if command in args.fail:
                    device.event("fault fail")
                    reply = "--- ERROR: " + args.fail[command]
                elif command in args.answer:
                    reply = args.answer[command]
                else:
                    try:
                        reply = device.execute(command)
                    except Error as e:
                        reply = "--- ERROR: " + str(e)
                    reply = styled(reply)
                device.report()
            replies.append(reply)
        if replies:
            delay(args)  # and the reply back
            text = replies[0] if len(replies) == 1 else "".join(r + ";" for r in replies)
            conn.sendall(frame(text))


class Faults:
    """Counts commands over every connection; each fault fires once, at its count."""

    def __init__(self, args):
        self.lock = threading.Lock()
        self.count = 0
        self.pending = {}
        for name in ("drop", "stall", "garbage", "fail"):
            after = getattr(args, name + "_after")
            if after is not None:
                self.pending[name] = after

    def next(self, command):
        with self.lock:
            self.count += 1
            for name, after in list(self.pending.items()):
                if self.count > after:
                    del self.pending[name]
                    return name
        return None


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--port", type=int, default=0)
    parser.add_argument("--ext-force", default="[0,0,0]", help="the user's force [x,y,z] in N")
    parser.add_argument("--log", help="append every command received to this file")
    parser.add_argument("--drop-after", type=int)
    parser.add_argument("--stall-after", type=int)
    parser.add_argument("--garbage-after", type=int)
    parser.add_argument("--fail-after", metavar="N=TEXT")
    parser.add_argument("--fail", action="append", default=[], metavar="COMMAND=TEXT")
    parser.add_argument("--answer", action="append", default=[], metavar="COMMAND=TEXT")
    parser.add_argument("--events", help="append time-stamped events to this file")
    parser.add_argument("--latency-ms", type=float, default=0.0)
    parser.add_argument("--jitter-ms", type=float, default=0.0)
    parser.add_argument("--uncalibrated", action="store_true")
    parser.add_argument("--homing-s", type=float, default=1.0)
    parser.add_argument("--emergency-button", action="store_true")
    parser.add_argument("--relay-off", action="store_true")
    parser.add_argument("--leftover", action="append", default=[], metavar="NAME")
    parser.add_argument("--number-format", metavar="FORMAT",
                        help="printf format of every number replied (%%g, %%.6f; default: "
                             "full precision, Python's repr)")
    args = parser.parse_args()
    global NUMBER_FORMAT
    if args.number_format is not None:
        args.number_format % 1.0  # a bad format fails here, not at the first reply
        NUMBER_FORMAT = args.number_format
    args.fail = dict(item.partition("=")[::2] for item in args.fail)
    args.fail_after_text = ""
    if args.fail_after is not None:
        count, _, args.fail_after_text = args.fail_after.partition("=")
        args.fail_after = int(count)
    args.answer = dict(item.partition("=")[::2] for item in args.answer)

    device = Device(parse_vector(args.ext_force), args)
    for name in args.leftover:  # effects another program left behind
        obj = device.new_object("biasforce")
        obj["force"] = [5.0, 0.0, 0.0]
        obj["enabled"] = True
        device.objects[name] = obj
    device.report()
    threading.Thread(target=device.run, daemon=True).start()
    server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    server.bind(("127.0.0.1", args.port))
    server.listen(8)
    print("PORT %d" % server.getsockname()[1], flush=True)
    log_file = open(args.log, "a") if args.log else None
    faults = Faults(args)

    def client(conn):
        try:
            serve(conn, device, args, faults, log_file)
        except OSError:
            pass
        finally:
            try:
                conn.close()
            except OSError:
                pass

    while True:
        conn, _ = server.accept()
        threading.Thread(target=client, args=(conn,), daemon=True).start()


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:
        sys.exit(0)

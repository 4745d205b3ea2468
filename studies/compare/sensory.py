"""The sensory door model (door-models.md section 2) in plain numpy, with the data of the
fit benchmark and the simulation the comparison fits use.

Written as a researcher would for a study: the spec's formulas as printed (S with tanh),
a fixed-step classic Runge-Kutta integrator under the measured force, vectorized over
strokes (and over parameter sets, for the genetic algorithm), nothing compiled.

The integrator is the one doorbench's fit uses (analysis/fit/fit_windows.h): classic RK4,
2 steps per sample interval, the force linear between samples, started from the measured
state at a sequence's first sample. check_model.py compares it with the C++ one.
"""

import csv
import json
import os

import numpy as np

NAMES = ["J", "k", "k_inf", "k_lock", "theta0", "theta1", "theta2", "theta3", "c",
         "d1", "d2", "s", "theta4", "beta", "beta_f", "k_stop", "c_stop"]
INDEX = {name: i for i, name in enumerate(NAMES)}
RUNAWAY_RATE = 1e3  # rad/s: beyond this a trial parameter set has blown up


# --- the model ---------------------------------------------------------------------------

def S(x, x0, beta):
    """The spec's switch: about 0 below x0, about 1 above."""
    return 0.5 * (1.0 + np.tanh(beta * (x - x0)))


def W(x, a, b, beta):
    """About 1 for a < x < b, about 0 outside."""
    return S(x, a, beta) - S(x, b, beta)


def torque(p, theta, omega, theta_max):
    """tau_m(theta, omega) in N m for parameters p (shape (17,) or (P, 17)); theta and omega
    broadcast against p's leading axes followed by one more axis."""
    (J, k, k_inf, k_lock, th0, th1, th2, th3, c, d1, d2, s, th4, beta, beta_f, k_stop,
     c_stop) = (p[..., i, None] for i in range(len(NAMES)))
    unlatch = -(k * theta + k_inf * (theta - th0) * S(theta, th0, beta)) * (1 - S(theta, th1, beta))
    snap = c * omega * W(theta, th1, th2, beta)
    latch = k_lock * (th3 - theta) * W(theta, th2, th3, beta)
    friction = -np.tanh(s * omega) * (d1 - d2 * (1 - S(theta, th4, beta_f)))
    stops = np.where(theta > theta_max, -(k_stop * (theta - theta_max) + c_stop * omega),
                     np.where(theta < 0, -(k_stop * theta + c_stop * omega), 0.0))
    return unlatch + snap + latch + friction + stops


def integrate(p, seq, r_h, theta_max, substeps=2):
    """Simulates every sequence of `seq` (whole strokes or windows: arrays t, F of shape
    (M, L), first states theta0, omega0 of shape (M,)) under its measured force with
    classic RK4, `substeps` steps per sample interval. Returns theta, omega of shape
    p.shape[:-1] + (M, L); a sequence that runs away is NaN from there on."""
    p = np.asarray(p, dtype=float)
    t, F = seq["t"], seq["F"]
    M, L = t.shape
    shape = p.shape[:-1] + (M,)
    theta = np.broadcast_to(seq["theta0"], shape).copy()
    omega = np.broadcast_to(seq["omega0"], shape).copy()
    out_theta = np.empty(shape + (L,))
    out_omega = np.empty(shape + (L,))
    out_theta[..., 0] = theta
    out_omega[..., 0] = omega
    inverse_J = 1.0 / p[..., INDEX["J"], None]
    fraction = 1.0 / substeps
    with np.errstate(all="ignore"):
        for j in range(L - 1):
            h = (t[:, j + 1] - t[:, j]) * fraction
            half_h, sixth_h = 0.5 * h, h / 6.0
            tau_k = r_h * F[:, j]
            tau_step = r_h * (F[:, j + 1] - F[:, j]) * fraction
            for m in range(substeps):
                tau_start = tau_k + tau_step * m
                tau_middle = tau_start + 0.5 * tau_step
                tau_end = tau_start + tau_step
                a1 = (torque(p, theta, omega, theta_max) + tau_start) * inverse_J
                theta2, omega2 = theta + omega * half_h, omega + a1 * half_h
                a2 = (torque(p, theta2, omega2, theta_max) + tau_middle) * inverse_J
                theta3, omega3 = theta + omega2 * half_h, omega + a2 * half_h
                a3 = (torque(p, theta3, omega3, theta_max) + tau_middle) * inverse_J
                theta4, omega4 = theta + omega3 * h, omega + a3 * h
                a4 = (torque(p, theta4, omega4, theta_max) + tau_end) * inverse_J
                theta = theta + (omega + (omega2 + omega3) * 2.0 + omega4) * sixth_h
                omega = omega + (a1 + (a2 + a3) * 2.0 + a4) * sixth_h
            runaway = ~(np.abs(omega) <= RUNAWAY_RATE) | ~np.isfinite(theta)
            theta[runaway] = np.nan
            omega[runaway] = np.nan
            out_theta[..., j + 1] = theta
            out_omega[..., j + 1] = omega
    return out_theta, out_omega


# --- the data ----------------------------------------------------------------------------

class Data:
    """The benchmark's strokes and setup as exported by doorbench_export_fit_strokes."""

    def __init__(self, directory):
        with open(os.path.join(directory, "setup.json")) as f:
            self.setup = json.load(f)
        params = self.setup["parameters"]
        assert [q["name"] for q in params] == NAMES, "parameter order differs from the model's"
        self.truth = np.array([q["truth"] for q in params])
        self.start = np.array([q["start"] for q in params])
        self.lower = np.array([q["bounds"][0] for q in params])
        self.upper = np.array([q["bounds"][1] for q in params])
        self.free = np.array([i for i, q in enumerate(params) if q["free"]])
        self.r_h = self.setup["handle_radius_m"]
        self.theta_max = self.setup["theta_max_rad"]
        self.sigma_theta = self.setup["noise"]["angle_rad"]
        self.sigma_omega = self.setup["noise"]["rate_rad_s"]
        self.strokes = read_strokes(os.path.join(directory, "strokes.csv"))
        self.ids = [s["id"] for s in self.setup["strokes"]]
        assert self.ids == list(self.strokes), "strokes.csv and setup.json disagree"
        self.whole = sequences([self.strokes[i] for i in self.ids], [(0, None)] * len(self.ids))
        self.samples = sum(len(self.strokes[i]["t"]) for i in self.ids)

    def windows(self, window_samples=200):
        """0.2 s windows (200 sample intervals at 1 kHz) that share their boundary samples,
        each started from the measured state; a last piece shorter than half a window joins
        the window before it."""
        parts, spans = [], []
        for i in self.ids:
            n = len(self.strokes[i]["t"])
            starts = list(range(0, n - 1, window_samples))
            if len(starts) > 1 and (n - 1) - starts[-1] < window_samples // 2:
                starts.pop()
            for w, first in enumerate(starts):
                last = starts[w + 1] if w + 1 < len(starts) else n - 1
                parts.append(self.strokes[i])
                spans.append((first, last + 1))
        return sequences(parts, spans)

    def full(self, free_values):
        """All 17 parameters from the free ones (the rest at the truth's fixed values)."""
        free_values = np.asarray(free_values, dtype=float)
        p = np.broadcast_to(self.truth, free_values.shape[:-1] + (len(NAMES),)).copy()
        p[..., self.free] = free_values
        return p


def read_strokes(path):
    strokes = {}
    with open(path) as f:
        rows = csv.DictReader(line for line in f if not line.startswith("#"))
        for row in rows:
            s = strokes.setdefault(int(row["stroke"]), {"t": [], "F": [], "theta": [], "omega": []})
            s["t"].append(float(row["time_s"]))
            s["F"].append(float(row["force_N"]))
            s["theta"].append(float(row["angle_rad"]))
            s["omega"].append(float(row["rate_rad_s"]))
    return {k: {c: np.array(v) for c, v in s.items()} for k, s in strokes.items()}


def sequences(strokes, spans):
    """Pads the spans [first, end) of the strokes into (M, L) arrays; padded samples keep the
    last time step and force and are masked out."""
    lengths = [(end if end is not None else len(s["t"])) - first
               for s, (first, end) in zip(strokes, spans)]
    M, L = len(strokes), max(lengths)
    out = {c: np.zeros((M, L)) for c in ("t", "F", "theta", "omega")}
    mask = np.zeros((M, L), dtype=bool)
    for m, (s, (first, _), n) in enumerate(zip(strokes, spans, lengths)):
        for c in out:
            out[c][m, :n] = s[c][first:first + n]
        dt = s["t"][first + n - 1] - s["t"][first + n - 2]
        out["t"][m, n:] = s["t"][first + n - 1] + dt * np.arange(1, L - n + 1)
        out["F"][m, n:] = s["F"][first + n - 1]
        mask[m, 1:n] = True  # the first sample is the start state, not a residual
    out["mask"] = mask
    out["theta0"] = out["theta"][:, 0].copy()
    out["omega0"] = out["omega"][:, 0].copy()
    return out


# --- metrics -----------------------------------------------------------------------------

def omega_errors(p, data, seq):
    """omega_sim - omega_meas at every residual sample of `seq` (NaN where a run blew up)."""
    _, omega = integrate(p, seq, data.r_h, data.theta_max)
    return (omega - seq["omega"])[..., seq["mask"]]


def metrics(p, data):
    """RMSE and largest |omega error| replaying whole strokes (the study's figure) and on
    0.2 s windows from the measured states."""
    out = {}
    for name, seq in (("replay", data.whole), ("windows", data.windows())):
        e = omega_errors(p, data, seq)
        out[name] = {"rmse_rad_s": float(np.sqrt(np.mean(e ** 2))),
                     "max_abs_rad_s": float(np.max(np.abs(e)))}
    return out


def parameter_errors(p, data):
    """Relative error (%) of every free parameter against the truth."""
    return {NAMES[i]: float(100 * (p[i] - data.truth[i]) / data.truth[i]) for i in data.free}


def constraint_breaks(p):
    """The spec's ordering constraints that p breaks (empty when it is a valid door)."""
    q = dict(zip(NAMES, p))
    broken = []
    if not (0 < q["theta0"] < q["theta1"] < q["theta2"] < q["theta3"]):
        broken.append("0 < theta0 < theta1 < theta2 < theta3")
    if not (q["d1"] >= q["d2"] >= 0):
        broken.append("d1 >= d2 >= 0")
    return broken


def report(method, p, data, wall_s, evaluations, extra=None):
    """The result of one method as a JSON-ready dict."""
    p = np.asarray(p, dtype=float)
    errors = parameter_errors(p, data)
    worst = max(errors, key=lambda n: abs(errors[n]))
    out = {"method": method, "wall_s": wall_s, "evaluations": evaluations,
           "values": dict(zip(NAMES, p.tolist())), "error_percent": errors,
           "largest_error_percent": abs(errors[worst]), "largest_error_parameter": worst,
           "constraint_breaks": constraint_breaks(p), "metrics": metrics(p, data)}
    out.update(extra or {})
    return out

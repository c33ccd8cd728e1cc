"""The power stage in a circuit simulator: ngspice netlists built from a Stage,
run through `ngspice -b`, parsed (issue 36, item 2). It checks the tank
calculator (texelpad/plate/tank.py) against a circuit with switches, dead
time, body diodes, the DC-blocking capacitor and the piezo as a
Butterworth-Van Dyke model (hardware/README.md "Power stage").

    Stage(kind=, bus_volts=, inductance_h=, ...)     the circuit (SI units)
    tuned(kind, ...)                                 a Stage whose C_tune puts the
                                                     tank on the carrier, C_block included
    ac_sweep(stage)        -> Resonance              peak frequency, -3 dB Q, peak gain
    steady(stage, duty)    -> Steady                 piezo fundamental, drain peak
    envelope(stage, d0, d1) -> Envelope              time constant of a duty step
    netlist(stage, ...)                              the text ngspice runs
    figures(q)                                       the figures against `texelpad tank`:
                                                     python -m texelpad.plate.spice [Q]

The circuit, per kind (node names as in the netlists):

    single   V_bus -S_hi- sw -S_lo- 0;  sw -R_esr-L- x -C_block- p;  piezo p..0
    bridge   two such legs, sw_a and sw_b (leg B complementary: its high side
             is driven by leg A's low-side gate); piezo p..sw_b
    minimal  V_bus -R_esr-L- sw (the drain); S sw..0 (one low-side MOSFET);
             sw -C_block- p; piezo p..0 (the class-E-like variant)

The piezo: C0 (the clamped capacitance, `piezo_f`, what `texelpad tank
--piezo` takes) || C_tune || the bleed resistor || the motional branch
Rm-Lm-Cm. The motional branch's series resonance is placed at the tank's
frequency (mode_hz None) and Rm is chosen so that the tank's loaded Q (with
the inductor's ESR) is `q`: the electrical tank's loss is modelled as the
plate's mechanical load, the "simpler" model of the issue. Cm = coupling * C0
with coupling = 0.1 (k_eff = sqrt(Cm/(C0+Cm)) = 0.30: hard-PZT discs have a
planar k_p of 0.5..0.6, bonding them to glass lowers the effective value).
With the Rm that gives a loaded Q of 10..50, the branch's own Q,
1/(2 pi f Cm Rm), is below 1: it is a resistive load near f0, not a second
resonator, which is exactly the single resonance `texelpad tank` assumes. A
high-Q mechanical mode with the same coupling (coupling 1e-3 .. 1e-4 with
Rm = q * sqrt(L/C)) splits the response into two peaks: the calculator's
f and Q are then only a first guess, as hardware/README.md says.

Switches: ngspice voltage-controlled switches (SW model, Ron/Roff) with a
body diode each. The drive follows the board (the RP2040's PWM is
edge-aligned: high from the start of each period for D*T) and an
IR2104-class driver: each turn-on is delayed by the dead time, turn-offs are
not. Constant duty: PULSE sources; a duty schedule (the envelope): PWL
sources with the same edges.

Every run is in a fresh temporary directory with a timeout; a missing or
failing ngspice raises SpiceError naming the step. Pure: no texelpad.link,
no web.
"""
from __future__ import annotations

import math
import os
import shutil
import subprocess
import tempfile
from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np

from . import tank

KINDS = ("single", "bridge", "minimal")
# samples per carrier period on the linearized transient grid (the DFT uses
# whole periods of it); 256 resolve a 0.5 us dead time at 34 kHz (29.4 us)
SAMPLES_PER_PERIOD = 256
# gate rise / fall time, s (a gate driver's ~10..20 ns)
EDGE_S = 10e-9
# settle this many envelope time constants before measuring a steady state:
# the start-up transient is then exp(-7) = 0.09 % of the amplitude
SETTLE_TAUS = 7.0
TIMEOUT_S = 60.0


class SpiceError(RuntimeError):
    """ngspice is missing, timed out or failed; `step` names the netlist step."""

    def __init__(self, step: str, message: str):
        super().__init__("ngspice, %s: %s" % (step, message))
        self.step = step


@dataclass(frozen=True)
class Stage:
    """A power stage and its load, SI units (H, F, Hz, V, ohm, s)."""
    kind: str = "single"
    bus_volts: float = 24.0
    inductance_h: float = 390e-6        # the TPad Fire's series inductor
    esr_ohm: float = 0.5                # a ferrite inductor's loss at 34 kHz
    c_block_f: float = 2.2e-6           # >= 20 x the tank capacitance (README)
    c_tune_f: float = 0.0
    piezo_f: float = 40e-9              # C0, as given to `texelpad tank --piezo`
    q: float = 20.0                     # the loaded tank's Q (sets Rm)
    coupling: float = 0.1               # Cm / C0 (module docstring)
    mode_hz: float | None = None        # the motional branch's resonance; None: the tank's
    carrier_hz: float = 34000.0
    dead_time_s: float = 0.5e-6         # IR2104-class (hardware/README.md bill of materials)
    ron_ohm: float = 0.05               # MOSFET R_DS(on): "tens of mOhm"
    roff_ohm: float = 1e7
    coss_f: float = 300e-12             # MOSFET output capacitance (tens of mOhm parts)
    bleed_ohm: float = 1e6              # the 1 MOhm bleed resistor across the piezo

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError("kind: must be one of %s, got %r" % (", ".join(KINDS), self.kind))
        for name in ("bus_volts", "inductance_h", "esr_ohm", "c_block_f", "piezo_f", "q",
                     "coupling", "carrier_hz", "ron_ohm", "roff_ohm", "coss_f", "bleed_ohm"):
            tank._positive(name, getattr(self, name))
        if self.c_tune_f < 0 or not math.isfinite(self.c_tune_f):
            raise ValueError("c_tune_f: must be >= 0, got %r" % (self.c_tune_f,))
        if not 0.0 <= self.dead_time_s < 0.25 / self.carrier_hz:
            raise ValueError("dead_time_s: must be in [0, a quarter period), got %r"
                             % (self.dead_time_s,))
        self.motional()                 # Rm > 0: the ESR alone must not exceed the loss

    @property
    def piezo_side_f(self) -> float:
        """C0 + C_tune, F: the capacitance across the piezo."""
        return self.piezo_f + self.c_tune_f

    @property
    def tank_capacitance_f(self) -> float:
        """C_block in series with C0 + C_tune, F: what `texelpad tank -C` takes."""
        cp, cb = self.piezo_side_f, self.c_block_f
        return cp * cb / (cp + cb)

    @property
    def tank_hz(self) -> float:
        return tank.resonant_frequency(self.inductance_h, self.tank_capacitance_f)

    @property
    def piezo_share(self) -> float:
        """The piezo's part of the series capacitors' voltage, C_b / (C_b + C_p)."""
        return self.c_block_f / (self.c_block_f + self.piezo_side_f)

    def motional(self) -> tuple[float, float, float]:
        """(Rm ohm, Lm H, Cm F). Rm: the parallel loss across C_p whose
        series equivalent, 1/(w^2 C_p^2 Rm), adds to the ESR to give
        w L / q (the loaded Q)."""
        w = 2.0 * math.pi * self.tank_hz
        r_series = w * self.inductance_h / self.q - self.esr_ohm
        if r_series <= 0:
            raise ValueError("q: %g is above what the inductor's ESR (%g ohm) allows, %.3g"
                             % (self.q, self.esr_ohm, w * self.inductance_h / self.esr_ohm))
        rm = 1.0 / (w * w * self.piezo_side_f ** 2 * r_series)
        cm = self.coupling * self.piezo_f
        wm = 2.0 * math.pi * (self.mode_hz or self.tank_hz)
        return rm, 1.0 / (wm * wm * cm), cm


def tuned(kind: str = "single", **kw: float) -> Stage:
    """A Stage whose C_tune makes the tank (C_block in series) resonate at the
    carrier: C_total = tank.capacitance_for(L, f), C_p = 1/(1/C_total - 1/C_b)."""
    s = Stage(kind=kind, **kw)          # type: ignore[arg-type]
    need = tank.capacitance_for(s.inductance_h, s.carrier_hz)
    if need >= s.c_block_f:
        raise ValueError("c_block_f: must be well above the tank capacitance %.3g F" % need)
    cp = 1.0 / (1.0 / need - 1.0 / s.c_block_f)
    if cp < s.piezo_f:
        raise ValueError("piezo_f: %.3g F is more than the %.3g F the inductor needs at %g Hz"
                         " (a smaller inductor: texelpad tank --piezo)"
                         % (s.piezo_f, cp, s.carrier_hz))
    return replace(s, c_tune_f=cp - s.piezo_f)


# --- netlists ----------------------------------------------------------------------

def _g(x: float) -> str:
    return "%.9g" % x


def _load_lines(s: Stage, sw: str, ret: str) -> list[str]:
    """L (with ESR), C_block and the piezo (BVD, C_tune, bleed) from node sw to ret."""
    rm, lm, cm = s.motional()
    out = ["Rl %s l1 %s" % (sw, _g(s.esr_ohm)), "L1 l1 x %s" % _g(s.inductance_h),
           "Cb x p %s" % _g(s.c_block_f), "C0 p %s %s" % (ret, _g(s.piezo_f)),
           "Rb p %s %s" % (ret, _g(s.bleed_ohm)),
           "Rm p m1 %s" % _g(rm), "Lm m1 m2 %s" % _g(lm), "Cm m2 %s %s" % (ret, _g(cm))]
    if s.c_tune_f > 0:
        out.append("Ct p %s %s" % (ret, _g(s.c_tune_f)))
    return out


def _models(s: Stage) -> list[str]:
    return [".model swm sw(vt=0.5 vh=0 ron=%s roff=%s)" % (_g(s.ron_ohm), _g(s.roff_ohm)),
            ".model dbody d(is=1e-9 n=1.5 rs=0.02)"]


def _leg(s: Stage, name: str, out: str, hi: str, lo: str) -> list[str]:
    """A half bridge: S from bus to out (gate hi), out to 0 (gate lo), body
    diodes and output capacitances."""
    return ["S%sh bus %s %s 0 swm" % (name, out, hi), "D%sh %s bus dbody" % (name, out),
            "C%sh bus %s %s" % (name, out, _g(s.coss_f)),
            "S%sl %s 0 %s 0 swm" % (name, out, lo), "D%sl 0 %s dbody" % (name, out),
            "C%sl %s 0 %s" % (name, out, _g(s.coss_f))]


def _pulse(width: float, delay: float, period: float) -> str:
    """A gate PULSE on for `width` s (threshold to threshold) after `delay`."""
    if width <= EDGE_S:
        return "DC 0"
    return "PULSE(0 1 %s %s %s %s %s)" % (_g(delay - EDGE_S / 2), _g(EDGE_S), _g(EDGE_S),
                                           _g(width - EDGE_S), _g(period))


def _gate_intervals(s: Stage, duties: Sequence[float]) -> tuple[list[tuple[float, float]],
                                                                list[tuple[float, float]]]:
    """(high-side, low-side) gate on-intervals for one duty per period: the
    input is high for D*T from each period's start (edge-aligned PWM); each
    turn-on waits the dead time (IR2104-class driver)."""
    T, dt = 1.0 / s.carrier_hz, s.dead_time_s
    ins: list[list[float]] = []
    for k, d in enumerate(duties):
        if d <= 0:
            continue
        a, b = k * T, k * T + min(d, 1.0) * T
        if ins and abs(ins[-1][1] - a) < 1e-15:
            ins[-1][1] = b               # D = 1: the input stays high
        else:
            ins.append([a, b])
    end = len(duties) * T
    hi = [(a + dt, b) for a, b in ins if b - a > dt + EDGE_S]
    lo, t = [], 0.0
    for a, b in ins:
        if a - t > dt + EDGE_S:
            lo.append((t + (dt if t > 0 else 0.0), a))
        t = b
    if end - t > dt + EDGE_S:
        lo.append((t + (dt if t > 0 else 0.0), end))
    return hi, lo


def _pwl(intervals: list[tuple[float, float]]) -> str:
    if not intervals:
        return "DC 0"
    e = EDGE_S / 2
    pts = ["0 1"] if intervals[0][0] <= e else ["0 0"]
    for a, b in intervals:
        if a > e:
            pts += ["%s 0" % _g(a - e), "%s 1" % _g(a + e)]
        pts += ["%s 1" % _g(b - e), "%s 0" % _g(b + e)]
    return "PWL(%s)" % " ".join(pts)


def _sources(s: Stage, duties: Sequence[float] | float) -> list[str]:
    """The bus and the gate sources: PULSE for one duty, PWL for a schedule."""
    T, dt = 1.0 / s.carrier_hz, s.dead_time_s
    if isinstance(duties, (int, float)):
        d = float(duties)
        if not 0.0 <= d <= 1.0:
            raise ValueError("duty: must be in [0, 1], got %r" % (duties,))
        if s.kind == "minimal":
            hi, lo = _pulse(d * T, 0.0, T), "DC 0"
        else:
            hi = _pulse(d * T - dt, dt, T)
            lo = _pulse((1.0 - d) * T - dt, d * T + dt, T) if d > 0 else "DC 1"
    else:
        on = [(k * T, (k + min(max(x, 0.0), 1.0)) * T) for k, x in enumerate(duties)]
        if s.kind == "minimal":
            hi, lo = _pwl([(a, b) for a, b in on if b - a > EDGE_S]), "DC 0"
        else:
            ih, il = _gate_intervals(s, duties)
            hi, lo = _pwl(ih), _pwl(il)
    return ["Vbus bus 0 DC %s" % _g(s.bus_volts), "Vgh gh 0 %s" % hi, "Vgl gl 0 %s" % lo]


def _circuit(s: Stage, duties: Sequence[float] | float) -> list[str]:
    """The switching circuit of s.kind; the piezo is p..0 (p..sw_b for a bridge)."""
    if s.kind == "minimal":
        return (_sources(s, duties) + _models(s)
                + ["Rl bus l1 %s" % _g(s.esr_ohm), "L1 l1 sw %s" % _g(s.inductance_h),
                   "S1 sw 0 gh 0 swm", "D1 0 sw dbody", "C1 sw 0 %s" % _g(s.coss_f),
                   "Cb sw p %s" % _g(s.c_block_f)]
                + _load_lines(s, "sw", "0")[3:])      # C0, bleed, BVD, C_tune
    lines = _sources(s, duties) + _models(s) + _leg(s, "a", "sw", "gh", "gl")
    if s.kind == "bridge":
        return lines + _leg(s, "b", "swb", "gl", "gh") + _load_lines(s, "sw", "swb")
    return lines + _load_lines(s, "sw", "0")


def netlist(s: Stage, analysis: str, duties: Sequence[float] | float = 0.5,
            periods: int = 0, fstart: float = 0.0, fstop: float = 0.0,
            points: int = 0) -> str:
    """The netlist text: analysis "ac" (a 1 V AC source in place of the
    switches; out.txt: frequency, |V_piezo|) or "tran" (`periods` carrier
    periods, linearized to SAMPLES_PER_PERIOD a period; out.txt: time,
    v(p), v(sw) and for a bridge v(swb))."""
    if analysis == "ac":
        # the switches' on-resistance in series, as the tank sees it (two in a bridge)
        ron = s.ron_ohm * (2 if s.kind == "bridge" else 1)
        body = ["Vac src 0 DC 0 AC 1", "Rsw src sw %s" % _g(ron)] + _load_lines(s, "sw", "0")
        ctl = ["ac lin %d %s %s" % (points, _g(fstart), _g(fstop)), "wrdata out.txt vm(p)"]
    elif analysis == "tran":
        body = _circuit(s, duties)
        T = 1.0 / s.carrier_hz
        step = T / SAMPLES_PER_PERIOD
        vs = "v(p) v(sw) v(swb)" if s.kind == "bridge" else "v(p) v(sw)"
        # uic: start from rest (every capacitor discharged, no current)
        ctl = ["tran %s %s 0 %s uic" % (_g(step), _g(periods * T), _g(step / 2)),
               "linearize %s" % vs, "wrdata out.txt %s" % vs]
    else:
        raise ValueError("analysis: must be 'ac' or 'tran', got %r" % (analysis,))
    head = "* texelpad.plate.spice: %s stage, %s" % (s.kind, analysis)
    return "\n".join([head] + body + [".options reltol=1e-4", ".control",
                                      "set wr_singlescale", "set wr_vecnames"]
                     + ctl + ["quit", ".endc", ".end", ""])


# --- running ngspice ------------------------------------------------------------------

def ngspice() -> str:
    """The ngspice executable (TEXELPAD_NGSPICE, else on PATH), or SpiceError."""
    exe = os.environ.get("TEXELPAD_NGSPICE") or shutil.which("ngspice")
    if not exe:
        raise SpiceError("setup", "ngspice is not installed (Debian: apt-get install ngspice)")
    return exe


def run(text: str, step: str, timeout_s: float = TIMEOUT_S) -> np.ndarray:
    """Run a netlist (from netlist()) in a fresh temporary directory; the
    columns wrdata wrote to out.txt, as a float array (rows x columns)."""
    exe = ngspice()
    with tempfile.TemporaryDirectory(prefix="texelpad-spice-") as tmp:
        with open(os.path.join(tmp, "stage.cir"), "w") as f:
            f.write(text)
        try:
            p = subprocess.run([exe, "-b", "stage.cir"], cwd=tmp, capture_output=True,
                               text=True, timeout=timeout_s, stdin=subprocess.DEVNULL)
        except subprocess.TimeoutExpired:
            raise SpiceError(step, "no result within %g s" % timeout_s) from None
        except OSError as e:
            raise SpiceError(step, "cannot run %s: %s" % (exe, e)) from None
        log = (p.stdout + p.stderr).strip()
        errors = [ln.strip() for ln in log.splitlines()
                  if ln.lower().startswith("error") or "aborted" in ln
                  or "timestep too small" in ln.lower()]
        out = os.path.join(tmp, "out.txt")
        if p.returncode != 0 or errors or not os.path.exists(out):
            raise SpiceError(step, "exit status %d; %s" % (
                p.returncode, "; ".join(errors[:3]) or log[-500:] or "no output"))
        try:
            data = np.loadtxt(out, skiprows=1, ndmin=2)
        except ValueError as e:
            raise SpiceError(step, "unreadable output: %s" % e) from None
    if data.shape[0] < 2 or not np.all(np.isfinite(data)):
        raise SpiceError(step, "no usable data (%d rows)" % data.shape[0])
    return data


# --- analyses ----------------------------------------------------------------------------

@dataclass(frozen=True)
class Resonance:
    """An AC sweep of V_piezo / V_sw: peak frequency (Hz), the peak gain (the
    piezo volts per volt of drive fundamental), Q = f_peak / -3 dB bandwidth."""
    frequency_hz: float
    gain: float
    q: float


def _crossing(f: np.ndarray, a: np.ndarray, level: float, i: int, step: int) -> float:
    """Where a falls below level walking from index i by step, interpolated."""
    j = i
    while 0 <= j + step < len(a) and a[j + step] >= level:
        j += step
    k = j + step
    if not 0 <= k < len(a):
        raise SpiceError("ac", "the -3 dB point is outside the sweep")
    return float(f[j] + (f[k] - f[j]) * (a[j] - level) / (a[j] - a[k]))


def ac_sweep(s: Stage, span: float = 0.3, points: int = 6001) -> Resonance:
    """The tank's response from the switch node to the piezo, f0 (1 +- span)."""
    f0 = s.tank_hz
    d = run(netlist(s, "ac", fstart=f0 * (1 - span), fstop=f0 * (1 + span), points=points),
            "ac sweep of the %s stage" % s.kind)
    f, a = d[:, 0], d[:, 1]
    i = int(np.argmax(a))
    if i in (0, len(a) - 1):
        raise SpiceError("ac", "the peak is at the end of the sweep")
    # a parabola through the peak's neighbours (in the sweep's 1e-4 steps)
    y0, y1, y2 = a[i - 1], a[i], a[i + 1]
    den = y0 - 2 * y1 + y2
    off = 0.5 * (y0 - y2) / den if den else 0.0
    fp = float(f[i] + off * (f[i + 1] - f[i]))
    level = float(y1) / math.sqrt(2.0)
    bw = _crossing(f, a, level, i, 1) - _crossing(f, a, level, i, -1)
    return Resonance(fp, float(y1), fp / bw)


def _piezo(s: Stage, d: np.ndarray) -> np.ndarray:
    """The piezo's voltage from a transient's columns (p - sw_b for a bridge)."""
    return d[:, 1] - d[:, 3] if s.kind == "bridge" else d[:, 1]


def _periods_to_settle(s: Stage) -> int:
    tau = tank.envelope_time_constant(s.tank_hz, s.q)
    return int(math.ceil(SETTLE_TAUS * tau * s.carrier_hz))


def fundamental(v: np.ndarray, samples_per_period: int = SAMPLES_PER_PERIOD) -> np.ndarray:
    """Amplitude of the carrier fundamental in each whole period of v (a DFT
    bin per period: 2/N |sum v e^(-j 2 pi n/N)|)."""
    n = samples_per_period
    k = len(v) // n
    ph = np.exp(-2j * np.pi * np.arange(n) / n)
    return np.asarray(2.0 / n * np.abs(v[:k * n].reshape(k, n) @ ph))


@dataclass(frozen=True)
class Steady:
    """A transient run at one duty, measured over its last `measured` periods:
    the piezo voltage's fundamental amplitude (V), its peak (V), and the
    switch node's (the drain's, for the minimal variant) peak and minimum (V)."""
    duty: float
    piezo_v: float
    piezo_peak_v: float
    sw_peak_v: float
    sw_min_v: float
    periods: int


def steady(s: Stage, duty: float, measured: int = 4, periods: int | None = None) -> Steady:
    """Run to steady state at `duty` (SETTLE_TAUS envelope time constants)."""
    n = periods or _periods_to_settle(s) + measured
    d = run(netlist(s, "tran", duty, periods=n),
            "transient of the %s stage at duty %g" % (s.kind, duty))
    m = measured * SAMPLES_PER_PERIOD
    vp, vs = _piezo(s, d)[-m - 1:-1], d[-m - 1:-1, 2]
    amp = float(np.mean(fundamental(vp)))
    return Steady(duty, amp, float(np.max(np.abs(vp))), float(np.max(vs)), float(np.min(vs)), n)


@dataclass(frozen=True)
class Envelope:
    """A duty step at step_s: the fundamental per period (V, at the periods'
    centres, s) and the time (s) the amplitude takes to cover 1 - 1/e of
    the change (t63_s), with the amplitudes before and after; tau_s: the
    time constant fitted to the approach (_fit_tau); mean_step_v: the change
    of the piezo's per-period mean (the slow part that passes C_block)."""
    times_s: np.ndarray
    amplitude_v: np.ndarray
    before_v: float
    after_v: float
    t63_s: float
    tau_s: float
    step_s: float
    mean_step_v: float


def envelope(s: Stage, d0: float = 0.0, d1: float = 0.5, before: int = 0,
             taus_after: float = 8.0) -> Envelope:
    """Step the duty from d0 to d1 after `before` periods (0 with d0 = 0: from
    rest; else give d0 time to settle) and measure the time constant."""
    T = 1.0 / s.carrier_hz
    if before <= 0:
        before = 1 if d0 == 0 else _periods_to_settle(s)
    after = int(math.ceil(taus_after * tank.envelope_time_constant(s.tank_hz, s.q) / T))
    duties = [d0] * before + [d1] * after
    d = run(netlist(s, "tran", duties, periods=len(duties)),
            "duty step %g -> %g of the %s stage" % (d0, d1, s.kind))
    vp = _piezo(s, d)[:-1]
    amp = fundamental(vp)
    means = vp[:len(amp) * SAMPLES_PER_PERIOD].reshape(len(amp), -1).mean(axis=1)
    t = (np.arange(len(amp)) + 0.5) * T
    a0 = float(amp[before - 1]) if d0 > 0 else 0.0
    a1 = float(np.mean(amp[-2:]))
    target = a0 + (1.0 - math.exp(-1.0)) * (a1 - a0)
    rising = a1 > a0
    idx = [k for k in range(before, len(amp)) if (amp[k] >= target) == rising]
    if not idx:
        raise SpiceError("envelope", "the amplitude never covered 63 % of the step")
    k = idx[0]
    ka = max(k - 1, before - 1)
    ta, tb, ya, yb = t[ka], t[k], amp[ka], amp[k]
    if ka < before:              # the period before the step: the envelope starts at the step
        ta, ya = before * T, a0
    tc = ta + (tb - ta) * (target - ya) / (yb - ya) if yb != ya else tb
    return Envelope(t, amp, a0, a1, float(tc - before * T), _fit_tau(t, amp, before, a0, a1),
                    before * T, float(np.mean(means[-2:]) - means[before - 1]))


def _fit_tau(t: np.ndarray, amp: np.ndarray, before: int, a0: float, a1: float) -> float:
    """The time constant fitted to ln|a1 - amp| (s) where the remaining change
    is 60 % .. 5 % of the step: independent of how the envelope starts (a
    duty step also steps the switch node's mean, D * V_bus, which rings the
    tank at f0 in phase with the drive: the envelope starts at ~V_bus, not 0,
    and t63 comes out ~5 % short)."""
    rest = np.abs(a1 - amp[before:]) / abs(a1 - a0)
    k = np.nonzero((rest < 0.6) & (rest > 0.05))[0]
    if len(k) < 3:
        raise SpiceError("envelope", "too few periods to fit the time constant")
    slope = np.polyfit(t[before:][k], np.log(rest[k]), 1)[0]
    return float(-1.0 / slope)


# --- the figures (python -m texelpad.plate.spice [Q]) ---------------------------------------

def figures(q: float = 15.0) -> list[str]:
    """The measured figures against `texelpad tank`, as lines of text (the
    tests' stages: tuned to 34 kHz, 390 uH, 40 nF piezo, 2.2 uF C_block)."""
    out = []
    for kind in ("single", "bridge"):
        s = tuned(kind, q=q)
        r = ac_sweep(s)
        drive = "bridge" if kind == "bridge" else "single"
        full = steady(s, 0.5).piezo_v
        est = tank.piezo_voltage(s.bus_volts, r.q, 0.5, drive) * s.piezo_share
        e = envelope(s, 0.0, 0.5)
        want = tank.envelope_time_constant(r.frequency_hz, r.q)
        out += ["%s: resonance %.1f Hz (tank %.1f Hz, %+.2f %%), -3 dB Q %.2f, peak gain %.2f"
                % (kind, r.frequency_hz, s.tank_hz, 100 * (r.frequency_hz / s.tank_hz - 1),
                   r.q, r.gain),
                "  duty 0.5: piezo %.1f V = %.2f V per bus volt; tank estimate %.1f V "
                "(sim %+.1f %%)" % (full, full / s.bus_volts, est, 100 * (full / est - 1)),
                "  envelope 0 -> 0.5: tau %.1f us fitted, t63 %.1f us; Q/(pi f0) %.1f us "
                "(%+.1f %%, %+.1f %%); mean step %.1f V"
                % (1e6 * e.tau_s, 1e6 * e.t63_s, 1e6 * want, 100 * (e.tau_s / want - 1),
                   100 * (e.t63_s / want - 1), e.mean_step_v)]
        lost = s.dead_time_s * s.carrier_hz
        for d in (0.1, 0.2, 0.3, 0.4):
            a = steady(s, d).piezo_v / full
            out.append("  D %.1f: %.4f of D = 0.5; sin(pi D) %+.1f %%, sin(pi (D - t_dead f)) "
                       "%+.2f %%" % (d, a, 100 * (a / math.sin(math.pi * d) - 1),
                                     100 * (a / (math.sin(math.pi * (d - lost))
                                                 / math.sin(math.pi * (0.5 - lost))) - 1)))
    s = tuned("minimal", q=q)
    for d in (0.3, 0.5, 0.6, 0.7):
        st = steady(s, d)
        out.append("minimal D %.1f: drain peak %.1f V = %.2f x V_bus, piezo %.1f V"
                   % (d, st.sw_peak_v, st.sw_peak_v / s.bus_volts, st.piezo_v))
    return out


if __name__ == "__main__":
    import sys
    print("\n".join(figures(float(sys.argv[1]) if len(sys.argv) > 1 else 15.0)))

"""The resonant tank of a friction plate: series inductor + piezo capacitance.

The carrier's square wave drives an inductor L in series with the piezo discs
(clamped capacitance C_p, plus an optional tuning capacitor). At
f = 1 / (2*pi*sqrt(L*C)) the tank's reactances cancel and the voltage across
the capacitance is Q times the drive's fundamental: that is how a 12..48 V
supply puts the hundreds of volts on the piezo a glass plate needs. The
plate's own mechanical resonance is fixed by the glass and the bonding; the
tank is tuned to it (hardware/README.md).

    resonant_frequency(L, C)            f
    inductance_for(C, f)                L (the series inductor for C)
    capacitance_for(L, f)               C
    solve(inductance_h=, capacitance_f=, frequency_hz=)   any two -> Tank
    series_inductor(C_p, f)             the inductor that tunes the bare piezo
    tuning_capacitor(L, C_p, f)         what to add to C_p so that L resonates at f
    piezo_voltage(bus_v, q, ...)        estimated voltage amplitude at resonance
    envelope_time_constant(f, q)        how fast the amplitude follows the duty, Q/(pi f)
    envelope_bandwidth(f, q)            that as a -3 dB bandwidth, f/(2Q)
    finest_period(speed, bandwidth)     the shortest texture period rendered at a swipe speed
    plate_plays(amplitudes, dx, ...)    a map as the plate plays it along a swipe
    nearest_e12(x)                      the nearest standard (E12) value

All values in SI units (H, F, Hz, V, A, ohm). Non-positive or non-finite
inputs raise ValueError naming the argument; so do inputs so extreme that a
result leaves the range of floating point numbers (1e-300 H with 1e-300 F:
the frequency would be 1.6e299 Hz, and L*C underflows to 0 on the way).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, Sequence

TWO_PI = 2.0 * math.pi
# Standard component values per decade (IEC 60063 E12): inductors and film
# capacitors are commonly stocked in this series.
E12 = (1.0, 1.2, 1.5, 1.8, 2.2, 2.7, 3.3, 3.9, 4.7, 5.6, 6.8, 8.2)
# The piezo alone "already tunes" the tank when its capacitance is within
# 0.2 % of what is needed: the frequency is then within 0.1 %, far inside
# component tolerances (inductors +-10..20 %, piezo capacitance +-10..20 %).
MATCH_RTOL = 2e-3


def _positive(name: str, value: float) -> float:
    """value as a float, or ValueError naming the argument."""
    if isinstance(value, bool):
        raise ValueError("%s: must be a positive number, got %r" % (name, value))
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError("%s: must be a positive number, got %r" % (name, value)) from None
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError("%s: must be a positive finite number, got %r" % (name, value))
    return v


def _result(name: str, value: float) -> float:
    """A computed value that must be a positive finite float: the inputs were
    too extreme when it is not (overflow to inf, underflow to 0)."""
    if not 0.0 < value < math.inf:
        raise ValueError("%s: the result is beyond floating point range (%r): the inputs are "
                         "too extreme (check their units: 390u for 390 uH)" % (name, value))
    return value


def _inv_w2(x: float, frequency_hz: float) -> float:
    """1 / ((2*pi*f)^2 * x); where the direct product over- or underflows,
    from logarithms (the result may still be out of range: _result)."""
    w = TWO_PI * frequency_hz
    d = w * w * x
    if 0.0 < d < math.inf:
        return 1.0 / d
    lg = -2.0 * (math.log(TWO_PI) + math.log(frequency_hz)) - math.log(x)
    return math.inf if lg > 709.0 else math.exp(lg)


def resonant_frequency(inductance_h: float, capacitance_f: float) -> float:
    """f = 1 / (2*pi*sqrt(L*C)), Hz."""
    L = _positive("inductance_h", inductance_h)
    C = _positive("capacitance_f", capacitance_f)
    # sqrt(L)*sqrt(C): L*C itself can underflow to 0 (1e-300 * 1e-300)
    return _result("frequency_hz", 1.0 / (TWO_PI * math.sqrt(L) * math.sqrt(C)))


def inductance_for(capacitance_f: float, frequency_hz: float) -> float:
    """L = 1 / ((2*pi*f)^2 * C), H."""
    C = _positive("capacitance_f", capacitance_f)
    f = _positive("frequency_hz", frequency_hz)
    return _result("inductance_h", _inv_w2(C, f))


def capacitance_for(inductance_h: float, frequency_hz: float) -> float:
    """C = 1 / ((2*pi*f)^2 * L), F."""
    L = _positive("inductance_h", inductance_h)
    f = _positive("frequency_hz", frequency_hz)
    return _result("capacitance_f", _inv_w2(L, f))


@dataclass(frozen=True)
class Tank:
    """A series LC tank at resonance."""
    inductance_h: float
    capacitance_f: float
    frequency_hz: float

    @property
    def impedance_ohm(self) -> float:
        """Characteristic impedance sqrt(L/C) = the reactance of L (and of C)
        at resonance: tank current amplitude = capacitor voltage / this."""
        # sqrt(L)/sqrt(C): L/C itself can overflow (1e300 / 1e-300)
        return _result("impedance_ohm",
                       math.sqrt(self.inductance_h) / math.sqrt(self.capacitance_f))

    def as_dict(self) -> dict[str, float]:
        d = asdict(self)
        d["impedance_ohm"] = self.impedance_ohm
        return d


def solve(inductance_h: float | None = None, capacitance_f: float | None = None,
          frequency_hz: float | None = None) -> Tank:
    """Exactly two of L, C, f given: the Tank with the third computed."""
    given = [k for k, v in (("inductance_h", inductance_h), ("capacitance_f", capacitance_f),
                            ("frequency_hz", frequency_hz)) if v is not None]
    if len(given) != 2:
        raise ValueError("give exactly two of inductance_h, capacitance_f, frequency_hz "
                         "(got %s)" % (", ".join(given) or "none"))
    if frequency_hz is None:
        assert inductance_h is not None and capacitance_f is not None
        f = resonant_frequency(inductance_h, capacitance_f)
        return Tank(float(inductance_h), float(capacitance_f), f)
    if inductance_h is None:
        assert capacitance_f is not None
        L = inductance_for(capacitance_f, frequency_hz)
        return Tank(L, float(capacitance_f), float(frequency_hz))
    C = capacitance_for(inductance_h, frequency_hz)
    return Tank(float(inductance_h), C, float(frequency_hz))


def series_inductor(piezo_capacitance_f: float, frequency_hz: float) -> float:
    """The series inductor that tunes the bare piezo to frequency_hz.
    piezo_capacitance_f: an LCR meter at ~1 kHz (well below the plate's
    resonance) gives a first value; it is a little above the clamped
    capacitance the tank sees, and the plate's mechanical resonance pulls
    the effective value near f0, so the final tuning is measured
    (hardware/README.md)."""
    return inductance_for(_positive("piezo_capacitance_f", piezo_capacitance_f), frequency_hz)


@dataclass(frozen=True)
class Tuning:
    """The capacitor to add to the piezo so a given inductor resonates at f.

    placement: "parallel" (the piezo has too little capacitance: add
    capacitance_f across it), "series" (too much: put capacitance_f in series
    with it; the piezo then sees only piezo_share of the tank's capacitor
    voltage, so a smaller inductor is usually the better fix) or "none"."""
    placement: str
    capacitance_f: float | None
    inductance_h: float
    piezo_capacitance_f: float
    frequency_hz: float
    total_capacitance_f: float
    piezo_share: float

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def tuning_capacitor(inductance_h: float, piezo_capacitance_f: float,
                     frequency_hz: float) -> Tuning:
    """What to add to the piezo's capacitance C_p so that inductance_h
    resonates at frequency_hz: C_need = 1/((2*pi*f)^2 L); parallel
    C_need - C_p when C_need > C_p, series C_p*C_need/(C_p - C_need) when
    C_need < C_p."""
    L = _positive("inductance_h", inductance_h)
    Cp = _positive("piezo_capacitance_f", piezo_capacitance_f)
    f = _positive("frequency_hz", frequency_hz)
    need = capacitance_for(L, f)
    if abs(need - Cp) <= MATCH_RTOL * Cp:
        return Tuning("none", None, L, Cp, f, Cp, 1.0)
    if need > Cp:
        return Tuning("parallel", _result("capacitance_f", need - Cp), L, Cp, f, need, 1.0)
    cs = _result("capacitance_f", Cp * (need / (Cp - need)))
    # series capacitors share the tank's capacitor voltage inversely to C
    return Tuning("series", cs, L, Cp, f, need, cs / (cs + Cp))


def fundamental_amplitude(bus_volts: float, duty: float = 0.5, drive: str = "single") -> float:
    """Amplitude (V) of the carrier fundamental of a 0..bus_volts square wave
    of duty D: (2/pi) * V * sin(pi*D); a full bridge doubles it."""
    v = _positive("bus_volts", bus_volts)
    if not 0.0 <= duty <= 1.0:
        raise ValueError("duty: must be in [0, 1], got %r" % (duty,))
    if drive not in ("single", "bridge"):
        raise ValueError("drive: must be 'single' or 'bridge', got %r" % (drive,))
    a = (2.0 / math.pi) * v * math.sin(math.pi * duty)
    return 2.0 * a if drive == "bridge" else a


def piezo_voltage(bus_volts: float, q: float, duty: float = 0.5, drive: str = "single") -> float:
    """ESTIMATED voltage amplitude (V) across the tank capacitance at
    resonance: Q times the fundamental. Q (= f0 / -3 dB bandwidth of the
    loaded plate) must be measured per build; this is for choosing voltage
    ratings and for safety, not a prediction of the plate's amplitude."""
    return _result("piezo_volts", _positive("q", q) * fundamental_amplitude(bus_volts, duty, drive))


def envelope_time_constant(frequency_hz: float, q: float) -> float:
    """The time constant (s) with which the tank's amplitude follows a change
    of the drive: tau = 2 L / R = 2 Q / omega0 = Q / (pi * f0) for a series
    resonant tank driven at resonance (the envelope of a step is
    1 - exp(-t / tau)). texelpad/plate/spice.py measures it in ngspice."""
    f = _positive("frequency_hz", frequency_hz)
    return _result("tau_s", _positive("q", q) / (math.pi * f))


def envelope_bandwidth(frequency_hz: float, q: float) -> float:
    """The -3 dB bandwidth (Hz) of the amplitude envelope, f0 / (2 Q): the
    envelope is a first-order low-pass with envelope_time_constant's tau, and
    1 / (2 pi tau) = f0 / (2 Q) (half the tank's -3 dB bandwidth f0 / Q: the
    envelope sees one side of the resonance)."""
    f = _positive("frequency_hz", frequency_hz)
    return _result("bandwidth_hz", f / (2.0 * _positive("q", q)))


def finest_period(speed_m_s: float, bandwidth_hz: float) -> float:
    """The shortest texture period (m) the plate renders at a swipe speed:
    a spatial period lam under a finger moving at v is a temporal frequency
    v / lam, passed at -3 dB up to the envelope bandwidth, so lam = v / B
    (100 mm/s through 850 Hz: 0.118 mm)."""
    return _result("period_m", _positive("speed_m_s", speed_m_s)
                   / _positive("bandwidth_hz", bandwidth_hz))


# swipe speeds (m/s) `texelpad tank` reports the finest texture period at:
# a slow exploration, a typical one and a quick swipe
SWIPE_SPEEDS_M_S = (0.05, 0.1, 0.2)


def plate_plays(amplitudes: Sequence[float], dx_m: float, speed_m_s: float,
                frequency_hz: float, q: float) -> list[float]:
    """What the plate plays: the amplitude map sampled every dx_m along a
    swipe at speed_m_s, each sample held for dx/speed (as the refresh holds
    its duty), through the envelope's first-order low-pass (tau = Q/(pi f0)):
    the amplitude the plate reaches, starting from rest. Exact for a held
    input: y += (1 - exp(-dt/tau)) * (x - y) per sample."""
    dt = _positive("dx_m", dx_m) / _positive("speed_m_s", speed_m_s)
    k = -math.expm1(-dt / envelope_time_constant(frequency_hz, q))
    y, out = 0.0, []
    for x in amplitudes:
        y += k * (float(x) - y)
        out.append(y)
    return out


def nearest_e12(value: float, direction: int = 0) -> float:
    """The E12 standard value nearest to value in log scale (direction 0),
    or the largest one <= value (-1), or the smallest one >= value (+1)."""
    v = _positive("value", value)
    if direction not in (-1, 0, 1):
        raise ValueError("direction: must be -1, 0 or 1, got %r" % (direction,))
    decade = math.floor(math.log10(v))
    # candidates, rounded to 2 significant digits so that 3.9e-4 is 3.9e-4
    # ("%.2g" % m + "e%d" % d: no 10.0 ** d, which overflows at the ends of
    # the float range); those beyond the range (0, inf) are left out
    cands = sorted(c for c in (float("%.2ge%d" % (m, d)) for d in (decade - 1, decade, decade + 1)
                               for m in E12) if 0.0 < c < math.inf)
    tol = v * 1e-12                      # v itself counts as <= and >= v
    pick = [c for c in cands if c <= v + tol] if direction < 0 else \
        [c for c in cands if c >= v - tol] if direction > 0 else cands
    if not pick:
        raise ValueError("value: %r has no E12 value %s it within floating point range"
                         % (v, "below" if direction < 0 else "above"))
    if direction < 0:
        return max(pick)
    if direction > 0:
        return min(pick)
    return min(pick, key=lambda c: abs(math.log(c / v)))


# --- quantities as people type them ---------------------------------------------

# SI prefix -> power of ten (scaling divides for negative powers, so "56n"
# is exactly the float 5.6e-08)
PREFIXES = {"p": -12, "n": -9, "u": -6, "\u00b5": -6, "\u03bc": -6, "m": -3,
            "": 0, "k": 3, "K": 3, "M": 6}
UNIT_NAMES = {"H": "henry", "F": "farad", "Hz": "hertz", "V": "volt"}
# No quantity needs more characters ("1.0000000000000002e-300 uH" has 26).
MAX_QUANTITY_CHARS = 100


def parse_quantity(text: str, unit: str) -> float:
    """"390u", "390uH", "390 µH", "3.9e-4", "56n", "56nF", "34k", "34 kHz",
    "33.5e3" -> a positive float in SI units. `unit` ("H", "F", "Hz", "V")
    may be written or left out; another unit is an error."""
    s = text.strip()
    if not s:
        raise ValueError("empty value")
    if len(s) > MAX_QUANTITY_CHARS:
        # the prefix search below tries float() on every prefix, quadratic in
        # the length: a 100,000-character argument took seconds (fuzz, docs/testing.md)
        raise ValueError("%r... (%s characters) is too long for a value (e.g. 390u, 34 kHz)"
                         % (s[:20], format(len(s), ",")))
    # split the number from its suffix; the number is the longest prefix
    # that float() accepts (handles 1e-6 and .5)
    num = None
    cut = 0
    for i in range(len(s), 0, -1):
        try:
            num = float(s[:i])
        except ValueError:
            continue
        cut = i
        break
    if num is None:
        raise ValueError("%r is not a number" % text)
    suffix = s[cut:].strip()
    if unit and suffix.endswith(unit) and suffix[:-len(unit)] in PREFIXES:
        suffix = suffix[:-len(unit)]
    elif unit == "Hz" and suffix.lower().endswith("hz") and suffix[:-2] in PREFIXES:
        suffix = suffix[:-2]
    if suffix not in PREFIXES:
        if unit:
            hint = "e.g. 390u, 390u%s, 56n, 34k" % unit
        else:
            hint = "a plain number, or one with an SI prefix such as 1.5k"
        raise ValueError("%r: unknown unit %r (expected %s)" % (text, s[cut:].strip(), hint))
    e = PREFIXES[suffix]
    value = num / 10.0 ** -e if e < 0 else num * 10.0 ** e
    if not math.isfinite(value) or value <= 0.0:
        raise ValueError("%r: must be positive" % text)
    return value


def format_quantity(value: float, unit: str, digits: int = 4) -> str:
    """Engineering notation: 3.9e-4 H -> "390 µH", 5.6185e-8 F -> "56.19 nF"."""
    if value == 0 or not math.isfinite(value):
        return "%g %s" % (value, unit)
    exp3 = int(math.floor(math.log10(abs(value)) / 3.0)) * 3
    if not -12 <= exp3 <= 6:            # beyond the prefixes: 1.592e-301 Hz, not "0 pHz"
        return "%.*g %s" % (digits, value, unit)
    prefix = {-12: "p", -9: "n", -6: "\u00b5", -3: "m", 0: "", 3: "k", 6: "M"}[exp3]
    mant = value / 10.0 ** exp3
    text = "%.*g" % (digits, mant)
    if "e" in text:                     # 1000 after rounding: 999.97 -> 1e+03
        text = "%.0f" % mant
    return "%s %s%s" % (text, prefix, unit)


def arg_quantity(unit: str) -> Any:
    """An argparse `type=` for a quantity in `unit` (bad input: one-line
    usage error naming the flag)."""
    import argparse

    def parse(text: str) -> float:
        try:
            return parse_quantity(text, unit)
        except ValueError as e:
            raise argparse.ArgumentTypeError(str(e)) from None
    parse.__name__ = UNIT_NAMES.get(unit, unit)
    return parse


# --- the `texelpad tank` report ---------------------------------------------------

class TankInputError(ValueError):
    """A combination of inputs the calculator cannot use; `flag` names the
    command-line flag to blame."""

    def __init__(self, flag: str, message: str):
        super().__init__(message)
        self.flag = flag


def _f(x: float) -> str:
    return format_quantity(x, "Hz", 5)


def _v(volts: float) -> str:
    return "%.3g" % volts if volts < 100 or volts >= 1e6 else "%.0f" % volts


def _pct(a: float, b: float) -> str:
    d = 100.0 * (a / b - 1.0)
    return "%+.2f %%" % (0.0 if abs(d) < 0.005 else d)


def _tuning_line(t: Tuning) -> str:
    if t.placement == "none":
        return ("the bare piezo already tunes it within 0.1 %% (%s): no tuning capacitor"
                % _f(resonant_frequency(t.inductance_h, t.piezo_capacitance_f)))
    assert t.capacitance_f is not None
    e12 = nearest_e12(t.capacitance_f)
    if t.placement == "parallel":
        f12 = resonant_frequency(t.inductance_h, t.piezo_capacitance_f + e12)
        return ("add %s in parallel with the piezo (nearest E12 %s gives %s, %s)"
                % (format_quantity(t.capacitance_f, "F"), format_quantity(e12, "F"),
                   _f(f12), _pct(f12, t.frequency_hz)))
    cs = t.piezo_capacitance_f * (e12 / (t.piezo_capacitance_f + e12))   # no overflow
    f12 = resonant_frequency(t.inductance_h, cs)
    return ("add %s in series with the piezo (nearest E12 %s gives %s, %s); the piezo then "
            "gets only %.0f %% of the tank voltage: a smaller inductor, %s, tunes the bare "
            "piezo instead"
            % (format_quantity(t.capacitance_f, "F"), format_quantity(e12, "F"), _f(f12),
               _pct(f12, t.frequency_hz), 100.0 * t.piezo_share,
               format_quantity(series_inductor(t.piezo_capacitance_f, t.frequency_hz), "H")))


def report(inductance_h: float | None = None, capacitance_f: float | None = None,
           frequency_hz: float | None = None, piezo_f: float | None = None,
           bus_volts: float | None = None, q: float | None = None,
           drive: str = "single") -> tuple[str, dict[str, Any]]:
    """What `texelpad tank` prints: (text, figures in SI units).

    Without piezo_f: exactly two of L, C, f give the third. With piezo_f (the
    piezo's clamped capacitance): + f -> the series inductor; + L + f -> the
    tuning capacitor; + L -> the bare piezo's frequency. bus_volts and q
    together add the ESTIMATED voltage across the piezo at full amplitude
    and the envelope: how fast the amplitude follows the duty (tau, -3 dB
    bandwidth) and the finest texture period rendered at SWIPE_SPEEDS_M_S.
    Inputs whose results leave the floating point range raise
    TankInputError (no flag to blame: it is the combination)."""
    try:
        text, data = _report(inductance_h, capacitance_f, frequency_hz, piezo_f, bus_volts, q,
                             drive)
        _finite(data, "")
    except TankInputError:
        raise
    except (ValueError, ArithmeticError) as e:
        raise TankInputError("", "cannot compute with these values: %s" % e) from None
    return text, data


def _finite(v: Any, where: str) -> None:
    """Every float in the report is finite (none overflowed on the way)."""
    if isinstance(v, dict):
        for k, x in v.items():
            _finite(x, "%s.%s" % (where, k) if where else k)
    elif isinstance(v, list):
        for i, x in enumerate(v):
            _finite(x, "%s[%d]" % (where, i))
    elif isinstance(v, float) and not math.isfinite(v):
        raise ValueError("%s: the result is beyond floating point range (%r): the inputs are "
                         "too extreme (check their units: 390u for 390 uH)" % (where, v))


def _report(inductance_h: float | None, capacitance_f: float | None,
            frequency_hz: float | None, piezo_f: float | None, bus_volts: float | None,
            q: float | None, drive: str) -> tuple[str, dict[str, Any]]:
    L, C, f, Cp = inductance_h, capacitance_f, frequency_hz, piezo_f
    if bus_volts is not None and q is None:
        # --q alone is fine: the envelope needs no bus voltage
        raise TankInputError("--q", "--bus-volts needs --q (the voltage estimate is Q times "
                                    "the drive's fundamental)")
    lines: list[str] = []
    data: dict[str, Any] = {}
    share = 1.0
    if Cp is None:
        given = [n for n, v in (("--inductance", L), ("--capacitance", C), ("--frequency", f))
                 if v is not None]
        if len(given) != 2:
            raise TankInputError("", "give exactly two of --inductance, --capacitance, --frequency "
                                 "(got %s), or --piezo with --frequency and/or --inductance"
                                 % (", ".join(given) or "none"))
        t = solve(L, C, f)
        data["mode"] = "solve"
        lines.append("L = %s, C = %s, f = %s" % (format_quantity(t.inductance_h, "H"),
                                                 format_quantity(t.capacitance_f, "F"),
                                                 _f(t.frequency_hz)))
        computed = {"--inductance": "L", "--capacitance": "C", "--frequency": "f"}
        missing = [computed[k] for k in computed if k not in given][0]
        lines[-1] += "  (%s computed)" % missing
    else:
        if C is not None:
            raise TankInputError("--capacitance", "give --capacitance or --piezo, not both "
                                 "(with --piezo, --inductance and --frequency the tank "
                                 "computes the tuning capacitor)")
        if L is None and f is None:
            raise TankInputError("--piezo", "needs --frequency (series inductor) and/or "
                                 "--inductance (tuning capacitor, resonant frequency)")
        if L is None:
            assert f is not None
            Ls = series_inductor(Cp, f)
            t = Tank(Ls, Cp, f)
            data["mode"] = "series_inductor"
            lines.append("series inductor for a %s piezo at %s: L = %s"
                         % (format_quantity(Cp, "F"), _f(f), format_quantity(Ls, "H")))
            # a standard inductor just below, trimmed down to f by a
            # parallel capacitor (the benign kind: the piezo keeps the full
            # tank voltage); inductors are +-10..20 %: measure and re-trim
            e12 = nearest_e12(Ls, -1)
            f12 = resonant_frequency(e12, Cp)
            data["e12_inductor_h"] = e12
            data["e12_bare_frequency_hz"] = f12
            lines.append("  standard value below: %s gives %s with the bare piezo (%s); then "
                         % (format_quantity(e12, "H"), _f(f12), _pct(f12, f))
                         + _tuning_line(tuning_capacitor(e12, Cp, f)))
            data["e12_tuning"] = tuning_capacitor(e12, Cp, f).as_dict()
        elif f is None:
            fr = resonant_frequency(L, Cp)
            t = Tank(L, Cp, fr)
            data["mode"] = "piezo_frequency"
            lines.append("L = %s with a bare %s piezo resonates at %s"
                         % (format_quantity(L, "H"), format_quantity(Cp, "F"), _f(fr)))
        else:
            tu = tuning_capacitor(L, Cp, f)
            t = Tank(L, tu.total_capacitance_f, f)
            share = tu.piezo_share
            data["mode"] = "tuning_capacitor"
            data["tuning"] = tu.as_dict()
            lines.append("L = %s at %s needs %s of capacitance; the piezo has %s:"
                         % (format_quantity(L, "H"), _f(f),
                            format_quantity(tu.total_capacitance_f, "F"),
                            format_quantity(Cp, "F")))
            lines.append("  " + _tuning_line(tu))
    data["tank"] = t.as_dict()
    _impedance_and_estimate(t, bus_volts, q, drive, share, lines, data)
    if q is not None:
        _envelope(t, q, lines, data)
    return "\n".join(lines), data


def _impedance_and_estimate(t: Tank, bus_volts: float | None, q: float | None, drive: str,
                            share: float, lines: list[str], data: dict[str, Any]) -> None:
    """_report's last lines: the tank's impedance, and the voltage estimate
    when a bus voltage and Q were given (share: the piezo's part of the
    tank's capacitance)."""
    lines.append("  characteristic impedance sqrt(L/C) = %.4g ohm (tank current amplitude = "
                 "capacitor voltage amplitude / %.4g ohm; it circulates in the tank, the supply "
                 "delivers only the losses)" % (t.impedance_ohm, t.impedance_ohm))
    if bus_volts is not None and q is not None:
        vf = fundamental_amplitude(bus_volts, 0.5, drive)
        vc = piezo_voltage(bus_volts, q, 0.5, drive)
        i_amp = vc / t.impedance_ohm
        data["estimate"] = {"bus_volts": bus_volts, "q": q, "drive": drive,
                            "fundamental_v": vf, "capacitor_v": vc, "piezo_v": vc * share,
                            "current_a": i_amp}
        lines.append("  ESTIMATE at full amplitude (duty 0.5, %s drive, %g V bus, Q = %g): "
                     "fundamental %s V, piezo %s V amplitude (%s V peak-to-peak), tank "
                     "current %.3g A amplitude. Q must be measured per build (f0 / -3 dB "
                     "bandwidth); rate the inductor, capacitors and wiring above this."
                     % (drive, bus_volts, q, _v(vf), _v(vc * share),
                        _v(_result("piezo_volts", 2 * vc * share)), i_amp))


def _envelope(t: Tank, q: float, lines: list[str], data: dict[str, Any]) -> None:
    """_report's envelope line: how fast the plate's amplitude follows the
    duty, and the finest texture period it renders at a few swipe speeds."""
    tau = envelope_time_constant(t.frequency_hz, q)
    bw = envelope_bandwidth(t.frequency_hz, q)
    finest = [(v, finest_period(v, bw)) for v in SWIPE_SPEEDS_M_S]
    data["envelope"] = {"q": q, "time_constant_s": tau, "bandwidth_hz": bw,
                        "finest_period_m": [{"speed_m_s": v, "period_m": p} for v, p in finest]}
    lines.append("  ENVELOPE (Q = %g): the amplitude follows a change of duty with tau = "
                 "Q/(pi f0) = %s, a low-pass of -3 dB bandwidth f0/(2Q) = %s; the finest "
                 "texture period the plate renders is %s (speed / bandwidth)"
                 % (q, format_quantity(tau, "s"), _f(bw),
                    ", ".join("%.3g mm at %g mm/s" % (1e3 * p, 1e3 * v) for v, p in finest)))

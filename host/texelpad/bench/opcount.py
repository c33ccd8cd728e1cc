"""Op-count cost model of the device render paths: the "estimated RP2040"
column of `texelpad bench`.

The counts are a snapshot of the device source (texel 0.1.0, commit 58d33ca):
when an engine or the plan changes, re-count. `texelpad bench` checks them on
the unix port (same counts, unix per-op costs) and warns when the prediction
is off by more than a factor of two.

Nothing here is measured on a board. Each render path is counted by hand from
the device source (device/texel/gen/plan.py, rng.py, engine_*.py) in four classes:

  F  an interpreted operation with a float operand or result (arithmetic,
     compare, ** , a float stored into an array): on a board every float is
     boxed on the heap, so each F allocates.
  B  a call of a built-in float function (math.sin, math.floor, math.sqrt,
     math.frexp, int(float)).
  I  an interpreted operation on small ints / objects (arithmetic, bitwise,
     compare, subscript or attribute load/store, one loop step).
  C  a call of a Python-level function or method (frame set-up), and each
     call into ulab.
  V  one iteration of a viper loop (machine-word ints).
  Us, Uo  ulab element operations: sin, and any other vector op (per element).

Estimate = sum(count x cost). Per-op costs on the emulated RP2040 (125 MHz,
MicroPython 1.28 + ulab 6.12) are docs/background.md §3's measurements where it has
them: F = 16 us, V = 0.27 us, Us = 25 us, Uo = 2 us. §3 has no figure for
I, B and C; they are scaled from F by the ratio measured on the unix port in
the same run (I_rp = 16 us x I_unix/F_unix, likewise B and C), i.e. it
assumes integer ops, built-in calls and calls relate to a float op on the
board as they do on the unix port. The same counts times the unix port's calibrated costs predict
the unix timings, which the bench prints next to the measured ones as a check
of the counts.

Counting rules: loads of locals and constants are free, a load of a module
global or a builtin name is 1 I (a dict lookup on MicroPython); a chained compare
counts each comparison taken; branch-dependent counts are weighted by their
probability (the inverse normal's central branch |u-0.5| <= 0.425 is taken by
85 % of draws).
"""
from __future__ import annotations

from dataclasses import dataclass, field

# docs/background.md §3, measured on an emulated RP2040 @ 125 MHz (microseconds).
RP2040_US = {"F": 16.0, "V": 0.27, "Us": 25.0, "Uo": 2.0}
RP2040_SOURCE = "docs/background.md §3 (emulated RP2040 @ 125 MHz, MicroPython 1.28 + ulab 6.12)"
# Fallback unix-port ratios to a float op, used only when no calibration ran
# (MicroPython absent): measured once on the development host.
DEFAULT_RATIO = {"I": 0.23, "B": 1.1, "C": 1.2}

CLASSES = ("F", "B", "I", "C", "V", "Us", "Uo")


@dataclass
class Counts:
    """Op counts of one render path: fixed per map, per texel, per chunk of
    at most CHUNK samples within a texel (ulab only), and per sample."""
    per_map: dict[str, float] = field(default_factory=dict)
    per_texel: dict[str, float] = field(default_factory=dict)
    per_chunk: dict[str, float] = field(default_factory=dict)
    per_sample: dict[str, float] = field(default_factory=dict)
    chunk: int = 64

    def total(self, samples: int, texels: int, texel_samples: int) -> dict[str, float]:
        full, rest = divmod(samples, texel_samples)
        chunks_per_texel = -(-texel_samples // self.chunk)
        chunks = full * chunks_per_texel + (-(-rest // self.chunk) if rest else 0)
        out = {k: 0.0 for k in CLASSES}
        for part, mult in ((self.per_map, 1), (self.per_texel, texels),
                           (self.per_chunk, chunks), (self.per_sample, samples)):
            for k, v in part.items():
                out[k] += v * mult
        return out


# --- the plan (device/texel/gen/plan.py Plan.__init__), per texel ----------------
# One draw z (rng.Rng.normal):
#   calls normal, next_hi_lo, ppnd16                                  C 3
#   next_hi_lo: 44 int binops, 8 attribute loads, 8 stores, 1 tuple   I 61
#   self.next_hi_lo, self.F, unpack, 0xFFFF-hi, 0xFFFF-lo            I 5
#   u, uc: (F(x_hi)*65536.0 + (x_lo+0.5)) / 2^32 twice               F 8, B 2
#   ppnd16, central branch (85 %): q, 2 compares, r, q*ratio          F 6
#       _ratio: 2 subscripts, 7 x (loop, 2 subscripts, 4 F), n/d      I 23, F 29, C 1
#   ppnd16, tail (15 %): 4 F of branching, det_log (frexp, compare,
#       s, s2, 11 x (loop, subscript, 2 F), 4 F) = 31.5 F + 1 B + 24.5 I,
#       sqrt, negations, r-1.6, _ratio (29 F, 23 I), sign:
#       69 F, 2 B, 48.5 I, 2 C
#   expected ppnd16: F 40.1, B 0.3, I 26.8, C 1.15
#   global names: _M16 x 13 (next_hi_lo), _TWO32 x 2, ppnd16, _ratio/_A/_B
#   (central) or the tail's 20                                       I 19.6
# Rest of the loop body: pull (2 F), q>0 (1 F), 10**pull (1 F), cap test (1 I),
#   Nyquist test (1 F, 1 I), phase recurrence (4 F), f[i], phi[i] stores (2 F),
#   fixed-point step: fi*dx, floor, subtract, *2^28, +0.5, int (4 F, 2 B, 1 I),
#   & and store (2 I), ta[i] store (1 I), _frac_u28(step*L) (1 F + call:
#   floor, subtract, *2^28, +0.5, int = 3 F, 2 B, 2 I), accumulate (2 I),
#   loop step (1 I):  F 19, B 4, I 12, C 1; global names (_params, _TWO_PI,
#   _DX x 2, math x 2, UNITS_PER_TURN x 2, PHASE_MASK x 3, _frac_u28, int x 2):
#   I 15.
# Quantization (quant_db > 0) adds pull/q, round_half_away (5.5 F, 1 B, 1 I,
# 1 C), q*.
PLAN = Counts(
    # validate() (~10 keys: ~8 I + 1 C each), Rng warm-up (16 x next_hi_lo),
    # mu, sigma, buffers.
    per_map={"I": 80 + 16 * 62 + 20, "C": 10 + 16 + 8, "F": 8},
    per_texel={"F": 8 + 40.1 + 19, "B": 2 + 0.3 + 4, "I": 61 + 5 + 26.8 + 19.6 + 12 + 15,
               "C": 3 + 1.15 + 1},
)
PLAN_QUANT_EXTRA = {"F": 7.5, "B": 1, "I": 1, "C": 1}

# --- engine_int.render_u16 ------------------------------------------------
# per texel: loop, i*L, a+L, b>n, t28[i], d28[i], the global _fill (7 I) and
# the _fill call.
# _fill_py per sample: while test, (t+d)&M, t>>18, tab[i], the interpolation
# (i+1, tab[], -, t>>2, &, *, +, >>, +: 9 I), (v*g+8192)>>14 and the store
# (4 I), a += 1: 19 I.  viper: one loop iteration per sample.
INT_PER_MAP: dict[str, float] = {"I": 10, "C": 3, "F": 3}          # buffer, table(), gain_q14
INT_VIPER = Counts(per_map=INT_PER_MAP, per_texel={"I": 7, "C": 1}, per_sample={"V": 1})
INT_PY = Counts(per_map=INT_PER_MAP, per_texel={"I": 7, "C": 1}, per_sample={"I": 19})

# --- engine_pure.render_u16 -----------------------------------------------
# per texel: loop, i*L, a+L, b>n, plan.t28[i], plan.d28[i] (8 I).
# per sample: while test, (t+d)&M and the global _MASK (3 I), t*k, +1.0,
# *half_gain (3 F), sin (1 B), put() call (1 C): v*65535.0, +0.5 (2 F), int
# (1 B, 1 I for the name), out[j]= (1 I), a += 1 (1 I).
PURE = Counts(per_map={"I": 10, "C": 3, "F": 1}, per_texel={"I": 8},
              per_sample={"F": 5, "B": 2, "I": 7, "C": 1})

# --- engine_ulab.render_u16 -----------------------------------------------
# per texel: loop and bounds (4 I), t, d (4 I), step, half (4 I), w =
# _signed(d)*k (1 C, 3 I, 1 F).
# per chunk (<= 64 samples of one texel): while, m, compare, slice, (t+half)&M,
# _signed, np.sin look-up, a+m, (t+step)&M, a+=m, globals _signed and _MASK
# x 2 (15.5 I); start phase *k
# (1 F); _signed() and emit() calls and six ulab calls (8 C); per element: sin
# (1 Us) and five other vector ops: kf*w, +=, *=, +=, the converting slice
# store (5 Uo).
ULAB = Counts(per_map={"I": 10, "C": 4, "F": 2}, per_texel={"I": 15, "C": 1, "F": 1},
              per_chunk={"I": 15.5, "F": 1, "C": 8}, per_sample={"Us": 1, "Uo": 5})

# one-time (first render after boot): sine_table.table() copies the shipped
# 2 KB literal into an array('H'): one built-in call, no float work.
SINE_TABLE = Counts(per_map={"B": 1, "C": 1})

SYNTH = {"int": INT_VIPER, "int-py": INT_PY, "pure": PURE, "ulab": ULAB}


def costs_rp2040(calibration: dict | None) -> tuple[dict[str, float], str]:
    """Per-op costs on the emulated RP2040 (us) and how I and C were derived."""
    c = dict(RP2040_US)
    if calibration and calibration.get("float_op_us"):
        f = calibration["float_op_us"]
        ratio = {"I": calibration["int_op_us"] / f, "B": calibration["builtin_call_us"] / f,
                 "C": calibration["call_us"] / f}
        how = "the unix port's ratios measured in this run"
    else:
        ratio = dict(DEFAULT_RATIO)
        how = "default ratios (MicroPython was not run)"
    for k, r in ratio.items():
        c[k] = c["F"] * r
    how = "I = %.2f F, B = %.2f F, C = %.2f F: %s" % (ratio["I"], ratio["B"], ratio["C"], how)
    return c, how


def costs_unix(calibration: dict) -> dict[str, float]:
    """Per-op costs of the unix port measured by mpbench.calibrate (us).
    ulab element ops do not occur there (no ulab in the unix build)."""
    return {"F": calibration["float_op_us"], "I": calibration["int_op_us"],
            "B": calibration["builtin_call_us"], "C": calibration["call_us"],
            "V": calibration.get("viper_iteration_us", 0.0), "Us": 0.0, "Uo": 0.0}


def path_counts(variant: str, params: dict, samples: int, texels: int) -> dict[str, dict[str, float]]:
    """Op counts of the plan and the synthesis of one map."""
    L = params.get("texel_samples", 50)
    plan = PLAN.total(samples, texels, L)
    if params.get("quant_db", 0.0) > 0.0:
        for k, v in PLAN_QUANT_EXTRA.items():
            plan[k] += v * texels
    synth = SYNTH[variant].total(samples, texels, L)
    return {"plan": plan, "synth": synth}


def estimate_ms(counts: dict[str, float], costs: dict[str, float]) -> float:
    return sum(counts[k] * costs.get(k, 0.0) for k in CLASSES) / 1000.0


def estimate(variant: str, params: dict, samples: int, texels: int,
             costs: dict[str, float]) -> dict[str, float]:
    """Estimated plan, synthesis and total time of one map (ms)."""
    c = path_counts(variant, params, samples, texels)
    plan = estimate_ms(c["plan"], costs)
    synth = estimate_ms(c["synth"], costs)
    return {"plan_ms": plan, "synth_ms": synth, "total_ms": plan + synth}


def sine_table_ms(costs: dict[str, float]) -> float:
    return estimate_ms(SINE_TABLE.total(1, 1, 1), costs)


FORMULA = ("est = nF*F + nB*B + nI*I + nC*C + nV*V + nUs*Us + nUo*Uo, with op counts n* of the "
           "plan and the synthesis counted from the device source (texelpad/bench/opcount.py) and "
           "per-op costs from docs/background.md §3: F = 16 us (Python float op), V = 0.27 us (viper loop "
           "iteration), Us = 25 us (ulab sin per element), Uo = 2 us (other ulab op per element)")

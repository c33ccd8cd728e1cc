"""Error bounds of the device engines against the float64 reference.

Every bound is a first-order sum of the roundings on the path from the same
parameter set to one map sample; each float operation contributes at most one
unit of its last place (ulp), and the factor C_OPS = 4 covers the at most four
roundings on any one path (a product, a sum, a floor and a scale). Where the
bound exceeds the map's full range it is capped at 1: the samples are then not
reproducible at all (texels far beyond Nyquist, where even the float64
reference's sine argument has an ulp of radians), which tools report as the
fraction of texels above Nyquist.

Error is stated in PWM steps: one step is 1/3676 of full scale (RP2040 at
125 MHz with a 34 kHz carrier: TOP = 3675).
"""
from __future__ import annotations

import math

import numpy as np

PWM_STEPS = 3676
PWM_STEP = 1.0 / PWM_STEPS
EPS64 = 2.0 ** -52
EPS32 = 2.0 ** -23
C_OPS = 4.0
UNIT = 2.0 ** -28               # fixed-point phase unit, turns
DX = 0.0053
CHUNK = 64                      # engine_ulab.CHUNK


def _per_sample(plan, per_texel: np.ndarray) -> np.ndarray:
    return np.repeat(per_texel, plan.L)[: plan.n]


def sample_index(plan) -> np.ndarray:
    """k = 1..L of every sample within its texel."""
    return (np.arange(plan.n) % plan.L + 1).astype(np.float64)


def reference_phase_error(plan) -> np.ndarray:
    """Rounding of the float64 reference's own sine argument, turns:
    sin(2*pi*f*dx*k + phi) with |phi| unbounded (never wrapped)."""
    f = np.asarray(plan.f, dtype=np.float64)
    phi = np.abs(np.asarray(plan.phi, dtype=np.float64))
    k = sample_index(plan)
    arg = 2 * math.pi * _per_sample(plan, f) * DX * k + _per_sample(plan, phi)
    # The reference's phase recurrence adds one rounding of |phi| per texel.
    acc = np.concatenate([[0.0], np.cumsum(C_OPS * EPS64 * phi[:-1])])
    return (C_OPS * EPS64 * arg + _per_sample(plan, acc)) / (2 * math.pi)


def fixed_plan_phase_error(plan, plan_eps: float = EPS64) -> np.ndarray:
    """Phase error of the fixed-point plan (t28, d28), turns, for sample k
    of texel i:  start phase  0.5 u per texel boundary (rounding) plus the
    float error of frac(L * frac(f*dx));  step  k * (0.5 u + eps * f*dx)."""
    f = np.asarray(plan.f, dtype=np.float64)
    L = plan.L
    per_boundary = 0.5 * UNIT + C_OPS * plan_eps * (f * DX * L + 1.0)
    start = 0.5 * UNIT + C_OPS * plan_eps + np.concatenate([[0.0], np.cumsum(per_boundary[:-1])])
    k = sample_index(plan)
    step = k * (0.5 * UNIT + C_OPS * plan_eps * _per_sample(plan, f) * DX)
    return _per_sample(plan, start) + step


def float32_plan_pitch_error(plan32) -> np.ndarray:
    """Relative error of f_i when the plan itself runs in float32 (a board):
    pull = mu + sigma*z carries C*eps*|pull|, and 10^pull turns that into a
    relative error ln(10)*C*eps*|pull| plus the pow's own ulp."""
    f = np.asarray(plan32.f, dtype=np.float64)
    pull = np.abs(np.log10(f))
    return C_OPS * EPS32 * (1.0 + math.log(10) * (pull + 1.0))


OUTPUT_ERROR = {
    # Q16 table (0.5 LSB), its linear interpolation (0.5 LSB rounding and
    # (2*pi/1024)^2/16 = 2.4e-6 of curvature), Q14 gain (0.5 LSB + 2^-15 of
    # the value), final rounding to Q16 (0.5 LSB): 2.5 LSB of 65535 in all.
    "int": 2.4e-6 + 2.5 / 65535 + 2.0 ** -15,
    "pure": C_OPS * EPS64,
    # float32 inside a chunk: |k*w + phi0| <= 2*pi*(CHUNK+1) rad, a few
    # roundings of that, float32 sin and the float32 output.
    "ulab": (C_OPS * EPS32 * 2 * math.pi * (CHUNK + 1)) / 2 + 2 * EPS32,
    "numpy": 0.0,
}


def error_bound(plan, engine: str, u16: bool = False, plan_eps: float = EPS64,
                pitch_rel_err: np.ndarray | None = None) -> np.ndarray:
    """Per-sample bound on |map_engine - map_reference| (map units, <= 1).

    plan: the float64 plan the reference is rendered from. plan_eps: epsilon of
    the plan arithmetic of the engine under test (EPS32 for a float32 board).
    pitch_rel_err: per-texel relative pitch error of a float32 plan
    (float32_plan_pitch_error); its phase effect accumulates over texels."""
    turns = reference_phase_error(plan)
    if engine != "numpy":
        turns = turns + fixed_plan_phase_error(plan, plan_eps)
    if pitch_rel_err is not None:
        f = np.asarray(plan.f, dtype=np.float64)
        per_texel = pitch_rel_err * f * DX * plan.L
        acc = np.concatenate([[0.0], np.cumsum(per_texel[:-1])])
        k = sample_index(plan)
        turns = turns + _per_sample(plan, acc) + k * _per_sample(plan, pitch_rel_err * f * DX)
    # map = gain*(sin+1)/2: |d map| <= gain/2 * |d theta|
    bound = 0.5 * plan.gain * 2 * math.pi * turns + OUTPUT_ERROR[engine]
    if u16:
        bound = bound + 0.5 / 65535
    return np.minimum(bound, 1.0)


def eps_of(float_bits: int) -> float:
    """Machine epsilon (one ulp of 1.0) of a float with that many mantissa
    bits: EPS64 for 53, EPS32 for 24, 2^-21 for CircuitPython's 30-bit
    floats (22 bits, texel.compat.FLOAT_BITS there)."""
    return 2.0 ** (1 - float_bits)


def narrow_output_error(engine: str, float_bits: int) -> float:
    """What OUTPUT_ERROR leaves out on a narrow-float interpreter (0 for
    float64). "pure" is stated there for binary64 arithmetic; in narrower
    floats its per-sample path (phase to radians, |x| <= pi, sin, the gain's
    scale) carries C_OPS roundings of its epsilon on pi radians, of which the
    map sees half (map = gain*(sin+1)/2), plus the output's own. "ulab" is
    stated for float32 (ulab's arrays are float32 on these builds) and linear
    in its epsilon: scaled up where the scalars it is given are narrower
    still (CircuitPython). "int" and "numpy" do no float work per sample."""
    eps = eps_of(float_bits)
    if float_bits >= 53:
        return 0.0
    if engine == "pure":
        return C_OPS * eps * math.pi / 2 + 2 * eps
    if engine == "ulab" and eps > EPS32:
        return OUTPUT_ERROR["ulab"] * (eps / EPS32 - 1.0)
    return 0.0


def error_bound_on(plan, engine: str, float_bits: int = 53, u16: bool = False) -> np.ndarray:
    """error_bound for an engine running on an interpreter whose floats have
    `float_bits` mantissa bits (53: float64, CPython and the unix port; 24:
    float32, rp2/stm32 boards; 22: CircuitPython), where the plan itself is
    made in those floats: its phase arithmetic at that epsilon, its pitches
    off by float32_plan_pitch_error scaled to it (linear in epsilon), plus
    narrow_output_error. `plan` is the float64 plan of the reference."""
    if float_bits >= 53:
        return error_bound(plan, engine, u16=u16)
    eps = eps_of(float_bits)
    b = error_bound(plan, engine, u16=u16, plan_eps=eps,
                    pitch_rel_err=float32_plan_pitch_error(plan) * (eps / EPS32))
    return np.minimum(b + narrow_output_error(engine, float_bits), 1.0)


def in_pwm_steps(err: np.ndarray | float) -> np.ndarray | float:
    return np.asarray(err) * PWM_STEPS

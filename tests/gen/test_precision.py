"""Device-precision paths against the float64 reference, over the hard-case
suite (texelpad.analysis.hard_cases). Every comparison uses precision.error_bound, a
first-order sum of the roundings on the path to each sample (the docstring of
texelpad/analysis/precision.py says where each term comes from); errors are quoted in
PWM steps (1/3676 of full scale, RP2040 at 34 kHz)."""
import math

import numpy as np
import pytest

import texel
from texel.gen import engine_numpy, engine_int, engine_pure
from texel.gen.params import validate
from texel.gen.plan import Plan
from texelpad.analysis import precision as pr
from texelpad.analysis.hard_cases import HARD_CASES, WELL_CONDITIONED

ENGINES = {"int": engine_int, "pure": engine_pure}


@pytest.fixture(scope="module")
def refs():
    out = {}
    for name, (p, _) in HARD_CASES.items():
        plan = texel.make_plan(p)
        out[name] = (plan, engine_numpy.render(plan))
    return out


@pytest.mark.parametrize("engine", sorted(ENGINES))
@pytest.mark.parametrize("case", sorted(HARD_CASES))
def test_engine_within_bound(refs, case, engine):
    plan, ref = refs[case]
    m = ENGINES[engine]
    out = np.asarray(m.render(plan), dtype=float)
    assert out.shape == ref.shape
    assert np.isfinite(out).all()
    # in [0, gain] up to the engine's output rounding (Q16: 32767.5 -> 32768)
    assert out.min() >= 0.0 and out.max() <= plan.gain + pr.OUTPUT_ERROR[engine]
    err = np.abs(out - ref)
    assert (err <= pr.error_bound(plan, engine)).all()
    if case in WELL_CONDITIONED:
        assert err.max() <= pr.PWM_STEP, f"{err.max() * pr.PWM_STEPS:.3f} steps"
    q = np.asarray(m.render_u16(plan), dtype=float) / 65535
    assert (np.abs(q - ref) <= pr.error_bound(plan, engine, u16=True)).all()


@pytest.mark.parametrize("engine", ["numpy", "int", "pure"])
def test_deterministic(engine):
    p = HARD_CASES["study"][0]
    a = np.asarray(texel.render_u16(p, engine=engine))
    b = np.asarray(texel.render_u16(p, engine=engine))
    assert (a == b).all()
    other = np.asarray(texel.render_u16(dict(p, seed=8), engine=engine))
    assert (a != other).mean() > 0.5           # another seed is another texture


def test_int_engine_sine_table_error():
    """Table-only error (phase exact): 1024-point linear interpolation +
    Q16/Q14 rounding <= OUTPUT_ERROR['int'] (2.4e-6 + 2.5/65535 + 2^-15)."""
    from texel.gen import sine_table
    tab = sine_table.table()
    t = np.arange(0, 1 << 28, 4099, dtype=np.int64)
    i = t >> 18
    fr = (t >> 2) & 0xFFFF
    y0 = np.asarray(tab, dtype=np.int64)[i]
    y1 = np.asarray(tab, dtype=np.int64)[i + 1]
    v = y0 + (((y1 - y0) * fr + 32768) >> 16)
    v = (v * 16384 + 8192) >> 14
    exact = (np.sin(2 * np.pi * t / (1 << 28)) + 1) / 2
    assert np.abs(v / 65535 - exact).max() <= pr.OUTPUT_ERROR["int"]


def test_band_limit_is_explicit():
    p = dict(HARD_CASES["white-like"][0])
    faithful = texel.make_plan(p)
    assert faithful.fraction_above_nyquist() > 0.3
    capped = texel.make_plan(dict(p, band_limit_cpmm=texel.NYQUIST_CPMM))
    assert capped.fraction_above_nyquist() == 0.0
    assert max(capped.f) <= texel.NYQUIST_CPMM
    # draws below the cap are untouched
    f0, f1 = np.asarray(faithful.f), np.asarray(capped.f)
    below = f0 <= texel.NYQUIST_CPMM
    assert (f0[below] == f1[below]).all()


def test_extreme_pitches_are_finite(refs):
    for case in ("pitch-min", "pitch-nyquist", "irreg-max"):
        plan, ref = refs[case]
        assert np.isfinite(ref).all() and ref.min() >= 0 and ref.max() <= 1
    assert max(refs["irreg-max"][0].f) > 1e6 * texel.NYQUIST_CPMM


# --- float32 boards -----------------------------------------------------------
# On rp2/stm32 MicroPython every float is float32, the per-texel plan
# included. Plan(..., ftype=numpy.float32) runs the very same plan code with
# float32 arithmetic on CPython (numpy's float32 scalars round every operation
# to float32, as the board does; AS241 itself is evaluated in float64 and then
# rounded, a difference of < 1 ulp of z).

def _plan32(p):
    return Plan(validate(p), ftype=np.float32)


@pytest.mark.parametrize("case", sorted(HARD_CASES))
def test_float32_plan_within_bound(refs, case):
    """A float32 plan carries ~1e-7 relative error in every pitch; its phase
    effect accumulates texel by texel (float32_plan_pitch_error). The integer
    engine on that plan stays inside the bound that includes it."""
    plan64, ref = refs[case]
    plan32 = _plan32(HARD_CASES[case][0])
    out = np.asarray(engine_int.render(plan32), dtype=float)
    err = np.abs(out - ref)
    bound = pr.error_bound(plan64, "int", plan_eps=pr.EPS32,
                           pitch_rel_err=pr.float32_plan_pitch_error(plan32))
    assert (err <= bound).all()
    assert np.isfinite(out).all() and out.min() >= 0 and out.max() <= 1


@pytest.mark.parametrize("case", ["study", "seed-0", "ragged", "quant-coarse", "pitch-min"])
def test_float32_plan_typical_textures_within_one_step(refs, case):
    """For textures well below Nyquist on a screen, the float32 plan's pitch
    error accumulates to well under a PWM step (measured: <= 0.26 step)."""
    plan64, ref = refs[case]
    out = np.asarray(engine_int.render(_plan32(HARD_CASES[case][0])), dtype=float)
    assert np.abs(out - ref).max() <= pr.PWM_STEP


def test_long_map_integer_phase_does_not_drift_like_float32(refs):
    """'long-map' (262,144 samples at 79 c/mm, 1.1e5 turns): a float32 plan
    that accumulated the phase as a float (the original's recurrence) and took
    sin of it is off by nearly full scale by the end; the integer phase
    accumulation of the plan keeps the error to what the float32 pitches
    themselves cause, and with a float64 plan to < 1 PWM step."""
    plan64, ref = refs["long-map"]
    p32 = _plan32(HARD_CASES["long-map"][0])
    k = pr.sample_index(p32).astype(np.float32)
    f32 = np.repeat(np.asarray(p32.f, dtype=np.float32), p32.L)[: p32.n]
    ph32 = np.repeat(np.asarray(p32.phi, dtype=np.float32), p32.L)[: p32.n]
    naive = (np.sin(np.float32(2 * math.pi) * f32 * np.float32(0.0053) * k + ph32) + 1) / 2
    naive_err = np.abs(naive - ref).max()
    ours32 = np.abs(np.asarray(engine_int.render(p32), dtype=float) - ref).max()
    ours64 = np.abs(np.asarray(engine_int.render(plan64), dtype=float) - ref).max()
    assert naive_err > 0.5                      # drifted to an unrelated waveform
    assert ours32 < naive_err / 10
    assert ours64 < pr.PWM_STEP


@pytest.mark.parametrize("engine", ["int", "pure"])
def test_out_buffer_checked(engine):
    from array import array
    p = {"pitch_db": 6.3, "irregularity_db": -12.9, "length_samples": 100}
    with pytest.raises(ValueError, match="expected a uint16 buffer"):
        texel.render_u16(p, engine=engine, out=bytearray(200))
    with pytest.raises(ValueError, match="holds 50 samples, the map needs 100"):
        texel.render_u16(p, engine=engine, out=array("H", bytes(100)))
    buf = array("H", bytes(200))
    got = texel.render_u16(p, engine=engine, out=buf)
    assert got is buf
    assert list(buf) == list(texel.render_u16(p, engine=engine))


def test_sine_table_literal_matches_formula():
    """tools/gen_sine_table.py wrote the literal; it must equal the formula."""
    from texel.gen import sine_table
    exact = [int((math.sin(2 * math.pi * i / 1024) + 1.0) * 32767.5 + 0.5) for i in range(1025)]
    assert list(sine_table.table()) == exact


def test_numpy_engine_out_buffer():
    from array import array
    p = {"pitch_db": 6.3, "irregularity_db": -12.9, "length_samples": 100}
    buf = array("H", bytes(200))
    assert texel.render_u16(p, engine="numpy", out=buf) is buf
    assert list(buf) == list(texel.render_u16(p, engine="numpy"))
    with pytest.raises(ValueError, match="expected a uint16 buffer"):
        texel.render_u16(p, engine="numpy", out=bytearray(200))

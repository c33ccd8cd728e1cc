"""Texture format 2, the integer plan (device/texel/gen/plan_int.py): its
constants and tables are what they say, its arithmetic has the stated bounds,
its draws are normal (K-S over >= 10^5), its textures have the mean and SD of
log pitch they ask for, its int-engine map is within documented PWM steps of
the float64 rendering of the same draws, and the plan is the same bit for bit
on every runtime: CPython, the MicroPython unix port (viper and Python loops),
the float32 and float64 ulab builds and CircuitPython (no viper, 30-bit
floats). docs/generator.md ("Texture format 2") states the same figures.
"""
from __future__ import annotations

import math
import random
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import stats
from scipy.special import ndtri

import texel
from texel.gen import engine_int, engine_numpy
from texel.gen import plan_int as P
from texel.gen.plan_int_tables import table, NORM
from texel.runtime import scene as S
from texelpad import toolchain
from texelpad.analysis import precision as pr
from texelpad.analysis.hard_cases import HARD_CASES

from support import mpy

ROOT = Path(__file__).resolve().parents[2]
TAB = table()

# |z - Phi^-1((x + 0.5) / 2^32)| of the table inverse normal: linear
# interpolation between 32 points per octave of u (h^2/8 * z'' at the top
# octave, 5e-5) plus the 11-bit weight and Q24 rounding. Measured 6.1e-5.
NORM_ERR = 6.2e-5
# 2^x in Q28 from two tables and a first-order term: four roundings of
# 2^-29 relative each (tables, two products) and the dropped quadratic term
# (< 5.6e-11). Measured 8.1e-9.
EXP2_REL = 8.5e-9


def v2(case: str, **kw) -> dict:
    return dict(HARD_CASES[case][0], v=2, **kw)


def plan2(params: dict, **kw) -> P.PlanInt:
    return P.PlanInt(texel.validate(params), **kw)


# --- the constants and tables are their formulas --------------------------------------

def test_constants_are_their_formulas():
    assert P.C_DB == round(math.log2(10) / 10000 * 2 ** 40)
    assert P.LOG2_LOG2_10 == round(math.log2(math.log2(10)) * 2 ** 24)
    assert P.LOG2_STEP0 == round(math.log2(texel.DX_MM * 2 ** 28) * 2 ** 24)
    assert P.LN2_Q20 == round(math.log(2) * 2 ** 20)
    # the viper loop spells these as literals: they must be the same numbers
    src = (ROOT / "device/texel/gen/plan_int_viper.py").read_text()
    for lit in (str(P.LOG2_STEP0), str(P.LN2_Q20), str(P.Y_LO), str(P.Y_HI)):
        assert lit in src, lit


def test_tables_are_what_the_generator_script_makes():
    sys.path.insert(0, str(ROOT / "tools"))
    try:
        import gen_plan_int_tables as g
    finally:
        sys.path.pop(0)
    want = g.values()
    assert len(TAB) == len(want) == 256 + 256 + 32 * 32 + 1
    # one unit at most: a rounding tie may fall the other way with another
    # libm or scipy; the shipped values are the format and never change
    assert max(abs(a - b) for a, b in zip(TAB, want)) <= 1
    assert TAB[NORM + 1024] == 0 and TAB[0] == 1 << 28


# --- the arithmetic ----------------------------------------------------------------------

def _edges() -> list[int]:
    xs = [0, 1, 2 ** 31 - 1, 2 ** 31, 2 ** 32 - 2, 2 ** 32 - 1]
    for k in range(33):
        for d in (-1, 0, 1):
            for x in (2 ** k + d, 2 ** 32 - 2 ** k + d):
                if 0 <= x < 2 ** 32:
                    xs.append(x)
    return sorted(set(xs))


def _z(x: int) -> int:
    return P.norm_q24(x >> 16, x & 0xFFFF, TAB)


def test_inverse_normal_error_symmetry_and_order():
    rnd = np.random.default_rng(2026)
    xs = sorted(set(int(x) for x in rnd.integers(0, 2 ** 32, 200_000)) | set(_edges()))
    z = np.array([_z(x) for x in xs], dtype=np.float64) / 2 ** 24
    exact = ndtri((np.array(xs, dtype=np.float64) + 0.5) / 2 ** 32)
    err = np.abs(z - exact)
    print("\ninverse normal: max |error| %.3g over %d draws" % (err.max(), len(xs)))
    assert err.max() <= NORM_ERR
    assert np.all(np.diff(z) >= 0)                              # monotone in x
    for x in _edges() + [int(x) for x in rnd.integers(0, 2 ** 32, 2000)]:
        assert _z(x) == -_z(2 ** 32 - 1 - x)                  # exactly symmetric
    assert abs(_z(0) / 2 ** 24 - ndtri(0.5 / 2 ** 32)) < NORM_ERR     # -6.338: the extreme


def test_exp2_products_and_phase_advance():
    rnd = random.Random(5)
    rs = [0, 1, 255, 256, 65535, 65536, 2 ** 24 - 1] + [rnd.randrange(2 ** 24) for _ in range(100_000)]
    worst = max(abs(P.exp2_m(r, TAB) / 2 ** 28 / 2 ** (r / 2 ** 24) - 1) for r in rs)
    print("\n2^x: max relative error %.3g" % worst)
    assert worst <= EXP2_REL
    for _ in range(50_000):
        a, b = rnd.randrange(2 ** 29), rnd.randrange(2 ** 29)
        assert P.mul28(a, b) == (a * b + 2 ** 27) >> 28           # exact rounding
        L, d = rnd.randrange(1, 2 ** 20 + 1), rnd.randrange(2 ** 28)
        assert P.mulmod28(L, d) == (L * d) % 2 ** 28
    # the step and its 8 extra bits, across every exponent the loop can meet
    for y in range(P.Y_LO - 4 * P.Q24, P.Y_HI + 4 * P.Q24, 1234567):
        d, a, af, e = P.step_d(y, TAB)
        exact = 2.0 ** ((y + P.LOG2_STEP0) / 2 ** 24)
        if e >= 28:
            assert d == a and af == 0 and 0 <= d < 2 ** 28
            continue
        if e < -2:
            assert d == a == af == 0
            continue
        assert abs(d - exact) <= 0.5 + exact * EXP2_REL
        assert abs(a + af / 256 - exact) <= 1 / 256 + exact * EXP2_REL


# --- the draws are normal; the textures have their mean and SD -------------------------

@pytest.mark.parametrize("seed", [0, 1, 2 ** 32 - 1])
def test_draws_are_standard_normal_ks_over_200000(seed):
    pl = plan2({"pitch_db": 0.0, "irregularity_db": 0.0, "texel_samples": 1,
                "length_samples": 200_000, "seed": seed, "v": 2}, keep_z=True)
    z = np.frombuffer(pl.z, dtype=np.int32) / 2 ** 24
    res = stats.kstest(z, "norm")
    print("\nseed %d: K-S D = %.5f, p = %.3f; mean %.4f, sd %.4f"
          % (seed, res.statistic, res.pvalue, z.mean(), z.std()))
    assert res.pvalue > 0.01
    assert abs(z.mean()) < 4 / math.sqrt(len(z)) and abs(z.std() - 1) < 4 / math.sqrt(2 * len(z))


def test_log_pitch_is_normal_in_decades_ks():
    """log10 f of every texel ~ N(pitch_db/10, 10^(irregularity_db/10))."""
    p = {"pitch_db": 8.0, "irregularity_db": -8.0, "texel_samples": 1,
         "length_samples": 150_000, "seed": 42, "v": 2}
    pl = plan2(p)
    logf = np.frombuffer(pl.y, dtype=np.int32) / 2 ** 24 / math.log2(10)
    mu, sigma = 0.8, 10 ** -0.8
    res = stats.kstest(logf, "norm", args=(mu, sigma))
    print("\nlog10 f: K-S D = %.5f, p = %.3f" % (res.statistic, res.pvalue))
    assert res.pvalue > 0.01


# Cases whose drawn pitches are not clamped by Y_LO/Y_HI or quantized:
# log10 f is then mu + sigma z exactly (to the Q24 grid)
_UNCLAMPED = [c for c in sorted(HARD_CASES) if c not in ("irreg-max", "quant-coarse")]


@pytest.mark.parametrize("case", _UNCLAMPED)
def test_mean_and_sd_of_log_pitch_per_texture(case):
    pl = plan2(v2(case))
    logf = np.frombuffer(pl.y, dtype=np.int32) / 2 ** 24 / math.log2(10)
    p = pl.params
    mu, sigma = p["pitch_db"] / 10, 10 ** (p["irregularity_db"] / 10)
    n = len(logf)
    if n > 1:
        assert abs(logf.mean() - mu) <= 4 * sigma / math.sqrt(n) + 1e-7
        assert abs(logf.std(ddof=1) / sigma - 1) <= 4 / math.sqrt(2 * (n - 1)) + 1e-5
    else:
        assert abs(logf[0] - mu) <= 6.4 * sigma + 1e-7


def test_irregularity_max_is_clamped_not_broken():
    """sigma = 3.16 decades: draws beyond 2^15 c/mm or below 2^-22 c/mm are
    clamped (the steps there are aliasing or standing still anyway)."""
    pl = plan2(v2("irreg-max", texel_samples=1))
    y = np.frombuffer(pl.y, dtype=np.int32)
    assert y.min() >= P.Y_LO and y.max() <= P.Y_HI
    assert (y == P.Y_HI).any() and (y == P.Y_LO).any()
    assert pl.above_nyquist > 0
    d = np.frombuffer(pl.d28, dtype=np.int32)
    assert d.min() >= 0 and d.max() < 2 ** 28


def test_quantized_pitches_sit_on_the_grid():
    pl = plan2(v2("quant-coarse"))
    q = P._round_q(5000)
    y = np.frombuffer(pl.y, dtype=np.int32)
    assert q > 0 and np.all(y % q == 0)


def test_band_limit_caps_the_step():
    p = {"pitch_db": 19.0, "irregularity_db": 0.0, "seed": 3, "length_samples": 19200,
         "band_limit_cpmm": 50.0, "v": 2}
    pl = plan2(p)
    cap = round(50.0 * texel.DX_MM * 2 ** 28)
    d = np.frombuffer(pl.d28, dtype=np.int32)
    assert pl.dcap == cap and d.max() == cap
    assert max(pl.f) == 50.0


# --- the map against the float64 rendering of the same draws ----------------------------

def _steps(pl) -> np.ndarray:
    a = np.asarray(engine_int.render_u16(pl), dtype=np.float64) / 65535
    return np.abs(a - engine_numpy.render(pl)) * pr.PWM_STEPS


def _turns(pl) -> np.ndarray:
    """Turns of phase travelled up to each sample (|steps| summed)."""
    f = np.repeat(np.asarray(pl.f), pl.L)[: pl.n] * texel.DX_MM
    return np.cumsum(np.abs(f))


# One full screen (19,200 samples) below Nyquist: the played step's rounding
# drifts no further than its texel (the start phases carry 8 more bits), so
# what is left is 2^x's relative error times the turns travelled and the sine
# table (0.009 step) - measured at most 0.28 step (pitch-nyquist, 9,400 turns).
SCREEN_STEPS = 0.35


@pytest.mark.parametrize("case", sorted(HARD_CASES))
def test_map_within_documented_steps_of_float64_same_draws(case):
    pl = plan2(v2(case))
    err = _steps(pl)
    # the bound for every case: 2^x's relative error over the turns travelled
    # (a phase error of e turns moves gain*(sin+1)/2 by at most pi*e), plus
    # 2^-8 unit per sample of the advance, the int engine's table and Q16/Q14
    # rounding (<= 0.06 step)
    turns = _turns(pl) * EXP2_REL + np.arange(1, pl.n + 1) / 2 ** 36
    bound = math.pi * pl.gain * turns * pr.PWM_STEPS + 0.06 + math.pi * pl.L / 2 ** 29 * pr.PWM_STEPS
    print("\n%s: max %.3f PWM steps (bound at its worst sample %.3f)"
          % (case, err.max(), bound[np.argmax(err)]))
    assert np.all(err <= bound)
    if case not in ("irreg-max", "white-like", "long-map"):
        assert err.max() <= SCREEN_STEPS


def test_scene_plays_the_format2_plan_sample_for_sample():
    """A v2 texel region plays from its plan (K_PLAN): every position gives
    the int engine's map of the same parameters."""
    p = {"pitch_db": 12.3456, "irregularity_db": -7.0, "seed": 9, "v": 2}
    pl_params = dict(p, pitch_db=12.346, length_samples=4000)
    d = {"positions": 4000, "dx_um": 5.3}
    sc = S.build(S.validate({"regions": [{"start_mm": 0, "end_mm": 21.2,
                                          "texture": dict(p, kind="texel")}]}, d), d)
    assert len(sc.plans()) == 1
    want = np.asarray(texel.render_u16(pl_params, engine="int"))
    got = np.array([sc.amp(i) for i in range(4000)])
    assert np.array_equal(got, want)


# --- parameters ----------------------------------------------------------------------

def test_format2_parameters_on_the_grid_and_ties_refused():
    c = texel.validate({"pitch_db": 12.3456, "irregularity_db": -7.00049, "quant_db": 0.0012,
                        "band_limit_cpmm": 50.00011, "v": 2})
    assert (c["pitch_db"], c["irregularity_db"], c["quant_db"], c["band_limit_cpmm"]) == \
        (12.346, -7.0, 0.001, 50.0)
    assert texel.validate({"pitch_db": 12.3456, "irregularity_db": 0, "v": 1})["pitch_db"] == 12.3456
    assert texel.validate({"pitch_db": 1, "irregularity_db": 0})["v"] == 2     # no "v": format 2 (issue 32)
    assert texel.validate({"pitch_db": 12.3456, "irregularity_db": 0})["pitch_db"] == 12.346
    with pytest.raises(ValueError, match=r"pitch_db: 12\.3455 is half-way .* \(give 12\.345 or 12\.346\)"):
        texel.validate({"pitch_db": 12.3455, "irregularity_db": 0, "v": 2})
    with pytest.raises(ValueError, match=r"irregularity_db: -0\.0005 is half-way"):
        texel.validate({"pitch_db": 1, "irregularity_db": -0.0005, "v": 2})
    with pytest.raises(ValueError, match="draws: replaying logged draws is format 1's"):
        texel.make_plan({"pitch_db": 1, "irregularity_db": 0, "v": 2}, draws=(0.5, [0.0]))


def test_a_canonical_format2_set_validates_to_itself_at_the_nyquist_band_limit():
    """Hole (found when format 2 became the default): band_limit_cpmm at
    Nyquist (94.33962 c/mm, the top of its range) went onto the grid as 94.34,
    out of range - the canonical dict (a pulled scene) was refused when pushed
    again. The grid point below, 94.339, is what it takes now."""
    for key in ("band_limit_cpmm", "min_cpmm"):
        for value in (texel.NYQUIST_CPMM, 94.3396, 94.3391):
            c = texel.validate({"pitch_db": 6, "irregularity_db": -9, key: value, "v": 2})
            assert c[key] == 94.339 and texel.validate(c) == c, (key, value)
    c = texel.validate({"pitch_db": 6, "irregularity_db": -9, "band_limit_cpmm": 94.3384, "v": 2})
    assert c["band_limit_cpmm"] == 94.338


def test_every_grid_key_at_both_ends_of_its_range_stays_in_it():
    """The general rule behind the hole above (gen/grid.py _in_range): a value
    on format 2's grid never leaves its key's range, at either end, for every
    grid key - so every canonical set validates again to itself."""
    from texel.gen.grid import GRID_KEYS
    from texel.gen.params import OPTION_SPEC, SPEC
    base = {"pitch_db": 6, "irregularity_db": -9, "v": 2}
    for key in GRID_KEYS:
        lo, hi = (SPEC.get(key) or OPTION_SPEC[key])[2:4]
        for value in (lo, hi, lo + 0.0004, hi - 0.0004):
            if key == "quant_db" and 0 < value < 0.001:
                continue                    # refused: finer than the grid (0 = off)
            c = texel.validate(dict(base, **{key: value}))
            assert lo <= c[key] <= hi and texel.validate(c) == c, (key, value, c[key])


def test_format2_is_the_same_texture_for_every_seed_and_length_prefix():
    """The plan of a shorter map is the prefix of a longer one's (the draws
    come in texel order), as in format 1."""
    a = plan2({"pitch_db": 5, "irregularity_db": -9, "seed": 77, "length_samples": 19200, "v": 2})
    b = plan2({"pitch_db": 5, "irregularity_db": -9, "seed": 77, "length_samples": 5000, "v": 2})
    assert list(a.t28[: b.count]) == list(b.t28) and list(a.d28[: b.count]) == list(b.d28)


# --- the same plan on every runtime -----------------------------------------------------

RUNTIME_CASES = {
    "study": v2("study"),
    "pitch-nyquist": v2("pitch-nyquist"),
    "irreg-max": v2("irreg-max"),
    "white-like": v2("white-like"),
    "quant-coarse": v2("quant-coarse"),
    "texel-1": v2("texel-1", length_samples=3000),
    "texel-long": v2("texel-long"),
    "seed-max": v2("seed-max"),
    "ragged": v2("ragged"),
    "capped": {"pitch_db": 19.747, "irregularity_db": 0.0, "texel_samples": 7,
               "length_samples": 9600, "seed": 0, "band_limit_cpmm": 50.0, "v": 2},
    "huge-texel": {"pitch_db": 10.123, "irregularity_db": -30.0, "texel_samples": 1048576,
                   "length_samples": 100000, "seed": 99, "quant_db": 20.0, "v": 2},
}

RUNTIME_SCRIPT = r"""
import json
import texel
from texel.gen import plan_int as P
out = %(out)r
cases = %(cases)r
info = {"viper": P.VIPER, "same_loops": {}}
def save(path, buf):
    f = open(path, "wb")
    f.write(buf)
    f.close()
for name in sorted(cases):
    p = cases[name]
    pl = P.PlanInt(texel.validate(p))
    save(out + "/" + name + ".plan", bytes(pl.t28) + bytes(pl.d28) + bytes(pl.y))
    save(out + "/" + name + ".map", bytes(texel.render_u16(p, engine="int")))
    if P.VIPER:
        q = P.PlanInt(texel.validate(p), engine="py")
        info["same_loops"][name] = (bytes(q.t28) == bytes(pl.t28) and bytes(q.d28) == bytes(pl.d28)
                                    and bytes(q.y) == bytes(pl.y))
print(json.dumps(info))
"""


def _cpython_bytes(name: str) -> tuple[bytes, bytes]:
    p = RUNTIME_CASES[name]
    pl = plan2(p)
    return (bytes(pl.t28) + bytes(pl.d28) + bytes(pl.y),
            bytes(np.asarray(texel.render_u16(p, engine="int"), dtype=np.uint16)))


def _run_everywhere(exe: str, tmp_path) -> dict:
    code = RUNTIME_SCRIPT % {"out": str(tmp_path), "cases": RUNTIME_CASES}
    return mpy.run_json(code, exe=exe, heapsize="8M", timeout=300)


def _check_runtime(info: dict, tmp_path) -> None:
    for name in RUNTIME_CASES:
        plan, m = _cpython_bytes(name)
        assert (tmp_path / (name + ".plan")).read_bytes() == plan, name
        assert (tmp_path / (name + ".map")).read_bytes() == m, name
    if info["viper"]:
        assert all(info["same_loops"].values()), info["same_loops"]


def test_same_plan_and_map_bit_for_bit_on_the_unix_port(tmp_path):
    info = _run_everywhere(toolchain.require_micropython(), tmp_path)
    assert info["viper"] is True
    _check_runtime(info, tmp_path)


@pytest.mark.instruments
@pytest.mark.parametrize("name", ("micropython-ulab-f32", "micropython-ulab-f64", "circuitpython"))
def test_same_plan_and_map_bit_for_bit_on_the_instruments(name, tmp_path):
    """float32 boards and CircuitPython's 30-bit floats get the plan and map
    CPython gets: format 1 differed by 7.5 and 84.5 PWM steps (seed 3, 19 dB)."""
    exe = toolchain.interpreter(name)
    if exe is None:
        pytest.skip("%s is not on this machine (../shared/instruments)" % name)
    info = _run_everywhere(exe, tmp_path)
    assert info["viper"] is (name != "circuitpython")
    _check_runtime(info, tmp_path)

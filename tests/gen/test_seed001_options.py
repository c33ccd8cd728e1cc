"""Seed 001's stimulus in the generator (docs/generator.md, "Seed 001's
stimulus: a lower bound and phase reset"): the texture options min_cpmm and
phase (device/texel/gen/options.py, params.OPTION_SPEC) and the linear-unit
lognormal conversion (device/texel/gen/lognormal.py).

- lognormal.to_db/from_db by hand and by sampling the generator;
- canonical form: the options appear only when set, every other texture is
  byte for byte what it was; validation errors, also on device interpreters;
- the lower bound: no pitch below it, the pitches follow the truncated
  lognormal (K-S), the main stream is untouched, the post-pass tail is the
  loop's own arithmetic, the tries cap plays at the bound;
- phase reset: every texel starts at the first texel's phase, and the map
  jumps at texel borders where the continuous one does not; every engine
  and the scene's K_PLAN refresh play it;
- format 2 with the options is the same plan and int map bit for bit on
  CPython, the MicroPython unix port (viper and Python loops), the ulab
  float32/float64 builds and CircuitPython; format 1 agrees to the
  runtime's float precision; plan_numpy equals the scalar plans.
"""
from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from scipy import stats

import texel
from texel.gen import engine_numpy, lognormal, options
from texel.gen import plan as P1
from texel.gen import plan_int as P2
from texel.gen import plan_numpy as PN
from texel.gen.params import IRREG_DB_MIN
from texel.gen.plan_int_tables import table
from texel.runtime import scene as S
from texel.runtime.kinds import texel as KT
from texelpad import toolchain

from support import mpy

TAB = table()
WIDE = lognormal.to_db(4.0, 4.3)        # seed 001's "wide" condition
NARROW = lognormal.to_db(4.0, 1.2)      # and its "narrow" one


def seed001(which, v=2, **kw) -> dict:
    pitch, irreg = WIDE if which == "wide" else NARROW
    # 100 mm of display (18,868 samples), texels of 1.25 mm (236 samples)
    p = {"pitch_db": pitch, "irregularity_db": irreg, "texel_samples": 236,
         "length_samples": 18868, "seed": 5, "min_cpmm": 1.0, "v": v}
    p.update(kw)
    return p


def plan_of(p: dict, **kw):
    c = texel.validate(p)
    return P2.PlanInt(c, **kw) if c["v"] == 2 else P1.Plan(c, **kw)


# --- the linear-unit lognormal -------------------------------------------------------

def test_to_db_by_hand():
    # mean 4, SD 1.2 c/mm: sigma_ln^2 = ln(1 + 0.3^2) = 0.0861777,
    # sigma_ln = 0.293560, mu_ln = ln 4 - 0.0430888 = 1.343206;
    # mu10 = 0.583343 -> 5.833 dB; sigma10 = 0.127491 decade -> -8.945 dB
    assert lognormal.to_db(4, 1.2) == (5.833, -8.945)
    # mean 4, SD 4.3: sigma_ln^2 = ln(1 + 1.075^2) = 0.768078,
    # sigma_ln = 0.876401, mu_ln = 1.386294 - 0.384039 = 1.002255;
    # mu10 = 0.435271 -> 4.353 dB; sigma10 = 0.380617 decade -> -4.195 dB
    assert lognormal.to_db(4, 4.3) == (4.353, -4.195)
    # sd 0 (or a spread under 0.001 decade): the narrowest the generator draws
    assert lognormal.to_db(4, 0) == (6.021, IRREG_DB_MIN)
    assert lognormal.to_db(4, 1e-6)[1] == IRREG_DB_MIN
    for mean, sd in ((4, 1.2), (4, 4.3), (0.5, 0.1), (30, 60)):
        m, s = lognormal.from_db(*lognormal.to_db(mean, sd))
        # 0.001 dB of rounding: 2.3e-4 relative on the mean, more on a small SD
        assert abs(m / mean - 1) < 2e-3 and abs(s / sd - 1) < 2e-3, (mean, sd, m, s)


@pytest.mark.parametrize("args, msg", [
    (("4", 1), "mean_cpmm: expected a number, got str '4'"),
    ((True, 1), "mean_cpmm: expected a number, got bool True"),
    ((0, 1), "mean_cpmm: 0.0 must be > 0 (cycles/mm)"),
    ((4, -1), "sd_cpmm: -1.0 must be >= 0 (cycles/mm)"),
    ((float("nan"), 1), "mean_cpmm: nan is not finite"),
    ((4, float("inf")), "sd_cpmm: inf is not finite"),
    ((1000, 1), "pitch_db: 30.0 is out of range [-20.0, 19.747] (from mean_cpmm 1000.0, sd_cpmm 1.0)"),
    ((4, 4000), "pitch_db: -23.979 is out of range"),
    ((0.5, 1e6), "pitch_db: -66.021 is out of range"),
])
def test_to_db_refuses(args, msg):
    with pytest.raises(ValueError) as e:
        lognormal.to_db(*args)
    assert str(e.value).startswith(msg)


def test_to_db_refuses_a_spread_beyond_the_generator():
    # irregularity above 5 dB (3.16 decades) with a pitch still in range
    # (mu10 = -0.725 decade: -7.25 dB)
    with pytest.raises(ValueError, match=r"irregularity_db: 5\.\d+ is out of range \[-30.0, 5.0\]"):
        lognormal.to_db(1e11, 5.3e22)


@pytest.mark.parametrize("sd", [1.2, 4.3])
def test_sampled_pitches_have_the_linear_mean_and_sd(sd):
    """200,000 texels of format 2 without a bound: the sample mean and SD of
    the pitch in c/mm are those the paper gives. Tolerance: 5 standard
    errors of the estimate (SD/sqrt(n) for the mean; for the SD,
    sd*sqrt((kurtosis_excess + 2)/(4n)), kurtosis of the lognormal: 49 at
    sd 4.3, 0.9 at 1.2), plus the 0.001 dB rounding of to_db."""
    pitch, irreg = lognormal.to_db(4.0, sd)
    pl = plan_of({"pitch_db": pitch, "irregularity_db": irreg, "texel_samples": 1,
                  "length_samples": 200_000, "seed": 11, "v": 2})
    f = np.frombuffer(pl.f, dtype=np.float64)
    s2 = math.log(1 + (sd / 4.0) ** 2)
    kurt = math.exp(4 * s2) + 2 * math.exp(3 * s2) + 3 * math.exp(2 * s2) - 6
    se_mean = sd / math.sqrt(f.size)
    se_sd = sd * math.sqrt((kurt + 2) / (4 * f.size))
    print("\nmean %.4f (4 +- %.4f), SD %.4f (%.1f +- %.4f)" % (f.mean(), 5 * se_mean, f.std(), sd, 5 * se_sd))
    assert abs(f.mean() - 4.0) < 5 * se_mean + 4.0 * 3e-4
    assert abs(f.std() - sd) < 5 * se_sd + sd * 1e-3


# --- canonical form and validation ---------------------------------------------------

def test_options_only_in_the_canonical_dict_when_set():
    base = {"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7, "v": 2}
    c = texel.validate(base)
    assert "min_cpmm" not in c and "phase" not in c
    assert texel.validate(dict(base, min_cpmm=None, phase="continuous")) == c
    c2 = texel.validate(dict(base, min_cpmm=1, phase="reset"))
    assert c2 == dict(c, min_cpmm=1.0, phase="reset") and type(c2["min_cpmm"]) is float
    assert list(c2)[-2:] == ["min_cpmm", "phase"]
    assert texel.validate(c2) == c2
    # format 2's 0.001 c/mm grid, as band_limit_cpmm
    assert texel.validate(dict(base, min_cpmm=1.00012))["min_cpmm"] == 1.0
    assert texel.validate(dict(base, v=1, min_cpmm=1.00012))["min_cpmm"] == 1.00012
    # a scene's texel texture: the same rule
    d = {"positions": 19200, "dx_um": 5.3}
    tex = dict(base, kind="texel")
    plain = S.validate({"regions": [{"start_mm": 0, "end_mm": 50, "texture": tex}]}, d)
    assert set(plain["regions"][0]["texture"]) == {"kind"} | set(KT.TEXEL_KEYS)
    opt = S.validate({"regions": [{"start_mm": 0, "end_mm": 50,
                                   "texture": dict(tex, phase="reset", min_cpmm=2)}]}, d)
    assert opt["regions"][0]["texture"] == dict(plain["regions"][0]["texture"], phase="reset",
                                                min_cpmm=2.0)
    assert S.validate(opt, d) == opt


BAD = [
    ({"min_cpmm": 0.001}, "min_cpmm: 0.001 is out of range [0.01, 94.33962264150944]"),
    ({"min_cpmm": 95}, "min_cpmm: 95.0 is out of range [0.01, 94.33962264150944]"),
    ({"min_cpmm": "1"}, "min_cpmm: expected a number in [0.01, 94.33962264150944], got str '1'"),
    ({"min_cpmm": float("nan")}, "min_cpmm: nan is not finite (allowed [0.01, 94.33962264150944])"),
    ({"min_cpmm": 10, "band_limit_cpmm": 10}, "min_cpmm: 10.0 must be below band_limit_cpmm 10.0 (cycles/mm)"),
    ({"min_cpmm": 10.0004, "band_limit_cpmm": 10, "v": 2},
     "min_cpmm: 10.0 must be below band_limit_cpmm 10.0 (cycles/mm)"),
    ({"min_cpmm": 1.0005, "v": 2}, "min_cpmm: 1.0005 is half-way between two points"),
    ({"phase": "resets"}, "phase: expected one of 'continuous', 'reset', got 'resets'"),
    ({"phase": "Reset"}, "phase: expected one of 'continuous', 'reset', got 'Reset'"),
    ({"phase": 1}, "phase: expected one of 'continuous', 'reset', got int 1"),
    ({"phase": None}, "phase: expected one of 'continuous', 'reset', got NoneType None"),
    ({"phase": True}, "phase: expected one of 'continuous', 'reset', got bool True"),
    ({"phase": ["reset"]}, "phase: expected one of 'continuous', 'reset', got list"),
    ({"phase": "x" * 100}, "phase: expected one of 'continuous', 'reset', got a str of 100 characters"),
    ({"phases": "reset"}, "unknown key 'phases' (allowed: pitch_db, irregularity_db, texel_samples, "
     "length_samples, quant_db, seed, gain, v, band_limit_cpmm, min_cpmm, phase)"),
]


def _error(p: dict) -> str:
    try:
        texel.validate(p)
    except ValueError as e:
        return str(e)
    return "accepted"


@pytest.mark.parametrize("extra, msg", BAD)
def test_bad_options_are_refused(extra, msg):
    p = dict({"pitch_db": 6.3, "irregularity_db": -12.9}, **extra)
    before = dict(p)
    assert _error(p).startswith(msg)
    assert p == before


def test_bad_options_in_a_scene_name_their_path():
    d = {"positions": 19200, "dx_um": 5.3}
    for extra, want in (({"phase": "x"}, "regions[0].texture.phase: expected one of"),
                        ({"min_cpmm": 5, "band_limit_cpmm": 4}, "regions[0].texture.min_cpmm: 5.0 must be below")):
        tex = dict({"kind": "texel", "pitch_db": 1, "irregularity_db": -9}, **extra)
        with pytest.raises(ValueError) as e:
            S.validate({"regions": [{"start_mm": 0, "end_mm": 50, "texture": tex}]}, d)
        assert str(e.value).startswith(want)


# --- the lower bound -----------------------------------------------------------------

@pytest.mark.parametrize("v", [1, 2])
def test_bound_leaves_the_main_stream_and_other_texels_alone(v):
    p = seed001("wide", v=v)
    free = plan_of(dict(p, min_cpmm=None))
    bound = plan_of(p)
    f0 = np.array(free.f)
    f1 = np.array(bound.f)
    below = f0 < 1.0
    print("\nformat %d: %d of %d texels below 1 c/mm redrawn, %d at the bound"
          % (v, below.sum(), bound.count, bound.at_min))
    assert bound.redrawn == below.sum() > 0 and bound.at_min == 0
    assert np.array_equal(f1[~below], f0[~below])
    assert np.all(f1 >= 1.0)
    # a bound under every pitch: the plan is the loop's, bit for bit
    low = plan_of(dict(p, min_cpmm=float(f0.min()) * 0.99))
    assert low.redrawn == 0
    for k in ("t28", "d28"):
        assert bytes(getattr(low, k)) == bytes(getattr(free, k))


def test_tail_is_the_loops_own_arithmetic():
    """options.tail_int / tail_float recompute t28/d28 (phi) from the
    pitches: on a plan nobody changed they give back the loop's arrays -
    with a band limit, quantization, aliased steps, a ragged end and long
    texels - in float64 and in float32 (the board's float)."""
    cases = [dict(pitch_db=4.353, irregularity_db=-4.195, texel_samples=236, length_samples=18868),
             dict(pitch_db=19.0, irregularity_db=2.0, texel_samples=3, length_samples=3001,
                  band_limit_cpmm=60.0, quant_db=0.5),
             dict(pitch_db=19.747, irregularity_db=5.0, texel_samples=7, length_samples=5000),
             dict(pitch_db=10.0, irregularity_db=-3.0, texel_samples=700_000, length_samples=1_000_000)]
    for i, c in enumerate(cases):
        pl = plan_of(dict(c, seed=i, v=2))
        t, d, above = bytes(pl.t28), bytes(pl.d28), pl.above_nyquist
        assert options.tail_int(pl, pl.y, 0, TAB) == above
        assert (bytes(pl.t28), bytes(pl.d28)) == (t, d), c
        for ftype in (float, np.float32):
            q = P1.Plan(texel.validate(dict(c, seed=i, v=1)), ftype=ftype)
            before = (bytes(q.t28), bytes(q.d28), bytes(q.phi), q.above_nyquist)
            options.tail_float(q, ftype)
            assert (bytes(q.t28), bytes(q.d28), bytes(q.phi), q.above_nyquist) == before, (c, ftype)


def test_log_pitch_is_the_loops():
    pl = plan_of({"pitch_db": 3.0, "irregularity_db": 4.9, "quant_db": 0.7, "texel_samples": 1,
                  "length_samples": 20000, "seed": 3, "v": 2}, keep_z=True)
    ys = [options.log_pitch(z, pl.mu, pl.sigma, pl.q) for z in pl.z]
    assert ys == list(pl.y)


@pytest.mark.parametrize("v", [1, 2])
def test_tries_cap_plays_at_the_bound(v):
    """A bound far in the tail: 64 tries fail, every texel plays at it."""
    pl = plan_of({"pitch_db": -20.0, "irregularity_db": -30.0, "texel_samples": 100,
                  "length_samples": 2000, "min_cpmm": 5.0, "seed": 1, "v": v})
    assert pl.redrawn == pl.at_min == pl.count == 20
    assert list(pl.f) == [5.0] * 20
    dmin = options.d_min(5000)
    if v == 2:
        assert list(pl.d28) == [dmin] * 20
        # the phase advances by exactly D_MIN per sample
        assert all((pl.t28[i + 1] - pl.t28[i]) % 2 ** 28 == 100 * dmin % 2 ** 28 for i in range(19))
    else:
        assert max(abs(d - dmin) for d in pl.d28) <= 1


@pytest.mark.parametrize("v", [1, 2])
@pytest.mark.parametrize("pitch_db, irregularity_db, hopeless", [
    (-20.0, -30.0, True), (-1.2, -20.0, True), (-1.2, -12.0, False), (-3.0, -8.0, False),
    (0.5, -30.0, False)])
def test_skipping_hopeless_tries_changes_nothing(v, pitch_db, irregularity_db, hopeless,
                                                 monkeypatch):
    """When no draw can reach the bound (the largest z the generator gives is
    below it) the tries are skipped: the same plan as trying them all."""
    p = {"pitch_db": pitch_db, "irregularity_db": irregularity_db, "texel_samples": 189,
         "length_samples": 9600, "min_cpmm": 1.0, "seed": 9, "phase": "reset", "v": v}
    fast = plan_of(p)
    monkeypatch.setattr(options, "SKIP_HOPELESS", False)
    slow = plan_of(p)
    assert (fast.redrawn, fast.at_min) == (slow.redrawn, slow.at_min)
    assert list(fast.t28) == list(slow.t28) and list(fast.d28) == list(slow.d28)
    assert list(fast.f) == list(slow.f)
    assert (fast.at_min == fast.count) is hopeless      # hopeless: every texel at the bound


@pytest.mark.parametrize("v", [1, 2])
@pytest.mark.parametrize("which", ["wide", "narrow"])
def test_bounded_pitches_follow_the_truncated_lognormal(v, which):
    """One texel per sample, 150,000 texels (seed 001's numbers with its
    1 c/mm bound; the wide condition has 12.6 % of its draws below it):
    no pitch below the bound, and K-S against scipy's lognormal truncated at
    the bound, (F(x) - F(b)) / (1 - F(b)), gives p > 0.01 (fixed seed: the
    figure is the same on every run)."""
    p = seed001(which, v=v, texel_samples=1, length_samples=150_000, seed=21)
    pl = plan_of(p) if v == 2 else PN.PlanNumpy(texel.validate(p))
    f = np.asarray(pl.f, dtype=np.float64)
    assert f.min() >= 1.0
    pitch, irreg = (WIDE if which == "wide" else NARROW)
    dist = stats.lognorm(s=10 ** (irreg / 10) * math.log(10), scale=10 ** (pitch / 10))
    fb = dist.cdf(1.0)
    res = stats.kstest(f, lambda x: (dist.cdf(x) - fb) / (1 - fb))
    print("\n%s v%d: %d redrawn (%.2f %%; lognormal below 1: %.2f %%), K-S D=%.5f p=%.3f"
          % (which, v, pl.redrawn, 100 * pl.redrawn / pl.count, 100 * fb, res.statistic, res.pvalue))
    assert res.pvalue > 0.01
    assert pl.at_min == 0
    assert abs(pl.redrawn / pl.count - fb) < 5 * math.sqrt(fb * (1 - fb) / pl.count) + 1e-4


# --- phase reset ---------------------------------------------------------------------

@pytest.mark.parametrize("v", [1, 2])
def test_reset_starts_every_texel_at_the_first_phase_and_jumps(v):
    p = {"pitch_db": 3.0, "irregularity_db": -8.0, "texel_samples": 189, "length_samples": 18900,
         "seed": 8, "v": v}
    run = plan_of(p)
    rst = plan_of(dict(p, phase="reset"))
    assert set(rst.t28) == {run.t28[0]} and set(rst.phi) == {run.phi[0]}
    assert list(rst.d28) == list(run.d28) and list(rst.f) == list(run.f)
    L, n = p["texel_samples"], p["length_samples"]
    # one sample's largest change inside a texel: (1/2) * 2*pi*f*dx
    slope = 0.5 * 2 * math.pi * max(rst.f) * texel.DX_MM
    for engine in ("numpy", "int", "pure"):
        m_run = np.asarray(texel.render(p, engine=engine), dtype=np.float64)
        m_rst = np.asarray(texel.render(dict(p, phase="reset"), engine=engine), dtype=np.float64)
        borders = np.arange(L, n, L)
        j_run = np.abs(m_run[borders] - m_run[borders - 1])
        j_rst = np.abs(m_rst[borders] - m_rst[borders - 1])
        inside = np.abs(np.diff(m_rst)).max()
        tol = slope + 2e-4                  # + the int engine's table and Q16 rounding
        print("\nv%d %s: borders over one step's change: continuous %d, reset %d of %d"
              % (v, engine, (j_run > tol).sum(), (j_rst > tol).sum(), borders.size))
        assert (j_run > tol).sum() == 0
        assert (j_rst > tol).sum() > 0.5 * borders.size
        assert inside >= j_rst.max() - 1e-12      # the jumps are at the borders
        # texel 0 is the same texture either way
        assert np.array_equal(m_run[:L], m_rst[:L])


def test_every_engine_and_the_scene_plan_play_the_options():
    """numpy (float64, from f/phi), int and pure (from t28/d28) agree on a
    bounded, reset plan as on any plan (within the int engine's Q16/table
    error), and a scene region plays it from its plan (K_PLAN) sample for
    sample as the int engine renders it."""
    p = dict(seed001("wide"), phase="reset", length_samples=4000)
    m_np = np.asarray(texel.render_u16(p, engine="numpy"), dtype=np.int64)
    for engine in ("int", "pure"):
        m = np.asarray(texel.render_u16(p, engine=engine), dtype=np.int64)
        assert np.abs(m - m_np).max() <= 8, engine          # 1.2e-4 of full scale
    # without the options every engine is far from it: the test can tell
    other = np.asarray(texel.render_u16(dict(p, phase="continuous", min_cpmm=None),
                                        engine="int"), dtype=np.int64)
    assert np.abs(other - m_np).max() > 10_000
    d = {"positions": 4000, "dx_um": 5.3}
    tex = {k: v for k, v in p.items() if k != "length_samples"}
    sc = S.build(S.validate({"regions": [{"start_mm": 0, "end_mm": 21.2,
                                          "texture": dict(tex, kind="texel")}]}, d), d)
    assert len(sc.plans()) == 1
    got = np.array([sc.amp(i) for i in range(4000)])
    assert np.array_equal(got, np.asarray(texel.render_u16(p, engine="int")))


@pytest.mark.parametrize("v", [1, 2])
@pytest.mark.parametrize("extra", [{"min_cpmm": 1.0}, {"phase": "reset"},
                                   {"min_cpmm": 2.5, "phase": "reset", "quant_db": 1.0}])
def test_plan_numpy_is_the_scalar_plan(v, extra):
    p = texel.validate(dict(seed001("wide", v=v, texel_samples=30), **extra))
    a = PN.make_plan(p)
    assert type(a) is (PN.PlanIntNumpy if v == 2 else PN.PlanNumpy)
    b = P2.PlanInt(p) if v == 2 else P1.Plan(p)
    for k in ("t28", "d28", "f", "phi"):
        assert bytes(memoryview(getattr(a, k)).cast("B")) == bytes(memoryview(getattr(b, k)).cast("B")), k
    assert (a.redrawn, a.at_min, a.above_nyquist) == (b.redrawn, b.at_min, b.above_nyquist)
    if v == 2:
        assert bytes(a.y) == bytes(b.y)
        # engine_numpy's float views of a PlanInt (int_pitches/int_phases)
        assert np.array_equal(engine_numpy._pitches_phases(b)[1], np.asarray(b.phi))
    c = P2.PlanInt(p, keep_y=False) if v == 2 else None
    if c is not None:                   # what a board's scene builds: no y kept
        assert bytes(c.t28) == bytes(b.t28) and bytes(c.d28) == bytes(b.d28) and c.y is None


# --- every runtime -------------------------------------------------------------------

RUNTIME_CASES = {
    "wide": seed001("wide"),
    "narrow-reset": seed001("narrow", phase="reset", texel_samples=4906),
    "reset-only": {"pitch_db": 12.0, "irregularity_db": -10.0, "texel_samples": 50,
                   "length_samples": 9600, "seed": 3, "phase": "reset", "v": 2},
    "bound-quant-cap": {"pitch_db": 0.0, "irregularity_db": 0.0, "texel_samples": 7,
                        "length_samples": 3000, "seed": 4, "min_cpmm": 0.5, "band_limit_cpmm": 50.0,
                        "quant_db": 2.0, "v": 2},
    "at-min": {"pitch_db": -20.0, "irregularity_db": -30.0, "texel_samples": 100,
               "length_samples": 2000, "min_cpmm": 5.0, "seed": 1, "phase": "reset", "v": 2},
    "aliased": {"pitch_db": 19.747, "irregularity_db": 3.0, "texel_samples": 3,
                "length_samples": 3000, "min_cpmm": 0.01, "seed": 6, "v": 2},
}
FLOAT_CASES = {
    "wide-v1": seed001("wide", v=1, length_samples=9600),
    "reset-v1": dict(RUNTIME_CASES["reset-only"], v=1),
    "quant-v1": dict(RUNTIME_CASES["bound-quant-cap"], v=1),
}
BAD_ON_DEVICE = [e for e, _ in BAD if "nan" not in repr(e)]      # (nan: no literal)

RUNTIME_SCRIPT = r"""
import json
import texel
from texel.gen import plan_int as P
from texel.gen import plan as P1
from texel.gen import lognormal
from texel.runtime import scene as S
from texel.runtime.kinds import texel as KT, samples as KS
out = %(out)r
cases = %(cases)r
fcases = %(fcases)r
bad = %(bad)r
info = {"viper": P.VIPER, "same_loops": {}, "counts": {}, "scene": {}, "float": {}, "bad": [],
        "lognormal": [lognormal.to_db(4, 1.2), lognormal.to_db(4, 4.3)], "ulab": {}}
def save(path, buf):
    f = open(path, "wb")
    f.write(buf)
    f.close()
for name in sorted(cases):
    p = cases[name]
    pl = P.PlanInt(texel.validate(p))
    info["counts"][name] = [pl.redrawn, pl.at_min, pl.above_nyquist]
    save(out + "/" + name + ".plan", bytes(pl.t28) + bytes(pl.d28) + bytes(pl.y))
    m = texel.render_u16(p, engine="int")
    save(out + "/" + name + ".map", bytes(m))
    if P.VIPER:
        q = P.PlanInt(texel.validate(p), engine="py")
        info["same_loops"][name] = (bytes(q.t28) == bytes(pl.t28) and bytes(q.d28) == bytes(pl.d28)
                                    and bytes(q.y) == bytes(pl.y))
    if "ulab" in texel.engines():
        u = texel.render_u16(p, engine="ulab")
        info["ulab"][name] = max([abs(int(u[i]) - m[i]) for i in range(len(m))])
    n = min(p["length_samples"], 3000)
    d = {"positions": n, "dx_um": 5.3}
    tex = {"kind": "texel"}
    for k in p:
        if k != "length_samples":
            tex[k] = p[k]
    sc = S.build(S.validate({"regions": [{"start_mm": 0, "end_mm": n * 0.0053,
                                          "texture": tex}]}, d), d)
    want = texel.render_u16(dict(p, length_samples=n), engine="int")
    info["scene"][name] = [len(sc.plans()), all([sc.amp(i) == want[i] for i in range(n)])]
for name in sorted(fcases):
    pl = P1.Plan(texel.validate(fcases[name]))
    info["float"][name] = [list(pl.f), pl.redrawn, pl.at_min, len(set(pl.t28))]
for extra in bad:
    p = {"pitch_db": 6.3, "irregularity_db": -12.9}
    p.update(extra)
    try:
        texel.validate(p)
        info["bad"].append("accepted")
    except ValueError as e:
        info["bad"].append(str(e))
print(json.dumps(info))
"""


def _run(exe: str, tmp_path) -> dict:
    code = RUNTIME_SCRIPT % {"out": str(tmp_path), "cases": RUNTIME_CASES, "fcases": FLOAT_CASES,
                             "bad": BAD_ON_DEVICE}
    return mpy.run_json(code, exe=exe, heapsize="8M", timeout=600)


def _digits5(msg: str) -> str:
    return re.sub(r"\d+\.\d+", lambda m: "%.5g" % float(m.group()), msg)


def _check(info: dict, tmp_path, float_rel: float) -> None:
    for name, p in RUNTIME_CASES.items():
        pl = plan_of(p)
        assert (tmp_path / (name + ".plan")).read_bytes() == \
            bytes(pl.t28) + bytes(pl.d28) + bytes(pl.y), name
        m = np.asarray(texel.render_u16(p, engine="int"), dtype=np.uint16)
        assert (tmp_path / (name + ".map")).read_bytes() == m.tobytes(), name
        assert info["counts"][name] == [pl.redrawn, pl.at_min, pl.above_nyquist], name
        # a region plays from its plan (K_PLAN) when its texels are shorter
        # than it (kinds.texel.on_plan); else from the int engine's map
        L, n = p["texel_samples"], min(p["length_samples"], 3000)
        assert info["scene"][name] == [1 if 4 < L < n else 0, True], name
    assert info["counts"]["at-min"][:2] == [20, 20] and info["counts"]["wide"][0] > 0
    if info["viper"]:
        assert all(info["same_loops"].values()), info["same_loops"]
    for name, (f, redrawn, at_min, starts) in info["float"].items():
        ref = P1.Plan(texel.validate(FLOAT_CASES[name]))
        assert (redrawn, at_min) == (ref.redrawn, ref.at_min), name
        assert np.allclose(f, list(ref.f), rtol=float_rel, atol=0), name
        assert (starts == 1) is (FLOAT_CASES[name].get("phase") == "reset"), name
    # the same messages; a float shown to 5 digits (float32 boards show the
    # Nyquist pitch 94.34 c/mm as 94.33962, CPython as 94.33962264150944)
    assert [_digits5(m) for m in info["bad"]] == \
        [_digits5(_error(dict({"pitch_db": 6.3, "irregularity_db": -12.9}, **e))) for e in BAD_ON_DEVICE]
    assert [tuple(x) for x in info["lognormal"]] == [NARROW, WIDE]
    for name, worst in info["ulab"].items():
        # ulab's float32 sine of the same fixed-point phases: 0.03 PWM step
        # (engine_ulab.py); in uint16 units a few counts
        assert worst <= 16, (name, worst)


def test_float_cases_stay_clear_of_the_bound():
    """Precondition of the format-1 comparison across runtimes: no draw of
    the main stream lies within 1e-3 of the bound, so a float32 runtime
    takes the same redraw decisions as CPython."""
    for name, p in FLOAT_CASES.items():
        if "min_cpmm" in p:
            f = np.array(P1.Plan(texel.validate(dict(p, min_cpmm=None))).f)
            assert np.abs(f / p["min_cpmm"] - 1).min() > 1e-3, name


def test_same_options_plan_on_the_unix_port(tmp_path):
    info = _run(toolchain.require_micropython(), tmp_path)
    assert info["viper"] is True
    _check(info, tmp_path, float_rel=1e-12)


@pytest.mark.instruments
@pytest.mark.parametrize("name, rel", [("micropython-ulab-f32", 2e-5), ("micropython-ulab-f64", 1e-12),
                                       ("circuitpython", 8e-5)])
def test_same_options_plan_on_the_instruments(name, rel, tmp_path):
    """Format 2 with the options: bit for bit. Format 1: pitches within the
    runtime's float (float32 ~ 10^pull's relative error of a few 1e-7 times
    ln 10 and |pull| < 2: 2e-5 is ~30 ulps; CircuitPython's 30-bit floats
    4x that)."""
    exe = toolchain.interpreter(name)
    if exe is None:
        pytest.skip("%s is not on this machine (../shared/instruments)" % name)
    info = _run(exe, tmp_path)
    assert info["viper"] is (name != "circuitpython")
    assert bool(info["ulab"]) is True
    _check(info, tmp_path, float_rel=rel)
    print("\n%s: ulab vs int, worst uint16 difference per case: %s" % (name, json.dumps(info["ulab"])))

"""The vectorised plan and synthesis on CPython are today's, bit for bit.

device/texel/gen/plan_numpy.py builds format 1's Plan (gen/plan.py) and
format 2's PlanInt (gen/plan_int.py, its Python loop texels_py) with numpy;
device/texel/gen/engine_numpy.py synthesises the whole map at once instead of
a texel at a time. Both must change nothing: for random textures of both
formats (seeded: the same cases every run) - quantization on and off, band
limits, pitches far above Nyquist (aliased), 1-sample texels, texels longer
than the map, lengths that are no multiple of the texel, gains, the extreme
seeds - and for the hard cases and the golden runs' replayed draws, every
array of the plan has the same bytes, every scalar the same value and type,
and the maps (y, the float map, uint16) are the same bits as the per-texel
loop the engine ran before (render_y_loop below, verbatim).
"""
from __future__ import annotations

import math
import random
from array import array

import numpy as np
import pytest

import texel
from texel.gen import engine_numpy, plan_numpy as PN
from texel.gen import plan_int as PI
from texel.gen.plan import Plan
from texel.gen.plan_int import PlanInt
from texel.gen.params import texel_count
from texel.gen.plan_int_tables import table
from texel.gen.rng import Rng
from texelpad.analysis.hard_cases import HARD_CASES
from support import golden

N_RANDOM = 250          # random textures per format


def render_y_loop(plan):
    """engine_numpy.render_y as it was: one texel at a time (commit b5a87b1)."""
    n, L = plan.n, plan.L
    y = np.empty(n, dtype=np.float64)
    t = np.arange(1, L + 1, dtype=np.float64)
    two_pi = 2 * math.pi
    for i in range(plan.count):
        a = i * L
        b = min(a + L, n)
        pitch = plan.f[i] * 0.0053
        y[a:b] = np.sin(two_pi * pitch * t[: b - a] + plan.phi[i])
    return y


def u16_loop(plan):
    m = render_y_loop(plan)
    m += 1.0
    m *= 0.5 * plan.gain
    return np.floor(m * 65535.0 + 0.5).astype(np.uint16)


def bits(a) -> bytes:
    return np.ascontiguousarray(a).tobytes()


FLOAT_ARRAYS = ("f", "phi")
INT_ARRAYS = ("t28", "d28")
SCALARS = ("n", "L", "count", "gain", "above_nyquist", "u")
INT_SCALARS = ("mu", "sigma", "q", "cap_mc", "dcap", "x0")


def assert_same_plan(want, got, label=""):
    """Every attribute of the two plans: the same values of the same types,
    arrays byte for byte (format 2: its integers, log pitches and draws too)."""
    fmt2 = isinstance(want, PlanInt)
    assert isinstance(got, type(want)), (label, type(want), type(got))
    for k in SCALARS + (INT_SCALARS if fmt2 else ()):
        a, b = getattr(want, k), getattr(got, k)
        assert a == b and type(a) is type(b), (label, k, a, b)
    for k in INT_ARRAYS + FLOAT_ARRAYS + (("y", "z") if fmt2 else ()):
        a, b = getattr(want, k), getattr(got, k)
        assert type(a) is type(b), (label, k, type(a), type(b))
        if a is None:
            continue
        assert bytes(a) == bytes(b), (label, k, np.flatnonzero(
            np.frombuffer(bytes(a), dtype=np.uint8) != np.frombuffer(bytes(b), dtype=np.uint8))[:5])
    if isinstance(want.t28, memoryview):            # PlanInt: halves of one array
        assert got.t28.obj is got.d28.obj and len(got.t28.obj) == 2 * got.count
    assert want.fraction_above_nyquist() == got.fraction_above_nyquist()
    assert want.pitches_db() == got.pitches_db()


def assert_same_maps(loop_plan, *plans, label=""):
    y0 = render_y_loop(loop_plan)
    q0 = u16_loop(loop_plan)
    for plan in plans:
        y = engine_numpy.render_y(plan)
        assert y.dtype == np.float64 and y.shape == (loop_plan.n,)
        bad = np.flatnonzero(y.view(np.uint64) != y0.view(np.uint64))
        assert bad.size == 0, (label, bad[:5], y[bad[:5]], y0[bad[:5]])
        m = engine_numpy.render(plan)
        m0 = y0 * 1.0
        m0 += 1.0
        m0 *= 0.5 * loop_plan.gain
        assert bits(m) == bits(m0), label
        q = engine_numpy.render_u16(plan)
        assert q.dtype == np.uint16 and bits(q) == bits(q0), label
        out = array("H", bytes(2 * loop_plan.n))
        assert engine_numpy.render_u16(plan, out) is out and bytes(out) == bits(q0), label


def random_params(rnd: random.Random, v: int) -> dict:
    L = rnd.choice([1, 2, 3, 7, 50, 50, 64, 333, rnd.randint(1, 4000), 30000])
    n = rnd.choice([1, 2, L, L + 1, 2 * L - 1, 19200, rnd.randint(1, 20000),
                    rnd.randint(1, 4) * L + rnd.randint(0, max(L - 1, 0))])
    n = max(1, min(n, 40000))
    if L == 1:
        n = min(n, 6000)                 # the per-texel loops of the reference stay quick
    p = {"pitch_db": rnd.choice([rnd.uniform(-20.0, 19.747), 19.747, -20.0,
                                 rnd.uniform(15.0, 19.747)]),
         "irregularity_db": rnd.choice([rnd.uniform(-30.0, 5.0), 5.0, -30.0,
                                        rnd.uniform(-5.0, 5.0)]),
         "texel_samples": L, "length_samples": n,
         "quant_db": rnd.choice([0.0, 0.0, 0.001, rnd.uniform(0.001, 20.0), 20.0, 5.0]),
         "seed": rnd.choice([0, 1, 7, 0xFFFFFFFF, rnd.randint(0, 0xFFFFFFFF)]),
         "gain": rnd.choice([1.0, 0.0, 0.5, rnd.random()]),
         "band_limit_cpmm": rnd.choice([None, None, rnd.uniform(0.01, 94.34), 94.3396, 0.01]),
         "v": v}
    return p


def _valid(rnd, v):
    while True:
        try:
            return texel.validate(random_params(rnd, v))
        except ValueError:              # format 2's grid refuses a half-way value
            continue


@pytest.mark.parametrize("v", [1, 2])
def test_random_textures_plan_and_maps_bit_for_bit(v):
    rnd = random.Random(20230 + v)
    seen = {"quant": 0, "cap": 0, "aliased": 0, "texel1": 0, "long_texel": 0, "ragged": 0}
    for k in range(N_RANDOM):
        p = _valid(rnd, v)
        label = "case %d: %r" % (k, p)
        if v == 1:
            want = Plan(p)
            got = PN.PlanNumpy(p)
        else:
            want = PlanInt(p, keep_z=True, engine="py")
            got = PN.PlanIntNumpy(p, keep_z=True)
        assert_same_plan(want, got, label)
        if v == 2:
            # float views: the engine's own numpy copy, the numpy plan's
            # properties, and the loop plan's properties (read last: cached)
            want2 = PlanInt(p, engine="py")
            assert_same_maps(want, want2, got, label=label)
            assert bytes(got.f) == bytes(want.f) and bytes(got.phi) == bytes(want.phi), label
        else:
            assert_same_maps(want, want, got, label=label)
        seen["quant"] += p["quant_db"] > 0
        seen["cap"] += p["band_limit_cpmm"] is not None
        seen["aliased"] += want.above_nyquist > 0
        seen["texel1"] += p["texel_samples"] == 1
        seen["long_texel"] += p["texel_samples"] > p["length_samples"]
        seen["ragged"] += p["length_samples"] % p["texel_samples"] != 0
    # the random cases reach every branch the brief names
    assert min(seen.values()) >= 10, seen


@pytest.mark.parametrize("v", [1, 2])
@pytest.mark.parametrize("case", list(HARD_CASES))
def test_hard_cases(case, v):
    p = texel.validate(dict(HARD_CASES[case][0], v=v))
    want = Plan(p) if v == 1 else PlanInt(p, engine="py", keep_z=True)
    got = PN.make_plan(p) if v == 1 else PN.PlanIntNumpy(p, keep_z=True)
    assert_same_plan(want, got, case)
    fresh = Plan(p) if v == 1 else PlanInt(p)   # the engine's own float views (format 2)
    assert_same_maps(want, fresh, got, label=case)
    # texel.make_plan (numpy on CPython) against the loops' plan, the same keys
    assert_same_plan(fresh, texel.make_plan(p), case)
    assert_same_plan(fresh, texel.make_plan(dict(HARD_CASES[case][0], v=v)), case)


@pytest.fixture(scope="module")
def gruns(golden_dir):
    return golden.runs(golden_dir)


def test_golden_runs_replayed_draws(gruns):
    """The lab's logged draws (../shared/golden/spt): the same plan and map."""
    assert len(gruns) == 8
    for r in gruns:
        p = texel.validate(r["params"])
        want = Plan(p, r["draws"])
        got = PN.make_plan(p, r["draws"])
        assert_same_plan(want, got, r["id"])
        assert_same_plan(want, texel.make_plan(r["params"], r["draws"]), r["id"])
        assert_same_maps(want, got, label=r["id"])
        # and still the original's map (tests/gen/test_golden.py's bound)
        assert np.abs(engine_numpy.render_y(got) - r["map"]).max() < 1e-9


def test_replayed_draws_random_and_refused():
    rnd = random.Random(5)
    for _ in range(40):
        p = _valid(rnd, 1)
        count = texel_count(p)
        zs = [rnd.choice([rnd.gauss(0, 1), 10.0, -10.0, 0.0, -0.0, rnd.uniform(-10, 10)])
              for _ in range(count + rnd.randint(0, 3))]
        draws = (rnd.choice([rnd.random(), 0.0, 1.0, 0.5]), zs)
        assert_same_plan(Plan(p, draws), PN.make_plan(p, draws))
    p = texel.validate({"pitch_db": 6.0, "irregularity_db": -10.0, "length_samples": 200, "v": 1})
    for bad in [(0.5, [0.0]), (2.0, [0.0] * 4), (0.5, [0.0, 11.0, 0.0, 0.0]), 3,
                (0.5, "abcd"), (0.5, [float("nan")] * 4)]:
        with pytest.raises(ValueError) as a:
            Plan(p, bad)
        with pytest.raises(ValueError) as b:
            PN.make_plan(p, bad)
        assert str(a.value) == str(b.value)
    with pytest.raises(ValueError, match="format 1's"):
        PN.make_plan(texel.validate(dict(p, v=2)), (0.5, [0.0] * 4))


@pytest.mark.parametrize("v", [1, 2])
def test_make_plan_takes_the_loop_for_few_texels(v):
    """plan_numpy.make_plan: the loops below LOOP_BELOW texels (quicker
    there), the arrays from it on - the same plan either way."""
    for count in (1, 2, PN.LOOP_BELOW - 1, PN.LOOP_BELOW, PN.LOOP_BELOW + 1, 400):
        p = texel.validate({"pitch_db": 12.0, "irregularity_db": -3.0, "seed": count,
                            "texel_samples": 50, "length_samples": 50 * count - 7, "v": v})
        got = PN.make_plan(p)
        loop = Plan if v == 1 else PlanInt
        fast = PN.PlanNumpy if v == 1 else PN.PlanIntNumpy
        assert type(got) is (loop if count < PN.LOOP_BELOW else fast), count
        assert_same_plan(loop(p), got, count)
        assert_same_plan(loop(p), fast(p), count)
        assert type(texel.make_plan(p)) is type(got), count   # texel's API: the same choice


def test_texel_make_plan_uses_plan_numpy_on_cpython_only(monkeypatch):
    """texel.make_plan on CPython with numpy is plan_numpy's (issue 23 item
    9); where compat has no numpy, or on any other implementation (a board),
    it runs the loops - the same plans, the same refusals word for word."""
    p = dict(HARD_CASES["study"][0])                      # 384 texels
    assert type(texel.make_plan(p)) is PN.PlanNumpy
    assert type(texel.make_plan(dict(p, v=2))) is PN.PlanIntNumpy
    draws = (0.25, [0.5] * 384)
    assert type(texel.make_plan(p, draws)) is PN.PlanNumpy

    def refusals():
        out = []
        for args in [(dict(p, v=2), draws), (dict(p, v=2), (0.5, [])), (p, (0.5, [0.0])),
                     (p, (2.0, [0.0] * 384)), (p, 3), (p, (0.5, [float("nan")] * 384)),
                     (dict(p, v=3), None), (dict(p, pitch_db=99.0), None),
                     (dict(p, bogus=1), None)]:
            with pytest.raises(ValueError) as e:
                texel.make_plan(*args)
            out.append(str(e.value))
        return out

    on_numpy = refusals()
    assert on_numpy[0] == on_numpy[1] == ("draws: replaying logged draws is format 1's (v=1); "
                                          "format 2 draws from its seed")
    plans = [texel.make_plan(p), texel.make_plan(dict(p, v=2)), texel.make_plan(p, draws)]
    for attr, value in (("numpy_mod", None), ("IMPL", "micropython")):
        with monkeypatch.context() as m:
            m.setattr(texel.compat, attr, value)
            loops = [texel.make_plan(p), texel.make_plan(dict(p, v=2)),
                     texel.make_plan(p, draws)]
            assert [type(x) for x in loops] == [Plan, PlanInt, Plan], attr
            assert refusals() == on_numpy, attr
        for want, got in zip(loops, plans):
            assert_same_plan(want, got, attr)


def test_generator_outputs_are_the_rng_stream():
    for seed in (0, 1, 7, 12345, 0x7FFFFFFF, 0x80000000, 0xFFFFFFFF):
        for count in (0, 1, 2, 5, 400):
            rng = Rng(seed)
            want = []
            for _ in range(count + 1):
                hi, lo = rng.next_hi_lo()
                want.append((hi << 16) | lo)
            got = PN.outputs(seed, count)
            assert got.dtype == np.int64 and got.tolist() == want, (seed, count)


def _extreme_outputs():
    xs = [0, 1, 2, 3, 0x7FFFFFFE, 0x7FFFFFFF, 0x80000000, 0x80000001, 0xFFFFFFFE, 0xFFFFFFFF]
    # around AS241's branch point |u - 0.5| = 0.425 (its other one, r = 5, is
    # beyond every 32-bit draw: r <= 4.8 at x = 0; replayed draws give z itself)
    for u in (0.075, 0.925):
        c = int(u * 2 ** 32)
        xs += [max(0, min(0xFFFFFFFF, c + d)) for d in range(-3, 4)]
    rnd = random.Random(9)
    xs += [rnd.getrandbits(32) for _ in range(20000)]
    xs += [rnd.getrandbits(rnd.randint(1, 32)) for _ in range(2000)]
    xs += [0xFFFFFFFF - rnd.getrandbits(rnd.randint(1, 32)) for _ in range(2000)]
    return xs


def test_normal_draws_both_formats():
    """Format 1's AS241 (Rng.normal) and format 2's table inverse normal
    (plan_int.norm_q24) of the same outputs, element by element."""
    xs = _extreme_outputs()
    x = np.array(xs, dtype=np.int64)
    assert math.sqrt(-math.log(0.5 / 2 ** 32)) < 4.8      # AS241's r at x = 0
    z1 = PN.normals(x)
    tab = table()
    z2 = PN.norm_q24(x, PN._tab())
    r = Rng(0)
    for i, v in enumerate(xs):
        r.next_hi_lo = lambda v=v: (v >> 16, v & 0xFFFF)
        want = r.normal()
        assert z1[i] == want and math.copysign(1, z1[i]) == math.copysign(1, want), v
        assert int(z2[i]) == PI.norm_q24(v >> 16, v & 0xFFFF, tab), v


def test_phase_steps_every_octave():
    """plan_int.step_d over the whole clamped range of log pitches, every
    binary exponent of the step and its edges."""
    tab = table()
    ys = list(range(PI.Y_LO, PI.Y_LO + 5000)) + list(range(PI.Y_HI - 5000, PI.Y_HI + 1))
    for e in range(-3, 37):             # where w = y + LOG2_STEP0 crosses e * 2^24
        c = (e << 24) - PI.LOG2_STEP0
        ys += [y for y in range(c - 300, c + 300) if PI.Y_LO <= y <= PI.Y_HI]
    rnd = random.Random(11)
    ys += [rnd.randint(PI.Y_LO, PI.Y_HI) for _ in range(30000)]
    got = PN.step_d(np.array(ys, dtype=np.int64), PN._tab())
    for i, y in enumerate(ys):
        assert tuple(int(g[i]) for g in got) == PI.step_d(y, tab), y


def test_numpy_engine_reads_a_format2_plan_as_before():
    """engine_numpy makes a PlanInt's float views itself (numpy); the plan's
    own (cached) views come out the same, and a plan without log pitches
    (keep_y=False, a board's) is refused as before."""
    p = texel.validate(dict(HARD_CASES["study"][0], v=2))
    fresh = PlanInt(p)
    y = engine_numpy.render_y(fresh)
    assert fresh._f is None                 # the engine did not fill the plan's cache
    cached = PlanInt(p)
    cached.f, cached.phi                    # noqa: B018 - fill the cache, then render from it
    assert bits(engine_numpy.render_y(cached)) == bits(y)
    assert bits(y) == bits(render_y_loop(PlanInt(p)))
    bare = PlanInt(p, keep_y=False)
    with pytest.raises(TypeError):
        engine_numpy.render_y(bare)

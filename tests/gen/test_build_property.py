"""Every valid texel parameter set BUILDS: hypothesis draws parameter sets
that texel.validate accepts - the whole range of every key, bounds, ints for
floats, subnormals, 17-digit values, quantization grids from 0.001 to 20 dB,
band limits, gain 0 - and each is planned and rendered, not only validated.

For each case (CPython):
- validate() returns a new dict, leaves its input alone and is idempotent;
- make_plan(): ceil(n/L) texels, every pitch finite and > 0 (capped by the
  band limit, on the quantization grid), phases finite, t28/d28 in
  [0, 2^28), pitches_db() finite;
- the float64 reference (numpy engine) is a finite map in [0, gain];
- the int and pure engines' uint16 and float maps are in range and within
  texelpad.analysis.precision.error_bound of the reference, sample by sample
  (as tests/gen/test_precision.py does for the hard cases); numpy's own
  uint16 map is the reference rounded;
- texel.render_u16 (the API path) gives the int engine's map.
Replayed draws (make_plan(params, draws)) likewise, z over the whole allowed
[-10, 10]. And with one key set to anything at all (huge ints, every float,
None, strings, complex, containers), or draws of anything: a ValueError
naming the key (or "draws:"), or a set that builds - never another
exception (these two found the holes fixed in params.py and plan.py). A subset of cases, extremes included, runs again under the real
MicroPython unix port (plan integers and uint16 maps bit-identical to
CPython's).

Lengths are capped at LEN_CAP samples in the generated cases for speed; the
extremes (1 and 1,048,576 samples, texels of 1 and 1,048,576 samples) are
explicit cases (EXTREMES), the two longest maps in a test marked slow.

Hypothesis profiles (tests/conftest.py): by default the runs are
derandomized (the same cases every run) and bounded; with
TEXELPAD_HYPOTHESIS=nightly they draw fresh random cases, NIGHTLY_SCALE (25)
times as many (thousands per property):
    TEXELPAD_HYPOTHESIS=nightly pytest -s tests/gen/test_build_property.py
Regression tests for the holes found: tests/gen/test_params.py (CPython),
the end of this module (MicroPython, the float32 build) and
tests/runtime/test_scene_property.py (the long stretch).
"""
from __future__ import annotations

import copy
import json
import math
import os
import struct

import numpy as np
import pytest
from hypothesis import Phase, example, given, note, settings, strategies as st

from support import hyp_profiles, mpy  # noqa: F401 (hyp_profiles: registers the profiles)
import texel
from texel.gen import engine_int, engine_numpy, engine_pure
from texel.gen import params as P
from texel.gen import plan as PL
from texelpad.analysis import precision as pr

# --- profiles (registered in tests/conftest.py) ---------------------------------------
NIGHTLY = os.environ.get("TEXELPAD_HYPOTHESIS") == "nightly"
NIGHTLY_SCALE = 25                  # tests/conftest.py


def hyp_settings(n, **kw):
    """Settings for a property of n examples (n * NIGHTLY_SCALE at night)."""
    prof = settings.get_profile("texelpad-nightly" if NIGHTLY else "texelpad-default")
    return settings(prof, max_examples=n * (NIGHTLY_SCALE if NIGHTLY else 1), **kw)


N_PARAMS = 200          # parameter sets per run (default profile)
N_DRAWS = 60            # replayed-draw cases
LEN_CAP = 1500          # longest generated map, samples
NYQ = P.NYQUIST_CPMM
UNIT = 1 << 28


# --- valid parameter sets ----------------------------------------------------------------
def _int_in(lo, hi):
    return st.integers(math.ceil(lo), math.floor(hi))


def _uniform_int(lo, hi):
    """About uniform in [lo, hi]: hypothesis draws small bounded integers
    mostly at their lower end (it still shrinks toward lo)."""
    return st.integers(0, 2 ** 24).map(lambda k: lo + k % (hi - lo + 1))


@st.composite
def _pick(draw, *strategies):
    """st.one_of with an about uniform choice of the branch."""
    return draw(strategies[draw(_uniform_int(0, len(strategies) - 1))])


def _finite(lo, hi):
    """Valid floats in [lo, hi]: hypothesis' own choice, uniform with full
    17-digit precision, or the bounds and their inner neighbours."""
    return _pick(
        st.floats(lo, hi, allow_nan=False, allow_infinity=False),
        st.integers(0, 2 ** 53).map(lambda k: min(hi, lo + (hi - lo) * (k / 2 ** 53))),
        st.sampled_from([lo, hi, math.nextafter(lo, math.inf), math.nextafter(hi, -math.inf)]))


VALID = {
    "pitch_db": _pick(_finite(P.PITCH_DB_MIN, P.PITCH_DB_MAX), _int_in(P.PITCH_DB_MIN, P.PITCH_DB_MAX),
                      st.sampled_from([0.0, -0.0, 5e-324, -5e-324, 2.2250738585072014e-308, 6.3])),
    "irregularity_db": _pick(_finite(P.IRREG_DB_MIN, P.IRREG_DB_MAX), _int_in(P.IRREG_DB_MIN, P.IRREG_DB_MAX),
                             st.sampled_from([P.IRREG_DB_MAX, 4.99, 3.0, 5e-324])),
    "texel_samples": _pick(_uniform_int(1, 8), _uniform_int(1, 400), st.integers(1, P.TEXEL_MAX),
                           st.sampled_from([1, 2, 4, 5, 50, 65535, 65536, P.TEXEL_MAX])),
    "length_samples": _pick(_uniform_int(1, LEN_CAP), _uniform_int(1, 64), st.sampled_from([1, 2, LEN_CAP])),
    "quant_db": _pick(st.sampled_from([0, 0.0]), _finite(P.QUANT_DB_MIN, P.QUANT_DB_MAX),
                      _int_in(1, P.QUANT_DB_MAX),
                      st.sampled_from([P.QUANT_DB_MIN, 0.0010000000000000002, 0.01, 10.0])),
    "seed": _pick(st.integers(0, P.SEED_MAX), st.sampled_from([0, 1, P.SEED_MAX])),
    "gain": _pick(_finite(0.0, 1.0), st.sampled_from([0, 1, 5e-324, 1e-300, 2.0 ** -15])),
    "v": st.just(1),
    "band_limit_cpmm": _pick(st.none(), _finite(0.01, NYQ), st.sampled_from([0.01, 1, 94, NYQ])),
}
assert sorted(VALID) == sorted(P.KEYS)
REQUIRED = ("pitch_db", "irregularity_db")


@st.composite
def valid_params(draw):
    p = {k: draw(VALID[k]) for k in REQUIRED}
    for k in P.KEYS:
        if k not in REQUIRED and draw(_uniform_int(0, 3)):       # each optional key 3 times in 4
            p[k] = draw(VALID[k])
    if "length_samples" not in p:
        p["length_samples"] = draw(VALID["length_samples"])    # the default 9600 is over LEN_CAP
    p["v"] = 1              # the property is format 1's float plan (no "v" is format 2: test_plan_int)
    if draw(_uniform_int(0, 4)) == 0:                           # one in 5: hundreds of short texels
        p["texel_samples"] = draw(_uniform_int(1, 10))
        p["length_samples"] = draw(_uniform_int(LEN_CAP // 2, LEN_CAP))
    return p


def _ex(**kw):
    d = {"pitch_db": P.PITCH_DB_MAX, "irregularity_db": P.IRREG_DB_MAX, "length_samples": LEN_CAP,
         "seed": P.SEED_MAX, "v": 1}
    d.update(kw)
    return d


# The extremes, explicitly: sigma 3.16 decades at both pitch bounds with
# one-sample texels (pitches of 10^-22 .. 10^22 c/mm), the coarsest and
# finest quantization grids, the band limit at both ends, gain 0 and a
# subnormal gain, one-sample maps, texels longer than the map, and maps and
# texels of LENGTH_MAX / TEXEL_MAX samples (one texel).
EXTREMES = [
    _ex(texel_samples=1),
    _ex(pitch_db=P.PITCH_DB_MIN, texel_samples=1),
    _ex(texel_samples=1, quant_db=P.QUANT_DB_MAX),
    _ex(texel_samples=1, quant_db=P.QUANT_DB_MIN),
    _ex(pitch_db=P.PITCH_DB_MIN, texel_samples=1, quant_db=P.QUANT_DB_MAX),
    _ex(texel_samples=3, band_limit_cpmm=0.01),
    _ex(texel_samples=1, band_limit_cpmm=NYQ, quant_db=P.QUANT_DB_MIN),
    _ex(irregularity_db=P.IRREG_DB_MIN, texel_samples=1, quant_db=P.QUANT_DB_MIN),
    _ex(pitch_db=P.PITCH_DB_MIN, irregularity_db=P.IRREG_DB_MIN, texel_samples=P.TEXEL_MAX),
    _ex(texel_samples=7, gain=0),
    _ex(texel_samples=7, gain=5e-324),
    _ex(texel_samples=1, length_samples=1),
    _ex(texel_samples=P.TEXEL_MAX, length_samples=1),
    _ex(texel_samples=5, length_samples=2, seed=0),
    _ex(texel_samples=P.TEXEL_MAX, length_samples=P.LENGTH_MAX),
]
# Longer ones (seconds each: test_longest_maps_build, slow): LENGTH_MAX
# samples in 65,535-sample texels, and LENGTH_MAX one-sample texels.
EXTREMES_SLOW = [
    _ex(pitch_db=6.3, irregularity_db=-12.9, texel_samples=65535, length_samples=P.LENGTH_MAX),
    _ex(texel_samples=1, length_samples=P.LENGTH_MAX, quant_db=P.QUANT_DB_MIN),
]


# --- the property -------------------------------------------------------------------------
def _as_np(buf):
    return np.asarray(buf, dtype=np.float64)


def check_plan(c, plan):
    n, L = c["length_samples"], c["texel_samples"]
    count = (n + L - 1) // L
    assert (plan.n, plan.L, plan.count) == (n, L, count)
    f = _as_np(plan.f)
    phi = _as_np(plan.phi)
    assert len(f) == len(phi) == len(plan.t28) == len(plan.d28) == count
    assert np.isfinite(f).all() and (f > 0).all(), "pitch not finite and > 0"
    assert np.isfinite(phi).all(), "start phase not finite"
    t28 = np.asarray(plan.t28, dtype=np.int64)
    d28 = np.asarray(plan.d28, dtype=np.int64)
    assert ((t28 >= 0) & (t28 < UNIT)).all() and ((d28 >= 0) & (d28 < UNIT)).all()
    assert np.isfinite(plan.pitches_db()).all()
    assert 0.0 <= plan.fraction_above_nyquist() <= 1.0
    assert plan.above_nyquist == int((f > NYQ).sum())
    cap = c["band_limit_cpmm"]
    if cap is not None:
        assert f.max() <= cap
    q = c["quant_db"] / 10.0
    if q > 0:
        free = f if cap is None else f[f < cap]
        k = np.log10(free) / q
        # on the grid: 10^(q*j) for an integer j (log10 and the division
        # add a few ulps of |log10 f| / q)
        assert (np.abs(k - np.round(k)) <= 1e-9 * (1 + np.abs(k))).all(), "pitch off the quant grid"
    return f


def check_render(c, plan, *, api=True):
    """Every engine's map for one plan: range and the documented bound."""
    n, gain = plan.n, plan.gain
    ref = engine_numpy.render(plan)
    assert ref.shape == (n,) and np.isfinite(ref).all()
    assert ref.min() >= 0.0 and ref.max() <= gain
    q_np = engine_numpy.render_u16(plan)
    assert q_np.dtype == np.uint16 and (q_np == np.floor(ref * 65535.0 + 0.5)).all()
    maps = {}
    for name, m in (("int", engine_int), ("pure", engine_pure)):
        q = m.render_u16(plan)
        assert len(q) == n
        qa = np.asarray(q, dtype=np.int64)
        assert qa.min() >= 0 and qa.max() <= 65535
        err = np.abs(qa / 65535.0 - ref)
        bound = pr.error_bound(plan, name, u16=True)
        bad = err > bound
        assert not bad.any(), "%s u16 off the reference by %r > bound %r at sample %d" % (
            name, err[bad][0], bound[bad][0], int(np.argmax(bad)))
        fm = _as_np(m.render(plan))
        assert len(fm) == n and np.isfinite(fm).all()
        assert fm.min() >= 0.0 and fm.max() <= min(1.0, gain + pr.OUTPUT_ERROR[name])
        assert (np.abs(fm - ref) <= pr.error_bound(plan, name)).all(), "%s float map off" % name
        maps[name] = qa
    if api:
        q = texel.render_u16(c, engine="int")
        assert (np.asarray(q, dtype=np.int64) == maps["int"]).all()
    if gain == 0.0:
        assert not maps["int"].any() and not maps["pure"].any() and not q_np.any()
    return maps


def check_params(p):
    before = copy.deepcopy(p)
    c = texel.validate(p)
    assert p == before and c is not p, "validate() changed its input"
    assert texel.validate(c) == c, "canonical form not idempotent"
    assert list(c) == list(P.KEYS)
    for k in P.KEYS:
        kind = P.SPEC[k][0]
        if c[k] is not None:
            assert type(c[k]) is (int if kind == "i" else float), k
    plan = texel.make_plan(p)
    check_plan(c, plan)
    check_render(c, plan)
    return c, plan


def test_every_valid_parameter_set_builds():
    seen = {"cases": 0, "sigma>=1 decade": 0, "quantized": 0, "band-limited": 0, "gain<1": 0,
            ">=100 texels": 0, "one-sample texels": 0, "texel > map": 0, "pitch > 1e6 c/mm": 0}

    @hyp_settings(N_PARAMS)
    @given(valid_params())
    def prop(p):
        note("params %r" % (p,))
        c, plan = check_params(p)
        seen["cases"] += 1
        seen["sigma>=1 decade"] += c["irregularity_db"] >= 0
        seen["quantized"] += c["quant_db"] > 0
        seen["band-limited"] += c["band_limit_cpmm"] is not None
        seen["gain<1"] += c["gain"] < 1
        seen[">=100 texels"] += plan.count >= 100
        seen["one-sample texels"] += plan.L == 1
        seen["texel > map"] += plan.L > plan.n
        seen["pitch > 1e6 c/mm"] += max(plan.f) > 1e6

    prop()
    print("\n", seen)
    assert seen["cases"] >= 0.9 * N_PARAMS * (NIGHTLY_SCALE if NIGHTLY else 1)
    assert min(seen.values()) >= 3, seen          # every corner visited


@pytest.mark.parametrize("p", EXTREMES, ids=range(len(EXTREMES)))
def test_extremes_build(p):
    c, plan = check_params(p)
    print("\n%r: %d texels, pitches %.3g .. %.3g c/mm" % (
        {k: v for k, v in p.items() if k != "seed"}, plan.count, min(plan.f), max(plan.f)))


@pytest.mark.slow
@pytest.mark.parametrize("p", EXTREMES_SLOW, ids=range(len(EXTREMES_SLOW)))
def test_longest_maps_build(p):
    """LENGTH_MAX-sample maps of 16 texels, and of 1,048,576 one-sample
    texels at sigma 3.16 decades (pitches 10^-22 .. 10^22 c/mm); plan and
    every engine, checked whole."""
    c, plan = check_params(p)
    assert plan.n == P.LENGTH_MAX
    print("\n%d texels, pitches %.3g .. %.3g c/mm, %.1f %% above Nyquist"
          % (plan.count, min(plan.f), max(plan.f), 100 * plan.fraction_above_nyquist()))


# --- any value at all: a ValueError, or a parameter set that builds ---------------------------
_huge = st.sampled_from([10 ** 400, -(10 ** 400), 2 ** 1024, 2 ** 62, -(2 ** 63), 2 ** 64 + 1])
_anything = st.one_of(
    st.integers(), _huge, st.floats(), st.floats(width=32), st.sampled_from([5e-324, -5e-324, 1e308]),
    st.none(), st.booleans(), st.text(max_size=20), st.binary(max_size=4), st.complex_numbers(),
    st.lists(st.integers(), max_size=3), st.dictionaries(st.text(max_size=3), st.integers(), max_size=2))
N_ANY = 150             # one key set to anything


@st.composite
def any_value_params(draw):
    p = draw(valid_params())
    key = draw(st.sampled_from(P.KEYS + ("bogus",)))
    p[key] = draw(_pick(_anything, VALID.get(key, st.integers())))
    return key, p


def test_any_value_is_refused_or_builds():
    """One key of a valid set replaced by anything (huge ints, every float,
    None, bools, strings, bytes, complex, containers): validate() raises
    ValueError naming that key, or the set builds as above - never another
    exception (a huge int in a float field raised OverflowError)."""
    seen = {"refused": 0, "built": 0}

    @hyp_settings(N_ANY)
    @given(any_value_params())
    def prop(case):
        key, p = case
        note("key %s, params %r" % (key, p))
        try:
            c = texel.validate(p)
        except ValueError as e:
            msg = str(e)
            assert msg.startswith(key + ":") or key == "bogus" and msg.startswith("unknown key"), msg
            assert "\n" not in msg and len(msg) < 300, msg
            seen["refused"] += 1
            return
        if c["length_samples"] <= LEN_CAP:
            check_params(p)
        seen["built"] += 1

    prop()
    print("\n", seen)
    assert min(seen.values()) >= 10


# --- replayed draws ----------------------------------------------------------------------
_z = st.one_of(st.floats(-PL.Z_MAX, PL.Z_MAX, allow_nan=False),
               st.sampled_from([PL.Z_MAX, -PL.Z_MAX, 0.0, -0.0, 5e-324, 6.4, -6.4]),
               st.integers(-10, 10))


@st.composite
def params_and_draws(draw):
    p = draw(valid_params())
    p["length_samples"] = min(draw(VALID["length_samples"]), 400)
    c = texel.validate(p)
    count = P.texel_count(c)
    u = draw(st.one_of(st.floats(0.0, 1.0), st.sampled_from([0, 1, 0.0, 1.0, 5e-324])))
    # up to 40 drawn values, repeated to the texel count (and 0..3 more: unused)
    pattern = draw(st.lists(_z, min_size=1, max_size=min(count, 40)))
    zs = [pattern[i % len(pattern)] for i in range(count + draw(st.integers(0, 3)))]
    return p, (u, zs if draw(st.booleans()) else tuple(zs))


@hyp_settings(N_DRAWS)
@given(params_and_draws())
@example((_ex(texel_samples=1, length_samples=300, quant_db=P.QUANT_DB_MAX), (1.0, [PL.Z_MAX] * 300)))
@example((_ex(pitch_db=P.PITCH_DB_MIN, texel_samples=1, length_samples=300, quant_db=P.QUANT_DB_MAX),
          (0.0, [-PL.Z_MAX] * 300)))
@example((_ex(texel_samples=2, length_samples=300), (0.5, [PL.Z_MAX, -PL.Z_MAX] * 75)))
def test_every_valid_draw_builds(case):
    p, draws = case
    note("params %r, u %r, z %r" % (p, draws[0], draws[1][:8]))
    c = texel.validate(p)
    plan = texel.make_plan(p, draws)
    f = check_plan(c, plan)
    assert f.max() < 10.0 ** 34.7 and f.min() > 10.0 ** -34.7      # within float32's normal range
    check_render(c, plan, api=False)
    q = texel.render_u16(p, draws, engine="int")
    assert (np.asarray(q) == np.asarray(engine_int.render_u16(plan))).all()


@st.composite
def any_draws(draw):
    p = draw(valid_params())
    p["length_samples"] = min(p["length_samples"], 300)
    count = P.texel_count(texel.validate(p))
    pattern = draw(st.lists(_pick(_z, st.floats(), _anything), min_size=1, max_size=4))
    zs = [pattern[i % len(pattern)] for i in range(count + draw(st.integers(-1, 2)))]
    u = draw(_pick(st.floats(0.0, 1.0), _anything))
    return p, draw(_pick(st.just((u, zs)), st.just((u, tuple(zs))), _anything,
                         st.tuples(_anything, _anything)))


def test_any_draws_are_refused_or_build():
    """Replayed draws of anything (z beyond +-10, every float, huge ints,
    None, complex, strings, containers; u likewise; draws not a pair): a
    ValueError starting "draws:", or a plan that builds as above (finite
    z = 100 raised OverflowError, z = -1e300 made a pitch of 0, complex
    and None raised TypeError)."""
    seen = {"refused": 0, "built": 0}

    @hyp_settings(N_DRAWS)
    @given(any_draws())
    def prop(case):
        p, draws = case
        note("params %r, draws %.300r" % (p, draws))
        try:
            plan = texel.make_plan(p, draws)
        except ValueError as e:
            assert str(e).startswith("draws: ") and len(str(e)) < 300, str(e)
            seen["refused"] += 1
            return
        check_plan(texel.validate(p), plan)
        check_render(texel.validate(p), plan, api=False)
        seen["built"] += 1

    prop()
    print("\n", seen)
    assert min(seen.values()) >= 5


# --- the same builds under MicroPython ------------------------------------------------------
MP_BUILD = r"""
import json, struct, binascii, texel
def dec(v):
    # floats travel as their IEEE-754 bits (the port's parser may misread a
    # 17-digit literal by one ulp)
    if isinstance(v, str):
        return struct.unpack("<d", binascii.unhexlify(v))[0]
    if isinstance(v, dict):
        return dict((k, dec(x)) for k, x in v.items())
    return v
def ck(xs):
    s = 0
    for x in xs:
        s = (s * 31 + x) %% 1000000007
    return s
for p in json.loads(%r):
    p = dec(p)
    try:
        pl = texel.make_plan(p)
        qi = texel.render_u16(p, engine="int")
        qp = texel.render_u16(p, engine="pure")
        print(json.dumps(["ok", pl.count, ck(pl.t28), ck(pl.d28), ck(qi), ck(qp), min(qi), max(qi),
                          min(qp), max(qp), pl.above_nyquist]))
    except Exception as e:
        print(json.dumps(["other", "%%s: %%s" %% (type(e).__name__, e)]))
"""


def _ck(xs):
    s = 0
    for x in xs:
        s = (s * 31 + int(x)) % 1000000007
    return s


def _mp_batch():
    batch = [dict(p, length_samples=min(p["length_samples"], 2000)) for p in EXTREMES + EXTREMES_SLOW]

    @hyp_settings(24, phases=[Phase.generate])
    @given(valid_params())
    def collect(p):
        batch.append(p)

    collect()
    return batch


def test_builds_match_under_micropython():
    """Plans and int/pure maps of the extremes and a generated batch: no
    exception under the unix port, and the same integers as CPython (both
    binary64: the plan is bit-identical, so t28/d28 and both maps are)."""
    batch = _mp_batch()
    enc = [{k: (struct.pack("<d", v).hex() if isinstance(v, float) else v) for k, v in p.items()}
           for p in batch]
    out = mpy.run(MP_BUILD % json.dumps(enc), timeout=600)
    got = [json.loads(line) for line in out.splitlines() if line.startswith("[")]
    assert len(got) == len(batch)
    for p, g in zip(batch, got):
        assert g[0] == "ok", (p, g)
        pl = texel.make_plan(p)
        qi = texel.render_u16(p, engine="int")
        qp = texel.render_u16(p, engine="pure")
        want = ["ok", pl.count, _ck(pl.t28), _ck(pl.d28), _ck(qi), _ck(qp), min(qi), max(qi),
                min(qp), max(qp), pl.above_nyquist]
        assert g == want, p
    print("\nMicroPython: %d parameter sets built, identical to CPython" % len(batch))


# --- regressions on the interpreters (the CPython ones: tests/gen/test_params.py) -----------
MP_REFUSALS = r"""
import texel
for p, draws in %s:
    try:
        texel.make_plan(p, draws)
        print("accepted")
    except ValueError as e:
        print(e)
    except Exception as e:
        print("OTHER %%s: %%s" %% (type(e).__name__, e))
"""


def test_refusals_match_under_micropython():
    """Huge ints in float fields (MicroPython called 10**400 "not finite",
    CPython raised OverflowError) and replayed draws out of range (z = 100:
    MicroPython raised OverflowError "can't convert inf to int"): the same
    ValueError, word for word, on the unix port as on CPython."""
    base = {"pitch_db": 6, "irregularity_db": 5, "length_samples": 100, "v": 1}
    cases = [(dict(base, **{k: v}), None) for k in ("pitch_db", "gain", "band_limit_cpmm")
             for v in (10 ** 400, -(2 ** 70))]
    cases += [(base, (0.5, [z] * 2)) for z in (100.0, -1e300, 12.0, 10 ** 400, -11, 9.5)]
    got = mpy.run(MP_REFUSALS % repr(cases)).splitlines()
    want = []
    for p, draws in cases:
        try:
            texel.make_plan(p, draws)
            want.append("accepted")
        except ValueError as e:
            want.append(str(e))
    assert got == want
    assert want[-1] == "accepted" and all(w != "accepted" for w in want[:-1])


def test_replayed_draws_at_the_bound_build_on_float32():
    """|z| = Z_MAX at the widest spread and coarsest grid (pitches 10^34 and
    10^-34 c/mm) plans and renders under the float32 MicroPython build (a
    board's precision): pitches finite and > 0, maps in range."""
    exe = mpy.toolchain.interpreter("micropython-ulab-f32")
    if exe is None:
        pytest.skip("micropython-ulab-f32 instrument not available")
    code = r"""
import texel
for pd, z in ((19.747, 10.0), (-20.0, -10.0), (19.747, -10.0), (-20.0, 10.0)):
    p = {"pitch_db": pd, "irregularity_db": 5.0, "quant_db": 20.0, "texel_samples": 3,
         "length_samples": 3000, "v": 1}
    pl = texel.make_plan(p, (1.0, [z] * 1000))
    q = texel.render_u16(p, (1.0, [z] * 1000), engine="int")
    f = pl.f[0]
    print(f >= 1.2e-38, f < 3e38, pl.d28[0] >= 0, min(q) >= 0, max(q) <= 65535)
"""
    out = mpy.run(code, exe=exe).split()
    assert out == ["True"] * 20, out

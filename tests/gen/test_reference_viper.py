"""gen/reference_viper.py: the sums of sines (2sin, 3sin, 4sin) as uint16 maps in machine-word
ints, a float32 board's fast path for reference_u16 (a stock Pico's power-up 4sin took 3.5 s
of board time by the float path; issue 30). Checked three ways:
- its constants follow from gen/reference.py's _SINES and _MINMAX;
- its arithmetic (a numpy twin, below) is within 1 u16 of the binary64 map at every sample of
  every length up to 200,000 (the clipped continuation of 3sin/4sin included);
- the viper code itself, on real interpreters (the unix port, 64-bit words, and the ulab
  float32 build, where reference_u16 takes this path), is that twin sample for sample.
Tolerance 1 u16 (1.5e-5 of the map; 0.06 of a PWM count at the Pico's 3,676): the float32
path's own (tests/runtime/test_circuitpython_runtime.py), from the sine table's Q16 rounding."""
from __future__ import annotations

import ast

import numpy as np
import pytest

import texel
from support import mpy
from texel.gen import reference as R
from texel.gen import sine_table

NAMES = ("2sin", "3sin", "4sin")
TURN = 100000


def _constants(name: str) -> tuple[int, int, int]:
    """(A0, WS, RQ) as the module's comment derives them: s = 2*A/(65535*16) - m."""
    m = len(R._SINES[name])
    sc = 2.0 / (65535 * 16)
    if name == "2sin":
        a, b = 0.3 * sc, 0.5 - 0.3 * m
    else:
        lo, hi = R._MINMAX[name]
        inv = 1.0 / (hi - lo)
        a, b = sc * inv, (-m - lo) * inv
    ws = int(np.floor(65536.0 / (65535 * a) + 0.5))
    return int(np.floor(-b / a + 0.5)), ws, 2 ** 36 // ws


def _twin(name: str, n: int) -> np.ndarray:
    """reference_viper.fill's arithmetic in numpy int64, exact (where fill's 32-bit words wrap,
    in x*2^16 and u*ws, their difference e is exact all the same)."""
    tab = np.frombuffer(bytes(sine_table.table()), dtype="<u2").astype(np.int64)
    i = np.arange(n, dtype=np.int64)
    a = np.zeros(n, dtype=np.int64)
    for step in R._SINES[name]:
        y = ((i * step) % TURN) * 1024
        k = y // TURN
        r = y - k * TURN
        y0 = tab[k]
        a += (y0 << 4) + (((tab[k + 1] - y0) * ((r * 21475) >> 19)) >> 8)
    a0, ws, rq = _constants(name)
    x = a - a0
    xc = np.clip(x, 0, ws - 1)
    u = ((xc >> 6) * rq) >> 14                  # the estimate, then exact by the remainder
    e = (xc << 16) - u * ws
    assert ((e >= 0) & (e < 8 * ws)).all()       # the estimate is low by < 8: few steps
    u = u + (e + ws - (ws >> 1)) // ws           # fill's loop: e ends in [ws//2 - ws, ws//2)
    return np.where(x <= 0, 0, np.where(x >= ws, 65535, np.minimum(u, 65535)))


def test_the_constants_follow_from_the_float_path():
    # read, not imported: the module imports micropython
    tree = ast.parse((mpy.DEVICE / "texel" / "gen" / "reference_viper.py").read_text())
    lit = next(node.value for node in tree.body if isinstance(node, ast.Assign)
               and getattr(node.targets[0], "id", None) == "CONSTANTS")
    assert ast.literal_eval(lit) == {name: _constants(name) for name in NAMES}


@pytest.mark.parametrize("name", NAMES)
def test_the_integer_arithmetic_is_within_one_u16_of_binary64_everywhere(name):
    n = 200000                                  # 3sin/4sin clip beyond the half screen
    want = np.asarray(texel.reference_u16(name, n), dtype=np.int64)
    got = _twin(name, n)
    d = np.abs(got - want)
    assert d.max() <= 1, (name, int(d.max()), int(np.argmax(d)))
    print("%s: %d of %d samples off by 1 u16" % (name, int((d > 0).sum()), n))


CODE = """
import json
from array import array
from binascii import hexlify
from texel.gen import reference, reference_viper, sine_table
from texel import compat
out = {"int_path": bool(reference._int_sines()), "maps": {}}
for name, n in %r:
    steps = reference._SINES[name]
    buf = array('H', bytes(2 * n))
    a0, ws, rq = reference_viper.CONSTANTS[name]
    reference_viper.fill(buf, n, array('i', reference_viper.steps_of(steps)),
                         array('i', bytes(8 * len(steps))), len(steps), sine_table.table(), a0, ws,
                         rq)
    via = reference.reference_u16(name, n)
    out["maps"][name + str(n)] = [hexlify(buf).decode(), via == buf]
print(json.dumps(out))
"""

CASES = [("4sin", 9600), ("2sin", 19200), ("3sin", 1), ("4sin", 40000)]


@pytest.mark.parametrize("exe", ["micropython", "micropython-ulab-f32"])
def test_the_viper_code_is_the_twin_on_real_interpreters(exe):
    from texelpad import toolchain
    path = toolchain.interpreter(exe)
    if path is None:
        pytest.skip("no %s here (../shared/instruments)" % exe)
    got = mpy.run_json(CODE % (CASES,), exe=path, timeout=300)
    # reference_u16 takes the integer path on float32 only (binary64 keeps the CSV's floats)
    assert got["int_path"] is (exe == "micropython-ulab-f32")
    for name, n in CASES:
        vals, via_u16 = got["maps"][name + str(n)]
        got_map = np.frombuffer(bytes.fromhex(vals), dtype="<u2")
        assert (got_map == _twin(name, n)).all(), (exe, name, n)
        if exe == "micropython-ulab-f32":       # reference_u16 renders by it
            assert via_u16, (exe, name, n)


@pytest.mark.parametrize("name", NAMES)
def test_the_c_loop_is_the_twin(name):
    """texel_core.c tc_sines (the C core's sines: the stock Pico's native module renders
    2sin/3sin/4sin by it), its CPython build: the twin's integers at every sample of
    200,000 (the clipped continuation of 3sin/4sin included), in one call and in 7 (the
    phases carried as between a board's chunks)."""
    from support import core_c
    if not core_c.available():
        pytest.skip("no gcc here")
    n = 200000
    want = _twin(name, n)
    steps, consts = R._SINES[name], _constants(name)
    assert (np.asarray(core_c.sines(steps, consts, n), dtype=np.int64) == want).all()
    assert core_c.sines(steps, consts, 40000, parts=7) == want[:40000].tolist()


MIRROR = r"""
import json
from array import array
from binascii import hexlify
import texel
from texel.gen import reference as R
out = {"copy16": bool(R._copy16()), "maps": {}}
for name, n, size in %r:
    if size:                                    # a board's chunks: 1 KB arrays, or slab views
        if size < 0:
            slab = memoryview(array("H", bytes(2 * n)))
            chunks = tuple(slab[a:a + -size] for a in range(0, n, -size))
        else:
            chunks = tuple(array("H", bytes(2 * min(size, n - a))) for a in range(0, n, size))
        texel.reference_u16(name, n, chunks)
        buf = b"".join(bytes(c) for c in chunks)
    else:
        buf = bytes(texel.reference_u16(name, n))
    out["maps"]["%%s %%d %%d" %% (name, n, size)] = hexlify(buf).decode()
print(json.dumps(out))
"""

# (row, length, chunk size: 0 one buffer, < 0 memoryviews of one slab): just past the half
# screen, the full screen, the mirror's period (19198) and its edges, a second period's
# reversed run, and chunk sizes that do not divide the half screen
MIRROR_CASES = [("pink", 9601, 512), ("white", 19200, 512), ("blue", 19200, 0),
                ("pink", 19198, 0), ("white", 19199, 512), ("blue", 28800, 512),
                ("pink", 38397, 700), ("white", 40000, -512), ("blue", 19200, 1)]


@pytest.mark.parametrize("exe", ["micropython", "micropython-ulab-f32"])
def test_a_noise_row_mirrored_by_viper_is_the_python_map(exe):
    """gen/reference.py _mirror: a noise row longer than the half screen repeats it
    mirrored; with viper (reference_viper.copy16, run by run, chunk by chunk) the maps are
    CPython's (the per-sample loop) value for value, in one buffer, 1 KB chunks, other
    chunk sizes and a slab's memoryviews."""
    from texelpad import toolchain
    path = toolchain.interpreter(exe)
    if path is None:
        pytest.skip("no %s here (../shared/instruments)" % exe)
    got = mpy.run_json(MIRROR % (MIRROR_CASES,), exe=path, timeout=300, heapsize="8m")
    assert got["copy16"] is True
    for name, n, size in MIRROR_CASES:
        want = np.asarray(texel.reference_u16(name, n), dtype="<u2")
        have = np.frombuffer(bytes.fromhex(got["maps"]["%s %d %d" % (name, n, size)]),
                             dtype="<u2")
        assert (have == want).all(), (exe, name, n, size, np.flatnonzero(have != want)[:5])

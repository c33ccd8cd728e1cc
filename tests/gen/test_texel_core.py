"""The C core (device/cmod/texelcore) in its three builds gives the Python
loops' integers, bit for bit:

- CPython through ctypes (tests/support/core_c.py): format 2's per-texel
  plan (texel_core.c tc_texels against plan_int.texels_py: t28, d28, the log
  pitches, the draws, the texels above Nyquist, the start phase's draw) and
  the int engine (tc_fill, tc_render against engine_int._fill_py) on the hard
  cases and random parameter sets on format 2's grid;
- the dynamic native module for x64 (texelpad.firmware.natmod, MicroPython's
  dynruntime.mk) on the MicroPython unix port: texel.compat.core() finds it,
  plan_int and engine_int run it, and its plan and map are CPython's; the
  viper and Python loops on the same interpreter agree; the brush painter
  through it paints what viper paints; its u16 makes compat's zeroed
  buffers; bad arguments are a ValueError;
- the armv6m module on the emulated stock Pico after `texelpad deploy` and
  the firmware's user C module: tests/host/test_emulated_pico.py and
  tests/firmware/test_firmware_pico.py.
"""
from __future__ import annotations

import os
import random
import shutil
from array import array

import pytest

import texel
from texel.gen import engine_int, plan_int as P, sine_table
from texel.gen.plan_int_tables import table
from texelpad import toolchain
from texelpad.firmware import natmod

from support import core_c, mpy

from texelpad.analysis.hard_cases import HARD_CASES

pytestmark = pytest.mark.skipif(not core_c.available(), reason="no gcc for the C core's build")
IN_CI = bool(os.environ.get("CI"))


def _random_sets(n: int, seed: int) -> list[dict]:
    """Format-2 parameter sets drawn over the whole range, on the grid:
    every option of the per-texel loop (quantization, band limit, texel
    lengths from 1 sample up)."""
    r = random.Random(seed)
    out = []
    for i in range(n):
        p = {"pitch_db": round(r.uniform(-20.0, 19.747), 3),
             "irregularity_db": round(r.uniform(-30.0, 5.0), 3),
             "texel_samples": r.choice((1, 2, 3, 7, 50, 333, 4096)),
             "length_samples": r.choice((1, 97, 1000, 19200)),
             "seed": r.randrange(1 << 32), "v": 2}
        if i % 3 == 0:
            p["quant_db"] = round(r.uniform(0.001, 20.0), 3)
        if i % 4 == 1:
            p["band_limit_cpmm"] = round(r.uniform(0.1, 94.339), 3)
        out.append(p)
    return out


def v2(case: str, **kw) -> dict:
    return dict(HARD_CASES[case][0], v=2, **kw)


# the hard cases of tests/gen/test_plan_int.py's runtimes, and random sets
HARD = {
    "study": v2("study"), "pitch-nyquist": v2("pitch-nyquist"), "irreg-max": v2("irreg-max"),
    "white-like": v2("white-like"), "quant-coarse": v2("quant-coarse"),
    "texel-1": v2("texel-1", length_samples=3000), "texel-long": v2("texel-long"),
    "seed-max": v2("seed-max"), "ragged": v2("ragged"),
    "capped": {"pitch_db": 19.747, "irregularity_db": 0.0, "texel_samples": 7,
               "length_samples": 9600, "seed": 0, "band_limit_cpmm": 50.0, "v": 2},
    "huge-texel": {"pitch_db": 10.123, "irregularity_db": -30.0, "texel_samples": 1048576,
                   "length_samples": 100000, "seed": 99, "quant_db": 20.0, "v": 2},
}
CASES = dict(HARD, **{"random-%d" % i: p for i, p in enumerate(_random_sets(60, 8))})


def _c_plan(pl: P.PlanInt, keep: int) -> tuple:
    """tc_texels on the plan's own inputs, with fresh outputs."""
    c = pl.count
    st = P.seeded(pl.params["seed"])
    t28, d28, ys, zs = (array("i", bytes(4 * max(c, 1))) for _ in range(4))
    above = core_c.texels(st, c, pl.L, pl.mu, pl.sigma, pl.q, pl.dcap, array("i", table()),
                          t28, d28, ys, zs, keep)
    return above, st, t28[:c], d28[:c], ys[:c], zs[:c]


@pytest.mark.parametrize("name", sorted(CASES))
def test_c_plan_is_the_python_loop_bit_for_bit(name):
    p = texel.validate(CASES[name])
    want = P.PlanInt(p, keep_z=True, engine="py")
    above, st, t28, d28, ys, zs = _c_plan(want, 3)
    assert above == want.above_nyquist
    assert (st[8], st[9]) == want.x0
    assert list(t28) == list(want.t28) and list(d28) == list(want.d28)
    assert list(ys) == list(want.y) and list(zs) == list(want.z)
    # keep = 0: nothing written where the caller keeps nothing
    above0, _, t0, d0, ys0, zs0 = _c_plan(want, 0)
    assert (above0, list(t0), list(d0)) == (above, list(t28), list(d28))
    assert not any(ys0) and not any(zs0)


def test_c_plan_on_the_loops_hard_edges():
    """Draws at the inverse normal's ends (irregularity at its maximum: sigma*z
    beyond 64 octaves), y clamped at both ends, steps above a turn per
    sample, quantization of negative and positive log pitches, and a band
    limit below every texel's pitch."""
    sets = [{"pitch_db": pd, "irregularity_db": 5.0, "texel_samples": 1, "length_samples": 4000,
             "seed": s, "v": 2, **extra}
            for pd in (-20.0, 0.0, 19.747) for s in (0, 1, 4294967295)
            for extra in ({}, {"quant_db": 0.001}, {"quant_db": 20.0}, {"band_limit_cpmm": 0.1})]
    for p in sets:
        want = P.PlanInt(texel.validate(p), keep_z=True, engine="py")
        above, st, t28, d28, ys, zs = _c_plan(want, 3)
        assert (above, list(t28), list(d28), list(ys), list(zs)) == (
            want.above_nyquist, list(want.t28), list(want.d28), list(want.y), list(want.z)), p


def test_c_fill_and_render_are_the_int_engine_bit_for_bit():
    tab = array("H", sine_table.table())
    r = random.Random(5)
    for _ in range(400):
        n = r.choice((0, 1, 5, 512))
        t, d = r.randrange(1 << 28), r.choice((0, 1, (1 << 28) - 1, r.randrange(1 << 28)))
        g = r.choice((0, 1, 8192, 16384))
        a = array("H", bytes(2 * n))
        b = array("H", bytes(2 * n))
        assert core_c.fill(a, 0, n, t, d, tab, g) == engine_int._fill_py(b, 0, n, t, d, tab, g)
        assert a == b
    for name in ("study", "texel-1", "ragged", "huge-texel", "random-3", "random-7"):
        p = texel.validate(CASES[name])
        pl = P.PlanInt(p, engine="py")
        want = engine_int.render_u16(pl)
        out = array("H", bytes(2 * pl.n))
        core_c.render(out, pl.n, pl.L, pl.count, array("i", pl.t28), array("i", pl.d28), tab,
                      engine_int.gain_q14(pl.gain))
        assert list(out) == list(want), name


def test_c_samples_fill_is_the_python_loop_bit_for_bit():
    """kinds/samples.py's map of a tiled or stretched region (its Python
    loop, one flat buffer) and the C core's into chunks (tc_samples): the
    same values on the hard cases - one value, one position, regions not a
    multiple of 512, a shrink, a stretch past 32,769 positions (int64 there,
    Python's two exact steps) and random ramps of every sign."""
    from texel.runtime.kinds import samples as KS
    r = random.Random(11)
    cases = [([7], "stretch", 1), ([7], "tile", 600), ([0, 65535], "stretch", 19200),
             ([65535, 0], "stretch", 40001), ([1, 2, 3], "tile", 1025), ([5, 9], "stretch", 2),
             ([r.randrange(65536) for _ in range(600)], "stretch", 1),
             ([r.randrange(65536) for _ in range(19200)], "stretch", 9600),
             ([r.randrange(65536) for _ in range(513)], "stretch", 65536),
             ([r.randrange(65536) for _ in range(700)], "tile", 9601)]
    cases += [([r.randrange(65536) for _ in range(r.randrange(1, 300))], r.choice(KS.FITS),
               r.randrange(1, 5000)) for _ in range(60)]
    for vals, fit, n in cases:
        want = array("H", bytes(2 * n))
        KS._loop(tuple(vals), 0, len(vals), fit, n, want, 0, n)
        assert core_c.samples(vals, fit, n) == list(want), (len(vals), fit, n)


def _options_cases():
    from texel.gen import lognormal
    r = random.Random(17)
    wide, narrow = ([round(x, 2) for x in lognormal.to_db(4.0, sd)] for sd in (4.3, 1.2))
    out = [  # seed 001's conditions, the mapping trial's start, a hopeless mean, the tries cap
        {"pitch_db": wide[0], "irregularity_db": wide[1], "texel_samples": 236,
         "length_samples": 18868, "seed": 5, "min_cpmm": 1.0},
        {"pitch_db": narrow[0], "irregularity_db": narrow[1], "texel_samples": 236,
         "length_samples": 18868, "seed": 5, "min_cpmm": 1.0, "phase": "reset"},
        {"pitch_db": 2.515, "irregularity_db": -1.922, "texel_samples": 189, "min_cpmm": 1.0,
         "phase": "reset", "seed": 173254587, "length_samples": 9600},
        {"pitch_db": -15.0, "irregularity_db": -20.0, "texel_samples": 20, "min_cpmm": 1.0,
         "seed": 2, "length_samples": 4000},
        {"pitch_db": -3.0, "irregularity_db": 0.0, "texel_samples": 7, "min_cpmm": 2.0,
         "seed": 4294967295, "quant_db": 0.5, "length_samples": 3000,
         "band_limit_cpmm": 40.0}]
    for _ in range(25):
        out.append({"pitch_db": round(r.uniform(-8, 12), 2),
                    "irregularity_db": round(r.uniform(-20, 4), 2),
                    "texel_samples": r.choice((1, 3, 17, 236)), "seed": r.randrange(2 ** 32),
                    "min_cpmm": r.choice((0.5, 1.0, 3.0)), "length_samples": 2000,
                    "phase": r.choice(("reset", "continuous"))})
    return out


@pytest.mark.parametrize("hopeless", [True, False])
def test_c_options_are_the_python_post_pass_bit_for_bit(hopeless, monkeypatch):
    """Seed 001's options on a format-2 plan (gen/options.py apply_int: the
    bound's redraws from the second stream, the tail recomputed, the phase
    reset) by the C core (tc_options) against the Python post-pass: the same
    log pitches, t28, d28 and counts - with and without the hopeless skip."""
    from texel.gen import options
    monkeypatch.setattr(options, "SKIP_HOPELESS", hopeless)
    tab = table()
    seen = [0, 0, 0]                        # redrawn, at the bound, above Nyquist: each met
    for p in _options_cases():
        c = texel.validate(dict(p, v=2))
        want = P.PlanInt(c, engine="py")
        bare = dict(c)
        bare.pop("min_cpmm", None)
        bare.pop("phase", None)
        pl = P.PlanInt(texel.validate(bare), engine="py")
        pl.params = c
        ys = array("i", pl.y)
        dmin = options.d_min(want.min_mc)
        hl = options.SKIP_HOPELESS and options._below(options.log_pitch(
            P.norm_q24(0xFFFF, 0xFFFF, tab), pl.mu, pl.sigma, pl.q), dmin, tab)
        flags = 1 | (2 if hl else 0) | (4 if c.get("phase") == "reset" else 0)
        got = core_c.options(pl, ys, dmin, flags, options.MIN_TRIES)
        assert got == (want.redrawn, want.at_min, want.above_nyquist), p
        assert (list(ys), list(pl.t28), list(pl.d28)) == (
            list(want.y), list(want.t28), list(want.d28)), p
        seen = [a + (b > 0) for a, b in zip(seen, got)]
    assert min(seen) >= 2, seen


def test_c_plan_with_options_is_planint_bit_for_bit():
    """The C plan's options (texelcore_api.h plan -> tc_plan_options: the redraw
    stream, d_min, the hopeless test and the tries set up in C, where the
    Python sets them up in gen/options.py _apply_c) against PlanInt with its
    Python post-pass: the same t28, d28 and counts; the phase reset alone
    too. MIN_TRIES is the header's: a texel out of tries plays at the bound
    on both sides only if both try as often."""
    from texel.gen import options
    assert "#define TC_MIN_TRIES %d " % options.MIN_TRIES in (
        core_c.CORE / "texel_core.h").read_text()
    seen = [0, 0, 0]
    for p in _options_cases() + [{"pitch_db": 3.0, "irregularity_db": -8.0, "texel_samples": 50,
                                  "seed": 9, "length_samples": 5000, "phase": "reset"},
                                 {"pitch_db": 3.0, "irregularity_db": -8.0, "texel_samples": 50,
                                  "seed": 9, "length_samples": 5000, "min_cpmm": None,
                                  "phase": "continuous"}]:
        c = texel.validate(dict(p, v=2))
        want = P.PlanInt(c, engine="py")
        t28, d28, got = core_c.plan_with_options(c)
        assert (t28, d28) == (list(want.t28), list(want.d28)), p
        assert got == (want.redrawn, want.at_min, want.above_nyquist), p
        seen = [a + (b > 0) for a, b in zip(seen, got)]
    assert min(seen) >= 2, seen


# --- the native module on the unix port -------------------------------------------------

@pytest.fixture(scope="module")
def x64_module(tmp_path_factory):
    """A folder holding _texelcore.mpy for x64, built from this checkout."""
    lack = natmod.missing("x64")
    if lack:
        if IN_CI:
            pytest.fail("CI cannot build the native module: no " + "; no ".join(lack))
        pytest.skip("cannot build the native module here: no " + "; no ".join(lack))
    d = tmp_path_factory.mktemp("natmod")
    f = natmod.build("x64", d)
    shutil.copyfile(f, d / "_texelcore.mpy")
    return d


# the end of the native-module scripts below: each of their CALLS made, and what it raised
# (a refusal is a ValueError with its words; None: it was not refused)
_REFUSALS = r"""
for call in CALLS:
    try:
        eval(call)
        info["errors"].append((call, None))
    except ValueError as e:
        info["errors"].append((call, str(e)))
print(json.dumps(info))
"""


NATIVE_SCRIPT = r"""
import json
import texel
from texel import compat
from texel.gen import plan_int as P, engine_int as E, brush as B
out = %(out)r
cases = %(cases)r
c = compat.core()
info = {"core": c is not None and c.BUILD, "plan": P.ENGINE, "engine": E.ENGINE,
        "same": {}, "errors": []}
def save(path, buf):
    f = open(path, "wb")
    f.write(buf)
    f.close()
for name in sorted(cases):
    p = cases[name]
    pl = P.PlanInt(texel.validate(p))
    save(out + "/" + name + ".plan", bytes(pl.t28) + bytes(pl.d28) + bytes(pl.y))
    save(out + "/" + name + ".map", bytes(texel.render_u16(p, engine="int")))
    same = True
    for e in ("viper", "py"):
        q = P.PlanInt(texel.validate(p), engine=e)
        same = same and bytes(q.t28) == bytes(pl.t28) and bytes(q.d28) == bytes(pl.d28) \
            and bytes(q.y) == bytes(pl.y)
    info["same"][name] = same
br = B.validate(%(brush)r)
info["brush_same"] = list(B.paint(br, 3, 3000, how="c")) == list(B.paint(br, 3, 3000, how="viper"))
from array import array
from texel.runtime import refresh_fast as RF
z = [array("I", [1, 2, 0xFFFFFFFF]), array("i", range(-70, 70)), array("H", [7] * 5)]
for a in z:
    RF._zero(a)                 # refresh_fast's dropped generation: the C core's memset
info["zero"] = [RF._ZEROS[1] is c.zero] + [list(a) for a in z]   # _zero calls it directly
u = c.u16(19200)
u[19199] = 65535
info["u16"] = [isinstance(u, array), len(u), sum(u), len(bytes(u)), len(c.u16(0)),
               type(compat.u16_one_block(7)) is array, list(compat.u16_buffer(3))]
from texel.runtime.kinds import samples as KS
from texel.runtime.upload import Chunks
info["samples"] = []
for vals, fit, n in ((tuple(range(0, 65536, 97)), "stretch", 19200), ((1, 2, 3), "tile", 1000),
                     ((0, 65535), "stretch", 40000)):
    d = Chunks(n)
    KS.fill_chunks(vals, fit, n, d.chunks)
    info["samples"].append(bytes(b"".join(bytes(x) for x in d.chunks)).hex())
tab = E.sine_table.table()
CALLS = ("c.fill(bytearray(4), 0, 10, 0, 0, tab, 1)",
             "c.fill(bytearray(40), 0, 10, 0, 0, bytearray(8), 1)",
             "c.texels(P.seeded(1), 50, 1, 0, 0, 0, 0, P.table(), array('i', [0]), array('i', [0] * 50), array('i', [0]), array('i', [0]), 0)",
             "c.texels(P.seeded(1), 5, 0, 0, 0, 0, 0, P.table(), array('i', [0] * 5), array('i', [0] * 5), array('i', [0]), array('i', [0]), 0)",
             "c.render(array('H', [0] * 10), 20, 4, 5, array('i', [0] * 5), array('i', [0] * 5), tab, 1)",
             "c.u16(-1)", "c.u16(1048577)",
             "c.samples((array('H', [0] * 512),), 9, 600, array('H', [1, 2]), 2, 1)",
             "c.samples((array('H', [0] * 512),), 9, 500, array('H', [1]), 2, 1)",
             "c.samples((bytearray(10),), 9, 500, array('H', [1]), 1, 0)")
""" + _REFUSALS

_BRUSH = {"k": [8.0] + [1.5 + 0.1 * (i % 20) for i in range(96)],
          "lam": [0.5] + [0.05 / (1 + 0.04 * i) for i in range(96)], "range": [0.0, 1.0]}


def test_native_module_on_the_unix_port_is_cpythons_plan_and_map(x64_module, tmp_path):
    cases = {k: CASES[k] for k in sorted(CASES) if not k.startswith("random-")
             or int(k.split("-")[1]) < 20}
    for k, p in enumerate(_options_cases()[:6]):     # seed 001's options: tc_options
        cases["options-%d" % k] = dict(p, v=2)
    code = NATIVE_SCRIPT % {"out": str(tmp_path), "cases": cases, "brush": _BRUSH}
    info = mpy.run_json(code, exe=toolchain.require_micropython(), heapsize="8M", timeout=300,
                        extra_path=str(x64_module))
    assert info["zero"] == [True, [0, 0, 0], [0] * 140, [0] * 5], info["zero"]
    assert info["core"] == "native" and info["plan"] == "c" and info["engine"] == "c"
    for name, p in cases.items():
        pl = P.PlanInt(texel.validate(p))
        assert (tmp_path / (name + ".plan")).read_bytes() == (
            bytes(pl.t28) + bytes(pl.d28) + bytes(pl.y)), name
        assert (tmp_path / (name + ".map")).read_bytes() == bytes(
            array("H", texel.render_u16(p, engine="int"))), name
    assert all(info["same"].values()), info["same"]
    assert info["brush_same"] is True
    # u16: a zeroed array('H') in one block (compat's buffers take it)
    assert info["u16"] == [True, 19200, 65535, 38400, 0, True, [0, 0, 0]]
    # samples regions (kinds/samples.py fill_chunks by the C core): CPython's Python loop
    from texel.runtime.kinds import samples as KS
    for (vals, fit, n), got in zip(((tuple(range(0, 65536, 97)), "stretch", 19200),
                                    ((1, 2, 3), "tile", 1000), ((0, 65535), "stretch", 40000)),
                                   info["samples"]):
        want = array("H", bytes(2 * n))
        KS._loop(vals, 0, len(vals), fit, n, want, 0, n)
        assert bytes.fromhex(got) == bytes(want), (fit, n)
    for call, err in info["errors"]:
        assert err is not None, "accepted: " + call
        assert "_texelcore" in err or "out" in err or "range" in err or "disagree" in err, err


# The refresh in C (refresh_core.c) against refresh_viper.core on the same word array W,
# refresh by refresh: every state word, the CC word and the telemetry ring. A scene with
# every region kind (constant, a map, a texel plan, an upload's chunks, a gap), the finger
# sweeping, jumping, dropping out for fewer and for more refreshes than the lift debounce,
# resting on the ends and beyond them; a telemetry sample every refresh.
REFRESH_SCRIPT = r"""
import json, random
from array import array
import texel.app as app
from texel import compat
from texel.runtime import refresh_viper as RV
c = compat.core()
# a map in flash (K_BUF: the firmware's ROMFS references, gen/reference.py flash_u16)
# stood in for by one RAM block: elsewhere a reference plays from RAM chunks (K_CHUNK)
from texel.runtime.kinds import reference as KR
import texel
_maps = {}
def _flash(name, n):
    if (name, n) not in _maps:
        _maps[(name, n)] = texel.reference_u16(name, n)
    return _maps[(name, n)]
KR.flash = _flash
app.start("virtual", %(scene)r)
r = app._rt.refresh
app.stream(8333)
S = r._S
STM = %(stm)r
adc = array("I", [0] * 20)      # an STM32's ADC1 registers: CR2 word 2, DR word 19
if STM:
    import uctypes
    r.use_stm32_registers(uctypes.addressof(r._clk), uctypes.addressof(adc),
                          uctypes.addressof(r._cc))
rings = (S, r.tel_t, r.tel_pos, r.tel_amp)
def snap():
    return [list(a) for a in rings] + [r._cc[0], adc[2]]
def put(v):
    for a, b in zip(rings, v):
        for i in range(len(b)):
            a[i] = b[i]
random.seed(7)
raws = []
x = 30000
if %(edges)r:
    # the finger at every region's edges: a slow sweep (a raw step of 2, under a
    # position) across each start and end, both ways, so that p meets each one
    # exactly; between them a jump to the next edge or a random one (across many
    # rows, both ways); now and then a dropout (the position dead-reckoned, the lift)
    def raw_at(pos):                    # the raw reading that rests at position pos
        d = (pos * 256) * 16384 // (S[16] * 16384 + S[17])
        return max(0, min(65535, S[14] - d if S[13] else S[14] + d))
    edges = []
    for i in range(r.scene.count):
        edges += [r.scene._t[4 * i], r.scene._t[4 * i + 1]]
    order = edges + [random.choice(edges) for _ in range(24)]
    for e in order:
        at = raw_at(e)
        raws += [max(0, at - 24)] * 30      # settle there after the jump
        for dx in list(range(-24, 25, 2)) + list(range(24, -25, -2)):
            raws.append(max(0, min(65535, at + dx)))
        if random.randrange(8) == 0:
            raws += [random.randrange(0, 300)] * random.choice((1, 2, 6))
for k in range(%(n)d):
    m = k %% 400
    if m < 150:
        x = 2000 + (k * 97) %% 61000          # sweeping
    elif m < 160:
        x = random.randrange(0, 300)          # a dropout (below the lift level)
    elif m < 170:
        x = random.choice((0, 65535, 1999, 63001))
    elif m < 200:
        x = random.randrange(65536)           # jumps
    else:
        x = max(0, min(65535, x + random.randrange(-900, 901)))
    raws.append(x)
same = 0
first = None
cr2s = {}
seen = {}
for k in range(len(raws)):
    r._clk[0] = (k * 120 + 5) & 0x3FFFFFFF
    r._adc[1] = raws[k]
    adc[19] = (raws[k] >> 4) | (0xABC000 if k & 1 else 0)   # DR: 12 bits (and junk above)
    adc[2] = k & 0x400                                       # CR2 before: EOCS or not
    before = snap()
    RV.core(RV._WA)
    a = snap()
    put(before)
    r._cc[0] = before[4]
    adc[2] = before[5]
    c.refresh(RV._W)
    cr2s[adc[2]] = 1
    b = snap()
    seen[S[20] - 1] = 1
    if a == b:
        same += 1
    elif first is None:
        first = (k, raws[k], [i for i in range(len(a[0])) if a[0][i] != b[0][i]])
t = r.scene._t
rows = [(t[4 * i], t[4 * i + 1]) for i in range(r.scene.count)]
print(json.dumps({"same": same, "n": len(raws), "first": first, "code": c.BUILD,
                  "cr2": sorted(cr2s), "rows": rows, "seen": sorted(seen),
                  "kinds": sorted(set(r.scene._t[4 * i + 2] for i in range(r.scene.count)))}))
"""


def test_the_c_refresh_is_the_viper_refresh_word_for_word(x64_module):
    """Issue 32 item 3: the refresh in C (on the firmware it is the RP2040's
    refresh interrupt) computes what refresh_viper.core computes, on the x64
    native module under the MicroPython unix port."""
    from texelpad.bench.link import regions16
    scene = {"regions": [
        {"start_mm": 0, "end_mm": 20, "texture": {"kind": "constant", "level": 0.3}},
        {"start_mm": 20, "end_mm": 40, "texture": {"kind": "reference", "name": "4sin"}},
        {"start_mm": 40, "end_mm": 60, "texture": {"kind": "texel", "pitch_db": 6.3,
                                                   "irregularity_db": -12.9, "seed": 7, "v": 2}},
        {"start_mm": 60, "end_mm": 70, "texture": {"kind": "samples", "fit": "stretch",
                                                   "u16": [0, 65535, 100]}},
        {"start_mm": 70, "end_mm": 80, "texture": {"kind": "samples", "fit": "tile",
                                                   "u16": [5, 60000, 300, 12345, 65535]}},
        {"start_mm": 85, "end_mm": 101.76, "texture": {"kind": "bump", "width_mm": 8}}]}
    for stm in (False, True):
        # stm: the STM32 path (S_ADC_CS bit 4: DR read, CR2 |= ADON | SWSTART) on a stand-in
        # register block (hw/stm32_irq.py; the real one runs on the emulated F405)
        code = REFRESH_SCRIPT % {"scene": scene, "n": 6000, "stm": stm, "edges": False}
        info = mpy.run_json(code, exe=toolchain.require_micropython(), heapsize="8M",
                            timeout=300, extra_path=str(x64_module))
        # every way a region plays: K_CONST, K_BUF, K_PLAN, K_CHUNK, K_TILE, K_STRETCH
        # (runtime/kinds/__init__.py)
        assert info["code"] == "native" and info["kinds"] == [0, 1, 2, 3, 4, 5], info
        assert info["same"] == info["n"], (stm, info)
        if stm:
            assert info["cr2"] == [0x40000001, 0x40000401], info
    # 16 texel regions: the table walk past many rows
    info = mpy.run_json(REFRESH_SCRIPT % {"scene": regions16({"positions": 19200,
                                                               "dx_um": 5.3}, 2, 3), "n": 3000,
                                          "stm": False, "edges": False},
                        exe=toolchain.require_micropython(), heapsize="8M", timeout=300,
                        extra_path=str(x64_module))
    assert info["same"] == info["n"], info


def test_the_c_refresh_finds_the_region_the_table_walk_finds(x64_module):
    """The C refresh starts its region lookup from the row the finger was in
    (W_ROW) instead of walking the table: the same region as the walk (and
    refresh_viper.core) wherever the finger goes - 16 regions of every kind
    with gaps between them, p exactly at each start and end, just below and
    past them, both ways, jumps across many rows, dropouts and lifts."""
    total = 19200 * 5.3 / 1000.0
    w = total / 16
    kinds = [{"kind": "constant", "level": 0.7},
             {"kind": "texel", "pitch_db": 3.1, "irregularity_db": -12.9, "seed": 5, "v": 2},
             {"kind": "samples", "fit": "stretch", "u16": [0, 65535, 100, 40000]},
             {"kind": "reference", "name": "4sin"},
             {"kind": "samples", "fit": "tile", "u16": [7, 65535, 0, 30000, 12]},
             {"kind": "bump", "width_mm": 2}]
    regions = []
    for k in range(16):
        # a gap of ~1 mm before every region but the first (row 0 starts at 0) and
        # after the last (the sentinel row follows a gap)
        s0 = 0 if k == 0 else round(k * w + 1.0, 3)
        regions.append({"start_mm": s0, "end_mm": round((k + 1) * w - (1.0 if k == 15 else 0.5), 3),
                        "texture": kinds[k % len(kinds)]})
    info = mpy.run_json(REFRESH_SCRIPT % {"scene": {"regions": regions, "idle_amplitude": 13107},
                                          "n": 400, "stm": False, "edges": True},
                        exe=toolchain.require_micropython(), heapsize="8M", timeout=300,
                        extra_path=str(x64_module))
    assert info["same"] == info["n"], info["first"]
    assert len(info["rows"]) == 16 and info["kinds"] == [0, 1, 2, 3, 4, 5], info["rows"]
    seen = set(info["seen"])
    # every region's first position, last position and the one past it, met exactly
    for st, en in info["rows"]:
        near = [p for p in sorted(seen) if st - 9 <= p <= st + 9 or en - 9 <= p <= en + 9]
        assert {st, en - 1, en} <= seen, (st, en, near)
    assert -1 in seen                   # lifted


def test_c_grid_is_grid_py_where_it_decides():
    """check_core.h tc_grid (the texel check's fast path) against gen/grid.py
    on CPython's double: where it gives a point, on_grid gives it without
    refusing and _in_range keeps it; it leaves to Python every tie within
    GRID_TIE and every point outside the range - and only those."""
    from texel.gen.grid import GRID_TIE, on_grid, _in_range
    r = random.Random(11)
    vals = [0.0, -0.0, 19.747, -20.0, 94.339, 94.3396, 94.3394, 0.0105, 0.0095, 12.3455,
            -12.3455, 12.34549, 12.34551, 12.3459, 1e-9, 999.9995]
    vals += [round(r.uniform(-30, 95), r.choice((2, 3, 4, 5, 7))) for _ in range(20000)]
    vals += [k / 1000.0 + d for k in range(-30000, 95000, 7) for d in (0.0, 0.00049, 0.0000051)]
    lo, hi = -20.0, 94.339
    decided = 0
    for v in vals:
        got = core_c.grid(v, GRID_TIE, lo, hi)
        try:
            want: float | None = on_grid("k", v)
        except ValueError:
            want = None
        if want is not None and _in_range(want, lo, hi) != want:
            want = None                 # _in_range moves it: Python's to decide
        assert got == want, v
        decided += got is not None
    assert decided > 0.6 * len(vals)       # (a third of the swept values sit on ties)


def test_c_plan_constants_are_plan_ints():
    """texelcore_api.h plan's integers on CPython: tc_mdb is grid.mdb,
    tc_plan_consts PlanInt's mu, sigma, q and dcap, tc_seeded plan_int.seeded
    - over the hard cases and the random sets (the seeds' whole range)."""
    from texel.gen.grid import mdb
    for name, p in CASES.items():
        pl = P.PlanInt(texel.validate(p))
        c = pl.params
        ms = [core_c.mdb(c[k]) for k in ("pitch_db", "irregularity_db", "quant_db")]
        assert ms == [mdb(c[k]) for k in ("pitch_db", "irregularity_db", "quant_db")], name
        cap = core_c.mdb(c["band_limit_cpmm"]) if c["band_limit_cpmm"] is not None else 0
        assert core_c.plan_consts(*ms, cap) == [pl.mu, pl.sigma, pl.q, pl.dcap], name
        assert core_c.seeded(c["seed"]) == list(P.seeded(c["seed"])), name
    r = random.Random(3)
    for v in [0.0, -0.0, 0.0005, -0.0005, 19.747, -20.0, 94.339] + \
            [round(r.uniform(-30, 95), 3) for _ in range(5000)]:
        assert core_c.mdb(v) == mdb(v), v


def test_native_texel_check_is_the_python_check(x64_module, tmp_path):
    """The x64 native module's texel_check (a scene's texel regions) on the
    unix port: the same canonical dict, keys, values and types as the Python
    check, or None and the Python check decides - over the hard cases and
    3,000 mixed textures; every valid texture but a grid point _in_range
    moves takes the fast path."""
    from support import texel_check
    lit = tmp_path / "cases.txt"
    lit.write_text(repr(texel_check.cases(3000)))
    info = mpy.run_json(texel_check.script(path=str(lit)),
                        exe=toolchain.require_micropython(), heapsize="8M", timeout=300,
                        extra_path=str(x64_module))
    assert info["build"] == "native" and info["bad"] == [], info["bad"][:3]
    assert info["fast"] > 500 and info["fallback_ok"] <= 0.01 * info["n"], info
    assert info["plans"] > 200 and info["c_plans"] > 150, info     # plan_of's C plan: PlanInt's
    assert info["c_option_plans"] > 20, info     # ... seed 001's options too (tc_plan_options)


BRUSH_CHECK_SCRIPT = r"""
import json
from texel.gen import brush as B
def run(b):
    try:
        return ["ok", repr(B.validate(b))]
    except ValueError as e:
        return ["err", str(e)]
out = {"same": [], "differ": [], "fast": 0}
c = B._native_c()
for b in %(cases)s:
    for key in ("k", "lam"):
        v = b.get(key)
        if isinstance(v, list):
            b[key] = [float(x) if x in ("nan", "inf", "-inf") else x for x in v]
    fast = run(b)
    out["fast"] += c.floats_in(b["k"], B.K_MIN, B.K_MAX) < 0 and \
        c.floats_in(b["lam"], 0.0, B.LAM_MAX) < 0
    B._C = False
    try:
        slow = run(b)
    finally:
        B._C = None
    (out["same"] if fast == slow else out["differ"]).append([fast, slow])
print(json.dumps({"same": len(out["same"]), "differ": out["differ"][:3], "fast": out["fast"],
                  "errors": sum(1 for f, s in out["same"] if f[0] == "err")}))
"""


def test_native_brush_check_is_the_python_check(x64_module, tmp_path):
    """texel/gen/brush.py validate with the x64 native module's floats_in (a
    brush's lists checked in C) and without it: the same checked brush or the
    same refusal word for word - over brushes whose lists hold ints, bools,
    NaN, infinities, None, the bounds themselves and values just past them."""
    from texel.gen import brush as B
    r = random.Random(11)
    base = [("k", B.K_MIN, B.K_MAX), ("lam", 0.0, B.LAM_MAX)]
    cases = []
    for i in range(120):
        b = {"k": [round(r.uniform(0.05, 20.0), 3) for _ in range(B.K)],
             "lam": [round(r.uniform(0.0, 2.0), 4) for _ in range(B.K)], "range": [0.0, 1.0]}
        if i % 2:
            key, lo, hi = base[i % 4 // 2]
            j = r.randrange(B.K)
            b[key][j] = r.choice([lo, hi, lo - 1e-9 if lo else -1e-300, hi * (1 + 1e-12), 3,
                                  True, False, None, "nan", "inf", "-inf", 0, [1.0]])
        if i % 7 == 0:
            b["k"] = tuple(b["k"])
        cases.append(b)
    lit = tmp_path / "brushes.txt"
    lit.write_text(repr(cases))
    info = mpy.run_json(BRUSH_CHECK_SCRIPT % {"cases": "eval(open(%r).read())" % str(lit)},
                        exe=toolchain.require_micropython(), heapsize="8M", timeout=300,
                        extra_path=str(x64_module))
    assert info["differ"] == [] and info["same"] == len(cases), info
    assert info["fast"] >= 60 and info["errors"] >= 20, info


def test_c_brush_log2_and_wave_constants_are_the_python_ones():
    """brush_core.c tb_log2_q24 and tb_wave_ll on CPython against brush.log2_q24 and
    brush._waves_ll: every v below 5,000, the powers of two and their neighbours up
    to 2^30, 20,000 random ones; the waves' constants of one-shape brushes, their
    bases at the 32-bit ends too."""
    from texel.gen import brush as B
    t = array("i", B.LOG2)
    r = random.Random(13)
    vs = list(range(1, 5000)) + [x + d for e in range(1, 30) for x in (1 << e,)
                                 for d in (-1, 0, 1)] + [r.randrange(1, 1 << 30)
                                                         for _ in range(20000)]
    assert [core_c.log2_q24(v, t) for v in vs] == [B.log2_q24(v) for v in vs]
    for i in range(60):
        lam = [round(r.uniform(0.0, 3.0), 5) for _ in range(B.K)]
        if i % 6 == 0:
            lam[1:] = [0.0] * (B.K - 1)
        a, _ = B.leakage(lam)
        kk = round(r.uniform(0.05, 30), 3)
        s = B._shape(kk, False)
        base = r.choice([r.randrange(-(1 << 31), 1 << 31), -(1 << 31), (1 << 31) - 1, 0])
        want = (array("i", bytes(4 * B.K)), array("i", bytes(4 * B.K)))
        B._waves_ll([kk] * B.K, a, want[0], want[1], base)
        got = (array("i", bytes(4 * B.K)), array("i", bytes(4 * B.K)))
        core_c.wave_ll(a, got[0], got[1], base, s, B.LL_NONE, B.LL_MAX, t)
        assert got == want, (i, base)


BRUSH_COMP_SCRIPT = r"""
import json
from texel.gen import brush as B
same = 0
differ = []
fast = 0
c = B._native_c()
has = [hasattr(c, "wave_ll"), hasattr(c, "leak_start")]
for b in %(cases)s:
    v = B.validate(b)
    one = v["k"].count(v["k"][1]) - (v["k"][0] == v["k"][1]) == B.K - 1
    got = B.compensated(v)
    B._C = False
    try:
        want = B.compensated(v)
    finally:
        B._C = None
    g = [list(got[0]), list(got[1]), got[2], got[3]]
    w = [list(want[0]), list(want[1]), want[2], want[3]]
    if g == w:
        same += 1
        fast += one
    else:
        differ.append([b, g, w])
print(json.dumps({"same": same, "differ": differ[:2], "one_shape": fast, "has": has}))
"""


def test_native_brush_constants_are_the_python_ones(x64_module, tmp_path):
    """texel/gen/brush.py compensated (a brush's integer constants) with the x64
    native module's leak_start and wave_ll and without them: the same invk, ll,
    sign and offset - designed brushes (one shape), fitted ones (a shape per
    wavenumber), a lone line, ties for the largest scale, scales of 0, the
    smallest and largest scales and shapes."""
    from texel.gen import brush as B
    r = random.Random(12)
    cases = []
    for i in range(150):
        kind = i % 5
        if kind == 0:       # designed: one shape
            k = [round(r.uniform(0.05, 30), 3)] + [round(r.uniform(0.05, 30), 3)] * (B.K - 1)
        else:               # fitted: a shape each
            k = [round(r.uniform(0.05, 1000.0 if kind == 4 else 20.0), 4) for _ in range(B.K)]
        lam = [round(r.uniform(0.0, 3.0), 5) for _ in range(B.K)]
        if kind == 1:
            lam = [0.0] * B.K
            lam[r.randrange(1, B.K)] = r.choice([1e-3, 1.0, 1000.0])      # a lone line
        elif kind == 2:
            top = max(lam[1:])
            lam[r.randrange(1, B.K)] = top          # a tie for the largest
            lam[r.randrange(1, B.K)] = 0.0
        elif kind == 3 and i % 10 == 3:
            lam = [0.0] * B.K                       # no waves at all
        rng = r.choice([[0.0, 1.0], [1.0, 0.0], [-0.5, 0.25], [0.2, 0.2001]])
        cases.append({"k": k, "lam": lam, "range": rng})
    # one shape, tiny scales over the widest range: compensated's base below -2^31
    cases.append({"k": [2.0] * B.K, "lam": [1e-34] * B.K, "range": [0.0, 1e6]})
    cases.append({"k": [2.0] * B.K, "lam": [1000.0] * B.K, "range": [0.2, 0.2001]})
    lit = tmp_path / "brushes.txt"
    lit.write_text(repr(cases))
    info = mpy.run_json(BRUSH_COMP_SCRIPT % {"cases": "eval(open(%r).read())" % str(lit)},
                        exe=toolchain.require_micropython(), heapsize="8M", timeout=300,
                        extra_path=str(x64_module))
    assert info["has"] == [True, True], info     # (the C ran: not the Python twice)
    assert info["differ"] == [] and info["same"] == len(cases), info["differ"][:1]
    assert info["one_shape"] >= 25, info


def test_native_region_check_is_the_python_scene_check(x64_module, tmp_path):
    """scene.py's checks with the x64 native module's region_check and
    texel_check and without them (the unix port): the same canonical scene,
    spans and types, or the same refusal word for word - over 1,000 scenes
    of edges (boundaries as ints, bools, NaN, at and past the display's end,
    rounding to no position, extra and missing keys, overlaps)."""
    from support import texel_check
    lit = tmp_path / "scenes.txt"
    lit.write_text(repr(texel_check.scenes(1000)))
    info = mpy.run_json(texel_check.scene_script(path=str(lit)),
                        exe=toolchain.require_micropython(), heapsize="16M", timeout=300,
                        extra_path=str(x64_module))
    assert info["fast_region"] and info["bad"] == [], info["bad"][:3]
    assert info["ok"] > 150 and info["fast_regions"] > 1000, info


DESCRIBE_SCRIPT = r"""
import json, random
import texel
from texel.runtime import scene as S
from texel.runtime.kinds import reference as KR
# a map in flash stood in for by a memoryview (not an array: mode "flash", 0 bytes)
KR.flash = lambda name, n: memoryview(texel.reference_u16(name, n))
random.seed(5)
names = ["2sin", "4sin", "square", "pink"]
def texture():
    k = random.randrange(7)
    if k == 0:
        return {"kind": "texel", "pitch_db": random.choice([0, 3.1, 6.3, 12.0]),
                "irregularity_db": random.choice([-12.9, -3.0, 0]), "seed": random.randrange(99),
                "v": random.choice([1, 2])}
    if k == 1:
        return {"kind": "reference", "name": random.choice(names)}
    if k == 2:
        return {"kind": "constant", "level": random.random()}
    if k == 3:
        return {"kind": "samples", "fit": random.choice(["tile", "stretch"]),
                "u16": [random.randrange(65536) for _ in range(random.choice([1, 2, 5, 600]))]}
    if k == 4:
        return {"kind": "bump", "width_mm": random.choice([0.5, 2, 8])}
    return {"kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7,
            "texel_samples": random.choice([3, 18, 50])}
bad = []
n = 0
modes = {}
for dx in (5.3, 652.8, 0.001, 13.37, 1.0):
    positions = 400 if dx > 100 else 19200
    disp = {"positions": positions, "dx_um": dx}
    total = positions * dx / 1000.0
    for _ in range(12):
        cuts = sorted(set(round(random.uniform(0, total), 3) for _ in range(random.randrange(2, 9))))
        regs = []
        for i in range(0, len(cuts) - 1, 1 + random.randrange(2)):
            regs.append({"start_mm": cuts[i], "end_mm": cuts[i + 1], "texture": texture()})
        try:
            c = S.validate({"regions": regs, "name": "d"}, disp)
        except ValueError:
            continue
        b = S.build(c, disp)
        S._DESCRIBE = None
        a = b.describe()
        have = bool(S._DESCRIBE)
        S._DESCRIBE = False
        p = b.describe()
        S._DESCRIBE = None
        n += 1
        for r in a["regions"]:
            modes[r["mode"]] = 1
        ta = [sorted((k, repr(v), type(v).__name__) for k, v in r.items()) for r in a["regions"]]
        tp = [sorted((k, repr(v), type(v).__name__) for k, v in r.items()) for r in p["regions"]]
        if a != p or ta != tp:
            bad.append([dx, ta, tp])
print(json.dumps({"n": n, "bad": bad[:2], "c": have, "modes": sorted(modes)}))
"""


def test_the_c_describe_is_scene_describe(x64_module):
    """Scene.describe() with the x64 native module's describe_regions and
    with the Python loop: the same regions - keys, values, their types and
    reprs - over 60 scenes of every kind and play mode (a map in flash stood
    in for), on five displays (dx 0.001 to 652.8 um: the mm rounding)."""
    info = mpy.run_json(DESCRIBE_SCRIPT, exe=toolchain.require_micropython(), heapsize="16M",
                        timeout=300, extra_path=str(x64_module))
    assert info["c"] and info["bad"] == [], info["bad"]
    assert info["n"] >= 40, info
    assert info["modes"] == ["constant", "flash", "map", "plan", "stretch", "tile"], info


def test_an_old_native_module_is_not_used(tmp_path):
    """A /lib/_texelcore.mpy of another API (a board deployed by another
    texelpad) is passed over: the viper loops run, with the same plan."""
    (tmp_path / "_texelcore.py").write_text("API = 0\nBUILD = 'old'\n")
    out = mpy.run("from texel import compat\nfrom texel.gen import plan_int as P\n"
                  "print(compat.core(), P.ENGINE)", extra_path=str(tmp_path))
    assert out.split() == ["None", "viper"]


def test_natmod_says_what_is_missing(monkeypatch):
    monkeypatch.setattr(natmod.shutil, "which", lambda name: None)
    lack = natmod.missing("armv6m")
    assert any("arm-none-eabi-gcc" in m for m in lack) and any("make" in m for m in lack)
    with pytest.raises(natmod.NatmodError, match="no make"):
        natmod.build("armv6m", "/nonexistent")
    assert natmod.missing("xtensa") and natmod.native_module("xtensa") is None
    said = []
    monkeypatch.setenv("TEXELPAD_CACHE", "/nonexistent-texelpad-cache")
    assert natmod.native_module("armv6m", said.append) is None
    assert said and "viper" in said[-1]


SINES_SCRIPT = r"""
import json
from array import array
from texel import compat
from texel.gen import reference as R, sine_table
from texel.gen.reference_viper import CONSTANTS, steps_of
c = compat.core()
info = {"core": c is not None and c.BUILD, "maps": {}, "via": {}, "errors": []}
info["int_path"] = "c" if R._int_sines() is c.sines else repr(R._int_sines())
tab = sine_table.table()
def args(name):
    s = R._SINES[name]
    return array("i", steps_of(s)), array("i", bytes(8 * len(s))), len(s)
for name in ("2sin", "3sin", "4sin"):
    n = 40000
    buf = array("H", bytes(2 * n))
    st, ph, m = args(name)
    for a in range(0, n, 7001):                 # parts, the phases carried
        b = min(n, a + 7001)
        c.sines(memoryview(buf)[a:b], b - a, st, ph, m, tab, *CONSTANTS[name])
    info["maps"][name] = bytes(buf).hex()
    info["via"][name] = bytes(R.reference_u16(name, n)) == bytes(buf)
st, ph, m = args("4sin")
a0, ws, rq = CONSTANTS["4sin"]
CALLS = ("c.sines(array('H', [0] * 9), 10, st, ph, m, tab, a0, ws, rq)",
             "c.sines(array('H', [0] * 9), 9, st, ph, 5, tab, a0, ws, rq)",
             "c.sines(array('H', [0] * 9), 9, st, ph, 0, tab, a0, ws, rq)",
             "c.sines(array('H', [0] * 9), 9, st, array('i', [1024, 0] * 4), m, tab, a0, ws, rq)",
             "c.sines(array('H', [0] * 9), 9, array('i', [0, 100000] * 4), ph, m, tab, a0, ws, rq)",
             "c.sines(array('H', [0] * 9), 9, st, ph, m, tab, a0, ws, rq + 1)",
             "c.sines(array('H', [0] * 9), 9, st, ph, m, tab, a0, 1, rq)",
             "c.sines(array('H', [0] * 9), 9, st, ph, m, array('H', [0] * 9), a0, ws, rq)")
""" + _REFUSALS


@pytest.mark.parametrize("exe", ["micropython", "micropython-ulab-f32"])
def test_native_sines_are_the_c_loop_and_render_float32_references(x64_module, exe):
    """texelcore_api.h sines (texel_core.c tc_sines), the x64 native module on the unix
    port: 2sin, 3sin and 4sin over 40,000 samples in parts are the CPython build's
    integers (tests/gen/test_reference_viper.py: those are the viper twin's at every sample
    of 200,000); a float32 interpreter's reference_u16 renders by it (a stock Pico's
    native module); bad arguments are refused before the loop touches memory."""
    from texel.gen import reference as R
    path = toolchain.interpreter(exe)
    if path is None:
        pytest.skip("no %s here (../shared/instruments)" % exe)
    if not core_c.available():
        pytest.skip("no gcc here")
    info = mpy.run_json(SINES_SCRIPT, exe=path, heapsize="8M", timeout=300,
                        extra_path=str(x64_module))
    assert info["core"] == "native", info
    for name, consts in (("2sin", (174760, 1747627, 39321)), ("3sin", (212345, 2721014, 25255)),
                         ("4sin", (400547, 3393228, 20251))):
        want = core_c.sines(R._SINES[name], consts, 40000)
        assert list(array("H", bytes.fromhex(info["maps"][name]))) == want, (exe, name)
    if exe == "micropython-ulab-f32":
        assert info["int_path"] == "c" and all(info["via"].values()), info
    else:                                       # binary64 keeps the float path (the CSV's)
        assert info["int_path"] == "False", info
    assert all(why for _call, why in info["errors"]), info["errors"]


PARTS_SCRIPT = r"""
import json
import texel.app as app
from texel.gen import brush as B, brush_parts as BP
from texel.runtime.upload import Chunks
br = B.validate(%(brush)r)
out = {"build": B._native_c().BUILD, "parts": []}
for n, at in ((19200, 0), (19200, 19199), (19200, 7777), (1000, 500), (50, 10)):
    ch = Chunks(n)
    BP.Painting(br, 9, n, ch, at).finish()
    whole = B.paint(br, 9, n, how="c")
    out["parts"].append(b"".join(bytes(c) for c in ch.chunks) == bytes(whole))
# a push of a full-screen brush with the (virtual board's scripted) finger at 63.6 mm,
# position 12000: the scene plays (swapped in) with the samples there painted and the
# rest to come; tidy() paints it
import texel.wire as W
from array import array
S = {"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": {"kind": "brush",
      "brush": %(brush)r, "seed": 4}}]}
app.start("virtual")
W.finger([(0, 63.6)])
W.advance(200)
out["pos"] = app._rt.refresh.pos
app._push(S)
sc = app._rt.refresh.scene
ch = sc._bufs[0]
got = b"".join(bytes(c) for c in ch)
whole = bytes(B.paint(br, 4, 19200, how="c"))
out["pending"] = len(sc.painting)
out["near"] = got[2 * 11900:2 * 12100] == whole[2 * 11900:2 * 12100]
out["far_zero"] = got[:2 * 2000] == bytes(4000)
app.tidy()
out["after"] = [len(sc.painting), b"".join(bytes(c) for c in ch) == whole]
# app.push() of another brush returns with it all painted in parts
made = []
_init = BP.Painting.__init__
def init(self, *a, **k):
    made.append(1)
    _init(self, *a, **k)
BP.Painting.__init__ = init
W.finger([(0, 0.53)])
W.advance(200)
S6 = {"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": {"kind": "brush",
      "brush": %(brush)r, "seed": 6}}]}
app.push(S6)
sc = app._rt.refresh.scene
out["push"] = [len(made), len(sc.painting), b"".join(bytes(c) for c in sc._bufs[0]) ==
               bytes(B.paint(br, 6, 19200, how="c"))]
W.finger([(0, None)])
W.advance(200)
app.push({"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": {"kind": "brush",
          "brush": %(brush)r, "seed": 5}}]})
sc = app._rt.refresh.scene
out["lifted"] = [len(made), len(sc.painting), b"".join(bytes(c) for c in sc._bufs[0]) ==
                 bytes(B.paint(br, 5, 19200, how="c"))]
# paint_part and skip refuse what would write out of their buffers
c = B._native_c()
invk, ll, sign, off, tab, t = BP.comp_tables(br)
u = array("H", bytes(2000))
ring = array("i", bytes(4 * 192))
work = array("i", bytes(4 * (4 * 97 + 3 * 192)))
from texel.gen.rng import Rng
st = B.state(Rng(1))
def part(w_from, w_to, lo, r=ring, wk=work):
    c.paint_part(st, invk, ll, sign, off, 1000, (u,), 30, tab, t[4], t[1], t[2], t[3], t[5],
                 r, w_from, w_to, lo, wk)
CALLS = ("part(1, 4, 0)", "part(0, 30, 0)", "part(4, 2, 0)", "part(-2, 2, 0)",
         "part(0, 2, 1001)", "part(0, 2, 2147483647)", "part(0, 2, -1)",
         "part(0, 2, 0, r=array('i', [0] * 100))", "part(0, 2, 0, wk=array('i', [0] * 100))",
         "c.skip(st, -1)", "c.skip(bytearray(4), 1)")
out["refused"] = []
for call in CALLS:
    try:
        eval(call)
        out["refused"].append([call, None])
    except ValueError as e:
        out["refused"].append([call, str(e)])
print(json.dumps(out))
"""


def test_native_painting_in_parts_is_the_whole_painting(x64_module):
    """brush_parts.Painting through the x64 native module (paint_part, skip) on the
    unix port: the map paint() paints whole, from any finger position; a push
    with the finger on the display swaps its scene in with the samples under
    the finger painted and the rest painted by tidy() (texel.wire runs it after
    the answer), push() returns with it all painted, and a lifted finger paints
    it whole before the swap - the finger the virtual board's, scripted; and
    paint_part and skip refuse windows, lo_emit and buffers out of range."""
    info = mpy.run_json(PARTS_SCRIPT % {"brush": _BRUSH}, exe=toolchain.require_micropython(),
                        heapsize="8M", timeout=300, extra_path=str(x64_module))
    assert info["build"] == "native" and info["parts"] == [True] * 5, info
    assert abs(info["pos"] - 12000) <= 20, info["pos"]
    assert info["pending"] == 1 and info["near"] and info["far_zero"], info
    assert info["after"] == [0, True] and info["push"] == [1, 0, True], info
    assert info["lifted"] == [1, 0, True], info
    assert [why for _, why in info["refused"] if why is None] == [], info["refused"]

"""The texelpad firmware on the emulated Pico: built with the offline kit (boards/pico), the
.uf2 booted as if dragged onto a Pico in BOOTSEL mode, everything checked through its serial
port as a user's host sees it. No timing asserted: the figures are the benchmark's
(python -m bench.firmware)."""
from __future__ import annotations

import ast
import hashlib
import json

import numpy as np
import pytest

from support import digest, refresh_same
from support.cli import run_cli
from support.firmware import built
from support.pico import emulated_pico

pytestmark = [pytest.mark.slow, pytest.mark.instruments]

_BRUSH = {"k": [8.0] + [1.5 + 0.1 * (i % 20) for i in range(96)],
          "lam": [0.5] + [0.05 / (1 + 0.04 * i) for i in range(96)], "range": [0.0, 1.0]}


@pytest.fixture(scope="module")
def fw():
    return built("pico")


@pytest.fixture(scope="module")
def pico(fw):
    with emulated_pico(firmware=fw.uf2) as emu:
        yield emu


def _connect(port, **kw):
    from texelpad.link.board import connect
    return connect(port, timeout=60, **kw)


def test_the_uf2_boots_playing_its_power_up_scene_with_texel_from_flash(pico):
    with _connect(pico.port) as b:       # the handshake imports texel: from /rom
        st = b.status()
        where = b.link.eval("import texel, sys\nprint(repr((texel.__file__, sys.path)))")
        info = json.loads(b.link.eval("print(repr(open('/rom/firmware.json').read()))"))
    assert st["running"] and st["board"] == "pico" and st["refresh"] == "viper-irq"
    assert st["refreshes"] > 0 and st["overruns"] == 0 and st["faults"] == 0
    kinds = [(r["kind"], r["mode"]) for r in st["scene"]["regions"]]
    assert kinds == [("reference", "flash"), ("texel", "plan")]     # texel.app.DEFAULT_SCENE
    # the reference plays from flash: only the texel region's plan is in RAM
    assert st["scene"]["buffer_bytes"] == st["scene"]["regions"][1]["bytes"]
    # texel's code is frozen in the firmware (a __file__ naming no file); its data is the ROMFS's
    from texelpad.firmware.romfs import code_digest
    assert where[0] == "texel/__init__.py" and where[1][:4] == ["", ".frozen", "/rom", "/rom/lib"]
    assert info["board"] == "pico" and info["micropython"] == "1.28.0"
    assert info["frozen_code_sha256"] == code_digest() and info["code_in_romfs"] is False
    print("\nheap free while the power-up scene plays: %s bytes" % format(st["mem_free"], ","))


def test_the_references_in_flash_are_the_hosts_maps_bit_for_bit(pico):
    from texel.gen import reference
    code = ("import hashlib, binascii\nfrom texel.gen.reference import flash_u16\n"
            "_o = {}\nfor _n in %r:\n"
            " _p = '/rom/lib/texel/gen/ref/%%s.u16' %% _n\n"
            " _v = flash_u16(_n, 19200)\n"
            " _o[_n] = (binascii.hexlify(hashlib.sha256(memoryview(open(_p, 'rb'))).digest()),"
            " 19200, _v[0], _v[9599], _v[19199])\n"
            "print(repr(_o))" % (reference.STUDY_NAMES,))
    with _connect(pico.port) as b:
        got = b.link.eval(code)
    for name in reference.STUDY_NAMES:
        m = np.asarray(reference.reference_u16(name, 19200), dtype="<u2")
        digest, n, first, mid, last = got[name]
        assert digest.decode() == hashlib.sha256(m.tobytes()).hexdigest(), name
        assert (n, first, mid, last) == (19200, m[0], m[9599], m[19199]), name


def test_the_generators_tables_read_in_place_make_the_hosts_maps(pico):
    # the sine and plan tables come from the ROMFS (texel.rom.const_table), not copied
    import texel
    p = {"pitch_db": 8.1, "irregularity_db": -6.0, "seed": 11, "v": 2, "length_samples": 4800}
    want = hashlib.sha256(np.asarray(texel.render_u16(p, engine="int"), dtype="<u2").tobytes())
    with _connect(pico.port) as b:
        got = b.link.eval(
            "import texel, hashlib, binascii\nfrom texel.gen import sine_table, plan_int_tables\n"
            "from texel.gen import brush\n"
            "m = texel.render_u16(%r, engine='int')\n"
            "print(repr((binascii.hexlify(hashlib.sha256(m).digest()),"
            " str(type(sine_table.table())), str(type(plan_int_tables.table())),"
            " [str(type(t)) for t in brush._tables()[1:]],"
            " [list(t[k] for k in (0, 1, 100, 150, 191)) for t in brush._tables()[1:]])))"
            % (p,))
    assert got[0].decode() == want.hexdigest()
    assert got[1:3] == ("<class 'struct'>", "<class 'struct'>")     # views of flash, not arrays
    # and the brush painter's five (gen/brush.py TABLE_FILES), signed where they are
    from texel.gen import brush
    assert got[3] == ["<class 'struct'>"] * 5
    want_t = [[t[k] for k in (0, 1, 100, 150, 191)] for t in (brush.PHASE, brush.TW, brush.HANN,
                                                              brush.LOG2, brush.POS)]
    assert min(min(t) for t in want_t) < 0 and got[4] == want_t     # negatives read as such


def test_push_status_and_scene_pull_through_the_command_line(pico, capsys, tmp_path):
    port = pico.port
    code, out, err = run_cli(capsys, "push", "--port", port, "--pitch-db", "7",
                             "--irregularity-db", "-10", "--seed", "3")
    assert code == 0, err
    code, out, err = run_cli(capsys, "status", "--port", port)
    assert code == 0, err
    f = tmp_path / "s.json"
    code, out, err = run_cli(capsys, "scene", "pull", str(f), "--port", port)
    assert code == 0, err
    tex = json.loads(f.read_text())["regions"][0]["texture"]
    assert (tex["kind"], tex["pitch_db"], tex["seed"], tex["v"]) == ("texel", 7.0, 3, 2)


def test_a_full_screen_reference_and_a_brush_after_a_series_of_pushes(pico):
    from texelpad.scenes import __path__ as scene_dir  # the shipped scenes
    import pathlib
    shipped = [json.loads(p.read_text()) for p in sorted(pathlib.Path(scene_dir[0]).glob("*.json"))]
    full = {"regions": [{"start_mm": 0, "end_mm": 101.76,
                         "texture": {"kind": "reference", "name": "white"}}]}
    brush = {"regions": [{"start_mm": 10, "end_mm": 30,
                          "texture": {"kind": "brush", "brush": _BRUSH, "seed": 4}}]}
    with _connect(pico.port) as b:
        frees = []
        for rnd in range(2):
            for sc in shipped:
                b.push(sc)
                frees.append(b.status()["mem_free"])
            b.push_texel({"pitch_db": 5.0 + rnd, "irregularity_db": -12.0, "seed": rnd})
        b.push(full)
        st = b.status()
        assert st["scene"]["regions"][0]["name"] == "white" and st["scene"]["buffer_bytes"] == 0
        # a map in flash takes no RAM, and status says so region by region too
        assert (st["scene"]["regions"][0]["mode"], st["scene"]["regions"][0]["bytes"]) == (
            "flash", 0)
        from texelpad.cli.board import describe_scene
        text = describe_scene(st["scene"])
        assert "flash, 0 B" in text and "(1 map played in place from flash: no RAM)" in text, text
        b.push(brush)
        st = b.status()
        assert st["scene"]["regions"][0]["kind"] == "brush" and st["faults"] == 0
        assert st["overruns"] == 0
    print("\nheap free after each of %d pushes: min %s, max %s bytes"
          % (len(frees), format(min(frees), ","), format(max(frees), ",")))


def test_the_firmware_paints_a_full_screen_brush_in_c_as_the_host_does(pico, capsys):
    """The firmware's C painter (_texelcore, device/cmod/texelcore) paints a
    full-screen brush region (seed 002, issue 21) into the map CPython paints:
    the same integers once the painting's float setup is (float32 here: within
    one PWM step, 8 u16 measured), with no viper module loaded for it; the
    push's cost on the chip's own clock is printed (the benchmark reports it:
    python -m bench.firmware)."""
    import ast
    from texel.gen import brush as B
    host = B.paint(B.validate(_BRUSH), 21, 19200)
    with _connect(pico.port) as b:
        b.push({"regions": [{"start_mm": 0, "end_mm": 101.76,
                             "texture": {"kind": "constant", "level": 0.5}}]})
        st = b.push({"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": {
            "kind": "brush", "brush": _BRUSH, "seed": 21}}]})
        lp = st["last_push"]
        out = b.link.exec("import sys\nfrom texel.gen import brush as _B\nimport texel.app as _A\n"
                          "print(repr((_B._native_c() is not None, "
                          "'texel_ram.brush_viper' in sys.modules, "
                          "[_A._rt.refresh.scene.amp(p) for p in range(0, 19200, 61)])))",
                          timeout=60)
        c, viper_loaded, got = ast.literal_eval(out.strip().splitlines()[-1])
    want = [host[p] for p in range(0, 19200, 61)]
    diff = [abs(a - w) for a, w in zip(got, want)]
    print("\nfull-screen brush on the firmware (C painter): validate %.1f + build %.1f ms; "
          "%d of %d samples equal CPython's, worst %d u16"
          % (lp["validate_us"] / 1e3, lp["build_us"] / 1e3, diff.count(0), len(diff), max(diff)))
    assert c is True and viper_loaded is False and st["faults"] == 0
    assert len(got) == len(want) and max(diff) <= 65535 // 3676
    assert diff.count(0) >= 0.8 * len(diff)


_CORE_DIGEST = r"""
import sys, gc, texel
from texel import compat
from texel.gen import plan_int as P, engine_int as E
""" + digest.DEVICE + r"""_res = []
for _p in %r:
    gc.collect()
    _pl = P.PlanInt(texel.validate(_p))
    _res.append((_dig((_pl.t28, _pl.d28, _pl.y)), _dig((E.render_u16(_pl),))))
print(repr((compat.core().BUILD, P.ENGINE, E.ENGINE, _res,
            sorted(m for m in sys.modules if m.endswith("_int_viper")))))
"""


def test_the_firmware_plans_and_renders_format_2_in_c_as_cpython_does(pico):
    """Format 2's per-texel plan and the int engine run in the firmware's C
    core (_texelcore, a user C module), with no viper twin loaded, and give
    CPython's plan and map (digests of every value): the hard edges too -
    1-sample texels at the lowest pitch, the Nyquist pitch under a band limit,
    the last seed with quantization."""
    import ast
    import texel
    from texel.gen.engine_int import render_u16
    from texel.gen.plan_int import PlanInt
    cases = [{"pitch_db": 6.0, "irregularity_db": -10.0, "texel_samples": 50,
              "length_samples": 19200, "seed": 3},
             {"pitch_db": -20.0, "irregularity_db": 5.0, "texel_samples": 1, "seed": 4294967295,
              "quant_db": 0.5, "length_samples": 3000},
             {"pitch_db": 19.747, "irregularity_db": 0.0, "texel_samples": 7, "seed": 0,
              "band_limit_cpmm": 50.0, "length_samples": 2100}]

    def dig(arrs):
        s = 0
        for a in arrs:
            for v in a:
                s = (s * 31 + (int(v) & 0xFFFFFF)) & 0xFFFFFF
        return s
    want = []
    for c in cases:
        pl = PlanInt(texel.validate(c))
        want.append((dig((pl.t28, pl.d28, pl.y)), dig((render_u16(pl),))))
    with _connect(pico.port) as b:
        out = b.link.exec(_CORE_DIGEST % (cases,), timeout=120)
    build, plan_engine, fill_engine, got, viper = ast.literal_eval(out.strip().splitlines()[-1])
    assert (build, plan_engine, fill_engine) == ("firmware", "c", "c")
    assert got == want and viper == []


def test_the_firmware_texel_and_region_checks_are_the_python_checks_in_float32(pico):
    """The firmware's texel_check and region_check (the C core's fast paths
    for a scene's regions, in the RP2040's float32) give the Python checks'
    canonical texture and scene - keys, values, types - or leave them to it."""
    from support import texel_check
    with _connect(pico.port) as b:
        def ex(code):
            return b.link.exec(code, timeout=300)
        info = texel_check.run_batches(ex, texel_check.script, texel_check.cases(300, seed=3), 50)
        assert info["build"] == "firmware" and info["bad"] == [], info["bad"][:3]
        assert info["fast"] > 60 and info["fallback_ok"] <= 3 and info["c_plans"] > 20, info
        # and scene.py's region_check: the same canonical scenes or refusals
        info = texel_check.run_batches(ex, texel_check.scene_script,
                                       texel_check.scenes(60, seed=4), 15)
    assert info["fast_region"] and info["ok"] >= 5 and info["fast_regions"] > 50, info


# On the board: W and the region table the C core's install builds for a swap
# against FastRefresh._install's Python (refresh_fast._INSTALL False) for the same
# scene, every address compared - a chunked buffer's chunk table read through
# machine.mem32 (install puts every chunk table in one array) - then the scene
# playing before is swapped back in.
_INSTALL_SAME = r"""
import gc, machine, texel.app as A
from texel.runtime import refresh_fast as F, scene as S
rf = A._rt.refresh
disp = A._rt.board["display"]
def words():
    w, sc, tab, _ = rf._keep
    bufs = sc.buffers() if sc is not None else ()
    out = list(w)
    out[F.W_TAB] = None                     # a copy of the table each time
    out[F.W_ROW] = None                     # the refresh's own (the finger's row)
    t = list(tab)
    for k in range(len(bufs)):
        if isinstance(bufs[k], tuple):      # its chunk table, read through
            ct = w[F.W_BUF0 + k]
            ch = [machine.mem32[ct + 4 * c] & 0xFFFFFFFF for c in range(len(bufs[k]))]
            out[F.W_BUF0 + k] = ch
            for r in range(0, len(t) - 4, 4):
                if t[r + 2] == 3 and t[r + 3] == ct:
                    t[r + 3] = ch
    return out, t, F._INSTALL is not False
def churn():
    # what the C made must be referenced from the refresh's generation (rf._keep):
    # a collection and new allocations here would reuse anything that is not
    gc.collect()
    return [bytearray(64) for _ in range(64)]
before = rf.scene
got = []
try:
    for sc, engine in %s:
        built = S.build(sc, disp, engine=engine) if sc is not None else None
        F._INSTALL = None
        rf.swap(built)
        junk = churn()
        a = words()
        F._INSTALL = False
        rf.swap(built)
        junk = churn()
        b = words()
        got.append((a[2], b[2], a[:2] == b[:2], len(a[0])))
        built = junk = None
finally:
    F._INSTALL = None
    rf.swap(before)
print(repr(got))
"""


def test_the_c_core_installs_the_words_the_python_does(pico):
    """A swap's word array W and region table built by the firmware's C core
    (texelcore_api.h install) against the Python's (refresh_fast._install):
    the same words and rows - every kind of region (a constant, a reference
    map in flash, a texel plan, three samples tiled in place (K_TILE: a plan's
    5 words), a 3-sample texel in chunks, the int engine's one-block buffer),
    16 texel regions, no scene at all."""
    import ast
    from texelpad.bench.link import regions16
    with _connect(pico.port) as b:
        d = b.status()["display"]
        end = round(d["positions"] * d["dx_um"] / 1000.0, 6)
        mixed = {"regions": [
            {"start_mm": 0, "end_mm": 10, "texture": {"kind": "constant", "level": 0.3}},
            {"start_mm": 10, "end_mm": 40, "texture": {"kind": "reference", "name": "2sin"}},
            {"start_mm": 40, "end_mm": 60, "texture": {"kind": "texel", "pitch_db": 5.0,
                                                        "irregularity_db": -9.0, "seed": 2}},
            {"start_mm": 60, "end_mm": 70, "texture": {"kind": "samples", "u16": [1, 2, 3]}},
            {"start_mm": 71, "end_mm": end, "texture": {
                "kind": "texel", "pitch_db": 12.0, "irregularity_db": -9.0, "seed": 2,
                "texel_samples": 3}}]}
        cases = [(mixed, None), (mixed, "int"), (regions16(d, 2, 5), None), (None, None)]
        out = b.link.exec(_INSTALL_SAME % (cases,), timeout=300)
    got = ast.literal_eval(out.strip().splitlines()[-1])
    assert [g[:3] for g in got] == [(True, False, True)] * len(cases), got
    # W_FIXED, two buffers (the flash map, the chunks), two plans (the texel's, the samples')
    assert got[0][3] == 15 + 2 + 5 * 2 and got[2][3] > 15 + 5 * 16 - 1, got


# On the board: each case (floats given as {"__f": their bits}, an OrderedDict as
# {"__od": its items}, n lists nested as {"__deep": n}) made into its value, printed by repr() and then by the C
# core's answer writer (texel.wire.say's), which prints nothing and answers False
# where it leaves the value to repr()
_SAY = r"""
import struct, texel.app as A, texel.wire as W
from collections import OrderedDict
def mk(v):
    if isinstance(v, dict):
        if '__f' in v:
            return struct.unpack('<f', struct.pack('<I', v['__f']))[0]
        if '__od' in v:
            return OrderedDict(v['__od'])
        if '__deep' in v:
            d = [1]
            for _ in range(v['__deep'] - 1):
                d = [d]
            return d
        return {k: mk(x) for k, x in v.items()}
    if isinstance(v, list):
        return [mk(x) for x in v]
    if isinstance(v, tuple):
        return tuple(mk(x) for x in v)
    return v
for c in %r + [A.changes()]:
    v = mk(c)
    print('R' + repr(v))
    print('C', end='')
    ok = W._say_c(v)
    if not ok:
        print()
    print('S' + repr(ok))
"""


def _same(a, b):
    """Equal, floats as float32 (NaN equal to NaN, -0.0 not 0.0), types too."""
    import struct
    if isinstance(a, float) and isinstance(b, float):
        return struct.pack("<f", a) == struct.pack("<f", b) or (a != a and b != b)
    if type(a) is not type(b):
        return False
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return a == b


def test_the_c_core_writes_answers_as_repr_with_floats_as_their_bits(pico):
    """texel.wire.say's C writer (texelcore_api.h answer) on the firmware: every
    value it writes reads back on the host (floats_from_bits) as repr()'s value,
    each float32 the same float32 (random bit patterns, zeros, subnormals, the
    largest, infinities, NaN) and, where there is no float, the same text byte
    for byte (quotes, backslashes, 1-tuples, empty containers, 16 levels); what
    it does not write - an int beyond a small int, bytes, text to escape or
    UTF-8, an OrderedDict, 17 levels - it leaves to repr(), printing nothing."""
    import ast
    import random
    from texelpad.link.protocol import _f32, floats_from_bits
    rng = random.Random(11)
    fb = [0, 0x80000000, 1, 0x807FFFFF, 0x7F7FFFFF, 0x7F800000, 0xFF800000, 0x7FC00000,
          0x3DCCCCCD, 0x41A00000] + [rng.getrandbits(32) for _ in range(150)]

    def deep(n):
        return {"__deep": n}
    plain = ["", "a", "it's", 'say "hi"', "both ' and \"", "back\\slash", "~", [], (), {},
             (1,), [(), [], {}, (None,)], {"k": {"k2": [1, (2, -3)]}, 5: True, "f": False},
             0, -1, (1 << 30) - 1, -(1 << 30) + 1, deep(16)]
    leave = [1 << 30, 1 << 40, -(1 << 31), b"x", "tab\t", "caf\u00e9", "\x7f",
             {"__od": [("a", 1)]}, deep(17), [1, 2, "\n"]]
    floats = [{"__f": b} for b in fb] + [{"pitch_db": {"__f": 0x40C9999A}, "n": [{"__f": 1}]}]
    cases = plain + leave + floats
    with _connect(pico.port) as b:
        b.push({"regions": [{"start_mm": 0, "end_mm": 50, "texture": {
            "kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7}}]})
        out = b.link.exec(_SAY % (cases,), timeout=300)
    lines = out.replace("\r\n", "\n").split("\n")
    got = []
    for k in range(0, len(lines) - 2, 3):
        r, c, s = lines[k], lines[k + 1], lines[k + 2]
        assert r[0] == "R" and c[0] == "C" and s[0] == "S", lines[k:k + 3]
        got.append((r[1:], c[1:], ast.literal_eval(s[1:])))
    assert len(got) == len(cases) + 1

    def host(v):                        # the case as the host expects it read back
        if isinstance(v, dict) and "__f" in v:
            return _f32(v["__f"])
        if isinstance(v, dict) and "__deep" in v:
            d = [1]
            for _ in range(v["__deep"] - 1):
                d = [d]
            return d
        if isinstance(v, dict):
            return {k: host(x) for k, x in v.items()}
        if isinstance(v, (list, tuple)):
            return type(v)(host(x) for x in v)
        return v
    for case, (r, c, said) in zip(cases, got):
        if case in leave:
            assert said is False and c == "", (case, c)
            continue
        assert said is True, case
        assert _same(floats_from_bits(ast.literal_eval(c)), host(case)), (case, c)
        if case in plain:
            assert c == r, (case, c, r)          # repr's own text
    # the playing scene's changes() (push's answer): repr()'s values, float32 for float32
    r, c, said = got[-1]
    assert said is True and "j" in c
    st = floats_from_bits(ast.literal_eval(c))
    assert _same(st, ast.literal_eval(r)) and st["scene"]["regions"][0]["pitch_db"] == 6.3


def test_pushes_go_to_the_standing_reader_and_every_other_use_still_finds_the_repl(pico):
    """On an RP2040 a push is a frame to texel.wire.stand() (no compile on the
    board): pushes in a row stay in it, a refusal, a board-side exception and
    a frame too large for the heap are answered there and it reads on, any other exchange ends it first, and a
    host that vanished while it stood leaves the next tool - a plain mpremote
    exec, texelpad's link - a REPL, with the display still playing."""
    from support.vboard import mpremote
    from texelpad.link import protocol
    from texelpad.link.transport import BoardError

    def scene(pitch):
        return {"regions": [{"start_mm": 0, "end_mm": 50, "texture": {
            "kind": "texel", "pitch_db": pitch, "irregularity_db": -12.9, "seed": 7}}]}
    with _connect(pico.port) as b:
        assert b.stands
        n0 = b.status()["pushes"]
        for k, pitch in enumerate((1.5, 2.5, 3.5)):
            st = b.push(scene(pitch))
            assert b.link.standing and st["pushes"] == n0 + k + 1
            assert st["scene"]["regions"][0]["pitch_db"] == pitch
        ans = b.link.eval_frame(*protocol.staged_frame("pushed", [scene(99.0)], 0), 60)
        assert ans[0] == "err" and "pitch_db" in ans[1] and b.link.standing   # the board's
        with pytest.raises(ValueError, match="pitch_db"):     # the host's own check
            b.push(scene(99.0))
        # a frame calling pushed with two arguments too many: the board's TypeError, answered
        with pytest.raises(BoardError, match="TypeError"):
            b.link.eval_frame(*protocol.staged_frame("pushed", [scene(4.0), 1, 2], 0), 60)
        assert b.link.standing
        # a frame whose data has no room on the heap (200,000 bytes): the board reads
        # past it, answers the MemoryError and reads on
        with pytest.raises(BoardError, match="MemoryError"):
            b.link.eval_frame(b'[200000,23,["pushed",[],[],0,null]', b" " * 200000, 120)
        assert b.link.standing
        st = b.push(scene(4.5))
        assert st["scene"]["regions"][0]["pitch_db"] == 4.5
        assert b.link.exec("print(6 * 7)").strip() == "42" and not b.link.standing
        st2 = b.status()
        assert st2["scene"] == st["scene"] and st2["pushes"] == n0 + 4
        b.push(scene(5.5))
        assert b.link.standing
        b.link._close_port()                # the host vanished: no Ctrl-B, no empty line
        b.link.t = None
    r = mpremote(pico.port, "print(6 * 7)")
    assert r.returncode == 0 and "42" in r.stdout, r.stdout + r.stderr
    with _connect(pico.port) as b:
        st = b.status()
        assert st["running"] and st["scene"]["regions"][0]["pitch_db"] == 5.5
        assert st["pushes"] == n0 + 5 and st["faults"] == 0
        before = st["refreshes"]
        assert b.status()["refreshes"] > before
        b.push(scene(6.5))                  # and vanished again: the link itself next
        assert b.link.standing
        b.link._close_port()
        b.link.t = None
    with _connect(pico.port) as b:
        st = b.status()
        assert st["scene"]["regions"][0]["pitch_db"] == 6.5 and st["pushes"] == n0 + 6


# On the board: each text read by json.loads and by the C reader (scene_json);
# printed per text: (the same value or the same exception, the C read it itself)
_JSON_SAME = r"""
import json, _texelcore
def run(f, t):
    try:
        return ('ok', repr(f(t)))
    except Exception as e:
        return ('exc', type(e).__name__, str(e))
out = []
for t in %r:
    a = run(json.loads, t)
    c = run(_texelcore.scene_json, t)
    fast = c != ('ok', 'None')
    out.append((a == c or not fast, fast))
print(repr(out))
"""


def _json_cases(seed):
    """Texts for the C reader: (text, whether it must read it itself). Strict
    JSON as the host writes it (every bench scene, random documents with
    escapes, UTF-8, ints past 32 bits, exponents, float32's edges, 20 levels)
    and what it must leave to json.loads (a \\u escape, modjson's lenient
    commas and colons, syntax errors, 30 levels) - a number that is no number
    raises the same error from both."""
    import json as pyjson
    import random
    from bench.firmware import scene_list
    from texelpad.link import protocol
    from texelpad.link.board import host_check
    rng = random.Random(seed)
    texts = []
    for _, _, sc in scene_list({"positions": 19200, "dx_um": 5.3})[:12]:
        texts.append((protocol.scene_text(host_check(sc)), True))
    words = ["a", "", 'say "hi"', "back\\slash", "tab\t and\nnew", "caf\u00e9 \u2192",
             "sl/ash", "regions", "pitch_db"]
    nums = [0, -1, 7, 2 ** 31, -(2 ** 40), 10 ** 20, 0.0, -0.0, 1.5, -12.9, 6.3, 1e-45, 1e-38,
            3.4e38, 1e39, 1.7976931348623157e308, 123456789.123, 5e-324]

    def doc(d):
        r = rng.random()
        if d > 3 or r < 0.35:
            return rng.choice(nums + words + [None, True, False])
        if r < 0.65:
            return [doc(d + 1) for _ in range(rng.randrange(4))]
        return {rng.choice(words): doc(d + 1) for _ in range(rng.randrange(4))}
    docs = [d for d in (doc(0) for _ in range(80)) if d is not None]     # null: the C's None
    for d in docs[:60]:
        texts.append((pyjson.dumps(d, ensure_ascii=False, separators=(",", ":")), True))
    for d in docs[60:70]:
        texts.append((pyjson.dumps(d, ensure_ascii=False, indent=1), True))
    texts.append(("[" * 20 + "1" + "]" * 20, True))
    texts.append((' { "a" : [ 1 , 2.5e3 , -3E-2 ] , "b" : "x" } \r\n', True))
    for t in ['"\\u00e9"', '{"a" 1}', "[1 2]", '{"a":1,}', "[1,,2]", "{1:2}", "[" * 30 + "]" * 30,
              "", "[", '"abc', "tru", "nul", "[1]x", "{}}", '["a\x00b"]', '["a\\\x00"]']:
        texts.append((t, False))
    for t in ['{"a":1.2.3}', "[1e5e5]", "-", "[--1]", '{"b":1-2}']:
        texts.append((t, True))                     # the same ValueError from both
    return texts


def test_the_c_core_reads_a_scenes_json_as_json_loads_does(pico):
    """The firmware's C reader of a pushed scene's JSON (texelcore_api.h
    scene_json, texel/wire.py staged) gives json.loads's value - the same repr(),
    so the same types, float32s and dict order - or json.loads's own ValueError,
    and leaves what it does not read strictly to json.loads (_json_cases)."""
    import ast
    cases = _json_cases(21)
    with _connect(pico.port) as b:
        got = []
        for k in range(0, len(cases), 20):
            out = b.link.exec(_JSON_SAME % ([t for t, _ in cases[k:k + 20]],), timeout=300)
            got += ast.literal_eval(out.strip().splitlines()[-1])
    assert len(got) == len(cases)
    for (text, fast), (same, c_read) in zip(cases, got):
        assert same, text
        assert c_read == fast, (text, c_read)


def test_the_heap_hint_skips_the_holes_and_not_with_gc_disabled(pico):
    """texelcore_fw.h heap_hint (compat.skip_holes, before every push): after
    a collection the allocator's search starts in the holes; the hint moves it
    past them (and no further the second time), and does nothing while
    gc.disable() is on (no collection would look below it again)."""
    code = ("import gc, _texelcore as c\n_k = [bytearray(24) for _ in range(300)]\n"
            "_k = _k[::2]\ngc.collect()\n_a = c.heap_hint(64)\n_b = c.heap_hint(64)\n"
            "gc.collect()\ngc.disable()\n_d = c.heap_hint(64)\ngc.enable()\n_k = None\n"
            "print(repr((_a, _b, _d)))\n")
    with _connect(pico.port) as b:
        a, b2, d = ast.literal_eval(b.link.exec(code, timeout=60).strip().splitlines()[-1])
    assert a > 0 and b2 == 0 and d == 0, (a, b2, d)


def test_a_bad_push_is_refused_and_the_scene_kept(pico):
    from texelpad.link.transport import LinkError
    good = {"regions": [{"start_mm": 0, "end_mm": 50.88,
                         "texture": {"kind": "reference", "name": "4sin"}}]}
    with _connect(pico.port) as b:
        b.push(good)
        before = b.scene_source()
        for bad in ({"regions": [{"start_mm": 0, "end_mm": 50,
                                  "texture": {"kind": "reference", "name": "nope"}}]},
                    {"regions": [{"start_mm": 0, "end_mm": 50,
                                  "texture": {"kind": "texel", "pitch_db": 99}}]}):
            with pytest.raises((ValueError, LinkError)):
                b.push(bad)
            assert b.scene_source() == before and b.status()["running"]


def _texel_file(port):
    with _connect(port) as b:
        st = b.status()
        assert st["running"] and st["scene"]["regions"][0]["name"] == "4sin"   # what played
        return b.link.eval("import texel\nprint(repr(texel.__file__))")


def test_deploy_finds_the_firmware_and_rewrites_only_its_romfs(pico, capsys):
    code, out, err = run_cli(capsys, "deploy", "--port", pico.port)
    assert code == 0, err
    assert "texelpad firmware found (board pico" in err and "already holds this texelpad" in out
    assert "its frozen code is this texelpad's" in err
    # --force: this texelpad's code into the ROMFS, where it runs instead of the frozen copy
    # (frozen_boot.py), as it does when a host's texelpad is newer than the firmware's
    code, out, err = run_cli(capsys, "deploy", "--port", pico.port, "--force")
    assert code == 0, err
    assert "ROMFS partition rewritten" in out and "this texelpad's code" in out
    assert "restarted pico" in out
    assert _texel_file(pico.port) == "/rom/lib/texel/__init__.mpy"
    # and a plain deploy puts the partition back to the data: the frozen code runs again
    code, out, err = run_cli(capsys, "deploy", "--port", pico.port)
    assert code == 0, err
    assert "ROMFS partition rewritten" in out and "the code is the firmware's, frozen" in out
    assert _texel_file(pico.port) == "texel/__init__.py"


def test_a_partition_a_cut_off_deploy_left_is_repaired_by_the_next(pico, capsys):
    # the partition's first block erased, as a deploy cut off right after its erase leaves it:
    # no /rom, no firmware.json; the board still runs (its REPL), and deploy knows the
    # firmware by its build name and writes the partition whole
    from texelpad.link.board import connect
    with connect(pico.port, timeout=60) as b:
        b.stop()                        # as deploy does before it writes the partition
        b.link.exec("import vfs\n_d = vfs.rom_ioctl(2, 0)\ntry:\n vfs.umount('/rom')\n"
                    "except OSError:\n pass\n_d.ioctl(6, 0)")
        b.link.soft_reset()
        assert b.link.eval("import os\ntry:\n os.stat('/rom/firmware.json')\n print(True)\n"
                           "except OSError:\n print(False)") is False
    code, out, err = run_cli(capsys, "deploy", "--port", pico.port)
    assert code == 0, err
    assert "texelpad firmware found (board pico" in err and "ROMFS partition rewritten" in out
    with connect(pico.port, timeout=60) as b:
        st = b.start("pico")
        assert st["running"] and st["scene"]["regions"][0]["mode"] == "flash"   # 4sin from flash


def test_the_firmware_c_refresh_is_the_viper_refresh_for_every_kind(pico):
    """The firmware's C refresh as the Cortex-M0+ runs it (tests/gen/test_texel_core.py
    checks the x64 build) computes what refresh_viper.core computes on the same W:
    a constant, a reference in flash, a texel plan, samples tiled and stretched in
    place, samples and a 3-sample texel in chunks, gaps; the finger sweeping,
    jumping, dropping out and lifted. texel.app plays again afterwards."""
    scene = {"regions": [
        {"start_mm": 0, "end_mm": 10, "texture": {"kind": "constant", "level": 0.3}},
        {"start_mm": 10, "end_mm": 30, "texture": {"kind": "reference", "name": "2sin"}},
        {"start_mm": 30, "end_mm": 45, "texture": {"kind": "texel", "pitch_db": 5.0,
                                                    "irregularity_db": -9.0, "seed": 2}},
        {"start_mm": 46, "end_mm": 60, "texture": {"kind": "samples", "fit": "stretch",
                                                    "u16": [0, 65535, 7, 40000]}},
        {"start_mm": 60, "end_mm": 70, "texture": {"kind": "samples", "fit": "tile",
                                                    "u16": [9, 65535, 30000]}},
        {"start_mm": 70, "end_mm": 80, "texture": {"kind": "samples", "fit": "tile",
                                                    "u16": list(range(0, 65535, 97))}},
        {"start_mm": 82, "end_mm": 101, "texture": {
            "kind": "texel", "pitch_db": 12.0, "irregularity_db": -9.0, "seed": 2,
            "texel_samples": 3}}]}
    with _connect(pico.port) as b:
        out = b.link.exec(refresh_same.script("pico", scene, 900, stop_app=True), timeout=300)
        assert b.status()["running"]
    same, n, first, kinds, build = ast.literal_eval(out.strip().splitlines()[-1])
    assert build == "firmware" and kinds == [0, 1, 2, 3, 4, 5], (build, kinds)
    assert same == n == 900, first


def test_texelpad_virtual_boots_your_own_firmware(fw, tmp_path, capsys):
    """`texelpad virtual --chip rp2040 --firmware FILE.uf2` (issue 30): the maker's own
    build booted on the emulated Pico from the command line, its ROMFS partition in the
    flash as a Pico's UF2 bootloader writes it; nothing deployed (the firmware carries
    texelpad), its power-up scene playing, status through the port it prints. And the
    flag's refusals: without --chip, a missing file (exit 2, one line each)."""
    import os
    import signal
    import subprocess
    import sys
    from texelpad.sim.emulated import why_not
    code, out, err = run_cli(capsys, "virtual", "--firmware", str(fw.uf2))
    assert code == 2 and "--firmware: boots a .uf2 on an emulated chip: give --chip rp2040" \
        in err and err.count("\n") == 1, err
    code, out, err = run_cli(capsys, "virtual", "--chip", "rp2040", "--firmware",
                             str(tmp_path / "nope.uf2"))
    assert code == 2 and "nope.uf2: no such file" in err and err.count("\n") == 1, err
    if why_not():
        pytest.skip(why_not())
    exe = os.path.join(os.path.dirname(sys.executable), "texelpad")
    env = dict(os.environ, TEXELPAD_RUNTIME_DIR=str(tmp_path / "run"))
    p = subprocess.Popen([exe, "virtual", "--chip", "rp2040", "--firmware", str(fw.uf2)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        port = p.stdout.readline().strip()
        assert port.startswith("/dev/"), (port, p.stderr.read() if p.poll() is not None else "")
        r = subprocess.run([exe, "status", "--port", port, "--timeout", "60", "--json"],
                           capture_output=True, text=True, env=env, timeout=300)
        assert r.returncode == 0, r.stderr
        st = json.loads(r.stdout)
        assert st["running"] and st["board"] == "pico" and st["refresh"] == "viper-irq", st
        print("\nvirtual --chip rp2040 --firmware: %s, %s refreshes, scene %s"
              % (st["firmware"], st["refreshes"], [x["kind"] for x in st["scene"]["regions"]]))
    finally:
        p.send_signal(signal.SIGTERM)
        out, err = p.communicate(timeout=120)
    assert p.returncode == 0, err
    assert "the firmware carries texelpad: nothing to deploy" in err and "deploy:" not in err, err

"""A lean port (compat.PORT_TABLE "lean": CircuitPython, which compiles the
sources into its heap): app.tidy() forgets the board files' checks
(texel.runtime.boards) after a start, so their code is freed while the display
plays; the next start imports them again. Checked on CPython (the code really becomes garbage) and on the
real CircuitPython unix build (the heap it frees); the figures on the chip:
bench/results/circuitpython.txt."""
from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

import pytest

from texel import compat
from texelpad import toolchain

from support import mpy

ROOT = Path(__file__).resolve().parents[2]
DEVICE = ROOT / "device" / "texel"
TEXEL = {"kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7, "v": 2}


def _top_imports(path: Path) -> set[str]:
    """Modules a device file imports at its top level (run at import)."""
    rel = path.relative_to(DEVICE.parent).with_suffix("")
    pkg = list(rel.parts)[:-1]          # a module's package; an __init__'s own
    out = set()
    tree = ast.parse(path.read_text())
    for node in tree.body:
        nodes = [node]
        if isinstance(node, ast.Try):
            nodes = node.body + [n for h in node.handlers for n in h.body]
        for n in nodes:
            if isinstance(n, ast.ImportFrom):
                base = pkg[:len(pkg) - (n.level - 1)] if n.level else []
                mod = ".".join(base + ([n.module] if n.module else []))
                out.add(mod)
                out.update(mod + "." + a.name for a in n.names)
            elif isinstance(n, ast.Import):
                out.update(a.name for a in n.names)
    return out


# what a lean port forgets together (texel.app._PAINTER: the brush painter's modules)
PAINTER = ("texel.gen.brush", "texel.gen.brush_viper", "texel.gen.brush_parts")


@pytest.mark.parametrize("forgotten", ["texel.runtime.boards", *PAINTER])
def test_no_module_imports_what_a_lean_port_forgets_at_its_top(forgotten):
    # else forgetting it would free nothing (and a second import would hold it twice);
    # a module forgotten with it may (brush_parts imports brush)
    together = PAINTER if forgotten in PAINTER else ()
    users = sorted(str(p.relative_to(DEVICE)) for p in DEVICE.rglob("*.py")
                   if forgotten in _top_imports(p) and
                   "texel." + str(p.relative_to(DEVICE).with_suffix("")).replace("/", ".")
                   not in together)
    assert users == []


def test_the_painter_forgotten_together_is_apps():
    from texel import app
    assert tuple(app._PAINTER) == PAINTER


CPYTHON_SCRIPT = r"""
import gc, json, sys, weakref
sys.path.insert(0, %(device)r)
import texel.app as app
app.LEAN = True
out = {}
app.start("virtual", app.full_screen(%(tex)r), report=False)
boards = sys.modules["texel.runtime.boards"]
code = weakref.ref(boards.validate)         # a function of the module: its code
del boards
out["tidied"] = app.tidy()
gc.collect()
out["gone"] = ["texel.runtime.boards" not in sys.modules,
               not hasattr(sys.modules["texel.runtime"], "boards"), code() is None]
st = app.push(app.full_screen(dict(%(tex)r, seed=8)))
out["pushed"] = st["scene"]["regions"][0]["seed"]
app.tidy()
out["after_push"] = "texel.runtime.boards" in sys.modules
out["running"] = app.status()["running"]
app.stop()
app.start("virtual", app.full_screen(%(tex)r), report=False)     # imported again
out["again"] = app.status()["board"]
app.stop()
print(json.dumps(out))
"""


def test_tidy_forgets_the_board_checks_after_a_start_and_they_come_back():
    # a fresh interpreter: in the test process other modules hold texel.runtime.boards
    p = subprocess.run([sys.executable, "-c", CPYTHON_SCRIPT % {"device": str(DEVICE.parent),
                                                                 "tex": TEXEL}],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout.strip().splitlines()[-1])
    assert out["tidied"] is True
    assert out["gone"] == [True, True, True]    # nothing held its code: freed
    assert out["pushed"] == 8
    assert out["after_push"] is False           # a push does not need them
    assert out["running"] is True and out["again"] == "virtual"


def test_a_port_that_is_not_lean_keeps_them(monkeypatch):
    import texel.app as app
    monkeypatch.setattr(app, "LEAN", False)
    app.start("virtual", app.full_screen(TEXEL), report=False)
    try:
        app.tidy()
        assert "texel.runtime.boards" in sys.modules
    finally:
        app.stop()


def test_the_port_table_says_which_ports_are_lean():
    assert {p: r["lean"] for p, r in compat.PORT_TABLE.items()} == {
        "rp2": False, "stm32": False, "circuitpython": True, "virtual": False}
    assert compat.LEAN is False                 # CPython: a development host


CPY_SCRIPT = r"""
import gc, sys, json
import texel.app as app
from texel import compat
out = {"lean": compat.LEAN}
app.start("pico_cpy", app.full_screen(%(tex)r), report=False)
gc.collect()
out["started"] = gc.mem_free()
out["loaded"] = "texel.runtime.boards" in sys.modules
out["tidied"] = app.tidy()
gc.collect()
out["after"] = gc.mem_free()
out["gone"] = "texel.runtime.boards" not in sys.modules
st = app.push(app.full_screen(dict(%(tex)r, seed=8)))
out["pushed"] = st["scene"]["regions"][0]["seed"]
app.stop()
app.start("pico_cpy", app.full_screen(%(tex)r), report=False)
out["again"] = app.status()["running"]
app.stop()
print(json.dumps(out))
"""


@pytest.mark.instruments
def test_circuitpython_frees_the_board_checks_heap():
    exe = toolchain.interpreter("circuitpython")
    if exe is None:
        pytest.skip("CircuitPython is not on this machine (../shared/instruments)")
    out = mpy.run_json(CPY_SCRIPT % {"tex": TEXEL}, exe=exe, extra_path=mpy.FAKES,
                       heapsize="4M", timeout=300)
    assert out["lean"] is True and out["loaded"] is True
    assert out["tidied"] is True and out["gone"] is True
    # the board checks' compiled code, freed (13 KB on the emulated Pico)
    assert out["after"] - out["started"] >= 8000, out
    print("\nCircuitPython (unix build): %d B free started, %d B after tidy()"
          % (out["started"], out["after"]))
    assert out["pushed"] == 8 and out["again"] is True


RULE_SCRIPT = r"""
import json, sys, types
sys.path.insert(0, %(device)r)
sys.implementation.name = %(impl)r     # (only what compat reads at its import)
sys.platform = %(platform)r
if %(romfs)r:
    sys.modules["vfs"] = types.SimpleNamespace(rom_ioctl=lambda *a: 0)
from texel import compat
import texel.app as app
print(json.dumps([compat.PORT, bool(compat.ROM), compat.LEAN, app.FORGET_PAINTER]))
"""


@pytest.mark.parametrize("impl, platform, romfs, want", [
    # stock MicroPython + texelpad deploy: lean, and the painter is forgotten
    ("micropython", "rp2", False, ["rp2", False, True, True]),
    ("micropython", "rp2", True, ["rp2", True, False, False]),     # the texelpad firmware
    ("micropython", "pyboard", False, ["stm32", False, True, True]),
    ("micropython", "pyboard", True, ["stm32", True, False, False]),
    # CircuitPython: lean, but the painter stays (it would compile it again)
    ("circuitpython", "RP2040", False, ["circuitpython", False, True, False]),
])
def test_a_port_without_its_romfs_is_lean(impl, platform, romfs, want):
    """compat: a port the texelpad firmware exists for, running without its
    ROMFS (stock MicroPython: deploy's .mpy files load into the heap) is lean
    as CircuitPython is; with the ROMFS its code stays in flash. app: a lean
    port forgets the brush painter while no brush plays, but CircuitPython."""
    p = subprocess.run([sys.executable, "-c", RULE_SCRIPT % {
        "device": str(DEVICE.parent), "impl": impl, "platform": platform, "romfs": romfs}],
        capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stdout.strip().splitlines()[-1]) == want


def _scene(level):
    import texel.app as app
    return app.full_screen({"kind": "constant", "level": level})


def test_start_with_no_room_for_the_board_checks_stops_the_display_first(monkeypatch):
    """A lean port whose playing scene leaves no room to load the board checks
    (a MemoryError; a stock Pico playing 16 texel regions, bench/firmware.py
    --stock): start() stops the display, loads them in the room that made and
    starts - and when the start then fails, the display that played plays again."""
    import texel.app as app
    real = app._checked_board
    calls = []

    def tight(name):
        calls.append(app._rt is not None)
        if app._rt is not None:
            raise MemoryError("memory allocation failed, allocating 876 bytes")
        return real(name)
    app.start("virtual", _scene(0.25), report=False)
    try:
        monkeypatch.setattr(app, "_checked_board", tight)
        st = app.start("virtual", _scene(0.75))
        assert calls == [True, False]
        assert st["running"] and st["scene"]["regions"][0]["amplitude"] == 49151
        # the retry fails (a board file that is not there): what played plays again
        calls.clear()
        with pytest.raises(ValueError) as e:
            app.start("no_such_board", _scene(0.5))
        assert calls == [True, False, False]        # the retry, then the restart's own
        assert str(e.value).startswith("board 'no_such_board' did not start (")
        assert str(e.value).endswith("the display plays what it played before (board 'virtual')")
        st = app.status()
        assert st["running"] and st["scene"]["regions"][0]["amplitude"] == 49151
        # a bad scene after the stop: the same
        with pytest.raises(ValueError) as e:
            app.start("virtual", {"regions": "no"})
        assert str(e.value).endswith("the display plays what it played before (board 'virtual')")
        assert app.status()["scene"]["regions"][0]["amplitude"] == 49151
        # an idle display (a push that found no room even in the playing scene's:
        # app._make_room) is idle again after a failed start, not the default scene
        app._drop_playing(app._rt)
        with pytest.raises(ValueError) as e:
            app.start("no_such_board", _scene(0.5))
        assert str(e.value).endswith("the display plays what it played before (board 'virtual')")
        st = app.status()
        assert st["running"] and st["scene"] is None, st["scene"]
        # nothing playing: the MemoryError is the caller's
        app.stop()
        monkeypatch.setattr(app, "_checked_board", lambda name: (_ for _ in ()).throw(
            MemoryError("no room")))
        with pytest.raises(MemoryError):
            app.start("virtual", _scene(0.5))
    finally:
        monkeypatch.setattr(app, "_checked_board", real)
        app.stop()


PAINTER_SCRIPT = r"""
import gc, json, sys, weakref
sys.path.insert(0, %(device)r)
import texel.app as app
app.LEAN = True
app.FORGET_PAINTER = True       # (a stock Pico's: app.py)
brush = {"kind": "brush", "brush": {"k": [2.0] * 97, "lam": [0.5] + [0.05] * 96}, "seed": 1}
out = {}
app.start("virtual", app.full_screen(brush), report=False)
app.tidy()
out["kept_while_playing"] = "texel.gen.brush" in sys.modules
code = weakref.ref(sys.modules["texel.gen.brush"].paint)
app.push(app.full_screen({"kind": "constant", "level": 0.5}))
out["forgot"] = app._forget_builders()
gc.collect()
out["gone"] = ["texel.gen.brush" not in sys.modules, code() is None]
st = app.push(app.full_screen(dict(brush, seed=2)))     # imported again
out["again"] = [st["scene"]["regions"][0]["seed"], "texel.gen.brush" in sys.modules]
app.stop()
print(json.dumps(out))
"""


def test_tidy_forgets_the_brush_painter_while_no_brush_plays():
    """A lean port that loads .mpy (a stock Pico: gen/brush.py is 22 KB of its
    heap; app.FORGET_PAINTER) keeps the painter only while a brush plays; a
    brush push imports it again. Not CircuitPython (it would compile it again)."""
    p = subprocess.run([sys.executable, "-c", PAINTER_SCRIPT % {"device": str(DEVICE.parent)}],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout.strip().splitlines()[-1])
    assert out["kept_while_playing"] is True
    assert out["forgot"] is True and out["gone"] == [True, True]
    assert out["again"] == [2, True]



REFUSED_SCRIPT = r"""
import json, sys
sys.path.insert(0, %(device)r)
import texel.app as app
from texel.runtime import scene as S
app.LEAN = True
app.FORGET_PAINTER = True       # (a stock Pico's: app.py)
old = app.full_screen({"kind": "reference", "name": "pink"})
brush = {"kind": "brush", "brush": {"k": [2.0] * 97, "lam": [0.5] + [0.05] * 96}, "seed": 1}
app.start("virtual", old, report=False)
real = S.build
seen = []
def build(canonical, *a, **kw):
    # the brush's build runs out of memory, beside the old scene and in its room
    # alike (after its painter was imported); what is loaded when the old one is
    # built again is recorded
    if canonical["regions"][0]["texture"]["kind"] == "brush":
        import texel.gen.brush
        seen.append(["brush", kw.get("words", True)])
        raise S.OutOfMemory("scene: out of memory while building")
    seen.append(["old", "texel.gen.brush" in sys.modules])
    return real(canonical, *a, **kw)
S.build = build
out = {}
try:
    app.push(app.full_screen(brush))
except ValueError as e:
    out["refused"] = str(e)
out["seen"] = seen
out["playing"] = app._rt.refresh.scene.source["regions"][0]["texture"]["kind"]
app.stop()
# an old brush keeps its painter through a refused push: it is built again with it
S.build = real
app.start("virtual", app.full_screen(brush), report=False)
big = app.full_screen({"kind": "constant", "level": 0.5})
def build2(canonical, *a, **kw):
    if canonical is big or canonical["regions"][0]["texture"]["kind"] == "constant":
        raise S.OutOfMemory("scene: out of memory while building")
    seen2.append("texel.gen.brush" in sys.modules)
    return real(canonical, *a, **kw)
seen2 = []
S.build = build2
try:
    app.push(big)
except ValueError as e:
    out["refused2"] = str(e)
out["old_brush_kept_painter"] = seen2
out["playing2"] = app._rt.refresh.scene.source["regions"][0]["texture"]["kind"]
app.stop()
print(json.dumps(out))
"""


def test_a_refused_brush_forgets_its_painter_before_the_old_scene_is_built_again():
    """A brush that fits neither beside the playing scene nor in its room (a
    stock Pico, bench/firmware.py --stock): the painter its build imported (22
    KB there) is forgotten before the old scene is built again, which then
    plays on; the first try, which the room's try follows, does not measure the
    heap for its message (build's words=False: trial allocations, each failing
    one a collection, ~0.45 s of a push on a stock Pico)."""
    p = subprocess.run([sys.executable, "-c", REFUSED_SCRIPT % {"device": str(DEVICE.parent)}],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout.strip().splitlines()[-1])
    assert out["seen"] == [["brush", False], ["brush", True], ["old", False]]
    assert out["refused"].endswith("that scene was built again and plays on")
    assert out["playing"] == "reference"
    # an old brush is built again with its painter still loaded (not forgotten, then
    # loaded again while the display is idle)
    assert out["old_brush_kept_painter"] == [True]
    assert out["refused2"].endswith("that scene was built again and plays on")
    assert out["playing2"] == "brush"

"""Fuzz target "link": the host's link (texelpad.link.transport.Link, Board,
connect) and the board commands of the command line against a board that
misbehaves (tests/fuzz/fakeboard.py: the REPL, raw paste and the image's
answers, with faults in the byte stream, the answers and the port drawn per
case), on a virtual clock - a 30 s timeout costs no real time.

A case: a plan for the board, a timeout (0.05 .. 40 s), and a session -
Link(port) then requests on the link (eval, exec, a call, write_file,
resync), or connect(port) then Board requests (status, push of a scene or
texel parameters - with long samples regions as uploads -, start, stop,
scene_source, stream, telemetry, monitor, render_u16, finger,
board_display, eval, write_file, resync), or a board command of the command
line (push, status, stop, monitor) with --port.

Properties, per case:
- every request returns or raises LinkError (a subclass: LinkTimeout,
  NotTexelpad, NoBoard, PortBusy, DeviceError ...) - nothing else, no hang;
  close() never raises;
- every read of the port happens while a deadline runs, and never after it;
- the link prints nothing (stdout, stderr);
- the command line exits 0, 1 or 2 and fails in one line "texelpad ...:
  error: ..." without a traceback;
- a board with no fault and a timeout of 2 s or more answers every request
  correctly: eval the literal sent, exec the text printed, write_file the
  bytes written, render_u16 the host's own map, status a running display;
  the command line exits 0.
"""
from __future__ import annotations

import contextlib
import io
import json
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, strategies as st

import fakeboard as fb
import fuzzlib
import texel
import texel.app
import texelpad
from texelpad import cli
from texelpad.link import board as board_mod
from texelpad.link.transport import Link, LinkError

FUZZ_TARGET = "link"
pytestmark = pytest.mark.fuzz
PORT = "/dev/ttyFUZZ0"
TIMEOUTS = [0.05, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 12.0, 30.0, 40.0]
SMALL_SCENE = {"regions": [{"start_mm": 0, "end_mm": 10.6,
                            "texture": {"kind": "constant", "level": 0.5}}]}


def _idx(draw, n: int) -> int:
    return draw(st.integers(0, 2 ** 24)) % n


# --- plans -------------------------------------------------------------------------------------

FRAMING = [b"\x04", b">", b"R", b"\x01", b"O"]
JUNK_ANSWERS = [b"{[]: 1}\r\n", b"{{}}\r\n", b"-" * 100_000 + b"1\r\n", b"(" * 300 + b"\r\n",
                b"[" * 150 + b"]" * 150 + b"\r\n", b"1" * 5000 + b"\r\n", b"('ok',)\r\n",
                b"('ok', 1, 2)\r\n", b"42\r\n", b"None\r\n", b"('err', 5)\r\n", b"('err', None)\r\n",
                b"('ok', {'running': 'yes'})\r\n", b"('ok', {'running': True})\r\n",
                b"('ok', [1, 2, 3])\r\n", b"('ok', None)\r\n", b"('ok', b'!!')\r\n",
                b"('ok', 'x')\r\n", b"('ok', ([(1, 2)], 0))\r\n", b"('ok', ([], 'lost'))\r\n",
                b"\x00\r\n", b"\xff\xfe\xfd\r\n", b"", b"\r\n", b"print(1)\r\n", b"'\r\n",
                b"(('missing', 'x'), 'micropython', (1, 28), 6, 'rp2')\r\n",
                b"((1, '0.1.0'), 'micropython', 5, 6, 'rp2')\r\n",
                b"((2, '9.9.9'), 'micropython', (1, 28, 0), 6, 'rp2')\r\n",
                b"(('x', 1), 'micropython', (1, 28, 0), 6, 'rp2')\r\n",
                b"((1, None), 'micropython', (1, 28, 0), 6, 'rp2')\r\n",
                b"((), 'micropython', (1, 28, 0), 6, 'rp2')\r\n",
                b"('ok', {'display': {'positions': -1, 'dx_um': 5.3}, 'running': True})\r\n",
                b"('ok', {'display': None, 'running': True})\r\n",
                b"('ok', {'running': True})\r\n", b"\x04\r\n", b">\r\n", b"OK\r\n",
                b"raw REPL; CTRL-B to exit\r\n>", b"('ok', {'regions': 5})\r\n",
                b"('ok', {'regions': [{'texture': {'kind': 'samples', 'u16': 3}}]})\r\n"]
ERRORS = [b"Traceback (most recent call last):\r\n  File \"<stdin>\", line 1\r\nMemoryError: \r\n",
          b"\xff\xfe invalid utf-8 \x80\r\n", b"x", b"\x04", b"Traceback\r\n" * 2000]


@st.composite
def junk_literal(draw) -> bytes:
    v = draw(st.recursive(
        st.one_of(st.none(), st.booleans(), st.integers(), st.floats(), st.text(max_size=10),
                  st.binary(max_size=10)),
        lambda ch: st.one_of(st.lists(ch, max_size=4), st.tuples(ch, ch),
                             st.dictionaries(st.text(max_size=5), ch, max_size=3),
                             st.tuples(st.sampled_from(["ok", "err"]), ch)),
        max_leaves=10))
    return repr(v).encode("utf-8", "replace") + b"\r\n"


@st.composite
def answer_fault(draw):
    kind = ["out", "out", "out+", "+out", "err", "slow", "hang", "huge", "chatty", "reset"][_idx(draw, 10)]
    if kind in ("out", "out+", "+out"):
        arg = draw(st.one_of(st.sampled_from(JUNK_ANSWERS), junk_literal(), st.binary(max_size=30)))
    elif kind == "err":
        arg = draw(st.one_of(st.sampled_from(ERRORS), st.binary(min_size=1, max_size=30)))
    elif kind == "slow":
        arg = draw(st.sampled_from([0.01, 0.1, 0.5, 1.0, 3.0, 11.0, 35.0, 100.0]))
    elif kind == "huge":
        arg = draw(st.sampled_from([1000, 20_000, 300_000]))
    elif kind == "chatty":
        arg = draw(st.sampled_from([b"x", b"tick\r\n", b"\x04", b">", b"\x04>"]))
    else:
        arg = None
    return kind, arg


@st.composite
def stream_fault(draw):
    if _idx(draw, 2):
        trig = ("at", draw(st.one_of(st.integers(0, 60), st.integers(0, 3000))))
    else:
        trig = ("nth", FRAMING[_idx(draw, len(FRAMING))], draw(st.integers(1, 12)))
    kind = ["cut", "insert", "delete", "flip", "stall", "flood"][_idx(draw, 6)]
    arg = {"cut": lambda: None,
           "insert": lambda: draw(st.one_of(st.binary(min_size=1, max_size=20),
                                            st.sampled_from(FRAMING + [b"OK", b"R\x01", b"\x04\x04>",
                                                                       b"raw REPL; CTRL-B to exit\r\n>"]))),
           "delete": lambda: draw(st.integers(1, 5)),
           "flip": lambda: draw(st.integers(0, 255)),
           "stall": lambda: draw(st.sampled_from([0.05, 0.5, 2.0, 15.0, 60.0])),
           "flood": lambda: draw(st.sampled_from([b"x", b"\x04", b">", b"spam\r\n", b"\x00\xff"]))}[kind]()
    return trig, kind, arg


@st.composite
def plans(draw):
    clean = _idx(draw, 4) == 0                    # a quarter: a board without faults
    p = fb.Plan()
    p.start = "friendly" if clean else ["friendly", "friendly", "raw", "busy"][_idx(draw, 4)]
    p.paste = ["ok", "ok", "ok", "refuse", "old"][_idx(draw, 5)]
    p.window = draw(st.sampled_from([32, 64, 128, 256, 256, 512, 4096, 65535]))
    if not clean and _idx(draw, 8) == 0:
        p.window = draw(st.sampled_from([0, 1, 2, 3]))
    p.byte_s = draw(st.sampled_from([1e-6, 1e-5, 1e-5, 8.7e-5]))
    p.latency = draw(st.sampled_from([0.0, 0.0, 0.001, 0.02]))
    p.running = _idx(draw, 5) != 0
    if not clean:
        for _ in range(draw(st.sampled_from([0, 1, 1, 2, 3]))):
            p.stream_faults.append(draw(stream_fault()))
        for _ in range(draw(st.sampled_from([0, 1, 1, 2]))):
            p.answers[draw(st.integers(0, 8))] = draw(answer_fault())
        for _ in range(draw(st.sampled_from([0, 0, 0, 1]))):
            op = ["probe", "open", "read", "write"][_idx(draw, 4)]
            how = ["busy", "missing", "denied", "other"][_idx(draw, 4)] if op == "probe" else \
                ["unplugged", "oserror", "timeout"][_idx(draw, 3)]
            p.port_faults.append((op, draw(st.integers(1, 40)) if op in ("read", "write") else 1,
                                  how, draw(st.booleans())))
    return p


# --- sessions ------------------------------------------------------------------------------------

TEXEL = {"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7}


@st.composite
def scene_to_push(draw):
    how = _idx(draw, 5)
    if how == 0:
        return SMALL_SCENE
    if how == 1:
        return {"regions": [{"start_mm": 0, "end_mm": 50.88, "texture": {"kind": "reference", "name": "4sin"}},
                            {"start_mm": 50.88, "end_mm": 101.76, "texture": dict(kind="texel", **TEXEL)}]}
    if how == 2:                                  # a long samples region: an upload
        m = draw(st.sampled_from([513, 2049, 5000]))
        return {"regions": [{"start_mm": 0, "end_mm": 20, "texture": {
            "kind": "samples", "u16": [(37 * i) % 65536 for i in range(m)]}}]}
    if how == 3:
        return {"regions": [{"start_mm": 0, "end_mm": 5, "texture": {
            "kind": "samples", "values": [0.0, 0.5, 1.0], "fit": "stretch"}}], "name": "fuzz"}
    return {"regions": [{"start_mm": 1, "end_mm": 2, "texture": {"kind": "texel", "pitch_db": 3.0,
                                                                 "irregularity_db": -10.0}}]}


LITERALS = st.recursive(st.one_of(st.none(), st.booleans(), st.integers(-2 ** 63, 2 ** 63),
                                  st.floats(allow_nan=False, allow_infinity=False),
                                  st.text(max_size=20)),
                        lambda ch: st.one_of(st.lists(ch, max_size=4),
                                             st.dictionaries(st.text(max_size=4), ch, max_size=3)),
                        max_leaves=8)


@st.composite
def board_op(draw):
    k = _idx(draw, 15)
    if k == 0:
        return ("status",)
    if k == 1:
        return ("push", draw(scene_to_push()))
    if k == 2:
        return ("push_texel", dict(TEXEL, seed=draw(st.integers(0, 99))))
    if k == 3:
        return ("start", draw(st.sampled_from(["virtual", "virtual", "nope"])),
                draw(st.sampled_from([None, SMALL_SCENE])))
    if k == 4:
        return ("stop",)
    if k == 5:
        return ("scene_source",)
    if k == 6:
        return ("stream", draw(st.sampled_from([0, 125, 2083])))
    if k == 7:
        return ("telemetry",)
    if k == 8:
        return ("monitor", draw(st.sampled_from([0.0, 0.03, 0.2])))
    if k == 9:
        return ("render_u16", dict(TEXEL, length_samples=draw(st.integers(1, 300))),
                draw(st.sampled_from([None, "int", "pure"])))
    if k == 10:
        return ("finger", [(0.0, None), (10.0, 2.0), (50.0, None)])
    if k == 11:
        return ("board_display", draw(st.sampled_from(["virtual", "pico", "nope"])))
    return link_op_of(draw, k - 12)


def link_op_of(draw, k: int):
    if k == 0:
        return ("eval", draw(LITERALS))
    if k == 1:
        return ("write_file", draw(st.sampled_from(["x.bin", "/lib/t.py", "a b'\\\n.txt"])),
                draw(st.binary(max_size=3000)), draw(st.sampled_from([7, 256, 2048])))
    return ("resync",)


@st.composite
def link_op(draw):
    k = _idx(draw, 5)
    if k < 3:
        return link_op_of(draw, k)
    if k == 3:
        # (a \x04 in a board's output ends its framing: the raw REPL cannot carry it)
        return ("exec", draw(st.text(max_size=30)).replace("\x04", ""))
    return ("call_status",)


@st.composite
def sessions(draw):
    kind = ["link", "board", "board", "board", "cli"][_idx(draw, 5)]
    if kind == "link":
        return kind, draw(st.lists(link_op(), max_size=4))
    if kind == "board":
        return kind, (draw(st.booleans()), draw(st.lists(board_op(), max_size=4)))
    cmd = ["push", "push", "status", "stop", "monitor"][_idx(draw, 5)]
    argv = [cmd, "--port", PORT]
    if cmd == "push":
        argv += draw(st.sampled_from([["--pitch-db", "6", "--irregularity-db", "-10"],
                                      ["--reference", "4sin"], ["--constant", "0.25"],
                                      ["--scene", "split-4sin"], ["--scene", "{long}"]]))
        if _idx(draw, 3) == 0:
            argv += ["--board", "virtual"]
    if cmd == "monitor":
        argv += ["--seconds", "0.05"]
    if cmd in ("push", "status") and _idx(draw, 3) == 0:
        argv.append("--json")
    return kind, argv


# --- running a case ---------------------------------------------------------------------------------

class Broken(AssertionError):
    def __init__(self, text: str, kind: str = ""):
        super().__init__(text)
        self.kind = kind


def expect_clean(op: tuple, value, world: fb.World) -> None:
    """What a faultless board must answer."""
    name = op[0]
    if name == "eval":
        if value != op[1]:
            raise Broken("eval of %s answered %s" % (fuzzlib.short(op[1]), fuzzlib.short(value)))
    elif name == "exec":
        if value != op[1].replace("\n", "\r\n") + "\r\n":
            raise Broken("exec printed %r, expected %r" % (value, op[1]))
    elif name == "write_file":
        if world.device.files.get(op[1]) != op[2]:
            raise Broken("write_file: the board holds %s, not the %d bytes written"
                         % (fuzzlib.short(world.device.files.get(op[1])), len(op[2])))
    elif name == "render_u16":
        want = np.asarray(texel.render_u16(op[1], engine=op[2]), dtype=np.uint16)
        if not np.array_equal(value, want):
            raise Broken("render_u16 answered another map")
    elif name in ("status", "call_status"):
        if not isinstance(value, dict) or "running" not in value:
            raise Broken("status answered %s" % fuzzlib.short(value))


def run_op(op: tuple, b, link):
    name = op[0]
    if name == "status":
        return b.status()
    if name == "push":
        return b.push(op[1])
    if name == "push_texel":
        return b.push_texel(op[1])
    if name == "start":
        return b.start(op[1], op[2])
    if name == "stop":
        return b.stop()
    if name == "scene_source":
        return b.scene_source()
    if name == "stream":
        return b.stream(op[1])
    if name == "telemetry":
        return b.telemetry()
    if name == "monitor":
        return list(b.monitor(op[1], rate_hz=125))
    if name == "render_u16":
        return b.render_u16(op[1], engine=op[2])
    if name == "finger":
        return b.finger(op[1])
    if name == "board_display":
        return board_mod.board_display(b, op[1])
    if name == "eval":
        return link.eval("print(repr(%r))" % (op[1],))
    if name == "exec":
        return link.exec("print(%r)" % (op[1],))
    if name == "write_file":
        return link.write_file(op[1], op[2], chunk=op[3])
    if name == "resync":
        return link.resync()
    if name == "call_status":
        return link.call("texel.app", "status")
    raise AssertionError(name)


# a request the board may refuse although nothing is wrong with the link
SEMANTIC = ("not running", "the board refused", "did not start", "unknown", "no such",
            "is not running", "board 'nope'", "nope")


def _semantic(e: LinkError) -> bool:
    from texelpad.link.transport import DeviceError
    return isinstance(e, DeviceError) or any(w in str(e) for w in SEMANTIC)


def session(world: fb.World, timeout: float, kind: str, spec, tmp: Path) -> list[str]:
    """Run one session; returns the outcome words. Raises Broken (or what
    the code under test raised) on a broken property."""
    clean = world.plan.clean() and timeout >= 2.0
    outcomes = []
    if kind == "cli":
        argv = [a.replace("{long}", str(tmp / "long.json")) for a in spec] + ["--timeout", repr(timeout)]
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = cli.main(argv)
            except SystemExit as e:
                code = e.code
        err = err.getvalue()
        # (in-process, a host traceback is an exception out of main(); a
        # "Traceback" in stderr is the board's, inside an error message)
        if code not in (0, 1, 2):
            raise Broken("%s: exit %r, stderr %r" % (argv[0], code, err[-600:]), "exit")
        if code != 0:
            lines = err.strip().split("\n")
            if len(lines) != 1 or ": error: " not in lines[0]:
                raise Broken("%s: exit %d with stderr %r (expected one error line)"
                             % (argv[0], code, err[:600]), "lines")
        if clean and code != 0 and not (code == 1 and (not world.plan.running or argv[0] == "monitor")):
            raise Broken("%s on a faultless board: exit %d: %s" % (argv[0], code, err.strip()[:300]))
        return ["cli %s: exit %d" % (argv[0], code)]
    link = b = None
    try:
        if kind == "link":
            link = Link(PORT, timeout=timeout)
            ops = spec
        else:
            check, ops = spec
            b = texelpad.connect(PORT, timeout=timeout, check=check)
            link = b.link
    except LinkError as e:
        if clean:
            raise Broken("opening a faultless board failed: %s: %s" % (type(e).__name__, e))
        return ["open: %s" % type(e).__name__]
    outcomes.append("open: ok")
    try:
        for op in ops:
            try:
                value = run_op(op, b, link)
            except LinkError as e:
                if clean and not _semantic(e):
                    raise Broken("%s on a faultless board: %s: %s" % (op[0], type(e).__name__, e))
                outcomes.append("%s: %s" % (op[0], type(e).__name__))
                continue
            if clean:
                expect_clean(op, value, world)
            outcomes.append("%s: ok" % op[0])
    finally:
        (b or link).close()
    return outcomes


@st.composite
def cases(draw):
    return draw(plans()), draw(st.sampled_from(TIMEOUTS)), draw(sessions())


@pytest.fixture(scope="module")
def tmp():
    """A temporary working directory with a scene file of a long samples
    region (pushed as an upload); texel.app stopped afterwards."""
    d = Path(tempfile.mkdtemp(prefix="texelpad-fuzz-link-"))
    long = {"regions": [{"start_mm": 0, "end_mm": 30, "texture": {
        "kind": "samples", "u16": [(91 * i) % 65536 for i in range(6000)], "fit": "tile"}}]}
    (d / "long.json").write_text(json.dumps(long))
    cwd = os.getcwd()
    os.chdir(d)
    try:
        yield d
    finally:
        os.chdir(cwd)
        texel.app.stop()
        shutil.rmtree(d, ignore_errors=True)


@fuzzlib.fuzz_settings()
@given(case=cases())
def test_link(tmp: Path, case) -> None:
    plan, timeout, (kind, spec) = case
    world = fb.World(plan)
    with world.patches():                   # (texel.app's quick gc)
        texel.app.stop()
        if plan.running:
            texel.app.start("virtual", SMALL_SCENE)
    describe = lambda: "%s timeout=%g %s %s" % (plan, timeout, kind, fuzzlib.short(spec, 300))  # noqa: E731
    with fuzzlib.case(FUZZ_TARGET, describe) as s:
        out, err = io.StringIO(), io.StringIO()
        with fuzzlib.watchdog(120, "a link case"):
            try:
                with world.patches():
                    if kind == "cli":
                        outcomes = session(world, timeout, kind, spec, tmp)
                    else:
                        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                            outcomes = session(world, timeout, kind, spec, tmp)
                if world.violations:
                    raise Broken("; ".join(sorted(set(world.violations))), "deadline")
                if out.getvalue() or err.getvalue():
                    raise Broken("the link printed: stdout %r, stderr %r"
                                 % (out.getvalue()[:300], err.getvalue()[:300]), "printed")
            except fb.Spin as e:
                raise Broken(str(e), "spin") from None
            except Exception as e:      # a broken property, or not a LinkError
                fuzzlib.allow_known(FUZZ_TARGET, e, describe)
                outcomes = ["known bug"]
        for o in outcomes:
            s.outcomes[o] += 1
        s.outcomes["virtual seconds (sum)"] += int(world.clock.t - 1000.0)

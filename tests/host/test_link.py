"""The host's link and Python API against the virtual board on a pty (the
device code under the real MicroPython unix port): handshake, push, status,
monitor, stop; every failure a clear LinkError; bad input on the API path
refused with the board's state unchanged; never a soft reset."""
import ast
import copy
import math
import re
import time

import pytest

import texel

import texelpad
from texelpad.link import board as board_mod
from texelpad.link import (DeviceError, ImageTooOld, LinkTimeout, LiteralError, NoBoard,
                           NotTexelpad, PortBusy, literal)
from texelpad.sim.virtual import VirtualBoard

pytestmark = [pytest.mark.vboard]

TEXEL = {"pitch_db": 3.0, "irregularity_db": -10.0, "seed": 1}


# --- literals (no board) --------------------------------------------------------

def test_literal_round_trips_plain_data():
    v = {"regions": [{"start_mm": 0, "end_mm": 1.5e1, "texture": {
        "kind": "x'\"\\\n", "v": [1, -2, 3.25, True, None, (1, 2)]}}], "u": "é"}
    assert ast.literal_eval(literal(v)) == v


@pytest.mark.parametrize("bad, where", [
    ({"a": float("nan")}, "a: nan is not finite"),
    ({"a": [0, float("inf")]}, "a[1]: inf is not finite"),
    ({"regions": [{"texture": {"seed": -math.inf}}]}, "regions[0].texture.seed: -inf"),
    ({"a": object()}, "a: object values cannot be sent"),
    ({"a": {1: 2}}, "a: key 1 is not a string"),
    ({"a": b"bytes"}, "a: bytes values cannot be sent"),
    ({"a": {1, 2}}, "a: set values cannot be sent"),
])
def test_literal_refuses_what_is_not_plain_data(bad, where):
    with pytest.raises(LiteralError) as e:
        literal(bad)
    assert str(e.value).startswith(where), str(e.value)


def test_literal_refuses_cycles_and_oversize():
    a = []
    a.append(a)
    with pytest.raises(LiteralError, match="contains itself"):
        literal(a)
    with pytest.raises(LiteralError, match="more than the link's 100-byte limit"):
        literal(list(range(100)), limit=100)


# --- a board on a pty -----------------------------------------------------------

@pytest.fixture(scope="module")
def vb():
    with VirtualBoard(image="source") as v:
        with texelpad.connect(v.port) as b:
            b.start("virtual", None, realtime=True)
        yield v


@pytest.fixture
def b(vb):
    with texelpad.connect(vb.port) as board:
        yield board


def test_handshake_reports_firmware_and_image(b):
    assert b.firmware["implementation"] == "micropython"
    assert b.firmware["version"] >= (1, 26, 0)
    assert b.image == {"protocol": texelpad.link.board.PROTOCOL, "texel": texel.__version__}


def test_push_status_monitor_round_trip(b):
    st0 = b.status()
    st = b.push_texel(dict(TEXEL, seed=5))
    assert st["pushes"] == st0["pushes"] + 1
    reg = st["scene"]["regions"]
    assert len(reg) == 1 and reg[0]["seed"] == 5 and reg[0]["mode"] == "plan"
    assert (reg[0]["start"], reg[0]["end"]) == (0, 19200)
    assert b.scene_source()["regions"][0]["texture"]["seed"] == 5
    t0 = b.finger([(0, 10.0), (400, 60.0)])
    samples = list(b.monitor(0.6, rate_hz=500, poll_s=0.02))
    assert len(samples) > 150                        # 500/s for 0.6 s, minus ring-lapping
    ts = [s[0] for s in samples]
    assert ts == sorted(ts) and ts[0] >= t0
    down = [s for s in samples if s[1] >= 0]
    assert down and max(s[1] for s in down) > 9000   # the finger reached past 47.7 mm
    assert all(0 <= s[2] <= 65535 for s in samples)
    st2 = b.status()
    assert st2["faults"] == 0 and st2["refreshes"] > st["refreshes"]


def _snapshot(b):
    st = b.status()
    return st, b.scene_source()


def _still_playing(b, st0):
    """status() once the realtime board's refresh thread has counted past st0's
    refreshes: up to 5 s. Between two quick status calls a busy host can starve
    that thread (a full CI run on 2 cores read 6,837 refreshes twice, at 78575c5)."""
    t_end = time.monotonic() + 5.0
    st = b.status()
    while st["refreshes"] <= st0["refreshes"] and time.monotonic() < t_end:
        time.sleep(0.05)
        st = b.status()
    return st


BAD_PUSHES = [
    ({"pitch_db": float("nan"), "irregularity_db": -10.0}, LiteralError, "regions[0].texture.pitch_db: nan"),
    ({"pitch_db": 3.0, "irregularity_db": float("inf")}, LiteralError,
     "regions[0].texture.irregularity_db: inf"),
    ({"pitch_db": 99.0, "irregularity_db": -10.0}, ValueError,
     "regions[0].texture.pitch_db: 99.0 is out of range"),
    ({"pitch_db": "3", "irregularity_db": -10.0}, ValueError, "regions[0].texture.pitch_db: "),
    ({"pitch_db": 3.0, "irregularity_db": -10.0, "seed": True}, ValueError,
     "regions[0].texture.seed: "),
    ({"pitch_db": 3.0, "irregularity_db": -10.0, "colour": 1}, ValueError,
     "regions[0].texture: unknown key"),
    ({"pitch_db": 3.0, "irregularity_db": -10.0, "seed": "1'); import os; os.remove('x"},
     ValueError, "regions[0].texture.seed: "),
    ({"pitch_db": 3.0, "irregularity_db": -10.0, "seed\n'": 1}, ValueError,
     "regions[0].texture: unknown key"),
]


@pytest.mark.parametrize("params, exc, prefix", BAD_PUSHES)
def test_bad_texel_parameters_change_nothing(b, params, exc, prefix):
    st0, src0 = _snapshot(b)
    keep = copy.deepcopy(params)
    with pytest.raises(exc) as e:
        b.push_texel(params)
    assert str(e.value).startswith(prefix), str(e.value)
    assert "\n" not in str(e.value)
    st1, src1 = _snapshot(b)
    assert src1 == src0 and st1["pushes"] == st0["pushes"]
    st2 = _still_playing(b, st0)
    assert st2["refreshes"] > st0["refreshes"] and st2["faults"] == 0   # still playing
    assert repr(params) == repr(keep)                                   # input untouched


def test_oversized_upload_refused_before_sending(b):
    st0, src0 = _snapshot(b)
    sent = b.link.sent
    scene = {"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": {
        "kind": "samples", "values": [0.5] * 19201}}]}
    with pytest.raises(ValueError, match=r"regions\[0\].texture.values"):
        b.push(scene)
    assert b.link.sent - sent < 200            # only the status call crossed
    assert _snapshot(b)[1] == src0


def test_device_refusal_keeps_the_scene_and_uses_the_device_words(b):
    """Past the host's own check (a host that skipped it): the board's
    validation refuses, in its words, and the old scene plays on."""
    st0, src0 = _snapshot(b)
    bad = {"regions": [{"start_mm": 0, "end_mm": 10, "texture": {
        "kind": "reference", "name": "4sin\"); print('pwned"}}]}
    with pytest.raises(DeviceError) as e:
        b.link.call("texel.app", "push", bad)
    assert str(e.value).startswith("regions[0].texture.name: ")
    assert "pwned" not in b.link.exec("print(1)")
    st1, src1 = _snapshot(b)
    assert src1 == src0 and st1["pushes"] == st0["pushes"] and st1["faults"] == 0


def test_reconnect_never_soft_resets(vb):
    with texelpad.connect(vb.port) as b1:
        b1.link.exec("_texelpad_marker = 42")
        n1 = b1.status()["refreshes"]
    time.sleep(0.1)
    with texelpad.connect(vb.port) as b2:
        assert b2.link.eval("print(repr(_texelpad_marker))") == 42     # same interpreter
        assert b2.status()["refreshes"] > n1                           # never stopped


def test_port_busy(vb):
    with texelpad.connect(vb.port):
        with pytest.raises(PortBusy, match="is busy"):
            texelpad.connect(vb.port)


def test_no_board():
    with pytest.raises(NoBoard, match="no such port"):
        texelpad.connect("/dev/ttyTEXELPAD-none")


def test_board_without_the_image(tmp_path):
    with VirtualBoard(tmp_path / "flash", image=None) as v:
        with pytest.raises(NotTexelpad, match="not texelpad's device image: install it with "
                                              "texelpad deploy"):
            texelpad.connect(v.port)
        with texelpad.connect(v.port, check=False) as b:           # what deploy does
            assert b.image is None


def test_image_older_than_host(vb, monkeypatch):
    monkeypatch.setattr(board_mod, "HOST_IMAGE_VERSION", "9.0.0")
    with pytest.raises(ImageTooOld, match=r"texel %s \(protocol 3\).*run texelpad deploy"
                       % re.escape(texel.__version__)):
        texelpad.connect(vb.port)
    monkeypatch.setattr(board_mod, "HOST_IMAGE_VERSION", texel.__version__)
    monkeypatch.setattr(board_mod, "PROTOCOL", 4)
    with pytest.raises(ImageTooOld, match="protocol 3"):
        texelpad.connect(vb.port)


def test_timeout_is_a_clear_error(tmp_path):
    with VirtualBoard(tmp_path / "f", image="source") as v:
        b = texelpad.connect(v.port, timeout=1.0)
        with pytest.raises(LinkTimeout, match="stopped answering"):
            b.link.exec("import time\ntime.sleep(5)")
        b.link.t = None          # the board is busy: drop the link without Ctrl-B


def test_board_renders_what_the_host_renders(b):
    """The generator run on the board (MicroPython, viper int engine) gives
    the host's int-engine map bit for bit."""
    import numpy as np
    import texel
    p = {"pitch_db": 12.0, "irregularity_db": -6.0, "seed": 3, "length_samples": 3000}
    got = b.render_u16(p, engine="int")
    want = np.asarray(texel.render_u16(p, engine="int"), dtype=np.uint16)
    assert got.dtype == np.uint16 and got.shape == (3000,)
    assert np.array_equal(got, want)


def test_ulab_engine_on_a_board_without_ulab(b):
    from texelpad.link.transport import NoUlab
    with pytest.raises(NoUlab, match="has none"):
        b.render_u16({"pitch_db": 3.0, "irregularity_db": -10.0}, engine="ulab")
    with pytest.raises(ValueError, match="pitch_db: nan"):
        b.render_u16({"pitch_db": float("nan"), "irregularity_db": -10.0})


# --- answers before the work after them (issue 32 item 4) --------------------------

def test_an_answer_is_read_before_the_work_after_it(b):
    """eval_reply returns at the answer's line while the board goes on (a
    push's collection: texel.wire.reply); the next command reads the rest
    first, so nothing is mixed up: the work was done, its error text (if it
    raised) is kept as late_error, and the prompt is where mpremote expects
    it. A push's answer has no heap figure; status() after it has one."""
    link = b.link
    assert link.eval_reply("import time\nprint(repr(('ok', 1)))\ntime.sleep_ms(300)\n"
                           "_after = 7") == ("ok", 1)
    assert link.t.tail is not None                   # the board was still sleeping
    assert link.eval("print(repr(_after))") == 7
    assert link.t.tail is None and link.t.late_error == ""
    assert link.eval_reply("print(repr(2))\nraise KeyError(5)") == 2
    assert link.eval("print(repr(3))") == 3
    assert "KeyError: 5" in link.t.late_error
    # a command that ends before printing a line is read to its end, as eval reads it
    with pytest.raises(board_mod.LinkError, match="ZeroDivisionError"):
        link.eval_reply("1/0")
    assert link.t.tail is None
    st = b.push_texel(dict(TEXEL, seed=9))
    assert st["mem_free"] is None and st["scene"]["regions"][0]["seed"] == 9
    assert isinstance(b.status()["mem_free"], int)


def test_an_interrupt_after_an_answer_leaves_a_clean_link(b):
    """Ctrl-C (resync) while the work after an answer still runs: the tail
    is dropped with the rest of what the board sent, and the link works."""
    link = b.link
    assert link.eval_reply("import time\nprint(repr(4))\ntime.sleep_ms(5000)") == 4
    link.resync()
    assert link.t.tail is None
    assert link.eval("print(repr(5))") == 5

"""texel.serve (texel.app.serve(): how a CircuitPython board plays on between
texelpad commands) answers the raw REPL's framing byte for byte, on the real
interpreters: CPython, the MicroPython unix port and CircuitPython's unix
build (../shared/instruments: the same VM as the board, no viper). Its console
is a scripted read() here; the board's own (usb_cdc.console, its Ctrl-C)
is tests/host/test_emulated_cpy.py's, through texelpad's CLI and mpremote on
the emulated CircuitPython Pico."""
from __future__ import annotations

import pytest

from support import mpy
from texelpad import toolchain

# Each run: chunks the console "receives", one per read() (None: nothing
# waiting), then the output the board sent, as a repr at the end.
PRELUDE = r"""
import sys
from texel import serve

class _Rt:
    # a paced-loop runtime as texel.app's: refresh.step counted, ticks from a counter
    loop_mode = True
    hz = 1000
    def __init__(self):
        self.t = 0
        self.steps = 0
        self.refresh = self
    def ticks(self):
        self.t += 250             # us per tick read: 4 reads per refresh period
        return self.t
    def diff(self, a, b):
        return a - b
    def step(self):
        self.steps += 1

class _WrapRt(_Rt):
    # a clock that wraps at 2^30 us as CircuitPython's (compat.ticks_us) does, 0.1 s a read
    hz = 10
    def ticks(self):
        self.t = (self.t + 100000) & 0x3FFFFFFF
        return self.t
    def diff(self, a, b):
        return ((a - b + 0x20000000) & 0x3FFFFFFF) - 0x20000000

INT = object()                      # a Ctrl-C at this read


def run(name, chunks, rt=None, repl=True):
    # serve's output goes to stdout, as on a board; the case's frame around it
    state = {"rt": rt, "stops": 0}
    def read():
        if not chunks:
            return None                  # (each case ends itself: Ctrl-B, Ctrl-D, Ctrl-C)
        c = chunks.pop(0)
        if c is INT:
            raise KeyboardInterrupt
        return c
    def stop():
        state["stops"] += 1
        state["rt"] = None
    sys.stdout.write("@@<" + name + ">@@")
    try:
        serve.serve(lambda: state["rt"], stop, read, repl=repl)
        how = "returned"
    except KeyboardInterrupt:
        how = "interrupt"
    except SystemExit:
        how = "exit"
    sys.stdout.write("@@</" + name + " " + how + " " + str(state["stops"]) + ">@@")
"""

CASES = r"""
# a session: Ctrl-A, a request in two pieces, an error, raw-paste refused, Ctrl-B
run("session", [b"\r\x01", b"x = 6\nprint(x ", b"* 7)", b"\x04", None,
                b"raise ValueError('no')\x04", b"\x05A\x01", b"print(x)\x04\x02"])
# the namespace is the session's; an empty Ctrl-D is the raw REPL's soft reset
run("reset", [b"\x01y = 1\x04\x04"])
# a Ctrl-C: the display stops, then (no Ctrl-A came) the banner; then a request
run("ctrl_c", [b"\x01", INT, None, b"print('after')\x04\x02"])
# code.py's serve (repl=False): a Ctrl-C stops the display and ends it, as a program ends
run("ctrl_c_end", [b"\x01", INT, b"print('never')\x04"], repl=False)
rt = _Rt()
run("plays", [None] * 40 + [b"\x01print('hi')\x04"] + [None] * 40 + [b"\x02"], rt)
print("\nsteps", rt.steps)
# a Ctrl-C, then a tool's Ctrl-A in two reads ("\r", then "\x01"): one banner
run("split", [INT, b"\r", b"\x01", b"\x02"])
# hours on a clock that wraps every 2^30 us: the refresh stays paced
wr = _WrapRt()
run("wraps", [None] * 6000 + [b"\x02"], wr)
print("\nwrapsteps", wr.steps, wr.t)
"""

# (line ends compared as "\n": the unix ports' and CPython's stdout are text streams)
BANNER = "\x1etexel-serve\nraw REPL; CTRL-B to exit\n>"


def _interpreters():
    out = [pytest.param(None, id="cpython")]
    for name in ("micropython", "circuitpython"):
        exe = toolchain.interpreter(name)
        out.append(pytest.param(name, id=name, marks=pytest.mark.skipif(
            exe is None, reason="no %s interpreter here" % name)))
    return out


def _run(name):
    """{case: (how serve ended, its output, stops)} and the plays case's steps."""
    code = PRELUDE + CASES
    if name is None:
        import subprocess
        import sys
        p = subprocess.run([sys.executable, "-c", code], capture_output=True,
                           cwd=str(mpy.DEVICE), timeout=120)
        assert p.returncode == 0, p.stderr
        out = p.stdout.decode()
    else:
        out = mpy.run(code, exe=toolchain.interpreter(name), timeout=120)
    out = out.replace("\r\n", "\n")
    res = {}
    for case in ("session", "reset", "ctrl_c", "ctrl_c_end", "plays", "split", "wraps"):
        body = out.split("@@<%s>@@" % case, 1)[1]
        body, end = body.split("@@</%s " % case, 1)
        how, stops = end.split(">@@", 1)[0].split()
        res[case] = (how, body, int(stops))
    res["steps"] = int(out.split("\nsteps", 1)[1].split()[0])
    res["wrapsteps"] = int(out.rsplit("wrapsteps", 1)[1].split()[0])
    return res


@pytest.mark.parametrize("name", _interpreters())
def test_serve_answers_as_the_raw_repl_does(name):
    r = _run(name)
    how, out, stops = r["session"]
    assert how == "returned" and stops == 1        # Ctrl-B: nothing would refresh: stopped
    parts = out.split(BANNER)
    assert parts[0] == "\x1etexel-serve\n" and len(parts) == 2      # the start mark, one banner
    rest = parts[1]
    assert rest.startswith("OK42\n\x04\x04>")
    rest = rest[len("OK42\n\x04\x04>"):]
    assert rest.startswith("OK\x04") and "ValueError: no" in rest
    err, rest = rest[3:].split("\x04>", 1)
    assert err.rstrip().endswith("ValueError: no")
    assert rest == "R\x00" + "OK6\n\x04\x04>"          # raw paste refused, then standard mode
    how, out, stops = r["reset"]
    assert how == "exit" and out.endswith(BANNER + "OK\x04\x04>OK\n")
    how, out, stops = r["ctrl_c"]
    assert how == "returned" and stops == 2        # the Ctrl-C, then the Ctrl-B
    assert out.count(BANNER) == 2 and out.endswith(BANNER + "OKafter\n\x04\x04>")
    how, out, stops = r["split"]
    assert how == "returned" and out.count(BANNER) == 1, out
    how, out, stops = r["ctrl_c_end"]
    assert how == "interrupt" and stops == 1 and out.count(BANNER) == 1 and "never" not in out


@pytest.mark.parametrize("name", _interpreters())
def test_serve_refreshes_between_requests_and_after_them(name):
    r = _run(name)
    how, out, stops = r["plays"]
    assert how == "returned" and stops == 1
    assert out.endswith(BANNER + "OKhi\n\x04\x04>")
    # 81 console reads, the loop paced at 1 kHz on a clock that moves 250 us at each
    # read of it (four a period): the refresh ran between the reads
    assert 10 <= r["steps"] <= 81, r["steps"]


@pytest.mark.parametrize("name", _interpreters())
def test_serve_keeps_pacing_across_the_clocks_wrap(name):
    """6,000 console reads, 16 refreshes between reads at 10 Hz on a clock moving 0.1 s a
    read: ~2.7 hours, 18 wraps of CircuitPython's 2^30 us clock. Scheduling refresh k at
    k * 1e6 // hz after the start stopped refreshing after 2^29 us (~9 minutes): the
    difference of two wrapping ticks never grows past that."""
    r = _run(name)
    assert r["wrapsteps"] >= 6000 * 15, r["wrapsteps"]

"""Fuzz target "repl": REPL control bytes at random moments on the emulated Pico (issue 30).

A stock MicroPython Pico after `texelpad deploy` (../shared/instruments/rp2emu: the real
v1.28 firmware on rp2040js), playing. A case: a request started in the raw REPL - a texel
push, a samples upload and push, a telemetry burst, a start, a stop, or nothing - then,
after a drawn delay, 1..3 control bytes with drawn gaps: Ctrl-A (raw REPL), Ctrl-B
(friendly REPL), Ctrl-C (KeyboardInterrupt), Ctrl-D (soft reset, or end of input),
Ctrl-E (paste mode) - what mpremote, Thonny and a typing teacher send. Then the host
recovers as mpremote does (Ctrl-C, Ctrl-C, Ctrl-A).

Properties, per case:
- the emulator reports no error (a HardFault on a chip) and keeps running;
- the raw REPL answers; `texel.app.status()` is a dict; a display that says it runs
  refreshes (its count grows) without faults; one that does not starts again with
  `texel.app.start('pico', ...)`.
Figures (not asserted, printed): the wall time from the last byte to the raw REPL prompt
with mpremote's recovery (no pause), and the emulator's own count of emulated against wall
seconds (its pace; rp2040js skips ahead through idle sleeps, so board time is not simply
wall time times a constant).

Cases: 5 in a smoke run (CI), TEXELPAD_FUZZ_REPL_CASES otherwise (default 100 nightly): one
case costs 5..40 s of an emulator, not microseconds.
"""
from __future__ import annotations

import os
import time

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import fuzzlib
from support.repl import Raw, status

FUZZ_TARGET = "repl"
pytestmark = [pytest.mark.fuzz, pytest.mark.slow, pytest.mark.instruments]

BYTES = {"A": b"\x01", "B": b"\x02", "C": b"\x03", "D": b"\x04", "E": b"\x05"}
CONST = {"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": {"kind": "constant",
                                                                    "level": 0.3}}]}
TEXEL = {"regions": [{"start_mm": 0, "end_mm": 50.88, "texture": {
    "kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7, "v": 2}}]}
REQUESTS = {
    "push": "app.push(%r)" % (TEXEL,),
    "upload": "import binascii\nwire.upload_begin([2400])\n"
              "for i in range(0, 2400, 200): wire.upload_write(0, i, "
              "binascii.b2a_base64(bytes(400)).decode().strip())\n"
              "app.push({'regions': [{'start_mm': 0, 'end_mm': 101.76, 'texture': "
              "{'kind': 'samples', 'fit': 'tile', 'u16': wire.take_upload(0)}}]})",
    "telemetry": "import time\napp.stream(500)\n"
                 "for _ in range(30): wire.telemetry_b64(); time.sleep_ms(20)",
    "start": "app.start('pico', %r)" % (TEXEL,),
    "stop": "app.stop()",
    "idle": "import time; time.sleep_ms(1500)",
}
FIGURES: list[float] = []       # wall s from the last control byte to the raw REPL prompt


def _cases() -> int:
    env = os.environ.get("TEXELPAD_FUZZ_REPL_CASES")
    if env:
        return int(env)
    return 100 if fuzzlib.mode() == "nightly" else 5


@pytest.fixture(scope="module")
def board():
    from support.pico import emulated_pico
    from texelpad.deploy.install import deploy
    from texelpad.link.board import connect
    with emulated_pico() as emu:
        with connect(emu.port, check=False, import_image=False, timeout=60) as b:
            deploy(b)
        with connect(emu.port, timeout=60) as b:
            b.start("pico", CONST)
        r = Raw(emu.port, emu)
        try:
            r.raw()
            yield r
        finally:
            r.close()
        summary = emu.stop()
    if FIGURES:
        walls = sorted(FIGURES)
        print("\nrepl fuzz: %d cases; last control byte -> raw REPL prompt (mpremote's "
              "recovery): wall median %.2f s, max %.2f s; the emulator: %s"
              % (len(walls), walls[len(walls) // 2], walls[-1], " ".join(summary.split())))


def _recover(r: Raw) -> float:
    """mpremote's enter_raw_repl, as it does it (Ctrl-C, input dropped, Ctrl-A, the
    prompt awaited: no pause); s of wall time from now to the raw REPL prompt. A board
    that soft-resets meanwhile may eat the Ctrl-A: then once more, as a user would."""
    t0 = time.monotonic()
    r.s.write(b"\r\x03")
    r.s.reset_input_buffer()
    r.buf = b""
    r.s.write(b"\r\x01")
    try:
        r.read_until(b"raw REPL; CTRL-B to exit\r\n>", 10)
    except AssertionError:
        r.raw()
    return time.monotonic() - t0


@settings(fuzzlib.fuzz_settings(), max_examples=_cases(),
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(what=st.sampled_from(sorted(REQUESTS)),
       delay=st.integers(0, 40).map(lambda k: k * 0.05),
       keys=st.lists(st.tuples(st.sampled_from(sorted(BYTES)), st.integers(0, 10)),
                     min_size=1, max_size=3))
def test_control_bytes_at_any_moment_never_fault_or_hang_the_board(board, what, delay, keys):
    r = board
    desc = lambda: "%s, after %.2f s: %s" % (what, delay, " ".join(       # noqa: E731
        "^%s+%dms" % (k, 50 * g) for k, g in keys))
    with fuzzlib.case(FUZZ_TARGET, desc) as stats:
        r.start("import texel.app as app, texel.wire as wire\n" + REQUESTS[what])
        time.sleep(delay)
        for k, gap in keys:
            r.s.write(BYTES[k])
            time.sleep(0.05 * gap)
        wall = _recover(r)
        emu = r.emu
        assert emu.alive() and "EMULATOR ERROR" not in emu.stderr(), (desc(), emu.stderr()[-500:])
        FIGURES.append(wall)
        st0 = status(r)
        assert isinstance(st0, dict) and "running" in st0, st0
        if st0["running"]:
            time.sleep(0.3)
            st1 = status(r)
            assert st1["refreshes"] != st0["refreshes"] and st1["faults"] == 0, (desc(), st0, st1)
            stats.outcomes["playing"] += 1
        else:
            r.exec("import texel.app as app; app.start('pico', %r)" % (CONST,))
            assert status(r)["running"], desc()
            stats.outcomes["stopped, started again"] += 1
        assert "EMULATOR ERROR" not in emu.stderr(), emu.stderr()[-500:]

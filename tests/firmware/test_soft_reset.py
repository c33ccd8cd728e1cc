"""A board survives its users (issue 30): soft resets and Ctrl-C's at seeded random moments,
between and in the middle of pushes, sample uploads and telemetry, on the emulated Pico -
the texelpad firmware (boards/pico, its C soft-reset hook) and a stock MicroPython Pico after
`texelpad deploy`. After each: no emulator error, the REPL answers, status() says what is true
(a raw-REPL soft reset leaves the carrier off and the display stopped; a friendly Ctrl-D runs
main.py, which plays the power-up scene again; a Ctrl-C inside a push keeps a whole scene
playing). And the teacher's one-liner, a plain `mpremote connect PORT exec "..."` on a
playing board, as typed.

The cause these pin (device/texel/hw/rp2.py, "Why slices 0..3"): MicroPython v1.28's soft
reset stops PWM slices 0..3 only, and the refresh tick ran on slice 7, interrupting through
the reset into code in the freed heap. No timing is asserted; the wall time of each round is
printed, and the board's own clock from the last command before each soft reset to the first
answer after it. After a raw-REPL reset the display is stopped and rp2emu's clock follows the
wall while the board waits, so that figure is an upper bound of the board's time to answer
(the host's turnaround included); after a friendly Ctrl-D main.py's power-up scene plays, its
refresh is scheduled, and the clock runs ahead of the wall while the host waits (the 0.2 s
drains): there it bounds main.py's work plus those waits counted several times over."""
from __future__ import annotations

import ast
import random
import subprocess
import sys
import time
from pathlib import Path

import pytest

from support.firmware import built
from support.repl import SOAK_CONST, SOAK_TEXEL, SOAK_WORK, Raw, soak_code, status as _status
from support.pico import emulated_pico

pytestmark = [pytest.mark.slow, pytest.mark.instruments]

SEED = 30
ROUNDS = 22
CONST, TEXEL = SOAK_CONST, SOAK_TEXEL


def _teacher_one_liner(port: str, emu) -> None:
    """mpremote's default exec (a soft reset before and after) on a playing board."""
    mp = str(Path(sys.executable).with_name("mpremote"))
    for _ in range(2):
        p = subprocess.run([mp, "connect", port, "exec",
                            "import texel.app as app; print(app.status())"],
                           capture_output=True, text=True, timeout=120)
        assert p.returncode == 0, p.stdout + p.stderr
        assert "'running': False" in p.stdout, p.stdout
        assert emu.alive() and "EMULATOR ERROR" not in emu.stderr()


def _carrier_pin(r: Raw) -> tuple[int, int]:
    """GP16's (FUNCSEL, OUTTOPAD): 4 = driven by PWM, 5 = a plain output (SIO); its level."""
    out = r.exec("import machine; m = machine.mem32; "
                 "print(m[0x40014084] & 31, (m[0x40014080] >> 9) & 1)")
    f, level = out.split()
    return int(f), int(level)


def _soak(port: str, emu, board: str, hook: bool = False) -> list[str]:
    rng = random.Random(SEED)
    r = Raw(port, emu)
    log = []
    board_ms: list[int] = []
    try:
        r.raw()
        playing = _status(r)["running"]
        for k in range(ROUNDS):
            t0 = time.monotonic()
            if not playing:
                r.exec("import texel.app as app; app.start(%r, %r)" % (board, CONST))
            what = rng.choice(SOAK_WORK)
            how = rng.choice(("ctrl-c", "ctrl-c", "raw-reset", "raw-reset", "friendly-reset"))
            r.start(soak_code(what))
            time.sleep(rng.uniform(0.0, 2.5))   # a moment inside it (or after it ended)
            r.ctrl_c()                           # KeyboardInterrupt wherever it is
            st = _status(r)
            assert st["running"], (k, what, how, st)        # a Ctrl-C never stops the display
            if how != "ctrl-c":
                b0 = r.ticks_ms()
            if how == "raw-reset":
                r.soft_reset_raw()
                board_ms.append((r.ticks_ms() - b0) % (1 << 30))  # ticks_ms wraps at 2^30
                if hook:        # the firmware's C hook: the carrier pin a plain output, low
                    assert _carrier_pin(r) == (5, 0), k
                st = _status(r)
                assert not st["running"], (k, st)           # carrier off, display stopped
                playing = False
            elif how == "friendly-reset":
                r.soft_reset_friendly()
                r.raw()
                board_ms.append((r.ticks_ms() - b0) % (1 << 30))
                st = _status(r)
                assert st["running"], (k, st)               # main.py: the power-up scene
                playing = True
            else:
                playing = True
            assert emu.alive() and "EMULATOR ERROR" not in emu.stderr(), emu.stderr()[-500:]
            log.append("%2d %-9s %-14s %5.1f s%s" % (k, what, how, time.monotonic() - t0,
                                                     "  board %d ms" % board_ms[-1]
                                                     if how != "ctrl-c" else ""))
        # after all of it: a push through texelpad's own link works
        r.s.write(b"\x02")
        r.drain()
    finally:
        r.close()
    from texelpad.link.board import connect
    with connect(port, timeout=60) as b:
        if not b.status()["running"]:
            b.start(board, CONST)
        b.push(TEXEL)
        assert b.status()["scene"] is not None
    board_ms.sort()
    log.append("board clock, last command before a soft reset to the first answer after it (an "
               "upper bound: the host's turnaround and the friendly reset's main.py included): "
               "median %d ms, max %d ms over %d resets"
               % (board_ms[len(board_ms) // 2], board_ms[-1], len(board_ms)))
    return log


def _main_py(r: Raw, run: str, what: str) -> str:
    """The power-up's work (run: main.py's code) on a fresh heap, timed by the board's own clock:
    what a friendly Ctrl-D runs before the REPL answers (MicroPython's own reset aside). Its
    split screen's 4sin is the firmware's flash map, or rendered by gen/reference_viper.py on a
    stock Pico (3.5 s by the float path): CPython's within 1 u16."""
    import texel
    out = r.exec("import time\nt0 = time.ticks_ms()\n%s\n"
                 "print(time.ticks_diff(time.ticks_ms(), t0))" % run)
    ms = int(out.split()[-1])
    got = ast.literal_eval(r.exec("import texel.app as _A\nprint(repr([_A._rt.refresh.scene.amp(p) "
                                  "for p in range(0, 9600, 41)]))").strip())
    want = texel.reference_u16("4sin", 9600)
    diff = [abs(a - want[p]) for a, p in zip(got, range(0, 9600, 41))]
    assert len(diff) == 235 and max(diff) <= 1 and diff.count(0) >= 0.8 * len(diff), diff
    return ("%s (import texel.app and the power-up scene) on a fresh heap: %d ms of board time; "
            "its 4sin against CPython: %d of %d samples equal, worst %d u16"
            % (what, ms, diff.count(0), len(diff), max(diff)))


@pytest.fixture(scope="module")
def fw():
    return built("pico")


def test_the_firmware_survives_soft_resets_and_ctrl_c(fw):
    with emulated_pico(firmware=fw.uf2) as emu:
        r = Raw(emu.port, emu)
        try:
            r.raw()
            r.soft_reset_raw()              # the frozen main.py ran at boot: a fresh heap
            first = _main_py(r, "import texel.main", "texel.main (the frozen main.py's)")
        finally:
            r.close()
        _teacher_one_liner(emu.port, emu)
        log = _soak(emu.port, emu, "pico", hook=True)
        print("\n".join(["firmware soak (seed %d):" % SEED, first] + log))
        summary = emu.stop()            # (its error lines, if any, are in the summary)
    assert "EMULATOR ERROR" not in summary


def test_a_stock_pico_after_deploy_survives_soft_resets_and_ctrl_c(capsys):
    from support.cli import run_cli
    with emulated_pico() as emu:
        code, out, err = run_cli(capsys, "deploy", "--port", emu.port)
        assert code == 0, out + err
        r = Raw(emu.port, emu)
        try:
            r.raw()
            r.soft_reset_raw()              # a fresh heap, nothing playing
            first = _main_py(r, "exec(open('/main.py').read())", "/main.py")
        finally:
            r.close()
        _teacher_one_liner(emu.port, emu)
        log = _soak(emu.port, emu, "pico")
        with capsys.disabled():
            print("\n".join(["stock soak (seed %d):" % SEED, first] + log))
        assert "EMULATOR ERROR" not in emu.stderr()

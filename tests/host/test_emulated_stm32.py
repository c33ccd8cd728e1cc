"""Issue 30 on the STM32 (../shared/instruments/stm32emu: real MicroPython v1.28 for a pyboard
v1.1 variant on an emulated STM32F405, texel from this checkout in a ROMFS image): a board that
plays survives soft resets and Ctrl-C's at seeded random moments of pushes, uploads and
telemetry, as on the emulated Pico (tests/firmware/test_soft_reset.py). After a soft reset the
refresh timer (TIM7) is stopped and its interrupt disabled, and the carrier timer (TIM8) is
stopped with its outputs disabled (CCER 0): the piezo is not driven - the safe state, since
nothing is left to refresh the duty. A Ctrl-C never stops the display. The REPL answers and
texel.app.start() works again. The plain `mpremote connect PORT exec "..."` as a teacher types
it. How far the instrument reaches: no pin output (registers only), no /flash (so no main.py:
a friendly Ctrl-D leaves the display stopped too; a real pyboard runs its /flash/main.py).

Figures printed, none asserted: wall time per round, and the board's own clock from the last
command before each reset to the first after it - an upper bound that says little here: under
--icount an idle board's clock skips ahead of the wall, so the host's waits (the friendly path's
0.2 s drains) count many times over (the Pico's, tests/firmware/test_soft_reset.py, follows the
wall while the board waits)."""
from __future__ import annotations

import random
import subprocess
import sys
import time
from pathlib import Path

import pytest

from support.repl import Raw, status as _status
from support.stm32 import build_romfs, emulated_stm32

pytestmark = [pytest.mark.slow, pytest.mark.instruments]

SEED = 34
ROUNDS = 12
CONST = {"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": {"kind": "constant",
                                                                    "level": 0.3}}]}
TEXEL = {"regions": [{"start_mm": 0, "end_mm": 50.88, "texture": {
    "kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7, "v": 2}},
    {"start_mm": 50.88, "end_mm": 101.76, "texture": {"kind": "constant", "level": 0.6}}]}
# the uploaded values in place of the region's (as texelpad.link's push does): a 2,400-value
# literal takes minutes through the emulated UART under --icount
SAMPLES = ("{'regions': [{'start_mm': 0, 'end_mm': 101.76, 'texture': {'kind': 'samples', "
           "'fit': 'tile', 'u16': app.take_upload(0)}}]}")
# TIM7 (refresh, APB1) and TIM8 (carrier, APB2): RM0090 register offsets
TIMERS = ("import machine; m = machine.mem32; "
          "print(m[0x40001400] & 1, m[0x4000140C] & 1, m[0x40010400] & 1, m[0x40010420] & 0x5555)")


@pytest.fixture(scope="module")
def romfs(tmp_path_factory):
    return build_romfs(tmp_path_factory.mktemp("stm32") / "texel.romfs")


def _timers(r: Raw) -> dict:
    """TIM7 counting, TIM7 update interrupt enabled, TIM8 counting, TIM8 outputs enabled."""
    t7, irq, t8, ccer = (int(v) for v in r.exec(TIMERS).split())
    return {"tim7": t7, "tim7_irq": irq, "tim8": t8, "tim8_outputs": ccer}


def _ticks(r: Raw) -> int:
    return int(r.exec("import time; print(time.ticks_ms())"))


def test_the_stm32_survives_soft_resets_and_ctrl_c(romfs, capsys):
    rng = random.Random(SEED)
    with emulated_stm32(romfs) as emu:
        mp = str(Path(sys.executable).with_name("mpremote"))
        r = Raw(emu.port, emu)
        log, board_ms = [], []
        try:
            r.raw()
            r.exec("import texel.app as app; app.start('pyboard', %r)" % (CONST,))
            on = _timers(r)
            assert on == {"tim7": 1, "tim7_irq": 1, "tim8": 1, "tim8_outputs": on["tim8_outputs"]}
            assert on["tim8_outputs"] != 0, on
            playing = True
            for k in range(ROUNDS):
                t0 = time.monotonic()
                if not playing:
                    r.exec("import texel.app as app; app.start('pyboard', %r)" % (CONST,))
                what = rng.choice(("push", "upload", "telemetry", "idle"))
                how = rng.choice(("ctrl-c", "raw-reset", "raw-reset", "friendly-reset"))
                code = {"push": "app.push(%r)" % (TEXEL,),
                        "upload": "import binascii\napp.upload_begin([2400])\n"
                                  "for i in range(0, 2400, 200): app.upload_write(0, i, "
                                  "binascii.b2a_base64(bytes(400)).decode().strip())\n"
                                  "app.push(%s)" % (SAMPLES,),
                        "telemetry": "import time\napp.stream(125)\n"
                                     "for _ in range(40): app.telemetry(); time.sleep_ms(20)",
                        "idle": "import time; time.sleep_ms(3000)"}[what]
                r.start("import texel.app as app\n" + code)
                time.sleep(rng.uniform(0.0, 1.0))
                r.s.write(b"\x03")
                r.drain()
                r.raw()
                st = _status(r)
                assert st["running"], (k, what, how, st)        # a Ctrl-C never stops the display
                if how != "ctrl-c":
                    b0 = _ticks(r)
                    if how == "raw-reset":
                        r.soft_reset_raw()
                    else:
                        r.soft_reset_friendly()
                        r.raw()
                    board_ms.append((_ticks(r) - b0) % (1 << 30))   # ticks_ms wraps at 2^30
                    off = _timers(r)
                    assert off == {"tim7": 0, "tim7_irq": 0, "tim8": 0, "tim8_outputs": 0}, (k, off)
                    assert not _status(r)["running"], k
                    playing = False
                assert emu.alive(), k
                log.append("%2d %-9s %-14s %5.1f s%s" % (k, what, how, time.monotonic() - t0,
                                                         "  board %d ms" % board_ms[-1]
                                                         if how != "ctrl-c" else ""))
            if not playing:
                r.exec("import texel.app as app; app.start('pyboard', %r)" % (CONST,))
            r.s.write(b"\x02")
            r.drain()
        finally:
            r.close()
        # the teacher's one-liner on a playing board: mpremote's own soft resets around it
        p = subprocess.run([mp, "connect", emu.port, "exec",
                            "import texel.app as app; print(app.status())"],
                           capture_output=True, text=True, timeout=120)
        assert p.returncode == 0 and "'running': False" in p.stdout, p.stdout + p.stderr
        assert emu.alive()
        # and after all of it, texelpad's own link starts and pushes
        from texelpad.link.board import connect
        with connect(emu.port, timeout=60) as b:
            b.start("pyboard", CONST)
            st = b.push(TEXEL)
            assert st["running"] and st["faults"] == 0
        board_ms.sort()
        with capsys.disabled():
            print("\n".join(["stm32 soak (seed %d):" % SEED] + log))
            print("board clock, last command before a soft reset to the first answer after it "
                  "(upper bound): median %d ms, max %d ms over %d resets"
                  % (board_ms[len(board_ms) // 2], board_ms[-1], len(board_ms)))

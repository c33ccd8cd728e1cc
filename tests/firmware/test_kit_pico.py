"""The classroom kit on the emulated Pico (the texelpad firmware, texel frozen in):
`texelpad scene boot A B C` writes a playlist, the board's power-up (its main.py)
plays A and steps it at each press of BOOTSEL, the LED (GPIO 25, read back from
the chip's SIO output register: the emulator has no pin output) blinks the scene's number, and a laptop's Ctrl-C ends the stepping with the
scene playing. The emulator reads BOOTSEL as held for ever (rp2040js: the QSPI
chip select reads low), so the press pattern is faked at the backend
(texel.hw.pins.bootsel, which the kit's real button code calls); everything else
is the chip's. A second part polls the real rp2.bootsel_button() while the
display plays: its interrupts-off reads (~9 us, ports/rp2/modrp2.c) cost the
refresh no overrun. No timing asserted."""
from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

from support.cli import run_cli
from support.firmware import built
from support.pico import emulated_pico

pytestmark = [pytest.mark.slow, pytest.mark.instruments]

MAIN_PY = Path(__file__).resolve().parents[2] / "device" / "texel" / "main.py"
PLAYLIST = ("texel-sweep", "gradient", "constant-half")

# Before main.py: BOOTSEL pressed in two windows of the board's own clock (the first
# bouncing), the LED pin sampled at every poll, and a Ctrl-C (a laptop plugged in)
# after the polls.
PREFIX = """import time, machine, texel.kit as _k, texel.hw.pins as _p
_t0 = time.ticks_ms()
def _bootsel():
    t = time.ticks_diff(time.ticks_ms(), _t0)
    return (300 <= t < 304 or 308 <= t < 500 or 900 <= t < 1100)
_p.bootsel = _bootsel
_seen = []
_n = [0]
def _sleep(ms, _s=_k._sleep):
    v = (machine.mem32[0xD0000010] >> 25) & 1     # SIO GPIO_OUT: what GPIO 25 drives
    if not _seen or _seen[-1] != v:
        _seen.append(v)
    _n[0] += 1
    if _n[0] > %d:
        print("LED", repr(_seen))
        raise KeyboardInterrupt
    _s(ms)
_k._sleep = _sleep
"""


@pytest.fixture(scope="module")
def pico():
    fw = built("pico")
    with emulated_pico(firmware=fw.uf2) as emu:
        yield emu


def _mpremote(port: str, code: str) -> subprocess.CompletedProcess:
    exe = Path(sys.executable).parent / "mpremote"
    return subprocess.run([str(exe) if exe.exists() else "mpremote", "connect", port,
                           "exec", code], capture_output=True, text=True, timeout=600)


def test_a_playlist_steps_by_bootsel_and_shows_on_the_led(pico, capsys):
    code, out, err = run_cli(capsys, "scene", "boot", *PLAYLIST, "--port", pico.port)
    assert code == 0 and "playlist of 3 scenes" in out, err
    # mpremote's exec soft-resets first: the power-up's main.py as the board runs it
    r = _mpremote(pico.port, PREFIX % 160 + MAIN_PY.read_text())
    assert r.returncode == 0, r.stderr
    assert "a playlist of 3 scenes" in r.stdout, r.stdout
    assert "texelpad: scene 2 of 3" in r.stdout and "texelpad: scene 3 of 3" in r.stdout, r.stdout
    led = ast.literal_eval(r.stdout.split("LED ", 1)[1].splitlines()[0])
    assert len(led) >= 5 and 1 in led, led                # blinking (distinct levels in turn)
    code, out, err = run_cli(capsys, "status", "--port", pico.port)
    assert code == 0 and "constant 0.5" in out, out + err


def test_polling_the_real_bootsel_costs_the_refresh_no_overrun(pico):
    r = _mpremote(pico.port, (
        "import texel.app as a, texel.kit as k, rp2\n"
        "a.start(None, None, report=False)\n"
        "st0 = a.status()\n"
        "k.run([None, None], polls=100)\n"        # the emulator's BOOTSEL: held, never a press
        "st = a.status()\n"
        "print(repr((rp2.bootsel_button(), st['refreshes'] - st0['refreshes'], "
        "st['overruns'], st['faults'], st['worst_us'])))\n"))
    assert r.returncode == 0, r.stderr
    held, refreshes, overruns, faults, worst = ast.literal_eval(r.stdout.strip().splitlines()[-1])
    print("100 polls of the real BOOTSEL: %d refreshes, %d overruns, worst %d us"
          % (refreshes, overruns, worst))
    assert held == 1 and refreshes > 0 and overruns == 0 and faults == 0

"""Issue 30 on CircuitPython (../shared/instruments/cpyemu: the emulated Pico running stock
CircuitPython 10.2.1, texel on its CIRCUITPY drive as `texelpad deploy` lays it out): the
display plays inside texel.app.run_loop() (no timer IRQ on CircuitPython); a Ctrl-C at a seeded
random moment ends the loop with the carrier off (run_loop's finally: hw.off - nothing is left
to refresh the duty, so the piezo is not driven); a soft reload (Ctrl-D at the raw REPL, as
mpremote sends; Ctrl-B, leaving the raw REPL, which restarts CircuitPython's VM; Ctrl-D at the
friendly REPL) leaves nothing running, GP16 free (a new PWMOut on it works: the carrier's PWM
was released) and the next start plays. And the plain `mpremote connect PORT exec "..."`.
No timing asserted; wall times printed."""
from __future__ import annotations

import random
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from support.proc import stop_group
from support.repl import Raw, status as _status
from texelpad import toolchain

pytestmark = [pytest.mark.slow, pytest.mark.instruments]

SEED = 35
ROUNDS = 4
ROOT = Path(__file__).resolve().parents[2]


def _cpyemu() -> Path:
    d = toolchain.instruments_dir()
    k = d / "cpyemu" if d is not None else None
    if k is None or not (k / "run.sh").is_file():
        pytest.skip("no cpyemu in the instruments")
    for tool in ("node", "mcopy", "mkfs.fat"):
        if not shutil.which(tool):
            pytest.skip("%s is missing: the emulated CircuitPython Pico needs node, mtools and "
                        "dosfstools (.ci/run installs them)" % tool)
    return k


class _Emu:
    def __init__(self, proc):
        self.proc = proc

    def alive(self) -> bool:
        return self.proc.poll() is None

    def stderr(self) -> str:
        return ""


def _free_gp16(r: Raw) -> str:
    return r.exec("import board, pwmio\np = pwmio.PWMOut(board.GP16, frequency=34000)\n"
                  "p.deinit()\nprint('GP16 free')")


def test_circuitpython_survives_ctrl_c_and_soft_reloads(tmp_path, capsys):
    k = _cpyemu()
    img = tmp_path / "circuitpy.img"
    p = subprocess.run([str(k / "make-texel-fs.sh"), str(img), str(ROOT)], capture_output=True,
                       text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    proc = subprocess.Popen([str(k / "run.sh"), "--pty", "--flash", str(img)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
    rng = random.Random(SEED)
    log = []
    try:
        assert proc.stdout is not None
        port = proc.stdout.readline().decode().strip()
        assert port.startswith("/dev/"), port
        emu = _Emu(proc)
        r = Raw(port, emu)
        try:
            r.raw()
            for n in range(ROUNDS):
                t0 = time.monotonic()
                how = ("raw-reset", "leave-raw", "friendly-reset", "raw-reset")[n]
                r.start("import texel.app as app\napp.start('pico_cpy')\nprint('PLAYING')\n"
                        "app.run_loop(120)")
                r.read_until(b"PLAYING", 300)
                time.sleep(rng.uniform(0.2, 3.0))
                r.s.write(b"\x03")                      # Ctrl-C inside the loop
                out, err = r.result(120)
                assert not err, err                     # run_loop takes its KeyboardInterrupt
                st = _status(r)
                carrier = r.exec("import texel.app as app; print(app._rt.hw._pwm.duty_cycle)")
                assert st["running"] and carrier == "0", (n, st, carrier)   # carrier off
                if how == "raw-reset":
                    r.soft_reset_raw()
                elif how == "leave-raw":
                    r.s.write(b"\x02")                  # mpremote's exit: the VM restarts
                    r.read_until(b">>> ", 60)
                    r.raw()
                else:                                   # Ctrl-D at the friendly REPL
                    r.s.write(b"\x02")
                    r.read_until(b">>> ", 60)
                    r.s.write(b"\x04")
                    r.read_until(b"soft reboot", 60)
                    r.read_until(b"Press any key to enter the REPL", 120)   # code.py ran
                    r.s.write(b"\r")
                    r.read_until(b">>> ", 60)
                    r.raw()
                assert not _status(r)["running"], n
                assert _free_gp16(r) == "GP16 free"
                assert emu.alive(), n
                log.append("%d %-14s %5.1f s" % (n, how, time.monotonic() - t0))
            r.s.write(b"\x02")
            r.drain()
        finally:
            r.close()
        mp = str(Path(sys.executable).with_name("mpremote"))
        q = subprocess.run([mp, "connect", port, "exec", "import texel.app as app; print(app.status())"],
                           capture_output=True, text=True, timeout=180)
        assert q.returncode == 0 and "'running': False" in q.stdout, q.stdout + q.stderr
        assert proc.poll() is None
    finally:
        stop_group(proc)
    with capsys.disabled():
        print("\n".join(["\ncircuitpython rounds (seed %d):" % SEED] + log))

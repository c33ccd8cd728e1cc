"""The link to a board: mpremote's serial transport (pinned in pyproject),
wrapped in this one module.

What crosses the wire is code the host writes itself around `repr()`
literals of plain data (`literal()` refuses anything else, NaN and inf
included: their repr is not a literal); user text is never pasted into code.
A display is never soft-reset: the raw REPL is entered without Ctrl-D, so a
texture playing in the board's timer IRQ keeps playing while the host talks.

Every failure is a `LinkError` whose text says what happened and what to
do; `DeviceError` carries the device's own ValueError text unchanged.

Every read has a deadline. mpremote's `read_until` checks its timeouts only
while no byte arrives, so a port that never stops talking (a board running a
program that prints, a GPS module, a modem) would keep the host reading
forever. `_DeadlineSerial` stands between mpremote and the serial port: a
read (or an `in_waiting` poll) after the current operation's deadline raises
TransportError, whatever mpremote's loop was doing. The raw REPL is entered
by this module's own `_Transport.enter_raw_repl`, with a bounded flush and no
printing of what the port sent.
"""
from __future__ import annotations

import ast
import io
import struct
import time
from contextlib import contextmanager, redirect_stdout
from typing import Any, Iterator

# mpremote is pinned (pyproject): its SerialTransport is the raw-REPL /
# raw-paste implementation used here.
from mpremote.transport import TransportError, TransportExecError
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


class Interrupted(KeyboardInterrupt):
    """Ctrl-C during a request; the text says what the board does now."""


class BoardError(LinkError):
    """The board raised an exception running host code (not a refusal):
    one line (the exception); .traceback has the board's whole text."""

    def __init__(self, text: str):
        lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
        super().__init__("the board raised an error: %s" % (_cut(lines[-1]) if lines
                                                             else "(no text)"))
        self.traceback = text


def _cut(text: str, n: int = 300) -> str:
    return text if len(text) <= n else text[:n] + "... (%d characters)" % len(text)


def unexpected(port: str, what: str, value: Any) -> LinkError:
    """A well-framed answer of the wrong shape: another program, an image of
    another version or a fault, never a TypeError deep in a command."""
    return LinkError("unexpected answer from %s to %s: %s" % (port, what, _cut(repr(value), 200)))


def answer(port: str, ans: Any, what: str) -> Any:
    """The value of a request's ('ok', value) / ('err', the device's
    ValueError text) answer (protocol.call and its kin): DeviceError for a
    refusal, LinkError for any other shape."""
    if not (type(ans) is tuple and len(ans) == 2 and ans[0] in ("ok", "err")
            and (ans[0] == "ok" or type(ans[1]) is str)):
        raise unexpected(port, what, ans)
    if ans[0] == "err":
        raise DeviceError(ans[1])
    return ans[1]


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


# --- deadlines -------------------------------------------------------------------

class _DeadlineSerial:
    """A serial port whose reads end at a deadline: read(), read_until-style
    polls (in_waiting / inWaiting) after `deadline` (time.monotonic()) raise
    TransportError naming what the port kept sending. Everything else is the
    port's own (attributes are read and set through to it)."""

    _own = ("_port", "deadline", "seconds", "tail")

    def __init__(self, port: Any):
        object.__setattr__(self, "_port", port)
        object.__setattr__(self, "deadline", None)     # None: no operation running
        object.__setattr__(self, "seconds", 0.0)       # the running operation's limit
        object.__setattr__(self, "tail", b"")          # the last bytes read (for the error)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._port, name)

    def __setattr__(self, name: str, value: Any) -> None:
        if name in self._own:
            object.__setattr__(self, name, value)
        else:
            setattr(self._port, name, value)

    def _check(self) -> None:
        if self.deadline is not None and time.monotonic() >= self.deadline:
            raise TransportError(_late(self.seconds, self.tail))

    def read(self, size: int = 1) -> bytes:
        self._check()
        data = self._port.read(size)
        if data:
            object.__setattr__(self, "tail", (self.tail + data)[-48:])
        return data

    def inWaiting(self) -> int:              # mpremote's spelling
        self._check()
        return self._port.in_waiting

    @property
    def in_waiting(self) -> int:
        self._check()
        return self._port.in_waiting


def _late(seconds: float, tail: bytes) -> str:
    """'no answer within 2 s; the port kept sending ...': one line."""
    text = "no answer within %g s" % seconds
    shown = " ".join(tail.decode("utf-8", "replace").split())[-40:]
    if shown:
        text += "; the port kept sending other text (last: %r)" % shown
    return text


def _why(e: BaseException) -> str:
    """An exception's text on one line."""
    return " ".join(str(e).split()) or type(e).__name__


# The slowest link a request's deadline allows for sending its code: below a
# 115,200-baud UART's ~11 KB/s (USB CDC boards are far faster).
MIN_BYTES_PER_S = 5000


class _Transport(SerialTransport):
    """mpremote's SerialTransport with a deadline on every read: each
    exec_raw (so also each call fs_writefile makes) and the raw-REPL entry
    run under one, and reads past it raise TransportError."""

    RAW_PROMPT = b"raw REPL; CTRL-B to exit\r\n"

    def __init__(self, port: str, baudrate: int, timeout: float):
        # pyserial's per-read limit: mpremote reads a pty with blocking
        # read(1) calls, so a silent board still returns to the deadline check.
        super().__init__(port, baudrate=baudrate, exclusive=True, timeout=min(1.0, timeout))
        self.op_timeout = timeout
        # a port that stops reading (a stuck USB device) must not block a write forever
        serial: Any = self.serial  # type: ignore[has-type]  # pyserial's, set by SerialTransport
        serial.write_timeout = max(timeout, 1.0)
        self.serial = _DeadlineSerial(serial)

    @contextmanager
    def deadline(self, seconds: float, shown: float | None = None) -> Iterator[None]:
        """Reads in the block end `seconds` from now (or at an earlier
        deadline already running); the error names `shown` seconds (the
        timeout the caller asked for), default `seconds`."""
        s = self.serial
        old = (s.deadline, s.seconds)
        end = time.monotonic() + seconds
        if old[0] is None or end < old[0]:
            s.deadline, s.seconds = end, seconds if shown is None else shown
        s.tail = b""
        try:
            yield
        finally:
            s.deadline, s.seconds = old

    def _enter_raw_repl(self, soft_reset: bool = False, timeout_overall: float = 10) -> None:
        """Ctrl-C, then Ctrl-A and wait for the raw REPL banner, all within
        timeout_overall: what the port sends meanwhile is read and dropped
        (mpremote's own flush loop never ends on a port that keeps talking,
        and prints what it read on failure). Never a soft reset."""
        if soft_reset:
            raise ValueError("texelpad never soft-resets a board")
        with self.deadline(timeout_overall):
            self.serial.write(b"\r\x03")         # Ctrl-C: interrupt a running program
            n = self.serial.in_waiting
            while n > 0:                          # flush (bounded by the deadline)
                self.serial.read(n)
                n = self.serial.in_waiting
            self._ctrl_a(b"\r\x01")              # Ctrl-A: the raw REPL
            self._read_banner(retry=True)

    def _read_banner(self, retry: bool) -> bool:
        """Read up to the raw REPL's banner (under the running deadline) and
        leave its ">" for exec_raw, as mpremote does; True when texel.app.serve()
        answered it (SERVE_MARK before it: it takes the standard raw mode only).
        Output still in flight (a program that printed until Ctrl-C) is read in
        bulk, but never the last len(banner) + 1 bytes waiting: the banner and
        its ">" are the last the board sends. retry: Ctrl-A again after
        RETRY_CTRL_A_S of quiet - CircuitPython throws its console input away
        at a Ctrl-C (the Ctrl-A behind it may be gone) and code.py's end waits
        for a key."""
        keep = len(self.RAW_PROMPT) + 1
        tail = len(SERVE_MARK) + len(self.RAW_PROMPT)
        data = b""
        again = time.monotonic() + RETRY_CTRL_A_S
        while not data.endswith(self.RAW_PROMPT):
            n = self.serial.in_waiting        # raises at the deadline
            new = self.serial.read(n - keep if n > keep else 1)
            if new:
                data = (data + new)[-tail:]
                again = time.monotonic() + RETRY_CTRL_A_S
            elif retry and time.monotonic() > again:
                self._ctrl_a(b"\r\x01")
                again = time.monotonic() + RETRY_CTRL_A_S
        # one banner read (two read together count once: owed is an upper bound,
        # as CircuitPython may drop a Ctrl-A); _answer reads past at most that many
        self.banners_owed = max(0, self.banners_owed - 1)
        self.in_raw_repl = True
        self.serve_banner = data.endswith(SERVE_MARK + self.RAW_PROMPT)
        if self.serve_banner:
            self.use_raw_paste = False
        return self.serve_banner

    serve_banner = False        # the last banner came from texel.app.serve() (SERVE_MARK)
    banners_owed = 0            # Ctrl-As sent whose raw-REPL banners may come yet (_answer)

    def _ctrl_a(self, data: bytes) -> None:
        """Send `data`, which ends in a Ctrl-A, and count the banner it is owed."""
        self.banners_owed += 1
        self.serial.write(data)

    def knock(self, seconds: float) -> str | None:
        """Ctrl-A alone, no Ctrl-C: a board at its REPL (either) answers with
        the raw REPL's banner, a CircuitPython board running texel.app.serve()
        with SERVE_MARK before it (texel/serve.py: it plays on and answers as
        the raw REPL does; a Ctrl-C would stop its display). Returns "serve",
        "raw", or None when no banner came within `seconds` (a program runs:
        enter_raw_repl's Ctrl-C is for that). Never a soft reset."""
        try:
            with self.deadline(seconds):
                # Ctrl-A alone: a friendly REPL acts on it only at an empty line, so a
                # half-typed line is neither run nor lost (then no banner: the Ctrl-C path)
                self._ctrl_a(b"\x01")
                return "serve" if self._read_banner(retry=False) else "raw"
        except TransportError:
            return None

    def read_until(self, min_num_bytes: int, ending: bytes, timeout: float | None = 10,
                   data_consumer: Any = None, timeout_overall: float | None = None) -> bytes:
        if timeout_overall is None:
            return super().read_until(min_num_bytes, ending, timeout, data_consumer)
        with self.deadline(timeout_overall):
            return super().read_until(min_num_bytes, ending, timeout, data_consumer,
                                      timeout_overall)

    # --- answers read before the command ends (texel.wire.reply) ----------------
    # A command that prints its answer as one line and then goes on working (the
    # board's collection after a push) is read up to that line only: the rest of
    # its output and its two end markers (\x04 after the output, \x04 after the
    # error text) are the tail, read before the next use of the raw REPL.
    tail: bytes | None = None       # bytes read past the answer; None: nothing pending
    late_error: str = ""            # error text a tail ended with (the work after an answer)

    def settle(self) -> None:
        """Read the pending tail (if any) to the command's end; keeps its
        error text, if it had one, in late_error."""
        if self.tail is None:
            return
        buf, self.tail = self.tail, None
        with self.deadline(self.op_timeout):
            while buf.count(b"\x04") < 2:      # byte by byte: the prompt after it stays
                buf += self.serial.read(1)
        err = buf.split(b"\x04")[1]
        if err:
            self.late_error = err.decode("utf-8", "replace")

    def _answer(self) -> bytes:
        """The board's 2-byte answer (b"OK", b"R\\x01", ...), waited for until
        the operation's deadline, past the banners still owed: a board slow
        to answer Ctrl-A got it again (RETRY_CTRL_A_S) and answers both, the
        second banner after _read_banner has returned (test_link_late_banner)."""
        got = self._read_exact(2)
        # a serving board's own banner (texel/serve.py _grace answers a Ctrl-C with
        # one when no Ctrl-A follows soon) is never an answer where "OK" is awaited
        while ((self.banners_owed and got in (b"ra", b"\r\n", SERVE_MARK[:2]))
               or (not self.use_raw_paste and got == SERVE_MARK[:2])):
            self.banners_owed = max(0, self.banners_owed - 1)
            while not got.endswith(self.RAW_PROMPT + b">"):
                got += self.serial.read(1)                  # raises at the deadline
            got = self._read_exact(2)
        self.banners_owed = 0       # any not come by now were dropped (CircuitPython)
        return got

    def raw_paste_write(self, command_bytes: bytes) -> None:
        """mpremote's, but its 2-byte window size read until the operation's
        deadline (mpremote's one pyserial read returns short on a loaded
        emulator, and it unpacks what came unchecked)."""
        window_size = struct.unpack("<H", self._read_exact(2))[0]
        window_remain = window_size
        i = 0
        while i < len(command_bytes):
            while window_remain == 0 or self.serial.inWaiting():
                data = self.serial.read(1)
                if data == b"\x01":            # a new window may be sent
                    window_remain += window_size
                elif data == b"\x04":          # the board ended it: acknowledge
                    self.serial.write(b"\x04")
                    return
                elif data:
                    raise TransportError("unexpected read during raw paste: %r" % data)
            b = command_bytes[i:min(i + window_remain, len(command_bytes))]
            self.serial.write(b)
            window_remain -= len(b)
            i += len(b)
        self.serial.write(b"\x04")
        data = self.read_until(1, b"\x04")
        if not data.endswith(b"\x04"):
            raise TransportError("could not complete raw paste: %r" % data)

    def _read_exact(self, n: int) -> bytes:
        got = b""
        while len(got) < n:
            got += self.serial.read(n - len(got))        # raises at the deadline
        return got

    def exec_raw_no_follow(self, command: Any) -> None:
        """mpremote's, but every answer read by _answer: until the operation's
        deadline (serve reads the console between refreshes, and an emulated
        board under load takes longer than mpremote's one read), and past late
        banners. The standard raw mode serves CircuitPython's texel/serve.py."""
        self.settle()
        data = bytes(command, "utf8") if isinstance(command, str) else bytes(command)
        if not self.read_until(1, b">").endswith(b">"):
            raise TransportError("could not enter raw repl")
        if self.use_raw_paste:
            self.serial.write(b"\x05A\x01")
            got = self._answer()
            if got == b"R\x01":
                self.raw_paste_write(data)
                return
            if got != b"R\x00":        # no raw paste at all: it answered as Ctrl-A
                # (mpremote's ending: the banner's first bytes are read already)
                banner = got + self.read_until(1, b"w REPL; CTRL-B to exit\r\n>")
                if not banner.endswith(self.RAW_PROMPT + b">"):
                    raise TransportError("could not enter raw repl")
            self.use_raw_paste = False
        for i in range(0, len(data), 256):
            self.serial.write(data[i:i + 256])
            time.sleep(0.01)
        self.serial.write(b"\x04")
        got = self._answer()
        if got != b"OK":
            raise TransportError("could not exec command (response: %r)" % got)

    def exec_reply_first(self, command: bytes, timeout: float | None = None
                         ) -> tuple[bytes, bytes]:
        """Send and run `command` and return (its output, its error text) as
        soon as its first line has arrived, leaving the rest as the tail; a
        command that ends before printing a line returns as exec_raw does."""
        t = self.op_timeout if timeout is None else timeout
        with self.deadline(t + len(command) / MIN_BYTES_PER_S, t), redirect_stdout(io.StringIO()):
            self.exec_raw_no_follow(command)
            # byte by byte, as mpremote's read_until: nothing past the line (or past
            # the end markers: the next prompt's ">" stays for the next command)
            buf = bytearray()
            while True:
                c = self.serial.read(1)
                buf += c
                if c == b"\n":
                    self.tail = b""
                    return bytes(buf), b""
                if c == b"\x04":               # ended without a line: its error text
                    err = bytearray()
                    while not err.endswith(b"\x04"):
                        err += self.serial.read(1)
                    return bytes(buf[:-1]), bytes(err[:-1])

    def enter_raw_repl(self, soft_reset: bool = False, timeout_overall: float = 10) -> None:
        self.tail = None        # Ctrl-C and the flush below end whatever was pending
        self._enter_raw_repl(soft_reset, timeout_overall)

    def exec_raw(self, command: bytes, timeout: float | None = None,
                 data_consumer: Any = None) -> tuple[bytes, bytes]:
        """Send and run `command`; the whole exchange ends within `timeout`
        (default: the link's) plus the time to send the command at
        MIN_BYTES_PER_S (a 512 KB scene over a 115,200-baud UART)."""
        t = self.op_timeout if timeout is None else timeout
        # mpremote print()s what it read when a board falls out of the raw
        # REPL; that would land in the host's own output (--json): dropped
        with self.deadline(t + len(command) / MIN_BYTES_PER_S, t), redirect_stdout(io.StringIO()):
            return super().exec_raw(command, timeout=t, data_consumer=data_consumer)


# --- the link -----------------------------------------------------------------

def _answer_value(line: str) -> Any:
    """The value of a board's answer line: a repr() literal, each float as its
    bits (`<bits>j`) where the board's C core wrote it (protocol.floats_from_bits).
    ValueError, SyntaxError, TypeError, MemoryError or RecursionError for a line
    that is not one (TypeError: '{[]: 1}' parses but cannot be built; the others:
    a line of 100,000 nested operators)."""
    value = ast.literal_eval(line)
    return protocol.floats_from_bits(value) if "j" in line else value


# What texel.app.serve() (device/texel/serve.py MARK) prints when it starts and
# before each raw-REPL banner it answers.
SERVE_MARK = b"\x1etexel-serve\r\n"
# s a board at its REPL takes to answer a bare Ctrl-A (Link: after it, Ctrl-C)
KNOCK_S = 1.0
# s without a banner after which _enter_raw_repl sends Ctrl-A again
RETRY_CTRL_A_S = 1.5
# What texel.wire.stand() prints when it starts reading frames (Link.eval_frame),
# then its line's end ("\r\n": the board's stdout makes "\n" that)
STAND_MARK = b"\x1etexel-stand"
# The one command that starts it
STAND = b"__import__('texel.wire').wire.stand()"
# Bytes of a frame per write (a write must end within the port's write_timeout)
FRAME_PIECE = 1024
# The link's last command on a CircuitPython board that plays (Link.close(serve=True))
HAND_OVER = b"import texel.app as _a\n_a.serve(False, True)\n_a = None"


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
            # every read under a deadline (_Transport): a silent board and one
            # that never stops talking both end in a LinkError
            self.t = _Transport(port, baudrate=baudrate, timeout=timeout)
        except TransportError as e:
            raise NoBoard("cannot open %s: %s" % (port, e)) from None
        # serving: the board runs texel.app.serve() (CircuitPython, playing): it
        # answers as the raw REPL does, and this link never interrupts it
        self.serving = False
        # standing: the board runs texel.wire.stand() (eval_frame): every other
        # exchange first ends it (_sit)
        self.standing = False
        try:
            # a bare Ctrl-A first: a board at its REPL, or serving, answers it
            # without an interrupt; Ctrl-C only when a program holds the REPL
            mode = self.t.knock(min(KNOCK_S, timeout))
            self.serving = mode == "serve"
            if mode is None:
                # soft_reset=False: never restart a playing display (docs/background.md §4)
                self.t.enter_raw_repl(soft_reset=False, timeout_overall=timeout)
        except (TransportError, serial.SerialException, OSError) as e:
            self._close_port()
            raise NotTexelpad("%s does not answer as a MicroPython board (no raw REPL within "
                              "%g s: %s). Is it a MicroPython/CircuitPython board, and is no "
                              "program holding its REPL?" % (port, timeout, _why(e))) from None

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

    def close(self, serve: bool = False) -> None:
        """Leave the raw REPL (Ctrl-B, no reset) and release the port. On a
        serving board (CircuitPython) nothing is sent: it plays on, serving.
        serve=True (a CircuitPython board: Ctrl-B would restart its VM and
        end what plays): the last command is texel.app.serve(False), which
        plays on and serves when something plays, else ends at once (then
        Ctrl-B)."""
        if getattr(self, "t", None) is None:
            return
        try:
            self._sit()
            self.t.settle()             # the last answer's tail (a collection) first
            handed = False
            if serve and not self.serving:
                try:
                    handed = self._hand_over()
                except Exception:
                    # Ctrl-B below: a serve that did start returns and stops its display,
                    # else CircuitPython's VM restarts; either way nothing is left driven
                    handed = False
            if not self.serving and not handed:
                self.t.exit_raw_repl()
        except Exception:
            pass
        self._close_port()
        self.t = None                           # type: ignore[assignment]  # closed: no transport

    def _hand_over(self) -> bool:
        """Run HAND_OVER without waiting for its end: True once the board says
        it serves (SERVE_MARK), False when the command ended (nothing plays)."""
        with self.t.deadline(self.timeout), redirect_stdout(io.StringIO()):
            self.t.exec_raw_no_follow(HAND_OVER)
            buf = b""
            while not buf.endswith(SERVE_MARK):
                buf = (buf + self.t.serial.read(1))[-len(SERVE_MARK):]
                if buf.endswith(b"\x04"):          # ended: read its error text too
                    self.t.tail = b"\x04"
                    self.t.settle()
                    return False
        self.serving = True
        return True

    # every exchange with the board (exec, resync, soft_reset) counts one: a status a
    # Board remembers (link/board.py Board._known_status) is its own only while this
    # count is where it was left - nothing else has run on the board since
    commands = 0

    def resync(self, timeout: float | None = None) -> None:
        """Interrupt what the board runs (Ctrl-C) and enter the raw REPL again,
        without a reset: a clean state after a request was cut off half-way
        (a timeout, Ctrl-C on the host). LinkTimeout when the board does not
        answer within the timeout."""
        if self.t is None:
            raise LinkError("the link to %s is closed" % self.port)
        self.commands += 1
        self.serving = False        # Ctrl-C ends texel.app.serve(): its display stops
        self.standing = False       # and texel.wire.stand() (the display plays on)
        try:
            self.t.enter_raw_repl(soft_reset=False,
                                  timeout_overall=self.timeout if timeout is None else timeout)
        except (TransportError, serial.SerialException, OSError) as e:
            raise LinkTimeout("%s does not answer (%s); the board may have reset or been "
                              "unplugged" % (self.port, _why(e))) from None

    def soft_reset(self, timeout: float | None = None) -> None:
        """Soft-reset the board from the raw REPL (Ctrl-D at its prompt): a
        fresh interpreter and heap, files kept; main.py does not run from the
        raw REPL, so nothing starts playing. Only deploy uses it, after the
        display was stopped for the writes (a playing display is never
        reset). Back in the raw REPL afterwards."""
        if self.t is None:
            raise LinkError("the link to %s is closed" % self.port)
        self.commands += 1
        t = self.timeout if timeout is None else timeout
        self._sit()
        was_serving = self.serving
        if was_serving:
            # out of texel.app.serve(): Ctrl-C stops its display. Run by the link's hand-over
            # in the raw REPL, it then answers as the raw REPL would, and a Ctrl-B ends it
            # (that raw REPL's prompt follows); run by code.py, code.py ends, and the
            # resync is at CircuitPython's own raw REPL already
            self.resync(t)
        if was_serving and self.t.serve_banner:
            with self.t.deadline(t):
                self.t.serial.write(b"\x02")
                # serve reads what comes with its Ctrl-B and drops it: the Ctrl-D waits for
                # the raw REPL's prompt, or code.py's "Press any key ... CTRL-D to reload."
                end = b""
                while not end.endswith(b"\x04>"):
                    end = (end + self.t.serial.read(1))[-32:]
        try:
            self.t.settle()
            with self.t.deadline(t):
                self.t.serial.write(b"\x04")
                self.t.read_until(1, b"soft reboot\r\n", timeout=t)
                # then boot.py may print; the banner ends it (its ">" is left for exec);
                # a soft reset from the raw REPL runs no main.py/code.py, on either port
                self.t.read_until(1, _Transport.RAW_PROMPT, timeout=t)
        except (TransportError, serial.SerialException, OSError) as e:
            raise LinkTimeout("%s did not come back from a soft reset (%s)"
                              % (self.port, _why(e))) from None

    def exec(self, code: str, timeout: float | None = None, reply_first: bool = False) -> str:
        """Run host-written code on the board; return what it printed.
        A device exception raises LinkError with the device's traceback.
        reply_first: return once the first line has arrived (the code goes
        on working on the board: eval_reply)."""
        if self.t is None:
            raise LinkError("the link to %s is closed" % self.port)
        self.commands += 1
        self._sit()
        data = code.encode("utf-8")
        self.sent += len(data)
        run = self.t.exec_reply_first if reply_first else self.t.exec_raw
        with self._answering():
            out, err = run(data, timeout=self.timeout if timeout is None else timeout)
        self.received += len(out) + len(err)
        if err:
            raise BoardError(err.decode("utf-8", "replace"))
        return out.decode("utf-8", "replace")

    def eval_reply(self, code: str, timeout: float | None = None) -> Any:
        """eval() of code whose first printed line is its answer and which
        then goes on working (texel.wire.reply: the collection after a push):
        returns when that line arrives; the next use of the link first reads
        the rest."""
        return self.eval(code, timeout, reply_first=True)

    def eval_frame(self, head: bytes, data: bytes, timeout: float | None = None) -> Any:
        """A request to the board's standing reader (texel.wire.stand: a header
        line and its data, protocol.staged_frame), started first when it does not
        run: returns the value of its one answer line, as eval_reply does - no
        compile on the board, and no raw-REPL exchange per request. A board that
        raised answers ('raise', its text): BoardError, and the reader goes on."""
        if self.t is None:
            raise LinkError("the link to %s is closed" % self.port)
        self.commands += 1
        t = self.timeout if timeout is None else timeout
        self.sent += len(head) + len(data)
        with self._answering():
            with self.t.deadline(t + (len(head) + len(data)) / MIN_BYTES_PER_S, t), \
                    redirect_stdout(io.StringIO()):
                if not self.standing:
                    self._stand()
                frame = head + data
                for i in range(0, len(frame), FRAME_PIECE):    # each write within its timeout
                    self.t.serial.write(frame[i:i + FRAME_PIECE])
                buf = bytearray()
                while not buf.endswith(b"\n"):
                    c = self.t.serial.read(1)
                    if c == b"\x04":           # the reader itself ended: its error text
                        err = self._ended_text()
                        self.resync()           # what it did not read is at the raw REPL's prompt
                        raise BoardError(err or "the board's reader ended")
                    buf += c
        self.received += len(buf)
        out = bytes(buf).decode("utf-8", "replace").strip()
        try:
            value = _answer_value(out)
        except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
            value = None
        if type(value) is not tuple or len(value) not in (2, 3) or \
                value[0] not in ("ok", "err", "raise"):
            # not a frame's answer (a line something else printed: an interrupt handler's
            # traceback): the answers are out of step with the frames - start afresh
            self.resync()
            raise LinkError("unexpected answer from %s: %r" % (self.port, out[-200:]))
        if value[0] == "raise":
            if len(value) == 3:         # the reader ended (a frame it could not read)
                self.resync()
            raise BoardError(str(value[1]))
        return value

    def _stand(self) -> None:
        """Start texel.wire.stand() (under the caller's deadline): its mark
        says it reads frames; an error instead (an image without it) raises."""
        self.t.settle()
        self.t.exec_raw_no_follow(STAND)
        got = b""
        while not (got.endswith(b"\n") and STAND_MARK in got):
            c = self.t.serial.read(1)
            if c == b"\x04":                   # it ended at once: its error text
                raise BoardError(self._ended_text() or "texel.wire.stand() ended at once")
            got = (got + c)[-len(STAND_MARK) - 4:]
        self.standing = True

    def _ended_text(self) -> str:
        """After the \\x04 that ends a command's output: its error text, read to
        its own \\x04 (the raw REPL's prompt is left for the next command)."""
        self.t.late_error = ""
        self.t.tail = b"\x04"
        self.t.settle()
        return self.t.late_error

    def _sit(self) -> None:
        """End the standing reader, if it runs (an empty line: stand() returns
        and the raw REPL prints the command's end, read here), so that the next
        exchange finds the raw REPL. A board that does not answer raises
        LinkTimeout; the link then knows nothing of it (resync)."""
        if not self.standing:
            return
        self.standing = False
        with self._answering(), redirect_stdout(io.StringIO()):
            self.t.serial.write(b"\n")
            self.t.tail = b""
            self.t.settle()

    @contextmanager
    def _answering(self) -> Iterator[None]:
        """The port's failures in the block (a deadline passed, the port gone) as
        LinkTimeout, in the words every exchange uses."""
        try:
            yield
        except TransportError as e:
            raise LinkTimeout("%s stopped answering (%s); the board may have reset or been "
                              "unplugged" % (self.port, e)) from None
        except (serial.SerialException, OSError) as e:
            raise LinkTimeout("%s: the serial link failed (%s); was the board unplugged?"
                              % (self.port, e)) from None

    def eval(self, code: str, timeout: float | None = None, reply_first: bool = False) -> Any:
        """Run code whose last printed line is a repr() literal; return its value."""
        out = self.exec(code, timeout, reply_first).strip()
        last = out.splitlines()[-1] if out else ""
        try:
            return _answer_value(last)
        except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
            raise LinkError("unexpected answer from %s: %r" % (self.port, out[-200:])) from None

    def call(self, module: str, func: str, *args: Any, timeout: float | None = None,
             **kwargs: Any) -> Any:
        """`module.func(*args, **kwargs)` on the board, arguments as literals; a
        device ValueError becomes DeviceError with the device's text."""
        return answer(self.port, self.eval(protocol.call(module, func, args, kwargs), timeout),
                      "%s.%s()" % (module, func))

    def write_file(self, path: str, data: bytes, chunk: int = 2048, progress=None) -> None:
        """Write `data` to `path` on the board with mpremote's fs_writefile, in
        chunks of bytes literals (raw-paste flow control keeps the board's
        buffer from overrunning); progress(bytes_done) after each chunk."""
        if self.t is None:
            raise LinkError("the link to %s is closed" % self.port)
        self._sit()
        try:
            self.t.fs_writefile(path, bytes(data), chunk_size=chunk, progress_callback=(
                (lambda done, total: progress(done)) if progress else None))
        except TransportExecError as e:           # the board's own error (after a reset, ...)
            lines = [ln.strip() for ln in e.error_output.splitlines() if ln.strip()]
            raise LinkError("the board raised an error while writing %s: %s"
                            % (path, lines[-1] if lines else "(no text)")) from None
        except TransportError as e:
            raise LinkTimeout("%s stopped answering while writing %s (%s)"
                              % (self.port, path, e)) from None
        except UnicodeDecodeError:          # mpremote decodes the board's error text strictly
            raise LinkError("the board raised an error while writing %s (its text is not "
                            "UTF-8)" % path) from None
        except (serial.SerialException, OSError) as e:
            raise LinkError("%s: writing %s failed (%s)" % (self.port, path, e)) from None
        # what fs_writefile sent: open, one "w(<bytes literal>)" per chunk, close
        self.sent += len(path) + 32 + sum(len(repr(data[i:i + chunk])) + 3
                                          for i in range(0, len(data), chunk))

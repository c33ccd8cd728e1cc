"""A board that misbehaves on demand, for the "link" fuzz target: a fake
pyserial port whose other end is a model of MicroPython's REPL (friendly
REPL, raw REPL, raw-paste mode with its flow-control window, Ctrl-A/B/C/D,
soft reboot), on a virtual clock.

The requests the host sends are really run: the code is exec'd in a sandbox
namespace (files in memory, `os` faked) that imports the real texel and
texel.app under CPython, so every answer is the one a board running the
image would give - until the plan (Plan, drawn by hypothesis) corrupts it:

- the byte stream the board sends: cut (silent from then on), bytes
  inserted, deleted or replaced, an endless flood, a stall - each at a byte
  offset or at the n-th \\x04, '>', 'R', \\x01 or 'O' (the framing bytes);
- an answer: replaced by junk (bytes, text, wrong literals: "{[]: 1}",
  "('ok',)", 300 open brackets, 5,000 digits, 100,000 minus signs), text
  added, an error output (a traceback, invalid UTF-8), a slow or endless
  program, one that prints forever, a huge output, a soft reset;
- the port: open fails (busy, missing, no permission), a read or write
  raises (unplugged, write timeout) once or from then on;
- the board: starts in the friendly REPL, already in the raw REPL or busy
  printing; raw paste accepted with any window (1 .. 65,535), refused
  (R\\x00) or unknown (old firmware); bytes take 1 us (USB) to 100 us
  (a UART) each; answers come after a latency.

Time is virtual: a read that waits moves the clock to when the bytes
arrive or to its timeout; every serial call costs a little, so a loop that
polls reaches its deadline. `time` is replaced in the link's modules and
mpremote's (World.patches), so a 30 s timeout costs no real time. A case
that makes more than Clock.limit clock calls, or runs past the watchdog,
is a hang.
"""
from __future__ import annotations

import builtins
import contextlib
import errno
import io
import math
import struct
import types
from dataclasses import dataclass, field
from typing import Any
from unittest import mock

import serial

import fuzzlib

RAW_BANNER = b"raw REPL; CTRL-B to exit\r\n>"
FRIENDLY_BANNER = (b"MicroPython v1.28.0 on 2026-01-01; Raspberry Pi Pico with RP2040\r\n"
                   b"Type \"help()\" for more information.\r\n>>> ")
KBI = (b"Traceback (most recent call last):\r\n  File \"<stdin>\", line 1, in <module>\r\n"
       b"KeyboardInterrupt: \r\n")
FLOOD_CAP = 65536            # unread bytes a flood keeps (a real port's buffer drops the rest)


class Spin(BaseException):
    """Too many clock or serial calls in one case: a loop that does not end."""


class NoDeadline(AssertionError):
    """A read from the port while no deadline runs (or after it)."""


# --- the clock --------------------------------------------------------------------------------

class Clock:
    """Virtual time. Every call costs: at least call_cost, and more the
    longer the host has been reading since it last wrote (that time /
    SLOWDOWN): a loop that polls a port which never stops sending reaches a
    60 s deadline in ~40,000 calls, while an answer - the first fraction of
    a second after a request - is read at full resolution."""

    SLOWDOWN = 5_000

    def __init__(self, call_cost: float = 2e-5, limit: int = 400_000):
        self.t0 = self.t = self.t_mark = 1000.0
        self.calls = 0
        self.call_cost = call_cost
        self.limit = limit

    def mark(self) -> None:
        """The host wrote: a new exchange begins."""
        self.t_mark = self.t

    def cost(self) -> float:
        return max(self.call_cost, (self.t - self.t_mark) / self.SLOWDOWN)

    def tick(self, cost: float | None = None) -> None:
        self.calls += 1
        if self.calls > self.limit:
            raise Spin("more than %d clock/serial calls in one case (virtual t = %.3f s): "
                       "a loop that does not end" % (self.limit, self.t - self.t0))
        self.t += self.cost() if cost is None else cost

    def monotonic(self) -> float:
        self.tick(self.cost() / 10)
        return self.t

    def sleep(self, s: float) -> None:
        self.tick(max(0.0, float(s)))

    def module(self) -> types.SimpleNamespace:
        """What the patched modules see as `time`."""
        return types.SimpleNamespace(monotonic=self.monotonic, perf_counter=self.monotonic,
                                     time=lambda: 1.7e9 + self.monotonic(), sleep=self.sleep,
                                     ticks_ms=lambda: int(self.monotonic() * 1000))


def _cycle(pattern: bytes, start: int, n: int) -> bytes:
    """Bytes start .. start + n of pattern repeated forever."""
    off = start % len(pattern)
    return (pattern * ((off + n) // len(pattern) + 1))[off:off + n]


# --- what the board has sent --------------------------------------------------------------------

class Stream:
    """Bytes on their way to the host, each with its arrival time: chunk
    [start, data, pos, flood, interruptible]; byte j of a chunk arrives at
    start + (j + 1) * byte_s; a flood's data is a pattern repeated forever."""

    def __init__(self, byte_s: float):
        self.byte_s = byte_s
        self.chunks: list[list] = []

    def end(self) -> float:
        if not self.chunks:
            return 0.0
        c = self.chunks[-1]
        return math.inf if c[3] else c[0] + len(c[1]) * self.byte_s

    def emit(self, data: bytes, at: float) -> None:
        if data:
            self.chunks.append([max(at, self.end()), bytes(data), 0, False, False])

    def flood(self, pattern: bytes, at: float, interruptible: bool) -> None:
        self.chunks.append([max(at, self.end()), pattern or b"?", 0, True, interruptible])

    def _arrived(self, c: list, now: float) -> int:
        n = int(math.floor((now - c[0]) / self.byte_s + 1e-9))
        if n < 0:
            n = 0
        if c[3]:
            return min(n, c[2] + FLOOD_CAP)
        return min(n, len(c[1]))

    def available(self, now: float) -> int:
        total = 0
        for c in self.chunks:
            a = self._arrived(c, now)
            total += max(0, a - c[2])
            if c[3] or a < len(c[1]):
                break
        return total

    def time_of(self, n: int) -> float:
        """When the n-th unread byte arrives (inf: never)."""
        for c in self.chunks:
            left = math.inf if c[3] else len(c[1]) - c[2]
            if n <= left:
                return c[0] + (c[2] + n) * self.byte_s
            n -= left
        return math.inf

    def take(self, n: int) -> bytes:
        out = bytearray()
        while n > 0 and self.chunks:
            c = self.chunks[0]
            if c[3]:
                out += _cycle(c[1], c[2], n)
                c[2] += n
                return bytes(out)
            k = min(n, len(c[1]) - c[2])
            out += c[1][c[2]:c[2] + k]
            c[2] += k
            n -= k
            if c[2] >= len(c[1]):
                self.chunks.pop(0)
        return bytes(out)

    def stop_flood(self, now: float) -> None:
        """An interruptible flood (a program printing) ends at `now`: what
        arrived stays, nothing more comes from it, nor anything queued after it."""
        for i, c in enumerate(self.chunks):
            if c[3] and c[4]:
                a = self._arrived(c, now)
                c[1] = _cycle(c[1], c[2], max(0, a - c[2]))
                c[0], c[2], c[3] = c[0] + c[2] * self.byte_s, 0, False
                del self.chunks[i + 1:]
                return


# --- the plan ------------------------------------------------------------------------------

@dataclass
class Plan:
    start: str = "friendly"              # friendly | raw | busy
    paste: str = "ok"                    # ok | refuse | old
    window: int = 256
    byte_s: float = 1e-5
    latency: float = 0.0
    running: bool = True                 # texelpad plays when the host comes
    stream_faults: list = field(default_factory=list)   # (trigger, kind, arg)
    answers: dict = field(default_factory=dict)         # exchange index -> (kind, arg)
    port_faults: list = field(default_factory=list)     # (op, k, how, sticky)

    def clean(self) -> bool:
        return (self.start != "busy" and not self.stream_faults and not self.answers
                and not self.port_faults and self.window >= 1)


class FakeOs:
    """The `os` the sandboxed requests see: files in memory."""

    def __init__(self, files: dict):
        self.files = files

    def stat(self, p):
        if p in self.files:
            return (0x8000, 0, 0, 0, 0, 0, len(self.files[p]), 0, 0, 0)
        if any(f.startswith(p.rstrip("/") + "/") for f in self.files) or p in ("", "/", "."):
            return (0x4000, 0, 0, 0, 0, 0, 0, 0, 0, 0)
        raise OSError(errno.ENOENT, "ENOENT")

    def remove(self, p):
        if p not in self.files:
            raise OSError(errno.ENOENT, "ENOENT")
        del self.files[p]

    def rename(self, a, b):
        if a not in self.files:
            raise OSError(errno.ENOENT, "ENOENT")
        self.files[b] = self.files.pop(a)

    def mkdir(self, p):
        raise OSError(errno.EEXIST, "EEXIST")

    def statvfs(self, p):
        return (4096, 4096, 1000, 500, 500, 0, 0, 0, 0, 255)

    def ilistdir(self, d):
        return iter(())

    def listdir(self, d="."):
        return []


class FakeFile(io.BytesIO):
    def __init__(self, files: dict, path: str, mode: str):
        super().__init__(files.get(path, b"") if "r" in mode or "a" in mode else b"")
        self.files, self.path, self.mode = files, path, mode
        if "a" in mode:
            self.seek(0, 2)
        if "r" in mode and path not in files:
            raise OSError(errno.ENOENT, "ENOENT")

    def close(self):
        if not self.closed and ("w" in self.mode or "a" in self.mode):
            self.files[self.path] = self.getvalue()
        super().close()


# --- the board --------------------------------------------------------------------------------

class Device:
    def __init__(self, plan: Plan, clock: Clock):
        self.plan, self.clock = plan, clock
        self.stream = Stream(plan.byte_s)
        self.state = "raw" if plan.start == "raw" else "friendly"
        self.line = bytearray()
        self.paste_buf = bytearray()
        self.paste_used = 0
        self.running: tuple | None = None        # (t_end, out, err)
        self.queue = bytearray()                 # input that came while a program ran
        self.exchanges = 0
        self.files: dict[str, bytes] = {}
        self.sent = 0                            # bytes emitted (fault offsets)
        self.nth: dict[bytes, int] = {}
        self.faults = list(plan.stream_faults)
        self.dead = False
        self.flooding = False
        os_ = FakeOs(self.files)

        def _import(name, globals=None, locals=None, fromlist=(), level=0):
            if name in ("os", "uos"):
                return os_
            return builtins.__import__(name, globals, locals, fromlist, level)
        self._out = io.StringIO()

        def _print(*a, sep=" ", end="\n", file=None, flush=False):
            self._out.write(sep.join(str(x) for x in a) + end)
        box = dict(builtins.__dict__)
        box.update(__import__=_import, print=_print,
                   open=lambda p, mode="r", *a, **k: FakeFile(self.files, p, mode))
        self.globals: dict[str, Any] = {"__builtins__": box, "__name__": "__main__"}
        if plan.start == "busy":                 # a program printing when the host comes
            self.state = "busy"
            self.stream.flood(b"temperature 21.5 C\r\n", clock.t, interruptible=True)

    # --- output, through the plan's faults ---------------------------------------
    def emit(self, data: bytes, at: float) -> None:
        at += self.plan.latency
        while data and not self.dead:
            hit, pos = None, None
            for f in self.faults:
                p = self._trigger(f[0], data)
                if p is not None and (pos is None or p < pos):
                    hit, pos = f, p
            if hit is None:
                self._count(data)
                self.stream.emit(data, at)
                self.sent += len(data)
                return
            self.faults.remove(hit)
            head, data = data[:pos], data[pos:]
            self._count(head)
            self.stream.emit(head, at)
            self.sent += len(head)
            kind, arg = hit[1], hit[2]
            if kind == "cut":
                self.dead = True
            elif kind == "insert":
                self.stream.emit(arg, at)
                self.sent += len(arg)
            elif kind == "delete":
                self._count(data[:arg])
                self.sent += len(data[:arg])
                data = data[arg:]
            elif kind == "flip":
                data = bytes([arg]) + data[1:]
            elif kind == "stall":
                at += arg
            elif kind == "flood":
                self.stream.flood(arg, at, interruptible=False)
                self.dead = True

    def _count(self, data: bytes) -> None:
        for b in (b"\x04", b">", b"R", b"\x01", b"O"):
            k = data.count(b)
            if k:
                self.nth[b] = self.nth.get(b, 0) + k

    def _trigger(self, trig: tuple, data: bytes) -> int | None:
        """Where in `data` (about to be sent) a fault's trigger falls, if it does."""
        if trig[0] == "at":
            p = trig[1] - self.sent
            return p if 0 <= p < len(data) else None
        _, b, k = trig                          # the k-th (1-based) byte b of the stream
        seen = self.nth.get(b, 0)
        p = -1
        while seen < k:
            p = data.find(b, p + 1)
            if p < 0:
                return None
            seen += 1
        return p if p >= 0 else None

    # --- time ---------------------------------------------------------------------
    def poll(self, until: float) -> None:
        """Let the board run until virtual time `until`."""
        while self.running is not None and self.running[0] <= until:
            t_end, out, err = self.running
            self.running = None
            self.state = "raw"
            self.emit(out + b"\x04" + err + b"\x04>", t_end)
            queued = bytes(self.queue)
            self.queue.clear()
            self._input(queued, t_end)

    def receive(self, data: bytes) -> None:
        now = self.clock.t
        self.poll(now)
        self._input(data, now)

    # --- the REPL -------------------------------------------------------------------
    def _input(self, data: bytes, now: float) -> None:
        for i, b in enumerate(data):
            if self.running is not None:
                if b == 3:                          # Ctrl-C interrupts the program
                    self.running = None
                    self.stream.stop_flood(now)
                    self.state = "raw"
                    self.emit(b"\x04" + KBI + b"\x04>", now)
                else:
                    self.queue.append(b)
                continue
            st = self.state
            if st == "busy":
                if b == 3:
                    self.stream.stop_flood(now)
                    self.state = "friendly"
                    self.emit(KBI + b">>> ", now)
            elif st == "friendly":
                if b == 1:
                    self.state = "raw"
                    self.line.clear()
                    self.emit(b"\r\n" + RAW_BANNER, now)
                elif b in (3, 13):
                    self.emit(b"\r\n>>> ", now)
                elif b == 4:
                    self.emit(b"MPY: soft reboot\r\n" + FRIENDLY_BANNER, now)
                else:
                    self.emit(bytes([b]), now)
            elif st == "raw":
                if b == 1:
                    if bytes(self.line) == b"\x05A":
                        self.line.clear()
                        if self.plan.paste == "ok":
                            self.state = "paste"
                            self.paste_buf.clear()
                            self.paste_used = 0
                            self.emit(b"R\x01" + struct.pack("<H", self.plan.window & 0xFFFF), now)
                            continue
                        if self.plan.paste == "refuse":
                            self.emit(b"R\x00", now)
                            continue
                    self.line.clear()                # (old firmware: a plain raw REPL reset)
                    self.emit(RAW_BANNER, now)
                elif b == 2:
                    self.state = "friendly"
                    self.emit(b"\r\n" + FRIENDLY_BANNER, now)
                elif b == 3:
                    self.line.clear()
                elif b == 4:
                    if not self.line:
                        self.emit(b"OK\r\nMPY: soft reboot\r\n" + RAW_BANNER, now)
                    else:
                        code = bytes(self.line)
                        self.line.clear()
                        self.emit(b"OK", now)
                        self._run(code, now)
                else:
                    self.line.append(b)
            elif st == "paste":
                if b == 4:
                    self.emit(b"\x04", now)
                    self.state = "raw"
                    self._run(bytes(self.paste_buf), now)
                else:
                    self.paste_buf.append(b)
                    self.paste_used += 1
                    w = self.plan.window
                    if w and self.paste_used % w == 0:
                        self.emit(b"\x01", now)

    def _run(self, code: bytes, now: float) -> None:
        k = self.exchanges
        self.exchanges += 1
        out, err = self._exec(code)
        runtime = 0.0
        kind, arg = self.plan.answers.get(k, (None, None))
        if kind == "out":
            out = arg
        elif kind == "out+":
            out = out + arg
        elif kind == "+out":
            out = arg + out
        elif kind == "err":
            err = arg
        elif kind == "slow":
            runtime = arg
        elif kind == "hang":
            runtime = math.inf
        elif kind == "huge":
            out = b"x" * arg + out
        elif kind == "chatty":
            self.stream.flood(arg or b"x", now, interruptible=True)
            self.running = (math.inf, b"", b"")
            return
        elif kind == "reset":
            self.state = "friendly"
            self.emit(b"\r\nMPY: soft reboot\r\n" + FRIENDLY_BANNER, now)
            return
        self.running = (now + runtime, out, err)
        self.poll(now)

    def _exec(self, code: bytes) -> tuple[bytes, bytes]:
        """Run a request as the board would: (output, error output)."""
        self._out = io.StringIO()
        err = b""
        try:
            text = code.decode("utf-8")
            exec(compile(text, "<stdin>", "exec"), self.globals)
        except Exception as e:                  # noqa: BLE001 - the board's traceback
            err = (b"Traceback (most recent call last):\r\n  File \"<stdin>\", line 1, in "
                   b"<module>\r\n" + ("%s: %s" % (type(e).__name__, e)).encode(
                       "utf-8", "replace") + b"\r\n")
        return self._out.getvalue().replace("\n", "\r\n").encode("utf-8", "replace"), err


# --- the port ----------------------------------------------------------------------------------

PROBE_TEXTS = {"busy": "[Errno 11] could not exclusively lock port fuzz: [Errno 11] Resource "
                       "temporarily unavailable",
               "missing": "[Errno 2] could not open port fuzz: [Errno 2] No such file or directory",
               "denied": "[Errno 13] could not open port fuzz: [Errno 13] Permission denied",
               "other": "Could not configure port: (5, 'Input/output error')"}


class World:
    """One case's board, port and clock, and what was seen."""

    def __init__(self, plan: Plan):
        self.plan = plan
        self.clock = Clock()
        self.device = Device(plan, self.clock)
        self.counts: dict[str, int] = {}
        self.broken: set[str] = set()
        self.violations: list[str] = []

    def fault(self, op: str) -> None:
        """The port's own failures (Plan.port_faults: (op, k, how, sticky))."""
        n = self.counts[op] = self.counts.get(op, 0) + 1
        if op in self.broken:
            raise self._error(op, "unplugged")
        for fop, k, how, sticky in self.plan.port_faults:
            if fop == op and k == n:
                if sticky:
                    self.broken.add(op)
                raise self._error(op, how)

    @staticmethod
    def _error(op: str, how: str) -> BaseException:
        if op == "probe":
            return serial.SerialException(PROBE_TEXTS.get(how, PROBE_TEXTS["other"]))
        if op == "open":
            return OSError(errno.EBUSY, "Device or resource busy")
        if how == "timeout" and op == "write":
            return serial.SerialTimeoutException("Write timeout")
        if how == "oserror":
            return OSError(errno.EIO, "Input/output error")
        return serial.SerialException("device reports readiness to read but returned no data "
                                      "(device disconnected or multiple access on port?)")

    def serial(self, *args: Any, **kwargs: Any) -> "FakeSerial":
        return FakeSerial(self, *args, **kwargs)

    @contextlib.contextmanager
    def patches(self):
        """The fake port in place of pyserial's, the virtual clock in place of
        `time` in the link's modules and mpremote's, the deadline wrapper
        known to the port, and texel.app never started in real time (a
        thread)."""
        import mpremote.transport_serial as mts
        import texel.app
        import texel.compat
        import texel.wire
        import texelpad.cli.board
        import texelpad.link.board
        import texelpad.link.transport as tr
        world = self

        class Tracked(tr._DeadlineSerial):
            def __init__(self, port):
                super().__init__(port)
                if isinstance(port, FakeSerial):
                    port.wrapper = self
        start = texel.app.start

        def start_stepped(board_name, scene=None, realtime=False, fast=None, **opts):
            return start(board_name, scene, False, fast, **opts)
        t = self.clock.module()
        import gc
        # texel.app collects garbage after every start, stop and push: on a
        # board a few ms, here (a large heap) 13 ms each - most of a case
        quick_gc = types.SimpleNamespace(**{k: getattr(gc, k) for k in dir(gc)
                                            if not k.startswith("_")})
        quick_gc.collect = lambda *a: 0
        with contextlib.ExitStack() as stack:
            for target, name, value in [
                    (serial, "Serial", lambda *a, **k: world.serial(*a, probe=True, **k)),
                    (serial, "serial_for_url", world.serial), (tr, "_DeadlineSerial", Tracked),
                    (tr, "time", t), (mts, "time", t), (texelpad.link.board, "time", t),
                    (texelpad.cli.board, "time", t), (texel.app, "start", start_stepped),
                    (texel.app, "gc", quick_gc), (texel.wire, "gc", quick_gc),
                    (texel.compat, "heap_free", lambda: None)]:     # (status(): a gc too)
                stack.enter_context(mock.patch.object(target, name, value))
            # texel.wire.reply prints its answer with the module's print, not the
            # request's: on this board both go to the device's output (the board's
            # console), or a staged call answered nothing ("unexpected answer ''")
            stack.enter_context(mock.patch.object(
                texel.wire, "print", world.device.globals["__builtins__"]["print"], create=True))
            yield


class FakeSerial:
    """pyserial's Serial as mpremote and the link use it."""

    def __init__(self, world: World, port: str | None = None, *args: Any, probe: bool = False,
                 do_not_open: bool = False, **kwargs: Any):
        self.world = world
        self.port = port
        self.timeout = kwargs.get("timeout")
        self.write_timeout = kwargs.get("write_timeout")
        self.is_open = False
        self.rts = self.dtr = True
        self.wrapper = None
        if probe:
            world.fault("probe")
            self.is_open = True
        elif not do_not_open:
            self.open()

    def isOpen(self) -> bool:
        return self.is_open

    def open(self) -> None:
        self.world.fault("open")
        self.is_open = True

    def close(self) -> None:
        self.is_open = False

    def _check(self) -> None:
        w = self.wrapper
        if w is None or w.deadline is None:
            self.world.violations.append("a read with no deadline running")
            raise NoDeadline("a read from the port with no deadline running")
        if self.world.clock.t > w.deadline + 1e-6:
            self.world.violations.append("a read after the deadline")
            raise NoDeadline("a read from the port %.3f s after its deadline"
                             % (self.world.clock.t - w.deadline))

    def write(self, data: bytes) -> int:
        self.world.clock.tick()
        self.world.clock.mark()
        self.world.fault("write")
        self.world.device.receive(bytes(data))
        return len(data)

    @property
    def in_waiting(self) -> int:
        self._check()
        w, c = self.world, self.world.clock
        c.tick()
        w.fault("read")
        w.device.poll(c.t)
        return w.device.stream.available(c.t)

    def inWaiting(self) -> int:
        return self.in_waiting

    def read(self, n: int = 1) -> bytes:
        self._check()
        w, c = self.world, self.world.clock
        c.tick()
        w.fault("read")
        dev = w.device
        limit = c.t + (math.inf if self.timeout is None else self.timeout)
        if n <= 0:
            return b""
        dev.poll(min(limit, c.t + 3600))
        t_n = dev.stream.time_of(n)
        if t_n <= limit:
            c.t = max(c.t, t_n)
            dev.poll(c.t)
            return dev.stream.take(n)
        if limit == math.inf:
            raise fuzzlib.Hang("a read without a timeout on a port that never sends: it blocks forever")
        c.t = limit
        dev.poll(c.t)
        return dev.stream.take(min(n, dev.stream.available(c.t)))

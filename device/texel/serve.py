# texel.serve -- play and answer the host at once, where no timer interrupt
# plays (CircuitPython): texel.app.serve() runs this loop.
#
# Why: CircuitPython restarts its VM when a link leaves the raw REPL (Ctrl-B,
# which mpremote and texelpad's link send after each command; its main.c
# run_repl -> cleanup_after_vm), and its display plays only while Python runs
# the refresh (refresh.mode "loop"). So texelpad's link never leaves the raw
# REPL on CircuitPython while something plays: its last command is
# texel.app.serve(), which keeps the refresh paced (as app.run_loop does) and,
# between refreshes, reads the console and answers as the raw REPL does
# (standard mode), so the next `texelpad status` / `push` / `monitor` talks to
# it as to a board's raw REPL (docs/runtime.md, "CircuitPython: serve"):
#   Ctrl-A          -> MARK + the raw REPL's banner + ">"; the link knows it by
#                      MARK (host/texelpad/link/transport.py) and sends no Ctrl-C
#   code + Ctrl-D   -> "OK", what the code prints, "\x04", its traceback (if it
#                      raised), "\x04", ">" - the raw REPL's own answer; the code
#                      runs in one namespace kept between requests
#   Ctrl-E A Ctrl-A -> "R\x00": raw-paste is understood but not offered (mpremote
#                      then sends in the standard mode)
#   Ctrl-D alone    -> a soft reset, as the raw REPL does one (SystemExit: the
#                      port restarts its VM and prints "soft reboot")
#   Ctrl-B          -> the display stops, serve() returns: the raw REPL itself again
#   Ctrl-C          -> the port's own KeyboardInterrupt: the display stops
#                      (app.stop: carrier off, pins driven low) and, in the
#                      link's hand-over (repl=True), serve goes on answering as
#                      the raw REPL would; under code.py (repl=False) the
#                      interrupt ends it, as CircuitPython's programs end. CircuitPython throws
#                      away its console input at a Ctrl-C (supervisor's
#                      tud_cdc_rx_wanted_cb flushes the FIFO), so a tool's Ctrl-A
#                      sent right behind it (mpremote, texelpad's resync) may be
#                      gone: when none comes within GRACE_MS, serve answers the
#                      banner as if it had.
# The refresh pauses while a request runs (one thread); afterwards the pacing
# starts afresh, with no burst of late refreshes.
import gc
import sys
from . import compat
from .runtime.pace import Pacer, clock_of

MARK = "\x1etexel-serve\r\n"        # never in host code: its text is ASCII repr() literals
BANNER = "raw REPL; CTRL-B to exit\r\n>"
POLL_EVERY = 16                     # refreshes between console reads when the loop has no slack
GRACE_MS = 30                       # after a Ctrl-C: the wait for a tool's Ctrl-A


def _out(text):
    sys.stdout.write(text)
    f = getattr(sys.stdout, "flush", None)
    if f is not None:
        f()


def _take(buf, data):
    """Take `data` (bytes the console received) into the request's parts (a
    list: CircuitPython's bytearray cannot delete a slice), answering Ctrl-A
    and raw-paste as the raw REPL does, up to the first request or Ctrl-B:
    (RAN, its code, the bytes after it), (LEAVE, None, the rest) or (None,
    None, b""). The request runs in _loop itself: CircuitPython's Python stack
    (pystack) is small, and a start() inside a request is deep."""
    while data:
        i = len(data)                       # the text of a request runs to the first
        for ch in (b"\x01", b"\x02", b"\x04"):  # control byte serve answers (C finds)
            j = data.find(ch, 0, i)
            if j >= 0:
                i = j
        if i:
            buf.append(data[:i])
            data = data[i:]
            continue
        c = data[0]
        data = data[1:]
        if c == 1:                          # Ctrl-A
            if buf and buf[0] is not _CUT and b"".join(buf) == b"\x05A":  # raw-paste: no
                _out("R\x00")
            else:
                _out(MARK + BANNER)
            buf.clear()
        elif c == 4:                        # Ctrl-D
            if not buf:
                _out("OK\r\n")
                raise SystemExit            # the raw REPL's soft reset
            try:
                code = None if buf[0] is _CUT else b"".join(buf).decode()
            except MemoryError:     # no block for the request's text: a heap with a scene
                code = None
            buf.clear()
            if code is None:
                _out("OK\x04MemoryError: no room for the request's text (%s bytes free)\r\n"
                     "\x04>" % compat.heap_free())
                continue
            return RAN, code, data
        else:                               # Ctrl-B
            return LEAVE, None, data
    return None, None, b""


RAN = 1
LEAVE = 2
_CUT = b"\x00cut"                  # buf's first piece after a MemoryError lost some of it


def serve(current, stop, read=None, repl=True):
    """Refresh what current() (app's runtime, or None) plays when it is a
    paced loop, and answer the host, until a Ctrl-B (returns) or an empty
    Ctrl-D (SystemExit: a soft reset). stop(): app.stop, at a Ctrl-C, which
    then ends serve (KeyboardInterrupt) unless repl: serve runs in the raw
    REPL (the link's hand-over) and answers as that raw REPL would."""
    global _active
    _out(MARK)                      # the hand-over's sign (transport.Link.close)
    if _active:                     # a request to this very loop: it serves on after it
        return
    if read is None:
        read = compat.console_reader()
    ns = {"__name__": "__main__"}
    buf = []                        # the request's text so far, in pieces
    pending = None                  # bytes read but not yet answered (after a Ctrl-C)
    _active = True
    try:
        while True:
            try:
                if _loop(current, read, buf, ns, pending) == LEAVE:
                    stop()          # nothing would refresh it any more: carrier off
                    return
            except KeyboardInterrupt:
                stop()
                if not repl:
                    raise
                buf.clear()
                pending = _grace(read)
            except MemoryError:     # outside a request (reading the console): serve on;
                buf.clear()         # the cut request's end must not run as a request
                buf.append(_CUT)
                pending = None
                gc.collect()
            except BaseException:   # SystemExit (a soft reset), or a fault: carrier off
                stop()
                raise
    finally:
        _active = False


_active = False                     # a serve() loop runs (requests run inside it)


def _grace(read):
    """After a Ctrl-C: what arrives within GRACE_MS, for the loop to answer
    (a tool's Ctrl-A among it gets the banner there); without a Ctrl-A
    (CircuitPython threw it away with its input) the banner first, once."""
    t0 = compat.ticks_us()
    got = b""
    while compat.ticks_diff(compat.ticks_us(), t0) < GRACE_MS * 1000:
        data = read()
        if data:
            got += data
    if b"\x01" not in got:
        _out(MARK + BANNER)
    return got or None


def _loop(current, read, buf, ns, data):
    cur = step = pacer = None
    since = 0
    while True:
        rt = current()
        if rt is not cur:           # a request started or stopped the display
            cur = rt
            step = rt.refresh.step if rt is not None and rt.loop_mode else None
            if step is not None:
                pacer = Pacer(rt.hz, clock_of(rt))
                rt.pacer = pacer    # its late count: status()["late"]
        if step is not None and data is None:
            if pacer.due():
                step()
                since += 1
                if since < POLL_EVERY:
                    continue
        since = 0
        if data is None:
            data = read()
        ran = False
        while data:
            what, code, data = _take(buf, data)
            if what == LEAVE:
                return LEAVE
            if what == RAN:         # one request, answered as the raw REPL answers it
                ran = True
                _out("OK")
                try:
                    exec(code, ns)
                except BaseException as e:      # SystemExit too: the raw REPL reports it
                    _out("\x04")
                    compat.print_exception(e)
                    _out("\x04>")
                    if isinstance(e, KeyboardInterrupt):
                        raise                   # framed, then the display stops (serve)
                else:
                    _out("\x04\x04>")
                code = None
        data = None
        if ran and step is not None and current() is cur:
            pacer.restart()         # the request took the time: no catching up

"""A board slow to answer the raw REPL's Ctrl-A gets a second Ctrl-A
(transport.RETRY_CTRL_A_S) and then answers both, the second banner after
the link has read the first: those owed banners are read past, never taken
for the answer to the next command. Found in CI (stop 49): the emulated F405,
under load, answered a connect's raw-paste request with b"R\\x01" after a
late banner, and the link, having taken the banner's "ra" for the answer,
had fallen back to the standard raw REPL ("could not exec command").

The board is the real virtual board (MicroPython's unix port on a pty); in
front of it a pty relay holds the board's answers for a while after the
first Ctrl-A, as a loaded emulator does. Nothing asserts a timing."""
import os
import pty
import select
import threading
import time
import tty

import pytest

from support.vboard import virtual_board
from texelpad.link.board import connect
from texelpad.link.transport import RETRY_CTRL_A_S

pytestmark = [pytest.mark.vboard]

HOLD_S = RETRY_CTRL_A_S + 1.0        # past the retry: the link sends Ctrl-A again
SPLIT_S = 0.3                        # then the first banner, and the second this much later
BANNER_END = b"CTRL-B to exit\r\n>"


class SlowRelay:
    """A pty whose other end relays to `port`, holding the board's bytes
    for HOLD_S after the first Ctrl-A the host sends, then passing its first
    banner and, SPLIT_S later, the rest (the banner of the second Ctrl-A)."""

    def __init__(self, port: str):
        self.board = os.open(port, os.O_RDWR | os.O_NOCTTY)
        tty.setraw(self.board)
        self.master, self.slave = pty.openpty()
        tty.setraw(self.slave)
        self.port = os.ttyname(self.slave)
        self.hold_until = None
        self.split_until = 0.0
        self.held = 0                   # bytes held back (the test's proof the hold happened)
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        pending = b""
        while not self.stop.is_set():
            r, _, _ = select.select([self.master, self.board], [], [], 0.02)
            try:
                if self.master in r:
                    got = os.read(self.master, 4096)
                    if b"\x01" in got and self.hold_until is None:
                        self.hold_until = time.monotonic() + HOLD_S
                    os.write(self.board, got)
                if self.board in r:
                    pending += os.read(self.board, 4096)
                now = time.monotonic()
                if self.hold_until is not None and now < self.hold_until:
                    self.held = max(self.held, len(pending))
                elif pending and self.hold_until is not None:
                    cut = pending.find(BANNER_END) + len(BANNER_END)
                    os.write(self.master, pending[:cut])
                    pending = pending[cut:]
                    self.hold_until = None
                    self.split_until = now + SPLIT_S
                elif pending and now >= self.split_until:
                    os.write(self.master, pending)
                    pending = b""
            except OSError:
                return

    def close(self) -> None:
        self.stop.set()
        self.thread.join(timeout=5)
        for fd in (self.board, self.master, self.slave):
            try:
                os.close(fd)
            except OSError:
                pass


def test_a_banner_answered_late_is_not_taken_for_the_next_answer():
    with virtual_board() as port:
        relay = SlowRelay(port)
        try:
            with connect(relay.port, timeout=30) as b:
                st = b.status()
                assert b.link.eval("print(6 * 7)") == 42       # the link stays in step
            assert relay.held > 0                          # the board's answer was held
            assert "running" in st
        finally:
            relay.close()

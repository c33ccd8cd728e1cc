"""Every read of the link has a deadline: a port that never stops talking, or
one that is silent, ends in a clear LinkError within the timeout - at the
raw-REPL entry, at the handshake, in a request - and the command line says
so in one line and exits 1. mpremote's read_until checks its timeouts only
while no byte arrives; texelpad.link.transport puts the deadline under it.

The fake ports are ptys whose other end a thread drives: "chatty" writes
text forever (and reads what the host sends, as a device would). Bounds are
generous (a 1-2 s timeout must end within 15 s); nothing asserts timing."""
import os
import pty
import subprocess
import sys
import threading
import time
import tty

import pytest

import texelpad
from texelpad.link import LinkError, LinkTimeout, NotTexelpad
from texelpad.link.transport import Link

BOUND_S = 15.0          # a 1-2 s timeout returns well within this
TEXT = b"temperature 21.5 C, humidity 40 %, all good\r\n"
RAW_BANNER = b"raw REPL; CTRL-B to exit\r\n>"


class FakePort:
    """A pty: the slave is the serial port; a thread on the master plays the
    device. mode: "chatty" (text forever), "silent" (reads, never answers),
    "raw-then-chatty" (answers Ctrl-A with the raw REPL banner, then text
    forever)."""

    def __init__(self, mode: str):
        self.mode = mode
        self.master, self.slave = pty.openpty()
        tty.setraw(self.slave)
        self.port = os.ttyname(self.slave)
        os.set_blocking(self.master, False)
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        import select
        talking = self.mode == "chatty"
        while not self.stop.is_set():
            r, w, _ = select.select([self.master], [self.master] if talking else [], [], 0.05)
            try:
                if r:
                    got = os.read(self.master, 4096)
                    if self.mode == "raw-then-chatty" and b"\x01" in got and not talking:
                        os.write(self.master, RAW_BANNER)
                        talking = True
                if w:
                    os.write(self.master, TEXT)
            except BlockingIOError:
                pass
            except OSError:
                return

    def close(self) -> None:
        self.stop.set()
        self.thread.join(timeout=5)
        for fd in (self.master, self.slave):
            try:
                os.close(fd)
            except OSError:
                pass


@pytest.fixture
def fake():
    ports = []

    def make(mode):
        p = FakePort(mode)
        ports.append(p)
        return p
    yield make
    for p in ports:
        p.close()


def bounded(fn, seconds: float = BOUND_S):
    """fn() in a thread; fail (instead of hanging the suite) if it has not
    returned within `seconds`. Returns (result, exception, elapsed)."""
    out = {}

    def run():
        try:
            out["value"] = fn()
        except BaseException as e:          # noqa: BLE001 - handed to the test
            out["error"] = e
    t0 = time.monotonic()
    t = threading.Thread(target=run, daemon=True)
    t.start()
    t.join(seconds)
    if t.is_alive():
        pytest.fail("still reading after %g s: the read has no deadline" % seconds)
    return out.get("value"), out.get("error"), time.monotonic() - t0


def test_raw_repl_entry_on_a_chatty_port_ends_at_the_deadline(fake):
    port = fake("chatty").port
    _, err, _ = bounded(lambda: Link(port, timeout=1.0))
    assert isinstance(err, NotTexelpad), err
    text = str(err)
    assert "does not answer as a MicroPython board" in text
    assert "no answer within 1 s" in text and "kept sending other text" in text
    assert "\n" not in text


def test_raw_repl_entry_on_a_silent_port_ends_at_the_deadline(fake):
    port = fake("silent").port
    _, err, _ = bounded(lambda: Link(port, timeout=1.0))
    assert isinstance(err, NotTexelpad), err
    assert "kept sending" not in str(err)


def test_handshake_on_a_port_that_enters_the_raw_repl_then_talks_forever(fake):
    port = fake("raw-then-chatty").port
    _, err, _ = bounded(lambda: texelpad.connect(port, timeout=1.0, check=False))
    assert isinstance(err, LinkError), err
    assert "no answer within 1 s" in str(err) and "\n" not in str(err)


def test_cli_status_on_a_chatty_port_fails_in_one_line_exit_1(fake):
    """The reported hang: `texelpad status --port <chatty> --timeout 2`."""
    port = fake("chatty").port
    t0 = time.monotonic()
    r = subprocess.run([sys.executable, "-m", "texelpad.cli", "status", "--port", port,
                        "--timeout", "2"], capture_output=True, text=True, timeout=60)
    assert time.monotonic() - t0 < BOUND_S + 10     # interpreter start-up included
    assert r.returncode == 1, (r.stdout, r.stderr)
    assert r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("texelpad status: error: %s does not answer" % port)
    assert "kept sending other text" in lines[0]


@pytest.mark.slow
@pytest.mark.vboard
def test_a_request_whose_output_never_ends_times_out_and_resync_recovers(tmp_path):
    """A board running a program that keeps printing: the request ends at its
    deadline with LinkTimeout, though bytes never stop arriving; resync()
    (Ctrl-C, raw REPL) then gets the board back. (The unix port takes Ctrl-C
    only at its prompt, so the program here ends by itself after 4 s.)"""
    from texelpad.sim.virtual import VirtualBoard
    with VirtualBoard(tmp_path / "flash", image="source") as vb:
        with texelpad.connect(vb.port, timeout=1.0, check=False) as b:
            _, err, _ = bounded(lambda: b.link.exec(
                "import time\n_t = time.time() + 4\nwhile time.time() < _t:\n print('x' * 60)"))
            assert isinstance(err, LinkTimeout), err
            assert "no answer within 1 s" in str(err) and "kept sending" in str(err)
            _, err, _ = bounded(lambda: b.link.resync(timeout=10))
            assert err is None, err
            assert b.link.eval("print(repr(6 * 7))") == 42

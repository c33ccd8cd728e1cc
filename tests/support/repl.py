"""A board's REPL driven byte by byte through its own serial port, as mpremote and Thonny
drive it: Ctrl-A/B/C/D at the moments a test chooses (tests/firmware/test_soft_reset.py,
tests/fuzz/test_repl_fuzz.py)."""
from __future__ import annotations

import time


class Raw:
    """The board's REPL through its own port, byte by byte, as mpremote and Thonny drive it."""

    def __init__(self, port: str, emu) -> None:
        import serial
        self.s = serial.Serial(port, 115200, timeout=0.05)
        self.emu = emu
        self.buf = b""              # read past the last token: the next read_until's start

    def close(self) -> None:
        self.s.close()

    def read_until(self, token: bytes, seconds: float) -> bytes:
        buf, self.buf = self.buf, b""
        end = time.monotonic() + seconds
        while token not in buf:
            if time.monotonic() > end:
                raise AssertionError("no %r within %.0f s; got %r; emulator: %s"
                                     % (token, seconds, buf[-300:], self.emu.stderr()[-300:]))
            buf += self.s.read(4096)
        cut = buf.index(token) + len(token)
        self.buf = buf[cut:]
        return buf[:cut]

    def drain(self) -> bytes:
        time.sleep(0.2)
        out, self.buf = self.buf + self.s.read(65536), b""
        return out

    def raw(self) -> None:
        """Interrupt whatever runs and enter the raw REPL (mpremote's enter_raw_repl)."""
        self.s.write(b"\r\x03\x03")
        self.drain()
        self.s.write(b"\r\x01")
        self.read_until(b"raw REPL; CTRL-B to exit\r\n>", 60)

    def start(self, code: str) -> None:
        self.s.write(code.encode() + b"\x04")
        self.read_until(b"OK", 60)

    def result(self, seconds: float = 300) -> tuple[str, str]:
        buf = self.read_until(b"\x04>", seconds)
        out, err = buf[:-2].split(b"\x04", 1)
        return out.decode(errors="replace").strip(), err.decode(errors="replace").strip()

    def exec(self, code: str, seconds: float = 300) -> str:
        self.start(code)
        out, err = self.result(seconds)
        assert not err, (code[:80], err)
        return out

    def soft_reset_raw(self) -> None:
        """Ctrl-D at the raw REPL prompt: mpremote's default before/after exec, Thonny's Stop."""
        self.s.write(b"\x04")
        self.read_until(b"soft reboot", 30)
        self.read_until(b"raw REPL; CTRL-B to exit\r\n>", 30)

    def soft_reset_friendly(self) -> None:
        """Ctrl-D at the friendly prompt: the REPL user's soft reset (main.py runs)."""
        self.s.write(b"\x02")
        self.read_until(b">>> ", 30)
        self.s.write(b"\x04")
        self.read_until(b"soft reboot", 30)
        self.read_until(b">>> ", 300)             # main.py's power-up scene first


def status(r: Raw) -> dict:
    out = r.exec("import texel.app as app; print(repr(app.status()))")
    return eval(out.splitlines()[-1])           # the board's repr() literal (a test's own board)

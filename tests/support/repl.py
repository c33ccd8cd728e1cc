"""A board's REPL driven byte by byte through its own serial port, as mpremote and Thonny
drive it: Ctrl-A/B/C/D at the moments a test chooses (tests/firmware/test_soft_reset.py,
tests/fuzz/test_repl_fuzz.py)."""
from __future__ import annotations

import time


class Raw:
    """The board's REPL through its own port, byte by byte, as mpremote and Thonny drive it."""

    def __init__(self, port: str, emu, paste: bool = False) -> None:
        """paste: send code in raw-paste mode (mpremote's way: the board grants a window of
        bytes at a time), else all at once in the plain raw REPL (pyboard.py's older way)."""
        import serial
        self.s = serial.Serial(port, 115200, timeout=0.05)
        self.emu = emu
        self.paste = paste
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
        if self.paste:
            self._paste(code.encode())
            return
        self.s.write(code.encode() + b"\x04")
        self.read_until(b"OK", 60)

    def _paste(self, data: bytes) -> None:
        """Raw-paste mode as mpremote sends it (its pyboard.py raw_paste_write): Ctrl-E A Ctrl-A,
        the board's "R\\x01" and window size, then no more bytes than it has granted (each
        Ctrl-A it sends grants another window), Ctrl-D, and its Ctrl-D back."""
        import struct
        self.s.write(b"\x05A\x01")
        self.read_until(b"R\x01", 60)
        end = time.monotonic() + 60
        while len(self.buf) < 2:
            if time.monotonic() > end:
                raise AssertionError("no raw-paste window size within 60 s")
            self.buf += self.s.read(2 - len(self.buf))
        window = remain = struct.unpack("<H", self.buf[:2])[0]
        self.buf = self.buf[2:]
        i = 0
        while i < len(data):
            while remain == 0 or self.s.in_waiting:
                if time.monotonic() > end:
                    raise AssertionError("raw paste: no window granted within 60 s (%d of %d "
                                         "bytes sent)" % (i, len(data)))
                c = self.s.read(1)
                if c == b"\x01":
                    remain += window
                    end = time.monotonic() + 60
                elif c == b"\x04":
                    raise AssertionError("raw paste: the board ended it at byte %d" % i)
                elif c:
                    raise AssertionError("raw paste: unexpected %r from the board" % c)
            piece = data[i:i + remain]
            self.s.write(piece)
            remain -= len(piece)
            i += len(piece)
        self.s.write(b"\x04")
        self.read_until(b"\x04", 60)

    def result(self, seconds: float = 300) -> tuple[str, str]:
        buf = self.read_until(b"\x04>", seconds)
        out, err = buf[:-2].split(b"\x04", 1)
        return out.decode(errors="replace").strip(), err.decode(errors="replace").strip()

    def exec(self, code: str, seconds: float = 300) -> str:
        self.start(code)
        out, err = self.result(seconds)
        assert not err, (code[:80], err)
        return out

    def ctrl_c(self) -> None:
        """Ctrl-C wherever the board is (a KeyboardInterrupt), then back at the raw REPL."""
        self.s.write(b"\x03")
        self.drain()
        self.raw()

    def ticks_ms(self) -> int:
        """The board's own clock (time.ticks_ms: wraps at 2^30)."""
        return int(self.exec("import time; print(time.ticks_ms())"))

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


# The soft-reset soaks' work (tests/firmware/test_soft_reset.py, tests/host/test_emulated_stm32.py):
# cheap scenes - a constant (nothing to render), a texel half (a render the Ctrl-C can land in) -
# and an upload the Ctrl-C can land in, its values then pushed in place of the region's as
# texelpad.link's push does (a 2,400-value literal takes minutes through the STM32's UART)
SOAK_CONST = {"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": {"kind": "constant",
                                                                         "level": 0.3}}]}
SOAK_TEXEL = {"regions": [{"start_mm": 0, "end_mm": 50.88, "texture": {
    "kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7, "v": 2}},
    {"start_mm": 50.88, "end_mm": 101.76, "texture": {"kind": "constant", "level": 0.6}}]}
SOAK_WORK = ("push", "upload", "telemetry", "idle")


def soak_code(what: str) -> str:
    """The board code of one soak round's work (SOAK_WORK), texel.app imported as app."""
    return "import texel.app as app, texel.wire as wire\n" + {
        "push": "app.push(%r)" % (SOAK_TEXEL,),
        "upload": "import binascii\nwire.upload_begin([2400])\n"
                  "for i in range(0, 2400, 200): wire.upload_write(0, i, "
                  "binascii.b2a_base64(bytes(400)).decode().strip())\n"
                  "app.push({'regions': [{'start_mm': 0, 'end_mm': 101.76, 'texture': "
                  "{'kind': 'samples', 'fit': 'tile', 'u16': wire.take_upload(0)}}]})",
        "telemetry": "import time\napp.stream(125)\n"
                     "for _ in range(40): app.telemetry(); time.sleep_ms(20)",
        "idle": "import time; time.sleep_ms(3000)"}[what]


def status(r: Raw) -> dict:
    out = r.exec("import texel.app as app; print(repr(app.status()))")
    return eval(out.splitlines()[-1])           # the board's repr() literal (a test's own board)

"""The emulated Raspberry Pi Pico as a board: `texelpad virtual --chip rp2040`.

../shared/instruments/rp2emu (an instrument, found by texelpad.toolchain,
never copied into the project) runs the real MicroPython v1.28 firmware for
RPI_PICO on rp2040js, with time from cycle counts. In its serial mode it is
a pty that the host opens as it opens a Pico on USB, so everything texelpad
does to a Pico - deploy (armv6m .mpy into its flash), push, status, monitor,
demo - runs here unchanged, on the chip's own code and timing (about 3x
slower than a real chip in wall time on this machine; its status figures
are in emulated time, which is the chip's).

The emulator runs in a process group of its own (run.sh -> pty_host.py ->
node) with a flash file (a temporary one unless given); stop() ends the whole
group (SIGTERM, which lets the emulator save its flash, then SIGKILL for what
is left) and removes the temporary folder. While it runs it is announced in
the same registry as the unix-port virtual board, so `texelpad ports` and
the commands without --port find it.
"""
from __future__ import annotations

import os
import shutil
import signal
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any, Callable

from .. import toolchain

# rp2emu's flash file: the 2 MB flash from FS_OFFSET (the stock Pico's littlefs)
# to its end (rp2emu/README.md, --flash); firmware must end below FS_OFFSET.
FS_OFFSET = 0xA0000
FS_BYTES = 0x200000 - FS_OFFSET
BOOT_TIMEOUT = 120.0        # s: the first use may install rp2040js (npm ci); ~1.5 s after
STOP_GRACE = 30.0           # s: pty_host.py gives the emulator 20 s after the signal
CHIPS = ("rp2040",)


def rp2emu_dir() -> Path | None:
    d = toolchain.instruments_dir()
    return d / "rp2emu" if d else None


def why_not() -> str | None:
    """None when the emulated Pico can run on this machine, else why not."""
    d = rp2emu_dir()
    if d is None:
        return ("the instruments are not found (../shared/instruments beside the checkout, "
                "$TEXELPAD_INSTRUMENTS or $TEXELPAD_SHARED): no emulated Pico")
    if not (d / "run.sh").is_file():
        return "no emulated Pico in %s (rp2emu/run.sh missing)" % d.parent
    if not shutil.which(os.environ.get("RP2EMU_NODE", "node")):
        return "node (>= 18) is not installed: the emulated Pico (rp2emu) needs it"
    if not shutil.which("python3"):
        return "python3 is not on PATH: the emulated Pico's pty relay needs it"
    if not (d / "node_modules" / "rp2040js" / "package.json").is_file() \
            and not shutil.which("npm"):
        return "rp2040js is not installed in %s/node_modules and npm is missing" % d
    return None


def group_members(pgid: int) -> list[tuple[int, str, str]]:
    """(pid, state, command line) of every process in process group pgid
    (zombies too: state 'Z'), read from /proc ([] where there is no /proc)."""
    out: list[tuple[int, str, str]] = []
    try:
        entries = os.listdir("/proc")
    except OSError:
        return out
    for entry in entries:
        if not entry.isdigit():
            continue
        try:
            with open("/proc/%s/stat" % entry, "rb") as f:
                stat = f.read().decode("ascii", "replace")
            # pid (comm) state ppid pgrp ...: comm may hold spaces and parentheses
            fields = stat[stat.rindex(")") + 2:].split()
            state, pgrp = fields[0], int(fields[2])
            if pgrp != pgid:
                continue
            with open("/proc/%s/cmdline" % entry, "rb") as f:
                cmd = f.read().replace(b"\0", b" ").decode("utf-8", "replace").strip()
        except (OSError, ValueError, IndexError):
            continue                    # gone meanwhile
        out.append((int(entry), state, cmd))
    return out


class EmulatedPico:
    """A running emulated Pico: .port (its /dev/pts path once started),
    .flash (the flash file), .pgid (its process group), .dir (its temporary
    folder, None with a flash file of the caller's)."""

    chip = "rp2040"

    def __init__(self, flash: str | os.PathLike | None = None, instant_flash: bool = True,
                 extra_args: tuple[str, ...] = (),
                 firmware: str | os.PathLike | None = None) -> None:
        why = why_not()
        emu = rp2emu_dir()
        if why or emu is None:
            raise RuntimeError(why or "no rp2emu (../shared/instruments/rp2emu)")
        self.dir = Path(tempfile.mkdtemp(prefix="texelpad-pico-"))
        self.temporary = flash is None
        self.flash = self.dir / "flash.img" if flash is None else Path(flash).resolve()
        self.firmware = Path(firmware).resolve() if firmware else None
        if self.firmware is not None:
            extra_args = ("--firmware", str(self._flash_uf2(self.firmware))) + tuple(extra_args)
        self.port: str | None = None
        self.failure: str | None = None
        self._out_path = self.dir / "stdout"
        self._err_path = self.dir / "stderr"
        self._out = open(self._out_path, "wb")
        self._err = open(self._err_path, "wb")
        args = [str(emu / "run.sh"), "--pty", "--flash", str(self.flash)]
        if instant_flash:
            args.append("--instant-flash")  # flash writes take no emulated time
        self.proc = subprocess.Popen(args + list(extra_args), stdin=subprocess.DEVNULL,
                                     stdout=self._out, stderr=self._err,
                                     start_new_session=True)   # a group, stopped as one
        self.pgid = self.proc.pid
        self._registry: Path | None = None
        self._stopped = False

    def _flash_uf2(self, uf2: Path) -> Path:
        """A .uf2 as if dragged onto the Pico: rp2emu loads firmware blocks
        below its filesystem area (FS_OFFSET) from --firmware and keeps the
        area itself in the flash file; so blocks at or above it (the texelpad
        firmware's ROMFS partition) go into the flash file (a new one, erased
        elsewhere: 0xFF) and the rest into a firmware-only .uf2."""
        from ..firmware import romfs
        try:
            blocks = romfs.read_uf2(uf2.read_bytes())
        except (OSError, ValueError) as e:
            raise RuntimeError("%s: %s" % (uf2, e)) from None
        low = [b for b in blocks if b[0] - romfs.XIP_BASE < FS_OFFSET]
        high = [b for b in blocks if b[0] - romfs.XIP_BASE >= FS_OFFSET]
        if high:
            if self.flash.exists():
                raise RuntimeError("%s already holds a filesystem: flashing a .uf2 with a ROMFS "
                                   "partition takes a new flash file" % self.flash)
            area = bytearray(b"\xff" * FS_BYTES)
            for addr, payload, _ in high:
                off = addr - romfs.XIP_BASE - FS_OFFSET
                if off + len(payload) > FS_BYTES:
                    raise RuntimeError("%s: a block at 0x%08x is past the 2 MB flash" % (uf2, addr))
                area[off:off + len(payload)] = payload
            self.flash.write_bytes(bytes(area))
        out = self.dir / "firmware.uf2"
        out.write_bytes(romfs.write_uf2(low))
        return out

    def __enter__(self) -> "EmulatedPico":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.stop()

    def _text(self, path: Path) -> str:
        try:
            return path.read_text(errors="replace")
        except OSError:
            return ""

    def stderr(self) -> str:
        return self._text(self._err_path)

    def stdout(self) -> str:
        return self._text(self._out_path)

    def start(self, timeout: float = BOOT_TIMEOUT) -> str:
        """Wait for the pty path (the first line of the emulator's stdout,
        printed once the board's USB is up at its prompt); returns it."""
        t_end = time.monotonic() + timeout
        while time.monotonic() < t_end:
            first, nl, _ = self.stdout().partition("\n")
            if nl and first.startswith("/dev/") and os.path.exists(first):
                self.port = first
                return first
            if self.proc.poll() is not None:
                raise RuntimeError("the emulated Pico exited (status %s) before it gave its "
                                   "port: %s" % (self.proc.returncode, _tail(self.stderr())))
            time.sleep(0.1)
        raise RuntimeError("the emulated Pico gave no port within %.0f s: %s"
                           % (timeout, _tail(self.stderr())))

    wait_port = start

    def alive(self) -> bool:
        alive = self.proc.poll() is None
        if not alive and self.failure is None:
            self.failure = "the emulator exited (status %s): %s" % (
                self.proc.returncode, _tail(self.stderr()) or "no message")
        return alive

    def stop(self) -> str:
        """Stop the whole process group (SIGTERM, then SIGKILL after
        STOP_GRACE) and remove the temporary folder (the flash with it, if it
        was temporary); returns the emulator's summary line(s). Safe to call
        twice. Raises RuntimeError if a process of the group is left."""
        if self._stopped:
            return ""
        self._stopped = True
        self.unannounce()
        try:
            if self.proc.poll() is None:
                try:
                    os.killpg(self.pgid, signal.SIGTERM)
                except ProcessLookupError:
                    pass
                try:
                    self.proc.wait(STOP_GRACE)
                except subprocess.TimeoutExpired:
                    pass
            # the relay has exited (or is stuck): what is left of the group goes now
            t_end = time.monotonic() + 10
            while True:
                live = [m for m in group_members(self.pgid) if m[1] != "Z"]
                if not live:
                    break
                if time.monotonic() > t_end:
                    raise RuntimeError("emulated Pico: processes left in group %d: %r"
                                       % (self.pgid, live))
                try:
                    os.killpg(self.pgid, signal.SIGKILL)
                except ProcessLookupError:
                    break
                time.sleep(0.1)
            if self.proc.poll() is None:
                self.proc.kill()
                self.proc.wait(10)
            return self.stdout().partition("\n")[2]
        finally:
            for f in (self._out, self._err):
                f.close()
            shutil.rmtree(self.dir, ignore_errors=True)

    # the registry of running boards (shared with the unix-port virtual board)
    def announce(self) -> Path:
        from .virtual import announce
        self._registry = announce(self.port or "", str(self.flash), self.temporary, self.chip)
        return self._registry

    def unannounce(self) -> None:
        if self._registry is not None:
            try:
                self._registry.unlink()
            except OSError:
                pass
            self._registry = None


# The finger on the emulated Pico's softpot (GPIO26 = ADC channel 0), as rp2emu's
# --adc-js function of emulated time: 12-bit counts. Board file 'pico' reads
# raw_at_start 2,000 .. raw_at_end 63,000 (16-bit read_u16 units, /16 here)
# and lift_below 1,000: 0 is a lifted finger.
FINGERS = {
    "lifted": "(ch, t) => 0",
    "rest": "(ch, t) => ch === 0 ? 2031 : 0",               # mid-strip, still
    # a swipe from end to end and back every 2 s (~100 mm/s on the board file 'pico': 103-115
    # between two telemetry samples, bench/brush_chase.py; it said 50.9), as the study's
    # participants explored the plate
    "sweep": "(ch, t) => ch === 0 ? Math.round(125 + 3812 * (1 - Math.abs((t % 2) - 1))) : 0",
}


def finger_js(finger: str) -> str:
    """A FINGERS name, or a JavaScript (ch, t) => 0..4095 function as is."""
    return FINGERS.get(finger, finger)


def _tail(text: str, n: int = 600) -> str:
    return " ".join(text.split())[-n:]


def open_emulated(flash: str | None = None, start: bool = True,
                  progress: Callable[[str], None] | None = None,
                  finger: str = "lifted", firmware: str | os.PathLike | None = None,
                  ) -> EmulatedPico:
    """A started emulated Pico with texelpad's image deployed into its flash
    (only what changed, when the flash file already holds an image) and,
    unless start=False, the board file 'pico' playing the default scene;
    finger: a FINGERS name or an --adc-js function. firmware: a .uf2 to boot
    instead of the instrument's stock MicroPython; when it is the texelpad
    firmware (deploy's romfs_install.firmware_info) nothing is deployed and its
    power-up scene plays as it booted (a stock .uf2 gets the image deployed)."""
    from ..link.board import connect
    from ..deploy.install import deploy
    from ..deploy.romfs_install import firmware_info
    say = progress or (lambda m: None)
    emu = EmulatedPico(flash, extra_args=("--adc-js", finger_js(finger)), firmware=firmware)
    try:
        say("booting the emulated RP2040 (rp2040js, %s)"
            % ("firmware %s" % Path(firmware).name if firmware else "MicroPython firmware"))
        emu.start()
        with connect(emu.port, check=False, import_image=False, timeout=60) as b:
            # deploy's own test for the texelpad firmware; a partition that does not read
            # (no image digest) is deployed, which repairs it
            info = firmware_info(b) if firmware is not None else None
            frozen = info is not None and info.get("image_sha256") is not None
            if frozen:
                say("the firmware carries texelpad: nothing to deploy")
            else:
                deploy(b, progress=(lambda m: say("deploy: " + m)))
        if start:
            with connect(emu.port, timeout=60) as b:
                if not b.status().get("running"):
                    say("starting board file 'pico' (building the default scene takes a few "
                        "emulated seconds)")
                    b.start("pico")
    except BaseException:
        emu.stop()
        raise
    return emu

"""`texelpad virtual`: a virtual board on a pty until Ctrl-C (or SIGTERM, SIGHUP):
the device image under the MicroPython unix port, or with --chip rp2040 the
emulated Raspberry Pi Pico (sim/emulated.py: the real firmware on rp2040js)."""
from __future__ import annotations

import argparse
import os
import time
from pathlib import Path
from typing import Any

from ..link.transport import LinkError
from ..sim.virtual import open_virtual, stop_on_signals
from .connection import link_failure
from .errors import EXIT_FAIL, EXIT_OK, CliError, to_stderr
from .parsing import positive_float


def add_virtual(p: argparse.ArgumentParser) -> None:
    p.description = ("Start the device image under the MicroPython unix port on a "
                    "pseudo-terminal, playing in real time what a board plays at power-up (the "
                    "power-up scene of its flash, set by texelpad scene boot, else the study's "
                    "split screen), and print "
                    "its serial port as the first line, so texelpad --port, mpremote connect "
                    "PORT resume ..., or any serial tool can talk to it; texelpad ports lists "
                    "it. A soft reset (Ctrl-D, mpremote's default) restarts the interpreter "
                    "on the same port, as on a board. Runs until Ctrl-C, SIGTERM or SIGHUP.")
    p.add_argument("--chip", choices=("rp2040",),
                   help="emulate a chip instead: rp2040 = a Raspberry Pi Pico running the real "
                        "MicroPython firmware (../shared/instruments/rp2emu; needs node), "
                        "texelpad's image deployed into its flash and board file 'pico' "
                        "playing; its figures are the chip's (emulated time)")
    p.add_argument("--finger", default="lifted", metavar="sweep|rest|lifted|JS",
                   help="with --chip: the finger on the softpot (ADC0): sweep (end to end and "
                        "back every 2 s), rest (mid-strip), lifted (default), or a JavaScript "
                        "function (ch, t_seconds) => 0..4095")
    p.add_argument("--firmware", metavar="FILE.uf2",
                   help="with --chip rp2040: boot this .uf2 as if dragged onto the Pico in "
                        "BOOTSEL mode (e.g. texelpad firmware's firmware/texelpad-pico.uf2: it "
                        "plays its power-up scene, nothing deployed; a stock MicroPython .uf2 "
                        "gets texelpad's image deployed). A .uf2 with a ROMFS partition "
                        "takes a new --flash file (or none)")
    p.add_argument("--flash", metavar="DIR|FILE",
                   help="keep the board's filesystem in the folder DIR (with --chip: in the "
                        "flash image FILE) between runs (default: temporary); its power-up "
                        "scene plays at start")
    p.add_argument("--source", action="store_true",
                   help="run the device code from this checkout instead of deploying the "
                        "compiled image into the flash")
    p.add_argument("--no-start", action="store_true",
                   help="do not start texelpad (a bare board: for deploy tests)")
    p.add_argument("--seconds", type=positive_float, metavar="S", help="stop after S seconds")
    p.set_defaults(func=cmd_virtual)


def check_flash(flash: str | None, chip: str | None) -> None:
    """--flash before anything starts: the unix-port board's flash is a
    folder (made when missing), the emulated chip's a flash image file of
    FS_BYTES (or a new one). Not that: one line naming --flash, exit
    2; a place that cannot be made or written: exit 1."""
    if flash is None:
        return
    # the emulated Pico's flash file: its 2 MB flash from the filesystem area on,
    # 1,441,792 bytes (rp2emu refuses a file of another size: its README, --flash)
    from ..sim.emulated import FS_BYTES
    p = Path(flash)
    if not chip:
        if p.exists() and not p.is_dir():
            raise CliError("--flash", "%s is a file, not a folder: the virtual board's flash "
                           "is a folder (a flash image file is for --chip rp2040)" % flash)
        try:
            p.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise CliError("--flash", "cannot make the flash folder %s: %s"
                           % (flash, e.strerror or e), EXIT_FAIL) from None
        if not os.access(p, os.W_OK | os.X_OK):
            raise CliError("--flash", "cannot write in the flash folder %s: permission denied"
                           % flash, EXIT_FAIL)
        return
    if p.is_dir():
        raise CliError("--flash", "%s is a folder: the emulated %s's flash is an image file "
                       "(a new name makes one)" % (flash, chip.upper()))
    if p.exists():
        try:
            size = p.stat().st_size
        except OSError as e:
            raise CliError("--flash", "cannot read %s: %s" % (flash, e.strerror or e),
                           EXIT_FAIL) from None
        if size != FS_BYTES or not p.is_file():
            raise CliError("--flash", "%s is not an emulated %s's flash image (%s bytes; an "
                           "image is %s: what a previous --flash run saved); left untouched"
                           % (flash, chip.upper(), format(size, ","),
                              format(FS_BYTES, ",")))
        if not os.access(p, os.R_OK | os.W_OK):
            raise CliError("--flash", "cannot read and write %s: permission denied" % flash,
                           EXIT_FAIL)
        return
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise CliError("--flash", "cannot make %s: no such folder %s" % (flash, parent),
                       EXIT_FAIL)
    if not os.access(parent, os.W_OK | os.X_OK):
        raise CliError("--flash", "cannot make %s: permission denied" % flash, EXIT_FAIL)


def cmd_virtual(args: argparse.Namespace) -> int:
    progress = lambda m: to_stderr("virtual: " + m)       # noqa: E731
    if args.finger != "lifted" and not args.chip:
        raise CliError("--finger", "the unix-port virtual board's finger is scripted over the "
                       "link (Board.finger); --finger is for --chip rp2040")
    if args.firmware is not None:
        if not args.chip:
            raise CliError("--firmware", "boots a .uf2 on an emulated chip: give --chip rp2040 "
                           "too (the unix-port virtual board runs no firmware image)")
        if not os.path.isfile(args.firmware):
            raise CliError("--firmware", "%s: no such file (texelpad firmware --board pico "
                           "builds firmware/texelpad-pico.uf2)" % args.firmware)
    if args.chip and args.source:
        raise CliError("--source", "the emulated %s runs the compiled image from its flash; "
                       "--source is for the unix-port virtual board" % args.chip)
    check_flash(args.flash, args.chip)
    vb: Any = None                  # a VirtualBoard or an EmulatedPico: the same few calls
    # SIGTERM/SIGHUP end it as Ctrl-C does: the interpreter killed, the
    # temporary flash and the registry entry removed (also while deploying)
    with stop_on_signals():
        try:
            try:
                if args.chip:
                    from ..sim.emulated import open_emulated, why_not
                    why = why_not()
                    if why:
                        raise CliError("--chip", why, EXIT_FAIL)
                    try:
                        vb = open_emulated(args.flash, not args.no_start, progress, args.finger,
                                           firmware=args.firmware)
                    except RuntimeError as e:
                        if args.firmware and str(e).startswith(str(args.firmware)):
                            raise CliError("--firmware", str(e), EXIT_FAIL) from None
                        raise
                else:
                    vb = open_virtual(args.flash, args.source, not args.no_start, progress)
            except LinkError as e:
                raise link_failure(e) from None
            except RuntimeError as e:       # the emulator did not come up
                raise CliError("--chip", str(e), EXIT_FAIL) from None
            vb.announce()
            print(vb.port, flush=True)
            to_stderr("virtual: %s is on %s (flash: %s); Ctrl-C stops it"
                      % ("an emulated %s" % args.chip.upper() if args.chip else "a virtual board",
                         vb.port, vb.flash))
            t_end = None if args.seconds is None else time.monotonic() + args.seconds
            while vb.alive() and (t_end is None or time.monotonic() < t_end):
                time.sleep(0.2)
            if not vb.alive():
                raise CliError("", "the virtual board on %s stopped: %s" % (
                    vb.port, vb.failure or "its supervisor ended"), EXIT_FAIL)
        except KeyboardInterrupt:       # Ctrl-C, SIGTERM, SIGHUP: the normal way to stop it
            pass
        finally:
            if vb is not None:
                vb.stop()
    return EXIT_OK

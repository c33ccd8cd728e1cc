"""`texelpad firmware`: build the texelpad firmware (.uf2) for a board folder (texelpad.firmware)."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .errors import EXIT_FAIL, EXIT_OK, CliError


def add_firmware(p: argparse.ArgumentParser) -> None:
    p.description = (
        "Build DIR/texelpad-NAME.uf2: MicroPython 1.28 + ulab with texelpad's code frozen in "
        "and its data (reference maps, tables, board files) in a ROMFS partition "
        "(docs/firmware.md). Drag it onto a Pico in BOOTSEL mode and it boots playing its "
        "power-up scene. texelpad has no release yet, so this is how a maker gets the .uf2 "
        "today (tools/release_firmware.sh builds every board as a release would). A board "
        "folder is checked first, as `texelpad board check --firmware texelpad` does. "
        "Building needs Debian's gcc-arm-none-eabi libnewlib-arm-none-eabi cmake and a "
        "MicroPython v1.28.0 source tree (the offline kit in ../shared/instruments/mpfirmware, "
        "or --micropython DIR).")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--board", default=None, metavar="NAME",
                   help="a board folder shipped in boards/ (pico, pico_bridge, pyboard; "
                        "default pico)")
    g.add_argument("--circuitpython", action="store_true",
                   help="instead: DIR/texelpad-circuitpython.zip, what a CircuitPython board's "
                        "CIRCUITPY drive needs (lib/texel as sources, code.py starting the "
                        "power-up scene, README.txt); unzip it onto the drive "
                        "(docs/firmware.md, \"CircuitPython\")")
    g.add_argument("--board-dir", default=None, metavar="DIR",
                   help="a board folder of your own (mpconfigboard.h, mpconfigboard.cmake, "
                        "pins.csv, manifest.py, board.json: copy boards/pico; an STM32 board: "
                        "copy boards/pyboard)")
    p.add_argument("--out", default="firmware", metavar="DIR",
                   help="where the .uf2 goes (default ./firmware), beside texelpad-NAME.romfs "
                        "(the partition alone) and .elf (for a debugger), and the build's own: "
                        "build/ and build.log (kept: a second build only relinks), board/ (the "
                        "board folder as built, with the frozen power-up), usermods.cmake (the C "
                        "modules), .build.lock (one build at a time per folder)")
    p.add_argument("--micropython", default=None, metavar="DIR",
                   help="a MicroPython v1.28.0 checkout to build with (default: the offline kit)")
    p.add_argument("--ulab", default=None, metavar="DIR",
                   help="with --micropython: a ulab 6.12 checkout, built in as a user C module")
    p.add_argument("--qemu", action="store_true",
                   help="an STM32 board (pyboard): build its emulated twin instead "
                        "(DIR/texelpad-NAME-qemu.*: the same firmware with the board folder's "
                        "qemu/ definition, for ../shared/instruments/stm32emu; docs/firmware.md)")
    p.set_defaults(func=cmd_firmware)


def _board_dir(args: argparse.Namespace) -> Path:
    from ..firmware.build import repo_boards_dir
    if args.board_dir:
        return Path(args.board_dir)
    name = args.board or "pico"
    boards = repo_boards_dir()
    if boards is None:
        raise CliError("--board", "the boards/ folder ships with texelpad's source, not the "
                                  "wheel: clone the repository, or give --board-dir DIR")
    d = boards / name
    if not d.is_dir():
        have = sorted(x.name for x in boards.iterdir() if (x / "board.json").is_file())
        raise CliError("--board", "%r: no such board folder in %s (have: %s)"
                       % (name, boards, ", ".join(have)))
    return d


def _board_check(board_dir: Path) -> None:
    """What `texelpad board check --firmware texelpad` refuses in the folder's board.json
    (e.g. a cpu_hz no PLL setting makes, a pin the PWM cannot drive): refused here with
    its lines, exit 2, before a 2-3 minute build. A file that is not JSON is left to the
    build's own folder check (firmware/build.py check_board_dir), which says so."""
    import json
    from ..deploy import boardcheck
    path = board_dir / "board.json"
    try:
        doc = json.loads(path.read_text())
    except (OSError, ValueError, RecursionError):
        return
    rep = boardcheck.check(doc, "texelpad", board_dir.name)
    if rep.errors:
        n = len(rep.errors)
        raise CliError("--board-dir", "\n".join(
            [p.line(str(path)) for p in rep.errors]
            + ["%s: %d problem%s for the texelpad firmware (texelpad board check %s --firmware "
               "texelpad says the same): fix %s, then build" % (path, n, "" if n == 1 else "s",
                                                               path, "it" if n == 1 else "them")]))


CPY_README = """texelpad for CircuitPython (texel %(version)s): copy onto the CIRCUITPY drive

1. Install CircuitPython 10 on the board (circuitpython.org/downloads; e.g. the
   Raspberry Pi Pico's .uf2: hold BOOTSEL, plug it in, drag the .uf2 onto RPI-RP2).
2. Copy lib/ and code.py from here onto the CIRCUITPY drive that appears
   (code.py replaces the drive's own: keep a copy if you wrote one).
3. The board restarts and plays the power-up scene; /texelpad.json, if you add
   one (texelpad scene boot), chooses the board file and scene.
4. From a computer: texelpad status --port PORT, texelpad push --port PORT ...
   (the display plays on between commands: texel.app.serve, docs/runtime.md).

Board file: pico_cpy (wiring in lib/texel/boards.d/pico_cpy.json and texelpad's
hardware/README.md). %(files)d files, %(bytes)d bytes.
"""


def _circuitpython_zip(out: str) -> int:
    """DIR/texelpad-circuitpython.zip: the CIRCUITPY layout texelpad deploy writes,
    with the power-up script as code.py (CircuitPython runs code.py first)."""
    import zipfile
    from .. import image
    from texel import __version__
    files = image.build_image(image.TARGETS["circuitpython"], include_main=True)
    d = Path(out)
    d.mkdir(parents=True, exist_ok=True)
    path = d / "texelpad-circuitpython.zip"
    tmp = path.with_name(path.name + ".tmp")
    n = sum(f.size for f in files)
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
        for f in files:
            name = "code.py" if f.remote == image.REMOTE_MAIN else f.remote.lstrip("/")
            z.writestr(name, f.data)
        z.writestr("README.txt", CPY_README % {"version": __version__, "files": len(files),
                                                "bytes": n})
    tmp.replace(path)
    print("%s  (CircuitPython: %d files, %d bytes on the drive)" % (path, len(files), n))
    print("  unzip it onto the CIRCUITPY drive (lib/ and code.py); README.txt inside says how")
    return EXIT_OK


def cmd_firmware(args: argparse.Namespace) -> int:
    from ..firmware.build import FirmwareError, build_firmware
    if args.circuitpython:
        if args.micropython or args.ulab:
            raise CliError("--circuitpython", "builds no firmware: CircuitPython's own .uf2 "
                                              "comes from circuitpython.org")
        return _circuitpython_zip(args.out)
    if args.ulab and not args.micropython:
        raise CliError("--ulab", "goes with --micropython (the offline kit has its own ulab)")
    d = _board_dir(args)
    _board_check(d)
    try:
        b = build_firmware(d, args.out, args.micropython, args.ulab,
                           progress=lambda m: print("firmware: " + m, file=sys.stderr, flush=True),
                           qemu=args.qemu)
    except FirmwareError as e:
        msg = str(e)
        flag = "--board-dir" if ("board folder" in msg or "board.json" in msg
                                 or "mpconfigboard" in msg) else ""
        if flag:
            raise CliError(flag, msg) from None
        print("texelpad firmware: " + msg, file=sys.stderr)
        return EXIT_FAIL
    kb = 1024
    if b.port == "stm32":
        return _stm32_done(b)
    print("%s  (board %s)" % (b.uf2, b.board))
    print("  MicroPython 1.28 + ulab: %d KB of flash; texelpad's ROMFS: %d of %d KB at 0x%06x; "
          "your files (littlefs): %d KB" % (b.firmware_bytes // kb, b.romfs_bytes // kb,
                                            b.romfs_capacity // kb, b.romfs_base,
                                            b.storage_bytes // kb))
    print("  built in %.0f s. Hold BOOTSEL, plug the Pico in, drag the .uf2 onto RPI-RP2; it "
          "reboots playing. Then: texelpad demo --port PORT" % b.seconds)
    return EXIT_OK


def _stm32_done(b) -> int:
    kb = 1024
    print("%s  (board %s%s)" % (b.image, b.board, ", the emulated twin" if b.qemu else ""))
    print("  MicroPython 1.28 with texelpad frozen in: %d KB of flash; texelpad's ROMFS: %d of %d "
          "KB at 0x%08x; the same blocks as .bin files beside it" % (
              b.firmware_bytes // kb, b.romfs_bytes // kb, b.romfs_capacity // kb, b.romfs_base))
    if b.qemu:
        print("  built in %.0f s. Boot it on the emulated STM32F405 (docs/firmware.md):\n"
              "  FW=%s ../shared/instruments/stm32emu/run.sh --pty --icount 3 --no-romfs "
              "-device loader,file=%s,addr=0x%08x,force-raw=on" % (b.seconds, b.elf, b.romfs,
                                                                  b.romfs_base))
    else:
        print("  built in %.0f s. Set the board's BOOT0 jumper (DFU mode), plug it in, then: "
              "dfu-util -a 0 -D %s; remove the jumper and reset. Then: texelpad demo --port PORT"
              % (b.seconds, b.image))
    return EXIT_OK

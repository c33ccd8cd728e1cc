"""Build the texelpad firmware for a board folder (boards/<name>/): `texelpad firmware`.

    build_firmware(board_dir, out_dir, micropython=None, ulab=None, progress=None) -> Built

What it makes, in out_dir:
    texelpad-<name>.uf2      the firmware and texelpad's ROMFS partition in one file: drag it
                             onto a Pico in BOOTSEL mode and it boots playing its power-up scene
    texelpad-<name>.romfs    the ROMFS partition alone (what `texelpad deploy` writes)
    texelpad-<name>.elf      the firmware's symbols (rp2emu --profile, arm-none-eabi-nm)
    build/                   CMake's folder (kept: a rebuild only relinks)

The MicroPython build is the rp2 port of MicroPython v1.28.0 with ulab 6.12 and texelpad's brush
core (_texelcore: device/cmod/texelcore - format 2's plan and int engine, the brush painter)
as user C modules (user_modules):
by default the offline kit in ../shared/instruments/mpfirmware (build.sh), or a MicroPython
checkout of the user's (micropython=DIR: `git clone -b v1.28.0
https://github.com/micropython/micropython`, `make -C mpy-cross`, `make -C ports/rp2 submodules`;
ulab=DIR: ulab 6.12's checkout). Needs Debian's gcc-arm-none-eabi libnewlib-arm-none-eabi cmake.

The board folder holds a MicroPython board definition (mpconfigboard.h, mpconfigboard.cmake,
pins.csv, manifest.py) and texelpad's board file (board.json); the build copies it, adds the
frozen power-up (frozen_main.py as main.py) and never writes into the board folder.
"""
from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import time
from pathlib import Path
from typing import Callable, Iterator

from .. import toolchain
from .. import image
from . import romfs
from .common import (BUILD_PREFIX, FIRMWARE_INFO, FROZEN_BOOT, FROZEN_MAIN,  # noqa: F401
                     MICROPYTHON_VERSION, TEXELCORE_DIR, Built, FirmwareError,
                     board_of_build, finish_payload, run_logged as _run)

FLASH_BYTES = 2 * 1024 * 1024         # a Pico's W25Q16 (PICO_FLASH_SIZE_BYTES for "pico")
# every board folder's (rp2 folders also hold mpconfigboard.cmake, stm32 ones mpconfigboard.mk)
BOARD_FILES = ("mpconfigboard.h", "pins.csv", "manifest.py", "board.json")

def repo_boards_dir() -> Path | None:
    """boards/ of the checkout this package runs from (None from a wheel)."""
    d = Path(__file__).resolve().parents[3] / "boards"
    return d if d.is_dir() else None


def _macro(text: str, name: str) -> int | None:
    """The value of #define NAME (an int expression of +, *, (), digits) in a header."""
    m = re.search(r"^\s*#define\s+%s\s+(.+?)\s*(//.*)?$" % name, text, re.M)
    if not m:
        return None
    expr = m.group(1)
    if not re.fullmatch(r"[\d\s()*+]+", expr):
        raise FirmwareError("mpconfigboard.h: %s = %s: use a number like (640 * 1024)" % (name, expr))
    return int(eval(expr, {"__builtins__": {}}))   # digits, spaces, * + ( ) only


def layout(board_dir: Path) -> tuple[int, int, int]:
    """(ROMFS base offset, ROMFS bytes, littlefs bytes) of a board definition."""
    text = (board_dir / "mpconfigboard.h").read_text()
    storage = _macro(text, "MICROPY_HW_FLASH_STORAGE_BYTES")
    rom = _macro(text, "MICROPY_HW_ROMFS_BYTES")
    if not rom:
        raise FirmwareError("%s/mpconfigboard.h: MICROPY_HW_ROMFS_BYTES is missing or 0: texelpad "
                            "runs from a ROMFS partition (e.g. #define MICROPY_HW_ROMFS_BYTES "
                            "(640 * 1024))" % board_dir)
    if storage is None:
        raise FirmwareError("%s/mpconfigboard.h: MICROPY_HW_FLASH_STORAGE_BYTES is missing" % board_dir)
    if rom % 4096 or storage % 4096:
        raise FirmwareError("%s/mpconfigboard.h: the ROMFS and storage sizes must be multiples "
                            "of 4096" % board_dir)
    return FLASH_BYTES - storage - rom, rom, storage


def check_board_dir(board_dir: Path) -> dict:
    """The board file (board.json) of a board folder, after checking the folder is one."""
    if not board_dir.is_dir():
        raise FirmwareError("%s: no such board folder" % board_dir)
    missing = [f for f in BOARD_FILES if not (board_dir / f).is_file()]
    if missing:
        raise FirmwareError("%s: not a texelpad board folder: %s missing (boards/pico is an "
                            "example)" % (board_dir, ", ".join(missing)))
    from texel.runtime import boards
    real = str(board_dir / "board.json")
    # the board file's name is the folder's (boards/pico/board.json is board "pico")
    as_named = str(board_dir / (board_dir.name + ".json"))
    try:
        doc = json.loads((board_dir / "board.json").read_text())
        if isinstance(doc, dict) and doc.get("name") != board_dir.name:
            raise ValueError("%s: name: %r: must be the board folder's name (%r)"
                             % (real, doc.get("name"), board_dir.name))
        board = boards.validate(doc, as_named)
    except RecursionError:
        raise FirmwareError("%s: not a board file (nested too deep)" % real) from None
    except ValueError as e:
        raise FirmwareError(str(e).replace(as_named, real).splitlines()[0][:400]) from None
    if board["port"] == "stm32":
        from . import build_stm32
        try:
            build_stm32.check_stm32_dir(board_dir)
        except build_stm32.LayoutError as e:
            raise FirmwareError(str(e)) from None
        return board
    if board["port"] != "rp2":
        raise FirmwareError("%s/board.json: port %r: the texelpad firmware is built for RP2040 "
                            "and STM32 boards (ports rp2, stm32); other ports take `texelpad "
                            "deploy` on their stock firmware" % (board_dir, board["port"]))
    missing = [f for f in ("mpconfigboard.cmake",) if not (board_dir / f).is_file()]
    if missing:
        raise FirmwareError("%s: not a texelpad board folder: %s missing (boards/pico is an "
                            "example)" % (board_dir, ", ".join(missing)))
    layout(board_dir)
    return board


def romfs_payload(board_dir: Path, board: dict) -> tuple[dict[str, bytes], bytes]:
    """(files, image) of the ROMFS partition for a board folder."""
    return payload_for(board["name"], (board_dir / "board.json").read_bytes())


def payload_for(name: str, board_json: bytes, code: bool = False,
                frozen_code: str | None = None) -> tuple[dict[str, bytes], bytes]:
    """(files, image) of the ROMFS partition of the firmware for board name:
    texelpad's package data and flash maps, the board file (board_json)
    among the shipped boards, firmware.json (the board, the versions, the
    digest of the code frozen in the firmware and of the partition's files:
    what `texelpad deploy` compares); with code, texelpad's .mpy image too
    (it then runs instead of the frozen copy: FROZEN_BOOT)."""
    files = romfs.romfs_files(image.TARGETS["rp2"], code=code)
    return finish_payload(name, board_json, files, frozen_code or romfs.code_digest(), code)


def stage_board(board_dir: Path, stage: Path) -> None:
    """The definition the build reads: a copy of the board folder with
    texelpad's frozen power-up (main.py, boot.py) and the texel package's
    sources beside its manifest.py (which freezes them)."""
    shutil.rmtree(stage, ignore_errors=True)
    shutil.copytree(board_dir, stage)
    shutil.copyfile(FROZEN_MAIN, stage / "main.py")
    shutil.copyfile(FROZEN_BOOT, stage / "boot.py")
    for rel, data in romfs.frozen_sources().items():
        dst = stage / rel
        dst.parent.mkdir(parents=True, exist_ok=True)
        dst.write_bytes(data)


def _kit() -> Path | None:
    d = toolchain.instruments_dir()
    return d / "mpfirmware" if d and (d / "mpfirmware" / "build.sh").is_file() else None


def _needs() -> None:
    missing = [t for t in ("arm-none-eabi-gcc", "cmake", "make") if not shutil.which(t)]
    if missing:
        raise FirmwareError("%s not found: install Debian's gcc-arm-none-eabi "
                            "libnewlib-arm-none-eabi cmake build-essential" % ", ".join(missing))


def user_modules(out: Path, ulab_cmake: Path | None, say: Callable[[str], None]) -> Path:
    """The user C modules' CMake file for the build (out/usermods.cmake):
    ulab's (when given) and texelpad's _texelcore (when its sources are
    here: a checkout; without them the firmware runs the viper twins)."""
    lines = ["# written by texelpad firmware (host/texelpad/firmware/build.py)"]
    if ulab_cmake is not None:
        lines.append("include(%s)" % Path(ulab_cmake).as_posix())
    if (TEXELCORE_DIR / "micropython.cmake").is_file():
        lines.append("include(%s)" % (TEXELCORE_DIR / "micropython.cmake").as_posix())
    else:
        say("no %s: the firmware runs format 2 and the brush in viper, without the C core"
            % TEXELCORE_DIR)
    f = out / "usermods.cmake"
    text = "\n".join(lines) + "\n"
    changed = f.is_file() and f.read_text() != text
    if not f.is_file() or changed:                  # unchanged: CMake keeps its cache
        f.write_text(text)
    # the rp2 Makefile runs CMake only when its build folder has no Makefile, so a
    # folder configured with other user modules (an older texelpad's: ulab alone)
    # would silently keep them: have it configured again
    cmake_dir = out / "build" / "build"
    cache = cmake_dir / "CMakeCache.txt"
    if cache.is_file():
        want = "USER_C_MODULES:UNINITIALIZED=%s" % f
        if changed or want not in cache.read_text(errors="replace").splitlines():
            say("the build folder was configured with other C modules: configuring it again")
            (cmake_dir / "Makefile").unlink(missing_ok=True)
            # MicroPython collects each source's MP_REGISTER_MODULE into a file of
            # genhdr/module/ and links every file there: a module whose source is
            # gone (texelpad 0.2's _texelbrush, now _texelcore) would stay listed
            shutil.rmtree(cmake_dir / "genhdr", ignore_errors=True)
    return f


def build_firmware(board_dir: str | os.PathLike, out_dir: str | os.PathLike,
                   micropython: str | os.PathLike | None = None,
                   ulab: str | os.PathLike | None = None,
                   progress: Callable[[str], None] | None = None, qemu: bool = False) -> Built:
    """The firmware of a board folder: an rp2 board's .uf2 (_build), an stm32 board's .dfu
    (build_stm32; qemu: its emulated twin instead)."""
    say = progress or (lambda m: None)
    t0 = time.monotonic()
    board_dir = Path(board_dir).resolve()
    board = check_board_dir(board_dir)
    if board["port"] != "stm32" and qemu:
        raise FirmwareError("--qemu: an emulated twin is built for STM32 boards (their qemu/ "
                            "folder); the Pico's firmware boots on rp2emu as it is")
    if board["port"] == "stm32" and ulab is not None:
        raise FirmwareError("--ulab: the STM32 firmware is built without ulab")
    out = Path(out_dir).resolve()
    out.mkdir(parents=True, exist_ok=True)
    with _one_build_at_a_time(out, say):
        if board["port"] == "stm32":
            from .build_stm32 import build_stm32
            return build_stm32(board_dir, board, out, micropython, qemu, say, t0)
        return _build(board_dir, board, out, micropython, ulab, say, t0)


@contextlib.contextmanager
def _one_build_at_a_time(out: Path, say: Callable[[str], None]) -> Iterator[None]:
    """An exclusive flock on out/.build.lock while building: two builds into
    one folder (two terminals, or two test workers sharing the tests' cache)
    would write the same CMake tree and .uf2 at once. The second waits, then
    finds the tree built and only relinks. No fcntl (Windows): no lock."""
    try:
        import fcntl
    except ImportError:                 # pragma: no cover - not POSIX
        yield
        return
    with open(out / ".build.lock", "w") as f:
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            say("another build is using %s: waiting for it to end" % out)
            fcntl.flock(f, fcntl.LOCK_EX)
        yield                           # closing the file lets go of the lock


def _build(board_dir: Path, board: dict, out: Path, micropython: str | os.PathLike | None,
           ulab: str | os.PathLike | None, say: Callable[[str], None], t0: float) -> Built:
    name = board["name"]
    base, capacity, storage = layout(board_dir)
    say("texelpad's data for the ROMFS partition (maps, boards); its code is frozen")
    files, img = romfs_payload(board_dir, board)
    if len(img) > capacity:
        raise FirmwareError("texelpad's image (%s bytes) does not fit the ROMFS partition (%s "
                            "bytes): raise MICROPY_HW_ROMFS_BYTES in %s/mpconfigboard.h"
                            % (format(len(img), ","), format(capacity, ","), board_dir))
    # the definition the build reads: a copy of the folder with the frozen power-up in it
    stage = out / "board" / (BUILD_PREFIX + re.sub(r"[^A-Za-z0-9]", "_", name).upper())
    stage_board(board_dir, stage)
    _needs()
    log = out / "build.log"
    log.write_text("")
    fw = out / "build"
    if micropython is None:
        kit = _kit()
        if kit is None:
            raise FirmwareError("no MicroPython source tree: give --micropython DIR (MicroPython "
                                "v%s, see docs/firmware.md), or put the offline kit at "
                                "../shared/instruments/mpfirmware" % MICROPYTHON_VERSION)
        mods = user_modules(out, kit / "ulab" / "code" / "micropython.cmake", say)
        say("building MicroPython v%s + ulab with the offline kit (about 2 min the first time; "
            "log: %s)" % (MICROPYTHON_VERSION, log))
        _run(["bash", str(kit / "build.sh"), str(stage), str(fw), str(mods)], log)
        bin_, uf2, elf = fw / "firmware.bin", fw / "firmware.uf2", fw / "firmware.elf"
    else:
        mp = Path(micropython).resolve()
        port = mp / "ports" / "rp2"
        if not (port / "Makefile").is_file():
            raise FirmwareError("%s: not a MicroPython source tree (no ports/rp2/Makefile)" % mp)
        cm = None
        if ulab is not None:
            cm = Path(ulab).resolve() / "code" / "micropython.cmake"
            if not cm.is_file():
                raise FirmwareError("%s: not a ulab checkout (no code/micropython.cmake)" % ulab)
        user_mods = ["USER_C_MODULES=%s" % user_modules(out, cm, say)]
        say("building MicroPython from %s (log: %s)" % (mp, log))
        jobs = "-j%d" % (os.cpu_count() or 2)
        _run(["make", "-C", str(mp / "mpy-cross"), jobs], log)
        _run(["make", "-C", str(port), "BOARD_DIR=%s" % stage, "BUILD=%s" % (fw / "build"), jobs]
             + user_mods, log)
        bin_, uf2, elf = (fw / "build" / n for n in ("firmware.bin", "firmware.uf2", "firmware.elf"))
    fw_bytes = bin_.stat().st_size
    if fw_bytes > base:
        raise FirmwareError("the firmware (%s bytes) runs into the ROMFS partition at %s: lower "
                            "MICROPY_HW_ROMFS_BYTES or MICROPY_HW_FLASH_STORAGE_BYTES"
                            % (format(fw_bytes, ","), format(base, ",")))
    say("joining the firmware and the ROMFS partition into one .uf2")
    joined = romfs.join_uf2(uf2.read_bytes(), romfs.uf2_blocks(img, romfs.XIP_BASE + base))
    dst = out / ("texelpad-%s.uf2" % name)
    tmp = dst.with_suffix(".uf2.tmp")
    tmp.write_bytes(joined)
    os.replace(tmp, dst)
    rom = out / ("texelpad-%s.romfs" % name)
    rom.write_bytes(img)
    elf_dst = out / ("texelpad-%s.elf" % name)
    shutil.copyfile(elf, elf_dst)
    return Built(dst, rom, elf_dst, name, fw_bytes, len(img), capacity, base, storage,
                 time.monotonic() - t0)

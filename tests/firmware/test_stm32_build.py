"""The STM32 firmware build's pure parts (issue 34; no compiler, no board): the DfuSe writer and
reader, the flash layout read from a board folder's linker script, a maker's folder refused
with one line before any build, the staged folder keeping unchanged files' times (make
recompiles what depends on a file whose time changed), the ROMFS payload. The build itself and
its image booted: tests/firmware/test_firmware_pyboard.py."""
from __future__ import annotations

import json
import os
import shutil
import struct
import zlib
from pathlib import Path

import pytest

from texelpad.firmware import build, build_stm32, dfuse, romfs

ROOT = Path(__file__).resolve().parents[2]
PYBOARD = ROOT / "boards" / "pyboard"


def test_dfuse_round_trip_and_its_checks():
    blocks = [(0x08000000, b"\x01" * 13), (0x08020000, bytes(range(256)) * 3), (0x080C0000, b"")]
    data = dfuse.dfuse_file(blocks)
    back = dfuse.read_dfuse(data)
    assert [a for a, _d in back] == [a for a, _d in blocks]
    for (_a, d), (_b, e) in zip(blocks, back):
        assert e[:len(d)] == d and len(e) % 8 == 0 and not e[len(d):].strip(b"\0")
    # the suffix: DFU 1.1a, "UFD", 16 bytes, ST's bootloader 0483:df11, CRC over the rest
    assert data[-16:-4] == struct.pack("<4H3sB", 0, 0xDF11, 0x0483, 0x011A, b"UFD", 16)
    assert struct.unpack("<I", data[-4:])[0] == 0xFFFFFFFF & (-zlib.crc32(data[:-4]) - 1)
    bad = bytearray(data)
    bad[40] ^= 1
    with pytest.raises(ValueError, match="CRC"):
        dfuse.read_dfuse(bytes(bad))
    with pytest.raises(ValueError, match="not a DfuSe"):
        dfuse.read_dfuse(b"hello" * 10)
    with pytest.raises(ValueError, match="at least one block"):
        dfuse.dfuse_file([])


def test_the_pyboards_flash_layout_comes_from_its_linker_script():
    lay = build_stm32.flash_layout(PYBOARD)
    assert lay == {"start": (0x08000000, 16 * 1024), "text": (0x08020000, 640 * 1024),
                   "romfs": (0x080C0000, 256 * 1024)}
    # sectors 5-9 then 10-11 of the F405's 1 MB: they meet, and end at the flash's end
    assert lay["text"][0] + lay["text"][1] == lay["romfs"][0]
    assert lay["romfs"][0] + lay["romfs"][1] == 0x08100000


def _copy(tmp_path: Path) -> Path:
    d = tmp_path / "mine"
    shutil.copytree(PYBOARD, d)
    board = json.loads((d / "board.json").read_text())
    board["name"] = "mine"
    (d / "board.json").write_text(json.dumps(board))
    return d


def test_a_makers_stm32_folder_is_refused_with_one_line_before_building(tmp_path):
    d = _copy(tmp_path)
    assert build.check_board_dir(d)["port"] == "stm32"
    (d / "texelpad_f405.ld").unlink()
    with pytest.raises(build.FirmwareError, match="needs one linker script .* FLASH_ROMFS"):
        build.check_board_dir(d)
    d = _copy(tmp_path / "b")
    (d / "mpconfigboard.mk").unlink()
    with pytest.raises(build.FirmwareError, match="mpconfigboard.mk missing"):
        build.check_board_dir(d)
    d = _copy(tmp_path / "c")
    ld = d / "texelpad_f405.ld"
    ld.write_text(ld.read_text().replace("FLASH_TEXT (rx)", "FLASH_TXT (rx)"))
    with pytest.raises(build.FirmwareError, match="no MEMORY region FLASH_TEXT"):
        build.check_board_dir(d)
    for k, (old_, new_, words) in enumerate((
            ("FLASH_ROMFS (r) : ORIGIN = 0x080C0000", "FLASH_ROMFS (r) : ORIGIN = 0x080B0000",
             "overlaps FLASH_TEXT"),
            ("FLASH_TEXT (rx) : ORIGIN = 0x08020000, LENGTH = 640K",
             "FLASH_TEXT (rx) : ORIGIN = 0x08020000, LENGTH = 512K", None),
            ("FLASH_ROMFS (r) : ORIGIN = 0x080C0000, LENGTH = 256K",
             "FLASH_ROMFS (r) : ORIGIN = 0x080C1000, LENGTH = 200K", "flash sector boundaries"))):
        d = _copy(tmp_path / ("l%d" % k))
        ld = d / "texelpad_f405.ld"
        assert old_ in ld.read_text()
        ld.write_text(ld.read_text().replace(old_, new_))
        if words is None:
            build.check_board_dir(d)                  # sectors 5-8 then 10-11: fine
        else:
            with pytest.raises(build.FirmwareError, match=words):
                build.check_board_dir(d)
    d = _copy(tmp_path / "h")
    (d / "stm32f4xx_hal_conf.h").unlink()
    with pytest.raises(build.FirmwareError, match="stm32f4xx_hal_conf.h"):
        build.check_board_dir(d)
    with pytest.raises(build.FirmwareError, match="--ulab: the STM32 firmware is built without"):
        build.build_firmware(_copy(tmp_path / "e"), tmp_path / "out", ulab=tmp_path)
    with pytest.raises(build.FirmwareError, match="--qemu: an emulated twin is built for STM32"):
        build.build_firmware(ROOT / "boards" / "pico", tmp_path / "out", qemu=True)


def test_the_staged_folder_keeps_unchanged_files_times(tmp_path):
    st = tmp_path / "stage"
    build_stm32.stage(PYBOARD, st, qemu=True)
    h = st / "mpconfigboard.h"
    assert "QEMU" in h.read_text() and (st / "board_init.c").is_file() and not (st / "qemu").exists()
    assert (st / "texel" / "hw" / "stm32_irq.py").is_file() and not (st / "texel/hw/rp2.py").exists()
    old = h.stat().st_mtime_ns - 10_000_000_000
    os.utime(h, ns=(old, old))
    (st / "stale.c").write_text("left from an older board folder")
    build_stm32.stage(PYBOARD, st, qemu=True)
    assert h.stat().st_mtime_ns == old                  # unchanged: not rewritten
    assert not (st / "stale.c").exists()                # gone from the folder: gone here
    build_stm32.stage(PYBOARD, st, qemu=False)          # the real board: its own header
    assert "QEMU" not in h.read_text() and not (st / "board_init.c").exists()


def test_the_pyboards_partition_holds_data_and_three_maps_not_code():
    from texelpad import image
    files, img = build_stm32.payload("pyboard", (PYBOARD / "board.json").read_bytes())
    assert romfs.read_romfs(img) == files
    assert not any(k.endswith(".mpy") for k in files)
    assert not any("texel_ram" in k for k in files)
    # the maps of the three slowest references (image.MAP_NAMES), not all nine
    assert sorted(k for k in files if "/ref/" in k) == sorted(
        "lib/texel/gen/ref/%s.u16" % n for n in image.MAP_NAMES)
    assert {"lib/texel/gen/reference_noise.bin", "lib/texel/gen/sine_table.u16",
            "lib/texel/boards.d/pyboard.json", "firmware.json"} <= set(files)
    info = json.loads(files["firmware.json"])
    assert info["frozen_code_sha256"] == romfs.code_digest(build_stm32.TARGET)
    assert len(img) <= build_stm32.flash_layout(PYBOARD)["romfs"][1]

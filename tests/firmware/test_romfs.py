"""The ROMFS image and the .uf2 the firmware build writes (pure: no build, no board)."""
from __future__ import annotations

import json
import struct
from pathlib import Path

import pytest

from texelpad.firmware import build, romfs

ROOT = Path(__file__).resolve().parents[2]


def test_a_romfs_image_reads_back_file_for_file():
    files = {"lib/texel/app.mpy": b"M\x06abc", "lib/texel/gen/ref/x.u16": bytes(range(256)) * 3,
             "lib/texel/gen/ref/y.u16": b"\x01\x02" * 9, "firmware.json": b"{}",
             "lib/texel/boards.d/pico.json": b"{\"name\": \"pico\"}"}
    img = romfs.romfs_image(files)
    assert img.startswith(romfs.ROMFS_HEADER) and len(img) % 2 == 0
    assert romfs.read_romfs(img) == files
    assert romfs.romfs_image(dict(reversed(list(files.items())))) == img    # order-free


@pytest.mark.parametrize("n", [1, 2, 3, 5, 126, 127, 128, 16383, 16384, 38400])
def test_u16_maps_start_4_byte_aligned_whatever_their_sizes(n):
    # a Cortex-M0+ faults on an unaligned halfword load (viper ptr16 is a plain ldrh)
    # each map starts with a marker found nowhere else in the image
    files = {"a/%d.u16" % k: b"MAP%d\xee\xdd\xcc\xbb" % k + bytes([k]) * (n + k) for k in range(5)}
    files["b.mpy"] = b"x" * n
    img = romfs.romfs_image(files)
    for k in range(5):
        data = files["a/%d.u16" % k]
        at = img.find(data)
        assert at >= 0 and at % romfs.ALIGN == 0
    assert romfs.read_romfs(img) == files


def test_uf2_blocks_join_and_read_back():
    fw = romfs.write_uf2(romfs.uf2_blocks(b"\x11" * 1000, romfs.XIP_BASE))
    joined = romfs.join_uf2(fw, romfs.uf2_blocks(b"\x22" * 300, romfs.XIP_BASE + 0xA0000))
    blocks = romfs.read_uf2(joined)
    assert [a for a, _, _ in blocks] == [romfs.XIP_BASE + 256 * k for k in range(4)] + [
        romfs.XIP_BASE + 0xA0000, romfs.XIP_BASE + 0xA0000 + 256]
    n = len(blocks)
    for i in range(n):      # block numbers and the count are the joined file's own
        no, count, fam = struct.unpack_from("<3I", joined, 512 * i + 20)
        assert (no, count, fam) == (i, n, romfs.RP2040_FAMILY)
    assert blocks[-1][1] == b"\x22" * 44 + b"\xff" * 212
    with pytest.raises(ValueError, match="overlap"):
        romfs.join_uf2(fw, romfs.uf2_blocks(b"\x33" * 10, romfs.XIP_BASE + 512))
    with pytest.raises(ValueError, match="not a UF2"):
        romfs.read_uf2(b"\0" * 512)


def test_the_romfs_holds_texelpad_and_the_references_flash_maps():
    import numpy as np
    from texel.gen import reference
    files = romfs.romfs_files()
    assert romfs.BOOT_MODULE in files and "lib/texel/app.mpy" in files
    assert "lib/texel/hw/rp2.mpy" in files and "lib/texel/hw/stm32.mpy" not in files
    # the brush painter's tables, read in place (gen/brush.py TABLE_FILES)
    from texel.gen import brush
    for (f, code), values in zip(brush.TABLE_FILES, (brush.PHASE, brush.TW, brush.HANN,
                                                     brush.LOG2, brush.POS)):
        dt = "<i2" if code == "h" else "<i4"
        assert np.frombuffer(files["lib/texel/gen/" + f], dtype=dt).tolist() == list(values), f
    for name in reference.STUDY_NAMES:
        m = np.frombuffer(files["lib/texel/gen/ref/%s.u16" % name], dtype="<u2")
        assert len(m) == reference.FLASH_SAMPLES
        # a region of any length plays a prefix: the same values as rendering it that long
        for n in (1, 9600, 12345):
            assert (m[:n] == np.asarray(reference.reference_u16(name, n))).all()


@pytest.mark.parametrize("board", ["pico", "pico_bridge"])
def test_every_board_folder_is_a_firmware_definition_with_the_shipped_board_file(board):
    d = ROOT / "boards" / board
    doc = build.check_board_dir(d)
    assert doc["name"] == board
    # the installed package carries the same file (a wheel deploys without boards/)
    shipped = ROOT / "device" / "texel" / "boards.d" / (board + ".json")
    assert json.loads(shipped.read_text()) == json.loads((d / "board.json").read_text())
    base, rom, storage = build.layout(d)
    assert base + rom + storage == build.FLASH_BYTES
    assert base <= 0xA0000          # the emulated Pico's flash file starts there
    assert "package(\"texel\", base_path=\"$(BOARD_DIR)\")" in (d / "manifest.py").read_text()


def test_a_board_folder_that_is_not_one_is_refused_saying_what_is_missing(tmp_path):
    with pytest.raises(build.FirmwareError, match="no such board folder"):
        build.check_board_dir(tmp_path / "nope")
    with pytest.raises(build.FirmwareError, match="mpconfigboard.h, .*board.json missing"):
        build.check_board_dir(tmp_path)
    import shutil
    d = tmp_path / "mine"
    shutil.copytree(ROOT / "boards" / "pico", d)
    with pytest.raises(build.FirmwareError, match="must be the board folder's name"):
        build.check_board_dir(d)
    doc = json.loads((d / "board.json").read_text())
    doc["name"] = "mine"
    doc["carrier"]["freq_hz"] = 5
    (d / "board.json").write_text(json.dumps(doc))
    with pytest.raises(build.FirmwareError, match=r"mine/board.json: carrier.freq_hz"):
        build.check_board_dir(d)
    doc["carrier"]["freq_hz"] = 34000
    (d / "board.json").write_text(json.dumps(doc))
    (d / "mpconfigboard.h").write_text("#define MICROPY_HW_FLASH_STORAGE_BYTES (1408 * 1024)\n")
    with pytest.raises(build.FirmwareError, match="MICROPY_HW_ROMFS_BYTES is missing"):
        build.check_board_dir(d)
    (d / "board.json").write_text("[" * 50000)
    with pytest.raises(build.FirmwareError, match="board.json"):
        build.check_board_dir(d)


def test_every_viper_module_runs_from_ram_not_from_the_freeze():
    """romfs.RAM_MODULES is every module holding viper code: MicroPython's
    mpy-tool aligns frozen armv6m code to 2 bytes while viper code loads its
    constants as if it started on 4, so no native code may be frozen (the
    firmware stopped booting when one function moved 2 bytes)."""
    import re
    from texelpad import image
    deco = re.compile(r"^\s*@micropython\.viper\s*$", re.M)
    rp2 = set(image.package_modules("rp2"))
    viper = {p.relative_to(image.PACKAGE_DIR).as_posix()
             for p in image.PACKAGE_DIR.rglob("*.py") if deco.search(p.read_text())}
    # (the STM32's refresh interrupt, hw/stm32_irq.py, is frozen into the pyboard's firmware:
    # armv7emsp's viper loads its constants with movw/movt, not PC-relative; its firmware
    # boots and refreshes in tests/firmware/test_firmware_pyboard.py)
    assert viper - {p.relative_to(image.PACKAGE_DIR).as_posix() for p in rp2} == {"hw/stm32_irq.py"}
    viper &= {p.relative_to(image.PACKAGE_DIR).as_posix() for p in rp2}
    assert viper and viper == set(romfs.RAM_MODULES)
    frozen = romfs.frozen_sources()
    for rel in romfs.RAM_MODULES:
        assert not deco.search(frozen["texel/" + rel].decode())


def test_a_second_build_into_one_folder_waits_for_the_first(tmp_path):
    """build_firmware holds an exclusive flock on OUT/.build.lock: a second
    build into the same folder (another terminal, another test worker) says it
    waits and starts only when the first lets go."""
    import fcntl
    import threading
    import time
    first = open(tmp_path / ".build.lock", "w")
    fcntl.flock(first, fcntl.LOCK_EX)           # the build that is running
    said: list[str] = []
    entered = threading.Event()

    def second():
        with build._one_build_at_a_time(tmp_path, said.append):
            entered.set()

    t = threading.Thread(target=second)
    t.start()
    for _ in range(1000):                         # until the second has tried once
        if said:
            break
        time.sleep(0.01)
    assert not entered.is_set()                   # it waits on the first
    assert said == ["another build is using %s: waiting for it to end" % tmp_path]
    first.close()                                # the first build ends
    assert entered.wait(10)
    t.join(10)


def test_a_board_folder_board_check_refuses_is_refused_before_the_build(tmp_path, capsys):
    """`texelpad firmware --board-dir DIR` runs `texelpad board check --firmware
    texelpad` first (issue 30): a cpu_hz no PLL setting makes and a pin the
    chip does not have are refused with the check's own lines, exit 2, in
    well under a second - no 2-3 minute build, nothing written to --out."""
    import shutil
    import time
    from support.cli import run_cli
    d = tmp_path / "mine"
    shutil.copytree(ROOT / "boards" / "pico", d)
    doc = json.loads((d / "board.json").read_text())
    doc.update(name="mine", cpu_hz=123456789)
    doc["carrier"]["pins"] = [99]
    (d / "board.json").write_text(json.dumps(doc))
    out = tmp_path / "out"
    t0 = time.monotonic()
    code, so, err = run_cli(capsys, "firmware", "--board-dir", str(d), "--out", str(out))
    print("refused in %.2f s" % (time.monotonic() - t0))
    assert code == 2 and "Traceback" not in err, err
    lines = err.strip().splitlines()
    assert "cpu_hz: 123,456,789 Hz is not a clock the RP2040's PLL makes" in lines[0], err
    assert "carrier.pins[0]: GPIO 99 does not exist" in lines[1], err
    assert lines[2].endswith("2 problems for the texelpad firmware (texelpad board check %s "
                             "--firmware texelpad says the same): fix them, then build"
                             % (d / "board.json")), err
    assert not out.exists() or not any(out.iterdir())
    # the same lines as the check itself prints
    code, so, check_err = run_cli(capsys, "board", "check", str(d / "board.json"),
                                  "--firmware", "texelpad")
    assert code == 2 and check_err.splitlines()[:2] == [
        ln.split("--board-dir: ", 1)[-1] for ln in lines[:2]]

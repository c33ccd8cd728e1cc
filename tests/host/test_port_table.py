"""One place for each port fact: texel.compat.PORT_TABLE (platform, backend,
stand-in probe, mpy arch, default board, refresh modes, ROMFS data, words).
Every reader agrees with it (runtime.boards, texelpad.image, texel.app, main.py),
no device or host module outside it compares sys.platform or the
implementation's name (a backend's own chip check aside), and every board
file has one source (boards/NAME/board.json, copied into the package by
tools/gen_boards.py)."""
from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

import pytest

from texel import app, compat
from texel.runtime import boards
from texelpad import image

ROOT = Path(__file__).resolve().parents[2]
DEVICE = ROOT / "device" / "texel"
HOST = ROOT / "host" / "texelpad"
sys.path.insert(0, str(ROOT / "tools"))
import gen_boards  # noqa: E402


@pytest.mark.parametrize("port", compat.PORTS)
def test_every_row_names_what_exists(port):
    row = compat.PORT_TABLE[port]
    mod, cls = row["backend"]
    src = DEVICE / "hw" / (mod + ".py")
    classes = {n.name for n in ast.walk(ast.parse(src.read_text())) if isinstance(n, ast.ClassDef)}
    assert cls in classes, (src, cls)
    assert image.PORT_BACKEND[port] == mod
    board = boards.load(row["board"])                  # its default board is shipped, of its port
    assert board["port"] == port
    assert boards.PORT_MODES[port] == row["modes"] and boards.DEFAULT_MODE[port] == row["modes"][0]
    assert boards.PORT_CHIP[port] == row["chip"]


def test_the_readers_agree_with_the_table():
    assert tuple(compat.PORT_TABLE) == compat.PORTS == boards.PORTS
    assert boards.PLATFORM_PORT == {"rp2": "rp2", "pyboard": "stm32"}
    assert image.TARGETS["rp2"].arch == compat.PORT_TABLE["rp2"]["arch"] == "armv6m"
    assert image.TARGETS["pyboard"].arch == compat.PORT_TABLE["stm32"]["arch"] == "armv7emsp"
    assert [compat.port_of(i, p) for i, p in (("micropython", "rp2"), ("micropython", "pyboard"),
                                               ("circuitpython", "RP2040"), ("micropython", "linux"),
                                               ("cpython", "linux"), ("micropython", "esp32"))] \
        == ["rp2", "stm32", "circuitpython", None, None, None]
    assert compat.PORT is None and compat.default_board() == "virtual"     # CPython: a host
    assert app.default_board(config=False) == "virtual"
    assert compat.backend("virtual").__name__ == "VirtualHw"
    with pytest.raises(ImportError, match="no backend for port 'esp32'"):
        compat.backend("esp32")


PLATFORM_CHECK = re.compile(r"sys\.platform\s*(==|!=|\bin\b)|implementation\.name\s*(==|!=|\bin\b)"
                            r"|platform\s*==\s*[\"']|[\"'](rp2|pyboard)[\"']\s*==")


def test_no_platform_checks_outside_the_table():
    found = []
    for p in sorted(DEVICE.rglob("*.py")) + sorted(HOST.rglob("*.py")):
        rel = p.relative_to(ROOT).as_posix()
        if rel == "device/texel/compat.py" or rel.startswith("device/texel/hw/"):
            continue                    # the table, and a backend's own chip check
        for line in p.read_text().splitlines():
            if PLATFORM_CHECK.search(line.split("#")[0]):
                found.append("%s: %s" % (rel, line.strip()))     # (no line number: it moves)
    # texel.app.CONFIG: the unix port's relative power-up file (the table's UNIX_PLATFORMS)
    assert found == ['device/texel/app.py: CONFIG = "texelpad.json" if sys.platform in '
                     'compat.UNIX_PLATFORMS else "/texelpad.json"'], found


def test_main_py_asks_the_table():
    src = (DEVICE / "main.py").read_text()
    assert "default_board" in src and "sys.platform" not in src
    for name in ("pico", "pyboard", "pico_cpy", "circuitpython"):
        assert '"%s"' % name not in src


def test_every_board_file_has_one_source():
    c = gen_boards.copies()
    assert sorted(p.name for p in c) == ["pico.json", "pico_bridge.json", "pyboard.json"]
    for path, data in c.items():
        assert path.read_bytes() == data, "%s differs from boards/: python tools/gen_boards.py" % path
    folders = {p.stem for p in c}
    for f in sorted((DEVICE / "boards.d").glob("*.json")):    # the rest: the package's alone
        assert f.stem in folders or not (ROOT / "boards" / f.stem).exists()

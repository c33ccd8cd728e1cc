"""docs/device-api.md as printed: its Python blocks, one after the other, on
the MicroPython unix port (the board there is the virtual one: texel.app's
start() with no name picks it from texel.compat.PORT_TABLE), and what they
print. Its mpremote line runs on the emulated Pico in test_doc_mpremote.py."""
from __future__ import annotations

import re
from pathlib import Path

from support import mpy

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "device-api.md"


def blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", DOC.read_text(), re.S)


def test_the_page_has_its_examples():
    assert len(blocks()) == 3
    assert "mpremote exec \"import texel.app as a; print(a.start(None, a.full_screen(" \
        in DOC.read_text()


def test_the_examples_run_as_printed_and_print_what_they_say():
    out = mpy.run("\n".join(blocks()), heapsize="2M").splitlines()
    assert out == [
        "virtual True 2",                                   # the study's split screen
        "gaussian 8.0",                                     # the bump, its defaults filled in
        "regions[0].texture.width_mm: 0 is out of range [0.01, 1000.0]",
        "bump",                                             # the refusal changed nothing
        "['map', 'plan', 'constant']",
        "False",
    ]

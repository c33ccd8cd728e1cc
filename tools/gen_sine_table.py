#!/usr/bin/env python3
"""Regenerate the sine table literal in device/texel/gen/sine_table.py.

(sin(2*pi*i/1024) + 1) * 32767.5, rounded half up, i = 0..1024, as uint16
little-endian. Shipped as a literal so a board does not spend 1,025 float sines
(~150 ms on an emulated RP2040) at its first render. tests/gen/test_precision.py
checks the literal against this formula.
"""
import math
import re
import struct
from pathlib import Path

PATH = Path(__file__).resolve().parents[1] / "device" / "texel" / "gen" / "sine_table.py"
SIZE = 1024


def values():
    return [int((math.sin(2 * math.pi * i / SIZE) + 1.0) * 32767.5 + 0.5) for i in range(SIZE + 1)]


def literal(raw):
    """bytes as the `_RAW = (b'...' ...)` literal of a device table module."""
    lines = []
    for i in range(0, len(raw), 32):
        lines.append("    b'" + "".join("\\x%02x" % b for b in raw[i:i + 32]) + "'")
    return "_RAW = (\n" + "\n".join(lines) + "\n)\n"


def write_raw(path, raw):
    """Replace the _RAW literal in the module at path with raw."""
    src = path.read_text()
    path.write_text(re.sub(r"_RAW = \(\n.*?\)\n", lambda m: literal(raw), src, flags=re.S))
    print("wrote", path)


def main():
    write_raw(PATH, struct.pack("<%dH" % (SIZE + 1), *values()))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Regenerate package.json at the repository root: mip's description of the
device package, so a board can install it without texelpad:

    mpremote mip install ./package.json             # from this checkout
    mpremote mip install github:OWNER/REPO          # from a GitHub copy of it

Both install the `texel` package as source .py files under the board's /lib
(the same layout `texelpad deploy` writes, see host/texelpad/image.py).
tests/host/test_image.py checks the committed file against what this writes, so
run it after adding, removing or renaming a device file or a board.
"""
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "host"), str(ROOT / "device")]   # works without an install too

from texelpad.image import write_package_json  # noqa: E402


def main():
    path = ROOT / "package.json"
    d = write_package_json(path)
    print("wrote %s (%d files, version %s)" % (path, len(d["urls"]), d["version"]))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Copy each firmware board folder's board file, boards/NAME/board.json (the
one source: `texelpad firmware` builds from the folder), into the device
package as device/texel/boards.d/NAME.json, byte for byte, so an installed
texelpad (a wheel, which has no boards/) deploys it. The package's other
board files (pico_cpy, virtual: no firmware folder) have no second
copy. tests/host/test_port_table.py fails while a copy differs:

    python tools/gen_boards.py            # after editing boards/*/board.json
"""
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BOARDS = ROOT / "boards"
PACKAGE_BOARDS = ROOT / "device" / "texel" / "boards.d"


def copies() -> dict[Path, bytes]:
    """{package path: the folder's board file bytes} for every board folder."""
    return {PACKAGE_BOARDS / (d.name + ".json"): (d / "board.json").read_bytes()
            for d in sorted(BOARDS.iterdir()) if (d / "board.json").is_file()}


def main() -> int:
    for path, data in copies().items():
        if not path.is_file() or path.read_bytes() != data:
            path.write_bytes(data)
            print("wrote %s" % path.relative_to(ROOT))
    return 0


if __name__ == "__main__":
    sys.exit(main())

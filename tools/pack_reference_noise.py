#!/usr/bin/env python3
"""Pack the study's three noise rows (white, pink, blue) into
device/texel/gen/reference_noise.bin, the package data texel.reference() reads.

The rows have no closed form (their seeds are unknown), so the golden data
itself is the reference: golden/reference_textures.csv rows 4-6 (1-based;
row order 2sin, 3sin, 4sin, white, pink, blue, square, triangle, sawtooth).

Format: 3 rows x 9,600 samples, uint16 little-endian, row-major, no header
(57,600 bytes); q = floor(v*65535 + 0.5) for v in [0, 1], so the stored value
q/65535 is within 0.5/65535 (7.6e-6) of the CSV value.

    python tools/pack_reference_noise.py [--csv PATH] [--out PATH] [--check]

--check compares instead of writing (exit 1 if the file differs). The CSV is
found at $TEXELPAD_SHARED/golden/ or ../shared/golden/ next to the repo.
"""
import argparse
import csv
import os
import sys
from array import array
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "device" / "texel" / "gen" / "reference_noise.bin"
ROWS = {"white": 3, "pink": 4, "blue": 5}      # 0-based rows of the CSV
LENGTH = 9600


def default_csv() -> Path:
    shared = os.environ.get("TEXELPAD_SHARED")
    base = Path(shared) if shared else ROOT.parent / "shared"
    return base / "golden" / "reference_textures.csv"


def quantize(v: float) -> int:
    if not 0.0 <= v <= 1.0:
        raise ValueError(f"value {v!r} outside [0, 1]")
    return int(v * 65535.0 + 0.5)


def pack(csv_path: Path) -> bytes:
    with open(csv_path, newline="") as f:
        rows = [[float(x) for x in r] for r in csv.reader(f) if r]
    if len(rows) != 9 or any(len(r) != LENGTH for r in rows):
        raise ValueError(f"{csv_path}: expected 9 rows x {LENGTH} values")
    data = array("H")
    for name, i in ROWS.items():
        data.extend(quantize(v) for v in rows[i])
    if sys.byteorder == "big":
        data.byteswap()
    return data.tobytes()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--csv", type=Path, default=default_csv())
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--check", action="store_true", help="compare, do not write")
    a = ap.parse_args(argv)
    blob = pack(a.csv)
    if a.check:
        same = a.out.exists() and a.out.read_bytes() == blob
        print(f"{a.out}: {'up to date' if same else 'DIFFERS from ' + str(a.csv)}")
        return 0 if same else 1
    a.out.write_bytes(blob)
    print(f"wrote {a.out} ({len(blob)} bytes) from {a.csv}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Regenerate the tables of texture format 2 (device/texel/gen/plan_int_tables.py).

Three int32 tables, little-endian, in one bytes literal (docs/generator.md,
"Texture format 2"):

  EXP_HI[k]  = round(2^(k/256)   * 2^28), k = 0..255   2^x, top 8 bits of x's fraction
  EXP_MID[k] = round(2^(k/65536) * 2^28), k = 0..255   the next 8 bits
  NORM[e*32 + j] = round(-Phi^-1(2^e * (1 + j/32) / 2^33) * 2^24),
                 e = 0..31 (octave of the folded draw w = 2v+1), j = 0..31,
                 and NORM[1024] = 0 (u = 1/2): the inverse normal at 32
                 points per octave of u, in Q24.

Phi^-1 is scipy.special.ndtri (relative error ~1e-15, far below the Q24 unit
6e-8). The tables ARE the format: once shipped they never change (a texture
made with format 2 must stay the same texture), so this script exists to show
where they came from; tests/gen/test_plan_int.py checks the shipped literal
against it to within one unit (a rounding tie could differ between libm and
scipy versions, never by more).
"""
import math
import struct
from pathlib import Path

from gen_sine_table import write_raw

PATH = Path(__file__).resolve().parents[1] / "device" / "texel" / "gen" / "plan_int_tables.py"
NORM_PER_OCTAVE = 32
OCTAVES = 32


def exp_hi():
    return [round(2.0 ** (k / 256.0) * 2 ** 28) for k in range(256)]


def exp_mid():
    return [round(2.0 ** (k / 65536.0) * 2 ** 28) for k in range(256)]


def norm():
    from scipy.special import ndtri
    out = []
    for e in range(OCTAVES):
        for j in range(NORM_PER_OCTAVE):
            u = math.ldexp(1.0 + j / NORM_PER_OCTAVE, e - 33)
            out.append(round(-float(ndtri(u)) * 2 ** 24))
    out.append(0)
    return out


def values():
    return exp_hi() + exp_mid() + norm()


def main():
    v = values()
    write_raw(PATH, struct.pack("<%di" % len(v), *v))


if __name__ == "__main__":
    main()

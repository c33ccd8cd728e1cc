#!/usr/bin/env python3
"""Regenerate the table literals of device/texel/gen/brush.py (between the
"# --- tables" and "# --- end of tables" lines): COS and HANN (integer
formulas a float32 board could round differently, so shipped as literals) and
the painting compensation COMP_K / COMP_LAM (gamma functions and a root
search a board does not have). tests/brush/test_paint.py checks every literal
against this script's formulas.

    .venv/bin/python tools/gen_brush_tables.py
"""
import math
import re
import textwrap
from pathlib import Path

import numpy as np
from scipy import optimize, special

PATH = Path(__file__).resolve().parents[1] / "device" / "texel" / "gen" / "brush.py"
N, HOP = 188, 47
GRID = 57                   # log-spaced shapes 0.05 .. 1000: 13.7 points per decade
K_LO, K_HI = 0.05, 1000.0


def cos_table():
    return [int(math.floor(16384 * math.cos(2 * math.pi * j / N) + 0.5)) for j in range(N)]


def hann_table():
    r = [int(math.floor(256 * math.cos(2 * math.pi * n / N) + 0.5)) for n in range(N // 2)]
    return [256 - x for x in r] + [256 + x for x in r]


def log2_table():
    """LOG2[i] = round(log2(1 + i/256) * 2^24), i = 0 .. 256: Q24 octaves."""
    return [int(math.floor(math.log2(1 + i / 256) * (1 << 24) + 0.5)) for i in range(257)]


LOG2_LN2_Q24 = int(math.floor(math.log2(math.log(2)) * (1 << 24) + 0.5))


def smoothing():
    """c_d: how much of window j's magnitude a re-analysis of window j + d
    sees (one painted window of a constant 1, weighted by HANN and halved as
    paint() does, analysed with the periodic Hann window as
    host/texelpad/brush/transform.py does), and S2 = sum c_d^2: the variance
    factor of the analysed magnitude, a weighted sum of the windows' iid
    draws (sum c_d = 1: the mean is kept)."""
    ws = np.array(hann_table()) / 512.0
    wa = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(N) / N)
    x = np.zeros(N * 9)
    s0 = 4 * N
    x[s0:s0 + N] = ws / 2.0                # paint() halves the overlap-added sum
    c = np.array([(x[s0 + d * HOP:s0 + d * HOP + N] * wa).sum() / wa.sum()
                  for d in range(-4, 5)])
    return c, float((c ** 2).sum())


def cv(k):
    return math.sqrt(special.gamma(1 + 2 / k) / special.gamma(1 + 1 / k) ** 2 - 1)


def comp_tables():
    """For a shape k of the grid: the shape k' to draw each window's magnitude
    with so that the re-analysed magnitude (a c-weighted sum of draws) has
    k's coefficient of variation (CV(k') = CV(k) / sqrt(S2)), clamped to
    [K_LO, K_HI]; and lam' / lam, so that its mean is lam Gamma(1 + 1/k)."""
    _, s2 = smoothing()
    ks, lams = [], []
    for i in range(GRID):
        k = K_LO * (K_HI / K_LO) ** (i / (GRID - 1))
        target = cv(k) / math.sqrt(s2)
        if target >= cv(K_LO):
            kp = K_LO
        elif target <= cv(K_HI):
            kp = K_HI
        else:
            kp = optimize.brentq(lambda x: cv(x) - target, K_LO, K_HI, xtol=1e-12)
        ks.append(kp)
        lams.append(special.gamma(1 + 1 / k) / special.gamma(1 + 1 / kp))
    return ks, lams


def literal(name, vals, fmt=str):
    body = ", ".join(fmt(v) for v in vals)
    return name + " = (\n" + textwrap.fill(body, 96, initial_indent="    ",
                                            subsequent_indent="    ") + ")\n"


def block():
    c, s2 = smoothing()
    ks, lams = comp_tables()
    f = lambda v: repr(float("%.9g" % v))             # noqa: E731 - 9 digits: float32 and more
    return ("# --- tables (tools/gen_brush_tables.py writes them; tests/brush/test_paint.py\n"
            "# checks them against its formulas): literals, so every runtime has the same\n"
            "# numbers (a float32 board could round a cosine the other way; it has no gamma).\n"
            "# COS[j] = round(16384 cos(2 pi j / WINDOW)), Q14; COS[j + 94] = -COS[j].\n"
            + literal("COS", cos_table()) +
            "# HANN[n] = 256 - round(256 cos(2 pi n / WINDOW)) for n < 94 and 256 + the\n"
            "# same for n + 94: the periodic Hann window in Q9 (512 = 1.0), rounded in\n"
            "# pairs so the four windows over any sample sum to exactly 1024 (= 2.0):\n"
            "# overlap-add has no seams at all.\n"
            + literal("HANN", hann_table()) +
            "# The painting compensation (docs/brush.md, \"Painting\"): a re-analysed\n"
            "# window sees a weighted sum of the neighbouring windows' draws (weights\n"
            "# %s, sum of squares S2 = %.4f),\n"
            "# so each window draws with shape COMP_K and scale lam * COMP_LAM at the\n"
            "# brush's shape k (log-spaced grid of %d points, %g .. %g; linear in log k\n"
            "# between them): the analysed magnitude then has the brush's mean and\n"
            "# coefficient of variation.\n" % (" ".join("%.4f" % x for x in c if x > 1e-6), s2,
                                                GRID, K_LO, K_HI)
            + "COMP_GRID = %d\nCOMP_K_LO = %r\nCOMP_K_HI = %r\n" % (GRID, K_LO, K_HI)
            + literal("COMP_K", ks, f) + literal("COMP_LAM", lams, f)
            + "# LOG2[i] = round(log2(1 + i/256) 2^24), i = 0 .. 256 (the Weibull draws'\n"
            "# logarithms in Q24 octaves: magnitudes(); linear between entries, with the\n"
            "# 12-bit weight: within 4.1e-6 octave); LOG2_LN2 = round(log2(ln 2) 2^24).\n"
            + literal("LOG2", log2_table()) + "LOG2_LN2 = %d\n" % LOG2_LN2_Q24
            + "# --- end of tables\n")


def main():
    src = PATH.read_text()
    new, n = re.subn(r"# --- tables.*?# --- end of tables\n", lambda m: block(), src, flags=re.S)
    if n != 1:
        raise SystemExit("no '# --- tables' ... '# --- end of tables' block in %s" % PATH)
    PATH.write_text(new)
    print("wrote", PATH)


if __name__ == "__main__":
    main()

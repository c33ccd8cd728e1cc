#!/usr/bin/env python3
"""Regenerate the table literals of device/texel/gen/brush.py (between the
"# --- tables" and "# --- end of tables" lines): the integer tables (PHASE,
TW, HANN, LOG2: formulas a float32 board could round differently, so shipped
as literals) and the painting's compensation (LEAK, COMP_LK, COMP0_LK, LG1, LG2: gamma
functions, root searches and a seeded Monte Carlo a board does not have).
tests/brush/test_paint.py checks every literal against this script.

    .venv/bin/python tools/gen_brush_tables.py

The painting (docs/brush.md, "Painting"): each window draws its magnitudes
and phases independently, so a re-analysed window of the painted map reads,
at wavenumber k, the sum of many independent phasors - its own window's draw
at k, the three windows on each side that overlap it, and the Hann leak of
their neighbours k +- 1, k +- 2 (coupling()). Powers add (leak_kernel: the
deconvolution brush.leakage() solves), the distribution of the sum is what
the compensation tables correct (comp_waves: the draws' shape k' for the
shape a re-analysis fits). The windows' means (k = 0) have no phase:
a re-analysed mean is a weighted sum of the neighbours' means (smoothing(),
comp_mean).
"""
import math
import re
import textwrap
from pathlib import Path

import numpy as np
from scipy import optimize, special

PATH = Path(__file__).resolve().parents[1] / "device" / "texel" / "gen" / "brush.py"
N, HOP = 192, 48
PHASES = 256                # phases per turn: the low byte of a window's draw
GRID = 57                   # log-spaced shapes 0.05 .. 1000: 13.7 points per decade
K_LO, K_HI = 0.05, 1000.0
MC_SEED, MC_DRAWS = 20261126, 200000    # analysed_shapes' Monte Carlo (seeded: the same tables)


def phase_table():
    """PHASE[p] = round(16384 cos(2 pi p / 256)): Q14; sin is PHASE[(p - 64) & 255]."""
    return [int(math.floor(16384 * math.cos(2 * math.pi * p / PHASES) + 0.5))
            for p in range(PHASES)]


def twiddle_table():
    """TW[j] = round(4096 cos(2 pi j / 192)): the FFT's twiddles in Q12 (sin is
    TW[(j + 144) % 192]). Q12, not more: an FFT value (< 2^19, brush.fill)
    times a twiddle stays below 2^31 on a 32-bit board."""
    return [int(math.floor(4096 * math.cos(2 * math.pi * j / N) + 0.5)) for j in range(N)]


def hann_table():
    r = [int(math.floor(256 * math.cos(2 * math.pi * n / N) + 0.5)) for n in range(N // 2)]
    return [256 - x for x in r] + [256 + x for x in r]


def log2_table():
    """LOG2[i] = round(log2(1 + i/256) * 2^24), i = 0 .. 256: Q24 octaves."""
    return [int(math.floor(math.log2(1 + i / 256) * (1 << 24) + 0.5)) for i in range(257)]


LOG2_LN2_Q24 = int(math.floor(math.log2(math.log(2)) * (1 << 24) + 0.5))


def _paint_one(kp, phi):
    """One painted window (at 4 N) holding cos(2 pi kp n / N + phi), weighted
    by HANN and halved as brush.paint does."""
    ws = np.array(hann_table()) / 512.0
    y = np.zeros(N * 9)
    y[4 * N:5 * N] = np.cos(2 * np.pi * kp * np.arange(N) / N + phi) * ws / 2.0
    return y


def _analyse(y, d, k):
    """The magnitude transform (host/texelpad/brush/transform.py) of the
    window d hops from the painted one, at wavenumber k (complex, 2 X / W)."""
    wa = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(N) / N)
    seg = y[4 * N + d * HOP:4 * N + d * HOP + N]
    return 2.0 / wa.sum() * (seg * wa * np.exp(-2j * np.pi * k * np.arange(N) / N)).sum()


def coupling(k=40):
    """b[d, dk]^2: the power a re-analysis at wavenumber k of the window d
    hops away reads from a unit wave painted at k + dk with a uniformly random
    phase (d = -3 .. 3, dk = -3 .. 3; a mid-band k: the kernel is the same
    everywhere but near 0 and the Nyquist). The phase average of |A e^(i phi)
    + B e^(-i phi)|^2 is |A|^2 + |B|^2."""
    g = np.zeros((7, 7))
    for d in range(-3, 4):
        for dk in range(-3, 4):
            x0 = _analyse(_paint_one(k + dk, 0.0), d, k)
            x9 = _analyse(_paint_one(k + dk, math.pi / 2), d, k)
            a, b = (x0 - 1j * x9) / 2, (x0 + 1j * x9) / 2
            g[d + 3, dk + 3] = abs(a) ** 2 + abs(b) ** 2
    return g


def leak_kernel():
    """(gain, [g0, g1, g2, g3]): the total power a re-analysis reads from a
    unit painted wave (all windows and neighbours) and the share of it each
    wavenumber distance 0 .. 3 carries (symmetric; the shares sum to 1 over
    dk = -3 .. 3)."""
    g = coupling().sum(axis=0)
    gain = float(g.sum())
    return gain, [float(g[3 + i] / gain) for i in range(4)]


def leak_q14(shares):
    return [int(math.floor(16384 / shares[0] + 0.5))] + \
        [int(math.floor(16384 * x / shares[0] + 0.5)) for x in shares[1:]]


def smoothing():
    """c_d: how much of window j's mean a re-analysis of window j + d sees
    (one painted window of a constant 1, weighted by HANN and halved as
    paint() does, analysed with the periodic Hann window), and S2 = sum c_d^2
    (sum c_d = 1: the mean is kept)."""
    y = _paint_one(0, 0.0)
    c = np.array([_analyse(y, d, 0).real / 2.0 for d in range(-4, 5)])
    return c, float((c ** 2).sum())


def cv(k):
    return math.sqrt(special.gamma(1 + 2 / k) / special.gamma(1 + 1 / k) ** 2 - 1)


def grid():
    return [K_LO * (K_HI / K_LO) ** (i / (GRID - 1)) for i in range(GRID)]


def _invert(fn, target, lo=K_LO, hi=K_HI):
    """The shape x in [lo, hi] where the decreasing fn(x) = target (clamped)."""
    if target >= fn(lo):
        return lo
    if target <= fn(hi):
        return hi
    return optimize.brentq(lambda x: fn(x) - target, lo, hi, xtol=1e-10)


def comp_mean():
    """The mean's compensation (k = 0): ln k', the shape whose weighted sum
    of draws (smoothing) has shape k's coefficient of variation (CV(k') =
    CV(k) / sqrt(S2)); the scale keeps the mean lam Gamma(1 + 1/k) on the
    board (brush.compensated: LG1 at k and at k')."""
    _, s2 = smoothing()
    return [math.log(_invert(cv, cv(k) / math.sqrt(s2))) for k in grid()]


def weibull_shape_mle(x):
    """The maximum-likelihood Weibull shape of samples x > 0 (loc 0; the
    fit texelpad.brush.fits makes): the root of sum x^k ln x / sum x^k - 1/k
    = mean ln x, in log k."""
    lx = np.log(x)
    lx = lx - lx.max()                      # scale-free: the shape does not see it
    mlx = lx.mean()

    def f(lk):
        k = math.exp(lk)
        w = np.exp(k * lx)
        return (w * lx).sum() / w.sum() - 1.0 / k - mlx
    return math.exp(optimize.brentq(f, math.log(1e-3), math.log(1e4), xtol=1e-9))


def analysed_fits():
    """The Weibull fit (maximum likelihood, as a brush is fitted: shape,
    scale) of a re-analysed magnitude when every window draws Weibull(k', 1)
    with a uniform phase: |sum b_i m_i e^(i phi_i)| over the couplings b
    (coupling(); those above 1e-5 of the power), by a seeded Monte Carlo at
    the grid's shapes k'; the shape increasing in k' (checked)."""
    b = np.sqrt(coupling().ravel())
    b = b[b ** 2 > 1e-5 * (b ** 2).sum()]
    rng = np.random.default_rng(MC_SEED)
    u = rng.random((MC_DRAWS, b.size))
    ph = np.exp(2j * np.pi * rng.random((MC_DRAWS, b.size)))
    e = -np.log(u)                          # Weibull(k') = e^(1/k'): common numbers
    shapes, scales = [], []
    for kp in grid():
        r = np.abs(((e ** (1.0 / kp)) * ph) @ b)
        c = weibull_shape_mle(r)
        shapes.append(c)
        scales.append(float(np.mean(r ** c) ** (1.0 / c)))
    if any(shapes[i + 1] < shapes[i] for i in range(len(shapes) - 1)):
        raise SystemExit("analysed shape is not monotone in k': %r" % shapes)
    return shapes, scales


def comp_waves():
    """The waves' compensation (k >= 1): ln k', the draws' shape whose
    independent-phase overlap re-analyses with shape k (interpolating the
    analysed shape in log k'; clamped: shapes above what any k' reaches read
    back at that shape, about a Rayleigh's - docs/brush.md); and, on the same
    grid of k', log2(1 / S(k')) with S the analysed scale of draws of scale
    1: the factor on the scale so a flat brush re-analyses to its own scale
    (brush.leakage deconvolves the neighbours with LEAK)."""
    g = grid()
    lg = np.log(g)
    ash, asc = analysed_fits()
    out = []
    for k in g:
        if k <= ash[0]:
            out.append(lg[0])
        elif k >= ash[-1]:
            out.append(lg[-1])
        else:
            out.append(float(np.interp(math.log(k), np.log(ash), lg)))
    return out, [-math.log2(x) for x in asc], ash


def lgamma_table():
    """LG1[i] = ln Gamma(1 + 1/k_i) at the grid's shapes: a Weibull's mean is
    lam Gamma(1 + 1/k) (smooth in log k: linear between grid points)."""
    g = np.array(grid())
    return [float(x) for x in special.gammaln(1 + 1 / g)]


def literal(name, vals, fmt=str):
    body = ", ".join(fmt(v) for v in vals)
    return name + " = (\n" + textwrap.fill(body, 96, initial_indent="    ",
                                            subsequent_indent="    ") + ")\n"


def _f(v):
    return repr(float("%.9g" % v))                  # 9 digits: float32 and more


def block():
    c, s2 = smoothing()
    gain, shares = leak_kernel()
    lk0 = comp_mean()
    lk, ls, ash = comp_waves()
    lg1 = lgamma_table()
    return ("# --- tables (tools/gen_brush_tables.py writes them; tests/brush/test_paint.py\n"
            "# checks them against its formulas): literals, so every runtime has the same\n"
            "# numbers (a float32 board could round a cosine the other way; it has no gamma).\n"
            "# PHASE[p] = round(16384 cos(2 pi p / 256)), Q14: a window's phase p (its\n"
            "# draw's low byte); sin is PHASE[(p - 64) & 255].\n"
            + literal("PHASE", phase_table()) +
            "# TW[j] = round(4096 cos(2 pi j / 192)), Q12: the FFT's twiddles; sin is\n"
            "# TW[(j + 144) % 192].\n"
            + literal("TW", twiddle_table()) +
            "# HANN[n] = 256 - round(256 cos(2 pi n / WINDOW)) for n < 96 and 256 + the\n"
            "# same for n + 96: the periodic Hann window in Q9 (512 = 1.0), rounded in\n"
            "# pairs so the four windows over any sample sum to exactly 1024 (= 2.0):\n"
            "# overlap-add has no seams at all.\n"
            + literal("HANN", hann_table()) +
            "# The painting's compensation (docs/brush.md, \"Painting\"; the derivation is\n"
            "# in tools/gen_brush_tables.py). Waves (k >= 1): a re-analysed window reads\n"
            "# LEAK_GAIN = %.5f of a unit wave's power painted with independent\n"
            "# phases, shared over wavenumber distances 0, 1, 2, 3 as LEAK (leakage()\n"
            "# deconvolves it); COMP_LK[i] = ln k', the shape to draw for the grid's\n"
            "# shape k_i (log-spaced, %d points, %g .. %g; linear in ln k between them)\n"
            "# so the re-analysed magnitude fits (maximum likelihood) with shape k_i - it\n"
            "# reaches %.3f at most (k' = %g), about a Rayleigh's: sharper brushes read\n"
            "# back at that shape; COMP_LS[i] = log2(1 / S) at k' = k_i, S the fitted\n"
            "# scale of a re-analysis of draws of scale 1 (a seeded Monte Carlo). The\n"
            "# mean (k = 0) is a weighted sum of neighbouring windows' draws (weights\n"
            "# %s;\n"
            "# S2 = %.4f): COMP0_LK keeps its coefficient of variation, LG1 = ln Gamma(1 + 1/k)\n"
            "# on the grid its mean (compensated()).\n"
            % (gain, GRID, K_LO, K_HI, ash[-1], K_HI,
               " ".join("%.4f" % x for x in c if x > 1e-6), s2)
            + "COMP_GRID = %d\nCOMP_K_LO = %r\nCOMP_K_HI = %r\n" % (GRID, K_LO, K_HI)
            + "LEAK_GAIN = %s\n" % _f(gain)
            + "LEAK = (%s)\n" % ", ".join(_f(x) for x in shares)
            + "# LEAK_Q14 = round(16384 / LEAK[0]), round(16384 LEAK[d] / LEAK[0]) for d = 1 .. 3\n"
            "# (leakage()'s integer sweeps)\n"
            + "LEAK_Q14 = (%s)\n" % ", ".join(str(x) for x in leak_q14(shares))
            + literal("COMP_LK", lk, _f) + literal("COMP_LS", ls, _f)
            + literal("COMP0_LK", lk0, _f) + literal("LG1", lg1, _f)
            + "# LOG2[i] = round(log2(1 + i/256) 2^24), i = 0 .. 256 (the Weibull draws'\n"
            "# logarithms in Q24 octaves: draws(); linear between entries, with the\n"
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

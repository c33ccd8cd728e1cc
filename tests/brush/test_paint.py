"""Painting a brush (device/texel/gen/brush.py; seed 002): the tables are
their formulas, overlap-add has no seams, the same brush and seed give the
same map on CPython (pure Python and numpy), the MicroPython unix port (pure
Python and viper), the float32 ulab build and CircuitPython within a stated
tolerance, a brush region is refused by key path and allocates only its
region, and a painted brush re-analysed has the brush's statistics."""
from __future__ import annotations

import json
import math
import sys
from array import array

import numpy as np
import pytest

import texel.runtime.scene as S
from texel.gen import brush as B
from texelpad import toolchain

from support import mpy

sys.path.insert(0, str(mpy.ROOT / "tools"))
import gen_brush_tables as T  # noqa: E402

DISPLAY = {"positions": 19200, "dx_um": 5.3}
# one PWM step of the TPaD boards' carrier in u16 units: a 34 kHz carrier
# from a 125 MHz clock has 3,676 counts (texel.runtime.duty), 65535 / 3676
PWM_STEP_U16 = 65535 / 3676


def brushes():
    """Brushes across the ranges: shapes 0.3 .. 200, scales up to full
    range, an inverted (friction) range, a single line, all-zero."""
    rng = np.random.default_rng(5)
    out = []
    for i in range(4):
        k = list(np.exp(rng.uniform(np.log(0.3), np.log(200), B.K)))
        lam = [float(rng.uniform(0.2, 0.8))] + list(rng.uniform(0, 0.08, B.K - 1) *
                                                     rng.uniform(0, 1) ** 2)
        out.append({"k": [float(x) for x in k], "lam": [float(x) for x in lam]})
    out.append({"k": [2.0] * B.K, "lam": [0.9] + [0.02] * (B.K - 1), "range": [1.2, 0.3]})
    line = [0.0] * B.K
    line[10] = 0.2
    out.append({"k": [1000.0] * B.K, "lam": [0.5] + line[1:]})
    out.append({"k": [1.0] * B.K, "lam": [0.0] * B.K})
    return out


def test_the_tables_are_their_formulas():
    assert list(B.COS) == T.cos_table() and list(B.HANN) == T.hann_table()
    ks, lams = T.comp_tables()
    assert B.COMP_GRID == T.GRID and (B.COMP_K_LO, B.COMP_K_HI) == (T.K_LO, T.K_HI)
    assert np.allclose(B.COMP_K, ks, rtol=1e-8) and np.allclose(B.COMP_LAM, lams, rtol=1e-8)
    # the four windows over any sample sum to 1024 exactly: no seam anywhere
    assert {sum(B.HANN[(n + j * B.HOP) % B.WINDOW] for j in range(4))
            for n in range(B.WINDOW)} == {1024}
    assert B.WINDOW == 4 * B.HOP and B.K == B.WINDOW // 2 + 1


def test_a_constant_brush_paints_a_constant_without_seams():
    """k = 1000 at wavenumber 0 only (each window's mean drawn within
    +-0.3 % of 0.5 once compensated): the map is the mean everywhere, region
    edges included - overlap-add is whole, no dip between windows."""
    b = B.validate({"k": [1000.0] * B.K, "lam": [0.5] + [0.0] * (B.K - 1)})
    m = np.array(B.paint(b, 3, 5000), float) / 65535
    assert np.ptp(m) <= 0.006 and abs(m.mean() - 0.5) < 0.003
    assert abs(m[:100].mean() - m[2000:3000].mean()) < 0.003
    assert abs(m[-100:].mean() - m[2000:3000].mean()) < 0.003


def test_a_single_line_is_one_continuous_wave():
    """Wavenumber 10 only, constant magnitude: a sinusoid of 10 cycles per
    window (10.04 c/mm) whose amplitude is the brush's, without a phase jump
    at any window boundary (the spectrum has one line)."""
    lam = [0.5] + [0.0] * (B.K - 1)
    lam[10] = 0.25
    b = B.validate({"k": [1000.0] * B.K, "lam": lam})
    m = np.array(B.paint(b, 9, 188 * 40), float) / 65535
    spec = np.abs(np.fft.rfft((m - m.mean()) * np.hanning(len(m))))
    f = np.fft.rfftfreq(len(m), 0.0053)
    peak = f[np.argmax(spec)]
    assert abs(peak - 10 / (188 * 0.0053)) < 0.05
    # amplitude: half the peak-to-peak away from the edges
    mid = m[1000:-1000]
    assert abs((mid.max() - mid.min()) / 2 - 0.25) < 0.01
    # all energy within +-1 c/mm of the line: one continuous wave
    near = np.abs(f - peak) < 1.0
    assert (spec[near] ** 2).sum() / (spec ** 2).sum() > 0.99


def test_cpython_pure_python_and_numpy_paint_the_same_integers():
    for i, b in enumerate(brushes()):
        v = B.validate(b)
        assert B.paint(v, i, 2000, frame=B.frame_py) == B.paint(v, i, 2000,
                                                                 frame=B.frame_numpy())


RUNTIMES = [None, "micropython-ulab-f32", "circuitpython"]


@pytest.mark.parametrize("runtime", RUNTIMES, ids=["unix", "ulab-f32", "circuitpython"])
def test_the_board_paints_what_the_host_paints(runtime, capsys):
    """Every brush and seed on a real interpreter, the Python loops and (where
    the port has it) the viper ones (brush_viper.py: every per-window step;
    and its frame alone), against CPython. The integer synthesis is identical;
    only the magnitudes' float draws can differ (a float32 or 30-bit float
    log and power): the bound is one PWM step (measured: see the output)."""
    exe = None
    if runtime is not None:
        exe = toolchain.interpreter(runtime)
        if exe is None:
            pytest.skip("%s is not in ../shared/instruments" % runtime)
    bs = brushes()
    n = 1500
    code = """
import json
from texel.gen import brush as B
for i, b in enumerate(%r):
    v = B.validate(b)
    print(json.dumps(["%%d-py" %% i, list(B.paint(v, 1000 + i, %d, viper=False))]))
    if B.frame_viper() is not None:
        print(json.dumps(["%%d-viper" %% i, list(B.paint(v, 1000 + i, %d))]))
        # and viper's frame alone on the Python path
        print(json.dumps(["%%d-frame" %% i, list(B.paint(v, 1000 + i, %d, viper=False,
                                                          frame=B.frame_viper()))]))
""" % (bs, n, n, n)
    got = dict(json.loads(line) for line in
               mpy.run(code, exe=exe, timeout=900).strip().splitlines())
    worst = 0
    for key, m in got.items():
        i = int(key.split("-")[0])
        want = np.array(B.paint(B.validate(bs[i]), 1000 + i, n), dtype=np.int64)
        worst = max(worst, int(np.abs(np.array(m) - want).max()))
    names = {k.split("-")[1] for k in got}
    with capsys.disabled():
        print("\nbrush paint on %s (%s): worst difference from CPython %d u16 = %.2f PWM step"
              % (runtime or "the unix port", "+".join(sorted(names)), worst,
                 worst / PWM_STEP_U16))
    assert worst <= PWM_STEP_U16
    if runtime is None:
        assert names == {"py", "viper", "frame"} and worst == 0


@pytest.mark.parametrize("bad, fragment", [
    ({"k": [2.0] * 94, "lam": [0.1] * 95}, "brush.k: expected 95 numbers"),
    ({"k": [2.0] * 95, "lam": [0.1] * 94 + [float("nan")]}, "brush.lam[94]: nan is not finite"),
    ({"k": [2.0] * 95, "lam": [-0.1] + [0.1] * 94}, "brush.lam[0]: -0.1 is outside"),
    ({"k": [0.0] + [2.0] * 94, "lam": [0.1] * 95}, "brush.k[0]: 0.0 is outside"),
    ({"k": [2.0] * 10 ** 5, "lam": [0.1] * 95}, "brush.k: expected 95 numbers"),
    ({"k": [2.0] * 95, "lam": [0.1] * 95, "range": [1, 1]}, "brush.range: a0 and a1 must differ"),
    ({"k": [2.0] * 95, "lam": [0.1] * 95, "window": 200}, "brush.window: this display paints"),
    ({"k": [2.0] * 95, "lam": [0.1] * 95, "x": 1}, "brush: unknown key 'x'"),
    ({"k": "2", "lam": [0.1] * 95}, "brush.k: expected a list"),
    ([1, 2], "brush: expected an object"),
])
def test_a_bad_brush_region_is_refused_by_key_path(bad, fragment):
    scene = {"regions": [{"start_mm": 0, "end_mm": 10,
                          "texture": {"kind": "brush", "brush": bad, "seed": 1}}]}
    with pytest.raises(ValueError) as e:
        S.validate(scene, DISPLAY)
    assert "regions[0].texture." + fragment in str(e.value)


def test_a_brush_region_allocates_only_its_region():
    """On the unix port: building a scene with a 50.88 mm brush region keeps
    what a reference region of the same length keeps (its 2-byte-a-sample
    buffer and the scene's table) plus the scene's own copy of the brush -
    its 190 numbers (2,304 bytes measured here: boxed floats in two lists) -
    and passes through at most a window's work arrays and the brush's
    lists more: never a second map (measured with gc.mem_alloc around
    build); the refresh then reads it with the heap locked, as every region."""
    b = brushes()[0]
    code = """
import gc, json
import texel.runtime.scene as S
from texel.gen import brush as B
d = {"positions": 19200, "dx_um": 5.3}
def kept(tex):
    c = S.validate({"regions": [{"start_mm": 0, "end_mm": 50.88, "texture": tex}]}, d)
    gc.collect(); gc.collect()
    a0 = gc.mem_alloc()
    sc = S.build(c, d)
    a1 = gc.mem_alloc()
    gc.collect()
    return sc, a1 - a0, gc.mem_alloc() - a0
# first builds import modules and make tables (once per boot, not per region)
kept({"kind": "reference", "name": "4sin"})
kept({"kind": "brush", "brush": %r, "seed": 3})
_, ref_peak, ref_kept = kept({"kind": "reference", "name": "4sin"})
sc, _, kept_b = kept({"kind": "brush", "brush": %r, "seed": 4})
import micropython
micropython.heap_lock()
s = 0
for p in range(0, 9600, 7):
    s += sc.amp(p)
micropython.heap_unlock()
print(json.dumps([ref_kept, kept_b, s > 0]))
""" % (b, b)
    ref_kept, kept, ok = mpy.run_json(code)
    assert ok and ref_kept >= 2 * 9600
    assert 0 <= kept - ref_kept <= 190 * 16 + 2 * 95 * 8, (kept, ref_kept)
    # working memory: a full-screen brush region (38,400 bytes) builds in a
    # 256 KB heap (the unix port's imports leave ~190 KB of it; the draws'
    # floats are garbage, collected as they go). The emulated Pico builds one
    # too (tests/host/test_emulated_pico.py).
    code = """
import texel.runtime.scene as S
d = {"positions": 19200, "dx_um": 5.3}
c = S.validate({"regions": [{"start_mm": 0, "end_mm": 101.76,
                             "texture": {"kind": "brush", "brush": %r, "seed": 4}}]}, d)
sc = S.build(c, d)
print(sc.amp(100) >= 0)
""" % (b,)
    assert mpy.run(code, heapsize="256k").strip() == "True"


def test_a_painted_brush_reanalysed_has_the_brush_statistics():
    """Isolated wavenumbers (every 4th; a neighbour leaks half its magnitude
    into the Hann analysis, docs/brush.md): 10 full-screen paintings, each
    window re-analysed, Weibull fitted by maximum likelihood (scipy.stats):
    the scale within 5 %, the shape within 12 % of the brush's - the
    compensation matches mean and coefficient of variation, not the whole
    distribution (the analysed magnitude is a weighted sum of draws)."""
    from scipy import stats
    N, H = B.WINDOW, B.HOP
    w = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(N) / N)
    for kt in (2.0, 5.0, 12.0):
        lam = [0.5] + [0.04 if i % 4 == 0 and i > 4 else 0.0 for i in range(1, B.K)]
        b = B.validate({"k": [1000.0] + [kt] * (B.K - 1), "lam": lam})
        rows = []
        for s in range(10):
            x = np.array(B.paint(b, s, 19200), float) / 65535
            fr = np.stack([x[j * H:j * H + N] * w for j in range((len(x) - N) // H + 1)])
            rows.append(2 * np.abs(np.fft.rfft(fr, axis=1))[:, :B.K] / w.sum())
        m = np.concatenate(rows)
        for k in (8, 24, 52, 88):
            c, _, scale = stats.weibull_min.fit(m[:, k], floc=0)
            assert abs(scale / 0.04 - 1) < 0.05, (kt, k, scale)
            assert abs(c / kt - 1) < 0.12, (kt, k, c)


def test_the_integer_log2_is_within_its_stated_bound():
    """brush.log2_q24 (the Weibull draws' logarithms): within 4.1e-6 octave
    of log2 over every v < 5,000 and 20,000 random v < 2^30."""
    rng = np.random.default_rng(1)
    vs = list(range(1, 5000)) + [int(x) for x in rng.integers(1, 2 ** 30 - 1, 20000)]
    worst = max(abs(B.log2_q24(v) / 2 ** 24 - math.log2(v)) for v in vs)
    assert worst < 4.1e-6, worst

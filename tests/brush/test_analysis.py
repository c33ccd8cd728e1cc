"""The Tactile Paintbrush's analysis (texelpad.brush: transform, fits,
swipes, compare; seed 002, issue 12 items 1-2): the transform's units and
geometry, recordings and their resampling, the per-wavenumber fits (a round
trip from known Weibull parameters within stated confidence bounds, model
selection, Gaussian noise, degenerate maps), the swipe model, the paper's
comparison on a tiny set, and the benchmark's report. Seeded; nothing here
asserts on time.

Confidence bounds (test_weibull_round_trip, test_white_noise_gives_rayleigh):
the asymptotic standard errors of the Weibull MLE from the inverse Fisher
information per observation (for shape k and scale lam,
    I = [[((1 - g)^2 + pi^2/6) / k^2, -(1 - g) / lam], [-(1 - g) / lam, k^2 / lam^2]],
g = Euler's gamma; det I = pi^2 / (6 lam^2)), so with n independent values

    SE(k)   = k * sqrt(6 / pi^2 / n)                        (0.780 k / sqrt n)
    SE(lam) = lam / k * sqrt((1 + 6 (1 - g)^2 / pi^2) / n)  (1.053 lam / (k sqrt n)).

Each of the 2 x 97 estimates must lie within Z_BOUND = 4.6 standard errors
(Bonferroni over 194 estimates at a family-wise 1e-3: z = 4.56, rounded up),
and the standardised errors must look standard normal as a set (mean within
4 standard errors of the mean, 4 / sqrt 97 = 0.41, of 0; SD within 0.75 ..
1.25, i.e. 3.5 times the SD's own standard error 1 / sqrt(2 * 96) = 0.072).
The windows of a map overlap (4 per sample), so its magnitudes are not
independent: for a map the SE is inflated by sqrt(1 + 2 sum_j rho_j^2) = 1.39,
rho_j the correlation of a white-noise Fourier coefficient between windows j
hops apart (0.659, 0.167, 0.0075: periodic Hann, 75 % overlap), rho_j^2 the
correlation of their squared magnitudes (complex Gaussian), so 1 + 2 sum
rho_j^2 is the variance inflation of a mean of them - computed in the test.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from texel.gen import brush as GB
from texel.gen.params import DX_MM
from texelpad.brush import compare as C
from texelpad.brush import fits as F
from texelpad.brush import swipes as S
from texelpad.brush import transform as T

K = GB.K
Z_BOUND = 4.6
EULER = 0.5772156649015329


def se_k(k, n):
    return k * math.sqrt(6.0 / math.pi ** 2 / n)


def se_lam(k, lam, n):
    return lam / k * math.sqrt((1.0 + 6.0 * (1.0 - EULER) ** 2 / math.pi ** 2) / n)


def overlap_inflation() -> float:
    w = T.window()
    rho = [float(np.sum(w[:GB.WINDOW - j * GB.HOP] * w[j * GB.HOP:]) / np.sum(w * w))
           for j in (1, 2, 3)]
    return math.sqrt(1.0 + 2.0 * sum(r * r for r in rho))


# --- the transform ----------------------------------------------------------------------

def test_geometry_is_brush_py():
    assert (T.WINDOW, T.HOP, T.K) == (GB.WINDOW, GB.HOP, GB.K) == (192, 48, 97)
    assert GB.NYQ == GB.K - 1 == GB.WINDOW // 2
    assert T.WINDOW_MM == pytest.approx(1.0176) and T.HOP_MM == pytest.approx(0.2544)
    w = T.window()
    assert w.sum() == pytest.approx(GB.WINDOW / 2, abs=1e-12)
    # periodic Hann, 4 windows a hop apart overlap-add to exactly 2 at every sample
    acc = np.zeros(GB.WINDOW + 3 * GB.HOP)
    for j in range(4):
        acc[j * GB.HOP: j * GB.HOP + GB.WINDOW] += w
    assert np.allclose(acc[3 * GB.HOP: GB.WINDOW], 2.0, atol=1e-12)
    assert T.wavelengths_mm()[1] == pytest.approx(1.0176) and math.isinf(T.wavelengths_mm()[0])
    assert T.wavelengths_mm()[GB.NYQ] == pytest.approx(2 * DX_MM)       # 10.6 um


@pytest.mark.parametrize("k", [1, 2, 7, 50, GB.NYQ - 1])
@pytest.mark.parametrize("phase", [0.0, 0.4, 2.0])
def test_a_sinusoid_of_amplitude_a_gives_m_k_a(k, phase):
    a = 0.3
    n = np.arange(GB.WINDOW * 4)
    x = a * np.sin(2 * math.pi * k * n / GB.WINDOW + phase)
    m = T.stft_magnitudes(x)
    assert m.shape == (T.n_windows(x.size), K)
    assert np.allclose(m[:, k], a, atol=1e-12)
    others = np.delete(m, [k - 1, k, k + 1], axis=1)       # the Hann main lobe is 3 bins
    assert others.max() < 1e-12
    if 2 <= k <= GB.NYQ - 2:                                # the lobe: half amplitude beside
        assert np.allclose(m[:, [k - 1, k + 1]], a / 2, atol=1e-12)


def test_a_constant_gives_m_0_and_leaks_into_m_1():
    """m_0 = c; the periodic Hann's spectrum has bins -1, 0, 1 (w = 1/2 -
    (e^+ + e^-)/4), so a constant c also gives m_1 = 2 (c W / 2) / W = c:
    wavenumber 1 carries the mean (seed 002: "the first two coefficients ...
    are poorly fit with a Rayleigh distribution"). Nothing above k = 1."""
    for c in (0.5, 0.03, 1.0):
        m = T.stft_magnitudes(np.full(1000, c))
        assert np.allclose(m[:, 0], c, rtol=1e-13)
        assert np.allclose(m[:, 1], c, rtol=1e-13)
        assert m[:, 2:].max() < 1e-15
    assert T.stft_magnitudes(np.zeros(500)).max() == 0.0


def test_the_nyquist_bin_is_real():
    """k = NYQ (96): the sampled sinusoid is A cos(phi) (-1)^n, so m_NYQ = 2 A |cos phi|."""
    n = np.arange(GB.WINDOW * 2)
    for phi in (0.0, 0.7, math.pi / 2):
        m = T.stft_magnitudes(0.2 * np.cos(math.pi * n + phi))
        assert np.allclose(m[:, GB.NYQ], 2 * 0.2 * abs(math.cos(phi)), atol=1e-12)


def test_parseval_per_window():
    """sum (x w)^2 = (1/N) sum |X|^2 over all N bins; in magnitudes:
    (W^2 / N) (m_0^2 + 1/2 sum_{1..NYQ-1} m_k^2 + 1/4 m_NYQ^2)."""
    rng = np.random.default_rng(5)
    x = rng.normal(0.4, 0.2, 2000)
    m = T.stft_magnitudes(x)
    w, N = T.window(), GB.WINDOW
    W = w.sum()
    for i in range(m.shape[0]):
        seg = x[i * GB.HOP: i * GB.HOP + N] * w
        rhs = W * W / N * (m[i, 0] ** 2 + 0.5 * np.sum(m[i, 1:GB.NYQ] ** 2)
                           + 0.25 * m[i, GB.NYQ] ** 2)
        assert np.sum(seg * seg) == pytest.approx(rhs, rel=1e-12)


def test_windows_and_the_tail():
    rng = np.random.default_rng(1)
    tail = 10
    x = rng.random(GB.WINDOW + 3 * GB.HOP + tail)
    m = T.stft_magnitudes(x)
    assert m.shape == (4, K) and T.n_windows(x.size) == 4 and T.n_windows(GB.WINDOW - 1) == 0
    # window 2 is samples 2 HOP .. 2 HOP + WINDOW - 1
    X = np.fft.rfft(x[2 * GB.HOP: 2 * GB.HOP + GB.WINDOW] * T.window())
    W = T.window().sum()
    assert m[2, 0] == pytest.approx(abs(X[0]) / W)
    assert np.allclose(m[2, 1:], 2 * np.abs(X[1:]) / W)
    # the tail (fewer than HOP samples after the last whole window) is not analysed
    y = x.copy()
    y[-tail:] = 99.0
    assert np.array_equal(T.stft_magnitudes(y), m)
    assert T.stft_magnitudes(x[:GB.WINDOW]).shape == (1, K)


@pytest.mark.parametrize("bad, match", [
    (np.zeros(GB.WINDOW - 1), "less than one window"),
    (np.r_[np.zeros(300), np.nan, np.zeros(10)], "sample 300 is nan"),
    (np.r_[np.zeros(300), np.inf], "non-finite"),
    (np.zeros((2, 300)), "1-D"),
])
def test_the_transform_refuses(bad, match):
    with pytest.raises(ValueError, match=match):
        T.stft_magnitudes(bad)


# --- recordings -------------------------------------------------------------------------

def test_resampling_an_uneven_unsorted_recording():
    """A tribometer-like recording (3.86 um encoder steps, jittered, shuffled,
    some positions repeated) of f(p) = 0.5 + 0.3 sin(2 pi 2.5 p) comes back on
    the 5.3 um grid from its first position; linear interpolation's error is
    at most h^2/8 max|f''| = (6e-3 mm)^2 / 8 * 0.3 (2 pi 2.5)^2 = 3.3e-4."""
    rng = np.random.default_rng(3)
    p = np.arange(0.0, 3.0, 0.00386) + rng.uniform(-0.001, 0.001, 778)
    p[0] = 0.0
    f = 0.5 + 0.3 * np.sin(2 * math.pi * 2.5 * p)
    p = np.r_[p, p[100:110]]          # repeats: the same position sampled twice
    f = np.r_[f, f[100:110]]
    order = rng.permutation(p.size)
    y = T.resample(p[order], f[order])
    grid = p.min() + np.arange(y.size) * DX_MM
    assert y.size == int(math.floor((p.max() - p.min()) / DX_MM)) + 1
    assert np.abs(y - (0.5 + 0.3 * np.sin(2 * math.pi * 2.5 * grid))).max() < 3.3e-4
    # a linear function is interpolated exactly, whatever the order
    lin = T.resample(p[order], 2.0 * p[order] + 1.0)
    assert np.allclose(lin, 2.0 * grid + 1.0, atol=1e-12)


def test_repeated_positions_are_averaged():
    p = np.r_[0.0, 0.0, np.arange(1, 200) * 0.0053]
    f = np.r_[1.0, 3.0, np.zeros(199)]
    y = T.resample(p, f)
    assert y[0] == pytest.approx(2.0) and y.size == 200


@pytest.mark.parametrize("p, f, match", [
    ([0.0, np.nan, 2.0], [0.0, 0.0, 0.0], "position of row 1 is nan"),
    ([0.0, 1.0, 2.0], [0.0, np.inf, 0.0], "friction of row 1 is inf"),
    ([0.0, 0.5], [0.0, 0.0], "spans 0.5 mm"),
    ([1.0] * 400, [0.0] * 400, "spans 0 mm"),
    ([0.0, 1.0], [0.0], "one length"),
    ([], [], "no rows"),
    ([1e13, 1e13 + 2.0], [0.0, 1.0], "too large|longest map"),
    ([0.0, 10000.0], [0.0, 1.0], "longest map"),
])
def test_resample_refuses(p, f, match):
    with pytest.raises(ValueError, match=match):
        T.resample(p, f)
    with pytest.raises(ValueError, match="dx_um"):
        T.resample([0.0, 2.0], [0.0, 1.0], dx_um=0.0)


def test_read_recording(tmp_path):
    path = tmp_path / "rec.csv"
    rows = ["# tribometer export", "position_mm,friction"] + [
        "%.6f,%.6f" % (i * 0.005, 0.5 + 0.1 * math.sin(i / 7)) for i in range(300)]
    rows.insert(5, "")
    path.write_text("\n".join(rows) + "\n")
    p, f = T.read_recording(path)
    assert p.size == f.size == 300 and p[1] == pytest.approx(0.005) and f[0] == pytest.approx(0.5)
    y = T.resample(p, f)
    assert T.stft_magnitudes(y).shape[1] == K
    # extra columns after the second are ignored when the header has them too
    (tmp_path / "wide.csv").write_text("pos,mu,normal_N\n0,0.5,1.0\n1,0.6,1.1\n")
    assert T.read_recording(tmp_path / "wide.csv")[1].tolist() == [0.5, 0.6]
    # by name, in any order and with texelpad render's sample number first
    (tmp_path / "render.csv").write_text("sample,x_mm,friction\n0,0.0000,0.25\n1,0.0053,0.5\n")
    p, f = T.read_recording(tmp_path / "render.csv")
    assert p.tolist() == [0.0, 0.0053] and f.tolist() == [0.25, 0.5]
    (tmp_path / "tabs.csv").write_text("Friction\tnormal_N\tPosition_mm\n0.5\t1\t0\n0.6\t1\t2\n")
    p, f = T.read_recording(tmp_path / "tabs.csv")
    assert p.tolist() == [0.0, 2.0] and f.tolist() == [0.5, 0.6]
    (tmp_path / "latin1.csv").write_bytes(b"position_mm,friction\n0,0.5\xff\n")
    with pytest.raises(ValueError, match="latin1.csv is not UTF-8"):
        T.read_recording(tmp_path / "latin1.csv")


@pytest.mark.parametrize("text, match", [
    ("", "empty"),
    ("# only a comment\n", "empty"),
    ("position_mm,friction\n", "no data rows"),
    ("0.0,0.5\n0.1,0.6\n", "line 1: expected a header"),
    ("position\n0.0\n", "line 1: the header has 1 column"),
    ("position_mm,friction\n0,0.5\n0.1,abc\n", "line 3: friction 'abc' is not a finite number"),
    ("position_mm,friction\n0,0.5\nx,0.5\n", "line 3: position 'x'"),
    ("position_mm,friction\n0,0.5\n0.1,nan\n", "line 3: friction 'nan'"),
    ("position_mm,friction\n0,0.5\n\n0.1\n", "line 4: 1 field"),
    # columns by name (issue 24): a sample number or a position in um is no mm position
    ("sample,friction\n0,0.5\n1,0.6\n", "no position column in its header \\('sample'"),
    ("x_um,friction\n0,0.5\n5,0.6\n", "no position column"),
    ("temp_C,x_mm\n20,0\n20,0.1\n", "no friction column"),
])
def test_read_recording_errors_name_the_line(tmp_path, text, match):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(ValueError, match=match) as e:
        T.read_recording(path)
    assert "bad.csv" in str(e.value)


# --- fits -------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def weibull_data():
    """400 windows x 97 wavenumbers of Weibull(k_j, lam_j) magnitudes:
    k from 0.7 to 30 and lam from 0.5 down to 1e-4 (log-spaced), as a brush
    might hold; fitted once with all three models."""
    n = 400
    k = np.geomspace(0.7, 30.0, K)
    lam = np.geomspace(0.5, 1e-4, K)
    rng = np.random.default_rng(2016)
    mags = stats.weibull_min.rvs(k, scale=lam, size=(n, K), random_state=rng)
    return n, k, lam, mags, F.fit_swipe(mags)


def test_weibull_round_trip(weibull_data):
    """Known (k, lam) per wavenumber -> fit -> recovered within Z_BOUND
    asymptotic standard errors (module docstring), and the standardised
    errors look standard normal."""
    n, k, lam, _, fit = weibull_data
    zk = (fit["weibull"]["k"] - k) / se_k(k, n)
    zl = (fit["weibull"]["lam"] - lam) / se_lam(k, lam, n)
    for z in (zk, zl):
        assert np.abs(z).max() < Z_BOUND, np.abs(z).max()
        assert abs(z.mean()) < 4.0 / math.sqrt(K)
        assert 0.75 < z.std() < 1.25
    assert not fit["degenerate"].any() and fit["windows"] == n
    assert fit["fallbacks"] == {"rayleigh": 0, "rice": 0, "weibull": 0}
    # the fitted (k, lam) are a brush the board accepts
    assert GB.validate(F.weibull_brush(fit))["k"] == pytest.approx(list(fit["weibull"]["k"]))


def test_model_selection_picks_weibull_for_weibull_data(weibull_data):
    """Weibull fits Weibull data best: lowest mean K-S; the highest likelihood
    and the lowest K-S in >= 85 % of the wavenumbers; and in every column whose
    shape Rice cannot take (k <= 1.5: heavier-tailed than Rayleigh; k >= 8:
    skewed left, Rice never is) the highest likelihood and the lowest K-S but
    for one column each. Near k = 2 .. 5 Rice fits as well (it contains
    Rayleigh, and near-Gaussian shapes). One column by likelihood: at n = 400
    a column near k = 8 goes to Rice now and then (this data set's k = 8.24,
    by 5 in log-likelihood; over seeds 0 .. 59 of this set, 3 had one such
    column among the 54, none had two)."""
    n, k, _, _, fit = weibull_data
    mean_ks = {mo: fit[mo]["ks"].mean() for mo in F.MODELS}
    assert min(mean_ks, key=mean_ks.get) == "weibull"
    w = F.MODELS.index("weibull")
    by_ks, by_ll = F.best_model(fit, "ks"), F.best_model(fit, "loglik")
    assert np.mean(by_ks == w) >= 0.85 and np.mean(by_ll == w) >= 0.85
    unlike_rice = (k <= 1.5) | (k >= 8.0)
    assert np.sum(by_ll[unlike_rice] != w) <= 1
    assert np.sum(by_ks[unlike_rice] != w) <= 1
    assert mean_ks["rayleigh"] > 2 * mean_ks["weibull"]


def test_ks_by_the_integral_transform_is_scipys_kstest(weibull_data):
    _, _, _, mags, fit = weibull_data
    for j in (0, 40, GB.NYQ):
        p = fit["weibull"]
        direct = stats.kstest(mags[:, j], stats.weibull_min.cdf, args=(p["k"][j], 0, p["lam"][j]))
        assert fit["weibull"]["ks"][j] == pytest.approx(direct.statistic, abs=1e-12)
        p = fit["rice"]
        direct = stats.kstest(mags[:, j], stats.rice.cdf,
                              args=(p["nu"][j] / p["sigma"][j], 0, p["sigma"][j]))
        assert fit["rice"]["ks"][j] == pytest.approx(direct.statistic, abs=1e-12)
        direct = stats.kstest(mags[:, j], stats.rayleigh.cdf, args=(0, fit["rayleigh"]["sigma"][j]))
        assert fit["rayleigh"]["ks"][j] == pytest.approx(direct.statistic, abs=1e-12)


def test_white_noise_gives_rayleigh():
    """A Gaussian white-noise map (mean 0.5, SD 0.1, 797 windows): at every
    wavenumber 2 .. NYQ - 2 (94) the Weibull shape is 2 (Rayleigh) within Z_BOUND
    standard errors inflated for the windows' overlap (module docstring), the
    Rayleigh sigma is the noise's sigma_n sqrt(3 / (2 W)) (W = 96) within
    the same, and Rayleigh fits well there; at k = 0 (the window's mean) and
    k = 1 (its Hann leak) the magnitudes are not zero-mean and Rayleigh
    fails (K-S > 0.4) while Weibull's k is large."""
    rng = np.random.default_rng(12)
    x = 0.5 + 0.1 * rng.standard_normal(2 * S.SCREEN_SAMPLES)
    m = T.stft_magnitudes(x)
    n = m.shape[0]
    fit = F.fit_swipe(m)
    infl = overlap_inflation()
    assert infl == pytest.approx(1.387, abs=1e-3)
    band = slice(2, GB.NYQ - 1)
    k = fit["weibull"]["k"][band]
    assert np.abs(k - 2.0).max() < Z_BOUND * infl * se_k(2.0, n)
    assert abs(np.median(k) - 2.0) < 0.05
    sigma = 0.1 * math.sqrt(3.0 / (2.0 * T.window().sum()))
    # Rayleigh's sigma MLE: SE sigma / (2 sqrt n) (Fisher information 4 / sigma^2)
    s = fit["rayleigh"]["sigma"][band]
    assert np.abs(s - sigma).max() < Z_BOUND * infl * sigma / (2 * math.sqrt(n))
    assert fit["rayleigh"]["ks"][band].mean() < 0.04
    assert np.all(fit["rayleigh"]["ks"][:2] > 0.4)
    assert np.all(fit["weibull"]["k"][:2] > 20) and np.all(fit["weibull"]["ks"][:2] < 0.1)


def test_the_constant_map():
    """A constant map: wavenumbers 0 and 1 all equal c (the mean and its Hann
    leak), the rest rounding (~1e-17): every column degenerate, with the
    parameters fits.py documents, and no warning, NaN parameter or crash."""
    c = 0.5
    fit = F.fit_swipe(T.stft_magnitudes(np.full(3000, c)))
    assert fit["degenerate"].all()
    for j, v in ((0, c), (1, c), (2, 0.0), (GB.NYQ, 0.0)):
        assert fit["weibull"]["k"][j] == F.K_MAX
        assert fit["weibull"]["lam"][j] == pytest.approx(v, abs=1e-15)
        assert fit["rice"]["nu"][j] == pytest.approx(v, abs=1e-15)
        assert fit["rice"]["sigma"][j] == 0.0
        assert fit["rayleigh"]["sigma"][j] == pytest.approx(v / math.sqrt(2), abs=1e-15)
        assert fit["weibull"]["ks"][j] == 0.0 and fit["rice"]["ks"][j] == 0.0
    # a point mass at c under Rayleigh(c / sqrt 2): the CDF at c is 1 - e^-1 = 0.632
    assert fit["rayleigh"]["ks"][0] == pytest.approx(1 - math.exp(-1.0))
    assert fit["rayleigh"]["ks"][5] == 0.0
    assert np.isnan(fit["weibull"]["loglik"]).all()
    GB.validate(F.weibull_brush(fit))          # still a valid brush (lam = 0 is allowed)
    for mo in F.MODELS:
        for name in F.PARAM_NAMES[mo]:
            assert np.all(np.isfinite(fit[mo][name]))
    # an all-zero map, and a map that is constant over part of its length
    z = F.fit_swipe(T.stft_magnitudes(np.zeros(1000)))
    assert z["degenerate"].all() and np.all(z["weibull"]["lam"] == 0.0)
    part = np.r_[np.full(2000, 0.5), 0.5 + 0.1 * np.random.default_rng(0).standard_normal(2000)]
    fp = F.fit_swipe(T.stft_magnitudes(part))
    assert not fp["degenerate"].any()
    assert all(np.all(np.isfinite(fp[mo][n])) for mo in F.MODELS for n in F.PARAM_NAMES[mo])


def test_nearly_constant_columns_cap_k():
    """A line of almost constant magnitude (CV 1e-5): Weibull k at the cap
    K_MAX with lam the constrained MLE (~ the value); Rice nu ~ the value,
    sigma ~ the spread; nothing degenerate."""
    rng = np.random.default_rng(4)
    m = np.abs(rng.normal(0.01, 0.003, (200, K)))
    m[:, 10] = 0.3 * (1 + 1e-5 * rng.standard_normal(200))
    fit = F.fit_swipe(m)
    assert not fit["degenerate"][10]
    assert fit["weibull"]["k"][10] == F.K_MAX == GB.K_MAX
    assert fit["weibull"]["lam"][10] == pytest.approx(0.3, rel=1e-3)
    assert fit["rice"]["nu"][10] == pytest.approx(0.3, rel=1e-4)
    assert fit["rice"]["sigma"][10] == pytest.approx(3e-6, rel=0.3)


def test_nan_and_bad_magnitudes_are_refused():
    with pytest.raises(ValueError, match="non-finite|is nan"):
        T.stft_magnitudes(np.full(1000, np.nan))
    m = np.ones((10, K))
    m[3, 7] = np.nan
    with pytest.raises(ValueError, match="window 3, wavenumber 7"):
        F.fit_swipe(m)
    m[3, 7] = -1.0
    with pytest.raises(ValueError, match="negative"):
        F.fit_swipe(m)
    with pytest.raises(ValueError, match="shape"):
        F.fit_swipe(np.ones((10, K - 1)))
    with pytest.raises(ValueError, match="unknown"):
        F.fit_swipe(np.ones((10, K)), models=("gamma",))


# --- swipes -----------------------------------------------------------------------------

def test_textures_match_the_golden_rows(golden_dir):
    g = np.loadtxt(golden_dir / "reference_textures.csv", delimiter=",")
    for i, name in enumerate(S.TEXTURES[:9]):
        t = S.texture(name)
        assert t.shape == (S.SCREEN_SAMPLES,)
        assert np.abs(t[:9600] - g[i]).max() < 1e-5, name      # noise rows: uint16 storage
    for name in S.TEXEL_PARAMS:
        t = S.texture(name)
        assert t.shape == (S.SCREEN_SAMPLES,) and 0.0 <= t.min() and t.max() <= 1.0
    assert len(S.TEXTURES) == 11


def test_the_swipe_model():
    """On a constant map: the friction is gain * c plus noise of SD noise_sd,
    so the transform's floor is Rayleigh with sigma = noise_sd sqrt(3/(2W));
    seeded swipes repeat; a texture's swipes do not depend on the textures
    after it."""
    model = S.SwipeModel()
    rng = np.random.default_rng(9)
    s = S.swipe(np.full(S.SCREEN_SAMPLES, 0.5), rng, model)
    assert s.friction.size == model.length_samples
    assert np.mean(s.friction) == pytest.approx(0.5 * s.gain, abs=4 * 0.02 / math.sqrt(9600))
    assert np.std(s.friction) == pytest.approx(model.noise_sd, rel=0.05)
    assert abs(s.stretch - 1.0) < 0.1 and 0.8 < s.gain < 1.25
    fit = F.fit_swipe(T.stft_magnitudes(s.friction), models=("rayleigh",))
    floor = model.noise_sd * math.sqrt(3.0 / (2.0 * T.window().sum()))
    assert np.median(fit["rayleigh"]["sigma"][2:GB.NYQ - 1]) == pytest.approx(floor, rel=0.05)

    small = S.SwipeModel(length_samples=1200)
    a = S.make_swipes(2, seed=7, names=("2sin", "white"), model=small)
    b = S.make_swipes(2, seed=7, names=("2sin", "white", "pink"), model=small)
    c = S.make_swipes(2, seed=8, names=("2sin", "white"), model=small)
    assert [(x.texture, x.index) for x in a] == [("2sin", 0), ("2sin", 1), ("white", 0),
                                                  ("white", 1)]
    assert all(np.array_equal(x.friction, y.friction) for x, y in zip(a, b))
    assert not np.array_equal(a[0].friction, c[0].friction)
    assert not np.array_equal(a[0].friction, a[1].friction)
    with pytest.raises(ValueError, match="warp_sd"):
        S.SwipeModel(warp_sd=-1.0)
    with pytest.raises(ValueError, match="unknown"):
        S.texture("velvet")
    with pytest.raises(ValueError, match="covers"):
        S.swipe(np.zeros(100), rng, small)


# --- the comparison ---------------------------------------------------------------------

def test_silhouette_and_distances_on_a_hand_made_set():
    X = np.array([[0.0], [0.1], [10.0], [10.1]])
    D = C.distance_matrix(X, "euclidean")
    # point 0: a = 0.1, b = (10 + 10.1) / 2; point 1: a = 0.1, b = (9.9 + 10) / 2; symmetric
    s = [(10.05 - 0.1) / 10.05, (9.95 - 0.1) / 9.95]
    assert C.silhouette(D, ["a", "a", "b", "b"]) == pytest.approx(np.mean(s + s))
    # standardized Euclidean: zero-variance components are left out
    Y = np.array([[0.0, 5.0, 1.0], [2.0, 5.0, 1.0], [4.0, 5.0, 3.0]])
    v = Y[:, [0, 2]].var(axis=0, ddof=1)
    d01 = math.sqrt(4.0 / v[0])
    assert C.distance_matrix(Y, "seuclidean")[0, 1] == pytest.approx(d01)
    assert C.distance_matrix(Y, "canberra")[0, 1] == pytest.approx(1.0)     # |0-2|/(0+2)
    assert C.distance_matrix(Y, "braycurtis")[0, 1] == pytest.approx(2.0 / 14.0)
    with pytest.raises(ValueError, match="unknown"):
        C.distance_matrix(Y, "cosine")


def _brush(k, lam):
    return {"k": [float(k)] * K, "lam": [float(lam)] * K}


def test_brush_distance():
    a, b = _brush(2.0, 0.01), _brush(3.0, 0.02)
    assert C.brush_distance(a, a, "euclidean") == 0.0
    assert C.brush_distance(a, b, "euclidean") == pytest.approx(math.sqrt(K * (1 + 1e-4)))
    assert C.brush_distance(a, b, "canberra") == pytest.approx(K * (1 / 5 + 1 / 3))
    assert C.brush_distance(a, b, "braycurtis") == pytest.approx(
        K * 1.01 / (K * (5 + 0.03)))
    var = np.r_[np.full(K, 4.0), np.zeros(K)]
    assert C.brush_distance(a, b, "seuclidean", variances=var) == pytest.approx(
        math.sqrt(K / 4.0))
    with pytest.raises(ValueError, match="variances"):
        C.brush_distance(a, b, "seuclidean")
    for bad, match in ((dict(a, k=a["k"][:-1]), r"brush\.k: expected %d" % K),
                       (dict(a, lam=[math.nan] * K), r"brush\.lam\[0\]"),
                       (dict(a, lam=[-1.0] * K), r"brush\.lam\[0\]"),
                       (dict(a, k=[0.0] * K), r"brush\.k\[0\]"),
                       ({"k": a["k"]}, "missing 'lam'")):
        with pytest.raises(ValueError, match=match):
            C.brush_distance(bad, b)
    # a fit's Weibull vector and brush_vector agree in order
    fit = {"weibull": {"k": np.arange(K) + 1.0, "lam": np.arange(K) * 0.01}}
    brush = F.weibull_brush(fit)
    assert np.array_equal(C.brush_vector(brush), C.param_vector(fit, "weibull"))


@pytest.fixture(scope="module")
def tiny():
    """3 textures x 3 short swipes (1,200 samples: 22 windows)."""
    model = S.SwipeModel(length_samples=1200)
    sw = S.make_swipes(3, seed=1, names=("2sin", "white", "square"), model=model)
    fits = [F.fit_swipe(T.stft_magnitudes(s.friction)) for s in sw]
    return sw, fits, [s.texture for s in sw]


def test_ks_table_and_consistency_on_a_tiny_set(tiny):
    sw, fits, labels = tiny
    rows = C.ks_table(fits, labels)
    assert [(r["texture"], r["model"]) for r in rows[:3]] == [("2sin", m) for m in F.MODELS]
    assert len(rows) == 4 * 3 and rows[-1]["texture"] == "all" and rows[-1]["swipes"] == 9
    for tex in ("2sin", "white", "square", "all"):
        assert sum(r["best"] for r in rows if r["texture"] == tex) == pytest.approx(1.0)
    assert all(0.0 <= r[b[0]] <= 1.0 for r in rows for b in C.BANDS)
    best = C.best_by_band(rows)
    assert best["white"]["0"] != "rayleigh"           # k = 0 is the mean: not zero-mean
    res = C.consistency(fits, labels)
    assert set(res["silhouette"]) == set(F.MODELS)
    for mo in F.MODELS:
        for me in C.METRICS:
            assert -1.0 <= res["silhouette"][mo][me] <= 1.0
            pts = res["mds"][mo][me]["points"]
            assert pts.shape == (9, 2) and np.all(np.isfinite(pts))
            assert math.sqrt(np.mean(np.sum(pts ** 2, axis=1))) == pytest.approx(1.0)
    again = C.consistency(fits, labels)
    assert np.array_equal(again["mds"]["weibull"]["braycurtis"]["points"],
                          res["mds"]["weibull"]["braycurtis"]["points"])
    # three very different textures: swipes cluster
    assert res["silhouette"]["weibull"]["braycurtis"] > 0.3


def test_the_benchmark_report(tmp_path):
    from bench import brush_fit as B, jsonable
    res = B.run(swipes_per_texture=2, names=("2sin", "pink"),
                model=S.SwipeModel(length_samples=1200), full_screen=False)
    text = B.format_tables(res)
    for word in ("Fit time per swipe", "K-S statistic", "Silhouette", "Bray-Curtis", "pink"):
        assert word in text
    B.ks_figure(res, str(tmp_path / "ks.png"))
    B.mds_figure(res, str(tmp_path / "mds.png"))
    assert (tmp_path / "ks.png").stat().st_size > 10000
    import json
    json.dumps(jsonable(res))

"""Per-wavenumber distribution fits of a swipe's spectral magnitudes (seed 002
§III-C, D): the magnitudes of one wavenumber across a swipe's windows
(texelpad.brush.transform.stft_magnitudes, one column of its (windows, K)
array) modelled by

    rayleigh  sigma        f(x) = x/sigma^2 exp(-x^2 / (2 sigma^2))      (eq. 1)
    rice      nu, sigma    f(x) = x/sigma^2 exp(-(x^2+nu^2)/(2 sigma^2))
                                  I0(x nu / sigma^2)                      (eq. 2)
    weibull   k, lam       f(x) = k/lam (x/lam)^(k-1) exp(-(x/lam)^k)     (eq. 3)

each by maximum likelihood with scipy.stats (rayleigh and weibull_min and
rice with loc fixed at 0; rice's shape b = nu / sigma and scale sigma), and
the Kolmogorov-Smirnov statistic of each fit (scipy.stats.kstest against the
fitted distribution: the largest distance between the empirical CDF and the
fitted one; 0 = perfect; seed 002 Fig. 4 reports means of 0.173, 0.164 and
0.077 for the three). The Weibull's (k, lam) per wavenumber are a brush
(device/texel/gen/brush.py).

How the fits are run (the why of each step):
- each column is divided by its root mean square before fitting and the
  scale parameters multiplied back after: all three families are scale
  families, so the MLE is unchanged, and the optimiser works at unit scale
  whatever the friction units (magnitudes run from ~1e-6 to ~0.5);
- starting points from moments, so scipy's Nelder-Mead (rv_continuous.fit)
  starts near the optimum - 1.5-2x faster than scipy's own starts, the same
  optimum (likelihoods equal to ~1e-9 relative): Weibull k0 = pi / (sqrt 6
  SD(ln x)) (Var ln x = pi^2 / (6 k^2)), lam0 = exp(mean ln x + gamma / k0);
  Rice nu0^4 = 2 E[x^2]^2 - E[x^4], sigma0^2 = (E[x^2] - nu0^2) / 2;
- the K-S statistic by the probability integral transform: kstest(F(x),
  "uniform") on every column of a model at once equals kstest(x, F) (F is
  continuous and increasing; the test suite checks the two agree), at a
  third of the cost of 97 separate calls.

Degenerate columns, and what comes back for them (never an exception, never
a NaN parameter):
- Weibull shape kept within the brush's limits K_MIN = 0.05 .. K_MAX = 1000
  (texel.gen.brush, imported: a fitted brush always validates): a column
  whose unconstrained MLE k exceeds K_MAX (a nearly deterministic magnitude:
  a line of a sum of sines, the window mean of a smooth texture; CV = SD /
  mean below ~0.13 %) gets k = K_MAX and lam = the MLE of the scale with k
  fixed there (the constrained MLE: the Weibull profile likelihood in k has
  one maximum, so the constrained optimum lies on the bound); likewise
  k = K_MIN below it (Weibull(0.05) puts 27 decades between its 10 % and
  90 % quantiles; with the floor below, a column spans at most 9). A painted k = 1000 varies the magnitude by ~0.13 % SD:
  indistinguishable from constant.
- all-equal columns (spread max - min <= REL_EQUAL * max; REL_EQUAL = 1e-9,
  far below float noise of a real signal yet above the rfft's rounding, which
  is ~1e-16 relative) and zero columns (max <= REL_ZERO * the largest
  magnitude of the whole swipe, REL_ZERO = 1e-9: a constant map's
  wavenumbers >= 2 come out ~1e-17, rounding, not texture; 1e-9 of full
  scale is 180 dB down, below any display's resolution - a uint16 step is
  1.5e-5): the value v is the column's mean (0 for a zero column) and
      weibull  k = K_MAX, lam = v   (the capped MLE; for v = 0 a point mass at 0)
      rice     nu = v, sigma = 0    (the limit of the MLE: a point mass at v)
      rayleigh sigma = v / sqrt 2   (its closed-form MLE sqrt(mean x^2 / 2); 0 for 0)
  K-S: 0 for rice and weibull (their limit is the point mass the data are);
  rayleigh's K-S is computed as for any column (it cannot be a point mass,
  so it fits a constant badly: K-S = 1 - e^-1 = 0.632) except for a zero
  column (0). Log-likelihoods are NaN there (a point mass has no density).
  These columns are flagged in the result's "degenerate" mask.
- in other columns, magnitudes below REL_ZERO times the column's largest are
  raised to that floor so that every log(x) of the likelihood is finite (a
  window of exactly zero contrast inside a textured swipe).
- should scipy's optimiser ever return a non-finite value, the moment
  estimates above are used instead (counted in the result's "fallbacks").

Speed (measured by bench/brush_fit.py; this machine, one core): ~5 ms
per wavenumber for the three models and their K-S, ~0.5 s for a 201-window
swipe (9,600 samples).

Pure logic: numpy, scipy (docs/architecture.md).
"""
from __future__ import annotations

import math
import warnings
from typing import Any, Iterable

import numpy as np
from scipy import stats

# K_MIN, K_MAX: the shapes a brush may hold (texel.gen.brush.validate), so every
# fitted (k, lam) is a valid brush
from texel.gen.brush import K, K_MAX, K_MIN

MODELS = ("rayleigh", "rice", "weibull")
PARAM_NAMES = {"rayleigh": ("sigma",), "rice": ("nu", "sigma"), "weibull": ("k", "lam")}
REL_ZERO = 1e-9         # a column this far below the swipe's largest magnitude is zero
REL_EQUAL = 1e-9        # a column whose relative spread is below this is constant
_SKIP_FREE = 4.0        # k0 > _SKIP_FREE * K_MAX: fit k = K_MAX directly (free fit overflows)
_SQRT2 = math.sqrt(2.0)


def _weibull_start(x: np.ndarray) -> tuple[float, float]:
    lx = np.log(x)
    sd = float(lx.std())
    k0 = math.pi / (math.sqrt(6.0) * sd) if sd > 0 else math.inf
    k0 = min(k0, 1e12)
    lam0 = float(np.exp(lx.mean() + np.euler_gamma / k0))
    return k0, lam0


def _weibull_scale_at(x: np.ndarray, k: float) -> float:
    """The scale's MLE at fixed shape k: (mean x^k)^(1/k), in logs (x^1000
    overflows for x > 2.0). A start for scipy, which then polishes it."""
    lk = k * np.log(x)
    top = float(lk.max())
    return math.exp((top + math.log(float(np.mean(np.exp(lk - top))))) / k)


def _rice_start(x: np.ndarray) -> tuple[float, float]:
    m2 = float(np.mean(x * x))
    m4 = float(np.mean(x ** 4))
    nu4 = 2.0 * m2 * m2 - m4
    nu = nu4 ** 0.25 if nu4 > 0 else 0.0
    s2 = max((m2 - nu * nu) / 2.0, 1e-12 * m2)
    return nu, math.sqrt(s2)


def _fit_weibull(x: np.ndarray) -> tuple[float, float, bool]:
    """(k, lam, fell_back) of a unit-scale column."""
    k0, lam0 = _weibull_start(x)
    k = lam = math.nan
    if k0 <= _SKIP_FREE * K_MAX:
        c, _, s = stats.weibull_min.fit(x, min(max(k0, K_MIN), K_MAX), floc=0, scale=lam0)
        k, lam = float(c), float(s)
    if not (k <= K_MAX):          # above the cap (or skipped): the constrained MLE at K_MAX
        start = _weibull_scale_at(x, K_MAX)
        _, _, s = stats.weibull_min.fit(x, fc=K_MAX, floc=0, scale=start)
        k, lam = K_MAX, float(s)
    elif k < K_MIN:
        _, _, s = stats.weibull_min.fit(x, fc=K_MIN, floc=0, scale=_weibull_scale_at(x, K_MIN))
        k, lam = K_MIN, float(s)
    if math.isfinite(k) and math.isfinite(lam) and k > 0 and lam > 0:
        return k, lam, False
    return min(max(k0, K_MIN), K_MAX), lam0, True


def _fit_rice(x: np.ndarray) -> tuple[float, float, bool]:
    """(nu, sigma, fell_back) of a unit-scale column."""
    nu0, s0 = _rice_start(x)
    b, _, s = stats.rice.fit(x, nu0 / s0, floc=0, scale=s0)
    nu, sigma = float(b) * float(s), float(s)
    if math.isfinite(nu) and math.isfinite(sigma) and nu >= 0 and sigma > 0:
        return nu, sigma, False
    return nu0, s0, True


def _fit_rayleigh(x: np.ndarray) -> float:
    _, s = stats.rayleigh.fit(x, floc=0)      # closed form: sqrt(mean x^2 / 2)
    return float(s)


def _frozen(model: str, p: dict[str, np.ndarray], cols):
    """scipy frozen distribution of `model` over the columns `cols`,
    parameters broadcast along the last axis."""
    if model == "rayleigh":
        return stats.rayleigh(loc=0, scale=p["sigma"][cols])
    if model == "rice":
        return stats.rice(p["nu"][cols] / p["sigma"][cols], loc=0, scale=p["sigma"][cols])
    return stats.weibull_min(p["k"][cols], loc=0, scale=p["lam"][cols])


def _checked(mags: Any, models: Iterable[str]) -> tuple[np.ndarray, tuple[str, ...]]:
    """fit_swipe's input as an array, and its models, or ValueError saying what is wrong."""
    m = np.asarray(mags, dtype=float)
    models = tuple(models)
    for name in models:
        if name not in MODELS:
            raise ValueError("models: unknown %r (known: %s)" % (name, ", ".join(MODELS)))
    if m.ndim != 2 or m.shape[1] != K or m.shape[0] < 1:
        raise ValueError("mags: expected shape (windows >= 1, %d), got %r" % (K, m.shape))
    if not np.all(np.isfinite(m)):
        w, k = np.argwhere(~np.isfinite(m))[0]
        raise ValueError("mags: window %d, wavenumber %d is %r; magnitudes must be finite"
                         % (w, k, float(m[w, k])))
    if np.any(m < 0):
        w, k = np.argwhere(m < 0)[0]
        raise ValueError("mags: window %d, wavenumber %d is negative (%r)" % (w, k, float(m[w, k])))
    return m, models


def fit_swipe(mags, models: Iterable[str] = MODELS) -> dict:
    """Fit every wavenumber (column) of a swipe's magnitudes, shape
    (windows, K) as from stft_magnitudes, with each of `models`. Returns

        {"rayleigh": {"sigma": (K,), "ks": (K,), "loglik": (K,)},
         "rice":     {"nu": (K,), "sigma": (K,), "ks": (K,), "loglik": (K,)},
         "weibull":  {"k": (K,), "lam": (K,), "ks": (K,), "loglik": (K,)},
         "degenerate": bool (K,), "windows": n, "fallbacks": {model: count}}

    parameters in the magnitudes' own units (friction), ks the K-S statistic
    of the fit, loglik the summed log density of the column under the fit.
    Degenerate columns (all equal, or zero) as the module docstring says.
    Raises ValueError for a wrong shape or a non-finite or negative
    magnitude."""
    m, models = _checked(mags, models)
    n = m.shape[0]
    top = float(m.max())
    cmax = m.max(axis=0)
    zero = cmax <= REL_ZERO * top if top > 0 else np.ones(K, bool)
    equal = (cmax - m.min(axis=0)) <= REL_EQUAL * cmax
    degen = zero | equal
    value = np.where(zero, 0.0, m.mean(axis=0))
    live = np.flatnonzero(~degen)

    # unit-scale columns (module docstring), small magnitudes floored for finite logs
    rms = np.sqrt(np.mean(m * m, axis=0))
    rms[degen] = 1.0
    u = m / rms
    floor = REL_ZERO * u.max(axis=0)
    u = np.maximum(u, floor)

    out: dict = {"degenerate": degen, "windows": n, "fallbacks": {}}
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        # the optimisers' trial points overflow harmlessly (x^k at a far-off scale)
        warnings.simplefilter("ignore", RuntimeWarning)
        for model in models:
            p = {name: np.zeros(K) for name in PARAM_NAMES[model]}
            falls = 0
            for j in live:
                x = u[:, j]
                if model == "rayleigh":
                    p["sigma"][j] = _fit_rayleigh(x)
                elif model == "rice":
                    p["nu"][j], p["sigma"][j], fb = _fit_rice(x)
                    falls += fb
                else:
                    p["k"][j], p["lam"][j], fb = _fit_weibull(x)
                    falls += fb
            # back to friction units; degenerate columns by the docstring's rule
            for name in ("sigma", "nu", "lam"):
                if name in p:
                    p[name] *= rms
            if model == "rayleigh":
                p["sigma"][degen] = value[degen] / _SQRT2
            elif model == "rice":
                p["nu"][degen] = value[degen]
                p["sigma"][degen] = 0.0
            else:
                p["k"][degen] = K_MAX
                p["lam"][degen] = value[degen]
            ks = np.zeros(K)
            ll = np.full(K, np.nan)
            if live.size:
                d = _frozen(model, p, live)
                xs = np.maximum(m[:, live], floor[live] * rms[live])
                ks[live] = stats.kstest(d.cdf(xs), "uniform", axis=0).statistic
                ll[live] = d.logpdf(xs).sum(axis=0)
            if model == "rayleigh":
                # a constant v > 0 under Rayleigh(v/sqrt 2): the CDF at v is 1 - e^-1
                eq = np.flatnonzero(equal & ~zero)
                if eq.size:
                    ks[eq] = stats.kstest(stats.rayleigh.cdf(m[:, eq], scale=p["sigma"][eq]),
                                          "uniform", axis=0).statistic
            p["ks"] = ks
            p["loglik"] = ll
            out[model] = p
            out["fallbacks"][model] = falls
    return out


def weibull_brush(fit: dict) -> dict[str, list[float]]:
    """The Weibull (k, lam) lists of a fit_swipe result: the numbers a brush
    holds (device/texel/gen/brush.py; the lead's brush format adds the rest)."""
    return {"k": [float(v) for v in fit["weibull"]["k"]],
            "lam": [float(v) for v in fit["weibull"]["lam"]]}


def best_model(fit: dict, by: str = "ks") -> np.ndarray:
    """Per wavenumber, the index into MODELS of the best fit: the lowest K-S
    statistic (by="ks") or the highest log-likelihood (by="loglik"; NaN in
    degenerate columns, where -1 is returned)."""
    if by == "ks":
        return np.argmin(np.stack([fit[mo]["ks"] for mo in MODELS]), axis=0)
    if by == "loglik":
        ll = np.stack([fit[mo]["loglik"] for mo in MODELS])
        best = np.argmax(np.where(np.isnan(ll), -np.inf, ll), axis=0)
        return np.where(np.all(np.isnan(ll), axis=0), -1, best)
    raise ValueError("by: expected 'ks' or 'loglik', got %r" % (by,))

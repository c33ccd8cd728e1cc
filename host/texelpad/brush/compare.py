"""The paper's comparison of the three models over swipes (seed 002 §III-D,
Fig. 4, Fig. 5, Table II), on fit_swipe results (texelpad.brush.fits):

- goodness of fit: the K-S statistics per texture and model, as means over
  swipes and wavenumber bands (BANDS), and which model fits best where (the
  lowest K-S per swipe and wavenumber). Wavenumber 0 is the window's mean
  friction, far from zero-mean, so Rayleigh (a zero-mean complex Gaussian's
  magnitude) cannot fit it; wavenumber 1 carries the periodic Hann window's
  leak of that mean (a constant c gives m_1 = c, transform.py), which is why
  seed 002 saw "the first two coefficients in each texel" poorly fit by
  Rayleigh - the bands keep k = 0 and k = 1 apart for that reason.
- consistency: every swipe becomes a parameter vector per model
  (param_vector: rayleigh sigma_0..96 - 97 numbers; rice nu_0..96 then
  sigma_0..96 and weibull k_0..96 then lam_0..96 - 194 numbers; seed 002 has
  101 and 202), distances between swipes under the paper's four metrics
  (METRICS: "Euclidean, standardized Euclidean, Canberra, and Bray-Curtis",
  scipy.spatial.distance's definitions), the silhouette score of the
  clustering by texture (sklearn.metrics.silhouette_score, metric=
  "precomputed": seed 002 eq. 4, s(i) = (b - a) / max(a, b), averaged; -1 ..
  1, higher = swipes of a texture closer together than to another
  texture's), and a 2-D MDS embedding of each distance matrix
  (sklearn.manifold.MDS, precomputed dissimilarities, fixed random_state)
  for a figure like Fig. 5.

Standardized Euclidean divides each component's squared difference by that
component's variance over the set of vectors compared (scipy's default V,
ddof = 1); components with zero variance over the set (e.g. a wavenumber
every swipe fits as degenerate) carry no information and are left out
rather than divided by zero. Canberra's 0/0 terms count 0 (scipy).

brush_distance compares two brushes (dicts with "k" and "lam", K floats
each: the lead's brush format) by the same metrics on the Weibull vector.

Pure logic: numpy, scipy, scikit-learn (docs/architecture.md).
"""
from __future__ import annotations

import inspect
import math
from typing import Mapping, Sequence

import numpy as np
from scipy.spatial.distance import pdist, squareform

from texel.gen.brush import K, NYQ

from .fits import MODELS

METRICS = ("euclidean", "seuclidean", "canberra", "braycurtis")
METRIC_LABELS = {"euclidean": "Euclidean", "seuclidean": "standardized Euclidean",
                 "canberra": "Canberra", "braycurtis": "Bray-Curtis"}
# wavenumber bands [lo, hi): the mean, its Hann leak, then wavelengths 0.51-0.11 mm,
# 0.102-0.033 mm, 32-10.6 um (1.0176 mm / k; the last band ends at the Nyquist, NYQ)
BANDS = (("0", 0, 1), ("1", 1, 2), ("2-9", 2, 10), ("10-31", 10, 32), ("32-%d" % NYQ, 32, K))
MDS_RANDOM_STATE = 0


def param_vector(fit: Mapping, model: str) -> np.ndarray:
    """One swipe's parameters under `model` as one vector (module docstring)."""
    p = fit[model]
    if model == "rayleigh":
        return np.asarray(p["sigma"], dtype=float).copy()
    if model == "rice":
        return np.concatenate([p["nu"], p["sigma"]]).astype(float)
    if model == "weibull":
        return np.concatenate([p["k"], p["lam"]]).astype(float)
    raise ValueError("model: unknown %r (known: %s)" % (model, ", ".join(MODELS)))


def param_matrix(fits: Sequence[Mapping], model: str) -> np.ndarray:
    return np.stack([param_vector(f, model) for f in fits])


def _check_metric(metric: str) -> None:
    if metric not in METRICS:
        raise ValueError("metric: unknown %r (known: %s)" % (metric, ", ".join(METRICS)))


def distance_matrix(X, metric: str) -> np.ndarray:
    """The square matrix of distances between the rows of X under `metric`
    (one of METRICS; standardized Euclidean with the variances of X's own
    columns, zero-variance columns left out)."""
    _check_metric(metric)
    X = np.asarray(X, dtype=float)
    if X.ndim != 2 or X.shape[0] < 2:
        raise ValueError("X: expected at least 2 row vectors, got shape %r" % (X.shape,))
    if not np.all(np.isfinite(X)):
        raise ValueError("X: parameter vectors must be finite")
    if metric == "seuclidean":
        v = X.var(axis=0, ddof=1)
        keep = v > 0
        if not keep.any():
            return np.zeros((X.shape[0], X.shape[0]))
        return squareform(pdist(X[:, keep], "seuclidean", V=v[keep]))
    return squareform(pdist(X, metric))


def silhouette(D, labels) -> float:
    """Silhouette score of the clustering `labels` under the precomputed
    distances D (sklearn.metrics.silhouette_score, metric="precomputed")."""
    from sklearn.metrics import silhouette_score
    return float(silhouette_score(np.asarray(D, dtype=float), np.asarray(labels),
                                  metric="precomputed"))


def _mds(random_state: int):
    from sklearn.manifold import MDS
    params = inspect.signature(MDS).parameters
    if "metric_mds" in params:
        # scikit-learn >= 1.8 renamed dissimilarity= to metric= (dissimilarity is
        # deprecated, gone in 1.10) and added the classical-MDS start, which is
        # deterministic and better than random starts
        return MDS(n_components=2, metric="precomputed", init="classical_mds",
                   random_state=random_state, normalized_stress="auto")
    return MDS(n_components=2, dissimilarity="precomputed", n_init=4,
               random_state=random_state, normalized_stress="auto")


def mds_embedding(D, random_state: int = MDS_RANDOM_STATE) -> tuple[np.ndarray, float]:
    """(points (n, 2), stress) of metric MDS on the precomputed distances D.
    Scaled so that the embedding's RMS distance from its centroid is 1 (the
    figure's axes carry no unit; the paper's neither)."""
    D = np.asarray(D, dtype=float)
    m = _mds(random_state)
    Y = m.fit_transform(D)
    Y = Y - Y.mean(axis=0)
    r = math.sqrt(float(np.mean(np.sum(Y * Y, axis=1))))
    return (Y / r if r > 0 else Y), float(m.stress_)


def ks_table(fits: Sequence[Mapping], labels: Sequence[str], bands=BANDS) -> list[dict]:
    """One row per texture (in first-seen order) and model: mean K-S over the
    texture's swipes, over all wavenumbers ("mean") and per band, and "best":
    the fraction of (swipe, wavenumber) cells where this model has the lowest
    K-S of the three (ties to the first in MODELS order). Then one row per
    model over every texture (texture "all")."""
    labels = list(labels)
    if len(labels) != len(fits):
        raise ValueError("labels: %d for %d fits" % (len(labels), len(fits)))
    ks = {mo: np.stack([f[mo]["ks"] for f in fits]) for mo in MODELS}      # (swipes, K)
    best = np.argmin(np.stack([ks[mo] for mo in MODELS]), axis=0)          # (swipes, K)
    rows = []
    groups = list(dict.fromkeys(labels)) + ["all"]
    lab = np.asarray(labels)
    for tex in groups:
        sel = np.ones(len(labels), bool) if tex == "all" else lab == tex
        for i, mo in enumerate(MODELS):
            a = ks[mo][sel]
            row = {"texture": tex, "model": mo, "swipes": int(sel.sum()),
                   "mean": float(a.mean())}
            for name, lo, hi in bands:
                row[name] = float(a[:, lo:hi].mean())
            row["best"] = float(np.mean(best[sel] == i))
            rows.append(row)
    return rows


def best_by_band(rows: Sequence[Mapping], bands=BANDS) -> dict[str, dict[str, str]]:
    """Per texture, per band: the model with the lowest mean K-S in ks_table's rows."""
    out: dict[str, dict[str, str]] = {}
    for tex in dict.fromkeys(r["texture"] for r in rows):
        mine = [r for r in rows if r["texture"] == tex]
        out[tex] = {name: min(mine, key=lambda r: r[name])["model"]
                    for name, _, _ in list(bands) + [("mean", 0, K)]}
    return out


def consistency(fits: Sequence[Mapping], labels: Sequence[str], models=MODELS, metrics=METRICS,
                mds: bool = True, random_state: int = MDS_RANDOM_STATE) -> dict:
    """The paper's Table II and Fig. 5 on `fits`: {"silhouette": {model:
    {metric: score}}, "mds": {model: {metric: {"points": (n, 2), "stress":
    s}}} (when mds), "labels": [...]}."""
    labels = list(labels)
    if len(labels) != len(fits):
        raise ValueError("labels: %d for %d fits" % (len(labels), len(fits)))
    sil: dict = {}
    emb: dict = {}
    for mo in models:
        X = param_matrix(fits, mo)
        sil[mo], emb[mo] = {}, {}
        for me in metrics:
            D = distance_matrix(X, me)
            sil[mo][me] = silhouette(D, labels)
            if mds:
                pts, stress = mds_embedding(D, random_state)
                emb[mo][me] = {"points": pts, "stress": stress}
    out = {"silhouette": sil, "labels": labels}
    if mds:
        out["mds"] = emb
    return out


def brush_vector(brush: Mapping) -> np.ndarray:
    """A brush's Weibull vector k_0..96 then lam_0..96 (the order of
    param_vector(fit, "weibull")). ValueError naming the key for a missing
    key, a wrong length, a non-finite value, k <= 0 or lam < 0."""
    parts = []
    for key in ("k", "lam"):
        if key not in brush:
            raise ValueError("brush: missing %r" % key)
        try:
            v = np.asarray(brush[key], dtype=float)
        except (TypeError, ValueError):
            raise ValueError("brush.%s: expected %d numbers" % (key, K)) from None
        if v.shape != (K,):
            raise ValueError("brush.%s: expected %d numbers, got shape %r" % (key, K, v.shape))
        bad = np.flatnonzero(~np.isfinite(v) | ((v <= 0) if key == "k" else (v < 0)))
        if bad.size:
            raise ValueError("brush.%s[%d]: %r is not a %s" % (
                key, bad[0], float(v[bad[0]]),
                "finite shape > 0" if key == "k" else "finite scale >= 0"))
        parts.append(v)
    return np.concatenate(parts)


def brush_distance(a: Mapping, b: Mapping, metric: str = "braycurtis", variances=None) -> float:
    """Distance between two brushes' Weibull vectors (brush_vector) under one
    of METRICS. "seuclidean" needs the per-component variances of the set the
    brushes are compared within (variances=, 2K numbers, e.g.
    param_matrix(fits, "weibull").var(axis=0, ddof=1)); components with zero
    variance are left out, as in distance_matrix."""
    _check_metric(metric)
    u, v = brush_vector(a), brush_vector(b)
    if metric == "seuclidean":
        if variances is None:
            raise ValueError("metric 'seuclidean' needs variances= (2*%d per-component variances "
                             "of the set of brushes compared)" % K)
        var = np.asarray(variances, dtype=float)
        if var.shape != u.shape or not np.all(np.isfinite(var)) or np.any(var < 0):
            raise ValueError("variances: expected %d finite numbers >= 0" % u.size)
        keep = var > 0
        return float(math.sqrt(np.sum((u[keep] - v[keep]) ** 2 / var[keep])))
    return float(pdist(np.stack([u, v]), metric)[0])

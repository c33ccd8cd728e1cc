"""What painting makes (issue 21 items 4-5; seed 002 §III-D's comparison
turned on the Tactile Paintbrush's own output): does a map painted from a
brush read, feel and correlate like the map the brush was fitted to?

    .venv/bin/python -m bench.brush_painting [--quick] [--json PATH]
        [--figure [PATH]] [--sources A,B] [--swipes N] [--paint-seeds N] [--seed S]

For each source (texelpad.brush.swipes.TEXTURES: the nine reference textures
and the two texel renderings, a full screen each, values in amplitude units):

1. a brush: texelpad.brush.document.fit of the source's map ("amplitude":
   range [0, 1]), then painted (document.paint) with --paint-seeds seeds
   (default 3: 0, 1, 2; --quick 2), a full screen each, as amplitude / 65535;
2. swipes (texelpad.brush.swipes.SwipeModel, the default model: 50.88 mm,
   3 % warp, 5 % gain, 0.02 noise): --swipes of the source (default 10, the
   paper's count; --quick 3), drawn exactly as swipes.make_swipes draws them
   (SeedSequence(seed, spawn_key=(i, j)), i the source's place in TEXTURES,
   so they are the swipes of bench.brush_fit), and as many of the
   paintings (swipe j of painting seed j mod seeds; spawn_key=(i, j, 1):
   independent starts, warps, gains and noise);
3. per swipe, Weibull per wavenumber (transform.stft_magnitudes - the plain
   transform, as the paper's comparison and brush_fit - then
   fits.fit_swipe): a parameter vector k_0..K-1, lam_0..K-1 per swipe
   (compare.param_vector);
4. seed 002's metrics (compare.METRICS: Euclidean, standardized Euclidean,
   Canberra, Bray-Curtis) between all swipes of all sources and paintings
   (standardized Euclidean: the variances of that whole set). Per source:
   the median distance between the source's own swipes ("within"), between
   a source swipe and a painted swipe ("src-paint"; ratio = src-paint /
   within: 1 = a painted swipe is as close to the source's swipes as they are
   to each other), between painted swipes, and to the nearest other source's
   swipes (the scale at which a texture is another texture). Then would a
   painted swipe be taken for its source: its silhouette against the
   sources' swipe clusters (seed 002 eq. 4 with a = the mean distance to its
   source's swipes, b = the smallest mean distance to another source's) and
   the nearest texture (the source whose swipes are closest on average),
   beside the same for the source's own swipes (leave-one-out: sklearn's
   silhouette_samples on the sources' swipes). The silhouette of the
   sources' swipes alone (compare.silhouette: seed 002 Table II's Weibull
   column on our data) and with the painted swipes labelled as their source;
5. how it feels: the distance on the felt plane (texelpad.analysis.perception
   .felt_distance: felt pitch and noisiness, dB; under perception.JND_DB =
   1 dB they feel the same) between the source and painting seed 0, and for
   scale the source and painting seed 1, the two paintings, and the source
   and the other sources (the nearest, the median); the W2 distance between
   the felt spectra (perception.w2_db) of source and painting 0 beside; the
   felt levels beside (the distances leave the level out);
6. the autocorrelation r(m) of the source and of each painting (mean
   removed, normalised per lag by its overlap: a sinusoid gives cos 2 pi f m)
   at lags of whole windows j * WINDOW (j = 1 .. as many as fit in 12 mm;
   texel.gen.brush's WINDOW, whatever it is) and at 2 mm and 10 mm
   (round(mm / DX_MM) samples). Issue 21's criterion for a painting:
   |r| <= 0.1 at those lags (the worst painting seed and lag); the source's
   own r beside - a periodic source (the sines, square, triangle, sawtooth,
   the near-periodic texel) has |r| near 1 at its own periods, and its
   painting may keep that.

--figure: docs/img/brush-painting.png (default path) - for the pink
reference and the irregular texel rendering: the source map (4 mm), its
painting (seed 0, same span) and both autocorrelations against lag in mm
(0 .. 12 mm, window multiples and 2 / 10 mm marked).
--json: everything (every swipe's vector, every r); the maps are left out.
Prints progress on stderr, tables on stdout; never fails on time. One
process (the default run: ~80 s on one core; --quick ~30 s).
Pure logic otherwise (no link, no web framework: docs/architecture.md).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import statistics
import sys
import textwrap
import time
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from texel.gen import brush as B
from texel.gen.params import DX_MM

from texelpad.analysis import perception as P
from . import jsonable
from texelpad.brush import compare as C
from texelpad.brush import document as D
from texelpad.brush import fits as F
from texelpad.brush import swipes as S
from texelpad.brush import transform as T

Progress = Callable[[str], None]
QUICK_SWIPES = 3
DEFAULT_PAINT_SEEDS = 3
QUICK_PAINT_SEEDS = 2
ACF_MAX_MM = 12.0               # the autocorrelation is reported / drawn up to this lag
MM_LAGS = (2.0, 10.0)           # issue 21: r at 2 mm and 10 mm
ACF_LIMIT = 0.1                 # issue 21: a painting's |r| at those lags
SHOW_MM = 4.0                   # the figure's span of map
FIGURE_SOURCES = ("pink", "texel-p15-i-5")
DEFAULT_FIGURE = os.path.join("docs", "img", "brush-painting.png")
PAINTED_STREAM = 1              # spawn_key=(i, j, PAINTED_STREAM) for painted swipes


def lag_samples(mm: float) -> int:
    """A lag in mm as display samples: round(mm / DX_MM)."""
    return int(round(mm / DX_MM))


def window_mm() -> float:
    return B.WINDOW * DX_MM


def acf_lags(max_mm: float = ACF_MAX_MM) -> dict[str, int]:
    """The lags reported, by name: "1W", "2W", ... (whole windows of
    B.WINDOW samples up to max_mm) then "2mm", "10mm" (MM_LAGS)."""
    out = {"%dW" % j: j * B.WINDOW for j in range(1, int(max_mm / window_mm() + 1e-9) + 1)}
    for mm in MM_LAGS:
        out["%gmm" % mm] = lag_samples(mm)
    return out


def autocorrelation(x, max_lag: int) -> np.ndarray:
    """r(m), m = 0 .. max_lag, of a map: sum over n of (x_n - mean)(x_{n+m} -
    mean) / ((N - m) var) - each lag normalised by its own overlap, so a
    periodic map gives r = 1 at its period however far (FFT, zero-padded:
    no wrap-around). A constant map gives zeros (r(0) = 1)."""
    a = np.asarray(x, dtype=float)
    n = a.size
    max_lag = int(min(max_lag, n - 1))
    a = a - a.mean()
    size = 1 << int(math.ceil(math.log2(2 * n)))
    f = np.fft.rfft(a, size)
    s = np.fft.irfft(f.real ** 2 + f.imag ** 2, size)[:max_lag + 1]
    var = float(np.dot(a, a)) / n
    if not var > 0:
        r = np.zeros(max_lag + 1)
        r[0] = 1.0
        return r
    return s / (n - np.arange(max_lag + 1)) / var


def _weibull_fit(friction: np.ndarray) -> dict:
    """One swipe's Weibull fit on the plain transform (the paper's comparison)."""
    return F.fit_swipe(T.stft_magnitudes(friction), models=("weibull",))


def _swipes_of(fmaps: Sequence[np.ndarray], n: int, seed: int, i: int, model: S.SwipeModel,
               stream: int | None = None) -> list:
    """n swipes, swipe j of fmaps[j mod len(fmaps)], drawn from
    SeedSequence(seed, spawn_key=(i, j)) - swipes.make_swipes' streams - or
    (i, j, stream) for another set of the same source."""
    out = []
    for j in range(n):
        key = (i, j) if stream is None else (i, j, stream)
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=key))
        s = S.swipe(fmaps[j % len(fmaps)], rng, model)
        s.index = j
        out.append(s)
    return out


def _source(i: int, name: str, swipes: int, paint_seeds: Sequence[int], seed: int,
            model: S.SwipeModel, samples: int, lags: dict[str, int]) -> dict:
    """Everything about one source that does not need the others."""
    m = np.asarray(S.texture(name, samples), dtype=float)
    t0 = time.perf_counter()
    brush = D.fit([m], "amplitude", name=name,
                  source="texelpad.brush.swipes texture %s (%d samples)" % (name, samples))
    t_fit = time.perf_counter() - t0
    t0 = time.perf_counter()
    paintings = [D.paint(brush, s, samples) / 65535.0 for s in paint_seeds]
    t_paint = (time.perf_counter() - t0) / len(paint_seeds)
    src_sw = _swipes_of([m], swipes, seed, i, model)
    pnt_sw = _swipes_of(paintings, swipes, seed, i, model, PAINTED_STREAM)
    t0 = time.perf_counter()
    src_fit = [_weibull_fit(s.friction) for s in src_sw]
    pnt_fit = [_weibull_fit(s.friction) for s in pnt_sw]
    t_swipes = (time.perf_counter() - t0) / (2 * swipes)
    max_lag = max(lags.values())
    r_src = autocorrelation(m, max_lag)
    r_pnt = [autocorrelation(p, max_lag) for p in paintings]
    acf: dict[str, Any] = {"source": {k: float(r_src[v]) for k, v in lags.items()},
           "paintings": [{k: float(r[v]) for k, v in lags.items()} for r in r_pnt]}
    acf["painting_mean"] = {k: float(np.mean([p[k] for p in acf["paintings"]])) for k in lags}
    acf["max_abs_source"] = max(abs(v) for v in acf["source"].values())
    acf["max_abs_painting"] = max(abs(v) for p in acf["paintings"] for v in p.values())
    acf["criterion_met"] = bool(acf["max_abs_painting"] <= ACF_LIMIT)

    def meta(s, f, paint_seed=None):
        d = {"index": s.index, "start_mm": s.start_mm, "gain": s.gain, "stretch": s.stretch,
             "weibull_ks_mean": float(np.mean(f["weibull"]["ks"])),
             "vector": C.param_vector(f, "weibull")}
        if paint_seed is not None:
            d["painting_seed"] = paint_seed
        return d
    return {
        "index": i,
        "brush": {"windows": brush["fit"]["windows"], "k": brush["k"], "lam": brush["lam"],
                  "ks_mean": float(np.mean(brush["fit"]["ks"])), "fit_s": t_fit},
        "paint_s": t_paint,
        "swipe_fit_s": t_swipes,
        "source_swipes": [meta(s, f) for s, f in zip(src_sw, src_fit)],
        "painted_swipes": [meta(s, f, paint_seeds[j % len(paint_seeds)])
                           for j, (s, f) in enumerate(zip(pnt_sw, pnt_fit))],
        "acf": acf,
        "_map": m, "_paintings": paintings,
    }


def _median(a) -> float:
    a = np.asarray(a, dtype=float).ravel()
    return float(np.median(a)) if a.size else math.nan


def _pairs(Dm: np.ndarray, rows: np.ndarray) -> np.ndarray:
    sub = Dm[np.ix_(rows, rows)]
    return sub[np.triu_indices(len(rows), 1)]


def compare_swipes(per: dict, names: Sequence[str]) -> dict:
    """The paper's metrics over all swipes (module docstring, step 4)."""
    vecs, who, kind = [], [], []
    for ii, name in enumerate(names):
        for grp, lab in (("source_swipes", 0), ("painted_swipes", 1)):
            for s in per[name][grp]:
                vecs.append(s["vector"])
                who.append(ii)
                kind.append(lab)
    X = np.stack(vecs)
    who_a, kind_a = np.asarray(who), np.asarray(kind)
    src_rows = [np.flatnonzero((who_a == ii) & (kind_a == 0)) for ii in range(len(names))]
    pnt_rows = [np.flatnonzero((who_a == ii) & (kind_a == 1)) for ii in range(len(names))]
    all_src = np.flatnonzero(kind_a == 0)
    out: dict = {}
    for me in C.METRICS:
        Dm = C.distance_matrix(X, me)
        # mean distance from every swipe to each source's swipes (a swipe's own
        # zero distance left out of its own cluster's mean)
        mean_to = np.empty((X.shape[0], len(names)))
        for jj, rows in enumerate(src_rows):
            tot = Dm[:, rows].sum(axis=1)
            cnt = np.full(X.shape[0], float(len(rows)))
            own = np.isin(np.arange(X.shape[0]), rows)
            cnt[own] -= 1.0
            mean_to[:, jj] = tot / np.maximum(cnt, 1.0)
        per_src = {}
        sil_src_all: list[float] = []
        sil_pnt_all: list[float] = []
        ok_src: list[bool] = []
        ok_pnt: list[bool] = []
        for ii, name in enumerate(names):
            within = _pairs(Dm, src_rows[ii])
            sp = Dm[np.ix_(src_rows[ii], pnt_rows[ii])]
            pp = _pairs(Dm, pnt_rows[ii])
            others = {names[jj]: _median(Dm[np.ix_(src_rows[ii], src_rows[jj])])
                      for jj in range(len(names)) if jj != ii}
            nearest = min(others, key=lambda o: others[o])
            res: dict[str, Any] = {"within_source": _median(within), "source_to_painting": _median(sp),
                   "within_painting": _median(pp), "nearest_other": nearest,
                   "to_nearest_other": others[nearest], "to_others_median": _median(
                       list(others.values()))}
            res["ratio"] = (res["source_to_painting"] / res["within_source"]
                            if res["within_source"] > 0 else math.inf)
            for grp, rows, sil_acc, ok_acc in (("source", src_rows[ii], sil_src_all, ok_src),
                                               ("painted", pnt_rows[ii], sil_pnt_all, ok_pnt)):
                a = mean_to[rows, ii]
                other = np.delete(mean_to[rows], ii, axis=1)
                b = other.min(axis=1)
                with np.errstate(invalid="ignore", divide="ignore"):
                    sil = np.where(np.maximum(a, b) > 0, (b - a) / np.maximum(a, b), 0.0)
                pred = np.argmin(mean_to[rows], axis=1)
                res["silhouette_" + grp] = float(sil.mean())
                res["classified_" + grp] = [names[p] for p in pred]
                res["correct_" + grp] = int(np.sum(pred == ii))
                sil_acc.extend(sil.tolist())
                ok_acc.extend((pred == ii).tolist())
            per_src[name] = res
        labels_src = [names[w] for w in who_a[all_src]]
        D_src = C.distance_matrix(X[all_src], me)       # the sources' swipes alone (Table II)
        out[me] = {
            "sources": per_src,
            "silhouette_sources": C.silhouette(D_src, labels_src),
            "silhouette_with_paintings": C.silhouette(Dm, [names[w] for w in who_a]),
            "silhouette_source_swipes_mean": float(np.mean(sil_src_all)),
            "silhouette_painted_swipes_mean": float(np.mean(sil_pnt_all)),
            "accuracy_source": float(np.mean(ok_src)),
            "accuracy_painted": float(np.mean(ok_pnt)),
            "ratio_median": _median([r["ratio"] for r in per_src.values()]),
        }
    return out


def perception(per: dict, names: Sequence[str]) -> dict:
    """Felt distances (dB), W2 beside, and felt levels (module docstring, step 5)."""
    pat_src = {n: P.map_pattern(per[n]["_map"]) for n in names}
    pt_src = {n: pat_src[n].felt_point() for n in names}
    out = {}
    for n in names:
        pats = [P.map_pattern(p) for p in per[n]["_paintings"][:2]]
        pts = [p.felt_point() for p in pats]
        others = {o: pt_src[n].distance(pt_src[o]) for o in names if o != n}
        nearest = min(others, key=lambda o: others[o])
        out[n] = {"source_painting": pt_src[n].distance(pts[0]),
                  "source_painting2": pt_src[n].distance(pts[1]),
                  "painting_painting2": pts[0].distance(pts[1]),
                  "w2_source_painting": P.w2_db(pat_src[n], pats[0]),
                  "felt_source": pt_src[n].as_dict(), "felt_painting": pts[0].as_dict(),
                  "nearest_other": nearest, "to_nearest_other": others[nearest],
                  "to_others_median": _median(list(others.values())),
                  "level_source_db": pat_src[n].level_db, "level_painting_db": pats[0].level_db}
    return out


def run(names: Sequence[str] = S.TEXTURES, swipes: int = S.SWIPES_PER_TEXTURE,
        paint_seeds: Sequence[int] = tuple(range(DEFAULT_PAINT_SEEDS)), seed: int = 0,
        model: S.SwipeModel = S.SwipeModel(), samples: int = S.SCREEN_SAMPLES,
        progress: Progress | None = None) -> dict:
    """The whole report as a dict (numpy arrays and the maps inside: jsonable
    for JSON leaves the maps out)."""
    names = list(names)
    paint_seeds = [int(s) for s in paint_seeds]
    if len(names) < 2 or len(set(names)) != len(names):
        raise ValueError("names: expected at least 2 different sources, got %r" % (names,))
    if not (isinstance(swipes, int) and swipes >= 2):
        raise ValueError("swipes: expected an int >= 2 (a silhouette needs two), got %r"
                         % (swipes,))
    if len(paint_seeds) < 2:
        raise ValueError("paint_seeds: expected at least 2 (a second painting for scale)")
    say = progress or (lambda msg: None)
    t_start = time.perf_counter()
    lags = acf_lags()
    per = {}
    for n_done, name in enumerate(names):
        i = S.TEXTURES.index(name) if name in S.TEXTURES else len(S.TEXTURES) + n_done
        t0 = time.perf_counter()
        per[name] = _source(i, name, swipes, paint_seeds, seed, model, samples, lags)
        say("%2d/%d %-14s brush, %d paintings, %d + %d swipes fitted (%.1f s); painting's "
            "r at 1 window %+.3f (source %+.3f)"
            % (n_done + 1, len(names), name, len(paint_seeds), swipes, swipes,
               time.perf_counter() - t0, per[name]["acf"]["painting_mean"]["1W"],
               per[name]["acf"]["source"]["1W"]))
    say("comparing (4 metrics, silhouettes, nearest texture) and the perceptual distances")
    cmp_ = compare_swipes(per, names)
    perc = perception(per, names)
    return {
        "config": {"sources": names, "swipes": swipes, "paint_seeds": paint_seeds, "seed": seed,
                   "model": dataclasses.asdict(model), "samples": samples,
                   "window": B.WINDOW, "hop": B.HOP, "wavenumbers": B.K,
                   "brush_format": D.FORMAT, "dx_mm": DX_MM, "lags": lags,
                   "acf_limit": ACF_LIMIT, "metrics": list(C.METRICS),
                   "perception_model": P.DEFAULT_MODEL.as_dict()},
        "sources": per,
        "compare": cmp_,
        "perception": perc,
        "seconds": time.perf_counter() - t_start,
    }


# --- the report -----------------------------------------------------------------------
def _lag_columns(lags: dict[str, int]) -> list[str]:
    """The lags printed: 1, 2 and 10 windows (those there are), 2 mm, 10 mm."""
    return [k for k in ("1W", "2W", "10W") if k in lags] + ["%gmm" % mm for mm in MM_LAGS]


def _para(text: str) -> str:
    return textwrap.fill(text, 100)


def format_tables(res: dict) -> str:
    # each table ends with its blank line
    return "\n".join(_intro(res) + [""] + _fits_table(res) + _distance_tables(res)
                     + _silhouettes(res) + _feel_table(res) + _acf_table(res))


def _intro(res: dict) -> list[str]:
    cfg = res["config"]
    names = cfg["sources"]
    w_mm = cfg["window"] * cfg["dx_mm"]
    return [_para(
        "What painting makes: %d sources, each fitted to a brush (%s; window %d samples = "
        "%.4f mm, hop %d, %d wavenumbers), painted with seeds %s (%d samples each); %d swipes "
        "of each source and %d of its paintings (SwipeModel, %d samples), Weibull per "
        "wavenumber per swipe."
        % (len(names), cfg["brush_format"], cfg["window"], w_mm, cfg["hop"], cfg["wavenumbers"],
           ", ".join(map(str, cfg["paint_seeds"])), cfg["samples"], cfg["swipes"],
           cfg["swipes"], cfg["model"]["length_samples"]))]


def _fits_table(res: dict) -> list[str]:
    names, per = res["config"]["sources"], res["sources"]
    lines = []
    lines.append("Fits (mean K-S of the Weibull fits; brush: the source map's, over all its "
                 "windows):")
    lines.append("  %-14s %8s %10s %12s %13s %9s" % ("source", "windows", "brush K-S",
                                                     "source swipe", "painted swipe", "paint s"))
    for n in names:
        p = per[n]
        lines.append("  %-14s %8d %10.3f %12.3f %13.3f %9.2f" % (
            n, p["brush"]["windows"], p["brush"]["ks_mean"],
            statistics.mean(s["weibull_ks_mean"] for s in p["source_swipes"]),
            statistics.mean(s["weibull_ks_mean"] for s in p["painted_swipes"]), p["paint_s"]))
    lines.append("")
    return lines


def _distance_tables(res: dict) -> list[str]:
    names = res["config"]["sources"]
    lines = []
    lines.append(_para(
        "Distances between swipes' Weibull vectors (seed 002's metrics), median over pairs: "
        "within the source's swipes, source-to-painting, within the painting's, to the nearest "
        "other source; ratio = src-paint / within (1: a painted swipe is as close to the "
        "source's swipes as they are to each other). Silhouette of the source's swipes "
        "(leave-one-out) and of the painted swipes against the sources' clusters; nearest "
        "texture: swipes taken for their source (of how many)."))
    row = "  %-14s %9.4g %9.4g %6.2f %9.4g  %-13s %8.4g %7.3f %7.3f %5d/%-2d %5d/%-2d"
    for me in C.METRICS:
        c = res["compare"][me]
        lines.append("")
        lines.append("  %s" % C.METRIC_LABELS[me])
        lines.append("  %-14s %9s %9s %6s %9s  %-22s %7s %7s %8s %8s" % (
            "source", "within", "src-paint", "ratio", "paint", "nearest other source",
            "sil src", "sil pnt", "src ok", "pnt ok"))
        for n in names:
            r = c["sources"][n]
            lines.append(row % (n, r["within_source"], r["source_to_painting"], r["ratio"],
                                r["within_painting"], r["nearest_other"], r["to_nearest_other"],
                                r["silhouette_source"], r["silhouette_painted"],
                                r["correct_source"], len(r["classified_source"]),
                                r["correct_painted"], len(r["classified_painted"])))
        lines.append("  %-14s %26s %5.2f %9s  %-22s %7.3f %7.3f %7.0f%% %7.0f%%" % (
            "all", "median ratio", c["ratio_median"], "", "", c["silhouette_source_swipes_mean"],
            c["silhouette_painted_swipes_mean"], 100 * c["accuracy_source"],
            100 * c["accuracy_painted"]))
    lines.append("")
    return lines


def _silhouettes(res: dict) -> list[str]:
    lines = []
    lines.append(_para(
        "Silhouette of the swipes clustered by source (Weibull; seed 002 Table II's column on "
        "our data), the sources' swipes alone / with the painted swipes labelled as their "
        "source:"))
    for me in C.METRICS:
        c = res["compare"][me]
        lines.append("  %-24s %7.3f / %7.3f" % (C.METRIC_LABELS[me], c["silhouette_sources"],
                                                c["silhouette_with_paintings"]))
    lines.append("")
    return lines


def _feel_table(res: dict) -> list[str]:
    names = res["config"]["sources"]
    lines = []
    lines.append(_para(
        "How it feels (texelpad.analysis.perception, dB on the felt plane: felt pitch and "
        "noisiness; under 1 dB the same; W2: the felt spectra's 2-Wasserstein distance; levels "
        "beside, re a full-scale sine):"))
    lines.append("  %-14s %9s %9s %9s  %-22s %8s %8s %10s %11s" % (
        "source", "src-pnt0", "src-pnt1", "pnt0-pnt1", "nearest other source", "others",
        "W2 s-p0", "level src", "level pnt0"))
    for n in names:
        r = res["perception"][n]
        lines.append("  %-14s %9.2f %9.2f %9.2f  %-13s %8.2f %8.2f %8.2f %10.1f %11.1f" % (
            n, r["source_painting"], r["source_painting2"], r["painting_painting2"],
            r["nearest_other"], r["to_nearest_other"], r["to_others_median"],
            r["w2_source_painting"], r["level_source_db"], r["level_painting_db"]))
    lines.append("  (others: the median over the other sources)")
    lines.append("")
    return lines


def _acf_table(res: dict) -> list[str]:
    cfg = res["config"]
    names, per = cfg["sources"], res["sources"]
    w_mm = cfg["window"] * cfg["dx_mm"]
    lines = []
    lags = cfg["lags"]
    cols = _lag_columns(lags)
    nw = sum(1 for k in lags if k.endswith("W"))
    lines.append(_para(
        "Autocorrelation r at whole windows (W = %d samples = %.4f mm) and at %s (%s samples); "
        "painting: the mean over its seeds; max|r|: over all %d window multiples up to %g mm "
        "and the mm lags (painting: the worst seed); issue 21 wants a painting's |r| <= %g "
        "there:"
        % (cfg["window"], w_mm, " and ".join("%g mm" % mm for mm in MM_LAGS),
           ", ".join(str(lags["%gmm" % mm]) for mm in MM_LAGS), nw, ACF_MAX_MM,
           cfg["acf_limit"])))
    lines.append("  %-14s %-9s " % ("source", "map") + " ".join("%7s" % c for c in cols)
                 + " %7s  %s" % ("max|r|", "|r|<=%g" % cfg["acf_limit"]))
    met = 0
    for n in names:
        a = per[n]["acf"]
        src = " ".join("%+7.3f" % a["source"][c] for c in cols)
        pnt = " ".join("%+7.3f" % a["painting_mean"][c] for c in cols)
        lines.append("  %-14s %-9s %s %7.3f" % (n, "source", src, a["max_abs_source"]))
        lines.append("  %-14s %-9s %s %7.3f  %s" % ("", "painting", pnt, a["max_abs_painting"],
                                                   "yes" if a["criterion_met"] else "NO"))
        met += a["criterion_met"]
    lines.append("  paintings meeting |r| <= %g at every lag: %d of %d"
                 % (cfg["acf_limit"], met, len(names)))
    return lines


# --- the figure -----------------------------------------------------------------------
def figure(res: dict, path: str, sources: Sequence[str] = FIGURE_SOURCES) -> str:
    """For each of `sources` in the report (else its first two): the source
    map over SHOW_MM, its painting (seed 0) over the same span, and both
    autocorrelations against lag 0 .. ACF_MAX_MM mm with the window multiples
    and 2 / 10 mm marked (matplotlib Agg canvas, pyplot untouched)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    names = res["config"]["sources"]
    show = [n for n in sources if n in names] or names[:2]
    per = res["sources"]
    n_show = lag_samples(SHOW_MM)
    max_lag = lag_samples(ACF_MAX_MM)
    w_mm = window_mm()
    fig = Figure(figsize=(13.0, 2.9 * len(show)), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(show), 3, squeeze=False, gridspec_kw={"width_ratios": [1, 1, 1.5]})
    x = np.arange(n_show) * DX_MM
    lag_mm = np.arange(max_lag + 1) * DX_MM
    seed0 = res["config"]["paint_seeds"][0]
    for row, name in zip(axes, show):
        src = per[name]["_map"]
        pnt = per[name]["_paintings"][0]
        for ax, y, label, colour in ((row[0], src, "source: %s" % name, "0.3"),
                                     (row[1], pnt, "its painting (seed %d)" % seed0, "C0")):
            for j in range(1, int(SHOW_MM / w_mm) + 1):
                ax.axvline(j * w_mm, color="0.8", lw=0.7, zorder=0)
            ax.plot(x, y[:n_show], lw=0.6, color=colour)
            ax.set_xlim(0, SHOW_MM)
            ax.set_ylim(-0.02, 1.02)
            ax.set_title(label, fontsize=9, loc="left")
            ax.set_ylabel("amplitude", fontsize=8)
        r_src = autocorrelation(src, max_lag)
        r_pnt = autocorrelation(pnt, max_lag)
        ax = row[2]
        ax.axhspan(-ACF_LIMIT, ACF_LIMIT, color="C2", alpha=0.12, lw=0,
                   label="|r| <= %g" % ACF_LIMIT)
        for j in range(1, int(ACF_MAX_MM / w_mm) + 1):
            ax.axvline(j * w_mm, color="0.75", lw=0.7, ls=":", zorder=0,
                       label="window multiples" if j == 1 else None)
        for mm in MM_LAGS:
            ax.axvline(lag_samples(mm) * DX_MM, color="C3", lw=0.9, ls="--", zorder=0)
            ax.text(lag_samples(mm) * DX_MM, 1.0, " %g mm" % mm, color="C3", fontsize=7,
                    va="top")
        ax.plot(lag_mm, r_pnt, lw=0.7, color="C0", label="painting")
        ax.plot(lag_mm, r_src, lw=0.7, color="0.2", label="source")
        ax.set_xlim(0, ACF_MAX_MM)
        ax.set_ylim(-1.05, 1.05)
        ax.set_ylabel("autocorrelation r", fontsize=8)
        ax.set_title("r at 1 window (%.4f mm): source %+.2f, painting %+.2f"
                     % (w_mm, r_src[B.WINDOW], r_pnt[B.WINDOW]), fontsize=9, loc="left")
        ax.legend(fontsize=7, loc="lower right", ncol=2)
    axes[-1][0].set_xlabel("position (mm)")
    axes[-1][1].set_xlabel("position (mm)")
    axes[-1][2].set_xlabel("lag (mm)")
    fig.suptitle("What painting makes: a source map, the painting of the brush fitted to it, and "
                 "both autocorrelations (window %d samples, %s)"
                 % (B.WINDOW, res["config"]["brush_format"]), fontsize=10)
    fig.savefig(path, dpi=90)
    return path


def _cannot_write(path: str) -> str | None:
    p = Path(path)
    parent = p.parent if str(p.parent) else Path(".")
    if p.is_dir():
        return "is a directory"
    if not parent.is_dir():
        return "no such directory: %s" % parent
    if not os.access(parent, os.W_OK):
        return "permission denied"
    return None


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m bench.brush_painting",
                                description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true",
                   help="%d swipes per source and %d painting seeds (unless given)"
                   % (QUICK_SWIPES, QUICK_PAINT_SEEDS))
    p.add_argument("--sources", metavar="A,B,...",
                   help="sources (default: all of %s)" % ", ".join(S.TEXTURES))
    p.add_argument("--swipes", type=int, help="swipes of each source and of its paintings "
                   "(default %d, --quick %d)" % (S.SWIPES_PER_TEXTURE, QUICK_SWIPES))
    p.add_argument("--paint-seeds", type=int, help="paintings per source, seeds 0 .. N-1 "
                   "(default %d, --quick %d)" % (DEFAULT_PAINT_SEEDS, QUICK_PAINT_SEEDS))
    p.add_argument("--seed", type=int, default=0, help="swipe seed (default %(default)s)")
    p.add_argument("--json", metavar="PATH")
    p.add_argument("--figure", metavar="PATH", nargs="?", const=DEFAULT_FIGURE,
                   help="write the figure (default path: %s)" % DEFAULT_FIGURE)
    a = p.parse_args(argv)
    swipes = a.swipes if a.swipes is not None else (QUICK_SWIPES if a.quick
                                                     else S.SWIPES_PER_TEXTURE)
    seeds = a.paint_seeds if a.paint_seeds is not None else (QUICK_PAINT_SEEDS if a.quick
                                                             else DEFAULT_PAINT_SEEDS)
    if swipes < 2:
        p.error("--swipes: expected >= 2 (a silhouette needs two swipes of a source)")
    if seeds < 2:
        p.error("--paint-seeds: expected >= 2 (a second painting gives the scale)")
    if a.seed < 0:
        p.error("--seed: expected >= 0")
    names = list(S.TEXTURES)
    if a.sources:
        names = [n.strip() for n in a.sources.split(",") if n.strip()]
        bad = [n for n in names if n not in S.TEXTURES]
        if bad:
            p.error("--sources: unknown %r (known: %s)" % (bad[0], ", ".join(S.TEXTURES)))
        if len(set(names)) < 2:
            p.error("--sources: expected at least 2 different sources")
    for flag, path in (("--json", a.json), ("--figure", a.figure)):
        why = _cannot_write(path) if path else None
        if why:
            print("brush_painting: %s %s: %s" % (flag, path, why), file=sys.stderr)
            return 1

    def progress(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    res = run(names=names, swipes=swipes, paint_seeds=tuple(range(seeds)), seed=a.seed,
              progress=progress)
    print(format_tables(res))
    print("\n%d sources, %d swipes fitted, in %.1f s"
          % (len(names), 2 * swipes * len(names), res["seconds"]))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(jsonable(res), f, allow_nan=False)
        print("wrote", a.json)
    if a.figure:
        figure(res, a.figure)
        print("wrote", a.figure)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

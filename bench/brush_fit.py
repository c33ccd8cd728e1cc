"""Benchmark and report for the Tactile Paintbrush's analysis (seed 002 §III;
issue 12 items 1-2): noisy swipes of the eleven textures we have, each
transformed and fitted per wavenumber with Rayleigh, Rice and Weibull, then
the paper's comparison.

    .venv/bin/python -m bench.brush_fit [--swipes N] [--seed S] [--jobs J]
        [--json PATH] [--figure-dir DIR]

What it does (texelpad.brush: swipes, transform, fits, compare):
- swipes: --swipes per texture (default 10) of texelpad.brush.swipes.TEXTURES
  (the nine references and two texel renderings, a full screen each) under
  the default SwipeModel (9,600 samples = 197 windows; start, 3 % slow warp,
  5 % gain, 0.02 friction noise; swipes.py's docstring), seeded by --seed;
- per swipe: the space-frequency transform (transform.stft_magnitudes) and
  fits.fit_swipe per model, timed (wall clock, perf_counter; the transform
  once, each model's fits and K-S separately), plus one full-screen swipe
  (19,200 samples, 397 windows) for the scale the issue quotes;
- prints the fit time per swipe, the K-S table per texture and model (mean
  over swipes; all wavenumbers and per band, compare.BANDS; "best" = the
  share of (swipe, wavenumber) cells where the model has the lowest K-S),
  the model that fits best per band, and the silhouette table (seed 002
  Table II: model x metric, with the paper's values beside);
- --json: everything, every swipe's parameters included;
- --figure-dir: brush-ks.png (like seed 002 Fig. 4: K-S per swipe and
  wavenumber per model, histograms below) and brush-mds.png (like Fig. 5:
  MDS of the swipes for every model x metric, texture averages marked).

--jobs J fits in J processes (default: 2, or 1 on a one-core machine); the
times per swipe are each process's own wall clock. Never fails on time; the
default run takes well under two minutes on two cores.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import statistics
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Callable

import numpy as np

from texel.gen.brush import HOP, K, WINDOW

from . import jsonable
from texelpad.brush import compare as C
from texelpad.brush import fits as F
from texelpad.brush import swipes as S
from texelpad.brush import transform as T

Progress = Callable[[str], None]
# seed 002 Table II: silhouette coefficients (rows: metric; columns: Rayleigh, Rice, Weibull)
PAPER_SILHOUETTE = {
    "euclidean": {"rayleigh": -0.074, "rice": -0.157, "weibull": 0.098},
    "seuclidean": {"rayleigh": 0.107, "rice": 0.009, "weibull": 0.033},
    "canberra": {"rayleigh": 0.069, "rice": 0.017, "weibull": 0.055},
    "braycurtis": {"rayleigh": -0.067, "rice": -0.065, "weibull": 0.154},
}
PAPER_MEAN_KS = {"rayleigh": 0.173, "rice": 0.164, "weibull": 0.077}    # seed 002 Fig. 4
FIGURE_NAMES = ("brush-ks.png", "brush-mds.png")
DEFAULT_JOBS = min(2, os.cpu_count() or 1)


def _fit_timed(friction: np.ndarray) -> tuple[dict, dict]:
    """(fit, seconds) of one swipe: the transform, then each model alone."""
    t0 = time.perf_counter()
    mags = T.stft_magnitudes(friction)
    secs = {"transform": time.perf_counter() - t0}
    fit: dict = {}
    for mo in F.MODELS:
        t0 = time.perf_counter()
        r = F.fit_swipe(mags, models=(mo,))
        secs[mo] = time.perf_counter() - t0
        fit[mo] = r[mo]
        fit["degenerate"], fit["windows"] = r["degenerate"], r["windows"]
        fit.setdefault("fallbacks", {})[mo] = r["fallbacks"][mo]
    secs["total"] = sum(secs.values())
    return fit, secs


def run(swipes_per_texture: int = S.SWIPES_PER_TEXTURE, seed: int = 0, names=S.TEXTURES,
        model: S.SwipeModel = S.SwipeModel(), jobs: int = 1, full_screen: bool = True,
        mds: bool = True, progress: Progress | None = None) -> dict:
    """The whole report as a dict (numpy arrays inside; jsonable for JSON)."""
    t_start = time.perf_counter()
    say = progress or (lambda msg: None)
    sw = S.make_swipes(swipes_per_texture, seed=seed, names=names, model=model)
    say("%d swipes of %d textures made" % (len(sw), len(names)))
    if jobs > 1:
        with ProcessPoolExecutor(max_workers=jobs) as ex:
            done = list(ex.map(_fit_timed, [s.friction for s in sw], chunksize=4))
    else:
        done = []
        for i, s in enumerate(sw):
            done.append(_fit_timed(s.friction))
            if (i + 1) % max(1, swipes_per_texture) == 0:
                say("fitted %d/%d swipes (%s)" % (i + 1, len(sw), s.texture))
    fits = [d[0] for d in done]
    secs = [d[1] for d in done]
    labels = [s.texture for s in sw]
    full = None
    if full_screen:
        # one full-screen swipe (19,200 samples: 397 windows), the size the issue quotes
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(10**6,)))
        fs = S.swipe(S.texture("white", 2 * S.SCREEN_SAMPLES), rng,
                     S.SwipeModel(length_samples=S.SCREEN_SAMPLES))
        f_full, s_full = _fit_timed(fs.friction)
        full = {"samples": S.SCREEN_SAMPLES, "windows": f_full["windows"], "seconds": s_full}
    say("comparing (silhouettes%s)" % (", MDS" if mds else ""))
    rows = C.ks_table(fits, labels)
    cons = C.consistency(fits, labels, mds=mds)
    return {
        "config": {"swipes_per_texture": swipes_per_texture, "seed": seed, "textures": list(names),
                   "model": dataclasses.asdict(model), "window": WINDOW, "hop": HOP, "wavenumbers": K,
                   "k_max": F.K_MAX, "jobs": jobs, "metrics": list(C.METRICS),
                   "models": list(F.MODELS), "bands": [list(b) for b in C.BANDS]},
        "swipes": [{"texture": s.texture, "index": s.index, "start_mm": s.start_mm,
                    "gain": s.gain, "stretch": s.stretch, "seconds": t, "fit": f}
                   for s, f, t in zip(sw, fits, secs)],
        "full_screen": full,
        "ks_table": rows,
        "best_by_band": C.best_by_band(rows),
        "silhouette": cons["silhouette"],
        "mds": cons.get("mds"),
        "labels": labels,
        "seconds": time.perf_counter() - t_start,
    }


def _med(xs):
    return statistics.median(xs) if xs else math.nan


def format_tables(res: dict) -> str:
    cfg = res["config"]
    sw = res["swipes"]
    lines = []
    win = sw[0]["fit"]["windows"]
    lines.append("Fit time per swipe (%d swipes of %d windows = %d samples; wall clock, %s):"
                 % (len(sw), win, (win - 1) * HOP + WINDOW,
                    "1 process" if cfg["jobs"] == 1 else "%d processes" % cfg["jobs"]))
    lines.append("  %-10s %9s %9s %9s" % ("step", "median", "min", "max"))
    for key in ("transform",) + F.MODELS + ("total",):
        xs = [s["seconds"][key] for s in sw]
        lines.append("  %-10s %8.3fs %8.3fs %8.3fs" % (key, _med(xs), min(xs), max(xs)))
    full = res.get("full_screen")
    if full:
        s = full["seconds"]
        lines.append("  full-screen swipe (%d samples, %d windows): %.3f s (rayleigh %.3f, "
                     "rice %.3f, weibull %.3f)" % (full["samples"], full["windows"], s["total"],
                                                    s["rayleigh"], s["rice"], s["weibull"]))
    falls = {mo: sum(s["fit"]["fallbacks"][mo] for s in sw) for mo in F.MODELS}
    degen = sum(int(np.sum(s["fit"]["degenerate"])) for s in sw)
    capped = sum(int(np.sum((np.asarray(s["fit"]["weibull"]["k"]) >= F.K_MAX)
                            & ~np.asarray(s["fit"]["degenerate"]))) for s in sw)
    lines.append("  cells: %d (swipes x wavenumbers); degenerate %d; Weibull k capped at %g: %d; "
                 "optimiser fallbacks %s" % (len(sw) * K, degen, F.K_MAX, capped,
                                             ", ".join("%s %d" % kv for kv in falls.items())))
    lines.append("")
    bands = [b[0] for b in C.BANDS]
    lines.append("K-S statistic, mean over swipes (columns: all wavenumbers, then bands of k; "
                 "best = share of cells where the model has the lowest K-S):")
    lines.append("  %-14s %-9s %6s " % ("texture", "model", "mean")
                 + " ".join("%6s" % ("k=" + b if b in ("0", "1") else b) for b in bands)
                 + " %6s" % "best")
    last = None
    for r in res["ks_table"]:
        if last is not None and r["texture"] != last:
            lines.append("")
        last = r["texture"]
        lines.append("  %-14s %-9s %6.3f " % (r["texture"], r["model"], r["mean"])
                     + " ".join("%6.3f" % r[b] for b in bands) + " %5.0f%%" % (100 * r["best"]))
    lines.append("  (seed 002 Fig. 4, all textures: rayleigh %.3f, rice %.3f, weibull %.3f)"
                 % tuple(PAPER_MEAN_KS[m] for m in F.MODELS))
    lines.append("")
    lines.append("Lowest mean K-S per band:")
    lines.append("  %-14s " % "texture" + " ".join("%-9s" % ("k=" + b if b in ("0", "1") else b)
                                                    for b in bands + ["mean"]))
    for tex, best in res["best_by_band"].items():
        lines.append("  %-14s " % tex + " ".join("%-9s" % best[b] for b in bands + ["mean"]))
    lines.append("")
    lines.append("Silhouette coefficients of the swipes clustered by texture (seed 002 Table II; "
                 "the paper's in brackets):")
    lines.append("  %-24s " % "" + " ".join("%-17s" % m.capitalize() for m in F.MODELS))
    for me in C.METRICS:
        lines.append("  %-24s " % C.METRIC_LABELS[me] + " ".join(
            "%6.3f (%6.3f)   " % (res["silhouette"][mo][me], PAPER_SILHOUETTE[me][mo])
            for mo in F.MODELS))
    return "\n".join(lines)


def ks_figure(res: dict, path: str) -> None:
    """Seed 002 Fig. 4: per model, the K-S statistic of every swipe (rows,
    grouped by texture) and wavenumber (columns), light = low = a good fit;
    below, the histogram of all of them with its mean (matplotlib Agg canvas,
    pyplot's global state untouched, as texelpad.analysis.figures)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    sw = res["swipes"]
    labels = [s["texture"] for s in sw]
    fig = Figure(figsize=(13.5, 7.2), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 3, gridspec_kw={"height_ratios": [3.2, 1.0]})
    groups = list(dict.fromkeys(labels))
    for j, mo in enumerate(F.MODELS):
        img = np.stack([np.asarray(s["fit"][mo]["ks"], dtype=float) for s in sw])
        ax = axes[0][j]
        im = ax.imshow(img, aspect="auto", cmap="viridis_r", vmin=0.0, vmax=1.0,
                       interpolation="nearest", extent=(-0.5, K - 0.5, len(sw) - 0.5, -0.5))
        for g in groups[1:]:
            ax.axhline(labels.index(g) - 0.5, color="white", lw=0.6)
        ax.set_yticks([labels.index(g) + labels.count(g) / 2 - 0.5 for g in groups])
        ax.set_yticklabels(groups if j == 0 else [], fontsize=7)
        ax.set_xlabel("wavenumber (k cycles per %.4f mm window)" % (WINDOW * 0.0053))
        ax.set_title("%s fit errors" % mo.capitalize())
        h = axes[1][j]
        h.hist(img.ravel(), bins=50, range=(0, 1), color="C0")
        h.set_title("mean K-S: %.3f (paper %.3f)" % (img.mean(), PAPER_MEAN_KS[mo]), fontsize=9)
        h.set_xlabel("K-S statistic")
        if j == 0:
            h.set_ylabel("count")
            ax.set_ylabel("texture (swipes)")
    fig.colorbar(im, ax=axes[0].tolist(), shrink=0.8, label="K-S statistic")
    fig.suptitle("K-S statistics of the per-wavenumber fits: %d swipes of %d textures "
                 "(texelpad.brush.swipes)" % (len(sw), len(groups)))
    fig.savefig(path, dpi=90)


def mds_figure(res: dict, path: str) -> None:
    """Seed 002 Fig. 5, all twelve panels: the MDS embedding of the swipes
    per model (columns) and distance metric (rows), one colour per texture,
    each texture's average position ringed."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    labels = res["labels"]
    groups = list(dict.fromkeys(labels))
    lab = np.asarray(labels)
    fig = Figure(figsize=(12.5, 15.0), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(C.METRICS), len(F.MODELS))
    colours = ([f"C{i}" for i in range(10)] + ["black", "0.55", "gold"]) * 2
    markers = ["o"] * 13 + ["s"] * 13
    for i, me in enumerate(C.METRICS):
        for j, mo in enumerate(F.MODELS):
            ax = axes[i][j]
            pts = np.asarray(res["mds"][mo][me]["points"], dtype=float)
            for g, c, mk in zip(groups, colours, markers):
                p = pts[lab == g]
                ax.scatter(p[:, 0], p[:, 1], s=12, color=c, marker=mk, alpha=0.75,
                           label=g, lw=0)
                m = p.mean(axis=0)
                ax.scatter([m[0]], [m[1]], s=90, facecolor=c, edgecolor="black", marker=mk, lw=1.2)
            ax.set_title("%s model, %s distances\nsilhouette: %.3f"
                         % (mo.capitalize(), C.METRIC_LABELS[me], res["silhouette"][mo][me]),
                         fontsize=9)
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_aspect("equal", adjustable="datalim")
    axes[0][0].legend(fontsize=7, loc="best", markerscale=1.5, ncol=2)
    fig.suptitle("MDS of the swipes' parameter vectors (small: swipes; large, ringed: "
                 "each texture's average)")
    fig.savefig(path, dpi=80)


def _unwritable_dir(path: str) -> str | None:
    p = Path(path)
    if not p.is_dir():
        return "no such directory"
    if not os.access(p, os.W_OK):
        return "permission denied"
    return None


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m bench.brush_fit", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--swipes", type=int, default=S.SWIPES_PER_TEXTURE,
                   help="swipes per texture (default %(default)s)")
    p.add_argument("--seed", type=int, default=0, help="swipe seed (default %(default)s)")
    p.add_argument("--jobs", type=int, default=DEFAULT_JOBS,
                   help="fitting processes (default %(default)s: up to 2 cores)")
    p.add_argument("--json", metavar="PATH")
    p.add_argument("--figure-dir", metavar="DIR",
                   help="write %s there (e.g. docs/img)" % " and ".join(FIGURE_NAMES))
    a = p.parse_args(argv)
    if a.swipes < 2:
        p.error("--swipes: expected >= 2 (a silhouette needs two swipes of a texture)")
    if a.jobs < 1 or a.seed < 0:
        p.error("--jobs: expected >= 1; --seed: expected >= 0")
    if a.figure_dir:
        why = _unwritable_dir(a.figure_dir)
        if why:
            print("brush_fit: --figure-dir %s: %s" % (a.figure_dir, why), file=sys.stderr)
            return 1
    if a.json:
        parent = Path(a.json).parent
        if Path(a.json).is_dir() or not (parent if str(parent) else Path(".")).is_dir():
            print("brush_fit: --json: cannot write %s" % a.json, file=sys.stderr)
            return 1

    def progress(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    res = run(swipes_per_texture=a.swipes, seed=a.seed, jobs=a.jobs,
              mds=bool(a.figure_dir or a.json), progress=progress)
    print(format_tables(res))
    print("\n%d swipes in %.1f s" % (len(res["swipes"]), res["seconds"]))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(jsonable(res), f)
    if a.figure_dir:
        ks_figure(res, os.path.join(a.figure_dir, FIGURE_NAMES[0]))
        mds_figure(res, os.path.join(a.figure_dir, FIGURE_NAMES[1]))
        print("figures: %s" % ", ".join(os.path.join(a.figure_dir, n) for n in FIGURE_NAMES))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

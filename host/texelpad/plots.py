"""Figures for the command line (matplotlib, drawn off-screen with the Agg
canvas; pyplot and its global backend state are never touched)."""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

import texel


def pitch_normal_pdf(db: np.ndarray, pitch_db: float, irregularity_db: float) -> np.ndarray:
    """Density of a texel's pitch in dB: 10*log10 f ~ Normal(pitch_db, 10*sigma)
    with sigma = 10^(irregularity_db/10) decades (log10 f ~ Normal(log10 P, sigma))."""
    sd = 10.0 * 10.0 ** (irregularity_db / 10.0)
    return np.exp(-0.5 * ((db - pitch_db) / sd) ** 2) / (sd * math.sqrt(2 * math.pi))


def spectrum(fmap: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One-sided amplitude spectrum of the map (mean removed, Hann window):
    spatial frequency in cycles/mm and amplitude in map units."""
    n = fmap.size
    w = np.hanning(n) if n > 1 else np.ones(1)
    a = np.abs(np.fft.rfft((fmap - fmap.mean()) * w)) * 2.0 / max(w.sum(), 1e-300)
    f = np.fft.rfftfreq(n, d=texel.DX_MM)
    return f, a


def render_figure(fmap: np.ndarray, plan: Any, path: str | Path, engine: str = "") -> None:
    """Map, spectrum and texel pitch histogram of one rendering, as a PNG."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    p = plan.params
    fig = Figure(figsize=(10, 11.5), layout="constrained")
    FigureCanvasAgg(fig)
    ax_map, ax_zoom, ax_spec, ax_hist = fig.subplots(4, 1)
    sigma = 10.0 ** (p["irregularity_db"] / 10.0)
    fig.suptitle("pitch %.2f dB (%.3g c/mm), irregularity %.2f dB (%.3g decade), seed %d, "
                 "%d texel%s of %d samples%s" % (
                     p["pitch_db"], 10 ** (p["pitch_db"] / 10), p["irregularity_db"], sigma,
                     p["seed"], plan.count, "" if plan.count == 1 else "s", plan.L,
                     (", " + engine) if engine else ""))

    x = np.arange(fmap.size) * texel.DX_MM
    ax_map.plot(x, fmap, lw=0.4, color="C0")
    ax_map.set_xlim(0, max(x[-1], texel.DX_MM))
    ax_map.set_ylim(-0.02, 1.02)
    ax_map.set_xlabel("position (mm)")
    ax_map.set_ylabel("friction reduction")
    ax_map.set_title("friction map (%d samples, %.2f mm)" % (fmap.size, fmap.size * texel.DX_MM))

    # zoom: the first 8 texels (at least 100 samples), texel borders marked
    nz = int(min(fmap.size, max(100, 8 * plan.L)))
    ax_zoom.plot(x[:nz], fmap[:nz], lw=0.8, color="C0", marker="." if nz <= 400 else None,
                 ms=2)
    for k in range(plan.L, nz, plan.L):
        if nz // plan.L <= 40:
            ax_zoom.axvline(k * texel.DX_MM, color="0.8", lw=0.6, zorder=0)
    ax_zoom.set_xlim(0, max(x[nz - 1], texel.DX_MM))
    ax_zoom.set_ylim(-0.02, 1.02)
    ax_zoom.set_xlabel("position (mm)")
    ax_zoom.set_ylabel("friction reduction")
    ax_zoom.set_title("first %d samples (%.3g mm)%s" % (
        nz, nz * texel.DX_MM, ", texel borders in grey" if plan.L < nz else ""))

    f, a = spectrum(fmap)
    keep = f > 0
    if keep.any():
        ax_spec.loglog(f[keep], np.maximum(a[keep], 1e-12), lw=0.5, color="C0")
    ax_spec.axvline(texel.NYQUIST_CPMM, color="C3", ls="--", lw=1,
                    label="Nyquist %.1f c/mm" % texel.NYQUIST_CPMM)
    ax_spec.axvline(10 ** (p["pitch_db"] / 10), color="C2", ls=":", lw=1.2,
                    label="central pitch %.3g c/mm" % 10 ** (p["pitch_db"] / 10))
    ax_spec.set_xlabel("spatial frequency (cycles/mm)")
    ax_spec.set_ylabel("amplitude")
    ax_spec.set_title("spectrum (Hann window, mean removed)")
    ax_spec.legend(loc="lower left", fontsize="small")

    db = 10.0 * np.log10(np.asarray(plan.f, dtype=np.float64))
    sd = 10.0 * sigma
    lo = min(db.min(), p["pitch_db"] - 4 * sd)
    hi = max(db.max(), p["pitch_db"] + 4 * sd)
    if hi - lo < 1e-6:
        lo, hi = lo - 0.5, hi + 0.5
    bins = int(min(80, max(10, math.sqrt(db.size) * 2)))
    ax_hist.hist(db, bins=np.linspace(lo, hi, bins + 1), density=True, color="C0", alpha=0.6,
                 label="texel pitches (%d)" % db.size)
    grid = np.linspace(lo, hi, 400)
    ax_hist.plot(grid, pitch_normal_pdf(grid, p["pitch_db"], p["irregularity_db"]), color="C1",
                 lw=1.5, label="Normal(%.2f dB, %.3g dB)" % (p["pitch_db"], sd))
    nyq_db = 10 * math.log10(texel.NYQUIST_CPMM)
    if lo <= nyq_db <= hi:
        ax_hist.axvline(nyq_db, color="C3", ls="--", lw=1, label="Nyquist (%.0f%% of texels above)"
                        % (100 * plan.fraction_above_nyquist()))
    ax_hist.set_xlim(lo, hi)
    ax_hist.set_xlabel("texel pitch (dB re 1 cycle/mm)")
    ax_hist.set_ylabel("density (1/dB)")
    ax_hist.set_title("texel pitch histogram against the drawing distribution"
                      + (" (quantized %g dB)" % p["quant_db"] if p["quant_db"] > 0 else ""))
    ax_hist.legend(loc="upper right", fontsize="small")
    fig.savefig(str(path), dpi=110)

"""The brush's figure (`texelpad brush show`, docs/brush.md): its scale and
shape against wavelength, and a painted sample beside the original it was
fitted to. matplotlib (Agg), pure logic otherwise."""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from texel.gen.params import DX_MM

from .document import paint, to_values
from .transform import wavelengths_mm

SHOW_MM = 10.0          # the painted sample's length: 10 mm (1,887 samples)


def brush_figure(doc: dict[str, Any], out: str | os.PathLike, seed: int = 0,
                 original: np.ndarray | None = None) -> Path:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    wl = wavelengths_mm()[1:] * 1000.0          # um, wavenumbers 1 .. 96 (NYQ)
    lam = np.array(doc["lam"][1:])
    k = np.array(doc["k"][1:])
    fig = plt.figure(figsize=(9, 6.2))
    gs = fig.add_gridspec(3, 2, height_ratios=[1.2, 1, 1])
    a1 = fig.add_subplot(gs[0, 0])
    a1.loglog(wl, np.maximum(lam, 1e-9), ".-", ms=3)
    a1.set_xlabel("wavelength (um)")
    a1.set_ylabel("Weibull scale lam")
    a1.invert_xaxis()
    a1.set_title("scale per wavenumber (mean: %.3g)" % doc["lam"][0], fontsize=9)
    a2 = fig.add_subplot(gs[0, 1])
    a2.semilogx(wl, k, ".-", ms=3, color="C1")
    a2.axhline(2.0, ls=":", color="0.5", lw=0.8)
    a2.text(wl[-1], 2.0, " k = 2: Rayleigh", fontsize=7, va="bottom", color="0.4")
    a2.set_xlabel("wavelength (um)")
    a2.set_ylabel("Weibull shape k")
    a2.invert_xaxis()
    a2.set_title("shape per wavenumber (mean: %.3g)" % doc["k"][0], fontsize=9)
    n = int(round(SHOW_MM / DX_MM))
    x = np.arange(n) * DX_MM
    painted = to_values(doc, paint(doc, seed, n))
    rows = [("painted (seed %d)" % seed, painted, "C0")]
    if original is not None:
        rows.insert(0, ("original", np.asarray(original, float)[:n], "0.3"))
    for i, (label, y, color) in enumerate(rows):
        ax = fig.add_subplot(gs[1 + i, :])
        ax.plot(x[:len(y)], y, lw=0.6, color=color)
        ax.set_ylabel(label, fontsize=8)
        ax.set_xlim(0, SHOW_MM)
        if i == len(rows) - 1:
            ax.set_xlabel("position (mm)")
    fig.suptitle("brush %s (%s)" % (doc.get("name") or "", doc.get("source") or ""), fontsize=10)
    fig.tight_layout()
    out = Path(out)
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out

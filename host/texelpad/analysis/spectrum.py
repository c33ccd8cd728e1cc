"""Spectra of friction maps and the texel pitch distribution (numpy only)."""
from __future__ import annotations

import math

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

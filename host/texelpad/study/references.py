"""The nine reference textures of the matching study (seed 000; ../shared/SPEC.md
§2) as points of the pitch - irregularity plane: the simulated participant's
targets (bench/study_compare.py) and the marks a summary figure draws.

Nothing published gives these points: seed 000 quotes only the subjects' mean
Central Pitch for six of the nine (2sin ~4.8 dB, 3sin ~6.0 dB, 4sin ~7.8 dB,
the shaped waveforms ~0 dB: "the fundamental frequency ... 1 cycle/mm") and
no irregularity at all. So a reference's point is a documented spectral model,
not a measurement of what people feel:

- the map: the reference's half-screen row from texel's own generator
  (device/texel/gen/reference.py: 9,600 samples at DX_MM = 5.3 um, 50.88 mm;
  it agrees with ../shared/golden/reference_textures.csv to 3e-13 for the
  closed forms and 7.6e-6 - the uint16 storage step - for the noise rows);
- its spectrum: the mean removed, a Hann window (the line components of the
  sums of sines fall between bins, 2.5 c/mm x 50.88 mm = 127.2 cycles; a
  rectangular window would leak their power into every bin and widen the
  spread; the same convention as texelpad.analysis.spectrum), the one-sided
  FFT on rfftfreq(9600, DX_MM) - bins every 1/50.88 mm = 0.0197 c/mm - kept
  within the display's band [0.01 c/mm (PITCH_DB_MIN), 94.34 c/mm (Nyquist)]:
  every bin but DC;
- weights w(f) = |X(f)|^2 (power; see below), summed over linear-frequency
  bins. That is the distribution of the map's power over log f (a bin holds
  PSD*df = PSD*f*dln f), the same thing the texel generator's parameters
  describe: log10 f ~ Normal(log10 P, sigma) (SPEC §1);
- central pitch = 10*log10 of the weighted geometric mean frequency (c/mm),
  irregularity = 10*log10 of the weighted SD of log10 f (decades): the dB
  conventions of texel.gen.params and seed 000 (10*log10, re 1 c/mm and
  1 decade); both clamped to the generator's limits (texel.gen.params:
  PITCH_DB_MIN .. PITCH_DB_MAX, IRREG_DB_MIN .. IRREG_DB_MAX).

The weighting, and how each choice compares with the paper's quoted pitches
(dB; "-": nothing quoted; computed by spectral_position with weighting=...):

    reference  paper   pitch        irregularity
                       mag.  power  mag.  power
    2sin        4.8    7.0   5.9   -4.5   -7.2
    3sin        6.0    7.0   7.0   -6.4   -6.5
    4sin        7.8    7.9   7.9   -6.1   -6.1
    white        -    15.4  15.4   -3.7   -3.8
    pink         -    12.5   7.6   -2.0   -1.1
    blue         -    17.2  17.9   -5.7   -7.5
    square      ~0     9.1   1.4   -1.5   -4.7
    triangle    ~0     1.4   0.1   -4.7  -11.9
    sawtooth    ~0    10.2   2.4   -1.8   -4.1
    |error| mean / max over the six quoted: magnitude 4.0 / 10.2 dB,
                                            power     1.0 / 2.4 dB

Power it is. Magnitude weighting lets the slowly falling harmonics of the
square and sawtooth waves (amplitude 1/n, n up to Nyquist = 94 harmonics)
pull the pitch to 9-10 dB, where the subjects chose ~0 dB; power (1/n^2)
keeps it near the fundamental, as seed 000's discussion says the dominant
sensation is. Neither weighting can tell 2sin's two equal lines (2.5 and
6 c/mm) apart from their geometric mean 5.9 dB, 1.1 dB above the quoted
4.8 dB; 3sin is 1.0 dB high, 4sin within 0.1 dB. The rectangular window
changes the power pitches by <= 0.1 dB except pink (6.7 dB instead of 7.6).

Read the irregularities with care (nothing checks them): in power, blue
noise (PSD ~ sin^2(pi f dx), most of it in the top octaves) spreads over
less of log f than the sums of sines (-7.5 dB against -7.2 .. -6.1 dB); white
and pink are the most irregular of the nine, the triangle wave the least.

Pure logic: texel and numpy, no link, no web framework (docs/architecture.md).
"""
from __future__ import annotations

import functools
import math

import numpy as np

import texel
from texel.gen.params import (DX_MM, IRREG_DB_MAX, IRREG_DB_MIN, NYQUIST_CPMM, PITCH_DB_MAX,
                              PITCH_DB_MIN)
from texel.gen.reference import HALF_SCREEN, STUDY_NAMES

from ..analysis.calibration import QUOTED_PITCH_DB
from .space import Point, to_point

REFERENCES = tuple(STUDY_NAMES)     # the CSV's row order: 2sin, 3sin, 4sin, white, ..., sawtooth
FAMILIES = {"2sin": "sums of sinusoids", "3sin": "sums of sinusoids", "4sin": "sums of sinusoids",
            "white": "colors of noise", "pink": "colors of noise", "blue": "colors of noise",
            "square": "shaped waveforms", "triangle": "shaped waveforms",
            "sawtooth": "shaped waveforms"}
# seed 000, Discussion: the subjects' mean Central Pitch in the free exploration (dB re 1 c/mm);
# the shaped waveforms' "1 cycle/mm (0 dB) for all textures". Nothing for the noises or for
# irregularity. (The felt model's calibration holds them: texelpad.analysis.calibration.)
PAPER_PITCH_DB = QUOTED_PITCH_DB
WEIGHTINGS = ("power", "magnitude")
WEIGHTING = "power"                 # the model's choice (module docstring: the table)
BAND_CPMM = (10.0 ** (PITCH_DB_MIN / 10.0), NYQUIST_CPMM)    # 0.01 .. 94.34 c/mm


def spectral_position(fmap, weighting: str = WEIGHTING) -> tuple[float, float]:
    """(pitch_db, irregularity_db) of a friction map (DX_MM per sample) by the
    spectral model of this module's docstring, NOT clamped: 10*log10 of the
    weighted geometric mean frequency (c/mm) and of the weighted SD of
    log10 f (decades) over the band BAND_CPMM, weights |X|^2 ("power") or
    |X| ("magnitude") of the Hann-windowed, mean-removed map."""
    if weighting not in WEIGHTINGS:
        raise ValueError("weighting: expected one of %s, got %r" % (", ".join(WEIGHTINGS),
                                                                     weighting))
    x = np.asarray(fmap, dtype=float)
    if x.ndim != 1 or x.size < 4:
        raise ValueError("fmap: expected a 1-D map of at least 4 samples, got shape %r"
                         % (x.shape,))
    mag = np.abs(np.fft.rfft((x - x.mean()) * np.hanning(x.size)))
    f = np.fft.rfftfreq(x.size, d=DX_MM)
    keep = (f >= BAND_CPMM[0]) & (f <= BAND_CPMM[1])
    w = mag[keep] ** 2 if weighting == "power" else mag[keep]
    total = float(w.sum())
    if not total > 0.0:
        raise ValueError("fmap: no spectral content in the band %.3g .. %.4g c/mm (a flat map)"
                         % BAND_CPMM)
    lf = np.log10(f[keep])
    mu = float(np.sum(w * lf) / total)                       # mean log10 f (decades re 1 c/mm)
    sd = math.sqrt(float(np.sum(w * (lf - mu) ** 2) / total))  # decades
    return 10.0 * mu, 10.0 * math.log10(sd) if sd > 0.0 else -math.inf


def clamp_to_generator(pitch: float, irregularity: float) -> tuple[float, float]:
    """The point limited to what texel.validate allows (texel.gen.params)."""
    return (min(PITCH_DB_MAX, max(PITCH_DB_MIN, pitch)),
            min(IRREG_DB_MAX, max(IRREG_DB_MIN, irregularity)))


def _check(name: str) -> str:
    if name not in REFERENCES:
        raise ValueError("reference: unknown %r (known: %s)" % (name, ", ".join(REFERENCES)))
    return name


@functools.lru_cache(maxsize=None)
def position(name: str, weighting: str = WEIGHTING) -> tuple[float, float]:
    """(pitch_db, irregularity_db) of reference `name`: the spectral model on
    texel's half-screen row (HALF_SCREEN = 9,600 samples), clamped to the
    generator's limits. Cached (a 9,600-sample FFT; the noise rows are read
    from texel/gen/reference_noise.bin)."""
    m = np.asarray(texel.reference(_check(name), HALF_SCREEN), dtype=float)
    return clamp_to_generator(*spectral_position(m, weighting))


def positions(weighting: str = WEIGHTING) -> dict[str, tuple[float, float]]:
    """Every reference's position, in REFERENCES order."""
    return {n: position(n, weighting) for n in REFERENCES}


def target_point(name: str, weighting: str = WEIGHTING) -> Point:
    """The reference's point in texelpad.study.space's unit square (pitch
    -15 .. 25 dB, irregularity -25 .. 5 dB), clamped to the square: the
    simulated participant's target."""
    return to_point(*position(name, weighting)).clamped()

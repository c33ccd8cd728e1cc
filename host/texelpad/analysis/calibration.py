"""Calibrating the felt model (texelpad.analysis.perception) on what is
published - and only that (docs/encoder.md, "Calibration"):

- seed 000's text: the subjects' mean Central Pitch in the free exploration
  for six of the nine references (QUOTED_PITCH_DB);
- the trained rater's matches (../shared/golden/rater/): the parameters the
  rater chose for each reference AND the 192 texel pitches of the rendering
  the rater felt. A match says "this rendering feels like that reference": a
  good model puts the two at the same felt point.

The lab's per-subject result files (NU-Haptics-Lab/SinglePitchTexel) are the
encoder's held-out test: nothing here reads, fits or tunes to them.

What is fitted: the model's constants that are assumptions, not measurements
(perception: FULL_SCALE_SL_DB, SLOPE_ABOVE_DB_PER_OCTAVE, MASKING_DB), on a
grid (CONSTANTS), by the loss

    sum over textures of  |felt(reference) - felt(rater's rendering)|^2
                        + (felt pitch(reference) - quoted mean)^2   (the six quoted)

in dB^2 on the felt plane (perception.FeltPoint.distance). The sourced
constants (speed, the threshold's knee, best frequency and lower slope, the
fingertip's corner, the resolution) stay as their sources give them.
leave_one_out() refits without each texture in turn and reports the held-out
texture: how the fold's model matches the rater's rendering to the reference,
how its encoder lands against the rater's parameters and the quoted mean.

The rater's texel-pitch file labels each row with its texture (corrected
2026-11-28, ../shared/golden/README.md: the lab's .mat stores the sequences
in its test order, and an earlier copy labelled them in family order, so
seven of nine labels were wrong). rater_pitches() reads the rows by their
labels; rater_label_check() measures each row's log mean and log SD against
the match it is labelled with and solves the assignment by statistics alone
(Hungarian, on those two numbers), so a test can say the labels are right.
Square's and triangle's matches are identical (-0.045 dB, -10 dB): the
statistics cannot tell those two rows apart, only the labels can.

Pure analysis: numpy, scipy and texel; never the link or a web framework.
"""
from __future__ import annotations

import csv
import itertools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

from texel.gen.params import DX_MM

from . import perception as P

# seed 000, "Discussion": the subjects' mean Central Pitch in the free
# exploration, as quoted ("around 3 cycles/mm (4.8 dB)", "around 4 cycles/mm
# (6.0 dB)", "around 6 cycles/mm (7.8 dB)"; the shaped waveforms "close to
# the fundamental frequency: 1 cycle/mm (0 dB)"). Nothing else is quoted.
QUOTED_PITCH_DB = {"2sin": 4.8, "3sin": 6.0, "4sin": 7.8,
                   "square": 0.0, "triangle": 0.0, "sawtooth": 0.0}
NAMES = ("2sin", "3sin", "4sin", "white", "pink", "blue", "square", "triangle", "sawtooth")
RATER_TEXEL_SAMPLES = 50          # the rater's renderings: 50-sample texels, 9,600 samples
RATER_TEXELS = 192
# the grid of the assumed constants (perception's comments say why each is assumed)
CONSTANTS = {"full_scale_sl_db": (20.0, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0, 60.0),
             "slope_above_db_per_octave": (6.0, 12.0, 18.0, 24.0, 36.0),
             "masking_db": (None, 10.0)}


def rater_dir(shared: str | Path | None = None) -> Path:
    """../shared/golden/rater beside the repository (or under `shared`)."""
    if shared is None:
        shared = Path(__file__).resolve().parents[4] / "shared"
    d = Path(shared) / "golden" / "rater"
    if not (d / "trained_rater_matches.csv").is_file():
        raise FileNotFoundError("the rater's data: %s/trained_rater_matches.csv not found "
                                "(../shared/golden/rater beside the repository)" % d)
    return d


def rater_matches(shared: str | Path | None = None) -> dict[str, tuple[float, float]]:
    """{texture: (pitch_db, irregularity_db)} the trained rater chose."""
    with open(rater_dir(shared) / "trained_rater_matches.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    return {r["texture"]: (float(r["pitch_db"]), float(r["irregularity_db"])) for r in rows}


def rater_pitches(shared: str | Path | None = None) -> dict[str, np.ndarray]:
    """{texture: the 192 texel pitches (c/mm) of the rater's rendering of it},
    read by the file's row labels (module docstring)."""
    with open(rater_dir(shared) / "trained_rater_texel_pitches.csv", newline="") as f:
        rows = list(csv.reader(f))[1:]
    out = {r[0]: np.array([float(v) for v in r[1:]]) for r in rows}
    if sorted(out) != sorted(NAMES) or len(rows) != len(NAMES):
        raise ValueError("the rater's pitch file: expected one row for each of %s, got %s"
                         % (", ".join(NAMES), ", ".join(r[0] for r in rows)))
    for name, seq in out.items():
        if seq.size != RATER_TEXELS or not np.all(np.isfinite(seq)) or not np.all(seq > 0):
            raise ValueError("the rater's pitch file: row %r needs %d positive pitches"
                             % (name, RATER_TEXELS))
    return out


def log_stats_db(pitches: np.ndarray) -> tuple[float, float]:
    """(10 log10 of the geometric mean pitch, 10 log10 of the SD of log10 f):
    the (pitch_db, irregularity_db) a texel sequence has."""
    lg = np.log10(np.asarray(pitches, dtype=np.float64))
    return 10.0 * float(np.mean(lg)), 10.0 * math.log10(float(np.std(lg, ddof=1)))


def rater_label_check(shared: str | Path | None = None) -> dict[str, Any]:
    """Each row's statistics against the match its label names, and the
    assignment the statistics alone make (module docstring):
    {"rows": {label: {"stats_db", "match_db", "distance_db"}},
     "by_statistics": {texture: label}, "labels_cost", "best_cost"} -
    the labels are right when their cost is the least any assignment has."""
    from scipy.optimize import linear_sum_assignment
    matches = rater_matches(shared)
    pitches = rater_pitches(shared)
    names = list(NAMES)
    stats = np.array([log_stats_db(pitches[n]) for n in names])
    target = np.array([matches[n] for n in names])
    cost = ((stats[:, None, :] - target[None, :, :]) ** 2).sum(axis=-1)
    ri, ci = linear_sum_assignment(cost)
    rows = {n: {"stats_db": [float(v) for v in stats[i]], "match_db": list(matches[n]),
                "distance_db": float(math.sqrt(cost[i, i]))} for i, n in enumerate(names)}
    return {"rows": rows, "by_statistics": {names[c]: names[r] for r, c in zip(ri, ci)},
            "labels_cost": float(np.trace(cost)), "best_cost": float(cost[ri, ci].sum())}


def render_pitches(pitches: Sequence[float] | np.ndarray,
                   texel_samples: int = RATER_TEXEL_SAMPLES, phase0: float = 0.0
                   ) -> np.ndarray:
    """The map (0..1) of texels with these pitches (c/mm), as the lab's
    generator renders them: the phase advances 2 pi f_i DX per sample of texel
    i, continuous across texels, from phase0 (rad); (sin + 1) / 2
    (docs/generator.md)."""
    inc = np.repeat(2.0 * np.pi * np.asarray(pitches, dtype=np.float64) * DX_MM, texel_samples)
    theta = phase0 + np.concatenate(([0.0], np.cumsum(inc)[:-1]))
    return (np.sin(theta) + 1.0) / 2.0


@dataclass
class Data:
    """The calibration's inputs: each reference's and the rater's rendering's
    periodogram (fixed by the maps; the model only weighs them)."""
    names: tuple[str, ...]
    reference: dict[str, np.ndarray]
    rendering: dict[str, np.ndarray]
    spectra: dict[str, tuple[np.ndarray, np.ndarray]]
    matches: dict[str, tuple[float, float]]
    m: int

    def points(self, model: P.Model) -> dict[str, tuple[P.FeltPoint, P.FeltPoint]]:
        return {n: (P.pattern_of_spectrum(self.spectra[n][0], self.m, model).felt_point(),
                    P.pattern_of_spectrum(self.spectra[n][1], self.m, model).felt_point())
                for n in self.names}


def load(shared: str | Path | None = None, names: Iterable[str] = NAMES) -> Data:
    """The nine references (texel's own, 9,600 samples: the study's half
    screen) and the rater's renderings, with their periodograms."""
    from .encoder import reference_map
    names = tuple(names)
    pitches = rater_pitches(shared)
    ref = {n: reference_map(n) for n in names}
    ren = {n: render_pitches(pitches[n]) for n in names}
    spectra = {n: (P.periodogram(ref[n])[1], P.periodogram(ren[n])[1]) for n in names}
    m = P.segment_length(next(iter(ref.values())).size)
    return Data(names, ref, ren, spectra, rater_matches(shared), m)


def loss(points: Mapping[str, tuple[P.FeltPoint, P.FeltPoint]], names: Iterable[str]) -> float:
    """The calibration's loss (module docstring) over `names`, dB^2."""
    total = 0.0
    for n in names:
        a, b = points[n]
        total += a.distance(b) ** 2
        if n in QUOTED_PITCH_DB:
            total += (a.pitch_db - QUOTED_PITCH_DB[n]) ** 2
    return total


def models(base: P.Model = P.DEFAULT_MODEL) -> list[P.Model]:
    """Every combination of CONSTANTS, the rest as in `base`."""
    keys = list(CONSTANTS)
    out = []
    for values in itertools.product(*(CONSTANTS[k] for k in keys)):
        kw = base.as_dict()
        kw = {k: kw[k] for k in ("speed_mm_s", "full_scale_sl_db", "masking_db",
                                 "resolution_decades", "slope_above_db_per_octave",
                                 "fingertip_corner_hz", "line_db")}
        kw.update(dict(zip(keys, values)))
        out.append(P.Model(**kw))
    return out


@dataclass
class Fit:
    model: P.Model
    loss: float
    names: tuple[str, ...]


class Calibration:
    """The grid's felt points, computed once; fits over any subset of textures."""

    def __init__(self, data: Data, base: P.Model = P.DEFAULT_MODEL) -> None:
        self.data = data
        self.grid = [(m, data.points(m)) for m in models(base)]

    def fit(self, names: Iterable[str]) -> Fit:
        names = tuple(names)
        best = min(self.grid, key=lambda g: loss(g[1], names))
        return Fit(best[0], loss(best[1], names), names)


def constants_of(model: P.Model) -> dict[str, Any]:
    return {k: getattr(model, k) for k in CONSTANTS}


def leave_one_out(cal: Calibration, encode: bool = True) -> list[dict[str, Any]]:
    """For each texture: refit without it, then on it - the felt distance
    between the reference and the rater's rendering, the felt pitch's error
    against the quoted mean, and (encode=True) the fold's encoder (felt
    method) against the rater's parameters, with the felt distance between
    its texture and the rater's rendering."""
    from . import encoder as E
    data = cal.data
    rows = []
    for held in data.names:
        fold = cal.fit([n for n in data.names if n != held])
        pts = data.points(fold.model)
        a, b = pts[held]
        row: dict[str, Any] = {
            "texture": held, "constants": constants_of(fold.model),
            "train_loss": round(fold.loss, 4),
            "reference": a.as_dict(), "rater_rendering": b.as_dict(),
            "felt_distance_db": round(a.distance(b), 4),
            "quoted_pitch_db": QUOTED_PITCH_DB.get(held),
            "felt_pitch_error_db": round(a.pitch_db - QUOTED_PITCH_DB[held], 4)
            if held in QUOTED_PITCH_DB else None,
            "rater": {"pitch_db": data.matches[held][0],
                      "irregularity_db": data.matches[held][1]},
        }
        if encode:
            r = E.encode(data.reference[held], model=fold.model, intervals=False)
            enc = P.felt_point({"pitch_db": r["pitch_db"], "irregularity_db":
                                r["irregularity_db"], "gain": 1.0},
                               data.reference[held].size, fold.model)
            ren = P.pattern_of_spectrum(data.spectra[held][1], data.m, fold.model).felt_point()
            row["encoded"] = {"pitch_db": r["pitch_db"], "irregularity_db": r["irregularity_db"],
                              "aliased_fraction": r["aliasing"]["expected_fraction"]}
            row["encoded_vs_rater_db"] = {
                "pitch": round(r["pitch_db"] - data.matches[held][0], 3),
                "irregularity": round(r["irregularity_db"] - data.matches[held][1], 3),
                "felt": round(enc.distance(ren), 4)}
        rows.append(row)
    return rows

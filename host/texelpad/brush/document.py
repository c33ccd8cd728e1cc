"""A brush as a document (docs/brush.md; seed 002's "brush"): what `texelpad brush`
fits, designs, saves, shows, compares and paints, and what a scene region
carries to a board.

    {"format": "texelpad-brush/2", "name": "...", "source": "...",
     "window": 192, "hop": 48, "wavenumbers": 97, "dx_um": 5.3,
     "range": [a0, a1], "k": [97 shapes], "lam": [97 scales],
     "fit": {"windows": n, "ks": [97 K-S statistics]}?}

k, lam: the Weibull distribution (shape, scale) of the spectral magnitude at
each wavenumber 0 (the window's mean) .. 96 (10.6 um), in the recording's
units (device/texel/gen/brush.py has the geometry); range: the value a0 plays
as amplitude 0 and a1 as amplitude 1. A friction recording maps high
friction to low ultrasonic amplitude (the plate's friction reduction), so a
fitted recording's range is [high, low] - its 99.5th and 0.5th percentiles;
a map already in amplitude units (a reference texture, a texel rendering)
has [0, 1].

Sizes (measured by the tests and the benchmark): the JSON is ~4 KB, the
binary form (to_bytes: b"TPB1", K, the range and k, lam as float32) 790
bytes, the region a board receives (k, lam, range as repr'd floats) ~3 KB -
against the 38,400 bytes of the full-screen map it paints.

Fitting (fit): the de-meaned space-frequency transform of every recording
(transform.stft_magnitudes(demean=True): the painter draws the mean and the
wavenumber-1 wave apart), all windows of all recordings together, Weibull by
maximum likelihood per wavenumber (fits.fit_swipe: scipy.stats).
Painting (paint): texel.gen.brush.paint - the same integers on the host and
on a board. Pure logic and files: no link, no web framework.
"""
from __future__ import annotations

import json
import math
import os
import struct
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from texel.gen import brush as B
from texel.gen.params import DX_MM

FORMAT = B.FORMAT
DOC_KEYS = {"format", "name", "source", "window", "hop", "wavenumbers", "dx_um", "range", "k",
            "lam", "fit"}
MAGIC = b"TPB1"
SHAPES = {"white": 0.0, "pink": -3.0103, "brown": -6.0206, "blue": 3.0103}   # dB per octave


def check(doc: Any, where: str = "brush") -> dict[str, Any]:
    """A brush document checked: the board's own validation of k, lam, range
    (texel.gen.brush.validate: by key path), its geometry, and nothing
    unknown. Returns a new, complete document."""
    if not isinstance(doc, dict):
        raise ValueError("%s: expected a brush document (a JSON object)" % where)
    bad = sorted(set(doc) - DOC_KEYS)
    if bad:
        raise ValueError("%s: unknown key %r (allowed: %s)" % (where, bad[0],
                                                               ", ".join(sorted(DOC_KEYS))))
    # the format too: validate says why an old format (texelpad-brush/1) is refused
    core = {k: doc[k] for k in ("format", "k", "lam", "range", "window", "hop", "wavenumbers")
            if k in doc}
    v = B.validate(core, where)
    dx = doc.get("dx_um", round(DX_MM * 1000, 6))
    if dx != round(DX_MM * 1000, 6):
        raise ValueError("%s.dx_um: this display's sample is %r um, got %r"
                         % (where, round(DX_MM * 1000, 6), dx))
    out = {"format": FORMAT, "name": str(doc.get("name", "")), "source": str(doc.get("source", "")),
           "window": B.WINDOW, "hop": B.HOP, "wavenumbers": B.K, "dx_um": dx,
           "range": v["range"], "k": v["k"], "lam": v["lam"]}
    if "fit" in doc:
        out["fit"] = doc["fit"]
    return out


def make(k: Sequence[float], lam: Sequence[float], range_: Sequence[float] = (0.0, 1.0),
         name: str = "", source: str = "") -> dict[str, Any]:
    return check({"k": [float(x) for x in k], "lam": [float(x) for x in lam],
                  "range": [float(x) for x in range_], "name": name, "source": source})


# --- files ----------------------------------------------------------------------------
def load(path: str | os.PathLike) -> dict[str, Any]:
    """A brush from its JSON file or its binary form (by the magic)."""
    p = Path(path)
    data = p.read_bytes()
    try:
        if data[:4] == MAGIC:
            return from_bytes(data)
        try:
            doc = json.loads(data.decode("utf-8"))
        except (UnicodeDecodeError, ValueError) as e:
            raise ValueError("not a brush (JSON or %r binary): %s" % (MAGIC, e)) from None
        except RecursionError:
            # json.loads recurses per level: a file nested thousands deep is no brush
            # (a brush is two levels deep: {"k": [...], ...})
            raise ValueError("not a brush: its JSON is nested too deeply (a brush document "
                             "is an object of lists of numbers)") from None
        return check(doc)
    except ValueError as e:
        raise ValueError("%s: %s" % (p, e)) from None


def save(doc: dict[str, Any], path: str | os.PathLike) -> Path:
    """Written beside and renamed: a failed write never leaves half a brush
    (.tpb: the binary form, else JSON)."""
    p = Path(path)
    doc = check(doc)
    data = to_bytes(doc) if p.suffix == ".tpb" else \
        (json.dumps(doc, indent=1, allow_nan=False) + "\n").encode("utf-8")
    tmp = p.with_name(p.name + ".tmp")
    tmp.write_bytes(data)
    os.replace(tmp, p)
    return p


def to_bytes(doc: dict[str, Any]) -> bytes:
    """The compact form: MAGIC, K (uint16), the range, k and lam as float32
    little-endian: 4 + 2 + 8 + 8 K = 790 bytes. float32 keeps 7 digits:
    from_bytes(to_bytes(b)) paints within a Q13 unit of b (tests)."""
    return MAGIC + struct.pack("<H2f%df%df" % (B.K, B.K), B.K, *doc["range"], *doc["k"],
                               *doc["lam"])


def from_bytes(data: bytes, where: str = "brush") -> dict[str, Any]:
    n = 4 + 2 + 8 + 8 * B.K
    k_count = struct.unpack_from("<H", data, 4)[0] if len(data) >= 6 else B.K
    if data[:4] == MAGIC and k_count != B.K and len(data) == 4 + 2 + 8 + 8 * k_count:
        # a whole binary brush of another geometry (95 wavenumbers: texelpad-brush/1)
        raise ValueError("%s: %d wavenumbers; this display paints %d (fit or design it again)"
                         % (where, k_count, B.K))
    if len(data) != n or data[:4] != MAGIC:
        raise ValueError("%s: a binary brush is %d bytes starting %r, got %d bytes"
                         % (where, n, MAGIC, len(data)))
    if k_count != B.K:
        raise ValueError("%s: %d wavenumbers; this display paints %d" % (where, k_count, B.K))
    vals = struct.unpack_from("<2f%df%df" % (B.K, B.K), data, 6)
    return check({"range": list(vals[:2]), "k": list(vals[2:2 + B.K]),
                  "lam": list(vals[2 + B.K:])}, where)


# --- fitting, designing, painting -----------------------------------------------------
def fit(maps: Sequence[np.ndarray], kind: str = "friction", name: str = "",
        source: str = "") -> dict[str, Any]:
    """The brush of one or more maps on the display's 5.3 um grid (each at
    least a window long): Weibull per wavenumber over all their windows.
    kind "friction": range [p99.5, p0.5] of the values; "amplitude": [0, 1]."""
    from .fits import fit_swipe
    from .transform import stft_magnitudes
    if kind not in ("friction", "amplitude"):
        raise ValueError("kind: expected 'friction' or 'amplitude', got %r" % (kind,))
    if not maps:
        raise ValueError("fit: no map given")
    mags = np.concatenate([stft_magnitudes(m, demean=True) for m in maps])
    f = fit_swipe(mags, models=("weibull",))
    allv = np.concatenate([np.asarray(m, float) for m in maps])
    if kind == "friction":
        hi, lo = np.percentile(allv, [99.5, 0.5])
        if not hi > lo:
            raise ValueError("fit: the recording is constant (%g): no friction range to map"
                             % hi)
        rng = [float(hi), float(lo)]
    else:
        rng = [0.0, 1.0]
    doc = make(f["weibull"]["k"], f["weibull"]["lam"], rng, name, source)
    doc["fit"] = {"windows": int(mags.shape[0]),
                  "ks": [round(float(x), 5) for x in f["weibull"]["ks"]]}
    return doc


def design(shape: str | float = "white", level: float = 0.05, mean: float = 0.5,
           k: float = 2.0, k_mean: float = 20.0, band: tuple[int, int] = (1, B.K - 1),
           range_: Sequence[float] = (0.0, 1.0), name: str = "") -> dict[str, Any]:
    """A brush by hand from a spectral shape: lam at wavenumber n =
    level * (n / 4)^(slope / 6.02) inside band (n = 4 is a 0.25 mm
    wavelength; slope in dB per octave: a named shape of SHAPES or a number),
    0 outside; every shape k (2: each window's magnitude Rayleigh, as
    Gaussian noise would give); the mean's scale `mean` with shape k_mean
    (20: within ~6 % window to window)."""
    slope = SHAPES.get(shape, shape) if isinstance(shape, str) else float(shape)
    if isinstance(slope, str):
        raise ValueError("shape: expected one of %s or dB per octave, got %r"
                         % (", ".join(SHAPES), shape))
    lo, hi = band
    if not 1 <= lo <= hi <= B.K - 1:
        raise ValueError("band: expected 1 <= low <= high <= %d, got %r" % (B.K - 1, band))
    lam = [0.0] * B.K
    for n in range(lo, hi + 1):
        lam[n] = level * (n / 4.0) ** (slope / (20 * math.log10(2)))
    lam[0] = mean
    ks = [k] * B.K
    ks[0] = k_mean
    return make(ks, lam, range_, name or "designed %s" % shape,
                "texelpad brush design shape=%s level=%g mean=%g k=%g" % (shape, level, mean, k))


def region(doc: dict[str, Any], seed: int, start_mm: float, end_mm: float) -> dict[str, Any]:
    """The scene region that paints this brush on a board: ~200 numbers."""
    d = check(doc)
    return {"start_mm": start_mm, "end_mm": end_mm,
            "texture": {"kind": "brush", "seed": seed,
                        "brush": {"k": d["k"], "lam": d["lam"], "range": d["range"]}}}


def paint(doc: dict[str, Any], seed: int, n: int = 19200) -> np.ndarray:
    """The uint16 map (0..65535) the brush paints over n display samples with
    seed - what a board's brush region of n samples plays."""
    d = check(doc)
    v = B.validate({"k": d["k"], "lam": d["lam"], "range": d["range"]})
    return np.frombuffer(B.paint(v, seed, n), dtype=np.uint16).copy()


def to_values(doc: dict[str, Any], u16: np.ndarray) -> np.ndarray:
    """A painted map back in the brush's units (friction): a0 + amp (a1 - a0)."""
    a0, a1 = doc["range"]
    return a0 + (np.asarray(u16, float) / 65535.0) * (a1 - a0)


def distance(a: dict[str, Any], b: dict[str, Any], metric: str = "braycurtis") -> float:
    """Distance between two brushes (compare.brush_distance: the paper's
    metrics over the Weibull vectors; seuclidean needs a set of brushes)."""
    from .compare import brush_distance
    return brush_distance(check(a), check(b), metric)


FELT_SEEDS = (0, 1, 2)          # paintings averaged for a brush's felt point


def felt_point(doc: dict[str, Any], seeds: Sequence[int] = FELT_SEEDS, n: int = 19200):
    """Where a brush sits on the felt plane (texelpad.analysis.perception:
    felt pitch and noisiness): the mean periodogram of its paintings with
    `seeds`, n samples each (a full screen), as the display plays them
    (0..65535 -> 0..1 modulation)."""
    from ..analysis import perception as P
    d = check(doc)
    if not seeds:
        raise ValueError("seeds: expected at least one")
    spec = np.mean([P.periodogram(paint(d, s, n) / 65535.0)[1] for s in seeds], axis=0)
    return P.pattern_of_spectrum(spec, P.segment_length(n)).felt_point()


def felt_distance(a: dict[str, Any], b: dict[str, Any], seeds: Sequence[int] = FELT_SEEDS,
                  n: int = 19200) -> tuple[float, Any, Any]:
    """(distance in dB on the felt plane, a's felt point, b's): under
    perception.JND_DB the two brushes feel the same."""
    fa, fb = felt_point(a, seeds, n), felt_point(b, seeds, n)
    return fa.distance(fb), fa, fb

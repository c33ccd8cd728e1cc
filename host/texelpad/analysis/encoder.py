"""The texel encoder: a friction map -> the few texel parameters that feel the
same (docs/encoder.md).

Seed 000 calls the Single-Pitch Texel a tactile codec whose decoder is the
generator and whose encoder was a person moving sliders. This is that
encoder: encode(map) chooses the texture (pitch_db, irregularity_db, gain;
texel length, quantization, seed and format as given) whose expected felt
pattern is nearest the map's, by the distance of texelpad.analysis.perception
(the 2-Wasserstein distance between felt spectra on a log-frequency axis,
in dB), and reports why:

- gain: closed form - the texture's variance gain^2/8 matched to the map's
  (a texel map is gain*(sin+1)/2; docs/generator.md), at most 1;
- pitch and irregularity: scipy.optimize's Nelder-Mead from the best of a
  coarse grid around the map's felt mean pitch, within the generator's limits
  (texel.gen.params); each candidate is an analytic expected spectrum
  (perception.expected_periodogram), never a rendering;
- the report: both spectra on a log-frequency axis, the distance minimised,
  the range of each parameter that feels the same (within EQUIVALENT_DB of
  the minimum: where a parameter is not identifiable, the range says so), what
  1, 3 and 5 dB quantization would cost (seed 000's quantization test), the
  compression, and the fraction of drawn texels above Nyquist (aliased).

Decoding is the generator: decode(result) renders the texture.

Inputs: any 1-D map (DX_MM = 5.3 um per sample); read_map() reads CSV/NPY,
reference_map() the study's references, scene_region_map() a scene region.
Non-finite samples up to NAN_FILL_MAX of the map are filled by linear
interpolation (reported); everything else that cannot be encoded is an
EncodeError (a ValueError) saying why.

Pure analysis: numpy, scipy and texel; never the link, the command line or
a web framework (docs/architecture.md).
"""
from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any, Mapping

import numpy as np

import texel
from texel.gen.params import (DX_MM, FORMAT_NEW, IRREG_DB_MAX, IRREG_DB_MIN, LENGTH_MAX,
                              NYQUIST_CPMM, PITCH_DB_MAX, PITCH_DB_MIN)

from . import perception as P

BOUNDS = ((PITCH_DB_MIN, PITCH_DB_MAX), (IRREG_DB_MIN, IRREG_DB_MAX))
# A parameter value "feels the same" as the chosen one when its distance is
# within EQUIVALENT_DB of the minimum: a quarter of the ~1 dB pitch resolution
# (perception.RESOLUTION_DECADES; seed 000: 1 dB quantization unnoticed), and
# above the ~0.05-0.15 dB a single rendering differs from its expectation
# (tests/analysis/test_encoder.py checks the expected spectrum).
EQUIVALENT_DB = 0.25
NAN_FILL_MAX = 0.05             # fill at most 5 % non-finite samples, refuse more
QUANT_COSTS_DB = (1.0, 3.0, 5.0)    # seed 000's quantization test levels
U16_FULL = 65535.0
# the coarse start: irregularities (dB) tried at the felt mean pitch, and pitch
# offsets (dB) tried at the best of them
_COARSE_IRREG = (-24.0, -16.0, -12.0, -9.0, -6.0, -3.0, 0.0, 3.0)
_COARSE_PITCH = (-2.0, 2.0)
_SPECTRUM_STEP = 5              # report the spectra every 5 GRID steps (0.05 decade)


class EncodeError(ValueError):
    """A map that cannot be encoded, and why."""


# --- inputs -----------------------------------------------------------------------------

def reference_map(name: str, length_samples: int | None = None) -> np.ndarray:
    """Reference texture `name` (texel.reference_names()) as a float map;
    default length: the study's half screen (9,600 samples, 50.88 mm)."""
    from texel.gen.reference import HALF_SCREEN
    names = texel.reference_names()
    if name not in names:
        raise EncodeError("reference: unknown %r (known: %s)" % (name, ", ".join(names)))
    n = HALF_SCREEN if length_samples is None else int(length_samples)
    if not 1 <= n <= LENGTH_MAX:
        raise EncodeError("length: %d samples is outside 1 .. %d" % (n, LENGTH_MAX))
    return np.asarray(texel.reference(name, n), dtype=np.float64)


def scene_region_map(scene: Any, region: int) -> np.ndarray:
    """The friction map a board plays in region `region` (0-based, in start
    order) of `scene` (a scene dict; texel.runtime.scene validates it), on the
    TPaD display (19,200 x 5.3 um), as float64 in [0, 1]."""
    from texel.runtime import scene as tscene
    display = {"positions": 19200, "dx_um": 5.3}
    try:
        canonical = tscene.validate(scene, display)
        sc = tscene.build(canonical, display)
    except ValueError as e:
        raise EncodeError("scene: %s" % e) from None
    spans = [(a, b) for (a, b, _, _) in sc.spans()]
    if not isinstance(region, int) or isinstance(region, bool) or not 0 <= region < len(spans):
        raise EncodeError("region: expected 1 .. %d (the scene has %d region%s), got %r"
                          % (len(spans), len(spans), "" if len(spans) == 1 else "s",
                             region + 1 if isinstance(region, int) else region))
    start, end = spans[region]
    amp = sc.amp
    return np.fromiter((amp(i) for i in range(start, end)), dtype=np.float64,
                       count=end - start) / U16_FULL


def read_map(path: str | Path) -> tuple[np.ndarray, list[str]]:
    """A friction map from a file, and notes on how it was read.

    .npy: a 1-D array (or one row/column); uint16 is the board's format
    (0..65535 = friction 0..1, texel.render_u16) and is scaled by 1/65535.
    .csv/.txt: one number per line, or columns with an optional header: the
    column named friction (as `texelpad render --out FILE.csv` writes it) or
    else the last; lines starting with # are skipped; "nan" is a number.
    Integer data above 1 that fits 0..65535 is taken as uint16 counts.
    Every problem is an EncodeError naming the file."""
    p = Path(path)
    notes: list[str] = []
    try:
        if p.suffix.lower() == ".npy":
            try:
                a = np.load(p, allow_pickle=False)
            except ValueError as e:
                raise EncodeError("%s: not a plain .npy array (%s)" % (path, e)) from None
            a = np.asarray(a)
            if a.ndim == 2 and 1 in a.shape:
                a = a.reshape(-1)
            if a.ndim != 1:
                raise EncodeError("%s: expected a 1-D map, got an array of shape %s"
                                  % (path, a.shape))
            if a.dtype == np.uint16:
                notes.append("uint16 map scaled by 1/65535")
                return a.astype(np.float64) / U16_FULL, notes
            if not (np.issubdtype(a.dtype, np.number) or a.dtype == bool):
                raise EncodeError("%s: expected numbers, got dtype %s" % (path, a.dtype))
            x = a.astype(np.float64)
        else:
            text = p.read_text(encoding="utf-8")
            x = _parse_csv(text, str(path))
    except OSError as e:
        raise EncodeError("cannot read %s: %s" % (path, e.strerror or e)) from None
    except UnicodeDecodeError:
        raise EncodeError("%s is not UTF-8 text (a .npy file must end in .npy)" % path) from None
    if x.size > LENGTH_MAX:
        raise EncodeError("%s: %s samples, more than the %s a texture can have"
                          % (path, format(x.size, ","), format(LENGTH_MAX, ",")))
    fin = x[np.isfinite(x)]
    if fin.size and fin.max() > 1.5 and fin.max() <= U16_FULL and fin.min() >= 0 \
            and np.all(fin == np.round(fin)):
        notes.append("integer values up to %d taken as uint16 counts (scaled by 1/65535)"
                     % fin.max())
        x = x / U16_FULL
    return x, notes


def _parse_csv(text: str, name: str) -> np.ndarray:
    rows = []
    header: list[str] | None = None
    for k, line in enumerate(text.splitlines()):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        cells = [c.strip() for c in s.replace(";", ",").replace("\t", ",").split(",")]
        try:
            rows.append([float(c) for c in cells])
        except ValueError:
            if not rows and header is None:
                header = [c.lower() for c in cells]
                continue
            bad = next(c for c in cells if not _is_float(c))
            raise EncodeError("%s line %d: %r is not a number" % (name, k + 1, bad[:40])) \
                from None
        if len(rows) > LENGTH_MAX:
            raise EncodeError("%s: more than %s samples" % (name, format(LENGTH_MAX, ",")))
    if not rows:
        raise EncodeError("%s: no numbers in it" % name)
    width = len(rows[0])
    if any(len(r) != width for r in rows):
        k = next(i for i, r in enumerate(rows) if len(r) != width)
        raise EncodeError("%s: data row %d has %d columns, the first has %d"
                          % (name, k + 1, len(rows[k]), width))
    col = width - 1
    if header is not None and len(header) == width:
        for want in ("friction", "map", "value", "amplitude"):
            if want in header:
                col = header.index(want)
                break
    return np.array([r[col] for r in rows], dtype=np.float64)


def _is_float(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return False


def _clean(fmap: Any) -> tuple[np.ndarray, list[str]]:
    """The map as finite float64, its non-finite samples filled (at most
    NAN_FILL_MAX of them); EncodeError otherwise."""
    notes: list[str] = []
    if isinstance(fmap, np.ndarray) and fmap.dtype == np.uint16:
        notes.append("uint16 map scaled by 1/65535 (the board's format: texel.render_u16)")
        fmap = fmap / U16_FULL
    try:
        x = np.array(fmap, dtype=np.float64)
    except (TypeError, ValueError):
        raise EncodeError("map: expected a sequence of numbers, got %s"
                          % type(fmap).__name__) from None
    if x.ndim == 2 and 1 in x.shape:
        x = x.reshape(-1)
    if x.ndim != 1:
        raise EncodeError("map: expected a 1-D map, got shape %s" % (x.shape,))
    if x.size < P.MIN_SAMPLES:
        raise EncodeError("map: %d sample%s (%.3g mm) is too short to have a spectrum: at "
                          "least %d (%.3g mm)" % (x.size, "" if x.size == 1 else "s",
                                                 x.size * DX_MM, P.MIN_SAMPLES,
                                                 P.MIN_SAMPLES * DX_MM))
    if x.size > LENGTH_MAX:
        raise EncodeError("map: %s samples, more than the %s a texture can have"
                          % (format(x.size, ","), format(LENGTH_MAX, ",")))
    bad = ~np.isfinite(x)
    nbad = int(bad.sum())
    if nbad:
        if nbad > NAN_FILL_MAX * x.size or nbad == x.size:
            raise EncodeError("map: %d of %d samples are not finite (NaN or inf; the first at "
                              "%d): more than the %g %% that are filled in"
                              % (nbad, x.size, int(np.argmax(bad)), 100 * NAN_FILL_MAX))
        k = np.arange(x.size)
        x[bad] = np.interp(k[bad], k[~bad], x[~bad])
        notes.append("%d non-finite sample%s (the first at %d) filled by linear interpolation"
                     % (nbad, "" if nbad == 1 else "s", int(np.argmax(bad))))
    lo, hi = float(x.min()), float(x.max())
    if lo < -1e-9 or hi > 1 + 1e-9:
        notes.append("values span %.4g .. %.4g, outside the display's 0 .. 1: the spectrum is "
                     "encoded, the level through the gain (at most 1)" % (lo, hi))
    return x, notes


# --- encoding ---------------------------------------------------------------------------

def _texture(pitch: float, irr: float, *, texel_samples: int, quant_db: float, gain: float,
             seed: int, v: int) -> dict[str, Any]:
    """The texture dict the board plays (a texel region's keys; texel.validate
    and texel.runtime.scene accept it): defaults left out but for the ones
    that say what was chosen; the format always: a texture without one would
    read as format 1)."""
    t: dict[str, Any] = {"pitch_db": pitch, "irregularity_db": irr,
                         "texel_samples": texel_samples, "gain": gain, "seed": seed}
    if quant_db > 0:
        t["quant_db"] = quant_db
    t["v"] = v
    return t


def _round_db(x: float) -> float:
    """Parameters to 0.01 dB: far below the ~1 dB resolution, and never near a
    half-way point of format 2's 0.001 dB grid (texel.validate refuses those)."""
    return float(round(x, 2))


METHODS = ("felt", "w2")
# The felt method's tie-break (a recorded choice, docs/encoder.md): where several
# textures feel the same as the map (a ridge of equal felt pitch and noisiness,
# e.g. a wide texture in the skin's band and one far above it whose aliased
# texels feel alike), the one nearest where the lab's free-exploration sliders
# start - log10 P = 0.5 (5 dB), sigma 0.5 decade (-3.01 dB): the lab's
# free_exploration_and_quantization_test_app, NU-Haptics-Lab/SinglePitchTexel -
# as a participant stops moving a slider once the texture feels the same. The
# weight keeps the pull below 0.01 dB wherever the felt point is identifiable.
SLIDER_START_DB = (5.0, 10.0 * math.log10(0.5))
TIE_BREAK = 1e-3
# ... and within the sliders' reach: irregularity at most 1 decade (0 dB; the
# lab's app, as above). The generator goes to +5 dB, the felt method stops
# where a participant's slider does (W2 keeps the generator's limits).
FELT_IRREG_MAX_DB = 0.0


def encode(fmap: Any, *, texel_samples: int = 50, quant_db: float = 0.0, seed: int = 0,
           v: int = FORMAT_NEW, model: P.Model | None = None, intervals: bool = True,
           source: str | None = None, method: str = "felt") -> dict[str, Any]:
    """Encode a friction map (1-D, values ~0..1, DX_MM = 5.3 um per sample) as
    texel parameters that feel the same, with the report (docs/encoder.md).

    method: "felt" (default) - the texture whose felt pitch and noisiness
    (perception.FeltPoint: what people match, seed 000/001) equal the map's,
    nearest the lab's slider start where several do (SLIDER_START_DB);
    "w2" - the texture whose whole felt spectrum is nearest the map's
    (perception.w2_db): recovers the parameters of a map that is itself a
    texel rendering, even one far above the skin's band.
    texel_samples, quant_db, seed, v: the texture's texel length, pitch
    quantization (dB; 0 = none), seed and format (default 2; 1 = the lab's
    float generator) - fixed, not fitted; the candidates are rendered with
    them. model: the perceptual model (default perception.DEFAULT_MODEL).
    intervals: also scan each parameter for the range that feels the same
    (~40 more candidates). source: a label kept in the result.

    Returns a JSON-ready dict: "pitch_db", "irregularity_db", "gain" and the
    other texture keys; "texture" (the dict a board plays, e.g.
    Board.push_texel); "distance_db" (minimised); "ranges"; "felt"; "spectrum";
    "quantization"; "compression"; "aliasing"; "skin_band"; "map"; "model";
    "method"; "notes"; "evaluations"; "seconds". EncodeError (a ValueError)
    when the map cannot be encoded."""
    t0 = time.perf_counter()
    if method not in METHODS:
        raise EncodeError("method: expected one of %s, got %r" % (", ".join(METHODS), method))
    model = P.DEFAULT_MODEL if model is None else model
    # the fixed texture keys first: a bad one is the caller's error, named as texel names it
    try:
        fixed = texel.validate({"pitch_db": 0.0, "irregularity_db": 0.0,
                                "texel_samples": texel_samples, "quant_db": quant_db,
                                "seed": seed, "v": v})
    except ValueError as e:
        raise EncodeError(str(e)) from None
    x, notes, gain = _prepare(fmap, fixed["texel_samples"])
    target = P.map_pattern(x, model)
    if target.sl_db < 0:
        notes.append("the map is felt below the detection threshold at its strongest "
                     "(%.1f dB): it would hardly be felt; encoded by its shape" % target.sl_db)
    cands = _Candidates(target, x.size, fixed["texel_samples"], fixed["quant_db"], gain, model,
                        method)
    pitch, irr = (_search_felt if method == "felt" else _search_w2)(cands)
    return _report(x, notes, gain, fixed, cands, pitch, irr, intervals, source, t0)


def _prepare(fmap: Any, L: int) -> tuple[np.ndarray, list[str], float]:
    """The cleaned map, the notes so far and the gain (closed form: a texel map
    gain*(sin+1)/2 has variance gain^2/8, matched to the map's, at most 1)."""
    x, notes = _clean(fmap)
    n = x.size
    var = float(np.var(x))
    if not var > 1e-18:
        raise EncodeError("map: constant (every sample is %.6g): there is no texture to feel, "
                          "nothing to encode (play it as a constant level)" % float(x[0]))
    gain = math.sqrt(8.0 * var)
    if gain > 1.005:
        notes.append("the map varies more than a full-scale texel can (its rms asks for gain "
                     "%.3g): gain 1" % gain)
    gain = min(1.0, float("%.4g" % gain))         # 4 significant digits, at most 1
    if n * DX_MM < 2.0:
        notes.append("a short map (%.3g mm): its spectrum has bins every %.3g c/mm (%.2f dB), "
                     "so lower pitches cannot be told apart"
                     % (n * DX_MM, 1.0 / (n * DX_MM), 10 * math.log10(1.0 / (n * DX_MM))))
    if n < 20 * L:
        # the candidates are expected spectra (the mean over seeds); with few texels a
        # rendering is far from its mean (one texel: one pure tone at a random pitch)
        notes.append("only %s texel%s of %d samples in the map: a rendering differs much from "
                     "seed to seed, and the distance is to the mean over seeds"
                     % ("%.3g" % (n / L), "" if n <= L else "s", L))
    return x, notes, gain


class _Candidates:
    """Candidate textures' expected felt patterns, cached, and their distance
    to the map by the method's measure (felt plane or W2)."""

    def __init__(self, target: P.Pattern, n: int, L: int, q: float, gain: float,
                 model: P.Model, method: str) -> None:
        self.target, self.n, self.L, self.q, self.gain = target, n, L, q, gain
        self.model, self.method = model, method
        self.target_point = target.felt_point()
        self.cache: dict[tuple[float, float, float], tuple[float, P.Pattern]] = {}

    def __call__(self, pitch: float, irr: float, q: float | None = None
                 ) -> tuple[float, P.Pattern]:
        pitch = _clip_pitch(pitch)
        irr = min(max(irr, BOUNDS[1][0]), BOUNDS[1][1])
        q = self.q if q is None else q
        key = (round(pitch, 6), round(irr, 6), q)
        if key not in self.cache:
            pat = P.texel_pattern({"pitch_db": pitch, "irregularity_db": irr,
                                   "texel_samples": self.L, "quant_db": q, "gain": self.gain,
                                   "length_samples": self.n}, model=self.model)
            self.cache[key] = (self.distance(pat), pat)
        return self.cache[key]

    def distance(self, pat: P.Pattern) -> float:
        if self.method == "felt":
            return self.target_point.distance(pat.felt_point())
        return P.w2_db(self.target, pat)


def _nelder_mead(objective: Any, starts: list[tuple[float, float, float]],
                 bounds: tuple[tuple[float, float], tuple[float, float]] = BOUNDS
                 ) -> tuple[float, float]:
    """Nelder-Mead (scipy) within BOUNDS from the best start, and from the best
    start of another basin (a pitch 2 dB or more away) when it is nearly as
    good; the better end, rounded to 0.01 dB."""
    from scipy.optimize import minimize
    starts = sorted(starts)
    runs = [starts[0]]
    other = [s for s in starts[1:] if abs(s[1] - starts[0][1]) >= 2.0]
    if other and other[0][0] <= 1.5 * starts[0][0] + 0.05:
        runs.append(other[0])
    res = None
    for _, pb, ib in runs:
        simplex = np.array([[pb, ib], [pb + (1.5 if pb + 1.5 <= bounds[0][1] else -1.5), ib],
                            [pb, ib + (3.0 if ib + 3.0 <= bounds[1][1] else -3.0)]])
        r = minimize(objective, np.array([pb, ib]), method="Nelder-Mead", bounds=bounds,
                     options={"initial_simplex": simplex, "xatol": 0.02, "fatol": 1e-4,
                              "maxfev": 160})
        if res is None or r.fun < res.fun:
            res = r
    assert res is not None                      # runs holds at least the best start
    pitch = _clip_pitch(_round_db(float(res.x[0])))
    irr = min(max(_round_db(float(res.x[1])), bounds[1][0]), bounds[1][1])
    return pitch, irr


def _search_w2(cand: _Candidates) -> tuple[float, float]:
    """The texture whose felt spectrum is nearest the map's (W2): the starts
    are a coarse column of irregularities at the felt mean pitch, the felt
    peak and the band-power peak (what is felt of a high pitch can be mostly
    its texel borders, low in frequency: the power's peak still says where
    it is), then +-2 dB of pitch at the best."""
    target = cand.target

    def objective(z: np.ndarray) -> float:
        return cand(float(z[0]), float(z[1]))[0]

    mean_db, _ = target.moments_db()
    pitches: list[float] = []
    for p0 in (mean_db, 10.0 * float(P.GRID[int(np.argmax(target.felt))]),
               10.0 * float(P.GRID[int(np.argmax(target.band_power))])):
        p0 = _clip_pitch(p0)
        if all(abs(p0 - p) > 0.5 for p in pitches):
            pitches.append(p0)
    starts = [(objective(np.array([p0, i0])), p0, i0) for p0 in pitches for i0 in _COARSE_IRREG]
    _, pb, ib = min(starts)
    for dp in _COARSE_PITCH:
        starts.append((objective(np.array([pb + dp, ib])), _clip_pitch(pb + dp), ib))
    return _nelder_mead(objective, starts)


def _search_felt(cand: _Candidates) -> tuple[float, float]:
    """The texture whose felt point (pitch, noisiness) is the map's, nearest
    the sliders' start where several are (TIE_BREAK): the starts are a coarse
    column of irregularities at the map's felt pitch, 3 dB either side of it
    and at the sliders' start."""
    p0, i0 = SLIDER_START_DB

    bounds = (BOUNDS[0], (BOUNDS[1][0], FELT_IRREG_MAX_DB))

    def objective(z: np.ndarray) -> float:
        p, i = _clip_pitch(float(z[0])), min(max(float(z[1]), bounds[1][0]), bounds[1][1])
        d = cand(p, i)[0]
        return d * d + TIE_BREAK * ((p - p0) ** 2 + (i - i0) ** 2)

    felt = cand.target_point.pitch_db
    pitches: list[float] = []
    for p in (felt, felt - 3.0, felt + 3.0, p0):
        p = _clip_pitch(p)
        if all(abs(p - q) > 0.5 for q in pitches):
            pitches.append(p)
    starts = [(objective(np.array([p, i])), p, i) for p in pitches for i in _COARSE_IRREG
              if i <= FELT_IRREG_MAX_DB]
    return _nelder_mead(objective, starts, bounds)


def _report(x: np.ndarray, notes: list[str], gain: float, fixed: Mapping[str, Any],
            cand: _Candidates, pitch: float, irr: float, intervals: bool,
            source: str | None, t0: float) -> dict[str, Any]:
    """The result dict (encode's docstring) for the chosen texture."""
    n, L, q, model, target = x.size, cand.L, cand.q, cand.model, cand.target
    best, pat = cand(pitch, irr)
    texture = _texture(pitch, irr, texel_samples=L, quant_db=q, gain=gain,
                       seed=fixed["seed"], v=fixed["v"])
    texel.validate(texture)                      # what the board will be sent
    ranges = _ranges(cand, pitch, irr, best) if intervals else None
    quant = {}
    if q == 0:
        for qd in QUANT_COSTS_DB:
            quant["%g" % qd] = round(cand(pitch, irr, qd)[0], 3)
    plan = texel.make_plan(dict(texture, length_samples=n))
    literal = repr(texture).encode("ascii")
    lo_hz, hi_hz = P.skin_band_hz(model)
    v = model.speed_mm_s
    out: dict[str, Any] = {
        "pitch_db": pitch, "irregularity_db": irr, "gain": gain, "texel_samples": L,
        "quant_db": q, "seed": fixed["seed"], "v": fixed["v"],
        "texture": texture,
        "method": cand.method,
        "distance_db": round(best, 4),
        "felt_distance_db": round(cand.target_point.distance(pat.felt_point()), 4),
        "w2_distance_db": round(P.w2_db(target, pat), 4),
        "ranges": ranges,
        "felt": {"map": _felt(target), "rendering": _felt(pat)},
        "skin_band": {"hz": [round(lo_hz, 1), round(hi_hz, 1)],
                      "cpmm": [round(lo_hz / v, 4), round(hi_hz / v, 3)],
                      "pitch_db_max": round(10.0 * math.log10(hi_hz / v), 2),
                      "speed_mm_s": v},
        "spectrum": _spectrum(target, pat, n),
        "quantization": {"cost_db": quant, "equivalent_db": _equivalent(cand.method)}
        if quant else None,
        "compression": {"map_bytes": 2 * n, "map_format": "uint16 (2 bytes per sample, as a "
                        "board holds an uploaded map)", "texture_bytes": len(literal),
                        "texture_format": "the texture as the Python literal a board is sent",
                        "ratio": round(2 * n / len(literal), 1)},
        "aliasing": {"expected_fraction": round(P.expected_aliased_fraction(texture), 6),
                     "map_top_band_fraction": round(_top_band_fraction(x), 6),
                     "drawn_fraction": round(plan.fraction_above_nyquist(), 6),
                     "drawn_texels": plan.above_nyquist, "texels": plan.count,
                     "nyquist_cpmm": round(NYQUIST_CPMM, 4)},
        "map": {"samples": n, "length_mm": round(n * DX_MM, 4), "mean": round(float(x.mean()), 6),
                "rms": round(float(x.std()), 6), "min": round(float(x.min()), 6),
                "max": round(float(x.max()), 6)},
        "model": model.as_dict(),
        "notes": notes,
        "evaluations": len(cand.cache),
        "seconds": None,
    }
    if source is not None:
        out["source"] = source
    out["seconds"] = round(time.perf_counter() - t0, 4)
    return out


def _top_band_fraction(x: np.ndarray) -> float:
    """The share of the map's power in the top 0.1 decade below Nyquist (74.9 ..
    94.3 c/mm): a map with none there has nothing a texture must alias to
    match (docs/encoder.md, "aliasing")."""
    f, p = P.periodogram(x)
    total = float(p[1:].sum())
    top = float(p[f >= NYQUIST_CPMM / 10 ** 0.1].sum())
    return top / total if total > 0.0 else 0.0


def _felt(pat: P.Pattern) -> dict[str, Any]:
    """A pattern's felt point, its unfused spread, level and strongest band."""
    mean, sd = pat.moments_db()
    fp = pat.felt_point()
    return {"pitch_db": round(fp.pitch_db, 3), "noisiness_db": round(fp.noisiness_db, 3),
            "tonal": round(fp.tonal, 4), "spread_db": round(sd, 3),
            "level_db": _finite(pat.level_db), "peak_sl_db": _finite(pat.sl_db)}


def _equivalent(method: str) -> float:
    """What 'feels the same' is for a method: within the felt plane's
    difference threshold (perception.JND_DB), or within EQUIVALENT_DB of the
    W2 minimum."""
    return P.JND_DB if method == "felt" else EQUIVALENT_DB


def _clip_pitch(p: float) -> float:
    return min(max(p, BOUNDS[0][0]), BOUNDS[0][1])


def _finite(x: float) -> float | None:
    return round(float(x), 3) if math.isfinite(x) else None


def _interval(f: Any, lo: float, hi: float, x0: float, limit: float, grid: np.ndarray
              ) -> list[float]:
    """The interval around x0 within [lo, hi] where f <= limit, from f on a
    grid (crossings linearly interpolated), rounded to 0.01 dB."""
    xs = np.unique(np.clip(np.concatenate((grid, [x0])), lo, hi))
    ys = np.array([f(v) for v in xs])
    k = int(np.searchsorted(xs, x0))
    a = b = k
    while a > 0 and ys[a - 1] <= limit:
        a -= 1
    while b < xs.size - 1 and ys[b + 1] <= limit:
        b += 1
    left = xs[a] if a == 0 or ys[a - 1] == ys[a] else \
        xs[a - 1] + (limit - ys[a - 1]) * (xs[a] - xs[a - 1]) / (ys[a] - ys[a - 1])
    right = xs[b] if b == xs.size - 1 or ys[b + 1] == ys[b] else \
        xs[b] + (limit - ys[b]) * (xs[b + 1] - xs[b]) / (ys[b + 1] - ys[b])
    return [round(float(left), 2), round(float(right), 2)]


def _ranges(candidate: _Candidates, pitch: float, irr: float, best: float) -> dict[str, Any]:
    """Each parameter's range (the other held) that feels the same as the map:
    felt method, a felt distance within perception.JND_DB (or within
    EQUIVALENT_DB of the chosen texture's, when that is farther); W2, within
    EQUIVALENT_DB of the minimum. Where it is wide, the parameter is not
    identifiable from what a finger feels."""
    eq = _equivalent(candidate.method)
    limit = max(eq, best + EQUIVALENT_DB) if candidate.method == "felt" else best + eq
    pg = pitch + np.array([-6, -4, -3, -2, -1.5, -1, -0.6, -0.3, 0.3, 0.6, 1, 1.5, 2, 3, 4, 6])
    ig = np.arange(IRREG_DB_MIN, IRREG_DB_MAX + 0.5, 1.0)
    pr = _interval(lambda p: candidate(p, irr)[0], *BOUNDS[0], pitch, limit, pg)
    ir = _interval(lambda i: candidate(pitch, i)[0], *BOUNDS[1], irr, limit, ig)
    return {"pitch_db": pr, "irregularity_db": ir, "equivalent_db": eq,
            "limit_db": round(limit, 4)}


def _spectrum(target: P.Pattern, pat: P.Pattern, n: int) -> dict[str, Any]:
    """Both spectra on the log-frequency axis, for the report and the figure:
    band power (dB re a full-scale sine) and the felt distributions (sum 1),
    every 0.05 decade from the map's first bin to Nyquist."""
    f0 = 1.0 / (P.segment_length(n) * DX_MM)
    keep = np.nonzero((P.GRID >= math.log10(f0) - 1e-9)
                      & (P.GRID <= math.log10(NYQUIST_CPMM) + 1e-9))[0][::_SPECTRUM_STEP]

    def db(e: np.ndarray) -> list[float]:
        return [round(float(v), 2) for v in
                10.0 * np.log10(np.maximum(e[keep] / P.FULL_SCALE_POWER, 1e-12))]

    dm = target.distribution()
    dr = pat.distribution()
    # felt distributions summed over each reported step (so each list sums to ~1)
    def felt(d: np.ndarray) -> list[float]:
        c = np.concatenate(([0.0], np.cumsum(d)))
        edges = np.clip(np.concatenate((keep - _SPECTRUM_STEP // 2,
                                        [keep[-1] + _SPECTRUM_STEP // 2 + 1])), 0, d.size)
        return [round(float(v), 5) for v in np.diff(c[edges])]
    return {"log10_f": [round(float(v), 3) for v in P.GRID[keep]],
            "f_cpmm": [float("%.4g" % 10 ** v) for v in P.GRID[keep]],
            "map_db": db(target.band_power), "rendering_db": db(pat.band_power),
            "map_felt": felt(dm), "rendering_felt": felt(dr),
            "band": "power within a Gaussian band of SD %g decade" % P.RESOLUTION_DECADES
            if target.model.resolution_decades == P.RESOLUTION_DECADES else
            "power within a Gaussian band of SD %g decade" % target.model.resolution_decades}


def decode(result: Mapping[str, Any], length_samples: int | None = None,
           engine: str | None = None) -> np.ndarray:
    """Decoding is the generator: the texture of an encode() result (or a
    texture dict) rendered length_samples long (default: the encoded map's)."""
    tex = dict(result.get("texture", result))
    n = length_samples if length_samples is not None else \
        result.get("map", {}).get("samples", tex.get("length_samples", 9600))
    tex["length_samples"] = int(n)
    return np.asarray(texel.render(tex, engine=engine), dtype=np.float64)
